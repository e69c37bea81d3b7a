//! `petrinav lab …`: experiment suites and reports.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::{Args, Subcommand};
use lab::runner::{BatchParams, Shard};
use lab::suite::{Suite, SuiteInfo, SuiteKind};

use crate::outln;

#[derive(Subcommand, Debug)]
pub enum LabCommand {
    /// Runs a suite (`voting`, `deadlock`) or scenario files as a batch, then writes the
    /// report (tables, pictures, index.html) next to the results.
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
    Run(RunArgs),
    /// Re-simulates one run of a batch: its picture (the run's own world,
    /// trajectory coloured by behaviour, footprints, activity-trace events and dead-locks) and,
    /// optionally, its full per-tick trace (perceptions, votes, weights).
    ///
    /// RUN is the `key` of a results line, e.g. `e3/field03#1`. Examples:
    ///
    ///   petrinav lab replay out/voting 'e4/field12#0' -o run.png
    ///
    ///   petrinav lab replay out/voting 'e1/field03#7' --trace run.jsonl
    Replay(ReplayArgs),
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
    /// `voting`, `deadlock`, or scenario files (.toml).
    #[arg(required = true)]
    what: Vec<String>,
    /// Runs per scenario (default: the suite's or the file's, 50).
    #[arg(long)]
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
    /// Run only this slice of the jobs: i/n (e.g. 2/8); merge the folders'
    /// results.jsonl afterwards and run `lab report`.
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
    /// Print the run's record as JSON.
    #[arg(long)]
    json: bool,
}

pub fn run(cmd: LabCommand) -> Result<()> {
    match cmd {
        LabCommand::Run(a) => run_suite(&a),
        LabCommand::Replay(a) => replay(&a),
        LabCommand::Report { dir, no_pictures } => report(&dir, !no_pictures),
    }
}

fn load_suite(what: &[String], runs: Option<u32>) -> Result<(Suite, BTreeMap<String, String>)> {
    if let [name] = what
        && let Some(suite) = Suite::shipped(name, runs)
    {
        return Ok((suite?, BTreeMap::new()));
    }
    if let Some(bad) = what.iter().find(|w| !w.ends_with(".toml")) {
        bail!(
            "unknown suite `{bad}`: the suites are `voting` and `deadlock`; or give scenario files (.toml)"
        );
    }
    let paths: Vec<&Path> = what.iter().map(Path::new).collect();
    let suite = Suite::files(&paths, runs)?;
    let mut sources = BTreeMap::new();
    for (p, s) in paths.iter().zip(&suite.scenarios) {
        let abs = std::fs::canonicalize(p).unwrap_or_else(|_| p.to_path_buf());
        sources.insert(s.scenario().name.clone(), abs.display().to_string());
    }
    Ok((suite, sources))
}

fn run_suite(a: &RunArgs) -> Result<()> {
    let (suite, sources) = load_suite(&a.what, a.runs)?;
    let out = a
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("out").join(suite.name.replace('/', "-")));
    std::fs::create_dir_all(&out).with_context(|| format!("creating {}", out.display()))?;
    let info = suite.info(sources);
    let info_path = out.join("suite.json");
    if info_path.exists() && a.resume {
        let old: SuiteInfo = serde_json::from_str(&std::fs::read_to_string(&info_path)?)
            .with_context(|| format!("reading {}", info_path.display()))?;
        if old.scenarios != info.scenarios || old.runs != info.runs || old.seed != info.seed {
            bail!(
                "{} belongs to another batch (scenarios, runs or seed differ): resume it with the same arguments, or choose another --out",
                out.display()
            );
        }
    }
    // Written first, so that an interrupted batch can be checked on resume.
    std::fs::write(&info_path, serde_json::to_string_pretty(&info)?)
        .with_context(|| format!("writing {}", info_path.display()))?;
    let params = BatchParams {
        results: out.join("results.jsonl"),
        resume: a.resume,
        jobs: a.jobs,
        progress: true,
    };
    let jobs = suite.jobs().len();
    let summary = suite.run(&params, a.shard)?;
    eprintln!(
        "{} runs ({} already done, {} now, {} failed) -> {}",
        summary.total,
        summary.skipped,
        summary.ran,
        summary.failures,
        params.results.display()
    );
    if a.shard.is_some() {
        eprintln!(
            "shard done ({} of {jobs} jobs); merge the shards' results.jsonl and run `petrinav lab report`",
            summary.total
        );
        return Ok(());
    }
    let written = lab::report::write(&out, &suite, &info, !a.no_pictures)?;
    outln!("{}", written.text)?;
    outln!("report: {}", out.join("index.html").display())?;
    Ok(())
}

