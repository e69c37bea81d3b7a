//! The guide robot's policies in the museum, from their events: the rule
//! hands the robot to contour tracking at every Warning; the source's
//! supervisor decides only at the start and on returns from Warning to
//! Success, with λ7, λ8 from the remaining reference trajectories (both on
//! the source's localizer, whose Warnings people raise); the crediting
//! supervisor decides at the start, at every Warning and at every return.

use guide::supervisor::Behaviour;
use guide::supervisor::credit::CreditSupervisor;
use guide::supervisor::credit_learning::CreditModel;
use guide::supervisor::log::{CalibrationRun, Entry};
use guide::supervisor::reference::Reference;
use guide::supervisor::{Rates, Supervisor};
use guide::{CreditPlan, Policy, SupervisorPlan};
use lab::runs::mission::{self, LegSpec, MissionSetup, PeoplePlan};
use lab::suites::tourguide::{
    EXHIBITS, GOAL, LOST_AFTER_S, START, disturbances, museum, museum_with_patches, source_guide,
};
use robot::{Event, Vec2};
use sim::TraceParams;

/// The museum with the source's localizer (people raise its Warnings).
fn setup(people: usize) -> MissionSetup {
    let mut s = MissionSetup::new(museum().unwrap(), 300.0);
    s.guide = source_guide();
    s.people = Some(PeoplePlan {
        count: people,
        anchors: EXHIBITS.to_vec(),
        spread_m: 2.5,
        keep_clear_m: 1.0,
    });
    s
}

/// The museum mission from the start to the goal.
fn spec(policy: Policy, seed: u64) -> LegSpec<'static> {
    LegSpec {
        from: "start",
        to: "goal",
        start: START,
        believed: START,
        goal: GOAL,
        policy,
        seed,
        trace: TraceParams::default(),
    }
}

fn run(policy: Policy, seed: u64) -> Vec<Event> {
    let leg = mission::run_leg(&setup(40), &spec(policy, seed)).unwrap();
    leg.trace.events
}

fn at(events: &[Event], kind: &str) -> Vec<f64> {
    events
        .iter()
        .filter(|e| e.kind == kind)
        .map(|e| e.time_s)
        .collect()
}

/// The switch at time `t`, its target.
fn switch_to(events: &[Event], t: f64) -> Option<String> {
    events
        .iter()
        .find(|e| e.kind == "switch" && e.time_s == t)
        .and_then(|e| e.text("to").map(str::to_string))
}

#[test]
fn the_rule_hands_over_at_every_warning_and_back_at_every_success() {
    let events = run(Policy::Rule, 5);
    let warnings = at(&events, "warning");
    assert!(
        warnings.len() >= 2,
        "a crowded hall makes the localizer warn: {warnings:?}"
    );
    for &t in &warnings {
        assert_eq!(
            switch_to(&events, t).as_deref(),
            Some("contour"),
            "warning at {t}"
        );
    }
    for t in at(&events, "success") {
        assert_eq!(
            switch_to(&events, t).as_deref(),
            Some("automove"),
            "success at {t}"
        );
    }
    // No switch happens at any other moment.
    let moments: Vec<f64> = at(&events, "warning")
        .into_iter()
        .chain(at(&events, "success"))
        .collect();
    assert!(at(&events, "switch").iter().all(|t| moments.contains(t)));
}

fn plan() -> SupervisorPlan {
    let line = |len: f64| vec![START.position(), Vec2::new(START.x_m, START.y_m + len)];
    let mut rates = Rates::initial();
    rates.set(3, 0.05);
    rates.set(4, 0.1);
    rates.set(7, 1.0 / 60.0);
    rates.set(8, 1.0 / 130.0);
    SupervisorPlan {
        supervisor: Supervisor::new().unwrap(),
        rates,
        automove: Reference {
            mean_time_s: 60.0,
            mean_speed_mps: 0.4,
            trajectory: line(24.0),
        },
        contour: Reference {
            mean_time_s: 130.0,
            mean_speed_mps: 0.3,
            trajectory: line(40.0),
        },
    }
}

#[test]
fn the_source_supervisor_decides_at_the_start_and_on_returns_to_success_only() {
    let p = plan();
    let events = run(Policy::SupervisorSource(Box::new(p.clone())), 5);
    let decisions: Vec<&Event> = events.iter().filter(|e| e.kind == "decision").collect();
    assert!(decisions.len() >= 2, "{} decisions", decisions.len());
    assert_eq!(decisions[0].time_s, 0.0);
    assert_eq!(decisions[0].text("reason"), Some("start"));
    // At the start: the learnt λ7, λ8.
    let start = p.supervisor.decide(&p.rates).unwrap();
    assert_eq!(decisions[0].number("f_auto"), Some(start.f_auto));
    let successes = at(&events, "success");
    for d in &decisions[1..] {
        assert_eq!(d.text("reason"), Some("recovered"));
        assert!(
            successes.contains(&d.time_s),
            "a decision at {} without a return to Success",
            d.time_s
        );
        // λ7, λ8 from the remaining part of each reference, from where the
        // robot believed it was.
        let here = d.position.unwrap();
        let mut r = p.rates;
        r.set(7, p.automove.rate_from(here));
        r.set(8, p.contour.rate_from(here));
        let again = p.supervisor.decide(&r).unwrap();
        assert_eq!(d.number("lambda3"), Some(0.05));
        assert!((d.number("f_auto").unwrap() - again.f_auto).abs() < 1e-15);
        assert!((d.number("f_cont").unwrap() - again.f_cont).abs() < 1e-15);
    }
    assert_eq!(
        decisions.len() - 1,
        successes.len(),
        "one decision per return to Success"
    );
    // The rule still holds under the supervisor.
    for t in at(&events, "warning") {
        assert!(
            switch_to(&events, t).as_deref() == Some("contour")
                || events
                    .iter()
                    .rfind(|e| e.kind == "switch" && e.time_s < t)
                    .and_then(|e| e.text("to"))
                    == Some("contour"),
            "warning at {t}: contour tracking drives"
        );
    }
}

