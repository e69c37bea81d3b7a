//! Guide missions on a map: the tour-guide robot driven by its own
//! localizer and planners from one place to another, judged by the truth.
//!
//! A *leg* is one simulation: the Jinny-like robot (181-beam laser, wheel
//! odometry with its realistic slips) starts at a pose, the
//! [`GuideController`] gets the map, the start as its initial estimate and
//! the goal, and runs until the simulator ends the run. The lab watches what
//! the controller cannot: the distance between its estimate and the true
//! pose at every tick. A *tour* is a sequence of legs through places in
//! order: each leg starts where the last one ended (true pose), and the
//! controller starts from the last leg's final *estimate* — localization
//! errors carry over, as on a real robot. People are placed anew for each
//! leg.
//!
//! **Decision — a leg that ends without arriving (`collision`, `timeout`,
//! `lost`, `unreachable`, `gave_up`).** The guide's operator takes the robot to the
//! place it was heading for and gives it its pose there (ROS users: drive it
//! over, then "2D Pose Estimate"): the next leg starts at that place,
//! estimate = truth, so a leg's outcome measures that leg. Rejected:
//! starting the next leg where the robot stopped, because one failure then
//! cascaded (a time-out in a corner with no route on the static map made
//! the tour's remaining legs `unreachable`); rejected: after a collision, a
//! nudge to where the robot was a second before, because a robot creeping
//! at a door or turning on the spot is then still touching distance from
//! the wall. Figures: `crates/lab/EXPERIMENTS.md`.
//!
//! **Outcomes.** `reached` (within the goal tolerance of the true position
//! when the controller declared arrival), `lost` (the controller declared
//! arrival elsewhere, or its estimate was more than `lost_error_m` from the
//! truth for `lost_after_s`), `collision`, `timeout`, `unreachable` (no
//! route on the static map: the leg is not run), and `gave_up` (the
//! controller stopped, e.g. without a laser).

use std::collections::BTreeMap;
use std::sync::Arc;

use anyhow::{Context, Result};
use guide::supervisor::Behaviour;
use guide::supervisor::log::{CalibrationRun, Entry, MissionRecord};
use guide::{GuideController, GuideError, GuideMap, GuideParams, GuideStats, GuideSummary, Policy};
use robot::{Controller, Event, Notes, Perception, Pose, Request, Step, Vec2};
use sim::render::{MarkerKind, Picture};
use sim::{OccupancyGrid, Outcome, RobotParams, RunParams, Simulation, Task, TraceParams, World};

use crate::pictures::{EventMarker, MarkerPlace, Replay};
use crate::record::RunRecord;

/// How a leg ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LegOutcome {
    /// At the goal (by the true position).
    Reached,
    /// Collided.
    Collision,
    /// Out of time.
    Timeout,
    /// The estimate was wrong: arrival declared elsewhere, or far from the
    /// truth for too long.
    Lost,
    /// No route on the static map.
    Unreachable,
    /// The controller stopped.
    GaveUp,
}

/// Localization over a leg (true error: estimate against truth).
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct LocalizationSummary {
    /// Mean position error over the ticks, metres.
    pub mean_error_m: f64,
    /// Median position error, metres.
    pub median_error_m: f64,
    /// Largest position error, metres.
    pub max_error_m: f64,
    /// Times the localizer went to Warning.
    pub warnings: u32,
    /// Time in Warning, seconds.
    pub time_in_warning_s: f64,
    /// Time the robot was truly lost (true error over
    /// [`TRUE_LOSS_M`] or [`TRUE_LOSS_RAD`]), seconds.
    #[serde(default)]
    pub lost_s: f64,
    /// Time in Warning while truly lost, seconds.
    #[serde(default)]
    pub warning_lost_s: f64,
    /// Time in Warning while the true error was under
    /// [`FINE_ERROR_M`], seconds.
    #[serde(default)]
    pub warning_fine_s: f64,
    /// Time the true error was under [`FINE_ERROR_M`], seconds.
    #[serde(default)]
    pub fine_s: f64,
}

/// A position error above this is a true loss, metres (issue's and
/// the report's definition, with [`TRUE_LOSS_RAD`]).
pub const TRUE_LOSS_M: f64 = 0.5;

/// A heading error above this is a true loss, radians (20°).
pub const TRUE_LOSS_RAD: f64 = 20.0 * std::f64::consts::PI / 180.0;

/// A true error under this is a good estimate: a Warning then is a false
/// alarm, metres.
pub const FINE_ERROR_M: f64 = 0.2;

/// AutoMove over a leg.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct PlannerSummary {
    /// Times it became Abnormal.
    pub abnormal_episodes: u32,
    /// Time Abnormal, seconds.
    pub time_abnormal_s: f64,
}

/// One leg's result (`nav go`/`nav tour` print it as JSON, keys stable).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct LegResult {
    /// Where from (a place's name, or `x,y,θ`).
    pub from: String,
    /// Where to.
    pub to: String,
    /// How it ended.
    pub outcome: LegOutcome,
    /// Simulated time, seconds.
    pub time_s: f64,
    /// Length of the true path, metres.
    pub path_m: f64,
    /// Distance from the true final position to the goal, metres.
    pub final_error_m: f64,
    /// The localizer.
    pub localization: LocalizationSummary,
    /// AutoMove.
    pub planner: PlannerSummary,
}

