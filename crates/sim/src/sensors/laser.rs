//! Laser range finder: N beams over a field of view, each an exact ray.
//!
//! Per read: the people are culled per beam by their angular interval (a
//! person at distance `d` covers bearings within `asin(r/d)` of its centre,
//! so only those beams get the ray–disc test: `O(people + covered beams)`),
//! then each beam is cast on the grid only up to the nearest person it hit
//! (people in front shorten the grid traversal). Beam directions in the
//! sensor frame are precomputed; nothing is allocated per read.
//!
//! Noise: each beam independently drops out with `dropout_probability`
//! (reported as `NaN`); otherwise a hit gets Gaussian noise of
//! `range_sigma_m` and is clamped to `[0, max_range_m]`. Nothing within
//! range reads `f64::INFINITY` (as [`robot::LaserScan`] documents).

use std::f64::consts::TAU;

use robot::{LaserScan, Pose, Vec2};

use super::{Scene, Schedule, into_frame, validate_period};
use crate::error::Result;
use crate::fast_math::{mounted, norm};
use crate::noise::RandomStream;
use crate::ray_disc::ray_disc;
use crate::validate;

/// Parameters of a laser range finder.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LaserParams {
    /// Pose of the sensor on the robot (robot frame). Default: the centre,
    /// facing forwards.
    pub mount: Pose,
    /// Number of beams, 1 to 100 000. Default 181.
    pub beams: usize,
    /// Field of view, radians, centred on the sensor's axis, in (0, 2π]:
    /// beams from `−fov/2` to `+fov/2` inclusive (a full circle spaces them
    /// `2π/beams` apart, without repeating the first). Default π (180°).
    pub fov_rad: f64,
    /// Maximum range, metres. Default 30.
    pub max_range_m: f64,
    /// Standard deviation of the Gaussian range noise, metres. Default 0.01.
    pub range_sigma_m: f64,
    /// Probability that a beam returns nothing (`NaN`). Default 0.001.
    pub dropout_probability: f64,
    /// Read period, seconds (`None`: every control tick). Default `None`.
    pub period_s: Option<f64>,
}

impl Default for LaserParams {
    fn default() -> LaserParams {
        LaserParams {
            mount: Pose::default(),
            beams: 181,
            fov_rad: std::f64::consts::PI,
            max_range_m: 30.0,
            range_sigma_m: 0.01,
            dropout_probability: 0.001,
            period_s: None,
        }
    }
}

impl LaserParams {
    /// Checks every field.
    pub fn validate(&self) -> Result<()> {
        validate::pose("laser.mount", &self.mount)?;
        validate::count_within("laser.beams", self.beams, 1, 100_000, "between 1 and 100 000")?;
        validate::within(
            "laser.fov_rad",
            self.fov_rad,
            f64::MIN_POSITIVE,
            TAU,
            "in (0, 2π]",
        )?;
        validate::positive("laser.max_range_m", self.max_range_m)?;
        validate::non_negative("laser.range_sigma_m", self.range_sigma_m)?;
        validate::probability("laser.dropout_probability", self.dropout_probability)?;
        validate_period("laser.period_s", self.period_s)
    }

    /// Angle of the first beam and between beams, radians (sensor frame).
    pub fn angles_rad(&self) -> (f64, f64) {
        let n = self.beams.max(1);
        let full = self.fov_rad >= TAU - 1e-9;
        let inc = if n == 1 {
            0.0
        } else if full {
            self.fov_rad / n as f64
        } else {
            self.fov_rad / (n - 1) as f64
        };
        let min = if n == 1 { 0.0 } else { -self.fov_rad / 2.0 };
        (min, inc)
    }
}

/// A laser range finder at run time.
#[derive(Debug, Clone)]
pub struct Laser {
    params: LaserParams,
    angle_min_rad: f64,
    increment_rad: f64,
    /// Beam directions in the sensor frame.
    dirs: Vec<Vec2>,
    /// Per beam, the nearest person hit (or the maximum range).
    near: Vec<f64>,
    rng: RandomStream,
    schedule: Schedule,
}

impl Laser {
    /// A laser with these (validated) parameters drawing from `rng`.
    pub fn new(params: LaserParams, rng: RandomStream) -> Result<Laser> {
        params.validate()?;
        let (angle_min_rad, increment_rad) = params.angles_rad();
        let dirs = (0..params.beams)
            .map(|k| {
                let a = angle_min_rad + k as f64 * increment_rad;
                Vec2::new(a.cos(), a.sin())
            })
            .collect();
        Ok(Laser {
            near: vec![0.0; params.beams],
            schedule: Schedule::new(params.period_s),
            params,
            angle_min_rad,
            increment_rad,
            dirs,
            rng,
        })
    }

