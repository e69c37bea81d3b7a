//! Monte Carlo localization: a particle filter on the laser scan against a
//! known occupancy map, for the tour-guide robot's Localizer
//! (tour-guide.md).
//!
//! ```
//! use nav::localization::{Localizer, LocalizationStatus, MclParams};
//! use robot::{Cell, GridMap, LaserScan, Pose};
//!
//! // A 4 m × 4 m room (0.05 m cells) with walls on its border cells.
//! let n = 80;
//! let cells = (0..n * n)
//!     .map(|k| if k % n == 0 || k % n == n - 1 || k / n == 0 || k / n == n - 1 { Cell::Occupied } else { Cell::Free })
//!     .collect();
//! let map = GridMap::new(n, n, 0.05, Pose::default(), cells)?;
//! let mut mcl = Localizer::new(&map, MclParams::default(), 7)?;
//! // The robot is at the room's centre facing +x; we believe it is 0.14 m off.
//! let guess = Pose::new(2.1, 1.9, 0.05);
//! mcl.init_pose(guess, 0.2, 0.1)?;
//! // Its 37-beam scan over 180° sees the walls' faces 1.95 m away.
//! let range = |a: f64| {
//!     let (s, c) = a.sin_cos();
//!     let along = |d: f64| if d.abs() > 1e-9 { 1.95 / d.abs() } else { f64::INFINITY };
//!     along(c).min(along(s))
//! };
//! let scan = LaserScan {
//!     mount: Pose::default(),
//!     angle_min_rad: -std::f64::consts::FRAC_PI_2,
//!     angle_increment_rad: std::f64::consts::PI / 36.0,
//!     range_max_m: 10.0,
//!     ranges_m: (0..37).map(|k| range(-std::f64::consts::FRAC_PI_2 + k as f64 * std::f64::consts::PI / 36.0)).collect(),
//! };
//! let info = mcl.update(Pose::default(), &scan)?.expect("the first scan is always used");
//! assert_eq!(info.iteration, 1);
//! let error = |p: Pose| (p.x_m - 2.0).hypot(p.y_m - 2.0);
//! // One iteration weighs the cloud towards the truth.
//! assert!(error(mcl.estimate()) < 0.75 * error(guess), "{:?}", mcl.estimate());
//! assert!(info.effective_sample_size < 500.0);
//! assert_eq!(mcl.status(), LocalizationStatus::Success);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! # The filter
//!
//! A [`Localizer`] is a component a controller owns. Each control tick the
//! controller hands it the odometry pose and the scan
//! ([`Localizer::update`]). As in ROS AMCL, the filter runs only once the
//! odometry says the robot moved at least `update_min_d` (0.2 m) or turned
//! at least `update_min_a` (π/6) since the last filter iteration (and on
//! the first scan after an initialisation). A filter iteration
//!
//! 1. moves every particle by a noisy copy of the odometry increment since
//!    the last iteration ([`motion_model`], *Probabilistic Robotics* §5.4).
//!    The increment is accumulated and sampled once per iteration, as AMCL
//!    does, so the `α` noise parameters mean the same as AMCL's and the
//!    noise does not depend on the control rate;
//! 2. weights the particles with the likelihood field ([`likelihood_field`],
//!    §6.4) over `max_beams` (60) of the scan's beams;
//! 3. takes the estimate: the weighted mean position and the circular mean
//!    heading;
//! 4. compares how the scan matches the map at the estimate and at the
//!    odometry pose, and steps the Success/Warning machine ([`status`]);
//! 5. resamples ([`resampling`], low variance, table 4.4) when the
//!    effective sample size falls below half the particles, shrinking a
//!    global-localization cloud by the KLD bound ([`kld`]) and, if enabled,
//!    injecting random particles ([`recovery`]).
//!
//! Between iterations [`Localizer::estimate`] is the last estimate moved by
//! the odometry increment since (what AMCL's `map → odom` transform gives),
//! so a controller sees a pose every tick.
//!
//! # Decisions
//!
//! - **Success / Warning** ([`status`]): the odometry pose is the
//!   prediction (last estimate + odometry increment since the last
//!   iteration); the score is the fraction of all valid beams whose
//!   endpoint lies within 0.1 m of a wall; the scan matches when the
//!   estimate's score beats the prediction's by more than 0.02, fails when
//!   it falls short by more, and within that margin matches only if at
//!   least 0.8 of the beams are explained. Without the level rule the
//!   comparison is noise for a filter that tracks well, and crowds change
//!   nothing (figures below).
//! - **Unknown cells** are not obstacles for the distance; endpoints off
//!   the map get the largest distance (AMCL). Distances are measured to the
//!   boundary between occupied and other cells, inside obstacles too
//!   ([`likelihood_field`]).
//! - **Beams** combine as AMCL's sum of cubes, `w ← w·(1 + Σ p³)`
//!   ([`BeamCombination`]). The product (`Σ ln p`) tracks more tightly in
//!   an empty building but loses the robot among people (figures below).
//!   AMCL's beam skipping is available ([`BeamSkip`], off).
//! - **Max range**: beams at or beyond the maximum range (`∞`), drop-outs
//!   (`NaN`) and negative ranges are skipped, as AMCL's likelihood-field
//!   model skips max-range readings.
//! - **Motion noise** `α1…α4 = 0.01`, calibrated on the simulated odometry
//!   ([`OdometryMotionModel`]); AMCL's 0.2 is [`OdometryMotionModel::amcl`]
//!   and is used while a global cloud explores.
//! - **Recovery** (random particles, AMCL's `recovery_alpha_slow/fast`) is
//!   off by default: with AMCL's suggested 0.001 / 0.1 it *harmed*
//!   tracking (figures below).
//! - **Global localization** ([`Localizer::init_global`]) starts with
//!   `global_particles` (20 000) uniform over the free cells and moves them
//!   with the larger `global_motion` noise; each resampling shrinks the set
//!   to the KLD bound of the bins the resampled particles occupy, never
//!   below `particles` (500), and once it is down to `particles` the
//!   tracking noise applies.
//! - **Bad input** is an error, never a panic: non-finite odometry or a
//!   scan whose angles, mount or maximum range are not usable
//!   ([`LocalizationError`]). Single `NaN`/`∞` ranges are normal data.
//!
//! # Figures
//!
//! `cargo run --release -p nav --example mcl_drive -- <map> --seeds 5 …`:
//! the Jinny-like robot (181 beams over 180°, 30 m, σ 0.01 m, mounted
//! 0.2 m ahead; default odometry noise) drives a corridor route steered by
//! its true pose, simulation seeds 1–5; position error of
//! [`Localizer::estimate`] at every control tick (0.1 s), median of the
//! five runs' medians and the largest error of all runs.
//!
//! | map, route | options | median | max | Warning (iterations) |
//! |---|---|---|---|---|
//! | building_31, 135.8 m | defaults | 0.044 m | 0.098 m | 0.9 % |
//! | levine, 129.6 m | defaults | 0.025 m | 0.063 m | 0.0 % |
//! | building_31, 20 people | `--people 20` | 0.040 m | 0.091 m | 13.8 % |
//! | building_31, 60 people | `--people 60` | 0.036 m | 0.094 m | 46.8 % |
//! | building_31, 0 / 20 / 60 people | `--min-explained 0` (comparison alone) | | | 0.9 / 0.3 / 0.6 % |
//! | building_31 | `--alpha 0.2` (AMCL) | 0.091 m | 0.283 m | |
//! | levine | `--alpha 0.2` (AMCL) | 0.067 m | 0.595 m | |
//! | building_31 | `--log-product` | 0.018 m | 0.059 m | |
//! | levine | `--log-product` | 0.041 m | 0.074 m | |
//! | building_31, 60 people | `--log-product --people 60` | 0.080 m | 0.586 m | |
//! | building_31 | `--recovery` | 0.060 m | 13.3 m | |
//! | building_31, 60 people | `--recovery --people 60` | 5.4 m | 15.6 m | |
//!
//! The estimate runs 2–4 cm *ahead* of the robot on average: the
//! likelihood field ignores occlusion, so an endpoint pushed through a
//! thin wall lands in the free space behind it, closer to a surface than
//! one that falls short; a laser that looks only forward is thus pulled
//! forward (AMCL's model shares this).
//!
//! Global localization (`--global`, seeds 1–10, 20 000 particles shrinking
//! to 500): the error fell below 0.3 m for good after 10.5, 11.6, 11.7,
//! 12.3, 12.8, 12.8, 12.9, 22.5, 22.5 and 83.5 m of travel (median 12.6 m);
//! the first ~10 m of the route run up a long, featureless corridor.
//!
//! One filter iteration with 500 particles and 60 of 181 beams on
//! building_31 takes about 0.16 ms (`benches/localization.rs`).

