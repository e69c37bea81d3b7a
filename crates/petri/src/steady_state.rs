//! Balance equations of a CTMC: the stationary distribution `π Q = 0, Σπ = 1`
//! of an irreducible chain, and the non-singular systems `x (−Q_TT) = b` met
//! when absorbing the transient part of a non-ergodic chain.
//!
//! Both are written per state `j` as *outflow = inflow (+ source)*:
//! `exit_j · x_j = Σ_{i≠j} x_i q_ij (+ b_j)`. The chain is given by its
//! incoming entries per state, which is what Gauss–Seidel needs.
//!
//! Methods:
//! * **direct**: below ~160 states, GTH elimination (no subtractions, so
//!   every probability is accurate to rounding even when rates span many
//!   orders of magnitude, as in the supervisor net; its back substitution
//!   rescales instead of overflowing when they are very far apart); above,
//!   sparse LU of the
//!   system with one equation replaced by fixing `x_k = 1` (then normalised)
//!   — any principal submatrix of an irreducible generator is non-singular,
//!   so this is exact and needs no dense normalisation row. `O(fill-in)`
//!   time and memory, and the fill-in of GSPN state spaces (many places,
//!   hence many dimensions) grows fast: for small chains.
//! * **BiCGSTAB** preconditioned by a Gauss–Seidel sweep, for larger chains
//!   (the default above [`SolveParams::direct_limit`] states): see
//!   [`crate::krylov`].
//! * **Gauss–Seidel / SOR**: `x_j ← (1−ω) x_j + ω (inflow_j + b_j) / exit_j`
//!   in state order, normalised after each sweep; `O(nnz)` per sweep and no
//!   extra memory. Stops when the relative residual is at most the tolerance.
//!   Slower than BiCGSTAB on most chains (3–4× on the FMS family), and SOR
//!   with ω > 1 can diverge; offered for comparison and for absorption
//!   systems.
//!
//! [`Method::Auto`] picks direct for small chains (and larger ones whose LU
//! stays cheap), BiCGSTAB otherwise. Measured against it on Kanban 2–6 and
//! not chosen automatically (`EXPERIMENTS.md`, `BENCHMARKS.md`): GMRES(m)
//! with the same preconditioner (more products than BiCGSTAB even without
//! restarts, stagnates when restarted), and SOR, which at ω = 1.2 took
//! fewer passes over the matrix than BiCGSTAB on Kanban 4 and 5 but is
//! erratic in ω and diverges from ω = 1.3.
//!
//! Residual: `‖x Q (+ b)‖₁ / Σ_j exit_j x_j` — the total flow imbalance over
//! the total flow, independent of the time unit and of the number of states.

use std::time::Instant;

use crate::error::{Error, Result};
pub(crate) use crate::interrupt::SOLVING;
use crate::interrupt::{Interrupt, Stage};
use crate::krylov::{self, Stopping};
use crate::linear;
use crate::rows::Chain;
#[cfg(test)]
use crate::rows::Rows;
pub(crate) use crate::rows::most_probable;

/// How to solve the balance equations.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// Direct up to [`SolveParams::direct_limit`] states, BiCGSTAB above.
    #[default]
    Auto,
    /// GTH elimination (tiny chains) or sparse LU.
    Direct,
    /// Gauss–Seidel, over-relaxed by [`SolveParams::omega`].
    GaussSeidel,
    /// BiCGSTAB preconditioned by a Gauss–Seidel sweep (see [`crate::krylov`]).
    Bicgstab,
}

/// Solver settings.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct SolveParams {
    /// Method; default [`Method::Auto`].
    pub method: Method,
    /// Relative residual at which an iterative solve stops. Default 1e-12.
    pub tolerance: f64,
    /// Sweeps before an iterative solve gives up. Default 100,000.
    pub max_iterations: usize,
    /// Relaxation factor ω of SOR in (0, 2); 1 is Gauss–Seidel. Default 1.
    pub omega: f64,
    /// Largest chain that [`Method::Auto`] solves directly. Default 2,000:
    /// the sparse LU's fill-in grows fast on the high-dimensional state
    /// spaces of GSPNs (Kanban N = 2, 4,600 states: 0.27 s against 6 ms for
    /// BiCGSTAB; FMS N = 4, 35,910 states: 218 s against 0.08 s — see
    /// `BENCHMARKS.md`).
    pub direct_limit: usize,
}

