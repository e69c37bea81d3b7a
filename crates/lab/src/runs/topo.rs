//! Runs of the topological layer (docs/topo-fpn.md) in the simulator, shared by
//! the `topo` suite and the `petrinav topo` commands: exploration that
//! builds the fuzzy Petri net, routes driven with it, the two baselines a
//! route is compared with, and the net drawn over the world.
//!
//! The robot is the 16-sonar `ring` preset (sonars and odometry only, as
//! the source's Nomad-200). **Decision — odometry:** calibrated, as in the
//! dead-lock suite — slip of σ 1 % per wheel and step, no large slips
//! ([`robot()`]); the simulator's default, with a large slip of one wheel
//! (up to 50 %) about every 20 s, is the stress case ([`slipping_robot`]):
//! it turns the heading by a few degrees at a time and puts the robot a
//! metre off after a single 9 m corridor.
//! The controllers never see the true pose; the lab keeps it beside them to
//! judge:
//!
//! - **place recognition** ([`Recognition`]): a stop *is* the same place as
//!   an earlier one when its true position is within [`SAME_PLACE_M`] of
//!   where that place was first recorded and the robot faces the same way
//!   (within 45°). Every stop after the first is then a true positive (the
//!   robot recognised the place it truly is at), a false positive (it
//!   recognised a place it is not at), a false negative (it is at a known
//!   place but took it for a new one), or a true negative (a new place,
//!   recorded as new). Precision = TP / (TP + FP), recall = TP / (TP + FN).
//! - **routes** ([`RouteMethod`]): driven with the map, a route succeeds
//!   when the route follower declares arrival at the goal place and the
//!   robot truly stands within [`ARRIVE_M`] of where the goal place was
//!   recorded; declaring arrival elsewhere is a failure of its own
//!   (`wrong_place`). Wall following alone has no map to tell it where it
//!   is, so it is judged by an oracle: it succeeds the moment its true
//!   position comes within [`ARRIVE_M`] of the goal's — generous to it.
//! - **the shortest path** on the true grid ([`shortest_path_m`]): 8-connected
//!   Dijkstra ([`sim::geodesic`]) over the cells where the robot's disc fits, an upper bound no
//!   sonar robot without a metric map can reach, reported as a distance and
//!   as a time at free movement's cruise speed.

use std::collections::BTreeMap;

use anyhow::{Context, Result, bail};
use robot::{Command, Controller, Notes, Perception, Pose, Step, Vec2, wrap_angle};
use sim::geodesic::{self, Lattice, Steps};
use sim::render::{MarkerKind, Picture};
use sim::shapes::WorldSpec;
use sim::{
    DistanceField, OccupancyGrid, RobotParams, RunParams, RunResult, Simulation, Task, Trace, TraceParams,
    World,
};
use topo::{
    Action, Executor, Explorer, FuzzyPetriNet, NavState, NavStats, NavigateParams, PlaceId, Plan, PlanMode,
    Progress, Ring, RouteFollower, Strategy, StrategyParams, TopoParams, Turn, Visit, plan,
};

/// Two stops are at the same place when their true positions are this
/// close, metres (and their headings within 45°).
pub const SAME_PLACE_M: f64 = 0.5;

/// A route has arrived when the robot truly stands this close to where the
/// goal place was recorded, metres.
pub const ARRIVE_M: f64 = 0.5;

/// Heading tolerance of "the same place", radians.
const SAME_HEADING_RAD: f64 = std::f64::consts::FRAC_PI_4;

/// The 50 m² office, as shipped.
pub const OFFICE: &str = include_str!("office.toml");

/// The worlds: name, exploration time (s), start of the exploration.
/// `office_slips` is the office with the simulator's default odometry
/// (large slips: [`slipping_robot`]), the stress case.
pub const WORLDS: [(&str, f64, Pose); 3] = [
    (
        "office",
        600.0,
        Pose {
            x_m: 1.0,
            y_m: 0.75,
            theta_rad: 0.0,
        },
    ),
    (
        "floor",
        1800.0,
        Pose {
            x_m: 1.0,
            y_m: 6.0,
            theta_rad: 0.0,
        },
    ),
    (
        "office_slips",
        600.0,
        Pose {
            x_m: 1.0,
            y_m: 0.75,
            theta_rad: 0.0,
        },
    ),
];

