//! Which engine solves a net — `petrinav gspn solve --engine
//! auto|explicit|structured` — shared by the command line and the Python
//! package: the explicit engine ([`petri::CompiledGspn`]: the reachability
//! graph and a sparse generator) or the structured one
//! ([`petri::StructuredGspn`]: a product of components' local spaces, no
//! generator stored).
//!
//! ```
//! use lab::engine::{self, Engine};
//! use lab::gspn::SolveOptions;
//!
//! let gspn = petri::families::kanban(4).instantiate(&petri::Params::new())?;
//! let out = engine::solve(&gspn, &SolveOptions::default(), Engine::Auto, None, petri::Interrupt::NEVER, &mut |_| {})?;
//! assert_eq!(out.choice.engine, "structured");
//! let busy = out.measure(&petri::Expr::parse("#Pm1 >= 1")?)?;
//! assert!((busy - 0.3284401823).abs() < 1e-9);
//! # Ok::<(), anyhow::Error>(())
//! ```
//!
//! **What `auto` does.** It asks the structured engine first (finding the
//! structure is a symbolic search, milliseconds on the nets here) and uses
//! it when all of these hold; otherwise the explicit engine, with the reason
//! in [`Choice::reason`]:
//!
//! * the method is `auto` or `gauss-seidel` (the structured engine only
//!   iterates);
//! * the net has a product structure with an irreducible chain
//!   ([`petri::Error::Unstructured`] says why not);
//! * the chain has at least [`AUTO_MIN_STATES`] states: below, the
//!   explicit engine is fast and its answers are the ones the repository's
//!   tables and suites were made with, to the last bit;
//! * the net has no vanishing markings, unless the explicit engine would
//!   not fit in memory: the explicit engine eliminates them, and is faster
//!   on such nets (`crates/petri/BENCHMARKS.md`).

use std::sync::Arc;

use anyhow::{Context, Result, bail};
use petri::{
    Expr, Gspn, Interrupt, Method, PlaceId, SolveInfo, StructureParams, StructuredGspn, StructuredParams,
    StructuredSolution,
};
use serde_json::{Value, json};

use crate::gspn::{MeasureError, MemoryReport, SolveOptions, SteadyState, nodes_json, peak_rss_bytes};

/// Smallest chain (states of the product space) that `auto` gives to the
/// structured engine.
pub const AUTO_MIN_STATES: u64 = 100_000;

/// Bytes per marking the explicit engine needs, about (generation, the
/// generator and BiCGSTAB's vectors: `crates/petri/BENCHMARKS.md`), for
/// `auto`'s check on nets with vanishing markings.
pub const EXPLICIT_BYTES_PER_MARKING: u64 = 160;

/// The engine asked for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Engine {
    /// The structured engine where it applies and pays (see the module
    /// docs), the explicit one otherwise.
    #[default]
    Auto,
    /// Reachability graph and sparse generator.
    Explicit,
    /// Product structure, no generator stored; an error where it does not
    /// apply.
    Structured,
}

impl Engine {
    /// `auto`, `explicit` or `structured`.
    pub fn parse(text: &str) -> Result<Engine> {
        match text {
            "auto" => Ok(Engine::Auto),
            "explicit" => Ok(Engine::Explicit),
            "structured" => Ok(Engine::Structured),
            other => bail!("unknown engine `{other}`: auto, explicit or structured"),
        }
    }
}

/// The engine used and why.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Choice {
    /// `"explicit"` or `"structured"`.
    pub engine: &'static str,
    /// Why, in a sentence.
    pub reason: String,
}

/// A net solved by the structured engine.
#[derive(Debug, Clone)]
pub struct StructuredSteady {
    /// The prepared net.
    pub model: Arc<StructuredGspn>,
    /// Its solution.
    pub solution: StructuredSolution,
}

/// A solution by either engine.
#[derive(Debug, Clone)]
pub enum Solved {
    /// By the explicit engine.
    Explicit(SteadyState),
    /// By the structured engine.
    Structured(StructuredSteady),
}

/// A solved net and the engine's choice.
#[derive(Debug, Clone)]
pub struct Outcome {
    /// The solution.
    pub solved: Solved,
    /// Which engine, and why.
    pub choice: Choice,
}

/// The components of `--partition`: components separated by `;`, places
/// by `,` (or spaces), outermost first.
pub fn parse_partition(gspn: &Gspn, text: &str) -> Result<Vec<Vec<PlaceId>>> {
    text.split(';')
        .filter(|c| !c.trim().is_empty())
        .map(|c| {
            c.split([',', ' '])
                .filter(|p| !p.is_empty())
                .map(|p| gspn.place(p).with_context(|| format!("in --partition `{text}`")))
                .collect()
        })
        .collect()
}

