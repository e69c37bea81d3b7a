//! Monte Carlo localization: a particle filter on the laser scan against a
//! known occupancy map, for the tour-guide robot's Localizer
//! (docs/tour-guide.md).
//!
//! ```
//! use localization::{Localizer, LocalizationStatus, MclParams};
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
//! `cargo run --release -p localization --example mcl_drive -- <map> --seeds 5 …`:
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
#![warn(missing_docs)]

pub mod consistency;
pub mod gaussian;
pub mod kld;
pub mod likelihood_field;
pub mod motion_model;
pub mod recovery;
pub mod relocalization;
pub mod resampling;
pub mod status;

use std::sync::Arc;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use robot::{Cell, GridMap, LaserScan, Pose, Vec2, wrap_angle};

pub use consistency::{ConsistencyTolerances, Neighbourhood, ScanConsistency};
pub use gaussian::Gaussian;
pub use kld::KldParams;
pub use likelihood_field::{
    BeamCombination, BeamSkip, BeamTable, LikelihoodField, LikelihoodFieldParams, PreparedScan,
    squared_distance_transform,
};
pub use motion_model::{OdometryIncrement, OdometryMotionModel};
pub use recovery::{Recovery, RecoveryParams};
pub use relocalization::{RecoveryStage, RelocalizationParams};
pub use resampling::{effective_sample_size, low_variance_resample};
pub use status::{LocalizationStatus, MatchOutcome, StatusMachine, StatusParams, StatusRule};

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
    /// Success/Warning judgement (by default the contradiction rule:
    /// through tolerance 0.25 m, at most 0.1 contradicted, 10 beams of
    /// evidence, a check every 0.25 s).
    pub status: StatusParams,
    /// Recovery after a contradiction Warning (a cloud of 3 000 within
    /// 2.5 m and 90°, global after 20 s).
    pub relocalization: RelocalizationParams,
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
            relocalization: RelocalizationParams::default(),
        }
    }
}

/// Share of the particles a correction resets ([`Localizer::update`],
/// sensor resetting).
pub const SENSOR_RESET_SHARE: f64 = 0.2;

/// A recovery cloud has settled when its estimate's cluster holds this
/// share of the weight ([`relocalization`]).
pub const SETTLED_SHARE: f64 = 0.8;

