//! Reachability graph (RG) of a GSPN, tangible and vanishing markings alike.
//!
//! Breadth-first from `M0`. Markings are numbered in discovery order, so the
//! store itself is the BFS queue. For each marking the transitions that may
//! fire under GSPN semantics ([`Gspn::firable`]) give its edges; each edge
//! carries a coefficient: the probability `w_t / Σw` of an immediate
//! transition in a vanishing marking, or the server factor
//! (`min(degree, k)`) of a timed transition in a tangible one. Rates are not
//! involved, so the same graph serves every rate binding.
//!
//! Successors are computed on the packed marking: the transition's token
//! changes are added to the bit fields directly, widening a field first if a
//! count would not fit (see the `marking` module). Cost: `O(|T|)` enabling tests
//! per marking plus one hash probe per edge. Memory: the packed marking (often
//! 8 bytes) + ~5 bytes of hash table per marking, 8 bytes per edge (+8 when
//! some coefficient differs from 1).

use std::time::Instant;

use crate::error::{Error, Result};
use crate::gspn::{Gspn, MarkingKind};
use crate::marking::{Layout, MarkingStore, bits_for};
use crate::net::TransitionId;
use crate::scc::Successors;

/// Index of a marking in a [`ReachabilityGraph`] (0 is the initial marking).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, serde::Serialize)]
pub struct MarkingId(pub u32);

/// Options of state-space generation.
#[derive(Debug, Clone)]
pub struct ExploreParams {
    /// Stop with [`Error::StateLimit`] beyond this many markings (tangible and
    /// vanishing). Default 10,000,000 (a few GiB at most for typical nets).
    pub max_states: usize,
}

impl Default for ExploreParams {
    fn default() -> Self {
        ExploreParams {
            max_states: 10_000_000,
        }
    }
}

/// Figures about a generation run.
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct ExploreStats {
    /// Markings found.
    pub markings: usize,
    /// Of which tangible.
    pub tangible: usize,
    /// Of which vanishing.
    pub vanishing: usize,
    /// Edges.
    pub edges: usize,
    /// Wall-clock seconds.
    pub seconds: f64,
    /// 64-bit words per packed marking.
    pub words_per_marking: usize,
    /// Bytes of marking storage (packed markings + hash table) per marking.
    pub bytes_per_marking: f64,
    /// Times the packing had to be widened.
    pub relayouts: usize,
}

/// The reachability graph.
#[derive(Debug, Clone)]
pub struct ReachabilityGraph {
    pub(crate) store: MarkingStore,
    pub(crate) vanishing: Vec<bool>,
    pub(crate) offsets: Vec<u64>,
    pub(crate) targets: Vec<u32>,
    pub(crate) transitions: Vec<u32>,
    pub(crate) coeffs: Option<Vec<f64>>,
    pub(crate) max_tokens: Vec<u32>,
    pub(crate) stats: ExploreStats,
}

/// An edge of the reachability graph.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Edge {
    /// Target marking.
    pub target: MarkingId,
    /// Transition fired.
    pub transition: TransitionId,
    /// Probability (immediate) or server factor (timed).
    pub coeff: f64,
}

