//! Structural checks of a tree (`petrinav bt check`), each finding with the
//! node's path, file and line (docs/behaviour-trees.md, *Checks*):
//!
//! | kind | what |
//! |---|---|
//! | `unreachable` | a node no tick can reach: after a child that always succeeds in a Fallback, always fails in a Sequence; a recovery that is never needed; a `BehaviorTree` no one uses |
//! | `endless_loop` | a loop with no way out: `RetryUntilSuccessful` forever around a child that cannot succeed, `Repeat`/`KeepRunningUntilFailure` forever around one that cannot fail |
//! | `never_succeeds` | the tree as a whole can only fail or run forever |
//! | `reactive_preemption` | a reactive node with a child that keeps running before a later one that also runs: BehaviorTree.CPP re-starts the first at every tick and it pre-empts the later one forever (a gate such as Nav2's `PathLongerOnApproach`, which runs its child only while its condition holds, counts as passing at once) |
//! | `read_before_write` | an input port reads a blackboard entry that no node has written on some path to it, and that the application does not provide |
//! | `missing_subtree`, `subtree_cycle` | a `SubTree` no file defines; subtrees that include each other |
//! | `dead_parallel_threshold` | a `Parallel` threshold that can never be reached, or never matters |
//!
//! "Always succeeds/fails" is decided from the structure: constants,
//! `ForceSuccess`/`ForceFailure`, inverted ones, loops that exit only one
//! way, and Nav2's selector actions (which return SUCCESS whatever
//! happens); every other leaf may do either. A read is not reported when
//! the reading node sits in an earlier child of a Fallback whose later child
//! writes the entry (the "check, else compute" idiom of Nav2's trees), nor
//! in an earlier child of a node that re-ticks it while a later child runs
//! (reactive Sequence or Fallback, PipelineSequence) when a later child
//! writes the entry: a monitor of the running child's reports, which finds
//! the entry unset at its first tick by construction (Nav2's
//! `IsWithinPathTrackingBounds` passes until `FollowPath`'s first tracking
//! feedback). The first idiom's premise is taken on both sides: a check
//! whose entry is unset fails (Nav2's `ValidatePath` rejects an empty
//! path), so after the Fallback the entries its later children write count
//! as written on that path.

use std::collections::{BTreeSet, HashMap};

use serde::Serialize;

use crate::params::TreeParams;
use crate::tree::{Direction, Kind, NodeId, Tree};

/// What a finding is about.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum FindingKind {
    /// A node no tick reaches.
    Unreachable,
    /// A loop with no way out.
    EndlessLoop,
    /// The tree can never succeed.
    NeverSucceeds,
    /// A reactive node that pre-empts a later child forever.
    ReactivePreemption,
    /// A blackboard entry read before any node writes it.
    ReadBeforeWrite,
    /// A `SubTree` no file defines.
    MissingSubtree,
    /// Subtrees that include each other.
    SubtreeCycle,
    /// A `Parallel` threshold that can never be met or never matters.
    DeadParallelThreshold,
}

impl FindingKind {
    /// The snake-case name (as in JSON).
    pub fn name(self) -> &'static str {
        match self {
            FindingKind::Unreachable => "unreachable",
            FindingKind::EndlessLoop => "endless_loop",
            FindingKind::NeverSucceeds => "never_succeeds",
            FindingKind::ReactivePreemption => "reactive_preemption",
            FindingKind::ReadBeforeWrite => "read_before_write",
            FindingKind::MissingSubtree => "missing_subtree",
            FindingKind::SubtreeCycle => "subtree_cycle",
            FindingKind::DeadParallelThreshold => "dead_parallel_threshold",
        }
    }
}

/// One finding.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Finding {
    /// What.
    pub kind: FindingKind,
    /// The node's path.
    pub path: String,
    /// Its file.
    pub file: String,
    /// Its line.
    pub line: u32,
    /// Explanation.
    pub message: String,
}

/// Options of [`check`].
#[derive(Debug, Clone)]
pub struct CheckOptions {
    /// Blackboard entries the application writes before the tree runs.
    pub external: BTreeSet<String>,
}

