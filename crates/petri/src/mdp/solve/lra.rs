//! Long-run average reward per unit of time, minimal or maximal.
//!
//! 1. **Maximal end components** of the whole model ([`super::graph::mecs`]):
//!    the process ends up for ever in one of them, and inside one a policy
//!    can reach every state, so the optimal gain `g_M` is the same in all
//!    its states.
//! 2. **The gain of each component** by relative value iteration on its
//!    own rows, uniformised so that every step is a jump with probability
//!    at most `1 − κ` (κ = 1/8: aperiodic). A timed state (every state in
//!    discrete time, a Markovian one in a Markov automaton) makes a real
//!    step with probability `q_s = δ/τ_s` per uniformised step of length
//!    `δ = (1 − κ) · min τ`; the probabilistic states of a Markov
//!    automaton take no time and are resolved within the step, their
//!    values the optimum over their rows of what follows (Butkova, Wimmer
//!    & Hermanns, *Long-run rewards for Markov automata*, TACAS 2017). The
//!    changes `Δ = x' − x` of the timed states bound the gain:
//!    `min Δ/δ ≤ g_M ≤ max Δ/δ` (Puterman, *Markov Decision Processes*,
//!    thm 8.5.5, in a communicating component), and the iteration stops
//!    when the two meet the precision.
//! 3. **Which component to end in**: every component collapsed into one
//!    state that may *stay* (value `g_M`) or take a row leaving it; no end
//!    component remains, so interval iteration from `[min g, max g]`
//!    converges (bounds of `g_M` folded into the lower and upper
//!    constants).
//!
//! Components of up to [`EXACT_LIMIT`] states are solved by **policy
//! iteration** instead (Howard's, for the semi-Markov formulation
//! `h(s) = ρ(s, a) − g τ(s) + Σ p h(s')`): each policy's best recurrent
//! class is evaluated exactly (stationary distribution and bias by LU),
//! the other states routed to it, the policy improved until no state
//! gains. Value iteration on a chain whose rates span seven orders of
//! magnitude (the supervisor's 1000/s next to 1e-4/s) needs millions of
//! sweeps; policy iteration needs a handful. Its result is certified as
//! the iteration's is: one uniformised step applied to the bias gives
//! `min Δ/δ ≤ g_M ≤ max Δ/δ`, tightened by the policy's own gain (which
//! the optimum is at least, or for `min` at most).
//!
//! The probabilistic states inside a component are resolved exactly when
//! they form no cycle (the common case); a cycle of them (allowed as long
//! as it can be left: no Zeno behaviour) is iterated until it changes by
//! less than 1e-15 relative, which the reported bound does not include.

use rayon::prelude::*;

use super::super::graph;
use super::super::property::Direction;
use super::super::value_iteration::{self, Equations};
use super::{Collapse, OptimizeParams, Optimum, View, attractor};
use crate::error::{Error, Result};
use crate::interrupt::Interrupt;
use crate::scc::{Successors, tarjan};

const NONE: u32 = u32::MAX;
/// Aperiodicity: every uniformised step stays put with probability ≥ κ.
const KAPPA: f64 = 0.125;
/// Timed states of a component from which a sweep runs in parallel.
const PARALLEL_FROM: usize = 8192;
/// Largest component solved by policy iteration (exact evaluations by
/// sparse LU); larger ones by relative value iteration.
pub const EXACT_LIMIT: usize = 20_000;
/// Rounds of policy iteration before the last policy is kept as it is
/// (its bounds are certified all the same).
const MAX_POLICY_ROUNDS: usize = 200;

#[inline]
fn better(dir: Direction, a: f64, b: f64) -> bool {
    match dir {
        Direction::Min => a < b,
        Direction::Max => a > b,
    }
}

/// One maximal end component being solved.
struct Component<'v, 'a> {
    view: &'v View<'a>,
    inside: &'v [bool],
    /// States in the component, timed ones and probabilistic ones.
    timed: Vec<u32>,
    instant: Vec<u32>,
    /// The probabilistic states in resolution order (bottom-up), and where
    /// each of their strongly connected components ends.
    instant_order: Vec<u32>,
    instant_bounds: Vec<usize>,
    /// Uniformised step length.
    delta: f64,
}

