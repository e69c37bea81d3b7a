//! A behaviour tree as a GSPN (docs/behaviour-trees.md, *Translation*).
//!
//! Ticks become events: the tree is assumed to be ticked at once after
//! every change (an action ends, a condition changes, a timer expires), so
//! each node is a sub-net that a token enters through its `go` place and
//! leaves through `ok` or `ko`. Zero-time logic (control flow, conditions
//! read, outcome draws) is immediate transitions; durations are timed ones
//! (Erlang chains of `phases` exponential stages; an action whose duration
//! does not depend on its outcome draws the outcome in its last stage, a
//! race of two timed transitions, which halves the running states). A parent that stops a
//! running child (reactive pre-emption, a parallel decided, a pipeline that
//! failed, a timeout) marks the child's `halt` place; high-priority
//! transitions then clear every place of the child's subtree, one place
//! after the other, and `halted` tells the parent when it is empty.
//!
//! Conditions are places of the world (`true`/`false`), shared by the
//! nodes with the same parameter key; timed transitions switch them while
//! the tree runs. The tree's end is the place `done_ok` or `done_ko`; every
//! end marking is dead, so the CTMC is absorbing.

use std::collections::BTreeMap;

use petri::{ArcKind, Net, PlaceId, TransitionId};

use crate::error::{Error, Result};
use crate::formula::Formula;
use crate::params::TreeParams;
use crate::tree::{Kind, NodeId, Tree};

/// Priority of the conditions' initial draws (before anything else).
const PRI_INIT: u32 = 1_000_000;
/// Priority of resetting persistent indices of a node halted while running.
const PRI_RESET: u32 = 500_000;
/// Priorities of clearing a halted subtree: `PRI_CLEAN + k` for its k-th place.
const PRI_CLEAN: u32 = 1_000;
/// Priority of reporting a halted subtree empty.
const PRI_HALTED: u32 = 500;
/// Priority of reactive pre-emption.
const PRI_PREEMPT: u32 = 2;
/// Priority of ordinary control flow.
const PRI_FLOW: u32 = 1;

/// What a timed transition stands for (to attribute failures to it).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(tag = "event", rename_all = "snake_case")]
pub enum Trigger {
    /// An action leaf ends with success.
    Success {
        /// The leaf.
        node: NodeId,
    },
    /// An action leaf ends with failure.
    Failure {
        /// The leaf.
        node: NodeId,
    },
    /// A condition changes (the first node reading it).
    Change {
        /// The condition.
        node: NodeId,
    },
    /// A timer of a `Timeout`, `Delay` or periodic decorator.
    Timer {
        /// The decorator.
        node: NodeId,
    },
    /// An intermediate Erlang phase (no outcome).
    Phase,
}

/// What the rate of a timed transition is made of (for sensitivities).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RateRole {
    /// A stage of an action's duration: `phases / mean_time`.
    Duration,
    /// A condition's change: proportional to its `change_rate`.
    Change,
    /// A stage of a decorator's timer.
    Timer,
}

/// The net of a tree and what its places and transitions stand for.
#[derive(Debug, Clone)]
pub struct Translation {
    /// The GSPN.
    pub net: Net,
    /// Marked when the tree has succeeded.
    pub done_ok: PlaceId,
    /// Marked when the tree has failed.
    pub done_ko: PlaceId,
    /// Per node (by [`NodeId`]): the places marked while it is active.
    pub activity: Vec<Vec<PlaceId>>,
    /// Per transition: what a timed transition stands for (`None` for immediate ones).
    pub triggers: Vec<Option<Trigger>>,
    /// Per transition: the node whose parameter sets its rate, and how
    /// (`None` for immediate transitions).
    pub roles: Vec<Option<(NodeId, RateRole)>>,
    /// Each persistent condition's places and changes, by its key.
    pub conditions: BTreeMap<String, ConditionNet>,
}

impl Translation {
    /// The places of the world: every persistent condition's `true` and
    /// `false` places. The zero-time control flow only tests them, so the
    /// analysis passes them to the state-space generation as the context
    /// its memory of forced hops may leave out
    /// ([`petri::ExploreParams::forced_context`]).
    pub fn world(&self) -> Vec<PlaceId> {
        self.conditions
            .values()
            .flat_map(|c| [c.holds, c.fails])
            .collect()
    }
}

/// A persistent condition in the net: its `true` and `false` places (one
/// marked from the start, drawn by two immediate transitions weighted
/// `p_true` and `1 − p_true`) and its changes (rates `change_rate·(1 −
/// p_true)` to false and `change_rate·p_true` to true; `None` where the
/// rate is 0).
#[derive(Debug, Clone, Copy)]
pub struct ConditionNet {
    /// Marked while the condition holds.
    pub holds: PlaceId,
    /// Marked while it does not.
    pub fails: PlaceId,
    /// The change from true to false.
    pub to_false: Option<TransitionId>,
    /// The change from false to true.
    pub to_true: Option<TransitionId>,
}

/// The interface of a node's sub-net.
#[derive(Debug, Clone, Copy)]
struct Io {
    go: PlaceId,
    ok: PlaceId,
    ko: PlaceId,
}

struct Builder<'a> {
    tree: &'a Tree,
    params: &'a TreeParams,
    net: Net,
    /// Places each node owns (cleared when an ancestor or itself is halted).
    own: Vec<Vec<PlaceId>>,
    /// Halt machinery per node: (`halt`, `halted`).
    halts: BTreeMap<NodeId, (PlaceId, PlaceId)>,
    /// Persistent one-hot indices: (node, `active` place, index places).
    persistent: Vec<(NodeId, PlaceId, Vec<PlaceId>)>,
    /// Condition state by key.
    conditions: BTreeMap<String, ConditionNet>,
    triggers: BTreeMap<TransitionId, Trigger>,
    roles: BTreeMap<TransitionId, (NodeId, RateRole)>,
    /// Places from which a lingering child's report is taken (see `take`).
    taken: BTreeMap<(NodeId, PlaceId), PlaceId>,
    done: (PlaceId, PlaceId),
    counter: usize,
}

