//! Explicit searches over a product state space under GSPN semantics, for
//! nets with immediate transitions (whose priorities the symbolic search
//! cannot apply): which states of the product are reachable from `M0`,
//! what class each is (tangible, or vanishing with the priority and weight
//! sum of the immediate transitions that fire there), and whether `M0` can
//! be reached back from every one (the chain is then irreducible).
//!
//! Breadth-first, one bit per product state for the visited set and two for
//! the frontiers; successors and predecessors come from the descriptor's
//! local maps. `O(states · transitions)` time.

use hashbrown::HashMap;

use crate::descriptor::{Descriptor, NONE};
use crate::error::{Error, Result};
use crate::interrupt::Interrupt;
use crate::sweep::{Class, Kinds, TANGIBLE, UNREACHABLE};

/// What a stopped search was doing.
const SEARCHING: &str = "searching the product state space";

/// A set of product states, one bit each.
#[derive(Debug, Clone)]
pub(crate) struct Bits(Vec<u64>);

impl Bits {
    pub(crate) fn new(n: u64) -> Bits {
        Bits(vec![0; n.div_ceil(64) as usize])
    }

    /// Sets bit `i`; whether it was clear.
    #[inline]
    pub(crate) fn set(&mut self, i: u64) -> bool {
        let w = &mut self.0[(i / 64) as usize];
        let m = 1u64 << (i % 64);
        let was = *w & m == 0;
        *w |= m;
        was
    }

    fn ones(&self) -> impl Iterator<Item = u64> + '_ {
        self.0.iter().enumerate().flat_map(|(w, &word)| {
            let mut bits = word;
            std::iter::from_fn(move || {
                if bits == 0 {
                    return None;
                }
                let b = bits.trailing_zeros() as u64;
                bits &= bits - 1;
                Some(w as u64 * 64 + b)
            })
        })
    }

    fn is_empty(&self) -> bool {
        self.0.iter().all(|&w| w == 0)
    }

    pub(crate) fn count(&self) -> u64 {
        self.0.iter().map(|w| u64::from(w.count_ones())).sum()
    }
}

/// The class of local states `l` (tangible, or vanishing with the highest
/// enabled priority and its weight sum).
fn class_of(desc: &Descriptor, l: &[u32]) -> Class {
    let mut best = 0u32;
    let mut sum = 0.0;
    for e in &desc.events {
        if let Some((prio, w)) = e.immediate {
            if prio >= best && e.enabled_at(l) {
                if prio > best {
                    best = prio;
                    sum = 0.0;
                }
                sum += w;
            }
        }
    }
    Class {
        priority: best,
        weight_sum: sum,
    }
}

/// Whether event `e` fires in a state of class `c`.
#[inline]
fn fires(e: &crate::descriptor::Event, c: Class) -> bool {
    match e.immediate {
        None => c.priority == 0,
        Some((prio, _)) => prio == c.priority,
    }
}

/// The reachable states of the product under GSPN semantics, classified;
/// and the number of tangible and vanishing ones.
pub(crate) fn classify(desc: &Descriptor, m0: u64, stop: Interrupt<'_>) -> Result<(Kinds, u64, u64)> {
    let n = desc.states;
    let mut visited = Bits::new(n);
    let mut frontier = Bits::new(n);
    visited.set(m0);
    frontier.set(m0);
    let mut class = vec![UNREACHABLE; n as usize];
    let mut classes = vec![
        Class {
            priority: u32::MAX,
            weight_sum: 0.0,
        },
        Class {
            priority: 0,
            weight_sum: 0.0,
        },
    ];
    let mut ids: HashMap<(u32, u64), u16> = HashMap::new();
    let mut l = vec![0u32; desc.levels()];
    let (mut tangible, mut vanishing) = (0u64, 0u64);
    while !frontier.is_empty() {
        stop.check(SEARCHING)?;
        let mut next = Bits::new(n);
        for i in frontier.ones() {
            desc.locals(i, &mut l);
            let c = class_of(desc, &l);
            let id = if c.priority == 0 {
                tangible += 1;
                TANGIBLE
            } else {
                vanishing += 1;
                match ids.get(&(c.priority, c.weight_sum.to_bits())) {
                    Some(&id) => id,
                    None => {
                        let id = u16::try_from(classes.len()).map_err(|_| {
                            Error::Invalid("more than 65,535 classes of vanishing markings".into())
                        })?;
                        classes.push(c);
                        ids.insert((c.priority, c.weight_sum.to_bits()), id);
                        id
                    }
                }
            };
            class[i as usize] = id;
            for e in &desc.events {
                if e.self_loop || !fires(e, c) || !e.enabled_at(&l) {
                    continue;
                }
                let mut j = i;
                for m in &e.maps {
                    let s = m.succ[l[m.level] as usize];
                    j = j + u64::from(s) * desc.strides[m.level]
                        - u64::from(l[m.level]) * desc.strides[m.level];
                }
                if visited.set(j) {
                    next.set(j);
                }
            }
        }
        frontier = next;
    }
    Ok((Kinds { class, classes }, tangible, vanishing))
}

/// Whether every reachable state (class other than unreachable) can reach
/// `m0` under GSPN semantics.
pub(crate) fn reaches_back(desc: &Descriptor, kinds: &Kinds, m0: u64, stop: Interrupt<'_>) -> Result<bool> {
    let n = desc.states;
    let mut visited = Bits::new(n);
    let mut frontier = Bits::new(n);
    visited.set(m0);
    frontier.set(m0);
    let mut l = vec![0u32; desc.levels()];
    let mut p = vec![0u32; desc.levels()];
    while !frontier.is_empty() {
        stop.check(SEARCHING)?;
        let mut next = Bits::new(n);
        for j in frontier.ones() {
            desc.locals(j, &mut l);
            for e in desc.events.iter().filter(|e| !e.self_loop) {
                p.copy_from_slice(&l);
                if !e.maps.iter().all(|m| {
                    let q = m.pred[l[m.level] as usize];
                    p[m.level] = q;
                    q != NONE
                }) {
                    continue;
                }
                let i = desc.index(&p);
                let c = kinds.class[i as usize];
                if c == UNREACHABLE || !fires(e, kinds.classes[c as usize]) {
                    continue;
                }
                if visited.set(i) {
                    next.set(i);
                }
            }
        }
        frontier = next;
    }
    let reachable = kinds.class.iter().filter(|&&c| c != UNREACHABLE).count() as u64;
    Ok(visited.count() == reachable)
}
