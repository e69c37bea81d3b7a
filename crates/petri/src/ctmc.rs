//! The CTMC of a GSPN, compiled once and solved for any rates.
//!
//! [`CompiledGspn::build`] generates the reachability graph, eliminates the
//! vanishing markings and keeps the result *symbolically*: every entry of the
//! generator is `rate[t] · c` with `c` the server factor times the vanishing
//! path probability — which depend on markings and weights only. Solving for
//! new rates ([`CompiledGspn::solve_rates`]) therefore rebuilds nothing: it
//! computes the exit rates (one pass over the entries) and solves. The
//! strongly connected structure of the chain does not depend on rates either
//! (they are > 0), so the bottom components of a non-ergodic chain are found
//! once here.
//!
//! Long-run distribution from `M0` (docs/gspn.md, *The pipeline*, 4): `Σ_B P(reach B) · π_B` over the
//! bottom strongly connected components `B`; `P(reach B)` comes from the
//! expected sojourn times `x` in the transient states, `x(−Q_TT) = π0_T`,
//! as `π0_B + Σ_{s∈T} x_s Σ_{b∈B} q_sb`.
//!
//! # Numbers
//!
//! Every number a [`Solution`] holds is finite, or the solve fails: the
//! chain is solved in the time unit of its fastest rate (divided by a power
//! of two, exactly), so rates such as 1e200 next to 1e-3 neither overflow
//! nor lose accuracy (GTH rescales its back substitution, see
//! [`crate::steady_state`]); rates more than [`MAX_RATE_SPREAD`] apart are
//! [`Error::RateSpread`], naming both transitions and the ratio; anything
//! else that comes out NaN or infinite is [`Error::NotFinite`], naming the
//! number. [`CompiledGspn::measure`] does the same for a measure that
//! divides by zero.

use std::time::Instant;

use hashbrown::HashMap;

use crate::error::{Error, Result};
use crate::expr::Expr;
use crate::gspn::Gspn;
use crate::interrupt::{Interrupt, Stage};
use crate::marking::MarkingStore;
use crate::net::{Params, PlaceId, TransitionId};
use crate::reachability::{ExploreParams, ExploreStats, ReachabilityGraph};
use crate::rows::{Chain, Ids, Offset, Offsets, Rows};
use crate::scc::{Components, Successors};
use crate::steady_state::{self, SolveInfo, SolveParams};
use crate::vanishing;

const NONE: u32 = u32::MAX;

/// What [`Error::Cancelled`] says a stopped compilation was doing.
const COMPILING: &str = "compiling the CTMC";

/// Largest ratio between the fastest and the slowest rate of the timed
/// transitions that fire in a chain that [`CompiledGspn::solve_rates`]
/// accepts ([`Error::RateSpread`] beyond).
///
/// The solve works in the time unit of the fastest rate (scaled by a power
/// of two, which is exact), so every generator entry is at most its
/// coefficient and nothing overflows; GTH, which subtracts nothing, keeps
/// every probability accurate to rounding however far apart the rates are,
/// as long as the scaled rates are normal doubles. `1e300` leaves the
/// elimination some eight orders of magnitude above the smallest normal
/// double (2.2e-308) for coefficients (vanishing-path probabilities) and
/// sums of rates.
pub const MAX_RATE_SPREAD: f64 = 1e300;

/// Sizes and timings of a compilation.
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct CompileStats {
    /// State-space generation figures.
    pub explore: ExploreStats,
    /// Entries `(s, t, s')` of the symbolic generator (self-loops included).
    pub entries: usize,
    /// Distinct `(transition, coefficient)` values among them.
    pub distinct_values: usize,
    /// Heap bytes of the generator's rows kept after compiling (incoming
    /// rows, and the outgoing ones for chains that are not irreducible:
    /// offsets, 4-byte indices, 2- or 4-byte value ids).
    pub matrix_bytes: usize,
    /// Heap bytes of the outgoing rows held while the incoming ones were
    /// built: all of them for a chain that is not irreducible, which keeps
    /// them; the offsets and indices for an irreducible one, which releases
    /// its value ids before the incoming indices are allocated and the rest
    /// at the end.
    pub transposed_bytes: usize,
    /// Heap bytes of the packed tangible and vanishing markings kept.
    pub marking_bytes: usize,
    /// Seconds spent eliminating vanishing markings and building the chain.
    pub compile_seconds: f64,
    /// Number of strongly connected components of the tangible chain.
    pub components: usize,
    /// Number of bottom components (1 for an ergodic chain).
    pub bottom_components: usize,
    /// Tangible states outside every bottom component.
    pub transient_states: usize,
}

/// One line of a [`MemoryAccount`]: what holds memory, when, and how much.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct MemoryPart {
    /// What the bytes hold.
    pub component: &'static str,
    /// When they exist: `"generation"` (freed before compiling),
    /// `"compile"` (freed once the incoming rows are built), `"chain"`
    /// (kept with the compiled chain) or `"solve"` (during a solve).
    pub stage: &'static str,
    /// Heap bytes, from the allocations' capacities.
    pub bytes: u64,
    /// `bytes` per tangible marking.
    pub bytes_per_marking: f64,
}

/// Where the memory of generating, compiling and solving a chain goes,
/// from the capacities of the actual allocations
/// ([`CompiledGspn::memory_account`]).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct MemoryAccount {
    /// Tangible markings (the denominator of every "per marking").
    pub tangible_markings: usize,
    /// Every component, in pipeline order.
    pub parts: Vec<MemoryPart>,
    /// Held at the end of generation: markings, hash index, graph.
    pub generation_bytes: u64,
    /// Held while both directions of the generator exist: the chain's
    /// parts but the diagonal split, plus the outgoing rows.
    pub compile_bytes: u64,
    /// Held during the solve: the chain's parts and the solve's.
    pub solve_bytes: u64,
    /// The largest of the three: the pipeline's peak heap.
    pub peak_bytes: u64,
    /// What the memory guard ([`crate::estimated_bytes`]) estimated for
    /// this chain's markings and edges at the end of generation.
    pub guard_estimate_bytes: u64,
}

