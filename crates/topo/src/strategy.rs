//! The navigation strategies of the topological layer, executed from one
//! reference place to the next on a sonar-ring robot: free movement, wall
//! following left or right, detour left or right (docs/topo-fpn.md).
//!
//! A transition starts where the robot stopped in front of an obstacle (a
//! reference place). [`Executor`] plays it in two phases:
//!
//! 1. **Exit turn** — rotate in place toward the transition's exit turn by
//!    [`StrategyParams::min_turn_rad`] (90°), or 180°, or 270°: the first of
//!    these steps where the transducer straight ahead sees beyond
//!    [`StrategyParams::clear_m`] with room to drive beside it (a dead end
//!    turns about). Each step slows down to end on its angle, so that the
//!    strategy leaves on a repeatable heading. No clear way at 270°: a
//!    failure. A transition played again from the map turns instead to the
//!    heading it left on when it was recorded ([`Executor::aiming`]): the
//!    heading a robot stops on in front of an obstacle varies by tens of
//!    degrees (an arc round a door jamb ends wherever something comes
//!    ahead), the walls do not;
//! 2. **Strategy** — until an obstacle ahead closes to
//!    [`StrategyParams::stop_m`]: then the robot brakes, and once stopped
//!    the executor reports [`Progress::Arrived`], the next reference place.
//!    - *free movement* holds the heading the turn left it with, edging
//!      away from walls that come closer than [`StrategyParams::side_min_m`]
//!      on a side;
//!    - *wall following* keeps the wall on its side at
//!      [`StrategyParams::wall_m`] (a PD law on the perpendicular distance
//!      the side transducers see); when the wall ends (a convex corner, a
//!      door) it arcs round toward it at that radius;
//!    - *detour* turns toward its side at the place, follows the obstacle
//!      on the other side until the heading it had at the place is free
//!      again, then goes straight along it (free movement).
//!
//! Speeds: cruise [`StrategyParams::cruise_mps`], slowing as the obstacle
//! ahead nears so the robot stops a few centimetres past `stop_m`. A
//! transition that lasts more than [`StrategyParams::timeout_s`] fails (a
//! wall follower circling an island, free movement in a loop).
//!
//! Pure: the executor sees only the ring's ranges and the odometry heading
//! (no map, no position), as on the source's Nomad-200.

use robot::{Command, wrap_angle};
use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};

use super::fpn::{PlaceKind, Strategy, Turn};
use super::ring::{Ring, Side};

/// Parameters of the strategies (lengths from the robot's centre).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct StrategyParams {
    /// Cruise speed, m/s. Default 0.3.
    pub cruise_mps: f64,
    /// Slowest forward speed while approaching an obstacle, m/s. Default 0.06.
    pub creep_mps: f64,
    /// Turn rate in place, rad/s. Default 1.0.
    pub turn_radps: f64,
    /// Largest turn rate while driving, rad/s. Default 1.2.
    pub max_omega_radps: f64,
    /// An obstacle this close ahead (centre to echo along the heading)
    /// makes a reference place, metres. Default 0.5.
    pub stop_m: f64,
    /// The exit turn ends once this much is free ahead, metres. Default 0.9.
    pub clear_m: f64,
    /// Half-width of the cone "ahead" (transducers within it count),
    /// radians. Default 25° (the three front transducers of the ring).
    pub ahead_half_width_rad: f64,
    /// The exit turn's step, radians: turns are 1, 2 or 3 steps. Default
    /// 90°.
    pub min_turn_rad: f64,
    /// Distance kept to the wall by wall following, metres. Default 0.45.
    pub wall_m: f64,
    /// Proportional gain of wall following, rad/s per metre. Default 2.5.
    pub wall_kp: f64,
    /// Derivative gain of wall following, rad/s per (m/s). Default 2.0.
    pub wall_kd: f64,
    /// Beyond `wall_m` plus this, the wall is lost (a convex corner or a
    /// door): arc round toward it, metres. Default 0.45.
    pub wall_lost_m: f64,
    /// Free movement edges away from a side wall nearer than this, metres.
    /// Default 0.4.
    pub side_min_m: f64,
    /// Heading-hold gain of free movement, rad/s per radian. Default 1.5.
    pub heading_kp: f64,
    /// A detour returns to its heading within this angle, radians.
    /// Default 10°.
    pub detour_return_rad: f64,
    /// A transition longer than this fails, seconds. Default 60 (18 m at
    /// cruise speed: round an office, not across a floor).
    pub timeout_s: f64,
}

