//! Drives the AIBOT-like robot through a cluttered field with a fixed list
//! of commands, then prints the run's summary as JSON and the first ticks
//! of its trace as JSON lines.
//!
//! Run with `cargo run -p sim --example scripted_drive`.

use robot::{Command, Pose, Vec2};
use sim::{RobotParams, RunParams, ScriptedController, Simulation, Task, TraceParams, World, generators};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let world = World::new(generators::cluttered_field(10.0, 0.05, 0, 1)?);
    let task = Task {
        start: Pose::new(1.0, 1.0, 0.0),
        goal: Some(Vec2::new(2.2, 2.3)),
    };
    let run = RunParams {
        time_limit_s: 30.0,
        trace: TraceParams::poses(),
        ..RunParams::default()
    };
    let mut sim = Simulation::new(&world, RobotParams::aibot(), run, task, 1)?;
    let straight = Command::Twist {
        v_mps: 0.3,
        omega_radps: 0.0,
    };
    let mut script = ScriptedController::new(vec![
        (straight, 4.0),
        // About a quarter turn on the spot, left: ω = 0.2 m/s / 0.25 m.
        (
            Command::Wheels {
                left_mps: -0.1,
                right_mps: 0.1,
            },
            2.0,
        ),
        (straight, 4.0),
    ])?;
    let result = sim.run(&mut script);
    println!("{}", serde_json::to_string_pretty(&result)?);
    if let Some(trace) = sim.take_trace() {
        let first = sim::Trace {
            seed: trace.seed,
            ticks: trace.ticks.into_iter().take(3).collect(),
        };
        first.write_json_lines(std::io::stdout().lock())?;
    }
    Ok(())
}
