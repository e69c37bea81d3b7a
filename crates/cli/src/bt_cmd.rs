//! `petrinav bt …`: behaviour trees (BehaviorTree.CPP v3/v4 XML, Nav2's
//! trees) checked, quantified through their GSPN, simulated, and fitted to logs.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result};
use bt::check::CheckOptions;
use bt::montecarlo::{Limits, estimate};
use bt::{AnalyzeOptions, ReadOptions, Tree, TreeParams};
use clap::{Args, Subcommand};

use crate::output::{Table, fields, num};
use crate::{out, outln};

#[derive(Subcommand, Debug)]
pub enum BtCommand {
    /// Structural faults, each with the node's path and line: unreachable
    /// nodes, loops with no way out, reactive nodes that pre-empt a later
    /// child forever, blackboard entries read before any node writes them,
    /// missing or cyclic subtrees, dead parallel thresholds.
    ///
    /// Exit code: 0 nothing found, 1 findings, 2 the tree could not be read.
    /// Nav2's navigator entries (goal, goals, path, error codes…) count as
    /// written unless --no-nav2-blackboard.
    ///
    /// Example: petrinav bt check models/bt/nav2/navigate_to_pose_w_replanning_and_recovery.xml
    Check(CheckArgs),
    /// P(success), P(failure), mean time to the end and its quantiles, each
    /// leaf's share of the failures, how long each node is active, and the
    /// sensitivity of P(success) and of the mean time to every leaf
    /// parameter (which leaf to improve first, with --sensitivities) — from
    /// the tree's GSPN.
    ///
    /// Leaf parameters come from a TOML sidecar (--params; defaults: actions
    /// succeed with p = 0.9 after 1 s, conditions hold with p = 0.9, drawn at
    /// each evaluation; see docs/behaviour-trees.md).
    ///
    /// Example: petrinav bt analyze models/bt/nav2/navigate_to_pose_w_replanning_and_recovery.xml
    /// --params models/bt/nav2/nominal.toml --svg tree.svg
    Analyze(AnalyzeArgs),
    /// Monte Carlo: executions of the tree by a tick-based interpreter
    /// independent of the net, with 99 % intervals.
    ///
    /// Example: petrinav bt simulate tree.xml --params p.toml --runs 100000
    Simulate(SimulateArgs),
    /// Estimates leaf parameters from execution logs and writes a sidecar:
    /// our JSONL (.jsonl), BehaviorTree.CPP 4's FileLogger2 (.btlog), its
    /// MinitraceLogger (.json, durations only).
    ///
    /// Example: petrinav bt fit tree.xml run1.btlog run2.btlog -o measured.toml
    Fit(FitArgs),
}

#[derive(Args, Debug)]
pub struct TreeArgs {
    /// The tree: a BehaviorTree.CPP XML file (v3 or v4; includes are read
    /// relative to it).
    tree: PathBuf,
    /// The tree to expand, if the file has several and no main_tree_to_execute.
    #[arg(long, value_name = "ID")]
    main: Option<String>,
    /// A TreeNodesModel file to add (actions, conditions and their ports).
    #[arg(long, value_name = "FILE")]
    model: Vec<PathBuf>,
}

#[derive(Args, Debug)]
pub struct CheckArgs {
    #[command(flatten)]
    tree: TreeArgs,
    /// Leaf parameters: actions with a mean time of 0 count as finishing
    /// within their tick (else Nav2's synchronous actions do).
    #[arg(long, value_name = "TOML")]
    params: Option<PathBuf>,
    /// A blackboard entry the application writes before the tree runs (repeatable).
    #[arg(long, value_name = "KEY")]
    blackboard: Vec<String>,
    /// Do not count Nav2's navigator entries as written.
    #[arg(long)]
    no_nav2_blackboard: bool,
    /// Print JSON.
    #[arg(long)]
    json: bool,
}

#[derive(Args, Debug)]
pub struct AnalyzeArgs {
    #[command(flatten)]
    tree: TreeArgs,
    /// Leaf parameters (TOML sidecar); defaults without it.
    #[arg(long, value_name = "TOML")]
    params: Option<PathBuf>,
    /// Quantiles of the time to the end (repeatable; default 0.5, 0.9, 0.99).
    #[arg(long = "quantile", value_name = "Q")]
    quantiles: Vec<f64>,
    /// Also compute the sensitivities of P(success) and of the mean time to
    /// every leaf parameter: one re-solve per time parameter, per action's
    /// probability of success when its last stage draws the outcome and per
    /// persistent condition's probability of holding, one re-compilation per
    /// other probability (under a second on Nav2's largest trees;
    /// crates/bt/BENCHMARKS.md).
    #[arg(long)]
    sensitivities: bool,
    /// Write the tree drawn as SVG, coloured by activity and failures.
    #[arg(long, value_name = "FILE")]
    svg: Option<PathBuf>,
    /// Write the tree's GSPN as Graphviz DOT (render with `dot -Tsvg`).
    #[arg(long, value_name = "FILE")]
    dot: Option<PathBuf>,
    /// Write the tree's GSPN in petrinav's TOML format (for `petrinav gspn …`).
    #[arg(long, value_name = "FILE")]
    net: Option<PathBuf>,
    /// Print JSON.
    #[arg(long)]
    json: bool,
}

