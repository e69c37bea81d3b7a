//! `petrinav gspn …`: the GSPN engine on the command line.

mod optimize;

use std::io::IsTerminal as _;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use clap::{Args, Subcommand, ValueEnum};
use guide::supervisor::Behaviour;
use lab::gspn::{SimOptions, SolveOptions};
use petri::io::Format;
use petri::{
    CompiledGspn, ExploreParams, Gspn, Interrupt, Method, Net, Params, Progress, ProgressSnapshot,
    ReachabilityGraph, SolveParams, Stage,
};
use serde_json::Value;

use crate::output::{Table, fields, num};
use crate::{out, outln};

#[derive(Subcommand, Debug)]
pub enum GspnCommand {
    /// Size, structure and behavioural properties of a net: reachability
    /// graph, dead markings, bounds, liveness, invariants.
    ///
    /// Example: petrinav gspn info FlexibleManufacturingSystem.PNPRO --param N=3
    Info(InfoArgs),
    /// Steady-state solution: probabilities, mean tokens, throughputs, measures.
    ///
    /// Example: petrinav gspn solve model.toml --measure '#P1 = 1 and #P7 = 1'
    Solve(SolveArgs),
    /// The tour-guide supervisor's decision between AutoMove and Contour
    /// tracking, on the shipped supervisor net.
    ///
    /// Unspecified rates take the source's initial values. Example:
    /// petrinav gspn select --set lambda7=1/122.33 --set lambda8=1/186.98
    Select(SelectArgs),
    /// Discrete-event simulation with confidence intervals (batch means).
    ///
    /// Example: petrinav gspn simulate model.toml --time 100000 --seed 1
    Simulate(SimulateArgs),
    /// The best policy of a net with decisions (or of a Storm DRN model)
    /// for a property, its value with a guaranteed bound, and for every
    /// choice marking the action chosen and each alternative's value.
    ///
    /// Example: petrinav gspn optimize net.toml --objective 'Tmin=? [F "done"]' --policy-out policy.json
    Optimize(optimize::OptimizeArgs),
    /// Converts between formats, chosen by extension: .pnpro (GreatSPN),
    /// .pnml (ISO 15909-2), .toml (petrinav), .dot (Graphviz, output only),
    /// .drn (Storm's explicit format: the net's CTMC or Markov automaton,
    /// output only).
    Convert {
        /// Input file.
        input: PathBuf,
        /// Output file.
        output: PathBuf,
        /// Sets a parameter (for .drn output): NAME=VALUE.
        #[arg(long = "param", short = 'p', value_name = "NAME=VALUE")]
        params: Vec<String>,
        /// Rate for every timed transition that has none (for .drn output).
        #[arg(long, value_name = "R")]
        default_rate: Option<f64>,
    },
    /// Graphviz drawing of the net, its reachability graph or its tangible
    /// reachability graph (CTMC). Render with `dot -Tsvg`.
    Dot(DotArgs),
    /// Writes a member of a scalable benchmark family as a model file.
    ///
    /// Example: petrinav gspn family kanban 4 -o kanban4.toml
    Family {
        /// Family.
        #[arg(value_enum)]
        family: Family,
        /// Size parameter (kanbans per cell, pallets, philosophers, robots, stations, buffer places).
        n: u32,
        /// Output file (format by extension); standard output (TOML) if absent.
        #[arg(short, long)]
        output: Option<PathBuf>,
    },
}

/// Scalable net families.
#[derive(ValueEnum, Clone, Copy, Debug)]
pub enum Family {
    /// Ciardo & Tilgner's Kanban system (16 places; N = 4: 454,475 states).
    Kanban,
    /// Flexible manufacturing system, GSPN variant (immediate choices).
    Fms,
    /// Dining philosophers of the MCC (deadlock; 3^N markings).
    Philosophers,
    /// N robots sharing 3 corridors (immediate choice of a free corridor).
    Robots,
    /// N robots choosing among 3 corridors, fast and risky to slow and
    /// safe: a net with decisions (gspn optimize; N = 100: 216,751 states).
    Corridors,
    /// A server polling N stations of 3 customers each (4N · 4^N states).
    Polling,
    /// 5 stations in tandem with buffers of N places, 2 servers each, blocking ((N+1)^5 states).
    Tandem,
}

/// Options shared by commands that load and instantiate a net.
#[derive(Args, Debug)]
pub struct NetArgs {
    /// Model file: .pnpro, .pnml or .toml.
    pub file: PathBuf,
    /// Sets a parameter (constant, template, rate, weight): NAME=VALUE; the
    /// value may be an expression over numbers, e.g. lambda=1/3.
    #[arg(long = "param", short = 'p', value_name = "NAME=VALUE")]
    pub params: Vec<String>,
    /// Stop with an error beyond this many markings (tangible + vanishing);
    /// no limit by default: the memory guard decides.
    #[arg(long, value_name = "N")]
    pub max_states: Option<usize>,
    /// Stop with an error as soon as generating, compiling and solving the
    /// state space found so far would need more memory than this: bytes, or
    /// a number with K, M, G (powers of 1024), e.g. 12G. Default: 85 % of the
    /// memory available when the command starts (MemAvailable).
    #[arg(long, value_name = "SIZE", value_parser = parse_size)]
    pub max_memory: Option<u64>,
}

