//! Shared by the cross-checking tests: random GSPNs described by plain
//! numbers (so that proptest can shrink them), and comparison helpers.
//!
//! [`spec`] gives structured nets built to be ergodic (below); [`arbitrary`]
//! gives arbitrary small nets — most not ergodic, some unbounded or with
//! timeless traps — for the properties that must hold anyway.
//!
//! # The structured random nets
//!
//! A few cyclic token-conserving processes share resources:
//!
//! - process `j` has places `P{j}_0 … P{j}_{L−1}` (`L` = 2…4) and `tokens`
//!   tokens, all in `P{j}_0` at the start; step `i` moves a token from
//!   `P{j}_i` to `P{j}_{i+1 mod L}` by transition `T{j}_{i}` and, optionally,
//!   a parallel alternative `A{j}_{i}` of the same kind (a race between two
//!   timed transitions, or a weighted/prioritised choice between two
//!   immediate ones);
//! - a step is timed (rate 0.1…10, single, 2-server or infinite-server) or
//!   immediate (weight 0.1…10, priority 1…3); every process has at least one
//!   timed step;
//! - optionally a process holds a resource `R{k}` (1 or 2 tokens, possibly
//!   shared with other processes) from step `a` (acquire) to step `r > a`
//!   (release): it never holds two resources, so no deadlock;
//! - optionally an immediate *bounce* `B{j}_{i}` sends a token from `P{j}_i`
//!   back to `P{j}_{i−1}`, with the priority of the immediate step `i`, which
//!   it competes with. When step `i − 1` is immediate too this is a
//!   **vanishing loop** (`P_{i−1} → P_i → P_{i−1} → …`), left with
//!   probability > 0 each round because step `i` never needs a resource;
//! - optionally the first step of a process is inhibited while a place
//!   `P{k}_q`, `q ≥ 1`, of another process holds `m` tokens. Step 0 holds
//!   nothing and a token in `P{k}_q` always moves on, so this cannot
//!   deadlock (with `q = 0` two processes could block each other's start).
//!
//! Every place is covered by a P-invariant (a process cycle; a resource plus
//! the places that hold it), so the nets are bounded. From any marking every
//! token can be driven back to its initial place without firing a first
//! step, so the untimed net is reversible and has no dead marking. Under
//! GSPN semantics priorities may still make part of the tangible chain
//! transient (about 2% of the nets), and rarely (about 1 in 3,000) split it
//! into several bottom components: priority races decided once and for all.
//! The simulation cross-check skips those.

#![allow(dead_code)]

use petri::{ArcKind, Net, Servers};
use proptest::prelude::*;

/// Timing of a step's transition.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Kind {
    /// Rate and server semantics (0: single, 1: two servers, 2: infinite).
    Timed(f64, u8),
    /// Weight and priority.
    Immediate(f64, u32),
}

/// One step of a process: the main transition and maybe an alternative.
#[derive(Debug, Clone)]
pub struct Step {
    pub main: Kind,
    pub alt: Option<Kind>,
}

/// A cyclic process.
#[derive(Debug, Clone)]
pub struct Process {
    pub tokens: u32,
    pub steps: Vec<Step>,
    /// (resource index, acquire step, release step).
    pub hold: Option<(usize, usize, usize)>,
    /// (place index i ≥ 1, weight): immediate transition `P_i → P_{i−1}`.
    pub bounce: Option<(usize, f64)>,
    /// (other process, its place index, multiplicity) inhibiting step 0.
    pub inhibitor: Option<(usize, usize, u32)>,
}

/// A random net.
#[derive(Debug, Clone)]
pub struct Spec {
    pub resources: Vec<u32>,
    pub processes: Vec<Process>,
}

fn log_uniform() -> impl Strategy<Value = f64> {
    (-1.0f64..=1.0).prop_map(|e| 10f64.powf(e))
}

fn timed() -> impl Strategy<Value = Kind> {
    (
        log_uniform(),
        prop_oneof![3 => Just(0u8), 1 => Just(1u8), 1 => Just(2u8)],
    )
        .prop_map(|(r, s)| Kind::Timed(r, s))
}