/// The instant states' successor lists inside the component.
struct InstantGraph<'c> {
    start: Vec<u64>,
    targets: Vec<u32>,
    _c: std::marker::PhantomData<&'c ()>,
}

impl Successors for InstantGraph<'_> {
    fn num_nodes(&self) -> usize {
        self.start.len() - 1
    }

    fn successors(&self, v: u32) -> &[u32] {
        &self.targets[self.start[v as usize] as usize..self.start[v as usize + 1] as usize]
    }
}

impl<'v, 'a> Component<'v, 'a> {
    fn new(view: &'v View<'a>, inside: &'v [bool], states: &[u32]) -> Result<Component<'v, 'a>> {
        let m = view.model;
        let continuous = m.model_type.is_continuous();
        let (timed, instant): (Vec<u32>, Vec<u32>) = states
            .iter()
            .partition(|&&s| !continuous || m.is_markovian(s as usize));
        if timed.is_empty() {
            return Err(Error::Zeno {
                count: states.len(),
                states: states
                    .iter()
                    .take(3)
                    .map(|s| format!("state {s}"))
                    .collect::<Vec<_>>()
                    .join(", "),
            });
        }
        let min_tau = timed
            .iter()
            .map(|&s| view.sojourn(s as usize))
            .fold(f64::INFINITY, f64::min);
        // Instant states: their order of resolution.
        let n = view.n();
        let mut is_instant = vec![false; 0];
        if !instant.is_empty() {
            is_instant = vec![false; n];
            for &s in &instant {
                is_instant[s as usize] = true;
            }
        }
        let mut start = vec![0u64; n + 1];
        let mut targets = Vec::new();
        if !instant.is_empty() {
            for s in 0..n {
                if is_instant[s] {
                    for r in m.rows(s).filter(|&r| inside[r]) {
                        targets.extend(view.targets(r).iter().filter(|&&t| is_instant[t as usize]));
                    }
                }
                start[s + 1] = targets.len() as u64;
            }
        }
        let g = InstantGraph {
            start,
            targets,
            _c: std::marker::PhantomData,
        };
        let mut instant_order = Vec::new();
        let mut instant_bounds = Vec::new();
        if !instant.is_empty() {
            let _ = tarjan::<_, ()>(
                &g,
                |v| is_instant[v as usize],
                |scc| {
                    instant_order.extend_from_slice(scc);
                    instant_bounds.push(instant_order.len());
                    Ok(())
                },
            );
        }
        Ok(Component {
            view,
            inside,
            timed,
            instant,
            instant_order,
            instant_bounds,
            delta: (1.0 - KAPPA) * min_tau,
        })
    }

    /// `action[r] + Σ p v(t)` over the row's entries.
    #[inline]
    fn row_value(&self, r: usize, action: &[f64], v: &[f64]) -> f64 {
        let m = self.view.model;
        let mut x = action[r];
        for k in m.entry_start[r] as usize..m.entry_start[r + 1] as usize {
            x += self.view.prob[k] * v[m.col[k] as usize];
        }
        x
    }

    /// Values of the instant states from the timed states' values in `v`
    /// (written into `v`).
    fn resolve_instant(&self, action: &[f64], dir: Direction, v: &mut [f64]) {
        let m = self.view.model;
        let mut start = 0;
        for &end in &self.instant_bounds {
            let scc = &self.instant_order[start..end];
            start = end;
            let cyclic = scc.len() > 1
                || m.rows(scc[0] as usize)
                    .filter(|&r| self.inside[r])
                    .any(|r| self.view.targets(r).contains(&scc[0]));
            for round in 0..100_000 {
                let mut change = 0.0f64;
                let mut scale = 0.0f64;
                for &s in scc {
                    let s = s as usize;
                    let mut best: Option<f64> = None;
                    for r in m.rows(s).filter(|&r| self.inside[r]) {
                        let x = self.row_value(r, action, v);
                        if best.is_none_or(|b| better(dir, x, b)) {
                            best = Some(x);
                        }
                    }
                    let new = best.unwrap_or(0.0);
                    change = change.max((new - v[s]).abs());
                    scale = scale.max(new.abs());
                    v[s] = new;
                }
                if !cyclic || (round > 0 && change <= 1e-15 * scale) {
                    break;
                }
            }
        }
    }

