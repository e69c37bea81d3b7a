//! Nets with decisions as Markov automata (docs/gspn.md, *Decisions*),
//! compiled once and solved for any rates.
//!
//! [`DecisionNet::build`] generates the reachability graph and keeps three
//! kinds of marking as states of a Markov automaton:
//!
//! * **tangible** markings: Markovian states, their timed transitions
//!   racing as in the CTMC;
//! * **choice** markings, where a policy chooses ([`Gspn::is_choice`]):
//!   probabilistic states with one row per decision and, when transitions
//!   that are not decisions are enabled too, one row `random` in which
//!   those race by weight;
//! * the **initial** marking, even when it is vanishing (a probabilistic
//!   state with one row), so that every objective has one initial state.
//!
//! Every other vanishing marking is eliminated exactly as for the CTMC
//! (`vanishing.rs`), the elimination stopping at choice markings as at
//! tangible ones. Like [`CompiledGspn`](crate::CompiledGspn), the
//! Markovian rows are kept symbolically (`rate[t] · c`, `c` the server
//! factor times the eliminated paths' probability), so
//! [`DecisionNet::bind`] makes the numeric [`Model`] for new rates without
//! rebuilding anything, and [`DecisionNet::solve`] re-solves a
//! [`NetObjective`] prepared once.
//!
//! A set of choice markings in which the policy could choose for ever
//! without time passing is refused when building ([`Error::Zeno`]).

use crate::error::{Error, Result};
use crate::expr::Expr;
use crate::gspn::Gspn;
use crate::interrupt::Interrupt;
use crate::marking::MarkingStore;
use crate::mdp::{
    Direction, Goal, Model, ModelType, OptimizeParams, Optimum, Property, Query, RewardVectors,
};
use crate::net::{Params, TransitionId};
use crate::policy::{Action, Policy};
use crate::reachability::{ExploreParams, ReachabilityGraph};
use crate::vanishing;

const NONE: u32 = u32::MAX;

/// A net with decisions, compiled to a symbolic Markov automaton.
#[derive(Debug, Clone)]
pub struct DecisionNet {
    gspn: Gspn,
    store: MarkingStore,
    /// Graph index of each state's marking.
    state_rg: Vec<u32>,
    /// Whether each state is Markovian (a tangible marking).
    markovian: Vec<bool>,
    /// Markovian rows: per state, entries `(target, transition, coefficient)`
    /// sorted by target, then transition.
    m_start: Vec<u64>,
    m_target: Vec<u32>,
    m_trans: Vec<u32>,
    m_coeff: Vec<f64>,
    /// Immediate firings after a timed one (for impulse rewards): per
    /// state, `(transition, coefficient)` with the expected firings of each
    /// immediate transition on the eliminated path.
    flow_start: Vec<u64>,
    flow_trans: Vec<u32>,
    flow_coeff: Vec<f64>,
    flow_f_start: Vec<u64>,
    flow_f: Vec<(u32, f64)>,
    /// Probabilistic rows: per state, its actions.
    a_state_start: Vec<u32>,
    a_action: Vec<Action>,
    a_start: Vec<u64>,
    a_target: Vec<u32>,
    a_prob: Vec<f64>,
    /// Expected firings of each immediate transition when the action is
    /// taken (the transition chosen included).
    a_f_start: Vec<u64>,
    a_f: Vec<(u32, f64)>,
    /// Markings in the reachability graph (tangible and vanishing).
    reachable_markings: usize,
}

