//! The distribution of the time to the end of an absorbing chain as a
//! function of `t`, from a shift-and-invert Krylov space: every quantile
//! from a few dozen block solves, to about ten significant digits.
//!
//! With `A = −Q_TT` the negated generator of the transient states and `p₀`
//! the initial distribution on them, the mass not yet ended at `t` is the
//! survival `S(t) = p₀ e^{−tA} 1`. A time-stepping method (Crank–Nicolson
//! on a grid, [`crate::CompiledGspn::absorption_cdf_steps`]) pays one block
//! solve per step, ~25 per mean time for quantiles to 10⁻⁴; uniformisation
//! pays a product per `1/Λ`, hopeless when rates span orders of magnitude.
//!
//! Here the row vectors `p₀, p₀ M⁻¹, p₀ M⁻², …` with `M = I + γA` span a
//! *rational* Krylov space (Moret & Novati, *RD-rational approximations of
//! the matrix exponential*, BIT 44, 2004; van den Eshof & Hochbruck,
//! *Preconditioning Lanczos approximations to the matrix exponential*, SIAM
//! J. Sci. Comput. 27, 2006). Arnoldi (classical Gram–Schmidt as two
//! matrix–vector products with the basis, a second pass where the first
//! cancelled most of the vector — "twice is enough"; the modified form,
//! vector by vector, is in `crates/petri/EXPERIMENTS.md`) gives an
//! orthonormal basis `V_m` and the
//! Hessenberg `H_m` of `M⁻¹` on it (transposed: `p ↦ p
//! M⁻¹` acts on rows), so `A ≈ (H_m⁻¹ − I)/γ` there and
//!
//! `S(t) ≈ ‖p₀‖ (1ᵀ V_m) exp(t G) e₁`, `G = (I − H_m⁻¹)/γ`,
//!
//! for every `t` at once: the small matrix's exponential replaces the
//! steps. Its error does not depend on the fastest rate (the stiff part
//! is what `M⁻¹` damps) and falls geometrically with `m` for `t` of the
//! order of `γ` and beyond; `γ` a quarter of the mean time to the end
//! serves the body and the tail of the distribution (`bt analyze`: 20–34
//! vectors on Nav2's large chains, quantiles within 1.1·10⁻⁹ of the matrix
//! exponential's; `crates/bt/BENCHMARKS.md`).
//!
//! **When to stop** (`m`): every 2 vectors from 8 on — every vector once
//! two readings agree to [`CLOSE`] times the tolerance — the times where `S`
//! falls to the caller's levels (the quantiles) are read off; the space is
//! kept once two successive readings agree on them to the tolerance,
//! relatively (or once it is invariant: a breakdown, after which the
//! result is exact). `S` converges more slowly at times far below `γ`; as
//! the check is on the times asked for, a quantile there costs more
//! vectors, not accuracy.
//! A space that has not settled by [`MAX_VECTORS`] vectors is an
//! [`Error::NoConvergence`], on which a caller can fall back to the grid.
//!
//! **Reading a time off `S`** ([`Survival::first_below`]): `exp(δG)` for a
//! step `δ` of the horizon over [`GRID`] marches `u_k = exp(kδG) e₁` to
//! the first step below the level; inside it, a bisection takes one
//! matrix–vector product per halving with `exp(δ/2^l · G)` (each by its
//! own scaling and squaring, computed once per call as deep as needed;
//! once `δ/2^l · G` is small, ‖·‖₁ ≤ ½, the same Taylor series is applied
//! to the vector instead, a product with a vector per term rather than
//! one with a matrix) until the interval is [`RESOLUTION`] of the time,
//! then interpolates linearly. The products run in place, without
//! allocating (a reading on a large space: ~0.3 ms).
//!
//! Deterministic: one thread, a fixed order of operations.

use faer::linalg::matmul::matmul;
use faer::prelude::Solve;
use faer::{Accum, Col, ColMut, ColRef, Mat, Par, Scale};

use crate::blocks::BlockSystem;
use crate::error::{Error, Result};
use crate::profile_lu::dot;

