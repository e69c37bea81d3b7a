//! Decisions from Python: `Net.optimize` and `petrinav.Model` (what
//! `petrinav.load` returns for a `.drn` file), both through
//! `lab::optimize` as `petrinav gspn optimize --json` is.
//!
//! The result is the dict `--json` prints, with numbers as floats (an
//! infinite value is `math.inf`, not the string `"infinity"`) and one key
//! more, `policy`: the action chosen in each choice state, by the state's
//! name (a net's marking, a DRN model's `state N`).

use std::path::Path;

use lab::optimize::{self as work, Optimization, OptimizeOptions, Problem};
use petri::mdp::{ModelType, Precision};
use petri::{ExploreParams, Interrupt};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::convert::json_to_py;
use crate::errors::Kind;
use crate::run::detached;

/// The options of a call, checked as `gspn optimize` checks its own.
pub(crate) fn options(
    precision: f64,
    absolute: bool,
    default_rate: Option<f64>,
    explore: ExploreParams,
) -> anyhow::Result<OptimizeOptions> {
    if !(precision.is_finite() && precision > 0.0) {
        anyhow::bail!("precision must be a number > 0, got {precision}");
    }
    Ok(OptimizeOptions {
        explore,
        precision: Precision {
            epsilon: precision,
            relative: !absolute,
            ..Precision::default()
        },
        default_rate,
    })
}

/// Optimises `objective` on `problem` off the GIL (Ctrl-C stops the
/// iterations) and returns the result as a dict.
pub(crate) fn optimize<'py>(
    py: Python<'py>,
    problem: &Problem,
    objective: &str,
    options: &OptimizeOptions,
) -> PyResult<Bound<'py, PyAny>> {
    let result = detached(py, Kind::Solve, |stop| {
        problem.optimize(objective, options, Interrupt::new(stop))
    })?;
    result_dict(py, &result)
}

/// Sets `key` to the float `v` (infinite values included).
fn set_number(d: &Bound<'_, PyDict>, key: &str, v: f64) -> PyResult<()> {
    d.set_item(key, v)
}

/// The `--json` object as a dict, numbers as floats, and `policy`.
fn result_dict<'py>(py: Python<'py>, r: &Optimization) -> PyResult<Bound<'py, PyAny>> {
    let o = &r.optimum;
    let mut json = r.to_json();
    // Rebuilt below with floats for what may be infinite.
    for key in ["value", "bound", "lower", "upper", "initial_states", "choices"] {
        json.as_object_mut().map(|m| m.remove(key));
    }
    let d = json_to_py(py, &json)?.cast_into::<PyDict>()?;
    set_number(&d, "value", r.value())?;
    set_number(&d, "bound", r.bound())?;
    set_number(&d, "lower", o.lower[r.initial])?;
    set_number(&d, "upper", o.upper[r.initial])?;
    let initial = PyList::empty(py);
    for &s in r.model.initial_states() {
        let s = s as usize;
        let e = PyDict::new(py);
        e.set_item("state", s)?;
        set_number(&e, "value", o.value(s))?;
        set_number(&e, "lower", o.lower[s])?;
        set_number(&e, "upper", o.upper[s])?;
        initial.append(e)?;
    }
    d.set_item("initial_states", initial)?;
    let choices = PyList::empty(py);
    let policy = PyDict::new(py);
    for c in &r.choices {
        let alternatives = PyList::empty(py);
        for (i, (action, l, u)) in c.alternatives.iter().enumerate() {
            let a = PyDict::new(py);
            a.set_item("action", action)?;
            set_number(&a, "value", if l == u { *l } else { l + (u - l) / 2.0 })?;
            set_number(&a, "lower", *l)?;
            set_number(&a, "upper", *u)?;
            if let Some(rel) = &c.relative {
                set_number(&a, "relative", rel[i])?;
            }
            alternatives.append(a)?;
        }
        let e = PyDict::new(py);
        e.set_item("state", c.state)?;
        e.set_item("marking", &c.name)?;
        e.set_item("chosen", &c.chosen)?;
        e.set_item("alternatives", alternatives)?;
        choices.append(e)?;
        policy.set_item(&c.name, &c.chosen)?;
    }
    d.set_item("choices", choices)?;
    d.set_item("policy", policy)?;
    Ok(d.into_any())
}

/// A model read from a DRN file (Storm's explicit format): a DTMC, CTMC,
/// MDP or Markov automaton with its labels and reward models, optimised
/// or checked as ``petrinav gspn optimize model.drn`` does.
///
/// Made by :func:`petrinav.load` for a ``.drn`` file.
#[pyclass(module = "petrinav", frozen)]
pub(crate) struct Model {
    problem: Problem,
}

