//! Laser scan endpoints as points in the robot frame.

use robot::{LaserScan, Pose, Vec2};

/// The endpoints of a scan's beams that hit something, in the robot frame
/// (the scan's mount applied): beams that hit nothing (`INFINITY`), fell
/// out (`NaN`) or read beyond `range_max_m` give no point.
pub fn points(scan: &LaserScan) -> impl Iterator<Item = Vec2> + '_ {
    let dirs = scan.beam_directions();
    let to_robot = scan.mount.transformer();
    scan.ranges_m.iter().enumerate().filter_map(move |(i, &r)| {
        if !(r.is_finite() && r >= 0.0 && r < scan.range_max_m) {
            return None;
        }
        let (ca, sa) = dirs[i];
        Some(to_robot(Vec2::new(r * ca, r * sa)))
    })
}

/// The scan with each range replaced by the median of it and its two
/// neighbours (a 3-beam median filter, as a laser filter chain runs before
/// a reactive controller): Gaussian range noise of σ becomes ≈ 0.67 σ, and
/// the chance that a beam reads 2σ short drops from 2.3 % to 0.16 % (the
/// median of three is that short only when two of them are). Edges are
/// kept where they are (at a jump the median is one side or the other);
/// a thing seen by a single beam is dropped — at 1° between beams, under
/// 2.6 cm wide at 1.5 m. Beams without a finite reading, and beams beside
/// one, are left as they are.
pub fn median3(scan: &LaserScan) -> LaserScan {
    let r = &scan.ranges_m;
    let mut out = scan.clone();
    for i in 1..r.len().saturating_sub(1) {
        let (a, b, c) = (r[i - 1], r[i], r[i + 1]);
        if a.is_finite() && b.is_finite() && c.is_finite() {
            out.ranges_m[i] = a.max(b).min(a.min(b).max(c));
        }
    }
    out
}

/// Whether the scan sees bearing `bearing_rad` (robot frame, the sensor's
/// offset neglected) within its field of view.
pub fn covers(scan: &LaserScan, bearing_rad: f64) -> bool {
    covers_relative(scan, robot::wrap_angle(bearing_rad - scan.mount.theta_rad))
}

/// Whether the scan sees bearing `rel` (sensor frame) within its field of
/// view.
pub fn covers_relative(scan: &LaserScan, rel: f64) -> bool {
    if scan.ranges_m.is_empty() {
        return false;
    }
    let last = scan.angle_min_rad + (scan.ranges_m.len() - 1) as f64 * scan.angle_increment_rad;
    let (lo, hi) = if last >= scan.angle_min_rad {
        (scan.angle_min_rad, last)
    } else {
        (last, scan.angle_min_rad)
    };
    rel >= lo - 1e-9 && rel <= hi + 1e-9
}

/// The fastest forward speed along the arc of curvature `omega / v` from
/// which the robot can still stop, decelerating at `decel_mps2`, before a
/// disc centred on the arc is `blocked` (its centre given in the robot
/// frame): `√(2 a d)` with `d` the free length of the arc (sampled every
/// 2 cm), less one control period of travel at the speed asked. Infinite
/// when the arc is clear for 1.5 m; 0 when it is blocked at once. A
/// circular robot turning on the spot sweeps nothing, so the turn itself is
/// never limited. A safety layer under any behaviour.
pub fn safe_speed_by(
    v: f64,
    omega: f64,
    decel_mps2: f64,
    period_s: f64,
    blocked: impl Fn(Vec2) -> bool,
) -> f64 {
    const STEP_M: f64 = 0.02;
    const HORIZON_M: f64 = 1.5;
    if v <= 0.0 {
        return f64::INFINITY;
    }
    let kappa = omega / v;
    let mut s = 0.0;
    while s <= HORIZON_M {
        let at = if kappa.abs() < 1e-9 {
            Vec2::new(s, 0.0)
        } else {
            Vec2::new((kappa * s).sin() / kappa, (1.0 - (kappa * s).cos()) / kappa)
        };
        if blocked(at) {
            let d = (s - v * period_s).max(0.0);
            return (2.0 * decel_mps2 * d).sqrt();
        }
        s += STEP_M;
    }
    f64::INFINITY
}

/// [`safe_speed_by`] against points (robot frame): the disc of `radius_m`
/// (the footprint and a margin) must touch none of them.
pub fn safe_speed(points: &[Vec2], v: f64, omega: f64, radius_m: f64, decel_mps2: f64, period_s: f64) -> f64 {
    let r2 = radius_m * radius_m;
    safe_speed_by(v, omega, decel_mps2, period_s, |c| {
        points
            .iter()
            .any(|q| (q.x - c.x).powi(2) + (q.y - c.y).powi(2) < r2)
    })
}