/// Largest Krylov space (block solves).
pub const MAX_VECTORS: usize = 64;
/// Once two sizes agree to this many times the tolerance, the times are
/// read off at every size instead of every second one.
pub const CLOSE: f64 = 100.0;
/// Steps of the march over the horizon in [`Survival::first_below`].
pub const GRID: usize = 512;
/// Bisections inside a step of the march stop once the interval is at
/// most this fraction of the time (linear interpolation is then exact to
/// ~10⁻¹⁰ of it)…
pub const RESOLUTION: f64 = 1e-5;
/// … or after this many.
pub const MAX_HALVINGS: usize = 60;

/// `S(t) = P(the run has not ended by t)` for every `t ≥ 0`, approximated
/// on a Krylov space (see the module doc).
#[derive(Debug, Clone)]
pub struct Survival {
    /// `‖p₀‖ · 1ᵀ V_m`.
    weights: Vec<f64>,
    /// `G = (I − H_m⁻¹)/γ`, `m × m`.
    g: Mat<f64>,
    /// Block solves done.
    solves: usize,
    /// The times of the levels it was built for.
    times: Vec<Option<f64>>,
}

impl Survival {
    /// A chain with no mass left in its transient states.
    fn ended() -> Survival {
        Survival {
            weights: Vec::new(),
            g: Mat::zeros(0, 0),
            solves: 0,
            times: Vec::new(),
        }
    }

    /// For each level the space was built for, the first time `S` falls to
    /// it within the horizon ([`Survival::first_below`]).
    pub fn times(&self) -> &[Option<f64>] {
        &self.times
    }

    /// Size of the space (block solves done to build it).
    pub fn solves(&self) -> usize {
        self.solves
    }

    fn dim(&self) -> usize {
        self.weights.len()
    }

    /// `S(t)`.
    pub fn at(&self, t: f64) -> f64 {
        let m = self.dim();
        if m == 0 {
            return 0.0;
        }
        let e = expm(&(&self.g * Scale(t)));
        (0..m).map(|i| self.weights[i] * e[(i, 0)]).sum()
    }

    /// For each level, the first `t ≤ horizon` where `S(t) ≤ level`
    /// (`None` if `S` stays above it up to the horizon).
    pub fn first_below(&self, levels: &[f64], horizon: f64) -> Vec<Option<f64>> {
        let m = self.dim();
        if m == 0 {
            return levels.iter().map(|_| Some(0.0)).collect();
        }
        let delta = horizon / GRID as f64;
        // ladder[l] = exp(δ/2^l · G), each by its own scaling and squaring
        // (squaring a finer one would keep its few significant digits),
        // made as deep as a bisection needs.
        let mut ladder = Ladder {
            g: &self.g,
            norm1: norm1(&self.g),
            delta,
            steps: vec![expm(&(&self.g * Scale(delta)))],
        };
        let mut out = vec![None; levels.len()];
        let mut u = unit(m);
        let mut s_u = self.weights[0];
        for (slot, &level) in out.iter_mut().zip(levels) {
            if s_u <= level {
                *slot = Some(0.0);
            }
        }
        let mut next = Col::<f64>::zeros(m);
        for k in 0..GRID {
            if out.iter().all(Option::is_some) {
                break;
            }
            product(&mut next, &ladder.steps[0], &u);
            let s_next = self.weigh(&next);
            for (slot, &level) in out.iter_mut().zip(levels) {
                if slot.is_none() && s_next <= level {
                    let bracket = (k as f64 * delta, s_u, s_next);
                    *slot = Some(ladder.bisect(self, &u, bracket, level));
                }
            }
            std::mem::swap(&mut u, &mut next);
            s_u = s_next;
        }
        out
    }

    /// `S` at the point of the small space `u` (`‖p₀‖ 1ᵀ V_m u`).
    fn weigh(&self, u: &Col<f64>) -> f64 {
        self.weights.iter().enumerate().map(|(i, &w)| w * u[i]).sum()
    }
}

/// `exp(δ/2^l · G)` for `l = 0, 1, …` as far as computed.
struct Ladder<'a> {
    g: &'a Mat<f64>,
    /// `‖G‖₁`.
    norm1: f64,
    delta: f64,
    steps: Vec<Mat<f64>>,
}