impl MemoryAccount {
    /// `peak_bytes` per tangible marking.
    pub fn peak_per_marking(&self) -> f64 {
        self.peak_bytes as f64 / self.tangible_markings.max(1) as f64
    }
}

/// A GSPN compiled to a symbolic CTMC over its tangible markings.
#[derive(Debug, Clone)]
pub struct CompiledGspn {
    gspn: Gspn,
    stats: CompileStats,
    store: MarkingStore,
    /// RG index of each tangible state; empty when they are the same (no
    /// vanishing markings).
    tangible_rg: Vec<u32>,
    num_tangible: usize,
    /// `(transition, coefficient)` of each value id.
    dictionary: Vec<(u32, f64)>,
    /// Outgoing entries per state (index = target), self-loops kept: kept
    /// only for chains that are not irreducible (their components and
    /// absorption need them); `None` otherwise.
    outgoing: Option<Rows>,
    /// Incoming entries per state (index = source), self-loops left out.
    incoming: Rows,
    /// `(state, value id)` of the entries from a state to itself (left out
    /// of `incoming`; they count in throughputs only).
    self_loops: Vec<(u32, u32)>,
    imm: ImmediateFlows,
    initial: Vec<(u32, f64)>,
    /// Timed transitions that label an entry of the chain (the rates that
    /// matter to a solve), ascending.
    firing_timed: Vec<u32>,
    /// `None` when the chain is irreducible.
    components: Option<Components>,
    bottoms: Vec<Vec<u32>>,
    transient: Vec<u32>,
}

/// The long-run solution for one binding of the rates.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Solution {
    /// Long-run probability of each tangible marking.
    pub pi: Vec<f64>,
    /// Rates used, by transition (0 for immediate ones).
    pub rates: Vec<f64>,
    /// Mean firings per unit time, by transition.
    pub throughput: Vec<f64>,
    /// `E[#p]`, by place.
    pub mean_tokens: Vec<f64>,
    /// `P{#p > 0}`, by place.
    pub prob_nonempty: Vec<f64>,
    /// How the stationary equations were solved (the largest bottom
    /// component's solve; residual of the whole long-run distribution).
    pub info: SolveInfo,
    /// Residual of the absorption equations (0 for ergodic chains).
    pub absorption_residual: f64,
    /// Long-run probability of ending in each bottom component, in the order
    /// of [`CompiledGspn::bottom_components`] (`[1.0]` for an ergodic chain).
    pub bottom_probabilities: Vec<f64>,
}

impl Solution {
    /// Throughput of `t`.
    pub fn throughput(&self, t: TransitionId) -> f64 {
        self.throughput[t.index()]
    }

    /// Mean token count of `p`.
    pub fn mean_tokens(&self, p: PlaceId) -> f64 {
        self.mean_tokens[p.index()]
    }

    /// Probability that `p` is marked.
    pub fn prob_nonempty(&self, p: PlaceId) -> f64 {
        self.prob_nonempty[p.index()]
    }
}

/// Timed firings `(src, trans, coeff)` that enter vanishing markings, with
/// the expected immediate firings `F` that follow each.
#[derive(Debug, Clone)]
struct ImmediateFlows {
    src: Vec<u32>,
    trans: Vec<u32>,
    coeff: Vec<f64>,
    f_start: Vec<u64>,
    f_items: Vec<(u32, f64)>,
}

impl Default for ImmediateFlows {
    fn default() -> Self {
        ImmediateFlows {
            src: Vec::new(),
            trans: Vec::new(),
            coeff: Vec::new(),
            f_start: vec![0],
            f_items: Vec::new(),
        }
    }
}

impl Successors for Rows {
    fn num_nodes(&self) -> usize {
        self.len()
    }

    fn successors(&self, v: u32) -> &[u32] {
        let (a, b) = self.range(v as usize);
        &self.index[a..b]
    }
}

/// Assigns value ids to `(transition, coefficient)` pairs.
struct Dictionary {
    pairs: Vec<(u32, f64)>,
    index: HashMap<(u32, u64), u32>,
}

impl Dictionary {
    fn new(num_transitions: usize) -> Dictionary {
        // Ids 0..T are the pairs (t, 1): the common case needs no lookup.
        Dictionary {
            pairs: (0..num_transitions as u32).map(|t| (t, 1.0)).collect(),
            index: HashMap::new(),
        }
    }

    #[inline]
    fn id(&mut self, t: u32, c: f64) -> u32 {
        if c == 1.0 {
            return t;
        }
        let pairs = &mut self.pairs;
        *self.index.entry((t, c.to_bits())).or_insert_with(|| {
            pairs.push((t, c));
            (pairs.len() - 1) as u32
        })
    }
}

/// Row lengths of the incoming rows of `outgoing` as offsets (entry
/// `d + 1` counts row `d`), self-loops left out and pushed on `self_loops`
/// as `(state, value id)`.
fn incoming_counts<O: Offset>(outgoing: &Rows, self_loops: &mut Vec<(u32, u32)>) -> Vec<O> {
    let n = outgoing.len();
    let mut in_offsets = vec![O::ZERO; n + 1];
    for s in 0..n {
        let (a, b) = outgoing.range(s);
        for (k, &d) in (a..b).zip(&outgoing.index[a..b]) {
            if d as usize != s {
                let c = &mut in_offsets[d as usize + 1];
                *c = O::of(c.to() + 1);
            } else {
                self_loops.push((s as u32, outgoing.ids.get(k) as u32));
            }
        }
    }
    for j in 0..n {
        in_offsets[j + 1] = O::of(in_offsets[j + 1].to() + in_offsets[j].to());
    }
    in_offsets
}

/// Calls `put(position, source, entry)` for every entry of `outgoing` but
/// the self-loops, `position` being its place in the incoming rows: sources
/// are visited in order, so each incoming row comes out sorted by source.
/// `cursors[d]` is row `d`'s fill cursor: it starts at the row's start and
/// ends at its end, i.e. the next row's start, and is shifted back, so that
/// the offsets serve again. `O(entries + states)`.
fn scatter<O: Offset>(outgoing: &Rows, cursors: &mut [O], mut put: impl FnMut(usize, u32, usize)) {
    let n = outgoing.len();
    for s in 0..n {
        let (a, b) = outgoing.range(s);
        for (k, &d) in (a..b).zip(&outgoing.index[a..b]) {
            let d = d as usize;
            if d != s {
                let pos = cursors[d].to();
                cursors[d] = O::of(pos + 1);
                put(pos, s as u32, k);
            }
        }
    }
    cursors.copy_within(0..n, 1);
    cursors[0] = O::ZERO;
}

