//! `petrinav.Net`, its state space and its steady-state solution.

use std::path::PathBuf;
use std::sync::{Arc, Mutex};

use lab::gspn::{self as work, SimOptions, SteadyState};
use lab::optimize::{OptimizeOptions, Problem};
use numpy::prelude::*;
use numpy::{PyArray1, PyArray2};
use petri::io::Format;
use petri::{ExploreParams, Interrupt, Method, SolveParams};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::convert::{assignments, json_to_py};
use crate::errors::Kind;
use crate::optimize;
use crate::run::{detached, guarded};

/// A place of a net: its name, initial token count and capacity.
#[pyclass(module = "petrinav", frozen, get_all)]
pub(crate) struct Place {
    /// The place's name.
    name: String,
    /// Its initial token count, with the net's parameters bound.
    initial: u32,
    /// Its capacity, or ``None``.
    capacity: Option<u32>,
}

#[pymethods]
impl Place {
    fn __repr__(&self) -> String {
        format!("Place(name={:?}, initial={})", self.name, self.initial)
    }
}

/// A transition of a net: timed (with its rate) or immediate (with its
/// weight and priority).
#[pyclass(module = "petrinav", frozen, get_all)]
pub(crate) struct Transition {
    /// The transition's name.
    name: String,
    /// ``"timed"`` or ``"immediate"``.
    kind: &'static str,
    /// The rate of a timed transition with the net's parameters bound
    /// (``None`` for immediate ones and timed ones without a rate).
    rate: Option<f64>,
    /// The weight of an immediate transition (``None`` for timed ones).
    weight: Option<f64>,
    /// The priority of an immediate transition (``None`` for timed ones).
    priority: Option<u32>,
    /// Servers of a timed transition: ``1``, ``k``, or ``None`` for
    /// infinite servers (immediate: ``None``).
    servers: Option<u32>,
}

#[pymethods]
impl Transition {
    fn __repr__(&self) -> String {
        match self.kind {
            "timed" => format!(
                "Transition(name={:?}, kind='timed', rate={})",
                self.name,
                self.rate.map_or("None".into(), |r| format!("{r:?}"))
            ),
            _ => format!(
                "Transition(name={:?}, kind='immediate', weight={:?}, priority={})",
                self.name,
                self.weight.unwrap_or(f64::NAN),
                self.priority.unwrap_or(0)
            ),
        }
    }
}

/// An arc between a place and a transition.
#[pyclass(name = "Arc", module = "petrinav", frozen, get_all)]
pub(crate) struct Arc_ {
    /// ``"input"``, ``"output"`` or ``"inhibitor"``.
    kind: &'static str,
    /// The place's name.
    place: String,
    /// The transition's name.
    transition: String,
    /// Its multiplicity, with the net's parameters bound.
    multiplicity: u32,
}

#[pymethods]
impl Arc_ {
    fn __repr__(&self) -> String {
        format!(
            "Arc(kind={:?}, place={:?}, transition={:?}, multiplicity={})",
            self.kind, self.place, self.transition, self.multiplicity
        )
    }
}

/// The state-space limits of a call.
fn explore_params(max_states: Option<usize>, max_memory: Option<u64>) -> ExploreParams {
    let defaults = ExploreParams::default();
    ExploreParams {
        max_states: max_states.unwrap_or(defaults.max_states),
        max_memory: max_memory.unwrap_or(defaults.max_memory),
        ..defaults
    }
}

/// `method` as the command line's `--method` spells it (`_` for `-` too).
fn method(name: &str) -> anyhow::Result<Method> {
    Ok(match name.replace('_', "-").as_str() {
        "auto" => Method::Auto,
        "direct" => Method::Direct,
        "gauss-seidel" => Method::GaussSeidel,
        "bicgstab" => Method::Bicgstab,
        _ => anyhow::bail!("unknown method `{name}`: auto, direct, gauss-seidel, bicgstab"),
    })
}

