//! The net as a modeller writes it: places, transitions and arcs whose
//! markings, multiplicities, rates and weights may be expressions over named
//! parameters. Files are read into and written from this form; analysis works
//! on its instantiation, [`Gspn`](crate::Gspn).

use std::collections::BTreeMap;

use crate::error::{Error, Result};
use crate::expr::Expr;

/// Index of a place in its net.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, serde::Serialize)]
pub struct PlaceId(pub u32);

/// Index of a transition in its net.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, serde::Serialize)]
pub struct TransitionId(pub u32);

impl PlaceId {
    /// As a `usize` index.
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

impl TransitionId {
    /// As a `usize` index.
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

/// Whether a parameter is meant to hold whole numbers (markings,
/// multiplicities) or reals (rates, weights).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ParamKind {
    /// Whole numbers.
    Int,
    /// Real numbers.
    #[default]
    Real,
}

/// A named parameter. Without a value it must be bound before analysis
/// (GreatSPN calls such a parameter a *template*).
#[derive(Debug, Clone, PartialEq)]
pub struct Param {
    /// Its name.
    pub name: String,
    /// Its value, if the model gives one.
    pub value: Option<f64>,
    /// Integer or real.
    pub kind: ParamKind,
    /// A value suggested by the file for information only (GreatSPN's
    /// `last-binding` or a measure assignment); never used silently.
    pub suggested: Option<f64>,
    /// Free text.
    pub doc: Option<String>,
}

/// A place.
#[derive(Debug, Clone, PartialEq)]
pub struct Place {
    /// Unique name.
    pub name: String,
    /// Initial token count (an expression over parameters).
    pub initial: Expr,
    /// Optional capacity: transitions that would put more tokens are disabled.
    pub capacity: Option<u32>,
    /// Layout position, if the file has one.
    pub position: Option<(f64, f64)>,
    /// Free text.
    pub doc: Option<String>,
}

/// Server semantics of a timed transition: its rate in marking `M` is
/// `λ · min(enabling degree, k)` with `k` = 1, `k`, or ∞.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Servers {
    /// One server: the rate does not depend on the enabling degree.
    #[default]
    Single,
    /// `k` servers.
    K(u32),
    /// As many servers as the enabling degree.
    Infinite,
}

/// Timed or immediate, with the attributes that go with it.
#[derive(Debug, Clone, PartialEq)]
pub enum TransitionKind {
    /// Exponentially distributed firing delay.
    Timed {
        /// Rate λ > 0; `None` for plain P/T nets that carry no rates.
        rate: Option<Expr>,
        /// Server semantics.
        servers: Servers,
    },
    /// Fires in zero time.
    Immediate {
        /// Weight w > 0 among the enabled immediate transitions of the same priority.
        weight: Expr,
        /// Priority level π ≥ 1; higher levels pre-empt lower ones.
        priority: Expr,
    },
}

/// A transition.
#[derive(Debug, Clone, PartialEq)]
pub struct Transition {
    /// Unique name.
    pub name: String,
    /// Timed or immediate.
    pub kind: TransitionKind,
    /// A **decision** (immediate transitions only): where it is enabled at
    /// the highest priority, a policy chooses whether it fires instead of
    /// chance (docs/gspn.md, *Decisions*). Its weight plays no part.
    pub decision: bool,
    /// Layout position, if the file has one.
    pub position: Option<(f64, f64)>,
    /// Free text.
    pub doc: Option<String>,
}

impl Transition {
    /// Whether it is immediate.
    pub fn is_immediate(&self) -> bool {
        matches!(self.kind, TransitionKind::Immediate { .. })
    }
}

/// A named set of markings (a *label*, as PRISM and Storm call it): the
/// markings where `expr`, an expression over token counts, is non-zero.
/// Properties name it in quotes (`Pmax=? [F "goal"]`).
#[derive(Debug, Clone, PartialEq)]
pub struct Label {
    /// Its name.
    pub name: String,
    /// The condition, e.g. `#P3 = 1`.
    pub expr: Expr,
}

/// A reward model: a **rate** earned per unit of time spent in a tangible
/// marking (an expression over token counts and parameters) and
/// **impulses** earned each time a transition fires (expressions over
/// parameters). Properties name it: `R{"cost"}min=? [F "goal"]`.
#[derive(Debug, Clone, PartialEq)]
pub struct RewardModel {
    /// Its name.
    pub name: String,
    /// Reward per unit of time in a marking, if any.
    pub rate: Option<Expr>,
    /// Reward per firing, by transition.
    pub impulses: Vec<(TransitionId, Expr)>,
}

/// The three kinds of arc.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum ArcKind {
    /// Place → transition: tokens consumed.
    Input,
    /// Transition → place: tokens produced.
    Output,
    /// Place ⊸ transition: the transition is enabled only while the place
    /// holds fewer tokens than the multiplicity.
    Inhibitor,
}