impl Default for StrategyParams {
    fn default() -> StrategyParams {
        StrategyParams {
            cruise_mps: 0.3,
            creep_mps: 0.06,
            turn_radps: 1.0,
            max_omega_radps: 1.2,
            stop_m: 0.5,
            clear_m: 0.9,
            ahead_half_width_rad: 25f64.to_radians(),
            min_turn_rad: FRAC_PI_2,
            wall_m: 0.45,
            wall_kp: 2.5,
            wall_kd: 2.0,
            wall_lost_m: 0.45,
            side_min_m: 0.4,
            heading_kp: 1.5,
            detour_return_rad: 10f64.to_radians(),
            timeout_s: 60.0,
        }
    }
}

impl StrategyParams {
    /// Checks every field (finite, positive, `stop_m < clear_m`).
    pub fn validate(&self) -> Result<(), String> {
        let fields = [
            ("cruise_mps", self.cruise_mps),
            ("creep_mps", self.creep_mps),
            ("turn_radps", self.turn_radps),
            ("max_omega_radps", self.max_omega_radps),
            ("stop_m", self.stop_m),
            ("clear_m", self.clear_m),
            ("ahead_half_width_rad", self.ahead_half_width_rad),
            ("min_turn_rad", self.min_turn_rad),
            ("wall_m", self.wall_m),
            ("wall_kp", self.wall_kp),
            ("wall_kd", self.wall_kd),
            ("wall_lost_m", self.wall_lost_m),
            ("side_min_m", self.side_min_m),
            ("heading_kp", self.heading_kp),
            ("detour_return_rad", self.detour_return_rad),
            ("timeout_s", self.timeout_s),
        ];
        for (name, v) in fields {
            if !v.is_finite() || v <= 0.0 {
                return Err(format!("strategy.{name} must be finite and > 0, got {v}"));
            }
        }
        if self.creep_mps > self.cruise_mps {
            return Err("strategy.creep_mps must not exceed strategy.cruise_mps".into());
        }
        if self.stop_m >= self.clear_m {
            return Err("strategy.stop_m must be below strategy.clear_m".into());
        }
        if self.min_turn_rad > PI {
            return Err("strategy.min_turn_rad must be at most π".into());
        }
        Ok(())
    }
}

/// Length scale of the wall heading's average, metres.
const ALIGN_SCALE_M: f64 = 1.0;

/// A heading this far from a wall stretch's mean starts a new stretch,
/// radians (20°).
const SEGMENT_TURN_RAD: f64 = 0.35;

/// Homing drives along a free heading at most this far from its bearing
/// (three transducers' spacing, 67.5°); farther, it goes round what blocks
/// the bearing instead.
const HOMING_FREE_RAD: f64 = 3.0 * std::f64::consts::FRAC_PI_8;

/// The smallest turn counts as done this close to its angle, radians.
const TURN_DONE_RAD: f64 = 0.02;

/// What the robot does at a reference place: the exit turn, then the
/// strategy.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize, serde::Deserialize)]
pub struct Action {
    /// The exit turn.
    pub exit_turn: Turn,
    /// The strategy.
    pub strategy: Strategy,
}

/// The actions open at a place of type `kind`, `concave` or not, in a
/// fixed order:
///
/// | type | actions |
/// |---|---|
/// | (a) | turn right, then: follow the wall (now on the left), free movement, detour right |
/// | (b) | turn left, then: follow the wall (now on the right), free movement, detour left |
/// | (c) | turn left or right, then free movement; detour left or right |
/// | (c), concave (a dead end) | those of (c), and wall following after either turn |
///
/// Wall following may not leave a (c) place: round a free-standing
/// obstacle it could loop forever. **Decision:** a dead end is (c) (see
/// [`super::situation`]) but its walls are one concave whole, not a
/// free-standing obstacle, so wall following may leave it: turning about,
/// the follower takes the wall on its side out of the dead end.
pub fn actions_at(kind: PlaceKind, concave: bool) -> &'static [Action] {
    const fn a(exit_turn: Turn, strategy: Strategy) -> Action {
        Action { exit_turn, strategy }
    }
    const A: [Action; 3] = [
        a(Turn::Right, Strategy::WallFollowLeft),
        a(Turn::Right, Strategy::FreeMovement),
        a(Turn::Right, Strategy::DetourRight),
    ];
    const B: [Action; 3] = [
        a(Turn::Left, Strategy::WallFollowRight),
        a(Turn::Left, Strategy::FreeMovement),
        a(Turn::Left, Strategy::DetourLeft),
    ];
    const C: [Action; 4] = [
        a(Turn::Left, Strategy::FreeMovement),
        a(Turn::Right, Strategy::FreeMovement),
        a(Turn::Left, Strategy::DetourLeft),
        a(Turn::Right, Strategy::DetourRight),
    ];
    const DEAD_END: [Action; 6] = [
        a(Turn::Right, Strategy::WallFollowLeft),
        a(Turn::Left, Strategy::WallFollowRight),
        a(Turn::Left, Strategy::FreeMovement),
        a(Turn::Right, Strategy::FreeMovement),
        a(Turn::Left, Strategy::DetourLeft),
        a(Turn::Right, Strategy::DetourRight),
    ];
    match (kind, concave) {
        (PlaceKind::A, _) => &A,
        (PlaceKind::B, _) => &B,
        (PlaceKind::C, false) => &C,
        (PlaceKind::C, true) => &DEAD_END,
    }
}

