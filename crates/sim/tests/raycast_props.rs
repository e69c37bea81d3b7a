//! Ray casting against an analytic brute force, on random grids.
//!
//! * [`sim::cast`] (clearance jumps) must return the same bits as
//!   [`sim::cast_traversal`] (cell by cell), on every input, including grids
//!   edited with `set` after they were built.
//! * Both must agree to 1e-9 m with a brute force that intersects the ray
//!   with the square of every blocked cell and with the grid's border. Where
//!   the ray only grazes a cell (passes within 1 nm of its edge or corner
//!   without entering it by more), counting that cell or not are both right:
//!   the reference accepts either.

use std::f64::consts::PI;

use proptest::prelude::*;
use robot::{Pose, Vec2};
use sim::{Cell, CellIndex, OccupancyGrid, cast, cast_many, cast_traversal};

const TOL: f64 = 1e-9;
const EPS: f64 = 1e-9;

/// Entry and exit distances of the ray `s + t d` (t ≥ 0) through the box
/// `[x0, x1] × [y0, y1]`, or `None` if it misses.
fn slab(s: Vec2, d: Vec2, x0: f64, x1: f64, y0: f64, y1: f64) -> Option<(f64, f64)> {
    let mut lo = 0.0f64;
    let mut hi = f64::INFINITY;
    for (p, v, a, b) in [(s.x, d.x, x0, x1), (s.y, d.y, y0, y1)] {
        if v == 0.0 {
            if p < a || p > b {
                return None;
            }
        } else {
            let (t0, t1) = ((a - p) / v, (b - p) / v);
            lo = lo.max(t0.min(t1));
            hi = hi.min(t0.max(t1));
        }
    }
    (lo <= hi).then_some((lo, hi))
}

/// What the brute force allows as the hit distance.
#[derive(Debug)]
struct Reference {
    /// The ray starts in a blocked cell or outside.
    starts_blocked: bool,
    /// Nearest entry into a blocked cell's square that the ray certainly
    /// crosses, and the distance from which it is certainly outside the grid.
    definite: f64,
    /// Intervals of distances where a hit is also right (grazed cells, the
    /// grid border).
    also: Vec<(f64, f64)>,
}

impl Reference {
    fn new(g: &OccupancyGrid, origin: Vec2, angle: f64) -> Reference {
        let r = g.resolution_m();
        let s = g.to_map(origin);
        let a = angle - g.origin().theta_rad;
        let d = Vec2::new(a.cos(), a.sin());
        let start = CellIndex {
            i: (s.x / r).floor() as i64,
            j: (s.y / r).floor() as i64,
        };
        let (wm, hm) = (g.width() as f64 * r, g.height() as f64 * r);
        let mut reference = Reference {
            starts_blocked: g.blocked(start),
            definite: f64::INFINITY,
            also: Vec::new(),
        };
        if reference.starts_blocked {
            return reference;
        }
        // The border: certainly out once past the grown rectangle, maybe out
        // once past the shrunk one.
        let out_late = slab(s, d, -EPS, wm + EPS, -EPS, hm + EPS).map_or(0.0, |(_, t)| t);
        let out_early = slab(s, d, EPS, wm - EPS, EPS, hm - EPS).map_or(0.0, |(_, t)| t);
        reference.definite = out_late;
        reference.also.push((out_early, out_late));
        for j in 0..g.height() as i64 {
            for i in 0..g.width() as i64 {
                if !g.blocked(CellIndex { i, j }) {
                    continue;
                }
                let (x0, y0) = (i as f64 * r, j as f64 * r);
                let (x1, y1) = (x0 + r, y0 + r);
                let inner = slab(s, d, x0 + EPS, x1 - EPS, y0 + EPS, y1 - EPS);
                let outer = slab(s, d, x0 - EPS, x1 + EPS, y0 - EPS, y1 + EPS);
                match (inner, outer) {
                    (Some(_), _) => {
                        let (t_in, _) = slab(s, d, x0, x1, y0, y1).expect("crosses the inner square");
                        reference.definite = reference.definite.min(t_in);
                    }
                    (None, Some(span)) => reference.also.push(span),
                    (None, None) => {}
                }
            }
        }
        reference
    }

    /// Whether a result is one of the right answers.
    fn accepts(&self, result: Option<f64>, max_range: f64) -> Result<(), String> {
        if self.starts_blocked {
            return if result == Some(0.0) {
                Ok(())
            } else {
                Err(format!("starts blocked, got {result:?}"))
            };
        }
        match result {
            None if self.definite > max_range - TOL => Ok(()),
            None => Err(format!("missed the hit at {} (range {max_range})", self.definite)),
            Some(t) if t > max_range + TOL => Err(format!("hit at {t} beyond the range {max_range}")),
            Some(t) => {
                let explained = (t - self.definite).abs() <= TOL
                    || self
                        .also
                        .iter()
                        .any(|&(lo, hi)| lo - TOL <= t && t <= hi + TOL && lo <= self.definite + TOL);
                if explained && t <= self.definite + TOL {
                    Ok(())
                } else {
                    Err(format!(
                        "hit at {t}, expected {} (or {:?})",
                        self.definite, self.also
                    ))
                }
            }
        }
    }
}

