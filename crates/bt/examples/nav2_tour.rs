//! Reads, checks and analyses every Nav2 tree shipped in `models/bt/nav2`
//! with the nominal parameters, and prints one line per tree.
//!
//! Run: `cargo run --release -p bt --example nav2_tour`

use bt::check::CheckOptions;
use bt::{AnalyzeOptions, ReadOptions, TreeParams};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../../models/bt/nav2");
    let params = TreeParams::read_file(format!("{dir}/nominal.toml"))?;
    let mut files: Vec<_> = std::fs::read_dir(dir)
        .map_err(|source| bt::Error::Io {
            path: dir.into(),
            source,
        })?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "xml") && !p.ends_with("nav2_tree_nodes.xml"))
        .collect();
    files.sort();
    for f in files {
        let tree = bt::read_file(&f, &ReadOptions::default())?;
        let findings = bt::check(&tree, Some(&params), &CheckOptions::nav2());
        let start = std::time::Instant::now();
        let options = AnalyzeOptions {
            sensitivities: false,
            ..AnalyzeOptions::default()
        };
        match bt::analyze(&tree, &params, &options) {
            Ok(r) => println!(
                "{:<62} nodes {:>3} findings {} states {:>6} P(success) {:.4} P(never) {:.4} mean {:>8.2} s  ({:.1} ms)",
                f.file_name().unwrap_or_default().to_string_lossy(),
                tree.len(),
                findings.len(),
                r.states,
                r.p_success,
                r.p_never,
                r.mean_time,
                start.elapsed().as_secs_f64() * 1e3
            ),
            Err(e) => println!("{}: {e}", f.display()),
        }
    }
    Ok(())
}
