//! What the behaviour activity trace costs (docs/activity-trace.md): control
//! ticks per second with and without it, for both controllers, on a
//! dead-lock-suite world (8 m × 6 m floor at 0.05 m, one U trap across the
//! course, drawn once from a fixed seed).
//!
//! - `loops/*`: whole control ticks (sensing, controller, integration,
//!   collisions) of the simulator; a run that ends (goal, collision) is
//!   replaced by a fresh one with the next seed, so every sample is
//!   `TICKS` ticks of real trap runs.
//! - `steps/*`: the controller alone, fed 1,000 perceptions recorded from
//!   the plain controller's runs (open loop; plain and traced get the same
//!   inputs), so the trace's own cost is not hidden behind the sensors'.
//!
//! `plain` is the controller without the trace (priority: `detect = false`;
//! voting: the bare `VotingController`), `trace` with detection and
//! recovery. Figures: `crates/lab/BENCHMARKS.md`. Run with
//! `cargo bench -p lab --bench trace`.

use std::cell::Cell as SeedCell;

use activity::{PriorityController, PriorityParams};
use divan::Bencher;
use divan::counter::ItemsCount;
use lab::traps::{TrapKind, TrapSpec};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use robot::{Controller, Notes, Perception, Pose, Vec2};
use sim::shapes::WorldSpec;
use sim::{RobotParams, RunParams, Simulation, Task, World};
use voting::trace_layer::TracedVoting;
use voting::{VotingController, VotingParams};

fn main() {
    divan::main();
}

/// Ticks per sample.
const TICKS: usize = 1000;

const START: Pose = Pose {
    x_m: 1.0,
    y_m: 3.0,
    theta_rad: 0.0,
};
const GOAL: Vec2 = Vec2 { x: 7.0, y: 3.0 };

fn trap_world() -> World {
    let mut spec = WorldSpec::new(8.0, 6.0, 0.05);
    spec.walls = true;
    let trap = TrapSpec {
        kinds: vec![TrapKind::U],
        depth_m: [1.4, 1.4],
        width_m: [1.6, 1.6],
        angle_deg: [0.0, 0.0],
        position: [0.5, 0.5],
        ..TrapSpec::default()
    };
    trap.draw(
        START.position(),
        GOAL,
        &mut spec,
        &mut ChaCha8Rng::seed_from_u64(1),
    );
    World::new(spec.rasterise().expect("the bench world rasterises"))
}

#[derive(Clone, Copy, Debug)]
enum Kind {
    PriorityPlain,
    PriorityTrace,
    VotingPlain,
    VotingTrace,
}

impl Kind {
    fn robot(self) -> RobotParams {
        match self {
            Kind::PriorityPlain | Kind::PriorityTrace => RobotParams::sonar_ring(),
            Kind::VotingPlain | Kind::VotingTrace => RobotParams::aibot(),
        }
    }

    fn controller(self) -> Box<dyn Controller> {
        let priority = |detect| PriorityParams {
            detect,
            recovery: detect,
            ..PriorityParams::default()
        };
        let voting = || VotingController::new(VotingParams::default()).expect("default voting parameters");
        match self {
            Kind::PriorityPlain => Box::new(PriorityController::new(priority(false)).expect("valid")),
            Kind::PriorityTrace => Box::new(PriorityController::new(priority(true)).expect("valid")),
            Kind::VotingPlain => Box::new(voting()),
            Kind::VotingTrace => Box::new(TracedVoting::new(voting(), PriorityParams::default())),
        }
    }
}

fn simulation(world: &World, kind: Kind, seed: u64) -> Simulation {
    let run = RunParams {
        time_limit_s: 1e9,
        collision_fatal: false,
        ..RunParams::default()
    };
    let task = Task {
        start: START,
        goal: Some(GOAL),
    };
    Simulation::new(world, kind.robot(), run, task, seed).expect("the bench run starts")
}

fn loop_ticks(bencher: Bencher, kind: Kind) {
    let world = trap_world();
    let seed = SeedCell::new(0u64);
    bencher
        .counter(ItemsCount::new(TICKS))
        .with_inputs(|| {
            seed.set(seed.get() + 1);
            seed.get()
        })
        .bench_local_values(|first_seed| {
            let mut s = first_seed;
            let mut sim = simulation(&world, kind, s);
            let mut c = kind.controller();
            for _ in 0..TICKS {
                if sim.tick(c.as_mut()).is_some() {
                    s += 1_000_000;
                    sim = simulation(&world, kind, s);
                    c = kind.controller();
                }
            }
            sim.time_s()
        });
}

/// 1,000 perceptions of the plain controller's runs on `kind`'s robot in
/// the trap world (restarting when a run ends): plain and traced variants
/// are fed the same inputs.
fn recorded(kind: Kind) -> Vec<Perception> {
    let kind = match kind {
        Kind::PriorityPlain | Kind::PriorityTrace => Kind::PriorityPlain,
        Kind::VotingPlain | Kind::VotingTrace => Kind::VotingPlain,
    };
    let world = trap_world();
    let mut s = 7;
    let mut sim = simulation(&world, kind, s);
    let mut c = kind.controller();
    let mut out = Vec::with_capacity(TICKS);
    while out.len() < TICKS {
        if sim.tick(c.as_mut()).is_some() {
            s += 1;
            sim = simulation(&world, kind, s);
            c = kind.controller();
            continue;
        }
        out.push(sim.perception().clone());
    }
    out
}

fn controller_steps(bencher: Bencher, kind: Kind) {
    let perceptions = recorded(kind);
    bencher
        .counter(ItemsCount::new(perceptions.len()))
        .with_inputs(|| kind.controller())
        .bench_local_values(|mut c| {
            let mut notes = Notes::disabled();
            for p in &perceptions {
                divan::black_box(c.step(p, &mut notes));
            }
            c
        });
}

const KINDS: [Kind; 4] = [
    Kind::PriorityPlain,
    Kind::PriorityTrace,
    Kind::VotingPlain,
    Kind::VotingTrace,
];

impl std::fmt::Display for Kind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Kind::PriorityPlain => "priority_plain",
            Kind::PriorityTrace => "priority_trace",
            Kind::VotingPlain => "voting_plain",
            Kind::VotingTrace => "voting_trace",
        })
    }
}

#[divan::bench(args = KINDS, sample_count = 40)]
fn loops(b: Bencher, kind: Kind) {
    loop_ticks(b, kind);
}

#[divan::bench(args = KINDS, sample_count = 200)]
fn steps(b: Bencher, kind: Kind) {
    controller_steps(b, kind);
}
