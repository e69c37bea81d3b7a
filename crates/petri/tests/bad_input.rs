//! Bad input through the library API — rates, weights, parameters, limits,
//! assignments, measures, solver settings — gets a clear error naming what is
//! wrong, and never a panic. (Bad *files* are the subject of
//! `io_bad_input.rs`.)

use std::process::Command;

use petri::{
    CompiledGspn, Error, ExploreParams, Expr, Method, Net, ParamKind, Params, ReachabilityGraph, SolveParams,
    families, io,
};

const SUPERVISOR: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../models/supervisor.toml");

fn compile(net: &Net) -> CompiledGspn {
    let g = net.instantiate(&Params::new()).unwrap();
    CompiledGspn::build(&g, &ExploreParams::default()).unwrap()
}

/// `queue` fed by a source transition `arrive` (no input place: unbounded),
/// emptied by `serve`; rates are the parameters `lambda` and `mu`.
fn unbounded() -> Net {
    let mut n = Net::new("unbounded");
    n.set_param("lambda", Some(1.0), ParamKind::Real);
    n.set_param("mu", Some(2.0), ParamKind::Real);
    let q = n.add_place("queue", 0u32);
    let arrive = n.add_timed("arrive", Expr::param("lambda"));
    n.output(arrive, q);
    let serve = n.add_timed("serve", Expr::param("mu"));
    n.input(q, serve);
    n
}

/// A two-state net whose only rate is the parameter `lambda` (of value 1)
/// and whose immediate transition has weight `w`.
fn two_state(w: Expr) -> Net {
    let mut n = Net::new("two-state");
    n.set_param("lambda", Some(1.0), ParamKind::Real);
    let a = n.add_place("A", 1u32);
    let b = n.add_place("B", 0u32);
    let go = n.add_timed("go", Expr::param("lambda"));
    n.input(a, go);
    n.output(go, b);
    let back = n.add_immediate("back", w, 1);
    n.input(b, back);
    n.output(back, a);
    n
}

#[track_caller]
fn assert_invalid_value(err: Error, element: &str, what: &str) {
    let msg = err.to_string();
    match err {
        Error::InvalidValue {
            element: e, what: w, ..
        } => {
            assert!(e.contains(element), "element `{e}` should name {element}: {msg}");
            assert!(w.contains(what), "attribute `{w}` should be {what}: {msg}");
        }
        other => panic!("expected InvalidValue for {element}, got {other:?}"),
    }
}

#[test]
fn zero_negative_and_non_finite_rates_are_refused_when_solving() {
    let c = compile(&simple());
    for bad in [0.0, -1.0, f64::NAN, f64::INFINITY, f64::NEG_INFINITY, -0.0] {
        let err = c
            .solve(&Params::new().with("lambda", bad), None, &SolveParams::default())
            .unwrap_err();
        assert_invalid_value(err, "`go`", "rate");
        let mut rates = c.gspn().rates(&Params::new(), None).unwrap();
        rates[0] = bad;
        let err = c.solve_rates(&rates, &SolveParams::default()).unwrap_err();
        assert_invalid_value(err, "`go`", "rate");
    }
    // One rate per transition.
    let err = c.solve_rates(&[1.0], &SolveParams::default()).unwrap_err();
    assert!(matches!(err, Error::Invalid(_)), "{err:?}");
    assert!(
        err.to_string().contains("1 rates given for 2 transitions"),
        "{err}"
    );
    // A rate written as a negative number in the net itself.
    let mut net = simple();
    net.transitions[0].kind = petri::TransitionKind::Timed {
        rate: Some(Expr::Num(-3.0)),
        servers: petri::Servers::Single,
    };
    let err = compile(&net)
        .solve(&Params::new(), None, &SolveParams::default())
        .unwrap_err();
    assert_invalid_value(err, "`go`", "rate");
}

/// [`two_state`] with weight 1: transitions `go` (timed, rate `lambda` = 1)
/// and `back` (immediate).
fn simple() -> Net {
    two_state(Expr::Num(1.0))
}