impl ArcKind {
    /// Lower-case name.
    pub fn name(self) -> &'static str {
        match self {
            ArcKind::Input => "input",
            ArcKind::Output => "output",
            ArcKind::Inhibitor => "inhibitor",
        }
    }
}

/// An arc between a place and a transition.
#[derive(Debug, Clone, PartialEq)]
pub struct Arc {
    /// Input, output or inhibitor.
    pub kind: ArcKind,
    /// The place.
    pub place: PlaceId,
    /// The transition.
    pub transition: TransitionId,
    /// Multiplicity ≥ 1 (an expression over parameters).
    pub multiplicity: Expr,
}

/// A Generalized Stochastic Petri Net as written in a model file.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Net {
    /// The model's name.
    pub name: String,
    /// Named parameters, in file order.
    pub params: Vec<Param>,
    /// Places; a [`PlaceId`] indexes this.
    pub places: Vec<Place>,
    /// Transitions; a [`TransitionId`] indexes this.
    pub transitions: Vec<Transition>,
    /// Arcs.
    pub arcs: Vec<Arc>,
    /// Named sets of markings, in file order.
    pub labels: Vec<Label>,
    /// Reward models, in file order.
    pub rewards: Vec<RewardModel>,
    /// Free text.
    pub doc: Option<String>,
}

/// Values for parameters, e.g. from `--param NAME=VALUE`.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Params(pub BTreeMap<String, f64>);

impl Params {
    /// No values.
    pub fn new() -> Params {
        Params::default()
    }

    /// Adds or replaces a value (builder style).
    pub fn with(mut self, name: impl Into<String>, value: f64) -> Params {
        self.0.insert(name.into(), value);
        self
    }

    /// Adds or replaces a value.
    pub fn set(&mut self, name: impl Into<String>, value: f64) {
        self.0.insert(name.into(), value);
    }

    /// The value of `name`, if given.
    pub fn get(&self, name: &str) -> Option<f64> {
        self.0.get(name).copied()
    }

    /// Parses assignments `NAME=VALUE` (the value may be an expression over
    /// numbers, e.g. `lambda7=1/122.33`).
    pub fn parse_assignments<S: AsRef<str>>(items: &[S]) -> Result<Params> {
        let mut out = Params::new();
        for item in items {
            let text = item.as_ref();
            let (name, value) = text.split_once('=').ok_or_else(|| Error::BadAssignment {
                text: text.into(),
                message: "expected NAME=VALUE".into(),
            })?;
            let name = name.trim();
            if name.is_empty() {
                return Err(Error::BadAssignment {
                    text: text.into(),
                    message: "the name is empty".into(),
                });
            }
            let expr = Expr::parse(value).map_err(|e| Error::BadAssignment {
                text: text.into(),
                message: e.to_string(),
            })?;
            let v = expr
                .eval_params(&|_| None, name)
                .map_err(|e| Error::BadAssignment {
                    text: text.into(),
                    message: e.to_string(),
                })?;
            if !v.is_finite() {
                return Err(Error::BadAssignment {
                    text: text.into(),
                    message: format!("the value {v} is not finite"),
                });
            }
            out.set(name, v);
        }
        Ok(out)
    }
}

impl Net {
    /// An empty net.
    pub fn new(name: impl Into<String>) -> Net {
        Net {
            name: name.into(),
            ..Net::default()
        }
    }

    /// The place called `name`.
    pub fn place_id(&self, name: &str) -> Option<PlaceId> {
        self.places
            .iter()
            .position(|p| p.name == name)
            .map(|i| PlaceId(i as u32))
    }

    /// The transition called `name`.
    pub fn transition_id(&self, name: &str) -> Option<TransitionId> {
        self.transitions
            .iter()
            .position(|t| t.name == name)
            .map(|i| TransitionId(i as u32))
    }

    /// The parameter called `name`.
    pub fn param(&self, name: &str) -> Option<&Param> {
        self.params.iter().find(|p| p.name == name)
    }

    /// Adds a place with a numeric initial marking.
    pub fn add_place(&mut self, name: impl Into<String>, initial: impl Into<Expr>) -> PlaceId {
        self.places.push(Place {
            name: name.into(),
            initial: initial.into(),
            capacity: None,
            position: None,
            doc: None,
        });
        PlaceId(self.places.len() as u32 - 1)
    }

    /// Adds a timed transition with a single server.
    pub fn add_timed(&mut self, name: impl Into<String>, rate: impl Into<Expr>) -> TransitionId {
        self.add_transition(
            name,
            TransitionKind::Timed {
                rate: Some(rate.into()),
                servers: Servers::Single,
            },
        )
    }

