//! Node models: what a node type is (action, condition, control, decorator)
//! and which ports it reads or writes — from a file's `<TreeNodesModel>`,
//! from Nav2's model (built in: `models/bt/nav2/nav2_tree_nodes.xml`), and
//! from BehaviorTree.CPP's own nodes.
//!
//! A leaf that no model names is classified by its type's name (docs/behaviour-trees.md,
//! *Leaves*): a condition if it starts with `Is`, `Are`, `Has`, `Would` or `Can`
//! followed by a capital letter, or ends with `Condition`; an action otherwise.

use std::collections::BTreeMap;

use crate::tree::Direction;

/// The role of a node type.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Role {
    /// A leaf that acts.
    Action,
    /// A leaf that reads.
    Condition,
    /// A node with children.
    Control,
    /// A node with one child.
    Decorator,
    /// A subtree reference.
    SubTree,
}

/// One port of a model.
#[derive(Debug, Clone, PartialEq)]
pub struct PortModel {
    /// Its name.
    pub name: String,
    /// Input, output or both.
    pub direction: Direction,
    /// The default value, if the model gives one.
    pub default: Option<String>,
}

/// The model of one node type.
#[derive(Debug, Clone, PartialEq)]
pub struct NodeModel {
    /// Its role.
    pub role: Role,
    /// Its ports.
    pub ports: Vec<PortModel>,
}

impl NodeModel {
    /// The direction of port `name` (`Unknown` if the model lacks it).
    pub fn direction(&self, name: &str) -> Direction {
        self.ports
            .iter()
            .find(|p| p.name == name)
            .map_or(Direction::Unknown, |p| p.direction)
    }
}

/// Models by node type.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Models(pub BTreeMap<String, NodeModel>);

/// Nav2's `TreeNodesModel`, shipped with its licence in `models/bt/nav2/`.
pub const NAV2_MODEL_XML: &str = include_str!("../../../models/bt/nav2/nav2_tree_nodes.xml");

impl Models {
    /// Nav2's model (parsed from [`NAV2_MODEL_XML`]).
    pub fn nav2() -> Models {
        let doc = roxmltree::Document::parse(NAV2_MODEL_XML).expect("the shipped Nav2 model is well formed");
        let mut m = Models::default();
        for el in doc.descendants().filter(|e| e.has_tag_name("TreeNodesModel")) {
            m.add_from(el);
        }
        m
    }

    /// Adds (or replaces) the models declared under a `<TreeNodesModel>` element.
    pub fn add_from(&mut self, model: roxmltree::Node<'_, '_>) {
        for el in model.children().filter(|e| e.is_element()) {
            let role = match el.tag_name().name() {
                "Action" => Role::Action,
                "Condition" => Role::Condition,
                "Control" => Role::Control,
                "Decorator" => Role::Decorator,
                "SubTree" => Role::SubTree,
                _ => continue,
            };
            let Some(id) = el.attribute("ID") else { continue };
            let ports = el
                .children()
                .filter(|p| p.is_element())
                .filter_map(|p| {
                    let direction = match p.tag_name().name() {
                        "input_port" => Direction::Input,
                        "output_port" => Direction::Output,
                        "inout_port" => Direction::InOut,
                        _ => return None,
                    };
                    Some(PortModel {
                        name: p.attribute("name")?.to_string(),
                        direction,
                        default: p.attribute("default").map(str::to_string),
                    })
                })
                .collect();
            self.0.insert(id.to_string(), NodeModel { role, ports });
        }
    }

    /// The model of `id`.
    pub fn get(&self, id: &str) -> Option<&NodeModel> {
        self.0.get(id)
    }
}

/// The models of a file holding a `<TreeNodesModel>` (at its root or under
/// `<root>`); `file` names it in errors.
pub fn parse_models(text: &str, file: &str) -> crate::error::Result<Models> {
    let doc = roxmltree::Document::parse(text).map_err(|e| crate::error::Error::Xml {
        file: file.to_string(),
        line: e.pos().row,
        column: e.pos().col,
        message: e.to_string(),
    })?;
    let mut m = Models::default();
    for el in doc.descendants().filter(|e| e.has_tag_name("TreeNodesModel")) {
        m.add_from(el);
    }
    Ok(m)
}

/// The naming rule for leaves no model names: whether `id` reads as a condition.
pub fn looks_like_condition(id: &str) -> bool {
    let prefixed = ["Is", "Are", "Has", "Would", "Can"].iter().any(|p| {
        id.strip_prefix(p)
            .and_then(|rest| rest.chars().next())
            .is_some_and(|c| c.is_ascii_uppercase())
    });
    prefixed || id.ends_with("Condition")
}

/// Ports of BehaviorTree.CPP's own leaves that write or read the blackboard.
pub fn builtin_port_direction(id: &str, port: &str) -> Direction {
    match (id, port) {
        ("SetBlackboard", "output_key") => Direction::Output,
        ("SetBlackboard", "value") => Direction::Input,
        ("UnsetBlackboard", "key") => Direction::Input,
        _ => Direction::Unknown,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nav2_model_classifies_its_nodes() {
        let m = Models::nav2();
        assert_eq!(m.get("GoalUpdated").unwrap().role, Role::Condition);
        assert_eq!(m.get("FollowPath").unwrap().role, Role::Action);
        assert_eq!(m.get("RecoveryNode").unwrap().role, Role::Control);
        assert_eq!(m.get("RateController").unwrap().role, Role::Decorator);
        let cp = m.get("ComputePathToPose").unwrap();
        assert_eq!(cp.direction("path"), Direction::Output);
        assert_eq!(cp.direction("goal"), Direction::Input);
    }

    #[test]
    fn naming_rule() {
        assert!(looks_like_condition("IsStuck"));
        assert!(looks_like_condition("BatteryCondition"));
        assert!(!looks_like_condition("Island"));
        assert!(!looks_like_condition("FollowPath"));
    }
}