/// The generated floor: 20 m × 18 m at 0.05 m
/// ([`sim::generators::office`]: corridors 2 m wide along y = 6 m and
/// y = 12 m, rooms in 4 m slots with 1 m doors and a 1.2 m × 0.6 m table
/// in each, an open hall between the corridors in the middle slot).
pub fn floor() -> Result<World> {
    Ok(World::new(sim::generators::office(400, 360, 0.05)?))
}

/// The office of `office.toml`.
pub fn office() -> Result<World> {
    #[derive(serde::Deserialize)]
    struct File {
        world: WorldSpec,
    }
    let file: File = toml::from_str(OFFICE).context("office.toml")?;
    Ok(World::new(file.world.rasterise()?))
}

/// The robot of the topological layer: the 16-sonar ring, with calibrated
/// odometry (module docs).
pub fn robot() -> RobotParams {
    let mut r = RobotParams::sonar_ring();
    r.odometry.large_slip_probability = 0.0;
    r
}

/// The same robot with the simulator's default odometry: large slips of
/// one wheel (up to 50 %) about every 20 s on top of the 1 % noise.
pub fn slipping_robot() -> RobotParams {
    RobotParams::sonar_ring()
}

/// Whether two true poses are the same place.
pub fn same_place(a: Pose, b: Pose) -> bool {
    a.position().dist(b.position()) <= SAME_PLACE_M
        && wrap_angle(a.theta_rad - b.theta_rad).abs() <= SAME_HEADING_RAD
}

/// Place recognition judged against the true poses (module docs).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Recognition {
    /// Recognised the place it truly was at.
    pub true_positives: u32,
    /// Recognised a place it was not at.
    pub false_positives: u32,
    /// At a known place, took it for a new one (or for another).
    pub false_negatives: u32,
    /// A new place, recorded as new.
    pub true_negatives: u32,
}

impl Recognition {
    /// TP / (TP + FP); NaN without any recognition.
    pub fn precision(&self) -> f64 {
        let d = self.true_positives + self.false_positives;
        if d == 0 {
            f64::NAN
        } else {
            f64::from(self.true_positives) / f64::from(d)
        }
    }

    /// TP / (TP + FN); NaN without any true re-visit.
    pub fn recall(&self) -> f64 {
        let d = self.true_positives + self.false_negatives;
        if d == 0 {
            f64::NAN
        } else {
            f64::from(self.true_positives) / f64::from(d)
        }
    }

    /// Judges the stops `visits` (in order) with the true pose at each.
    pub fn judge(visits: &[(Visit, Pose)]) -> Recognition {
        let mut r = Recognition::default();
        // Where each place was first recorded (true pose).
        let mut first: BTreeMap<PlaceId, Pose> = BTreeMap::new();
        for (v, truth) in visits {
            let truly_known = first
                .iter()
                .find(|(_, p)| same_place(**p, *truth))
                .map(|(&id, _)| id);
            if v.new {
                if truly_known.is_some() {
                    r.false_negatives += 1;
                } else {
                    r.true_negatives += 1;
                }
                first.insert(v.place, *truth);
            } else {
                match first.get(&v.place) {
                    Some(&p) if same_place(p, *truth) => r.true_positives += 1,
                    _ => {
                        r.false_positives += 1;
                        if truly_known.is_some() {
                            r.false_negatives += 1;
                        }
                    }
                }
            }
        }
        r
    }
}

/// The size of the map after a stop.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Growth {
    /// When, seconds.
    pub time_s: f64,
    /// Places.
    pub places: usize,
    /// Transitions.
    pub transitions: usize,
}