/// An objective prepared on a [`DecisionNet`]: everything that does not
/// depend on the rates (target markings, reward rates, impulses),
/// evaluated once.
#[derive(Debug, Clone)]
pub struct NetObjective {
    /// The property.
    pub property: Property,
    direction: Direction,
    kind: ObjectiveKind,
    target: Vec<bool>,
    /// Reward rate per state.
    state_reward: Vec<f64>,
    /// Impulse per transition.
    impulse: Vec<f64>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum ObjectiveKind {
    Reach,
    Total,
    LongRun,
}

/// One choice marking of a solution: what the policy does and what each
/// alternative is worth.
#[derive(Debug, Clone)]
pub struct ChoiceReport {
    /// The state in the model.
    pub state: usize,
    /// Its marking.
    pub marking: Vec<u32>,
    /// The action chosen.
    pub chosen: Action,
    /// Every action with the bounds of its value.
    pub alternatives: Vec<(Action, f64, f64)>,
}

/// The branches of an action: `(weight, target marking, transition)`.
type Branches = Vec<(f64, usize, u32)>;

/// A sparse row under construction: entries merged by key in order.
fn merge_sorted<K: Ord + Copy>(items: &mut [(K, f64)], out: &mut Vec<(K, f64)>) {
    items.sort_by_key(|a| a.0);
    out.clear();
    for &(k, v) in items.iter() {
        match out.last_mut() {
            Some(last) if last.0 == k => last.1 += v,
            _ => out.push((k, v)),
        }
    }
}

impl DecisionNet {
    /// Generates the state space of `gspn` and compiles its Markov
    /// automaton (see the module docs).
    pub fn build(gspn: &Gspn, explore: &ExploreParams) -> Result<DecisionNet> {
        Self::build_interruptible(gspn, explore, Interrupt::NEVER)
    }

    /// [`build`](Self::build), stopped when `stop` is raised.
    pub fn build_interruptible(
        gspn: &Gspn,
        explore: &ExploreParams,
        stop: Interrupt<'_>,
    ) -> Result<DecisionNet> {
        let rg = ReachabilityGraph::explore_interruptible(gspn, explore, stop)?;
        stop.check("compiling the Markov automaton")?;
        let n_rg = rg.num_markings();
        let mut firable = Vec::new();
        let mut kept_id = vec![NONE; n_rg];
        let mut state_rg = Vec::new();
        let mut choice = vec![false; n_rg];
        for i in 0..n_rg {
            if rg.vanishing[i] {
                firable.clear();
                let (a, b) = rg.range(i);
                firable.extend(rg.transitions[a..b].iter().map(|&t| TransitionId(t)));
                choice[i] = gspn.is_choice(&firable);
            }
            if !rg.vanishing[i] || i == 0 || choice[i] {
                kept_id[i] = state_rg.len() as u32;
                state_rg.push(i as u32);
            }
        }
        let el = vanishing::eliminate(gspn, &rg, &kept_id)?;
        let mut net = DecisionNet {
            gspn: gspn.clone(),
            store: MarkingStore::new(crate::marking::Layout::new(vec![1])),
            markovian: state_rg.iter().map(|&i| !rg.vanishing[i as usize]).collect(),
            state_rg,
            m_start: vec![0],
            m_target: Vec::new(),
            m_trans: Vec::new(),
            m_coeff: Vec::new(),
            flow_start: vec![0],
            flow_trans: Vec::new(),
            flow_coeff: Vec::new(),
            flow_f_start: vec![0],
            flow_f: Vec::new(),
            a_state_start: vec![0],
            a_action: Vec::new(),
            a_start: vec![0],
            a_target: Vec::new(),
            a_prob: Vec::new(),
            a_f_start: vec![0],
            a_f: Vec::new(),
            reachable_markings: n_rg,
        };
        for s in 0..net.state_rg.len() {
            let i = net.state_rg[s] as usize;
            if net.markovian[s] {
                net.markovian_row(&rg, &el, &kept_id, i);
            } else {
                net.probabilistic_rows(&rg, &el, &kept_id, i, choice[i]);
            }
            net.m_start.push(net.m_target.len() as u64);
            net.flow_start.push(net.flow_trans.len() as u64);
            net.a_state_start.push(net.a_action.len() as u32);
        }
        let mut store = rg.store;
        store.drop_index();
        net.store = store;
        net.check_zeno()?;
        Ok(net)
    }

