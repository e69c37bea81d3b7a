//! Thin wrappers over `faer`'s direct solvers: dense LU with partial pivoting
//! for small systems, sparse LU (COLAMD ordering, supernodal or simplicial as
//! faer decides) for larger ones. Results are checked for non-finite values.

use faer::Mat;
use faer::prelude::Solve;
use faer::sparse::{SparseColMat, Triplet};

use crate::error::{Error, Result};

/// Below this size a dense LU is faster than a sparse one.
pub(crate) const DENSE_LIMIT: usize = 160;

/// Solves `A X = B` for square `A` given as triplets `(row, col, value)`
/// (duplicates are summed); `rhs` holds `B` column by column (each of length
/// `n`) and receives `X`. One step of iterative refinement (re-using the
/// factorisation) bring the error down to what the conditioning allows.
pub(crate) fn solve(
    what: &'static str,
    n: usize,
    triplets: &[(u32, u32, f64)],
    rhs: &mut [Vec<f64>],
) -> Result<()> {
    if n == 0 {
        return Ok(());
    }
    let singular = |detail: String| Error::Singular { what, detail };
    type Factor = Box<dyn Fn(&mut Mat<f64>)>;
    let factor: Factor = if n <= DENSE_LIMIT {
        let mut a = Mat::<f64>::zeros(n, n);
        for &(r, c, v) in triplets {
            a[(r as usize, c as usize)] += v;
        }
        let lu = a.partial_piv_lu();
        Box::new(move |b: &mut Mat<f64>| lu.solve_in_place(b))
    } else {
        let entries: Vec<Triplet<usize, usize, f64>> = triplets
            .iter()
            .map(|&(r, c, v)| Triplet::new(r as usize, c as usize, v))
            .collect();
        let a = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &entries)
            .map_err(|e| singular(format!("cannot build the sparse matrix: {e:?}")))?;
        let lu = a
            .sp_lu()
            .map_err(|e| singular(format!("sparse LU failed: {e:?}")))?;
        Box::new(move |b: &mut Mat<f64>| lu.solve_in_place(b))
    };
    // Solve in blocks of columns to bound the dense workspace.
    const BLOCK: usize = 32;
    for chunk in rhs.chunks_mut(BLOCK) {
        let b0 = Mat::<f64>::from_fn(n, chunk.len(), |i, j| chunk[j][i]);
        let mut x = b0.clone();
        factor(&mut x);
        {
            // r = b - A x
            let mut r = b0.clone();
            for &(row, col, v) in triplets {
                for j in 0..chunk.len() {
                    r[(row as usize, j)] -= v * x[(col as usize, j)];
                }
            }
            factor(&mut r);
            for j in 0..chunk.len() {
                for i in 0..n {
                    x[(i, j)] += r[(i, j)];
                }
            }
        }
        for (j, col) in chunk.iter_mut().enumerate() {
            for (i, v) in col.iter_mut().enumerate() {
                *v = x[(i, j)];
            }
        }
    }
    if rhs.iter().flatten().any(|x| !x.is_finite()) {
        return Err(singular("the solution has non-finite entries".into()));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check(n: usize) {
        // Tridiagonal, diagonally dominant.
        let mut t = Vec::new();
        for i in 0..n as u32 {
            t.push((i, i, 4.0));
            if i > 0 {
                t.push((i, i - 1, -1.0));
            }
            if (i as usize) + 1 < n {
                t.push((i, i + 1, -1.0));
                t.push((i, i + 1, -0.5)); // duplicate, summed
            }
        }
        let x: Vec<f64> = (0..n).map(|i| i as f64 + 1.0).collect();
        let mut b = vec![0.0; n];
        for &(r, c, v) in &t {
            b[r as usize] += v * x[c as usize];
        }
        let mut rhs = vec![b];
        solve("test", n, &t, &mut rhs).unwrap();
        for i in 0..n {
            assert!((rhs[0][i] - x[i]).abs() < 1e-10, "{i}: {}", rhs[0][i]);
        }
    }

    #[test]
    fn dense_and_sparse_paths_agree_with_known_solution() {
        check(5);
        check(DENSE_LIMIT + 50);
    }

    #[test]
    fn singular_system_is_an_error() {
        let t = vec![(0, 0, 1.0), (0, 1, 1.0), (1, 0, 1.0), (1, 1, 1.0)];
        let mut rhs = vec![vec![1.0, 2.0]];
        assert!(solve("test", 2, &t, &mut rhs).is_err());
    }
}