/// `12G`, `800M`, `1.5GiB`, `65536`: bytes, with K/M/G/T (powers of 1024).
fn parse_size(s: &str) -> std::result::Result<u64, String> {
    let t = s.trim();
    let lower = t.to_ascii_lowercase();
    let body = lower.trim_end_matches("ib").trim_end_matches('b');
    let (num, mult) = match body.chars().last() {
        Some('k') => (&body[..body.len() - 1], 1u64 << 10),
        Some('m') => (&body[..body.len() - 1], 1 << 20),
        Some('g') => (&body[..body.len() - 1], 1 << 30),
        Some('t') => (&body[..body.len() - 1], 1 << 40),
        _ => (body, 1),
    };
    match num.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 && v * (mult as f64) < 1.8e19 => Ok((v * mult as f64) as u64),
        _ => Err(format!(
            "`{t}` is not a memory size (e.g. 12G, 800M, 1.5GiB or a number of bytes)"
        )),
    }
}

#[derive(Args, Debug)]
pub struct InfoArgs {
    #[command(flatten)]
    net: NetArgs,
    /// Print JSON instead of tables.
    #[arg(long)]
    json: bool,
    /// Show the product structure instead: the components (places tied
    /// together), their local state counts, the reachable markings against
    /// the potential ones; found symbolically, so it also works for nets
    /// far too large to generate.
    #[arg(long)]
    structure: bool,
    /// With --structure: components to use, outermost first, `;` between
    /// components and `,` between places (merged where the reachable set
    /// does not factor between them).
    #[arg(long, value_name = "PLACES;PLACES…")]
    partition: Option<String>,
}

#[derive(Args, Debug)]
pub struct SolveArgs {
    #[command(flatten)]
    net: NetArgs,
    /// Rate for every timed transition that has none (plain P/T nets).
    #[arg(long, value_name = "R")]
    default_rate: Option<f64>,
    /// A measure: a condition (its probability), e.g. '#P1 = 1 and #P7 = 1',
    /// or an arithmetic expression (its mean), e.g. '#P1 + 2 * #P2'.
    #[arg(long = "measure", short = 'm', value_name = "EXPR")]
    measures: Vec<String>,
    /// Steady-state method: auto = direct (GTH or sparse LU) up to 2,000
    /// states, or beyond while the LU's fill-in stays small (nearly
    /// one-dimensional chains); BiCGSTAB otherwise.
    #[arg(long, value_enum, default_value_t = MethodArg::Auto)]
    method: MethodArg,
    /// Relative residual at which iterative methods stop.
    #[arg(long, default_value_t = 1e-12)]
    tolerance: f64,
    /// Solve the net under this policy (a file written by `gspn optimize
    /// --policy-out`): its choice markings resolved, every measure applies.
    #[arg(long, value_name = "FILE")]
    policy: Option<PathBuf>,
    /// Engine: explicit = reachability graph and sparse generator;
    /// structured = product of components' local spaces, no generator
    /// stored (nets far beyond the explicit engine's memory); auto = the
    /// structured engine for chains of 100,000 states or more with a product
    /// structure and no vanishing markings, the explicit one otherwise (the
    /// reason is printed).
    #[arg(long, value_enum, default_value_t = EngineArg::Auto)]
    engine: EngineArg,
    /// Structured engine: components to use, outermost first, `;` between
    /// components and `,` between places.
    #[arg(long, value_name = "PLACES;PLACES…")]
    partition: Option<String>,
    /// Print JSON instead of tables.
    #[arg(long)]
    json: bool,
    /// Also print where the memory went: bytes per tangible marking by
    /// component (from the allocations), by stage, the memory guard's
    /// estimate and the process's peak resident memory (a `memory` field
    /// with --json).
    #[arg(long)]
    stats: bool,
}

#[derive(ValueEnum, Clone, Copy, Debug)]
enum EngineArg {
    Auto,
    Explicit,
    Structured,
}

#[derive(ValueEnum, Clone, Copy, Debug)]
enum MethodArg {
    Auto,
    Direct,
    GaussSeidel,
    Bicgstab,
}

#[derive(Args, Debug)]
pub struct SelectArgs {
    /// Sets a supervisor rate: lambdaN=VALUE (N from 1 to 11, to 15 for a
    /// crediting net; λ1 and λ2 are set by the hypotheses and ignored).
    #[arg(long = "set", short = 's', value_name = "lambdaN=VALUE")]
    set: Vec<String>,
    /// Another supervisor net: of the source's structure, or of the crediting
    /// supervisor's (models/supervisor_credit.toml: it has the transition t15).
    #[arg(long, value_name = "FILE")]
    model: Option<PathBuf>,
    /// Decide as the crediting supervisor does at a Warning (lost); the
    /// default decides localized.
    #[arg(long)]
    lost: bool,
    /// Print JSON instead of a table.
    #[arg(long)]
    json: bool,
}

