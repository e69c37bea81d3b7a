//! A behaviour tree as read: subtrees expanded in place, every node with its
//! kind, its path in the XML, its file and line, and the blackboard keys of
//! its ports (after subtree remapping).

use serde::Serialize;

/// Index of a node in [`Tree::nodes`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
pub struct NodeId(pub u32);

impl NodeId {
    /// As a `usize` index.
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

/// What a node does. Durations are in seconds; thresholds as written.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Kind {
    /// A leaf that does something (its parameters come from the sidecar).
    Action,
    /// A leaf that reads the world, in zero time.
    Condition,
    /// A leaf that returns this result in zero time (`AlwaysSuccess`,
    /// `AlwaysFailure`, `SetBlackboard`, `Script`, …).
    Constant {
        /// The result.
        success: bool,
    },
    /// `Sleep`: an action that always succeeds after `msec` (mean).
    Sleep {
        /// Mean duration, seconds.
        mean_s: f64,
    },
    /// `Sequence`: children in order until one fails.
    Sequence,
    /// `SequenceWithMemory` (v3 `SequenceStar`): a failed child is resumed,
    /// not restarted, at the next activation.
    SequenceWithMemory,
    /// `ReactiveSequence`: conditions before the running child are re-read.
    ReactiveSequence,
    /// `Fallback` (`Selector`): children in order until one succeeds.
    Fallback,
    /// `ReactiveFallback`.
    ReactiveFallback,
    /// `Parallel`: all children at once; thresholds as written (negative
    /// counts from the number of children, -1 = all).
    Parallel {
        /// `success_count` (v4) or `success_threshold` (v3).
        success: i64,
        /// `failure_count` (v4) or `failure_threshold` (v3).
        failure: i64,
    },
    /// `ParallelAll`: every child to completion; fails when more than
    /// `max_failures` failed.
    ParallelAll {
        /// `max_failures` (-1 = never).
        max_failures: i64,
    },
    /// `IfThenElse(condition, then[, else])`.
    IfThenElse,
    /// `WhileDoElse(condition, do[, else])`: the condition is re-read.
    WhileDoElse,
    /// `SwitchN`: one of `cases` children by a blackboard value, the last as
    /// default — a choice the tree leaves open.
    Switch {
        /// Number of children (cases + default).
        cases: usize,
    },
    /// Nav2 `PipelineSequence`: earlier children keep being ticked while
    /// later ones run.
    PipelineSequence,
    /// Nav2 `RecoveryNode`: `child0`, and on its failure `child1` then
    /// `child0` again, at most `retries` times.
    Recovery {
        /// `number_of_retries`.
        retries: u32,
    },
    /// Nav2 `RoundRobin`: one child at a time, resuming after the last tried.
    RoundRobin,
    /// `Inverter`.
    Inverter,
    /// `ForceSuccess`.
    ForceSuccess,
    /// `ForceFailure`.
    ForceFailure,
    /// `Repeat`: the child `cycles` times while it succeeds (-1: forever).
    Repeat {
        /// `num_cycles`.
        cycles: i64,
    },
    /// `RetryUntilSuccessful`: the child until it succeeds, at most
    /// `attempts` times (-1: forever).
    Retry {
        /// `num_attempts`.
        attempts: i64,
    },
    /// `KeepRunningUntilFailure`: restarts the child while it succeeds.
    KeepRunningUntilFailure,
    /// `Timeout`: fails and halts the child after `msec` (mean).
    Timeout {
        /// Mean timeout, seconds.
        mean_s: f64,
    },
    /// `Delay`: waits `delay_msec` (mean), then runs the child.
    Delay {
        /// Mean delay, seconds.
        mean_s: f64,
    },
    /// Nav2 `RateController`, `DistanceController`, `SpeedController`,
    /// `GoalUpdatedController`: runs the child at activation, then again
    /// after each interval while its parent keeps ticking it.
    Periodic {
        /// Mean interval between runs, seconds, as the XML gives it (`hz`);
        /// `None` when it depends on the robot (distance, speed, goal
        /// updates): then from the sidecar, or never.
        mean_interval_s: Option<f64>,
    },
    /// A decorator that runs its child only while a condition of the world
    /// holds, else succeeds at once (Nav2 `PathLongerOnApproach`).
    Gate,
    /// A decorator with no effect on results or timing here (Nav2
    /// `GoalUpdater`, `SingleTrigger`; `SubTree` wrappers are removed).
    PassThrough,
}

impl Kind {
    /// Whether the node is a leaf.
    pub fn is_leaf(&self) -> bool {
        matches!(
            self,
            Kind::Action | Kind::Condition | Kind::Constant { .. } | Kind::Sleep { .. }
        )
    }
}

