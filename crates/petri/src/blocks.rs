//! Block-triangular solves of `x M = b` for `M = s·I + c·A`, where `A = diag(out) − R` is
//! the negated generator of a chain's transient states (`R` the rates
//! between them, `out` each state's exit rate).
//!
//! Ordering the states by the chain's strongly connected components in
//! topological order makes `M` block triangular: each component's unknowns
//! follow from those of the components before it by substitution, and only the diagonal blocks are
//! factorised — by a division for a component of one state, by an LU
//! without pivoting in a profile-reducing order stored by profile
//! ([`crate::profile_lu`], which says why no pivoting is needed: `M` is
//! row diagonally dominant) up to [`DENSE_BLOCK_LIMIT`] states, by a sparse
//! LU above. Components whose blocks are equal entry for entry share one
//! factorisation (the same sub-chain in many contexts). Each component's
//! states are kept in its factor's order, and a vector kept in that order
//! throughout ([`BlockSystem::order`], as the time steps do) is solved in
//! place, each component's unknowns contiguous. Chains that
//! finish (a behaviour tree's run, a mission) are mostly such sequences of
//! small components, so the cost is `O(states + entries + Σ f)` per solve
//! over the factors' stored entries `f` (at most `k²` for `k` states),
//! against the fill-in of a sparse LU of the whole matrix.
//!
//! Used by [`crate::absorption`] for the absorbing chain's two linear
//! systems and for every implicit time step of its time distribution.

use faer::Mat;
use faer::prelude::Solve;
use faer::sparse::linalg::solvers::Lu;
use faer::sparse::{SparseColMat, Triplet};
use hashbrown::HashMap;

use crate::error::{Error, Result};
use crate::profile_lu::{ProfileLu, profile_order};
use crate::scc::{Successors, tarjan};

/// Components up to this size get a dense LU; larger ones a sparse LU.
pub(crate) const DENSE_BLOCK_LIMIT: usize = 400;

/// Compressed rows: `start[i]..start[i + 1]` in `cols`/`vals`.
#[derive(Debug, Default)]
struct Csr {
    start: Vec<u32>,
    cols: Vec<u32>,
    vals: Vec<f64>,
}

impl Csr {
    /// Rows of `(row, col, value)` entries (any order).
    fn new(n: usize, entries: impl Iterator<Item = (u32, u32, f64)> + Clone) -> Csr {
        let mut start = vec![0u32; n + 1];
        for (r, _, _) in entries.clone() {
            start[r as usize + 1] += 1;
        }
        for i in 0..n {
            start[i + 1] += start[i];
        }
        let nnz = start[n] as usize;
        let mut cursor = start.clone();
        let mut cols = vec![0u32; nnz];
        let mut vals = vec![0.0; nnz];
        for (r, c, v) in entries {
            let k = cursor[r as usize] as usize;
            cols[k] = c;
            vals[k] = v;
            cursor[r as usize] += 1;
        }
        Csr { start, cols, vals }
    }

    #[inline]
    fn row(&self, i: usize) -> impl Iterator<Item = (u32, f64)> + '_ {
        let r = self.start[i] as usize..self.start[i + 1] as usize;
        self.cols[r.clone()]
            .iter()
            .copied()
            .zip(self.vals[r].iter().copied())
    }
}

impl Successors for Csr {
    fn num_nodes(&self) -> usize {
        self.start.len() - 1
    }

    fn successors(&self, v: u32) -> &[u32] {
        &self.cols[self.start[v as usize] as usize..self.start[v as usize + 1] as usize]
    }
}

/// The factorised diagonal block of one component.
enum Block {
    /// One state: its diagonal entry.
    Scalar(f64),
    /// Index in [`BlockSystem::dense`] (components with equal blocks share one).
    Dense(usize),
    /// A sparse LU of the block's transpose.
    Sparse(Box<Lu<usize, f64>>),
}

