//! The galleries (`galleries.toml`, docs/tour-guide.md "The galleries"):
//! the second building of the tour-guide suite, where which behaviour gets
//! the robot to the next stop sooner depends on the place — two of the
//! tour's six legs have a service door 0.80 m wide on the straight line
//! between their stops, which AutoMove's planner refuses (its clearance
//! wants 0.85 m) and goes round through the corridor, and which contour
//! tracking passes at creep speed; the other four go through the corridor,
//! where contour tracking follows every wall of the galleries it crosses.
//!
//! **A campaign** is a museum day of [`TOURS`] tours of [`LEGS`] legs each
//! (a leg is a mission: one trip between two stops, with its own record);
//! each leg starts where the last one ended, the localizer from the last
//! one's estimate ([`crate::runs::mission`]'s tours: after a failed leg the
//! operator puts the robot at the stop it was heading for). The visitors
//! change by quarters of the day ([`VISITORS`]: the museum opens empty,
//! fills, is busiest at midday, empties), placed anew for every leg around
//! the exhibits. Leg `k` of campaign `c` has the same seed under every
//! strategy (common random numbers), so strategies are compared leg by leg,
//! and the hindsight oracle — per leg, the best fixed strategy on that leg
//! — is computed from the fixed strategies' records.
//!
//! **Strategies** ([`STRATEGIES`]): the four fixed ones of the museum;
//! `calibrate_then_commit`: the first tour with AutoMove alone, the second
//! with contour tracking alone (its calibration, counted in its cost like
//! any other tour), then on every leg the behaviour that was faster on it
//! in calibration (a failed leg counting the time limit; a tie to
//! AutoMove) followed by the rule; and `supervisor`, the crediting
//! supervisor learning per route and crowd from the day's earlier legs
//! (its exploration, too, is paid for by the legs it costs).

use anyhow::{Context, Result, bail};
use guide::Policy;
use guide::supervisor::Behaviour;
use robot::{Pose, Vec2};
use sim::World;
use sim::shapes::WorldSpec;

use crate::record::RunRecord;
use crate::runs::mission::{LegOutcome, Stop, Whereabouts};

/// The galleries, as shipped.
pub const GALLERIES: &str = include_str!("galleries.toml");

/// The condition's name (the scenarios' prefix).
pub const CONDITION: &str = "galleries";

/// Tours per campaign (a museum day).
pub const TOURS: u32 = 12;

/// Legs per tour.
pub const LEGS: u32 = 6;

/// Legs per campaign.
pub const CAMPAIGN_LEGS: u32 = TOURS * LEGS;

/// Visitors in the building during each quarter of the day's tours.
pub const VISITORS: [usize; 4] = [0, 25, 50, 25];

/// The strategies run in the galleries, in the report's order.
pub const STRATEGIES: [&str; 6] = [
    "automove",
    "automove_then_contour",
    "contour",
    "rule",
    "calibrate_then_commit",
    "supervisor",
];

/// The fixed strategies: what the hindsight oracle chooses from.
pub const FIXED: [&str; 4] = ["automove", "automove_then_contour", "contour", "rule"];

/// Time limit of a leg, seconds (what a failed leg costs).
pub const LEG_TIME_LIMIT_S: f64 = 300.0;

