//! The control loop end to end: outcomes, collisions, the bumper, odometry,
//! bad set-ups.

use robot::{Command, Controller, Notes, Perception, Pose, Step, Vec2};
use sim::{
    Cell, CellIndex, CrowdParams, DriveParams, Error, LaserParams, OccupancyGrid, OdometryParams, Outcome,
    RobotParams, RunParams, ScriptedController, Simulation, Task, World,
};

/// A 10 m × 4 m room at 0.05 m with a wall along its right end (x ≥ 9 m).
fn room() -> World {
    let mut g = OccupancyGrid::new(200, 80, 0.05, Pose::default());
    for j in 0..80 {
        for i in 180..200 {
            g.set(CellIndex { i, j }, Cell::Occupied);
        }
    }
    World::new(g)
}

fn forward(v_mps: f64, seconds: f64) -> ScriptedController {
    ScriptedController::new(vec![(
        Command::Twist {
            v_mps,
            omega_radps: 0.0,
        },
        seconds,
    )])
    .unwrap()
}

fn quiet_aibot() -> RobotParams {
    RobotParams {
        odometry: OdometryParams::perfect(),
        ..RobotParams::aibot()
    }
}

#[test]
fn driving_straight_reaches_the_goal_on_time() {
    let world = room();
    let task = Task {
        start: Pose::new(1.0, 2.0, 0.0),
        goal: Some(Vec2::new(4.015, 2.0)),
    };
    let mut sim = Simulation::new(&world, quiet_aibot(), RunParams::default(), task, 1).unwrap();
    let r = sim.run(&mut forward(0.3, 100.0));
    assert_eq!(r.outcome, Some(Outcome::Goal));
    // Ramp to 0.3 m/s at 1 m/s² (0.01 + 0.02 m), then 0.03 m per tick: after
    // k ticks 0.03 (k − 1) m; 2.715 m (tolerance 0.3 m) takes 92 ticks.
    assert!((r.final_pose.x_m - 3.73).abs() < 1e-9, "{:?}", r.final_pose);
    assert!((r.path_length_m - (r.final_pose.x_m - 1.0)).abs() < 1e-9);
    assert_eq!(r.ticks, 92);
    assert!((r.time_s - 9.2).abs() < 1e-9);
    assert_eq!(r.collisions, 0);
    assert!(r.odometry_error_m < 1e-9, "perfect odometry");
    assert!(r.goal_distance_m.unwrap() <= 0.3);
    // Nearest at the start: the map's left edge, 1 m away (less the radius).
    assert!((r.min_clearance_m - 0.85).abs() < 1e-9, "{}", r.min_clearance_m);
}

#[test]
fn driving_into_a_wall_is_a_fatal_collision() {
    let world = room();
    let task = Task {
        start: Pose::new(8.0, 2.0, 0.0),
        goal: None,
    };
    let mut sim = Simulation::new(&world, quiet_aibot(), RunParams::default(), task, 1).unwrap();
    let r = sim.run(&mut forward(0.3, 100.0));
    assert_eq!(r.outcome, Some(Outcome::Collision));
    assert_eq!(r.collisions, 1);
    assert_eq!(r.min_clearance_m, 0.0);
    // The footprint touches the wall at x = 9: the centre passed 8.85.
    assert!(
        r.final_pose.x_m > 8.85 && r.final_pose.x_m < 8.85 + 0.031,
        "{:?}",
        r.final_pose
    );
}

#[test]
fn a_non_fatal_collision_stalls_presses_the_bumper_and_fools_odometry() {
    let world = room();
    let task = Task {
        start: Pose::new(8.0, 2.0, 0.0),
        goal: None,
    };
    let run = RunParams {
        collision_fatal: false,
        time_limit_s: 20.0,
        ..RunParams::default()
    };
    let mut sim = Simulation::new(&world, quiet_aibot(), run, task, 1).unwrap();
    let mut push = forward(0.3, 100.0);
    let mut bumped = false;
    while sim.tick(&mut push).is_none() {
        bumped |= sim.perception().bumper;
    }
    let r = sim.result();
    assert_eq!(r.outcome, Some(Outcome::TimeLimit));
    assert!(bumped);
    // Stalled, the robot creeps back to the wall: contact episodes.
    assert!(r.collisions >= 1);
    assert!(r.final_pose.x_m < 8.85 && r.final_pose.x_m > 8.8);
    // The wheels kept turning against the wall: dead reckoning ran on.
    assert!(r.final_estimate.x_m > 9.5, "{:?}", r.final_estimate);
}

