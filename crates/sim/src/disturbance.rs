//! Disturbances: physical events that move the robot without its wheel
//! odometry seeing it (or seeing it right), or blind it for a long time —
//! the causes of *true* localisation loss.
//!
//! All three are off by default ([`DisturbanceParams::default`]): nothing is
//! drawn, nothing is checked, and a run is bit for bit what it is without
//! them. A caller turns them on with
//! [`Simulation::with_disturbances`](crate::Simulation::with_disturbances)
//! and reads back what happened with
//! [`Simulation::disturbances`](crate::Simulation::disturbances) (one
//! [`DisturbanceEvent`] each) and [`RunResult::disturbances`](crate::RunResult::disturbances)
//! (counts).
//!
//! ```
//! use robot::{Command, Pose};
//! use sim::{
//!     DisturbanceKind, DisturbanceParams, OccupancyGrid, OdometryParams, PushParams, RobotParams,
//!     RunParams, ScriptedController, Simulation, SlipParams, SlipPatch, Task, World,
//! };
//!
//! let world = World::new(OccupancyGrid::new(200, 100, 0.05, Pose::default()));
//! let robot = RobotParams { odometry: OdometryParams::perfect(), ..RobotParams::aibot() };
//! let task = Task { start: Pose::new(1.0, 2.5, 0.0), goal: None };
//! let run = RunParams { time_limit_s: 20.0, ..RunParams::default() };
//! let disturbances = DisturbanceParams {
//!     // A wet strip of floor across the robot's way…
//!     slip: SlipParams {
//!         patches: vec![SlipPatch { min: [3.0, 2.0], max: [4.0, 3.0] }],
//!         ..SlipParams::default()
//!     },
//!     // …and visitors who shove a robot standing among them.
//!     push: PushParams { rate_per_person_s: 0.05, ..PushParams::default() },
//!     ..DisturbanceParams::default()
//! };
//! let mut sim = Simulation::new(&world, robot, run, task, 3)?.with_disturbances(disturbances)?;
//! let mut drive = ScriptedController::new(vec![(Command::Twist { v_mps: 0.3, omega_radps: 0.0 }, 15.0)])?;
//! let result = sim.run(&mut drive);
//! assert_eq!(result.disturbances.slips, 1);
//! let DisturbanceKind::Slip { left_ratio, distance_m, odometry_distance_m, .. } = sim.disturbances()[0].kind
//! else { unreachable!() };
//! assert!(left_ratio <= 0.2 && distance_m < odometry_distance_m);
//! // The true pose and the dead-reckoned one part ways.
//! assert!(result.odometry_error_m > 0.0);
//! # Ok::<(), sim::Error>(())
//! ```
//!
//! # The model
//!
//! **1. Pushed while braked** ([`PushParams`]). Visitors shove a robot that
//! stands still, to get it out of their way or for fun; its wheels are
//! braked (or held by the motors), so they skid or the robot is dragged,
//! and the encoders count nothing: a kidnapping the odometry does not see.
//! The robot is *braked* once its forward speed, driven and commanded, has
//! been below `braked_speed_mps` for `braked_after_s` (per physics
//! sub-step, at its end): standing with its brakes on, or turning on the
//! spot, when its motors hold it against a push along the floor as brakes
//! would (a robot surrounded by visitors turns to and fro looking for a
//! way out, and is pushed all the same). While it is braked and not already
//! being pushed, each person whose disc comes within `reach_m` of the
//! footprint (rim to rim) pushes it with hazard `rate_per_person_s`: the
//! pushes form a non-homogeneous Poisson process of intensity
//! `λ(t) = rate · n_reach(t) · [braked(t)]`, drawn by inversion (R. Y.
//! Rubinstein, D. P. Kroese, *Simulation and the Monte Carlo Method*, §2.7
//! — the time change of a unit-rate process): push `k` strikes at the end
//! of the sub-step in which `Λ = Σ λ Δt`, accumulated since push `k − 1`,
//! reaches `E_k ~ Exp(1)`. Among the `n` people in reach at that moment
//! the pusher is the one of rank `⌊u_k n⌋` (ascending index), `u_k ~ U(0,
//! 1)`: the first of `n` equal competing hazards is uniform among them.
//!
//! A push moves the robot by `d ~ U(distance_min_m, distance_max_m)` along
//! the direction from the pusher's centre to the robot's centre turned by
//! `ψ ~ U(−direction_jitter_rad, direction_jitter_rad)`, and turns it by
//! `φ ~ U(−turn_max_rad, turn_max_rad)`, at constant rates over
//! `T = max(d / speed_mps, |φ| / turn_rate_radps)` (a pure translation
//! takes `d / speed_mps`, a pure turn `|φ| / turn_rate_radps`, and neither
//! rate exceeds its limit), by equal fractions of `(d, φ)` per physics
//! sub-step, from the sub-step after it strikes. A sub-step whose footprint
//! would overlap a blocked cell or a person's disc is refused and the push
//! ends there (the robot stops within one sub-step of the obstacle: at
//! most `speed_mps · Δt`, 5 cm at the defaults, short of it; it never
//! touches). While pushed, the robot is held: its wheels stay at 0 whatever
//! the controller commands (they ramp up from 0 afterwards) and the
//! encoders measure no rotation, so the dead-reckoned pose does not move.
//! The distance the centre travels counts in
//! [`RunResult::path_length_m`](crate::RunResult::path_length_m) (it is the
//! true path). The hazard does not accumulate during a push (one push at a
//! time), and it persists across periods of driving (it is the integral of
//! the intensity). A robot still commanded to stand after a push is still
//! braked and can be pushed again.
//!
//! **2. Wheel slip on marked floor patches** ([`SlipParams`]). Wet,
//! polished or carpeted patches of floor (a cleaned strip, a rug) where the
//! tyres lose grip. Each time the robot's *centre* enters a patch (the
//! first patch, by index, containing it changes to that patch, checked at
//! the start of each physics sub-step), slip ratios `s_l, s_r ~ U(0,
//! slip_max)` are drawn for the crossing; while the centre is in the patch
//! the robot truly moves as with rim speeds `(1 − s_l)·l` and `(1 − s_r)·r`
//! while the encoders measure the unslipped `l`, `r` (before the
//! odometry's own noise, [`crate::sensors::odometry`]): a scale error of
//! the odometry and, through `s_l ≠ s_r`, a heading error `(s_l − s_r)·D /
//! b` after `D` metres of straight driving on a base of `b`.
//!
//! **3. A group closing round the robot** ([`SurroundParams`]). A school
//! class or a tour group comes to look at the robot and stands all round
//! it: every laser beam ends on a person a metre away for as long as they
//! stay, and a controller cannot localise nor, usually, move. Events form a
//! homogeneous Poisson process of rate `rate_per_s` over mission time
//! (gaps `~ Exp(rate)`), each with a group size `m ~ U{group_min, …,
//! group_max}` and a duration `D ~ U(duration_min_s, duration_max_s)`. At
//! an event (applied at the end of the sub-step containing its time) the
//! `m` people nearest the robot's centre within `range_m` (fewer if fewer
//! are there; see [`Crowd::surround`] for who is skipped) come to it as the
//! crowd's visitors do and stand all round it until `t + D`, ignoring
//! requests to step aside; then they leave as after any visit.
//!
//! # Defaults and their grounds
//!
//! The defaults are assumptions of plausible magnitude for a museum, to be
//! varied in experiments, not measurements:
//!
//! - `push.braked_after_s` 1 s: people do not shove a robot that is moving
//!   or pausing between two moves; a second of stillness makes it an object
//!   in the way. `braked_speed_mps` 0.01 m/s: below the resolution of a
//!   speed command, i.e. stopped.
//! - `push.reach_m` 0.4 m: a push is done with bent arms from someone
//!   standing next to the robot, well within an adult's arm's length
//!   (≈ 0.6–0.7 m shoulder to fingertip).
//! - `push.distance_*` 0.3–2 m: from a nudge to dragging the robot aside
//!   by about a corridor's width. `turn_max_rad` π/2: a shove off-centre
//!   turns a small round base by up to a quarter turn.
//!   `direction_jitter_rad` π/6: people push roughly away from themselves.
//! - `push.speed_mps` 0.5 m/s: half a slow walk (1.0–1.4 m/s), the pace of
//!   someone shoving or dragging a 20–50 kg machine; `turn_rate_radps`
//!   1 rad/s: a quarter turn in about 1.6 s.
//! - `slip.slip_max` 0.2: up to 20 % lost travel per wheel, strong slip
//!   for rubber tyres on a wet or polished floor; J. Borenstein, L. Feng
//!   (*Measurement and correction of systematic odometry errors in mobile
//!   robots*, IEEE T-RA 12(6), 1996) list slippery floors among the
//!   non-systematic odometry errors.
//! - `surround.group_*` 6–10 people: a family or a small tour group;
//!   `duration_*` 20–60 s: the time visitors stand by an exhibit (the
//!   crowd's own `robot_linger_mean_s` is 20 s); `range_m` 12 m: a group in
//!   sight of the robot in a hall.
//! - All rates 0 and no patches: off.
//!
//! # Common random numbers
//!
//! Each disturbance draws from its own stream of the run's seed
//! ([`RandomStream::new`]`(seed, PUSH = 8 / SLIP = 9 / SURROUND = 10)`), in
//! a fixed order per event, whatever the robot does: push `k` draws `E_k`,
//! `d`, `φ`, `ψ`, `u_k` (five uniforms' worth, drawn when push `k − 1`
//! strikes, push 1 at the start); slip crossing `k` draws `s_l`, `s_r`;
//! surround event `k` draws its gap, size and duration (one uniform each).
//! No other stream is touched (people's streams, sensors, odometry draw as
//! before). So two controllers run on the same seed meet the same pushes
//! (the `k`-th push of one has the same size and turn as the `k`-th of the
//! other; whether and when it strikes depends on where and how long the
//! robot stands, as physically it should), the same slips on their `k`-th
//! crossings, and the same groups at the same times.
//!
//! # Cost
//!
//! Off: one branch per physics sub-step. On: per sub-step `O(1)`, plus
//! `O(patches)` for the slip look-up, plus, while braked, `O(people in
//! reach)` through the crowd's spatial hash ([`Crowd::within_gap`]); per
//! surround event `O(n log n)` for the `n` people in range and three rays
//! per person tried. No allocation per sub-step (one event per
//! disturbance).
//!
//! [`Crowd::surround`]: crate::Crowd::surround
//! [`Crowd::within_gap`]: crate::Crowd::within_gap
//! [`RandomStream::new`]: crate::RandomStream::new

