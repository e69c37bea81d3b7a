//! The simulator against nets solvable by hand: M/M/1/K, a weighted random
//! choice, server semantics, dead markings, timeless traps; determinism and
//! parameter checks.

use petri::simulation::{Estimate, SimParams, SimResult, simulate};
use petri::{ArcKind, CompiledExpr, Error, Expr, Gspn, Net, Params, Servers};

fn instantiate(net: &Net) -> (Gspn, Vec<f64>) {
    let g = net.instantiate(&Params::new()).unwrap();
    let r = g.rates(&Params::new(), None).unwrap();
    (g, r)
}

fn measure(g: &Gspn, text: &str) -> (String, CompiledExpr) {
    let e = Expr::parse(text)
        .unwrap()
        .compile(&|n| g.place(n).ok().map(|p| p.index()), &|_| None)
        .unwrap();
    (text.to_string(), e)
}

/// `x` within `k` half-widths of the estimate (4 at 95 % keeps fixed-seed
/// tests far from the edge while still catching a wrong answer).
fn near(e: &Estimate, x: f64, k: f64, what: &str) {
    assert!(
        (e.mean - x).abs() <= k * e.half_width,
        "{what}: estimate {} ± {} does not contain {x} within {k} half-widths",
        e.mean,
        e.half_width
    );
}

fn precise(e: &Estimate, x: f64, rel: f64, what: &str) {
    assert!(
        e.half_width < rel * x.abs(),
        "{what}: half-width {} is not below {rel} of {x}",
        e.half_width
    );
}

const LAMBDA: f64 = 1.0;
const MU: f64 = 2.0;
const K: u32 = 5;

/// M/M/1/K: arrivals blocked by an inhibitor arc of multiplicity K.
fn mm1k() -> Net {
    let mut n = Net::new("mm1k");
    let q = n.add_place("queue", 0u32);
    let arrive = n.add_timed("arrive", LAMBDA);
    let serve = n.add_timed("serve", MU);
    n.output(arrive, q);
    n.add_arc(ArcKind::Inhibitor, q, arrive, K);
    n.input(q, serve);
    n
}

/// `P{n}` of M/M/1/K.
fn mm1k_distribution() -> Vec<f64> {
    let rho: f64 = LAMBDA / MU;
    let norm: f64 = (0..=K).map(|n| rho.powi(n as i32)).sum();
    (0..=K).map(|n| rho.powi(n as i32) / norm).collect()
}

#[test]
fn mm1k_estimates_contain_the_closed_forms() {
    let net = mm1k();
    let (g, r) = instantiate(&net);
    let pn = mm1k_distribution();
    let mut measures: Vec<_> = (0..=K).map(|n| measure(&g, &format!("#queue = {n}"))).collect();
    measures.push(measure(&g, "#queue > 0 and #queue < 5"));
    let params = SimParams {
        warmup: 100.0,
        seed: 42,
        ..SimParams::new(400_000.0)
    };
    let res = simulate(&g, &r, &measures, &params).unwrap();

    let mean: f64 = pn.iter().enumerate().map(|(n, p)| n as f64 * p).sum();
    let busy = 1.0 - pn[0];
    let throughput = MU * busy;
    assert!((throughput - LAMBDA * (1.0 - pn[K as usize])).abs() < 1e-12);

    let queue = res.place("queue").unwrap();
    near(queue, mean, 4.0, "mean queue length");
    precise(queue, mean, 0.02, "mean queue length");
    let nonempty = &res.prob_nonempty[0];
    near(nonempty, busy, 4.0, "P{n > 0}");
    precise(nonempty, busy, 0.02, "P{n > 0}");
    for name in ["serve", "arrive"] {
        let x = res.throughput(name).unwrap();
        near(x, throughput, 4.0, name);
        precise(x, throughput, 0.02, name);
    }
    for (n, p) in pn.iter().enumerate() {
        let e = res.measure(&format!("#queue = {n}")).unwrap();
        near(e, *p, 4.0, &format!("P{{n = {n}}}"));
    }
    near(
        res.measure("#queue > 0 and #queue < 5").unwrap(),
        busy - pn[K as usize],
        4.0,
        "P{0 < n < K}",
    );

    assert_eq!(res.replications, 1);
    assert_eq!(res.absorbed_runs, 0);
    assert_eq!(queue.batches, 20);
    assert_eq!(res.simulated_time, 400_000.0);
    assert_eq!(res.measured_time, 400_000.0 - 100.0);
    // About λ(1 − P_K) + μ P{n>0} firings per time unit.
    let rate = 2.0 * throughput;
    assert!((res.events as f64 / res.simulated_time - rate).abs() < 0.02 * rate);
}

