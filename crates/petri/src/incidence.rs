//! The incidence matrix `C = O − I` of a net.
//!
//! `C[p, t]` is the change in the number of tokens of place `p` when
//! transition `t` fires: output multiplicity minus input multiplicity. Firing a
//! sequence `σ` from `M` leads to `M' = M + C·σ⃗` (the *state equation*, with
//! `σ⃗` the count of each transition in `σ`), which is what the invariants of
//! [`invariants`](crate::invariants) are built on.
//!
//! What the matrix does not see, by construction:
//!
//! - **inhibitor arcs**, priorities and capacities: they only forbid firings
//!   and never change what a firing does, so every equation derived from `C`
//!   (P-invariants, the state equation) holds in the GSPN as in its underlying
//!   place/transition net;
//! - **self-loops**: a place that is both input and output of `t` with the same
//!   multiplicity gets `C[p, t] = 0` (parallel arcs are merged first, so an
//!   input of 2 and an output of 3 give `+1`).
//!
//! Stored sparse by column (one column per transition, as
//! [`Gspn::delta`] gives it); building it costs `O(arcs)`.

use std::fmt;

use crate::gspn::Gspn;
use crate::net::{PlaceId, TransitionId};

/// The incidence matrix of a net: places × transitions, integer entries,
/// stored sparse by column. See the [module docs](self) for what it contains.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct Incidence {
    num_places: usize,
    /// One column per transition: the non-zero `(place index, C[p, t])`,
    /// sorted by place.
    columns: Vec<Vec<(u32, i64)>>,
}

impl Incidence {
    /// The incidence matrix of `gspn` (inhibitor arcs left out).
    pub fn new(gspn: &Gspn) -> Incidence {
        let columns = (0..gspn.num_transitions())
            .map(|t| {
                let mut col = gspn.delta(TransitionId(t as u32)).to_vec();
                col.retain(|&(_, v)| v != 0);
                col.sort_unstable_by_key(|&(p, _)| p);
                col
            })
            .collect();
        Incidence {
            num_places: gspn.num_places(),
            columns,
        }
    }

    /// Number of rows (places).
    pub fn num_places(&self) -> usize {
        self.num_places
    }

    /// Number of columns (transitions).
    pub fn num_transitions(&self) -> usize {
        self.columns.len()
    }

    /// Number of non-zero entries.
    pub fn nnz(&self) -> usize {
        self.columns.iter().map(Vec::len).sum()
    }

    /// Column `t`: the non-zero `(place index, C[p, t])`, sorted by place
    /// (empty if `t` is out of range).
    pub fn column(&self, t: TransitionId) -> &[(u32, i64)] {
        self.columns.get(t.index()).map_or(&[], Vec::as_slice)
    }

    /// The entry `C[p, t]` (0 if either index is out of range).
    pub fn get(&self, p: PlaceId, t: TransitionId) -> i64 {
        let col = self.column(t);
        col.binary_search_by_key(&p.0, |&(q, _)| q)
            .map_or(0, |i| col[i].1)
    }

    /// The matrix by rows: for each place, the non-zero
    /// `(transition index, C[p, t])`, sorted by transition.
    pub fn rows(&self) -> Vec<Vec<(u32, i64)>> {
        let mut rows = vec![Vec::new(); self.num_places];
        for (t, col) in self.columns.iter().enumerate() {
            for &(p, v) in col {
                rows[p as usize].push((t as u32, v));
            }
        }
        rows
    }

    /// The matrix as dense rows (`dense[p][t] = C[p, t]`).
    pub fn to_dense(&self) -> Vec<Vec<i64>> {
        let mut dense = vec![vec![0; self.columns.len()]; self.num_places];
        for (t, col) in self.columns.iter().enumerate() {
            for &(p, v) in col {
                dense[p as usize][t] = v;
            }
        }
        dense
    }

    /// `yᵀ·C` for a sparse place vector `y` given as `(place index,
    /// coefficient)`: one entry per transition. `None` if an index is out of
    /// range.
    pub fn left_product(&self, y: &[(u32, u64)]) -> Option<Vec<i128>> {
        let mut dense = vec![0i128; self.num_places];
        for &(p, c) in y {
            *dense.get_mut(p as usize)? += i128::from(c);
        }
        Some(
            self.columns
                .iter()
                .map(|col| col.iter().map(|&(p, v)| dense[p as usize] * i128::from(v)).sum())
                .collect(),
        )
    }

    /// `C·x` for a sparse transition vector `x` given as `(transition index,
    /// coefficient)`: one entry per place. `None` if an index is out of range.
    pub fn right_product(&self, x: &[(u32, u64)]) -> Option<Vec<i128>> {
        let mut out = vec![0i128; self.num_places];
        for &(t, c) in x {
            for &(p, v) in self.columns.get(t as usize)? {
                out[p as usize] += i128::from(c) * i128::from(v);
            }
        }
        Some(out)
    }

