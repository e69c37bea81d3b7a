//! Occupancy grids.
//!
//! A grid of `width × height` square cells of side `resolution_m`. Cell
//! `(0, 0)` is the lower-left corner of the map; its lower-left corner is at
//! `origin` in the world (position and rotation, as in ROS `map_server`:
//! the map frame is the world frame moved by `origin`). Row `j` is `y`, column
//! `i` is `x` in the map frame. Unknown cells count as occupied for
//! collisions and sensing.
//!
//! The grid keeps a clearance field (distance to the nearest blocked cell,
//! see [`crate::clearance`]) in step with its cells, built once when the grid
//! is made and repaired locally by [`OccupancyGrid::set`]; the ray caster
//! uses it to skip free space.

use robot::{Pose, Vec2};

use crate::clearance::Clearance;
use crate::error::{Error, Result};

pub use robot::{Cell, CellIndex};

/// How many cells of each state a grid has.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
pub struct CellCounts {
    /// Free cells.
    pub free: usize,
    /// Occupied cells.
    pub occupied: usize,
    /// Unknown cells.
    pub unknown: usize,
}

/// The finest resolution a map may have, metres per cell (1 mm).
pub const MIN_RESOLUTION_M: f64 = 1e-3;

/// The coarsest resolution a map may have, metres per cell (10 m; ROS maps
/// have 0.01–0.1).
pub const MAX_RESOLUTION_M: f64 = 10.0;

/// The widest a map may span on a side, metres (10 km).
pub const MAX_EXTENT_M: f64 = 10_000.0;

/// The farthest a map's origin may lie from the world's, metres, on
/// either axis (10,000 km: any projected coordinates on Earth).
pub const MAX_ORIGIN_M: f64 = 1e7;

/// Checks a resolution against [`MIN_RESOLUTION_M`]…[`MAX_RESOLUTION_M`];
/// `what` names it in the error.
pub fn check_resolution(what: &str, resolution_m: f64) -> Result<()> {
    if resolution_m.is_finite() && (MIN_RESOLUTION_M..=MAX_RESOLUTION_M).contains(&resolution_m) {
        Ok(())
    } else {
        Err(Error::InvalidValue {
            what: what.to_string(),
            requirement: "between 0.001 and 10 metres per cell (sim::grid::MIN_RESOLUTION_M … MAX_RESOLUTION_M)",
            value: resolution_m,
        })
    }
}

/// Checks a map origin: finite, within [`MAX_ORIGIN_M`] on either axis;
/// `what` names it in the error.
pub fn check_origin(what: &str, origin: Pose) -> Result<()> {
    for (axis, value, limit) in [
        ("x", origin.x_m, MAX_ORIGIN_M),
        ("y", origin.y_m, MAX_ORIGIN_M),
        ("yaw", origin.theta_rad, f64::MAX),
    ] {
        if !(value.is_finite() && value.abs() <= limit) {
            return Err(Error::InvalidValue {
                what: format!("{what} {axis}"),
                requirement: if axis == "yaw" {
                    "finite"
                } else {
                    "finite and within ±1e7 m (sim::grid::MAX_ORIGIN_M)"
                },
                value,
            });
        }
    }
    Ok(())
}

/// An occupancy grid.
#[derive(Debug, Clone, PartialEq)]
pub struct OccupancyGrid {
    width: usize,
    height: usize,
    resolution_m: f64,
    origin: Pose,
    cells: Vec<Cell>,
    clearance: Clearance,
}

impl OccupancyGrid {
    /// An all-free grid. `resolution_m` must be finite and > 0 (checked by
    /// the loaders; here a bad value is a programming error and panics).
    pub fn new(width: usize, height: usize, resolution_m: f64, origin: Pose) -> OccupancyGrid {
        assert!(
            resolution_m.is_finite() && resolution_m > 0.0,
            "resolution must be > 0"
        );
        let cells = vec![Cell::Free; width * height];
        OccupancyGrid {
            width,
            height,
            resolution_m,
            origin,
            clearance: Clearance::build(width, height, &cells),
            cells,
        }
    }

