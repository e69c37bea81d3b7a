//! Differential-drive kinematics: exact arc integration of wheel speeds, and
//! the wheel-speed and acceleration limits of the drive.
//!
//! With wheel rim speeds `v_L`, `v_R` (m/s) held constant for `Δt` and wheel
//! base `d`, the robot moves along a circular arc (docs/sim.md, *Kinematics*):
//! `v = (v_R + v_L)/2`, `ω = (v_R − v_L)/d`, `R = v/ω`,
//! `x' = x + R (sin(θ + ωΔt) − sin θ)`, `y' = y − R (cos(θ + ωΔt) − cos θ)`,
//! `θ' = θ + ωΔt` (θ counter-clockwise from +x).
//!
//! [`integrate`] evaluates the same arc in the algebraically identical chord
//! form `x' = x + vΔt · sinc(ωΔt/2) · cos(θ + ωΔt/2)`,
//! `y' = y + vΔt · sinc(ωΔt/2) · sin(θ + ωΔt/2)` with `sinc(u) = sin(u)/u`,
//! which has no `1/(v_R − v_L)`: it is numerically safe when the wheel speeds
//! are nearly equal, reduces exactly (bit for bit) to the straight-line update
//! `x' = x + vΔt cos θ` when `v_R = v_L`, and to a turn in place (`x' = x`)
//! when `v_R = −v_L`. Cost: one `sin_cos` of the mid heading and one `sin`.

use robot::Pose;

use crate::error::Result;
use crate::{fast_math, validate};

/// Parameters of a differential-drive base with a circular footprint.
///
/// The defaults describe a generic small indoor robot; [`DriveParams::aibot`]
/// and [`DriveParams::jinny`] give the two robots of the reproduced
/// experiments.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct DriveParams {
    /// Distance between the wheels' contact points, metres. Default 0.3.
    pub wheel_base_m: f64,
    /// Radius of the circular footprint used for collisions and the bumper,
    /// metres. Default 0.2.
    pub radius_m: f64,
    /// Largest wheel rim speed, m/s, forwards or backwards. Commands beyond
    /// it are scaled down, both wheels by the same factor so that the path's
    /// curvature is kept. Default 0.5.
    pub max_wheel_speed_mps: f64,
    /// Largest change of a wheel's rim speed per second, m/s²; each wheel is
    /// limited on its own. `f64::INFINITY` for none. Default 1.0.
    pub max_wheel_accel_mps2: f64,
}

/// Cruise speed of the AIBOT-like robot, m/s (docs/voting.md: "average speed 0.3 m/s").
pub const AIBOT_CRUISE_SPEED_MPS: f64 = 0.3;

/// Cruise speed assumed for the Jinny-like tour-guide robot, m/s.
pub const JINNY_CRUISE_SPEED_MPS: f64 = 0.5;

impl Default for DriveParams {
    fn default() -> DriveParams {
        DriveParams {
            wheel_base_m: 0.3,
            radius_m: 0.2,
            max_wheel_speed_mps: 0.5,
            max_wheel_accel_mps2: 1.0,
        }
    }
}

impl DriveParams {
    /// The AIBOT-like robot of the voting experiments: footprint radius
    /// 0.15 m, wheel base 0.25 m, wheels up to 0.5 m/s (cruise
    /// [`AIBOT_CRUISE_SPEED_MPS`] = 0.3 m/s, with room to turn at cruise
    /// speed), 1 m/s² per wheel.
    pub fn aibot() -> DriveParams {
        DriveParams {
            wheel_base_m: 0.25,
            radius_m: 0.15,
            max_wheel_speed_mps: 0.5,
            max_wheel_accel_mps2: 1.0,
        }
    }

    /// The Jinny-like tour-guide robot: footprint radius 0.35 m, wheel base
    /// 0.5 m, wheels up to 1.0 m/s (cruise [`JINNY_CRUISE_SPEED_MPS`]),
    /// 0.5 m/s² per wheel (a heavy base among visitors).
    pub fn jinny() -> DriveParams {
        DriveParams {
            wheel_base_m: 0.5,
            radius_m: 0.35,
            max_wheel_speed_mps: 1.0,
            max_wheel_accel_mps2: 0.5,
        }
    }

