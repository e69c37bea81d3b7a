//! The fuzzy Petri net of a topological map, `FPN = (P, T, D, I, O, f, λ, α, β)`
//! (`docs/topo-fpn.md`), and its JSON file format.
//!
//! * `P`: reference places ([`Place`]): where the robot had to abandon its
//!   strategy because of an obstacle in front, with the odometry pose, the
//!   type (a/b/c), whether the place has a concavity to recalibrate odometry,
//!   and the number of visits.
//! * `T`: transitions ([`Transition`]): a navigation strategy that drove the
//!   robot from one place to the next. `I` and `O` give every transition
//!   exactly one input place ([`Transition::from`]) and one output place
//!   ([`Transition::to`]).
//! * `D` and `β`: the proposition "the robot is at `p_i`" of every place, in
//!   bijection with the places; [`FuzzyPetriNet::proposition`] spells it out
//!   instead of storing one string per place.
//! * `λ`: the activation thresholds, stored per transition
//!   ([`Transition::lambda`]), learnt from failures
//!   ([`FuzzyPetriNet::record_attempt`]).
//! * `α` and `f`: the values of places and transitions. They are the result
//!   of route planning and are reset by every plan (step 1 of the
//!   propagation sets `α` from the goals), so they live in
//!   [`Plan`](super::Plan), not in the map.
//!
//! # Costs
//!
//! Every transition has a real cost `c_t > 0` ([`Transition::cost`]); its
//! weighted cost is `C(t) = c_t / Σ_u c_u`, the sum running over **all**
//! transitions of the net (the spec's decision), so any simple path costs at
//! most 1. [`cost_of`] is the default cost of a transition from its duration
//! and strategy.
//!
//! # File format
//!
//! JSON, versioned, every field required and no other field accepted:
//!
//! ```json
//! {
//!   "format": "petrinav-fpn",
//!   "version": 1,
//!   "places": [
//!     { "name": "p1", "x_m": 0.0, "y_m": 0.0, "heading_rad": 0.0,
//!       "kind": "a", "concave": true, "visits": 2 }
//!   ],
//!   "transitions": [
//!     { "from": "p1", "to": "p2", "strategy": "wall_follow_left",
//!       "exit_turn": "right", "duration_s": 12.5, "cost": 18.5,
//!       "lambda": 1.0, "attempts": 3, "failures": 0 }
//!   ]
//! }
//! ```
//!
//! Two fields came later and may be left out, so that files written before
//! them still read: a place's `"heading_aligned"` (default `false`) and a
//! transition's `"leave_heading_rad"` (the map heading it left its place
//! on; default none — and written only when recorded, so such a file also
//! writes back byte for byte).
//!
//! Transitions name their places; a transition's id is its position in the
//! list (from 0), a place's id its position in `places`. Reading checks
//! everything [`FuzzyPetriNet::add_place`] and
//! [`FuzzyPetriNet::add_transition`] check, and reports the first problem as
//! a [`TopoError`] naming the place or transition. Writing is exact:
//! numbers are written in their shortest form that reads back to the same
//! bits, so reading a written map gives the same map and writing it again
//! the same bytes.

use std::collections::HashMap;
use std::fmt;
use std::path::Path;

use serde::{Deserialize, Serialize};

use super::TopoError;

/// The `"format"` of an FPN map file.
pub const FORMAT: &str = "petrinav-fpn";
/// The `"version"` of the file format this code reads and writes.
pub const FORMAT_VERSION: u64 = 1;

/// Fixed part of every transition's default cost ([`cost_of`]): taking a
/// transition means switching behaviour at a reference place, which costs
/// the equivalent of 1 s even for a transition of no duration. Seconds.
pub const SWITCH_COST_S: f64 = 1.0;

/// A reference place, by its position in [`FuzzyPetriNet::places`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(transparent)]
pub struct PlaceId(pub u32);

impl PlaceId {
    /// The place's position in [`FuzzyPetriNet::places`].
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

/// A transition, by its position in [`FuzzyPetriNet::transitions`]. Shown as
/// `t0`, `t1`, …
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(transparent)]
pub struct TransitionId(pub u32);

impl TransitionId {
    /// The transition's position in [`FuzzyPetriNet::transitions`].
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

impl fmt::Display for TransitionId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "t{}", self.0)
    }
}

/// The type of a reference place: which way the robot can turn away from
/// the obstacle in front of it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum PlaceKind {
    /// (a) Only a right turn is possible; any strategy may continue.
    #[serde(rename = "a")]
    A,
    /// (b) Only a left turn is possible; any strategy may continue.
    #[serde(rename = "b")]
    B,
    /// (c) Both turns are possible; any strategy but wall following (it
    /// could loop forever) may continue.
    #[serde(rename = "c")]
    C,
}

impl PlaceKind {
    /// `a`, `b` or `c`, as in the file.
    pub fn letter(self) -> &'static str {
        match self {
            PlaceKind::A => "a",
            PlaceKind::B => "b",
            PlaceKind::C => "c",
        }
    }

    /// Whether a stop classified `other` can be a place of this type: the
    /// same type, or either is (c). A side whose free distance is near the
    /// threshold of "open" flips a classification between (a) or (b) and
    /// (c); (a) and (b) are mirror images and never one another.
    pub fn compatible(self, other: PlaceKind) -> bool {
        self == other || self == PlaceKind::C || other == PlaceKind::C
    }

    /// Whether a transition with `strategy` may leave a place of this type:
    /// wall following may not leave a type (c) place.
    pub fn allows(self, strategy: Strategy) -> bool {
        !(self == PlaceKind::C && strategy.is_wall_following())
    }
}

/// A direction of turn.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Turn {
    /// To the left.
    Left,
    /// To the right.
    Right,
    /// No turn.
    Straight,
}

impl Turn {
    /// `left`, `right` or `straight`, as in the file.
    pub fn name(self) -> &'static str {
        match self {
            Turn::Left => "left",
            Turn::Right => "right",
            Turn::Straight => "straight",
        }
    }

    /// The other way (left ↔ right; straight stays straight).
    pub fn mirrored(self) -> Turn {
        match self {
            Turn::Left => Turn::Right,
            Turn::Right => Turn::Left,
            Turn::Straight => Turn::Straight,
        }
    }
}

/// A navigation strategy: what drives the robot along a transition.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Strategy {
    /// Free movement (wander, go straight).
    FreeMovement,
    /// Wall following with the wall on the left.
    WallFollowLeft,
    /// Wall following with the wall on the right.
    WallFollowRight,
    /// Going round an obstacle by its left side.
    DetourLeft,
    /// Going round an obstacle by its right side.
    DetourRight,
}

