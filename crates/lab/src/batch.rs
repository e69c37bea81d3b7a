//! A suite run into a results folder, as `petrinav lab run` does it —
//! shared with the Python package (`crates/py`): `suite.json` written
//! first so that an interrupted batch can be checked on resume, the runs
//! appended to `results.jsonl` by the [`runner`](crate::runner). The suite
//! comes from the registry (`lab::suites::load`: a name, or scenario
//! files).
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

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

use anyhow::{Context, Result, bail};

use crate::runner::{BatchParams, BatchSummary, Shard};
use crate::suite::{Suite, SuiteInfo};

/// Most worker threads a batch starts per core: `--jobs` beyond this many
/// times the cores is capped (the runs would only wait on each other, and
/// thousands of threads cost memory and start-up before the first run).
pub const MAX_JOBS_PER_CORE: usize = 4;

/// The worker threads a batch uses for `asked` (`--jobs`): at least 1 (0
/// is an error), at most [`MAX_JOBS_PER_CORE`] × the cores; with the
/// message to show when it was capped. Results do not depend on it.
pub fn cap_jobs(asked: usize) -> Result<(usize, Option<String>)> {
    if asked == 0 {
        bail!("--jobs 0: a batch needs at least one worker thread (leave --jobs out to use every core)");
    }
    let cores = std::thread::available_parallelism().map_or(1, std::num::NonZeroUsize::get);
    let most = MAX_JOBS_PER_CORE * cores;
    Ok(if asked > most {
        (
            most,
            Some(format!(
                "--jobs {asked}: capped at {most} worker threads ({MAX_JOBS_PER_CORE} per core, {cores} cores); more would only wait on each other. Results do not depend on it"
            )),
        )
    } else {
        (asked, None)
    })
}

/// The `suite.json` of a results folder.
pub fn read_info(dir: &Path) -> Result<SuiteInfo> {
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

/// Writes the `suite.json` of a results folder.
pub fn write_info(dir: &Path, info: &SuiteInfo) -> Result<()> {
    let path = dir.join("suite.json");
    std::fs::write(&path, serde_json::to_string_pretty(info)?)
        .with_context(|| format!("writing {}", path.display()))
}

/// The options of `lab run` beyond the suite.
#[derive(Debug, Clone)]
pub struct RunOptions {
    /// Worker threads (default: all cores; capped by [`cap_jobs`]); results
    /// do not depend on it.
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
    if out.join("suite.json").exists() && options.resume && !read_info(&out)?.same_batch(info) {
        bail!(
            "{} belongs to another batch (suite, scenarios, runs or seed differ): resume it with the same arguments, or choose another --out",
            out.display()
        );
    }
    // Written first, so that an interrupted batch can be checked on resume.
    write_info(&out, info)?;
    let jobs = options.jobs.map(cap_jobs).transpose()?.map(|(n, _)| n);
    let params = BatchParams {
        results: out.join("results.jsonl"),
        resume: options.resume,
        jobs,
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