/// What an exploration needs.
#[derive(Debug, Clone)]
pub struct ExploreSpec {
    /// The explorer's parameters.
    pub params: TopoParams,
    /// Where the robot starts.
    pub start: Pose,
    /// How long it explores, seconds.
    pub time_s: f64,
    /// The run's seed (simulator and explorer).
    pub seed: u64,
    /// What to trace.
    pub trace: TraceParams,
    /// The robot ([`robot()`] or [`slipping_robot`]).
    pub robot: RobotParams,
}

/// What an exploration gave.
#[derive(Debug, Clone)]
pub struct Exploration {
    /// The map.
    pub map: FuzzyPetriNet,
    /// For every place (by id), the true pose where it was first recorded.
    pub truth: Vec<Pose>,
    /// Every stop with the true pose at it.
    pub visits: Vec<(Visit, Pose)>,
    /// Place recognition against the true poses.
    pub recognition: Recognition,
    /// The map's size after every stop.
    pub growth: Vec<Growth>,
    /// Legs that found no place (a timeout, no way out).
    pub failures: u32,
    /// Odometry recalibrations at concave places.
    pub recalibrations: u32,
    /// The simulator's summary.
    pub result: RunResult,
    /// The trace, if asked for.
    pub trace: Option<Trace>,
}

/// The control period of these runs, seconds (the simulator's default).
const PERIOD_S: f64 = 0.1;

/// Explores `world` (module docs).
pub fn explore(world: &World, spec: &ExploreSpec) -> Result<Exploration> {
    if !(spec.time_s.is_finite() && spec.time_s > 0.0) {
        bail!(
            "the exploration time must be a finite number of seconds > 0, got {}",
            spec.time_s
        );
    }
    let run = RunParams {
        time_limit_s: spec.time_s,
        collision_fatal: false,
        trace: spec.trace,
        ..RunParams::default()
    };
    let task = Task {
        start: spec.start,
        goal: None,
    };
    let mut sim = Simulation::new(world, spec.robot.clone(), run, task, spec.seed)
        .context("the exploration's start")?;
    let mut explorer = Explorer::new(spec.params, spec.seed)?;
    let mut visits = Vec::new();
    let mut truth: Vec<Pose> = Vec::new();
    let mut growth = Vec::new();
    loop {
        let ended = sim.tick(&mut explorer).is_some();
        // The stops of this tick (the last one's too), with the true pose.
        let known = explorer.visits();
        while visits.len() < known.len() {
            let v = known[visits.len()];
            let here = sim.pose();
            if v.new && truth.len() <= v.place.0 as usize {
                truth.resize(v.place.0 as usize + 1, here);
            }
            visits.push((v, here));
            growth.push(Growth {
                time_s: v.time_s,
                places: explorer.map().num_places(),
                transitions: explorer.map().num_transitions(),
            });
        }
        if let Some(e) = explorer.error() {
            bail!("the explorer failed: {e}");
        }
        if ended {
            break;
        }
    }
    let result = sim.result();
    let trace = sim.take_trace();
    let recognition = Recognition::judge(&visits);
    let failures = explorer.failures();
    let recalibrations = explorer.builder().recalibrations();
    let map = explorer.into_map();
    if truth.len() != map.num_places() {
        bail!(
            "{} places but {} true poses recorded",
            map.num_places(),
            truth.len()
        );
    }
    Ok(Exploration {
        map,
        truth,
        visits,
        recognition,
        growth,
        failures,
        recalibrations,
        result,
        trace,
    })
}

/// How a map's places hang together, following transitions not rejected
/// outright (`λ > 0`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Connectivity {
    /// Places.
    pub places: usize,
    /// The net is connected (Murata's sense: its graph, arcs taken either
    /// way, is in one piece).
    pub connected: bool,
    /// Places of the largest strongly connected part (every place of it
    /// can reach every other).
    pub largest_strong: usize,
}

impl Connectivity {
    /// Every place can reach every other.
    pub fn strongly_connected(&self) -> bool {
        self.largest_strong == self.places
    }
}

