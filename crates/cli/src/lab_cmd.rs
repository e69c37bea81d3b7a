//! `petrinav lab …`: experiment suites and reports.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::{Args, Subcommand};
use lab::batch::RunOptions;
use lab::runner::Shard;
use lab::suite::{Suite, SuiteInfo};

use crate::outln;

#[derive(Subcommand, Debug)]
pub enum LabCommand {
    /// Runs a suite (`voting`, `deadlock`, `maps`, `tourguide`, …; `lab list`
    /// shows them all) or scenario files as a batch, then writes the report
    /// (tables, pictures, index.html) next to the results.
    ///
    /// Every run is reproducible from (scenario, run index, seed); results
    /// are appended one JSON line per run, so an interrupted batch continues
    /// with --resume. Examples:
    ///
    ///   petrinav lab run voting --runs 10
    ///
    ///   petrinav lab run my_scenario.toml --out out/mine
    ///
    ///   petrinav lab run voting --shard 3/8 --out out/part3
    ///
    ///   petrinav lab run tourguide --runs 2   (2 campaigns per density and strategy)
    Run(RunArgs),
    /// Lists the suites.
    List,
    /// Re-simulates one run of a batch: its picture (the run's own world,
    /// trajectory coloured by behaviour, footprints, activity-trace events and dead-locks) and,
    /// optionally, its full per-tick trace (perceptions, votes, weights).
    ///
    /// RUN is the `key` of a results line, e.g. `e3/field03#1`. Examples:
    ///
    ///   petrinav lab replay out/voting 'e4/field12#0' -o run.png
    ///
    ///   petrinav lab replay out/voting 'e1/field03#7' --trace run.jsonl
    ///
    ///   petrinav lab replay out/voting 'e4/field12#0' --html run.html   (open it in a browser)
    ///
    ///   petrinav lab replay out/voting 'e4/field12#0' --mcap run.mcap   (open it in Foxglove)
    Replay(ReplayArgs),
    /// Merges the folders of a sharded batch (`lab run … --shard i/n`) into one, in the
    /// order of an unsharded run, and writes its report.
    ///
    /// The parts must come from the same batch (suite, runs, seed). A run found in two
    /// parts must be identical in both. When runs are in no part, the merge says which
    /// shards are incomplete and writes nothing (run them again with --resume, then merge
    /// again), unless --partial. Merging the same parts again leaves the merged file as it
    /// is. Example:
    ///
    ///   petrinav lab merge out/voting out/part1 out/part2 out/part3
    Merge {
        /// The merged folder (must not hold other results).
        out: PathBuf,
        /// The shards' folders (a folder without suite.json holds no run yet and is left
        /// out).
        #[arg(required = true)]
        parts: Vec<PathBuf>,
        /// Merge even when runs are in no part: the report covers the others, and
        /// `lab run … --resume --out OUT` completes the batch in the merged folder.
        #[arg(long)]
        partial: bool,
        /// Skip the pictures.
        #[arg(long)]
        no_pictures: bool,
    },
    /// Writes a Slurm job array for a batch: one shard per task (`lab run … --shard i/n
    /// --resume`) and a merge job after the array (`lab merge`), with absolute paths for
    /// the nodes; --submit queues both. A task that failed or was cut short continues
    /// where it stopped when submitted again (--array). docs/cluster.md explains the
    /// scripts. Examples:
    ///
    ///   petrinav lab slurm voting --runs 50 --shards 20 -o /scratch/voting --submit
    ///
    ///   petrinav lab slurm tourguide --shards 8 --partition long --time 2:00:00 -o /scratch/tg
    ///
    ///   petrinav lab slurm voting --runs 50 --shards 20 -o /scratch/voting --submit --array 3,7
    Slurm(crate::lab_slurm::SlurmArgs),
    /// Recomputes the report of a results folder (tables, pictures, index.html).
    Report {
        /// The folder of a batch (holds suite.json and results.jsonl).
        dir: PathBuf,
        /// Skip the pictures.
        #[arg(long)]
        no_pictures: bool,
    },
}

