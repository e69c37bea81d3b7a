//! Exploration: the robot drives from reference place to reference place
//! and builds the fuzzy Petri net as it goes (docs/topo-fpn.md, "Experiments":
//! "explore with wall following and free movement").
//!
//! At the very start it drives straight ahead to the first obstacle: the
//! first place. At every place it picks the next action among those of
//! [`actions_at`] its type but detours (the spec explores
//! "with wall following and free movement"):
//!
//! 1. an action **not yet tried** from this place, at random among them
//!    (seeded);
//! 2. otherwise, the first transition of the cheapest route (the planner,
//!    optimal mode) to the nearest place that still has untried actions —
//!    the map itself leads the robot to its frontier;
//! 3. otherwise (none left, or none reachable) a random action.
//!
//! A failed leg (timeout, no way out) leaves the robot at no known place:
//! it turns left and drives straight to the next obstacle, recording no
//! transition.

use std::collections::BTreeSet;

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use robot::{Command, Controller, Event, Notes, Perception, Pose, Step, Vec2};

use super::TopoError;
use super::builder::{Arrival, MapBuilder};
use super::fpn::{FuzzyPetriNet, PlaceId, TransitionId, Turn};
use super::propagation::{PlanMode, plan};
use super::recognition::RecognitionParams;
use super::situation::SituationParams;
use super::strategy::{Action, StrategyParams, actions_at};
use super::walker::{Leg, Walker, WalkerStep};

/// Everything that shapes the topological layer's driving and mapping.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TopoParams {
    /// The strategies.
    pub strategy: StrategyParams,
    /// Classifying places.
    pub situation: SituationParams,
    /// Recognising places.
    pub recognition: RecognitionParams,
}

/// One stop at a reference place.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Visit {
    /// When, seconds.
    pub time_s: f64,
    /// The place.
    pub place: PlaceId,
    /// Added by this stop.
    pub new: bool,
    /// Recalibrated odometry.
    pub recalibrated: bool,
    /// Recalibrated the heading too.
    pub heading_recalibrated: bool,
    /// The distance tolerance used, metres.
    pub tolerance_m: f64,
    /// The robot's map pose at the stop (before recalibration).
    pub map_pose: Pose,
    /// Its odometry pose.
    pub odometry: Pose,
    /// The place the leg started at.
    pub from: Option<PlaceId>,
    /// The leg's action.
    pub action: Action,
    /// The transition recorded.
    pub transition: Option<TransitionId>,
}

impl Visit {
    /// The stop that ended `leg` at `arrival`, perceived in `p`, with the
    /// transition recorded for it.
    pub fn of_arrival(
        p: &Perception,
        leg: &Leg,
        arrival: &Arrival,
        transition: Option<TransitionId>,
    ) -> Visit {
        Visit {
            time_s: p.time_s,
            place: arrival.place,
            new: arrival.new,
            recalibrated: arrival.recalibrated,
            heading_recalibrated: arrival.heading_recalibrated,
            tolerance_m: arrival.tolerance_m,
            map_pose: arrival.map_pose,
            odometry: p.odometry,
            from: leg.from,
            action: leg.action,
            transition,
        }
    }
}

/// The place event a controller of this module emits (`kind` "place";
/// payload: `place` name, `type` a/b/c, `new`, `recalibrated`,
/// `strategy`), at the map position.
pub fn place_event(map: &FuzzyPetriNet, v: &Visit) -> Event {
    let p = map.place(v.place);
    Event::new("place", v.time_s)
        .at(Vec2::new(v.map_pose.x_m, v.map_pose.y_m))
        .with("place", p.name.as_str())
        .with("type", p.kind.letter())
        .with("new", v.new)
        .with("recalibrated", v.recalibrated)
        .with("strategy", v.action.strategy.name())
}

/// The actions the explorer plays at a place of type `kind`: those of
/// [`actions_at`] but detours — the spec explores "with wall following and
/// free movement".
fn exploring_actions(place: &super::Place) -> impl Iterator<Item = Action> {
    actions_at(place.kind, place.concave)
        .iter()
        .copied()
        .filter(|a| a.strategy.detour_side().is_none())
}