    /// The new value of timed state `s` from `v`.
    #[inline]
    fn timed_step(&self, s: usize, state: &[f64], action: &[f64], dir: Direction, v: &[f64]) -> f64 {
        let m = self.view.model;
        let q = self.delta / self.view.sojourn(s);
        let earned = self.delta * state[s];
        let mut best: Option<f64> = None;
        for r in m.rows(s).filter(|&r| self.inside[r]) {
            let x = earned + q * self.row_value(r, action, v) + (1.0 - q) * v[s];
            if best.is_none_or(|b| better(dir, x, b)) {
                best = Some(x);
            }
        }
        best.unwrap_or(v[s])
    }

    /// The component's gain bounds; `v` ends with the relative values the
    /// policy is read from.
    fn gain(
        &self,
        state: &[f64],
        action: &[f64],
        dir: Direction,
        params: &OptimizeParams,
        v: &mut [f64],
        stop: Interrupt<'_>,
    ) -> Result<(f64, f64, usize)> {
        let p = &params.precision;
        let mut next = Vec::with_capacity(self.timed.len());
        for sweeps in 1..=p.max_iterations {
            if sweeps % 64 == 0 {
                stop.check("iterating long-run values")?;
            }
            self.resolve_instant(action, dir, v);
            next.clear();
            if self.timed.len() >= PARALLEL_FROM {
                let vr: &[f64] = v;
                self.timed
                    .par_iter()
                    .map(|&s| self.timed_step(s as usize, state, action, dir, vr))
                    .collect_into_vec(&mut next);
            } else {
                next.extend(
                    self.timed
                        .iter()
                        .map(|&s| self.timed_step(s as usize, state, action, dir, v)),
                );
            }
            let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
            for (&s, &x) in self.timed.iter().zip(&next) {
                let d = x - v[s as usize];
                lo = lo.min(d);
                hi = hi.max(d);
            }
            let (glo, ghi) = (lo / self.delta, hi / self.delta);
            // Keep the values bounded: shift by the first timed state's.
            let shift = next[0];
            for (&s, &x) in self.timed.iter().zip(&next) {
                v[s as usize] = x - shift;
            }
            for &s in &self.instant {
                v[s as usize] -= shift;
            }
            if p.converged(glo, ghi) {
                self.resolve_instant(action, dir, v);
                return Ok((glo, ghi.max(glo), sweeps));
            }
        }
        Err(Error::NoConvergence {
            solver: "long-run value iteration",
            iterations: p.max_iterations,
            residual: f64::NAN,
            tolerance: p.epsilon,
        })
    }

    /// `Σ p v(t)` over row `r`'s entries.
    #[inline]
    fn expected(&self, r: usize, v: &[f64]) -> f64 {
        let m = self.view.model;
        (m.entry_start[r] as usize..m.entry_start[r + 1] as usize)
            .map(|k| self.view.prob[k] * v[m.col[k] as usize])
            .sum()
    }

    /// Reward per visit of row `r` of state `s`: the state's rate over its
    /// sojourn and the row's own.
    #[inline]
    fn visit_reward(&self, s: usize, r: usize, state: &[f64], action: &[f64]) -> f64 {
        let tau = self.view.sojourn(s);
        action[r] + if tau > 0.0 { state[s] * tau } else { 0.0 }
    }

