//! Known answers for the GSPN semantics, on nets solved by hand: vanishing
//! loops (geometric series of immediate firings), timeless traps,
//! priorities, k-server and infinite-server transitions (birth–death closed
//! forms), self-loops, and absorption into several bottom components.

use petri::{
    ArcKind, CompiledGspn, Error, ExploreParams, Net, Params, PlaceId, ReachabilityGraph, Servers, Solution,
    SolveParams, TransitionId,
};

fn compile(net: &Net) -> CompiledGspn {
    let g = net.instantiate(&Params::new()).unwrap();
    CompiledGspn::build(&g, &ExploreParams::default()).unwrap_or_else(|e| panic!("{}: {e}", net.name))
}

fn solve(c: &CompiledGspn) -> Solution {
    c.solve(&Params::new(), None, &SolveParams::default()).unwrap()
}

#[track_caller]
fn assert_close(got: f64, want: f64, rel: f64, what: &str) {
    assert!(
        (got - want).abs() <= rel * want.abs().max(1e-300),
        "{what}: got {got}, want {want} (relative error {:.2e})",
        (got - want).abs() / want.abs()
    );
}

/// Long-run probability of the tangible markings satisfying `cond`.
fn pi_where(c: &CompiledGspn, sol: &Solution, cond: impl Fn(&[u32]) -> bool) -> f64 {
    (0..c.num_tangible())
        .filter(|&s| cond(&c.tangible_marking(s)))
        .map(|s| sol.pi[s])
        .sum()
}

fn x(c: &CompiledGspn, sol: &Solution, name: &str) -> f64 {
    sol.throughput(c.gspn().transition(name).unwrap())
}

fn arcs(net: &mut Net, t: TransitionId, ins: &[PlaceId], outs: &[PlaceId]) {
    for &p in ins {
        net.input(p, t);
    }
    for &p in outs {
        net.output(t, p);
    }
}

// ---------------------------------------------------------------------------
// Vanishing loops
// ---------------------------------------------------------------------------

const LAMBDA: f64 = 2.0;
const MU: f64 = 0.5;
const NU: f64 = 3.0;

/// `A —ta(λ)→ V1`; from `V1`, `i1` (weight 3) to `V2` or `i2` (weight 1) to
/// `B`; from `V2`, `i3` (weight 1) to `C` or `i4` (weight 4) back to `V1`;
/// `B —tb(μ)→ A`, `C —tc(ν)→ A`. `V1 ⇄ V2` is a vanishing loop.
fn vanishing_loop(back_priority: u32, initial: &str) -> Net {
    let mut n = Net::new("vanishing loop");
    let p = |n: &mut Net, name: &str| n.add_place(name, u32::from(name == initial));
    let (a, v1, v2, b, c) = (
        p(&mut n, "A"),
        p(&mut n, "V1"),
        p(&mut n, "V2"),
        p(&mut n, "B"),
        p(&mut n, "C"),
    );
    let t = n.add_timed("ta", LAMBDA);
    arcs(&mut n, t, &[a], &[v1]);
    let t = n.add_immediate("i1", 3.0, 1);
    arcs(&mut n, t, &[v1], &[v2]);
    let t = n.add_immediate("i2", 1.0, 1);
    arcs(&mut n, t, &[v1], &[b]);
    let t = n.add_immediate("i3", 1.0, 1);
    arcs(&mut n, t, &[v2], &[c]);
    let t = n.add_immediate("i4", 4.0, back_priority);
    arcs(&mut n, t, &[v2], &[v1]);
    let t = n.add_timed("tb", MU);
    arcs(&mut n, t, &[b], &[a]);
    let t = n.add_timed("tc", NU);
    arcs(&mut n, t, &[c], &[a]);
    n
}

