//! Route planning by propagation over the fuzzy Petri net
//! (`docs/topo-fpn.md`, "Route planning by propagation").
//!
//! 1. `α(p_g) = 0` for every goal place, `α(p) = 1` for the others.
//! 2. Rounds of, with synchronous updates (every `f` from the `α` of the
//!    previous round, then every `α`):
//!    1. *composition* `f(t) = min(1, C(t) + α(p_j))` for `t: p_i → p_j`;
//!    2. *thresholding*: if `f(t) > λ(t)` then `f(t) = 1` (rejected);
//!    3. *inference*: `α(p_i) = min(α(p_i), min_{t leaving p_i} f(t))`.
//! 3. The route: from the start, at each place the leaving transition with
//!    the smallest `f` (ties: the smallest id), until a goal; a rejected
//!    transition is never taken.
//!
//! `C(t) = c_t / Σ_u c_u` over all transitions (see [`fpn`](super::fpn)).
//!
//! # Modes
//!
//! * [`PlanMode::Paper`]: the source's stopping rule, rounds while the start
//!   has `α(p_s) = 1`, by the literal propagation ([`Planner::propagate_literal`]
//!   with [`Stop::StartReached`]). After `k` rounds `α(p)` is the cheapest
//!   value of routes of at most `k` transitions, so the rule stops after the
//!   fewest transitions `k*` of any route, with `α(p_s)` the value of the
//!   cheapest route of `k*` transitions. Step 3 then walks along the
//!   smallest `f` of that last round, which at the start's successors already
//!   counts routes of `k*` transitions from them: the route walked may take
//!   more than `k*` transitions and cost less than `α(p_s)`, never less than
//!   the cheapest route (the property tests check both bounds; the CLI shows
//!   `α(p_s)` beside the route's cost). Stops too when a round changes
//!   nothing (no route). `O(k* · (|P| + |T|))`.
//! * [`PlanMode::Optimal`] (default): the fixed point of the same rounds, the
//!   cheapest route. Computed by a label-setting search
//!   ([`Planner::label_setting`]) rather than by rounds: the literal rounds
//!   take up to the number of transitions of the longest cheapest route
//!   (the hop diameter: about 200 rounds of 40 000 transitions on a
//!   10 000-place map), the search `O((|P| + |T|) log |P|)`.
//!
//! # The label-setting search, and why it is the fixed point
//!
//! Write the round for one transition as a function of its destination's
//! value, `g_t(a) = min(1, C(t) + a)` if that is `≤ λ(t)`, else "rejected"
//! (∞ below, shown as 1). Every `g_t` is **non-decreasing** in `a` (the sum
//! and the clamp are; the threshold turns a value above `λ(t)` into ∞,
//! which is larger still) and **does not decrease a value**: `g_t(a) ≥ a`
//! for `a ≤ 1` because `C(t) ≥ 0`, also in floating point, where `fl(C + a)
//! ≥ a` since rounding is monotone. The rounds are the Bellman–Ford
//! iteration of `α(p) = min(α(p), min_t g_t(α(p_j)))` from the initial
//! values; after `k` rounds `α(p)` is the least value, over routes of at
//! most `k` transitions from `p` to a goal, of the route's functions
//! composed from the goal back (`g_{t1}(g_{t2}(… g_{tk}(0)))`). Since no
//! `g_t` decreases a value and all are non-decreasing, leaving a cycle out
//! of a route never makes it worse, so simple routes suffice, there are at
//! most `|P| − 1` transitions in one, and the rounds reach their fixed point
//! — the least value over all routes — after at most `|P| − 1` rounds that
//! change something. Dijkstra's algorithm computes exactly that least value
//! for such non-decreasing, non-decreasing-along-edges ("superior") edge
//! functions (Knuth, *A generalization of Dijkstra's algorithm*, 1977):
//! settle places from the goals backwards in increasing `α`; when `p_j` is
//! settled its `α(p_j)` is final, and every transition `t: p_i → p_j` is
//! relaxed once with `g_t(α(p_j))`.
//!
//! **The threshold depends on the route.** Whether `t` is rejected depends
//! on `α(p_j)`: rejected given one route from `p_j`, accepted given a
//! cheaper one. The rounds may reject `t` early and accept it once `α(p_j)`
//! has dropped; at the fixed point `t` is judged with the final `α(p_j)`.
//! The search judges `t` once, when `p_j` is settled — with the final
//! `α(p_j)`, so exactly as the fixed point does. Because `g_t` is
//! non-decreasing, a cheaper destination can only turn a rejected
//! transition into an accepted one, never the reverse, which is why judging
//! it once with the least `α(p_j)` is right.
//!
//! Both compute every value with the same floating-point expression, and
//! both values are minima over the same set of numbers, so they agree bit
//! for bit (the tests check it on random nets).
//!
//! # Decision: a route costing exactly 1
//!
//! The spec gives `f = 1` two meanings: "rejected or no route" and, through
//! the clamp, "costs 1". A simple route costs at most 1, and exactly 1 only
//! when it takes every transition of the net (a corridor explored one way,
//! or a map of two places). Read literally, such a route would never be
//! taken. Here the two are kept apart: a place is *reached* when some
//! accepted route leads from it to a goal, a transition *accepted* when its
//! destination is reached and `f(t) ≤ λ(t)`; only unreached places and
//! rejected transitions count as "`α = 1`" in the stopping rule and as
//! "never taken" in step 3, and [`Plan::reached`]/[`Plan::accepted`] say
//! which they are. In every other case this is the spec to the letter.
//!
//! # Route extraction
//!
//! With exact arithmetic the walk of step 3 cannot loop: at the fixed point
//! each step goes to a place with `α` smaller by `C(t) > 0`, and in paper
//! mode each step after the first goes to a place whose `α` of the round
//! before is smaller by `C(t)`. In floating point a weighted cost below
//! half an ulp of `α` (costs differing by a factor of 2^53 or more) adds
//! nothing; the walk then checks for a place visited twice and reports
//! [`PlanError::Cycle`] rather than looping.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use serde::Serialize;

