//! Generates and solves one member of a scalable net family and prints the
//! figures: `cargo run --release -p petri --example family -- kanban 4`.

use std::time::Instant;

use petri::{CompiledGspn, ExploreParams, Method, Params, SolveParams, families};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let family = args.first().map(String::as_str).unwrap_or("kanban");
    let n: u32 = args.get(1).map(|s| s.parse()).transpose()?.unwrap_or(3);
    let method = match args.get(2).map(String::as_str) {
        Some("direct") => Method::Direct,
        Some("gs") => Method::GaussSeidel,
        Some("bicgstab") => Method::Bicgstab,
        _ => Method::Auto,
    };
    let net = match family {
        "kanban" => families::kanban(n),
        "fms" => families::fms(n, false),
        "philosophers" => families::philosophers(n),
        "robots" => families::robots_corridors(n, 3),
        other => return Err(format!("unknown family {other}").into()),
    };
    let t0 = Instant::now();
    let gspn = net.instantiate(&Params::new())?;
    if args.get(2).map(String::as_str) == Some("explore") {
        // State-space generation only.
        let rg = petri::ReachabilityGraph::explore(&gspn, &ExploreParams::default())?;
        let st = rg.stats();
        println!(
            "{family} {n}: {} markings ({} tangible), {} edges, explore {:.3} s ({:.2} M markings/s, {:.2} M tangible/s, {:.1} B/marking)",
            st.markings,
            st.tangible,
            st.edges,
            st.seconds,
            st.markings as f64 / st.seconds / 1e6,
            st.tangible as f64 / st.seconds / 1e6,
            st.bytes_per_marking
        );
        return Ok(());
    }
    let compiled = CompiledGspn::build(&gspn, &ExploreParams::default())?;
    let t1 = Instant::now();
    let st = compiled.stats();
    println!(
        "{family} {n}: {} markings ({} tangible, {} vanishing), {} edges, explore {:.3} s ({:.2} M markings/s, {:.1} B/marking), compile {:.3} s, {:.1} MB (matrix {:.2} B/entry, markings {:.1} B/marking)",
        st.explore.markings,
        st.explore.tangible,
        st.explore.vanishing,
        st.explore.edges,
        st.explore.seconds,
        st.explore.markings as f64 / st.explore.seconds / 1e6,
        st.explore.bytes_per_marking,
        st.compile_seconds,
        compiled.heap_bytes() as f64 / 1e6,
        st.matrix_bytes as f64 / st.entries as f64,
        st.marking_bytes as f64 / st.explore.markings as f64
    );
    let omega: f64 = std::env::var("OMEGA")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1.0);
    let tolerance: f64 = std::env::var("TOL")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1e-12);
    let params = SolveParams {
        method,
        omega,
        tolerance,
        ..SolveParams::default()
    };
    let sol = compiled.solve(&Params::new(), Some(1.0), &params)?;
    let t2 = Instant::now();
    println!(
        "solve: {} {} iterations, residual {:.2e}, {:.3} s; total {:.3} s",
        sol.info.method,
        sol.info.iterations,
        sol.info.residual,
        (t2 - t1).as_secs_f64(),
        (t2 - t0).as_secs_f64()
    );
    if std::env::var("PI_HASH").is_ok() {
        let h = sol.pi.iter().fold(0u64, |h, v| h.rotate_left(5) ^ v.to_bits());
        println!("pi hash {h:016x}");
    }
    // The benchmark measure of the Kanban family (issue 16, Storm's
    // `S=? [ Pm1 >= 1 ]`).
    if family == "kanban" {
        let expr = petri::Expr::parse("#Pm1 >= 1")?;
        println!("P(Pm1 >= 1) = {:.12}", compiled.measure(&sol, &expr)?);
    }
    // Where the memory went (`STATS=1`): bytes per tangible marking by
    // component, from the allocations (`petrinav gspn solve --stats` prints
    // the same table).
    if std::env::var("STATS").is_ok() {
        let acc = compiled.memory_account(Some(&sol));
        for p in &acc.parts {
            println!(
                "  {:<52} {:<10} {:>7.1} B/marking",
                p.component, p.stage, p.bytes_per_marking
            );
        }
        let per = |b: u64| b as f64 / acc.tangible_markings as f64;
        println!(
            "  generation {:.1}, transpose {:.1}, solve {:.1}, peak {:.1}, guard estimate {:.1} B/marking",
            per(acc.generation_bytes),
            per(acc.compile_bytes),
            per(acc.solve_bytes),
            per(acc.peak_bytes),
            per(acc.guard_estimate_bytes)
        );
    }
    Ok(())
}
