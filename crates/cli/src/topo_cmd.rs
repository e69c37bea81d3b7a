//! `petrinav topo …`: topological maps as fuzzy Petri nets (spec
//! `docs/topo-fpn.md`; library `topo`): plan a route on a map file, convert
//! it for other tools, generate random office-like maps.
//!
//! Layout, so that more subcommands (`explore`, `go`: the robot building a
//! map and following a route in the simulator) are one more variant of
//! [`TopoCommand`] with its `…Args`, a line in [`run`] and their function:
//! what the subcommands share is kept apart from them —
//!
//! * [`load_map`]: a map file read and checked, errors naming the file
//!   (in `topo_map.rs`, with [`find_place`] and [`ModeArg`], which
//!   `topo_run.rs` uses too);
//! * [`RouteArgs`] (`--from`, `--to` …, `--mode`), flattened into a
//!   subcommand's args, and [`Route`], the same request as plain data (from
//!   `RouteArgs`, or from the optional options of `convert`), planned by
//!   [`plan_route`] with place names checked ([`find_place`]) and a "no
//!   route" explained;
//! * [`print_plan`]: a plan as the route, its table of `f(t)` and the
//!   alternatives at its places, or as JSON ([`plan_json`], stable keys).

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, anyhow, bail};
use clap::{Args, Subcommand};
use serde_json::{Value, json};
use topo::{
    FuzzyPetriNet, PlaceId, Plan, PlanError, PlanMode, Planner, TransitionId, random_office_like, to_dot,
    to_pnml,
};

use crate::output::{Table, fields, num};
use crate::topo_map::{ModeArg, find_place, load_map};
use crate::{out, outln};

#[derive(Subcommand, Debug)]
pub enum TopoCommand {
    /// Plans a route on a topological map: the places and transitions to take, with the
    /// values of the propagation along it.
    ///
    /// The map is a fuzzy Petri net (a `.fpn.json` file, as `topo generate` writes): places
    /// are the robot's reference places, transitions the navigation strategies that lead
    /// from one to the next, each with a cost C(t) (its share of the cost of all
    /// transitions) and a threshold λ(t) learnt from failures. Planning sets α = 0 at the
    /// goals and propagates f(t) = min(1, C(t) + α(destination)) backwards; a transition
    /// with f(t) > λ(t) is rejected (f = 1) and never taken. At each place the route takes
    /// the leaving transition with the smallest f.
    ///
    /// `--mode optimal` (default) propagates to the fixed point: the cheapest route.
    /// `--mode paper` stops, as the source does, as soon as the start has a value (after as
    /// many rounds as the fewest transitions of any route; α(from) is then the value of the
    /// cheapest such route) and walks along the smallest f of that last round: often a
    /// costlier route than optimal's, never a cheaper one.
    ///
    /// Several --to places: the route leads to the nearest. The table lists each transition
    /// of the route (C, f, λ, strategy, exit turn), then the other transitions leaving the
    /// route's places and why they were not taken (costlier, rejected: f > λ, or leading
    /// nowhere). Examples:
    ///
    ///   petrinav topo generate 50 -o office.fpn.json
    ///
    ///   petrinav topo plan office.fpn.json --from p1 --to p50
    ///
    ///   petrinav topo plan office.fpn.json --from p1 --to p50 --to p8 --mode paper --json
    Plan(PlanArgs),
    /// Converts a map, by the output's extension: .pnml (the place/transition net, for Petri
    /// net tools; the fuzzy values kept as tool-specific data), .dot (Graphviz; `neato` draws
    /// places at their odometry positions), .fpn.json or .json (the map file,
    /// rewritten).
    ///
    /// With --from and --to, the route planned between them is drawn in the DOT picture
    /// (thick; rejected transitions dashed, places labelled with α, transitions with f) or
    /// recorded in the PNML file (the start marked with a token). Examples:
    ///
    ///   petrinav topo convert office.fpn.json office.pnml
    ///
    ///   petrinav topo convert office.fpn.json route.dot --from p1 --to p50 && neato -Tsvg route.dot > route.svg
    Convert(ConvertArgs),
    /// Writes a random office-like map: places on a 2.5 m grid (jittered), transitions
    /// between near neighbours, every place reachable from every other, one transition in
    /// ten with a threshold lowered by failures (some rejected). The same arguments give
    /// the same map.
    ///
    ///   petrinav topo generate 10000 --transitions 40000 --seed 7 -o big.fpn.json
    Generate(GenerateArgs),
    /// Explores a world with the 16-sonar ring robot (sonars and odometry only) and writes
    /// the topological map it builds: every time an obstacle ahead makes it abandon its
    /// strategy it has found a reference place (type a: only a right turn possible, b: only
    /// left, c: both), recognised as a known one or added; the strategy that led there
    /// becomes a transition. The robot picks untried actions first, then goes where the map
    /// still has untried ones. Place recognition is judged against the simulator's true
    /// poses (precision, recall). Examples:
    ///
    ///   petrinav topo explore office --time 600 -o office.fpn.json --picture office.png
    ///
    ///   petrinav topo explore my_world.toml --start 1,1,0 --seed 3 -o my.fpn.json --json
    Explore(crate::topo_run::ExploreArgs),
    /// Drives a route on a map in the world it was made in: plan, play each transition's
    /// exit turn and strategy until the next reference place, recognise it, replan when it is
    /// not the one planned (the map learns: a transition that fails has its threshold λ
    /// lowered, places found are added). The robot starts at the start place's map pose;
    /// arrival is the goal recognised within 0.5 m of its map position. Examples:
    ///
    ///   petrinav topo go office office.fpn.json --from p3 --to p9 -o route.png
    ///
    ///   petrinav topo go office office.fpn.json --from p3 --to p9 --save-map learnt.fpn.json --json
    Go(crate::topo_run::GoArgs),
}