use std::f64::consts::{FRAC_PI_2, FRAC_PI_6, PI};

use robot::{Pose, Vec2};

use crate::error::{Error, Result};
use crate::fast_math;
use crate::noise::{RandomStream, streams};
use crate::people::Crowd;
use crate::validate;
use crate::world::World;

/// Which disturbances happen, and how (module docs). The default turns all
/// off.
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct DisturbanceParams {
    /// Pushes while braked. Default off (rate 0).
    pub push: PushParams,
    /// Wheel slip on floor patches. Default off (no patches).
    pub slip: SlipParams,
    /// Groups closing round the robot. Default off (rate 0).
    pub surround: SurroundParams,
}

impl DisturbanceParams {
    /// Checks every field; errors are [`Error::InvalidValue`] naming it
    /// (`disturbance.push.reach_m`, `disturbance.slip.patches[2].max[0]`…).
    pub fn validate(&self) -> Result<()> {
        self.push.validate()?;
        self.slip.validate()?;
        self.surround.validate()
    }

    /// Whether nothing can happen: no push rate, no patch, no surround
    /// rate.
    pub fn is_off(&self) -> bool {
        self.push.rate_per_person_s == 0.0 && self.slip.patches.is_empty() && self.surround.rate_per_s == 0.0
    }
}

