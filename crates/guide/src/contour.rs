//! Contour tracking: following the contour of walls, exhibits (and people)
//! at a set distance from the raw laser scan, every control cycle, and
//! leaving it towards the goal when the way is clear (docs/tour-guide.md).
//!
//! **Following.** The contour is the set of scan points on the followed
//! side (left or right; bearings from 45° across the front to 180° on that
//! side, so a wall ahead counts before the robot reaches it, and within
//! `d* + lost_m`). A 180° laser ahead of the centre cannot see the wall
//! beside or behind the robot's centre — the very part whose distance is to
//! be held — so the nearest contour point of every cycle is remembered in
//! the odometry frame for `memory_s` seconds, and remembered points now out
//! of the laser's view count as contour too (the scan is believed where it
//! looks: what it no longer shows is gone).
//!
//! The law looks ahead along the contour: with `n` the contour point
//! nearest the robot and `t` the contour's tangent there (the direction
//! that keeps the contour on its side), the spot `a = L t` ahead of the
//! robot is moved onto the offset curve — to distance `d*` from the
//! contour point nearest it — and the robot steers at that target:
//! `ψ = bearing(target)`, `ω = k_ψ ψ`, `v = v_cruise · max(0, cos ψ)`,
//! slowed further near obstacles ahead. Along a straight wall the target
//! lies on the parallel at `d*`, so the robot converges to it; round a
//! convex corner the target lies on the circle of radius `d*` about the
//! corner, so the robot circles it without the lag of a law that only
//! looks sideways; at a concave corner the wall ahead pulls the target
//! away from it before the robot gets there.
//!
//! **Stalls.** A robot that follows a contour without getting `stall_m`
//! anywhere for `stall_s` (wedged in a pocket, turning back and forth at a
//! gap too narrow for it) turns round and follows the contour the other
//! way, as a wall follower does at a dead end.
//!
//! **Centred.** When both sides have a contour (bearings 45°–135°) and
//! `d_left + d_right ≤ corridor_m`, the robot keeps to the middle:
//! `ψ = (tangent of both) + atan(k_d (d_left − d_right) / 2)`.
//!
//! **Decision — the leave rule (Bug2-like).** The tracker starts by driving
//! straight at the goal (`Seek`); when something stands within `hit_m`
//! ahead and in the goal's way it stops and asks (below), turns on the
//! spot to face the goal (within 17°) if it does not already, records the
//! distance to the goal (the hit point) and starts following the obstacle
//! on the side that turns the robot less from the goal's bearing, chosen
//! once it faces the goal (a side chosen from a scan that cannot see the
//! way round sent the robot the long way). It leaves the contour for the
//! goal when (a) the goal's bearing is within the laser's view and clear, a
//! corridor as wide as the robot plus `margin_m`, up to `leave_clear_m` or
//! the goal, and (b) the goal is at least `leave_progress_m` nearer than at
//! the hit point (Lumelsky & Stepanov's Bug2 condition, which keeps the
//! robot from circling an obstacle for ever with exact sensing). It needs
//! the robot's pose only for the goal's bearing and distance: a poor
//! localization bends the route, it does not stop the tracking. A contour
//! lost for `lost_after_s` (nothing seen or remembered on its side: a
//! person who walked away) is left for the goal too — a Bug algorithm
//! leaves an obstacle it no longer senses; the arc towards a lost contour
//! otherwise circles on the spot for ever, since Bug2's progress condition
//! is never met there. Rejected: no hit until the robot faces the goal,
//! because AutoMove's hand-over among visitors then drove on instead of
//! stopping to ask (collisions tripled in the museum); rejected: a hit that
//! ends only once the way has stayed clear for 0.25–0.5 s, because the
//! robot then waits out every brief opening between visitors.
//!
//! **The scan.** Every cycle the tracker reads the scan through a 3-beam
//! median filter ([`scan::median3`]): the safety layer's margins below are
//! a few σ of the laser's noise (σ 0.01 m), and a lone short reading must
//! not stop the robot in a door.
//!
//! **Decision — doors (gaps narrower than the usual clearance).** A door of
//! 0.80 m is 5 cm wider than the 0.70 m robot on either side: the usual
//! room check, the centred law (which takes a jamb's corner for a wall) and
//! the stall rule all refuse it, and the cause is not a margin but the lack
//! of a way to pass a gap, so there is one. A *gap* is the narrowest pair
//! of scan points, one inside the usual clearance ahead, between
//! `2 (r + pass_margin_m)` and `2 (r + margin_m)` apart, with nothing
//! between them and room for the footprint beyond (not a corner), in the
//! direction the law wants to go when that direction is blocked for the
//! usual clearance (not a niche beside a free corridor). The robot then
//! steers by pure pursuit onto the line through the gap's middle
//! ([`GAP_LOOKAHEAD_M`] ahead), at `creep_mps`, until its footprint is
//! through; from off the line and near the sides the look-ahead shortens
//! (`L` between 0.05 and 0.25 m) so that the offset, decaying as
//! `e^(−s / L)`, is within 2 cm when the footprint's front reaches the
//! sides' line. Once found, a gap is what its sides are: its middle between
//! them and its line square to them (smoothed pair directions let a door's
//! line turn as its sides were seen from nearer), and while it is being
//! passed only pairs within 0.2 m of its middle are looked at (a narrower
//! false pair can otherwise take the door's place). Of each side the point
//! nearest its line is kept once the robot is in the gap (the safety
//! layer's 5 cm squares lie up to 1.8 cm off a jamb's corner and are
//! forgotten after 3 s), and the sides are obstacles for the safety layer.
//! Only there, at creep speed, the safety layer's margin is
//! `pass_margin_m` (0.015 m: 2.2 σ of the filtered noise), growing linearly
//! to `safety_margin_m` at `cruise_mps` (speed-dependent protective fields
//! as on industrial safety scanners). A gap the robot stalls at is refused
//! for 30 s. In a gap the robot asks people to step aside: a gap between
//! people widens, a door does not. Not solved: a door approached steeply
//! from within ~0.5 m of its wall is lost when its far jamb is beyond the
//! 1.5 m search reach, and the robot then follows the wall past it.
//!
//! **Decision — asking people to step aside.** Contour tracking has no map
//! and cannot tell a person from a wall, so it does what a guide robot
//! does: "excuse me" whenever it is held up, and a wall simply does not
//! move. It asks ([`Request::StepAside`], `ask_radius_m`, the request
//! AutoMove makes) when (a) seeking, its way to the goal is blocked: it
//! stops and asks for `hit_wait_s` before it follows what blocks it (3 s:
//! people react after 0.5–1.5 s and walk 1 m beyond the radius); (b) it has
//! been held up for `ask_after_s` (turning on the spot because the way
//! ahead is blocked, or stopped by the safety layer); (c) it is following
//! something that stands on the goal's bearing within `hit_m`; (d) it is
//! passing a gap. A person who steps aside takes the contour away, and the
//! lost-contour rule sends the robot back to the goal. The safety layer
//! remembers what it saw beside the robot for `safety_memory_s` (10 s, not
//! the 3 s AutoMove's uses): after a 3 s wait it forgot the wall beside it
//! and turned into it.
//!
//! **Decision — passages (the far side ahead is not a wall ahead).** The
//! front sector (from −45° on the other side) can put the far side of a
//! passage into the followed contour, and its nearest point then fails the
//! corridor check and turns the robot back. So the corridor check asks that
//! nothing of the followed side's *own half* — what lies beside or ahead of
//! the robot's centre on that side, remembered points included — be nearer
//! than the middle: what stands ahead on the other half is the far side of
//! a passage, and the robot centres between the two. Only while it moves
//! (the last command at least `creep_mps`): turning on the spot sweeps the
//! front sector across both halves, and the centred flag then flipped every
//! few cycles while the robot was wedged. Rejected: front points counted
//! only when chained to the contour beside the robot, and the tangent taken
//! from the own half's nearest point, because the obstacle met at the hit
//! point was then lost; rejected: the other half's point taken as the
//! nearest only when 0.1 m nearer than the own half's, because a person
//! ahead on the other side was then followed too late. Still fragile: a
//! room whose way out is a maze of furniture, where the nearest contour
//! point can jump to furniture on the other half and the law follows that
//! instead. Test: `tests/contour.rs`, the passage leg on the real map by
//! dead reckoning.
//!
//! The figures behind these decisions, and the variants rejected, are in
//! `crates/guide/EXPERIMENTS.md` (section `contour.rs`);
//! the figures of contour tracking on the maps and in the museum are in the
//! `maps` and `tourguide` suites' reports (`petrinav lab run maps`,
//! `petrinav lab run tourguide`).

use std::collections::VecDeque;

use robot::{Command, LaserScan, Pose, Request, Vec2, wrap_angle};

use super::scan;

/// Which side the contour is on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Side {
    /// The contour on the robot's left.
    Left,
    /// The contour on the robot's right.
    Right,
}

impl Side {
    fn sign(self) -> f64 {
        match self {
            Side::Left => 1.0,
            Side::Right => -1.0,
        }
    }

    /// The other side.
    pub fn other(self) -> Side {
        match self {
            Side::Left => Side::Right,
            Side::Right => Side::Left,
        }
    }
}

