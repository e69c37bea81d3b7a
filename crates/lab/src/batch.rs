//! A suite run into a results folder, as `petrinav lab run` does it —
//! shared with the Python package (`crates/py`): `suite.json` written
//! first so that an interrupted batch can be checked on resume (with the
//! shard a part holds, so that it is not resumed as another), the runs
//! appended to `results.jsonl` by the [`runner`](crate::runner). The suite
//! comes from the registry (`lab::suites::load`: a name, or scenario
//! files). And the parts of a sharded batch merged back, as `petrinav lab
//! merge` does it: [`read_parts`], then [`merge`], which names the
//! incomplete shards ([`Incomplete`]) rather than write part of a batch.
//!
//! ```no_run
//! use lab::batch::{self, RunOptions};
//!
//! // A suite's name, e.g. from the command line.
//! let name = std::env::args().nth(1).unwrap_or_default();
//! let suite = lab::suites::load(&[name], Some(2))?;
//! let options = RunOptions {
//!     out: Some("out/mine".into()),
//!     ..RunOptions::default()
//! };
//! let done = batch::run(suite, &options)?;
//! lab::report::write(&done.out, done.suite.as_ref(), false)?;
//! # Ok::<(), anyhow::Error>(())
//! ```

use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

use anyhow::{Context, Result, bail};

use crate::runner::{BatchParams, BatchSummary, Campaign, Job, MergeSummary, Shard};
use crate::suite::{Suite, SuiteInfo};

/// The `suite.json` of a results folder.
pub fn read_info(dir: &Path) -> Result<SuiteInfo> {
    Ok(read_folder(dir)?.info)
}

/// The shard a results folder holds (`lab run --shard i/n` records it in
/// `suite.json`); `None` for a whole batch, a merged one, or a folder
/// written before shards were recorded.
pub fn read_shard(dir: &Path) -> Result<Option<Shard>> {
    Ok(read_folder(dir)?.shard)
}

/// Writes the `suite.json` of a results folder, with the shard it holds
/// (`None`: the whole batch), through a temporary file and a rename, so
/// that a process killed while writing it leaves the old file or the new
/// one, never half of one.
pub fn write_info(dir: &Path, info: &SuiteInfo, shard: Option<Shard>) -> Result<()> {
    let path = dir.join("suite.json");
    let tmp = dir.join(format!("suite.json.tmp{}", std::process::id()));
    let folder = Folder {
        info: info.clone(),
        shard,
    };
    std::fs::write(&tmp, serde_json::to_string_pretty(&folder)?)
        .with_context(|| format!("writing {}", tmp.display()))?;
    std::fs::rename(&tmp, &path).with_context(|| format!("writing {}", path.display()))
}

/// What `suite.json` holds: the suite's description and, in a shard's
/// folder, the shard.
#[derive(serde::Serialize, serde::Deserialize)]
struct Folder {
    #[serde(flatten)]
    info: SuiteInfo,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    shard: Option<Shard>,
}

fn read_folder(dir: &Path) -> Result<Folder> {
    let path = dir.join("suite.json");
    if !path.exists() {
        bail!(
            "{} is not a results folder (it has no suite.json): `petrinav lab run` makes one",
            dir.display()
        );
    }
    serde_json::from_str(
        &std::fs::read_to_string(&path).with_context(|| format!("reading {}", path.display()))?,
    )
    .with_context(|| format!("{} is not a suite description", path.display()))
}

/// The options of `lab run` beyond the suite.
#[derive(Debug, Clone)]
pub struct RunOptions {
    /// Worker threads (default: all cores); results do not depend on it.
    pub jobs: Option<usize>,
    /// Output folder (default: `out/<suite name>`).
    pub out: Option<PathBuf>,
    /// Continue an interrupted batch in the output folder.
    pub resume: bool,
    /// Run only this slice of the batch.
    pub shard: Option<Shard>,
    /// Draw a progress bar on standard error when it is a terminal.
    pub progress: bool,
    /// Stops the batch when raised ([`BatchParams::stop`]).
    pub stop: Option<Arc<AtomicBool>>,
}

impl Default for RunOptions {
    /// The command line's defaults.
    fn default() -> RunOptions {
        RunOptions {
            jobs: None,
            out: None,
            resume: false,
            shard: None,
            progress: true,
            stop: None,
        }
    }
}