/// `max ≥ min`, else an error naming `what` (the maximum).
fn ordered(what: &str, min: f64, max: f64, requirement: &'static str) -> Result<()> {
    if max >= min {
        Ok(())
    } else {
        Err(Error::InvalidValue {
            what: what.to_string(),
            requirement,
            value: max,
        })
    }
}

/// Pushes while braked (module docs, model 1).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PushParams {
    /// Hazard of a push per person in reach per second of braked time,
    /// 1/s; 0: never. Default 0.
    pub rate_per_person_s: f64,
    /// A person pushes only when their disc is this close to the robot's
    /// footprint, rim to rim, metres. Default 0.4.
    pub reach_m: f64,
    /// The robot is braked after this long with its wheels and its command
    /// stopped, seconds. Default 1.0.
    pub braked_after_s: f64,
    /// Forward speeds (driven and commanded, the mean of the wheel rim
    /// speeds) below this count as standing, m/s, > 0. Default 0.01.
    pub braked_speed_mps: f64,
    /// Smallest translation of a push, metres. Default 0.3.
    pub distance_min_m: f64,
    /// Largest translation of a push, metres, ≥ `distance_min_m`.
    /// Default 2.0.
    pub distance_max_m: f64,
    /// Largest turn of a push either way, radians, in [0, π]. Default π/2.
    pub turn_max_rad: f64,
    /// Largest deviation of the push's direction from the line pusher →
    /// robot, radians, in [0, π]. Default π/6.
    pub direction_jitter_rad: f64,
    /// Speed at which the robot is pushed, m/s, > 0. Default 0.5.
    pub speed_mps: f64,
    /// Fastest turn while pushed (a pure turn's rate), rad/s, > 0.
    /// Default 1.0.
    pub turn_rate_radps: f64,
}

impl Default for PushParams {
    fn default() -> PushParams {
        PushParams {
            rate_per_person_s: 0.0,
            reach_m: 0.4,
            braked_after_s: 1.0,
            braked_speed_mps: 0.01,
            distance_min_m: 0.3,
            distance_max_m: 2.0,
            turn_max_rad: FRAC_PI_2,
            direction_jitter_rad: FRAC_PI_6,
            speed_mps: 0.5,
            turn_rate_radps: 1.0,
        }
    }
}

impl PushParams {
    /// Checks every field.
    pub fn validate(&self) -> Result<()> {
        validate::non_negative("disturbance.push.rate_per_person_s", self.rate_per_person_s)?;
        validate::non_negative("disturbance.push.reach_m", self.reach_m)?;
        validate::non_negative("disturbance.push.braked_after_s", self.braked_after_s)?;
        validate::positive("disturbance.push.braked_speed_mps", self.braked_speed_mps)?;
        validate::non_negative("disturbance.push.distance_min_m", self.distance_min_m)?;
        validate::non_negative("disturbance.push.distance_max_m", self.distance_max_m)?;
        ordered(
            "disturbance.push.distance_max_m",
            self.distance_min_m,
            self.distance_max_m,
            ">= distance_min_m",
        )?;
        validate::within(
            "disturbance.push.turn_max_rad",
            self.turn_max_rad,
            0.0,
            PI,
            "in [0, pi]",
        )?;
        validate::within(
            "disturbance.push.direction_jitter_rad",
            self.direction_jitter_rad,
            0.0,
            PI,
            "in [0, pi]",
        )?;
        validate::positive("disturbance.push.speed_mps", self.speed_mps)?;
        validate::positive("disturbance.push.turn_rate_radps", self.turn_rate_radps)
    }
}

/// An axis-aligned rectangle of slippery floor, world frame, metres.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SlipPatch {
    /// Lower-left corner `[x, y]`, metres.
    pub min: [f64; 2],
    /// Upper-right corner `[x, y]`, metres; each coordinate > `min`'s.
    pub max: [f64; 2],
}

impl SlipPatch {
    /// Whether `p` lies in the patch (borders included).
    pub fn contains(&self, p: Vec2) -> bool {
        p.x >= self.min[0] && p.x <= self.max[0] && p.y >= self.min[1] && p.y <= self.max[1]
    }
}

