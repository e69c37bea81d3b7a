//! Optimal values and policies of a [`Model`] for an objective: the
//! probability of reaching a set, the expected total reward (or time)
//! until reaching it, the long-run average reward — each the minimum or
//! the maximum over all policies.
//!
//! 1. **Graph analysis** ([`super::graph`]) fixes every value that does not
//!    need numbers: probability 0 and 1, and for expected totals the
//!    states whose value is **infinite** (`Tmin`/`Rmin`: no policy reaches
//!    the set with probability 1; `Tmax`/`Rmax`: some policy misses it
//!    with positive probability, Storm's and PRISM's convention) or 0.
//! 2. **End components** that would give the equations several fixed
//!    points are collapsed into one state with the rows leaving them:
//!    every maximal end component of the undecided states for `Pmax`, the
//!    zero-reward ones for `Rmin` (Baier et al., CAV 2017). None can
//!    remain for `Pmin` and `Rmax` once the graph analysis is done.
//! 3. **Sound iteration** ([`super::value_iteration`]): interval iteration
//!    for probabilities, optimistic value iteration for totals; long-run
//!    averages in `lra`.
//! 4. **The policy**: in an undecided state the row best for the values
//!    found (ties to the first row); in a collapsed end component, the
//!    best row leaving it, and in its other states rows that lead there;
//!    in a state of value 1 (`Pmax`) rows that reach the set surely, of
//!    value 0 (`Pmin`) rows that avoid it. Memoryless and deterministic,
//!    optimal up to the bound.

use std::time::Instant;

mod lra;

use super::graph::{self, Backward, Structure};
use super::model::Model;
use super::property::Direction;
use super::value_iteration::{self, Bounds, Equations, Precision};
use crate::error::Result;
use crate::interrupt::Interrupt;

const NONE: u32 = u32::MAX;

/// What to optimise, resolved on a model's states and rows.
#[derive(Debug, Clone, PartialEq)]
pub enum Goal {
    /// The probability of eventually reaching `target`.
    Reach {
        /// The set, per state.
        target: Vec<bool>,
    },
    /// The expected reward accumulated until `target` is reached:
    /// `state` per unit of time (per step in discrete time; nothing in a
    /// probabilistic state) and `action` per row taken. The expected time
    /// is the state reward 1 everywhere.
    Total {
        /// The set, per state.
        target: Vec<bool>,
        /// Reward rate per state.
        state: Vec<f64>,
        /// Reward per row.
        action: Vec<f64>,
    },
    /// The long-run average reward per unit of time (per step in discrete
    /// time): `state` per unit of time, `action` per row taken.
    LongRun {
        /// Reward rate per state.
        state: Vec<f64>,
        /// Reward per row.
        action: Vec<f64>,
    },
}

/// Options of [`optimize`].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct OptimizeParams {
    /// Precision and limits.
    pub precision: Precision,
}

/// Optimal values, their bounds and a policy.
#[derive(Debug, Clone)]
pub struct Optimum {
    /// Minimum or maximum.
    pub direction: Direction,
    /// Lower bound per state (`∞` where the value is infinite).
    pub lower: Vec<f64>,
    /// Upper bound per state.
    pub upper: Vec<f64>,
    /// The row chosen in each state (an index into the model's rows).
    pub choice: Vec<u32>,
    /// Reward of each row as the objective counts it (totals: the row's
    /// reward plus the state's over its expected sojourn; empty
    /// otherwise), for [`Optimum::row_bounds`].
    pub(crate) row_reward: Vec<f64>,
    /// Long-run averages: each state's relative value (bias) under the
    /// policy, in reward units (empty otherwise).
    pub(crate) bias: Vec<f64>,
    /// Which method gave the numbers.
    pub method: &'static str,
    /// Sweeps of the iterations.
    pub iterations: usize,
    /// Optimistic guesses that failed.
    pub failed_guesses: usize,
    /// Wall-clock seconds (graph analysis included).
    pub seconds: f64,
}

impl Optimum {
    /// The value of state `s`: the middle of its interval.
    pub fn value(&self, s: usize) -> f64 {
        let (l, u) = (self.lower[s], self.upper[s]);
        if l == u { l } else { l + (u - l) / 2.0 }
    }

