//! Summary statistics with confidence intervals.
//!
//! * Proportions (the reliability index `I_R = successes / runs`): Wilson
//!   score interval, which behaves at 0 and 1 where the normal approximation
//!   does not (Wilson 1927; Brown, Cai & DasGupta 2001).
//! * Means (the time index `I_T`, path lengths): Student-t interval
//!   `x̄ ± t_{1−α/2, n−1} · s/√n`.
//! * Means of observations that come in clusters sharing something (the
//!   missions of one campaign share one learner, so they are not
//!   independent): [`Clustered`], the mean of the clusters' means with a
//!   Student-t interval over the clusters, `x̄ ± t_{1−α/2, k−1} · s_k/√k`
//!   for `k` clusters — the cluster-level analysis of Donner and Klar
//!   (*Design and Analysis of Cluster Randomization Trials*, 2000, ch. 6),
//!   valid whatever the correlation within a cluster, at the price of
//!   `k − 1` degrees of freedom. Paired differences (a strategy minus
//!   another on the same missions) go in as the observations.

use petri::simulation::student_t_quantile;

/// Standard normal quantile at `p`: the Student-t quantile with a huge
/// number of degrees of freedom, which equals it to far better than needed
/// at the confidence levels used here.
fn normal_quantile(p: f64) -> f64 {
    student_t_quantile(p, 1e9)
}

/// A proportion with its Wilson interval.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Proportion {
    /// Successes.
    pub successes: usize,
    /// Trials.
    pub n: usize,
    /// `successes / n` (NaN when `n = 0`).
    pub value: f64,
    /// Lower bound of the interval.
    pub low: f64,
    /// Upper bound of the interval.
    pub high: f64,
}

/// The median of the finite values of `xs`; NaN when there is none.
pub fn median(xs: impl IntoIterator<Item = f64>) -> f64 {
    let mut v: Vec<f64> = xs.into_iter().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

impl Proportion {
    /// As a report writes it: `83 % (75–90)`; `-` without trials.
    pub fn percent(&self) -> String {
        if self.n == 0 {
            return "-".into();
        }
        format!(
            "{:.0} % ({:.0}–{:.0})",
            100.0 * self.value,
            100.0 * self.low,
            100.0 * self.high
        )
    }

    /// The proportion and its interval at `confidence` (e.g. 0.95).
    pub fn new(successes: usize, n: usize, confidence: f64) -> Proportion {
        if n == 0 {
            return Proportion {
                successes,
                n,
                value: f64::NAN,
                low: f64::NAN,
                high: f64::NAN,
            };
        }
        let z = normal_quantile(0.5 + confidence / 2.0);
        let nf = n as f64;
        let p = successes as f64 / nf;
        let z2 = z * z;
        let centre = (p + z2 / (2.0 * nf)) / (1.0 + z2 / nf);
        let half = z / (1.0 + z2 / nf) * (p * (1.0 - p) / nf + z2 / (4.0 * nf * nf)).sqrt();
        Proportion {
            successes,
            n,
            value: p,
            // Exact at the ends (the formula gives 0 and 1 up to rounding).
            low: if successes == 0 {
                0.0
            } else {
                (centre - half).max(0.0)
            },
            high: if successes == n {
                1.0
            } else {
                (centre + half).min(1.0)
            },
        }
    }
}

/// A mean with its Student-t interval.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Mean {
    /// Samples.
    pub n: usize,
    /// Sample mean (NaN when empty).
    pub mean: f64,
    /// Half-width of the interval (NaN when fewer than 2 samples).
    pub half_width: f64,
    /// Sample standard deviation.
    pub std_dev: f64,
}

impl Mean {
    /// As a report writes it, one decimal: `12.3 ± 0.4`, `12.3` without an
    /// interval, `-` without samples.
    pub fn one_decimal(&self) -> String {
        if self.n == 0 {
            "-".into()
        } else if self.half_width.is_finite() {
            format!("{:.1} ± {:.1}", self.mean, self.half_width)
        } else {
            format!("{:.1}", self.mean)
        }
    }

    /// The mean of `xs` and its interval at `confidence`.
    pub fn new(xs: &[f64], confidence: f64) -> Mean {
        let n = xs.len();
        if n == 0 {
            return Mean {
                n,
                mean: f64::NAN,
                half_width: f64::NAN,
                std_dev: f64::NAN,
            };
        }
        let nf = n as f64;
        let mean = xs.iter().sum::<f64>() / nf;
        if n < 2 {
            return Mean {
                n,
                mean,
                half_width: f64::NAN,
                std_dev: f64::NAN,
            };
        }
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (nf - 1.0);
        let sd = var.sqrt();
        let t = student_t_quantile(0.5 + confidence / 2.0, nf - 1.0);
        Mean {
            n,
            mean,
            half_width: t * sd / nf.sqrt(),
            std_dev: sd,
        }
    }
}

