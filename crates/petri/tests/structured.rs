//! The structured engine against the explicit one: same answers within
//! 1e-9 on every net whose structure is found, a reason otherwise.

use petri::{
    CompiledGspn, Error, ExploreParams, Expr, Gspn, Interrupt, Net, Params, SolveParams, StructuredGspn,
    StructuredParams, families,
};

fn compare(gspn: &Gspn, rates: &[f64], measures: &[&str]) {
    let explicit = CompiledGspn::build(gspn, &ExploreParams::default()).unwrap();
    let params = SolveParams::default();
    let sol = explicit.solve_rates(rates, &params).unwrap();
    let s = StructuredGspn::build(gspn, &StructuredParams::default(), Interrupt::NEVER).unwrap();
    assert_eq!(
        s.stats().tangible as usize,
        explicit.num_tangible(),
        "{}",
        gspn.name()
    );
    let ssol = s.solve_rates(rates, &params, Interrupt::NEVER).unwrap();
    assert!(
        ssol.info.residual <= params.tolerance,
        "{}: {:?}",
        gspn.name(),
        ssol.info
    );
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * a.abs().max(1.0);
    for (t, (a, b)) in sol.throughput.iter().zip(&ssol.throughput).enumerate() {
        assert!(
            close(*a, *b),
            "{}: throughput of {}: {a} vs {b}",
            gspn.name(),
            gspn.transition_names()[t]
        );
    }
    for (p, (a, b)) in sol.mean_tokens.iter().zip(&ssol.mean_tokens).enumerate() {
        assert!(
            close(*a, *b),
            "{}: E[#{}]: {a} vs {b}",
            gspn.name(),
            gspn.place_names()[p]
        );
    }
    for (p, (a, b)) in sol.prob_nonempty.iter().zip(&ssol.prob_nonempty).enumerate() {
        assert!(
            close(*a, *b),
            "{}: P(#{} > 0): {a} vs {b}",
            gspn.name(),
            gspn.place_names()[p]
        );
    }
    for m in measures {
        let e = Expr::parse(m).unwrap();
        let (a, b) = (explicit.measure(&sol, &e).unwrap(), s.measure(&ssol, &e).unwrap());
        assert!(close(a, b), "{}: {m}: {a} vs {b}", gspn.name());
    }
}

#[test]
fn kanban_one_to_four_agree_with_the_explicit_engine() {
    for n in 1..=4 {
        let g = families::kanban(n).instantiate(&Params::new()).unwrap();
        let rates = g.rates(&Params::new(), None).unwrap();
        compare(
            &g,
            &rates,
            &["#Pm1 >= 1", "#Pkan2 + #Pout4 * 2", "#Pm1 = 1 and #Pm4 > 0"],
        );
    }
}

#[test]
fn fms_with_immediate_transitions_agrees_with_the_explicit_engine() {
    for n in 1..=3 {
        let g = families::fms(n, false).instantiate(&Params::new()).unwrap();
        let rates = g.rates(&Params::new(), None).unwrap();
        compare(&g, &rates, &["#P1 >= 1", "#M2"]);
    }
}

/// Every MCC and GreatSPN net in `tests/data` (and the supervisor net):
/// where the structured engine applies, the explicit engine's answers
/// within 1e-9; where it does not, a reason — and never for an ergodic net
/// with a product structure whose chain the explicit engine solves.
#[test]
fn every_real_net_agrees_with_the_explicit_engine_or_gets_a_reason() {
    let data = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data");
    let nets: [(&str, Params); 11] = [
        ("mcc/TokenRing-PT-005.pnml", Params::new()),
        ("mcc/Philosophers-PT-000005.pnml", Params::new()),
        ("mcc/Philosophers-PT-000010.pnml", Params::new()),
        ("mcc/FMS-PT-00002.pnml", Params::new()),
        ("greatspn/2PhaseLockViolation.PNPRO", Params::new()),
        ("greatspn/Cycle_of_Four_Seasons.PNPRO", Params::new()),
        (
            "greatspn/FlexibleManufacturingSystem.PNPRO",
            Params::new().with("N", 3.0),
        ),
        ("greatspn/Philosophers4.PNPRO", Params::new()),
        ("greatspn/ReaderWriter.PNPRO", Params::new().with("K", 1.0)),
        ("greatspn/ReaderWriter.PNPRO", Params::new().with("K", 2.0)),
        ("../../../../models/supervisor.toml", Params::new()),
    ];
    let mut solved = Vec::new();
    for (file, params) in nets {
        let net = petri::io::read_file(format!("{data}/{file}")).unwrap();
        let g = net.instantiate(&params).unwrap();
        let rates = g.rates(&Params::new(), Some(1.0)).unwrap();
        match StructuredGspn::build(&g, &StructuredParams::default(), Interrupt::NEVER) {
            Ok(_) => {
                compare(&g, &rates, &[]);
                solved.push(file);
            }
            Err(Error::Unstructured { reason }) => {
                assert!(!reason.is_empty(), "{file}");
                println!("{file}: {reason}");
                let explicit = CompiledGspn::build(&g, &ExploreParams::default()).unwrap();
                assert!(!explicit.is_ergodic() || explicit.num_tangible() > 0, "{file}");
            }
            Err(e) => panic!("{file}: {e}"),
        }
    }
    println!("solved by the structured engine: {solved:?}");
    assert!(solved.len() >= 5, "{solved:?}");
}