    /// Half the width of the interval of `s`: the value is within this of
    /// the true one.
    pub fn error_bound(&self, s: usize) -> f64 {
        let (l, u) = (self.lower[s], self.upper[s]);
        if l == u { 0.0 } else { (u - l) / 2.0 }
    }

    /// For a long-run average: the relative value of taking row `r` of
    /// state `s` and following the policy after, `ρ(s, r) − g τ(s) +
    /// Σ p h(s')` — in a communicating component every row has the same
    /// gain, and this is what tells them apart (the reward gained or lost
    /// on the way, against the policy). `None` for other objectives.
    pub fn row_relative(&self, model: &Model, s: usize, r: usize) -> Option<f64> {
        if self.bias.is_empty() {
            return None;
        }
        let view_tau = if !model.model_type.is_continuous() {
            1.0
        } else if model.is_markovian(s) {
            1.0 / model.exit_rate[s]
        } else {
            0.0
        };
        let mut q = self.row_reward.get(r).copied().unwrap_or(0.0) - self.value(s) * view_tau;
        for (t, p) in model.row_probabilities(r) {
            q += p * self.bias[t];
        }
        Some(q)
    }

    /// Lower and upper bounds of the value of taking row `r` (of state
    /// `s`) and following the policy after: the alternatives a choice
    /// marking weighs.
    pub fn row_bounds(&self, model: &Model, r: usize) -> (f64, f64) {
        // Long-run averages: a row's own reward does not count.
        let reward = if self.bias.is_empty() {
            self.row_reward.get(r).copied().unwrap_or(0.0)
        } else {
            0.0
        };
        let (mut l, mut u) = (reward, reward);
        for (t, p) in model.row_probabilities(r) {
            l += p * self.lower[t];
            u += p * self.upper[t];
        }
        (l, u)
    }
}

/// The view of a model the solvers read: structure, probabilities and the
/// expected sojourn time of each state.
pub(crate) struct View<'a> {
    pub(crate) model: &'a Model,
    pub(crate) structure: Structure<'a>,
    pub(crate) prob: std::borrow::Cow<'a, [f64]>,
    pub(crate) back: Backward,
}

impl<'a> View<'a> {
    pub(crate) fn new(model: &'a Model) -> View<'a> {
        let structure = Structure {
            row_start: &model.row_start,
            entry_start: &model.entry_start,
            col: &model.col,
        };
        let back = Backward::new(&structure);
        View {
            model,
            structure,
            prob: model.probabilities(),
            back,
        }
    }

    pub(crate) fn n(&self) -> usize {
        self.model.num_states()
    }

    /// Expected time spent in `s` per visit: `1/E` (Markovian), 0
    /// (probabilistic), 1 (a step, in discrete time).
    pub(crate) fn sojourn(&self, s: usize) -> f64 {
        if !self.model.model_type.is_continuous() {
            1.0
        } else if self.model.is_markovian(s) {
            1.0 / self.model.exit_rate[s]
        } else {
            0.0
        }
    }

    pub(crate) fn targets(&self, r: usize) -> &[u32] {
        &self.model.col[self.model.entry_start[r] as usize..self.model.entry_start[r + 1] as usize]
    }

    /// Each row's reward: `action[r] + state[s] · sojourn(s)`.
    pub(crate) fn row_rewards(&self, state: &[f64], action: &[f64]) -> Vec<f64> {
        let mut out = vec![0.0; self.model.num_rows()];
        for (s, &rate) in state.iter().enumerate().take(self.n()) {
            let tau = self.sojourn(s);
            let earned = if tau > 0.0 && rate != 0.0 { rate * tau } else { 0.0 };
            for r in self.model.rows(s) {
                out[r] = action.get(r).copied().unwrap_or(0.0) + earned;
            }
        }
        out
    }
}

/// How the undecided states map onto the equations: each state its own
/// equation, or end components collapsed into one.
pub(crate) struct Collapse {
    /// Equation of each state ([`NONE`] for fixed states).
    pub(crate) local: Vec<u32>,
    /// Rows dropped because they stay inside their collapsed component.
    pub(crate) inside: Vec<bool>,
    /// Collapsed component of each state ([`NONE`] if none).
    pub(crate) class: Vec<u32>,
    /// Number of equations.
    pub(crate) count: usize,
}

impl Collapse {
    /// The undecided states `maybe`, with the end components of `ecs`
    /// (if any) collapsed.
    pub(crate) fn new(view: &View<'_>, maybe: &[bool], ecs: Option<&graph::Mecs>) -> Collapse {
        let n = view.n();
        let mut local = vec![NONE; n];
        let mut class = vec![NONE; n];
        let mut of_class: Vec<u32> = Vec::new();
        let mut count = 0u32;
        for s in 0..n {
            if !maybe[s] {
                continue;
            }
            match ecs.map_or(NONE, |e| e.of_state[s]) {
                NONE => {
                    local[s] = count;
                    count += 1;
                }
                c => {
                    if of_class.len() <= c as usize {
                        of_class.resize(c as usize + 1, NONE);
                    }
                    if of_class[c as usize] == NONE {
                        of_class[c as usize] = count;
                        count += 1;
                    }
                    local[s] = of_class[c as usize];
                    class[s] = c;
                }
            }
        }
        let inside = match ecs {
            Some(e) => e.row_inside.clone(),
            None => vec![false; view.model.num_rows()],
        };
        Collapse {
            local,
            inside,
            class,
            count: count as usize,
        }
    }

