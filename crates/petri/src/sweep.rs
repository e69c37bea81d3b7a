//! Matrix-free Gauss–Seidel / SOR sweeps over a Kronecker descriptor
//! ([`crate::descriptor`]): the balance equations
//! `exit_j x_j = Σ_i x_i q_ij` solved in place on one vector, every `q_ij`
//! computed from the local maps when it is needed.
//!
//! **Rows.** The last component (the *inner* level) varies fastest: a
//! *row* is the states sharing the other components' local states, `n =
//! |S_K|` consecutive entries. For a row, each event that moves an outer
//! component has *one* source row (the predecessors of the row's states
//! under that event), so its inflow is an AXPY `acc[c] += s · x_src[c]`
//! (or a gather `acc[c] += s · g[c] · x_src[ip[c]]` when it also moves the
//! inner level) over contiguous memory; the events that move only the inner
//! level are a small sparse matrix over the row, applied in a sequential
//! Gauss–Seidel pass that reads the values just updated. Exit rates are
//! summed per row the same way (nothing per state is stored). Cost per
//! state: one multiply-add per incoming event, a division, and streaming
//! reads of the source rows.
//!
//! **Order and threads.** States are updated in index order within a
//! *slice* (the states sharing the outermost component's local state).
//! Slices are coloured so that no event moves a state between two slices of
//! the same colour; a sweep processes the colours in turn, the slices of
//! one colour in parallel (each reads only slices of other colours, which
//! nobody writes meanwhile). The colouring depends on the net only, so the
//! iteration — and every bit of its result — is the same on any number of
//! threads. Per-slice sums are added in slice order.
//!
//! **Vanishing markings** (nets with immediate transitions) are states of
//! the chain too: a vanishing marking leaves at total rate 1, each
//! immediate transition of the highest enabled priority with probability
//! `w / Σw`; timed transitions do not fire there. Restricted to the
//! tangible states and renormalised, the stationary vector of this chain is
//! the GSPN's (the jump chain is the same; only the time spent in the
//! vanishing markings, removed by the restriction, differs). Each state's
//! class (unreachable, tangible, or vanishing with its priority and weight
//! sum) is looked up in [`Kinds`]. With classes no event is folded into the
//! row matrix, so each inner state lists the in-row events that lead to
//! it, and each event the inner states where it is enabled: a state costs
//! its in- and out-degree, not the number of events. Unreachable states
//! are skipped before anything is summed for them.

use rayon::prelude::*;

use crate::descriptor::{Descriptor, Factor, NONE};

/// Class of every state of the product space, for nets with immediate
/// transitions: `class[i]` indexes `classes`; class 0 is unreachable,
/// class 1 tangible, the others vanishing.
#[derive(Debug, Clone)]
pub(crate) struct Kinds {
    /// Per state.
    pub class: Vec<u16>,
    /// Per class.
    pub classes: Vec<Class>,
}

/// What a state class allows to fire.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Class {
    /// Priority of the immediate transitions that fire (0: tangible).
    pub priority: u32,
    /// Sum of their weights.
    pub weight_sum: f64,
}

/// The unreachable class.
pub(crate) const UNREACHABLE: u16 = 0;
/// The tangible class.
pub(crate) const TANGIBLE: u16 = 1;

/// An event bound to its rate and arranged for the row passes.
#[derive(Debug, Clone)]
struct Bound {
    /// Index in the descriptor's events.
    event: usize,
    /// Indices (in the event's maps) of the outer levels it touches.
    outer: Vec<usize>,
    /// Index of its inner-level map, if it touches the inner level.
    inner: Option<usize>,
    /// Whether it moves level 0 (its source rows lie in other slices).
    moves_level0: bool,
    /// Whether it moves some outer level (its source row is another row).
    moves_outer: bool,
    /// Whether it is in the row matrix (`Plan::in_*`) and `inner_exit`.
    aggregated: bool,
    /// Rate (scaled; 1 for an immediate transition, whose weight comes
    /// from the class).
    rate: f64,
    /// Inner predecessor of each inner state (0 where none; `g_in` is 0).
    ip: Vec<u32>,
    /// `rate ·` inner factor at the predecessor, 0 where none.
    g_in: Vec<f64>,
    /// `rate ·` inner factor at the state, 0 where disabled.
    g_out: Vec<f64>,
    /// The inner states where `g_in` is not 0.
    in_at: Vec<u32>,
    /// The inner states where `g_out` is not 0.
    out_at: Vec<u32>,
    /// Inner degree at each inner state (functional factors only).
    inner_degree: Vec<u32>,
    /// Cap of a functional factor (`None` otherwise).
    min_cap: Option<u32>,
    /// Whether the product factor lives on an outer level.
    outer_local_cap: Option<u32>,
    /// Firing factor per class (with kinds).
    class_factor: Vec<f64>,
}

