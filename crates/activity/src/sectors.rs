//! Nearest obstacle per sector around the robot, from whatever range
//! sensors a perception carries (laser beams, sonar axes, triggered IR
//! detectors), in the robot frame.
//!
//! | sector | bearing (robot frame) |
//! |---|---|
//! | front | \|a\| ≤ 30° |
//! | left | 30° < a < 150° |
//! | right | −150° < a < −30° |
//! | back | \|a\| ≥ 150° |
//!
//! Distances are from the robot's centre (a sensor's reading plus its
//! mount's offset along the beam); `f64::INFINITY` when nothing is seen.

use robot::{Perception, Pose, Vec2, wrap_angle};

/// Distances to the nearest obstacle per sector, metres.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Sectors {
    /// Ahead.
    pub front_m: f64,
    /// On the left.
    pub left_m: f64,
    /// On the right.
    pub right_m: f64,
    /// Behind.
    pub back_m: f64,
}

impl Default for Sectors {
    fn default() -> Self {
        Sectors {
            front_m: f64::INFINITY,
            left_m: f64::INFINITY,
            right_m: f64::INFINITY,
            back_m: f64::INFINITY,
        }
    }
}

impl Sectors {
    fn add(&mut self, mount: &Pose, beam_rad: f64, range_m: f64) {
        if !range_m.is_finite() || range_m < 0.0 {
            return;
        }
        let dir = mount.theta_rad + beam_rad;
        let hit = mount.transform(Vec2::new(range_m * beam_rad.cos(), range_m * beam_rad.sin()));
        let d = hit.norm();
        let a = wrap_angle(dir).to_degrees();
        let slot = if a.abs() <= 30.0 {
            &mut self.front_m
        } else if a.abs() >= 150.0 {
            &mut self.back_m
        } else if a > 0.0 {
            &mut self.left_m
        } else {
            &mut self.right_m
        };
        *slot = slot.min(d);
    }

    /// The sectors of a perception.
    pub fn of(p: &Perception) -> Sectors {
        let mut s = Sectors::default();
        for scan in &p.lasers {
            for (i, &r) in scan.ranges_m.iter().enumerate() {
                let a = scan.angle_min_rad + i as f64 * scan.angle_increment_rad;
                s.add(&scan.mount, a, r);
            }
        }
        for sonar in &p.sonar {
            s.add(&sonar.mount, 0.0, sonar.range_m);
        }
        for ir in p.ir.iter().filter(|d| d.triggered) {
            s.add(&ir.mount, 0.0, ir.range_m);
        }
        s
    }

    /// The nearest of all.
    pub fn min_m(&self) -> f64 {
        self.front_m.min(self.left_m).min(self.right_m).min(self.back_m)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use robot::LaserScan;

    #[test]
    fn laser_beams_fall_into_sectors() {
        let p = Perception {
            lasers: vec![LaserScan {
                mount: Pose::new(0.1, 0.0, 0.0),
                angle_min_rad: -std::f64::consts::FRAC_PI_2,
                angle_increment_rad: std::f64::consts::FRAC_PI_2,
                range_max_m: 10.0,
                ranges_m: vec![2.0, 1.0, f64::NAN],
            }],
            ..Perception::default()
        };
        let s = Sectors::of(&p);
        assert!((s.front_m - 1.1).abs() < 1e-12);
        assert!((s.right_m - (2.0f64.powi(2) + 0.01).sqrt()).abs() < 1e-12);
        assert_eq!(s.left_m, f64::INFINITY);
        assert_eq!(s.back_m, f64::INFINITY);
    }
}