#[test]
fn missing_rates_need_a_valid_default() {
    let mut net = simple();
    net.transitions[0].kind = petri::TransitionKind::Timed {
        rate: None,
        servers: petri::Servers::Single,
    };
    let c = compile(&net);
    let err = c
        .solve(&Params::new(), None, &SolveParams::default())
        .unwrap_err();
    assert!(
        matches!(&err, Error::MissingRate { transition } if transition == "go"),
        "{err:?}"
    );
    for bad in [0.0, -2.0, f64::NAN, f64::INFINITY] {
        let err = c
            .solve(&Params::new(), Some(bad), &SolveParams::default())
            .unwrap_err();
        assert_invalid_value(err, "default rate", "value");
    }
    assert!(
        c.solve(&Params::new(), Some(2.0), &SolveParams::default())
            .is_ok()
    );
}

#[test]
fn zero_negative_and_non_finite_weights_are_refused_when_instantiating() {
    for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let err = two_state(Expr::Num(bad)).instantiate(&Params::new()).unwrap_err();
        assert_invalid_value(err, "`back`", "weight");
    }
    // A weight given by a parameter that is 0.
    let mut net = two_state(Expr::param("w"));
    net.set_param("w", Some(1.0), ParamKind::Real);
    let err = net.instantiate(&Params::new().with("w", 0.0)).unwrap_err();
    assert_invalid_value(err, "`back`", "weight");
    // Priority 0 and fractional priorities.
    for bad in [0.0, 1.5, -1.0] {
        let mut net = simple();
        net.transitions[1].kind = petri::TransitionKind::Immediate {
            weight: Expr::Num(1.0),
            priority: Expr::Num(bad),
        };
        let err = net.instantiate(&Params::new()).unwrap_err();
        assert_invalid_value(err, "`back`", "priority");
    }
}

#[test]
fn supervisor_with_p_zero_needs_the_zero_weight_branch_left_out() {
    // The shipped model keeps both branches; p = 0 makes t0's weight 0.
    let net = io::read_file(SUPERVISOR).unwrap();
    let err = net.instantiate(&Params::new().with("p", 0.0)).unwrap_err();
    assert_invalid_value(err, "`t0`", "weight");
    let err = net.instantiate(&Params::new().with("p", 1.0)).unwrap_err();
    assert_invalid_value(err, "`t1`", "weight");
    let err = net.without_transition("t7b").unwrap_err();
    assert!(
        matches!(&err, Error::UnknownName { kind: "transition", name } if name == "t7b"),
        "{err:?}"
    );
}

#[test]
fn unbound_parameters_are_named_with_what_uses_them() {
    // A rate parameter without a value: found when solving.
    let mut net = simple();
    net.set_param("lambda", None, ParamKind::Real);
    let c = compile(&net);
    let err = c
        .solve(&Params::new(), None, &SolveParams::default())
        .unwrap_err();
    match &err {
        Error::UnboundParameter { name, used_by, .. } => {
            assert_eq!(name, "lambda");
            assert!(used_by.contains("`go`"), "{err}");
        }
        other => panic!("expected UnboundParameter, got {other:?}"),
    }
    assert!(err.to_string().contains("--param lambda=VALUE"), "{err}");
    // A marking parameter without a value: found when instantiating.
    let mut net = simple();
    net.places[0].initial = Expr::param("N");
    net.set_param("N", None, ParamKind::Int);
    let err = net.instantiate(&Params::new()).unwrap_err();
    assert!(
        matches!(&err, Error::UnboundParameter { name, used_by, .. } if name == "N" && used_by.contains("`A`")),
        "{err:?}"
    );
    // (The GreatSPN FMS file without N: `io_files.rs`, flexible_manufacturing_system_needs_n.)
}

#[test]
fn unknown_parameter_overrides_are_refused_and_list_the_known_ones() {
    let net = simple();
    let err = net.instantiate(&Params::new().with("lambda7", 1.0)).unwrap_err();
    match &err {
        Error::UnknownParameter { name, known } => {
            assert_eq!(name, "lambda7");
            assert!(known.contains("lambda"), "{err}");
        }
        other => panic!("expected UnknownParameter, got {other:?}"),
    }
    let c = compile(&net);
    let err = c
        .solve(&Params::new().with("lambda7", 1.0), None, &SolveParams::default())
        .unwrap_err();
    assert!(
        matches!(&err, Error::UnknownParameter { name, .. } if name == "lambda7"),
        "{err:?}"
    );
    // A net without parameters says so.
    let mut bare = Net::new("bare");
    bare.add_place("A", 1u32);
    let err = bare.instantiate(&Params::new().with("x", 1.0)).unwrap_err();
    assert!(err.to_string().contains("its parameters: none"), "{err}");
}

