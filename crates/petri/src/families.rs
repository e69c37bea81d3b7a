//! Scalable GSPN families for tests, benchmarks and examples.
//!
//! | family | source | size |
//! |---|---|---|
//! | [`kanban`] | Ciardo & Tilgner's Kanban system, rates of the PRISM benchmark | N = 1…5: 160; 4,600; 58,400; 454,475; 2,546,432 tangible markings |
//! | [`fms`] | Ciardo & Trivedi's flexible manufacturing system (structure of the MCC `FMS-PT` nets) | grows ~ N⁶ |
//! | [`philosophers`] | dining philosophers as in the MCC `Philosophers-PT` nets (either fork first; can deadlock) | 3^N markings |
//! | [`robots_corridors`] | N robots sharing K one-way corridors (immediate choice of a free corridor) | C(N+K, K)-ish |
//! | [`corridors_decide`] | N robots choosing among 3 corridors, fast and risky to slow and safe (decisions) | N = 40: 18,701 states, N = 100: 216,751, N = 175: 1,046,501 |
//! | [`mm1k`] | M/M/1/K queue | K + 1 |
//! | [`polling`] | a server cycling over N stations of 3 customers each, exhaustive service | 4N · 4^N |
//! | [`tandem`] | 5 stations in series with buffers of N places and 2 servers each, blocking | (N + 1)^5 |

use crate::error::{Error, Result};
use crate::expr::{BinOp, Expr};
use crate::net::{ArcKind, Net, ParamKind, PlaceId, Servers, TransitionId};

/// Most places plus transitions [`Family::build`] makes: a million nodes
/// is a net file of about a hundred megabytes, and far beyond any state
/// space that can be generated (philosophers: `3^N` markings).
pub const MAX_NODES: u64 = 1_000_000;

/// The scalable families, for a size chosen by a user: [`Family::build`]
/// checks the size before anything is allocated.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Family {
    /// [`kanban`]: `n` kanbans per cell (16 places, 16 transitions).
    Kanban,
    /// [`fms`] with immediate choices: `n` pallets (fixed structure).
    Fms,
    /// [`philosophers`]: `5n` places, `5n` transitions.
    Philosophers,
    /// [`robots_corridors`] with 3 corridors: `n` robots (fixed structure).
    Robots,
    /// [`corridors_decide`]: `n` robots choosing corridors (decisions;
    /// fixed structure).
    Corridors,
    /// [`polling`]: `n` stations (`4n` places, `4n` transitions).
    Polling,
    /// [`tandem`]: buffers of `n` places (fixed structure).
    Tandem,
}

impl Family {
    /// The family's name as the command line spells it.
    pub fn name(self) -> &'static str {
        match self {
            Family::Kanban => "kanban",
            Family::Fms => "fms",
            Family::Philosophers => "philosophers",
            Family::Robots => "robots",
            Family::Corridors => "corridors",
            Family::Polling => "polling",
            Family::Tandem => "tandem",
        }
    }

    /// Places plus transitions of the member of size `n`.
    pub fn nodes(self, n: u32) -> u64 {
        match self {
            Family::Philosophers => 10 * u64::from(n),
            Family::Polling => 8 * u64::from(n),
            // The others' structure does not grow with n (only tokens).
            _ => {
                let net = self.make(1);
                (net.places.len() + net.transitions.len()) as u64
            }
        }
    }

    fn make(self, n: u32) -> Net {
        match self {
            Family::Kanban => kanban(n),
            Family::Fms => fms(n, false),
            Family::Philosophers => philosophers(n),
            Family::Robots => robots_corridors(n, 3),
            Family::Corridors => corridors_decide(n),
            Family::Polling => polling(n, POLLING_CUSTOMERS),
            Family::Tandem => tandem(n, TANDEM_STATIONS),
        }
    }

    /// The member of size `n` (≥ 1): [`Error::SizeLimit`] beyond
    /// [`MAX_NODES`] places and transitions, [`Error::Invalid`] for 0.
    pub fn build(self, n: u32) -> Result<Net> {
        if n == 0 {
            return Err(Error::Invalid(format!(
                "the size parameter of {} must be at least 1",
                self.name()
            )));
        }
        let nodes = self.nodes(n);
        if nodes > MAX_NODES {
            return Err(Error::SizeLimit {
                what: format!("the net of {} {n}", self.name()),
                unit: "places and transitions",
                size: nodes,
                limit: MAX_NODES,
            });
        }
        Ok(self.make(n))
    }
}