/// The outgoing rows a transposition reads: kept by a chain that is not
/// irreducible, or given up on the way by one that is.
enum Outgoing<'a> {
    Kept(&'a Rows),
    Released(Rows),
}

/// The incoming rows of the outgoing ones, self-loops left out (see
/// [`incoming_counts`]), each row sorted by source. Kept outgoing rows are
/// scattered in one pass (both directions whole at the end: 12 bytes per
/// entry); released ones in two, the value ids first and freed, then the
/// sources (the same rows at a peak of 10 bytes per entry: the outgoing
/// indices and the incoming indices and value ids).
fn transpose<O: Offset>(
    outgoing: Outgoing<'_>,
    dictionary_len: usize,
    self_loops: &mut Vec<(u32, u32)>,
) -> (Vec<O>, Vec<u32>, Ids) {
    let rows = match &outgoing {
        Outgoing::Kept(rows) => *rows,
        Outgoing::Released(rows) => rows,
    };
    let mut in_offsets = incoming_counts::<O>(rows, self_loops);
    let m = in_offsets[rows.len()].to();
    let mut in_ids = Ids::zeros(m, dictionary_len);
    let mut in_src;
    match outgoing {
        Outgoing::Kept(out) => {
            in_src = vec![0u32; m];
            scatter(out, &mut in_offsets, |pos, s, k| {
                in_src[pos] = s;
                in_ids.set(pos, out.ids.get(k));
            });
        }
        Outgoing::Released(mut out) => {
            let ids = std::mem::replace(&mut out.ids, Ids::zeros(0, dictionary_len));
            scatter(&out, &mut in_offsets, |pos, _, k| in_ids.set(pos, ids.get(k)));
            drop(ids);
            in_src = vec![0u32; m];
            scatter(&out, &mut in_offsets, |pos, s, _| in_src[pos] = s);
        }
    }
    (in_offsets, in_src, in_ids)
}

/// The incoming rows ([`transpose`]), with 4-byte offsets up to 2³²
/// entries, 8-byte beyond.
fn incoming_rows(outgoing: Outgoing<'_>, dictionary_len: usize, self_loops: &mut Vec<(u32, u32)>) -> Rows {
    let entries = match &outgoing {
        Outgoing::Kept(rows) => rows.index.len(),
        Outgoing::Released(rows) => rows.index.len(),
    };
    let (offsets, index, ids) = if entries <= u32::MAX as usize {
        let (o, s, i) = transpose::<u32>(outgoing, dictionary_len, self_loops);
        (Offsets::U32(o), s, i)
    } else {
        let (o, s, i) = transpose::<u64>(outgoing, dictionary_len, self_loops);
        (Offsets::U64(o), s, i)
    };
    Rows {
        offsets,
        index,
        ids,
        below: Vec::new(),
    }
}

/// Whether every state reaches and is reached from state 0, i.e. the chain
/// is irreducible: Tarjan's algorithm on the outgoing rows alone (so that
/// the transposition can release them), stopped at the first component
/// smaller than the chain. `O(states + entries)`, 21 bytes per state at
/// most.
fn strongly_connected(outgoing: &Rows) -> bool {
    let n = outgoing.len();
    n > 0
        && crate::scc::tarjan(
            outgoing,
            |_| true,
            |c: &[u32]| if c.len() == n { Ok(()) } else { Err(()) },
        )
        .is_ok()
}

/// A steady state before its normalisation and measures.
struct Reducible {
    /// Unnormalised π (sums to 1 up to the absorption solve's error).
    pi: Vec<f64>,
    /// What the solvers did.
    info: SolveInfo,
    /// Residual of the absorption equations (0 without transient states).
    absorption_residual: f64,
    /// Probability of ending in each bottom component.
    bottom_probabilities: Vec<f64>,
}

/// Numbers the tangible markings in graph order: the tangible id of every
/// graph index ([`NONE`] for a vanishing one) and the graph index of every
/// tangible id.
fn tangible_numbering(rg: &ReachabilityGraph) -> (Vec<u32>, Vec<u32>) {
    let mut tangible_id = vec![NONE; rg.num_markings()];
    let mut tangible_rg = Vec::with_capacity(rg.num_tangible());
    for (i, slot) in tangible_id.iter_mut().enumerate() {
        if !rg.vanishing[i] {
            *slot = tangible_rg.len() as u32;
            tangible_rg.push(i as u32);
        }
    }
    (tangible_id, tangible_rg)
}

/// The outgoing rows of a tangible chain, before compression.
struct TangibleRows {
    /// Row offsets (one more than rows).
    offsets: Vec<u64>,
    /// Target of each entry.
    dst: Vec<u32>,
    /// Dictionary id of each entry.
    ids: Vec<u32>,
    /// The initial distribution over tangible markings.
    initial: Vec<(u32, f64)>,
}