    /// Checks every field: wheel base, radius, speed > 0 and finite; the
    /// acceleration > 0 (infinite allowed).
    pub fn validate(&self) -> Result<()> {
        validate::positive("drive.wheel_base_m", self.wheel_base_m)?;
        validate::positive("drive.radius_m", self.radius_m)?;
        validate::positive("drive.max_wheel_speed_mps", self.max_wheel_speed_mps)?;
        if self.max_wheel_accel_mps2.is_nan() || self.max_wheel_accel_mps2 <= 0.0 {
            return Err(crate::Error::InvalidValue {
                what: "drive.max_wheel_accel_mps2".to_string(),
                requirement: "> 0 (infinite for no limit)",
                value: self.max_wheel_accel_mps2,
            });
        }
        Ok(())
    }

    /// The wheel speeds actually driven for one step of `dt_s` seconds, from
    /// the current ones towards the commanded `target` (left, right), m/s:
    /// non-finite targets count as 0; the target pair is scaled into
    /// `±max_wheel_speed_mps` keeping its ratio; then each wheel moves
    /// towards it by at most `max_wheel_accel_mps2 · dt_s`.
    pub fn limit(&self, current: (f64, f64), target: (f64, f64), dt_s: f64) -> (f64, f64) {
        let clean = |v: f64| if v.is_finite() { v } else { 0.0 };
        let (mut l, mut r) = (clean(target.0), clean(target.1));
        let biggest = l.abs().max(r.abs());
        if biggest > self.max_wheel_speed_mps {
            let k = self.max_wheel_speed_mps / biggest;
            l *= k;
            r *= k;
        }
        let step = self.max_wheel_accel_mps2 * dt_s;
        let ramp = |from: f64, to: f64| from + (to - from).clamp(-step, step);
        (ramp(current.0, l), ramp(current.1, r))
    }
}

/// `sin(u)/u`, accurate near 0.
#[inline]
fn sinc(u: f64) -> f64 {
    if u.abs() < 1e-4 {
        // Taylor series; the next term, u⁴/120, is below 1e-18.
        1.0 - u * u / 6.0
    } else {
        u.sin() / u
    }
}

/// The pose after driving the wheels at constant rim speeds `left_mps`,
/// `right_mps` for `dt_s` seconds from `pose`, on a base of wheel base
/// `wheel_base_m`: the exact arc (module docs). The heading is wrapped to
/// (−π, π].
#[inline]
pub fn integrate(pose: Pose, left_mps: f64, right_mps: f64, wheel_base_m: f64, dt_s: f64) -> Pose {
    let v = 0.5 * (right_mps + left_mps);
    let dtheta = (right_mps - left_mps) / wheel_base_m * dt_s;
    let half = 0.5 * dtheta;
    let chord = v * dt_s * sinc(half);
    let (s, c) = (pose.theta_rad + half).sin_cos();
    fast_math::pose(
        pose.x_m + chord * c,
        pose.y_m + chord * s,
        pose.theta_rad + dtheta,
    )
}

