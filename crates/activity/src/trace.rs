//! The behaviour activity trace and the dead-lock detector
//! (docs/activity-trace.md; Skrzypczyk).
//!
//! The trace is the time-ordered list of characteristic points `CP_k` — the
//! robot's position when event `k` happened:
//!
//! 1. navigation starts;
//! 2. *goal tracking* becomes the selected behaviour;
//! 3. *avoid front* becomes the selected behaviour while the heading error
//!    `ΔΘ < ε` (the obstacle sits on the straight course to the goal).
//!
//! A dead-lock is the chunk `CP2, CP3, CP2` at the end of the trace with all
//! three points inside a circle of radius `r_T` centred at their centroid.
//! Each detected dead-lock is recorded at that centroid.
//!
//! **Progress test (beyond the source).** A robot that slides slowly along
//! a wall towards a gap also produces `CP2, CP3, CP2` within `r_T`, while
//! it is in fact getting on. A dead-lock is a *return*: the chunk's last
//! `CP2` is no nearer the goal than its first. With
//! [`ActivityTrace::with_progress_test`], a chunk whose last `CP2` is more
//! than `progress_m` nearer the goal than its first is not a dead-lock.
//! Without it ([`ActivityTrace::new`]) the detector is the source's.
//!
//! The test is on by default for both controllers: a false dead-lock
//! costs more than a late one (its repulsion can close the only way
//! through for good — on the voting suite's narrow gap the source's
//! detector took success from 0.98 to 0.54), while the test lets a few
//! genuine dead-locks be recognised one loop later (figures and command:
//! `crates/activity/EXPERIMENTS.md`, section `trace.rs`).

use robot::Vec2;

/// The three characteristic events.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum Event {
    /// Navigation starts.
    Start,
    /// Goal tracking takes control.
    GoalTracking,
    /// Avoid front takes control with the goal straight ahead.
    BlockedAhead,
}

impl Event {
    /// The event's characteristic-point name, `"CP1"`, `"CP2"` or `"CP3"`.
    pub fn label(self) -> &'static str {
        match self {
            Event::Start => "CP1",
            Event::GoalTracking => "CP2",
            Event::BlockedAhead => "CP3",
        }
    }

    /// The event's number in the source (1, 2, 3).
    pub fn number(self) -> u8 {
        match self {
            Event::Start => 1,
            Event::GoalTracking => 2,
            Event::BlockedAhead => 3,
        }
    }
}

/// A characteristic point.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct CharacteristicPoint {
    /// Which event.
    pub event: Event,
    /// Where the robot was (odometry frame), metres.
    pub at: Vec2,
    /// Its distance to the goal then, metres (`f64::INFINITY` without a goal).
    pub goal_distance_m: f64,
    /// When, seconds.
    pub time_s: f64,
}

/// The activity trace with its dead-lock detector and buffer.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct ActivityTrace {
    points: Vec<CharacteristicPoint>,
    deadlocks: Vec<Vec2>,
    r_t_m: f64,
    progress_m: f64,
}

impl ActivityTrace {
    /// An empty trace whose detector is the source's: the chunk within
    /// radius `r_t_m`.
    pub fn new(r_t_m: f64) -> ActivityTrace {
        ActivityTrace {
            points: Vec::new(),
            deadlocks: Vec::new(),
            r_t_m,
            progress_m: f64::INFINITY,
        }
    }

    /// The same trace with the progress test (module docs): a chunk whose
    /// last `CP2` is more than `progress_m` nearer the goal than its first
    /// is not a dead-lock. `f64::INFINITY` turns the test off.
    pub fn with_progress_test(mut self, progress_m: f64) -> ActivityTrace {
        self.progress_m = progress_m;
        self
    }

    /// Appends an event at `at` (with the goal, if any, for the progress
    /// test); returns the centroid of a dead-lock if the trace now ends with
    /// one (and records it).
    pub fn record(&mut self, event: Event, at: Vec2, goal: Option<Vec2>, time_s: f64) -> Option<Vec2> {
        let goal_distance_m = goal.map_or(f64::INFINITY, |g| g.dist(at));
        self.points.push(CharacteristicPoint {
            event,
            at,
            goal_distance_m,
            time_s,
        });
        let d = detect(&self.points, self.r_t_m, self.progress_m)?;
        self.deadlocks.push(d);
        Some(d)
    }

    /// The characteristic points, oldest first.
    pub fn points(&self) -> &[CharacteristicPoint] {
        &self.points
    }

