//! Policies: what to choose in each choice marking of a net with decisions
//! (docs/gspn.md, *Decisions*), written to and read from a JSON file.
//!
//! `gspn optimize --policy-out FILE` writes the optimal memoryless policy;
//! `gspn solve NET --policy FILE` runs the net under it
//! ([`Gspn::with_policy`]), so that every steady-state measure applies to
//! the CTMC the policy induces.
//!
//! ```json
//! {
//!   "format": "petrinav-policy",
//!   "version": 1,
//!   "net": "supervisor_decisions",
//!   "objective": "R{\"done\"}max=? [LRA]",
//!   "choices": [
//!     { "marking": { "P0": 1, "P5": 1, "P7": 1 }, "fire": "start_auto" },
//!     { "marking": { "P1": 1, "P6": 1, "P7": 1, "D": 1 }, "random": true }
//!   ]
//! }
//! ```
//!
//! - `marking` gives the token count of every marked place (places left out
//!   hold no token); `fire` names the decision to fire, `random: true` lets
//!   the transitions that are not decisions race by their weights.
//! - `objective` is informative. `format`, `version`, `net` and `choices`
//!   are required; unknown keys are errors.
//! - Checked against the net ([`Policy::bind`]): the net's name, every
//!   place and transition named, each `fire` a decision, no marking twice.
//!   A choice marking the policy says nothing about, or an action not
//!   available where it is chosen, is an error naming the marking when the
//!   state space is generated.

use std::collections::{BTreeMap, HashMap};

use serde::{Deserialize, Serialize};

use super::Gspn;
use crate::error::{Error, Result};
use crate::net::TransitionId;

/// The `format` field of a policy file.
pub const POLICY_FORMAT: &str = "petrinav-policy";
/// The `version` field this reader understands.
pub const POLICY_VERSION: u32 = 1;

/// An action of a choice marking.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Action {
    /// Fire this decision.
    Fire(TransitionId),
    /// Let the enabled transitions that are not decisions race by weight.
    Random,
}

impl Action {
    /// `t3`, or `random`.
    pub fn describe(&self, gspn: &Gspn) -> String {
        match self {
            Action::Fire(t) => gspn.transition_names()[t.index()].clone(),
            Action::Random => "random".into(),
        }
    }
}

/// One line of a policy file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Choice {
    marking: BTreeMap<String, u32>,
    #[serde(skip_serializing_if = "Option::is_none", default)]
    fire: Option<String>,
    #[serde(skip_serializing_if = "std::ops::Not::not", default)]
    random: bool,
}

/// The file.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct File {
    format: String,
    version: u32,
    net: String,
    #[serde(skip_serializing_if = "Option::is_none", default)]
    objective: Option<String>,
    choices: Vec<Choice>,
}

/// A memoryless policy: one action per choice marking.
#[derive(Debug, Clone)]
pub struct Policy {
    source_name: String,
    file: File,
    /// Markings (as token vectors of the net bound) → actions.
    bound: HashMap<Vec<u32>, Action>,
}

impl Policy {
    /// An empty policy for the net called `net`, found for `objective`.
    pub fn new(net: &str, objective: Option<&str>) -> Policy {
        Policy {
            source_name: "the policy".into(),
            file: File {
                format: POLICY_FORMAT.into(),
                version: POLICY_VERSION,
                net: net.into(),
                objective: objective.map(str::to_string),
                choices: Vec::new(),
            },
            bound: HashMap::new(),
        }
    }

    /// Adds the action of marking `m` of `gspn` (replacing an earlier one).
    pub fn set(&mut self, gspn: &Gspn, m: &[u32], action: Action) {
        let marking: BTreeMap<String, u32> = gspn
            .place_names()
            .iter()
            .zip(m)
            .filter(|&(_, &k)| k > 0)
            .map(|(n, &k)| (n.clone(), k))
            .collect();
        let choice = Choice {
            marking,
            fire: match action {
                Action::Fire(t) => Some(gspn.transition_names()[t.index()].clone()),
                Action::Random => None,
            },
            random: action == Action::Random,
        };
        match self.bound.insert(m.to_vec(), action) {
            Some(_) => {
                if let Some(c) = self.file.choices.iter_mut().find(|c| c.marking == choice.marking) {
                    *c = choice;
                }
            }
            None => self.file.choices.push(choice),
        }
    }