/// Successor lists of a map's places.
struct Adjacency(Vec<Vec<u32>>);

impl petri::scc::Successors for Adjacency {
    fn num_nodes(&self) -> usize {
        self.0.len()
    }

    fn successors(&self, v: u32) -> &[u32] {
        &self.0[v as usize]
    }
}

impl Adjacency {
    /// Nodes of the largest strongly connected component.
    fn largest_component(&self) -> usize {
        let mut largest = 0;
        let Ok(()) = petri::scc::tarjan(
            self,
            |_| true,
            |c| {
                largest = largest.max(c.len());
                Ok::<(), std::convert::Infallible>(())
            },
        );
        largest
    }
}

/// The connectivity of `map` (Tarjan's components of its transitions, and
/// of its transitions taken either way for the pieces).
pub fn connectivity(map: &FuzzyPetriNet) -> Connectivity {
    let n = map.num_places();
    let mut out = Adjacency(vec![Vec::new(); n]);
    let mut either = Adjacency(vec![Vec::new(); n]);
    for t in map.transitions().iter().filter(|t| t.lambda > 0.0) {
        out.0[t.from.index()].push(t.to.0);
        either.0[t.from.index()].push(t.to.0);
        either.0[t.to.index()].push(t.from.0);
    }
    Connectivity {
        places: n,
        connected: either.largest_component() == n,
        largest_strong: out.largest_component(),
    }
}

/// Whether every place of `map` can reach every other (the net is strongly
/// connected), following transitions not rejected outright (`λ > 0`).
pub fn strongly_connected(map: &FuzzyPetriNet) -> bool {
    connectivity(map).strongly_connected()
}

/// How a route is driven.
#[derive(Debug, Clone)]
pub enum RouteMethod {
    /// With the map: plan, follow place by place, replan, learn.
    Map(NavigateParams),
    /// Right-hand wall following, no map, until the robot truly arrives
    /// (a leg that times out or finds no way out starts again where it
    /// is).
    WallFollowing(StrategyParams),
}

/// What a route needs.
#[derive(Debug, Clone)]
pub struct RouteSpec<'a> {
    /// The map (the route follower updates a copy of it).
    pub map: &'a FuzzyPetriNet,
    /// The true pose of every place (judging only).
    pub truth: &'a [Pose],
    /// Where the robot starts (it is put at the place's true pose).
    pub from: PlaceId,
    /// Where it goes.
    pub to: PlaceId,
    /// How.
    pub method: RouteMethod,
    /// Time limit, seconds.
    pub time_limit_s: f64,
    /// The run's seed.
    pub seed: u64,
    /// What to trace.
    pub trace: TraceParams,
    /// The robot ([`robot()`] or [`slipping_robot`]).
    pub robot: RobotParams,
}

/// How a route ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RouteOutcome {
    /// At the goal.
    Reached,
    /// The follower declared arrival where the goal is not.
    WrongPlace,
    /// The time limit passed.
    TimeLimit,
    /// The follower gave up (too many legs, an error).
    GaveUp,
}

impl RouteOutcome {
    /// Its name in records.
    pub fn name(self) -> &'static str {
        match self {
            RouteOutcome::Reached => "goal",
            RouteOutcome::WrongPlace => "wrong_place",
            RouteOutcome::TimeLimit => "time_limit",
            RouteOutcome::GaveUp => "gave_up",
        }
    }
}

/// What a route gave.
#[derive(Debug, Clone)]
pub struct RouteRun {
    /// How it ended.
    pub outcome: RouteOutcome,
    /// The route first planned (map routes).
    pub plan: Option<Plan>,
    /// The follower's counts (map routes).
    pub stats: Option<NavStats>,
    /// The true distance to the goal place at the end, metres.
    pub final_distance_m: f64,
    /// The map after the route (map routes: what it learnt).
    pub map: Option<FuzzyPetriNet>,
    /// The simulator's summary.
    pub result: RunResult,
    /// The trace, if asked for.
    pub trace: Option<Trace>,
    /// Every leg of a map route that ended at a place, judged against the
    /// true poses (empty for wall following).
    pub legs: Vec<LegTruth>,
}

