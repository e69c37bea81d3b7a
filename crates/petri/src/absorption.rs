//! Absorbing chains: where a run ends, how long it takes, and the
//! distribution of that time — for nets that *finish* (a behaviour tree's
//! execution, a mission), rather than run forever.
//!
//! The CTMC's bottom strongly connected components are its ends (a dead
//! marking is a component of one state). With `T` the transient states and
//! `π0` the initial distribution after vanishing elimination:
//!
//! - expected time in each transient state, `x (−Q_TT) = π0_T`;
//! - probability of ending in component `B`, `π0_B + Σ_{s∈T} x_s q_{sB}`;
//! - mean time to the end, `Σ_s x_s` (finite when every run ends);
//! - mean time of the runs that end in `B`, `Σ_s x_s h_B(s) / P(B)` with
//!   `h_B` the absorption probabilities from each state, `(−Q_TT) h_B = q_{·B}`
//!   — computed for every `B` at once as `Σ_i z_i q_{iB} / P(B)` with
//!   `z (−Q_TT) = x`;
//! - `P(T ≤ t)` by uniformisation (Jensen's method): with `Λ ≥` every exit
//!   rate and `P = I + Q/Λ`, `P(T > t) = Σ_k Poisson(k; Λt) ‖π0_T P_TT^k‖₁`,
//!   the sum cut when the Poisson tail is below the tolerance.
//!
//! - the same on a grid by Crank–Nicolson (`absorption_cdf_grid`), whose
//!   cost does not grow with the fastest rate;
//! - `P(T > t)` for every `t` at once, on a shift-and-invert Krylov space
//!   (`absorption_survival`, [`crate::survival`]): a few dozen solves for
//!   quantiles to 10⁻⁹, where the grid takes ~25 per mean time for 10⁻⁴.
//!
//! Both linear systems, and every implicit time step, are solved block by
//! block over the chain's strongly connected components in topological
//! order (`crate::blocks`): a finishing chain is mostly small components
//! in sequence, which a sparse LU of the whole matrix would fill in.

use crate::blocks::BlockSystem;
use crate::ctmc::CompiledGspn;
use crate::error::{Error, Result};
use crate::net::TransitionId;

/// What an absorbing chain does from its initial marking.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Absorption {
    /// Probability of ending in each bottom component, in the order of
    /// [`CompiledGspn::bottom_components`].
    pub end_probability: Vec<f64>,
    /// Mean time to reach any end (over the runs that end; all do when the
    /// end probabilities sum to 1).
    pub mean_time: f64,
    /// Mean time of the runs ending in each component (0 where its
    /// probability is 0).
    pub mean_time_to: Vec<f64>,
    /// Expected time spent in each tangible state before the end (0 for the
    /// states of bottom components).
    pub sojourn: Vec<f64>,
    /// For each bottom component and timed transition: the probability that
    /// the run ends there through a firing of that transition (the last
    /// timed event before the end). Ends reached at time 0 are not counted.
    pub entered_by: Vec<Vec<(TransitionId, f64)>>,
}

/// The transient part of a compiled chain, with its rates bound.
struct Transient {
    /// Tangible state → index among the transient states (`u32::MAX` otherwise).
    local: Vec<u32>,
    states: Vec<u32>,
    /// Bottom component of each state (`u32::MAX` for transient ones).
    bottom_of: Vec<u32>,
    /// `(from, to, rate)` among transient states, `from != to`.
    inner: Vec<(u32, u32, f64)>,
    /// `(from, bottom component, transition, rate)`.
    exits: Vec<(u32, u32, TransitionId, f64)>,
    /// Exit rate of each transient state (to anything but itself).
    out_rate: Vec<f64>,
}

fn transient(chain: &CompiledGspn, rates: &[f64]) -> Result<Transient> {
    let n = chain.num_tangible();
    if chain.is_ergodic() {
        return Err(Error::Invalid(
            "the chain is irreducible: no run ever ends (no absorbing marking)".into(),
        ));
    }
    let mut bottom_of = vec![u32::MAX; n];
    for (b, states) in chain.bottom_components().iter().enumerate() {
        for &s in states {
            bottom_of[s as usize] = b as u32;
        }
    }
    let states: Vec<u32> = (0..n as u32)
        .filter(|&s| bottom_of[s as usize] == u32::MAX)
        .collect();
    let mut local = vec![u32::MAX; n];
    for (i, &s) in states.iter().enumerate() {
        local[s as usize] = i as u32;
    }
    let mut inner = Vec::new();
    let mut exits = Vec::new();
    let mut out_rate = vec![0.0; states.len()];
    for (i, &s) in states.iter().enumerate() {
        for (d, t, c) in chain.entries_from(s as usize) {
            let r = rates[t.index()] * c;
            if !(r.is_finite() && r >= 0.0) {
                return Err(Error::InvalidValue {
                    element: format!("transition `{}`", chain.gspn().transition_names()[t.index()]),
                    what: "the rate",
                    requirement: "a finite number ≥ 0",
                    value: rates[t.index()],
                });
            }
            if d == s || r == 0.0 {
                continue;
            }
            out_rate[i] += r;
            match local[d as usize] {
                u32::MAX => exits.push((i as u32, bottom_of[d as usize], t, r)),
                j => inner.push((i as u32, j, r)),
            }
        }
    }
    Ok(Transient {
        local,
        states,
        bottom_of,
        inner,
        exits,
        out_rate,
    })
}

