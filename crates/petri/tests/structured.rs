//! The structured engine against the explicit one: same answers within
//! 1e-9 on every net whose structure is found, a reason otherwise.

use petri::{
    CompiledGspn, Error, ExploreParams, Expr, Gspn, Interrupt, Params, SolveParams, StructuredGspn,
    StructuredParams, families,
};

fn compare(gspn: &Gspn, rates: &[f64], measures: &[&str]) {
    let explicit = CompiledGspn::build(gspn, &ExploreParams::default()).unwrap();
    let params = SolveParams::default();
    let sol = explicit.solve_rates(rates, &params).unwrap();
    let s = StructuredGspn::build(gspn, &StructuredParams::default(), Interrupt::NEVER).unwrap();
    assert_eq!(s.stats().tangible as usize, explicit.num_tangible(), "{}", gspn.name());
    let ssol = s.solve_rates(rates, &params, Interrupt::NEVER).unwrap();
    assert!(ssol.info.residual <= params.tolerance, "{}: {:?}", gspn.name(), ssol.info);
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * a.abs().max(1.0);
    for (t, (a, b)) in sol.throughput.iter().zip(&ssol.throughput).enumerate() {
        assert!(close(*a, *b), "{}: throughput of {}: {a} vs {b}", gspn.name(), gspn.transition_names()[t]);
    }
    for (p, (a, b)) in sol.mean_tokens.iter().zip(&ssol.mean_tokens).enumerate() {
        assert!(close(*a, *b), "{}: E[#{}]: {a} vs {b}", gspn.name(), gspn.place_names()[p]);
    }
    for (p, (a, b)) in sol.prob_nonempty.iter().zip(&ssol.prob_nonempty).enumerate() {
        assert!(close(*a, *b), "{}: P(#{} > 0): {a} vs {b}", gspn.name(), gspn.place_names()[p]);
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
        compare(&g, &rates, &["#Pm1 >= 1", "#Pkan2 + #Pout4 * 2", "#Pm1 = 1 and #Pm4 > 0"]);
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

#[test]
fn philosophers_deadlock_so_the_engine_says_why_it_does_not_apply() {
    let g = families::philosophers(4).instantiate(&Params::new()).unwrap();
    match StructuredGspn::build(&g, &StructuredParams::default(), Interrupt::NEVER) {
        Err(Error::Unstructured { reason }) => assert!(reason.contains("irreducible"), "{reason}"),
        other => panic!("{other:?}"),
    }
}
