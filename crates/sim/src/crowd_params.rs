//! The crowd's parameters ([`CrowdParams`], [`CrowdSize`]): what a world
//! carries ([`crate::World::with_crowd`]) and [`crate::people`] moves.
//! Apart from the crowd itself so that `world` and `people` do not import
//! each other: `people` walks a `World`, a `World` holds only these values.

use robot::Vec2;

use crate::error::Result;
use crate::validate;

/// How many people a crowd has.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CrowdSize {
    /// A density: people per 100 m² of free space (rounded to the nearest
    /// whole person).
    PerArea {
        /// People per 100 m² of free map area.
        people_per_100m2: f64,
    },
    /// An exact number of people.
    Count {
        /// How many.
        people: usize,
    },
}

impl Default for CrowdSize {
    fn default() -> CrowdSize {
        CrowdSize::PerArea {
            people_per_100m2: 0.0,
        }
    }
}

/// Parameters of the crowd (module docs for the model). The defaults give no
/// people; set [`CrowdParams::size`].
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CrowdParams {
    /// How many people are placed at random. Default: density 0 (nobody).
    pub size: CrowdSize,
    /// People placed at these positions (world frame) before the random
    /// ones — someone standing on the goal, a group blocking a door. They
    /// must not overlap a wall, each other or the robot's start footprint
    /// (`keep_clear_m` does not apply). Default empty.
    pub positions: Vec<Vec2>,
    /// Radius of a person's disc, metres. Default 0.25.
    pub radius_m: f64,
    /// Mean preferred walking speed, m/s. Default 1.0.
    pub speed_mean_mps: f64,
    /// Standard deviation of the preferred speed across people, m/s (the
    /// draw is clamped to [0.2, 1.8] × the mean). Default 0.2.
    pub speed_sigma_mps: f64,
    /// Exhibits people walk between, world frame; empty: people wander.
    /// Default empty.
    pub waypoints: Vec<Vec2>,
    /// People aim at a random free point within this distance of the
    /// exhibit, metres. Default 1.0.
    pub gather_radius_m: f64,
    /// Wanderers pick targets within this distance, metres. Default 5.0.
    pub wander_radius_m: f64,
    /// A target counts as reached within this distance, metres. Default 0.5.
    pub arrival_tolerance_m: f64,
    /// Probability of lingering on reaching a target (and of starting the
    /// run lingering). Default 0.5.
    pub linger_probability: f64,
    /// Mean lingering time (exponential), seconds. Default 20.
    pub linger_mean_s: f64,
    /// A target not reached within this time is given up, seconds.
    /// Default 60.
    pub target_timeout_s: f64,
    /// A walking person who has moved less than their radius in this time
    /// gives up their target (stuck behind an obstacle), seconds. Default 5.
    pub stuck_timeout_s: f64,
    /// Relaxation time `τ` of the driving force, seconds. Default 0.5.
    pub relaxation_time_s: f64,
    /// Strength `A` of the repulsion between people, m/s². Default 2.0.
    pub person_repulsion_mps2: f64,
    /// Range `B` of the repulsion between people, metres. Default 0.3.
    pub person_range_m: f64,
    /// Strength of the repulsion from the robot, m/s² (0: people ignore the
    /// robot, but still never walk into it). Default 2.0.
    pub robot_repulsion_mps2: f64,
    /// People never step closer than this to the robot's footprint, metres
    /// (a person does not press against a machine; the robot's own small
    /// motions then do not count as bumping into someone standing by).
    /// Default 0.1.
    pub robot_clearance_m: f64,
    /// Strength `A_w` of the repulsion from walls, m/s². Default 5.0.
    pub wall_repulsion_mps2: f64,
    /// Range `B_w` of the repulsion from walls, metres. Default 0.1.
    pub wall_range_m: f64,
    /// Field-of-view weight `λ` in [0, 1] of people and robots behind a
    /// person (1: isotropic). Default 0.5.
    pub anisotropy: f64,
    /// Nobody is placed within this distance of the robot's footprint at
    /// the start, metres. Default 1.0.
    pub keep_clear_m: f64,
    /// Mean delay before a person asked to step aside moves, seconds
    /// (each draws uniformly in 0.5–1.5 × this). Default 1.0.
    pub step_aside_delay_s: f64,
    /// People asked to step aside walk to this far outside the request's
    /// radius, metres. Default 1.0.
    pub step_aside_distance_m: f64,
    /// Probability that a person asked to step aside does, in [0, 1].
    /// Default 1.0.
    pub step_aside_compliance: f64,
    /// Rate at which a person takes an interest in the robot and comes to
    /// see it, per second of simulated time (a Poisson process: each step
    /// of `Δt`, a person who may (module docs) does with probability
    /// `1 − exp(−rate Δt)`); 0: nobody ever does. Default 0.
    pub robot_interest_rate_per_s: f64,
    /// Only people within this distance of the robot's centre take an
    /// interest in it, and people coming to it or standing by it lose
    /// interest when it is farther, metres. Default 8.0.
    pub robot_interest_range_m: f64,
    /// People who come to see the robot stop when their centre is within
    /// this distance of the robot's centre and stand at this distance
    /// (for a robot too big for that, just outside `robot_clearance_m`),
    /// metres. Default 0.9.
    pub robot_gather_distance_m: f64,
    /// Mean time a person stands by the robot (exponential), seconds.
    /// Default 20.
    pub robot_linger_mean_s: f64,
}