#[test]
fn vanishing_loop_is_resolved_exactly_with_its_geometric_series_of_firings() {
    let c = compile(&vanishing_loop(1, "A"));
    let rg = ReachabilityGraph::explore(c.gspn(), &ExploreParams::default()).unwrap();
    assert_eq!(
        (rg.num_markings(), rg.num_tangible(), rg.num_vanishing()),
        (5, 3, 2),
        "markings A, B, C tangible; V1, V2 vanishing"
    );
    assert_eq!(c.num_tangible(), 3);
    assert!(c.is_ergodic());
    let sol = solve(&c);

    // From V1: to V2 with a = 3/4, from V2 back with b = 4/5. Each round
    // returns with probability ab = 0.6, so V1 is visited 1/(1 − ab) = 2.5
    // times on average (a geometric series).
    let (a, b) = (0.75, 0.8);
    let visits = 1.0 / (1.0 - a * b);
    let to_b = (1.0 - a) * visits; // 0.625
    let to_c = a * (1.0 - b) * visits; // 0.375
    // One cycle A → (B or C) → A lasts T on average.
    let cycle = 1.0 / LAMBDA + to_b / MU + to_c / NU;
    let pi_a = (1.0 / LAMBDA) / cycle;
    let pi_b = (to_b / MU) / cycle;
    let pi_c = (to_c / NU) / cycle;
    let g = c.gspn();
    let (pa, pb, pc) = (
        g.place("A").unwrap(),
        g.place("B").unwrap(),
        g.place("C").unwrap(),
    );
    assert_close(sol.mean_tokens(pa), pi_a, 1e-14, "π(A)");
    assert_close(sol.mean_tokens(pb), pi_b, 1e-14, "π(B)");
    assert_close(sol.mean_tokens(pc), pi_c, 1e-14, "π(C)");
    assert_eq!(
        sol.mean_tokens(g.place("V1").unwrap()),
        0.0,
        "vanishing places hold no time"
    );

    let rate = 1.0 / cycle; // cycles per unit time
    assert_close(x(&c, &sol, "ta"), rate, 1e-14, "X(ta)");
    assert_close(
        x(&c, &sol, "i1"),
        rate * a * visits,
        1e-14,
        "X(i1) = X(ta)·a/(1 − ab)",
    );
    assert_close(x(&c, &sol, "i2"), rate * to_b, 1e-14, "X(i2)");
    assert_close(x(&c, &sol, "i3"), rate * to_c, 1e-14, "X(i3)");
    assert_close(
        x(&c, &sol, "i4"),
        rate * a * b * visits,
        1e-14,
        "X(i4) = X(ta)·ab/(1 − ab)",
    );
    assert_close(x(&c, &sol, "tb"), rate * to_b, 1e-14, "X(tb)");
    assert_close(x(&c, &sol, "tc"), rate * to_c, 1e-14, "X(tc)");
}

#[test]
fn vanishing_initial_marking_starts_in_the_exit_distribution() {
    let c = compile(&vanishing_loop(1, "V1"));
    let mut init: Vec<(Vec<u32>, f64)> = c
        .initial_distribution()
        .iter()
        .map(|&(s, p)| (c.tangible_marking(s as usize), p))
        .collect();
    init.sort_by(|x, y| x.0.cmp(&y.0));
    // Places A, V1, V2, B, C: B with 0.625, C with 0.375.
    assert_eq!(init.len(), 2, "{init:?}");
    assert_eq!(init[0].0, [0, 0, 0, 0, 1]);
    assert_close(init[0].1, 0.375, 1e-15, "P(start in C)");
    assert_eq!(init[1].0, [0, 0, 0, 1, 0]);
    assert_close(init[1].1, 0.625, 1e-15, "P(start in B)");
    // The long run does not depend on where it starts.
    let from_a = solve(&compile(&vanishing_loop(1, "A")));
    let sol = solve(&c);
    for (p, (&x, &y)) in sol.mean_tokens.iter().zip(&from_a.mean_tokens).enumerate() {
        assert_close(x, y, 1e-14, &format!("E[#{}]", c.gspn().place_names()[p]));
    }
}

#[test]
fn vanishing_loop_with_a_pre_empted_exit() {
    // i4 (back to V1) now has priority 2: from V2 it always wins, i3 never
    // fires, and the loop is left through i2 only: V1 is visited 1/(1 − a) = 4
    // times per cycle.
    let c = compile(&vanishing_loop(2, "A"));
    assert_eq!(c.num_tangible(), 2, "C is never reached");
    let sol = solve(&c);
    let cycle = 1.0 / LAMBDA + 1.0 / MU;
    let rate = 1.0 / cycle;
    assert_eq!(x(&c, &sol, "i3"), 0.0);
    assert_eq!(x(&c, &sol, "tc"), 0.0);
    assert_close(x(&c, &sol, "i2"), rate, 1e-14, "X(i2)");
    assert_close(x(&c, &sol, "i1"), rate * 3.0, 1e-14, "X(i1) = X(ta)·a/(1 − a)");
    assert_close(x(&c, &sol, "i4"), rate * 3.0, 1e-14, "X(i4)");
}