/// Where the people of each leg stand at its start.
#[derive(Debug, Clone, PartialEq)]
pub struct PeoplePlan {
    /// How many.
    pub count: usize,
    /// They gather around these points (the places).
    pub anchors: Vec<Vec2>,
    /// Within this distance of an anchor, metres.
    pub spread_m: f64,
    /// And no nearer than this to the robot's footprint, metres.
    pub keep_clear_m: f64,
}

/// What a mission runs on: the world (map and crowd), the robot, the
/// controller's parameters, the run's limits.
#[derive(Debug, Clone)]
pub struct MissionSetup {
    /// The world, with its crowd's parameters (waypoints, speeds…).
    pub world: World,
    /// Where each leg's people start ([`crowd_near`], drawn from the leg's
    /// seed around the anchors, clear of the leg's start); `None`: the
    /// world's crowd as it is.
    pub people: Option<PeoplePlan>,
    /// The robot (Jinny-like by default).
    pub robot: RobotParams,
    /// The guide controller's parameters.
    pub guide: GuideParams,
    /// Time limit of a leg, seconds.
    pub time_limit_s: f64,
    /// Goal tolerance, metres (the simulator's judgement).
    pub goal_tolerance_m: f64,
    /// A true error above this for `lost_after_s` ends the leg as lost,
    /// metres. Default 2.
    pub lost_error_m: f64,
    /// Physical causes of true loss (pushes, slips, groups closing round
    /// the robot; [`sim::DisturbanceParams`]). Default: none.
    pub disturbances: sim::DisturbanceParams,
    /// Seconds, see `lost_error_m`. Default 5.
    pub lost_after_s: f64,
    /// The map prepared for the controller ([`MissionSetup::prepare`]).
    prepared: Option<Arc<GuideMap>>,
}

impl MissionSetup {
    /// The Jinny-like robot in `world` with default parameters and a time
    /// limit.
    pub fn new(world: World, time_limit_s: f64) -> MissionSetup {
        MissionSetup {
            world,
            people: None,
            robot: RobotParams::jinny(),
            guide: GuideParams::default(),
            time_limit_s,
            goal_tolerance_m: 0.3,
            lost_error_m: 2.0,
            lost_after_s: 5.0,
            disturbances: sim::DisturbanceParams::default(),
            prepared: None,
        }
    }

    /// Prepares the world's map for the guide controller with `guide`
    /// ([`GuideMap`]: likelihood field, cost maps), once for every leg run
    /// on this setup and its clones, instead of once a leg; the legs are
    /// the same bit for bit. A leg whose `world` or `guide` has changed
    /// since prepares its own. Fails as a leg would on bad parameters.
    pub fn prepare(&mut self) -> Result<()> {
        let map = self.world.grid().grid_map();
        let prepared = GuideMap::new(&map, self.guide.clone()).context("preparing the map for the guide")?;
        self.prepared = Some(Arc::new(prepared));
        Ok(())
    }
}

/// A snapshot of the particle cloud when the localizer warned.
#[derive(Debug, Clone, PartialEq)]
pub struct Cloud {
    /// When, seconds.
    pub time_s: f64,
    /// The particles' positions.
    pub particles: Vec<Vec2>,
}

/// A leg as it was driven, for pictures: per tick the true pose and a
/// state label, the events, the clouds at warnings.
#[derive(Debug, Clone, Default)]
pub struct LegTrace {
    /// Time at each tick (when the sensors read), seconds.
    pub times: Vec<f64>,
    /// True pose at each tick.
    pub poses: Vec<Pose>,
    /// Estimated pose at each tick.
    pub estimates: Vec<Pose>,
    /// The behaviour and state at each tick (`automove`, `automove ·
    /// warning`, `contour`, `asking`…).
    pub labels: Vec<&'static str>,
    /// The controller's events.
    pub events: Vec<Event>,
    /// Particle clouds at warnings.
    pub clouds: Vec<Cloud>,
}

/// A leg's result, the estimate it ended with, and its trace.
#[derive(Debug, Clone)]
pub struct LegRun {
    /// The result.
    pub result: LegResult,
    /// The controller's final estimate (where the next leg starts from).
    pub final_estimate: Pose,
    /// The true final pose.
    pub final_pose: Pose,
    /// The controller's counters.
    pub stats: GuideStats,
    /// What the leg leaves for a mission log (sojourns, decisions).
    pub summary: GuideSummary,
    /// The trace (poses, labels, events, clouds).
    pub trace: LegTrace,
    /// What the simulator measured (`None` for a leg not run).
    pub sim: Option<SimSummary>,
    /// The physical disturbances that happened (pushes, slips, groups).
    pub disturbances: Vec<sim::DisturbanceEvent>,
}

/// What the simulator measured over a leg.
#[derive(Debug, Clone)]
pub struct SimSummary {
    /// Control ticks.
    pub ticks: u64,
    /// Smallest clearance to walls and people, metres.
    pub min_clearance_m: f64,
    /// Final distance between the true and dead-reckoned positions, metres.
    pub odometry_error_m: f64,
    /// The simulator's trace, when the leg asked for one.
    pub trace: Option<sim::Trace>,
}

/// Passes a controller's notes through, keeping its events.
struct Watch<'c> {
    inner: &'c mut GuideController,
    notes: Notes,
}

