//! `ExploreParams::forced_context`: stretches of forced hops that neither
//! read nor change the context places are remembered once for every count
//! those places hold. The graph must be the one generated without it —
//! the same markings in the same order, the same edges — for any set of
//! context places: on a net built for it (where it must also save work), on
//! arbitrary small nets with arbitrary context sets, and through a timeless
//! trap.

mod common;

use common::{Arbitrary, arbitrary};
use petri::{ArcKind, ExploreParams, Net, Params, PlaceId, ReachabilityGraph, Result};
use proptest::prelude::*;
use proptest::test_runner::RngSeed;

fn explore(net: &Net, context: Vec<PlaceId>) -> Result<ReachabilityGraph> {
    explore_up_to(net, context, 300)
}

fn explore_up_to(net: &Net, context: Vec<PlaceId>, max_states: usize) -> Result<ReachabilityGraph> {
    let g = net.instantiate(&Params::new())?;
    let params = ExploreParams {
        max_states,
        skip_forced: true,
        forced_context: context,
        ..ExploreParams::default()
    };
    ReachabilityGraph::explore(&g, &params)
}

/// The differences between two graphs (empty if they are the same).
fn differences(a: &ReachabilityGraph, b: &ReachabilityGraph) -> Vec<String> {
    let mut bad = Vec::new();
    if a.num_markings() != b.num_markings() {
        bad.push(format!(
            "{} markings against {}",
            a.num_markings(),
            b.num_markings()
        ));
        return bad;
    }
    for i in 0..a.num_markings() {
        let m = petri::MarkingId(i as u32);
        if a.marking(m) != b.marking(m) || a.is_vanishing(m) != b.is_vanishing(m) {
            bad.push(format!(
                "marking {i}: {:?} against {:?}",
                a.marking(m),
                b.marking(m)
            ));
        }
        let (ea, eb): (Vec<_>, Vec<_>) = (a.edges(m).collect(), b.edges(m).collect());
        if ea != eb {
            bad.push(format!("edges of {i}: {ea:?} against {eb:?}"));
        }
    }
    if a.place_bounds() != b.place_bounds() {
        bad.push(format!(
            "bounds {:?} against {:?}",
            a.place_bounds(),
            b.place_bounds()
        ));
    }
    bad
}

/// `processes` independent on/off processes (timed switches) and a cycle
/// of control flow: a timed start, twelve forced hops that never look at
/// the processes, one read of the first process (a forced hop that depends
/// on it), then six more forced hops back to the start. Returns the net
/// and the processes' places.
fn environment_and_flow(processes: usize) -> (Net, Vec<PlaceId>) {
    let mut n = Net::new("environment and flow");
    let mut env = Vec::new();
    for k in 0..processes {
        let on = n.add_place(format!("e{k}.on"), 1u32);
        let off = n.add_place(format!("e{k}.off"), 0u32);
        let t = n.add_timed(format!("e{k}.to_off"), 1.0 + k as f64);
        n.input(on, t);
        n.output(t, off);
        let t = n.add_timed(format!("e{k}.to_on"), 2.0);
        n.input(off, t);
        n.output(t, on);
        env.extend([on, off]);
    }
    let idle = n.add_place("idle", 1u32);
    let mut at = n.add_place("s0", 0u32);
    let go = n.add_timed("go", 3.0);
    n.input(idle, go);
    n.output(go, at);
    for k in 1..=12 {
        let next = n.add_place(format!("s{k}"), 0u32);
        let t = n.add_immediate(format!("hop{k}"), 1.0, 1);
        n.input(at, t);
        n.output(t, next);
        at = next;
    }
    let after = n.add_place("read", 0u32);
    for (k, tested) in [(0, env[0]), (1, env[1])] {
        let t = n.add_immediate(format!("read{k}"), 1.0, 1);
        n.input(at, t);
        n.input(tested, t);
        n.output(t, tested);
        n.output(t, after);
    }
    at = after;
    for k in 1..=6 {
        let next = if k == 6 {
            idle
        } else {
            n.add_place(format!("r{k}"), 0u32)
        };
        let t = n.add_immediate(format!("back{k}"), 1.0, 1);
        n.input(at, t);
        n.output(t, next);
        at = next;
    }
    (n, env)
}