#[test]
fn mm1k_with_independent_replications() {
    let (g, r) = instantiate(&mm1k());
    let pn = mm1k_distribution();
    let params = SimParams {
        warmup: 50.0,
        replications: 30,
        seed: 9,
        ..SimParams::new(5_000.0)
    };
    let res = simulate(&g, &r, &[], &params).unwrap();
    assert_eq!(res.replications, 30);
    assert_eq!(res.places[0].batches, 30);
    assert_eq!(res.simulated_time, 30.0 * 5_000.0);
    near(&res.prob_nonempty[0], 1.0 - pn[0], 4.0, "P{n > 0}");
    near(
        res.throughput("serve").unwrap(),
        MU * (1.0 - pn[0]),
        4.0,
        "X(serve)",
    );
}

/// `a` —t (rate 1)→ `b`; from `b` immediate `left` (weight 1) to `c` or
/// `right` (weight 3) to `d`; back to `a` at rate 2 from either.
fn choice() -> Net {
    let mut n = Net::new("choice");
    let a = n.add_place("a", 1u32);
    let b = n.add_place("b", 0u32);
    let c = n.add_place("c", 0u32);
    let d = n.add_place("d", 0u32);
    let t = n.add_timed("t", 1.0);
    n.input(a, t);
    n.output(t, b);
    let left = n.add_immediate("left", 1.0, 1);
    let right = n.add_immediate("right", 3.0, 1);
    n.input(b, left);
    n.output(left, c);
    n.input(b, right);
    n.output(right, d);
    let back_c = n.add_timed("back_c", 2.0);
    let back_d = n.add_timed("back_d", 2.0);
    n.input(c, back_c);
    n.output(back_c, a);
    n.input(d, back_d);
    n.output(back_d, a);
    n
}

#[test]
fn immediate_choice_follows_the_weights() {
    let (g, r) = instantiate(&choice());
    let measures = [measure(&g, "#c = 1 or #d = 1")];
    let params = SimParams {
        seed: 1,
        ..SimParams::new(200_000.0)
    };
    let res = simulate(&g, &r, &measures, &params).unwrap();
    // A cycle lasts 1/1 + 1/2 = 3/2 on average: X(t) = 2/3, split 1:3.
    let x = |n: &str| *res.throughput(n).unwrap();
    near(&x("t"), 2.0 / 3.0, 4.0, "X(t)");
    near(&x("left"), 1.0 / 6.0, 4.0, "X(left)");
    near(&x("right"), 1.0 / 2.0, 4.0, "X(right)");
    precise(&x("right"), 0.5, 0.02, "X(right)");
    let ratio = x("right").mean / x("left").mean;
    assert!((ratio - 3.0).abs() < 0.1, "right/left = {ratio}");
    // Every firing of t is followed at once by left or right.
    let flow = x("left").mean + x("right").mean - x("t").mean;
    assert!(flow.abs() < 1e-12 + 20.0 / 200_000.0, "{flow}");
    near(&x("back_c"), 1.0 / 6.0, 4.0, "X(back_c)");
    // Vanishing marking b: no time spent there.
    assert_eq!(res.place("b").unwrap().mean, 0.0);
    assert_eq!(res.place("b").unwrap().half_width, 0.0);
    near(res.place("a").unwrap(), 2.0 / 3.0, 4.0, "E[#a]");
    near(res.place("c").unwrap(), 1.0 / 12.0, 4.0, "E[#c]");
    near(res.place("d").unwrap(), 1.0 / 4.0, 4.0, "E[#d]");
    near(
        res.measure("#c = 1 or #d = 1").unwrap(),
        1.0 / 3.0,
        4.0,
        "P{c or d}",
    );
}