/// Prefixes of the error codes that Nav2's `bt_navigator` clears (so
/// writes) before each goal (`error_code_name_prefixes`, default list).
const NAV2_ERROR_PREFIXES: [&str; 12] = [
    "assisted_teleop",
    "backup",
    "compute_path",
    "dock_robot",
    "drive_on_heading",
    "follow_object",
    "follow_path",
    "nav_thru_poses",
    "nav_to_pose",
    "spin",
    "undock_robot",
    "wait",
];

impl CheckOptions {
    /// What Nav2's navigators write before a tree runs: `goal`, `goals`,
    /// `path`, `waypoint_statuses`, `number_recoveries`, and
    /// `<prefix>_error_code` / `<prefix>_error_msg` for the default prefixes.
    pub fn nav2() -> CheckOptions {
        let mut external: BTreeSet<String> =
            ["goal", "goals", "path", "waypoint_statuses", "number_recoveries"]
                .iter()
                .map(|s| s.to_string())
                .collect();
        for p in NAV2_ERROR_PREFIXES {
            external.insert(format!("{p}_error_code"));
            external.insert(format!("{p}_error_msg"));
        }
        CheckOptions { external }
    }

    /// Nothing provided from outside.
    pub fn none() -> CheckOptions {
        CheckOptions {
            external: BTreeSet::new(),
        }
    }
}

/// Nav2 actions that always return SUCCESS (the selectors).
const ALWAYS_SUCCEED: [&str; 6] = [
    "ControllerSelector",
    "PlannerSelector",
    "GoalCheckerSelector",
    "ProgressCheckerSelector",
    "SmootherSelector",
    "PathHandlerSelector",
];

/// Nav2's other actions that finish within their tick (`BT::SyncActionNode`s
/// besides the selectors).
const NAV2_SYNC: [&str; 9] = [
    "GetCurrentPose",
    "GetPoseFromPath",
    "ConcatenatePaths",
    "RemovePassedGoals",
    "TruncatePath",
    "TruncatePathLocal",
    "ExtractRouteNodesAsGoals",
    "AppendGoalPoseToGoals",
    "GetNextFewGoals",
];

/// Whether Nav2 implements action `id` as a synchronous node.
fn nav2_sync(id: &str) -> bool {
    ALWAYS_SUCCEED.contains(&id) || NAV2_SYNC.contains(&id)
}

struct Checker<'a> {
    tree: &'a Tree,
    params: Option<&'a TreeParams>,
    options: &'a CheckOptions,
    can_ok: Vec<bool>,
    can_ko: Vec<bool>,
    keys: Keys<'a>,
    findings: Vec<Finding>,
}

/// The blackboard entries of a tree as numbers, for the read-before-write
/// flow: a set of entries is a bitset, and whether a subtree writes an
/// entry is a range query on its writers' pre-order positions (a subtree is
/// a range of them): the flow is linear in the width of a node, where sets
/// of names and subtree walks made it quadratic (`crates/bt/BENCHMARKS.md`).
struct Keys<'a> {
    ids: HashMap<&'a str, u32>,
    /// Pre-order position of each node, and where its subtree's range ends.
    pre: Vec<u32>,
    end: Vec<u32>,
    /// Per entry, the pre-order positions of the nodes that write it,
    /// ascending.
    writers: Vec<Vec<u32>>,
    /// Per node, the entries it writes, and its input ports (index in its
    /// port list) with the entry each reads.
    writes: Vec<Vec<u32>>,
    reads: Vec<Vec<(usize, u32)>>,
}

