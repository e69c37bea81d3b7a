//! Analysis of real files: the MCC nets' published state-space sizes, the
//! GreatSPN examples (identical results after format round trips), and the
//! shipped supervisor model with the decision measures of the spec.

use petri::io::{self, Format};
use petri::{
    CompiledGspn, ExploreParams, Expr, MarkingKind, Net, Params, ReachabilityGraph, Solution, SolveParams,
    families,
};

const GREATSPN: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/greatspn");
const MCC: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/mcc");
const SUPERVISOR: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../models/supervisor.toml");

fn read(path: &str) -> Net {
    io::read_file(path).unwrap_or_else(|e| panic!("{path}: {e}"))
}

// ---------------------------------------------------------------------------
// MCC nets
// ---------------------------------------------------------------------------

#[test]
fn mcc_nets_have_the_contests_reachable_marking_counts() {
    // The table of tests/data/README.md (the contest's reference values).
    for (file, markings, dead) in [
        ("TokenRing-PT-005.pnml", 166, 0),
        ("Philosophers-PT-000005.pnml", 243, 2),
        ("Philosophers-PT-000010.pnml", 59_049, 2),
        ("FMS-PT-00002.pnml", 3_444, 0),
    ] {
        let g = read(&format!("{MCC}/{file}"))
            .instantiate(&Params::new())
            .unwrap();
        let rg = ReachabilityGraph::explore(&g, &ExploreParams::default()).unwrap();
        assert_eq!(rg.num_markings(), markings, "{file}: reachable markings");
        assert_eq!(
            rg.num_vanishing(),
            0,
            "{file}: a P/T net has no immediate transitions"
        );
        assert_eq!(rg.dead_markings().len(), dead, "{file}: dead markings");
    }
}

#[test]
fn mcc_fms_file_and_the_fms_family_have_the_same_long_run_behaviour() {
    // Same places and transitions by name; all rates 1 (the file has none,
    // so the default rate applies). The two nets number their markings
    // differently, so compare what does not depend on the numbering.
    let file = CompiledGspn::build(
        &read(&format!("{MCC}/FMS-PT-00002.pnml"))
            .instantiate(&Params::new())
            .unwrap(),
        &ExploreParams::default(),
    )
    .unwrap();
    let family = CompiledGspn::build(
        &families::fms(2, true).instantiate(&Params::new()).unwrap(),
        &ExploreParams::default(),
    )
    .unwrap();
    assert_eq!(file.num_tangible(), family.num_tangible());
    let a = file
        .solve(&Params::new(), Some(1.0), &SolveParams::default())
        .unwrap();
    let b = family
        .solve(&Params::new(), None, &SolveParams::default())
        .unwrap();
    let (ga, gb) = (file.gspn(), family.gspn());
    for (p, name) in ga.place_names().iter().enumerate() {
        let q = gb.place(name).unwrap();
        let (x, y) = (a.mean_tokens[p], b.mean_tokens(q));
        assert!(
            (x - y).abs() <= 1e-10 * x.abs().max(1e-300),
            "E[#{name}]: file {x} vs family {y}"
        );
    }
    for (t, name) in ga.transition_names().iter().enumerate() {
        let u = gb.transition(name).unwrap();
        let (x, y) = (a.throughput[t], b.throughput(u));
        assert!(
            (x - y).abs() <= 1e-10 * x.abs(),
            "X({name}): file {x} vs family {y}"
        );
    }
}

// ---------------------------------------------------------------------------
// GreatSPN files
// ---------------------------------------------------------------------------

