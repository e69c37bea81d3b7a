//! The tour-guide stack's speed on the real `building_31` map (tour-guide
//! issue targets): one control step of the guide controller — Monte Carlo
//! localization and AutoMove's 10 m × 10 m navigation function — and a whole
//! mission, simulator included.
//!
//! - `step/automove_filter`: a control step in which the localizer runs a
//!   filter iteration (500 particles, 60 of 181 beams) and AutoMove plans
//!   its window: the worst step. The perceptions alternate between two
//!   recorded ones whose odometry differs by 0.45 m, so that every step
//!   triggers an iteration. Target ≤ 3 ms.
//! - `step/automove`: the same steps without forcing iterations (the
//!   localizer iterates every 0.2 m of travel, about one step in four at
//!   0.5 m/s): the usual step.
//! - `missions/entrance_to_hall_south`: the whole leg from the entrance to the
//!   hall (26 m, 65 s simulated with seed 3, no people), simulator, laser, MCL and
//!   AutoMove, on one core. Target: a 200 s mission ≥ 50× faster than real
//!   time, i.e. ≤ 4 s per 200 s simulated.
//!
//! - `campaign/moderate_supervisor`: a whole campaign of the tour-guide suite
//!   on one core — ten calibration runs and 24 supervised missions in the
//!   museum among 25 visitors (laser, MCL, AutoMove or contour tracking,
//!   the GSPN decisions, learning from the log). Target ≤ 15 s.
//!
//! Figures: `crates/lab/BENCHMARKS.md`. Run with
//! `cargo bench -p lab --bench guide`.

use divan::Bencher;
use guide::supervisor::Behaviour;
use guide::{GuideController, GuideParams, Policy};
use lab::runs::mission::{self, MissionSetup};
use robot::{Controller, Notes, Perception, Pose};
use sim::{Places, RobotParams, RunParams, Simulation, Task, World};

fn main() {
    divan::main();
}

fn world() -> World {
    let yaml = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../maps/building_31/building_31.yaml"
    );
    World::new(sim::map_server::load(yaml).expect("the shipped map").grid)
}

fn place(name: &str) -> Pose {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../maps/building_31/places.yaml");
    Places::load(std::path::Path::new(path))
        .expect("the shipped places")
        .get(name)
        .expect("a shipped place")
        .pose
}

/// A controller on its way from the entrance and two perceptions 0.45 m
/// apart recorded on that way: more than twice `update_min_d` (0.2 m), so
/// that wherever the last filter iteration was, one of them is far enough
/// from it, and from then on every alternation runs an iteration (0.25 m
/// apart, both could lie within 0.2 m of the last iteration, and then no
/// step ever ran one).
fn recorded() -> (GuideController, [Perception; 2]) {
    let world = world();
    let start = place("entrance");
    let goal = place("hall_south").position();
    let map = world.grid().grid_map();
    let policy = Policy::Fixed(Behaviour::AutoMove);
    let mut c = GuideController::new(&map, GuideParams::default(), start, goal, policy, 1).unwrap();
    let task = Task {
        start,
        goal: Some(goal),
    };
    let mut sim = Simulation::new(&world, RobotParams::jinny(), RunParams::default(), task, 1).unwrap();
    for _ in 0..60 {
        sim.tick(&mut c);
    }
    let a = sim.perception().clone();
    while sim.perception().odometry.position().dist(a.odometry.position()) < 0.45 {
        sim.tick(&mut c);
    }
    let b = sim.perception().clone();
    (c, [a, b])
}

#[divan::bench_group(sample_count = 100)]
mod step {
    use super::*;

    #[divan::bench]
    fn automove_filter(bencher: Bencher) {
        let (mut c, ps) = recorded();
        let before = c.localizer().iterations();
        let mut k = 0;
        let mut steps = 0u64;
        let mut notes = Notes::disabled();
        bencher.bench_local(|| {
            k ^= 1;
            steps += 1;
            c.step(&ps[k], &mut notes)
        });
        // Every step but perhaps the first ran a filter iteration.
        assert!(
            c.localizer().iterations() - before + 1 >= steps,
            "{} filter iterations in {steps} steps",
            c.localizer().iterations() - before
        );
    }

    #[divan::bench]
    fn automove(bencher: Bencher) {
        let (mut c, ps) = recorded();
        let mut k = 0usize;
        let mut notes = Notes::disabled();
        bencher.bench_local(|| {
            // One step in four moves the odometry enough for a filter
            // iteration, as at cruise speed.
            k += 1;
            c.step(&ps[(k / 4) % 2], &mut notes)
        });
    }
}

#[divan::bench_group(sample_count = 3)]
mod campaign {
    use lab::record::RunRecord;
    use lab::suite::Suite;
    use lab::suites::tourguide::TourGuideSuite;

    use super::*;

    #[divan::bench]
    fn moderate_supervisor(bencher: Bencher) {
        let suite = TourGuideSuite::new(1).unwrap();
        let campaign = suite
            .campaigns()
            .into_iter()
            .find(|c| c.jobs.last().is_some_and(|j| j.scenario == "moderate/supervisor"))
            .expect("the moderate supervisor campaign");
        bencher.bench_local(|| {
            let mut earlier: Vec<RunRecord> = Vec::new();
            for job in &campaign.jobs {
                let r = suite.run(job, &earlier).unwrap();
                earlier.push(r);
            }
            divan::black_box(earlier.len())
        });
    }
}

#[divan::bench_group(sample_count = 5)]
mod missions {
    use super::*;

    #[divan::bench]
    fn entrance_to_hall_south(bencher: Bencher) {
        let setup = MissionSetup::new(world(), 300.0);
        let (start, goal) = (place("entrance"), place("hall_south").position());
        bencher.bench_local(|| {
            let leg = mission::run_leg(
                &setup,
                &mission::LegSpec {
                    from: "entrance",
                    to: "hall_south",
                    start,
                    believed: start,
                    goal,
                    policy: Policy::Fixed(Behaviour::AutoMove),
                    seed: 3,
                    trace: sim::TraceParams::default(),
                },
            )
            .unwrap();
            assert_eq!(leg.result.outcome, mission::LegOutcome::Reached);
            divan::black_box(leg.result.time_s)
        });
    }
}
