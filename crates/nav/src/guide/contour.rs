//! Contour tracking: following the contour of walls, exhibits (and people)
//! at a set distance from the raw laser scan, every control cycle, and
//! leaving it towards the goal when the way is clear (tour-guide.md).
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
//! ahead it records the distance to the goal (the hit point) and starts
//! following the obstacle on the side that turns the robot less from the
//! goal's bearing. It leaves the contour for the goal when (a) the goal's
//! bearing is within the laser's view and clear, a corridor as wide as the
//! robot plus `margin_m`, up to `leave_clear_m` or the goal, and (b) the
//! goal is at least `leave_progress_m` nearer than at the hit point
//! (Lumelsky & Stepanov's Bug2 condition, which keeps the robot from
//! circling an obstacle for ever with exact sensing). It needs the robot's
//! pose only for the goal's bearing and distance: a poor localization bends
//! the route, it does not stop the tracking.

use std::collections::VecDeque;

use robot::{Command, LaserScan, Pose, Vec2, wrap_angle};

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
    /// Following a contour without getting `stall_m` anywhere for this long
    /// turns the robot round to follow it the other way, seconds. Default 8.
    pub stall_s: f64,
    /// See `stall_s`, metres. Default 0.3.
    pub stall_m: f64,
    /// The speed is kept low enough to stop, at `decel_mps2`, before the
    /// footprint grown by this much touches anything the scan shows or
    /// showed beside the robot, metres. Default 0.06 (a remembered echo
    /// lies up to a cell from the nearest point of its wall).
    pub safety_margin_m: f64,
    /// Deceleration the stopping distance assumes, m/s². Default 0.4
    /// (below Jinny's 0.5 m/s² per wheel).
    pub decel_mps2: f64,
    /// How far ahead along the contour the tracker steers, metres.
    /// Default 0.4 (longer cuts convex corners, shorter swings wide of
    /// concave ones; both measured in `tests/contour.rs`).
    pub lookahead_m: f64,
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
            stall_s: 8.0,
            stall_m: 0.3,
            safety_margin_m: 0.03,
            decel_mps2: 0.4,
            lookahead_m: 0.4,
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
            ("lookahead_m", self.lookahead_m),
            ("stall_s", self.stall_s),
            ("stall_m", self.stall_m),
            ("decel_mps2", self.decel_mps2),
        ];
        for (name, v) in fields {
            if !(v.is_finite() && v > 0.0) {
                return Err(format!("contour.{name} must be a finite number > 0, got {v}"));
            }
        }
        for (name, v) in [
            ("margin_m", self.margin_m),
            ("leave_progress_m", self.leave_progress_m),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(format!("contour.{name} must be a finite number ≥ 0, got {v}"));
            }
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
}

