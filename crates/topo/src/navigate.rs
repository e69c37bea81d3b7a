//! Navigating with the map: from a known reference place to one of several
//! goal places, transition by transition (docs/topo-fpn.md, "Navigating with the
//! map").
//!
//! At the start the robot stands at the start place (its map pose is set to
//! the place's). Then, at every place:
//!
//! 1. plan from here to the goals (propagation, [`PlanMode`] of the
//!    parameters) and play the first transition of the route: its exit
//!    turn, then its strategy until the next reference place. The exit
//!    turn turns to the map heading the transition left on when it was
//!    recorded ([`Transition::leave_heading_rad`](super::Transition),
//!    [`super::Executor::aiming`]), not by the turn's 90° steps from
//!    wherever the robot happens to face;
//! 2. on arrival, recognise the place. The expected destination: the
//!    transition succeeded. Anywhere else (a known place or a new one): it
//!    failed — its attempt is counted, its threshold `λ(t)` lowered
//!    ([`FuzzyPetriNet::record_attempt`], rule in [`ThresholdParams`]), and
//!    what really happened is added to the map as a transition of its own
//!    (the map is updated as the robot goes); then plan again from here;
//! 3. a goal place recognised: done ([`robot::Step::Done`]).
//!
//! A planned transition between two places **on one spot** (map positions
//! within the recognition's base tolerance: a corner recorded facing one
//! wall and then the other) is played as a turn in place to the
//! destination's heading, then straight on to the obstacle if it is not
//! already ahead ([`super::Executor::facing`]); its strategy replayed would
//! test whether a way 0.5–0.9 m wide counts as free, a margin of a few
//! centimetres.
//!
//! A transition that ends **twice at the same wrong place** on one route
//! is rejected (`λ = 0`, [`NavigateParams::reject_repeated`]): a replay
//! that reproduces its outcome will do so again, and λ's halving alone
//! rejects a transition near the goal (whose `f` is only its own cost)
//! after four or five failures. A way back (below) that ends twice at one
//! wrong place is not borrowed again on the route.
//!
//! No route from a place (a place just added, or every way rejected):
//!
//! 1. plan again with the thresholds lowered on **earlier routes**
//!    restored ([`NavigateParams::retry_rejected`]; those rejected on this
//!    route stay rejected): a rejected transition that is the only known
//!    way is worth trying again before wandering off the net;
//! 2. **a way back onto the net** — if the robot stands on the spot of a
//!    known place that has a route (within the recognition's distance
//!    tolerance of its map position, whatever the heading or type: a
//!    corner reached from another side), play that place's first
//!    transition from here, expecting its destination; the leg is recorded
//!    as a transition of the place the robot is at;
//! 3. **back the way it came** ([`NavigateParams::retrace`]): if the
//!    place is new and the leg that led there was planned (a transition
//!    that ended off the net), undo that leg — turn about (to the heading
//!    opposite the one the robot stopped on) and play its strategy
//!    mirrored: wall following on the other side follows the same wall
//!    back, free movement goes straight back. It leads to the spot of the
//!    place the leg left, where the way back (2) finds a route. Only from
//!    a place whose type allows the strategy (no wall following from a
//!    (c) place), never after a detour or a turn on the spot, and once
//!    per new place;
//! 4. **homing** ([`NavigateParams::homing`]): head for the map position
//!    of the nearest goal place — along the free heading (a transducer's
//!    axis the ring sees clear) nearest its bearing if one is within 67.5°
//!    of it, otherwise round what blocks the bearing by a detour back to
//!    it (a Bug-like boundary following, [`super::Executor::homing`]), on a
//!    side drawn once per route and changed when a homing leg ended no
//!    nearer the goal than it began. The leg ends at the next obstacle, on
//!    reaching the point, or — driving straight on, not rounding an
//!    obstacle — once 0.25 m farther from the point than the nearest it
//!    came, if that was nearer than any homing leg came before on the
//!    route ([`NavigateParams::homing_stop_past`]: along a free heading
//!    that is not the bearing the robot passes the point's closest
//!    approach, and going on only leads away; "nearer than before" keeps
//!    two legs from passing the point back and forth). It records no
//!    transition (its course depends on where it started, not on a
//!    strategy that could be replayed);
//! 5. on the goal's spot already (within the base tolerance), or without
//!    homing: an action not yet tried from the place, as the explorer
//!    would, and plan again from wherever it leads.
//!
//! A stop on a **goal's spot** (map position within the recognition's base
//! tolerance of the goal's) that is not recognised as the goal — the robot
//! faces another way — turns to the goal's heading, goes on to the
//! obstacle if it is not already ahead, and recognises the place again
//! ([`NavigateParams::face_goals`]; plain recognition, without the
//! expected place's extra tolerance).
//!
//! A failed leg (timeout) counts as a failed attempt, and the robot drives
//! straight to the next obstacle. More than [`NavigateParams::max_legs`]
//! legs: give up.
//!
//! **Why a replayed transition ends elsewhere.** Recognition is rarely the
//! cause; the driving is. A place covers several stops (the two ends of a
//! corridor hold a stop against either wall), and a stop reached while
//! arcing round a door jamb is marginal: the same action from the same pose
//! passes the door in one replay and stops on the jamb in the next. The
//! decisions above — the recorded leaving heading, the way back, retracing,
//! homing toward the goal, rejection after two equal wrong ends — each
//! answer one of these failure modes; what still limits the routes is a
//! door jamb met differently on replay, which leaves the robot in a room
//! the map does not know.
//!
//! Rejected (on the `topo` suite; figures and commands in
//! `crates/topo/EXPERIMENTS.md`, section `navigate.rs`):
//!
//! - heading from a place without a route towards the nearest place the
//!   map can route from, or toward the last place a planned route left,
//!   instead of homing toward the goal, because routes arrived less often;
//! - replaying the exit turn by its recorded steps (90°, 180°, 270°),
//!   because the stops' headings spread by tens of degrees;
//! - the exit turn's `clear_m` at 1.3 m, because the explorations changed
//!   and fewer of their nets were connected;
//! - planning on costs divided by each transition's reliability, because
//!   the failures come from transitions tried once or twice, whose
//!   estimate says little;
//! - recognising a stop only where its side walls agree, because one corner
//!   is reached at different distances from its walls by different
//!   strategies (recall fell by a third);
//! - following the wall on the closed side instead of an untried action,
//!   because in a room the map does not know the walls lead round the room
//!   as often as out of it;
//! - leaving out of the rest of a route every transition that already
//!   failed on it (or avoiding them only while another route is known),
//!   because with fewer ways left the robot more often has no route and
//!   wanders;
//! - ignoring echoes on an arc's outer side, a spot of 0.6 m around a goal,
//!   the wall follower's side distance from 67.5°, flipping homing's side
//!   on revisiting a place, and the explorer leaving on the recorded heading
//!   too, because none did better and most did worse on one of the worlds;
//! - homing along free headings up to 87° off the bearing, stopping a
//!   homing leg abeam of the point, leaving by an untried action after two
//!   equal homing ends, and retracing legs that end at a known place,
//!   because none beat the rules above.

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use robot::{Command, Controller, Event, Notes, Perception, Step};

