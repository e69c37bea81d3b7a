//! The work behind `petrinav gspn …`, shared by the command line and the
//! Python package (`crates/py`): loading a net with parameter assignments,
//! the steady-state pipeline, the behavioural and structural report,
//! simulation, the supervisor's decision — each with the command line's
//! error messages and its JSON objects, so that both front ends say and
//! print the same.
//!
//! ```
//! use lab::gspn::{self, SolveOptions};
//!
//! let net = petri::families::kanban(1);
//! let gspn = gspn::instantiate(&net, &["N=2"])?;
//! let steady = gspn::solve(&gspn, &SolveOptions::default(), petri::Interrupt::NEVER, &mut |_| {})?;
//! assert_eq!(steady.space.compiled.num_tangible(), 4600);
//! let busy = steady.measure(&petri::Expr::parse("#Pm1 >= 1")?)?;
//! assert!(busy > 0.0 && busy < 1.0);
//! # Ok::<(), anyhow::Error>(())
//! ```

use std::collections::BTreeMap;
use std::ops::ControlFlow;
use std::path::Path;
use std::sync::Arc;

use anyhow::{Context, Result, bail};
use guide::supervisor::credit::{CreditDecision, CreditRates, CreditSupervisor, NUM_CREDIT_RATES};
use guide::supervisor::{Decision, Rates, Supervisor};
use petri::{
    CompiledGspn, ExploreParams, Expr, FarkasParams, Gspn, Interrupt, Invariants, Net, Params, Properties,
    ReachabilityGraph, SimParams, SimProgress, SimResult, Solution, SolveParams,
};
use serde_json::{Value, json};

/// Reads a net file in the format its extension says (`.pnpro`, `.pnml`,
/// `.toml`); errors begin `loading FILE: `.
pub fn read_net(path: &Path) -> Result<Net> {
    read_net_within(path, None)
}

/// [`read_net`] within `max_memory` bytes (`--max-memory`; default the
/// memory guard's, [`petri::default_max_memory`]): a file too large to
/// read within it is refused before it is read.
pub fn read_net_within(path: &Path, max_memory: Option<u64>) -> Result<Net> {
    let limit = max_memory.unwrap_or_else(petri::default_max_memory);
    petri::io::read_file_within(path, limit).with_context(|| format!("loading {}", path.display()))
}

/// Writes a net in the format the file's extension says; errors begin
/// `writing FILE: `.
pub fn write_net(net: &Net, path: &Path) -> Result<()> {
    petri::io::write_file(net, path).with_context(|| format!("writing {}", path.display()))
}

/// Binds parameters given as `NAME=VALUE` assignments (the value may be an
/// expression over numbers, e.g. `lambda=1/3`), as `--param` does.
pub fn instantiate<S: AsRef<str>>(net: &Net, assignments: &[S]) -> Result<Gspn> {
    let params = Params::parse_assignments(assignments)?;
    Ok(net.instantiate(&params)?)
}

/// [`read_net`] then [`instantiate`].
pub fn load<S: AsRef<str>>(path: &Path, assignments: &[S]) -> Result<(Net, Gspn)> {
    load_within(path, assignments, None)
}

/// [`read_net_within`] then [`instantiate`].
pub fn load_within<S: AsRef<str>>(
    path: &Path,
    assignments: &[S],
    max_memory: Option<u64>,
) -> Result<(Net, Gspn)> {
    let net = read_net_within(path, max_memory)?;
    let gspn = instantiate(&net, assignments)?;
    Ok((net, gspn))
}

/// A measure that does not parse or cannot be evaluated: its text, and
/// why (displayed as `measure `TEXT`: …`).
#[derive(Debug, thiserror::Error)]
#[error("measure `{text}`")]
pub struct MeasureError {
    /// The measure as written (after parsing, as the parser prints it).
    pub text: String,
    /// What is wrong (boxed: the engine's errors carry file positions and
    /// names, and a measure's result stays small).
    #[source]
    pub source: Box<petri::Error>,
}