/// Among the transducers' axes, the odometry heading nearest `bearing_rad`
/// along which the ring sees the way free: the transducer on the axis
/// beyond `clear_m`, and every transducer within `ahead_half_width_rad` of
/// it beyond `stop_m` + 0.3 m along the axis (robot at odometry heading
/// `heading_rad`). `None` when no axis is free.
fn free_heading_near(ring: &Ring, p: &StrategyParams, heading_rad: f64, bearing_rad: f64) -> Option<f64> {
    let echoes = ring.echoes();
    echoes
        .iter()
        .filter(|e| e.range_m > p.clear_m)
        .filter(|e| {
            echoes.iter().all(|o| {
                let off = wrap_angle(o.bearing_rad - e.bearing_rad);
                off.abs() > p.ahead_half_width_rad + 1e-9 || o.range_m * off.cos() > p.stop_m + 0.3
            })
        })
        .map(|e| wrap_angle(heading_rad + e.bearing_rad))
        .min_by(|a, b| {
            wrap_angle(a - bearing_rad)
                .abs()
                .total_cmp(&wrap_angle(b - bearing_rad).abs())
        })
}

/// What the executor is doing.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Phase {
    /// Rotating in place to the odometry heading `target_rad` (a replayed
    /// transition's leaving heading); then the exit turn's steps in
    /// direction `sign` if the way is not free there.
    Aiming { target_rad: f64, sign: f64 },
    /// Homing's first tick: choose, from the ring, the free heading
    /// nearest the odometry heading `bearing_rad` ([`Executor::homing`]).
    Choosing { bearing_rad: f64 },
    /// Rotating in place by the exit turn; `turned_rad` so far.
    Turning { sign: f64, turned_rad: f64 },
    /// Driving the strategy.
    Driving,
    /// Braking in front of an obstacle.
    Braking,
    /// Done: stopped at the next place.
    Arrived,
    /// Failed.
    Failed(Failure),
}

/// Why a transition failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Failure {
    /// The exit turn found no free way.
    NoWayOut,
    /// The transition took longer than the timeout.
    Timeout,
}

/// One tick of an executor.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Progress {
    /// Keep going with this command.
    Drive(Command),
    /// Stopped in front of an obstacle: a reference place (the command is a
    /// stop).
    Arrived,
    /// The transition failed (the command is a stop).
    Failed(Failure),
}

/// Plays one transition: exit turn, then a strategy until the next
/// reference place (module docs).
#[derive(Debug, Clone)]
pub struct Executor {
    params: StrategyParams,
    strategy: Strategy,
    phase: Phase,
    /// Heading at the start (the place's), radians (odometry).
    place_heading_rad: f64,
    /// Heading held by free movement (after the turn, or the detour's).
    hold_heading_rad: f64,
    /// Detour: still going round (not yet back on the place's heading).
    rounding: bool,
    last_heading_rad: f64,
    last_wall_error_m: Option<f64>,
    /// The wall was tracked steadily this tick.
    wall_steady: bool,
    /// The wall was lost this tick.
    wall_lost: bool,
    /// Distance driven along the wall without losing it, metres.
    wall_run_m: f64,
    /// Heading along the wall: sum of (cos, sin) weighted by distance,
    /// forgetting over [`ALIGN_SCALE_M`].
    wall_heading: (f64, f64),
    elapsed_s: f64,
    driven_s: f64,
    /// What the aiming turn leads to ([`Executor::homing`],
    /// [`Executor::facing`]).
    after_aim: AfterAim,
    /// The side homing detours on (`None`: the freer one).
    homing_side: Option<Turn>,
}

/// What an executor does once its aiming turn is over.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum AfterAim {
    /// The strategy if the way is free, else the exit turn's steps.
    Strategy,
    /// Free movement if the way is free, else a detour on the freer side
    /// back to the aimed heading ([`Executor::homing`]).
    Homing,
    /// Stop: the leg is the turn ([`Executor::facing`]).
    Stop,
}

