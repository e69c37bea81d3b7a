//! Markov decision processes and Markov automata: the explicit models of
//! nets with decisions (docs/gspn.md, *Decisions*) and of Storm's DRN
//! files, and their optimal values and policies for PRISM/Storm-style
//! properties, with sound bounds.
//!
//! ```
//! use petri::mdp::{Model, ModelBuilder, ModelType, OptimizeParams, Property};
//!
//! // State 0 chooses: a fair coin to the goal or back, or a sure step to
//! // a trap.
//! let mut b = ModelBuilder::new(ModelType::Mdp, false);
//! b.state(0.0).row("coin").entry(0, 0.5).entry(1, 0.5).row("trap").entry(2, 1.0);
//! b.state(0.0).row("stay").entry(1, 1.0);
//! b.state(0.0).row("stay").entry(2, 1.0);
//! b.initial(vec![0]).label("goal", vec![false, true, false]);
//! let model = b.finish()?;
//! let best = model.check(&Property::parse(r#"Pmax=? [F "goal"]"#)?, &OptimizeParams::default())?;
//! assert!((best.value(0) - 1.0).abs() <= best.error_bound(0) + 1e-12);
//! assert_eq!(model.action_name(best.choice[0] as usize), "coin");
//! # Ok::<(), petri::Error>(())
//! ```
//!
//! | step | module |
//! |---|---|
//! | the model: states, rows, exit rates, labels, rewards | [`model`] |
//! | properties (`Pmax=? [F "goal"]`) | [`property`] |
//! | probability 0/1 sets, end components | [`graph`] |
//! | sound value iteration (interval, optimistic), topological | [`value_iteration`] |
//! | reachability and expected totals; policies | [`solve`] |
//! | long-run averages | `solve::lra` |
//! | Storm's DRN format | [`crate::io::drn`] |

pub mod graph;
pub mod model;
pub mod property;
pub mod solve;
pub mod value_iteration;

pub use model::{Model, ModelBuilder, ModelType, RewardVectors, StateLabel};
pub use property::{Direction, Property, Query, StateFormula};
pub use solve::{Goal, OptimizeParams, Optimum, optimize};
pub use value_iteration::Precision;

use crate::error::{Error, Result};
use crate::expr::Expr;
use crate::interrupt::Interrupt;

impl Model {
    /// States of an end component of probabilistic states (a Markov
    /// automaton's Zeno behaviour: choices made for ever in no time), if
    /// there is one.
    pub fn zeno_states(&self) -> Option<Vec<u32>> {
        if self.model_type != ModelType::MarkovAutomaton {
            return None;
        }
        let n = self.num_states();
        let instant: Vec<bool> = (0..n).map(|s| !self.is_markovian(s)).collect();
        let st = graph::Structure {
            row_start: &self.row_start,
            entry_start: &self.entry_start,
            col: &self.col,
        };
        let ecs = graph::mecs(&st, &instant, None);
        (ecs.count > 0).then(|| (0..n as u32).filter(|&s| ecs.of_state[s as usize] == 0).collect())
    }

    /// The states where a state formula over this model's labels holds
    /// (quoted names are labels; `true`, `false`, numbers and logic).
    pub fn satisfying(&self, property: &Property, formula: &StateFormula) -> Result<Vec<bool>> {
        let refuse = |message: String| Error::Property {
            text: property.text.clone(),
            message,
        };
        if let Some(name) = formula.as_label() {
            if let Some(l) = self.label(name) {
                return Ok(l.states.clone());
            }
        }
        let mut used: Vec<String> = Vec::new();
        let mut missing = None;
        formula.expr.for_each_param(&mut |n| {
            if matches!(n, "true" | "false") {
                return;
            }
            if self.label(n).is_some() {
                if !used.iter().any(|u| u == n) {
                    used.push(n.to_string());
                }
            } else if missing.is_none() {
                missing = Some(n.to_string());
            }
        });
        if let Some(name) = missing {
            let known: Vec<&str> = self.labels.iter().map(|l| l.name.as_str()).collect();
            return Err(refuse(format!(
                "the model has no label \"{name}\" (its labels: {})",
                if known.is_empty() {
                    "none".into()
                } else {
                    known.join(", ")
                }
            )));
        }
        let expr = formula.expr.substitute(&|n| match n {
            "true" => Some(Expr::Num(1.0)),
            "false" => Some(Expr::Num(0.0)),
            n => Some(Expr::Tokens(n.to_string())),
        });
        let compiled = expr
            .compile(&|n| used.iter().position(|u| u == n), &|_| None)
            .map_err(|e| refuse(format!("{e} (a model read from a file has labels, not places)")))?;
        let labels: Vec<&[bool]> = used
            .iter()
            .filter_map(|n| self.label(n).map(|l| l.states.as_slice()))
            .collect();
        let mut marking = vec![0u32; labels.len()];
        let mut stack = Vec::new();
        Ok((0..self.num_states())
            .map(|s| {
                for (m, l) in marking.iter_mut().zip(&labels) {
                    *m = u32::from(l[s]);
                }
                compiled.eval(&marking, &mut stack) != 0.0
            })
            .collect())
    }