impl<'a> Keys<'a> {
    fn new(tree: &'a Tree, external: &'a BTreeSet<String>) -> Keys<'a> {
        let n = tree.len();
        let order = tree.preorder();
        let mut pre = vec![0u32; n];
        for (i, m) in order.iter().enumerate() {
            pre[m.index()] = i as u32;
        }
        // A subtree's range ends where its last child's ends.
        let mut end = vec![0u32; n];
        for m in order.iter().rev() {
            let node = tree.node(*m);
            end[m.index()] = node
                .children
                .last()
                .map_or(pre[m.index()] + 1, |c| end[c.index()]);
        }
        let mut ids: HashMap<&str, u32> = HashMap::new();
        let mut intern = |k: &'a str| -> u32 {
            let next = ids.len() as u32;
            *ids.entry(k).or_insert(next)
        };
        for k in external {
            intern(k);
        }
        let mut writes = vec![Vec::new(); n];
        let mut reads = vec![Vec::new(); n];
        for m in &order {
            for (i, p) in tree.node(*m).ports.iter().enumerate() {
                let Some(k) = p.key.as_deref() else { continue };
                let id = intern(k);
                if matches!(p.direction, Direction::Output | Direction::InOut) {
                    writes[m.index()].push(id);
                }
                if matches!(p.direction, Direction::Input | Direction::InOut) {
                    reads[m.index()].push((i, id));
                }
            }
        }
        let mut writers = vec![Vec::new(); ids.len()];
        for m in &order {
            for &k in &writes[m.index()] {
                writers[k as usize].push(pre[m.index()]);
            }
        }
        Keys {
            ids,
            pre,
            end,
            writers,
            writes,
            reads,
        }
    }

    fn len(&self) -> usize {
        self.writers.len()
    }

    /// Whether a node at a pre-order position in `from..to` writes `key`.
    fn written_in(&self, key: u32, from: u32, to: u32) -> bool {
        let w = &self.writers[key as usize];
        let i = w.partition_point(|&x| x < from);
        i < w.len() && w[i] < to
    }

    /// Whether some node of `n`'s subtree writes `key`.
    fn writes_within(&self, n: NodeId, key: u32) -> bool {
        self.written_in(key, self.pre[n.index()], self.end[n.index()])
    }

    /// Whether a later child of `parent` than `child` writes `key` (their
    /// subtrees follow `child`'s to the end of `parent`'s).
    fn later_sibling_writes(&self, child: NodeId, parent: NodeId, key: u32) -> bool {
        self.written_in(key, self.end[child.index()], self.end[parent.index()])
    }
}

/// A set of blackboard entries (see [`Keys`]).
#[derive(Clone)]
struct KeySet(Vec<u64>);

impl KeySet {
    fn new(keys: usize) -> KeySet {
        KeySet(vec![0; keys.div_ceil(64)])
    }

    fn contains(&self, k: u32) -> bool {
        self.0[k as usize / 64] >> (k % 64) & 1 == 1
    }

    fn insert(&mut self, k: u32) {
        self.0[k as usize / 64] |= 1 << (k % 64);
    }

    /// The entries in both.
    fn meet(&self, other: &KeySet) -> KeySet {
        KeySet(self.0.iter().zip(&other.0).map(|(a, b)| a & b).collect())
    }
}

/// Checks `tree`. With `params`, an action with a mean time of 0 counts as
/// instantaneous; without, Nav2's synchronous actions do.
pub fn check(tree: &Tree, params: Option<&TreeParams>, options: &CheckOptions) -> Vec<Finding> {
    let mut c = Checker {
        tree,
        params,
        options,
        can_ok: vec![true; tree.len()],
        can_ko: vec![true; tree.len()],
        keys: Keys::new(tree, &options.external),
        findings: Vec::new(),
    };
    c.outcomes();
    c.structure();
    c.subtrees();
    c.reads();
    c.findings
        .sort_by(|a, b| (a.line, a.kind, &a.path).cmp(&(b.line, b.kind, &b.path)));
    c.findings.dedup();
    c.findings
}

