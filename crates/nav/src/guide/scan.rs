//! Laser scan endpoints as points in the robot frame.

use robot::{LaserScan, Vec2};

/// The endpoints of a scan's beams that hit something, in the robot frame
/// (the scan's mount applied): beams that hit nothing (`INFINITY`), fell
/// out (`NaN`) or read beyond `range_max_m` give no point.
pub fn points(scan: &LaserScan) -> impl Iterator<Item = Vec2> + '_ {
    scan.ranges_m.iter().enumerate().filter_map(move |(i, &r)| {
        if !(r.is_finite() && r >= 0.0 && r < scan.range_max_m) {
            return None;
        }
        let a = scan.angle_min_rad + i as f64 * scan.angle_increment_rad;
        Some(scan.mount.transform(Vec2::new(r * a.cos(), r * a.sin())))
    })
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
}