    /// The equations: rows of every state of each equation, but the rows
    /// dropped; entries to fixed states folded into the constants with
    /// `fixed[t]` (lower and upper), `reward[r]` added.
    pub(crate) fn equations(
        &self,
        view: &View<'_>,
        fixed: &[(f64, f64)],
        reward: Option<&[f64]>,
    ) -> Equations {
        let n = view.n();
        let m = view.model;
        // States of each equation, in state order.
        let mut members: Vec<Vec<u32>> = vec![Vec::new(); self.count];
        for s in 0..n {
            if self.local[s] != NONE {
                members[self.local[s] as usize].push(s as u32);
            }
        }
        let mut eq = Equations {
            row_start: Vec::with_capacity(self.count + 1),
            ..Equations::default()
        };
        eq.row_start.push(0);
        eq.entry_start.push(0);
        let mut b_upper = Vec::new();
        let mut differs = false;
        for states in &members {
            for &s in states {
                for r in m.rows(s as usize) {
                    if self.inside[r] {
                        continue;
                    }
                    let base = reward.map_or(0.0, |w| w[r]);
                    let (mut lo, mut hi) = (base, base);
                    for k in m.entry_start[r] as usize..m.entry_start[r + 1] as usize {
                        let t = m.col[k] as usize;
                        let p = view.prob[k];
                        match self.local[t] {
                            NONE => {
                                lo += p * fixed[t].0;
                                hi += p * fixed[t].1;
                            }
                            l => {
                                eq.col.push(l);
                                eq.prob.push(p);
                            }
                        }
                    }
                    differs |= lo != hi;
                    eq.b.push(lo);
                    b_upper.push(hi);
                    eq.orig_row.push(r as u32);
                    eq.entry_start.push(eq.col.len() as u64);
                }
            }
            eq.row_start.push(eq.orig_row.len() as u32);
        }
        if differs {
            eq.b_upper = Some(b_upper);
        }
        eq
    }
}

/// A policy that reaches `goal` from the states of `from` surely, through
/// rows `allowed` (all of whose targets must keep to `from` ∪ `goal`):
/// backward breadth-first layers, each state taking a row into a lower
/// layer. Returns the row of each state reached.
pub(crate) fn attractor(
    view: &View<'_>,
    goal: &[bool],
    from: &[bool],
    allowed: &dyn Fn(usize) -> bool,
    choice: &mut [u32],
) {
    let n = view.n();
    let mut done = goal.to_vec();
    let mut queue: std::collections::VecDeque<u32> = (0..n as u32).filter(|&s| goal[s as usize]).collect();
    while let Some(t) = queue.pop_front() {
        for &(s, r) in view.back_of(t as usize) {
            let si = s as usize;
            if !done[si] && from[si] && allowed(r as usize) {
                done[si] = true;
                choice[si] = r;
                queue.push_back(s);
            }
        }
    }
}

impl View<'_> {
    pub(crate) fn back_of(&self, t: usize) -> &[(u32, u32)] {
        self.back.of(t)
    }
}

