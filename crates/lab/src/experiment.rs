//! One run of a scenario: the world (with its per-run variation), the
//! robot, the controller, the simulation, and the run's record.
//!
//! A run is reproducible from its seed alone: the start pose and obstacle
//! jitter come from a ChaCha8 stream of the seed, the simulator draws its
//! own streams from the same seed.

use std::collections::BTreeMap;

use activity::PriorityController;
use anyhow::{Context, Result};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use robot::{Controller, Event, Notes, Perception, Pose, Step, Vec2};
use sim::shapes::WorldSpec;
use sim::{CrowdParams, CrowdSize, OccupancyGrid, RunParams, Simulation, Task, Trace, TraceParams, World};
use voting::VotingController;

use crate::record::RunRecord;
use crate::scenario::{ControllerKind, Scenario};
use crate::traps::DrawnTrap;

/// A scenario ready to run many times: the world is built once when it does
/// not vary between runs.
pub struct Prepared {
    scenario: Scenario,
    fixed_world: Option<World>,
    base_grid: Option<OccupancyGrid>,
}

fn jitter_world(spec: &WorldSpec, amount_m: f64, rng: &mut ChaCha8Rng) -> WorldSpec {
    let mut w = spec.clone();
    let mut shift = || {
        let r = amount_m * rng.random::<f64>().sqrt();
        let a = std::f64::consts::TAU * rng.random::<f64>();
        (r * a.cos(), r * a.sin())
    };
    for s in &mut w.rects {
        let (dx, dy) = shift();
        s.x += dx;
        s.y += dy;
    }
    for s in &mut w.circles {
        let (dx, dy) = shift();
        s.x += dx;
        s.y += dy;
    }
    for s in &mut w.polygons {
        let (dx, dy) = shift();
        for p in &mut s.points {
            p[0] += dx;
            p[1] += dy;
        }
    }
    for s in &mut w.segments {
        let (dx, dy) = shift();
        s.from[0] += dx;
        s.from[1] += dy;
        s.to[0] += dx;
        s.to[1] += dy;
    }
    w
}

impl Prepared {
    /// Loads maps and builds the world if it is the same for every run.
    pub fn new(scenario: Scenario) -> Result<Prepared> {
        let base_grid = match (&scenario.world, &scenario.map) {
            (_, Some(map)) => Some(
                sim::map_server::load(map)
                    .with_context(|| format!("scenario `{}`", scenario.name))?
                    .grid,
            ),
            (Some(w), None) if scenario.jitter.obstacles_m == 0.0 && scenario.trap.is_none() => {
                Some(w.rasterise()?)
            }
            _ => None,
        };
        let fixed_world = match &base_grid {
            Some(g) => Some(Prepared::populate(&scenario, World::new(g.clone()))?),
            None => None,
        };
        Ok(Prepared {
            scenario,
            fixed_world,
            base_grid,
        })
    }

    /// The scenario.
    pub fn scenario(&self) -> &Scenario {
        &self.scenario
    }

    fn populate(s: &Scenario, world: World) -> Result<World> {
        let size = match (s.people.count, s.people.density) {
            (Some(n), _) if n > 0 => CrowdSize::Count { people: n },
            (_, Some(d)) if d > 0.0 => CrowdSize::PerArea { people_per_100m2: d },
            _ => return Ok(world),
        };
        Ok(world.with_crowd(CrowdParams {
            size,
            ..CrowdParams::default()
        })?)
    }

    /// The world of a run (built for this run if obstacles vary or a trap
    /// is drawn), and the trap drawn.
    fn world_for(
        &self,
        start: Pose,
        rng: &mut ChaCha8Rng,
    ) -> Result<(std::borrow::Cow<'_, World>, Option<DrawnTrap>)> {
        if let Some(w) = &self.fixed_world {
            return Ok((std::borrow::Cow::Borrowed(w), None));
        }
        let s = &self.scenario;
        let spec = s.world.as_ref().context("no world")?;
        let mut varied = jitter_world(spec, s.jitter.obstacles_m, rng);
        let trap = s
            .trap
            .as_ref()
            .map(|t| t.draw(start.position(), Vec2::new(s.goal.x, s.goal.y), &mut varied, rng));
        let grid = varied.rasterise()?;
        Ok((
            std::borrow::Cow::Owned(Prepared::populate(s, World::new(grid))?),
            trap,
        ))
    }

    /// The grid without per-run variation (for pictures).
    pub fn base_grid(&self) -> Result<OccupancyGrid> {
        match &self.base_grid {
            Some(g) => Ok(g.clone()),
            None => Ok(self.scenario.world.as_ref().context("no world")?.rasterise()?),
        }
    }

    /// The controller the scenario names, with its parameters.
    pub fn controller(&self) -> Result<Box<dyn Controller>> {
        let c = &self.scenario.controller;
        Ok(match c.kind {
            ControllerKind::Voting => {
                let v = VotingController::new(c.voting.clone()).map_err(|e| anyhow::anyhow!(e))?;
                if c.trace_layer.enabled {
                    Box::new(voting::trace_layer::TracedVoting::new(v, c.priority))
                } else {
                    Box::new(v)
                }
            }
            ControllerKind::Priority => {
                Box::new(PriorityController::new(c.priority).map_err(|e| anyhow::anyhow!(e))?)
            }
        })
    }

