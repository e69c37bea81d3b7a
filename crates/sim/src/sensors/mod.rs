//! Sensor models: laser range finder, sonar, infrared proximity detectors,
//! wheel odometry and the bumper.
//!
//! Each model is a parameter struct (units in the names, defaults
//! documented, [`Default`] impl, `validate`) and a runtime part that owns its
//! random stream and its buffers. Range sensors are mounted at a pose on the
//! robot (robot frame: x forward, y left), see the obstacles of a [`Scene`]
//! — the occupancy grid by exact ray casting ([`crate::raycast::cast`]) and
//! people by exact ray–disc geometry ([`crate::ray_disc`]) — and can be read
//! at their own period ([`Schedule`]); between reads the perception keeps the
//! last reading.

pub mod bumper;
pub mod ir;
pub mod laser;
pub mod odometry;
pub mod sonar;

pub use bumper::BumperParams;
pub use ir::{Ir, IrParams};
pub use laser::{Laser, LaserParams};
pub use odometry::{Odometry, OdometryParams};
pub use sonar::{Sonar, SonarParams};

use robot::{Pose, Vec2};

use crate::distance_field::DistanceField;
use crate::error::Result;
use crate::grid::OccupancyGrid;
use crate::people::Person;
use crate::{raycast, validate};

/// What range sensors see: the static grid and the people's discs.
#[derive(Debug, Clone, Copy)]
pub struct Scene<'a> {
    /// The occupancy grid (blocked cells reflect).
    pub grid: &'a OccupancyGrid,
    /// The grid's distance field, if available: rays then skip the free
    /// disc around the sensor ([`DistanceField::free_radius_m`]) — same
    /// readings (to rounding), fewer cells visited.
    pub field: Option<&'a DistanceField>,
    /// The people.
    pub people: &'a [Person],
    /// Radius of every person's disc, metres.
    pub person_radius_m: f64,
}

impl<'a> Scene<'a> {
    /// A scene without people (and without a distance field).
    pub fn static_only(grid: &'a OccupancyGrid) -> Scene<'a> {
        Scene {
            grid,
            field: None,
            people: &[],
            person_radius_m: 0.0,
        }
    }

    /// A radius around `p` known to be free of grid obstacles, metres (0
    /// without a distance field).
    #[inline]
    pub fn free_radius_m(&self, p: Vec2) -> f64 {
        self.field.map_or(0.0, |f| f.free_radius_m(p))
    }

    /// [`raycast::cast`] from `origin` along `angle_rad` (unit direction
    /// `dir`) up to `max_range_m`, starting `skip_m` along the ray — the
    /// caller knows the cells before are free.
    #[inline]
    pub(crate) fn cast(
        &self,
        origin: Vec2,
        dir: Vec2,
        angle_rad: f64,
        skip_m: f64,
        max_range_m: f64,
    ) -> Option<f64> {
        if skip_m <= 0.0 {
            return raycast::cast(self.grid, origin, angle_rad, max_range_m);
        }
        if skip_m >= max_range_m {
            return None;
        }
        raycast::cast(
            self.grid,
            origin + dir.scale(skip_m),
            angle_rad,
            max_range_m - skip_m,
        )
        .map(|t| t + skip_m)
    }
}

/// Mounts on the rim of a circular robot: one per angle (radians from the
/// robot's forward axis, counter-clockwise), at `rim_radius_m` from the
/// centre, facing outwards.
pub fn rim_mounts(angles_rad: &[f64], rim_radius_m: f64) -> Vec<Pose> {
    angles_rad
        .iter()
        .map(|&a| Pose::new(rim_radius_m * a.cos(), rim_radius_m * a.sin(), a))
        .collect()
}

/// `count` angles evenly spread over `[-arc/2, arc/2]` (one: straight ahead).
pub fn spread_angles(count: usize, arc_rad: f64) -> Vec<f64> {
    match count {
        0 => Vec::new(),
        1 => vec![0.0],
        n => (0..n)
            .map(|k| -arc_rad / 2.0 + arc_rad * k as f64 / (n - 1) as f64)
            .collect(),
    }
}

/// When a sensor reads: every control tick, or every `period_s` seconds
/// (read at the first tick at or after each multiple of the period).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Schedule {
    period_s: Option<f64>,
    next_s: f64,
}

impl Schedule {
    /// A schedule (`None`: every tick). The first read is at time 0.
    pub fn new(period_s: Option<f64>) -> Schedule {
        Schedule {
            period_s,
            next_s: 0.0,
        }
    }

    /// Whether the sensor reads at `time_s`; if so, the next read is planned.
    #[inline]
    pub fn due(&mut self, time_s: f64) -> bool {
        let Some(p) = self.period_s else {
            return true;
        };
        // Tolerance for times computed as tick · period.
        if time_s + 1e-9 < self.next_s {
            return false;
        }
        while self.next_s <= time_s + 1e-9 {
            self.next_s += p;
        }
        true
    }
}

/// Checks a sensor's read period.
pub(crate) fn validate_period(what: &str, period_s: Option<f64>) -> Result<()> {
    match period_s {
        Some(p) => validate::positive(what, p),
        None => Ok(()),
    }
}

/// Checks a list of mounts.
pub(crate) fn validate_mounts(what: &str, mounts: &[Pose]) -> Result<()> {
    for (k, m) in mounts.iter().enumerate() {
        validate::pose(&format!("{what}[{k}]"), m)?;
    }
    Ok(())
}

/// The point `p` expressed in a frame at `origin` with axes rotated by the
/// angle whose sine and cosine are `sin`, `cos`.
#[inline]
pub(crate) fn into_frame(p: Vec2, origin: Vec2, sin: f64, cos: f64) -> Vec2 {
    let (dx, dy) = (p.x - origin.x, p.y - origin.y);
    Vec2::new(cos * dx + sin * dy, -sin * dx + cos * dy)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn schedules_read_at_their_period() {
        let mut s = Schedule::new(Some(0.2));
        let reads: Vec<bool> = (0..6).map(|k| s.due(k as f64 * 0.1)).collect();
        assert_eq!(reads, vec![true, false, true, false, true, false]);
        let mut every = Schedule::new(None);
        assert!((0..3).all(|k| every.due(k as f64)));
    }

    #[test]
    fn rim_mounts_face_outwards() {
        let m = rim_mounts(&spread_angles(3, std::f64::consts::FRAC_PI_2), 0.15);
        assert_eq!(m.len(), 3);
        assert!((m[0].theta_rad + std::f64::consts::FRAC_PI_4).abs() < 1e-12);
        assert!((m[1].x_m - 0.15).abs() < 1e-12 && m[1].y_m.abs() < 1e-12);
    }
}
