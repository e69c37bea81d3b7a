//! A net instantiated for analysis: every marking, multiplicity, priority and
//! weight is a number; rates stay expressions so that they can be re-bound
//! without rebuilding anything (see [`CompiledGspn`](crate::CompiledGspn)).
//!
//! This module also holds the firing rule, shared by the state-space
//! generator, the simulator and the property checks.

pub(crate) mod enabling;
pub mod policy;

use std::collections::{BTreeMap, BTreeSet};

use std::sync::Arc;

use crate::error::{Error, Result};
use crate::expr::Expr;
use crate::net::{ArcKind, Label, Net, Params, PlaceId, RewardModel, Servers, TransitionId, TransitionKind};
use policy::{Action, Policy};

/// Timing of an instantiated transition.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Timing {
    /// Exponential delay; the rate is bound separately.
    Timed {
        /// Server semantics.
        servers: Servers,
    },
    /// Zero delay.
    Immediate {
        /// Priority level ≥ 1.
        priority: u32,
        /// Weight > 0.
        weight: f64,
    },
}

/// Kind of a marking under GSPN semantics.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MarkingKind {
    /// Some immediate transition is enabled: left in zero time.
    Vanishing,
    /// Only timed transitions (or none) are enabled.
    Tangible,
}

/// Compressed row storage of `(place, value)` pairs per transition.
#[derive(Debug, Clone, Default)]
struct PerTransition<V> {
    start: Vec<u32>,
    items: Vec<(u32, V)>,
}

impl<V: Copy> PerTransition<V> {
    fn from_lists(lists: Vec<Vec<(u32, V)>>) -> Self {
        let mut start = Vec::with_capacity(lists.len() + 1);
        let mut items = Vec::new();
        start.push(0);
        for l in lists {
            items.extend(l);
            start.push(items.len() as u32);
        }
        PerTransition { start, items }
    }

    #[inline]
    fn of(&self, t: usize) -> &[(u32, V)] {
        &self.items[self.start[t] as usize..self.start[t + 1] as usize]
    }
}

/// A GSPN ready for analysis. Build one with [`Gspn::new`] (or
/// [`Net::instantiate`]).
#[derive(Debug, Clone)]
pub struct Gspn {
    name: String,
    place_names: Vec<String>,
    transition_names: Vec<String>,
    initial: Vec<u32>,
    capacity: Vec<Option<u32>>,
    timing: Vec<Timing>,
    rate_exprs: Vec<Option<Expr>>,
    params: BTreeMap<String, Option<f64>>,
    structural_params: BTreeMap<String, String>,
    inputs: PerTransition<u32>,
    outputs: PerTransition<u32>,
    inhibitors: PerTransition<u32>,
    delta: PerTransition<i64>,
    /// Whether each transition is a decision.
    decision: Vec<bool>,
    /// Whether any is.
    has_decisions: bool,
    labels: Vec<Label>,
    rewards: Vec<RewardModel>,
    /// What to choose in the choice markings ([`Gspn::with_policy`]).
    policy: Option<Arc<Policy>>,
    /// The candidates of the firing rule ([`Gspn::firable`]).
    candidates: Candidates,
}

/// Which transitions may be enabled in a marking: each transition with
/// input arcs is listed under one of its input places (the one with the
/// fewest consumers), so only the lists of marked places need testing;
/// transitions without input arcs are always candidates.
#[derive(Debug, Clone, Default)]
struct Candidates {
    /// `start[p]..start[p + 1]` in `keyed`: the transitions keyed on place `p`.
    start: Vec<u32>,
    keyed: Vec<TransitionId>,
    sourceless: Vec<TransitionId>,
}

impl Candidates {
    fn new(num_places: usize, inputs: &PerTransition<u32>, num_transitions: usize) -> Candidates {
        let mut consumers = vec![0u32; num_places];
        for &(p, _) in &inputs.items {
            consumers[p as usize] += 1;
        }
        let mut lists = vec![Vec::new(); num_places];
        let mut sourceless = Vec::new();
        for t in 0..num_transitions {
            let tid = TransitionId(t as u32);
            match inputs
                .of(t)
                .iter()
                .min_by_key(|&&(p, _)| (consumers[p as usize], p))
            {
                Some(&(p, _)) => lists[p as usize].push(tid),
                None => sourceless.push(tid),
            }
        }
        let mut start = Vec::with_capacity(num_places + 1);
        let mut keyed = Vec::new();
        start.push(0);
        for l in lists {
            keyed.extend(l);
            start.push(keyed.len() as u32);
        }
        Candidates {
            start,
            keyed,
            sourceless,
        }
    }