/// One leg of a route by the map, with where the robot truly was.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct LegTruth {
    /// When the leg ended, seconds.
    pub time_s: f64,
    /// The place it left (`None` after a failed leg).
    pub from: Option<PlaceId>,
    /// The place the planned transition leads to (`None`: no route, or an
    /// untried action).
    pub planned_to: Option<PlaceId>,
    /// The place the follower recognised (or added) at the end.
    pub arrived: PlaceId,
    /// It added that place.
    pub new: bool,
    /// It ended at the planned place (as the follower judged).
    pub as_planned: bool,
    /// The true pose at the start of the leg.
    pub start: Pose,
    /// The true pose at its end.
    pub end: Pose,
    /// The true end is the planned place's ([`same_place`] with where it
    /// was recorded while exploring; `None`: no planned place, or one
    /// added after the exploration).
    pub truly_at_planned: Option<bool>,
    /// The true start is the origin place's (as above).
    pub started_at_origin: Option<bool>,
}

/// Right-hand wall following from stop to stop, for ever.
struct WallFollower {
    params: StrategyParams,
    executor: Executor,
}

impl Controller for WallFollower {
    fn step(&mut self, p: &Perception, notes: &mut Notes) -> Step {
        let ring = Ring::of(p);
        let (l, r) = p.wheel_speeds_mps;
        let stopped = l.abs() < 0.01 && r.abs() < 0.01;
        match self.executor.step(&ring, p.odometry.theta_rad, stopped, PERIOD_S) {
            Progress::Drive(c) => Step::Run(c),
            Progress::Arrived => {
                // A wall ahead: turn away from the followed wall, go on.
                let a = Action {
                    exit_turn: Turn::Left,
                    strategy: Strategy::WallFollowRight,
                };
                self.executor = Executor::new(self.params, a.strategy, a.exit_turn, p.odometry.theta_rad);
                Step::Run(Command::Stop)
            }
            Progress::Failed(f) => {
                // A leg that took too long (a wall followed round and
                // round a room) or found no way out: start again from
                // here; only the time limit ends a wall follower.
                notes.event(robot::Event::new("restart", p.time_s).with("failure", format!("{f:?}")));
                self.executor = Executor::new(
                    self.params,
                    Strategy::WallFollowRight,
                    Turn::Left,
                    p.odometry.theta_rad,
                );
                Step::Run(Command::Stop)
            }
        }
    }
}