/// Parameters of contour tracking (module docs for the law).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ContourParams {
    /// Distance `d*` kept from the contour, from the robot's centre,
    /// metres. Default 0.8 (0.45 m of clearance for a 0.35 m robot).
    pub distance_m: f64,
    /// Speed along a straight contour, m/s. Default 0.4.
    pub cruise_mps: f64,
    /// Largest turn rate, rad/s. Default 0.8 (Jinny's wheels, ±0.2 m/s
    /// at this rate, stop within 0.4 s at 0.5 m/s²: little overshoot).
    pub max_turn_radps: f64,
    /// Gain `k_d` of the offset from the middle of a corridor in the
    /// desired heading, 1/m. Default 2.0.
    pub k_distance: f64,
    /// Gain `k_ψ` from heading error to turn rate, 1/s. Default 2.5.
    pub k_heading: f64,
    /// The robot's footprint radius, metres. Default 0.35.
    pub robot_radius_m: f64,
    /// Clearance added to the footprint when checking a way is clear,
    /// metres. Default 0.15.
    pub margin_m: f64,
    /// While seeking the goal, something within this distance ahead starts
    /// the following, metres. Default 1.2.
    pub hit_m: f64,
    /// The goal's bearing must be clear this far (or to the goal) to leave
    /// a contour, metres. Default 2.5.
    pub leave_clear_m: f64,
    /// To leave a contour the goal must be this much nearer than at the
    /// hit point, metres. Default 0.5.
    pub leave_progress_m: f64,
    /// A corridor at most this wide (sum of the two side distances) is
    /// followed in its middle, metres. Default 2.6.
    pub corridor_m: f64,
    /// A contour farther than `distance_m` plus this is lost (the tracker
    /// arcs towards where it was), metres. Default 1.5.
    pub lost_m: f64,
    /// How long the nearest contour point is remembered once out of view,
    /// seconds. Default 4.
    pub memory_s: f64,
    /// A contour lost (nothing seen or remembered on its side within
    /// `distance_m + lost_m`) this long is left for the goal, seconds.
    /// Default 2.
    pub lost_after_s: f64,
    /// Following a contour without getting `stall_m` anywhere for this long
    /// turns the robot round to follow it the other way, seconds. Default 8.
    pub stall_s: f64,
    /// See `stall_s`, metres. Default 0.3.
    pub stall_m: f64,
    /// The speed is kept low enough to stop, at `decel_mps2`, before the
    /// footprint grown by this much touches anything the (filtered) scan
    /// shows or showed beside the robot, metres, at `cruise_mps`; at
    /// `creep_mps` and below the footprint grows by `pass_margin_m` only,
    /// and in between by a margin growing linearly with the speed (module
    /// docs, doors). Default 0.03.
    pub safety_margin_m: f64,
    /// The safety layer remembers what it saw beside the robot, now out of
    /// the laser's view, this long (and until the robot has moved 1 m),
    /// seconds. Default 10 (more than `hit_wait_s` and `ask_after_s`: a
    /// robot that waits must not forget the wall beside it; the
    /// simulator's 3 s let it turn into a wall after a 3 s wait). Not
    /// longer: with 60 s, what people were beside the robot held it long
    /// after they left (`lab run maps`, building_31 among 20 people,
    /// contour legs reached 13 → 4 of 33), though 10 s is what still lets
    /// the robot touch a lone post beside it after a wait of more than
    /// 10 s in building_31's south corridor (tour 3, last leg).
    pub safety_memory_s: f64,
    /// Deceleration the stopping distance assumes, m/s². Default 0.4
    /// (below Jinny's 0.5 m/s² per wheel).
    pub decel_mps2: f64,
    /// How far ahead along the contour the tracker steers, metres.
    /// Default 0.4 (longer cuts convex corners, shorter swings wide of
    /// concave ones; both measured in `tests/contour.rs`).
    pub lookahead_m: f64,
    /// Clearance beside the footprint with which a gap is passed at
    /// `creep_mps`, metres: a gap at least `2 (robot_radius_m +
    /// pass_margin_m)` wide is a way through. Default 0.015 (2.2 σ of the
    /// filtered scan's noise; module docs, doors).
    pub pass_margin_m: f64,
    /// Speed through a gap narrower than the usual clearance, m/s.
    /// Default 0.08.
    pub creep_mps: f64,
    /// Held up this long by something in the way, the robot asks the
    /// people around it to step aside, seconds. Default 1.
    pub ask_after_s: f64,
    /// Radius of the request to step aside, metres. Default 1.5 (as
    /// AutoMove's).
    pub ask_radius_m: f64,
    /// Seeking the goal and finding its way blocked, the robot stops and
    /// asks this long before it follows what blocks it, seconds. Default 3.
    pub hit_wait_s: f64,
}

impl Default for ContourParams {
    fn default() -> ContourParams {
        ContourParams {
            distance_m: 0.8,
            cruise_mps: 0.4,
            max_turn_radps: 0.8,
            k_distance: 2.0,
            k_heading: 2.5,
            robot_radius_m: 0.35,
            margin_m: 0.15,
            hit_m: 1.2,
            leave_clear_m: 2.5,
            leave_progress_m: 0.5,
            corridor_m: 2.6,
            lost_m: 1.5,
            memory_s: 4.0,
            lost_after_s: 2.0,
            stall_s: 8.0,
            stall_m: 0.3,
            safety_margin_m: 0.03,
            safety_memory_s: 10.0,
            decel_mps2: 0.4,
            lookahead_m: 0.4,
            pass_margin_m: 0.015,
            creep_mps: 0.08,
            ask_after_s: 1.0,
            ask_radius_m: 1.5,
            hit_wait_s: 3.0,
        }
    }
}

impl ContourParams {
    /// Checks every field: finite and > 0; the contour distance more than
    /// the footprint.
    pub fn validate(&self) -> Result<(), String> {
        let fields = [
            ("distance_m", self.distance_m),
            ("cruise_mps", self.cruise_mps),
            ("max_turn_radps", self.max_turn_radps),
            ("k_distance", self.k_distance),
            ("k_heading", self.k_heading),
            ("robot_radius_m", self.robot_radius_m),
            ("hit_m", self.hit_m),
            ("leave_clear_m", self.leave_clear_m),
            ("corridor_m", self.corridor_m),
            ("lost_m", self.lost_m),
            ("memory_s", self.memory_s),
            ("lost_after_s", self.lost_after_s),
            ("lookahead_m", self.lookahead_m),
            ("stall_s", self.stall_s),
            ("stall_m", self.stall_m),
            ("decel_mps2", self.decel_mps2),
            ("creep_mps", self.creep_mps),
            ("safety_memory_s", self.safety_memory_s),
            ("ask_radius_m", self.ask_radius_m),
        ];
        for (name, v) in fields {
            if !(v.is_finite() && v > 0.0) {
                return Err(format!("contour.{name} must be a finite number > 0, got {v}"));
            }
        }
        for (name, v) in [
            ("margin_m", self.margin_m),
            ("leave_progress_m", self.leave_progress_m),
            ("safety_margin_m", self.safety_margin_m),
            ("pass_margin_m", self.pass_margin_m),
            ("ask_after_s", self.ask_after_s),
            ("hit_wait_s", self.hit_wait_s),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(format!("contour.{name} must be a finite number ≥ 0, got {v}"));
            }
        }
        if self.pass_margin_m > self.safety_margin_m || self.safety_margin_m > self.margin_m {
            return Err(format!(
                "contour: pass_margin_m ({}) ≤ safety_margin_m ({}) ≤ margin_m ({}) is required",
                self.pass_margin_m, self.safety_margin_m, self.margin_m
            ));
        }
        if self.creep_mps > self.cruise_mps {
            return Err(format!(
                "contour.creep_mps ({}) must not exceed cruise_mps ({})",
                self.creep_mps, self.cruise_mps
            ));
        }
        if self.distance_m <= self.robot_radius_m {
            return Err(format!(
                "contour.distance_m ({}) must exceed the robot's radius ({})",
                self.distance_m, self.robot_radius_m
            ));
        }
        Ok(())
    }
}

/// What the tracker is doing.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub enum ContourMode {
    /// Driving at the goal.
    Seek,
    /// Following a contour; the goal was `hit_goal_m` away when it began.
    Follow {
        /// The contour's side.
        side: Side,
        /// Distance to the goal at the hit point, metres.
        hit_goal_m: f64,
    },
}

/// One cycle's output.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContourStep {
    /// The velocity command.
    pub command: Command,
    /// The mode after this cycle.
    pub mode: ContourMode,
    /// Distance to the followed contour, metres (`INFINITY` when seeking
    /// or when it is lost).
    pub contour_m: f64,
    /// The robot is in a corridor and keeps to its middle.
    pub centred: bool,
    /// The robot is passing a gap narrower than its usual clearance.
    pub gap: bool,
    /// What the robot asks of the people around it.
    pub request: Option<Request>,
}

/// The contour tracker (module docs).
#[derive(Debug, Clone)]
pub struct ContourTracker {
    p: ContourParams,
    mode: ContourMode,
    /// The nearest contour point of recent cycles, odometry frame, with
    /// when it was seen, oldest first.
    memory: VecDeque<(Vec2, f64)>,
    /// Where (odometry) and when the robot last made progress.
    checkpoint: Option<(Vec2, f64)>,
    /// What the safety layer keeps clear of.
    nearby: scan::NearbyPoints,
    /// Turning on the spot to this side (+1 left, −1 right) while blocked.
    turning: Option<f64>,
    /// The gap being passed, odometry frame.
    gap: Option<Gap>,
    /// Since when something has held the robot up.
    held_since: Option<f64>,
    /// Since when the robot has waited at a hit point.
    hit_since: Option<f64>,
    /// Since when the followed contour has been lost.
    lost_since: Option<f64>,
    /// Gaps the robot stalled at (middle, odometry frame), and when.
    refused: Vec<(Vec2, f64)>,
    /// The speed commanded last cycle, m/s.
    last_v: f64,
}

