//! Analysis of Nav2's largest shipped tree (`navigate_on_route_graph_w_recovery.xml`)
//! and of the most used one, with the nominal parameters: with and without
//! sensitivities. Figures in `crates/bt/BENCHMARKS.md`.

use bt::{AnalyzeOptions, ReadOptions, Tree, TreeParams};

fn main() {
    divan::main();
}

const DIR: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../models/bt/nav2");

fn load(file: &str) -> (Tree, TreeParams) {
    let tree = bt::read_file(format!("{DIR}/{file}"), &ReadOptions::default()).expect("a shipped tree");
    let params = TreeParams::read_file(format!("{DIR}/nominal.toml")).expect("the shipped parameters");
    (tree, params)
}

#[divan::bench(args = ["navigate_on_route_graph_w_recovery.xml", "navigate_to_pose_w_replanning_and_recovery.xml"])]
fn analyze_without_sensitivities(bencher: divan::Bencher, file: &str) {
    let (tree, params) = load(file);
    let options = AnalyzeOptions {
        sensitivities: false,
        ..AnalyzeOptions::default()
    };
    bencher.bench(|| bt::analyze(&tree, &params, &options).expect("analysis"));
}

#[divan::bench(args = ["navigate_on_route_graph_w_recovery.xml", "navigate_to_pose_w_replanning_and_recovery.xml"], sample_count = 10)]
fn analyze_with_sensitivities(bencher: divan::Bencher, file: &str) {
    let (tree, params) = load(file);
    let options = AnalyzeOptions::default();
    bencher.bench(|| bt::analyze(&tree, &params, &options).expect("analysis"));
}