impl Ladder<'_> {
    fn step(&mut self, l: usize) -> &Mat<f64> {
        while self.steps.len() <= l {
            let h = self.delta / f64::powi(2.0, self.steps.len() as i32);
            self.steps.push(expm(&(self.g * Scale(h))));
        }
        &self.steps[l]
    }

    /// `exp(δ/2^l · G) u`: by the matrix of rung `l` while `δ/2^l · G`
    /// has a 1-norm above ½, below by the Taylor series applied to `u`
    /// (the same series and cut as [`expm`]'s, a product with a vector per
    /// term instead of one with a matrix).
    fn apply(&mut self, l: usize, u: &Col<f64>) -> Col<f64> {
        let h = self.delta / f64::powi(2.0, l as i32);
        let nu = h * self.norm1;
        if nu > 0.5 {
            return self.step(l) * u;
        }
        let degree = taylor_degree(nu);
        // Horner on the vector: u + hG (u + hG/2 (u + … (u + hG/K u)))
        let mut e = u.clone();
        let mut t = Col::<f64>::zeros(u.nrows());
        for k in (1..=degree).rev() {
            matmul(
                t.as_mat_mut(),
                Accum::Replace,
                self.g,
                e.as_mat(),
                h / k as f64,
                Par::Seq,
            );
            t += u;
            std::mem::swap(&mut e, &mut t);
        }
        e
    }

    /// The time in `[lo, lo + δ]` where `S` crosses `level`, from `u` at
    /// `lo` (`bracket = (lo, S(lo), S(lo + δ))`, `S(lo) > level ≥ S(lo +
    /// δ)`): halvings until the interval is at most [`RESOLUTION`] of the
    /// time (and at most [`MAX_HALVINGS`]), then linear interpolation.
    fn bisect(&mut self, s: &Survival, u: &Col<f64>, bracket: (f64, f64, f64), level: f64) -> f64 {
        let (mut lo, mut s_lo, mut s_hi) = bracket;
        let mut u = u.clone();
        let mut width = self.delta;
        for l in 1..=MAX_HALVINGS {
            if width <= RESOLUTION * lo {
                break;
            }
            width *= 0.5;
            let next = self.apply(l, &u);
            let s_mid = s.weigh(&next);
            if s_mid <= level {
                s_hi = s_mid;
            } else {
                lo += width;
                s_lo = s_mid;
                u = next;
            }
        }
        let f = if s_lo > s_hi {
            ((s_lo - level) / (s_lo - s_hi)).clamp(0.0, 1.0)
        } else {
            0.5
        };
        lo + f * width
    }
}