fn structured_params(
    gspn: &Gspn,
    options: &SolveOptions,
    partition: Option<&str>,
) -> Result<StructuredParams> {
    Ok(StructuredParams {
        structure: StructureParams {
            partition: partition.map(|p| parse_partition(gspn, p)).transpose()?,
        },
        max_memory: options.explore.max_memory,
    })
}

/// Solves `gspn` with the engine asked for (see the module docs for
/// `auto`); `partition` is `--partition`'s text. `phase` is told each stage.
pub fn solve(
    gspn: &Gspn,
    options: &SolveOptions,
    engine: Engine,
    partition: Option<&str>,
    stop: Interrupt<'_>,
    phase: &mut dyn FnMut(&'static str),
) -> Result<Outcome> {
    let rates = crate::gspn::rates(gspn, options.default_rate)?;
    let explicit = |reason: String, phase: &mut dyn FnMut(&'static str)| -> Result<Outcome> {
        let solved = crate::gspn::solve(gspn, options, stop, phase)?;
        Ok(Outcome {
            solved: Solved::Explicit(solved),
            choice: Choice {
                engine: "explicit",
                reason,
            },
        })
    };
    if engine == Engine::Explicit {
        return explicit("asked for (--engine explicit)".into(), phase);
    }
    let iterative = matches!(options.solve.method, Method::Auto | Method::GaussSeidel);
    if engine == Engine::Auto && !iterative {
        return explicit(
            format!(
                "--method {:?} is a method of the explicit engine",
                options.solve.method
            ),
            phase,
        );
    }
    phase("finding the product structure");
    let params = structured_params(gspn, options, partition)?;
    let model = match StructuredGspn::build(gspn, &params, stop) {
        Ok(m) => m,
        Err(e @ (petri::Error::Unstructured { .. } | petri::Error::MemoryLimit { .. }))
            if engine == Engine::Auto =>
        {
            return explicit(e.to_string(), phase);
        }
        Err(e) => return Err(e.into()),
    };
    let st = model.stats();
    if engine == Engine::Auto {
        if st.states < AUTO_MIN_STATES {
            return explicit(
                format!(
                    "a small chain ({} states, below {AUTO_MIN_STATES}): the explicit engine",
                    st.states
                ),
                phase,
            );
        }
        let markings = st.tangible + st.vanishing;
        if st.vanishing > 0
            && markings.saturating_mul(EXPLICIT_BYTES_PER_MARKING) <= options.explore.max_memory
        {
            return explicit(
                format!(
                    "{} vanishing markings, which the explicit engine eliminates (faster here)",
                    st.vanishing
                ),
                phase,
            );
        }
    }
    let sizes: Vec<String> = st.components.iter().map(usize::to_string).collect();
    let reason = format!(
        "{} ({} component{}: {} local states)",
        if engine == Engine::Auto {
            "a product structure"
        } else {
            "asked for (--engine structured)"
        },
        sizes.len(),
        if sizes.len() == 1 { "" } else { "s" },
        sizes.join(" × ")
    );
    phase("solving the steady state");
    let solution = model.solve_rates(&rates, &options.solve, stop)?;
    Ok(Outcome {
        solved: Solved::Structured(StructuredSteady {
            model: Arc::new(model),
            solution,
        }),
        choice: Choice {
            engine: "structured",
            reason,
        },
    })
}

/// What the command line's tables print of a solution, by either engine.
#[derive(Debug, Clone)]
pub struct Summary<'a> {
    /// Tangible markings.
    pub tangible: u64,
    /// Vanishing markings.
    pub vanishing: u64,
    /// Whether the chain has one recurrent class.
    pub ergodic: bool,
    /// Probability of ending in each bottom component.
    pub bottom_probabilities: &'a [f64],
    /// How the equations were solved.
    pub info: &'a SolveInfo,
    /// `P{#p > 0}` by place.
    pub prob_nonempty: &'a [f64],
    /// `E[#p]` by place.
    pub mean_tokens: &'a [f64],
    /// Throughput by transition.
    pub throughput: &'a [f64],
}

const ONE: [f64; 1] = [1.0];

impl Outcome {
    /// The instantiated net.
    pub fn gspn(&self) -> &Gspn {
        match &self.solved {
            Solved::Explicit(s) => s.space.compiled.gspn(),
            Solved::Structured(s) => s.model.gspn(),
        }
    }