/// A random grid: exact binary resolutions and cell-aligned origins (so ray
/// origins can sit exactly on boundaries), or arbitrary ones.
#[derive(Debug, Clone)]
struct GridCase {
    width: usize,
    height: usize,
    resolution_m: f64,
    origin: Pose,
    cells: Vec<u8>,
    edits: Vec<(usize, u8)>,
}

impl GridCase {
    fn build(&self) -> OccupancyGrid {
        let state = |v: u8| match v {
            0 => Cell::Occupied,
            1 => Cell::Unknown,
            _ => Cell::Free,
        };
        let cells = self.cells.iter().map(|&v| state(v)).collect();
        let mut g = OccupancyGrid::from_cells(self.width, self.height, self.resolution_m, self.origin, cells)
            .unwrap();
        for &(k, v) in &self.edits {
            let k = k % (self.width * self.height);
            let c = CellIndex {
                i: (k % self.width) as i64,
                j: (k / self.width) as i64,
            };
            g.set(c, state(v));
        }
        g
    }
}

fn grid_case() -> impl Strategy<Value = GridCase> {
    let exact = (
        prop::sample::select(vec![0.25, 0.5, 1.0]),
        -8i32..8,
        -8i32..8,
        prop::sample::select(vec![0.0, PI / 2.0, PI]),
    )
        .prop_map(|(r, ox, oy, yaw)| (r, Pose::new(ox as f64 * r, oy as f64 * r, yaw)));
    let arbitrary = (
        prop::sample::select(vec![0.05, 0.1, 0.37]),
        -5.0f64..5.0,
        -5.0f64..5.0,
        -PI..PI,
    )
        .prop_map(|(r, x, y, yaw)| (r, Pose::new(x, y, yaw)));
    (
        prop_oneof![exact, arbitrary],
        1usize..150,
        1usize..150,
        // Permille of blocked cells: mostly sparse, so that clearance jumps happen.
        prop::sample::select(vec![0u32, 2, 10, 50, 300]),
        any::<u64>(),
        prop::collection::vec((any::<usize>(), 0u8..4), 0..6),
    )
        .prop_map(|((resolution_m, origin), width, height, permille, seed, edits)| {
            let mut s = seed;
            let cells = (0..width * height)
                .map(|_| {
                    s = s
                        .wrapping_mul(6364136223846793005)
                        .wrapping_add(1442695040888963407);
                    let roll = ((s >> 33) % 1000) as u32;
                    if roll < permille { (s >> 20) as u8 % 2 } else { 2 }
                })
                .collect();
            GridCase {
                width,
                height,
                resolution_m,
                origin,
                cells,
                edits,
            }
        })
}

/// A ray: where it starts (in units of the map's size, or on a cell
/// boundary or corner) and its angle (any, axis-aligned or diagonal in the
/// map frame, or through lattice points).
#[derive(Debug, Clone)]
struct RayCase {
    u: f64,
    v: f64,
    snap: u8,
    angle_kind: u8,
    angle: f64,
    k: i32,
    lattice: (i32, i32),
}

fn ray_case() -> impl Strategy<Value = RayCase> {
    (
        -0.05f64..1.05,
        -0.05f64..1.05,
        0u8..4,
        0u8..3,
        -PI..PI,
        0i32..8,
        (-4i32..5, -4i32..5),
    )
        .prop_map(|(u, v, snap, angle_kind, angle, k, lattice)| RayCase {
            u,
            v,
            snap,
            angle_kind,
            angle,
            k,
            lattice,
        })
}

