//! The odometry motion model: a pose moved by a noisy copy of the
//! increment between two odometry poses.
//!
//! S. Thrun, W. Burgard, D. Fox, *Probabilistic Robotics*, MIT Press 2005,
//! §5.4, table 5.6 (`sample_motion_model_odometry`). The relative motion
//! between the odometry poses `x̄ = (x̄, ȳ, θ̄)` and `x̄' = (x̄', ȳ', θ̄')`
//! is decomposed into a rotation, a translation and a second rotation:
//!
//! ```text
//! δrot1  = atan2(ȳ' − ȳ, x̄' − x̄) − θ̄
//! δtrans = √((x̄' − x̄)² + (ȳ' − ȳ)²)
//! δrot2  = θ̄' − θ̄ − δrot1
//! ```
//!
//! and each part is perturbed by zero-mean Gaussian noise whose *variance*
//! grows with the motion (the four parameters are AMCL's `odom_alpha1..4`
//! for its `diff` model):
//!
//! ```text
//! δ̂rot1  = δrot1  − N(0, α1·δrot1² + α2·δtrans²)
//! δ̂trans = δtrans − N(0, α3·δtrans² + α4·δrot1² + α4·δrot2²)
//! δ̂rot2  = δrot2  − N(0, α1·δrot2² + α2·δtrans²)
//! ```
//!
//! - `α1` rotation from rotation (rad²/rad²),
//! - `α2` rotation from translation (rad²/m²),
//! - `α3` translation from translation (m²/m²),
//! - `α4` translation from rotation (m²/rad²).
//!
//! The particle `(x, y, θ)` then moves to
//! `(x + δ̂trans·cos(θ + δ̂rot1), y + δ̂trans·sin(θ + δ̂rot1), θ + δ̂rot1 + δ̂rot2)`.
//! With all `α = 0` this is exactly the odometry increment expressed in the
//! particle's frame.
//!
//! **Backwards motion.** When the displacement points more than 90° away
//! from the heading (the robot backed up), `δtrans` is taken *negative* and
//! `δrot1` is the bearing of the displacement minus π, so that `δrot1` stays
//! within ±π/2 and the rotation noise of a straight reverse is as small as
//! that of a straight forward motion. (The book's decomposition would give
//! `δrot1 ≈ ±π` and a large rotation noise; ROS AMCL avoids that by taking
//! `min(|δrot1|, |δrot1 − π|)` for the noise only. Both give the same
//! noiseless motion; the signed translation also puts the translation noise
//! along the heading.)
//!
//! **Pure rotation.** Below [`PURE_ROTATION_M`] of translation the bearing
//! of the displacement is meaningless (a turn on the spot with a few
//! millimetres of jitter can give any `δrot1`), so, as AMCL does, the
//! noise is computed as if `δrot1 = 0` and `δrot2` were the whole rotation.
//! The noiseless decomposition is kept exact (the tiny displacement is
//! still applied in its true direction).

use robot::{Pose, wrap_angle};

use super::gaussian::Gaussian;

/// Translations below this many metres count as a turn on the spot for the
/// noise (AMCL's threshold, `amcl_odom.cpp`).
pub const PURE_ROTATION_M: f64 = 0.01;

/// The relative motion between two odometry poses, decomposed as
/// rotation–translation–rotation (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct OdometryIncrement {
    /// First rotation, radians, in (−π/2, π/2] (or 0 without translation).
    pub rot1_rad: f64,
    /// Translation, metres; negative when the robot backed up.
    pub trans_m: f64,
    /// Second rotation, radians.
    pub rot2_rad: f64,
}

impl OdometryIncrement {
    /// The increment that takes odometry pose `from` to `to`.
    pub fn between(from: &Pose, to: &Pose) -> OdometryIncrement {
        let (dx, dy) = (to.x_m - from.x_m, to.y_m - from.y_m);
        let t = dx.hypot(dy);
        let turn = wrap_angle(to.theta_rad - from.theta_rad);
        if t == 0.0 {
            return OdometryIncrement {
                rot1_rad: 0.0,
                trans_m: 0.0,
                rot2_rad: turn,
            };
        }
        let mut rot1 = wrap_angle(dy.atan2(dx) - from.theta_rad);
        let mut trans = t;
        if rot1.abs() > std::f64::consts::FRAC_PI_2 {
            rot1 = wrap_angle(rot1 - std::f64::consts::PI);
            trans = -t;
        }
        OdometryIncrement {
            rot1_rad: rot1,
            trans_m: trans,
            rot2_rad: wrap_angle(turn - rot1),
        }
    }