/// The obstacles near the robot for the safety layer: this scan's points
/// and those of earlier scans now out of the laser's view — a 180° laser
/// ahead of the centre does not see what is beside the robot's rear half,
/// which a turn can sweep. Earlier points are kept one per 5 cm square of
/// the odometry frame, and forgotten once the robot has moved
/// [`NearbyPoints::FORGET_AFTER_M`] since (a turn counts as the arc its rim
/// travels), after [`NearbyPoints::FORGET_AFTER_S`] (what stood beside the
/// robot may have been a person who left; [`NearbyPoints::forgetting_after`]
/// for another time), or when they are out of reach.
///
/// Rejected: forgetting a point by the robot's *net* motion from where it
/// saw it instead of the motion summed since, because in the museum what
/// people stood beside the robot then held it up longer; telling a wall
/// from a person out of view is what is missing, not the distance.
///
/// Known weakness: a wall beside the robot, where a laser 0.2 m ahead of
/// the centre cannot see, is forgotten while the robot stands or turns
/// beside it for long, and the law can then turn into it. The variants
/// examined (points cleared when the laser sees through them, 2 cm
/// squares, no forgetting by time, a look before moving towards an unseen
/// side) each cost legs elsewhere: `crates/guide/EXPERIMENTS.md`, section
/// `guide/scan.rs`.
#[derive(Debug, Clone, Default)]
pub struct NearbyPoints {
    /// Remembered points are forgotten after this long, seconds (`None`:
    /// [`NearbyPoints::FORGET_AFTER_S`]).
    forget_after_s: Option<f64>,
    /// Remembered points by 5 cm square (odometry frame): the point, the
    /// motion counter and the time when last seen.
    memory: std::collections::BTreeMap<(i64, i64), (Vec2, f64, f64)>,
    /// The points of the last update, robot frame.
    points: Vec<Vec2>,
    /// Motion so far, metres, and the last odometry pose.
    travelled_m: f64,
    last: Option<Pose>,
}

impl NearbyPoints {
    /// Remembered points are forgotten after this much motion, metres.
    pub const FORGET_AFTER_M: f64 = 1.0;
    /// …or after this long, seconds.
    pub const FORGET_AFTER_S: f64 = 3.0;
    /// Points farther than this from the robot are not kept, metres.
    pub const REACH_M: f64 = 1.5;
    /// Side of the squares points are kept by, metres.
    const SQUARE_M: f64 = 0.05;
    /// Radius of the rim whose arc measures a turn, metres.
    const RIM_M: f64 = 0.35;

    /// Remembering points out of view for `seconds` (and as long as the
    /// robot has not moved [`NearbyPoints::FORGET_AFTER_M`]) instead of
    /// [`NearbyPoints::FORGET_AFTER_S`]; a `seconds` that is not a number is
    /// the default.
    pub fn forgetting_after(seconds: f64) -> NearbyPoints {
        NearbyPoints {
            forget_after_s: (!seconds.is_nan()).then_some(seconds),
            ..NearbyPoints::default()
        }
    }

