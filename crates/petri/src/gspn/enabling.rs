//! The firing rule kept up to date along a run of firings.
//!
//! [`Gspn::firable`] evaluates a marking from scratch. State-space
//! generation evaluates many markings that differ from one already
//! evaluated by a single firing (a successor followed through forced
//! vanishing markings, see
//! [`ExploreParams::skip_forced`](crate::ExploreParams::skip_forced)).
//! Whether `s` is enabled depends only on the counts of its input and
//! inhibitor places and of the bounded places it adds tokens to; after `t`
//! fires, only the transitions with such a place among those `t` changes
//! can change state. [`EnablingIndex`] lists them per transition, and
//! [`EnabledSet`] holds the enabled transitions of one marking as a bitset
//! (one bit per transition) that [`EnabledSet::refresh`] brings to the
//! marking after a firing by re-testing that list alone.
//!
//! [`EnabledSet::firable`] applies the priority rule to the set and returns
//! exactly what [`Gspn::firable`] returns for the same marking, in the same
//! (transition) order: set bits are read in index order, so no candidate
//! list is sorted. Cost: filling a set costs the candidates of the marked
//! places (as [`Gspn::firable`]); a refresh costs the transitions listed
//! for the firing; reading the firable ones costs a word per 64
//! transitions plus one step per enabled transition.

use super::{Gspn, MarkingKind, Timing};
use crate::net::TransitionId;

/// What [`EnabledSet`] needs besides the net: per transition, the
/// transitions to re-test after it fires, and which transitions are
/// immediate.
#[derive(Debug, Clone)]
pub(crate) struct EnablingIndex {
    /// `start[t]..start[t + 1]` in `retest`: the transitions whose
    /// enabling may change when `t` fires, in index order. Empty when not
    /// asked for, or when the lists would be longer than [`RETEST_LIMIT`]
    /// (a refresh then fills the set anew).
    start: Vec<u32>,
    retest: Vec<u32>,
    /// One bit per immediate transition.
    immediate: Vec<u64>,
}

/// The most entries the re-test lists of an [`EnablingIndex`] may hold
/// (64 MiB): a place read by every transition and changed by every
/// transition would make them quadratic in the transitions.
pub(crate) const RETEST_LIMIT: usize = 1 << 24;

/// Words of a bitset of `n` bits.
fn words_for(n: usize) -> usize {
    n.div_ceil(64)
}

impl EnablingIndex {
    /// The index of `gspn`, with the re-test lists if `incremental` (linear
    /// in its arcs and in those lists).
    pub(crate) fn new(gspn: &Gspn, incremental: bool) -> EnablingIndex {
        let nt = gspn.num_transitions();
        let mut immediate = vec![0u64; words_for(nt)];
        for (t, timing) in gspn.timing.iter().enumerate() {
            if matches!(timing, Timing::Immediate { .. }) {
                immediate[t / 64] |= 1 << (t % 64);
            }
        }
        let (start, retest) = if incremental {
            retest_lists(gspn).unwrap_or_default()
        } else {
            Default::default()
        };
        EnablingIndex {
            start,
            retest,
            immediate,
        }
    }

    /// The transitions to re-test after `t` fires, if listed.
    #[inline]
    fn retest(&self, t: TransitionId) -> Option<&[u32]> {
        let at = self.start.get(t.index()..t.index() + 2)?;
        Some(&self.retest[at[0] as usize..at[1] as usize])
    }
}

/// The re-test lists of [`EnablingIndex`] (`start`, `retest`), or `None`
/// beyond [`RETEST_LIMIT`] entries.
fn retest_lists(gspn: &Gspn) -> Option<(Vec<u32>, Vec<u32>)> {
    let nt = gspn.num_transitions();
    let np = gspn.num_places();
    // The transitions whose enabling reads each place.
    let mut readers: Vec<Vec<u32>> = vec![Vec::new(); np];
    for s in 0..nt {
        let sid = TransitionId(s as u32);
        let bounded_outputs = gspn
            .delta(sid)
            .iter()
            .filter(|&&(p, d)| d > 0 && gspn.capacity[p as usize].is_some());
        for &(p, _) in gspn.inputs(sid).iter().chain(gspn.inhibitors(sid)) {
            readers[p as usize].push(s as u32);
        }
        for &(p, _) in bounded_outputs {
            readers[p as usize].push(s as u32);
        }
    }
    let mut start = Vec::with_capacity(nt + 1);
    let mut retest = Vec::new();
    let mut seen = vec![false; nt];
    start.push(0);
    for t in 0..nt {
        let from = retest.len();
        for &(p, _) in gspn.delta(TransitionId(t as u32)) {
            for &s in &readers[p as usize] {
                if !std::mem::replace(&mut seen[s as usize], true) {
                    retest.push(s);
                }
            }
        }
        retest[from..].sort_unstable();
        for &s in &retest[from..] {
            seen[s as usize] = false;
        }
        if retest.len() > RETEST_LIMIT {
            return None;
        }
        start.push(retest.len() as u32);
    }
    Some((start, retest))
}

/// The enabled transitions of one marking (see the module docs).
#[derive(Debug, Clone, Default)]
pub(crate) struct EnabledSet {
    bits: Vec<u64>,
}

impl EnabledSet {
    #[inline]
    fn set(&mut self, t: usize, on: bool) {
        let bit = 1u64 << (t % 64);
        if on {
            self.bits[t / 64] |= bit;
        } else {
            self.bits[t / 64] &= !bit;
        }
    }