/// A gap in the way: its two sides, its middle and the direction through
/// it (odometry frame, or the robot's when just found), its width.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Gap {
    /// When it was last found, seconds.
    seen_s: f64,
    sides: [Vec2; 2],
    mid: Vec2,
    through: Vec2,
    width_m: f64,
}

/// The points of a cycle's scan (robot frame) with their bearings and
/// distances, computed once a cycle: the arc tangents and the `hypot`s of
/// the comparisons below were a fifth of a crowded contour cycle.
struct Polar<'a> {
    points: &'a [Vec2],
    bearings: &'a [f64],
    norms: &'a [f64],
}

impl Polar<'_> {
    /// The nearest point with bearing in `[lo, hi]` (radians), and its
    /// distance, if any (of equally near ones, the first).
    fn nearest_in(&self, lo: f64, hi: f64) -> Option<(Vec2, f64)> {
        self.points
            .iter()
            .zip(self.bearings)
            .zip(self.norms)
            .filter(|&((_, &a), _)| a >= lo && a <= hi)
            .map(|((&q, _), &n)| (q, n))
            .min_by(|a, b| a.1.total_cmp(&b.1))
    }
}

/// What one control cycle sees: the filtered scan and its points, the
/// goal's distance and bearing, the clearance the law wants, the odometry
/// pose and the time.
struct Cycle<'a> {
    scan: &'a LaserScan,
    polar: Polar<'a>,
    /// Distance to the goal, metres.
    goal_m: f64,
    /// Bearing of the goal, robot frame, radians.
    goal_bearing: f64,
    /// Half the width of the usual clearance (footprint and margin), metres.
    half: f64,
    odometry: Pose,
    time_s: f64,
}

/// What the hit rule decided this cycle (seeking, stopped at an obstacle).
#[derive(Debug, Clone, Copy)]
struct Hit {
    /// Waiting for the obstacle to step aside.
    waiting: bool,
    /// Turning to the goal on the spot, still asking.
    turning_to_goal: bool,
}

/// The heading the law wants this cycle and what it follows.
#[derive(Debug, Clone, Copy)]
struct Aim {
    /// Heading, robot frame, radians (wrapped).
    psi: f64,
    /// Distance to the followed contour, metres (`INFINITY` if none).
    contour_m: f64,
    /// Centred in a corridor.
    centred: bool,
    /// Passing a gap.
    in_gap: bool,
}

/// The point of `points` nearest `q` (of equally near ones, the first).
fn nearest_to(points: &[Vec2], q: Vec2) -> Option<Vec2> {
    points
        .iter()
        .map(|&a| (a, a.dist(q)))
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(a, _)| a)
}

/// Projections onto the offset curve [`offset_point`] makes at most.
const OFFSET_STEPS: usize = 4;

/// The robot faces a direction within this angle of it, radians: only
/// then does a blocked way start a turn on the spot, and only then is the
/// side to follow chosen at a hit.
const FACING_RAD: f64 = 0.3;

/// Clearance beyond the footprint the way straight ahead must leave for
/// any speed when not in a gap, metres.
const AHEAD_MARGIN_M: f64 = 0.05;

/// Full speed once the way ahead is free this far beyond the set contour
/// distance d*, metres (speed falls linearly to none where the footprint
/// would touch).
const SLOW_BEYOND_DISTANCE_M: f64 = 1.0;

/// In a gap, full (creep) speed once the way ahead is free this far,
/// metres.
const GAP_SLOW_WITHIN_M: f64 = 0.3;

/// The robot counts as held up by the safety layer when the law wanted at
/// least this fraction of `creep_mps` and got less (dimensionless).
const HELD_FRACTION: f64 = 0.5;

/// The reaction time the safety layer allows before braking: one control
/// period, seconds.
const REACTION_S: f64 = 0.1;

/// A gap is passed once the robot's centre is this far beyond the
/// footprint's radius past its line, metres.
const GAP_PASSED_M: f64 = 0.1;

/// A gap is dropped once the robot is farther than this from its middle,
/// metres.
const GAP_DROP_M: f64 = 2.5;

/// A new gap is taken only within this angle of the wanted heading,
/// degrees.
const GAP_WITHIN_DEG: f64 = 35.0;

/// A gap whose middle is within this distance of one the robot stalled at
/// lately is refused, metres.
const GAP_REFUSED_M: f64 = 0.3;

/// In a corridor the robot keeps to the middle unless something on the
/// followed side's own half is nearer than the middle (or d*) by more than
/// this, metres.
const CORRIDOR_SLACK_M: f64 = 0.05;

/// The followed contour takes in points on its side and this far past the
/// front onto the other side, degrees.
const CONTOUR_FRONT_DEG: f64 = 45.0;

/// A corridor's walls are the nearest points beside the robot: bearings
/// between this and [`BESIDE_TO_DEG`] on either side, degrees.
const BESIDE_FROM_DEG: f64 = 45.0;

/// The outer bound of "beside the robot" ([`BESIDE_FROM_DEG`]), degrees.
const BESIDE_TO_DEG: f64 = 135.0;

/// At a hit, clear bearings are looked for either side of the goal's in
/// steps of this, degrees ...
const FREE_SIDE_STEP_DEG: f64 = 5.0;

/// ... up to this many steps (180°).
const FREE_SIDE_STEPS: i32 = 36;

/// The point of the offset curve — `d` from the contour, no nearer to any
/// of its points — near `q`: `q` moved to `d` from the contour point
/// nearest it (towards or away from it); if that lands behind the robot
/// (`x < 0` in its frame), then away from the point nearest it while one
/// is nearer than `d`, up to [`OFFSET_STEPS`] moves. One step puts a look-ahead spot near a wall onto the
/// parallel at `d`. In a concave corner met with the robot already within
/// `d` of the wall ahead, it lands behind the robot, still too near the
/// side wall: its bearing is then about ±180° and the robot turned towards
/// the corner as often as away from it (building_31's room north of the
/// middle corridor: wedged in the corner for 12 s, then a stall and a turn
/// round). The next moves push it off the side wall, to the corner of the
/// offset curve, away from the followed side. Rejected: pushing ahead of
/// the robot too (whenever a point is nearer than `d`), because fewer of
/// the maps suite's contour legs arrived (`crates/guide/EXPERIMENTS.md`).
fn offset_point(contour: &[Vec2], q: Vec2, d: f64) -> Vec2 {
    let mut at = q;
    for step in 0..OFFSET_STEPS {
        match nearest_to(contour, at) {
            // The first step pulls or pushes onto the parallel; later
            // ones only push away from a point still too near.
            Some(m) if m.dist(at) > 1e-9 && (step == 0 || (at.x < 0.0 && m.dist(at) < d - 1e-6)) => {
                at = m + (at - m).scale(d / m.dist(at));
            }
            _ => break,
        }
    }
    at
}

/// Whether a corridor of half-width `half_m` along bearing `bearing` is
/// free of points up to `length_m`.
fn clear_along(points: &[Vec2], bearing: f64, half_m: f64, length_m: f64) -> bool {
    let (s, c) = bearing.sin_cos();
    points.iter().all(|p| {
        let along = p.x * c + p.y * s;
        let across = -p.x * s + p.y * c;
        !(along > 0.0 && along < length_m && across.abs() < half_m)
    })
}

/// How far ahead on the line through a gap the robot steers, metres: a
/// lateral offset decays as `e^(−s / L)` over the distance `s` driven, so
/// 0.25 m takes a 30 cm offset to under 1 cm in the metre before a gap
/// found 1.5 m ahead. Rejected: 0.5 m, because the robot then arrived
/// 5–6 cm off the axis and touched the jamb.
pub const GAP_LOOKAHEAD_M: f64 = 0.25;

/// A gap found with its middle within this of the one being passed is
/// that gap seen again, metres.
const GAP_SAME_M: f64 = 0.2;

/// The shortest look-ahead onto the line through a gap, metres.
const GAP_LOOKAHEAD_MIN_M: f64 = 0.05;

/// The robot's offset from the line through a gap should be below this
/// when its footprint reaches the line of the sides, metres.
const GAP_ON_LINE_M: f64 = 0.02;

/// Gaps are looked for this far ahead, metres.
const GAP_REACH_M: f64 = 1.5;

/// A gap the robot stalled at is not taken again for this long, seconds.
const GAP_REFUSED_S: f64 = 30.0;

/// A gap not found again for this long is dropped, unless the robot is in
/// it already (its sides beside the robot, out of the laser's view),
/// seconds.
const GAP_UNSEEN_S: f64 = 1.0;

/// `v` turned by `angle_rad`.
fn rotate(v: Vec2, angle_rad: f64) -> Vec2 {
    let (sn, c) = angle_rad.sin_cos();
    Vec2::new(c * v.x - sn * v.y, sn * v.x + c * v.y)
}

