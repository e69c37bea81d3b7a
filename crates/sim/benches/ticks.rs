//! Control ticks per second, per core, with a simple reactive controller.
//!
//! - `aibot_field`: the AIBOT-like robot (7 IR, 3 sonar of 9 rays each,
//!   odometry, bumper) wandering in a 10 m × 10 m field at 0.05 m with 20
//!   box obstacles (`generators::cluttered_field`). Target ≥ 200 000 ticks/s.
//! - `laser_office_crowd`: the Jinny-like robot (181-beam laser over 180°,
//!   30 m) wandering along the corridors of the real `building_31` SLAM map
//!   (693 × 648 cells at 0.05 m, ROS map_server format, in
//!   the repository's `maps/`) among 30 wandering people. Target ≥ 20 000 ticks/s.
//! - `laser_hall_crowd`: the same robot in an open museum hall among 0 to
//!   300 visitors walking between exhibits.
//! - `laser_hall_disturbed`: the hall with every disturbance on
//!   ([`sim::disturbance`]): pushes at 0.2 per person per second of
//!   standing, four slippery strips across the hall, a curious group every
//!   50 s on average; the robot wanders (`wander`) or stands (`stand`:
//!   braked all along, the push hazard looked up every sub-step, groups
//!   round it). Compare with `laser_hall_crowd` at the same crowd.
//!
//! Collisions are not fatal here, so every sample runs its full number of
//! ticks; each sample is a fresh run with its own seed. The allocation
//! counter shows that a tick allocates nothing.
//!
//! Run with `cargo bench -p sim --bench ticks`.

use std::cell::Cell as SeedCell;

use divan::counter::ItemsCount;
use divan::{AllocProfiler, Bencher};
use robot::Vec2;
use robot::{Command, Controller, Notes, Perception, Pose, Step};
use sim::{
    Cell, CellIndex, CrowdParams, CrowdSize, DisturbanceParams, OccupancyGrid, PushParams, RobotParams,
    RunParams, Simulation, SlipParams, SlipPatch, SurroundParams, Task, World, generators,
};

#[global_allocator]
static ALLOC: AllocProfiler = AllocProfiler::system();

fn main() {
    divan::main();
}

/// Ticks per sample.
const TICKS: usize = 1000;

/// Forward at 0.3 m/s, veering away from IR detections, turning on the spot
/// towards the freer side when the front is blocked.
struct IrSonarWander;

impl Controller for IrSonarWander {
    fn step(&mut self, p: &Perception, _notes: &mut Notes) -> Step {
        let front = p.ir[2..5].iter().any(|d| d.triggered) || p.sonar[1].range_m < 0.35;
        let left_free = p.sonar[2].range_m.min(10.0);
        let right_free = p.sonar[0].range_m.min(10.0);
        let turn = if left_free >= right_free { 1.0 } else { -1.0 };
        if front {
            return Step::Run(Command::Twist {
                v_mps: 0.0,
                omega_radps: 1.5 * turn,
            });
        }
        let right = p.ir[..2].iter().filter(|d| d.triggered).count() as f64;
        let left = p.ir[5..].iter().filter(|d| d.triggered).count() as f64;
        Step::Run(Command::Twist {
            v_mps: 0.3,
            omega_radps: 0.8 * (right - left),
        })
    }
}

/// Forward at 0.5 m/s; when the front ±30° is closer than 1 m, turn on the
/// spot towards the side whose beams read farther on average.
struct LaserWander;

impl Controller for LaserWander {
    fn step(&mut self, p: &Perception, _notes: &mut Notes) -> Step {
        let scan = &p.lasers[0].ranges_m;
        let n = scan.len();
        let mid = n / 2;
        let w = n / 6;
        let finite = |x: f64| if x.is_finite() { x } else { 30.0 };
        let front = scan[mid - w..=mid + w]
            .iter()
            .filter(|x| !x.is_nan())
            .fold(f64::INFINITY, |a, &b| a.min(b));
        if front < 1.0 {
            let right: f64 = scan[..mid].iter().map(|&x| finite(x)).sum();
            let left: f64 = scan[mid + 1..].iter().map(|&x| finite(x)).sum();
            let turn = if left >= right { 1.0 } else { -1.0 };
            return Step::Run(Command::Twist {
                v_mps: 0.0,
                omega_radps: turn,
            });
        }
        Step::Run(Command::Twist {
            v_mps: 0.5,
            omega_radps: 0.0,
        })
    }
}

fn run_params() -> RunParams {
    RunParams {
        time_limit_s: 1e9,
        collision_fatal: false,
        ..RunParams::default()
    }
}

#[divan::bench(sample_count = 50)]
fn aibot_field(bencher: Bencher) {
    let world = World::new(generators::cluttered_field(10.0, 0.05, 20, 1).unwrap());
    let seed = SeedCell::new(0u64);
    bencher
        .counter(ItemsCount::new(TICKS))
        .with_inputs(|| {
            seed.set(seed.get() + 1);
            let task = Task {
                start: Pose::new(1.0, 1.0, 0.8),
                goal: None,
            };
            Simulation::new(&world, RobotParams::aibot(), run_params(), task, seed.get()).unwrap()
        })
        .bench_local_refs(|sim| {
            let mut c = IrSonarWander;
            for _ in 0..TICKS {
                sim.tick(&mut c);
            }
        });
}

