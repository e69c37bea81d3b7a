//! Determinism: the same net compiled and solved twice gives bit-identical
//! results; re-solving a compiled net for new rates gives exactly what a
//! fresh compilation does; BiCGSTAB gives bit-identical results on 1, 2 or 3
//! threads (its blocks and reduction chunks have fixed sizes).

mod common;

use petri::{CompiledGspn, ExploreParams, Method, Net, ParamKind, Params, Solution, SolveParams, families};

fn compile(net: &Net) -> CompiledGspn {
    let g = net.instantiate(&Params::new()).unwrap();
    CompiledGspn::build(&g, &ExploreParams::default()).unwrap()
}

fn solve(c: &CompiledGspn, overrides: &Params, method: Method) -> Solution {
    let p = SolveParams {
        method,
        ..SolveParams::default()
    };
    c.solve(overrides, None, &p).unwrap()
}

fn bits(v: &[f64]) -> Vec<u64> {
    v.iter().map(|x| x.to_bits()).collect()
}

/// `π`, throughputs, mean token counts, `P{#p > 0}` and bottom
/// probabilities are equal bit for bit.
#[track_caller]
fn assert_identical(a: &Solution, b: &Solution, what: &str) {
    assert!(bits(&a.pi) == bits(&b.pi), "{what}: π differs");
    assert!(
        bits(&a.throughput) == bits(&b.throughput),
        "{what}: throughputs differ"
    );
    assert!(
        bits(&a.mean_tokens) == bits(&b.mean_tokens),
        "{what}: mean tokens differ"
    );
    assert!(
        bits(&a.prob_nonempty) == bits(&b.prob_nonempty),
        "{what}: P{{#p > 0}} differ"
    );
    assert!(
        bits(&a.bottom_probabilities) == bits(&b.bottom_probabilities),
        "{what}: bottom probabilities differ"
    );
    assert_eq!(a.info.iterations, b.info.iterations, "{what}: iterations differ");
}

fn random_net() -> Net {
    use proptest::strategy::{Strategy, ValueTree};
    let mut runner = proptest::test_runner::TestRunner::deterministic();
    common::spec(3, 3).new_tree(&mut runner).unwrap().current().net()
}

#[test]
fn compiling_and_solving_twice_gives_identical_results() {
    for net in [
        families::kanban(2),
        families::fms(2, false),
        families::robots_corridors(5, 2),
        families::philosophers(4),
        random_net(),
    ] {
        for method in [
            Method::Auto,
            Method::Direct,
            Method::GaussSeidel,
            Method::Bicgstab,
        ] {
            let what = format!("{}, {method:?}", net.name);
            let (c1, c2) = (compile(&net), compile(&net));
            assert_eq!(c1.num_tangible(), c2.num_tangible(), "{what}");
            for s in 0..c1.num_tangible() {
                assert_eq!(
                    c1.tangible_marking(s),
                    c2.tangible_marking(s),
                    "{what}: state {s}"
                );
            }
            let a = solve(&c1, &Params::new(), method);
            assert_identical(&a, &solve(&c2, &Params::new(), method), &what);
            assert_identical(
                &a,
                &solve(&c1, &Params::new(), method),
                &format!("{what}, re-solved"),
            );
        }
    }
}

#[test]
fn re_solving_for_new_rates_equals_compiling_with_them() {
    // The compiled structure does not depend on the rates: binding new ones
    // must give what a net built with them as defaults gives.
    let net = families::kanban(2);
    let c = compile(&net);
    let new = Params::new().with("in1", 0.3).with("back", 2.5).with("out4", 7.0);
    let mut rebuilt = net.clone();
    for (name, value) in &new.0 {
        rebuilt.set_param(name.clone(), Some(*value), ParamKind::Real);
    }
    let fresh = compile(&rebuilt);
    for method in [Method::Direct, Method::GaussSeidel, Method::Bicgstab] {
        let a = solve(&c, &new, method);
        let b = solve(&fresh, &Params::new(), method);
        assert_identical(&a, &b, &format!("kanban(2) re-solved, {method:?}"));
        // And the rates did change something.
        let old = solve(&c, &Params::new(), method);
        assert!(bits(&old.pi) != bits(&a.pi), "{method:?}: new rates, new π");
    }
}

/// Solves `c` with BiCGSTAB inside a rayon pool of 1 thread and pools of
/// each of `others` threads.
fn bicgstab_on_pools(c: &CompiledGspn, others: &[usize], what: &str) -> Solution {
    let solve_on = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| solve(c, &Params::new(), Method::Bicgstab))
    };
    let one = solve_on(1);
    assert_eq!(one.info.method, "bicgstab", "{what}");
    for &threads in others {
        assert_identical(
            &one,
            &solve_on(threads),
            &format!("{what}, 1 vs {threads} threads"),
        );
    }
    one
}