impl Model {
    fn model(&self) -> &petri::mdp::Model {
        match &self.problem {
            Problem::Drn { model, .. } => model,
            // `load_drn` makes only DRN problems.
            Problem::Net { .. } => unreachable!("a petrinav.Model holds a DRN model"),
        }
    }
}

/// Reads a DRN file (`max_memory` bounds what it may take; parameters do
/// not apply to a DRN file and are refused).
pub(crate) fn load_drn(
    py: Python<'_>,
    path: &Path,
    assignments: &[String],
    max_memory: Option<u64>,
) -> PyResult<Model> {
    if !assignments.is_empty() {
        return crate::run::guarded(py, Kind::Parameter, || {
            anyhow::bail!(
                "{}: a DRN file holds numbers, not parameters: params do not apply",
                path.display()
            )
        });
    }
    let mut explore = ExploreParams::default();
    if let Some(m) = max_memory {
        explore.max_memory = m;
    }
    let options = OptimizeOptions {
        explore,
        ..OptimizeOptions::default()
    };
    let problem = detached(py, Kind::Format, |_| work::load(path, assignments, &options))?;
    Ok(Model { problem })
}

#[pymethods]
impl Model {
    /// The model's type: ``"DTMC"``, ``"CTMC"``, ``"MDP"`` or ``"MA"``
    /// (Markov automaton).
    #[getter]
    fn r#type(&self) -> &'static str {
        match self.model().model_type() {
            ModelType::Dtmc => "DTMC",
            ModelType::Ctmc => "CTMC",
            ModelType::Mdp => "MDP",
            ModelType::MarkovAutomaton => "MA",
        }
    }

    /// The file it was read from.
    #[getter]
    fn path(&self) -> String {
        self.problem.path().display().to_string()
    }

    /// Number of states (``len(model)``).
    #[getter]
    fn states(&self) -> usize {
        self.model().num_states()
    }

    /// Number of actions (choices, rows) over all states.
    #[getter]
    fn actions(&self) -> usize {
        self.model().num_rows()
    }

    /// Number of transitions (non-zero entries).
    #[getter]
    fn transitions(&self) -> usize {
        self.model().num_entries()
    }

    /// The initial states.
    #[getter]
    fn initial_states(&self) -> Vec<u32> {
        self.model().initial_states().to_vec()
    }

    /// The labels (``init`` included), each with its states.
    #[getter]
    fn labels(&self) -> std::collections::BTreeMap<String, Vec<usize>> {
        self.model()
            .labels()
            .iter()
            .map(|l| {
                let states = l
                    .states
                    .iter()
                    .enumerate()
                    .filter(|(_, m)| **m)
                    .map(|(s, _)| s)
                    .collect();
                (l.name.clone(), states)
            })
            .collect()
    }

    /// The names of the reward models.
    #[getter]
    fn reward_models(&self) -> Vec<String> {
        self.model().rewards().iter().map(|r| r.name.clone()).collect()
    }

    /// The optimum of ``objective`` (PRISM / Storm syntax: ``'Pmax=? [F
    /// "goal"]'``, ``'Tmin=? [F "goal"]'``, ``'R{"cost"}min=? [F
    /// "goal"]'``, ``'LRAmax=? ["up"]'``, ``'R{"cost"}max=? [LRA]'``; a
    /// model without choices takes ``P=?``, ``T=?``…), as ``petrinav gspn
    /// optimize model.drn --json``: a dict with ``value``, its guaranteed
    /// ``bound`` and the interval ``lower``, ``upper`` from the first
    /// initial state, ``initial_states``, ``method``, ``iterations``,
    /// ``seconds``, ``model``, ``choices`` (every choice state with each
    /// alternative's value) and ``policy`` (``{"state N": action}``).
    /// ``precision`` is half the interval's width, relative to the value
    /// (absolute with ``absolute=True``). Releases the GIL; Ctrl-C stops it.
    #[pyo3(signature = (objective, *, precision=1e-6, absolute=false))]
    fn optimize<'py>(
        &self,
        py: Python<'py>,
        objective: &str,
        precision: f64,
        absolute: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        let options = crate::run::guarded(py, Kind::Parameter, || {
            options(precision, absolute, None, ExploreParams::default())
        })?;
        optimize(py, &self.problem, objective, &options)
    }

    fn __len__(&self) -> usize {
        self.model().num_states()
    }

    fn __repr__(&self) -> String {
        format!(
            "<petrinav.Model {}: {}>",
            self.problem.path().display(),
            work::describe_model(self.model())
        )
    }
}