#[divan::bench(sample_count = 20)]
fn laser_office_crowd(bencher: Bencher) {
    let map = sim::map_server::load(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../maps/building_31/building_31.yaml"
    ))
    .unwrap();
    let world = World::new(map.grid)
        .with_crowd(CrowdParams {
            size: CrowdSize::Count { people: 30 },
            ..CrowdParams::default()
        })
        .unwrap();
    let seed = SeedCell::new(0u64);
    bencher
        .counter(ItemsCount::new(TICKS))
        .with_inputs(|| {
            seed.set(seed.get() + 1);
            // In the main corridor, heading along it.
            let task = Task {
                start: Pose::new(-17.2, 6.4, std::f64::consts::FRAC_PI_2),
                goal: None,
            };
            Simulation::new(&world, RobotParams::jinny(), run_params(), task, seed.get()).unwrap()
        })
        .bench_local_refs(|sim| {
            let mut c = LaserWander;
            for _ in 0..TICKS {
                sim.tick(&mut c);
            }
        });
}

/// A 15 m × 35 m hall at 0.05 m, walls around, eight exhibit cases of
/// 1 m × 2 m in two rows; the exhibits' front points.
fn hall() -> (OccupancyGrid, Vec<Vec2>) {
    let (w, h) = (300i64, 700i64);
    let mut g = OccupancyGrid::new(w as usize, h as usize, 0.05, Pose::default());
    for i in 0..w {
        for j in [0, 1, h - 2, h - 1] {
            g.set(CellIndex { i, j }, Cell::Occupied);
        }
    }
    for j in 0..h {
        for i in [0, 1, w - 2, w - 1] {
            g.set(CellIndex { i, j }, Cell::Occupied);
        }
    }
    let mut fronts = Vec::new();
    for row in 0..4 {
        for (col, x) in [(0, 4.0), (1, 10.0)] {
            let y = 6.0 + 7.0 * row as f64;
            for j in (y / 0.05) as i64..((y + 2.0) / 0.05) as i64 {
                for i in ((x - 0.5) / 0.05) as i64..((x + 0.5) / 0.05) as i64 {
                    g.set(CellIndex { i, j }, Cell::Occupied);
                }
            }
            let side = if col == 0 { 1.0 } else { -1.0 };
            fronts.push(Vec2::new(x + side * 1.2, y + 1.0));
        }
    }
    (g, fronts)
}

#[divan::bench(sample_count = 10, args = [0, 30, 100, 300])]
fn laser_hall_crowd(bencher: Bencher, people: usize) {
    let (grid, exhibits) = hall();
    let world = World::new(grid)
        .with_crowd(CrowdParams {
            size: CrowdSize::Count { people },
            waypoints: exhibits,
            ..CrowdParams::default()
        })
        .unwrap();
    let seed = SeedCell::new(0u64);
    bencher
        .counter(ItemsCount::new(TICKS))
        .with_inputs(|| {
            seed.set(seed.get() + 1);
            let task = Task {
                start: Pose::new(7.0, 2.0, std::f64::consts::FRAC_PI_2),
                goal: None,
            };
            Simulation::new(&world, RobotParams::jinny(), run_params(), task, seed.get()).unwrap()
        })
        .bench_local_refs(|sim| {
            let mut c = LaserWander;
            for _ in 0..TICKS {
                sim.tick(&mut c);
            }
        });
}

/// Stands still.
struct Stand;

impl Controller for Stand {
    fn step(&mut self, _p: &Perception, _notes: &mut Notes) -> Step {
        Step::Run(Command::Stop)
    }
}

#[divan::bench(sample_count = 10, args = [("wander", 30), ("stand", 30), ("wander", 100), ("stand", 100)])]
fn laser_hall_disturbed(bencher: Bencher, (mode, people): (&str, usize)) {
    let (grid, exhibits) = hall();
    let world = World::new(grid)
        .with_crowd(CrowdParams {
            size: CrowdSize::Count { people },
            waypoints: exhibits,
            ..CrowdParams::default()
        })
        .unwrap();
    let disturbances = DisturbanceParams {
        push: PushParams {
            rate_per_person_s: 0.2,
            ..PushParams::default()
        },
        slip: SlipParams {
            patches: (0..4)
                .map(|k| SlipPatch {
                    min: [0.0, 4.0 + 7.0 * k as f64],
                    max: [15.0, 5.0 + 7.0 * k as f64],
                })
                .collect(),
            ..SlipParams::default()
        },
        surround: SurroundParams {
            rate_per_s: 0.02,
            ..SurroundParams::default()
        },
    };
    let seed = SeedCell::new(0u64);
    bencher
        .counter(ItemsCount::new(TICKS))
        .with_inputs(|| {
            seed.set(seed.get() + 1);
            let task = Task {
                start: Pose::new(7.0, 2.0, std::f64::consts::FRAC_PI_2),
                goal: None,
            };
            Simulation::new(&world, RobotParams::jinny(), run_params(), task, seed.get())
                .unwrap()
                .with_disturbances(disturbances.clone())
                .unwrap()
        })
        .bench_local_refs(|sim| {
            if mode == "stand" {
                for _ in 0..TICKS {
                    sim.tick(&mut Stand);
                }
            } else {
                let mut c = LaserWander;
                for _ in 0..TICKS {
                    sim.tick(&mut c);
                }
            }
        });
}