/// Drives a route (module docs).
pub fn route(world: &World, spec: &RouteSpec<'_>) -> Result<RouteRun> {
    let n = spec.map.num_places();
    for (what, p) in [("from", spec.from), ("to", spec.to)] {
        if p.0 as usize >= n || p.0 as usize >= spec.truth.len() {
            bail!("route {what} place #{}: the map has {n} places", p.0);
        }
    }
    if !(spec.time_limit_s.is_finite() && spec.time_limit_s > 0.0) {
        bail!(
            "the time limit must be a finite number of seconds > 0, got {}",
            spec.time_limit_s
        );
    }
    let start = spec.truth[spec.from.0 as usize];
    let goal = spec.truth[spec.to.0 as usize];
    let run = RunParams {
        time_limit_s: spec.time_limit_s,
        collision_fatal: false,
        trace: spec.trace,
        ..RunParams::default()
    };
    let task = Task { start, goal: None };
    let mut sim =
        Simulation::new(world, spec.robot.clone(), run, task, spec.seed).context("the route's start")?;
    match &spec.method {
        RouteMethod::Map(params) => {
            let planned = plan(spec.map, spec.from, &[spec.to], params.mode).ok();
            let mut follower =
                RouteFollower::new(spec.map.clone(), spec.from, &[spec.to], *params, spec.seed)?;
            let mut legs = Vec::new();
            let mut leg_start = start;
            let truth_of = |p: PlaceId| spec.truth.get(p.0 as usize).copied();
            loop {
                let ended = sim.tick(&mut follower).is_some();
                let known = follower.legs();
                while legs.len() < known.len() {
                    let l = known[legs.len()];
                    let end = sim.pose();
                    let planned_to = l.planned.map(|t| follower.map().transition(t).to);
                    legs.push(LegTruth {
                        time_s: l.visit.time_s,
                        from: l.visit.from,
                        planned_to,
                        arrived: l.visit.place,
                        new: l.visit.new,
                        as_planned: l.as_planned,
                        start: leg_start,
                        end,
                        truly_at_planned: planned_to.and_then(truth_of).map(|q| same_place(q, end)),
                        started_at_origin: l.visit.from.and_then(truth_of).map(|q| same_place(q, leg_start)),
                    });
                    leg_start = end;
                }
                if ended || follower.state() != NavState::Going {
                    break;
                }
            }
            let here = sim.pose();
            let d = here.position().dist(goal.position());
            let outcome = match follower.state() {
                NavState::Arrived if d <= ARRIVE_M => RouteOutcome::Reached,
                NavState::Arrived => RouteOutcome::WrongPlace,
                NavState::GaveUp => RouteOutcome::GaveUp,
                NavState::Going if follower.error().is_some() => RouteOutcome::GaveUp,
                NavState::Going => RouteOutcome::TimeLimit,
            };
            let stats = follower.stats();
            Ok(RouteRun {
                outcome,
                plan: planned,
                stats: Some(stats),
                final_distance_m: d,
                map: Some(follower.into_map()),
                result: sim.result(),
                trace: sim.take_trace(),
                legs,
            })
        }
        RouteMethod::WallFollowing(params) => {
            params.validate().map_err(anyhow::Error::msg)?;
            let mut c = WallFollower {
                params: *params,
                executor: Executor::new(*params, Strategy::WallFollowRight, Turn::Left, start.theta_rad),
            };
            let mut outcome = RouteOutcome::TimeLimit;
            loop {
                let ended = sim.tick(&mut c);
                if sim.pose().position().dist(goal.position()) <= ARRIVE_M {
                    outcome = RouteOutcome::Reached;
                    break;
                }
                match ended {
                    None => {}
                    Some(sim::Outcome::GaveUp) => {
                        outcome = RouteOutcome::GaveUp;
                        break;
                    }
                    Some(_) => break,
                }
            }
            Ok(RouteRun {
                outcome,
                plan: None,
                stats: None,
                final_distance_m: sim.pose().position().dist(goal.position()),
                map: None,
                result: sim.result(),
                trace: sim.take_trace(),
                legs: Vec::new(),
            })
        }
    }
}

/// The length of the shortest collision-free path from `a` to `b` on the
/// true grid for a disc of `radius_m` (8-connected Dijkstra over the cells
/// whose centre is farther than `radius_m` from every blocked cell);
/// `None` when there is none.
pub fn shortest_path_m(grid: &OccupancyGrid, a: Vec2, b: Vec2, radius_m: f64) -> Option<f64> {
    let field = DistanceField::new(grid);
    let (w, h) = (grid.width(), grid.height());
    let passable: Vec<bool> = (0..w * h)
        .map(|k| {
            let c = sim::CellIndex {
                i: (k % w) as i64,
                j: (k / w) as i64,
            };
            field.distance_m(grid.cell_center(c)) > radius_m
        })
        .collect();
    // No path from or to a point off the grid or where the disc does not fit.
    let node = |p: Vec2| {
        let c = grid.cell_of(p);
        let k = c.j as usize * w + c.i as usize;
        (grid.contains(c) && passable[k]).then_some(k)
    };
    let (ia, ib) = (node(a)?, node(b)?);
    let lattice = Lattice {
        width: w,
        height: h,
        passable: &passable,
        cut_corners: true,
    };
    let steps = Steps {
        straight: 1.0,
        diagonal: std::f64::consts::SQRT_2,
    };
    let d = geodesic::distances(&lattice, steps, &[(ia, 0.0)], Some(ib))[ib];
    d.is_finite().then(|| d * grid.resolution_m())
}