    /// The symbolic Markovian row of graph marking `i`.
    fn markovian_row(&mut self, rg: &ReachabilityGraph, el: &vanishing::Elimination, kept: &[u32], i: usize) {
        let mut row: Vec<((u32, u32), f64)> = Vec::new();
        let (a, b) = rg.range(i);
        for k in a..b {
            let (w, t, c) = (rg.targets[k] as usize, rg.transitions[k], rg.coeff(k));
            if kept[w] != NONE {
                row.push(((kept[w], t), c));
                continue;
            }
            for &(u, q) in el.dist(w as u32) {
                row.push(((u, t), c * q));
            }
            let f = el.firings(w as u32);
            if !f.is_empty() {
                self.flow_trans.push(t);
                self.flow_coeff.push(c);
                self.flow_f.extend_from_slice(f);
                self.flow_f_start.push(self.flow_f.len() as u64);
            }
        }
        let mut merged = Vec::new();
        merge_sorted(&mut row, &mut merged);
        for ((u, t), c) in merged {
            self.m_target.push(u);
            self.m_trans.push(t);
            self.m_coeff.push(c);
        }
    }

    /// The actions of a kept vanishing marking `i`: one per decision and
    /// `random` (a choice marking), or the single random switch (the
    /// initial marking when it is vanishing and no choice).
    fn probabilistic_rows(
        &mut self,
        rg: &ReachabilityGraph,
        el: &vanishing::Elimination,
        kept: &[u32],
        i: usize,
        is_choice: bool,
    ) {
        let g = &self.gspn;
        let (a, b) = rg.range(i);
        let edges: Vec<(usize, u32)> = (a..b)
            .map(|k| (rg.targets[k] as usize, rg.transitions[k]))
            .collect();
        // (action, [(weight, target marking, transition)])
        let mut actions: Vec<(Action, Branches)> = Vec::new();
        if is_choice {
            for &(w, t) in &edges {
                if g.is_decision(TransitionId(t)) {
                    actions.push((Action::Fire(TransitionId(t)), vec![(1.0, w, t)]));
                }
            }
            let random: Vec<(f64, usize, u32)> = edges
                .iter()
                .filter(|&&(_, t)| !g.is_decision(TransitionId(t)))
                .map(|&(w, t)| (g.weight(TransitionId(t)).unwrap_or(1.0), w, t))
                .collect();
            if !random.is_empty() {
                actions.push((Action::Random, random));
            }
        } else {
            let all: Vec<(f64, usize, u32)> = (a..b)
                .map(|k| (rg.coeff(k), rg.targets[k] as usize, rg.transitions[k]))
                .collect();
            let label = match all.as_slice() {
                [(_, _, t)] if g.is_decision(TransitionId(*t)) => Action::Fire(TransitionId(*t)),
                _ => Action::Random,
            };
            actions.push((label, all));
        }
        let (mut dist, mut fires) = (Vec::new(), Vec::new());
        let (mut d_out, mut f_out) = (Vec::new(), Vec::new());
        for (action, branches) in actions {
            let total: f64 = branches.iter().map(|b| b.0).sum();
            dist.clear();
            fires.clear();
            for &(weight, w, t) in &branches {
                let q = weight / total;
                fires.push((t, q));
                if kept[w] != NONE {
                    dist.push((kept[w], q));
                } else {
                    dist.extend(el.dist(w as u32).iter().map(|&(u, p)| (u, q * p)));
                    fires.extend(el.firings(w as u32).iter().map(|&(u, f)| (u, q * f)));
                }
            }
            merge_sorted(&mut dist, &mut d_out);
            merge_sorted(&mut fires, &mut f_out);
            self.a_action.push(action);
            for &(u, p) in &d_out {
                self.a_target.push(u);
                self.a_prob.push(p);
            }
            self.a_start.push(self.a_target.len() as u64);
            self.a_f.extend_from_slice(&f_out);
            self.a_f_start.push(self.a_f.len() as u64);
        }
    }

    /// Refuses an end component of probabilistic states ([`Error::Zeno`]),
    /// naming its markings.
    fn check_zeno(&self) -> Result<()> {
        let rates = vec![1.0; self.gspn.num_transitions()];
        let model = self.bind_numbers(&rates)?;
        if let Some(states) = model.zeno_states() {
            let shown: Vec<String> = states
                .iter()
                .take(3)
                .map(|&s| format!("[{}]", self.gspn.format_marking(&self.marking(s as usize))))
                .collect();
            return Err(Error::Zeno {
                count: states.len(),
                states: shown.join(", "),
            });
        }
        Ok(())
    }

    /// The instantiated net.
    pub fn gspn(&self) -> &Gspn {
        &self.gspn
    }