impl Strategy {
    /// Every strategy, in the order of the enum.
    pub const ALL: [Strategy; 5] = [
        Strategy::FreeMovement,
        Strategy::WallFollowLeft,
        Strategy::WallFollowRight,
        Strategy::DetourLeft,
        Strategy::DetourRight,
    ];

    /// The name used in files (`free_movement`, `wall_follow_left`, …).
    pub fn name(self) -> &'static str {
        match self {
            Strategy::FreeMovement => "free_movement",
            Strategy::WallFollowLeft => "wall_follow_left",
            Strategy::WallFollowRight => "wall_follow_right",
            Strategy::DetourLeft => "detour_left",
            Strategy::DetourRight => "detour_right",
        }
    }

    /// Words for people (`wall following left`, …).
    pub fn label(self) -> &'static str {
        match self {
            Strategy::FreeMovement => "free movement",
            Strategy::WallFollowLeft => "wall following left",
            Strategy::WallFollowRight => "wall following right",
            Strategy::DetourLeft => "detour left",
            Strategy::DetourRight => "detour right",
        }
    }

    /// Whether this is wall following (either side).
    pub fn is_wall_following(self) -> bool {
        matches!(self, Strategy::WallFollowLeft | Strategy::WallFollowRight)
    }

    /// The side of a detour, `None` for the other strategies.
    pub fn detour_side(self) -> Option<Turn> {
        match self {
            Strategy::DetourLeft => Some(Turn::Left),
            Strategy::DetourRight => Some(Turn::Right),
            _ => None,
        }
    }

    /// The complexity penalty of the strategy in [`cost_of`], in the
    /// equivalent of seconds: free movement 0 s (one behaviour, nothing to
    /// track), wall following 5 s (a distance to keep, corners to take,
    /// the wall to lose), detour 10 s (leaving and regaining a heading round
    /// an obstacle whose extent is unknown: the most behaviours emerging on
    /// the way).
    pub fn complexity_s(self) -> f64 {
        match self {
            Strategy::FreeMovement => 0.0,
            Strategy::WallFollowLeft | Strategy::WallFollowRight => 5.0,
            Strategy::DetourLeft | Strategy::DetourRight => 10.0,
        }
    }
}

impl fmt::Display for Strategy {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.label())
    }
}

/// The default real cost `c_t` of a transition, combining the time it takes
/// and the complexity of the behaviours on the way:
///
/// `c_t = SWITCH_COST_S + duration_s + strategy.complexity_s()`
///
/// that is 1 s for the behaviour switch at the origin place
/// ([`SWITCH_COST_S`]), the duration, and 0 s (free movement), 5 s (wall
/// following) or 10 s (detour) ([`Strategy::complexity_s`]). Always > 0 for
/// a duration ≥ 0.
pub fn cost_of(duration_s: f64, strategy: Strategy) -> f64 {
    SWITCH_COST_S + duration_s + strategy.complexity_s()
}

/// A reference place.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Place {
    /// Unique name. Not empty, no control characters, no white space at
    /// either end. [`FuzzyPetriNet::add_place`] names a place without a
    /// name `p1`, `p2`, … after its position.
    pub name: String,
    /// Odometry position, x, metres.
    pub x_m: f64,
    /// Odometry position, y, metres.
    pub y_m: f64,
    /// Odometry heading when the place was detected, radians.
    pub heading_rad: f64,
    /// Which turns are possible there.
    pub kind: PlaceKind,
    /// Whether the place has a concavity usable to recalibrate odometry.
    pub concave: bool,
    /// Whether `heading_rad` was measured along a wall (wall following
    /// that ended there), so that it can recalibrate the heading.
    #[serde(default)]
    pub heading_aligned: bool,
    /// How many times the robot has been there.
    pub visits: u32,
}

impl Place {
    /// Whether a transition with `strategy` may leave this place: wall
    /// following may not leave a type (c) place, unless it is concave (a
    /// dead end, whose walls are one whole: no free-standing obstacle to
    /// loop round).
    pub fn allows(&self, strategy: Strategy) -> bool {
        self.concave || self.kind.allows(strategy)
    }

    /// A place without a name yet (named on [`FuzzyPetriNet::add_place`]),
    /// not concave, visited once.
    pub fn new(x_m: f64, y_m: f64, heading_rad: f64, kind: PlaceKind) -> Place {
        Place {
            name: String::new(),
            x_m,
            y_m,
            heading_rad,
            kind,
            concave: false,
            heading_aligned: false,
            visits: 1,
        }
    }
}

/// A transition `t_{i→j}`: the strategy that drove the robot from `p_i` to
/// `p_j`.
#[derive(Debug, Clone, PartialEq)]
pub struct Transition {
    /// The input place `p_i`.
    pub from: PlaceId,
    /// The output place `p_j`.
    pub to: PlaceId,
    /// The strategy run from `p_i`.
    pub strategy: Strategy,
    /// The direction the robot turned when leaving `p_i`.
    pub exit_turn: Turn,
    /// How long the strategy took to reach `p_j`, seconds (≥ 0).
    pub duration_s: f64,
    /// The real cost `c_t` (> 0, finite), in the equivalent of seconds;
    /// see [`cost_of`].
    pub cost: f64,
    /// The activation threshold `λ(t)` in `[0, 1]`: the transition is
    /// rejected when `f(t) > λ(t)`; 1 never rejects, 0 always does.
    pub lambda: f64,
    /// How many times the robot tried this transition while navigating.
    pub attempts: u32,
    /// How many of those attempts did not end at `p_j` (≤ `attempts`).
    pub failures: u32,
    /// The map heading the robot left `p_i` on — its heading at the end of
    /// the exit turn — when the transition was recorded (the circular mean
    /// over the traversals that found it again), radians. Navigation turns
    /// to it rather than by the exit turn's steps
    /// ([`super::navigate`]). `None`: not recorded (a map file written
    /// before it was).
    pub leave_heading_rad: Option<f64>,
}

impl Transition {
    /// A transition with the default cost [`cost_of`], `λ = 1`, never
    /// attempted.
    pub fn new(
        from: PlaceId,
        to: PlaceId,
        strategy: Strategy,
        exit_turn: Turn,
        duration_s: f64,
    ) -> Transition {
        Transition {
            from,
            to,
            strategy,
            exit_turn,
            duration_s,
            cost: cost_of(duration_s, strategy),
            lambda: 1.0,
            attempts: 0,
            failures: 0,
            leave_heading_rad: None,
        }
    }
}

