//! The shipped suites end to end: common random numbers between scenarios
//! that differ only in the controller, and the dead-lock experiment's
//! outcome (activity-trace.md) on its first runs.

use lab::suite::Suite;

#[test]
fn trace_layer_without_detections_is_the_bare_voting_run() {
    let suite = Suite::voting(Some(8)).unwrap();
    let mut compared = 0;
    for field in ["field01", "field10", "field12"] {
        let bare = suite.scenario(&format!("e4/{field}")).unwrap();
        let traced = suite.scenario(&format!("e5/{field}")).unwrap();
        for run in 0..8 {
            let a = bare.run(suite.seeds(run)).unwrap();
            let b = traced.run(suite.seeds(run)).unwrap();
            assert_eq!(a.start, b.start, "{field}#{run}: same start");
            if b.deadlocks == 0 {
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
    let suite = Suite::deadlock(Some(4)).unwrap();
    let jobs = suite.jobs();
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
    let suite = Suite::deadlock(Some(24)).unwrap();
    let successes = |name: &str| {
        let prep = suite.scenario(name).unwrap();
        (0..24)
            .map(|run| prep.run(suite.seeds(run)).unwrap())
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