pub mod gaussian;
pub mod kld;
pub mod likelihood_field;
pub mod motion_model;
pub mod recovery;
pub mod resampling;
pub mod status;

use std::sync::Arc;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use robot::{Cell, GridMap, LaserScan, Pose, Vec2, wrap_angle};

pub use gaussian::Gaussian;
pub use kld::KldParams;
pub use likelihood_field::{
    BeamCombination, BeamSkip, BeamTable, LikelihoodField, LikelihoodFieldParams, PreparedScan,
    squared_distance_transform,
};
pub use motion_model::{OdometryIncrement, OdometryMotionModel};
pub use recovery::{Recovery, RecoveryParams};
pub use resampling::{effective_sample_size, low_variance_resample};
pub use status::{LocalizationStatus, MatchOutcome, StatusMachine, StatusParams};

/// Why the localizer refused something.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LocalizationError {
    /// A parameter is out of its range.
    #[error("localization parameter `{name}` must be {requirement}, got {value}")]
    InvalidParameter {
        /// The parameter (field path in [`MclParams`], or an argument).
        name: &'static str,
        /// What it must be.
        requirement: &'static str,
        /// What it was.
        value: f64,
    },
    /// The map has no free cell (nowhere to put particles).
    #[error("the map has no free cell to place particles in")]
    NoFreeCell,
    /// A pose argument is not finite.
    #[error("{what} must be a finite pose, got {pose:?}")]
    NonFinitePose {
        /// Which pose.
        what: &'static str,
        /// The pose given.
        pose: Pose,
    },
    /// A scan's geometry is unusable.
    #[error("laser scan: {reason}")]
    BadScan {
        /// What is wrong.
        reason: &'static str,
    },
    /// [`Localizer::update`] before [`Localizer::init_pose`] or
    /// [`Localizer::init_global`].
    #[error("the localizer has no particles: call init_pose or init_global first")]
    NotInitialised,
}

/// Parameters of the localizer. Every field has its unit and default; the
/// defaults are ROS AMCL's where AMCL has the parameter.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MclParams {
    /// Particles while tracking ([`Localizer::init_pose`]), and the fewest
    /// a global cloud shrinks to; 1 to 10⁷. Default 500.
    pub particles: usize,
    /// Particles of [`Localizer::init_global`], 1 to 10⁷. Default 20 000.
    pub global_particles: usize,
    /// Odometry motion model `α1…α4` (AMCL `odom_alpha1..4`). Default 0.2
    /// each.
    pub motion: OdometryMotionModel,
    /// Motion model while a global cloud has more than `particles`
    /// particles (exploration). Default AMCL's 0.2 each.
    pub global_motion: OdometryMotionModel,
    /// Likelihood-field model (σ_hit 0.2 m, z_hit 0.95, z_rand 0.05, max
    /// distance 2 m, sum of cubes).
    pub field: LikelihoodFieldParams,
    /// Beams of a scan used by the filter, evenly spaced, ≥ 1 (AMCL
    /// `laser_max_beams`). Default 60.
    pub max_beams: usize,
    /// Translation that triggers a filter iteration, metres, ≥ 0 (AMCL
    /// `update_min_d`). Default 0.2.
    pub update_min_d_m: f64,
    /// Rotation that triggers a filter iteration, radians, ≥ 0 (AMCL
    /// `update_min_a`). Default π/6.
    pub update_min_a_rad: f64,
    /// Resample when `N_eff` falls below this fraction of the particles,
    /// in [0, 1] (1: every iteration). Default 0.5.
    pub resample_threshold: f64,
    /// KLD bound used to shrink a global cloud.
    pub kld: KldParams,
    /// Random-particle injection (default off).
    pub recovery: RecoveryParams,
    /// Success/Warning judgement (within 0.1 m, margin 0.02, 0.8
    /// explained).
    pub status: StatusParams,
}

