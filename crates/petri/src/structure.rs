//! Finding a product structure in a net's reachable markings: a partition of
//! the places into *components* such that the reachable set is exactly the
//! product of the components' local state spaces, and each transition's
//! enabling, effect and rate factor over the components (a superposed GSPN:
//! its generator is `Σ_t rate_t ⊗_k W_t^(k)` plus the diagonal).
//!
//! How ([`Structure::detect`]):
//!
//! 1. **Place order.** Places tied by a minimal P-invariant are grouped
//!    (union of overlapping supports; a place in none is a group of its
//!    own), the groups ordered to minimise the sum over transitions of the
//!    distance between the first and last group each touches (exhaustively
//!    up to [`MAX_EXHAUSTIVE_GROUPS`] groups, in the net's order beyond),
//!    places within a group in the net's order. Or the order of a partition
//!    given by the user (`--partition`).
//! 2. **Symbolic reachability** (`crate::mdd`): the reachable markings as
//!    a decision diagram over that order, by saturation, each place capped
//!    by its structural bound.
//! 3. **Cuts.** A depth reached by a single node splits the set into a
//!    product (what lies above times what lies below). The components are
//!    the runs of places between cuts (with a user partition: between the
//!    user's boundaries that are cuts — the others are merged, and said).
//!    So the product is exact by construction: places whose counts are
//!    correlated (Kanban's cells 2 and 3, bound by `#Pkan2 = #Pkan3`) end
//!    up in one component.
//! 4. **Local spaces**: the paths of the diagram between two cuts, in
//!    lexicographic order (a component's local state is ranked by binary
//!    search among them). Adjacent components with fewer than
//!    [`COARSEN_LIMIT`] joint states are merged (their product), so that no
//!    level is too small to amortise the solver's per-row work.
//!
//! The invariant groups' own projections are counted too, for the report
//! (`gspn info --structure`): their product is the *potential* state space,
//! which the reachable set fills only when no group needs merging.
//!
//! For a net with immediate transitions the diagram holds the P/T net's
//! reachable markings (priorities do not factor over places): a superset of
//! the GSPN's, which [`crate::structured`] narrows by an explicit search.

use std::collections::BTreeMap;

use crate::error::{Error, Result};
use crate::gspn::Gspn;
use crate::invariants::{FarkasParams, p_invariants, structural_bounds};
use crate::mdd::{EMPTY, Mdd, MddLimits, TERMINAL};
use crate::net::{PlaceId, TransitionId};

/// Most invariant groups ordered exhaustively (8! = 40,320 orders).
pub const MAX_EXHAUSTIVE_GROUPS: usize = 8;
/// Adjacent components whose product has at most this many local states
/// are merged into one.
pub const COARSEN_LIMIT: u128 = 1024;
/// Largest local state space of a component (beyond: an error, and the
/// caller uses the explicit engine).
pub const MAX_LOCAL_STATES: usize = 1 << 24;

/// How to look for the structure.
#[derive(Debug, Clone, Default)]
pub struct StructureParams {
    /// Components given by the user, outermost first, each a list of
    /// places; every place must appear exactly once. `None`: found
    /// automatically.
    pub partition: Option<Vec<Vec<PlaceId>>>,
}

/// A component: some places and the local markings they take.
#[derive(Debug, Clone)]
pub struct Component {
    /// Its places, in the order of the local markings' entries.
    pub places: Vec<PlaceId>,
    /// Local markings, `places.len()` counts each (the local state `l` is
    /// `states[l·w .. (l+1)·w]`), lexicographically sorted unless
    /// [`reorder`](Self::reorder)ed.
    states: Vec<u32>,
    /// The local states in lexicographic order of their markings, for
    /// ranking; empty while the states themselves are in that order.
    sorted: Vec<u32>,
}

impl Component {
    /// Number of local states.
    pub fn len(&self) -> usize {
        if self.places.is_empty() {
            1
        } else {
            self.states.len() / self.places.len()
        }
    }

    /// Whether it has no local state (never: a component holds at least
    /// the initial marking's part).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The token counts of local state `l`, one per place.
    #[inline]
    pub fn state(&self, l: usize) -> &[u32] {
        let w = self.places.len();
        &self.states[l * w..(l + 1) * w]
    }

    /// The local state with these counts, if it is one.
    pub fn rank(&self, counts: &[u32]) -> Option<usize> {
        let at = |i: usize| {
            if self.sorted.is_empty() {
                i
            } else {
                self.sorted[i] as usize
            }
        };
        let (mut lo, mut hi) = (0, self.len());
        while lo < hi {
            let mid = (lo + hi) / 2;
            match self.state(at(mid)).cmp(counts) {
                std::cmp::Ordering::Less => lo = mid + 1,
                std::cmp::Ordering::Greater => hi = mid,
                std::cmp::Ordering::Equal => return Some(at(mid)),
            }
        }
        None
    }

