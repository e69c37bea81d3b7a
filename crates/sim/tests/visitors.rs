//! Museum visitors and the robot: with an interest rate, people come to a
//! standing robot, stand around it (not all on one side), leave when their
//! time is up, and leave when the robot asks them to step aside.

use std::f64::consts::{FRAC_PI_2, TAU};

use robot::{Command, Controller, Notes, Perception, Pose, Request, Step, Vec2};
use sim::{
    Activity, Cell, CellIndex, CrowdParams, CrowdSize, OccupancyGrid, RobotParams, RunParams, Simulation,
    Task, World,
};

/// The robot stands in the middle of the room.
const ROBOT_AT: Vec2 = Vec2 { x: 6.0, y: 6.0 };

/// An open 12 m × 12 m room at 0.05 m, walls around, an exhibit near each
/// corner; people take an interest in the robot at `rate_per_s`, stand by
/// it for `linger_mean_s` on average.
fn museum(rate_per_s: f64, linger_mean_s: f64) -> World {
    let n = 240;
    let mut g = OccupancyGrid::new(n as usize, n as usize, 0.05, Pose::default());
    for k in 0..n {
        for (i, j) in [(k, 0), (k, n - 1), (0, k), (n - 1, k)] {
            g.set(CellIndex { i, j }, Cell::Occupied);
        }
    }
    World::new(g)
        .with_crowd(CrowdParams {
            size: CrowdSize::Count { people: 12 },
            waypoints: vec![
                Vec2::new(2.0, 2.0),
                Vec2::new(10.0, 2.0),
                Vec2::new(2.0, 10.0),
                Vec2::new(10.0, 10.0),
            ],
            robot_interest_rate_per_s: rate_per_s,
            robot_linger_mean_s: linger_mean_s,
            ..CrowdParams::default()
        })
        .unwrap()
}

/// Stands still; from `ask_from_s` on asks the people within 1.5 m to step
/// aside, every tick (as a blocked robot keeps asking).
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
        (self.now_s >= self.ask_from_s).then_some(Request::StepAside { radius_m: 1.5 })
    }
}

/// A Jinny-like robot (radius 0.35 m) standing at [`ROBOT_AT`].
fn standing_robot(world: &World, seed: u64) -> Simulation {
    let task = Task {
        start: Pose::new(ROBOT_AT.x, ROBOT_AT.y, 0.0),
        goal: None,
    };
    let run = RunParams {
        time_limit_s: 1e9,
        ..RunParams::default()
    };
    Simulation::new(world, RobotParams::jinny(), run, task, seed).unwrap()
}

/// Bearings (from the robot) of the people standing by it within 1.2 m.
fn bearings_of_people_at_the_robot(sim: &Simulation) -> Vec<f64> {
    sim.crowd()
        .people()
        .iter()
        .filter(|q| matches!(q.activity, Activity::AtRobot { .. }) && q.position.dist(ROBOT_AT) <= 1.2)
        .map(|q| (q.position.y - ROBOT_AT.y).atan2(q.position.x - ROBOT_AT.x))
        .collect()
}

/// How many of the four quadrants around the robot hold someone.
fn quadrants(bearings: &[f64]) -> usize {
    let mut seen = [false; 4];
    for &a in bearings {
        seen[((a.rem_euclid(TAU) / FRAC_PI_2) as usize).min(3)] = true;
    }
    seen.iter().filter(|&&s| s).count()
}

/// The widest angle around the robot with nobody in it, radians (more than
/// π: everybody on one side).
fn widest_gap_rad(bearings: &[f64]) -> f64 {
    let mut a: Vec<f64> = bearings.iter().map(|b| b.rem_euclid(TAU)).collect();
    a.sort_by(f64::total_cmp);
    let wrap = a.first().map_or(TAU, |f| f + TAU - a[a.len() - 1]);
    a.windows(2).map(|w| w[1] - w[0]).fold(wrap, f64::max)
}

/// Nobody overlaps the robot's footprint (nor comes within the clearance)
/// or anybody else.
fn assert_apart(sim: &Simulation) {
    let people = sim.crowd().people();
    let r = sim.crowd().radius_m();
    let keep = r + sim.robot().drive.radius_m + sim.world().crowd().robot_clearance_m;
    for (k, a) in people.iter().enumerate() {
        assert!(
            a.position.dist(ROBOT_AT) >= keep - 1e-9,
            "person {k} at {:?} within the robot's clearance at {} s",
            a.position,
            sim.time_s()
        );
        for b in &people[k + 1..] {
            assert!(
                a.position.dist(b.position) >= 2.0 * r - 1e-9,
                "people overlap at {} s",
                sim.time_s()
            );
        }
    }
}

