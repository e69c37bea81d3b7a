//! Compressed sparse rows whose values come from a small dictionary.
//!
//! Every entry of a GSPN's generator is `rate[t] · c` where the pair
//! `(t, c)` — transition and coefficient (server factor × vanishing path
//! probability) — takes few distinct values. Entries therefore store an index
//! into a dictionary of pairs (2 bytes when there are at most 65,536 of them,
//! 4 otherwise) instead of a transition and a coefficient (12 bytes); binding
//! new rates only recomputes the dictionary's values. The solvers are bound by
//! memory traffic, so this makes every pass over the chain faster.

/// Dictionary indices, as narrow as the dictionary allows.
#[derive(Debug, Clone)]
pub(crate) enum Ids {
    /// At most 65,536 distinct values.
    U16(Vec<u16>),
    /// More.
    U32(Vec<u32>),
}

impl Ids {
    pub(crate) fn new(ids: Vec<u32>, dictionary_len: usize) -> Ids {
        if dictionary_len <= usize::from(u16::MAX) + 1 {
            let narrow = ids.iter().map(|&i| i as u16).collect();
            drop(ids);
            Ids::U16(narrow)
        } else {
            Ids::U32(ids)
        }
    }

    /// `len` zeros, as narrow as a dictionary of `dictionary_len` allows.
    pub(crate) fn zeros(len: usize, dictionary_len: usize) -> Ids {
        if dictionary_len <= usize::from(u16::MAX) + 1 {
            Ids::U16(vec![0; len])
        } else {
            Ids::U32(vec![0; len])
        }
    }

    /// Sets entry `k` to `id` (which the width holds).
    #[inline]
    pub(crate) fn set(&mut self, k: usize, id: usize) {
        match self {
            Ids::U16(v) => v[k] = id as u16,
            Ids::U32(v) => v[k] = id as u32,
        }
    }

    #[inline]
    pub(crate) fn get(&self, k: usize) -> usize {
        match self {
            Ids::U16(v) => usize::from(v[k]),
            Ids::U32(v) => v[k] as usize,
        }
    }

    pub(crate) fn bytes(&self) -> usize {
        match self {
            Ids::U16(v) => v.capacity() * 2,
            Ids::U32(v) => v.capacity() * 4,
        }
    }
}

/// Where each row starts (and, last, the number of entries): 4 bytes per
/// row when the entries number at most `u32::MAX`, 8 otherwise.
#[derive(Debug, Clone)]
pub(crate) enum Offsets {
    /// At most `u32::MAX` entries.
    U32(Vec<u32>),
    /// More.
    U64(Vec<u64>),
}

/// An integer type of [`Offsets`].
pub(crate) trait Offset: Copy {
    const ZERO: Self;
    fn to(self) -> usize;
    fn of(v: usize) -> Self;
}

impl Offset for u32 {
    const ZERO: u32 = 0;
    #[inline]
    fn to(self) -> usize {
        self as usize
    }
    #[inline]
    fn of(v: usize) -> u32 {
        v as u32
    }
}

impl Offset for u64 {
    const ZERO: u64 = 0;
    #[inline]
    fn to(self) -> usize {
        self as usize
    }
    #[inline]
    fn of(v: usize) -> u64 {
        v as u64
    }
}

impl Offsets {
    /// `offsets` (ascending from 0), narrowed when its last value fits.
    pub(crate) fn new(offsets: Vec<u64>) -> Offsets {
        if offsets.last().is_none_or(|&m| m <= u64::from(u32::MAX)) {
            let narrow = offsets.iter().map(|&o| o as u32).collect();
            drop(offsets);
            Offsets::U32(narrow)
        } else {
            Offsets::U64(offsets)
        }
    }

    /// Start of row `j` (`j = rows` gives the number of entries).
    #[inline]
    pub(crate) fn get(&self, j: usize) -> usize {
        match self {
            Offsets::U32(v) => v[j] as usize,
            Offsets::U64(v) => v[j] as usize,
        }
    }

    /// Number of offsets (rows + 1).
    pub(crate) fn len(&self) -> usize {
        match self {
            Offsets::U32(v) => v.len(),
            Offsets::U64(v) => v.len(),
        }
    }

    /// Heap bytes.
    pub(crate) fn bytes(&self) -> usize {
        match self {
            Offsets::U32(v) => v.capacity() * 4,
            Offsets::U64(v) => v.capacity() * 8,
        }
    }
}

/// Rows of `(index, value id)` entries, indices sorted within each row.
#[derive(Debug, Clone)]
pub(crate) struct Rows {
    pub offsets: Offsets,
    pub index: Vec<u32>,
    pub ids: Ids,
    /// Per row, how many entries have an index below the row's own
    /// (computed by [`Rows::split_diagonal`], for triangular sweeps).
    pub below: Vec<u32>,
}

/// An index type of the dictionary.
trait Id: Copy {
    fn at(self) -> usize;
}

impl Id for u16 {
    #[inline]
    fn at(self) -> usize {
        usize::from(self)
    }
}

impl Id for u32 {
    #[inline]
    fn at(self) -> usize {
        self as usize
    }
}