#[test]
fn vanishing_loop_left_with_a_tiny_probability() {
    // V1 ⇄ V2 with an exit of weight 1e-6 against 1: about 1e6 rounds per
    // visit. The loop's system is badly conditioned (~1e6) but still solved.
    let mut n = Net::new("sticky loop");
    let a = n.add_place("A", 1u32);
    let v1 = n.add_place("V1", 0u32);
    let v2 = n.add_place("V2", 0u32);
    let t = n.add_timed("ta", 1.0);
    arcs(&mut n, t, &[a], &[v1]);
    let t = n.add_immediate("go", 1.0, 1);
    arcs(&mut n, t, &[v1], &[v2]);
    let t = n.add_immediate("back", 1.0, 1);
    arcs(&mut n, t, &[v2], &[v1]);
    let t = n.add_immediate("out", 1e-6, 1);
    arcs(&mut n, t, &[v2], &[a]);
    let c = compile(&n);
    assert_eq!(c.num_tangible(), 1);
    let sol = solve(&c);
    let p_out = 1e-6 / (1.0 + 1e-6);
    assert_close(x(&c, &sol, "out"), 1.0, 1e-9, "X(out)");
    assert_close(x(&c, &sol, "go"), 1.0 / p_out, 1e-9, "X(go) = 1/p");
    assert_close(
        x(&c, &sol, "back"),
        (1.0 - p_out) / p_out,
        1e-9,
        "X(back) = (1 − p)/p",
    );
}

// ---------------------------------------------------------------------------
// Timeless traps
// ---------------------------------------------------------------------------

/// `A —t→ X`, then `X —x→ Y —y→ X` forever; `exit` adds `X —out→ Z` at
/// priority `exit`.
fn ping_pong(exit: Option<u32>) -> Net {
    let mut n = Net::new("ping pong");
    let a = n.add_place("A", 1u32);
    let px = n.add_place("X", 0u32);
    let py = n.add_place("Y", 0u32);
    let t = n.add_timed("t", 1.0);
    arcs(&mut n, t, &[a], &[px]);
    let t = n.add_immediate("x", 1.0, 2);
    arcs(&mut n, t, &[px], &[py]);
    let t = n.add_immediate("y", 1.0, 2);
    arcs(&mut n, t, &[py], &[px]);
    if let Some(priority) = exit {
        let z = n.add_place("Z", 0u32);
        let t = n.add_immediate("out", 1.0, priority);
        arcs(&mut n, t, &[px], &[z]);
        let t = n.add_timed("back", 1.0);
        arcs(&mut n, t, &[z], &[a]);
    }
    n
}

#[test]
fn timeless_trap_reached_after_a_timed_firing_is_an_error_naming_its_markings() {
    let g = ping_pong(None).instantiate(&Params::new()).unwrap();
    match CompiledGspn::build(&g, &ExploreParams::default()) {
        Err(Error::TimelessTrap { count, markings }) => {
            assert_eq!(count, 2, "the trap is {{X}}, {{Y}}: {markings}");
            assert!(markings.contains("[X]") && markings.contains("[Y]"), "{markings}");
        }
        other => panic!("expected a timeless trap, got {other:?}"),
    }
    // The exploration alone is fine: the trap is a property of the chain.
    let rg = ReachabilityGraph::explore(&g, &ExploreParams::default()).unwrap();
    assert_eq!((rg.num_tangible(), rg.num_vanishing()), (1, 2));
}

#[test]
fn loop_whose_only_exit_is_pre_empted_is_a_timeless_trap() {
    // `out` leaves X but has priority 1 < 2: it never fires.
    let g = ping_pong(Some(1)).instantiate(&Params::new()).unwrap();
    let err = CompiledGspn::build(&g, &ExploreParams::default()).unwrap_err();
    assert!(matches!(err, Error::TimelessTrap { count: 2, .. }), "{err}");
    assert!(err.to_string().contains("timeless trap"), "{err}");
    // At the same priority it is a vanishing loop left with probability 1/2
    // from X: x fires (1/2)/(1 − 1/2) = 1 time per exit on average.
    let c = compile(&ping_pong(Some(2)));
    let sol = solve(&c);
    let out = x(&c, &sol, "out");
    assert_close(out, 0.5, 1e-14, "X(out): cycles A → Z → A of mean 2");
    assert_close(x(&c, &sol, "x"), out, 1e-14, "X(x) = X(out)");
    assert_close(x(&c, &sol, "y"), out, 1e-14, "X(y) = X(out)");
}

