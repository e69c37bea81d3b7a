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
//! count would not fit (see the `marking` module). The firing rule of a
//! stored marking tests the transitions keyed on its marked places and keeps
//! the enabled ones as a bitset (`gspn::enabling`). Cost: those enabling
//! tests per marking plus one hash probe per edge (see the `marking` module
//! for the table; lookups run in parallel rounds, see
//! [`ReachabilityGraph::explore`]).
//! Memory: the packed marking (often 8 bytes) + 21–43 bytes of hash table per
//! marking (5 for markings wider than a word), 8 bytes per edge (+8 when some
//! coefficient differs from 1). The memory guard
//! ([`ExploreParams::max_memory`]) stops generation before the whole pipeline
//! (generation, compilation, solve) would need more than the limit.
//!
//! On request ([`ExploreParams::skip_forced`]) a vanishing marking with a
//! single firable transition is passed through instead of stored: chains
//! of zero-time hops (a behaviour tree's control flow) then cost one edge.
//! Following such a run evaluates the firing rule of each marking on it
//! from the enabled set of the one before: only the transitions whose
//! enabling reads a place the hop changed are tested again, on the unpacked
//! marking, while the packed key is updated in place for the lookups. Where
//! runs end is remembered by key (hashed once, with the store's hash) and
//! not followed again.

use hashbrown::HashTable;
use std::time::Instant;

use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::gspn::enabling::{EnabledSet, EnablingIndex};
use crate::gspn::{Gspn, MarkingKind};
use crate::interrupt::{Interrupt, Stage};
use crate::marking::{Layout, MarkingStore, bits_for, hash_words, same_key};
use crate::net::{PlaceId, TransitionId};
use crate::scc::Successors;

/// Index of a marking in a [`ReachabilityGraph`] (0 is the initial marking).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, serde::Serialize)]
pub struct MarkingId(pub u32);

/// Options of state-space generation.
#[derive(Debug, Clone)]
pub struct ExploreParams {
    /// Stop with [`Error::StateLimit`] beyond this many markings (tangible and
    /// vanishing). Default: no limit (`usize::MAX`); the memory guard
    /// [`ExploreParams::max_memory`] decides what is too big.
    pub max_states: usize,
    /// Stop with [`Error::MemoryLimit`] as soon as generating, compiling and
    /// solving the markings and edges found so far would need more than this
    /// many bytes (see [`estimated_bytes`]). Default:
    /// [`default_max_memory`], 85 % of the memory available at the time.
    pub max_memory: u64,
    /// Pass through *forced* vanishing markings — those where exactly one
    /// immediate transition can fire — instead of storing them: an edge into
    /// one goes on, in the same firing, to the first marking that is
    /// tangible or offers a choice (at most [`FORCED_HOPS`] hops; a longer
    /// run of forced hops, a timeless loop, is stored as it is). The
    /// tangible markings, their rates and every choice are unchanged, so is
    /// the CTMC; what is lost is what only the skipped markings carried: the
    /// throughputs of the immediate transitions fired in them, and the
    /// markings themselves (their count, their firings in a graph export;
    /// [`ReachabilityGraph::place_bounds`] still counts their tokens).
    /// Default: off (docs/gspn.md, *The pipeline*).
    pub skip_forced: bool,
    /// With [`skip_forced`](Self::skip_forced): places that the memory of
    /// forced hops may leave out. A stretch of forced hops that neither
    /// reads nor changes these places (no transition with an arc on one
    /// fires, and none could become enabled whatever they hold) is
    /// remembered once for every count they hold, and replayed in one step
    /// from any marking that differs from it only there — e.g. the states of
    /// independent processes of the environment that the zero-time control
    /// flow tests now and then, which would otherwise repeat every forced
    /// run once per combination of their states. Only the speed depends on
    /// the set: the graph is the same for any (docs/gspn.md, *The
    /// pipeline*). Ignored for nets with decisions; places the net does not
    /// have are left out. Default: none.
    pub forced_context: Vec<PlaceId>,
}

/// Where forced hops lead: the packed key of a forced vanishing marking →
/// the key of the first marking after it that is not forced (see
/// [`ExploreParams::skip_forced`]); pairs stored flat, `2·words` each, with
/// the key's hash ([`hash_words`], so every table agrees and a key is hashed
/// once per lookup).
#[derive(Default)]
struct Forced {
    words: usize,
    pairs: Vec<u64>,
    hashes: Vec<u64>,
    /// Per pair: what the user of the table stores with it (a stretch's
    /// length and whether it ends its run, see [`Context`]; 0 otherwise).
    tags: Vec<u32>,
    index: HashTable<u32>,
}

impl Forced {
    fn key(&self, i: u32) -> &[u64] {
        let at = i as usize * 2 * self.words;
        &self.pairs[at..at + self.words]
    }

    /// Where the run from `key` (of hash `h`) ends, if known.
    fn get(&self, key: &[u64], h: u64) -> Option<&[u64]> {
        self.get_tagged(key, h).map(|(end, _)| end)
    }

    /// [`get`](Self::get), with the pair's tag.
    fn get_tagged(&self, key: &[u64], h: u64) -> Option<(&[u64], u32)> {
        if key.len() != self.words {
            return None;
        }
        let i = *self.index.find(h, |&i| same_key(self.key(i), key))?;
        let at = (2 * i as usize + 1) * self.words;
        Some((&self.pairs[at..at + self.words], self.tags[i as usize]))
    }