#[derive(Args, Debug)]
pub struct SimulateArgs {
    #[command(flatten)]
    net: NetArgs,
    /// Simulated time per run.
    #[arg(long, value_name = "T")]
    time: f64,
    /// Seed of the random number generator.
    #[arg(long, value_name = "S")]
    seed: u64,
    /// Simulated time discarded at the start.
    #[arg(long, default_value_t = 0.0)]
    warmup: f64,
    /// Number of batches for the batch-means confidence intervals.
    #[arg(long, default_value_t = 20)]
    batches: usize,
    /// Confidence level of the intervals.
    #[arg(long, default_value_t = 0.95)]
    confidence: f64,
    /// Rate for every timed transition that has none.
    #[arg(long, value_name = "R")]
    default_rate: Option<f64>,
    /// A measure expression, as for `solve`.
    #[arg(long = "measure", short = 'm', value_name = "EXPR")]
    measures: Vec<String>,
    /// Stop with an error after this many transition firings (all runs):
    /// about a minute of simulation at the default.
    #[arg(long, default_value_t = 1_000_000_000, value_name = "N")]
    max_events: u64,
    /// Stop with an error after this many seconds of wall-clock time
    /// (`inf` for no limit).
    #[arg(long, default_value_t = 600.0, value_name = "S")]
    max_wall: f64,
    /// Simulate the net under this policy (`gspn optimize --policy-out`).
    #[arg(long, value_name = "FILE")]
    policy: Option<PathBuf>,
    /// Print JSON instead of tables.
    #[arg(long)]
    json: bool,
}

#[derive(Args, Debug)]
pub struct DotArgs {
    #[command(flatten)]
    net: NetArgs,
    /// What to draw.
    #[arg(long, value_enum, default_value_t = Graph::Net)]
    graph: Graph,
    /// Label CTMC edges with rates (tangible graph only) using this default
    /// for transitions without one.
    #[arg(long, value_name = "R")]
    default_rate: Option<f64>,
    /// Refuse graphs with more markings than this.
    #[arg(long, default_value_t = 2000)]
    max_markings: usize,
    /// Output file; standard output if absent.
    #[arg(short, long)]
    output: Option<PathBuf>,
}

#[derive(ValueEnum, Clone, Copy, Debug)]
enum Graph {
    /// The net itself.
    Net,
    /// Reachability graph (tangible and vanishing markings).
    Rg,
    /// Tangible reachability graph (the CTMC).
    Trg,
}

pub fn run(cmd: GspnCommand) -> Result<()> {
    match cmd {
        GspnCommand::Info(a) => info(&a),
        GspnCommand::Solve(a) => solve(&a),
        GspnCommand::Select(a) => select(&a),
        GspnCommand::Simulate(a) => simulate(&a),
        GspnCommand::Optimize(a) => optimize::run(&a),
        GspnCommand::Convert {
            input,
            output,
            params,
            default_rate,
        } => convert(&input, &output, &params, default_rate),
        GspnCommand::Dot(a) => dot(&a),
        GspnCommand::Family { family, n, output } => family_cmd(family, n, output.as_deref()),
    }
}

fn load(args: &NetArgs) -> Result<(Net, Gspn)> {
    lab::gspn::load_within(&args.file, &args.params, args.max_memory)
}

fn explore(args: &NetArgs, gspn: &Gspn) -> Result<ReachabilityGraph> {
    lab::gspn::explore(gspn, &explore_params(args), Interrupt::NEVER)
}

pub(crate) fn explore_params(args: &NetArgs) -> ExploreParams {
    let defaults = ExploreParams::default();
    ExploreParams {
        max_states: args.max_states.unwrap_or(defaults.max_states),
        max_memory: args.max_memory.unwrap_or(defaults.max_memory),
        ..defaults
    }
}

pub(crate) fn print_json(v: &Value) -> Result<()> {
    outln!("{}", serde_json::to_string_pretty(v)?)?;
    Ok(())
}