/// The route options of a subcommand that always plans.
#[derive(Args, Debug)]
pub struct RouteArgs {
    /// Where the robot is: a place's name.
    #[arg(long, value_name = "PLACE", allow_hyphen_values = true)]
    from: String,
    /// Where it goes: a place's name. Repeat for several goals; the route leads to the nearest.
    #[arg(
        long = "to",
        value_name = "PLACE",
        required = true,
        allow_hyphen_values = true
    )]
    to: Vec<String>,
    /// The stopping rule of the propagation.
    #[arg(long, value_enum, default_value_t = ModeArg::Optimal)]
    mode: ModeArg,
}

impl RouteArgs {
    fn route(&self) -> Route {
        Route {
            from: self.from.clone(),
            to: self.to.clone(),
            mode: self.mode.into(),
        }
    }
}

/// A route request: place names and the mode.
#[derive(Debug, Clone)]
pub struct Route {
    from: String,
    to: Vec<String>,
    mode: PlanMode,
}

#[derive(Args, Debug)]
pub struct PlanArgs {
    /// The map: a petrinav FPN map file (JSON).
    #[arg(value_name = "MAP.fpn.json")]
    map: PathBuf,
    #[command(flatten)]
    route: RouteArgs,
    /// Print JSON instead of tables (stable keys).
    #[arg(long)]
    json: bool,
}

#[derive(Args, Debug)]
pub struct ConvertArgs {
    /// The map: a petrinav FPN map file (JSON).
    #[arg(value_name = "MAP.fpn.json")]
    map: PathBuf,
    /// The output: .pnml, .dot, .fpn.json or .json.
    #[arg(value_name = "OUT")]
    output: PathBuf,
    /// Plan a route from this place and show it in the output (with --to).
    #[arg(long, value_name = "PLACE", requires = "to", allow_hyphen_values = true)]
    from: Option<String>,
    /// The route's goal; repeat for several (with --from).
    #[arg(
        long = "to",
        value_name = "PLACE",
        requires = "from",
        allow_hyphen_values = true
    )]
    to: Vec<String>,
    /// The stopping rule of the route's propagation [default: optimal].
    #[arg(long, value_enum, requires = "from")]
    mode: Option<ModeArg>,
    /// The PNML net's name [default: the map file's name without extensions].
    #[arg(long, value_name = "NAME")]
    name: Option<String>,
}

#[derive(Args, Debug)]
pub struct GenerateArgs {
    /// Number of places (1 to 1,000,000).
    #[arg(value_name = "N_PLACES")]
    places: usize,
    /// Number of transitions [default: 4 × N_PLACES]; at least 2 × (N_PLACES − 1), so that
    /// every place joins the others both ways.
    #[arg(long, value_name = "N")]
    transitions: Option<usize>,
    /// Seed of the random generator.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// The map file to write; standard output if absent.
    #[arg(short, long, value_name = "MAP.fpn.json")]
    output: Option<PathBuf>,
}