    /// Remembers that the run from `key` (of hash `h`) ends at `end`.
    fn insert(&mut self, key: &[u64], h: u64, end: &[u64]) {
        self.insert_tagged(key, h, end, 0);
    }

    /// [`insert`](Self::insert), with a tag.
    fn insert_tagged(&mut self, key: &[u64], h: u64, end: &[u64], tag: u32) {
        if self.words != key.len() {
            self.clear();
            self.words = key.len();
        }
        if self.index.find(h, |&i| same_key(self.key(i), key)).is_some() {
            return;
        }
        let i = self.hashes.len() as u32;
        self.pairs.extend_from_slice(key);
        self.pairs.extend_from_slice(end);
        self.hashes.push(h);
        self.tags.push(tag);
        let hashes = &self.hashes;
        self.index.insert_unique(h, i, |&j| hashes[j as usize]);
    }

    /// Moves `other`'s pairs into `self`.
    fn absorb(&mut self, other: &mut Forced) {
        let w = other.words;
        if w > 0 {
            for ((pair, &h), &tag) in other
                .pairs
                .chunks_exact(2 * w)
                .zip(&other.hashes)
                .zip(&other.tags)
            {
                self.insert_tagged(&pair[..w], h, &pair[w..], tag);
            }
        }
        other.clear();
    }

    fn clear(&mut self) {
        self.pairs.clear();
        self.hashes.clear();
        self.tags.clear();
        self.index.clear();
    }
}

/// What [`ExploreParams::forced_context`] lets the memory of forced hops
/// leave out, and how to check that a stretch of hops may.
///
/// A hop from marking `x` by the one firable transition `u` is *free of
/// the context* when `u` has no arc on a context place and no immediate
/// transition with an arc on one could be enabled in `x` whatever the
/// context places hold (one of its other input or inhibitor places rules
/// it out). Then the immediate transitions enabled in `x` are those enabled
/// in every `x'` that differs from `x` only in context places, so `x'` is
/// forced too, by the same `u`, and the hop changes no context place: a
/// stretch of free hops from `x` is the same stretch from `x'`, ending in
/// the same marking but for the context places, which keep `x'`'s counts.
/// A stretch whose last marking is not forced and free in that sense ends
/// the run from every such `x'` ([`COMPLETE`]); one that stops before a hop
/// that is not free (a condition read, say) is continued from there as any
/// run. Stretches are keyed by the marking with the context fields cleared.
struct Context {
    /// Per transition: it has an arc (of any kind) on a context place.
    touches: Vec<bool>,
    /// The immediate transitions with an arc on a context place.
    watch: Vec<Watched>,
    places: Vec<u32>,
    /// The bits of the context fields in the current layout.
    bits: Vec<u64>,
    /// The initial marking, context fields cleared: no stretch passes
    /// through a marking that may be it (the initial marking is stored, so a
    /// run would stop there).
    initial: Vec<u64>,
}

/// An immediate transition with an arc on a context place: its other
/// input places and inhibitor places, `(place, multiplicity)`.
struct Watched {
    inputs: Vec<(u32, u32)>,
    inhibitors: Vec<(u32, u32)>,
}

/// Tag bit of a remembered stretch that ends its run.
const COMPLETE: u32 = 1 << 31;

impl Context {
    /// The context of `places` in `gspn`, if it can serve (a net with
    /// decisions resolves choices by whole markings: none).
    fn new(gspn: &Gspn, places: &[PlaceId]) -> Option<Context> {
        if places.is_empty() || gspn.has_decisions() {
            return None;
        }
        let mut is_context = vec![false; gspn.num_places()];
        // A place the net does not have is left out (the set only changes
        // the speed).
        for p in places {
            if let Some(c) = is_context.get_mut(p.index()) {
                *c = true;
            }
        }
        let on = |arcs: &[(u32, u32)]| arcs.iter().any(|&(p, _)| is_context[p as usize]);
        let others = |arcs: &[(u32, u32)]| -> Vec<(u32, u32)> {
            arcs.iter()
                .copied()
                .filter(|&(p, _)| !is_context[p as usize])
                .collect()
        };
        let mut touches = Vec::with_capacity(gspn.num_transitions());
        let mut watch = Vec::new();
        for t in (0..gspn.num_transitions() as u32).map(TransitionId) {
            let touched = on(gspn.inputs(t)) || on(gspn.outputs(t)) || on(gspn.inhibitors(t));
            touches.push(touched);
            if touched && gspn.is_immediate(t) {
                watch.push(Watched {
                    inputs: others(gspn.inputs(t)),
                    inhibitors: others(gspn.inhibitors(t)),
                });
            }
        }
        let places: Vec<u32> = (0..gspn.num_places() as u32)
            .filter(|&p| is_context[p as usize])
            .collect();
        if places.is_empty() {
            return None;
        }
        Some(Context {
            touches,
            watch,
            places,
            bits: Vec::new(),
            initial: Vec::new(),
        })
    }

    /// Brings the masks to `layout` (at the start and after a relayout).
    fn fit(&mut self, layout: &Layout, m0: &[u32]) {
        self.bits = layout.mask_of(self.places.iter().map(|&p| p as usize));
        self.initial = vec![0; layout.words()];
        layout.encode(m0, &mut self.initial);
        for (k, b) in self.initial.iter_mut().zip(&self.bits) {
            *k &= !b;
        }
    }