#[test]
fn lower_priority_immediate_transitions_never_fire_when_pre_empted() {
    let mut n = choice();
    let b = n.place_id("b").unwrap();
    let a = n.place_id("a").unwrap();
    let urgent = n.add_immediate("urgent", 0.001, 2);
    n.input(b, urgent);
    n.output(urgent, a);
    let (g, r) = instantiate(&n);
    let res = simulate(&g, &r, &[], &SimParams::new(1_000.0)).unwrap();
    assert_eq!(res.throughput("left").unwrap().mean, 0.0);
    assert_eq!(res.throughput("right").unwrap().mean, 0.0);
    assert!(res.throughput("urgent").unwrap().mean > 0.5);
    assert!((res.place("a").unwrap().mean - 1.0).abs() < 1e-12);
}

#[test]
fn server_semantics_scale_the_rates() {
    // N independent two-state tokens: idle —go (λ)→ busy —back (μ)→ idle.
    // Infinite servers on both: E[#busy] = N λ / (λ + μ).
    // One server on `back` instead: a closed M/M/1 (finite source) queue.
    for servers in [Servers::Infinite, Servers::K(2)] {
        let mut n = Net::new("servers");
        let idle = n.add_place("idle", 6u32);
        let busy = n.add_place("busy", 0u32);
        let go = n.add_timed("go", 0.5);
        let back = n.add_timed("back", 1.5);
        n.set_servers(go, Servers::Infinite);
        n.set_servers(back, servers);
        n.input(idle, go);
        n.output(go, busy);
        n.input(busy, back);
        n.output(back, idle);
        let (g, r) = instantiate(&n);
        let params = SimParams {
            warmup: 20.0,
            seed: 5,
            ..SimParams::new(100_000.0)
        };
        let res = simulate(&g, &r, &[], &params).unwrap();
        // Birth–death chain on k = #busy: birth (6−k)·0.5, death min(k, c)·1.5.
        let c = match servers {
            Servers::K(c) => c as usize,
            _ => 6,
        };
        let mut p = vec![1.0f64];
        for k in 0..6 {
            let birth = (6 - k) as f64 * 0.5;
            let death = (k + 1).min(c) as f64 * 1.5;
            p.push(p[k] * birth / death);
        }
        let norm: f64 = p.iter().sum();
        let mean: f64 = p.iter().enumerate().map(|(k, x)| k as f64 * x / norm).sum();
        if c == 6 {
            assert!((mean - 6.0 * 0.5 / 2.0).abs() < 1e-12);
        }
        near(
            res.place("busy").unwrap(),
            mean,
            4.0,
            &format!("E[#busy], {servers:?}"),
        );
        near(res.place("idle").unwrap(), 6.0 - mean, 4.0, "E[#idle]");
        let x_back: f64 = p
            .iter()
            .enumerate()
            .map(|(k, x)| k.min(c) as f64 * 1.5 * x / norm)
            .sum();
        near(res.throughput("back").unwrap(), x_back, 4.0, "X(back)");
    }
}

/// `a` —t1→ `b` —t2→ `c`, and nothing leaves `c`.
fn absorbing() -> Net {
    let mut n = Net::new("absorbing");
    let a = n.add_place("a", 1u32);
    let b = n.add_place("b", 0u32);
    let c = n.add_place("c", 0u32);
    let t1 = n.add_timed("t1", 1.0);
    let t2 = n.add_timed("t2", 1.0);
    n.input(a, t1);
    n.output(t1, b);
    n.input(b, t2);
    n.output(t2, c);
    n
}