use super::fpn::{FuzzyPetriNet, PlaceId, TransitionId};

/// Which stopping rule the propagation follows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PlanMode {
    /// The source's rule: stop as soon as `α(start) < 1` (or when a round
    /// changes nothing): `α(start)` is the value of the cheapest route
    /// among the shortest in transitions, and the route walked along the
    /// last round's `f` costs at most that (see the module documentation).
    Paper,
    /// To the fixed point: the cheapest route.
    #[default]
    Optimal,
}

impl PlanMode {
    /// `paper` or `optimal`.
    pub fn name(self) -> &'static str {
        match self {
            PlanMode::Paper => "paper",
            PlanMode::Optimal => "optimal",
        }
    }
}

/// When the literal propagation stops.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stop {
    /// As soon as this place is reached (`α < 1`), or when a round changes
    /// nothing: the paper's rule.
    StartReached(PlaceId),
    /// When a round changes nothing.
    FixedPoint,
}

/// What can go wrong while planning.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PlanError {
    /// A place id the map does not have.
    #[error("no place #{id}: the map has {places} places")]
    UnknownPlace {
        /// The id.
        id: u32,
        /// How many places the map has.
        places: usize,
    },
    /// A place name the map does not have.
    #[error("no place named `{name}` in the map")]
    UnknownPlaceName {
        /// The name.
        name: String,
    },
    /// No goal was given.
    #[error("no goal place given")]
    NoGoal,
    /// No route: every route from the start to the goals is missing or has
    /// a transition rejected by its threshold.
    #[error(
        "no route from `{start}` to `{}`: no sequence of transitions leads there, or every one has a transition rejected by its threshold λ",
        .goals.join("`, `")
    )]
    NoRoute {
        /// The start's name.
        start: String,
        /// The goals' names.
        goals: Vec<String>,
    },
    /// The walk of step 3 came back to a place (only with weighted costs so
    /// small against others that adding them changes nothing).
    #[error(
        "the route from `{start}` comes back to `{place}`: weighted costs differ too much (by 2^53 or more) to be added exactly"
    )]
    Cycle {
        /// The start's name.
        start: String,
        /// The place visited twice.
        place: String,
    },
    /// The walk of step 3 reached a place with no accepted leaving
    /// transition (cannot happen; reported rather than panicking).
    #[error("the route from `{start}` reached `{place}`, where every leaving transition is rejected")]
    DeadEnd {
        /// The start's name.
        start: String,
        /// The place.
        place: String,
    },
}