impl Default for SolveParams {
    fn default() -> Self {
        SolveParams {
            method: Method::Auto,
            tolerance: 1e-12,
            max_iterations: 100_000,
            omega: 1.0,
            direct_limit: 2_000,
        }
    }
}

impl SolveParams {
    fn stopping(&self) -> Stopping {
        Stopping {
            tolerance: self.tolerance,
            max_iterations: self.max_iterations,
        }
    }

    pub(crate) fn validate(&self) -> Result<()> {
        let bad = |what: &'static str, requirement: &'static str, value: f64| {
            Err(Error::InvalidValue {
                element: "the solver settings".into(),
                what,
                requirement,
                value,
            })
        };
        if !(self.tolerance > 0.0 && self.tolerance < 1.0) {
            return bad("the tolerance", "in (0, 1)", self.tolerance);
        }
        if !(self.omega > 0.0 && self.omega < 2.0) {
            return bad("ω", "in (0, 2)", self.omega);
        }
        if self.max_iterations == 0 {
            return bad("the iteration limit", "≥ 1", 0.0);
        }
        Ok(())
    }
}

/// What a solve did.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct SolveInfo {
    /// `"direct-gth"`, `"direct-lu"`, `"bicgstab"`, `"gauss-seidel"`, `"sor"` or `"trivial"`.
    pub method: &'static str,
    /// Sweeps done (0 for direct solves).
    pub iterations: usize,
    /// Relative residual (see the module docs).
    pub residual: f64,
    /// Wall-clock seconds.
    pub seconds: f64,
    /// Heap bytes of the vectors the method held at once besides the chain
    /// (BiCGSTAB: 7 vectors of `n` doubles; Gauss–Seidel: 1; the direct
    /// methods' factorisations are not counted). The exit rates and the
    /// dictionary's values, which every method reads, are counted by
    /// [`crate::CompiledGspn::memory_account`].
    pub vector_bytes: u64,
}

/// Largest residual accepted from a direct solve before falling back.
const DIRECT_ACCEPT: f64 = 1e-9;

/// Whether a sparse LU of the chain is cheap: the lower envelope of the
/// matrix in its numbering (BFS order) bounds the fill-in a banded
/// elimination would create, and its squares the work. COLAMD, which faer
/// uses, does at least as well in practice.
fn lu_is_cheap(rows: &Chain<'_>) -> bool {
    let n = rows.n();
    let (mut envelope, mut work) = (0f64, 0f64);
    for j in 0..n {
        let (a, b) = rows.incoming.range(j);
        let lowest = rows.incoming.index[a..b]
            .first()
            .map_or(j, |&i| (i as usize).min(j));
        let e = (j - lowest) as f64;
        envelope += e;
        work += e * e;
        if envelope > 2e7 || work > 2e9 {
            return false;
        }
    }
    true
}

/// Relative residual of `x` (see the module docs); `rhs` is `b` or none for
/// the stationary equations.
pub(crate) fn residual(rows: &Chain<'_>, x: &[f64], rhs: Option<&[f64]>) -> f64 {
    rows.residual(x, rhs)
}