/// Translates `tree` with `params` into a GSPN.
///
/// Errors: parameters of the wrong kind for a leaf
/// ([`TreeParams::check_kinds`]), and what the translation refuses.
pub fn translate(tree: &Tree, params: &TreeParams) -> Result<Translation> {
    params.check_kinds(tree)?;
    let mut net = Net::new(format!("bt:{}", tree.main));
    net.doc = Some(format!(
        "behaviour tree `{}` translated by petrinav (crates/bt)",
        tree.main
    ));
    let done_ok = net.add_place("done_ok", 0u32);
    let done_ko = net.add_place("done_ko", 0u32);
    let mut b = Builder {
        tree,
        params,
        net,
        own: vec![Vec::new(); tree.len()],
        halts: BTreeMap::new(),
        persistent: Vec::new(),
        conditions: BTreeMap::new(),
        triggers: BTreeMap::new(),
        roles: BTreeMap::new(),
        taken: BTreeMap::new(),
        done: (done_ok, done_ko),
        counter: 0,
    };
    let root = Tree::ROOT;
    let io = b.io(root);
    b.net.places[io.go.index()].initial = 1u32.into();
    b.node(root, io)?;
    // The tree's end: a root that lingers (a periodic decorator) is halted first.
    let (ok, ko) = (b.finish(root, io.ok, "end_ok"), b.finish(root, io.ko, "end_ko"));
    b.arc_out(ok, done_ok);
    b.arc_out(ko, done_ko);
    b.finalize_halts();
    let activity = b.activity();
    let triggers = (0..b.net.transitions.len())
        .map(|t| {
            let tid = TransitionId(t as u32);
            if b.net.transitions[t].is_immediate() {
                None
            } else {
                Some(b.triggers.get(&tid).copied().unwrap_or(Trigger::Phase))
            }
        })
        .collect();
    b.net.validate()?;
    let roles = (0..b.net.transitions.len())
        .map(|t| b.roles.get(&TransitionId(t as u32)).copied())
        .collect();
    Ok(Translation {
        net: b.net,
        done_ok,
        done_ko,
        activity,
        roles,
        triggers,
        conditions: b.conditions,
    })
}

