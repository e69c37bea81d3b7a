//! Minimal-support semi-positive P- and T-invariants, by the Farkas
//! (Fourier–Motzkin) algorithm, and what follows from them.
//!
//! A **P-invariant** is a vector `y ≥ 0, y ≠ 0` over places with `yᵀ·C = 0`
//! ([`Incidence`]): the weighted token count `y·M` is the same in every
//! reachable marking `M`, namely `y·M0`. A **T-invariant** is `x ≥ 0, x ≠ 0`
//! over transitions with `C·x = 0`: a firing sequence that fires each `t`
//! exactly `x_t` times (if one is firable) returns to the marking it started
//! from. Every semi-positive invariant is a non-negative combination of the
//! *minimal-support* ones (those whose support contains no other invariant's
//! support); each minimal support carries exactly one invariant up to scaling,
//! and this module returns it scaled to coprime integers.
//!
//! # Algorithm
//!
//! Martínez & Silva, *A simple and fast algorithm to obtain all invariants of
//! a generalised Petri net* (Informatik-Fachberichte 52, Springer, 1982), with
//! the minimal-support pruning studied by Colom & Silva, *Convex geometry and
//! semiflows in P/T nets* (Advances in Petri Nets 1990, LNCS 483, 1991). For
//! P-invariants, start from `[C | I]` (one row per place); for T-invariants
//! from `[Cᵀ | I]`. Then, one column of the `C` part at a time:
//!
//! 1. pick the column that minimises `pos·neg − pos − neg` (rows with a
//!    positive entry there times rows with a negative one, minus the rows the
//!    step removes): the bound on how much the matrix can grow;
//! 2. keep the rows that are zero in that column; for each pair of rows of
//!    opposite sign, add the non-negative combination that cancels the column,
//!    divided by the gcd of its entries;
//! 3. keep a combination only if no *other* current row has an `I`-part
//!    support included in the union of the two rows' supports. This is the
//!    support-inclusion test in its "adjacency" form (Fukuda & Prodon, *Double
//!    description method revisited*, LNCS 1120, 1996, Prop. 7): the rows of
//!    each intermediate matrix are then exactly the minimal-support
//!    (extreme) rows of the cone they span, so no non-minimal row and no
//!    duplicate is ever created (duplicates are still removed, as a guard).
//!
//! When every column is zero, the `I` parts of the remaining rows are the
//! minimal-support invariants.
//!
//! **Complexity**: exponential in the worst case — a net can have
//! exponentially many minimal invariants, and intermediate matrices can be
//! larger than the result. A step costs `O(pos·neg·rows·⌈n/64⌉)` word
//! operations for `n` rows at the start; [`FarkasParams::max_rows`] bounds the
//! matrix so that a hopeless run fails with [`Error::InvariantRowLimit`]
//! instead of exhausting memory. Arithmetic is exact (checked `i128`
//! internally, `u64` coefficients in the result); a coefficient that does not
//! fit is [`Error::InvariantOverflow`], never a wrong answer.
//!
//! # What the invariants tell
//!
//! Inhibitor arcs, priorities and capacities do not enter `C` (see
//! [`incidence`](crate::incidence)); they only forbid firings, so every
//! consequence below holds for the GSPN as for its underlying P/T net:
//!
//! - every marking reachable from `M0` satisfies `y·M = y·M0` for each
//!   P-invariant `y` ([`Invariants::holds_in`]);
//! - place `p` never holds more than `⌊y·M0 / y_p⌋` tokens
//!   ([`structural_bounds`]);
//! - if every place is in some P-invariant's support
//!   ([`Invariants::covers_all`]), the net is *conservative* and hence
//!   structurally bounded (bounded for every initial marking);
//! - if the net is live and bounded, every transition is in some
//!   T-invariant's support (the net is *consistent*): a T-invariant cover is
//!   a necessary condition, not a sufficient one.
//!
//! ```
//! use petri::{Net, Params, FarkasParams, p_invariants, structural_bounds};
//!
//! // Two places exchanging one token.
//! let mut net = Net::new("pair");
//! let a = net.add_place("a", 1u32);
//! let b = net.add_place("b", 0u32);
//! let go = net.add_timed("go", 1.0);
//! let back = net.add_timed("back", 1.0);
//! net.input(a, go);
//! net.output(go, b);
//! net.input(b, back);
//! net.output(back, a);
//! let gspn = net.instantiate(&Params::new())?;
//!
//! let p = p_invariants(&gspn, &FarkasParams::default())?;
//! assert_eq!(p.vectors(), &[vec![(0, 1), (1, 1)]]);
//! assert_eq!(p.display(&gspn).to_string(), "a + b = 1");
//! assert!(p.covers_all());
//! assert_eq!(structural_bounds(&gspn, &p), vec![Some(1), Some(1)]);
//! # Ok::<(), petri::Error>(())
//! ```

