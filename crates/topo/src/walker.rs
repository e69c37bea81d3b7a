//! The robot going from reference place to reference place: plays one
//! [`Action`] at a time with an [`Executor`], and on every stop in front of
//! an obstacle classifies the place ([`Situation`]), recognises or adds it
//! ([`MapBuilder::arrive`]) and records the transition that led there
//! ([`MapBuilder::record`]) with the map heading its exit turn ended on.
//! The explorer and the route follower decide which action comes next;
//! this is what they share.

use robot::{Command, Perception, Pose};

use super::TopoError;
use super::builder::{Arrival, Cues, MapBuilder};
use super::fpn::{PlaceId, Strategy, TransitionId, Turn};
use super::ring::Ring;
use super::situation::{Situation, SituationParams};
use super::strategy::{Action, Executor, Failure, Progress, StrategyParams};

/// Wheels slower than this (both) count as stopped, m/s.
const STOPPED_MPS: f64 = 0.01;

/// A homing leg stops once the robot's map position is this close to its
/// point, metres.
const HOMING_REACHED_M: f64 = 0.2;

/// A homing leg with a passing margin ([`Walker::start_homing`]) stops once
/// it drives straight on this much farther from its point than the nearest
/// it came, metres.
pub const HOMING_PASSED_M: f64 = 0.25;

/// A leg: where it started (if at a known place) and what it plays.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Leg {
    /// The place it left (`None`: after a failure, from nowhere known).
    pub from: Option<PlaceId>,
    /// The action played.
    pub action: Action,
}

/// What one tick of the walker gave.
#[derive(Debug, Clone, PartialEq)]
pub enum WalkerStep {
    /// Driving a leg.
    Drive(Command),
    /// Stopped at a reference place; the caller starts the next leg.
    Arrived {
        /// The leg that ended.
        leg: Leg,
        /// What the place looks like.
        situation: Situation,
        /// Which place it is.
        arrival: Arrival,
        /// The transition recorded for the leg (`None` for a leg from
        /// nowhere).
        transition: Option<TransitionId>,
        /// The leg's duration, seconds.
        duration_s: f64,
    },
    /// The leg failed; the caller starts another (the robot is at no known
    /// place).
    Failed {
        /// The leg that failed.
        leg: Leg,
        /// Why.
        failure: Failure,
    },
    /// Waiting for the caller to start a leg.
    Idle,
}

/// Plays legs and builds the map (module docs).
#[derive(Debug, Clone)]
pub struct Walker {
    builder: MapBuilder,
    strategy: StrategyParams,
    situation: SituationParams,
    leg: Option<(Leg, Executor)>,
    /// The map heading the leg's exit turn ended on (once it has).
    left_heading_rad: Option<f64>,
    expected: Option<PlaceId>,
    place: Option<PlaceId>,
    last_time_s: Option<f64>,
    odom: Pose,
    /// The leg records no transition ([`Walker::start_homing`],
    /// [`Walker::start_facing`]).
    unrecorded: bool,
    /// The point a homing leg heads for (map frame).
    homing_target: Option<(f64, f64)>,
    /// A homing leg stops once past its point's closest approach, if that
    /// came nearer than this, metres.
    homing_stop_past: Option<f64>,
    /// The nearest the homing leg has come to its point so far, metres.
    homing_nearest_m: f64,
}

impl Walker {
    /// A walker building on `builder`'s map.
    pub fn new(
        builder: MapBuilder,
        strategy: StrategyParams,
        situation: SituationParams,
    ) -> Result<Walker, TopoError> {
        strategy.validate().map_err(TopoError::Params)?;
        situation.validate().map_err(TopoError::Params)?;
        Ok(Walker {
            builder,
            strategy,
            situation,
            leg: None,
            left_heading_rad: None,
            expected: None,
            place: None,
            last_time_s: None,
            odom: Pose::default(),
            unrecorded: false,
            homing_target: None,
            homing_stop_past: None,
            homing_nearest_m: f64::INFINITY,
        })
    }

    /// The map builder.
    pub fn builder(&self) -> &MapBuilder {
        &self.builder
    }