/// The initial distribution on the transient states (in `tr`'s numbering).
fn initial_transient(chain: &CompiledGspn, tr: &Transient) -> Vec<f64> {
    let mut p = vec![0.0; tr.states.len()];
    for &(s, w) in chain.initial_distribution() {
        let i = tr.local[s as usize];
        if i != u32::MAX {
            p[i as usize] += w;
        }
    }
    p
}

/// TR-BDF2's `γ = 2 − √2`: with it, both stages of a step use the one
/// matrix `I + (γh/2) A`.
const GAMMA: f64 = 2.0 - std::f64::consts::SQRT_2;

/// Grid steps taken by TR-BDF2 before Crank–Nicolson takes over, and the
/// TR-BDF2 steps in each.
const START_STEPS: usize = 2;
const START_SUBSTEPS: usize = 4;

/// One TR-BDF2 step of length `τ` from `p`, in place (`rhs` is scratch;
/// `start` factorises `M_γ = I + (γτ/2) A`; both vectors in its order): the trapezoidal stage is
/// `p_γ = 2 p M_γ⁻¹ − p`, the BDF2 stage `p' = (p_γ − (1 − γ)² p) M_γ⁻¹ /
/// (γ(2 − γ))`.
fn tr_bdf2_step(start: &BlockSystem, p: &mut Vec<f64>, rhs: &mut Vec<f64>) {
    for (r, &q) in rhs.iter_mut().zip(p.iter()) {
        *r = 2.0 * q;
    }
    start.solve_ordered(rhs);
    let scale = 1.0 / (GAMMA * (2.0 - GAMMA));
    let back = 1.0 + (1.0 - GAMMA) * (1.0 - GAMMA);
    for (r, &q) in rhs.iter_mut().zip(p.iter()) {
        *r = (*r - back * q) * scale;
    }
    start.solve_ordered(rhs);
    std::mem::swap(p, rhs);
}

/// `P(T > t)` on the grid `t_k = k·h`, `k = 0, 1, …`, by Crank–Nicolson on
/// the forward equation `dp/dt = p Q_TT`: `p_{k+1} (I + (h/2) A) = p_k (I −
/// (h/2) A)` with `A = −Q_TT`, one block-triangular factorisation
/// ([`crate::blocks`]) for every step. Second order in `h` and stable for
/// any rate, so its cost does not grow with the fastest rate as
/// uniformisation's does.
///
/// Crank–Nicolson carries the components of the start far faster than
/// `1/h` as oscillations (its amplification tends to −1), so the first
/// [`START_STEPS`] grid steps are taken as [`START_SUBSTEPS`] TR-BDF2 steps
/// of `τ = h/4` each (a trapezoidal stage over `γτ`, then a BDF2 stage:
/// `p_γ (I + (γτ/2) A) = p (I − (γτ/2) A)`, then `p' (I + (γτ/2) A) = (p_γ −
/// (1 − γ)² p) / (γ(2 − γ))`). TR-BDF2 is L-stable, so those components are
/// damped — by a factor 3·10⁻⁶ over the start at `hλ = 40` — and second
/// order, so the start does not cost accuracy. Backward-Euler half steps
/// (Rannacher's start) damp as well but are first order: on a coarse grid
/// their error shifts every later value (by 10⁻³ of the median on Nav2's
/// goal-patience tree, against 2·10⁻⁵ with this start; `crates/bt/BENCHMARKS.md`).
///
/// With `M = I + (h/2) A`, a Crank–Nicolson step's right-hand side is
/// `p_k (2I − M)`, so the step is `p_{k+1} = 2 p_k M⁻¹ − p_k`: one block
/// solve and no product with `A`; so is TR-BDF2's trapezoidal stage with
/// its own matrix.
/// Stops after `max_steps` steps, or once the survival is at most `stop_below`.
fn survival_crank_nicolson(
    tr: &Transient,
    p0: &[f64],
    h: f64,
    max_steps: usize,
    stop_below: f64,
) -> Result<Vec<f64>> {
    let what = "the time distribution (Crank–Nicolson)";
    let sys = BlockSystem::new(what, &tr.out_rate, &tr.inner, 1.0, 0.5 * h)?;
    let tau = h / START_SUBSTEPS as f64;
    let start = BlockSystem::new(what, &tr.out_rate, &tr.inner, 1.0, 0.5 * GAMMA * tau)?;
    // The vectors are kept in the systems' order, which depends on the
    // chain's pattern only: the same for both.
    debug_assert_eq!(start.order(), sys.order());
    let mut p = sys.ordered(p0);
    let mut rhs = vec![0.0; p.len()];
    let mut out = Vec::with_capacity(max_steps + 1);
    out.push(p.iter().sum::<f64>());
    for k in 0..max_steps {
        if k < START_STEPS {
            for _ in 0..START_SUBSTEPS {
                tr_bdf2_step(&start, &mut p, &mut rhs);
            }
        } else {
            for (v, &q) in rhs.iter_mut().zip(&p) {
                *v = 2.0 * q;
            }
            sys.solve_ordered(&mut rhs);
            for (v, &q) in rhs.iter_mut().zip(&p) {
                *v -= q;
            }
            std::mem::swap(&mut p, &mut rhs);
        }
        let survival = p.iter().sum::<f64>();
        out.push(survival);
        if !survival.is_finite() {
            return Err(Error::NotFinite {
                what: "the time distribution".into(),
                value: survival,
                cause: "the Crank–Nicolson steps lost all precision".into(),
            });
        }
        if survival <= stop_below {
            break;
        }
    }
    Ok(out)
}