/// Solves the stationary equations of an irreducible chain (`rhs = None`)
/// or `exit·x − inflow(x) = b` (`rhs = Some(b)`).
pub(crate) fn solve(
    rows: &Chain<'_>,
    rhs: Option<&[f64]>,
    params: &SolveParams,
    stop: Interrupt<'_>,
) -> Result<(Vec<f64>, SolveInfo)> {
    params.validate()?;
    stop.check(SOLVING)?;
    stop.stage(Stage::Solving);
    let start = Instant::now();
    let n = rows.n();
    if n == 0 {
        return Ok((Vec::new(), SolveInfo::default()));
    }
    if let Some(j) = (0..n).find(|&j| !(rows.exit(j) > 0.0 && rows.exit(j).is_finite())) {
        if rhs.is_none() && n == 1 {
            return Ok((
                vec![1.0],
                SolveInfo {
                    method: "trivial",
                    ..SolveInfo::default()
                },
            ));
        }
        return Err(Error::Singular {
            what: "the balance equations",
            detail: format!(
                "state {j} has exit rate {} in a chain that should not absorb",
                rows.exit(j)
            ),
        });
    }
    if rhs.is_none() && n == 1 {
        return Ok((
            vec![1.0],
            SolveInfo {
                method: "trivial",
                ..SolveInfo::default()
            },
        ));
    }
    let method = match params.method {
        // Small chains, and larger ones whose LU stays cheap (narrow
        // envelope in the BFS numbering, e.g. nearly one-dimensional chains
        // on which Krylov methods crawl), are solved directly.
        Method::Auto if n <= params.direct_limit || lu_is_cheap(rows) => Method::Direct,
        // Absorption systems (rhs given): our BiCGSTAB is built for the
        // stationary equations, so large ones use Gauss–Seidel, small ones LU
        // (Gauss–Seidel can crawl on stiff transient cycles).
        Method::Bicgstab if rhs.is_some() && n <= params.direct_limit => Method::Direct,
        Method::Auto | Method::Bicgstab if rhs.is_some() => Method::GaussSeidel,
        Method::Auto => Method::Bicgstab,
        m => m,
    };
    let (x, name, iterations) = match method {
        Method::Bicgstab => {
            let (x, it) = krylov::bicgstab(rows, params.stopping(), stop)?;
            (x, "bicgstab", it)
        }
        Method::Direct if rhs.is_none() && n <= linear::DENSE_LIMIT => (gth(rows)?, "direct-gth", 0),
        Method::Direct => (solve_direct(rows, rhs)?, "direct-lu", 0),
        _ => {
            let (x, it) = gauss_seidel(rows, rhs, params, stop)?;
            (
                x,
                if params.omega == 1.0 {
                    "gauss-seidel"
                } else {
                    "sor"
                },
                it,
            )
        }
    };
    let residual_now = residual(rows, &x, rhs);
    // A direct solve is checked like an iterative one: LU loses accuracy on
    // badly conditioned chains, and a wrong answer must not pass silently.
    if name == "direct-lu" && residual_now > DIRECT_ACCEPT.max(params.tolerance) {
        if params.method == Method::Auto && rhs.is_none() {
            let (x, it) = krylov::bicgstab(rows, params.stopping(), stop)?;
            let r = residual(rows, &x, rhs);
            return Ok((
                x,
                SolveInfo {
                    method: "bicgstab",
                    iterations: it,
                    residual: r,
                    seconds: start.elapsed().as_secs_f64(),
                    vector_bytes: krylov::bicgstab_bytes(n),
                },
            ));
        }
        return Err(Error::Singular {
            what: "the balance equations",
            detail: format!(
                "sparse LU is inaccurate on this chain (residual {residual_now:.2e}); use an iterative method"
            ),
        });
    }
    Ok((
        x,
        SolveInfo {
            method: name,
            iterations,
            residual: residual_now,
            seconds: start.elapsed().as_secs_f64(),
            vector_bytes: match name {
                "bicgstab" => krylov::bicgstab_bytes(n),
                "gauss-seidel" | "sor" => 8 * n as u64,
                _ => 0,
            },
        },
    ))
}