impl Default for MclParams {
    fn default() -> MclParams {
        MclParams {
            particles: 500,
            global_particles: 20_000,
            motion: OdometryMotionModel::default(),
            global_motion: OdometryMotionModel::amcl(),
            field: LikelihoodFieldParams::default(),
            max_beams: 60,
            update_min_d_m: 0.2,
            update_min_a_rad: std::f64::consts::PI / 6.0,
            resample_threshold: 0.5,
            kld: KldParams::default(),
            recovery: RecoveryParams::default(),
            status: StatusParams::default(),
        }
    }
}

/// Largest particle count accepted.
pub const MAX_PARTICLES: usize = 10_000_000;

fn check(
    ok: bool,
    name: &'static str,
    requirement: &'static str,
    value: f64,
) -> Result<(), LocalizationError> {
    if ok {
        Ok(())
    } else {
        Err(LocalizationError::InvalidParameter {
            name,
            requirement,
            value,
        })
    }
}

fn non_negative(name: &'static str, v: f64) -> Result<(), LocalizationError> {
    check(v.is_finite() && v >= 0.0, name, "a finite number ≥ 0", v)
}

fn positive(name: &'static str, v: f64) -> Result<(), LocalizationError> {
    check(v.is_finite() && v > 0.0, name, "a finite number > 0", v)
}

fn unit(name: &'static str, v: f64) -> Result<(), LocalizationError> {
    check((0.0..=1.0).contains(&v), name, "in [0, 1]", v)
}

fn count(name: &'static str, v: usize) -> Result<(), LocalizationError> {
    check(
        (1..=MAX_PARTICLES).contains(&v),
        name,
        "between 1 and 10 000 000",
        v as f64,
    )
}

impl MclParams {
    /// Checks every field; the first bad one is the error.
    pub fn validate(&self) -> Result<(), LocalizationError> {
        count("particles", self.particles)?;
        count("global_particles", self.global_particles)?;
        non_negative("motion.alpha1", self.motion.alpha1)?;
        non_negative("motion.alpha2", self.motion.alpha2)?;
        non_negative("motion.alpha3", self.motion.alpha3)?;
        non_negative("motion.alpha4", self.motion.alpha4)?;
        non_negative("global_motion.alpha1", self.global_motion.alpha1)?;
        non_negative("global_motion.alpha2", self.global_motion.alpha2)?;
        non_negative("global_motion.alpha3", self.global_motion.alpha3)?;
        non_negative("global_motion.alpha4", self.global_motion.alpha4)?;
        positive("field.sigma_hit_m", self.field.sigma_hit_m)?;
        non_negative("field.z_hit", self.field.z_hit)?;
        non_negative("field.z_rand", self.field.z_rand)?;
        check(
            self.field.z_hit + self.field.z_rand > 0.0,
            "field.z_hit + field.z_rand",
            "> 0",
            self.field.z_hit + self.field.z_rand,
        )?;
        positive("field.max_distance_m", self.field.max_distance_m)?;
        if let Some(skip) = &self.field.beam_skip {
            non_negative("field.beam_skip.distance_m", skip.distance_m)?;
            unit("field.beam_skip.threshold", skip.threshold)?;
            unit("field.beam_skip.error_threshold", skip.error_threshold)?;
        }
        check(
            self.max_beams >= 1,
            "max_beams",
            "at least 1",
            self.max_beams as f64,
        )?;
        non_negative("update_min_d_m", self.update_min_d_m)?;
        non_negative("update_min_a_rad", self.update_min_a_rad)?;
        unit("resample_threshold", self.resample_threshold)?;
        positive("kld.epsilon", self.kld.epsilon)?;
        non_negative("kld.z", self.kld.z)?;
        positive("kld.bin_xy_m", self.kld.bin_xy_m)?;
        positive("kld.bin_theta_rad", self.kld.bin_theta_rad)?;
        unit("recovery.alpha_slow", self.recovery.alpha_slow)?;
        unit("recovery.alpha_fast", self.recovery.alpha_fast)?;
        check(
            self.recovery.alpha_slow <= self.recovery.alpha_fast,
            "recovery.alpha_slow",
            "≤ recovery.alpha_fast",
            self.recovery.alpha_slow,
        )?;
        non_negative("status.explained_within_m", self.status.explained_within_m)?;
        unit("status.margin", self.status.margin)?;
        unit("status.min_explained", self.status.min_explained)
    }
}

/// One particle: a pose hypothesis and its normalised weight.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Particle {
    /// The pose, world frame.
    pub pose: Pose,
    /// Normalised weight (the weights sum to 1).
    pub weight: f64,
}

/// What one filter iteration did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UpdateInfo {
    /// Filter iterations so far, this one included (1 for the first).
    pub iteration: u64,
    /// Particles weighted in this iteration.
    pub particles: usize,
    /// Beams of the scan the filter used (valid ones of the `max_beams`
    /// subset); 0 means the scan carried no information and the weights
    /// were left as they were.
    pub beams_used: usize,
    /// Beams left out by beam skipping ([`BeamSkip`]).
    pub beams_skipped: usize,
    /// Effective sample size `1/Σw²` after weighting (before resampling).
    pub effective_sample_size: f64,
    /// Whether the particles were resampled.
    pub resampled: bool,
    /// Particle count after this iteration.
    pub particles_after: usize,
    /// Random particles injected by recovery.
    pub injected: usize,
    /// The new estimate.
    pub estimate: Pose,
    /// The odometry pose it was compared with: the previous estimate moved
    /// by the odometry increment (module [`status`]).
    pub odometry_pose: Pose,
    /// Fraction of the scan's valid beams the map explains at the
    /// estimate, in [0, 1] (module [`status`]).
    pub score_estimate: f64,
    /// The same at the odometry pose.
    pub score_odometry: f64,
    /// The judgement of this iteration.
    pub outcome: MatchOutcome,
    /// The state after this iteration.
    pub status: LocalizationStatus,
}