#[test]
fn philosophers4_is_absorbed_by_its_dead_marking() {
    let net = read(&format!("{GREATSPN}/Philosophers4.PNPRO"));
    let c = CompiledGspn::build(
        &net.instantiate(&Params::new()).unwrap(),
        &ExploreParams::default(),
    )
    .unwrap();
    assert!(!c.is_ergodic());
    let sol = c.solve(&Params::new(), None, &SolveParams::default()).unwrap();
    assert!(
        sol.throughput.iter().all(|&x| x == 0.0),
        "long-run throughputs are exactly 0: {:?}",
        sol.throughput
    );
    let g = c.gspn();
    let mut firable = Vec::new();
    let mut on_dead = 0.0;
    for (s, &p) in sol.pi.iter().enumerate() {
        let m = c.tangible_marking(s);
        let dead = g.firable(&m, &mut firable) == MarkingKind::Tangible && firable.is_empty();
        if dead {
            on_dead += p;
        } else {
            assert_eq!(
                p,
                0.0,
                "live marking {} has long-run weight",
                g.format_marking(&m)
            );
        }
    }
    assert!((on_dead - 1.0).abs() < 1e-12, "π on dead markings: {on_dead}");
    let bottoms = c.bottom_components();
    assert!(
        bottoms.iter().all(|b| b.len() == 1),
        "every bottom component is a dead marking"
    );
}

/// What an analysis gives, for comparing two versions of a net.
#[derive(Debug, PartialEq)]
struct Analysis {
    markings: usize,
    tangible: usize,
    vanishing: usize,
    pi: Vec<u64>,
    throughput: Vec<u64>,
    mean_tokens: Vec<u64>,
    bottom_probabilities: Vec<u64>,
}

fn analyse(net: &Net, params: &Params) -> (Analysis, Solution) {
    let g = net.instantiate(params).unwrap();
    let c = CompiledGspn::build(&g, &ExploreParams::default()).unwrap();
    let sol = c.solve(&Params::new(), None, &SolveParams::default()).unwrap();
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect();
    let explore = &c.stats().explore;
    let analysis = Analysis {
        markings: explore.markings,
        tangible: explore.tangible,
        vanishing: explore.vanishing,
        pi: bits(&sol.pi),
        throughput: bits(&sol.throughput),
        mean_tokens: bits(&sol.mean_tokens),
        bottom_probabilities: bits(&sol.bottom_probabilities),
    };
    (analysis, sol)
}

fn round_trip(net: &Net, via: Format) -> Net {
    let text = io::write_string(net, via).unwrap();
    let middle = io::read_str(&text, via, "middle").unwrap();
    let text = io::write_string(&middle, Format::Pnpro).unwrap();
    io::read_str(&text, Format::Pnpro, "back.PNPRO").unwrap()
}

#[test]
fn greatspn_files_round_trip_through_toml_and_pnml_with_identical_analysis_results() {
    for (file, params) in [
        ("2PhaseLockViolation.PNPRO", Params::new()),
        ("Cycle_of_Four_Seasons.PNPRO", Params::new()),
        ("FlexibleManufacturingSystem.PNPRO", Params::new().with("N", 3.0)),
        ("Philosophers4.PNPRO", Params::new()),
        // K = 1 (the file's last binding): with K ≥ 2 `is_read` consumes K
        // tokens and produces one, and the net runs dry.
        ("ReaderWriter.PNPRO", Params::new().with("K", 1.0)),
        ("ReaderWriter.PNPRO", Params::new().with("K", 2.0)),
    ] {
        let net = read(&format!("{GREATSPN}/{file}"));
        let (original, sol) = analyse(&net, &params);
        assert!(original.tangible > 1, "{file}: {original:?}");
        let total: f64 = sol.pi.iter().sum();
        assert!((total - 1.0).abs() < 1e-12, "{file}: Σπ = {total}");
        for via in [Format::Toml, Format::Pnml] {
            let (back, _) = analyse(&round_trip(&net, via), &params);
            assert!(
                back == original,
                "{file}: PNPRO → {via:?} → PNPRO changes the analysis:\n{back:?}\nvs\n{original:?}"
            );
        }
    }
}

