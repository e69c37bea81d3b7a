//! Graph analysis before any number is computed: which states reach a set
//! with probability 0 or 1 under some or every policy, and the maximal end
//! components (MECs), where a policy can keep the process for ever.
//!
//! The algorithms are those of de Alfaro's thesis (*Formal Verification of
//! Probabilistic Systems*, 1997, ch. 3) and of Baier & Katoen
//! (*Principles of Model Checking*, 10.6), on the model's support graph
//! (every entry has a positive probability):
//!
//! | set | meaning | computation |
//! |---|---|---|
//! | [`prob0_max`] | `Pmax(F T) = 0` | not backward-reachable from `T` |
//! | [`prob0_min`] | `Pmin(F T) = 0` | complement of the states whose every row reaches, least fixed point |
//! | [`prob1_max`] | `Pmax(F T) = 1` | de Alfaro's nested fixed point |
//! | [`prob1_min`] | `Pmin(F T) = 1` | not backward-reachable, outside `T`, from `Pmin = 0` |
//! | [`mecs`] | maximal end components | SCCs refined until no row leaves its SCC |
//!
//! Each is `O(E)` (the nested fixed points and the MEC refinement `O(E)`
//! per round, a few rounds in practice), with backward adjacency lists
//! built once ([`Backward`]).

use crate::scc::{Successors, tarjan};

const NONE: u32 = u32::MAX;

/// The structure of an MDP the analyses read: row groups and the rows'
/// targets (values are not needed).
#[derive(Debug, Clone, Copy)]
pub struct Structure<'a> {
    /// Rows of state `s`: `row_start[s]..row_start[s + 1]`.
    pub row_start: &'a [u32],
    /// Entries of row `r`: `entry_start[r]..entry_start[r + 1]`.
    pub entry_start: &'a [u64],
    /// Target of each entry.
    pub col: &'a [u32],
}

impl Structure<'_> {
    /// Number of states.
    pub fn num_states(&self) -> usize {
        self.row_start.len() - 1
    }

    #[inline]
    fn rows(&self, s: usize) -> std::ops::Range<usize> {
        self.row_start[s] as usize..self.row_start[s + 1] as usize
    }

    #[inline]
    fn targets(&self, r: usize) -> &[u32] {
        &self.col[self.entry_start[r] as usize..self.entry_start[r + 1] as usize]
    }
}

/// For every state, the rows (and their states) that can enter it.
#[derive(Debug, Clone)]
pub struct Backward {
    start: Vec<u64>,
    /// `(state, row)` of each incoming entry.
    from: Vec<(u32, u32)>,
}

impl Backward {
    /// Built from the entries of `m`: `O(E)`, 8 bytes per entry.
    pub fn new(m: &Structure<'_>) -> Backward {
        let n = m.num_states();
        let mut start = vec![0u64; n + 1];
        for &t in m.col {
            start[t as usize + 1] += 1;
        }
        for i in 0..n {
            start[i + 1] += start[i];
        }
        let mut fill = start.clone();
        let mut from = vec![(0u32, 0u32); m.col.len()];
        for s in 0..n {
            for r in m.rows(s) {
                for &t in m.targets(r) {
                    let k = &mut fill[t as usize];
                    from[*k as usize] = (s as u32, r as u32);
                    *k += 1;
                }
            }
        }
        Backward { start, from }
    }

    /// The `(state, row)` pairs entering `t`.
    #[inline]
    pub(crate) fn of(&self, t: usize) -> &[(u32, u32)] {
        &self.from[self.start[t] as usize..self.start[t + 1] as usize]
    }
}

/// States from which `target` is reached with probability 0 under every
/// policy (`Pmax = 0`): those that cannot reach it in the graph, through
/// states of `within` (all when `None`).
pub fn prob0_max(m: &Structure<'_>, back: &Backward, target: &[bool], within: Option<&[bool]>) -> Vec<bool> {
    let n = m.num_states();
    let mut reach = target.to_vec();
    let mut stack: Vec<u32> = (0..n as u32).filter(|&s| target[s as usize]).collect();
    while let Some(t) = stack.pop() {
        for &(s, _) in back.of(t as usize) {
            let si = s as usize;
            if !reach[si] && within.is_none_or(|w| w[si]) {
                reach[si] = true;
                stack.push(s);
            }
        }
    }
    reach.iter().map(|&r| !r).collect()
}