/// The outgoing rows of the tangible chain of a graph with vanishing
/// markings: each edge into a vanishing marking is replaced by the
/// tangible markings its elimination reaches, entries with the same target
/// and transition merged (summed in order); the immediate firings on the
/// way are recorded in `imm`.
fn tangible_rows(
    gspn: &Gspn,
    rg: &ReachabilityGraph,
    tangible_id: &[u32],
    tangible_rg: &[u32],
    dict: &mut Dictionary,
    imm: &mut ImmediateFlows,
    stop: Interrupt<'_>,
) -> Result<TangibleRows> {
    let el = vanishing::eliminate(gspn, rg, tangible_id)?;
    stop.check(COMPILING)?;
    let mut offsets = Vec::with_capacity(tangible_rg.len() + 1);
    offsets.push(0u64);
    let (mut dst, mut ids) = (Vec::new(), Vec::new());
    let mut row: Vec<(u32, u32, f64)> = Vec::new();
    for &s in tangible_rg {
        row.clear();
        let (a, b) = rg.range(s as usize);
        for k in a..b {
            let (w, t, c) = (rg.targets[k], rg.transitions[k], rg.coeff(k));
            if tangible_id[w as usize] != NONE {
                row.push((tangible_id[w as usize], t, c));
                continue;
            }
            for &(u, q) in el.dist(w) {
                row.push((u, t, c * q));
            }
            let f = el.firings(w);
            if !f.is_empty() {
                imm.src.push(tangible_id[s as usize]);
                imm.trans.push(t);
                imm.coeff.push(c);
                imm.f_items.extend_from_slice(f);
                imm.f_start.push(imm.f_items.len() as u64);
            }
        }
        // Merge entries with the same target and transition.
        row.sort_unstable_by_key(|e| (e.0, e.1));
        let mut i = 0;
        while i < row.len() {
            let (u, t, mut c) = row[i];
            i += 1;
            while i < row.len() && row[i].0 == u && row[i].1 == t {
                c += row[i].2;
                i += 1;
            }
            dst.push(u);
            ids.push(dict.id(t, c));
        }
        offsets.push(dst.len() as u64);
    }
    let initial = if rg.vanishing[0] {
        el.dist(0).to_vec()
    } else {
        vec![(tangible_id[0], 1.0)]
    };
    Ok(TangibleRows {
        offsets,
        dst,
        ids,
        initial,
    })
}

/// The timed transitions that label at least one of the chain's
/// `entries` entries (their rates set the solve's time unit), in order.
fn firing_timed(gspn: &Gspn, dict: &Dictionary, ids: &Ids, entries: usize) -> Vec<u32> {
    let mut fires = vec![false; gspn.num_transitions()];
    for k in 0..entries {
        fires[dict.pairs[ids.get(k)].0 as usize] = true;
    }
    (0..gspn.num_transitions() as u32)
        .filter(|&t| fires[t as usize] && !gspn.is_immediate(TransitionId(t)))
        .collect()
}

/// The strongly connected components of a chain that is not irreducible,
/// its bottom components' states (in the order of [`Components::bottoms`])
/// and its transient states, each list in state order.
fn bottom_partition(outgoing: &Rows, n: usize) -> (Option<Components>, Vec<Vec<u32>>, Vec<u32>) {
    let c = Components::of(outgoing);
    let bottom_ids = c.bottoms();
    let mut bottom_index = vec![NONE; c.len()];
    for (b, &id) in bottom_ids.iter().enumerate() {
        bottom_index[id as usize] = b as u32;
    }
    let mut bottoms = vec![Vec::new(); bottom_ids.len()];
    let mut transient = Vec::new();
    for s in 0..n as u32 {
        match bottom_index[c.comp[s as usize] as usize] {
            NONE => transient.push(s),
            b => bottoms[b as usize].push(s),
        }
    }
    (Some(c), bottoms, transient)
}

/// Every choice marking of `rg` must have been resolved by a policy
/// ([`Gspn::with_policy`]): [`Error::Undecided`] names the first that was
/// not.
fn check_decided(gspn: &Gspn, rg: &ReachabilityGraph) -> Result<()> {
    let mut firable = Vec::new();
    for i in (0..rg.num_markings()).filter(|&i| rg.vanishing[i]) {
        firable.clear();
        let (a, b) = rg.range(i);
        firable.extend(rg.transitions[a..b].iter().map(|&t| TransitionId(t)));
        if gspn.is_choice(&firable) {
            let m = rg.marking(crate::reachability::MarkingId(i as u32));
            return Err(gspn.undecided(&m, &firable));
        }
    }
    Ok(())
}

impl CompiledGspn {
    /// Generates the state space of `gspn` and compiles its CTMC.
    pub fn build(gspn: &Gspn, explore: &ExploreParams) -> Result<CompiledGspn> {
        let rg = ReachabilityGraph::explore(gspn, explore)?;
        CompiledGspn::from_graph(gspn.clone(), rg)
    }

    /// Compiles the CTMC of an already generated reachability graph.
    pub fn from_graph(gspn: Gspn, rg: ReachabilityGraph) -> Result<CompiledGspn> {
        Self::from_graph_interruptible(gspn, rg, Interrupt::NEVER)
    }