/// A Generalized Stochastic Petri Net, loaded from a file or text with its
/// parameters bound: analyse it, solve it, simulate it, save it.
///
/// Made by :func:`petrinav.load`, :func:`petrinav.loads` or
/// :func:`petrinav.family`. The state space is generated once, on the first
/// call that needs it, and kept.
#[pyclass(module = "petrinav", frozen)]
pub(crate) struct Net {
    net: petri::Net,
    gspn: petri::Gspn,
    assignments: Vec<String>,
    /// The state space of the last limits asked for.
    space: Mutex<Option<CachedSpace>>,
    /// The Markov automaton of the last limits and default rate
    /// [`Net::optimize`] was called with.
    decisions: Mutex<Option<CachedDecisions>>,
}

/// A net's Markov automaton and what it was compiled under
/// (`max_states`, `max_memory`, the default rate's bits).
type CachedDecisions = ((usize, u64, Option<u64>), Arc<Problem>);

/// A state space and the limits (`max_states`, `max_memory`) it was
/// generated under.
type CachedSpace = ((usize, u64), Arc<work::StateSpace>);

impl Net {
    /// `net` with `assignments` bound: instantiated (the errors of
    /// `--param`), and the values written into its parameters, so that
    /// what is saved is the net as bound.
    pub(crate) fn new(mut net: petri::Net, assignments: Vec<String>) -> anyhow::Result<Net> {
        let gspn = work::instantiate(&net, &assignments)?;
        for (name, value) in petri::Params::parse_assignments(&assignments)?.0 {
            if let Some(p) = net.params.iter_mut().find(|p| p.name == name) {
                p.value = Some(value);
            }
        }
        Ok(Net {
            net,
            gspn,
            assignments,
            space: Mutex::new(None),
            decisions: Mutex::new(None),
        })
    }

    /// The state space for these limits, generated on first use.
    fn space(&self, params: &ExploreParams, stop: Interrupt<'_>) -> anyhow::Result<Arc<work::StateSpace>> {
        let key = (params.max_states, params.max_memory);
        if let Some((k, s)) = self
            .space
            .lock()
            .map_err(|_| anyhow::anyhow!("state space lock poisoned"))?
            .as_ref()
            && *k == key
        {
            return Ok(s.clone());
        }
        let space = Arc::new(work::state_space(&self.gspn, params, stop, &mut |_| {})?);
        *self
            .space
            .lock()
            .map_err(|_| anyhow::anyhow!("state space lock poisoned"))? = Some((key, space.clone()));
        Ok(space)
    }

    /// The net's Markov automaton for these options, compiled on first use.
    fn decisions(&self, options: &OptimizeOptions) -> anyhow::Result<Arc<Problem>> {
        let key = (
            options.explore.max_states,
            options.explore.max_memory,
            options.default_rate.map(f64::to_bits),
        );
        let mut cache = self
            .decisions
            .lock()
            .map_err(|_| anyhow::anyhow!("automaton lock poisoned"))?;
        if let Some((k, p)) = cache.as_ref()
            && *k == key
        {
            return Ok(p.clone());
        }
        let path = PathBuf::from(self.gspn.name());
        let problem = Arc::new(Problem::from_net(&path, self.net.clone(), &self.gspn, options)?);
        *cache = Some((key, problem.clone()));
        Ok(problem)
    }

    fn solve_impl(
        &self,
        py: Python<'_>,
        solve: SolveParams,
        default_rate: Option<f64>,
        explore: ExploreParams,
    ) -> PyResult<Solution> {
        let steady = detached(py, Kind::Solve, |stop| {
            let stop = Interrupt::new(stop);
            // As `gspn solve`: the rates are checked before the state space.
            let rates = work::rates(&self.gspn, default_rate)?;
            let space = self.space(&explore, stop)?;
            SteadyState::solve(space, &rates, &solve, stop, &mut |_| {})
        })?;
        Ok(Solution { steady })
    }
}

#[pymethods]
impl Net {
    /// The net's name.
    #[getter]
    fn name(&self) -> &str {
        self.gspn.name()
    }

