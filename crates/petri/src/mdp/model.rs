//! The explicit model every objective is solved on: a DTMC, CTMC, MDP or
//! Markov automaton (MA), as Storm's sparse models and its DRN files hold
//! them.
//!
//! States `0..n` are numbered; state `s` owns the rows (actions)
//! `row_start[s]..row_start[s + 1]`, each a sparse distribution over states.
//! In continuous time each state has an **exit rate**: a state with exit
//! rate `E > 0` is *Markovian* (one row; time passes, `Exp(E)`), a state of
//! an MA with `E = 0` is *probabilistic* (its rows are chosen by the policy
//! and take no time). A Markovian row holds either probabilities (Storm's
//! MA form) or rates summing to `E` (the CTMC form, [`Model::rate_rows`]);
//! the solvers read probabilities `rate / E` either way, so the two forms
//! of the same chain give the same bits.
//!
//! Rewards follow Storm: a **state reward** is earned per unit of time in
//! a Markovian state (per step in discrete time; nothing in a probabilistic
//! state), an **action reward** each time a row is taken.

use crate::error::{Error, Result};

/// Tolerance on a distribution's sum (`|Σ p − 1| ≤ 1e-6`, Storm's
/// default precision): files print probabilities with six digits.
pub const SUM_TOLERANCE: f64 = 1e-6;

/// The four kinds of model.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum ModelType {
    /// Discrete-time Markov chain: one row per state, a step per transition.
    Dtmc,
    /// Continuous-time Markov chain: one row per state, all Markovian.
    Ctmc,
    /// Markov decision process: rows chosen by the policy, a step each.
    Mdp,
    /// Markov automaton: Markovian states (one row, an exit rate) and
    /// probabilistic states (rows chosen by the policy, no time).
    MarkovAutomaton,
}

impl ModelType {
    /// Whether time is continuous (exit rates).
    pub fn is_continuous(self) -> bool {
        matches!(self, ModelType::Ctmc | ModelType::MarkovAutomaton)
    }

    /// Whether states may have several rows.
    pub fn is_nondeterministic(self) -> bool {
        matches!(self, ModelType::Mdp | ModelType::MarkovAutomaton)
    }

    /// The name DRN files use (`@type: …`).
    pub fn drn_name(self) -> &'static str {
        match self {
            ModelType::Dtmc => "DTMC",
            ModelType::Ctmc => "CTMC",
            ModelType::Mdp => "MDP",
            ModelType::MarkovAutomaton => "Markov Automaton",
        }
    }
}

/// A reward model's values on a [`Model`].
#[derive(Debug, Clone, PartialEq)]
pub struct RewardVectors {
    /// Its name.
    pub name: String,
    /// Per state (rate in continuous time, per step in discrete time).
    pub state: Option<Vec<f64>>,
    /// Per row (action).
    pub action: Option<Vec<f64>>,
}

/// A named set of states.
#[derive(Debug, Clone, PartialEq)]
pub struct StateLabel {
    /// Its name.
    pub name: String,
    /// Membership, per state.
    pub states: Vec<bool>,
}

/// An explicit DTMC, CTMC, MDP or Markov automaton (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct Model {
    pub(crate) model_type: ModelType,
    pub(crate) row_start: Vec<u32>,
    pub(crate) entry_start: Vec<u64>,
    pub(crate) col: Vec<u32>,
    pub(crate) val: Vec<f64>,
    pub(crate) exit_rate: Vec<f64>,
    pub(crate) rate_rows: bool,
    pub(crate) initial: Vec<u32>,
    pub(crate) labels: Vec<StateLabel>,
    pub(crate) rewards: Vec<RewardVectors>,
    /// Action names and each row's name (index into the names).
    pub(crate) action_names: Vec<String>,
    pub(crate) row_action: Vec<u32>,
}

/// Builds a [`Model`] state by state and row by row; [`ModelBuilder::finish`]
/// checks it ([`Model::validate`]).
#[derive(Debug, Clone)]
pub struct ModelBuilder {
    model: Model,
    names: std::collections::HashMap<String, u32>,
}

