//! The solving stages of the goal-patience tree's analysis, timed apart
//! from the state-space generation: the absorption (two block solves of
//! `x (−Q_TT) = b`), the quantiles 0.5, 0.9 and 0.99 from the Krylov
//! space `bt analyze` builds (`absorption_survival`: shift a quarter of
//! the mean time, sizes agreeing to 1e-9), and for comparison the time
//! distribution on the grid it used before (`absorption_cdf_steps`: 25
//! steps per mean time, up to the 0.99 quantile). The chain is built once
//! from the shipped tree and nominal parameters. Figures in
//! `crates/bt/BENCHMARKS.md`.

use bt::{AnalyzeOptions, ReadOptions, TreeParams};
use petri::CompiledGspn;

fn main() {
    divan::main();
}

const DIR: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../models/bt/nav2");
const TREE: &str = "navigate_to_pose_w_replanning_goal_patience_and_recovery.xml";

/// The goal-patience tree's compiled chain and its rates.
fn chain() -> (CompiledGspn, Vec<f64>) {
    let tree = bt::read_file(format!("{DIR}/{TREE}"), &ReadOptions::default()).expect("a shipped tree");
    let params = TreeParams::read_file(format!("{DIR}/nominal.toml")).expect("the shipped parameters");
    let tr = bt::translate::translate(&tree, &params).expect("a translation");
    bt::analyze::chain(&tr, AnalyzeOptions::default().max_states).expect("a chain")
}

#[divan::bench(sample_count = 20)]
fn absorption(bencher: divan::Bencher) {
    let (compiled, rates) = chain();
    bencher.bench(|| compiled.absorption(&rates).expect("absorption"));
}

#[divan::bench(sample_count = 20)]
fn quantiles_krylov(bencher: divan::Bencher) {
    let (compiled, rates) = chain();
    let a = compiled.absorption(&rates).expect("absorption");
    let p_end: f64 = a.end_probability.iter().sum();
    let levels: Vec<f64> = [0.5, 0.9, 0.99].iter().map(|q| 1.0 - q * p_end).collect();
    bencher.bench(|| {
        compiled
            .absorption_survival(&rates, 0.25 * a.mean_time, 20.0 * a.mean_time, &levels, 1e-9)
            .expect("survival")
    });
}

#[divan::bench(sample_count = 20)]
fn time_distribution(bencher: divan::Bencher) {
    let (compiled, rates) = chain();
    let a = compiled.absorption(&rates).expect("absorption");
    let p_end: f64 = a.end_probability.iter().sum();
    let h = a.mean_time / 25.0;
    bencher.bench(|| {
        compiled
            .absorption_cdf_steps(&rates, h, 500, 0.99 * p_end)
            .expect("time distribution")
    });
}