impl Executor {
    /// Starts a transition at a place where the odometry heading is
    /// `heading_rad`: `exit_turn` first (`Straight`: none), then `strategy`.
    /// A detour turns toward its own side whatever `exit_turn` says.
    pub fn new(params: StrategyParams, strategy: Strategy, exit_turn: Turn, heading_rad: f64) -> Executor {
        let turn = match strategy.detour_side() {
            Some(side) => side,
            None => exit_turn,
        };
        let phase = match turn {
            Turn::Left => Phase::Turning {
                sign: 1.0,
                turned_rad: 0.0,
            },
            Turn::Right => Phase::Turning {
                sign: -1.0,
                turned_rad: 0.0,
            },
            Turn::Straight => Phase::Driving,
        };
        Executor {
            params,
            strategy,
            phase,
            place_heading_rad: heading_rad,
            hold_heading_rad: heading_rad,
            rounding: strategy.detour_side().is_some(),
            last_heading_rad: heading_rad,
            last_wall_error_m: None,
            wall_steady: false,
            wall_lost: false,
            wall_run_m: 0.0,
            wall_heading: (0.0, 0.0),
            elapsed_s: 0.0,
            driven_s: 0.0,
            after_aim: AfterAim::Strategy,
            homing_side: None,
        }
    }

    /// Heading for a point (navigation off the net, [`super::navigate`]):
    /// rotate in place (the shorter way) to the odometry heading
    /// `bearing_rad`, then free movement along it if the way ahead leaves
    /// room to drive; otherwise a detour round what blocks it, on the side
    /// the ring sees freer (the larger perpendicular range from 45° to 90°),
    /// back to `bearing_rad` and on along it. The leg ends, as every leg, at
    /// the next obstacle ahead.
    pub fn homing(
        params: StrategyParams,
        heading_rad: f64,
        bearing_rad: f64,
        side: Option<Turn>,
    ) -> Executor {
        let mut ex = Executor::new(params, Strategy::FreeMovement, Turn::Left, heading_rad);
        ex.phase = Phase::Choosing {
            bearing_rad: wrap_angle(bearing_rad),
        };
        ex.place_heading_rad = wrap_angle(bearing_rad);
        ex.after_aim = AfterAim::Homing;
        ex.homing_side = side;
        ex
    }

    /// A turn in place to the odometry heading `facing_rad` (the shorter
    /// way), and then the leg is over ([`Progress::Arrived`] once
    /// stopped): to look at a place from the heading it was recorded with.
    pub fn facing(params: StrategyParams, heading_rad: f64, facing_rad: f64) -> Executor {
        let mut ex = Executor::new(params, Strategy::FreeMovement, Turn::Left, heading_rad);
        ex.phase = Phase::Aiming {
            target_rad: wrap_angle(facing_rad),
            sign: 1.0,
        };
        ex.after_aim = AfterAim::Stop;
        ex
    }

    /// Like [`Executor::new`], but the exit turn first rotates (the shorter
    /// way) to the odometry heading `leave_heading_rad` — where a recorded
    /// transition left its place — and the strategy starts there if the
    /// way ahead leaves room to drive (beyond `stop_m` + 0.1 m); otherwise
    /// the exit turn's steps go on from that heading. A detour ignores it
    /// (it turns toward its side and comes back to the place's heading).
    pub fn aiming(
        params: StrategyParams,
        strategy: Strategy,
        exit_turn: Turn,
        heading_rad: f64,
        leave_heading_rad: f64,
    ) -> Executor {
        let mut ex = Executor::new(params, strategy, exit_turn, heading_rad);
        if strategy.detour_side().is_none() && leave_heading_rad.is_finite() {
            let sign = match exit_turn {
                Turn::Right => -1.0,
                _ => 1.0,
            };
            ex.phase = Phase::Aiming {
                target_rad: wrap_angle(leave_heading_rad),
                sign,
            };
        }
        ex
    }

    /// Brakes now: the leg ends where the robot stops
    /// ([`Progress::Arrived`]), as if an obstacle had come ahead (homing
    /// that has reached its point, [`super::Walker::start_homing`]). Only
    /// while driving the strategy; otherwise nothing.
    pub fn brake(&mut self) {
        if self.phase == Phase::Driving {
            self.phase = Phase::Braking;
        }
    }

    /// A detour still going round its obstacle (not yet back on its
    /// heading).
    pub fn rounding(&self) -> bool {
        self.rounding && self.strategy.detour_side().is_some()
    }

    /// The strategy played.
    pub fn strategy(&self) -> Strategy {
        self.strategy
    }

    /// Time since the start, seconds.
    pub fn elapsed_s(&self) -> f64 {
        self.elapsed_s
    }

    /// Time spent driving the strategy (after the exit turn), seconds.
    pub fn driven_s(&self) -> f64 {
        self.driven_s
    }