/// Parses measure expressions (`#P1 = 1 and #P7 = 1`, `#P1 + 2 * #P2`).
pub fn parse_measures<S: AsRef<str>>(texts: &[S]) -> Result<Vec<Expr>> {
    texts.iter().map(|t| Ok(parse_measure(t.as_ref())?)).collect()
}

/// Parses one measure expression.
pub fn parse_measure(text: &str) -> std::result::Result<Expr, MeasureError> {
    Expr::parse(text).map_err(|source| MeasureError {
        text: text.to_string(),
        source: Box::new(source),
    })
}

/// How to generate, compile and solve (the options of `gspn solve`).
#[derive(Debug, Clone, Default)]
pub struct SolveOptions {
    /// State-space limits (`--max-states`, `--max-memory`).
    pub explore: ExploreParams,
    /// Method and tolerance (`--method`, `--tolerance`); the default,
    /// [`petri::Method::Auto`], chooses as the command line does.
    pub solve: SolveParams,
    /// Rate of every timed transition without one (`--default-rate`).
    pub default_rate: Option<f64>,
}

/// A net's state space: its CTMC over the tangible markings, compiled
/// once and solvable for any rates.
#[derive(Debug, Clone)]
pub struct StateSpace {
    /// The CTMC over the tangible markings.
    pub compiled: CompiledGspn,
    /// Markings of the reachability graph, tangible and vanishing.
    pub reachable_markings: usize,
    /// Vanishing markings eliminated.
    pub vanishing_markings: usize,
}

/// A solved net: its state space and its long-run solution.
#[derive(Debug, Clone)]
pub struct SteadyState {
    /// The state space solved.
    pub space: Arc<StateSpace>,
    /// Its long-run solution.
    pub solution: Solution,
}

/// Generates the reachability graph (`stop` interrupts it).
pub fn explore(gspn: &Gspn, params: &ExploreParams, stop: Interrupt<'_>) -> Result<ReachabilityGraph> {
    Ok(ReachabilityGraph::explore_interruptible(gspn, params, stop)?)
}

