//! Wheel odometry: noisy encoder increments, dead-reckoned into a pose
//! estimate that drifts from the truth.
//!
//! **Model.** At every physics step each wheel's true travel `Δs` (rim speed
//! × step, whether or not the robot actually moved: a wheel spinning against
//! a wall still counts) is measured as
//! `Δŝ = Δs · (1 + e) · (1 + ε) · (1 + s)`:
//!
//! - `e` a fixed calibration error per wheel (`left_scale_error`,
//!   `right_scale_error`), the systematic part of odometry error
//!   (J. Borenstein, L. Feng, *UMBmark*, 1995);
//! - `ε ~ N(0, slip_sigma²)` drawn per wheel per step: multiplicative slip;
//! - `s`, usually 0: with probability `large_slip_probability` per step one
//!   wheel, chosen at random, slips by `s ~ U(−large_slip_max,
//!   large_slip_max)` (a bump, a wet patch, a carpet edge).
//!
//! The estimate integrates the measured increments with the same exact arc
//! kinematics as the true pose ([`crate::kinematics::integrate`]); it starts
//! at the true start pose. The wheel speeds reported in the perception are
//! the measured increments of the last control period divided by it.

use robot::Pose;

use crate::error::Result;
use crate::kinematics;
use crate::noise::RandomStream;
use crate::validate;

/// Parameters of the odometry error model (module docs).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct OdometryParams {
    /// Standard deviation of the per-step multiplicative slip of each
    /// wheel, dimensionless. Default 0.01.
    pub slip_sigma: f64,
    /// Probability, per physics step, of a large slip of one wheel.
    /// Default 0.005 (about one every 20 s at 0.1 s steps).
    pub large_slip_probability: f64,
    /// Largest relative error of a large slip, in [0, 1]. Default 0.5.
    pub large_slip_max: f64,
    /// Systematic relative error of the left wheel's encoder (wrong wheel
    /// diameter), dimensionless, > −1. Default 0.
    pub left_scale_error: f64,
    /// Systematic relative error of the right wheel's encoder. Default 0.
    pub right_scale_error: f64,
}

impl Default for OdometryParams {
    fn default() -> OdometryParams {
        OdometryParams {
            slip_sigma: 0.01,
            large_slip_probability: 0.005,
            large_slip_max: 0.5,
            left_scale_error: 0.0,
            right_scale_error: 0.0,
        }
    }
}

impl OdometryParams {
    /// Perfect odometry: no noise, no slip, no calibration error.
    pub fn perfect() -> OdometryParams {
        OdometryParams {
            slip_sigma: 0.0,
            large_slip_probability: 0.0,
            large_slip_max: 0.0,
            left_scale_error: 0.0,
            right_scale_error: 0.0,
        }
    }

    /// Checks every field.
    pub fn validate(&self) -> Result<()> {
        validate::non_negative("odometry.slip_sigma", self.slip_sigma)?;
        validate::probability("odometry.large_slip_probability", self.large_slip_probability)?;
        validate::within(
            "odometry.large_slip_max",
            self.large_slip_max,
            0.0,
            1.0,
            "in [0, 1]",
        )?;
        validate::within(
            "odometry.left_scale_error",
            self.left_scale_error,
            -0.999,
            10.0,
            "in [-0.999, 10]",
        )?;
        validate::within(
            "odometry.right_scale_error",
            self.right_scale_error,
            -0.999,
            10.0,
            "in [-0.999, 10]",
        )
    }
}

/// Wheel odometry at run time.
#[derive(Debug, Clone)]
pub struct Odometry {
    params: OdometryParams,
    estimate: Pose,
    travel_m: (f64, f64),
    speeds_mps: (f64, f64),
    rng: RandomStream,
}

