//! Rates per context, shrunk towards the building's where a context has few
//! observations: the estimator the crediting supervisor learns with
//! ([`super::credit_learning`]).
//!
//! A **context** is a route (a leg between two named places; a log of one
//! route has one) × a crowd context (quiet, busy, crowded). A kind of rate —
//! a behaviour's progress speed, its failures while localized, the
//! localizer leaving Success… — is observed per behaviour `b` (AutoMove,
//! contour tracking), route `ℓ` and crowd context `c` as a count `n` (events,
//! or metres of progress) over an exposure `t` (seconds). Each level is a
//! gamma–Poisson estimate whose prior mean is the level above, fitted to
//! the data (empirical Bayes, as in Clayton and Kaldor's rates for small
//! areas, *Biometrics* 43, 1987), with a prior worth `w` observations:
//!
//! 1. **Building**, per behaviour and crowd context, pooled over routes: the
//!    main-effects model `μ_bc = a_b · g_c` ([`main_effects`]), with the
//!    model file's rate as `w` pseudo-observations per behaviour — the
//!    crowd acts alike on both behaviours until their own data say
//!    otherwise.
//! 2. **Route**, per behaviour: a route effect
//!    `ρ_bℓ = (n_bℓ + w) / (Σ_c t_bℓc μ_bc + w)`, its counts over what the
//!    building's rates predict for its exposures — 1 until the route has
//!    data, the route's own ratio once it has many.
//! 3. **Context**: `λ_bℓc = (n_bℓc + w) / (t_bℓc + w / (ρ_bℓ μ_bc))`.
//!
//! A context never seen takes `ρ_bℓ μ_bc`, a route never seen `μ_bc`; one
//! with many observations its own rate. `w` is one observation's worth:
//! one event for events, one traversal of the route (its reference length
//! in metres) for progress. Nothing learnt is 0, infinite or NaN when the
//! prior rates are finite and > 0.

use std::collections::BTreeMap;

/// Number of crowd contexts (quiet, busy, crowded).
pub const CONTEXTS: usize = 3;

/// Time exposed and events (fractional: shared failures; metres for
/// progress).
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct Exposure {
    /// Seconds.
    pub time_s: f64,
    /// Events.
    pub events: f64,
}

impl Exposure {
    /// Adds another's time and events.
    pub fn add(&mut self, other: &Exposure) {
        self.time_s += other.time_s;
        self.events += other.events;
    }

    /// `(events + 1) / (time + 1/prior)`: one pseudo-event at `prior`.
    pub fn rate(&self, prior: f64) -> f64 {
        self.rate_with(prior, 1.0)
    }

    /// `(events + w) / (time + w/prior)`: `w` pseudo-events at `prior`.
    pub fn rate_with(&self, prior: f64, w: f64) -> f64 {
        (self.events + w) / (self.time_s + w / prior)
    }
}

/// Per behaviour (AutoMove, contour tracking) and crowd context.
pub type Cells = [[Exposure; CONTEXTS]; 2];

/// One kind of rate, observed per route, behaviour and crowd context.
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize)]
pub struct RouteTable {
    /// By route name (`""` for a log of one route).
    pub routes: BTreeMap<String, Cells>,
}

impl RouteTable {
    /// Adds `events` over `time_s` to a cell.
    pub fn add(&mut self, route: &str, behaviour: usize, context: usize, events: f64, time_s: f64) {
        let cells = self.routes.entry(route.to_string()).or_default();
        let e = &mut cells[behaviour.min(1)][context.min(CONTEXTS - 1)];
        e.events += events;
        e.time_s += time_s;
    }

    /// The cells of `route` (empty ones when it has none).
    pub fn route(&self, route: &str) -> Cells {
        self.routes.get(route).copied().unwrap_or_default()
    }

    /// All routes together.
    pub fn pooled(&self) -> Cells {
        let mut out = Cells::default();
        for cells in self.routes.values() {
            for (o, c) in out.iter_mut().zip(cells) {
                for (o, c) in o.iter_mut().zip(c) {
                    o.add(c);
                }
            }
        }
        out
    }
}