    /// Renumbers the local states: the new state `i` is the old
    /// `order[i]` (a permutation).
    pub(crate) fn reorder(&mut self, order: &[u32]) {
        let w = self.places.len();
        if w == 0 {
            return;
        }
        let mut states = Vec::with_capacity(self.states.len());
        for &o in order {
            states.extend_from_slice(self.state(o as usize));
        }
        self.states = states;
        let mut sorted: Vec<u32> = (0..self.len() as u32).collect();
        sorted.sort_by(|&a, &b| self.state(a as usize).cmp(self.state(b as usize)));
        self.sorted = sorted;
    }

    /// Heap bytes of the local markings.
    pub fn heap_bytes(&self) -> usize {
        self.states.capacity() * 4 + self.places.capacity() * 4
    }
}

/// A group of places tied by P-invariants, with the number of distinct
/// markings they take in the reachable set.
#[derive(Debug, Clone, serde::Serialize)]
pub struct GroupInfo {
    /// Place names.
    pub places: Vec<String>,
    /// Distinct markings of these places among the reachable markings
    /// (an upper bound when `exact` is false: too many to count one by one).
    pub projected_states: u128,
    /// Whether `projected_states` was counted exactly.
    pub exact: bool,
}

/// The product structure of a net's reachable set.
#[derive(Debug, Clone)]
pub struct Structure {
    components: Vec<Component>,
    reachable: u128,
    groups: Vec<GroupInfo>,
    notes: Vec<String>,
    mdd_nodes: usize,
    exact: bool,
    reversible: Option<bool>,
    seconds: f64,
}

impl Structure {
    /// Finds the structure of `gspn`'s reachable markings (see the module
    /// docs). Fails when the symbolic search exceeds its limits (a place
    /// without a structural bound grows past 65,536 tokens, 4 million
    /// diagram nodes, or 2²⁶ children entries — a place holding many
    /// tokens), when a component would have more than
    /// [`MAX_LOCAL_STATES`] local states, or on a bad partition.
    pub fn detect(gspn: &Gspn, params: &StructureParams) -> Result<Structure> {
        let start = std::time::Instant::now();
        let bounds = match p_invariants(gspn, &FarkasParams::default()) {
            Ok(inv) => structural_bounds(gspn, &inv),
            Err(_) => vec![None; gspn.num_places()],
        };
        let groups: Vec<Vec<u32>> = match &params.partition {
            Some(p) => checked_partition(gspn, p)?,
            None => ordered_groups(gspn),
        };
        let order: Vec<u32> = groups.iter().flatten().copied().collect();
        let mut mdd = Mdd::new(gspn, &order, &bounds, MddLimits::default());
        let root = mdd.forward(gspn.initial_marking())?;
        let reachable = mdd.count(root);
        let per_depth = mdd.nodes_per_depth(root);
        // Group boundaries (depths where a group starts), then cuts.
        let mut starts = Vec::with_capacity(groups.len());
        let mut d = 0;
        for g in &groups {
            starts.push(d);
            d += g.len();
        }
        let is_cut = |d: usize| d == 0 || per_depth[d] == 1;
        let mut notes = Vec::new();
        let boundaries: Vec<usize> = if params.partition.is_some() {
            let names = gspn.place_names();
            for (k, &s) in starts.iter().enumerate().skip(1) {
                if !is_cut(s) {
                    notes.push(format!(
                        "components {} and {} merged: the markings of `{}` depend on those before it",
                        k,
                        k + 1,
                        names[order[s] as usize]
                    ));
                }
            }
            starts.iter().copied().filter(|&s| is_cut(s)).collect()
        } else {
            (0..order.len()).filter(|&d| is_cut(d)).collect()
        };
        let group_info = group_projections(&mdd, root, &groups, &starts, gspn);
        let mut components = Vec::new();
        for (i, &s) in boundaries.iter().enumerate() {
            let end = boundaries.get(i + 1).copied().unwrap_or(order.len());
            components.push(segment(&mdd, root, s, end, gspn)?);
        }
        if params.partition.is_none() {
            components = coarsen(components);
            // The largest component innermost: the solver's rows are then
            // as long as possible (see `crate::sweep`).
            if let Some(big) =
                (0..components.len()).max_by_key(|&k| (components[k].len(), std::cmp::Reverse(k)))
            {
                let c = components.remove(big);
                components.push(c);
            }
        }
        let product = components
            .iter()
            .fold(1u128, |acc, c| acc.saturating_mul(c.len() as u128));
        let reversible = if gspn.num_immediate() == 0 {
            Some(mdd.backward_covers(root, gspn.initial_marking())?)
        } else {
            None
        };
        Ok(Structure {
            reversible,
            exact: product == reachable,
            components,
            reachable,
            groups: group_info,
            notes,
            mdd_nodes: mdd.arena_len(),
            seconds: start.elapsed().as_secs_f64(),
        })
    }

