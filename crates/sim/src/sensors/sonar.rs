//! Sonar: a few transducers, each returning the nearest echo inside its cone.
//!
//! **Model.** A transducer reports the distance to the nearest obstacle
//! point inside its cone (the first echo), within `[min_range_m,
//! max_range_m]`:
//!
//! - people (discs) are found *analytically*: the exact nearest point of
//!   each disc inside the cone ([`crate::ray_disc::cone_disc`]);
//! - the grid is sampled by a fan of `rays_per_cone` exact rays spread
//!   evenly from one edge of the cone to the other. With the default 9 rays
//!   over 25° (3.1° apart) neighbouring rays are less than one 5 cm cell
//!   apart up to 0.9 m, and 11 cm apart at 2 m, so what matters for
//!   obstacle avoidance — walls, boxes, table legs within a couple of
//!   metres — is always seen, while a thin pole far away may slip between
//!   rays as it would fail to echo on a real transducer. Rays after the
//!   first stop at the nearest echo found so far (exact: the answer is the
//!   minimum anyway), so the fan costs little more than one ray.
//!
//! Echoes nearer than `min_range_m` (inside the transducer's ring-down
//! time) read as `min_range_m`: the controller learns that something is
//! very close. **Decision:** real Polaroid-type sonar may instead miss
//! them; reading the minimum is the safer model for obstacle avoidance and
//! matches the voting behaviour's `D_obs ≤ D_min` case. Noise: Gaussian of
//! `range_sigma_m`, clamped to the range interval; with
//! `dropout_probability` an echo is lost (`f64::INFINITY`, as when nothing
//! is within range — specular reflection away from the transducer).
//! Specular reflection itself is not modelled.

use robot::{Pose, SonarReading, Vec2};

use super::{Scene, Schedule, into_frame, rim_mounts, spread_angles, validate_mounts, validate_period};
use crate::error::Result;
use crate::fast_math::{mounted, norm};
use crate::noise::RandomStream;
use crate::ray_disc::cone_disc;
use crate::validate;

/// Parameters of a sonar array (all transducers alike).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SonarParams {
    /// One pose per transducer on the robot (robot frame; the cone's axis is
    /// the mount's x axis). Default: three at −30°, 0°, +30° on the rim of
    /// an AIBOT-sized robot (radius 0.15 m).
    pub mounts: Vec<Pose>,
    /// Full cone width, radians, in (0, π). Default 25°.
    pub cone_rad: f64,
    /// Rays sampling the grid across the cone (module docs), 1 to 10 000.
    /// Default 9.
    pub rays_per_cone: usize,
    /// Minimum range, metres. Default 0.15.
    pub min_range_m: f64,
    /// Maximum range, metres. Default 10.7.
    pub max_range_m: f64,
    /// Standard deviation of the Gaussian range noise, metres. Default 0.02.
    pub range_sigma_m: f64,
    /// Probability that an echo is lost. Default 0.
    pub dropout_probability: f64,
    /// Read period, seconds (`None`: every control tick). Default `None`.
    pub period_s: Option<f64>,
}

impl Default for SonarParams {
    fn default() -> SonarParams {
        SonarParams {
            mounts: rim_mounts(&spread_angles(3, 60f64.to_radians()), 0.15),
            cone_rad: 25f64.to_radians(),
            rays_per_cone: 9,
            min_range_m: 0.15,
            max_range_m: 10.7,
            range_sigma_m: 0.02,
            dropout_probability: 0.0,
            period_s: None,
        }
    }
}

impl SonarParams {
    /// No transducers.
    pub fn none() -> SonarParams {
        SonarParams {
            mounts: Vec::new(),
            ..SonarParams::default()
        }
    }

    /// Checks every field.
    pub fn validate(&self) -> Result<()> {
        validate_mounts("sonar.mounts", &self.mounts)?;
        validate::within(
            "sonar.cone_rad",
            self.cone_rad,
            f64::MIN_POSITIVE,
            std::f64::consts::PI - 1e-9,
            "in (0, π)",
        )?;
        validate::count_within(
            "sonar.rays_per_cone",
            self.rays_per_cone,
            1,
            10_000,
            "between 1 and 10 000",
        )?;
        validate::non_negative("sonar.min_range_m", self.min_range_m)?;
        validate::positive("sonar.max_range_m", self.max_range_m)?;
        if self.min_range_m >= self.max_range_m {
            return Err(crate::Error::InvalidValue {
                what: "sonar.min_range_m".to_string(),
                requirement: "below sonar.max_range_m",
                value: self.min_range_m,
            });
        }
        validate::non_negative("sonar.range_sigma_m", self.range_sigma_m)?;
        validate::probability("sonar.dropout_probability", self.dropout_probability)?;
        validate_period("sonar.period_s", self.period_s)
    }
}