/// How far a disc of `radius_m` centred on the robot can move straight
/// ahead before it touches one of `points` (robot frame), metres: 0 when
/// one ahead of the centre is inside it already.
fn free_ahead(points: &[Vec2], radius_m: f64) -> f64 {
    points
        .iter()
        .filter(|q| q.x > 0.0 && q.y.abs() < radius_m)
        .map(|q| (q.x - (radius_m * radius_m - q.y * q.y).sqrt()).max(0.0))
        .fold(f64::INFINITY, f64::min)
}

/// The squared distance from `q` to the segment `ab` (no square root: the
/// gap search compares it with a bound, many times a cycle).
fn to_segment_squared(q: Vec2, a: Vec2, b: Vec2) -> f64 {
    let ab = b - a;
    let t = ((q - a).dot(ab) / ab.dot(ab).max(1e-12)).clamp(0.0, 1.0);
    let d = q - (a + ab.scale(t));
    d.dot(d)
}

/// Whether `q` lies on the segment between the gap's sides `j` and `k`:
/// within 5 cm of it and not within 10 cm of either end (their own wall).
fn on_segment(q: Vec2, j: Vec2, k: Vec2) -> bool {
    dist_squared(q, j) >= 0.01 && dist_squared(q, k) >= 0.01 && to_segment_squared(q, j, k) < 0.0025
}

/// `|a − b|²`.
fn dist_squared(a: Vec2, b: Vec2) -> f64 {
    let d = a - b;
    d.dot(d)
}

/// A gap in the way (module docs, doors), robot frame: its two sides, its
/// middle and the unit direction through it away from the robot. The
/// narrowest pair of points `j`, `k`, one of them inside the usual
/// clearance straight ahead (`robot_radius_m + margin_m` either side,
/// within 1.5 m), such that: `|jk|` is between `2 (robot_radius_m +
/// pass_margin_m)` and `2 (robot_radius_m + margin_m)`; nothing lies within
/// 5 cm of the segment between them (not two points of one wall); the
/// middle is ahead, within 60° of the heading; and the footprint grown by
/// `pass_margin_m` can go `robot_radius_m + 0.3` m on through the middle
/// (not a corner). `O(n²)` pairs in the points within reach, checked
/// narrowest first; each pair's beams between its two points are looked at
/// before all points (what lies on a wall's segment or in the way beyond a
/// false gap is mostly there), which takes the search from 30 % of a packed
/// museum mission to 6 % (the plain definition is a property test).
fn find_gap(points: &[Vec2], p: &ContourParams, around: Option<Vec2>) -> Option<Gap> {
    const REACH_M: f64 = GAP_REACH_M;
    let usual = p.robot_radius_m + p.margin_m;
    let fits = p.robot_radius_m + p.pass_margin_m;
    // Squared distances throughout: `hypot` was most of a crowded cycle.
    let reach_near = REACH_M + 2.0 * usual;
    let near: Vec<Vec2> = points
        .iter()
        .copied()
        .filter(|&q| q.dot(q) < reach_near * reach_near)
        .collect();
    let (w_lo, w_hi) = (2.0 * fits, 2.0 * usual);
    let is_side = |q: Vec2| q.x > 0.0 && q.y.abs() < usual && q.dot(q) < REACH_M * REACH_M;
    // `|atan2(y, x)| ≤ 60°` for `x > 0`, without the arc tangent.
    let tan_60 = 60f64.to_radians().tan();
    let mut pairs: Vec<(f64, usize, usize)> = Vec::new();
    for (ji, &j) in near.iter().enumerate() {
        if !is_side(j) {
            continue;
        }
        for (ki, &k) in near.iter().enumerate() {
            // Both inside the clearance: the pair was met as (k, j) already,
            // with the same width and the same verdict.
            if ki < ji && is_side(k) {
                continue;
            }
            let w2 = dist_squared(k, j);
            if w2 >= w_lo * w_lo && w2 <= w_hi * w_hi {
                // The middle ahead, within 60° of the heading (checked here
                // rather than on each candidate: the same pairs survive).
                let mid = (j + k).scale(0.5);
                // Two points of one wall: the beam between them in the
                // middle lies on their segment (a cheap part of the check
                // below, done before the sort: most pairs go here).
                let (lo, hi) = (ji.min(ki), ji.max(ki));
                let on_wall = hi > lo + 1 && on_segment(near[lo + 1 + (hi - lo - 1) / 2], j, k);
                let tracked = around.is_none_or(|a| dist_squared(a, mid) < GAP_SAME_M * GAP_SAME_M);
                if mid.x > 0.0 && mid.y.abs() <= tan_60 * mid.x && !on_wall && tracked {
                    pairs.push((w2.sqrt(), ji, ki));
                }
            }
        }
    }
    // Narrowest first; of equal widths, in scan order (a total order: the
    // result does not depend on the sort's algorithm).
    pairs.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)).then(a.2.cmp(&b.2)));
    let reach = p.robot_radius_m + 0.3;
    let bound = fits - 1e-9;
    pairs.into_iter().find_map(|(w, ji, ki)| {
        let (j, k) = (near[ji], near[ki]);
        let mid = (j + k).scale(0.5);
        let across = (k - j).scale(1.0 / w);
        let mut through = Vec2::new(-across.y, across.x);
        if through.dot(mid) < 0.0 {
            through = through.scale(-1.0);
        }
        // Room beyond: the footprint goes on through the middle.
        let in_the_way = |q: Vec2| {
            let rel = q - mid;
            let along = rel.dot(through);
            if along < 0.0 {
                rel.dot(rel) < bound * bound
            } else if along > reach {
                dist_squared(rel, through.scale(reach)) < bound * bound
            } else {
                rel.dot(across).abs() < bound
            }
        };
        // The points are in scan order, so what lies on the segment of two
        // points of one wall, or in the way beyond two points of different
        // things, is mostly seen by the beams between them: those are
        // looked at first (the middle one before the sort, above), then all
        // points (the verdict is the same; only the work differs).
        let (lo, hi) = (ji.min(ki), ji.max(ki));
        let between = &near[lo + 1..hi];
        // Nothing on the segment between them, nothing in the way beyond.
        let rejected = between.iter().any(|&q| on_segment(q, j, k) || in_the_way(q))
            || near.iter().any(|&q| on_segment(q, j, k) || in_the_way(q));
        if rejected {
            return None;
        }
        Some(Gap {
            seen_s: 0.0,
            sides: [j, k],
            mid,
            through,
            width_m: w,
        })
    })
}

impl ContourTracker {
    /// A tracker, seeking the goal first.
    pub fn new(params: ContourParams) -> Result<ContourTracker, String> {
        params.validate()?;
        Ok(ContourTracker {
            p: params,
            mode: ContourMode::Seek,
            memory: VecDeque::new(),
            checkpoint: None,
            nearby: scan::NearbyPoints::forgetting_after(params.safety_memory_s),
            turning: None,
            gap: None,
            held_since: None,
            hit_since: None,
            lost_since: None,
            refused: Vec::new(),
            last_v: 0.0,
        })
    }

    /// A tracker that starts following the contour on `side` (for tests and
    /// pure wall following: the goal is then never sought).
    pub fn following(params: ContourParams, side: Side) -> Result<ContourTracker, String> {
        let mut t = ContourTracker::new(params)?;
        t.mode = ContourMode::Follow {
            side,
            hit_goal_m: f64::NEG_INFINITY,
        };
        Ok(t)
    }

    /// The parameters.
    pub fn params(&self) -> &ContourParams {
        &self.p
    }

    /// The current mode.
    pub fn mode(&self) -> ContourMode {
        self.mode
    }

    /// Starts again from seeking the goal (a new goal).
    pub fn reset(&mut self) {
        self.mode = ContourMode::Seek;
        self.memory.clear();
        self.checkpoint = None;
        self.turning = None;
        self.gap = None;
        self.held_since = None;
        self.hit_since = None;
        self.lost_since = None;
        self.refused.clear();
        self.last_v = 0.0;
    }