use std::fmt;

use crate::error::{Error, Result};
use crate::gspn::Gspn;
use crate::incidence::{Incidence, name_or_index};
use crate::net::TransitionId;

/// Parameters of the Farkas algorithm.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FarkasParams {
    /// The most rows the intermediate matrix may hold, the initial rows (one
    /// per place, or per transition) included. A row costs a few dozen bytes
    /// plus 32 bytes per non-zero entry plus one bit per initial row. Default
    /// 100 000.
    pub max_rows: usize,
}

impl Default for FarkasParams {
    fn default() -> Self {
        FarkasParams { max_rows: 100_000 }
    }
}

/// What a run of the Farkas algorithm did.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
pub struct FarkasInfo {
    /// Rows at the start: the number of places (P) or transitions (T).
    pub initial_rows: usize,
    /// The most rows any intermediate matrix held.
    pub rows_peak: usize,
    /// Columns eliminated: at most the number of columns, fewer when some
    /// are zero from the start or become zero in every row (dependent columns).
    pub columns_eliminated: usize,
    /// Pairs of rows of opposite sign examined.
    pub pairs_examined: u64,
    /// Pairs that passed the support test and were combined into a new row.
    pub rows_combined: u64,
}

/// Whether invariants are over places or over transitions.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum InvariantKind {
    /// P-invariants (P-semiflows): `yᵀ·C = 0`.
    Place,
    /// T-invariants (T-semiflows): `C·x = 0`.
    Transition,
}

impl InvariantKind {
    fn plural(self) -> &'static str {
        match self {
            InvariantKind::Place => "P-invariants",
            InvariantKind::Transition => "T-invariants",
        }
    }
}

/// The minimal-support semi-positive invariants of a net, of one kind. Build
/// with [`p_invariants`] or [`t_invariants`].
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct Invariants {
    kind: InvariantKind,
    dimension: usize,
    vectors: Vec<Vec<(u32, u64)>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    token_sums: Option<Vec<u128>>,
    info: FarkasInfo,
}

/// The minimal-support semi-positive P-invariants of `gspn` (`y ≥ 0`,
/// `y ≠ 0`, `yᵀ·C = 0`), with the token sum `y·M0` each one conserves.
///
/// Fails with [`Error::InvariantRowLimit`] if the Farkas algorithm needs more
/// than `params.max_rows` rows, and with [`Error::InvariantOverflow`] if a
/// coefficient does not fit.
pub fn p_invariants(gspn: &Gspn, params: &FarkasParams) -> Result<Invariants> {
    let c = Incidence::new(gspn);
    let (vectors, info) = farkas(c.rows(), c.num_transitions(), params, InvariantKind::Place)?;
    let m0 = gspn.initial_marking();
    let token_sums = vectors.iter().map(|y| dot(y, m0).unwrap_or(0)).collect();
    Ok(Invariants {
        kind: InvariantKind::Place,
        dimension: c.num_places(),
        vectors,
        token_sums: Some(token_sums),
        info,
    })
}

/// The minimal-support semi-positive T-invariants of `gspn` (`x ≥ 0`,
/// `x ≠ 0`, `C·x = 0`).
///
/// Fails like [`p_invariants`].
pub fn t_invariants(gspn: &Gspn, params: &FarkasParams) -> Result<Invariants> {
    let c = Incidence::new(gspn);
    let columns = (0..c.num_transitions())
        .map(|t| c.column(TransitionId(t as u32)).to_vec())
        .collect();
    let (vectors, info) = farkas(columns, c.num_places(), params, InvariantKind::Transition)?;
    Ok(Invariants {
        kind: InvariantKind::Transition,
        dimension: c.num_transitions(),
        vectors,
        token_sums: None,
        info,
    })
}

