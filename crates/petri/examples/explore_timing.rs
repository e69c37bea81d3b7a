//! Times state-space generation alone, and the whole compilation, on a net
//! file, and prints a digest of the reachability graph (every marking in
//! its order, every edge's target, transition and coefficient bits) so two
//! builds can be compared for identical results:
//! `cargo run --release -p petri --example explore_timing -- net.toml 5 forced`
//! (rounds, and `forced` to pass through forced vanishing markings).

use std::hash::{DefaultHasher, Hasher};
use std::time::Instant;

use petri::{CompiledGspn, ExploreParams, MarkingId, Params, ReachabilityGraph};

fn digest(rg: &ReachabilityGraph) -> u64 {
    let mut h = DefaultHasher::new();
    for i in 0..rg.num_markings() {
        let m = MarkingId(i as u32);
        for c in rg.marking(m) {
            h.write_u32(c);
        }
        h.write_u8(u8::from(rg.is_vanishing(m)));
        for e in rg.edges(m) {
            h.write_u32(e.target.0);
            h.write_u32(e.transition.0);
            h.write_u64(e.coeff.to_bits());
        }
    }
    h.finish()
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let path = args
        .first()
        .ok_or("usage: explore_timing NET [ROUNDS] [forced]")?;
    let rounds: usize = args.get(1).map(|s| s.parse()).transpose()?.unwrap_or(5);
    let params = ExploreParams {
        skip_forced: args.get(2).map(String::as_str) == Some("forced"),
        ..ExploreParams::default()
    };
    let gspn = petri::io::read_file(path)?.instantiate(&Params::new())?;
    let mut explore = Vec::new();
    let mut build = Vec::new();
    for _ in 0..rounds {
        let t0 = Instant::now();
        let rg = ReachabilityGraph::explore(&gspn, &params)?;
        explore.push(t0.elapsed().as_secs_f64());
        let t0 = Instant::now();
        let compiled = CompiledGspn::build(&gspn, &params)?;
        build.push(t0.elapsed().as_secs_f64());
        std::hint::black_box(compiled);
        if explore.len() == 1 {
            println!(
                "{} markings ({} tangible), {} edges, digest {:016x}",
                rg.num_markings(),
                rg.num_tangible(),
                rg.num_edges(),
                digest(&rg)
            );
        }
    }
    let show = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        format!(
            "fastest {:.1} ms, median {:.1} ms",
            v[0] * 1e3,
            v[v.len() / 2] * 1e3
        )
    };
    println!("explore: {}", show(&mut explore));
    println!("build:   {}", show(&mut build));
    Ok(())
}