impl Controller for Watch<'_> {
    fn step(&mut self, p: &Perception, notes: &mut Notes) -> Step {
        self.notes.clear();
        let step = self.inner.step(p, &mut self.notes);
        // The simulator's own trace (replays) gets the notes too.
        self.notes.forward_to(notes);
        step
    }

    fn request(&self) -> Option<Request> {
        self.inner.request()
    }
}

/// The label of the state the controller is in.
fn label(c: &GuideController, asking: bool) -> &'static str {
    use guide::supervisor::Behaviour::{AutoMove, Contour};
    use localization::LocalizationStatus::Warning;
    let warning = c.status() == Warning;
    match (c.active(), warning, asking) {
        (AutoMove, _, true) => "automove / asking",
        (AutoMove, false, false) => "automove",
        (AutoMove, true, false) => "automove / warning",
        (Contour, false, _) => "contour",
        (Contour, true, _) => "contour / warning",
    }
}

fn median(xs: &mut [f64]) -> f64 {
    if xs.is_empty() {
        return 0.0;
    }
    xs.sort_by(f64::total_cmp);
    let n = xs.len();
    if n % 2 == 1 {
        xs[n / 2]
    } else {
        0.5 * (xs[n / 2 - 1] + xs[n / 2])
    }
}

/// One leg to run.
#[derive(Debug, Clone)]
pub struct LegSpec<'a> {
    /// Where from (a name for the result).
    pub from: &'a str,
    /// Where to (a name for the result).
    pub to: &'a str,
    /// The robot's true start pose.
    pub start: Pose,
    /// The controller's initial estimate (the start, on a first leg).
    pub believed: Pose,
    /// The goal.
    pub goal: Vec2,
    /// How the controller chooses its behaviour.
    pub policy: Policy,
    /// Seed of the simulator (the localizer's is derived from it).
    pub seed: u64,
    /// What the simulator's own trace records (off by default).
    pub trace: TraceParams,
}

/// A leg that cannot be run (AutoMove finds no way to the goal): its
/// result, with the reason as an event.
fn unreachable(leg: &LegSpec<'_>, why: String) -> LegRun {
    let LegSpec {
        from,
        to,
        start,
        believed,
        goal,
        ..
    } = *leg;
    LegRun {
        result: LegResult {
            from: from.to_string(),
            to: to.to_string(),
            outcome: LegOutcome::Unreachable,
            time_s: 0.0,
            path_m: 0.0,
            final_error_m: start.position().dist(goal),
            localization: LocalizationSummary::default(),
            planner: PlannerSummary::default(),
        },
        final_estimate: believed,
        final_pose: start,
        stats: GuideStats::default(),
        summary: GuideSummary::default(),
        trace: LegTrace {
            events: vec![Event::new("unreachable", 0.0).with("why", why)],
            ..LegTrace::default()
        },
        sim: None,
        disturbances: Vec::new(),
    }
}

/// The leg's world: the setup's, with its people placed around the
/// anchors near the start when the setup has a plan for them.
fn leg_world<'w>(setup: &'w MissionSetup, leg: &LegSpec<'_>) -> Result<std::borrow::Cow<'w, World>> {
    let LegSpec {
        from,
        to,
        start,
        seed,
        ..
    } = *leg;
    Ok(match &setup.people {
        Some(plan) => {
            let radius = setup.robot.drive.radius_m;
            let at = crowd_near(
                &setup.world,
                &plan.anchors,
                plan.count,
                plan.spread_m,
                start.position(),
                radius + plan.keep_clear_m,
                seed,
            );
            if at.len() < plan.count {
                anyhow::bail!(
                    "leg {from} → {to}: only {} of {} people fit around the places",
                    at.len(),
                    plan.count
                );
            }
            std::borrow::Cow::Owned(setup.world.with_positions(at)?)
        }
        None => std::borrow::Cow::Borrowed(&setup.world),
    })
}

/// What driving a leg leaves: the trace, the estimate's error each tick,
/// whether the estimate was far from the truth for too long, and the time
/// spent lost, warning or fine.
struct Driven {
    trace: LegTrace,
    errors: Vec<f64>,
    lost: bool,
    truth_watch: TruthWatch,
}

/// Drives the leg to its end (or until the estimate has been farther than
/// `lost_error_m` from the truth for `lost_after_s`), a tick of `period`
/// seconds at a time, tracing it.
fn drive(
    setup: &MissionSetup,
    sim: &mut Simulation,
    controller: &mut GuideController,
    period: f64,
) -> Driven {
    let mut trace = LegTrace::default();
    let mut errors = Vec::new();
    let mut far_since: Option<f64> = None;
    let mut lost = false;
    let mut truth_watch = TruthWatch::default();
    let mut watch = Watch {
        inner: controller,
        notes: Notes::enabled(),
    };
    loop {
        let truth = sim.pose();
        let time_s = sim.time_s();
        let ended = sim.tick(&mut watch);
        let estimate = watch.inner.estimate();
        let error = truth.position().dist(estimate.position());
        errors.push(error);
        let heading_error = robot::wrap_angle(truth.theta_rad - estimate.theta_rad).abs();
        truth_watch.tick(
            period,
            error,
            heading_error,
            watch.inner.status() == localization::LocalizationStatus::Warning,
        );
        trace.times.push(time_s);
        trace.poses.push(truth);
        trace.estimates.push(estimate);
        trace
            .labels
            .push(label(watch.inner, watch.inner.request().is_some()));
        for e in &watch.notes.events {
            // A warning comes from a filter iteration, which noted its cloud.
            if e.kind == "warning"
                && let Some((_, cloud)) = watch
                    .notes
                    .clouds
                    .iter()
                    .find(|(n, _)| *n == guide::PARTICLES_CLOUD)
            {
                trace.clouds.push(Cloud {
                    time_s: e.time_s,
                    particles: cloud.iter().map(|p| p.position()).collect(),
                });
            }
            trace.events.push(e.clone());
        }
        if ended.is_some() {
            break;
        }
        if error > setup.lost_error_m {
            let since = *far_since.get_or_insert(time_s);
            if time_s - since >= setup.lost_after_s {
                lost = true;
                break;
            }
        } else {
            far_since = None;
        }
    }
    Driven {
        trace,
        errors,
        lost,
        truth_watch,
    }
}

