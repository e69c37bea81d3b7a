//! Infrared proximity detectors: binary, short range, one narrow beam each.
//!
//! **Model.** Each detector is a single ray along its mount's axis: it
//! triggers when a blocked cell or a person lies on that ray within the
//! detection range. Nothing between two detectors' rays is seen — an
//! obstacle edge that slips between beams is missed, the weakness the
//! voting experiments probe. A detector's beam has a width
//! (`beam_rad`): real IR proximity detectors (an LED and a photodiode
//! behind small lenses) see within a cone of a few degrees either side of
//! their axis, sampled here by three rays (axis and both edges); with
//! `beam_rad = 0` a detector is a single ray. Noise: the detection range varies per reading
//! by a Gaussian of `range_sigma_m` (surface reflectivity, ambient light),
//! so an obstacle near the limit flickers.

use robot::{IrReading, Pose, Vec2};

use super::{Scene, Schedule, into_frame, rim_mounts, spread_angles, validate_mounts, validate_period};
use crate::error::Result;
use crate::fast_math::{mounted, norm};
use crate::noise::RandomStream;
use crate::ray_disc::ray_disc;
use crate::validate;

/// Parameters of an array of infrared detectors (all alike).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct IrParams {
    /// One pose per detector on the robot (robot frame; the beam is the
    /// mount's x axis). Default: seven across the front arc, −90° to +90°
    /// every 30°, on the rim of an AIBOT-sized robot (radius 0.15 m).
    pub mounts: Vec<Pose>,
    /// Nominal detection range from the mount, metres. Default 0.8.
    pub range_m: f64,
    /// Standard deviation of the per-reading detection range, metres.
    /// Default 0.02.
    pub range_sigma_m: f64,
    /// Full width of each detector's beam, radians, in [0, π/2); sampled by
    /// three rays (axis and edges), or one ray when 0. Default 10°
    /// (0.1745): a lensed IR proximity detector's cone, still narrow enough
    /// that 20° between neighbouring beams stay blind. With single rays
    /// (0) the AIBOT-like robot met the front corners of 0.5 m boxes
    /// between two beams in a quarter to a half of the runs of the
    /// voting suite's simple fields.
    #[serde(default)]
    pub beam_rad: f64,
    /// Read period, seconds (`None`: every control tick). Default `None`.
    pub period_s: Option<f64>,
}

impl Default for IrParams {
    fn default() -> IrParams {
        IrParams {
            mounts: rim_mounts(&spread_angles(7, std::f64::consts::PI), 0.15),
            range_m: 0.8,
            range_sigma_m: 0.02,
            beam_rad: 10f64.to_radians(),
            period_s: None,
        }
    }
}

impl IrParams {
    /// No detectors.
    pub fn none() -> IrParams {
        IrParams {
            mounts: Vec::new(),
            ..IrParams::default()
        }
    }

    /// Checks every field.
    pub fn validate(&self) -> Result<()> {
        validate_mounts("ir.mounts", &self.mounts)?;
        validate::positive("ir.range_m", self.range_m)?;
        validate::non_negative("ir.range_sigma_m", self.range_sigma_m)?;
        validate::within(
            "ir.beam_rad",
            self.beam_rad,
            0.0,
            std::f64::consts::FRAC_PI_2 - 1e-9,
            "in [0, π/2)",
        )?;
        validate_period("ir.period_s", self.period_s)
    }
}

/// An infrared array at run time.
#[derive(Debug, Clone)]
pub struct Ir {
    params: IrParams,
    rng: RandomStream,
    schedule: Schedule,
}

impl Ir {
    /// An array with these (validated) parameters drawing from `rng`.
    pub fn new(params: IrParams, rng: RandomStream) -> Result<Ir> {
        params.validate()?;
        Ok(Ir {
            schedule: Schedule::new(params.period_s),
            params,
            rng,
        })
    }

    /// The parameters.
    pub fn params(&self) -> &IrParams {
        &self.params
    }