/// Two places sharing 100,000 tokens (`A + B = N`): the decision diagram
/// of the reachable set would hold N nodes of up to N children (5·10⁹
/// entries, 20 GB) — the engine refuses it within its entry limit instead of
/// filling the memory, and says why.
#[test]
fn a_place_holding_many_tokens_is_refused_not_an_out_of_memory() {
    let mut net = Net::new("shared");
    let a = net.add_place("A", 100_000u32);
    let b = net.add_place("B", 0u32);
    for (name, from, to) in [("t", a, b), ("u", b, a)] {
        let t = net.add_timed(name, 1.0);
        net.input(from, t);
        net.output(t, to);
    }
    let g = net.instantiate(&Params::new()).unwrap();
    match StructuredGspn::build(&g, &StructuredParams::default(), Interrupt::NEVER) {
        Err(Error::Unstructured { reason }) => {
            assert!(reason.contains("decision-diagram entries"), "{reason}")
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn philosophers_deadlock_so_the_engine_says_why_it_does_not_apply() {
    let g = families::philosophers(4).instantiate(&Params::new()).unwrap();
    match StructuredGspn::build(&g, &StructuredParams::default(), Interrupt::NEVER) {
        Err(Error::Unstructured { reason }) => assert!(reason.contains("irreducible"), "{reason}"),
        other => panic!("{other:?}"),
    }
}

#[test]
fn polling_and_tandem_families_agree_with_the_explicit_engine() {
    for net in [
        families::polling(3, 3),
        families::polling(4, 2),
        families::tandem(3, 4),
        families::tandem(4, 5),
    ] {
        let g = net.instantiate(&Params::new()).unwrap();
        let rates = g.rates(&Params::new(), None).unwrap();
        let s = StructuredGspn::build(&g, &StructuredParams::default(), Interrupt::NEVER).unwrap();
        // Every combination of the components' local states is reachable.
        assert_eq!(s.stats().states, s.stats().tangible, "{}", g.name());
        compare(&g, &rates, &[]);
    }
}

#[test]
fn the_structured_solution_is_identical_on_one_two_and_three_threads() {
    let g = families::kanban(3).instantiate(&Params::new()).unwrap();
    let rates = g.rates(&Params::new(), None).unwrap();
    let s = StructuredGspn::build(&g, &StructuredParams::default(), Interrupt::NEVER).unwrap();
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            s.solve_rates(&rates, &SolveParams::default(), Interrupt::NEVER)
                .unwrap()
        })
    };
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    let one = run(1);
    for threads in [2, 3] {
        let other = run(threads);
        assert_eq!(one.info.iterations, other.info.iterations, "{threads} threads");
        assert!(
            bits(&one.throughput) == bits(&other.throughput),
            "{threads} threads"
        );
        assert!(
            bits(&one.mean_tokens) == bits(&other.mean_tokens),
            "{threads} threads"
        );
        assert_eq!(
            one.info.residual.to_bits(),
            other.info.residual.to_bits(),
            "{threads} threads"
        );
    }
}

/// Regression: the vanishing states' flows were left in the solver's
/// scaled time unit (the fastest rate, a power of two), so immediate
/// throughputs came out 2^k too small whenever a rate exceeded 2 (the
/// supervisor net's were 512 times too small).
#[test]
fn immediate_throughputs_are_in_the_model_time_unit_when_rates_are_fast() {
    let g = families::fms(2, false).instantiate(&Params::new()).unwrap();
    let rates: Vec<f64> = g
        .rates(&Params::new(), None)
        .unwrap()
        .iter()
        .map(|r| r * 1000.0)
        .collect();
    compare(&g, &rates, &["#P1 >= 1"]);
}

/// A net with decisions is a Markov decision process: the structured
/// engine must refuse it (treating the choice as a random switch would be a
/// wrong answer), saying why.
#[test]
fn nets_with_decisions_are_refused_with_the_reason() {
    let g = families::corridors_decide(2).instantiate(&Params::new()).unwrap();
    match StructuredGspn::build(&g, &StructuredParams::default(), Interrupt::NEVER) {
        Err(Error::Unstructured { reason }) => assert!(reason.contains("decision"), "{reason}"),
        Err(e) => panic!("another error: {e}"),
        Ok(_) => panic!("a net with decisions was accepted"),
    }
}
