//! Analysis of Nav2's five largest shipped trees — the one with the most
//! nodes (`navigate_on_route_graph_w_recovery.xml`), the two 5,520-state
//! ones and the two largest chains (the goal-patience and the
//! consistent-replanning trees, 14,640 states each) —
//! with both parameter sets, without sensitivities (the target of issue
//! 49: ≤ 100 ms each); with the sidecar's defaults (every condition drawn
//! at each evaluation: no condition state in the chain); and with
//! sensitivities on the first two; and `bt check` (the shipped trees, and
//! a Fallback 20,000 and 99,000 actions wide). Figures in
//! `crates/bt/BENCHMARKS.md`.

use bt::{AnalyzeOptions, ReadOptions, Tree, TreeParams};

fn main() {
    divan::main();
}

const DIR: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../models/bt/nav2");

/// The five largest shipped trees (`models/bt/nav2/largest.txt`).
fn largest() -> Vec<&'static str> {
    include_str!("../../../models/bt/nav2/largest.txt")
        .lines()
        .filter(|l| !l.trim().is_empty() && !l.starts_with('#'))
        .collect()
}

/// The tree `file` and the parameter set `set` (`""`: the defaults).
fn load(file: &str, set: &str) -> (Tree, TreeParams) {
    let tree = bt::read_file(format!("{DIR}/{file}"), &ReadOptions::default()).expect("a shipped tree");
    let params = if set.is_empty() {
        TreeParams::default()
    } else {
        TreeParams::read_file(format!("{DIR}/{set}.toml")).expect("the shipped parameters")
    };
    (tree, params)
}

fn without_sensitivities(bencher: divan::Bencher, file: &str, set: &str) {
    let (tree, params) = load(file, set);
    let options = AnalyzeOptions {
        sensitivities: false,
        ..AnalyzeOptions::default()
    };
    bencher.bench(|| bt::analyze(&tree, &params, &options).expect("analysis"));
}

#[divan::bench(args = largest(), sample_count = 20)]
fn analyze_nominal(bencher: divan::Bencher, file: &str) {
    without_sensitivities(bencher, file, "nominal");
}

#[divan::bench(args = largest(), sample_count = 20)]
fn analyze_degraded(bencher: divan::Bencher, file: &str) {
    without_sensitivities(bencher, file, "degraded");
}

#[divan::bench(args = largest(), sample_count = 20)]
fn analyze_defaults(bencher: divan::Bencher, file: &str) {
    without_sensitivities(bencher, file, "");
}

#[divan::bench(args = ["navigate_on_route_graph_w_recovery.xml", "navigate_to_pose_w_replanning_and_recovery.xml"], sample_count = 5)]
fn analyze_with_sensitivities(bencher: divan::Bencher, file: &str) {
    let (tree, params) = load(file, "nominal");
    let options = AnalyzeOptions::default();
    bencher.bench(|| bt::analyze(&tree, &params, &options).expect("analysis"));
}

/// `bt check` on every shipped Nav2 tree, and on a Fallback of `n` actions
/// that each read and write entries of their own (the shape on which the
/// read-before-write flow was quadratic: 73 s at 20,000 before it counted
/// entries as bits and subtrees as ranges).
#[divan::bench(args = [0, 20_000, 99_000], sample_count = 5)]
fn check(bencher: divan::Bencher, n: usize) {
    let trees: Vec<Tree> = if n == 0 {
        std::fs::read_dir(DIR)
            .expect("models/bt/nav2")
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|x| x == "xml") && !p.ends_with("nav2_tree_nodes.xml"))
            .map(|p| bt::read_file(p, &ReadOptions::default()).expect("a shipped tree"))
            .collect()
    } else {
        let leaves: String = (0..n)
            .map(|i| format!("<ComputePathToPose goal=\"{{g{i}}}\" path=\"{{p{i}}}\"/>"))
            .collect();
        let xml = format!(
            "<root BTCPP_format=\"4\" main_tree_to_execute=\"M\"><BehaviorTree ID=\"M\"><Fallback>{leaves}</Fallback></BehaviorTree></root>"
        );
        vec![bt::read_str(&xml, "wide.xml", None, &ReadOptions::default()).expect("the wide tree")]
    };
    let options = bt::check::CheckOptions::nav2();
    bencher.bench(|| {
        trees
            .iter()
            .map(|t| bt::check(t, None, &options).len())
            .sum::<usize>()
    });
}