#[test]
fn bicgstab_is_bit_identical_on_any_number_of_threads() {
    // 58,400 states: one preconditioner block, but four reduction chunks.
    let c = compile(&families::kanban(3));
    assert_eq!(c.num_tangible(), 58_400);
    let sol = bicgstab_on_pools(&c, &[2, 3], "kanban(3)");
    assert!(sol.info.residual <= 1e-12, "{:?}", sol.info);
}

#[test]
fn bicgstab_with_two_preconditioner_blocks_is_bit_identical_on_any_number_of_threads() {
    // 454,475 states ≥ 2 × 2^16: two blocks solved in parallel. About 6 s in
    // the test profile, so 1 vs 2 threads only.
    let c = compile(&families::kanban(4));
    assert_eq!(c.num_tangible(), 454_475);
    assert!(c.num_tangible() >= petri::krylov::BLOCKS * petri::krylov::MIN_BLOCK);
    let sol = bicgstab_on_pools(&c, &[2], "kanban(4)");
    assert!(sol.info.residual <= 1e-12, "{:?}", sol.info);
}

/// Plain breadth-first search with a `HashMap`: the numbering the engine's
/// generator must reproduce (discovery order, successors in transition
/// order).
fn reference_bfs(g: &petri::Gspn) -> (Vec<Vec<u32>>, Vec<Vec<u32>>) {
    let mut index = std::collections::HashMap::new();
    let mut markings = vec![g.initial_marking().to_vec()];
    index.insert(markings[0].clone(), 0u32);
    let mut succ = Vec::new();
    let mut firable = Vec::new();
    let mut i = 0;
    while i < markings.len() {
        let m = markings[i].clone();
        g.firable(&m, &mut firable);
        let mut row = Vec::new();
        for &t in &firable {
            let mut s = m.clone();
            g.fire(t, &mut s).unwrap();
            let n = markings.len() as u32;
            let j = *index.entry(s.clone()).or_insert_with(|| {
                markings.push(s);
                n
            });
            row.push(j);
        }
        succ.push(row);
        i += 1;
    }
    (markings, succ)
}

#[test]
fn generation_on_one_and_two_threads_gives_breadth_first_numbering_and_identical_solutions() {
    // Kanban 3 (58,400 markings) passes the size from which rounds run in
    // parallel; FMS 2 has vanishing markings and widens its fields.
    for net in [families::kanban(3), families::fms(2, false)] {
        let g = net.instantiate(&Params::new()).unwrap();
        let (markings, succ) = reference_bfs(&g);
        let mut solutions = Vec::new();
        for threads in [1, 2] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let (rg, compiled) = pool.install(|| {
                let rg = petri::ReachabilityGraph::explore(&g, &ExploreParams::default()).unwrap();
                (rg.clone(), CompiledGspn::from_graph(g.clone(), rg).unwrap())
            });
            assert_eq!(rg.num_markings(), markings.len(), "{} on {threads}", net.name);
            for (i, m) in markings.iter().enumerate() {
                let id = petri::MarkingId(i as u32);
                assert_eq!(&rg.marking(id), m, "{} marking {i} on {threads}", net.name);
                let targets: Vec<u32> = rg.edges(id).map(|e| e.target.0).collect();
                assert_eq!(targets, succ[i], "{} edges of {i} on {threads}", net.name);
            }
            solutions.push(pool.install(|| solve(&compiled, &Params::new(), Method::Auto)));
        }
        assert_identical(&solutions[0], &solutions[1], &net.name);
    }
}

#[test]
fn widening_three_large_counters_into_one_word_terminates() {
    // Regression (Kanban 8 livelock): three places filled with 2²⁰ − 1
    // tokens each by independent transitions. With a bit of headroom each
    // the fields would take 3 × 21 bits + 3 control bits: two words, so the
    // layout is fitted; fitting to the stored markings alone took from one
    // field what a pending successor needed, and the round was widened and
    // fitted again forever. 2³ markings, in one word.
    let mut n = Net::new("three counters");
    for k in 0..3 {
        let control = n.add_place(format!("c{k}"), 1u32);
        let counter = n.add_place(format!("p{k}"), 0u32);
        let fill = n.add_timed(format!("fill{k}"), 1.0);
        n.input(control, fill);
        n.add_arc(petri::ArcKind::Output, counter, fill, (1u32 << 20) - 1);
    }
    let g = n.instantiate(&Params::new()).unwrap();
    // A livelock fails the test instead of hanging it.
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let rg = petri::ReachabilityGraph::explore(&g, &ExploreParams::default()).unwrap();
        let _ = tx.send((rg.num_markings(), rg.stats().words_per_marking));
    });
    let (markings, words) = rx
        .recv_timeout(std::time::Duration::from_secs(60))
        .expect("generation of 8 markings did not end within a minute");
    assert_eq!((markings, words), (8, 1));
}