/// A rate at each level for one behaviour, route and crowd context
/// (module docs), for the logs.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Shrunk {
    /// The building's, `μ_bc`.
    pub building: f64,
    /// The route effect `ρ_bℓ`.
    pub route_effect: f64,
    /// The context's, `λ_bℓc`: the rate used.
    pub rate: f64,
}

/// The shrunk rate of behaviour `b` on `route` in crowd context `c`
/// (module docs): `prior` the model's pseudo-observations per behaviour at
/// the building level, `(count, exposure)` (both > 0: the prior rate is
/// their ratio), `w` one observation's worth (a count) at the route and
/// context levels.
pub fn shrink(table: &RouteTable, prior: [(f64, f64); 2], route: &str, b: usize, c: usize, w: f64) -> Shrunk {
    let (b, c) = (b.min(1), c.min(CONTEXTS - 1));
    let pooled = table.pooled();
    let field = |cells: &Cells, f: fn(&Exposure) -> f64| -> [[f64; CONTEXTS]; 2] {
        std::array::from_fn(|b| std::array::from_fn(|c| f(&cells[b][c])))
    };
    let mu = main_effects(field(&pooled, |e| e.events), field(&pooled, |e| e.time_s), prior);
    let cells = table.route(route);
    let expected: f64 = (0..CONTEXTS).map(|k| cells[b][k].time_s * mu[b][k]).sum();
    let observed: f64 = (0..CONTEXTS).map(|k| cells[b][k].events).sum();
    let route_effect = (observed + w) / (expected + w);
    let building = mu[b][c];
    Shrunk {
        building,
        route_effect,
        rate: cells[b][c].rate_with(route_effect * building, w),
    }
}

