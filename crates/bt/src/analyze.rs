//! Quantifying a tree: the probability that it succeeds, fails or never
//! ends; the mean time to its end (overall, and of the runs that succeed or
//! fail) and the quantiles of that time; each leaf's share of the failures;
//! how long each node is active; and the sensitivity of P(success) and of
//! the mean time to every leaf's parameters.
//!
//! The tree is translated to a GSPN ([`crate::translate`]), its CTMC compiled
//! once and solved as an absorbing chain ([`petri::absorption`]). A leaf's
//! *share of the failures* is the probability that the timed event ending a
//! failed run is that leaf's failure (or its condition's change, or its
//! timer), over P(failure); instantaneous leaves that fail in the same
//! instant as an earlier event are not separated from it, and failures at
//! time 0 are reported apart. Sensitivities are forward differences:
//! durations and change rates re-solve the compiled chain with scaled rates;
//! so does an action's `p_success` when its last stage draws the outcome
//! (one mean time: success and failure rates in the ratio p : 1 − p, the
//! same chain for p + δ), and a persistent condition's `p_true` (its change
//! rates and the weights of its first draw, re-weighting the initial
//! distribution); other probabilities re-translate and re-compile the tree.

use std::collections::BTreeMap;

use petri::{CompiledGspn, ExploreParams, Gspn, Params};
use rayon::prelude::*;
use serde::Serialize;

use crate::error::{Error, Result};
use crate::params::TreeParams;
use crate::translate::{RateRole, Translation, Trigger, translate};
use crate::tree::{Kind, NodeId, Tree};

/// How to analyse.
#[derive(Debug, Clone)]
pub struct AnalyzeOptions {
    /// Quantiles of the time to the end (of the runs that end), e.g. 0.5, 0.9, 0.99.
    pub quantiles: Vec<f64>,
    /// Compute the sensitivities (one re-solve or re-compilation per parameter).
    pub sensitivities: bool,
    /// Largest state space (markings, tangible and vanishing); default 2,000,000.
    pub max_states: usize,
}

impl Default for AnalyzeOptions {
    fn default() -> Self {
        AnalyzeOptions {
            quantiles: vec![0.5, 0.9, 0.99],
            sensitivities: true,
            max_states: 2_000_000,
        }
    }
}

/// Per node: how active it is and how much it fails the tree.
#[derive(Debug, Clone, Serialize)]
pub struct NodeStat {
    /// The node.
    pub node: NodeId,
    /// Its path.
    pub path: String,
    /// `Type(name)`.
    pub label: String,
    /// Expected time it is active per run, seconds.
    pub active_time: f64,
    /// `active_time` over the mean run time: the probability of finding it
    /// active at a random instant of a run.
    pub activity: f64,
    /// Share of the tree's failures ended by an event of its subtree.
    pub failure_share: f64,
}

/// The sensitivity of the results to one parameter of one key.
#[derive(Debug, Clone, Serialize)]
pub struct Sensitivity {
    /// The sidecar key (`name`, else type).
    pub key: String,
    /// `p_success`, `mean_time`, `p_true`, `change_rate` or `mean_interval`.
    pub parameter: String,
    /// Its current value.
    pub value: f64,
    /// ∂P(success)/∂parameter.
    pub d_p_success: f64,
    /// ∂(mean time)/∂parameter, seconds per unit.
    pub d_mean_time: f64,
}

/// What `analyze` finds.
#[derive(Debug, Clone, Serialize)]
pub struct Report {
    /// The tree's main `ID`.
    pub tree: String,
    /// P(the root returns SUCCESS).
    pub p_success: f64,
    /// P(the root returns FAILURE).
    pub p_failure: f64,
    /// P(the run never ends: a loop with no way out).
    pub p_never: f64,
    /// Mean time to the end (of the runs that end), seconds.
    pub mean_time: f64,
    /// Mean time of the runs that succeed (0 if none).
    pub mean_time_success: f64,
    /// Mean time of the runs that fail (0 if none).
    pub mean_time_failure: f64,
    /// `(q, t)`: the runs that end do so by `t` with probability `q`.
    pub quantiles: Vec<(f64, f64)>,
    /// Probability of failing at time 0 (before any timed event).
    pub failure_at_start: f64,
    /// Every node, in tree order.
    pub nodes: Vec<NodeStat>,
    /// Sensitivities, largest |∂P(success)| first.
    pub sensitivities: Vec<Sensitivity>,
    /// Net size: places, transitions.
    pub net_size: (usize, usize),
    /// Tangible states of the CTMC.
    pub states: usize,
    /// Sidecar keys that name no node.
    pub unused_params: Vec<String>,
}

