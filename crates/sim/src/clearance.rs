//! Clearance field: for every cell, the chessboard (Chebyshev) distance in
//! cells to the nearest blocked cell, counting everything outside the grid as
//! blocked, capped at [`CLEARANCE_CAP`].
//!
//! A free cell of clearance `k` is the centre of a `(2k − 1) × (2k − 1)` square
//! of free cells that lies entirely inside the grid. The ray caster uses these
//! squares to skip empty space without changing which cells it reports
//! (see [`crate::raycast`]).
//!
//! Built in `O(cells)` by the two-pass 3 × 3 chamfer transform with unit
//! weights, which is exact for the chessboard metric (Rosenfeld & Pfaltz,
//! *Sequential operations in digital picture processing*, 1966). A change of
//! one cell is repaired locally: a new obstacle lowers the values within
//! `CAP` of it (`O(CAP²)`, a few microseconds); a freed cell re-runs the
//! transform on the window of radius `2 · CAP` around it (`O(CAP²)` too, but
//! up to 66,000 cells in a serial chain: well under a millisecond).

use robot::Cell;

/// Largest clearance stored, in cells. Larger values skip more free space per
/// step but make a change of one cell ([`crate::OccupancyGrid::set`]) cost more.
pub const CLEARANCE_CAP: u8 = 64;

/// Per-cell clearance of a grid, row by row from the bottom like the cells.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Clearance {
    width: usize,
    height: usize,
    dist: Vec<u8>,
}

#[inline]
fn blocked(c: Cell) -> bool {
    c != Cell::Free
}

impl Clearance {
    /// The clearance of a whole grid.
    pub(crate) fn build(width: usize, height: usize, cells: &[Cell]) -> Clearance {
        let mut c = Clearance {
            width,
            height,
            dist: vec![0; cells.len()],
        };
        c.chamfer_window(cells, width, height, 0, 0);
        c
    }

    /// Clearance of the in-grid cell `(i, j)`: 0 when blocked, ≥ 1 when free.
    #[inline]
    pub(crate) fn at(&self, i: usize, j: usize) -> u8 {
        self.dist[j * self.width + i]
    }

    /// Repairs the field after cell `(i, j)` changed between blocked and free.
    pub(crate) fn update(&mut self, cells: &[Cell], i: usize, j: usize) {
        let cap = CLEARANCE_CAP as usize;
        if blocked(cells[j * self.width + i]) {
            // A new obstacle only lowers values: min with the distance to it.
            let (u0, u1) = (i.saturating_sub(cap), (i + cap).min(self.width - 1));
            let (v0, v1) = (j.saturating_sub(cap), (j + cap).min(self.height - 1));
            for y in v0..=v1 {
                let row = &mut self.dist[y * self.width..(y + 1) * self.width];
                for (x, d) in row.iter_mut().enumerate().take(u1 + 1).skip(u0) {
                    let to_new = x.abs_diff(i).max(y.abs_diff(j)) as u8;
                    *d = (*d).min(to_new);
                }
            }
            return;
        }
        let win = 2 * cap;
        let (x0, x1) = (i.saturating_sub(win), (i + win + 1).min(self.width));
        let (y0, y1) = (j.saturating_sub(win), (j + win + 1).min(self.height));
        // Recompute on the window, then keep only the cells within `cap` of
        // the change: any blocked cell closer than `cap` to those lies inside
        // the window, so their values are exact.
        let mut scratch = self.clone_window(x0, x1, y0, y1);
        scratch.chamfer_window(cells, self.width, self.height, x0, y0);
        let (u0, u1) = (i.saturating_sub(cap), (i + cap + 1).min(self.width));
        let (v0, v1) = (j.saturating_sub(cap), (j + cap + 1).min(self.height));
        for y in v0..v1 {
            for x in u0..u1 {
                self.dist[y * self.width + x] = scratch.dist[(y - y0) * scratch.width + (x - x0)];
            }
        }
    }

    fn clone_window(&self, x0: usize, x1: usize, y0: usize, y1: usize) -> Clearance {
        Clearance {
            width: x1 - x0,
            height: y1 - y0,
            dist: vec![0; (x1 - x0) * (y1 - y0)],
        }
    }

