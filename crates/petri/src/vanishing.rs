//! Exact elimination of vanishing markings.
//!
//! From a vanishing marking `v` the net fires immediate transitions, each
//! with probability `w_t / Σw`, until it reaches a tangible marking. For every
//! vanishing `v` this module computes
//!
//! * `D(v)`: the probability of ending in each tangible marking, and
//! * `F(v)`: the expected number of firings of each immediate transition on
//!   the way (the immediate transitions' throughputs are built from it).
//!
//! The vanishing part of the reachability graph is split into strongly
//! connected components (Tarjan), processed in reverse topological order so
//! that a component only needs the results of components below it. A
//! component without a cycle is one marking: `D(v) = Σ_e p_e·D(target_e)`. A
//! component with cycles ("vanishing loop") is an absorbing Markov chain:
//! `(I − P_CC) X = P_C,out · [D of exits]`, solved exactly by LU; if no edge
//! leaves it, it is a *timeless trap* and an error. Cost: linear in the
//! vanishing subgraph plus the LU of each loop component.

use crate::error::{Error, Result};
use crate::gspn::Gspn;
use crate::linear;
use crate::reachability::{MarkingId, ReachabilityGraph};
use crate::scc::tarjan;

const NONE: u32 = u32::MAX;

/// Results of the elimination, stored flat.
#[derive(Debug, Clone, Default)]
pub(crate) struct Elimination {
    /// For each marking of the RG: its slot (vanishing ones only).
    slot: Vec<u32>,
    d_start: Vec<u64>,
    d_items: Vec<(u32, f64)>,
    f_start: Vec<u64>,
    f_items: Vec<(u32, f64)>,
}

impl Elimination {
    /// `D(v)`: (tangible id, probability), sorted by id.
    pub(crate) fn dist(&self, v: u32) -> &[(u32, f64)] {
        let s = self.slot[v as usize] as usize;
        &self.d_items[self.d_start[s] as usize..self.d_start[s + 1] as usize]
    }

    /// `F(v)`: (immediate transition, expected firings), sorted.
    pub(crate) fn firings(&self, v: u32) -> &[(u32, f64)] {
        let s = self.slot[v as usize] as usize;
        &self.f_items[self.f_start[s] as usize..self.f_start[s + 1] as usize]
    }

    fn push(&mut self, v: u32, d: &mut Accumulator, f: &mut Accumulator) {
        self.slot[v as usize] = (self.d_start.len() - 1) as u32;
        d.drain_sorted(&mut self.d_items);
        self.d_start.push(self.d_items.len() as u64);
        f.drain_sorted(&mut self.f_items);
        self.f_start.push(self.f_items.len() as u64);
    }
}

/// Dense scratch vector with a list of touched entries.
struct Accumulator {
    value: Vec<f64>,
    touched: Vec<u32>,
}

impl Accumulator {
    fn new(n: usize) -> Self {
        Accumulator {
            value: vec![0.0; n],
            touched: Vec::new(),
        }
    }

    #[inline]
    fn add(&mut self, i: u32, v: f64) {
        let slot = &mut self.value[i as usize];
        if *slot == 0.0 {
            // May push an index twice if a sum cancels to 0: `drain_sorted` dedups.
            self.touched.push(i);
        }
        *slot += v;
    }

    fn drain_sorted(&mut self, out: &mut Vec<(u32, f64)>) {
        self.touched.sort_unstable();
        self.touched.dedup();
        for &i in &self.touched {
            let v = std::mem::take(&mut self.value[i as usize]);
            if v != 0.0 {
                out.push((i, v));
            }
        }
        self.touched.clear();
    }
}

