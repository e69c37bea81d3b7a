//! Recovery by random particles when the measurement likelihood drops
//! (Augmented MCL).
//!
//! S. Thrun, W. Burgard, D. Fox, *Probabilistic Robotics*, §8.3.5, table
//! 8.3, as ROS AMCL implements it (`recovery_alpha_slow`,
//! `recovery_alpha_fast`): two exponential averages of the mean
//! measurement likelihood `w_avg`,
//!
//! ```text
//! w_slow ← w_slow + α_slow (w_avg − w_slow)
//! w_fast ← w_fast + α_fast (w_avg − w_fast)      (0 ≤ α_slow ≪ α_fast)
//! ```
//!
//! and at resampling each new particle is, with probability
//! `max(0, 1 − w_fast / w_slow)`, drawn uniformly over the free space
//! instead of from the old set. A sudden drop of the likelihood (the robot
//! was carried away, or the filter diverged) makes `w_fast` fall below
//! `w_slow` and injects random particles.
//!
//! The averages are kept as logarithms, so likelihoods far below the
//! smallest `f64` (a product over many beams) do not underflow.
//!
//! **Default: off** (`α_slow = α_fast = 0`, as in AMCL). People who hide
//! the walls lower the likelihood for many seconds, which would scatter
//! particles over the building while the estimate is in fact fine; the
//! tour-guide's Warning state, not the filter, handles that. AMCL's
//! suggested values `0.001` and `0.1` enable it.

/// The two averaging rates (module docs). `0 ≤ α_slow ≤ α_fast ≤ 1`;
/// `α_slow = 0` disables recovery.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RecoveryParams {
    /// `α_slow`, per filter iteration, in [0, 1]. Default 0 (off).
    pub alpha_slow: f64,
    /// `α_fast`, per filter iteration, in [0, 1], ≥ `α_slow`. Default 0.
    pub alpha_fast: f64,
}

impl RecoveryParams {
    /// Whether recovery is on.
    pub fn enabled(&self) -> bool {
        self.alpha_slow > 0.0 && self.alpha_fast > 0.0
    }
}

/// The running averages (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Recovery {
    params: RecoveryParams,
    ln_w_slow: Option<f64>,
    ln_w_fast: Option<f64>,
}

/// `ln((1 − α)·e^a + α·e^b)` without overflow or underflow.
fn ln_blend(a: f64, b: f64, alpha: f64) -> f64 {
    let (x, y) = ((1.0 - alpha).ln() + a, alpha.ln() + b);
    let m = x.max(y);
    if m == f64::NEG_INFINITY {
        return m;
    }
    m + ((x - m).exp() + (y - m).exp()).ln()
}

impl Recovery {
    /// Averages not yet started.
    pub fn new(params: RecoveryParams) -> Recovery {
        Recovery {
            params,
            ln_w_slow: None,
            ln_w_fast: None,
        }
    }

    /// Forgets the averages (after a re-initialisation of the filter).
    pub fn reset(&mut self) {
        self.ln_w_slow = None;
        self.ln_w_fast = None;
    }

    /// Takes the logarithm of one iteration's mean measurement likelihood.
    /// The first observation starts both averages.
    pub fn observe(&mut self, ln_w_avg: f64) {
        if !self.params.enabled() || ln_w_avg.is_nan() {
            return;
        }
        self.ln_w_slow = Some(match self.ln_w_slow {
            None => ln_w_avg,
            Some(s) => ln_blend(s, ln_w_avg, self.params.alpha_slow),
        });
        self.ln_w_fast = Some(match self.ln_w_fast {
            None => ln_w_avg,
            Some(f) => ln_blend(f, ln_w_avg, self.params.alpha_fast),
        });
    }

    /// The probability `max(0, 1 − w_fast / w_slow)` of replacing a
    /// resampled particle by a random one (0 when off).
    pub fn injection_probability(&self) -> f64 {
        match (self.ln_w_slow, self.ln_w_fast) {
            (Some(s), Some(f)) if self.params.enabled() && s.is_finite() => (1.0 - (f - s).exp()).max(0.0),
            _ => 0.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn off_by_default() {
        let mut r = Recovery::new(RecoveryParams::default());
        r.observe(0.0);
        r.observe(-50.0);
        assert_eq!(r.injection_probability(), 0.0);
    }

    #[test]
    fn a_sudden_drop_injects_and_a_steady_level_does_not() {
        let mut r = Recovery::new(RecoveryParams {
            alpha_slow: 0.001,
            alpha_fast: 0.1,
        });
        for _ in 0..200 {
            r.observe(10f64.ln());
        }
        assert!(r.injection_probability() < 1e-9);
        // The likelihood falls to a tenth, far below any f64 scale too.
        for _ in 0..20 {
            r.observe(1f64.ln());
        }
        let p = r.injection_probability();
        assert!(p > 0.5 && p < 1.0, "{p}");
        let mut tiny = Recovery::new(RecoveryParams {
            alpha_slow: 0.001,
            alpha_fast: 0.1,
        });
        tiny.observe(-2000.0);
        for _ in 0..30 {
            tiny.observe(-2010.0);
        }
        assert!(tiny.injection_probability() > 0.9);
    }

    #[test]
    fn blend_is_the_weighted_mean() {
        let v = ln_blend(2f64.ln(), 4f64.ln(), 0.25).exp();
        assert!((v - 2.5).abs() < 1e-12);
    }
}