/// Everything a pass needs: the descriptor, the bound events, the classes.
#[derive(Debug)]
pub(crate) struct Plan<'a> {
    desc: &'a Descriptor,
    kinds: Option<&'a Kinds>,
    inner: usize,
    n: usize,
    events: Vec<Bound>,
    /// Events read per row in `gather` (not aggregated).
    gathered: Vec<usize>,
    /// Events that move only the inner level and are not aggregated.
    inrow: Vec<usize>,
    /// Their incoming entries per inner state (`inrow_off[c]` to
    /// `inrow_off[c + 1]` in `inrow_in`): position in `inrow`, inner
    /// predecessor and `g_in`, in `inrow` order — so that a state reads
    /// only the events that reach it.
    inrow_off: Vec<u32>,
    inrow_in: Vec<(u32, u32, f64)>,
    /// The aggregated events' incoming entries per inner state.
    in_off: Vec<u32>,
    in_ip: Vec<u32>,
    in_g: Vec<f64>,
    /// The aggregated events' exit rate per inner state.
    inner_exit: Vec<f64>,
    /// Colour of each level-0 local state.
    colors: Vec<u32>,
    num_colors: u32,
}

/// What a pass accumulates.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Sums {
    /// `Σ_j |inflow_j − exit_j x_j|` with the values before each update.
    pub imbalance: f64,
    /// `Σ_j exit_j x_j` with the values after.
    pub flow: f64,
    /// `Σ_j x_j` after.
    pub total: f64,
    /// Smallest entry after.
    pub min: f64,
}

impl Default for Sums {
    fn default() -> Sums {
        Sums {
            imbalance: 0.0,
            flow: 0.0,
            total: 0.0,
            min: f64::INFINITY,
        }
    }
}

impl Sums {
    fn add(self, o: Sums) -> Sums {
        Sums {
            imbalance: self.imbalance + o.imbalance,
            flow: self.flow + o.flow,
            total: self.total + o.total,
            min: self.min.min(o.min),
        }
    }
}

/// Per-slice scratch: the row's outer local states (and a copy for
/// predecessors), the inflow from other rows, the exit rates, the in-row
/// events' factors.
struct Scratch {
    locals: Vec<u32>,
    pred: Vec<u32>,
    acc: Vec<f64>,
    exit: Vec<f64>,
    inv: Vec<f64>,
    /// Per in-row event (position in `Plan::inrow`), its outer factor and
    /// degree at the row, `None` where disabled.
    inrow: Vec<Option<(f64, u32)>>,
    /// How many of them are enabled at the row.
    inrow_enabled: usize,
}

impl Scratch {
    fn new(levels: usize, n: usize, inrow: usize) -> Scratch {
        Scratch {
            locals: vec![0; levels],
            pred: vec![0; levels],
            acc: vec![0.0; n],
            exit: vec![0.0; n],
            inv: vec![0.0; n],
            inrow: vec![None; inrow],
            inrow_enabled: 0,
        }
    }
}

/// The row an event's inflow comes from, and its outer factor there.
struct Source<'s> {
    values: &'s [f64],
    start: usize,
    factor: f64,
    degree: u32,
}

