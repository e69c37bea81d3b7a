//! Sound value iteration on the equations `x(s) = opt_r (b_r + Σ_j p_rj x(j))`
//! that remain once the graph analysis has fixed every value it can.
//!
//! Two methods, both with a **guaranteed** bound:
//!
//! * **Interval iteration** (Haddad & Monmege, *Interval iteration
//!   algorithm for MDPs and IMDPs*, TCS 2018; Baier et al., CAV 2017):
//!   a lower bound iterated from below and an upper bound from above, for
//!   problems where both are known at the start (probabilities: 0 and 1;
//!   long-run averages: the smallest and largest gain).
//! * **Optimistic value iteration** (Hartmanns & Kaminski, CAV 2020), for
//!   expected totals, which have no upper bound to start from: iterate from
//!   below until the changes are small, *guess* an upper bound a little
//!   above, and keep it only once one Bellman step does not raise it
//!   anywhere (`Φ(u) ≤ u` proves `u ≥ x*` when the fixed point is unique,
//!   which the end-component treatment before guarantees); a wrong guess
//!   sends the lower iteration on with a tighter threshold.
//!
//! Both are **topological**: the equations are split into strongly
//! connected components, solved bottom-up, each iterated only until its
//! own states meet the precision (a component without a cycle in one
//! step). Within a component the iteration is Jacobi's: every new value is
//! computed from the previous vector, in parallel on large components —
//! the same bits on any number of threads, since each state's sum runs in
//! its row order whatever thread computes it.
//!
//! Stopping rule, per state: `u − l ≤ 2ε·|(l + u)/2|` (relative, the
//! default) or `u − l ≤ 2ε` (absolute). The value reported is the
//! midpoint, within `ε` (relative or absolute) of the true value. The
//! bounds are computed in double precision: they hold up to the rounding
//! of the sweeps (a few units in the last place), as Storm's do.

use rayon::prelude::*;

use super::property::Direction;
use crate::error::{Error, Result};
use crate::interrupt::Interrupt;
use crate::scc::{Successors, tarjan};

/// Components at least this large are iterated in parallel.
const PARALLEL_FROM: usize = 8192;

/// Precision and limits of the iterations.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Precision {
    /// `ε`: half the width of the final interval, relative to the value
    /// (or absolute). Default 1e-6, Storm's default precision.
    pub epsilon: f64,
    /// Whether `ε` is relative (default) or absolute.
    pub relative: bool,
    /// Sweeps over a component before giving up
    /// ([`Error::NoConvergence`]). Default 10,000,000.
    pub max_iterations: usize,
}

impl Default for Precision {
    fn default() -> Self {
        Precision {
            epsilon: 1e-6,
            relative: true,
            max_iterations: 10_000_000,
        }
    }
}

impl Precision {
    /// Whether the interval `[l, u]` meets the precision.
    #[inline]
    pub(crate) fn converged(&self, l: f64, u: f64) -> bool {
        let w = u - l;
        if w.is_nan() || w <= 0.0 {
            return true;
        }
        if self.relative {
            w <= self.epsilon * (l.abs() + u.abs())
        } else {
            w <= 2.0 * self.epsilon
        }
    }
}

/// The equations of the states left after the graph analysis ("maybe"
/// states, end components collapsed): `x(s) = opt_r (b_r + Σ p x(col))`.
#[derive(Debug, Clone, Default)]
pub(crate) struct Equations {
    pub(crate) row_start: Vec<u32>,
    pub(crate) entry_start: Vec<u64>,
    pub(crate) col: Vec<u32>,
    pub(crate) prob: Vec<f64>,
    /// Constant of each row: its reward plus the fixed values it reaches.
    pub(crate) b: Vec<f64>,
    /// The constants for the upper bound when they differ (bounds of the
    /// values folded in, as in the long-run average's second stage).
    pub(crate) b_upper: Option<Vec<f64>>,
    /// The model's row of each row.
    pub(crate) orig_row: Vec<u32>,
}

impl Successors for Equations {
    fn num_nodes(&self) -> usize {
        self.row_start.len() - 1
    }

    fn successors(&self, v: u32) -> &[u32] {
        let v = v as usize;
        let a = self.entry_start[self.row_start[v] as usize] as usize;
        let b = self.entry_start[self.row_start[v + 1] as usize] as usize;
        &self.col[a..b]
    }
}

impl Equations {
    pub(crate) fn num_states(&self) -> usize {
        self.row_start.len() - 1
    }