pub fn run(cmd: TopoCommand) -> Result<()> {
    match cmd {
        TopoCommand::Plan(a) => plan_cmd(&a),
        TopoCommand::Convert(a) => convert(&a),
        TopoCommand::Generate(a) => generate(&a),
        TopoCommand::Explore(a) => crate::topo_run::explore(&a),
        TopoCommand::Go(a) => crate::topo_run::go(&a),
    }
}

// ---------------------------------------------------------------------------
// Shared by the subcommands.
// ---------------------------------------------------------------------------

/// Plans `route` on `net` (the map read from `map`): place names checked,
/// and a missing route explained (whether one exists when thresholds are
/// ignored, and which thresholds stand in its way).
pub fn plan_route(planner: &Planner<'_>, route: &Route, map: &Path) -> Result<Plan> {
    let net = planner.net();
    let start = find_place(net, &route.from, "--from", map)?;
    let goals = route
        .to
        .iter()
        .map(|g| find_place(net, g, "--to", map))
        .collect::<Result<Vec<_>>>()?;
    match planner.plan(start, &goals, route.mode) {
        Ok(plan) => Ok(plan),
        Err(PlanError::NoRoute { .. }) => Err(explain_no_route(net, start, &goals, route.mode)),
        Err(e) => Err(e.into()),
    }
}

/// A "no route" error with the reason: no transitions lead there at all, or
/// thresholds reject every route (then the route that thresholds block, and
/// its transitions with lowered thresholds).
fn explain_no_route(net: &FuzzyPetriNet, start: PlaceId, goals: &[PlaceId], mode: PlanMode) -> anyhow::Error {
    let name = |p: PlaceId| net.place(p).name.as_str();
    let goal_names = goals
        .iter()
        .map(|&g| format!("`{}`", name(g)))
        .collect::<Vec<_>>()
        .join(", ");
    let mut open = net.clone();
    for t in net.transition_ids() {
        // λ = 1 is in range: cannot fail.
        let _ = open.set_lambda(t, 1.0);
    }
    match Planner::new(&open).plan(start, goals, mode) {
        Err(_) => {
            let reachable = reachable_from(net, start);
            anyhow!(
                "no route from `{}` to {goal_names}: no sequence of transitions leads there ({} of the map's {} places can be reached from `{}`)",
                name(start),
                reachable,
                net.num_places(),
                name(start)
            )
        }
        Ok(p) => {
            let lowered: Vec<String> = p
                .route
                .iter()
                .filter(|t| net.transition(**t).lambda < 1.0)
                .map(|&t| {
                    let tr = net.transition(t);
                    format!(
                        "{t} {} → {} (λ = {}, f = {})",
                        name(tr.from),
                        name(tr.to),
                        num(tr.lambda),
                        num(p.f[t.index()])
                    )
                })
                .collect();
            let path: Vec<&str> = p.places.iter().map(|&q| name(q)).collect();
            anyhow!(
                "no route from `{}` to {goal_names}: every route there takes a transition whose threshold rejects it (f > λ); ignoring thresholds the route would be {}, whose thresholds lowered by failures are: {}",
                name(start),
                path.join(" → "),
                lowered.join(", ")
            )
        }
    }
}

/// How many places can be reached from `start` along transitions (itself
/// included).
fn reachable_from(net: &FuzzyPetriNet, start: PlaceId) -> usize {
    let mut seen = vec![false; net.num_places()];
    let mut stack = vec![start];
    seen[start.index()] = true;
    let mut count = 1;
    while let Some(p) = stack.pop() {
        for &t in net.leaving(p) {
            let q = net.transition(t).to;
            if !std::mem::replace(&mut seen[q.index()], true) {
                count += 1;
                stack.push(q);
            }
        }
    }
    count
}

/// Why a transition leaving a place of the route was not taken.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Status {
    /// On the route.
    Taken,
    /// Accepted, with a larger `f` than the one taken.
    Costlier,
    /// Accepted, with the same `f` as the one taken and a larger id.
    Tie,
    /// `min(1, C(t) + α(p_j)) > λ(t)`.
    Rejected,
    /// Its destination leads to no goal (paper mode: not when the
    /// propagation stopped).
    Unreached,
}