    /// Reading buffers, one per detector (not triggered).
    pub fn empty_readings(&self) -> Vec<IrReading> {
        self.params
            .mounts
            .iter()
            .map(|m| IrReading {
                mount: *m,
                range_m: self.params.range_m,
                triggered: false,
            })
            .collect()
    }

    /// Reads every detector into `out` (from [`Ir::empty_readings`]; entry
    /// `k` for mount `k`, extra entries left alone) if the array is due at
    /// `time_s`; returns whether it read.
    pub fn read(&mut self, scene: &Scene, robot: &Pose, time_s: f64, out: &mut [IrReading]) -> bool {
        if !self.schedule.due(time_s) {
            return false;
        }
        let r = scene.person_radius_m;
        let (rsin, rcos) = robot.theta_rad.sin_cos();
        for (k, reading) in out.iter_mut().enumerate().take(self.params.mounts.len()) {
            let (origin, heading) = mounted(robot, rsin, rcos, &self.params.mounts[k]);
            let range = (self.params.range_m + self.rng.gaussian(self.params.range_sigma_m)).max(0.0);
            let half = 0.5 * self.params.beam_rad;
            let skip = scene.free_radius_m(origin);
            let ray = |a: f64| {
                let (sin, cos) = a.sin_cos();
                let person = scene.people.iter().any(|q| {
                    let rel = into_frame(q.position, origin, sin, cos);
                    norm(rel) - r <= range
                        && ray_disc(rel, Vec2::new(1.0, 0.0), r).is_some_and(|t| t <= range)
                });
                person || scene.cast(origin, Vec2::new(cos, sin), a, skip, range).is_some()
            };
            reading.triggered = ray(heading) || (half > 0.0 && (ray(heading - half) || ray(heading + half)));
        }
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::{Cell, OccupancyGrid};

    #[test]
    fn detects_along_the_beam_only() {
        let mut g = OccupancyGrid::new(100, 100, 0.05, Pose::default());
        let p = IrParams {
            range_sigma_m: 0.0,
            ..IrParams::default()
        };
        let mut ir = Ir::new(p, RandomStream::new(1, 3)).unwrap();
        let mut out = ir.empty_readings();
        let robot = Pose::new(2.0, 2.0, 0.0);
        ir.read(&Scene::static_only(&g), &robot, 0.0, &mut out);
        assert!(out.iter().all(|d| !d.triggered));
        // A cell on the forward beam, 0.6 m ahead of the rim.
        let c = g.cell_of(Vec2::new(2.77, 2.0));
        g.set(c, Cell::Occupied);
        ir.read(&Scene::static_only(&g), &robot, 0.1, &mut out);
        let fired: Vec<bool> = out.iter().map(|d| d.triggered).collect();
        assert_eq!(fired, vec![false, false, false, true, false, false, false]);
    }

    #[test]
    fn a_beam_has_a_width() {
        let mut g = OccupancyGrid::new(100, 100, 0.05, Pose::default());
        // One cell 0.6 m ahead of the front detector, 4° off its axis (the
        // axis runs along the middle of the row of cells below it).
        let robot = Pose::new(2.0, 2.025, 0.0);
        let a = 4f64.to_radians();
        let c = g.cell_of(Vec2::new(2.15 + 0.6 * a.cos(), 2.025 + 0.6 * a.sin()));
        g.set(c, Cell::Occupied);
        let fired = |beam_rad: f64| {
            let p = IrParams {
                range_sigma_m: 0.0,
                beam_rad,
                ..IrParams::default()
            };
            let mut ir = Ir::new(p, RandomStream::new(1, 3)).unwrap();
            let mut out = ir.empty_readings();
            ir.read(&Scene::static_only(&g), &robot, 0.0, &mut out);
            out[3].triggered
        };
        assert!(!fired(0.0), "a single ray misses it");
        assert!(fired(10f64.to_radians()), "a 10° beam sees it");
        assert!(
            IrParams {
                beam_rad: 2.0,
                ..IrParams::default()
            }
            .validate()
            .is_err()
        );
    }
}
