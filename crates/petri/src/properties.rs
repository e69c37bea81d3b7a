//! Behavioural properties read off the reachability graph.
//!
//! All of them are properties of the GSPN's reachability graph — tangible
//! and vanishing markings, with immediate transitions pre-empting timed ones
//! and priorities respected — which is what the net does. For a plain P/T
//! net (no immediate transitions) they coincide with the classical untimed
//! properties.
//!
//! * **bounds**: the largest token count of each place over all reachable
//!   markings; the net is *safe* when every bound is ≤ 1.
//! * **dead markings**: markings that enable nothing (deadlocks).
//! * **dead transitions**: never fire from `M0` (not even quasi-live).
//! * **live transitions** (L4): from every reachable marking the transition
//!   can fire again. In a finite graph: it labels an edge inside every
//!   terminal strongly connected component (every run ends in one).
//! * **reversibility**: `M0` is a home state — reachable from every
//!   reachable marking: the graph has one terminal component and it
//!   contains `M0`.
//! * **mutual exclusion**: pairs of places (each marked somewhere) that are
//!   never marked together.
//!
//! Cost: one Tarjan pass over the graph (`O(V + E)`), one pass over the
//! markings for bounds and co-marking (`O(V · m · P/64)` for `m` marked
//! places per marking; skipped above [`MAX_MUTEX_PLACES`] places).

use crate::gspn::Gspn;
use crate::net::{PlaceId, TransitionId};
use crate::reachability::{MarkingId, ReachabilityGraph};
use crate::scc::Components;

/// Above this many places the mutual-exclusion table is not computed.
pub const MAX_MUTEX_PLACES: usize = 4096;

/// The behavioural properties of a net's reachability graph.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Properties {
    /// Largest token count of each place.
    pub bounds: Vec<u32>,
    /// Every bound ≤ 1.
    pub safe: bool,
    /// Markings that enable nothing.
    pub dead_markings: Vec<MarkingId>,
    /// Transitions that never fire.
    pub dead_transitions: Vec<TransitionId>,
    /// Transitions that can always fire again (L4-live).
    pub live_transitions: Vec<TransitionId>,
    /// Whether every transition is live.
    pub live: bool,
    /// Whether `M0` is reachable from every reachable marking.
    pub reversible: bool,
    /// Number of terminal strongly connected components of the graph.
    pub terminal_components: usize,
    /// Pairs of places, each marked in some reachable marking, never marked
    /// together; `None` when the net has more than [`MAX_MUTEX_PLACES`] places.
    pub mutually_exclusive: Option<Vec<(PlaceId, PlaceId)>>,
}