impl<'a> Plan<'a> {
    /// Binds `rates` (by transition, already scaled) to the descriptor.
    pub(crate) fn new(desc: &'a Descriptor, kinds: Option<&'a Kinds>, rates: &[f64]) -> Plan<'a> {
        let k = desc.levels();
        let inner = k - 1;
        let n = desc.sizes[inner];
        let events: Vec<Bound> = desc
            .events
            .iter()
            .enumerate()
            .filter(|(_, e)| !e.self_loop)
            .map(|(ei, _)| bind(desc, kinds, ei, rates))
            .collect();
        let gathered = (0..events.len()).filter(|&b| !events[b].aggregated).collect();
        let inrow = (0..events.len())
            .filter(|&b| !events[b].aggregated && !events[b].moves_outer)
            .collect();
        let mut plan = Plan {
            desc,
            kinds,
            inner,
            n,
            events,
            gathered,
            inrow,
            inrow_off: Vec::new(),
            inrow_in: Vec::new(),
            in_off: Vec::new(),
            in_ip: Vec::new(),
            in_g: Vec::new(),
            inner_exit: vec![0.0; n],
            colors: Vec::new(),
            num_colors: 1,
        };
        plan.aggregate_inner();
        plan.index_inrow();
        plan.color_level0();
        plan
    }

    /// The aggregated events as one sparse matrix over the inner level
    /// (entries in event order per state), and their exit rates.
    fn aggregate_inner(&mut self) {
        let n = self.n;
        let mut rows: Vec<Vec<(u32, f64)>> = vec![Vec::new(); n];
        let mut exit = vec![0.0; n];
        for ev in self.events.iter().filter(|e| e.aggregated) {
            for c in 0..n {
                if ev.g_in[c] != 0.0 {
                    rows[c].push((ev.ip[c], ev.g_in[c]));
                }
                exit[c] += ev.g_out[c];
            }
        }
        self.in_off = Vec::with_capacity(n + 1);
        self.in_off.push(0);
        for r in rows {
            for (ip, g) in r {
                self.in_ip.push(ip);
                self.in_g.push(g);
            }
            self.in_off.push(self.in_ip.len() as u32);
        }
        self.inner_exit = exit;
    }

    /// The in-row events' incoming entries by inner state.
    fn index_inrow(&mut self) {
        let n = self.n;
        self.inrow_off = Vec::with_capacity(n + 1);
        self.inrow_off.push(0);
        for c in 0..n {
            for (k, &b) in self.inrow.iter().enumerate() {
                let ev = &self.events[b];
                let g = ev.g_in[c];
                if g != 0.0 {
                    self.inrow_in.push((k as u32, ev.ip[c], g));
                }
            }
            self.inrow_off.push(self.inrow_in.len() as u32);
        }
    }

    /// Greedy colouring of level 0's local states: two states joined by an
    /// event that moves level 0 get different colours.
    fn color_level0(&mut self) {
        if self.desc.levels() < 2 {
            self.colors = vec![0];
            self.num_colors = 1;
            return;
        }
        let n0 = self.desc.sizes[0];
        let mut adj: Vec<Vec<u32>> = vec![Vec::new(); n0];
        for ev in self.events.iter().filter(|e| e.moves_level0) {
            let e = &self.desc.events[ev.event];
            if let Some(m) = e.maps.iter().find(|m| m.level == 0) {
                for (l, &s) in m.succ.iter().enumerate() {
                    if s != NONE && s as usize != l {
                        adj[l].push(s);
                        adj[s as usize].push(l as u32);
                    }
                }
            }
        }
        let mut colors = vec![u32::MAX; n0];
        let mut used = Vec::new();
        for l in 0..n0 {
            used.clear();
            used.extend(
                adj[l]
                    .iter()
                    .map(|&m| colors[m as usize])
                    .filter(|&c| c != u32::MAX),
            );
            let mut c = 0;
            while used.contains(&c) {
                c += 1;
            }
            colors[l] = c;
        }
        self.num_colors = colors.iter().copied().max().map_or(1, |m| m + 1);
        self.colors = colors;
    }

    /// States per slice.
    fn slice_len(&self) -> usize {
        if self.desc.levels() < 2 {
            self.desc.states as usize
        } else {
            self.desc.strides[0] as usize
        }
    }

    /// One Gauss–Seidel (ω = 1) or SOR sweep over `x`, in place.
    pub(crate) fn sweep(&self, x: &mut [f64], omega: f64) -> Sums {
        let len = self.slice_len();
        if self.desc.levels() < 2 {
            return self.slice_sweep(0, x, &[None], omega);
        }
        let mut total = Sums::default();
        for color in 0..self.num_colors {
            let mut writers: Vec<(usize, &mut [f64])> = Vec::new();
            let mut readers: Vec<Option<&[f64]>> = Vec::with_capacity(self.colors.len());
            for (l0, chunk) in x.chunks_mut(len).enumerate() {
                if self.colors[l0] == color {
                    writers.push((l0, chunk));
                    readers.push(None);
                } else {
                    let r: &[f64] = chunk;
                    readers.push(Some(r));
                }
            }
            let sums: Vec<Sums> = writers
                .into_par_iter()
                .map(|(l0, chunk)| self.slice_sweep(l0, chunk, &readers, omega))
                .collect();
            total = sums.into_iter().fold(total, Sums::add);
        }
        total
    }

    /// `Σ_j |inflow_j − exit_j x_j|`, `Σ_j exit_j x_j` and `Σ_j x_j` at `x`.
    pub(crate) fn residual(&self, x: &[f64]) -> Sums {
        let len = self.slice_len();
        let readers: Vec<Option<&[f64]>> = x.chunks(len).map(Some).collect();
        let sums: Vec<Sums> = (0..readers.len())
            .into_par_iter()
            .map(|l0| self.slice_residual(l0, &readers))
            .collect();
        sums.into_iter().fold(Sums::default(), Sums::add)
    }

    /// The outer local states of row `r` of slice `l0` into `locals`.
    fn row_locals(&self, l0: usize, r: usize, locals: &mut [u32]) {
        if self.desc.levels() >= 2 {
            locals[0] = l0 as u32;
        }
        let mut rem = r;
        for lev in (1..self.inner).rev() {
            let s = self.desc.sizes[lev];
            locals[lev] = (rem % s) as u32;
            rem /= s;
        }
    }

    fn slice_sweep(&self, l0: usize, own: &mut [f64], readers: &[Option<&[f64]>], omega: f64) -> Sums {
        let n = self.n;
        let base = l0 * self.slice_len();
        let mut sc = Scratch::new(self.desc.levels(), n, self.inrow.len());
        let mut sums = Sums::default();
        for r in 0..own.len() / n {
            self.row_locals(l0, r, &mut sc.locals);
            let start = r * n;
            self.gather(base + start, &*own, base, readers, &mut sc);
            sc.inrow_enabled = self.inrow_factors(&sc.locals, &mut sc.inrow);
            let row = &mut own[start..start + n];
            let s = if self.kinds.is_none() && sc.inrow_enabled == 0 {
                self.update_plain(row, &mut sc, omega)
            } else {
                self.update_general(row, base + start, &sc, omega)
            };
            sums = sums.add(s);
        }
        sums
    }

    /// The in-row Gauss–Seidel update of a row whose in-row events are all
    /// in the row matrix (no classes): the hot loop. The sequential part
    /// reads the row matrix and multiplies by the reciprocal exit rate
    /// (computed in a vectorised pass before); `acc` then holds each
    /// state's imbalance, summed afterwards in another vectorised pass.
    fn update_plain(&self, row: &mut [f64], sc: &mut Scratch, omega: f64) -> Sums {
        let n = row.len();
        let (in_off, in_ip, in_g) = (&self.in_off[..=n], &self.in_ip[..], &self.in_g[..]);
        let (acc, exit, inv) = (&mut sc.acc[..n], &sc.exit[..n], &mut sc.inv[..n]);
        for (i, &d) in inv.iter_mut().zip(exit) {
            *i = 1.0 / d;
        }
        // `old + ω (new − old)` is not `new` to the last bit at ω = 1: two
        // loops, so that Gauss–Seidel is exactly Gauss–Seidel.
        if omega == 1.0 {
            for c in 0..n {
                let mut v = acc[c];
                let (a, b) = (in_off[c] as usize, in_off[c + 1] as usize);
                for (&g, &ip) in in_g[a..b].iter().zip(&in_ip[a..b]) {
                    v += g * row[ip as usize];
                }
                let old = row[c];
                row[c] = v * inv[c];
                acc[c] = v - exit[c] * old;
            }
        } else {
            for c in 0..n {
                let mut v = acc[c];
                let (a, b) = (in_off[c] as usize, in_off[c + 1] as usize);
                for (&g, &ip) in in_g[a..b].iter().zip(&in_ip[a..b]) {
                    v += g * row[ip as usize];
                }
                let old = row[c];
                row[c] = old + omega * (v * inv[c] - old);
                acc[c] = v - exit[c] * old;
            }
        }
        let (imbalance, flow, total, min) = row_sums(acc, exit, row);
        Sums {
            imbalance,
            flow,
            total,
            min,
        }
    }

    /// The in-row update with classes, conditioned or functional events.
    fn update_general(&self, row: &mut [f64], row_start: usize, sc: &Scratch, omega: f64) -> Sums {
        let mut sums = Sums::default();
        for c in 0..row.len() {
            let Some(d) = self.exit_of(sc.exit[c], row_start + c) else {
                continue;
            };
            let v = sc.acc[c] + self.inrow_inflow(c, &*row, row_start, &sc.inrow);
            let old = row[c];
            sums.imbalance += (v - d * old).abs();
            let new = v / d;
            let x = if omega == 1.0 {
                new
            } else {
                old + omega * (new - old)
            };
            row[c] = x;
            sums.flow += d * x;
            sums.total += x;
            sums.min = sums.min.min(x);
        }
        sums
    }

    fn slice_residual(&self, l0: usize, readers: &[Option<&[f64]>]) -> Sums {
        let n = self.n;
        let base = l0 * self.slice_len();
        let own = readers[l0].unwrap_or(&[]);
        let mut sc = Scratch::new(self.desc.levels(), n, self.inrow.len());
        let mut sums = Sums::default();
        for r in 0..own.len() / n {
            self.row_locals(l0, r, &mut sc.locals);
            let start = r * n;
            self.gather(base + start, own, base, readers, &mut sc);
            sc.inrow_enabled = self.inrow_factors(&sc.locals, &mut sc.inrow);
            let row = &own[start..start + n];
            for c in 0..n {
                let Some(d) = self.exit_of(sc.exit[c], base + start + c) else {
                    continue;
                };
                let v = sc.acc[c] + self.inrow_inflow(c, row, base + start, &sc.inrow);
                sums.imbalance += (v - d * row[c]).abs();
                sums.flow += d * row[c];
                sums.total += row[c];
            }
        }
        sums
    }

    /// The exit rate of state `i` from the summed rates `e`: 1 for a
    /// vanishing state, `None` for an unreachable one.
    #[inline]
    fn exit_of(&self, e: f64, i: usize) -> Option<f64> {
        match self.kinds {
            None => Some(e),
            Some(k) => match k.class[i] {
                UNREACHABLE => None,
                TANGIBLE => Some(e),
                _ => Some(1.0),
            },
        }
    }

    /// The outer factors at this row of the in-row events (`None` where
    /// disabled), and how many are enabled.
    fn inrow_factors(&self, locals: &[u32], out: &mut [Option<(f64, u32)>]) -> usize {
        let mut enabled = 0;
        for (o, &b) in out.iter_mut().zip(&self.inrow) {
            *o = self.outer_factor(&self.events[b], locals);
            enabled += usize::from(o.is_some());
        }
        enabled
    }

    /// Inflow into inner state `c` of the row from the row itself.
    #[inline]
    fn inrow_inflow(&self, c: usize, row: &[f64], row_start: usize, inrow: &[Option<(f64, u32)>]) -> f64 {
        let mut v = 0.0;
        let (a, b) = (self.in_off[c] as usize, self.in_off[c + 1] as usize);
        for k in a..b {
            v += self.in_g[k] * row[self.in_ip[k] as usize];
        }
        let (a, b) = (self.inrow_off[c] as usize, self.inrow_off[c + 1] as usize);
        for &(k, ip, g) in &self.inrow_in[a..b] {
            let Some((f, deg)) = inrow[k as usize] else {
                continue;
            };
            let ev = &self.events[self.inrow[k as usize]];
            let ip = ip as usize;
            let rate = match ev.min_cap {
                Some(cap) => ev.rate * f64::from(deg.min(ev.inner_degree[ip]).min(cap)),
                None => f * g,
            };
            v += rate * row[ip] * self.class_at(ev, row_start + ip);
        }
        v
    }

    /// Exit rates and the inflow from other rows of the row at global index
    /// `row_start` whose outer local states are `sc.locals`, into `sc.acc`
    /// and `sc.exit`.
    fn gather(
        &self,
        row_start: usize,
        own: &[f64],
        own_base: usize,
        readers: &[Option<&[f64]>],
        sc: &mut Scratch,
    ) {
        sc.exit.copy_from_slice(&self.inner_exit);
        sc.pred.copy_from_slice(&sc.locals);
        let mut scalar_exit = 0.0;
        // Plain sources (a whole row times a number) are summed in one pass
        // at the end; the others are added as they come.
        let mut plain: Vec<(f64, &[f64])> = Vec::with_capacity(self.gathered.len());
        let mut others: Vec<(usize, Source<'_>)> = Vec::new();
        for &b in &self.gathered {
            let ev = &self.events[b];
            if let Some((f, deg)) = self.outer_factor(ev, &sc.locals) {
                self.add_exit(ev, f, deg, &mut scalar_exit, &mut sc.exit, row_start);
            }
            if ev.moves_outer {
                if let Some(src) =
                    self.source(ev, &sc.locals, &mut sc.pred, row_start, own, own_base, readers)
                {
                    if ev.inner.is_none() && self.kinds.is_none() {
                        plain.push((src.factor * ev.rate, src.values));
                    } else {
                        others.push((b, src));
                    }
                }
            }
        }
        fused_sum(&mut sc.acc, &plain);
        for (b, src) in &others {
            self.add_inflow(&self.events[*b], src, &mut sc.acc);
        }
        if scalar_exit != 0.0 {
            sc.exit.iter_mut().for_each(|v| *v += scalar_exit);
        }
    }

    /// The source row of a cross event for the row at `row_start`, if the
    /// row's outer states have predecessors under it.
    #[allow(clippy::too_many_arguments)]
    fn source<'s>(
        &self,
        ev: &Bound,
        locals: &[u32],
        pred: &mut [u32],
        row_start: usize,
        own: &'s [f64],
        own_base: usize,
        readers: &[Option<&'s [f64]>],
    ) -> Option<Source<'s>> {
        let e = &self.desc.events[ev.event];
        let mut start = row_start as i64;
        let mut ok = true;
        for &m in &ev.outer {
            let map = &e.maps[m];
            let p = map.pred[locals[map.level] as usize];
            if p == NONE {
                ok = false;
                break;
            }
            pred[map.level] = p;
            start += (i64::from(p) - i64::from(locals[map.level])) * self.desc.strides[map.level] as i64;
        }
        let found = if ok { self.outer_factor(ev, pred) } else { None };
        for &m in &ev.outer {
            let lev = e.maps[m].level;
            pred[lev] = locals[lev];
        }
        let (factor, degree) = found?;
        let start = start as usize;
        let values = if ev.moves_level0 {
            let p0 = e
                .maps
                .iter()
                .find(|m| m.level == 0)
                .map(|m| m.pred[locals[0] as usize])?;
            let slice = readers[p0 as usize]?;
            let off = start - p0 as usize * self.slice_len();
            &slice[off..off + self.n]
        } else {
            &own[start - own_base..start - own_base + self.n]
        };
        Some(Source {
            values,
            start,
            factor,
            degree,
        })
    }

    /// The event's outer factor at outer local states `l` (`None` if not
    /// enabled there), and the outer levels' minimum degree.
    #[inline]
    fn outer_factor(&self, ev: &Bound, l: &[u32]) -> Option<(f64, u32)> {
        let e = &self.desc.events[ev.event];
        let mut deg = u32::MAX;
        for &m in &ev.outer {
            let map = &e.maps[m];
            let s = l[map.level] as usize;
            if map.succ[s] == NONE {
                return None;
            }
            deg = deg.min(map.degree[s]);
        }
        let f = ev.outer_local_cap.map_or(1.0, |cap| f64::from(deg.min(cap)));
        Some((f, deg))
    }

    #[inline]
    fn class_at(&self, ev: &Bound, i: usize) -> f64 {
        match self.kinds {
            None => 1.0,
            Some(k) => ev.class_factor[k.class[i] as usize],
        }
    }

    #[inline]
    fn add_exit(&self, ev: &Bound, f: f64, deg: u32, scalar: &mut f64, exit: &mut [f64], row_start: usize) {
        let n = self.n;
        match (ev.inner.is_some(), ev.min_cap, self.kinds) {
            (false, _, None) => *scalar += f * ev.rate,
            (false, _, Some(k)) => {
                let v = f * ev.rate;
                for (x, &cl) in exit.iter_mut().zip(&k.class[row_start..row_start + n]) {
                    *x += v * ev.class_factor[cl as usize];
                }
            }
            (true, Some(cap), _) => {
                for &c in &ev.out_at {
                    let c = c as usize;
                    let d = deg.min(ev.inner_degree[c]).min(cap);
                    exit[c] += ev.rate * f64::from(d) * self.class_at(ev, row_start + c);
                }
            }
            (true, None, None) => {
                for (x, &g) in exit.iter_mut().zip(&ev.g_out) {
                    *x += f * g;
                }
            }
            (true, None, Some(k)) => {
                // Only where the event is enabled: adding `f · 0 · …` would
                // change no bit.
                let cls = &k.class[row_start..row_start + n];
                for &c in &ev.out_at {
                    let c = c as usize;
                    exit[c] += f * ev.g_out[c] * ev.class_factor[cls[c] as usize];
                }
            }
        }
    }

    /// `acc += inflow` from a source row.
    #[inline]
    fn add_inflow(&self, ev: &Bound, src: &Source<'_>, acc: &mut [f64]) {
        let n = self.n;
        let (f, x) = (src.factor, src.values);
        match (ev.inner.is_some(), ev.min_cap, self.kinds) {
            (false, _, None) => {
                let s = f * ev.rate;
                for (a, &v) in acc.iter_mut().zip(x) {
                    *a += s * v;
                }
            }
            (false, _, Some(k)) => {
                let s = f * ev.rate;
                let cls = &k.class[src.start..src.start + n];
                for ((a, &v), &cl) in acc.iter_mut().zip(x).zip(cls) {
                    *a += s * v * ev.class_factor[cl as usize];
                }
            }
            (true, Some(cap), _) => {
                for &c in &ev.in_at {
                    let c = c as usize;
                    let ip = ev.ip[c] as usize;
                    let d = src.degree.min(ev.inner_degree[ip]).min(cap);
                    acc[c] += ev.rate * f64::from(d) * x[ip] * self.class_at(ev, src.start + ip);
                }
            }
            (true, None, None) => {
                for ((a, &g), &ip) in acc.iter_mut().zip(&ev.g_in).zip(&ev.ip) {
                    *a += f * g * x[ip as usize];
                }
            }
            (true, None, Some(k)) => {
                // Only where the event leads: `f · 0 · x` adds a zero.
                for &c in &ev.in_at {
                    let (c, ip) = (c as usize, ev.ip[c as usize] as usize);
                    acc[c] += f * ev.g_in[c] * x[ip] * ev.class_factor[k.class[src.start + ip] as usize];
                }
            }
        }
    }
}