#[test]
fn a_dead_marking_holds_to_the_end() {
    let (g, r) = instantiate(&absorbing());
    let measures = [measure(&g, "#c = 1")];
    // With a warmup the dead marking is reached before measuring (with
    // probability 1 − 101 e^{−100}): the estimates are exact.
    let params = SimParams {
        warmup: 100.0,
        ..SimParams::new(1_000.0)
    };
    let res = simulate(&g, &r, &measures, &params).unwrap();
    assert_eq!(res.absorbed_runs, 1);
    assert_eq!(res.events, 2);
    for x in &res.throughputs {
        assert_eq!((x.mean, x.half_width), (0.0, 0.0));
    }
    let expect = [0.0, 0.0, 1.0];
    for (p, &e) in expect.iter().enumerate() {
        assert_eq!(res.places[p].mean, e);
        assert_eq!(res.places[p].half_width, 0.0);
        assert_eq!(res.prob_nonempty[p].mean, e);
    }
    assert_eq!(res.measure("#c = 1").unwrap().mean, 1.0);

    // Without warmup: two firings in [0, 1000], the long-run values ≈ those
    // of the dead marking.
    let res = simulate(&g, &r, &measures, &SimParams::new(1_000.0)).unwrap();
    for x in &res.throughputs {
        assert!((x.mean - 1.0 / 1_000.0).abs() < 1e-15, "{}", x.mean);
    }
    assert!(res.place("c").unwrap().mean > 0.95);
    assert!(res.place("a").unwrap().mean < 0.05);
}

#[test]
fn an_initially_dead_net_is_fine() {
    let mut n = Net::new("dead");
    let p = n.add_place("p", 3u32);
    let t = n.add_timed("t", 1.0);
    n.add_arc(ArcKind::Inhibitor, p, t, 1u32);
    let (g, r) = instantiate(&n);
    let res = simulate(&g, &r, &[], &SimParams::new(10.0)).unwrap();
    assert_eq!(res.events, 0);
    assert_eq!(res.places[0].mean, 3.0);
    assert_eq!(res.throughputs[0].mean, 0.0);
    assert_eq!(res.absorbed_runs, 1);
}

#[test]
fn replications_estimate_the_mixture_over_dead_markings() {
    // From `start`, a timed step then a 1:3 choice into two dead markings.
    // The long-run probability of `right` is 3/4; one batch-means run would
    // give 0 or 1.
    let mut n = Net::new("fork");
    let s = n.add_place("start", 1u32);
    let m = n.add_place("mid", 0u32);
    let l = n.add_place("left", 0u32);
    let rr = n.add_place("right", 0u32);
    let go = n.add_timed("go", 1.0);
    n.input(s, go);
    n.output(go, m);
    let tl = n.add_immediate("to_left", 1.0, 1);
    let tr = n.add_immediate("to_right", 3.0, 1);
    n.input(m, tl);
    n.output(tl, l);
    n.input(m, tr);
    n.output(tr, rr);
    let (g, r) = instantiate(&n);
    let params = SimParams {
        warmup: 50.0,
        replications: 2_000,
        seed: 11,
        ..SimParams::new(100.0)
    };
    let res = simulate(&g, &r, &[], &params).unwrap();
    assert_eq!(res.absorbed_runs, 2_000);
    near(res.place("right").unwrap(), 0.75, 4.0, "P{right}");
    near(res.place("left").unwrap(), 0.25, 4.0, "P{left}");
    let sum = res.place("right").unwrap().mean + res.place("left").unwrap().mean;
    assert!((sum - 1.0).abs() < 1e-12);
}