/// Refuses to resume in `out` a batch other than the one it holds, or
/// another shard of it.
fn check_resumable(out: &Path, info: &SuiteInfo, shard: Option<Shard>) -> Result<()> {
    let there = read_folder(out)?;
    if !there.info.same_batch(info) {
        bail!(
            "{} belongs to another batch (suite, scenarios, runs or seed differ): resume it with the same arguments, or choose another --out",
            out.display()
        );
    }
    match (there.shard, shard) {
        (Some(held), asked) if asked != Some(held) => bail!(
            "{} holds shard {held} of this batch, not {}: resume it with --shard {held}, or choose another --out",
            out.display(),
            asked.map_or_else(|| "the whole batch".to_string(), |s| format!("shard {s}"))
        ),
        _ => Ok(()),
    }
}

/// A batch run into its folder.
pub struct Ran {
    /// The suite.
    pub suite: Box<dyn Suite>,
    /// The results folder.
    pub out: PathBuf,
    /// `results.jsonl` in it.
    pub results: PathBuf,
    /// What the runner did.
    pub summary: BatchSummary,
    /// Runs in the whole batch (all shards).
    pub jobs: usize,
}

/// `lab run`: the suite's folder (checked to belong to the same batch on
/// resume), `suite.json`, then the runs. The report is not written
/// ([`crate::report::write`]).
pub fn run(suite: Box<dyn Suite>, options: &RunOptions) -> Result<Ran> {
    let info = suite.info();
    let out = options
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("out").join(info.name.replace('/', "-")));
    std::fs::create_dir_all(&out).with_context(|| format!("creating {}", out.display()))?;
    if out.join("suite.json").exists() && options.resume {
        check_resumable(&out, info, options.shard)?;
    }
    // Written first, so that an interrupted batch can be checked on resume.
    write_info(&out, info, options.shard)?;
    let params = BatchParams {
        results: out.join("results.jsonl"),
        resume: options.resume,
        jobs: options.jobs,
        progress: options.progress,
        stop: options.stop.clone(),
    };
    let jobs: usize = suite.campaigns().iter().map(|c| c.jobs.len()).sum();
    let summary = crate::suite::run(suite.as_ref(), &params, options.shard)?;
    Ok(Ran {
        suite,
        out,
        results: params.results,
        summary,
        jobs,
    })
}

/// The folders of a sharded batch, read for `lab merge`.
#[derive(Debug, Clone)]
pub struct Parts {
    /// The batch they belong to (the first part's `suite.json`).
    pub info: SuiteInfo,
    /// Each part's folder and the shard it says it holds.
    pub parts: Vec<(PathBuf, Option<Shard>)>,
    /// Folders that hold no results yet (no `suite.json`: a shard that
    /// died or was stopped before its first write), left out.
    pub empty: Vec<PathBuf>,
}

/// Reads the parts' `suite.json`: they must describe the same batch. A
/// folder without one holds no run yet and is set aside
/// ([`Parts::empty`]), unless all are so.
pub fn read_parts(dirs: &[PathBuf]) -> Result<Parts> {
    let mut info: Option<SuiteInfo> = None;
    let mut parts: Vec<(PathBuf, Option<Shard>)> = Vec::new();
    let mut empty = Vec::new();
    for dir in dirs {
        if !dir.join("suite.json").exists() {
            empty.push(dir.clone());
            continue;
        }
        let folder = read_folder(dir)?;
        match (&info, parts.first()) {
            (Some(first), Some((first_dir, _))) if !first.same_batch(&folder.info) => bail!(
                "{} and {} are not parts of the same batch (suite, scenarios, runs or seed differ)",
                first_dir.display(),
                dir.display()
            ),
            (Some(_), _) => {}
            (None, _) => info = Some(folder.info),
        }
        parts.push((dir.clone(), folder.shard));
    }
    let Some(info) = info else {
        bail!(
            "no folder to merge holds results (none has a suite.json): {}",
            dirs.iter()
                .map(|d| d.display().to_string())
                .collect::<Vec<_>>()
                .join(", ")
        );
    };
    Ok(Parts { info, parts, empty })
}

/// How much of one shard the parts hold.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ShardProgress {
    /// The shard.
    pub shard: Shard,
    /// Runs of the shard.
    pub runs: usize,
    /// Of those, runs found in some part.
    pub found: usize,
    /// The parts that say they hold this shard.
    pub parts: Vec<PathBuf>,
}

impl ShardProgress {
    /// Whether every run of the shard was found.
    pub fn complete(&self) -> bool {
        self.found == self.runs
    }
}

