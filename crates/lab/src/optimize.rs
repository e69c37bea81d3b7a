//! The work behind `petrinav gspn optimize` and `gspn convert … .drn`,
//! shared with the Python package: a net with decisions or a DRN file,
//! optimised for a property (docs/gspn.md, *Decisions*), the policy as a
//! report, a JSON object and a policy file.
//!
//! ```
//! use lab::optimize::{self, OptimizeOptions};
//!
//! let problem = optimize::load(std::path::Path::new("../../models/supervisor_decisions.toml"), &[] as &[&str], &OptimizeOptions::default())?;
//! let best = problem.optimize(r#"R{"success"}max=? [LRA]"#, &OptimizeOptions::default(), petri::Interrupt::NEVER)?;
//! assert!(best.value() > 0.0 && !best.choices.is_empty());
//! # Ok::<(), anyhow::Error>(())
//! ```

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use petri::io::drn::{self, DrnParams};
use petri::mdp::{Model, ModelType, OptimizeParams, Optimum, Precision, Property};
use petri::{DecisionNet, ExploreParams, Gspn, Interrupt, Net, Policy};
use serde_json::{Value, json};

/// How to build and solve (the options of `gspn optimize`).
#[derive(Debug, Clone, Default)]
pub struct OptimizeOptions {
    /// State-space limits of a net (`--max-states`, `--max-memory`).
    pub explore: ExploreParams,
    /// Precision of the iterations (`--precision`, `--absolute`).
    pub precision: Precision,
    /// Rate of every timed transition without one (`--default-rate`).
    pub default_rate: Option<f64>,
}

/// What is optimised: a net with its automaton and rates, or a model read
/// from a DRN file.
#[derive(Debug, Clone)]
pub enum Problem {
    /// A net (`.toml`, `.pnpro`, `.pnml`).
    Net {
        /// The file.
        path: PathBuf,
        /// The net as read.
        net: Box<Net>,
        /// Its Markov automaton, compiled once.
        automaton: Box<DecisionNet>,
        /// The timed transitions' rates.
        rates: Vec<f64>,
    },
    /// A DRN file.
    Drn {
        /// The file.
        path: PathBuf,
        /// The model.
        model: Box<Model>,
    },
}

/// Whether `path` names a DRN file (`.drn`).
pub fn is_drn(path: &Path) -> bool {
    path.extension().is_some_and(|e| e.eq_ignore_ascii_case("drn"))
}

/// Loads a net (with `NAME=VALUE` assignments) and compiles its Markov
/// automaton, or reads a DRN file (assignments refused).
pub fn load<S: AsRef<str>>(path: &Path, assignments: &[S], options: &OptimizeOptions) -> Result<Problem> {
    if is_drn(path) {
        if !assignments.is_empty() || options.default_rate.is_some() {
            bail!(
                "{}: a DRN file holds numbers, not parameters: --param and --default-rate do not apply",
                path.display()
            );
        }
        let params = DrnParams {
            max_memory: options.explore.max_memory,
        };
        let model =
            drn::read_drn_file(path, &params).with_context(|| format!("loading {}", path.display()))?;
        return Ok(Problem::Drn {
            path: path.to_path_buf(),
            model: Box::new(model),
        });
    }
    let (net, gspn) = crate::gspn::load(path, assignments)?;
    Problem::from_net(path, net, &gspn, options)
}

/// One choice state of an optimum: what the policy does and what each
/// alternative is worth.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Choice {
    /// The state in the model.
    pub state: usize,
    /// Its marking (marked places, `P0 P5 P7`), or `state N` for a DRN model.
    pub name: String,
    /// The action chosen.
    pub chosen: String,
    /// Every action with the lower and upper bounds of its value.
    pub alternatives: Vec<(String, f64, f64)>,
    /// For a long-run average: every action's relative value (the reward
    /// it gains or loses on the way against the policy, which the gain,
    /// equal for all in a recurrent component, does not show).
    pub relative: Option<Vec<f64>>,
}

