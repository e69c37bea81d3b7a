//! Joint marginals of a vector over the product state space: for a subset
//! of levels (components), the sum of the vector over the states sharing
//! those levels' local states. One pass over the vector serves any number
//! of subsets; the structured engine's measures ([`crate::structured`]) and
//! its aggregation steps ([`crate::aggregation`]) read them.

use rayon::prelude::*;

use crate::descriptor::Descriptor;
use crate::sweep::{Kinds, TANGIBLE};

/// Fixed number of row ranges summed in parallel (each holds its own copy
/// of the marginals, added in range order afterwards).
const PARTS: usize = 4;

/// The joint marginals of `x` over each subset of levels (each ascending),
/// counting only tangible states when `kinds` is given. Entry `j` of a
/// subset's marginal is the tuple of its levels' local states in mixed
/// radix (the last level fastest).
pub(crate) fn marginals(
    desc: &Descriptor,
    kinds: Option<&Kinds>,
    x: &[f64],
    subsets: &[Vec<usize>],
) -> Vec<Vec<f64>> {
    let sizes = &desc.sizes;
    let k = sizes.len();
    let n = sizes[k - 1];
    let strides: Vec<Vec<usize>> = subsets
        .iter()
        .map(|s| {
            let mut st = vec![0usize; k];
            let mut acc = 1;
            for &lev in s.iter().rev() {
                st[lev] = acc;
                acc *= sizes[lev];
            }
            st
        })
        .collect();
    let empty = || -> Vec<Vec<f64>> {
        subsets
            .iter()
            .map(|s| vec![0.0; s.iter().map(|&l| sizes[l]).product()])
            .collect()
    };
    let rows = desc.states as usize / n;
    // Rows in fixed chunks, each summed alone, then added in chunk order:
    // the same bits on any number of threads.
    let chunk = rows.div_ceil(PARTS).max(1);
    let parts: Vec<Vec<Vec<f64>>> = (0..rows.div_ceil(chunk))
        .into_par_iter()
        .map(|part| {
            let mut out = empty();
            let mut locals = vec![0usize; k];
            let mut w = vec![0.0; n];
            for r in part * chunk..((part + 1) * chunk).min(rows) {
                let mut rem = r;
                for lev in (0..k - 1).rev() {
                    locals[lev] = rem % sizes[lev];
                    rem /= sizes[lev];
                }
                let start = r * n;
                match kinds {
                    None => w.copy_from_slice(&x[start..start + n]),
                    Some(kd) => {
                        for (c, v) in w.iter_mut().enumerate() {
                            *v = if kd.class[start + c] == TANGIBLE {
                                x[start + c]
                            } else {
                                0.0
                            };
                        }
                    }
                }
                let mut row_sum = None;
                for (s, (st, arr)) in subsets.iter().zip(strides.iter().zip(out.iter_mut())) {
                    let base: usize = s.iter().filter(|&&l| l < k - 1).map(|&l| locals[l] * st[l]).sum();
                    if s.contains(&(k - 1)) {
                        for (a, &v) in arr[base..base + n].iter_mut().zip(&w) {
                            *a += v;
                        }
                    } else {
                        arr[base] += *row_sum.get_or_insert_with(|| w.iter().sum::<f64>());
                    }
                }
            }
            out
        })
        .collect();
    let mut total = empty();
    for part in parts {
        for (t, p) in total.iter_mut().zip(part) {
            for (a, b) in t.iter_mut().zip(p) {
                *a += b;
            }
        }
    }
    total
}