    /// A grid from its cells, row by row from the bottom (`cells[j * width +
    /// i]` is cell `(i, j)`). Fails if the geometry is out of range
    /// ([`OccupancyGrid::check_geometry`]) or if there are not `width ×
    /// height` cells. Faster than [`OccupancyGrid::new`] followed by one
    /// [`OccupancyGrid::set`] per cell.
    pub fn from_cells(
        width: usize,
        height: usize,
        resolution_m: f64,
        origin: Pose,
        cells: Vec<Cell>,
    ) -> Result<OccupancyGrid> {
        OccupancyGrid::check_geometry(width, height, resolution_m, origin)?;
        if width.checked_mul(height) != Some(cells.len()) {
            return Err(Error::Geometry(format!(
                "a {width} × {height} grid needs {} cells, got {}",
                width.saturating_mul(height),
                cells.len()
            )));
        }
        Ok(OccupancyGrid {
            width,
            height,
            resolution_m,
            origin,
            clearance: Clearance::build(width, height, &cells),
            cells,
        })
    }

    /// Checks a grid's geometry before anything is made of it: the
    /// resolution within [`MIN_RESOLUTION_M`]…[`MAX_RESOLUTION_M`], the
    /// origin finite and within [`MAX_ORIGIN_M`] of the world's, the
    /// extent (cells × resolution) at most [`MAX_EXTENT_M`] a side. Errors
    /// name the value and the limit.
    pub fn check_geometry(width: usize, height: usize, resolution_m: f64, origin: Pose) -> Result<()> {
        check_resolution("resolution_m", resolution_m)?;
        check_origin("origin", origin)?;
        let (w_m, h_m) = (width as f64 * resolution_m, height as f64 * resolution_m);
        if w_m > MAX_EXTENT_M || h_m > MAX_EXTENT_M {
            return Err(Error::Geometry(format!(
                "a map of {width} × {height} cells of {resolution_m} m spans {w_m} × {h_m} m, more than the {MAX_EXTENT_M} m a side a map may span (sim::grid::MAX_EXTENT_M: the robots here drive in buildings and campuses, and several of their structures grow with the distances; cover a larger area with several maps)"
            )));
        }
        Ok(())
    }

    /// Columns.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Rows.
    pub fn height(&self) -> usize {
        self.height
    }

    /// Side of a cell, metres.
    pub fn resolution_m(&self) -> f64 {
        self.resolution_m
    }

    /// Pose of the map's lower-left corner in the world.
    pub fn origin(&self) -> Pose {
        self.origin
    }

    /// Whether the cell is inside the grid.
    #[inline]
    pub fn contains(&self, c: CellIndex) -> bool {
        c.i >= 0 && c.j >= 0 && (c.i as usize) < self.width && (c.j as usize) < self.height
    }

    /// The cell's state; outside the grid everything is unknown.
    #[inline]
    pub fn get(&self, c: CellIndex) -> Cell {
        if self.contains(c) {
            self.cells[c.j as usize * self.width + c.i as usize]
        } else {
            Cell::Unknown
        }
    }

    /// Whether the cell blocks motion and sensing (occupied, unknown, or
    /// outside the map).
    #[inline]
    pub fn blocked(&self, c: CellIndex) -> bool {
        self.get(c) != Cell::Free
    }

    /// Sets a cell (ignored outside the grid). Changing a cell between free
    /// and blocked also repairs the clearance field around it: a few
    /// microseconds for a new obstacle, well under a millisecond for a freed
    /// cell. To
    /// fill a whole grid, build it with [`OccupancyGrid::from_cells`].
    pub fn set(&mut self, c: CellIndex, v: Cell) {
        if self.contains(c) {
            let (i, j) = (c.i as usize, c.j as usize);
            let k = j * self.width + i;
            let was_blocked = self.cells[k] != Cell::Free;
            self.cells[k] = v;
            if was_blocked != (v != Cell::Free) {
                self.clearance.update(&self.cells, i, j);
            }
        }
    }

    /// Clearance of an in-grid cell: chessboard distance in cells to the
    /// nearest blocked cell or to the outside, capped at
    /// [`crate::clearance::CLEARANCE_CAP`]; 0 for a blocked cell.
    /// `None` outside the grid.
    #[inline]
    pub fn clearance(&self, c: CellIndex) -> Option<u8> {
        self.contains(c)
            .then(|| self.clearance.at(c.i as usize, c.j as usize))
    }

    /// The clearance field, for the ray caster.
    #[inline]
    pub(crate) fn clearance_field(&self) -> &Clearance {
        &self.clearance
    }

