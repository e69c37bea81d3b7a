//! Monte Carlo localization speed on building_31 (≈ 35 × 32 m, 693 × 648
//! cells of 0.05 m).
//!
//! - `filter_iteration`: one filter iteration of [`Localizer::update`] —
//!   motion model, likelihood field over 60 of the 181 beams, estimate,
//!   the Success/Warning scores (two poses × 181 beams) and low-variance
//!   resampling — with 500 particles. The odometry alternates between two
//!   poses 0.25 m apart, so every call runs an iteration. `always_resample`
//!   forces the resampling (threshold 1) that the default `N_eff` test may
//!   skip; `default` uses the default parameters.
//! - `measurement_500`: the likelihood field alone, 500 poses × 60 beams.
//! - `build_field`: the distance transforms and the field of the map (done
//!   once per map).
//!
//! Run with `cargo bench -p localization --bench localization`. Target: one
//! iteration ≤ 0.5 ms.
//!
//! Medians on the shared 2-core machine (load ≈ 2.5 from other work), two
//! runs:
//!
//! | bench | median |
//! |---|---|
//! | `filter_iteration_default` | 155–169 µs |
//! | `filter_iteration_always_resample` | 158–161 µs |
//! | `measurement_500` (30 000 beams) | 104–105 µs (3.5 ns a beam) |
//! | `build_field` (449 064 cells, two transforms) | 15.7–16.7 ms |

use divan::Bencher;
use localization::{LikelihoodField, LikelihoodFieldParams, Localizer, MclParams, PreparedScan};
use robot::{Command, GridMap, LaserScan, Pose};
use sim::{RobotParams, RunParams, ScriptedController, Simulation, Task, World};

fn main() {
    divan::main();
}

/// The map, and a Jinny scan (181 beams, 30 m, σ 0.01 m) from a pose in
/// the left corridor facing north.
fn setup() -> (GridMap, LaserScan, Pose) {
    let path = format!(
        "{}/../../maps/building_31/building_31.yaml",
        env!("CARGO_MANIFEST_DIR")
    );
    let grid = sim::map_server::load(path).expect("the test map loads").grid;
    let map = grid.grid_map();
    let world = World::new(grid);
    let truth = Pose::new(-17.2, 5.0, std::f64::consts::FRAC_PI_2);
    let task = Task {
        start: truth,
        goal: None,
    };
    let mut sim =
        Simulation::new(&world, RobotParams::jinny(), RunParams::default(), task, 1).expect("simulation");
    let mut stop = ScriptedController::new(vec![(Command::Stop, 1.0)]).expect("script");
    sim.tick(&mut stop);
    (map, sim.perception().lasers[0].clone(), truth)
}

fn iteration(bencher: Bencher, params: MclParams) {
    let (map, scan, truth) = setup();
    let mut mcl = Localizer::new(&map, params, 7).expect("localizer");
    mcl.init_pose(truth, 0.1, 0.05).expect("init");
    let a = Pose::new(0.0, 0.0, 0.0);
    let b = Pose::new(0.25, 0.0, 0.0);
    mcl.update(a, &scan).expect("update");
    let mut forward = true;
    bencher.bench_local(|| {
        let odometry = if forward { b } else { a };
        forward = !forward;
        mcl.update(odometry, &scan)
            .expect("update")
            .expect("an iteration")
    });
}

#[divan::bench]
fn filter_iteration_default(bencher: Bencher) {
    iteration(bencher, MclParams::default());
}

#[divan::bench]
fn filter_iteration_always_resample(bencher: Bencher) {
    iteration(
        bencher,
        MclParams {
            resample_threshold: 1.0,
            ..MclParams::default()
        },
    );
}

#[divan::bench]
fn measurement_500(bencher: Bencher) {
    let (map, scan, truth) = setup();
    let field = LikelihoodField::new(&map, 2.0);
    let table = field.beam_table(&LikelihoodFieldParams::default(), scan.range_max_m);
    let mut prepared = PreparedScan::default();
    prepared.fill(&scan, 60, map.resolution_m());
    let poses: Vec<(f64, f64, f64)> = (0..500)
        .map(|k| {
            let d = k as f64 / 500.0;
            field.pose_in_cells(&Pose::new(
                truth.x_m + 0.2 * (d - 0.5),
                truth.y_m,
                truth.theta_rad + 0.1 * d,
            ))
        })
        .collect();
    bencher.bench_local(|| {
        poses
            .iter()
            .map(|&p| field.log_likelihood(&table, &prepared, p))
            .sum::<f64>()
    });
}

#[divan::bench(sample_count = 20)]
fn build_field(bencher: Bencher) {
    let (map, _, _) = setup();
    bencher.bench_local(|| LikelihoodField::new(&map, 2.0));
}