/// Generates the reachability graph and compiles the CTMC; `phase` is told
/// each stage as it starts ("generating the reachability graph",
/// "eliminating vanishing markings"); `stop` interrupts either
/// ([`petri::interrupt`]).
pub fn state_space(
    gspn: &Gspn,
    params: &ExploreParams,
    stop: Interrupt<'_>,
    phase: &mut dyn FnMut(&'static str),
) -> Result<StateSpace> {
    phase("generating the reachability graph");
    let rg = explore(gspn, params, stop)?;
    let (reachable_markings, vanishing_markings) = (rg.num_markings(), rg.num_vanishing());
    phase("eliminating vanishing markings");
    let compiled = CompiledGspn::from_graph_interruptible(gspn.clone(), rg, stop)?;
    Ok(StateSpace {
        compiled,
        reachable_markings,
        vanishing_markings,
    })
}

/// The rates of the timed transitions, as `gspn solve` checks them before
/// generating anything (`default_rate` for those without one).
pub fn rates(gspn: &Gspn, default_rate: Option<f64>) -> Result<Vec<f64>> {
    Ok(gspn.rates(&Params::new(), default_rate)?)
}

/// `gspn solve`: the rates are checked before the state space is generated,
/// then the graph, the CTMC ([`state_space`]) and its steady state
/// ([`SteadyState::solve`]); `phase` is told each stage as it starts,
/// `stop` interrupts any of them.
pub fn solve(
    gspn: &Gspn,
    options: &SolveOptions,
    stop: Interrupt<'_>,
    phase: &mut dyn FnMut(&'static str),
) -> Result<SteadyState> {
    let rates = rates(gspn, options.default_rate)?;
    let space = Arc::new(state_space(gspn, &options.explore, stop, phase)?);
    SteadyState::solve(space, &rates, &options.solve, stop, phase)
}

impl SteadyState {
    /// Solves `space` for `rates` (indexed by transition; see [`rates`]);
    /// `phase` is told "solving the steady state".
    pub fn solve(
        space: Arc<StateSpace>,
        rates: &[f64],
        params: &SolveParams,
        stop: Interrupt<'_>,
        phase: &mut dyn FnMut(&'static str),
    ) -> Result<SteadyState> {
        phase("solving the steady state");
        let solution = space.compiled.solve_rates_interruptible(rates, params, stop)?;
        Ok(SteadyState { space, solution })
    }

    /// The long-run value of a measure: the probability of a condition, the
    /// mean of an arithmetic expression. Errors (a place the net does not
    /// have…) are [`MeasureError`]s.
    pub fn measure(&self, expr: &Expr) -> std::result::Result<f64, MeasureError> {
        self.space
            .compiled
            .measure(&self.solution, expr)
            .map_err(|source| MeasureError {
                text: expr.to_string(),
                source: Box::new(source),
            })
    }

    /// [`measure`](Self::measure) of each.
    pub fn measures(&self, exprs: &[Expr]) -> Result<Vec<f64>> {
        exprs.iter().map(|m| Ok(self.measure(m)?)).collect()
    }

    /// Where the memory went ([`CompiledGspn::memory_account`]) and the
    /// process's peak resident memory (`gspn solve --stats`).
    pub fn memory(&self) -> MemoryReport {
        MemoryReport {
            account: self.space.compiled.memory_account(Some(&self.solution)),
            peak_rss_bytes: peak_rss_bytes(),
        }
    }

    /// The object `gspn solve --json` prints; `measures` pairs each measure
    /// as the user wrote it with its value.
    pub fn to_json(&self, measures: &[(String, f64)]) -> Value {
        let space = &self.space;
        let gspn = space.compiled.gspn();
        let sol = &self.solution;
        let (places, transitions, ms) = nodes_json(
            gspn,
            &sol.prob_nonempty,
            &sol.mean_tokens,
            &sol.throughput,
            measures,
        );
        json!({
            "name": gspn.name(),
            "reachable_markings": space.reachable_markings,
            "tangible_markings": space.compiled.num_tangible(),
            "vanishing_markings": space.vanishing_markings,
            "ergodic": space.compiled.is_ergodic(),
            "bottom_components": sol.bottom_probabilities.len(),
            "solver": sol.info.method,
            "iterations": sol.info.iterations,
            "residual": sol.info.residual,
            "seconds": sol.info.seconds,
            "places": places,
            "transitions": transitions,
            "measures": ms,
        })
    }
}

/// The `places`, `transitions` and `measures` objects of `gspn solve
/// --json`, from a solution's vectors (either engine's).
pub(crate) fn nodes_json(
    gspn: &Gspn,
    prob_nonempty: &[f64],
    mean_tokens: &[f64],
    throughput: &[f64],
    measures: &[(String, f64)],
) -> (Value, Value, Value) {
    let places: BTreeMap<&str, Value> = gspn
        .place_names()
        .iter()
        .enumerate()
        .map(|(p, n)| {
            (
                n.as_str(),
                json!({"prob_nonempty": prob_nonempty[p], "mean_tokens": mean_tokens[p]}),
            )
        })
        .collect();
    let transitions: BTreeMap<&str, Value> = gspn
        .transition_names()
        .iter()
        .enumerate()
        .map(|(t, n)| {
            (
                n.as_str(),
                json!({"throughput": throughput[t], "immediate": gspn.is_immediate(petri::TransitionId(t as u32))}),
            )
        })
        .collect();
    let ms: BTreeMap<&str, f64> = measures.iter().map(|(m, v)| (m.as_str(), *v)).collect();
    (json!(places), json!(transitions), json!(ms))
}

/// The byte account of a solve and the process's peak resident memory.
#[derive(Debug, Clone, serde::Serialize)]
pub struct MemoryReport {
    /// Bytes per component, from the allocations' capacities.
    #[serde(flatten)]
    pub account: petri::MemoryAccount,
    /// Peak resident memory of the process (`VmHWM`), if it can be read.
    pub peak_rss_bytes: Option<u64>,
}

impl MemoryReport {
    /// `peak_rss_bytes` per tangible marking.
    pub fn peak_rss_per_marking(&self) -> Option<f64> {
        self.peak_rss_bytes
            .map(|b| b as f64 / self.account.tangible_markings.max(1) as f64)
    }
}

/// Peak resident memory of this process (`VmHWM` in `/proc/self/status`),
/// in bytes; `None` where it cannot be read (not Linux).
pub fn peak_rss_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let kib = status
        .lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))?
        .trim()
        .trim_end_matches("kB")
        .trim()
        .parse::<u64>()
        .ok()?;
    Some(kib * 1024)
}