/// How a port passes data.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Direction {
    /// Read by the node.
    Input,
    /// Written by the node.
    Output,
    /// Both.
    InOut,
    /// No model says.
    Unknown,
}

/// One port of a node as the XML sets it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Port {
    /// The port's name (the attribute).
    pub name: String,
    /// The attribute's value as written.
    pub value: String,
    /// Its direction, from the node's model.
    pub direction: Direction,
    /// The blackboard entry it refers to, in the root blackboard's names
    /// after subtree remapping (`None` for a literal value). Entries private
    /// to a subtree instance are named `SubtreeID#k/entry`.
    pub key: Option<String>,
}

/// A node of the expanded tree.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Node {
    /// What it does.
    pub kind: Kind,
    /// Its type: the element name, or the `ID` of `<Action ID=…>` forms.
    pub id: String,
    /// The `name` attribute, if any.
    pub name: Option<String>,
    /// Path from the main tree: `Tree/Kind(name)/Kind#i/…`, each step named
    /// by its type and its `name`, or by its child index when unnamed;
    /// subtrees appear as `SubTree(ID)`.
    pub path: String,
    /// File (index into [`Tree::files`]).
    pub file: usize,
    /// 1-based line of the element.
    pub line: u32,
    /// Children in order.
    pub children: Vec<NodeId>,
    /// The parent (`None` for the root).
    pub parent: Option<NodeId>,
    /// Ports with their blackboard keys.
    pub ports: Vec<Port>,
}

impl Node {
    /// The key under which the sidecar's parameters are looked up: the
    /// `name` if given, else the type.
    pub fn param_key(&self) -> &str {
        self.name.as_deref().unwrap_or(&self.id)
    }

    /// `Type(name)` or `Type`.
    pub fn label(&self) -> String {
        match &self.name {
            Some(n) if n != &self.id => format!("{}({n})", self.id),
            _ => self.id.clone(),
        }
    }
}

/// A subtree that a `SubTree` node names but no file defines, kept for
/// `bt check` (reading fails on it unless asked to keep going).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MissingSubtree {
    /// The `ID` asked for.
    pub id: String,
    /// The `SubTree` node's path.
    pub path: String,
    /// Its file.
    pub file: usize,
    /// Its line.
    pub line: u32,
}

/// A behaviour tree, expanded from its main tree.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Tree {
    /// The main tree's `ID`.
    pub main: String,
    /// Nodes; [`NodeId`] indexes this; the root is node 0.
    pub nodes: Vec<Node>,
    /// Files read (the first is the one given; then includes).
    pub files: Vec<String>,
    /// `BTCPP_format` as written (3 or 4; 3 when absent).
    pub format: u32,
    /// `BehaviorTree` definitions never reached from the main tree.
    pub unused_trees: Vec<(String, usize, u32)>,
    /// `SubTree` references to trees no file defines (only with
    /// [`crate::ReadOptions::keep_missing`], each then an action leaf;
    /// otherwise reading fails).
    pub missing: Vec<MissingSubtree>,
    /// `SubTree` references that close a cycle, with the cycle (only with
    /// [`crate::ReadOptions::keep_missing`]; otherwise reading fails).
    pub cycles: Vec<(String, MissingSubtree)>,
}

impl Tree {
    /// The root node.
    pub const ROOT: NodeId = NodeId(0);

    /// A node.
    pub fn node(&self, id: NodeId) -> &Node {
        &self.nodes[id.index()]
    }

    /// Number of nodes.
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// Whether the tree has no node (never true for a tree that was read).
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// Node ids in depth-first pre-order (the order the XML lists them).
    pub fn preorder(&self) -> Vec<NodeId> {
        self.preorder_from(Tree::ROOT)
    }

    /// The subtree of `n` (itself first) in depth-first pre-order.
    pub fn preorder_from(&self, n: NodeId) -> Vec<NodeId> {
        let mut out = Vec::new();
        let mut stack = vec![n];
        while let Some(n) = stack.pop() {
            out.push(n);
            stack.extend(self.node(n).children.iter().rev().copied());
        }
        out
    }

    /// The leaves under `n` (itself if a leaf), in order.
    pub fn leaves_under(&self, n: NodeId) -> Vec<NodeId> {
        let mut out = Vec::new();
        let mut stack = vec![n];
        while let Some(m) = stack.pop() {
            let node = self.node(m);
            if node.kind.is_leaf() {
                out.push(m);
            }
            stack.extend(node.children.iter().rev().copied());
        }
        out
    }

    /// Where a node is: `file:line`.
    pub fn location(&self, n: NodeId) -> String {
        let node = self.node(n);
        format!("{}:{}", self.files[node.file], node.line)
    }
}
