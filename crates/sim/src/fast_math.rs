//! Small numeric helpers for the hot paths.
//!
//! `robot::Vec2::norm` uses `hypot` (overflow-safe, but several times
//! slower than `sqrt(x² + y²)`); positions in a map are far from overflow,
//! so the hot paths use the plain form. `Pose::new` wraps headings with a
//! floating remainder; [`wrap`] skips it when the angle is already in range
//! (bit-identical to `robot::wrap_angle`).

use robot::{Pose, Vec2};

/// Euclidean length of `v`.
#[inline]
pub(crate) fn norm(v: Vec2) -> f64 {
    (v.x * v.x + v.y * v.y).sqrt()
}

/// Distance between `a` and `b`.
#[inline]
pub(crate) fn dist(a: Vec2, b: Vec2) -> f64 {
    norm(a - b)
}

/// `robot::wrap_angle`, fast when the angle is already in (−π, π].
#[inline]
pub(crate) fn wrap(a: f64) -> f64 {
    if a > -std::f64::consts::PI && a <= std::f64::consts::PI {
        a
    } else {
        robot::wrap_angle(a)
    }
}

/// A pose with its heading wrapped by [`wrap`].
#[inline]
pub(crate) fn pose(x_m: f64, y_m: f64, theta_rad: f64) -> Pose {
    Pose {
        x_m,
        y_m,
        theta_rad: wrap(theta_rad),
    }
}

/// A sensor mounted at `mount` on a robot at `robot` (whose heading has sine
/// `sin` and cosine `cos`): its origin in the world and its heading
/// (unwrapped).
#[inline]
pub(crate) fn mounted(robot: &Pose, sin: f64, cos: f64, mount: &Pose) -> (Vec2, f64) {
    (
        Vec2::new(
            robot.x_m + cos * mount.x_m - sin * mount.y_m,
            robot.y_m + sin * mount.x_m + cos * mount.y_m,
        ),
        robot.theta_rad + mount.theta_rad,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fast_wrap_matches_wrap_angle() {
        for &a in &[
            0.0,
            1.0,
            -1.0,
            3.0,
            -3.2,
            3.2,
            7.0,
            -7.0,
            std::f64::consts::PI,
            -std::f64::consts::PI,
        ] {
            assert_eq!(wrap(a).to_bits(), robot::wrap_angle(a).to_bits(), "{a}");
        }
    }
}
