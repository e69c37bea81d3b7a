//! Routes with a map that has no way to the goal (issue 13: routes in the
//! office failed when a transition left the robot off the net): the route
//! follower heads for the goal place's map position, goes round what blocks
//! the way, and turns on the goal's spot to recognise it.

use nav::topo::{FuzzyPetriNet, NavState, NavigateParams, Place, PlaceKind, RouteFollower};
use robot::Pose;
use sim::shapes::{SegmentSpec, WorldSpec};
use sim::{RobotParams, RunParams, Simulation, Task, World};

fn wall(from: [f64; 2], to: [f64; 2]) -> SegmentSpec {
    SegmentSpec {
        from,
        to,
        thickness: 0.1,
    }
}

/// Two rooms of 4 m × 4 m side by side (x 1–5 and 5–9, y 1–5), joined by
/// a 1.2 m door at the north end of the wall between them (y 3.8–5).
fn two_rooms() -> World {
    let mut spec = WorldSpec::new(10.0, 6.0, 0.05);
    spec.segments = vec![
        wall([1.0, 1.0], [9.0, 1.0]),
        wall([9.0, 1.0], [9.0, 5.0]),
        wall([9.0, 5.0], [1.0, 5.0]),
        wall([1.0, 5.0], [1.0, 1.0]),
        wall([5.0, 1.0], [5.0, 3.8]),
    ];
    World::new(spec.rasterise().unwrap())
}

/// A map of two places and no transition: `start` facing the west wall of
/// the west room, `goal` facing the east wall of the east room (both in
/// the middle of a wall: type (c)).
fn map() -> FuzzyPetriNet {
    let mut map = FuzzyPetriNet::new();
    map.add_place(Place::new(1.6, 3.0, std::f64::consts::PI, PlaceKind::C))
        .unwrap();
    map.add_place(Place::new(8.4, 3.0, 0.0, PlaceKind::C)).unwrap();
    map
}

/// Drives from place 0 to place 1 for at most `time_s`; how it ended, the
/// true distance to the goal's position, and the follower.
fn drive(params: NavigateParams, seed: u64, time_s: f64) -> (NavState, f64, RouteFollower) {
    let world = two_rooms();
    let map = map();
    let (start, goal) = (map.place_ids().next().unwrap(), map.place_ids().nth(1).unwrap());
    let task = Task {
        start: Pose::new(1.6, 3.0, std::f64::consts::PI),
        goal: None,
    };
    let mut robot = RobotParams::sonar_ring();
    robot.odometry.large_slip_probability = 0.0;
    let run = RunParams {
        time_limit_s: time_s,
        collision_fatal: false,
        ..RunParams::default()
    };
    let mut sim = Simulation::new(&world, robot, run, task, seed).unwrap();
    let mut follower = RouteFollower::new(map, start, &[goal], params, seed).unwrap();
    while sim.tick(&mut follower).is_none() && follower.state() == NavState::Going {}
    let d = sim.pose().position().dist(robot::Vec2::new(8.4, 3.0));
    (follower.state(), d, follower)
}

#[test]
fn off_the_net_the_robot_heads_for_the_goal_round_the_wall_and_recognises_it() {
    for seed in [1, 2, 3] {
        let (state, d, follower) = drive(NavigateParams::default(), seed, 240.0);
        assert_eq!(state, NavState::Arrived, "seed {seed}: {:?}", follower.stats());
        assert!(d <= 0.5, "seed {seed}: arrived {d:.2} m from the goal");
        let stats = follower.stats();
        assert!(stats.homings >= 2, "seed {seed}: {stats:?}");
    }
}

/// What the route follower did before (issue 13): untried actions at
/// random from a place without a route. The same drive rarely arrives.
#[test]
fn without_homing_the_robot_wanders() {
    let params = NavigateParams {
        homing: false,
        ..NavigateParams::default()
    };
    let arrived = [1, 2, 3, 4, 5, 6]
        .into_iter()
        .filter(|&seed| drive(params, seed, 240.0).0 == NavState::Arrived)
        .count();
    eprintln!("arrived {arrived}");
    assert!(arrived <= 2, "{arrived} of 6 arrived without homing");
}