/// For each place `p`, the bound `min ⌊y·M0 / y_p⌋` over the P-invariants `y`
/// with `y_p > 0`, using `gspn`'s initial marking: no reachable marking puts
/// more tokens in `p`. `None` for a place in no invariant's support (it may
/// still be bounded; only the reachability graph can tell).
///
/// The minimum over minimal-support invariants equals the minimum over all
/// semi-positive invariants (a combination's ratio is a weighted mediant of
/// its parts'), so no better bound follows from P-invariants. Capacities are
/// not taken into account. `invariants` must be the P-invariants of `gspn`'s
/// net (they do not depend on the initial marking, so they may be reused for
/// another one); for T-invariants or vectors of another size every bound is
/// `None`. Bounds above `u64::MAX` saturate.
pub fn structural_bounds(gspn: &Gspn, invariants: &Invariants) -> Vec<Option<u64>> {
    let m0 = gspn.initial_marking();
    let mut bounds: Vec<Option<u64>> = vec![None; m0.len()];
    if invariants.kind != InvariantKind::Place || invariants.dimension != m0.len() {
        return bounds;
    }
    for y in &invariants.vectors {
        let Some(sum) = dot(y, m0) else { continue };
        for &(p, c) in y {
            if c == 0 {
                continue;
            }
            let b = u64::try_from(sum / u128::from(c)).unwrap_or(u64::MAX);
            let slot = &mut bounds[p as usize];
            *slot = Some(slot.map_or(b, |old| old.min(b)));
        }
    }
    bounds
}

/// `Σ y_i · m[i]`, or `None` if an index is out of range. Cannot overflow:
/// fewer than 2³² terms, each below 2⁹⁶.
fn dot(y: &[(u32, u64)], m: &[u32]) -> Option<u128> {
    y.iter().try_fold(0u128, |acc, &(i, c)| {
        let v = *m.get(i as usize)?;
        Some(acc + u128::from(c) * u128::from(v))
    })
}

impl Invariants {
    /// Over places or over transitions.
    pub fn kind(&self) -> InvariantKind {
        self.kind
    }

    /// The length of the vectors: the number of places (P) or transitions (T).
    pub fn dimension(&self) -> usize {
        self.dimension
    }

    /// The invariants, each sparse as `(index, coefficient > 0)` sorted by
    /// index, with coprime coefficients. The list is sorted
    /// lexicographically, so the order is deterministic.
    pub fn vectors(&self) -> &[Vec<(u32, u64)>] {
        &self.vectors
    }

    /// Number of minimal invariants.
    pub fn len(&self) -> usize {
        self.vectors.len()
    }

    /// Whether there is none.
    pub fn is_empty(&self) -> bool {
        self.vectors.is_empty()
    }

    /// For P-invariants, the token sum `y·M0` each one conserves (same order
    /// as [`vectors`](Self::vectors)); `None` for T-invariants.
    pub fn token_sums(&self) -> Option<&[u128]> {
        self.token_sums.as_deref()
    }

    /// What the Farkas run did.
    pub fn info(&self) -> &FarkasInfo {
        &self.info
    }

    /// The places (P) or transitions (T) in no invariant's support, by index.
    pub fn uncovered(&self) -> Vec<u32> {
        let mut covered = vec![false; self.dimension];
        for v in &self.vectors {
            for &(i, _) in v {
                covered[i as usize] = true;
            }
        }
        (0..self.dimension as u32)
            .filter(|&i| !covered[i as usize])
            .collect()
    }

    /// Whether every place (P) or transition (T) is in some invariant's
    /// support. For P-invariants: the net is conservative, hence
    /// structurally bounded. For T-invariants: the net is consistent, which
    /// every live and bounded net is (necessary, not sufficient).
    pub fn covers_all(&self) -> bool {
        self.uncovered().is_empty()
    }

