//! Route planning on fuzzy Petri nets (`topo::propagation`) against
//! independent algorithms written here, on random nets with cycles,
//! self-loops, parallel transitions, several goals, unreachable goals,
//! costs of many magnitudes (and ties) and thresholds that reject some
//! transitions; then hand-made nets for what random ones show rarely.
//!
//! **The rejection rule, as the spec writes it:** `f(t) = min(1, C(t) +
//! α(p_j)) > λ(t)` rejects `t`. It depends on `α(p_j)`, the value of the
//! transition's destination, so it is judged *per route*: the same
//! transition is accepted on a route whose rest is cheap and rejected on one
//! whose rest is dear. The oracles mirror that:
//!
//! * `bellman_ford`: plain Bellman–Ford over the transitions, from the goals
//!   backwards: repeat "for every transition `t: p → q` with `d(q)` known,
//!   `f = min(1, C(t) + d(q))`; if `f ≤ λ(t)` and `f < d(p)` then
//!   `d(p) = f`" until nothing changes (updates in place, in transition
//!   order, so a different order from the library's synchronous rounds and
//!   its heap). A transition is judged with its destination's current
//!   value, and again whenever that value drops.
//! * `brute_force` (small nets): every simple route from the start that
//!   ends at its first goal, valued from the goal back with each transition
//!   judged by the value of *that route's* rest; the least value, the
//!   fewest transitions among valid routes, and the least value among valid
//!   routes of that many transitions.
//!
//! Properties: in `optimal` mode every place's `α` equals Bellman–Ford's
//! bit for bit (`C(t) + α` is rounded the same way and the minimum is over
//! the same numbers), and equals the brute force's minimum; the route is a
//! valid route (consecutive transitions from the start to a goal, each
//! accepted given the route's rest) whose value is `α(start)` and whose
//! cost is the shortest distance; no route ⇔ [`PlanError::NoRoute`] ⇔ no
//! valid route; the literal rounds to the fixed point give the same values
//! bit for bit. In `paper` mode: the same "no route" cases, never cheaper
//! than `optimal`, `α(start)` the least value among valid routes with the
//! fewest transitions, that many rounds, and a valid route worth at most
//! `α(start)` (step 3 walks the last round's `f`, which may lead along more
//! transitions than there were rounds: see the last test).

use proptest::prelude::*;
use topo::{
    FuzzyPetriNet, Place, PlaceId, PlaceKind, Plan, PlanError, PlanMode, Planner, Stop,
    Strategy as Behaviour, ThresholdParams, Transition, TransitionId, Turn, plan,
};

/// A random net: places `0..n`, transitions `(from, to, cost, λ)`.
#[derive(Debug, Clone)]
struct Case {
    n: usize,
    arcs: Vec<(usize, usize, f64, f64)>,
    goals: Vec<usize>,
    start: usize,
}

fn cost() -> impl Strategy<Value = f64> {
    prop_oneof![
        3 => 1.0f64..20.0,
        // Ties.
        2 => Just(1.0),
        1 => Just(4.0),
        // Magnitudes from 10^-3 to 10^3.
        2 => (-3.0f64..3.0).prop_map(|e| 10f64.powf(e)),
    ]
}

fn lambda() -> impl Strategy<Value = f64> {
    prop_oneof![
        6 => Just(1.0),
        2 => 0.0f64..1.0,
        // Low enough to reject most routes, not all.
        2 => 0.0f64..0.4,
        // Learnt after k failures.
        1 => (1i32..12).prop_map(|k| 0.5f64.powi(k)),
        1 => Just(0.0),
    ]
}

fn case(max_places: usize) -> impl Strategy<Value = Case> {
    (1..=max_places)
        .prop_flat_map(|n| {
            let arc = (0..n, 0..n, cost(), lambda());
            (
                Just(n),
                prop::collection::vec(arc, n - 1..=3 * n),
                prop::collection::vec(0..n, 1..=3),
                0..n,
            )
        })
        .prop_map(|(n, arcs, goals, start)| Case {
            n,
            arcs,
            goals,
            start,
        })
}