/// Draws the net over the world: places at their map positions (numbered
/// as in the map), transitions as lines coloured by strategy, and — when
/// the true poses are given — a grey tick from each place to where it truly
/// is (odometry drift made visible); optionally a trajectory below.
pub fn picture(
    grid: &OccupancyGrid,
    map: &FuzzyPetriNet,
    truth: Option<&[Pose]>,
    trajectory: Option<&[Pose]>,
    path: &std::path::Path,
) -> Result<()> {
    let mut pic = Picture::new(grid);
    if let Some(poses) = trajectory {
        let labels: Vec<&str> = vec!["trajectory"; poses.len()];
        pic.trajectory(poses, Some(&labels));
    }
    for t in map.transitions() {
        let (a, b) = (map.place(t.from), map.place(t.to));
        let name = t.strategy.name();
        pic.trajectory(
            &[Pose::new(a.x_m, a.y_m, 0.0), Pose::new(b.x_m, b.y_m, 0.0)],
            Some(&[name, name]),
        );
    }
    if let Some(truth) = truth {
        for (k, p) in map.places().iter().enumerate() {
            if let Some(q) = truth.get(k) {
                pic.ray(Vec2::new(p.x_m, p.y_m), q.position());
            }
        }
    }
    for p in map.places() {
        let at = Vec2::new(p.x_m, p.y_m);
        pic.marker(at, MarkerKind::Point);
        pic.text(at + Vec2::new(0.1, 0.1), &p.name);
    }
    pic.save(path)
        .with_context(|| format!("writing {}", path.display()))?;
    Ok(())
}

