//! Distance to the nearest obstacle, precomputed over a grid.
//!
//! For every cell, the exact Euclidean *feature transform*: the blocked cell
//! whose centre is nearest to the cell's centre (P. Felzenszwalb,
//! D. Huttenlocher, *Distance Transforms of Sampled Functions*, Theory of
//! Computing 8, 2012: one pass down the columns, then the lower envelope of
//! parabolas along the rows, keeping the arg-min). Building it costs
//! `O(width · height)` time and 4 bytes per cell; it is built once per world
//! and shared by all its runs.
//!
//! A query ([`DistanceField::nearest`]) looks at the features of the 3 × 3
//! cells around the point and at the map's edge (outside the map is
//! blocked), and returns the nearest point of those blocked squares: `O(1)`.
//! It is never nearer than the true nearest obstacle and, by the triangle
//! inequality, at most `3/√2` cells farther; in practice it is exact but for
//! rare near-ties (the unit tests compare it with brute force). People use
//! it for their wall forces and the simulator for the robot's clearance.

use robot::{Pose, Vec2};

use crate::grid::{CellIndex, OccupancyGrid};

const NONE: u32 = u32::MAX;

/// The nearest obstacle to a point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NearestObstacle {
    /// The obstacle's nearest point, world frame.
    pub point: Vec2,
    /// Distance from the query point to it, metres (0 inside an obstacle).
    pub distance_m: f64,
}

/// The feature transform of an occupancy grid (module docs).
#[derive(Debug, Clone)]
pub struct DistanceField {
    width: usize,
    height: usize,
    resolution_m: f64,
    origin: Pose,
    cos: f64,
    sin: f64,
    nearest: Vec<u32>,
}

impl DistanceField {
    /// Builds the field of `grid` (blocked = occupied or unknown).
    pub fn new(grid: &OccupancyGrid) -> DistanceField {
        let (w, h) = (grid.width(), grid.height());
        let cells = grid.cells();
        // Pass 1: per column, the nearest blocked row (or -1).
        let mut col = vec![-1i32; w * h];
        for i in 0..w {
            let mut last: i64 = -1;
            for j in 0..h {
                if cells[j * w + i] != crate::grid::Cell::Free {
                    last = j as i64;
                }
                col[j * w + i] = last as i32;
            }
            let mut next: i64 = -1;
            for j in (0..h).rev() {
                if cells[j * w + i] != crate::grid::Cell::Free {
                    next = j as i64;
                }
                let prev = col[j * w + i] as i64;
                let best = match (prev >= 0, next >= 0) {
                    (true, true) => {
                        if j as i64 - prev <= next - j as i64 {
                            prev
                        } else {
                            next
                        }
                    }
                    (true, false) => prev,
                    (false, true) => next,
                    (false, false) => -1,
                };
                col[j * w + i] = best as i32;
            }
        }
        // Pass 2: per row, the lower envelope of the parabolas
        // (x − q)² + f(q) over the columns q that have a blocked cell.
        let mut nearest = vec![NONE; w * h];
        let mut v = vec![0usize; w];
        let mut z = vec![0f64; w + 1];
        for j in 0..h {
            let row = &col[j * w..(j + 1) * w];
            let f = |q: usize| {
                let dj = j as f64 - row[q] as f64;
                dj * dj
            };
            let mut k: usize = 0;
            let mut any = false;
            for (q, &near_row) in row.iter().enumerate() {
                if near_row < 0 {
                    continue;
                }
                if !any {
                    any = true;
                    v[0] = q;
                    z[0] = f64::NEG_INFINITY;
                    z[1] = f64::INFINITY;
                    continue;
                }
                let fq = f(q) + (q * q) as f64;
                // z[0] = −∞ stops the search at k = 0.
                let mut s;
                loop {
                    let p = v[k];
                    s = (fq - (f(p) + (p * p) as f64)) / (2.0 * (q as f64 - p as f64));
                    if s <= z[k] {
                        k -= 1;
                    } else {
                        break;
                    }
                }
                k += 1;
                v[k] = q;
                z[k] = s;
                z[k + 1] = f64::INFINITY;
            }
            if !any {
                continue;
            }
            let mut k = 0;
            for x in 0..w {
                while z[k + 1] < x as f64 {
                    k += 1;
                }
                let q = v[k];
                nearest[j * w + x] = (row[q] as usize * w + q) as u32;
            }
        }
        let origin = grid.origin();
        let (sin, cos) = origin.theta_rad.sin_cos();
        DistanceField {
            width: w,
            height: h,
            resolution_m: grid.resolution_m(),
            origin,
            cos,
            sin,
            nearest,
        }
    }

