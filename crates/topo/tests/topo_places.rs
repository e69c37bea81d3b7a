//! Reference places in small hand-made worlds: the ring robot drives a
//! strategy until an obstacle stops it, and the stop is classified — a
//! corner of each kind, a dead end, a T junction, a free-standing obstacle
//! (issue: "types and the concavity flag are right in small hand-made
//! worlds").

use robot::{Command, Controller, Notes, Perception, Pose, Step};
use sim::shapes::{CircleSpec, SegmentSpec, WorldSpec};
use sim::{RobotParams, RunParams, Simulation, Task, World};
use topo::Executor;
use topo::{PlaceKind, Progress, Ring, Situation, SituationParams, Strategy, StrategyParams, Turn};

/// Plays one transition; remembers the situation where it stopped.
struct Play {
    executor: Executor,
    situation: Option<Situation>,
    failed: bool,
}

impl Controller for Play {
    fn step(&mut self, p: &Perception, _notes: &mut Notes) -> Step {
        let ring = Ring::of(p);
        let (l, r) = p.wheel_speeds_mps;
        let stopped = l.abs() < 0.01 && r.abs() < 0.01;
        match self.executor.step(&ring, p.odometry.theta_rad, stopped, 0.1) {
            Progress::Drive(c) => Step::Run(c),
            Progress::Arrived => {
                if self.situation.is_none() {
                    self.situation = Some(Situation::classify(&ring, &SituationParams::default()));
                }
                Step::Run(Command::Stop)
            }
            Progress::Failed(_) => {
                self.failed = true;
                Step::Run(Command::Stop)
            }
        }
    }
}

fn wall(from: [f64; 2], to: [f64; 2]) -> SegmentSpec {
    SegmentSpec {
        from,
        to,
        thickness: 0.1,
    }
}

fn world(segments: Vec<SegmentSpec>, circles: Vec<CircleSpec>) -> World {
    let mut spec = WorldSpec::new(10.0, 10.0, 0.05);
    spec.segments = segments;
    spec.circles = circles;
    World::new(spec.rasterise().unwrap())
}

/// Drives `strategy` from `start` (no exit turn) and returns where it
/// stopped: the situation and the true pose.
fn stop_at(world: &World, start: Pose, strategy: Strategy, seed: u64) -> (Situation, Pose) {
    let task = Task { start, goal: None };
    let mut sim =
        Simulation::new(world, RobotParams::sonar_ring(), RunParams::default(), task, seed).unwrap();
    let mut play = Play {
        executor: Executor::new(
            StrategyParams::default(),
            strategy,
            Turn::Straight,
            start.theta_rad,
        ),
        situation: None,
        failed: false,
    };
    for _ in 0..600 {
        let out = sim.tick(&mut play);
        assert!(out.is_none(), "run ended: {out:?} at {:?}", sim.pose());
        assert!(!play.failed, "the transition failed at {:?}", sim.pose());
        if let Some(s) = play.situation {
            return (s, sim.pose());
        }
    }
    panic!("no place within 60 s; at {:?}", sim.pose());
}

const N: f64 = std::f64::consts::FRAC_PI_2;

/// A 1.5 m corridor going north from y = 1 to y = 6, turning east (right)
/// at the top.
fn right_corner() -> World {
    world(
        vec![
            wall([3.0, 1.0], [3.0, 7.5]), // west wall, up to the top wall
            wall([3.0, 7.5], [9.0, 7.5]), // top wall
            wall([4.5, 1.0], [4.5, 6.0]), // east wall of the north leg
            wall([4.5, 6.0], [9.0, 6.0]), // south wall of the east leg
            wall([3.0, 1.0], [4.5, 1.0]), // closed bottom
        ],
        vec![],
    )
}

/// Its mirror image: turning west (left) at the top.
fn left_corner() -> World {
    world(
        vec![
            wall([7.0, 1.0], [7.0, 7.5]),
            wall([1.0, 7.5], [7.0, 7.5]),
            wall([5.5, 1.0], [5.5, 6.0]),
            wall([1.0, 6.0], [5.5, 6.0]),
            wall([5.5, 1.0], [7.0, 1.0]),
        ],
        vec![],
    )
}

/// A corridor north into an east–west corridor (a T).
fn t_junction() -> World {
    world(
        vec![
            wall([4.0, 1.0], [4.0, 6.0]),
            wall([5.5, 1.0], [5.5, 6.0]),
            wall([1.0, 6.0], [4.0, 6.0]),
            wall([5.5, 6.0], [9.0, 6.0]),
            wall([1.0, 7.5], [9.0, 7.5]),
            wall([4.0, 1.0], [5.5, 1.0]),
        ],
        vec![],
    )
}

/// A corridor closed at the top.
fn dead_end() -> World {
    world(
        vec![
            wall([4.0, 1.0], [4.0, 7.0]),
            wall([5.2, 1.0], [5.2, 7.0]),
            wall([4.0, 7.0], [5.2, 7.0]),
            wall([4.0, 1.0], [5.2, 1.0]),
        ],
        vec![],
    )
}

/// An open room with a pillar in the middle.
fn pillar() -> World {
    world(
        vec![
            wall([0.5, 0.5], [9.5, 0.5]),
            wall([9.5, 0.5], [9.5, 9.5]),
            wall([9.5, 9.5], [0.5, 9.5]),
            wall([0.5, 9.5], [0.5, 0.5]),
        ],
        vec![CircleSpec {
            x: 5.0,
            y: 6.0,
            r: 0.4,
        }],
    )
}

fn check(world: &World, start: Pose, strategy: Strategy, kind: PlaceKind, concave: bool) {
    for seed in 1..=5 {
        let (s, at) = stop_at(world, start, strategy, seed);
        assert_eq!(
            (s.kind, s.concave),
            (kind, concave),
            "{strategy:?} from {start:?}, seed {seed}: stopped at {at:?} as {s:?}"
        );
    }
}

#[test]
fn a_corner_turning_right_is_type_a_and_concave() {
    check(
        &right_corner(),
        Pose::new(3.75, 2.0, N),
        Strategy::FreeMovement,
        PlaceKind::A,
        true,
    );
    check(
        &right_corner(),
        Pose::new(3.5, 2.0, N),
        Strategy::WallFollowLeft,
        PlaceKind::A,
        true,
    );
}

#[test]
fn a_corner_turning_left_is_type_b_and_concave() {
    check(
        &left_corner(),
        Pose::new(6.25, 2.0, N),
        Strategy::FreeMovement,
        PlaceKind::B,
        true,
    );
    check(
        &left_corner(),
        Pose::new(6.5, 2.0, N),
        Strategy::WallFollowRight,
        PlaceKind::B,
        true,
    );
}

#[test]
fn a_t_junction_is_type_c_and_not_concave() {
    check(
        &t_junction(),
        Pose::new(4.75, 2.0, N),
        Strategy::FreeMovement,
        PlaceKind::C,
        false,
    );
}

#[test]
fn a_dead_end_is_type_c_and_concave() {
    check(
        &dead_end(),
        Pose::new(4.6, 2.0, N),
        Strategy::FreeMovement,
        PlaceKind::C,
        true,
    );
    check(
        &dead_end(),
        Pose::new(4.5, 2.0, N),
        Strategy::WallFollowLeft,
        PlaceKind::C,
        true,
    );
}

#[test]
fn a_pillar_in_the_open_is_type_c_and_not_concave() {
    check(
        &pillar(),
        Pose::new(5.0, 2.0, N),
        Strategy::FreeMovement,
        PlaceKind::C,
        false,
    );
}