fn rate(net: &mut Net, name: &str, value: f64) -> Expr {
    net.set_param(name, Some(value), ParamKind::Real);
    Expr::param(name)
}

fn arcs(net: &mut Net, t: TransitionId, inputs: &[PlaceId], outputs: &[PlaceId]) {
    for &p in inputs {
        net.input(p, t);
    }
    for &p in outputs {
        net.output(t, p);
    }
}

/// The Kanban manufacturing system (Ciardo & Tilgner 1996) with `n` kanbans
/// per cell: 16 places, 16 single-server timed transitions, rates of the
/// PRISM benchmark model (`in1` = 1, `redo` 0.36/0.42/0.39/0.33, `ok`
/// 0.84/0.98/0.91/0.77, `back` 0.3, `synch123` 0.4, `synch234` 0.5, `out4` 0.9).
pub fn kanban(n: u32) -> Net {
    let mut net = Net::new(format!("kanban{n}"));
    net.set_param("N", Some(f64::from(n)), ParamKind::Int);
    let mut pm = Vec::new();
    let mut pback = Vec::new();
    let mut pkan = Vec::new();
    let mut pout = Vec::new();
    for i in 1..=4 {
        pm.push(net.add_place(format!("Pm{i}"), 0u32));
        pback.push(net.add_place(format!("Pback{i}"), 0u32));
        pkan.push(net.add_place(format!("Pkan{i}"), Expr::param("N")));
        pout.push(net.add_place(format!("Pout{i}"), 0u32));
    }
    let in1 = rate(&mut net, "in1", 1.0);
    let t = net.add_timed("tin1", in1);
    arcs(&mut net, t, &[pkan[0]], &[pm[0]]);
    let redo = [0.36, 0.42, 0.39, 0.33];
    let ok = [0.84, 0.98, 0.91, 0.77];
    let back = rate(&mut net, "back", 0.3);
    for i in 0..4 {
        let r = rate(&mut net, &format!("redo{}", i + 1), redo[i]);
        let t = net.add_timed(format!("tredo{}", i + 1), r);
        arcs(&mut net, t, &[pm[i]], &[pback[i]]);
        let t = net.add_timed(format!("tback{}", i + 1), back.clone());
        arcs(&mut net, t, &[pback[i]], &[pm[i]]);
        let r = rate(&mut net, &format!("ok{}", i + 1), ok[i]);
        let t = net.add_timed(format!("tok{}", i + 1), r);
        arcs(&mut net, t, &[pm[i]], &[pout[i]]);
    }
    let s1 = rate(&mut net, "synch123", 0.4);
    let t = net.add_timed("tsynch1_23", s1);
    arcs(
        &mut net,
        t,
        &[pout[0], pkan[1], pkan[2]],
        &[pkan[0], pm[1], pm[2]],
    );
    let s2 = rate(&mut net, "synch234", 0.5);
    let t = net.add_timed("tsynch4_23", s2);
    arcs(
        &mut net,
        t,
        &[pout[1], pout[2], pkan[3]],
        &[pkan[1], pkan[2], pm[3]],
    );
    let out4 = rate(&mut net, "out4", 0.9);
    let t = net.add_timed("tout4", out4);
    arcs(&mut net, t, &[pout[3]], &[pkan[3]]);
    net
}