fn build(c: &Case) -> FuzzyPetriNet {
    let mut net = FuzzyPetriNet::new();
    for i in 0..c.n {
        net.add_place(Place::new(i as f64, 0.0, 0.0, PlaceKind::A))
            .unwrap();
    }
    for &(a, b, cost, lambda) in &c.arcs {
        let mut t = Transition::new(
            PlaceId(a as u32),
            PlaceId(b as u32),
            Behaviour::FreeMovement,
            Turn::Straight,
            0.0,
        );
        t.cost = cost;
        t.lambda = lambda;
        net.add_transition(t).unwrap();
    }
    net
}

/// `(from, to, C(t), λ(t))` by transition: `C(t) = c_t / Σ c_u`, the sum in
/// transition order.
fn weighted(c: &Case) -> Vec<(usize, usize, f64, f64)> {
    let total = c.arcs.iter().fold(0.0, |s, a| s + a.2);
    c.arcs.iter().map(|&(a, b, w, l)| (a, b, w / total, l)).collect()
}

/// The value of a transition whose destination has value `rest`: `None`
/// when rejected (`f > λ`).
fn judge(weighted_cost: f64, rest: f64, lambda: f64) -> Option<f64> {
    let f = (weighted_cost + rest).min(1.0);
    (f <= lambda).then_some(f)
}

/// Plain Bellman–Ford from the goals backwards (see the module docs):
/// `d(p)`, `∞` where no valid route leads to a goal.
fn bellman_ford(c: &Case) -> Vec<f64> {
    let arcs = weighted(c);
    let mut d = vec![f64::INFINITY; c.n];
    for &g in &c.goals {
        d[g] = 0.0;
    }
    let mut passes = 0;
    loop {
        let mut changed = false;
        for &(p, q, w, l) in &arcs {
            if d[q].is_finite()
                && let Some(f) = judge(w, d[q], l)
                && f < d[p]
            {
                d[p] = f;
                changed = true;
            }
        }
        if !changed {
            return d;
        }
        passes += 1;
        assert!(passes <= c.n + 1, "Bellman–Ford converges in |P| passes");
    }
}

/// What enumerating every simple route gives.
#[derive(Debug, PartialEq)]
struct Brute {
    /// The least value of a valid route (`None`: no valid route).
    best: Option<f64>,
    /// The fewest transitions of a valid route.
    fewest: Option<usize>,
    /// The least value among the valid routes with `fewest` transitions.
    best_of_fewest: Option<f64>,
}

/// Every simple route from the start ending at its first goal (see the
/// module docs). Exponential: small nets only.
fn brute_force(c: &Case) -> Brute {
    let arcs = weighted(c);
    let is_goal = |p: usize| c.goals.contains(&p);
    let mut out = Brute {
        best: None,
        fewest: None,
        best_of_fewest: None,
    };
    let mut valid: Vec<(usize, f64)> = Vec::new();
    // Depth-first over routes, with the transitions taken so far.
    fn walk(
        at: usize,
        route: &mut Vec<usize>,
        visited: &mut Vec<bool>,
        arcs: &[(usize, usize, f64, f64)],
        is_goal: &dyn Fn(usize) -> bool,
        valid: &mut Vec<(usize, f64)>,
    ) {
        if is_goal(at) {
            // Valued from the goal back, each transition judged by the rest.
            let mut rest = 0.0;
            for &t in route.iter().rev() {
                match judge(arcs[t].2, rest, arcs[t].3) {
                    Some(f) => rest = f,
                    None => return,
                }
            }
            valid.push((route.len(), rest));
            return;
        }
        for (t, &(p, q, _, _)) in arcs.iter().enumerate() {
            if p == at && !visited[q] {
                visited[q] = true;
                route.push(t);
                walk(q, route, visited, arcs, is_goal, valid);
                route.pop();
                visited[q] = false;
            }
        }
    }
    let mut visited = vec![false; c.n];
    visited[c.start] = true;
    walk(
        c.start,
        &mut Vec::new(),
        &mut visited,
        &arcs,
        &is_goal,
        &mut valid,
    );
    for &(hops, v) in &valid {
        out.best = Some(out.best.map_or(v, |b: f64| b.min(v)));
        out.fewest = Some(out.fewest.map_or(hops, |f: usize| f.min(hops)));
    }
    if let Some(k) = out.fewest {
        out.best_of_fewest = valid
            .iter()
            .filter(|&&(h, _)| h == k)
            .map(|&(_, v)| v)
            .reduce(f64::min);
    }
    out
}