#[test]
fn stretches_free_of_the_context_are_followed_once_and_the_graph_is_unchanged() {
    let (net, env) = environment_and_flow(3);
    let without = explore(&net, Vec::new()).unwrap();
    let with = explore(&net, env).unwrap();
    assert_eq!(differences(&without, &with), Vec::<String>::new());
    // 8 states of the processes × (idle, 13 forced markings after `go`, 6
    // after the read).
    assert_eq!(without.num_tangible(), 8);
    let (a, b) = (without.stats().forced_evaluated, with.stats().forced_evaluated);
    // Without: 19 forced markings per state of the processes, and the 7
    // tangible ones other than the initial, each evaluated when first reached.
    assert_eq!(a, 8 * 19 + 7);
    // The twelve hops before the read and the six after it are evaluated for
    // the first state of the processes only; the read (and the marking
    // before it, where it is enabled) for every one.
    assert!(b < a / 3, "{b} evaluations with the context, {a} without");
}

/// With a context, past 2,048 stored markings a round's chunks run in
/// parallel (past 32,768 without), each learning stretches of its own: 16
/// processes (65,536 states), on one thread and on two, give the graph
/// generated without the context.
#[test]
fn stretches_learnt_in_parallel_chunks_give_the_same_graph() {
    let (net, env) = environment_and_flow(16);
    let on = |threads: usize, context: Vec<PlaceId>| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| explore_up_to(&net, context, 100_000).unwrap())
    };
    let without = on(1, Vec::new());
    assert_eq!(without.num_tangible(), 1 << 16);
    for threads in [1, 2] {
        let with = on(threads, env.clone());
        let bad = differences(&without, &with);
        assert!(
            bad.is_empty(),
            "{threads} threads: {:?}",
            &bad[..bad.len().min(3)]
        );
        assert!(with.stats().forced_evaluated < without.stats().forced_evaluated / 3);
    }
}

#[test]
fn places_the_net_does_not_have_are_left_out_of_the_context() {
    let (net, mut env) = environment_and_flow(3);
    let without = explore(&net, Vec::new()).unwrap();
    let with = explore(&net, env.clone()).unwrap();
    env.push(PlaceId(10_000));
    let with_unknown = explore(&net, env).unwrap();
    assert_eq!(differences(&without, &with_unknown), Vec::<String>::new());
    assert_eq!(
        with_unknown.stats().forced_evaluated,
        with.stats().forced_evaluated
    );
}

#[test]
fn a_context_that_the_flow_changes_is_never_skipped() {
    // The read consumes and returns the tested place: with the flow's own
    // places as context too (they change at every hop), nothing is
    // remembered without them and the graph is the same.
    let (net, _) = environment_and_flow(3);
    let every: Vec<PlaceId> = (0..net.places.len() as u32).map(PlaceId).collect();
    let without = explore(&net, Vec::new()).unwrap();
    let with = explore(&net, every).unwrap();
    assert_eq!(differences(&without, &with), Vec::<String>::new());
    assert_eq!(with.stats().forced_evaluated, without.stats().forced_evaluated);
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 256,
        rng_seed: RngSeed::Fixed(0x0f0c_ed00),
        failure_persistence: None,
        ..ProptestConfig::default()
    })]

    /// Any context set on arbitrary nets (inhibitor arcs, priorities,
    /// multiplicities, timeless traps, unbounded nets): the same graph, or
    /// the same error.
    #[test]
    fn any_context_leaves_the_graph_of_an_arbitrary_net_unchanged(a in arbitrary(), mask in any::<u8>()) {
        let net = a.net();
        let context: Vec<PlaceId> = (0..a.places as u32).filter(|p| mask >> p & 1 == 1).map(PlaceId).collect();
        match (explore(&net, Vec::new()), explore(&net, context)) {
            (Ok(x), Ok(y)) => {
                let bad = differences(&x, &y);
                prop_assert!(bad.is_empty(), "{:#?}", bad);
            }
            (Err(x), Err(y)) => prop_assert_eq!(x.to_string(), y.to_string()),
            (x, y) => prop_assert!(false, "{:?} against {:?}", x.map(|g| g.num_markings()), y.map(|g| g.num_markings())),
        }
    }
}

/// `a`'s net with two on/off processes (timed switches) that its immediate
/// transitions test: `tests[t]` 1–4 gives transition `t` a test arc on one
/// of the four places of the processes (0: none). Returns the net and the
/// processes' places.
fn with_environment(a: &Arbitrary, tests: &[u8]) -> (Net, Vec<PlaceId>) {
    let mut n = a.net();
    let mut env = Vec::new();
    for k in 0..2 {
        let on = n.add_place(format!("e{k}.on"), 1u32);
        let off = n.add_place(format!("e{k}.off"), 0u32);
        for (from, to, rate) in [(on, off, 0.5 + k as f64), (off, on, 1.5)] {
            let t = n.add_timed(format!("e{k}.switch{}", from.0), rate);
            n.input(from, t);
            n.output(t, to);
        }
        env.extend([on, off]);
    }
    for (t, &(immediate, ..)) in a.transitions.iter().enumerate() {
        let k = tests[t % tests.len()];
        if immediate && k > 0 {
            let id = petri::TransitionId(t as u32);
            let p = env[(k - 1) as usize];
            n.input(p, id);
            n.output(id, p);
        }
    }
    (n, env)
}

