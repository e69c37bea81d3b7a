//! Standard normal variates by the Marsaglia polar method.
//!
//! G. Marsaglia, T. A. Bray, *A Convenient Method for Generating Normal
//! Variables*, SIAM Review 6(3), 1964: draw `(u, v)` uniform in the square
//! `[−1, 1)²` until `s = u² + v²` lies in `(0, 1)`, then `u·m` and `v·m` with
//! `m = √(−2 ln s / s)` are two independent standard normal variates. The
//! second one is kept for the next call, so on average one logarithm, one
//! square root and 1.27 pairs of uniform draws give two variates.
//!
//! Deterministic: the same generator state gives the same sequence on every
//! platform (only `ln`, `sqrt` and arithmetic, no lookup tables).

use rand::RngExt;
use rand_chacha::ChaCha8Rng;

/// A seeded source of standard normal variates (module docs).
#[derive(Debug, Clone)]
pub struct Gaussian {
    rng: ChaCha8Rng,
    spare: Option<f64>,
}

impl Gaussian {
    /// A source drawing from `rng`.
    pub fn new(rng: ChaCha8Rng) -> Gaussian {
        Gaussian { rng, spare: None }
    }

    /// The uniform generator underneath (for uniform draws from the same
    /// stream).
    pub fn rng(&mut self) -> &mut ChaCha8Rng {
        &mut self.rng
    }

    /// Uniform in `[0, 1)`.
    #[inline]
    pub fn uniform(&mut self) -> f64 {
        self.rng.random::<f64>()
    }

    /// A standard normal variate.
    #[inline]
    pub fn normal(&mut self) -> f64 {
        if let Some(z) = self.spare.take() {
            return z;
        }
        loop {
            let u = 2.0 * self.rng.random::<f64>() - 1.0;
            let v = 2.0 * self.rng.random::<f64>() - 1.0;
            let s = u * u + v * v;
            if s > 0.0 && s < 1.0 {
                let m = (-2.0 * s.ln() / s).sqrt();
                self.spare = Some(v * m);
                return u * m;
            }
        }
    }

    /// A normal variate of standard deviation `sigma` (no draw when `sigma`
    /// is 0, so noiseless models consume no randomness).
    #[inline]
    pub fn gaussian(&mut self, sigma: f64) -> f64 {
        if sigma > 0.0 { sigma * self.normal() } else { 0.0 }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn moments_and_tails_of_the_standard_normal() {
        let mut g = Gaussian::new(ChaCha8Rng::seed_from_u64(3));
        let n = 200_000;
        let (mut s, mut s2, mut beyond2) = (0.0, 0.0, 0usize);
        for _ in 0..n {
            let z = g.normal();
            s += z;
            s2 += z * z;
            beyond2 += (z.abs() > 2.0) as usize;
        }
        let mean = s / n as f64;
        let var = s2 / n as f64 - mean * mean;
        assert!(mean.abs() < 0.01, "{mean}");
        assert!((var - 1.0).abs() < 0.015, "{var}");
        // P(|Z| > 2) = 0.0455.
        let p = beyond2 as f64 / n as f64;
        assert!((p - 0.0455).abs() < 0.002, "{p}");
    }

    #[test]
    fn zero_sigma_draws_nothing() {
        let mut a = Gaussian::new(ChaCha8Rng::seed_from_u64(9));
        let mut b = a.clone();
        assert_eq!(a.gaussian(0.0), 0.0);
        assert_eq!(a.normal(), b.normal());
    }
}