/// How thresholds are learnt from failures ([`FuzzyPetriNet::record_attempt`]).
///
/// **Rule:** after every failed attempt, `λ(t) ← factor · λ(t)`; successes
/// leave `λ` as it is. A transition is rejected when
/// `f(t) = min(1, C(t) + α(p_j)) > λ(t)`. Since `C` normalises by the cost of
/// all transitions, `f` along a route of `k` transitions out of `n` is about
/// `k/n`, so with the default factor ½ a transition is first rejected after
/// about `log2(n/k)` failures (3 failures for 5-transition routes in a
/// 40-transition map), sooner for transitions far from the goal, which have
/// the most alternatives.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ThresholdParams {
    /// The factor applied to `λ` after each failure, in `[0, 1]`. Default 0.5.
    pub factor: f64,
}

impl Default for ThresholdParams {
    fn default() -> ThresholdParams {
        ThresholdParams { factor: 0.5 }
    }
}

impl ThresholdParams {
    /// Checks the factor.
    pub fn validate(&self) -> Result<(), TopoError> {
        if !(0.0..=1.0).contains(&self.factor) {
            return Err(TopoError::BadParam {
                name: "factor",
                value: self.factor,
                expected: "a number in [0, 1]",
            });
        }
        Ok(())
    }
}

/// A topological map as a fuzzy Petri net (see the module documentation).
///
/// Places and transitions are only added, never removed, so ids stay valid.
/// Every place and transition satisfies the checks of
/// [`add_place`](Self::add_place) and [`add_transition`](Self::add_transition)
/// at all times: the methods that change them check again.
#[derive(Debug, Clone, Default)]
pub struct FuzzyPetriNet {
    places: Vec<Place>,
    transitions: Vec<Transition>,
    /// Name → place.
    by_name: HashMap<String, PlaceId>,
    /// Transitions leaving each place, by increasing id.
    leaving: Vec<Vec<TransitionId>>,
    /// Transitions entering each place, by increasing id.
    entering: Vec<Vec<TransitionId>>,
    /// `Σ c_t` summed in id order.
    total_cost: f64,
}

impl PartialEq for FuzzyPetriNet {
    /// Same places and transitions, in the same order (the indexes follow).
    fn eq(&self, other: &FuzzyPetriNet) -> bool {
        self.places == other.places && self.transitions == other.transitions
    }
}

/// Why a name cannot name a place, if it cannot.
fn name_problem(name: &str) -> Option<&'static str> {
    if name.is_empty() {
        Some("a place name cannot be empty")
    } else if name
        .chars()
        .any(|c| c.is_control() || c == '\u{fffe}' || c == '\u{ffff}')
    {
        Some("a place name cannot contain control characters")
    } else if name.trim() != name {
        Some("a place name cannot begin or end with white space")
    } else {
        None
    }
}

fn finite(owner: impl Fn() -> String, field: &'static str, value: f64) -> Result<(), TopoError> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(TopoError::BadValue {
            owner: owner(),
            field,
            value,
            expected: "a finite number",
        })
    }
}

fn check_lambda(owner: impl Fn() -> String, lambda: f64) -> Result<(), TopoError> {
    if (0.0..=1.0).contains(&lambda) {
        Ok(())
    } else {
        Err(TopoError::BadValue {
            owner: owner(),
            field: "lambda",
            value: lambda,
            expected: "a threshold in [0, 1]",
        })
    }
}

fn check_cost(owner: impl Fn() -> String, cost: f64) -> Result<(), TopoError> {
    if cost.is_finite() && cost > 0.0 {
        Ok(())
    } else {
        Err(TopoError::BadValue {
            owner: owner(),
            field: "cost",
            value: cost,
            expected: "a finite cost > 0",
        })
    }
}

impl FuzzyPetriNet {
    /// An empty net.
    pub fn new() -> FuzzyPetriNet {
        FuzzyPetriNet::default()
    }

    /// The places, by id.
    pub fn places(&self) -> &[Place] {
        &self.places
    }

    /// The transitions, by id.
    pub fn transitions(&self) -> &[Transition] {
        &self.transitions
    }

    /// Number of places.
    pub fn num_places(&self) -> usize {
        self.places.len()
    }

    /// Number of transitions.
    pub fn num_transitions(&self) -> usize {
        self.transitions.len()
    }

    /// The place `id`.
    ///
    /// # Panics
    /// If the net has no place `id` (see [`get_place`](Self::get_place)).
    pub fn place(&self, id: PlaceId) -> &Place {
        &self.places[id.index()]
    }

    /// The place `id`, if the net has it.
    pub fn get_place(&self, id: PlaceId) -> Option<&Place> {
        self.places.get(id.index())
    }

    /// The transition `id`.
    ///
    /// # Panics
    /// If the net has no transition `id` (see
    /// [`get_transition`](Self::get_transition)).
    pub fn transition(&self, id: TransitionId) -> &Transition {
        &self.transitions[id.index()]
    }

    /// The transition `id`, if the net has it.
    pub fn get_transition(&self, id: TransitionId) -> Option<&Transition> {
        self.transitions.get(id.index())
    }

    /// The place named `name`. O(1).
    pub fn place_id(&self, name: &str) -> Option<PlaceId> {
        self.by_name.get(name).copied()
    }

    /// The place ids, in order.
    pub fn place_ids(&self) -> impl ExactSizeIterator<Item = PlaceId> + use<> {
        (0..self.places.len() as u32).map(PlaceId)
    }

    /// The transition ids, in order.
    pub fn transition_ids(&self) -> impl ExactSizeIterator<Item = TransitionId> + use<> {
        (0..self.transitions.len() as u32).map(TransitionId)
    }

    /// The transitions leaving `place` (its output transitions), by
    /// increasing id; empty for a place the net does not have.
    pub fn leaving(&self, place: PlaceId) -> &[TransitionId] {
        self.leaving.get(place.index()).map_or(&[], Vec::as_slice)
    }

    /// The transitions entering `place`, by increasing id; empty for a place
    /// the net does not have.
    pub fn entering(&self, place: PlaceId) -> &[TransitionId] {
        self.entering.get(place.index()).map_or(&[], Vec::as_slice)
    }