/// A mission on a prepared map (`MissionSetup::prepare`, the suite's way)
/// is the mission on the raw map, bit for bit: poses, estimates, events;
/// and a prepared setup whose parameters changed since prepares its own.
#[test]
fn a_prepared_map_runs_the_same_mission() {
    let spec = |policy| spec(policy, 11);
    let raw = setup(25);
    let mut prepared = setup(25);
    prepared.prepare().unwrap();
    for policy in [Policy::Rule, Policy::Fixed(guide::supervisor::Behaviour::Contour)] {
        let a = mission::run_leg(&raw, &spec(policy.clone())).unwrap();
        let b = mission::run_leg(&prepared, &spec(policy)).unwrap();
        assert_eq!(a.trace.poses, b.trace.poses);
        assert_eq!(a.trace.estimates, b.trace.estimates);
        assert_eq!(a.trace.events, b.trace.events);
        assert_eq!(a.result.time_s, b.result.time_s);
    }
    // Other parameters after preparing: the leg does not use the stale map.
    let mut changed = prepared.clone();
    changed.guide.automove.local.cost.inscribed_radius_m += 0.05;
    let mut fresh = raw.clone();
    fresh.guide = changed.guide.clone();
    let a = mission::run_leg(
        &fresh,
        &spec(Policy::Fixed(guide::supervisor::Behaviour::AutoMove)),
    )
    .unwrap();
    let b = mission::run_leg(
        &changed,
        &spec(Policy::Fixed(guide::supervisor::Behaviour::AutoMove)),
    )
    .unwrap();
    assert_eq!(a.trace.poses, b.trace.poses);
}

fn calibration(b: Behaviour, t: f64, len: f64) -> Entry {
    Entry::Calibration(CalibrationRun {
        behaviour: b,
        success: true,
        duration_s: t,
        path_m: len,
        trajectory: vec![[START.x_m, START.y_m], [START.x_m, START.y_m + len]],
        outcome: "goal".into(),
        segments: Vec::new(),
        route: None,
    })
}

#[test]
fn the_crediting_supervisor_decides_at_the_start_at_every_warning_and_every_return() {
    // The packed museum with its pushes, slips and groups: pushes make the
    // localizer (the contradiction rule) warn.
    let (world, patches) = museum_with_patches().unwrap();
    let mut s = MissionSetup::new(world, 300.0);
    s.people = Some(PeoplePlan {
        count: 60,
        anchors: EXHIBITS.to_vec(),
        spread_m: 2.5,
        keep_clear_m: 1.0,
    });
    s.disturbances = disturbances(60, &patches);
    s.lost_after_s = LOST_AFTER_S;
    s.prepare().unwrap();
    let log = vec![
        calibration(Behaviour::AutoMove, 60.0, 24.0),
        calibration(Behaviour::Contour, 130.0, 40.0),
    ];
    let plan = CreditPlan {
        planner: std::sync::Arc::new(CreditSupervisor::new().unwrap()),
        model: CreditModel::learn(&log).unwrap(),
        route: String::new(),
    };
    // The first seed whose mission has a Warning.
    let (events, segments) = (1..=40)
        .map(|seed| {
            let leg = mission::run_leg(&s, &spec(Policy::Supervisor(Box::new(plan.clone())), seed)).unwrap();
            (leg.trace.events, leg.summary.segments)
        })
        .find(|(e, _)| e.iter().any(|e| e.kind == "warning"))
        .expect("a packed museum with pushes makes the localizer warn");
    let decisions: Vec<&Event> = events.iter().filter(|e| e.kind == "decision").collect();
    assert_eq!(decisions[0].time_s, 0.0);
    assert_eq!(decisions[0].text("reason"), Some("start"));
    for (kind, reason) in [("warning", "warning"), ("success", "recovered")] {
        for t in at(&events, kind) {
            let d = decisions
                .iter()
                .find(|d| d.time_s == t)
                .unwrap_or_else(|| panic!("no decision at the {kind} at {t}"));
            assert_eq!(d.text("reason"), Some(reason));
            assert!(d.text("context").is_some());
            assert!(d.number("lambda12").is_some_and(|x| x > 0.0));
            assert!(d.number("lambda4_cont").is_some_and(|x| x > 0.0));
            let marking = d.text("marking").unwrap_or_default();
            assert!(
                marking.starts_with("P0 ") && marking.contains(if kind == "warning" { "P6" } else { "P5" })
            );
        }
    }
    assert_eq!(
        decisions.len(),
        1 + at(&events, "warning").len() + at(&events, "success").len(),
        "one decision at the start and at every change of the localizer"
    );
    // Switches happen only at decisions.
    let moments: Vec<f64> = decisions.iter().map(|d| d.time_s).collect();
    assert!(at(&events, "switch").iter().all(|t| moments.contains(t)));
    // The mission's segments cover it and name the states.
    assert!(!segments.is_empty());
    assert!(segments.iter().any(|s| !s.localized));
}