    /// Chamfer transform of `self` seen as the window at `(x0, y0)` of a grid
    /// `grid_w × grid_h`. Outside the grid counts as blocked (distance 0);
    /// inside the grid but outside the window counts as far (the cap).
    fn chamfer_window(&mut self, cells: &[Cell], grid_w: usize, grid_h: usize, x0: usize, y0: usize) {
        let cap = CLEARANCE_CAP;
        let (w, h) = (self.width, self.height);
        if w == 0 || h == 0 {
            return;
        }
        // A copy with a one-cell frame holding the neighbours' fixed values,
        // so the passes need no bounds checks.
        let pw = w + 2;
        let frame = |inside_grid: bool| if inside_grid { cap } else { 0 };
        let mut d = vec![0u8; pw * (h + 2)];
        for py in 0..h + 2 {
            for px in 0..pw {
                let inside_window = px >= 1 && py >= 1 && px <= w && py <= h;
                d[py * pw + px] = if inside_window {
                    let c = cells[(py - 1 + y0) * grid_w + px - 1 + x0];
                    if blocked(c) { 0 } else { cap }
                } else {
                    // Grid coordinates of the frame cell (may be −1).
                    let (gx, gy) = ((px + x0) as isize - 1, (py + y0) as isize - 1);
                    frame(gx >= 0 && gy >= 0 && (gx as usize) < grid_w && (gy as usize) < grid_h)
                };
            }
        }
        for py in 1..=h {
            for px in 1..=w {
                let k = py * pw + px;
                if d[k] != 0 {
                    let m = d[k - 1].min(d[k - pw - 1]).min(d[k - pw]).min(d[k - pw + 1]);
                    d[k] = d[k].min(m.saturating_add(1));
                }
            }
        }
        for py in (1..=h).rev() {
            for px in (1..=w).rev() {
                let k = py * pw + px;
                if d[k] != 0 {
                    let m = d[k + 1].min(d[k + pw + 1]).min(d[k + pw]).min(d[k + pw - 1]);
                    d[k] = d[k].min(m.saturating_add(1));
                }
            }
        }
        for y in 0..h {
            self.dist[y * w..(y + 1) * w].copy_from_slice(&d[(y + 1) * pw + 1..(y + 1) * pw + 1 + w]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Brute force: chessboard distance to the nearest blocked or outside cell.
    fn brute(width: usize, height: usize, cells: &[Cell]) -> Vec<u8> {
        let mut out = vec![0; cells.len()];
        for j in 0..height {
            for i in 0..width {
                if blocked(cells[j * width + i]) {
                    continue;
                }
                let mut best = (i + 1).min(j + 1).min(width - i).min(height - j);
                for y in 0..height {
                    for x in 0..width {
                        if blocked(cells[y * width + x]) {
                            best = best.min(x.abs_diff(i).max(y.abs_diff(j)));
                        }
                    }
                }
                out[j * width + i] = best.min(CLEARANCE_CAP as usize) as u8;
            }
        }
        out
    }

    fn pseudo_random_cells(width: usize, height: usize, seed: u64, density: u64) -> Vec<Cell> {
        let mut s = seed;
        (0..width * height)
            .map(|_| {
                s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                if (s >> 33) % 1000 < density {
                    Cell::Occupied
                } else {
                    Cell::Free
                }
            })
            .collect()
    }

    #[test]
    fn build_matches_brute_force() {
        for (w, h, seed, density) in [(1, 1, 1, 0), (7, 3, 2, 100), (90, 80, 3, 2), (150, 40, 4, 0)] {
            let cells = pseudo_random_cells(w, h, seed, density);
            assert_eq!(
                Clearance::build(w, h, &cells).dist,
                brute(w, h, &cells),
                "{w}×{h}"
            );
        }
    }

    #[test]
    fn local_updates_match_a_rebuild() {
        let (w, h) = (170, 150);
        let mut cells = pseudo_random_cells(w, h, 9, 1);
        let mut c = Clearance::build(w, h, &cells);
        let mut s = 77u64;
        for n in 0..60 {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let (i, j) = ((s >> 20) as usize % w, (s >> 40) as usize % h);
            cells[j * w + i] = if n % 3 == 0 { Cell::Free } else { Cell::Unknown };
            c.update(&cells, i, j);
            assert_eq!(
                c,
                Clearance::build(w, h, &cells),
                "after change {n} at ({i}, {j})"
            );
        }
    }
}
