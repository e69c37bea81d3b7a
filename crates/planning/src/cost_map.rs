//! The cost map the navigation function is propagated over.
//!
//! Built for a [`Window`] of a static [`GridMap`], plus obstacle points in
//! world coordinates (laser endpoints, see [`laser_endpoints`], so that
//! people and furniture not on the map count). Every cell gets an
//! *intrinsic cost* `c ≥ 0` or is *lethal* (`c = ∞`, the robot's centre
//! may not enter it):
//!
//! * **Obstacles**: occupied cells of the map, **unknown cells and cells
//!   outside the map** (the planner never goes where the map knows nothing;
//!   with a whole-map window the map's edge is a wall), and cells containing
//!   an obstacle point.
//! * `d` = Euclidean distance in metres between the cell's centre and the
//!   centre of the nearest obstacle cell (exact, [`super::distance_transform`]).
//! * **Lethal** when `d ≤ inscribed_radius_m` (the robot's footprint, as a
//!   disc, would overlap the obstacle cell's centre).
//! * Otherwise, as costmap_2d's inflation layer (ROS navigation,
//!   `inflation_layer.cpp`) but on the scale the navigation function uses:
//!
//!   `c(d) = max_cost · exp(−decay_per_m · (d − inscribed_radius_m))` for
//!   `d ≤ inflation_radius_m`, and `c(d) = 0` beyond.
//!
//!   Traversing a cell costs `(1 + c)` times the distance travelled in it
//!   (K. Konolige, *A gradient method for realtime robot control*, IROS
//!   2000: the intrinsic cost that keeps paths away from obstacles). The
//!   default decay, 10 per metre, is costmap_2d's default
//!   `cost_scaling_factor`; with the defaults a cell just outside the
//!   inscribed radius (0.35 m) is 6× as expensive as open floor, one at
//!   0.45 m 2.8×, at 0.55 m 1.7×, at 0.75 m 1.09×, and the cost left at the
//!   1 m cut-off, 0.0075, makes the step there negligible. A slower decay
//!   keeps the robot farther from walls but makes it detour round cluttered
//!   passages (on `building_31`, a decay of 5 per metre lengthens one of the
//!   test routes by 10 % to avoid a gap between furniture).
//!
//! The distance transform runs over the window grown by
//! `⌈inflation_radius_m / resolution⌉` cells on each side, so a wall just
//! outside the window still inflates the cells inside it. Building costs
//! `O((w + 2m)(h + 2m) + points)` time for a `w × h` window and margin `m`;
//! the buffers are kept for the next build ([`CostMap::rebuild`]).
//!
//! Built on a [`StaticCostLayer`] instead ([`CostMap::build_on`],
//! [`CostMap::rebuild_on`]), the map's part comes precomputed and only the
//! obstacle points are added: the same cost map, bit for bit (see
//! [`super::static_layer`]), for a copy of the window and a little work per
//! sensed cell.

use std::sync::Arc;

use robot::{Cell, CellIndex, GridMap, LaserScan, Pose, Vec2};

use super::cost_model::{CostParams, cost_table, margin_cells};
use super::distance_transform::{BEYOND, DistanceTransform};
use super::{PlanningError, StaticCostLayer, Window};

/// Why a cell is lethal.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub enum Blocked {
    /// An occupied cell of the map.
    Occupied,
    /// An unknown cell of the map.
    Unknown,
    /// Outside the map (unknown).
    OutsideMap,
    /// A cell containing an obstacle point (seen by a sensor).
    Sensed,
    /// A free cell within the inscribed radius of an obstacle.
    Inflated {
        /// Distance from the cell's centre to the nearest obstacle cell's
        /// centre, metres.
        clearance_m: f64,
    },
}

impl std::fmt::Display for Blocked {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Blocked::Occupied => write!(f, "an occupied cell"),
            Blocked::Unknown => write!(f, "an unknown cell"),
            Blocked::OutsideMap => write!(f, "outside the map"),
            Blocked::Sensed => write!(f, "an obstacle seen by the sensors"),
            Blocked::Inflated { clearance_m } => write!(
                f,
                "{clearance_m:.3} m from an obstacle, within the robot's inscribed radius"
            ),
        }
    }
}