fn ping_pong(after_timed: bool) -> Net {
    let mut n = Net::new("trap");
    let a = n.add_place("a", 0u32);
    let b = n.add_place("b", 0u32);
    let x = n.add_immediate("x", 1.0, 1);
    let y = n.add_immediate("y", 1.0, 1);
    n.input(a, x);
    n.output(x, b);
    n.input(b, y);
    n.output(y, a);
    if after_timed {
        let s = n.add_place("s", 1u32);
        let t = n.add_timed("t", 1.0);
        n.input(s, t);
        n.output(t, a);
    } else {
        n.places[a.index()].initial = Expr::Num(1.0);
    }
    n
}

#[test]
fn a_timeless_trap_is_an_error_not_a_hang() {
    for after_timed in [false, true] {
        let (g, r) = instantiate(&ping_pong(after_timed));
        for chain in [1_000, SimParams::default().max_immediate_chain] {
            let params = SimParams {
                max_immediate_chain: chain,
                warmup: if after_timed { 5.0 } else { 0.0 },
                ..SimParams::new(10.0)
            };
            match simulate(&g, &r, &[], &params) {
                Err(Error::TimelessTrap { count, markings }) => {
                    assert_eq!(count, 2, "{markings}");
                    assert!(
                        markings.starts_with("a; b") || markings.starts_with("b; a"),
                        "{markings}"
                    );
                }
                other => panic!("expected a timeless trap, got {other:?}"),
            }
        }
    }
}

#[test]
fn a_long_but_finite_immediate_chain_is_not_a_trap() {
    // 50 tokens moved one by one by an immediate transition: 50 firings in a row.
    let mut n = Net::new("chain");
    let a = n.add_place("a", 0u32);
    let b = n.add_place("b", 0u32);
    let fill = n.add_timed("fill", 1.0);
    n.add_arc(ArcKind::Output, a, fill, 50u32);
    n.add_arc(ArcKind::Inhibitor, a, fill, 1u32);
    let mv = n.add_immediate("move", 1.0, 1);
    n.input(a, mv);
    n.output(mv, b);
    let (g, r) = instantiate(&n);
    let params = SimParams {
        max_immediate_chain: 50,
        ..SimParams::new(100.0)
    };
    let res = simulate(&g, &r, &[], &params).unwrap();
    let x = res.throughput("move").unwrap().mean;
    assert!((x - 50.0 * res.throughput("fill").unwrap().mean).abs() < 1e-9);
    let params = SimParams {
        max_immediate_chain: 49,
        ..params
    };
    assert!(matches!(
        simulate(&g, &r, &[], &params),
        Err(Error::TimelessTrap { count: 1, .. })
    ));
}

#[test]
fn the_wall_time_bound_stops_an_endless_run_with_a_projection() {
    // Issue 17: `--time 1e300` ran with no end in sight.
    let (g, r) = instantiate(&mm1k());
    let params = SimParams {
        max_wall_s: Some(0.05),
        ..SimParams::new(1e300)
    };
    let start = std::time::Instant::now();
    match simulate(&g, &r, &[], &params) {
        Err(Error::WallTimeLimit {
            limit_s,
            events,
            time,
            run,
            end_time,
            projected,
        }) => {
            assert_eq!((limit_s, run, end_time), (0.05, 1, 1e300));
            assert!(events > 0 && time > 0.0);
            assert!(projected > 1e290, "{projected}");
        }
        other => panic!("expected the wall-time limit, got {other:?}"),
    }
    assert!(start.elapsed().as_secs_f64() < 5.0);
    let bad = SimParams {
        max_wall_s: Some(0.0),
        ..SimParams::new(1.0)
    };
    assert!(matches!(
        simulate(&g, &r, &[], &bad),
        Err(Error::InvalidValue { .. })
    ));
}