/// The compiled chain of a tree for one set of probabilities.
struct Solved {
    tr: Translation,
    compiled: CompiledGspn,
    rates: Vec<f64>,
    /// Bottom component → 1 success, 0 failure, 2 never ends.
    ends: Vec<u8>,
}

/// The CTMC of a translated tree, as `analyze` solves it (forced zero-time
/// hops passed through, at most `max_states` markings), and the rate of
/// every transition.
pub fn chain(tr: &Translation, max_states: usize) -> Result<(CompiledGspn, Vec<f64>)> {
    let gspn: Gspn = tr.net.instantiate(&Params::new())?;
    let explore = ExploreParams {
        max_states,
        skip_forced: true,
        forced_context: tr.world(),
        ..ExploreParams::default()
    };
    let compiled = CompiledGspn::build(&gspn, &explore).map_err(|e| match e {
        petri::Error::TimelessTrap { .. } => Error::Analysis(format!(
            "the tree loops in zero time (an instantaneous child retried or repeated forever): {e}"
        )),
        e => Error::Petri(e),
    })?;
    let rates = gspn.rates(&Params::new(), None)?;
    Ok((compiled, rates))
}

fn compile(tree: &Tree, params: &TreeParams, options: &AnalyzeOptions) -> Result<Solved> {
    let tr = translate(tree, params)?;
    let (compiled, rates) = chain(&tr, options.max_states)?;
    let ends = compiled
        .bottom_components()
        .iter()
        .map(|b| {
            let m = compiled.tangible_marking(b[0] as usize);
            if m[tr.done_ok.index()] > 0 {
                1
            } else if m[tr.done_ko.index()] > 0 {
                0
            } else {
                2
            }
        })
        .collect();
    Ok(Solved {
        tr,
        compiled,
        rates,
        ends,
    })
}

/// The chain's transient part with `rates` bound (for the absorption and
/// the quantiles both).
fn absorbing<'a>(s: &'a Solved, rates: &[f64]) -> Result<petri::Absorbing<'a>> {
    if s.compiled.is_ergodic() {
        return Err(Error::Analysis(
            "the tree never ends: its net has no end marking reachable (a loop with no way out)".into(),
        ));
    }
    Ok(s.compiled.absorbing(rates)?)
}

/// P(success), P(failure), P(never), mean time, and the absorption itself
/// (from the chain's initial distribution, or from `initial`).
fn outcome(
    s: &Solved,
    chain: &petri::Absorbing,
    initial: Option<&[(u32, f64)]>,
) -> Result<(f64, f64, f64, f64, petri::Absorption)> {
    let a = match initial {
        None => chain.absorption(),
        Some(initial) => chain.absorption_from(initial),
    };
    let a = a.map_err(|e| match e {
        petri::Error::Singular { .. } => Error::Analysis(format!(
            "some state of the run cannot reach an end (a loop with no way out): {e}"
        )),
        e => Error::Petri(e),
    })?;
    let mut p = [0.0; 3];
    for (b, &kind) in s.ends.iter().enumerate() {
        p[kind as usize] += a.end_probability[b];
    }
    Ok((p[1], p[0], p[2], a.mean_time, a))
}