#[test]
fn greatspn_examples_have_the_expected_long_run_behaviour() {
    // Ergodic with immediate transitions: FMS (N = 3), ReaderWriter (K = 1).
    for (file, params) in [
        ("FlexibleManufacturingSystem.PNPRO", Params::new().with("N", 3.0)),
        ("ReaderWriter.PNPRO", Params::new().with("K", 1.0)),
        ("Cycle_of_Four_Seasons.PNPRO", Params::new()),
    ] {
        let g = read(&format!("{GREATSPN}/{file}")).instantiate(&params).unwrap();
        let c = CompiledGspn::build(&g, &ExploreParams::default()).unwrap();
        assert!(c.is_ergodic(), "{file}");
        let sol = c.solve(&Params::new(), None, &SolveParams::default()).unwrap();
        assert!(
            sol.throughput.iter().all(|&x| x > 0.0),
            "{file}: every transition fires: {:?}",
            sol.throughput
        );
    }
    // The four seasons follow each other at rate 1 (the editor's default delay).
    let g = read(&format!("{GREATSPN}/Cycle_of_Four_Seasons.PNPRO"))
        .instantiate(&Params::new())
        .unwrap();
    let c = CompiledGspn::build(&g, &ExploreParams::default()).unwrap();
    let sol = c.solve(&Params::new(), None, &SolveParams::default()).unwrap();
    assert_eq!(c.num_tangible(), 4);
    for &p in &sol.pi {
        assert!((p - 0.25).abs() < 1e-15, "{:?}", sol.pi);
    }
}

// ---------------------------------------------------------------------------
// The supervisor model
// ---------------------------------------------------------------------------

const LAMBDA7: f64 = 1.0 / 122.33;
const LAMBDA8: f64 = 1.0 / 186.98;

/// The shipped model under a hypothesis: the branch of weight 0 left out
/// (`t1` for AutoMove with p = 1, `t0` for Contour with p = 0), compiled.
fn supervisor(automove: bool) -> CompiledGspn {
    let net = read(SUPERVISOR);
    let (drop, p) = if automove { ("t1", 1.0) } else { ("t0", 0.0) };
    let net = net.without_transition(drop).unwrap();
    let g = net.instantiate(&Params::new().with("p", p)).unwrap();
    CompiledGspn::build(&g, &ExploreParams::default()).unwrap()
}

fn hypothesis(automove: bool) -> Params {
    let (l1, l2) = if automove {
        (0.001, 1000.0)
    } else {
        (1000.0, 0.001)
    };
    Params::new()
        .with("lambda1", l1)
        .with("lambda2", l2)
        .with("lambda7", LAMBDA7)
        .with("lambda8", LAMBDA8)
}

fn probability(c: &CompiledGspn, sol: &Solution, condition: &str) -> f64 {
    c.measure(sol, &Expr::parse(condition).unwrap()).unwrap()
}

#[test]
fn supervisor_model_has_13_tangible_markings() {
    let shipped = read(SUPERVISOR);
    let c = CompiledGspn::build(
        &shipped.instantiate(&Params::new()).unwrap(),
        &ExploreParams::default(),
    )
    .unwrap();
    assert_eq!(c.num_tangible(), 13, "as shipped (p = 0.5)");
    assert_eq!(supervisor(true).num_tangible(), 13, "AutoMove hypothesis");
    assert_eq!(supervisor(false).num_tangible(), 13, "Contour hypothesis");
    assert!(c.is_ergodic());
}

