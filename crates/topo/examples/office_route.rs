//! A route planned on a random office-like topological map, in the
//! source's paper mode and in optimal mode.
//!
//! ```text
//! cargo run -p topo --example office_route -- [PLACES] [TRANSITIONS] [SEED]
//! cargo run -p topo --example office_route -- 400 1600 7
//! ```
//!
//! Prints, for each mode, the route's places, its number of transitions and
//! its cost `C` (the sum of the normalised transition costs).

use topo::{PlaceId, PlanMode, plan, random_office_like};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let arg = |i: usize, default: u64| -> Result<u64, Box<dyn std::error::Error>> {
        Ok(args.get(i).map(|s| s.parse()).transpose()?.unwrap_or(default))
    };
    let (n_places, n_transitions, seed) = (arg(0, 100)? as usize, arg(1, 400)? as usize, arg(2, 1)?);
    let map = random_office_like(n_places, n_transitions, seed)?;
    let start = PlaceId(0);
    let goal = PlaceId(map.num_places() as u32 - 1);
    println!(
        "{} places, {} transitions; from {} to {}",
        map.num_places(),
        map.num_transitions(),
        map.place(start).name,
        map.place(goal).name
    );
    for mode in [PlanMode::Paper, PlanMode::Optimal] {
        let route = plan(&map, start, &[goal], mode)?;
        let names: Vec<&str> = route.places.iter().map(|&p| map.place(p).name.as_str()).collect();
        println!(
            "{mode:?}: {} transitions, C = {:.5}: {}",
            route.route.len(),
            route.cost,
            names.join(" → ")
        );
    }
    Ok(())
}