#[test]
fn immediate_self_loop_is_a_timeless_trap_of_one_marking() {
    let mut n = Net::new("spin");
    let a = n.add_place("A", 1u32);
    let s = n.add_place("S", 0u32);
    let t = n.add_timed("t", 1.0);
    arcs(&mut n, t, &[a], &[s]);
    let t = n.add_immediate("spin", 1.0, 1);
    arcs(&mut n, t, &[s], &[s]);
    let g = n.instantiate(&Params::new()).unwrap();
    let err = CompiledGspn::build(&g, &ExploreParams::default()).unwrap_err();
    match &err {
        Error::TimelessTrap { count: 1, markings } => assert!(markings.contains("[S]"), "{markings}"),
        other => panic!("expected a trap of one marking, got {other}"),
    }
}

#[test]
fn unreachable_trap_is_no_error() {
    // The ping-pong places never get a token.
    let mut n = ping_pong(None);
    let t = n.transition_id("t").unwrap();
    n.arcs
        .retain(|arc| !(arc.transition == t && arc.kind == ArcKind::Output));
    let a = n.place_id("A").unwrap();
    n.output(t, a);
    let c = compile(&n);
    assert_eq!(c.num_tangible(), 1);
    assert_close(x(&c, &solve(&c), "t"), 1.0, 1e-15, "X(t)");
}

// ---------------------------------------------------------------------------
// Priorities
// ---------------------------------------------------------------------------

/// `A —ta(λ)→ B`; from `B`, `hi` (priority 2, weight 1) to `C` or `lo`
/// (priority 1, weight 100) to `D`; `C —tc→ A`, `D —td→ A`. With
/// `alternate`, `hi` is inhibited by `H`, puts a token in `H`, and `td`
/// takes it back: `hi` and `lo` then alternate.
fn priorities(alternate: bool) -> Net {
    let mut n = Net::new("priorities");
    let a = n.add_place("A", 1u32);
    let b = n.add_place("B", 0u32);
    let c = n.add_place("C", 0u32);
    let d = n.add_place("D", 0u32);
    let t = n.add_timed("ta", LAMBDA);
    arcs(&mut n, t, &[a], &[b]);
    let hi = n.add_immediate("hi", 1.0, 2);
    arcs(&mut n, hi, &[b], &[c]);
    let t = n.add_immediate("lo", 100.0, 1);
    arcs(&mut n, t, &[b], &[d]);
    let t = n.add_timed("tc", MU);
    arcs(&mut n, t, &[c], &[a]);
    let td = n.add_timed("td", NU);
    arcs(&mut n, td, &[d], &[a]);
    if alternate {
        let h = n.add_place("H", 0u32);
        n.inhibitor(h, hi);
        n.output(hi, h);
        n.input(h, td);
    }
    n
}

#[test]
fn lower_priority_immediate_transition_never_fires_when_pre_empted() {
    let c = compile(&priorities(false));
    let rg = ReachabilityGraph::explore(c.gspn(), &ExploreParams::default()).unwrap();
    let lo = c.gspn().transition("lo").unwrap();
    for m in 0..rg.num_markings() {
        assert!(
            rg.edges(petri::MarkingId(m as u32)).all(|e| e.transition != lo),
            "no edge fires `lo`"
        );
    }
    let d = c.gspn().place("D").unwrap();
    assert_eq!(rg.place_bounds()[d.index()], 0, "D is never marked");
    let sol = solve(&c);
    assert_eq!(x(&c, &sol, "lo"), 0.0);
    assert_eq!(x(&c, &sol, "td"), 0.0);
    let rate = 1.0 / (1.0 / LAMBDA + 1.0 / MU);
    assert_close(x(&c, &sol, "hi"), rate, 1e-14, "X(hi)");
}

#[test]
fn lower_priority_immediate_transition_fires_when_the_higher_is_disabled() {
    // H empty: hi (priority 2) beats lo (weight 100) and marks H. H marked:
    // hi is inhibited, lo fires, and td empties H. Two cycles take
    // 2/λ + 1/μ + 1/ν.
    let c = compile(&priorities(true));
    assert_eq!(c.num_tangible(), 4, "A, C+H, A+H, D+H");
    let sol = solve(&c);
    let two_cycles = 2.0 / LAMBDA + 1.0 / MU + 1.0 / NU;
    assert_close(x(&c, &sol, "ta"), 2.0 / two_cycles, 1e-14, "X(ta)");
    assert_close(x(&c, &sol, "hi"), 1.0 / two_cycles, 1e-14, "X(hi)");
    assert_close(x(&c, &sol, "lo"), 1.0 / two_cycles, 1e-14, "X(lo)");
    let g = c.gspn();
    let (a, h) = (g.place("A").unwrap().index(), g.place("H").unwrap().index());
    let a_with_h = pi_where(&c, &sol, |m| m[a] == 1 && m[h] == 1);
    assert_close(a_with_h, (1.0 / LAMBDA) / two_cycles, 1e-14, "P{A and H}");
}