impl Checker<'_> {
    fn add(&mut self, kind: FindingKind, n: NodeId, message: String) {
        let node = self.tree.node(n);
        self.findings.push(Finding {
            kind,
            path: node.path.clone(),
            file: self.tree.files[node.file].clone(),
            line: node.line,
            message,
        });
    }

    /// Whether each node can succeed / fail, bottom-up.
    fn outcomes(&mut self) {
        for n in self.tree.preorder().into_iter().rev() {
            let node = self.tree.node(n);
            let k: Vec<usize> = node.children.iter().map(|c| c.index()).collect();
            let ok = |i: usize| self.can_ok[k[i]];
            let ko = |i: usize| self.can_ko[k[i]];
            let all_ok = k.iter().all(|&c| self.can_ok[c]);
            let any_ok = k.iter().any(|&c| self.can_ok[c]);
            let all_ko = k.iter().all(|&c| self.can_ko[c]);
            let any_ko = k.iter().any(|&c| self.can_ko[c]);
            let (s, f) = match &node.kind {
                Kind::Constant { success } => (*success, !*success),
                Kind::Sleep { .. } => (true, false),
                Kind::Action if ALWAYS_SUCCEED.contains(&node.id.as_str()) => (true, false),
                Kind::Action | Kind::Condition => (true, true),
                Kind::Sequence
                | Kind::ReactiveSequence
                | Kind::SequenceWithMemory
                | Kind::PipelineSequence => (all_ok, any_ko),
                Kind::Fallback | Kind::ReactiveFallback => (any_ok, all_ko),
                Kind::Parallel { .. } | Kind::ParallelAll { .. } => (any_ok, any_ko),
                Kind::IfThenElse | Kind::WhileDoElse => {
                    let else_ok = k.len() == 3 && ok(2);
                    let else_ko = k.len() < 3 || ko(2);
                    (
                        (ok(0) && ok(1)) || (ko(0) && else_ok),
                        (ok(0) && ko(1)) || (ko(0) && else_ko),
                    )
                }
                Kind::Switch { .. } => (any_ok, any_ko),
                Kind::Recovery { .. } => (ok(0), ko(0)),
                Kind::RoundRobin => (any_ok, all_ko),
                Kind::Inverter => (ko(0), ok(0)),
                Kind::ForceSuccess => (true, false),
                Kind::ForceFailure => (false, true),
                Kind::Repeat { cycles } => (*cycles >= 0 && ok(0) || *cycles == 0, ko(0)),
                Kind::Retry { attempts } => (ok(0), *attempts >= 0 && ko(0)),
                Kind::KeepRunningUntilFailure => (false, ko(0)),
                Kind::Timeout { .. } => (ok(0), true),
                Kind::Delay { .. } | Kind::PassThrough | Kind::Periodic { .. } => (ok(0), ko(0)),
                Kind::Gate => (true, ko(0)),
            };
            self.can_ok[n.index()] = s;
            self.can_ko[n.index()] = f;
        }
    }

    /// Whether leaf-level node `n` finishes within its tick.
    fn instantaneous(&self, n: NodeId) -> bool {
        self.tree.preorder_from(n).into_iter().all(|m| {
            let node = self.tree.node(m);
            match node.kind {
                Kind::Action => match self.params {
                    Some(p)
                        if p.actions.contains_key(node.param_key()) || p.actions.contains_key(&node.path) =>
                    {
                        let a = p.action(self.tree, m);
                        a.mean_time_success == 0.0 && a.mean_time_failure == 0.0
                    }
                    _ => nav2_sync(&node.id),
                },
                Kind::Sleep { mean_s } => mean_s == 0.0,
                Kind::Timeout { .. } | Kind::Delay { .. } | Kind::Periodic { .. } => false,
                _ => true,
            }
        }) || matches!(self.tree.node(n).kind, Kind::Gate)
    }

    fn structure(&mut self) {
        for n in self.tree.preorder() {
            let node = self.tree.node(n).clone();
            let kids = node.children.clone();
            match node.kind {
                Kind::Sequence
                | Kind::ReactiveSequence
                | Kind::SequenceWithMemory
                | Kind::PipelineSequence => {
                    if let Some(i) = kids[..kids.len().saturating_sub(1)]
                        .iter()
                        .position(|c| !self.can_ok[c.index()])
                    {
                        self.unreachable_after(
                            &kids,
                            i,
                            "cannot succeed, so the children after it never run",
                        );
                    }
                }
                Kind::Fallback | Kind::ReactiveFallback => {
                    if let Some(i) = kids[..kids.len().saturating_sub(1)]
                        .iter()
                        .position(|c| !self.can_ko[c.index()])
                    {
                        self.unreachable_after(&kids, i, "cannot fail, so the children after it never run");
                    }
                }
                Kind::Recovery { retries } => {
                    if retries == 0 {
                        self.add(
                            FindingKind::Unreachable,
                            kids[1],
                            "number_of_retries is 0: the recovery never runs".into(),
                        );
                    } else if !self.can_ko[kids[0].index()] {
                        self.add(
                            FindingKind::Unreachable,
                            kids[1],
                            "the first child cannot fail: the recovery never runs".into(),
                        );
                    }
                }
                Kind::Repeat { cycles: 0 } => {
                    self.add(
                        FindingKind::Unreachable,
                        kids[0],
                        "num_cycles is 0: never ticked".into(),
                    );
                }
                Kind::Retry { attempts: 0 } => {
                    self.add(
                        FindingKind::Unreachable,
                        kids[0],
                        "num_attempts is 0: never ticked".into(),
                    );
                }
                Kind::Retry { attempts: -1 } if !self.can_ok[kids[0].index()] => self.add(
                    FindingKind::EndlessLoop,
                    n,
                    "retries forever a child that cannot succeed: a loop with no way out".into(),
                ),
                Kind::Repeat { cycles: -1 } if !self.can_ko[kids[0].index()] => self.add(
                    FindingKind::EndlessLoop,
                    n,
                    "repeats forever a child that cannot fail: a loop with no way out".into(),
                ),
                Kind::KeepRunningUntilFailure if !self.can_ko[kids[0].index()] => self.add(
                    FindingKind::EndlessLoop,
                    n,
                    "restarts forever a child that cannot fail: a loop with no way out".into(),
                ),
                Kind::IfThenElse | Kind::WhileDoElse => {
                    if !self.can_ok[kids[0].index()] {
                        self.add(
                            FindingKind::Unreachable,
                            kids[1],
                            "the condition cannot succeed".into(),
                        );
                    }
                    if kids.len() == 3 && !self.can_ko[kids[0].index()] {
                        self.add(
                            FindingKind::Unreachable,
                            kids[2],
                            "the condition cannot fail".into(),
                        );
                    }
                }
                Kind::Parallel { success, failure } => self.parallel(n, kids.len() as i64, success, failure),
                _ => {}
            }
            if matches!(node.kind, Kind::ReactiveSequence | Kind::ReactiveFallback) {
                self.reactive(n);
            }
        }
        if !self.can_ok[Tree::ROOT.index()] {
            self.add(
                FindingKind::NeverSucceeds,
                Tree::ROOT,
                "the tree can never return SUCCESS: it only fails or runs forever".into(),
            );
        }
    }

    fn unreachable_after(&mut self, kids: &[NodeId], i: usize, why: &str) {
        let label = self.tree.node(kids[i]).label();
        for &c in &kids[i + 1..] {
            self.add(FindingKind::Unreachable, c, format!("`{label}` {why}"));
        }
    }

    fn reactive(&mut self, n: NodeId) {
        let kids = self.tree.node(n).children.clone();
        let durative: Vec<usize> = (0..kids.len())
            .filter(|&i| !self.instantaneous(kids[i]))
            .collect();
        if let [first, .., last] = durative.as_slice() {
            let a = self.tree.node(kids[*first]).label();
            let b = self.tree.node(kids[*last]).label();
            self.add(
                FindingKind::ReactivePreemption,
                kids[*first],
                format!(
                    "`{a}` keeps running before `{b}`, which also runs: the reactive parent restarts `{a}` at every tick and it pre-empts `{b}` forever (BehaviorTree.CPP 4 throws here when its exception for several running children is enabled)"
                ),
            );
        }
    }

    fn parallel(&mut self, n: NodeId, count: i64, success: i64, failure: i64) {
        let need_s = if success < 0 { count + success + 1 } else { success };
        let need_f = if failure < 0 { count + failure + 1 } else { failure };
        let mut say = |m: String| self.add(FindingKind::DeadParallelThreshold, n, m);
        if need_s > count || need_s < 0 {
            say(format!(
                "success_count {success} needs {need_s} of {count} children: it can never succeed"
            ));
        } else if need_f > count || need_f < 0 {
            say(format!(
                "failure_count {failure} needs {need_f} of {count} children: it can never be reached"
            ));
        } else if need_f > count - need_s + 1 {
            say(format!(
                "failure_count {need_f} never matters: with {count} children and a success count of {need_s}, the parallel fails after {} failures",
                count - need_s + 1
            ));
        } else if need_s == 0 {
            say("success_count 0: it succeeds before any child runs".into());
        }
    }

    fn subtrees(&mut self) {
        let tree = self.tree;
        for m in &tree.missing {
            self.findings.push(Finding {
                kind: FindingKind::MissingSubtree,
                path: m.path.clone(),
                file: tree.files[m.file].clone(),
                line: m.line,
                message: format!("the subtree `{}` is not defined in any file read", m.id),
            });
        }
        for (cycle, m) in &tree.cycles {
            self.findings.push(Finding {
                kind: FindingKind::SubtreeCycle,
                path: m.path.clone(),
                file: tree.files[m.file].clone(),
                line: m.line,
                message: cycle.clone(),
            });
        }
        for (id, file, line) in &tree.unused_trees {
            self.findings.push(Finding {
                kind: FindingKind::Unreachable,
                path: format!("BehaviorTree({id})"),
                file: tree.files[*file].clone(),
                line: *line,
                message: format!("the tree `{id}` is defined but never used by `{}`", tree.main),
            });
        }
    }

    fn reads(&mut self) {
        let mut start = KeySet::new(self.keys.len());
        for k in &self.options.external {
            if let Some(&id) = self.keys.ids.get(k.as_str()) {
                start.insert(id);
            }
        }
        self.flow(Tree::ROOT, &start);
    }

    /// Whether a read of `key` at `n` is one of two idioms: "check, else
    /// compute" (`n` is under an earlier child of a Fallback whose later
    /// child writes `key`) or a monitor (`n` is under an earlier child of a
    /// node that re-ticks its earlier children while a later one runs — a
    /// reactive Sequence or Fallback, a PipelineSequence — and a later child
    /// writes `key`: the monitor reads what the running child reports).
    fn guarded(&self, n: NodeId, key: u32) -> bool {
        let mut child = n;
        while let Some(p) = self.tree.node(child).parent {
            let parent = self.tree.node(p);
            if matches!(
                parent.kind,
                Kind::Fallback | Kind::ReactiveFallback | Kind::ReactiveSequence | Kind::PipelineSequence
            ) && self.keys.later_sibling_writes(child, p, key)
            {
                return true;
            }
            child = p;
        }
        false
    }

    /// Whether `c`'s subtree reads an entry that is not in `defined`, that
    /// `c` does not write itself, and that a later child of `parent` writes:
    /// a check of "check, else compute" whose entry is unset.
    fn checks_unset(&self, c: NodeId, parent: NodeId, defined: &KeySet) -> bool {
        self.tree.preorder_from(c).into_iter().any(|m| {
            self.keys.reads[m.index()].iter().any(|&(_, k)| {
                !defined.contains(k)
                    && !self.keys.writes_within(c, k)
                    && self.keys.later_sibling_writes(c, parent, k)
            })
        })
    }

    /// Reports the input ports of `n` that read entries not in `defined`.
    fn read_ports(&mut self, n: NodeId, defined: &KeySet) {
        for i in 0..self.keys.reads[n.index()].len() {
            let (port, k) = self.keys.reads[n.index()][i];
            if !defined.contains(k) && !self.guarded(n, k) {
                let p = &self.tree.node(n).ports[port];
                let message = format!(
                    "port `{}` reads `{{{}}}`, which no node has written on some path to here (and the application does not provide it)",
                    p.name,
                    p.key.as_deref().unwrap_or_default()
                );
                self.add(FindingKind::ReadBeforeWrite, n, message);
            }
        }
    }

    /// `defined` with the entries `n` writes.
    fn with_writes(&self, n: NodeId, defined: &KeySet) -> KeySet {
        let mut out = defined.clone();
        for &k in &self.keys.writes[n.index()] {
            out.insert(k);
        }
        out
    }

    /// Entries defined after `n` succeeds and after it fails, given those
    /// defined before; reports reads of undefined entries.
    fn flow(&mut self, n: NodeId, defined: &KeySet) -> (KeySet, KeySet) {
        let tree = self.tree;
        let node = tree.node(n);
        let kids = &node.children;
        let meet = KeySet::meet;
        // A node's own ports: read when it is ticked; a decorator or control
        // node (Nav2's GoalUpdater) writes its outputs before its children run.
        if node.kind.is_leaf() || kids.is_empty() {
            self.read_ports(n, defined);
            let out = self.with_writes(n, defined);
            return (out.clone(), out);
        }
        self.read_ports(n, defined);
        let defined = &self.with_writes(n, defined);
        match node.kind {
            Kind::Sequence | Kind::ReactiveSequence | Kind::SequenceWithMemory | Kind::PipelineSequence => {
                let mut d = defined.clone();
                let mut fail: Option<KeySet> = None;
                for &c in kids {
                    let (s, f) = self.flow(c, &d);
                    if self.can_ko[c.index()] {
                        fail = Some(fail.map_or(f.clone(), |x| meet(&x, &f)));
                    }
                    d = s;
                }
                let f = fail.unwrap_or_else(|| d.clone());
                (d, f)
            }
            Kind::Fallback | Kind::ReactiveFallback | Kind::RoundRobin => {
                let round = matches!(node.kind, Kind::RoundRobin);
                let mut d = defined.clone();
                let mut ok: Option<KeySet> = None;
                for &c in kids {
                    let (s, f) = self.flow(c, if round { defined } else { &d });
                    // The idiom's premise, taken on both sides: a check of an
                    // entry that a later child computes fails while the entry
                    // is unset, so it does not end the Fallback on this path.
                    let unset_check = !round && self.checks_unset(c, n, &d);
                    if self.can_ok[c.index()] && !unset_check {
                        ok = Some(ok.map_or(s.clone(), |x| meet(&x, &s)));
                    }
                    d = if round { defined.clone() } else { f };
                }
                let s = ok.unwrap_or_else(|| d.clone());
                (s, d)
            }
            Kind::Recovery { .. } => {
                let (s0, f0) = self.flow(kids[0], defined);
                let (_, f1) = self.flow(kids[1], &f0);
                (s0, meet(&f0, &f1))
            }
            Kind::IfThenElse | Kind::WhileDoElse => {
                let (sc, fc) = self.flow(kids[0], defined);
                let (s1, f1) = self.flow(kids[1], &sc);
                match kids.get(2) {
                    Some(&e) => {
                        let (s2, f2) = self.flow(e, &fc);
                        (meet(&s1, &s2), meet(&f1, &f2))
                    }
                    None => (s1, meet(&f1, &fc)),
                }
            }
            Kind::Inverter => {
                let (s, f) = self.flow(kids[0], defined);
                (f, s)
            }
            Kind::Parallel { .. } | Kind::ParallelAll { .. } | Kind::Switch { .. } => {
                for &c in kids {
                    self.flow(c, defined);
                }
                (defined.clone(), defined.clone())
            }
            Kind::Gate => {
                self.flow(kids[0], defined);
                (defined.clone(), defined.clone())
            }
            _ => {
                let (s, f) = self.flow(kids[0], defined);
                let both = meet(&s, &f);
                match node.kind {
                    Kind::ForceSuccess | Kind::ForceFailure => (both.clone(), both),
                    _ => (s, f),
                }
            }
        }
    }
}