impl Status {
    fn name(self) -> &'static str {
        match self {
            Status::Taken => "taken",
            Status::Costlier => "costlier",
            Status::Tie => "tie",
            Status::Rejected => "rejected",
            Status::Unreached => "unreached",
        }
    }
}

/// `min(1, C(t) + α(p_j))` with the plan's `α`, before thresholding; `None`
/// when the destination is unreached.
fn composed(net: &FuzzyPetriNet, plan: &Plan, t: TransitionId) -> Option<f64> {
    let to = net.transition(t).to.index();
    plan.reached[to].then(|| (net.weighted_cost(t) + plan.alpha[to]).min(1.0))
}

fn status(net: &FuzzyPetriNet, plan: &Plan, t: TransitionId, taken: Option<TransitionId>) -> Status {
    if taken == Some(t) {
        return Status::Taken;
    }
    if plan.accepted[t.index()] {
        let best = taken.map_or(f64::INFINITY, |b| plan.f[b.index()]);
        return if plan.f[t.index()] == best {
            Status::Tie
        } else {
            Status::Costlier
        };
    }
    match composed(net, plan, t) {
        Some(v) if v > net.transition(t).lambda => Status::Rejected,
        _ => Status::Unreached,
    }
}

/// The transitions leaving the route's places that the route does not take,
/// place by place along the route (the goal's excluded), by id.
fn alternatives(net: &FuzzyPetriNet, plan: &Plan) -> Vec<(TransitionId, Status)> {
    let mut out = Vec::new();
    for (k, &t_taken) in plan.route.iter().enumerate() {
        let at = plan.places[k];
        for &t in net.leaving(at) {
            if t != t_taken {
                out.push((t, status(net, plan, t, Some(t_taken))));
            }
        }
    }
    out
}

/// `1 transition`, `2 transitions`.
fn transitions(n: usize) -> String {
    if n == 1 {
        "1 transition".into()
    } else {
        format!("{n} transitions")
    }
}

fn mode_words(mode: PlanMode) -> &'static str {
    match mode {
        PlanMode::Optimal => "optimal (to the fixed point: the cheapest route)",
        PlanMode::Paper => "paper (stopped when the start got a value: the fewest transitions)",
    }
}

/// The plan as JSON (stable keys; see [`print_plan`]).
pub fn plan_json(net: &FuzzyPetriNet, plan: &Plan, map: &Path) -> Value {
    let name = |p: PlaceId| net.place(p).name.clone();
    let transition = |t: TransitionId| {
        let tr = net.transition(t);
        json!({
            "transition": t.to_string(),
            "from": name(tr.from),
            "to": name(tr.to),
            "strategy": tr.strategy.name(),
            "exit_turn": tr.exit_turn.name(),
            "duration_s": tr.duration_s,
            "cost": tr.cost,
            "weighted_cost": net.weighted_cost(t),
            "f": plan.f[t.index()],
            "lambda": tr.lambda,
        })
    };
    let route: Vec<Value> = plan
        .route
        .iter()
        .enumerate()
        .map(|(k, &t)| {
            let mut v = transition(t);
            v["step"] = json!(k + 1);
            v
        })
        .collect();
    let places: Vec<Value> = plan
        .places
        .iter()
        .map(|&p| {
            let q = net.place(p);
            json!({
                "name": q.name,
                "kind": q.kind.letter(),
                "x_m": q.x_m,
                "y_m": q.y_m,
                "alpha": plan.alpha[p.index()],
            })
        })
        .collect();
    let alternatives: Vec<Value> = alternatives(net, plan)
        .into_iter()
        .map(|(t, s)| {
            let mut v = transition(t);
            v["status"] = json!(s.name());
            v["composed"] = json!(composed(net, plan, t));
            v
        })
        .collect();
    json!({
        "map": map.display().to_string(),
        "mode": plan.mode.name(),
        "from": name(plan.start),
        "goals": plan.goals.iter().map(|&g| name(g)).collect::<Vec<_>>(),
        "goal": name(plan.goal()),
        "cost": plan.cost,
        "alpha_start": plan.alpha[plan.start.index()],
        "iterations": plan.iterations,
        "places": places,
        "route": route,
        "alternatives": alternatives,
    })
}