    /// The proposition `β(place)` of `D`: "the robot is at p3".
    ///
    /// # Panics
    /// If the net has no place `place`.
    pub fn proposition(&self, place: PlaceId) -> String {
        format!("the robot is at {}", self.place(place).name)
    }

    /// `Σ_u c_u` over all transitions, summed in id order (0 for a net
    /// without transitions). O(1).
    pub fn total_cost(&self) -> f64 {
        self.total_cost
    }

    /// The weighted cost `C(t) = c_t / Σ_u c_u`, the sum over all
    /// transitions. O(1).
    ///
    /// # Panics
    /// If the net has no transition `t`.
    pub fn weighted_cost(&self, t: TransitionId) -> f64 {
        self.transition(t).cost / self.total_cost
    }

    /// `C(t)` of every transition, by id. O(|T|).
    pub fn weighted_costs(&self) -> Vec<f64> {
        self.transitions
            .iter()
            .map(|t| t.cost / self.total_cost)
            .collect()
    }

    fn transition_owner(&self, id: usize, t: &Transition) -> String {
        let name = |p: PlaceId| {
            self.places
                .get(p.index())
                .map_or_else(|| format!("#{}", p.0), |p| p.name.clone())
        };
        format!("transition t{id} ({} → {})", name(t.from), name(t.to))
    }

    /// Adds a place and returns its id. A place with an empty name is named
    /// `p{k}` with `k` its position from 1 (`p{k}_2`, `p{k}_3`, … if that
    /// name is taken).
    ///
    /// Checks: the name is unique, not empty, without control characters
    /// or white space at either end; the position and heading are finite.
    pub fn add_place(&mut self, mut place: Place) -> Result<PlaceId, TopoError> {
        let index = self.places.len();
        if index >= u32::MAX as usize {
            return Err(TopoError::TooMany { what: "places" });
        }
        if place.name.is_empty() {
            let base = format!("p{}", index + 1);
            let mut name = base.clone();
            let mut k = 2;
            while self.by_name.contains_key(&name) {
                name = format!("{base}_{k}");
                k += 1;
            }
            place.name = name;
        }
        if let Some(reason) = name_problem(&place.name) {
            return Err(TopoError::BadName {
                place: index,
                name: place.name,
                reason,
            });
        }
        if let Some(first) = self.by_name.get(&place.name) {
            return Err(TopoError::DuplicateName {
                name: place.name,
                first: first.index(),
                second: index,
            });
        }
        let owner = || format!("place `{}`", place.name);
        finite(owner, "x_m", place.x_m)?;
        finite(owner, "y_m", place.y_m)?;
        finite(owner, "heading_rad", place.heading_rad)?;
        let id = PlaceId(index as u32);
        self.by_name.insert(place.name.clone(), id);
        self.places.push(place);
        self.leaving.push(Vec::new());
        self.entering.push(Vec::new());
        Ok(id)
    }

    /// Adds a transition and returns its id.
    ///
    /// Checks: both places exist; wall following does not leave a type (c)
    /// place; the duration is finite and ≥ 0; the cost is finite and > 0
    /// (and the sum of all costs stays finite); `λ ∈ [0, 1]`;
    /// `failures ≤ attempts`.
    pub fn add_transition(&mut self, t: Transition) -> Result<TransitionId, TopoError> {
        let index = self.transitions.len();
        if index >= u32::MAX as usize {
            return Err(TopoError::TooMany { what: "transitions" });
        }
        for (end, p) in [("from", t.from), ("to", t.to)] {
            if p.index() >= self.places.len() {
                return Err(TopoError::UnknownPlaceId {
                    transition: index,
                    end,
                    id: p.0,
                    places: self.places.len(),
                });
            }
        }
        let owner = || self.transition_owner(index, &t);
        let origin = &self.places[t.from.index()];
        if !origin.allows(t.strategy) {
            return Err(TopoError::StrategyNotAllowed {
                owner: owner(),
                place: origin.name.clone(),
                strategy: t.strategy,
            });
        }
        if !(t.duration_s.is_finite() && t.duration_s >= 0.0) {
            return Err(TopoError::BadValue {
                owner: owner(),
                field: "duration_s",
                value: t.duration_s,
                expected: "a finite duration ≥ 0",
            });
        }
        check_cost(owner, t.cost)?;
        let total = self.total_cost + t.cost;
        if !total.is_finite() {
            return Err(TopoError::BadValue {
                owner: owner(),
                field: "cost",
                value: t.cost,
                expected: "costs whose sum is finite",
            });
        }
        check_lambda(owner, t.lambda)?;
        if let Some(h) = t.leave_heading_rad {
            finite(owner, "leave_heading_rad", h)?;
        }
        if t.failures > t.attempts {
            return Err(TopoError::BadCounts {
                owner: owner(),
                attempts: t.attempts,
                failures: t.failures,
            });
        }
        let id = TransitionId(index as u32);
        self.leaving[t.from.index()].push(id);
        self.entering[t.to.index()].push(id);
        self.total_cost = total;
        self.transitions.push(t);
        Ok(id)
    }

    fn check_transition(&self, id: TransitionId) -> Result<(), TopoError> {
        if id.index() < self.transitions.len() {
            Ok(())
        } else {
            Err(TopoError::UnknownTransition {
                id: id.0,
                transitions: self.transitions.len(),
            })
        }
    }

    /// Sets the heading of `place` (finite, radians) and whether it was
    /// measured along a wall.
    pub fn set_heading(&mut self, place: PlaceId, heading_rad: f64, aligned: bool) -> Result<(), TopoError> {
        let places = self.places.len();
        let p = self
            .places
            .get_mut(place.index())
            .ok_or(TopoError::NoSuchPlace { id: place.0, places })?;
        if !heading_rad.is_finite() {
            return Err(TopoError::Params(format!(
                "place {}: heading {heading_rad} is not finite",
                p.name
            )));
        }
        p.heading_rad = robot::wrap_angle(heading_rad);
        p.heading_aligned = aligned;
        Ok(())
    }

    /// Counts one more visit of `place` (saturating).
    pub fn record_visit(&mut self, place: PlaceId) -> Result<(), TopoError> {
        let places = self.places.len();
        let p = self
            .places
            .get_mut(place.index())
            .ok_or(TopoError::NoSuchPlace { id: place.0, places })?;
        p.visits = p.visits.saturating_add(1);
        Ok(())
    }