use super::TopoError;
use super::builder::Arrival;
use super::builder::MapBuilder;
use super::explore::{TopoParams, Visit, place_event};
use super::fpn::{FuzzyPetriNet, PlaceId, Strategy, ThresholdParams, TransitionId, Turn};
use super::propagation::{Plan, PlanMode, plan};
use super::strategy::Failure;
use super::strategy::{Action, actions_at};
use super::walker::{Leg, Walker, WalkerStep};

/// Parameters of navigation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NavigateParams {
    /// Driving and mapping.
    pub topo: TopoParams,
    /// How routes are planned. Default optimal.
    pub mode: PlanMode,
    /// How thresholds drop after failures.
    pub thresholds: ThresholdParams,
    /// Legs before giving up. Default 40.
    pub max_legs: u32,
    /// Head for the nearest goal place's map position when there is no
    /// route from here and no way back onto the net (module docs).
    /// Default true.
    pub homing: bool,
    /// A planned leg that ended at a new place (off the net) is undone
    /// first: turn about and play its strategy mirrored, back the way it
    /// came (module docs). Default true.
    pub retrace: bool,
    /// A homing leg also stops once past the point's closest approach
    /// along its line ([`super::Walker::start_homing`], module docs).
    /// Default true.
    pub homing_stop_past: bool,
    /// Reject a transition (λ = 0) that ended at the same wrong place
    /// twice on a route (module docs). Default true.
    pub reject_repeated: bool,
    /// On the spot of a goal place but facing another way: turn to the
    /// goal's heading and look again (module docs). Default true.
    pub face_goals: bool,
    /// Play a planned transition between two places on one spot (map
    /// positions within the recognition's base tolerance) as a turn in
    /// place to the destination's heading (module docs). Default true.
    pub turn_on_spot: bool,
    /// With no route, plan again with the thresholds lowered on earlier
    /// routes restored (module docs). Default true.
    pub retry_rejected: bool,
}