impl CompiledGspn {
    /// `P(end reached by t)` on the grid `t_k = k·t_max/steps`, `k = 0…steps`,
    /// by Crank–Nicolson (error O(h²), `h = t_max/steps`; any rates):
    /// cheaper than [`absorption_cdf`](Self::absorption_cdf) when rates are
    /// far apart (a fast rate makes uniformisation take `Λ t` steps).
    pub fn absorption_cdf_grid(&self, rates: &[f64], t_max: f64, steps: usize) -> Result<Vec<f64>> {
        if !(t_max.is_finite() && t_max > 0.0) || steps == 0 {
            return Err(Error::Invalid(format!(
                "a time grid needs t_max > 0 and steps ≥ 1 (got {t_max}, {steps})"
            )));
        }
        self.absorption_cdf_steps(rates, t_max / steps as f64, steps, 2.0)
    }

    /// `P(end reached by k·h)` for `k = 0, 1, …` as for
    /// [`absorption_cdf_grid`](Self::absorption_cdf_grid), stopped after
    /// `max_steps` steps or at the first point where it reaches `level`
    /// (the last value returned): the grid of a quantile need not be longer
    /// than the quantile.
    pub fn absorption_cdf_steps(
        &self,
        rates: &[f64],
        h: f64,
        max_steps: usize,
        level: f64,
    ) -> Result<Vec<f64>> {
        if !(h.is_finite() && h > 0.0) {
            return Err(Error::Invalid(format!("a time step must be > 0 (got {h})")));
        }
        let tr = transient(self, rates)?;
        let p = initial_transient(self, &tr);
        let survival = survival_crank_nicolson(&tr, &p, h, max_steps, 1.0 - level)?;
        Ok(survival.into_iter().map(|v| (1.0 - v).clamp(0.0, 1.0)).collect())
    }

    /// `S(t) = P(the run has not ended by t)` for every `t` at once, from a
    /// shift-and-invert Krylov space with `M = I − shift·Q_TT`
    /// ([`crate::survival`]): `shift` a quarter to a half of the mean time
    /// to the end suits every quantile of the time; the space grows until two sizes
    /// agree, to `tolerance` relatively, on the first times within
    /// `horizon` where `S` falls to `levels` ([`Survival::times`](crate::survival::Survival::times)).
    ///
    /// Errors: [`Error::NoConvergence`] if it has not settled by
    /// [`crate::survival::MAX_VECTORS`] vectors (then
    /// [`absorption_cdf_steps`](Self::absorption_cdf_steps) still serves);
    /// an irreducible chain; parameters that are not positive and finite.
    pub fn absorption_survival(
        &self,
        rates: &[f64],
        shift: f64,
        horizon: f64,
        levels: &[f64],
        tolerance: f64,
    ) -> Result<crate::survival::Survival> {
        self.absorbing(rates)?.survival(shift, horizon, levels, tolerance)
    }