/// Wheel slip on floor patches (module docs, model 2).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SlipParams {
    /// The slippery patches. Default none (off).
    pub patches: Vec<SlipPatch>,
    /// Largest slip ratio of a wheel (fraction of its rim travel lost), in
    /// [0, 1]. Default 0.2.
    pub slip_max: f64,
}

impl Default for SlipParams {
    fn default() -> SlipParams {
        SlipParams {
            patches: Vec::new(),
            slip_max: 0.2,
        }
    }
}

impl SlipParams {
    /// Checks every field: corners finite, `min < max` on both axes.
    pub fn validate(&self) -> Result<()> {
        for (k, patch) in self.patches.iter().enumerate() {
            for axis in 0..2 {
                validate::finite(
                    &format!("disturbance.slip.patches[{k}].min[{axis}]"),
                    patch.min[axis],
                )?;
                validate::finite(
                    &format!("disturbance.slip.patches[{k}].max[{axis}]"),
                    patch.max[axis],
                )?;
                if patch.max[axis] <= patch.min[axis] {
                    return Err(Error::InvalidValue {
                        what: format!("disturbance.slip.patches[{k}].max[{axis}]"),
                        requirement: "> the same coordinate of min",
                        value: patch.max[axis],
                    });
                }
            }
        }
        validate::within("disturbance.slip.slip_max", self.slip_max, 0.0, 1.0, "in [0, 1]")
    }

    /// The first patch (by index) containing `p`.
    fn patch_at(&self, p: Vec2) -> Option<usize> {
        self.patches.iter().position(|q| q.contains(p))
    }
}

/// Largest group size accepted (guards the draw against absurd values).
const MAX_GROUP: usize = 100_000;

/// Groups closing round the robot (module docs, model 3).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SurroundParams {
    /// Events per second of mission time; 0: never. Default 0.
    pub rate_per_s: f64,
    /// Smallest group, people, ≥ 1. Default 6.
    pub group_min: usize,
    /// Largest group, people, ≥ `group_min` (at most 100 000). Default 10.
    pub group_max: usize,
    /// Shortest stay, seconds. Default 20.
    pub duration_min_s: f64,
    /// Longest stay, seconds, ≥ `duration_min_s`. Default 60.
    pub duration_max_s: f64,
    /// Only people whose centre is this close to the robot's come,
    /// metres. Default 12.
    pub range_m: f64,
}

impl Default for SurroundParams {
    fn default() -> SurroundParams {
        SurroundParams {
            rate_per_s: 0.0,
            group_min: 6,
            group_max: 10,
            duration_min_s: 20.0,
            duration_max_s: 60.0,
            range_m: 12.0,
        }
    }
}

impl SurroundParams {
    /// Checks every field.
    pub fn validate(&self) -> Result<()> {
        validate::non_negative("disturbance.surround.rate_per_s", self.rate_per_s)?;
        validate::count_within(
            "disturbance.surround.group_min",
            self.group_min,
            1,
            MAX_GROUP,
            "in [1, 100000]",
        )?;
        validate::count_within(
            "disturbance.surround.group_max",
            self.group_max,
            self.group_min,
            MAX_GROUP,
            ">= group_min and <= 100000",
        )?;
        validate::non_negative("disturbance.surround.duration_min_s", self.duration_min_s)?;
        validate::non_negative("disturbance.surround.duration_max_s", self.duration_max_s)?;
        ordered(
            "disturbance.surround.duration_max_s",
            self.duration_min_s,
            self.duration_max_s,
            ">= duration_min_s",
        )?;
        validate::non_negative("disturbance.surround.range_m", self.range_m)
    }
}

/// What happened (module docs).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum DisturbanceKind {
    /// The robot was pushed while braked.
    Push {
        /// Index of the pusher in the crowd ([`crate::Crowd::people`]).
        pusher: usize,
        /// World direction of the push, radians.
        direction_rad: f64,
        /// Translation drawn, metres.
        intended_translation_m: f64,
        /// Turn drawn, radians (positive: counter-clockwise).
        intended_rotation_rad: f64,
        /// Translation applied so far (less than drawn when stopped early
        /// or still going), metres.
        applied_translation_m: f64,
        /// Turn applied so far, radians.
        applied_rotation_rad: f64,
        /// The push ended early: the footprint would have touched a wall
        /// or a person.
        stopped_early: bool,
    },
    /// The robot's centre crossed a slippery patch.
    Slip {
        /// Index of the patch in [`SlipParams::patches`].
        patch: usize,
        /// Left wheel's slip ratio.
        left_ratio: f64,
        /// Right wheel's slip ratio.
        right_ratio: f64,
        /// True distance the centre was driven in the patch, metres.
        distance_m: f64,
        /// Distance the encoders measured meanwhile (before the odometry's
        /// own noise: the mean of the two wheels' rim travel), metres.
        odometry_distance_m: f64,
    },
    /// A group closed round the robot.
    Surround {
        /// Group size drawn.
        group_size: usize,
        /// Stay drawn, seconds.
        duration_s: f64,
        /// The people who came (indices in the crowd), nearest first
        /// (fewer than `group_size` if fewer were in range).
        people: Vec<usize>,
    },
}

