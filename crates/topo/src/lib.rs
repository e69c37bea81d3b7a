//! Topological maps as fuzzy Petri nets (`docs/topo-fpn.md`).
//!
//! The robot's map is built from what its control system does: every
//! reference place is where an obstacle made it abandon its strategy, and
//! every transition is the strategy that led from one reference place to the
//! next. Routes are planned by propagating values over the net.
//!
//! | module | what it does |
//! |---|---|
//! | [`fpn`] | the net `FPN = (P, T, D, I, O, f, λ, α, β)`: places, transitions, costs, thresholds learnt from failures, the JSON file |
//! | [`propagation`] | route planning: the spec's propagation literally (paper mode) and its fixed point by a label-setting search (optimal mode) |
//! | [`export`] | Graphviz DOT and PNML |
//! | [`generate`] | random office-like maps for tests and benchmarks |
//!
//! ```
//! use topo::{FuzzyPetriNet, Place, PlaceKind, PlanMode, Strategy, Transition, Turn, plan};
//!
//! let mut map = FuzzyPetriNet::new();
//! let door = map.add_place(Place::new(0.0, 0.0, 0.0, PlaceKind::A))?; // p1
//! let corner = map.add_place(Place::new(4.0, 0.0, 0.0, PlaceKind::B))?; // p2
//! let desk = map.add_place(Place::new(4.0, 3.0, 1.6, PlaceKind::C))?; // p3
//! // Straight across the room, round the table: one long detour…
//! map.add_transition(Transition::new(door, desk, Strategy::DetourLeft, Turn::Right, 40.0))?;
//! // …or along the walls, two quick transitions.
//! map.add_transition(Transition::new(door, corner, Strategy::WallFollowRight, Turn::Right, 8.0))?;
//! map.add_transition(Transition::new(corner, desk, Strategy::FreeMovement, Turn::Left, 6.0))?;
//!
//! let best = plan(&map, door, &[desk], PlanMode::Optimal)?;
//! let names: Vec<&str> = best.places.iter().map(|&p| map.place(p).name.as_str()).collect();
//! assert_eq!(names, ["p1", "p2", "p3"]);
//! // C(t) = c_t / Σ c_u: (14 + 7) / (51 + 14 + 7).
//! assert!((best.cost - 21.0 / 72.0).abs() < 1e-12);
//!
//! // The source's stopping rule takes the first route found: the fewest transitions.
//! let paper = plan(&map, door, &[desk], PlanMode::Paper)?;
//! assert_eq!(paper.route.len(), 1);
//! assert!(paper.cost > best.cost);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![warn(missing_docs)]

pub mod builder;
pub mod explore;
pub mod export;
pub mod fpn;
pub mod generate;
pub mod navigate;
pub mod propagation;
pub mod recognition;
pub mod ring;
pub mod situation;
pub mod strategy;
pub mod walker;

use std::path::PathBuf;

pub use builder::{Arrival, MapBuilder};
pub use explore::{Explorer, TopoParams, Visit, place_event};
pub use export::{to_dot, to_pnml};
pub use fpn::{
    FORMAT, FORMAT_VERSION, FuzzyPetriNet, Place, PlaceId, PlaceKind, Strategy, ThresholdParams, Transition,
    TransitionId, Turn, cost_of,
};
pub use generate::random_office_like;
pub use navigate::{NavLeg, NavState, NavStats, NavigateParams, RouteFollower};
pub use propagation::{Plan, PlanError, PlanMode, Planner, Propagation, Stop, plan, plan_by_name};
pub use recognition::{RecognitionParams, match_place};
pub use ring::{Echo, Ring, Side};
pub use situation::{Situation, SituationParams};
pub use strategy::{Action, Executor, Failure, Progress, StrategyParams, actions_at};
pub use walker::{Leg, Walker, WalkerStep};

/// `, near `…``, or nothing.
fn near_text(near: &Option<String>) -> String {
    near.as_ref().map(|n| format!(", near `{n}`")).unwrap_or_default()
}