    /// Absorption probabilities, mean times and sojourn times for `rates`
    /// (one per transition, as for [`CompiledGspn::solve_rates`]).
    ///
    /// Errors: an irreducible chain (nothing ends), a singular system (a
    /// transient state from which no end is reachable).
    pub fn absorption(&self, rates: &[f64]) -> Result<Absorption> {
        self.absorbing(rates)?.absorption()
    }

    /// The chain's transient part with `rates` bound, for several of the
    /// measures above at once ([`Absorbing`]: it is built once).
    ///
    /// Errors: an irreducible chain (nothing ends), a rate that is not a
    /// finite number ≥ 0.
    pub fn absorbing(&self, rates: &[f64]) -> Result<Absorbing<'_>> {
        Ok(Absorbing {
            chain: self,
            tr: transient(self, rates)?,
        })
    }
}

/// A compiled chain's transient part with its rates bound
/// ([`CompiledGspn::absorbing`]): what the absorption and the time
/// distribution are both computed from, built once for both.
pub struct Absorbing<'a> {
    chain: &'a CompiledGspn,
    tr: Transient,
}

impl Absorbing<'_> {
    /// [`CompiledGspn::absorption_survival`] on this chain.
    pub fn survival(
        &self,
        shift: f64,
        horizon: f64,
        levels: &[f64],
        tolerance: f64,
    ) -> Result<crate::survival::Survival> {
        for (name, v) in [("shift", shift), ("horizon", horizon), ("tolerance", tolerance)] {
            if !(v.is_finite() && v > 0.0) {
                return Err(Error::Invalid(format!(
                    "the {name} of a survival function must be > 0 (got {v})"
                )));
            }
        }
        let tr = &self.tr;
        let sys = BlockSystem::new(
            "the time distribution (Krylov space)",
            &tr.out_rate,
            &tr.inner,
            1.0,
            shift,
        )?;
        let p = sys.ordered(&initial_transient(self.chain, tr));
        crate::survival::build(&sys, &p, shift, horizon, levels, tolerance)
    }

    /// [`CompiledGspn::absorption`] on this chain.
    pub fn absorption(&self) -> Result<Absorption> {
        self.absorption_from(self.chain.initial_distribution())
    }

    /// The absorption from another initial distribution over the chain's
    /// tangible states (`(state, probability)` pairs, as
    /// [`CompiledGspn::initial_distribution`] gives them) — e.g. the same
    /// chain with the initial draws weighted otherwise. A state out of
    /// range is an error.
    pub fn absorption_from(&self, initial: &[(u32, f64)]) -> Result<Absorption> {
        let (chain, tr) = (self.chain, &self.tr);
        let m = tr.states.len();
        let nb = chain.bottom_components().len();
        let mut pi0_t = vec![0.0; m];
        let mut end_probability = vec![0.0; nb];
        if let Some(&(s, p)) = initial
            .iter()
            .find(|&&(s, p)| s as usize >= tr.local.len() || !(p.is_finite() && p >= 0.0))
        {
            return Err(Error::Invalid(format!(
                "an initial probability {p} of state {s} (the chain has {} tangible states; probabilities are finite and ≥ 0)",
                tr.local.len()
            )));
        }
        for &(s, p) in initial {
            match tr.local[s as usize] {
                u32::MAX => end_probability[tr.bottom_of[s as usize] as usize] += p,
                i => pi0_t[i as usize] += p,
            }
        }
        // x (−Q_TT) = π0_T.
        let sys = BlockSystem::new("the absorption equations", &tr.out_rate, &tr.inner, 0.0, 1.0)?;
        let mut x = pi0_t;
        sys.solve_row(&mut x);
        let mut entered: Vec<std::collections::BTreeMap<TransitionId, f64>> = vec![Default::default(); nb];
        for &(i, b, t, r) in &tr.exits {
            end_probability[b as usize] += x[i as usize] * r;
            *entered[b as usize].entry(t).or_insert(0.0) += x[i as usize] * r;
        }
        // Σ_s x_s h_B(s) = x (−Q_TT)⁻¹ q_{·B} = z q_{·B} with z (−Q_TT) = x:
        // one more row solve serves every end.
        let mut z = x.clone();
        sys.solve_row(&mut z);
        let mut weighted = vec![0.0; nb];
        for &(i, b, _, r) in &tr.exits {
            weighted[b as usize] += z[i as usize] * r;
        }
        let mean_time_to = weighted
            .iter()
            .zip(&end_probability)
            .map(|(&w, &p)| if p > 0.0 { w / p } else { 0.0 })
            .collect();
        let total: f64 = end_probability.iter().sum();
        let mean_time = x.iter().sum::<f64>() / total.max(f64::MIN_POSITIVE);
        let mut sojourn = vec![0.0; chain.num_tangible()];
        for (i, &s) in tr.states.iter().enumerate() {
            sojourn[s as usize] = x[i];
        }
        let all = [mean_time]
            .into_iter()
            .chain(end_probability.iter().copied())
            .chain(x.iter().copied());
        if let Some(v) = all.into_iter().find(|v| !v.is_finite()) {
            return Err(Error::NotFinite {
                what: "an absorption measure".into(),
                value: v,
                cause: "the absorption equations lost all precision".into(),
            });
        }
        Ok(Absorption {
            end_probability,
            mean_time,
            mean_time_to,
            sojourn,
            entered_by: entered.into_iter().map(|m| m.into_iter().collect()).collect(),
        })
    }
}

