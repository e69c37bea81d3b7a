//! Aggregation–disaggregation steps over one component of a product state
//! space: the coarse chain of a component's local states, weighted by the
//! current iterate, solved exactly, and the iterate rescaled so that its
//! marginal over that component is the coarse solution (Koury, McAllister
//! & Stewart's iterative aggregation–disaggregation, with the aggregates
//! of Buchholz's methods for Kronecker-structured chains: all states that
//! share a component's local state).
//!
//! For component `k` and an iterate `x` with marginal `ξ` over `S_k`, the
//! coarse chain moves from `l` to `l'` at rate
//! `Σ_e rate_e · E_x[factor_e · [e enabled] | l_k = l]` over the events `e`
//! that take `l` to `l'`: an event that touches only component `k` keeps
//! its own rate; one that also touches other components is weighted by the
//! joint marginal of `x` over the components it touches. Its stationary
//! vector `η` gives the correction `x_i ← x_i · η(l_k(i)) / ξ(l_k(i))`:
//! exact when the conditional distributions within each aggregate are, and
//! the identity at the solution.
//!
//! Cost: one pass over `x` for the marginals, one to rescale, and a solve of
//! a chain of `|S_k|` states (direct or BiCGSTAB by
//! [`crate::steady_state`]).

use rayon::prelude::*;

use crate::descriptor::Descriptor;
use crate::error::Result;
use crate::interrupt::Interrupt;
use crate::marginals::marginals;
use crate::rows::{Chain, Rows};
use crate::steady_state::{self, SolveParams};

/// Rescales `x` so that its marginal over component `level` is the
/// stationary vector of the coarse chain (see the module docs). `rates`
/// are by transition (scaled as in the sweep). Nets with immediate
/// transitions are not aggregated (their classes are not weighted here).
pub(crate) fn correct(desc: &Descriptor, rates: &[f64], x: &mut [f64], level: usize) -> Result<()> {
    let n = desc.sizes[level];
    // The subsets of levels of the events that move this level.
    let moving: Vec<&crate::descriptor::Event> = desc
        .events
        .iter()
        .filter(|e| e.immediate.is_none() && e.maps.iter().any(|m| m.level == level && m.moves))
        .collect();
    let mut subsets: Vec<Vec<usize>> = vec![vec![level]];
    for e in &moving {
        let s: Vec<usize> = e.maps.iter().map(|m| m.level).collect();
        if !subsets.contains(&s) {
            subsets.push(s);
        }
    }
    let marg = marginals(desc, None, x, &subsets);
    let xi = &marg[0];
    // Coarse entries (target, source, value), merged per pair below.
    let mut entries: Vec<(u32, u32, f64)> = Vec::new();
    let mut locals = vec![0u32; desc.levels()];
    for e in &moving {
        let s: Vec<usize> = e.maps.iter().map(|m| m.level).collect();
        let idx = subsets.iter().position(|x| *x == s).unwrap_or(0);
        let map = e
            .maps
            .iter()
            .find(|m| m.level == level)
            .map(|m| &m.succ[..])
            .unwrap_or(&[]);
        let rate = rates[e.transition as usize];
        for (j, &mass) in marg[idx].iter().enumerate() {
            if mass == 0.0 {
                continue;
            }
            let mut rem = j;
            for &lev in s.iter().rev() {
                locals[lev] = (rem % desc.sizes[lev]) as u32;
                rem /= desc.sizes[lev];
            }
            if !e.enabled_at(&locals) {
                continue;
            }
            let l = locals[level] as usize;
            let to = map[l] as usize;
            if to != l {
                entries.push((to as u32, l as u32, rate * e.factor_at(&locals) * mass / xi[l]));
            }
        }
    }
    let eta = coarse_solution(n, entries)?;
    let total: f64 = xi.iter().sum();
    let scale: Vec<f64> = eta
        .iter()
        .zip(xi)
        .map(|(&h, &m)| if m > 0.0 { h * total / m } else { 1.0 })
        .collect();
    rescale(desc, x, level, &scale);
    Ok(())
}

/// `x_i ← x_i · scale[l_level(i)]`.
fn rescale(desc: &Descriptor, x: &mut [f64], level: usize, scale: &[f64]) {
    let stride = desc.strides[level] as usize;
    let size = desc.sizes[level];
    let block = stride * size;
    x.par_chunks_mut(block).for_each(|b| {
        for (l, part) in b.chunks_mut(stride).enumerate() {
            let s = scale[l];
            part.iter_mut().for_each(|v| *v *= s);
        }
    });
}

/// Solves the coarse chain given as merged `(target, source, rate)`
/// entries over `n` states, exactly (to 1e-13).
fn coarse_solution(n: usize, mut entries: Vec<(u32, u32, f64)>) -> Result<Vec<f64>> {
    entries.sort_by_key(|e| (e.0, e.1));
    let mut merged: Vec<(u32, u32, f64)> = Vec::with_capacity(entries.len());
    for (t, s, v) in entries {
        match merged.last_mut() {
            Some(last) if last.0 == t && last.1 == s => last.2 += v,
            _ => merged.push((t, s, v)),
        }
    }
    let mut exit = vec![0.0; n];
    for &(_, s, v) in &merged {
        exit[s as usize] += v;
    }
    let values: Vec<f64> = merged.iter().map(|e| e.2).collect();
    let ids: Vec<(u32, u32, u32)> = merged
        .iter()
        .enumerate()
        .map(|(k, e)| (e.0, e.1, k as u32))
        .collect();
    let rows = Rows::from_entries(n, ids, values.len());
    let chain = Chain {
        incoming: &rows,
        values: &values,
        exit: &exit,
    };
    let params = SolveParams {
        tolerance: 1e-13,
        ..SolveParams::default()
    };
    Ok(steady_state::solve(&chain, None, &params, Interrupt::NEVER)?.0)
}