/// The values `α` and `f` the propagation ends with.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Propagation {
    /// `α(p)` by place, in `[0, 1]`: 0 at the goals, 1 where no accepted
    /// route leads (and, exactly, for a route costing 1).
    pub alpha: Vec<f64>,
    /// `f(t)` by transition, in `[0, 1]`: 1 when rejected or leading to an
    /// unreached place. In paper mode, the `f` of the last round (computed
    /// from the `α` of the round before).
    pub f: Vec<f64>,
    /// By place: whether an accepted route leads from it to a goal.
    pub reached: Vec<bool>,
    /// By transition: whether its destination is reached and `f(t) ≤ λ(t)`.
    pub accepted: Vec<bool>,
    /// Literal propagation: the rounds performed (the last one of a fixed
    /// point changes nothing). Label-setting search: the places settled.
    pub iterations: usize,
}

/// A planned route and the values behind it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Plan {
    /// The stopping rule used.
    pub mode: PlanMode,
    /// Where the route starts.
    pub start: PlaceId,
    /// The goal places given.
    pub goals: Vec<PlaceId>,
    /// The transitions to take, in order (empty when the start is a goal).
    pub route: Vec<TransitionId>,
    /// The places along the route: the start, then the destination of each
    /// transition; the last one is a goal.
    pub places: Vec<PlaceId>,
    /// `Σ C(t)` along the route, added from the start.
    pub cost: f64,
    /// `α(p)` by place (see [`Propagation::alpha`]).
    pub alpha: Vec<f64>,
    /// `f(t)` by transition (see [`Propagation::f`]).
    pub f: Vec<f64>,
    /// By place: whether an accepted route leads from it to a goal.
    pub reached: Vec<bool>,
    /// By transition: accepted (not rejected, destination reached).
    pub accepted: Vec<bool>,
    /// Paper mode: the rounds of the propagation. Optimal mode: the places
    /// settled by the label-setting search.
    pub iterations: usize,
}

impl Plan {
    /// The goal the route reaches.
    pub fn goal(&self) -> PlaceId {
        *self.places.last().unwrap_or(&self.start)
    }
}

/// The net laid out flat for planning: weighted costs, thresholds and the
/// transitions entering each place in compressed rows. Built once in
/// `O(|P| + |T|)`; plans as many routes as wanted while the net is not
/// changed (it borrows the net).
#[derive(Debug, Clone)]
pub struct Planner<'a> {
    net: &'a FuzzyPetriNet,
    /// `C(t)` by transition.
    weighted: Vec<f64>,
    /// `λ(t)` by transition.
    lambda: Vec<f64>,
    /// Destination of each transition.
    to: Vec<u32>,
    /// Origin of each transition.
    from: Vec<u32>,
    /// Transitions entering place `q`: `in_start[q]..in_start[q + 1]`.
    in_start: Vec<u32>,
    /// Their origins…
    in_from: Vec<u32>,
    /// … weighted costs …
    in_weighted: Vec<f64>,
    /// … and thresholds.
    in_lambda: Vec<f64>,
}