impl ModelBuilder {
    /// An empty model of type `model_type`; `rate_rows`: Markovian rows hold
    /// rates (the CTMC form) instead of probabilities.
    pub fn new(model_type: ModelType, rate_rows: bool) -> ModelBuilder {
        ModelBuilder {
            model: Model {
                model_type,
                row_start: vec![0],
                entry_start: vec![0],
                col: Vec::new(),
                val: Vec::new(),
                exit_rate: Vec::new(),
                rate_rows: rate_rows && model_type.is_continuous(),
                initial: Vec::new(),
                labels: Vec::new(),
                rewards: Vec::new(),
                action_names: Vec::new(),
                row_action: Vec::new(),
            },
            names: std::collections::HashMap::new(),
        }
    }

    /// Starts the next state; `exit_rate` for continuous-time models (0:
    /// probabilistic, MA only).
    pub fn state(&mut self, exit_rate: f64) -> &mut Self {
        if self.model.model_type.is_continuous() {
            self.model.exit_rate.push(exit_rate);
        }
        let rows = self.model.entry_start.len() as u32 - 1;
        self.model.row_start.push(rows);
        self
    }

    /// Starts a row of the current state, named `action`.
    pub fn row(&mut self, action: &str) -> &mut Self {
        let next = self.names.len() as u32;
        let id = *self.names.entry(action.to_string()).or_insert(next);
        if id == next {
            self.model.action_names.push(action.to_string());
        }
        self.model.row_action.push(id);
        let entries = self.model.col.len() as u64;
        self.model.entry_start.push(entries);
        if let Some(last) = self.model.row_start.last_mut() {
            *last += 1;
        }
        self
    }

    /// Adds an entry to the current row.
    pub fn entry(&mut self, target: u32, value: f64) -> &mut Self {
        self.model.col.push(target);
        self.model.val.push(value);
        if let Some(last) = self.model.entry_start.last_mut() {
            *last += 1;
        }
        self
    }

    /// Marks the initial states.
    pub fn initial(&mut self, states: Vec<u32>) -> &mut Self {
        self.model.initial = states;
        self
    }

    /// Adds a label.
    pub fn label(&mut self, name: &str, states: Vec<bool>) -> &mut Self {
        self.model.labels.push(StateLabel {
            name: name.into(),
            states,
        });
        self
    }

    /// Adds a reward model.
    pub fn reward(&mut self, reward: RewardVectors) -> &mut Self {
        self.model.rewards.push(reward);
        self
    }

    /// The model, checked ([`Model::validate`]).
    pub fn finish(self) -> Result<Model> {
        let m = self.model;
        m.validate()?;
        Ok(m)
    }
}

/// What is wrong with a model, for [`Model::validate`].
pub(crate) fn invalid(message: String) -> Error {
    Error::Invalid(format!("inconsistent model: {message}"))
}