/// Grassmann–Taksar–Heyman elimination (dense, `O(n³)`): Gaussian
/// elimination on the rates in which every pivot is a sum of positive rates,
/// so no subtraction ever happens and each probability is accurate to a few
/// ulps relative, whatever the spread of the rates (Grassmann, Taksar &
/// Heyman 1985; Stewart 1994 §2.7).
fn gth(rows: &Chain<'_>) -> Result<Vec<f64>> {
    let n = rows.n();
    let mut q = vec![0.0f64; n * n];
    for j in 0..n {
        rows.for_each_in(j, &mut |i, v| {
            if i != j {
                q[i * n + j] += v;
            }
        });
    }
    let mut pivot = vec![0.0; n];
    for k in (1..n).rev() {
        let s: f64 = q[k * n..k * n + k].iter().sum();
        if !(s > 0.0 && s.is_finite()) {
            return Err(Error::Singular {
                what: "the steady-state equations",
                detail: format!("state {k} cannot reach the states before it (reducible chain?)"),
            });
        }
        pivot[k] = s;
        for i in 0..k {
            let f = q[i * n + k] / s;
            if f != 0.0 {
                for j in 0..k {
                    q[i * n + j] += f * q[k * n + j];
                }
            }
        }
    }
    // Back substitution, `x_k = Σ_{i<k} x_i q_ik / pivot_k` from `x_0 = 1`.
    // With rates far apart the unnormalised `x` grows like their ratio to
    // the power of the chain's depth and would overflow (then ∞/∞ = NaN):
    // whenever `x_k` would pass [`GTH_RESCALE`], the earlier entries are
    // multiplied by `pivot_k / s_k` and `x_k` set to 1 — the same vector up
    // to a common factor, one rounding per entry and rescaling; what falls
    // below the smallest double then is below it relative to the largest
    // probability too.
    let mut x = vec![0.0; n];
    x[0] = 1.0;
    for k in 1..n {
        let s: f64 = (0..k).map(|i| x[i] * q[i * n + k]).sum();
        let xk = s / pivot[k];
        if xk <= GTH_RESCALE {
            x[k] = xk;
        } else {
            for v in &mut x[..k] {
                *v = *v * pivot[k] / s;
            }
            x[k] = 1.0;
        }
    }
    let sum: f64 = x.iter().sum();
    x.iter_mut().for_each(|v| *v /= sum);
    Ok(x)
}

/// Largest unnormalised probability GTH's back substitution lets grow
/// before rescaling: far from overflow even after summing `n` terms.
const GTH_RESCALE: f64 = 1e100;

/// The most probable state after `sweeps` Gauss–Seidel sweeps from the
/// uniform distribution (a cheap guess for the state to pin).
pub(crate) fn probable_state(rows: &Chain<'_>, sweeps: usize) -> usize {
    let n = rows.n();
    let mut x = vec![1.0 / n as f64; n];
    for _ in 0..sweeps {
        for j in 0..n {
            x[j] = rows.inflow(j, &x) / rows.exit(j);
        }
    }
    most_probable(&x)
}

fn solve_direct(rows: &Chain<'_>, rhs: Option<&[f64]>) -> Result<Vec<f64>> {
    let n = rows.n();
    let mut triplets: Vec<(u32, u32, f64)> = Vec::new();
    match rhs {
        Some(b) => {
            for j in 0..n {
                triplets.push((j as u32, j as u32, rows.exit(j)));
                rows.for_each_in(j, &mut |i, v| triplets.push((j as u32, i as u32, -v)));
            }
            let mut sol = vec![b.to_vec()];
            linear::solve("the absorption equations", n, &triplets, &mut sol)?;
            let mut x = sol.pop().unwrap_or_default();
            x.iter_mut().for_each(|v| *v = v.max(0.0));
            Ok(x)
        }
        None => {
            // Fix x_k = 1 for a probable state k (a few Gauss–Seidel sweeps
            // tell): pinning an improbable one loses all accuracy.
            let k = probable_state(rows, 5);
            let local = |i: usize| if i < k { i } else { i - 1 };
            let mut b = vec![0.0; n - 1];
            for j in (0..n).filter(|&j| j != k) {
                let lj = local(j) as u32;
                triplets.push((lj, lj, rows.exit(j)));
                rows.for_each_in(j, &mut |i, v| {
                    if i == k {
                        b[lj as usize] += v;
                    } else {
                        triplets.push((lj, local(i) as u32, -v));
                    }
                });
            }
            let mut sol = vec![b];
            linear::solve("the steady-state equations", n - 1, &triplets, &mut sol)?;
            let mut x = sol.pop().unwrap_or_default();
            x.insert(k, 1.0);
            x.iter_mut().for_each(|v| *v = v.max(0.0));
            let sum: f64 = x.iter().sum();
            if !(sum.is_finite() && sum > 0.0) {
                return Err(Error::Singular {
                    what: "the steady-state equations",
                    detail: format!("the solution sums to {sum}"),
                });
            }
            x.iter_mut().for_each(|v| *v /= sum);
            Ok(x)
        }
    }
}