    /// The components, outermost first.
    pub fn components(&self) -> &[Component] {
        &self.components
    }

    /// Mutable access to the components (to renumber their local states).
    pub(crate) fn components_mut(&mut self) -> &mut [Component] {
        &mut self.components
    }

    /// Reachable markings of the P/T net (see the module docs).
    pub fn reachable(&self) -> u128 {
        self.reachable
    }

    /// Product of the components' local state counts: the reachable count
    /// when [`is_exact`](Self::is_exact).
    pub fn product(&self) -> u128 {
        self.components
            .iter()
            .fold(1u128, |acc, c| acc.saturating_mul(c.len() as u128))
    }

    /// Whether the reachable set is exactly the product of the components'
    /// local spaces (always, unless something is badly wrong).
    pub fn is_exact(&self) -> bool {
        self.exact
    }

    /// For a net without immediate transitions, whether every reachable
    /// marking reaches the initial one back (then its CTMC is irreducible);
    /// `None` with immediate transitions (decided by an explicit search).
    pub fn reversible(&self) -> Option<bool> {
        self.reversible
    }

    /// The groups of places tied by P-invariants and their projections.
    pub fn groups(&self) -> &[GroupInfo] {
        &self.groups
    }

    /// Product of the groups' projected state counts: the potential state
    /// space of the invariant groups.
    pub fn potential(&self) -> u128 {
        self.groups
            .iter()
            .fold(1u128, |acc, g| acc.saturating_mul(g.projected_states))
    }

    /// What was merged and why (with a user partition).
    pub fn notes(&self) -> &[String] {
        &self.notes
    }

    /// Decision-diagram nodes created by the symbolic search.
    pub fn mdd_nodes(&self) -> usize {
        self.mdd_nodes
    }

    /// Seconds spent finding the structure.
    pub fn seconds(&self) -> f64 {
        self.seconds
    }

    /// The component and local state of each place in a marking: for place
    /// `p`, `(component, position in its places)`.
    pub fn place_positions(&self, num_places: usize) -> Vec<(usize, usize)> {
        let mut pos = vec![(usize::MAX, 0); num_places];
        for (k, c) in self.components.iter().enumerate() {
            for (i, p) in c.places.iter().enumerate() {
                pos[p.index()] = (k, i);
            }
        }
        pos
    }

    /// The local states of a marking, one per component (`None` if a part
    /// is not a local state).
    pub fn locals_of(&self, marking: &[u32]) -> Option<Vec<usize>> {
        self.components
            .iter()
            .map(|c| {
                let counts: Vec<u32> = c.places.iter().map(|p| marking[p.index()]).collect();
                c.rank(&counts)
            })
            .collect()
    }
}

/// The partition checked (every place exactly once), as place indices.
fn checked_partition(gspn: &Gspn, partition: &[Vec<PlaceId>]) -> Result<Vec<Vec<u32>>> {
    let n = gspn.num_places();
    let mut seen = vec![false; n];
    let mut groups = Vec::new();
    for g in partition {
        if g.is_empty() {
            return Err(Error::Invalid("a component of the partition has no place".into()));
        }
        let mut out = Vec::new();
        for p in g {
            if p.index() >= n {
                return Err(Error::Invalid(format!(
                    "place index {} is out of range",
                    p.index()
                )));
            }
            if std::mem::replace(&mut seen[p.index()], true) {
                return Err(Error::Invalid(format!(
                    "place `{}` appears twice in the partition",
                    gspn.place_names()[p.index()]
                )));
            }
            out.push(p.0);
        }
        groups.push(out);
    }
    let missing: Vec<&str> = (0..n)
        .filter(|&p| !seen[p])
        .map(|p| gspn.place_names()[p].as_str())
        .collect();
    if !missing.is_empty() {
        return Err(Error::Invalid(format!(
            "the partition leaves out {} place(s): {}",
            missing.len(),
            missing.join(", ")
        )));
    }
    Ok(groups)
}