/// Checks that `plan`'s route is a valid route of `c` and returns its value
/// (from the goal back, each transition judged by the route's rest).
fn check_route(c: &Case, plan: &Plan) -> Result<f64, TestCaseError> {
    let arcs = weighted(c);
    let is_goal = |p: PlaceId| c.goals.contains(&p.index());
    prop_assert_eq!(plan.start.index(), c.start);
    prop_assert_eq!(plan.places.len(), plan.route.len() + 1);
    prop_assert_eq!(plan.places[0], plan.start);
    prop_assert!(is_goal(plan.goal()), "the route ends at a goal");
    prop_assert!(
        plan.places[..plan.route.len()].iter().all(|&p| !is_goal(p)),
        "and stops at the first"
    );
    for (k, t) in plan.route.iter().enumerate() {
        let (p, q, _, _) = arcs[t.index()];
        prop_assert_eq!((p, q), (plan.places[k].index(), plan.places[k + 1].index()));
    }
    let mut rest = 0.0;
    for t in plan.route.iter().rev() {
        let (_, _, w, l) = arcs[t.index()];
        match judge(w, rest, l) {
            Some(f) => rest = f,
            None => prop_assert!(false, "{t} is taken, but rejected given the route's rest"),
        }
    }
    let cost = plan.route.iter().fold(0.0, |s, t| s + arcs[t.index()].2);
    prop_assert_eq!(
        plan.cost.to_bits(),
        cost.to_bits(),
        "cost = Σ C(t) from the start"
    );
    Ok(rest)
}

fn goals(c: &Case) -> Vec<PlaceId> {
    c.goals.iter().map(|&g| PlaceId(g as u32)).collect()
}