    #[inline]
    pub(crate) fn rows(&self, s: usize) -> std::ops::Range<usize> {
        self.row_start[s] as usize..self.row_start[s + 1] as usize
    }

    /// `b_r + Σ p x(col)` in entry order.
    #[inline]
    pub(crate) fn row_value(&self, r: usize, x: &[f64], b: &[f64]) -> f64 {
        let (a, e) = (self.entry_start[r] as usize, self.entry_start[r + 1] as usize);
        let mut v = b[r];
        for k in a..e {
            v += self.prob[k] * x[self.col[k] as usize];
        }
        v
    }

    /// The constants of the lower (`upper` false) or upper bound.
    fn constants(&self, upper: bool) -> &[f64] {
        match (&self.b_upper, upper) {
            (Some(b), true) => b,
            _ => &self.b,
        }
    }

    /// One Bellman step at `s`: the best row's value.
    #[inline]
    pub(crate) fn step(&self, s: usize, x: &[f64], b: &[f64], dir: Direction) -> f64 {
        let mut rows = self.rows(s);
        let first = rows.next().map_or(0.0, |r| self.row_value(r, x, b));
        rows.fold(first, |best, r| {
            let v = self.row_value(r, x, b);
            match dir {
                Direction::Min => best.min(v),
                Direction::Max => best.max(v),
            }
        })
    }

    /// Whether `s` has a row entering itself.
    fn has_self_loop(&self, s: usize) -> bool {
        self.successors(s as u32).contains(&(s as u32))
    }

    /// The strongly connected components, bottom-up (each after every
    /// component it reaches): `order` holds the states, `bounds` where
    /// each component ends in it.
    fn components(&self) -> (Vec<u32>, Vec<usize>) {
        let mut order = Vec::with_capacity(self.num_states());
        let mut bounds = Vec::new();
        let _ = tarjan::<_, ()>(
            self,
            |_| true,
            |scc| {
                order.extend_from_slice(scc);
                bounds.push(order.len());
                Ok(())
            },
        );
        (order, bounds)
    }
}

/// Lower and upper bounds per state, and the work done.
#[derive(Debug, Clone, Default)]
pub(crate) struct Bounds {
    pub(crate) lower: Vec<f64>,
    pub(crate) upper: Vec<f64>,
    /// Sweeps over components (a component without cycle counts one).
    pub(crate) iterations: usize,
    /// Guesses of optimistic value iteration that failed.
    pub(crate) failed_guesses: usize,
}

/// New values of `states` from `x` (the lower bound's constants, or the
/// upper's), in order, in parallel when many.
fn sweep(eq: &Equations, states: &[u32], x: &[f64], upper: bool, dir: Direction, out: &mut Vec<f64>) {
    out.clear();
    let b = eq.constants(upper);
    if states.len() >= PARALLEL_FROM {
        states
            .par_iter()
            .map(|&s| eq.step(s as usize, x, b, dir))
            .collect_into_vec(out);
    } else {
        out.extend(states.iter().map(|&s| eq.step(s as usize, x, b, dir)));
    }
}

fn no_convergence(iterations: usize, width: f64, p: &Precision) -> Error {
    Error::NoConvergence {
        solver: "value iteration",
        iterations,
        residual: width,
        tolerance: p.epsilon,
    }
}

/// The widest interval of `states`, relative or absolute as `p` says.
fn widest(states: &[u32], l: &[f64], u: &[f64], p: &Precision) -> f64 {
    states
        .iter()
        .map(|&s| {
            let (a, b) = (l[s as usize], u[s as usize]);
            let w = b - a;
            if p.relative && a.abs() + b.abs() > 0.0 {
                2.0 * w / (a.abs() + b.abs())
            } else {
                w
            }
        })
        .fold(0.0, f64::max)
}

/// Interval iteration from `lower ≤ x* ≤ upper` (given per state, both
/// fixed points of the iteration's direction: `lower ≤ Φ(lower)`,
/// `Φ(upper) ≤ upper`).
pub(crate) fn interval_iteration(
    eq: &Equations,
    dir: Direction,
    lower: Vec<f64>,
    upper: Vec<f64>,
    p: &Precision,
    stop: Interrupt<'_>,
) -> Result<Bounds> {
    let (order, bounds) = eq.components();
    let mut out = Bounds {
        lower,
        upper,
        ..Bounds::default()
    };
    let mut scratch = (Vec::new(), Vec::new());
    let mut start = 0;
    for &end in &bounds {
        let states = &order[start..end];
        start = end;
        if acyclic_step(eq, states, dir, &mut out) {
            continue;
        }
        stop.check("iterating values")?;
        tighten(eq, states, dir, &mut out, &mut scratch);
        let mut sweeps = 1usize;
        narrow(eq, states, dir, &mut out, p, stop, &mut sweeps, &mut scratch)?;
    }
    Ok(out)
}