fn immediate() -> impl Strategy<Value = Kind> {
    (log_uniform(), 1u32..=3).prop_map(|(w, p)| Kind::Immediate(w, p))
}

fn step() -> impl Strategy<Value = Step> {
    prop_oneof![
        (timed(), proptest::option::weighted(0.3, timed())).prop_map(|(main, alt)| Step { main, alt }),
        (immediate(), proptest::option::weighted(0.3, immediate()))
            .prop_map(|(main, alt)| Step { main, alt }),
    ]
}

/// Random processes: `max_processes` of at most 4 steps and `max_tokens`
/// tokens each, sharing up to 2 resources.
pub fn spec(max_processes: usize, max_tokens: u32) -> impl Strategy<Value = Spec> {
    let process = (
        1..=max_tokens,
        proptest::collection::vec(step(), 2..=4),
        any::<(bool, usize, usize, usize)>(),
        any::<(bool, usize)>(),
        log_uniform(),
        any::<(bool, usize, usize)>(),
        1u32..=2,
    );
    (
        proptest::collection::vec(1u32..=2, 1..=2),
        proptest::collection::vec(process, 1..=max_processes),
    )
        .prop_map(|(resources, raw)| {
            let n = raw.len();
            let lens: Vec<usize> = raw.iter().map(|r| r.1.len()).collect();
            let processes = raw
                .into_iter()
                .enumerate()
                .map(|(j, (tokens, mut steps, hold, bounce, bw, inh, m))| {
                    let l = steps.len();
                    if !steps.iter().any(|s| matches!(s.main, Kind::Timed(..))) {
                        // Without a timed step the tokens would cycle in zero time.
                        let k = hold.1 % l;
                        steps[k] = Step {
                            main: Kind::Timed(1.0, 0),
                            alt: None,
                        };
                    }
                    let hold = hold.0.then(|| {
                        let a = hold.2 % (l - 1);
                        let r = a + 1 + hold.3 % (l - 1 - a);
                        (hold.1 % resources.len(), a, r)
                    });
                    let held = |i: usize| hold.is_some_and(|(_, a, r)| i > a && i <= r);
                    let immediate = |i: usize| matches!(steps[i].main, Kind::Immediate(..));
                    let allowed: Vec<usize> = (1..l)
                        .filter(|&i| {
                            immediate(i) && hold.is_none_or(|(_, a, _)| a != i) && held(i) == held(i - 1)
                        })
                        .collect();
                    // Prefer the bounces that make vanishing loops.
                    let loops: Vec<usize> = allowed.iter().copied().filter(|&i| immediate(i - 1)).collect();
                    let choices = if loops.is_empty() { allowed } else { loops };
                    let bounce = (bounce.0 && !choices.is_empty()).then(|| choices[bounce.1 % choices.len()]);
                    let inhibitor = (inh.0 && n > 1).then(|| {
                        let other = (j + 1 + inh.1 % (n - 1)) % n;
                        (other, 1 + inh.2 % (lens[other] - 1), m)
                    });
                    Process {
                        tokens,
                        steps,
                        hold,
                        bounce: bounce.map(|i| (i, bw)),
                        inhibitor,
                    }
                })
                .collect();
            Spec { resources, processes }
        })
}