// ---------------------------------------------------------------------------
// Server semantics
// ---------------------------------------------------------------------------

/// Birth–death probabilities `p_n ∝ Π_{i ≤ n} birth(i−1)/death(i)`, `n = 0..=k`.
fn birth_death(k: u32, birth: impl Fn(u32) -> f64, death: impl Fn(u32) -> f64) -> Vec<f64> {
    let mut p = vec![1.0];
    for n in 1..=k {
        p.push(p[n as usize - 1] * birth(n - 1) / death(n));
    }
    let total: f64 = p.iter().sum();
    p.iter().map(|v| v / total).collect()
}

/// M/M/c/K: arrivals at λ blocked at `k` by an inhibitor arc, service at μ
/// with `servers`; `multiplicity` tokens per customer on the service's input.
fn queue(lambda: f64, mu: f64, k: u32, servers: Servers, multiplicity: u32) -> Net {
    let mut n = Net::new("queue");
    let q = n.add_place("queue", 0u32);
    let arrive = n.add_timed("arrive", lambda);
    n.add_arc(ArcKind::Output, q, arrive, multiplicity);
    n.add_arc(ArcKind::Inhibitor, q, arrive, k * multiplicity);
    let serve = n.add_timed("serve", mu);
    n.set_servers(serve, servers);
    n.add_arc(ArcKind::Input, q, serve, multiplicity);
    n
}

/// Checks `π`, `E[#queue]` and both throughputs against `p` (customers
/// `0..=k`, `multiplicity` tokens each) and the service rate in state `n`.
fn check_queue(net: &Net, p: &[f64], multiplicity: u32, service: impl Fn(u32) -> f64, what: &str) {
    let c = compile(net);
    let k = p.len() - 1;
    assert_eq!(c.num_tangible(), k + 1, "{what}: states 0..=K");
    let sol = solve(&c);
    for s in 0..c.num_tangible() {
        let n = c.tangible_marking(s)[0] / multiplicity;
        assert_close(sol.pi[s], p[n as usize], 1e-13, &format!("{what}: p_{n}"));
    }
    let mean: f64 = p.iter().enumerate().map(|(n, x)| (n as f64) * x).sum();
    let q = c.gspn().place("queue").unwrap();
    assert_close(
        sol.mean_tokens(q),
        mean * f64::from(multiplicity),
        1e-13,
        &format!("{what}: E[#queue]"),
    );
    let served: f64 = p.iter().enumerate().map(|(n, x)| service(n as u32) * x).sum();
    assert_close(x(&c, &sol, "serve"), served, 1e-13, &format!("{what}: X(serve)"));
    assert_close(
        x(&c, &sol, "arrive"),
        served,
        1e-13,
        &format!("{what}: X(arrive) = X(serve)"),
    );
}

#[test]
fn k_server_queue_matches_the_m_m_c_k_closed_form() {
    let (lambda, mu, k, servers) = (2.5, 0.8, 7u32, 3u32);
    let service = |n: u32| f64::from(n.min(servers)) * mu;
    let p = birth_death(k, |_| lambda, service);
    // X(arrive) = λ(1 − p_K) as well.
    assert!(
        (p.iter()
            .enumerate()
            .map(|(n, x)| service(n as u32) * x)
            .sum::<f64>()
            - lambda * (1.0 - p[7]))
            .abs()
            < 1e-12
    );
    check_queue(
        &queue(lambda, mu, k, Servers::K(servers), 1),
        &p,
        1,
        service,
        "M/M/3/7",
    );
}

#[test]
fn infinite_server_queue_matches_the_truncated_poisson_distribution() {
    let (lambda, mu, k) = (2.5, 0.8, 9u32);
    let rho: f64 = lambda / mu;
    // p_n ∝ ρⁿ/n!
    let mut p: Vec<f64> = (0..=k)
        .scan(1.0, |term, n| {
            if n > 0 {
                *term *= rho / f64::from(n);
            }
            Some(*term)
        })
        .collect();
    let total: f64 = p.iter().sum();
    p.iter_mut().for_each(|v| *v /= total);
    let service = |n: u32| f64::from(n) * mu;
    check_queue(
        &queue(lambda, mu, k, Servers::Infinite, 1),
        &p,
        1,
        service,
        "M/M/∞/9",
    );
    // k servers with k ≥ K are infinitely many servers.
    check_queue(&queue(lambda, mu, k, Servers::K(k), 1), &p, 1, service, "M/M/9/9");
    check_queue(
        &queue(lambda, mu, k, Servers::K(50), 1),
        &p,
        1,
        service,
        "M/M/50/9",
    );
}