#[derive(Args, Debug)]
pub struct SimulateArgs {
    #[command(flatten)]
    tree: TreeArgs,
    /// Leaf parameters (TOML sidecar).
    #[arg(long, value_name = "TOML")]
    params: Option<PathBuf>,
    /// Executions.
    #[arg(long, default_value_t = 10_000)]
    runs: usize,
    /// Seed of the first execution (execution k uses seed + k).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Print JSON.
    #[arg(long)]
    json: bool,
}

#[derive(Args, Debug)]
pub struct FitArgs {
    #[command(flatten)]
    tree: TreeArgs,
    /// Log files (.jsonl, .btlog, .json).
    #[arg(required = true)]
    logs: Vec<PathBuf>,
    /// Output sidecar (standard output if absent).
    #[arg(short, long)]
    output: Option<PathBuf>,
}

pub fn run(cmd: BtCommand) -> Result<ExitCode> {
    match cmd {
        BtCommand::Check(a) => Ok(check(&a)),
        BtCommand::Analyze(a) => analyze(&a).map(|()| ExitCode::SUCCESS),
        BtCommand::Simulate(a) => simulate(&a).map(|()| ExitCode::SUCCESS),
        BtCommand::Fit(a) => fit(&a).map(|()| ExitCode::SUCCESS),
    }
}

fn read(args: &TreeArgs, keep_missing: bool) -> Result<Tree> {
    let mut options = ReadOptions {
        main: args.main.clone(),
        keep_missing,
        ..ReadOptions::default()
    };
    for m in &args.model {
        let text = std::fs::read_to_string(m).with_context(|| format!("reading {}", m.display()))?;
        let models = bt::model::parse_models(&text, &m.display().to_string())?;
        options.models.0.extend(models.0);
    }
    Ok(bt::read_file(&args.tree, &options)?)
}

fn params(path: Option<&Path>) -> Result<TreeParams> {
    Ok(match path {
        Some(p) => TreeParams::read_file(p)?,
        None => TreeParams::default(),
    })
}

fn check(a: &CheckArgs) -> ExitCode {
    match check_inner(a) {
        Ok(found) if found => ExitCode::from(1),
        Ok(_) => ExitCode::SUCCESS,
        Err(e) => {
            if crate::broken_pipe(&e) {
                return ExitCode::SUCCESS;
            }
            eprintln!("error: {e:#}");
            ExitCode::from(2)
        }
    }
}

fn check_inner(a: &CheckArgs) -> Result<bool> {
    let tree = read(&a.tree, true)?;
    let p = match &a.params {
        Some(p) => Some(TreeParams::read_file(p)?),
        None => None,
    };
    if let Some(p) = &p {
        p.check_kinds(&tree)?;
    }
    let mut options = if a.no_nav2_blackboard {
        CheckOptions::none()
    } else {
        CheckOptions::nav2()
    };
    options.external.extend(a.blackboard.iter().cloned());
    let findings = bt::check(&tree, p.as_ref(), &options);
    if a.json {
        let v = serde_json::json!({
            "tree": tree.main,
            "file": a.tree.tree.display().to_string(),
            "nodes": tree.len(),
            "findings": findings,
        });
        outln!("{}", serde_json::to_string_pretty(&v)?)?;
    } else if findings.is_empty() {
        outln!("{}: no finding ({} nodes)", a.tree.tree.display(), tree.len())?;
    } else {
        for f in &findings {
            outln!(
                "{}:{}: {}: {}\n    {}",
                f.file,
                f.line,
                f.kind.name(),
                f.path,
                f.message
            )?;
        }
        outln!("{} finding(s)", findings.len())?;
    }
    Ok(!findings.is_empty())
}

fn analyze(a: &AnalyzeArgs) -> Result<()> {
    let tree = read(&a.tree, false)?;
    let p = params(a.params.as_deref())?;
    let mut options = AnalyzeOptions {
        sensitivities: a.sensitivities,
        ..AnalyzeOptions::default()
    };
    if !a.quantiles.is_empty() {
        if let Some(q) = a.quantiles.iter().find(|q| !(**q > 0.0 && **q < 1.0)) {
            anyhow::bail!("--quantile {q}: a probability strictly between 0 and 1");
        }
        options.quantiles = a.quantiles.clone();
    }
    if let Some(path) = &a.dot {
        let net = bt::analyze::net_of(&tree, &p)?;
        std::fs::write(path, petri::io::write_string(&net, petri::io::Format::Dot)?)
            .with_context(|| format!("writing {}", path.display()))?;
    }
    if let Some(path) = &a.net {
        let net = bt::analyze::net_of(&tree, &p)?;
        petri::io::write_file(&net, path)?;
    }
    let start = std::time::Instant::now();
    let r = bt::analyze(&tree, &p, &options)?;
    let seconds = start.elapsed().as_secs_f64();
    if let Some(path) = &a.svg {
        std::fs::write(path, bt::svg::render(&tree, Some(&r)))
            .with_context(|| format!("writing {}", path.display()))?;
    }
    if a.json {
        outln!("{}", serde_json::to_string_pretty(&r)?)?;
        return Ok(());
    }
    print_report(&tree, &r, seconds)
}