    /// The places, in the net's order.
    #[getter]
    fn places(&self) -> Vec<Place> {
        let capacities = self.gspn.capacities();
        self.gspn
            .place_names()
            .iter()
            .zip(self.gspn.initial_marking())
            .zip(capacities)
            .map(|((name, &initial), &capacity)| Place {
                name: name.clone(),
                initial,
                capacity,
            })
            .collect()
    }

    /// The transitions, in the net's order, with their rates, weights and
    /// priorities (parameters bound).
    #[getter]
    fn transitions(&self) -> Vec<Transition> {
        let g = &self.gspn;
        let params = g.params();
        (0..g.num_transitions())
            .map(|t| {
                let id = petri::TransitionId(t as u32);
                let name = g.transition_names()[t].clone();
                match g.timing(id) {
                    petri::Timing::Immediate { priority, weight } => Transition {
                        name,
                        kind: "immediate",
                        rate: None,
                        weight: Some(weight),
                        priority: Some(priority),
                        servers: None,
                    },
                    petri::Timing::Timed { servers } => Transition {
                        rate: g
                            .rate_expr(id)
                            .and_then(|e| e.eval_params(&|n| params.get(n).copied().flatten(), &name).ok()),
                        name,
                        kind: "timed",
                        weight: None,
                        priority: None,
                        servers: match servers {
                            petri::Servers::Single => Some(1),
                            petri::Servers::K(k) => Some(k),
                            petri::Servers::Infinite => None,
                        },
                    },
                }
            })
            .collect()
    }

    /// The arcs: input, output and inhibitor, in the file's canonical order.
    #[getter]
    fn arcs(&self) -> Vec<Arc_> {
        let g = &self.gspn;
        let params = g.params();
        self.net
            .arcs
            .iter()
            .map(|a| Arc_ {
                kind: a.kind.name(),
                place: self.net.places[a.place.index()].name.clone(),
                transition: self.net.transitions[a.transition.index()].name.clone(),
                multiplicity: a
                    .multiplicity
                    .eval_params(&|n| params.get(n).copied().flatten(), "an arc")
                    .map_or(0, |v| v as u32),
            })
            .collect()
    }

    /// The parameters and their bound values (``None``: declared, unused
    /// and without value).
    #[getter]
    fn params(&self) -> std::collections::BTreeMap<String, Option<f64>> {
        self.gspn.params().clone()
    }

