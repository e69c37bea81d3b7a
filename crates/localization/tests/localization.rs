//! Monte Carlo localization against the simulator on the two real maps.
//!
//! The simulated Jinny-like robot (181-beam laser over 180°, 30 m, σ 1 cm,
//! mounted 0.2 m ahead; default odometry noise) drives a route through the
//! corridors, steered with the TRUE pose (the harness tests the localizer,
//! not a planner); the localizer sees only the perceptions. The figures of
//! longer runs come from `examples/mcl_drive.rs`.

#[path = "common/mcl_harness.rs"]
mod harness;

use harness::{DriveSetup, drive};
use localization::{LocalizationStatus, MclParams, StatusParams};

fn assert_tracks(setup: &DriveSetup) {
    let s = drive(setup);
    let (median, max) = (s.median_error_m(), s.max_error_m());
    eprintln!(
        "{}: {:.1} m driven, {} iterations, error median {median:.3} m, max {max:.3} m, Warning {:.1} %",
        setup.map,
        s.distance_m,
        s.iterations,
        100.0 * s.warning_fraction()
    );
    assert!(s.finished, "the route was not finished");
    assert!(s.distance_m >= 100.0, "only {:.1} m driven", s.distance_m);
    assert!(median <= 0.10, "median error {median:.3} m");
    assert!(max <= 0.30, "largest error {max:.3} m");
    // A good track is mostly Success.
    assert!(s.warning_fraction() < 0.1, "Warning {:.3}", s.warning_fraction());
}

#[test]
fn tracks_the_jinny_robot_over_100_m_of_building_31() {
    assert_tracks(&DriveSetup::tracking("building_31"));
}

#[test]
fn tracks_the_jinny_robot_over_100_m_of_levine() {
    assert_tracks(&DriveSetup::tracking("levine"));
}

#[test]
fn same_seeds_give_identical_estimates_and_another_seed_does_not() {
    let setup = DriveSetup {
        max_distance_m: 12.0,
        ..DriveSetup::tracking("building_31")
    };
    let a = drive(&setup);
    let b = drive(&setup);
    assert!(a.iterations > 40);
    let bits = |s: &harness::DriveStats| -> Vec<u64> {
        s.infos
            .iter()
            .flat_map(|i| {
                [
                    i.estimate.x_m.to_bits(),
                    i.estimate.y_m.to_bits(),
                    i.estimate.theta_rad.to_bits(),
                ]
            })
            .collect()
    };
    assert_eq!(bits(&a), bits(&b));
    assert_eq!(a.errors_m, b.errors_m);
    let c = drive(&DriveSetup {
        mcl_seed: setup.mcl_seed + 1,
        ..setup
    });
    assert_ne!(bits(&a), bits(&c));
}

#[test]
fn people_hiding_the_walls_raise_warnings_under_the_source_rule_only() {
    let source = MclParams {
        status: StatusParams::explained(),
        ..MclParams::default()
    };
    let quiet = DriveSetup {
        max_distance_m: 60.0,
        params: source,
        ..DriveSetup::tracking("building_31")
    };
    let crowded = DriveSetup {
        people: 60,
        ..quiet.clone()
    };
    let q = drive(&quiet);
    let c = drive(&crowded);
    eprintln!(
        "source rule: Warning {:.1} % of the iterations without people, {:.1} % with 60; errors max {:.3} / {:.3} m",
        100.0 * q.warning_fraction(),
        100.0 * c.warning_fraction(),
        q.max_error_m(),
        c.max_error_m()
    );
    assert!(q.warning_fraction() < 0.05);
    assert!(c.warning_fraction() > q.warning_fraction() + 0.15);
    assert!(c.warnings_raised >= 3);
    // The crowd hides walls but the estimate stays good: a warning, not a loss.
    assert!(c.max_error_m() <= 0.3, "{}", c.max_error_m());
    // In Warning, the map explains less of the scan.
    let mean = |s: &harness::DriveStats, w: LocalizationStatus| {
        let v: Vec<f64> = s
            .infos
            .iter()
            .filter(|i| i.status == w)
            .map(|i| i.score_estimate)
            .collect();
        v.iter().sum::<f64>() / v.len().max(1) as f64
    };
    assert!(mean(&c, LocalizationStatus::Warning) < mean(&c, LocalizationStatus::Success));
    // The contradiction rule (the default) tells crowded from lost: the
    // same crowd raises no Warning, and the estimate is as good.
    let contradiction = drive(&DriveSetup {
        params: MclParams::default(),
        ..crowded.clone()
    });
    eprintln!(
        "contradiction rule: Warning {:.1} % with 60 people, error max {:.3} m",
        100.0 * contradiction.warning_fraction(),
        contradiction.max_error_m()
    );
    assert!(contradiction.warning_fraction() < 0.02);
    assert!(
        contradiction.max_error_m() <= 0.3,
        "{}",
        contradiction.max_error_m()
    );
}

#[test]
fn global_localization_converges_in_building_31() {
    let setup = DriveSetup {
        init: None,
        max_distance_m: 50.0,
        ..DriveSetup::tracking("building_31")
    };
    let s = drive(&setup);
    let at = s.converged_at_m.expect("converged within 50 m");
    eprintln!("global localization: within 0.3 m from {at:.1} m travelled on");
    assert!(at < 40.0, "{at}");
    // From then on it tracks, and the particle cloud has shrunk to the
    // tracking size.
    let tail = &s.errors_m[s.errors_m.len() - 100..];
    assert!(harness::max(tail) < 0.15);
    assert_eq!(s.infos.last().unwrap().particles_after, setup.params.particles);
}

#[test]
fn a_kidnapped_robot_warns_and_finds_itself_again() {
    // 20 m into building_31's route the localizer's belief jumps 1 m and
    // 40° away from the truth (a push the odometry did not see).
    for (dx, dy, dth) in [
        (1.0, 0.0, 40f64.to_radians()),
        (0.0, -1.5, 0.0),
        (0.0, 0.0, -70f64.to_radians()),
    ] {
        let s = drive(&DriveSetup {
            max_distance_m: 60.0,
            kidnap: Some((20.0, (dx, dy, dth))),
            timed: true,
            ..DriveSetup::tracking("building_31")
        });
        let k = s.kidnapped_at_tick.expect("the kidnap happened");
        let warned = s.statuses[k..]
            .iter()
            .position(|&w| w == LocalizationStatus::Warning)
            .expect("the contradiction rule raises a Warning");
        let found = s.errors_m[k + warned..]
            .iter()
            .position(|&e| e < 0.2)
            .expect("the recovery finds the robot again");
        let back = s.statuses[k + warned..]
            .iter()
            .position(|&w| w == LocalizationStatus::Success)
            .expect("and the Warning clears");
        eprintln!(
            "kidnap ({dx}, {dy}, {:.0}°): Warning after {:.1} s, error < 0.2 m after {:.1} s more, Success after {:.1} s; final error {:.3} m",
            dth.to_degrees(),
            warned as f64 * 0.1,
            found as f64 * 0.1,
            back as f64 * 0.1,
            s.errors_m.last().unwrap()
        );
        assert!(warned as f64 * 0.1 < 3.0, "Warning after {} ticks", warned);
        assert!(found as f64 * 0.1 < 30.0);
        assert!(harness::max(&s.errors_m[s.errors_m.len() - 50..]) < 0.2);
        assert_eq!(*s.statuses.last().unwrap(), LocalizationStatus::Success);
    }
}
