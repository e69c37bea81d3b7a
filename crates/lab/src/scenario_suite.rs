//! A suite made of scenarios ([`crate::scenario::Scenario`]), each run a
//! number of times independently: everything but what the suite adds —
//! its metrics, the events it keeps, its report — which come as
//! [`ScenarioHooks`].

use std::collections::BTreeMap;

use anyhow::{Context, Result};
use rayon::prelude::*;
use sim::TraceParams;

use crate::experiment::{Prepared, RunOutput, RunSeeds};
use crate::page::{Block, Figure, RunLink};
use crate::pictures::{self, EventMarker, Replay};
use crate::record::RunRecord;
use crate::runner::{self, Campaign, Job};
use crate::suite::{ReportContext, Suite, SuiteInfo, SuiteReport};
use crate::viewer::PageRun;

/// The name from which every run's simulator seed is derived
/// ([`ScenarioSuite::seeds`]).
const NOISE_STREAM: &str = "simulator noise";

/// Runs drawn per scenario picture.
pub const RUNS_PER_PICTURE: u32 = 8;

/// What a scenario suite adds to the generic machinery.
#[derive(Clone, Copy)]
pub struct ScenarioHooks {
    /// Sets the run's metrics from what it produced (its events, its
    /// record).
    pub metrics: fn(&RunOutput, &mut RunRecord) -> Result<()>,
    /// Event kinds kept in the records (the rest stays in traces).
    pub keep_events: &'static [&'static str],
    /// How events are drawn on pictures.
    pub markers: &'static [EventMarker],
    /// The suite's report.
    pub report: fn(&ScenarioSuite, &ReportContext<'_>) -> Result<SuiteReport>,
}

/// A suite of scenarios, each run `runs` times.
pub struct ScenarioSuite {
    info: SuiteInfo,
    scenarios: Vec<Prepared>,
    hooks: ScenarioHooks,
}

impl ScenarioSuite {
    /// A suite called `name`, registered as `suite`, running each of
    /// `scenarios` `runs` times from base seed `seed`; `sources` says where
    /// scenarios came from (files), by name.
    pub fn new(
        name: &str,
        suite: &str,
        runs: u32,
        seed: u64,
        scenarios: Vec<Prepared>,
        sources: BTreeMap<String, String>,
        hooks: ScenarioHooks,
    ) -> ScenarioSuite {
        ScenarioSuite {
            info: SuiteInfo {
                name: name.to_string(),
                suite: suite.to_string(),
                runs,
                seed,
                scenarios: scenarios.iter().map(|p| p.scenario().name.clone()).collect(),
                sources,
            },
            scenarios,
            hooks,
        }
    }

    /// The seeds of run `run` of every scenario ([`RunSeeds`]).
    ///
    /// Common random numbers: run k of every scenario in a batch meets the
    /// same per-run variation (start, jitter, trap) and the same simulator
    /// noise streams (sensors, odometry, people); neither depends on the
    /// scenario's name. Two scenarios that differ only in the controller —
    /// the five experiments on one field of the voting suite, the
    /// controllers of the dead-lock suite, two parameter sets in your own
    /// files — therefore run identically until the controllers act
    /// differently: with the activity-trace layer, a run in which no
    /// dead-lock is detected is the run without it, tick for tick. Their
    /// difference is measured on the same draws, free of sampling noise
    /// between them.
    pub fn seeds(&self, run: u32) -> RunSeeds {
        RunSeeds {
            sim: runner::derive_seed(self.info.seed, NOISE_STREAM, run),
            variation: runner::derive_seed(self.info.seed, "", run),
        }
    }

    /// The prepared scenario called `name`.
    pub fn scenario(&self, name: &str) -> Option<&Prepared> {
        self.scenarios.iter().find(|p| p.scenario().name == name)
    }

    /// The prepared scenarios, in order.
    pub fn scenarios(&self) -> &[Prepared] {
        &self.scenarios
    }

    fn prepared(&self, job: &Job) -> Result<&Prepared> {
        self.scenario(&job.scenario)
            .with_context(|| format!("unknown scenario `{}`", job.scenario))
    }

    /// The record of a run's output: the common measures, the suite's
    /// metrics, the events it keeps.
    fn record(&self, out: &RunOutput) -> Result<RunRecord> {
        let mut record = out.record.clone();
        (self.hooks.metrics)(out, &mut record)?;
        record.events = out
            .events
            .iter()
            .filter(|e| self.hooks.keep_events.contains(&e.kind.as_str()))
            .cloned()
            .collect();
        Ok(record)
    }

