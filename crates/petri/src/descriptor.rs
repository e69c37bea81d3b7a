//! The Kronecker descriptor of a GSPN over a product structure: for every
//! transition and every component it touches, the local successor and
//! predecessor of each local state and the local part of the rate factor.
//!
//! With components `1..K` of local spaces `S_k`, a global state is the tuple
//! `(l_1, …, l_K)`, numbered `Σ_k l_k · stride_k` (the last component
//! varies fastest). A transition `t` fires in a state iff every component
//! it touches enables it locally (inputs, inhibitors, capacities of the
//! component's places), and leads to the state whose touched components
//! moved to their local successors: `W_t^(k)` is the 0/1 matrix of the map
//! `l ↦ succ_t^k(l)`, an injection because firing adds a fixed vector. The
//! rate factor (server semantics) is
//!
//! * 1 for single servers and immediate transitions;
//! * a product of local factors when every input place of `t` lies in one
//!   component (`min(degree, k)` or the degree, a function of that
//!   component's local state);
//! * otherwise the *functional* factor `min(min_k degree_k(l_k), k)` over
//!   the components holding inputs (the enabling degree is a minimum over
//!   input places, which does not factor as a product).
//!
//! A transition that changes no place is a self-loop: it adds to its
//! throughput, not to the chain (as in [`crate::CompiledGspn`]).
//! Building the maps costs `O(Σ_k |S_k| · log |S_k|)` per transition.

use crate::error::{Error, Result};
use crate::gspn::{Gspn, Timing};
use crate::net::{Servers, TransitionId};
use crate::structure::Structure;

/// No local state (disabled, or no predecessor).
pub(crate) const NONE: u32 = u32::MAX;

/// One transition's effect on one component.
#[derive(Debug, Clone)]
pub(crate) struct LocalMap {
    /// The component (level).
    pub level: usize,
    /// Local successor of each local state ([`NONE`]: not enabled there).
    pub succ: Vec<u32>,
    /// Local predecessor of each local state ([`NONE`]: none).
    pub pred: Vec<u32>,
    /// Enabling degree from the input places in this component, at each
    /// local state (`u32::MAX` when none of the inputs is here).
    pub degree: Vec<u32>,
    /// Whether some local state moves (not only a condition).
    pub moves: bool,
}

/// How an event's rate factor is made up.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Factor {
    /// 1 wherever enabled.
    One,
    /// The local factor of one component: `min(degree, cap)` of
    /// `levels[i]`.
    Local {
        /// Index into the event's `maps`.
        map: usize,
        /// Servers (`u32::MAX` for infinite).
        cap: u32,
    },
    /// `min(min over the maps of degree, cap)`.
    Min {
        /// Servers (`u32::MAX` for infinite).
        cap: u32,
    },
}

/// One transition of the descriptor.
#[derive(Debug, Clone)]
pub(crate) struct Event {
    /// The transition.
    pub transition: u32,
    /// `Some((priority, weight))` for an immediate transition.
    pub immediate: Option<(u32, f64)>,
    /// Its local maps, by level, ascending.
    pub maps: Vec<LocalMap>,
    /// How its rate factor is computed.
    pub factor: Factor,
    /// Whether it changes no place (a self-loop wherever enabled).
    pub self_loop: bool,
}

impl Event {
    /// The rate factor from local states `l` (one per level of the
    /// structure), given that the event is enabled there.
    #[inline]
    pub fn factor_at(&self, locals: &[u32]) -> f64 {
        match self.factor {
            Factor::One => 1.0,
            Factor::Local { map, cap } => {
                let m = &self.maps[map];
                f64::from(m.degree[locals[m.level] as usize].min(cap))
            }
            Factor::Min { cap } => {
                let d = self
                    .maps
                    .iter()
                    .map(|m| m.degree[locals[m.level] as usize])
                    .min()
                    .unwrap_or(1);
                f64::from(d.min(cap))
            }
        }
    }

    /// Whether enabled in local states `l`.
    #[inline]
    pub fn enabled_at(&self, locals: &[u32]) -> bool {
        self.maps.iter().all(|m| m.succ[locals[m.level] as usize] != NONE)
    }
}

/// The descriptor: levels and events.
#[derive(Debug, Clone)]
pub(crate) struct Descriptor {
    /// Local states per level.
    pub sizes: Vec<usize>,
    /// Index stride per level.
    pub strides: Vec<u64>,
    /// Product of the sizes: the number of global states.
    pub states: u64,
    /// The events (transitions that can fire; dead ones, disabled in every
    /// local state of some component, are left out).
    pub events: Vec<Event>,
}