    /// Wall following that ends along a straight wall is aligned with it:
    /// the odometry heading averaged over the last metre or so of steady
    /// tracking (distance within 8 cm of `wall_m`), once at least
    /// `min_run_m` of steady tracking has been driven since the wall was
    /// last lost or turned a corner (the heading left the stretch's mean by
    /// more than 20°), and the robot still heads along it (`heading_rad`
    /// within 20° of the mean).
    /// `None` for other strategies or a shorter run.
    pub fn aligned_heading(&self, min_run_m: f64, heading_rad: f64) -> Option<f64> {
        let (c, s) = self.wall_heading;
        let mean = s.atan2(c);
        (self.strategy.is_wall_following()
            && self.wall_run_m >= min_run_m
            && c.hypot(s) > 0.0
            && wrap_angle(heading_rad - mean).abs() <= SEGMENT_TURN_RAD)
            .then_some(mean)
    }

    /// Whether the exit turn is over.
    pub fn turned(&self) -> bool {
        !matches!(
            self.phase,
            Phase::Turning { .. } | Phase::Aiming { .. } | Phase::Choosing { .. }
        )
    }

    /// One control tick: the ring, the odometry heading, whether the robot
    /// has stopped (both wheels under 1 cm/s), the period.
    pub fn step(&mut self, ring: &Ring, heading_rad: f64, stopped: bool, dt_s: f64) -> Progress {
        let p = self.params;
        self.elapsed_s += dt_s;
        let dheading = wrap_angle(heading_rad - self.last_heading_rad);
        self.last_heading_rad = heading_rad;
        if !matches!(self.phase, Phase::Arrived | Phase::Failed(_)) && self.elapsed_s > p.timeout_s {
            self.phase = Phase::Failed(Failure::Timeout);
        }
        let ahead = ring.ahead_m(p.ahead_half_width_rad);
        match self.phase {
            Phase::Arrived => Progress::Arrived,
            Phase::Failed(f) => Progress::Failed(f),
            Phase::Choosing { bearing_rad } => {
                // A free heading within 67.5° of the bearing: along it.
                // None: the bearing, which is blocked, and round what blocks
                // it (the aiming phase's detour).
                let target_rad = free_heading_near(ring, &p, heading_rad, bearing_rad)
                    .filter(|h| wrap_angle(h - bearing_rad).abs() <= HOMING_FREE_RAD + 1e-9)
                    .unwrap_or(bearing_rad);
                self.place_heading_rad = target_rad;
                self.phase = Phase::Aiming {
                    target_rad,
                    sign: 1.0,
                };
                Progress::Drive(Command::Stop)
            }
            Phase::Aiming { target_rad, sign } => {
                let left_rad = wrap_angle(target_rad - heading_rad);
                if left_rad.abs() <= TURN_DONE_RAD {
                    if self.after_aim == AfterAim::Stop && ahead <= p.stop_m + 0.1 {
                        self.phase = Phase::Braking;
                        return Progress::Drive(Command::Stop);
                    }
                    if ahead > p.stop_m + 0.1 {
                        self.phase = Phase::Driving;
                        self.hold_heading_rad = heading_rad;
                        self.last_wall_error_m = None;
                        return self.drive(ring, heading_rad, ahead, dt_s);
                    }
                    if self.after_aim == AfterAim::Homing {
                        // Round what blocks the way, on the freer side.
                        let left = ring.side_m(Side::Left, FRAC_PI_4, FRAC_PI_2);
                        let right = ring.side_m(Side::Right, FRAC_PI_4, FRAC_PI_2);
                        let go_left = match self.homing_side {
                            Some(Turn::Left) => true,
                            Some(Turn::Right) => false,
                            _ => left >= right,
                        };
                        let (strategy, sign) = if go_left {
                            (Strategy::DetourLeft, 1.0)
                        } else {
                            (Strategy::DetourRight, -1.0)
                        };
                        self.strategy = strategy;
                        self.rounding = true;
                        self.phase = Phase::Turning {
                            sign,
                            turned_rad: 0.0,
                        };
                        return Progress::Drive(Command::Stop);
                    }
                    // Blocked there (the robot stands elsewhere than when
                    // the transition was recorded): the exit turn's steps.
                    self.phase = Phase::Turning {
                        sign,
                        turned_rad: 0.0,
                    };
                    return Progress::Drive(Command::Stop);
                }
                let rate = (2.0 * left_rad.abs()).clamp(0.2, p.turn_radps);
                Progress::Drive(Command::Twist {
                    v_mps: 0.0,
                    omega_radps: left_rad.signum() * rate,
                })
            }
            Phase::Turning { sign, turned_rad } => {
                let turned_rad = turned_rad + sign * dheading;
                // Turns go by steps of min_turn_rad (90°: then 180°, 270°)
                // so that the strategy leaves on a repeatable heading; each
                // step ends on its angle, and the turn is over at the first
                // whose way is clear: the transducer straight ahead sees
                // beyond clear_m and its neighbours leave room to drive (a
                // passage narrower than their cones is fine).
                let step_rad = p.min_turn_rad;
                let target = ((turned_rad + TURN_DONE_RAD) / step_rad).ceil().max(1.0) * step_rad;
                let nearest = (turned_rad / step_rad).round();
                let at_step = nearest >= 1.0 && (turned_rad - nearest * step_rad).abs() <= TURN_DONE_RAD;
                let clear = ring.ahead_m(0.01) > p.clear_m && ahead > p.stop_m + 0.1;
                if at_step && clear {
                    self.phase = Phase::Driving;
                    self.hold_heading_rad = heading_rad;
                    self.last_wall_error_m = None;
                    return self.drive(ring, heading_rad, ahead, dt_s);
                }
                if turned_rad > 1.75 * PI {
                    self.phase = Phase::Failed(Failure::NoWayOut);
                    return Progress::Failed(Failure::NoWayOut);
                }
                self.phase = Phase::Turning { sign, turned_rad };
                let left_rad = if at_step { step_rad } else { target - turned_rad };
                let rate = (2.0 * left_rad).clamp(0.2, p.turn_radps);
                Progress::Drive(Command::Twist {
                    v_mps: 0.0,
                    omega_radps: sign * rate,
                })
            }
            Phase::Driving => self.drive(ring, heading_rad, ahead, dt_s),
            Phase::Braking => {
                if stopped {
                    self.phase = Phase::Arrived;
                    Progress::Arrived
                } else {
                    Progress::Drive(Command::Stop)
                }
            }
        }
    }