/// Builds the survival of the row vector `p0` (in `sys`'s order) under
/// `M = I + γA` (`sys`), growing the space until the times where `S`
/// falls to `levels` (within `horizon`) agree between two successive
/// sizes to `tolerance`, relatively.
pub(crate) fn build(
    sys: &BlockSystem,
    p0: &[f64],
    gamma: f64,
    horizon: f64,
    levels: &[f64],
    tolerance: f64,
) -> Result<Survival> {
    let n = p0.len();
    let beta = norm(p0);
    if n == 0 || beta == 0.0 {
        let mut s = Survival::ended();
        s.times = levels.iter().map(|_| Some(0.0)).collect();
        return Ok(s);
    }
    let max = MAX_VECTORS.min(n);
    // The basis, one column per vector, its room doubled as it grows (a
    // resize alone reserves the exact size: a copy per vector).
    let mut room = (max + 1).min(16);
    let mut basis = Mat::<f64>::with_capacity(n, room);
    basis.resize_with(n, 1, |i, _| p0[i] / beta);
    // 1ᵀ v of each basis vector.
    let mut sums = vec![p0.iter().sum::<f64>() / beta];
    // h[j][i]: column j of the Hessenberg, row i ≤ j + 1.
    let mut h = vec![vec![0.0; max + 1]; max];
    let mut previous: Option<Vec<Option<f64>>> = None;
    let mut last_change = f64::INFINITY;
    // `w` enters each step as the last basis vector (it was stored from it).
    let mut w: Vec<f64> = p0.iter().map(|&x| x / beta).collect();
    let mut c = Col::<f64>::zeros(max);
    for j in 0..max {
        sys.solve_ordered(&mut w);
        let before = norm(&w);
        if !before.is_finite() {
            return Err(Error::NotFinite {
                what: "the time distribution (Krylov space)".into(),
                value: before,
                cause: "a block solve lost all precision".into(),
            });
        }
        // Classical Gram–Schmidt (`c = Vᵀw`, `w −= V c`: two passes over
        // the basis as matrix–vector products), and once more if it
        // cancelled most of `w` (Daniel, Gragg, Kaufman & Stewart's
        // criterion, η = 1/√2).
        let v = basis.as_ref().subcols(0, j + 1);
        let mut rest = before;
        for _ in 0..2 {
            let entering = rest;
            let w_ref = ColRef::from_slice(&w);
            matmul(
                c.as_mut().subrows_mut(0, j + 1).as_mat_mut(),
                Accum::Replace,
                v.transpose(),
                w_ref.as_mat(),
                1.0,
                Par::Seq,
            );
            let cj = c.as_ref().subrows(0, j + 1);
            matmul(
                ColMut::from_slice_mut(&mut w).as_mat_mut(),
                Accum::Add,
                v,
                cj.as_mat(),
                -1.0,
                Par::Seq,
            );
            for (i, hi) in h[j].iter_mut().take(j + 1).enumerate() {
                *hi += cj[i];
            }
            rest = norm(&w);
            if rest > std::f64::consts::FRAC_1_SQRT_2 * entering {
                break;
            }
        }
        h[j][j + 1] = rest;
        let m = j + 1;
        let invariant = rest <= 1e-13 * before || m == n;
        let due = m >= 8 && (m % 2 == 0 || last_change <= CLOSE * tolerance);
        if invariant || m == max || due {
            let mut candidate = project(&sums, &h, m, beta, gamma)?;
            candidate.times = candidate.first_below(levels, horizon);
            if invariant {
                return Ok(candidate);
            }
            if let Some(prev) = &previous {
                last_change = change(prev, &candidate.times, horizon);
                if last_change <= tolerance {
                    return Ok(candidate);
                }
            }
            previous = Some(candidate.times);
        }
        if m < max {
            for x in &mut w {
                *x /= rest;
            }
            sums.push(w.iter().sum::<f64>());
            if m + 1 > room {
                room = (2 * room).min(max + 1);
                basis.reserve(n, room);
            }
            basis.resize_with(n, m + 1, |i, _| w[i]);
        }
    }
    Err(Error::NoConvergence {
        solver: "the time distribution (shift-and-invert Krylov)",
        iterations: max,
        residual: last_change,
        tolerance,
    })
}

/// The largest relative change between two sets of times (infinite if
/// one reaches a level within the horizon and the other does not).
fn change(a: &[Option<f64>], b: &[Option<f64>], horizon: f64) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| match (x, y) {
            (Some(x), Some(y)) => (x - y).abs() / x.abs().max(y.abs()).max(1e-12 * horizon),
            (None, None) => 0.0,
            _ => f64::INFINITY,
        })
        .fold(0.0, f64::max)
}

/// The survival on the first `m` vectors (`sums` their `1ᵀ v`): `G = (I −
/// H_m⁻¹)/γ`, weights `β 1ᵀ V_m`.
fn project(sums: &[f64], h: &[Vec<f64>], m: usize, beta: f64, gamma: f64) -> Result<Survival> {
    let hm = Mat::<f64>::from_fn(m, m, |i, j| h[j][i]);
    let inv = hm.partial_piv_lu().solve(Mat::<f64>::identity(m, m));
    if !(0..m).all(|j| (0..m).all(|i| inv[(i, j)].is_finite())) {
        return Err(Error::NotFinite {
            what: "the time distribution (Krylov space)".into(),
            value: f64::NAN,
            cause: "the projected shift-and-invert matrix is singular".into(),
        });
    }
    let g = Mat::<f64>::from_fn(m, m, |i, j| (f64::from(u8::from(i == j)) - inv[(i, j)]) / gamma);
    let weights = sums[..m].iter().map(|&v| beta * v).collect();
    Ok(Survival {
        weights,
        g,
        solves: m,
        times: Vec::new(),
    })
}