#[derive(Args, Debug)]
pub struct RunArgs {
    /// A suite (`voting`, `deadlock`, `maps`, `tourguide`, …; see `lab
    /// list`), or scenario files (.toml).
    #[arg(required = true)]
    what: Vec<String>,
    /// Runs per scenario (default: the suite's or the file's, 50), at most
    /// 1,000,000.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=i64::from(lab::scenario::MAX_RUNS)))]
    runs: Option<u32>,
    /// Worker threads (default: all cores). Results do not depend on it.
    #[arg(long, short = 'j')]
    jobs: Option<usize>,
    /// Output folder (default: `out/<suite name>`).
    #[arg(long, short = 'o')]
    out: Option<PathBuf>,
    /// Continue an interrupted batch in the output folder.
    #[arg(long)]
    resume: bool,
    /// Run only this slice of the batch: i/n (e.g. 2/8); `lab merge` puts
    /// the slices' folders back together.
    #[arg(long, value_name = "i/n")]
    shard: Option<Shard>,
    /// Skip the pictures of the report.
    #[arg(long)]
    no_pictures: bool,
}

#[derive(Args, Debug)]
pub struct ReplayArgs {
    /// The folder of a batch (holds suite.json).
    dir: PathBuf,
    /// The run: `SCENARIO#INDEX`, as in the results' `key`.
    run: String,
    /// Picture of the run (.png or .svg).
    #[arg(long, short = 'o')]
    output: Option<PathBuf>,
    /// Per-tick trace as JSON lines (perceptions included).
    #[arg(long)]
    trace: Option<PathBuf>,
    /// The run viewer: one self-contained HTML page (map, trajectory,
    /// sensors, people, a time slider, the controller's notes per tick)
    /// that opens offline in any browser.
    #[arg(long, value_name = "FILE.html")]
    html: Option<PathBuf>,
    /// The run as MCAP in Foxglove's schemas (map, poses, transforms,
    /// scans, people, the controller's notes, events): open it in
    /// Foxglove as a local file.
    #[arg(long, value_name = "FILE.mcap")]
    mcap: Option<PathBuf>,
    /// Print the run's record as JSON.
    #[arg(long)]
    json: bool,
}

pub fn run(cmd: LabCommand) -> Result<()> {
    match cmd {
        LabCommand::Run(a) => run_suite(&a),
        LabCommand::List => list(),
        LabCommand::Replay(a) => replay(&a),
        LabCommand::Merge {
            out,
            parts,
            partial,
            no_pictures,
        } => merge(&out, &parts, partial, !no_pictures),
        LabCommand::Slurm(a) => crate::lab_slurm::run(&a),
        LabCommand::Report { dir, no_pictures } => report(&dir, !no_pictures),
    }
}

fn list() -> Result<()> {
    for r in lab::suites::REGISTRY {
        outln!("{:<10} {}", r.name, r.about)?;
    }
    Ok(())
}

fn read_info(dir: &Path) -> Result<SuiteInfo> {
    lab::batch::read_info(dir)
}

fn run_suite(a: &RunArgs) -> Result<()> {
    let suite = lab::suites::load(&a.what, a.runs)?;
    let ran = lab::batch::run(
        suite,
        &RunOptions {
            jobs: a.jobs,
            out: a.out.clone(),
            resume: a.resume,
            shard: a.shard,
            ..RunOptions::default()
        },
    )?;
    let summary = &ran.summary;
    eprintln!(
        "{} runs ({} already done, {} now: {}) -> {}",
        summary.total,
        summary.skipped,
        summary.ran,
        summary.outcomes_in_words(),
        ran.results.display()
    );
    if a.shard.is_some() {
        eprintln!(
            "shard done ({} of {} runs); put the shards together with `petrinav lab merge OUT PART…`",
            summary.total, ran.jobs
        );
        return Ok(());
    }
    print_report(&ran.out, ran.suite.as_ref(), !a.no_pictures)
}

fn print_report(dir: &Path, suite: &dyn Suite, pictures: bool) -> Result<()> {
    let written = lab::report::write(dir, suite, pictures)?;
    outln!("{}", written.text)?;
    outln!("report: {}", dir.join("index.html").display())?;
    Ok(())
}

fn suite_of(dir: &Path) -> Result<Box<dyn Suite>> {
    lab::suites::rebuild(&read_info(dir)?)
}

fn report(dir: &Path, pictures: bool) -> Result<()> {
    let suite = suite_of(dir)?;
    print_report(dir, suite.as_ref(), pictures)
}