/// A component's pattern (`v` its states, sorted; their positions in `v`
/// written to `local`): the component's size, then one bit per entry of the
/// `k × k` block, the diagonal included.
fn pattern_key(v: &[u32], graph: &Csr, comp: &[u32], local: &mut [u32]) -> Vec<u64> {
    let k = v.len();
    for (i, &st) in v.iter().enumerate() {
        local[st as usize] = i as u32;
    }
    let mut key = vec![0u64; (k * k).div_ceil(64) + 1];
    key[0] = k as u64;
    let mut set = |e: usize| key[1 + e / 64] |= 1 << (e % 64);
    for (i, &st) in v.iter().enumerate() {
        set(i * k + i);
        for &j in graph.successors(st) {
            if comp[j as usize] == comp[st as usize] {
                set(local[j as usize] as usize * k + i);
            }
        }
    }
    key
}

/// The block pattern of a [`pattern_key`] as a matrix of ones and zeros.
fn pattern_matrix(k: usize, key: &[u64]) -> Vec<f64> {
    (0..k * k)
        .map(|e| {
            if key[1 + e / 64] >> (e % 64) & 1 == 1 {
                1.0
            } else {
                0.0
            }
        })
        .collect()
}

/// `M = s·I + c·A` factorised block by block.
pub(crate) struct BlockSystem {
    /// States grouped by component, components in topological order
    /// (every entry `M_ij` between components goes from an earlier `i` to a later `j`).
    states: Vec<u32>,
    /// `comp_start[b]..comp_start[b + 1]` in `states`.
    comp_start: Vec<u32>,
    /// Position of each state in its component.
    local: Vec<u32>,
    /// Component of each state.
    comp: Vec<u32>,
    blocks: Vec<Block>,
    /// The distinct dense factorisations: components whose diagonal blocks
    /// are equal entry for entry (the same sub-chain repeated in another
    /// context, as a finishing chain's phases often are) share one, which
    /// keeps the factors a time step reads in cache.
    dense: Vec<ProfileLu>,
    /// Entries between components, by column, both indices positions in
    /// `states` (filled once the factors have fixed the order).
    cols: Csr,
}

impl BlockSystem {
    /// Factorises `s·I + c·(diag(out) − R)` with `R` given as `(from, to,
    /// rate)` entries (`from ≠ to`, duplicates summed). Errors: a singular
    /// diagonal block (`what` names the system).
    pub(crate) fn new(
        what: &'static str,
        out: &[f64],
        inner: &[(u32, u32, f64)],
        s: f64,
        c: f64,
    ) -> Result<BlockSystem> {
        let n = out.len();
        let graph = Csr::new(n, inner.iter().map(|&(i, j, r)| (i, j, r)));
        // Tarjan reports sink components first: reversed, a topological order.
        let mut found: Vec<Vec<u32>> = Vec::new();
        tarjan(
            &graph,
            |_| true,
            |scc: &[u32]| -> std::result::Result<(), ()> {
                let mut v = scc.to_vec();
                v.sort_unstable();
                found.push(v);
                Ok(())
            },
        )
        .map_err(|()| Error::Invalid("component search stopped".into()))?;
        found.reverse();
        let mut states = Vec::with_capacity(n);
        let mut comp_start = vec![0u32];
        let mut local = vec![0u32; n];
        let mut comp = vec![0u32; n];
        // Profile orders already found, by the components' patterns.
        let mut orders: HashMap<Vec<u64>, Vec<u32>> = HashMap::new();
        for (b, v) in found.iter().enumerate() {
            for &st in v {
                comp[st as usize] = b as u32;
            }
        }
        for v in &found {
            // A component's states in the profile order of its pattern (the
            // order depends on the chain's pattern only, so every system of
            // the same chain numbers its vectors alike).
            let ordered = if v.len() > 1 && v.len() <= DENSE_BLOCK_LIMIT {
                let order = orders
                    .entry(pattern_key(v, &graph, &comp, &mut local))
                    .or_insert_with_key(|key| profile_order(v.len(), &pattern_matrix(v.len(), key)));
                order.iter().map(|&o| v[o as usize]).collect()
            } else {
                v.clone()
            };
            for (k, &st) in ordered.iter().enumerate() {
                local[st as usize] = k as u32;
            }
            states.extend_from_slice(&ordered);
            comp_start.push(states.len() as u32);
        }
        let mut sys = BlockSystem {
            states,
            comp_start,
            local,
            comp,
            blocks: Vec::with_capacity(found.len()),
            dense: Vec::new(),
            cols: Csr::default(),
        };
        sys.factor(what, out, &graph, s, c)?;
        // Entries between components, by column: M_ij = −c·r_ij, at the
        // states' final positions.
        let mut pos = vec![0u32; n];
        for (k, &st) in sys.states.iter().enumerate() {
            pos[st as usize] = k as u32;
        }
        let comp = &sys.comp;
        sys.cols = Csr::new(
            n,
            inner
                .iter()
                .filter(|&&(i, j, _)| comp[i as usize] != comp[j as usize])
                .map(|&(i, j, r)| (pos[j as usize], pos[i as usize], -c * r)),
        );
        Ok(sys)
    }