    /// Counts of free, occupied and unknown cells.
    pub fn counts(&self) -> CellCounts {
        let mut n = CellCounts::default();
        for &c in &self.cells {
            match c {
                Cell::Free => n.free += 1,
                Cell::Occupied => n.occupied += 1,
                Cell::Unknown => n.unknown += 1,
            }
        }
        n
    }

    /// All cells, row by row from the bottom.
    pub fn cells(&self) -> &[Cell] {
        &self.cells
    }

    /// A world point in the map frame (metres from the map's corner).
    #[inline]
    pub fn to_map(&self, p: Vec2) -> Vec2 {
        self.origin.inverse_transform(p)
    }

    /// A map-frame point in the world.
    #[inline]
    pub fn to_world(&self, p: Vec2) -> Vec2 {
        self.origin.transform(p)
    }

    /// The cell containing a world point.
    #[inline]
    pub fn cell_of(&self, p: Vec2) -> CellIndex {
        let m = self.to_map(p);
        CellIndex {
            i: (m.x / self.resolution_m).floor() as i64,
            j: (m.y / self.resolution_m).floor() as i64,
        }
    }

    /// The centre of a cell, in the world.
    pub fn cell_center(&self, c: CellIndex) -> Vec2 {
        self.to_world(Vec2::new(
            (c.i as f64 + 0.5) * self.resolution_m,
            (c.j as f64 + 0.5) * self.resolution_m,
        ))
    }

    /// Whether a world point lies in a blocked cell.
    #[inline]
    pub fn blocked_at(&self, p: Vec2) -> bool {
        self.blocked(self.cell_of(p))
    }

    /// Free area, m².
    pub fn free_area_m2(&self) -> f64 {
        let free = self.cells.iter().filter(|&&c| c == Cell::Free).count();
        free as f64 * self.resolution_m * self.resolution_m
    }

    /// The grid as a controller's static map (the same cells and geometry,
    /// without the simulator's clearance field).
    pub fn grid_map(&self) -> robot::GridMap {
        robot::GridMap::new(
            self.width,
            self.height,
            self.resolution_m,
            self.origin,
            self.cells.clone(),
        )
        .expect("an occupancy grid's geometry is checked when it is built")
    }

    /// Whether a disc (e.g. the robot's footprint) overlaps a blocked cell.
    /// Exact for axis-aligned cells in the map frame: a cell overlaps the
    /// disc when its closest point to the centre is within the radius.
    pub fn disc_blocked(&self, center: Vec2, radius_m: f64) -> bool {
        let m = self.to_map(center);
        let r = self.resolution_m;
        let (i0, i1) = (
            ((m.x - radius_m) / r).floor() as i64,
            ((m.x + radius_m) / r).floor() as i64,
        );
        let (j0, j1) = (
            ((m.y - radius_m) / r).floor() as i64,
            ((m.y + radius_m) / r).floor() as i64,
        );
        for j in j0..=j1 {
            let cy = (m.y).clamp(j as f64 * r, (j + 1) as f64 * r);
            for i in i0..=i1 {
                let c = CellIndex { i, j };
                if !self.blocked(c) {
                    continue;
                }
                let cx = (m.x).clamp(i as f64 * r, (i + 1) as f64 * r);
                if (cx - m.x).powi(2) + (cy - m.y).powi(2) < radius_m * radius_m {
                    return true;
                }
            }
        }
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn world_cell_world_round_trip_with_rotated_origin() {
        let g = OccupancyGrid::new(100, 50, 0.05, Pose::new(-2.0, 3.0, 0.3));
        for &(x, y) in &[(-1.5, 3.7), (0.0, 4.0), (1.0, 5.0)] {
            let c = g.cell_of(Vec2::new(x, y));
            let back = g.cell_center(c);
            assert_eq!(g.cell_of(back), c);
            assert!(back.dist(Vec2::new(x, y)) <= 0.05 * std::f64::consts::SQRT_2 / 2.0 + 1e-12);
        }
    }

    #[test]
    fn outside_is_blocked_and_discs_touch_walls() {
        let mut g = OccupancyGrid::new(10, 10, 0.1, Pose::default());
        assert!(g.blocked(CellIndex { i: -1, j: 0 }));
        g.set(CellIndex { i: 5, j: 5 }, Cell::Occupied);
        assert!(g.disc_blocked(Vec2::new(0.45, 0.55), 0.06));
        assert!(!g.disc_blocked(Vec2::new(0.3, 0.3), 0.05));
        assert!((g.free_area_m2() - 0.99).abs() < 1e-12);
    }
}