impl Default for NavigateParams {
    fn default() -> NavigateParams {
        NavigateParams {
            topo: TopoParams::default(),
            mode: PlanMode::Optimal,
            thresholds: ThresholdParams::default(),
            max_legs: 40,
            homing: true,
            retrace: true,
            homing_stop_past: true,
            reject_repeated: true,
            face_goals: true,
            turn_on_spot: true,
            retry_rejected: true,
        }
    }
}

/// One leg of a navigation.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct NavLeg {
    /// The stop it ended with.
    pub visit: Visit,
    /// The transition planned for it (`None`: no route, or after a failed
    /// leg).
    pub planned: Option<TransitionId>,
    /// It ended where planned.
    pub as_planned: bool,
}

/// Counts of a navigation.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct NavStats {
    /// Legs played (transitions taken, planned or not).
    pub legs: u32,
    /// Legs that ended where planned.
    pub as_planned: u32,
    /// Plans made again after arriving elsewhere.
    pub replans: u32,
    /// Legs that failed (timeout, no way out).
    pub failed_legs: u32,
    /// Places with no route to the goals.
    pub no_route: u32,
    /// Of those, places left by a way back onto the net (a nearby known
    /// place's transition).
    pub ways_back: u32,
    /// Of those, places left heading for the nearest goal's map position.
    pub homings: u32,
    /// Of those, new places left back the way the planned leg came.
    pub retraces: u32,
    /// Turns in place to a goal's heading on its spot.
    pub facings: u32,
    /// Planned transitions played as a turn on the spot.
    pub turns_on_spot: u32,
}

/// How a navigation stands.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum NavState {
    /// On the way.
    Going,
    /// A goal place recognised.
    Arrived,
    /// Too many legs.
    GaveUp,
}

/// The route-following controller (module docs).
#[derive(Debug)]
pub struct RouteFollower {
    walker: Walker,
    params: NavigateParams,
    start: PlaceId,
    goals: Vec<PlaceId>,
    expected: Option<TransitionId>,
    /// The expected transition leaves another place (a way back).
    borrowed: bool,
    state: NavState,
    started: bool,
    first_plan: Option<Plan>,
    legs: Vec<NavLeg>,
    stats: NavStats,
    rng: ChaCha8Rng,
    /// The side homing goes round obstacles on, once chosen.
    homing_side: Option<Turn>,
    /// The distance to the homing target when the last homing leg began.
    homing_from_m: Option<f64>,
    /// The nearest homing legs came to their point on this route, metres.
    homing_nearest_m: f64,
    /// The leg being played is a homing leg.
    homing_leg: bool,
    /// The way back from the new place a planned leg just ended at: the
    /// place, the mirrored action and the map heading to leave on.
    retrace: Option<(PlaceId, Action, f64)>,
    /// Where each transition that failed on this route last ended.
    wrong_ends: std::collections::BTreeMap<(TransitionId, bool), PlaceId>,
    /// Transitions not to borrow again on this route (a way back that
    /// ended twice at one wrong place).
    no_borrow: std::collections::BTreeSet<TransitionId>,
    /// The leg being played is a turn to a goal's heading.
    facing: bool,
    /// Transitions rejected on this route (ended twice at one wrong place).
    rejected_here: std::collections::BTreeSet<TransitionId>,
    error: Option<TopoError>,
}