/// Analyses `tree` with `params`.
pub fn analyze(tree: &Tree, params: &TreeParams, options: &AnalyzeOptions) -> Result<Report> {
    let s = compile(tree, params, options)?;
    let chain = absorbing(&s, &s.rates)?;
    let (p_success, p_failure, p_never, mean_time, a) = outcome(&s, &chain, None)?;
    let mean_of = |kind: u8| -> f64 {
        let (mut num, mut den) = (0.0, 0.0);
        for (b, &k) in s.ends.iter().enumerate() {
            if k == kind {
                num += a.mean_time_to[b] * a.end_probability[b];
                den += a.end_probability[b];
            }
        }
        if den > 0.0 { num / den } else { 0.0 }
    };
    let blame = failure_blame(&s, &a);
    let attributed: f64 = blame.values().sum();
    let nodes = node_stats(tree, &s, &a, mean_time, &blame, p_failure);
    let quantiles = quantiles(&s, &chain, &options.quantiles, mean_time, 1.0 - p_never)?;
    let sensitivities = if options.sensitivities {
        sensitivities(tree, params, options, &s, p_success, mean_time)?
    } else {
        Vec::new()
    };
    Ok(Report {
        tree: tree.main.clone(),
        p_success,
        p_failure,
        p_never,
        mean_time,
        mean_time_success: mean_of(1),
        mean_time_failure: mean_of(0),
        quantiles,
        failure_at_start: (p_failure - attributed).max(0.0),
        nodes,
        sensitivities,
        net_size: (s.tr.net.places.len(), s.tr.net.transitions.len()),
        states: s.compiled.num_tangible(),
        unused_params: params.unused_keys(tree),
    })
}

/// Probability mass of failures by the node whose timed event ended them.
fn failure_blame(s: &Solved, a: &petri::Absorption) -> BTreeMap<NodeId, f64> {
    let mut blame = BTreeMap::new();
    for (b, &kind) in s.ends.iter().enumerate() {
        if kind != 0 {
            continue;
        }
        for &(t, p) in &a.entered_by[b] {
            let node = match s.tr.triggers[t.index()] {
                Some(Trigger::Success { node })
                | Some(Trigger::Failure { node })
                | Some(Trigger::Change { node })
                | Some(Trigger::Timer { node }) => Some(node),
                _ => s.tr.roles[t.index()].map(|(n, _)| n),
            };
            if let Some(n) = node {
                *blame.entry(n).or_insert(0.0) += p;
            }
        }
    }
    blame
}

fn node_stats(
    tree: &Tree,
    s: &Solved,
    a: &petri::Absorption,
    mean_time: f64,
    blame: &BTreeMap<NodeId, f64>,
    p_failure: f64,
) -> Vec<NodeStat> {
    // Per place, the nodes active while it is marked; per state, each node
    // counted once (`seen`) over its marked places.
    let mut nodes_of = vec![Vec::new(); s.tr.net.places.len()];
    for (n, places) in s.tr.activity.iter().enumerate() {
        for p in places {
            nodes_of[p.index()].push(n);
        }
    }
    let mut active = vec![0.0; tree.len()];
    let mut seen = vec![usize::MAX; tree.len()];
    let mut m = vec![0; s.tr.net.places.len()];
    for (st, &x) in a.sojourn.iter().enumerate() {
        if x <= 0.0 {
            continue;
        }
        s.compiled.tangible_marking_into(st, &mut m);
        for (p, _) in m.iter().enumerate().filter(|(_, c)| **c > 0) {
            for &n in &nodes_of[p] {
                if seen[n] != st {
                    seen[n] = st;
                    active[n] += x;
                }
            }
        }
    }
    tree.preorder()
        .into_iter()
        .map(|n| {
            let share: f64 = tree.preorder_from(n).iter().filter_map(|m| blame.get(m)).sum();
            NodeStat {
                node: n,
                path: tree.node(n).path.clone(),
                label: tree.node(n).label(),
                active_time: active[n.index()],
                activity: if mean_time > 0.0 {
                    active[n.index()] / mean_time
                } else {
                    0.0
                },
                failure_share: if p_failure > 0.0 { share / p_failure } else { 0.0 },
            }
        })
        .collect()
}