/// The optimal-mode properties; returns the plan (`None`: no route).
fn check_optimal(c: &Case, planner: &Planner<'_>) -> Result<Option<Plan>, TestCaseError> {
    let d = bellman_ford(c);
    let start = PlaceId(c.start as u32);
    let result = planner.plan(start, &goals(c), PlanMode::Optimal);
    // The values of every place, whatever the start.
    let values = planner.label_setting(&goals(c)).unwrap();
    for (p, &dp) in d.iter().enumerate() {
        prop_assert_eq!(values.reached[p], dp.is_finite(), "reached({})", p);
        let expected = if dp.is_finite() { dp } else { 1.0 };
        prop_assert_eq!(
            values.alpha[p].to_bits(),
            expected.to_bits(),
            "α(p{}) = {}",
            p + 1,
            expected
        );
    }
    // The literal rounds to the fixed point: the same values, bit for bit.
    let literal = planner.propagate_literal(&goals(c), Stop::FixedPoint).unwrap();
    prop_assert_eq!(&literal.alpha, &values.alpha);
    prop_assert_eq!(&literal.f, &values.f);
    prop_assert_eq!(&literal.accepted, &values.accepted);
    match result {
        Err(PlanError::NoRoute { .. }) => {
            prop_assert!(
                d[c.start].is_infinite(),
                "no route, but Bellman–Ford found {}",
                d[c.start]
            );
            Ok(None)
        }
        Err(e) => Err(TestCaseError::fail(format!("unexpected error: {e}"))),
        Ok(p) => {
            prop_assert!(d[c.start].is_finite(), "a route where Bellman–Ford finds none");
            let value = check_route(c, &p)?;
            prop_assert_eq!(
                value.to_bits(),
                d[c.start].to_bits(),
                "the route's value is α(start)"
            );
            prop_assert_eq!(p.alpha[c.start].to_bits(), d[c.start].to_bits());
            prop_assert!(
                (p.cost - d[c.start]).abs() <= 1e-12,
                "cost {} vs shortest distance {}",
                p.cost,
                d[c.start]
            );
            Ok(Some(p))
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 1500, ..ProptestConfig::default() })]

    /// Small nets: optimal mode = Bellman–Ford = brute force; paper mode =
    /// the brute force's fewest transitions.
    #[test]
    fn small_nets_agree_with_bellman_ford_and_every_route(c in case(7)) {
        let net = build(&c);
        let planner = Planner::new(&net);
        let brute = brute_force(&c);
        let optimal = check_optimal(&c, &planner)?;
        prop_assert_eq!(optimal.is_some(), brute.best.is_some());
        if let (Some(p), Some(best)) = (&optimal, brute.best) {
            prop_assert_eq!(p.alpha[c.start].to_bits(), best.to_bits(), "α(start) = the least valid route");
        }
        let paper = planner.plan(PlaceId(c.start as u32), &goals(&c), PlanMode::Paper);
        match (paper, &optimal) {
            (Err(PlanError::NoRoute { .. }), None) => {}
            (Ok(p), Some(o)) => {
                let value = check_route(&c, &p)?;
                prop_assert_eq!(Some(p.iterations), brute.fewest, "rounds = the fewest transitions");
                prop_assert_eq!(
                    p.alpha[c.start].to_bits(),
                    brute.best_of_fewest.unwrap().to_bits(),
                    "α(start) = the least valid route with the fewest transitions"
                );
                prop_assert!(p.alpha[c.start] >= o.alpha[c.start]);
                prop_assert!(value <= p.alpha[c.start], "the route is worth at most α(start)");
                prop_assert!(p.cost >= o.cost - 1e-12, "paper {} cheaper than optimal {}", p.cost, o.cost);
            }
            (p, o) => prop_assert!(false, "paper {:?} vs optimal {:?}", p.map(|p| p.route), o.as_ref().map(|p| &p.route)),
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 400, ..ProptestConfig::default() })]

    /// Larger nets: optimal mode = Bellman–Ford; paper never cheaper.
    #[test]
    fn larger_nets_agree_with_bellman_ford(c in case(40)) {
        let net = build(&c);
        let planner = Planner::new(&net);
        let optimal = check_optimal(&c, &planner)?;
        let paper = planner.plan(PlaceId(c.start as u32), &goals(&c), PlanMode::Paper);
        match (paper, optimal) {
            (Err(PlanError::NoRoute { .. }), None) => {}
            (Ok(p), Some(o)) => {
                check_route(&c, &p)?;
                prop_assert!(p.alpha[c.start] >= o.alpha[c.start]);
                prop_assert!(p.cost >= o.cost - 1e-12, "paper {} cheaper than optimal {}", p.cost, o.cost);
                prop_assert_eq!(p.route.is_empty(), o.route.is_empty(), "empty only when the start is a goal");
            }
            (p, o) => prop_assert!(false, "paper {:?} vs optimal {:?}", p.map(|p| p.route), o.map(|p| p.route)),
        }
    }
}

// ---------------------------------------------------------------------------
// Hand-made nets.
// ---------------------------------------------------------------------------

/// Places p1…pn and transitions `(from, to, cost, λ)`, places from 1.
fn net(n: usize, arcs: &[(u32, u32, f64, f64)]) -> FuzzyPetriNet {
    let c = Case {
        n,
        arcs: arcs
            .iter()
            .map(|&(a, b, w, l)| (a as usize - 1, b as usize - 1, w, l))
            .collect(),
        goals: vec![0],
        start: 0,
    };
    build(&c)
}

fn route(net: &FuzzyPetriNet, from: u32, to: &[u32], mode: PlanMode) -> Result<Vec<u32>, PlanError> {
    let goals: Vec<PlaceId> = to.iter().map(|&g| PlaceId(g - 1)).collect();
    plan(net, PlaceId(from - 1), &goals, mode).map(|p| p.route.iter().map(|t| t.0).collect())
}

#[test]
fn paper_takes_a_near_goal_in_transitions_optimal_a_cheaper_one() {
    // p1 → p2 (goal) costs 10; p1 → p3 → p4 → p5 (goal) costs 1 + 1 + 1.
    let n = net(
        5,
        &[
            (1, 2, 10.0, 1.0),
            (1, 3, 1.0, 1.0),
            (3, 4, 1.0, 1.0),
            (4, 5, 1.0, 1.0),
        ],
    );
    assert_eq!(route(&n, 1, &[2, 5], PlanMode::Paper).unwrap(), [0]);
    assert_eq!(route(&n, 1, &[2, 5], PlanMode::Optimal).unwrap(), [1, 2, 3]);
    let p = plan(&n, PlaceId(0), &[PlaceId(1), PlaceId(4)], PlanMode::Optimal).unwrap();
    assert_eq!(p.goal(), PlaceId(4));
}

