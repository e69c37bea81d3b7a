//! Disturbances end to end: off changes nothing; a push moves the true pose
//! and not the odometry, and stops at a wall; a robot that keeps driving is
//! never pushed; slip on a patch (known answer); the same seed gives the
//! same draws to two controllers; a group closes round the robot and does
//! not step aside until its time is up; bad parameters.

use robot::{Command, Controller, Notes, Perception, Pose, Request, Step, Vec2};
use sim::{
    Activity, Cell, CellIndex, CrowdParams, CrowdSize, DisturbanceKind, DisturbanceParams, Error,
    OccupancyGrid, OdometryParams, PushParams, RobotParams, RunParams, ScriptedController, Simulation,
    SlipParams, SlipPatch, SurroundParams, Task, TraceParams, World,
};

/// A `w` × `h` m room at 0.05 m with walls all round (one cell thick).
fn walled(w: usize, h: usize) -> OccupancyGrid {
    let (n, m) = (w as i64 * 20, h as i64 * 20);
    let mut g = OccupancyGrid::new(n as usize, m as usize, 0.05, Pose::default());
    for i in 0..n {
        g.set(CellIndex { i, j: 0 }, Cell::Occupied);
        g.set(CellIndex { i, j: m - 1 }, Cell::Occupied);
    }
    for j in 0..m {
        g.set(CellIndex { i: 0, j }, Cell::Occupied);
        g.set(CellIndex { i: n - 1, j }, Cell::Occupied);
    }
    g
}

/// A 12 m × 12 m museum hall with `people` visitors walking between four
/// exhibits (none of them taking an interest in the robot on their own).
fn museum(people: usize) -> World {
    World::new(walled(12, 12))
        .with_crowd(CrowdParams {
            size: CrowdSize::Count { people },
            waypoints: vec![
                Vec2::new(2.0, 2.0),
                Vec2::new(10.0, 2.0),
                Vec2::new(2.0, 10.0),
                Vec2::new(10.0, 10.0),
            ],
            ..CrowdParams::default()
        })
        .unwrap()
}

/// People at `positions` standing still for ever, not shying away from the
/// robot, in a 10 m × 4 m room whose right wall's inner face is at x = 9 m.
fn standing_people(positions: Vec<Vec2>) -> World {
    let mut g = OccupancyGrid::new(200, 80, 0.05, Pose::default());
    for j in 0..80 {
        for i in 180..200 {
            g.set(CellIndex { i, j }, Cell::Occupied);
        }
    }
    World::new(g)
        .with_crowd(CrowdParams {
            positions,
            linger_probability: 1.0,
            linger_mean_s: 1e9,
            robot_repulsion_mps2: 0.0,
            ..CrowdParams::default()
        })
        .unwrap()
}

fn run_params(time_limit_s: f64) -> RunParams {
    RunParams {
        time_limit_s,
        ..RunParams::default()
    }
}

fn twist(v_mps: f64, omega_radps: f64) -> Command {
    Command::Twist { v_mps, omega_radps }
}

/// Stands still (a script that has ended answers `Done(Stop)`).
fn stand() -> ScriptedController {
    ScriptedController::new(Vec::new()).unwrap()
}

/// Pushes of `distance_m`, straight away from the pusher, at `rate` per
/// person per second.
fn pushes(rate: f64, distance_m: f64) -> DisturbanceParams {
    DisturbanceParams {
        push: PushParams {
            rate_per_person_s: rate,
            distance_min_m: distance_m,
            distance_max_m: distance_m,
            direction_jitter_rad: 0.0,
            turn_max_rad: 0.3,
            ..PushParams::default()
        },
        ..DisturbanceParams::default()
    }
}

/// A reactive wanderer on the laser, annotating its choices.
struct Wander;

impl Controller for Wander {
    fn step(&mut self, p: &Perception, notes: &mut Notes) -> Step {
        let scan = &p.lasers[0].ranges_m;
        let n = scan.len();
        let front = scan[n / 3..2 * n / 3]
            .iter()
            .filter(|x| !x.is_nan())
            .fold(f64::INFINITY, |a, &b| a.min(b));
        notes.value("front_m", front.min(100.0));
        if front < 1.0 || p.bumper {
            notes.behaviour("turn");
            Step::Run(twist(0.0, 0.8))
        } else {
            notes.behaviour("forward");
            Step::Run(twist(0.4, 0.1))
        }
    }
}