/// States from which some policy avoids `target` for ever with
/// probability 1 (`Pmin = 0`): the complement of the least set containing
/// `target` and every state all of whose rows enter the set.
pub fn prob0_min(m: &Structure<'_>, back: &Backward, target: &[bool]) -> Vec<bool> {
    let n = m.num_states();
    let mut reach = target.to_vec();
    let mut row_hit = vec![false; m.entry_start.len() - 1];
    let mut missing: Vec<u32> = (0..n).map(|s| m.rows(s).len() as u32).collect();
    let mut stack: Vec<u32> = (0..n as u32).filter(|&s| target[s as usize]).collect();
    while let Some(t) = stack.pop() {
        for &(s, r) in back.of(t as usize) {
            let (si, ri) = (s as usize, r as usize);
            if reach[si] || row_hit[ri] {
                continue;
            }
            row_hit[ri] = true;
            missing[si] -= 1;
            if missing[si] == 0 {
                reach[si] = true;
                stack.push(s);
            }
        }
    }
    reach.iter().map(|&r| !r).collect()
}

/// States from which every policy reaches `target` with probability 1
/// (`Pmin = 1`): those that cannot reach a `Pmin = 0` state
/// (`prob0_min`, given) through states outside `target`.
pub fn prob1_min(m: &Structure<'_>, back: &Backward, target: &[bool], pmin0: &[bool]) -> Vec<bool> {
    let n = m.num_states();
    let mut bad = pmin0.to_vec();
    let mut stack: Vec<u32> = (0..n as u32).filter(|&s| pmin0[s as usize]).collect();
    while let Some(t) = stack.pop() {
        for &(s, _) in back.of(t as usize) {
            let si = s as usize;
            if !bad[si] && !target[si] {
                bad[si] = true;
                stack.push(s);
            }
        }
    }
    bad.iter().map(|&b| !b).collect()
}

/// States from which some policy reaches `target` with probability 1
/// (`Pmax = 1`): de Alfaro's nested fixed point. `U` starts as every
/// state; each round keeps the states that reach `target` through rows
/// staying in `U`, until `U` is stable.
pub fn prob1_max(m: &Structure<'_>, back: &Backward, target: &[bool]) -> Vec<bool> {
    let n = m.num_states();
    let rows = m.entry_start.len() - 1;
    let mut u = vec![true; n];
    let mut stays = vec![true; rows];
    loop {
        // Rows whose every target is in U.
        for s in 0..n {
            for r in m.rows(s) {
                stays[r] = u[s] && m.targets(r).iter().all(|&t| u[t as usize]);
            }
        }
        // Backward from target through staying rows.
        let mut r_set = target.to_vec();
        for (s, x) in r_set.iter_mut().enumerate() {
            *x = *x && u[s];
        }
        let mut stack: Vec<u32> = (0..n as u32).filter(|&s| r_set[s as usize]).collect();
        while let Some(t) = stack.pop() {
            for &(s, r) in back.of(t as usize) {
                let si = s as usize;
                if !r_set[si] && u[si] && stays[r as usize] {
                    r_set[si] = true;
                    stack.push(s);
                }
            }
        }
        if r_set == u {
            return u;
        }
        u = r_set;
    }
}

/// Maximal end components of the sub-MDP of the states in `states` and,
/// of theirs, the rows `allowed` (all when `None`).
#[derive(Debug, Clone)]
pub struct Mecs {
    /// MEC of each state ([`u32::MAX`]: none).
    pub of_state: Vec<u32>,
    /// Whether each row belongs to its state's MEC (stays in it).
    pub row_inside: Vec<bool>,
    /// Number of MECs.
    pub count: usize,
}

/// The successor lists of a sub-MDP, for Tarjan.
struct SubGraph {
    start: Vec<u64>,
    targets: Vec<u32>,
}

impl Successors for SubGraph {
    fn num_nodes(&self) -> usize {
        self.start.len() - 1
    }

    fn successors(&self, v: u32) -> &[u32] {
        &self.targets[self.start[v as usize] as usize..self.start[v as usize + 1] as usize]
    }
}