    /// Collects into `out`, in transition order, every transition that
    /// might be enabled in `m`.
    #[inline]
    fn collect(&self, m: &[u32], out: &mut Vec<TransitionId>) {
        out.clear();
        out.extend_from_slice(&self.sourceless);
        for (p, &k) in m.iter().enumerate() {
            if k > 0 {
                out.extend_from_slice(&self.keyed[self.start[p] as usize..self.start[p + 1] as usize]);
            }
        }
        out.sort_unstable();
    }
}

impl Net {
    /// Instantiates the net with parameter `overrides` (see [`Gspn::new`]).
    pub fn instantiate(&self, overrides: &Params) -> Result<Gspn> {
        Gspn::new(self, overrides)
    }
}

fn whole(v: f64, element: String, what: &'static str, min: f64) -> Result<u32> {
    if !v.is_finite() || v < min || v != v.trunc() || v > f64::from(u32::MAX) {
        return Err(Error::InvalidValue {
            element,
            what,
            requirement: if min > 0.0 {
                "a whole number ≥ 1"
            } else {
                "a whole number ≥ 0"
            },
            value: v,
        });
    }
    Ok(v as u32)
}

/// Evaluates a structural expression (marking, multiplicity, priority,
/// weight) in a context ("the initial marking of place `P`").
type EvalStructural<'a> = dyn FnMut(&Expr, String) -> Result<f64> + 'a;

/// Each transition's timing (servers, or priority and weight, checked) and
/// rate expression (`None` for immediate ones).
fn timings(net: &Net, eval_structural: &mut EvalStructural<'_>) -> Result<(Vec<Timing>, Vec<Option<Expr>>)> {
    let nt = net.transitions.len();
    let mut timing = Vec::with_capacity(nt);
    let mut rate_exprs = Vec::with_capacity(nt);
    for t in &net.transitions {
        match &t.kind {
            TransitionKind::Timed { rate, servers } => {
                if let Servers::K(0) = servers {
                    return Err(Error::InvalidValue {
                        element: format!("transition `{}`", t.name),
                        what: "the number of servers",
                        requirement: "≥ 1",
                        value: 0.0,
                    });
                }
                if let Some(r) = rate {
                    if r.uses_tokens() {
                        return Err(Error::Eval {
                            text: r.to_string(),
                            context: format!("the rate of transition `{}`", t.name),
                            message: "marking-dependent rates are not supported; use server semantics (nservers) instead".into(),
                        });
                    }
                }
                timing.push(Timing::Timed { servers: *servers });
                rate_exprs.push(rate.clone());
            }
            TransitionKind::Immediate { weight, priority } => {
                let pr = eval_structural(priority, format!("the priority of transition `{}`", t.name))?;
                let pr = whole(pr, format!("transition `{}`", t.name), "the priority", 1.0)?;
                let w = eval_structural(weight, format!("the weight of transition `{}`", t.name))?;
                if !(w.is_finite() && w > 0.0) {
                    return Err(Error::InvalidValue {
                        element: format!("immediate transition `{}`", t.name),
                        what: "the weight",
                        requirement: "a finite number > 0 (leave a branch of weight 0 out of the net)",
                        value: w,
                    });
                }
                timing.push(Timing::Immediate {
                    priority: pr,
                    weight: w,
                });
                rate_exprs.push(None);
            }
        }
    }
    Ok((timing, rate_exprs))
}