    /// Number of states of the automaton.
    pub fn num_states(&self) -> usize {
        self.state_rg.len()
    }

    /// Markings of the reachability graph (tangible and vanishing).
    pub fn reachable_markings(&self) -> usize {
        self.reachable_markings
    }

    /// Number of choice states (two actions or more).
    pub fn num_choices(&self) -> usize {
        (0..self.num_states())
            .filter(|&s| self.a_state_start[s + 1] - self.a_state_start[s] >= 2)
            .count()
    }

    /// Whether state `s` is Markovian (a tangible marking).
    pub fn is_markovian(&self, s: usize) -> bool {
        self.markovian[s]
    }

    /// The marking of state `s`.
    pub fn marking(&self, s: usize) -> Vec<u32> {
        let mut m = vec![0; self.gspn.num_places()];
        self.store.decode(self.state_rg[s] as usize, &mut m);
        m
    }

    /// The actions of state `s` (empty for a Markovian state).
    pub fn actions(&self, s: usize) -> &[Action] {
        &self.a_action[self.a_state_start[s] as usize..self.a_state_start[s + 1] as usize]
    }

    /// The numeric model for `rates` (by transition, as
    /// [`Gspn::rates`] gives them), without labels or rewards.
    fn bind_numbers(&self, rates: &[f64]) -> Result<Model> {
        let n = self.num_states();
        let any_probabilistic = self.markovian.iter().any(|&m| !m);
        let model_type = if any_probabilistic {
            ModelType::MarkovAutomaton
        } else {
            ModelType::Ctmc
        };
        let mut row_start = Vec::with_capacity(n + 1);
        let mut entry_start = Vec::with_capacity(n + 1);
        let (mut col, mut val) = (Vec::new(), Vec::new());
        let mut exit = Vec::with_capacity(n);
        let mut names: Vec<String> = Vec::new();
        let mut row_action = Vec::new();
        let mut name_of = std::collections::HashMap::new();
        let mut name_id = |a: Action, names: &mut Vec<String>| -> u32 {
            *name_of.entry(a).or_insert_with(|| {
                names.push(a.describe(&self.gspn));
                names.len() as u32 - 1
            })
        };
        row_start.push(0u32);
        entry_start.push(0u64);
        for s in 0..n {
            if self.markovian[s] {
                let (a, b) = (self.m_start[s] as usize, self.m_start[s + 1] as usize);
                let mut e = 0.0;
                let mut k = a;
                while k < b {
                    let target = self.m_target[k];
                    let mut v = 0.0;
                    while k < b && self.m_target[k] == target {
                        v += rates[self.m_trans[k] as usize] * self.m_coeff[k];
                        k += 1;
                    }
                    if !v.is_finite() {
                        return Err(Error::NotFinite {
                            what: format!(
                                "the rate out of marking [{}]",
                                self.gspn.format_marking(&self.marking(s))
                            ),
                            value: v,
                            cause: "a rate times its enabling degree exceeds the largest double".into(),
                        });
                    }
                    col.push(target);
                    val.push(v);
                    e += v;
                }
                if a == b {
                    // A dead marking: time passes for ever (a self-loop).
                    col.push(s as u32);
                    val.push(1.0);
                    e = 1.0;
                }
                exit.push(e);
                row_action.push(NONE);
                entry_start.push(col.len() as u64);
            } else {
                exit.push(0.0);
                for r in self.a_state_start[s] as usize..self.a_state_start[s + 1] as usize {
                    for k in self.a_start[r] as usize..self.a_start[r + 1] as usize {
                        col.push(self.a_target[k]);
                        val.push(self.a_prob[k]);
                    }
                    row_action.push(name_id(self.a_action[r], &mut names));
                    entry_start.push(col.len() as u64);
                }
            }
            row_start.push(entry_start.len() as u32 - 1);
        }
        let mut model = Model::from_parts(model_type, row_start, entry_start, col, val, exit, true, vec![0]);
        // Markovian rows: named by nothing (DRN prints their index).
        let timed = names.len() as u32;
        if row_action.contains(&NONE) {
            names.push("0".into());
        }
        for r in &mut row_action {
            if *r == NONE {
                *r = timed;
            }
        }
        model.set_action_names(names, row_action);
        Ok(model)
    }

