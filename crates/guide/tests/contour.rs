//! Contour tracking in small worlds, on the simulator's Jinny-like robot
//! (laser 0.2 m ahead of the centre, 180° field of view): the set distance
//! is held along straight walls and around concave and convex corners.

use guide::{ContourParams, ContourTracker, Side};
use robot::{Controller, Notes, Perception, Pose, Step, Vec2};
use sim::{Cell, CellIndex, OccupancyGrid, RobotParams, RunParams, Simulation, Task, World};

/// Marks the cells of the rectangle `[x0, x1] × [y0, y1]` (metres) occupied.
fn block(g: &mut OccupancyGrid, x0: f64, y0: f64, x1: f64, y1: f64) {
    let r = g.resolution_m();
    for j in (y0 / r).round() as i64..(y1 / r).round() as i64 {
        for i in (x0 / r).round() as i64..(x1 / r).round() as i64 {
            g.set(CellIndex { i, j }, Cell::Occupied);
        }
    }
}

/// A room of `w × h` metres with 0.1 m walls inside its border.
fn room(w: f64, h: f64) -> OccupancyGrid {
    let mut g = OccupancyGrid::new(
        (w / 0.05).round() as usize,
        (h / 0.05).round() as usize,
        0.05,
        Pose::default(),
    );
    block(&mut g, 0.0, 0.0, w, 0.1);
    block(&mut g, 0.0, h - 0.1, w, h);
    block(&mut g, 0.0, 0.0, 0.1, h);
    block(&mut g, w - 0.1, 0.0, w, h);
    g
}

/// Follows the contour on one side for ever (the goal is never sought).
struct Follower(ContourTracker);

impl Controller for Follower {
    fn step(&mut self, p: &Perception, _notes: &mut Notes) -> Step {
        let s = self.0.step(
            &p.lasers[0],
            p.odometry,
            p.odometry,
            Vec2::new(1e6, 1e6),
            p.time_s,
        );
        Step::Run(s.command)
    }
}

/// Runs the follower for `seconds` from `start`; returns the true distance
/// from the robot's centre to the nearest wall at every tick after the
/// first `settle_s` seconds, and the path length.
fn lap(world: &World, start: Pose, side: Side, seconds: f64, settle_s: f64) -> (Vec<(f64, Pose)>, f64) {
    let run = RunParams {
        time_limit_s: seconds,
        ..RunParams::default()
    };
    let task = Task { start, goal: None };
    let mut sim = Simulation::new(world, RobotParams::jinny(), run, task, 11).unwrap();
    let mut c = Follower(ContourTracker::following(ContourParams::default(), side).unwrap());
    let mut out = Vec::new();
    while sim.tick(&mut c).is_none() {
        if sim.time_s() > settle_s {
            out.push((
                world.distance_field().distance_m(sim.pose().position()),
                sim.pose(),
            ));
        }
    }
    let r = sim.result();
    eprintln!(
        "path {:.2} m in {:.1} s, end {:?}",
        r.path_length_m, r.time_s, r.final_pose
    );
    assert_eq!(r.collisions, 0, "no contact");
    (out, r.path_length_m)
}

fn check(name: &str, distances: &[(f64, Pose)], want: f64) {
    let (lo, hi) = distances
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &(d, _)| {
            (a.min(d), b.max(d))
        });
    let worst = distances
        .iter()
        .max_by(|a, b| (a.0 - want).abs().total_cmp(&(b.0 - want).abs()))
        .unwrap();
    eprintln!(
        "{name}: distance in [{lo:.3}, {hi:.3}] over {} ticks",
        distances.len()
    );
    assert!(
        lo >= want - 0.10 && hi <= want + 0.10,
        "{name}: distance to the contour in [{lo:.3}, {hi:.3}] m, wanted {want} ± 0.10 (worst at {:?})",
        worst.1
    );
}

#[test]
fn along_straight_walls_and_around_concave_corners() {
    // Inside a 9 m × 6 m room, wall on the right: four concave corners.
    let world = World::new(room(9.0, 6.0));
    let d = ContourParams::default().distance_m;
    let start = Pose::new(2.0, 0.1 + d, 0.0);
    let (dist, path) = lap(&world, start, Side::Right, 75.0, 2.0);
    // A lap of the inner rectangle at d from the walls is about 23.6 m.
    assert!(path > 23.0, "went round the room: {path:.1} m");
    check("room", &dist, d);
}