    /// The map builder, mutable.
    pub fn builder_mut(&mut self) -> &mut MapBuilder {
        &mut self.builder
    }

    /// Takes the builder.
    pub fn into_builder(self) -> MapBuilder {
        self.builder
    }

    /// The place the robot stands at (between legs), if known.
    pub fn place(&self) -> Option<PlaceId> {
        self.place
    }

    /// The leg being played.
    pub fn leg(&self) -> Option<Leg> {
        self.leg.as_ref().map(|(l, _)| *l)
    }

    /// The nearest the last homing leg came to its point, driving
    /// straight on (since its last detour), metres; infinite if it never
    /// did.
    pub fn homing_nearest_m(&self) -> f64 {
        self.homing_nearest_m
    }

    /// The last odometry pose seen.
    pub fn odometry(&self) -> Pose {
        self.odom
    }

    /// The robot stands at `place` (the start of a mission): localise there.
    pub fn stand_at(&mut self, place: PlaceId, odom: Pose) -> Result<(), TopoError> {
        self.builder.localize_at(place, odom)?;
        self.place = Some(place);
        self.odom = odom;
        Ok(())
    }

    /// Starts a leg from where the robot stands, expecting it to end at
    /// `expected` (a planned transition's destination; see
    /// [`super::recognition`]); with `leave_heading_rad` (a map heading:
    /// where the transition left the place when recorded) the exit turn
    /// turns to it ([`Executor::aiming`]).
    pub fn start_expecting(
        &mut self,
        action: Action,
        expected: Option<PlaceId>,
        leave_heading_rad: Option<f64>,
    ) {
        self.start(action);
        if let (Some(h), Some((_, ex))) = (leave_heading_rad, &mut self.leg) {
            *ex = Executor::aiming(
                self.strategy,
                action.strategy,
                action.exit_turn,
                self.odom.theta_rad,
                self.builder.odom_heading(h),
            );
        }
        self.expected = expected;
    }

    /// Starts a leg that heads for the map position `target` (x, y) from
    /// where the robot stands ([`Executor::homing`]), expecting nothing;
    /// the place it ends at is recognised or added, but no transition is
    /// recorded for it (its course depends on where it started from, not
    /// on a strategy that could be played again). With `stop_past`, the
    /// leg also stops once, driving straight on (not rounding an
    /// obstacle), it is [`HOMING_PASSED_M`] farther from the point than
    /// the nearest it came, if that was nearer than `stop_past` metres:
    /// it has passed the point's closest approach along its line, and
    /// going on leads away from it ([`Walker::homing_nearest_m`] says how
    /// near it came).
    pub fn start_homing(&mut self, target: (f64, f64), side: Option<Turn>, stop_past: Option<f64>) {
        let here = self.builder.map_pose(self.odom);
        let bearing = (target.1 - here.y_m).atan2(target.0 - here.x_m);
        self.start(Action {
            exit_turn: Turn::Left,
            strategy: Strategy::FreeMovement,
        });
        if let Some((_, ex)) = &mut self.leg {
            self.homing_target = Some(target);
            self.homing_stop_past = stop_past;
            self.homing_nearest_m = f64::INFINITY;
            *ex = Executor::homing(
                self.strategy,
                self.odom.theta_rad,
                self.builder.odom_heading(bearing),
                side,
            );
        }
        self.unrecorded = true;
    }

    /// Starts a turn in place to the map heading `heading_rad`
    /// ([`Executor::facing`]), expecting place `expected` (which the robot
    /// stands on the spot of): the place is then recognised again from the
    /// heading the expected one was recorded with. No transition is
    /// recorded.
    pub fn start_facing(&mut self, heading_rad: f64, expected: Option<PlaceId>) {
        self.start(Action {
            exit_turn: Turn::Straight,
            strategy: Strategy::FreeMovement,
        });
        if let Some((_, ex)) = &mut self.leg {
            *ex = Executor::facing(
                self.strategy,
                self.odom.theta_rad,
                self.builder.odom_heading(heading_rad),
            );
        }
        self.expected = expected;
        self.unrecorded = true;
    }