/// The maximal end components of the sub-MDP of `states` with the rows
/// `allowed` (see [`Mecs`]): strongly connected components of the rows
/// still allowed, then every row leaving its component is dropped and
/// states without rows removed, until nothing changes (Baier & Katoen,
/// algorithm 47). Components left with a row are the MECs.
pub fn mecs(m: &Structure<'_>, states: &[bool], allowed: Option<&[bool]>) -> Mecs {
    let n = m.num_states();
    let rows = m.entry_start.len() - 1;
    let mut alive = states.to_vec();
    let mut row_ok: Vec<bool> = (0..rows).map(|r| allowed.is_none_or(|a| a[r])).collect();
    for (s, live) in alive.iter_mut().enumerate() {
        for r in m.rows(s) {
            row_ok[r] = row_ok[r] && *live && m.targets(r).iter().all(|&t| states[t as usize]);
        }
        if *live && !m.rows(s).any(|r| row_ok[r]) {
            *live = false;
        }
    }
    let mut comp = vec![NONE; n];
    loop {
        let graph = sub_graph(m, &alive, &row_ok);
        let mut count = 0u32;
        comp.iter_mut().for_each(|c| *c = NONE);
        let _ = tarjan::<_, ()>(
            &graph,
            |v| alive[v as usize],
            |scc| {
                for &v in scc {
                    comp[v as usize] = count;
                }
                count += 1;
                Ok(())
            },
        );
        let mut changed = false;
        for s in 0..n {
            if !alive[s] {
                continue;
            }
            for r in m.rows(s) {
                if row_ok[r] && m.targets(r).iter().any(|&t| comp[t as usize] != comp[s]) {
                    row_ok[r] = false;
                    changed = true;
                }
            }
            if !m.rows(s).any(|r| row_ok[r]) {
                alive[s] = false;
                changed = true;
            }
        }
        if !changed {
            break;
        }
    }
    // Renumber the components that kept states, in state order.
    let mut id = vec![NONE; n];
    let mut of_state = vec![NONE; n];
    let mut next = 0u32;
    for s in 0..n {
        if alive[s] {
            let c = comp[s] as usize;
            if id[c] == NONE {
                id[c] = next;
                next += 1;
            }
            of_state[s] = id[c];
        }
    }
    Mecs {
        of_state,
        row_inside: row_ok,
        count: next as usize,
    }
}

fn sub_graph(m: &Structure<'_>, alive: &[bool], row_ok: &[bool]) -> SubGraph {
    let n = m.num_states();
    let mut start = Vec::with_capacity(n + 1);
    start.push(0u64);
    let mut targets = Vec::new();
    for (s, &live) in alive.iter().enumerate().take(n) {
        if live {
            for r in m.rows(s) {
                if row_ok[r] {
                    targets.extend_from_slice(m.targets(r));
                }
            }
        }
        start.push(targets.len() as u64);
    }
    SubGraph { start, targets }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An MDP from per-state lists of rows, each a list of targets.
    fn mdp(states: &[&[&[u32]]]) -> (Vec<u32>, Vec<u64>, Vec<u32>) {
        let mut row_start = vec![0u32];
        let mut entry_start = vec![0u64];
        let mut col = Vec::new();
        for rows in states {
            for row in *rows {
                col.extend_from_slice(row);
                entry_start.push(col.len() as u64);
            }
            row_start.push(entry_start.len() as u32 - 1);
        }
        (row_start, entry_start, col)
    }

    #[test]
    fn probability_zero_and_one_sets() {
        // 0: a → 1 (target), b → 2 (trap), c → {0, 3}; 3: → 0 or → 2; 2: self.
        let (rs, es, col) = mdp(&[&[&[1], &[2], &[0, 3]], &[&[1]], &[&[2]], &[&[0], &[2]]]);
        let m = Structure {
            row_start: &rs,
            entry_start: &es,
            col: &col,
        };
        let back = Backward::new(&m);
        let target = [false, true, false, false];
        assert_eq!(
            prob0_max(&m, &back, &target, None),
            vec![false, false, true, false]
        );
        let p0min = prob0_min(&m, &back, &target);
        assert_eq!(p0min, vec![true, false, true, true]);
        assert_eq!(
            prob1_min(&m, &back, &target, &p0min),
            vec![false, true, false, false]
        );
        assert_eq!(prob1_max(&m, &back, &target), vec![true, true, false, true]);
    }

    #[test]
    fn end_components() {
        // {0, 1} loop with an exit from 1 to 2; 2 → 3 → 2 with 3 also → 4 (absorbing).
        let (rs, es, col) = mdp(&[&[&[1]], &[&[0], &[2]], &[&[3]], &[&[2], &[4]], &[&[4]]]);
        let m = Structure {
            row_start: &rs,
            entry_start: &es,
            col: &col,
        };
        let all = vec![true; 5];
        let e = mecs(&m, &all, None);
        assert_eq!(e.count, 3);
        assert_eq!(e.of_state[0], e.of_state[1]);
        assert_eq!(e.of_state[2], e.of_state[3]);
        assert_ne!(e.of_state[0], e.of_state[2]);
        assert!(!e.row_inside[2], "1's row to 2 leaves {{0, 1}}");
        // Without state 4, 3's exit row leaves the allowed states.
        let some = vec![true, true, true, true, false];
        let e = mecs(&m, &some, None);
        assert_eq!(e.count, 2);
        assert_eq!(e.of_state[4], NONE);
    }
}