    /// Whether no immediate transition with an arc on a context place could
    /// be enabled in `m`, whatever the context places hold.
    fn free(&self, m: &[u32]) -> bool {
        !self.watch.iter().any(|t| {
            t.inputs.iter().all(|&(p, w)| m[p as usize] >= w)
                && t.inhibitors.iter().all(|&(p, w)| m[p as usize] < w)
        })
    }

    /// `key` with the context fields cleared, into `out`.
    fn project(&self, key: &[u64], out: &mut Vec<u64>) {
        out.clear();
        out.extend(key.iter().zip(&self.bits).map(|(k, b)| k & !b));
    }
}

/// What generation remembers from round to round: where forced hops lead,
/// the stretches free of the context, the widths firings asked for.
struct Memory {
    /// Forced hops already followed (learnt by the batches of earlier rounds).
    forced: Forced,
    /// Stretches free of the context, learnt likewise ([`Context`]).
    free: Forced,
    context: Option<Context>,
    /// Per place, the widest field a firing asked for: no relayout fits a
    /// field below it (see `MarkingStore::fitted_layout`).
    floor: Vec<u8>,
    /// Forced markings evaluated ([`ExploreStats::forced_evaluated`]).
    evaluated: usize,
}

impl Memory {
    fn new(gspn: &Gspn, params: &ExploreParams, layout: &Layout, m0: &[u32]) -> Memory {
        let mut context = params
            .skip_forced
            .then(|| Context::new(gspn, &params.forced_context))
            .flatten();
        if let Some(cx) = context.as_mut() {
            cx.fit(layout, m0);
        }
        Memory {
            forced: Forced::default(),
            free: Forced::default(),
            context,
            floor: vec![0; m0.len()],
            evaluated: 0,
        }
    }

    /// The layout to widen `store`'s to for a firing that needs `needed`.
    fn fitted(&mut self, store: &MarkingStore, needed: &[u8], pending: impl FnOnce() -> Vec<u32>) -> Layout {
        for ((f, &n), &w) in self.floor.iter_mut().zip(needed).zip(store.layout().widths()) {
            if n > w {
                *f = (*f).max(n);
            }
        }
        store.fitted_layout(needed, &self.floor, pending)
    }

    /// Forgets what was learnt in the old layout (after a relayout to `layout`).
    fn forget(&mut self, layout: &Layout, m0: &[u32], batches: &mut [Batch]) {
        self.forced.clear();
        self.free.clear();
        if let Some(cx) = self.context.as_mut() {
            cx.fit(layout, m0);
        }
        for b in batches {
            b.learnt.clear();
            b.learnt_free.clear();
            b.cut = false;
        }
    }

    /// Takes in what a round's batches learnt.
    fn absorb(&mut self, batches: &mut [Batch]) {
        for b in batches.iter_mut() {
            self.evaluated += b.evaluated;
            self.forced.absorb(&mut b.learnt);
            self.free.absorb(&mut b.learnt_free);
        }
        // A run cut by the hop limit stores a forced marking, which a
        // remembered stretch would pass through: none is used from now on.
        if batches.iter().any(|b| b.cut) {
            self.context = None;
            self.free.clear();
        }
    }
}

/// The longest run of forced vanishing hops followed in one firing when
/// [`ExploreParams::skip_forced`] is set.
pub const FORCED_HOPS: usize = 4096;

impl Default for ExploreParams {
    fn default() -> Self {
        ExploreParams {
            max_states: usize::MAX,
            max_memory: default_max_memory(),
            skip_forced: false,
            forced_context: Vec::new(),
        }
    }
}

/// Used when the available memory cannot be read (not Linux): 8 GiB.
pub const FALLBACK_MAX_MEMORY: u64 = 8 << 30;

/// The default memory guard: 85 % of `MemAvailable` in `/proc/meminfo`
/// (the memory the kernel can give without swapping, other processes'
/// use deducted) when it is read, [`FALLBACK_MAX_MEMORY`] otherwise.
pub fn default_max_memory() -> u64 {
    std::fs::read_to_string("/proc/meminfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find_map(|l| l.strip_prefix("MemAvailable:"))
                .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<u64>().ok())
        })
        .map_or(FALLBACK_MAX_MEMORY, |kib| kib * 1024 / 100 * 85)
}

/// Bytes per tangible marking held while solving, besides the packed
/// markings and the incoming rows' entries: the rows' offsets (4, or 8
/// beyond 2³² entries) and diagonal split (4), the exit rates (8) and
/// BiCGSTAB's seven vectors of doubles (56).
pub const SOLVE_BYTES_PER_STATE: u64 = 72;
/// Bytes per entry held while solving: the incoming rows' 4-byte column
/// index and 2-byte value id.
pub const SOLVE_BYTES_PER_EDGE: u64 = 6;
/// Bytes per entry held while an irreducible chain's generator is
/// transposed: the outgoing 4-byte indices and the incoming rows' 4-byte
/// indices and 2-byte value ids (the outgoing value ids are released
/// before the incoming indices are allocated).
pub const COMPILE_BYTES_PER_EDGE: u64 = 10;
/// Bytes per marking held while transposing, besides the packed markings:
/// both directions' row offsets (4 bytes each, 8 beyond 2³² entries).
pub const COMPILE_BYTES_PER_STATE: u64 = 8;
/// Bytes the estimate adds for what does not grow with the chain: the
/// dictionary of values, the self-loops of the nets measured, the
/// reductions' scratch (1 MiB).
pub const FIXED_BYTES: u64 = 1 << 20;

