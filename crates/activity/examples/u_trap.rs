//! The priority-arbitrated controller on the 16-sonar ring robot facing a
//! U-shaped trap between it and its goal, in the simulator: the activity
//! trace detects dead-locks, each turning the potential-field recovery on.
//! Not every seed escapes within 180 s: seed 2 reaches the goal in about
//! 80 s with recovery and stays trapped without (`2 --no-recovery`); seed 1
//! stays trapped either way.
//!
//! ```text
//! cargo run -p activity --example u_trap -- [SEED] [--no-recovery]
//! cargo run -p activity --example u_trap -- 2
//! cargo run -p activity --example u_trap -- 2 --no-recovery
//! ```
//!
//! Prints how the run ended, its time, the trace's characteristic points
//! and the dead-locks it detected.

use activity::{PriorityController, PriorityParams};
use robot::{Pose, Vec2};
use sim::shapes::{SegmentSpec, WorldSpec};
use sim::{RobotParams, RunParams, Simulation, Task, World};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let recovery = !args.iter().any(|a| a == "--no-recovery");
    let seed: u64 = match args.iter().find(|a| !a.starts_with("--")) {
        Some(s) => s.parse()?,
        None => 1,
    };

    // A U open towards the robot, its bottom between the robot and the goal.
    let mut spec = WorldSpec::new(12.0, 8.0, 0.05);
    spec.walls = true;
    let wall = |from: [f64; 2], to: [f64; 2]| SegmentSpec {
        from,
        to,
        thickness: 0.1,
    };
    spec.segments = vec![
        wall([5.0, 2.5], [7.0, 2.5]),
        wall([7.0, 2.5], [7.0, 5.5]),
        wall([7.0, 5.5], [5.0, 5.5]),
    ];
    let world = World::new(spec.rasterise()?);
    let task = Task {
        start: Pose::new(2.0, 4.0, 0.0),
        goal: Some(Vec2::new(10.5, 4.0)),
    };
    let run = RunParams {
        time_limit_s: 180.0,
        ..RunParams::default()
    };
    let mut sim = Simulation::new(&world, RobotParams::sonar_ring(), run, task, seed)?;
    let mut controller = PriorityController::new(PriorityParams {
        recovery,
        ..PriorityParams::default()
    })?;
    let r = sim.run(&mut controller);
    println!(
        "recovery {}: {:?} after {:.1} s, {:.2} m driven, {} collision(s)",
        if recovery { "on" } else { "off" },
        r.outcome,
        r.time_s,
        r.path_length_m,
        r.collisions
    );
    println!(
        "{} characteristic points, dead-locks at {:?}",
        controller.trace().points().len(),
        controller.trace().deadlocks()
    );
    Ok(())
}
