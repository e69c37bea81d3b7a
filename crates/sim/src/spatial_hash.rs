//! A uniform grid of buckets over a rectangle, for neighbour queries among
//! moving discs.
//!
//! The items are kept sorted by (bucket, index): a rebuild is one sort of
//! `n` keys (`O(n log n)`, whatever the size of the map, no allocation once
//! sized), and a query looks up, by binary search, the run of each row of
//! buckets overlapping the query square. Items come out in a fixed order
//! (bucket by bucket, by index within a bucket), so results depend on
//! nothing but the positions.

use robot::Vec2;

/// Buckets of item indices (module docs).
#[derive(Debug, Clone)]
pub struct SpatialHash {
    min: Vec2,
    cell_m: f64,
    nx: usize,
    ny: usize,
    /// `(bucket, item)`, sorted.
    keys: Vec<(u32, u32)>,
}

impl SpatialHash {
    /// Buckets of side `cell_m` over the rectangle `[min, max]`; points
    /// outside it fall into the border buckets. `cell_m` is raised if needed
    /// to keep at most about a million buckets.
    pub fn new(min: Vec2, max: Vec2, cell_m: f64) -> SpatialHash {
        let (w, h) = ((max.x - min.x).max(0.0), (max.y - min.y).max(0.0));
        let mut cell = if cell_m.is_finite() && cell_m > 0.0 {
            cell_m
        } else {
            1.0
        };
        cell = cell.max((w * h / 1.0e6).sqrt());
        let nx = ((w / cell).ceil() as usize).max(1);
        let ny = ((h / cell).ceil() as usize).max(1);
        SpatialHash {
            min,
            cell_m: cell,
            nx,
            ny,
            keys: Vec::new(),
        }
    }

    #[inline]
    fn coord(&self, v: f64, lo: f64, n: usize) -> usize {
        let k = ((v - lo) / self.cell_m).floor();
        if k >= 0.0 { (k as usize).min(n - 1) } else { 0 }
    }

    /// Rebuilds the buckets from the positions (item `k` is `points[k]`).
    pub fn rebuild(&mut self, points: impl Iterator<Item = Vec2>) {
        self.keys.clear();
        for (k, p) in points.enumerate() {
            let b = self.coord(p.y, self.min.y, self.ny) * self.nx + self.coord(p.x, self.min.x, self.nx);
            self.keys.push((b as u32, k as u32));
        }
        self.keys.sort_unstable();
    }

    /// Calls `f` with every item whose bucket overlaps the square of
    /// half-side `radius_m` around `p` (a superset of the items within
    /// `radius_m` of `p` at the last rebuild).
    #[inline]
    pub fn for_each_near(&self, p: Vec2, radius_m: f64, mut f: impl FnMut(usize)) {
        if self.keys.is_empty() {
            return;
        }
        let (i0, i1) = (
            self.coord(p.x - radius_m, self.min.x, self.nx),
            self.coord(p.x + radius_m, self.min.x, self.nx),
        );
        let (j0, j1) = (
            self.coord(p.y - radius_m, self.min.y, self.ny),
            self.coord(p.y + radius_m, self.min.y, self.ny),
        );
        for j in j0..=j1 {
            let (lo, hi) = ((j * self.nx + i0) as u32, (j * self.nx + i1) as u32);
            let a = self.keys.partition_point(|&(b, _)| b < lo);
            for &(b, k) in &self.keys[a..] {
                if b > hi {
                    break;
                }
                f(k as usize);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::noise::RandomStream;

    #[test]
    fn finds_every_neighbour() {
        let mut rng = RandomStream::new(9, 0);
        let pts: Vec<Vec2> = (0..300)
            .map(|_| Vec2::new(rng.uniform_in(-1.0, 11.0), rng.uniform_in(-1.0, 6.0)))
            .collect();
        let mut h = SpatialHash::new(Vec2::new(0.0, 0.0), Vec2::new(10.0, 5.0), 0.7);
        h.rebuild(pts.iter().copied());
        for q in &pts[..50] {
            for &r in &[0.3, 1.0, 2.5] {
                let mut got = Vec::new();
                h.for_each_near(*q, r, |k| {
                    if pts[k].dist(*q) <= r {
                        got.push(k)
                    }
                });
                got.sort();
                let want: Vec<usize> = (0..pts.len()).filter(|&k| pts[k].dist(*q) <= r).collect();
                assert_eq!(got, want);
            }
        }
    }
}