/// A component of one state without a self loop: its bounds in one step
/// from its successors' (final) bounds. Whether `states` was one.
fn acyclic_step(eq: &Equations, states: &[u32], dir: Direction, out: &mut Bounds) -> bool {
    if states.len() != 1 || eq.has_self_loop(states[0] as usize) {
        return false;
    }
    let s = states[0] as usize;
    out.lower[s] = eq.step(s, &out.lower, eq.constants(false), dir);
    out.upper[s] = eq.step(s, &out.upper, eq.constants(true), dir);
    out.iterations += 1;
    true
}

/// Sweep buffers of the lower and the upper bound.
type Scratch = (Vec<f64>, Vec<f64>);

/// One sweep of both bounds of `states`, kept monotone: rounding never
/// widens the interval, and the upper bound never goes below the lower.
fn tighten(eq: &Equations, states: &[u32], dir: Direction, out: &mut Bounds, (nl, nu): &mut Scratch) {
    sweep(eq, states, &out.lower, false, dir, nl);
    sweep(eq, states, &out.upper, true, dir, nu);
    for (i, &s) in states.iter().enumerate() {
        let s = s as usize;
        out.lower[s] = out.lower[s].max(nl[i]);
        out.upper[s] = out.upper[s].min(nu[i]).max(out.lower[s]);
    }
    out.iterations += 1;
}

/// Both bounds of `states` (valid bounds) swept together until every
/// state meets the precision; `sweeps` counts the component's sweeps so
/// far, against `p.max_iterations`.
#[allow(clippy::too_many_arguments)]
fn narrow(
    eq: &Equations,
    states: &[u32],
    dir: Direction,
    out: &mut Bounds,
    p: &Precision,
    stop: Interrupt<'_>,
    sweeps: &mut usize,
    scratch: &mut Scratch,
) -> Result<()> {
    while !states
        .iter()
        .all(|&s| p.converged(out.lower[s as usize], out.upper[s as usize]))
    {
        if *sweeps >= p.max_iterations {
            return Err(no_convergence(
                *sweeps,
                widest(states, &out.lower, &out.upper, p),
                p,
            ));
        }
        if *sweeps % 64 == 0 {
            stop.check("iterating values")?;
        }
        tighten(eq, states, dir, out, scratch);
        *sweeps += 1;
    }
    Ok(())
}

/// Optimistic value iteration (see the module docs) for equations whose
/// fixed point is unique and at least `lower` (every `b ≥ 0`).
pub(crate) fn optimistic(
    eq: &Equations,
    dir: Direction,
    lower: Vec<f64>,
    p: &Precision,
    stop: Interrupt<'_>,
) -> Result<Bounds> {
    let (order, bounds) = eq.components();
    let n = eq.num_states();
    let mut out = Bounds {
        lower,
        upper: vec![f64::INFINITY; n],
        ..Bounds::default()
    };
    let mut start = 0;
    for &end in &bounds {
        let states = &order[start..end];
        start = end;
        if acyclic_step(eq, states, dir, &mut out) {
            continue;
        }
        optimistic_component(eq, states, dir, &mut out, p, stop)?;
    }
    Ok(out)
}