impl DisturbanceKind {
    /// `"push"`, `"slip"` or `"surround"`.
    pub fn name(&self) -> &'static str {
        match self {
            DisturbanceKind::Push { .. } => "push",
            DisturbanceKind::Slip { .. } => "slip",
            DisturbanceKind::Surround { .. } => "surround",
        }
    }
}

/// One disturbance of a run: when, and what (serialised flat, with a
/// `kind` tag: `{"start_s":…, "end_s":…, "kind":"push", "pusher":…}`).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct DisturbanceEvent {
    /// When it began, seconds: for a push the end of the sub-step in which
    /// it struck (the robot moves from the next one), for a slip the start
    /// of the first sub-step with the centre in the patch, for a surround
    /// the event's time in its Poisson process (applied at the end of the
    /// sub-step containing it).
    pub start_s: f64,
    /// When it ended, seconds (`None`: still going when last looked at).
    /// For a surround, the start plus the duration drawn.
    pub end_s: Option<f64>,
    /// What happened.
    #[serde(flatten)]
    pub kind: DisturbanceKind,
}

/// Totals of a run's disturbances.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct DisturbanceCounts {
    /// Pushes that struck.
    pub pushes: u32,
    /// Pushes ended early against a wall or a person.
    pub pushes_stopped_early: u32,
    /// Total translation pushed, metres.
    pub pushed_m: f64,
    /// Total turn pushed (absolute), radians.
    pub pushed_rad: f64,
    /// Patch crossings.
    pub slips: u32,
    /// True distance driven in patches, metres.
    pub slip_distance_m: f64,
    /// Surround events.
    pub surrounds: u32,
    /// People who came, over all surround events.
    pub surround_people: u32,
}

impl DisturbanceCounts {
    /// Whether nothing happened.
    pub fn is_zero(&self) -> bool {
        *self == DisturbanceCounts::default()
    }
}

/// The random numbers of one push, drawn in this order (module docs).
#[derive(Debug, Clone, Copy)]
struct PushDraw {
    /// `E_k ~ Exp(1)`.
    threshold: f64,
    distance_m: f64,
    rotation_rad: f64,
    jitter_rad: f64,
    /// `u_k ~ U(0, 1)`: which of the people in reach pushes.
    pick: f64,
}

impl PushDraw {
    fn new(rng: &mut RandomStream, p: &PushParams) -> PushDraw {
        let threshold = rng.exponential(1.0);
        let distance_m = rng.uniform_in(p.distance_min_m, p.distance_max_m);
        let rotation_rad = rng.uniform_in(-p.turn_max_rad, p.turn_max_rad);
        let jitter_rad = rng.uniform_in(-p.direction_jitter_rad, p.direction_jitter_rad);
        let pick = rng.uniform();
        PushDraw {
            threshold,
            distance_m,
            rotation_rad,
            jitter_rad,
            pick,
        }
    }
}

/// A push under way.
#[derive(Debug, Clone, Copy)]
struct ActivePush {
    /// Its entry in the event list.
    event: usize,
    /// Unit vector of the push, world frame.
    direction: Vec2,
    distance_m: f64,
    rotation_rad: f64,
    duration_s: f64,
    elapsed_s: f64,
}

#[derive(Debug, Clone)]
struct PushState {
    rng: RandomStream,
    next: PushDraw,
    /// `Λ` since the last push.
    hazard: f64,
    /// How long wheels and command have been stopped, seconds.
    still_for_s: f64,
    active: Option<ActivePush>,
}

#[derive(Debug, Clone)]
struct SlipState {
    rng: RandomStream,
    /// The patch the centre is in, its event and its `(s_l, s_r)`.
    inside: Option<(usize, usize, (f64, f64))>,
}

#[derive(Debug, Clone)]
struct SurroundState {
    rng: RandomStream,
    /// Time of the next event, its group size and duration.
    next_s: f64,
    group: usize,
    duration_s: f64,
}

impl SurroundState {
    /// Draws the event after one at `after_s`: gap, size, duration.
    fn draw(&mut self, p: &SurroundParams, after_s: f64) {
        self.next_s = after_s + self.rng.exponential(1.0 / p.rate_per_s);
        let span = p.group_max - p.group_min + 1;
        self.group = p.group_min + ((self.rng.uniform() * span as f64) as usize).min(span - 1);
        self.duration_s = self.rng.uniform_in(p.duration_min_s, p.duration_max_s);
    }
}

/// The disturbances of a run in progress (used by the simulation).
#[derive(Debug, Clone)]
pub(crate) struct Disturbances {
    params: DisturbanceParams,
    events: Vec<DisturbanceEvent>,
    counts: DisturbanceCounts,
    push: Option<PushState>,
    slip: Option<SlipState>,
    surround: Option<SurroundState>,
    /// People in reach (reused).
    near: Vec<usize>,
}