    /// Sets the threshold `λ(t)`, which must be in `[0, 1]`.
    pub fn set_lambda(&mut self, t: TransitionId, lambda: f64) -> Result<(), TopoError> {
        self.check_transition(t)?;
        check_lambda(
            || self.transition_owner(t.index(), &self.transitions[t.index()]),
            lambda,
        )?;
        self.transitions[t.index()].lambda = lambda;
        Ok(())
    }

    /// Sets the heading transition `t` leaves its place on (finite,
    /// radians; wrapped to (−π, π]).
    pub fn set_leave_heading(&mut self, t: TransitionId, heading_rad: f64) -> Result<(), TopoError> {
        self.check_transition(t)?;
        finite(
            || self.transition_owner(t.index(), &self.transitions[t.index()]),
            "leave_heading_rad",
            heading_rad,
        )?;
        self.transitions[t.index()].leave_heading_rad = Some(robot::wrap_angle(heading_rad));
        Ok(())
    }

    /// Sets the duration of transition `t` (finite, ≥ 0), seconds.
    pub fn set_duration(&mut self, t: TransitionId, duration_s: f64) -> Result<(), TopoError> {
        self.check_transition(t)?;
        if !duration_s.is_finite() || duration_s < 0.0 {
            return Err(TopoError::BadValue {
                owner: self.transition_owner(t.index(), &self.transitions[t.index()]),
                field: "duration_s",
                value: duration_s,
                expected: "a finite duration ≥ 0",
            });
        }
        self.transitions[t.index()].duration_s = duration_s;
        Ok(())
    }

    /// Sets the real cost `c_t`, which must be finite and > 0 (with a finite
    /// sum over all transitions). O(|T|): the sum is recomputed in id order.
    pub fn set_cost(&mut self, t: TransitionId, cost: f64) -> Result<(), TopoError> {
        self.check_transition(t)?;
        let owner = || self.transition_owner(t.index(), &self.transitions[t.index()]);
        check_cost(owner, cost)?;
        let total = self
            .transitions
            .iter()
            .enumerate()
            .map(|(i, u)| if i == t.index() { cost } else { u.cost })
            .fold(0.0, |s, c| s + c);
        if !total.is_finite() {
            return Err(TopoError::BadValue {
                owner: owner(),
                field: "cost",
                value: cost,
                expected: "costs whose sum is finite",
            });
        }
        self.transitions[t.index()].cost = cost;
        self.total_cost = total;
        Ok(())
    }

    /// Lowers `λ(t)` after a failure: `λ ← factor · λ` (see
    /// [`ThresholdParams`]). Returns the new `λ`.
    pub fn lower_threshold(&mut self, t: TransitionId, params: &ThresholdParams) -> Result<f64, TopoError> {
        params.validate()?;
        self.check_transition(t)?;
        let tr = &mut self.transitions[t.index()];
        tr.lambda *= params.factor;
        Ok(tr.lambda)
    }

    /// Records an attempt of transition `t` while navigating: counts it, and
    /// on failure counts the failure and lowers `λ(t)`
    /// ([`lower_threshold`](Self::lower_threshold)). Returns the new `λ`.
    pub fn record_attempt(
        &mut self,
        t: TransitionId,
        success: bool,
        params: &ThresholdParams,
    ) -> Result<f64, TopoError> {
        params.validate()?;
        self.check_transition(t)?;
        let tr = &mut self.transitions[t.index()];
        tr.attempts = tr.attempts.saturating_add(1);
        if success {
            return Ok(tr.lambda);
        }
        // `attempts` saturates first, so `failures ≤ attempts` holds.
        tr.failures = tr.failures.saturating_add(1);
        self.lower_threshold(t, params)
    }

    // -----------------------------------------------------------------
    // Files
    // -----------------------------------------------------------------

    /// The map as JSON (pretty-printed, ending with a newline). Exact: see
    /// the module documentation.
    pub fn to_json(&self) -> String {
        let mut s = serde_json::to_string_pretty(&self.file_view())
            .expect("a map serialises: its numbers are finite and its keys strings");
        s.push('\n');
        s
    }

    /// Reads a map from JSON, checking everything (see the module
    /// documentation). A byte-order mark at the start is skipped.
    ///
    /// Errors say what is wrong and where: [`TopoError::Empty`] for a file
    /// without text, [`TopoError::NotAnObject`] for JSON that is not an
    /// object, [`TopoError::Format`]/[`TopoError::Version`] for another
    /// file, [`TopoError::Json`] (line, column and the text there) for text
    /// that is not JSON, is cut short or holds a value of the wrong type,
    /// and the errors of [`add_place`](Self::add_place) and
    /// [`add_transition`](Self::add_transition) naming the place or
    /// transition for values out of range.
    pub fn from_json(text: &str) -> Result<FuzzyPetriNet, TopoError> {
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        if text.trim().is_empty() {
            return Err(TopoError::Empty);
        }
        // The header first, leniently, so that another file is reported as
        // such rather than by its first unknown field.
        let (format, version) = match serde_json::from_str(text).map_err(|e| json_error(text, e))? {
            Header::Object { format, version } => (format, version),
            Header::Other(found) => return Err(TopoError::NotAnObject { found }),
        };
        match format {
            Some(serde_json::Value::String(f)) if f == FORMAT => {}
            found => {
                return Err(TopoError::Format {
                    found: found.map_or_else(|| "(none)".into(), |v| v.to_string()),
                });
            }
        }
        match version {
            Some(serde_json::Value::Number(n)) if n.as_u64() == Some(FORMAT_VERSION) => {}
            found => {
                return Err(TopoError::Version {
                    found: found.map_or_else(|| "(none)".into(), |v| v.to_string()),
                });
            }
        }
        let file: FileIn = serde_json::from_str(text).map_err(|e| json_error(text, e))?;
        FuzzyPetriNet::from_file(file)
    }

    /// Writes the map to `path` as JSON ([`to_json`](Self::to_json)).
    pub fn save(&self, path: impl AsRef<Path>) -> Result<(), TopoError> {
        let path = path.as_ref();
        std::fs::write(path, self.to_json()).map_err(|source| TopoError::Io {
            path: path.to_path_buf(),
            source,
        })
    }