/// Runs one leg (module docs).
pub fn run_leg(setup: &MissionSetup, leg: &LegSpec<'_>) -> Result<LegRun> {
    let LegSpec {
        from,
        to,
        start,
        believed,
        goal,
        ref policy,
        seed,
        trace: sim_trace,
    } = *leg;
    let map = setup.world.grid().grid_map();
    let prepared = match &setup.prepared {
        Some(m) if m.is_for(&map, &setup.guide) => Ok(std::borrow::Cow::Borrowed(&**m)),
        _ => GuideMap::new(&map, setup.guide.clone()).map(std::borrow::Cow::Owned),
    };
    let started = prepared.and_then(|m| {
        GuideController::on_map(&m, believed, goal, policy.clone(), seed ^ 0x6c6f_6361_6c69_7a65)
    });
    let mut controller = match started {
        Ok(c) => c,
        Err(GuideError::AutoMove(e)) => return Ok(unreachable(leg, e.to_string())),
        Err(e) => return Err(e).context("starting the guide controller"),
    };
    let run = RunParams {
        time_limit_s: setup.time_limit_s,
        goal_tolerance_m: setup.goal_tolerance_m,
        trace: sim_trace,
        ..RunParams::default()
    };
    let task = Task {
        start,
        goal: Some(goal),
    };
    let world = leg_world(setup, leg)?;
    let mut sim = Simulation::new(&world, setup.robot.clone(), run, task, seed)
        .and_then(|s| s.with_disturbances(setup.disturbances.clone()))
        .with_context(|| format!("leg {from} → {to}"))?;
    let Driven {
        trace,
        mut errors,
        lost,
        truth_watch,
    } = drive(setup, &mut sim, &mut controller, run.control_period_s);
    let r = sim.result();
    let outcome = if lost {
        LegOutcome::Lost
    } else {
        match r.outcome {
            Some(Outcome::Goal) => LegOutcome::Reached,
            Some(Outcome::Collision) => LegOutcome::Collision,
            Some(Outcome::TimeLimit) => LegOutcome::Timeout,
            Some(Outcome::Lost) => LegOutcome::Lost,
            Some(Outcome::GaveUp) | None => LegOutcome::GaveUp,
        }
    };
    let stats = controller.stats();
    let mean = if errors.is_empty() {
        0.0
    } else {
        errors.iter().sum::<f64>() / errors.len() as f64
    };
    let max = errors.iter().copied().fold(0.0, f64::max);
    let result = LegResult {
        from: from.to_string(),
        to: to.to_string(),
        outcome,
        time_s: r.time_s,
        path_m: r.path_length_m,
        final_error_m: r.final_pose.position().dist(goal),
        localization: LocalizationSummary {
            mean_error_m: mean,
            median_error_m: median(&mut errors),
            max_error_m: max,
            warnings: stats.warnings,
            time_in_warning_s: stats.time_in_warning_s,
            lost_s: truth_watch.lost_s,
            warning_lost_s: truth_watch.warning_lost_s,
            warning_fine_s: truth_watch.warning_fine_s,
            fine_s: truth_watch.fine_s,
        },
        planner: PlannerSummary {
            abnormal_episodes: stats.abnormal_episodes,
            time_abnormal_s: stats.time_abnormal_s,
        },
    };
    let disturbances = sim.disturbances().to_vec();
    Ok(LegRun {
        disturbances,
        result,
        final_estimate: controller.estimate(),
        final_pose: r.final_pose,
        stats,
        summary: controller.summary(r.time_s),
        trace,
        sim: Some(SimSummary {
            ticks: r.ticks,
            min_clearance_m: r.min_clearance_m,
            odometry_error_m: r.odometry_error_m,
            trace: sim.take_trace(),
        }),
    })
}

/// How often a visitor within reach pushes or turns the robot while it
/// stands, per second ([`visitor_disturbances`]).
pub const PUSH_RATE_PER_PERSON_S: f64 = 0.005;

/// How often a group closes round the robot, per visitor in the building
/// and second ([`visitor_disturbances`]).
pub const SURROUND_RATE_PER_VISITOR_S: f64 = 1.0 / 15_000.0;