/// `g_t(a)`: the value of a transition whose destination has `α = a`, ∞
/// when rejected or when the destination is unreached (`a = ∞`).
#[inline]
fn compose(weighted: f64, alpha_dest: f64, lambda: f64) -> f64 {
    if alpha_dest == f64::INFINITY {
        return f64::INFINITY;
    }
    let v = weighted + alpha_dest;
    let f = if v < 1.0 { v } else { 1.0 };
    if f > lambda { f64::INFINITY } else { f }
}

/// Values with ∞ for "unreached"/"rejected" into a [`Propagation`].
fn finish(alpha: Vec<f64>, f: Vec<f64>, iterations: usize) -> Propagation {
    let reached = alpha.iter().map(|a| a.is_finite()).collect();
    let accepted = f.iter().map(|v| v.is_finite()).collect();
    let clamp = |v: f64| if v.is_finite() { v } else { 1.0 };
    Propagation {
        alpha: alpha.into_iter().map(clamp).collect(),
        f: f.into_iter().map(clamp).collect(),
        reached,
        accepted,
        iterations,
    }
}

impl<'a> Planner<'a> {
    /// Lays the net out. `O(|P| + |T|)`.
    pub fn new(net: &'a FuzzyPetriNet) -> Planner<'a> {
        let total = net.total_cost();
        let transitions = net.transitions();
        let weighted: Vec<f64> = transitions.iter().map(|t| t.cost / total).collect();
        let mut in_start = Vec::with_capacity(net.num_places() + 1);
        let mut in_from = Vec::with_capacity(transitions.len());
        let mut in_weighted = Vec::with_capacity(transitions.len());
        let mut in_lambda = Vec::with_capacity(transitions.len());
        in_start.push(0);
        for q in net.place_ids() {
            for &t in net.entering(q) {
                let tr = &transitions[t.index()];
                in_from.push(tr.from.0);
                in_weighted.push(weighted[t.index()]);
                in_lambda.push(tr.lambda);
            }
            in_start.push(in_from.len() as u32);
        }
        Planner {
            net,
            to: transitions.iter().map(|t| t.to.0).collect(),
            from: transitions.iter().map(|t| t.from.0).collect(),
            lambda: transitions.iter().map(|t| t.lambda).collect(),
            weighted,
            in_start,
            in_from,
            in_weighted,
            in_lambda,
        }
    }

    /// The net planned over.
    pub fn net(&self) -> &'a FuzzyPetriNet {
        self.net
    }

    fn check(&self, place: PlaceId) -> Result<(), PlanError> {
        if place.index() < self.net.num_places() {
            Ok(())
        } else {
            Err(PlanError::UnknownPlace {
                id: place.0,
                places: self.net.num_places(),
            })
        }
    }

    fn check_goals(&self, goals: &[PlaceId]) -> Result<(), PlanError> {
        if goals.is_empty() {
            return Err(PlanError::NoGoal);
        }
        goals.iter().try_for_each(|&g| self.check(g))
    }

    fn initial_alpha(&self, goals: &[PlaceId]) -> Vec<f64> {
        let mut alpha = vec![f64::INFINITY; self.net.num_places()];
        for g in goals {
            alpha[g.index()] = 0.0;
        }
        alpha
    }

