//! Symbolic reachability: the reachable markings of a net as a multi-valued
//! decision diagram (MDD) over its places, built by *saturation*.
//!
//! The places are put in an order (depth 0 first); a node at depth `d` maps
//! each token count of the place at depth `d` to a node at depth `d + 1`, and
//! the paths from the root to the terminal are the markings of the set. The
//! diagram is *quasi-reduced*: every path visits every depth, and no two
//! nodes at a depth have the same children (a unique table per depth), so a
//! depth reached by exactly one node from the root splits the set into a
//! product — the markings of the places above it times those below.
//! [`crate::structure`] cuts the places into components there.
//!
//! Saturation (Ciardo, Lüttgen & Siminiceanu, *Saturation: an efficient
//! iteration strategy for symbolic state-space generation*, TACAS 2001)
//! builds the set bottom-up: a node is *saturated* when its set is closed
//! under every transition whose topmost touched place is at its depth or
//! below. Each transition's enabling and effect are a conjunction of
//! conditions and changes per place (inputs, inhibitors, capacities), so
//! firing it is a recursive walk over the depths it touches
//! (`rec_fire`), results cached per (transition, node); the union of two
//! closed sets is closed, so unions of saturated nodes stay saturated.
//! Token counts are the local states themselves: a node's children grow as
//! counts are discovered, up to a cap per place (its structural bound from
//! the P-invariants where there is one).
//!
//! **Semantics.** This is the reachability set of the underlying P/T net:
//! priorities of immediate transitions are not applied (they do not factor
//! per place), so for a net with immediate transitions the set may hold
//! markings the GSPN never reaches ([`crate::structured`] removes them with
//! an explicit search). Without immediate transitions it is exact.
//!
//! The backward search ([`Mdd::backward_covers`]) saturates the predecessors
//! of `M0` inside the bounding box of the forward set and checks that they
//! include every reachable marking: then `M0` is a home state and the chain
//! of a net without immediate transitions is irreducible.
//!
//! Cost: proportional to the nodes created times the local states per node
//! (saturation's intermediate diagrams stay close to the final one on
//! structured nets); [`MddLimits`] bounds nodes and token counts.

use std::hash::BuildHasher;

use hashbrown::{HashMap, HashTable};

use crate::error::{Error, Result};
use crate::gspn::Gspn;
use crate::net::TransitionId;

/// The empty set (at any depth).
pub(crate) const EMPTY: u32 = 0;
/// The set holding the empty suffix (below the last depth).
pub(crate) const TERMINAL: u32 = 1;

/// Bounds on a symbolic search: beyond them it stops with an error (the
/// caller falls back to explicit generation).
#[derive(Debug, Clone, Copy)]
pub(crate) struct MddLimits {
    /// Most nodes the arena may hold (intermediate ones included).
    pub max_nodes: usize,
    /// Largest token count of a place without a structural bound.
    pub max_tokens: u32,
    /// Most operations computed (firings and unions not found in their
    /// caches): bounds the time and the caches' memory of a search whose
    /// place order makes the diagram's intermediate sets explode.
    pub max_operations: u64,
    /// Most children entries the arena's nodes may hold together, and the
    /// widest node a search may build: a node of a place holding `k` tokens
    /// has `k + 1` entries, so a place with many tokens (a P-invariant
    /// `A + B = N` makes N nodes of up to N entries) would otherwise fill
    /// the memory before the node limit is reached.
    pub max_entries: usize,
}

impl Default for MddLimits {
    fn default() -> Self {
        MddLimits {
            max_nodes: 4_000_000,
            max_tokens: 1 << 16,
            max_operations: 2_000_000,
            max_entries: 1 << 26,
        }
    }
}