/// Estimated peak bytes of compiling and solving a state space of
/// `markings` markings whose packed markings take `marking_bytes` (by
/// length) and which has `edges` edges: the larger of
///
/// * the transposition, while both directions of the generator exist:
///   `marking_bytes + markings·`[`COMPILE_BYTES_PER_STATE`]` +
///   edges·`[`COMPILE_BYTES_PER_EDGE`];
/// * the solve, once an irreducible chain has released its outgoing rows:
///   `marking_bytes + markings·`[`SOLVE_BYTES_PER_STATE`]` +
///   edges·`[`SOLVE_BYTES_PER_EDGE`];
///
/// plus [`FIXED_BYTES`].
/// Lengths, not capacities: a vector's unused capacity beyond its length
/// is address space that no page backs until it is written, and every
/// array is shrunk to its length before the next stage. The generation's
/// own peak (hash index and graph) is added by the guard
/// ([`ExploreParams::max_memory`]) from what it holds. For nets without
/// vanishing markings, as irreducible chains: eliminating vanishing
/// markings adds working memory that this leaves out, and a reducible chain
/// keeps its outgoing rows (2 bytes per entry more while transposing, 6
/// while solving).
/// `CompiledGspn::memory_account` lists what was actually allocated.
pub fn estimated_bytes(marking_bytes: u64, markings: usize, edges: usize) -> u64 {
    let (m, e) = (markings as u64, edges as u64);
    // Beyond 2³² entries the offsets stay 8 bytes wide: 4 more per marking
    // and direction.
    let wide = u64::from(e > u64::from(u32::MAX));
    let compile = marking_bytes + m * (COMPILE_BYTES_PER_STATE + 8 * wide) + e * COMPILE_BYTES_PER_EDGE;
    let solve = marking_bytes + m * (SOLVE_BYTES_PER_STATE + 4 * wide) + e * SOLVE_BYTES_PER_EDGE;
    FIXED_BYTES + compile.max(solve)
}

/// What the memory guard compares with its limit: the larger of what
/// generation holds now (`generation_bytes`: packed markings, hash index,
/// graph arrays) and [`estimated_bytes`] of the later stages.
pub fn guard_bytes(generation_bytes: u64, marking_bytes: u64, markings: usize, edges: usize) -> u64 {
    generation_bytes.max(estimated_bytes(marking_bytes, markings, edges))
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
    /// Heap bytes of the packed markings when generation ended.
    pub marking_bytes: usize,
    /// Heap bytes of the hash index when generation ended (freed before
    /// compiling).
    pub index_bytes: usize,
    /// Heap bytes of the graph's edges and per-marking arrays (offsets,
    /// vanishing flags, targets, transitions, coefficients) when
    /// generation ended.
    pub edge_bytes: usize,
    /// With [`ExploreParams::skip_forced`]: the forced markings whose firing
    /// rule was evaluated to follow a hop (each once; fewer with
    /// [`ExploreParams::forced_context`], whose remembered stretches are
    /// replayed instead).
    pub forced_evaluated: usize,
}

/// A store holding only the initial marking `m0` (index 0), in the
/// narrowest layout that fits it.
fn store_with(m0: &[u32]) -> MarkingStore {
    let mut store = MarkingStore::new(Layout::for_marking(m0, 1));
    let mut key = vec![0u64; store.layout().words()];
    store.layout().encode(m0, &mut key);
    store.insert(&key);
    store
}