#[test]
fn paper_and_optimal_agree_when_the_fewest_transitions_are_cheapest() {
    // A ring with chords: the direct ways are also the cheap ones.
    let n = net(
        5,
        &[
            (1, 2, 1.0, 1.0),
            (2, 3, 1.0, 1.0),
            (3, 4, 1.0, 1.0),
            (4, 5, 1.0, 1.0),
            (5, 1, 1.0, 1.0),
            (1, 3, 1.5, 1.0),
            (3, 5, 1.5, 1.0),
            (2, 4, 3.0, 1.0),
        ],
    );
    for (from, to) in [(1, 5), (2, 5), (1, 4), (4, 3), (2, 1)] {
        let paper = plan(&n, PlaceId(from - 1), &[PlaceId(to - 1)], PlanMode::Paper).unwrap();
        let optimal = plan(&n, PlaceId(from - 1), &[PlaceId(to - 1)], PlanMode::Optimal).unwrap();
        assert_eq!(paper.route, optimal.route, "p{from} → p{to}");
        assert_eq!(paper.cost, optimal.cost);
    }
}

#[test]
fn a_threshold_at_the_value_accepts_just_below_rejects() {
    // p1 → p2 → p3 costs 2 + 2; p1 → p3 costs 5. Total 9.
    let mut n = net(3, &[(1, 2, 2.0, 1.0), (2, 3, 2.0, 1.0), (1, 3, 5.0, 1.0)]);
    assert_eq!(route(&n, 1, &[3], PlanMode::Optimal).unwrap(), [0, 1]);
    let f0 = plan(&n, PlaceId(0), &[PlaceId(2)], PlanMode::Optimal).unwrap().f[0];
    assert_eq!(f0, 2.0 / 9.0 + 2.0 / 9.0);
    n.set_lambda(TransitionId(0), f0).unwrap();
    assert_eq!(
        route(&n, 1, &[3], PlanMode::Optimal).unwrap(),
        [0, 1],
        "f = λ is accepted"
    );
    n.set_lambda(TransitionId(0), f64::from_bits(f0.to_bits() - 1))
        .unwrap();
    assert_eq!(
        route(&n, 1, &[3], PlanMode::Optimal).unwrap(),
        [2],
        "f > λ is rejected"
    );
    // Rejecting the other way too leaves no route; λ = 1 gives it back.
    n.set_lambda(TransitionId(2), 0.5).unwrap();
    assert!(matches!(
        route(&n, 1, &[3], PlanMode::Optimal),
        Err(PlanError::NoRoute { .. })
    ));
    n.set_lambda(TransitionId(2), 0.0).unwrap();
    n.set_lambda(TransitionId(0), 1.0).unwrap();
    assert_eq!(
        route(&n, 1, &[3], PlanMode::Paper).unwrap(),
        [0, 1],
        "λ = 0 always rejects"
    );
}

#[test]
fn the_same_transition_is_accepted_or_rejected_by_the_rest_of_the_route() {
    // t0: p1 → p2 (C = 1/10, λ = 0.25). From p2, p3 is near (t1, 1/10) and
    // p4 far (t2, 5/10); p1 → p4 directly costs 3/10 (t3).
    let n = net(
        4,
        &[
            (1, 2, 1.0, 0.25),
            (2, 3, 1.0, 1.0),
            (2, 4, 5.0, 1.0),
            (1, 4, 3.0, 1.0),
        ],
    );
    assert_eq!(
        route(&n, 1, &[3], PlanMode::Optimal).unwrap(),
        [0, 1],
        "f(t0) = 0.2 ≤ 0.25"
    );
    assert_eq!(
        route(&n, 1, &[4], PlanMode::Optimal).unwrap(),
        [3],
        "f(t0) = 0.6 > 0.25"
    );
    // Both goals: the near one, through t0.
    assert_eq!(route(&n, 1, &[3, 4], PlanMode::Optimal).unwrap(), [0, 1]);
}

