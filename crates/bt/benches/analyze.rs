//! Analysis of Nav2's five largest shipped trees — the one with the most
//! nodes (`navigate_on_route_graph_w_recovery.xml`), the two 5,520-state
//! ones and the two largest chains (the goal-patience and the
//! consistent-replanning trees, 14,640 states each) —
//! with both parameter sets, without sensitivities (the target of issue
//! 49: ≤ 100 ms each); with the sidecar's defaults (every condition drawn
//! at each evaluation: no condition state in the chain); and with
//! sensitivities on the first two. Figures in `crates/bt/BENCHMARKS.md`.

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
