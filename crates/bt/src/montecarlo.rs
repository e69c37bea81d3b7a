//! A direct Monte Carlo interpreter of a tree, independent of the
//! translation: it ticks the tree the way BehaviorTree.CPP does (status per
//! node, halts, per-node memory), under the same stochastic rules as the
//! net (docs/behaviour-trees.md, *Semantics*), and advances a clock from event to
//! event: an action's end, a condition's change, a timer. After every event
//! the root is ticked once, as if the tree were ticked infinitely fast.
//!
//! It shares the tree, the parameters and the [`Formula`] test of *pure*
//! subtrees with the translation — not the net, nor any of its patterns.
//! Estimates come with Student/normal 99 % intervals; runs are seeded per
//! run index, so results do not depend on the thread count.

use std::collections::BTreeMap;

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;

use crate::error::{Error, Result};
use crate::formula::Formula;
use crate::params::TreeParams;
use crate::tree::{Kind, NodeId, Tree};

/// A node's status, as BehaviorTree.CPP has it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Status {
    Idle,
    Running,
    Success,
    Failure,
}

/// Per-node memory.
#[derive(Debug, Clone, Default)]
struct Mem {
    /// Child index (Sequence, Fallback, Recovery, reactive running child, pipeline's furthest, …).
    idx: usize,
    /// Persistent index (RoundRobin, SequenceWithMemory): survives completion.
    persistent: usize,
    /// A count (retries, repeats, failures of a RoundRobin, successes of a parallel).
    count: i64,
    /// Another count (failures of a parallel).
    count2: i64,
    /// An action's outcome, a gate's state, a periodic's "waiting".
    flag: bool,
    /// An action's end, a timer's deadline.
    time: f64,
    /// Children that completed (Parallel).
    done: Vec<bool>,
}

/// The outcome of one simulated execution.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Run {
    /// `Some(true)` success, `Some(false)` failure, `None` cut (never ended within the limits).
    pub success: Option<bool>,
    /// Its duration, seconds.
    pub time: f64,
}

/// Limits of one simulated execution.
#[derive(Debug, Clone, Copy)]
pub struct Limits {
    /// Events (ticks) before a run is cut as never ending.
    pub max_events: u64,
    /// Simulated seconds before a run is cut.
    pub max_time: f64,
}

impl Default for Limits {
    fn default() -> Self {
        Limits {
            max_events: 1_000_000,
            max_time: 1e9,
        }
    }
}

struct World {
    /// Condition key → (holds, next change time).
    conditions: BTreeMap<String, (bool, f64)>,
}

/// The interpreter of one tree.
pub struct Interpreter<'a> {
    tree: &'a Tree,
    params: &'a TreeParams,
    pure: Vec<bool>,
    linger: Vec<bool>,
    status: Vec<Status>,
    mem: Vec<Mem>,
    world: World,
    now: f64,
    rng: ChaCha8Rng,
}

fn erlang(rng: &mut ChaCha8Rng, mean: f64, phases: u32) -> f64 {
    if mean <= 0.0 {
        return 0.0;
    }
    let rate = f64::from(phases) / mean;
    (0..phases)
        .map(|_| -(1.0 - rng.random::<f64>()).ln() / rate)
        .sum()
}