/// What a build produced.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
pub struct CostMapInfo {
    /// Cells in the window.
    pub cells: usize,
    /// Cells of the window with a finite cost.
    pub free_cells: usize,
    /// Obstacle points that fell in a free cell of the window or its margin
    /// and turned it into an obstacle.
    pub sensed_cells: usize,
    /// Obstacle points ignored: not finite.
    pub ignored_points: usize,
    /// Margin around the window over which distances were computed, cells.
    pub margin_cells: usize,
}

// Class of a cell of the grown window (0: free; anything else blocks).
const FREE: u8 = 0;
const OCCUPIED: u8 = 1;
const UNKNOWN: u8 = 2;
const OUTSIDE: u8 = 3;
const SENSED: u8 = 4;

/// Intrinsic costs of a window (module docs).
#[derive(Debug, Clone)]
pub struct CostMap {
    params: CostParams,
    window: Window,
    info: CostMapInfo,
    /// Built on a static layer: the layer, and the distinct free map cells
    /// hit by obstacle points within the margin, sorted. `None`: built from
    /// the map, with the grown grid below.
    layer: Option<Arc<StaticCostLayer>>,
    sensed: Vec<CellIndex>,
    /// Margin `m` in cells and the grown grid's width and height.
    margin: usize,
    grown_w: usize,
    grown_h: usize,
    /// Per cell of the grown grid: its class.
    class: Vec<u8>,
    /// Per cell of the grown grid: squared distance to the nearest obstacle
    /// cell, cells², or `BEYOND`.
    dist_sq: Vec<u32>,
    /// Per cell of the window plus a ring of lethal cells: the cost.
    cost: Vec<f64>,
    /// Cost by squared distance in cells (`0..=cap²`), for `table_res`.
    table: Vec<f64>,
    table_res: f64,
    transform: DistanceTransform,
}

impl CostMap {
    /// Builds the cost map of `window` of `map` with obstacle points (world
    /// coordinates; non-finite points are ignored and counted).
    ///
    /// Errors: invalid parameters, a window that belongs to another map
    /// (other resolution or origin), or an inflation radius of more than
    /// 30 000 cells.
    pub fn build(
        params: CostParams,
        map: &GridMap,
        window: Window,
        obstacles: &[Vec2],
    ) -> Result<CostMap, PlanningError> {
        params.validate()?;
        let mut c = CostMap {
            params,
            window,
            info: CostMapInfo::default(),
            layer: None,
            sensed: Vec::new(),
            margin: 0,
            grown_w: 0,
            grown_h: 0,
            class: Vec::new(),
            dist_sq: Vec::new(),
            cost: Vec::new(),
            table: Vec::new(),
            table_res: f64::NAN,
            transform: DistanceTransform::new(),
        };
        c.rebuild(map, window, obstacles)?;
        Ok(c)
    }

