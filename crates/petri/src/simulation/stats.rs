//! Statistics for the simulator's confidence intervals: running mean and
//! variance, and quantiles of Student's t and of the standard normal
//! distribution, computed here to avoid a dependency.
//!
//! - `ln Γ` by the Lanczos approximation (g = 7, 9 coefficients; relative
//!   error about 1e-15).
//! - The regularised incomplete beta function `I_x(a, b)` by its continued
//!   fraction, evaluated with the modified Lentz method (Press et al.,
//!   *Numerical Recipes*, 3rd ed., §6.4), and the regularised upper incomplete
//!   gamma function `Q(a, x)` by its series or continued fraction (§6.2).
//! - The upper tail of Student's t with `ν` degrees of freedom,
//!   `P{T > t} = ½ · I_{ν/(ν+t²)}(ν/2, ½)` for `t ≥ 0` (Abramowitz & Stegun
//!   26.7.1 and 26.5.27), inverted by Newton's method safeguarded by
//!   bisection; closed forms for `ν = 1` (Cauchy) and `ν = 2`; for
//!   `ν > 10⁶` the Cornish–Fisher expansion in `1/ν` (A&S 26.7.5), whose
//!   first neglected term is below 1e-20 there.
//! - The normal quantile by Acklam's rational approximation (relative error
//!   1.15e-9), polished by two Newton steps on `Φ(z) = ½ erfc(−z/√2)`, with
//!   `erfc(x) = Q(½, x²)`.

/// Running mean and sum of squared deviations (Welford's algorithm), so that
/// the sample variance of the observations is `m2 / (n − 1)` without storing
/// them and without the cancellation of the textbook formula.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Welford {
    pub(crate) n: usize,
    pub(crate) mean: f64,
    pub(crate) m2: f64,
}

impl Welford {
    /// Adds an observation.
    #[inline]
    pub(crate) fn push(&mut self, x: f64) {
        self.n += 1;
        let d = x - self.mean;
        self.mean += d / self.n as f64;
        self.m2 += d * (x - self.mean);
    }

    /// Sample variance (`∞` with fewer than two observations).
    pub(crate) fn variance(&self) -> f64 {
        if self.n < 2 {
            f64::INFINITY
        } else {
            (self.m2 / (self.n - 1) as f64).max(0.0)
        }
    }
}

/// `ln Γ(x)` for `x > 0` (Lanczos, g = 7).
pub(crate) fn ln_gamma(x: f64) -> f64 {
    const G: f64 = 7.0;
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        // Reflection: Γ(x) Γ(1 − x) = π / sin(πx).
        let pi = std::f64::consts::PI;
        return (pi / (pi * x).sin()).abs().ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut a = C[0];
    let t = x + G + 0.5;
    for (i, &c) in C.iter().enumerate().skip(1) {
        a += c / (x + i as f64);
    }
    0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

const TINY: f64 = 1e-300;
const EPS: f64 = 1e-16;

/// Continued fraction of the incomplete beta function (modified Lentz).
fn beta_cf(a: f64, b: f64, x: f64) -> f64 {
    let max_iter = 300 + (20.0 * a.max(b).sqrt()) as usize;
    let (qab, qap, qam) = (a + b, a + 1.0, a - 1.0);
    let guard = |v: f64| if v.abs() < TINY { TINY } else { v };
    let mut c = 1.0;
    let mut d = 1.0 / guard(1.0 - qab * x / qap);
    let mut h = d;
    for m in 1..=max_iter {
        let m = m as f64;
        let m2 = 2.0 * m;
        let aa = m * (b - m) * x / ((qam + m2) * (a + m2));
        d = 1.0 / guard(1.0 + aa * d);
        c = guard(1.0 + aa / c);
        h *= d * c;
        let aa = -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2));
        d = 1.0 / guard(1.0 + aa * d);
        c = guard(1.0 + aa / c);
        let del = d * c;
        h *= del;
        if (del - 1.0).abs() < EPS {
            break;
        }
    }
    h
}

/// Regularised incomplete beta `I_x(a, b)`, given `x` and `y = 1 − x`
/// separately so that neither loses digits to cancellation.
fn inc_beta(a: f64, b: f64, x: f64, y: f64) -> f64 {
    if x <= 0.0 {
        return 0.0;
    }
    if y <= 0.0 {
        return 1.0;
    }
    let ln_front = ln_gamma(a + b) - ln_gamma(a) - ln_gamma(b) + a * x.ln() + b * y.ln();
    let front = ln_front.exp();
    if x < (a + 1.0) / (a + b + 2.0) {
        front * beta_cf(a, b, x) / a
    } else {
        1.0 - front * beta_cf(b, a, y) / b
    }
}