/// The particle filter (module docs).
#[derive(Debug, Clone)]
pub struct Localizer {
    params: MclParams,
    /// Shared by the localizers on one map ([`Localizer::on_same_map`]).
    field: Arc<LikelihoodField>,
    table: Option<BeamTable>,
    prepared: PreparedScan,
    map_origin: Pose,
    map_width: usize,
    resolution_m: f64,
    free_cells: Arc<[usize]>,
    noise: Gaussian,
    x: Vec<f64>,
    y: Vec<f64>,
    theta: Vec<f64>,
    weight: Vec<f64>,
    // Scratch buffers, reused.
    log_lik: Vec<f64>,
    endpoint_sq: Vec<u16>,
    beam_near: Vec<u32>,
    beam_used: Vec<bool>,
    picks: Vec<usize>,
    keys: Vec<u64>,
    nx: Vec<f64>,
    ny: Vec<f64>,
    ntheta: Vec<f64>,
    initialised: bool,
    /// Odometry at the last filter iteration (None: no scan since init).
    filter_odometry: Option<Pose>,
    /// The latest odometry pose given.
    odometry: Option<Pose>,
    /// Estimate at the last filter iteration (or the initial pose).
    mean: Pose,
    iterations: u64,
    machine: StatusMachine,
    recovery: Recovery,
}

impl Localizer {
    /// A localizer on `map` with these parameters, every random draw from
    /// `seed` (same seed, same inputs → bit-identical results). Builds the
    /// likelihood field (`O(cells)`). It has no particles until
    /// [`Localizer::init_pose`] or [`Localizer::init_global`].
    ///
    /// Errors: [`LocalizationError::InvalidParameter`],
    /// [`LocalizationError::NoFreeCell`].
    pub fn new(map: &GridMap, params: MclParams, seed: u64) -> Result<Localizer, LocalizationError> {
        params.validate()?;
        let free_cells: Arc<[usize]> = map
            .cells()
            .iter()
            .enumerate()
            .filter(|(_, c)| **c == Cell::Free)
            .map(|(k, _)| k)
            .collect();
        if free_cells.is_empty() {
            return Err(LocalizationError::NoFreeCell);
        }
        let geometry = (map.origin(), map.width(), map.resolution_m());
        Ok(Localizer::fresh(
            Arc::new(LikelihoodField::new(map, params.field.max_distance_m)),
            free_cells,
            geometry,
            params,
            seed,
        ))
    }

    /// A new localizer on this one's map, with its parameters and every
    /// random draw from `seed`: the same as [`Localizer::new`] on the map
    /// (no particles, nothing of this one's state), without building the
    /// likelihood field and the free cells again — they are shared. For
    /// missions after missions on one map.
    pub fn on_same_map(&self, seed: u64) -> Localizer {
        Localizer::fresh(
            Arc::clone(&self.field),
            Arc::clone(&self.free_cells),
            (self.map_origin, self.map_width, self.resolution_m),
            self.params,
            seed,
        )
    }

    /// A localizer without particles on a prepared field; `geometry` is
    /// the map's origin, width in cells and resolution.
    fn fresh(
        field: Arc<LikelihoodField>,
        free_cells: Arc<[usize]>,
        (map_origin, map_width, resolution_m): (Pose, usize, f64),
        params: MclParams,
        seed: u64,
    ) -> Localizer {
        Localizer {
            field,
            table: None,
            prepared: PreparedScan::default(),
            map_origin,
            map_width,
            resolution_m,
            free_cells,
            noise: Gaussian::new(ChaCha8Rng::seed_from_u64(seed)),
            x: Vec::new(),
            y: Vec::new(),
            theta: Vec::new(),
            weight: Vec::new(),
            log_lik: Vec::new(),
            endpoint_sq: Vec::new(),
            beam_near: Vec::new(),
            beam_used: Vec::new(),
            picks: Vec::new(),
            keys: Vec::new(),
            nx: Vec::new(),
            ny: Vec::new(),
            ntheta: Vec::new(),
            initialised: false,
            filter_odometry: None,
            odometry: None,
            mean: Pose::default(),
            iterations: 0,
            machine: StatusMachine::new(),
            recovery: Recovery::new(params.recovery),
            params,
        }
    }

    /// The parameters.
    pub fn params(&self) -> &MclParams {
        &self.params
    }

    /// The likelihood field of the map.
    pub fn field(&self) -> &LikelihoodField {
        &self.field
    }

    fn reset_after_init(&mut self, mean: Pose) {
        let n = self.x.len();
        self.weight.clear();
        self.weight.resize(n, 1.0 / n as f64);
        self.filter_odometry = None;
        self.odometry = None;
        self.mean = mean;
        self.machine = StatusMachine::new();
        self.recovery.reset();
        self.initialised = true;
    }

    /// Places `particles` particles around `pose`: Gaussian with standard
    /// deviation `std_xy_m` (metres) in x and in y and `std_theta_rad`
    /// (radians) in heading. The next [`Localizer::update`] runs a filter
    /// iteration whatever the motion. The status restarts at *Success*.
    ///
    /// Errors: a non-finite pose, negative or non-finite deviations.
    pub fn init_pose(
        &mut self,
        pose: Pose,
        std_xy_m: f64,
        std_theta_rad: f64,
    ) -> Result<(), LocalizationError> {
        if !(pose.x_m.is_finite() && pose.y_m.is_finite() && pose.theta_rad.is_finite()) {
            return Err(LocalizationError::NonFinitePose {
                what: "initial pose",
                pose,
            });
        }
        non_negative("std_xy_m", std_xy_m)?;
        non_negative("std_theta_rad", std_theta_rad)?;
        let n = self.params.particles;
        self.x.clear();
        self.y.clear();
        self.theta.clear();
        for _ in 0..n {
            self.x.push(pose.x_m + self.noise.gaussian(std_xy_m));
            self.y.push(pose.y_m + self.noise.gaussian(std_xy_m));
            self.theta
                .push(wrap_angle(pose.theta_rad + self.noise.gaussian(std_theta_rad)));
        }
        self.reset_after_init(Pose::new(pose.x_m, pose.y_m, pose.theta_rad));
        Ok(())
    }

    /// A uniformly random pose over the free cells.
    fn random_free_pose(&mut self) -> Pose {
        let k =
            ((self.noise.uniform() * self.free_cells.len() as f64) as usize).min(self.free_cells.len() - 1);
        let cell = self.free_cells[k];
        let (i, j) = (cell % self.map_width, cell / self.map_width);
        let u = self.noise.uniform();
        let v = self.noise.uniform();
        let local = Vec2::new(
            (i as f64 + u) * self.resolution_m,
            (j as f64 + v) * self.resolution_m,
        );
        let p = self.map_origin.transform(local);
        let th = (2.0 * self.noise.uniform() - 1.0) * std::f64::consts::PI;
        Pose::new(p.x, p.y, th)
    }