    /// Rebuilds for another window or other obstacles, reusing the memory.
    /// On error the cost map is left as it was.
    pub fn rebuild(
        &mut self,
        map: &GridMap,
        window: Window,
        obstacles: &[Vec2],
    ) -> Result<CostMapInfo, PlanningError> {
        if window.resolution_m() != map.resolution_m() || window.origin() != map.origin() {
            return Err(PlanningError::WindowMapMismatch);
        }
        let res = map.resolution_m();
        let cap = margin_cells(&self.params, res)?;
        let m = cap as usize;
        let (w, h) = (window.width(), window.height());
        check_grown(&window, m)?;
        let (gw, gh) = (w + 2 * m, h + 2 * m);
        self.layer = None;
        self.sensed.clear();
        self.window = window;
        self.margin = m;
        self.grown_w = gw;
        self.grown_h = gh;
        if self.table_res != res || self.table.len() != (cap as usize + 1).pow(2) {
            self.table = cost_table(&self.params, res, cap);
            self.table_res = res;
        }

        // Classes of the grown grid: the map's cells, outside is OUTSIDE.
        self.class.clear();
        self.class.resize(gw * gh, OUTSIDE);
        let cells = map.cells();
        let (mw, mh) = (map.width() as i64, map.height() as i64);
        let i0 = window.min().i - m as i64; // map column of grown column 0
        let j0 = window.min().j - m as i64;
        let lo = i0.max(0); // overlapping map columns lo..hi
        let hi = (i0 + gw as i64).min(mw);
        for gj in 0..gh {
            let mj = j0 + gj as i64;
            if mj < 0 || mj >= mh || lo >= hi {
                continue;
            }
            let src = &cells[(mj * mw + lo) as usize..(mj * mw + hi) as usize];
            let dst = &mut self.class[gj * gw + (lo - i0) as usize..][..src.len()];
            for (d, s) in dst.iter_mut().zip(src) {
                *d = match s {
                    Cell::Free => FREE,
                    Cell::Occupied => OCCUPIED,
                    Cell::Unknown => UNKNOWN,
                };
            }
        }
        let mut sensed = 0;
        let mut ignored = 0;
        for &p in obstacles {
            let Ok(c) = window.cell_of("obstacle point", p) else {
                ignored += 1;
                continue;
            };
            let (gi, gj) = (c.i - i0, c.j - j0);
            if gi >= 0 && gj >= 0 && (gi as usize) < gw && (gj as usize) < gh {
                let k = gj as usize * gw + gi as usize;
                if self.class[k] == FREE {
                    self.class[k] = SENSED;
                    sensed += 1;
                }
            }
        }

        self.transform
            .compute(&self.class, gw, gh, cap, &mut self.dist_sq);

        // Costs of the window, with a ring of lethal cells around it.
        let pw = w + 2;
        self.cost.clear();
        self.cost.resize(pw * (h + 2), f64::INFINITY);
        let mut free = 0;
        for v in 0..h {
            let src = &self.dist_sq[(v + m) * gw + m..][..w];
            let dst = &mut self.cost[(v + 1) * pw + 1..][..w];
            for (d, &s) in dst.iter_mut().zip(src) {
                *d = if s == BEYOND { 0.0 } else { self.table[s as usize] };
                free += usize::from(d.is_finite());
            }
        }
        self.info = CostMapInfo {
            cells: w * h,
            free_cells: free,
            sensed_cells: sensed,
            ignored_points: ignored,
            margin_cells: m,
        };
        Ok(self.info)
    }

    /// Builds the cost map of `window` on a static layer (of the window's
    /// map) with obstacle points: equal to [`CostMap::build`] with the
    /// layer's map and parameters, bit for bit ([`super::static_layer`]).
    ///
    /// Errors: a window of another map (other resolution or origin), or a
    /// window too large (as [`CostMap::build`]).
    pub fn build_on(
        layer: &Arc<StaticCostLayer>,
        window: Window,
        obstacles: &[Vec2],
    ) -> Result<CostMap, PlanningError> {
        let mut c = CostMap {
            params: *layer.params(),
            window,
            info: CostMapInfo::default(),
            layer: None,
            sensed: Vec::new(),
            margin: 0,
            grown_w: 0,
            grown_h: 0,
            class: Vec::new(),
            dist_sq: Vec::new(),
            cost: Vec::new(),
            table: Vec::new(),
            table_res: f64::NAN,
            transform: DistanceTransform::new(),
        };
        c.rebuild_on(layer, window, obstacles)?;
        Ok(c)
    }