/// Regularised upper incomplete gamma `Q(a, x)`.
fn gamma_q(a: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 1.0;
    }
    let ln_front = -x + a * x.ln() - ln_gamma(a);
    if x < a + 1.0 {
        // Series for P(a, x).
        let mut ap = a;
        let mut del = 1.0 / a;
        let mut sum = del;
        for _ in 0..1000 {
            ap += 1.0;
            del *= x / ap;
            sum += del;
            if del.abs() < sum.abs() * EPS {
                break;
            }
        }
        1.0 - sum * ln_front.exp()
    } else {
        // Continued fraction for Q(a, x) (modified Lentz).
        let guard = |v: f64| if v.abs() < TINY { TINY } else { v };
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / TINY;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..1000 {
            let i = i as f64;
            let an = -i * (i - a);
            b += 2.0;
            d = 1.0 / guard(an * d + b);
            c = guard(b + an / c);
            let del = d * c;
            h *= del;
            if (del - 1.0).abs() < EPS {
                break;
            }
        }
        ln_front.exp() * h
    }
}

/// Complementary error function.
fn erfc(x: f64) -> f64 {
    if x >= 0.0 {
        gamma_q(0.5, x * x)
    } else {
        2.0 - gamma_q(0.5, x * x)
    }
}

/// The standard normal quantile `Φ⁻¹(p)` for `0 < p < 1`.
pub(crate) fn normal_quantile(p: f64) -> f64 {
    if !(p > 0.0 && p < 1.0) {
        return f64::NAN;
    }
    if p > 0.5 {
        return -normal_quantile(1.0 - p);
    }
    // Acklam's approximation, lower region and central region (p ≤ ½ here).
    const A: [f64; 6] = [
        -3.969_683_028_665_376e1,
        2.209_460_984_245_205e2,
        -2.759_285_104_469_687e2,
        1.383_577_518_672_69e2,
        -3.066_479_806_614_716e1,
        2.506_628_277_459_239,
    ];
    const B: [f64; 5] = [
        -5.447_609_879_822_406e1,
        1.615_858_368_580_409e2,
        -1.556_989_798_598_866e2,
        6.680_131_188_771_972e1,
        -1.328_068_155_288_572e1,
    ];
    const C: [f64; 6] = [
        -7.784_894_002_430_293e-3,
        -3.223_964_580_411_365e-1,
        -2.400_758_277_161_838,
        -2.549_732_539_343_734,
        4.374_664_141_464_968,
        2.938_163_982_698_783,
    ];
    const D: [f64; 4] = [
        7.784_695_709_041_462e-3,
        3.224_671_290_700_398e-1,
        2.445_134_137_142_996,
        3.754_408_661_907_416,
    ];
    let mut z = if p < 0.02425 {
        let q = (-2.0 * p.ln()).sqrt();
        (((((C[0] * q + C[1]) * q + C[2]) * q + C[3]) * q + C[4]) * q + C[5])
            / ((((D[0] * q + D[1]) * q + D[2]) * q + D[3]) * q + 1.0)
    } else {
        let q = p - 0.5;
        let r = q * q;
        (((((A[0] * r + A[1]) * r + A[2]) * r + A[3]) * r + A[4]) * r + A[5]) * q
            / (((((B[0] * r + B[1]) * r + B[2]) * r + B[3]) * r + B[4]) * r + 1.0)
    };
    // Newton on Φ(z) − p, Φ(z) = ½ erfc(−z/√2), φ(z) = e^{−z²/2}/√(2π).
    for _ in 0..2 {
        let cdf = 0.5 * erfc(-z / std::f64::consts::SQRT_2);
        let pdf = (-0.5 * z * z).exp() / (2.0 * std::f64::consts::PI).sqrt();
        if pdf > 0.0 && cdf.is_finite() {
            let step = (cdf - p) / pdf;
            if step.is_finite() {
                z -= step;
            }
        }
    }
    z
}

/// Upper tail `P{T > t}` of Student's t with `df` degrees of freedom, `t ≥ 0`.
fn t_tail(t: f64, df: f64) -> f64 {
    let t2 = t * t;
    let x = df / (df + t2);
    let y = t2 / (df + t2);
    0.5 * inc_beta(0.5 * df, 0.5, x, y)
}

/// Density of Student's t.
fn t_pdf(t: f64, df: f64) -> f64 {
    let ln = ln_gamma(0.5 * (df + 1.0))
        - ln_gamma(0.5 * df)
        - 0.5 * (df * std::f64::consts::PI).ln()
        - 0.5 * (df + 1.0) * (t * t / df).ln_1p();
    ln.exp()
}