#[test]
fn around_convex_corners() {
    // A 3 m × 2 m block in a 12 m × 10 m room, kept on the left.
    let mut g = room(12.0, 10.0);
    block(&mut g, 4.5, 4.0, 7.5, 6.0);
    let world = World::new(g);
    let d = ContourParams::default().distance_m;
    let start = Pose::new(5.0, 4.0 - d, 0.0);
    let (dist, path) = lap(&world, start, Side::Left, 60.0, 2.0);
    // Round the block: 2 (3 + 2) m of sides plus a circle of radius d.
    assert!(
        path > 2.0 * 5.0 + 2.0 * std::f64::consts::PI * d - 1.0,
        "{path:.1} m"
    );
    check("block", &dist, d);
}

#[test]
fn centred_in_a_corridor() {
    // A 1.9 m wide corridor, 14 m long: the robot keeps to the middle.
    let mut g = room(16.0, 6.0);
    block(&mut g, 0.0, 0.0, 16.0, 2.0);
    block(&mut g, 0.0, 3.9, 16.0, 6.0);
    let world = World::new(g);
    let start = Pose::new(1.0, 2.6, 0.0);
    let (dist, _) = lap(&world, start, Side::Left, 30.0, 4.0);
    let middle = 0.95;
    let along: Vec<(f64, Pose)> = dist.into_iter().filter(|(_, p)| p.x_m < 14.5).collect();
    check("corridor", &along, middle);
}

/// Seeks `goal` (the odometry as the pose estimate); counts the cycles in
/// which the tracker asked people to step aside and in which it was
/// passing a gap.
struct Seeker {
    tracker: ContourTracker,
    goal: Vec2,
    asked: usize,
    in_gap: usize,
    request: Option<robot::Request>,
}

impl Controller for Seeker {
    fn step(&mut self, p: &Perception, _notes: &mut Notes) -> Step {
        let s = self
            .tracker
            .step(&p.lasers[0], p.odometry, p.odometry, self.goal, p.time_s);
        self.asked += usize::from(s.request.is_some());
        self.in_gap += usize::from(s.gap);
        self.request = s.request;
        // The simulator ends the run at the goal, by the true position.
        Step::Run(s.command)
    }

    fn request(&self) -> Option<robot::Request> {
        self.request
    }
}

/// Runs a seeker from `start` to `goal` for at most `seconds`; returns it
/// and the run's result.
fn seek(world: &World, start: Pose, goal: Vec2, seconds: f64) -> (Seeker, sim::RunResult) {
    let run = RunParams {
        time_limit_s: seconds,
        ..RunParams::default()
    };
    let task = Task {
        start,
        goal: Some(goal),
    };
    let mut sim = Simulation::new(world, RobotParams::jinny(), run, task, 5).unwrap();
    let mut c = Seeker {
        tracker: ContourTracker::new(ContourParams::default()).unwrap(),
        goal,
        asked: 0,
        in_gap: 0,
        request: None,
    };
    while sim.tick(&mut c).is_none() {}
    let r = sim.result();
    eprintln!(
        "{:?} in {:.1} s, path {:.2} m, asked {} cycles, {} in a gap, clearance {:.3} m",
        r.outcome, r.time_s, r.path_length_m, c.asked, c.in_gap, r.min_clearance_m
    );
    (c, r)
}

/// An 8 m × 4 m room split at x = 4 m by a wall with a door of `width_m`
/// centred on y = 2 m.
fn room_with_door(width_m: f64) -> World {
    let mut g = room(8.0, 4.0);
    block(&mut g, 4.0, 0.0, 4.1, 2.0 - width_m / 2.0);
    block(&mut g, 4.0, 2.0 + width_m / 2.0, 4.1, 4.0);
    World::new(g)
}

/// Seeks `goal` from `start` through the 0.80 m door of
/// [`room_with_door`]: the goal is reached without contact, the door passed
/// as a gap, and the clearance stays above `min_clearance_m`.
fn passes_door(start: Pose, goal: Vec2, min_clearance_m: f64) {
    let world = room_with_door(0.8);
    let (c, r) = seek(&world, start, goal, 120.0);
    assert_eq!(r.outcome, Some(sim::Outcome::Goal), "through the door");
    assert_eq!(r.collisions, 0, "no contact");
    assert!(c.in_gap > 0, "passed as a gap");
    assert!(
        r.min_clearance_m > min_clearance_m,
        "clearance {:.3} m",
        r.min_clearance_m
    );
}