    /// [`CostMap::build_on`] reusing the memory (the cost model becomes the
    /// layer's). On error the cost map is left as it was.
    pub fn rebuild_on(
        &mut self,
        layer: &Arc<StaticCostLayer>,
        window: Window,
        obstacles: &[Vec2],
    ) -> Result<CostMapInfo, PlanningError> {
        if (window.resolution_m(), window.origin()) != layer.frame() {
            return Err(PlanningError::WindowMapMismatch);
        }
        let m = layer.margin_cells();
        check_grown(&window, m)?;
        if self.params != *layer.params() {
            // The table of a build from the map was for the old model.
            self.params = *layer.params();
            self.table.clear();
            self.table_res = f64::NAN;
        }
        self.window = window;
        self.layer = Some(Arc::clone(layer));
        self.class.clear();
        self.dist_sq.clear();
        self.margin = m;
        let (w, h) = (window.width() as i64, window.height() as i64);
        self.grown_w = window.width() + 2 * m;
        self.grown_h = window.height() + 2 * m;
        let free = layer.copy_window(&window, &mut self.cost);

        // The distinct free map cells hit within the grown window.
        self.sensed.clear();
        let mut ignored = 0;
        let (i0, j0) = (window.min().i - m as i64, window.min().j - m as i64);
        for &p in obstacles {
            let Ok(c) = window.cell_of("obstacle point", p) else {
                ignored += 1;
                continue;
            };
            let (gi, gj) = (c.i - i0, c.j - j0);
            if gi >= 0
                && gj >= 0
                && gi < w + 2 * m as i64
                && gj < h + 2 * m as i64
                && layer.cell(c) == Some(Cell::Free)
            {
                self.sensed.push(c);
            }
        }
        self.sensed.sort_unstable_by_key(|c| (c.j, c.i));
        self.sensed.dedup();
        let mut lost = 0;
        for &s in &self.sensed {
            lost += layer.stamp(&window, s, &mut self.cost);
        }
        self.info = CostMapInfo {
            cells: window.len(),
            free_cells: free - lost,
            sensed_cells: self.sensed.len(),
            ignored_points: ignored,
            margin_cells: m,
        };
        Ok(self.info)
    }

    /// The parameters.
    pub fn params(&self) -> &CostParams {
        &self.params
    }

    /// The window.
    pub fn window(&self) -> Window {
        self.window
    }

    /// What the last build produced.
    pub fn info(&self) -> CostMapInfo {
        self.info
    }

    /// The intrinsic cost of a map cell: `∞` if lethal or outside the window.
    #[inline]
    pub fn cost(&self, c: CellIndex) -> f64 {
        match self.window.index_of(c) {
            Some(k) => self.cost[self.padded(k)],
            None => f64::INFINITY,
        }
    }

    /// Whether a map cell is lethal (or outside the window).
    pub fn is_lethal(&self, c: CellIndex) -> bool {
        self.cost(c).is_infinite()
    }

    /// Why a cell of the window is lethal; `None` for a cell with a finite
    /// cost or outside the window.
    pub fn why_lethal(&self, c: CellIndex) -> Option<Blocked> {
        let k = self.window.index_of(c)?;
        if self.cost[self.padded(k)].is_finite() {
            return None;
        }
        if let Some(layer) = &self.layer {
            return Some(match layer.cell(c) {
                None => Blocked::OutsideMap,
                Some(Cell::Occupied) => Blocked::Occupied,
                Some(Cell::Unknown) => Blocked::Unknown,
                Some(Cell::Free)
                    if self
                        .sensed
                        .binary_search_by_key(&(c.j, c.i), |s| (s.j, s.i))
                        .is_ok() =>
                {
                    Blocked::Sensed
                }
                Some(Cell::Free) => Blocked::Inflated {
                    clearance_m: (self.layered_dist_sq(layer, c) as f64).sqrt() * self.window.resolution_m(),
                },
            });
        }
        let g = self.grown(k);
        Some(match self.class[g] {
            OCCUPIED => Blocked::Occupied,
            UNKNOWN => Blocked::Unknown,
            OUTSIDE => Blocked::OutsideMap,
            SENSED => Blocked::Sensed,
            _ => Blocked::Inflated {
                clearance_m: (self.dist_sq[g] as f64).sqrt() * self.window.resolution_m(),
            },
        })
    }

    /// Distance from a window cell's centre to the nearest obstacle cell's
    /// centre, metres, if within the inflation radius (rounded up to whole
    /// cells); `None` beyond it or outside the window.
    pub fn clearance_m(&self, c: CellIndex) -> Option<f64> {
        let k = self.window.index_of(c)?;
        let d2 = match &self.layer {
            Some(layer) => self.layered_dist_sq(layer, c),
            None => self.dist_sq[self.grown(k)],
        };
        (d2 != BEYOND).then(|| (d2 as f64).sqrt() * self.window.resolution_m())
    }

    /// On a static layer: the squared distance from a map cell to the
    /// nearest obstacle, the map's or a sensed cell, cells², `BEYOND` past
    /// the margin. `O(sensed cells)`.
    fn layered_dist_sq(&self, layer: &StaticCostLayer, c: CellIndex) -> u32 {
        let cap = self.margin as u64;
        self.sensed
            .iter()
            .map(|s| {
                let (dx, dy) = (s.i.abs_diff(c.i), s.j.abs_diff(c.j));
                if dx > cap || dy > cap || dx * dx + dy * dy > cap * cap {
                    BEYOND
                } else {
                    (dx * dx + dy * dy) as u32
                }
            })
            .fold(layer.dist_sq(c), u32::min)
    }