fn info(a: &InfoArgs) -> Result<()> {
    if a.structure {
        return structure_info(a);
    }
    let (net, gspn) = load(&a.net)?;
    let phase = Phase::new();
    let analysis = lab::gspn::analyse(&gspn, &explore_params(&a.net), Interrupt::NEVER, &mut |m| {
        phase.show(m)
    })?;
    drop(phase);
    if a.json {
        return print_json(&analysis.to_json(&net, &gspn));
    }
    let (rg, props) = (&analysis.graph, &analysis.properties);
    let (pinv, tinv) = (&analysis.p_invariants, &analysis.t_invariants);
    let places = gspn.place_names();
    let trans = gspn.transition_names();
    let tnames = |ts: &[petri::TransitionId]| ts.iter().map(|t| trans[t.index()].clone()).collect::<Vec<_>>();
    let st = rg.stats();
    let structural = analysis.structural_bounds(&gspn);
    out!(
        "{}",
        fields(&[
            ("net", format!("{} ({})", gspn.name(), a.net.file.display())),
            (
                "size",
                format!(
                    "{} places, {} transitions ({} immediate), {} arcs",
                    gspn.num_places(),
                    gspn.num_transitions(),
                    gspn.num_immediate(),
                    net.arcs.len()
                )
            ),
            (
                "reachability graph",
                format!(
                    "{} markings ({} tangible, {} vanishing), {} edges, {:.3} s",
                    rg.num_markings(),
                    rg.num_tangible(),
                    rg.num_vanishing(),
                    rg.num_edges(),
                    st.seconds
                )
            ),
            ("dead markings", props.dead_markings.len().to_string()),
            ("bounded", format!("yes (safe: {})", yes(props.safe))),
            (
                "live",
                format!(
                    "{} ({} of {} transitions live, {} dead)",
                    yes(props.live),
                    props.live_transitions.len(),
                    gspn.num_transitions(),
                    props.dead_transitions.len()
                )
            ),
            ("reversible (M0 home state)", yes(props.reversible).to_string()),
            (
                "covered by P-invariants",
                pinv.as_ref()
                    .map_or("not computed".into(), |i| yes(i.covers_all()).to_string())
            ),
        ])
    )?;
    let mut t = Table::new(["place", "initial", "bound", "structural bound"]);
    for (p, name) in places.iter().enumerate() {
        let sb = structural
            .as_ref()
            .and_then(|b| b[p])
            .map_or("-".to_string(), |v| v.to_string());
        t.row([
            name.clone(),
            gspn.initial_marking()[p].to_string(),
            props.bounds[p].to_string(),
            sb,
        ]);
    }
    outln!("\n{}", t.render())?;
    if !props.dead_transitions.is_empty() {
        outln!(
            "dead transitions: {}\n",
            tnames(&props.dead_transitions).join(", ")
        )?;
    }
    for (label, inv) in [("P-invariants", pinv), ("T-invariants", tinv)] {
        match inv {
            Ok(i) if i.is_empty() => outln!("{label}: none\n")?,
            Ok(i) => outln!("{label} ({}):\n{}", i.len(), i.display(&gspn))?,
            Err(e) => outln!("{label}: not computed ({e})\n")?,
        }
    }
    if let Some(pairs) = &props.mutually_exclusive {
        let shown: Vec<String> = pairs
            .iter()
            .take(20)
            .map(|(p, q)| format!("{}|{}", places[p.index()], places[q.index()]))
            .collect();
        let more = if pairs.len() > 20 {
            format!(" … ({} pairs in all; --json lists them)", pairs.len())
        } else {
            String::new()
        };
        outln!(
            "mutually exclusive places: {}{more}",
            if shown.is_empty() {
                "none".into()
            } else {
                shown.join(", ")
            }
        )?;
    }
    Ok(())
}

/// `gspn info --structure`.
fn structure_info(a: &InfoArgs) -> Result<()> {
    let (_, gspn) = load(&a.net)?;
    let phase = Phase::new();
    phase.show("finding the product structure");
    let s = lab::engine::structure(&gspn, a.partition.as_deref())?;
    drop(phase);
    if a.json {
        return print_json(&lab::engine::structure_json(&gspn, &s));
    }
    let names = gspn.place_names();
    let product =
        |v: &mut dyn Iterator<Item = u128>| v.map(|x| x.to_string()).collect::<Vec<_>>().join(" × ");
    out!(
        "{}",
        fields(&[
            ("net", format!("{} ({})", gspn.name(), a.net.file.display())),
            ("reachable markings", s.reachable().to_string()),
            (
                "components",
                format!(
                    "{} = {}{}",
                    product(&mut s.components().iter().map(|c| c.len() as u128)),
                    s.product(),
                    if s.is_exact() {
                        " (exactly the reachable set)"
                    } else {
                        " (NOT the reachable set)"
                    }
                )
            ),
            (
                "P-invariant groups",
                format!(
                    "{} = {} potential markings",
                    product(&mut s.groups().iter().map(|g| g.projected_states)),
                    s.potential()
                )
            ),
            (
                "home state",
                match s.reversible() {
                    Some(true) => "yes: every marking reaches M0 (irreducible chain)".to_string(),
                    Some(false) => "no: some marking does not reach M0 back".to_string(),
                    None => "decided when solving (immediate transitions)".to_string(),
                }
            ),
            (
                "symbolic search",
                format!("{} decision-diagram nodes, {:.3} s", s.mdd_nodes(), s.seconds())
            ),
        ])
    )?;
    let mut t = Table::new(["component", "local states", "places"]);
    for (k, c) in s.components().iter().enumerate() {
        t.row([
            (k + 1).to_string(),
            c.len().to_string(),
            c.places
                .iter()
                .map(|p| names[p.index()].as_str())
                .collect::<Vec<_>>()
                .join(" "),
        ]);
    }
    outln!("\n{}", t.render())?;
    let mut t = Table::new(["P-invariant group", "projected states", "places"]);
    for (k, g) in s.groups().iter().enumerate() {
        t.row([
            (k + 1).to_string(),
            if g.exact {
                g.projected_states.to_string()
            } else {
                format!("≤ {}", g.projected_states)
            },
            g.places.join(" "),
        ]);
    }
    outln!("{}", t.render())?;
    for n in s.notes() {
        outln!("note: {n}")?;
    }
    Ok(())
}

