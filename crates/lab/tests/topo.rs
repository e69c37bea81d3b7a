//! The topological layer in the simulator: an exploration of the shipped
//! office, place recognition judged against the true poses, routes by the
//! map and by wall following, and the suite's campaigns.

use ::topo::{NavigateParams, TopoParams};
use lab::runs::topo::{self, ExploreSpec, RouteMethod, RouteOutcome, RouteSpec};
use lab::suite::Suite;
use lab::suites::topo::{self as suite, ROUTES, TopoSuite};
use sim::TraceParams;

fn spec(seed: u64, time_s: f64) -> ExploreSpec {
    ExploreSpec {
        params: TopoParams::default(),
        start: suite::WORLDS[0].2,
        time_s,
        seed,
        trace: TraceParams::default(),
        robot: topo::robot(),
    }
}

#[test]
fn exploring_the_office_finds_places_and_every_stop_is_judged_once() {
    let world = suite::office().unwrap();
    let e = topo::explore(&world, &spec(3, 240.0)).unwrap();
    assert!(e.map.num_places() >= 4, "{} places", e.map.num_places());
    assert!(e.map.num_transitions() >= 3);
    assert_eq!(e.truth.len(), e.map.num_places());
    let r = e.recognition;
    // A stop recognised as a known place is a TP or an FP; a stop taken
    // for a new place is a TN, or an FN when it truly was a known place.
    let new = e.visits.iter().filter(|(v, _)| v.new).count() as u32;
    let known = e.visits.len() as u32 - new;
    assert_eq!(r.true_positives + r.false_positives, known);
    assert!(r.true_negatives <= new && new - r.true_negatives <= r.false_negatives);
    assert!(r.true_negatives >= 1);
    // The map's size only grows, one entry per stop.
    assert_eq!(e.growth.len(), e.visits.len());
    assert!(
        e.growth
            .windows(2)
            .all(|w| w[0].places <= w[1].places && w[0].time_s <= w[1].time_s)
    );
    // Same seed, same map.
    let again = topo::explore(&world, &spec(3, 240.0)).unwrap();
    assert_eq!(again.map.to_json(), e.map.to_json());
    assert!(topo::explore(&world, &spec(3, f64::NAN)).is_err());
}

#[test]
fn routes_are_judged_against_where_the_goal_truly_is() {
    let world = suite::office().unwrap();
    let e = topo::explore(&world, &spec(5, 300.0)).unwrap();
    let pairs = topo::routable_pairs(&e.map);
    assert!(!pairs.is_empty());
    let (from, to) = pairs[0];
    let goal = e.truth[to.0 as usize].position();
    for method in [
        RouteMethod::Map(NavigateParams::default()),
        RouteMethod::WallFollowing(TopoParams::default().strategy),
    ] {
        let run = topo::route(
            &world,
            &RouteSpec {
                map: &e.map,
                truth: &e.truth,
                from,
                to,
                method: method.clone(),
                time_limit_s: 200.0,
                seed: 9,
                trace: TraceParams::poses(),
                robot: topo::robot(),
            },
        )
        .unwrap();
        let end = run.result.final_pose;
        let d = end.position().dist(goal);
        assert!((d - run.final_distance_m).abs() < 1e-9);
        match run.outcome {
            RouteOutcome::Reached => assert!(d <= topo::ARRIVE_M, "{method:?}: reached at {d} m"),
            RouteOutcome::WrongPlace => assert!(d > topo::ARRIVE_M),
            RouteOutcome::TimeLimit => assert!(run.result.time_s >= 200.0 - 1e-9),
            RouteOutcome::GaveUp => {}
        }
        if matches!(method, RouteMethod::Map(_)) {
            assert!(run.plan.is_some() && run.map.is_some() && run.stats.is_some());
            // Every leg that ended at a place, judged against the truth.
            let stats = run.stats.unwrap();
            assert_eq!(run.legs.len() as u32, stats.legs - stats.failed_legs);
            assert_eq!(
                run.legs.iter().filter(|l| l.as_planned).count() as u32,
                stats.as_planned
            );
            for l in &run.legs {
                if l.as_planned {
                    assert_eq!(l.planned_to, Some(l.arrived));
                }
                if let (Some(q), Some(at)) = (l.planned_to, l.truly_at_planned) {
                    assert_eq!(at, topo::same_place(e.truth[q.0 as usize], l.end));
                }
            }
        } else {
            assert!(run.legs.is_empty());
        }
    }
    // A place the map does not have is an error.
    let bad = RouteSpec {
        map: &e.map,
        truth: &e.truth,
        from,
        to: ::topo::PlaceId(e.map.num_places() as u32),
        method: RouteMethod::Map(NavigateParams::default()),
        time_limit_s: 10.0,
        seed: 1,
        trace: TraceParams::default(),
        robot: topo::robot(),
    };
    assert!(topo::route(&world, &bad).is_err());
}

#[test]
fn a_campaign_is_one_exploration_then_each_route_by_both_methods() {
    let s = TopoSuite::new(2).unwrap();
    let campaigns = s.campaigns();
    assert_eq!(campaigns.len(), 2 * suite::WORLDS.len());
    let mut keys = std::collections::BTreeSet::new();
    for c in &campaigns {
        assert_eq!(c.jobs.len() as u32, 1 + 2 * ROUTES);
        assert!(c.jobs[0].scenario.ends_with("/explore"));
        // Route k by both methods: same seed (common random numbers).
        for pair in c.jobs[1..].chunks(2) {
            assert_eq!(pair[0].run, pair[1].run);
            assert_eq!(pair[0].seed, pair[1].seed);
            assert_ne!(pair[0].scenario, pair[1].scenario);
        }
        for j in &c.jobs {
            assert!(keys.insert(j.key()), "duplicate key {}", j.key());
        }
    }
    assert!(TopoSuite::new(0).is_err());
}