impl CompiledGspn {
    /// `P(end reached by t)` for each time in `times` (ascending or not),
    /// by uniformisation with truncation error below `tolerance`.
    ///
    /// Cost: `O((Λ t_max + √(Λ t_max)) · entries)` with `Λ` the largest exit
    /// rate; an error beyond `max_steps` steps.
    pub fn absorption_cdf(
        &self,
        rates: &[f64],
        times: &[f64],
        tolerance: f64,
        max_steps: usize,
    ) -> Result<Vec<f64>> {
        let tr = transient(self, rates)?;
        let m = tr.states.len();
        let mut p = initial_transient(self, &tr);
        let lambda = tr.out_rate.iter().copied().fold(0.0, f64::max) * 1.02;
        if lambda == 0.0 || m == 0 {
            return Ok(times.iter().map(|_| 1.0 - p.iter().sum::<f64>()).collect());
        }
        let t_max = times.iter().copied().fold(0.0, f64::max);
        // Survival after k uniformised steps, for k = 0, 1, …
        let mut survival = vec![p.iter().sum::<f64>()];
        let need = |lt: f64| (lt + 10.0 * lt.sqrt() + 20.0).ceil() as usize;
        let steps = need(lambda * t_max);
        if steps > max_steps {
            return Err(Error::Invalid(format!(
                "the time distribution needs {steps} uniformisation steps (more than {max_steps}): rates up to {lambda:.3e} over a time of {t_max:.3e}"
            )));
        }
        let mut next = vec![0.0; m];
        for _ in 0..steps {
            for (i, v) in next.iter_mut().enumerate() {
                *v = p[i] * (1.0 - tr.out_rate[i] / lambda);
            }
            for &(i, j, r) in &tr.inner {
                next[j as usize] += p[i as usize] * r / lambda;
            }
            std::mem::swap(&mut p, &mut next);
            survival.push(p.iter().sum::<f64>());
        }
        Ok(times
            .iter()
            .map(|&t| {
                let lt = lambda * t.max(0.0);
                // Poisson weights in log form (no overflow for large Λt).
                let mut acc = 0.0;
                let mut weight_sum = 0.0;
                let mut ln_k_factorial = 0.0;
                for (k, &s) in survival.iter().enumerate() {
                    if k > 0 {
                        ln_k_factorial += (k as f64).ln();
                    }
                    let lw = -lt + (k as f64) * lt.max(f64::MIN_POSITIVE).ln() - ln_k_factorial;
                    let w = lw.exp();
                    acc += w * s;
                    weight_sum += w;
                    if k as f64 > lt && 1.0 - weight_sum < tolerance {
                        break;
                    }
                }
                (1.0 - acc).clamp(0.0, 1.0)
            })
            .collect())
    }
}

#[cfg(test)]
mod tests {
    use crate::{CompiledGspn, ExploreParams, Net, Params};

    /// The compiled chain of `net` and the rate of every transition.
    fn compiled(net: &Net) -> (CompiledGspn, Vec<f64>) {
        let g = net.instantiate(&Params::new()).unwrap();
        let c = CompiledGspn::build(&g, &ExploreParams::default()).unwrap();
        let rates = g.rates(&Params::new(), None).unwrap();
        (c, rates)
    }

    /// start → (rate a) ok, or (rate b) ko: P(ok) = a/(a+b), E[T] = 1/(a+b).
    #[test]
    fn race_of_two_exponentials() {
        let mut net = Net::new("race");
        let s = net.add_place("s", 1u32);
        let ok = net.add_place("ok", 0u32);
        let ko = net.add_place("ko", 0u32);
        let a = net.add_timed("a", 3.0);
        let b = net.add_timed("b", 1.0);
        net.input(s, a);
        net.output(a, ok);
        net.input(s, b);
        net.output(b, ko);
        let (c, rates) = compiled(&net);
        let r = c.absorption(&rates).unwrap();
        let okb = c
            .bottom_components()
            .iter()
            .position(|b| c.tangible_marking(b[0] as usize)[1] == 1)
            .unwrap();
        assert!((r.end_probability[okb] - 0.75).abs() < 1e-12);
        assert!((r.mean_time - 0.25).abs() < 1e-12);
        assert!((r.mean_time_to[okb] - 0.25).abs() < 1e-12);
        let cdf = c.absorption_cdf(&rates, &[0.1, 1.0], 1e-12, 100_000).unwrap();
        for (t, p) in [0.1f64, 1.0].iter().zip(cdf) {
            assert!((p - (1.0 - (-4.0 * t).exp())).abs() < 1e-9, "{t}: {p}");
        }
    }