    /// The propagation exactly as the spec writes it: synchronous rounds of
    /// composition, thresholding and inference, until `stop`. The reference
    /// the fast search is checked against, and the paper mode.
    ///
    /// `O(rounds · (|P| + |T|))`, with at most `|P|` rounds (see the module
    /// documentation).
    pub fn propagate_literal(&self, goals: &[PlaceId], stop: Stop) -> Result<Propagation, PlanError> {
        self.check_goals(goals)?;
        if let Stop::StartReached(s) = stop {
            self.check(s)?;
        }
        let mut alpha = self.initial_alpha(goals);
        let mut f = vec![f64::INFINITY; self.weighted.len()];
        let mut rounds = 0;
        // Every round that changes something lowers the value of some place
        // to that of a simple route with one more transition, so at most
        // |P| rounds happen; the bound only guards against a mistake.
        let max_rounds = self.net.num_places() + 1;
        loop {
            let start_reached = match stop {
                Stop::StartReached(s) => alpha[s.index()].is_finite(),
                Stop::FixedPoint => false,
            };
            if start_reached {
                break;
            }
            if rounds == max_rounds {
                debug_assert!(false, "the propagation did not reach its fixed point");
                break;
            }
            rounds += 1;
            // Composition and thresholding, all from the previous α.
            for (t, ft) in f.iter_mut().enumerate() {
                *ft = compose(self.weighted[t], alpha[self.to[t] as usize], self.lambda[t]);
            }
            // Inference.
            let mut changed = false;
            for (t, &ft) in f.iter().enumerate() {
                let p = self.from[t] as usize;
                if ft < alpha[p] {
                    alpha[p] = ft;
                    changed = true;
                }
            }
            if !changed {
                break;
            }
        }
        Ok(finish(alpha, f, rounds))
    }

    /// The fixed point of the propagation by a label-setting search from the
    /// goals backwards (Dijkstra with a binary heap, ties by place id; see
    /// the module documentation for why it equals the fixed point).
    /// [`Propagation::iterations`] counts the places settled.
    ///
    /// `O((|P| + |T|) log |P|)`.
    pub fn label_setting(&self, goals: &[PlaceId]) -> Result<Propagation, PlanError> {
        self.check_goals(goals)?;
        let n = self.net.num_places();
        let mut alpha = self.initial_alpha(goals);
        let mut settled = vec![false; n];
        let mut settled_count = 0;
        // Values are ≥ 0, so their bit patterns order as they do.
        let mut heap: BinaryHeap<Reverse<(u64, u32)>> = BinaryHeap::with_capacity(n.min(1 << 16));
        for g in goals {
            heap.push(Reverse((0.0f64.to_bits(), g.0)));
        }
        while let Some(Reverse((bits, q))) = heap.pop() {
            let q = q as usize;
            if settled[q] || bits != alpha[q].to_bits() {
                continue;
            }
            settled[q] = true;
            settled_count += 1;
            let aq = alpha[q];
            let (lo, hi) = (self.in_start[q] as usize, self.in_start[q + 1] as usize);
            for k in lo..hi {
                let p = self.in_from[k] as usize;
                if settled[p] {
                    continue;
                }
                let fv = compose(self.in_weighted[k], aq, self.in_lambda[k]);
                if fv < alpha[p] {
                    alpha[p] = fv;
                    heap.push(Reverse((fv.to_bits(), p as u32)));
                }
            }
        }
        let f = (0..self.weighted.len())
            .map(|t| compose(self.weighted[t], alpha[self.to[t] as usize], self.lambda[t]))
            .collect();
        Ok(finish(alpha, f, settled_count))
    }

    /// Plans a route from `start` to the nearest of `goals` (see the module
    /// documentation for the modes).
    pub fn plan(&self, start: PlaceId, goals: &[PlaceId], mode: PlanMode) -> Result<Plan, PlanError> {
        self.check(start)?;
        let values = match mode {
            PlanMode::Paper => self.propagate_literal(goals, Stop::StartReached(start))?,
            PlanMode::Optimal => self.label_setting(goals)?,
        };
        let (route, places) = self.extract(&values, start, goals)?;
        let cost = route.iter().fold(0.0, |s, t| s + self.weighted[t.index()]);
        Ok(Plan {
            mode,
            start,
            goals: goals.to_vec(),
            route,
            places,
            cost,
            alpha: values.alpha,
            f: values.f,
            reached: values.reached,
            accepted: values.accepted,
            iterations: values.iterations,
        })
    }

