//! The rectangle of map cells a planner works on.
//!
//! A [`Window`] is `width × height` cells of a [`GridMap`], its lower-left
//! cell at `min` (map cell indices, which may lie outside the map: cells
//! outside the map are unknown). It carries the map's frame (resolution and
//! origin pose), so it converts between world points, cell indices and its
//! own row-major indices. The local planner uses a square window centred on
//! the robot ([`Window::centred`], 10 m × 10 m by default); the global
//! planner uses the whole map ([`Window::whole`]).

use robot::{CellIndex, GridMap, Pose, Vec2};

use super::PlanningError;

/// Largest number of cells in a window (2³⁰, ≈ 32 000 × 32 000): indices fit
/// in `u32` with room for a padding ring.
pub const MAX_WINDOW_CELLS: usize = 1 << 30;

/// Largest cell index magnitude accepted for a window corner or a point
/// (2⁴⁰ cells): far beyond any map, small enough that index arithmetic never
/// overflows.
const MAX_CELL_INDEX: i64 = 1 << 40;

/// A rectangle of map cells in the map's frame (module docs).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Window {
    min: CellIndex,
    width: usize,
    height: usize,
    resolution_m: f64,
    origin: Pose,
}

impl Window {
    /// The window of `width × height` cells of `map` whose lower-left cell
    /// is `min`.
    ///
    /// Errors: an empty window, more than [`MAX_WINDOW_CELLS`] cells, or a
    /// corner farther than 2⁴⁰ cells from the map's origin.
    pub fn new(map: &GridMap, min: CellIndex, width: usize, height: usize) -> Result<Window, PlanningError> {
        let cells = width.checked_mul(height);
        if width == 0 || height == 0 || cells.is_none_or(|n| n > MAX_WINDOW_CELLS) {
            return Err(PlanningError::BadWindow {
                width,
                height,
                reason: "a window has 1 to 2^30 cells",
            });
        }
        if min.i.abs() > MAX_CELL_INDEX || min.j.abs() > MAX_CELL_INDEX {
            return Err(PlanningError::BadWindow {
                width,
                height,
                reason: "the window's corner is more than 2^40 cells from the map",
            });
        }
        Ok(Window {
            min,
            width,
            height,
            resolution_m: map.resolution_m(),
            origin: map.origin(),
        })
    }

    /// The whole map.
    pub fn whole(map: &GridMap) -> Result<Window, PlanningError> {
        Window::new(map, CellIndex { i: 0, j: 0 }, map.width(), map.height())
    }

    /// A square window of side `size_m` (rounded to whole cells, at least
    /// one) centred on the cell containing `centre`, which is cell
    /// `(side/2, side/2)` of the window (a 10 m window at 0.05 m is
    /// 200 × 200 cells, the centre cell at (100, 100)).
    ///
    /// Errors: `size_m` not a finite number > 0 ([`PlanningError::BadParam`]),
    /// `centre` not finite ([`PlanningError::BadPoint`]), or a window too
    /// large ([`PlanningError::BadWindow`]).
    pub fn centred(map: &GridMap, centre: Vec2, size_m: f64) -> Result<Window, PlanningError> {
        if !(size_m.is_finite() && size_m > 0.0) {
            return Err(PlanningError::BadParam {
                name: "window_size_m",
                value: size_m,
                expected: "a finite number > 0",
            });
        }
        let c = checked_cell_of(map.resolution_m(), map.origin(), "window centre", centre)?;
        let side_f = (size_m / map.resolution_m()).round().max(1.0);
        if side_f > (MAX_WINDOW_CELLS as f64).sqrt() {
            return Err(PlanningError::BadWindow {
                width: usize::MAX,
                height: usize::MAX,
                reason: "a window has 1 to 2^30 cells",
            });
        }
        let side = side_f as usize;
        let half = (side / 2) as i64;
        Window::new(
            map,
            CellIndex {
                i: c.i - half,
                j: c.j - half,
            },
            side,
            side,
        )
    }

    /// Lower-left cell (map cell indices).
    pub fn min(&self) -> CellIndex {
        self.min
    }

    /// Columns.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Rows.
    pub fn height(&self) -> usize {
        self.height
    }

    /// Number of cells.
    pub fn len(&self) -> usize {
        self.width * self.height
    }

    /// Always false: a window has at least one cell.
    pub fn is_empty(&self) -> bool {
        false
    }

    /// Side of a cell, metres (the map's).
    pub fn resolution_m(&self) -> f64 {
        self.resolution_m
    }

    /// Pose of the map's lower-left corner in the world (the map's origin).
    pub fn origin(&self) -> Pose {
        self.origin
    }

    /// Whether a map cell lies in the window.
    #[inline]
    pub fn contains(&self, c: CellIndex) -> bool {
        let (u, v) = (c.i.wrapping_sub(self.min.i), c.j.wrapping_sub(self.min.j));
        u >= 0 && v >= 0 && (u as u64) < self.width as u64 && (v as u64) < self.height as u64
    }