impl ReachabilityGraph {
    /// Generates the reachability graph of `gspn` from its initial marking.
    pub fn explore(gspn: &Gspn, params: &ExploreParams) -> Result<ReachabilityGraph> {
        let start = Instant::now();
        let np = gspn.num_places();
        let m0 = gspn.initial_marking().to_vec();
        let mut store = MarkingStore::new(Layout::for_marking(&m0, 1));
        let mut key = vec![0u64; store.layout().words()];
        store.layout().encode(&m0, &mut key);
        store.insert(&key);
        drop(key);

        let mut vanishing = Vec::new();
        let mut offsets = vec![0u64];
        let mut targets: Vec<u32> = Vec::new();
        let mut transitions: Vec<u32> = Vec::new();
        let mut coeffs: Option<Vec<f64>> = None;
        let mut max_tokens = m0.clone();
        let mut relayouts = 0;

        let mut cur = vec![0u32; np];
        let mut firable: Vec<TransitionId> = Vec::new();
        // Markings are expanded in batches: the successors of a batch are
        // computed first, their hash slots loaded together (overlapping the
        // cache misses), then inserted in order — the numbering is exactly
        // that of expanding one marking after the other.
        let mut batch = Batch::default();
        let mut i = 0usize;
        while i < store.len() {
            let end = (i + BATCH).min(store.len());
            'build: loop {
                batch.clear();
                let w = store.layout().words();
                for m in i..end {
                    store.decode(m, &mut cur);
                    for (mx, &c) in max_tokens.iter_mut().zip(&cur) {
                        *mx = (*mx).max(c);
                    }
                    let kind = gspn.firable(&cur, &mut firable);
                    batch.vanishing.push(kind == MarkingKind::Vanishing);
                    let total_weight: f64 = if kind == MarkingKind::Vanishing {
                        firable.iter().map(|&t| gspn.weight(t).unwrap_or(1.0)).sum()
                    } else {
                        1.0
                    };
                    for &t in &firable {
                        // Widen fields that the firing would overflow, then
                        // compute the batch again in the new layout.
                        let mut widen: Option<Vec<u8>> = None;
                        for &(p, d) in gspn.delta(t) {
                            if d > 0 {
                                let p = p as usize;
                                let new = u64::from(cur[p]) + d as u64;
                                if new > u64::from(u32::MAX) {
                                    return Err(Error::TokenOverflow {
                                        place: gspn.place_names()[p].clone(),
                                        limit: u64::from(u32::MAX),
                                    });
                                }
                                if new > u64::from(store.layout().max_value(p)) {
                                    let w = widen.get_or_insert_with(|| store.layout().widths().to_vec());
                                    w[p] = (bits_for(new as u32) + 1).min(32);
                                }
                            }
                        }
                        if let Some(w) = widen {
                            store.relayout(Layout::new(w));
                            relayouts += 1;
                            continue 'build;
                        }
                        let at = batch.keys.len();
                        batch.keys.extend_from_slice(store.key(m));
                        for &(p, d) in gspn.delta(t) {
                            store.layout().add(&mut batch.keys[at..at + w], p as usize, d);
                        }
                        let c = if kind == MarkingKind::Vanishing {
                            gspn.weight(t).unwrap_or(1.0) / total_weight
                        } else {
                            gspn.server_factor(t, &cur)
                        };
                        batch.edges.push((t.0, c));
                    }
                    batch.ends.push(batch.edges.len());
                }
                break;
            }
            store.touch(&batch.keys);
            let w = store.layout().words();
            let mut e = 0;
            for (m, (&end_m, &v)) in batch.ends.iter().zip(&batch.vanishing).enumerate() {
                for &(t, c) in &batch.edges[e..end_m] {
                    let (j, new) = store.insert(&batch.keys[e * w..(e + 1) * w]);
                    if new && store.len() > params.max_states {
                        return Err(state_limit(gspn, params.max_states, i + m, &max_tokens));
                    }
                    if c != 1.0 && coeffs.is_none() {
                        coeffs = Some(vec![1.0; targets.len()]);
                    }
                    if let Some(cs) = coeffs.as_mut() {
                        cs.push(c);
                    }
                    targets.push(j);
                    transitions.push(t);
                    e += 1;
                }
                vanishing.push(v);
                offsets.push(targets.len() as u64);
            }
            i = end;
        }
        let n = store.len();
        let nv = vanishing.iter().filter(|&&v| v).count();
        let stats = ExploreStats {
            markings: n,
            tangible: n - nv,
            vanishing: nv,
            edges: targets.len(),
            seconds: start.elapsed().as_secs_f64(),
            words_per_marking: store.layout().words(),
            bytes_per_marking: store.heap_bytes() as f64 / n as f64,
            relayouts,
        };
        Ok(ReachabilityGraph {
            store,
            vanishing,
            offsets,
            targets,
            transitions,
            coeffs,
            max_tokens,
            stats,
        })
    }

    /// Number of markings.
    pub fn num_markings(&self) -> usize {
        self.store.len()
    }

    /// Number of tangible markings.
    pub fn num_tangible(&self) -> usize {
        self.stats.tangible
    }

    /// Number of vanishing markings.
    pub fn num_vanishing(&self) -> usize {
        self.stats.vanishing
    }

    /// Number of edges.
    pub fn num_edges(&self) -> usize {
        self.targets.len()
    }

    /// Generation figures.
    pub fn stats(&self) -> &ExploreStats {
        &self.stats
    }

    /// Whether marking `m` is vanishing.
    pub fn is_vanishing(&self, m: MarkingId) -> bool {
        self.vanishing[m.0 as usize]
    }

    /// The token counts of marking `m`.
    pub fn marking(&self, m: MarkingId) -> Vec<u32> {
        let mut out = vec![0; self.max_tokens.len()];
        self.store.decode(m.0 as usize, &mut out);
        out
    }

    /// Decodes marking `m` into `out`.
    pub fn marking_into(&self, m: MarkingId, out: &mut [u32]) {
        self.store.decode(m.0 as usize, out);
    }

    /// Token count of place index `p` in marking `m`.
    pub fn tokens(&self, m: MarkingId, p: usize) -> u32 {
        self.store.tokens(m.0 as usize, p)
    }

    /// The largest token count of each place over all reachable markings.
    pub fn place_bounds(&self) -> &[u32] {
        &self.max_tokens
    }

    /// The edges leaving `m`.
    pub fn edges(&self, m: MarkingId) -> impl Iterator<Item = Edge> + '_ {
        let (a, b) = self.range(m.0 as usize);
        (a..b).map(move |k| Edge {
            target: MarkingId(self.targets[k]),
            transition: TransitionId(self.transitions[k]),
            coeff: self.coeffs.as_ref().map_or(1.0, |c| c[k]),
        })
    }

    #[inline]
    pub(crate) fn range(&self, i: usize) -> (usize, usize) {
        (self.offsets[i] as usize, self.offsets[i + 1] as usize)
    }

    #[inline]
    pub(crate) fn coeff(&self, k: usize) -> f64 {
        self.coeffs.as_ref().map_or(1.0, |c| c[k])
    }

    /// Markings with no outgoing edge (dead markings, deadlocks).
    pub fn dead_markings(&self) -> Vec<MarkingId> {
        (0..self.num_markings())
            .filter(|&i| self.offsets[i] == self.offsets[i + 1])
            .map(|i| MarkingId(i as u32))
            .collect()
    }
}