impl RayCase {
    fn origin_and_angle(&self, g: &OccupancyGrid) -> (Vec2, f64) {
        let r = g.resolution_m();
        let (wm, hm) = (g.width() as f64 * r, g.height() as f64 * r);
        let (mut x, mut y) = (self.u * wm, self.v * hm);
        // 1: on a vertical boundary, 2: on a horizontal one, 3: on a corner.
        if self.snap & 1 != 0 {
            x = (x / r).round() * r;
        }
        if self.snap & 2 != 0 {
            y = (y / r).round() * r;
        }
        let yaw = g.origin().theta_rad;
        let angle = match self.angle_kind {
            0 => self.angle,
            1 => self.k as f64 * PI / 4.0 + yaw,
            _ => {
                let (a, b) = self.lattice;
                if a == 0 && b == 0 {
                    yaw
                } else {
                    (b as f64).atan2(a as f64) + yaw
                }
            }
        };
        (g.to_world(Vec2::new(x, y)), angle)
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 2000, ..ProptestConfig::default() })]

    #[test]
    fn fast_cast_equals_traversal_and_brute_force(
        grid in grid_case(),
        rays in prop::collection::vec(ray_case(), 1..8),
        max_range in prop::sample::select(vec![0.3, 3.0, 30.0, 1000.0]),
    ) {
        let g = grid.build();
        let mut angles = Vec::new();
        let mut origins = Vec::new();
        for ray in &rays {
            let (o, a) = ray.origin_and_angle(&g);
            let fast = cast(&g, o, a, max_range);
            let plain = cast_traversal(&g, o, a, max_range);
            prop_assert_eq!(fast.map(f64::to_bits), plain.map(f64::to_bits), "from {:?} at {}", o, a);
            let reference = Reference::new(&g, o, a);
            if let Err(e) = reference.accepts(plain, max_range) {
                prop_assert!(false, "from {:?} at {}: {}", o, a, e);
            }
            origins.push(o);
            angles.push(a);
        }
        let mut out = Vec::new();
        cast_many(&g, origins[0], &angles, max_range, &mut out);
        for (&a, &got) in angles.iter().zip(&out) {
            prop_assert_eq!(got.map(f64::to_bits), cast(&g, origins[0], a, max_range).map(f64::to_bits));
        }
    }

    #[test]
    fn world_cell_world_round_trips(
        x in -50.0f64..50.0,
        y in -50.0f64..50.0,
        ox in -20.0f64..20.0,
        oy in -20.0f64..20.0,
        yaw in -PI..PI,
        r in prop::sample::select(vec![0.01, 0.05, 0.1, 1.0]),
    ) {
        let g = OccupancyGrid::new(10, 10, r, Pose::new(ox, oy, yaw));
        let p = Vec2::new(x, y);
        let c = g.cell_of(p);
        let center = g.cell_center(c);
        prop_assert!(center.dist(p) <= r * std::f64::consts::SQRT_2 / 2.0 + 1e-9);
        prop_assert_eq!(g.cell_of(center), c);
        let back = g.to_world(g.to_map(p));
        prop_assert!(back.dist(p) < 1e-9);
    }
}

#[test]
fn exact_diagonals_from_corners_on_a_checkerboard() {
    // Every other cell blocked: diagonal rays from corners graze corners at
    // every step, the worst case for tie handling.
    let (w, h) = (40usize, 30usize);
    let cells = (0..w * h)
        .map(|k| {
            let (i, j) = (k % w, k / w);
            if (i + j) % 2 == 0 && i % 5 == 0 {
                Cell::Occupied
            } else {
                Cell::Free
            }
        })
        .collect();
    let g = OccupancyGrid::from_cells(w, h, 0.5, Pose::default(), cells).unwrap();
    for i in 0..=w {
        for j in 0..=h {
            for k in 0..8 {
                let (o, a) = (Vec2::new(i as f64 * 0.5, j as f64 * 0.5), k as f64 * PI / 4.0);
                let plain = cast_traversal(&g, o, a, 100.0);
                assert_eq!(cast(&g, o, a, 100.0).map(f64::to_bits), plain.map(f64::to_bits));
                Reference::new(&g, o, a).accepts(plain, 100.0).unwrap();
            }
        }
    }
}

#[test]
fn exact_ties_between_boundaries_are_handled_alike() {
    // From a cell corner along (2, 1) the ray crosses a vertical and a
    // horizontal boundary at exactly the same distance at every other
    // corner: cos θ = 2 sin θ holds exactly in floating point for these
    // lattice directions. Sparse walls make the fast caster jump and land on
    // such ties.
    let (w, h) = (120usize, 90usize);
    let mut s = 5u64;
    let cells = (0..w * h)
        .map(|_| {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            if (s >> 33) % 1000 < 4 {
                Cell::Occupied
            } else {
                Cell::Free
            }
        })
        .collect();
    let g = OccupancyGrid::from_cells(w, h, 0.5, Pose::default(), cells).unwrap();
    let mut ties = 0;
    for (a, b) in [
        (2, 1),
        (4, 1),
        (1, 2),
        (1, 4),
        (-2, 1),
        (2, -1),
        (-4, -1),
        (-1, -2),
        (4, 2),
        (-2, -4),
    ] {
        let angle = f64::atan2(b as f64, a as f64);
        let (c, s) = (angle.cos(), angle.sin());
        if c.abs() == 2.0 * s.abs()
            || c.abs() == 4.0 * s.abs()
            || s.abs() == 2.0 * c.abs()
            || s.abs() == 4.0 * c.abs()
        {
            ties += 1;
        }
        for i in 0..=w {
            for j in 0..=h {
                let o = Vec2::new(i as f64 * 0.5, j as f64 * 0.5);
                let plain = cast_traversal(&g, o, angle, 1000.0);
                assert_eq!(
                    cast(&g, o, angle, 1000.0).map(f64::to_bits),
                    plain.map(f64::to_bits),
                    "{o:?} ({a}, {b})"
                );
                Reference::new(&g, o, angle).accepts(plain, 1000.0).unwrap();
            }
        }
    }
    assert!(ties >= 6, "the directions should give exact ties ({ties})");
}
