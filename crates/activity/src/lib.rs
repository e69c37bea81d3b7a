//! Priority-arbitrated behaviours with a behaviour activity trace that
//! detects dead-locks and a potential field that escapes them
//! (docs/activity-trace.md; Skrzypczyk).
//!
//! Eight behaviours compute activations `a_i ∈ [0, 1]` through sigmoids
//! `σ(x) = 1 / (1 + e^{−x})` of their inputs; the behaviour
//! `k = argmax_i a_i q_i` (fixed priorities `q_i`) controls the robot with a
//! heuristic command `f_k(a_k)`. Characteristic events feed the
//! [`ActivityTrace`]; when it reports a dead-lock, recovery turns on: the
//! goal-tracking behaviour steers to `arg(F)` of the potential field
//! ([`field`]) instead of the direct bearing to the goal.
//!
//! Sensing uses [`crate::sectors`]: the nearest obstacle ahead, left, right
//! and behind, from any range sensor the robot has. The behaviours need
//! ranges all round (speed up reacts to what is behind, avoid left/right to
//! the sides): the dead-lock suite gives the controller a ring of 16 sonars
//! (`sim::RobotParams::sonar_ring`). On AIBOT (binary IR over the front
//! half, which reads only "something within 0.8 m", three sonars ahead)
//! avoid left/right never activate and the robot scrapes walls it passes:
//! on the dead-lock suite's U traps (200 runs) the plain controller ends
//! 105 runs in a collision on AIBOT and none on the ring; with recovery
//! 13 against none (reaching the goal in 0.91 against 0.97).
//!
//! The task execution watcher ([`TaskState`]) starts a task on the first
//! perception with a goal, completes it within `arrive_m` of the goal by
//! odometry, and stops with an exception on a bumper contact.
//!
//! ```
//! use activity::{PriorityController, PriorityParams};
//! use robot::{Controller, Notes, Perception, Step, Vec2};
//!
//! let mut c = PriorityController::new(PriorityParams::default()).unwrap();
//! let p = Perception { goal: Some(Vec2::new(0.0, 3.0)), ..Perception::default() };
//! let mut notes = Notes::enabled();
//! // Nothing in sight, goal to the left: goal tracking turns towards it (CP2).
//! assert!(matches!(c.step(&p, &mut notes), Step::Run(_)));
//! assert_eq!(notes.behaviour, Some("goal tracking"));
//! assert_eq!(c.trace().points().len(), 2); // CP1 (start), CP2
//! ```
#![warn(missing_docs)]

pub mod field;
pub mod sectors;
pub mod trace;

use robot::{Command, Controller, Notes, Perception, Step, Vec2, wrap_angle};

use crate::sectors::Sectors;
pub use field::FieldParams;
pub use trace::{ActivityTrace, CharacteristicPoint, Event};

/// The eight behaviours, in the order of [`Behaviour::ALL`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum Behaviour {
    /// Collision imminent or goal reached.
    Stop,
    /// Obstacle ahead: turn away.
    AvoidFront,
    /// Obstacles on both sides: go straight through, centred.
    NarrowPassage,
    /// Obstacle on the left: veer right.
    AvoidLeft,
    /// Obstacle on the right: veer left.
    AvoidRight,
    /// Obstacle behind: move away from it.
    SpeedUp,
    /// Turn towards the desired heading.
    GoalTracking,
    /// Nothing detected: go straight.
    Stroll,
}

impl Behaviour {
    /// All behaviours.
    pub const ALL: [Behaviour; 8] = [
        Behaviour::Stop,
        Behaviour::AvoidFront,
        Behaviour::NarrowPassage,
        Behaviour::AvoidLeft,
        Behaviour::AvoidRight,
        Behaviour::SpeedUp,
        Behaviour::GoalTracking,
        Behaviour::Stroll,
    ];

    /// Display name.
    pub fn name(self) -> &'static str {
        match self {
            Behaviour::Stop => "stop",
            Behaviour::AvoidFront => "avoid front",
            Behaviour::NarrowPassage => "narrow passage",
            Behaviour::AvoidLeft => "avoid left",
            Behaviour::AvoidRight => "avoid right",
            Behaviour::SpeedUp => "speed up",
            Behaviour::GoalTracking => "goal tracking",
            Behaviour::Stroll => "stroll",
        }
    }
}

