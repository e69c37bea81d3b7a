//! What a suite is, for the generic core: the [`Suite`] trait every suite
//! implements, the description a results folder keeps (`suite.json`), and
//! the driver that runs a suite through the batch runner.
//!
//! The core knows no suite by name. Each suite lives in its own folder
//! under `src/suites/` and is listed once in the registry
//! ([`crate::suites::REGISTRY`]); a suite built from scenario files can use
//! [`crate::scenario_suite::ScenarioSuite`] for everything but its report.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use serde_json::Value;
use sim::TraceParams;

use crate::page::{Block, RunLink};
use crate::pictures::{EventMarker, Replay};
use crate::record::{self, RunRecord, Runs};
use crate::runner::{self, BatchParams, BatchSummary, Campaign, Job, Shard};
use crate::summary::Summary;
use crate::viewer::PageRun;

/// What a results folder says about the suite that produced it
/// (`suite.json`), so that a report can be recomputed, a batch resumed or
/// shards merged from the folder alone.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SuiteInfo {
    /// Name (the report's title, the default output folder).
    pub name: String,
    /// The registered suite that built it ([`Registration::name`]).
    pub suite: String,
    /// Runs per scenario.
    pub runs: u32,
    /// Base seed.
    pub seed: u64,
    /// Scenario names, in order (the rows of the report).
    pub scenarios: Vec<String>,
    /// Where scenarios came from (file paths), by name, for suites built
    /// from files.
    #[serde(default)]
    pub sources: BTreeMap<String, String>,
}

impl SuiteInfo {
    /// Whether `other` describes the same batch (a folder can be resumed
    /// or merged with it).
    pub fn same_batch(&self, other: &SuiteInfo) -> bool {
        self.suite == other.suite
            && self.scenarios == other.scenarios
            && self.runs == other.runs
            && self.seed == other.seed
    }
}

/// How a suite is asked for on the command line.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct SuiteArgs {
    /// Runs per scenario (`None`: the suite's default).
    pub runs: Option<u32>,
    /// Scenario files, for suites built from files.
    pub files: Vec<PathBuf>,
}

impl SuiteArgs {
    /// The arguments that rebuild the suite a folder describes.
    pub fn of(info: &SuiteInfo) -> Result<SuiteArgs> {
        let files = if info.sources.is_empty() {
            Vec::new()
        } else {
            info.scenarios
                .iter()
                .map(|n| {
                    info.sources
                        .get(n)
                        .map(PathBuf::from)
                        .with_context(|| format!("suite.json does not say where scenario `{n}` came from"))
                })
                .collect::<Result<_>>()?
        };
        Ok(SuiteArgs {
            runs: Some(info.runs),
            files,
        })
    }
}

/// A suite in the registry.
#[derive(Debug, Clone, Copy)]
pub struct Registration {
    /// The name users type (`petrinav lab run NAME`), unique.
    pub name: &'static str,
    /// One line for `--help` and error messages.
    pub about: &'static str,
    /// Builds the suite.
    pub build: fn(&SuiteArgs) -> Result<Box<dyn Suite>>,
}

/// What the generic report hands a suite.
pub struct ReportContext<'a> {
    /// The results folder.
    pub dir: &'a Path,
    /// The suite's description.
    pub info: &'a SuiteInfo,
    /// The records, by scenario.
    pub runs: &'a Runs,
    /// One summary per scenario, in the suite's order.
    pub summaries: &'a [Summary],
    /// Whether to draw pictures.
    pub pictures: bool,
}

impl ReportContext<'_> {
    /// Where a picture named `file` goes (`pictures/` in the results
    /// folder, created if needed): the path to write and the link for the
    /// page.
    pub fn picture_path(&self, file: &str) -> Result<(PathBuf, String)> {
        let dir = self.dir.join("pictures");
        std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
        Ok((dir.join(file), format!("pictures/{file}")))
    }

    /// Writes the viewer page of a pictured run (`viewer/` in the results
    /// folder, named after the run's key) and returns the path written and
    /// the link for the page's figure, labelled `label`.
    pub fn viewer_page(
        &self,
        replay: &Replay,
        markers: &[EventMarker],
        key: &str,
        label: &str,
    ) -> Result<(PathBuf, RunLink)> {
        let (path, href) = self.viewer_runs_page(&[PageRun { replay, key }], markers, key)?;
        Ok((
            path,
            RunLink {
                label: label.to_string(),
                href,
            },
        ))
    }

    /// Writes the viewer page of the runs a picture draws (`viewer/` in the
    /// results folder, named after `title`: a scenario's name) and returns
    /// the path written and the page's link (`#run=K` on it opens the
    /// run of index K in `runs`).
    pub fn viewer_runs_page(
        &self,
        runs: &[PageRun<'_>],
        markers: &[EventMarker],
        title: &str,
    ) -> Result<(PathBuf, String)> {
        let dir = self.dir.join("viewer");
        std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
        let file = format!("{}.html", title.replace(['/', '#'], "-"));
        let path = dir.join(&file);
        crate::viewer::write_runs_page(runs, markers, &self.info.name, title, &path)?;
        Ok((path, format!("viewer/{file}")))
    }
}

