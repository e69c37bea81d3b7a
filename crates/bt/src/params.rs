//! Per-leaf parameters: the TOML sidecar of a tree, with stated defaults.
//!
//! ```toml
//! [defaults]            # optional; these are the built-in defaults
//! p_success = 0.9       # an action's probability of succeeding
//! mean_time = 1.0       # an action's mean duration, seconds (0: instantaneous)
//! phases = 1            # Erlang phases of every duration (1: exponential)
//! p_true = 0.9          # a condition's probability of holding
//! change_rate = 0.0     # how fast a condition changes, 1/s (0: fixed for an execution)
//!
//! [leaf.FollowPath]     # by the node's `name`, else its type
//! p_success = 0.8
//! mean_time = 30.0      # both outcomes; or:
//! mean_time_success = 25.0
//! mean_time_failure = 40.0
//!
//! [leaf.GoalUpdated]
//! p_true = 0.05
//! change_rate = 0.02
//!
//! [node.RateController] # decorators and control nodes
//! mean_interval = 1.0   # Periodic decorators (seconds; 0 = never again)
//! weights = [1, 1]      # SwitchN: relative weights of its children
//! ```
//!
//! A condition with `change_rate > 0` is a state of the world: it holds
//! with probability `p_true` at the start of an execution and then changes
//! as a two-state Markov process with relaxation rate `change_rate` (from
//! true to false at `change_rate·(1 − p_true)`, back at `change_rate·p_true`,
//! so that `p_true` stays its probability at any time); the nodes with the
//! same key read the same state. With `change_rate = 0` (the default) each
//! evaluation is an independent draw with probability `p_true` (as in
//! Colledanchise et al.'s stochastic behaviour trees), and a reactive parent
//! keeps the result it got.
//! Every value is checked (probabilities in [0, 1], durations and rates 0
//! or from 1e-9 to 1e9 — seconds, or per second — phases 1…64); an error
//! names the file, line, table and field.

use std::collections::BTreeMap;
use std::path::Path;

use serde::{Deserialize, Serialize};
use toml::Spanned;

use crate::error::{Error, Result};
use crate::tree::{Kind, NodeId, Tree};

/// The smallest time (s) or rate (per s) other than 0 a sidecar may give.
pub const MIN_SCALE: f64 = 1e-9;
/// The largest time (s) or rate (per s) a sidecar may give.
pub const MAX_SCALE: f64 = 1e9;

/// Parameters of an action leaf.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ActionParams {
    /// Probability of succeeding, in [0, 1].
    pub p_success: f64,
    /// Mean duration when it succeeds, seconds (0: instantaneous).
    pub mean_time_success: f64,
    /// Mean duration when it fails, seconds (0: instantaneous).
    pub mean_time_failure: f64,
    /// Erlang phases of both durations (1: exponential).
    pub phases: u32,
}

/// Parameters of a condition leaf (or a `Gate` decorator's condition).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ConditionParams {
    /// Probability of holding (at the start and at any time), in [0, 1].
    pub p_true: f64,
    /// Relaxation rate of the two-state process, 1/s (0: fixed during an execution).
    pub change_rate: f64,
}

/// Parameters of a control node or decorator.
#[derive(Debug, Clone, PartialEq, Serialize, Default)]
pub struct NodeParams {
    /// Mean interval of a `Periodic` decorator, seconds (overrides the XML's `hz`).
    pub mean_interval: Option<f64>,
    /// Relative weights of a `SwitchN`'s children.
    pub weights: Option<Vec<f64>>,
}

/// The defaults of every leaf.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Defaults {
    /// For actions.
    pub action: ActionParams,
    /// For conditions.
    pub condition: ConditionParams,
}

impl Default for Defaults {
    fn default() -> Self {
        Defaults {
            action: ActionParams {
                p_success: 0.9,
                mean_time_success: 1.0,
                mean_time_failure: 1.0,
                phases: 1,
            },
            condition: ConditionParams {
                p_true: 0.9,
                change_rate: 0.0,
            },
        }
    }
}