fn yes(b: bool) -> &'static str {
    if b { "yes" } else { "no" }
}

fn solve_params(method: MethodArg, tolerance: f64) -> SolveParams {
    SolveParams {
        method: match method {
            MethodArg::Auto => Method::Auto,
            MethodArg::Direct => Method::Direct,
            MethodArg::GaussSeidel => Method::GaussSeidel,
            MethodArg::Bicgstab => Method::Bicgstab,
        },
        tolerance,
        ..SolveParams::default()
    }
}

/// What a long command is doing, on a terminal (a spinner with the phase
/// and the time spent); nothing when standard error is not a terminal.
/// Ctrl-C ends these commands at once (no handler is installed for them).
struct Phase(std::cell::OnceCell<Option<indicatif::ProgressBar>>);

impl Phase {
    fn new() -> Phase {
        Phase(std::cell::OnceCell::new())
    }

    /// Shows `message`, starting the spinner on the first one.
    fn show(&self, message: &'static str) {
        let bar = self.0.get_or_init(|| {
            std::io::stderr().is_terminal().then(|| {
                let b = indicatif::ProgressBar::new_spinner();
                b.set_style(
                    indicatif::ProgressStyle::with_template("{spinner} {msg} ({elapsed})")
                        .unwrap_or_else(|_| indicatif::ProgressStyle::default_spinner()),
                );
                b.enable_steady_tick(std::time::Duration::from_millis(120));
                b
            })
        });
        if let Some(b) = bar {
            b.set_message(message);
        }
    }
}

impl Drop for Phase {
    fn drop(&mut self) {
        if let Some(Some(b)) = self.0.get() {
            b.finish_and_clear();
        }
    }
}

/// Runs `work` while a spinner on standard error (a terminal) shows what
/// `progress` says, redrawn ten times a second by a second thread that
/// ends with `work`. Ctrl-C ends the command at once.
fn with_progress_line<T>(progress: &Progress, work: impl FnOnce() -> T) -> T {
    let bar = indicatif::ProgressBar::new_spinner();
    bar.set_style(
        indicatif::ProgressStyle::with_template("{spinner} {msg} ({elapsed})")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_spinner()),
    );
    let (done, finished) = std::sync::mpsc::channel::<()>();
    let shown = bar.clone();
    let result = std::thread::scope(|scope| {
        scope.spawn(move || {
            let bar = shown;
            let mut rate = StageRate::default();
            while let Err(std::sync::mpsc::RecvTimeoutError::Timeout) =
                finished.recv_timeout(std::time::Duration::from_millis(100))
            {
                let now = progress.snapshot();
                bar.set_message(progress_message(&now, rate.per_second(&now)));
                bar.tick();
            }
        });
        let result = work();
        // Fails only if the thread has already ended.
        let _ = done.send(());
        result
    });
    bar.finish_and_clear();
    result
}

/// Markings per second since generation was first seen.
#[derive(Default)]
struct StageRate {
    first: Option<(std::time::Instant, usize)>,
}

impl StageRate {
    fn per_second(&mut self, now: &ProgressSnapshot) -> f64 {
        if now.stage != Stage::Generating {
            return 0.0;
        }
        let (since, markings) = *self
            .first
            .get_or_insert_with(|| (std::time::Instant::now(), now.markings));
        let seconds = since.elapsed().as_secs_f64();
        if seconds > 0.0 {
            now.markings.saturating_sub(markings) as f64 / seconds
        } else {
            0.0
        }
    }
}

/// The progress line of `gspn solve`: the stage and its counters.
fn progress_message(now: &ProgressSnapshot, markings_per_second: f64) -> String {
    match now.stage {
        Stage::Idle => "starting".into(),
        Stage::Generating => format!(
            "generating the reachability graph: {} markings, {} edges ({:.2} M markings/s)",
            now.markings,
            now.edges,
            markings_per_second / 1e6
        ),
        Stage::Compiling => format!("compiling the CTMC of {} markings", now.markings),
        Stage::Structuring if now.markings == 0 => "finding the product structure".into(),
        Stage::Structuring => format!("preparing the structured engine: {} states", now.markings),
        Stage::Solving if now.iteration == 0 => "solving the steady state".into(),
        Stage::Solving => format!(
            "solving the steady state: sweep or iteration {}, residual estimate {:.1e}",
            now.iteration, now.residual
        ),
    }
}