    /// The timed transitions' rates from the net's parameters with
    /// `overrides` (see [`Gspn::rates`]).
    pub fn rates(&self, overrides: &Params, default_rate: Option<f64>) -> Result<Vec<f64>> {
        self.gspn.rates(overrides, default_rate)
    }

    /// The numeric Markov automaton (a CTMC when no state is
    /// probabilistic) for `rates`, with the net's labels (and `init`) and
    /// reward models: what `gspn convert NET file.drn` writes.
    pub fn bind(&self, rates: &[f64]) -> Result<Model> {
        self.check_rates(rates)?;
        let mut model = self.bind_numbers(rates)?;
        let n = self.num_states();
        let mut init = vec![false; n];
        init[0] = true;
        model.set_label("init", init);
        let markings: Vec<Vec<u32>> = (0..n).map(|s| self.marking(s)).collect();
        for l in self.gspn.labels() {
            let compiled = self.gspn.compile_expr(&l.expr)?;
            let mut stack = Vec::new();
            let states = markings
                .iter()
                .map(|m| compiled.eval(m, &mut stack) != 0.0)
                .collect();
            model.set_label(&l.name, states);
        }
        for r in self.gspn.rewards() {
            let (state, impulse) = self.reward_values(&r.name)?;
            model.set_reward(RewardVectors {
                name: r.name.clone(),
                state: r.rate.as_ref().map(|_| state),
                action: (!r.impulses.is_empty()).then(|| self.action_rewards(&model, rates, &impulse)),
            });
        }
        Ok(model)
    }

    fn check_rates(&self, rates: &[f64]) -> Result<()> {
        if rates.len() != self.gspn.num_transitions() {
            return Err(Error::Invalid(format!(
                "{} rates given for {} transitions",
                rates.len(),
                self.gspn.num_transitions()
            )));
        }
        for &t in &self.m_trans {
            let r = rates[t as usize];
            if !(r.is_finite() && r > 0.0) {
                return Err(Error::InvalidValue {
                    element: format!("timed transition `{}`", self.gspn.transition_names()[t as usize]),
                    what: "the rate",
                    requirement: "a finite number > 0",
                    value: r,
                });
            }
        }
        Ok(())
    }

    /// A reward model's rate in each state (0 in probabilistic states) and
    /// impulse per transition.
    fn reward_values(&self, name: &str) -> Result<(Vec<f64>, Vec<f64>)> {
        let r = self
            .gspn
            .rewards()
            .iter()
            .find(|r| r.name == name)
            .ok_or_else(|| Error::Invalid(format!("the net has no reward model `{name}`")))?;
        let n = self.num_states();
        let mut state = vec![0.0; n];
        if let Some(rate) = &r.rate {
            let compiled = self.gspn.compile_expr(rate)?;
            let mut stack = Vec::new();
            for (s, v) in state.iter_mut().enumerate() {
                if self.markovian[s] {
                    let m = self.marking(s);
                    *v = compiled.eval(&m, &mut stack);
                    if !v.is_finite() {
                        return Err(Error::NotFinite {
                            what: format!(
                                "the reward rate `{rate}` of `{name}` in marking [{}]",
                                self.gspn.format_marking(&m)
                            ),
                            value: *v,
                            cause: "the expression divides by zero or overflows there".into(),
                        });
                    }
                }
            }
        }
        let mut impulse = vec![0.0; self.gspn.num_transitions()];
        for (t, e) in &r.impulses {
            let context = format!(
                "the impulse of `{}` in reward model `{name}`",
                self.gspn.transition_names()[t.index()]
            );
            impulse[t.index()] =
                e.eval_params(&|p| self.gspn.params().get(p).copied().flatten(), &context)?;
        }
        Ok((state, impulse))
    }