    /// Starts a leg from where the robot stands.
    pub fn start(&mut self, action: Action) {
        self.unrecorded = false;
        self.homing_target = None;
        self.expected = None;
        let leg = Leg {
            from: self.place,
            action,
        };
        let ex = Executor::new(
            self.strategy,
            action.strategy,
            action.exit_turn,
            self.odom.theta_rad,
        );
        self.leg = Some((leg, ex));
        self.left_heading_rad = None;
    }

    /// Starts a leg from nowhere known: turn left, then straight ahead to
    /// the next obstacle (after a failure, or at the very start).
    pub fn start_anywhere(&mut self, exit_turn: Turn) {
        self.place = None;
        self.start(Action {
            exit_turn,
            strategy: Strategy::FreeMovement,
        });
    }

    /// One control tick.
    pub fn step(&mut self, p: &Perception) -> Result<WalkerStep, TopoError> {
        let dt_s = match self.last_time_s {
            Some(t) if p.time_s > t => p.time_s - t,
            _ => 0.1,
        };
        self.last_time_s = Some(p.time_s);
        self.odom = p.odometry;
        self.builder.track(p.odometry);
        let Some((leg, ex)) = &mut self.leg else {
            return Ok(WalkerStep::Idle);
        };
        let ring = Ring::of(p);
        let (l, r) = p.wheel_speeds_mps;
        let stopped = l.abs() < STOPPED_MPS && r.abs() < STOPPED_MPS;
        if let Some((x, y)) = self.homing_target {
            let here = self.builder.map_pose(p.odometry);
            let d = (x - here.x_m).hypot(y - here.y_m);
            if d <= HOMING_REACHED_M {
                ex.brake();
            }
            if ex.rounding() {
                // Round an obstacle the distance may grow: measured again
                // from where the detour is back on its heading.
                self.homing_nearest_m = f64::INFINITY;
            } else if ex.turned() {
                if self
                    .homing_stop_past
                    .is_some_and(|m| self.homing_nearest_m < m && d > self.homing_nearest_m + HOMING_PASSED_M)
                {
                    ex.brake();
                }
                self.homing_nearest_m = self.homing_nearest_m.min(d);
            }
        }
        let progress = ex.step(&ring, p.odometry.theta_rad, stopped, dt_s);
        if self.left_heading_rad.is_none() && ex.turned() {
            // The heading the strategy starts on (the turn ended this tick).
            self.left_heading_rad = Some(self.builder.map_pose(p.odometry).theta_rad);
        }
        match progress {
            Progress::Drive(c) => Ok(WalkerStep::Drive(c)),
            Progress::Arrived => {
                let leg = *leg;
                let duration_s = ex.elapsed_s();
                let aligned = ex.aligned_heading(self.builder.params().align_min_run_m, p.odometry.theta_rad);
                self.leg = None;
                let situation = Situation::classify(&ring, &self.situation);
                // Aligned with the wall only if the wall followed is the one
                // of the corner (the closed side).
                let wall_closed = match leg.action.strategy {
                    Strategy::WallFollowLeft => !situation.left_open,
                    Strategy::WallFollowRight => !situation.right_open,
                    _ => false,
                };
                let cues = Cues {
                    aligned_heading_rad: aligned.filter(|_| wall_closed),
                    expected: self.expected.take(),
                };
                let arrival = self.builder.arrive(&situation, p.odometry, cues)?;
                let transition = match leg.from.filter(|_| !self.unrecorded) {
                    Some(from) => Some(self.builder.record(
                        from,
                        arrival.place,
                        leg.action.strategy,
                        leg.action.exit_turn,
                        duration_s,
                        self.left_heading_rad,
                    )?),
                    None => None,
                };
                self.place = Some(arrival.place);
                Ok(WalkerStep::Arrived {
                    leg,
                    situation,
                    arrival,
                    transition,
                    duration_s,
                })
            }
            Progress::Failed(failure) => {
                let leg = *leg;
                self.leg = None;
                self.place = None;
                Ok(WalkerStep::Failed { leg, failure })
            }
        }
    }
}