    /// An immediate first draw between two starts (weights 1 : 1), then
    /// `A` → ok at rate 1 or `B` → ko at rate 2: from the initial
    /// distribution re-weighted 1 : 3, P(ok) = 1/4 and E[T] = 1/4·1 + 3/4·1/2.
    #[test]
    fn absorption_from_another_initial_distribution() {
        let mut net = Net::new("draw");
        let i = net.add_place("i", 1u32);
        let a = net.add_place("a", 0u32);
        let b = net.add_place("b", 0u32);
        let ok = net.add_place("ok", 0u32);
        let ko = net.add_place("ko", 0u32);
        for (name, to) in [("x", a), ("y", b)] {
            let t = net.add_immediate(name, 1.0, 1);
            net.input(i, t);
            net.output(t, to);
        }
        let (ta, tb) = (net.add_timed("ta", 1.0), net.add_timed("tb", 2.0));
        net.input(a, ta);
        net.output(ta, ok);
        net.input(b, tb);
        net.output(tb, ko);
        let (c, rates) = compiled(&net);
        let chain = c.absorbing(&rates).unwrap();
        let initial: Vec<(u32, f64)> = c
            .initial_distribution()
            .iter()
            .map(|&(s, w)| {
                (
                    s,
                    w * if c.tangible_marking(s as usize)[1] == 1 {
                        0.5
                    } else {
                        1.5
                    },
                )
            })
            .collect();
        let r = chain.absorption_from(&initial).unwrap();
        let okb = c
            .bottom_components()
            .iter()
            .position(|b| c.tangible_marking(b[0] as usize)[3] == 1)
            .unwrap();
        assert!((r.end_probability[okb] - 0.25).abs() < 1e-12, "{r:?}");
        assert!((r.mean_time - 0.625).abs() < 1e-12, "{r:?}");
        let same = chain.absorption_from(c.initial_distribution()).unwrap();
        assert_eq!(same.end_probability, chain.absorption().unwrap().end_probability);
        for bad in [(c.num_tangible() as u32, 1.0), (0, f64::NAN), (0, -1.0)] {
            assert!(chain.absorption_from(&[bad]).is_err(), "{bad:?}");
        }
    }

    /// Two exponential stages (Erlang 2, rate 2 each): mean 1, P(T ≤ t) = 1 − e^{−2t}(1 + 2t).
    #[test]
    fn erlang_two_stages() {
        let mut net = Net::new("erlang");
        let p0 = net.add_place("p0", 1u32);
        let p1 = net.add_place("p1", 0u32);
        let p2 = net.add_place("p2", 0u32);
        let t1 = net.add_timed("t1", 2.0);
        let t2 = net.add_timed("t2", 2.0);
        net.input(p0, t1);
        net.output(t1, p1);
        net.input(p1, t2);
        net.output(t2, p2);
        let (c, rates) = compiled(&net);
        let r = c.absorption(&rates).unwrap();
        assert!((r.mean_time - 1.0).abs() < 1e-12);
        let t = 0.7;
        let cdf = c.absorption_cdf(&rates, &[t], 1e-12, 100_000).unwrap()[0];
        let exact = |t: f64| 1.0 - (-2.0 * t).exp() * (1.0 + 2.0 * t);
        assert!((cdf - exact(t)).abs() < 1e-9);
        // Crank–Nicolson on 0…1.4 in 400 steps: second order, close to 1e-5.
        let grid = c.absorption_cdf_grid(&rates, 1.4, 400).unwrap();
        assert!(
            (grid[200] - exact(t)).abs() < 1e-5,
            "{} vs {}",
            grid[200],
            exact(t)
        );
    }

    /// A chain of timed stages from a single start (rates in order).
    fn stages(rates: &[f64]) -> (CompiledGspn, Vec<f64>) {
        let mut net = Net::new("stages");
        let mut prev = net.add_place("p0", 1u32);
        for (k, &r) in rates.iter().enumerate() {
            let next = net.add_place(format!("p{}", k + 1), 0u32);
            let t = net.add_timed(format!("t{k}"), r);
            net.input(prev, t);
            net.output(t, next);
            prev = next;
        }
        compiled(&net)
    }