/// The arcs' multiplicities, merged per (transition, kind, place): input
/// and output multiplicities add up, parallel inhibitor arcs keep the
/// smallest.
fn merged_arcs(
    net: &Net,
    eval_structural: &mut EvalStructural<'_>,
) -> Result<BTreeMap<(u32, ArcKind, u32), u32>> {
    let mut merged: BTreeMap<(u32, ArcKind, u32), u32> = BTreeMap::new();
    for a in &net.arcs {
        let ctx = format!(
            "the multiplicity of the {} arc between `{}` and `{}`",
            a.kind.name(),
            net.places[a.place.index()].name,
            net.transitions[a.transition.index()].name
        );
        let v = eval_structural(&a.multiplicity, ctx.clone())?;
        let m = whole(v, ctx, "the value", 1.0)?;
        let key = (a.transition.0, a.kind, a.place.0);
        match merged.get_mut(&key) {
            None => {
                merged.insert(key, m);
            }
            Some(old) if a.kind == ArcKind::Inhibitor => *old = (*old).min(m),
            Some(old) => {
                *old = old.checked_add(m).ok_or_else(|| Error::InvalidValue {
                    element: format!(
                        "the parallel {} arcs between `{}` and `{}`",
                        a.kind.name(),
                        net.places[a.place.index()].name,
                        net.transitions[a.transition.index()].name
                    ),
                    what: "the total multiplicity",
                    requirement: "at most 4294967295",
                    value: f64::from(*old) + f64::from(m),
                })?
            }
        }
    }
    Ok(merged)
}

/// Each transition's change of the marking, `outputs − inputs`, per place
/// in place order, zeros left out.
fn token_deltas(ins: &[Vec<(u32, u32)>], outs: &[Vec<(u32, u32)>]) -> Vec<Vec<(u32, i64)>> {
    ins.iter()
        .zip(outs)
        .map(|(ins, outs)| {
            let mut d: BTreeMap<u32, i64> = BTreeMap::new();
            for &(p, m) in ins {
                *d.entry(p).or_default() -= i64::from(m);
            }
            for &(p, m) in outs {
                *d.entry(p).or_default() += i64::from(m);
            }
            d.into_iter().filter(|&(_, v)| v != 0).collect()
        })
        .collect()
}

impl Gspn {
    /// Binds the parameters (the net's own values, replaced by `overrides`)
    /// and checks everything that does not depend on rates: markings and
    /// multiplicities are whole numbers, priorities ≥ 1, weights > 0.
    pub fn new(net: &Net, overrides: &Params) -> Result<Gspn> {
        net.validate()?;
        let params = net.resolve_params(overrides)?;
        let mut structural_params = BTreeMap::new();
        let mut eval_structural = |e: &Expr, context: String| -> Result<f64> {
            let mut missing = None;
            e.for_each_param(&mut |n| {
                structural_params
                    .entry(n.to_string())
                    .or_insert_with(|| context.clone());
                if missing.is_none() && !matches!(params.get(n), Some(Some(_))) {
                    missing = Some(n.to_string());
                }
            });
            if let Some(name) = missing {
                return Err(unbound(net, &name, &context));
            }
            e.eval_params(&|n| params.get(n).copied().flatten(), &context)
        };

        let mut initial = Vec::with_capacity(net.places.len());
        for p in &net.places {
            let ctx = format!("the initial marking of place `{}`", p.name);
            let v = eval_structural(&p.initial, ctx.clone())?;
            initial.push(whole(
                v,
                format!("place `{}`", p.name),
                "the initial marking",
                0.0,
            )?);
        }

        let (timing, rate_exprs) = timings(net, &mut eval_structural)?;
        let merged = merged_arcs(net, &mut eval_structural)?;
        let nt = net.transitions.len();
        let mut ins = vec![Vec::new(); nt];
        let mut outs = vec![Vec::new(); nt];
        let mut inhs = vec![Vec::new(); nt];
        for (&(t, kind, p), &m) in &merged {
            let list = match kind {
                ArcKind::Input => &mut ins,
                ArcKind::Output => &mut outs,
                ArcKind::Inhibitor => &mut inhs,
            };
            list[t as usize].push((p, m));
        }
        let deltas = token_deltas(&ins, &outs);
        let inputs = PerTransition::from_lists(ins);
        let candidates = Candidates::new(net.places.len(), &inputs, nt);

        Ok(Gspn {
            name: net.name.clone(),
            place_names: net.places.iter().map(|p| p.name.clone()).collect(),
            transition_names: net.transitions.iter().map(|t| t.name.clone()).collect(),
            initial,
            capacity: net.places.iter().map(|p| p.capacity).collect(),
            timing,
            rate_exprs,
            params,
            structural_params,
            inputs,
            outputs: PerTransition::from_lists(outs),
            inhibitors: PerTransition::from_lists(inhs),
            delta: PerTransition::from_lists(deltas),
            decision: net.transitions.iter().map(|t| t.decision).collect(),
            has_decisions: net.has_decisions(),
            labels: net.labels.clone(),
            rewards: net.rewards.clone(),
            policy: None,
            candidates,
        })
    }

