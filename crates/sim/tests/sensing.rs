//! What the sensors see from inside a simulation: the IR blind spot between
//! beams, people seen by every range sensor and blocking the robot.

use robot::{Command, Pose, Vec2};
use sim::{
    Cell, CrowdParams, IrParams, LaserParams, OccupancyGrid, OdometryParams, Outcome, RobotParams, RunParams,
    ScriptedController, Simulation, SonarParams, Task, World,
};

/// AIBOT-like, noiseless, plus a noiseless 181-beam laser at the centre.
fn robot_with_everything() -> RobotParams {
    RobotParams {
        lasers: vec![LaserParams {
            range_sigma_m: 0.0,
            dropout_probability: 0.0,
            max_range_m: 8.0,
            ..LaserParams::default()
        }],
        sonar: SonarParams {
            range_sigma_m: 0.0,
            ..SonarParams::default()
        },
        ir: IrParams {
            range_sigma_m: 0.0,
            ..IrParams::default()
        },
        odometry: OdometryParams::perfect(),
        ..RobotParams::aibot()
    }
}

fn stand_still() -> ScriptedController {
    ScriptedController::new(vec![(Command::Stop, 100.0)]).unwrap()
}

/// Reads the sensors once (first tick) at `start` in `world`.
fn first_reading(world: &World, start: Pose) -> robot::Perception {
    let task = Task { start, goal: None };
    let mut sim = Simulation::new(world, robot_with_everything(), RunParams::default(), task, 5).unwrap();
    sim.tick(&mut stand_still());
    sim.perception().clone()
}

#[test]
fn a_thin_obstacle_between_two_ir_beams_is_missed_but_sonar_and_laser_see_it() {
    // One 5 cm cell, 0.4 m from the middle sonar at 10° to its left: between
    // the IR beams at 0° and +30°.
    let mut g = OccupancyGrid::new(100, 100, 0.05, Pose::default());
    let robot = Pose::new(2.0, 2.0, 0.0);
    let a = 10f64.to_radians();
    let spot = Vec2::new(2.15 + 0.4 * a.cos(), 2.0 + 0.4 * a.sin());
    g.set(g.cell_of(spot), Cell::Occupied);
    let p = first_reading(&World::new(g.clone()), robot);
    assert!(p.ir.iter().all(|d| !d.triggered), "IR sees it: {:?}", p.ir);
    assert!(p.sonar[1].range_m < 0.45, "sonar: {}", p.sonar[1].range_m);
    let nearest_beam = p.lasers[0].ranges_m.iter().copied().fold(f64::INFINITY, f64::min);
    assert!(nearest_beam < 0.6, "laser: {nearest_beam}");

    // A wall across the same place is seen by the IR too.
    for j in 0..100 {
        let c = g.cell_of(Vec2::new(spot.x, j as f64 * 0.05 + 0.025));
        g.set(c, Cell::Occupied);
    }
    let p = first_reading(&World::new(g), robot);
    assert!(p.ir[3].triggered, "front IR misses a wall");
}

#[test]
fn people_are_seen_by_every_range_sensor() {
    // A person 1 m ahead of the robot, lingering for ever.
    let g = OccupancyGrid::new(100, 100, 0.05, Pose::default());
    let world = World::new(g)
        .with_crowd(CrowdParams {
            positions: vec![Vec2::new(2.7, 2.0)],
            linger_probability: 1.0,
            linger_mean_s: 1e9,
            ..CrowdParams::default()
        })
        .unwrap();
    let p = first_reading(&world, Pose::new(2.0, 2.0, 0.0));
    // The laser at the centre: the person's near side is 0.7 − 0.25 away.
    assert!(
        (p.lasers[0].ranges_m[90] - 0.45).abs() < 1e-9,
        "{}",
        p.lasers[0].ranges_m[90]
    );
    // The middle sonar on the rim: 0.45 − 0.15.
    assert!((p.sonar[1].range_m - 0.30).abs() < 1e-9, "{}", p.sonar[1].range_m);
    assert!(p.ir[3].triggered);
    assert!(!p.ir[0].triggered && !p.ir[6].triggered);
}