impl Spec {
    /// The net.
    pub fn net(&self) -> Net {
        let mut net = Net::new("random");
        let res: Vec<_> = self
            .resources
            .iter()
            .enumerate()
            .map(|(k, &c)| net.add_place(format!("R{k}"), c))
            .collect();
        let places: Vec<Vec<_>> = self
            .processes
            .iter()
            .enumerate()
            .map(|(j, p)| {
                (0..p.steps.len())
                    .map(|i| net.add_place(format!("P{j}_{i}"), if i == 0 { p.tokens } else { 0 }))
                    .collect()
            })
            .collect();
        for (j, p) in self.processes.iter().enumerate() {
            let l = p.steps.len();
            for (i, s) in p.steps.iter().enumerate() {
                let alts = std::iter::once(("T", s.main)).chain(s.alt.map(|k| ("A", k)));
                for (prefix, kind) in alts {
                    let name = format!("{prefix}{j}_{i}");
                    let t = match kind {
                        Kind::Timed(rate, servers) => {
                            let t = net.add_timed(name, rate);
                            net.set_servers(
                                t,
                                match servers {
                                    0 => Servers::Single,
                                    1 => Servers::K(2),
                                    _ => Servers::Infinite,
                                },
                            );
                            t
                        }
                        Kind::Immediate(w, prio) => net.add_immediate(name, w, prio),
                    };
                    net.input(places[j][i], t);
                    net.output(t, places[j][(i + 1) % l]);
                    if let Some((k, a, r)) = p.hold {
                        if i == a {
                            net.input(res[k], t);
                        }
                        if i == r {
                            net.output(t, res[k]);
                        }
                    }
                    if let (0, Some((other, q, m))) = (i, p.inhibitor) {
                        net.add_arc(ArcKind::Inhibitor, places[other][q], t, m);
                    }
                }
            }
            if let Some((i, w)) = p.bounce {
                let Kind::Immediate(_, prio) = p.steps[i].main else {
                    unreachable!("bounces leave immediate steps only")
                };
                let t = net.add_immediate(format!("B{j}_{i}"), w, prio);
                net.input(places[j][i], t);
                net.output(t, places[j][i - 1]);
            }
        }
        net
    }

    /// Whether some vanishing loop is possible (a bounce after an immediate step).
    pub fn has_vanishing_loop(&self) -> bool {
        self.processes.iter().any(|p| {
            p.bounce
                .is_some_and(|(i, _)| matches!(p.steps[i - 1].main, Kind::Immediate(..)))
        })
    }
}

/// An arbitrary small net: per transition (immediate?, priority, weight or
/// rate, servers, a place it takes a token from, a place it puts one in),
/// per (transition, place) extra input, output and inhibitor multiplicities
/// (0: no arc), and an initial marking. Most transitions move one token, so
/// many nets are bounded; many are not ergodic, some are unbounded or have
/// timeless traps.
#[derive(Debug, Clone)]
pub struct Arbitrary {
    pub places: usize,
    pub transitions: Vec<(bool, u32, f64, u8, usize, usize)>,
    pub arcs: Vec<(u32, u32, u32)>,
    pub initial: Vec<u32>,
}

pub fn arbitrary() -> impl Strategy<Value = Arbitrary> {
    (1usize..=5, 1usize..=7).prop_flat_map(|(np, nt)| {
        let extra = || prop_oneof![8 => Just(0u32), 1 => 1u32..=2];
        (
            proptest::collection::vec(
                (
                    proptest::bool::weighted(0.3),
                    1u32..=2,
                    0.1f64..10.0,
                    0u8..3,
                    0..np,
                    0..np,
                ),
                nt,
            ),
            proptest::collection::vec((extra(), extra(), extra()), np * nt),
            proptest::collection::vec(0u32..=3, np),
        )
            .prop_map(move |(transitions, arcs, initial)| Arbitrary {
                places: np,
                transitions,
                arcs,
                initial,
            })
    })
}

impl Arbitrary {
    /// The net.
    pub fn net(&self) -> Net {
        let mut net = Net::new("arbitrary");
        let places: Vec<_> = (0..self.places)
            .map(|p| net.add_place(format!("p{p}"), self.initial[p]))
            .collect();
        for (t, &(immediate, priority, value, servers, from, to)) in self.transitions.iter().enumerate() {
            let id = if immediate {
                net.add_immediate(format!("t{t}"), value, priority)
            } else {
                let id = net.add_timed(format!("t{t}"), value);
                let s = [Servers::Single, Servers::K(2), Servers::Infinite][servers as usize];
                net.set_servers(id, s);
                id
            };
            net.input(places[from], id);
            net.output(id, places[to]);
            for (p, &place) in places.iter().enumerate() {
                let (i, o, h) = self.arcs[t * self.places + p];
                for (kind, m) in [(ArcKind::Input, i), (ArcKind::Output, o), (ArcKind::Inhibitor, h)] {
                    if m > 0 {
                        net.add_arc(kind, place, id, m);
                    }
                }
            }
        }
        net
    }
}

/// `|a − b| ≤ rel · max(|a|, |b|) + abs`.
pub fn close(a: f64, b: f64, rel: f64, abs: f64) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs()) + abs
}