    /// The model's name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Number of places.
    pub fn num_places(&self) -> usize {
        self.place_names.len()
    }

    /// Number of transitions.
    pub fn num_transitions(&self) -> usize {
        self.transition_names.len()
    }

    /// Place names, by [`PlaceId`].
    pub fn place_names(&self) -> &[String] {
        &self.place_names
    }

    /// Transition names, by [`TransitionId`].
    pub fn transition_names(&self) -> &[String] {
        &self.transition_names
    }

    /// The place called `name`.
    pub fn place(&self, name: &str) -> Result<PlaceId> {
        self.place_names
            .iter()
            .position(|n| n == name)
            .map(|i| PlaceId(i as u32))
            .ok_or_else(|| Error::UnknownName {
                kind: "place",
                name: name.into(),
            })
    }

    /// The transition called `name`.
    pub fn transition(&self, name: &str) -> Result<TransitionId> {
        self.transition_names
            .iter()
            .position(|n| n == name)
            .map(|i| TransitionId(i as u32))
            .ok_or_else(|| Error::UnknownName {
                kind: "transition",
                name: name.into(),
            })
    }

    /// The initial marking.
    pub fn initial_marking(&self) -> &[u32] {
        &self.initial
    }

    /// The capacity of each place, if any.
    pub fn capacities(&self) -> &[Option<u32>] {
        &self.capacity
    }

    /// Timing of transition `t`.
    pub fn timing(&self, t: TransitionId) -> Timing {
        self.timing[t.index()]
    }

    /// Input checks of a solve with `rates` (one per transition, as
    /// [`Gspn::rates`] gives them): as many as the transitions, a finite
    /// number > 0 for every timed one (immediate transitions' entries are
    /// not checked here).
    pub fn check_rates(&self, rates: &[f64]) -> Result<()> {
        if rates.len() != self.num_transitions() {
            return Err(Error::Invalid(format!(
                "{} rates given for {} transitions",
                rates.len(),
                self.num_transitions()
            )));
        }
        for (t, &r) in rates.iter().enumerate() {
            if !(self.is_immediate(TransitionId(t as u32)) || (r.is_finite() && r > 0.0)) {
                return Err(Error::InvalidValue {
                    element: format!("timed transition `{}`", self.transition_names()[t]),
                    what: "the rate",
                    requirement: "a finite number > 0",
                    value: r,
                });
            }
        }
        Ok(())
    }

    /// Whether `t` is immediate.
    pub fn is_immediate(&self, t: TransitionId) -> bool {
        matches!(self.timing[t.index()], Timing::Immediate { .. })
    }

    /// Number of immediate transitions.
    pub fn num_immediate(&self) -> usize {
        self.timing
            .iter()
            .filter(|t| matches!(t, Timing::Immediate { .. }))
            .count()
    }

    /// Input arcs of `t` as `(place index, multiplicity)`.
    #[inline]
    pub fn inputs(&self, t: TransitionId) -> &[(u32, u32)] {
        self.inputs.of(t.index())
    }

    /// Output arcs of `t` as `(place index, multiplicity)`.
    #[inline]
    pub fn outputs(&self, t: TransitionId) -> &[(u32, u32)] {
        self.outputs.of(t.index())
    }

    /// Inhibitor arcs of `t` as `(place index, multiplicity)`.
    #[inline]
    pub fn inhibitors(&self, t: TransitionId) -> &[(u32, u32)] {
        self.inhibitors.of(t.index())
    }

    /// Token change caused by firing `t`, as `(place index, change)`, zero
    /// changes left out.
    #[inline]
    pub fn delta(&self, t: TransitionId) -> &[(u32, i64)] {
        self.delta.of(t.index())
    }

    /// Bound parameter values (`None`: declared without value, unused).
    pub fn params(&self) -> &BTreeMap<String, Option<f64>> {
        &self.params
    }