#[test]
fn giving_up_ends_the_run() {
    struct Quitter;
    impl Controller for Quitter {
        fn step(&mut self, p: &Perception, _: &mut Notes) -> Step {
            if p.time_s >= 0.5 {
                Step::GiveUp
            } else {
                Step::Run(Command::Stop)
            }
        }
    }
    let task = Task {
        start: Pose::new(1.0, 2.0, 0.0),
        goal: Some(Vec2::new(5.0, 2.0)),
    };
    let r = Simulation::new(&room(), quiet_aibot(), RunParams::default(), task, 1)
        .unwrap()
        .run(&mut Quitter);
    assert_eq!(r.outcome, Some(Outcome::GaveUp));
    assert_eq!(r.ticks, 6);
}

#[test]
fn a_goal_at_the_start_is_reached_at_once() {
    let task = Task {
        start: Pose::new(1.0, 2.0, 0.0),
        goal: Some(Vec2::new(1.1, 2.0)),
    };
    let mut sim = Simulation::new(&room(), quiet_aibot(), RunParams::default(), task, 1).unwrap();
    assert_eq!(sim.outcome(), Some(Outcome::Goal));
    let r = sim.run(&mut forward(0.3, 1.0));
    assert_eq!((r.outcome, r.ticks), (Some(Outcome::Goal), 0));
}

#[test]
fn bad_start_and_goal_are_geometry_errors() {
    let world = room();
    let robot = RobotParams::aibot();
    let cases = [
        (Pose::new(9.5, 2.0, 0.0), None, "inside the wall"),
        (Pose::new(8.9, 2.0, 0.0), None, "footprint touches the wall"),
        (Pose::new(-1.0, 2.0, 0.0), None, "off the map"),
        (
            Pose::new(1.0, 2.0, 0.0),
            Some(Vec2::new(12.0, 2.0)),
            "goal off the map",
        ),
        (
            Pose::new(1.0, 2.0, 0.0),
            Some(Vec2::new(9.5, 2.0)),
            "goal in the wall",
        ),
    ];
    for (start, goal, why) in cases {
        let task = Task { start, goal };
        match Simulation::new(&world, robot.clone(), RunParams::default(), task, 1) {
            Err(Error::Geometry(msg)) => assert!(!msg.is_empty()),
            other => panic!("{why}: {other:?}"),
        }
    }
    // A person placed on the robot.
    let crowded = room()
        .with_crowd(CrowdParams {
            positions: vec![Vec2::new(1.2, 2.0)],
            ..CrowdParams::default()
        })
        .unwrap();
    let task = Task {
        start: Pose::new(1.0, 2.0, 0.0),
        goal: None,
    };
    assert!(matches!(
        Simulation::new(&crowded, robot, RunParams::default(), task, 1),
        Err(Error::Geometry(_))
    ));
}

#[test]
fn bad_parameters_are_invalid_values() {
    let world = room();
    let task = Task {
        start: Pose::new(1.0, 2.0, 0.0),
        goal: None,
    };
    let robots = [
        RobotParams {
            drive: DriveParams {
                radius_m: -0.1,
                ..DriveParams::aibot()
            },
            ..RobotParams::aibot()
        },
        RobotParams {
            lasers: vec![LaserParams {
                dropout_probability: 1.5,
                ..LaserParams::default()
            }],
            ..RobotParams::aibot()
        },
        RobotParams {
            odometry: OdometryParams {
                slip_sigma: f64::NAN,
                ..OdometryParams::default()
            },
            ..RobotParams::aibot()
        },
    ];
    for robot in robots {
        let e = Simulation::new(&world, robot, RunParams::default(), task, 1).unwrap_err();
        assert!(matches!(e, Error::InvalidValue { .. }), "{e}");
    }
    let runs = [
        RunParams {
            control_period_s: 0.0,
            ..RunParams::default()
        },
        RunParams {
            physics_substeps: 0,
            ..RunParams::default()
        },
        RunParams {
            goal_tolerance_m: -1.0,
            ..RunParams::default()
        },
    ];
    for run in runs {
        let e = Simulation::new(&world, RobotParams::aibot(), run, task, 1).unwrap_err();
        assert!(matches!(e, Error::InvalidValue { .. }), "{e}");
    }
    let nan_start = Task {
        start: Pose {
            x_m: f64::NAN,
            y_m: 1.0,
            theta_rad: 0.0,
        },
        goal: None,
    };
    assert!(matches!(
        Simulation::new(&world, RobotParams::aibot(), RunParams::default(), nan_start, 1),
        Err(Error::InvalidValue { .. })
    ));
    // A controller's NaN command is a stop, not a panic.
    let mut sim = Simulation::new(&world, quiet_aibot(), RunParams::default(), task, 1).unwrap();
    let mut nan = ScriptedController::new(vec![(
        Command::Wheels {
            left_mps: f64::NAN,
            right_mps: f64::INFINITY,
        },
        1.0,
    )])
    .unwrap();
    sim.tick(&mut nan);
    assert_eq!(sim.pose(), Pose::new(1.0, 2.0, 0.0));
}