/// Arbitrary nets whose immediate transitions test independent processes,
/// the processes as context: the same graph each time, and work saved in
/// many of them (the check has something to check).
#[test]
fn processes_tested_by_arbitrary_nets_as_context_leave_their_graphs_unchanged() {
    use proptest::strategy::ValueTree;
    let mut runner = proptest::test_runner::TestRunner::deterministic();
    let strategy = (arbitrary(), proptest::collection::vec(0u8..=4, 7));
    let (mut same, mut saved) = (0, 0);
    for _ in 0..300 {
        let (a, tests) = strategy.new_tree(&mut runner).unwrap().current();
        let (net, env) = with_environment(&a, &tests);
        match (explore(&net, Vec::new()), explore(&net, env)) {
            (Ok(x), Ok(y)) => {
                let bad = differences(&x, &y);
                assert!(bad.is_empty(), "{a:#?} {tests:?}: {bad:#?}");
                same += 1;
                if y.stats().forced_evaluated < x.stats().forced_evaluated {
                    saved += 1;
                }
            }
            (Err(x), Err(y)) => assert_eq!(x.to_string(), y.to_string(), "{a:#?} {tests:?}"),
            (x, y) => panic!(
                "{a:#?} {tests:?}: {:?} against {:?}",
                x.map(|g| g.num_markings()),
                y.map(|g| g.num_markings())
            ),
        }
    }
    assert!(
        same >= 100 && saved >= 20,
        "{same} graphs compared, work saved in {saved}"
    );
}

/// A net (found by the arbitrary-net check below) whose immediate
/// transition `grow` adds a token to three places at every hop while a
/// process is on: a timeless loop, each run cut at the hop limit and each
/// cut marking stored and followed again, so three counts grow by
/// thousands per marking until their fields fill the word. Generation must
/// end at the state limit: it once took turns widening one field and
/// fitting another back forever, the counts of followed hops not being
/// among those a relayout fits to.
#[test]
fn growing_counts_in_a_timeless_loop_end_at_the_state_limit() {
    let mut n = Net::new("growing timeless loop");
    let p: Vec<PlaceId> = [1u32, 2, 0, 0, 1, 0]
        .iter()
        .enumerate()
        .map(|(k, &m)| n.add_place(format!("p{k}"), m))
        .collect();
    let names = ["t0", "t1", "t4", "t5", "t6", "off", "on"];
    let timed: Vec<_> = names.iter().map(|name| n.add_timed(*name, 1.0)).collect();
    let grow = n.add_immediate("grow", 1.0, 2);
    type Arcs<'a> = &'a [(usize, u32)];
    let mut arc = |t, ins: Arcs, outs: Arcs, inhibitors: Arcs| {
        let kinds = [ArcKind::Input, ArcKind::Output, ArcKind::Inhibitor];
        for (kind, list) in kinds.into_iter().zip([ins, outs, inhibitors]) {
            for &(q, m) in list {
                n.add_arc(kind, p[q], t, m);
            }
        }
    };
    arc(timed[0], &[(0, 2)], &[(1, 1)], &[(2, 2), (3, 1)]);
    arc(timed[1], &[(1, 1), (3, 1)], &[(1, 1), (2, 1)], &[(2, 2)]);
    arc(timed[2], &[(1, 3), (3, 1)], &[(0, 1)], &[]);
    arc(timed[3], &[(2, 1)], &[(1, 1)], &[]);
    arc(timed[4], &[(0, 1)], &[(3, 3)], &[]);
    arc(timed[5], &[(4, 1)], &[(5, 1)], &[]);
    arc(timed[6], &[(5, 1)], &[(4, 1)], &[]);
    arc(
        grow,
        &[(0, 1), (2, 1), (4, 1)],
        &[(0, 2), (2, 2), (3, 1), (4, 1)],
        &[(1, 2)],
    );
    match explore(&n, Vec::new()) {
        Err(petri::Error::StateLimit { .. }) => {}
        other => panic!(
            "expected the state limit, got {:?}",
            other.map(|g| g.num_markings())
        ),
    }
}