    /// Step 3: the walk from the start along the smallest `f`.
    fn extract(
        &self,
        values: &Propagation,
        start: PlaceId,
        goals: &[PlaceId],
    ) -> Result<(Vec<TransitionId>, Vec<PlaceId>), PlanError> {
        let name = |p: PlaceId| self.net.place(p).name.clone();
        let mut is_goal = vec![false; self.net.num_places()];
        for g in goals {
            is_goal[g.index()] = true;
        }
        if !values.reached[start.index()] {
            return Err(PlanError::NoRoute {
                start: name(start),
                goals: goals.iter().map(|&g| name(g)).collect(),
            });
        }
        let mut visited = vec![false; self.net.num_places()];
        let mut route = Vec::new();
        let mut places = vec![start];
        let mut at = start;
        while !is_goal[at.index()] {
            if std::mem::replace(&mut visited[at.index()], true) {
                return Err(PlanError::Cycle {
                    start: name(start),
                    place: name(at),
                });
            }
            let mut best: Option<TransitionId> = None;
            for &t in self.net.leaving(at) {
                if values.accepted[t.index()]
                    && best.is_none_or(|b| values.f[t.index()] < values.f[b.index()])
                {
                    best = Some(t);
                }
            }
            let Some(t) = best else {
                return Err(PlanError::DeadEnd {
                    start: name(start),
                    place: name(at),
                });
            };
            route.push(t);
            at = self.net.transition(t).to;
            places.push(at);
        }
        Ok((route, places))
    }
}

/// Plans a route on `net` ([`Planner::plan`]; lays the net out first, which
/// costs about as much as an optimal plan: keep a [`Planner`] to plan many
/// routes).
pub fn plan(
    net: &FuzzyPetriNet,
    start: PlaceId,
    goals: &[PlaceId],
    mode: PlanMode,
) -> Result<Plan, PlanError> {
    Planner::new(net).plan(start, goals, mode)
}