/// The physical causes of true loss among `visitors` visitors, with these
/// slip patches (each wheel losing up to `slip_max` of its turn on them).
/// Each rate comes from its cause, so only the number of visitors changes
/// between densities, and every suite of guide legs has the same physics:
///
/// - **pushes**: a visitor within 0.4 m of the robot while it stands
///   (braked, or turning on the spot) pushes or turns it with
///   [`PUSH_RATE_PER_PERSON_S`] (one push per 200 s of a visitor beside the
///   standing robot — children, mostly), 0.3–2 m and up to 90°; the
///   odometry sees nothing;
/// - **groups**: with [`SURROUND_RATE_PER_VISITOR_S`] per visitor (one
///   group every 10 min among 25 visitors, every 4 min among 60) 6–10 of
///   the nearest visitors close round the robot for 20–60 s and do not
///   step aside, hiding every wall from the laser;
/// - **slips**: on the patches, drawn per crossing.
pub fn visitor_disturbances(
    visitors: usize,
    patches: &[sim::SlipPatch],
    slip_max: f64,
) -> sim::DisturbanceParams {
    sim::DisturbanceParams {
        push: sim::PushParams {
            rate_per_person_s: if visitors > 0 { PUSH_RATE_PER_PERSON_S } else { 0.0 },
            ..sim::PushParams::default()
        },
        slip: sim::SlipParams {
            patches: patches.to_vec(),
            slip_max,
        },
        surround: sim::SurroundParams {
            rate_per_s: visitors as f64 * SURROUND_RATE_PER_VISITOR_S,
            ..sim::SurroundParams::default()
        },
    }
}

/// Time in Warning against the truth, tick by tick (the Warning of the
/// state after the tick's control step, the error of the estimate then).
#[derive(Debug, Clone, Copy, Default)]
struct TruthWatch {
    lost_s: f64,
    warning_lost_s: f64,
    warning_fine_s: f64,
    fine_s: f64,
}

impl TruthWatch {
    fn tick(&mut self, dt: f64, error_m: f64, heading_error_rad: f64, warning: bool) {
        let lost = error_m > TRUE_LOSS_M || heading_error_rad > TRUE_LOSS_RAD;
        let fine = error_m < FINE_ERROR_M;
        if lost {
            self.lost_s += dt;
            if warning {
                self.warning_lost_s += dt;
            }
        }
        if fine {
            self.fine_s += dt;
            if warning {
                self.warning_fine_s += dt;
            }
        }
    }
}

/// A named place or a pose.
#[derive(Debug, Clone, PartialEq)]
pub struct Stop {
    /// Its name (the place's, or `x,y,θ`).
    pub name: String,
    /// The pose.
    pub pose: Pose,
}

/// Runs a tour through `stops` in order: one leg between each consecutive
/// pair (module docs). Leg `k` uses the seed derived from `seed` and `k`.
pub fn run_tour(setup: &MissionSetup, stops: &[Stop], policy: Policy, seed: u64) -> Result<Vec<LegRun>> {
    run_tour_interruptible(
        setup,
        stops,
        policy,
        seed,
        &std::sync::atomic::AtomicBool::new(false),
    )
}

/// [`run_tour`], stopped with an error before the next leg once `stop` is
/// raised (from another thread, e.g. on Ctrl-C).
pub fn run_tour_interruptible(
    setup: &MissionSetup,
    stops: &[Stop],
    policy: Policy,
    seed: u64,
    stop: &std::sync::atomic::AtomicBool,
) -> Result<Vec<LegRun>> {
    let mut legs = Vec::new();
    let Some(first) = stops.first() else {
        return Ok(legs);
    };
    let mut here = Whereabouts::at(first);
    for (k, next) in stops.iter().skip(1).enumerate() {
        if stop.load(std::sync::atomic::Ordering::Relaxed) {
            anyhow::bail!("the tour was stopped on request after {k} legs");
        }
        let leg = run_leg(
            setup,
            &LegSpec {
                from: &here.name,
                to: &next.name,
                start: here.pose,
                believed: here.estimate,
                goal: next.pose.position(),
                policy: policy.clone().on_route(&route_name(&here.name, &next.name)),
                seed: crate::runner::derive_seed(seed, "tour leg", k as u32),
                trace: TraceParams::default(),
            },
        )?;
        here = here.after(&leg, next);
        legs.push(leg);
    }
    Ok(legs)
}

/// A leg's route as mission logs name it: `from → to`.
pub fn route_name(from: &str, to: &str) -> String {
    format!("{from} → {to}")
}

/// Where the robot of a tour is between legs.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Whereabouts {
    /// A name for it: the last place reached, else `x,y,θ`.
    pub name: String,
    /// The true pose.
    pub pose: Pose,
    /// The controller's estimate.
    pub estimate: Pose,
}

impl Whereabouts {
    /// At a place, knowing it.
    pub fn at(stop: &Stop) -> Whereabouts {
        Whereabouts {
            name: stop.name.clone(),
            pose: stop.pose,
            estimate: stop.pose,
        }
    }

    /// After `leg` towards `to`: where it stopped when it arrived; after any
    /// other end (collision, time-out, lost, unreachable, gave up) at `to`,
    /// knowing it (the operator took it there: module docs).
    pub fn after(&self, leg: &LegRun, to: &Stop) -> Whereabouts {
        match leg.result.outcome {
            LegOutcome::Reached => Whereabouts {
                name: to.name.clone(),
                pose: leg.final_pose,
                estimate: leg.final_estimate,
            },
            LegOutcome::Collision
            | LegOutcome::Timeout
            | LegOutcome::Lost
            | LegOutcome::Unreachable
            | LegOutcome::GaveUp => Whereabouts::at(to),
        }
    }
}