    /// Adds an immediate transition.
    pub fn add_immediate(
        &mut self,
        name: impl Into<String>,
        weight: impl Into<Expr>,
        priority: u32,
    ) -> TransitionId {
        self.add_transition(
            name,
            TransitionKind::Immediate {
                weight: weight.into(),
                priority: Expr::from(priority),
            },
        )
    }

    /// Adds a transition of any kind.
    pub fn add_transition(&mut self, name: impl Into<String>, kind: TransitionKind) -> TransitionId {
        self.transitions.push(Transition {
            name: name.into(),
            kind,
            decision: false,
            position: None,
            doc: None,
        });
        TransitionId(self.transitions.len() as u32 - 1)
    }

    /// Adds a decision: an immediate transition that a policy chooses
    /// (weight 1, which plays no part).
    pub fn add_decision(&mut self, name: impl Into<String>, priority: u32) -> TransitionId {
        let t = self.add_immediate(name, 1.0, priority);
        self.transitions[t.index()].decision = true;
        t
    }

    /// Whether the net has a decision transition.
    pub fn has_decisions(&self) -> bool {
        self.transitions.iter().any(|t| t.decision)
    }

    /// Adds (or replaces) a label: the markings where `expr` holds.
    pub fn add_label(&mut self, name: impl Into<String>, expr: Expr) {
        let name = name.into();
        match self.labels.iter_mut().find(|l| l.name == name) {
            Some(l) => l.expr = expr,
            None => self.labels.push(Label { name, expr }),
        }
    }

    /// The label called `name`.
    pub fn label(&self, name: &str) -> Option<&Label> {
        self.labels.iter().find(|l| l.name == name)
    }

    /// Adds (or replaces) a reward model.
    pub fn add_reward(&mut self, reward: RewardModel) {
        match self.rewards.iter_mut().find(|r| r.name == reward.name) {
            Some(r) => *r = reward,
            None => self.rewards.push(reward),
        }
    }

    /// Sets the server semantics of a timed transition (no effect on immediate ones).
    pub fn set_servers(&mut self, t: TransitionId, s: Servers) {
        if let TransitionKind::Timed { servers, .. } = &mut self.transitions[t.index()].kind {
            *servers = s;
        }
    }

    /// Adds an arc.
    pub fn add_arc(
        &mut self,
        kind: ArcKind,
        place: PlaceId,
        transition: TransitionId,
        multiplicity: impl Into<Expr>,
    ) {
        self.arcs.push(Arc {
            kind,
            place,
            transition,
            multiplicity: multiplicity.into(),
        });
    }

    /// Adds an input arc of multiplicity 1.
    pub fn input(&mut self, place: PlaceId, transition: TransitionId) {
        self.add_arc(ArcKind::Input, place, transition, 1u32);
    }

    /// Adds an output arc of multiplicity 1.
    pub fn output(&mut self, transition: TransitionId, place: PlaceId) {
        self.add_arc(ArcKind::Output, place, transition, 1u32);
    }

    /// Adds an inhibitor arc of multiplicity 1.
    pub fn inhibitor(&mut self, place: PlaceId, transition: TransitionId) {
        self.add_arc(ArcKind::Inhibitor, place, transition, 1u32);
    }

    /// Declares a parameter with a default value (replacing an earlier one).
    pub fn set_param(&mut self, name: impl Into<String>, value: Option<f64>, kind: ParamKind) {
        let name = name.into();
        if let Some(p) = self.params.iter_mut().find(|p| p.name == name) {
            p.value = value;
            p.kind = kind;
        } else {
            self.params.push(Param {
                name,
                value,
                kind,
                suggested: None,
                doc: None,
            });
        }
    }

    /// A copy without the named transition and its arcs (e.g. a branch of
    /// weight 0 that must be left out).
    pub fn without_transition(&self, name: &str) -> Result<Net> {
        let t = self.transition_id(name).ok_or_else(|| Error::UnknownName {
            kind: "transition",
            name: name.into(),
        })?;
        let mut net = self.clone();
        net.transitions.remove(t.index());
        net.arcs.retain(|a| a.transition != t);
        for a in &mut net.arcs {
            if a.transition.0 > t.0 {
                a.transition.0 -= 1;
            }
        }
        for r in &mut net.rewards {
            r.impulses.retain(|(u, _)| *u != t);
            for (u, _) in &mut r.impulses {
                if u.0 > t.0 {
                    u.0 -= 1;
                }
            }
        }
        Ok(net)
    }