#[test]
fn visitors_come_stand_around_the_robot_and_leave_when_their_time_is_up() {
    let world = museum(0.2, 20.0);
    let mut sim = standing_robot(&world, 3);
    let mut stand = Stand {
        ask_from_s: f64::INFINITY,
        now_s: 0.0,
    };
    let n = sim.crowd().people().len();
    // Per person: when the current visit ends, while standing by the robot.
    let mut until: Vec<Option<f64>> = vec![None; n];
    // Per person who has just left the robot: how far from it they were.
    let mut left_from: Vec<Option<f64>> = vec![None; n];
    let (mut visits, mut departures, mut went_away) = (0, 0, 0);
    // The most people standing by the robot within a minute, with their
    // bearings from it.
    let mut most: Vec<f64> = Vec::new();
    // Ticks with at least four people standing by the robot; of those,
    // ticks when they surround it (no empty half-plane), ticks when they
    // hold three quadrants.
    let (mut crowded, mut surrounded, mut three_quadrants) = (0, 0, 0);
    for tick in 1..=2000 {
        sim.tick(&mut stand);
        assert_eq!(sim.outcome(), None);
        assert_apart(&sim);
        let t = sim.time_s();
        for (k, q) in sim.crowd().people().iter().enumerate() {
            let d = q.position.dist(ROBOT_AT);
            match (q.activity, until[k]) {
                (Activity::AtRobot { until_s }, None) => {
                    // Stopped within 0.9 m, then one step of their own.
                    assert!(d <= 1.2, "person {k} stopped at {d} m");
                    until[k] = Some(until_s);
                    visits += 1;
                }
                (Activity::AtRobot { until_s }, Some(u)) => assert_eq!(until_s, u),
                (a, Some(u)) => {
                    // They leave at the first step past their time, for a
                    // new exhibit.
                    assert!(
                        t >= u && t - u < 0.1 + 1e-9,
                        "person {k} left at {t} s, due at {u} s"
                    );
                    assert!(
                        matches!(a, Activity::Walking { .. }) && q.waypoint.is_some(),
                        "{a:?}"
                    );
                    until[k] = None;
                    left_from[k] = Some(d);
                    departures += 1;
                }
                (_, None) => {}
            }
            if q.activity.with_robot() {
                left_from[k] = None;
            } else if left_from[k].is_some_and(|from| d > from + 2.0) {
                went_away += 1;
                left_from[k] = None;
            }
        }
        let b = bearings_of_people_at_the_robot(&sim);
        if tick <= 600 && b.len() > most.len() {
            most = b.clone();
        }
        if b.len() >= 4 {
            crowded += 1;
            surrounded += usize::from(widest_gap_rad(&b) < std::f64::consts::PI);
            three_quadrants += usize::from(quadrants(&b) >= 3);
        }
    }
    // Within a minute several people stand by the robot, all around it.
    assert!(most.len() >= 4, "at most {} people by the robot", most.len());
    assert!(quadrants(&most) >= 3, "{most:?}");
    assert!(widest_gap_rad(&most) < std::f64::consts::PI, "{most:?}");
    // And so most of the time.
    assert!(crowded > 1000, "{crowded} ticks with four people by the robot");
    assert!(
        surrounded as f64 >= 0.9 * crowded as f64,
        "{surrounded} of {crowded}"
    );
    assert!(
        three_quadrants as f64 >= 0.95 * crowded as f64,
        "{three_quadrants} of {crowded}"
    );
    // Visits end when due; at 0.2/s many visitors take an interest again
    // before they are far, but many walk away first.
    assert!(
        departures >= 40 && visits >= departures,
        "{visits} visits, {departures} departures"
    );
    assert!(
        4 * went_away >= departures,
        "{went_away} of {departures} walked away"
    );
}

#[test]
fn asked_to_step_aside_visitors_leave() {
    // Visitors who would stand by the robot for ever; from 60 s on the
    // robot asks those within 1.5 m to step aside (or, for comparison,
    // never asks).
    let world = museum(0.2, 1e9);
    let run = |ask_from_s: f64| {
        let mut sim = standing_robot(&world, 3);
        let mut stand = Stand {
            ask_from_s,
            now_s: 0.0,
        };
        let n = sim.crowd().people().len();
        let mut by_robot = Vec::new();
        let mut went_aside = vec![false; n];
        let mut near = 0;
        for tick in 1..=750 {
            sim.tick(&mut stand);
            assert_apart(&sim);
            let people = sim.crowd().people();
            if tick == 600 {
                by_robot = (0..n)
                    .filter(|&k| matches!(people[k].activity, Activity::AtRobot { .. }))
                    .collect();
            }
            if tick > 600 {
                for (k, q) in people.iter().enumerate() {
                    went_aside[k] |= !q.activity.with_robot() && q.position.dist(ROBOT_AT) > 2.0;
                }
            }
            if tick > 650 {
                near += people.iter().filter(|q| q.position.dist(ROBOT_AT) < 1.5).count();
            }
        }
        let stayed = by_robot
            .iter()
            .filter(|&&k| matches!(sim.crowd().people()[k].activity, Activity::AtRobot { .. }))
            .count();
        let went_aside = by_robot.iter().filter(|&&k| went_aside[k]).count();
        (by_robot.len(), stayed, went_aside, near as f64 / 100.0)
    };
    let (standing, stayed, went_aside, near) = run(f64::INFINITY);
    assert!(standing >= 6, "{standing} people by the robot");
    assert_eq!((stayed, went_aside), (standing, 0), "they stand for ever");
    assert!(near >= standing as f64, "{near} people near the robot on average");
    let (standing_asked, _, went_aside, near_asked) = run(60.0);
    assert_eq!(standing_asked, standing, "the same run until asked");
    // Everyone went aside, though at 0.2/s some take an interest again
    // and come back (to be asked again).
    assert_eq!(went_aside, standing);
    assert!(
        near_asked < 0.5 * near,
        "{near_asked} people near the robot on average, {near} unasked"
    );
}