    /// Global localization: `global_particles` particles uniform over the
    /// free cells of the map, headings uniform. The status restarts at
    /// *Success*.
    pub fn init_global(&mut self) {
        let n = self.params.global_particles;
        self.x.clear();
        self.y.clear();
        self.theta.clear();
        for _ in 0..n {
            let p = self.random_free_pose();
            self.x.push(p.x_m);
            self.y.push(p.y_m);
            self.theta.push(p.theta_rad);
        }
        self.weight.clear();
        self.weight.resize(n, 1.0 / n as f64);
        let mean = self.weighted_mean();
        self.reset_after_init(mean);
    }

    /// The weighted mean of the particles: positions averaged, headings by
    /// the circular mean `atan2(Σ w sin θ, Σ w cos θ)`.
    fn weighted_mean(&self) -> Pose {
        let (mut sx, mut sy, mut ss, mut sc, mut sw) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for i in 0..self.x.len() {
            let w = self.weight[i];
            sx += w * self.x[i];
            sy += w * self.y[i];
            let (s, c) = self.theta[i].sin_cos();
            ss += w * s;
            sc += w * c;
            sw += w;
        }
        if sw <= 0.0 {
            return self.mean;
        }
        Pose::new(sx / sw, sy / sw, ss.atan2(sc))
    }

    fn check_scan(scan: &LaserScan) -> Result<(), LocalizationError> {
        let m = &scan.mount;
        if !(m.x_m.is_finite() && m.y_m.is_finite() && m.theta_rad.is_finite()) {
            return Err(LocalizationError::BadScan {
                reason: "the mount pose is not finite",
            });
        }
        if !(scan.angle_min_rad.is_finite() && scan.angle_increment_rad.is_finite()) {
            return Err(LocalizationError::BadScan {
                reason: "the beam angles are not finite",
            });
        }
        if scan.range_max_m.is_nan() || scan.range_max_m <= 0.0 {
            return Err(LocalizationError::BadScan {
                reason: "the maximum range must be > 0",
            });
        }
        Ok(())
    }

    /// Takes the odometry pose and the scan of one control tick. Runs a
    /// filter iteration (and returns what it did) on the first scan after
    /// an initialisation and whenever the odometry moved at least
    /// `update_min_d_m` or turned at least `update_min_a_rad` since the
    /// last iteration; otherwise only records the odometry (the scan is not
    /// used) and returns `None`.
    ///
    /// Errors (the localizer is left unchanged): not initialised, a
    /// non-finite odometry pose, a scan with a non-finite mount or angles
    /// or a maximum range that is NaN or ≤ 0.
    pub fn update(
        &mut self,
        odometry: Pose,
        scan: &LaserScan,
    ) -> Result<Option<UpdateInfo>, LocalizationError> {
        if !self.initialised {
            return Err(LocalizationError::NotInitialised);
        }
        if !(odometry.x_m.is_finite() && odometry.y_m.is_finite() && odometry.theta_rad.is_finite()) {
            return Err(LocalizationError::NonFinitePose {
                what: "odometry",
                pose: odometry,
            });
        }
        Localizer::check_scan(scan)?;
        self.odometry = Some(odometry);
        let inc = match self.filter_odometry {
            None => OdometryIncrement::default(),
            Some(from) => {
                let inc = OdometryIncrement::between(&from, &odometry);
                if inc.distance_m() < self.params.update_min_d_m
                    && inc.rotation_rad().abs() < self.params.update_min_a_rad
                {
                    return Ok(None);
                }
                inc
            }
        };
        Ok(Some(self.iterate(&inc, odometry, scan)))
    }

    /// One filter iteration (module docs).
    fn iterate(&mut self, inc: &OdometryIncrement, odometry: Pose, scan: &LaserScan) -> UpdateInfo {
        let n = self.x.len();
        // 1. Motion.
        if *inc != OdometryIncrement::default() {
            // A global cloud not yet shrunk to the tracking size explores
            // with the larger noise.
            let model = if n > self.params.particles {
                &self.params.global_motion
            } else {
                &self.params.motion
            };
            let std = model.std_devs(inc);
            for i in 0..n {
                let p = Pose {
                    x_m: self.x[i],
                    y_m: self.y[i],
                    theta_rad: self.theta[i],
                };
                let q = OdometryMotionModel::perturb(inc, &std, &mut self.noise).apply(&p);
                self.x[i] = q.x_m;
                self.y[i] = q.y_m;
                self.theta[i] = q.theta_rad;
            }
        }
        let odometry_pose = inc.apply(&self.mean);
        // 2. Measurement.
        let (beams_used, beams_skipped) = self.weigh(scan);
        let effective_sample_size = effective_sample_size(&self.weight);
        // 3. Estimate.
        let estimate = self.weighted_mean();
        // 4. Status.
        let within = self.params.status.explained_within_m;
        let (score_estimate, valid) = self.field.explained_fraction(&estimate, scan, within);
        let (score_odometry, _) = self.field.explained_fraction(&odometry_pose, scan, within);
        let outcome = self.params.status.judge(score_estimate, score_odometry, valid);
        let status = self.machine.observe(outcome);
        // 5. Resampling.
        let p_inject = self.recovery.injection_probability();
        let resampled = effective_sample_size < self.params.resample_threshold * n as f64 || p_inject > 0.0;
        let mut injected = 0;
        if resampled {
            injected = self.resample(p_inject);
        }
        self.mean = estimate;
        self.filter_odometry = Some(odometry);
        self.iterations += 1;
        UpdateInfo {
            iteration: self.iterations,
            particles: n,
            beams_used,
            beams_skipped,
            effective_sample_size,
            resampled,
            particles_after: self.x.len(),
            injected,
            estimate,
            odometry_pose,
            score_estimate,
            score_odometry,
            outcome,
            status,
        }
    }