#[test]
fn default_disturbances_change_nothing_bit_for_bit() {
    let world = museum(25).with_crowd(CrowdParams {
        robot_interest_rate_per_s: 0.02,
        ..museum(25).crowd().clone()
    });
    let world = world.unwrap();
    let record = |disturbed: bool| {
        let task = Task {
            start: Pose::new(6.0, 6.0, 0.3),
            goal: Some(Vec2::new(11.0, 11.0)),
        };
        let run = RunParams {
            time_limit_s: 40.0,
            collision_fatal: false,
            physics_substeps: 2,
            trace: TraceParams::full(),
            ..RunParams::default()
        };
        let mut sim = Simulation::new(&world, RobotParams::jinny(), run, task, 11).unwrap();
        if disturbed {
            sim = sim.with_disturbances(DisturbanceParams::default()).unwrap();
            assert!(sim.disturbance_params().is_none(), "all off: nothing to run");
        }
        let result = sim.run(&mut Wander);
        assert!(sim.disturbances().is_empty() && result.disturbances.is_zero());
        let json = serde_json::to_string(&result).unwrap();
        assert!(!json.contains("disturbances"), "{json}");
        let trace = sim.take_trace().unwrap();
        format!("{result:?}\n{trace:?}\n{:?}", sim.crowd().people())
    };
    assert_eq!(record(false), record(true));
}

#[test]
fn a_push_moves_the_true_pose_not_the_odometry_and_stops_at_the_wall() {
    // A visitor stands 0.2 m (rim to rim) behind the robot, which stands
    // 0.85 m from the wall; pushes are 2 m long, straight away from them.
    let world = standing_people(vec![Vec2::new(7.4, 2.0)]);
    let start = Pose::new(8.0, 2.0, 0.0);
    let task = Task { start, goal: None };
    let run = run_params(30.0);
    // Default (noisy) odometry: standing still, it still measures nothing.
    let mut sim = Simulation::new(&world, RobotParams::aibot(), run, task, 3)
        .unwrap()
        .with_disturbances(pushes(2.0, 2.0))
        .unwrap();
    let mut still = stand();
    while !sim.pushed() {
        assert!(sim.tick(&mut still).is_none());
        assert!(sim.time_s() < 10.0, "never pushed");
    }
    // Braked after 1 s: no push before.
    let struck_s = sim.disturbances()[0].start_s;
    assert!(struck_s >= 1.0 - 1e-9, "{struck_s}");
    // While pushed the robot is held: a controller commanding full speed
    // gets no wheel turn, and the encoders see none.
    let mut go = ScriptedController::new(vec![(twist(0.3, 0.0), 100.0)]).unwrap();
    let mut ticks = 0;
    while sim.pushed() {
        assert!(sim.tick(&mut go).is_none(), "{:?}", sim.outcome());
        assert_eq!(sim.wheels_mps(), (0.0, 0.0));
        assert_eq!(sim.estimate(), start);
        ticks += 1;
    }
    assert!(ticks >= 10, "{ticks} ticks");
    let pose = sim.pose();
    // Stopped within one sub-step (0.5 m/s × 0.1 s) short of touching the
    // wall at x = 9 − 0.15.
    assert!(pose.x_m <= 8.85 && pose.x_m > 8.85 - 0.05 - 1e-9, "{pose:?}");
    assert_eq!(pose.y_m, 2.0, "straight away from the pusher");
    let e = &sim.disturbances()[0];
    let DisturbanceKind::Push {
        pusher,
        direction_rad,
        intended_translation_m,
        intended_rotation_rad,
        applied_translation_m,
        applied_rotation_rad,
        stopped_early,
    } = e.kind
    else {
        panic!("{e:?}")
    };
    assert_eq!((pusher, direction_rad, intended_translation_m), (0, 0.0, 2.0));
    assert!(stopped_early && e.end_s.is_some());
    assert!((applied_translation_m - (pose.x_m - 8.0)).abs() < 1e-9);
    // The turn is spread over the same time: applied in proportion.
    assert!(intended_rotation_rad.abs() <= 0.3);
    assert!((applied_rotation_rad - intended_rotation_rad * applied_translation_m / 2.0).abs() < 1e-9);
    assert!((pose.theta_rad - applied_rotation_rad).abs() < 1e-9);
    let r = sim.result();
    assert_eq!(
        (r.disturbances.pushes, r.disturbances.pushes_stopped_early),
        (1, 1)
    );
    assert!((r.disturbances.pushed_m - applied_translation_m).abs() < 1e-9);
    assert!(
        (r.path_length_m - applied_translation_m).abs() < 1e-9,
        "the pushed path counts"
    );
    assert!((r.odometry_error_m - applied_translation_m).abs() < 1e-9);
    // Nobody within reach any more: no second push.
    let r = sim.run(&mut stand());
    assert_eq!(r.disturbances.pushes, 1);
    assert_eq!(r.collisions, 0);
}