impl LegTrace {
    /// Writes one JSON object per tick: time, true pose, estimate, state,
    /// and the events of that tick; with the simulator's trace of the leg
    /// (`sim`), also the command and the controller's notes of the tick
    /// (`notes`: name → value, e.g. MCL's `effective_sample_size`, contour
    /// tracking's `contour_mode`; [`guide::GuideController`]).
    pub fn write_json_lines(&self, sim: Option<&sim::Trace>, mut out: impl std::io::Write) -> Result<()> {
        let mut events = self.events.iter().peekable();
        let mut ticks = sim.map(|s| s.ticks.iter().peekable());
        for k in 0..self.times.len() {
            let t = self.times[k];
            let mut now = Vec::new();
            while let Some(e) = events.next_if(|e| e.time_s <= t + 1e-9) {
                now.push(e);
            }
            let mut line = serde_json::json!({
                "time_s": t,
                "true_pose": self.poses[k],
                "estimate": self.estimates[k],
                "state": self.labels[k],
                "events": now,
            });
            // The simulator's tick of the same time (one per control cycle).
            if let Some(tick) = ticks
                .as_mut()
                .and_then(|it| it.next_if(|tick| (tick.time_s - t).abs() < 1e-9))
            {
                let notes: serde_json::Map<String, serde_json::Value> = tick
                    .values
                    .iter()
                    .map(|&(name, v)| (name.to_string(), serde_json::json!(v)))
                    .collect();
                line["command"] = serde_json::json!(tick.command);
                line["notes"] = serde_json::Value::Object(notes);
            }
            serde_json::to_writer(&mut out, &line)?;
            out.write_all(b"\n")?;
        }
        Ok(())
    }
}

/// Free places for `n` people near `anchors` (within `spread_m`, uniform in
/// a disc around a random anchor), none overlapping a wall or another
/// person, none within `keep_clear_m` of `robot`'s centre; drawn
/// from `seed`. A crowd in a building gathers where the tour goes, not in
/// the empty space a SLAM map shows around it. Fewer than `n` when the
/// space runs out (after 200 tries per person).
pub fn crowd_near(
    world: &World,
    anchors: &[Vec2],
    n: usize,
    spread_m: f64,
    robot: Vec2,
    keep_clear_m: f64,
    seed: u64,
) -> Vec<Vec2> {
    use rand::{RngExt, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed ^ 0x0063_726f_7764);
    let r = world.crowd().radius_m;
    let mut out: Vec<Vec2> = Vec::with_capacity(n);
    if anchors.is_empty() {
        return out;
    }
    'people: for _ in 0..n {
        for _ in 0..200 {
            let a = anchors[rng.random_range(0..anchors.len())];
            let d = spread_m * rng.random::<f64>().sqrt();
            let t = std::f64::consts::TAU * rng.random::<f64>();
            let q = a + Vec2::new(d * t.cos(), d * t.sin());
            if world.on_map(q)
                && !world.grid().disc_blocked(q, r + 0.05)
                && q.dist(robot) >= keep_clear_m + r
                && out.iter().all(|o| o.dist(q) >= 2.0 * r + 0.05)
            {
                out.push(q);
                continue 'people;
            }
        }
        // This one found no room: nor will the next ones.
        break;
    }
    out
}

/// A leg's record with what every suite of legs keeps: outcome, time,
/// path, contact, clearance, odometry error, ticks per behaviour label, the
/// true start pose; no metrics, events or state (each suite adds its own).
pub fn leg_base_record(leg: &LegRun) -> crate::record::RunRecord {
    let r = &leg.result;
    let sim = leg.sim.as_ref();
    let mut behaviour_ticks = BTreeMap::new();
    for l in &leg.trace.labels {
        *behaviour_ticks.entry(l.to_string()).or_insert(0) += 1;
    }
    let start = leg.trace.poses.first().copied().unwrap_or_default();
    crate::record::RunRecord {
        success: r.outcome == LegOutcome::Reached,
        outcome: outcome_name(r.outcome).to_string(),
        time_s: r.time_s,
        path_length_m: r.path_m,
        collisions: u32::from(r.outcome == LegOutcome::Collision),
        min_clearance_m: sim.map_or(0.0, |s| s.min_clearance_m),
        odometry_error_m: sim.map_or(0.0, |s| s.odometry_error_m),
        goal_distance_m: r.final_error_m,
        ticks: sim.map_or(0, |s| s.ticks),
        behaviour_ticks,
        metrics: BTreeMap::new(),
        events: Vec::new(),
        start: [start.x_m, start.y_m, start.theta_rad],
        trap: None,
        state: None,
    }
}

/// The lab's common outcome name of a leg's outcome (`goal`, `collision`,
/// `time_limit`, `lost`, `unreachable`, `gave_up`): what summaries count.
pub fn outcome_name(o: LegOutcome) -> &'static str {
    match o {
        LegOutcome::Reached => "goal",
        LegOutcome::Collision => "collision",
        LegOutcome::Timeout => "time_limit",
        LegOutcome::Lost => "lost",
        LegOutcome::Unreachable => "unreachable",
        LegOutcome::GaveUp => "gave_up",
    }
}

/// A trajectory thinned to points at least `step_m` apart (and its last).
fn thin(poses: &[Pose], step_m: f64) -> Vec<[f64; 2]> {
    let mut out: Vec<[f64; 2]> = Vec::new();
    for p in poses {
        if out
            .last()
            .is_none_or(|q| Vec2::new(q[0], q[1]).dist(p.position()) >= step_m)
        {
            out.push([p.x_m, p.y_m]);
        }
    }
    if let (Some(last), Some(p)) = (out.last(), poses.last())
        && Vec2::new(last[0], last[1]).dist(p.position()) > 0.0
    {
        out.push([p.x_m, p.y_m]);
    }
    out
}