    /// Reads a map from a JSON file ([`from_json`](Self::from_json)); errors
    /// name the file.
    pub fn load(path: impl AsRef<Path>) -> Result<FuzzyPetriNet, TopoError> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|source| TopoError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        FuzzyPetriNet::from_json(&text).map_err(|e| TopoError::InFile {
            path: path.to_path_buf(),
            error: Box::new(e),
        })
    }

    fn file_view(&self) -> FileOut<'_> {
        FileOut {
            format: FORMAT,
            version: FORMAT_VERSION,
            places: &self.places,
            transitions: self
                .transitions
                .iter()
                .map(|t| TransitionOut {
                    from: &self.places[t.from.index()].name,
                    to: &self.places[t.to.index()].name,
                    strategy: t.strategy,
                    exit_turn: t.exit_turn,
                    duration_s: t.duration_s,
                    cost: t.cost,
                    lambda: t.lambda,
                    attempts: t.attempts,
                    failures: t.failures,
                    leave_heading_rad: t.leave_heading_rad,
                })
                .collect(),
        }
    }

    fn from_file(file: FileIn) -> Result<FuzzyPetriNet, TopoError> {
        let mut net = FuzzyPetriNet::new();
        for p in file.places {
            if p.name.is_empty() {
                // Naming is for `add_place` callers; a file names its places.
                return Err(TopoError::BadName {
                    place: net.places.len(),
                    name: p.name,
                    reason: "a place name cannot be empty",
                });
            }
            net.add_place(p)?;
        }
        for (i, t) in file.transitions.into_iter().enumerate() {
            let find = |end: &'static str, name: &str| {
                net.place_id(name).ok_or_else(|| TopoError::UnknownPlaceName {
                    transition: i,
                    end,
                    name: name.to_string(),
                })
            };
            let (from, to) = (find("from", &t.from)?, find("to", &t.to)?);
            net.add_transition(Transition {
                from,
                to,
                strategy: t.strategy,
                exit_turn: t.exit_turn,
                duration_s: t.duration_s,
                cost: t.cost,
                lambda: t.lambda,
                attempts: t.attempts,
                failures: t.failures,
                leave_heading_rad: t.leave_heading_rad,
            })?;
        }
        Ok(net)
    }
}

/// A JSON reader's error as a [`TopoError::Json`]: the position, the
/// message without serde_json's own " at line … column …", a hint when the
/// text ends too early, and the text at the position.
fn json_error(text: &str, e: serde_json::Error) -> TopoError {
    let message = e.to_string();
    let suffix = format!(" at line {} column {}", e.line(), e.column());
    let mut message = message.strip_suffix(&suffix).unwrap_or(&message).to_string();
    let near = if e.is_eof() {
        message.push_str(": the text stops before the map is complete (a truncated file?)");
        None
    } else {
        text.lines()
            .nth(e.line().saturating_sub(1))
            .and_then(|line| snippet(line, e.column()))
    };
    TopoError::Json {
        line: e.line(),
        column: e.column(),
        message,
        near,
    }
}

/// At most [`SNIPPET_CHARS`] characters of `line` around byte `column` (from
/// 1), trimmed; `None` when they hold nothing but punctuation (`},`), which
/// says nothing.
fn snippet(line: &str, column: usize) -> Option<String> {
    let at = column.saturating_sub(1).min(line.len());
    let chars: Vec<(usize, char)> = line.char_indices().collect();
    let pos = chars.partition_point(|&(i, _)| i < at);
    let lo = pos.saturating_sub(SNIPPET_CHARS * 3 / 4);
    let hi = (lo + SNIPPET_CHARS).min(chars.len());
    let piece: String = chars[lo..hi].iter().map(|&(_, c)| c).collect();
    let piece = piece.trim();
    if !piece.chars().any(char::is_alphanumeric) {
        return None;
    }
    let (open, close) = (
        if lo > 0 { "…" } else { "" },
        if hi < chars.len() { "…" } else { "" },
    );
    Some(format!("{open}{piece}{close}"))
}

/// How much of a line [`TopoError::Json`] quotes.
const SNIPPET_CHARS: usize = 60;

impl Serialize for FuzzyPetriNet {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        self.file_view().serialize(serializer)
    }
}

impl<'de> Deserialize<'de> for FuzzyPetriNet {
    /// Checks as [`FuzzyPetriNet::from_json`] does, with the error as text.
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<FuzzyPetriNet, D::Error> {
        let file = FileIn::deserialize(deserializer)?;
        if file.format != FORMAT {
            return Err(serde::de::Error::custom(TopoError::Format {
                found: serde_json::Value::String(file.format).to_string(),
            }));
        }
        if file.version != FORMAT_VERSION {
            return Err(serde::de::Error::custom(TopoError::Version {
                found: file.version.to_string(),
            }));
        }
        FuzzyPetriNet::from_file(file).map_err(serde::de::Error::custom)
    }
}

/// The top of a map file: its `"format"` and `"version"`, whatever their
/// types, or what the JSON text is when it is not an object.
enum Header {
    Object {
        format: Option<serde_json::Value>,
        version: Option<serde_json::Value>,
    },
    /// `array`, `string`, `number`, `boolean` or `null`.
    Other(&'static str),
}

impl<'de> Deserialize<'de> for Header {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Header, D::Error> {
        deserializer.deserialize_any(HeaderVisitor)
    }
}

struct HeaderVisitor;

impl<'de> serde::de::Visitor<'de> for HeaderVisitor {
    type Value = Header;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("any JSON value")
    }

    fn visit_map<A: serde::de::MapAccess<'de>>(self, mut map: A) -> Result<Header, A::Error> {
        let (mut format, mut version) = (None, None);
        while let Some(key) = map.next_key::<String>()? {
            match key.as_str() {
                // A second one is reported as a duplicate field later.
                "format" if format.is_none() => format = Some(map.next_value()?),
                "version" if version.is_none() => version = Some(map.next_value()?),
                _ => {
                    map.next_value::<serde::de::IgnoredAny>()?;
                }
            }
        }
        Ok(Header::Object { format, version })
    }

    fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut seq: A) -> Result<Header, A::Error> {
        while seq.next_element::<serde::de::IgnoredAny>()?.is_some() {}
        Ok(Header::Other("array"))
    }

    fn visit_str<E>(self, _: &str) -> Result<Header, E> {
        Ok(Header::Other("string"))
    }

    fn visit_bool<E>(self, _: bool) -> Result<Header, E> {
        Ok(Header::Other("boolean"))
    }

    fn visit_i64<E>(self, _: i64) -> Result<Header, E> {
        Ok(Header::Other("number"))
    }

    fn visit_u64<E>(self, _: u64) -> Result<Header, E> {
        Ok(Header::Other("number"))
    }

    fn visit_f64<E>(self, _: f64) -> Result<Header, E> {
        Ok(Header::Other("number"))
    }

    fn visit_unit<E>(self) -> Result<Header, E> {
        Ok(Header::Other("null"))
    }
}

