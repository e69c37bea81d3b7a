//! Ray casting speed, in rays per second, on the real building maps.
//!
//! Each iteration is 256 laser scans, each 181 beams over 180° from a free pose
//! (poses drawn uniformly among the free cells with a
//! fixed seed), with a maximum range of 8 or 30 m. `cast_many` is the
//! accelerated caster ([`sim::cast_many`], bit-identical to the traversal);
//! `traversal` is the plain cell-by-cell traversal
//! ([`sim::cast_traversal`]). On `building_31` most free cells lie in the
//! white area around the building, so many beams cross open space.
//!
//! Run with `cargo bench -p sim --bench raycast`.
//!
//! Medians on the shared 2-core machine (load ≈ 3.5 from other builds):
//!
//! | map, range | `cast_many` | `traversal` | speed-up |
//! |---|---|---|---|
//! | building_31, 8 m | 8.9 M rays/s | 3.4 M rays/s | 2.6× |
//! | building_31, 30 m | 7.4 M rays/s (41,000 scans/s) | 2.5 M rays/s | 3.0× |
//! | levine, 30 m | 2.3 M rays/s | 0.47 M rays/s | 4.9× |

use std::f64::consts::PI;

use divan::Bencher;
use divan::counter::ItemsCount;
use robot::{Pose, Vec2};
use sim::{Cell, OccupancyGrid, cast_many, cast_traversal, map_server};

const BEAMS: usize = 181;

fn main() {
    divan::main();
}

fn map(name: &str) -> OccupancyGrid {
    let path = format!("{}/../../maps/{name}/{name}.yaml", env!("CARGO_MANIFEST_DIR"));
    map_server::load(path).expect("the test maps load").grid
}

/// 256 free poses with random headings, from a fixed seed.
fn poses(g: &OccupancyGrid) -> Vec<Pose> {
    let free: Vec<usize> = (0..g.cells().len())
        .filter(|&k| g.cells()[k] == Cell::Free)
        .collect();
    let mut s = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = move || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        s >> 11
    };
    (0..256)
        .map(|_| {
            let k = free[next() as usize % free.len()];
            let (i, j) = ((k % g.width()) as i64, (k / g.width()) as i64);
            let c = g.cell_center(sim::CellIndex { i, j });
            let heading = (next() as f64 / (1u64 << 53) as f64) * 2.0 * PI - PI;
            Pose::new(c.x, c.y, heading)
        })
        .collect()
}

fn beams(p: &Pose) -> Vec<f64> {
    (0..BEAMS)
        .map(|k| p.theta_rad - PI / 2.0 + k as f64 * PI / (BEAMS - 1) as f64)
        .collect()
}

fn scans(b: Bencher, name: &str, range_m: f64, fast: bool) {
    let g = map(name);
    let poses = poses(&g);
    let angles: Vec<Vec<f64>> = poses.iter().map(beams).collect();
    let mut out = Vec::with_capacity(BEAMS);
    b.counter(ItemsCount::new(BEAMS * poses.len())).bench_local(|| {
        for (p, angles) in poses.iter().zip(&angles) {
            let origin = Vec2::new(p.x_m, p.y_m);
            if fast {
                cast_many(&g, origin, angles, range_m, &mut out);
            } else {
                out.clear();
                out.extend(angles.iter().map(|&a| cast_traversal(&g, origin, a, range_m)));
            }
            divan::black_box(&out);
        }
    });
}

#[divan::bench(args = [8.0, 30.0], sample_count = 20)]
fn building_31_cast_many(b: Bencher, range_m: f64) {
    scans(b, "building_31", range_m, true);
}

#[divan::bench(args = [8.0, 30.0], sample_count = 20)]
fn building_31_traversal(b: Bencher, range_m: f64) {
    scans(b, "building_31", range_m, false);
}

#[divan::bench(args = [30.0], sample_count = 10)]
fn levine_cast_many(b: Bencher, range_m: f64) {
    scans(b, "levine", range_m, true);
}

#[divan::bench(args = [30.0], sample_count = 10)]
fn levine_traversal(b: Bencher, range_m: f64) {
    scans(b, "levine", range_m, false);
}
