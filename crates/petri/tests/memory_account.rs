//! The byte account of a compiled and solved chain
//! (`CompiledGspn::memory_account`): its stages add up, the memory guard's
//! estimate covers what was allocated without overstating it much, and the
//! outgoing rows an irreducible chain releases are still readable.

use petri::{CompiledGspn, ExploreParams, MarkingId, Params, ReachabilityGraph, SolveParams, families};

fn solved(n: u32) -> (CompiledGspn, petri::Solution) {
    let gspn = families::kanban(n).instantiate(&Params::new()).unwrap();
    let c = CompiledGspn::build(&gspn, &ExploreParams::default()).unwrap();
    let sol = c.solve(&Params::new(), None, &SolveParams::default()).unwrap();
    (c, sol)
}

#[test]
fn stages_add_up_and_the_guard_covers_the_peak() {
    for n in [3, 4] {
        let (c, sol) = solved(n);
        let acc = c.memory_account(Some(&sol));
        assert_eq!(acc.tangible_markings, c.num_tangible());
        let stage = |s: &str| -> u64 { acc.parts.iter().filter(|p| p.stage == s).map(|p| p.bytes).sum() };
        assert_eq!(acc.solve_bytes, stage("chain") + stage("solve"), "kanban {n}");
        assert!(
            acc.compile_bytes <= stage("chain") + stage("compile"),
            "kanban {n}"
        );
        assert_eq!(
            acc.peak_bytes,
            acc.generation_bytes.max(acc.compile_bytes).max(acc.solve_bytes)
        );
        for p in &acc.parts {
            let per = p.bytes as f64 / c.num_tangible() as f64;
            assert!((p.bytes_per_marking - per).abs() < 1e-9, "{}", p.component);
        }
        // BiCGSTAB's seven vectors.
        assert_eq!(sol.info.method, "bicgstab");
        assert_eq!(sol.info.vector_bytes, 7 * 8 * c.num_tangible() as u64);
        // The guard covers every stage, and overstates the peak by little
        // more than its fixed allowance (lengths, not capacities: 2 %).
        let est = acc.guard_estimate_bytes;
        assert!(
            est >= acc.solve_bytes && est >= acc.compile_bytes,
            "kanban {n}: estimate {est} below the account {acc:?}"
        );
        let peak = acc.compile_bytes.max(acc.solve_bytes).max(acc.generation_bytes);
        assert!(
            ((est - petri::FIXED_BYTES) as f64) < 1.02 * peak as f64,
            "kanban {n}: estimate {est} far above the account {acc:?}"
        );
    }
}

#[test]
fn an_irreducible_chain_keeps_one_direction_and_still_lists_its_entries() {
    let (c, sol) = solved(2);
    assert!(c.is_ergodic());
    let acc = c.memory_account(Some(&sol));
    assert!(acc.parts.iter().any(|p| p.stage == "compile" && p.bytes > 0));
    assert!(!acc.parts.iter().any(|p| p.component.contains("reducible")));
    // Without vanishing markings the chain's entries are the graph's edges.
    let gspn = families::kanban(2).instantiate(&Params::new()).unwrap();
    let rg = ReachabilityGraph::explore(&gspn, &ExploreParams::default()).unwrap();
    assert_eq!(rg.num_vanishing(), 0);
    for s in (0..c.num_tangible()).step_by(97) {
        let mut from_graph: Vec<(u32, u32, u64)> = rg
            .edges(MarkingId(s as u32))
            .map(|e| (e.target.0, e.transition.0, e.coeff.to_bits()))
            .collect();
        let mut from_chain: Vec<(u32, u32, u64)> =
            c.entries_from(s).map(|(d, t, k)| (d, t.0, k.to_bits())).collect();
        from_graph.sort_unstable();
        from_chain.sort_unstable();
        assert_eq!(from_graph, from_chain, "state {s}");
        assert!(!from_chain.is_empty());
    }
}