/// Ordered pairs of distinct places with a planned route on `map`
/// (`optimal` mode), in id order.
pub fn routable_pairs(map: &FuzzyPetriNet) -> Vec<(PlaceId, PlaceId)> {
    let n = map.num_places() as u32;
    let mut out = Vec::new();
    for a in 0..n {
        for b in 0..n {
            if a != b && plan(map, PlaceId(a), &[PlaceId(b)], PlanMode::Optimal).is_ok() {
                out.push((PlaceId(a), PlaceId(b)));
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn visit(place: u32, new: bool) -> Visit {
        Visit {
            time_s: 0.0,
            place: PlaceId(place),
            new,
            recalibrated: false,
            heading_recalibrated: false,
            tolerance_m: 0.5,
            map_pose: Pose::default(),
            odometry: Pose::default(),
            from: None,
            action: Action {
                exit_turn: Turn::Left,
                strategy: Strategy::FreeMovement,
            },
            transition: None,
        }
    }

    /// Places p1…pn and transitions `(from, to, λ)` (1-based places), as
    /// a map file would hold them.
    fn net(n: usize, arcs: &[(u32, u32, f64)]) -> FuzzyPetriNet {
        let places: Vec<serde_json::Value> = (1..=n)
            .map(|i| serde_json::json!({"name": format!("p{i}"), "x_m": i as f64, "y_m": 0.0, "heading_rad": 0.0, "kind": "a", "concave": false, "heading_aligned": false, "visits": 1}))
            .collect();
        let transitions: Vec<serde_json::Value> = arcs
            .iter()
            .map(|&(a, b, lambda)| {
                serde_json::json!({"from": format!("p{a}"), "to": format!("p{b}"), "strategy": "free_movement",
                    "exit_turn": "right", "duration_s": 1.0, "cost": 1.0, "lambda": lambda, "attempts": 0, "failures": 0})
            })
            .collect();
        let file = serde_json::json!({"format": "petrinav-fpn", "version": 1, "places": places, "transitions": transitions});
        FuzzyPetriNet::from_json(&file.to_string()).unwrap()
    }

    #[test]
    fn connectivity_of_hand_made_nets() {
        let c = |n, arcs: &[(u32, u32, f64)]| {
            let k = connectivity(&net(n, arcs));
            (k.connected, k.largest_strong, k.strongly_connected())
        };
        // A walk that never comes back to its start: connected, and only
        // the cycle p2 → p3 → p4 → p2 is strongly connected.
        assert_eq!(
            c(
                5,
                &[(1, 2, 1.0), (2, 3, 1.0), (3, 4, 1.0), (4, 2, 1.0), (4, 5, 1.0)]
            ),
            (true, 3, false)
        );
        // Closed: strongly connected.
        assert_eq!(c(3, &[(1, 2, 1.0), (2, 3, 1.0), (3, 1, 1.0)]), (true, 3, true));
        // Two pieces (a failed leg left no transition).
        assert_eq!(c(4, &[(1, 2, 1.0), (2, 1, 1.0), (3, 4, 1.0)]), (false, 2, false));
        // A rejected transition (λ = 0) does not count.
        assert_eq!(c(2, &[(1, 2, 1.0), (2, 1, 0.0)]), (true, 1, false));
        assert_eq!(c(2, &[(1, 2, 0.0)]), (false, 1, false));
        // One place; none.
        assert_eq!(c(1, &[]), (true, 1, true));
        assert_eq!(c(0, &[]), (true, 0, true));
    }

    #[test]
    fn recognition_counts_each_kind_of_stop() {
        let at = |x: f64| Pose::new(x, 0.0, 0.0);
        let visits = [
            (visit(0, true), at(0.0)),  // new, truly new: TN
            (visit(1, true), at(3.0)),  // TN
            (visit(0, false), at(0.2)), // back at p1, recognised: TP
            (visit(1, false), at(0.1)), // at p1, taken for p2: FP and FN
            (visit(2, true), at(3.1)),  // at p2, taken for new: FN
            (visit(0, false), at(6.0)), // somewhere new, taken for p1: FP
        ];
        let r = Recognition::judge(&visits);
        assert_eq!(
            (
                r.true_positives,
                r.false_positives,
                r.false_negatives,
                r.true_negatives
            ),
            (1, 2, 2, 2)
        );
        assert!((r.precision() - 1.0 / 3.0).abs() < 1e-12);
        assert!((r.recall() - 1.0 / 3.0).abs() < 1e-12);
        // Facing the other way is another place.
        let turned = [
            (visit(0, true), at(0.0)),
            (visit(1, true), Pose::new(0.0, 0.0, 3.0)),
        ];
        assert_eq!(Recognition::judge(&turned).true_negatives, 2);
        assert!(Recognition::default().precision().is_nan());
    }

    #[test]
    fn shortest_path_goes_round_a_wall_and_knows_when_there_is_none() {
        let mut g = OccupancyGrid::new(100, 60, 0.05, Pose::default());
        // A wall across x = 2.5 m from y = 0 to 2.2 m: the way round is
        // above it.
        for j in 0..44 {
            for i in 49..51 {
                g.set(sim::CellIndex { i, j }, sim::Cell::Occupied);
            }
        }
        let d = shortest_path_m(&g, Vec2::new(1.0, 0.5), Vec2::new(4.0, 0.5), 0.2).unwrap();
        // Up to y ≈ 2.2 + 0.2, over, and down: at least 2 × 1.9 + …
        assert!(d > 2.0 * 1.9 && d < 7.0, "{d}");
        let straight = shortest_path_m(&g, Vec2::new(1.0, 2.8), Vec2::new(4.0, 2.8), 0.2).unwrap();
        assert!((straight - 3.0).abs() < 0.06, "{straight}");
        // Closed off: no path.
        for j in 44..60 {
            for i in 49..51 {
                g.set(sim::CellIndex { i, j }, sim::Cell::Occupied);
            }
        }
        assert_eq!(
            shortest_path_m(&g, Vec2::new(1.0, 0.5), Vec2::new(4.0, 0.5), 0.2),
            None
        );
    }
}