/// What `gspn info` reports: the reachability graph, behavioural
/// properties, minimal P- and T-invariants (or why they were not computed).
#[derive(Debug)]
pub struct Analysis {
    /// The reachability graph.
    pub graph: ReachabilityGraph,
    /// Bounds, dead markings and transitions, liveness, reversibility…
    pub properties: Properties,
    /// Minimal P-invariants.
    pub p_invariants: petri::Result<Invariants>,
    /// Minimal T-invariants.
    pub t_invariants: petri::Result<Invariants>,
}

/// `gspn info`: the graph, then properties, then invariants (`phase` is
/// told each stage; `stop` interrupts the graph's generation).
pub fn analyse(
    gspn: &Gspn,
    params: &ExploreParams,
    stop: Interrupt<'_>,
    phase: &mut dyn FnMut(&'static str),
) -> Result<Analysis> {
    phase("generating the reachability graph");
    let graph = explore(gspn, params, stop)?;
    phase("behavioural properties");
    let properties = Properties::of(gspn, &graph);
    phase("invariants");
    let p_invariants = petri::p_invariants(gspn, &FarkasParams::default());
    let t_invariants = petri::t_invariants(gspn, &FarkasParams::default());
    Ok(Analysis {
        graph,
        properties,
        p_invariants,
        t_invariants,
    })
}

impl Analysis {
    /// Structural bounds from the P-invariants, if they were computed.
    pub fn structural_bounds(&self, gspn: &Gspn) -> Option<Vec<Option<u64>>> {
        self.p_invariants
            .as_ref()
            .ok()
            .map(|i| petri::structural_bounds(gspn, i))
    }

    /// The object `gspn info --json` prints.
    pub fn to_json(&self, net: &Net, gspn: &Gspn) -> Value {
        let (rg, props) = (&self.graph, &self.properties);
        let places = gspn.place_names();
        let trans = gspn.transition_names();
        let tnames =
            |ts: &[petri::TransitionId]| ts.iter().map(|t| trans[t.index()].clone()).collect::<Vec<_>>();
        let st = rg.stats();
        let inv_json = |inv: &petri::Result<Invariants>| match inv {
            Ok(i) => json!(
                (0..i.len())
                    .filter_map(|k| i.display_vector(k, gspn).map(|d| d.to_string()))
                    .collect::<Vec<_>>()
            ),
            Err(e) => json!({ "error": e.to_string() }),
        };
        let (pinv, tinv) = (&self.p_invariants, &self.t_invariants);
        let structural = self.structural_bounds(gspn);
        let bounds: BTreeMap<&str, u32> = places
            .iter()
            .map(String::as_str)
            .zip(props.bounds.iter().copied())
            .collect();
        let mutex = props.mutually_exclusive.as_ref().map(|pairs| {
            pairs
                .iter()
                .map(|(p, q)| json!([places[p.index()], places[q.index()]]))
                .collect::<Vec<_>>()
        });
        json!({
            "name": gspn.name(),
            "places": gspn.num_places(),
            "transitions": gspn.num_transitions(),
            "immediate_transitions": gspn.num_immediate(),
            "arcs": net.arcs.len(),
            "reachable_markings": rg.num_markings(),
            "tangible_markings": rg.num_tangible(),
            "vanishing_markings": rg.num_vanishing(),
            "edges": rg.num_edges(),
            "dead_markings": props.dead_markings.len(),
            "bounded": true,
            "safe": props.safe,
            "live": props.live,
            "reversible": props.reversible,
            "terminal_components": props.terminal_components,
            "bounds": bounds,
            "dead_transitions": tnames(&props.dead_transitions),
            "live_transitions": tnames(&props.live_transitions),
            "mutually_exclusive": mutex,
            "p_invariants": inv_json(pinv),
            "t_invariants": inv_json(tinv),
            "covered_by_p_invariants": pinv.as_ref().ok().map(|i| i.covers_all()),
            "covered_by_t_invariants": tinv.as_ref().ok().map(|i| i.covers_all()),
            "structurally_bounded": pinv.as_ref().ok().map(|i| i.covers_all()),
            "structural_bounds": structural.as_ref().map(|b| places.iter().zip(b).map(|(p, v)| (p.clone(), json!(v))).collect::<BTreeMap<_, _>>()),
            "generation": { "seconds": st.seconds, "bytes_per_marking": st.bytes_per_marking, "words_per_marking": st.words_per_marking },
        })
    }
}

/// The options of `gspn simulate`.
#[derive(Debug, Clone)]
pub struct SimOptions {
    /// Simulated time per run (`--time`).
    pub time: f64,
    /// Seed (`--seed`).
    pub seed: u64,
    /// Simulated time discarded at the start (`--warmup`, default 0).
    pub warmup: f64,
    /// Batches of the batch-means intervals (`--batches`, default 20).
    pub batches: usize,
    /// Confidence level (`--confidence`, default 0.95).
    pub confidence: f64,
    /// Rate of every timed transition without one (`--default-rate`).
    pub default_rate: Option<f64>,
    /// Measure expressions, as written (`--measure`).
    pub measures: Vec<String>,
    /// Cap on firings, all runs (`--max-events`, default 10⁹).
    pub max_events: u64,
    /// Wall-clock budget in seconds, `None` for none (`--max-wall`,
    /// default 600).
    pub max_wall_s: Option<f64>,
}

impl SimOptions {
    /// The command line's defaults for a run of `time` with `seed`.
    pub fn new(time: f64, seed: u64) -> SimOptions {
        SimOptions {
            time,
            seed,
            warmup: 0.0,
            batches: 20,
            confidence: 0.95,
            default_rate: None,
            measures: Vec::new(),
            max_events: 1_000_000_000,
            max_wall_s: Some(600.0),
        }
    }
}

/// A simulation error with the command line's hint on the option that
/// raises the limit (`--max-events`, `--max-wall`); displayed as the error
/// followed by the hint.
#[derive(Debug, thiserror::Error)]
#[error("{error}{hint}")]
pub struct SimulationError {
    /// What the engine said.
    pub error: petri::Error,
    /// The hint (empty when there is none).
    pub hint: &'static str,
}

/// `gspn simulate`: rates and measures checked, then the simulation;
/// `observer` sees its progress and may stop it ([`petri::simulate_observed`]).
pub fn simulate(
    gspn: &Gspn,
    options: &SimOptions,
    observer: &mut dyn FnMut(&SimProgress) -> ControlFlow<()>,
) -> Result<SimResult> {
    let rates = gspn.rates(&Params::new(), options.default_rate)?;
    let measures = parse_measures(&options.measures)?
        .iter()
        .zip(&options.measures)
        .map(|(e, t)| Ok((t.clone(), gspn.compile_expr(e)?)))
        .collect::<Result<Vec<_>>>()?;
    let mut p = SimParams::new(options.time);
    p.seed = options.seed;
    p.warmup = options.warmup;
    p.batches = options.batches;
    p.confidence = options.confidence;
    p.max_events = options.max_events;
    p.max_wall_s = options.max_wall_s;
    petri::simulate_observed(gspn, &rates, &measures, &p, observer).map_err(|error| {
        let hint = match error {
            petri::Error::EventLimit { .. } => " (--max-events N raises the limit)",
            petri::Error::WallTimeLimit { .. } => " (--max-wall S raises the limit)",
            _ => "",
        };
        SimulationError { error, hint }.into()
    })
}

/// What `gspn select` decided ([`select`]), and with which supervisor.
#[derive(Debug, Clone)]
pub enum Selection {
    /// The source's supervisor (`models/supervisor.toml` or a net of its
    /// structure).
    Source {
        /// The decision.
        decision: Decision,
        /// The rates used.
        rates: Rates,
    },
    /// The crediting supervisor (`models/supervisor_credit.toml` or a net
    /// of its structure: it has the transition `t15`).
    Credit {
        /// The decision.
        decision: CreditDecision,
        /// The rates used.
        rates: CreditRates,
        /// Decided while localized (Success), or lost (Warning).
        localized: bool,
    },
}

impl Selection {
    /// The `--json` object: the source's decision as it always was; the
    /// crediting one with `"supervisor": "credit"` and `"localized"`.
    pub fn to_json(&self) -> Result<Value> {
        Ok(match self {
            Selection::Source { decision, .. } => serde_json::to_value(decision)?,
            Selection::Credit {
                decision, localized, ..
            } => {
                let mut v = serde_json::to_value(decision)?;
                if let Some(o) = v.as_object_mut() {
                    o.insert("supervisor".into(), "credit".into());
                    o.insert("localized".into(), (*localized).into());
                }
                v
            }
        })
    }
}

/// The index `N` of a rate named `lambdaN` (1 ≤ N ≤ `count`), or an error
/// naming the name given and the closest valid one.
fn rate_index(name: &str, count: usize) -> Result<usize> {
    let index = name
        .strip_prefix("lambda")
        .filter(|k| !k.starts_with('0'))
        .and_then(|k| k.parse::<usize>().ok());
    match index {
        Some(k) if (1..=count).contains(&k) => Ok(k),
        Some(k) => bail!(
            "unknown rate `{name}`: λ{k} is not one of this supervisor's rates, lambda1 … lambda{count}"
        ),
        None => {
            let known: Vec<String> = (1..=count).map(|k| format!("lambda{k}")).collect();
            let known: Vec<&str> = known.iter().map(String::as_str).collect();
            let hint =
                petri::closest(name, &known).map_or(String::new(), |c| format!(" (did you mean `{c}`?)"));
            bail!("unknown rate `{name}`{hint}: this supervisor's rates are lambda1 … lambda{count}")
        }
    }
}

/// `gspn select`: the supervisor's decision for rates set as
/// `lambdaN=VALUE` assignments (the others at the supervisor's initial
/// values), on the shipped source's supervisor net or on `model` — a net
/// of the source's structure, or of the crediting supervisor's (it has the
/// transition `t15`, as `models/supervisor_credit.toml`), which decides
/// `localized` or lost (the source's decides only while localized).
pub fn select<S: AsRef<str>>(set: &[S], model: Option<&Path>, localized: bool) -> Result<Selection> {
    let net = model.map(read_net).transpose()?;
    let assignments = Params::parse_assignments(set)?.0;
    let of_model = || {
        format!(
            "the supervisor net of {}",
            model.unwrap_or(Path::new("")).display()
        )
    };
    if let Some(net) = net.as_ref().filter(|n| n.transition_id("t15").is_some()) {
        let supervisor = CreditSupervisor::from_net(net).with_context(of_model)?;
        let mut rates = CreditRates::initial();
        for (name, value) in assignments {
            rates.try_set(rate_index(&name, NUM_CREDIT_RATES)?, value)?;
        }
        let decision = supervisor.decide(&rates, localized)?;
        return Ok(Selection::Credit {
            decision,
            rates,
            localized,
        });
    }
    if !localized {
        bail!(
            "--lost: the source's supervisor decides only while localized (at the start and on returns to Success); the crediting net (models/supervisor_credit.toml) decides lost too"
        );
    }
    let supervisor = match &net {
        None => Supervisor::new()?,
        Some(net) => Supervisor::from_net(net).with_context(of_model)?,
    };
    let mut rates = Rates::initial();
    for (name, value) in assignments {
        rates.try_set(rate_index(&name, guide::supervisor::NUM_RATES)?, value)?;
    }
    let decision = supervisor.decide(&rates)?;
    Ok(Selection::Source { decision, rates })
}
