//! What each fuzz target does with its input: read it with the reader as a
//! user's file would be read, then use what was read the way the commands
//! do (write it back, instantiate, explore, solve, plan, learn, decide).
//! Any outcome is fine — `Ok` or an error — except a panic, an abort
//! (allocation failures included: libFuzzer's malloc limit catches
//! them), a hang, or a non-finite number where the engine promises
//! finite ones (issue 17), which these functions assert.
//!
//! Included by the fuzz crate (`fuzz/src/lib.rs`) and, on stable, by the
//! regression test `crates/lab/tests/fuzz_regressions.rs`; uses only
//! crates both have.

use std::path::PathBuf;
use std::sync::OnceLock;

use petri::io::Format;
use petri::{CompiledGspn, ExploreParams, Expr, Params, Properties, ReachabilityGraph, SolveParams};

/// What a target does with one input.
pub type Target = fn(&[u8]);

/// Every target, by the name of its folder in `fuzz/regressions/` and of
/// its binary in `fuzz/fuzz_targets/`.
pub const TARGETS: &[(&str, Target)] = &[
    ("pnpro", pnpro),
    ("pnml", pnml),
    ("toml_net", toml_net),
    ("expr", expr),
    ("map_yaml", map_yaml),
    ("map_image", map_image),
    ("scenario", scenario),
    ("places", places),
    ("mission_log", mission_log),
    ("results", results),
    ("fpn_map", fpn_map),
    ("drn", drn),
    ("policy", policy),
    ("bt_xml", bt_xml),
    ("bt_params", bt_params),
    ("bt_log", bt_log),
];

/// Largest state space a fuzzed net is explored to: enough to reach the
/// solver with vanishing loops and bottom components, fast per input.
const MAX_STATES: usize = 400;

/// A GreatSPN project file (`petri::io::read_str`, as `read_file` does).
pub fn pnpro(data: &[u8]) {
    net(data, Format::Pnpro);
}

/// A PNML file.
pub fn pnml(data: &[u8]) {
    net(data, Format::Pnml);
}

/// A net in petrinav's TOML format.
pub fn toml_net(data: &[u8]) {
    net(data, Format::Toml);
}

fn net(data: &[u8], format: Format) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(net) = petri::io::read_str(text, format, "fuzz") else {
        return;
    };
    // What `gspn convert` and `gspn dot` do.
    for f in [Format::Pnpro, Format::Pnml, Format::Toml] {
        if let Ok(written) = petri::io::write_string(&net, f) {
            let _ = petri::io::read_str(&written, f, "round trip");
        }
    }
    let _ = petri::io::write_dot(&net);
    // What `gspn info` and `gspn solve --default-rate 1` do, on a small
    // state space.
    let Ok(gspn) = net.instantiate(&Params::new()) else {
        return;
    };
    let Ok(rates) = gspn.rates(&Params::new(), Some(1.0)) else {
        return;
    };
    let Ok(rg) = ReachabilityGraph::explore(
        &gspn,
        &ExploreParams {
            max_states: MAX_STATES,
            ..ExploreParams::default()
        },
    ) else {
        return;
    };
    let _ = Properties::of(&gspn, &rg);
    let Ok(compiled) = CompiledGspn::from_graph(gspn, rg) else {
        return;
    };
    if let Ok(sol) = compiled.solve_rates(&rates, &SolveParams::default()) {
        let all = sol
            .pi
            .iter()
            .chain(&sol.throughput)
            .chain(&sol.mean_tokens)
            .chain(&sol.prob_nonempty)
            .chain(&sol.bottom_probabilities);
        for &x in all.chain([&sol.info.residual, &sol.absorption_residual]) {
            assert!(x.is_finite(), "a solution holds {x}");
        }
        let sum: f64 = sol.pi.iter().sum();
        assert!(sol.pi.is_empty() || (sum - 1.0).abs() < 1e-6, "Σπ = {sum}");
    }
}