    /// Parameters that fix the structure (markings, multiplicities,
    /// priorities, weights), with the first thing each one determines.
    pub fn structural_params(&self) -> &BTreeMap<String, String> {
        &self.structural_params
    }

    /// The rate expression of a timed transition, if it has one.
    pub fn rate_expr(&self, t: TransitionId) -> Option<&Expr> {
        self.rate_exprs[t.index()].as_ref()
    }

    /// The weight of an immediate transition (`None` for timed ones).
    pub fn weight(&self, t: TransitionId) -> Option<f64> {
        match self.timing[t.index()] {
            Timing::Immediate { weight, .. } => Some(weight),
            Timing::Timed { .. } => None,
        }
    }

    /// Evaluates every timed transition's rate with the bound parameters,
    /// replaced by `overrides`. `default_rate` is used for transitions that
    /// have no rate. Immediate transitions get 0. Fails if `overrides` would
    /// change a structural parameter.
    pub fn rates(&self, overrides: &Params, default_rate: Option<f64>) -> Result<Vec<f64>> {
        let mut values = self.params.clone();
        for (name, v) in &overrides.0 {
            match values.get_mut(name) {
                None => {
                    return Err(Error::UnknownParameter {
                        name: name.clone(),
                        known: values.keys().cloned().collect::<Vec<_>>().join(", "),
                    });
                }
                Some(slot) => {
                    if let Some(what) = self.structural_params.get(name) {
                        if *slot != Some(*v) {
                            return Err(Error::StructuralParameter {
                                name: name.clone(),
                                what: what.clone(),
                            });
                        }
                    }
                    *slot = Some(*v);
                }
            }
        }
        if let Some(d) = default_rate {
            if !(d.is_finite() && d > 0.0) {
                return Err(Error::InvalidValue {
                    element: "the default rate".into(),
                    what: "the value",
                    requirement: "a finite number > 0",
                    value: d,
                });
            }
        }
        let mut rates = vec![0.0; self.num_transitions()];
        for (t, rate) in rates.iter_mut().enumerate() {
            if self.is_immediate(TransitionId(t as u32)) {
                continue;
            }
            let name = &self.transition_names[t];
            let v = match &self.rate_exprs[t] {
                Some(e) => {
                    let ctx = format!("the rate of transition `{name}`");
                    let mut missing = None;
                    e.for_each_param(&mut |n| {
                        if missing.is_none() && !matches!(values.get(n), Some(Some(_))) {
                            missing = Some(n.to_string());
                        }
                    });
                    if let Some(n) = missing {
                        return Err(Error::UnboundParameter {
                            name: n,
                            used_by: ctx,
                            hint: String::new(),
                        });
                    }
                    e.eval_params(&|n| values.get(n).copied().flatten(), &ctx)?
                }
                None => default_rate.ok_or_else(|| Error::MissingRate {
                    transition: name.clone(),
                })?,
            };
            if !(v.is_finite() && v > 0.0) {
                return Err(Error::InvalidValue {
                    element: format!("timed transition `{name}`"),
                    what: "the rate",
                    requirement: "a finite number > 0",
                    value: v,
                });
            }
            *rate = v;
        }
        Ok(rates)
    }

    /// Whether `t` is enabled in `m` (inputs, inhibitors, capacities;
    /// priorities are not considered here).
    #[inline]
    pub fn is_enabled(&self, t: TransitionId, m: &[u32]) -> bool {
        self.inputs(t).iter().all(|&(p, k)| m[p as usize] >= k)
            && self.inhibitors(t).iter().all(|&(p, k)| m[p as usize] < k)
            && self.capacity_allows(t, m)
    }

    #[inline]
    fn capacity_allows(&self, t: TransitionId, m: &[u32]) -> bool {
        self.delta(t).iter().all(|&(p, d)| {
            d <= 0
                || match self.capacity[p as usize] {
                    None => true,
                    Some(c) => i64::from(m[p as usize]) + d <= i64::from(c),
                }
        })
    }