    /// The initial marking: token counts by place (numpy ``int64``).
    #[getter]
    fn initial_marking<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        PyArray1::from_iter(py, self.gspn.initial_marking().iter().map(|&k| i64::from(k)))
    }

    /// The same net with these parameters bound too (``N=4``,
    /// ``lambda="1/3"``), as :func:`petrinav.load`'s ``params``.
    #[pyo3(signature = (**params))]
    fn with_params(&self, py: Python<'_>, params: Option<&Bound<'_, PyDict>>) -> PyResult<Net> {
        let mut all = self.assignments.clone();
        all.extend(assignments(params)?);
        guarded(py, Kind::Parameter, || Net::new(self.net.clone(), all))
    }

    /// Generates the reachability graph and compiles the CTMC over the
    /// tangible markings (kept for later calls). Releases the GIL; Ctrl-C
    /// stops it (``KeyboardInterrupt``).
    ///
    /// ``max_states`` stops with :class:`StateLimitError` beyond that many
    /// markings; ``max_memory`` (bytes, default 85 % of the available
    /// memory) bounds what generating, compiling and solving would need.
    #[pyo3(signature = (*, max_states=None, max_memory=None))]
    fn state_space(
        &self,
        py: Python<'_>,
        max_states: Option<usize>,
        max_memory: Option<u64>,
    ) -> PyResult<StateSpace> {
        let params = explore_params(max_states, max_memory);
        let space = detached(py, Kind::StateLimit, |stop| {
            self.space(&params, Interrupt::new(stop))
        })?;
        Ok(StateSpace { space })
    }

    /// The steady state, as ``petrinav gspn solve`` computes it: the rates
    /// checked, the state space generated (or reused), the balance
    /// equations solved by ``method`` (``"auto"``: direct up to 2,000
    /// states, BiCGSTAB above; ``"direct"``, ``"gauss-seidel"``,
    /// ``"bicgstab"``) to relative residual ``tolerance``.
    /// ``default_rate`` is the rate of timed transitions without one.
    /// Releases the GIL; Ctrl-C stops it.
    #[pyo3(signature = (*, method="auto", tolerance=1e-12, default_rate=None, max_states=None, max_memory=None))]
    fn solve(
        &self,
        py: Python<'_>,
        method: &str,
        tolerance: f64,
        default_rate: Option<f64>,
        max_states: Option<usize>,
        max_memory: Option<u64>,
    ) -> PyResult<Solution> {
        let m = guarded(py, Kind::Parameter, || self::method(method))?;
        let params = SolveParams {
            method: m,
            tolerance,
            ..SolveParams::default()
        };
        self.solve_impl(py, params, default_rate, explore_params(max_states, max_memory))
    }

    /// The best policy of a net with decisions for ``objective`` (PRISM /
    /// Storm syntax: ``'Pmax=? [F "goal"]'``, ``'Tmin=? [F #Done = 1]'``,
    /// ``'R{"cost"}min=? [F "done"]'``, ``'LRAmax=? ["up"]'``,
    /// ``'R{"done"}max=? [LRA]'``; quoted names are the net's labels), as
    /// ``petrinav gspn optimize NET --json``: a dict with ``value``, its
    /// guaranteed ``bound`` and the interval ``lower``, ``upper`` from the
    /// initial marking, ``method``, ``iterations``, ``seconds``, ``model``,
    /// ``choices`` (every choice marking with the value of each
    /// alternative) and ``policy`` (``{marking: transition chosen}``).
    /// Infinite values are ``math.inf``. ``precision`` is half the
    /// interval's width, relative to the value (absolute with
    /// ``absolute=True``). The Markov automaton is compiled once for the
    /// limits and ``default_rate`` and kept. Releases the GIL; Ctrl-C stops
    /// the iterations.
    #[pyo3(signature = (objective, *, precision=1e-6, absolute=false, default_rate=None, max_states=None, max_memory=None))]
    #[allow(clippy::too_many_arguments)]
    fn optimize<'py>(
        &self,
        py: Python<'py>,
        objective: &str,
        precision: f64,
        absolute: bool,
        default_rate: Option<f64>,
        max_states: Option<usize>,
        max_memory: Option<u64>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let options = guarded(py, Kind::Parameter, || {
            optimize::options(
                precision,
                absolute,
                default_rate,
                explore_params(max_states, max_memory),
            )
        })?;
        let problem = detached(py, Kind::StateLimit, |_| self.decisions(&options))?;
        optimize::optimize(py, &problem, objective, &options)
    }

    /// Size, reachability graph, bounds, liveness, dead markings and
    /// transitions, reversibility, mutual exclusion, P- and T-invariants:
    /// the dict ``petrinav gspn info --json`` prints. Releases the GIL;
    /// Ctrl-C stops the graph's generation.
    #[pyo3(signature = (*, max_states=None, max_memory=None))]
    fn properties<'py>(
        &self,
        py: Python<'py>,
        max_states: Option<usize>,
        max_memory: Option<u64>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let params = explore_params(max_states, max_memory);
        let json = detached(py, Kind::StateLimit, |stop| {
            let a = work::analyse(&self.gspn, &params, Interrupt::new(stop), &mut |_| {})?;
            Ok(a.to_json(&self.net, &self.gspn))
        })?;
        json_to_py(py, &json)
    }

    /// Discrete-event simulation with confidence intervals (batch means),
    /// as ``petrinav gspn simulate --json``: a dict with ``place_names``,
    /// ``transition_names``, ``places`` (mean tokens, by place),
    /// ``prob_nonempty`` (``P{#p > 0}``, by place), ``throughputs`` (by
    /// transition), ``measures`` (``[expression, estimate]`` pairs), each
    /// estimate ``{"mean", "half_width", "batches"}`` at level
    /// ``confidence``; and ``events``, ``simulated_time``,
    /// ``measured_time``, ``confidence``, ``replications``,
    /// ``absorbed_runs``. The same ``seed`` gives the same numbers.
    /// Stops with :class:`SimulationError` after ``max_events`` firings or
    /// ``max_wall`` seconds (``None``: no limit). Releases the GIL; Ctrl-C
    /// stops it (``KeyboardInterrupt``).
    #[pyo3(
        signature = (*, time, seed, warmup=0.0, batches=20, confidence=0.95, measures=Vec::new(), default_rate=None, max_events=1_000_000_000, max_wall=Some(600.0)),
        text_signature = "($self, *, time, seed, warmup=0.0, batches=20, confidence=0.95, measures=(), default_rate=None, max_events=1000000000, max_wall=600.0)"
    )]
    #[allow(clippy::too_many_arguments)]
    fn simulate<'py>(
        &self,
        py: Python<'py>,
        time: f64,
        seed: u64,
        warmup: f64,
        batches: usize,
        confidence: f64,
        measures: Vec<String>,
        default_rate: Option<f64>,
        max_events: u64,
        max_wall: Option<f64>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let options = SimOptions {
            warmup,
            batches,
            confidence,
            default_rate,
            measures,
            max_events,
            max_wall_s: max_wall.filter(|w| *w != f64::INFINITY),
            ..SimOptions::new(time, seed)
        };
        let json = detached(py, Kind::Simulation, |stop| {
            let r = work::simulate(&self.gspn, &options, &mut |_| {
                if stop.load(std::sync::atomic::Ordering::Relaxed) {
                    std::ops::ControlFlow::Break(())
                } else {
                    std::ops::ControlFlow::Continue(())
                }
            })?;
            Ok(serde_json::to_value(&r)?)
        })?;
        json_to_py(py, &json)
    }

    /// Writes the net in the format the file's extension says: ``.pnml``
    /// (ISO/IEC 15909-2, readable by pm4py), ``.pnpro`` (GreatSPN),
    /// ``.toml`` (petrinav), ``.dot`` (Graphviz), as ``petrinav gspn
    /// convert`` — with the parameters given at load written as their
    /// values (so the file loads without them).
    fn save(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        guarded(py, Kind::File, || work::write_net(&self.net, &path))
    }

    /// The net as text in ``format``: ``"pnml"``, ``"pnpro"``, ``"toml"``
    /// or ``"dot"``.
    #[pyo3(signature = (format="toml"))]
    fn dumps(&self, py: Python<'_>, format: &str) -> PyResult<String> {
        guarded(py, Kind::Format, || {
            Ok(petri::io::write_string(&self.net, format_named(format)?)?)
        })
    }

    fn __repr__(&self) -> String {
        format!(
            "<petrinav.Net {:?}: {} places, {} transitions ({} immediate), {} arcs>",
            self.gspn.name(),
            self.gspn.num_places(),
            self.gspn.num_transitions(),
            self.gspn.num_immediate(),
            self.net.arcs.len()
        )
    }
}