    /// Multiplies the weights by the scan's likelihood and normalises them;
    /// returns the beams used and skipped (0 used: weights untouched).
    fn weigh(&mut self, scan: &LaserScan) -> (usize, usize) {
        if self
            .table
            .as_ref()
            .is_none_or(|t| t.range_max_m() != scan.range_max_m)
        {
            self.table = Some(self.field.beam_table(&self.params.field, scan.range_max_m));
        }
        self.prepared.fill(scan, self.params.max_beams, self.resolution_m);
        let beams = self.prepared.len();
        if beams == 0 {
            return (0, 0);
        }
        let table = self.table.as_ref().expect("built above");
        let n = self.x.len();
        let pose = |i: usize| Pose {
            x_m: self.x[i],
            y_m: self.y[i],
            theta_rad: self.theta[i],
        };
        self.log_lik.clear();
        let mut skipped = 0;
        match self.params.field.beam_skip {
            None => {
                for i in 0..n {
                    let ll =
                        self.field
                            .log_likelihood(table, &self.prepared, self.field.pose_in_cells(&pose(i)));
                    self.log_lik.push(ll);
                }
            }
            Some(skip) => {
                // Pass 1: every endpoint's distance, and per beam how many
                // particles it is near an obstacle for.
                self.endpoint_sq.clear();
                for i in 0..n {
                    self.field.endpoint_distances(
                        &self.prepared,
                        self.field.pose_in_cells(&pose(i)),
                        &mut self.endpoint_sq,
                    );
                }
                let near = self.field.squared_cells_within(skip.distance_m);
                self.beam_near.clear();
                self.beam_near.resize(beams, 0);
                for row in self.endpoint_sq.chunks_exact(beams) {
                    for (count, &sq) in self.beam_near.iter_mut().zip(row) {
                        *count += (sq <= near) as u32;
                    }
                }
                let needed = skip.threshold * n as f64;
                self.beam_used.clear();
                self.beam_used
                    .extend(self.beam_near.iter().map(|&c| c as f64 > needed));
                skipped = self.beam_used.iter().filter(|u| !**u).count();
                if skipped as f64 > skip.error_threshold * beams as f64 {
                    self.beam_used.iter_mut().for_each(|u| *u = true);
                    skipped = 0;
                }
                // Pass 2: the likelihood over the beams kept.
                for row in self.endpoint_sq.chunks_exact(beams) {
                    let sum: f32 = row
                        .iter()
                        .zip(&self.beam_used)
                        .filter(|(_, used)| **used)
                        .map(|(&sq, _)| table.value(sq))
                        .sum();
                    self.log_lik.push(table.combine(sum as f64));
                }
            }
        }
        // Prior weight times likelihood, in logs.
        for (l, &w) in self.log_lik.iter_mut().zip(&self.weight) {
            *l += w.ln();
        }
        let max = self.log_lik.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let mut sum = 0.0;
        for (w, &l) in self.weight.iter_mut().zip(&self.log_lik) {
            *w = (l - max).exp();
            sum += *w;
        }
        if !(sum.is_finite() && sum > 0.0 && max.is_finite()) {
            self.weight.iter_mut().for_each(|w| *w = 1.0 / n as f64);
            return (beams - skipped, skipped);
        }
        // ln of the mean likelihood Σ w_prior·q (the prior weights sum to 1).
        self.recovery.observe(max + sum.ln());
        let inv = 1.0 / sum;
        self.weight.iter_mut().for_each(|w| *w *= inv);
        (beams - skipped, skipped)
    }

    /// Low-variance resampling to the target count, with random particles
    /// injected with probability `p_inject`; returns how many.
    fn resample(&mut self, p_inject: f64) -> usize {
        let n = self.x.len();
        let floor = self.params.particles;
        let mut n_out = floor;
        if n > floor {
            // Shrink a large cloud to the KLD bound of the bins its
            // resampled particles occupy.
            let u = self.noise.uniform();
            low_variance_resample(&self.weight, n, u, &mut self.picks);
            self.gather();
            let k = self
                .params
                .kld
                .occupied_bins(&self.nx, &self.ny, &self.ntheta, &mut self.keys);
            n_out = self.params.kld.sample_count(k).clamp(floor, n);
        }
        let u = self.noise.uniform();
        low_variance_resample(&self.weight, n_out, u, &mut self.picks);
        self.gather();
        let mut injected = 0;
        if p_inject > 0.0 {
            for k in 0..n_out {
                if self.noise.uniform() < p_inject {
                    let p = self.random_free_pose();
                    self.nx[k] = p.x_m;
                    self.ny[k] = p.y_m;
                    self.ntheta[k] = p.theta_rad;
                    injected += 1;
                }
            }
        }
        std::mem::swap(&mut self.x, &mut self.nx);
        std::mem::swap(&mut self.y, &mut self.ny);
        std::mem::swap(&mut self.theta, &mut self.ntheta);
        self.weight.clear();
        self.weight.resize(n_out, 1.0 / n_out as f64);
        injected
    }

    /// Copies the particles `picks` into the scratch buffers.
    fn gather(&mut self) {
        self.nx.clear();
        self.ny.clear();
        self.ntheta.clear();
        for &i in &self.picks {
            self.nx.push(self.x[i]);
            self.ny.push(self.y[i]);
            self.ntheta.push(self.theta[i]);
        }
    }

    /// The pose estimate now: the estimate of the last filter iteration
    /// moved by the odometry increment since (module docs). Before any
    /// iteration, the initial pose (or the mean of a global cloud).
    pub fn estimate(&self) -> Pose {
        match (self.filter_odometry, self.odometry) {
            (Some(from), Some(to)) => OdometryIncrement::between(&from, &to).apply(&self.mean),
            _ => self.mean,
        }
    }

    /// Weighted covariance of the particles of the last filter iteration
    /// (after any resampling), about their weighted mean: rows and columns
    /// `x` (m), `y` (m), `θ` (rad; deviations wrapped to (−π, π]).
    pub fn covariance(&self) -> [[f64; 3]; 3] {
        let m = self.weighted_mean();
        let mut c = [[0.0; 3]; 3];
        let sw: f64 = self.weight.iter().sum();
        if sw <= 0.0 {
            return c;
        }
        for i in 0..self.x.len() {
            let d = [
                self.x[i] - m.x_m,
                self.y[i] - m.y_m,
                wrap_angle(self.theta[i] - m.theta_rad),
            ];
            let w = self.weight[i] / sw;
            for (r, row) in c.iter_mut().enumerate() {
                for (k, v) in row.iter_mut().enumerate() {
                    *v += w * d[r] * d[k];
                }
            }
        }
        c
    }