impl RouteFollower {
    /// Navigation on `map` from `start` to any of `goals`; `seed` drives
    /// the choices when there is no route.
    pub fn new(
        map: FuzzyPetriNet,
        start: PlaceId,
        goals: &[PlaceId],
        params: NavigateParams,
        seed: u64,
    ) -> Result<RouteFollower, TopoError> {
        params.thresholds.validate()?;
        for &p in std::iter::once(&start).chain(goals) {
            if map.get_place(p).is_none() {
                return Err(TopoError::NoSuchPlace {
                    id: p.0,
                    places: map.num_places(),
                });
            }
        }
        if goals.is_empty() {
            return Err(TopoError::Params(
                "navigation needs at least one goal place".into(),
            ));
        }
        let builder = MapBuilder::with_map(map, params.topo.recognition)?;
        Ok(RouteFollower {
            walker: Walker::new(builder, params.topo.strategy, params.topo.situation)?,
            params,
            start,
            goals: goals.to_vec(),
            expected: None,
            borrowed: false,
            state: NavState::Going,
            started: false,
            first_plan: None,
            legs: Vec::new(),
            stats: NavStats::default(),
            rng: ChaCha8Rng::seed_from_u64(seed),
            homing_side: None,
            homing_from_m: None,
            homing_nearest_m: f64::INFINITY,
            homing_leg: false,
            retrace: None,
            wrong_ends: std::collections::BTreeMap::new(),
            no_borrow: std::collections::BTreeSet::new(),
            facing: false,
            rejected_here: std::collections::BTreeSet::new(),
            error: None,
        })
    }

    /// The map as it is now (updated on the way).
    pub fn map(&self) -> &FuzzyPetriNet {
        self.walker.builder().map()
    }

    /// Takes the map.
    pub fn into_map(self) -> FuzzyPetriNet {
        self.walker.into_builder().into_map()
    }

    /// The plan made at the start.
    pub fn first_plan(&self) -> Option<&Plan> {
        self.first_plan.as_ref()
    }

    /// The legs so far.
    pub fn legs(&self) -> &[NavLeg] {
        &self.legs
    }

    /// The counts so far.
    pub fn stats(&self) -> NavStats {
        self.stats
    }

    /// How it stands.
    pub fn state(&self) -> NavState {
        self.state
    }

    /// The place the robot believes it stands at (between legs).
    pub fn place(&self) -> Option<PlaceId> {
        self.walker.place()
    }

    /// The error that stopped it, if any.
    pub fn error(&self) -> Option<&TopoError> {
        self.error.as_ref()
    }

    /// A way back onto the net from `at`, a place without a route (module
    /// docs): the first transition of the route from the nearest known
    /// place with one that the robot stands on the spot of — within the
    /// recognition's distance tolerance of its map position, whatever the
    /// heading or type — and whose strategy may leave `at`; with the map
    /// heading it leaves on.
    fn way_back(&self, at: PlaceId) -> Option<(TransitionId, Option<f64>)> {
        let b = self.walker.builder();
        let map = b.map();
        let here = b.map_pose(self.walker.odometry());
        let tolerance_m = b.params().tolerance_m(b.since_recalibration_m());
        let origin = map.place(at);
        let mut near: Vec<(f64, PlaceId)> = map
            .place_ids()
            .filter(|&q| q != at)
            .map(|q| {
                let p = map.place(q);
                ((p.x_m - here.x_m).hypot(p.y_m - here.y_m), q)
            })
            .filter(|&(d, _)| d <= tolerance_m)
            .collect();
        near.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        for (_, q) in near {
            if let Ok(p) = plan(map, q, &self.goals, self.params.mode)
                && let Some(&t) = p.route.first()
                && !self.no_borrow.contains(&t)
            {
                let tr = map.transition(t);
                if origin.allows(tr.strategy) && tr.leave_heading_rad.is_some() {
                    return Some((t, tr.leave_heading_rad));
                }
            }
        }
        None
    }