/// A sonar array at run time.
#[derive(Debug, Clone)]
pub struct Sonar {
    params: SonarParams,
    /// Ray angles relative to the cone's axis.
    rays: Vec<f64>,
    /// Their sines and cosines.
    rays_sin_cos: Vec<(f64, f64)>,
    /// Per transducer, the ray that found the last echo.
    first_ray: Vec<usize>,
    rng: RandomStream,
    schedule: Schedule,
}

impl Sonar {
    /// A sonar array with these (validated) parameters drawing from `rng`.
    pub fn new(params: SonarParams, rng: RandomStream) -> Result<Sonar> {
        params.validate()?;
        let rays = spread_angles(params.rays_per_cone, params.cone_rad);
        Ok(Sonar {
            rays_sin_cos: rays.iter().map(|a| a.sin_cos()).collect(),
            first_ray: vec![params.rays_per_cone / 2; params.mounts.len()],
            rays,
            schedule: Schedule::new(params.period_s),
            params,
            rng,
        })
    }

    /// The parameters.
    pub fn params(&self) -> &SonarParams {
        &self.params
    }

    /// Reading buffers, one per transducer (ranges `INFINITY`).
    pub fn empty_readings(&self) -> Vec<SonarReading> {
        self.params
            .mounts
            .iter()
            .map(|m| SonarReading {
                mount: *m,
                cone_rad: self.params.cone_rad,
                range_m: f64::INFINITY,
            })
            .collect()
    }

    /// The nearest echo inside the cone of transducer `k` at `origin`,
    /// heading `heading` (world frame), before noise, if any within the
    /// maximum range. The ray that found the last echo is cast first: the
    /// robot moves little between reads, so it usually bounds the others
    /// at once (the answer, a minimum, does not depend on the order).
    fn nearest(&mut self, scene: &Scene, k: usize, origin: Vec2, heading: f64) -> Option<f64> {
        let mut best = self.params.max_range_m;
        let mut found = false;
        let half = 0.5 * self.params.cone_rad;
        let r = scene.person_radius_m;
        let (sin, cos) = heading.sin_cos();
        for person in scene.people {
            let rel = into_frame(person.position, origin, sin, cos);
            if norm(rel) - r >= best {
                continue;
            }
            if let Some(t) = cone_disc(rel, half, r) {
                if t <= best {
                    best = t;
                    found = true;
                }
            }
        }
        let skip = scene.free_radius_m(origin);
        let first = self.first_ray[k];
        let n = self.rays.len();
        for m in 0..n {
            // `first`, then the others in order.
            let j = match m {
                0 => first,
                m if m <= first => m - 1,
                m => m,
            };
            let (s, c) = self.rays_sin_cos[j];
            let dir = Vec2::new(cos * c - sin * s, sin * c + cos * s);
            if let Some(t) = scene.cast(origin, dir, heading + self.rays[j], skip, best) {
                if !found || t < best {
                    self.first_ray[k] = j;
                }
                best = best.min(t);
                found = true;
            }
        }
        found.then_some(best)
    }

