//! Same seed, same run, bit for bit — alone, or in rayon pools of 1 and 2
//! threads; different seeds, different runs.

use rayon::prelude::*;
use robot::{Command, Controller, Notes, Perception, Pose, Step, Vec2};
use sim::{CrowdParams, CrowdSize, RobotParams, RunParams, Simulation, Task, TraceParams, World, generators};

/// A reactive wanderer on the laser (or the sonar when there is no laser),
/// annotating its choices.
struct Wander;

impl Controller for Wander {
    fn step(&mut self, p: &Perception, notes: &mut Notes) -> Step {
        let front = match p.lasers.first() {
            Some(scan) => {
                let n = scan.ranges_m.len();
                scan.ranges_m[n / 3..2 * n / 3]
                    .iter()
                    .filter(|x| !x.is_nan())
                    .fold(f64::INFINITY, |a, &b| a.min(b))
            }
            None => p.sonar.iter().map(|s| s.range_m).fold(f64::INFINITY, f64::min),
        };
        notes.value("front_m", front.min(100.0));
        if front < 0.8 || p.bumper {
            notes.behaviour("turn");
            notes.event(robot::Event::new("blocked", p.time_s));
            Step::Run(Command::Twist {
                v_mps: 0.0,
                omega_radps: 1.0,
            })
        } else {
            notes.behaviour("forward");
            Step::Run(Command::Twist {
                v_mps: 0.4,
                omega_radps: 0.1,
            })
        }
    }
}

fn office_world() -> World {
    office_world_with_visitors(0.0)
}

/// The office, its people taking an interest in the robot at `rate_per_s`.
fn office_world_with_visitors(rate_per_s: f64) -> World {
    World::new(generators::building_31_like())
        .with_crowd(CrowdParams {
            size: CrowdSize::Count { people: 30 },
            waypoints: vec![Vec2::new(5.0, 10.8), Vec2::new(18.0, 16.0), Vec2::new(30.0, 21.6)],
            linger_mean_s: 5.0,
            robot_interest_rate_per_s: rate_per_s,
            robot_linger_mean_s: 5.0,
            ..CrowdParams::default()
        })
        .unwrap()
}

/// The whole observable record of a run, as text (`Debug` prints every
/// `f64` exactly, NaN included).
fn run(world: &World, robot: &RobotParams, seed: u64) -> String {
    let task = Task {
        start: Pose::new(2.0, 10.8, 0.0),
        goal: Some(Vec2::new(30.0, 21.6)),
    };
    let params = RunParams {
        time_limit_s: 20.0,
        collision_fatal: false,
        trace: TraceParams::full(),
        ..RunParams::default()
    };
    let mut sim = Simulation::new(world, robot.clone(), params, task, seed).unwrap();
    let result = sim.run(&mut Wander);
    let trace = sim.take_trace().unwrap();
    assert_eq!(trace.ticks.len() as u64, result.ticks);
    format!("{result:?}\n{trace:?}\n{:?}", sim.crowd().people())
}

fn robots() -> Vec<RobotParams> {
    let mut both = RobotParams::jinny();
    both.sonar = sim::SonarParams::default();
    both.ir = sim::IrParams::default();
    vec![RobotParams::jinny(), RobotParams::aibot(), both]
}

#[test]
fn same_seed_same_trace_on_any_thread_count() {
    let world = office_world();
    let seeds: Vec<u64> = (1..=4).collect();
    for robot in robots() {
        let alone: Vec<String> = seeds.iter().map(|&s| run(&world, &robot, s)).collect();
        for threads in [1, 2] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let pooled: Vec<String> =
                pool.install(|| seeds.par_iter().map(|&s| run(&world, &robot, s)).collect());
            for (k, (a, b)) in alone.iter().zip(&pooled).enumerate() {
                assert!(a == b, "seed {} differs with {threads} threads", seeds[k]);
            }
        }
        // Different seeds, different runs.
        for k in 1..alone.len() {
            assert_ne!(alone[0], alone[k]);
        }
    }
}

#[test]
fn same_seed_same_trace_with_visitors_on_any_thread_count() {
    // People come to see the robot (and follow it while it wanders).
    let world = office_world_with_visitors(0.5);
    let seeds: Vec<u64> = (1..=4).collect();
    let robot = RobotParams::jinny();
    let alone: Vec<String> = seeds.iter().map(|&s| run(&world, &robot, s)).collect();
    assert!(
        alone.iter().any(|r| r.contains("AtRobot")),
        "nobody came to the robot"
    );
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let pooled: Vec<String> =
            pool.install(|| seeds.par_iter().map(|&s| run(&world, &robot, s)).collect());
        for (k, (a, b)) in alone.iter().zip(&pooled).enumerate() {
            assert!(a == b, "seed {} differs with {threads} threads", seeds[k]);
        }
    }
    for k in 1..alone.len() {
        assert_ne!(alone[0], alone[k]);
    }
    // The visitors change the run.
    assert_ne!(alone[0], run(&office_world(), &robot, seeds[0]));
}

#[test]
fn adding_a_sensor_does_not_change_the_people() {
    // Each subsystem draws from its own stream of the run's seed.
    let world = office_world();
    let people = |robot: RobotParams| {
        let task = Task {
            start: Pose::new(2.0, 10.8, 0.0),
            goal: None,
        };
        let sim = Simulation::new(&world, robot, RunParams::default(), task, 77).unwrap();
        format!("{:?}", sim.crowd().people())
    };
    let mut with_sonar = RobotParams::jinny();
    with_sonar.sonar = sim::SonarParams::default();
    assert_eq!(people(RobotParams::jinny()), people(with_sonar));
}

#[test]
fn the_trace_is_json_lines_and_off_by_default() {
    let world = office_world();
    let task = Task {
        start: Pose::new(2.0, 10.8, 0.0),
        goal: None,
    };
    let off = RunParams {
        time_limit_s: 1.0,
        ..RunParams::default()
    };
    let mut sim = Simulation::new(&world, RobotParams::jinny(), off, task, 3).unwrap();
    sim.run(&mut Wander);
    assert!(sim.trace().is_none());

    let on = RunParams {
        trace: TraceParams::poses(),
        ..off
    };
    let mut sim = Simulation::new(&world, RobotParams::jinny(), on, task, 3).unwrap();
    sim.run(&mut Wander);
    let trace = sim.take_trace().unwrap();
    let mut out = Vec::new();
    trace.write_json_lines(&mut out).unwrap();
    let text = String::from_utf8(out).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 10);
    let first: serde_json::Value = serde_json::from_str(lines[0]).unwrap();
    assert_eq!(first["tick"], 0);
    assert_eq!(first["behaviour"], "forward");
    assert!(first["values"][0][0] == "front_m");
    assert!(first.get("perception").is_none(), "perception not asked for");
    assert_eq!(first["true_pose"]["x_m"], 2.0);
}

#[test]
fn runs_can_move_between_threads() {
    fn send_and_sync<T: Send + Sync>() {}
    send_and_sync::<Simulation>();
    send_and_sync::<World>();
}