    /// Checks names and arc endpoints.
    pub fn validate(&self) -> Result<()> {
        let mut seen: BTreeMap<&str, &'static str> = BTreeMap::new();
        let named = self
            .places
            .iter()
            .map(|p| (p.name.as_str(), "a place"))
            .chain(self.transitions.iter().map(|t| (t.name.as_str(), "a transition")));
        for (name, what) in named {
            if name.is_empty() {
                return Err(Error::Invalid(format!("{what} has an empty name")));
            }
            if let Some(first) = seen.insert(name, what) {
                return Err(Error::DuplicateName {
                    name: name.into(),
                    first,
                    second: what,
                });
            }
        }
        let mut params = std::collections::BTreeSet::new();
        for p in &self.params {
            if !params.insert(p.name.as_str()) {
                return Err(Error::DuplicateName {
                    name: p.name.clone(),
                    first: "a parameter",
                    second: "a parameter",
                });
            }
            if seen.contains_key(p.name.as_str()) {
                return Err(Error::DuplicateName {
                    name: p.name.clone(),
                    first: seen[p.name.as_str()],
                    second: "a parameter",
                });
            }
        }
        self.validate_decisions_labels_rewards()?;
        for (i, a) in self.arcs.iter().enumerate() {
            if a.place.index() >= self.places.len() {
                return Err(Error::UnknownNode {
                    arc: format!("arc #{i}"),
                    expected: "place",
                    name: format!("index {}", a.place.0),
                    hint: String::new(),
                });
            }
            if a.transition.index() >= self.transitions.len() {
                return Err(Error::UnknownNode {
                    arc: format!("arc #{i}"),
                    expected: "transition",
                    name: format!("index {}", a.transition.0),
                    hint: String::new(),
                });
            }
        }
        Ok(())
    }

    /// Decisions are immediate; label and reward names are unique and
    /// non-empty; impulses name transitions of the net, once each.
    fn validate_decisions_labels_rewards(&self) -> Result<()> {
        if let Some(t) = self.transitions.iter().find(|t| t.decision && !t.is_immediate()) {
            return Err(Error::Invalid(format!(
                "transition `{}` is timed: only immediate transitions can be decisions",
                t.name
            )));
        }
        let mut labels = std::collections::BTreeSet::new();
        for l in &self.labels {
            if l.name.is_empty() || l.name.contains('"') {
                return Err(Error::Invalid(format!(
                    "label `{}`: a label's name must be non-empty and hold no `\"`",
                    l.name
                )));
            }
            if !labels.insert(l.name.as_str()) {
                return Err(Error::DuplicateName {
                    name: l.name.clone(),
                    first: "a label",
                    second: "a label",
                });
            }
        }
        let mut rewards = std::collections::BTreeSet::new();
        for r in &self.rewards {
            if r.name.is_empty() || r.name.contains('"') {
                return Err(Error::Invalid(format!(
                    "reward model `{}`: a reward model's name must be non-empty and hold no `\"`",
                    r.name
                )));
            }
            if !rewards.insert(r.name.as_str()) {
                return Err(Error::DuplicateName {
                    name: r.name.clone(),
                    first: "a reward model",
                    second: "a reward model",
                });
            }
            let mut seen = std::collections::BTreeSet::new();
            for (t, _) in &r.impulses {
                let Some(tr) = self.transitions.get(t.index()) else {
                    return Err(Error::UnknownNode {
                        arc: format!("reward model `{}`", r.name),
                        expected: "transition",
                        name: format!("index {}", t.0),
                        hint: String::new(),
                    });
                };
                if !seen.insert(*t) {
                    return Err(Error::Invalid(format!(
                        "reward model `{}` gives transition `{}` two impulses",
                        r.name, tr.name
                    )));
                }
            }
        }
        Ok(())
    }

    /// The value of every parameter after applying `overrides`: the
    /// overrides must name parameters the net declares.
    pub fn resolve_params(&self, overrides: &Params) -> Result<BTreeMap<String, Option<f64>>> {
        let mut values: BTreeMap<String, Option<f64>> =
            self.params.iter().map(|p| (p.name.clone(), p.value)).collect();
        for (name, v) in &overrides.0 {
            match values.get_mut(name) {
                Some(slot) => *slot = Some(*v),
                None => {
                    let known = if self.params.is_empty() {
                        "none".to_string()
                    } else {
                        self.params
                            .iter()
                            .map(|p| p.name.as_str())
                            .collect::<Vec<_>>()
                            .join(", ")
                    };
                    return Err(Error::UnknownParameter {
                        name: name.clone(),
                        known,
                    });
                }
            }
        }
        for p in &self.params {
            if let (ParamKind::Int, Some(v)) = (p.kind, values.get(&p.name).copied().flatten()) {
                if v != v.trunc() || !v.is_finite() {
                    return Err(Error::InvalidValue {
                        element: format!("integer parameter `{}`", p.name),
                        what: "the value",
                        requirement: "a whole number",
                        value: v,
                    });
                }
            }
        }
        Ok(values)
    }
}