    /// Policy iteration (see the module docs): the gain's certified
    /// bounds and the rounds done; `v` ends with the bias, `choice` with
    /// the policy, `local` is scratch (all [`NONE`] before and after).
    fn policy_iteration(
        &self,
        state: &[f64],
        action: &[f64],
        dir: Direction,
        v: &mut [f64],
        local: &mut [u32],
        choice: &mut [u32],
    ) -> Result<(f64, f64, usize)> {
        let m = self.view.model;
        let members: Vec<u32> = {
            let mut all: Vec<u32> = self.timed.iter().chain(&self.instant).copied().collect();
            all.sort_unstable();
            all
        };
        for (i, &s) in members.iter().enumerate() {
            local[s as usize] = i as u32;
        }
        // Start from the first row inside the component.
        let mut pi: Vec<usize> = members
            .iter()
            .map(|&s| {
                m.rows(s as usize)
                    .find(|&r| self.inside[r])
                    .unwrap_or(m.rows(s as usize).start)
            })
            .collect();
        let mut g;
        let mut rounds = 0;
        let result = loop {
            rounds += 1;
            let (gain, routed, reference) =
                self.evaluate_best_class(&members, local, &pi, state, action, dir)?;
            g = gain;
            pi = routed;
            self.bias(&members, local, &pi, reference, g, state, action, v)?;
            // Improvement: a row strictly better than the policy's.
            let mut changed = false;
            for (i, &s) in members.iter().enumerate() {
                let s = s as usize;
                let tau = self.view.sojourn(s);
                let q = |r: usize| self.visit_reward(s, r, state, action) - g * tau + self.expected(r, v);
                let current = q(pi[i]);
                let mut best = (pi[i], current);
                for r in m.rows(s).filter(|&r| self.inside[r]) {
                    let x = q(r);
                    let tol = 1e-12 * (x.abs() + current.abs() + 1.0);
                    let gain_more = match dir {
                        Direction::Max => x > best.1 + tol,
                        Direction::Min => x < best.1 - tol,
                    };
                    if gain_more {
                        best = (r, x);
                    }
                }
                if best.0 != pi[i] {
                    pi[i] = best.0;
                    changed = true;
                }
            }
            if !changed || rounds >= MAX_POLICY_ROUNDS {
                break Ok(());
            }
        };
        result?;
        for (i, &s) in members.iter().enumerate() {
            choice[s as usize] = pi[i] as u32;
            local[s as usize] = NONE;
        }
        // Certify: one uniformised step on the bias.
        let (dlo, dhi) = self.step_bounds(state, action, dir, v);
        let (lo, hi) = match dir {
            Direction::Max => (g.max(dlo).min(dhi), dhi),
            Direction::Min => (dlo, g.min(dhi).max(dlo)),
        };
        Ok((lo, hi.max(lo), rounds))
    }

    /// `min Δ/δ` and `max Δ/δ` of one uniformised step from `v` (which it
    /// leaves as it was, the probabilistic states resolved).
    fn step_bounds(&self, state: &[f64], action: &[f64], dir: Direction, v: &mut [f64]) -> (f64, f64) {
        self.resolve_instant(action, dir, v);
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for &s in &self.timed {
            let d = self.timed_step(s as usize, state, action, dir, v) - v[s as usize];
            lo = lo.min(d);
            hi = hi.max(d);
        }
        (lo / self.delta, hi / self.delta)
    }

    /// The policy's recurrent classes inside the component, each's gain
    /// (stationary distribution by LU); the best class kept and every
    /// other state routed to it. Returns the gain, the routed policy and a
    /// state of the class (local index).
    #[allow(clippy::too_many_arguments)]
    fn evaluate_best_class(
        &self,
        members: &[u32],
        local: &[u32],
        pi: &[usize],
        state: &[f64],
        action: &[f64],
        dir: Direction,
    ) -> Result<(f64, Vec<usize>, usize)> {
        let m = self.view.model;
        let k = members.len();
        // The policy's successor lists, in local indices.
        let mut start = vec![0u64; k + 1];
        let mut targets = Vec::new();
        for i in 0..k {
            targets.extend(self.view.targets(pi[i]).iter().map(|&t| local[t as usize]));
            start[i + 1] = targets.len() as u64;
        }
        let g = InstantGraph {
            start,
            targets,
            _c: std::marker::PhantomData,
        };
        let comps = crate::scc::Components::of(&g);
        let mut best: Option<(f64, u32)> = None;
        for c in comps.bottoms() {
            let class: Vec<usize> = (0..k).filter(|&i| comps.comp[i] == c).collect();
            let gain = self.class_gain(members, local, pi, &class, state, action)?;
            if best.is_none_or(|(b, _)| better(dir, gain, b)) {
                best = Some((gain, c));
            }
        }
        let Some((gain, c)) = best else {
            return Err(Error::Invalid(
                "internal: a component's policy has no recurrent class".into(),
            ));
        };
        // States whose policy already leads into the class keep it (so that
        // improvements are not undone); the others are routed into it,
        // inside the component.
        // A state reaches the class surely unless it can reach another
        // recurrent class of the policy.
        let mut elsewhere: Vec<bool> = (0..k)
            .map(|i| comps.bottom[comps.comp[i] as usize] && comps.comp[i] != c)
            .collect();
        loop {
            let mut changed = false;
            for i in 0..k {
                if !elsewhere[i] && g.successors(i as u32).iter().any(|&t| elsewhere[t as usize]) {
                    elsewhere[i] = true;
                    changed = true;
                }
            }
            if !changed {
                break;
            }
        }
        let reaches: Vec<bool> = elsewhere.iter().map(|&e| !e).collect();
        let n = self.view.n();
        let mut goal = vec![false; n];
        let mut from = vec![false; n];
        for (i, &s) in members.iter().enumerate() {
            if reaches[i] {
                goal[s as usize] = true;
            } else {
                from[s as usize] = true;
            }
        }
        let mut rows: Vec<u32> = m.row_start[..n].to_vec();
        for (i, &s) in members.iter().enumerate() {
            rows[s as usize] = pi[i] as u32;
        }
        let inside = self.inside;
        let row_state = |r: usize| m.row_start.partition_point(|&x| x as usize <= r) - 1;
        attractor(
            self.view,
            &goal,
            &from,
            &|r| inside[r] && local[row_state(r)] != NONE,
            &mut rows,
        );
        let routed = members.iter().map(|&s| rows[s as usize] as usize).collect();
        let reference = (0..k).find(|&i| comps.comp[i] == c).unwrap_or(0);
        Ok((gain, routed, reference))
    }