/// An expression (rates, weights, markings, measures): parsed, printed and
/// parsed again, compiled against a four-place net, evaluated.
pub fn expr(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(e) = Expr::parse(text) else {
        return;
    };
    let printed = e.to_string();
    let again = Expr::parse(&printed);
    assert!(
        again.is_ok(),
        "`{text}` printed as `{printed}`, which does not parse: {again:?}"
    );
    let places = ["P0", "P1", "P2", "P3"];
    let lookup = |n: &str| match n {
        "a" => Some(2.0),
        "N" => Some(3.0),
        _ => None,
    };
    let _ = e.eval_params(&lookup, "the fuzzed expression");
    if let Ok(c) = e.compile(&|n| places.iter().position(|p| *p == n), &lookup) {
        let mut stack = Vec::new();
        for marking in [[0, 0, 0, 0], [1, 2, 3, 4], [u32::MAX, 0, 7, 1]] {
            let _ = c.eval(&marking, &mut stack);
        }
    }
}

/// A map_server YAML file.
pub fn map_yaml(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let _ = sim::map_server::parse_yaml(text, "fuzz.yaml");
}

/// A map image (PNG or PGM), turned into a grid as `map_server::load` does.
pub fn map_image(data: &[u8]) {
    static YAML: OnceLock<sim::map_server::MapYaml> = OnceLock::new();
    let yaml = YAML.get_or_init(|| {
        sim::map_server::parse_yaml(
            "image: m.pgm\nresolution: 0.05\norigin: [-1.0, 2.0, 0.5]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n",
            "fuzz.yaml",
        )
        .expect("the fixed YAML parses")
    });
    let Ok(pixels) = sim::map_server::decode_image(data) else {
        return;
    };
    if let Ok((grid, occupancy)) = sim::map_server::grid_from_pixels(yaml, &pixels) {
        assert_eq!(occupancy.len(), grid.width() * grid.height());
    }
}

/// A scenario file (`lab run my_scenario.toml`), with no folder to resolve
/// a map file against.
pub fn scenario(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let _ = lab::scenario::Scenario::parse(text, "fuzz.toml", None);
}

/// A places file (`name: [x, y, theta]`).
pub fn places(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok(places) = sim::places::Places::parse(text, "places.yaml") {
        for p in places.iter() {
            assert!(places.get(&p.name).is_some());
        }
    }
}

/// The file an input is written to, as logs and results are files: one
/// per target and process.
fn temp_file(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("petrinav-fuzz-{name}-{}", std::process::id()))
}

/// A tour guide's mission log (read from a file, as the log is) for either
/// shipped supervisor net — each line checked as data — then the rates
/// learnt from it and the supervisor's decision on them, which must be
/// taken on finite numbers.
pub fn mission_log(data: &[u8]) {
    use guide::supervisor::credit::CreditSupervisor;
    use guide::supervisor::credit_learning::CreditModel;
    static SUPERVISORS: OnceLock<(guide::supervisor::Supervisor, CreditSupervisor)> = OnceLock::new();
    static PATH: OnceLock<PathBuf> = OnceLock::new();
    let (source, credit) = SUPERVISORS.get_or_init(|| {
        (
            guide::supervisor::Supervisor::new().expect("the shipped net compiles"),
            CreditSupervisor::new().expect("the shipped crediting net compiles"),
        )
    });
    let path = PATH.get_or_init(|| temp_file("mission-log.jsonl"));
    if std::fs::write(path, data).is_err() {
        return;
    }
    if let Ok(log) = guide::supervisor::log::MissionLog::read(path, source.net_id()) {
        let _ = (log.missions(), log.next_mission(), log.notices());
        if let Ok(learned) = guide::supervisor::learning::learn_or_prior(log.entries())
            && let Ok(d) = source.decide(&learned.rates)
        {
            for x in [d.f_auto, d.f_cont, d.u_auto, d.u_cont, d.p_loc_succ, d.p_loc_warn] {
                assert!(x.is_finite(), "the decision {d:?} holds {x}");
            }
        }
    }
    if let Ok(log) = guide::supervisor::log::MissionLog::read(path, credit.net_id())
        && let Ok(model) = CreditModel::learn(log.entries())
    {
        for context in 0..guide::supervisor::shrinkage::CONTEXTS {
            let rates = model.rates("fuzz", context, 10.0, 10.0);
            for localized in [true, false] {
                if let Ok(d) = credit.decide_with(&rates.automove, &rates.contour, localized) {
                    for x in [d.f_auto, d.f_cont, d.p_success, d.p_loc_warn] {
                        assert!(x.is_finite(), "the decision {d:?} holds {x}");
                    }
                }
            }
        }
    }
}