    /// One control cycle: the scan, the odometry pose (for the short
    /// memory of contour points out of view), the robot's pose estimate and
    /// the goal (world frame; only the goal's bearing and distance are
    /// used), the time.
    pub fn step(
        &mut self,
        scan: &LaserScan,
        odometry: Pose,
        estimate: Pose,
        goal: Vec2,
        time_s: f64,
    ) -> ContourStep {
        let p = self.p;
        let filtered = scan::median3(scan);
        let scan = &filtered;
        let points: Vec<Vec2> = scan::points(scan).collect();
        // Their bearings, once a cycle (the arc tangent was a tenth of a
        // crowded mission).
        let bearings: Vec<f64> = points.iter().map(|q| q.angle()).collect();
        let norms: Vec<f64> = points.iter().map(|q| q.norm()).collect();
        let to_goal = estimate.inverse_transform(goal);
        let cycle = Cycle {
            scan,
            polar: Polar {
                points: &points,
                bearings: &bearings,
                norms: &norms,
            },
            goal_m: to_goal.norm(),
            goal_bearing: to_goal.angle(),
            half: p.robot_radius_m + p.margin_m,
            odometry,
            time_s,
        };
        self.check_stall(odometry, time_s);
        self.expire_gap(odometry, time_s);
        let hit = self.leave_or_hit(&cycle);
        let aim = self.aim(&cycle);
        let in_gap = aim.in_gap;
        // Room straight ahead for the footprint and 5 cm (in a gap, and
        // `pass_margin_m`): full speed beyond d* + 1 m, none when it would
        // touch.
        let body = p.robot_radius_m + if in_gap { p.pass_margin_m } else { AHEAD_MARGIN_M };
        let free = free_ahead(&points, body);
        let slow_within = if in_gap {
            GAP_SLOW_WITHIN_M
        } else {
            p.distance_m + SLOW_BEYOND_DISTANCE_M - body
        };
        let room = (free / slow_within).clamp(0.0, 1.0);
        // Stopped at a hit (waiting, or turning to the goal): held up, and
        // asking at once.
        let at_hit = hit.waiting || hit.turning_to_goal;
        let (psi, mut held) = self.turn_if_blocked(&cycle.polar, aim.psi, room, hit);
        let omega = if hit.waiting {
            0.0
        } else {
            (p.k_heading * psi).clamp(-p.max_turn_radps, p.max_turn_radps)
        };
        let top = if in_gap { p.creep_mps } else { p.cruise_mps };
        let wanted = if at_hit {
            0.0
        } else {
            top * psi.cos().max(0.0) * room
        };
        let v = self.guarded_speed(scan, odometry, time_s, wanted, omega, in_gap);
        // Held up: the safety layer stopped what the law wanted.
        if wanted >= HELD_FRACTION * p.creep_mps && v < HELD_FRACTION * p.creep_mps {
            held = true;
        }
        // Following something that stands in the goal's way: it may be
        // people.
        let in_the_way = matches!(self.mode, ContourMode::Follow { .. })
            && !clear_along(&points, cycle.goal_bearing, cycle.half, p.hit_m.min(cycle.goal_m));
        if in_the_way {
            held = true;
        }
        let request = self.request(in_gap, held, at_hit, time_s);
        self.last_v = v;
        ContourStep {
            command: Command::Twist {
                v_mps: v,
                omega_radps: omega,
            },
            mode: self.mode,
            contour_m: aim.contour_m,
            centred: aim.centred,
            gap: in_gap,
            request,
        }
    }

    /// Stalled on a contour (a pocket, a gap too narrow to tell from a
    /// passage): follows it the other way, and refuses the gap being
    /// passed.
    fn check_stall(&mut self, odometry: Pose, time_s: f64) {
        let p = self.p;
        let (here, since) = *self.checkpoint.get_or_insert((odometry.position(), time_s));
        if odometry.position().dist(here) >= p.stall_m {
            self.checkpoint = Some((odometry.position(), time_s));
        } else if time_s - since >= p.stall_s {
            if let ContourMode::Follow { side, hit_goal_m } = self.mode {
                self.mode = ContourMode::Follow {
                    side: side.other(),
                    hit_goal_m,
                };
                self.memory.clear();
            }
            if let Some(g) = self.gap.take() {
                self.refused.push((g.mid, time_s));
            }
            self.checkpoint = Some((odometry.position(), time_s));
        }
    }

    /// The leave and hit rules: leaves a contour for the goal when the way
    /// to it is clear and the robot is nearer than at the hit; seeking,
    /// stops at an obstacle (waiting, then turning to the goal, then
    /// following a side).
    fn leave_or_hit(&mut self, cycle: &Cycle<'_>) -> Hit {
        let p = self.p;
        let points = cycle.polar.points;
        let (goal_m, goal_bearing, half) = (cycle.goal_m, cycle.goal_bearing, cycle.half);
        let in_gap = self.gap.is_some();
        let mut hit = Hit {
            waiting: false,
            turning_to_goal: false,
        };
        match self.mode {
            ContourMode::Follow { hit_goal_m, .. } => {
                let length = p.leave_clear_m.min(goal_m);
                if !in_gap
                    && goal_m < hit_goal_m - p.leave_progress_m
                    && scan::covers(cycle.scan, goal_bearing)
                    && clear_along(points, goal_bearing, half, length)
                {
                    self.mode = ContourMode::Seek;
                    self.memory.clear();
                }
                self.hit_since = None;
            }
            ContourMode::Seek => {
                let blocked_ahead = !clear_along(points, 0.0, half, p.hit_m);
                let blocked_goal = !clear_along(points, goal_bearing, half, p.hit_m.min(goal_m));
                if blocked_ahead && blocked_goal && !in_gap {
                    // Stop and ask first: a person steps aside, a wall
                    // does not. Then, if the goal is not ahead, turn to it
                    // on the spot (still asking) before choosing the side
                    // to follow: the side is chosen from a scan that sees
                    // the goal's way (module docs, the leave rule).
                    let since = *self.hit_since.get_or_insert(cycle.time_s);
                    if cycle.time_s - since < p.hit_wait_s {
                        hit.waiting = true;
                    } else if goal_bearing.abs() >= FACING_RAD {
                        hit.turning_to_goal = true;
                    } else {
                        let side = self.free_side(points, goal_bearing, half);
                        self.mode = ContourMode::Follow {
                            side,
                            hit_goal_m: goal_m,
                        };
                        self.hit_since = None;
                    }
                } else {
                    self.hit_since = None;
                }
            }
        }
        hit
    }

    /// The heading the law wants (robot frame, wrapped): the goal's when
    /// seeking, the contour's when following, through a gap in the way
    /// when there is one; back to seeking when the contour has been lost
    /// for `lost_after_s`.
    fn aim(&mut self, cycle: &Cycle<'_>) -> Aim {
        let p = self.p;
        let (odometry, time_s) = (cycle.odometry, cycle.time_s);
        let (mut psi, mut contour_m, mut centred) = match self.mode {
            ContourMode::Seek => (cycle.goal_bearing, f64::INFINITY, false),
            ContourMode::Follow { side, .. } => self.follow(cycle.scan, &cycle.polar, side, odometry, time_s),
        };
        // A gap in the way the law wants to go, narrower than the usual
        // clearance, that the footprint fits through: pass it (module
        // docs, doors).
        self.find_gap_towards(cycle.polar.points, odometry, time_s, wrap_angle(psi));
        let in_gap = self.gap.is_some();
        if let Some(gap) = self.gap {
            psi = self.through_gap(gap, odometry);
            contour_m = f64::INFINITY;
            centred = false;
        }
        // The contour gone (a person who walked away, the end of a wall
        // out of reach) for `lost_after_s`: back to the goal (a Bug
        // algorithm leaves an obstacle it no longer senses).
        if matches!(self.mode, ContourMode::Follow { .. }) && !in_gap && contour_m.is_infinite() {
            let since = *self.lost_since.get_or_insert(time_s);
            if time_s - since >= p.lost_after_s {
                self.mode = ContourMode::Seek;
                self.memory.clear();
                self.lost_since = None;
                psi = cycle.goal_bearing;
            }
        } else {
            self.lost_since = None;
        }
        Aim {
            psi: wrap_angle(psi),
            contour_m,
            centred,
            in_gap,
        }
    }

    /// The heading after the hit and a blocked way ahead are taken into
    /// account, and whether the robot is held up: none while waiting at a
    /// hit; blocked the way it wants to go, a turn on the spot.
    fn turn_if_blocked(&mut self, polar: &Polar<'_>, psi: f64, room: f64, hit: Hit) -> (f64, bool) {
        let mut psi = psi;
        let mut held = hit.waiting || hit.turning_to_goal;
        if hit.waiting {
            psi = 0.0;
        } else if hit.turning_to_goal {
            self.turning = None;
        } else if room == 0.0 && (psi.abs() < FACING_RAD || self.turning.is_some()) {
            // Blocked the way it wants to go: turn on the spot, away from
            // the contour (or towards the freer side when seeking), and keep
            // turning that way until the way ahead opens.
            let side = *self.turning.get_or_insert_with(|| match self.mode {
                ContourMode::Follow { side, .. } => -side.sign(),
                ContourMode::Seek => {
                    let left = polar
                        .nearest_in(0.0, std::f64::consts::PI)
                        .map_or(f64::INFINITY, |(_, n)| n);
                    let right = polar
                        .nearest_in(-std::f64::consts::PI, 0.0)
                        .map_or(f64::INFINITY, |(_, n)| n);
                    if left >= right { 1.0 } else { -1.0 }
                }
            });
            psi = side * std::f64::consts::FRAC_PI_2;
            held = true;
        } else {
            self.turning = None;
        }
        (psi, held)
    }

    /// The speed the safety layer allows of `wanted`, keeping clear of the
    /// obstacles near (this scan's and earlier ones out of view) and, in a
    /// gap, of its sides.
    fn guarded_speed(
        &mut self,
        scan: &LaserScan,
        odometry: Pose,
        time_s: f64,
        wanted: f64,
        omega: f64,
        in_gap: bool,
    ) -> f64 {
        let mut near = self.nearby.update(scan, odometry, time_s).to_vec();
        // The sides of the gap being passed, as found (the remembered
        // echoes are one per 5 cm square: up to a few centimetres from the
        // jamb's corner).
        if let Some(g) = self.gap {
            near.extend(g.sides.map(|q| odometry.inverse_transform(q)));
        }
        Self::safe_speed(&self.p, &near, wanted, omega, in_gap)
    }