    /// The gain of a recurrent class of the policy: `Σ μ ρ / Σ μ τ` with
    /// `μ` the stationary distribution of its jump chain.
    #[allow(clippy::too_many_arguments)]
    fn class_gain(
        &self,
        members: &[u32],
        local: &[u32],
        pi: &[usize],
        class: &[usize],
        state: &[f64],
        action: &[f64],
    ) -> Result<f64> {
        let c = class.len();
        let mut at = vec![NONE; members.len()];
        for (j, &i) in class.iter().enumerate() {
            at[i] = j as u32;
        }
        // (I − P)ᵀ μ = 0 with the first equation replaced by Σ μ = 1.
        let mut triplets = Vec::new();
        for (j, &i) in class.iter().enumerate() {
            if j != 0 {
                triplets.push((j as u32, j as u32, 1.0));
            }
            let r = pi[i];
            let m = self.view.model;
            for k in m.entry_start[r] as usize..m.entry_start[r + 1] as usize {
                let t = at[local[m.col[k] as usize] as usize];
                if t != 0 && t != NONE {
                    triplets.push((t, j as u32, -self.view.prob[k]));
                }
            }
            triplets.push((0, j as u32, 1.0));
        }
        let mut rhs = vec![vec![0.0; c]];
        rhs[0][0] = 1.0;
        crate::linear::solve(
            "a recurrent class's stationary distribution",
            c,
            &triplets,
            &mut rhs,
        )?;
        let (mut num, mut den) = (0.0, 0.0);
        for (j, &i) in class.iter().enumerate() {
            let s = members[i] as usize;
            num += rhs[0][j] * self.visit_reward(s, pi[i], state, action);
            den += rhs[0][j] * self.view.sojourn(s);
        }
        if den.is_nan() || den <= 0.0 {
            return Err(Error::Zeno {
                count: c,
                states: class
                    .iter()
                    .take(3)
                    .map(|&i| format!("state {}", members[i]))
                    .collect::<Vec<_>>()
                    .join(", "),
            });
        }
        Ok(num / den)
    }

    /// The bias of a unichain policy of gain `g`: `h = ρ − g τ + P h`,
    /// `h = 0` at `at`, a state of its recurrent class (whose equation the
    /// others imply); written into `v`.
    #[allow(clippy::too_many_arguments)]
    fn bias(
        &self,
        members: &[u32],
        local: &[u32],
        pi: &[usize],
        at: usize,
        g: f64,
        state: &[f64],
        action: &[f64],
        v: &mut [f64],
    ) -> Result<()> {
        let m = self.view.model;
        let k = members.len();
        let mut triplets = Vec::new();
        let mut rhs = vec![vec![0.0; k]];
        for (i, &s) in members.iter().enumerate() {
            if i == at {
                triplets.push((i as u32, i as u32, 1.0));
                continue;
            }
            let s = s as usize;
            triplets.push((i as u32, i as u32, 1.0));
            let r = pi[i];
            for q in m.entry_start[r] as usize..m.entry_start[r + 1] as usize {
                let t = local[m.col[q] as usize];
                triplets.push((i as u32, t, -self.view.prob[q]));
            }
            rhs[0][i] = self.visit_reward(s, r, state, action) - g * self.view.sojourn(s);
        }
        crate::linear::solve("a policy's bias", k, &triplets, &mut rhs)?;
        for (i, &s) in members.iter().enumerate() {
            v[s as usize] = rhs[0][i];
        }
        Ok(())
    }

