//! `petrinav topo`, run as a user would: routes planned on the hand-made
//! small office (`crates/topo/tests/data/small_office.fpn.json`) with their
//! tables and JSON, paper against optimal mode, several goals, thresholds
//! rejecting transitions; conversions (PNML read back by petri's reader,
//! DOT with the route, the map file rewritten byte for byte); generated maps;
//! and every kind of bad input a clear error naming what is wrong, with a
//! non-zero exit code and never a panic.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use serde_json::Value;

fn petrinav(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_petrinav"))
        .args(args)
        .output()
        .expect("the petrinav binary runs")
}

fn fresh(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("topo_{name}"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

const OFFICE: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../topo/tests/data/small_office.fpn.json"
);

fn office_text() -> String {
    std::fs::read_to_string(OFFICE).unwrap()
}

/// Runs, expects success, returns standard output.
fn ok(args: &[&str]) -> String {
    let out = petrinav(args);
    assert!(out.status.success(), "{args:?}: {}", stderr(&out));
    stdout(&out)
}

/// Runs, expects a clean failure (exit code 1, a one-line `error:`
/// message, no panic), returns the message.
fn fails(args: &[&str]) -> String {
    let out = petrinav(args);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "{args:?}: {err}");
    assert!(!err.contains("panicked"), "{args:?}: {err}");
    assert!(err.starts_with("error: "), "{args:?}: {err}");
    assert!(stdout(&out).is_empty(), "{args:?}: nothing on standard output");
    err
}

fn plan_json(extra: &[&str]) -> Value {
    let mut args = vec!["topo", "plan", OFFICE, "--json"];
    args.extend_from_slice(extra);
    serde_json::from_str(&ok(&args)).unwrap()
}

fn route_of(v: &Value) -> Vec<&str> {
    v["route"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| t["transition"].as_str().unwrap())
        .collect()
}

#[test]
fn plan_prints_the_route_and_the_values_along_it() {
    let text = ok(&["topo", "plan", OFFICE, "--from", "door", "--to", "desk"]);
    // The cheapest route goes by the corner: C = (8 + 6) / 98.
    assert!(
        text.contains("door → t1 → corner → t2 → desk  (2 transitions)"),
        "{text}"
    );
    assert!(text.contains("0.142857  (Σ C(t) along the route)"), "{text}");
    // One row per transition: step, id, places, strategy, exit turn, C, f, λ, α(to).
    let row = text
        .lines()
        .find(|l| l.trim_start().starts_with("1  t1"))
        .unwrap_or_else(|| panic!("{text}"));
    let cells: Vec<&str> = row.split_whitespace().collect();
    assert_eq!(
        cells,
        [
            "1",
            "t1",
            "door",
            "corner",
            "wall",
            "following",
            "right",
            "right",
            "0.0816327",
            "0.142857",
            "1",
            "0.0612245"
        ],
        "{text}"
    );
    // The alternatives: the long detour is costlier, the way by the window
    // is rejected by its learnt threshold (f = 13/98 > λ = 1/8).
    let rejected = text.lines().find(|l| l.starts_with("t4 ")).unwrap();
    assert!(
        rejected.contains("rejected: min(1, C + α(window)) = 0.132653 > λ"),
        "{rejected}"
    );
    assert!(rejected.contains("0.125"), "{rejected}");
    let costlier = text.lines().find(|l| l.starts_with("t0 ")).unwrap();
    assert!(costlier.ends_with("costlier"), "{costlier}");

    let v = plan_json(&["--from", "door", "--to", "desk"]);
    assert_eq!(v["mode"], "optimal");
    assert_eq!(
        (v["from"].as_str(), v["goal"].as_str()),
        (Some("door"), Some("desk"))
    );
    assert_eq!(route_of(&v), ["t1", "t2"]);
    let route = v["route"].as_array().unwrap();
    let keys: Vec<&str> = route[0].as_object().unwrap().keys().map(String::as_str).collect();
    assert_eq!(
        keys,
        [
            "cost",
            "duration_s",
            "exit_turn",
            "f",
            "from",
            "lambda",
            "step",
            "strategy",
            "to",
            "transition",
            "weighted_cost"
        ]
    );
    assert_eq!(route[0]["strategy"], "wall_follow_right");
    assert_eq!(route[1]["exit_turn"], "left");
    assert_eq!(route[1]["f"].as_f64(), Some(6.0 / 98.0));
    let cost = v["cost"].as_f64().unwrap();
    let sum: f64 = route.iter().map(|t| t["weighted_cost"].as_f64().unwrap()).sum();
    assert_eq!(cost, sum);
    assert!((cost - 14.0 / 98.0).abs() < 1e-15);
    assert_eq!(v["alpha_start"].as_f64(), route[0]["f"].as_f64());
    let places: Vec<&str> = v["places"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p["name"].as_str().unwrap())
        .collect();
    assert_eq!(places, ["door", "corner", "desk"]);
    assert_eq!(v["places"][2]["alpha"].as_f64(), Some(0.0));
    let status: Vec<(&str, &str)> = v["alternatives"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| (t["transition"].as_str().unwrap(), t["status"].as_str().unwrap()))
        .collect();
    assert_eq!(
        status,
        [("t0", "costlier"), ("t4", "rejected"), ("t7", "costlier")]
    );
    let t4 = &v["alternatives"][1];
    assert_eq!(t4["f"].as_f64(), Some(1.0), "a rejected transition's f is 1");
    assert!((t4["composed"].as_f64().unwrap() - 13.0 / 98.0).abs() < 1e-15);
}