/// The four states of the task execution watcher.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum TaskState {
    /// No task.
    Waiting,
    /// Driving to the goal.
    Executing,
    /// Goal reached.
    Completed,
    /// Collision: stopped and reported.
    Exception,
}

/// The unsigned heading error of the goal-tracking behaviour:
/// `ΔΘ = |Θ_d − Θ_r|` if that is ≤ π, else `2π − |Θ_d − Θ_r|`.
pub fn heading_error(desired_rad: f64, heading_rad: f64) -> f64 {
    let d = (desired_rad - heading_rad).abs() % (2.0 * std::f64::consts::PI);
    if d <= std::f64::consts::PI {
        d
    } else {
        2.0 * std::f64::consts::PI - d
    }
}

/// The logistic sigmoid.
pub fn sigmoid(x: f64) -> f64 {
    1.0 / (1.0 + (-x).exp())
}

/// Parameters (all with documented defaults).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PriorityParams {
    /// Fixed priorities `q_i`, in the order of [`Behaviour::ALL`]. Default
    /// (1.0, 0.9, 0.85, 0.8, 0.8, 0.7, 0.6, 0.5).
    pub priorities: [f64; 8],
    /// Slope of the goal-tracking sigmoid `α_gt`, 1/rad. Default 8.
    pub alpha_gt: f64,
    /// Heading error below which goal tracking is barely active, `ε`, rad.
    /// Default 0.2 (11°).
    pub epsilon_rad: f64,
    /// Slope of the obstacle sigmoids, 1/m. Default 15.
    pub alpha_obstacle: f64,
    /// Distance ahead at which avoid front is half active, m (from the
    /// robot's centre). Default 0.6.
    pub front_m: f64,
    /// Distance at the sides at which avoid left/right are half active, m.
    /// Default 0.45.
    pub side_m: f64,
    /// Distance behind at which speed up is half active, m. Default 0.4.
    pub back_m: f64,
    /// Distance ahead at which stop is half active, m. Default 0.25.
    pub stop_m: f64,
    /// Clearance at which stroll is half active, m. Default 1.0.
    pub clear_m: f64,
    /// Cruise speed, m/s. Default 0.3.
    pub cruise_mps: f64,
    /// Largest turn rate, rad/s. Default 1.5.
    pub max_turn_radps: f64,
    /// Goal reached (by odometry) within this distance, m. Default 0.05:
    /// a run is judged by the robot's true position within the task's
    /// tolerance (0.3 m in the lab), so aiming at the goal point itself
    /// leaves the whole tolerance to dead-reckoning error; stopping at
    /// 0.2 m by odometry left 0.1 m, and 1 run in 9 ended `lost` after a
    /// detour (measured on the dead-lock suite).
    pub arrive_m: f64,
    /// Dead-lock detection: radius `r_T` of the chunk's circle, m. Default 0.6.
    pub r_t_m: f64,
    /// Dead-lock detection, progress test (beyond the source, see
    /// [`trace`]): a `CP2, CP3, CP2` chunk whose last `CP2` is more than
    /// this much nearer the goal than its first is progress, not a
    /// dead-lock, m. Default 0.25; `inf` (in TOML: `inf`) gives the source's
    /// detector.
    pub progress_m: f64,
    /// Keep the activity trace and detect dead-locks. Default true; false
    /// gives the bare priority controller, which records nothing (the
    /// baseline of the trace's cost in `cargo bench -p lab --bench trace`).
    pub detect: bool,
    /// Recover from detected dead-locks by the potential field. Default
    /// true; false detects and counts dead-locks but drives on as before.
    pub recovery: bool,
    /// The potential field of the recovery.
    pub field: FieldParams,
}

impl Default for PriorityParams {
    fn default() -> Self {
        PriorityParams {
            priorities: [1.0, 0.9, 0.85, 0.8, 0.8, 0.7, 0.6, 0.5],
            alpha_gt: 8.0,
            epsilon_rad: 0.2,
            alpha_obstacle: 15.0,
            front_m: 0.6,
            side_m: 0.45,
            back_m: 0.4,
            stop_m: 0.25,
            clear_m: 1.0,
            cruise_mps: 0.3,
            max_turn_radps: 1.5,
            arrive_m: 0.05,
            r_t_m: 0.6,
            progress_m: 0.25,
            detect: true,
            recovery: true,
            field: FieldParams::default(),
        }
    }
}