/// Places grouped by overlapping minimal P-invariant supports, groups
/// ordered by the sum of transition spans (see the module docs).
fn ordered_groups(gspn: &Gspn) -> Vec<Vec<u32>> {
    let n = gspn.num_places();
    let mut parent: Vec<usize> = (0..n).collect();
    fn find(parent: &mut [usize], mut x: usize) -> usize {
        while parent[x] != x {
            parent[x] = parent[parent[x]];
            x = parent[x];
        }
        x
    }
    if let Ok(inv) = p_invariants(gspn, &FarkasParams::default()) {
        for y in inv.vectors() {
            let mut first = None;
            for &(p, c) in y {
                if c == 0 {
                    continue;
                }
                let r = find(&mut parent, p as usize);
                match first {
                    None => first = Some(r),
                    Some(f) => {
                        let (a, b) = (f.min(r), f.max(r));
                        parent[b] = a;
                        first = Some(a);
                    }
                }
            }
        }
    }
    // Groups in order of their first place.
    let mut by_root: BTreeMap<usize, Vec<u32>> = BTreeMap::new();
    for p in 0..n {
        let r = find(&mut parent, p);
        by_root.entry(r).or_default().push(p as u32);
    }
    let mut groups: Vec<Vec<u32>> = by_root.into_values().collect();
    groups.sort_by_key(|g| g[0]);
    let mut group_of = vec![0usize; n];
    for (k, g) in groups.iter().enumerate() {
        for &p in g {
            group_of[p as usize] = k;
        }
    }
    // The groups each transition touches.
    let touched: Vec<Vec<usize>> = (0..gspn.num_transitions())
        .map(|t| {
            let t = TransitionId(t as u32);
            let mut g: Vec<usize> = gspn
                .inputs(t)
                .iter()
                .chain(gspn.outputs(t))
                .chain(gspn.inhibitors(t))
                .map(|&(p, _)| group_of[p as usize])
                .collect();
            g.sort_unstable();
            g.dedup();
            g
        })
        .filter(|g| g.len() > 1)
        .collect();
    let k = groups.len();
    if k <= 2 || k > MAX_EXHAUSTIVE_GROUPS || touched.is_empty() {
        return groups;
    }
    let cost = |perm: &[usize]| -> usize {
        let mut pos = vec![0; k];
        for (i, &g) in perm.iter().enumerate() {
            pos[g] = i;
        }
        touched
            .iter()
            .map(|gs| {
                let (lo, hi) = gs
                    .iter()
                    .fold((usize::MAX, 0), |(lo, hi), &g| (lo.min(pos[g]), hi.max(pos[g])));
                hi - lo
            })
            .sum()
    };
    let mut perm: Vec<usize> = (0..k).collect();
    let (mut best, mut best_cost) = (perm.clone(), cost(&perm));
    while next_permutation(&mut perm) {
        let c = cost(&perm);
        if c < best_cost {
            best_cost = c;
            best = perm.clone();
        }
    }
    best.into_iter().map(|g| groups[g].clone()).collect()
}

/// Rearranges into the next lexicographic permutation; false after the last.
fn next_permutation(p: &mut [usize]) -> bool {
    let n = p.len();
    if n < 2 {
        return false;
    }
    let mut i = n - 1;
    while i > 0 && p[i - 1] >= p[i] {
        i -= 1;
    }
    if i == 0 {
        return false;
    }
    let mut j = n - 1;
    while p[j] <= p[i - 1] {
        j -= 1;
    }
    p.swap(i - 1, j);
    p[i..].reverse();
    true
}

/// The component of depths `start..end`: the unique node at `start` (a
/// cut, or the root) and the paths from it down to `end`.
fn segment(mdd: &Mdd, root: u32, start: usize, end: usize, gspn: &Gspn) -> Result<Component> {
    let top = mdd
        .reachable_nodes(root)
        .into_iter()
        .find(|&n| mdd.depth(n) == start)
        .ok_or_else(|| Error::Invalid("internal: no node at a cut of the decision diagram".into()))?;
    let states = mdd.enumerate(top, end, MAX_LOCAL_STATES).ok_or_else(|| {
        Error::Invalid(format!(
            "a component of the reachable set has more than {MAX_LOCAL_STATES} local states (places from `{}` on)",
            gspn.place_names()[mdd.place_at(start) as usize]
        ))
    })?;
    Ok(Component {
        places: (start..end).map(|d| PlaceId(mdd.place_at(d))).collect(),
        states,
        sorted: Vec::new(),
    })
}

/// Merges adjacent components while their product stays within
/// [`COARSEN_LIMIT`] local states.
fn coarsen(components: Vec<Component>) -> Vec<Component> {
    let mut out: Vec<Component> = Vec::new();
    for c in components {
        match out.last_mut() {
            Some(last) if (last.len() as u128) * (c.len() as u128) <= COARSEN_LIMIT => {
                *last = product(last, &c);
            }
            _ => out.push(c),
        }
    }
    out
}

