//! The static part of the cost map, computed once per map.
//!
//! A [`CostMap`] built from the map ([`CostMap::build`]) runs the distance
//! transform over the window grown by the inflation margin every time,
//! although only the sensed obstacles change from one control cycle to the
//! next. A [`StaticCostLayer`] does the map's part once, for the whole map:
//! the capped squared distance from every map cell to the nearest obstacle
//! of the map (occupied, unknown, or outside the map — a ring of outside
//! cells around the map is enough, the nearest outside cell of a map cell
//! is always in it), and the intrinsic cost it gives. A cost map of a
//! window is then ([`CostMap::build_on`], [`CostMap::rebuild_on`]):
//!
//! 1. the window's row slices of the static costs (cells outside the map
//!    lethal), and its number of free cells from per-row prefix counts;
//! 2. for every distinct free map cell hit by an obstacle point, within the
//!    window's inflation margin: the intrinsic cost of each window cell
//!    raised to the cost at its distance from that cell — a precomputed
//!    *stamp* of the disc where that cost is positive.
//!
//! **Equal to [`CostMap::build`], bit for bit.** The old build's distance
//! `d` of a window cell is the smallest of its distance to the map's
//! obstacles and to the sensed cells, exact up to the cap and "beyond"
//! after it; every obstacle within the cap of a window cell lies in the
//! grown window, so the whole-map transform gives the same capped distance
//! to the map's obstacles. Both use the same cost table `t` (by squared
//! distance, non-increasing by construction, see
//! [`CostParams::cost_at`]), so `t(min(d₁, d₂)) = max(t(d₁), t(d₂))`: the
//! stamps' maximum is the old cost exactly. Classes, clearances and the
//! build's counts are answered from the layer and the list of sensed cells.
//! `tests/planning_props.rs` checks costs, [`CostMap::why_lethal`],
//! [`CostMap::clearance_m`] and [`CostMap::info`] against
//! [`CostMap::build`] on random maps, windows and obstacle points.
//!
//! Cost: building the layer is one distance transform of the map,
//! `O(w · h)` (about 3 ms for `building_31`'s 693 × 648 cells, 45 ms for
//! `levine`'s 2048 × 2048); it keeps 17 bytes per map cell (the cells,
//! squared distances, costs, prefix counts: 7.6 MB for `building_31`,
//! 71 MB for `levine`). A cost map of a `w × h` window then costs a copy of
//! `w · h` costs and `O(s · r²)` for `s` sensed cells and a stamp of radius
//! `r` cells (the inflation radius), instead of the transform over
//! `(w + 2r)(h + 2r)` cells.
//!
//! [`CostMap`]: super::CostMap
//! [`CostMap::build`]: super::CostMap::build
//! [`CostMap::build_on`]: super::CostMap::build_on
//! [`CostMap::rebuild_on`]: super::CostMap::rebuild_on
//! [`CostMap::why_lethal`]: super::CostMap::why_lethal
//! [`CostMap::clearance_m`]: super::CostMap::clearance_m
//! [`CostMap::info`]: super::CostMap::info

use robot::{Cell, CellIndex, GridMap, Pose};

use super::cost_model::cost_table;
use super::distance_transform::{BEYOND, DistanceTransform};
use super::{CostParams, PlanningError, Window};

/// The map's part of every cost map on it (module docs).
#[derive(Clone)]
pub struct StaticCostLayer {
    params: CostParams,
    width: usize,
    height: usize,
    resolution_m: f64,
    origin: Pose,
    /// The map's cells, to check that a map is this one.
    cells: Vec<Cell>,
    /// Per map cell, row-major: squared distance to the nearest obstacle
    /// cell, cells², or `BEYOND` past the cap.
    dist_sq: Vec<u32>,
    /// Per map cell: the intrinsic cost.
    cost: Vec<f64>,
    /// Per map row `j`, `width + 1` entries: free cells (finite cost) of
    /// the row left of column `i`, at `j · (width + 1) + i`.
    free_before: Vec<u32>,
    /// Margin of the inflation, cells (the cap of the distances).
    cap: u32,
    /// The stamp of a sensed cell: per row offset `dy` in `-r..=r`, the
    /// half-widths of the lethal part and of the part with a positive cost,
    /// and the costs of the latter.
    stamp: Vec<StampRow>,
}

impl std::fmt::Debug for StaticCostLayer {
    /// The map's size and frame and the cost model, not the millions of
    /// cells.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("StaticCostLayer")
            .field("params", &self.params)
            .field("width", &self.width)
            .field("height", &self.height)
            .field("resolution_m", &self.resolution_m)
            .field("origin", &self.origin)
            .field("margin_cells", &self.cap)
            .finish_non_exhaustive()
    }
}