    /// Rows the relative values `v` make best in every state.
    fn greedy(&self, state: &[f64], action: &[f64], dir: Direction, v: &[f64], choice: &mut [u32]) {
        let m = self.view.model;
        for &s in self.timed.iter().chain(&self.instant) {
            let s = s as usize;
            let mut best: Option<(usize, f64)> = None;
            for r in m.rows(s).filter(|&r| self.inside[r]) {
                let x = if self.timed.binary_search(&(s as u32)).is_ok() {
                    let q = self.delta / self.view.sojourn(s);
                    self.delta * state[s] + q * self.row_value(r, action, v)
                } else {
                    self.row_value(r, action, v)
                };
                if best.is_none_or(|(_, b)| better(dir, x, b)) {
                    best = Some((r, x));
                }
            }
            if let Some((r, _)) = best {
                choice[s] = r as u32;
            }
        }
    }
}

/// Long-run average reward (see the module docs): `state` per unit of
/// time, `action` per row taken.
pub(crate) fn long_run(
    view: &View<'_>,
    state: &[f64],
    action: &[f64],
    dir: Direction,
    params: &OptimizeParams,
    stop: Interrupt<'_>,
) -> Result<Optimum> {
    let n = view.n();
    let m = view.model;
    let all = vec![true; n];
    let ecs = graph::mecs(&view.structure, &all, None);
    let mut members: Vec<Vec<u32>> = vec![Vec::new(); ecs.count];
    for s in 0..n {
        if ecs.of_state[s] != NONE {
            members[ecs.of_state[s] as usize].push(s as u32);
        }
    }
    let mut choice: Vec<u32> = m.row_start[..n].to_vec();
    let mut v = vec![0.0; n];
    let mut gains = Vec::with_capacity(ecs.count);
    let mut iterations = 0;
    let mut local = vec![NONE; n];
    let mut iterated = false;
    for states in &members {
        let c = Component::new(view, &ecs.row_inside, states)?;
        iterated |= states.len() > EXACT_LIMIT;
        let (lo, hi, sweeps) = if states.len() <= EXACT_LIMIT {
            stop.check("solving long-run values")?;
            c.policy_iteration(state, action, dir, &mut v, &mut local, &mut choice)?
        } else {
            let g = c.gain(state, action, dir, params, &mut v, stop)?;
            c.greedy(state, action, dir, &v, &mut choice);
            g
        };
        gains.push((lo, hi));
        iterations += sweeps;
    }
    // Stage 2: which component to end in.
    let collapse = Collapse::new(view, &all, Some(&ecs));
    let mut eq = collapse.equations(view, &vec![(0.0, 0.0); n], None);
    add_stay_rows(&mut eq, &collapse, &gains);
    let k = eq.num_states();
    let glo = gains.iter().map(|g| g.0).fold(f64::INFINITY, f64::min);
    let ghi = gains.iter().map(|g| g.1).fold(f64::NEG_INFINITY, f64::max);
    let (glo, ghi) = if gains.is_empty() { (0.0, 0.0) } else { (glo, ghi) };
    let b =
        value_iteration::interval_iteration(&eq, dir, vec![glo; k], vec![ghi; k], &params.precision, stop)?;
    iterations += b.iterations;
    let mut lower = vec![0.0; n];
    let mut upper = vec![0.0; n];
    for s in 0..n {
        let l = collapse.local[s] as usize;
        lower[s] = b.lower[l];
        upper[s] = b.upper[l];
    }
    stage_two_policy(view, dir, &collapse, &eq, &b, &mut choice);
    Ok(Optimum {
        direction: dir,
        lower,
        upper,
        choice,
        row_reward: view.row_rewards(state, action),
        bias: v,
        method: if iterated {
            "long-run value iteration"
        } else {
            "policy iteration, certified by a value-iteration step"
        },
        iterations,
        failed_guesses: 0,
        seconds: 0.0,
    })
}