/// The product of two components (`a`'s places first; lexicographic order
/// is kept).
fn product(a: &Component, b: &Component) -> Component {
    let mut states = Vec::with_capacity(a.states.len() * b.len() + b.states.len() * a.len());
    for i in 0..a.len() {
        for j in 0..b.len() {
            states.extend_from_slice(a.state(i));
            states.extend_from_slice(b.state(j));
        }
    }
    Component {
        places: a.places.iter().chain(&b.places).copied().collect(),
        states,
        sorted: Vec::new(),
    }
}

/// Most distinct markings of a group counted one by one for the report;
/// beyond, the count is an upper bound (the paths from every node).
const MAX_PROJECTION_COUNTED: usize = 1 << 20;

/// Each invariant group's projection of the reachable set, counted.
fn group_projections(
    mdd: &Mdd,
    root: u32,
    groups: &[Vec<u32>],
    starts: &[usize],
    gspn: &Gspn,
) -> Vec<GroupInfo> {
    let names = gspn.place_names();
    let all = mdd.reachable_nodes(root);
    let mut out = Vec::new();
    for (g, &s) in groups.iter().zip(starts) {
        let end = s + g.len();
        let tops: Vec<u32> = all.iter().copied().filter(|&n| mdd.depth(n) == s).collect();
        let mut seen: std::collections::BTreeSet<Vec<u32>> = std::collections::BTreeSet::new();
        let mut exact = true;
        for &t in &tops {
            match mdd.enumerate(t, end, MAX_PROJECTION_COUNTED) {
                Some(v) => seen.extend(v.chunks(g.len()).map(<[u32]>::to_vec)),
                None => exact = false,
            }
            if !exact || seen.len() > MAX_PROJECTION_COUNTED {
                exact = false;
                break;
            }
        }
        let projected_states = if exact {
            seen.len() as u128
        } else {
            let mut memo = hashbrown::HashMap::new();
            tops.iter()
                .map(|&t| truncated_count(mdd, t, end, &mut memo))
                .fold(0u128, u128::saturating_add)
        };
        out.push(GroupInfo {
            places: g.iter().map(|&p| names[p as usize].clone()).collect(),
            projected_states,
            exact,
        });
    }
    out
}

/// Number of paths from `n` down to depth `end` (not to the terminal).
fn truncated_count(mdd: &Mdd, n: u32, end: usize, memo: &mut hashbrown::HashMap<u32, u128>) -> u128 {
    if n == EMPTY {
        return 0;
    }
    if n == TERMINAL || mdd.depth(n) >= end {
        return 1;
    }
    if let Some(&c) = memo.get(&n) {
        return c;
    }
    let c = mdd
        .children(n)
        .to_vec()
        .into_iter()
        .map(|c| truncated_count(mdd, c, end, memo))
        .fold(0u128, u128::saturating_add);
    memo.insert(n, c);
    c
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::families;
    use crate::net::Params;

    fn sizes(s: &Structure) -> Vec<usize> {
        s.components().iter().map(Component::len).collect()
    }

    #[test]
    fn kanban_is_cell_one_times_cells_two_and_three_times_cell_four() {
        for (n, cell, middle) in [(3u32, 20usize, 146usize), (5, 56, 812)] {
            let g = families::kanban(n).instantiate(&Params::new()).unwrap();
            let s = Structure::detect(&g, &StructureParams::default()).unwrap();
            assert_eq!(sizes(&s), vec![cell, cell, middle], "N = {n}");
            assert!(s.is_exact());
            assert_eq!(s.reachable(), (cell * middle * cell) as u128);
            // `#Pm2 + #Pback2 + #Pout2 + #Pkan3 = N` is a P-invariant: the
            // invariants already tie cells 2 and 3 into one group.
            let groups: Vec<u128> = s.groups().iter().map(|g| g.projected_states).collect();
            assert_eq!(groups, vec![cell as u128, middle as u128, cell as u128]);
        }
    }

    #[test]
    fn kanban_ten_has_a_billion_markings() {
        let g = families::kanban(10).instantiate(&Params::new()).unwrap();
        let s = Structure::detect(&g, &StructureParams::default()).unwrap();
        assert_eq!(sizes(&s), vec![286, 286, 12_298]);
        assert_eq!(s.reachable(), 1_005_927_208);
        assert_eq!(s.potential(), s.reachable());
        assert_eq!(s.reversible(), Some(true));
    }
}