/// Length of the path driven by the centre of the base in one step at
/// constant wheel speeds: `|v_R + v_L|/2 · Δt`, metres (0 for a turn in
/// place).
#[inline]
pub fn arc_length_m(left_mps: f64, right_mps: f64, dt_s: f64) -> f64 {
    (0.5 * (right_mps + left_mps) * dt_s).abs()
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use robot::wrap_angle;

    /// The spec's formula, as written (well-conditioned speeds only).
    fn spec_arc(p: Pose, l: f64, r: f64, d: f64, dt: f64) -> Pose {
        if l == r {
            return Pose::new(
                p.x_m + l * p.theta_rad.cos() * dt,
                p.y_m + l * p.theta_rad.sin() * dt,
                p.theta_rad,
            );
        }
        let radius = d * (r + l) / (2.0 * (r - l));
        let w = (r - l) / d;
        let th = p.theta_rad + w * dt;
        Pose::new(
            p.x_m + radius * (th.sin() - p.theta_rad.sin()),
            p.y_m - radius * (th.cos() - p.theta_rad.cos()),
            th,
        )
    }

    fn close(a: Pose, b: Pose, tol: f64) -> bool {
        (a.x_m - b.x_m).abs() <= tol
            && (a.y_m - b.y_m).abs() <= tol
            && wrap_angle(a.theta_rad - b.theta_rad).abs() <= tol
    }

    #[test]
    fn agrees_with_the_spec_formula() {
        let p = Pose::new(1.0, -2.0, 0.4);
        for &(l, r) in &[(0.1, 0.3), (0.3, 0.1), (-0.2, 0.2), (0.5, -0.1), (0.3, 0.3001)] {
            let a = integrate(p, l, r, 0.25, 0.7);
            let b = spec_arc(p, l, r, 0.25, 0.7);
            assert!(close(a, b, 1e-9), "{l} {r}: {a:?} vs {b:?}");
        }
    }

    #[test]
    fn straight_and_in_place_are_exact() {
        let p = Pose::new(0.5, 0.25, 0.3);
        let s = integrate(p, 0.3, 0.3, 0.25, 2.0);
        assert_eq!(s.x_m, 0.5 + 0.3 * 2.0 * 0.3f64.cos());
        assert_eq!(s.y_m, 0.25 + 0.3 * 2.0 * 0.3f64.sin());
        assert_eq!(s.theta_rad, 0.3);
        let t = integrate(p, -0.2, 0.2, 0.25, 1.0);
        assert_eq!((t.x_m, t.y_m), (0.5, 0.25));
        assert_eq!(t.theta_rad, wrap_angle(0.3 + 0.4 / 0.25));
    }

    #[test]
    fn a_full_circle_comes_back() {
        // ω = 0.2/0.25 rad/s: one turn takes 2π/0.8 s.
        let p = Pose::new(3.0, 4.0, -1.0);
        let q = integrate(p, 0.2, 0.4, 0.25, 2.0 * std::f64::consts::PI / 0.8);
        assert!(close(p, q, 1e-12), "{q:?}");
    }

    #[test]
    fn nearly_equal_speeds_are_safe() {
        let p = Pose::new(0.0, 0.0, 0.0);
        let q = integrate(p, 0.3, 0.3 + 1e-15, 0.25, 1.0);
        assert!((q.x_m - 0.3).abs() < 1e-12 && q.y_m.abs() < 1e-12, "{q:?}");
    }

    #[test]
    fn limits_keep_curvature_and_ramp() {
        let d = DriveParams::aibot();
        // Scaled into ±0.5 m/s keeping the 1:2 ratio, then ramped by 0.1 m/s.
        let (l, r) = d.limit((0.0, 0.0), (0.5, 1.0), 0.1);
        assert!((l - 0.1).abs() < 1e-12 && (r - 0.1).abs() < 1e-12);
        let (l, r) = d.limit((0.25, 0.5), (0.5, 1.0), 0.1);
        assert!((l - 0.25).abs() < 1e-12 && (r - 0.5).abs() < 1e-12);
        assert_eq!(d.limit((0.0, 0.0), (f64::NAN, 0.0), 0.1), (0.0, 0.0));
    }

    #[test]
    fn bad_parameters_are_rejected() {
        let d = DriveParams {
            wheel_base_m: -0.1,
            ..DriveParams::default()
        };
        assert!(matches!(d.validate(), Err(crate::Error::InvalidValue { .. })));
        let d = DriveParams {
            max_wheel_accel_mps2: f64::INFINITY,
            ..DriveParams::default()
        };
        assert!(d.validate().is_ok());
    }

    proptest! {
        /// n steps of dt at constant speeds equal the closed-form arc over n·dt.
        #[test]
        fn stepping_equals_the_closed_form(
            l in -1.0f64..1.0, r in -1.0f64..1.0, dt in 0.001f64..0.5, n in 1usize..400,
            x in -10.0f64..10.0, y in -10.0f64..10.0, th in -3.1f64..3.1, d in 0.1f64..1.0,
        ) {
            let start = Pose::new(x, y, th);
            let mut p = start;
            for _ in 0..n {
                p = integrate(p, l, r, d, dt);
            }
            let closed = integrate(start, l, r, d, n as f64 * dt);
            prop_assert!(close(p, closed, 1e-9), "{:?} vs {:?}", p, closed);
        }

        /// Straight motion and turns in place are exact for any n.
        #[test]
        fn straight_and_in_place_stay_exact(v in -1.0f64..1.0, dt in 0.001f64..0.5, n in 1usize..400, th in -3.1f64..3.1) {
            let start = Pose::new(0.0, 0.0, th);
            let mut p = start;
            let mut q = start;
            for _ in 0..n {
                p = integrate(p, v, v, 0.3, dt);
                q = integrate(q, -v, v, 0.3, dt);
            }
            prop_assert_eq!(p.theta_rad, start.theta_rad);
            prop_assert_eq!((q.x_m, q.y_m), (0.0, 0.0));
            let closed = integrate(start, v, v, 0.3, n as f64 * dt);
            prop_assert!(close(p, closed, 1e-9));
            prop_assert!(wrap_angle(q.theta_rad - (th + 2.0 * v / 0.3 * n as f64 * dt)).abs() < 1e-9);
        }
    }
}