    /// The Success/Warning state.
    pub fn status(&self) -> LocalizationStatus {
        self.machine.status()
    }

    /// Filter iterations since construction.
    pub fn iterations(&self) -> u64 {
        self.iterations
    }

    /// The particles of the last filter iteration (for pictures).
    pub fn particles(&self) -> impl ExactSizeIterator<Item = Particle> + '_ {
        (0..self.x.len()).map(|i| Particle {
            pose: Pose {
                x_m: self.x[i],
                y_m: self.y[i],
                theta_rad: self.theta[i],
            },
            weight: self.weight[i],
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn room(n: usize) -> GridMap {
        let cells = (0..n * n)
            .map(|k| {
                let (i, j) = (k % n, k / n);
                if i == 0 || j == 0 || i == n - 1 || j == n - 1 || (i == n / 3 && j < n / 2) {
                    Cell::Occupied
                } else {
                    Cell::Free
                }
            })
            .collect();
        GridMap::new(n, n, 0.05, Pose::new(-1.0, -1.0, 0.0), cells).unwrap()
    }

    #[test]
    fn bad_parameters_are_structured_errors() {
        let map = room(40);
        let cases: Vec<(MclParams, &str)> = vec![
            (
                MclParams {
                    particles: 0,
                    ..MclParams::default()
                },
                "particles",
            ),
            (
                MclParams {
                    motion: OdometryMotionModel {
                        alpha2: -0.1,
                        ..OdometryMotionModel::default()
                    },
                    ..MclParams::default()
                },
                "motion.alpha2",
            ),
            (
                MclParams {
                    field: LikelihoodFieldParams {
                        sigma_hit_m: f64::NAN,
                        ..LikelihoodFieldParams::default()
                    },
                    ..MclParams::default()
                },
                "field.sigma_hit_m",
            ),
            (
                MclParams {
                    field: LikelihoodFieldParams {
                        z_hit: 0.0,
                        z_rand: 0.0,
                        ..LikelihoodFieldParams::default()
                    },
                    ..MclParams::default()
                },
                "field.z_hit + field.z_rand",
            ),
            (
                MclParams {
                    max_beams: 0,
                    ..MclParams::default()
                },
                "max_beams",
            ),
            (
                MclParams {
                    update_min_d_m: -1.0,
                    ..MclParams::default()
                },
                "update_min_d_m",
            ),
            (
                MclParams {
                    update_min_a_rad: f64::INFINITY,
                    ..MclParams::default()
                },
                "update_min_a_rad",
            ),
            (
                MclParams {
                    resample_threshold: 1.5,
                    ..MclParams::default()
                },
                "resample_threshold",
            ),
            (
                MclParams {
                    recovery: RecoveryParams {
                        alpha_slow: 0.2,
                        alpha_fast: 0.1,
                    },
                    ..MclParams::default()
                },
                "recovery.alpha_slow",
            ),
            (
                MclParams {
                    status: StatusParams {
                        margin: f64::NAN,
                        ..StatusParams::default()
                    },
                    ..MclParams::default()
                },
                "status.margin",
            ),
        ];
        for (p, name) in cases {
            match Localizer::new(&map, p, 1) {
                Err(LocalizationError::InvalidParameter { name: got, .. }) => assert_eq!(got, name),
                other => panic!("{name}: {other:?}"),
            }
        }
        assert!(MclParams::default().validate().is_ok());
    }

    #[test]
    fn a_map_without_free_cells_and_bad_calls_are_errors() {
        let full = GridMap::new(3, 3, 0.1, Pose::default(), vec![Cell::Occupied; 9]).unwrap();
        assert_eq!(
            Localizer::new(&full, MclParams::default(), 1).unwrap_err(),
            LocalizationError::NoFreeCell
        );
        let mut l = Localizer::new(&room(40), MclParams::default(), 1).unwrap();
        let scan = LaserScan {
            range_max_m: 10.0,
            angle_increment_rad: 0.1,
            ranges_m: vec![1.0; 5],
            ..LaserScan::default()
        };
        assert_eq!(
            l.update(Pose::default(), &scan),
            Err(LocalizationError::NotInitialised)
        );
        assert!(matches!(
            l.init_pose(
                Pose {
                    x_m: f64::NAN,
                    ..Pose::default()
                },
                0.1,
                0.1
            ),
            Err(LocalizationError::NonFinitePose { .. })
        ));
        assert!(matches!(
            l.init_pose(Pose::default(), -0.1, 0.1),
            Err(LocalizationError::InvalidParameter { name: "std_xy_m", .. })
        ));
        l.init_pose(Pose::new(0.3, 0.3, 0.0), 0.1, 0.1).unwrap();
        let odo_nan = Pose {
            y_m: f64::INFINITY,
            ..Pose::default()
        };
        assert!(matches!(
            l.update(odo_nan, &scan),
            Err(LocalizationError::NonFinitePose { .. })
        ));
        for bad in [
            LaserScan {
                range_max_m: 0.0,
                ..scan.clone()
            },
            LaserScan {
                range_max_m: f64::NAN,
                ..scan.clone()
            },
            LaserScan {
                angle_min_rad: f64::NAN,
                ..scan.clone()
            },
            LaserScan {
                mount: Pose {
                    theta_rad: f64::INFINITY,
                    ..Pose::default()
                },
                ..scan.clone()
            },
        ] {
            assert!(matches!(
                l.update(Pose::default(), &bad),
                Err(LocalizationError::BadScan { .. })
            ));
        }
        assert_eq!(l.iterations(), 0);
        // Nothing valid in the scan: the iteration runs, the weights stay.
        let blind = LaserScan {
            ranges_m: vec![f64::NAN, f64::INFINITY, 10.0],
            ..scan
        };
        let info = l.update(Pose::default(), &blind).unwrap().unwrap();
        assert_eq!(info.beams_used, 0);
        assert_eq!(info.outcome, MatchOutcome::NoData);
        assert!((info.effective_sample_size - 500.0).abs() < 1e-6);
    }

    #[test]
    fn the_filter_runs_only_after_enough_motion_and_estimates_in_between() {
        let mut l = Localizer::new(&room(40), MclParams::default(), 3).unwrap();
        l.init_pose(Pose::new(0.5, 0.5, 0.0), 0.0, 0.0).unwrap();
        let scan = LaserScan {
            range_max_m: 10.0,
            ranges_m: vec![f64::INFINITY],
            ..LaserScan::default()
        };
        let odo0 = Pose::new(10.0, 20.0, 1.0);
        assert!(l.update(odo0, &scan).unwrap().is_some());
        // 0.1 m forward in the odometry frame: no iteration, but the
        // estimate follows.
        let odo1 = odo0.compose(&Pose::new(0.1, 0.0, 0.0));
        assert!(l.update(odo1, &scan).unwrap().is_none());
        let e = l.estimate();
        assert!((e.x_m - 0.6).abs() < 1e-9 && (e.y_m - 0.5).abs() < 1e-9, "{e:?}");
        // 0.25 m: an iteration.
        let odo2 = odo0.compose(&Pose::new(0.25, 0.0, 0.0));
        let info = l.update(odo2, &scan).unwrap().unwrap();
        assert_eq!(info.iteration, 2);
        assert!((info.odometry_pose.x_m - 0.75).abs() < 1e-9);
        // A turn of π/6 on the spot: an iteration.
        let odo3 = odo2.compose(&Pose::new(0.0, 0.0, std::f64::consts::PI / 6.0 + 1e-9));
        assert!(l.update(odo3, &scan).unwrap().is_some());
        assert_eq!(l.iterations(), 3);
        assert_eq!(l.particles().len(), 500);
    }

    #[test]
    fn covariance_of_an_initial_cloud() {
        let mut l = Localizer::new(
            &room(40),
            MclParams {
                particles: 20_000,
                ..MclParams::default()
            },
            5,
        )
        .unwrap();
        l.init_pose(Pose::new(0.5, 0.4, 3.0), 0.2, 0.1).unwrap();
        let c = l.covariance();
        assert!((c[0][0] / 0.04 - 1.0).abs() < 0.05, "{c:?}");
        assert!((c[1][1] / 0.04 - 1.0).abs() < 0.05, "{c:?}");
        assert!((c[2][2] / 0.01 - 1.0).abs() < 0.05, "{c:?}");
        assert!(c[0][1].abs() < 0.002);
        // Headings near ±π average to π, not 0.
        assert!(l.estimate().theta_rad.abs() > 2.9);
    }

    #[test]
    fn global_init_covers_only_free_cells() {
        let map = room(40);
        let mut l = Localizer::new(
            &map,
            MclParams {
                global_particles: 5000,
                ..MclParams::default()
            },
            5,
        )
        .unwrap();
        l.init_global();
        assert_eq!(l.particles().len(), 5000);
        assert!(l.particles().all(|p| !map.blocked_at(p.pose.position())));
        let total: f64 = l.particles().map(|p| p.weight).sum();
        assert!((total - 1.0).abs() < 1e-9);
    }

    /// A noiseless 37-beam scan over 180° from `pose` by marching each ray
    /// in 1 mm steps to the first blocked cell.
    fn scan_from(map: &GridMap, pose: Pose) -> LaserScan {
        let inc = std::f64::consts::PI / 36.0;
        let ranges_m = (0..37)
            .map(|k| {
                let a = pose.theta_rad - std::f64::consts::FRAC_PI_2 + k as f64 * inc;
                let mut r = 0.0;
                while r < 10.0 {
                    let p = Vec2::new(pose.x_m + r * a.cos(), pose.y_m + r * a.sin());
                    if map.blocked_at(p) {
                        return r;
                    }
                    r += 0.001;
                }
                f64::INFINITY
            })
            .collect();
        LaserScan {
            mount: Pose::default(),
            angle_min_rad: -std::f64::consts::FRAC_PI_2,
            angle_increment_rad: inc,
            range_max_m: 10.0,
            ranges_m,
        }
    }

    #[test]
    fn beam_skipping_leaves_out_a_beam_no_particle_explains() {
        let map = room(40);
        let params = MclParams {
            field: LikelihoodFieldParams {
                beam_skip: Some(BeamSkip::default()),
                ..LikelihoodFieldParams::default()
            },
            // Every call is an iteration.
            update_min_d_m: 0.0,
            update_min_a_rad: 0.0,
            ..MclParams::default()
        };
        let mut l = Localizer::new(&map, params, 9).unwrap();
        let truth = Pose::new(-0.1, 0.2, 0.0);
        l.init_pose(truth, 0.02, 0.01).unwrap();
        let mut scan = scan_from(&map, truth);
        let info = l.update(Pose::default(), &scan).unwrap().unwrap();
        assert_eq!((info.beams_used, info.beams_skipped), (37, 0));
        // Someone 0.3 m ahead, in the middle of the free space (more than
        // 0.5 m from every wall for every particle).
        scan.ranges_m[18] = 0.3;
        let info = l.update(Pose::default(), &scan).unwrap().unwrap();
        assert_eq!((info.beams_used, info.beams_skipped), (36, 1));
    }

    #[test]
    fn recovery_injects_random_particles_when_the_likelihood_drops() {
        let map = room(40);
        let params = MclParams {
            recovery: RecoveryParams {
                alpha_slow: 0.001,
                alpha_fast: 0.1,
            },
            // Every call is an iteration.
            update_min_d_m: 0.0,
            update_min_a_rad: 0.0,
            ..MclParams::default()
        };
        let mut l = Localizer::new(&map, params, 9).unwrap();
        let truth = Pose::new(0.4, -0.2, 0.0);
        l.init_pose(truth, 0.02, 0.01).unwrap();
        let good = scan_from(&map, truth);
        for _ in 0..10 {
            let info = l.update(Pose::default(), &good).unwrap().unwrap();
            assert_eq!(info.injected, 0, "{info:?}");
        }
        // Carried away without odometry: the scans now come from elsewhere.
        let kidnapped = scan_from(&map, Pose::new(-0.4, 0.5, 2.0));
        let injected: usize = (0..5)
            .map(|_| l.update(Pose::default(), &kidnapped).unwrap().unwrap().injected)
            .sum();
        assert!(injected > 50, "{injected}");
    }
}