#[test]
fn the_observer_sees_progress_and_can_interrupt() {
    let (g, r) = instantiate(&mm1k());
    let params = SimParams::new(1e300);
    let mut seen = Vec::new();
    let result = petri::simulate_observed(&g, &r, &[], &params, &mut |p| {
        seen.push(*p);
        if seen.len() == 3 {
            std::ops::ControlFlow::Break(())
        } else {
            std::ops::ControlFlow::Continue(())
        }
    });
    match result {
        Err(Error::Interrupted { events, run, .. }) => {
            assert_eq!(events, 3 * petri::simulation::CHECK_EVERY);
            assert_eq!(run, 1);
        }
        other => panic!("expected an interruption, got {other:?}"),
    }
    assert_eq!(seen.len(), 3);
    assert!(
        seen.windows(2)
            .all(|w| w[0].time < w[1].time && w[0].events < w[1].events)
    );
    assert!(seen.iter().all(|p| (0.0..=1e-280).contains(&p.fraction())));
    // A run that ends: same results as without an observer.
    let params = SimParams {
        seed: 4,
        ..SimParams::new(2e5)
    };
    let mut calls = 0;
    let observed = petri::simulate_observed(&g, &r, &[], &params, &mut |p| {
        calls += 1;
        assert!(p.fraction() > 0.0 && p.fraction() <= 1.0);
        std::ops::ControlFlow::Continue(())
    })
    .unwrap();
    assert_eq!(observed, simulate(&g, &r, &[], &params).unwrap());
    assert!(
        calls as u64 == observed.events / petri::simulation::CHECK_EVERY,
        "{calls}"
    );
}

#[test]
fn the_event_cap_stops_the_run() {
    let (g, r) = instantiate(&mm1k());
    let params = SimParams {
        max_events: 1_000,
        ..SimParams::new(1e6)
    };
    match simulate(&g, &r, &[], &params) {
        Err(Error::EventLimit {
            limit,
            time,
            end_time,
        }) => {
            assert_eq!(limit, 1_000);
            assert!(time > 0.0 && time < end_time);
        }
        other => panic!("expected the event limit, got {other:?}"),
    }
}

fn run(seed: u64, replications: usize) -> SimResult {
    let (g, r) = instantiate(&choice());
    let measures = [measure(&g, "#a = 1")];
    let params = SimParams {
        seed,
        replications,
        warmup: 1.0,
        ..SimParams::new(2_000.0)
    };
    simulate(&g, &r, &measures, &params).unwrap()
}

#[test]
fn same_seed_same_result_bit_for_bit() {
    for reps in [1, 5] {
        let a = run(123, reps);
        let b = run(123, reps);
        assert_eq!(a, b);
        let bits = |r: &SimResult| -> Vec<u64> {
            r.places
                .iter()
                .chain(&r.prob_nonempty)
                .chain(&r.throughputs)
                .chain(r.measures.iter().map(|(_, e)| e))
                .flat_map(|e| [e.mean.to_bits(), e.half_width.to_bits()])
                .collect()
        };
        assert_eq!(bits(&a), bits(&b));
        let c = run(124, reps);
        assert_ne!(a, c);
        assert_ne!(a.places[0].mean, c.places[0].mean);
    }
}

#[test]
fn results_serialise_to_json() {
    let res = run(1, 1);
    let json = serde_json::to_value(&res).unwrap();
    assert_eq!(json["places"][0]["batches"], 20);
    assert!(json["throughputs"][0]["half_width"].as_f64().unwrap() > 0.0);
    assert_eq!(json["measures"][0][0], "#a = 1");
    assert_eq!(json["transition_names"][1], "left");
}

