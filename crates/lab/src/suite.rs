//! Suites: named sets of scenarios run as one batch.
//!
//! | suite | scenarios |
//! |---|---|
//! | `voting` | the fourteen fields of `scenarios/voting/` × the four behaviour combinations of the source (`e1`…`e4`) and `e4` with the activity-trace layer (`e5`) |
//! | `deadlock` | `scenarios/deadlock/`: a dead-end trap drawn per run (U, and V in two rows); priority arbitration on the 16-sonar ring robot with and without dead-lock detection + recovery (and with drifting odometry), voting on AIBOT with and without the trace layer |
//! | a scenario file | that scenario alone |
//!
//! The shipped scenarios are compiled into the binary, so a suite runs from
//! anywhere; the files in `scenarios/` are the same text, for reading and
//! copying.

use std::collections::BTreeMap;
use std::path::Path;

use anyhow::{Context, Result, bail};
use nav::voting::Teams;

use crate::experiment::{Prepared, RunSeeds};
use crate::runner::{self, BatchParams, BatchSummary, Job, Shard};
use crate::scenario::{ControllerKind, Scenario};

/// The fourteen fields of the voting experiments, as shipped.
pub const VOTING_FIELDS: [(&str, &str); 14] = [
    ("field01", include_str!("../../../scenarios/voting/field01.toml")),
    ("field02", include_str!("../../../scenarios/voting/field02.toml")),
    ("field03", include_str!("../../../scenarios/voting/field03.toml")),
    ("field04", include_str!("../../../scenarios/voting/field04.toml")),
    ("field05", include_str!("../../../scenarios/voting/field05.toml")),
    ("field06", include_str!("../../../scenarios/voting/field06.toml")),
    ("field07", include_str!("../../../scenarios/voting/field07.toml")),
    ("field08", include_str!("../../../scenarios/voting/field08.toml")),
    ("field09", include_str!("../../../scenarios/voting/field09.toml")),
    ("field10", include_str!("../../../scenarios/voting/field10.toml")),
    ("field11", include_str!("../../../scenarios/voting/field11.toml")),
    ("field12", include_str!("../../../scenarios/voting/field12.toml")),
    ("field13", include_str!("../../../scenarios/voting/field13.toml")),
    ("field14", include_str!("../../../scenarios/voting/field14.toml")),
];

/// The dead-lock suite's scenarios, as shipped.
pub const DEADLOCK_SCENARIOS: [(&str, &str); 7] = [
    (
        "priority",
        include_str!("../../../scenarios/deadlock/priority.toml"),
    ),
    (
        "priority_recovery",
        include_str!("../../../scenarios/deadlock/priority_recovery.toml"),
    ),
    (
        "priority_recovery_slips",
        include_str!("../../../scenarios/deadlock/priority_recovery_slips.toml"),
    ),
    (
        "priority_v",
        include_str!("../../../scenarios/deadlock/priority_v.toml"),
    ),
    (
        "priority_v_recovery",
        include_str!("../../../scenarios/deadlock/priority_v_recovery.toml"),
    ),
    ("voting", include_str!("../../../scenarios/deadlock/voting.toml")),
    (
        "voting_trace",
        include_str!("../../../scenarios/deadlock/voting_trace.toml"),
    ),
];

/// The experiments of the voting suite: `e1`…`e4` are the source's four
/// behaviour combinations; `e5` is `e4` with the activity-trace layer
/// (dead-lock detection and recovery, activity-trace.md).
pub const VOTING_EXPERIMENTS: u32 = 5;

/// The name from which every run's simulator seed is derived
/// ([`Suite::seeds`]).
const NOISE_STREAM: &str = "simulator noise";

/// What kind of suite, for the report.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SuiteKind {
    /// The voting suite: fields × combinations.
    Voting,
    /// The dead-lock suite: traps, with and without detection + recovery.
    Deadlock,
    /// Scenarios from files.
    Custom,
}

/// A suite ready to run.
pub struct Suite {
    /// Name.
    pub name: String,
    /// Kind.
    pub kind: SuiteKind,
    /// Runs per scenario.
    pub runs: u32,
    /// Base seed.
    pub seed: u64,
    /// Scenarios by name, in order.
    pub scenarios: Vec<Prepared>,
}

/// What a results folder says about the suite that produced it
/// (`suite.json`), so that a report can be recomputed from the folder alone.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SuiteInfo {
    /// Name.
    pub name: String,
    /// Kind.
    pub kind: SuiteKind,
    /// Runs per scenario.
    pub runs: u32,
    /// Base seed.
    pub seed: u64,
    /// Scenario names, in order.
    pub scenarios: Vec<String>,
    /// Where custom scenarios came from (file paths), by name.
    #[serde(default)]
    pub sources: BTreeMap<String, String>,
}