    /// Enabling degree: how many times `t` could fire concurrently. A
    /// transition without input arcs has degree 1 (so an infinite-server
    /// source behaves as a single server). Markings passed to the firing-rule
    /// methods must have one entry per place of this net.
    #[inline]
    pub fn enabling_degree(&self, t: TransitionId, m: &[u32]) -> u32 {
        self.inputs(t)
            .iter()
            .map(|&(p, k)| m[p as usize] / k)
            .min()
            .unwrap_or(1)
    }

    /// The factor that multiplies `t`'s rate in `m`: 1, `min(degree, k)` or
    /// the degree.
    #[inline]
    pub fn server_factor(&self, t: TransitionId, m: &[u32]) -> f64 {
        match self.timing[t.index()] {
            Timing::Timed {
                servers: Servers::Single,
            }
            | Timing::Immediate { .. } => 1.0,
            Timing::Timed {
                servers: Servers::K(k),
            } => f64::from(self.enabling_degree(t, m).min(k)),
            Timing::Timed {
                servers: Servers::Infinite,
            } => f64::from(self.enabling_degree(t, m)),
        }
    }

    /// Fires `t` in `m` (a marking of this net, which must enable `t`).
    /// Fails, leaving `m` unchanged, if a count would go negative (`t` was
    /// not enabled) or overflow.
    pub fn fire(&self, t: TransitionId, m: &mut [u32]) -> Result<()> {
        for &(p, d) in self.delta(t) {
            let v = i64::from(m[p as usize]) + d;
            if v < 0 {
                return Err(Error::Invalid(format!(
                    "transition `{}` fired while not enabled (place `{}` would go negative)",
                    self.transition_names[t.index()],
                    self.place_names[p as usize]
                )));
            }
            if v > i64::from(u32::MAX) {
                return Err(Error::TokenOverflow {
                    place: self.place_names[p as usize].clone(),
                    limit: u64::from(u32::MAX),
                });
            }
        }
        for &(p, d) in self.delta(t) {
            m[p as usize] = (i64::from(m[p as usize]) + d) as u32;
        }
        Ok(())
    }

    /// Compiles a measure expression (over token counts `#place` and the
    /// net's parameters) for evaluation on this net's markings.
    pub fn compile_expr(&self, expr: &Expr) -> Result<crate::expr::CompiledExpr> {
        expr.compile(&|n| self.place_names.iter().position(|p| p == n), &|n| {
            self.params.get(n).copied().flatten()
        })
    }

    /// Collects into `out` the transitions that may fire in `m` under GSPN
    /// semantics, and says whether `m` is vanishing: if any immediate
    /// transition is enabled, only the enabled immediate transitions of the
    /// highest priority; otherwise all enabled timed transitions. Both in
    /// transition order. Cost: the places, plus the transitions keyed on a
    /// marked place (each transition is keyed on one of its input places).
    pub fn firable(&self, m: &[u32], out: &mut Vec<TransitionId>) -> MarkingKind {
        // Only transitions with a marked input place (or none) can be
        // enabled; they are tested in transition order, filtered in place.
        self.candidates.collect(m, out);
        let mut kept = 0;
        let mut best_priority = 0u32;
        for i in 0..out.len() {
            let tid = out[i];
            if let Timing::Immediate { priority, .. } = self.timing[tid.index()] {
                if priority >= best_priority && self.is_enabled(tid, m) {
                    if priority > best_priority {
                        kept = 0;
                        best_priority = priority;
                    }
                    out[kept] = tid;
                    kept += 1;
                }
            }
        }
        if best_priority > 0 {
            out.truncate(kept);
            return MarkingKind::Vanishing;
        }
        for i in 0..out.len() {
            let tid = out[i];
            if matches!(self.timing[tid.index()], Timing::Timed { .. }) && self.is_enabled(tid, m) {
                out[kept] = tid;
                kept += 1;
            }
        }
        out.truncate(kept);
        MarkingKind::Tangible
    }

    /// Whether the net has decision transitions.
    #[inline]
    pub fn has_decisions(&self) -> bool {
        self.has_decisions
    }

    /// Whether `t` is a decision.
    #[inline]
    pub fn is_decision(&self, t: TransitionId) -> bool {
        self.decision[t.index()]
    }

    /// The net's labels (named marking sets).
    pub fn labels(&self) -> &[Label] {
        &self.labels
    }