    /// Makes this the set of `m`: the candidates of its marked places
    /// (see [`Gspn::firable`]) that pass [`Gspn::is_enabled`].
    pub(crate) fn fill(&mut self, gspn: &Gspn, m: &[u32]) {
        self.bits.clear();
        self.bits.resize(words_for(gspn.num_transitions()), 0);
        let c = &gspn.candidates;
        for &t in &c.sourceless {
            self.set(t.index(), true);
        }
        for (p, &k) in m.iter().enumerate() {
            if k > 0 {
                for &t in &c.keyed[c.start[p] as usize..c.start[p + 1] as usize] {
                    self.set(t.index(), true);
                }
            }
        }
        for w in 0..self.bits.len() {
            let mut b = self.bits[w];
            while b != 0 {
                let t = w * 64 + b.trailing_zeros() as usize;
                b &= b - 1;
                if !gspn.is_enabled(TransitionId(t as u32), m) {
                    self.set(t, false);
                }
            }
        }
    }

    /// Brings the set of a marking to `m`, that marking after firing `t`
    /// (by re-testing what `t` may have changed, or anew when the index has
    /// no re-test lists).
    #[inline]
    pub(crate) fn refresh(&mut self, gspn: &Gspn, index: &EnablingIndex, t: TransitionId, m: &[u32]) {
        match index.retest(t) {
            Some(retest) => {
                for &s in retest {
                    self.set(s as usize, gspn.is_enabled(TransitionId(s), m));
                }
            }
            None => self.fill(gspn, m),
        }
    }

    /// What [`Gspn::firable`] returns for the marking of this set: the
    /// enabled immediate transitions of the highest priority if there are
    /// any, else the enabled timed ones, in transition order.
    pub(crate) fn firable(
        &self,
        gspn: &Gspn,
        index: &EnablingIndex,
        out: &mut Vec<TransitionId>,
    ) -> MarkingKind {
        out.clear();
        let mut best = 0u32;
        for (w, (&b, &imm)) in self.bits.iter().zip(&index.immediate).enumerate() {
            let mut b = b & imm;
            while b != 0 {
                let t = w * 64 + b.trailing_zeros() as usize;
                b &= b - 1;
                if let Timing::Immediate { priority, .. } = gspn.timing[t] {
                    if priority > best {
                        out.clear();
                        best = priority;
                    }
                    if priority == best {
                        out.push(TransitionId(t as u32));
                    }
                }
            }
        }
        if best > 0 {
            return MarkingKind::Vanishing;
        }
        for (w, (&b, &imm)) in self.bits.iter().zip(&index.immediate).enumerate() {
            let mut b = b & !imm;
            while b != 0 {
                out.push(TransitionId((w * 64) as u32 + b.trailing_zeros()));
                b &= b - 1;
            }
        }
        MarkingKind::Tangible
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::net::{ArcKind, Net, Params, PlaceId};
    use proptest::prelude::*;

    /// An arc drawn at random: kind (input, output, inhibitor), place,
    /// multiplicity.
    type RandomArc = (u8, usize, u32);

    /// A net of `np` places (capacity 2 on every third) and the given
    /// transitions: `(0 for timed or the priority, arcs)`.
    fn net(np: usize, transitions: &[(u32, Vec<RandomArc>)]) -> Net {
        let mut net = Net::new("random");
        for p in 0..np {
            let id = net.add_place(format!("P{p}"), 0u32);
            if p % 3 == 2 {
                net.places[id.index()].capacity = Some(2);
            }
        }
        for (i, (prio, arcs)) in transitions.iter().enumerate() {
            let t = if *prio == 0 {
                net.add_timed(format!("T{i}"), 1.0)
            } else {
                net.add_immediate(format!("T{i}"), 1.0, *prio)
            };
            for &(k, p, mult) in arcs {
                let kind = [ArcKind::Input, ArcKind::Output, ArcKind::Inhibitor][usize::from(k) % 3];
                net.add_arc(kind, PlaceId(p as u32), t, mult);
            }
        }
        net
    }

    proptest! {
        /// Along a random run of firings, the refreshed set gives what the
        /// firing rule gives from scratch, in the same order.
        #[test]
        fn refreshed_set_matches_the_firing_rule(
            transitions in prop::collection::vec(
                (0u32..3, prop::collection::vec((0u8..3, 0usize..8, 1u32..3), 0..4)),
                1..80,
            ),
            m0 in prop::collection::vec(0u32..3, 8),
            choices in prop::collection::vec(any::<prop::sample::Index>(), 1..40),
            incremental in any::<bool>(),
        ) {
            let net = net(8, &transitions);
            let Ok(gspn) = net.instantiate(&Params::new()) else { return Ok(()) };
            let index = EnablingIndex::new(&gspn, incremental);
            let mut m = m0;
            for (p, c) in m.iter_mut().enumerate() {
                if p % 3 == 2 {
                    *c = (*c).min(2);
                }
            }
            let mut set = EnabledSet::default();
            set.fill(&gspn, &m);
            let (mut expected, mut got) = (Vec::new(), Vec::new());
            for choice in choices {
                let kind = gspn.firable(&m, &mut expected);
                prop_assert_eq!(set.firable(&gspn, &index, &mut got), kind);
                prop_assert_eq!(&got, &expected);
                if expected.is_empty() {
                    break;
                }
                let t = expected[choice.index(expected.len())];
                gspn.fire(t, &mut m).unwrap();
                set.refresh(&gspn, &index, t, &m);
            }
        }
    }
}