    /// Reads a policy file (syntax and fields; [`Policy::bind`] checks it
    /// against a net). `source` names the file in errors.
    pub fn parse(text: &str, source: &str) -> Result<Policy> {
        let file: File = serde_json::from_str(text).map_err(|e| Error::Format {
            location: format!("{source}:{}:{}", e.line(), e.column()),
            message: format!("not a policy file: {e}"),
        })?;
        let refuse = |message: String| Error::Policy {
            source_name: source.to_string(),
            message,
        };
        if file.format != POLICY_FORMAT {
            return Err(refuse(format!(
                "`format` is `{}`, expected `{POLICY_FORMAT}`",
                file.format
            )));
        }
        if file.version != POLICY_VERSION {
            return Err(refuse(format!(
                "version {} is not supported (this reader knows version {POLICY_VERSION})",
                file.version
            )));
        }
        for (i, c) in file.choices.iter().enumerate() {
            match (&c.fire, c.random) {
                (Some(_), true) => {
                    return Err(refuse(format!(
                        "choice {} both fires `{}` and chooses random: one action per marking",
                        i + 1,
                        c.fire.as_deref().unwrap_or_default()
                    )));
                }
                (None, false) => {
                    return Err(refuse(format!(
                        "choice {} has no action: give `fire: \"TRANSITION\"` or `random: true`",
                        i + 1
                    )));
                }
                _ => {}
            }
        }
        Ok(Policy {
            source_name: source.to_string(),
            file,
            bound: HashMap::new(),
        })
    }

    /// Reads a policy file from disk.
    pub fn read_file(path: &std::path::Path) -> Result<Policy> {
        let text = std::fs::read_to_string(path).map_err(|source| Error::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Policy::parse(&text, &path.display().to_string())
    }

    /// The file's text (pretty JSON, one line per choice's field).
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(&self.file).unwrap_or_default() + "\n"
    }

    /// The name errors give the policy (its file).
    pub fn source_name(&self) -> &str {
        &self.source_name
    }

    /// The net the policy was made for.
    pub fn net_name(&self) -> &str {
        &self.file.net
    }

    /// The objective it was found for, if recorded.
    pub fn objective(&self) -> Option<&str> {
        self.file.objective.as_deref()
    }

    /// Number of choice markings it covers.
    pub fn len(&self) -> usize {
        self.file.choices.len()
    }

    /// Whether it covers no marking.
    pub fn is_empty(&self) -> bool {
        self.file.choices.is_empty()
    }

    /// The action of marking `m` (once bound to a net).
    pub fn action(&self, m: &[u32]) -> Option<Action> {
        self.bound.get(m).copied()
    }

    /// Checks the policy against `gspn` and indexes its markings: the
    /// net's name, every place and transition it names, each `fire` a
    /// decision, no marking listed twice.
    pub fn bind(&mut self, gspn: &Gspn) -> Result<()> {
        let refuse = |message: String| Error::Policy {
            source_name: self.source_name.clone(),
            message,
        };
        if self.file.net != gspn.name() {
            return Err(refuse(format!(
                "it was made for the net `{}`, not for `{}`",
                self.file.net,
                gspn.name()
            )));
        }
        let mut bound = HashMap::with_capacity(self.file.choices.len());
        for (i, c) in self.file.choices.iter().enumerate() {
            let mut m = vec![0u32; gspn.num_places()];
            for (place, &k) in &c.marking {
                let p = gspn
                    .place(place)
                    .map_err(|_| refuse(format!("choice {}: the net has no place `{place}`", i + 1)))?;
                m[p.index()] = k;
            }
            let action = match &c.fire {
                Some(name) => {
                    let t = gspn.transition(name).map_err(|_| {
                        refuse(format!("choice {}: the net has no transition `{name}`", i + 1))
                    })?;
                    if !gspn.is_decision(t) {
                        return Err(refuse(format!(
                            "choice {}: `{name}` is not a decision, a policy cannot fire it",
                            i + 1
                        )));
                    }
                    Action::Fire(t)
                }
                None => Action::Random,
            };
            if bound.insert(m.clone(), action).is_some() {
                return Err(refuse(format!(
                    "choice {}: marking [{}] is listed twice",
                    i + 1,
                    gspn.format_marking(&m)
                )));
            }
        }
        self.bound = bound;
        Ok(())
    }

    /// [`bind`](Self::bind) on a copy, for checks that must not change it.
    pub fn check(&self, gspn: &Gspn) -> Result<()> {
        self.clone().bind(gspn)
    }
}