impl Disturbances {
    /// The disturbances `params` of a run of seed `seed`, starting at
    /// `now_s`; `None` when they are all off (nothing to do, nothing
    /// drawn).
    pub(crate) fn new(params: DisturbanceParams, seed: u64, now_s: f64) -> Result<Option<Disturbances>> {
        params.validate()?;
        if params.is_off() {
            return Ok(None);
        }
        let push = (params.push.rate_per_person_s > 0.0).then(|| {
            let mut rng = RandomStream::new(seed, streams::PUSH);
            let next = PushDraw::new(&mut rng, &params.push);
            PushState {
                rng,
                next,
                hazard: 0.0,
                still_for_s: 0.0,
                active: None,
            }
        });
        let slip = (!params.slip.patches.is_empty()).then(|| SlipState {
            rng: RandomStream::new(seed, streams::SLIP),
            inside: None,
        });
        let surround = (params.surround.rate_per_s > 0.0).then(|| {
            let mut s = SurroundState {
                rng: RandomStream::new(seed, streams::SURROUND),
                next_s: 0.0,
                group: 0,
                duration_s: 0.0,
            };
            s.draw(&params.surround, now_s);
            s
        });
        Ok(Some(Disturbances {
            params,
            events: Vec::new(),
            counts: DisturbanceCounts::default(),
            push,
            slip,
            surround,
            near: Vec::new(),
        }))
    }

    /// The parameters.
    pub(crate) fn params(&self) -> &DisturbanceParams {
        &self.params
    }

    /// What has happened so far.
    pub(crate) fn events(&self) -> &[DisturbanceEvent] {
        &self.events
    }

    /// Totals so far.
    pub(crate) fn counts(&self) -> DisturbanceCounts {
        self.counts
    }

    /// Whether a push is under way (the robot is held).
    pub(crate) fn held(&self) -> bool {
        self.push.as_ref().is_some_and(|p| p.active.is_some())
    }

    /// One sub-step of `dt_s` ending at `end_s` of the push under way from
    /// `pose`: the new pose, or `pose` when the footprint at the next
    /// position would be `blocked` (the push then ends).
    pub(crate) fn push_step(
        &mut self,
        pose: Pose,
        dt_s: f64,
        end_s: f64,
        blocked: impl Fn(Vec2) -> bool,
    ) -> Pose {
        let Some(state) = &mut self.push else {
            return pose;
        };
        let Some(a) = &mut state.active else {
            return pose;
        };
        let before = (a.elapsed_s / a.duration_s).min(1.0);
        a.elapsed_s += dt_s;
        let after = (a.elapsed_s / a.duration_s).min(1.0);
        let f = after - before;
        let next = fast_math::pose(
            pose.x_m + a.direction.x * a.distance_m * f,
            pose.y_m + a.direction.y * a.distance_m * f,
            pose.theta_rad + a.rotation_rad * f,
        );
        let event = &mut self.events[a.event];
        if blocked(next.position()) {
            event.end_s = Some(end_s);
            if let DisturbanceKind::Push { stopped_early, .. } = &mut event.kind {
                *stopped_early = true;
            }
            self.counts.pushes_stopped_early += 1;
            state.active = None;
            return pose;
        }
        if let DisturbanceKind::Push {
            applied_translation_m,
            applied_rotation_rad,
            ..
        } = &mut event.kind
        {
            *applied_translation_m = a.distance_m * after;
            *applied_rotation_rad = a.rotation_rad * after;
        }
        self.counts.pushed_m += a.distance_m * f;
        self.counts.pushed_rad += (a.rotation_rad * f).abs();
        if after >= 1.0 {
            event.end_s = Some(end_s);
            state.active = None;
        }
        next
    }

    /// The slip ratios `(s_l, s_r)` for a sub-step starting at `time_s`
    /// with the robot's centre at `at`, if it is in a patch; a crossing
    /// into a patch draws them and opens its event, leaving one closes it.
    pub(crate) fn slip_at(&mut self, at: Vec2, time_s: f64) -> Option<(f64, f64)> {
        let state = self.slip.as_mut()?;
        let now = self.params.slip.patch_at(at);
        if let Some((patch, event, ratios)) = state.inside {
            if now == Some(patch) {
                return Some(ratios);
            }
            self.events[event].end_s = Some(time_s);
            state.inside = None;
        }
        let patch = now?;
        let s = self.params.slip.slip_max;
        let ratios = (state.rng.uniform_in(0.0, s), state.rng.uniform_in(0.0, s));
        state.inside = Some((patch, self.events.len(), ratios));
        self.events.push(DisturbanceEvent {
            start_s: time_s,
            end_s: None,
            kind: DisturbanceKind::Slip {
                patch,
                left_ratio: ratios.0,
                right_ratio: ratios.1,
                distance_m: 0.0,
                odometry_distance_m: 0.0,
            },
        });
        self.counts.slips += 1;
        Some(ratios)
    }

    /// Adds a sub-step driven in the current patch: `true_m` travelled by
    /// the centre, `measured_m` by the encoders' reckoning.
    pub(crate) fn slipped(&mut self, true_m: f64, measured_m: f64) {
        let Some((_, event, _)) = self.slip.as_ref().and_then(|s| s.inside) else {
            return;
        };
        if let DisturbanceKind::Slip {
            distance_m,
            odometry_distance_m,
            ..
        } = &mut self.events[event].kind
        {
            *distance_m += true_m;
            *odometry_distance_m += measured_m;
        }
        self.counts.slip_distance_m += true_m;
    }