/// A results file (`results.jsonl` of `lab report`): read, checked against
/// a batch of three runs (`e1/field01#0`, `e1/field02#0`,
/// `e1/field03#0`, the keys of the seed), grouped and summarised; every
/// interval of a summary must be a number or absent.
pub fn results(data: &[u8]) {
    static PATH: OnceLock<PathBuf> = OnceLock::new();
    let path = PATH.get_or_init(|| temp_file("results.jsonl"));
    if std::fs::write(path, data).is_err() {
        return;
    }
    let Ok((lines, _)) = lab::runner::read_results(path) else {
        return;
    };
    let scenarios: Vec<String> = ["e1/field01", "e1/field02", "e1/field03"]
        .map(String::from)
        .to_vec();
    let keys: Vec<String> = scenarios.iter().map(|s| format!("{s}#0")).collect();
    if lab::record::check_lines(path, &lines, &keys, "fuzz").is_err() {
        return;
    }
    let Ok(runs) = lab::record::group(&lines) else {
        return;
    };
    for s in lab::summary::summarise(&scenarios, &runs) {
        let _ = lab::tables::csv(std::slice::from_ref(&s));
    }
}

/// A topological map file (fuzzy Petri net, JSON): read, written back and
/// read again, exported, and a route planned in both modes from the first
/// place to the last.
pub fn fpn_map(data: &[u8]) {
    use topo::{FuzzyPetriNet, PlaceId, PlanMode};
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(net) = FuzzyPetriNet::from_json(text) else {
        return;
    };
    let written = net.to_json();
    let again = FuzzyPetriNet::from_json(&written);
    assert!(again.is_ok(), "a map written back does not read: {again:?}");
    let _ = topo::to_dot(&net, None);
    if net.num_places() > 0 {
        let last = PlaceId(net.num_places() as u32 - 1);
        for mode in [PlanMode::Optimal, PlanMode::Paper] {
            if let Ok(plan) = topo::plan(&net, PlaceId(0), &[last], mode) {
                let _ = topo::to_dot(&net, Some(&plan));
            }
        }
    }
}

/// Largest DRN model a fuzzed file is solved on.
const MAX_DRN_STATES: usize = 400;

/// A Storm DRN file (`petri::io::drn::read_drn`, with a 64 MiB memory
/// guard): written back and read again (must read), then, when small,
/// solved for a reachability, an expected-time and a long-run property on
/// its first label: every value a number or ±∞ where promised, bounds in
/// order.
pub fn drn(data: &[u8]) {
    use petri::io::drn::{DrnParams, read_drn, write_drn};
    use petri::mdp::{OptimizeParams, Property};
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let params = DrnParams { max_memory: 64 << 20 };
    let Ok(model) = read_drn(text, "fuzz", &params) else {
        return;
    };
    let mut written = Vec::new();
    write_drn(&model, &mut written, None).expect("a model read writes");
    let again = read_drn(
        std::str::from_utf8(&written).expect("UTF-8"),
        "round trip",
        &params,
    );
    assert!(again.is_ok(), "a written model does not read back: {again:?}");
    if model.num_states() > MAX_DRN_STATES {
        return;
    }
    let label = model
        .labels()
        .first()
        .map_or("init".to_string(), |l| l.name.clone());
    for text in [
        format!("Pmax=? [F \"{label}\"]"),
        format!("Tmin=? [F \"{label}\"]"),
        format!("LRAmin=? [\"{label}\"]"),
    ] {
        let Ok(p) = Property::parse(&text) else { continue };
        if let Ok(o) = model.check(&p, &OptimizeParams::default()) {
            for s in 0..model.num_states() {
                let (l, u) = (o.lower[s], o.upper[s]);
                assert!(
                    !l.is_nan() && !u.is_nan() && l <= u,
                    "{text}: state {s} in [{l}, {u}]"
                );
            }
        }
    }
}

/// The net policies are checked against: the worked example of
/// docs/gspn.md (a choice of two decisions and a random switch).
const POLICY_NET: &str = r##"
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
[[transition]]
name = "again"
rate = 1
inputs = ["done"]
outputs = ["idle"]
"##;