    /// The reward model a property names (the only one when it names none).
    pub fn reward_model(&self, property: &Property) -> Result<&RewardVectors> {
        let refuse = |message: String| Error::Property {
            text: property.text.clone(),
            message,
        };
        let known = || {
            self.rewards
                .iter()
                .map(|r| r.name.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        };
        match property.reward_name() {
            Some(name) => self.rewards.iter().find(|r| r.name == name).ok_or_else(|| {
                refuse(format!(
                    "the model has no reward model \"{name}\" (its reward models: {})",
                    if self.rewards.is_empty() {
                        "none".into()
                    } else {
                        known()
                    }
                ))
            }),
            None => match self.rewards.as_slice() {
                [only] => Ok(only),
                [] => Err(refuse("the model has no reward model".into())),
                _ => Err(refuse(format!(
                    "name the reward model: R{{\"…\"}} (one of {})",
                    known()
                ))),
            },
        }
    }

    /// The property's direction, checked: a nondeterministic model needs
    /// `min` or `max`; a Markov chain takes either (they agree).
    pub fn direction(&self, property: &Property) -> Result<Direction> {
        match property.direction {
            Some(d) => Ok(d),
            None if self.model_type.is_nondeterministic() => Err(Error::Property {
                text: property.text.clone(),
                message: "this model has choices: say min or max (e.g. Pmax=?)".into(),
            }),
            None => Ok(Direction::Max),
        }
    }

    /// The goal a property sets on this model (labels resolved, reward
    /// models found).
    pub fn goal(&self, property: &Property) -> Result<Goal> {
        let n = self.num_states();
        let rows = self.num_rows();
        let reward_vectors = |r: &RewardVectors| {
            (
                r.state.clone().unwrap_or_else(|| vec![0.0; n]),
                r.action.clone().unwrap_or_else(|| vec![0.0; rows]),
            )
        };
        Ok(match &property.query {
            Query::Reach(phi) => Goal::Reach {
                target: self.satisfying(property, phi)?,
            },
            Query::Time(phi) => Goal::Total {
                target: self.satisfying(property, phi)?,
                state: vec![1.0; n],
                action: vec![0.0; rows],
            },
            Query::Reward(_, phi) => {
                let (state, action) = reward_vectors(self.reward_model(property)?);
                Goal::Total {
                    target: self.satisfying(property, phi)?,
                    state,
                    action,
                }
            }
            Query::RewardLra(_) => {
                let (state, action) = reward_vectors(self.reward_model(property)?);
                Goal::LongRun { state, action }
            }
            Query::Lra(phi) => Goal::LongRun {
                state: self
                    .satisfying(property, phi)?
                    .iter()
                    .map(|&b| if b { 1.0 } else { 0.0 })
                    .collect(),
                action: vec![0.0; rows],
            },
        })
    }

    /// Solves a property on this model: Zeno behaviour refused, the goal
    /// resolved, the optimum computed.
    pub fn check(&self, property: &Property, params: &OptimizeParams) -> Result<Optimum> {
        self.check_interruptible(property, params, Interrupt::NEVER)
    }

    /// [`check`](Self::check), stopped when `stop` is raised.
    pub fn check_interruptible(
        &self,
        property: &Property,
        params: &OptimizeParams,
        stop: Interrupt<'_>,
    ) -> Result<Optimum> {
        if let Some(states) = self.zeno_states() {
            return Err(Error::Zeno {
                count: states.len(),
                states: states
                    .iter()
                    .take(3)
                    .map(|s| format!("state {s}"))
                    .collect::<Vec<_>>()
                    .join(", "),
            });
        }
        let dir = self.direction(property)?;
        let goal = self.goal(property)?;
        optimize(self, &goal, dir, params, stop)
    }
}