    /// Book-keeping at the end of a physics sub-step of `dt_s` ending at
    /// `end_s`, the robot's footprint at `pose` with radius `radius_m`, its
    /// wheels driven at `wheels_mps` and commanded to `commanded_mps`:
    /// the braked clock, the push hazard (a push may strike), surround
    /// events due.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn after_substep(
        &mut self,
        world: &World,
        crowd: &mut Crowd,
        pose: Pose,
        radius_m: f64,
        wheels_mps: (f64, f64),
        commanded_mps: (f64, f64),
        end_s: f64,
        dt_s: f64,
    ) {
        let at = pose.position();
        if let Some(state) = &mut self.push {
            let p = &self.params.push;
            // Standing: neither driving nor commanded to drive forward or
            // back (turning on the spot the motors hold the robot as
            // brakes would).
            let still = [
                0.5 * (wheels_mps.0 + wheels_mps.1),
                0.5 * (commanded_mps.0 + commanded_mps.1),
            ]
            .iter()
            .all(|v| v.abs() < p.braked_speed_mps);
            state.still_for_s = if still { state.still_for_s + dt_s } else { 0.0 };
            // Tolerance for a clock summed in steps of dt.
            if state.active.is_none() && still && state.still_for_s >= p.braked_after_s - 1e-9 {
                crowd.within_gap(at, radius_m, p.reach_m, &mut self.near);
                let n = self.near.len();
                if n > 0 {
                    state.hazard += p.rate_per_person_s * n as f64 * dt_s;
                    if state.hazard >= state.next.threshold {
                        let draw = std::mem::replace(&mut state.next, PushDraw::new(&mut state.rng, p));
                        state.hazard = 0.0;
                        let pusher = self.near[((draw.pick * n as f64) as usize).min(n - 1)];
                        let from = crowd.people()[pusher].position;
                        let away = at - from;
                        let direction_rad = away.y.atan2(away.x) + draw.jitter_rad;
                        let duration_s =
                            (draw.distance_m / p.speed_mps).max(draw.rotation_rad.abs() / p.turn_rate_radps);
                        let event = self.events.len();
                        self.events.push(DisturbanceEvent {
                            start_s: end_s,
                            end_s: (duration_s <= 0.0).then_some(end_s),
                            kind: DisturbanceKind::Push {
                                pusher,
                                direction_rad: fast_math::wrap(direction_rad),
                                intended_translation_m: draw.distance_m,
                                intended_rotation_rad: draw.rotation_rad,
                                applied_translation_m: 0.0,
                                applied_rotation_rad: 0.0,
                                stopped_early: false,
                            },
                        });
                        self.counts.pushes += 1;
                        if duration_s > 0.0 {
                            state.active = Some(ActivePush {
                                event,
                                direction: Vec2::new(direction_rad.cos(), direction_rad.sin()),
                                distance_m: draw.distance_m,
                                rotation_rad: draw.rotation_rad,
                                duration_s,
                                elapsed_s: 0.0,
                            });
                        }
                    }
                }
            }
        }
        if let Some(state) = &mut self.surround {
            let p = &self.params.surround;
            while state.next_s <= end_s {
                let (start_s, group_size, duration_s) = (state.next_s, state.group, state.duration_s);
                let until_s = start_s + duration_s;
                let people = crowd.surround(world, (at, radius_m), group_size, p.range_m, end_s, until_s);
                self.counts.surrounds += 1;
                self.counts.surround_people += people.len() as u32;
                self.events.push(DisturbanceEvent {
                    start_s,
                    end_s: Some(until_s),
                    kind: DisturbanceKind::Surround {
                        group_size,
                        duration_s,
                        people,
                    },
                });
                state.draw(p, start_s);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Sets field `field` of the parameters to `v`.
    fn with(field: &str, v: f64) -> DisturbanceParams {
        let mut d = DisturbanceParams::default();
        let (p, s, g) = (&mut d.push, &mut d.slip, &mut d.surround);
        match field {
            "push.rate_per_person_s" => p.rate_per_person_s = v,
            "push.reach_m" => p.reach_m = v,
            "push.braked_after_s" => p.braked_after_s = v,
            "push.braked_speed_mps" => p.braked_speed_mps = v,
            "push.distance_min_m" => p.distance_min_m = v,
            "push.distance_max_m" => p.distance_max_m = v,
            "push.turn_max_rad" => p.turn_max_rad = v,
            "push.direction_jitter_rad" => p.direction_jitter_rad = v,
            "push.speed_mps" => p.speed_mps = v,
            "push.turn_rate_radps" => p.turn_rate_radps = v,
            "slip.slip_max" => s.slip_max = v,
            "surround.rate_per_s" => g.rate_per_s = v,
            "surround.duration_min_s" => g.duration_min_s = v,
            "surround.duration_max_s" => g.duration_max_s = v,
            "surround.range_m" => g.range_m = v,
            _ => unreachable!("{field}"),
        }
        d
    }

    fn named(d: &DisturbanceParams) -> String {
        match d.validate() {
            Err(Error::InvalidValue { what, .. }) => what,
            other => panic!("{d:?}: {other:?}"),
        }
    }

    #[test]
    fn defaults_are_valid_and_off() {
        let d = DisturbanceParams::default();
        assert!(d.validate().is_ok() && d.is_off());
        assert!(Disturbances::new(d, 1, 0.0).unwrap().is_none(), "nothing to run");
        assert_eq!(PushParams::default().reach_m, 0.4);
        assert_eq!(SlipParams::default().slip_max, 0.2);
        assert_eq!(SurroundParams::default().group_max, 10);
    }

    #[test]
    fn bad_parameters_are_errors_naming_them() {
        let fields = [
            "push.rate_per_person_s",
            "push.reach_m",
            "push.braked_after_s",
            "push.braked_speed_mps",
            "push.distance_min_m",
            "push.distance_max_m",
            "push.turn_max_rad",
            "push.direction_jitter_rad",
            "push.speed_mps",
            "push.turn_rate_radps",
            "slip.slip_max",
            "surround.rate_per_s",
            "surround.duration_min_s",
            "surround.duration_max_s",
            "surround.range_m",
        ];
        for field in fields {
            for v in [-1.0, f64::NAN, f64::INFINITY] {
                assert_eq!(
                    named(&with(field, v)),
                    format!("disturbance.{field}"),
                    "{field} = {v}"
                );
            }
        }
        // Out of range but finite.
        for (field, v) in [
            ("push.turn_max_rad", 4.0),
            ("push.direction_jitter_rad", 3.5),
            ("push.braked_speed_mps", 0.0),
            ("push.speed_mps", 0.0),
            ("push.turn_rate_radps", 0.0),
            ("slip.slip_max", 1.5),
        ] {
            assert_eq!(named(&with(field, v)), format!("disturbance.{field}"));
        }
        // Minimum above maximum: the maximum is named.
        assert_eq!(
            named(&with("push.distance_min_m", 3.0)),
            "disturbance.push.distance_max_m"
        );
        assert_eq!(
            named(&with("surround.duration_min_s", 61.0)),
            "disturbance.surround.duration_max_s"
        );
        let mut d = DisturbanceParams::default();
        d.surround.group_max = 5;
        assert_eq!(named(&d), "disturbance.surround.group_max");
        d.surround.group_min = 0;
        assert_eq!(named(&d), "disturbance.surround.group_min");
        // Patches: finite corners, min < max on both axes.
        let patch = |min: [f64; 2], max: [f64; 2]| DisturbanceParams {
            slip: SlipParams {
                patches: vec![
                    SlipPatch {
                        min: [0.0, 0.0],
                        max: [1.0, 1.0],
                    },
                    SlipPatch { min, max },
                ],
                ..SlipParams::default()
            },
            ..DisturbanceParams::default()
        };
        assert!(patch([0.0, 0.0], [1.0, 2.0]).validate().is_ok());
        assert_eq!(
            named(&patch([1.0, 0.0], [1.0, 2.0])),
            "disturbance.slip.patches[1].max[0]"
        );
        assert_eq!(
            named(&patch([0.0, 3.0], [1.0, 2.0])),
            "disturbance.slip.patches[1].max[1]"
        );
        assert_eq!(
            named(&patch([f64::NAN, 0.0], [1.0, 2.0])),
            "disturbance.slip.patches[1].min[0]"
        );
        assert_eq!(
            named(&patch([0.0, 0.0], [1.0, f64::INFINITY])),
            "disturbance.slip.patches[1].max[1]"
        );
    }

    #[test]
    fn draws_come_in_a_fixed_order_per_event() {
        let p = PushParams {
            rate_per_person_s: 1.0,
            ..PushParams::default()
        };
        let mut rng = RandomStream::new(5, streams::PUSH);
        let a = PushDraw::new(&mut rng, &p);
        let b = PushDraw::new(&mut rng, &p);
        // By hand from the same stream: E, d, φ, ψ, u per push.
        let mut r = RandomStream::new(5, streams::PUSH);
        for draw in [a, b] {
            assert_eq!(draw.threshold, r.exponential(1.0));
            assert_eq!(draw.distance_m, r.uniform_in(0.3, 2.0));
            assert_eq!(draw.rotation_rad, r.uniform_in(-FRAC_PI_2, FRAC_PI_2));
            assert_eq!(draw.jitter_rad, r.uniform_in(-FRAC_PI_6, FRAC_PI_6));
            assert_eq!(draw.pick, r.uniform());
        }
        assert!((0.3..2.0).contains(&a.distance_m) && a.rotation_rad.abs() <= FRAC_PI_2);
        // Surround: gap, size, duration; sizes cover [min, max].
        let s = SurroundParams {
            rate_per_s: 0.1,
            group_min: 2,
            group_max: 4,
            ..SurroundParams::default()
        };
        let mut state = SurroundState {
            rng: RandomStream::new(5, streams::SURROUND),
            next_s: 0.0,
            group: 0,
            duration_s: 0.0,
        };
        let mut seen = [0; 5];
        let mut t = 0.0;
        for _ in 0..300 {
            state.draw(&s, t);
            assert!(state.next_s >= t && (20.0..60.0).contains(&state.duration_s));
            t = state.next_s;
            seen[state.group] += 1;
        }
        assert_eq!(seen[..2], [0, 0]);
        assert!(seen[2..].iter().all(|&k| k > 60), "{seen:?}");
        // 300 gaps of mean 10 s.
        assert!((t / 300.0 - 10.0).abs() < 2.0, "{}", t / 300.0);
    }

    #[test]
    fn events_serialise_flat_with_their_kind() {
        let e = DisturbanceEvent {
            start_s: 1.5,
            end_s: None,
            kind: DisturbanceKind::Surround {
                group_size: 3,
                duration_s: 20.0,
                people: vec![4, 2],
            },
        };
        let json = serde_json::to_string(&e).unwrap();
        assert_eq!(
            json,
            r#"{"start_s":1.5,"end_s":null,"kind":"surround","group_size":3,"duration_s":20.0,"people":[4,2]}"#
        );
        assert_eq!(e.kind.name(), "surround");
    }
}