/// The round that starts at marking `i` when the store holds `len`
/// markings: its end, and whether it runs on the `threads` threads.
/// Rounds run in parallel from [`PARALLEL_FROM`] stored markings, with
/// [`MAX_CHUNKS_PER_THREAD`] chunks per thread; on one thread a round is
/// one [`BATCH`]. When `context` (forced runs remembered across a
/// context, see [`ExploreParams::forced_context`]), from
/// [`PARALLEL_FROM_CONTEXT`], with [`MIN_CHUNKS_PER_THREAD`] chunks per
/// thread in a store of a few thousand markings (what a round learns of
/// forced runs serves the next: short rounds learn together), growing to
/// the most in one of [`ROUND_GROWN`] markings.
fn round(i: usize, len: usize, threads: usize, context: bool) -> (usize, bool) {
    let (from, per_thread) = if context {
        let grown = len * MAX_CHUNKS_PER_THREAD / ROUND_GROWN;
        (
            PARALLEL_FROM_CONTEXT,
            grown.clamp(MIN_CHUNKS_PER_THREAD, MAX_CHUNKS_PER_THREAD),
        )
    } else {
        (PARALLEL_FROM, MAX_CHUNKS_PER_THREAD)
    };
    if threads < 2 || len < from {
        return ((i + BATCH).min(len), false);
    }
    ((i + per_thread * BATCH * threads).min(len), true)
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
    ///
    /// Markings are numbered in breadth-first discovery order (successors in
    /// transition order), the same on any number of threads: rounds of
    /// markings are expanded and looked up in parallel, the new successors
    /// inserted in order. A choice marking (docs/gspn.md, *Decisions*) has
    /// an edge per alternative, unless the net runs under a policy
    /// ([`Gspn::with_policy`]), whose choice it then follows. Errors:
    /// [`Error::MemoryLimit`] (see [`ExploreParams::max_memory`]),
    /// [`Error::StateLimit`], [`Error::TokenOverflow`], [`Error::Policy`].
    pub fn explore(gspn: &Gspn, params: &ExploreParams) -> Result<ReachabilityGraph> {
        Self::explore_interruptible(gspn, params, Interrupt::NEVER)
    }

    /// [`explore`](Self::explore), stopped with [`Error::Cancelled`] when
    /// `stop` is raised (checked before each round of expansions: see
    /// [`crate::interrupt`]).
    pub fn explore_interruptible(
        gspn: &Gspn,
        params: &ExploreParams,
        stop: Interrupt<'_>,
    ) -> Result<ReachabilityGraph> {
        let start = Instant::now();
        stop.stage(Stage::Generating);
        let m0 = gspn.initial_marking().to_vec();
        let mut store = store_with(&m0);

        let mut vanishing = Vec::new();
        let mut offsets = vec![0u64];
        let mut targets: Vec<u32> = Vec::new();
        let mut transitions: Vec<u32> = Vec::new();
        let mut coeffs: Option<Vec<f64>> = None;
        let mut max_tokens = m0.clone();
        let mut relayouts = 0;

        // Markings are expanded in rounds. A round's markings are split into
        // chunks of `BATCH`; each chunk's successors are computed, their hash
        // slots loaded together (overlapping the cache misses) and looked up
        // in the store as it was when the round began — read-only, so the
        // chunks run in parallel once the store is large. The successors
        // not found are then inserted one after the other, in order: the
        // numbering is exactly that of expanding one marking after the other
        // (breadth-first discovery order), whatever the number of threads.
        let mut batches: Vec<Batch> = Vec::new();
        let mut memory = Memory::new(gspn, params, store.layout(), &m0);
        let threads = rayon::current_num_threads();
        let index = EnablingIndex::new(gspn, params.skip_forced);
        let mut i = 0usize;
        while i < store.len() {
            stop.check("generating the reachability graph")?;
            stop.generated(store.len(), targets.len());
            // The round's size changes the speed, never the result.
            let (end, parallel) = round(i, store.len(), threads, memory.context.is_some());
            let chunks = (end - i).div_ceil(BATCH);
            batches.resize_with(chunks.max(batches.len()), Batch::default);
            let run = |(c, b): (usize, &mut Batch)| {
                let lo = i + c * BATCH;
                let skip = params.skip_forced.then_some(&memory.forced);
                let context = memory.context.as_ref().map(|cx| (cx, &memory.free));
                b.expand(gspn, &index, &store, lo..(lo + BATCH).min(end), skip, context)
            };
            let events: Vec<Result<Option<Vec<u8>>>> = if parallel {
                batches[..chunks].par_iter_mut().enumerate().map(run).collect()
            } else {
                batches[..chunks].iter_mut().enumerate().map(run).collect()
            };
            // The first event in marking order: an error, or a field to widen
            // (then the round is computed again in the new layout).
            if let Some(event) = events.into_iter().find_map(|e| e.transpose()) {
                let needed = event?;
                let layout =
                    memory.fitted(&store, &needed, || largest_successor_counts(gspn, &store, i..end));
                store.relayout(layout);
                relayouts += 1;
                memory.forget(store.layout(), &m0, &mut batches);
                continue;
            }
            let w = store.layout().words();
            for b in &batches[..chunks] {
                for (mx, &c) in max_tokens.iter_mut().zip(&b.max_tokens) {
                    *mx = (*mx).max(c);
                }
            }
            memory.absorb(&mut batches[..chunks]);
            let mut m = i;
            for b in &batches[..chunks] {
                let mut e = 0;
                for (&end_m, &v) in b.ends.iter().zip(&b.vanishing) {
                    for k in e..end_m {
                        let j = match b.found[k] {
                            NOT_FOUND => {
                                let (j, new) = store.insert(&b.keys[k * w..(k + 1) * w]);
                                if new && store.len() > params.max_states {
                                    return Err(state_limit(gspn, params.max_states, m, &max_tokens));
                                }
                                j
                            }
                            j => j,
                        };
                        let (t, c) = b.edges[k];
                        if c != 1.0 && coeffs.is_none() {
                            coeffs = Some(vec![1.0; targets.len()]);
                        }
                        if let Some(cs) = coeffs.as_mut() {
                            cs.push(c);
                        }
                        targets.push(j);
                        transitions.push(t);
                    }
                    e = end_m;
                    vanishing.push(v);
                    offsets.push(targets.len() as u64);
                    m += 1;
                }
            }
            i = end;
            let graph_bytes = graph_len_bytes(&offsets, &vanishing, &targets, coeffs.as_ref());
            check_memory(&store, graph_bytes, targets.len(), params.max_memory)?;
        }
        stop.generated(store.len(), targets.len());
        // Vec growth leaves up to half of each array unused; large blocks are
        // remapped, not copied, when shrunk.
        targets.shrink_to_fit();
        transitions.shrink_to_fit();
        offsets.shrink_to_fit();
        if let Some(c) = coeffs.as_mut() {
            c.shrink_to_fit();
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
            marking_bytes: store.heap_bytes() - store.index_bytes(),
            index_bytes: store.index_bytes(),
            edge_bytes: edge_bytes(&offsets, &vanishing, &targets, &transitions, coeffs.as_ref()),
            forced_evaluated: memory.evaluated,
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

/// Markings per chunk (see [`ReachabilityGraph::explore`]): their ~10
/// successors each are a few hundred slot loads in flight, which fit the L1
/// cache.
const BATCH: usize = 32;
/// Chunks per round and thread once the store is large (32: their slots
/// stay in its L2 cache until they are inserted; see [`round`]).
const MAX_CHUNKS_PER_THREAD: usize = 32;
/// Chunks per round and thread in a small store.
const MIN_CHUNKS_PER_THREAD: usize = 4;
/// Stored markings from which a round has [`MAX_CHUNKS_PER_THREAD`].
const ROUND_GROWN: usize = 1 << 17;
/// Stored markings from which rounds run in parallel (below, the hash table
/// is in cache and a round is too short to share).
const PARALLEL_FROM: usize = 1 << 15;
/// The same with forced runs remembered across a context: an expansion
/// follows forced runs and replays remembered stretches, several times
/// the work of one without (the behaviour trees' chains: ~3.6 µs a marking,
/// against ~0.7 µs for Kanban's), so short rounds pay from a few thousand
/// markings (`crates/petri/EXPERIMENTS.md`).
const PARALLEL_FROM_CONTEXT: usize = 1 << 11;
/// `Batch::found` of a successor that was not stored when the round began.
const NOT_FOUND: u32 = u32::MAX;

/// The successors of a chunk of markings, before insertion.
#[derive(Default)]
struct Batch {
    /// Packed successor keys, `words` each.
    keys: Vec<u64>,
    /// `(transition, coefficient)` per successor.
    edges: Vec<(u32, f64)>,
    /// The successor's index if it was stored when the round began,
    /// [`NOT_FOUND`] otherwise.
    found: Vec<u32>,
    /// End of each marking's successors in `edges`.
    ends: Vec<usize>,
    /// Whether each marking is vanishing.
    vanishing: Vec<bool>,
    /// Largest token count of each place over the chunk's markings.
    max_tokens: Vec<u32>,
    cur: Vec<u32>,
    /// The transitions enabled in `cur`, and those that may fire there.
    enabled: EnabledSet,
    firable: Vec<TransitionId>,
    /// A successor followed through forced hops, its enabled and its firable
    /// transitions.
    next: Vec<u32>,
    next_enabled: EnabledSet,
    next_firable: Vec<TransitionId>,
    /// Forced hops followed in this round (merged into the explorer's after it).
    learnt: Forced,
    /// The keys of the forced markings of the hops being followed, and
    /// their hashes.
    path: Vec<u64>,
    path_hashes: Vec<u64>,
    /// Stretches free of the context learnt in this round (see [`Context`]).
    learnt_free: Forced,
    /// A key with the context cleared, and the start of the stretch being
    /// learnt (empty when none is).
    projected: Vec<u64>,
    stretch: Vec<u64>,
    /// The end of a remembered run or stretch, copied out of its table.
    end: Vec<u64>,
    /// A run cut by the hop limit was met in this round.
    cut: bool,
    /// Markings whose firing rule was evaluated while following hops.
    evaluated: usize,
}

/// The fields a firing of `t` in `m` would overflow in `layout` (`None` if it
/// fits), or the error of a count beyond `u32`.
fn widening(gspn: &Gspn, layout: &Layout, m: &[u32], t: TransitionId) -> Result<Option<Vec<u8>>> {
    let mut widen: Option<Vec<u8>> = None;
    for &(p, d) in gspn.delta(t) {
        if d > 0 {
            let p = p as usize;
            let new = u64::from(m[p]) + d as u64;
            if new > u64::from(u32::MAX) {
                return Err(Error::TokenOverflow {
                    place: gspn.place_names()[p].clone(),
                    limit: u64::from(u32::MAX),
                });
            }
            if new > u64::from(layout.max_value(p)) {
                let w = widen.get_or_insert_with(|| layout.widths().to_vec());
                w[p] = w[p].max(bits_for(new as u32));
            }
        }
    }
    Ok(widen)
}

impl Batch {
    /// Computes the successors of `markings` and looks them up in `store`.
    /// Returns the widths a firing needs if it would overflow a field (the
    /// batch is then incomplete; see `MarkingStore::fitted_layout`), or the error of a count beyond
    /// `u32`.
    fn expand(
        &mut self,
        gspn: &Gspn,
        index: &EnablingIndex,
        store: &MarkingStore,
        markings: std::ops::Range<usize>,
        skip_forced: Option<&Forced>,
        context: Option<(&Context, &Forced)>,
    ) -> Result<Option<Vec<u8>>> {
        self.keys.clear();
        self.edges.clear();
        self.found.clear();
        self.ends.clear();
        self.vanishing.clear();
        self.cut = false;
        self.evaluated = 0;
        let np = gspn.num_places();
        self.max_tokens.clear();
        self.max_tokens.resize(np, 0);
        self.cur.resize(np, 0);
        let layout = store.layout();
        let w = layout.words();
        for m in markings {
            store.decode(m, &mut self.cur);
            for (mx, &c) in self.max_tokens.iter_mut().zip(&self.cur) {
                *mx = (*mx).max(c);
            }
            self.enabled.fill(gspn, &self.cur);
            let kind = self.enabled.firable(gspn, index, &mut self.firable);
            let kind = gspn.resolve(&self.cur, &mut self.firable, kind)?;
            self.vanishing.push(kind == MarkingKind::Vanishing);
            let total_weight: f64 = if kind == MarkingKind::Vanishing {
                self.firable.iter().map(|&t| gspn.weight(t).unwrap_or(1.0)).sum()
            } else {
                1.0
            };
            for k in 0..self.firable.len() {
                let t = self.firable[k];
                // Fields that the firing would overflow are widened first.
                if let Some(widen) = widening(gspn, layout, &self.cur, t)? {
                    return Ok(Some(widen));
                }
                let at = self.keys.len();
                self.keys.extend_from_slice(store.key(m));
                for &(p, d) in gspn.delta(t) {
                    layout.add(&mut self.keys[at..at + w], p as usize, d);
                }
                if let Some(known) = skip_forced {
                    if let Some(widen) = self.follow_forced(gspn, index, store, known, context, at, t)? {
                        return Ok(Some(widen));
                    }
                }
                let c = if kind == MarkingKind::Vanishing {
                    gspn.weight(t).unwrap_or(1.0) / total_weight
                } else {
                    gspn.server_factor(t, &self.cur)
                };
                self.edges.push((t.0, c));
            }
            self.ends.push(self.edges.len());
        }
        store.touch(&self.keys);
        self.found.extend(
            self.keys
                .chunks_exact(w)
                .map(|k| store.find(k).unwrap_or(NOT_FOUND)),
        );
        Ok(None)
    }

    /// Follows the successor key at `at` (reached from `self.cur` by `t`)
    /// through forced vanishing markings (see [`ExploreParams::skip_forced`]),
    /// rewriting the key in place; hops followed before (`known`, or this
    /// round's) are not followed again, nor are stretches free of the
    /// `context` (with the stretches known before; see [`Context`]).
    /// Returns the widths a hop needs if it would overflow a field.
    #[allow(clippy::too_many_arguments)]
    fn follow_forced(
        &mut self,
        gspn: &Gspn,
        index: &EnablingIndex,
        store: &MarkingStore,
        known: &Forced,
        context: Option<(&Context, &Forced)>,
        at: usize,
        t: TransitionId,
    ) -> Result<Option<Vec<u8>>> {
        let layout = store.layout();
        let w = layout.words();
        self.path.clear();
        self.path_hashes.clear();
        self.stretch.clear();
        let mut ended = false;
        // `next` is the marking of the key, `next_enabled` its set before
        // `fired` fired; both are made from `cur`'s when first needed, or
        // decoded afresh after a remembered stretch (`stale`).
        let mut fired = t;
        let mut copied = false;
        let mut stale = false;
        // Hops of the stretch being learnt, and of the whole run.
        let mut stretch_hops = 0u32;
        let mut hops = 0usize;
        while hops < FORCED_HOPS {
            let key = &self.keys[at..at + w];
            // A stored marking is not followed through (it is one that is not
            // forced, the initial marking, or one where the hop limit cut a run).
            if store.find(key).is_some() {
                self.end_stretch(context, at, w, stretch_hops, false);
                ended = true;
                break;
            }
            let h = hash_words(key);
            if let Some(end) = known.get(key, h).or_else(|| self.learnt.get(key, h)) {
                self.end.clear();
                self.end.extend_from_slice(end);
                // The stretch being learnt stops here, where the run's
                // remembered end is read, not at that end (the hops in
                // between may not be free of the context).
                self.end_stretch(context, at, w, stretch_hops, false);
                self.keys[at..at + w].copy_from_slice(&self.end);
                ended = true;
                break;
            }
            if let Some((cx, stretches)) = context {
                cx.project(&self.keys[at..at + w], &mut self.projected);
                if self.stretch.is_empty() {
                    let hp = hash_words(&self.projected);
                    let remembered = stretches
                        .get_tagged(&self.projected, hp)
                        .or_else(|| self.learnt_free.get_tagged(&self.projected, hp));
                    if let Some((end, tag)) = remembered {
                        self.end.clear();
                        self.end.extend_from_slice(end);
                        hops += self.replay(cx, layout, at, h, tag);
                        if tag & COMPLETE != 0 {
                            ended = true;
                            break;
                        }
                        stale = true;
                        continue;
                    }
                    self.stretch.clone_from(&self.projected);
                } else if self.projected == cx.initial {
                    // Possibly the initial marking (stored): the stretch
                    // stops before it, and a new one starts there.
                    self.end_stretch(context, at, w, stretch_hops, false);
                    stretch_hops = 0;
                    self.stretch.clone_from(&self.projected);
                }
            }
            if stale {
                self.next.resize(self.cur.len(), 0);
                layout.decode(&self.keys[at..at + w], &mut self.next);
                self.next_enabled.fill(gspn, &self.next);
                stale = false;
                copied = true;
            } else {
                if !copied {
                    self.next.clone_from(&self.cur);
                    for &(p, d) in gspn.delta(t) {
                        let c = &mut self.next[p as usize];
                        *c = (i64::from(*c) + d) as u32;
                    }
                    self.next_enabled.clone_from(&self.enabled);
                    copied = true;
                }
                self.next_enabled.refresh(gspn, index, fired, &self.next);
            }
            self.evaluated += 1;
            let kind = self.next_enabled.firable(gspn, index, &mut self.next_firable);
            let kind = gspn.resolve(&self.next, &mut self.next_firable, kind)?;
            let free = context.is_some_and(|(cx, _)| cx.free(&self.next));
            if kind != MarkingKind::Vanishing || self.next_firable.len() != 1 {
                // Remembered as its own end (its firing rule is not evaluated again).
                self.learnt
                    .insert(&self.keys[at..at + w], h, &self.keys[at..at + w]);
                self.end_stretch(context, at, w, stretch_hops, free);
                ended = true;
                break;
            }
            let u = self.next_firable[0];
            if !free || context.is_some_and(|(cx, _)| cx.touches[u.index()]) {
                // Not free of the context: the stretch stops here, and a new
                // one may start after this hop.
                self.end_stretch(context, at, w, stretch_hops, false);
                self.stretch.clear();
                stretch_hops = 0;
            } else {
                stretch_hops += 1;
            }
            if let Some(widen) = widening(gspn, layout, &self.next, u)? {
                return Ok(Some(widen));
            }
            self.path.extend_from_slice(&self.keys[at..at + w]);
            self.path_hashes.push(h);
            for &(p, d) in gspn.delta(u) {
                layout.add(&mut self.keys[at..at + w], p as usize, d);
                let c = &mut self.next[p as usize];
                *c = (i64::from(*c) + d) as u32;
            }
            // Largest counts: only the places this hop changed (and, at the
            // first hop, those `t` changed) hold counts not yet counted.
            let changed = if hops == 0 { gspn.delta(t) } else { &[] };
            for &(p, _) in changed.iter().chain(gspn.delta(u)) {
                let mx = &mut self.max_tokens[p as usize];
                *mx = (*mx).max(self.next[p as usize]);
            }
            fired = u;
            hops += 1;
        }
        // A run cut by the hop limit (a timeless loop) is not remembered.
        if ended {
            let end = &self.keys[at..at + w];
            for (k, &h) in self.path.chunks_exact(w).zip(&self.path_hashes) {
                self.learnt.insert(k, h, end);
            }
        } else {
            self.cut = true;
        }
        Ok(None)
    }

    /// Replays a remembered stretch of tag `tag` from the key at `at` (of
    /// hash `h`) to its end, `self.end` with the key's context fields;
    /// returns the hops it stands for.
    fn replay(&mut self, cx: &Context, layout: &Layout, at: usize, h: u64, tag: u32) -> usize {
        let key = &mut self.keys[at..at + layout.words()];
        self.path.extend_from_slice(key);
        self.path_hashes.push(h);
        // The context fields are the key's, their counts those of every
        // marking of the stretch (counted as a hop would count them: only if
        // it has one).
        let hops = tag & !COMPLETE;
        if hops > 0 {
            for &p in &cx.places {
                let mx = &mut self.max_tokens[p as usize];
                *mx = (*mx).max(layout.get(key, p as usize));
            }
        }
        for ((k, &e), &b) in key.iter_mut().zip(&self.end).zip(&cx.bits) {
            *k = (*k & b) | e;
        }
        hops.max(1) as usize
    }

    /// Remembers the stretch being learnt, from `self.stretch` to the key at
    /// `at`, if it has hops (`complete`: the key's marking ends the run from
    /// every marking of the stretch's start, see [`Context`]).
    fn end_stretch(
        &mut self,
        context: Option<(&Context, &Forced)>,
        at: usize,
        w: usize,
        hops: u32,
        complete: bool,
    ) {
        let Some((cx, _)) = context else { return };
        if self.stretch.is_empty() || (hops == 0 && !complete) {
            return;
        }
        cx.project(&self.keys[at..at + w], &mut self.projected);
        let tag = hops.min(!COMPLETE) | if complete { COMPLETE } else { 0 };
        let h = hash_words(&self.stretch);
        self.learnt_free
            .insert_tagged(&self.stretch, h, &self.projected, tag);
        self.stretch.clear();
    }
}

/// The memory guard after a round: [`guard_bytes`] of the store and of a
/// graph of `graph_bytes` (by length) with `edges` edges against `limit`.
fn check_memory(store: &MarkingStore, graph_bytes: usize, edges: usize, limit: u64) -> Result<()> {
    let marking_bytes = (store.len() * store.layout().words() * 8) as u64;
    let generation = marking_bytes + (store.index_bytes() + graph_bytes) as u64;
    let estimate = guard_bytes(generation, marking_bytes, store.len(), edges);
    if estimate > limit {
        return Err(Error::MemoryLimit {
            estimate,
            limit,
            markings: store.len(),
            edges,
        });
    }
    Ok(())
}

/// The largest count of each place over the successors of the markings
/// `range` of `store` (the round a widening interrupted), counted without
/// the packing's limits.
fn largest_successor_counts(gspn: &Gspn, store: &MarkingStore, range: std::ops::Range<usize>) -> Vec<u32> {
    let np = gspn.initial_marking().len();
    let mut largest = vec![0u32; np];
    let mut m = vec![0u32; np];
    let mut firable = Vec::new();
    for i in range {
        store.decode(i, &mut m);
        // A policy that does not fit fails in the expansion itself.
        let _ = gspn.firable_resolved(&m, &mut firable);
        for &t in &firable {
            for &(p, d) in gspn.delta(t) {
                let c = i64::from(m[p as usize]) + d;
                let c = u32::try_from(c.max(0)).unwrap_or(u32::MAX);
                largest[p as usize] = largest[p as usize].max(c);
            }
        }
    }
    largest
}

/// Bytes of the graph's arrays by length (what is written; see
/// [`estimated_bytes`]).
fn graph_len_bytes(offsets: &[u64], vanishing: &[bool], targets: &[u32], coeffs: Option<&Vec<f64>>) -> usize {
    // Targets and transitions have the same length.
    offsets.len() * 8 + vanishing.len() + targets.len() * 8 + coeffs.map_or(0, |c| c.len() * 8)
}

/// Heap bytes of the graph's arrays (capacities, not lengths).
fn edge_bytes(
    offsets: &Vec<u64>,
    vanishing: &Vec<bool>,
    targets: &Vec<u32>,
    transitions: &Vec<u32>,
    coeffs: Option<&Vec<f64>>,
) -> usize {
    offsets.capacity() * 8
        + vanishing.capacity()
        + (targets.capacity() + transitions.capacity()) * 4
        + coeffs.map_or(0, |c| c.capacity() * 8)
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