/// Greedy rows for the equations' states and the collapsed components'
/// routing: `values` per state (the midpoints).
pub(crate) fn extract_policy(
    view: &View<'_>,
    dir: Direction,
    collapse: &Collapse,
    row_value: &dyn Fn(usize) -> f64,
    choice: &mut [u32],
) {
    let n = view.n();
    let m = view.model;
    // Best row of each equation, over its states' rows not dropped.
    let mut best: Vec<(u32, f64)> = vec![(NONE, 0.0); collapse.count];
    for s in 0..n {
        let l = collapse.local[s];
        if l == NONE {
            continue;
        }
        for r in m.rows(s) {
            if collapse.inside[r] {
                continue;
            }
            let v = row_value(r);
            let slot = &mut best[l as usize];
            let better = slot.0 == NONE
                || match dir {
                    Direction::Min => v < slot.1,
                    Direction::Max => v > slot.1,
                };
            if better {
                *slot = (r as u32, v);
            }
        }
    }
    // Plain states take their best row; a collapsed component's exit state
    // takes its best row, the others route to it inside the component.
    let mut exit_state = vec![false; n];
    for s in 0..n {
        let l = collapse.local[s];
        if l == NONE {
            continue;
        }
        let r = best[l as usize].0;
        if r == NONE {
            continue;
        }
        if collapse.class[s] == NONE || m.rows(s).contains(&(r as usize)) {
            choice[s] = r;
            exit_state[s] = collapse.class[s] != NONE;
        }
    }
    let classes: Vec<bool> = collapse.class.iter().map(|&c| c != NONE).collect();
    if classes.iter().any(|&c| c) {
        let class = &collapse.class;
        let inside = &collapse.inside;
        let row_state = |r: usize| m.row_start.partition_point(|&x| x as usize <= r) - 1;
        let from: Vec<bool> = (0..n).map(|s| classes[s] && !exit_state[s]).collect();
        attractor(
            view,
            &exit_state,
            &from,
            &|r| {
                inside[r] && {
                    let s = row_state(r);
                    view.targets(r).iter().all(|&t| class[t as usize] == class[s])
                }
            },
            choice,
        );
    }
}

/// Bounds for every state: fixed values where the analysis fixed them,
/// the iteration's bounds elsewhere.
fn spread(collapse: &Collapse, fixed: &[(f64, f64)], b: &Bounds) -> (Vec<f64>, Vec<f64>) {
    let n = fixed.len();
    let mut lower = vec![0.0; n];
    let mut upper = vec![0.0; n];
    for s in 0..n {
        match collapse.local[s] {
            NONE => (lower[s], upper[s]) = fixed[s],
            l => {
                lower[s] = b.lower[l as usize];
                upper[s] = b.upper[l as usize];
            }
        }
    }
    (lower, upper)
}

/// The optimal values of `goal` in every state of `model`, with bounds and
/// a memoryless policy (see the module docs).
pub fn optimize(
    model: &Model,
    goal: &Goal,
    dir: Direction,
    params: &OptimizeParams,
    stop: Interrupt<'_>,
) -> Result<Optimum> {
    let start = Instant::now();
    let view = View::new(model);
    let mut out = match goal {
        Goal::Reach { target } => reach(&view, target, dir, params, stop)?,
        Goal::Total {
            target,
            state,
            action,
        } => total(&view, target, state, action, dir, params, stop)?,
        Goal::LongRun { state, action } => lra::long_run(&view, state, action, dir, params, stop)?,
    };
    out.seconds = start.elapsed().as_secs_f64();
    Ok(out)
}

/// The first row of every state: the policy's default.
fn first_rows(model: &Model) -> Vec<u32> {
    model.row_start[..model.num_states()].to_vec()
}