    /// Whether `marking` satisfies every P-invariant: `y·M = y·M0` for each.
    /// Every marking reachable from `M0` does, so `false` proves `marking`
    /// unreachable (`true` proves nothing). Always `false` for T-invariants,
    /// which say nothing about markings, and for a marking whose length is
    /// not the number of places.
    pub fn holds_in(&self, marking: &[u32]) -> bool {
        let Some(sums) = &self.token_sums else {
            return false;
        };
        marking.len() == self.dimension
            && self
                .vectors
                .iter()
                .zip(sums)
                .all(|(y, &s)| dot(y, marking) == Some(s))
    }

    /// The invariants with names, one per line, e.g.
    /// `Think_1 + Eat_1 + 2·Catch_1 = 1` (P, with its token sum) or
    /// `t1 + t2` (T); nothing if there is none. `gspn` gives the names; an
    /// index it lacks prints as `#i`.
    pub fn display<'a>(&'a self, gspn: &'a Gspn) -> DisplayInvariants<'a> {
        DisplayInvariants {
            invariants: self,
            gspn,
        }
    }

    /// The invariant at `index` with names, as in [`display`](Self::display);
    /// `None` if there is no such invariant.
    pub fn display_vector<'a>(&'a self, index: usize, gspn: &'a Gspn) -> Option<DisplayInvariant<'a>> {
        (index < self.vectors.len()).then_some(DisplayInvariant {
            invariants: self,
            index,
            gspn,
        })
    }

    /// The invariants with names, for machine-readable output.
    pub fn named(&self, gspn: &Gspn) -> Vec<NamedInvariant> {
        let names = self.names(gspn);
        self.vectors
            .iter()
            .enumerate()
            .map(|(k, v)| NamedInvariant {
                terms: v
                    .iter()
                    .map(|&(i, c)| NamedTerm {
                        name: name_or_index(names, i as usize),
                        coefficient: c,
                    })
                    .collect(),
                token_sum: self.token_sums.as_ref().and_then(|s| s.get(k).copied()),
            })
            .collect()
    }

    fn names<'a>(&self, gspn: &'a Gspn) -> &'a [String] {
        match self.kind {
            InvariantKind::Place => gspn.place_names(),
            InvariantKind::Transition => gspn.transition_names(),
        }
    }
}

/// One invariant with names, for machine-readable output; see
/// [`Invariants::named`].
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct NamedInvariant {
    /// The support in index order, with coefficients.
    pub terms: Vec<NamedTerm>,
    /// For a P-invariant, the token sum `y·M0` it conserves.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub token_sum: Option<u128>,
}

/// A place or transition of an invariant's support, with its coefficient.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct NamedTerm {
    /// The place's or transition's name.
    pub name: String,
    /// Its coefficient (≥ 1).
    pub coefficient: u64,
}

/// One invariant printed with names; see [`Invariants::display_vector`].
#[derive(Debug, Clone, Copy)]
pub struct DisplayInvariant<'a> {
    invariants: &'a Invariants,
    index: usize,
    gspn: &'a Gspn,
}

impl fmt::Display for DisplayInvariant<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let inv = self.invariants;
        let names = inv.names(self.gspn);
        let Some(v) = inv.vectors.get(self.index) else {
            return Ok(());
        };
        for (k, &(i, c)) in v.iter().enumerate() {
            if k > 0 {
                f.write_str(" + ")?;
            }
            if c != 1 {
                write!(f, "{c}·")?;
            }
            f.write_str(&name_or_index(names, i as usize))?;
        }
        if let Some(sum) = inv.token_sums.as_ref().and_then(|s| s.get(self.index)) {
            write!(f, " = {sum}")?;
        }
        Ok(())
    }
}

/// All invariants printed with names, one per line; see
/// [`Invariants::display`].
#[derive(Debug, Clone, Copy)]
pub struct DisplayInvariants<'a> {
    invariants: &'a Invariants,
    gspn: &'a Gspn,
}

impl fmt::Display for DisplayInvariants<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for index in 0..self.invariants.vectors.len() {
            if index > 0 {
                f.write_str("\n")?;
            }
            let one = DisplayInvariant {
                invariants: self.invariants,
                index,
                gspn: self.gspn,
            };
            write!(f, "{one}")?;
        }
        Ok(())
    }
}

/// `(index, coefficient)` pairs sorted by index.
type SparseVector = Vec<(u32, u64)>;

