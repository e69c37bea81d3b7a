//! The behaviour activity trace and the dead-lock detector (spec:
//! activity-trace.md; Skrzypczyk).
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
    /// When, seconds.
    pub time_s: f64,
}

/// The activity trace with its dead-lock detector and buffer.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct ActivityTrace {
    points: Vec<CharacteristicPoint>,
    deadlocks: Vec<Vec2>,
    r_t_m: f64,
}

impl ActivityTrace {
    /// An empty trace whose detector uses radius `r_t_m`.
    pub fn new(r_t_m: f64) -> ActivityTrace {
        ActivityTrace {
            points: Vec::new(),
            deadlocks: Vec::new(),
            r_t_m,
        }
    }

    /// Appends an event; returns the centroid of a dead-lock if the trace now
    /// ends with one (and records it).
    pub fn record(&mut self, event: Event, at: Vec2, time_s: f64) -> Option<Vec2> {
        self.points.push(CharacteristicPoint { event, at, time_s });
        let d = detect(&self.points, self.r_t_m)?;
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
/// CP2` and lie within `r_t_m` of their centroid.
pub fn detect(points: &[CharacteristicPoint], r_t_m: f64) -> Option<Vec2> {
    let [a, b, c] = points.get(points.len().checked_sub(3)?..)? else {
        return None;
    };
    if (a.event, b.event, c.event) != (Event::GoalTracking, Event::BlockedAhead, Event::GoalTracking) {
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
        let d = detect(&pts, 0.5).unwrap();
        assert!((d.x - 1.1).abs() < 1e-12 && (d.y - 1.0).abs() < 1e-12);
    }

    #[test]
    fn same_chunk_spread_wider_is_not() {
        let pts = [
            cp(Event::GoalTracking, 0.0, 0.0),
            cp(Event::BlockedAhead, 1.5, 0.0),
            cp(Event::GoalTracking, 3.0, 0.0),
        ];
        assert_eq!(detect(&pts, 0.5), None);
        assert!(detect(&pts, 1.6).is_some());
    }

    #[test]
    fn other_patterns_are_not_deadlocks() {
        let pts = [
            cp(Event::BlockedAhead, 1.0, 1.0),
            cp(Event::GoalTracking, 1.0, 1.0),
            cp(Event::BlockedAhead, 1.0, 1.0),
        ];
        assert_eq!(detect(&pts, 0.5), None);
        assert_eq!(detect(&pts[..2], 0.5), None);
        let mut t = ActivityTrace::new(0.5);
        assert_eq!(t.record(Event::GoalTracking, Vec2::new(0.0, 0.0), 1.0), None);
        assert_eq!(t.record(Event::BlockedAhead, Vec2::new(0.1, 0.0), 2.0), None);
        assert!(t.record(Event::GoalTracking, Vec2::new(0.0, 0.1), 3.0).is_some());
        assert_eq!(t.deadlocks().len(), 1);
    }
}