/// A format by its name (`pnml`, `pnpro`, `toml`, `dot`).
fn format_named(name: &str) -> anyhow::Result<Format> {
    Format::ALL
        .into_iter()
        .find(|f| f.name().eq_ignore_ascii_case(name) || f.extension().eq_ignore_ascii_case(name))
        .ok_or_else(|| anyhow::anyhow!("unknown format `{name}`: pnml, pnpro, toml, dot"))
}

/// The state space of a net: its tangible markings (the states of the
/// CTMC) in the order of :attr:`Solution.probabilities`.
///
/// ``len(space)`` is the number of tangible markings.
#[pyclass(module = "petrinav", frozen)]
pub(crate) struct StateSpace {
    space: Arc<work::StateSpace>,
}

/// The tangible markings as an `(n, places)` int64 array.
fn markings_array<'py>(py: Python<'py>, space: &work::StateSpace) -> PyResult<Bound<'py, PyArray2<i64>>> {
    let c = &space.compiled;
    let (n, p) = (c.num_tangible(), c.gspn().num_places());
    let mut flat = Vec::with_capacity(n * p);
    for s in 0..n {
        flat.extend(c.tangible_marking(s).into_iter().map(i64::from));
    }
    PyArray1::from_vec(py, flat).reshape([n, p])
}