#[test]
fn paper_mode_takes_the_fewest_transitions_and_may_cost_more() {
    let optimal = plan_json(&["--from", "door", "--to", "desk"]);
    let paper = plan_json(&["--from", "door", "--to", "desk", "--mode", "paper"]);
    assert_eq!(paper["mode"], "paper");
    assert_eq!(route_of(&paper), ["t0"], "one round: the direct detour");
    assert_eq!(paper["iterations"], 1);
    assert_eq!(paper["cost"].as_f64(), Some(40.0 / 98.0));
    assert!(paper["cost"].as_f64() > optimal["cost"].as_f64());
    // Where the fewest transitions are also the cheapest, they agree.
    let a = plan_json(&["--from", "desk", "--to", "window"]);
    let b = plan_json(&["--from", "desk", "--to", "window", "--mode", "paper"]);
    assert_eq!(route_of(&a), ["t3", "t4"]);
    assert_eq!(route_of(&a), route_of(&b));
    assert_eq!(a["cost"], b["cost"]);
    let text = ok(&[
        "topo", "plan", OFFICE, "--from", "door", "--to", "desk", "--mode", "paper",
    ]);
    assert!(
        text.contains("1 round\n") && text.contains("door → t0 → desk"),
        "{text}"
    );
}

#[test]
fn several_goals_lead_to_the_nearest_and_thresholds_depend_on_the_route() {
    // t4 (door → window, λ = 1/8): f = 9/98 when the window is a goal,
    // accepted; rejected on the way to the desk (13/98).
    let v = plan_json(&["--from", "door", "--to", "desk", "--to", "window"]);
    assert_eq!(v["goals"], serde_json::json!(["desk", "window"]));
    assert_eq!(v["goal"], "window");
    assert_eq!(route_of(&v), ["t4"]);
    assert_eq!(v["cost"].as_f64(), Some(9.0 / 98.0));
    let text = ok(&[
        "topo", "plan", OFFICE, "--from", "door", "--to", "desk", "--to", "window",
    ]);
    assert!(text.contains("window (the nearest)"), "{text}");
    // The start among the goals: nothing to do.
    let v = plan_json(&["--from", "desk", "--to", "desk", "--to", "door"]);
    assert_eq!(route_of(&v), Vec::<&str>::new());
    assert_eq!(v["cost"].as_f64(), Some(0.0));
    let text = ok(&["topo", "plan", OFFICE, "--from", "desk", "--to", "desk"]);
    assert!(text.contains("the start is a goal"), "{text}");
    // Names with quotes and spaces are names like others.
    let err = fails(&["topo", "plan", OFFICE, "--from", "closet \"B\"", "--to", "desk"]);
    assert!(err.contains("no route from `closet \"B\"` to `desk`"), "{err}");
}