impl<'a> Interpreter<'a> {
    /// An interpreter of `tree` with `params`.
    pub fn new(tree: &'a Tree, params: &'a TreeParams) -> Interpreter<'a> {
        let pure = (0..tree.len())
            .map(|i| Formula::of(tree, params, NodeId(i as u32)).is_some())
            .collect();
        let linger = (0..tree.len())
            .map(|i| {
                tree.preorder_from(NodeId(i as u32))
                    .iter()
                    .any(|&m| matches!(tree.node(m).kind, Kind::Periodic { .. }))
            })
            .collect();
        Interpreter {
            tree,
            params,
            pure,
            linger,
            status: vec![Status::Idle; tree.len()],
            mem: vec![Mem::default(); tree.len()],
            world: World {
                conditions: BTreeMap::new(),
            },
            now: 0.0,
            rng: ChaCha8Rng::seed_from_u64(0),
        }
    }

    /// One execution from a fresh tree, seeded by `seed`.
    pub fn run(&mut self, seed: u64, limits: Limits) -> Result<Run> {
        self.rng = ChaCha8Rng::seed_from_u64(seed);
        self.now = 0.0;
        self.status.iter_mut().for_each(|s| *s = Status::Idle);
        self.mem.iter_mut().for_each(|m| *m = Mem::default());
        self.world.conditions.clear();
        for n in self.tree.preorder() {
            let changing = self.params.condition(self.tree, n).change_rate > 0.0;
            if matches!(self.tree.node(n).kind, Kind::Gate)
                || (matches!(self.tree.node(n).kind, Kind::Condition) && changing)
            {
                let key = self.params.condition_key(self.tree, n);
                if !self.world.conditions.contains_key(&key) {
                    let c = self.params.condition(self.tree, n);
                    let holds = self.rng.random::<f64>() < c.p_true;
                    let next = self.next_change(holds, c.p_true, c.change_rate);
                    self.world.conditions.insert(key, (holds, next));
                }
            }
        }
        for _ in 0..limits.max_events {
            match self.tick(Tree::ROOT)? {
                Status::Success => {
                    return Ok(Run {
                        success: Some(true),
                        time: self.now,
                    });
                }
                Status::Failure => {
                    return Ok(Run {
                        success: Some(false),
                        time: self.now,
                    });
                }
                _ => {}
            }
            let next = self.next_event();
            if !next.is_finite() || next > limits.max_time {
                return Ok(Run {
                    success: None,
                    time: self.now,
                });
            }
            self.now = next;
            self.apply_changes();
        }
        Ok(Run {
            success: None,
            time: self.now,
        })
    }

    fn next_change(&mut self, holds: bool, p: f64, rate: f64) -> f64 {
        let r = if holds { rate * (1.0 - p) } else { rate * p };
        if r > 0.0 {
            self.now - (1.0 - self.rng.random::<f64>()).ln() / r
        } else {
            f64::INFINITY
        }
    }

    fn apply_changes(&mut self) {
        let keys: Vec<String> = self.world.conditions.keys().cloned().collect();
        for key in keys {
            let (holds, at) = self.world.conditions[&key];
            if at <= self.now {
                // Parameters of the first node with this key (the translation's choice too).
                let n = self
                    .tree
                    .preorder()
                    .into_iter()
                    .find(|&n| {
                        matches!(self.tree.node(n).kind, Kind::Condition | Kind::Gate)
                            && self.params.condition_key(self.tree, n) == key
                    })
                    .unwrap_or(Tree::ROOT);
                let c = self.params.condition(self.tree, n);
                let next = self.next_change(!holds, c.p_true, c.change_rate);
                self.world.conditions.insert(key, (!holds, next));
            }
        }
    }

    /// The earliest pending event: a running action's end, an armed timer, a condition's change.
    fn next_event(&self) -> f64 {
        let mut t = self
            .world
            .conditions
            .values()
            .map(|c| c.1)
            .fold(f64::INFINITY, f64::min);
        for (i, node) in self.tree.nodes.iter().enumerate() {
            let timer = match node.kind {
                Kind::Action | Kind::Sleep { .. } => self.status[i] == Status::Running,
                Kind::Timeout { .. } => self.status[i] == Status::Running,
                Kind::Delay { .. } => self.status[i] == Status::Running && !self.mem[i].flag,
                Kind::Periodic { .. } => self.mem[i].flag,
                _ => false,
            };
            if timer {
                t = t.min(self.mem[i].time);
            }
        }
        t
    }

    fn holds(&self, n: NodeId) -> bool {
        let key = self.params.condition_key(self.tree, n);
        self.world.conditions.get(&key).is_some_and(|c| c.0)
    }

    /// Halts `n`'s subtree (BehaviorTree.CPP's halt + reset): every node
    /// back to idle; a persistent index is reset only where its node was running.
    fn reset(&mut self, n: NodeId) {
        for m in self.tree.preorder_from(n) {
            let i = m.index();
            let running = self.status[i] == Status::Running;
            let keep = self.mem[i].persistent;
            self.mem[i] = Mem {
                persistent: if running { 0 } else { keep },
                ..Mem::default()
            };
            self.status[i] = Status::Idle;
        }
    }

    fn done(&mut self, n: NodeId, s: Status) -> Result<Status> {
        self.status[n.index()] = s;
        if s != Status::Running {
            let kids = self.tree.node(n).children.clone();
            for c in kids {
                self.reset(c);
            }
        }
        Ok(s)
    }

    /// A child's report taken by a parent that does not tick it again: a
    /// child that may linger (a periodic decorator) is halted.
    fn take(&mut self, c: NodeId, s: Status) -> Status {
        if s != Status::Running && self.linger[c.index()] {
            self.reset(c);
        }
        s
    }

    /// Re-reads a pure child (conditions only): its value now.
    fn reread(&mut self, c: NodeId) -> Result<Status> {
        self.reset(c);
        self.tick(c)
    }

    fn tick(&mut self, n: NodeId) -> Result<Status> {
        let node = self.tree.node(n);
        let i = n.index();
        if self.status[i] == Status::Idle {
            self.status[i] = Status::Running;
            self.mem[i].idx = 0;
        }
        match node.kind.clone() {
            Kind::Action | Kind::Sleep { .. } => self.action(n),
            Kind::Condition => {
                let c = self.params.condition(self.tree, n);
                let holds = if c.change_rate > 0.0 {
                    self.holds(n)
                } else {
                    self.rng.random::<f64>() < c.p_true
                };
                self.done(n, if holds { Status::Success } else { Status::Failure })
            }
            Kind::Constant { success } => {
                self.done(n, if success { Status::Success } else { Status::Failure })
            }
            Kind::Sequence | Kind::Fallback => self.sequence(n, matches!(node.kind, Kind::Sequence)),
            Kind::ReactiveSequence | Kind::ReactiveFallback => {
                self.reactive(n, matches!(node.kind, Kind::ReactiveSequence))
            }
            Kind::SequenceWithMemory => self.sequence_with_memory(n),
            Kind::PipelineSequence => self.pipeline(n),
            Kind::Parallel { success, failure } => self.parallel(n, success, failure, None),
            Kind::ParallelAll { max_failures } => self.parallel(n, -1, -1, Some(max_failures)),
            Kind::IfThenElse | Kind::WhileDoElse => {
                self.if_then_else(n, matches!(node.kind, Kind::WhileDoElse))
            }
            Kind::Switch { .. } => self.switch(n),
            Kind::Recovery { retries } => self.recovery(n, retries),
            Kind::RoundRobin => self.round_robin(n),
            Kind::Inverter | Kind::ForceSuccess | Kind::ForceFailure | Kind::PassThrough => self.decorator(n),
            Kind::Repeat { cycles } => self.repeat(n, cycles, true),
            Kind::Retry { attempts } => self.repeat(n, attempts, false),
            Kind::KeepRunningUntilFailure => self.repeat(n, -1, true),
            Kind::Timeout { mean_s } => self.timeout(n, mean_s),
            Kind::Delay { mean_s } => self.delay(n, mean_s),
            Kind::Periodic { mean_interval_s } => self.periodic(n, mean_interval_s),
            Kind::Gate => self.gate(n),
        }
    }

    fn action(&mut self, n: NodeId) -> Result<Status> {
        let i = n.index();
        if self.mem[i].count == 0 {
            // Started now: draw the outcome and the duration.
            let a = self.params.action(self.tree, n);
            let ok = self.rng.random::<f64>() < a.p_success;
            let mean = if ok {
                a.mean_time_success
            } else {
                a.mean_time_failure
            };
            let d = erlang(&mut self.rng, mean, a.phases);
            self.mem[i].flag = ok;
            self.mem[i].count = 1;
            self.mem[i].time = self.now + d;
        }
        if self.now >= self.mem[i].time {
            let s = if self.mem[i].flag {
                Status::Success
            } else {
                Status::Failure
            };
            return self.done(n, s);
        }
        self.done(n, Status::Running)
    }

    fn sequence(&mut self, n: NodeId, is_sequence: bool) -> Result<Status> {
        let kids = self.tree.node(n).children.clone();
        let (pass, stop) = if is_sequence {
            (Status::Success, Status::Failure)
        } else {
            (Status::Failure, Status::Success)
        };
        while self.mem[n.index()].idx < kids.len() {
            let c = kids[self.mem[n.index()].idx];
            let s = self.tick(c)?;
            let s = self.take(c, s);
            if s == Status::Running {
                return self.done(n, Status::Running);
            }
            if s == stop {
                return self.done(n, stop);
            }
            debug_assert_eq!(s, pass);
            self.mem[n.index()].idx += 1;
        }
        self.done(n, pass)
    }

    /// A reactive sequence or fallback: the pure children before the
    /// running one are read again (one that now stops the node resets the
    /// running child), then the node goes on as its plain form.
    fn reactive(&mut self, n: NodeId, is_sequence: bool) -> Result<Status> {
        let kids = self.tree.node(n).children.clone();
        let stop = if is_sequence {
            Status::Failure
        } else {
            Status::Success
        };
        let running = self.mem[n.index()].idx;
        // Earlier children: pure ones are read again; the others keep their result.
        for &c in &kids[..running] {
            if self.pure[c.index()] && self.reread(c)? == stop {
                self.reset(kids[running]);
                return self.done(n, stop);
            }
        }
        self.sequence(n, is_sequence)
    }

    fn sequence_with_memory(&mut self, n: NodeId) -> Result<Status> {
        let kids = self.tree.node(n).children.clone();
        loop {
            let k = self.mem[n.index()].persistent;
            let c = kids[k];
            let s = self.tick(c)?;
            let s = self.take(c, s);
            match s {
                Status::Running => return self.done(n, Status::Running),
                Status::Failure => return self.done(n, Status::Failure),
                _ => {
                    if k + 1 == kids.len() {
                        self.mem[n.index()].persistent = 0;
                        return self.done(n, Status::Success);
                    }
                    self.mem[n.index()].persistent = k + 1;
                }
            }
        }
    }

    fn pipeline(&mut self, n: NodeId) -> Result<Status> {
        let kids = self.tree.node(n).children.clone();
        let mut i = 0;
        while i < kids.len() {
            let c = kids[i];
            let furthest = self.mem[n.index()].idx;
            let s = if i < furthest {
                if self.pure[c.index()] {
                    self.reread(c)?
                } else if self.status[c.index()] == Status::Running {
                    self.tick(c)?
                } else {
                    self.status[c.index()]
                }
            } else {
                self.tick(c)?
            };
            match s {
                Status::Failure => return self.done(n, Status::Failure),
                Status::Running if i >= furthest => {
                    self.mem[n.index()].idx = i;
                    return self.done(n, Status::Running);
                }
                Status::Success if i >= furthest => self.mem[n.index()].idx = i + 1,
                _ => {}
            }
            i += 1;
        }
        self.done(n, Status::Success)
    }

    fn parallel(&mut self, n: NodeId, success: i64, failure: i64, all: Option<i64>) -> Result<Status> {
        let kids = self.tree.node(n).children.clone();
        let count = kids.len() as i64;
        if self.mem[n.index()].done.len() != kids.len() {
            self.mem[n.index()].done = vec![false; kids.len()];
        }
        let need_s = if success < 0 { count + success + 1 } else { success };
        let need_f = if failure < 0 { count + failure + 1 } else { failure };
        for (k, &c) in kids.iter().enumerate() {
            if self.mem[n.index()].done[k] {
                continue;
            }
            let s = self.tick(c)?;
            let s = self.take(c, s);
            match s {
                Status::Success => {
                    self.mem[n.index()].done[k] = true;
                    self.mem[n.index()].count += 1;
                }
                Status::Failure => {
                    self.mem[n.index()].done[k] = true;
                    self.mem[n.index()].count2 += 1;
                }
                _ => {}
            }
            let (ok, ko) = (self.mem[n.index()].count, self.mem[n.index()].count2);
            if let Some(max) = all {
                if ok + ko == count {
                    let failed = max >= 0 && ko > max;
                    return self.done(n, if failed { Status::Failure } else { Status::Success });
                }
                continue;
            }
            if ok >= need_s {
                return self.done(n, Status::Success);
            }
            if count - ko < need_s || ko >= need_f {
                return self.done(n, Status::Failure);
            }
        }
        self.done(n, Status::Running)
    }

    fn if_then_else(&mut self, n: NodeId, reactive: bool) -> Result<Status> {
        let kids = self.tree.node(n).children.clone();
        let i = n.index();
        // mem.idx: 0 = deciding, 1 = then running, 2 = else running.
        if self.mem[i].idx == 0 {
            let s = self.tick(kids[0])?;
            let s = self.take(kids[0], s);
            match s {
                Status::Running => return self.done(n, Status::Running),
                Status::Success => self.mem[i].idx = 1,
                _ if kids.len() == 3 => self.mem[i].idx = 2,
                _ => return self.done(n, Status::Failure),
            }
        } else if reactive && self.pure[kids[0].index()] {
            let holds = self.reread(kids[0])? == Status::Success;
            let want = if holds { 1 } else { 2 };
            if want != self.mem[i].idx {
                let current = kids[self.mem[i].idx];
                self.reset(current);
                if want == 2 && kids.len() < 3 {
                    return self.done(n, Status::Failure);
                }
                self.mem[i].idx = want;
            }
        }
        let b = kids[self.mem[i].idx];
        let s = self.tick(b)?;
        let s = self.take(b, s);
        self.done(n, s)
    }

    fn switch(&mut self, n: NodeId) -> Result<Status> {
        let kids = self.tree.node(n).children.clone();
        let i = n.index();
        if self.mem[i].count == 0 {
            let w = self
                .params
                .node(self.tree, n)
                .weights
                .unwrap_or_else(|| vec![1.0; kids.len()]);
            let total: f64 = w.iter().sum();
            let mut u = self.rng.random::<f64>() * total;
            let mut pick = kids.len() - 1;
            for (k, &wk) in w.iter().enumerate() {
                if u < wk {
                    pick = k;
                    break;
                }
                u -= wk;
            }
            self.mem[i].idx = pick;
            self.mem[i].count = 1;
        }
        let c = kids[self.mem[i].idx];
        let s = self.tick(c)?;
        let keep = self.status[c.index()] == Status::Running;
        let r = self.done(n, s);
        if keep {
            self.status[i] = Status::Running;
        }
        r
    }

    fn recovery(&mut self, n: NodeId, retries: u32) -> Result<Status> {
        let kids = self.tree.node(n).children.clone();
        let i = n.index();
        loop {
            let k = self.mem[i].idx;
            let s = self.tick(kids[k])?;
            let s = self.take(kids[k], s);
            match (k, s) {
                (_, Status::Running) => return self.done(n, Status::Running),
                (0, Status::Success) => return self.done(n, Status::Success),
                (0, _) if self.mem[i].count < i64::from(retries) => {
                    self.reset(kids[0]);
                    self.mem[i].idx = 1;
                }
                (0, _) => return self.done(n, Status::Failure),
                (_, Status::Success) => {
                    self.reset(kids[1]);
                    self.mem[i].count += 1;
                    self.mem[i].idx = 0;
                }
                _ => return self.done(n, Status::Failure),
            }
        }
    }

    fn round_robin(&mut self, n: NodeId) -> Result<Status> {
        let kids = self.tree.node(n).children.clone();
        let i = n.index();
        let k = kids.len();
        loop {
            let c = kids[self.mem[i].persistent];
            let s = self.tick(c)?;
            let s = self.take(c, s);
            match s {
                Status::Running => return self.done(n, Status::Running),
                Status::Success => {
                    self.mem[i].persistent = (self.mem[i].persistent + 1) % k;
                    self.reset(c);
                    return self.done(n, Status::Success);
                }
                _ => {
                    self.reset(c);
                    self.mem[i].persistent = (self.mem[i].persistent + 1) % k;
                    self.mem[i].count += 1;
                    if self.mem[i].count as usize >= k {
                        self.mem[i].persistent = 0;
                        return self.done(n, Status::Failure);
                    }
                }
            }
        }
    }

    fn decorator(&mut self, n: NodeId) -> Result<Status> {
        let c = self.tree.node(n).children[0];
        let s = self.tick(c)?;
        let mapped = match (&self.tree.node(n).kind, s) {
            (_, Status::Running) => Status::Running,
            (Kind::Inverter, Status::Success) => Status::Failure,
            (Kind::Inverter, _) => Status::Success,
            (Kind::ForceSuccess, _) => Status::Success,
            (Kind::ForceFailure, _) => Status::Failure,
            (_, s) => s,
        };
        self.pass(n, c, mapped)
    }

    /// A pass-through decorator's report: a child that keeps running in the
    /// background (a periodic decorator) keeps the decorator running too.
    fn pass(&mut self, n: NodeId, c: NodeId, s: Status) -> Result<Status> {
        if self.status[c.index()] == Status::Running {
            self.status[n.index()] = Status::Running;
            return Ok(s);
        }
        self.done(n, s)
    }

    fn repeat(&mut self, n: NodeId, times: i64, on_success: bool) -> Result<Status> {
        let c = self.tree.node(n).children[0];
        let i = n.index();
        if times == 0 {
            return self.done(n, Status::Success);
        }
        let again = if on_success {
            Status::Success
        } else {
            Status::Failure
        };
        let mut spins = 0u64;
        loop {
            let s = self.tick(c)?;
            let s = self.take(c, s);
            if s == Status::Running {
                return self.done(n, Status::Running);
            }
            if s != again {
                return self.done(n, s);
            }
            self.mem[i].count += 1;
            if times > 0 && self.mem[i].count >= times {
                return self.done(n, s);
            }
            self.reset(c);
            spins += 1;
            if spins > 10_000_000 {
                return Err(Error::Analysis(format!(
                    "{}: the child is repeated forever in zero time",
                    self.tree.node(n).path
                )));
            }
        }
    }

    fn timeout(&mut self, n: NodeId, mean_s: f64) -> Result<Status> {
        let c = self.tree.node(n).children[0];
        let i = n.index();
        if !self.mem[i].flag {
            self.mem[i].flag = true;
            let phases = self.params.defaults.action.phases;
            self.mem[i].time = self.now + erlang(&mut self.rng, mean_s, phases);
        }
        if self.now >= self.mem[i].time {
            self.reset(c);
            return self.done(n, Status::Failure);
        }
        let s = self.tick(c)?;
        let s = self.take(c, s);
        self.done(n, s)
    }

    fn delay(&mut self, n: NodeId, mean_s: f64) -> Result<Status> {
        let c = self.tree.node(n).children[0];
        let i = n.index();
        if self.mem[i].count == 0 {
            self.mem[i].count = 1;
            let phases = self.params.defaults.action.phases;
            self.mem[i].time = self.now + erlang(&mut self.rng, mean_s, phases);
        }
        if !self.mem[i].flag {
            if self.now < self.mem[i].time {
                return self.done(n, Status::Running);
            }
            self.mem[i].flag = true;
        }
        let s = self.tick(c)?;
        self.pass(n, c, s)
    }

    fn periodic(&mut self, n: NodeId, interval: Option<f64>) -> Result<Status> {
        let c = self.tree.node(n).children[0];
        let i = n.index();
        let interval = self
            .params
            .node(self.tree, n)
            .mean_interval
            .or(interval)
            .unwrap_or(0.0);
        if self.mem[i].flag {
            // Waiting for the next run.
            if self.now < self.mem[i].time {
                self.status[i] = Status::Running;
                return Ok(Status::Running);
            }
            self.mem[i].flag = false;
            self.reset(c);
        } else if self.mem[i].count == 1 && self.status[c.index()] != Status::Running {
            // Ran once and will never run again (no interval).
            self.status[i] = Status::Running;
            return Ok(Status::Running);
        }
        let s = self.tick(c)?;
        match s {
            Status::Running => {
                self.status[i] = Status::Running;
                Ok(Status::Running)
            }
            Status::Success => {
                self.status[i] = Status::Running;
                self.mem[i].count = 1;
                if interval > 0.0 {
                    self.mem[i].flag = true;
                    let phases = self.params.defaults.action.phases;
                    self.mem[i].time = self.now + erlang(&mut self.rng, interval, phases);
                }
                Ok(Status::Success)
            }
            _ => self.done(n, s),
        }
    }

    fn gate(&mut self, n: NodeId) -> Result<Status> {
        let c = self.tree.node(n).children[0];
        let i = n.index();
        if self.mem[i].count == 0 {
            self.mem[i].count = 1;
            self.mem[i].flag = self.holds(n);
        }
        if !self.mem[i].flag {
            return self.done(n, Status::Success);
        }
        let s = self.tick(c)?;
        self.pass(n, c, s)
    }
}