fn reach(
    view: &View<'_>,
    target: &[bool],
    dir: Direction,
    params: &OptimizeParams,
    stop: Interrupt<'_>,
) -> Result<Optimum> {
    let n = view.n();
    let st = &view.structure;
    let mut choice = first_rows(view.model);
    let (zero, one) = match dir {
        Direction::Max => (
            graph::prob0_max(st, &view.back, target, None),
            graph::prob1_max(st, &view.back, target),
        ),
        Direction::Min => {
            let zero = graph::prob0_min(st, &view.back, target);
            let one = graph::prob1_min(st, &view.back, target, &zero);
            (zero, one)
        }
    };
    let maybe: Vec<bool> = (0..n).map(|s| !zero[s] && !one[s] && !target[s]).collect();
    let ecs = (dir == Direction::Max).then(|| graph::mecs(st, &maybe, None));
    let collapse = Collapse::new(view, &maybe, ecs.as_ref().filter(|e| e.count > 0));
    let fixed: Vec<(f64, f64)> = (0..n)
        .map(|s| {
            if one[s] || target[s] {
                (1.0, 1.0)
            } else {
                (0.0, 0.0)
            }
        })
        .collect();
    let eq = collapse.equations(view, &fixed, None);
    let k = eq.num_states();
    let b =
        value_iteration::interval_iteration(&eq, dir, vec![0.0; k], vec![1.0; k], &params.precision, stop)?;
    let (lower, upper) = spread(&collapse, &fixed, &b);
    // Policy: value 1 states reach the target surely (max), value 0 states
    // avoid it (min), the others by their values.
    match dir {
        Direction::Max => {
            let inside_one = |r: usize| {
                view.targets(r)
                    .iter()
                    .all(|&t| one[t as usize] || target[t as usize])
            };
            let from: Vec<bool> = (0..n).map(|s| one[s] && !target[s]).collect();
            attractor(view, target, &from, &inside_one, &mut choice);
        }
        Direction::Min => {
            for s in (0..n).filter(|&s| zero[s]) {
                if let Some(r) = view
                    .model
                    .rows(s)
                    .find(|&r| view.targets(r).iter().all(|&t| zero[t as usize]))
                {
                    choice[s] = r as u32;
                }
            }
        }
    }
    let bounds = Bounds { lower, upper, ..b };
    Ok(optimum_of_bounds(
        view,
        dir,
        &collapse,
        bounds,
        Vec::new(),
        choice,
        "interval iteration",
    ))
}

/// The optimum from a solve's bounds: the policy of the states left to
/// choose by the middle of their bounds (`row_reward` added per row when
/// not empty), and the rest of the record.
fn optimum_of_bounds(
    view: &View<'_>,
    dir: Direction,
    collapse: &Collapse,
    b: Bounds,
    row_reward: Vec<f64>,
    mut choice: Vec<u32>,
    method: &'static str,
) -> Optimum {
    let (lower, upper) = (b.lower, b.upper);
    let mid: Vec<f64> = (0..view.n())
        .map(|s| lower[s] + (upper[s] - lower[s]) / 2.0)
        .collect();
    let (m, prob) = (view.model, &view.prob);
    let row_value = |r: usize| {
        let ahead = (m.entry_start[r] as usize..m.entry_start[r + 1] as usize)
            .map(|k| prob[k] * mid[m.col[k] as usize])
            .sum::<f64>();
        row_reward.get(r).map_or(ahead, |rho| rho + ahead)
    };
    extract_policy(view, dir, collapse, &row_value, &mut choice);
    Optimum {
        direction: dir,
        lower,
        upper,
        choice,
        row_reward,
        bias: Vec::new(),
        method,
        iterations: b.iterations,
        failed_guesses: b.failed_guesses,
        seconds: 0.0,
    }
}