/// The nearest point of `points` with bearing in `[lo, hi]` (robot frame,
/// radians), if any.
fn nearest_in(points: &[Vec2], lo: f64, hi: f64) -> Option<Vec2> {
    points
        .iter()
        .copied()
        .filter(|p| {
            let a = p.angle();
            a >= lo && a <= hi
        })
        .min_by(|a, b| a.norm().total_cmp(&b.norm()))
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

impl ContourTracker {
    /// A tracker, seeking the goal first.
    pub fn new(params: ContourParams) -> Result<ContourTracker, String> {
        params.validate()?;
        Ok(ContourTracker {
            p: params,
            mode: ContourMode::Seek,
            memory: VecDeque::new(),
            checkpoint: None,
            nearby: scan::NearbyPoints::default(),
            turning: None,
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
        let points: Vec<Vec2> = scan::points(scan).collect();
        let to_goal = estimate.inverse_transform(goal);
        let goal_m = to_goal.norm();
        let goal_bearing = to_goal.angle();
        let half = p.robot_radius_m + p.margin_m;
        // Stalled on a contour (a pocket, a gap too narrow to tell from a
        // passage): follow it the other way.
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
            self.checkpoint = Some((odometry.position(), time_s));
        }
        // Leave, or hit.
        match self.mode {
            ContourMode::Follow { hit_goal_m, .. } => {
                let length = p.leave_clear_m.min(goal_m);
                if goal_m < hit_goal_m - p.leave_progress_m
                    && scan::covers(scan, goal_bearing)
                    && clear_along(&points, goal_bearing, half, length)
                {
                    self.mode = ContourMode::Seek;
                    self.memory.clear();
                }
            }
            ContourMode::Seek => {
                let blocked_ahead = !clear_along(&points, 0.0, half, p.hit_m);
                let blocked_goal = !clear_along(&points, goal_bearing, half, p.hit_m.min(goal_m));
                if blocked_ahead && blocked_goal {
                    let side = self.free_side(&points, goal_bearing, half);
                    self.mode = ContourMode::Follow {
                        side,
                        hit_goal_m: goal_m,
                    };
                }
            }
        }
        let (mut psi, contour_m, centred) = match self.mode {
            ContourMode::Seek => (goal_bearing, f64::INFINITY, false),
            ContourMode::Follow { side, .. } => self.follow(scan, &points, side, odometry, time_s),
        };
        psi = wrap_angle(psi);
        // Room straight ahead, as wide as the footprint and 5 cm: full speed
        // beyond d* + 1 m, none when the footprint would touch.
        let body = p.robot_radius_m + 0.05;
        let front = points
            .iter()
            .filter(|q| q.x > 0.0 && q.y.abs() < body)
            .map(|q| q.x)
            .fold(f64::INFINITY, f64::min);
        let room = ((front - body) / (p.distance_m + 1.0 - body)).clamp(0.0, 1.0);
        if room == 0.0 && (psi.abs() < 0.3 || self.turning.is_some()) {
            // Blocked the way it wants to go: turn on the spot, away from
            // the contour (or towards the freer side when seeking), and keep
            // turning that way until the way ahead opens.
            let side = *self.turning.get_or_insert_with(|| match self.mode {
                ContourMode::Follow { side, .. } => -side.sign(),
                ContourMode::Seek => {
                    let left =
                        nearest_in(&points, 0.0, std::f64::consts::PI).map_or(f64::INFINITY, Vec2::norm);
                    let right =
                        nearest_in(&points, -std::f64::consts::PI, 0.0).map_or(f64::INFINITY, Vec2::norm);
                    if left >= right { 1.0 } else { -1.0 }
                }
            });
            psi = side * std::f64::consts::FRAC_PI_2;
        } else {
            self.turning = None;
        }
        let omega = (p.k_heading * psi).clamp(-p.max_turn_radps, p.max_turn_radps);
        let v = p.cruise_mps * psi.cos().max(0.0) * room;
        let near = self.nearby.update(scan, odometry, time_s);
        let v = v.min(scan::safe_speed(
            near,
            v,
            omega,
            p.robot_radius_m + p.safety_margin_m,
            p.decel_mps2,
            0.1,
        ));
        ContourStep {
            command: Command::Twist {
                v_mps: v,
                omega_radps: omega,
            },
            mode: self.mode,
            contour_m,
            centred,
        }
    }

    /// The side to follow when blocked: the obstacle on the side away from
    /// the smaller turn towards a clear bearing near the goal's.
    fn free_side(&self, points: &[Vec2], goal_bearing: f64, half: f64) -> Side {
        let step = 5f64.to_radians();
        for k in 0..=36 {
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
        points: &[Vec2],
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
            Side::Left => (deg(-45.0), deg(180.0)),
            Side::Right => (deg(-180.0), deg(45.0)),
        };
        let mut contour: Vec<Vec2> = points
            .iter()
            .copied()
            .filter(|q| (lo..=hi).contains(&q.angle()) && q.norm() < p.distance_m + p.lost_m)
            .collect();
        let seen = contour
            .iter()
            .copied()
            .min_by(|a, b| a.norm().total_cmp(&b.norm()));
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
        if let Some(n) = seen {
            self.memory.push_back((odometry.transform(n), time_s));
        }
        let nearest_to = |q: Vec2| {
            contour
                .iter()
                .copied()
                .min_by(|a, b| a.dist(q).total_cmp(&b.dist(q)))
        };
        let Some(n) = nearest_to(Vec2::default()) else {
            // Lost: arc towards the contour's side on a circle of radius d*.
            return (
                s * (p.cruise_mps / p.distance_m) / p.k_heading,
                f64::INFINITY,
                false,
            );
        };
        let d = n.norm();
        // Corridor: both sides seen beside the robot.
        let left = nearest_in(points, deg(45.0), deg(135.0));
        let right = nearest_in(points, deg(-135.0), deg(-45.0));
        if let (Some(l), Some(r)) = (left, right)
            && l.norm() + r.norm() <= p.corridor_m
            && d > p.distance_m.min(0.5 * (l.norm() + r.norm())) - 0.05
        {
            let tl = wrap_angle(l.angle() - std::f64::consts::FRAC_PI_2);
            let tr = wrap_angle(r.angle() + std::f64::consts::FRAC_PI_2);
            let offset = 0.5 * (l.norm() - r.norm());
            let psi = 0.5 * (tl + tr) + (p.k_distance * offset).atan();
            return (psi, d, true);
        }
        // Look ahead along the contour's tangent: the point of the offset
        // curve (d* from the contour) nearest that spot is where to steer.
        let normal = n.scale(-1.0 / d); // from the contour to the robot
        let tangent = Vec2::new(-s * normal.y, s * normal.x);
        let ahead = tangent.scale(p.lookahead_m);
        let target = match nearest_to(ahead) {
            Some(m) if m.dist(ahead) > 1e-9 => m + (ahead - m).scale(p.distance_m / m.dist(ahead)),
            _ => ahead,
        };
        (target.angle(), d, false)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
    fn seeking_hits_an_obstacle_then_leaves_when_the_goal_is_clear_and_nearer() {
        let mut t = ContourTracker::new(ContourParams::default()).unwrap();
        // Something 1 m ahead, the goal behind it: follow, keeping it on
        // the side away from the freer turn (all clear to the left).
        let pts: Vec<(f64, f64)> = (-20..=5).map(|k| (k as f64, 1.0)).collect();
        let s = t.step(
            &scan_of(&pts),
            Pose::default(),
            Pose::default(),
            Vec2::new(10.0, 0.0),
            0.0,
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
            0.1,
        );
        assert!(matches!(s.mode, ContourMode::Follow { .. }));
        // Nearer by more than leave_progress_m and clear: leave.
        let s = t.step(
            &scan_of(&[]),
            Pose::default(),
            Pose::default(),
            Vec2::new(9.0, 0.0),
            0.2,
        );
        assert_eq!(s.mode, ContourMode::Seek);
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
        ] {
            assert!(ContourTracker::new(bad).is_err());
        }
    }
}