    /// Length of the translation, metres.
    pub fn distance_m(&self) -> f64 {
        self.trans_m.abs()
    }

    /// Total change of heading, radians in (−π, π].
    pub fn rotation_rad(&self) -> f64 {
        wrap_angle(self.rot1_rad + self.rot2_rad)
    }

    /// `pose` moved by this increment, in `pose`'s own frame (exact).
    #[inline]
    pub fn apply(&self, pose: &Pose) -> Pose {
        let (s, c) = (pose.theta_rad + self.rot1_rad).sin_cos();
        Pose::new(
            pose.x_m + self.trans_m * c,
            pose.y_m + self.trans_m * s,
            pose.theta_rad + self.rot1_rad + self.rot2_rad,
        )
    }

    /// The rotations the noise is computed from: `(δrot1, δrot2)`, or
    /// `(0, total rotation)` for a turn on the spot (module docs).
    fn noise_rotations(&self) -> (f64, f64) {
        if self.trans_m.abs() < PURE_ROTATION_M {
            (0.0, self.rotation_rad())
        } else {
            (self.rot1_rad, self.rot2_rad)
        }
    }
}

/// The four noise parameters of the odometry motion model (module docs).
///
/// **Defaults: 0.01 each**, calibrated on the Jinny-like robot's odometry
/// (`sim::OdometryParams::default()`: 1 % slip per wheel and step, a large
/// slip of up to 50 % of a step about every 20 s). Over 2 988 increments of
/// 0.2 m driven on building_31, the heading error of the odometry increment
/// had an rms of 0.005 rad, a 99th percentile of 0.023 rad and a maximum of
/// 0.053 rad; the translation error a maximum of 0.014 m. With `α = 0.01`
/// a 0.2 m increment gets a rotation noise of 0.02 rad and a translation
/// noise of 0.02 m (standard deviations), which covers the worst slip at
/// 2.6 σ. ROS AMCL's generic default, 0.2 (0.09 rad and 0.09 m per 0.2 m),
/// spreads the particles so much that the sum-of-cubes weights cannot
/// gather them again: 0.091 m median and 0.28 m maximum error on
/// building_31, 0.60 m maximum on levine (see [`super`]). Calibrate them
/// for another robot.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct OdometryMotionModel {
    /// `α1`: rotation noise from rotation, rad²/rad², ≥ 0. Default 0.01.
    pub alpha1: f64,
    /// `α2`: rotation noise from translation, rad²/m², ≥ 0. Default 0.01.
    pub alpha2: f64,
    /// `α3`: translation noise from translation, m²/m², ≥ 0. Default 0.01.
    pub alpha3: f64,
    /// `α4`: translation noise from rotation, m²/rad², ≥ 0. Default 0.01.
    pub alpha4: f64,
}

impl Default for OdometryMotionModel {
    fn default() -> OdometryMotionModel {
        OdometryMotionModel {
            alpha1: 0.01,
            alpha2: 0.01,
            alpha3: 0.01,
            alpha4: 0.01,
        }
    }
}

impl OdometryMotionModel {
    /// ROS AMCL's defaults (`odom_alpha1..4 = 0.2`).
    pub fn amcl() -> OdometryMotionModel {
        OdometryMotionModel {
            alpha1: 0.2,
            alpha2: 0.2,
            alpha3: 0.2,
            alpha4: 0.2,
        }
    }
}

impl OdometryMotionModel {
    /// A noiseless model (every `α` zero).
    pub fn exact() -> OdometryMotionModel {
        OdometryMotionModel {
            alpha1: 0.0,
            alpha2: 0.0,
            alpha3: 0.0,
            alpha4: 0.0,
        }
    }