/// A row of the Farkas matrix.
#[derive(Debug, Clone)]
struct Row {
    /// The `A` part on the columns not yet eliminated (eliminated ones are
    /// zero), sparse and sorted by column.
    rest: Vec<(u32, i128)>,
    /// The `I` part: the combination of initial rows, sparse, sorted, > 0.
    y: Vec<(u32, i128)>,
    /// Bitset of `y`'s support.
    support: Vec<u64>,
    /// `y`'s support size.
    weight: u32,
}

/// The minimal-support `y ≥ 0, y ≠ 0` with `yᵀ·A = 0`, for `A` given by its
/// rows (`(column, value)`, sorted by column), by Fourier–Motzkin elimination
/// with the adjacency test (see the module docs).
fn farkas(
    matrix: Vec<Vec<(u32, i64)>>,
    num_columns: usize,
    params: &FarkasParams,
    kind: InvariantKind,
) -> Result<(Vec<SparseVector>, FarkasInfo)> {
    let n = matrix.len();
    let num_columns = matrix
        .iter()
        .flatten()
        .map(|&(c, _)| c as usize + 1)
        .max()
        .unwrap_or(0)
        .max(num_columns);
    let mut nonzero_column = vec![false; num_columns];
    for &(c, v) in matrix.iter().flatten() {
        if v != 0 {
            nonzero_column[c as usize] = true;
        }
    }
    let columns = nonzero_column.iter().filter(|&&b| b).count();
    let what = kind.plural();
    let limit = |eliminated| Error::InvariantRowLimit {
        what,
        limit: params.max_rows,
        eliminated,
        columns,
    };
    let overflow = |eliminated, limit| Error::InvariantOverflow {
        what,
        limit,
        eliminated,
    };
    if n > params.max_rows {
        return Err(limit(0));
    }

    let words = n.div_ceil(64);
    let mut rows = initial_rows(matrix, words);
    let mut info = FarkasInfo {
        initial_rows: n,
        rows_peak: n,
        ..FarkasInfo::default()
    };

    let mut pos = vec![0usize; num_columns];
    let mut neg = vec![0usize; num_columns];
    let mut union = vec![0u64; words];
    while let Some(j) = pivot_column(&rows, &mut pos, &mut neg) {
        let values: Vec<i128> = rows
            .iter()
            .map(|r| {
                r.rest
                    .binary_search_by_key(&j, |&(c, _)| c)
                    .map_or(0, |k| r.rest[k].1)
            })
            .collect();
        let mut combined =
            combine_pairs(&rows, &values, &mut union, &mut info, params.max_rows).map_err(|e| match e {
                Overflow::Entry => overflow(info.columns_eliminated, i128::MAX as u128),
                Overflow::Rows => limit(info.columns_eliminated),
            })?;
        combined.sort_unstable_by(|x, z| x.y.cmp(&z.y));
        combined.dedup_by(|x, z| x.y == z.y);

        let mut next: Vec<Row> = rows
            .into_iter()
            .zip(&values)
            .filter(|&(_, &v)| v == 0)
            .map(|(r, _)| r)
            .collect();
        next.extend(combined);
        rows = next;
        info.columns_eliminated += 1;
        info.rows_peak = info.rows_peak.max(rows.len());
    }

    let mut vectors =
        normalised_supports(rows).map_err(|()| overflow(info.columns_eliminated, u128::from(u64::MAX)))?;
    vectors.sort_unstable();
    vectors.dedup();
    Ok((vectors, info))
}

/// Why [`combine_pairs`] stopped.
enum Overflow {
    /// An entry outgrew `i128`.
    Entry,
    /// The matrix outgrew the row limit.
    Rows,
}

/// The rows `(1, 0)`…`(0, 1)` of `[A | I]`: each matrix row (zeros
/// dropped, sorted by column) with its own unit vector as combination.
fn initial_rows(matrix: Vec<Vec<(u32, i64)>>, words: usize) -> Vec<Row> {
    matrix
        .into_iter()
        .enumerate()
        .map(|(i, r)| {
            let mut rest: Vec<(u32, i128)> = r
                .into_iter()
                .filter(|&(_, v)| v != 0)
                .map(|(c, v)| (c, i128::from(v)))
                .collect();
            rest.sort_unstable_by_key(|&(c, _)| c);
            let mut support = vec![0u64; words];
            support[i / 64] |= 1 << (i % 64);
            Row {
                rest,
                y: vec![(i as u32, 1)],
                support,
                weight: 1,
            }
        })
        .collect()
}

