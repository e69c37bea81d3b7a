//! Nets with decisions solved by hand (docs/gspn.md, *Decisions*): values,
//! policies, infinite and zero results, refused nets.

use petri::io::{self, Format};
use petri::mdp::{OptimizeParams, Precision, Property};
use petri::{Action, DecisionNet, Error, ExploreParams, Net, Params};

fn net(text: &str) -> Net {
    io::read_str(text, Format::Toml, "test.toml").unwrap()
}

fn compile(net: &Net) -> DecisionNet {
    let g = net.instantiate(&Params::new()).unwrap();
    DecisionNet::build(&g, &ExploreParams::default()).unwrap()
}

fn tight() -> OptimizeParams {
    OptimizeParams {
        precision: Precision {
            epsilon: 1e-12,
            ..Precision::default()
        },
    }
}

/// The value from the initial marking and the decision chosen in the
/// marking `where_` (given by its marked places).
fn solve(d: &DecisionNet, property: &str) -> (f64, f64, Vec<(String, String)>) {
    let p = Property::parse(property).unwrap();
    let obj = d.objective(&p).unwrap();
    let rates = d.rates(&Params::new(), None).unwrap();
    let (model, opt) = d.solve(&obj, &rates, &tight()).unwrap();
    let g = d.gspn();
    let choices = d
        .choices(&model, &opt)
        .into_iter()
        .map(|c| (g.format_marking(&c.marking), c.chosen.describe(g)))
        .collect();
    (opt.value(0), opt.error_bound(0), choices)
}

fn assert_close(got: (f64, f64), want: f64) {
    let (v, bound) = got;
    assert!(
        (v - want).abs() <= bound + 1e-12 * want.abs().max(1.0),
        "got {v} ± {bound}, want {want}"
    );
}

const WORKED: &str = r##"
name = "worked"
[[place]]
name = "idle"
initial = 1
[[place]]
name = "a"
[[place]]
name = "b"
[[place]]
name = "c"
[[place]]
name = "done"
[[place]]
name = "alarm"
[[transition]]
name = "go_a"
kind = "immediate"
decision = true
inputs = ["idle"]
outputs = ["a"]
[[transition]]
name = "go_b"
kind = "immediate"
decision = true
inputs = ["idle"]
outputs = ["b"]
[[transition]]
name = "slip"
kind = "immediate"
inputs = ["idle"]
outputs = ["c"]
[[transition]]
name = "skid"
kind = "immediate"
weight = 3
inputs = ["idle"]
outputs = ["a"]
[[transition]]
name = "ring"
kind = "immediate"
priority = 2
inputs = ["alarm"]
[[transition]]
name = "a_done"
rate = 1
inputs = ["a"]
outputs = ["done"]
[[transition]]
name = "b_done"
rate = 2
inputs = ["b"]
outputs = ["done"]
[[transition]]
name = "c_done"
rate = 0.25
inputs = ["c"]
outputs = ["done"]
"##;

#[test]
fn worked_example() {
    // docs/gspn.md: go_a → 1, go_b → 1/2, random → 1/4·4 + 3/4·1 = 7/4.
    let d = compile(&net(WORKED));
    assert_eq!(d.num_choices(), 1);
    let (v, b, choices) = solve(&d, "Tmin=? [F #done = 1]");
    assert_close((v, b), 0.5);
    assert_eq!(choices, vec![("idle".to_string(), "go_b".to_string())]);
    let (v, b, choices) = solve(&d, "Tmax=? [F #done = 1]");
    assert_close((v, b), 1.75);
    assert_eq!(choices[0].1, "random");
    // The alarm's priority 2 acts first; then `idle` chooses alike.
    let mut n = net(WORKED);
    n.places[5].initial = petri::Expr::Num(1.0);
    let d = compile(&n);
    let (v, b, _) = solve(&d, "Tmin=? [F #done = 1]");
    assert_close((v, b), 0.5);
    let (v, b, _) = solve(&d, "Tmax=? [F #done = 1]");
    assert_close((v, b), 1.75);
}

const RISKY: &str = r##"
name = "risky"
[[place]]
name = "start"
initial = 1
[[place]]
name = "R"
[[place]]
name = "S"
[[place]]
name = "goal"
[[place]]
name = "fail"
[labels]
goal = "#goal = 1"
[[transition]]
name = "risky"
kind = "immediate"
decision = true
inputs = ["start"]
outputs = ["R"]
[[transition]]
name = "retry"
kind = "immediate"
decision = true
inputs = ["start"]
outputs = ["S"]
[[transition]]
name = "win"
rate = 7
inputs = ["R"]
outputs = ["goal"]
[[transition]]
name = "lose"
rate = 3
inputs = ["R"]
outputs = ["fail"]
[[transition]]
name = "s_win"
rate = 1
inputs = ["S"]
outputs = ["goal"]
[[transition]]
name = "s_fail"
rate = 1
inputs = ["S"]
outputs = ["fail"]
[[transition]]
name = "s_back"
rate = 2
inputs = ["S"]
outputs = ["start"]
"##;