/// The flexible manufacturing system of Ciardo & Trivedi with `n` pallets of
/// each part type (places and arcs as the MCC `FMS-PT` nets: machines M1 ×3,
/// M2 ×1, M3 ×2). With `timed_only` every transition is timed with rate 1
/// (the P/T net's reachability set); otherwise it is a GSPN: machine
/// acquisitions (`tM1`, `tM2`, `tM3`) and the assembly start `tx` are
/// immediate, parts leaving machines choose by weight (`tP1e`:`tP1j` =
/// 0.8:0.2, `tP2e`:`tP2j` = 0.6:0.4), and processing steps are timed with
/// infinite servers. **Decision:** the original's load throttle
/// `min(1, Np/Σ#parts)` is marking dependent and left out.
pub fn fms(n: u32, timed_only: bool) -> Net {
    let mut net = Net::new(format!("fms{n}"));
    net.set_param("N", Some(f64::from(n)), ParamKind::Int);
    let names = [
        "P1", "P1wM1", "P1M1", "M1", "P1d", "P1s", "P1wP2", "P12", "P12wM3", "P12M3", "M3", "P12s", "P2",
        "P2wM2", "P2M2", "M2", "P2d", "P2wP1", "P2s", "P3", "P3M2", "P3s",
    ];
    let mut p = std::collections::BTreeMap::new();
    for name in names {
        let init: Expr = match name {
            "P1" | "P2" | "P3" => Expr::param("N"),
            "M1" => 3u32.into(),
            "M2" => 1u32.into(),
            "M3" => 2u32.into(),
            _ => 0u32.into(),
        };
        p.insert(name, net.add_place(name, init));
    }
    // (name, inputs, outputs, kind): kind = rate for timed, or (weight) for immediate.
    enum K {
        Timed(f64),
        Imm(f64),
    }
    let spec: [(&str, &[&str], &[&str], K); 20] = [
        ("tP1", &["P1"], &["P1wM1"], K::Timed(1.0 / 3.0)),
        ("tM1", &["P1wM1", "M1"], &["P1M1"], K::Imm(1.0)),
        ("tP1M1", &["P1M1"], &["P1d", "M1"], K::Timed(1.0 / 4.0)),
        ("tP1e", &["P1d"], &["P1s"], K::Imm(0.8)),
        ("tP1j", &["P1d"], &["P1wP2"], K::Imm(0.2)),
        ("tP1s", &["P1s"], &["P1"], K::Timed(1.0 / 60.0)),
        ("tP2", &["P2"], &["P2wM2"], K::Timed(1.0 / 2.0)),
        ("tM2", &["P2wM2", "M2"], &["P2M2"], K::Imm(1.0)),
        ("tP2M2", &["P2M2"], &["P2d", "M2"], K::Timed(1.0 / 6.0)),
        ("tP2e", &["P2d"], &["P2s"], K::Imm(0.6)),
        ("tP2j", &["P2d"], &["P2wP1"], K::Imm(0.4)),
        ("tP2s", &["P2s"], &["P2"], K::Timed(1.0 / 60.0)),
        ("tx", &["P1wP2", "P2wP1"], &["P12"], K::Imm(1.0)),
        ("tP12", &["P12"], &["P12wM3"], K::Timed(1.0)),
        ("tM3", &["P12wM3", "M3"], &["P12M3"], K::Imm(1.0)),
        ("tP12M3", &["P12M3"], &["P12s", "M3"], K::Timed(1.0 / 2.0)),
        ("tP12s", &["P12s"], &["P1", "P2"], K::Timed(1.0 / 60.0)),
        ("tP3", &["P3"], &["P3M2"], K::Timed(1.0 / 2.0)),
        ("tP3M2", &["P3M2", "M2"], &["M2", "P3s"], K::Timed(1.0 / 2.0)),
        ("tP3s", &["P3s"], &["P3"], K::Timed(1.0 / 60.0)),
    ];
    for (name, ins, outs, kind) in spec {
        let t = match kind {
            _ if timed_only => net.add_timed(name, 1.0),
            K::Timed(r) => {
                let e = rate(&mut net, &format!("r_{name}"), r);
                let t = net.add_timed(name, e);
                net.set_servers(t, Servers::Infinite);
                t
            }
            K::Imm(w) => net.add_immediate(name, w, 1),
        };
        for i in ins {
            net.add_arc(ArcKind::Input, p[i], t, 1u32);
        }
        for o in outs {
            net.add_arc(ArcKind::Output, p[o], t, 1u32);
        }
    }
    net
}