fn gauss_seidel(
    rows: &Chain<'_>,
    rhs: Option<&[f64]>,
    params: &SolveParams,
    stop: Interrupt<'_>,
) -> Result<(Vec<f64>, usize)> {
    let n = rows.n();
    let omega = params.omega;
    let mut x = match rhs {
        None => vec![1.0 / n as f64; n],
        Some(b) => (0..n).map(|j| b[j] / rows.exit(j)).collect(),
    };
    let mut last = f64::INFINITY;
    let mut swept = 0;
    for it in 1..=params.max_iterations {
        swept = it;
        stop.check(SOLVING)?;
        let (mut imbalance, mut flow) = (0.0f64, 0.0f64);
        for j in 0..n {
            let d = rows.exit(j);
            let s = rows.inflow(j, &x) + rhs.map_or(0.0, |b| b[j]);
            let old = x[j];
            imbalance += (s - d * old).abs();
            let new = s / d;
            x[j] = if omega == 1.0 {
                new
            } else {
                old + omega * (new - old)
            };
            flow += d * x[j];
        }
        if rhs.is_none() {
            let sum: f64 = x.iter().sum();
            if !(sum.is_finite() && sum > 0.0) {
                break;
            }
            x.iter_mut().for_each(|v| *v /= sum);
            flow /= sum;
            imbalance /= sum;
        }
        let proxy = if flow > 0.0 { imbalance / flow } else { imbalance };
        stop.iterated(it, proxy);
        if proxy <= params.tolerance {
            last = residual(rows, &x, rhs);
            if last <= params.tolerance {
                return Ok((x, it));
            }
        } else {
            last = proxy;
        }
        if !last.is_finite() {
            break;
        }
    }
    Err(Error::NoConvergence {
        solver: if omega == 1.0 { "Gauss-Seidel" } else { "SOR" },
        iterations: swept,
        residual: last,
        tolerance: params.tolerance,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Birth–death chain 0..n with birth λ (value id 0) and death μ (id 1).
    struct Owned {
        rows: Rows,
        values: Vec<f64>,
        exit: Vec<f64>,
    }

    impl Owned {
        fn chain(&self) -> Chain<'_> {
            Chain {
                incoming: &self.rows,
                values: &self.values,
                exit: &self.exit,
            }
        }
    }

    fn birth_death(n: usize, lambda: f64, mu: f64) -> Owned {
        let mut entries = Vec::new();
        let mut exit = vec![0.0; n];
        for (i, e) in exit.iter_mut().enumerate() {
            if i + 1 < n {
                entries.push(((i + 1) as u32, i as u32, 0));
                *e += lambda;
            }
            if i > 0 {
                entries.push(((i - 1) as u32, i as u32, 1));
                *e += mu;
            }
        }
        Owned {
            rows: Rows::from_entries(n, entries, 2),
            values: vec![lambda, mu],
            exit,
        }
    }

    fn closed_form(n: usize, rho: f64) -> Vec<f64> {
        let w: Vec<f64> = (0..n).map(|i| rho.powi(i as i32)).collect();
        let s: f64 = w.iter().sum();
        w.iter().map(|v| v / s).collect()
    }

    #[test]
    fn birth_death_matches_closed_form_with_every_method() {
        for n in [2, 7, 300] {
            let owned = birth_death(n, 1.0, 1.7);
            let rows = owned.chain();
            let exact = closed_form(n, 1.0 / 1.7);
            for method in [Method::Direct, Method::GaussSeidel, Method::Bicgstab] {
                let p = SolveParams {
                    method,
                    ..SolveParams::default()
                };
                let (x, info) = solve(&rows, None, &p, Interrupt::NEVER).unwrap();
                assert!(info.residual <= 1e-12, "{method:?} {n}: {}", info.residual);
                for i in 0..n {
                    // LU is normwise accurate (absolute error ~ ε); iterative to its residual.
                    let tol = match method {
                        Method::Direct => 1e-10 * exact[i] + 1e-14,
                        _ => 1e-10,
                    };
                    assert!(
                        (x[i] - exact[i]).abs() <= tol,
                        "{method:?} {n} {i}: {} vs {}",
                        x[i],
                        exact[i]
                    );
                }
            }
        }
    }

    #[test]
    fn stiff_rates_are_solved_exactly() {
        // Rates 1e-3 next to 1e3, as in the supervisor net.
        let owned = birth_death(4, 1e-3, 1e3);
        let rows = owned.chain();
        let (x, info) = solve(&rows, None, &SolveParams::default(), Interrupt::NEVER).unwrap();
        let exact = closed_form(4, 1e-6);
        for i in 0..4 {
            assert!(
                (x[i] - exact[i]).abs() <= 1e-12 * exact[i].max(1e-30) + 1e-300,
                "{i}"
            );
        }
        assert!(info.residual < 1e-13);
    }

    #[test]
    fn gth_rescales_instead_of_overflowing_on_a_deep_stiff_chain() {
        // π_i ∝ 10^(6 i) over 150 states: unnormalised, 10^894 (∞ before
        // the rescaling, then ∞/∞ = NaN).
        let n = 150;
        let owned = birth_death(n, 1.0, 1e-6);
        let (x, info) = solve(&owned.chain(), None, &SolveParams::default(), Interrupt::NEVER).unwrap();
        assert_eq!(info.method, "direct-gth");
        assert!(x.iter().all(|v| v.is_finite() && *v >= 0.0));
        for j in 0..5 {
            // From the top: 1e-6 per step down (1 − 1e-6 normalisation).
            let exact = (1.0 - 1e-6) * 1e-6f64.powi(j as i32);
            let got = x[n - 1 - j];
            assert!((got - exact).abs() <= 1e-12 * exact, "{j}: {got} vs {exact}");
        }
        assert_eq!(
            x[0], 0.0,
            "10^-894 relative to the top is below the smallest double"
        );
    }

    #[test]
    fn absorption_system() {
        // One transient state with exit 2 and source 1: x = 0.5.
        let owned = Owned {
            rows: Rows::from_entries(1, vec![], 0),
            values: vec![],
            exit: vec![2.0],
        };
        let rows = owned.chain();
        let (x, _) = solve(&rows, Some(&[1.0]), &SolveParams::default(), Interrupt::NEVER).unwrap();
        assert!((x[0] - 0.5).abs() < 1e-15);
    }

    #[test]
    fn gauss_seidel_reports_non_convergence() {
        let owned = birth_death(200, 1.0, 1.0001);
        let rows = owned.chain();
        let p = SolveParams {
            method: Method::GaussSeidel,
            max_iterations: 3,
            ..SolveParams::default()
        };
        assert!(matches!(
            solve(&rows, None, &p, Interrupt::NEVER),
            Err(Error::NoConvergence { .. })
        ));
        let bad = SolveParams {
            omega: 2.5,
            ..SolveParams::default()
        };
        assert!(solve(&rows, None, &bad, Interrupt::NEVER).is_err());
    }
}