/// What a transition does to the place at one depth.
#[derive(Debug, Clone, Copy)]
struct LocalFn {
    depth: u32,
    /// Tokens the transition needs (its input multiplicity, 0 if none).
    need: u32,
    /// Inhibitor multiplicity (`u32::MAX` if none): enabled below it.
    inhibit: u32,
    /// Change of the count.
    delta: i64,
    /// Capacity of the place (`u32::MAX` if none).
    capacity: u32,
}

impl LocalFn {
    /// The count after firing from `v`, if the transition is enabled there.
    #[inline]
    fn forward(&self, v: u32) -> Option<u32> {
        if v < self.need || v >= self.inhibit {
            return None;
        }
        let w = i64::from(v) + self.delta;
        (w >= 0 && w <= i64::from(self.capacity)).then_some(w as u32)
    }

    /// The count before firing into `v`, if the transition could have.
    #[inline]
    fn backward(&self, v: u32) -> Option<u32> {
        let p = i64::from(v) - self.delta;
        if p < 0 || p > i64::from(u32::MAX) {
            return None;
        }
        let p = p as u32;
        (self.forward(p) == Some(v)).then_some(p)
    }
}

/// A transition as a list of per-depth functions, in depth order.
#[derive(Debug, Clone)]
struct Event {
    locals: Vec<LocalFn>,
    backward: bool,
}

impl Event {
    fn top(&self) -> usize {
        self.locals.first().map_or(usize::MAX, |l| l.depth as usize)
    }

    fn bottom(&self) -> usize {
        self.locals.last().map_or(0, |l| l.depth as usize)
    }

    #[inline]
    fn local(&self, depth: usize) -> Option<&LocalFn> {
        self.locals.iter().find(|l| l.depth as usize == depth)
    }

    #[inline]
    fn apply(&self, f: &LocalFn, v: u32) -> Option<u32> {
        if self.backward {
            f.backward(v)
        } else {
            f.forward(v)
        }
    }
}

#[derive(Debug, Clone)]
struct Node {
    depth: u32,
    children: Box<[u32]>,
}

/// An arena of MDD nodes over a fixed order of places, with the
/// operations of saturation.
#[derive(Debug)]
pub(crate) struct Mdd {
    /// Place at each depth.
    order: Vec<u32>,
    /// Largest count allowed at each depth; `strict[d]` says whether
    /// exceeding it is an error (a cap) or only pruned (a bounding box).
    cap: Vec<u32>,
    strict: Vec<bool>,
    nodes: Vec<Node>,
    unique: Vec<HashTable<u32>>,
    hasher: hashbrown::DefaultHashBuilder,
    union_cache: HashMap<(u32, u32), u32>,
    intersect_cache: HashMap<(u32, u32), u32>,
    fire_cache: HashMap<(u32, u32), u32>,
    events: Vec<Event>,
    /// Events by top depth.
    by_top: Vec<Vec<u32>>,
    limits: MddLimits,
    /// Operations computed so far (see [`MddLimits::max_operations`]).
    operations: u64,
    /// Children entries of the arena's nodes (see [`MddLimits::max_entries`]).
    entries: usize,
    /// Names of places, for errors.
    place_names: Vec<String>,
}

impl Mdd {
    /// An empty arena over `order` (a permutation of `gspn`'s places), with
    /// `gspn`'s transitions as forward events. `bounds[p]` is place `p`'s
    /// structural bound, if known (counts above it never occur).
    pub(crate) fn new(gspn: &Gspn, order: &[u32], bounds: &[Option<u64>], limits: MddLimits) -> Mdd {
        let depth_of = inverse(order, gspn.num_places());
        let cap: Vec<u32> = order
            .iter()
            .map(|&p| bounds[p as usize].map_or(limits.max_tokens, |b| u32::try_from(b).unwrap_or(u32::MAX)))
            .collect();
        let strict = order.iter().map(|&p| bounds[p as usize].is_none()).collect();
        let mut mdd = Mdd {
            order: order.to_vec(),
            cap,
            strict,
            nodes: vec![
                Node {
                    depth: u32::MAX,
                    children: Box::new([]),
                },
                Node {
                    depth: order.len() as u32,
                    children: Box::new([]),
                },
            ],
            unique: (0..order.len()).map(|_| HashTable::new()).collect(),
            hasher: hashbrown::DefaultHashBuilder::default(),
            union_cache: HashMap::new(),
            intersect_cache: HashMap::new(),
            fire_cache: HashMap::new(),
            events: Vec::new(),
            by_top: vec![Vec::new(); order.len()],
            limits,
            operations: 0,
            entries: 0,
            place_names: gspn.place_names().to_vec(),
        };
        for t in 0..gspn.num_transitions() {
            let e = event_of(gspn, TransitionId(t as u32), &depth_of);
            mdd.add_event(e);
        }
        mdd
    }