#[test]
fn a_door_0_80_m_wide_is_passed_without_contact() {
    // 0.80 m for a 0.70 m robot: 5 cm either side when centred. The robot
    // starts 0.3 m off the door's axis and crooked, and must centre.
    passes_door(Pose::new(1.0, 2.3, -0.2), Vec2::new(7.0, 1.8), 0.01);
}

#[test]
fn a_door_approached_obliquely_from_beside_its_wall_is_passed_without_contact() {
    // The robot starts 0.65 m before the door's wall and 1.4 m off its
    // axis, heading across it: the jamb on its side leaves the laser's view
    // while it turns in, so it must be on the line before its footprint
    // gets there (the look-ahead shortens near the sides; with a fixed
    // 0.25 m the robot stopped 3 mm from that jamb and never got through).
    // Centred: 5 cm either side at most; 4.7 cm measured.
    passes_door(Pose::new(3.0, 3.4, -0.5), Vec2::new(7.0, 2.0), 0.035);
}

#[test]
fn a_door_narrower_than_the_robot_is_not_entered() {
    // 0.66 m: no way through; the robot must not touch the jambs trying.
    let world = room_with_door(0.66);
    let (_, r) = seek(&world, Pose::new(1.0, 2.0, 0.0), Vec2::new(7.0, 2.0), 60.0);
    assert_ne!(r.outcome, Some(sim::Outcome::Goal));
    assert_eq!(r.collisions, 0, "no contact");
}

#[test]
fn a_person_standing_in_the_way_is_asked_to_step_aside() {
    // A visitor lingering on the straight line to the goal in an open room.
    let person = Vec2::new(4.0, 3.0);
    let world = World::new(room(10.0, 6.0))
        .with_crowd(sim::CrowdParams {
            waypoints: vec![person],
            linger_probability: 1.0,
            linger_mean_s: 1e4,
            keep_clear_m: 0.5,
            positions: vec![person],
            ..sim::CrowdParams::default()
        })
        .unwrap();
    let (c, r) = seek(&world, Pose::new(1.5, 3.0, 0.0), Vec2::new(8.5, 3.0), 90.0);
    assert!(c.asked > 0, "asked the visitor to step aside");
    assert_eq!(r.outcome, Some(sim::Outcome::Goal));
    assert_eq!(r.collisions, 0);
}

/// A real map of `maps/`, as a world without people.
fn real_map(name: &str) -> World {
    let path = format!("{}/../../maps/{name}/{name}.yaml", env!("CARGO_MANIFEST_DIR"));
    World::new(sim::map_server::load(path).expect("the map loads").grid)
}

#[test]
fn building_31_the_way_out_of_the_room_south_of_the_middle_corridor() {
    // From middle_corridor_south to hall_north (maps/building_31/places.yaml)
    // on the real map, dead-reckoning only (no localizer): the robot must
    // leave the room through the 1.05 m passage between the long wall's end
    // and a low wall, following a box and the wall's end on its left while
    // heading at the low wall (module docs, passages). Before the passage
    // rule it turned back at the low wall and crept along the room's
    // furniture until the limit (200 s, 869 cycles in gaps, 1.3 cm from a
    // wall); with it, the goal in 84.9 s.
    let world = real_map("building_31");
    let (_, r) = seek(
        &world,
        Pose::new(-10.85, 3.2, -std::f64::consts::FRAC_PI_2),
        Vec2::new(-1.3, 14.0),
        200.0,
    );
    assert_eq!(r.outcome, Some(sim::Outcome::Goal), "out of the room to the hall");
    assert_eq!(r.collisions, 0, "no contact");
}

#[test]
fn levine_a_goal_behind_the_robot_is_faced_before_the_side_is_chosen() {
    // From south_west_end, arriving there facing south as a tour does, to
    // south_west (maps/levine/places.yaml): the goal is behind on the left,
    // round the corner to the north. Turning towards it, the robot faced
    // the corridor's wall, and its way "to the goal" counted as blocked
    // 20° into the turn: it followed the corridor south, round the loop,
    // and arrived after 130–180 s or not at all (2 of 9 tours). The side
    // is now chosen facing the goal, after the stop to ask (module docs,
    // the leave rule).
    let world = real_map("levine");
    let (_, r) = seek(
        &world,
        Pose::new(-13.65, -4.24, -std::f64::consts::FRAC_PI_2),
        Vec2::new(-8.0, -0.15),
        60.0,
    );
    assert_eq!(r.outcome, Some(sim::Outcome::Goal), "round the corner");
    assert_eq!(r.collisions, 0, "no contact");
}