#[pymethods]
impl StateSpace {
    fn __len__(&self) -> usize {
        self.space.compiled.num_tangible()
    }

    /// The tangible markings: a numpy ``int64`` array of shape
    /// ``(len(space), places)``, one row per marking, columns in the order
    /// of :attr:`place_names`.
    #[getter]
    fn markings<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<i64>>> {
        markings_array(py, &self.space)
    }

    /// The place names, the columns of :attr:`markings`.
    #[getter]
    fn place_names(&self) -> Vec<String> {
        self.space.compiled.gspn().place_names().to_vec()
    }

    /// Markings of the reachability graph, tangible and vanishing.
    #[getter]
    fn reachable_markings(&self) -> usize {
        self.space.reachable_markings
    }

    /// Tangible markings (``len(space)``).
    #[getter]
    fn tangible_markings(&self) -> usize {
        self.space.compiled.num_tangible()
    }

    /// Vanishing markings (eliminated).
    #[getter]
    fn vanishing_markings(&self) -> usize {
        self.space.vanishing_markings
    }

    /// Whether the CTMC is irreducible (one recurrent class).
    #[getter]
    fn ergodic(&self) -> bool {
        self.space.compiled.is_ergodic()
    }

    fn __repr__(&self) -> String {
        format!(
            "<petrinav.StateSpace of {:?}: {} tangible, {} vanishing markings>",
            self.space.compiled.gspn().name(),
            self.space.compiled.num_tangible(),
            self.space.vanishing_markings
        )
    }
}

/// The long-run (steady-state) solution of a net: probabilities of the
/// tangible markings, measures, mean token counts, throughputs.
#[pyclass(module = "petrinav", frozen)]
pub(crate) struct Solution {
    steady: SteadyState,
}

impl Solution {
    fn place(&self, name: &str) -> anyhow::Result<petri::PlaceId> {
        Ok(self.steady.space.compiled.gspn().place(name)?)
    }
}