/// The net of `args`, under `policy` when one is given.
fn load_under(args: &NetArgs, policy: Option<&Path>) -> Result<(Net, Gspn)> {
    let (net, gspn) = load(args)?;
    Ok(match policy {
        Some(p) => {
            let g = lab::optimize::with_policy(&gspn, p)?;
            (net, g)
        }
        None => (net, gspn),
    })
}

fn solve(a: &SolveArgs) -> Result<()> {
    let (_, gspn) = load_under(&a.net, a.policy.as_deref())?;
    let measures = lab::gspn::parse_measures(&a.measures)?;
    let options = SolveOptions {
        explore: explore_params(&a.net),
        solve: solve_params(a.method, a.tolerance),
        default_rate: a.default_rate,
    };
    let engine = match a.engine {
        EngineArg::Auto => lab::engine::Engine::Auto,
        EngineArg::Explicit => lab::engine::Engine::Explicit,
        EngineArg::Structured => lab::engine::Engine::Structured,
    };
    let partition = a.partition.as_deref();
    let steady = if std::io::stderr().is_terminal() {
        let progress = Progress::new();
        with_progress_line(&progress, || {
            lab::engine::solve(
                &gspn,
                &options,
                engine,
                partition,
                Interrupt::NEVER.with_progress(&progress),
                &mut |_| {},
            )
        })?
    } else {
        lab::engine::solve(&gspn, &options, engine, partition, Interrupt::NEVER, &mut |_| {})?
    };
    let values = steady.measures(&measures)?;
    let sol = steady.summary();
    let places = gspn.place_names();
    let trans = gspn.transition_names();
    if a.json {
        let ms: Vec<(String, f64)> = a.measures.iter().cloned().zip(values.iter().copied()).collect();
        let mut v = steady.to_json(&ms);
        if a.stats {
            if let Value::Object(o) = &mut v {
                o.insert("memory".into(), serde_json::to_value(steady.memory())?);
            }
        }
        return print_json(&v);
    }
    out!(
        "{}",
        fields(&[
            ("net", format!("{} ({})", gspn.name(), a.net.file.display())),
            (
                "state space",
                format!("{} tangible, {} vanishing markings", sol.tangible, sol.vanishing)
            ),
            (
                "engine",
                format!("{}: {}", steady.choice.engine, steady.choice.reason)
            ),
            (
                "long run",
                if sol.ergodic {
                    "ergodic (one recurrent class)".to_string()
                } else {
                    format!(
                        "not ergodic: {} bottom components, reached with probabilities {}",
                        sol.bottom_probabilities.len(),
                        sol.bottom_probabilities
                            .iter()
                            .map(|p| num(*p))
                            .collect::<Vec<_>>()
                            .join(", ")
                    )
                }
            ),
            (
                "solver",
                format!(
                    "{}, {} iterations, residual {:.2e}, {:.3} s",
                    sol.info.method, sol.info.iterations, sol.info.residual, sol.info.seconds
                )
            ),
        ])
    )?;
    let mut t = Table::new(["place", "P{#p > 0}", "E[#p]"]);
    for (p, n) in places.iter().enumerate() {
        t.row([n.clone(), num(sol.prob_nonempty[p]), num(sol.mean_tokens[p])]);
    }
    outln!("\n{}", t.render())?;
    let mut t = Table::new(["transition", "kind", "throughput"]);
    for (i, n) in trans.iter().enumerate() {
        let kind = if gspn.is_immediate(petri::TransitionId(i as u32)) {
            "immediate"
        } else {
            "timed"
        };
        t.row([n.clone(), kind.to_string(), num(sol.throughput[i])]);
    }
    outln!("{}", t.render())?;
    if !measures.is_empty() {
        let mut t = Table::new(["measure", "value"]);
        for (m, v) in a.measures.iter().zip(&values) {
            t.row([m.clone(), num(*v)]);
        }
        outln!("{}", t.render())?;
    }
    if a.stats {
        outln!("{}", memory_table(&steady.memory()))?;
    }
    Ok(())
}