    /// The expected impulse of each row: in a Markovian row, over the
    /// timed transition that fires and the immediate ones that follow; in
    /// a probabilistic row, over the immediate transitions it fires.
    fn action_rewards(&self, model: &Model, rates: &[f64], impulse: &[f64]) -> Vec<f64> {
        let mut out = vec![0.0; model.num_rows()];
        let worth = |f: &[(u32, f64)]| f.iter().map(|&(u, c)| c * impulse[u as usize]).sum::<f64>();
        for s in 0..self.num_states() {
            let rows = model.rows(s);
            if self.markovian[s] {
                let e = model.exit_rate(s);
                let (a, b) = (self.m_start[s] as usize, self.m_start[s + 1] as usize);
                let mut v = 0.0;
                for k in a..b {
                    let t = self.m_trans[k] as usize;
                    v += rates[t] * self.m_coeff[k] / e * impulse[t];
                }
                let (fa, fb) = (self.flow_start[s] as usize, self.flow_start[s + 1] as usize);
                for f in fa..fb {
                    let t = self.flow_trans[f] as usize;
                    let firings =
                        &self.flow_f[self.flow_f_start[f] as usize..self.flow_f_start[f + 1] as usize];
                    v += rates[t] * self.flow_coeff[f] / e * worth(firings);
                }
                out[rows.start] = v;
            } else {
                for (r, a) in rows.zip(self.a_state_start[s] as usize..) {
                    out[r] = worth(&self.a_f[self.a_f_start[a] as usize..self.a_f_start[a + 1] as usize]);
                }
            }
        }
        out
    }

    /// The states where a state formula holds: quoted names are the net's
    /// labels, `#P` token counts, bare names parameters, `true` and
    /// `false` what they say.
    pub fn satisfying(&self, property: &Property, phi: &crate::mdp::StateFormula) -> Result<Vec<bool>> {
        let labels = self.gspn.labels();
        let expr = phi.expr.substitute(&|n| {
            if let Some(l) = labels.iter().find(|l| l.name == n) {
                return Some(l.expr.clone());
            }
            match n {
                "true" => Some(Expr::Num(1.0)),
                "false" => Some(Expr::Num(0.0)),
                _ => None,
            }
        });
        let mut unknown = None;
        expr.for_each_param(&mut |n| {
            if unknown.is_none() && !matches!(self.gspn.params().get(n), Some(Some(_))) {
                unknown = Some(n.to_string());
            }
        });
        let refuse = |message: String| Error::Property {
            text: property.text.clone(),
            message,
        };
        if let Some(name) = unknown {
            let known: Vec<&str> = labels.iter().map(|l| l.name.as_str()).collect();
            return Err(refuse(format!(
                "\"{name}\" is neither a label of the net (its labels: {}) nor a parameter with a value",
                if known.is_empty() {
                    "none".into()
                } else {
                    known.join(", ")
                }
            )));
        }
        let compiled = self.gspn.compile_expr(&expr).map_err(|e| refuse(e.to_string()))?;
        let mut stack = Vec::new();
        let mut m = vec![0; self.gspn.num_places()];
        Ok((0..self.num_states())
            .map(|s| {
                self.store.decode(self.state_rg[s] as usize, &mut m);
                compiled.eval(&m, &mut stack) != 0.0
            })
            .collect())
    }