    #[inline]
    fn to_map(&self, p: Vec2) -> Vec2 {
        let (dx, dy) = (p.x - self.origin.x_m, p.y - self.origin.y_m);
        Vec2::new(self.cos * dx + self.sin * dy, -self.sin * dx + self.cos * dy)
    }

    #[inline]
    fn to_world(&self, m: Vec2) -> Vec2 {
        Vec2::new(
            self.origin.x_m + self.cos * m.x - self.sin * m.y,
            self.origin.y_m + self.sin * m.x + self.cos * m.y,
        )
    }

    /// The blocked cell whose centre is nearest to the centre of `c`, if the
    /// grid has any blocked cell and `c` is inside it.
    pub fn feature(&self, c: CellIndex) -> Option<CellIndex> {
        if c.i < 0 || c.j < 0 || c.i as usize >= self.width || c.j as usize >= self.height {
            return None;
        }
        let f = self.nearest[c.j as usize * self.width + c.i as usize];
        (f != NONE).then(|| CellIndex {
            i: (f as usize % self.width) as i64,
            j: (f as usize / self.width) as i64,
        })
    }

    /// The nearest obstacle to `p` (module docs for the accuracy): a blocked
    /// cell, or the edge of the map.
    pub fn nearest(&self, p: Vec2) -> NearestObstacle {
        let m = self.to_map(p);
        let r = self.resolution_m;
        let (wm, hm) = (self.width as f64 * r, self.height as f64 * r);
        if !(m.x > 0.0 && m.y > 0.0 && m.x < wm && m.y < hm) {
            return NearestObstacle {
                point: p,
                distance_m: 0.0,
            };
        }
        // The map's edge.
        let mut best = Vec2::new(0.0, m.y);
        let mut best_d = m.x;
        for (q, d) in [
            (Vec2::new(wm, m.y), wm - m.x),
            (Vec2::new(m.x, 0.0), m.y),
            (Vec2::new(m.x, hm), hm - m.y),
        ] {
            if d < best_d {
                best = q;
                best_d = d;
            }
        }
        let i = ((m.x / r) as usize).min(self.width - 1);
        let j = ((m.y / r) as usize).min(self.height - 1);
        let mut best_d2 = best_d * best_d;
        let mut last = NONE;
        for jj in j.saturating_sub(1)..=(j + 1).min(self.height - 1) {
            for ii in i.saturating_sub(1)..=(i + 1).min(self.width - 1) {
                let f = self.nearest[jj * self.width + ii];
                if f == NONE || f == last {
                    continue;
                }
                last = f;
                let (fi, fj) = ((f as usize % self.width) as f64, (f as usize / self.width) as f64);
                let q = Vec2::new(
                    m.x.clamp(fi * r, (fi + 1.0) * r),
                    m.y.clamp(fj * r, (fj + 1.0) * r),
                );
                let d2 = (q.x - m.x) * (q.x - m.x) + (q.y - m.y) * (q.y - m.y);
                if d2 < best_d2 {
                    best = q;
                    best_d2 = d2;
                }
            }
        }
        NearestObstacle {
            point: self.to_world(best),
            distance_m: best_d2.sqrt(),
        }
    }

    /// A radius around `p` guaranteed free of obstacles, metres: the exact
    /// distance between the centre of `p`'s cell and the nearest blocked
    /// cell's centre, less one cell diagonal (half for `p` within its cell,
    /// half for the blocked cell's extent), and at most the distance to the
    /// map's edge. One look-up; 0 in or next to an obstacle. Sensors start
    /// their rays there.
    #[inline]
    pub fn free_radius_m(&self, p: Vec2) -> f64 {
        let m = self.to_map(p);
        let r = self.resolution_m;
        let (wm, hm) = (self.width as f64 * r, self.height as f64 * r);
        if !(m.x > 0.0 && m.y > 0.0 && m.x < wm && m.y < hm) {
            return 0.0;
        }
        let edge = m.x.min(m.y).min(wm - m.x).min(hm - m.y);
        let i = ((m.x / r) as usize).min(self.width - 1);
        let j = ((m.y / r) as usize).min(self.height - 1);
        let f = self.nearest[j * self.width + i];
        if f == NONE {
            return edge;
        }
        let di = (f as usize % self.width) as f64 - i as f64;
        let dj = (f as usize / self.width) as f64 - j as f64;
        let centres = (di * di + dj * dj).sqrt() * r;
        (centres - std::f64::consts::SQRT_2 * r).max(0.0).min(edge)
    }