impl Default for CrowdParams {
    fn default() -> CrowdParams {
        CrowdParams {
            size: CrowdSize::default(),
            positions: Vec::new(),
            radius_m: 0.25,
            speed_mean_mps: 1.0,
            speed_sigma_mps: 0.2,
            waypoints: Vec::new(),
            gather_radius_m: 1.0,
            wander_radius_m: 5.0,
            arrival_tolerance_m: 0.5,
            linger_probability: 0.5,
            linger_mean_s: 20.0,
            target_timeout_s: 60.0,
            stuck_timeout_s: 5.0,
            relaxation_time_s: 0.5,
            person_repulsion_mps2: 2.0,
            person_range_m: 0.3,
            robot_repulsion_mps2: 2.0,
            robot_clearance_m: 0.1,
            wall_repulsion_mps2: 5.0,
            wall_range_m: 0.1,
            anisotropy: 0.5,
            keep_clear_m: 1.0,
            step_aside_delay_s: 1.0,
            step_aside_distance_m: 1.0,
            step_aside_compliance: 1.0,
            robot_interest_rate_per_s: 0.0,
            robot_interest_range_m: 8.0,
            robot_gather_distance_m: 0.9,
            robot_linger_mean_s: 20.0,
        }
    }
}

impl CrowdParams {
    /// Checks every field.
    pub fn validate(&self) -> Result<()> {
        match self.size {
            CrowdSize::PerArea { people_per_100m2 } => {
                validate::non_negative("crowd.size.people_per_100m2", people_per_100m2)?
            }
            CrowdSize::Count { .. } => {}
        }
        validate::positive("crowd.radius_m", self.radius_m)?;
        validate::positive("crowd.speed_mean_mps", self.speed_mean_mps)?;
        validate::non_negative("crowd.speed_sigma_mps", self.speed_sigma_mps)?;
        for (k, w) in self.waypoints.iter().enumerate() {
            validate::point(&format!("crowd.waypoints[{k}]"), *w)?;
        }
        for (k, w) in self.positions.iter().enumerate() {
            validate::point(&format!("crowd.positions[{k}]"), *w)?;
        }
        validate::non_negative("crowd.gather_radius_m", self.gather_radius_m)?;
        validate::positive("crowd.wander_radius_m", self.wander_radius_m)?;
        validate::positive("crowd.arrival_tolerance_m", self.arrival_tolerance_m)?;
        validate::probability("crowd.linger_probability", self.linger_probability)?;
        validate::non_negative("crowd.linger_mean_s", self.linger_mean_s)?;
        validate::positive("crowd.target_timeout_s", self.target_timeout_s)?;
        validate::positive("crowd.stuck_timeout_s", self.stuck_timeout_s)?;
        validate::positive("crowd.relaxation_time_s", self.relaxation_time_s)?;
        validate::non_negative("crowd.person_repulsion_mps2", self.person_repulsion_mps2)?;
        validate::positive("crowd.person_range_m", self.person_range_m)?;
        validate::non_negative("crowd.robot_repulsion_mps2", self.robot_repulsion_mps2)?;
        validate::non_negative("crowd.robot_clearance_m", self.robot_clearance_m)?;
        validate::non_negative("crowd.wall_repulsion_mps2", self.wall_repulsion_mps2)?;
        validate::positive("crowd.wall_range_m", self.wall_range_m)?;
        validate::within("crowd.anisotropy", self.anisotropy, 0.0, 1.0, "in [0, 1]")?;
        validate::non_negative("crowd.keep_clear_m", self.keep_clear_m)?;
        validate::non_negative("crowd.step_aside_delay_s", self.step_aside_delay_s)?;
        validate::non_negative("crowd.step_aside_distance_m", self.step_aside_distance_m)?;
        validate::probability("crowd.step_aside_compliance", self.step_aside_compliance)?;
        validate::non_negative("crowd.robot_interest_rate_per_s", self.robot_interest_rate_per_s)?;
        validate::non_negative("crowd.robot_interest_range_m", self.robot_interest_range_m)?;
        validate::non_negative("crowd.robot_gather_distance_m", self.robot_gather_distance_m)?;
        validate::non_negative("crowd.robot_linger_mean_s", self.robot_linger_mean_s)
    }

    /// How many people this crowd places at random on a map with
    /// `free_area_m2` of free space (besides [`CrowdParams::positions`]).
    pub fn count(&self, free_area_m2: f64) -> usize {
        match self.size {
            CrowdSize::PerArea { people_per_100m2 } => {
                (people_per_100m2 * free_area_m2 / 100.0).round() as usize
            }
            CrowdSize::Count { people } => people,
        }
    }
}