impl PriorityParams {
    /// Checks the parameters.
    pub fn validate(&self) -> Result<(), String> {
        let positive = [
            ("alpha_gt", self.alpha_gt),
            ("epsilon_rad", self.epsilon_rad),
            ("alpha_obstacle", self.alpha_obstacle),
            ("front_m", self.front_m),
            ("side_m", self.side_m),
            ("back_m", self.back_m),
            ("stop_m", self.stop_m),
            ("clear_m", self.clear_m),
            ("cruise_mps", self.cruise_mps),
            ("max_turn_radps", self.max_turn_radps),
            ("arrive_m", self.arrive_m),
            ("r_t_m", self.r_t_m),
            ("field.l0_m", self.field.l0_m),
        ];
        if self.progress_m.is_nan() || self.progress_m < 0.0 {
            return Err(format!(
                "progress_m must be ≥ 0 (inf: no progress test), got {}",
                self.progress_m
            ));
        }
        for (what, v) in positive {
            if !(v.is_finite() && v > 0.0) {
                return Err(format!("{what} must be a finite number > 0, got {v}"));
            }
        }
        if self.priorities.iter().any(|q| !(q.is_finite() && *q >= 0.0)) {
            return Err("priorities must be finite numbers ≥ 0".into());
        }
        Ok(())
    }
}

/// What one tick computed.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct Activations {
    /// `a_i`, in the order of [`Behaviour::ALL`].
    pub a: [f64; 8],
    /// Index of the selected behaviour.
    pub selected: usize,
    /// Desired heading `Θ_d` (world/odometry frame), rad.
    pub desired_rad: f64,
    /// Unsigned heading error `ΔΘ`, rad.
    pub error_rad: f64,
}

/// The priority controller with the activity trace.
#[derive(Debug, Clone)]
pub struct PriorityController {
    p: PriorityParams,
    state: TaskState,
    trace: ActivityTrace,
    previous: Option<Behaviour>,
    recovering: bool,
    last: Activations,
}

impl PriorityController {
    /// A controller with these parameters.
    pub fn new(p: PriorityParams) -> Result<PriorityController, String> {
        p.validate()?;
        Ok(PriorityController {
            p,
            state: TaskState::Waiting,
            trace: ActivityTrace::new(p.r_t_m).with_progress_test(p.progress_m),
            previous: None,
            recovering: false,
            last: Activations::default(),
        })
    }

    /// The activity trace so far.
    pub fn trace(&self) -> &ActivityTrace {
        &self.trace
    }

    /// The task watcher's state.
    pub fn state(&self) -> TaskState {
        self.state
    }

    /// Whether the potential-field recovery is on.
    pub fn recovering(&self) -> bool {
        self.recovering
    }

    /// What the last tick computed.
    pub fn activations(&self) -> &Activations {
        &self.last
    }

    fn command(&self, b: Behaviour, a: f64, s: &Sectors, signed_error: f64) -> Command {
        let p = &self.p;
        let twist = |v: f64, w: f64| Command::Twist {
            v_mps: v,
            omega_radps: w.clamp(-p.max_turn_radps, p.max_turn_radps),
        };
        match b {
            Behaviour::Stop => Command::Stop,
            Behaviour::AvoidFront => {
                let left_freer = s.left_m >= s.right_m;
                let w = p.max_turn_radps * a;
                twist(p.cruise_mps * 0.3 * (1.0 - a), if left_freer { w } else { -w })
            }
            Behaviour::NarrowPassage => {
                let l = s.left_m.min(2.0);
                let r = s.right_m.min(2.0);
                twist(p.cruise_mps * 0.6, 1.5 * (l - r))
            }
            Behaviour::AvoidLeft => twist(p.cruise_mps * (1.0 - 0.5 * a), -0.6 * p.max_turn_radps * a),
            Behaviour::AvoidRight => twist(p.cruise_mps * (1.0 - 0.5 * a), 0.6 * p.max_turn_radps * a),
            Behaviour::SpeedUp => twist(p.cruise_mps * 1.3, 0.0),
            Behaviour::GoalTracking => twist(
                p.cruise_mps * (1.0 - 0.8 * a),
                signed_error.signum() * p.max_turn_radps * a,
            ),
            Behaviour::Stroll => twist(p.cruise_mps, 0.0),
        }
    }
}

