//! What a ring of sonar transducers says around the robot: the range seen
//! along a bearing, the free distance ahead, the distance to a wall on a
//! side — the few questions the topological layer's strategies and its
//! reference-place detector ask.
//!
//! Ranges are from the robot's centre (a reading plus its transducer's
//! offset along the axis), bearings in the robot frame (counter-clockwise,
//! 0 ahead). A transducer that hears no echo reads `f64::INFINITY`.
//! Built for `sim::RobotParams::sonar_ring`'s 16 transducers 22.5° apart
//! (cones 25°), but any layout works: every question picks the transducers
//! whose axes lie in the bearings it asks about.

use robot::{Perception, Vec2, wrap_angle};

/// One transducer's axis and echo.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Echo {
    /// Bearing of the axis in the robot frame, radians.
    pub bearing_rad: f64,
    /// Distance from the robot's centre to the echo, metres (infinite: none).
    pub range_m: f64,
}

/// The echoes of one perception, by bearing.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Ring {
    echoes: Vec<Echo>,
}

/// Which side of the robot.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Side {
    /// Counter-clockwise of the heading.
    Left,
    /// Clockwise of the heading.
    Right,
}

impl Side {
    /// +1 for left, −1 for right (the sign of a turn toward it).
    pub fn sign(self) -> f64 {
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

impl Ring {
    /// The sonar echoes of a perception (lasers and IR are ignored: the
    /// topological layer is built for a sonar-only robot).
    pub fn of(p: &Perception) -> Ring {
        let echoes = p
            .sonar
            .iter()
            .map(|s| {
                let axis = Vec2::new(s.mount.theta_rad.cos(), s.mount.theta_rad.sin());
                let range_m = if s.range_m.is_finite() {
                    // Centre to echo: the mount's offset plus the reading
                    // along the axis.
                    let hit = Vec2::new(s.mount.x_m + s.range_m * axis.x, s.mount.y_m + s.range_m * axis.y);
                    hit.norm()
                } else {
                    f64::INFINITY
                };
                Echo {
                    bearing_rad: wrap_angle(s.mount.theta_rad),
                    range_m,
                }
            })
            .collect();
        Ring { echoes }
    }

    /// A ring from bearings (degrees, robot frame) and centre ranges
    /// (metres), for tests and hand-made perceptions.
    pub fn from_degrees(pairs: &[(f64, f64)]) -> Ring {
        Ring {
            echoes: pairs
                .iter()
                .map(|&(deg, r)| Echo {
                    bearing_rad: wrap_angle(deg.to_radians()),
                    range_m: r,
                })
                .collect(),
        }
    }

    /// All echoes.
    pub fn echoes(&self) -> &[Echo] {
        &self.echoes
    }

    /// Whether the ring has no transducer at all.
    pub fn is_empty(&self) -> bool {
        self.echoes.is_empty()
    }

    /// The range of the transducer whose axis is nearest `bearing_rad`
    /// (infinite with no transducer).
    pub fn range_toward(&self, bearing_rad: f64) -> f64 {
        self.echoes
            .iter()
            .min_by(|a, b| {
                let da = wrap_angle(a.bearing_rad - bearing_rad).abs();
                let db = wrap_angle(b.bearing_rad - bearing_rad).abs();
                da.total_cmp(&db)
            })
            .map_or(f64::INFINITY, |e| e.range_m)
    }

    /// Free distance ahead: over the transducers within `half_width_rad`
    /// of the heading, the smallest range projected on the heading.
    pub fn ahead_m(&self, half_width_rad: f64) -> f64 {
        self.echoes
            .iter()
            .filter(|e| e.bearing_rad.abs() <= half_width_rad + 1e-9)
            .map(|e| e.range_m * e.bearing_rad.cos())
            .fold(f64::INFINITY, f64::min)
    }

    /// Distance to a wall on `side`, assumed parallel to the heading: over
    /// the transducers between `from_rad` and `to_rad` of bearing on that
    /// side (e.g. 45°…112.5°), the smallest range times |sin(bearing)| —
    /// each transducer's estimate of the perpendicular distance.
    pub fn side_m(&self, side: Side, from_rad: f64, to_rad: f64) -> f64 {
        let s = side.sign();
        self.echoes
            .iter()
            .filter(|e| {
                let b = s * e.bearing_rad;
                b >= from_rad - 1e-9 && b <= to_rad + 1e-9
            })
            .map(|e| e.range_m * e.bearing_rad.sin().abs())
            .fold(f64::INFINITY, f64::min)
    }

    /// The nearest echo of all.
    pub fn nearest_m(&self) -> f64 {
        self.echoes
            .iter()
            .map(|e| e.range_m)
            .fold(f64::INFINITY, f64::min)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ring16(f: impl Fn(f64) -> f64) -> Ring {
        let pairs: Vec<(f64, f64)> = (0..16)
            .map(|k| {
                let deg = 22.5 * k as f64;
                (deg, f(wrap_angle(deg.to_radians())))
            })
            .collect();
        Ring::from_degrees(&pairs)
    }

    #[test]
    fn a_wall_parallel_on_the_left_is_seen_at_its_perpendicular_distance() {
        // Wall y = +0.5 in the robot frame: a ray at bearing b > 0 hits it
        // at 0.5 / sin b.
        let ring = ring16(|b| if b > 0.05 { 0.5 / b.sin() } else { f64::INFINITY });
        let d = ring.side_m(Side::Left, 45f64.to_radians(), 112.5f64.to_radians());
        assert!((d - 0.5).abs() < 1e-9, "{d}");
        assert_eq!(
            ring.side_m(Side::Right, 45f64.to_radians(), 112.5f64.to_radians()),
            f64::INFINITY
        );
        assert_eq!(
            ring.ahead_m(25f64.to_radians()),
            0.5 / 22.5f64.to_radians().sin() * 22.5f64.to_radians().cos()
        );
    }

    #[test]
    fn range_toward_picks_the_nearest_axis() {
        let ring = ring16(|b| 1.0 + b);
        assert!((ring.range_toward(0.1) - 1.0).abs() < 1e-12);
        assert!(
            (ring.range_toward(std::f64::consts::FRAC_PI_2) - (1.0 + std::f64::consts::FRAC_PI_2)).abs()
                < 1e-12
        );
        assert_eq!(Ring::default().range_toward(0.0), f64::INFINITY);
    }
}