/// A leg driven by one behaviour alone, as a calibration run of the
/// mission log: its time, length, and the trajectory the robot estimated
/// (every 0.5 m).
pub fn calibration_entry(leg: &LegRun, behaviour: Behaviour) -> Entry {
    Entry::Calibration(CalibrationRun {
        behaviour,
        success: leg.result.outcome == LegOutcome::Reached,
        duration_s: leg.result.time_s,
        path_m: leg.result.path_m,
        trajectory: thin(&leg.trace.estimates, 0.5),
        outcome: String::new(),
        segments: Vec::new(),
        route: None,
    })
}

/// [`calibration_entry`] with the run's outcome and segments, for the
/// crediting supervisor's log (which learns from calibration runs too).
pub fn credit_calibration_entry(leg: &LegRun, behaviour: Behaviour) -> Entry {
    match calibration_entry(leg, behaviour) {
        Entry::Calibration(c) => Entry::Calibration(CalibrationRun {
            outcome: outcome_name(leg.result.outcome).to_string(),
            segments: leg.summary.segments.clone(),
            ..c
        }),
        other => other,
    }
}

/// A leg as mission `number` of the mission log: outcome, duration, the
/// sojourns of the localizer and the planner, time per behaviour,
/// decisions.
pub fn mission_entry(leg: &LegRun, number: u32) -> Entry {
    let s = &leg.summary;
    Entry::Mission(MissionRecord {
        mission: number,
        success: leg.result.outcome == LegOutcome::Reached,
        outcome: outcome_name(leg.result.outcome).to_string(),
        duration_s: leg.result.time_s,
        localizer: s.localizer.clone(),
        planner: s.planner.clone(),
        time_automove_s: s.time_automove_s,
        time_contour_s: s.time_contour_s,
        decisions: s.decisions.clone(),
        segments: s.segments.clone(),
        route: None,
    })
}

/// Colour of the particles drawn at warnings.
pub const CLOUD_RGB: [u8; 3] = [0, 160, 160];

/// Draws legs over the map: true trajectories coloured by behaviour and
/// state, the particle clouds at warnings, the places (`stops`, labelled),
/// cropped to what was driven with a margin. PNG or SVG by extension.
pub fn picture(grid: &OccupancyGrid, legs: &[LegRun], stops: &[Stop], path: &std::path::Path) -> Result<()> {
    let mut pic = Picture::new(grid);
    let mut lo = Vec2::new(f64::INFINITY, f64::INFINITY);
    let mut hi = Vec2::new(f64::NEG_INFINITY, f64::NEG_INFINITY);
    let mut grow = |p: Vec2| {
        lo = Vec2::new(lo.x.min(p.x), lo.y.min(p.y));
        hi = Vec2::new(hi.x.max(p.x), hi.y.max(p.y));
    };
    for s in stops {
        grow(s.pose.position());
    }
    for leg in legs {
        for p in &leg.trace.poses {
            grow(p.position());
        }
    }
    if lo.x.is_finite() {
        pic.crop(lo - Vec2::new(3.0, 3.0), hi + Vec2::new(3.0, 3.0));
    }
    for leg in legs {
        for cloud in &leg.trace.clouds {
            for &q in &cloud.particles {
                pic.marker(q, MarkerKind::Square(CLOUD_RGB));
            }
        }
    }
    for leg in legs {
        pic.trajectory(&leg.trace.poses, Some(&leg.trace.labels));
    }
    let mut named: BTreeMap<String, Vec2> = BTreeMap::new();
    for (k, s) in stops.iter().enumerate() {
        let kind = if k == 0 {
            MarkerKind::Start
        } else {
            MarkerKind::Goal
        };
        pic.marker(s.pose.position(), kind);
        named.entry(s.name.clone()).or_insert(s.pose.position());
    }
    for (name, at) in &named {
        pic.text(*at + Vec2::new(0.3, 0.3), name);
    }
    pic.save(path)
        .with_context(|| format!("writing {}", path.display()))?;
    Ok(())
}

/// The metric names of a leg's record ([`leg_record`]).
pub mod metric {
    /// Mean true position error of the localizer over a leg, metres.
    pub const LOC_MEAN: &str = "loc_mean_error_m";
    /// Largest true position error over a leg, metres.
    pub const LOC_MAX: &str = "loc_max_error_m";
    /// Warnings of the localizer in a leg.
    pub const WARNINGS: &str = "warnings";
    /// Time in Warning in a leg, seconds.
    pub const WARNING_S: &str = "time_in_warning_s";
    /// AutoMove's abnormal episodes in a leg.
    pub const ABNORMAL: &str = "abnormal_episodes";
    /// Time Abnormal in a leg, seconds.
    pub const ABNORMAL_S: &str = "time_abnormal_s";
    /// Time truly lost (error over 0.5 m or 20°), seconds.
    pub const LOST_S: &str = "time_lost_s";
    /// Time in Warning while truly lost, seconds.
    pub const WARNING_LOST_S: &str = "time_warning_lost_s";
    /// Time with the true error under 0.2 m, seconds.
    pub const FINE_S: &str = "time_fine_s";
    /// Time in Warning with the true error under 0.2 m, seconds.
    pub const WARNING_FINE_S: &str = "time_warning_fine_s";
    /// Pushes.
    pub const PUSHES: &str = "pushes";
    /// Groups closing round the robot.
    pub const SURROUNDS: &str = "surrounds";
}

