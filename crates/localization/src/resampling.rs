//! Low-variance (systematic) resampling, triggered by the effective sample
//! size.
//!
//! S. Thrun, W. Burgard, D. Fox, *Probabilistic Robotics*, §4.3.4, table
//! 4.4 (`low_variance_sampler`): one random number `r ∈ [0, 1/M)` and the
//! comb `r + m/M`, `m = 0 … M−1`, laid over the cumulative weights; particle
//! `i` is copied once for every tooth that falls in its slice. `O(N + M)`,
//! and every particle of normalised weight `w_i` gets `⌊M·w_i⌋` or
//! `⌈M·w_i⌉` copies (the sampling variance of multinomial resampling is
//! avoided).
//!
//! **When.** Resampling loses diversity, so it is done only when the
//! effective sample size `N_eff = 1 / Σ w_i²` (A. Kong, J. S. Liu,
//! W. H. Wong, JASA 1994; "selective resampling", G. Grisetti, C. Stachniss,
//! W. Burgard, IEEE T-RO 2007) falls below a fraction of the number of
//! particles (default 0.5, [`super::MclParams::resample_threshold`]). ROS
//! AMCL instead resamples every `resample_interval` (default 2) filter
//! updates; the `N_eff` test adapts to how informative the scans are.

/// The effective sample size `(Σ w)² / Σ w²` of (not necessarily
/// normalised) weights: `N` for equal weights, 1 when one particle holds
/// all the weight, 0 for no weight at all.
pub fn effective_sample_size(weights: &[f64]) -> f64 {
    let (s, s2) = weights.iter().fold((0.0, 0.0), |(s, s2), &w| (s + w, s2 + w * w));
    if s2 > 0.0 { s * s / s2 } else { 0.0 }
}

/// Low-variance resampling (module docs): fills `out` with `n_out` indices
/// into `weights` (non-negative, not necessarily normalised), in
/// increasing order; `u ∈ [0, 1)` is the single uniform draw (the comb's
/// offset, in units of the tooth spacing). Weights that sum to zero (or
/// are not finite) are taken as equal.
pub fn low_variance_resample(weights: &[f64], n_out: usize, u: f64, out: &mut Vec<usize>) {
    out.clear();
    let n = weights.len();
    if n == 0 || n_out == 0 {
        return;
    }
    let total: f64 = weights.iter().sum();
    if !(total.is_finite() && total > 0.0) {
        // No information: a systematic draw of equal weights.
        out.extend((0..n_out).map(|m| (((m as f64 + u) * n as f64 / n_out as f64) as usize).min(n - 1)));
        return;
    }
    let step = total / n_out as f64;
    let mut c = weights[0];
    let mut i = 0;
    for m in 0..n_out {
        let target = (u + m as f64) * step;
        while target > c && i + 1 < n {
            i += 1;
            c += weights[i];
        }
        out.push(i);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn effective_sample_size_limits() {
        assert_eq!(effective_sample_size(&[0.25; 4]), 4.0);
        assert_eq!(effective_sample_size(&[0.0, 1.0, 0.0]), 1.0);
        assert_eq!(effective_sample_size(&[0.0, 0.0]), 0.0);
        assert!((effective_sample_size(&[3.0, 1.0]) - 1.6).abs() < 1e-12);
    }

    proptest! {
        #[test]
        fn copies_are_within_one_of_the_expected_count(
            weights in proptest::collection::vec(0.0f64..10.0, 1..60),
            n_out in 1usize..300,
            u in 0.0f64..1.0,
        ) {
            let total: f64 = weights.iter().sum();
            prop_assume!(total > 1e-9);
            let mut out = Vec::new();
            low_variance_resample(&weights, n_out, u, &mut out);
            prop_assert_eq!(out.len(), n_out);
            prop_assert!(out.windows(2).all(|p| p[0] <= p[1]));
            let mut counts = vec![0usize; weights.len()];
            for &i in &out {
                counts[i] += 1;
            }
            for (i, &w) in weights.iter().enumerate() {
                let expected = n_out as f64 * w / total;
                prop_assert!(
                    (counts[i] as f64 - expected).abs() < 1.0 + 1e-9,
                    "particle {} weight {}: {} copies, expected {}", i, w, counts[i], expected
                );
            }
        }
    }

    #[test]
    fn zero_weights_are_never_copied_and_no_weight_means_equal() {
        let mut out = Vec::new();
        low_variance_resample(&[0.0, 1.0, 0.0, 1.0], 6, 0.5, &mut out);
        assert_eq!(out, vec![1, 1, 1, 3, 3, 3]);
        low_variance_resample(&[0.0; 3], 3, 0.5, &mut out);
        assert_eq!(out, vec![0, 1, 2]);
        low_variance_resample(&[f64::NAN, 1.0], 2, 0.0, &mut out);
        assert_eq!(out, vec![0, 1]);
    }
}
