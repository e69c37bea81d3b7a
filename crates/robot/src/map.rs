//! A static occupancy map, as a robot receives it from a map server.
//!
//! A grid of `width × height` square cells of side `resolution_m`. Cell
//! `(0, 0)` is the lower-left corner of the map; its lower-left corner is at
//! `origin` in the world frame (position and rotation, as in ROS
//! `map_server`). Row `j` is `y`, column `i` is `x` in the map frame.
//!
//! This is plain data for controllers (localization, planning): the
//! simulator has its own grid with acceleration structures and converts to
//! this one; a real robot would fill it from its map server.

use crate::{Pose, Vec2};

/// State of a cell.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
#[repr(u8)]
pub enum Cell {
    /// Nothing there.
    #[default]
    Free = 0,
    /// An obstacle.
    Occupied = 1,
    /// Not mapped (counts as an obstacle).
    Unknown = 2,
}

/// Index of a cell: column `i` (x), row `j` (y), from the lower-left corner.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize)]
pub struct CellIndex {
    /// Column.
    pub i: i64,
    /// Row.
    pub j: i64,
}

/// Why a map could not be built.
#[derive(Debug, Clone, PartialEq)]
pub enum MapError {
    /// The resolution is not a finite number > 0, or the origin not finite.
    BadGeometry(String),
    /// `cells.len() != width × height`.
    CellCount {
        /// Columns.
        width: usize,
        /// Rows.
        height: usize,
        /// Cells given.
        cells: usize,
    },
}

impl std::fmt::Display for MapError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            MapError::BadGeometry(what) => write!(f, "map geometry: {what}"),
            MapError::CellCount { width, height, cells } => write!(
                f,
                "a {width} × {height} map needs {} cells, got {cells}",
                width.saturating_mul(*height)
            ),
        }
    }
}

impl std::error::Error for MapError {}

/// A static occupancy map.
#[derive(Debug, Clone, PartialEq)]
pub struct GridMap {
    width: usize,
    height: usize,
    resolution_m: f64,
    origin: Pose,
    cells: Vec<Cell>,
}

impl GridMap {
    /// A map from its cells, row by row from the bottom (`cells[j * width +
    /// i]` is cell `(i, j)`).
    pub fn new(
        width: usize,
        height: usize,
        resolution_m: f64,
        origin: Pose,
        cells: Vec<Cell>,
    ) -> Result<GridMap, MapError> {
        if !(resolution_m.is_finite() && resolution_m > 0.0) {
            return Err(MapError::BadGeometry(format!(
                "resolution must be a finite number > 0, got {resolution_m}"
            )));
        }
        if !(origin.x_m.is_finite() && origin.y_m.is_finite() && origin.theta_rad.is_finite()) {
            return Err(MapError::BadGeometry(format!(
                "origin must be finite, got {origin:?}"
            )));
        }
        if width.checked_mul(height) != Some(cells.len()) {
            return Err(MapError::CellCount {
                width,
                height,
                cells: cells.len(),
            });
        }
        Ok(GridMap {
            width,
            height,
            resolution_m,
            origin,
            cells,
        })
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

    /// All cells, row by row from the bottom.
    pub fn cells(&self) -> &[Cell] {
        &self.cells
    }

    /// Whether the cell is inside the map.
    #[inline]
    pub fn contains(&self, c: CellIndex) -> bool {
        c.i >= 0 && c.j >= 0 && (c.i as usize) < self.width && (c.j as usize) < self.height
    }

    /// The cell's state; outside the map everything is unknown.
    #[inline]
    pub fn get(&self, c: CellIndex) -> Cell {
        if self.contains(c) {
            self.cells[c.j as usize * self.width + c.i as usize]
        } else {
            Cell::Unknown
        }
    }

    /// Whether the cell blocks motion (occupied, unknown, or outside).
    #[inline]
    pub fn blocked(&self, c: CellIndex) -> bool {
        self.get(c) != Cell::Free
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
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cells_round_trip_and_outside_is_unknown() {
        let mut cells = vec![Cell::Free; 20 * 10];
        cells[3 * 20 + 4] = Cell::Occupied;
        let m = GridMap::new(20, 10, 0.1, Pose::new(-1.0, 2.0, 0.3), cells).unwrap();
        let c = CellIndex { i: 4, j: 3 };
        assert_eq!(m.get(c), Cell::Occupied);
        assert_eq!(m.cell_of(m.cell_center(c)), c);
        assert!(m.blocked(CellIndex { i: -1, j: 0 }));
        assert_eq!(m.get(CellIndex { i: 20, j: 0 }), Cell::Unknown);
        assert!(m.blocked_at(m.cell_center(c)));
    }

    #[test]
    fn bad_maps_are_errors() {
        assert!(GridMap::new(2, 2, 0.0, Pose::default(), vec![Cell::Free; 4]).is_err());
        assert!(GridMap::new(2, 2, f64::NAN, Pose::default(), vec![Cell::Free; 4]).is_err());
        assert!(GridMap::new(2, 2, 0.1, Pose::new(f64::INFINITY, 0.0, 0.0), vec![Cell::Free; 4]).is_err());
        let e = GridMap::new(2, 3, 0.1, Pose::default(), vec![Cell::Free; 4]).unwrap_err();
        assert_eq!(e.to_string(), "a 2 × 3 map needs 6 cells, got 4");
    }
}