    /// Prepares a property for repeated solves ([`DecisionNet::solve`]):
    /// target markings and rewards evaluated once.
    pub fn objective(&self, property: &Property) -> Result<NetObjective> {
        let direction = match property.direction {
            Some(d) => d,
            None if self.num_choices() > 0 => {
                return Err(Error::Property {
                    text: property.text.clone(),
                    message: "the net has decisions: say min or max (e.g. Pmax=?)".into(),
                });
            }
            None => Direction::Max,
        };
        let n = self.num_states();
        let nt = self.gspn.num_transitions();
        let reward = |name: Option<&str>| -> Result<(Vec<f64>, Vec<f64>)> {
            let rewards = self.gspn.rewards();
            let model = match name {
                Some(name) => rewards.iter().find(|r| r.name == name),
                None if rewards.len() == 1 => rewards.first(),
                None => None,
            };
            let Some(model) = model else {
                let known: Vec<&str> = rewards.iter().map(|r| r.name.as_str()).collect();
                return Err(Error::Property {
                    text: property.text.clone(),
                    message: match name {
                        Some(name) => format!(
                            "the net has no reward model \"{name}\" (its reward models: {})",
                            if known.is_empty() {
                                "none".into()
                            } else {
                                known.join(", ")
                            }
                        ),
                        None if known.is_empty() => {
                            "the net has no reward model ([rewards.NAME] in TOML)".into()
                        }
                        None => format!("name the reward model: R{{\"…\"}} (one of {})", known.join(", ")),
                    },
                });
            };
            self.reward_values(&model.name)
        };
        let (kind, target, state_reward, impulse) = match &property.query {
            Query::Reach(phi) => (
                ObjectiveKind::Reach,
                self.satisfying(property, phi)?,
                Vec::new(),
                Vec::new(),
            ),
            Query::Time(phi) => (
                ObjectiveKind::Total,
                self.satisfying(property, phi)?,
                vec![1.0; n],
                vec![0.0; nt],
            ),
            Query::Reward(name, phi) => {
                let (s, i) = reward(name.as_deref())?;
                (ObjectiveKind::Total, self.satisfying(property, phi)?, s, i)
            }
            Query::RewardLra(name) => {
                let (s, i) = reward(name.as_deref())?;
                (ObjectiveKind::LongRun, Vec::new(), s, i)
            }
            Query::Lra(phi) => {
                let inside = self.satisfying(property, phi)?;
                (
                    ObjectiveKind::LongRun,
                    Vec::new(),
                    inside.iter().map(|&b| if b { 1.0 } else { 0.0 }).collect(),
                    vec![0.0; nt],
                )
            }
        };
        Ok(NetObjective {
            property: property.clone(),
            direction,
            kind,
            target,
            state_reward,
            impulse,
        })
    }

    /// Binds `rates` and solves a prepared objective: the fast path for
    /// re-solving with new rates (nothing structural is rebuilt).
    pub fn solve(
        &self,
        objective: &NetObjective,
        rates: &[f64],
        params: &OptimizeParams,
    ) -> Result<(Model, Optimum)> {
        self.solve_interruptible(objective, rates, params, Interrupt::NEVER)
    }

    /// [`solve`](Self::solve), stopped when `stop` is raised.
    pub fn solve_interruptible(
        &self,
        objective: &NetObjective,
        rates: &[f64],
        params: &OptimizeParams,
        stop: Interrupt<'_>,
    ) -> Result<(Model, Optimum)> {
        self.check_rates(rates)?;
        let model = self.bind_numbers(rates)?;
        let goal = match objective.kind {
            ObjectiveKind::Reach => Goal::Reach {
                target: objective.target.clone(),
            },
            ObjectiveKind::Total => Goal::Total {
                target: objective.target.clone(),
                state: objective.state_reward.clone(),
                action: self.action_rewards(&model, rates, &objective.impulse),
            },
            ObjectiveKind::LongRun => Goal::LongRun {
                state: objective.state_reward.clone(),
                action: self.action_rewards(&model, rates, &objective.impulse),
            },
        };
        let optimum = crate::mdp::optimize(&model, &goal, objective.direction, params, stop)?;
        Ok((model, optimum))
    }

    /// Every choice state of a solution: the action taken and the bounds
    /// of each alternative's value.
    pub fn choices(&self, model: &Model, optimum: &Optimum) -> Vec<ChoiceReport> {
        (0..self.num_states())
            .filter(|&s| self.actions(s).len() >= 2)
            .map(|s| {
                let rows = model.rows(s);
                let first = rows.start;
                let alternatives = rows
                    .map(|r| {
                        let (l, u) = optimum.row_bounds(model, r);
                        (self.actions(s)[r - first], l, u)
                    })
                    .collect();
                ChoiceReport {
                    state: s,
                    marking: self.marking(s),
                    chosen: self.actions(s)[optimum.choice[s] as usize - first],
                    alternatives,
                }
            })
            .collect()
    }

    /// The policy of a solution as a [`Policy`] (every choice marking).
    pub fn policy(&self, optimum: &Optimum, model: &Model, objective: Option<&str>) -> Policy {
        let mut p = Policy::new(self.gspn.name(), objective);
        for c in self.choices(model, optimum) {
            p.set(&self.gspn, &c.marking, c.chosen);
        }
        p
    }
}