    /// The net's reward models.
    pub fn rewards(&self) -> &[RewardModel] {
        &self.rewards
    }

    /// The policy the net runs under, if any ([`Gspn::with_policy`]).
    pub fn policy(&self) -> Option<&Policy> {
        self.policy.as_deref()
    }

    /// This net run under `policy`: in every choice marking it reaches,
    /// the policy's action is taken, so the net is an ordinary GSPN again
    /// and every steady-state measure applies. The policy must name this
    /// net's places and decisions ([`Policy::bind`]).
    pub fn with_policy(&self, mut policy: Policy) -> Result<Gspn> {
        policy.bind(self)?;
        let mut g = self.clone();
        g.policy = Some(Arc::new(policy));
        Ok(g)
    }

    /// Whether the transitions `firable` in a vanishing marking make it a
    /// **choice marking**: at least two decisions, or a decision and a
    /// transition that is not one (docs/gspn.md, *Decisions*).
    pub fn is_choice(&self, firable: &[TransitionId]) -> bool {
        if !self.has_decisions {
            return false;
        }
        let decisions = firable.iter().filter(|t| self.decision[t.index()]).count();
        decisions >= 2 || (decisions == 1 && firable.len() >= 2)
    }

    /// [`firable`](Self::firable), with the choice markings resolved by the
    /// net's policy when it has one: the chosen decision alone, or the
    /// transitions that are not decisions (the random switch). Without a
    /// policy a choice marking keeps every alternative. Nets without
    /// decisions take the plain path. Errors: the policy says nothing about
    /// a choice marking, or names an action that is not available there.
    pub fn firable_resolved(&self, m: &[u32], out: &mut Vec<TransitionId>) -> Result<MarkingKind> {
        let kind = self.firable(m, out);
        self.resolve(m, out, kind)
    }

    /// The choice resolution of [`firable_resolved`](Self::firable_resolved)
    /// applied to `out`, what [`firable`](Self::firable) returned (`kind`)
    /// for `m`.
    pub(crate) fn resolve(
        &self,
        m: &[u32],
        out: &mut Vec<TransitionId>,
        kind: MarkingKind,
    ) -> Result<MarkingKind> {
        if kind == MarkingKind::Tangible || !self.is_choice(out) {
            return Ok(kind);
        }
        let Some(policy) = &self.policy else {
            return Ok(kind);
        };
        match policy.action(m) {
            None => Err(Error::Policy {
                source_name: policy.source_name().to_string(),
                message: format!(
                    "it says nothing about the choice marking [{}] (choices: {})",
                    self.format_marking(m),
                    self.describe_choices(out)
                ),
            }),
            Some(Action::Fire(t)) if out.contains(&t) && self.is_decision(t) => {
                out.clear();
                out.push(t);
                Ok(kind)
            }
            Some(Action::Random) if out.iter().any(|t| !self.is_decision(*t)) => {
                out.retain(|t| !self.decision[t.index()]);
                Ok(kind)
            }
            Some(action) => Err(Error::Policy {
                source_name: policy.source_name().to_string(),
                message: format!(
                    "it chooses {} in marking [{}], which offers only: {}",
                    action.describe(self),
                    self.format_marking(m),
                    self.describe_choices(out)
                ),
            }),
        }
    }

    /// [`firable_resolved`](Self::firable_resolved), failing with
    /// [`Error::Undecided`] on a choice marking that no policy resolves.
    pub fn firable_decided(&self, m: &[u32], out: &mut Vec<TransitionId>) -> Result<MarkingKind> {
        let kind = self.firable_resolved(m, out)?;
        if kind == MarkingKind::Vanishing && self.is_choice(out) {
            return Err(self.undecided(m, out));
        }
        Ok(kind)
    }

    /// The error for the choice marking `m` with its firable transitions.
    pub(crate) fn undecided(&self, m: &[u32], firable: &[TransitionId]) -> Error {
        Error::Undecided {
            marking: self.format_marking(m),
            choices: self.describe_choices(firable),
        }
    }

