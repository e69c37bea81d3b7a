//! Seeded random streams for a run.
//!
//! Every run owns its generators; nothing is shared between runs or
//! threads, so a run is reproducible from its seed on any thread count.
//! Each subsystem (people placement, people motion, odometry, each sensor)
//! draws from its own ChaCha8 *stream* of the run's seed
//! ([`RandomStream::new`]): the streams are independent, and adding a sensor
//! or changing its noise does not change what the people or the odometry do
//! for the same seed (common random numbers when comparing controllers or
//! sensor set-ups).
//!
//! Gaussian variates use Marsaglia's polar method (G. Marsaglia, T. A. Bray,
//! *A convenient method for generating normal variables*, SIAM Review 6,
//! 1964), which yields them in pairs; the second is kept for the next call.

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Stream numbers of the subsystems of a run (see the module docs).
pub(crate) mod streams {
    /// Initial placement of the people.
    pub const PLACEMENT: u64 = 0;
    /// People's choices while walking (targets, pauses).
    pub const PEOPLE: u64 = 1;
    /// Odometry slip.
    pub const ODOMETRY: u64 = 2;
    /// Infrared detectors.
    pub const IR: u64 = 3;
    /// Sonar.
    pub const SONAR: u64 = 4;
    /// Laser `k` uses stream `LASER0 + k`.
    pub const LASER0: u64 = 16;
}

/// A seeded random stream with uniform, Bernoulli and Gaussian draws.
#[derive(Debug, Clone)]
pub struct RandomStream {
    rng: ChaCha8Rng,
    spare: Option<f64>,
}

impl RandomStream {
    /// Stream number `stream` of the generator seeded with `seed`.
    pub fn new(seed: u64, stream: u64) -> RandomStream {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(stream);
        RandomStream { rng, spare: None }
    }

    /// Uniform in [0, 1).
    #[inline]
    pub fn uniform(&mut self) -> f64 {
        self.rng.random::<f64>()
    }

    /// Uniform in [lo, hi) (`lo` when the interval is empty).
    #[inline]
    pub fn uniform_in(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.uniform()
    }

    /// Uniform integer in `0..n` (`n` > 0).
    #[inline]
    pub fn index(&mut self, n: usize) -> usize {
        self.rng.random_range(0..n)
    }

    /// `true` with probability `p` (no draw when `p` is 0).
    #[inline]
    pub fn chance(&mut self, p: f64) -> bool {
        p > 0.0 && self.uniform() < p
    }

    /// A standard normal variate.
    #[inline]
    pub fn normal(&mut self) -> f64 {
        if let Some(z) = self.spare.take() {
            return z;
        }
        loop {
            let u = 2.0 * self.uniform() - 1.0;
            let v = 2.0 * self.uniform() - 1.0;
            let s = u * u + v * v;
            if s > 0.0 && s < 1.0 {
                let k = (-2.0 * s.ln() / s).sqrt();
                self.spare = Some(v * k);
                return u * k;
            }
        }
    }

    /// A normal variate of standard deviation `sigma` (no draw when `sigma`
    /// is 0).
    #[inline]
    pub fn gaussian(&mut self, sigma: f64) -> f64 {
        if sigma > 0.0 { sigma * self.normal() } else { 0.0 }
    }

    /// An exponential variate of mean `mean` (0 when `mean` is 0).
    #[inline]
    pub fn exponential(&mut self, mean: f64) -> f64 {
        if mean > 0.0 {
            -mean * (1.0 - self.uniform()).ln()
        } else {
            0.0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_has_unit_moments() {
        let mut r = RandomStream::new(7, 0);
        let n = 200_000;
        let (mut s, mut s2) = (0.0, 0.0);
        for _ in 0..n {
            let z = r.normal();
            s += z;
            s2 += z * z;
        }
        let mean = s / n as f64;
        let var = s2 / n as f64 - mean * mean;
        assert!(mean.abs() < 0.01, "{mean}");
        assert!((var - 1.0).abs() < 0.02, "{var}");
    }

    #[test]
    fn streams_differ_and_repeat() {
        let a: Vec<f64> = {
            let mut r = RandomStream::new(1, 0);
            (0..4).map(|_| r.uniform()).collect()
        };
        let b: Vec<f64> = {
            let mut r = RandomStream::new(1, 1);
            (0..4).map(|_| r.uniform()).collect()
        };
        let again: Vec<f64> = {
            let mut r = RandomStream::new(1, 0);
            (0..4).map(|_| r.uniform()).collect()
        };
        assert_ne!(a, b);
        assert_eq!(a, again);
    }
}