/// Times by which the runs that end have ended with probability `qs`,
/// from the survival function of a shift-and-invert Krylov space
/// ([`petri::survival`]: shift a quarter of the mean time, grown until two
/// sizes agree on the quantiles to 10⁻⁹), each time read off by bisection; a quantile
/// beyond 20 mean times is reported as 20 mean times. Should the space not
/// settle, the distribution on a Crank–Nicolson grid serves instead.
fn quantiles(
    s: &Solved,
    chain: &petri::Absorbing,
    qs: &[f64],
    mean_time: f64,
    p_end: f64,
) -> Result<Vec<(f64, f64)>> {
    if qs.is_empty() || mean_time <= 0.0 || p_end <= 0.0 {
        return Ok(qs.iter().map(|&q| (q, 0.0)).collect());
    }
    let horizon = MEANS as f64 * mean_time;
    if !horizon.is_finite() {
        return Err(Error::Analysis(format!(
            "the mean time to the end is {mean_time:e} s, too long to compute its quantiles ({MEANS} mean times overflow): are the leaves' times in seconds?"
        )));
    }
    let levels: Vec<f64> = qs.iter().map(|&q| 1.0 - q.min(1.0) * p_end).collect();
    match chain.survival(0.25 * mean_time, horizon, &levels, 1e-9) {
        Ok(survival) => Ok(qs
            .iter()
            .zip(survival.times())
            .map(|(&q, t)| (q, t.unwrap_or(horizon)))
            .collect()),
        Err(petri::Error::NoConvergence { .. }) => quantiles_on_grid(s, qs, mean_time, p_end),
        Err(e) => Err(e.into()),
    }
}

/// A quantile beyond this many mean times is reported as this many.
const MEANS: usize = 20;

/// The quantiles read off the distribution on a grid of 25 steps per mean
/// time (Crank–Nicolson, [`petri::CompiledGspn::absorption_cdf_steps`]) up
/// to the largest quantile or 20 mean times, by linear interpolation.
fn quantiles_on_grid(s: &Solved, qs: &[f64], mean_time: f64, p_end: f64) -> Result<Vec<(f64, f64)>> {
    const STEPS_PER_MEAN: usize = 25;
    let h = mean_time / STEPS_PER_MEAN as f64;
    let top = qs.iter().copied().fold(0.0, f64::max).min(1.0);
    let cdf: Vec<f64> = s
        .compiled
        .absorption_cdf_steps(&s.rates, h, STEPS_PER_MEAN * MEANS, top * p_end)?
        .into_iter()
        .map(|p| (p / p_end).min(1.0))
        .collect();
    let t_max = h * (cdf.len() - 1) as f64;
    Ok(qs
        .iter()
        .map(|&q| {
            let t = match cdf.iter().position(|&v| v >= q) {
                Some(0) => 0.0,
                Some(k) => {
                    let (a, b) = (cdf[k - 1], cdf[k]);
                    let f = if b > a { (q - a) / (b - a) } else { 1.0 };
                    h * ((k - 1) as f64 + f)
                }
                None => t_max,
            };
            (q, t)
        })
        .collect())
}

/// Distinct sidecar keys of the leaves (and periodic decorators), in tree order.
fn keys(tree: &Tree, params: &TreeParams) -> Vec<(String, NodeId)> {
    let mut seen = std::collections::BTreeSet::new();
    let mut out = Vec::new();
    for n in tree.preorder() {
        let node = tree.node(n);
        let key = match node.kind {
            Kind::Action => node.param_key().to_string(),
            Kind::Condition | Kind::Gate => params.condition_key(tree, n),
            _ => continue,
        };
        if seen.insert(key.clone()) {
            out.push((key, n));
        }
    }
    out
}

fn sensitivities(
    tree: &Tree,
    params: &TreeParams,
    options: &AnalyzeOptions,
    s: &Solved,
    p0: f64,
    t0: f64,
) -> Result<Vec<Sensitivity>> {
    let no_sens = AnalyzeOptions {
        sensitivities: false,
        ..options.clone()
    };
    // Every key is independent of the others: its re-solve and its
    // re-compilation run in parallel, collected in key order (the same
    // report for any number of threads).
    let per_key: Vec<Vec<Sensitivity>> = keys(tree, params)
        .into_par_iter()
        .map(|kn| key_sensitivities(tree, params, &no_sens, s, (p0, t0), kn))
        .collect::<Result<_>>()?;
    let mut out: Vec<Sensitivity> = per_key.into_iter().flatten().collect();
    out.sort_by(|a, b| b.d_p_success.abs().total_cmp(&a.d_p_success.abs()));
    Ok(out)
}