    /// Costs of the window with a ring of lethal cells around it: row-major,
    /// `(width + 2) × (height + 2)`, window cell `(u, v)` at
    /// `(v + 1)(width + 2) + u + 1`.
    pub(crate) fn padded_costs(&self) -> &[f64] {
        &self.cost
    }

    /// Padded index of a window index.
    #[inline]
    fn padded(&self, k: usize) -> usize {
        let w = self.window.width();
        (k / w + 1) * (w + 2) + k % w + 1
    }

    /// Grown-grid index of a window index.
    #[inline]
    fn grown(&self, k: usize) -> usize {
        let w = self.window.width();
        (k / w + self.margin) * self.grown_w + k % w + self.margin
    }
}

/// The window grown by `m` cells on each side must stay within 2³¹ cells.
fn check_grown(window: &Window, m: usize) -> Result<(), PlanningError> {
    let (w, h) = (window.width(), window.height());
    if (w + 2 * m)
        .checked_mul(h + 2 * m)
        .is_none_or(|n| n > 2 * super::window::MAX_WINDOW_CELLS)
    {
        return Err(PlanningError::BadWindow {
            width: w,
            height: h,
            reason: "the window and its inflation margin exceed 2^31 cells",
        });
    }
    Ok(())
}

/// Appends the world positions of a scan's echoes to `out`: beam `k` at
/// angle `angle_min_rad + k · angle_increment_rad` in the sensor frame
/// (`scan.mount` on a robot at `robot_in_world`). Beams without an echo
/// (infinite, NaN, not positive, or at or beyond `range_max_m`) are skipped.
pub fn laser_endpoints(robot_in_world: Pose, scan: &LaserScan, out: &mut Vec<Vec2>) {
    let sensor = robot_in_world.compose(&scan.mount);
    let dirs = scan.beam_directions();
    let to_world = sensor.transformer();
    out.extend(scan.ranges_m.iter().enumerate().filter_map(|(k, &r)| {
        if !(r.is_finite() && r > 0.0 && r < scan.range_max_m) {
            return None;
        }
        let (ca, sa) = dirs[k];
        Some(to_world(Vec2::new(r * ca, r * sa)))
    }));
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A `w × h` free map at 0.1 m with the given occupied and unknown cells.
    fn map(w: usize, h: usize, occupied: &[(usize, usize)], unknown: &[(usize, usize)]) -> GridMap {
        let mut cells = vec![Cell::Free; w * h];
        for &(i, j) in occupied {
            cells[j * w + i] = Cell::Occupied;
        }
        for &(i, j) in unknown {
            cells[j * w + i] = Cell::Unknown;
        }
        GridMap::new(w, h, 0.1, Pose::default(), cells).unwrap()
    }

    fn ci(i: i64, j: i64) -> CellIndex {
        CellIndex { i, j }
    }

    #[test]
    fn cost_follows_the_documented_formula() {
        let params = CostParams {
            inscribed_radius_m: 0.2,
            inflation_radius_m: 0.6,
            max_cost: 4.0,
            decay_per_m: 3.0,
        };
        let m = map(30, 30, &[(15, 15)], &[]);
        let cm = CostMap::build(params, &m, Window::whole(&m).unwrap(), &[]).unwrap();
        for i in 7..23 {
            for j in 7..23 {
                // Distance in cells; the boundaries are inclusive.
                let d_cells = (((i - 15) * (i - 15) + (j - 15) * (j - 15)) as f64).sqrt();
                let d = 0.1 * d_cells;
                let expected = if d_cells <= 2.0 {
                    f64::INFINITY
                } else if d_cells <= 6.0 {
                    4.0 * (-3.0 * (d - 0.2)).exp()
                } else {
                    0.0
                };
                let got = cm.cost(ci(i, j));
                assert!(
                    got == expected || (got - expected).abs() < 1e-12,
                    "cell ({i}, {j}) at {d} m: {got} vs {expected}"
                );
            }
        }
        // The map's edge (outside is unknown) is lethal too: cell (1, 15)
        // is 0.2 m from the outside.
        assert!(cm.is_lethal(ci(1, 15)));
        assert!(!cm.is_lethal(ci(2, 15)));
        assert_eq!(cm.why_lethal(ci(15, 15)), Some(Blocked::Occupied));
        assert!(
            matches!(cm.why_lethal(ci(16, 15)), Some(Blocked::Inflated { clearance_m }) if (clearance_m - 0.1).abs() < 1e-12)
        );
        assert_eq!(cm.why_lethal(ci(19, 15)), None);
        assert!((cm.clearance_m(ci(19, 15)).unwrap() - 0.4).abs() < 1e-12);
        assert_eq!(cm.clearance_m(ci(22, 22)), None);
    }

    #[test]
    fn the_cost_table_is_the_formula_and_non_increasing() {
        // The running minimum must change nothing for the formula (exp is
        // monotone), only guarantee the order the static layer relies on.
        for (p, res) in [
            (CostParams::default(), 0.05),
            (CostParams::default(), 0.1),
            (
                CostParams {
                    inscribed_radius_m: 0.0,
                    inflation_radius_m: 2.0,
                    max_cost: 1000.0,
                    decay_per_m: 0.3,
                },
                0.025,
            ),
        ] {
            let cap = margin_cells(&p, res).unwrap();
            let table = cost_table(&p, res, cap);
            for (d2, &c) in table.iter().enumerate() {
                let d = (d2 as f64).sqrt();
                let formula = if d <= p.inscribed_radius_m / res + 1e-9 {
                    f64::INFINITY
                } else if d <= p.inflation_radius_m / res + 1e-9 {
                    p.max_cost * (-p.decay_per_m * (d * res - p.inscribed_radius_m)).exp()
                } else {
                    0.0
                };
                assert_eq!(c.to_bits(), formula.to_bits(), "{p:?} at d² = {d2}");
            }
            assert!(table.windows(2).all(|t| t[1] <= t[0]));
        }
    }

    #[test]
    fn the_inscribed_radius_is_inclusive_despite_rounding() {
        // 0.35 / 0.05 = 6.999… in floating point: 7 cells away is lethal.
        let mut cells = vec![Cell::Free; 40 * 40];
        cells[20 * 40 + 20] = Cell::Occupied;
        let m = GridMap::new(40, 40, 0.05, Pose::default(), cells).unwrap();
        let cm = CostMap::build(CostParams::default(), &m, Window::whole(&m).unwrap(), &[]).unwrap();
        assert!(cm.is_lethal(ci(27, 20)));
        assert!(!cm.is_lethal(ci(28, 20)));
    }

    #[test]
    fn unknown_cells_and_outside_the_map_are_lethal() {
        let m = map(20, 20, &[], &[(5, 5)]);
        let p = CostParams {
            inscribed_radius_m: 0.0,
            inflation_radius_m: 0.0,
            ..CostParams::default()
        };
        let w = Window::new(&m, ci(-3, -3), 10, 10).unwrap();
        let cm = CostMap::build(p, &m, w, &[]).unwrap();
        assert_eq!(cm.why_lethal(ci(5, 5)), Some(Blocked::Unknown));
        assert_eq!(cm.why_lethal(ci(-1, 2)), Some(Blocked::OutsideMap));
        assert_eq!(cm.cost(ci(0, 0)), 0.0);
        assert_eq!(cm.cost(ci(4, 5)), 0.0);
        // Outside the window: lethal, no reason.
        assert!(cm.is_lethal(ci(7, 7)));
        assert_eq!(cm.why_lethal(ci(7, 7)), None);
        assert_eq!(cm.info().free_cells, 7 * 7 - 1);
    }

    #[test]
    fn a_wall_just_outside_the_window_inflates_cells_inside() {
        let wall: Vec<(usize, usize)> = (0..30).map(|j| (22, j)).collect();
        let m = map(30, 30, &wall, &[]);
        let p = CostParams {
            inscribed_radius_m: 0.35,
            inflation_radius_m: 0.6,
            max_cost: 1.0,
            decay_per_m: 0.0,
        };
        // Columns 10 to 19: the wall (column 22) is 3 cells to the right of
        // the window.
        let w = Window::new(&m, ci(10, 5), 10, 10).unwrap();
        let cm = CostMap::build(p, &m, w, &[]).unwrap();
        assert!(
            matches!(cm.why_lethal(ci(19, 10)), Some(Blocked::Inflated { clearance_m }) if (clearance_m - 0.3).abs() < 1e-12)
        );
        assert_eq!(cm.cost(ci(18, 10)), 1.0); // 0.4 m from the wall
        assert_eq!(cm.cost(ci(16, 10)), 1.0); // 0.6 m
        assert_eq!(cm.cost(ci(15, 10)), 0.0); // 0.7 m
        assert_eq!(cm.info().free_cells, 10 * 9);
    }

    #[test]
    fn obstacle_points_become_obstacles() {
        let m = map(20, 20, &[], &[]);
        let p = CostParams {
            inscribed_radius_m: 0.1,
            inflation_radius_m: 0.1,
            ..CostParams::default()
        };
        let w = Window::whole(&m).unwrap();
        let pts = [
            Vec2::new(1.05, 1.05),
            Vec2::new(f64::NAN, 0.0),
            Vec2::new(50.0, 50.0),
        ];
        let cm = CostMap::build(p, &m, w, &pts).unwrap();
        assert_eq!(cm.why_lethal(ci(10, 10)), Some(Blocked::Sensed));
        assert!(matches!(
            cm.why_lethal(ci(11, 10)),
            Some(Blocked::Inflated { .. })
        ));
        assert!(!cm.is_lethal(ci(12, 11)));
        let info = cm.info();
        assert_eq!((info.sensed_cells, info.ignored_points), (1, 1));
    }

    #[test]
    fn bad_parameters_are_errors() {
        let m = map(5, 5, &[], &[]);
        let w = Window::whole(&m).unwrap();
        for p in [
            CostParams {
                inscribed_radius_m: -0.1,
                ..CostParams::default()
            },
            CostParams {
                inflation_radius_m: f64::NAN,
                ..CostParams::default()
            },
            CostParams {
                inflation_radius_m: 0.2,
                ..CostParams::default()
            },
            CostParams {
                max_cost: f64::INFINITY,
                ..CostParams::default()
            },
            CostParams {
                max_cost: 1000.5,
                ..CostParams::default()
            },
            CostParams {
                decay_per_m: -1.0,
                ..CostParams::default()
            },
            CostParams {
                inflation_radius_m: 1e6,
                ..CostParams::default()
            },
        ] {
            assert!(
                matches!(CostMap::build(p, &m, w, &[]), Err(PlanningError::BadParam { .. })),
                "{p:?}"
            );
        }
        let other = GridMap::new(5, 5, 0.2, Pose::default(), vec![Cell::Free; 25]).unwrap();
        assert_eq!(
            CostMap::build(CostParams::default(), &other, w, &[]).unwrap_err(),
            PlanningError::WindowMapMismatch
        );
    }

    #[test]
    fn laser_endpoints_skip_beams_without_echo() {
        let scan = LaserScan {
            mount: Pose::new(0.1, 0.0, 0.0),
            angle_min_rad: -std::f64::consts::FRAC_PI_2,
            angle_increment_rad: std::f64::consts::FRAC_PI_2,
            range_max_m: 10.0,
            ranges_m: vec![1.0, f64::INFINITY, 2.0, f64::NAN, 10.0],
        };
        let mut out = vec![Vec2::new(9.0, 9.0)];
        laser_endpoints(Pose::new(1.0, 2.0, std::f64::consts::FRAC_PI_2), &scan, &mut out);
        assert_eq!(out.len(), 3);
        // Robot at (1, 2) facing +y; sensor 0.1 m ahead at (1, 2.1).
        // Beam 0 points to the robot's right (+x): (2, 2.1).
        assert!(out[1].dist(Vec2::new(2.0, 2.1)) < 1e-12);
        // Beam 2 points to its left (−x), 2 m: (−1, 2.1).
        assert!(out[2].dist(Vec2::new(-1.0, 2.1)) < 1e-12);
    }
}
