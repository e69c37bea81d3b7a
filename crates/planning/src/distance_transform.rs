//! Exact Euclidean distance transform of a grid, up to a cap.
//!
//! For every cell, the squared Euclidean distance (in cells², between cell
//! centres) to the nearest blocked cell — P. Felzenszwalb, D. Huttenlocher,
//! *Distance Transforms of Sampled Functions*, Theory of Computing 8 (2012):
//! a pass down every column gives the distance to the nearest blocked cell
//! of the same column, then along every row the lower envelope of the
//! parabolas `(x − q)² + g(q)²` gives the 2-D distance. Time `O(w · h)`,
//! scratch memory `O(w + h)` besides the output.
//!
//! The column distances are capped at `cap + 1` cells and the rows' lower
//! envelopes take only the columns with a blocked cell within the cap: the
//! others only give distances `> cap`, so every distance `≤ cap` stays
//! exact, open ground costs little, and a row without any such column is
//! skipped. Cells farther than `cap` from any blocked cell get [`BEYOND`].
//! The cost map needs distances only up to the inflation radius.

/// Output value for a cell farther than the cap from every blocked cell.
pub const BEYOND: u32 = u32::MAX;

/// Largest cap accepted, cells (squares stay far inside `u32`).
pub const MAX_CAP: u32 = 30_000;

/// Reusable scratch memory for [`DistanceTransform::compute`].
#[derive(Debug, Clone, Default)]
pub struct DistanceTransform {
    f: Vec<i64>,
    v: Vec<usize>,
    z: Vec<f64>,
}

impl DistanceTransform {
    /// Empty scratch memory (it grows on first use).
    pub fn new() -> DistanceTransform {
        DistanceTransform::default()
    }