/// The exploring controller (module docs).
#[derive(Debug)]
pub struct Explorer {
    walker: Walker,
    rng: ChaCha8Rng,
    tried: BTreeSet<(PlaceId, Action)>,
    visits: Vec<Visit>,
    failures: u32,
    started: bool,
    error: Option<TopoError>,
}

impl Explorer {
    /// An explorer starting with an empty map; `seed` drives its choices.
    pub fn new(params: TopoParams, seed: u64) -> Result<Explorer, TopoError> {
        let builder = MapBuilder::new(params.recognition)?;
        Ok(Explorer {
            walker: Walker::new(builder, params.strategy, params.situation)?,
            rng: ChaCha8Rng::seed_from_u64(seed),
            tried: BTreeSet::new(),
            visits: Vec::new(),
            failures: 0,
            started: false,
            error: None,
        })
    }

    /// The map so far.
    pub fn map(&self) -> &FuzzyPetriNet {
        self.walker.builder().map()
    }

    /// The map builder (drift, recalibrations).
    pub fn builder(&self) -> &MapBuilder {
        self.walker.builder()
    }

    /// Takes the map.
    pub fn into_map(self) -> FuzzyPetriNet {
        self.walker.into_builder().into_map()
    }

    /// Every stop so far.
    pub fn visits(&self) -> &[Visit] {
        &self.visits
    }

    /// Failed legs so far.
    pub fn failures(&self) -> u32 {
        self.failures
    }

    /// The error that stopped the explorer, if any.
    pub fn error(&self) -> Option<&TopoError> {
        self.error.as_ref()
    }

    fn choose(&mut self, at: PlaceId) -> Action {
        let map = self.walker.builder().map();
        let untried: Vec<Action> = exploring_actions(map.place(at))
            .filter(|a| !self.tried.contains(&(at, *a)))
            .collect();
        if !untried.is_empty() {
            let a = untried[self.rng.random_range(0..untried.len())];
            self.tried.insert((at, a));
            return a;
        }
        let frontier: Vec<PlaceId> = map
            .place_ids()
            .filter(|&p| exploring_actions(map.place(p)).any(|a| !self.tried.contains(&(p, a))))
            .collect();
        if !frontier.is_empty()
            && let Ok(route) = plan(map, at, &frontier, PlanMode::Optimal)
            && let Some(&t) = route.route.first()
        {
            let t = map.transition(t);
            return Action {
                exit_turn: t.exit_turn,
                strategy: t.strategy,
            };
        }
        let all: Vec<Action> = exploring_actions(map.place(at)).collect();
        all[self.rng.random_range(0..all.len())]
    }

    fn tick(&mut self, p: &Perception, notes: &mut Notes) -> Result<Step, TopoError> {
        if !self.started {
            self.started = true;
            self.walker.start_anywhere(Turn::Straight);
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
            } => {
                let visit = Visit::of_arrival(p, &leg, &arrival, transition);
                if notes.is_enabled() {
                    notes.event(place_event(self.map(), &visit));
                }
                self.visits.push(visit);
                let next = self.choose(arrival.place);
                self.walker.start(next);
                Ok(Step::Run(Command::Stop))
            }
            WalkerStep::Failed { failure, .. } => {
                self.failures += 1;
                if notes.is_enabled() {
                    notes.event(Event::new("leg_failed", p.time_s).with(
                        "why",
                        match failure {
                            super::Failure::NoWayOut => "no_way_out",
                            super::Failure::Timeout => "timeout",
                        },
                    ));
                }
                self.walker.start_anywhere(Turn::Left);
                Ok(Step::Run(Command::Stop))
            }
            WalkerStep::Idle => {
                self.walker.start_anywhere(Turn::Left);
                Ok(Step::Run(Command::Stop))
            }
        }
    }
}

impl Controller for Explorer {
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