/// Event `ei` of `desc` bound to its rate.
fn bind(desc: &Descriptor, kinds: Option<&Kinds>, ei: usize, rates: &[f64]) -> Bound {
    let e = &desc.events[ei];
    let inner = desc.levels() - 1;
    let rate = if e.immediate.is_some() {
        1.0
    } else {
        rates[e.transition as usize]
    };
    let outer: Vec<usize> = (0..e.maps.len()).filter(|&m| e.maps[m].level < inner).collect();
    let inner_map = (0..e.maps.len()).find(|&m| e.maps[m].level == inner);
    let moves_level0 = desc.levels() > 1 && e.maps.iter().any(|m| m.level == 0 && m.moves);
    let moves_outer = outer.iter().any(|&m| e.maps[m].moves);
    let (inner_cap, outer_local_cap, min_cap) = match e.factor {
        Factor::One => (None, None, None),
        Factor::Local { map, cap } if Some(map) == inner_map => (Some(cap), None, None),
        Factor::Local { cap, .. } => (None, Some(cap), None),
        Factor::Min { cap } => (None, None, Some(cap)),
    };
    let (mut ip, mut g_in, mut g_out, mut inner_degree) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    if let Some(im) = inner_map {
        let m = &e.maps[im];
        let local = |l: usize| inner_cap.map_or(1.0, |cap| f64::from(m.degree[l].min(cap)));
        ip = m.pred.iter().map(|&p| if p == NONE { 0 } else { p }).collect();
        g_in = m
            .pred
            .iter()
            .map(|&p| if p == NONE { 0.0 } else { rate * local(p as usize) })
            .collect();
        g_out = m
            .succ
            .iter()
            .enumerate()
            .map(|(l, &s)| if s == NONE { 0.0 } else { rate * local(l) })
            .collect();
        if min_cap.is_some() {
            inner_degree = m.degree.clone();
        }
    }
    let class_factor = kinds.map_or_else(Vec::new, |kd| {
        kd.classes
            .iter()
            .enumerate()
            .map(|(c, cl)| match e.immediate {
                _ if c == UNREACHABLE as usize => 0.0,
                None if cl.priority == 0 => 1.0,
                None => 0.0,
                Some((prio, w)) if cl.priority == prio => w / cl.weight_sum,
                Some(_) => 0.0,
            })
            .collect()
    });
    let nonzero = |g: &[f64]| -> Vec<u32> { (0..g.len() as u32).filter(|&c| g[c as usize] != 0.0).collect() };
    let (in_at, out_at) = (nonzero(&g_in), nonzero(&g_out));
    let aggregated = kinds.is_none() && outer.is_empty() && min_cap.is_none() && inner_map.is_some();
    Bound {
        event: ei,
        outer,
        inner: inner_map,
        moves_level0,
        moves_outer,
        aggregated,
        rate,
        ip,
        g_in,
        g_out,
        in_at,
        out_at,
        inner_degree,
        min_cap,
        outer_local_cap,
        class_factor,
    }
}