#[test]
fn a_robot_that_keeps_driving_is_never_pushed() {
    // Two visitors flank the robot within reach; the robot creeps to and
    // fro, never standing a whole second.
    let world = standing_people(vec![Vec2::new(4.0, 2.5), Vec2::new(4.0, 1.5)]);
    let task = Task {
        start: Pose::new(4.0, 2.0, 0.0),
        goal: None,
    };
    let creep = |pause_s: f64| {
        let mut script = Vec::new();
        for _ in 0..20 {
            script.extend([
                (twist(0.05, 0.0), 0.2),
                (Command::Stop, pause_s),
                (twist(-0.05, 0.0), 0.2),
                (Command::Stop, pause_s),
            ]);
        }
        ScriptedController::new(script).unwrap()
    };
    let run = |pause_s: f64, disturbances: Option<DisturbanceParams>| {
        let robot = RobotParams {
            odometry: OdometryParams::perfect(),
            ..RobotParams::aibot()
        };
        let mut sim = Simulation::new(&world, robot, run_params(35.0), task, 8).unwrap();
        if let Some(d) = disturbances {
            sim = sim.with_disturbances(d).unwrap();
        }
        let r = sim.run(&mut creep(pause_s));
        (r, sim.disturbances().to_vec())
    };
    let (driving, events) = run(0.7, Some(pushes(100.0, 0.5)));
    assert!(events.is_empty(), "{events:?}");
    // …and its run is the undisturbed one: the push stream touches nothing
    // else.
    let (undisturbed, _) = run(0.7, None);
    assert_eq!(driving, undisturbed);
    // Pausing 1.5 s at a time, the same robot is pushed.
    let (_, events) = run(1.5, Some(pushes(100.0, 0.5)));
    assert!(!events.is_empty());
    assert!(events.iter().all(|e| e.kind.name() == "push"));
}

#[test]
fn slip_on_a_patch_loses_travel_and_bends_the_heading_as_drawn() {
    let world = World::new(walled(10, 8));
    let robot = RobotParams {
        odometry: OdometryParams::perfect(),
        ..RobotParams::aibot()
    };
    let base = robot.drive.wheel_base_m;
    let task = Task {
        start: Pose::new(1.0, 4.0, 0.0),
        goal: None,
    };
    let d = DisturbanceParams {
        slip: SlipParams {
            patches: vec![SlipPatch {
                min: [3.0, 2.0],
                max: [5.0, 6.0],
            }],
            slip_max: 0.05,
        },
        ..DisturbanceParams::default()
    };
    for seed in [1, 2, 3] {
        let mut sim = Simulation::new(&world, robot.clone(), run_params(15.0), task, seed)
            .unwrap()
            .with_disturbances(d.clone())
            .unwrap();
        let r = sim.run(&mut ScriptedController::new(vec![(twist(0.3, 0.0), 100.0)]).unwrap());
        assert_eq!(r.disturbances.slips, 1);
        let e = &sim.disturbances()[0];
        let DisturbanceKind::Slip {
            patch,
            left_ratio,
            right_ratio,
            distance_m,
            odometry_distance_m,
        } = e.kind
        else {
            panic!("{e:?}")
        };
        assert_eq!(patch, 0);
        assert!((0.0..0.05).contains(&left_ratio) && (0.0..0.05).contains(&right_ratio));
        assert!(
            e.start_s > 6.0 && e.end_s.is_some_and(|t| t > e.start_s + 6.0),
            "{e:?}"
        );
        // Both wheels commanded alike: the centre travels (1 − mean slip)
        // of what the encoders measure…
        let mean = 0.5 * (left_ratio + right_ratio);
        assert!(
            (distance_m - (1.0 - mean) * odometry_distance_m).abs() < 1e-9,
            "{e:?}"
        );
        assert!(
            (distance_m - 2.0).abs() < 0.05,
            "the patch is 2 m long: {distance_m}"
        );
        // …and turns by (s_l − s_r)·D/b, which the odometry misses.
        let turn = (left_ratio - right_ratio) * odometry_distance_m / base;
        assert!(
            (r.final_pose.theta_rad - turn).abs() < 1e-9,
            "{:?} vs {turn}",
            r.final_pose
        );
        assert_eq!(r.final_estimate.theta_rad, 0.0);
        // The estimate ran ahead by the travel lost.
        let measured = r.final_estimate.x_m - 1.0;
        assert!((r.path_length_m - (measured - (odometry_distance_m - distance_m))).abs() < 1e-9);
        assert!((r.disturbances.slip_distance_m - distance_m).abs() < 1e-12);
    }
}