#[pymethods]
impl Solution {
    /// The long-run probability of each tangible marking (numpy
    /// ``float64``), in the order of :attr:`markings`.
    #[getter]
    fn probabilities<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, &self.steady.solution.pi)
    }

    /// The tangible markings, as :attr:`StateSpace.markings`.
    #[getter]
    fn markings<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<i64>>> {
        markings_array(py, &self.steady.space)
    }

    /// The state space solved.
    #[getter]
    fn state_space(&self) -> StateSpace {
        StateSpace {
            space: self.steady.space.clone(),
        }
    }

    /// The long-run probability of a condition over token counts, e.g.
    /// ``"#P1 = 1 and #P7 = 1"`` (as ``gspn solve --measure``). Raises
    /// :class:`MeasureError` for what does not parse or names a place the
    /// net does not have.
    fn probability(&self, py: Python<'_>, condition: &str) -> PyResult<f64> {
        self.mean(py, condition)
    }

    /// The long-run mean of an expression over token counts, e.g.
    /// ``"#P1 + 2 * #P2"`` (of a condition: its probability).
    fn mean(&self, py: Python<'_>, expression: &str) -> PyResult<f64> {
        guarded(py, Kind::Measure, || {
            Ok(self.steady.measure(&work::parse_measure(expression)?)?)
        })
    }

    /// ``E[#p]``: the long-run mean number of tokens in ``place``.
    fn mean_tokens(&self, py: Python<'_>, place: &str) -> PyResult<f64> {
        guarded(py, Kind::Measure, || {
            Ok(self.steady.solution.mean_tokens(self.place(place)?))
        })
    }

    /// ``P{#p > 0}``: the long-run probability that ``place`` is marked.
    fn prob_nonempty(&self, py: Python<'_>, place: &str) -> PyResult<f64> {
        guarded(py, Kind::Measure, || {
            Ok(self.steady.solution.prob_nonempty(self.place(place)?))
        })
    }

    /// The throughput of ``transition``: mean firings per time unit.
    fn throughput(&self, py: Python<'_>, transition: &str) -> PyResult<f64> {
        guarded(py, Kind::Measure, || {
            let t = self.steady.space.compiled.gspn().transition(transition)?;
            Ok(self.steady.solution.throughput(t))
        })
    }

    /// The marginal distribution of ``place``'s token count: a numpy
    /// ``float64`` array whose entry ``k`` is ``P{#p = k}``, up to the
    /// place's bound.
    fn marginal<'py>(&self, py: Python<'py>, place: &str) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let dist = guarded(py, Kind::Measure, || {
            let p = self.place(place)?.index();
            let c = &self.steady.space.compiled;
            let mut dist: Vec<f64> = Vec::new();
            for (s, &pi) in self.steady.solution.pi.iter().enumerate() {
                let k = c.tangible_marking(s)[p] as usize;
                if dist.len() <= k {
                    dist.resize(k + 1, 0.0);
                }
                dist[k] += pi;
            }
            Ok(dist)
        })?;
        Ok(PyArray1::from_vec(py, dist))
    }

    /// Mean tokens of every place, by name.
    #[getter]
    fn mean_tokens_by_place(&self) -> std::collections::BTreeMap<String, f64> {
        let names = self.steady.space.compiled.gspn().place_names();
        names
            .iter()
            .cloned()
            .zip(self.steady.solution.mean_tokens.iter().copied())
            .collect()
    }

    /// Throughput of every transition, by name.
    #[getter]
    fn throughputs(&self) -> std::collections::BTreeMap<String, f64> {
        let names = self.steady.space.compiled.gspn().transition_names();
        names
            .iter()
            .cloned()
            .zip(self.steady.solution.throughput.iter().copied())
            .collect()
    }

    /// The method that solved the largest component: ``"direct-gth"``,
    /// ``"direct-lu"``, ``"bicgstab"``, ``"gauss-seidel"``, ``"sor"`` or
    /// ``"trivial"``.
    #[getter]
    fn solver(&self) -> &'static str {
        self.steady.solution.info.method
    }

    /// Sweeps of an iterative solve (0 for a direct one).
    #[getter]
    fn iterations(&self) -> usize {
        self.steady.solution.info.iterations
    }

    /// Relative residual of the balance equations.
    #[getter]
    fn residual(&self) -> f64 {
        self.steady.solution.info.residual
    }

    /// Seconds spent solving (not generating).
    #[getter]
    fn seconds(&self) -> f64 {
        self.steady.solution.info.seconds
    }

    /// Whether the chain is ergodic.
    #[getter]
    fn ergodic(&self) -> bool {
        self.steady.space.compiled.is_ergodic()
    }

    /// Probability of ending in each bottom strongly connected component
    /// (``[1.0]`` for an ergodic chain).
    #[getter]
    fn bottom_probabilities(&self) -> Vec<f64> {
        self.steady.solution.bottom_probabilities.clone()
    }

    /// The dict ``petrinav gspn solve --json`` prints, with these measures
    /// (each as ``--measure``).
    #[pyo3(signature = (measures=Vec::new()), text_signature = "($self, measures=())")]
    fn to_dict<'py>(&self, py: Python<'py>, measures: Vec<String>) -> PyResult<Bound<'py, PyAny>> {
        let json = guarded(py, Kind::Measure, || {
            let exprs = work::parse_measures(&measures)?;
            let values = self.steady.measures(&exprs)?;
            Ok(self
                .steady
                .to_json(&measures.into_iter().zip(values).collect::<Vec<_>>()))
        })?;
        json_to_py(py, &json)
    }

    fn __repr__(&self) -> String {
        let s = &self.steady;
        format!(
            "<petrinav.Solution of {:?}: {} tangible markings, {}, residual {:.2e}>",
            s.space.compiled.gspn().name(),
            s.space.compiled.num_tangible(),
            s.solution.info.method,
            s.solution.info.residual
        )
    }
}