    /// Whether `y` (sparse, `(place index, coefficient)`) is a semi-positive
    /// P-invariant: some coefficient is non-zero and `yᵀ·C = 0`.
    pub fn is_p_invariant(&self, y: &[(u32, u64)]) -> bool {
        y.iter().any(|&(_, c)| c > 0) && self.left_product(y).is_some_and(|r| r.iter().all(|&v| v == 0))
    }

    /// Whether `x` (sparse, `(transition index, coefficient)`) is a
    /// semi-positive T-invariant: some coefficient is non-zero and `C·x = 0`.
    pub fn is_t_invariant(&self, x: &[(u32, u64)]) -> bool {
        x.iter().any(|&(_, c)| c > 0) && self.right_product(x).is_some_and(|r| r.iter().all(|&v| v == 0))
    }

    /// A printable table with place and transition names (rows are places,
    /// zeros printed as `.`), for human output.
    pub fn display<'a>(&'a self, gspn: &'a Gspn) -> DisplayIncidence<'a> {
        DisplayIncidence {
            incidence: self,
            gspn,
        }
    }
}

/// The incidence matrix as a table with names; see [`Incidence::display`].
#[derive(Debug, Clone, Copy)]
pub struct DisplayIncidence<'a> {
    incidence: &'a Incidence,
    gspn: &'a Gspn,
}

/// The name at `i` in `names`, or `#i` when the net does not match.
pub(crate) fn name_or_index(names: &[String], i: usize) -> String {
    names.get(i).cloned().unwrap_or_else(|| format!("#{i}"))
}

impl fmt::Display for DisplayIncidence<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let c = self.incidence;
        let places: Vec<String> = (0..c.num_places())
            .map(|p| name_or_index(self.gspn.place_names(), p))
            .collect();
        let transitions: Vec<String> = (0..c.num_transitions())
            .map(|t| name_or_index(self.gspn.transition_names(), t))
            .collect();
        let dense = c.to_dense();
        let cell = |v: i64| if v == 0 { ".".to_string() } else { v.to_string() };
        let first = places.iter().map(|n| n.chars().count()).max().unwrap_or(0);
        let widths: Vec<usize> = transitions
            .iter()
            .enumerate()
            .map(|(t, name)| {
                dense
                    .iter()
                    .map(|row| cell(row[t]).chars().count())
                    .chain([name.chars().count()])
                    .max()
                    .unwrap_or(1)
            })
            .collect();
        write!(f, "{:first$}", "")?;
        for (name, w) in transitions.iter().zip(&widths) {
            write!(f, " {name:>w$}")?;
        }
        for (name, row) in places.iter().zip(&dense) {
            write!(f, "\n{name:first$}")?;
            for (&v, w) in row.iter().zip(&widths) {
                write!(f, " {:>w$}", cell(v))?;
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::net::{ArcKind, Net, Params};

    fn net() -> Gspn {
        let mut n = Net::new("n");
        let a = n.add_place("a", 1u32);
        let b = n.add_place("b", 0u32);
        let c = n.add_place("c", 0u32);
        let t = n.add_timed("t", 1.0);
        let u = n.add_immediate("u", 1.0, 1);
        n.add_arc(ArcKind::Input, a, t, 2u32);
        n.output(t, b);
        n.inhibitor(c, t);
        n.input(b, u);
        n.output(u, b);
        n.add_arc(ArcKind::Output, c, u, 3u32);
        n.instantiate(&Params::new()).unwrap()
    }

    #[test]
    fn entries_leave_out_inhibitors_and_self_loops() {
        let g = net();
        let c = Incidence::new(&g);
        assert_eq!(c.to_dense(), vec![vec![-2, 0], vec![1, 0], vec![0, 3]]);
        assert_eq!(c.nnz(), 3);
        assert_eq!(c.get(PlaceId(0), TransitionId(0)), -2);
        assert_eq!(c.get(PlaceId(1), TransitionId(1)), 0);
        assert_eq!(c.get(PlaceId(9), TransitionId(9)), 0);
        assert_eq!(c.column(TransitionId(7)), &[]);
        assert_eq!(c.rows(), vec![vec![(0, -2)], vec![(0, 1)], vec![(1, 3)]]);
        assert_eq!(c.left_product(&[(0, 1), (1, 2)]), Some(vec![0, 0]));
        assert!(c.is_p_invariant(&[(0, 1), (1, 2)]));
        assert!(!c.is_p_invariant(&[(0, 1)]));
        assert!(!c.is_p_invariant(&[]));
        assert!(!c.is_p_invariant(&[(5, 1)]));
        assert_eq!(c.right_product(&[(1, 1)]), Some(vec![0, 0, 3]));
        assert!(!c.is_t_invariant(&[(1, 1)]));
        assert_eq!(c.right_product(&[(4, 1)]), None);
    }

    #[test]
    fn table() {
        let g = net();
        let s = Incidence::new(&g).display(&g).to_string();
        assert_eq!(s, "   t u\na -2 .\nb  1 .\nc  . 3");
    }
}