#[test]
fn structural_parameters_cannot_change_after_compilation() {
    let c = compile(&families::kanban(1));
    let err = c
        .solve(&Params::new().with("N", 2.0), None, &SolveParams::default())
        .unwrap_err();
    assert!(
        matches!(&err, Error::StructuralParameter { name, .. } if name == "N"),
        "{err:?}"
    );
    // The same value is fine.
    assert!(
        c.solve(&Params::new().with("N", 1.0), None, &SolveParams::default())
            .is_ok()
    );
}

#[test]
fn state_limit_on_an_unbounded_net_names_the_limit_and_the_growing_place() {
    let g = unbounded().instantiate(&Params::new()).unwrap();
    let limit = ExploreParams {
        max_states: 1000,
        ..ExploreParams::default()
    };
    for err in [
        ReachabilityGraph::explore(&g, &limit).unwrap_err(),
        CompiledGspn::build(&g, &limit).unwrap_err(),
    ] {
        let msg = err.to_string();
        match err {
            Error::StateLimit {
                limit,
                explored,
                hint,
            } => {
                assert_eq!(limit, 1000);
                assert!(explored <= 1000, "{msg}");
                assert!(hint.contains("`queue`") && hint.contains("unbounded"), "{msg}");
            }
            other => panic!("expected StateLimit, got {other:?}"),
        }
        assert!(msg.contains("more than 1000 markings"), "{msg}");
    }
}

#[test]
fn state_limit_on_a_bounded_net_blames_no_place() {
    let g = families::kanban(2).instantiate(&Params::new()).unwrap();
    let err = ReachabilityGraph::explore(
        &g,
        &ExploreParams {
            max_states: 1000,
            ..ExploreParams::default()
        },
    )
    .unwrap_err();
    match &err {
        Error::StateLimit {
            limit: 1000, hint, ..
        } => assert!(hint.is_empty(), "{err}"),
        other => panic!("expected StateLimit, got {other:?}"),
    }
    // The exact size passes, one less does not.
    assert!(
        ReachabilityGraph::explore(
            &g,
            &ExploreParams {
                max_states: 4600,
                ..ExploreParams::default()
            }
        )
        .is_ok()
    );
    assert!(
        ReachabilityGraph::explore(
            &g,
            &ExploreParams {
                max_states: 4599,
                ..ExploreParams::default()
            }
        )
        .is_err()
    );
}

#[test]
fn token_counts_beyond_u32_are_errors() {
    let mut net = unbounded();
    net.places[0].initial = Expr::Num(f64::from(u32::MAX));
    let g = net.instantiate(&Params::new()).unwrap();
    let err = ReachabilityGraph::explore(&g, &ExploreParams::default()).unwrap_err();
    assert!(
        matches!(&err, Error::TokenOverflow { place, .. } if place == "queue"),
        "{err:?}"
    );
    net.places[0].initial = Expr::Num(f64::from(u32::MAX) + 1.0);
    let err = net.instantiate(&Params::new()).unwrap_err();
    assert_invalid_value(err, "`queue`", "initial marking");
}

#[test]
fn degenerate_nets_are_solved_or_refused_without_panicking() {
    // No places, no transitions: one (empty) dead marking.
    let c = compile(&Net::new("empty"));
    assert_eq!(c.num_tangible(), 1);
    let sol = c.solve(&Params::new(), None, &SolveParams::default()).unwrap();
    assert_eq!(sol.pi, [1.0]);
    // Places but no transitions.
    let mut n = Net::new("still");
    n.add_place("A", 3u32);
    let c = compile(&n);
    let sol = c.solve(&Params::new(), None, &SolveParams::default()).unwrap();
    assert_eq!(sol.mean_tokens, [3.0]);
    // A transition without arcs fires forever without changing anything.
    let mut n = Net::new("idle");
    n.add_timed("tick", 2.0);
    let c = compile(&n);
    let sol = c.solve(&Params::new(), None, &SolveParams::default()).unwrap();
    assert_eq!(sol.throughput, [2.0]);
}

