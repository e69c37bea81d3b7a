//! Stopping state-space generation, compilation and solves from another
//! thread (`petri::Interrupt`).

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use petri::{CompiledGspn, Error, ExploreParams, Interrupt, Params, ReachabilityGraph, SolveParams};

fn kanban(n: u32) -> petri::Gspn {
    petri::families::kanban(n).instantiate(&Params::new()).unwrap()
}

#[test]
fn a_raised_flag_stops_each_stage_and_a_lowered_one_changes_nothing() {
    let gspn = kanban(2);
    let explore = ExploreParams::default();
    let (up, down) = (AtomicBool::new(true), AtomicBool::new(false));
    let cancelled = |r: Result<(), Error>, during: &str| match r {
        Err(Error::Cancelled { during: d }) => assert_eq!(d, during),
        other => panic!("expected Cancelled while {during}, got {other:?}"),
    };
    cancelled(
        ReachabilityGraph::explore_interruptible(&gspn, &explore, Interrupt::new(&up)).map(|_| ()),
        "generating the reachability graph",
    );
    let rg = ReachabilityGraph::explore_interruptible(&gspn, &explore, Interrupt::new(&down)).unwrap();
    cancelled(
        CompiledGspn::from_graph_interruptible(gspn.clone(), rg.clone(), Interrupt::new(&up)).map(|_| ()),
        "compiling the CTMC",
    );
    let compiled = CompiledGspn::from_graph_interruptible(gspn.clone(), rg, Interrupt::new(&down)).unwrap();
    let rates = gspn.rates(&Params::new(), None).unwrap();
    let params = SolveParams::default();
    cancelled(
        compiled
            .solve_rates_interruptible(&rates, &params, Interrupt::new(&up))
            .map(|_| ()),
        "solving the steady state",
    );
    let a = compiled
        .solve_rates_interruptible(&rates, &params, Interrupt::new(&down))
        .unwrap();
    let b = compiled.solve_rates(&rates, &params).unwrap();
    assert_eq!(a.pi, b.pi);
    assert_eq!(
        Error::Cancelled { during: "x" }.to_string(),
        "stopped on request while x"
    );
}

#[test]
fn a_flag_raised_midway_stops_a_long_generation_soon() {
    // Kanban N = 5: 2.5 million markings, seconds to generate.
    let gspn = kanban(5);
    let stop = AtomicBool::new(false);
    std::thread::scope(|s| {
        s.spawn(|| {
            std::thread::sleep(Duration::from_millis(200));
            stop.store(true, Ordering::Relaxed);
        });
        let started = Instant::now();
        let r =
            ReachabilityGraph::explore_interruptible(&gspn, &ExploreParams::default(), Interrupt::new(&stop));
        // Stopped at a round's start, long before the end (an Ok would mean
        // the whole graph was generated).
        assert!(
            matches!(r, Err(Error::Cancelled { .. })),
            "{:?}",
            r.map(|g| g.num_markings())
        );
        assert!(started.elapsed() < Duration::from_secs(3));
    });
}

#[test]
fn progress_follows_the_stages_and_changes_no_result() {
    use petri::{Progress, Stage};
    let gspn = kanban(3);
    let explore = ExploreParams::default();
    let progress = Progress::new();
    assert_eq!(progress.snapshot().stage, Stage::Idle);
    let observed = Interrupt::NEVER.with_progress(&progress);
    let rg = ReachabilityGraph::explore_interruptible(&gspn, &explore, observed).unwrap();
    let seen = progress.snapshot();
    assert_eq!(seen.stage, Stage::Generating);
    assert_eq!((seen.markings, seen.edges), (rg.num_markings(), rg.num_edges()));
    let compiled = CompiledGspn::from_graph_interruptible(gspn.clone(), rg, observed).unwrap();
    assert_eq!(progress.snapshot().stage, Stage::Compiling);
    let rates = gspn.rates(&Params::new(), None).unwrap();
    let params = SolveParams::default();
    let a = compiled
        .solve_rates_interruptible(&rates, &params, observed)
        .unwrap();
    let seen = progress.snapshot();
    assert_eq!(seen.stage, Stage::Solving);
    assert_eq!(a.info.method, "bicgstab");
    assert_eq!(seen.iteration, a.info.iterations);
    assert!(seen.residual.is_finite() && seen.residual > 0.0);
    let b = compiled.solve_rates(&rates, &params).unwrap();
    assert_eq!(a.pi, b.pi);
}