/// Estimates from many runs.
#[derive(Debug, Clone, Serialize)]
pub struct Estimate {
    /// Runs.
    pub runs: usize,
    /// Fraction that succeeded.
    pub p_success: f64,
    /// Half-width of its 99 % interval (normal approximation).
    pub p_success_hw: f64,
    /// Fraction cut as never ending.
    pub p_never: f64,
    /// Mean duration of the runs that ended.
    pub mean_time: f64,
    /// Half-width of its 99 % interval.
    pub mean_time_hw: f64,
}

/// z for a two-sided 99 % interval.
const Z99: f64 = 2.575_829_303_548_901;

/// Simulates `runs` executions (run `k` seeded with `seed + k`); parameters
/// of the wrong kind for a leaf are an error ([`TreeParams::check_kinds`]).
pub fn estimate(
    tree: &Tree,
    params: &TreeParams,
    runs: usize,
    seed: u64,
    limits: Limits,
) -> Result<Estimate> {
    params.check_kinds(tree)?;
    let mut it = Interpreter::new(tree, params);
    let (mut ok, mut never) = (0usize, 0usize);
    let (mut sum, mut sum2, mut ended) = (0.0, 0.0, 0usize);
    for k in 0..runs {
        let r = it.run(seed.wrapping_add(k as u64), limits)?;
        match r.success {
            Some(s) => {
                ok += usize::from(s);
                ended += 1;
                sum += r.time;
                sum2 += r.time * r.time;
            }
            None => never += 1,
        }
    }
    let n = runs.max(1) as f64;
    let p = ok as f64 / n;
    let m = if ended > 0 { sum / ended as f64 } else { 0.0 };
    let var = if ended > 1 {
        (sum2 - ended as f64 * m * m) / (ended as f64 - 1.0)
    } else {
        0.0
    };
    Ok(Estimate {
        runs,
        p_success: p,
        p_success_hw: Z99 * (p * (1.0 - p) / n).sqrt(),
        p_never: never as f64 / n,
        mean_time: m,
        mean_time_hw: Z99 * (var.max(0.0) / ended.max(1) as f64).sqrt(),
    })
}