/// A leg's record, as the `maps` suite keeps it (without the suite's state): the
/// outcome, time, path, clearance, ticks per behaviour and the
/// localization and planner measures.
pub fn leg_record(leg: &LegRun) -> Result<RunRecord> {
    let r = &leg.result;
    let mut record = leg_base_record(leg);
    let l = &r.localization;
    record.set_metric(metric::LOC_MEAN, l.mean_error_m)?;
    record.set_metric(metric::LOC_MAX, l.max_error_m)?;
    record.set_metric(metric::WARNINGS, f64::from(l.warnings))?;
    record.set_metric(metric::WARNING_S, l.time_in_warning_s)?;
    record.set_metric(metric::ABNORMAL, f64::from(r.planner.abnormal_episodes))?;
    record.set_metric(metric::ABNORMAL_S, r.planner.time_abnormal_s)?;
    record.set_metric(metric::LOST_S, l.lost_s)?;
    record.set_metric(metric::WARNING_LOST_S, l.warning_lost_s)?;
    record.set_metric(metric::FINE_S, l.fine_s)?;
    record.set_metric(metric::WARNING_FINE_S, l.warning_fine_s)?;
    let count = |kind: &str| leg.disturbances.iter().filter(|d| d.kind.name() == kind).count() as f64;
    record.set_metric(metric::PUSHES, count("push"))?;
    record.set_metric(metric::SURROUNDS, count("surround"))?;
    Ok(record)
}

/// A leg run with a simulator trace ([`LegSpec::trace`]) as a
/// replay to draw, watch or export (`nav go --html`): its `record` (e.g.
/// [`leg_record`]), the trace taken out of the leg, the setup it ran in
/// (map, robot) and the goal.
pub fn leg_replay(record: RunRecord, setup: &MissionSetup, leg: &mut LegRun, goal: Vec2) -> Result<Replay> {
    Ok(Replay {
        record,
        trace: leg
            .sim
            .as_mut()
            .and_then(|s| s.trace.take())
            .context("the leg was run without a simulator trace")?,
        grid: setup.world.grid().clone(),
        goal: Some(goal),
        robot_radius_m: setup.robot.drive.radius_m,
        // `mission::run_leg` runs at the simulator's default period.
        control_period_s: sim::RunParams::default().control_period_s,
        net: None,
    })
}

/// The crediting supervisor's net (`models/supervisor_credit.toml`) as a
/// viewer page draws it beside a leg the supervisor drove: its marking from
/// the controller's `net.P…` values, the last `decision` beside it.
pub fn supervisor_net_view() -> Result<crate::net_view::NetView> {
    let net = petri::io::read_str(
        guide::supervisor::credit::CREDIT_MODEL,
        petri::io::Format::Toml,
        "models/supervisor_credit.toml",
    )?;
    Ok(crate::net_view::NetView::of(&net, "net.", "decision"))
}

/// The events drawn on pictures and viewer pages of legs beyond the
/// trajectory's colours: the localizer's warnings.
pub const MARKERS: [EventMarker; 1] = [EventMarker {
    kind: "warning",
    marker: sim::render::MarkerKind::Ring([0, 160, 160]),
    place: MarkerPlace::Event,
    single_run_only: false,
}];

#[cfg(test)]
mod tests {
    use super::*;

    fn leg(outcome: LegOutcome, end: Pose) -> LegRun {
        LegRun {
            result: LegResult {
                from: "a".into(),
                to: "b".into(),
                outcome,
                time_s: 10.0,
                path_m: 1.0,
                final_error_m: 1.0,
                localization: LocalizationSummary::default(),
                planner: PlannerSummary::default(),
            },
            final_estimate: Pose::new(end.x_m + 0.1, end.y_m, end.theta_rad),
            final_pose: end,
            stats: GuideStats::default(),
            summary: GuideSummary::default(),
            trace: LegTrace::default(),
            sim: None,
            disturbances: Vec::new(),
        }
    }

    #[test]
    fn after_a_failed_leg_the_operator_takes_the_robot_to_its_place() {
        let here = Whereabouts::at(&Stop {
            name: "a".into(),
            pose: Pose::new(0.0, 0.0, 0.0),
        });
        let to = Stop {
            name: "b".into(),
            pose: Pose::new(5.0, 2.0, 1.0),
        };
        let end = Pose::new(3.0, 1.0, 0.5);
        // Arrived: where it stopped, with the estimate it has.
        let w = here.after(&leg(LegOutcome::Reached, end), &to);
        assert_eq!((w.name.as_str(), w.pose), ("b", end));
        assert_eq!(w.estimate, Pose::new(3.1, 1.0, 0.5));
        // Any other end, a collision included: at the place, knowing it.
        for outcome in [
            LegOutcome::Collision,
            LegOutcome::Timeout,
            LegOutcome::Lost,
            LegOutcome::Unreachable,
            LegOutcome::GaveUp,
        ] {
            let w = here.after(&leg(outcome, end), &to);
            assert_eq!(w, Whereabouts::at(&to), "{outcome:?}");
        }
    }
}