    /// Reads every transducer into `out` (from [`Sonar::empty_readings`];
    /// entry `k` for mount `k`, extra entries left alone) if the array is
    /// due at `time_s`; returns whether it read.
    pub fn read(&mut self, scene: &Scene, robot: &Pose, time_s: f64, out: &mut [SonarReading]) -> bool {
        if !self.schedule.due(time_s) {
            return false;
        }
        let (lo, hi) = (self.params.min_range_m, self.params.max_range_m);
        let (sin, cos) = robot.theta_rad.sin_cos();
        for (k, reading) in out.iter_mut().enumerate().take(self.params.mounts.len()) {
            let (origin, heading) = mounted(robot, sin, cos, &self.params.mounts[k]);
            let echo = self.nearest(scene, k, origin, heading);
            reading.range_m = match echo {
                _ if self.rng.chance(self.params.dropout_probability) => f64::INFINITY,
                None => f64::INFINITY,
                Some(d) => (d.max(lo) + self.rng.gaussian(self.params.range_sigma_m)).clamp(lo, hi),
            };
        }
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::{Cell, CellIndex, OccupancyGrid};

    fn noiseless() -> SonarParams {
        SonarParams {
            range_sigma_m: 0.0,
            ..SonarParams::default()
        }
    }

    #[test]
    fn sees_the_nearest_echo_in_the_cone() {
        // A wall 2 m ahead of the robot's centre; a block just inside the
        // left edge of the middle cone at 1 m.
        let mut g = OccupancyGrid::new(200, 200, 0.05, Pose::default());
        for j in 0..200 {
            g.set(CellIndex { i: 140, j }, Cell::Occupied);
        }
        let scene = Scene::static_only(&g);
        let p = noiseless();
        let mut s = Sonar::new(p.clone(), RandomStream::new(1, 4)).unwrap();
        let mut out = s.empty_readings();
        let robot = Pose::new(5.0, 5.0, 0.0);
        s.read(&scene, &robot, 0.0, &mut out);
        // Middle transducer at x = 5.15: the wall's face is at x = 7.0.
        assert!((out[1].range_m - 1.85).abs() < 1e-9, "{}", out[1].range_m);
        // Side transducers see the wall along their inner cone edge.
        let side = (2.0 - 0.15 * 30f64.to_radians().cos()) / 17.5f64.to_radians().cos();
        assert!(
            (out[0].range_m - side).abs() < 1e-9,
            "{} vs {side}",
            out[0].range_m
        );
        assert!((out[2].range_m - side).abs() < 1e-9);
        let mut g2 = g.clone();
        // A one-cell obstacle at bearing +10° from the middle transducer, 1 m away.
        let a = 10f64.to_radians();
        let c = g2.cell_of(Vec2::new(5.15 + a.cos(), 5.0 + a.sin()));
        g2.set(c, Cell::Occupied);
        let scene2 = Scene::static_only(&g2);
        s.read(&scene2, &robot, 0.1, &mut out);
        assert!(out[1].range_m < 1.0, "{}", out[1].range_m);
    }

    #[test]
    fn close_echoes_read_the_minimum_and_far_ones_infinity() {
        let mut g = OccupancyGrid::new(600, 600, 0.05, Pose::default());
        g.set(CellIndex { i: 104, j: 100 }, Cell::Occupied);
        let scene = Scene::static_only(&g);
        let mut s = Sonar::new(noiseless(), RandomStream::new(1, 4)).unwrap();
        let mut out = s.empty_readings();
        // Middle transducer at x = 5.05 + 0.15 = 5.2: the cell starts at 5.2.
        s.read(&scene, &Pose::new(5.05, 5.025, 0.0), 0.0, &mut out);
        assert_eq!(out[1].range_m, 0.15);
        // Facing away from everything within 10.7 m (the map is 30 m wide).
        s.read(
            &scene,
            &Pose::new(5.0, 10.0, std::f64::consts::FRAC_PI_2),
            0.1,
            &mut out,
        );
        assert_eq!(out[1].range_m, f64::INFINITY);
    }

    #[test]
    fn the_distance_field_shortcut_changes_nothing() {
        let mut rng = RandomStream::new(8, 0);
        let mut g = OccupancyGrid::new(120, 120, 0.05, Pose::new(0.3, -0.2, 0.4));
        for _ in 0..60 {
            let c = CellIndex {
                i: rng.index(120) as i64,
                j: rng.index(120) as i64,
            };
            g.set(c, Cell::Occupied);
        }
        let field = crate::distance_field::DistanceField::new(&g);
        let plain = Scene::static_only(&g);
        let fast = Scene {
            field: Some(&field),
            ..plain
        };
        let mut a = Sonar::new(noiseless(), RandomStream::new(1, 4)).unwrap();
        let mut b = Sonar::new(noiseless(), RandomStream::new(1, 4)).unwrap();
        let mut ir_a =
            crate::sensors::Ir::new(crate::sensors::IrParams::default(), RandomStream::new(1, 3)).unwrap();
        let mut ir_b = ir_a.clone();
        let (mut out_a, mut out_b) = (a.empty_readings(), b.empty_readings());
        let (mut ir_out_a, mut ir_out_b) = (ir_a.empty_readings(), ir_b.empty_readings());
        for t in 0..300 {
            let robot = g.to_world(robot::Vec2::new(
                rng.uniform_in(0.3, 5.7),
                rng.uniform_in(0.3, 5.7),
            ));
            let robot = Pose::new(robot.x, robot.y, rng.uniform_in(-3.0, 3.0));
            let time = t as f64 * 0.1;
            a.read(&plain, &robot, time, &mut out_a);
            b.read(&fast, &robot, time, &mut out_b);
            for (x, y) in out_a.iter().zip(&out_b) {
                assert!(
                    x.range_m == y.range_m || (x.range_m - y.range_m).abs() < 1e-9,
                    "{x:?} vs {y:?}"
                );
            }
            ir_a.read(&plain, &robot, time, &mut ir_out_a);
            ir_b.read(&fast, &robot, time, &mut ir_out_b);
            assert_eq!(ir_out_a, ir_out_b);
        }
    }

    #[test]
    fn bad_parameters_are_rejected() {
        for p in [
            SonarParams {
                cone_rad: 0.0,
                ..SonarParams::default()
            },
            SonarParams {
                min_range_m: 11.0,
                ..SonarParams::default()
            },
            SonarParams {
                rays_per_cone: 0,
                ..SonarParams::default()
            },
        ] {
            assert!(matches!(
                Sonar::new(p, RandomStream::new(1, 1)),
                Err(crate::Error::InvalidValue { .. })
            ));
        }
    }
}