impl Odometry {
    /// Odometry with these (validated) parameters, its estimate at `start`,
    /// drawing from `rng`.
    pub fn new(params: OdometryParams, start: Pose, rng: RandomStream) -> Result<Odometry> {
        params.validate()?;
        Ok(Odometry {
            params,
            estimate: start,
            travel_m: (0.0, 0.0),
            speeds_mps: (0.0, 0.0),
            rng,
        })
    }

    /// The dead-reckoned pose.
    pub fn estimate(&self) -> Pose {
        self.estimate
    }

    /// The measured wheel speeds of the last control period, m/s.
    pub fn wheel_speeds_mps(&self) -> (f64, f64) {
        self.speeds_mps
    }

    /// Measures one physics step of `dt_s` seconds in which the wheels
    /// turned at rim speeds `(left, right)` m/s, and dead-reckons it.
    pub fn step(&mut self, wheels_mps: (f64, f64), wheel_base_m: f64, dt_s: f64) {
        let p = &self.params;
        let mut l = wheels_mps.0 * dt_s * (1.0 + p.left_scale_error);
        let mut r = wheels_mps.1 * dt_s * (1.0 + p.right_scale_error);
        l *= 1.0 + self.rng.gaussian(p.slip_sigma);
        r *= 1.0 + self.rng.gaussian(p.slip_sigma);
        if self.rng.chance(p.large_slip_probability) {
            let s = self.rng.uniform_in(-p.large_slip_max, p.large_slip_max);
            if self.rng.chance(0.5) {
                l *= 1.0 + s;
            } else {
                r *= 1.0 + s;
            }
        }
        self.travel_m.0 += l;
        self.travel_m.1 += r;
        self.estimate = kinematics::integrate(self.estimate, l / dt_s, r / dt_s, wheel_base_m, dt_s);
    }

    /// Ends a control period of `period_s` seconds: the wheel speeds are the
    /// measured travel over it.
    pub fn end_period(&mut self, period_s: f64) {
        self.speeds_mps = (self.travel_m.0 / period_s, self.travel_m.1 / period_s);
        self.travel_m = (0.0, 0.0);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn perfect_odometry_follows_the_truth() {
        let start = Pose::new(1.0, 2.0, 0.5);
        let mut o = Odometry::new(OdometryParams::perfect(), start, RandomStream::new(1, 2)).unwrap();
        let mut truth = start;
        for _ in 0..100 {
            o.step((0.2, 0.3), 0.25, 0.1);
            truth = kinematics::integrate(truth, 0.2, 0.3, 0.25, 0.1);
        }
        o.end_period(0.1);
        assert!(o.estimate().position().dist(truth.position()) < 1e-12);
    }

    #[test]
    fn noisy_odometry_drifts() {
        let start = Pose::default();
        let mut errors = Vec::new();
        for seed in 0..20 {
            let mut o = Odometry::new(OdometryParams::default(), start, RandomStream::new(seed, 2)).unwrap();
            let mut truth = start;
            for _ in 0..600 {
                o.step((0.3, 0.3), 0.25, 0.1);
                truth = kinematics::integrate(truth, 0.3, 0.3, 0.25, 0.1);
            }
            errors.push(o.estimate().position().dist(truth.position()));
        }
        let mean = errors.iter().sum::<f64>() / errors.len() as f64;
        // 18 m driven: errors of some centimetres to decimetres.
        assert!(mean > 0.02 && mean < 2.0, "{mean}");
    }

    #[test]
    fn systematic_error_bends_a_straight_line() {
        let p = OdometryParams {
            right_scale_error: 0.01,
            ..OdometryParams::perfect()
        };
        let mut o = Odometry::new(p, Pose::default(), RandomStream::new(1, 2)).unwrap();
        for _ in 0..100 {
            o.step((0.3, 0.3), 0.25, 0.1);
        }
        // The right wheel seems 1 % faster: the estimate turns left.
        assert!(o.estimate().theta_rad > 0.0 && o.estimate().y_m > 0.0);
        o.end_period(1.0);
        assert!((o.wheel_speeds_mps().1 - 3.03).abs() < 1e-9);
    }
}