    /// What the robot asks of the people around: in a gap, "excuse me"
    /// (people make way, walls do not); held up, after `ask_after_s` (at
    /// once at a hit).
    fn request(&mut self, in_gap: bool, held: bool, at_hit: bool, time_s: f64) -> Option<Request> {
        let p = self.p;
        if in_gap {
            Some(Request::StepAside {
                radius_m: p.ask_radius_m,
            })
        } else if held {
            let since = *self.held_since.get_or_insert(time_s);
            (at_hit || time_s - since >= p.ask_after_s).then_some(Request::StepAside {
                radius_m: p.ask_radius_m,
            })
        } else {
            self.held_since = None;
            None
        }
    }

    /// The safety layer (module docs, doors): the fastest speed up to
    /// `wanted` from which the robot stops before its footprint, grown by a
    /// margin from `pass_margin_m` at `creep_mps` to `safety_margin_m` at
    /// `cruise_mps`, touches any of `near`; at creep speed the smaller
    /// margin alone.
    fn safe_speed(p: &ContourParams, near: &[Vec2], wanted: f64, omega: f64, in_gap: bool) -> f64 {
        if !in_gap {
            return wanted.min(scan::safe_speed(
                near,
                wanted,
                omega,
                p.robot_radius_m + p.safety_margin_m,
                p.decel_mps2,
                REACTION_S,
            ));
        }
        let margin = |v: f64| {
            let k = ((v - p.creep_mps) / (p.cruise_mps - p.creep_mps).max(1e-9)).clamp(0.0, 1.0);
            p.pass_margin_m + k * (p.safety_margin_m - p.pass_margin_m)
        };
        let limit = |v: f64| {
            v.min(scan::safe_speed(
                near,
                v,
                omega,
                p.robot_radius_m + margin(v),
                p.decel_mps2,
                REACTION_S,
            ))
        };
        let v = limit(wanted);
        if v >= p.creep_mps {
            v
        } else {
            v.max(limit(wanted.min(p.creep_mps)))
        }
    }

    /// Drops the gap being passed once the footprint is through it, or
    /// when it is no longer seen before the robot got to it.
    fn expire_gap(&mut self, odometry: Pose, time_s: f64) {
        let p = self.p;
        let here = odometry.position();
        self.refused.retain(|&(_, t)| time_s - t <= GAP_REFUSED_S);
        if let Some(g) = self.gap {
            // Passed; or no longer seen before the robot got to it (people
            // moved: the gap is not there any more).
            let past = (here - g.mid).dot(g.through);
            let unseen = time_s - g.seen_s > GAP_UNSEEN_S && past < -(p.robot_radius_m + GAP_PASSED_M);
            if past > p.robot_radius_m + GAP_PASSED_M || here.dist(g.mid) > GAP_DROP_M || unseen {
                self.gap = None;
            }
        }
    }

    /// Finds a gap in this scan (a new one only where the usual clearance
    /// along `heading`, robot frame, is blocked within reach, and within
    /// 35° of it; not one the robot stalled at lately), and keeps the one
    /// being passed.
    fn find_gap_towards(&mut self, points: &[Vec2], odometry: Pose, time_s: f64, heading: f64) {
        let p = self.p;
        let here = odometry.position();
        let usual = p.robot_radius_m + p.margin_m;
        let wanted = |g: &Gap| {
            wrap_angle(g.mid.angle() - heading).abs() < GAP_WITHIN_DEG.to_radians()
                && !clear_along(points, heading, usual, GAP_REACH_M)
        };
        // A new gap is wanted only where the usual clearance is blocked:
        // the search (quadratic in the points near) runs only then, or while
        // a gap is being passed.
        let blocked = || !clear_along(points, heading, usual, GAP_REACH_M);
        if self.gap.is_none() && !blocked() {
            return;
        }
        // The gap being passed is looked for where it is (a narrower pair
        // elsewhere, e.g. a jamb and something beyond it, took its place).
        let around = self.gap.map(|g| odometry.inverse_transform(g.mid));
        let found = find_gap(points, &p, around).filter(|g| self.gap.is_some() || wanted(g));
        if let Some(g) = found {
            let mid = odometry.transform(g.mid);
            if self.refused.iter().any(|&(at, _)| at.dist(mid) < GAP_REFUSED_M) {
                return;
            }
            let seen = Gap {
                seen_s: time_s,
                sides: g.sides.map(|q| odometry.transform(q)),
                mid: odometry.transform(g.mid),
                through: rotate(g.through, odometry.theta_rad),
                width_m: g.width_m,
            };
            // A new gap, or the one being passed seen again: its middle
            // and direction smoothed (each pair of echoes is noisy), and of
            // each side the point nearest the line through it kept (the
            // jamb's corner, seen best from close by; the safety layer's
            // echoes are coarser and forgotten after a while).
            match self.gap {
                None => self.gap = Some(seen),
                Some(g) if g.mid.dist(seen.mid) < GAP_SAME_M => {
                    const K: f64 = 0.3;
                    let mut t = seen.through;
                    if t.dot(g.through) < 0.0 {
                        t = t.scale(-1.0);
                    }
                    let t = g.through + (t - g.through).scale(K);
                    let through = t.scale(1.0 / t.norm().max(1e-9));
                    let mid = g.mid + (seen.mid - g.mid).scale(K);
                    let across = Vec2::new(through.y, -through.x);
                    // Before the gap its sides are in view: as seen now (a
                    // person who moved is not kept as a ghost).
                    let inside = (here - mid).dot(through) > -(p.robot_radius_m + GAP_PASSED_M);
                    let mut sides = if inside { g.sides } else { seen.sides };
                    for q in seen.sides {
                        let side = (q - mid).dot(across);
                        for s in &mut sides {
                            let old = (*s - mid).dot(across);
                            if old * side > 0.0 && side.abs() < old.abs() {
                                *s = q;
                            }
                        }
                    }
                    // The gap is what its sides are: its middle between
                    // them, its line square to them (smoothing the pairs'
                    // directions alone let the line turn 9° off a door's
                    // as its sides were seen from nearer).
                    let (mid, through) = match (sides[1] - sides[0]).norm() {
                        w if w > 1e-6 => {
                            let along = (sides[1] - sides[0]).scale(1.0 / w);
                            let t = Vec2::new(-along.y, along.x);
                            (
                                (sides[0] + sides[1]).scale(0.5),
                                if t.dot(through) < 0.0 { t.scale(-1.0) } else { t },
                            )
                        }
                        _ => (mid, through),
                    };
                    let width_m = sides[0].dist(sides[1]);
                    self.gap = Some(Gap {
                        seen_s: time_s,
                        sides,
                        mid,
                        through,
                        width_m,
                    });
                }
                Some(_) => {}
            }
        }
    }

    /// The heading that takes the robot along the line through the gap's
    /// middle, [`GAP_LOOKAHEAD_M`] ahead on it (pure pursuit onto the line),
    /// less when the robot is off the line near the sides (module docs,
    /// doors).
    fn through_gap(&self, gap: Gap, odometry: Pose) -> f64 {
        let mid = odometry.inverse_transform(gap.mid);
        let through = rotate(gap.through, -odometry.theta_rad);
        // The robot's place relative to the middle: along the line (< 0
        // before it) and across it.
        let along = -mid.dot(through);
        let across = -mid.dot(Vec2::new(-through.y, through.x));
        // The offset decays as `e^(−s / L)`: short enough for it to be
        // within GAP_ON_LINE_M when the footprint's front reaches the
        // sides' line.
        let room = -along - self.p.robot_radius_m;
        let lookahead = if room > 0.0 && across.abs() > GAP_ON_LINE_M {
            (room / (across.abs() / GAP_ON_LINE_M).ln()).clamp(GAP_LOOKAHEAD_MIN_M, GAP_LOOKAHEAD_M)
        } else {
            GAP_LOOKAHEAD_M
        };
        (mid + through.scale(along + lookahead)).angle()
    }

    /// The side to follow when blocked: the obstacle on the side away from
    /// the smaller turn towards a clear bearing near the goal's.
    fn free_side(&self, points: &[Vec2], goal_bearing: f64, half: f64) -> Side {
        let step = FREE_SIDE_STEP_DEG.to_radians();
        for k in 0..=FREE_SIDE_STEPS {
            let a = k as f64 * step;
            let left = clear_along(points, wrap_angle(goal_bearing + a), half, self.p.hit_m);
            let right = clear_along(points, wrap_angle(goal_bearing - a), half, self.p.hit_m);
            match (left, right) {
                // Turning left keeps the obstacle on the right.
                (true, false) => return Side::Right,
                (false, true) => return Side::Left,
                (true, true) => {
                    return if goal_bearing >= 0.0 {
                        Side::Right
                    } else {
                        Side::Left
                    };
                }
                _ => {}
            }
        }
        Side::Right
    }

