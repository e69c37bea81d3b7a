//! Times the stages of `bt analyze` on one shipped Nav2 tree: the
//! translation, the chain (generation and compilation), the transient
//! chain, the absorption, the Krylov stage of the quantiles (with its
//! number of block solves) and decoding every tangible marking (what the
//! nodes' activity reads). Fastest of `rounds` runs per stage, in ms.
//! Figures in `crates/bt/BENCHMARKS.md`.
//!
//! Run: `cargo run --release -p bt --example analyze_stages -- \
//! navigate_to_pose_w_replanning_goal_patience_and_recovery.xml degraded 10`
//! (`RAYON_NUM_THREADS=1` for one thread).

use std::time::Instant;

use bt::{ReadOptions, TreeParams};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../../models/bt/nav2");
    let mut args = std::env::args().skip(1);
    let file = args
        .next()
        .unwrap_or_else(|| "navigate_to_pose_w_replanning_goal_patience_and_recovery.xml".into());
    let set = args.next().unwrap_or_else(|| "nominal".into());
    let rounds: usize = args.next().map_or(Ok(10), |s| s.parse())?;
    let tree = bt::read_file(format!("{dir}/{file}"), &ReadOptions::default())?;
    let params = TreeParams::read_file(format!("{dir}/{set}.toml"))?;
    let names = [
        "translate",
        "chain",
        "transient",
        "absorption",
        "quantiles",
        "decode",
    ];
    let mut best = [f64::INFINITY; 6];
    let mut solves = 0;
    for _ in 0..rounds.max(1) {
        let t0 = Instant::now();
        let tr = bt::translate::translate(&tree, &params)?;
        let t1 = Instant::now();
        let (chain, rates) = bt::analyze::chain(&tr, usize::MAX)?;
        let t2 = Instant::now();
        let transient = chain.absorbing(&rates)?;
        let t3 = Instant::now();
        let a = transient.absorption()?;
        let t4 = Instant::now();
        // The levels of the quantiles 0.5, 0.9 and 0.99 of the runs that
        // end, the shift and horizon as `bt analyze` takes them.
        let ends: f64 = a.end_probability.iter().sum();
        let levels: Vec<f64> = [0.5, 0.9, 0.99].iter().map(|q| 1.0 - q * ends).collect();
        let s = transient.survival(0.25 * a.mean_time, 20.0 * a.mean_time, &levels, 1e-9)?;
        let t5 = Instant::now();
        let mut m = vec![0u32; tr.net.places.len()];
        let mut marked = 0usize;
        for st in 0..chain.num_tangible() {
            chain.tangible_marking_into(st, &mut m);
            marked += m.iter().filter(|&&c| c > 0).count();
        }
        let t6 = Instant::now();
        std::hint::black_box(marked);
        solves = s.solves();
        let stages = [t1 - t0, t2 - t1, t3 - t2, t4 - t3, t5 - t4, t6 - t5];
        for (b, d) in best.iter_mut().zip(stages) {
            *b = b.min(d.as_secs_f64() * 1e3);
        }
    }
    let line: Vec<String> = names
        .iter()
        .zip(best)
        .map(|(n, b)| format!("{n} {b:.1}"))
        .collect();
    println!("{file} {set}: {} ms; {solves} block solves", line.join(", "));
    Ok(())
}