#[test]
fn enabling_degree_counts_tokens_per_input_arc_multiplicity() {
    // Three tokens per customer: the enabling degree of `serve` in a marking
    // of 3n tokens is n, so the queue behaves as with multiplicity 1.
    let (lambda, mu, k, servers) = (1.2, 0.7, 6u32, 2u32);
    let service = |n: u32| f64::from(n.min(servers)) * mu;
    let p = birth_death(k, |_| lambda, service);
    check_queue(
        &queue(lambda, mu, k, Servers::K(servers), 3),
        &p,
        3,
        service,
        "M/M/2/6, 3 tokens each",
    );
    let service = |n: u32| f64::from(n) * mu;
    let p = birth_death(k, |_| lambda, service);
    check_queue(
        &queue(lambda, mu, k, Servers::Infinite, 3),
        &p,
        3,
        service,
        "M/M/∞/6, 3 tokens each",
    );
}

// ---------------------------------------------------------------------------
// Self-loops
// ---------------------------------------------------------------------------

/// `A ⇄ B` at rates 1.5 (`ab`) and 0.25 (`ba`). With `self_loops`, a timed
/// self-loop `spin` on `A` (rate 7) and a timed `hop` (rate 3) from `A` to a
/// vanishing `V` that `land` returns to `A` at once: a self-loop through a
/// vanishing marking.
fn flip_flop(self_loops: bool) -> Net {
    let mut n = Net::new("flip-flop");
    let a = n.add_place("A", 1u32);
    let b = n.add_place("B", 0u32);
    let t = n.add_timed("ab", 1.5);
    arcs(&mut n, t, &[a], &[b]);
    let t = n.add_timed("ba", 0.25);
    arcs(&mut n, t, &[b], &[a]);
    if self_loops {
        let t = n.add_timed("spin", 7.0);
        arcs(&mut n, t, &[a], &[a]);
        let v = n.add_place("V", 0u32);
        let t = n.add_timed("hop", 3.0);
        arcs(&mut n, t, &[a], &[v]);
        let t = n.add_immediate("land", 1.0, 1);
        arcs(&mut n, t, &[v], &[a]);
    }
    n
}

#[test]
fn self_loops_are_counted_in_throughputs_but_do_not_change_pi() {
    let plain = compile(&flip_flop(false));
    let looped = compile(&flip_flop(true));
    assert_eq!(looped.num_tangible(), 2);
    let (s0, s1) = (solve(&plain), solve(&looped));
    let pi_a = 0.25 / (1.5 + 0.25);
    let a = looped.gspn().place("A").unwrap();
    assert_close(s1.mean_tokens(a), pi_a, 1e-14, "π(A) with self-loops");
    for (x0, x1) in s0.pi.iter().zip(&s1.pi) {
        assert_close(*x1, *x0, 1e-14, "π unchanged by self-loops");
    }
    assert_close(x(&looped, &s1, "spin"), 7.0 * pi_a, 1e-14, "X(spin) = σ·π(A)");
    assert_close(x(&looped, &s1, "hop"), 3.0 * pi_a, 1e-14, "X(hop) = η·π(A)");
    assert_close(x(&looped, &s1, "land"), 3.0 * pi_a, 1e-14, "X(land) = X(hop)");
    assert_close(
        x(&looped, &s1, "ab"),
        x(&plain, &s0, "ab"),
        1e-14,
        "X(ab) unchanged",
    );
}

#[test]
fn single_tangible_marking_with_only_a_self_loop() {
    let mut n = Net::new("spinner");
    let a = n.add_place("A", 2u32);
    let t = n.add_timed("spin", 0.3);
    n.set_servers(t, Servers::Infinite);
    arcs(&mut n, t, &[a], &[a]);
    let c = compile(&n);
    assert_eq!(c.num_tangible(), 1);
    assert!(c.is_ergodic());
    let sol = solve(&c);
    assert_eq!(sol.pi, [1.0]);
    assert_close(x(&c, &sol, "spin"), 0.6, 1e-15, "X(spin) = 2 servers × 0.3");
}

// ---------------------------------------------------------------------------
// Absorption
// ---------------------------------------------------------------------------

