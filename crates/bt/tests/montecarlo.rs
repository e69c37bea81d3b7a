//! Analytic against Monte Carlo (outcome 2 of issue 49): for every Nav2 tree
//! shipped in `models/bt/nav2` and two parameter sets (`nominal.toml`,
//! `degraded.toml`), P(success) and the mean time of the translation's CTMC
//! lie within the 99 % interval of simulated executions of the independent
//! tick-based interpreter.
//!
//! The fast test runs 4,000 executions per tree and set and, since it makes
//! 60 comparisons at once, widens each interval to 99.99 % (z = 3.89; a
//! Bonferroni bound keeps the chance of any false alarm near 0.6 %).
//! `cargo test -p bt --release --test montecarlo -- --ignored --nocapture`
//! runs the 100,000-execution version with per-comparison 99 % intervals,
//! as the issue asks, and prints every comparison; by chance alone about
//! one comparison in a hundred falls outside its 99 % interval, so it fails
//! only when more than two do.

use bt::montecarlo::{Limits, estimate};
use bt::{AnalyzeOptions, ReadOptions, TreeParams};

const DIR: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../models/bt/nav2");

fn trees() -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(DIR)
        .expect("models/bt/nav2")
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".xml") && n != "nav2_tree_nodes.xml")
        .collect();
    v.sort();
    v
}

/// z of a two-sided 99 % interval.
const Z99: f64 = 2.575_829_303_548_901;

/// Compares on `runs` executions with intervals `z` standard errors wide;
/// returns a line per comparison outside.
fn compare(file: &str, set: &str, runs: usize, z: f64) -> Vec<String> {
    let tree = bt::read_file(format!("{DIR}/{file}"), &ReadOptions::default()).expect("a shipped tree");
    let params = TreeParams::read_file(format!("{DIR}/{set}.toml")).expect("a shipped parameter set");
    let options = AnalyzeOptions {
        sensitivities: false,
        quantiles: vec![],
        ..AnalyzeOptions::default()
    };
    let r = bt::analyze(&tree, &params, &options).expect("analysis");
    let mc = estimate(&tree, &params, runs, 49, Limits::default()).expect("simulation");
    let mut bad = Vec::new();
    let line = format!(
        "{file} [{set}]: P(success) {:.5} vs {:.5} ± {:.5}; mean time {:.3} vs {:.3} ± {:.3}",
        r.p_success, mc.p_success, mc.p_success_hw, r.mean_time, mc.mean_time, mc.mean_time_hw
    );
    println!("{line}");
    // A degenerate proportion (0 or 1) has a zero-width interval: allow one run.
    let scale = z / Z99;
    let p_tol = (scale * mc.p_success_hw).max(1.0 / runs as f64);
    if (r.p_success - mc.p_success).abs() > p_tol {
        bad.push(format!("P(success): {line}"));
    }
    if (r.mean_time - mc.mean_time).abs() > (scale * mc.mean_time_hw).max(1e-9) {
        bad.push(format!("mean time: {line}"));
    }
    if mc.p_never > 0.0 || r.p_never > 1e-9 {
        bad.push(format!(
            "never ends: analytic {} simulated {}: {line}",
            r.p_never, mc.p_never
        ));
    }
    bad
}

fn all(runs: usize, z: f64, allowed: usize) {
    let mut bad = Vec::new();
    for file in trees() {
        for set in ["nominal", "degraded"] {
            bad.extend(compare(&file, set, runs, z));
        }
    }
    println!("{} comparisons outside their interval", bad.len());
    assert!(bad.len() <= allowed, "outside the interval:\n{}", bad.join("\n"));
}

#[test]
fn nav2_trees_analytic_within_the_simulated_interval() {
    all(4_000, 3.89, 0);
}

#[test]
#[ignore = "100,000 executions per tree and set: minutes in release"]
fn nav2_trees_analytic_within_the_simulated_interval_100k() {
    all(100_000, Z99, 2);
}
