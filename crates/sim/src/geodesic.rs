//! Shortest paths on an 8-connected lattice: Dijkstra's algorithm from one
//! or more seeds over the passable nodes, straight steps of one length and
//! diagonal steps of another.
//!
//! The simulator's one grid shortest path. People's walking-distance fields
//! ([`crate::Routes`], `f32` on a coarse lattice, no corner cutting) and the
//! lab's bound on a route's length (the true grid's cells, `f64`, to one
//! target) both call [`distances`]. The robot's own planner is a different
//! algorithm and lives in `planning` (cost-weighted, incremental `A*` on a
//! bucket queue over the robot's map), which does not depend on the
//! simulator.
//!
//! The queue orders nodes by (distance, node index), both exact: the
//! distances are final when a node is taken, whatever order its neighbours
//! are visited in, and ties go to the lower index. Cost: `O(n log n)` for
//! `n` passable nodes.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// A distance the search can add and order exactly: `f32` or `f64`.
pub trait Distance: Copy + PartialOrd + std::ops::Add<Output = Self> {
    /// No path.
    const INFINITY: Self;
    /// A key that orders non-negative distances as they compare.
    fn key(self) -> u64;
}

impl Distance for f32 {
    const INFINITY: f32 = f32::INFINITY;
    fn key(self) -> u64 {
        u64::from(self.to_bits())
    }
}

impl Distance for f64 {
    const INFINITY: f64 = f64::INFINITY;
    fn key(self) -> u64 {
        self.to_bits()
    }
}

/// An `width × height` lattice, node `i + j·width`, with the nodes a path
/// may use.
#[derive(Debug, Clone, Copy)]
pub struct Lattice<'a> {
    /// Nodes per row.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Per node, row by row: whether a path may go through it.
    pub passable: &'a [bool],
    /// Whether a diagonal step may pass between two impassable nodes' corner
    /// (`false`: both nodes beside the diagonal must be passable).
    pub cut_corners: bool,
}

/// Lengths of one straight and one diagonal step.
#[derive(Debug, Clone, Copy)]
pub struct Steps<D> {
    /// Between 4-neighbours.
    pub straight: D,
    /// Between diagonal neighbours.
    pub diagonal: D,
}

/// Distances from the nearest seed to every node of `lattice` (row by
/// row; [`Distance::INFINITY`] where no path leads), by Dijkstra's
/// algorithm. `seeds` are (node, starting distance); impassable seeds
/// are ignored. With `target`, the search stops once the target's distance
/// is final (nodes farther away keep partial values).
///
/// # Panics
///
/// If `lattice.passable` does not have `width · height` entries or a seed
/// is outside the lattice (callers' bugs).
pub fn distances<D: Distance>(
    lattice: &Lattice<'_>,
    steps: Steps<D>,
    seeds: &[(usize, D)],
    target: Option<usize>,
) -> Vec<D> {
    let (w, h) = (lattice.width, lattice.height);
    assert_eq!(lattice.passable.len(), w * h, "one passable flag per node");
    let passable = lattice.passable;
    let mut dist = vec![D::INFINITY; w * h];
    let mut heap = BinaryHeap::new();
    for &(k, d) in seeds {
        if passable[k] && d < dist[k] {
            dist[k] = d;
            heap.push(Reverse((d.key(), k)));
        }
    }
    while let Some(Reverse((key, k))) = heap.pop() {
        let d = dist[k];
        if key > d.key() {
            continue; // a stale entry: k was reached shorter since
        }
        if target == Some(k) {
            break;
        }
        let (i, j) = (k % w, k / w);
        for jj in j.saturating_sub(1)..=(j + 1).min(h - 1) {
            for ii in i.saturating_sub(1)..=(i + 1).min(w - 1) {
                let m = jj * w + ii;
                if m == k || !passable[m] {
                    continue;
                }
                let step = if ii != i && jj != j {
                    if !lattice.cut_corners && (!passable[j * w + ii] || !passable[jj * w + i]) {
                        continue;
                    }
                    steps.diagonal
                } else {
                    steps.straight
                };
                let nd = d + step;
                if nd < dist[m] {
                    dist[m] = nd;
                    heap.push(Reverse((nd.key(), m)));
                }
            }
        }
    }
    dist
}

#[cfg(test)]
mod tests {
    use super::*;

    const UNIT: Steps<f64> = Steps {
        straight: 1.0,
        diagonal: std::f64::consts::SQRT_2,
    };

    #[test]
    fn open_lattice_gives_the_octile_distance() {
        let passable = vec![true; 7 * 5];
        let lattice = Lattice {
            width: 7,
            height: 5,
            passable: &passable,
            cut_corners: true,
        };
        let d = distances(&lattice, UNIT, &[(0, 0.0)], None);
        for j in 0..5 {
            for i in 0..7 {
                let (a, b) = (i.max(j) as f64, i.min(j) as f64);
                let octile = (a - b) + b * std::f64::consts::SQRT_2;
                assert!((d[j * 7 + i] - octile).abs() < 1e-12, "({i}, {j})");
            }
        }
    }

    #[test]
    fn corners_are_cut_only_when_allowed_and_walls_are_walked_round() {
        // 3 × 3 with the nodes (1, 0) and (0, 1) blocked: (1, 1) from (0, 0)
        // is one diagonal step past two blocked corners, or nothing.
        let mut passable = vec![true; 9];
        passable[1] = false;
        passable[3] = false;
        let mut lattice = Lattice {
            width: 3,
            height: 3,
            passable: &passable,
            cut_corners: true,
        };
        let d = distances(&lattice, UNIT, &[(0, 0.0)], None);
        assert!((d[4] - std::f64::consts::SQRT_2).abs() < 1e-12);
        lattice.cut_corners = false;
        let d = distances(&lattice, UNIT, &[(0, 0.0)], None);
        assert_eq!(d[4], f64::INFINITY);
        assert_eq!(d[1], f64::INFINITY);
    }

    #[test]
    fn the_nearest_seed_wins_and_a_target_stops_early() {
        let passable = vec![true; 10];
        let lattice = Lattice {
            width: 10,
            height: 1,
            passable: &passable,
            cut_corners: false,
        };
        let steps = Steps {
            straight: 0.5f32,
            diagonal: 0.7,
        };
        let d = distances(&lattice, steps, &[(0, 0.25), (9, 0.0)], None);
        assert_eq!(d[0], 0.25);
        assert_eq!(d[4], 2.25);
        assert_eq!(d[5], 2.0);
        let partial = distances(&lattice, steps, &[(0, 0.0)], Some(2));
        assert_eq!(partial[2], 1.0);
        assert_eq!(partial[9], f32::INFINITY);
    }
}