#[test]
fn risky_or_retry() {
    // risky: 0.7; retry for ever: p = 1/4 + p/2 → 1/2.
    let d = compile(&net(RISKY));
    let (v, b, c) = solve(&d, r#"Pmax=? [F "goal"]"#);
    assert_close((v, b), 0.7);
    assert_eq!(c[0].1, "risky");
    let (v, b, c) = solve(&d, r#"Pmin=? [F "goal"]"#);
    assert_close((v, b), 0.5);
    assert_eq!(c[0].1, "retry");
    // Failing is certain under no policy; time to goal is infinite.
    let (v, _, _) = solve(&d, r#"Tmin=? [F "goal"]"#);
    assert_eq!(v, f64::INFINITY);
}

const WEAR: &str = r##"
name = "wear"
[[place]]
name = "ready"
initial = 1
[[place]]
name = "wear"
[[place]]
name = "F"
[[place]]
name = "S"
[[place]]
name = "R"
[[place]]
name = "D"
[[place]]
name = "end"
[[transition]]
name = "fast"
kind = "immediate"
decision = true
inputs = ["ready"]
outputs = ["F"]
[[transition]]
name = "slow"
kind = "immediate"
decision = true
inputs = ["ready"]
outputs = ["S"]
[[transition]]
name = "f_ok"
rate = 4
inputs = ["F"]
outputs = ["D"]
[[transition]]
name = "f_jam"
rate = 12
inputs = ["F", "wear"]
outputs = ["R", "wear"]
[[transition]]
name = "s_ok"
rate = 1
inputs = ["S"]
outputs = ["D"]
[[transition]]
name = "repair"
rate = 0.5
inputs = ["R"]
outputs = ["ready"]
[[transition]]
name = "next"
rate = 1
inputs = ["D"]
outputs = ["ready", "wear"]
inhibitors = ["wear"]
[[transition]]
name = "finish"
rate = 1
inputs = ["D", "wear"]
outputs = ["end"]
"##;

#[test]
fn the_best_choice_differs_between_two_markings() {
    // New machine: fast (1/4) beats slow (1). Worn: fast jams 3 times in 4
    // into a repair of 2, slow takes 1: T(worn) = 1 + 1 = 2 by slow;
    // T(new) = 1/4 + 1 + 2 = 3.25 by fast.
    let d = compile(&net(WEAR));
    let (v, b, mut c) = solve(&d, "Tmin=? [F #end = 1]");
    assert_close((v, b), 3.25);
    c.sort();
    assert_eq!(
        c,
        vec![
            ("ready".to_string(), "fast".to_string()),
            ("ready wear".to_string(), "slow".to_string())
        ]
    );
}

const REPAIR: &str = r##"
name = "repair"
[[place]]
name = "up"
initial = 1
[[place]]
name = "broken"
[[place]]
name = "slow_fix"
[[place]]
name = "fast_fix"
[labels]
up = "#up = 1"
[rewards.profit]
rate = "3 * #up"
impulse = { fast = -2 }
[[transition]]
name = "fail"
rate = 1
inputs = ["up"]
outputs = ["broken"]
[[transition]]
name = "cheap"
kind = "immediate"
decision = true
inputs = ["broken"]
outputs = ["slow_fix"]
[[transition]]
name = "fast"
kind = "immediate"
decision = true
inputs = ["broken"]
outputs = ["fast_fix"]
[[transition]]
name = "fixed_slowly"
rate = 1
inputs = ["slow_fix"]
outputs = ["up"]
[[transition]]
name = "fixed_fast"
rate = 4
inputs = ["fast_fix"]
outputs = ["up"]
"##;

#[test]
fn long_run_profit_and_availability() {
    // Cheap repair: up 1, down 1 → profit 3/2 per unit of time, up 1/2.
    // Fast repair: up 1, down 1/4, cost 2 → (3 − 2)/(5/4) = 0.8, up 0.8.
    let d = compile(&net(REPAIR));
    let (v, b, c) = solve(&d, r#"R{"profit"}max=? [LRA]"#);
    assert_close((v, b), 1.5);
    assert_eq!(c[0].1, "cheap");
    let (v, b, _) = solve(&d, r#"R{"profit"}min=? [LRA]"#);
    assert_close((v, b), 0.8);
    let (v, b, c) = solve(&d, r#"LRAmax=? ["up"]"#);
    assert_close((v, b), 0.8);
    assert_eq!(c[0].1, "fast");
    let (v, b, _) = solve(&d, r#"LRAmin=? ["up"]"#);
    assert_close((v, b), 0.5);
}

const WAIT: &str = r##"
name = "wait"
[[place]]
name = "idle"
initial = 1
[[place]]
name = "W"
[[place]]
name = "G"
[labels]
goal = "#G = 1"
[rewards.cost]
impulse = { go = 1 }
[[transition]]
name = "wait"
kind = "immediate"
decision = true
inputs = ["idle"]
outputs = ["W"]
[[transition]]
name = "go"
kind = "immediate"
decision = true
inputs = ["idle"]
outputs = ["G"]
[[transition]]
name = "back"
rate = 1
inputs = ["W"]
outputs = ["idle"]
"##;

#[test]
fn waiting_for_ever_costs_nothing_and_never_arrives() {
    let d = compile(&net(WAIT));
    // Zero-cost waiting is an end component: the minimum must still arrive.
    let (v, b, c) = solve(&d, r#"R{"cost"}min=? [F "goal"]"#);
    assert_close((v, b), 1.0);
    assert_eq!(c[0].1, "go");
    let (v, b, _) = solve(&d, r#"Pmin=? [F "goal"]"#);
    assert_eq!((v, b), (0.0, 0.0));
    let (v, b, _) = solve(&d, r#"Pmax=? [F "goal"]"#);
    assert_eq!((v, b), (1.0, 0.0));
    // Going is immediate: no time; waiting for ever: never.
    let (v, _, _) = solve(&d, r#"Tmin=? [F "goal"]"#);
    assert_eq!(v, 0.0);
    let (v, _, _) = solve(&d, r#"Tmax=? [F "goal"]"#);
    assert_eq!(v, f64::INFINITY);
}

#[test]
fn a_choice_that_can_loop_in_no_time_is_refused() {
    // `again` leads back to `idle` through an immediate transition: the
    // policy could choose it for ever without time passing.
    let text = WAIT.replace(
        "[[transition]]\nname = \"back\"\nrate = 1",
        "[[transition]]\nname = \"back\"\nkind = \"immediate\"",
    );
    let g = net(&text).instantiate(&Params::new()).unwrap();
    let err = DecisionNet::build(&g, &ExploreParams::default()).unwrap_err();
    assert!(matches!(err, Error::Zeno { .. }), "{err}");
    assert!(err.to_string().contains("[idle]"), "{err}");
}

#[test]
fn a_net_with_a_choice_needs_a_policy_to_be_solved_or_simulated() {
    let g = net(WORKED).instantiate(&Params::new()).unwrap();
    let err = petri::CompiledGspn::build(&g, &ExploreParams::default()).unwrap_err();
    assert!(matches!(err, Error::Undecided { .. }), "{err}");
    assert!(
        err.to_string().contains("[idle]") && err.to_string().contains("go_a, go_b, random (slip, skid)"),
        "{err}"
    );
    // Under the optimal policy: the CTMC of go_b.
    let d = compile(&net(WORKED));
    let p = Property::parse("Tmin=? [F #done = 1]").unwrap();
    let obj = d.objective(&p).unwrap();
    let rates = d.rates(&Params::new(), None).unwrap();
    let (model, opt) = d.solve(&obj, &rates, &tight()).unwrap();
    let policy = d.policy(&opt, &model, Some(&p.text));
    let text = policy.to_json();
    let read = petri::Policy::parse(&text, "policy.json").unwrap();
    let under = g.with_policy(read).unwrap();
    let c = petri::CompiledGspn::build(&under, &ExploreParams::default()).unwrap();
    // Tangible markings: b, then done (absorbing).
    assert_eq!(c.num_tangible(), 2);
    let sol = c
        .solve(&Params::new(), None, &petri::SolveParams::default())
        .unwrap();
    let done = under.place("done").unwrap();
    assert!((sol.prob_nonempty(done) - 1.0).abs() < 1e-12);
    let go_b = under.transition("go_b").unwrap();
    assert_eq!(policy.action(&[1, 0, 0, 0, 0, 0]), Some(Action::Fire(go_b)));
    // Read back, the policy knows nothing until bound to a net.
    let mut read = petri::Policy::parse(&text, "policy.json").unwrap();
    assert_eq!(read.action(&[1, 0, 0, 0, 0, 0]), None);
    read.bind(&g).unwrap();
    assert_eq!(read.action(&[1, 0, 0, 0, 0, 0]), Some(Action::Fire(go_b)));
}