impl Model {
    /// Assembles a model from its arrays (see the module docs), checked.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn from_parts(
        model_type: ModelType,
        row_start: Vec<u32>,
        entry_start: Vec<u64>,
        col: Vec<u32>,
        val: Vec<f64>,
        exit_rate: Vec<f64>,
        rate_rows: bool,
        initial: Vec<u32>,
    ) -> Model {
        let rows = entry_start.len().saturating_sub(1);
        Model {
            model_type,
            row_start,
            entry_start,
            col,
            val,
            exit_rate,
            rate_rows,
            initial,
            labels: Vec::new(),
            rewards: Vec::new(),
            action_names: Vec::new(),
            row_action: vec![u32::MAX; rows],
        }
    }

    /// Its type.
    pub fn model_type(&self) -> ModelType {
        self.model_type
    }

    /// Number of states.
    pub fn num_states(&self) -> usize {
        self.row_start.len() - 1
    }

    /// Number of rows (actions over all states).
    pub fn num_rows(&self) -> usize {
        self.entry_start.len() - 1
    }

    /// Number of entries.
    pub fn num_entries(&self) -> usize {
        self.col.len()
    }

    /// The rows of state `s`.
    #[inline]
    pub fn rows(&self, s: usize) -> std::ops::Range<usize> {
        self.row_start[s] as usize..self.row_start[s + 1] as usize
    }

    /// The entries of row `r`: `(target, value)` (a rate in a Markovian row
    /// of a [`rate_rows`](Self::rate_rows) model, else a probability).
    pub fn row_entries(&self, r: usize) -> impl Iterator<Item = (u32, f64)> + '_ {
        let (a, b) = (self.entry_start[r] as usize, self.entry_start[r + 1] as usize);
        self.col[a..b].iter().copied().zip(self.val[a..b].iter().copied())
    }

    /// Exit rate of state `s` (continuous time; 0 otherwise).
    pub fn exit_rate(&self, s: usize) -> f64 {
        self.exit_rate.get(s).copied().unwrap_or(0.0)
    }

    /// Whether Markovian rows hold rates (CTMC form).
    pub fn rate_rows(&self) -> bool {
        self.rate_rows
    }

    /// Whether state `s` is Markovian (continuous time, exit rate > 0).
    #[inline]
    pub fn is_markovian(&self, s: usize) -> bool {
        self.exit_rate.get(s).is_some_and(|&e| e > 0.0)
    }

    /// Initial states.
    pub fn initial_states(&self) -> &[u32] {
        &self.initial
    }

    /// Labels.
    pub fn labels(&self) -> &[StateLabel] {
        &self.labels
    }

    /// The label called `name`.
    pub fn label(&self, name: &str) -> Option<&StateLabel> {
        self.labels.iter().find(|l| l.name == name)
    }

    /// Reward models.
    pub fn rewards(&self) -> &[RewardVectors] {
        &self.rewards
    }

    /// Adds or replaces a label.
    pub fn set_label(&mut self, name: &str, states: Vec<bool>) {
        match self.labels.iter_mut().find(|l| l.name == name) {
            Some(l) => l.states = states,
            None => self.labels.push(StateLabel {
                name: name.into(),
                states,
            }),
        }
    }

    /// Adds or replaces a reward model.
    pub fn set_reward(&mut self, reward: RewardVectors) {
        match self.rewards.iter_mut().find(|r| r.name == reward.name) {
            Some(r) => *r = reward,
            None => self.rewards.push(reward),
        }
    }

    /// The name of row `r`'s action (its index in its state when unnamed).
    pub fn action_name(&self, r: usize) -> String {
        match self
            .row_action
            .get(r)
            .and_then(|&i| self.action_names.get(i as usize))
        {
            Some(n) => n.clone(),
            None => {
                let s = self.row_start.partition_point(|&x| x as usize <= r) - 1;
                (r - self.row_start[s] as usize).to_string()
            }
        }
    }

    /// Names the rows' actions: `names`, and each row's index into them.
    pub fn set_action_names(&mut self, names: Vec<String>, row_action: Vec<u32>) {
        self.action_names = names;
        self.row_action = row_action;
    }

    /// Heap bytes of the arrays.
    pub fn heap_bytes(&self) -> usize {
        self.row_start.capacity() * 4
            + self.entry_start.capacity() * 8
            + self.col.capacity() * 4
            + self.val.capacity() * 8
            + self.exit_rate.capacity() * 8
            + self.labels.iter().map(|l| l.states.capacity()).sum::<usize>()
            + self
                .rewards
                .iter()
                .map(|r| {
                    (r.state.as_ref().map_or(0, Vec::capacity) + r.action.as_ref().map_or(0, Vec::capacity))
                        * 8
                })
                .sum::<usize>()
            + self.row_action.capacity() * 4
    }

    /// Row `r`'s entries as `(target, probability)`, the probabilities as
    /// [`probabilities`](Self::probabilities) gives them, without building
    /// the whole vector (what a question about one row should cost).
    pub fn row_probabilities(&self, r: usize) -> impl Iterator<Item = (usize, f64)> + '_ {
        // The state owning row `r`: the last whose first row is ≤ r.
        let s = self.row_start.partition_point(|&x| x as usize <= r) - 1;
        let e = if self.rate_rows { self.exit_rate[s] } else { 0.0 };
        let (a, b) = (self.entry_start[r] as usize, self.entry_start[r + 1] as usize);
        (a..b).map(move |k| {
            let v = self.val[k];
            (self.col[k] as usize, if e > 0.0 { v / e } else { v })
        })
    }

    /// The probabilities of every entry: the values themselves, or for
    /// the Markovian rows of a [`rate_rows`](Self::rate_rows) model
    /// `rate / E`.
    pub fn probabilities(&self) -> std::borrow::Cow<'_, [f64]> {
        if !self.rate_rows {
            return std::borrow::Cow::Borrowed(&self.val);
        }
        let mut p = self.val.clone();
        for s in 0..self.num_states() {
            let e = self.exit_rate[s];
            if e > 0.0 {
                let (a, b) = (
                    self.entry_start[self.row_start[s] as usize] as usize,
                    self.entry_start[self.row_start[s + 1] as usize] as usize,
                );
                for (x, &v) in p[a..b].iter_mut().zip(&self.val[a..b]) {
                    *x = v / e;
                }
            }
        }
        std::borrow::Cow::Owned(p)
    }

    /// Checks the model's consistency: sizes, targets in range, values
    /// finite and ≥ 0, every state with a row (one if it is Markovian or
    /// the model deterministic), distributions summing to 1 (rates to the
    /// exit rate) within [`SUM_TOLERANCE`], initial states in range, labels
    /// and rewards of the right lengths.
    pub fn validate(&self) -> Result<()> {
        let n = self.num_states();
        let rows = self.num_rows();
        if self.row_start.first() != Some(&0) || self.row_start[n] as usize != rows {
            return Err(invalid("row groups do not cover the rows".into()));
        }
        if self.entry_start[rows] as usize != self.col.len() || self.col.len() != self.val.len() {
            return Err(invalid("rows do not cover the entries".into()));
        }
        if self.model_type.is_continuous() && self.exit_rate.len() != n {
            return Err(invalid(format!(
                "{} exit rates for {n} states",
                self.exit_rate.len()
            )));
        }
        for s in 0..n {
            self.check_state(s)?;
        }
        if let Some(&s) = self.initial.iter().find(|&&s| s as usize >= n) {
            return Err(invalid(format!("initial state {s} out of range (0..{n})")));
        }
        if let Some(l) = self.labels.iter().find(|l| l.states.len() != n) {
            return Err(invalid(format!(
                "label `{}` covers {} states of {n}",
                l.name,
                l.states.len()
            )));
        }
        for r in &self.rewards {
            let bad = |v: &Option<Vec<f64>>, len: usize| v.as_ref().is_some_and(|v| v.len() != len);
            if bad(&r.state, n) || bad(&r.action, rows) {
                return Err(invalid(format!("reward model `{}` has the wrong length", r.name)));
            }
            let values = r.state.iter().chain(r.action.iter()).flatten();
            if let Some(v) = values.copied().find(|v| !v.is_finite()) {
                return Err(invalid(format!("reward model `{}` has the value {v}", r.name)));
            }
        }
        Ok(())
    }

    fn check_state(&self, s: usize) -> Result<()> {
        let n = self.num_states();
        let rows = self.rows(s);
        let e = self.exit_rate(s);
        if !(e.is_finite() && e >= 0.0) {
            return Err(invalid(format!("state {s} has the exit rate {e}")));
        }
        if rows.is_empty() {
            return Err(invalid(format!("state {s} has no transition")));
        }
        let single = !self.model_type.is_nondeterministic() || self.is_markovian(s);
        if single && rows.len() > 1 {
            return Err(invalid(format!(
                "state {s} has {} actions; a {} has one per state",
                rows.len(),
                if self.model_type.is_nondeterministic() {
                    "Markovian state"
                } else {
                    "Markov chain"
                }
            )));
        }
        if self.model_type == ModelType::Ctmc && e == 0.0 {
            return Err(invalid(format!("state {s} of a CTMC has exit rate 0")));
        }
        for r in rows {
            let mut sum = 0.0;
            for (t, v) in self.row_entries(r) {
                if t as usize >= n {
                    return Err(invalid(format!(
                        "state {s} goes to state {t}, out of range (0..{n})"
                    )));
                }
                if !(v.is_finite() && v >= 0.0) {
                    return Err(invalid(format!("state {s} has the transition value {v}")));
                }
                sum += v;
            }
            let expected = if self.rate_rows && e > 0.0 { e } else { 1.0 };
            if (sum - expected).abs() > SUM_TOLERANCE * expected {
                return Err(invalid(format!(
                    "the {} of state {s}'s row {} sum to {sum}, not {expected}",
                    if expected == 1.0 && !(self.rate_rows && e > 0.0) {
                        "probabilities"
                    } else {
                        "rates"
                    },
                    r - self.row_start[s] as usize
                )));
            }
        }
        Ok(())
    }
}
