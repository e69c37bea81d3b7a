//! How people find their way to an exhibit: a geodesic distance field per
//! waypoint on a coarse lattice, followed downhill.
//!
//! The lattice has nodes every `spacing_m` (0.2 m: fine enough for 1 m
//! doors, ~25 times fewer nodes than a 0.05 m map) in the map frame; a node
//! is passable when a person's disc fits there (distance to the nearest
//! obstacle ≥ the person's radius, by the world's distance field). For each
//! waypoint, Dijkstra's algorithm over the 8-connected passable nodes (steps
//! of 1 and √2 spacings, [`crate::geodesic`]) gives the walking distance of every node to the
//! waypoint's node: `O(n log n)` per waypoint, built once per world. A
//! person follows the field downhill ([`Routes::direction`]), around
//! exhibits and through doors, until near the exhibit, then walks straight.

use robot::{Pose, Vec2};

use crate::distance_field::DistanceField;
use crate::fast_math::norm;
use crate::geodesic::{self, Lattice, Steps};
use crate::grid::OccupancyGrid;

/// Lattice spacing, metres.
pub const ROUTE_SPACING_M: f64 = 0.2;

/// Walking-distance fields to each waypoint (module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct Routes {
    nx: usize,
    ny: usize,
    spacing_m: f64,
    origin: Pose,
    /// Per waypoint, per node (row by row): metres to the waypoint,
    /// `f32::INFINITY` if unreachable or impassable.
    fields: Vec<Vec<f32>>,
}

impl Routes {
    /// The fields of `waypoints` on `grid` for people of radius `radius_m`.
    pub fn new(grid: &OccupancyGrid, field: &DistanceField, waypoints: &[Vec2], radius_m: f64) -> Routes {
        let h = ROUTE_SPACING_M.max(grid.resolution_m());
        let (wm, hm) = (
            grid.width() as f64 * grid.resolution_m(),
            grid.height() as f64 * grid.resolution_m(),
        );
        let nx = ((wm / h).floor() as usize).max(1);
        let ny = ((hm / h).floor() as usize).max(1);
        let origin = grid.origin();
        let node =
            |i: usize, j: usize| origin.transform(Vec2::new((i as f64 + 0.5) * h, (j as f64 + 0.5) * h));
        let passable: Vec<bool> = (0..nx * ny)
            .map(|k| field.distance_m(node(k % nx, k / nx)) >= radius_m)
            .collect();
        let mut routes = Routes {
            nx,
            ny,
            spacing_m: h,
            origin,
            fields: Vec::with_capacity(waypoints.len()),
        };
        let lattice = Lattice {
            width: nx,
            height: ny,
            passable: &passable,
            // No corner cutting past an impassable node.
            cut_corners: false,
        };
        let steps = Steps {
            straight: h as f32,
            diagonal: (std::f64::consts::SQRT_2 * h) as f32,
        };
        for &w in waypoints {
            // Seed the waypoint's node and its passable neighbours (an
            // exhibit's own node is often inside the exhibit).
            let seeds: Vec<(usize, f32)> = routes
                .node_of(w)
                .into_iter()
                .flat_map(|(i, j)| routes.around(i, j))
                .map(|(ii, jj)| (jj * nx + ii, norm(node(ii, jj) - w) as f32))
                .collect();
            let dist = geodesic::distances(&lattice, steps, &seeds, None);
            routes.fields.push(dist);
        }
        routes
    }

    /// The node containing a world point, if inside the lattice.
    fn node_of(&self, p: Vec2) -> Option<(usize, usize)> {
        let m = self.origin.inverse_transform(p);
        let (i, j) = ((m.x / self.spacing_m).floor(), (m.y / self.spacing_m).floor());
        (i >= 0.0 && j >= 0.0 && (i as usize) < self.nx && (j as usize) < self.ny)
            .then_some((i as usize, j as usize))
    }

    /// The node and its 8 neighbours inside the lattice.
    fn around(&self, i: usize, j: usize) -> impl Iterator<Item = (usize, usize)> + use<> {
        let (nx, ny) = (self.nx, self.ny);
        let (i0, i1) = (i.saturating_sub(1), (i + 1).min(nx - 1));
        let (j0, j1) = (j.saturating_sub(1), (j + 1).min(ny - 1));
        (j0..=j1).flat_map(move |jj| (i0..=i1).map(move |ii| (ii, jj)))
    }

    /// Walking distance from `p` to waypoint `k`, metres (infinite when
    /// unreachable, off the lattice, or no such waypoint).
    pub fn distance_m(&self, k: usize, p: Vec2) -> f64 {
        match (self.fields.get(k), self.node_of(p)) {
            (Some(f), Some((i, j))) => f64::from(f[j * self.nx + i]),
            _ => f64::INFINITY,
        }
    }

    /// Unit direction downhill towards waypoint `k` from `p`: towards the
    /// neighbouring node (or `p`'s own) of least walking distance; `None`
    /// when none is reachable.
    pub fn direction(&self, k: usize, p: Vec2) -> Option<Vec2> {
        let f = self.fields.get(k)?;
        let (i, j) = self.node_of(p)?;
        let mut best = (f32::INFINITY, (i, j));
        for (ii, jj) in self.around(i, j) {
            let d = f[jj * self.nx + ii];
            if d < best.0 {
                best = (d, (ii, jj));
            }
        }
        if !best.0.is_finite() {
            return None;
        }
        let (ii, jj) = best.1;
        let h = self.spacing_m;
        let to = self
            .origin
            .transform(Vec2::new((ii as f64 + 0.5) * h, (jj as f64 + 0.5) * h))
            - p;
        let n = norm(to);
        (n > 1e-9).then(|| to.scale(1.0 / n))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::{Cell, CellIndex};

    #[test]
    fn walking_distance_goes_round_a_wall() {
        // 10 m × 6 m, a wall across x = 5 m with a 1 m door at the top.
        let mut g = OccupancyGrid::new(200, 120, 0.05, Pose::default());
        for j in 0..95 {
            for i in 98..102 {
                g.set(CellIndex { i, j }, Cell::Occupied);
            }
        }
        let field = DistanceField::new(&g);
        let r = Routes::new(&g, &field, &[Vec2::new(8.0, 1.0)], 0.25);
        let d = r.distance_m(0, Vec2::new(2.0, 1.0));
        // Through the door at (5, 5.25): √(3² + 4.25²) + √(3² + 4.25²) ≈ 10.4 m.
        assert!(d > 10.0 && d < 11.5, "{d}");
        // Downhill from the far side heads up towards the door, not into the wall.
        let dir = r.direction(0, Vec2::new(4.0, 1.0)).unwrap();
        assert!(dir.y > 0.5, "{dir:?}");
        assert!(r.distance_m(0, Vec2::new(8.1, 1.1)) < 0.3);
        assert_eq!(r.distance_m(1, Vec2::new(8.1, 1.1)), f64::INFINITY);
    }
}