/// The sensitivities to one key's parameters: its rate (a re-solve of the
/// compiled chain) and its probability (a re-compilation).
fn key_sensitivities(
    tree: &Tree,
    params: &TreeParams,
    no_sens: &AnalyzeOptions,
    s: &Solved,
    (p0, t0): (f64, f64),
    (key, n): (String, NodeId),
) -> Result<Vec<Sensitivity>> {
    let mut out = Vec::new();
    let is_action = matches!(tree.node(n).kind, Kind::Action);
    // Rates: scale the key's transitions and re-solve the same chain.
    let role = if is_action {
        RateRole::Duration
    } else {
        RateRole::Change
    };
    let (name, value) = if is_action {
        let a = params.action(tree, n);
        ("mean_time", 0.5 * (a.mean_time_success + a.mean_time_failure))
    } else {
        ("change_rate", params.condition(tree, n).change_rate)
    };
    let touched: Vec<usize> =
        s.tr.roles
            .iter()
            .enumerate()
            .filter(|(_, r)| {
                r.is_some_and(|(m, rr)| {
                    rr == role
                        && (if is_action {
                            tree.node(m).param_key() == key
                        } else {
                            params.condition_key(tree, m) == key
                        })
                })
            })
            .map(|(t, _)| t)
            .collect();
    if !touched.is_empty() && value > 0.0 {
        let h = 1e-4;
        let mut rates = s.rates.clone();
        for &t in &touched {
            // A duration scaled by (1 + h) divides its rates; a change rate multiplies them.
            rates[t] = if is_action {
                rates[t] / (1.0 + h)
            } else {
                rates[t] * (1.0 + h)
            };
        }
        let (p, _, _, t, _) = outcome(s, &absorbing(s, &rates)?, None)?;
        out.push(Sensitivity {
            key: key.clone(),
            parameter: name.into(),
            value,
            d_p_success: (p - p0) / (h * value),
            d_mean_time: (t - t0) / (h * value),
        });
    }
    // Probabilities: re-translate, or — where the probability is a ratio of
    // rates — re-solve.
    let (pname, pvalue) = if is_action {
        ("p_success", params.action(tree, n).p_success)
    } else {
        ("p_true", params.condition(tree, n).p_true)
    };
    let h = if pvalue + 1e-4 <= 1.0 { 1e-4 } else { -1e-4 };
    // The parameters a re-translation would use; where they move only
    // rates (and initial weights) of the same chain, a re-solve.
    let mut shifted = params.clone();
    if is_action {
        let mut a = params.action(tree, n);
        a.p_success += h;
        shifted.actions.insert(key.clone(), a);
    } else {
        let mut c = params.condition(tree, n);
        c.p_true += h;
        shifted.conditions.insert(key.clone(), c);
    }
    let moved = if is_action {
        outcome_as_rates(tree, params, &shifted, s).map(|r| (r, None))
    } else {
        condition_as_rates(tree, params, &shifted, s, &key).map(|(r, i)| (r, Some(i)))
    };
    let (p, t) = match moved {
        Some((rates, initial)) => {
            let (p, _, _, t, _) = outcome(s, &absorbing(s, &rates)?, initial.as_deref())?;
            (p, t)
        }
        None => {
            let s2 = compile(tree, &shifted, no_sens)?;
            let (p, _, _, t, _) = outcome(&s2, &absorbing(&s2, &s2.rates)?, None)?;
            (p, t)
        }
    };
    out.push(Sensitivity {
        key,
        parameter: pname.into(),
        value: pvalue,
        d_p_success: (p - p0) / h,
        d_mean_time: (t - t0) / h,
    });
    Ok(out)
}