impl Properties {
    /// Computes the properties of `rg`, the reachability graph of `gspn`.
    pub fn of(gspn: &Gspn, rg: &ReachabilityGraph) -> Properties {
        let np = gspn.num_places();
        let nt = gspn.num_transitions();
        let bounds = rg.place_bounds().to_vec();
        let safe = bounds.iter().all(|&b| b <= 1);
        let dead_markings = rg.dead_markings();

        let mut fired = vec![false; nt];
        for &t in &rg.transitions {
            fired[t as usize] = true;
        }
        let dead_transitions = (0..nt as u32)
            .filter(|&t| !fired[t as usize])
            .map(TransitionId)
            .collect();

        let comps = Components::of(rg);
        let terminal: Vec<u32> = comps.bottoms();
        let mut terminal_index = vec![u32::MAX; comps.len()];
        for (i, &c) in terminal.iter().enumerate() {
            terminal_index[c as usize] = i as u32;
        }
        // inside[k][t]: transition t labels an edge inside terminal component k.
        let mut inside = vec![vec![false; nt]; terminal.len()];
        for v in 0..rg.num_markings() {
            let c = comps.comp[v];
            let k = terminal_index[c as usize];
            if k == u32::MAX {
                continue;
            }
            let (a, b) = rg.range(v);
            for e in a..b {
                if comps.comp[rg.targets[e] as usize] == c {
                    inside[k as usize][rg.transitions[e] as usize] = true;
                }
            }
        }
        let live_transitions: Vec<TransitionId> = (0..nt)
            .filter(|&t| inside.iter().all(|row| row[t]))
            .map(|t| TransitionId(t as u32))
            .collect();
        let live = live_transitions.len() == nt;
        let reversible = terminal.len() == 1 && comps.comp[0] == terminal[0];

        let mutually_exclusive = (np <= MAX_MUTEX_PLACES).then(|| {
            let words = np.div_ceil(64);
            let mut co = vec![0u64; np * words];
            let mut marked_bits = vec![0u64; words];
            let mut marked: Vec<usize> = Vec::new();
            let mut m = vec![0u32; np];
            for v in 0..rg.num_markings() {
                rg.marking_into(MarkingId(v as u32), &mut m);
                marked.clear();
                marked_bits.iter_mut().for_each(|w| *w = 0);
                for (p, &k) in m.iter().enumerate() {
                    if k > 0 {
                        marked.push(p);
                        marked_bits[p / 64] |= 1 << (p % 64);
                    }
                }
                for &p in &marked {
                    for (w, &bits) in co[p * words..(p + 1) * words].iter_mut().zip(&marked_bits) {
                        *w |= bits;
                    }
                }
            }
            let mut pairs = Vec::new();
            for p in 0..np {
                if bounds[p] == 0 {
                    continue;
                }
                for q in p + 1..np {
                    if bounds[q] > 0 && co[p * words + q / 64] & (1 << (q % 64)) == 0 {
                        pairs.push((PlaceId(p as u32), PlaceId(q as u32)));
                    }
                }
            }
            pairs
        });

        Properties {
            bounds,
            safe,
            dead_markings,
            dead_transitions,
            live_transitions,
            live,
            reversible,
            terminal_components: terminal.len(),
            mutually_exclusive,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::net::{Net, Params};
    use crate::reachability::ExploreParams;

    fn props(net: &Net) -> Properties {
        let g = net.instantiate(&Params::new()).unwrap();
        let rg = ReachabilityGraph::explore(&g, &ExploreParams::default()).unwrap();
        Properties::of(&g, &rg)
    }

    #[test]
    fn mutual_exclusion_with_a_semaphore() {
        // Two processes idle -> critical -> idle sharing a semaphore.
        let mut n = Net::new("mutex");
        let sem = n.add_place("sem", 1u32);
        let mut crit = Vec::new();
        for i in 0..2 {
            let idle = n.add_place(format!("idle{i}"), 1u32);
            let c = n.add_place(format!("crit{i}"), 0u32);
            let enter = n.add_timed(format!("enter{i}"), 1.0);
            n.input(idle, enter);
            n.input(sem, enter);
            n.output(enter, c);
            let leave = n.add_timed(format!("leave{i}"), 1.0);
            n.input(c, leave);
            n.output(leave, idle);
            n.output(leave, sem);
            crit.push(c);
        }
        let p = props(&n);
        assert!(p.safe && p.live && p.reversible);
        assert!(p.dead_markings.is_empty() && p.dead_transitions.is_empty());
        let pairs = p.mutually_exclusive.unwrap();
        assert!(pairs.contains(&(crit[0], crit[1])), "{pairs:?}");
        assert!(pairs.contains(&(sem, crit[0])));
        assert!(
            !pairs.contains(&(PlaceId(1), PlaceId(4))),
            "idle0 and idle1 can both be marked"
        );
    }

    #[test]
    fn deadlocking_philosophers_are_not_live() {
        let p = props(&crate::families::philosophers(3));
        assert_eq!(p.dead_markings.len(), 2);
        assert!(!p.live && !p.reversible);
        assert!(p.live_transitions.is_empty());
        assert_eq!(p.terminal_components, 2);
        assert!(p.dead_transitions.is_empty());
    }

    #[test]
    fn transition_that_never_fires_is_dead_and_bounds_are_exact() {
        let mut n = Net::new("dead");
        let a = n.add_place("a", 3u32);
        let b = n.add_place("b", 0u32);
        let t = n.add_timed("move", 1.0);
        n.input(a, t);
        n.output(t, b);
        let back = n.add_timed("back", 1.0);
        n.input(b, back);
        n.output(back, a);
        let never = n.add_timed("never", 1.0);
        n.add_arc(crate::net::ArcKind::Input, a, never, 4u32);
        let p = props(&n);
        assert_eq!(p.bounds, vec![3, 3]);
        assert!(!p.safe);
        assert_eq!(p.dead_transitions, vec![never]);
        assert_eq!(p.live_transitions, vec![t, back]);
        assert!(p.reversible && !p.live);
    }
}
