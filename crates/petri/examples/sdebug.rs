use petri::*;
fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let fam = args.first().map(String::as_str).unwrap_or("fms");
    let n: u32 = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(1);
    let net = match fam { "kanban" => families::kanban(n), "fms" => families::fms(n, false), "fmst" => families::fms(n, true), _ => families::robots_corridors(n, 3) };
    let g = net.instantiate(&Params::new()).unwrap();
    let rates = g.rates(&Params::new(), Some(1.0)).unwrap();
    let mut sp = StructuredParams::default();
    if let Ok(perm) = std::env::var("PERM") {
        let s0 = Structure::detect(&g, &StructureParams::default()).unwrap();
        let comps = s0.components();
        let part: Vec<Vec<PlaceId>> = perm.chars().map(|c| comps[c.to_digit(10).unwrap() as usize].places.clone()).collect();
        sp.structure.partition = Some(part);
    }
    if let Ok(part) = std::env::var("PART") {
        let v: Vec<Vec<PlaceId>> = part.split(';').map(|c| c.split(',').map(|n| g.place(n.trim()).unwrap()).collect()).collect();
        sp.structure.partition = Some(v);
    }
    let t = std::time::Instant::now();
    let s = StructuredGspn::build(&g, &sp, Interrupt::NEVER).unwrap();
    println!("{:?} build {:.3}s", s.stats(), t.elapsed().as_secs_f64());
    let omega: f64 = std::env::var("OMEGA").ok().and_then(|v| v.parse().ok()).unwrap_or(1.0);
    let tol: f64 = std::env::var("TOL").ok().and_then(|v| v.parse().ok()).unwrap_or(1e-12);
    let p = SolveParams { method: if std::env::var("OMEGA").is_ok() { Method::GaussSeidel } else { Method::Auto }, omega, tolerance: tol, max_iterations: 3000, ..SolveParams::default() };
    let t = std::time::Instant::now();
    match s.solve_rates(&rates, &p, Interrupt::NEVER) {
        Ok(sol) => {
            println!("{:?} omega {} hist {:?} agg {} {:.3}s", sol.info, sol.omega, sol.omega_history, sol.aggregations, t.elapsed().as_secs_f64());
            if fam == "kanban" { println!("P(Pm1>=1) = {:.12}", s.measure(&sol, &Expr::parse("#Pm1 >= 1").unwrap()).unwrap()); }
        }
        Err(e) => println!("err {e}"),
    }
    if std::env::var("EXPLICIT").is_ok() {
        let c = CompiledGspn::build(&g, &ExploreParams::default()).unwrap();
        let sol = c.solve_rates(&rates, &SolveParams::default()).unwrap();
        println!("explicit {:?} tangible {}", sol.info, c.num_tangible());
    }
}
