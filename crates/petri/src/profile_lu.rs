//! LU factorisation of a small dense M-matrix in a profile-reducing order,
//! stored by profile: the diagonal blocks of [`crate::blocks`].
//!
//! The matrices factorised here are transposes of `B = s·I + c·(diag(out) − R)`
//! with `s ≥ 0`, `c > 0`, `R ≥ 0` the rates inside one strongly connected
//! component and `out_i ≥ Σ_j R_ij` each state's whole exit rate. `B` is
//! row diagonally dominant, so `Bᵀ` is *column* diagonally dominant, and
//! that is what makes elimination without pivoting safe:
//!
//! - each column's diagonal entry is at least the sum of the magnitudes of
//!   the others, so partial pivoting would keep the diagonal pivot anyway,
//!   and the growth factor is at most 2 (Wilkinson's bound for column
//!   diagonally dominant matrices; Higham, *Accuracy and Stability of
//!   Numerical Algorithms*, 2nd ed., ch. 9);
//! - column dominance passes to every Schur complement, and `Bᵀ` is an
//!   M-matrix whose Schur complements are M-matrices: a pivot is positive
//!   unless the block is singular (a component with no exit when `s = 0`);
//!   a zero or non-finite pivot is reported.
//!
//! A symmetric permutation `P Bᵀ Pᵀ` keeps the dominance, so the states
//! can be renumbered freely before the factorisation ([`profile_order`]
//! chooses the order from the pattern alone; [`crate::blocks`] numbers a
//! component's states that way before it builds the block). Without pivoting the
//! fill of `L` and `U` stays inside the envelope of the permuted pattern:
//! row `i` of `L` starts no earlier than the first neighbour of `i` in the
//! symmetrised pattern, and so on for the columns of `U`. The order is
//! reverse Cuthill–McKee (George & Liu, *Computer Solution of Large Sparse
//! Positive Definite Systems*, 1981, ch. 4) from the start node whose order gives
//! the smallest profile, or the natural order if that is smaller still.
//! Each row of the factors is then kept as one contiguous slice from the
//! first nonzero of `L` to the last nonzero of `U`, so both triangular
//! solves are dot products over short contiguous slices.
//!
//! Cost for a block of `k` states whose factors hold `f` entries: ordering
//! `O(e log e + k · (k + e))` over the `e` entries (every start node is tried),
//! factorisation `O(k² + Σ_i |L row i| · |U row i|)`, each solve `2f` flops.

/// `Σ a_i b_i` over equal-length slices, four partial sums (so that the
/// compiler can use vector registers; fixed lanes, so deterministic). Also
/// the Krylov space's products ([`crate::survival`]).
#[inline]
pub(crate) fn dot(a: &[f64], b: &[f64]) -> f64 {
    let mut acc = [0.0f64; 4];
    let (ca, cb) = (a.chunks_exact(4), b.chunks_exact(4));
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        for l in 0..4 {
            acc[l] += x[l] * y[l];
        }
    }
    let tail: f64 = ra.iter().zip(rb).map(|(x, y)| x * y).sum();
    (acc[0] + acc[1]) + (acc[2] + acc[3]) + tail
}

/// `A = L U` of a `k × k` matrix (in the order its caller chose, see
/// [`profile_order`]), with each row `i` of `L` (unit diagonal, not stored)
/// and `U` kept as columns `first[i]..=last[i]` in one slice.
#[derive(Debug, Clone)]
pub(crate) struct ProfileLu {
    /// First column stored in each row (`L`'s first nonzero, or the diagonal).
    first: Vec<u32>,
    /// Row `i` is `values[start[i]..start[i + 1]]`.
    start: Vec<u32>,
    values: Vec<f64>,
}

impl ProfileLu {
    /// Factorises the row-major `k × k` matrix `a` as it is numbered, which
    /// must be column diagonally dominant (see the module doc). `None` if a
    /// pivot is zero or not finite (a singular block).
    pub(crate) fn new(k: usize, mut m: Vec<f64>) -> Option<ProfileLu> {
        eliminate(k, &mut m)?;
        let mut first = Vec::with_capacity(k);
        let mut start = Vec::with_capacity(k + 1);
        let mut values = Vec::new();
        start.push(0);
        for i in 0..k {
            let row = &m[i * k..(i + 1) * k];
            let lo = row[..i].iter().position(|&v| v != 0.0).unwrap_or(i);
            let hi = row[i + 1..]
                .iter()
                .rposition(|&v| v != 0.0)
                .map_or(i, |j| i + 1 + j);
            first.push(lo as u32);
            values.extend_from_slice(&row[lo..=hi]);
            start.push(values.len() as u32);
        }
        Some(ProfileLu { first, start, values })
    }