#[test]
fn supervisor_decision_measures_match_the_spec() {
    let auto = supervisor(true);
    let sol_auto = auto
        .solve(&hypothesis(true), None, &SolveParams::default())
        .unwrap();
    let cont = supervisor(false);
    let sol_cont = cont
        .solve(&hypothesis(false), None, &SolveParams::default())
        .unwrap();
    let x = |c: &CompiledGspn, s: &Solution, t: &str| s.throughput(c.gspn().transition(t).unwrap());
    let f_auto = x(&auto, &sol_auto, "t9");
    let f_cont = x(&cont, &sol_cont, "t10");

    assert_eq!(
        format!("{f_cont:.2e}"),
        "5.35e-3",
        "f_cont = {f_cont} to three significant digits"
    );
    assert!(
        (f_auto - LAMBDA7).abs() <= 0.01 * LAMBDA7,
        "f_auto = {f_auto} within 1% of λ7 = {LAMBDA7}"
    );
    assert!(f_auto > f_cont, "select AutoMove: {f_auto} > {f_cont}");

    // Identities: X(t9) = λ7·P{P1 and P7 marked} (t9's inputs; P5 is not
    // one). The spec writes λ7·P{P1, P5, P7 marked}: the same number, since
    // a marking with P1 and P6 (localizer Warning) enables the immediate t3
    // and is vanishing, so in tangible markings P1 implies P5.
    let p17 = probability(&auto, &sol_auto, "#P1 = 1 and #P7 = 1");
    let p157 = probability(&auto, &sol_auto, "#P1 = 1 and #P5 = 1 and #P7 = 1");
    assert!(
        (f_auto - LAMBDA7 * p17).abs() <= 1e-12 * f_auto,
        "{f_auto} vs λ7·{p17}"
    );
    assert!(
        (f_auto - LAMBDA7 * p157).abs() <= 1e-12 * f_auto,
        "{f_auto} vs λ7·{p157}"
    );
    assert_eq!(probability(&auto, &sol_auto, "#P1 = 1 and #P6 = 1"), 0.0);
    let p2 = probability(&cont, &sol_cont, "#P2 = 1");
    assert!(
        (f_cont - LAMBDA8 * p2).abs() <= 1e-12 * f_cont,
        "{f_cont} vs λ8·{p2}"
    );

    // Utilisations: each task is mostly spent running its behaviour.
    let u_auto = probability(&auto, &sol_auto, "#P1 = 1");
    let u_cont = probability(&cont, &sol_cont, "#P2 = 1");
    assert!(
        u_auto > 0.99 && u_cont > 0.99,
        "U_auto = {u_auto}, U_cont = {u_cont}"
    );
    // Localizer and planner: Success and Normal almost always (rates 1e-3 vs 1e3).
    for (c, s) in [(&auto, &sol_auto), (&cont, &sol_cont)] {
        let success = probability(c, s, "#P5 = 1");
        let warning = probability(c, s, "#P6 = 1");
        assert!(
            (success + warning - 1.0).abs() < 1e-12,
            "P5 + P6 is a P-invariant"
        );
        assert!(warning < 1e-5, "P_loc,warn = {warning}");
        let normal = probability(c, s, "#P7 = 1");
        let abnormal = probability(c, s, "#P8 = 1");
        assert!(
            (normal + abnormal - 1.0).abs() < 1e-12,
            "P7 + P8 is a P-invariant"
        );
        assert!(abnormal < 1e-5, "P_pp,abno = {abnormal}");
    }
}

#[test]
fn supervisor_solves_agree_across_methods_despite_rates_from_1e_3_to_1e3() {
    use petri::Method;
    for automove in [true, false] {
        let c = supervisor(automove);
        let direct = c
            .solve(
                &hypothesis(automove),
                None,
                &SolveParams {
                    method: Method::Direct,
                    ..SolveParams::default()
                },
            )
            .unwrap();
        for method in [Method::GaussSeidel, Method::Bicgstab] {
            let p = SolveParams {
                method,
                tolerance: 1e-14,
                ..SolveParams::default()
            };
            let other = c.solve(&hypothesis(automove), None, &p).unwrap();
            for (t, (a, b)) in direct.throughput.iter().zip(&other.throughput).enumerate() {
                assert!(
                    (a - b).abs() <= 1e-9 * a.abs(),
                    "automove = {automove}, {method:?}: X({}) {a} vs {b}",
                    c.gspn().transition_names()[t]
                );
            }
        }
    }
}