/// [`plan`] with places given by name.
pub fn plan_by_name(
    net: &FuzzyPetriNet,
    start: &str,
    goals: &[&str],
    mode: PlanMode,
) -> Result<Plan, PlanError> {
    let find = |name: &str| {
        net.place_id(name).ok_or_else(|| PlanError::UnknownPlaceName {
            name: name.to_string(),
        })
    };
    let start = find(start)?;
    let goals = goals.iter().map(|g| find(g)).collect::<Result<Vec<_>, _>>()?;
    plan(net, start, &goals, mode)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fpn::{Place, PlaceKind, Strategy, Transition, Turn};

    /// Places p1…pn and transitions `(from, to, cost)` (1-based places).
    fn net(n: usize, arcs: &[(u32, u32, f64)]) -> FuzzyPetriNet {
        let mut net = FuzzyPetriNet::new();
        for i in 0..n {
            net.add_place(Place::new(i as f64, 0.0, 0.0, PlaceKind::A))
                .unwrap();
        }
        for &(a, b, c) in arcs {
            let mut t = Transition::new(
                PlaceId(a - 1),
                PlaceId(b - 1),
                Strategy::FreeMovement,
                Turn::Right,
                1.0,
            );
            t.cost = c;
            net.add_transition(t).unwrap();
        }
        net
    }

    #[test]
    fn paper_stops_at_the_fewest_transitions() {
        // p1 → p4 directly (cost 10), or p1 → p2 → p3 → p4 (cost 3).
        let n = net(4, &[(1, 4, 10.0), (1, 2, 1.0), (2, 3, 1.0), (3, 4, 1.0)]);
        let planner = Planner::new(&n);
        let paper = planner.plan(PlaceId(0), &[PlaceId(3)], PlanMode::Paper).unwrap();
        assert_eq!(paper.route, [TransitionId(0)]);
        assert_eq!(paper.iterations, 1);
        assert_eq!(paper.cost, 10.0 / 13.0);
        let optimal = planner
            .plan(PlaceId(0), &[PlaceId(3)], PlanMode::Optimal)
            .unwrap();
        assert_eq!(optimal.route, [TransitionId(1), TransitionId(2), TransitionId(3)]);
        assert!((optimal.cost - 3.0 / 13.0).abs() < 1e-15);
        assert_eq!(optimal.places, [PlaceId(0), PlaceId(1), PlaceId(2), PlaceId(3)]);
        // The literal propagation to the fixed point takes 3 rounds that
        // change something and one that does not.
        let fixed = planner
            .propagate_literal(&[PlaceId(3)], Stop::FixedPoint)
            .unwrap();
        assert_eq!(fixed.iterations, 4);
        assert_eq!(fixed.alpha, optimal.alpha);
    }

    #[test]
    fn a_route_through_every_transition_costs_one_and_is_taken() {
        let n = net(2, &[(1, 2, 4.0)]);
        for mode in [PlanMode::Paper, PlanMode::Optimal] {
            let plan = plan(&n, PlaceId(0), &[PlaceId(1)], mode).unwrap();
            assert_eq!(plan.route, [TransitionId(0)]);
            assert_eq!(plan.f, [1.0]);
            assert_eq!(plan.alpha, [1.0, 0.0]);
            assert_eq!((plan.reached[0], plan.accepted[0]), (true, true));
        }
        // Any threshold below 1 rejects it.
        let mut n = n;
        n.set_lambda(TransitionId(0), 0.999).unwrap();
        let e = plan(&n, PlaceId(0), &[PlaceId(1)], PlanMode::Optimal).unwrap_err();
        assert!(matches!(e, PlanError::NoRoute { .. }), "{e}");
    }

    #[test]
    fn start_at_a_goal_and_bad_arguments() {
        let n = net(3, &[(1, 2, 1.0)]);
        let p = plan(&n, PlaceId(1), &[PlaceId(1)], PlanMode::Paper).unwrap();
        assert!(p.route.is_empty());
        assert_eq!(
            (p.places.as_slice(), p.cost, p.iterations),
            ([PlaceId(1)].as_slice(), 0.0, 0)
        );
        assert_eq!(p.goal(), PlaceId(1));
        assert_eq!(
            plan(&n, PlaceId(0), &[], PlanMode::Optimal).unwrap_err(),
            PlanError::NoGoal
        );
        assert!(matches!(
            plan(&n, PlaceId(3), &[PlaceId(0)], PlanMode::Optimal).unwrap_err(),
            PlanError::UnknownPlace { id: 3, places: 3 }
        ));
        assert!(matches!(
            plan(&n, PlaceId(0), &[PlaceId(9)], PlanMode::Paper).unwrap_err(),
            PlanError::UnknownPlace { id: 9, .. }
        ));
        let e = plan_by_name(&n, "p1", &["p3", "p2"], PlanMode::Optimal).unwrap();
        assert_eq!(e.goal(), PlaceId(1));
        assert_eq!(
            plan_by_name(&n, "p1", &["nowhere"], PlanMode::Optimal).unwrap_err(),
            PlanError::UnknownPlaceName {
                name: "nowhere".into()
            }
        );
        let e = plan_by_name(&n, "p2", &["p1", "p3"], PlanMode::Paper).unwrap_err();
        assert_eq!(
            e.to_string(),
            "no route from `p2` to `p1`, `p3`: no sequence of transitions leads there, or every one has a transition rejected by its threshold λ"
        );
    }

    #[test]
    fn ties_go_to_the_smallest_transition_id() {
        let n = net(3, &[(1, 3, 2.0), (1, 2, 1.0), (2, 3, 1.0), (1, 3, 2.0)]);
        let p = plan(&n, PlaceId(0), &[PlaceId(2)], PlanMode::Optimal).unwrap();
        // f(t0) = f(t3) = 2/6; f(t1) = 1/6 + 1/6, equal in floating point too.
        assert_eq!(p.f[0], p.f[3]);
        assert_eq!(p.f[0], p.f[1]);
        assert_eq!(p.route, [TransitionId(0)]);
    }
}