/// Dining philosophers as in the MCC `Philosophers-PT` nets: philosopher `i`
/// thinks, takes either fork first (`FF1a`: left, `FF1b`: right), then the
/// other (`FF2a`, `FF2b`), eats and puts both back (`End`). All timed, rate
/// 1 (parameter `lambda`). It deadlocks when every philosopher holds one
/// fork; `3^n` reachable markings.
pub fn philosophers(n: u32) -> Net {
    let mut net = Net::new(format!("philosophers{n}"));
    let lambda = rate(&mut net, "lambda", 1.0);
    let n = n as usize;
    let think: Vec<_> = (1..=n)
        .map(|i| net.add_place(format!("Think_{i}"), 1u32))
        .collect();
    let fork: Vec<_> = (1..=n)
        .map(|i| net.add_place(format!("Fork_{i}"), 1u32))
        .collect();
    let catch1: Vec<_> = (1..=n)
        .map(|i| net.add_place(format!("Catch1_{i}"), 0u32))
        .collect();
    let catch2: Vec<_> = (1..=n)
        .map(|i| net.add_place(format!("Catch2_{i}"), 0u32))
        .collect();
    let eat: Vec<_> = (1..=n).map(|i| net.add_place(format!("Eat_{i}"), 0u32)).collect();
    for i in 0..n {
        let left = fork[(i + n - 1) % n];
        let right = fork[i];
        let k = i + 1;
        let t = net.add_timed(format!("FF1a_{k}"), lambda.clone());
        arcs(&mut net, t, &[think[i], left], &[catch1[i]]);
        let t = net.add_timed(format!("FF1b_{k}"), lambda.clone());
        arcs(&mut net, t, &[think[i], right], &[catch2[i]]);
        let t = net.add_timed(format!("FF2a_{k}"), lambda.clone());
        arcs(&mut net, t, &[catch1[i], right], &[eat[i]]);
        let t = net.add_timed(format!("FF2b_{k}"), lambda.clone());
        arcs(&mut net, t, &[catch2[i], left], &[eat[i]]);
        let t = net.add_timed(format!("End_{k}"), lambda.clone());
        arcs(&mut net, t, &[eat[i]], &[think[i], right, left]);
    }
    net
}

/// `n` robots sharing `k` corridors: an idle robot requests a passage
/// (rate `request`), takes any free corridor at once (immediate, equal
/// weights — the choice creates vanishing markings), traverses it (rate
/// `traverse`, one robot per corridor) and works at the far end (rate
/// `work`) before returning to idle.
pub fn robots_corridors(n: u32, k: u32) -> Net {
    let mut net = Net::new(format!("robots{n}_corridors{k}"));
    let request = rate(&mut net, "r_request", 0.5);
    let traverse = rate(&mut net, "r_traverse", 2.0);
    let work = rate(&mut net, "r_work", 0.25);
    let idle = net.add_place("Idle", n);
    let waiting = net.add_place("Waiting", 0u32);
    let working = net.add_place("Working", 0u32);
    let t = net.add_timed("request", request);
    net.set_servers(t, Servers::Infinite);
    arcs(&mut net, t, &[idle], &[waiting]);
    let t = net.add_timed("work_done", work);
    net.set_servers(t, Servers::Infinite);
    arcs(&mut net, t, &[working], &[idle]);
    for c in 1..=k {
        let free = net.add_place(format!("Free{c}"), 1u32);
        let busy = net.add_place(format!("Busy{c}"), 0u32);
        let t = net.add_immediate(format!("enter{c}"), 1.0, 1);
        arcs(&mut net, t, &[waiting, free], &[busy]);
        let t = net.add_timed(format!("leave{c}"), traverse.clone());
        arcs(&mut net, t, &[busy], &[free, working]);
    }
    net
}