/// `(Σ |a_i|, Σ e_i x_i, Σ x_i, min x_i)` in one pass, on four lanes (a
/// fixed order: the same bits every time).
#[inline]
fn row_sums(a: &[f64], e: &[f64], x: &[f64]) -> (f64, f64, f64, f64) {
    let (mut s, mut f, mut t) = ([0.0f64; 4], [0.0f64; 4], [0.0f64; 4]);
    let mut m = f64::INFINITY;
    let n = a.len().min(e.len()).min(x.len());
    let (ca, ce, cx) = (
        a[..n].chunks_exact(4),
        e[..n].chunks_exact(4),
        x[..n].chunks_exact(4),
    );
    let (ra, re, rx) = (ca.remainder(), ce.remainder(), cx.remainder());
    for ((a, e), x) in ca.zip(ce).zip(cx) {
        for k in 0..4 {
            s[k] += a[k].abs();
            f[k] += e[k] * x[k];
            t[k] += x[k];
            m = m.min(x[k]);
        }
    }
    for k in 0..ra.len() {
        s[k] += ra[k].abs();
        f[k] += re[k] * rx[k];
        t[k] += rx[k];
        m = m.min(rx[k]);
    }
    let sum = |v: [f64; 4]| (v[0] + v[1]) + (v[2] + v[3]);
    (sum(s), sum(f), sum(t), m)
}