#[test]
fn bad_solver_settings_are_errors() {
    let c = compile(&families::kanban(1));
    let base = SolveParams::default();
    for bad in [
        SolveParams {
            tolerance: 0.0,
            ..base
        },
        SolveParams {
            tolerance: f64::NAN,
            ..base
        },
        SolveParams {
            tolerance: 1.0,
            ..base
        },
        SolveParams { omega: 2.0, ..base },
        SolveParams { omega: 0.0, ..base },
        SolveParams {
            max_iterations: 0,
            ..base
        },
    ] {
        let err = c.solve(&Params::new(), None, &bad).unwrap_err();
        assert!(matches!(err, Error::InvalidValue { .. }), "{bad:?}: {err:?}");
    }
    // Too few iterations: an error with the residual reached, not a result.
    for method in [Method::GaussSeidel, Method::Bicgstab] {
        let p = SolveParams {
            method,
            max_iterations: 2,
            ..base
        };
        match c.solve(&Params::new(), None, &p).unwrap_err() {
            Error::NoConvergence {
                iterations,
                residual,
                tolerance,
                ..
            } => {
                assert!(iterations <= 2, "{method:?}: {iterations}");
                assert!(residual > tolerance, "{method:?}: {residual} ≤ {tolerance}");
            }
            other => panic!("{method:?}: expected NoConvergence, got {other:?}"),
        }
    }
}

#[test]
fn malformed_assignments_are_errors_that_quote_them() {
    let ok = Params::parse_assignments(&["lambda7 = 1/122.33", "N=3", "x=-2e-3", "y=min(2, 3)"]).unwrap();
    assert_eq!(ok.get("lambda7"), Some(1.0 / 122.33));
    assert_eq!(ok.get("N"), Some(3.0));
    assert_eq!(ok.get("y"), Some(2.0));
    for bad in [
        "lambda", "=1", " = 1", "a=", "a=1+", "a=(1", "a=1)", "a=b", "a=#P1", "a=1/0", "a=0/0", "a=1e999",
        "a=1 2", "a=max(", "a=foo(1)",
    ] {
        match Params::parse_assignments(&[bad]) {
            Err(Error::BadAssignment { text, message }) => {
                assert_eq!(text, bad);
                assert!(!message.is_empty(), "{bad}");
            }
            other => panic!("`{bad}`: expected BadAssignment, got {other:?}"),
        }
    }
    // Reasonable nesting is fine.
    let nested = format!("a={}1{}", "(".repeat(50), ")".repeat(50));
    assert_eq!(Params::parse_assignments(&[nested]).unwrap().get("a"), Some(1.0));
}

#[test]
fn measures_naming_unknown_places_or_parameters_are_errors() {
    let c = compile(&simple());
    let sol = c.solve(&Params::new(), None, &SolveParams::default()).unwrap();
    let m = |text: &str| c.measure(&sol, &Expr::parse(text).unwrap());
    assert!((m("#A = 1").unwrap() - 1.0).abs() < 1e-15);
    for (text, name) in [
        ("#P1 = 1", "unknown place `P1`"),
        ("#A > K", "unknown parameter `K`"),
    ] {
        let err = m(text).unwrap_err();
        assert!(matches!(err, Error::Eval { .. }), "{text}: {err:?}");
        assert!(err.to_string().contains(name), "{text}: {err}");
    }
    // A measure that does not parse says where.
    let err = Expr::parse("#A = = 1").unwrap_err();
    assert!(matches!(err, Error::Expr { position: 6, .. }), "{err:?}");
}

// ---------------------------------------------------------------------------
// Regression: deep nesting overflowed the stack
// ---------------------------------------------------------------------------

const CHILD: &str = "PETRI_BAD_INPUT_CHILD";

/// The deep inputs, by name.
fn deep_input(case: &str) -> String {
    const DEPTH: usize = 5_000;
    match case {
        "assignment-parentheses" => format!("a={}1{}", "(".repeat(DEPTH), ")".repeat(DEPTH)),
        "assignment-minus" => format!("a={}1", "-".repeat(10 * DEPTH)),
        "assignment-not" => format!("a={}1", "!".repeat(10 * DEPTH)),
        "measure-parentheses" => format!("{}#A{}", "(".repeat(DEPTH), ")".repeat(DEPTH)),
        _ => unreachable!("{case}"),
    }
}