    /// [`from_graph`](Self::from_graph), stopped with
    /// [`Error::Cancelled`] when `stop` is raised (checked between its
    /// stages: see [`crate::interrupt`]).
    pub fn from_graph_interruptible(
        gspn: Gspn,
        rg: ReachabilityGraph,
        stop: Interrupt<'_>,
    ) -> Result<CompiledGspn> {
        stop.check(COMPILING)?;
        stop.stage(Stage::Compiling);
        if gspn.has_decisions() {
            check_decided(&gspn, &rg)?;
        }
        let start = Instant::now();
        let (tangible_id, mut tangible_rg) = tangible_numbering(&rg);
        let n = tangible_rg.len();
        let identity = rg.stats.vanishing == 0;
        let mut dict = Dictionary::new(gspn.num_transitions());
        let mut imm = ImmediateFlows::default();
        let explore = rg.stats.clone();
        let (offsets, dst, ids, initial, mut store) = if rg.stats.vanishing == 0 {
            // Tangible ids are RG indices: the RG's edges are the chain,
            // moved, not copied.
            let ReachabilityGraph {
                store,
                offsets,
                targets,
                transitions,
                coeffs,
                ..
            } = rg;
            let mut ids = transitions;
            if let Some(cs) = coeffs {
                for (id, &c) in ids.iter_mut().zip(&cs) {
                    *id = dict.id(*id, c);
                }
            }
            (offsets, targets, ids, vec![(0u32, 1.0)], store)
        } else {
            let rows = tangible_rows(&gspn, &rg, &tangible_id, &tangible_rg, &mut dict, &mut imm, stop)?;
            (rows.offsets, rows.dst, rows.ids, rows.initial, rg.store)
        };
        store.drop_index();
        drop(tangible_id);
        if identity {
            tangible_rg = Vec::new();
        }

        // Offsets are narrowed before the value ids, while the transitions
        // are still 4 bytes wide and the incoming rows not yet allocated (the
        // peak is later).
        let dl = dict.pairs.len();
        let offsets = Offsets::new(offsets);
        let ids = Ids::new(ids, dl);
        let firing_timed = firing_timed(&gspn, &dict, &ids, dst.len());
        let outgoing = Rows {
            offsets,
            index: dst,
            ids,
            below: Vec::new(),
        };
        let entries = outgoing.index.len();
        stop.check(COMPILING)?;
        // An irreducible chain needs only the incoming rows (the transpose
        // without self-loops): exit rates and throughputs are summed from
        // them, and the outgoing rows are released while they are
        // transposed.
        let ergodic = strongly_connected(&outgoing);
        let mut self_loops = Vec::new();
        let (mut incoming, outgoing, transposed_bytes) = if ergodic {
            let held = outgoing.offsets.bytes() + outgoing.index.capacity() * 4;
            (
                incoming_rows(Outgoing::Released(outgoing), dl, &mut self_loops),
                None,
                held,
            )
        } else {
            let held = outgoing.heap_bytes();
            (
                incoming_rows(Outgoing::Kept(&outgoing), dl, &mut self_loops),
                Some(outgoing),
                held,
            )
        };
        stop.check(COMPILING)?;
        incoming.split_diagonal();

        let (components, bottoms, transient) = match outgoing.as_ref().filter(|_| !ergodic) {
            Some(outgoing) => bottom_partition(outgoing, n),
            None => (None, Vec::new(), Vec::new()),
        };
        let stats = CompileStats {
            explore,
            entries,
            distinct_values: dl,
            matrix_bytes: outgoing.as_ref().map_or(0, Rows::heap_bytes) + incoming.heap_bytes(),
            transposed_bytes,
            marking_bytes: store.heap_bytes(),
            compile_seconds: start.elapsed().as_secs_f64(),
            components: components.as_ref().map_or(1, |c| c.len()),
            bottom_components: if components.is_some() { bottoms.len() } else { 1 },
            transient_states: transient.len(),
        };
        Ok(CompiledGspn {
            gspn,
            stats,
            store,
            tangible_rg,
            num_tangible: n,
            dictionary: dict.pairs,
            outgoing,
            incoming,
            self_loops,
            imm,
            initial,
            firing_timed,
            components,
            bottoms,
            transient,
        })
    }

    /// The instantiated net.
    pub fn gspn(&self) -> &Gspn {
        &self.gspn
    }

    /// Sizes and timings.
    pub fn stats(&self) -> &CompileStats {
        &self.stats
    }

    /// Number of tangible markings (states of the CTMC).
    pub fn num_tangible(&self) -> usize {
        self.num_tangible
    }

    /// RG index (in the marking store) of tangible state `s`.
    #[inline]
    fn rg_index(&self, s: usize) -> usize {
        if self.tangible_rg.is_empty() {
            s
        } else {
            self.tangible_rg[s] as usize
        }
    }

    /// Token counts of tangible marking `s`.
    pub fn tangible_marking(&self, s: usize) -> Vec<u32> {
        let mut m = vec![0; self.gspn.num_places()];
        self.tangible_marking_into(s, &mut m);
        m
    }

    /// [`tangible_marking`](Self::tangible_marking) into `m` (one count per
    /// place), for a loop over many states without allocating.
    pub fn tangible_marking_into(&self, s: usize, m: &mut [u32]) {
        self.store.decode(self.rg_index(s), m);
    }