/// One row of a sensed cell's stamp.
#[derive(Debug, Clone)]
struct StampRow {
    dy: i64,
    /// Cells with `|dx| ≤ lethal` are lethal (`-1`: none).
    lethal: i64,
    /// Cells with `|dx| ≤ half` have a positive cost.
    half: i64,
    /// Costs for `dx` in `-half..=half`.
    costs: Vec<f64>,
}

impl StaticCostLayer {
    /// The static layer of `map` for the cost model `params`.
    ///
    /// Errors: invalid parameters, or an inflation radius of more than
    /// 30 000 cells (as [`CostMap::build`](super::CostMap::build)).
    pub fn new(params: CostParams, map: &GridMap) -> Result<StaticCostLayer, PlanningError> {
        params.validate()?;
        let res = map.resolution_m();
        let cap = super::cost_model::margin_cells(&params, res)?;
        let (w, h) = (map.width(), map.height());
        // The map and a ring of outside cells around it: everything but the
        // map's free cells blocks.
        let (pw, ph) = (w + 2, h + 2);
        let mut blocked = vec![1u8; pw * ph];
        for (j, row) in map.cells().chunks_exact(w.max(1)).enumerate().take(h) {
            for (b, &c) in blocked[(j + 1) * pw + 1..][..w].iter_mut().zip(row) {
                *b = u8::from(c != Cell::Free);
            }
        }
        let mut padded = Vec::new();
        DistanceTransform::new().compute(&blocked, pw, ph, cap, &mut padded);
        drop(blocked);
        let table = cost_table(&params, res, cap);
        let mut dist_sq = Vec::with_capacity(w * h);
        for j in 0..h {
            dist_sq.extend_from_slice(&padded[(j + 1) * pw + 1..][..w]);
        }
        drop(padded);
        let cost: Vec<f64> = dist_sq
            .iter()
            .map(|&d| if d == BEYOND { 0.0 } else { table[d as usize] })
            .collect();
        let mut free_before = Vec::with_capacity((w + 1) * h);
        for row in cost.chunks_exact(w.max(1)).take(h) {
            let mut n = 0u32;
            free_before.push(0);
            for c in row {
                n += u32::from(c.is_finite());
                free_before.push(n);
            }
        }
        let stamp = stamp(&table, cap);
        Ok(StaticCostLayer {
            params,
            width: w,
            height: h,
            resolution_m: res,
            origin: map.origin(),
            cells: map.cells().to_vec(),
            dist_sq,
            cost,
            free_before,
            cap,
            stamp,
        })
    }

    /// The cost model.
    pub fn params(&self) -> &CostParams {
        &self.params
    }

    /// The inflation margin, cells: obstacles this close to a window
    /// change its costs.
    pub fn margin_cells(&self) -> usize {
        self.cap as usize
    }

    /// Whether cost maps of `window` built on this layer equal those
    /// [`CostMap::build`](super::CostMap::build) makes from `map`: `map` has the layer's size,
    /// resolution and origin, and the same cells in the window grown by
    /// the margin (the only cells a window's cost map depends on). Costs
    /// `O` of the grown window's size.
    pub fn matches(&self, map: &GridMap, window: &Window) -> bool {
        if map.width() != self.width
            || map.height() != self.height
            || map.resolution_m() != self.resolution_m
            || map.origin() != self.origin
            || window.resolution_m() != self.resolution_m
            || window.origin() != self.origin
        {
            return false;
        }
        let m = self.cap as i64;
        let (i0, i1) = (
            (window.min().i - m).max(0),
            (window.min().i + window.width() as i64 + m).min(self.width as i64),
        );
        let (j0, j1) = (
            (window.min().j - m).max(0),
            (window.min().j + window.height() as i64 + m).min(self.height as i64),
        );
        if i0 >= i1 || j0 >= j1 {
            return true;
        }
        let cells = map.cells();
        (j0..j1).all(|j| {
            let r = (j as usize * self.width + i0 as usize)..(j as usize * self.width + i1 as usize);
            // Branch-free over the row (vectorised), unlike `==` on the enum.
            let diff = cells[r.clone()]
                .iter()
                .zip(&self.cells[r])
                .fold(0u8, |acc, (&a, &b)| acc | (a as u8 ^ b as u8));
            diff == 0
        })
    }

    /// Whether a map cell lies on the map.
    #[inline]
    fn on_map(&self, c: CellIndex) -> bool {
        c.i >= 0 && c.j >= 0 && (c.i as u64) < self.width as u64 && (c.j as u64) < self.height as u64
    }

    /// The map's cell (outside the map: `None`).
    pub(crate) fn cell(&self, c: CellIndex) -> Option<Cell> {
        self.on_map(c)
            .then(|| self.cells[c.j as usize * self.width + c.i as usize])
    }

    /// Squared distance from a map cell to the nearest obstacle of the map,
    /// cells², or `BEYOND` past the cap (0 outside the map).
    pub(crate) fn dist_sq(&self, c: CellIndex) -> u32 {
        if self.on_map(c) {
            self.dist_sq[c.j as usize * self.width + c.i as usize]
        } else {
            0
        }
    }