/// The rates of the translation of `shifted` (an action's `p_success`
/// moved), when that is a change of rates alone: every action whose
/// parameters move keeps one mean time and its outcome drawn by the last
/// stage (success and failure at rates in the ratio p : 1 − p, `translate`),
/// `p` strictly between 0 and 1 before and after — the same chain, so a
/// re-solve instead of a re-translation and re-compilation. `None`
/// otherwise.
fn outcome_as_rates(tree: &Tree, params: &TreeParams, shifted: &TreeParams, s: &Solved) -> Option<Vec<f64>> {
    let drawn_last = |a: &crate::params::ActionParams| {
        a.mean_time_success > 0.0
            && a.mean_time_failure == a.mean_time_success
            && 0.0 < a.p_success
            && a.p_success < 1.0
    };
    // Per moved action, the scale of its success and failure rates.
    let mut scale = BTreeMap::new();
    for m in tree.preorder() {
        if !matches!(tree.node(m).kind, Kind::Action) {
            continue;
        }
        let (a, b) = (params.action(tree, m), shifted.action(tree, m));
        if a == b {
            continue;
        }
        let same_times = (a.mean_time_success, a.phases) == (b.mean_time_success, b.phases);
        if !(drawn_last(&a) && drawn_last(&b) && same_times) {
            return None;
        }
        let (p, q) = (a.p_success, b.p_success);
        scale.insert(m, (q / p, (1.0 - q) / (1.0 - p)));
    }
    if scale.is_empty() {
        return None;
    }
    let mut rates = s.rates.clone();
    for (t, r) in rates.iter_mut().enumerate() {
        let (m, success) = match (s.tr.roles[t], s.tr.triggers[t]) {
            (Some((m, RateRole::Duration)), Some(Trigger::Success { node })) if node == m => (m, true),
            (Some((m, RateRole::Duration)), Some(Trigger::Failure { node })) if node == m => (m, false),
            _ => continue,
        };
        if let Some(&(up, down)) = scale.get(&m) {
            *r *= if success { up } else { down };
        }
    }
    Some(rates)
}

/// An initial distribution over a chain's tangible states:
/// `(state, probability)`.
type Initial = Vec<(u32, f64)>;

/// The rates and the initial distribution of the translation of `shifted`
/// (condition `key`'s `p_true` moved), when that changes rates and initial
/// weights alone: the conditions whose parameters move are exactly those
/// reading `key`'s state, a persistent one (a change rate) moved from `p` to
/// `q`, both strictly between 0 and 1. Its changes' rates are
/// `change_rate·(1 − p)` to false and `change_rate·p` to true, and its first
/// value is drawn before anything else with weights `p` and `1 − p`, so
/// every initial state where it holds is re-weighted by `q/p` and every
/// other by `(1 − q)/(1 − p)`: the same chain, a re-solve. `None` otherwise.
fn condition_as_rates(
    tree: &Tree,
    params: &TreeParams,
    shifted: &TreeParams,
    s: &Solved,
    key: &str,
) -> Option<(Vec<f64>, Initial)> {
    let net = s.tr.conditions.get(key)?;
    let mut moved = None;
    for m in tree.preorder() {
        if !matches!(tree.node(m).kind, Kind::Condition | Kind::Gate) {
            continue;
        }
        let (a, b) = (params.condition(tree, m), shifted.condition(tree, m));
        let reads_key = params.condition_key(tree, m) == key;
        if reads_key != (a != b) || (a != b && !matches!(tree.node(m).kind, Kind::Condition)) {
            return None;
        }
        if a != b {
            if moved.is_some_and(|x| x != (a, b)) {
                return None;
            }
            moved = Some((a, b));
        }
    }
    let (a, b) = moved?;
    let (p, q) = (a.p_true, b.p_true);
    let persistent = a.change_rate > 0.0 && b.change_rate == a.change_rate;
    if !(persistent && 0.0 < p.min(q) && p.max(q) < 1.0) {
        return None;
    }
    let (up, down) = (q / p, (1.0 - q) / (1.0 - p));
    let mut rates = s.rates.clone();
    for (t, scale) in [(net.to_false?, down), (net.to_true?, up)] {
        rates[t.index()] *= scale;
    }
    let initial = s
        .compiled
        .initial_distribution()
        .iter()
        .map(|&(st, w)| {
            let m = s.compiled.tangible_marking(st as usize);
            let holds = m[net.holds.index()] > 0;
            (st, w * if holds { up } else { down })
        })
        .collect();
    Some((rates, initial))
}

/// The GSPN of a tree, for `--dot` and for other tools.
pub fn net_of(tree: &Tree, params: &TreeParams) -> Result<petri::Net> {
    Ok(translate(tree, params)?.net)
}