    /// The way back from `at`, a new place where a planned leg played with
    /// `strategy` stopped facing map heading `heading_rad` (module docs):
    /// turn about, then the strategy mirrored — wall following on the
    /// other side, free movement straight back — if the place allows it;
    /// the exit turn is the one the place's type allows.
    fn retrace_of(
        &self,
        at: PlaceId,
        strategy: Strategy,
        heading_rad: f64,
    ) -> Option<(PlaceId, Action, f64)> {
        let place = self.walker.builder().map().place(at);
        let back = match strategy {
            Strategy::WallFollowLeft => Strategy::WallFollowRight,
            Strategy::WallFollowRight => Strategy::WallFollowLeft,
            Strategy::FreeMovement => Strategy::FreeMovement,
            Strategy::DetourLeft | Strategy::DetourRight => return None,
        };
        if !place.allows(back) {
            return None;
        }
        // The turn the place's actions leave with for that strategy, or
        // the place's own turn.
        let actions = super::strategy::actions_at(place.kind, place.concave);
        let exit_turn = actions
            .iter()
            .find(|a| a.strategy == back)
            .unwrap_or(&actions[0])
            .exit_turn;
        Some((
            at,
            Action {
                exit_turn,
                strategy: back,
            },
            robot::wrap_angle(heading_rad + std::f64::consts::PI),
        ))
    }