    /// The figures the tables print.
    pub fn summary(&self) -> Summary<'_> {
        match &self.solved {
            Solved::Explicit(s) => Summary {
                tangible: s.space.compiled.num_tangible() as u64,
                vanishing: s.space.vanishing_markings as u64,
                ergodic: s.space.compiled.is_ergodic(),
                bottom_probabilities: &s.solution.bottom_probabilities,
                info: &s.solution.info,
                prob_nonempty: &s.solution.prob_nonempty,
                mean_tokens: &s.solution.mean_tokens,
                throughput: &s.solution.throughput,
            },
            Solved::Structured(s) => Summary {
                tangible: s.model.stats().tangible,
                vanishing: s.model.stats().vanishing,
                ergodic: true,
                bottom_probabilities: &ONE,
                info: &s.solution.info,
                prob_nonempty: &s.solution.prob_nonempty,
                mean_tokens: &s.solution.mean_tokens,
                throughput: &s.solution.throughput,
            },
        }
    }

    /// The long-run value of a measure (as [`SteadyState::measure`]).
    pub fn measure(&self, expr: &Expr) -> std::result::Result<f64, MeasureError> {
        match &self.solved {
            Solved::Explicit(s) => s.measure(expr),
            Solved::Structured(s) => s.model.measure(&s.solution, expr).map_err(|source| MeasureError {
                text: expr.to_string(),
                source: Box::new(source),
            }),
        }
    }

    /// [`measure`](Self::measure) of each.
    pub fn measures(&self, exprs: &[Expr]) -> Result<Vec<f64>> {
        exprs.iter().map(|m| Ok(self.measure(m)?)).collect()
    }

    /// Where the memory went and the process's peak (`--stats`).
    pub fn memory(&self) -> MemoryReport {
        match &self.solved {
            Solved::Explicit(s) => s.memory(),
            Solved::Structured(s) => MemoryReport {
                account: s.model.memory_account(Some(&s.solution)),
                peak_rss_bytes: peak_rss_bytes(),
            },
        }
    }

    /// The object `gspn solve --json` prints: the explicit engine's fields
    /// (for the structured engine: the same names), plus `engine`,
    /// `engine_reason`, and for the structured engine `components` (local
    /// states of each), `omega` and `aggregations`.
    pub fn to_json(&self, measures: &[(String, f64)]) -> Value {
        let mut v = match &self.solved {
            Solved::Explicit(s) => s.to_json(measures),
            Solved::Structured(s) => structured_json(s, measures),
        };
        if let Value::Object(o) = &mut v {
            o.insert("engine".into(), json!(self.choice.engine));
            o.insert("engine_reason".into(), json!(self.choice.reason));
        }
        v
    }
}

fn structured_json(s: &StructuredSteady, measures: &[(String, f64)]) -> Value {
    let gspn = s.model.gspn();
    let sol = &s.solution;
    let st = s.model.stats();
    let (places, transitions, ms) = nodes_json(
        gspn,
        &sol.prob_nonempty,
        &sol.mean_tokens,
        &sol.throughput,
        measures,
    );
    json!({
        "name": gspn.name(),
        "reachable_markings": st.tangible + st.vanishing,
        "tangible_markings": st.tangible,
        "vanishing_markings": st.vanishing,
        "ergodic": true,
        "bottom_components": 1,
        "solver": sol.info.method,
        "iterations": sol.info.iterations,
        "residual": sol.info.residual,
        "seconds": sol.info.seconds,
        "places": places,
        "transitions": transitions,
        "measures": ms,
        "components": st.components,
        "omega": sol.omega,
        "aggregations": sol.aggregations,
    })
}

/// `gspn info --structure`: the product structure of `gspn`'s reachable
/// set (a symbolic search; no explicit state space is generated).
pub fn structure(gspn: &Gspn, partition: Option<&str>) -> Result<petri::Structure> {
    let params = StructureParams {
        partition: partition.map(|p| parse_partition(gspn, p)).transpose()?,
    };
    Ok(petri::Structure::detect(gspn, &params)?)
}

/// The object `gspn info --structure --json` prints.
pub fn structure_json(gspn: &Gspn, s: &petri::Structure) -> Value {
    let names = gspn.place_names();
    let components: Vec<Value> = s
        .components()
        .iter()
        .map(|c| {
            json!({
                "places": c.places.iter().map(|p| names[p.index()].clone()).collect::<Vec<_>>(),
                "local_states": c.len(),
            })
        })
        .collect();
    json!({
        "name": gspn.name(),
        "components": components,
        "reachable_markings": s.reachable().to_string(),
        "product_of_components": s.product().to_string(),
        "exact_product": s.is_exact(),
        "invariant_groups": s.groups(),
        "potential_markings": s.potential().to_string(),
        "notes": s.notes(),
        "reversible": s.reversible(),
        "decision_diagram_nodes": s.mdd_nodes(),
        "seconds": s.seconds(),
    })
}