    /// The dead-locks detected so far (their centroids).
    pub fn deadlocks(&self) -> &[Vec2] {
        &self.deadlocks
    }
}

/// The dead-lock at the end of `points`, if the last three are `CP2, CP3,
/// CP2`, lie within `r_t_m` of their centroid, and the last `CP2` is at
/// most `progress_m` nearer the goal than the first (`f64::INFINITY`: no
/// progress test, the source's detector). Constant time.
pub fn detect(points: &[CharacteristicPoint], r_t_m: f64, progress_m: f64) -> Option<Vec2> {
    let [a, b, c] = points.get(points.len().checked_sub(3)?..)? else {
        return None;
    };
    if (a.event, b.event, c.event) != (Event::GoalTracking, Event::BlockedAhead, Event::GoalTracking) {
        return None;
    }
    if a.goal_distance_m - c.goal_distance_m > progress_m {
        return None;
    }
    let centroid = Vec2::new((a.at.x + b.at.x + c.at.x) / 3.0, (a.at.y + b.at.y + c.at.y) / 3.0);
    [a, b, c]
        .iter()
        .all(|p| p.at.dist(centroid) <= r_t_m)
        .then_some(centroid)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cp(event: Event, x: f64, y: f64) -> CharacteristicPoint {
        CharacteristicPoint {
            event,
            at: Vec2::new(x, y),
            goal_distance_m: f64::INFINITY,
            time_s: 0.0,
        }
    }

    #[test]
    fn chunk_within_the_radius_is_a_deadlock() {
        let pts = [
            cp(Event::Start, 0.0, 0.0),
            cp(Event::GoalTracking, 1.0, 1.0),
            cp(Event::BlockedAhead, 1.2, 1.1),
            cp(Event::GoalTracking, 1.1, 0.9),
        ];
        let d = detect(&pts, 0.5, f64::INFINITY).unwrap();
        assert!((d.x - 1.1).abs() < 1e-12 && (d.y - 1.0).abs() < 1e-12);
    }

    #[test]
    fn same_chunk_spread_wider_is_not() {
        let pts = [
            cp(Event::GoalTracking, 0.0, 0.0),
            cp(Event::BlockedAhead, 1.5, 0.0),
            cp(Event::GoalTracking, 3.0, 0.0),
        ];
        assert_eq!(detect(&pts, 0.5, f64::INFINITY), None);
        assert!(detect(&pts, 1.6, f64::INFINITY).is_some());
    }

    #[test]
    fn other_patterns_are_not_deadlocks() {
        let pts = [
            cp(Event::BlockedAhead, 1.0, 1.0),
            cp(Event::GoalTracking, 1.0, 1.0),
            cp(Event::BlockedAhead, 1.0, 1.0),
        ];
        assert_eq!(detect(&pts, 0.5, f64::INFINITY), None);
        assert_eq!(detect(&pts[..2], 0.5, f64::INFINITY), None);
        let mut t = ActivityTrace::new(0.5);
        assert_eq!(
            t.record(Event::GoalTracking, Vec2::new(0.0, 0.0), None, 1.0),
            None
        );
        assert_eq!(
            t.record(Event::BlockedAhead, Vec2::new(0.1, 0.0), None, 2.0),
            None
        );
        assert!(
            t.record(Event::GoalTracking, Vec2::new(0.0, 0.1), None, 3.0)
                .is_some()
        );
        assert_eq!(t.deadlocks().len(), 1);
    }

    #[test]
    fn progress_test_passes_a_return_and_refuses_a_slide_towards_the_goal() {
        let goal = Some(Vec2::new(5.0, 0.0));
        let chunk = |t: &mut ActivityTrace, last_x: f64| {
            t.record(Event::GoalTracking, Vec2::new(0.0, 0.0), goal, 1.0);
            t.record(Event::BlockedAhead, Vec2::new(0.2, 0.1), goal, 2.0);
            t.record(Event::GoalTracking, Vec2::new(last_x, 0.0), goal, 3.0)
        };
        // Back where it was (a return): a dead-lock with or without the test.
        assert!(chunk(&mut ActivityTrace::new(0.6).with_progress_test(0.25), 0.05).is_some());
        // 0.5 m nearer the goal, still inside r_T: the source's detector
        // fires, the progress test does not.
        assert!(chunk(&mut ActivityTrace::new(0.6), 0.5).is_some());
        assert!(chunk(&mut ActivityTrace::new(0.6).with_progress_test(0.25), 0.5).is_none());
    }
}