    /// Entries stored (both factors with the diagonal).
    #[cfg(test)]
    pub(crate) fn stored(&self) -> usize {
        self.values.len()
    }

    /// `A z = y` in place.
    pub(crate) fn solve(&self, y: &mut [f64]) {
        let k = self.first.len();
        for i in 0..k {
            let f = self.first[i] as usize;
            let row = &self.values[self.start[i] as usize..self.start[i + 1] as usize];
            let s = dot(&row[..i - f], &y[f..i]);
            y[i] -= s;
        }
        for i in (0..k).rev() {
            let f = self.first[i] as usize;
            let row = &self.values[self.start[i] as usize..self.start[i + 1] as usize];
            let upper = &row[i - f + 1..];
            let s = dot(upper, &y[i + 1..i + 1 + upper.len()]);
            y[i] = (y[i] - s) / row[i - f];
        }
    }
}

/// Gaussian elimination without pivoting, in place (`L` below the
/// diagonal, `U` on and above). Each pivot row is applied only up to its
/// last nonzero, and only to the rows with a nonzero in the pivot column,
/// so the cost follows the envelope rather than `k³`.
fn eliminate(k: usize, m: &mut [f64]) -> Option<()> {
    for col in 0..k {
        let d = m[col * k + col];
        if !(d != 0.0 && d.is_finite()) {
            return None;
        }
        let hi = m[col * k + col + 1..(col + 1) * k]
            .iter()
            .rposition(|&v| v != 0.0)
            .map_or(col, |j| col + 1 + j);
        let (top, rest) = m.split_at_mut((col + 1) * k);
        let pivot = &top[col * k + col + 1..col * k + hi + 1];
        for row in rest.chunks_exact_mut(k) {
            if row[col] == 0.0 {
                continue;
            }
            let f = row[col] / d;
            row[col] = f;
            for (x, &p) in row[col + 1..=hi].iter_mut().zip(pivot) {
                *x -= f * p;
            }
        }
    }
    Some(())
}

/// The symmetric renumbering (position → index) with the smallest profile
/// `Σ_i (i − first neighbour of i)` of the symmetrised pattern of `a`
/// among reverse Cuthill–McKee from every start node and the natural order.
pub(crate) fn profile_order(k: usize, a: &[f64]) -> Vec<u32> {
    let mut adj: Vec<Vec<u32>> = vec![Vec::new(); k];
    for i in 0..k {
        for j in 0..i {
            if a[i * k + j] != 0.0 || a[j * k + i] != 0.0 {
                adj[i].push(j as u32);
                adj[j].push(i as u32);
            }
        }
    }
    // Neighbours by increasing degree (ties by index): the order
    // Cuthill–McKee visits them in.
    let degree: Vec<usize> = adj.iter().map(Vec::len).collect();
    for list in &mut adj {
        list.sort_by_key(|&j| (degree[j as usize], j));
    }
    let natural: Vec<u32> = (0..k as u32).collect();
    let mut best = (profile(&adj, &natural), natural);
    let mut position = vec![0u32; k];
    for root in 0..k as u32 {
        let order = reverse_cuthill_mckee(&adj, root);
        for (p, &v) in order.iter().enumerate() {
            position[v as usize] = p as u32;
        }
        let size = profile_with(&adj, &order, &position);
        if size < best.0 {
            best = (size, order);
        }
    }
    best.1
}

/// Breadth-first from `root`, neighbours by increasing degree, reversed;
/// nodes not reached (a pattern in pieces) follow in index order.
fn reverse_cuthill_mckee(adj: &[Vec<u32>], root: u32) -> Vec<u32> {
    let k = adj.len();
    let mut seen = vec![false; k];
    let mut order = Vec::with_capacity(k);
    let visit = |v: u32, order: &mut Vec<u32>, seen: &mut Vec<bool>| {
        seen[v as usize] = true;
        order.push(v);
        let mut head = order.len() - 1;
        while head < order.len() {
            let u = order[head] as usize;
            head += 1;
            for &w in &adj[u] {
                if !seen[w as usize] {
                    seen[w as usize] = true;
                    order.push(w);
                }
            }
        }
    };
    visit(root, &mut order, &mut seen);
    for v in 0..k as u32 {
        if !seen[v as usize] {
            visit(v, &mut order, &mut seen);
        }
    }
    order.reverse();
    order
}