/// `acc = Σ_j s_j · x_j` over the plain sources `(s_j, x_j)` (rows of the
/// same length), four sources per pass over `acc`.
fn fused_sum(acc: &mut [f64], sources: &[(f64, &[f64])]) {
    let n = acc.len();
    let mut groups = sources.chunks(4);
    match groups.next() {
        None => acc.fill(0.0),
        Some(first) => {
            acc.fill(0.0);
            add_group(acc, first, n);
        }
    }
    for g in groups {
        add_group(acc, g, n);
    }
}

/// `acc += Σ_j s_j · x_j` for up to four sources.
#[inline]
fn add_group(acc: &mut [f64], g: &[(f64, &[f64])], n: usize) {
    match g {
        [(a, xa), (b, xb), (c, xc), (d, xd)] => {
            let (xa, xb, xc, xd) = (&xa[..n], &xb[..n], &xc[..n], &xd[..n]);
            for i in 0..n {
                acc[i] += (a * xa[i] + b * xb[i]) + (c * xc[i] + d * xd[i]);
            }
        }
        [(a, xa), (b, xb), (c, xc)] => {
            let (xa, xb, xc) = (&xa[..n], &xb[..n], &xc[..n]);
            for i in 0..n {
                acc[i] += (a * xa[i] + b * xb[i]) + c * xc[i];
            }
        }
        [(a, xa), (b, xb)] => {
            let (xa, xb) = (&xa[..n], &xb[..n]);
            for i in 0..n {
                acc[i] += a * xa[i] + b * xb[i];
            }
        }
        [(a, xa)] => {
            let xa = &xa[..n];
            for i in 0..n {
                acc[i] += a * xa[i];
            }
        }
        _ => {}
    }
}