    /// Runs once with the scenario's controller, recording what `trace`
    /// asks for ([`Prepared::run_with`]).
    pub fn run_detailed(&self, seeds: RunSeeds, trace: TraceParams) -> Result<RunOutput> {
        self.run_with(seeds, trace, self.controller()?)
    }

    /// Runs once with `controller` in place of the scenario's (a suite's
    /// own controller), recording what `trace` asks for; returns the run's
    /// common measures, every event the controller emitted, and, with a
    /// trace, the run's own world grid (obstacle jitter included) for
    /// pictures and replays. The record's `metrics` and `events` are left
    /// empty: what to keep is the suite's choice.
    pub fn run_with(
        &self,
        seeds: RunSeeds,
        trace: TraceParams,
        controller: Box<dyn Controller>,
    ) -> Result<RunOutput> {
        let seed = seeds.sim;
        let s = &self.scenario;
        let mut rng = ChaCha8Rng::seed_from_u64(seeds.variation ^ 0x5eed_1ab0_0000_0001);
        let r = s.start.jitter_m * rng.random::<f64>().sqrt();
        let a = std::f64::consts::TAU * rng.random::<f64>();
        let dtheta = s.start.jitter_deg * (2.0 * rng.random::<f64>() - 1.0);
        let start = Pose::new(
            s.start.x + r * a.cos(),
            s.start.y + r * a.sin(),
            (s.start.theta_deg + dtheta).to_radians(),
        );
        let (world, trap) = self.world_for(start, &mut rng)?;
        let robot = s.robot.robot_params();
        let run = RunParams {
            control_period_s: s.control_period_s,
            time_limit_s: s.time_limit_s,
            goal_tolerance_m: s.goal_tolerance_m,
            collision_fatal: s.collision_fatal,
            trace,
            ..RunParams::default()
        };
        let task = Task {
            start,
            goal: Some(Vec2::new(s.goal.x, s.goal.y)),
        };
        let mut sim = Simulation::new(&world, robot, run, task, seed)
            .with_context(|| format!("scenario `{}`", s.name))?;
        let mut counting = Counting {
            inner: controller,
            notes: Notes::enabled(),
            ticks: BTreeMap::new(),
            events: Vec::new(),
        };
        let result = sim.run(&mut counting);
        let outcome = result
            .outcome
            .map(|o| {
                serde_json::to_value(o)
                    .ok()
                    .and_then(|v| v.as_str().map(str::to_string))
                    .unwrap_or_else(|| format!("{o:?}"))
            })
            .unwrap_or_else(|| "running".into());
        let record = RunRecord {
            success: result.outcome.is_some_and(|o| o.is_success()),
            outcome,
            time_s: result.time_s,
            path_length_m: result.path_length_m,
            collisions: result.collisions,
            min_clearance_m: result.min_clearance_m,
            odometry_error_m: result.odometry_error_m,
            goal_distance_m: result.goal_distance_m.unwrap_or(f64::NAN),
            ticks: result.ticks,
            behaviour_ticks: counting
                .ticks
                .into_iter()
                .map(|(k, v)| (k.to_string(), v))
                .collect(),
            metrics: BTreeMap::new(),
            events: Vec::new(),
            start: [start.x_m, start.y_m, start.theta_rad],
            trap,
            state: None,
        };
        let grid = if trace.enabled {
            Some(world.grid().clone())
        } else {
            None
        };
        Ok(RunOutput {
            record,
            events: counting.events,
            trace: sim.take_trace(),
            grid,
        })
    }
}

/// The seeds of one run.
///
/// The per-run variation of the scenario (start pose, obstacle jitter, the
/// drawn trap) comes from `variation`, the simulator's noise from `sim`. A
/// suite derives both from the run index alone ([`crate::scenario_suite::ScenarioSuite::seeds`]):
/// run `k` of every scenario in a suite meets the same variation and the
/// same noise, so controllers are compared on the same draws (common random
/// numbers).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RunSeeds {
    /// Seed of the simulator's noise streams.
    pub sim: u64,
    /// Seed of the scenario's per-run variation.
    pub variation: u64,
}

/// Everything [`Prepared::run_detailed`] produced.
pub struct RunOutput {
    /// The run's record: the common measures (no metrics or events yet).
    pub record: RunRecord,
    /// Every event the controller emitted, in order.
    pub events: Vec<Event>,
    /// The trace, when one was asked for.
    pub trace: Option<Trace>,
    /// The run's world grid (with this run's obstacle jitter), when a trace
    /// was asked for.
    pub grid: Option<OccupancyGrid>,
}

/// Counts the behaviour in control each tick, keeps the events, and passes
/// the notes on when the simulator records them.
struct Counting {
    inner: Box<dyn Controller>,
    notes: Notes,
    ticks: BTreeMap<&'static str, u64>,
    events: Vec<Event>,
}

impl Controller for Counting {
    fn step(&mut self, perception: &Perception, notes: &mut Notes) -> Step {
        self.notes.clear();
        let step = self.inner.step(perception, &mut self.notes);
        if let Some(b) = self.notes.behaviour {
            *self.ticks.entry(b).or_insert(0) += 1;
        }
        self.events.extend(self.notes.events.iter().cloned());
        self.notes.forward_to(notes);
        step
    }

    fn request(&self) -> Option<robot::Request> {
        self.inner.request()
    }
}