/// `n` robots choosing corridors, a net with decisions (docs/gspn.md,
/// *Decisions*): an idle robot requests a passage (rate `r_request` = 0.5,
/// infinite servers); a waiting robot takes a free corridor, the policy
/// choosing which when several are free (decisions `enter1…3`). Corridor
/// `c` is crossed at rate `r_cross_c` (3, 2, 1) but loses the robot at
/// rate `r_crash_c` (0.3, 0.05, 0): fast and risky to slow and safe. A
/// robot across works (rate `r_work` = 0.25, infinite servers) and goes
/// back to idle; a lost robot stays lost. Labels `all_working`
/// (`#Working = N`) and `lost` (`#Lost > 0`); reward model `trips` (an
/// impulse per crossing).
pub fn corridors_decide(n: u32) -> Net {
    let mut net = Net::new(format!("corridors{n}"));
    let request = rate(&mut net, "r_request", 0.5);
    let work = rate(&mut net, "r_work", 0.25);
    let idle = net.add_place("Idle", n);
    let waiting = net.add_place("Waiting", 0u32);
    let working = net.add_place("Working", 0u32);
    let lost = net.add_place("Lost", 0u32);
    let t = net.add_timed("request", request);
    net.set_servers(t, Servers::Infinite);
    arcs(&mut net, t, &[idle], &[waiting]);
    let t = net.add_timed("work_done", work);
    net.set_servers(t, Servers::Infinite);
    arcs(&mut net, t, &[working], &[idle]);
    let mut crossings = Vec::new();
    for (c, (cross, crash)) in [(3.0, 0.3), (2.0, 0.05), (1.0, 0.0)].into_iter().enumerate() {
        let c = c + 1;
        let free = net.add_place(format!("Free{c}"), 1u32);
        let busy = net.add_place(format!("Busy{c}"), 0u32);
        let t = net.add_decision(format!("enter{c}"), 1);
        arcs(&mut net, t, &[waiting, free], &[busy]);
        let r = rate(&mut net, &format!("r_cross{c}"), cross);
        let t = net.add_timed(format!("cross{c}"), r);
        arcs(&mut net, t, &[busy], &[free, working]);
        crossings.push((t, Expr::Num(1.0)));
        if crash > 0.0 {
            let r = rate(&mut net, &format!("r_crash{c}"), crash);
            let t = net.add_timed(format!("crash{c}"), r);
            arcs(&mut net, t, &[busy], &[free, lost]);
        }
    }
    let compare = |op, place: &str, value: u32| {
        Expr::Binary(
            op,
            Box::new(Expr::Tokens(place.into())),
            Box::new(Expr::from(value)),
        )
    };
    net.add_label("all_working", compare(BinOp::Eq, "Working", n));
    net.add_label("lost", compare(BinOp::Gt, "Lost", 0));
    net.add_reward(crate::net::RewardModel {
        name: "trips".into(),
        rate: None,
        impulses: crossings,
    });
    net
}

/// Customers per station of [`Family::Polling`].
pub const POLLING_CUSTOMERS: u32 = 3;
/// Stations of [`Family::Tandem`].
pub const TANDEM_STATIONS: u32 = 5;