/// A mean over clusters of observations, with a Student-t interval over
/// the clusters' means (module docs).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Clustered {
    /// Clusters with at least one observation.
    pub clusters: usize,
    /// Observations in all.
    pub n: usize,
    /// Mean of the clusters' means (NaN without a cluster).
    pub mean: f64,
    /// Half-width of the interval (NaN with fewer than 2 clusters).
    pub half_width: f64,
}

impl Clustered {
    /// The mean of the clusters' means of `clusters` (empty clusters left
    /// out; non-finite values are a bug of the caller and propagate) and
    /// its interval at `confidence`.
    pub fn new(clusters: &[Vec<f64>], confidence: f64) -> Clustered {
        let means: Vec<f64> = clusters
            .iter()
            .filter(|c| !c.is_empty())
            .map(|c| c.iter().sum::<f64>() / c.len() as f64)
            .collect();
        let m = Mean::new(&means, confidence);
        Clustered {
            clusters: means.len(),
            n: clusters.iter().map(Vec::len).sum(),
            mean: m.mean,
            half_width: m.half_width,
        }
    }

    /// Lower end of the interval.
    pub fn low(&self) -> f64 {
        self.mean - self.half_width
    }

    /// Upper end of the interval.
    pub fn high(&self) -> f64 {
        self.mean + self.half_width
    }

    /// As a report writes it: `+0.012 ± 0.034` with `decimals` decimals
    /// and a sign; `-` without clusters.
    pub fn signed(&self, decimals: usize) -> String {
        if self.clusters == 0 {
            "-".into()
        } else if self.half_width.is_finite() {
            format!("{:+.*} ± {:.*}", decimals, self.mean, decimals, self.half_width)
        } else {
            format!("{:+.*}", decimals, self.mean)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wilson_interval_known_values() {
        // 8 of 10 at 95%: (0.4902, 0.9433) (Newcombe 1998, table I).
        let p = Proportion::new(8, 10, 0.95);
        assert!(
            (p.low - 0.4902).abs() < 1e-4 && (p.high - 0.9433).abs() < 1e-4,
            "{p:?}"
        );
        let all = Proportion::new(50, 50, 0.95);
        assert_eq!(all.value, 1.0);
        assert!(all.high == 1.0 && all.low > 0.92 && all.low < 0.93, "{all:?}");
        let none = Proportion::new(0, 50, 0.95);
        assert!(none.low == 0.0 && none.high > 0.07 && none.high < 0.08);
        assert!(Proportion::new(0, 0, 0.95).value.is_nan());
    }

    #[test]
    fn t_interval() {
        let m = Mean::new(&[1.0, 2.0, 3.0, 4.0, 5.0], 0.95);
        assert_eq!(m.mean, 3.0);
        // s = sqrt(2.5), t(0.975, 4) = 2.776
        assert!((m.half_width - 2.776 * 2.5f64.sqrt() / 5f64.sqrt()).abs() < 1e-3);
        assert!(Mean::new(&[1.0], 0.95).half_width.is_nan());
    }

    #[test]
    fn clustered_interval_is_the_t_interval_of_the_cluster_means() {
        // Cluster means 1, 2, 6 (sizes 2, 1, 3): mean 3, s = sqrt(7),
        // t(0.975, 2) = 4.303.
        let c = Clustered::new(&[vec![0.0, 2.0], vec![2.0], vec![5.0, 6.0, 7.0], vec![]], 0.95);
        assert_eq!((c.clusters, c.n), (3, 6));
        assert!((c.mean - 3.0).abs() < 1e-12);
        assert!(
            (c.half_width - 4.303 * 7f64.sqrt() / 3f64.sqrt()).abs() < 1e-2,
            "{c:?}"
        );
        assert!((c.low() + c.high() - 6.0).abs() < 1e-12);
        assert_eq!(c.signed(1), format!("+3.0 ± {:.1}", c.half_width));
        // Perfectly correlated within clusters: repeating an observation
        // inside its cluster does not narrow the interval, as it would if
        // the observations were taken as independent.
        let once = Clustered::new(&[vec![1.0], vec![2.0], vec![4.0]], 0.95);
        let thrice = Clustered::new(&[vec![1.0; 3], vec![2.0; 3], vec![4.0; 3]], 0.95);
        assert!((once.half_width - thrice.half_width).abs() < 1e-12);
        let naive = Mean::new(&[1.0, 1.0, 1.0, 2.0, 2.0, 2.0, 4.0, 4.0, 4.0], 0.95);
        assert!(naive.half_width < 0.5 * thrice.half_width, "{naive:?} {thrice:?}");
        let one = Clustered::new(&[vec![1.0, 3.0]], 0.95);
        assert!(one.mean == 2.0 && one.half_width.is_nan());
        assert_eq!(Clustered::new(&[], 0.95).signed(2), "-");
    }
}