/// An optimisation's result.
#[derive(Debug, Clone)]
pub struct Optimization {
    /// The property.
    pub property: Property,
    /// The numeric model solved.
    pub model: Model,
    /// Values, bounds, policy.
    pub optimum: Optimum,
    /// The model's initial state the value is reported for.
    pub initial: usize,
    /// The choice states.
    pub choices: Vec<Choice>,
    /// The policy file's content (nets only).
    pub policy: Option<Policy>,
}

impl Problem {
    /// A net already read and instantiated (`gspn`, its parameters bound):
    /// its rates checked and its Markov automaton compiled; `path` names
    /// it in what is printed.
    pub fn from_net(path: &Path, net: Net, gspn: &Gspn, options: &OptimizeOptions) -> Result<Problem> {
        let rates = gspn.rates(&petri::Params::new(), options.default_rate)?;
        let automaton = DecisionNet::build(gspn, &options.explore)?;
        Ok(Problem::Net {
            path: path.to_path_buf(),
            net: Box::new(net),
            automaton: Box::new(automaton),
            rates,
        })
    }

    /// The file it came from.
    pub fn path(&self) -> &Path {
        match self {
            Problem::Net { path, .. } | Problem::Drn { path, .. } => path,
        }
    }

    /// The numeric model (a net's automaton bound to its rates, with
    /// labels and rewards).
    pub fn model(&self) -> Result<Model> {
        Ok(match self {
            Problem::Net { automaton, rates, .. } => automaton.bind(rates)?,
            Problem::Drn { model, .. } => (**model).clone(),
        })
    }

    /// The instantiated net, for a net.
    pub fn gspn(&self) -> Option<&Gspn> {
        match self {
            Problem::Net { automaton, .. } => Some(automaton.gspn()),
            Problem::Drn { .. } => None,
        }
    }

    /// Optimises `property` (PRISM/Storm syntax).
    pub fn optimize(
        &self,
        property: &str,
        options: &OptimizeOptions,
        stop: Interrupt<'_>,
    ) -> Result<Optimization> {
        let property = Property::parse(property)?;
        let params = OptimizeParams {
            precision: options.precision,
        };
        match self {
            Problem::Net { automaton, rates, .. } => {
                let objective = automaton.objective(&property)?;
                let (model, optimum) = automaton.solve_interruptible(&objective, rates, &params, stop)?;
                let g = automaton.gspn();
                let choices = automaton
                    .choices(&model, &optimum)
                    .into_iter()
                    .map(|c| Choice {
                        state: c.state,
                        name: g.format_marking(&c.marking),
                        chosen: c.chosen.describe(g),
                        alternatives: c
                            .alternatives
                            .iter()
                            .map(|&(a, l, u)| (a.describe(g), l, u))
                            .collect(),
                        relative: relative(&model, &optimum, c.state),
                    })
                    .collect();
                let policy = automaton.policy(&optimum, &model, Some(&property.text));
                Ok(Optimization {
                    property,
                    model,
                    optimum,
                    initial: 0,
                    choices,
                    policy: Some(policy),
                })
            }
            Problem::Drn { model, .. } => {
                let optimum = model.check_interruptible(&property, &params, stop)?;
                let choices = (0..model.num_states())
                    .filter(|&s| model.rows(s).len() >= 2)
                    .map(|s| Choice {
                        state: s,
                        name: format!("state {s}"),
                        chosen: model.action_name(optimum.choice[s] as usize),
                        alternatives: model
                            .rows(s)
                            .map(|r| {
                                let (l, u) = optimum.row_bounds(model, r);
                                (model.action_name(r), l, u)
                            })
                            .collect(),
                        relative: relative(model, &optimum, s),
                    })
                    .collect();
                Ok(Optimization {
                    property,
                    initial: model.initial_states().first().map_or(0, |&s| s as usize),
                    model: (**model).clone(),
                    optimum,
                    choices,
                    policy: None,
                })
            }
        }
    }
}

/// The relative values of the rows of state `s` (long-run averages).
fn relative(model: &Model, optimum: &Optimum, s: usize) -> Option<Vec<f64>> {
    model.rows(s).map(|r| optimum.row_relative(model, s, r)).collect()
}

/// A number for JSON: finite, or the string `"infinity"`.
pub fn json_number(v: f64) -> Value {
    if v.is_finite() {
        json!(v)
    } else if v > 0.0 {
        json!("infinity")
    } else {
        json!("-infinity")
    }
}