/// Eliminates every vanishing marking of `rg` that `tangible_id` does not
/// keep. `tangible_id` maps RG indices to the ids of the markings kept
/// (`u32::MAX` for those eliminated): the tangible ones, and for a net
/// with decisions its choice markings too, at which the elimination stops
/// as at a tangible marking.
pub(crate) fn eliminate(gspn: &Gspn, rg: &ReachabilityGraph, tangible_id: &[u32]) -> Result<Elimination> {
    let n = rg.num_markings();
    let nt = tangible_id.iter().filter(|&&k| k != NONE).count();
    let mut el = Elimination {
        slot: vec![NONE; n],
        d_start: vec![0],
        d_items: Vec::new(),
        f_start: vec![0],
        f_items: Vec::new(),
    };
    let mut d_acc = Accumulator::new(nt);
    let mut f_acc = Accumulator::new(gspn.num_transitions());
    let mut local = vec![NONE; n];
    tarjan(
        rg,
        |v| tangible_id[v as usize] == NONE,
        |scc| -> Result<()> {
            let single = scc.len() == 1 && {
                let (a, b) = rg.range(scc[0] as usize);
                !rg.targets[a..b].contains(&scc[0])
            };
            if single {
                let v = scc[0];
                let (a, b) = rg.range(v as usize);
                for k in a..b {
                    let p = rg.coeff(k);
                    let w = rg.targets[k];
                    f_acc.add(rg.transitions[k], p);
                    if tangible_id[w as usize] != NONE {
                        d_acc.add(tangible_id[w as usize], p);
                    } else {
                        for &(u, q) in el.dist(w) {
                            d_acc.add(u, p * q);
                        }
                        for &(u, q) in el.firings(w) {
                            f_acc.add(u, p * q);
                        }
                    }
                }
                el.push(v, &mut d_acc, &mut f_acc);
                Ok(())
            } else {
                solve_loop(
                    gspn,
                    rg,
                    tangible_id,
                    scc,
                    &mut local,
                    &mut el,
                    &mut d_acc,
                    &mut f_acc,
                )
            }
        },
    )?;
    Ok(el)
}

/// Solves one vanishing component with cycles.
#[allow(clippy::too_many_arguments)]
fn solve_loop(
    gspn: &Gspn,
    rg: &ReachabilityGraph,
    tangible_id: &[u32],
    scc: &[u32],
    local: &mut [u32],
    el: &mut Elimination,
    d_acc: &mut Accumulator,
    f_acc: &mut Accumulator,
) -> Result<()> {
    let m = scc.len();
    for (i, &v) in scc.iter().enumerate() {
        local[v as usize] = i as u32;
    }
    // Columns of the right-hand side: tangible targets, then transitions.
    let mut d_cols: Vec<u32> = Vec::new();
    let mut f_cols: Vec<u32> = Vec::new();
    let mut triplets: Vec<(u32, u32, f64)> = Vec::with_capacity(m * 3);
    // rhs entries as (row, column key, value); column key: (is_f, id)
    let mut rhs_entries: Vec<(u32, bool, u32, f64)> = Vec::new();
    let mut exits = false;
    for (i, &v) in scc.iter().enumerate() {
        triplets.push((i as u32, i as u32, 1.0));
        let (a, b) = rg.range(v as usize);
        for k in a..b {
            let p = rg.coeff(k);
            let w = rg.targets[k];
            rhs_entries.push((i as u32, true, rg.transitions[k], p));
            if local[w as usize] != NONE {
                triplets.push((i as u32, local[w as usize], -p));
            } else {
                exits = true;
                if tangible_id[w as usize] != NONE {
                    rhs_entries.push((i as u32, false, tangible_id[w as usize], p));
                } else {
                    for &(u, q) in el.dist(w) {
                        rhs_entries.push((i as u32, false, u, p * q));
                    }
                    for &(u, q) in el.firings(w) {
                        rhs_entries.push((i as u32, true, u, p * q));
                    }
                }
            }
        }
    }
    if !exits {
        for &v in scc {
            local[v as usize] = NONE;
        }
        let shown: Vec<String> = scc
            .iter()
            .take(3)
            .map(|&v| format!("[{}]", gspn.format_marking(&rg.marking(MarkingId(v)))))
            .collect();
        return Err(Error::TimelessTrap {
            count: m,
            markings: shown.join(", "),
        });
    }
    for &(_, is_f, id, _) in &rhs_entries {
        if is_f { f_cols.push(id) } else { d_cols.push(id) }
    }
    d_cols.sort_unstable();
    d_cols.dedup();
    f_cols.sort_unstable();
    f_cols.dedup();
    let ncols = d_cols.len() + f_cols.len();
    let mut rhs = vec![vec![0.0; m]; ncols];
    for &(row, is_f, id, val) in &rhs_entries {
        let col = if is_f {
            d_cols.len() + f_cols.binary_search(&id).unwrap_or(0)
        } else {
            d_cols.binary_search(&id).unwrap_or(0)
        };
        rhs[col][row as usize] += val;
    }
    linear::solve("a vanishing loop", m, &triplets, &mut rhs)?;
    for (i, &v) in scc.iter().enumerate() {
        for (c, &id) in d_cols.iter().enumerate() {
            let x = rhs[c][i];
            if x != 0.0 {
                d_acc.add(id, x);
            }
        }
        for (c, &id) in f_cols.iter().enumerate() {
            let x = rhs[d_cols.len() + c][i];
            if x != 0.0 {
                f_acc.add(id, x);
            }
        }
        el.push(v, d_acc, f_acc);
    }
    for &v in scc {
        local[v as usize] = NONE;
    }
    Ok(())
}