    /// The actions of a choice marking whose firable transitions are
    /// `firable`: each decision, and `random (…)` over the others.
    pub(crate) fn describe_choices(&self, firable: &[TransitionId]) -> String {
        let names = self.transition_names();
        let mut parts: Vec<String> = firable
            .iter()
            .filter(|t| self.is_decision(**t))
            .map(|t| names[t.index()].clone())
            .collect();
        let random: Vec<&str> = firable
            .iter()
            .filter(|t| !self.is_decision(**t))
            .map(|t| names[t.index()].as_str())
            .collect();
        if !random.is_empty() {
            parts.push(format!("random ({})", random.join(", ")));
        }
        parts.join(", ")
    }

    /// Formats a marking compactly: the marked places, `P3 P7 Q(2)`.
    pub fn format_marking(&self, m: &[u32]) -> String {
        let parts: Vec<String> = m
            .iter()
            .enumerate()
            .filter(|&(_, &k)| k > 0)
            .map(|(p, &k)| {
                if k == 1 {
                    self.place_names[p].clone()
                } else {
                    format!("{}({k})", self.place_names[p])
                }
            })
            .collect();
        if parts.is_empty() {
            "(empty)".into()
        } else {
            parts.join(" ")
        }
    }

    /// Parameters that are declared but have no value.
    pub fn unbound_params(&self) -> BTreeSet<&str> {
        self.params
            .iter()
            .filter(|(_, v)| v.is_none())
            .map(|(k, _)| k.as_str())
            .collect()
    }
}

fn unbound(net: &Net, name: &str, context: &str) -> Error {
    let hint = match net.param(name) {
        None => " (it is not declared in the model either)".to_string(),
        Some(p) => match p.suggested {
            Some(s) => format!(" (the file suggests {name}={})", crate::expr::fmt_number(s)),
            None => String::new(),
        },
    };
    Error::UnboundParameter {
        name: name.into(),
        used_by: context.into(),
        hint,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn small() -> Net {
        let mut n = Net::new("small");
        let a = n.add_place("a", 2u32);
        let b = n.add_place("b", 0u32);
        let t = n.add_timed("t", Expr::param("r"));
        n.set_servers(t, Servers::Infinite);
        n.input(a, t);
        n.output(t, b);
        let u = n.add_immediate("u", 1.0, 2);
        n.input(b, u);
        n.output(u, a);
        n.set_param("r", Some(2.0), crate::net::ParamKind::Real);
        n
    }

    #[test]
    fn firing_rule_and_server_semantics() {
        let g = small().instantiate(&Params::new()).unwrap();
        let t = g.transition("t").unwrap();
        let mut m = g.initial_marking().to_vec();
        assert!(g.is_enabled(t, &m));
        assert_eq!(g.server_factor(t, &m), 2.0);
        let mut out = Vec::new();
        assert_eq!(g.firable(&m, &mut out), MarkingKind::Tangible);
        g.fire(t, &mut m).unwrap();
        assert_eq!(m, vec![1, 1]);
        assert_eq!(g.firable(&m, &mut out), MarkingKind::Vanishing);
        assert_eq!(out, vec![g.transition("u").unwrap()]);
        assert_eq!(g.rates(&Params::new(), None).unwrap()[t.index()], 2.0);
        assert_eq!(
            g.rates(&Params::new().with("r", 5.0), None).unwrap()[t.index()],
            5.0
        );
    }

    #[test]
    fn bad_values_are_errors() {
        let mut n = small();
        n.transitions[1].kind = TransitionKind::Immediate {
            weight: Expr::Num(0.0),
            priority: Expr::Num(1.0),
        };
        assert!(matches!(
            n.instantiate(&Params::new()),
            Err(Error::InvalidValue { .. })
        ));
        let mut n = small();
        n.places[0].initial = Expr::param("N");
        let err = n.instantiate(&Params::new()).unwrap_err();
        assert!(matches!(err, Error::UnboundParameter { .. }), "{err}");
        let g = small().instantiate(&Params::new()).unwrap();
        assert!(matches!(
            g.rates(&Params::new().with("r", -1.0), None),
            Err(Error::InvalidValue { .. })
        ));
        assert!(matches!(
            g.rates(&Params::new().with("zz", 1.0), None),
            Err(Error::UnknownParameter { .. })
        ));
        let mut n = small();
        n.add_place("t", 0u32);
        assert!(matches!(
            n.instantiate(&Params::new()),
            Err(Error::DuplicateName { .. })
        ));
    }
}