    /// Distance from `p` to the nearest obstacle, metres.
    pub fn distance_m(&self, p: Vec2) -> f64 {
        self.nearest(p).distance_m
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::Cell;
    use crate::noise::RandomStream;

    fn brute(g: &OccupancyGrid, p: Vec2) -> f64 {
        let m = g.to_map(p);
        let r = g.resolution_m();
        let mut best =
            m.x.min(m.y)
                .min(g.width() as f64 * r - m.x)
                .min(g.height() as f64 * r - m.y);
        for j in 0..g.height() {
            for i in 0..g.width() {
                if g.blocked(CellIndex {
                    i: i as i64,
                    j: j as i64,
                }) {
                    let qx = m.x.clamp(i as f64 * r, (i + 1) as f64 * r);
                    let qy = m.y.clamp(j as f64 * r, (j + 1) as f64 * r);
                    best = best.min((qx - m.x).hypot(qy - m.y));
                }
            }
        }
        best
    }

    #[test]
    fn features_are_exact_for_cell_centres() {
        let mut rng = RandomStream::new(3, 0);
        let mut g = OccupancyGrid::new(37, 23, 0.1, Pose::new(1.0, -2.0, 0.3));
        for _ in 0..25 {
            let c = CellIndex {
                i: rng.index(37) as i64,
                j: rng.index(23) as i64,
            };
            g.set(c, Cell::Occupied);
        }
        let f = DistanceField::new(&g);
        for j in 0..23 {
            for i in 0..37 {
                let c = CellIndex { i, j };
                let got = f.feature(c).unwrap();
                let d2 = |a: CellIndex| ((a.i - c.i).pow(2) + (a.j - c.j).pow(2)) as f64;
                let mut best = f64::INFINITY;
                for jj in 0..23 {
                    for ii in 0..37 {
                        let b = CellIndex { i: ii, j: jj };
                        if g.blocked(b) {
                            best = best.min(d2(b));
                        }
                    }
                }
                assert!(g.blocked(got));
                assert_eq!(d2(got), best, "cell {c:?}");
            }
        }
    }

    #[test]
    fn distances_match_brute_force() {
        let mut rng = RandomStream::new(5, 0);
        let mut g = OccupancyGrid::new(60, 40, 0.05, Pose::new(-1.0, 0.5, -0.4));
        for _ in 0..6 {
            let (i0, j0) = (rng.index(55) as i64, rng.index(35) as i64);
            for j in j0..j0 + 1 + rng.index(5) as i64 {
                for i in i0..i0 + 1 + rng.index(5) as i64 {
                    g.set(CellIndex { i, j }, Cell::Occupied);
                }
            }
        }
        let f = DistanceField::new(&g);
        let mut worst: f64 = 0.0;
        for _ in 0..3000 {
            let m = Vec2::new(rng.uniform_in(0.0, 3.0), rng.uniform_in(0.0, 2.0));
            let p = g.to_world(m);
            let exact = brute(&g, p);
            let got = f.distance_m(p);
            assert!(got >= exact - 1e-12, "{got} < {exact}");
            worst = worst.max(got - exact);
        }
        // Far below the 3/√2-cell bound.
        assert!(worst < 0.1 * 0.05, "worst overestimate {worst}");
    }

    #[test]
    fn free_radius_is_a_lower_bound() {
        let mut rng = RandomStream::new(6, 0);
        let mut g = OccupancyGrid::new(80, 50, 0.05, Pose::new(0.5, 0.5, 0.2));
        for _ in 0..30 {
            g.set(
                CellIndex {
                    i: rng.index(80) as i64,
                    j: rng.index(50) as i64,
                },
                Cell::Occupied,
            );
        }
        let f = DistanceField::new(&g);
        for _ in 0..3000 {
            let p = g.to_world(Vec2::new(rng.uniform_in(0.0, 4.0), rng.uniform_in(0.0, 2.5)));
            let lb = f.free_radius_m(p);
            assert!(lb <= brute(&g, p) + 1e-12);
            assert!(!g.disc_blocked(p, lb));
        }
    }

    #[test]
    fn empty_grid_measures_to_the_edge() {
        let g = OccupancyGrid::new(10, 20, 0.1, Pose::default());
        let f = DistanceField::new(&g);
        let n = f.nearest(Vec2::new(0.3, 1.2));
        assert!((n.distance_m - 0.3).abs() < 1e-12);
        assert!((n.point.x - 0.0).abs() < 1e-12 && (n.point.y - 1.2).abs() < 1e-12);
        assert_eq!(f.distance_m(Vec2::new(-1.0, 0.5)), 0.0);
    }
}