/// The `--stats` table: bytes per tangible marking by component and stage,
/// the stages' totals, the guard's estimate and the peak resident memory.
fn memory_table(m: &lab::gspn::MemoryReport) -> String {
    let acc = &m.account;
    let n = acc.tangible_markings.max(1) as f64;
    let mib = |b: u64| format!("{:.1}", b as f64 / (1u64 << 20) as f64);
    let per = |b: u64| format!("{:.1}", b as f64 / n);
    let mut t = Table::new(["component", "stage", "MiB", "B/marking"]);
    for p in &acc.parts {
        t.row([
            p.component.to_string(),
            p.stage.to_string(),
            mib(p.bytes),
            format!("{:.1}", p.bytes_per_marking),
        ]);
    }
    for (what, b) in [
        ("held at the end of generation", acc.generation_bytes),
        ("held while transposing", acc.compile_bytes),
        ("held while solving", acc.solve_bytes),
        ("peak of the three", acc.peak_bytes),
        ("memory guard's estimate", acc.guard_estimate_bytes),
    ] {
        t.row([what.to_string(), "total".into(), mib(b), per(b)]);
    }
    if let Some(rss) = m.peak_rss_bytes {
        t.row([
            "peak resident memory (VmHWM)".into(),
            "process".into(),
            mib(rss),
            per(rss),
        ]);
    }
    format!(
        "memory, {} tangible markings (heap capacities):\n{}",
        acc.tangible_markings,
        t.render()
    )
}

fn select(a: &SelectArgs) -> Result<()> {
    let selection = lab::gspn::select(&a.set, a.model.as_deref(), !a.lost)?;
    if a.json {
        return print_json(&selection.to_json()?);
    }
    let choice = |c: Behaviour| match c {
        Behaviour::AutoMove => "AutoMove (map-based planner)",
        Behaviour::Contour => "Contour tracking (wall following)",
    };
    let (table, rates) = match &selection {
        lab::gspn::Selection::Source { decision: d, rates } => (
            fields(&[
                ("choice", choice(d.choice).to_string()),
                (
                    "f_auto",
                    format!("{}  (throughput of t9, AutoMove hypothesis)", num(d.f_auto)),
                ),
                (
                    "f_cont",
                    format!("{}  (throughput of t10, Contour hypothesis)", num(d.f_cont)),
                ),
                ("U_auto", format!("{}  P{{#P1 = 1}}", num(d.u_auto))),
                ("U_cont", format!("{}  P{{#P2 = 1}}", num(d.u_cont))),
                ("P_loc,succ", num(d.p_loc_succ)),
                ("P_loc,warn", num(d.p_loc_warn)),
                ("P_pp,norm", num(d.p_pp_norm)),
                ("P_pp,abno", num(d.p_pp_abno)),
                ("tangible markings", d.tangible_markings.to_string()),
            ]),
            rates.as_array().to_vec(),
        ),
        lab::gspn::Selection::Credit {
            decision: d,
            rates,
            localized,
        } => (
            fields(&[
                ("supervisor", "crediting".to_string()),
                (
                    "decided",
                    if *localized {
                        "localized (Success)"
                    } else {
                        "lost (Warning)"
                    }
                    .to_string(),
                ),
                ("choice", choice(d.choice).to_string()),
                (
                    "f_auto",
                    format!("{}  (completions, AutoMove hypothesis)", num(d.f_auto)),
                ),
                (
                    "f_cont",
                    format!("{}  (completions, contour hypothesis)", num(d.f_cont)),
                ),
                ("P_success", num(d.p_success)),
                ("P_loc,warn", num(d.p_loc_warn)),
            ]),
            rates.as_array().to_vec(),
        ),
    };
    out!("{table}")?;
    outln!(
        "rates λ3…λ{}: {}",
        rates.len(),
        rates[2..].iter().map(|v| num(*v)).collect::<Vec<_>>().join(", ")
    )?;
    Ok(())
}

fn simulate(a: &SimulateArgs) -> Result<()> {
    let (_, gspn) = load_under(&a.net, a.policy.as_deref())?;
    let options = SimOptions {
        warmup: a.warmup,
        batches: a.batches,
        confidence: a.confidence,
        default_rate: a.default_rate,
        measures: a.measures.clone(),
        max_events: a.max_events,
        max_wall_s: (a.max_wall != f64::INFINITY).then_some(a.max_wall),
        ..SimOptions::new(a.time, a.seed)
    };
    let r = simulate_with_progress(&gspn, &options)?;
    if a.json {
        return print_json(&serde_json::to_value(&r)?);
    }
    out!(
        "{}",
        fields(&[
            ("net", format!("{} ({})", gspn.name(), a.net.file.display())),
            (
                "run",
                format!(
                    "{} events over {} time units (warm-up {}), seed {}",
                    r.events,
                    num(r.simulated_time),
                    num(a.warmup),
                    a.seed
                )
            ),
            (
                "intervals",
                format!("{}% confidence, {} batches", num(100.0 * r.confidence), a.batches)
            ),
        ])
    )?;
    let ci = |e: &petri::Estimate| format!("{} ± {}", num(e.mean), num(e.half_width));
    let mut t = Table::new(["place", "P{#p > 0}", "E[#p]"]);
    for (i, n) in r.place_names.iter().enumerate() {
        t.row([n.clone(), ci(&r.prob_nonempty[i]), ci(&r.places[i])]);
    }
    outln!("\n{}", t.render())?;
    let mut t = Table::new(["transition", "throughput"]);
    for (i, n) in r.transition_names.iter().enumerate() {
        t.row([n.clone(), ci(&r.throughputs[i])]);
    }
    outln!("{}", t.render())?;
    if !r.measures.is_empty() {
        let mut t = Table::new(["measure", "value"]);
        for (n, e) in &r.measures {
            t.row([n.clone(), ci(e)]);
        }
        outln!("{}", t.render())?;
    }
    Ok(())
}