#[test]
fn driving_into_a_person_is_a_collision() {
    let g = OccupancyGrid::new(100, 100, 0.05, Pose::default());
    let world = World::new(g)
        .with_crowd(CrowdParams {
            positions: vec![Vec2::new(3.0, 2.0)],
            linger_probability: 1.0,
            linger_mean_s: 1e9,
            // The person does not step aside.
            robot_repulsion_mps2: 0.0,
            ..CrowdParams::default()
        })
        .unwrap();
    let task = Task {
        start: Pose::new(2.0, 2.0, 0.0),
        goal: Some(Vec2::new(4.0, 2.0)),
    };
    let mut sim = Simulation::new(&world, robot_with_everything(), RunParams::default(), task, 5).unwrap();
    let mut drive = ScriptedController::new(vec![(
        Command::Twist {
            v_mps: 0.3,
            omega_radps: 0.0,
        },
        100.0,
    )])
    .unwrap();
    let r = sim.run(&mut drive);
    assert_eq!(r.outcome, Some(Outcome::Collision));
    // Contact when the centres are 0.4 m apart.
    assert!(
        r.final_pose.x_m > 2.6 && r.final_pose.x_m < 2.6 + 0.031,
        "{:?}",
        r.final_pose
    );
}

#[test]
fn a_crowd_walks_and_never_overlaps_the_robot() {
    let g = sim::generators::building_31_like();
    let world = World::new(g)
        .with_crowd(CrowdParams {
            size: sim::CrowdSize::PerArea {
                people_per_100m2: 5.0,
            },
            waypoints: vec![Vec2::new(5.0, 10.8), Vec2::new(18.0, 16.0), Vec2::new(30.0, 21.6)],
            ..CrowdParams::default()
        })
        .unwrap();
    let task = Task {
        start: Pose::new(2.0, 10.8, 0.0),
        goal: None,
    };
    let run = RunParams {
        time_limit_s: 60.0,
        ..RunParams::default()
    };
    let mut sim = Simulation::new(&world, RobotParams::jinny(), run, task, 9).unwrap();
    let start: Vec<Vec2> = sim.crowd().people().iter().map(|q| q.position).collect();
    assert!(start.len() > 40, "{}", start.len());
    let r = sim.run(&mut stand_still());
    assert_eq!(r.outcome, Some(Outcome::TimeLimit));
    let moved = sim
        .crowd()
        .people()
        .iter()
        .zip(&start)
        .filter(|(q, s)| q.position.dist(**s) > 2.0)
        .count();
    assert!(moved > start.len() / 3, "{moved} of {} moved", start.len());
    assert!(r.min_clearance_m >= 0.0);
}

#[test]
fn the_sonar_ring_sees_a_wall_behind_that_aibot_cannot() {
    // A wall 0.5 m behind the robot's centre.
    let mut g = OccupancyGrid::new(100, 100, 0.05, Pose::default());
    for j in 0..100 {
        let c = g.cell_of(Vec2::new(1.5, j as f64 * 0.05 + 0.025));
        g.set(c, Cell::Occupied);
    }
    let world = World::new(g);
    let start = Pose::new(2.05, 2.5, 0.0);
    let read = |robot: RobotParams| {
        let task = Task { start, goal: None };
        let mut sim = Simulation::new(&world, robot, RunParams::default(), task, 5).unwrap();
        sim.tick(&mut stand_still());
        sim.perception().clone()
    };
    let ring = read(RobotParams::sonar_ring());
    assert_eq!(ring.sonar.len(), 16);
    // Mounts 22.5° apart all round, the first straight ahead.
    for (k, s) in ring.sonar.iter().enumerate() {
        let expected = robot::wrap_angle(std::f64::consts::TAU * k as f64 / 16.0);
        assert!((s.mount.theta_rad - expected).abs() < 1e-12, "mount {k}");
    }
    let behind = &ring.sonar[8];
    assert!(
        (behind.range_m - 0.35).abs() < 0.1,
        "rear sonar: {}",
        behind.range_m
    );
    assert!(
        ring.sonar[0].range_m > 2.0,
        "front sonar: {}",
        ring.sonar[0].range_m
    );
    let aibot = read(RobotParams::aibot());
    assert!(aibot.sonar.iter().all(|s| s.range_m > 2.0) && aibot.ir.iter().all(|d| !d.triggered));
}