    fn drive(&mut self, ring: &Ring, heading_rad: f64, ahead: f64, dt_s: f64) -> Progress {
        let p = self.params;
        self.driven_s += dt_s;
        if ahead <= p.stop_m {
            self.phase = Phase::Braking;
            return Progress::Drive(Command::Stop);
        }
        // Slow down over the last 0.5 m so that braking stops close to
        // stop_m.
        let room = ahead - p.stop_m;
        let v = (p.cruise_mps * (room / 0.5).min(1.0)).max(p.creep_mps);
        let omega = match self.strategy {
            Strategy::FreeMovement => self.free(ring, heading_rad),
            Strategy::WallFollowLeft => self.follow(ring, Side::Left, dt_s),
            Strategy::WallFollowRight => self.follow(ring, Side::Right, dt_s),
            Strategy::DetourLeft | Strategy::DetourRight => {
                let side = if self.strategy == Strategy::DetourLeft {
                    Side::Left
                } else {
                    Side::Right
                };
                if self.rounding {
                    let back = wrap_angle(heading_rad - self.place_heading_rad).abs() <= p.detour_return_rad;
                    // Back on the place's heading with the way ahead free:
                    // leave the obstacle.
                    if back && ahead > p.clear_m {
                        self.rounding = false;
                        self.hold_heading_rad = self.place_heading_rad;
                        self.free(ring, heading_rad)
                    } else {
                        // The obstacle is on the other side.
                        self.follow(ring, side.other(), dt_s)
                    }
                } else {
                    self.free(ring, heading_rad)
                }
            }
        };
        // Sharp turns at lower speed.
        let v = v * (1.0 - 0.6 * (omega.abs() / p.max_omega_radps).min(1.0));
        let v = v.max(p.creep_mps.min(v));
        if self.strategy.is_wall_following() {
            if self.wall_lost {
                self.wall_heading = (0.0, 0.0);
                self.wall_run_m = 0.0;
            } else if self.wall_steady {
                let (c, s) = self.wall_heading;
                if c.hypot(s) > 0.0 && wrap_angle(heading_rad - s.atan2(c)).abs() > SEGMENT_TURN_RAD {
                    // Round a corner: a new straight stretch.
                    self.wall_heading = (0.0, 0.0);
                    self.wall_run_m = 0.0;
                }
                let w = v * dt_s;
                let keep = (-w / ALIGN_SCALE_M).exp();
                self.wall_heading = (
                    self.wall_heading.0 * keep + w * heading_rad.cos(),
                    self.wall_heading.1 * keep + w * heading_rad.sin(),
                );
                self.wall_run_m += w;
            }
        }
        Progress::Drive(Command::Twist {
            v_mps: v,
            omega_radps: omega,
        })
    }

    /// Free movement: hold the heading, edge away from close side walls.
    fn free(&mut self, ring: &Ring, heading_rad: f64) -> f64 {
        let p = self.params;
        let mut omega = p.heading_kp * wrap_angle(self.hold_heading_rad - heading_rad);
        let left = ring.side_m(Side::Left, FRAC_PI_4, FRAC_PI_2);
        let right = ring.side_m(Side::Right, FRAC_PI_4, FRAC_PI_2);
        if left < p.side_min_m {
            omega -= 3.0 * (p.side_min_m - left) / p.side_min_m;
        }
        if right < p.side_min_m {
            omega += 3.0 * (p.side_min_m - right) / p.side_min_m;
        }
        if left < p.side_min_m || right < p.side_min_m {
            // The heading to hold follows the edging, so that the robot
            // does not turn back into the wall once clear of it.
            self.hold_heading_rad =
                wrap_angle(heading_rad + 0.5 * wrap_angle(self.hold_heading_rad - heading_rad));
        }
        omega.clamp(-p.max_omega_radps, p.max_omega_radps)
    }