fn merge(out: &Path, dirs: &[PathBuf], partial: bool, pictures: bool) -> Result<()> {
    let parts = lab::batch::read_parts(dirs)?;
    for dir in &parts.empty {
        eprintln!("{}: no results yet (no suite.json), left out", dir.display());
    }
    let suite = lab::suites::rebuild(&parts.info)?;
    let merged = lab::batch::merge(out, &parts, suite.as_ref(), partial)?;
    let summary = &merged.summary;
    let results = out.join("results.jsonl");
    if summary.unchanged {
        eprintln!(
            "{} already holds these {} runs (merged before): left as it is",
            results.display(),
            summary.merged
        );
    } else {
        eprintln!(
            "{} runs merged from {} folders ({} found twice, identical) -> {}",
            summary.merged,
            parts.parts.len(),
            summary.duplicates,
            results.display()
        );
    }
    if !summary.missing.is_empty() {
        let lagging: Vec<String> = merged
            .shards
            .iter()
            .flatten()
            .filter(|s| !s.complete())
            .map(|s| format!("shard {}: {} of {} done", s.shard, s.found, s.runs))
            .collect();
        let shown: Vec<&str> = summary.missing.iter().take(5).map(String::as_str).collect();
        eprintln!(
            "{} runs are in no part ({}); the report covers the others. To complete the batch, run it again with --resume --out {}",
            summary.missing.len(),
            if lagging.is_empty() {
                format!("e.g. {}", shown.join(", "))
            } else {
                lagging.join(", ")
            },
            out.display()
        );
    }
    print_report(out, suite.as_ref(), pictures)
}

/// Fails early (before a replay that may take a while) when a file cannot
/// go where asked: its folder missing, or the path a folder.
pub(crate) fn check_output(path: &Path) -> Result<()> {
    if path.is_dir() {
        bail!("cannot write {}: it is a folder", path.display());
    }
    if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty())
        && !parent.is_dir()
    {
        bail!(
            "cannot write {}: there is no folder {}",
            path.display(),
            parent.display()
        );
    }
    Ok(())
}

fn replay(a: &ReplayArgs) -> Result<()> {
    for path in [&a.output, &a.trace, &a.html, &a.mcap].into_iter().flatten() {
        check_output(path)?;
    }
    let suite = suite_of(&a.dir)?;
    let replay = lab::suite::replay_key(suite.as_ref(), &a.dir, &a.run, sim::TraceParams::full())?;
    if let Some(path) = &a.trace {
        let f = std::fs::File::create(path).with_context(|| format!("writing {}", path.display()))?;
        replay
            .trace
            .write_json_lines(std::io::BufWriter::new(f))
            .with_context(|| format!("writing {}", path.display()))?;
    }
    if let Some(path) = &a.output {
        lab::pictures::run_picture(&replay, suite.markers(), path)?;
    }
    if let Some(path) = &a.html {
        lab::viewer::write_page(&replay, suite.markers(), &suite.info().name, &a.run, path)?;
    }
    if let Some(path) = &a.mcap {
        let started = std::time::Instant::now();
        let written = lab::foxglove::write_file(&replay, &suite.info().name, &a.run, path)?;
        let messages: u64 = written.messages.values().sum();
        eprintln!(
            "{}: {messages} messages on {} topics, {:.1} kB, written in {:.0} ms",
            path.display(),
            written.messages.len(),
            written.bytes as f64 / 1000.0,
            started.elapsed().as_secs_f64() * 1000.0
        );
    }
    let r = &replay.record;
    if a.json {
        outln!("{}", serde_json::to_string_pretty(r)?)?;
    } else {
        let metrics: Vec<String> = r.metrics.iter().map(|(k, v)| format!("{k} {v}")).collect();
        outln!(
            "{}: {} after {:.1} s, path {:.2} m, {} collisions, min clearance {:.3} m{}",
            a.run,
            r.outcome.replace('_', " "),
            r.time_s,
            r.path_length_m,
            r.collisions,
            r.min_clearance_m,
            if metrics.is_empty() {
                String::new()
            } else {
                format!("; {}", metrics.join(", "))
            }
        )?;
    }
    Ok(())
}