    /// A fast stage (rate 20) then a slow one (rate 0.1) on a grid of 25
    /// steps per mean time (h = 0.402, 8 times the fast stage's mean): the
    /// start must not shift the distribution. Exact: the hypoexponential
    /// CDF `1 − (b e^{−a t} − a e^{−b t})/(b − a)`. Backward-Euler half
    /// steps at the start are off by 7.3e-4 here, this start by 4.6e-5.
    #[test]
    fn a_fast_stage_on_a_coarse_grid_keeps_second_order_accuracy() {
        let (a, b) = (20.0, 0.1);
        let (c, rates) = stages(&[a, b]);
        let h = (1.0 / a + 1.0 / b) / 25.0;
        let grid = c.absorption_cdf_steps(&rates, h, 200, 2.0).unwrap();
        let exact = |t: f64| 1.0 - (b * (-a * t).exp() - a * (-b * t).exp()) / (b - a);
        let worst = grid
            .iter()
            .enumerate()
            .map(|(k, &v)| (v - exact(k as f64 * h)).abs())
            .fold(0.0, f64::max);
        assert!(worst < 6e-5, "largest error {worst}");
    }

    /// Half the runs end at once (rate 1000), half after a slow stage (rate
    /// 1): `S(t) = 0.5 e^{−1000t} + 0.5 e^{−t}`.
    fn stiff_mixture() -> (CompiledGspn, Vec<f64>) {
        let mut net = Net::new("stiff start");
        let s = net.add_place("s", 1u32);
        let fast = net.add_place("fast", 0u32);
        let slow = net.add_place("slow", 0u32);
        let end = net.add_place("end", 0u32);
        for (name, to) in [("to_fast", fast), ("to_slow", slow)] {
            let t = net.add_immediate(name, 1.0, 1);
            net.input(s, t);
            net.output(t, to);
        }
        for (name, from, rate) in [("fast_end", fast, 1000.0), ("slow_end", slow, 1.0)] {
            let t = net.add_timed(name, rate);
            net.input(from, t);
            net.output(t, end);
        }
        compiled(&net)
    }

    /// Half the runs end at once (rate 1000), half after a slow stage
    /// (rate 1), on a grid with h = 0.04: Crank–Nicolson alone would carry
    /// the fast component as an oscillation (amplification −0.905 per
    /// step); the L-stable start damps it, so the distribution is monotone
    /// and close to the exact `0.5 (1 − e^{−1000 t}) + 0.5 (1 − e^{−t})`.
    #[test]
    fn a_stiff_start_does_not_oscillate() {
        let (c, rates) = stiff_mixture();
        let h = 0.04;
        let grid = c.absorption_cdf_steps(&rates, h, 100, 2.0).unwrap();
        let exact = |t: f64| 0.5 * (1.0 - (-1000.0 * t).exp()) + 0.5 * (1.0 - (-t).exp());
        for (k, w) in grid.windows(2).enumerate() {
            assert!(w[1] >= w[0], "not monotone at step {k}: {} then {}", w[0], w[1]);
        }
        // At t = h what is left of the fast part is the start's damping,
        // (R(−10))⁴ · 0.5 = 8.6e-4; from the second step on it is gone and
        // what is left is Crank–Nicolson's own error on the slow part.
        for (k, &v) in grid.iter().enumerate().skip(1) {
            let e = exact(k as f64 * h);
            let bound = if k == 1 { 1e-3 } else { 5e-5 };
            assert!((v - e).abs() < bound, "step {k}: {v} vs {e}");
        }
    }