/// In the child process: 5,000 nested parentheses must be an error; a long
/// chain of prefix operators may be accepted (it evaluates fine) or refused,
/// but must not crash either.
fn parse_deep_input(case: &str) {
    let text = deep_input(case);
    let result = if case.starts_with("assignment") {
        Params::parse_assignments(&[&text]).map(|_| ())
    } else {
        Expr::parse(&text).map(|_| ())
    };
    if case.ends_with("parentheses") {
        assert!(result.is_err(), "{case}: expected an error");
    }
}

/// `Params::parse_assignments` (the CLI's `--param`) and `Expr::parse`
/// (measures) parse recursively with no depth limit: 5,000 nested
/// parentheses abort the whole process with a stack overflow (2,000 already
/// do with the default 2 MiB test-thread stack). The file readers guard
/// against this (`io::MAX_EXPRESSION_DEPTH`), these entry points do not.
///
/// Each input is parsed in a child process (this test binary run again,
/// with [`CHILD`] set), so that the overflow fails this test instead of
/// killing every test in the binary.
#[test]
fn deeply_nested_expressions_are_an_error_not_a_stack_overflow() {
    if let Ok(case) = std::env::var(CHILD) {
        parse_deep_input(&case);
        return;
    }
    let exe = std::env::current_exe().unwrap();
    let mut crashed = Vec::new();
    for case in [
        "assignment-parentheses",
        "assignment-minus",
        "assignment-not",
        "measure-parentheses",
    ] {
        let out = Command::new(&exe)
            .args([
                "deeply_nested_expressions_are_an_error_not_a_stack_overflow",
                "--exact",
                "--test-threads=1",
                "--nocapture",
            ])
            .env(CHILD, case)
            .env_remove("RUST_MIN_STACK")
            .output()
            .unwrap();
        if !out.status.success() {
            let stderr = String::from_utf8_lossy(&out.stderr);
            let last = stderr.lines().rev().take(3).collect::<Vec<_>>().join(" / ");
            crashed.push(format!("{case}: {} ({last})", out.status));
        }
    }
    assert!(
        crashed.is_empty(),
        "deep inputs crashed the parser:\n{}",
        crashed.join("\n")
    );
}

#[test]
fn memory_guard_is_an_error_with_the_estimate_and_the_limit() {
    let g = families::kanban(3).instantiate(&Params::new()).unwrap();
    let guard = ExploreParams {
        max_memory: 1 << 20,
        ..ExploreParams::default()
    };
    for err in [
        ReachabilityGraph::explore(&g, &guard).unwrap_err(),
        CompiledGspn::build(&g, &guard).unwrap_err(),
    ] {
        let msg = err.to_string();
        match err {
            Error::MemoryLimit {
                estimate,
                limit,
                markings,
                edges,
            } => {
                assert_eq!(limit, 1 << 20);
                assert!(estimate > limit, "{msg}");
                assert!(markings < 58_400 && edges > 0, "{msg}");
            }
            other => panic!("expected MemoryLimit, got {other:?}"),
        }
        assert!(
            msg.contains("limit of 1.0 MiB") && msg.contains("--max-memory"),
            "{msg}"
        );
    }
    // The default guard (85 % of the available memory) lets it through.
    assert_eq!(
        ReachabilityGraph::explore(&g, &ExploreParams::default())
            .unwrap()
            .num_markings(),
        58_400
    );
}

/// A diverging SOR stops as soon as its iterate is no longer finite; its
/// error said it had done `max_iterations` sweeps.
#[test]
fn diverging_sor_reports_the_sweeps_it_did() {
    let gspn = families::kanban(3).instantiate(&Params::new()).unwrap();
    let c = CompiledGspn::build(&gspn, &ExploreParams::default()).unwrap();
    let p = SolveParams {
        method: Method::GaussSeidel,
        omega: 1.8,
        ..SolveParams::default()
    };
    match c.solve(&Params::new(), None, &p).unwrap_err() {
        Error::NoConvergence { iterations, .. } => {
            assert!(iterations > 0 && iterations < p.max_iterations, "{iterations}");
        }
        other => panic!("expected NoConvergence, got {other:?}"),
    }
}