#[test]
fn no_route_says_why() {
    // Nothing enters the closet.
    let err = fails(&["topo", "plan", OFFICE, "--from", "door", "--to", "closet \"B\""]);
    assert!(
        err.contains(
            "no route from `door` to `closet \"B\"`: no sequence of transitions leads there (4 of the map's 5 places can be reached from `door`)"
        ),
        "{err}"
    );
    // The closet's only way out failed 40 times: λ = 2^-40 rejects it.
    let err = fails(&["topo", "plan", OFFICE, "--from", "closet \"B\"", "--to", "door"]);
    assert!(
        err.contains("every route there takes a transition whose threshold rejects it"),
        "{err}"
    );
    assert!(
        err.contains("ignoring thresholds the route would be closet \"B\" → desk → door"),
        "{err}"
    );
    assert!(err.contains("t6 closet \"B\" → desk (λ = 9.09495e-13"), "{err}");
    let err = fails(&[
        "topo",
        "plan",
        OFFICE,
        "--from",
        "closet \"B\"",
        "--to",
        "door",
        "--mode",
        "paper",
        "--json",
    ]);
    assert!(err.contains("no route"), "{err}");
}

#[test]
fn unknown_places_are_named_with_the_places_there_are() {
    let err = fails(&["topo", "plan", OFFICE, "--from", "kitchen", "--to", "desk"]);
    assert!(
        err.contains("--from: no place named `kitchen` in ")
            && err.contains("its places are door, corner, desk, window, closet \"B\""),
        "{err}"
    );
    let err = fails(&[
        "topo", "plan", OFFICE, "--from", "door", "--to", "desk", "--to", "Window",
    ]);
    assert!(
        err.contains("--to: no place named `Window`") && err.contains("did you mean `window`?"),
        "{err}"
    );
    let dir = fresh("unknown");
    let big = dir.join("big.fpn.json");
    ok(&["topo", "generate", "40", "-o", big.to_str().unwrap()]);
    let err = fails(&[
        "topo",
        "plan",
        big.to_str().unwrap(),
        "--from",
        "p0",
        "--to",
        "p3",
    ]);
    assert!(
        err.contains("its 40 places are p1, p2, p3, p4, p5, p6, p7, p8, p9, p10 and 30 more"),
        "{err}"
    );
    // Missing options are clap's errors (exit code 2), not panics.
    let out = petrinav(&["topo", "plan", OFFICE, "--from", "door"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("--to <PLACE>"), "{}", stderr(&out));
}

/// Writes `text` as a map file and plans on it: the error message.
fn plan_on(dir: &Path, name: &str, text: &str) -> String {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    let p = path.to_str().unwrap();
    let err = fails(&["topo", "plan", p, "--from", "door", "--to", "desk"]);
    assert!(err.contains(p), "the message names the file: {err}");
    // `convert` reads maps the same way.
    let conv = fails(&["topo", "convert", p, dir.join("out.pnml").to_str().unwrap()]);
    assert_eq!(conv, err);
    err
}

/// The office map with the first `from` replaced by `to`.
fn office_with(from: &str, to: &str) -> String {
    let text = office_text();
    assert!(text.contains(from), "{from}");
    text.replacen(from, to, 1)
}

#[test]
fn malformed_map_files_are_clear_errors() {
    let dir = fresh("malformed");
    let text = office_text();
    let cases: Vec<(&str, String, &str)> = vec![
        ("empty", String::new(), "the file is empty"),
        ("blank", " \n\n".into(), "the file is empty"),
        (
            "not_json",
            "places: [door, desk]\n".into(),
            "line 1, column 1: expected value, near `places: [door, desk]`",
        ),
        (
            "pnml",
            "<?xml version=\"1.0\"?>\n<pnml/>\n".into(),
            "line 1, column 1: expected value",
        ),
        ("array", "[1, 2, 3]".into(), "the file holds a JSON array"),
        ("number", "42".into(), "the file holds a JSON number"),
        (
            "other_json",
            "{\"name\": \"supervisor\", \"places\": []}".into(),
            "not a petrinav FPN map: \"format\" is (none)",
        ),
        (
            "other_format",
            text.replace("petrinav-fpn", "petrinav-gspn"),
            "\"format\" is \"petrinav-gspn\", expected \"petrinav-fpn\"",
        ),
        (
            "version",
            text.replace("\"version\": 1", "\"version\": 2"),
            "FPN map file version 2: this petrinav reads version 1",
        ),
        (
            "truncated",
            text[..text.len() / 2].to_string(),
            "the text stops before the map is complete (a truncated file?)",
        ),
        (
            "truncated_end",
            text.trim_end().trim_end_matches('}').to_string(),
            "truncated",
        ),
        ("trailing", format!("{text}{{}}"), "trailing characters"),
        (
            "missing_field",
            text.replacen("      \"lambda\": 1.0,\n", "", 1),
            "missing field `lambda`",
        ),
        (
            "duplicate_field",
            text.replacen("\"lambda\": 1.0,", "\"lambda\": 1.0, \"lambda\": 0.5,", 1),
            "duplicate field `lambda`",
        ),
    ];
    for (name, body, expected) in cases {
        let err = plan_on(&dir, &format!("{name}.fpn.json"), &body);
        assert!(err.contains(expected), "{name}: {err}");
    }
    let err = fails(&[
        "topo",
        "plan",
        dir.join("absent.fpn.json").to_str().unwrap(),
        "--from",
        "a",
        "--to",
        "b",
    ]);
    assert!(err.contains("absent.fpn.json: No such file"), "{err}");
}

#[test]
fn inconsistent_map_files_name_what_is_wrong() {
    let dir = fresh("inconsistent");
    let cases: Vec<(&str, String, &str)> = vec![
        (
            "unknown_place",
            office_with("\"to\": \"corner\"", "\"to\": \"kitchen\""),
            "transition t1: `to` names no place: `kitchen`",
        ),
        (
            "lambda_above_1",
            office_with("\"lambda\": 0.125", "\"lambda\": 1.25"),
            "transition t4 (door → window): lambda = 1.25: expected a threshold in [0, 1]",
        ),
        (
            "lambda_negative",
            office_with("\"lambda\": 0.125", "\"lambda\": -0.5"),
            "transition t4 (door → window): lambda = -0.5: expected a threshold in [0, 1]",
        ),
        (
            "lambda_nan",
            office_with("\"lambda\": 0.125", "\"lambda\": NaN"),
            "expected value, near `\"lambda\": NaN,`",
        ),
        (
            "lambda_string",
            office_with("\"lambda\": 0.125", "\"lambda\": \"0.125\""),
            "invalid type: string \"0.125\", expected f64, near `\"lambda\": \"0.125\",`",
        ),
        (
            "lambda_huge",
            office_with("\"lambda\": 0.125", "\"lambda\": 1e999"),
            "number out of range",
        ),
        (
            // α and f are the values of a plan, not of the map: a file
            // holding them is not a map file.
            "alpha",
            office_with("\"visits\": 3", "\"visits\": 3, \"alpha\": 1.5"),
            "unknown field `alpha`",
        ),
        (
            "f",
            office_with("\"lambda\": 0.125,", "\"lambda\": 0.125, \"f\": -1,"),
            "unknown field `f`",
        ),
        (
            "negative_cost",
            office_with("\"cost\": 8.0", "\"cost\": -8.0"),
            "transition t1 (door → corner): cost = -8: expected a finite cost > 0",
        ),
        (
            "zero_cost",
            office_with("\"cost\": 8.0", "\"cost\": 0"),
            "cost = 0: expected a finite cost > 0",
        ),
        (
            "cost_string",
            office_with("\"cost\": 8.0", "\"cost\": \"cheap\""),
            "invalid type: string \"cheap\", expected f64, near `\"cost\": \"cheap\",`",
        ),
        (
            "negative_duration",
            office_with("\"duration_s\": 29.0", "\"duration_s\": -1"),
            "duration_s = -1: expected a finite duration ≥ 0",
        ),
        (
            "duplicate_name",
            office_with("\"name\": \"corner\"", "\"name\": \"door\""),
            "two places are named `door` (places 0 and 1, from 0)",
        ),
        (
            "empty_name",
            office_with("\"name\": \"corner\"", "\"name\": \"\""),
            "a place name cannot be empty",
        ),
        (
            "more_failures",
            office_with("\"failures\": 3", "\"failures\": 9"),
            "9 failures out of 4 attempts",
        ),
        (
            "negative_count",
            office_with("\"attempts\": 4", "\"attempts\": -4"),
            "invalid value: integer `-4`, expected u32",
        ),
        (
            "wall_following_from_c",
            office_with(
                "\"strategy\": \"free_movement\",\n      \"exit_turn\": \"left\",\n      \"duration_s\": 9.0",
                "\"strategy\": \"wall_follow_left\",\n      \"exit_turn\": \"left\",\n      \"duration_s\": 9.0",
            ),
            "wall following left cannot leave `desk`, a place of type (c)",
        ),
        (
            "unknown_strategy",
            office_with("\"strategy\": \"detour_left\"", "\"strategy\": \"teleport\""),
            "unknown variant `teleport`",
        ),
        (
            "bad_kind",
            office_with("\"kind\": \"a\"", "\"kind\": \"d\""),
            "unknown variant `d`, expected one of `a`, `b`, `c`",
        ),
    ];
    for (name, body, expected) in cases {
        let err = plan_on(&dir, &format!("{name}.fpn.json"), &body);
        assert!(err.contains(expected), "{name}: {err}");
    }
}

#[test]
fn convert_writes_pnml_dot_and_the_map_file() {
    let dir = fresh("convert");
    let (pnml, dot, json) = (
        dir.join("office.pnml"),
        dir.join("office.dot"),
        dir.join("copy.fpn.json"),
    );
    let out = petrinav(&["topo", "convert", OFFICE, pnml.to_str().unwrap()]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("5 places, 8 transitions"),
        "{}",
        stderr(&out)
    );
    let net = petri::io::read_file(&pnml).unwrap();
    assert_eq!(net.name, "small_office");
    assert_eq!(
        net.places.iter().map(|p| p.name.as_str()).collect::<Vec<_>>(),
        ["door", "corner", "desk", "window", "closet \"B\""]
    );
    assert_eq!(net.transitions.len(), 8);
    assert_eq!(net.arcs.len(), 16);
    // The map file rewritten is the same bytes.
    ok(&["topo", "convert", OFFICE, json.to_str().unwrap()]);
    assert_eq!(std::fs::read_to_string(&json).unwrap(), office_text());
    // A DOT picture, with the route when asked.
    ok(&["topo", "convert", OFFICE, dot.to_str().unwrap()]);
    let plain = std::fs::read_to_string(&dot).unwrap();
    assert!(
        plain.starts_with("digraph fpn {") && !plain.contains("penwidth"),
        "{plain}"
    );
    let out = petrinav(&[
        "topo",
        "convert",
        OFFICE,
        dot.to_str().unwrap(),
        "--from",
        "door",
        "--to",
        "desk",
    ]);
    assert!(
        stderr(&out).contains("with the route door → desk (2 transitions)"),
        "{}",
        stderr(&out)
    );
    let routed = std::fs::read_to_string(&dot).unwrap();
    assert_eq!(routed.matches("penwidth=3").count(), 2, "{routed}");
    assert!(
        routed.contains("n0 -> n1 [label=\"t1 wall following right\\nf=0.1429\""),
        "{routed}"
    );
    assert!(
        routed.contains("style=dashed"),
        "rejected transitions dashed: {routed}"
    );
    ok(&[
        "topo",
        "convert",
        OFFICE,
        dot.to_str().unwrap(),
        "--from",
        "door",
        "--to",
        "desk",
        "--mode",
        "paper",
    ]);
    let paper = std::fs::read_to_string(&dot).unwrap();
    assert_eq!(paper.matches("penwidth=3").count(), 1, "{paper}");
    // PNML with the route: the start marked, the plan recorded, still a net petri reads.
    ok(&[
        "topo",
        "convert",
        OFFICE,
        pnml.to_str().unwrap(),
        "--from",
        "door",
        "--to",
        "desk",
        "--name",
        "office route",
    ]);
    let text = std::fs::read_to_string(&pnml).unwrap();
    assert!(text.contains("<fpnPlan mode=\"optimal\" start=\"pl0\""), "{text}");
    let net = petri::io::read_file(&pnml).unwrap();
    assert_eq!(net.name, "office route");
    assert_eq!(net.places[0].initial.as_number(), Some(1.0));
}

#[test]
fn convert_refuses_unknown_outputs_and_misplaced_options() {
    let dir = fresh("convert_refuses");
    let (dot, json) = (dir.join("office.dot"), dir.join("copy.fpn.json"));
    let err = fails(&[
        "topo",
        "convert",
        OFFICE,
        dir.join("office.svg").to_str().unwrap(),
    ]);
    assert!(
        err.contains("unknown extension `.svg`: expected .pnml, .dot or .fpn.json"),
        "{err}"
    );
    let err = fails(&["topo", "convert", OFFICE, dir.join("office").to_str().unwrap()]);
    assert!(err.contains("no extension"), "{err}");
    let err = fails(&[
        "topo",
        "convert",
        OFFICE,
        json.to_str().unwrap(),
        "--from",
        "door",
        "--to",
        "desk",
    ]);
    assert!(err.contains("a map file has no route"), "{err}");
    let err = fails(&[
        "topo",
        "convert",
        OFFICE,
        dot.to_str().unwrap(),
        "--from",
        "door",
        "--to",
        "nowhere",
    ]);
    assert!(err.contains("--to: no place named `nowhere`"), "{err}");
    let err = fails(&["topo", "convert", OFFICE, dot.to_str().unwrap(), "--name", "x"]);
    assert!(err.contains("--name names the net of a .pnml output"), "{err}");
    let err = fails(&[
        "topo",
        "convert",
        OFFICE,
        dir.join("no/such/dir/x.pnml").to_str().unwrap(),
    ]);
    assert!(err.contains("writing"), "{err}");
    let out = petrinav(&["topo", "convert", OFFICE, dot.to_str().unwrap(), "--from", "door"]);
    assert_eq!(out.status.code(), Some(2), "--from needs --to");
}

#[test]
fn generate_is_deterministic_and_its_maps_plan() {
    let dir = fresh("generate");
    let (a, b, c) = (
        dir.join("a.fpn.json"),
        dir.join("b.fpn.json"),
        dir.join("c.fpn.json"),
    );
    let out = petrinav(&["topo", "generate", "60", "--seed", "3", "-o", a.to_str().unwrap()]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("60 places, 240 transitions"),
        "{}",
        stderr(&out)
    );
    ok(&["topo", "generate", "60", "--seed", "3", "-o", b.to_str().unwrap()]);
    ok(&[
        "topo",
        "generate",
        "60",
        "--seed",
        "4",
        "--transitions",
        "300",
        "-o",
        c.to_str().unwrap(),
    ]);
    let (ta, tb, tc) = (
        std::fs::read_to_string(&a).unwrap(),
        std::fs::read_to_string(&b).unwrap(),
        std::fs::read_to_string(&c).unwrap(),
    );
    assert_eq!(ta, tb, "same seed, same map");
    assert_ne!(ta, tc);
    assert_eq!(
        ok(&["topo", "generate", "60", "--seed", "3"]),
        ta,
        "standard output"
    );
    let map = topo::FuzzyPetriNet::from_json(&tc).unwrap();
    assert_eq!((map.num_places(), map.num_transitions()), (60, 300));
    let v: Value = serde_json::from_str(&ok(&[
        "topo",
        "plan",
        a.to_str().unwrap(),
        "--from",
        "p1",
        "--to",
        "p60",
        "--json",
    ]))
    .unwrap();
    assert_eq!(v["goal"], "p60");
    assert!(!route_of(&v).is_empty());
    let err = fails(&["topo", "generate", "0"]);
    assert!(
        err.contains("number of places = 0: expected between 1 and 1000000"),
        "{err}"
    );
    let err = fails(&["topo", "generate", "10", "--transitions", "5"]);
    assert!(err.contains("number of transitions = 5"), "{err}");
    let out = petrinav(&["topo", "generate", "-3"]);
    assert_eq!(out.status.code(), Some(2));
}

/// Help text with its line breaks (clap wraps to the terminal) as spaces.
fn help(args: &[&str]) -> String {
    ok(args).split_whitespace().collect::<Vec<_>>().join(" ")
}

#[test]
fn help_teaches_with_examples() {
    let text = help(&["topo", "--help"]);
    for cmd in ["plan", "convert", "generate"] {
        assert!(text.contains(cmd), "{text}");
    }
    let text = help(&["topo", "plan", "--help"]);
    for needle in [
        "f(t) = min(1, C(t) + α(destination))",
        "f(t) > λ(t) is rejected",
        "--mode paper",
        "petrinav topo plan office.fpn.json --from p1 --to p50",
        "Repeat for several goals",
    ] {
        assert!(text.contains(needle), "{needle}: {text}");
    }
    let text = help(&["topo", "convert", "--help"]);
    assert!(
        text.contains("petrinav topo convert office.fpn.json office.pnml"),
        "{text}"
    );
    let text = help(&["topo", "generate", "--help"]);
    assert!(text.contains("--seed"), "{text}");
}