impl Controller for PriorityController {
    fn step(&mut self, perception: &Perception, notes: &mut Notes) -> Step {
        let p = self.p;
        let pose = perception.odometry;
        let here = pose.position();
        let Some(goal) = perception.goal else {
            self.state = TaskState::Waiting;
            return Step::Done(Command::Stop);
        };
        if self.state == TaskState::Waiting {
            self.state = TaskState::Executing;
            if p.detect {
                self.trace
                    .record(Event::Start, here, Some(goal), perception.time_s);
                notes.event(robot::Event::new("CP1", perception.time_s).at(here));
            }
        }
        if perception.bumper {
            self.state = TaskState::Exception;
            notes.event(
                robot::Event::new("exception", perception.time_s)
                    .at(here)
                    .with("cause", "collision"),
            );
            return Step::GiveUp;
        }
        if (goal - here).norm() <= p.arrive_m {
            self.state = TaskState::Completed;
            return Step::Done(Command::Stop);
        }
        let s = Sectors::of(perception);
        let desired = if self.recovering {
            field::total_force(&p.field, here, goal, self.trace.deadlocks()).angle()
        } else {
            (goal - here).angle()
        };
        let error = heading_error(desired, pose.theta_rad);
        let signed = wrap_angle(desired - pose.theta_rad);
        let ao = p.alpha_obstacle;
        let a = [
            sigmoid(ao * (p.stop_m - s.front_m)),
            sigmoid(ao * (p.front_m - s.front_m)),
            sigmoid(ao * (p.side_m - s.left_m.max(s.right_m))),
            sigmoid(ao * (p.side_m - s.left_m)),
            sigmoid(ao * (p.side_m - s.right_m)),
            sigmoid(ao * (p.back_m - s.back_m)),
            sigmoid(p.alpha_gt * (error - p.epsilon_rad)),
            sigmoid(ao * (s.front_m.min(s.left_m).min(s.right_m) - p.clear_m)),
        ];
        let selected = (0..8)
            .max_by(|&i, &j| {
                (a[i] * p.priorities[i])
                    .total_cmp(&(a[j] * p.priorities[j]))
                    .then(j.cmp(&i))
            })
            .unwrap_or(7);
        let behaviour = Behaviour::ALL[selected];
        // Events fire when a behaviour *becomes* selected.
        if p.detect && self.previous != Some(behaviour) {
            let event = match behaviour {
                Behaviour::GoalTracking => Some(Event::GoalTracking),
                Behaviour::AvoidFront if error < p.epsilon_rad => Some(Event::BlockedAhead),
                _ => None,
            };
            if let Some(e) = event {
                notes.event(robot::Event::new(e.label(), perception.time_s).at(here));
                if let Some(d) = self.trace.record(e, here, Some(goal), perception.time_s) {
                    notes.event(robot::Event::new("deadlock", perception.time_s).at(d));
                    if p.recovery {
                        self.recovering = true;
                    }
                }
            }
        }
        self.previous = Some(behaviour);
        self.last = Activations {
            a,
            selected,
            desired_rad: desired,
            error_rad: error,
        };
        if notes.is_enabled() {
            notes.behaviour(behaviour.name());
            for (i, b) in Behaviour::ALL.iter().enumerate() {
                notes.value(b.name(), a[i]);
            }
            notes.value("desired_rad", desired);
        }
        Step::Run(self.command(behaviour, a[selected], &s, signed))
    }
}

/// The goal relative to a pose, for pictures.
pub fn to_goal(p: &Perception) -> Option<Vec2> {
    p.goal.map(|g| g - p.odometry.position())
}

#[cfg(test)]
mod tests {
    use super::*;
    use robot::{Pose, SonarReading};
    use std::f64::consts::PI;