    fn factor(&mut self, what: &'static str, out: &[f64], graph: &Csr, s: f64, c: f64) -> Result<()> {
        let singular = |detail: String| Error::Singular { what, detail };
        // Dense blocks already factorised, by their entries (positions and bits).
        let mut seen: HashMap<Vec<u64>, usize> = HashMap::new();
        for b in 0..self.comp_start.len() - 1 {
            let members = &self.states[self.comp_start[b] as usize..self.comp_start[b + 1] as usize];
            let k = members.len();
            let diag = |st: u32| s + c * out[st as usize];
            let block = if k == 1 {
                let d = diag(members[0]);
                if !(d != 0.0 && d.is_finite()) {
                    return Err(singular(format!("a state with diagonal entry {d}")));
                }
                Block::Scalar(d)
            } else {
                // Entries inside the component, by local index.
                let mut entries: Vec<(usize, usize, f64)> = Vec::new();
                for &st in members {
                    let i = self.local[st as usize] as usize;
                    entries.push((i, i, diag(st)));
                    for (j, r) in graph.row(st as usize) {
                        if self.comp[j as usize] == b as u32 {
                            entries.push((i, self.local[j as usize] as usize, -c * r));
                        }
                    }
                }
                if k <= DENSE_BLOCK_LIMIT {
                    // The block's entries by position, duplicates summed in
                    // the order they came (as a dense accumulation would):
                    // the key of equal blocks, and the matrix if new.
                    // (Rows come in order, each row's entries in the
                    // graph's order: a stable sort of each row by column.)
                    let mut row = 0;
                    while row < entries.len() {
                        let i = entries[row].0;
                        let end = row + entries[row..].iter().take_while(|e| e.0 == i).count();
                        entries[row..end].sort_by_key(|&(_, j, _)| j);
                        row = end;
                    }
                    debug_assert!(entries.windows(2).all(|w| (w[0].0, w[0].1) <= (w[1].0, w[1].1)));
                    let mut key: Vec<u64> = Vec::with_capacity(1 + 2 * entries.len());
                    key.push(k as u64);
                    let mut e = 0;
                    while e < entries.len() {
                        let (i, j, mut v) = entries[e];
                        e += 1;
                        while e < entries.len() && (entries[e].0, entries[e].1) == (i, j) {
                            v += entries[e].2;
                            e += 1;
                        }
                        key.extend([((i as u64) << 32) | j as u64, v.to_bits()]);
                    }
                    let d = match seen.get(&key) {
                        Some(&d) => d,
                        None => {
                            // The block's transpose, row-major.
                            let mut a = vec![0.0; k * k];
                            for pair in key[1..].chunks_exact(2) {
                                let (i, j) = ((pair[0] >> 32) as usize, (pair[0] & 0xFFFF_FFFF) as usize);
                                a[j * k + i] = f64::from_bits(pair[1]);
                            }
                            let lu = ProfileLu::new(k, a)
                                .ok_or_else(|| singular(format!("a component of {k} states is singular")))?;
                            self.dense.push(lu);
                            seen.insert(key, self.dense.len() - 1);
                            self.dense.len() - 1
                        }
                    };
                    Block::Dense(d)
                } else {
                    let lu_of = |t: &[Triplet<usize, usize, f64>]| -> Result<Lu<usize, f64>> {
                        SparseColMat::<usize, f64>::try_new_from_triplets(k, k, t)
                            .map_err(|e| singular(format!("cannot build the sparse matrix: {e:?}")))?
                            .sp_lu()
                            .map_err(|e| singular(format!("sparse LU failed: {e:?}")))
                    };
                    let tt: Vec<_> = entries.iter().map(|&(i, j, v)| Triplet::new(j, i, v)).collect();
                    Block::Sparse(Box::new(lu_of(&tt)?))
                }
            };
            self.blocks.push(block);
        }
        Ok(())
    }