impl Successors for ReachabilityGraph {
    fn num_nodes(&self) -> usize {
        self.store.len()
    }

    fn successors(&self, v: u32) -> &[u32] {
        let (a, b) = self.range(v as usize);
        &self.targets[a..b]
    }
}

/// Markings expanded per batch (see [`ReachabilityGraph::explore`]): their
/// ~10 successors each are a few hundred slot loads in flight, which fit the
/// L1 cache.
const BATCH: usize = 32;

/// The successors of a batch of markings, before insertion.
#[derive(Default)]
struct Batch {
    /// Packed successor keys, `words` each.
    keys: Vec<u64>,
    /// `(transition, coefficient)` per successor.
    edges: Vec<(u32, f64)>,
    /// End of each marking's successors in `edges`.
    ends: Vec<usize>,
    /// Whether each marking is vanishing.
    vanishing: Vec<bool>,
}

impl Batch {
    fn clear(&mut self) {
        self.keys.clear();
        self.edges.clear();
        self.ends.clear();
        self.vanishing.clear();
    }
}

fn state_limit(gspn: &Gspn, limit: usize, explored: usize, max_tokens: &[u32]) -> Error {
    let m0 = gspn.initial_marking();
    let mut growing: Vec<(u32, usize)> = max_tokens
        .iter()
        .enumerate()
        .filter(|&(p, &mx)| mx > 2 * m0[p].max(4))
        .map(|(p, &mx)| (mx, p))
        .collect();
    growing.sort_unstable_by(|a, b| b.cmp(a));
    let hint = if growing.is_empty() {
        String::new()
    } else {
        let names: Vec<String> = growing
            .iter()
            .take(3)
            .map(|&(mx, p)| format!("`{}` reached {mx} tokens", gspn.place_names()[p]))
            .collect();
        format!(" — the net may be unbounded: {}", names.join(", "))
    };
    Error::StateLimit {
        limit,
        explored,
        hint,
    }
}