#[allow(clippy::too_many_arguments)]
fn total(
    view: &View<'_>,
    target: &[bool],
    state: &[f64],
    action: &[f64],
    dir: Direction,
    params: &OptimizeParams,
    stop: Interrupt<'_>,
) -> Result<Optimum> {
    let n = view.n();
    let m = view.model;
    let st = &view.structure;
    let rho = view.row_rewards(state, action);
    let mut choice = first_rows(m);
    // States of infinite value, and the set every policy considered must
    // keep to.
    let finite = match dir {
        Direction::Max => {
            let zero = graph::prob0_min(st, &view.back, target);
            graph::prob1_min(st, &view.back, target, &zero)
        }
        Direction::Min => graph::prob1_max(st, &view.back, target),
    };
    let keeps = |r: usize| view.targets(r).iter().all(|&t| finite[t as usize]);
    // States of value 0.
    let zero_value = match dir {
        Direction::Max => {
            // No positive reward can be collected before the target.
            let positive: Vec<bool> = (0..n)
                .map(|s| !target[s] && m.rows(s).any(|r| rho[r] > 0.0))
                .collect();
            let within: Vec<bool> = (0..n).map(|s| !target[s]).collect();
            graph::prob0_max(st, &view.back, &positive, Some(&within))
                .iter()
                .zip(&finite)
                .map(|(&z, &f)| z && f)
                .collect::<Vec<bool>>()
        }
        Direction::Min => zero_reward_sure(view, target, &finite, &rho, &mut choice),
    };
    let maybe: Vec<bool> = (0..n)
        .map(|s| finite[s] && !target[s] && !zero_value[s])
        .collect();
    let ecs = if dir == Direction::Min {
        let zero_rows: Vec<bool> = (0..m.num_rows()).map(|r| rho[r] == 0.0 && keeps(r)).collect();
        Some(graph::mecs(st, &maybe, Some(&zero_rows)))
    } else {
        None
    };
    let collapse = Collapse::new(view, &maybe, ecs.as_ref().filter(|e| e.count > 0));
    let fixed: Vec<(f64, f64)> = (0..n)
        .map(|s| {
            if finite[s] {
                (0.0, 0.0)
            } else {
                (f64::INFINITY, f64::INFINITY)
            }
        })
        .collect();
    let eq = collapse.equations(view, &fixed, Some(&rho));
    let k = eq.num_states();
    let b = value_iteration::optimistic(&eq, dir, vec![0.0; k], &params.precision, stop)?;
    let (lower, upper) = spread(&collapse, &fixed, &b);
    let bounds = Bounds { lower, upper, ..b };
    Ok(optimum_of_bounds(
        view,
        dir,
        &collapse,
        bounds,
        rho,
        choice,
        "optimistic value iteration",
    ))
}

/// For `Rmin`: the states from which some policy reaches `target` surely
/// collecting no reward (value 0), with the rows that do it set in
/// `choice`: `Pmax = 1` on the sub-MDP of the zero-reward rows that keep
/// to `finite`.
fn zero_reward_sure(
    view: &View<'_>,
    target: &[bool],
    finite: &[bool],
    rho: &[f64],
    choice: &mut [u32],
) -> Vec<bool> {
    let n = view.n();
    let m = view.model;
    let ok = |r: usize| rho[r] == 0.0 && view.targets(r).iter().all(|&t| finite[t as usize]);
    // The sub-MDP's structure: states keep only their zero-reward rows (a
    // state without any gets an impossible self-row, which never helps).
    let mut row_start = vec![0u32];
    let mut entry_start = vec![0u64];
    let mut col = Vec::new();
    let mut orig = Vec::new();
    for s in 0..n {
        let mut any = false;
        for r in m.rows(s).filter(|&r| ok(r)) {
            col.extend_from_slice(view.targets(r));
            entry_start.push(col.len() as u64);
            orig.push(r as u32);
            any = true;
        }
        if !any {
            col.push(s as u32);
            entry_start.push(col.len() as u64);
            orig.push(NONE);
        }
        row_start.push(orig.len() as u32);
    }
    let sub = Structure {
        row_start: &row_start,
        entry_start: &entry_start,
        col: &col,
    };
    let back = Backward::new(&sub);
    let mut one = graph::prob1_max(&sub, &back, target);
    for s in 0..n {
        if !finite[s] || target[s] {
            one[s] = false;
        }
    }
    // Rows reaching the target surely inside `one`: backward layers.
    let mut done = target.to_vec();
    let mut queue: std::collections::VecDeque<u32> = (0..n as u32).filter(|&s| target[s as usize]).collect();
    while let Some(t) = queue.pop_front() {
        for &(s, r) in back.of(t as usize) {
            let (si, ri) = (s as usize, r as usize);
            let keeps = sub.col[sub.entry_start[ri] as usize..sub.entry_start[ri + 1] as usize]
                .iter()
                .all(|&u| one[u as usize] || target[u as usize]);
            if !done[si] && one[si] && orig[ri] != NONE && keeps {
                done[si] = true;
                choice[si] = orig[ri];
                queue.push_back(s);
            }
        }
    }
    one
}