fn profile(adj: &[Vec<u32>], order: &[u32]) -> usize {
    let mut position = vec![0u32; order.len()];
    for (p, &v) in order.iter().enumerate() {
        position[v as usize] = p as u32;
    }
    profile_with(adj, order, &position)
}

/// `Σ_i (i − first neighbour of i)` in the renumbering (`position` its inverse).
fn profile_with(adj: &[Vec<u32>], order: &[u32], position: &[u32]) -> usize {
    order
        .iter()
        .enumerate()
        .map(|(p, &v)| {
            let lo = adj[v as usize]
                .iter()
                .map(|&w| position[w as usize] as usize)
                .min()
                .map_or(p, |q| q.min(p));
            p - lo
        })
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// `Bᵀ` for `B = s·I + c·(diag(out) − R)` on `k` states with the given
    /// rates, `out` the row sums plus `leak`.
    fn transposed_block(k: usize, rates: &[(usize, usize, f64)], leak: &[f64], s: f64, c: f64) -> Vec<f64> {
        let mut a = vec![0.0; k * k];
        for (i, &l) in leak.iter().enumerate() {
            a[i * k + i] = s + c * l;
        }
        for &(i, j, r) in rates {
            a[i * k + i] += c * r;
            a[j * k + i] -= c * r;
        }
        a
    }

    /// `a` renumbered: entry `(p, q)` is `a[order[p]][order[q]]`.
    fn renumbered(k: usize, a: &[f64], order: &[u32]) -> Vec<f64> {
        let mut m = vec![0.0; k * k];
        for (p, &op) in order.iter().enumerate() {
            for (q, &oq) in order.iter().enumerate() {
                m[p * k + q] = a[op as usize * k + oq as usize];
            }
        }
        m
    }

    proptest! {
        /// The profile LU solves `A z = y` as a dense product checks, for
        /// random diagonally dominant blocks and any renumbering it picks.
        #[test]
        fn solves_dominant_blocks(
            k in 2usize..40,
            seed_rates in proptest::collection::vec((0usize..1000, 0usize..1000, 0.01f64..10.0), 1..200),
            leak_seed in proptest::collection::vec(0.0f64..1.0, 40),
            s in prop_oneof![Just(0.0), 0.1f64..2.0],
        ) {
            let rates: Vec<_> = seed_rates
                .iter()
                .map(|&(i, j, r)| (i % k, j % k, r))
                .filter(|&(i, j, _)| i != j)
                .collect();
            let mut leak: Vec<f64> = leak_seed[..k].to_vec();
            leak[0] += 0.5; // at least one exit: nonsingular even when s = 0
            let a = transposed_block(k, &rates, &leak, s, 0.7);
            let order = profile_order(k, &a);
            let lu = ProfileLu::new(k, renumbered(k, &a, &order)).expect("a nonsingular block");
            let want: Vec<f64> = (0..k).map(|i| 1.0 + (i % 3) as f64).collect();
            // y = A z in the original numbering, then renumbered.
            let y: Vec<f64> = (0..k).map(|i| dot(&a[i * k..(i + 1) * k], &want)).collect();
            let mut z: Vec<f64> = order.iter().map(|&o| y[o as usize]).collect();
            lu.solve(&mut z);
            for (p, &o) in order.iter().enumerate() {
                let w = want[o as usize];
                prop_assert!((z[p] - w).abs() <= 1e-10 * w.abs().max(1.0), "{} vs {}", z[p], w);
            }
        }
    }

    /// A ring numbered in a scattered order: the renumbering brings the
    /// profile down to that of a band of half-width 2.
    #[test]
    fn a_scattered_ring_gets_a_narrow_profile() {
        let k = 30;
        let label = |i: usize| (i * 7) % k;
        let rates: Vec<_> = (0..k).map(|i| (label(i), label((i + 1) % k), 1.0)).collect();
        let a = transposed_block(k, &rates, &vec![0.1; k], 0.0, 1.0);
        let lu = ProfileLu::new(k, renumbered(k, &a, &profile_order(k, &a))).unwrap();
        // A ring in its natural order has a profile of ~2k per factor;
        // scattered, ~k²/2.
        assert!(lu.stored() <= 5 * k, "{} entries stored", lu.stored());
    }

    /// A block with a zero pivot (no exit, `s = 0`) is reported singular.
    #[test]
    fn a_component_without_exit_is_singular() {
        let a = transposed_block(2, &[(0, 1, 1.0), (1, 0, 2.0)], &[0.0, 0.0], 0.0, 1.0);
        assert!(ProfileLu::new(2, a).is_none());
    }
}