    /// The symbolic entries leaving tangible state `s`: `(target, transition,
    /// coefficient)`, meaning rate `rate(transition) · coefficient` from `s`
    /// to `target` (targets may equal `s`: firings that come back).
    ///
    /// Irreducible chains keep only their incoming rows (half the memory):
    /// for them this scans every entry, `O(entries)` per call, and lists the
    /// entries by target, then transition — meant for drawing small chains.
    pub fn entries_from(&self, s: usize) -> impl Iterator<Item = (u32, TransitionId, f64)> + '_ {
        let entry = |d: u32, id: usize| {
            let (t, c) = self.dictionary[id];
            (d, TransitionId(t), c)
        };
        let list: Vec<(u32, TransitionId, f64)> = match &self.outgoing {
            Some(out) => {
                let (a, b) = out.range(s);
                (a..b).map(|k| entry(out.index[k], out.ids.get(k))).collect()
            }
            None => {
                let inc = &self.incoming;
                let mut list: Vec<(u32, TransitionId, f64)> = (0..inc.len())
                    .flat_map(|j| {
                        let (a, b) = inc.range(j);
                        (a..b)
                            .filter(move |&k| inc.index[k] as usize == s)
                            .map(move |k| (j as u32, inc.ids.get(k)))
                    })
                    .chain(
                        self.self_loops
                            .iter()
                            .filter(|e| e.0 as usize == s)
                            .map(|e| (e.0, e.1 as usize)),
                    )
                    .map(|(d, id)| entry(d, id))
                    .collect();
                list.sort_by_key(|e| (e.0, e.1));
                list
            }
        };
        list.into_iter()
    }

    /// Distribution over tangible markings reached from `M0` in zero time.
    pub fn initial_distribution(&self) -> &[(u32, f64)] {
        &self.initial
    }

    /// Tangible states of each bottom strongly connected component (empty
    /// when the chain is irreducible).
    pub fn bottom_components(&self) -> &[Vec<u32>] {
        &self.bottoms
    }

    /// Whether the chain is irreducible (ergodic).
    pub fn is_ergodic(&self) -> bool {
        self.components.is_none()
    }

    /// Approximate heap bytes of the compiled chain.
    pub fn heap_bytes(&self) -> usize {
        self.store.heap_bytes()
            + self.tangible_rg.capacity() * 4
            + self.outgoing.as_ref().map_or(0, Rows::heap_bytes)
            + self.incoming.heap_bytes()
            + self.self_loops.capacity() * 8
            + self.dictionary.capacity() * 16
            + self.components.as_ref().map_or(0, |c| c.comp.capacity() * 4)
    }

    /// Where the memory goes, component by component, from the capacities
    /// of the allocations (see [`MemoryAccount`]); the solve's part comes
    /// from `solution` (its solver's vectors, the exit rates and the
    /// dictionary's values), nothing without one.
    pub fn memory_account(&self, solution: Option<&Solution>) -> MemoryAccount {
        let n = self.num_tangible();
        let ex = &self.stats.explore;
        let mut parts = Vec::new();
        let mut add = |component: &'static str, stage: &'static str, bytes: usize| {
            parts.push(MemoryPart {
                component,
                stage,
                bytes: bytes as u64,
                bytes_per_marking: bytes as f64 / n.max(1) as f64,
            });
        };
        add("hash index of the markings", "generation", ex.index_bytes);
        add(
            "graph: edges, offsets, vanishing flags",
            "generation",
            ex.edge_bytes,
        );
        if self.outgoing.is_none() {
            add(
                "outgoing rows: offsets, indices (released by the transpose)",
                "compile",
                self.stats.transposed_bytes,
            );
        }
        add("packed markings", "chain", self.store.heap_bytes());
        add("tangible → graph index", "chain", self.tangible_rg.capacity() * 4);
        let inc = &self.incoming;
        add("incoming rows: offsets", "chain", inc.offsets.bytes());
        add("incoming rows: column indices", "chain", inc.index.capacity() * 4);
        add("incoming rows: value ids", "chain", inc.ids.bytes());
        add("incoming rows: diagonal split", "chain", inc.below.capacity() * 4);
        if let Some(out) = &self.outgoing {
            add("outgoing rows (reducible chain)", "chain", out.heap_bytes());
        }
        add("self-loops", "chain", self.self_loops.capacity() * 8);
        let imm = &self.imm;
        add(
            "vanishing: timed firings into them and their flows",
            "chain",
            imm.src.capacity() * 4
                + imm.trans.capacity() * 4
                + imm.coeff.capacity() * 8
                + imm.f_start.capacity() * 8
                + imm.f_items.capacity() * 16
                + self.initial.capacity() * 16,
        );
        add(
            "dictionary, components",
            "chain",
            self.dictionary.capacity() * 16
                + self
                    .components
                    .as_ref()
                    .map_or(0, |c| c.comp.capacity() * 4 + c.bottom.capacity())
                + self.bottoms.iter().map(|b| b.capacity() * 4).sum::<usize>()
                + self.transient.capacity() * 4,
        );
        if let Some(sol) = solution {
            add(
                "exit rates and values",
                "solve",
                n * 8 + self.dictionary.len() * 8,
            );
            add(
                "solver vectors (π included)",
                "solve",
                sol.info.vector_bytes as usize,
            );
        }
        let sum = |stages: &[&str]| -> u64 {
            parts
                .iter()
                .filter(|p| stages.contains(&p.stage))
                .map(|p| p.bytes)
                .sum()
        };
        let generation_bytes = sum(&["generation"]) + ex.marking_bytes as u64;
        let below = inc.below.capacity() as u64 * 4;
        let compile_bytes = sum(&["compile", "chain"]) - below;
        let solve_bytes = sum(&["chain", "solve"]);
        MemoryAccount {
            tangible_markings: n,
            generation_bytes,
            compile_bytes,
            solve_bytes,
            peak_bytes: generation_bytes.max(compile_bytes).max(solve_bytes),
            guard_estimate_bytes: {
                // What the guard compared with its limit after the last
                // round of generation (the arrays were shrunk since).
                let marking_bytes = (ex.markings * ex.words_per_marking * 8) as u64;
                crate::reachability::guard_bytes(
                    marking_bytes + (ex.index_bytes + ex.edge_bytes) as u64,
                    marking_bytes,
                    ex.markings,
                    ex.edges,
                )
            },
            parts,
        }
    }

    /// Evaluates the rates from the net's parameters with `overrides`, and
    /// solves.
    pub fn solve(
        &self,
        overrides: &Params,
        default_rate: Option<f64>,
        params: &SolveParams,
    ) -> Result<Solution> {
        let rates = self.gspn.rates(overrides, default_rate)?;
        self.solve_rates(&rates, params)
    }

    /// Solves for a vector of rates indexed by transition (entries of
    /// immediate transitions are ignored). Nothing structural is rebuilt.
    ///
    /// Errors: a rate that is not a finite number > 0
    /// ([`Error::InvalidValue`]), rates more than [`MAX_RATE_SPREAD`] apart
    /// ([`Error::RateSpread`]), solver failures ([`Error::NoConvergence`],
    /// [`Error::Singular`]), and a result that is not finite
    /// ([`Error::NotFinite`]) — never a NaN in the solution.
    pub fn solve_rates(&self, rates: &[f64], params: &SolveParams) -> Result<Solution> {
        self.solve_rates_interruptible(rates, params, Interrupt::NEVER)
    }

    /// [`solve_rates`](Self::solve_rates), stopped with
    /// [`Error::Cancelled`] when `stop` is raised (checked before each linear
    /// solve and at every sweep of an iterative one: see
    /// [`crate::interrupt`]).
    pub fn solve_rates_interruptible(
        &self,
        rates: &[f64],
        params: &SolveParams,
        stop: Interrupt<'_>,
    ) -> Result<Solution> {
        let start = Instant::now();
        params.validate()?;
        self.gspn.check_rates(rates)?;
        // Solve in the time unit of the fastest rate (docs/gspn.md, *Steady-state methods*: rates far
        // apart must not break the solver): every value is then at most its
        // coefficient, so no exit rate or elimination entry overflows, and
        // π does not depend on the time unit. Throughputs are scaled back.
        let scale = self.rate_scale(rates)?;
        let values: Vec<f64> = self
            .dictionary
            .iter()
            .map(|&(t, c)| rates[t as usize] / scale * c)
            .collect();
        let exit = self.exit_rates(&values);
        let chain = Chain {
            incoming: &self.incoming,
            values: &values,
            exit: &exit,
        };
        // π is allocated once the solver returns (an irreducible chain's
        // solver hands its own vector over): no extra vector during the solve.
        let Reducible {
            mut pi,
            mut info,
            absorption_residual,
            bottom_probabilities,
        } = match &self.components {
            None => {
                let (pi, info) = steady_state::solve(&chain, None, params, stop)?;
                Reducible {
                    pi,
                    info,
                    absorption_residual: 0.0,
                    bottom_probabilities: vec![1.0],
                }
            }
            Some(components) => self.solve_reducible(components, &values, &exit, params, stop)?,
        };
        // Absorption probabilities come from a numerical solve: renormalise so
        // that the distribution sums to 1 to rounding.
        let total: f64 = pi.iter().sum();
        if total > 0.0 && (total - 1.0).abs() > 0.0 {
            pi.iter_mut().for_each(|v| *v /= total);
        }
        info.residual = steady_state::residual(&chain, &pi, None);
        info.seconds = start.elapsed().as_secs_f64();
        let throughput = self.throughputs(&pi, rates, &values, scale);
        let (mean_tokens, prob_nonempty) = self.place_measures(&pi);
        self.check_finite(
            &pi,
            &throughput,
            &mean_tokens,
            &[
                ("the residual of the balance equations", info.residual),
                ("the residual of the absorption equations", absorption_residual),
            ],
            &bottom_probabilities,
        )?;
        Ok(Solution {
            pi,
            rates: rates.to_vec(),
            throughput,
            mean_tokens,
            prob_nonempty,
            info,
            absorption_residual,
            bottom_probabilities,
        })
    }

    /// The steady state of a chain that is not irreducible: the probability
    /// of ending in each bottom component (from the initial distribution,
    /// through the transient states' absorption equations), times each
    /// bottom component's own steady state.
    fn solve_reducible(
        &self,
        components: &Components,
        values: &[f64],
        exit: &[f64],
        params: &SolveParams,
        stop: Interrupt<'_>,
    ) -> Result<Reducible> {
        let n = self.num_tangible();
        let mut pi = vec![0.0; n];
        // Probability of ending in each bottom component.
        let mut init = vec![0.0; n];
        for &(s, p) in &self.initial {
            init[s as usize] += p;
        }
        let mut comp_prob = vec![0.0; components.len()];
        for (s, &p) in init.iter().enumerate() {
            comp_prob[components.comp[s] as usize] += p;
        }
        let mut absorption_bytes = 0;
        let mut absorption_residual = 0.0;
        if !self.transient.is_empty() {
            let sub = self.sub_chain(&self.transient)?;
            let sub_exit: Vec<f64> = self.transient.iter().map(|&s| exit[s as usize]).collect();
            let sub_chain = Chain {
                incoming: &sub,
                values,
                exit: &sub_exit,
            };
            let b: Vec<f64> = self.transient.iter().map(|&s| init[s as usize]).collect();
            let (x, ai) = steady_state::solve(&sub_chain, Some(&b), params, stop)?;
            absorption_residual = ai.residual;
            absorption_bytes = ai.vector_bytes;
            let out = self.outgoing()?;
            for (&s, &xs) in self.transient.iter().zip(&x) {
                let (a, b) = out.range(s as usize);
                for k in a..b {
                    let c = components.comp[out.index[k] as usize] as usize;
                    if components.bottom[c] {
                        comp_prob[c] += xs * values[out.ids.get(k)];
                    }
                }
            }
        }
        let mut info = SolveInfo {
            method: "trivial",
            vector_bytes: absorption_bytes,
            ..SolveInfo::default()
        };
        let mut bottom_probabilities = Vec::new();
        let mut largest = 0;
        for states in &self.bottoms {
            let prob = comp_prob[components.comp[states[0] as usize] as usize];
            bottom_probabilities.push(prob);
            let sub = self.sub_chain(states)?;
            let sub_exit: Vec<f64> = states.iter().map(|&s| exit[s as usize]).collect();
            let sub_chain = Chain {
                incoming: &sub,
                values,
                exit: &sub_exit,
            };
            let (x, i) = steady_state::solve(&sub_chain, None, params, stop)?;
            if states.len() >= largest {
                largest = states.len();
                info.method = i.method;
            }
            info.iterations += i.iterations;
            info.vector_bytes = info.vector_bytes.max(i.vector_bytes);
            for (&s, &v) in states.iter().zip(&x) {
                pi[s as usize] = prob * v;
            }
        }
        Ok(Reducible {
            pi,
            info,
            absorption_residual,
            bottom_probabilities,
        })
    }

    /// The fastest rate of a timed transition that fires in the chain (the
    /// time unit of the solve), after checking that the slowest is within
    /// [`MAX_RATE_SPREAD`] of it. 1 when no timed transition fires.
    fn rate_scale(&self, rates: &[f64]) -> Result<f64> {
        let (mut fastest, mut slowest) = (None::<usize>, None::<usize>);
        for t in self.firing_timed.iter().map(|&t| t as usize) {
            if fastest.is_none_or(|f| rates[t] > rates[f]) {
                fastest = Some(t);
            }
            if slowest.is_none_or(|s| rates[t] < rates[s]) {
                slowest = Some(t);
            }
        }
        let (Some(f), Some(s)) = (fastest, slowest) else {
            return Ok(1.0);
        };
        let ratio = rates[f] / rates[s];
        // Both rates are finite and > 0: the ratio is a number (maybe ∞).
        if ratio > MAX_RATE_SPREAD {
            let names = self.gspn.transition_names();
            return Err(Error::RateSpread {
                fastest: names[f].clone(),
                max: rates[f],
                slowest: names[s].clone(),
                min: rates[s],
                ratio,
                limit: MAX_RATE_SPREAD,
            });
        }
        // A power of two: scaling is then exact (π, throughputs: the same
        // bits as in the rates' own unit, as long as nothing overflows).
        let e = rates[f].log2().floor().clamp(-1022.0, 1023.0) as i64;
        Ok(f64::from_bits(((e + 1023) as u64) << 52))
    }

    /// Every number of a solution is finite, or the error names the first
    /// that is not.
    fn check_finite(
        &self,
        pi: &[f64],
        throughput: &[f64],
        mean_tokens: &[f64],
        residuals: &[(&str, f64)],
        bottom_probabilities: &[f64],
    ) -> Result<()> {
        let not_finite = |what: String, value: f64, cause: &str| Error::NotFinite {
            what,
            value,
            cause: cause.to_string(),
        };
        let solver = "the steady-state solve lost all precision (rates or weights too far apart?)";
        if let Some(s) = pi.iter().position(|p| !p.is_finite()) {
            return Err(not_finite(
                format!("the probability of tangible marking {s}"),
                pi[s],
                solver,
            ));
        }
        if let Some(b) = bottom_probabilities.iter().position(|p| !p.is_finite()) {
            return Err(not_finite(
                format!("the probability of reaching bottom component {b}"),
                bottom_probabilities[b],
                solver,
            ));
        }
        for &(what, r) in residuals {
            if !r.is_finite() {
                return Err(not_finite(what.to_string(), r, solver));
            }
        }
        if let Some(t) = throughput.iter().position(|x| !x.is_finite()) {
            return Err(not_finite(
                format!(
                    "the throughput of transition `{}`",
                    self.gspn.transition_names()[t]
                ),
                throughput[t],
                "a rate times its enabling degree exceeds the largest double",
            ));
        }
        if let Some(p) = mean_tokens.iter().position(|x| !x.is_finite()) {
            return Err(not_finite(
                format!("the mean token count of place `{}`", self.gspn.place_names()[p]),
                mean_tokens[p],
                solver,
            ));
        }
        Ok(())
    }

    /// Exit rates (self-loops excluded), summed from the incoming rows in
    /// row order: `exit_i = Σ_j Σ_{(i, id) ∈ in(j)} values[id]`.
    fn exit_rates(&self, values: &[f64]) -> Vec<f64> {
        let inc = &self.incoming;
        let mut exit = vec![0.0; self.num_tangible()];
        for j in 0..inc.len() {
            let (a, b) = inc.range(j);
            for k in a..b {
                exit[inc.index[k] as usize] += values[inc.ids.get(k)];
            }
        }
        exit
    }

    /// The outgoing rows, which chains that are not irreducible keep.
    fn outgoing(&self) -> Result<&Rows> {
        self.outgoing.as_ref().ok_or_else(|| {
            Error::Invalid("internal: the outgoing rows of an irreducible chain were released".into())
        })
    }

    /// Incoming rows of the chain restricted to `states` (sorted), in local
    /// indices; value ids are shared with the whole chain.
    fn sub_chain(&self, states: &[u32]) -> Result<Rows> {
        let out = self.outgoing()?;
        let mut local = vec![NONE; self.num_tangible()];
        for (i, &s) in states.iter().enumerate() {
            local[s as usize] = i as u32;
        }
        let mut entries = Vec::new();
        for (i, &s) in states.iter().enumerate() {
            let (a, b) = out.range(s as usize);
            for k in a..b {
                let d = out.index[k] as usize;
                if d != s as usize && local[d] != NONE {
                    entries.push((local[d], i as u32, out.ids.get(k) as u32));
                }
            }
        }
        Ok(Rows::from_entries(states.len(), entries, self.dictionary.len()))
    }

    /// Throughputs from `values` (rates divided by `scale`, times their
    /// coefficients), in the rates' own time unit.
    fn throughputs(&self, pi: &[f64], rates: &[f64], values: &[f64], scale: f64) -> Vec<f64> {
        let mut x = vec![0.0; self.gspn.num_transitions()];
        let inc = &self.incoming;
        let mut add = |s: usize, id: usize| {
            let p = pi[s];
            if p != 0.0 {
                x[self.dictionary[id].0 as usize] += p * values[id] * scale;
            }
        };
        for j in 0..inc.len() {
            let (a, b) = inc.range(j);
            for k in a..b {
                add(inc.index[k] as usize, inc.ids.get(k));
            }
        }
        for &(s, id) in &self.self_loops {
            add(s as usize, id as usize);
        }
        let imm = &self.imm;
        for e in 0..imm.src.len() {
            let p = pi[imm.src[e] as usize];
            if p == 0.0 {
                continue;
            }
            let flow = p * rates[imm.trans[e] as usize] * imm.coeff[e];
            for &(u, count) in &imm.f_items[imm.f_start[e] as usize..imm.f_start[e + 1] as usize] {
                x[u as usize] += flow * count;
            }
        }
        x
    }

    fn place_measures(&self, pi: &[f64]) -> (Vec<f64>, Vec<f64>) {
        let np = self.gspn.num_places();
        let mut mean = vec![0.0; np];
        let mut nonempty = vec![0.0; np];
        for (s, &p) in pi.iter().enumerate() {
            if p == 0.0 {
                continue;
            }
            let i = self.rg_index(s);
            for q in 0..np {
                let k = self.store.tokens(i, q);
                if k > 0 {
                    mean[q] += p * f64::from(k);
                    nonempty[q] += p;
                }
            }
        }
        (mean, nonempty)
    }

    /// Long-run mean of a measure expression over tangible markings (the
    /// probability of a condition such as `#P1 = 1 and #P7 = 1`, or the mean
    /// of an arithmetic expression such as `#P1 + 2 * #P2`). Parameters in it
    /// take the net's bound values.
    pub fn measure(&self, solution: &Solution, expr: &Expr) -> Result<f64> {
        let names = self.gspn.place_names();
        let params = self.gspn.params();
        let compiled = expr.compile(&|n| names.iter().position(|p| p == n), &|n| {
            params.get(n).copied().flatten()
        })?;
        let mut m = vec![0; self.gspn.num_places()];
        let mut stack = Vec::new();
        let mut sum = 0.0;
        for (s, &p) in solution.pi.iter().enumerate() {
            if p == 0.0 {
                continue;
            }
            self.store.decode(self.rg_index(s), &mut m);
            let v = compiled.eval(&m, &mut stack);
            if !v.is_finite() {
                return Err(Error::NotFinite {
                    what: format!("the measure `{expr}` in marking {}", self.gspn.format_marking(&m)),
                    value: v,
                    cause: "the expression divides by zero or overflows there".into(),
                });
            }
            sum += p * v;
        }
        if !sum.is_finite() {
            return Err(Error::NotFinite {
                what: format!("the long-run mean of `{expr}`"),
                value: sum,
                cause: "its values are too large to sum in double precision".into(),
            });
        }
        Ok(sum)
    }
}