#[test]
fn paper_mode_judges_thresholds_with_the_values_of_its_last_round() {
    // t0: p1 → p5 directly (C = 10/17). t1: p1 → p2 (1/17, λ = 0.2) and on
    // from p2 either t2: p2 → p5 (4/17: f(t1) = 5/17 > 0.2, rejected) or
    // t3, t4: p2 → p3 → p5 (1/17 each: f(t1) = 3/17 ≤ 0.2, accepted). The
    // paper rule stops after one round with t0; optimal finds t1 accepted.
    let n = net(
        5,
        &[
            (1, 5, 10.0, 1.0),
            (1, 2, 1.0, 0.2),
            (2, 5, 4.0, 1.0),
            (2, 3, 1.0, 1.0),
            (3, 5, 1.0, 1.0),
        ],
    );
    assert_eq!(route(&n, 1, &[5], PlanMode::Paper).unwrap(), [0]);
    assert_eq!(route(&n, 1, &[5], PlanMode::Optimal).unwrap(), [1, 3, 4]);
    // Without the direct way, the rounds go on until α(p2) is low enough
    // for t1: three rounds, the same route as optimal.
    let mut m = n.clone();
    m.set_lambda(TransitionId(0), 0.0).unwrap();
    let p = plan(&m, PlaceId(0), &[PlaceId(4)], PlanMode::Paper).unwrap();
    assert_eq!(p.route, [TransitionId(1), TransitionId(3), TransitionId(4)]);
    assert_eq!(p.iterations, 3);
}

#[test]
fn failures_lower_the_threshold_until_the_route_changes() {
    // The cheap route p1 → p2 → p3 (f(t0) = 4/20 = 0.2) against p1 → p3
    // (11/20). With the default factor ½, t0 is rejected once λ = ½^k < 0.2:
    // after k = 3 failures, as the ThresholdParams docs count.
    let mut n = net(
        3,
        &[
            (1, 2, 2.0, 1.0),
            (2, 3, 2.0, 1.0),
            (1, 3, 11.0, 1.0),
            (3, 1, 5.0, 1.0),
        ],
    );
    let params = ThresholdParams::default();
    let mut failures = 0;
    while route(&n, 1, &[3], PlanMode::Optimal).unwrap() == [0, 1] {
        n.record_attempt(TransitionId(0), false, &params).unwrap();
        failures += 1;
        assert!(failures < 10);
    }
    assert_eq!(failures, 3);
    assert_eq!(route(&n, 1, &[3], PlanMode::Optimal).unwrap(), [2]);
    // Successes do not raise it again.
    n.record_attempt(TransitionId(0), true, &params).unwrap();
    assert_eq!(route(&n, 1, &[3], PlanMode::Optimal).unwrap(), [2]);
    // But t0 is still taken towards p2, where its f is 2/20 ≤ 1/8.
    assert_eq!(route(&n, 1, &[2], PlanMode::Optimal).unwrap(), [0]);
}

#[test]
fn paper_walks_the_last_rounds_f_which_may_take_more_transitions_than_rounds() {
    // Found by the property test. Goal p3. Round 1: α(p2) = 15.6/T (t3),
    // α(p4) = 1/T. Round 2: α(p1) = f(t0) = 16.6/T: the start has a value
    // after 2 rounds, the fewest transitions. But at p2 the last round's f
    // already counts p2 → p4 → p3 (f(t1) = 2/T < f(t3)), so the walk takes
    // 3 transitions and costs 3/T: less than α(p1), here the cheapest route.
    let n = net(
        4,
        &[
            (1, 2, 1.0, 1.0),
            (4, 3, 1.0, 1.0),
            (2, 4, 1.0, 1.0),
            (2, 3, 15.6, 1.0),
        ],
    );
    let total = 18.6;
    let p = plan(&n, PlaceId(0), &[PlaceId(2)], PlanMode::Paper).unwrap();
    assert_eq!(p.iterations, 2);
    assert_eq!(p.route, [TransitionId(0), TransitionId(2), TransitionId(1)]);
    assert!((p.alpha[0] - 16.6 / total).abs() < 1e-15);
    assert!((p.cost - 3.0 / total).abs() < 1e-15);
    let o = plan(&n, PlaceId(0), &[PlaceId(2)], PlanMode::Optimal).unwrap();
    assert_eq!(o.route, p.route);
}
