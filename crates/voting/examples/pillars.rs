//! The voting controller on AIBOT (IR detectors, three sonars, odometry)
//! crossing a 10 m × 6 m room with three pillars to a goal, in the
//! simulator.
//!
//! ```text
//! cargo run -p voting --example pillars -- [SEED] [EXPERIMENT]
//! cargo run -p voting --example pillars -- 3 2
//! ```
//!
//! `EXPERIMENT` is the source's team (1: IR + odometry; 2: sonar +
//! odometry; 3: IR + sonar + odometry; 4: all, with planning; default 4).
//! Prints how the run ended, its time, path length and collisions.

use robot::{Pose, Vec2};
use sim::shapes::{CircleSpec, WorldSpec};
use sim::{RobotParams, RunParams, Simulation, Task, World};
use voting::{Teams, VotingController, VotingParams};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let seed: u64 = args.first().map(|s| s.parse()).transpose()?.unwrap_or(1);
    let experiment: u32 = args.get(1).map(|s| s.parse()).transpose()?.unwrap_or(4);
    let teams = Teams::experiment(experiment).ok_or("EXPERIMENT is 1, 2, 3 or 4")?;

    let mut spec = WorldSpec::new(10.0, 6.0, 0.05);
    spec.walls = true;
    for (x, y) in [(3.5, 3.2), (5.5, 2.4), (7.0, 3.6)] {
        spec.circles.push(CircleSpec { x, y, r: 0.4 });
    }
    let world = World::new(spec.rasterise()?);
    let task = Task {
        start: Pose::new(1.0, 3.0, 0.0),
        goal: Some(Vec2::new(9.0, 3.0)),
    };
    let run = RunParams {
        time_limit_s: 120.0,
        ..RunParams::default()
    };
    let mut sim = Simulation::new(&world, RobotParams::aibot(), run, task, seed)?;
    let mut controller = VotingController::new(VotingParams {
        teams,
        ..VotingParams::default()
    })?;
    let r = sim.run(&mut controller);
    println!(
        "{}: {:?} after {:.1} s, {:.2} m driven, {} collision(s)",
        teams.label(),
        r.outcome,
        r.time_s,
        r.path_length_m,
        r.collisions
    );
    Ok(())
}