    #[test]
    fn heading_error_wraps() {
        assert!((heading_error(0.1, -0.1) - 0.2).abs() < 1e-12);
        assert!((heading_error(3.0, -3.0) - (2.0 * PI - 6.0)).abs() < 1e-12);
        assert!((heading_error(-3.0, 3.0) - (2.0 * PI - 6.0)).abs() < 1e-12);
        assert!((heading_error(PI, -PI)).abs() < 1e-12);
        assert!((heading_error(PI / 2.0, -PI / 2.0) - PI).abs() < 1e-12);
    }

    fn sonar_ring(ranges: &[(f64, f64)]) -> Vec<SonarReading> {
        ranges
            .iter()
            .map(|&(deg, r)| SonarReading {
                mount: Pose::new(0.0, 0.0, deg.to_radians()),
                cone_rad: 0.4,
                range_m: r,
            })
            .collect()
    }

    #[test]
    fn open_space_turns_to_the_goal_then_strolls() {
        let mut c = PriorityController::new(PriorityParams::default()).unwrap();
        let mut p = Perception {
            goal: Some(Vec2::new(0.0, 5.0)),
            sonar: sonar_ring(&[(0.0, 9.0), (90.0, 9.0), (-90.0, 9.0), (180.0, 9.0)]),
            ..Perception::default()
        };
        let mut notes = Notes::enabled();
        let Step::Run(Command::Twist { omega_radps, .. }) = c.step(&p, &mut notes) else {
            panic!()
        };
        assert_eq!(notes.behaviour, Some("goal tracking"));
        assert!(omega_radps > 0.0, "turn left towards +y");
        let kinds: Vec<&str> = notes.events.iter().map(|e| e.kind.as_str()).collect();
        assert_eq!(kinds, ["CP1", "CP2"]);
        p.odometry = Pose::new(0.0, 0.0, PI / 2.0);
        notes.clear();
        c.step(&p, &mut notes);
        assert_eq!(notes.behaviour, Some("stroll"));
    }

    #[test]
    fn obstacle_on_the_course_raises_event_3() {
        let mut c = PriorityController::new(PriorityParams::default()).unwrap();
        let p = Perception {
            goal: Some(Vec2::new(5.0, 0.0)),
            sonar: sonar_ring(&[(0.0, 0.4), (90.0, 3.0), (-90.0, 3.0), (180.0, 9.0)]),
            ..Perception::default()
        };
        let mut notes = Notes::enabled();
        c.step(&p, &mut notes);
        assert_eq!(notes.behaviour, Some("avoid front"));
        assert_eq!(
            c.trace().points().last().map(|cp| cp.event),
            Some(Event::BlockedAhead)
        );
    }

    #[test]
    fn bumper_is_an_exception_and_arrival_completes() {
        let mut c = PriorityController::new(PriorityParams::default()).unwrap();
        let mut p = Perception {
            goal: Some(Vec2::new(5.0, 0.0)),
            bumper: true,
            ..Perception::default()
        };
        assert_eq!(c.step(&p, &mut Notes::disabled()), Step::GiveUp);
        assert_eq!(c.state(), TaskState::Exception);
        p.bumper = false;
        p.odometry = Pose::new(4.9, 0.0, 0.0);
        assert!(
            matches!(c.step(&p, &mut Notes::disabled()), Step::Run(_)),
            "0.1 m short"
        );
        p.odometry = Pose::new(4.96, 0.0, 0.0);
        assert!(matches!(c.step(&p, &mut Notes::disabled()), Step::Done(_)));
        assert_eq!(c.state(), TaskState::Completed);
        assert!(
            PriorityController::new(PriorityParams {
                r_t_m: 0.0,
                ..PriorityParams::default()
            })
            .is_err()
        );
        for (progress_m, ok) in [
            (-0.1, false),
            (f64::NAN, false),
            (0.0, true),
            (f64::INFINITY, true),
        ] {
            let p = PriorityParams {
                progress_m,
                ..PriorityParams::default()
            };
            assert_eq!(
                PriorityController::new(p).is_ok(),
                ok,
                "progress_m = {progress_m}"
            );
        }
    }
}