    fn add_event(&mut self, e: Event) {
        let id = self.events.len() as u32;
        if !e.locals.is_empty() {
            self.by_top[e.top()].push(id);
        }
        self.events.push(e);
    }

    /// Number of depths (places).
    pub(crate) fn depths(&self) -> usize {
        self.order.len()
    }

    /// The place at `depth`.
    pub(crate) fn place_at(&self, depth: usize) -> u32 {
        self.order[depth]
    }

    /// Depth of node `n` (the number of depths for [`TERMINAL`]).
    pub(crate) fn depth(&self, n: u32) -> usize {
        self.nodes[n as usize].depth as usize
    }

    /// Children of node `n`, indexed by token count.
    pub(crate) fn children(&self, n: u32) -> &[u32] {
        &self.nodes[n as usize].children
    }

    /// Nodes in the arena.
    pub(crate) fn arena_len(&self) -> usize {
        self.nodes.len()
    }

    fn unique(&mut self, depth: usize, mut ch: Vec<u32>) -> Result<u32> {
        while ch.last() == Some(&EMPTY) {
            ch.pop();
        }
        if ch.is_empty() {
            return Ok(EMPTY);
        }
        let hash = self.hasher.hash_one(&ch[..]);
        let nodes = &self.nodes;
        if let Some(&id) = self.unique[depth].find(hash, |&id| *nodes[id as usize].children == ch[..]) {
            return Ok(id);
        }
        if self.nodes.len() >= self.limits.max_nodes {
            return Err(Error::Invalid(format!(
                "the symbolic state space needs more than {} decision-diagram nodes",
                self.limits.max_nodes
            )));
        }
        self.room(ch.len())?;
        self.entries += ch.len();
        let id = self.nodes.len() as u32;
        self.nodes.push(Node {
            depth: depth as u32,
            children: ch.into_boxed_slice(),
        });
        let nodes = &self.nodes;
        let hasher = &self.hasher;
        self.unique[depth].insert_unique(hash, id, |&i| hasher.hash_one(&nodes[i as usize].children[..]));
        Ok(id)
    }

    /// An error if `len` more children entries would pass
    /// [`MddLimits::max_entries`] (a node that wide, or the arena that full).
    fn room(&self, len: usize) -> Result<()> {
        if self.entries.saturating_add(len) > self.limits.max_entries {
            return Err(Error::Invalid(format!(
                "the symbolic state space needs more than {} decision-diagram entries (a place holding many tokens)",
                self.limits.max_entries
            )));
        }
        Ok(())
    }

    /// Counts one computed operation; past [`MddLimits::max_operations`], an
    /// error.
    fn count_operation(&mut self) -> Result<()> {
        self.operations += 1;
        if self.operations > self.limits.max_operations {
            return Err(Error::Invalid(format!(
                "the symbolic search needs more than {} operations (the place order makes its intermediate sets large)",
                self.limits.max_operations
            )));
        }
        Ok(())
    }