    /// Wall following on `side`: a PD law on the perpendicular distance;
    /// arcs toward the wall once it is lost.
    fn follow(&mut self, ring: &Ring, side: Side, dt_s: f64) -> f64 {
        let p = self.params;
        let s = side.sign();
        let d = ring.side_m(side, FRAC_PI_4, 112.5f64.to_radians());
        let omega = if d > p.wall_m + p.wall_lost_m {
            // Lost: arc round toward the wall at radius wall_m.
            self.last_wall_error_m = None;
            self.wall_steady = false;
            self.wall_lost = true;
            s * p.cruise_mps * 0.7 / p.wall_m
        } else {
            let e = d - p.wall_m;
            let de = self.last_wall_error_m.map_or(0.0, |last| (e - last) / dt_s);
            self.last_wall_error_m = Some(e);
            self.wall_steady = e.abs() <= 0.08;
            self.wall_lost = false;
            let mut w = s * (p.wall_kp * e.clamp(-0.3, 0.3) + p.wall_kd * de);
            // Keep clear of the other side in narrow places.
            let other = ring.side_m(side.other(), FRAC_PI_4, FRAC_PI_2);
            if other < p.side_min_m {
                w += s * 3.0 * (p.side_min_m - other) / p.side_min_m;
            }
            w
        };
        omega.clamp(-p.max_omega_radps, p.max_omega_radps)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ring(f: impl Fn(f64) -> f64) -> Ring {
        let pairs: Vec<(f64, f64)> = (0..16)
            .map(|k| {
                let deg = 22.5 * k as f64;
                (deg, f(wrap_angle(deg.to_radians())))
            })
            .collect();
        Ring::from_degrees(&pairs)
    }

    #[test]
    fn the_exit_turn_goes_at_least_90_degrees_then_until_clear() {
        let mut ex = Executor::new(
            StrategyParams::default(),
            Strategy::FreeMovement,
            Turn::Right,
            0.0,
        );
        let open = ring(|_| 5.0);
        let mut heading = 0.0;
        let mut ticks = 0;
        loop {
            let Progress::Drive(Command::Twist { omega_radps, v_mps }) = ex.step(&open, heading, true, 0.1)
            else {
                panic!("turning")
            };
            if ex.turned() {
                assert!(v_mps > 0.0);
                break;
            }
            assert_eq!(v_mps, 0.0);
            assert!(omega_radps < 0.0);
            heading = wrap_angle(heading + omega_radps * 0.1);
            ticks += 1;
            assert!(ticks < 100);
        }
        assert!((heading + FRAC_PI_2).abs() <= TURN_DONE_RAD, "{heading}");
    }

    /// Plays `ex` on a fixed ring, integrating the heading, until the exit
    /// turn is over; the heading then.
    fn turn_until_driving(ex: &mut Executor, ring: &Ring, mut heading: f64) -> f64 {
        for _ in 0..300 {
            let Progress::Drive(c) = ex.step(ring, heading, true, 0.1) else {
                panic!("turning")
            };
            if ex.turned() {
                return heading;
            }
            if let Command::Twist { omega_radps, .. } = c {
                heading = wrap_angle(heading + omega_radps * 0.1);
            }
        }
        panic!("never turned");
    }

    #[test]
    fn a_replayed_transition_turns_to_the_heading_it_left_on() {
        let p = StrategyParams::default();
        let open = ring(|_| 5.0);
        // Arrived facing 20° off the heading it stood on when the transition
        // was recorded: a right turn by steps would leave on −70°; aiming
        // leaves on the recorded −90°.
        let mut ex = Executor::aiming(p, Strategy::FreeMovement, Turn::Right, 0.35, -FRAC_PI_2);
        let h = turn_until_driving(&mut ex, &open, 0.35);
        assert!((h + FRAC_PI_2).abs() <= TURN_DONE_RAD, "{h}");
        let mut stepped = Executor::new(p, Strategy::FreeMovement, Turn::Right, 0.35);
        let h = turn_until_driving(&mut stepped, &open, 0.35);
        assert!((h - (0.35 - FRAC_PI_2)).abs() <= TURN_DONE_RAD, "{h}");
        // Blocked at the aimed heading (only facing back is clear): the
        // right turn's steps go on from there, to 180°.
        let mut ex = Executor::aiming(p, Strategy::FreeMovement, Turn::Right, 0.0, 0.0);
        let mut heading: f64 = 0.0;
        for _ in 0..400 {
            let facing_back = wrap_angle(heading - PI).abs() < 0.2;
            let r = ring(|_| if facing_back { 5.0 } else { 0.45 });
            match ex.step(&r, heading, true, 0.1) {
                Progress::Drive(Command::Twist { omega_radps, v_mps }) => {
                    if ex.turned() {
                        assert!(v_mps > 0.0);
                        break;
                    }
                    assert!(omega_radps <= 0.0, "turns right only");
                    heading = wrap_angle(heading + omega_radps * 0.1);
                }
                Progress::Drive(Command::Stop) => {}
                other => panic!("{other:?}"),
            }
        }
        assert!(ex.turned());
        assert!(wrap_angle(heading - PI).abs() <= TURN_DONE_RAD, "{heading}");
        // A detour ignores the heading (it turns toward its side).
        let ex = Executor::aiming(p, Strategy::DetourLeft, Turn::Left, 0.0, 2.0);
        assert!(matches!(ex.phase, Phase::Turning { sign, .. } if sign > 0.0));
    }

    #[test]
    fn a_wall_ahead_brakes_then_arrives_once_stopped() {
        let mut ex = Executor::new(
            StrategyParams::default(),
            Strategy::FreeMovement,
            Turn::Straight,
            0.0,
        );
        let wall = ring(|b| if b.abs() < 0.5 { 0.45 / b.cos() } else { 5.0 });
        assert_eq!(ex.step(&wall, 0.0, false, 0.1), Progress::Drive(Command::Stop));
        assert_eq!(ex.step(&wall, 0.0, false, 0.1), Progress::Drive(Command::Stop));
        assert_eq!(ex.step(&wall, 0.0, true, 0.1), Progress::Arrived);
        assert_eq!(ex.step(&wall, 0.0, true, 0.1), Progress::Arrived);
    }

    #[test]
    fn wall_following_turns_toward_a_far_wall_and_away_from_a_near_one() {
        let p = StrategyParams::default();
        let wall_at = |d: f64| ring(move |b| if b > 0.1 { d / b.sin() } else { 5.0 });
        let mut ex = Executor::new(p, Strategy::WallFollowLeft, Turn::Straight, 0.0);
        let Progress::Drive(Command::Twist { omega_radps, .. }) = ex.step(&wall_at(0.7), 0.0, false, 0.1)
        else {
            panic!()
        };
        assert!(omega_radps > 0.0);
        let mut ex = Executor::new(p, Strategy::WallFollowLeft, Turn::Straight, 0.0);
        let Progress::Drive(Command::Twist { omega_radps, .. }) = ex.step(&wall_at(0.3), 0.0, false, 0.1)
        else {
            panic!()
        };
        assert!(omega_radps < 0.0);
    }

    #[test]
    fn a_dead_end_everywhere_fails_with_no_way_out() {
        let mut ex = Executor::new(StrategyParams::default(), Strategy::FreeMovement, Turn::Left, 0.0);
        let closed = ring(|_| 0.4);
        let mut heading: f64 = 0.0;
        for _ in 0..200 {
            match ex.step(&closed, heading, true, 0.1) {
                Progress::Drive(Command::Twist { omega_radps, .. }) => {
                    heading = wrap_angle(heading + omega_radps * 0.1)
                }
                Progress::Failed(f) => {
                    assert_eq!(f, Failure::NoWayOut);
                    return;
                }
                other => panic!("{other:?}"),
            }
        }
        panic!("never failed");
    }

    #[test]
    fn the_actions_respect_the_place_types() {
        for kind in [PlaceKind::A, PlaceKind::B, PlaceKind::C] {
            for a in actions_at(kind, false) {
                assert!(kind.allows(a.strategy), "{kind:?} {a:?}");
                match kind {
                    PlaceKind::A => assert_eq!(a.exit_turn, Turn::Right),
                    PlaceKind::B => assert_eq!(a.exit_turn, Turn::Left),
                    PlaceKind::C => assert_ne!(a.exit_turn, Turn::Straight),
                }
            }
        }
        // A dead end adds wall following after either turn.
        let dead_end = actions_at(PlaceKind::C, true);
        assert!(
            actions_at(PlaceKind::C, false)
                .iter()
                .all(|a| dead_end.contains(a))
        );
        assert_eq!(
            dead_end.iter().filter(|a| a.strategy.is_wall_following()).count(),
            2
        );
    }

    #[test]
    fn bad_params_are_named() {
        let p = StrategyParams {
            stop_m: 1.0,
            ..StrategyParams::default()
        };
        assert!(p.validate().unwrap_err().contains("stop_m"));
        let p = StrategyParams {
            wall_m: f64::NAN,
            ..StrategyParams::default()
        };
        assert!(p.validate().unwrap_err().contains("wall_m"));
        assert!(StrategyParams::default().validate().is_ok());
    }
}
