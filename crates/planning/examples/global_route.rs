//! The global route between two points of a real map, with its intermediate
//! goals, drawn to a PNG.
//!
//! ```text
//! cargo run -p planning --example global_route -- MAP X0 Y0 X1 Y1 [OUT.png]
//! cargo run -p planning --example global_route -- building_31 -17.2 14 -11 -3 route.png
//! ```
//!
//! `MAP` is `building_31`, `levine` (the maps shipped in
//! `maps/`) or the path of a map_server YAML file;
//! points are in metres, world frame. Prints the route's length, cost and
//! goals; draws the map, the route and its goals (red markers) to `OUT.png`
//! (default `global_route.png`).

use std::time::Instant;

use planning::{GlobalPlanner, RouteParams};
use robot::{Pose, Vec2};
use sim::map_server;
use sim::render::{MarkerKind, Picture};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() < 5 {
        return Err("usage: global_route MAP X0 Y0 X1 Y1 [OUT.png]".into());
    }
    let yaml = match args[0].as_str() {
        name @ ("building_31" | "levine") => {
            format!("{}/../../maps/{name}/{name}.yaml", env!("CARGO_MANIFEST_DIR"))
        }
        path => path.to_string(),
    };
    let number = |k: usize| -> Result<f64, Box<dyn std::error::Error>> {
        args[k]
            .parse::<f64>()
            .map_err(|e| format!("argument {k}: {e}").into())
    };
    let (start, goal) = (
        Vec2::new(number(1)?, number(2)?),
        Vec2::new(number(3)?, number(4)?),
    );
    let out = args.get(5).map_or("global_route.png", String::as_str);

    let grid = map_server::load(&yaml)?.grid;
    let map = grid.grid_map();
    let t = Instant::now();
    let mut planner = GlobalPlanner::new(&map, RouteParams::default())?;
    let t_cost = t.elapsed();
    let t = Instant::now();
    let route = planner.plan(start, goal)?;
    let t_route = t.elapsed();
    println!(
        "{} × {} cells; cost map {:.1} ms, route {:.1} ms ({} cells reached)",
        map.width(),
        map.height(),
        t_cost.as_secs_f64() * 1e3,
        t_route.as_secs_f64() * 1e3,
        route.navigation.reached_cells
    );
    println!(
        "length {:.2} m (through the goals {:.2} m), cost {:.2}, {} gradient steps, {} fallbacks",
        route.length_m,
        route.goals_length_m,
        route.cost,
        route.descent.gradient_steps,
        route.descent.fallback_steps
    );
    for (k, g) in route.goals.iter().enumerate() {
        println!("goal {k}: ({:.2}, {:.2})", g.x, g.y);
    }

    let poses: Vec<Pose> = route.path.iter().map(|p| Pose::new(p.x, p.y, 0.0)).collect();
    let mut picture = Picture::new(&grid);
    picture.trajectory(&poses, None).marker(start, MarkerKind::Start);
    for &g in &route.goals {
        picture.marker(g, MarkerKind::Goal);
    }
    picture.save(out)?;
    println!("wrote {out}");
    Ok(())
}