    /// The union of two nodes at the same depth.
    pub(crate) fn union(&mut self, a: u32, b: u32) -> Result<u32> {
        if a == EMPTY || a == b {
            return Ok(b);
        }
        if b == EMPTY {
            return Ok(a);
        }
        let key = (a.min(b), a.max(b));
        if let Some(&r) = self.union_cache.get(&key) {
            return Ok(r);
        }
        self.count_operation()?;
        let d = self.depth(a);
        let (ca, cb) = (self.children(a).to_vec(), self.children(b).to_vec());
        let mut ch = vec![EMPTY; ca.len().max(cb.len())];
        for (i, slot) in ch.iter_mut().enumerate() {
            let x = ca.get(i).copied().unwrap_or(EMPTY);
            let y = cb.get(i).copied().unwrap_or(EMPTY);
            *slot = self.union(x, y)?;
        }
        let r = self.unique(d, ch)?;
        self.union_cache.insert(key, r);
        Ok(r)
    }

    /// The intersection of two nodes at the same depth.
    pub(crate) fn intersect(&mut self, a: u32, b: u32) -> Result<u32> {
        if a == EMPTY || b == EMPTY {
            return Ok(EMPTY);
        }
        if a == b {
            return Ok(a);
        }
        let key = (a.min(b), a.max(b));
        if let Some(&r) = self.intersect_cache.get(&key) {
            return Ok(r);
        }
        let d = self.depth(a);
        let (ca, cb) = (self.children(a).to_vec(), self.children(b).to_vec());
        let mut ch = vec![EMPTY; ca.len().min(cb.len())];
        for (i, slot) in ch.iter_mut().enumerate() {
            *slot = self.intersect(ca[i], cb[i])?;
        }
        let r = self.unique(d, ch)?;
        self.intersect_cache.insert(key, r);
        Ok(r)
    }

    /// Applies event `e`'s function at `depth` to count `v`: the new count,
    /// `None` if disabled or outside the bounding box, an error past a cap.
    #[inline]
    fn step(&self, e: u32, depth: usize, v: u32) -> Result<Option<u32>> {
        let ev = &self.events[e as usize];
        let Some(f) = ev.local(depth) else {
            return Ok(Some(v));
        };
        match ev.apply(f, v) {
            Some(w) if w > self.cap[depth] => {
                if self.strict[depth] && !ev.backward {
                    Err(Error::Invalid(format!(
                        "place `{}` of no P-invariant holds more than {} tokens",
                        self.place_names[self.order[depth] as usize], self.cap[depth]
                    )))
                } else {
                    Ok(None)
                }
            }
            w => Ok(w),
        }
    }

    /// The saturated node of the set `ch` at `depth` (whose children are
    /// saturated): closed under every event whose top depth is `depth`.
    fn saturate(&mut self, depth: usize, mut ch: Vec<u32>) -> Result<u32> {
        let events = self.by_top[depth].clone();
        loop {
            let mut changed = false;
            for &e in &events {
                let mut work: Vec<u32> = (0..ch.len() as u32)
                    .filter(|&i| ch[i as usize] != EMPTY)
                    .collect();
                while let Some(i) = work.pop() {
                    let Some(j) = self.step(e, depth, i)? else {
                        continue;
                    };
                    let f = self.rec_fire(e, ch[i as usize])?;
                    if f == EMPTY {
                        continue;
                    }
                    let j = j as usize;
                    if j >= ch.len() {
                        self.room(j + 1)?;
                        ch.resize(j + 1, EMPTY);
                    }
                    let u = self.union(ch[j], f)?;
                    if u != ch[j] {
                        ch[j] = u;
                        changed = true;
                        work.push(j as u32);
                    }
                }
            }
            if !changed {
                break;
            }
        }
        self.unique(depth, ch)
    }