#[test]
fn substeps_follow_the_same_arc() {
    // Constant wheel speeds (no acceleration limit): the pose after 5 s is
    // the same exact arc whatever the number of sub-steps.
    let robot = RobotParams {
        drive: DriveParams {
            max_wheel_accel_mps2: f64::INFINITY,
            ..DriveParams::aibot()
        },
        ..quiet_aibot()
    };
    let task = Task {
        start: Pose::new(3.0, 2.0, 0.0),
        goal: None,
    };
    let turn = || {
        ScriptedController::new(vec![(
            Command::Wheels {
                left_mps: 0.1,
                right_mps: 0.15,
            },
            100.0,
        )])
        .unwrap()
    };
    let mut poses = Vec::new();
    for n in [1, 4] {
        let run = RunParams {
            physics_substeps: n,
            time_limit_s: 5.0,
            ..RunParams::default()
        };
        let mut sim = Simulation::new(&room(), robot.clone(), run, task, 3).unwrap();
        poses.push(sim.run(&mut turn()).final_pose);
    }
    let exact = sim::kinematics::integrate(task.start, 0.1, 0.15, 0.25, 5.0);
    for p in poses {
        assert!(p.position().dist(exact.position()) < 1e-9, "{p:?} vs {exact:?}");
    }
}

/// Waits, asking people to step aside, while anybody stands within 1 m
/// ahead; then drives on.
struct Polite {
    asking: bool,
}

impl Controller for Polite {
    fn step(&mut self, p: &Perception, _notes: &mut Notes) -> Step {
        let ahead = p
            .sonar
            .iter()
            .filter(|s| s.mount.theta_rad.abs() < 0.3)
            .map(|s| s.range_m)
            .fold(f64::INFINITY, f64::min);
        self.asking = ahead < 1.0;
        if self.asking {
            Step::Run(Command::Stop)
        } else {
            Step::Run(Command::Twist {
                v_mps: 0.3,
                omega_radps: 0.0,
            })
        }
    }

    fn request(&self) -> Option<robot::Request> {
        self.asking.then_some(robot::Request::StepAside { radius_m: 1.5 })
    }
}

#[test]
fn a_request_to_step_aside_clears_the_way() {
    // Someone lingering for ever in the middle of the way.
    let world = room()
        .with_crowd(CrowdParams {
            positions: vec![Vec2::new(2.5, 2.0)],
            linger_probability: 1.0,
            linger_mean_s: 1e9,
            ..CrowdParams::default()
        })
        .unwrap();
    let task = Task {
        start: Pose::new(1.0, 2.0, 0.0),
        goal: Some(Vec2::new(6.0, 2.0)),
    };
    let run = RunParams {
        time_limit_s: 60.0,
        trace: sim::TraceParams::poses(),
        ..RunParams::default()
    };
    let mut sim = Simulation::new(&world, quiet_aibot(), run, task, 3).unwrap();
    let r = sim.run(&mut Polite { asking: false });
    assert_eq!(r.outcome, Some(Outcome::Goal), "{r:?}");
    let trace = sim.take_trace().unwrap();
    let asked = trace.ticks.iter().filter(|t| t.request.is_some()).count();
    assert!(asked > 0, "the robot had to ask");
    // A robot that never asks waits for ever.
    struct Mute(Polite);
    impl Controller for Mute {
        fn step(&mut self, p: &Perception, n: &mut Notes) -> Step {
            self.0.step(p, n)
        }
    }
    let mut sim = Simulation::new(
        &world,
        quiet_aibot(),
        RunParams {
            time_limit_s: 60.0,
            ..RunParams::default()
        },
        task,
        3,
    )
    .unwrap();
    let r = sim.run(&mut Mute(Polite { asking: false }));
    assert_eq!(r.outcome, Some(Outcome::TimeLimit));
}