/// Drives forward at 0.2 m/s until `stop_s`, then stands; asks nothing.
fn drive_then_stand(stop_s: f64) -> ScriptedController {
    ScriptedController::new(vec![(twist(0.2, 0.0), stop_s)]).unwrap()
}

#[test]
fn the_same_seed_gives_two_controllers_the_same_draws() {
    let world = museum(30);
    let d = DisturbanceParams {
        push: PushParams {
            rate_per_person_s: 0.2,
            ..PushParams::default()
        },
        surround: SurroundParams {
            rate_per_s: 0.05,
            duration_min_s: 5.0,
            duration_max_s: 15.0,
            ..SurroundParams::default()
        },
        ..DisturbanceParams::default()
    };
    let run = |stop_s: f64| {
        let task = Task {
            start: Pose::new(3.0, 6.0, 0.0),
            goal: None,
        };
        let run = RunParams {
            collision_fatal: false,
            ..run_params(150.0)
        };
        let mut sim = Simulation::new(&world, RobotParams::jinny(), run, task, 21)
            .unwrap()
            .with_disturbances(d.clone())
            .unwrap();
        sim.run(&mut drive_then_stand(stop_s));
        (sim.disturbances().to_vec(), sim.crowd().people().to_vec())
    };
    let (a, people_a) = run(5.0);
    let (b, people_b) = run(8.0);
    assert_ne!(people_a, people_b, "the two runs differ");
    let surrounds = |events: &[sim::DisturbanceEvent]| -> Vec<(f64, Option<f64>, usize, f64)> {
        events
            .iter()
            .filter_map(|e| match e.kind {
                DisturbanceKind::Surround {
                    group_size,
                    duration_s,
                    ..
                } => Some((e.start_s, e.end_s, group_size, duration_s)),
                _ => None,
            })
            .collect()
    };
    assert!(surrounds(&a).len() >= 3, "{:?}", surrounds(&a));
    assert_eq!(surrounds(&a), surrounds(&b));
    // The k-th push is the same push in both runs, wherever and whenever
    // it strikes.
    let draws = |events: &[sim::DisturbanceEvent]| -> Vec<(f64, f64)> {
        events
            .iter()
            .filter_map(|e| match e.kind {
                DisturbanceKind::Push {
                    intended_translation_m,
                    intended_rotation_rad,
                    ..
                } => Some((intended_translation_m, intended_rotation_rad)),
                _ => None,
            })
            .collect()
    };
    let (pa, pb) = (draws(&a), draws(&b));
    let k = pa.len().min(pb.len());
    assert!(k >= 1, "{pa:?} {pb:?}");
    assert_eq!(pa[..k], pb[..k]);
}

/// Stands still; from `ask_from_s` on asks the people within 2 m to step
/// aside, every tick.
struct Stand {
    ask_from_s: f64,
    now_s: f64,
}

impl Controller for Stand {
    fn step(&mut self, p: &Perception, _notes: &mut Notes) -> Step {
        self.now_s = p.time_s;
        Step::Run(Command::Stop)
    }

    fn request(&self) -> Option<Request> {
        (self.now_s >= self.ask_from_s).then_some(Request::StepAside { radius_m: 2.0 })
    }
}