fn norm(a: &[f64]) -> f64 {
    dot(a, a).sqrt()
}

/// The 1-norm (largest column sum of magnitudes).
fn norm1(x: &Mat<f64>) -> f64 {
    (0..x.ncols())
        .map(|j| (0..x.nrows()).map(|i| x[(i, j)].abs()).sum::<f64>())
        .fold(0.0, f64::max)
}

/// The least Taylor degree `K ≤ 16` with `ν^{K+1}/(K+1)! ≤ 10⁻¹⁸` for a
/// matrix of 1-norm `ν ≤ ½`.
fn taylor_degree(nu: f64) -> usize {
    let mut degree = 1;
    let mut term = nu;
    while degree < 16 {
        term *= nu / (degree + 1) as f64;
        if term <= 1e-18 {
            break;
        }
        degree += 1;
    }
    degree
}

/// `out = a u`, in place.
fn product(out: &mut Col<f64>, a: &Mat<f64>, u: &Col<f64>) {
    matmul(out.as_mat_mut(), Accum::Replace, a, u.as_mat(), 1.0, Par::Seq);
}

fn unit(m: usize) -> Col<f64> {
    Col::from_fn(m, |i| f64::from(u8::from(i == 0)))
}

/// `exp(X)`: scaled by `2^s` to a 1-norm `ν ≤ ½`, a Taylor series of the
/// least degree `K ≤ 16` with `ν^{K+1}/(K+1)! ≤ 10⁻¹⁸`, squared `s` times.
fn expm(x: &Mat<f64>) -> Mat<f64> {
    let m = x.nrows();
    let norm1 = norm1(x);
    let s = if norm1 > 0.5 {
        (norm1 / 0.5).log2().ceil() as i32
    } else {
        0
    };
    let y = x * Scale(f64::powi(2.0, -s));
    let degree = taylor_degree(norm1 * f64::powi(2.0, -s));
    // Horner: I + Y (I + Y/2 (I + Y/3 (… (I + Y/K)))), then squared,
    // between two buffers.
    let mut e = Mat::<f64>::identity(m, m);
    let mut t = Mat::<f64>::zeros(m, m);
    for k in (1..=degree).rev() {
        matmul(&mut t, Accum::Replace, &y, &e, 1.0 / k as f64, Par::Seq);
        for i in 0..m {
            t[(i, i)] += 1.0;
        }
        std::mem::swap(&mut e, &mut t);
    }
    for _ in 0..s {
        matmul(&mut t, Accum::Replace, &e, &e, 1.0, Par::Seq);
        std::mem::swap(&mut e, &mut t);
    }
    e
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mat2(a: [f64; 4]) -> Mat<f64> {
        Mat::from_fn(2, 2, |i, j| a[2 * i + j])
    }

    #[test]
    fn expm_of_a_rotation_and_a_decay() {
        // exp([[0, -θ], [θ, 0]]) is the rotation by θ.
        let th = 2.5;
        let e = expm(&mat2([0.0, -th, th, 0.0]));
        let want = mat2([th.cos(), -th.sin(), th.sin(), th.cos()]);
        for (i, j) in [(0, 0), (0, 1), (1, 0), (1, 1)] {
            let (a, b) = (e[(i, j)], want[(i, j)]);
            assert!((a - b).abs() < 1e-14, "{a} vs {b}");
        }
        // A Jordan block: exp([[-λ, 1], [0, -λ]]) = e^{-λ} [[1, 1], [0, 1]].
        let l = 40.0;
        let e = expm(&mat2([-l, 1.0, 0.0, -l]));
        let d = (-l).exp();
        let want = mat2([d, d, 0.0, d]);
        for (i, j) in [(0, 0), (0, 1), (1, 0), (1, 1)] {
            let (a, b) = (e[(i, j)], want[(i, j)]);
            assert!((a - b).abs() <= 1e-12 * d, "{a} vs {b}");
        }
    }
}