/// Prints a plan: a summary, the route, the table of its transitions and the
/// alternatives at its places; or [`plan_json`].
pub fn print_plan(net: &FuzzyPetriNet, plan: &Plan, map: &Path, json: bool) -> Result<()> {
    if json {
        outln!("{}", serde_json::to_string_pretty(&plan_json(net, plan, map))?)?;
        return Ok(());
    }
    out!("{}", plan_summary(net, plan, map))?;
    if plan.route.is_empty() {
        outln!("\nthe start is a goal: nothing to do")?;
        return Ok(());
    }
    outln!("\n{}", route_table(net, plan).trim_end())?;
    let others = alternatives(net, plan);
    if others.is_empty() {
        outln!("\nno other transition leaves the route's places")?;
        return Ok(());
    }
    outln!(
        "\nthe other transitions leaving the route's places:\n{}",
        alternatives_table(net, plan, others).trim_end()
    )?;
    Ok(())
}

/// A plan's summary: the map, the mode, the start and goals, the cost, the
/// start's value, the propagation's length and the route.
fn plan_summary(net: &FuzzyPetriNet, plan: &Plan, map: &Path) -> String {
    let name = |p: PlaceId| net.place(p).name.as_str();
    let mut path = vec![name(plan.start).to_string()];
    for &t in &plan.route {
        path.push(t.to_string());
        path.push(name(net.transition(t).to).to_string());
    }
    let goals: Vec<&str> = plan.goals.iter().map(|&g| name(g)).collect();
    let goal = if plan.goals.len() > 1 {
        format!("{} (the nearest)", name(plan.goal()))
    } else {
        name(plan.goal()).to_string()
    };
    let iterations = match plan.mode {
        PlanMode::Optimal => format!("{} places settled", plan.iterations),
        PlanMode::Paper if plan.iterations == 1 => "1 round".to_string(),
        PlanMode::Paper => format!("{} rounds", plan.iterations),
    };
    fields(&[
        (
            "map",
            format!(
                "{} ({} places, {} transitions)",
                map.display(),
                net.num_places(),
                net.num_transitions()
            ),
        ),
        ("mode", mode_words(plan.mode).to_string()),
        ("from", name(plan.start).to_string()),
        ("to", goals.join(", ")),
        ("goal", goal),
        ("cost", format!("{}  (Σ C(t) along the route)", num(plan.cost))),
        (
            "α(from)",
            format!(
                "{}  ({})",
                num(plan.alpha[plan.start.index()]),
                match plan.mode {
                    PlanMode::Optimal => "the start's value: the cost",
                    PlanMode::Paper =>
                        "the start's value when the propagation stopped; f(t) below are of the last round",
                }
            ),
        ),
        ("propagation", iterations),
        (
            "route",
            format!("{}  ({})", path.join(" → "), transitions(plan.route.len())),
        ),
    ])
}

/// The table of a plan's route: per transition its places, strategy, exit
/// turn, cost, f, λ and the value of where it leads.
fn route_table(net: &FuzzyPetriNet, plan: &Plan) -> String {
    let name = |p: PlaceId| net.place(p).name.as_str();
    let mut t = Table::new([
        "step",
        "transition",
        "from",
        "to",
        "strategy",
        "exit turn",
        "C(t)",
        "f(t)",
        "λ(t)",
        "α(to)",
    ]);
    for (k, &id) in plan.route.iter().enumerate() {
        let tr = net.transition(id);
        t.row([
            (k + 1).to_string(),
            id.to_string(),
            name(tr.from).to_string(),
            name(tr.to).to_string(),
            tr.strategy.label().to_string(),
            tr.exit_turn.name().to_string(),
            num(net.weighted_cost(id)),
            num(plan.f[id.index()]),
            num(tr.lambda),
            num(plan.alpha[tr.to.index()]),
        ]);
    }
    t.render()
}

/// The table of the transitions `others` leaving the route's places, with
/// why each was not taken.
fn alternatives_table(net: &FuzzyPetriNet, plan: &Plan, others: Vec<(TransitionId, Status)>) -> String {
    let name = |p: PlaceId| net.place(p).name.as_str();
    let mut t = Table::new([
        "transition",
        "from",
        "to",
        "strategy",
        "C(t)",
        "f(t)",
        "λ(t)",
        "not taken",
    ]);
    for (id, s) in others {
        let tr = net.transition(id);
        let why = match s {
            Status::Rejected => format!(
                "rejected: min(1, C + α({})) = {} > λ",
                name(tr.to),
                num(composed(net, plan, id).unwrap_or(1.0))
            ),
            Status::Unreached => match plan.mode {
                PlanMode::Optimal => format!("unreached: no route on from {}", name(tr.to)),
                PlanMode::Paper => format!("unreached: {} had no value yet", name(tr.to)),
            },
            Status::Tie => "tie (the smaller id is taken)".to_string(),
            other => other.name().to_string(),
        };
        t.row([
            id.to_string(),
            name(tr.from).to_string(),
            name(tr.to).to_string(),
            tr.strategy.label().to_string(),
            num(net.weighted_cost(id)),
            num(plan.f[id.index()]),
            num(tr.lambda),
            why,
        ]);
    }
    t.render()
}