    /// The map's resolution and origin.
    pub(crate) fn frame(&self) -> (f64, Pose) {
        (self.resolution_m, self.origin)
    }

    /// Writes the static costs of `window` into `cost`, laid out as
    /// [`CostMap::padded_costs`](super::CostMap::padded_costs) (resized), and returns its free cells.
    pub(crate) fn copy_window(&self, window: &Window, cost: &mut Vec<f64>) -> usize {
        let (w, h) = (window.width(), window.height());
        let pw = w + 2;
        let n = pw * (h + 2);
        cost.resize(n, f64::INFINITY);
        // The padding ring's rows, then each row: outside the map, the
        // map's slice, outside again, and the ring's two cells.
        cost[..pw].fill(f64::INFINITY);
        cost[n - pw..].fill(f64::INFINITY);
        let (mw, mh) = (self.width as i64, self.height as i64);
        let lo = window.min().i.clamp(0, mw); // map columns lo..hi
        let hi = (window.min().i + w as i64).clamp(0, mw);
        let mut free = 0usize;
        for v in 0..h {
            let row = &mut cost[(v + 1) * pw..(v + 2) * pw];
            let j = window.min().j + v as i64;
            if j < 0 || j >= mh || lo >= hi {
                row.fill(f64::INFINITY);
                continue;
            }
            let (a, b) = ((lo - window.min().i) as usize, (hi - window.min().i) as usize);
            row[..a + 1].fill(f64::INFINITY);
            row[b + 1..].fill(f64::INFINITY);
            let k = j as usize * self.width;
            row[a + 1..b + 1].copy_from_slice(&self.cost[k + lo as usize..k + hi as usize]);
            let f = &self.free_before[j as usize * (self.width + 1)..];
            free += (f[hi as usize] - f[lo as usize]) as usize;
        }
        free
    }

    /// Raises the costs of `window` (laid out as [`CostMap::padded_costs`](super::CostMap::padded_costs))
    /// to those a sensed obstacle in map cell `s` gives; returns the number
    /// of free cells that became lethal.
    pub(crate) fn stamp(&self, window: &Window, s: CellIndex, cost: &mut [f64]) -> usize {
        let (w, h) = (window.width() as i64, window.height() as i64);
        let pw = window.width() + 2;
        let (su, sv) = (s.i - window.min().i, s.j - window.min().j);
        let mut lost = 0;
        for r in &self.stamp {
            let v = sv + r.dy;
            if v < 0 || v >= h {
                continue;
            }
            let row = &mut cost[(v as usize + 1) * pw + 1..][..w as usize];
            // The lethal middle: count the free cells it covers.
            let (a, b) = ((su - r.lethal).max(0), (su + r.lethal).min(w - 1));
            if a <= b {
                let middle = &mut row[a as usize..=b as usize];
                lost += middle.iter().filter(|c| c.is_finite()).count();
                middle.fill(f64::INFINITY);
            }
            // The whole row (the middle again, harmlessly), clipped: the
            // larger cost (branch-free, vectorised).
            let (a, b) = ((su - r.half).max(0), (su + r.half).min(w - 1));
            if a > b {
                continue;
            }
            let values = &r.costs[(a - (su - r.half)) as usize..=(b - (su - r.half)) as usize];
            for (c, &t) in row[a as usize..=b as usize].iter_mut().zip(values) {
                *c = if t > *c { t } else { *c };
            }
        }
        lost
    }
}

/// The stamp of a sensed cell: the offsets where the table's cost is
/// positive, by row (the table is non-increasing: a disc).
fn stamp(table: &[f64], cap: u32) -> Vec<StampRow> {
    // Squared distances past cap² never occur (they are "beyond").
    let within_cap = &table[..=((cap as usize).pow(2)).min(table.len() - 1)];
    let last_lethal = within_cap.iter().rposition(|&t| t == f64::INFINITY);
    let Some(last_positive) = within_cap.iter().rposition(|&t| t > 0.0) else {
        return Vec::new();
    };
    let cap = cap as i64;
    let half_within = |limit: usize, dy: i64| -> i64 {
        let rest = limit as i64 - dy * dy;
        if rest < 0 {
            return -1;
        }
        let mut x = (rest as f64).sqrt() as i64;
        while x * x > rest {
            x -= 1;
        }
        while (x + 1) * (x + 1) <= rest {
            x += 1;
        }
        x
    };
    (-cap..=cap)
        .filter_map(|dy| {
            let half = half_within(last_positive, dy);
            (half >= 0).then(|| StampRow {
                dy,
                lethal: last_lethal.map_or(-1, |l| half_within(l, dy)),
                half,
                costs: (-half..=half)
                    .map(|dx| table[(dx * dx + dy * dy) as usize])
                    .collect(),
            })
        })
        .collect()
}