/// Cornish–Fisher expansion of the t quantile around the normal quantile `z`
/// (Abramowitz & Stegun 26.7.5).
fn cornish_fisher(z: f64, df: f64) -> f64 {
    let z2 = z * z;
    let g1 = (z2 + 1.0) * z / 4.0;
    let g2 = ((5.0 * z2 + 16.0) * z2 + 3.0) * z / 96.0;
    let g3 = (((3.0 * z2 + 19.0) * z2 + 17.0) * z2 - 15.0) * z / 384.0;
    let g4 = ((((79.0 * z2 + 776.0) * z2 + 1482.0) * z2 - 1920.0) * z2 - 945.0) * z / 92160.0;
    z + g1 / df + g2 / (df * df) + g3 / (df * df * df) + g4 / (df * df * df * df)
}

/// The `t ≥ 0` with `P{T > t} = q`, for `0 < q ≤ ½`.
fn t_upper_quantile(q: f64, df: f64) -> f64 {
    if q >= 0.5 {
        return 0.0;
    }
    if df == 1.0 {
        // Cauchy: P{T > t} = ½ − atan(t)/π.
        return 1.0 / (std::f64::consts::PI * q).tan();
    }
    if df == 2.0 {
        // P{T > t} = ½ − t / (2 √(t² + 2)).
        return (1.0 - 2.0 * q) / (2.0 * q * (1.0 - q)).sqrt();
    }
    let z = -normal_quantile(q);
    let guess = cornish_fisher(z, df);
    if df > 1e6 {
        return guess;
    }
    // Bracket [lo, hi] with tail(lo) > q ≥ tail(hi), then safeguarded Newton.
    let mut lo = 0.0;
    let mut hi = if guess.is_finite() && guess > 0.0 {
        guess
    } else {
        1.0
    };
    let mut found = false;
    for _ in 0..4096 {
        if t_tail(hi, df) <= q {
            found = true;
            break;
        }
        lo = hi;
        hi *= 2.0;
        if !hi.is_finite() {
            return f64::INFINITY;
        }
    }
    if !found {
        return f64::INFINITY;
    }
    let mut t = if guess > lo && guess < hi {
        guess
    } else {
        0.5 * (lo + hi)
    };
    for _ in 0..200 {
        let f = t_tail(t, df) - q;
        if f == 0.0 {
            return t;
        }
        if f > 0.0 {
            lo = t;
        } else {
            hi = t;
        }
        let pdf = t_pdf(t, df);
        let newton = t + f / pdf;
        let next = if newton.is_finite() && newton > lo && newton < hi {
            newton
        } else {
            0.5 * (lo + hi)
        };
        if (next - t).abs() <= 1e-15 * t.abs().max(1e-300) || hi - lo <= 1e-15 * hi {
            return next;
        }
        t = next;
    }
    t
}

/// The `p`-quantile of Student's t distribution with `df` degrees of freedom:
/// the `t` with `P{T ≤ t} = p`. `df` need not be a whole number. Returns NaN
/// when `p` is not in `(0, 1)` or `df` is not a number `> 0`.
///
/// Method: closed forms for `df` = 1 and 2; otherwise the upper tail
/// `P{T > t} = ½ · I_{df/(df+t²)}(df/2, ½)` (regularised incomplete beta by
/// its continued fraction) inverted by Newton's method safeguarded by
/// bisection, from a Cornish–Fisher starting point; for `df > 10⁶` the
/// Cornish–Fisher expansion itself. Accurate to about 1e-12 relative.
///
/// ```
/// use petri::simulation::student_t_quantile;
/// assert!((student_t_quantile(0.975, 19.0) - 2.093).abs() < 1e-3);
/// ```
pub fn student_t_quantile(p: f64, df: f64) -> f64 {
    if !(p > 0.0 && p < 1.0 && df > 0.0) {
        return f64::NAN;
    }
    if p == 0.5 {
        0.0
    } else if p > 0.5 {
        t_upper_quantile(1.0 - p, df)
    } else {
        -t_upper_quantile(p, df)
    }
}