/// Simulates with a progress bar on a terminal (simulated time done, firings,
/// the firings the whole simulation needs at the rate seen so far), quiet
/// otherwise; Ctrl-C stops the simulation at its next check (some
/// milliseconds) with an error saying where it was.
fn simulate_with_progress(gspn: &Gspn, options: &SimOptions) -> Result<petri::SimResult> {
    let interrupted = crate::interrupt::flag();
    let bar = std::io::stderr().is_terminal().then(|| {
        let b = indicatif::ProgressBar::new(1000);
        b.set_style(
            indicatif::ProgressStyle::with_template(
                "{bar:40} {percent:>3}% of simulated time  {msg}  ETA {eta}",
            )
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        b
    });
    let result = lab::gspn::simulate(gspn, options, &mut |p| {
        if let Some(b) = &bar {
            b.set_position((p.fraction() * 1000.0) as u64);
            b.set_message(format!("{} firings of ~{:.1e}", p.events, p.projected_events()));
        }
        if interrupted.is_some_and(|f| f.load(std::sync::atomic::Ordering::Relaxed)) {
            std::ops::ControlFlow::Break(())
        } else {
            std::ops::ControlFlow::Continue(())
        }
    });
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    result
}

fn convert(input: &Path, output: &Path, params: &[String], default_rate: Option<f64>) -> Result<()> {
    if lab::optimize::is_drn(output) {
        let options = lab::optimize::OptimizeOptions {
            default_rate,
            ..Default::default()
        };
        let model = lab::optimize::write_drn(input, output, params, &options)?;
        eprintln!(
            "{} -> {}: {}",
            input.display(),
            output.display(),
            lab::optimize::describe_model(&model)
        );
        return Ok(());
    }
    if lab::optimize::is_drn(input) {
        anyhow::bail!(
            "{}: a DRN file holds a state space, not a net; it converts to .drn only",
            input.display()
        );
    }
    if !params.is_empty() || default_rate.is_some() {
        anyhow::bail!(
            "--param and --default-rate apply to .drn output only (a net file keeps its parameters)"
        );
    }
    let net = lab::gspn::read_net(input)?;
    lab::gspn::write_net(&net, output)?;
    eprintln!(
        "{} -> {}: {} places, {} transitions, {} arcs, {} parameters",
        input.display(),
        output.display(),
        net.places.len(),
        net.transitions.len(),
        net.arcs.len(),
        net.params.len()
    );
    Ok(())
}

fn write_out(text: &str, output: Option<&Path>) -> Result<()> {
    match output {
        Some(path) => std::fs::write(path, text).with_context(|| format!("writing {}", path.display())),
        None => {
            out!("{text}")?;
            Ok(())
        }
    }
}

fn dot(a: &DotArgs) -> Result<()> {
    let (net, gspn) = load(&a.net)?;
    let text = match a.graph {
        Graph::Net => petri::io::write_dot(&net)?,
        Graph::Rg => {
            let rg = explore(&a.net, &gspn)?;
            petri::io::write_reachability_dot(&gspn, &rg, a.max_markings)?
        }
        Graph::Trg => {
            let rates = gspn.rates(&Params::new(), a.default_rate).ok();
            let rg = explore(&a.net, &gspn)?;
            let compiled = CompiledGspn::from_graph(gspn, rg)?;
            petri::io::write_tangible_dot(&compiled, rates.as_deref(), a.max_markings)?
        }
    };
    write_out(&text, a.output.as_deref())
}

fn family_cmd(family: Family, n: u32, output: Option<&Path>) -> Result<()> {
    use petri::families::Family as F;
    let net = match family {
        Family::Kanban => F::Kanban,
        Family::Fms => F::Fms,
        Family::Philosophers => F::Philosophers,
        Family::Robots => F::Robots,
        Family::Corridors => F::Corridors,
        Family::Polling => F::Polling,
        Family::Tandem => F::Tandem,
    }
    .build(n)?;
    match output {
        Some(path) => lab::gspn::write_net(&net, path),
        None => write_out(&petri::io::write_string(&net, Format::Toml)?, None),
    }
}

#[cfg(test)]
mod tests {
    use super::parse_size;

    #[test]
    fn memory_sizes_parse_in_powers_of_1024() {
        assert_eq!(parse_size("12G"), Ok(12 << 30));
        assert_eq!(parse_size("1.5GiB"), Ok(3 << 29));
        assert_eq!(parse_size("800m"), Ok(800 << 20));
        assert_eq!(parse_size("65536"), Ok(65536));
        assert!(parse_size("lots").is_err());
        assert!(parse_size("-1G").is_err());
    }
}