/// Gives each collapsed component a first row "stay", worth its gain
/// (lower and upper bounds), with no entries.
fn add_stay_rows(eq: &mut Equations, collapse: &Collapse, gains: &[(f64, f64)]) {
    let k = eq.num_states();
    let mut class_of_local = vec![NONE; k];
    for (s, &c) in collapse.class.iter().enumerate() {
        if c != NONE {
            class_of_local[collapse.local[s] as usize] = c;
        }
    }
    let old = std::mem::take(eq);
    let b_upper_old = old.b_upper.clone().unwrap_or_else(|| old.b.clone());
    let mut b_upper = Vec::with_capacity(old.b.len() + gains.len());
    eq.row_start.push(0);
    eq.entry_start.push(0);
    for l in 0..k {
        if class_of_local[l] != NONE {
            let (lo, hi) = gains[class_of_local[l] as usize];
            eq.b.push(lo);
            b_upper.push(hi);
            eq.orig_row.push(NONE);
            eq.entry_start.push(eq.col.len() as u64);
        }
        for r in old.rows(l) {
            let (a, e) = (old.entry_start[r] as usize, old.entry_start[r + 1] as usize);
            eq.col.extend_from_slice(&old.col[a..e]);
            eq.prob.extend_from_slice(&old.prob[a..e]);
            eq.b.push(old.b[r]);
            b_upper.push(b_upper_old[r]);
            eq.orig_row.push(old.orig_row[r]);
            eq.entry_start.push(eq.col.len() as u64);
        }
        eq.row_start.push(eq.orig_row.len() as u32);
    }
    eq.b_upper = Some(b_upper);
}

/// Stage two's policy: outside components the best row; a component that
/// does best staying keeps its gain policy, one that does better leaving
/// routes its states to the state of the best leaving row.
fn stage_two_policy(
    view: &View<'_>,
    dir: Direction,
    collapse: &Collapse,
    eq: &Equations,
    b: &value_iteration::Bounds,
    choice: &mut [u32],
) {
    let n = view.n();
    let mid: Vec<f64> = (0..eq.num_states())
        .map(|l| b.lower[l] + (b.upper[l] - b.lower[l]) / 2.0)
        .collect();
    let b_up = eq.b_upper.as_deref().unwrap_or(&eq.b);
    let mut leave_state = vec![false; n];
    let mut leaving_local = vec![false; eq.num_states()];
    for (l, leaving) in leaving_local.iter_mut().enumerate() {
        let mut best: Option<(usize, f64)> = None;
        for r in eq.rows(l) {
            let lo = eq.row_value(r, &mid, &eq.b);
            let hi = eq.row_value(r, &mid, b_up);
            let x = lo + (hi - lo) / 2.0;
            if best.is_none_or(|(_, v)| better(dir, x, v)) {
                best = Some((r, x));
            }
        }
        let Some((r, _)) = best else { continue };
        let orig = eq.orig_row[r];
        if orig == NONE {
            continue; // stay: the gain policy holds
        }
        let s = view.model.row_start.partition_point(|&x| x <= orig) - 1;
        choice[s] = orig;
        if collapse.class[s] != NONE {
            leave_state[s] = true;
            *leaving = true;
        }
    }
    let leaving_class: Vec<bool> = (0..n)
        .map(|s| collapse.class[s] != NONE && leaving_local[collapse.local[s] as usize])
        .collect();
    if leaving_class.iter().any(|&x| x) {
        let from: Vec<bool> = (0..n).map(|s| leaving_class[s] && !leave_state[s]).collect();
        let class = &collapse.class;
        let m = view.model;
        attractor(
            view,
            &leave_state,
            &from,
            &|r| {
                collapse.inside[r] && {
                    let s = m.row_start.partition_point(|&x| x as usize <= r) - 1;
                    view.targets(r).iter().all(|&t| class[t as usize] == class[s])
                }
            },
            choice,
        );
    }
}