/// Clusters of a recovery cloud whose means are scored against the scan
/// ([`relocalization`]).
pub const RECOVERY_CANDIDATES: usize = 8;

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
        unit("status.min_explained", self.status.min_explained)?;
        non_negative("status.through_tolerance_m", self.status.through_tolerance_m)?;
        non_negative("status.through_tolerance_rad", self.status.through_tolerance_rad)?;
        unit("status.max_contradiction", self.status.max_contradiction)?;
        check(
            self.status.min_evidence_beams <= 100_000,
            "status.min_evidence_beams",
            "at most 100 000",
            self.status.min_evidence_beams as f64,
        )?;
        non_negative("status.check_period_s", self.status.check_period_s)?;
        let r = &self.relocalization;
        count("relocalization.particles", r.particles)?;
        positive("relocalization.radius_m", r.radius_m)?;
        check(
            r.heading_rad > 0.0 && r.heading_rad <= std::f64::consts::PI,
            "relocalization.heading_rad",
            "in (0, π]",
            r.heading_rad,
        )?;
        positive("relocalization.period_s", r.period_s)?;
        positive("relocalization.global_after_s", r.global_after_s)
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
    /// The scan's consistency with the map at the estimate (the
    /// contradiction rule only).
    pub consistency: Option<ScanConsistency>,
    /// Whether this was a filter iteration (`false`: a status check
    /// between iterations, the particles untouched).
    pub filtered: bool,
    /// Where a recovery stands after this iteration.
    pub recovery: RecoveryStage,
    /// A pose near the estimate that explains a scan the estimate
    /// contradicts (the contradiction rule's neighbourhood): the robot is
    /// off, not lost; after a filter iteration the cloud was partly reset
    /// there ([`Localizer::update`], sensor resetting).
    pub correction: Option<Pose>,
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
    /// Time of the last filter iteration and of the last judgement
    /// ([`Localizer::update_at`]), seconds.
    last_filter_s: Option<f64>,
    last_judged_s: Option<f64>,
    /// The time given with the scan being processed.
    now_s: Option<f64>,
    /// The recovery after a contradiction Warning, and when its stage began.
    stage: RecoveryStage,
    stage_since_s: Option<f64>,
    /// The cluster the recovery's estimate came from, and its share of
    /// the weight.
    recovery_bin: Option<(i64, i64, i64)>,
    cluster_share: f64,
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
            last_filter_s: None,
            last_judged_s: None,
            now_s: None,
            stage: RecoveryStage::Idle,
            stage_since_s: None,
            recovery_bin: None,
            cluster_share: 0.0,
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
        self.stage = RecoveryStage::Idle;
        self.stage_since_s = None;
        self.last_filter_s = None;
        self.last_judged_s = None;
        self.recovery_bin = None;
        self.cluster_share = 0.0;
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
        // A global cloud is a recovery from the start: its estimate is the
        // best cluster's, and its first Warning scatters nothing.
        if self.params.status.rule == StatusRule::Contradiction && self.params.relocalization.enabled {
            self.stage = RecoveryStage::Global;
        }
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

    /// The bin of particle `i` for clustering (0.5 m × 0.5 m × 0.5 rad)
    /// and the number of heading bins.
    fn cluster_key(&self, i: usize) -> ((i64, i64, i64), i64) {
        const XY: f64 = 0.5;
        const TH: f64 = 0.5;
        let bins_th = (std::f64::consts::TAU / TH).ceil() as i64;
        (
            (
                (self.x[i] / XY).floor() as i64,
                (self.y[i] / XY).floor() as i64,
                (((self.theta[i] + std::f64::consts::PI) / TH).floor() as i64).rem_euclid(bins_th),
            ),
            bins_th,
        )
    }

    /// The `k` bins with the largest total weight, heaviest first (ties:
    /// bin order). `O(n log n)`.
    fn heaviest_bins(&self, k: usize) -> Vec<(i64, i64, i64)> {
        let mut bins: std::collections::BTreeMap<(i64, i64, i64), f64> = std::collections::BTreeMap::new();
        for i in 0..self.x.len() {
            *bins.entry(self.cluster_key(i).0).or_insert(0.0) += self.weight[i];
        }
        let mut v: Vec<((i64, i64, i64), f64)> = bins.into_iter().collect();
        v.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
        v.into_iter().take(k).map(|(b, _)| b).collect()
    }

    /// The particles of the cluster around `bin`: it and its 26
    /// neighbours.
    fn cluster_members(&self, bin: (i64, i64, i64)) -> Vec<bool> {
        (0..self.x.len())
            .map(|i| {
                let (k, bins_th) = self.cluster_key(i);
                let dt = (k.2 - bin.2).rem_euclid(bins_th);
                (k.0 - bin.0).abs() <= 1 && (k.1 - bin.1).abs() <= 1 && (dt <= 1 || dt >= bins_th - 1)
            })
            .collect()
    }

    /// The weighted mean of the particles in `keep` (the last estimate if
    /// they weigh nothing).
    fn masked_mean(&self, keep: &[bool]) -> Pose {
        let (mut sx, mut sy, mut ss, mut sc, mut sw) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for i in (0..self.x.len()).filter(|&i| keep[i]) {
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

    /// The estimate while recovering (module [`relocalization`]): among
    /// the clusters around the [`RECOVERY_CANDIDATES`] heaviest bins, the
    /// mean that contradicts the scan least (`(through + 1)/(hit + through
    /// + 2)`, so that more evidence counts; ties: the heavier).
    /// The mean of a cloud with several modes lies between them, where the
    /// robot is not, and the heaviest mode of a flat likelihood is often
    /// a wrong one. Remembers the cluster for [`Localizer::collapse_to_cluster`].
    fn recovery_estimate(&mut self, scan: &LaserScan) -> Pose {
        let tol = self.params.status.tolerances();
        let mut best: Option<(f64, Pose, (i64, i64, i64))> = None;
        for bin in self.heaviest_bins(RECOVERY_CANDIDATES) {
            let mean = self.masked_mean(&self.cluster_members(bin));
            let c = self.field.consistency(&mean, scan, tol);
            // The contradiction with one pseudo-beam each way: a pose that
            // agrees with many walls beats one that agrees with a few.
            let score = (c.through as f64 + 1.0) / (c.evidence() as f64 + 2.0);
            if best.is_none_or(|(b, _, _)| score < b) {
                best = Some((score, mean, bin));
            }
        }
        match best {
            Some((_, mean, bin)) => {
                self.recovery_bin = Some(bin);
                let members = self.cluster_members(bin);
                let total: f64 = self.weight.iter().sum();
                let inside: f64 = self
                    .weight
                    .iter()
                    .zip(&members)
                    .filter(|(_, m)| **m)
                    .map(|(w, _)| w)
                    .sum();
                self.cluster_share = if total > 0.0 { inside / total } else { 0.0 };
                mean
            }
            None => self.weighted_mean(),
        }
    }

    /// Ends a recovery: resamples the tracking count of particles from the
    /// heaviest cluster only, so that the other modes of the recovery
    /// cloud cannot pull the estimate away later.
    fn collapse_to_cluster(&mut self) {
        let Some(bin) = self.recovery_bin.take() else {
            return;
        };
        let keep = self.cluster_members(bin);
        let mut sum = 0.0;
        for (w, &k) in self.weight.iter_mut().zip(&keep) {
            if !k {
                *w = 0.0;
            }
            sum += *w;
        }
        if sum.is_nan() || sum <= 0.0 {
            return;
        }
        self.weight.iter_mut().for_each(|w| *w /= sum);
        let n_out = self.params.particles;
        let u = self.noise.uniform();
        low_variance_resample(&self.weight, n_out, u, &mut self.picks);
        self.gather();
        std::mem::swap(&mut self.x, &mut self.nx);
        std::mem::swap(&mut self.y, &mut self.ny);
        std::mem::swap(&mut self.theta, &mut self.ntheta);
        self.weight.clear();
        self.weight.resize(n_out, 1.0 / n_out as f64);
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
    /// used) and returns `None`. Without a clock there are no status
    /// checks between iterations and no timed recovery iterations: use
    /// [`Localizer::update_at`] on a robot.
    ///
    /// Errors (the localizer is left unchanged): not initialised, a
    /// non-finite odometry pose, a scan with a non-finite mount or angles
    /// or a maximum range that is NaN or ≤ 0.
    pub fn update(
        &mut self,
        odometry: Pose,
        scan: &LaserScan,
    ) -> Result<Option<UpdateInfo>, LocalizationError> {
        self.update_inner(None, odometry, scan)
    }

    /// [`Localizer::update`] at time `time_s` (seconds, non-decreasing):
    /// also, between filter iterations, judges the scan at the current
    /// estimate every `status.check_period_s` (the contradiction rule), and
    /// while recovering runs a filter iteration every
    /// `relocalization.period_s` even without motion
    /// ([`relocalization`]). A check returns an [`UpdateInfo`] with
    /// `filtered: false`.
    pub fn update_at(
        &mut self,
        time_s: f64,
        odometry: Pose,
        scan: &LaserScan,
    ) -> Result<Option<UpdateInfo>, LocalizationError> {
        if !time_s.is_finite() {
            return Err(LocalizationError::InvalidParameter {
                name: "time_s",
                requirement: "a finite number",
                value: time_s,
            });
        }
        self.update_inner(Some(time_s), odometry, scan)
    }

    fn update_inner(
        &mut self,
        time_s: Option<f64>,
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
        self.now_s = time_s;
        let since = |last: Option<f64>| match (time_s, last) {
            (Some(t), Some(l)) => t - l,
            _ => 0.0,
        };
        let inc = match self.filter_odometry {
            None => OdometryIncrement::default(),
            Some(from) => {
                let inc = OdometryIncrement::between(&from, &odometry);
                let moved = inc.distance_m() >= self.params.update_min_d_m
                    || inc.rotation_rad().abs() >= self.params.update_min_a_rad;
                let recovery_due = self.stage != RecoveryStage::Idle
                    && since(self.last_filter_s) >= self.params.relocalization.period_s;
                if !(moved || recovery_due) {
                    let s = &self.params.status;
                    if s.rule == StatusRule::Contradiction
                        && s.check_period_s > 0.0
                        && since(self.last_judged_s) >= s.check_period_s
                    {
                        let check = self.status_check(scan);
                        // Off, not lost: a filter iteration now resets part
                        // of the cloud at the correction (the robot may
                        // stand for long, and no iteration would run).
                        if check.correction.is_some() && self.stage == RecoveryStage::Idle {
                            return Ok(Some(self.iterate(&inc, odometry, scan)));
                        }
                        return Ok(Some(check));
                    }
                    return Ok(None);
                }
                inc
            }
        };
        Ok(Some(self.iterate(&inc, odometry, scan)))
    }

    /// Judges `scan` at the current estimate without touching the
    /// particles (the contradiction rule between filter iterations).
    fn status_check(&mut self, scan: &LaserScan) -> UpdateInfo {
        let estimate = self.estimate();
        let warning = self.machine.status() == LocalizationStatus::Warning;
        let (outcome, c, correction) = self
            .params
            .status
            .judge_scan(&self.field, &estimate, scan, warning);
        let outcome = self.settled(outcome);
        let status = self.machine.observe(outcome);
        self.last_judged_s = self.now_s;
        self.after_judgement(status);
        let n = self.x.len();
        UpdateInfo {
            iteration: self.iterations,
            particles: n,
            beams_used: 0,
            beams_skipped: 0,
            effective_sample_size: effective_sample_size(&self.weight),
            resampled: false,
            particles_after: self.x.len(),
            injected: 0,
            estimate,
            odometry_pose: estimate,
            score_estimate: 1.0 - c.contradiction(),
            score_odometry: 1.0 - c.contradiction(),
            outcome,
            status,
            consistency: Some(c),
            filtered: false,
            recovery: self.stage,
            correction,
        }
    }

    /// After a judgement that left the machine in `status`:
    /// starts, escalates or ends a recovery (module [`relocalization`]).
    fn after_judgement(&mut self, status: LocalizationStatus) {
        let r = self.params.relocalization;
        if self.params.status.rule != StatusRule::Contradiction || !r.enabled {
            return;
        }
        match status {
            LocalizationStatus::Success => match self.stage {
                RecoveryStage::Idle => {}
                // A recovery cloud's other modes go at once.
                RecoveryStage::Scattered => {
                    self.collapse_to_cluster();
                    self.stage = RecoveryStage::Idle;
                    self.stage_since_s = None;
                }
                // A global cloud shrinks by KLD-sampling: the cluster
                // estimate holds until it is down to the tracking size.
                RecoveryStage::Global => {
                    if self.x.len() <= self.params.particles {
                        self.recovery_bin = None;
                        self.stage = RecoveryStage::Idle;
                        self.stage_since_s = None;
                    }
                }
            },
            LocalizationStatus::Warning => {
                let elapsed = match (self.now_s, self.stage_since_s) {
                    (Some(t), Some(s)) => t - s,
                    _ => 0.0,
                };
                if self.stage == RecoveryStage::Idle {
                    self.scatter_recovery_cloud();
                } else if elapsed >= r.global_after_s {
                    if self.stage == RecoveryStage::Scattered {
                        self.scatter_global();
                    } else {
                        self.scatter_recovery_cloud();
                    }
                }
            }
        }
    }

    /// Sensor resetting (S. Lenser, M. Veloso, *Sensor resetting
    /// localization for poorly modelled mobile robots*, ICRA 2000): a
    /// [`SENSOR_RESET_SHARE`] of the particles, evenly spread over the
    /// cloud, is moved to `q` (the nearest pose that explains a scan the
    /// estimate contradicts) with the tracking spread of a fresh start
    /// (0.05 m, 1°); all weights equal.
    fn reset_part_at(&mut self, q: &Pose) {
        let n = self.x.len();
        let k = ((n as f64 * SENSOR_RESET_SHARE).round() as usize).min(n);
        if k == 0 {
            return;
        }
        let stride = n / k;
        for i in (0..n).step_by(stride.max(1)).take(k) {
            self.x[i] = q.x_m + self.noise.gaussian(0.05);
            self.y[i] = q.y_m + self.noise.gaussian(0.05);
            self.theta[i] = wrap_angle(q.theta_rad + self.noise.gaussian(1f64.to_radians()));
        }
        self.weight.iter_mut().for_each(|w| *w = 1.0 / n as f64);
    }

    /// Adds a recovery cloud around the last estimate to the particles,
    /// all weights equal.
    fn scatter_recovery_cloud(&mut self) {
        let r = self.params.relocalization;
        let centre = self.mean;
        for _ in 0..r.particles {
            let u = [self.noise.uniform(), self.noise.uniform(), self.noise.uniform()];
            let p = r.scatter(&centre, u);
            self.x.push(p.x_m);
            self.y.push(p.y_m);
            self.theta.push(p.theta_rad);
        }
        let n = self.x.len();
        self.weight.clear();
        self.weight.resize(n, 1.0 / n as f64);
        self.stage = RecoveryStage::Scattered;
        self.stage_since_s = self.now_s;
        self.cluster_share = 0.0;
    }

    /// Replaces the particles by a global cloud, keeping the status (a
    /// recovery's second stage).
    fn scatter_global(&mut self) {
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
        self.stage = RecoveryStage::Global;
        self.stage_since_s = self.now_s;
        self.cluster_share = 0.0;
    }

    /// A match while recovering counts only once the cloud has settled on
    /// one place — [`SETTLED_SHARE`] of its weight in the estimate's
    /// cluster, or shrunk by KLD-sampling to the tracking size: until then
    /// it is no data (module [`relocalization`]: two poses may explain a
    /// crowded scan, and the Warning must last until the filter has chosen).
    fn settled(&self, outcome: MatchOutcome) -> MatchOutcome {
        if outcome == MatchOutcome::Matched
            && self.stage != RecoveryStage::Idle
            && self.x.len() > self.params.particles
            && self.cluster_share < SETTLED_SHARE
        {
            MatchOutcome::NoData
        } else {
            outcome
        }
    }

    /// Where a recovery stands.
    pub fn recovery_stage(&self) -> RecoveryStage {
        self.stage
    }

    /// One filter iteration (module docs).
    fn iterate(&mut self, inc: &OdometryIncrement, odometry: Pose, scan: &LaserScan) -> UpdateInfo {
        let n = self.x.len();
        // 1. Motion.
        if *inc != OdometryIncrement::default() {
            // A global cloud not yet shrunk to the tracking size explores
            // with the larger noise.
            // (A recovery cloud already spans the kidnap: it moves with
            // the tracking noise, module [`relocalization`].)
            let model = if n > self.params.particles && self.stage != RecoveryStage::Scattered {
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
        // 3. Estimate (while recovering, the heaviest cluster's).
        let estimate = if self.stage == RecoveryStage::Idle {
            self.weighted_mean()
        } else {
            self.recovery_estimate(scan)
        };
        // 4. Status.
        let mut correction = None;
        let (score_estimate, score_odometry, outcome, consistency) = match self.params.status.rule {
            StatusRule::Explained => {
                let within = self.params.status.explained_within_m;
                let (score_estimate, valid) = self.field.explained_fraction(&estimate, scan, within);
                let (score_odometry, _) = self.field.explained_fraction(&odometry_pose, scan, within);
                let outcome = self.params.status.judge(score_estimate, score_odometry, valid);
                (score_estimate, score_odometry, outcome, None)
            }
            StatusRule::Contradiction => {
                let tol = self.params.status.tolerances();
                let warning = self.machine.status() == LocalizationStatus::Warning;
                let (outcome, at_estimate, found) =
                    self.params
                        .status
                        .judge_scan(&self.field, &estimate, scan, warning);
                let outcome = self.settled(outcome);
                correction = found;
                let at_odometry = self.field.consistency(&odometry_pose, scan, tol);
                (
                    1.0 - at_estimate.contradiction(),
                    1.0 - at_odometry.contradiction(),
                    outcome,
                    Some(at_estimate),
                )
            }
        };
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
        self.last_filter_s = self.now_s;
        self.last_judged_s = self.now_s;
        if let Some(q) = correction
            && self.stage == RecoveryStage::Idle
        {
            self.reset_part_at(&q);
        }
        self.after_judgement(status);
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
            consistency,
            filtered: true,
            recovery: self.stage,
            correction,
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