fn print_report(tree: &Tree, r: &bt::Report, seconds: f64) -> Result<()> {
    let q: Vec<String> = r
        .quantiles
        .iter()
        .map(|(q, t)| format!("{}%: {} s", num(q * 100.0), num(*t)))
        .collect();
    out!(
        "{}",
        fields(&[
            ("tree", format!("{} ({} nodes)", r.tree, tree.len())),
            (
                "net",
                format!(
                    "{} places, {} transitions; {} tangible states; solved in {:.3} s",
                    r.net_size.0, r.net_size.1, r.states, seconds
                )
            ),
            ("P(success)", num(r.p_success)),
            ("P(failure)", num(r.p_failure)),
            ("P(never ends)", num(r.p_never)),
            (
                "mean time",
                format!(
                    "{} s (success {} s, failure {} s)",
                    num(r.mean_time),
                    num(r.mean_time_success),
                    num(r.mean_time_failure)
                )
            ),
            ("quantiles", q.join(", ")),
            ("failures at time 0", num(r.failure_at_start)),
        ])
    )?;
    let mut t = Table::new(["node", "active", "failures", "line"]);
    for s in &r.nodes {
        let node = tree.node(s.node);
        let depth = s.path.matches('/').count();
        t.row([
            format!("{}{}", "  ".repeat(depth), node.label()),
            num(s.activity),
            num(s.failure_share),
            node.line.to_string(),
        ]);
    }
    outln!(
        "\nnodes (active: share of the run; failures: share of P(failure) ended by an event of the subtree)"
    )?;
    out!("{}", t.render())?;
    if !r.sensitivities.is_empty() {
        let mut t = Table::new(["key", "parameter", "value", "dP(success)/d", "dT/d"]);
        for s in &r.sensitivities {
            t.row([
                s.key.clone(),
                s.parameter.clone(),
                num(s.value),
                num(s.d_p_success),
                num(s.d_mean_time),
            ]);
        }
        outln!("\nsensitivities (largest effect on P(success) first)")?;
        out!("{}", t.render())?;
    }
    if !r.unused_params.is_empty() {
        outln!(
            "\nwarning: parameters that name no node: {}",
            r.unused_params.join(", ")
        )?;
    }
    Ok(())
}

fn simulate(a: &SimulateArgs) -> Result<()> {
    let tree = read(&a.tree, false)?;
    let p = params(a.params.as_deref())?;
    let e = estimate(&tree, &p, a.runs, a.seed, Limits::default())?;
    if a.json {
        outln!("{}", serde_json::to_string_pretty(&e)?)?;
        return Ok(());
    }
    out!(
        "{}",
        fields(&[
            ("runs", e.runs.to_string()),
            (
                "P(success)",
                format!("{} ± {} (99 %)", num(e.p_success), num(e.p_success_hw))
            ),
            (
                "mean time",
                format!("{} ± {} s (99 %)", num(e.mean_time), num(e.mean_time_hw))
            ),
            ("cut (never ended)", num(e.p_never)),
        ])
    )?;
    Ok(())
}

fn fit(a: &FitArgs) -> Result<()> {
    let tree = read(&a.tree, false)?;
    let mut transitions = Vec::new();
    for (run, path) in a.logs.iter().enumerate() {
        let name = path.display().to_string();
        let bytes = std::fs::read(path).with_context(|| format!("reading {name}"))?;
        let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("");
        let mut t = match ext {
            "btlog" => bt::logs::read_btlog(&bytes, &name, run)?,
            "jsonl" => {
                let text = String::from_utf8(bytes).with_context(|| format!("{name}: not UTF-8"))?;
                let mut t = bt::logs::read_jsonl(&text, &name)?;
                // Runs of a JSONL file are numbered after the files before it.
                t.iter_mut().for_each(|x| x.run += run * 1_000_000);
                t
            }
            "json" => {
                let text = String::from_utf8(bytes).with_context(|| format!("{name}: not UTF-8"))?;
                bt::logs::read_minitrace(&text, &name, run)?
            }
            "db3" | "btdb" => anyhow::bail!(
                "{name}: SQLite logs are not read (docs/behaviour-trees.md, Logs): log with FileLogger2 (.btlog) instead"
            ),
            _ => anyhow::bail!("{name}: unknown log format (.jsonl, .btlog or .json)"),
        };
        transitions.append(&mut t);
    }
    let fit = bt::logs::fit(&tree, &transitions);
    let text = fit.to_toml();
    match &a.output {
        Some(p) => std::fs::write(p, text).with_context(|| format!("writing {}", p.display()))?,
        None => out!("{text}")?,
    }
    Ok(())
}
