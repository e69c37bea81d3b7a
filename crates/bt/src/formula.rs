//! The value of an instantaneous, side-effect-free subtree as a boolean
//! formula over the conditions it reads — what a reactive parent re-reads
//! while a later child runs (docs/behaviour-trees.md, *Reactive nodes*).
//!
//! A subtree is *pure* when it holds only conditions that change over time
//! (`change_rate > 0`), constants and the
//! control nodes and decorators that combine them without time or memory
//! (Sequence, Fallback and their reactive forms, Inverter, ForceSuccess,
//! ForceFailure, IfThenElse, pass-through decorators). Actions, timers and
//! loops make a subtree impure: a reactive parent keeps the result such a
//! child gave at its first evaluation.

use std::collections::BTreeMap;

use crate::params::TreeParams;
use crate::tree::{Kind, NodeId, Tree};

/// A boolean formula over condition keys.
#[derive(Debug, Clone, PartialEq)]
pub enum Formula {
    /// A constant.
    Const(bool),
    /// The state of a condition (by its shared key).
    Var(String),
    /// Negation.
    Not(Box<Formula>),
    /// Conjunction.
    And(Vec<Formula>),
    /// Disjunction.
    Or(Vec<Formula>),
}

impl Formula {
    /// The formula of node `n`, or `None` when its subtree is not pure.
    pub fn of(tree: &Tree, params: &TreeParams, n: NodeId) -> Option<Formula> {
        let node = tree.node(n);
        let kids = |tree: &Tree| -> Option<Vec<Formula>> {
            node.children
                .iter()
                .map(|&c| Formula::of(tree, params, c))
                .collect()
        };
        Some(match &node.kind {
            // A condition that does not change is drawn at each evaluation
            // and held by a reactive parent: not re-read, so not pure.
            Kind::Condition if params.condition(tree, n).change_rate > 0.0 => {
                Formula::Var(params.condition_key(tree, n))
            }
            Kind::Constant { success } => Formula::Const(*success),
            Kind::Inverter => Formula::Not(Box::new(Formula::of(tree, params, node.children[0])?)),
            Kind::ForceSuccess => {
                Formula::of(tree, params, node.children[0])?;
                Formula::Const(true)
            }
            Kind::ForceFailure => {
                Formula::of(tree, params, node.children[0])?;
                Formula::Const(false)
            }
            Kind::PassThrough => Formula::of(tree, params, node.children[0])?,
            Kind::Sequence | Kind::ReactiveSequence | Kind::SequenceWithMemory => Formula::And(kids(tree)?),
            Kind::Fallback | Kind::ReactiveFallback => Formula::Or(kids(tree)?),
            Kind::IfThenElse => {
                let k = kids(tree)?;
                let c = k[0].clone();
                let then = Formula::And(vec![c.clone(), k[1].clone()]);
                let other = match k.get(2) {
                    Some(e) => Formula::And(vec![Formula::Not(Box::new(c)), e.clone()]),
                    None => Formula::Const(false),
                };
                Formula::Or(vec![then, other])
            }
            _ => return None,
        })
    }

    /// Its value under an assignment of its variables.
    pub fn eval(&self, values: &BTreeMap<String, bool>) -> bool {
        match self {
            Formula::Const(b) => *b,
            Formula::Var(v) => values.get(v).copied().unwrap_or(false),
            Formula::Not(f) => !f.eval(values),
            Formula::And(fs) => fs.iter().all(|f| f.eval(values)),
            Formula::Or(fs) => fs.iter().any(|f| f.eval(values)),
        }
    }

    /// Its variables, sorted, without repeats.
    pub fn vars(&self) -> Vec<String> {
        let mut out = Vec::new();
        self.collect(&mut out);
        out.sort();
        out.dedup();
        out
    }

    fn collect(&self, out: &mut Vec<String>) {
        match self {
            Formula::Const(_) => {}
            Formula::Var(v) => out.push(v.clone()),
            Formula::Not(f) => f.collect(out),
            Formula::And(fs) | Formula::Or(fs) => fs.iter().for_each(|f| f.collect(out)),
        }
    }

    /// Every assignment of its variables under which it has value `value`
    /// (at most 2^12 assignments are enumerated; `None` beyond).
    pub fn assignments(&self, value: bool) -> Option<Vec<BTreeMap<String, bool>>> {
        let vars = self.vars();
        if vars.len() > 12 {
            return None;
        }
        let mut out = Vec::new();
        for bits in 0u32..(1 << vars.len()) {
            let a: BTreeMap<String, bool> = vars
                .iter()
                .enumerate()
                .map(|(i, v)| (v.clone(), bits >> i & 1 == 1))
                .collect();
            if self.eval(&a) == value {
                out.push(a);
            }
        }
        Some(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn assignments_of_a_conjunction() {
        let f = Formula::And(vec![
            Formula::Var("a".into()),
            Formula::Not(Box::new(Formula::Var("b".into()))),
        ]);
        assert_eq!(f.assignments(true).unwrap().len(), 1);
        assert_eq!(f.assignments(false).unwrap().len(), 3);
    }
}