/// The critical value `t` for a two-sided interval of level `confidence`
/// (`P{|T| ≤ t} = confidence`), computed from the tail `(1 − confidence)/2`
/// without forming `(1 + confidence)/2`.
pub(crate) fn t_critical(confidence: f64, df: f64) -> f64 {
    t_upper_quantile(0.5 * (1.0 - confidence), df)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol * b.abs().max(1.0)
    }

    #[test]
    fn t_quantiles_match_the_tables() {
        // Reference values: mpmath (30 digits), bisection on the incomplete beta.
        for (p, df, want, tol) in [
            (0.975, 1.0, 12.706_204_736_174_693, 1e-13),
            (0.975, 2.0, 4.302_652_729_749_462, 1e-13),
            (0.975, 3.0, 3.182_446_305_283_708, 1e-12),
            (0.95, 5.0, 2.015_048_373_333_024, 1e-12),
            (0.995, 9.0, 3.249_835_541_592_126, 1e-12),
            (0.975, 19.0, 2.093_024_054_408_309, 1e-12),
            (0.975, 30.0, 2.042_272_456_301_238, 1e-12),
            (0.975, 1000.0, 1.962_339_080_826_408, 1e-12),
            (0.999_95, 4.0, 15.544_100_581_546_11, 1e-10),
            (0.9, 2.5, 1.730_250_928_807_177, 1e-12),
            (0.999, 1e6, 3.090_240_456_316_519, 1e-10),
        ] {
            let got = student_t_quantile(p, df);
            assert!(close(got, want, tol), "t({p}, {df}) = {got}, want {want}");
            let lower = student_t_quantile(1.0 - p, df);
            assert!(close(lower, -want, tol), "t({}, {df}) = {lower}", 1.0 - p);
        }
        // The brief's rounded values.
        assert!((student_t_quantile(0.975, 1.0) - 12.706).abs() < 5e-4);
        assert!((student_t_quantile(0.975, 19.0) - 2.093).abs() < 5e-4);
        assert!((student_t_quantile(0.995, 9.0) - 3.250).abs() < 5e-4);
        assert!((student_t_quantile(0.975, 1000.0) - 1.962).abs() < 5e-4);
    }

    #[test]
    fn t_quantile_tends_to_the_normal_one() {
        let z = 1.959_963_984_540_054;
        assert!(close(normal_quantile(0.975), z, 1e-14));
        assert!(close(normal_quantile(0.025), -z, 1e-14));
        assert!(close(normal_quantile(1e-10), -6.361_340_902_404_056, 1e-12));
        assert!(close(
            student_t_quantile(0.975, 1e9),
            z * (1.0 + (z * z + 1.0) / 4e9),
            1e-13
        ));
        assert!(close(
            student_t_quantile(0.975, 2e6),
            z * (1.0 + (z * z + 1.0) / 8e6),
            1e-12
        ));
        // Both sides of the switch to the expansion agree.
        let a = student_t_quantile(0.999, 1e6);
        let b = student_t_quantile(0.999, 1e6 + 1.0);
        assert!(close(a, b, 1e-9), "{a} {b}");
    }

    #[test]
    fn degenerate_arguments_give_nan_not_panics() {
        for (p, df) in [
            (0.0, 3.0),
            (1.0, 3.0),
            (-0.1, 3.0),
            (f64::NAN, 3.0),
            (0.5, 0.0),
            (0.9, -1.0),
        ] {
            assert!(student_t_quantile(p, df).is_nan(), "{p} {df}");
        }
        assert_eq!(student_t_quantile(0.5, 7.0), 0.0);
        assert!(student_t_quantile(1.0 - 1e-16, 3.0).is_finite());
        assert!(student_t_quantile(0.999_999, 0.1) > 1e10);
        assert!(t_critical(0.999_999_999, 1.0).is_finite());
    }

    #[test]
    fn welford_matches_the_two_pass_formula() {
        let xs = [1e9 + 4.0, 1e9 + 7.0, 1e9 + 13.0, 1e9 + 16.0];
        let mut w = Welford::default();
        xs.iter().for_each(|&x| w.push(x));
        assert_eq!(w.mean, 1e9 + 10.0);
        assert!(close(w.variance(), 30.0, 1e-12));
    }

    proptest::proptest! {
        #[test]
        fn t_quantile_inverts_the_tail(p in 0.5001f64..0.99999, df in 1.0f64..500.0) {
            let t = student_t_quantile(p, df);
            let tail = t_tail(t, df);
            proptest::prop_assert!((tail - (1.0 - p)).abs() <= 1e-10 * (1.0 - p), "p {} df {} t {} tail {}", p, df, t, tail);
        }

        #[test]
        fn t_quantile_is_monotone_in_df(p in 0.51f64..0.9999, df in 1.0f64..1e5) {
            proptest::prop_assert!(student_t_quantile(p, df) >= student_t_quantile(p, df * 1.5) - 1e-12);
        }
    }
}