#[test]
fn invalid_parameters_are_errors() {
    let (g, r) = instantiate(&mm1k());
    let ok = SimParams::new(10.0);
    assert!(simulate(&g, &r, &[], &ok).is_ok());
    let bad = [
        SimParams::default(),
        SimParams::new(-1.0),
        SimParams::new(f64::NAN),
        SimParams::new(f64::INFINITY),
        SimParams {
            warmup: 10.0,
            ..ok.clone()
        },
        SimParams {
            warmup: 11.0,
            ..ok.clone()
        },
        SimParams {
            warmup: -1.0,
            ..ok.clone()
        },
        SimParams {
            warmup: f64::NAN,
            ..ok.clone()
        },
        SimParams {
            batches: 0,
            ..ok.clone()
        },
        SimParams {
            batches: 1,
            ..ok.clone()
        },
        SimParams {
            batches: usize::MAX,
            ..ok.clone()
        },
        SimParams {
            confidence: 0.0,
            ..ok.clone()
        },
        SimParams {
            confidence: 1.0,
            ..ok.clone()
        },
        SimParams {
            confidence: 95.0,
            ..ok.clone()
        },
        SimParams {
            confidence: f64::NAN,
            ..ok.clone()
        },
        SimParams {
            replications: 0,
            ..ok.clone()
        },
        SimParams {
            replications: usize::MAX,
            ..ok.clone()
        },
        SimParams {
            max_events: 0,
            ..ok.clone()
        },
        SimParams {
            max_immediate_chain: 0,
            ..ok.clone()
        },
        // Batch boundaries that coincide in floating point.
        SimParams {
            warmup: 1e17,
            batches: 1_000,
            ..SimParams::new(1e17 + 64.0)
        },
    ];
    for p in &bad {
        let err = simulate(&g, &r, &[], p).unwrap_err();
        assert!(matches!(err, Error::InvalidValue { .. }), "{p:?}: {err}");
        assert!(p.validate().is_err());
    }
    // With replications, `batches` is not used.
    assert!(
        simulate(
            &g,
            &r,
            &[],
            &SimParams {
                replications: 2,
                batches: 0,
                ..ok.clone()
            }
        )
        .is_ok()
    );

    // Rates: one per transition, finite and > 0 for timed ones.
    let err = simulate(&g, &r[..1], &[], &ok).unwrap_err();
    assert!(matches!(err, Error::Invalid(_)), "{err}");
    assert!(simulate(&g, &[1.0, 2.0, 3.0], &[], &ok).is_err());
    for v in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let err = simulate(&g, &[v, 2.0], &[], &ok).unwrap_err();
        assert!(matches!(err, Error::InvalidValue { .. }), "{err}");
        assert!(err.to_string().contains("arrive"), "{err}");
    }
    // Entries of immediate transitions are ignored.
    let (g, mut r) = instantiate(&choice());
    r[g.transition("left").unwrap().index()] = f64::NAN;
    assert!(simulate(&g, &r, &[], &ok).is_ok());
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]

    /// Whatever the parameters, a result or an error, never a panic; valid
    /// results have finite estimates and batches that add up.
    #[test]
    fn no_panics_on_any_parameters(
        end in proptest::prelude::prop_oneof![-1.0f64..50.0, proptest::prelude::Just(f64::NAN)],
        warmup in -1.0f64..60.0,
        batches in 0usize..40,
        replications in 0usize..4,
        confidence in -0.5f64..1.5,
        seed in proptest::prelude::any::<u64>(),
        max_chain in 0u64..3,
        max_wall_s in proptest::option::of(proptest::prelude::prop_oneof![-1.0f64..100.0, proptest::prelude::Just(f64::NAN)]),
    ) {
        let (g, r) = instantiate(&choice());
        let measures = [measure(&g, "#a + #c")];
        let params = SimParams {
            end_time: end,
            warmup,
            batches,
            replications,
            confidence,
            seed,
            max_events: 1_000_000,
            max_immediate_chain: max_chain,
            max_wall_s,
        };
        if let Ok(res) = simulate(&g, &r, &measures, &params) {
            let tokens: f64 = res.places.iter().map(|e| e.mean).sum();
            proptest::prop_assert!((tokens - 1.0).abs() < 1e-9, "{}", tokens);
            for e in res.places.iter().chain(&res.throughputs) {
                proptest::prop_assert!(e.mean.is_finite() && e.half_width.is_finite() && e.half_width >= 0.0);
            }
            let m = res.measures[0].1.mean;
            let direct = res.places[0].mean + res.places[2].mean;
            proptest::prop_assert!((m - direct).abs() < 1e-9);
        }
    }
}