/// Dot product with two independent accumulators, so that consecutive
/// additions do not wait on each other (rows are short; the sweeps are bound
/// by this latency, not by memory bandwidth).
/// `x` holds the states from `offset` on.
#[inline(always)]
fn dot<I: Id>(index: &[u32], ids: &[I], values: &[f64], x: &[f64], offset: usize) -> f64 {
    let (mut s0, mut s1) = (0.0, 0.0);
    let mut pairs = index.chunks_exact(2).zip(ids.chunks_exact(2));
    for (i, id) in &mut pairs {
        s0 += x[i[0] as usize - offset] * values[id[0].at()];
        s1 += x[i[1] as usize - offset] * values[id[1].at()];
    }
    if index.len() % 2 == 1 {
        let k = index.len() - 1;
        s0 += x[index[k] as usize - offset] * values[ids[k].at()];
    }
    s0 + s1
}

impl Rows {
    /// Builds rows from `(row, index, id)` entries.
    pub(crate) fn from_entries(n: usize, mut entries: Vec<(u32, u32, u32)>, dictionary_len: usize) -> Rows {
        entries.sort_unstable_by_key(|e| (e.0, e.1));
        let mut offsets = vec![0u64; n + 1];
        for e in &entries {
            offsets[e.0 as usize + 1] += 1;
        }
        for j in 0..n {
            offsets[j + 1] += offsets[j];
        }
        let mut rows = Rows {
            offsets: Offsets::new(offsets),
            index: entries.iter().map(|e| e.1).collect(),
            ids: Ids::new(entries.iter().map(|e| e.2).collect(), dictionary_len),
            below: Vec::new(),
        };
        rows.split_diagonal();
        rows
    }

    /// Records where each row crosses the diagonal.
    pub(crate) fn split_diagonal(&mut self) {
        self.below = (0..self.len())
            .map(|j| {
                let (a, b) = self.range(j);
                self.index[a..b].partition_point(|&i| (i as usize) < j) as u32
            })
            .collect();
    }

    /// Number of rows.
    pub(crate) fn len(&self) -> usize {
        self.offsets.len() - 1
    }

    #[inline]
    pub(crate) fn range(&self, j: usize) -> (usize, usize) {
        (self.offsets.get(j), self.offsets.get(j + 1))
    }

    #[inline]
    fn dot_span(&self, a: usize, b: usize, values: &[f64], x: &[f64]) -> f64 {
        self.dot_span_offset(a, b, values, x, 0)
    }

    /// Dot product over entries `a..b`, with `x[i - offset]` for state `i`.
    #[inline(always)]
    pub(crate) fn dot_span_offset(
        &self,
        a: usize,
        b: usize,
        values: &[f64],
        x: &[f64],
        offset: usize,
    ) -> f64 {
        if a >= b {
            return 0.0;
        }
        match &self.ids {
            Ids::U16(v) => dot(&self.index[a..b], &v[a..b], values, x, offset),
            Ids::U32(v) => dot(&self.index[a..b], &v[a..b], values, x, offset),
        }
    }

    /// `Σ_k x[index_k] · values[id_k]` over row `j`.
    #[inline]
    pub(crate) fn dot_row(&self, j: usize, values: &[f64], x: &[f64]) -> f64 {
        let (a, b) = self.range(j);
        self.dot_span(a, b, values, x)
    }

    /// Heap bytes.
    pub(crate) fn heap_bytes(&self) -> usize {
        self.offsets.bytes() + self.index.capacity() * 4 + self.ids.bytes() + self.below.capacity() * 4
    }
}

/// A chain for one binding of the rates: incoming rows, the dictionary's
/// values and the exit rates.
pub(crate) struct Chain<'a> {
    pub incoming: &'a Rows,
    pub values: &'a [f64],
    pub exit: &'a [f64],
}

impl Chain<'_> {
    /// Number of states.
    pub(crate) fn n(&self) -> usize {
        self.exit.len()
    }

    /// Total exit rate of state `j` (self-loops excluded).
    #[inline]
    pub(crate) fn exit(&self, j: usize) -> f64 {
        self.exit[j]
    }

    /// `Σ_{i≠j} x_i q_ij`.
    #[inline]
    pub(crate) fn inflow(&self, j: usize, x: &[f64]) -> f64 {
        self.incoming.dot_row(j, self.values, x)
    }

    /// Relative residual of `x`: `‖x Q (+ b)‖₁ / Σ_j exit_j x_j`, the total
    /// flow imbalance over the total flow; `rhs` is `b`, or none for the
    /// stationary equations.
    pub(crate) fn residual(&self, x: &[f64], rhs: Option<&[f64]>) -> f64 {
        let (mut imbalance, mut flow) = (0.0, 0.0);
        for j in 0..self.n() {
            let b = rhs.map_or(0.0, |b| b[j]);
            let out = self.exit(j) * x[j];
            imbalance += (self.inflow(j, x) + b - out).abs();
            flow += out.abs();
        }
        if flow > 0.0 { imbalance / flow } else { imbalance }
    }

    /// Calls `f(i, q_ij)` for the incoming entries of `j`.
    pub(crate) fn for_each_in(&self, j: usize, f: &mut dyn FnMut(usize, f64)) {
        let (a, b) = self.incoming.range(j);
        for k in a..b {
            f(
                self.incoming.index[k] as usize,
                self.values[self.incoming.ids.get(k)],
            );
        }
    }
}

/// Index of the largest finite positive entry (0 if none).
pub(crate) fn most_probable(x: &[f64]) -> usize {
    (0..x.len())
        .max_by(|&a, &b| x[a].total_cmp(&x[b]))
        .filter(|&k| x[k] > 0.0 && x[k].is_finite())
        .unwrap_or(0)
}