    /// Takes a new scan, read at `odometry` and `time_s`; returns the points
    /// near the robot, robot frame.
    pub fn update(&mut self, scan: &LaserScan, odometry: Pose, time_s: f64) -> &[Vec2] {
        let forget_after_s = self.forget_after_s.unwrap_or(Self::FORGET_AFTER_S);
        if let Some(last) = self.last {
            let turn = robot::wrap_angle(odometry.theta_rad - last.theta_rad).abs();
            self.travelled_m += odometry.position().dist(last.position()) + turn * Self::RIM_M;
        }
        self.last = Some(odometry);
        let now = self.travelled_m;
        let here = odometry.position();
        self.memory.retain(|_, &mut (at, m, t)| {
            now - m <= Self::FORGET_AFTER_M && time_s - t <= forget_after_s && at.dist(here) < Self::REACH_M
        });
        self.points.clear();
        self.points
            .extend(points(scan).filter(|q| q.norm() < Self::REACH_M));
        let seen = self.points.len();
        for &(at, _, _) in self.memory.values() {
            let q = odometry.inverse_transform(at);
            let from_sensor = scan.mount.inverse_transform(q).angle();
            if !covers_relative(scan, from_sensor) {
                self.points.push(q);
            }
        }
        for &q in &self.points[..seen] {
            let at = odometry.transform(q);
            let key = (
                (at.x / Self::SQUARE_M).floor() as i64,
                (at.y / Self::SQUARE_M).floor() as i64,
            );
            self.memory.insert(key, (at, now, time_s));
        }
        &self.points
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use robot::Pose;

    #[test]
    fn endpoints_honour_the_mount_and_skip_misses() {
        let scan = LaserScan {
            mount: Pose::new(0.2, 0.0, 0.0),
            angle_min_rad: -std::f64::consts::FRAC_PI_2,
            angle_increment_rad: std::f64::consts::FRAC_PI_2,
            range_max_m: 10.0,
            ranges_m: vec![1.0, f64::INFINITY, f64::NAN],
        };
        let p: Vec<Vec2> = points(&scan).collect();
        assert_eq!(p.len(), 1);
        assert!((p[0].x - 0.2).abs() < 1e-12 && (p[0].y + 1.0).abs() < 1e-12);
        assert!(covers(&scan, 1.0) && !covers(&scan, 2.0));
    }

    #[test]
    fn the_median_filter_keeps_edges_and_drops_lone_outliers() {
        let scan = LaserScan {
            mount: Pose::default(),
            angle_min_rad: 0.0,
            angle_increment_rad: 0.01,
            range_max_m: 10.0,
            ranges_m: vec![1.0, 1.0, 0.5, 1.0, 1.0, 3.0, 3.0, f64::NAN, 3.0, 2.9],
        };
        let m = median3(&scan).ranges_m;
        // The lone short reading is gone, the 1 m → 3 m edge stays put.
        assert_eq!(&m[..7], &[1.0, 1.0, 1.0, 1.0, 1.0, 3.0, 3.0]);
        // Beside a drop-out, as read; the ends as read.
        assert!(m[7].is_nan());
        assert_eq!((m[6], m[8], m[9]), (3.0, 3.0, 2.9));
    }

    #[test]
    fn the_speed_lets_the_robot_stop_before_what_is_ahead_not_for_what_is_beside() {
        let ahead = [Vec2::new(0.8, 0.0)];
        // The disc of 0.4 m touches after 0.4 m of straight travel; less
        // 0.05 m travelled in a period at 0.5 m/s: √(2 · 0.5 · 0.35).
        let v = safe_speed(&ahead, 0.5, 0.0, 0.4, 0.5, 0.1);
        assert!((v - 0.35f64.sqrt()).abs() < 0.02, "{v}");
        assert_eq!(
            safe_speed(&[Vec2::new(3.0, 0.0)], 0.5, 0.0, 0.4, 0.5, 0.1),
            f64::INFINITY
        );
        let beside = [Vec2::new(0.0, 0.6)];
        assert_eq!(safe_speed(&beside, 0.5, 0.0, 0.4, 0.5, 0.1), f64::INFINITY);
        // Turning towards it, the arc meets it.
        assert!(safe_speed(&beside, 0.5, 1.5, 0.4, 0.5, 0.1).is_finite());
        // Against it: nothing.
        assert_eq!(safe_speed(&[Vec2::new(0.35, 0.0)], 0.3, 0.0, 0.4, 0.5, 0.1), 0.0);
        assert_eq!(safe_speed(&ahead, 0.0, 1.0, 0.4, 0.5, 0.1), f64::INFINITY);
    }

    #[test]
    fn points_out_of_view_are_remembered_for_a_while() {
        let scan = |r: f64| LaserScan {
            mount: Pose::new(0.2, 0.0, 0.0),
            angle_min_rad: -std::f64::consts::FRAC_PI_2,
            angle_increment_rad: std::f64::consts::FRAC_PI_2,
            range_max_m: 10.0,
            ranges_m: vec![f64::INFINITY, f64::INFINITY, r],
        };
        let mut n = NearbyPoints::default();
        // A point 0.6 m to the left of the laser.
        assert_eq!(n.update(&scan(0.6), Pose::default(), 0.0).len(), 1);
        // The robot moved 0.5 m on: the point is behind the laser's view
        // now, and remembered.
        let p = n
            .update(&scan(f64::INFINITY), Pose::new(0.5, 0.0, 0.0), 0.5)
            .to_vec();
        assert_eq!(p.len(), 1);
        assert!(
            (p[0].x + 0.3).abs() < 1e-9 && (p[0].y - 0.6).abs() < 1e-9,
            "{p:?}"
        );
        // Still there a while later, forgotten after FORGET_AFTER_S…
        assert_eq!(
            n.update(&scan(f64::INFINITY), Pose::new(0.5, 0.0, 0.0), 2.9)
                .len(),
            1
        );
        assert!(
            n.update(&scan(f64::INFINITY), Pose::new(0.5, 0.0, 0.0), 3.1)
                .is_empty()
        );
        // …or once the robot has moved on.
        n.update(&scan(0.6), Pose::default(), 10.0);
        assert_eq!(
            n.update(&scan(f64::INFINITY), Pose::new(0.5, 0.0, 0.0), 10.1)
                .len(),
            1
        );
        assert!(
            n.update(&scan(f64::INFINITY), Pose::new(1.6, 0.0, 0.0), 10.2)
                .is_empty()
        );
    }
}