/// A policy file (`petri::Policy::parse`), bound to a small net with a
/// choice, the net run under it: explored, compiled, solved (what `gspn
/// solve --policy` does); the solution's numbers must be finite.
pub fn policy(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(p) = petri::Policy::parse(text, "fuzz") else {
        return;
    };
    let _ = p.to_json();
    let net = petri::io::read_str(POLICY_NET, Format::Toml, "worked.toml").expect("the policy net reads");
    let gspn = net
        .instantiate(&Params::new())
        .expect("the policy net instantiates");
    let Ok(under) = gspn.with_policy(p) else {
        return;
    };
    let explore = ExploreParams {
        max_states: MAX_STATES,
        ..ExploreParams::default()
    };
    let Ok(compiled) = CompiledGspn::build(&under, &explore) else {
        return;
    };
    if let Ok(sol) = compiled.solve(&Params::new(), None, &SolveParams::default()) {
        for &x in sol.pi.iter().chain(&sol.throughput) {
            assert!(x.is_finite(), "a solution holds {x}");
        }
    }
}

/// A behaviour-tree XML file (`bt::read_str`, subtrees missing or cyclic
/// kept as `bt check` reads them): checked, then — when it reads strictly —
/// translated, analysed within 2,000 markings (every probability and time
/// finite) and simulated a few times within bounded events.
pub fn bt_xml(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let lenient = bt::ReadOptions {
        keep_missing: true,
        max_nodes: 2_000,
        ..bt::ReadOptions::default()
    };
    if let Ok(tree) = bt::read_str(text, "fuzz.xml", None, &lenient) {
        let _ = bt::check(&tree, None, &bt::check::CheckOptions::nav2());
        let _ = bt::svg::render(&tree, None);
    }
    let strict = bt::ReadOptions {
        max_nodes: 2_000,
        ..bt::ReadOptions::default()
    };
    let Ok(tree) = bt::read_str(text, "fuzz.xml", None, &strict) else {
        return;
    };
    bt_analyze(&tree, &bt::TreeParams::default());
}

fn bt_analyze(tree: &bt::Tree, params: &bt::TreeParams) {
    let options = bt::AnalyzeOptions {
        sensitivities: false,
        quantiles: vec![0.5],
        max_states: 2_000,
    };
    if let Ok(r) = bt::analyze(tree, params, &options) {
        for x in [
            r.p_success,
            r.p_failure,
            r.p_never,
            r.mean_time,
            r.mean_time_success,
            r.mean_time_failure,
        ] {
            assert!(x.is_finite(), "a tree's analysis holds {x}: {r:?}");
        }
    }
    let limits = bt::montecarlo::Limits {
        max_events: 10_000,
        max_time: 1e6,
    };
    let _ = bt::montecarlo::estimate(tree, params, 3, 1, limits);
}

/// The tree every sidecar and log of the fuzz targets is applied to.
const BT_TREE: &str = r#"<root BTCPP_format="4"><BehaviorTree ID="T">
<ReactiveSequence><IsOk/><Fallback><A/><RetryUntilSuccessful num_attempts="3"><B/></RetryUntilSuccessful></Fallback></ReactiveSequence>
</BehaviorTree></root>"#;

/// A parameter sidecar (`bt::TreeParams::parse`), applied to a small tree.
pub fn bt_params(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(params) = bt::TreeParams::parse(text, "fuzz.toml") else {
        return;
    };
    let tree = bt::read_str(BT_TREE, "t.xml", None, &bt::ReadOptions::default()).expect("the fixed tree");
    bt_analyze(&tree, &params);
}

/// Logs: our JSONL, BehaviorTree.CPP's FileLogger2 and Minitrace; fitted
/// to a small tree, the sidecar written must read back.
pub fn bt_log(data: &[u8]) {
    let tree = bt::read_str(BT_TREE, "t.xml", None, &bt::ReadOptions::default()).expect("the fixed tree");
    let mut all = Vec::new();
    if let Ok(t) = bt::logs::read_btlog(data, "fuzz.btlog", 0) {
        all.extend(t);
    }
    if let Ok(text) = std::str::from_utf8(data) {
        if let Ok(t) = bt::logs::read_jsonl(text, "fuzz.jsonl") {
            all.extend(t);
        }
        if let Ok(t) = bt::logs::read_minitrace(text, "fuzz.json", 1) {
            all.extend(t);
        }
    }
    let fit = bt::logs::fit(&tree, &all);
    let written = fit.to_toml();
    let again = bt::TreeParams::parse(&written, "fit.toml");
    assert!(
        again.is_ok(),
        "a fitted sidecar does not read: {again:?}\n{written}"
    );
}