impl Builder<'_> {
    fn name(&mut self, n: NodeId, what: &str) -> String {
        self.counter += 1;
        format!("n{}_{}.{what}#{}", n.0, self.tree.node(n).id, self.counter)
    }

    /// A place owned by `n`.
    fn place(&mut self, n: NodeId, what: &str) -> PlaceId {
        let name = self.name(n, what);
        let p = self.net.add_place(name, 0u32);
        self.net.places[p.index()].doc = Some(self.tree.node(n).path.clone());
        self.own[n.index()].push(p);
        p
    }

    fn io(&mut self, n: NodeId) -> Io {
        Io {
            go: self.place(n, "go"),
            ok: self.place(n, "ok"),
            ko: self.place(n, "ko"),
        }
    }

    fn imm(&mut self, n: NodeId, what: &str, weight: f64, priority: u32) -> TransitionId {
        let name = self.name(n, what);
        self.net.add_immediate(name, weight, priority)
    }

    fn timed(&mut self, n: NodeId, what: &str, rate: f64, trigger: Trigger, role: RateRole) -> TransitionId {
        let name = self.name(n, what);
        let t = self.net.add_timed(name, rate);
        self.triggers.insert(t, trigger);
        self.roles.insert(t, (n, role));
        t
    }

    fn arc_in(&mut self, p: PlaceId, t: TransitionId) {
        self.net.input(p, t);
    }

    fn arc_out(&mut self, t: TransitionId, p: PlaceId) {
        self.net.output(t, p);
    }

    fn test(&mut self, p: PlaceId, t: TransitionId) {
        self.net.input(p, t);
        self.net.output(t, p);
    }

    fn inhibit(&mut self, p: PlaceId, t: TransitionId, k: u32) {
        self.net.add_arc(ArcKind::Inhibitor, p, t, k);
    }

    /// A flow transition `from → to` owned by `n`.
    fn flow(&mut self, n: NodeId, what: &str, from: &[PlaceId], to: &[PlaceId]) -> TransitionId {
        let t = self.imm(n, what, 1.0, PRI_FLOW);
        for &p in from {
            self.arc_in(p, t);
        }
        for &p in to {
            self.arc_out(t, p);
        }
        t
    }

    /// The halt places of `n` (created on first use).
    fn halt_of(&mut self, n: NodeId) -> (PlaceId, PlaceId) {
        if let Some(&h) = self.halts.get(&n) {
            return h;
        }
        let name_h = self.name(n, "halt");
        let name_d = self.name(n, "halted");
        let h = (self.net.add_place(name_h, 0u32), self.net.add_place(name_d, 0u32));
        self.halts.insert(n, h);
        h
    }

    /// Whether `n`'s subtree may keep running after it reported (a periodic
    /// decorator keeps its timer): parents that move on halt such a child.
    fn may_linger(&self, n: NodeId) -> bool {
        self.tree
            .preorder_from(n)
            .iter()
            .any(|&m| matches!(self.tree.node(m).kind, Kind::Periodic { .. }))
    }

    /// The place from which a parent takes child `c`'s report in `from`:
    /// `from` itself, or — when `c` may linger — a place marked once `c`
    /// has been halted after reporting.
    fn take(&mut self, c: NodeId, from: PlaceId) -> PlaceId {
        if !self.may_linger(c) {
            return from;
        }
        if let Some(&p) = self.taken.get(&(c, from)) {
            return p;
        }
        let (halt, halted) = self.halt_of(c);
        // The parent owns the places (the root's end owns them: outside any halt).
        let (wait, taken) = match self.tree.node(c).parent {
            Some(parent) => (self.place(parent, "wait_halt"), self.place(parent, "taken")),
            None => {
                let w = self
                    .net
                    .add_place(format!("end.wait_halt#{}", self.net.places.len()), 0u32);
                let t = self
                    .net
                    .add_place(format!("end.taken#{}", self.net.places.len()), 0u32);
                (w, t)
            }
        };
        self.flow(c, "halt_on_report", &[from], &[halt, wait]);
        self.flow(c, "report_taken", &[halted, wait], &[taken]);
        self.taken.insert((c, from), taken);
        taken
    }

    /// A transition taking child `c`'s report in `from` (see [`Self::take`]);
    /// callers add its other inputs and its outputs.
    fn finish(&mut self, c: NodeId, from: PlaceId, what: &str) -> TransitionId {
        let p = self.take(c, from);
        self.flow(c, what, &[p], &[])
    }

    /// Empties counter places `places` from `at` (a place), then marks the returned place.
    fn drain(&mut self, n: NodeId, at: PlaceId, places: &[PlaceId]) -> PlaceId {
        for &p in places {
            let t = self.imm(n, "drain", 1.0, PRI_FLOW + 2);
            self.arc_in(p, t);
            self.test(at, t);
        }
        let next = self.place(n, "drained");
        let t = self.flow(n, "drained", &[at], &[next]);
        for &p in places {
            self.inhibit(p, t, 1);
        }
        next
    }

    /// Transitions that halt `children` one after the other, from place
    /// `start`; returns the place marked when all are halted.
    fn halt_all(&mut self, n: NodeId, children: &[NodeId], start: PlaceId) -> PlaceId {
        let mut at = start;
        for &c in children {
            let (halt, halted) = self.halt_of(c);
            let wait = self.place(n, "halting");
            self.flow(n, "halt_child", &[at], &[halt, wait]);
            let next = self.place(n, "halted_child");
            self.flow(n, "child_halted", &[halted, wait], &[next]);
            // A child with nothing running is passed at once (fewer markings).
            let skip = self.imm(n, "child_idle", 1.0, PRI_FLOW + 3);
            self.arc_in(at, skip);
            self.arc_out(skip, next);
            for p in self.subtree_places(c) {
                self.inhibit(p, skip, 1);
            }
            at = next;
        }
        at
    }

    /// The `(true, false)` places of condition key `key` (created on first use).
    fn condition_state(&mut self, n: NodeId, key: &str) -> (PlaceId, PlaceId) {
        if let Some(c) = self.conditions.get(key) {
            return (c.holds, c.fails);
        }
        let cp = self.params.condition(self.tree, n);
        let safe: String = key
            .chars()
            .map(|c| if c.is_alphanumeric() { c } else { '_' })
            .collect();
        let k = self.conditions.len();
        let t = self.net.add_place(format!("c{k}_{safe}.true"), 0u32);
        let f = self.net.add_place(format!("c{k}_{safe}.false"), 0u32);
        let init = self.net.add_place(format!("c{k}_{safe}.init"), 1u32);
        for (target, w, what) in [(t, cp.p_true, "holds"), (f, 1.0 - cp.p_true, "fails")] {
            if w > 0.0 {
                let tr = self
                    .net
                    .add_immediate(format!("c{k}_{safe}.init_{what}"), w, PRI_INIT);
                self.arc_in(init, tr);
                self.arc_out(tr, target);
            }
        }
        let mut changes = [None, None];
        for (i, (from, to, rate, what)) in [
            (t, f, cp.change_rate * (1.0 - cp.p_true), "to_false"),
            (f, t, cp.change_rate * cp.p_true, "to_true"),
        ]
        .into_iter()
        .enumerate()
        {
            if rate > 0.0 {
                let tr = self.net.add_timed(format!("c{k}_{safe}.{what}"), rate);
                self.triggers.insert(tr, Trigger::Change { node: n });
                self.roles.insert(tr, (n, RateRole::Change));
                self.arc_in(from, tr);
                self.arc_out(tr, to);
                let (dok, dko) = self.done;
                self.inhibit(dok, tr, 1);
                self.inhibit(dko, tr, 1);
                changes[i] = Some(tr);
            }
        }
        let c = ConditionNet {
            holds: t,
            fails: f,
            to_false: changes[0],
            to_true: changes[1],
        };
        self.conditions.insert(key.to_string(), c);
        (t, f)
    }

    /// An Erlang chain of `phases` stages with total mean `mean_s` from
    /// `from` to `to`; the last stage is labelled `last`.
    fn delay(&mut self, n: NodeId, from: PlaceId, to: PlaceId, mean_s: f64, phases: u32, last: Trigger) {
        self.erlang(n, from, &[(to, 1.0, last, "")], mean_s, phases);
    }

    /// An Erlang chain of `phases` stages with total mean `mean_s` from
    /// `from`, whose last stage is one timed transition per end `(to,
    /// share of the rate, label, name suffix)`: with shares summing to 1 the
    /// time is Erlang whatever the end, and end `i` is taken with
    /// probability `share_i`.
    fn erlang(
        &mut self,
        n: NodeId,
        from: PlaceId,
        ends: &[(PlaceId, f64, Trigger, &str)],
        mean_s: f64,
        phases: u32,
    ) {
        let rate = f64::from(phases) / mean_s;
        let role = if matches!(ends[0].2, Trigger::Timer { .. }) {
            RateRole::Timer
        } else {
            RateRole::Duration
        };
        let mut at = from;
        for k in 1..phases {
            let next = self.place(n, "phase");
            let t = self.timed(n, &format!("stage{k}"), rate, Trigger::Phase, role);
            self.arc_in(at, t);
            self.arc_out(t, next);
            at = next;
        }
        for &(to, share, last, suffix) in ends {
            let t = self.timed(n, &format!("stage{phases}{suffix}"), share * rate, last, role);
            self.arc_in(at, t);
            self.arc_out(t, to);
        }
    }

    fn node(&mut self, n: NodeId, io: Io) -> Result<()> {
        let node = self.tree.node(n);
        match node.kind.clone() {
            Kind::Action | Kind::Sleep { .. } => self.action(n, io),
            Kind::Condition if self.params.condition(self.tree, n).change_rate == 0.0 => {
                // Drawn afresh at each evaluation: no state of the world.
                let p = self.params.condition(self.tree, n).p_true;
                for (w, out, what) in [(p, io.ok, "holds"), (1.0 - p, io.ko, "fails")] {
                    if w > 0.0 {
                        let t = self.imm(n, what, w, PRI_FLOW);
                        self.arc_in(io.go, t);
                        self.arc_out(t, out);
                    }
                }
            }
            Kind::Condition => {
                let key = self.params.condition_key(self.tree, n);
                let (t, f) = self.condition_state(n, &key);
                let yes = self.flow(n, "holds", &[io.go], &[io.ok]);
                self.test(t, yes);
                let no = self.flow(n, "fails", &[io.go], &[io.ko]);
                self.test(f, no);
            }
            Kind::Constant { success } => {
                self.flow(n, "const", &[io.go], &[if success { io.ok } else { io.ko }]);
            }
            Kind::Sequence | Kind::Fallback => {
                self.sequence(n, io, matches!(node.kind, Kind::Sequence), false)?
            }
            Kind::ReactiveSequence | Kind::ReactiveFallback => {
                self.sequence(n, io, matches!(node.kind, Kind::ReactiveSequence), true)?
            }
            Kind::SequenceWithMemory => self.sequence_with_memory(n, io)?,
            Kind::PipelineSequence => self.pipeline(n, io)?,
            Kind::Parallel { success, failure } => self.parallel(n, io, success, failure)?,
            Kind::ParallelAll { max_failures } => self.parallel_all(n, io, max_failures)?,
            Kind::IfThenElse | Kind::WhileDoElse => {
                self.if_then_else(n, io, matches!(node.kind, Kind::WhileDoElse))?
            }
            Kind::Switch { .. } => self.switch(n, io)?,
            Kind::Recovery { retries } => self.recovery(n, io, retries)?,
            Kind::RoundRobin => self.round_robin(n, io)?,
            Kind::Inverter | Kind::ForceSuccess | Kind::ForceFailure | Kind::PassThrough => {
                self.decorator(n, io, &node.kind)?
            }
            Kind::Repeat { cycles } => self.repeat(n, io, cycles, true)?,
            Kind::Retry { attempts } => self.repeat(n, io, attempts, false)?,
            Kind::KeepRunningUntilFailure => self.repeat(n, io, -1, true)?,
            Kind::Timeout { mean_s } => self.timeout(n, io, mean_s)?,
            Kind::Delay { mean_s } => {
                let c = self.child(n, 0)?;
                self.delay_or_flow(n, io.go, c.go, mean_s);
                self.flow(n, "ok", &[c.ok], &[io.ok]);
                self.flow(n, "ko", &[c.ko], &[io.ko]);
            }
            Kind::Periodic { mean_interval_s } => self.periodic(n, io, mean_interval_s)?,
            Kind::Gate => {
                let c = self.child(n, 0)?;
                let key = self.params.condition_key(self.tree, n);
                let (t, f) = self.condition_state(n, &key);
                let run = self.flow(n, "gate_open", &[io.go], &[c.go]);
                self.test(t, run);
                let skip = self.flow(n, "gate_closed", &[io.go], &[io.ok]);
                self.test(f, skip);
                self.flow(n, "ok", &[c.ok], &[io.ok]);
                self.flow(n, "ko", &[c.ko], &[io.ko]);
            }
        }
        Ok(())
    }

    fn delay_or_flow(&mut self, n: NodeId, from: PlaceId, to: PlaceId, mean_s: f64) {
        if mean_s > 0.0 {
            let phases = self.params.defaults.action.phases;
            self.delay(n, from, to, mean_s, phases, Trigger::Timer { node: n });
        } else {
            self.flow(n, "no_delay", &[from], &[to]);
        }
    }

    /// Builds child `i` of `n` and returns its interface.
    fn child(&mut self, n: NodeId, i: usize) -> Result<Io> {
        let c = self.tree.node(n).children[i];
        let io = self.io(c);
        self.node(c, io)?;
        Ok(io)
    }

    fn children(&mut self, n: NodeId) -> Result<Vec<Io>> {
        (0..self.tree.node(n).children.len())
            .map(|i| self.child(n, i))
            .collect()
    }

    fn action(&mut self, n: NodeId, io: Io) {
        let a = self.params.action(self.tree, n);
        let p = a.p_success;
        let mean = a.mean_time_success;
        if p > 0.0 && p < 1.0 && mean > 0.0 && a.mean_time_failure == mean {
            // One duration whatever the outcome: the outcome is drawn by
            // the last stage (two timed transitions, rates in the ratio
            // p : 1 − p), not at the start — the same law of outcome and
            // time, without a choice marking or a running state per outcome.
            let run = self.place(n, "run");
            self.flow(n, "start", &[io.go], &[run]);
            let ends = [
                (io.ok, p, Trigger::Success { node: n }, "_ok"),
                (io.ko, 1.0 - p, Trigger::Failure { node: n }, "_ko"),
            ];
            self.erlang(n, run, &ends, mean, a.phases);
            return;
        }
        for (success, w, mean) in [
            (true, a.p_success, a.mean_time_success),
            (false, 1.0 - a.p_success, a.mean_time_failure),
        ] {
            if w <= 0.0 {
                continue;
            }
            let out = if success { io.ok } else { io.ko };
            let t = self.imm(n, if success { "draw_ok" } else { "draw_ko" }, w, PRI_FLOW);
            self.arc_in(io.go, t);
            if mean > 0.0 {
                let run = self.place(n, if success { "run_ok" } else { "run_ko" });
                self.arc_out(t, run);
                let trig = if success {
                    Trigger::Success { node: n }
                } else {
                    Trigger::Failure { node: n }
                };
                self.delay(n, run, out, mean, a.phases, trig);
            } else {
                self.arc_out(t, out);
            }
        }
    }

    /// Monitors of a reactive parent while child `j` runs (`running` marked):
    /// when the earlier children's formula takes the value `preempt_when`,
    /// the transition consumes `running` and marks the returned place.
    fn monitors(&mut self, n: NodeId, j: usize, running: PlaceId, conjunction: bool) -> Option<PlaceId> {
        let kids = self.tree.node(n).children.clone();
        let parts: Vec<Formula> = kids[..j]
            .iter()
            .filter_map(|&c| Formula::of(self.tree, self.params, c))
            .collect();
        let f = if conjunction {
            Formula::And(parts)
        } else {
            Formula::Or(parts)
        };
        if f.vars().is_empty() {
            return None;
        }
        let assignments = f.assignments(!conjunction)?;
        let fired = self.place(n, "preempted");
        for a in assignments {
            let t = self.imm(n, "preempt", 1.0, PRI_PREEMPT);
            self.arc_in(running, t);
            self.arc_out(t, fired);
            for (key, value) in a {
                // Created with the earlier child that reads it.
                let c = self.conditions[&key];
                self.test(if value { c.holds } else { c.fails }, t);
            }
        }
        Some(fired)
    }

    /// Sequence and Fallback without lingering children: each child's
    /// result place is the next child's `go` (no transition of their own).
    fn wired_sequence(&mut self, n: NodeId, io: Io, is_sequence: bool) -> Result<()> {
        let kids = self.tree.node(n).children.clone();
        let gos: Vec<PlaceId> = std::iter::once(io.go)
            .chain(kids[1..].iter().map(|&c| self.place(c, "go")))
            .collect();
        for (i, &c) in kids.iter().enumerate() {
            let next = gos.get(i + 1).copied();
            let child = if is_sequence {
                Io {
                    go: gos[i],
                    ok: next.unwrap_or(io.ok),
                    ko: io.ko,
                }
            } else {
                Io {
                    go: gos[i],
                    ok: io.ok,
                    ko: next.unwrap_or(io.ko),
                }
            };
            self.node(c, child)?;
        }
        Ok(())
    }

    /// Sequence, Fallback and their reactive forms.
    fn sequence(&mut self, n: NodeId, io: Io, is_sequence: bool, reactive: bool) -> Result<()> {
        let kids = self.tree.node(n).children.clone();
        if !reactive && !kids.iter().any(|&c| self.may_linger(c)) {
            return self.wired_sequence(n, io, is_sequence);
        }
        let cs = self.children(n)?;
        let k = cs.len();
        let running: Vec<PlaceId> = (0..k).map(|_| self.place(n, "at")).collect();
        self.flow(n, "start", &[io.go], &[cs[0].go, running[0]]);
        for i in 0..k {
            let (pass, stop) = if is_sequence {
                (cs[i].ok, cs[i].ko)
            } else {
                (cs[i].ko, cs[i].ok)
            };
            let t_pass = self.finish(kids[i], pass, "next");
            self.arc_in(running[i], t_pass);
            if i + 1 < k {
                self.arc_out(t_pass, cs[i + 1].go);
                self.arc_out(t_pass, running[i + 1]);
            } else {
                self.arc_out(t_pass, if is_sequence { io.ok } else { io.ko });
            }
            let t_stop = self.finish(kids[i], stop, "stop");
            self.arc_in(running[i], t_stop);
            self.arc_out(t_stop, if is_sequence { io.ko } else { io.ok });
            if reactive && i > 0 {
                if let Some(fired) = self.monitors(n, i, running[i], is_sequence) {
                    let (halt, halted) = self.halt_of(kids[i]);
                    let wait = self.place(n, "preempting");
                    self.flow(n, "halt_running", &[fired], &[halt, wait]);
                    self.flow(
                        n,
                        "preempted",
                        &[halted, wait],
                        &[if is_sequence { io.ko } else { io.ok }],
                    );
                }
            }
        }
        Ok(())
    }

    /// A persistent one-hot index of `k` places (index 0 marked at the
    /// start), reset to 0 when `n` is halted while `active` is marked.
    fn persistent_index(&mut self, n: NodeId, k: usize) -> (PlaceId, Vec<PlaceId>) {
        let active = self.place(n, "active");
        let idx: Vec<PlaceId> = (0..k)
            .map(|i| {
                let name = self.name(n, &format!("index{i}"));
                self.net.add_place(name, u32::from(i == 0))
            })
            .collect();
        self.persistent.push((n, active, idx.clone()));
        (active, idx)
    }

    fn sequence_with_memory(&mut self, n: NodeId, io: Io) -> Result<()> {
        let kids = self.tree.node(n).children.clone();
        let cs = self.children(n)?;
        let k = cs.len();
        let (active, idx) = self.persistent_index(n, k);
        for i in 0..k {
            let t = self.flow(n, "resume", &[io.go], &[cs[i].go, active]);
            self.test(idx[i], t);
            let next = self.finish(kids[i], cs[i].ok, "next");
            self.arc_in(idx[i], next);
            if i + 1 < k {
                self.arc_out(next, idx[i + 1]);
                self.arc_out(next, cs[i + 1].go);
            } else {
                self.arc_out(next, idx[0]);
                self.arc_in(active, next);
                self.arc_out(next, io.ok);
            }
            let stop = self.finish(kids[i], cs[i].ko, "stop");
            self.arc_in(active, stop);
            self.arc_out(stop, io.ko);
        }
        Ok(())
    }

    fn pipeline(&mut self, n: NodeId, io: Io) -> Result<()> {
        let kids = self.tree.node(n).children.clone();
        let cs = self.children(n)?;
        let k = cs.len();
        let reach: Vec<PlaceId> = (0..k).map(|_| self.place(n, "reach")).collect();
        self.flow(n, "start", &[io.go], &[cs[0].go, reach[0]]);
        let win = self.place(n, "all_done");
        let lose = self.place(n, "failed");
        for i in 0..k {
            let adv = self.flow(n, "advance", &[cs[i].ok, reach[i]], &[]);
            if i + 1 < k {
                self.arc_out(adv, cs[i + 1].go);
                self.arc_out(adv, reach[i + 1]);
            } else {
                self.arc_out(adv, win);
            }
            let ignore = self.flow(n, "again_ok", &[cs[i].ok], &[]);
            self.inhibit(reach[i], ignore, 1);
            for r in &reach {
                // The pipeline's position is consumed when it fails.
                let t = self.flow(n, "child_failed", &[cs[i].ko, *r], &[lose]);
                let _ = t;
            }
            if i > 0 {
                if let Some(fired) = self.monitors(n, i, reach[i], true) {
                    self.flow(n, "condition_failed", &[fired], &[lose]);
                }
            }
        }
        let w = self.halt_all(n, &kids, win);
        self.flow(n, "succeeded", &[w], &[io.ok]);
        let l = self.halt_all(n, &kids, lose);
        self.flow(n, "failed", &[l], &[io.ko]);
        Ok(())
    }

    fn parallel(&mut self, n: NodeId, io: Io, success: i64, failure: i64) -> Result<()> {
        let kids = self.tree.node(n).children.clone();
        let count = kids.len() as i64;
        let need_s = if success < 0 { count + success + 1 } else { success };
        let need_f = if failure < 0 { count + failure + 1 } else { failure };
        if need_s > count || need_f > count || need_s < 0 || need_f < 0 {
            return Err(self.unsupported(
                n,
                format!(
                    "thresholds success {need_s}, failure {need_f} with {count} children: BehaviorTree.CPP stops with an error at run time (bt check: dead parallel threshold)"
                ),
            ));
        }
        let cs = self.children(n)?;
        let go: Vec<PlaceId> = cs.iter().map(|c| c.go).collect();
        self.flow(n, "start", &[io.go], &go);
        let s = self.place(n, "successes");
        let f = self.place(n, "failures");
        let decided_ok = self.place(n, "decided_ok");
        let decided_ko = self.place(n, "decided_ko");
        for (c, &kid) in cs.iter().zip(&kids) {
            let t = self.finish(kid, c.ok, "child_ok");
            self.arc_out(t, s);
            let t = self.finish(kid, c.ko, "child_ko");
            self.arc_out(t, f);
        }
        if need_s == 0 {
            return Err(self.unsupported(
                n,
                "a success count of 0 (it succeeds before any child runs)".into(),
            ));
        }
        let need_s = need_s as u32;
        let t = self.imm(n, "win", 1.0, PRI_FLOW + 1);
        self.net.add_arc(ArcKind::Input, s, t, need_s);
        self.arc_out(t, decided_ok);
        let lose_at = need_f.min(count - i64::from(need_s) + 1).max(1) as u32;
        let t = self.imm(n, "lose", 1.0, PRI_FLOW + 1);
        self.net.add_arc(ArcKind::Input, f, t, lose_at);
        self.arc_out(t, decided_ko);
        let w = self.halt_all(n, &kids, decided_ok);
        let w = self.drain(n, w, &[s, f]);
        self.flow(n, "succeeded", &[w], &[io.ok]);
        let l = self.halt_all(n, &kids, decided_ko);
        let l = self.drain(n, l, &[s, f]);
        self.flow(n, "failed", &[l], &[io.ko]);
        Ok(())
    }

    fn parallel_all(&mut self, n: NodeId, io: Io, max_failures: i64) -> Result<()> {
        let kids = self.tree.node(n).children.clone();
        let cs = self.children(n)?;
        let count = cs.len() as u32;
        let go: Vec<PlaceId> = cs.iter().map(|c| c.go).collect();
        self.flow(n, "start", &[io.go], &go);
        let s = self.place(n, "successes");
        let f = self.place(n, "failures");
        for (c, &kid) in cs.iter().zip(&kids) {
            let t = self.finish(kid, c.ok, "child_ok");
            self.arc_out(t, s);
            let t = self.finish(kid, c.ko, "child_ko");
            self.arc_out(t, f);
        }
        for fails in 0..=count {
            let t = self.imm(n, "all_done", 1.0, PRI_FLOW);
            if count - fails > 0 {
                self.net.add_arc(ArcKind::Input, s, t, count - fails);
            }
            if fails > 0 {
                self.net.add_arc(ArcKind::Input, f, t, fails);
            }
            let failed = max_failures >= 0 && i64::from(fails) > max_failures;
            self.arc_out(t, if failed { io.ko } else { io.ok });
        }
        Ok(())
    }

    fn if_then_else(&mut self, n: NodeId, io: Io, reactive: bool) -> Result<()> {
        let kids = self.tree.node(n).children.clone();
        let cs = self.children(n)?;
        let at: Vec<PlaceId> = (0..cs.len()).map(|_| self.place(n, "at")).collect();
        self.flow(n, "start", &[io.go], &[cs[0].go]);
        let then = self.finish(kids[0], cs[0].ok, "then");
        self.arc_out(then, cs[1].go);
        self.arc_out(then, at[1]);
        let other = self.finish(kids[0], cs[0].ko, "else");
        match cs.get(2) {
            Some(e) => {
                self.arc_out(other, e.go);
                self.arc_out(other, at[2]);
            }
            None => self.arc_out(other, io.ko),
        }
        for i in 1..cs.len() {
            let t = self.finish(kids[i], cs[i].ok, "ok");
            self.arc_in(at[i], t);
            self.arc_out(t, io.ok);
            let t = self.finish(kids[i], cs[i].ko, "ko");
            self.arc_in(at[i], t);
            self.arc_out(t, io.ko);
        }
        if !reactive {
            return Ok(());
        }
        let Some(f) = Formula::of(self.tree, self.params, kids[0]) else {
            return Ok(());
        };
        for (i, value) in [(1usize, false), (2usize, true)] {
            if i >= cs.len() {
                continue;
            }
            let Some(assignments) = f.assignments(value) else {
                continue;
            };
            let (halt, halted) = self.halt_of(kids[i]);
            let wait = self.place(n, "switching");
            for a in assignments {
                let t = self.imm(n, "switch_branch", 1.0, PRI_PREEMPT);
                self.arc_in(at[i], t);
                self.arc_out(t, halt);
                self.arc_out(t, wait);
                for (key, v) in a {
                    let c = self.conditions[&key];
                    self.test(if v { c.holds } else { c.fails }, t);
                }
            }
            let t = self.flow(n, "switched", &[halted, wait], &[]);
            if i == 1 {
                match cs.get(2) {
                    Some(e) => {
                        self.arc_out(t, e.go);
                        self.arc_out(t, at[2]);
                    }
                    None => self.arc_out(t, io.ko),
                }
            } else {
                self.arc_out(t, cs[1].go);
                self.arc_out(t, at[1]);
            }
        }
        Ok(())
    }

    fn switch(&mut self, n: NodeId, io: Io) -> Result<()> {
        let cs = self.children(n)?;
        let weights = self
            .params
            .node(self.tree, n)
            .weights
            .unwrap_or_else(|| vec![1.0; cs.len()]);
        if weights.len() != cs.len() {
            return Err(self.unsupported(
                n,
                format!(
                    "the sidecar gives {} weights for {} children",
                    weights.len(),
                    cs.len()
                ),
            ));
        }
        // The decision the tree leaves open: drawn here with the sidecar's weights.
        for (c, w) in cs.iter().zip(weights) {
            if w > 0.0 {
                let t = self.imm(n, "case", w, PRI_FLOW);
                self.arc_in(io.go, t);
                self.arc_out(t, c.go);
            }
            self.flow(n, "ok", &[c.ok], &[io.ok]);
            self.flow(n, "ko", &[c.ko], &[io.ko]);
        }
        Ok(())
    }

    fn recovery(&mut self, n: NodeId, io: Io, retries: u32) -> Result<()> {
        let kids = self.tree.node(n).children.clone();
        let cs = self.children(n)?;
        let (main, rec) = (cs[0], cs[1]);
        let tries: Vec<PlaceId> = (0..=retries).map(|_| self.place(n, "tries")).collect();
        self.flow(n, "start", &[io.go], &[main.go, tries[0]]);
        for (k, &tk) in tries.iter().enumerate() {
            let t = self.finish(kids[0], main.ok, "done");
            self.arc_in(tk, t);
            self.arc_out(t, io.ok);
            let t = self.finish(kids[0], main.ko, "recover");
            self.arc_in(tk, t);
            if k < retries as usize {
                self.arc_out(t, tk);
                self.arc_out(t, rec.go);
            } else {
                self.arc_out(t, io.ko);
            }
            if k < retries as usize {
                let t = self.finish(kids[1], rec.ok, "retry");
                self.arc_in(tk, t);
                self.arc_out(t, tries[k + 1]);
                self.arc_out(t, main.go);
                let t = self.finish(kids[1], rec.ko, "recovery_failed");
                self.arc_in(tk, t);
                self.arc_out(t, io.ko);
            }
        }
        Ok(())
    }

    fn round_robin(&mut self, n: NodeId, io: Io) -> Result<()> {
        let kids = self.tree.node(n).children.clone();
        let cs = self.children(n)?;
        let k = cs.len();
        let (active, idx) = self.persistent_index(n, k);
        let failed = self.place(n, "failed");
        let check = self.place(n, "check");
        let clear = self.place(n, "clear");
        for i in 0..k {
            let t = self.flow(n, "start", &[io.go], &[cs[i].go, active]);
            self.test(idx[i], t);
            let next = (i + 1) % k;
            let t = self.finish(kids[i], cs[i].ok, "child_ok");
            self.arc_in(idx[i], t);
            self.arc_out(t, idx[next]);
            self.arc_out(t, clear);
            let t = self.finish(kids[i], cs[i].ko, "child_ko");
            self.arc_in(idx[i], t);
            self.arc_out(t, idx[next]);
            self.arc_out(t, failed);
            self.arc_out(t, check);
            let t = self.flow(n, "try_next", &[check], &[cs[i].go]);
            self.test(idx[i], t);
            self.inhibit(failed, t, k as u32);
            let t = self.flow(n, "all_failed", &[check, idx[i], active], &[idx[0]]);
            self.net.add_arc(ArcKind::Input, failed, t, k as u32);
            self.arc_out(t, io.ko);
        }
        self.flow(n, "forget_failure", &[clear, failed], &[clear]);
        let t = self.flow(n, "succeeded", &[clear, active], &[io.ok]);
        self.inhibit(failed, t, 1);
        Ok(())
    }

    /// Inverter, ForceSuccess, ForceFailure and pass-through decorators:
    /// the child is wired straight to the decorator's places (no transition
    /// of their own), its results swapped or merged.
    fn decorator(&mut self, n: NodeId, io: Io, kind: &Kind) -> Result<()> {
        let c = self.tree.node(n).children[0];
        let wired = match kind {
            Kind::Inverter => Io {
                go: io.go,
                ok: io.ko,
                ko: io.ok,
            },
            Kind::ForceSuccess => Io {
                go: io.go,
                ok: io.ok,
                ko: io.ok,
            },
            Kind::ForceFailure => Io {
                go: io.go,
                ok: io.ko,
                ko: io.ko,
            },
            _ => io,
        };
        self.node(c, wired)
    }

    /// `Repeat` (`on_success`), `RetryUntilSuccessful` (not), and
    /// `KeepRunningUntilFailure` (`times` = -1, on success).
    fn repeat(&mut self, n: NodeId, io: Io, times: i64, on_success: bool) -> Result<()> {
        let kid = self.tree.node(n).children[0];
        let c = self.child(n, 0)?;
        if times == 0 {
            // BehaviorTree.CPP returns success without ticking the child.
            self.flow(n, "zero_times", &[io.go], &[io.ok]);
            return Ok(());
        }
        let (again, stop, out_again, out_stop) = if on_success {
            (c.ok, c.ko, io.ok, io.ko)
        } else {
            (c.ko, c.ok, io.ko, io.ok)
        };
        if times < 0 {
            self.flow(n, "start", &[io.go], &[c.go]);
            let t = self.finish(kid, stop, "stop");
            self.arc_out(t, out_stop);
            let t = self.finish(kid, again, "again");
            self.arc_out(t, c.go);
            return Ok(());
        }
        let count: Vec<PlaceId> = (0..times).map(|_| self.place(n, "count")).collect();
        self.flow(n, "start", &[io.go], &[c.go, count[0]]);
        for (k, &ck) in count.iter().enumerate() {
            let t = self.finish(kid, stop, "stop");
            self.arc_in(ck, t);
            self.arc_out(t, out_stop);
            let t = self.finish(kid, again, "again");
            self.arc_in(ck, t);
            if k + 1 < count.len() {
                self.arc_out(t, count[k + 1]);
                self.arc_out(t, c.go);
            } else {
                self.arc_out(t, out_again);
            }
        }
        Ok(())
    }

    fn timeout(&mut self, n: NodeId, io: Io, mean_s: f64) -> Result<()> {
        let kid = self.tree.node(n).children[0];
        let c = self.child(n, 0)?;
        if mean_s <= 0.0 {
            self.flow(n, "expired_at_once", &[io.go], &[io.ko]);
            return Ok(());
        }
        let timer = self.place(n, "timer");
        let expired = self.place(n, "expired");
        self.flow(n, "start", &[io.go], &[c.go, timer]);
        let phases = self.params.defaults.action.phases;
        // The timer's stages: each stage place is consumed by the child's report.
        let rate = f64::from(phases) / mean_s;
        let mut stages = vec![timer];
        for k in 1..=phases {
            let next = if k == phases {
                expired
            } else {
                self.place(n, "timer")
            };
            let trig = if k == phases {
                Trigger::Timer { node: n }
            } else {
                Trigger::Phase
            };
            let t = self.timed(n, &format!("timer{k}"), rate, trig, RateRole::Timer);
            self.arc_in(*stages.last().unwrap_or(&timer), t);
            self.arc_out(t, next);
            if k < phases {
                stages.push(next);
            }
        }
        for &s in &stages {
            let t = self.finish(kid, c.ok, "ok");
            self.arc_in(s, t);
            self.arc_out(t, io.ok);
            let t = self.finish(kid, c.ko, "ko");
            self.arc_in(s, t);
            self.arc_out(t, io.ko);
        }
        let (halt, halted) = self.halt_of(kid);
        let wait = self.place(n, "timing_out");
        self.flow(n, "timeout", &[expired], &[halt, wait]);
        self.flow(n, "timed_out", &[halted, wait], &[io.ko]);
        Ok(())
    }

    fn periodic(&mut self, n: NodeId, io: Io, interval: Option<f64>) -> Result<()> {
        let c = self.child(n, 0)?;
        let interval = self
            .params
            .node(self.tree, n)
            .mean_interval
            .or(interval)
            .unwrap_or(0.0);
        self.flow(n, "start", &[io.go], &[c.go]);
        if interval > 0.0 {
            let wait = self.place(n, "waiting");
            self.flow(n, "child_ok", &[c.ok], &[io.ok, wait]);
            let phases = self.params.defaults.action.phases;
            self.delay(n, wait, c.go, interval, phases, Trigger::Timer { node: n });
        } else {
            let idle = self.place(n, "idle");
            self.flow(n, "child_ok", &[c.ok], &[io.ok, idle]);
        }
        self.flow(n, "child_ko", &[c.ko], &[io.ko]);
        Ok(())
    }

    fn unsupported(&self, n: NodeId, reason: String) -> Error {
        let node = self.tree.node(n);
        Error::Unsupported {
            file: self.tree.files[node.file].clone(),
            line: node.line,
            path: node.path.clone(),
            id: node.id.clone(),
            reason,
        }
    }

    /// Places of `n`'s subtree that a halt clears (persistent indices
    /// excluded; the halt places of strict descendants included).
    fn subtree_places(&self, n: NodeId) -> Vec<PlaceId> {
        let mut out = Vec::new();
        for m in self.tree.preorder_from(n) {
            out.extend(self.own[m.index()].iter().copied());
            if m != n {
                if let Some(&(h, d)) = self.halts.get(&m) {
                    out.push(h);
                    out.push(d);
                }
            }
        }
        out
    }

    fn finalize_halts(&mut self) {
        let halts: Vec<(NodeId, (PlaceId, PlaceId))> = self.halts.iter().map(|(k, v)| (*k, *v)).collect();
        for (n, (halt, halted)) in halts {
            let places = self.subtree_places(n);
            for (k, &p) in places.iter().enumerate() {
                let t = self.imm(n, "clear", 1.0, PRI_CLEAN + k as u32);
                self.arc_in(p, t);
                self.test(halt, t);
            }
            let done = self.imm(n, "cleared", 1.0, PRI_HALTED);
            self.arc_in(halt, done);
            self.arc_out(done, halted);
            for &p in &places {
                self.inhibit(p, done, 1);
            }
            let inside = self.tree.preorder_from(n);
            let resets: Vec<(NodeId, PlaceId, Vec<PlaceId>)> = self
                .persistent
                .iter()
                .filter(|(m, _, _)| inside.contains(m))
                .cloned()
                .collect();
            for (m, active, idx) in resets {
                for &p in &idx[1..] {
                    let t = self.imm(m, "reset_index", 1.0, PRI_RESET);
                    self.arc_in(p, t);
                    self.arc_out(t, idx[0]);
                    self.test(active, t);
                    self.test(halt, t);
                }
            }
        }
    }

    fn activity(&self) -> Vec<Vec<PlaceId>> {
        (0..self.tree.len())
            .map(|i| {
                let n = NodeId(i as u32);
                let mut v: Vec<PlaceId> = self
                    .tree
                    .preorder_from(n)
                    .iter()
                    .flat_map(|m| self.own[m.index()].iter().copied())
                    .collect();
                v.sort();
                v
            })
            .collect()
    }
}
