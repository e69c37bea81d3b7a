//! KLD-sampling: how many particles a posterior needs, from how many
//! histogram bins it occupies.
//!
//! D. Fox, *Adapting the Sample Size in Particle Filters Through
//! KLD-Sampling*, IJRR 22(12), 2003 (and *Probabilistic Robotics* §8.3.7,
//! table 8.4). With `k` occupied bins, the number of samples that keeps the
//! Kullback–Leibler divergence between the sample-based and the true
//! (binned) posterior below `ε` with probability `1 − δ` is
//!
//! ```text
//! n = (k − 1) / (2ε) · (1 − 2/(9(k − 1)) + √(2/(9(k − 1))) · z_{1−δ})³
//! ```
//!
//! The localizer uses it only to *shrink* a large global-localization cloud
//! as it converges (module docs of [`super`]); ROS AMCL uses the same bound
//! (with bins of 0.5 m × 0.5 m × 10°) to size every resampling.

/// Parameters of the KLD bound and of its histogram.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct KldParams {
    /// `ε`: largest Kullback–Leibler divergence, > 0. Default 0.05.
    pub epsilon: f64,
    /// `z_{1−δ}`: upper standard normal quantile, ≥ 0. Default 2.326
    /// (`δ = 0.01`).
    pub z: f64,
    /// Side of a histogram bin in x and y, metres, > 0. Default 0.5 (AMCL).
    pub bin_xy_m: f64,
    /// Width of a histogram bin in heading, radians, > 0. Default 10°
    /// (AMCL).
    pub bin_theta_rad: f64,
}

impl Default for KldParams {
    fn default() -> KldParams {
        KldParams {
            epsilon: 0.05,
            z: 2.326,
            bin_xy_m: 0.5,
            bin_theta_rad: 10f64.to_radians(),
        }
    }
}

impl KldParams {
    /// The bound `n` for `k` occupied bins (module docs); 1 for `k ≤ 1`.
    pub fn sample_count(&self, k: usize) -> usize {
        if k <= 1 {
            return 1;
        }
        let km1 = (k - 1) as f64;
        let b = 2.0 / (9.0 * km1);
        let x = 1.0 - b + b.sqrt() * self.z;
        let n = km1 / (2.0 * self.epsilon) * x * x * x;
        if n.is_finite() {
            n.ceil().min(usize::MAX as f64 / 2.0) as usize
        } else {
            usize::MAX / 2
        }
    }

    /// Number of distinct bins the poses `(x[i], y[i], θ[i])` occupy
    /// (`keys` is a scratch buffer). `O(n log n)`, deterministic.
    pub fn occupied_bins(&self, x: &[f64], y: &[f64], theta: &[f64], keys: &mut Vec<u64>) -> usize {
        keys.clear();
        let key = |v: f64, side: f64| ((v / side).floor() as i64 as u64) & 0x1f_ffff;
        keys.extend(x.iter().zip(y).zip(theta).map(|((&x, &y), &t)| {
            (key(x, self.bin_xy_m) << 42) | (key(y, self.bin_xy_m) << 21) | key(t, self.bin_theta_rad)
        }));
        keys.sort_unstable();
        keys.dedup();
        keys.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bound_matches_the_published_values() {
        let p = KldParams {
            epsilon: 0.05,
            z: 2.326,
            ..KldParams::default()
        };
        // k = 2: (1/0.1)·(1 − 2/9 + √(2/9)·2.326)³ = 10·1.8743³ ≈ 65.8.
        assert_eq!(p.sample_count(2), 66);
        // Grows about linearly in k.
        let n100 = p.sample_count(100);
        assert!((1200..1400).contains(&n100), "{n100}");
        assert_eq!(p.sample_count(0), 1);
        assert!(p.sample_count(1000) > 8 * n100);
    }

    #[test]
    fn bins_count_distinct_cells() {
        let p = KldParams::default();
        let mut keys = Vec::new();
        let x = [0.1, 0.2, 0.6, -0.1, 0.1];
        let y = [0.1, 0.3, 0.1, 0.1, 0.1];
        let t = [0.0, 0.1, 0.0, 0.0, 3.0];
        // (0,0,0) twice, (1,0,0), (−1,0,0), (0,0,17).
        assert_eq!(p.occupied_bins(&x, &y, &t, &mut keys), 4);
    }
}