#[derive(Serialize)]
struct FileOut<'a> {
    format: &'static str,
    version: u64,
    places: &'a [Place],
    transitions: Vec<TransitionOut<'a>>,
}

#[derive(Serialize)]
struct TransitionOut<'a> {
    from: &'a str,
    to: &'a str,
    strategy: Strategy,
    exit_turn: Turn,
    duration_s: f64,
    cost: f64,
    lambda: f64,
    attempts: u32,
    failures: u32,
    #[serde(skip_serializing_if = "Option::is_none")]
    leave_heading_rad: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FileIn {
    format: String,
    version: u64,
    places: Vec<Place>,
    transitions: Vec<TransitionIn>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct TransitionIn {
    from: String,
    to: String,
    strategy: Strategy,
    exit_turn: Turn,
    duration_s: f64,
    cost: f64,
    lambda: f64,
    attempts: u32,
    failures: u32,
    #[serde(default)]
    leave_heading_rad: Option<f64>,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn two_places() -> FuzzyPetriNet {
        let mut net = FuzzyPetriNet::new();
        net.add_place(Place::new(0.0, 0.0, 0.0, PlaceKind::A)).unwrap();
        net.add_place(Place::new(3.0, 0.0, 0.0, PlaceKind::C)).unwrap();
        net
    }

    #[test]
    fn default_names_and_lookup() {
        let mut net = two_places();
        assert_eq!(net.place(PlaceId(0)).name, "p1");
        assert_eq!(net.place(PlaceId(1)).name, "p2");
        let mut named = Place::new(1.0, 1.0, 0.0, PlaceKind::B);
        named.name = "p4".into();
        net.add_place(named).unwrap();
        // The fourth place would be p4, which is taken.
        let id = net.add_place(Place::new(2.0, 2.0, 0.0, PlaceKind::B)).unwrap();
        assert_eq!(net.place(id).name, "p4_2");
        assert_eq!(net.place_id("p4"), Some(PlaceId(2)));
        assert_eq!(net.place_id("p9"), None);
        assert_eq!(net.proposition(PlaceId(1)), "the robot is at p2");
    }

    #[test]
    fn adjacency_and_weighted_costs() {
        let mut net = two_places();
        let a = net
            .add_transition(Transition::new(
                PlaceId(0),
                PlaceId(1),
                Strategy::WallFollowLeft,
                Turn::Right,
                10.0,
            ))
            .unwrap();
        let b = net
            .add_transition(Transition::new(
                PlaceId(1),
                PlaceId(0),
                Strategy::FreeMovement,
                Turn::Left,
                4.0,
            ))
            .unwrap();
        assert_eq!(net.leaving(PlaceId(0)), [a]);
        assert_eq!(net.entering(PlaceId(0)), [b]);
        assert_eq!(net.leaving(PlaceId(7)), []);
        assert_eq!(net.transition(a).cost, 16.0);
        assert_eq!(net.transition(b).cost, 5.0);
        assert_eq!(net.total_cost(), 21.0);
        assert_eq!(net.weighted_cost(a), 16.0 / 21.0);
        net.set_cost(b, 3.0).unwrap();
        assert_eq!(net.weighted_costs(), vec![16.0 / 19.0, 3.0 / 19.0]);
        assert!(net.set_cost(b, 0.0).is_err());
        assert!(net.set_cost(b, 0.75 * f64::MAX).is_ok());
        assert!(net.set_cost(a, 0.75 * f64::MAX).is_err(), "the sum overflows");
        assert_eq!(net.transition(a).cost, 16.0, "a refused cost leaves the old one");
        net.set_cost(b, 3.0).unwrap();
        assert_eq!(net.total_cost(), 19.0);
    }

    #[test]
    fn checks_on_add() {
        let mut net = two_places();
        let t = |s| Transition::new(PlaceId(1), PlaceId(0), s, Turn::Left, 1.0);
        // Wall following may not leave a type (c) place.
        let e = net.add_transition(t(Strategy::WallFollowRight)).unwrap_err();
        assert!(matches!(e, TopoError::StrategyNotAllowed { .. }), "{e}");
        net.add_transition(t(Strategy::DetourLeft)).unwrap();
        let mut bad = t(Strategy::FreeMovement);
        bad.to = PlaceId(5);
        assert!(matches!(
            net.add_transition(bad).unwrap_err(),
            TopoError::UnknownPlaceId { end: "to", id: 5, .. }
        ));
        let mut bad = t(Strategy::FreeMovement);
        bad.lambda = 1.5;
        assert!(matches!(
            net.add_transition(bad).unwrap_err(),
            TopoError::BadValue { field: "lambda", .. }
        ));
        let mut bad = t(Strategy::FreeMovement);
        bad.duration_s = f64::NAN;
        assert!(net.add_transition(bad).is_err());
        let mut bad = t(Strategy::FreeMovement);
        bad.failures = 1;
        assert!(matches!(
            net.add_transition(bad).unwrap_err(),
            TopoError::BadCounts { .. }
        ));
        let mut dup = Place::new(0.0, 0.0, 0.0, PlaceKind::A);
        dup.name = "p1".into();
        assert!(matches!(
            net.add_place(dup).unwrap_err(),
            TopoError::DuplicateName {
                first: 0,
                second: 2,
                ..
            }
        ));
        for name in [" p", "p\n", "a\u{7}b"] {
            let mut p = Place::new(0.0, 0.0, 0.0, PlaceKind::A);
            p.name = name.into();
            assert!(
                matches!(net.add_place(p).unwrap_err(), TopoError::BadName { .. }),
                "{name:?}"
            );
        }
        let mut p = Place::new(0.0, f64::INFINITY, 0.0, PlaceKind::A);
        p.name = "far".into();
        assert!(matches!(
            net.add_place(p).unwrap_err(),
            TopoError::BadValue { field: "y_m", .. }
        ));
        // Nothing failed half-way.
        assert_eq!((net.num_places(), net.num_transitions()), (2, 1));
        assert_eq!(net.place_id("far"), None);
    }

    #[test]
    fn thresholds_learn_from_failures() {
        let mut net = two_places();
        let t = net
            .add_transition(Transition::new(
                PlaceId(0),
                PlaceId(1),
                Strategy::FreeMovement,
                Turn::Right,
                1.0,
            ))
            .unwrap();
        let params = ThresholdParams::default();
        assert_eq!(net.record_attempt(t, true, &params).unwrap(), 1.0);
        assert_eq!(net.record_attempt(t, false, &params).unwrap(), 0.5);
        assert_eq!(net.record_attempt(t, false, &params).unwrap(), 0.25);
        let tr = net.transition(t);
        assert_eq!((tr.attempts, tr.failures, tr.lambda), (3, 2, 0.25));
        assert!(
            net.record_attempt(t, false, &ThresholdParams { factor: 1.5 })
                .is_err()
        );
        assert!(net.record_attempt(TransitionId(3), false, &params).is_err());
        assert!(net.set_lambda(t, -0.1).is_err());
        net.set_lambda(t, 1.0).unwrap();
        assert_eq!(net.transition(t).lambda, 1.0);
        net.record_visit(PlaceId(1)).unwrap();
        assert_eq!(net.place(PlaceId(1)).visits, 2);
        assert!(net.record_visit(PlaceId(9)).is_err());
    }

    #[test]
    fn bad_files_say_what_is_wrong() {
        let err = |text: &str| FuzzyPetriNet::from_json(text).unwrap_err();
        assert!(matches!(err(""), TopoError::Empty));
        assert!(matches!(err(" \n\t"), TopoError::Empty));
        for (text, found) in [
            ("[1, 2]", "array"),
            ("[]", "array"),
            ("\"map\"", "string"),
            ("3.5", "number"),
            ("true", "boolean"),
            ("null", "null"),
        ] {
            let e = err(text);
            assert!(
                matches!(e, TopoError::NotAnObject { found: f } if f == found),
                "{text}: {e}"
            );
        }
        let e = err(r#"{"format": 5, "version": 1}"#);
        assert_eq!(
            e.to_string(),
            "not a petrinav FPN map: \"format\" is 5, expected \"petrinav-fpn\""
        );
        let e = err(r#"{"format": "gspn"}"#);
        assert!(e.to_string().contains("\"format\" is \"gspn\""), "{e}");
        let e = err(r#"{"places": []}"#);
        assert!(e.to_string().contains("\"format\" is (none)"), "{e}");

        let mut net = two_places();
        net.add_transition(Transition::new(
            PlaceId(0),
            PlaceId(1),
            Strategy::FreeMovement,
            Turn::Right,
            2.0,
        ))
        .unwrap();
        let text = net.to_json();
        // Cut short: said so, wherever the cut.
        for cut in [1, text.len() / 3, text.len() / 2, text.len() - 3] {
            let e = err(&text[..cut]);
            assert!(
                matches!(&e, TopoError::Json { message, near: None, .. } if message.contains("truncated")),
                "cut at {cut}: {e}"
            );
        }
        // A string, NaN or a key of another kind where a number goes: the
        // error quotes the text there.
        let e = err(&text.replace("\"lambda\": 1.0", "\"lambda\": \"high\""));
        let m = e.to_string();
        assert!(m.contains("invalid type: string \"high\", expected f64"), "{m}");
        assert!(m.contains("near `\"lambda\": \"high\",`"), "{m}");
        let e = err(&text.replace("\"lambda\": 1.0", "\"lambda\": NaN"));
        assert!(e.to_string().contains("near `\"lambda\": NaN,`"), "{e}");
        let e = err(&text.replace("\"lambda\": 1.0", "\"lambda\": 1.0, \"alpha\": 0.5"));
        assert!(e.to_string().contains("unknown field `alpha`"), "{e}");
        // A minified file: a window round the position, not the whole line.
        let one_line = serde_json::to_string(&net).unwrap();
        let e = err(&one_line.replace("\"cost\":3.0", "\"cost\":true"));
        let TopoError::Json {
            line: 1,
            near: Some(near),
            ..
        } = &e
        else {
            panic!("{e}")
        };
        assert!(
            near.contains("\"cost\":true") && near.chars().count() <= 62,
            "{near}"
        );
        // A byte-order mark is skipped.
        assert_eq!(FuzzyPetriNet::from_json(&format!("\u{feff}{text}")).unwrap(), net);
    }

    #[test]
    fn json_round_trip() {
        let mut net = two_places();
        net.add_transition(Transition::new(
            PlaceId(0),
            PlaceId(1),
            Strategy::DetourRight,
            Turn::Straight,
            0.1,
        ))
        .unwrap();
        let text = net.to_json();
        let back = FuzzyPetriNet::from_json(&text).unwrap();
        assert_eq!(back, net);
        assert_eq!(back.to_json(), text);
        assert!(text.contains("\"strategy\": \"detour_right\""), "{text}");
        assert!(text.contains("\"kind\": \"c\""), "{text}");
        let via_serde: FuzzyPetriNet = serde_json::from_str(&text).unwrap();
        assert_eq!(via_serde, net);
        assert_eq!(serde_json::to_string_pretty(&net).unwrap() + "\n", text);
    }

    #[test]
    fn the_leaving_heading_is_optional_in_the_file() {
        let mut net = two_places();
        let t = net
            .add_transition(Transition::new(
                PlaceId(0),
                PlaceId(1),
                Strategy::FreeMovement,
                Turn::Left,
                3.0,
            ))
            .unwrap();
        // Not recorded: not written, so a file from before reads and writes
        // the same bytes.
        let old = net.to_json();
        assert!(!old.contains("leave_heading_rad"), "{old}");
        assert_eq!(
            FuzzyPetriNet::from_json(&old)
                .unwrap()
                .transition(t)
                .leave_heading_rad,
            None
        );
        // Recorded (wrapped to (−π, π]): written, read back exactly.
        net.set_leave_heading(t, 1.5 + std::f64::consts::TAU).unwrap();
        let h = net.transition(t).leave_heading_rad.unwrap();
        assert!((h - 1.5).abs() < 1e-12, "{h}");
        let text = net.to_json();
        assert!(text.contains("\"leave_heading_rad\""), "{text}");
        let back = FuzzyPetriNet::from_json(&text).unwrap();
        assert_eq!(back, net);
        assert_eq!(back.to_json(), text);
        // Not a number: an error naming the field.
        assert!(net.set_leave_heading(t, f64::NAN).is_err());
        let mut bad = Transition::new(PlaceId(0), PlaceId(1), Strategy::FreeMovement, Turn::Left, 3.0);
        bad.leave_heading_rad = Some(f64::INFINITY);
        let e = two_places().add_transition(bad).unwrap_err();
        assert!(e.to_string().contains("leave_heading_rad"), "{e}");
    }
}