/// A suite's part of the report.
#[derive(Debug, Clone, Default)]
pub struct SuiteReport {
    /// What the terminal shows after a batch (its main table).
    pub text: String,
    /// The page's first sentence, in place of "N runs per scenario, base
    /// seed S." when the suite counts otherwise.
    pub intro: Option<String>,
    /// The page's blocks after the introduction.
    pub blocks: Vec<Block>,
    /// Files the suite wrote (pictures).
    pub files: Vec<PathBuf>,
}

/// A suite: its runs, how to run and replay one, and its report.
pub trait Suite: Sync {
    /// The description kept in `suite.json`.
    fn info(&self) -> &SuiteInfo;

    /// The campaigns of the batch, in the order of a complete results
    /// file. Independent runs are campaigns of one run
    /// ([`Campaign::independent`]).
    fn campaigns(&self) -> Vec<Campaign>;

    /// Runs one job; `earlier` holds the records of its campaign's earlier
    /// runs, in order (the state it carries).
    fn run(&self, job: &Job, earlier: &[RunRecord]) -> Result<RunRecord>;

    /// Runs one job again with a trace, for pictures and `lab replay`; the
    /// record is the one [`Suite::run`] gives.
    fn replay(&self, job: &Job, earlier: &[RunRecord], trace: TraceParams) -> Result<Replay>;

    /// How the events of the suite's controllers are drawn on pictures of
    /// runs (`lab replay`, the report).
    fn markers(&self) -> &[EventMarker];

    /// The suite's tables, explanation and pictures.
    fn report(&self, ctx: &ReportContext<'_>) -> Result<SuiteReport>;
}

/// Runs a suite (or one shard of it) into `params.results`.
pub fn run(suite: &dyn Suite, params: &BatchParams, shard: Option<Shard>) -> Result<BatchSummary> {
    let mut campaigns = suite.campaigns();
    if let Some(s) = shard {
        campaigns = s.select(campaigns);
    }
    runner::run_batch(&campaigns, params, |job, earlier: &[Value]| {
        let earlier = earlier.iter().map(record::parse).collect::<Result<Vec<_>>>()?;
        Ok(serde_json::to_value(suite.run(job, &earlier)?)?)
    })
}

/// The job of `key` (`SCENARIO#INDEX`) in a suite, and the keys of its
/// campaign's earlier runs.
pub fn find_job(suite: &dyn Suite, key: &str) -> Result<(Job, Vec<String>)> {
    let campaigns = suite.campaigns();
    for c in &campaigns {
        if let Some(k) = c.jobs.iter().position(|j| j.key() == key) {
            return Ok((c.jobs[k].clone(), c.jobs[..k].iter().map(Job::key).collect()));
        }
    }
    let Some((name, index)) = key.rsplit_once('#') else {
        bail!("`{key}`: a run is SCENARIO#INDEX, e.g. e3/field03#1");
    };
    let info = suite.info();
    if !info.scenarios.iter().any(|s| s == name) {
        let known: Vec<&str> = info.scenarios.iter().map(String::as_str).collect();
        let hint = petri::closest(name, &known).map_or(String::new(), |c| format!(" (did you mean `{c}`?)"));
        bail!(
            "run `{key}`: no scenario `{name}` in this batch of the `{}` suite{hint}; it has: {}",
            info.suite,
            info.scenarios.join(", ")
        );
    }
    bail!(
        "no run `{index}` of `{name}` in this batch (it has {} runs per scenario)",
        info.runs
    )
}

/// Re-simulates the run `key` of a results folder (its campaign's earlier
/// runs read from `results.jsonl`).
pub fn replay_key(suite: &dyn Suite, dir: &Path, key: &str, trace: TraceParams) -> Result<Replay> {
    let (job, earlier_keys) = find_job(suite, key)?;
    let earlier = if earlier_keys.is_empty() {
        Vec::new()
    } else {
        let (lines, _) = runner::read_results(&dir.join("results.jsonl"))?;
        let by_key: BTreeMap<&str, &Value> = lines
            .iter()
            .filter_map(|l| Some((l.get("key")?.as_str()?, l)))
            .collect();
        earlier_keys
            .iter()
            .map(|k| {
                let line = by_key.get(k.as_str()).with_context(|| {
                    format!(
                        "run `{key}` needs the earlier run `{k}` of its campaign, which is not in the results"
                    )
                })?;
                record::parse(line)
            })
            .collect::<Result<_>>()?
    };
    suite.replay(&job, &earlier, trace)
}