/// The column to eliminate next: among those not yet zero, the one whose
/// elimination adds the fewest rows (`p·q − p − q` for `p` positive and `q`
/// negative entries), the first on ties; `None` when every column is zero.
/// `pos` and `neg` are scratch, one entry per column.
fn pivot_column(rows: &[Row], pos: &mut [usize], neg: &mut [usize]) -> Option<u32> {
    pos.fill(0);
    neg.fill(0);
    for r in rows {
        for &(c, v) in &r.rest {
            if v > 0 {
                pos[c as usize] += 1;
            } else {
                neg[c as usize] += 1;
            }
        }
    }
    (0..pos.len())
        .filter(|&c| pos[c] + neg[c] > 0)
        .min_by_key(|&c| {
            let (p, q) = (pos[c] as i128, neg[c] as i128);
            (p * q - p - q, c)
        })
        .map(|j| j as u32)
}

/// The new rows of a column's elimination: each pair of a row with a
/// positive (`values[a] > 0`) and a row with a negative entry in the column,
/// combined to cancel it, unless another row's support lies within the
/// pair's (the adjacency test: the result would not be minimal). `union`
/// is scratch of the support's width; `max_rows` bounds the rows kept plus
/// those made.
fn combine_pairs(
    rows: &[Row],
    values: &[i128],
    union: &mut [u64],
    info: &mut FarkasInfo,
    max_rows: usize,
) -> std::result::Result<Vec<Row>, Overflow> {
    let positive: Vec<usize> = (0..rows.len()).filter(|&k| values[k] > 0).collect();
    let negative: Vec<usize> = (0..rows.len()).filter(|&k| values[k] < 0).collect();
    let kept = rows.len() - positive.len() - negative.len();
    // Candidate witnesses for the support test, lightest first.
    let mut by_weight: Vec<usize> = (0..rows.len()).collect();
    by_weight.sort_by_key(|&k| rows[k].weight);

    let mut combined: Vec<Row> = Vec::new();
    for &a in &positive {
        for &b in &negative {
            info.pairs_examined += 1;
            let mut weight = 0;
            for (u, (x, z)) in union.iter_mut().zip(rows[a].support.iter().zip(&rows[b].support)) {
                *u = x | z;
                weight += u.count_ones();
            }
            let dominated = by_weight
                .iter()
                .take_while(|&&k| rows[k].weight <= weight)
                .any(|&k| {
                    k != a && k != b && rows[k].support.iter().zip(union.iter()).all(|(s, u)| s & !u == 0)
                });
            if dominated {
                continue;
            }
            let row =
                combine(&rows[a], values[a], &rows[b], values[b], union, weight).ok_or(Overflow::Entry)?;
            combined.push(row);
            info.rows_combined += 1;
            if kept + combined.len() > max_rows {
                return Err(Overflow::Rows);
            }
        }
    }
    Ok(combined)
}

/// The combinations `y` of the final rows, each divided by the gcd of its
/// coefficients, in the order of `rows`; `Err` if a coefficient exceeds
/// `u64`.
fn normalised_supports(rows: Vec<Row>) -> std::result::Result<Vec<SparseVector>, ()> {
    let mut vectors = Vec::with_capacity(rows.len());
    for r in rows {
        let g = r.y.iter().fold(0u128, |g, &(_, v)| gcd(g, v.unsigned_abs()));
        let v =
            r.y.iter()
                .map(|&(i, c)| {
                    let c = c.unsigned_abs() / g.max(1);
                    u64::try_from(c).map(|c| (i, c))
                })
                .collect::<std::result::Result<Vec<_>, _>>()
                .map_err(|_| ())?;
        vectors.push(v);
    }
    Ok(vectors)
}