#[test]
fn long_run_mixes_bottom_components_by_their_absorption_probabilities() {
    // Start S: to the dead marking D at rate 1, or into the cycle C1 ⇄ C2 at
    // rate 3 (through a transient T first, at rate 2). P(D) = 1/4, P(cycle) = 3/4.
    let mut n = Net::new("absorption");
    let s = n.add_place("S", 1u32);
    let d = n.add_place("D", 0u32);
    let tr = n.add_place("T", 0u32);
    let c1 = n.add_place("C1", 0u32);
    let c2 = n.add_place("C2", 0u32);
    let t = n.add_timed("die", 1.0);
    arcs(&mut n, t, &[s], &[d]);
    let t = n.add_timed("enter", 3.0);
    arcs(&mut n, t, &[s], &[tr]);
    let t = n.add_timed("settle", 2.0);
    arcs(&mut n, t, &[tr], &[c1]);
    let t = n.add_timed("c12", 4.0);
    arcs(&mut n, t, &[c1], &[c2]);
    let t = n.add_timed("c21", 1.0);
    arcs(&mut n, t, &[c2], &[c1]);
    let c = compile(&n);
    assert!(!c.is_ergodic());
    assert_eq!(c.stats().bottom_components, 2);
    assert_eq!(c.stats().transient_states, 2, "S and T");
    let sol = solve(&c);
    let mut bottoms: Vec<(usize, f64)> = c
        .bottom_components()
        .iter()
        .map(|b| b.len())
        .zip(sol.bottom_probabilities.iter().copied())
        .collect();
    bottoms.sort_by_key(|b| b.0);
    assert_eq!(bottoms.len(), 2);
    assert_close(bottoms[0].1, 0.25, 1e-14, "P(dead marking)");
    assert_close(bottoms[1].1, 0.75, 1e-14, "P(cycle)");
    let g = c.gspn();
    let m = |name: &str| sol.mean_tokens(g.place(name).unwrap());
    assert_close(m("D"), 0.25, 1e-14, "π(D)");
    assert_close(m("C1"), 0.75 * 0.2, 1e-14, "π(C1) = 3/4 · 1/(1 + 4)");
    assert_close(m("C2"), 0.75 * 0.8, 1e-14, "π(C2)");
    assert_eq!(
        (m("S"), m("T")),
        (0.0, 0.0),
        "transient markings have no long-run weight"
    );
    assert_eq!(x(&c, &sol, "die"), 0.0);
    assert_eq!(x(&c, &sol, "settle"), 0.0);
    assert_close(x(&c, &sol, "c12"), 0.75 * 0.2 * 4.0, 1e-14, "X(c12)");
    assert_close(x(&c, &sol, "c21"), 0.75 * 0.8, 1e-14, "X(c21)");
}

#[test]
fn vanishing_initial_marking_chooses_between_bottom_components() {
    // M0 = {S} is vanishing: `die` (weight 1) to the dead marking D, `live`
    // (weight 3) into the cycle C1 ⇄ C2. Nothing tangible is transient.
    let mut n = Net::new("first choice");
    let s = n.add_place("S", 1u32);
    let d = n.add_place("D", 0u32);
    let c1 = n.add_place("C1", 0u32);
    let c2 = n.add_place("C2", 0u32);
    let t = n.add_immediate("die", 1.0, 1);
    arcs(&mut n, t, &[s], &[d]);
    let t = n.add_immediate("live", 3.0, 1);
    arcs(&mut n, t, &[s], &[c1]);
    let t = n.add_timed("c12", 2.0);
    arcs(&mut n, t, &[c1], &[c2]);
    let t = n.add_timed("c21", 6.0);
    arcs(&mut n, t, &[c2], &[c1]);
    let c = compile(&n);
    assert_eq!((c.num_tangible(), c.stats().explore.vanishing), (3, 1));
    assert_eq!(c.stats().transient_states, 0);
    let sol = solve(&c);
    let g = c.gspn();
    let m = |name: &str| sol.mean_tokens(g.place(name).unwrap());
    assert_close(m("D"), 0.25, 1e-15, "π(D)");
    assert_close(m("C1"), 0.75 * 0.75, 1e-15, "π(C1) = 3/4 · 6/(2 + 6)");
    assert_close(m("C2"), 0.75 * 0.25, 1e-15, "π(C2)");
    assert_eq!(x(&c, &sol, "die"), 0.0, "fired once, at time 0");
    assert_eq!(x(&c, &sol, "live"), 0.0);
    assert_close(x(&c, &sol, "c12"), 0.75 * 0.75 * 2.0, 1e-15, "X(c12)");
}