/// Optimistic value iteration on one component (its successors' bounds
/// are final).
fn optimistic_component(
    eq: &Equations,
    states: &[u32],
    dir: Direction,
    out: &mut Bounds,
    p: &Precision,
    stop: Interrupt<'_>,
) -> Result<()> {
    let (mut nl, mut nu) = (Vec::new(), Vec::new());
    let mut threshold = p.epsilon;
    let mut sweeps = 0usize;
    loop {
        // 1. From below until the relative changes are under the threshold.
        let mut phase = 0usize;
        loop {
            if sweeps % 64 == 0 {
                stop.check("iterating values")?;
            }
            sweep(eq, states, &out.lower, false, dir, &mut nl);
            let mut change = 0.0f64;
            for (i, &s) in states.iter().enumerate() {
                let s = s as usize;
                let (old, new) = (out.lower[s], nl[i].max(out.lower[s]));
                let d = new - old;
                if d > 0.0 {
                    change = change.max(if new != 0.0 { d / new.abs() } else { d });
                }
                out.lower[s] = new;
            }
            sweeps += 1;
            phase += 1;
            out.iterations += 1;
            if change <= threshold {
                break;
            }
            if sweeps >= p.max_iterations {
                return Err(no_convergence(sweeps, change, p));
            }
        }
        // 2. Guess an upper bound a little above, and check it.
        let eps = if p.relative { p.epsilon } else { p.epsilon / 2.0 };
        for &s in states {
            let l = out.lower[s as usize];
            out.upper[s as usize] = if p.relative { l + eps * l.abs() } else { l + eps };
        }
        let mut verified = false;
        for _ in 0..phase.max(16) {
            sweep(eq, states, &out.lower, false, dir, &mut nl);
            sweep(eq, states, &out.upper, true, dir, &mut nu);
            sweeps += 1;
            out.iterations += 1;
            let mut inductive = true;
            let mut crossed = false;
            for (i, &s) in states.iter().enumerate() {
                let s = s as usize;
                out.lower[s] = out.lower[s].max(nl[i]);
                if nu[i] > out.upper[s] {
                    inductive = false;
                }
                out.upper[s] = nu[i];
                if out.upper[s] < out.lower[s] {
                    crossed = true;
                }
            }
            if inductive && !crossed {
                verified = true;
                break;
            }
            if crossed {
                break;
            }
        }
        if verified {
            break;
        }
        out.failed_guesses += 1;
        threshold /= 10.0;
        if sweeps >= p.max_iterations || threshold < 1e-300 {
            return Err(no_convergence(
                sweeps,
                widest(states, &out.lower, &out.upper, p),
                p,
            ));
        }
    }
    // 3. Both bounds are valid: iterate them together to the precision.
    let mut scratch = (nl, nu);
    narrow(eq, states, dir, out, p, stop, &mut sweeps, &mut scratch)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `x0 = max(0.5 x1 + 0.5, 0.9 x0 + 0.1 ...)`: a small system with a
    /// known fixed point.
    fn chain() -> Equations {
        // x0 = 0.5 x1 + 0.25 ; x1 = 0.5 x0 + 0.5 * 1  (fixed value 1 folded in b)
        Equations {
            row_start: vec![0, 1, 2],
            entry_start: vec![0, 1, 2],
            col: vec![1, 0],
            prob: vec![0.5, 0.5],
            b: vec![0.25, 0.5],
            b_upper: None,
            orig_row: vec![0, 1],
        }
    }

    #[test]
    fn interval_iteration_brackets_the_fixed_point() {
        // x0 = 0.5 x1 + 0.25, x1 = 0.5 x0 + 0.5 → x0 = 2/3, x1 = 5/6.
        let eq = chain();
        let p = Precision {
            epsilon: 1e-12,
            ..Precision::default()
        };
        let b = interval_iteration(
            &eq,
            Direction::Max,
            vec![0.0; 2],
            vec![1.0; 2],
            &p,
            Interrupt::NEVER,
        )
        .unwrap();
        for (s, exact) in [(0, 2.0 / 3.0), (1, 5.0 / 6.0)] {
            assert!(b.lower[s] <= exact + 1e-15 && exact <= b.upper[s] + 1e-15);
            assert!(b.upper[s] - b.lower[s] <= 2e-12 * exact);
        }
    }

    #[test]
    fn optimistic_iteration_finds_a_verified_upper_bound() {
        // Expected steps: x0 = 1 + 0.9 x0 → 10.
        let eq = Equations {
            row_start: vec![0, 1],
            entry_start: vec![0, 1],
            col: vec![0],
            prob: vec![0.9],
            b: vec![1.0],
            b_upper: None,
            orig_row: vec![0],
        };
        let p = Precision {
            epsilon: 1e-9,
            ..Precision::default()
        };
        let b = optimistic(&eq, Direction::Min, vec![0.0], &p, Interrupt::NEVER).unwrap();
        // Bounds hold up to the rounding of the last sweeps.
        assert!(
            b.lower[0] <= 10.0 * (1.0 + 1e-14) && 10.0 <= b.upper[0] * (1.0 + 1e-14),
            "{b:?}"
        );
        assert!(b.upper[0] - b.lower[0] <= 2e-9 * 10.0);
    }
}
