//! The behaviour activity trace as a layer on the voting controller
//! (docs/activity-trace.md, "Beyond the source").
//!
//! **Decision — characteristic events from the voting outcome:**
//!
//! 1. navigation starts → `CP1`;
//! 2. *goal seeking dominates*: the chosen action becomes the goal team's
//!    favourite (its `argmax`), after ticks in which it was not → `CP2`;
//! 3. *the obstacle team blocks the goal direction*: the goal lies ahead
//!    (`|bearing| < ε`), the goal team's favourite gets an obstacle-team vote
//!    below [`BLOCKED_VOTE`], and the chosen action is another one — when
//!    this situation begins → `CP3`.
//!
//! The same detector as the priority controller (`CP2, CP3, CP2` within
//! `r_T` of their centroid) records dead-locks; recovery makes the voting
//! controller's goal seeking steer to `arg(F)` of the same potential field
//! instead of the goal's bearing. Parameters (`r_T`, `ε`, the field) are the
//! priority controller's ([`PriorityParams`]).

use robot::{Controller, Notes, Perception, Step};

use super::VotingController;
use activity::{ActivityTrace, Event, PriorityParams, field};

/// Obstacle-team vote below which an action counts as blocked.
pub const BLOCKED_VOTE: f64 = 0.5;

/// The voting controller with the activity-trace layer.
#[derive(Debug, Clone)]
pub struct TracedVoting {
    voting: VotingController,
    p: PriorityParams,
    trace: ActivityTrace,
    started: bool,
    goal_dominated: bool,
    blocked: bool,
    recovering: bool,
}

impl TracedVoting {
    /// Wraps `voting`; `p` gives `r_T`, `ε`, the field, and whether to
    /// recover.
    pub fn new(voting: VotingController, p: PriorityParams) -> TracedVoting {
        TracedVoting {
            voting,
            p,
            trace: ActivityTrace::new(p.r_t_m).with_progress_test(p.progress_m),
            started: false,
            goal_dominated: false,
            blocked: false,
            recovering: false,
        }
    }

    /// The trace so far.
    pub fn trace(&self) -> &ActivityTrace {
        &self.trace
    }

    /// The wrapped controller.
    pub fn voting(&self) -> &VotingController {
        &self.voting
    }
}

fn argmax(v: &[f64]) -> Option<usize> {
    (0..v.len()).max_by(|&a, &b| v[a].total_cmp(&v[b]).then(b.cmp(&a)))
}

impl Controller for TracedVoting {
    fn step(&mut self, perception: &Perception, notes: &mut Notes) -> Step {
        let here = perception.odometry.position();
        if !self.started {
            self.started = true;
            self.trace
                .record(Event::Start, here, perception.goal, perception.time_s);
            notes.event(robot::Event::new("CP1", perception.time_s).at(here));
        }
        if self.recovering {
            if let Some(goal) = perception.goal {
                let f = field::total_force(&self.p.field, here, goal, self.trace.deadlocks());
                self.voting.steer_towards(Some(f.angle()));
            }
        }
        let step = self.voting.step(perception, notes);
        let b = self.voting.ballot();
        let n = b.fused.len();
        // The goal team's favourite and the obstacle team's opinion of it.
        let goal_votes: Vec<f64> = (0..n)
            .map(|m| {
                let odo = b.odo.get(m).map_or(0.0, |v| b.weights.odo * v);
                let plan = b.plan.get(m).map_or(0.0, |v| b.weights.plan * v);
                odo + plan
            })
            .collect();
        let Some(favourite) = argmax(&goal_votes) else {
            return step;
        };
        let obstacle_vote = b.ir.get(favourite).map_or(0.0, |v| b.weights.ir * v)
            + b.sonar.get(favourite).map_or(0.0, |v| b.weights.sonar * v);
        let dominated = b.chosen == favourite;
        let blocked = b.goal_bearing_rad.abs() < self.p.epsilon_rad
            && obstacle_vote < BLOCKED_VOTE
            && b.chosen != favourite;
        let mut event = None;
        if dominated && !self.goal_dominated {
            event = Some(Event::GoalTracking);
        } else if blocked && !self.blocked {
            event = Some(Event::BlockedAhead);
        }
        self.goal_dominated = dominated;
        self.blocked = blocked;
        if let Some(e) = event {
            notes.event(robot::Event::new(e.label(), perception.time_s).at(here));
            if let Some(d) = self.trace.record(e, here, perception.goal, perception.time_s) {
                notes.event(robot::Event::new("deadlock", perception.time_s).at(d));
                if self.p.recovery {
                    self.recovering = true;
                }
            }
        }
        step
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::VotingParams;
    use robot::{IrReading, Pose, SonarReading, Vec2};

    fn perception(front_blocked: bool, at: Vec2) -> Perception {
        Perception {
            goal: Some(Vec2::new(5.0, 0.0)),
            odometry: Pose::new(at.x, at.y, 0.0),
            ir: (0..7)
                .map(|i| IrReading {
                    mount: Pose::new(0.0, 0.0, (90.0 - 30.0 * i as f64).to_radians()),
                    range_m: 0.8,
                    triggered: front_blocked && (2..=4).contains(&i),
                })
                .collect(),
            sonar: [30.0f64, 0.0, -30.0]
                .iter()
                .map(|&d| SonarReading {
                    mount: Pose::new(0.0, 0.0, d.to_radians()),
                    cone_rad: 0.4,
                    range_m: if front_blocked && d == 0.0 { 0.2 } else { 5.0 },
                })
                .collect(),
            ..Perception::default()
        }
    }

    #[test]
    fn alternating_free_and_blocked_ticks_in_place_is_a_deadlock() {
        let v = VotingController::new(VotingParams::default()).unwrap();
        let mut t = TracedVoting::new(v, PriorityParams::default());
        let mut notes = Notes::enabled();
        let at = Vec2::new(1.0, 0.0);
        for blocked in [false, true, false] {
            notes.clear();
            t.step(&perception(blocked, at), &mut notes);
        }
        assert_eq!(t.trace().deadlocks().len(), 1, "{:?}", t.trace().points());
        assert!(t.recovering);
        // Recovery steers away from the dead-lock even though the goal is ahead.
        notes.clear();
        t.step(&perception(false, Vec2::new(1.2, 0.15)), &mut notes);
        assert!(t.voting().ballot().goal_bearing_rad.abs() > 0.1);
    }
}