/// Loads a net file — ``.pnpro`` (GreatSPN), ``.pnml`` (ISO PNML, e.g.
/// written by pm4py), ``.toml`` (petrinav) — and binds ``params`` (numbers
/// or expression strings such as ``"1/3"``), as ``petrinav gspn …
/// FILE --param NAME=VALUE``: a :class:`Net`. A ``.drn`` file (Storm's
/// explicit format: a DTMC, CTMC, MDP or Markov automaton) gives a
/// :class:`Model` (``params`` refused: a DRN file holds numbers;
/// ``max_memory`` in bytes bounds what reading it may take).
#[pyfunction]
#[pyo3(signature = (path, params=None, *, max_memory=None))]
pub(crate) fn load(
    py: Python<'_>,
    path: PathBuf,
    params: Option<&Bound<'_, PyDict>>,
    max_memory: Option<u64>,
) -> PyResult<Py<PyAny>> {
    let assignments = assignments(params)?;
    if lab::optimize::is_drn(&path) {
        let model = optimize::load_drn(py, &path, &assignments, max_memory)?;
        return Ok(Bound::new(py, model)?.into_any().unbind());
    }
    let net = detached(py, Kind::Format, |_| {
        let net = work::read_net(&path)?;
        Net::new(net, assignments)
    })?;
    Ok(Bound::new(py, net)?.into_any().unbind())
}

/// Reads a net from text in ``format`` (``"toml"``, ``"pnml"`` or
/// ``"pnpro"``); ``name`` stands for the file in error messages.
#[pyfunction]
#[pyo3(signature = (text, format="toml", params=None, name="<string>"))]
pub(crate) fn loads(
    py: Python<'_>,
    text: &str,
    format: &str,
    params: Option<&Bound<'_, PyDict>>,
    name: &str,
) -> PyResult<Net> {
    let assignments = assignments(params)?;
    detached(py, Kind::Format, |_| {
        let net = petri::io::read_str(text, format_named(format)?, name)?;
        Net::new(net, assignments)
    })
}

/// A member of a scalable benchmark family, as ``petrinav gspn family``:
/// ``"kanban"`` (``n`` kanbans per cell; parameter ``N``), ``"fms"``,
/// ``"philosophers"``, ``"robots"``, ``"polling"``, ``"tandem"``.
#[pyfunction]
#[pyo3(signature = (name, n, params=None))]
pub(crate) fn family(
    py: Python<'_>,
    name: &str,
    n: u32,
    params: Option<&Bound<'_, PyDict>>,
) -> PyResult<Net> {
    use petri::families::Family as F;
    let assignments = assignments(params)?;
    guarded(py, Kind::Parameter, || {
        let f = [
            F::Kanban,
            F::Fms,
            F::Philosophers,
            F::Robots,
            F::Polling,
            F::Tandem,
        ]
        .into_iter()
        .find(|f| f.name() == name)
        .ok_or_else(|| {
            anyhow::anyhow!("unknown family `{name}`: kanban, fms, philosophers, robots, polling, tandem")
        })?;
        Net::new(f.build(n)?, assignments)
    })
}

/// The names of what :func:`load` reads.
#[pyfunction]
pub(crate) fn formats(py: Python<'_>) -> PyResult<Bound<'_, PyList>> {
    PyList::new(py, Format::ALL.iter().filter(|f| f.can_read()).map(|f| f.name()))
}