    /// The time of `level` of `S` by bisection on a closed form.
    fn root(f: impl Fn(f64) -> f64, level: f64, mut lo: f64, mut hi: f64) -> f64 {
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if f(mid) <= level { hi = mid } else { lo = mid }
        }
        0.5 * (lo + hi)
    }

    /// The Krylov survival against closed forms: a fast stage then a slow
    /// one (hypoexponential) and twelve equal stages (Erlang 12), each
    /// quantile to 1e-9 relatively, and `S(t)` itself at a few times.
    #[test]
    fn krylov_survival_meets_closed_forms() {
        let (a, b) = (20.0, 0.1);
        let (c, rates) = stages(&[a, b]);
        let mean = 1.0 / a + 1.0 / b;
        let exact = |t: f64| (b * (-a * t).exp() - a * (-b * t).exp()) / (b - a);
        let levels = [0.5, 0.1, 0.01];
        let s = c
            .absorption_survival(&rates, 0.25 * mean, 20.0 * mean, &levels, 1e-10)
            .unwrap();
        for (&level, t) in levels.iter().zip(s.times()) {
            let want = root(exact, level, 0.0, 20.0 * mean);
            let got = t.expect("within the horizon");
            assert!(
                (got - want).abs() <= 1e-9 * want,
                "level {level}: {got} vs {want}"
            );
        }
        for t in [0.01, 0.3, 5.0, 30.0] {
            assert!(
                (s.at(t) - exact(t)).abs() < 1e-9,
                "S({t}) = {} vs {}",
                s.at(t),
                exact(t)
            );
        }
        // Erlang 12, rate 3: S(t) = e^{−3t} Σ_{k<12} (3t)^k / k!.
        let (c, rates) = stages(&[3.0; 12]);
        let erlang = |t: f64| {
            let (mut term, mut sum) = (1.0, 0.0);
            for k in 0..12 {
                if k > 0 {
                    term *= 3.0 * t / k as f64;
                }
                sum += term;
            }
            (-3.0 * t).exp() * sum
        };
        let s = c.absorption_survival(&rates, 1.0, 80.0, &levels, 1e-10).unwrap();
        assert!(
            s.solves() <= 12,
            "an invariant space of 12 states: {} solves",
            s.solves()
        );
        for (&level, t) in levels.iter().zip(s.times()) {
            let want = root(erlang, level, 0.0, 80.0);
            let got = t.unwrap();
            assert!(
                (got - want).abs() <= 1e-9 * want,
                "level {level}: {got} vs {want}"
            );
        }
    }

    /// Half the runs end at once (rate 1000), half after a slow stage: the
    /// quantile below one half is in the fast part, those above in the
    /// slow part; a level never reached within the horizon is `None`, one
    /// met at the start is 0.
    #[test]
    fn krylov_survival_of_a_stiff_mixture() {
        let (c, rates) = stiff_mixture();
        let exact = |t: f64| 0.5 * (-1000.0 * t).exp() + 0.5 * (-t).exp();
        let levels = [0.8, 0.4, 0.05, 1e-9, 1.0];
        let s = c
            .absorption_survival(&rates, 0.125, 10.0, &levels, 1e-10)
            .unwrap();
        let times = s.times();
        for (k, &level) in levels.iter().take(3).enumerate() {
            let want = root(exact, level, 0.0, 10.0);
            let got = times[k].unwrap();
            assert!(
                (got - want).abs() <= 1e-8 * want,
                "level {level}: {got} vs {want}"
            );
        }
        assert_eq!(times[3], None, "S(10) = 2.3e-5 stays above 1e-9");
        assert_eq!(times[4], Some(0.0));
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(24))]

        /// On random finishing chains (a start, a few states with random
        /// rates between them and to two ends), the Krylov survival agrees
        /// with uniformisation — an independent method — at the quantiles
        /// it reports.
        #[test]
        fn krylov_survival_agrees_with_uniformisation(
            n in 2usize..7,
            edges in proptest::collection::vec((0usize..7, 0usize..9, 0.05f64..20.0), 4..20),
        ) {
            let mut net = Net::new("random");
            let places: Vec<_> = (0..n).map(|i| net.add_place(format!("s{i}"), u32::from(i == 0))).collect();
            let ends = [net.add_place("ok", 0u32), net.add_place("ko", 0u32)];
            // Every state can end: s_i → ok at a slow rate.
            for (i, &p) in places.iter().enumerate() {
                let t = net.add_timed(format!("end{i}"), 0.2 + 0.1 * i as f64);
                net.input(p, t);
                net.output(t, ends[0]);
            }
            for (k, &(from, to, rate)) in edges.iter().enumerate() {
                let (from, to) = (from % n, to % (n + 2));
                if from == to {
                    continue;
                }
                let t = net.add_timed(format!("e{k}"), rate);
                net.input(places[from], t);
                net.output(t, if to < n { places[to] } else { ends[to - n] });
            }
            let (c, rates) = compiled(&net);
            let mean = c.absorption(&rates).unwrap().mean_time;
            let levels = [0.5, 0.1, 0.01];
            let s = c.absorption_survival(&rates, 0.25 * mean, 20.0 * mean, &levels, 1e-10).unwrap();
            let horizon = 20.0 * mean;
            for (&level, t) in levels.iter().zip(s.times()) {
                // Uniformisation's survival where the level is crossed, or
                // at the horizon if it is not crossed before (a heavy tail).
                let at = t.unwrap_or(horizon);
                let left = 1.0 - c.absorption_cdf(&rates, &[at], 1e-13, 10_000_000).unwrap()[0];
                match t {
                    Some(t) => proptest::prop_assert!((left - level).abs() < 1e-8, "S({t}) = {left} for level {level}"),
                    None => proptest::prop_assert!(left > level - 1e-8, "S({horizon}) = {left} below level {level}"),
                }
            }
        }
    }
}