/// The tour-guide supervisor net of the spec, with `p` = 1 (AutoMove
/// hypothesis) or 0 (Contour): a weight-0 branch is left out.
fn supervisor(automove: bool) -> Net {
    let (l1, l2) = if automove {
        (0.001, 1000.0)
    } else {
        (1000.0, 0.001)
    };
    let lambda = [
        l1,
        l2,
        0.001,
        1000.0,
        0.001,
        1000.0,
        1.0 / 122.33,
        1.0 / 186.98,
        0.001,
        0.001,
        1000.0,
    ];
    let mut n = Net::new("supervisor");
    let p: Vec<_> = (0..9)
        .map(|i| n.add_place(format!("P{i}"), u32::from(matches!(i, 0 | 5 | 7))))
        .collect();
    let arcs = |t, ins: &[usize], outs: &[usize], inh: &[usize], n: &mut Net| {
        for &i in ins {
            n.input(p[i], t);
        }
        for &o in outs {
            n.output(t, p[o]);
        }
        for &h in inh {
            n.inhibitor(p[h], t);
        }
    };
    if automove {
        let t0 = n.add_immediate("t0", 1.0, 1);
        arcs(t0, &[0], &[1], &[], &mut n);
    } else {
        let t1 = n.add_immediate("t1", 1.0, 1);
        arcs(t1, &[0], &[2], &[], &mut n);
    }
    // (name, index into lambda, inputs, outputs, inhibitors)
    type Places = &'static [usize];
    let timed: [(&str, usize, Places, Places, Places); 12] = [
        ("t2", 0, &[1, 5], &[2, 5], &[]),
        ("t4", 1, &[2, 5], &[1, 5], &[]),
        ("t5", 2, &[5], &[6], &[3, 4]),
        ("t6", 3, &[6], &[5], &[3, 4]),
        ("t7", 4, &[7], &[8], &[3, 4]),
        ("t8", 5, &[8], &[7], &[3, 4]),
        ("t9", 6, &[1, 7], &[3, 7], &[]),
        ("t10", 7, &[2], &[3], &[]),
        ("t11", 8, &[1, 8], &[4, 8], &[]),
        ("t12", 9, &[2, 6], &[4, 6], &[]),
        ("t13", 10, &[3], &[0], &[]),
        ("t14", 10, &[4], &[0], &[]),
    ];
    for (name, rate, ins, outs, inh) in timed {
        let t = n.add_timed(name, lambda[rate]);
        arcs(t, ins, outs, inh, &mut n);
    }
    let t3 = n.add_immediate("t3", 1.0, 1);
    arcs(t3, &[1, 6], &[2, 6], &[], &mut n);
    n
}

#[test]
fn supervisor_net_gives_the_specified_decision_measures() {
    // Rates from 1e-3 to 1e3. Each task cycle is a completion (mean 1/λ)
    // then a re-initialisation (mean 1/1000); localizer and planner
    // excursions change the throughput by about 1e-6 relative.
    for (automove, t, lambda) in [(false, "t10", 1.0 / 186.98), (true, "t9", 1.0 / 122.33)] {
        let (g, r) = instantiate(&supervisor(automove));
        let params = SimParams {
            seed: 3,
            ..SimParams::new(4e6)
        };
        let res = simulate(&g, &r, &[], &params).unwrap();
        let f = res.throughput(t).unwrap();
        let expected = lambda / (1.0 + lambda / 1000.0);
        near(f, expected, 4.0, t);
        precise(f, expected, 0.02, t);
        if !automove {
            assert!((f.mean - 0.00535).abs() < 0.0001, "f_cont = {}", f.mean);
        }
    }
}