/// The label of a voting-suite experiment (`e1` … `e4`), e.g.
/// "IR+sonar / odo+plan".
pub fn experiment_label(name: &str) -> Option<String> {
    let k: u32 = name.strip_prefix('e')?.parse().ok()?;
    match k {
        5 => Teams::experiment(4).map(|t| format!("{} + trace", t.label())),
        _ => Teams::experiment(k).map(|t| t.label()),
    }
}

impl Suite {
    /// The voting suite with `runs` runs per scenario (default 50).
    pub fn voting(runs: Option<u32>) -> Result<Suite> {
        let mut scenarios = Vec::new();
        let mut runs_default = 50;
        let mut seed = 1;
        for k in 1..=VOTING_EXPERIMENTS {
            let teams = Teams::experiment(k.min(4)).context("experiment")?;
            for (name, text) in VOTING_FIELDS {
                let mut s = Scenario::parse(text, &format!("scenarios/voting/{name}.toml"), None)?;
                runs_default = s.runs;
                seed = s.seed;
                s.name = format!("e{k}/{name}");
                s.controller.kind = ControllerKind::Voting;
                s.controller.voting.teams = teams;
                s.controller.trace_layer.enabled = k == 5;
                s.controller.priority.recovery = true;
                scenarios.push(Prepared::new(s)?);
            }
        }
        Ok(Suite {
            name: "voting".into(),
            kind: SuiteKind::Voting,
            runs: runs.unwrap_or(runs_default),
            seed,
            scenarios,
        })
    }

    /// The dead-lock suite with `runs` runs per scenario (default 200).
    pub fn deadlock(runs: Option<u32>) -> Result<Suite> {
        let mut scenarios = Vec::new();
        let mut runs_default = 200;
        let mut seed = 1;
        for (name, text) in DEADLOCK_SCENARIOS {
            let s = Scenario::parse(text, &format!("scenarios/deadlock/{name}.toml"), None)?;
            runs_default = s.runs;
            seed = s.seed;
            scenarios.push(Prepared::new(s)?);
        }
        Ok(Suite {
            name: "deadlock".into(),
            kind: SuiteKind::Deadlock,
            runs: runs.unwrap_or(runs_default),
            seed,
            scenarios,
        })
    }

    /// A shipped suite by name (`voting`, `deadlock`), if there is one.
    pub fn shipped(name: &str, runs: Option<u32>) -> Option<Result<Suite>> {
        match name {
            "voting" => Some(Suite::voting(runs)),
            "deadlock" => Some(Suite::deadlock(runs)),
            _ => None,
        }
    }

    /// A suite of scenario files.
    pub fn files(paths: &[&Path], runs: Option<u32>) -> Result<Suite> {
        let mut scenarios = Vec::new();
        let mut seen = std::collections::BTreeSet::new();
        for p in paths {
            let s = Scenario::load(p)?;
            if !seen.insert(s.name.clone()) {
                bail!("two scenarios are named `{}`", s.name);
            }
            scenarios.push(Prepared::new(s)?);
        }
        let first = scenarios.first().context("no scenario")?.scenario();
        let (r, seed) = (first.runs, first.seed);
        let name = if paths.len() == 1 {
            first.name.clone()
        } else {
            "custom".into()
        };
        Ok(Suite {
            name,
            kind: SuiteKind::Custom,
            runs: runs.unwrap_or(r),
            seed,
            scenarios,
        })
    }

    /// The jobs of the suite; a job's `seed` (written to its results line)
    /// is the simulator's seed of the run ([`Suite::seeds`]).
    pub fn jobs(&self) -> Vec<Job> {
        let names: Vec<String> = self.scenarios.iter().map(|p| p.scenario().name.clone()).collect();
        runner::jobs(&names, self.runs, |_, run| self.seeds(run).sim)
    }

    /// The suite's description for `suite.json`.
    pub fn info(&self, sources: BTreeMap<String, String>) -> SuiteInfo {
        SuiteInfo {
            name: self.name.clone(),
            kind: self.kind,
            runs: self.runs,
            seed: self.seed,
            scenarios: self.scenarios.iter().map(|p| p.scenario().name.clone()).collect(),
            sources,
        }
    }

    /// The seeds of run `run` of scenario `name` ([`RunSeeds`]).
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
            sim: runner::derive_seed(self.seed, NOISE_STREAM, run),
            variation: runner::derive_seed(self.seed, "", run),
        }
    }

    /// The prepared scenario called `name`.
    pub fn scenario(&self, name: &str) -> Option<&Prepared> {
        self.scenarios.iter().find(|p| p.scenario().name == name)
    }

    /// Runs the suite (or one shard of it) into `params.results`.
    pub fn run(&self, params: &BatchParams, shard: Option<Shard>) -> Result<BatchSummary> {
        let mut jobs = self.jobs();
        if let Some(s) = shard {
            jobs = s.select(jobs);
        }
        runner::run_batch(&jobs, params, |job| {
            let prep = self
                .scenario(&job.scenario)
                .with_context(|| format!("unknown scenario `{}`", job.scenario))?;
            let record = prep.run(self.seeds(job.run))?;
            Ok(serde_json::to_value(record)?)
        })
    }
}