/// A merge refused because runs are in no part (`lab merge` without
/// `--partial`): nothing was written.
#[derive(Debug, thiserror::Error)]
#[error("{}", incomplete_message(.missing, *.runs, .shards.as_deref()))]
pub struct Incomplete {
    /// Keys of the runs in no part, in job order.
    pub missing: Vec<String>,
    /// Runs in the batch.
    pub runs: usize,
    /// Each shard's progress, when the parts say how the batch was
    /// sharded (all with the same count).
    pub shards: Option<Vec<ShardProgress>>,
}

fn incomplete_message(missing: &[String], runs: usize, shards: Option<&[ShardProgress]>) -> String {
    let mut text = format!(
        "the batch is incomplete, so nothing was merged: {} of {runs} runs are in no part",
        missing.len()
    );
    let lagging: Vec<&ShardProgress> = shards
        .unwrap_or_default()
        .iter()
        .filter(|s| !s.complete())
        .collect();
    if lagging.is_empty() {
        let shown: Vec<&str> = missing.iter().take(5).map(String::as_str).collect();
        text += &format!(" (e.g. {})", shown.join(", "));
    }
    for s in &lagging {
        let held = if s.parts.is_empty() {
            "no part holds it".to_string()
        } else {
            let dirs: Vec<String> = s.parts.iter().map(|p| p.display().to_string()).collect();
            format!("in {}", dirs.join(", "))
        };
        text += &format!(
            "\n  shard {}: {} of {} runs done, {held}",
            s.shard, s.found, s.runs
        );
    }
    if !lagging.is_empty() {
        let indices: Vec<String> = lagging.iter().map(|s| s.shard.index.to_string()).collect();
        text += &format!(
            "\nRun those shards again (`lab run … --shard i/n --resume --out PART` continues a shard where it stopped; on Slurm, resubmit the array tasks {}), then merge again; or merge what there is with --partial.",
            indices.join(",")
        );
    } else {
        text += "\nRun the missing shards, then merge again; or merge what there is with --partial.";
    }
    text
}

/// What [`merge`] did.
#[derive(Debug, Clone)]
pub struct Merged {
    /// What the runner's merge did.
    pub summary: MergeSummary,
    /// Each shard's progress, when the parts say how the batch was sharded.
    pub shards: Option<Vec<ShardProgress>>,
}

/// `lab merge`: the parts' runs into `out/results.jsonl` in the order of
/// an unsharded batch, and `out/suite.json`. Runs in no part are an
/// [`Incomplete`] error, with nothing written, unless `partial`. The
/// report is not written ([`crate::report::write`]).
pub fn merge(out: &Path, parts: &Parts, suite: &dyn Suite, partial: bool) -> Result<Merged> {
    let campaigns = suite.campaigns();
    let keys = crate::runner::keys(&campaigns);
    let files: Vec<PathBuf> = parts.parts.iter().map(|(d, _)| d.join("results.jsonl")).collect();
    let gathered = crate::runner::gather(&files, &keys)?;
    let shards = shard_progress(parts, &campaigns, &gathered.missing);
    if !gathered.missing.is_empty() && !partial {
        return Err(Incomplete {
            missing: gathered.missing,
            runs: keys.len(),
            shards,
        }
        .into());
    }
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let summary = gathered.write(&out.join("results.jsonl"))?;
    write_info(out, &parts.info, None)?;
    Ok(Merged { summary, shards })
}

/// Each shard's runs and how many of them are missing, when every part
/// names its shard and all with the same count.
fn shard_progress(parts: &Parts, campaigns: &[Campaign], missing: &[String]) -> Option<Vec<ShardProgress>> {
    let count = parts.parts.first()?.1?.count;
    if parts
        .parts
        .iter()
        .any(|(_, s)| s.is_none_or(|s| s.count != count))
    {
        return None;
    }
    let missing: HashSet<&str> = missing.iter().map(String::as_str).collect();
    let progress = (1..=count)
        .map(|index| {
            let shard = Shard { index, count };
            let keys: Vec<String> = campaigns
                .iter()
                .enumerate()
                .filter(|(k, _)| shard.holds(*k))
                .flat_map(|(_, c)| c.jobs.iter().map(Job::key))
                .collect();
            ShardProgress {
                shard,
                runs: keys.len(),
                found: keys.iter().filter(|k| !missing.contains(k.as_str())).count(),
                parts: parts
                    .parts
                    .iter()
                    .filter(|(_, s)| *s == Some(shard))
                    .map(|(d, _)| d.clone())
                    .collect(),
            }
        })
        .collect();
    Some(progress)
}