/// A tree's parameters: defaults and per-key overrides.
#[derive(Debug, Clone, PartialEq, Serialize, Default)]
pub struct TreeParams {
    /// Defaults.
    pub defaults: Defaults,
    /// Actions by key (`name`, else type).
    pub actions: BTreeMap<String, ActionParams>,
    /// Conditions by key.
    pub conditions: BTreeMap<String, ConditionParams>,
    /// Control nodes and decorators by key.
    pub nodes: BTreeMap<String, NodeParams>,
    /// The file the parameters were read from (named in errors), if any.
    #[serde(skip)]
    pub source: Option<String>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct LeafToml {
    p_success: Option<Spanned<f64>>,
    mean_time: Option<Spanned<f64>>,
    mean_time_success: Option<Spanned<f64>>,
    mean_time_failure: Option<Spanned<f64>>,
    phases: Option<Spanned<i64>>,
    p_true: Option<Spanned<f64>>,
    change_rate: Option<Spanned<f64>>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct NodeToml {
    mean_interval: Option<Spanned<f64>>,
    weights: Option<Spanned<Vec<f64>>>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct FileToml {
    #[serde(default)]
    defaults: LeafToml,
    #[serde(default)]
    leaf: BTreeMap<String, LeafToml>,
    #[serde(default)]
    node: BTreeMap<String, NodeToml>,
}

/// Checks one value; `line` from the span.
struct Checker<'a> {
    file: &'a str,
    text: &'a str,
}

impl Checker<'_> {
    fn line(&self, offset: usize) -> u32 {
        self.text[..offset.min(self.text.len())]
            .bytes()
            .filter(|&b| b == b'\n')
            .count() as u32
            + 1
    }

    fn err(&self, table: &str, field: &str, value: String, offset: usize, requirement: &str) -> Error {
        Error::Param {
            file: self.file.to_string(),
            line: self.line(offset),
            table: table.to_string(),
            field: field.to_string(),
            value,
            requirement: requirement.to_string(),
        }
    }

    fn probability(&self, table: &str, field: &str, v: &Option<Spanned<f64>>) -> Result<Option<f64>> {
        match v {
            None => Ok(None),
            Some(s) => {
                let x = *s.get_ref();
                if (0.0..=1.0).contains(&x) {
                    Ok(Some(x))
                } else {
                    Err(self.err(
                        table,
                        field,
                        x.to_string(),
                        s.span().start,
                        "a probability in [0, 1]",
                    ))
                }
            }
        }
    }

    /// A time (s) or a rate (per s): 0, or from [`MIN_SCALE`] to
    /// [`MAX_SCALE`] — beyond, the chain's rates and times leave the range
    /// where its solves keep their precision (a mean time of 1e300 s made
    /// infinite conditional means).
    fn non_negative(&self, table: &str, field: &str, v: &Option<Spanned<f64>>) -> Result<Option<f64>> {
        match v {
            None => Ok(None),
            Some(s) => {
                let x = *s.get_ref();
                if x == 0.0 || (MIN_SCALE..=MAX_SCALE).contains(&x) {
                    Ok(Some(x))
                } else {
                    let shown = if x != 0.0 && !(1e-4..1e6).contains(&x.abs()) {
                        format!("{x:e}")
                    } else {
                        x.to_string()
                    };
                    Err(self.err(
                        table,
                        field,
                        shown,
                        s.span().start,
                        "0, or a number from 1e-9 to 1e9 (seconds, or per second)",
                    ))
                }
            }
        }
    }

    fn phases(&self, table: &str, v: &Option<Spanned<i64>>) -> Result<Option<u32>> {
        match v {
            None => Ok(None),
            Some(s) => {
                let x = *s.get_ref();
                if (1..=64).contains(&x) {
                    Ok(Some(x as u32))
                } else {
                    Err(self.err(
                        table,
                        "phases",
                        x.to_string(),
                        s.span().start,
                        "a whole number in 1…64",
                    ))
                }
            }
        }
    }

    fn action(&self, table: &str, t: &LeafToml, base: ActionParams) -> Result<ActionParams> {
        let mean = self.non_negative(table, "mean_time", &t.mean_time)?;
        Ok(ActionParams {
            p_success: self
                .probability(table, "p_success", &t.p_success)?
                .unwrap_or(base.p_success),
            mean_time_success: self
                .non_negative(table, "mean_time_success", &t.mean_time_success)?
                .or(mean)
                .unwrap_or(base.mean_time_success),
            mean_time_failure: self
                .non_negative(table, "mean_time_failure", &t.mean_time_failure)?
                .or(mean)
                .unwrap_or(base.mean_time_failure),
            phases: self.phases(table, &t.phases)?.unwrap_or(base.phases),
        })
    }

    fn condition(&self, table: &str, t: &LeafToml, base: ConditionParams) -> Result<ConditionParams> {
        Ok(ConditionParams {
            p_true: self
                .probability(table, "p_true", &t.p_true)?
                .unwrap_or(base.p_true),
            change_rate: self
                .non_negative(table, "change_rate", &t.change_rate)?
                .unwrap_or(base.change_rate),
        })
    }

    fn node(&self, table: &str, t: &NodeToml) -> Result<NodeParams> {
        let weights = match &t.weights {
            None => None,
            Some(w) => {
                let v = w.get_ref();
                if v.is_empty()
                    || v.iter().any(|x| !x.is_finite() || *x < 0.0)
                    || v.iter().sum::<f64>() <= 0.0
                {
                    return Err(self.err(
                        table,
                        "weights",
                        format!("{v:?}"),
                        w.span().start,
                        "finite weights ≥ 0 with a positive sum",
                    ));
                }
                Some(v.clone())
            }
        };
        Ok(NodeParams {
            mean_interval: self.non_negative(table, "mean_interval", &t.mean_interval)?,
            weights,
        })
    }
}

impl TreeParams {
    /// Reads a sidecar file.
    pub fn read_file(path: impl AsRef<Path>) -> Result<TreeParams> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|source| Error::Io {
            path: path.to_path_buf(),
            source,
        })?;
        TreeParams::parse(&text, &path.display().to_string())
    }

    /// Parses sidecar text; `file` names it in errors.
    pub fn parse(text: &str, file: &str) -> Result<TreeParams> {
        let raw: FileToml = toml::from_str(text).map_err(|e| {
            let line = e.span().map_or(0, |s| {
                text[..s.start.min(text.len())]
                    .bytes()
                    .filter(|&b| b == b'\n')
                    .count() as u32
                    + 1
            });
            Error::Param {
                file: file.to_string(),
                line,
                table: "-".into(),
                field: "-".into(),
                value: "-".into(),
                requirement: e.message().to_string(),
            }
        })?;
        let c = Checker { file, text };
        let base = Defaults::default();
        let defaults = Defaults {
            action: c.action("defaults", &raw.defaults, base.action)?,
            condition: c.condition("defaults", &raw.defaults, base.condition)?,
        };
        let mut out = TreeParams {
            defaults,
            source: Some(file.to_string()),
            ..TreeParams::default()
        };
        for (key, t) in &raw.leaf {
            let table = format!("leaf.{key}");
            let is_condition = t.p_true.is_some() || t.change_rate.is_some();
            let is_action = t.p_success.is_some()
                || t.mean_time.is_some()
                || t.mean_time_success.is_some()
                || t.mean_time_failure.is_some()
                || t.phases.is_some();
            if is_action || !is_condition {
                out.actions
                    .insert(key.clone(), c.action(&table, t, defaults.action)?);
            }
            if is_condition {
                out.conditions
                    .insert(key.clone(), c.condition(&table, t, defaults.condition)?);
            }
        }
        for (key, t) in &raw.node {
            out.nodes.insert(key.clone(), c.node(&format!("node.{key}"), t)?);
        }
        Ok(out)
    }

    /// The parameters of action leaf `n` (by `name`, then type, then defaults).
    pub fn action(&self, tree: &Tree, n: NodeId) -> ActionParams {
        let node = tree.node(n);
        if let Kind::Sleep { mean_s } = node.kind {
            return ActionParams {
                p_success: 1.0,
                mean_time_success: mean_s,
                mean_time_failure: mean_s,
                phases: self.defaults.action.phases,
            };
        }
        self.lookup(&self.actions, tree, n)
            .unwrap_or(self.defaults.action)
    }

    /// The parameters of condition `n` (a condition leaf or a `Gate`).
    pub fn condition(&self, tree: &Tree, n: NodeId) -> ConditionParams {
        self.lookup(&self.conditions, tree, n)
            .unwrap_or(self.defaults.condition)
    }

    /// The parameters of control node or decorator `n`.
    pub fn node(&self, tree: &Tree, n: NodeId) -> NodeParams {
        self.lookup(&self.nodes, tree, n).unwrap_or_default()
    }

    fn lookup<T: Clone>(&self, map: &BTreeMap<String, T>, tree: &Tree, n: NodeId) -> Option<T> {
        let node = tree.node(n);
        map.get(&node.path)
            .or_else(|| node.name.as_ref().and_then(|k| map.get(k)))
            .or_else(|| map.get(&node.id))
            .cloned()
    }

    /// The key under which a condition's state is shared: conditions with
    /// the same parameter key read the same state of the world.
    pub fn condition_key(&self, tree: &Tree, n: NodeId) -> String {
        let node = tree.node(n);
        if self.conditions.contains_key(&node.path) {
            node.path.clone()
        } else {
            node.param_key().to_string()
        }
    }

    /// Refuses parameters of the wrong kind: a leaf table that gives an
    /// action only a condition's fields (`p_true`, `change_rate`), or a
    /// condition (or `Gate`) only an action's, would be ignored in favour
    /// of the defaults. The error names the node (file, line, path), the
    /// table and the sidecar file.
    pub fn check_kinds(&self, tree: &Tree) -> Result<()> {
        for (i, node) in tree.nodes.iter().enumerate() {
            let n = NodeId(i as u32);
            let (wanted, other, given) = match node.kind {
                Kind::Action => (
                    self.lookup(&self.actions, tree, n).is_some(),
                    self.key_in(&self.conditions, tree, n),
                    "only a condition's fields (p_true, change_rate)",
                ),
                Kind::Condition | Kind::Gate => (
                    self.lookup(&self.conditions, tree, n).is_some(),
                    self.key_in(&self.actions, tree, n),
                    "no condition field (p_true, change_rate)",
                ),
                _ => continue,
            };
            if let (false, Some(key)) = (wanted, other) {
                let kind = if node.kind == Kind::Action {
                    "an action"
                } else {
                    "a condition"
                };
                let source = self
                    .source
                    .as_deref()
                    .map_or_else(String::new, |f| format!(" of {f}"));
                return Err(Error::Tree {
                    file: tree.files[node.file].clone(),
                    line: node.line,
                    path: node.path.clone(),
                    message: format!(
                        "`{}` is {kind}, but [leaf.{key}]{source} gives it {given}: \
                         they would be ignored",
                        node.id
                    ),
                });
            }
        }
        Ok(())
    }

    /// The key under which `map` holds parameters for node `n`, in lookup order.
    fn key_in<T>(&self, map: &BTreeMap<String, T>, tree: &Tree, n: NodeId) -> Option<String> {
        let node = tree.node(n);
        [
            Some(node.path.as_str()),
            node.name.as_deref(),
            Some(node.id.as_str()),
        ]
        .into_iter()
        .flatten()
        .find(|k| map.contains_key(*k))
        .map(str::to_string)
    }

    /// Keys of the sidecar that name no node of `tree` (likely misspelt).
    pub fn unused_keys(&self, tree: &Tree) -> Vec<String> {
        let names: std::collections::BTreeSet<&str> = tree
            .nodes
            .iter()
            .flat_map(|n| [Some(n.id.as_str()), n.name.as_deref(), Some(n.path.as_str())])
            .flatten()
            .collect();
        self.actions
            .keys()
            .chain(self.conditions.keys())
            .chain(self.nodes.keys())
            .filter(|k| !names.contains(k.as_str()))
            .cloned()
            .collect::<std::collections::BTreeSet<_>>()
            .into_iter()
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn out_of_range_probability_names_line_and_field() {
        let e = TreeParams::parse("[leaf.A]\nmean_time = 2\np_success = 1.2\n", "p.toml")
            .unwrap_err()
            .to_string();
        assert_eq!(e, "p.toml:3: [leaf.A] p_success = 1.2: a probability in [0, 1]");
    }

    #[test]
    fn negative_duration_is_refused() {
        let e = TreeParams::parse("[leaf.A]\nmean_time = -1\n", "p.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("p.toml:2: [leaf.A] mean_time = -1"), "{e}");
    }

    /// Times and rates beyond 1e-9…1e9 (s, or per s) are refused: a mean
    /// time of 1e300 s had made the conditional mean times infinite.
    #[test]
    fn times_and_rates_out_of_scale_are_refused() {
        for (field, v) in [
            ("mean_time", "1e300"),
            ("mean_time", "1e-12"),
            ("change_rate", "2e9"),
        ] {
            let e = TreeParams::parse(&format!("[leaf.A]\n{field} = {v}\n"), "p.toml")
                .unwrap_err()
                .to_string();
            assert!(e.contains(&format!("p.toml:2: [leaf.A] {field} = ")), "{e}");
            assert!(
                e.ends_with("0, or a number from 1e-9 to 1e9 (seconds, or per second)"),
                "{e}"
            );
        }
        for v in ["0", "1e-9", "1e9", "30.5"] {
            assert!(
                TreeParams::parse(&format!("[leaf.A]\nmean_time = {v}\n"), "p.toml").is_ok(),
                "{v}"
            );
        }
    }

    #[test]
    fn misspelt_field_is_an_error_with_line() {
        let e = TreeParams::parse("[leaf.A]\np_sucess = 0.5\n", "p.toml")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("p.toml:2:"), "{e}");
        assert!(e.contains("p_sucess"), "{e}");
    }

    fn tree() -> Tree {
        crate::read::read_str(
            "<root BTCPP_format=\"4\">\n<BehaviorTree ID=\"M\">\n<Fallback>\n\
             <IsStuck/>\n<Spin name=\"spin\"/>\n</Fallback>\n</BehaviorTree>\n</root>",
            "t.xml",
            None,
            &crate::ReadOptions::default(),
        )
        .unwrap()
    }

    #[test]
    fn condition_fields_on_an_action_are_an_error_naming_node_and_file() {
        let p = TreeParams::parse("[leaf.spin]\np_true = 0.5\n", "p.toml").unwrap();
        let e = p.check_kinds(&tree()).unwrap_err().to_string();
        assert_eq!(
            e,
            "t.xml:5: M/Fallback#0/Spin(spin): `Spin` is an action, but [leaf.spin] of p.toml \
             gives it only a condition's fields (p_true, change_rate): they would be ignored"
        );
    }

    #[test]
    fn action_fields_on_a_condition_are_an_error() {
        let p = TreeParams::parse("[leaf.IsStuck]\np_success = 0.5\n", "p.toml").unwrap();
        let e = p.check_kinds(&tree()).unwrap_err().to_string();
        assert!(
            e.starts_with("t.xml:4: M/Fallback#0/IsStuck#0: `IsStuck` is a condition"),
            "{e}"
        );
    }

    #[test]
    fn fields_of_the_right_kind_pass() {
        let p = TreeParams::parse(
            "[leaf.spin]\np_success = 0.5\n[leaf.IsStuck]\np_true = 0.1\n[leaf.Other]\np_true = 0.2\n",
            "p.toml",
        )
        .unwrap();
        assert!(p.check_kinds(&tree()).is_ok());
    }

    #[test]
    fn defaults_apply_and_mean_time_sets_both() {
        let p =
            TreeParams::parse("[defaults]\np_success = 0.5\n[leaf.A]\nmean_time = 3\n", "p.toml").unwrap();
        let a = p.actions["A"];
        assert_eq!(
            (a.p_success, a.mean_time_success, a.mean_time_failure),
            (0.5, 3.0, 3.0)
        );
    }
}