    /// Standard deviations of the noise on `(δrot1, δtrans, δrot2)` for this
    /// increment: radians, metres, radians.
    pub fn std_devs(&self, inc: &OdometryIncrement) -> [f64; 3] {
        let (r1, r2) = inc.noise_rotations();
        let t2 = inc.trans_m * inc.trans_m;
        [
            (self.alpha1 * r1 * r1 + self.alpha2 * t2).sqrt(),
            (self.alpha3 * t2 + self.alpha4 * (r1 * r1 + r2 * r2)).sqrt(),
            (self.alpha1 * r2 * r2 + self.alpha2 * t2).sqrt(),
        ]
    }

    /// A noisy copy `(δ̂rot1, δ̂trans, δ̂rot2)` of `inc` whose noise has the
    /// standard deviations `std` (from [`OdometryMotionModel::std_devs`]).
    #[inline]
    pub fn perturb(inc: &OdometryIncrement, std: &[f64; 3], g: &mut Gaussian) -> OdometryIncrement {
        OdometryIncrement {
            rot1_rad: inc.rot1_rad - g.gaussian(std[0]),
            trans_m: inc.trans_m - g.gaussian(std[1]),
            rot2_rad: inc.rot2_rad - g.gaussian(std[2]),
        }
    }

    /// One draw of the pose after `inc` from `pose`
    /// (`sample_motion_model_odometry`).
    pub fn sample(&self, inc: &OdometryIncrement, pose: &Pose, g: &mut Gaussian) -> Pose {
        let std = self.std_devs(inc);
        OdometryMotionModel::perturb(inc, &std, g).apply(pose)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;
    use std::f64::consts::PI;

    fn close(a: &Pose, b: &Pose) -> bool {
        (a.x_m - b.x_m).abs() < 1e-12
            && (a.y_m - b.y_m).abs() < 1e-12
            && wrap_angle(a.theta_rad - b.theta_rad).abs() < 1e-12
    }

    /// The increment of `from → to` applied to `p` equals `p ∘ (from⁻¹ ∘ to)`.
    fn expected(p: &Pose, from: &Pose, to: &Pose) -> Pose {
        let local = from.inverse_transform(to.position());
        p.compose(&Pose::new(local.x, local.y, to.theta_rad - from.theta_rad))
    }

    #[test]
    fn zero_noise_moves_exactly_by_the_increment() {
        let mut g = Gaussian::new(ChaCha8Rng::seed_from_u64(1));
        let model = OdometryMotionModel::exact();
        let from = Pose::new(1.0, -2.0, 0.4);
        let cases = [
            // forward, forward with a turn, turn on the spot, backwards,
            // backwards while turning, a sideways jitter of a millimetre.
            from.compose(&Pose::new(0.3, 0.0, 0.0)),
            from.compose(&Pose::new(0.25, 0.05, 0.3)),
            from.compose(&Pose::new(0.0, 0.0, -2.5)),
            from.compose(&Pose::new(-0.3, 0.0, 0.0)),
            from.compose(&Pose::new(-0.2, -0.04, 0.8)),
            from.compose(&Pose::new(0.0, 0.001, PI)),
        ];
        let particle = Pose::new(-7.0, 3.5, -2.9);
        for to in cases {
            let inc = OdometryIncrement::between(&from, &to);
            assert!(close(&inc.apply(&from), &to), "{inc:?}");
            let moved = model.sample(&inc, &particle, &mut g);
            assert!(close(&moved, &expected(&particle, &from, &to)), "{inc:?}");
        }
    }

    #[test]
    fn backwards_and_turns_decompose_sensibly() {
        let from = Pose::new(0.0, 0.0, 0.0);
        let back = OdometryIncrement::between(&from, &Pose::new(-0.5, 0.0, 0.0));
        assert_eq!(back.trans_m, -0.5);
        assert!(back.rot1_rad.abs() < 1e-15 && back.rot2_rad.abs() < 1e-15);
        let spin = OdometryIncrement::between(&from, &Pose::new(0.0, 0.0, 1.0));
        assert_eq!((spin.rot1_rad, spin.trans_m, spin.rot2_rad), (0.0, 0.0, 1.0));
        // Backing up straight has the same noise as driving forward.
        let m = OdometryMotionModel::amcl();
        let fwd = OdometryIncrement::between(&from, &Pose::new(0.5, 0.0, 0.0));
        assert_eq!(m.std_devs(&back), m.std_devs(&fwd));
        // A few millimetres of jitter in a turn on the spot add no
        // rotation noise from a spurious bearing.
        let jitter = OdometryIncrement::between(&from, &Pose::new(0.0, 0.003, 0.5));
        assert!(jitter.rot1_rad > 1.0);
        let s = m.std_devs(&jitter);
        let want = (0.2 * 0.5 * 0.5 + 0.2 * 0.003 * 0.003_f64).sqrt();
        assert!((s[2] - want).abs() < 1e-12 && s[0] < 0.002, "{s:?}");
    }

    #[test]
    fn sampled_increments_have_the_alpha_moments() {
        let model = OdometryMotionModel {
            alpha1: 0.1,
            alpha2: 0.05,
            alpha3: 0.02,
            alpha4: 0.01,
        };
        let inc = OdometryIncrement {
            rot1_rad: 0.3,
            trans_m: 0.5,
            rot2_rad: -0.2,
        };
        let std = model.std_devs(&inc);
        let want_var = [
            0.1 * 0.09 + 0.05 * 0.25,
            0.02 * 0.25 + 0.01 * (0.09 + 0.04),
            0.1 * 0.04 + 0.05 * 0.25,
        ];
        for k in 0..3 {
            assert!((std[k] * std[k] - want_var[k]).abs() < 1e-15);
        }
        let mut g = Gaussian::new(ChaCha8Rng::seed_from_u64(42));
        let n = 100_000;
        let mut sum = [0.0; 3];
        let mut sum2 = [0.0; 3];
        for _ in 0..n {
            let s = OdometryMotionModel::perturb(&inc, &std, &mut g);
            let v = [s.rot1_rad, s.trans_m, s.rot2_rad];
            for k in 0..3 {
                sum[k] += v[k];
                sum2[k] += v[k] * v[k];
            }
        }
        let truth = [0.3, 0.5, -0.2];
        for k in 0..3 {
            let mean = sum[k] / n as f64;
            let var = sum2[k] / n as f64 - mean * mean;
            // Standard error of the mean: σ/√n; of the variance: σ²·√(2/n).
            let se_mean = (want_var[k] / n as f64).sqrt();
            assert!((mean - truth[k]).abs() < 4.0 * se_mean, "part {k}: mean {mean}");
            let se_var = want_var[k] * (2.0 / n as f64).sqrt();
            assert!(
                (var - want_var[k]).abs() < 4.0 * se_var,
                "part {k}: var {var} vs {}",
                want_var[k]
            );
        }
    }

    #[test]
    fn sampled_poses_spread_as_the_linearised_model_predicts() {
        // Straight ahead 1 m: the lateral spread comes from δrot1 (variance
        // α2·1), the longitudinal one from δtrans (α3·1).
        let model = OdometryMotionModel {
            alpha1: 0.0,
            alpha2: 0.0004,
            alpha3: 0.0009,
            alpha4: 0.0,
        };
        let inc = OdometryIncrement::between(&Pose::default(), &Pose::new(1.0, 0.0, 0.0));
        let mut g = Gaussian::new(ChaCha8Rng::seed_from_u64(7));
        let n = 50_000;
        let (mut sx, mut sx2, mut sy2) = (0.0, 0.0, 0.0);
        for _ in 0..n {
            let p = model.sample(&inc, &Pose::default(), &mut g);
            sx += p.x_m;
            sx2 += p.x_m * p.x_m;
            sy2 += p.y_m * p.y_m;
        }
        let mx = sx / n as f64;
        let vx = sx2 / n as f64 - mx * mx;
        let vy = sy2 / n as f64;
        assert!((mx - 1.0).abs() < 0.001, "{mx}");
        assert!((vx / 0.0009 - 1.0).abs() < 0.05, "{vx}");
        assert!((vy / 0.0004 - 1.0).abs() < 0.05, "{vy}");
    }
}