impl Descriptor {
    /// Renumbers each component's local states in breadth-first order from
    /// the initial marking's local state over the events' local moves
    /// (states never met keep their relative order, after the others), and
    /// builds the descriptor over the renumbered structure.
    pub(crate) fn with_flow_order(gspn: &Gspn, structure: &mut Structure) -> Result<Descriptor> {
        let first = Self::build(gspn, structure)?;
        let m0 = structure
            .locals_of(gspn.initial_marking())
            .ok_or_else(|| Error::Invalid("internal: the initial marking is not a product state".into()))?;
        for (k, comp) in structure.components_mut().iter_mut().enumerate() {
            let n = comp.len();
            let mut adj: Vec<Vec<u32>> = vec![Vec::new(); n];
            for e in &first.events {
                for m in e.maps.iter().filter(|m| m.level == k && m.moves) {
                    for (l, &s) in m.succ.iter().enumerate() {
                        if s != NONE && s as usize != l {
                            adj[l].push(s);
                        }
                    }
                }
            }
            let mut order = Vec::with_capacity(n);
            let mut seen = vec![false; n];
            seen[m0[k]] = true;
            order.push(m0[k] as u32);
            let mut head = 0;
            while head < order.len() {
                let l = order[head] as usize;
                head += 1;
                for &s in &adj[l] {
                    if !std::mem::replace(&mut seen[s as usize], true) {
                        order.push(s);
                    }
                }
            }
            order.extend((0..n as u32).filter(|&l| !seen[l as usize]));
            comp.reorder(&order);
        }
        Self::build(gspn, structure)
    }

    /// Builds the local maps of every transition over `structure`.
    /// Fails if a transition leaves a component's local space while every
    /// component enables it somewhere (the structure would be wrong).
    fn build(gspn: &Gspn, structure: &Structure) -> Result<Descriptor> {
        let comps = structure.components();
        let sizes: Vec<usize> = comps.iter().map(|c| c.len()).collect();
        let mut strides = vec![1u64; sizes.len()];
        for k in (0..sizes.len().saturating_sub(1)).rev() {
            strides[k] = strides[k + 1] * sizes[k + 1] as u64;
        }
        let states = sizes.iter().map(|&s| s as u64).product();
        let pos = structure.place_positions(gspn.num_places());
        let mut events = Vec::new();
        for t in 0..gspn.num_transitions() {
            if let Some(e) = event(gspn, structure, &pos, TransitionId(t as u32))? {
                events.push(e);
            }
        }
        Ok(Descriptor {
            sizes,
            strides,
            states,
            events,
        })
    }

    /// Number of levels.
    pub(crate) fn levels(&self) -> usize {
        self.sizes.len()
    }

    /// The local states of global state `i`.
    pub(crate) fn locals(&self, mut i: u64, out: &mut [u32]) {
        for k in (0..self.levels()).rev() {
            let s = self.sizes[k] as u64;
            out[k] = (i % s) as u32;
            i /= s;
        }
    }

    /// The global index of local states `l`.
    pub(crate) fn index(&self, locals: &[u32]) -> u64 {
        locals
            .iter()
            .zip(&self.strides)
            .map(|(&l, &s)| u64::from(l) * s)
            .sum()
    }

    /// Heap bytes of the local maps.
    pub(crate) fn heap_bytes(&self) -> usize {
        self.events
            .iter()
            .flat_map(|e| &e.maps)
            .map(|m| (m.succ.capacity() + m.pred.capacity() + m.degree.capacity()) * 4)
            .sum()
    }
}

/// What `t` asks of and does to one place of a component.
#[derive(Debug, Clone, Copy)]
struct Part {
    /// Position of the place in its component.
    position: usize,
    /// Input multiplicity (0 if none).
    need: u32,
    /// Inhibitor multiplicity (`u32::MAX` if none).
    inhibit: u32,
    /// Change of the count.
    delta: i64,
    /// Capacity for a growing count (`u32::MAX` if none).
    capacity: u32,
}