    /// Row-major index of a map cell in the window (`v · width + u` with
    /// `(u, v)` the cell's offset from `min`), if inside.
    #[inline]
    pub fn index_of(&self, c: CellIndex) -> Option<usize> {
        if self.contains(c) {
            let (u, v) = ((c.i - self.min.i) as usize, (c.j - self.min.j) as usize);
            Some(v * self.width + u)
        } else {
            None
        }
    }

    /// The map cell at a row-major index of the window (`index < len()`).
    #[inline]
    pub fn cell_at(&self, index: usize) -> CellIndex {
        CellIndex {
            i: self.min.i + (index % self.width) as i64,
            j: self.min.j + (index / self.width) as i64,
        }
    }

    /// The map cell containing a world point (it may lie outside the
    /// window). Error for a non-finite point or one farther than 2⁴⁰ cells.
    pub fn cell_of(&self, what: &'static str, p: Vec2) -> Result<CellIndex, PlanningError> {
        checked_cell_of(self.resolution_m, self.origin, what, p)
    }

    /// The centre of a map cell, in the world.
    pub fn cell_center(&self, c: CellIndex) -> Vec2 {
        self.origin.transform(Vec2::new(
            (c.i as f64 + 0.5) * self.resolution_m,
            (c.j as f64 + 0.5) * self.resolution_m,
        ))
    }

    /// A world point in window cell units: `(0, 0)` is the lower-left
    /// corner of cell `min`, `(u + 0.5, v + 0.5)` the centre of the cell at
    /// offset `(u, v)`.
    pub fn to_window(&self, p: Vec2) -> (f64, f64) {
        let m = self.origin.inverse_transform(p);
        (
            m.x / self.resolution_m - self.min.i as f64,
            m.y / self.resolution_m - self.min.j as f64,
        )
    }

    /// The inverse of [`Window::to_window`].
    pub fn from_window(&self, x: f64, y: f64) -> Vec2 {
        self.origin.transform(Vec2::new(
            (x + self.min.i as f64) * self.resolution_m,
            (y + self.min.j as f64) * self.resolution_m,
        ))
    }
}

/// The map cell containing `p`, refusing non-finite and absurdly far points.
fn checked_cell_of(
    resolution_m: f64,
    origin: Pose,
    what: &'static str,
    p: Vec2,
) -> Result<CellIndex, PlanningError> {
    let bad = || PlanningError::BadPoint { what, point: p };
    if !(p.x.is_finite() && p.y.is_finite()) {
        return Err(bad());
    }
    let m = origin.inverse_transform(p);
    let (x, y) = ((m.x / resolution_m).floor(), (m.y / resolution_m).floor());
    let limit = MAX_CELL_INDEX as f64;
    if !(x.abs() <= limit && y.abs() <= limit) {
        return Err(bad());
    }
    Ok(CellIndex {
        i: x as i64,
        j: y as i64,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use robot::Cell;

    fn map() -> GridMap {
        GridMap::new(
            300,
            250,
            0.05,
            Pose::new(-2.0, 1.0, 0.0),
            vec![Cell::Free; 300 * 250],
        )
        .unwrap()
    }

    #[test]
    fn a_ten_metre_window_is_200_cells_centred_on_the_robot() {
        let m = map();
        let robot = m.cell_center(CellIndex { i: 150, j: 120 });
        let w = Window::centred(&m, robot, 10.0).unwrap();
        assert_eq!((w.width(), w.height()), (200, 200));
        assert_eq!(w.min(), CellIndex { i: 50, j: 20 });
        assert_eq!(w.index_of(CellIndex { i: 150, j: 120 }), Some(100 * 200 + 100));
        assert_eq!(w.cell_at(100 * 200 + 100), CellIndex { i: 150, j: 120 });
        let (x, y) = w.to_window(robot);
        assert!((x - 100.5).abs() < 1e-9 && (y - 100.5).abs() < 1e-9);
        let back = w.from_window(x, y);
        assert!(back.dist(robot) < 1e-9);
        assert!(!w.contains(CellIndex { i: 49, j: 20 }));
        assert!(w.contains(CellIndex { i: 249, j: 219 }));
        assert!(!w.contains(CellIndex { i: 250, j: 219 }));
    }

    #[test]
    fn bad_windows_and_points_are_errors() {
        let m = map();
        assert!(matches!(
            Window::centred(&m, Vec2::new(0.0, 0.0), f64::NAN),
            Err(PlanningError::BadParam { .. })
        ));
        assert!(matches!(
            Window::centred(&m, Vec2::new(0.0, 0.0), -1.0),
            Err(PlanningError::BadParam { .. })
        ));
        assert!(matches!(
            Window::centred(&m, Vec2::new(f64::INFINITY, 0.0), 10.0),
            Err(PlanningError::BadPoint { .. })
        ));
        assert!(matches!(
            Window::centred(&m, Vec2::new(1e300, 0.0), 10.0),
            Err(PlanningError::BadPoint { .. })
        ));
        assert!(matches!(
            Window::centred(&m, Vec2::new(0.0, 0.0), 1e9),
            Err(PlanningError::BadWindow { .. })
        ));
        assert!(matches!(
            Window::new(&m, CellIndex { i: 0, j: 0 }, 0, 5),
            Err(PlanningError::BadWindow { .. })
        ));
    }
}