    /// The goal place nearest the robot's map position, other than
    /// `except`, and its distance, metres.
    fn nearest_goal(&self, except: Option<PlaceId>) -> Option<(f64, PlaceId)> {
        let b = self.walker.builder();
        let map = b.map();
        let here = b.map_pose(self.walker.odometry());
        self.goals
            .iter()
            .copied()
            .filter(|&g| Some(g) != except)
            .map(|g| {
                let p = map.place(g);
                ((p.x_m - here.x_m).hypot(p.y_m - here.y_m), g)
            })
            .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)))
    }

    /// Where homing heads for (module docs) and how far it is: the map
    /// position of the nearest goal place, unless the robot already stands
    /// on its spot (within the recognition's base tolerance: it has looked
    /// there).
    fn homing_target(&self) -> Option<((f64, f64), f64)> {
        let b = self.walker.builder();
        self.nearest_goal(None)
            .filter(|&(d, _)| d > b.params().base_m)
            .map(|(d, g)| {
                let p = b.map().place(g);
                ((p.x_m, p.y_m), d)
            })
    }

    /// A goal place the robot stands on the spot of at `at` (its map
    /// position within the recognition's distance tolerance), not
    /// recognised because the robot faces another way: the nearest.
    fn goal_on_spot(&self, at: PlaceId) -> Option<PlaceId> {
        let tolerance_m = self.walker.builder().params().base_m;
        self.nearest_goal(Some(at))
            .filter(|&(d, _)| d <= tolerance_m)
            .map(|(_, g)| g)
    }

    /// A plan from `at` on the map with every threshold but those of the
    /// transitions rejected on this route back at 1 (module docs: a
    /// transition rejected on earlier routes is tried again when no other
    /// way is known).
    fn plan_retrying(&self, at: PlaceId) -> Option<Plan> {
        let map = self.walker.builder().map();
        if !map.transitions().iter().any(|t| t.lambda < 1.0) {
            return None;
        }
        let mut relaxed = map.clone();
        for t in map.transition_ids() {
            if !self.rejected_here.contains(&t) {
                relaxed.set_lambda(t, 1.0).ok()?;
            }
        }
        plan(&relaxed, at, &self.goals, self.params.mode)
            .ok()
            .filter(|p| !p.route.is_empty())
    }

    /// Plans from `at` and starts the first transition (or an untried
    /// action when there is no route).
    fn go_from(&mut self, at: PlaceId) {
        let map = self.walker.builder().map();
        let planned = match plan(map, at, &self.goals, self.params.mode) {
            Ok(p) if !p.route.is_empty() => Some(p),
            _ if self.params.retry_rejected => self.plan_retrying(at),
            _ => None,
        };
        let map = self.walker.builder().map();
        match planned {
            Some(p) => {
                let t = p.route[0];
                let tr = map.transition(t);
                let action = Action {
                    exit_turn: tr.exit_turn,
                    strategy: tr.strategy,
                };
                self.expected = Some(t);
                self.borrowed = false;
                let to = tr.to;
                let leave = tr.leave_heading_rad;
                if self.first_plan.is_none() {
                    self.first_plan = Some(p);
                }
                let (a, b) = (map.place(at), map.place(to));
                let spot = (a.x_m - b.x_m).hypot(a.y_m - b.y_m) <= self.walker.builder().params().base_m;
                if self.params.turn_on_spot && spot {
                    // A transition to a place on the same spot: a turn in
                    // place to its heading (module docs).
                    let heading = b.heading_rad;
                    self.stats.turns_on_spot += 1;
                    self.walker.start_facing(heading, Some(to));
                } else {
                    self.walker.start_expecting(action, Some(to), leave);
                }
            }
            _ => {
                self.stats.no_route += 1;
                if let Some((t, leave)) = self.way_back(at) {
                    let tr = self.walker.builder().map().transition(t);
                    let action = Action {
                        exit_turn: tr.exit_turn,
                        strategy: tr.strategy,
                    };
                    let to = tr.to;
                    self.expected = Some(t);
                    self.borrowed = true;
                    self.stats.ways_back += 1;
                    self.walker.start_expecting(action, Some(to), leave);
                    return;
                }
                if self.params.retrace
                    && let Some((from, action, heading)) = self.retrace.take()
                    && from == at
                {
                    // Undo the planned leg that led off the net.
                    self.expected = None;
                    self.stats.retraces += 1;
                    self.walker.start_expecting(action, None, Some(heading));
                    return;
                }
                if self.params.homing
                    && let Some((target, d)) = self.homing_target()
                {
                    self.expected = None;
                    self.stats.homings += 1;
                    // The side homing goes round obstacles on: drawn once,
                    // kept while homing gets nearer, changed when a homing
                    // leg ended no nearer than it began.
                    let side = match (self.homing_side, self.homing_from_m) {
                        (None, _) => {
                            if self.rng.random_range(0..2) == 0 {
                                Turn::Left
                            } else {
                                Turn::Right
                            }
                        }
                        (Some(s), Some(before)) if d >= before => s.mirrored(),
                        (Some(s), _) => s,
                    };
                    self.homing_side = Some(side);
                    self.homing_from_m = Some(d);
                    // Stopping past the point only while homing comes
                    // nearer than ever on the route (else two legs could
                    // pass it back and forth).
                    let stop_past = self.params.homing_stop_past.then_some(self.homing_nearest_m);
                    self.homing_leg = true;
                    self.walker.start_homing(target, Some(side), stop_past);
                    return;
                }
                let map = self.walker.builder().map();
                let kind = map.place(at).kind;
                let tried: Vec<Action> = map
                    .leaving(at)
                    .iter()
                    .map(|&t| {
                        let tr = map.transition(t);
                        Action {
                            exit_turn: tr.exit_turn,
                            strategy: tr.strategy,
                        }
                    })
                    .collect();
                let all = actions_at(kind, map.place(at).concave);
                let untried: Vec<Action> = all.iter().copied().filter(|a| !tried.contains(a)).collect();
                let pool = if untried.is_empty() { all.to_vec() } else { untried };
                let action = pool[self.rng.random_range(0..pool.len())];
                self.expected = None;
                self.walker.start(action);
            }
        }
    }

    /// Learns from a leg's end at `arrival`: the planned transition's
    /// attempt (unless borrowed), and a transition that twice ended at the
    /// same wrong place rejected. Whether the leg went as planned.
    fn learn_from_arrival(
        &mut self,
        planned: Option<TransitionId>,
        arrival: &Arrival,
    ) -> Result<bool, TopoError> {
        let borrowed = std::mem::take(&mut self.borrowed);
        if std::mem::take(&mut self.homing_leg) {
            self.homing_nearest_m = self.homing_nearest_m.min(self.walker.homing_nearest_m());
        }
        let map = self.walker.builder_mut().map_mut();
        let as_planned = planned.is_some_and(|t| map.transition(t).to == arrival.place);
        if let Some(t) = planned
            && !borrowed
        {
            map.record_attempt(t, as_planned, &self.params.thresholds)?;
        }
        if let Some(t) = planned
            && !as_planned
        {
            let again = self.wrong_ends.insert((t, borrowed), arrival.place) == Some(arrival.place);
            if again && self.params.reject_repeated {
                if borrowed {
                    self.no_borrow.insert(t);
                } else {
                    map.set_lambda(t, 0.0)?;
                    self.rejected_here.insert(t);
                }
            }
        }
        Ok(as_planned)
    }

    /// A leg arrived at a place: learns from it, records the visit, and
    /// stops at a goal, gives up after `max_legs`, or starts the next leg
    /// (facing the goal on the spot first, or retracing a wrong leg).
    fn arrived(
        &mut self,
        p: &Perception,
        leg: Leg,
        arrival: Arrival,
        transition: Option<TransitionId>,
        notes: &mut Notes,
    ) -> Result<Step, TopoError> {
        let planned = self.expected.take();
        let as_planned = self.learn_from_arrival(planned, &arrival)?;
        let visit = Visit::of_arrival(p, &leg, &arrival, transition);
        if notes.is_enabled() {
            notes.event(place_event(self.map(), &visit).with("as_planned", as_planned));
        }
        self.legs.push(NavLeg {
            visit,
            planned,
            as_planned,
        });
        self.stats.legs += 1;
        if as_planned {
            self.stats.as_planned += 1;
        }
        if self.goals.contains(&arrival.place) {
            self.state = NavState::Arrived;
            return Ok(Step::Done(Command::Stop));
        }
        if self.stats.legs >= self.params.max_legs {
            self.state = NavState::GaveUp;
            return Ok(Step::GiveUp);
        }
        if planned.is_some() && !as_planned {
            self.stats.replans += 1;
        }
        // Not after a turn on the spot (a planned transition played
        // as a turn, `exit_turn` straight): undoing a turn is no
        // drive back.
        self.retrace =
            if planned.is_some() && !as_planned && arrival.new && leg.action.exit_turn != Turn::Straight {
                self.retrace_of(arrival.place, leg.action.strategy, arrival.map_pose.theta_rad)
            } else {
                None
            };
        let faced = std::mem::take(&mut self.facing);
        if self.params.face_goals
            && !faced
            && let Some(g) = self.goal_on_spot(arrival.place)
        {
            let heading = self.walker.builder().map().place(g).heading_rad;
            self.expected = None;
            self.facing = true;
            self.stats.facings += 1;
            self.walker.start_facing(heading, None);
            return Ok(Step::Run(Command::Stop));
        }
        self.go_from(arrival.place);
        Ok(Step::Run(Command::Stop))
    }

    /// A leg failed: counted and its attempt recorded (unless borrowed);
    /// gives up after `max_legs`, or starts a leg from anywhere.
    fn failed(&mut self, p: &Perception, failure: &Failure, notes: &mut Notes) -> Result<Step, TopoError> {
        self.stats.legs += 1;
        self.stats.failed_legs += 1;
        let borrowed = std::mem::take(&mut self.borrowed);
        self.facing = false;
        self.homing_leg = false;
        if let Some(t) = self.expected.take()
            && !borrowed
        {
            self.walker
                .builder_mut()
                .map_mut()
                .record_attempt(t, false, &self.params.thresholds)?;
        }
        if notes.is_enabled() {
            notes.event(Event::new("leg_failed", p.time_s).with("why", format!("{failure:?}")));
        }
        if self.stats.legs >= self.params.max_legs {
            self.state = NavState::GaveUp;
            return Ok(Step::GiveUp);
        }
        self.walker.start_anywhere(Turn::Left);
        Ok(Step::Run(Command::Stop))
    }

    fn tick(&mut self, p: &Perception, notes: &mut Notes) -> Result<Step, TopoError> {
        match self.state {
            NavState::Arrived => return Ok(Step::Done(Command::Stop)),
            NavState::GaveUp => return Ok(Step::GiveUp),
            NavState::Going => {}
        }
        if !self.started {
            self.started = true;
            self.walker.stand_at(self.start, p.odometry)?;
            if self.goals.contains(&self.start) {
                self.state = NavState::Arrived;
                return Ok(Step::Done(Command::Stop));
            }
            self.go_from(self.start);
        }
        match self.walker.step(p)? {
            WalkerStep::Drive(c) => {
                if notes.is_enabled()
                    && let Some(leg) = self.walker.leg()
                {
                    notes.behaviour(leg.action.strategy.name());
                }
                Ok(Step::Run(c))
            }
            WalkerStep::Arrived {
                leg,
                arrival,
                transition,
                ..
            } => self.arrived(p, leg, arrival, transition, notes),
            WalkerStep::Failed { failure, .. } => self.failed(p, &failure, notes),
            WalkerStep::Idle => {
                self.walker.start_anywhere(Turn::Left);
                Ok(Step::Run(Command::Stop))
            }
        }
    }
}