    /// Replays run `run` of `prep`.
    fn replay_run(&self, prep: &Prepared, run: u32, trace: TraceParams) -> Result<Replay> {
        let out = prep.run_detailed(self.seeds(run), trace)?;
        let record = self.record(&out)?;
        let s = prep.scenario();
        Ok(Replay {
            record,
            trace: out.trace.context("the run kept no trace")?,
            grid: out.grid.context("the run kept no world")?,
            goal: Some(robot::Vec2::new(s.goal.x, s.goal.y)),
            robot_radius_m: s.robot.robot_params().drive.radius_m,
            control_period_s: s.control_period_s,
            net: None,
        })
    }

    /// Runs a scenario once, as a results line would record it.
    pub fn run_once(&self, name: &str, run: u32) -> Result<RunRecord> {
        let prep = self
            .scenario(name)
            .with_context(|| format!("unknown scenario `{name}`"))?;
        self.record(&prep.run_detailed(self.seeds(run), TraceParams::default())?)
    }

    /// The picture of `prep`'s first runs and their viewer page: the figure,
    /// and the files written.
    fn scenario_figure(
        &self,
        ctx: &ReportContext<'_>,
        prep: &Prepared,
    ) -> Result<(Figure, Vec<std::path::PathBuf>)> {
        let name = &prep.scenario().name;
        let (path, src) = ctx.picture_path(&format!("{}.png", name.replace('/', "-")))?;
        // Every run with everything the viewer shows: the picture's page
        // holds them all.
        let replays = (0..RUNS_PER_PICTURE.min(self.info.runs))
            .map(|run| self.replay_run(prep, run, TraceParams::full()))
            .collect::<Result<Vec<_>>>()?;
        pictures::overlay_picture(&replays, self.hooks.markers, &path)?;
        let keys: Vec<String> = (0..replays.len()).map(|run| format!("{name}#{run}")).collect();
        let page_runs: Vec<PageRun<'_>> = replays
            .iter()
            .zip(&keys)
            .map(|(replay, key)| PageRun { replay, key })
            .collect();
        let (page, href) = ctx.viewer_runs_page(&page_runs, self.hooks.markers, name)?;
        let runs = (0..replays.len())
            .map(|run| RunLink {
                label: format!("#{run}"),
                href: format!("{href}#run={run}"),
            })
            .collect();
        Ok((
            Figure {
                title: name.clone(),
                src,
                runs,
            },
            vec![path, page],
        ))
    }

    /// The pictures block of a report: the first [`RUNS_PER_PICTURE`] runs
    /// of every scenario drawn over each other (re-simulated), with the
    /// suite's event markers, and under each the links to its runs on one
    /// viewer page (`viewer/SCENARIO.html#run=K`); `None` when the report is
    /// asked without pictures.
    pub fn pictures(
        &self,
        ctx: &ReportContext<'_>,
        caption: &str,
        files: &mut Vec<std::path::PathBuf>,
    ) -> Result<Option<Block>> {
        if !ctx.pictures {
            return Ok(None);
        }
        // A scenario at a time on every core (the replays dominate); the
        // figures in the suite's order whatever the thread count.
        let drawn = self
            .scenarios
            .par_iter()
            .map(|prep| self.scenario_figure(ctx, prep))
            .collect::<Result<Vec<_>>>()?;
        let mut figures = Vec::new();
        for (figure, written) in drawn {
            figures.push(figure);
            files.extend(written);
        }
        Ok(Some(Block::Figures {
            heading: "Trajectories".into(),
            caption: caption.to_string(),
            figures,
        }))
    }
}

impl Suite for ScenarioSuite {
    fn info(&self) -> &SuiteInfo {
        &self.info
    }

    fn campaigns(&self) -> Vec<Campaign> {
        Campaign::independent(runner::jobs(&self.info.scenarios, self.info.runs, |_, run| {
            self.seeds(run).sim
        }))
    }

    fn run(&self, job: &Job, _earlier: &[RunRecord]) -> Result<RunRecord> {
        let out = self
            .prepared(job)?
            .run_detailed(self.seeds(job.run), TraceParams::default())?;
        self.record(&out)
    }

    fn replay(&self, job: &Job, _earlier: &[RunRecord], trace: TraceParams) -> Result<Replay> {
        self.replay_run(self.prepared(job)?, job.run, trace)
    }

    fn markers(&self) -> &[EventMarker] {
        self.hooks.markers
    }

    fn report(&self, ctx: &ReportContext<'_>) -> Result<SuiteReport> {
        (self.hooks.report)(self, ctx)
    }
}