    /// The desired heading while following on `side`, the contour's
    /// distance, and whether the robot is centred in a corridor.
    fn follow(
        &mut self,
        scan: &LaserScan,
        polar: &Polar<'_>,
        side: Side,
        odometry: Pose,
        time_s: f64,
    ) -> (f64, f64, bool) {
        let p = self.p;
        let s = side.sign();
        let deg = f64::to_radians;
        // The contour: points on the followed side, front included, and
        // remembered points now out of the laser's view on that side.
        let (lo, hi) = match side {
            Side::Left => (deg(-CONTOUR_FRONT_DEG), deg(180.0)),
            Side::Right => (deg(-180.0), deg(CONTOUR_FRONT_DEG)),
        };
        let mut contour: Vec<Vec2> = Vec::new();
        // The nearest point seen, and its distance.
        let mut seen: Option<(Vec2, f64)> = None;
        for ((&q, a), &n) in polar.points.iter().zip(polar.bearings).zip(polar.norms) {
            if (lo..=hi).contains(a) && n < p.distance_m + p.lost_m {
                contour.push(q);
                if seen.is_none_or(|(_, m)| n < m) {
                    seen = Some((q, n));
                }
            }
        }
        let seen_points = contour.len();
        while self.memory.front().is_some_and(|&(_, t)| time_s - t > p.memory_s) {
            self.memory.pop_front();
        }
        for &(at, _) in &self.memory {
            let here = odometry.inverse_transform(at);
            let from_sensor = scan.mount.inverse_transform(here).angle();
            if s * here.y > 0.0 && !scan::covers_relative(scan, from_sensor) {
                contour.push(here);
            }
        }
        if let Some((n, _)) = seen {
            self.memory.push_back((odometry.transform(n), time_s));
        }
        // The nearest of all: the nearest seen, or a nearer remembered one
        // (the first of equally near ones, in the contour's order).
        let nearest = contour[seen_points..]
            .iter()
            .map(|&q| (q, q.norm()))
            .fold(seen, |best, (q, n)| match best {
                Some((_, m)) if m <= n => best,
                _ => Some((q, n)),
            });
        let Some((n, d)) = nearest else {
            // Lost: arc towards the contour's side on a circle of radius d*.
            return (
                s * (p.cruise_mps / p.distance_m) / p.k_heading,
                f64::INFINITY,
                false,
            );
        };
        // Corridor: both sides seen beside the robot, and nothing on the
        // followed side's own half nearer than the middle (a wall ahead
        // on that side, which the look-ahead law turns away from). The
        // front sector's points on the other half are the far side of a
        // passage here, not a wall ahead, nor are remembered points behind
        // the robot's centre (module docs, passages).
        let left = polar.nearest_in(deg(BESIDE_FROM_DEG), deg(BESIDE_TO_DEG));
        let right = polar.nearest_in(deg(-BESIDE_TO_DEG), deg(-BESIDE_FROM_DEG));
        // Only while moving (module docs, passages): a robot turning on
        // the spot was commanded no speed last cycle.
        let own = || {
            if self.last_v < p.creep_mps {
                d
            } else {
                contour
                    .iter()
                    .filter(|q| s * q.y >= 0.0 && q.x >= 0.0)
                    .map(|q| q.norm())
                    .fold(f64::INFINITY, f64::min)
            }
        };
        if let (Some((l, ln)), Some((r, rn))) = (left, right)
            && ln + rn <= p.corridor_m
            && own() > p.distance_m.min(0.5 * (ln + rn)) - CORRIDOR_SLACK_M
        {
            let tl = wrap_angle(l.angle() - std::f64::consts::FRAC_PI_2);
            let tr = wrap_angle(r.angle() + std::f64::consts::FRAC_PI_2);
            let offset = 0.5 * (ln - rn);
            let psi = 0.5 * (tl + tr) + (p.k_distance * offset).atan();
            return (psi, d, true);
        }
        // Look ahead along the contour's tangent: the point of the offset
        // curve (d* from the contour) nearest that spot is where to steer.
        let normal = n.scale(-1.0 / d); // from the contour to the robot
        let tangent = Vec2::new(-s * normal.y, s * normal.x);
        let ahead = tangent.scale(p.lookahead_m);
        (offset_point(&contour, ahead, p.distance_m).angle(), d, false)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The gap search as its docs define it, without the pruning: every
    /// pair, narrowest first (stable), every point checked.
    fn find_gap_plain(points: &[Vec2], p: &ContourParams) -> Option<(Vec2, Vec2)> {
        let usual = p.robot_radius_m + p.margin_m;
        let fits = p.robot_radius_m + p.pass_margin_m;
        let near: Vec<Vec2> = points
            .iter()
            .copied()
            .filter(|q| q.norm() < GAP_REACH_M + 2.0 * usual)
            .collect();
        let mut pairs = Vec::new();
        for &j in near
            .iter()
            .filter(|q| q.x > 0.0 && q.y.abs() < usual && q.norm() < GAP_REACH_M)
        {
            for &k in &near {
                let w = k.dist(j);
                let mid = (j + k).scale(0.5);
                if w >= 2.0 * fits
                    && w <= 2.0 * usual
                    && mid.x > 0.0
                    && mid.angle().abs() <= 60f64.to_radians()
                {
                    pairs.push((w, j, k));
                }
            }
        }
        pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
        pairs.into_iter().find_map(|(w, j, k)| {
            let mid = (j + k).scale(0.5);
            let free = near
                .iter()
                .all(|&q| q.dist(j) < 0.1 || q.dist(k) < 0.1 || to_segment_squared(q, j, k).sqrt() >= 0.05);
            let across = (k - j).scale(1.0 / w);
            let mut through = Vec2::new(-across.y, across.x);
            if through.dot(mid) < 0.0 {
                through = through.scale(-1.0);
            }
            let reach = p.robot_radius_m + 0.3;
            let beyond = near.iter().all(|&q| {
                let rel = q - mid;
                let along = rel.dot(through);
                let clearance = if along < 0.0 {
                    rel.norm()
                } else if along > reach {
                    rel.dist(through.scale(reach))
                } else {
                    rel.dot(across).abs()
                };
                clearance >= fits - 1e-9
            });
            (free && beyond).then_some((j, k))
        })
    }

    proptest::proptest! {
        /// The pruned gap search (beams between the pair first, pairs met
        /// once, squared distances) finds the gap the plain definition
        /// finds, or neither finds one: scans of a few walls and people
        /// placed at random, with doors and gaps among them.
        #[test]
        fn the_pruned_gap_search_is_the_plain_one(
            things in proptest::collection::vec((0.3f64..2.5, -1.6f64..1.6, 0.1f64..0.6), 1..7),
            wall in 0.6f64..2.0,
            door in (-1.0f64..1.0, 0.6f64..1.1),
        ) {
            // A wall across the front at `wall` with a door, and discs
            // (people, pillars) of radius r at (x, y): the first hit of
            // each beam of a 181-beam laser.
            let mut ranges = vec![f64::INFINITY; 181];
            for (i, r) in ranges.iter_mut().enumerate() {
                let a = (i as f64 - 90.0).to_radians();
                let (sn, c) = a.sin_cos();
                if c > 1e-6 {
                    let t = wall / c;
                    let y = t * sn;
                    if (y - door.0).abs() > door.1 / 2.0 {
                        *r = r.min(t);
                    }
                }
                for &(x, y, rad) in &things {
                    // Ray–disc intersection.
                    let b = x * c + y * sn;
                    let d2 = x * x + y * y - b * b;
                    if b > 0.0 && d2 < rad * rad {
                        let t = b - (rad * rad - d2).sqrt();
                        if t > 0.0 {
                            *r = r.min(t);
                        }
                    }
                }
            }
            let scan = LaserScan {
                mount: Pose::default(),
                angle_min_rad: -std::f64::consts::FRAC_PI_2,
                angle_increment_rad: std::f64::consts::PI / 180.0,
                range_max_m: 30.0,
                ranges_m: ranges,
            };
            let points: Vec<Vec2> = scan::points(&scan).collect();
            let p = ContourParams::default();
            let fast = find_gap(&points, &p, None).map(|g| (g.sides[0], g.sides[1]));
            let plain = find_gap_plain(&points, &p);
            // The same gap (its sides in either order).
            let same = match (fast, plain) {
                (None, None) => true,
                (Some((a, b)), Some((c, d))) => (a == c && b == d) || (a == d && b == c),
                _ => false,
            };
            proptest::prop_assert!(same, "pruned {fast:?}, plain {plain:?}");
        }
    }

    fn scan_of(points: &[(f64, f64)]) -> LaserScan {
        // A 181-beam scan seeing walls given as lines y = c or x = c… here
        // simply the ranges of the listed (bearing_deg, range) pairs.
        let mut ranges = vec![f64::INFINITY; 181];
        for &(deg, r) in points {
            ranges[(deg + 90.0).round() as usize] = r;
        }
        LaserScan {
            mount: Pose::default(),
            angle_min_rad: -std::f64::consts::FRAC_PI_2,
            angle_increment_rad: std::f64::consts::PI / 180.0,
            range_max_m: 30.0,
            ranges_m: ranges,
        }
    }

    /// A straight wall on the left at `d`, seen by every beam from 1° to 90°.
    fn wall_left(d: f64) -> Vec<(f64, f64)> {
        (1..=90)
            .map(|k| (k as f64, d / (k as f64).to_radians().sin()))
            .collect()
    }

    #[test]
    fn along_a_wall_at_the_set_distance_it_drives_straight() {
        let mut t = ContourTracker::following(ContourParams::default(), Side::Left).unwrap();
        let s = t.step(
            &scan_of(&wall_left(0.8)),
            Pose::default(),
            Pose::default(),
            Vec2::new(50.0, 0.0),
            0.0,
        );
        let Command::Twist { v_mps, omega_radps } = s.command else {
            panic!()
        };
        assert!(omega_radps.abs() < 0.05, "{omega_radps}");
        assert!((v_mps - 0.4).abs() < 0.02, "{v_mps}");
        assert!((s.contour_m - 0.8).abs() < 1e-9);
        // Too far: turn towards it; too near: away.
        let far = t.step(
            &scan_of(&wall_left(1.2)),
            Pose::default(),
            Pose::default(),
            Vec2::new(50.0, 0.0),
            0.1,
        );
        let near = t.step(
            &scan_of(&wall_left(0.6)),
            Pose::default(),
            Pose::default(),
            Vec2::new(50.0, 0.0),
            0.2,
        );
        let w = |s: ContourStep| match s.command {
            Command::Twist { omega_radps, .. } => omega_radps,
            _ => f64::NAN,
        };
        assert!(w(far) > 0.3 && w(near) < -0.3, "{} {}", w(far), w(near));
    }

    #[test]
    fn a_wall_ahead_turns_the_robot_away_from_the_followed_side() {
        let mut t = ContourTracker::following(ContourParams::default(), Side::Left).unwrap();
        let mut pts = wall_left(0.8);
        pts.push((0.0, 0.7));
        pts.push((-5.0, 0.72));
        let s = t.step(
            &scan_of(&pts),
            Pose::default(),
            Pose::default(),
            Vec2::new(50.0, 0.0),
            0.0,
        );
        let Command::Twist { v_mps, omega_radps } = s.command else {
            panic!()
        };
        assert!(
            omega_radps < -0.75 && v_mps < 0.05,
            "turn right on the spot: {v_mps} {omega_radps}"
        );
    }

    #[test]
    fn a_box_passed_and_remembered_behind_is_not_a_wall_ahead_in_a_passage() {
        // Following on the left, a box ahead-left at 0.62 m is remembered;
        // 0.5 m on it is behind the robot, out of the laser's view, while
        // ahead lie a wall's end on the left and a low wall on the right at
        // 0.6 m: a passage, to be passed in its middle (module docs,
        // passages).
        let deg = f64::to_radians;
        let right_wall: Vec<(f64, f64)> = (-90..=-1)
            .map(|k| (k as f64, 0.6 / deg(-k as f64).sin()))
            .collect();
        // Points at x = 0.3, y = 0.54–0.64 (bearings 61–65°).
        let mut first = right_wall.clone();
        first.extend((61..=65).map(|k| (k as f64, 0.3 / deg(k as f64).cos())));
        let mut t = ContourTracker::following(ContourParams::default(), Side::Left).unwrap();
        let goal = Vec2::new(50.0, 0.0);
        let s0 = t.step(&scan_of(&first), Pose::default(), Pose::default(), goal, 0.0);
        let Command::Twist { v_mps, .. } = s0.command else {
            panic!()
        };
        assert!(v_mps >= t.params().creep_mps, "moving: {v_mps}");
        assert!(
            (s0.contour_m - 0.3 / deg(61.0).cos()).abs() < 0.01,
            "{}",
            s0.contour_m
        );
        // 0.5 m on: the wall's end at 0.9 m, bearings 50–58°.
        let mut second = right_wall;
        second.extend((50..=58).map(|k| (k as f64, 0.9)));
        let here = Pose::new(0.5, 0.0, 0.0);
        let s1 = t.step(&scan_of(&second), here, here, goal, 0.1);
        assert!(s1.contour_m < 0.65, "the box is the nearest: {}", s1.contour_m);
        assert!(s1.centred, "centred in the passage");
    }

    #[test]
    fn a_corner_target_behind_the_robot_is_pushed_off_the_side_wall() {
        // Robot at the origin heading +x, following the wall on its left
        // (y = 0.43) into a corner with the wall ahead at x = 0.7.
        let d = 0.8;
        let mut contour = Vec::new();
        for k in 0..=34 {
            contour.push(Vec2::new(-1.0 + 0.05 * f64::from(k), 0.43));
        }
        for k in 0..=48 {
            contour.push(Vec2::new(0.7, 0.43 - 0.05 * f64::from(k)));
        }
        // One move only: to d from the wall ahead, straight behind the
        // robot (bearing ±180°: no side to turn to).
        let one = Vec2::new(0.7, 0.0) + (Vec2::new(0.4, 0.0) - Vec2::new(0.7, 0.0)).scale(d / 0.3);
        assert!(one.x < 0.0 && one.y.abs() < 1e-9, "{one:?}");
        let t = offset_point(&contour, Vec2::new(0.4, 0.0), d);
        let nearest = contour.iter().map(|q| q.dist(t)).fold(f64::INFINITY, f64::min);
        assert!(nearest >= d - 1e-6, "on the offset curve: {nearest}");
        assert!(
            t.angle() < -std::f64::consts::FRAC_PI_2,
            "behind and to the right, away from the wall followed: {t:?}"
        );
        // Along a straight wall, farther than d: pulled onto the parallel.
        let wall: Vec<Vec2> = (0..40)
            .map(|k| Vec2::new(-1.0 + 0.1 * f64::from(k), 1.2))
            .collect();
        let on = offset_point(&wall, Vec2::new(0.4, 0.0), d);
        assert!((on.y - 0.4).abs() < 1e-9 && (on.x - 0.4).abs() < 1e-9, "{on:?}");
    }

    #[test]
    fn seeking_hits_an_obstacle_then_leaves_when_the_goal_is_clear_and_nearer() {
        let mut t = ContourTracker::new(ContourParams::default()).unwrap();
        // Something 1 m ahead, the goal behind it: follow, keeping it on
        // the side away from the freer turn (all clear to the left).
        let pts: Vec<(f64, f64)> = (-20..=5).map(|k| (k as f64, 1.0)).collect();
        // First it stops and asks (a person would step aside) for
        // hit_wait_s.
        let s = t.step(
            &scan_of(&pts),
            Pose::default(),
            Pose::default(),
            Vec2::new(10.0, 0.0),
            0.0,
        );
        assert_eq!(s.mode, ContourMode::Seek);
        assert!(matches!(s.request, Some(Request::StepAside { .. })));
        assert_eq!(
            s.command,
            Command::Twist {
                v_mps: 0.0,
                omega_radps: 0.0
            }
        );
        let s = t.step(
            &scan_of(&pts),
            Pose::default(),
            Pose::default(),
            Vec2::new(10.0, 0.0),
            ContourParams::default().hit_wait_s,
        );
        assert_eq!(
            s.mode,
            ContourMode::Follow {
                side: Side::Right,
                hit_goal_m: 10.0
            }
        );
        // Clear towards the goal but not nearer: stay on the contour.
        let s = t.step(
            &scan_of(&[]),
            Pose::default(),
            Pose::default(),
            Vec2::new(10.0, 0.0),
            3.1,
        );
        assert!(matches!(s.mode, ContourMode::Follow { .. }));
        // Nearer by more than leave_progress_m and clear: leave.
        let s = t.step(
            &scan_of(&[]),
            Pose::default(),
            Pose::default(),
            Vec2::new(9.0, 0.0),
            3.2,
        );
        assert_eq!(s.mode, ContourMode::Seek);
    }

    #[test]
    fn a_gap_is_the_narrowest_free_pair_in_the_way_the_footprint_fits_through() {
        let p = ContourParams::default();
        // Two jambs 1 m ahead, 0.8 m apart, slightly to the left; walls
        // behind them.
        let mut pts: Vec<Vec2> = Vec::new();
        for k in 0..20 {
            let along = 1.0 + 0.01 * k as f64;
            pts.push(Vec2::new(along, 0.5));
            pts.push(Vec2::new(along, -0.3));
        }
        for k in 0..30 {
            pts.push(Vec2::new(1.0, 0.5 + 0.05 * k as f64));
            pts.push(Vec2::new(1.0, -0.3 - 0.05 * k as f64));
        }
        let g = find_gap(&pts, &p, None).expect("a gap");
        assert!((g.width_m - 0.8).abs() < 1e-9, "{g:?}");
        assert!(g.mid.dist(Vec2::new(1.0, 0.1)) < 0.02, "{g:?}");
        assert!(g.through.x > 0.99, "{g:?}");
        // 0.72 m: the footprint and pass_margin_m do not fit.
        let narrow: Vec<Vec2> = pts
            .iter()
            .map(|q| if q.y > 0.0 { Vec2::new(q.x, q.y - 0.08) } else { *q })
            .collect();
        assert!(find_gap(&narrow, &p, None).is_none());
        // A wall straight ahead is no gap.
        let wall: Vec<Vec2> = (-20..=20).map(|k| Vec2::new(1.0, 0.05 * k as f64)).collect();
        assert!(find_gap(&wall, &p, None).is_none());
        // Nor is a corner: nothing to go on through.
        let mut corner = wall.clone();
        corner.extend((0..20).map(|k| Vec2::new(1.0 - 0.05 * k as f64, 1.0)));
        assert!(find_gap(&corner, &p, None).is_none());
    }

    #[test]
    fn bad_parameters_are_errors() {
        for bad in [
            ContourParams {
                distance_m: 0.3,
                ..ContourParams::default()
            },
            ContourParams {
                cruise_mps: f64::NAN,
                ..ContourParams::default()
            },
            ContourParams {
                margin_m: -0.1,
                ..ContourParams::default()
            },
            ContourParams {
                pass_margin_m: 0.05,
                ..ContourParams::default()
            },
            ContourParams {
                creep_mps: 1.0,
                ..ContourParams::default()
            },
            ContourParams {
                hit_wait_s: f64::INFINITY,
                ..ContourParams::default()
            },
        ] {
            assert!(ContourTracker::new(bad).is_err());
        }
    }
}
