//! Replays for the crate's unit tests (MCAP export, the viewer's data).

use std::collections::BTreeMap;

use robot::{Event, LaserScan, Perception, Pose, Vec2};
use sim::{OccupancyGrid, StepKind, Trace, TraceTick};

use crate::pictures::Replay;
use crate::record::RunRecord;

/// Three ticks of a robot with a 5-beam laser (one beam without a
/// return, one dropped out) among two people, an event at the last.
pub fn laser_replay() -> Replay {
    let ticks = (0..3u64)
        .map(|k| {
            let t = k as f64 * 0.1;
            TraceTick {
                tick: k,
                time_s: t,
                true_pose: Pose::new(1.0 + t, 1.0, 0.5),
                estimated_pose: Pose::new(1.0 + t, 1.02, 0.5),
                step: StepKind::Run,
                command: Some(robot::Command::Twist {
                    v_mps: 1.0,
                    omega_radps: 0.0,
                }),
                wheels_mps: (1.0, 1.0),
                contact: false,
                behaviour: Some("go"),
                values: vec![("w", 0.25), ("inf", f64::INFINITY)],
                events: if k == 2 {
                    vec![Event::new("stuck", t).at(Vec2::new(1.0, 1.0)).with("events", 3.0)]
                } else {
                    Vec::new()
                },
                clouds: if k == 1 {
                    vec![(
                        "particles",
                        vec![Pose::new(1.1, 1.0, 0.5), Pose::new(1.2, 0.9, 0.4)],
                    )]
                } else {
                    Vec::new()
                },
                request: None,
                perception: Some(Perception {
                    time_s: t,
                    lasers: vec![LaserScan {
                        mount: Pose::new(0.2, 0.0, 0.0),
                        angle_min_rad: -1.0,
                        angle_increment_rad: 0.5,
                        range_max_m: 4.0,
                        ranges_m: vec![1.0, 1.2345678, f64::INFINITY, f64::NAN, 2.0],
                    }],
                    ..Perception::default()
                }),
                people: vec![Vec2::new(3.0, 3.0), Vec2::new(2.0, 3.5)],
            }
        })
        .collect();
    Replay {
        record: RunRecord {
            success: true,
            outcome: "goal".into(),
            time_s: 0.2,
            path_length_m: 0.2,
            collisions: 0,
            min_clearance_m: 0.5,
            odometry_error_m: 0.02,
            goal_distance_m: 0.1,
            ticks: 3,
            behaviour_ticks: BTreeMap::new(),
            metrics: BTreeMap::new(),
            events: Vec::new(),
            start: [1.0, 1.0, 0.5],
            trap: None,
            state: None,
        },
        trace: Trace { seed: 7, ticks },
        grid: OccupancyGrid::new(40, 30, 0.1, Pose::new(0.0, 0.0, 0.0)),
        goal: Some(Vec2::new(3.5, 1.0)),
        robot_radius_m: 0.2,
        control_period_s: 0.1,
        net: None,
    }
}