#[test]
fn a_group_closes_round_the_robot_and_stays_until_its_time_is_up() {
    let world = museum(12);
    let at = Vec2::new(6.0, 6.0);
    let task = Task {
        start: Pose::new(at.x, at.y, 0.0),
        goal: None,
    };
    let d = DisturbanceParams {
        surround: SurroundParams {
            rate_per_s: 0.01,
            group_min: 4,
            group_max: 4,
            duration_min_s: 30.0,
            duration_max_s: 30.0,
            ..SurroundParams::default()
        },
        ..DisturbanceParams::default()
    };
    let mut sim = Simulation::new(&world, RobotParams::jinny(), run_params(1e9), task, 4)
        .unwrap()
        .with_disturbances(d)
        .unwrap();
    let mut quiet = Stand {
        ask_from_s: f64::INFINITY,
        now_s: 0.0,
    };
    while sim.disturbances().is_empty() {
        sim.tick(&mut quiet);
        assert!(sim.time_s() < 1000.0, "no group came");
    }
    let e = sim.disturbances()[0].clone();
    let DisturbanceKind::Surround { people: came, .. } = &e.kind else {
        panic!("{e:?}")
    };
    let until_s = e.end_s.unwrap();
    assert_eq!(until_s, e.start_s + 30.0);
    // The four nearest (an open hall: everybody can walk to the robot).
    let mut by_distance: Vec<usize> = (0..12).collect();
    let people = sim.crowd().people();
    by_distance.sort_by(|&i, &j| {
        people[i]
            .position
            .dist(at)
            .total_cmp(&people[j].position.dist(at))
    });
    assert_eq!(came[..], by_distance[..4]);
    // 15 s later they stand round the robot; it asks them to step aside
    // every tick, and they stay until their time is up.
    let mut asking = Stand {
        ask_from_s: 0.0,
        now_s: 0.0,
    };
    while sim.time_s() < e.start_s + 15.0 {
        sim.tick(&mut quiet);
    }
    for &k in came {
        let q = sim.crowd().people()[k];
        assert_eq!(q.activity, Activity::AtRobot { until_s }, "person {k}");
        // At the gather distance (0.9 m), give or take the others' push.
        assert!(q.position.dist(at) < 1.5, "person {k} at {:?}", q.position);
    }
    while sim.time_s() < until_s - 0.15 {
        sim.tick(&mut asking);
        for &k in came {
            let q = sim.crowd().people()[k];
            assert!(
                q.asked.is_none() && q.activity.with_robot(),
                "person {k} at {} s",
                sim.time_s()
            );
        }
    }
    // Time up: they are asked like anybody, and go.
    while sim.time_s() < until_s + 10.0 {
        sim.tick(&mut asking);
    }
    assert_eq!(sim.disturbances().len(), 1, "a second group would blur the test");
    for &k in came {
        let q = sim.crowd().people()[k];
        assert!(
            !q.activity.with_robot() && q.curious_until_s.is_none(),
            "person {k}: {q:?}"
        );
        assert!(q.position.dist(at) > 2.0, "person {k} at {:?}", q.position);
    }
    let r = sim.result();
    assert_eq!((r.disturbances.surrounds, r.disturbances.surround_people), (1, 4));
}

#[test]
fn bad_parameters_are_errors_naming_the_field() {
    let world = World::new(walled(4, 4));
    let task = Task {
        start: Pose::new(2.0, 2.0, 0.0),
        goal: None,
    };
    let sim = Simulation::new(&world, RobotParams::aibot(), RunParams::default(), task, 1).unwrap();
    let bad = DisturbanceParams {
        push: PushParams {
            reach_m: f64::NAN,
            ..PushParams::default()
        },
        ..DisturbanceParams::default()
    };
    match sim.clone().with_disturbances(bad) {
        Err(Error::InvalidValue { what, .. }) => assert_eq!(what, "disturbance.push.reach_m"),
        other => panic!("{:?}", other.map(|_| ())),
    }
    let bad = DisturbanceParams {
        slip: SlipParams {
            patches: vec![SlipPatch {
                min: [1.0, 1.0],
                max: [0.5, 2.0],
            }],
            ..SlipParams::default()
        },
        ..DisturbanceParams::default()
    };
    match sim.with_disturbances(bad) {
        Err(Error::InvalidValue { what, .. }) => assert_eq!(what, "disturbance.slip.patches[0].max[0]"),
        other => panic!("{:?}", other.map(|_| ())),
    }
    // From TOML, unknown fields are refused and missing ones default.
    let p: DisturbanceParams =
        toml::from_str("[push]\nrate_per_person_s = 0.1\n[surround]\ngroup_min = 2").unwrap();
    assert_eq!(p.push.rate_per_person_s, 0.1);
    assert_eq!(p.push.reach_m, 0.4);
    assert_eq!(p.surround.group_min, 2);
    assert!(toml::from_str::<DisturbanceParams>("[push]\nrate = 0.1").is_err());
    let p: DisturbanceParams = toml::from_str("[[slip.patches]]\nmin = [1, 2]\nmax = [3, 4]").unwrap();
    assert_eq!(p.slip.patches[0].max, [3.0, 4.0]);
}