    /// The parameters.
    pub fn params(&self) -> &LaserParams {
        &self.params
    }

    /// A scan buffer of the right shape (all ranges `INFINITY`).
    pub fn empty_scan(&self) -> LaserScan {
        LaserScan {
            mount: self.params.mount,
            angle_min_rad: self.angle_min_rad,
            angle_increment_rad: self.increment_rad,
            range_max_m: self.params.max_range_m,
            ranges_m: vec![f64::INFINITY; self.params.beams],
        }
    }

    /// Reads the scene from the robot at `robot` into `scan` (a buffer from
    /// [`Laser::empty_scan`]) if the sensor is due at `time_s`; returns
    /// whether it read.
    pub fn read(&mut self, scene: &Scene, robot: &Pose, time_s: f64, scan: &mut LaserScan) -> bool {
        if !self.schedule.due(time_s) {
            return false;
        }
        let (rsin, rcos) = robot.theta_rad.sin_cos();
        let (origin, heading) = mounted(robot, rsin, rcos, &self.params.mount);
        let max = self.params.max_range_m;
        let n = self.params.beams;
        // A buffer of the wrong length is fixed (allocates only then).
        scan.ranges_m.resize(n, f64::INFINITY);
        self.near.iter_mut().for_each(|x| *x = max);
        let r = scene.person_radius_m;
        let (sin, cos) = heading.sin_cos();
        for person in scene.people {
            let rel = into_frame(person.position, origin, sin, cos);
            let d = norm(rel);
            if d - r >= max {
                continue;
            }
            if d <= r {
                self.near.iter_mut().for_each(|x| *x = 0.0);
                continue;
            }
            if n == 1 {
                if let Some(t) = ray_disc(rel, self.dirs[0], r) {
                    self.near[0] = self.near[0].min(t);
                }
                continue;
            }
            let bearing = rel.y.atan2(rel.x) - self.angle_min_rad;
            let half = (r / d).asin() + 1e-12;
            let last = (n - 1) as f64;
            for shift in [-TAU, 0.0, TAU] {
                let lo = ((bearing - half + shift) / self.increment_rad).ceil().max(0.0);
                let hi = ((bearing + half + shift) / self.increment_rad).floor().min(last);
                if lo > hi {
                    continue;
                }
                for k in lo as usize..=hi as usize {
                    if let Some(t) = ray_disc(rel, self.dirs[k], r) {
                        self.near[k] = self.near[k].min(t);
                    }
                }
            }
        }
        let sigma = self.params.range_sigma_m;
        let dropout = self.params.dropout_probability;
        let heading0 = heading + self.angle_min_rad;
        let skip = scene.free_radius_m(origin);
        for k in 0..n {
            let limit = self.near[k];
            let d = self.dirs[k];
            let dir = Vec2::new(cos * d.x - sin * d.y, sin * d.x + cos * d.y);
            let hit = scene.cast(origin, dir, heading0 + k as f64 * self.increment_rad, skip, limit);
            let found = hit.is_some() || limit < max;
            let range = hit.map_or(limit, |t| t.min(limit));
            scan.ranges_m[k] = if self.rng.chance(dropout) {
                f64::NAN
            } else if !found {
                f64::INFINITY
            } else {
                (range + self.rng.gaussian(sigma)).clamp(0.0, max)
            };
        }
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::distance_field::DistanceField;
    use crate::grid::{Cell, CellIndex, OccupancyGrid};
    use crate::people::{Activity, Person};
    use crate::raycast;

    fn person(x: f64, y: f64) -> Person {
        Person {
            position: Vec2::new(x, y),
            velocity: Vec2::default(),
            preferred_speed_mps: 1.0,
            target: Vec2::new(x, y),
            activity: Activity::Lingering { until_s: 1e9 },
            waypoint: None,
            asked: None,
            curious_until_s: None,
        }
    }

    fn noiseless(beams: usize, fov: f64) -> LaserParams {
        LaserParams {
            beams,
            fov_rad: fov,
            max_range_m: 8.0,
            range_sigma_m: 0.0,
            dropout_probability: 0.0,
            ..LaserParams::default()
        }
    }

    /// The naive reading: every beam against the grid and every person.
    fn naive(scene: &Scene, p: &LaserParams, robot: &Pose) -> Vec<f64> {
        let o = robot.compose(&p.mount);
        let (min, inc) = p.angles_rad();
        (0..p.beams)
            .map(|k| {
                let a = o.theta_rad + min + k as f64 * inc;
                let dir = Vec2::new(a.cos(), a.sin());
                let mut best =
                    raycast::cast(scene.grid, o.position(), a, p.max_range_m).unwrap_or(f64::INFINITY);
                for q in scene.people {
                    if let Some(t) = ray_disc(q.position - o.position(), dir, scene.person_radius_m) {
                        best = best.min(t);
                    }
                }
                if best > p.max_range_m { f64::INFINITY } else { best }
            })
            .collect()
    }

    #[test]
    fn culled_scan_equals_the_naive_one() {
        let mut g = OccupancyGrid::new(200, 200, 0.05, Pose::default());
        for k in 0..200 {
            g.set(CellIndex { i: k, j: 150 }, Cell::Occupied);
            g.set(CellIndex { i: 30, j: k }, Cell::Occupied);
        }
        let mut rng = RandomStream::new(4, 0);
        let people: Vec<Person> = (0..40)
            .map(|_| person(rng.uniform_in(0.0, 10.0), rng.uniform_in(0.0, 10.0)))
            .collect();
        let field = DistanceField::new(&g);
        let scene = Scene {
            grid: &g,
            field: Some(&field),
            people: &people,
            person_radius_m: 0.25,
        };
        for (beams, fov) in [(181, std::f64::consts::PI), (360, TAU), (1, 1.0), (61, 4.0)] {
            let p = noiseless(beams, fov);
            let mut laser = Laser::new(p.clone(), RandomStream::new(1, 2)).unwrap();
            let mut scan = laser.empty_scan();
            for robot in [
                Pose::new(5.0, 5.0, 0.3),
                Pose::new(2.0, 6.5, -2.9),
                Pose::new(8.0, 2.0, 3.1),
            ] {
                assert!(laser.read(&scene, &robot, 0.0, &mut scan));
                let want = naive(&scene, &p, &robot);
                for (k, (&a, &b)) in scan.ranges_m.iter().zip(&want).enumerate() {
                    assert!(a == b || (a - b).abs() < 1e-9, "beams {beams} k {k}: {a} vs {b}");
                }
            }
        }
    }

    #[test]
    fn noise_and_dropouts() {
        let g = OccupancyGrid::new(100, 100, 0.05, Pose::default());
        let scene = Scene::static_only(&g);
        let p = LaserParams {
            range_sigma_m: 0.05,
            dropout_probability: 0.1,
            ..LaserParams::default()
        };
        let mut laser = Laser::new(p, RandomStream::new(3, 16)).unwrap();
        let mut scan = laser.empty_scan();
        let mut drops = 0;
        let mut err2 = 0.0;
        let mut hits = 0;
        for t in 0..50 {
            laser.read(&scene, &Pose::new(2.5, 2.5, 0.0), t as f64 * 0.1, &mut scan);
            // Straight ahead, the map's edge at 2.5 m.
            let x = scan.ranges_m[90];
            if x.is_nan() {
                drops += 1;
            } else {
                err2 += (x - 2.5) * (x - 2.5);
                hits += 1;
            }
        }
        assert!((1..=15).contains(&drops), "{drops}");
        let sd = (err2 / hits as f64).sqrt();
        assert!(sd > 0.02 && sd < 0.1, "{sd}");
    }

    #[test]
    fn a_read_rate_skips_ticks() {
        let g = OccupancyGrid::new(10, 10, 0.1, Pose::default());
        let p = LaserParams {
            period_s: Some(0.2),
            ..LaserParams::default()
        };
        let mut laser = Laser::new(p, RandomStream::new(3, 16)).unwrap();
        let mut scan = laser.empty_scan();
        let scene = Scene::static_only(&g);
        let reads: Vec<bool> = (0..4)
            .map(|k| laser.read(&scene, &Pose::new(0.5, 0.5, 0.0), k as f64 * 0.1, &mut scan))
            .collect();
        assert_eq!(reads, vec![true, false, true, false]);
        let bad = LaserParams {
            beams: 0,
            ..LaserParams::default()
        };
        assert!(matches!(
            Laser::new(bad, RandomStream::new(1, 1)),
            Err(crate::Error::InvalidValue { .. })
        ));
    }
}