fn suite_of(dir: &Path) -> Result<(Suite, SuiteInfo)> {
    let info_path = dir.join("suite.json");
    let info: SuiteInfo = serde_json::from_str(
        &std::fs::read_to_string(&info_path).with_context(|| format!("reading {}", info_path.display()))?,
    )
    .with_context(|| format!("{} is not a suite description", info_path.display()))?;
    let suite = match info.kind {
        SuiteKind::Voting | SuiteKind::Deadlock => Suite::shipped(&info.name, Some(info.runs))
            .with_context(|| format!("no shipped suite `{}`", info.name))??,
        SuiteKind::Custom => {
            let files: Vec<String> =
                info.scenarios
                    .iter()
                    .map(|n| {
                        info.sources.get(n).cloned().with_context(|| {
                            format!("suite.json does not say where scenario `{n}` came from")
                        })
                    })
                    .collect::<Result<_>>()?;
            load_suite(&files, Some(info.runs))?.0
        }
    };
    Ok((suite, info))
}

fn report(dir: &Path, pictures: bool) -> Result<()> {
    let (suite, info) = suite_of(dir)?;
    let written = lab::report::write(dir, &suite, &info, pictures)?;
    outln!("{}", written.text)?;
    outln!("report: {}", dir.join("index.html").display())?;
    Ok(())
}

fn replay(a: &ReplayArgs) -> Result<()> {
    let (suite, info) = suite_of(&a.dir)?;
    let (name, index) = a
        .run
        .rsplit_once('#')
        .context("RUN is SCENARIO#INDEX, e.g. e3/field03#1")?;
    let index: u32 = index
        .parse()
        .with_context(|| format!("`{index}` is not a run index"))?;
    let prep = suite.scenario(name).with_context(|| {
        format!(
            "no scenario `{name}` in this batch; it has: {}",
            info.scenarios.join(", ")
        )
    })?;
    if index >= suite.runs {
        bail!(
            "run {index} is out of range: the batch has {} runs per scenario",
            suite.runs
        );
    }
    let out = prep.run_detailed(suite.seeds(index), sim::TraceParams::full())?;
    let trace = out.trace.context("the run kept no trace")?;
    if let Some(path) = &a.trace {
        let f = std::fs::File::create(path).with_context(|| format!("writing {}", path.display()))?;
        trace
            .write_json_lines(std::io::BufWriter::new(f))
            .with_context(|| format!("writing {}", path.display()))?;
    }
    if let Some(path) = &a.output {
        let grid = out.grid.as_ref().context("the run kept no world")?;
        lab::report::run_picture(prep, grid, &out.record, &trace, path)?;
    }
    if a.json {
        outln!("{}", serde_json::to_string_pretty(&out.record)?)?;
    } else {
        let r = &out.record;
        outln!(
            "{}: {} after {:.1} s, path {:.2} m, {} collisions, min clearance {:.3} m, {} dead-locks",
            a.run,
            r.outcome.replace('_', " "),
            r.time_s,
            r.path_length_m,
            r.collisions,
            r.min_clearance_m,
            r.deadlocks
        )?;
    }
    Ok(())
}