/// The building: its world with the visitors' parameters, the tour's
/// stops in order (the last one the first again) and where visitors
/// gather.
#[derive(Debug, Clone)]
pub struct Galleries {
    /// The world (grid and crowd parameters; visitors are placed per leg).
    pub world: World,
    /// The tour's stops, in order; the tour ends where it began.
    pub stops: Vec<Stop>,
    /// Where visitors gather.
    pub exhibits: Vec<Vec2>,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct File {
    #[allow(dead_code)]
    name: String,
    tour: Vec<String>,
    world: WorldSpec,
    place: Vec<PlaceSpec>,
    exhibit: Vec<ExhibitSpec>,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct PlaceSpec {
    name: String,
    pose: [f64; 3],
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct ExhibitSpec {
    at: [f64; 2],
}

/// The galleries as shipped ([`GALLERIES`]).
pub fn galleries() -> Result<Galleries> {
    parse(GALLERIES, "galleries.toml")
}

/// A galleries file: the world, the places, the tour through them, the
/// exhibits. Errors name the file and what is wrong.
pub fn parse(text: &str, name: &str) -> Result<Galleries> {
    let file: File = toml::from_str(text).with_context(|| name.to_string())?;
    let grid = file.world.rasterise().with_context(|| name.to_string())?;
    let exhibits: Vec<Vec2> = file.exhibit.iter().map(|e| Vec2::new(e.at[0], e.at[1])).collect();
    let mut stops = Vec::with_capacity(file.tour.len());
    for t in &file.tour {
        let p = file
            .place
            .iter()
            .find(|p| &p.name == t)
            .with_context(|| format!("{name}: the tour's stop `{t}` is not a [[place]]"))?;
        stops.push(Stop {
            name: p.name.clone(),
            pose: Pose::new(p.pose[0], p.pose[1], p.pose[2]),
        });
    }
    if stops.len() != LEGS as usize + 1 || stops.first().map(|s| &s.name) != stops.last().map(|s| &s.name) {
        bail!(
            "{name}: the tour must visit {LEGS} legs and end where it began, got {} stops",
            stops.len()
        );
    }
    let world = World::new(grid).with_crowd(sim::CrowdParams {
        waypoints: exhibits.clone(),
        gather_radius_m: 1.2,
        linger_probability: 0.7,
        linger_mean_s: 30.0,
        robot_interest_rate_per_s: super::ROBOT_INTEREST_RATE_PER_S,
        ..sim::CrowdParams::default()
    })?;
    Ok(Galleries {
        world,
        stops,
        exhibits,
    })
}

/// The tour (from 0) and leg (from 0) of a campaign's leg `k`.
pub fn tour_leg(k: u32) -> (u32, u32) {
    (k / LEGS, k % LEGS)
}

/// Visitors during tour `t` (from 0).
pub fn visitors_at(t: u32) -> usize {
    VISITORS[((t * 4) / TOURS).min(3) as usize]
}

/// A leg's route: `from → to`, the context the supervisor learns per.
pub use crate::runs::mission::route_name;

/// What a galleries leg's record keeps for the next: where the robot is,
/// and the leg's entry of the mission log.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct LegState {
    /// Where the next leg starts (the operator's place after a failure).
    pub at: Whereabouts,
    /// The leg as the mission log keeps it.
    pub entry: guide::supervisor::log::Entry,
}

impl LegState {
    /// The state an earlier record carries.
    pub fn of(r: &RunRecord) -> Result<LegState> {
        let state = r.state.clone().context("an earlier leg without its state")?;
        serde_json::from_value(state).context("the state of an earlier leg")
    }
}

/// What a leg cost, seconds: its time when it reached its stop, the time
/// limit otherwise.
pub fn leg_cost_s(r: &RunRecord) -> f64 {
    if r.success { r.time_s } else { LEG_TIME_LIMIT_S }
}

/// The behaviour calibrate-then-commit starts leg `leg` of the tour with:
/// the one that was cheaper on it in calibration (tour 0 AutoMove alone,
/// tour 1 contour tracking alone), a tie to AutoMove.
pub fn committed(earlier: &[RunRecord], leg: u32) -> Result<Behaviour> {
    let cost = |tour: u32| -> Result<f64> {
        let k = (tour * LEGS + leg) as usize;
        earlier
            .get(k)
            .map(leg_cost_s)
            .with_context(|| format!("calibration leg {k} missing"))
    };
    Ok(if cost(1)? < cost(0)? {
        Behaviour::Contour
    } else {
        Behaviour::AutoMove
    })
}

/// The policy of leg `k` of a fixed strategy or of calibrate-then-commit.
pub fn fixed_policy(strategy: &str, k: u32, earlier: &[RunRecord]) -> Result<Policy> {
    let (t, leg) = tour_leg(k);
    Ok(match strategy {
        "automove" => Policy::Fixed(Behaviour::AutoMove),
        "contour" => Policy::Fixed(Behaviour::Contour),
        "automove_then_contour" => Policy::AutoMoveThenContour,
        "rule" => Policy::Rule,
        "calibrate_then_commit" => match t {
            0 => Policy::Fixed(Behaviour::AutoMove),
            1 => Policy::Fixed(Behaviour::Contour),
            _ => Policy::StartThenRule(committed(earlier, leg)?),
        },
        other => bail!("no galleries strategy `{other}`"),
    })
}

/// Where leg `k` starts: at the first stop for the first leg, else where
/// the last one left the robot.
pub fn start_of(galleries: &Galleries, k: u32, earlier: &[RunRecord]) -> Result<Whereabouts> {
    if k == 0 {
        return Ok(Whereabouts::at(&galleries.stops[0]));
    }
    let last = earlier
        .get(k as usize - 1)
        .context("a galleries leg without the one before")?;
    Ok(LegState::of(last)?.at)
}

/// Whether a leg's record reached its stop (for the oracle: a leg not
/// reached costs the time limit).
pub fn reached(r: &RunRecord) -> bool {
    r.outcome == crate::runs::mission::outcome_name(LegOutcome::Reached)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_shipped_galleries_have_a_closed_tour_of_six_legs_through_free_places() {
        let g = galleries().unwrap();
        assert_eq!(g.stops.len(), 7);
        assert_eq!(g.stops[0].name, g.stops[6].name);
        for s in &g.stops {
            assert!(!g.world.grid().disc_blocked(s.pose.position(), 0.8), "{}", s.name);
        }
        assert_eq!(g.exhibits.len(), 15);
        assert_eq!(route_name("a", "b"), "a → b");
        assert_eq!(tour_leg(13), (2, 1));
        assert_eq!(
            (visitors_at(0), visitors_at(3), visitors_at(6), visitors_at(11)),
            (0, 25, 50, 25)
        );
    }

    #[test]
    fn a_bad_galleries_file_is_refused_with_its_name() {
        let bad = GALLERIES.replace("\"south_1\", \"north_1\"]", "\"nowhere\", \"north_1\"]");
        let e = parse(&bad, "g.toml").unwrap_err().to_string();
        assert!(e.contains("g.toml") && e.contains("nowhere"), "{e}");
    }

    #[test]
    fn calibrate_then_commit_starts_each_leg_with_the_cheaper_behaviour_of_its_calibration() {
        let rec = |success: bool, time_s: f64| RunRecord {
            success,
            outcome: if success { "goal" } else { "time_limit" }.into(),
            time_s,
            path_length_m: 0.0,
            collisions: 0,
            min_clearance_m: 0.0,
            odometry_error_m: 0.0,
            goal_distance_m: 0.0,
            ticks: 0,
            behaviour_ticks: Default::default(),
            metrics: Default::default(),
            events: Vec::new(),
            start: [0.0; 3],
            trap: None,
            state: None,
        };
        let mut earlier: Vec<RunRecord> = (0..2 * LEGS).map(|_| rec(true, 50.0)).collect();
        // Leg 1: contour faster; leg 2: contour failed (costs the limit).
        earlier[(LEGS + 1) as usize] = rec(true, 30.0);
        earlier[(LEGS + 2) as usize] = rec(false, 20.0);
        assert_eq!(committed(&earlier, 0).unwrap(), Behaviour::AutoMove);
        assert_eq!(committed(&earlier, 1).unwrap(), Behaviour::Contour);
        assert_eq!(committed(&earlier, 2).unwrap(), Behaviour::AutoMove);
        assert!(matches!(
            fixed_policy("calibrate_then_commit", 2 * LEGS + 1, &earlier).unwrap(),
            Policy::StartThenRule(Behaviour::Contour)
        ));
        assert!(committed(&earlier[..LEGS as usize], 0).is_err());
    }
}