#[test]
fn place_capacity_blocks_like_an_inhibitor_arc() {
    // M/M/1/K with the bound as the queue's capacity instead of an inhibitor
    // arc on `arrive`: the same chain.
    let (lambda, mu, k) = (1.3, 0.9, 5u32);
    let mut n = Net::new("capacity");
    let q = n.add_place("queue", 0u32);
    n.places[q.index()].capacity = Some(k);
    let arrive = n.add_timed("arrive", lambda);
    n.output(arrive, q);
    let serve = n.add_timed("serve", mu);
    n.input(q, serve);
    let p = birth_death(k, |_| lambda, |_| mu);
    check_queue(&n, &p, 1, |n| if n > 0 { mu } else { 0.0 }, "M/M/1/5 by capacity");
}

// ---------------------------------------------------------------------------
// Passing through forced vanishing markings (`ExploreParams::skip_forced`)
// ---------------------------------------------------------------------------

/// `A —t(1)→ X —x→ Y —y→ V`; from `V`, `left` (weight 1) to `L` or `right`
/// (weight 3) to `R`; `L —l(2)→ A`, `R —r(5)→ A`. `X` and `Y` are forced,
/// `V` offers a choice.
fn forced_chain() -> Net {
    let mut n = Net::new("forced chain");
    let [a, px, py, v, l, r] = ["A", "X", "Y", "V", "L", "R"].map(|p| n.add_place(p, u32::from(p == "A")));
    let t = n.add_timed("t", 1.0);
    arcs(&mut n, t, &[a], &[px]);
    let t = n.add_immediate("x", 1.0, 1);
    arcs(&mut n, t, &[px], &[py]);
    let t = n.add_immediate("y", 1.0, 1);
    arcs(&mut n, t, &[py], &[v]);
    let t = n.add_immediate("left", 1.0, 1);
    arcs(&mut n, t, &[v], &[l]);
    let t = n.add_immediate("right", 3.0, 1);
    arcs(&mut n, t, &[v], &[r]);
    let t = n.add_timed("l", 2.0);
    arcs(&mut n, t, &[l], &[a]);
    let t = n.add_timed("r", 5.0);
    arcs(&mut n, t, &[r], &[a]);
    n
}

const SKIP: ExploreParams = ExploreParams {
    max_states: usize::MAX,
    max_memory: u64::MAX,
    skip_forced: true,
    forced_context: Vec::new(),
};

#[test]
fn skipping_forced_markings_keeps_the_chain() {
    let g = forced_chain().instantiate(&Params::new()).unwrap();
    let full = ReachabilityGraph::explore(&g, &ExploreParams::default()).unwrap();
    let skipped = ReachabilityGraph::explore(&g, &SKIP).unwrap();
    // X and Y are not stored; V (a choice) is.
    assert_eq!((full.num_tangible(), full.num_vanishing()), (3, 3));
    assert_eq!((skipped.num_tangible(), skipped.num_vanishing()), (3, 1));
    let (c1, c2) = (
        CompiledGspn::build(&g, &ExploreParams::default()).unwrap(),
        CompiledGspn::build(&g, &SKIP).unwrap(),
    );
    let (s1, s2) = (solve(&c1), solve(&c2));
    // Cycle A (mean 1) → L (1/4, mean 1/2) or R (3/4, mean 1/5): mean 1 + 1/8 + 3/20.
    let cycle = 1.0 + 0.125 + 0.15;
    for (c, s) in [(&c1, &s1), (&c2, &s2)] {
        assert_close(pi_where(c, s, |m| m[0] == 1), 1.0 / cycle, 1e-12, "π(A)");
        assert_close(pi_where(c, s, |m| m[4] == 1), 0.125 / cycle, 1e-12, "π(L)");
        assert_close(x(c, s, "t"), 1.0 / cycle, 1e-12, "X(t)");
        assert_close(x(c, s, "left"), 0.25 / cycle, 1e-12, "X(left)");
    }
}

#[test]
fn skipping_forced_markings_still_finds_a_timeless_trap() {
    // X and Y each enable one immediate transition: a forced loop, cut at
    // the hop limit and stored there, so the elimination names the trap.
    let g = ping_pong(None).instantiate(&Params::new()).unwrap();
    match CompiledGspn::build(&g, &SKIP) {
        Err(Error::TimelessTrap { .. }) => {}
        other => panic!("expected a timeless trap, got {other:?}"),
    }
}