// ---------------------------------------------------------------------------
// The subcommands.
// ---------------------------------------------------------------------------

fn plan_cmd(a: &PlanArgs) -> Result<()> {
    let net = load_map(&a.map)?;
    let planner = Planner::new(&net);
    let plan = plan_route(&planner, &a.route.route(), &a.map)?;
    print_plan(&net, &plan, &a.map, a.json)
}

/// What `convert` writes, by the output's extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum OutFormat {
    Pnml,
    Dot,
    Json,
}

fn out_format(path: &Path) -> Result<OutFormat> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("pnml") => Ok(OutFormat::Pnml),
        Some("dot" | "gv") => Ok(OutFormat::Dot),
        Some("json") => Ok(OutFormat::Json),
        Some(other) => bail!(
            "{}: unknown extension `.{other}`: expected .pnml, .dot or .fpn.json",
            path.display()
        ),
        None => bail!(
            "{}: no extension to choose the format by: expected .pnml, .dot or .fpn.json",
            path.display()
        ),
    }
}

/// The file name without its extensions (`office` for `office.fpn.json`).
fn stem(path: &Path) -> String {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    match name.split('.').next() {
        Some(s) if !s.is_empty() => s.to_string(),
        _ => "fpn".to_string(),
    }
}

fn convert(a: &ConvertArgs) -> Result<()> {
    let format = out_format(&a.output)?;
    let net = load_map(&a.map)?;
    let plan = match &a.from {
        Some(from) => {
            if format == OutFormat::Json {
                bail!(
                    "--from/--to show a route in a .dot or .pnml output; a map file has no route (use `petrinav topo plan`)"
                );
            }
            let route = Route {
                from: from.clone(),
                to: a.to.clone(),
                mode: a.mode.unwrap_or_default().into(),
            };
            Some(plan_route(&Planner::new(&net), &route, &a.map)?)
        }
        None => None,
    };
    if a.name.is_some() && format != OutFormat::Pnml {
        bail!("--name names the net of a .pnml output");
    }
    let text = match format {
        OutFormat::Pnml => {
            let name = a.name.clone().unwrap_or_else(|| stem(&a.map));
            to_pnml(&net, &name, plan.as_ref().map(|p| p.start), plan.as_ref())?
        }
        OutFormat::Dot => to_dot(&net, plan.as_ref())?,
        OutFormat::Json => net.to_json(),
    };
    std::fs::write(&a.output, text).with_context(|| format!("writing {}", a.output.display()))?;
    let route = plan.map_or_else(String::new, |p| {
        format!(
            ", with the route {} → {} ({})",
            net.place(p.start).name,
            net.place(p.goal()).name,
            transitions(p.route.len())
        )
    });
    eprintln!(
        "{} -> {}: {} places, {} transitions{route}",
        a.map.display(),
        a.output.display(),
        net.num_places(),
        net.num_transitions()
    );
    Ok(())
}

fn generate(a: &GenerateArgs) -> Result<()> {
    let transitions = match a.transitions {
        Some(n) => n,
        None => a
            .places
            .checked_mul(4)
            .ok_or_else(|| anyhow!("N_PLACES {}: too many places", a.places))?,
    };
    let net = random_office_like(a.places, transitions, a.seed).map_err(|e| anyhow!("{e}"))?;
    match &a.output {
        Some(path) => {
            net.save(path).map_err(|e| anyhow!("{e}"))?;
            let lowered = net.transitions().iter().filter(|t| t.lambda < 1.0).count();
            eprintln!(
                "{}: {} places, {} transitions ({lowered} with a threshold λ < 1), seed {}",
                path.display(),
                net.num_places(),
                net.num_transitions(),
                a.seed
            );
        }
        None => out!("{}", net.to_json())?,
    }
    Ok(())
}