/// A polling system: one server visits `n` stations in a cycle; station `i`
/// has `k` customers that think (`Think_i`, infinite servers: each arrives
/// at rate `arrive`) and queue (`Queue_i`). The server at a station
/// (`At_i`) serves its queue exhaustively (`serve_i`, rate `serve`), leaves
/// when it is empty (`leave_i`, rate `switch`, inhibited by the queue) and
/// walks to the next station (`Walk_i` → `At_{i+1}`, rate `walk`). All
/// transitions timed; the server's places form one P-invariant and each
/// station's another, and every combination is reachable, so the reachable
/// set is the product `2n · (k+1)^n` (the structured engine's components).
/// Rates differ by station (`arrive` 0.3 + 0.05·i, `serve` 2.0 − 0.1·i).
pub fn polling(n: u32, k: u32) -> Net {
    let mut net = Net::new(format!("polling{n}"));
    let switch = rate(&mut net, "switch", 5.0);
    let walk = rate(&mut net, "walk", 2.0);
    let at: Vec<PlaceId> = (0..n)
        .map(|i| net.add_place(format!("At_{}", i + 1), u32::from(i == 0)))
        .collect();
    let walking: Vec<PlaceId> = (0..n)
        .map(|i| net.add_place(format!("Walk_{}", i + 1), 0u32))
        .collect();
    for i in 0..n as usize {
        let name = i + 1;
        let think = net.add_place(format!("Think_{name}"), k);
        let queue = net.add_place(format!("Queue_{name}"), 0u32);
        let a = rate(&mut net, &format!("arrive{name}"), 0.3 + 0.05 * i as f64);
        let t = net.add_timed(format!("arrive_{name}"), a);
        net.set_servers(t, Servers::Infinite);
        arcs(&mut net, t, &[think], &[queue]);
        let sv = rate(&mut net, &format!("serve{name}"), 2.0 - 0.1 * i as f64);
        let t = net.add_timed(format!("serve_{name}"), sv);
        arcs(&mut net, t, &[queue, at[i]], &[think, at[i]]);
        let t = net.add_timed(format!("leave_{name}"), switch.clone());
        arcs(&mut net, t, &[at[i]], &[walking[i]]);
        net.inhibitor(queue, t);
        let t = net.add_timed(format!("walk_{name}"), walk.clone());
        arcs(&mut net, t, &[walking[i]], &[at[(i + 1) % n as usize]]);
    }
    net
}

/// An open tandem line of `stations` stations with buffers of `n` places:
/// jobs arrive at rate `lambda` while the first buffer has room; station
/// `i` has `Jobs_i` and `Free_i` (`Jobs_i + Free_i = n`) and two servers,
/// each moving a job on (`move_i`, rate `serve_i`) when the next buffer has
/// room — its enabling degree is `min(#Jobs_i, #Free_{i+1})` (at most 2), a
/// rate that depends on two stations' markings; the last station's jobs
/// leave (`depart`, two servers). The reachable set is the product of the
/// stations' `n + 1` local states.
pub fn tandem(n: u32, stations: u32) -> Net {
    let mut net = Net::new(format!("tandem{n}"));
    net.set_param("N", Some(f64::from(n)), ParamKind::Int);
    let jobs: Vec<PlaceId> = (1..=stations)
        .map(|i| net.add_place(format!("Jobs_{i}"), 0u32))
        .collect();
    let free: Vec<PlaceId> = (1..=stations)
        .map(|i| net.add_place(format!("Free_{i}"), Expr::param("N")))
        .collect();
    let a = rate(&mut net, "lambda", 1.0);
    let t = net.add_timed("arrive", a);
    arcs(&mut net, t, &[free[0]], &[jobs[0]]);
    for i in 0..stations as usize {
        let r = rate(&mut net, &format!("serve{}", i + 1), 0.8 + 0.15 * i as f64);
        if i + 1 < stations as usize {
            let t = net.add_timed(format!("move_{}", i + 1), r);
            net.set_servers(t, Servers::K(2));
            arcs(&mut net, t, &[jobs[i], free[i + 1]], &[free[i], jobs[i + 1]]);
        } else {
            let t = net.add_timed("depart", r);
            net.set_servers(t, Servers::K(2));
            arcs(&mut net, t, &[jobs[i]], &[free[i]]);
        }
    }
    net
}

/// An M/M/1/K queue: arrivals at `lambda` blocked by an inhibitor arc of
/// multiplicity `k` on place `queue`, service at `mu`.
pub fn mm1k(lambda: f64, mu: f64, k: u32) -> Net {
    let mut net = Net::new(format!("mm1_{k}"));
    let l = rate(&mut net, "lambda", lambda);
    let m = rate(&mut net, "mu", mu);
    let q = net.add_place("queue", 0u32);
    let arrive = net.add_timed("arrive", l);
    net.output(arrive, q);
    net.add_arc(ArcKind::Inhibitor, q, arrive, k);
    let serve = net.add_timed("serve", m);
    net.input(q, serve);
    net
}