/// What can go wrong with a map: building it, reading or writing it.
#[derive(Debug, thiserror::Error)]
pub enum TopoError {
    /// A parameter out of range (the message names it).
    #[error("{0}")]
    Params(String),
    /// A file could not be read or written.
    #[error("{}: {source}", .path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// What the system said.
        #[source]
        source: std::io::Error,
    },
    /// An error in a map file.
    #[error("{}: {error}", .path.display())]
    InFile {
        /// The file.
        path: PathBuf,
        /// The error.
        error: Box<TopoError>,
    },
    /// Text that is not JSON, or JSON that is not a map (a missing or
    /// unknown field, a value of the wrong type, a number out of range), or
    /// that stops early (a truncated file: the message says so).
    #[error("line {line}, column {column}: {message}{}", near_text(.near))]
    Json {
        /// Line, from 1.
        line: usize,
        /// Column, from 1 (in bytes; 0 at the end of an empty line).
        column: usize,
        /// What the JSON reader said.
        message: String,
        /// The text around the position, when it says something (at most
        /// 60 characters of the line; none for a file that stops early).
        near: Option<String>,
    },
    /// A file with no text (or only white space).
    #[error("the file is empty: expected a petrinav FPN map (JSON)")]
    Empty,
    /// JSON that is not an object.
    #[error(
        "not a petrinav FPN map: the file holds a JSON {found}, expected an object with \"format\": \"petrinav-fpn\""
    )]
    NotAnObject {
        /// `array`, `string`, `number`, `boolean` or `null`.
        found: &'static str,
    },
    /// A JSON file of something else.
    #[error("not a petrinav FPN map: \"format\" is {found}, expected \"petrinav-fpn\"")]
    Format {
        /// The `"format"` found, as JSON (`"gspn"`, `5`), or `(none)`.
        found: String,
    },
    /// A map file of a version this code does not read.
    #[error("FPN map file version {found}: this petrinav reads version 1")]
    Version {
        /// The `"version"` found (or `(none)`).
        found: String,
    },
    /// A place name that cannot be one.
    #[error("place {place} named {name:?}: {reason}")]
    BadName {
        /// The place's position (from 0).
        place: usize,
        /// The name.
        name: String,
        /// Why not.
        reason: &'static str,
    },
    /// Two places with one name.
    #[error("two places are named `{name}` (places {first} and {second}, from 0)")]
    DuplicateName {
        /// The name.
        name: String,
        /// The first place with it.
        first: usize,
        /// The second.
        second: usize,
    },
    /// A transition of a file naming a place the file does not have.
    #[error("transition t{transition}: `{end}` names no place: `{name}`")]
    UnknownPlaceName {
        /// The transition's position (from 0).
        transition: usize,
        /// `from` or `to`.
        end: &'static str,
        /// The name.
        name: String,
    },
    /// A transition with a place id the net does not have.
    #[error("transition t{transition}: `{end}` is place #{id}, but the net has {places} places")]
    UnknownPlaceId {
        /// The transition's position.
        transition: usize,
        /// `from` or `to`.
        end: &'static str,
        /// The id.
        id: u32,
        /// How many places the net has.
        places: usize,
    },
    /// A place id the net does not have.
    #[error("no place #{id}: the net has {places} places")]
    NoSuchPlace {
        /// The id.
        id: u32,
        /// How many places the net has.
        places: usize,
    },
    /// A transition id the net does not have.
    #[error("no transition t{id}: the net has {transitions} transitions")]
    UnknownTransition {
        /// The id.
        id: u32,
        /// How many transitions the net has.
        transitions: usize,
    },
    /// A number out of its range.
    #[error("{owner}: {field} = {value}: expected {expected}")]
    BadValue {
        /// The place or transition.
        owner: String,
        /// The field.
        field: &'static str,
        /// The value.
        value: f64,
        /// What is accepted.
        expected: &'static str,
    },
    /// More failures than attempts.
    #[error("{owner}: {failures} failures out of {attempts} attempts")]
    BadCounts {
        /// The transition.
        owner: String,
        /// Attempts.
        attempts: u32,
        /// Failures.
        failures: u32,
    },
    /// Wall following leaving a type (c) place.
    #[error(
        "{owner}: {strategy} cannot leave `{place}`, a place of type (c): where both turns are possible, wall following could loop forever"
    )]
    StrategyNotAllowed {
        /// The transition.
        owner: String,
        /// The origin place.
        place: String,
        /// The strategy.
        strategy: Strategy,
    },
    /// More places or transitions than ids can number.
    #[error("too many {what}")]
    TooMany {
        /// `places` or `transitions`.
        what: &'static str,
    },
    /// A parameter out of its range.
    #[error("{name} = {value}: expected {expected}")]
    BadParam {
        /// The parameter.
        name: &'static str,
        /// The value given.
        value: f64,
        /// What is accepted.
        expected: &'static str,
    },
    /// A plan made for another map.
    #[error("the plan was made for a map of {places} places and {transitions} transitions, not this one")]
    PlanMismatch {
        /// The plan's places.
        places: usize,
        /// The plan's transitions.
        transitions: usize,
    },
}