    /// The saturated set reached from node `q` by firing event `e` once
    /// (at `q`'s depth and below), then saturating.
    fn rec_fire(&mut self, e: u32, q: u32) -> Result<u32> {
        if q == EMPTY {
            return Ok(EMPTY);
        }
        let depth = self.depth(q);
        if depth > self.events[e as usize].bottom() {
            return Ok(q);
        }
        if let Some(&r) = self.fire_cache.get(&(e, q)) {
            return Ok(r);
        }
        self.count_operation()?;
        let children = self.children(q).to_vec();
        let mut s: Vec<u32> = Vec::new();
        for (i, &c) in children.iter().enumerate() {
            if c == EMPTY {
                continue;
            }
            let Some(j) = self.step(e, depth, i as u32)? else {
                continue;
            };
            let f = self.rec_fire(e, c)?;
            if f == EMPTY {
                continue;
            }
            let j = j as usize;
            if j >= s.len() {
                self.room(j + 1)?;
                s.resize(j + 1, EMPTY);
            }
            s[j] = self.union(s[j], f)?;
        }
        let r = if s.iter().all(|&c| c == EMPTY) {
            EMPTY
        } else {
            self.saturate(depth, s)?
        };
        self.fire_cache.insert((e, q), r);
        Ok(r)
    }

    /// The saturated set of everything reachable from `marking` (indexed by
    /// place) by the events added so far.
    fn reach_from(&mut self, marking: &[u32]) -> Result<u32> {
        let mut below = TERMINAL;
        for depth in (0..self.depths()).rev() {
            let v = marking[self.order[depth] as usize] as usize;
            self.room(v + 1)?;
            let mut ch = vec![EMPTY; v + 1];
            ch[v] = below;
            below = self.saturate(depth, ch)?;
        }
        Ok(below)
    }

    /// The reachable markings of the P/T net from `m0`: the root node.
    pub(crate) fn forward(&mut self, m0: &[u32]) -> Result<u32> {
        for depth in 0..self.depths() {
            let v = m0[self.order[depth] as usize];
            if v > self.cap[depth] {
                return Err(Error::Invalid(format!(
                    "place `{}` starts with more tokens than its bound",
                    self.place_names[self.order[depth] as usize]
                )));
            }
        }
        self.reach_from(m0)
    }

    /// Whether every marking of `reach` (the forward set from `m0`) can
    /// reach `m0` back (P/T semantics): the backward set of `m0`, pruned to
    /// the bounding box of `reach` (every path between two markings of
    /// `reach` stays in it), must contain `reach`.
    pub(crate) fn backward_covers(&mut self, reach: u32, m0: &[u32]) -> Result<bool> {
        let maxima = self.max_counts(reach);
        let forward_events = self.events.len();
        let saved = (
            self.cap.clone(),
            self.strict.clone(),
            std::mem::take(&mut self.by_top),
        );
        self.by_top = vec![Vec::new(); self.depths()];
        self.cap = maxima;
        self.strict = vec![false; self.depths()];
        for e in 0..forward_events {
            let mut back = self.events[e].clone();
            back.backward = true;
            self.add_event(back);
        }
        let result = self.reach_from(m0).and_then(|b| self.intersect(reach, b));
        let (cap, strict, by_top) = saved;
        self.cap = cap;
        self.strict = strict;
        self.by_top = by_top;
        self.events.truncate(forward_events);
        Ok(result? == reach)
    }

    /// The largest count at each depth over the set of `root`.
    pub(crate) fn max_counts(&self, root: u32) -> Vec<u32> {
        let mut maxima = vec![0u32; self.depths()];
        for n in self.reachable_nodes(root) {
            let d = self.depth(n);
            let top = self.children(n).len().saturating_sub(1) as u32;
            maxima[d] = maxima[d].max(top);
        }
        maxima
    }

    /// The nodes reachable from `root` (terminal excluded), in depth order.
    pub(crate) fn reachable_nodes(&self, root: u32) -> Vec<u32> {
        let mut seen = HashMap::new();
        let mut order = Vec::new();
        if root > TERMINAL {
            seen.insert(root, ());
            order.push(root);
        }
        let mut k = 0;
        while k < order.len() {
            let n = order[k];
            k += 1;
            for &c in self.children(n) {
                if c > TERMINAL && seen.insert(c, ()).is_none() {
                    order.push(c);
                }
            }
        }
        order.sort_by_key(|&n| (self.depth(n), n));
        order
    }