/// `t`'s parts per component, components ascending.
fn parts_by_level(gspn: &Gspn, pos: &[(usize, usize)], t: TransitionId) -> Vec<(usize, Vec<Part>)> {
    let mut by: std::collections::BTreeMap<(usize, usize), Part> = std::collections::BTreeMap::new();
    fn at<'a>(
        by: &'a mut std::collections::BTreeMap<(usize, usize), Part>,
        pos: &[(usize, usize)],
        p: u32,
    ) -> &'a mut Part {
        let (k, i) = pos[p as usize];
        by.entry((k, i)).or_insert(Part {
            position: i,
            need: 0,
            inhibit: u32::MAX,
            delta: 0,
            capacity: u32::MAX,
        })
    }
    for &(p, m) in gspn.inputs(t) {
        at(&mut by, pos, p).need = m;
    }
    for &(p, m) in gspn.inhibitors(t) {
        at(&mut by, pos, p).inhibit = m;
    }
    for &(p, d) in gspn.delta(t) {
        let part = at(&mut by, pos, p);
        part.delta = d;
        if d > 0 {
            if let Some(c) = gspn.capacities()[p as usize] {
                part.capacity = c;
            }
        }
    }
    let mut levels: Vec<(usize, Vec<Part>)> = Vec::new();
    for ((k, _), part) in by {
        match levels.last_mut() {
            Some((l, v)) if *l == k => v.push(part),
            _ => levels.push((k, vec![part])),
        }
    }
    levels
}

/// The local map of `parts` on component `comp` (level `k`), and whether
/// some enabled local state's successor is not a local state.
fn local_map(comp: &crate::structure::Component, k: usize, parts: &[Part]) -> (LocalMap, bool) {
    let n = comp.len();
    let (mut succ, mut pred, mut degree) = (vec![NONE; n], vec![NONE; n], vec![u32::MAX; n]);
    let (mut moves, mut leaves) = (false, false);
    let mut counts: Vec<u32> = Vec::with_capacity(comp.places.len());
    'states: for l in 0..n {
        let st = comp.state(l);
        // The parts decide first, from the counts they read: the state is
        // copied only where the transition is enabled (a component of many
        // places, most states disabled, is then not copied state by state).
        let mut deg = u32::MAX;
        for part in parts {
            let v = st[part.position];
            if v < part.need || v >= part.inhibit {
                continue 'states;
            }
            if let Some(d) = v.checked_div(part.need) {
                deg = deg.min(d);
            }
            let w = i64::from(v) + part.delta;
            if w < 0 || w > i64::from(part.capacity) {
                continue 'states;
            }
        }
        counts.clear();
        counts.extend_from_slice(st);
        for part in parts {
            counts[part.position] = (i64::from(st[part.position]) + part.delta) as u32;
        }
        match comp.rank(&counts) {
            Some(m) => {
                succ[l] = m as u32;
                pred[m] = l as u32;
                degree[l] = deg;
                moves |= m != l;
            }
            None => leaves = true,
        }
    }
    (
        LocalMap {
            level: k,
            succ,
            pred,
            degree,
            moves,
        },
        leaves,
    )
}

/// Transition `t` as an event, `None` if it is dead (some component never
/// enables it). A successor outside a component's local space while every
/// component enables `t` somewhere would contradict the exact product: an
/// error, never a silently dropped flow.
fn event(
    gspn: &Gspn,
    structure: &Structure,
    pos: &[(usize, usize)],
    t: TransitionId,
) -> Result<Option<Event>> {
    let comps = structure.components();
    let levels = parts_by_level(gspn, pos, t);
    let mut maps = Vec::with_capacity(levels.len());
    let mut leaves = None;
    for (k, parts) in &levels {
        let (map, left) = local_map(&comps[*k], *k, parts);
        if map.succ.iter().all(|&s| s == NONE) {
            return Ok(None);
        }
        if left && leaves.is_none() {
            leaves = Some(*k);
        }
        maps.push(map);
    }
    if let Some(k) = leaves {
        return Err(Error::Invalid(format!(
            "internal: transition `{}` leaves the local states of component {} although every component enables it",
            gspn.transition_names()[t.index()],
            k + 1
        )));
    }
    let inputs_at: Vec<usize> = levels
        .iter()
        .enumerate()
        .filter(|(_, (_, parts))| parts.iter().any(|p| p.need > 0))
        .map(|(i, _)| i)
        .collect();
    let (immediate, cap) = match gspn.timing(t) {
        Timing::Immediate { priority, weight } => (Some((priority, weight)), 1),
        Timing::Timed {
            servers: Servers::Single,
        } => (None, 1),
        Timing::Timed {
            servers: Servers::K(k),
        } => (None, k),
        Timing::Timed {
            servers: Servers::Infinite,
        } => (None, u32::MAX),
    };
    let factor = match inputs_at[..] {
        _ if cap == 1 => Factor::One,
        [] => Factor::One,
        [map] => Factor::Local { map, cap },
        _ => Factor::Min { cap },
    };
    let self_loop = !maps.iter().any(|m| m.moves);
    Ok(Some(Event {
        transition: t.0,
        immediate,
        maps,
        factor,
        self_loop,
    }))
}