/// The main-effects (multiplicative) model of a rate measured per
/// behaviour `b` (AutoMove, contour) and crowd context `c`:
/// `μ_bc = a_b · g_c`, fitted to the counts `n` (events, or metres of
/// progress) over the exposures `t` (seconds) by iterative proportional
/// fitting — the maximum-likelihood log-linear Poisson model with a
/// behaviour and a context effect and no interaction (Bishop, Fienberg
/// and Holland, *Discrete Multivariate Analysis*, ch. 3). Each
/// behaviour's `pseudo = (count, exposure)` is spread evenly over the
/// contexts first, so that every margin is positive and a table without
/// data gives `μ_bc = count / exposure`, the prior. 60 sweeps of a 2 × 3
/// table: microseconds.
pub fn main_effects(
    n: [[f64; CONTEXTS]; 2],
    t: [[f64; CONTEXTS]; 2],
    pseudo: [(f64, f64); 2],
) -> [[f64; CONTEXTS]; 2] {
    let share = CONTEXTS as f64;
    let n: [[f64; CONTEXTS]; 2] = std::array::from_fn(|b| n[b].map(|x| x + pseudo[b].0 / share));
    let t: [[f64; CONTEXTS]; 2] = std::array::from_fn(|b| t[b].map(|x| x + pseudo[b].1 / share));
    let mut a = [1.0; 2];
    let mut g = [1.0; CONTEXTS];
    for _ in 0..60 {
        for b in 0..2 {
            let exposure: f64 = (0..CONTEXTS).map(|c| t[b][c] * g[c]).sum();
            a[b] = n[b].iter().sum::<f64>() / exposure;
        }
        for c in 0..CONTEXTS {
            let exposure: f64 = (0..2).map(|b| t[b][c] * a[b]).sum();
            g[c] = (n[0][c] + n[1][c]) / exposure;
        }
    }
    std::array::from_fn(|b| std::array::from_fn(|c| a[b] * g[c]))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Speeds of 0.4 and 0.25 m/s, worth one metre each.
    const PRIOR: [(f64, f64); 2] = [(1.0, 2.5), (1.0, 4.0)];

    #[test]
    fn the_main_effects_model_fits_a_multiplicative_table_exactly() {
        // Rates a_b · g_c with a = (0.01, 0.04), g = (1, 2, 5): the fit
        // returns them whatever the exposures.
        let rate = |b: usize, c: usize| [0.01, 0.04][b] * [1.0, 2.0, 5.0][c];
        let t = [[100.0, 50.0, 10.0], [30.0, 300.0, 7.0]];
        let n = std::array::from_fn(|b| std::array::from_fn(|c| rate(b, c) * t[b][c]));
        let mu = main_effects(n, t, [(0.0, 0.0), (0.0, 0.0)]);
        for (b, row) in mu.iter().enumerate() {
            for (c, m) in row.iter().enumerate() {
                assert!((m / rate(b, c) - 1.0).abs() < 1e-9, "{b} {c}: {m}");
            }
        }
        // No data: the prior.
        let mu = main_effects(
            [[0.0; CONTEXTS]; 2],
            [[0.0; CONTEXTS]; 2],
            [(1.0, 1000.0), (1.0, 250.0)],
        );
        for (auto, cont) in mu[0].iter().zip(&mu[1]) {
            assert!((auto - 0.001).abs() < 1e-15 && (cont - 0.004).abs() < 1e-15);
        }
    }

    #[test]
    fn without_data_every_level_is_the_prior() {
        let t = RouteTable::default();
        let s = shrink(&t, PRIOR, "a → b", 1, 2, 30.0);
        assert!((s.building - 0.25).abs() < 1e-12 && s.route_effect == 1.0);
        assert!((s.rate - 0.25).abs() < 1e-12, "{s:?}");
    }

    #[test]
    fn a_route_where_a_behaviour_is_fast_keeps_its_speed_and_lends_none_to_the_others() {
        // Contour tracking: 0.2 m/s on three routes, 1.0 m/s on the door
        // route; AutoMove 0.4 m/s everywhere; all quiet, many traversals.
        let mut t = RouteTable::default();
        for (route, v) in [("r1", 0.2), ("r2", 0.2), ("r3", 0.2), ("door", 1.0)] {
            for _ in 0..5 {
                t.add(route, 1, 0, 30.0, 30.0 / v);
                t.add(route, 0, 0, 30.0, 30.0 / 0.4);
            }
        }
        let door = shrink(&t, PRIOR, "door", 1, 0, 30.0);
        assert!((door.rate - 1.0).abs() < 0.15, "{door:?}");
        assert!(door.route_effect > 2.0, "{door:?}");
        let r1 = shrink(&t, PRIOR, "r1", 1, 0, 30.0);
        assert!((r1.rate - 0.2).abs() < 0.03, "{r1:?}");
        // A route never driven: the building's contour speed, between.
        let new = shrink(&t, PRIOR, "new", 1, 0, 30.0);
        assert!(
            new.route_effect == 1.0 && new.rate > 0.2 && new.rate < 0.4,
            "{new:?}"
        );
        // The crowd never seen on the door route: the route effect times
        // the building's crowded rate — faster than the building, slower
        // than the route's own quiet data (the route effect is shrunk).
        let crowded = shrink(&t, PRIOR, "door", 1, 2, 30.0);
        assert!((crowded.rate - crowded.route_effect * crowded.building).abs() < 1e-12);
        assert!(
            crowded.rate > 2.0 * crowded.building && crowded.rate < door.rate,
            "{crowded:?} {door:?}"
        );
    }

    #[test]
    fn the_crowd_learnt_from_one_behaviour_reaches_the_other_on_every_route() {
        // AutoMove twice as slow in crowds on r1; contour never in a crowd.
        let mut t = RouteTable::default();
        for _ in 0..10 {
            t.add("r1", 0, 0, 30.0, 60.0);
            t.add("r1", 0, 2, 30.0, 120.0);
            t.add("r1", 1, 0, 30.0, 100.0);
            t.add("r2", 1, 0, 30.0, 30.0);
        }
        let quiet = shrink(&t, PRIOR, "r2", 1, 0, 30.0);
        let crowded = shrink(&t, PRIOR, "r2", 1, 2, 30.0);
        let ratio = crowded.rate / quiet.rate;
        assert!(ratio > 0.45 && ratio < 0.65, "{ratio}");
    }
}
