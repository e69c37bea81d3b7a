//! The shipped suites end to end: common random numbers between scenarios
//! that differ only in the controller, and the dead-lock experiment's
//! outcome (docs/activity-trace.md) on its first runs.

use lab::scenario_suite::ScenarioSuite;
use lab::suite::{Suite, SuiteArgs};
use lab::suites::shared::DEADLOCKS;

fn runs(n: u32) -> SuiteArgs {
    SuiteArgs {
        runs: Some(n),
        files: Vec::new(),
    }
}

#[test]
fn trace_layer_without_detections_is_the_bare_voting_run() {
    let suite: ScenarioSuite = lab::suites::voting::suite(&runs(8)).unwrap();
    let mut compared = 0;
    for field in ["field01", "field10", "field12"] {
        for run in 0..8 {
            let a = suite.run_once(&format!("e4/{field}"), run).unwrap();
            let b = suite.run_once(&format!("e5/{field}"), run).unwrap();
            assert_eq!(a.start, b.start, "{field}#{run}: same start");
            if b.metric(DEADLOCKS) == Some(0.0) {
                assert_eq!(
                    a, b,
                    "{field}#{run}: no dead-lock detected, so the same run tick for tick"
                );
                compared += 1;
            }
        }
    }
    assert!(compared >= 8, "only {compared} runs without detections");
}

#[test]
fn runs_differ_by_index_and_not_by_scenario() {
    let suite = lab::suites::deadlock::suite(&runs(4)).unwrap();
    let jobs: Vec<_> = suite.campaigns().into_iter().flat_map(|c| c.jobs).collect();
    let seed_of = |name: &str, run: u32| {
        jobs.iter()
            .find(|j| j.scenario == name && j.run == run)
            .unwrap()
            .seed
    };
    assert_eq!(seed_of("priority", 3), seed_of("voting_trace", 3));
    assert_eq!(seed_of("priority", 3), suite.seeds(3).sim);
    assert_ne!(suite.seeds(3), suite.seeds(2));
    assert_ne!(suite.seeds(3).sim, suite.seeds(3).variation);
}

#[test]
fn priority_recovery_escapes_the_traps_that_hold_the_plain_controller() {
    let suite = lab::suites::deadlock::suite(&runs(24)).unwrap();
    let successes = |name: &str| {
        (0..24)
            .map(|run| suite.run_once(name, run).unwrap())
            .map(|r| {
                assert_eq!(r.collisions, 0, "{name}: the ring robot touches nothing");
                assert!(r.trap.is_some());
                u32::from(r.success)
            })
            .sum::<u32>()
    };
    let plain = successes("priority");
    let recovering = successes("priority_recovery");
    assert!(plain <= 8, "plain priority got out of {plain} of 24 U traps");
    assert!(recovering >= 22, "recovery got out of only {recovering} of 24");
}