impl Controller for RouteFollower {
    fn step(&mut self, p: &Perception, notes: &mut Notes) -> Step {
        if self.error.is_some() {
            return Step::GiveUp;
        }
        match self.tick(p, notes) {
            Ok(s) => s,
            Err(e) => {
                self.error = Some(e);
                Step::GiveUp
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Place, PlaceKind, Strategy, Transition};
    use robot::Pose;
    use std::f64::consts::{FRAC_PI_2, PI};

    /// A corner `a` with a transition to `goal` leaving on −90°, and
    /// places without a way out: `beside` on `a`'s spot facing the other
    /// way, `far` 3 m off, `open` on the spot but of type (c).
    fn map() -> (FuzzyPetriNet, [PlaceId; 5], TransitionId) {
        let mut map = FuzzyPetriNet::new();
        let concave = |x: f64, heading: f64, kind: PlaceKind| {
            let mut p = Place::new(x, 0.0, heading, kind);
            p.concave = kind != PlaceKind::C;
            p
        };
        let a = map.add_place(concave(0.0, 0.0, PlaceKind::A)).unwrap();
        let goal = map.add_place(concave(5.0, 0.0, PlaceKind::B)).unwrap();
        let beside = map.add_place(concave(0.2, PI, PlaceKind::B)).unwrap();
        let far = map.add_place(concave(3.0, PI, PlaceKind::B)).unwrap();
        let open = map.add_place(concave(0.1, PI, PlaceKind::C)).unwrap();
        let mut t = Transition::new(a, goal, Strategy::WallFollowLeft, Turn::Right, 10.0);
        t.leave_heading_rad = Some(-FRAC_PI_2);
        let t = map.add_transition(t).unwrap();
        (map, [a, goal, beside, far, open], t)
    }

    fn way_back_from(at: usize) -> Option<(TransitionId, Option<f64>)> {
        let (map, places, _) = map();
        let mut f = RouteFollower::new(map, places[at], &[places[1]], NavigateParams::default(), 1).unwrap();
        f.walker.stand_at(places[at], Pose::default()).unwrap();
        f.way_back(places[at])
    }

    #[test]
    fn a_place_without_a_route_borrows_the_route_of_a_known_place_on_its_spot() {
        let (_, _, t) = map();
        // On a's spot, facing the other way: a's transition, leaving on
        // its recorded heading.
        assert_eq!(way_back_from(2), Some((t, Some(-FRAC_PI_2))));
        // Too far from any place with a route: none.
        assert_eq!(way_back_from(3), None);
        // On the spot, but wall following may not leave a (c) place.
        assert_eq!(way_back_from(4), None);
    }
}