    /// Squared distances of a `width × height` grid, row-major
    /// (`blocked[j · width + i] != 0` marks cell `(i, j)` blocked), into
    /// `out` (resized): exact where `≤ cap²`, [`BEYOND`] elsewhere (module
    /// docs). `cap` is clamped to [`MAX_CAP`].
    ///
    /// Panics if `blocked.len() != width · height` (a bug in the caller).
    pub fn compute(&mut self, blocked: &[u8], width: usize, height: usize, cap: u32, out: &mut Vec<u32>) {
        assert_eq!(blocked.len(), width * height, "blocked has width × height cells");
        let cap = cap.min(MAX_CAP);
        let g_cap = cap + 1;
        out.clear();
        out.resize(width * height, g_cap);
        if width == 0 || height == 0 {
            return;
        }
        // Pass 1: per column, the distance to the nearest blocked cell of the
        // column, capped at cap + 1 (stored unsquared for now). Both sweeps
        // go row by row, over contiguous memory.
        // Upward: distance to the nearest blocked cell at or below.
        for (o, &b) in out[..width].iter_mut().zip(&blocked[..width]) {
            *o = if b != 0 { 0 } else { g_cap };
        }
        for j in 1..height {
            let (below, row) = out[(j - 1) * width..(j + 1) * width].split_at_mut(width);
            for ((o, &d), &b) in row
                .iter_mut()
                .zip(below.iter())
                .zip(&blocked[j * width..(j + 1) * width])
            {
                *o = if b != 0 { 0 } else { (d + 1).min(g_cap) };
            }
        }
        // Downward: or at or above, whichever is nearer.
        for j in (0..height - 1).rev() {
            let (row, above) = out[j * width..(j + 2) * width].split_at_mut(width);
            for (o, &d) in row.iter_mut().zip(above.iter()) {
                *o = (*o).min(d + 1);
            }
        }
        // Pass 2: per row, the lower envelope of the parabolas
        // (x − q)² + g(q)² over the columns q with a blocked cell within the
        // cap (the others cannot give a distance ≤ cap).
        self.f.resize(width, 0);
        self.v.resize(width, 0);
        self.z.resize(width + 1, 0.0);
        let cap_sq = (cap as u64) * (cap as u64);
        for j in 0..height {
            let row = &mut out[j * width..(j + 1) * width];
            for (f, &g) in self.f.iter_mut().zip(row.iter()) {
                *f = (g as i64) * (g as i64);
            }
            let f = &self.f;
            let (v, z) = (&mut self.v, &mut self.z);
            let mut k = 0usize;
            let mut any = false;
            for (q, &g) in row.iter().enumerate() {
                if g > cap {
                    continue;
                }
                if !any {
                    any = true;
                    v[0] = q;
                    z[0] = f64::NEG_INFINITY;
                    z[1] = f64::INFINITY;
                    continue;
                }
                let fq = f[q] + (q * q) as i64;
                let mut s;
                loop {
                    let p = v[k];
                    s = (fq - (f[p] + (p * p) as i64)) as f64 / (2 * (q - p)) as f64;
                    if s <= z[k] {
                        // z[0] = −∞, so k > 0 here.
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
                row.fill(BEYOND);
                continue;
            }
            let mut k = 0usize;
            for (q, cell) in row.iter_mut().enumerate() {
                while z[k + 1] < q as f64 {
                    k += 1;
                }
                let p = v[k];
                let dx = q.abs_diff(p) as u64;
                let d2 = dx * dx + f[p] as u64;
                *cell = if d2 <= cap_sq { d2 as u32 } else { BEYOND };
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn brute(blocked: &[u8], w: usize, h: usize, cap: u32) -> Vec<u32> {
        let mut out = vec![BEYOND; w * h];
        for j in 0..h {
            for i in 0..w {
                let mut best = u64::MAX;
                for jj in 0..h {
                    for ii in 0..w {
                        if blocked[jj * w + ii] != 0 {
                            let (dx, dy) = (i.abs_diff(ii) as u64, j.abs_diff(jj) as u64);
                            best = best.min(dx * dx + dy * dy);
                        }
                    }
                }
                if best <= (cap as u64) * (cap as u64) {
                    out[j * w + i] = best as u32;
                }
            }
        }
        out
    }

    proptest! {
        #[test]
        fn equals_brute_force(
            w in 1usize..24,
            h in 1usize..24,
            density in 0.0f64..0.3,
            cap in 0u32..30,
            seed in any::<u64>(),
        ) {
            let mut s = seed | 1;
            let blocked: Vec<u8> = (0..w * h)
                .map(|_| {
                    s ^= s << 13;
                    s ^= s >> 7;
                    s ^= s << 17;
                    u8::from(((s >> 11) as f64 / (1u64 << 53) as f64) < density)
                })
                .collect();
            let mut out = Vec::new();
            DistanceTransform::new().compute(&blocked, w, h, cap, &mut out);
            prop_assert_eq!(out, brute(&blocked, w, h, cap));
        }
    }

    #[test]
    fn a_single_obstacle_gives_squared_distances() {
        let (w, h) = (9, 7);
        let mut blocked = vec![0u8; w * h];
        blocked[3 * w + 4] = 1;
        let mut out = Vec::new();
        DistanceTransform::new().compute(&blocked, w, h, 100, &mut out);
        assert_eq!(out[3 * w + 4], 0);
        assert_eq!(out[3 * w + 7], 9);
        assert_eq!(out[6 * w + 8], 9 + 16);
        assert_eq!(out[0], 16 + 9);
        // With a cap of 3 cells, only distances up to 3 remain.
        DistanceTransform::new().compute(&blocked, w, h, 3, &mut out);
        assert_eq!(out[3 * w + 7], 9);
        assert_eq!(out[6 * w + 8], BEYOND);
        assert_eq!(out[4 * w + 6], 5);
    }

    #[test]
    fn no_obstacle_is_beyond_everywhere() {
        let mut out = Vec::new();
        DistanceTransform::new().compute(&[0; 12], 4, 3, 50, &mut out);
        assert!(out.iter().all(|&d| d == BEYOND));
    }
}