    /// Nodes reachable from `root` at each depth.
    pub(crate) fn nodes_per_depth(&self, root: u32) -> Vec<usize> {
        let mut counts = vec![0; self.depths()];
        for n in self.reachable_nodes(root) {
            counts[self.depth(n)] += 1;
        }
        counts
    }

    /// Number of markings in the set of `root` (saturating at `u128::MAX`).
    pub(crate) fn count(&self, root: u32) -> u128 {
        let mut memo: HashMap<u32, u128> = HashMap::new();
        memo.insert(TERMINAL, 1);
        memo.insert(EMPTY, 0);
        for n in self.reachable_nodes(root).into_iter().rev() {
            let c = self
                .children(n)
                .iter()
                .fold(0u128, |acc, ch| acc.saturating_add(memo[ch]));
            memo.insert(n, c);
        }
        memo.get(&root).copied().unwrap_or(0)
    }

    /// The count vectors of every path from `top` down to depth `end`
    /// (`end` exclusive; every path reaches the same node there), in
    /// lexicographic order, flattened: `end − depth(top)` counts each.
    pub(crate) fn enumerate(&self, top: u32, end: usize, limit: usize) -> Option<Vec<u32>> {
        let start = self.depth(top);
        let width = end - start;
        let mut out = Vec::new();
        let mut path: Vec<u32> = Vec::with_capacity(width);
        // Stack of (node, next child to try).
        let mut stack: Vec<(u32, usize)> = vec![(top, 0)];
        while let Some(&mut (n, ref mut next)) = stack.last_mut() {
            if self.depth(n) == end || n == TERMINAL {
                out.extend_from_slice(&path);
                if out.len() / width.max(1) > limit {
                    return None;
                }
                stack.pop();
                path.pop();
                continue;
            }
            let ch = self.children(n);
            while *next < ch.len() && ch[*next] == EMPTY {
                *next += 1;
            }
            if *next == ch.len() {
                stack.pop();
                path.pop();
                continue;
            }
            let v = *next;
            *next += 1;
            path.push(v as u32);
            stack.push((ch[v], 0));
        }
        Some(out)
    }
}

/// `inverse[order[i]] = i`.
fn inverse(order: &[u32], n: usize) -> Vec<u32> {
    let mut inv = vec![u32::MAX; n];
    for (i, &p) in order.iter().enumerate() {
        inv[p as usize] = i as u32;
    }
    inv
}

/// Transition `t` as per-depth functions over the places it reads or changes.
fn event_of(gspn: &Gspn, t: TransitionId, depth_of: &[u32]) -> Event {
    let mut by_place: std::collections::BTreeMap<u32, LocalFn> = std::collections::BTreeMap::new();
    let blank = |p: u32| LocalFn {
        depth: depth_of[p as usize],
        need: 0,
        inhibit: u32::MAX,
        delta: 0,
        capacity: u32::MAX,
    };
    for &(p, k) in gspn.inputs(t) {
        by_place.entry(p).or_insert_with(|| blank(p)).need = k;
    }
    for &(p, k) in gspn.inhibitors(t) {
        by_place.entry(p).or_insert_with(|| blank(p)).inhibit = k;
    }
    for &(p, d) in gspn.delta(t) {
        let f = by_place.entry(p).or_insert_with(|| blank(p));
        f.delta = d;
        if d > 0 {
            if let Some(c) = gspn.capacities()[p as usize] {
                f.capacity = c;
            }
        }
    }
    let mut locals: Vec<LocalFn> = by_place.into_values().collect();
    locals.sort_by_key(|l| l.depth);
    Event {
        locals,
        backward: false,
    }
}