/// The model's kind in words.
pub fn describe_model(model: &Model) -> String {
    let n = model.num_states();
    let probabilistic = (0..n).filter(|&s| !model.is_markovian(s)).count();
    let kind = match model.model_type() {
        ModelType::Dtmc => "DTMC".to_string(),
        ModelType::Ctmc => "CTMC".to_string(),
        ModelType::Mdp => "MDP".to_string(),
        ModelType::MarkovAutomaton => format!("Markov automaton ({probabilistic} probabilistic states)"),
    };
    format!(
        "{kind}: {n} states, {} actions, {} transitions",
        model.num_rows(),
        model.num_entries()
    )
}

impl Optimization {
    /// The value from the initial state.
    pub fn value(&self) -> f64 {
        self.optimum.value(self.initial)
    }

    /// Its guaranteed bound (half the interval's width).
    pub fn bound(&self) -> f64 {
        self.optimum.error_bound(self.initial)
    }

    /// The object `gspn optimize --json` prints.
    pub fn to_json(&self) -> Value {
        let o = &self.optimum;
        let choices: Vec<Value> = self
            .choices
            .iter()
            .map(|c| {
                let alternatives: Vec<Value> = c
                    .alternatives
                    .iter()
                    .enumerate()
                    .map(|(i, (a, l, u))| {
                        let mid = if l == u { *l } else { l + (u - l) / 2.0 };
                        let mut v = json!({"action": a, "value": json_number(mid), "lower": json_number(*l), "upper": json_number(*u)});
                        if let Some(rel) = &c.relative {
                            v["relative"] = json_number(rel[i]);
                        }
                        v
                    })
                    .collect();
                json!({"state": c.state, "marking": c.name, "chosen": c.chosen, "alternatives": alternatives})
            })
            .collect();
        let initial: Vec<Value> = self
            .model
            .initial_states()
            .iter()
            .map(|&s| {
                let s = s as usize;
                json!({"state": s, "value": json_number(o.value(s)), "lower": json_number(o.lower[s]), "upper": json_number(o.upper[s])})
            })
            .collect();
        json!({
            "property": self.property.text,
            "model": {
                "type": self.model.model_type(),
                "states": self.model.num_states(),
                "actions": self.model.num_rows(),
                "transitions": self.model.num_entries(),
            },
            "value": json_number(self.value()),
            "bound": json_number(self.bound()),
            "lower": json_number(o.lower[self.initial]),
            "upper": json_number(o.upper[self.initial]),
            "initial_states": initial,
            "method": o.method,
            "iterations": o.iterations,
            "failed_guesses": o.failed_guesses,
            "seconds": o.seconds,
            "choices": choices,
        })
    }
}

/// `gspn convert NET file.drn`: the net's CTMC or Markov automaton, with
/// its labels, `init` and reward models, each state's marking as a
/// comment.
pub fn write_drn<S: AsRef<str>>(
    input: &Path,
    output: &Path,
    assignments: &[S],
    options: &OptimizeOptions,
) -> Result<Model> {
    let problem = load(input, assignments, options)?;
    let model = problem.model()?;
    let file = std::fs::File::create(output).with_context(|| format!("writing {}", output.display()))?;
    let mut w = std::io::BufWriter::new(file);
    match &problem {
        Problem::Net { automaton, .. } => {
            let g = automaton.gspn();
            let comment = |s: usize| g.format_marking(&automaton.marking(s));
            drn::write_drn(&model, &mut w, Some(&comment))
        }
        Problem::Drn { .. } => drn::write_drn(&model, &mut w, None),
    }
    .with_context(|| format!("writing {}", output.display()))?;
    std::io::Write::flush(&mut w).with_context(|| format!("writing {}", output.display()))?;
    Ok(model)
}

/// Runs a net under the policy in `policy_file` (`gspn solve --policy`).
pub fn with_policy(gspn: &Gspn, policy_file: &Path) -> Result<Gspn> {
    let policy = Policy::read_file(policy_file)?;
    Ok(gspn.with_policy(policy)?)
}