    /// The order the system keeps a vector in: position → state. A
    /// vector in this order is solved by [`BlockSystem::solve_ordered`]
    /// with every component's unknowns contiguous. It depends on the
    /// pattern of `inner` only (not on the rates, `s` or `c`).
    pub(crate) fn order(&self) -> &[u32] {
        &self.states
    }

    /// A vector indexed by state, copied into [`BlockSystem::order`].
    pub(crate) fn ordered(&self, v: &[f64]) -> Vec<f64> {
        self.states.iter().map(|&st| v[st as usize]).collect()
    }

    /// Solves the row system `x M = b` (that is `Mᵀ xᵀ = bᵀ`), in place,
    /// `b` indexed by state (one copy into [`BlockSystem::order`] and back).
    pub(crate) fn solve_row(&self, b: &mut [f64]) {
        let mut y = self.ordered(b);
        self.solve_ordered(&mut y);
        for (&st, &v) in self.states.iter().zip(&y) {
            b[st as usize] = v;
        }
    }

    /// Solves `x M = b` in place with `b` in [`BlockSystem::order`]: each
    /// component's right-hand side (its entries minus the contributions of
    /// the components before) is formed where it lies and solved there,
    /// without allocating (but for components beyond [`DENSE_BLOCK_LIMIT`]).
    pub(crate) fn solve_ordered(&self, b: &mut [f64]) {
        for (blk, block) in self.blocks.iter().enumerate() {
            let range = self.comp_start[blk] as usize..self.comp_start[blk + 1] as usize;
            for j in range.clone() {
                let s: f64 = self.cols.row(j).map(|(i, v)| b[i as usize] * v).sum();
                b[j] -= s;
            }
            let y = &mut b[range];
            match block {
                Block::Scalar(d) => y[0] /= d,
                Block::Dense(i) => self.dense[*i].solve(y),
                Block::Sparse(lu) => {
                    let mut m = Mat::<f64>::from_fn(y.len(), 1, |i, _| y[i]);
                    lu.solve_in_place(&mut m);
                    for (i, v) in y.iter_mut().enumerate() {
                        *v = m[(i, 0)];
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// `x M = b` by a dense LU of the whole `Mᵀ`.
    fn dense_row_solve(out: &[f64], inner: &[(u32, u32, f64)], s: f64, c: f64, b: &[f64]) -> Vec<f64> {
        let n = out.len();
        let mut m = Mat::<f64>::zeros(n, n);
        for i in 0..n {
            m[(i, i)] = s + c * out[i];
        }
        for &(i, j, r) in inner {
            m[(i as usize, j as usize)] -= c * r;
        }
        let mt = m.transpose().to_owned();
        let x = mt.partial_piv_lu().solve(Mat::<f64>::from_fn(n, 1, |i, _| b[i]));
        (0..n).map(|i| x[(i, 0)]).collect()
    }

    proptest! {
        /// Random chains — `copies` copies of a random sub-chain, each
        /// leading to the next, their states interleaved in the numbering,
        /// so that equal blocks repeat — solved block by block agree with a
        /// dense solve, for the absorption's `s = 0` and a time step's `s = 1`.
        #[test]
        fn block_solve_matches_dense_solve(
            m in 1usize..40,
            copies in 1usize..4,
            edges in proptest::collection::vec((0usize..1000, 0usize..1000, 0.01f64..5.0), 0..200),
            leaks in proptest::collection::vec(0.001f64..1.0, 40),
            time_step in any::<bool>(),
        ) {
            let n = m * copies;
            let id = |t: usize, i: usize| (t + copies * i) as u32;
            let mut inner = Vec::new();
            let mut out = vec![0.0; n];
            for t in 0..copies {
                for &(i, j, r) in &edges {
                    let (i, j) = (i % m, j % m);
                    if i != j {
                        inner.push((id(t, i), id(t, j), r));
                    }
                }
                // On to the next copy (or out of the chain, for the last).
                if t + 1 < copies {
                    inner.push((id(t, 0), id(t + 1, 0), 1.0));
                }
                out[id(t, 0) as usize] += 1.0;
                for (i, &l) in leaks[..m].iter().enumerate() {
                    out[id(t, i) as usize] += l;
                }
            }
            for &(i, _, r) in inner.iter().filter(|&&(i, j, _)| (i as usize % copies) == (j as usize % copies)) {
                out[i as usize] += r;
            }
            let (s, c) = if time_step { (1.0, 0.35) } else { (0.0, 1.0) };
            let b: Vec<f64> = (0..n).map(|i| 0.5 + (i % 4) as f64).collect();
            let want = dense_row_solve(&out, &inner, s, c, &b);
            let sys = BlockSystem::new("test", &out, &inner, s, c).unwrap();
            let mut got = b.clone();
            sys.solve_row(&mut got);
            for (g, w) in got.iter().zip(&want) {
                prop_assert!((g - w).abs() <= 1e-10 * w.abs().max(1.0), "{} vs {}", g, w);
            }
        }
    }

    /// The block solve against a dense solve of the same system, on a
    /// chain with a cycle, a branch and a large component.
    #[test]
    fn matches_a_dense_solve() {
        // 0 → {1 ⇄ 2} → 3, 0 → 3, and a ring 4 → 5 → … → 4 reached from 3.
        // … and from 3 also a dense component: a ring of 37 with chords.
        let ring = 450u32;
        let (small, s0) = (37u32, 4 + 450u32);
        let n = (s0 + small) as usize;
        let mut inner = vec![
            (0, 1, 1.0),
            (1, 2, 2.0),
            (2, 1, 0.5),
            (2, 3, 1.5),
            (0, 3, 0.25),
            (3, 4, 1.0),
            (3, s0, 0.5),
        ];
        for k in 0..ring {
            inner.push((4 + k, 4 + (k + 1) % ring, 3.0 + f64::from(k % 7)));
        }
        for k in 0..small {
            inner.push((s0 + k, s0 + (k + 1) % small, 2.0 + f64::from(k % 5)));
            inner.push((s0 + k, s0 + (k * 7 + 3) % small, 0.5 + f64::from(k % 3)));
        }
        inner.retain(|&(i, j, _)| i != j);
        let mut out = vec![0.0; n];
        for &(i, _, r) in &inner {
            out[i as usize] += r;
        }
        out[1] += 0.1;
        for k in 0..ring {
            out[(4 + k) as usize] += 0.01 * f64::from(k % 3 + 1);
        }
        for k in 0..small {
            out[(s0 + k) as usize] += 0.05 * f64::from(k % 4 + 1);
        }
        let (s, c) = (0.3, 0.7);
        let sys = BlockSystem::new("test", &out, &inner, s, c).unwrap();
        let mut m = Mat::<f64>::zeros(n, n);
        for i in 0..n {
            m[(i, i)] = s + c * out[i];
        }
        for &(i, j, r) in &inner {
            m[(i as usize, j as usize)] -= c * r;
        }
        let b: Vec<f64> = (0..n).map(|i| 1.0 + (i % 5) as f64).collect();
        let mut row = b.clone();
        sys.solve_row(&mut row);
        let mt = m.transpose().to_owned();
        let want = mt.partial_piv_lu().solve(Mat::<f64>::from_fn(n, 1, |i, _| b[i]));
        for i in 0..n {
            assert!(
                (row[i] - want[(i, 0)]).abs() < 1e-9 * want[(i, 0)].abs().max(1.0),
                "row {i}"
            );
        }
    }
}