/// The row `α·a + β·b` that cancels the column where `a` has `va > 0` and `b`
/// has `vb < 0`, divided by the gcd of its entries; `None` on overflow.
fn combine(a: &Row, va: i128, b: &Row, vb: i128, union: &[u64], weight: u32) -> Option<Row> {
    let (mut alpha, mut beta) = (vb.checked_neg()?, va);
    let g = gcd(alpha.unsigned_abs(), beta.unsigned_abs());
    let g = i128::try_from(g).ok()?;
    alpha /= g;
    beta /= g;
    let mut rest = merge(&a.rest, alpha, &b.rest, beta)?;
    let mut y = merge(&a.y, alpha, &b.y, beta)?;
    let g = rest
        .iter()
        .chain(&y)
        .fold(0u128, |g, &(_, v)| gcd(g, v.unsigned_abs()));
    if g > 1 {
        let g = i128::try_from(g).ok()?;
        for (_, v) in rest.iter_mut().chain(y.iter_mut()) {
            *v /= g;
        }
    }
    Some(Row {
        rest,
        y,
        support: union.to_vec(),
        weight,
    })
}

/// `α·x + β·z` for sparse sorted vectors, zeros dropped; `None` on overflow.
fn merge(x: &[(u32, i128)], alpha: i128, z: &[(u32, i128)], beta: i128) -> Option<Vec<(u32, i128)>> {
    let mut out = Vec::with_capacity(x.len() + z.len());
    let (mut i, mut k) = (0, 0);
    while i < x.len() || k < z.len() {
        let (c, v) = match (x.get(i), z.get(k)) {
            (Some(&(cx, vx)), Some(&(cz, vz))) if cx == cz => {
                i += 1;
                k += 1;
                (cx, alpha.checked_mul(vx)?.checked_add(beta.checked_mul(vz)?)?)
            }
            (Some(&(cx, vx)), Some(&(cz, _))) if cx < cz => {
                i += 1;
                (cx, alpha.checked_mul(vx)?)
            }
            (Some(&(cx, vx)), None) => {
                i += 1;
                (cx, alpha.checked_mul(vx)?)
            }
            (_, Some(&(cz, vz))) => {
                k += 1;
                (cz, beta.checked_mul(vz)?)
            }
            (None, None) => break,
        };
        if v != 0 {
            out.push((c, v));
        }
    }
    Some(out)
}

fn gcd(mut a: u128, mut b: u128) -> u128 {
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn merge_and_gcd() {
        assert_eq!(gcd(12, 18), 6);
        assert_eq!(gcd(0, 5), 5);
        assert_eq!(gcd(0, 0), 0);
        let x = [(0, 1), (2, 3)];
        let z = [(1, 5), (2, -1)];
        assert_eq!(merge(&x, 1, &z, 3), Some(vec![(0, 1), (1, 15)]));
        assert_eq!(merge(&x, i128::MAX, &z, 1), None);
    }

    #[test]
    fn farkas_on_a_small_matrix() {
        // Rows p0..p2, one column: p0 − p1 − p2 = 0 has rays p0+p1, p0+p2.
        let a = vec![vec![(0, 1)], vec![(0, -1)], vec![(0, -1)]];
        let (v, info) = farkas(a, 1, &FarkasParams::default(), InvariantKind::Place).unwrap();
        assert_eq!(v, vec![vec![(0, 1), (1, 1)], vec![(0, 1), (2, 1)]]);
        assert_eq!(info.columns_eliminated, 1);
        assert_eq!(info.pairs_examined, 2);
        // Multiplicities: 2·p0 = 3·p1 gives 3·p0 + 2·p1.
        let a = vec![vec![(0, 2)], vec![(0, -3)]];
        let (v, _) = farkas(a, 1, &FarkasParams::default(), InvariantKind::Place).unwrap();
        assert_eq!(v, vec![vec![(0, 3), (1, 2)]]);
    }

    #[test]
    fn empty_matrices() {
        let (v, info) = farkas(vec![], 3, &FarkasParams::default(), InvariantKind::Place).unwrap();
        assert!(v.is_empty());
        assert_eq!(info.columns_eliminated, 0);
        let (v, _) = farkas(
            vec![vec![], vec![]],
            0,
            &FarkasParams::default(),
            InvariantKind::Place,
        )
        .unwrap();
        assert_eq!(v, vec![vec![(0, 1)], vec![(1, 1)]]);
    }
}
