//! The CTMC of a GSPN, compiled once and solved for any rates.
//!
//! [`CompiledGspn::build`] generates the reachability graph, eliminates the
//! vanishing markings and keeps the result *symbolically*: every entry of the
//! generator is `rate[t] · c` with `c` the server factor times the vanishing
//! path probability — which depend on markings and weights only. Solving for
//! new rates ([`CompiledGspn::solve_rates`]) therefore rebuilds nothing: it
//! computes the exit rates (one pass over the entries) and solves. The
//! strongly connected structure of the chain does not depend on rates either
//! (they are > 0), so the bottom components of a non-ergodic chain are found
//! once here.
//!
//! Long-run distribution from `M0` (spec §4): `Σ_B P(reach B) · π_B` over the
//! bottom strongly connected components `B`; `P(reach B)` comes from the
//! expected sojourn times `x` in the transient states, `x(−Q_TT) = π0_T`,
//! as `π0_B + Σ_{s∈T} x_s Σ_{b∈B} q_sb`.

use std::time::Instant;

use crate::error::{Error, Result};
use crate::expr::Expr;
use crate::gspn::Gspn;
use crate::marking::MarkingStore;
use crate::net::{Params, PlaceId, TransitionId};
use crate::reachability::{ExploreParams, ExploreStats, ReachabilityGraph};
use crate::scc::{Components, Successors};
use crate::steady_state::{self, NumericRows, SolveInfo, SolveParams, SymbolicRows};
use crate::vanishing;

const NONE: u32 = u32::MAX;

/// Sizes and timings of a compilation.
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct CompileStats {
    /// State-space generation figures.
    pub explore: ExploreStats,
    /// Entries `(s, t, s')` of the symbolic generator (self-loops included).
    pub entries: usize,
    /// Seconds spent eliminating vanishing markings and building the chain.
    pub compile_seconds: f64,
    /// Number of strongly connected components of the tangible chain.
    pub components: usize,
    /// Number of bottom components (1 for an ergodic chain).
    pub bottom_components: usize,
    /// Tangible states outside every bottom component.
    pub transient_states: usize,
}

/// A GSPN compiled to a symbolic CTMC over its tangible markings.
#[derive(Debug, Clone)]
pub struct CompiledGspn {
    gspn: Gspn,
    stats: CompileStats,
    store: MarkingStore,
    tangible_rg: Vec<u32>,
    // Outgoing entries per tangible state (self-loops kept for throughputs).
    out_offsets: Vec<u64>,
    out_dst: Vec<u32>,
    out_trans: Vec<u32>,
    out_coeff: Option<Vec<f64>>,
    // Incoming entries per tangible state, self-loops left out.
    in_offsets: Vec<u64>,
    in_src: Vec<u32>,
    in_trans: Vec<u32>,
    in_coeff: Option<Vec<f64>>,
    imm: ImmediateFlows,
    initial: Vec<(u32, f64)>,
    components: Components,
    bottoms: Vec<Vec<u32>>,
    transient: Vec<u32>,
}

/// The long-run solution for one binding of the rates.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Solution {
    /// Long-run probability of each tangible marking.
    pub pi: Vec<f64>,
    /// Rates used, by transition (0 for immediate ones).
    pub rates: Vec<f64>,
    /// Mean firings per unit time, by transition.
    pub throughput: Vec<f64>,
    /// `E[#p]`, by place.
    pub mean_tokens: Vec<f64>,
    /// `P{#p > 0}`, by place.
    pub prob_nonempty: Vec<f64>,
    /// How the stationary equations were solved (the largest bottom
    /// component's solve; residual of the whole long-run distribution).
    pub info: SolveInfo,
    /// Residual of the absorption equations (0 for ergodic chains).
    pub absorption_residual: f64,
    /// Long-run probability of ending in each bottom component, in the order
    /// of [`CompiledGspn::bottom_components`].
    pub bottom_probabilities: Vec<f64>,
}

impl Solution {
    /// Throughput of `t`.
    pub fn throughput(&self, t: TransitionId) -> f64 {
        self.throughput[t.index()]
    }

    /// Mean token count of `p`.
    pub fn mean_tokens(&self, p: PlaceId) -> f64 {
        self.mean_tokens[p.index()]
    }

    /// Probability that `p` is marked.
    pub fn prob_nonempty(&self, p: PlaceId) -> f64 {
        self.prob_nonempty[p.index()]
    }
}

/// Entries of the generator per source state: `q(s, dst[k]) += rate[trans[k]] · coeff[k]`.
#[derive(Debug, Clone, Default)]
struct Entries {
    offsets: Vec<u64>,
    dst: Vec<u32>,
    trans: Vec<u32>,
    coeff: Option<Vec<f64>>,
}

/// Timed firings `(src, trans, coeff)` that enter vanishing markings, with
/// the expected immediate firings `F` that follow each.
#[derive(Debug, Clone)]
struct ImmediateFlows {
    src: Vec<u32>,
    trans: Vec<u32>,
    coeff: Vec<f64>,
    f_start: Vec<u64>,
    f_items: Vec<(u32, f64)>,
}

impl Default for ImmediateFlows {
    fn default() -> Self {
        ImmediateFlows {
            src: Vec::new(),
            trans: Vec::new(),
            coeff: Vec::new(),
            f_start: vec![0],
            f_items: Vec::new(),
        }
    }
}

struct OutGraph<'a> {
    offsets: &'a [u64],
    dst: &'a [u32],
}

impl Successors for OutGraph<'_> {
    fn num_nodes(&self) -> usize {
        self.offsets.len() - 1
    }

    fn successors(&self, v: u32) -> &[u32] {
        &self.dst[self.offsets[v as usize] as usize..self.offsets[v as usize + 1] as usize]
    }
}

impl CompiledGspn {
    /// Generates the state space of `gspn` and compiles its CTMC.
    pub fn build(gspn: &Gspn, explore: &ExploreParams) -> Result<CompiledGspn> {
        let rg = ReachabilityGraph::explore(gspn, explore)?;
        CompiledGspn::from_graph(gspn.clone(), rg)
    }

    /// Compiles the CTMC of an already generated reachability graph.
    pub fn from_graph(gspn: Gspn, rg: ReachabilityGraph) -> Result<CompiledGspn> {
        let start = Instant::now();
        let mut tangible_id = vec![NONE; rg.num_markings()];
        let mut tangible_rg = Vec::with_capacity(rg.num_tangible());
        for (i, slot) in tangible_id.iter_mut().enumerate() {
            if !rg.vanishing[i] {
                *slot = tangible_rg.len() as u32;
                tangible_rg.push(i as u32);
            }
        }
        let explore = rg.stats.clone();
        let mut imm = ImmediateFlows::default();
        let (chain, initial) = if explore.vanishing == 0 {
            // No vanishing markings: tangible ids are RG indices, the RG is the chain.
            let chain = Entries {
                offsets: rg.offsets,
                dst: rg.targets,
                trans: rg.transitions,
                coeff: rg.coeffs,
            };
            (chain, vec![(0u32, 1.0)])
        } else {
            let el = vanishing::eliminate(&gspn, &rg, &tangible_id)?;
            let mut chain = Entries {
                offsets: Vec::with_capacity(tangible_rg.len() + 1),
                ..Entries::default()
            };
            chain.offsets.push(0);
            let mut coeff = Vec::new();
            let mut row: Vec<(u32, u32, f64)> = Vec::new();
            for &s in &tangible_rg {
                row.clear();
                let (a, b) = rg.range(s as usize);
                for k in a..b {
                    let (w, t, c) = (rg.targets[k], rg.transitions[k], rg.coeff(k));
                    if tangible_id[w as usize] != NONE {
                        row.push((tangible_id[w as usize], t, c));
                        continue;
                    }
                    for &(u, q) in el.dist(w) {
                        row.push((u, t, c * q));
                    }
                    let f = el.firings(w);
                    if !f.is_empty() {
                        imm.src.push(tangible_id[s as usize]);
                        imm.trans.push(t);
                        imm.coeff.push(c);
                        imm.f_items.extend_from_slice(f);
                        imm.f_start.push(imm.f_items.len() as u64);
                    }
                }
                // Merge entries with the same target and transition.
                row.sort_unstable_by_key(|e| (e.0, e.1));
                let mut last = None;
                for &(u, t, c) in &row {
                    if last == Some((u, t)) {
                        if let Some(x) = coeff.last_mut() {
                            *x += c;
                        }
                    } else {
                        chain.dst.push(u);
                        chain.trans.push(t);
                        coeff.push(c);
                        last = Some((u, t));
                    }
                }
                chain.offsets.push(chain.dst.len() as u64);
            }
            chain.coeff = if coeff.iter().all(|&c| c == 1.0) {
                None
            } else {
                Some(coeff)
            };
            let initial = if rg.vanishing[0] {
                el.dist(0).to_vec()
            } else {
                vec![(tangible_id[0], 1.0)]
            };
            (chain, initial)
        };
        let mut store = rg.store;
        store.drop_index();
        Ok(CompiledGspn::finish(
            gspn,
            explore,
            store,
            tangible_rg,
            chain,
            imm,
            initial,
            start,
        ))
    }

    #[allow(clippy::too_many_arguments)]
    fn finish(
        gspn: Gspn,
        explore: ExploreStats,
        store: MarkingStore,
        tangible_rg: Vec<u32>,
        chain: Entries,
        imm: ImmediateFlows,
        initial: Vec<(u32, f64)>,
        start: Instant,
    ) -> CompiledGspn {
        let Entries {
            offsets: out_offsets,
            dst: out_dst,
            trans: out_trans,
            coeff: out_coeff,
        } = chain;
        let n = tangible_rg.len();
        // Transpose, leaving self-loops out.
        let mut in_offsets = vec![0u64; n + 1];
        for s in 0..n {
            for &d in &out_dst[out_offsets[s] as usize..out_offsets[s + 1] as usize] {
                if d as usize != s {
                    in_offsets[d as usize + 1] += 1;
                }
            }
        }
        for j in 0..n {
            in_offsets[j + 1] += in_offsets[j];
        }
        let m = in_offsets[n] as usize;
        let mut fill: Vec<u64> = in_offsets[..n].to_vec();
        let mut in_src = vec![0u32; m];
        let mut in_trans = vec![0u32; m];
        let mut in_coeff = out_coeff.as_ref().map(|_| vec![0.0; m]);
        for s in 0..n {
            for k in out_offsets[s] as usize..out_offsets[s + 1] as usize {
                let d = out_dst[k] as usize;
                if d != s {
                    let pos = fill[d] as usize;
                    fill[d] += 1;
                    in_src[pos] = s as u32;
                    in_trans[pos] = out_trans[k];
                    if let (Some(ic), Some(oc)) = (in_coeff.as_mut(), out_coeff.as_ref()) {
                        ic[pos] = oc[k];
                    }
                }
            }
        }
        drop(fill);
        let components = Components::of(&OutGraph {
            offsets: &out_offsets,
            dst: &out_dst,
        });
        let bottom_ids = components.bottoms();
        let mut bottom_index = vec![NONE; components.len()];
        for (b, &c) in bottom_ids.iter().enumerate() {
            bottom_index[c as usize] = b as u32;
        }
        let mut bottoms = vec![Vec::new(); bottom_ids.len()];
        let mut transient = Vec::new();
        if bottom_ids.len() > 1 || components.len() > 1 {
            for s in 0..n as u32 {
                let b = bottom_index[components.comp[s as usize] as usize];
                if b == NONE {
                    transient.push(s);
                } else {
                    bottoms[b as usize].push(s);
                }
            }
        }
        let stats = CompileStats {
            explore,
            entries: out_dst.len(),
            compile_seconds: start.elapsed().as_secs_f64(),
            components: components.len(),
            bottom_components: bottom_ids.len(),
            transient_states: transient.len(),
        };
        CompiledGspn {
            gspn,
            stats,
            store,
            tangible_rg,
            out_offsets,
            out_dst,
            out_trans,
            out_coeff,
            in_offsets,
            in_src,
            in_trans,
            in_coeff,
            imm,
            initial,
            components,
            bottoms,
            transient,
        }
    }

    /// The instantiated net.
    pub fn gspn(&self) -> &Gspn {
        &self.gspn
    }

    /// Sizes and timings.
    pub fn stats(&self) -> &CompileStats {
        &self.stats
    }

    /// Number of tangible markings (states of the CTMC).
    pub fn num_tangible(&self) -> usize {
        self.tangible_rg.len()
    }

    /// Token counts of tangible marking `s`.
    pub fn tangible_marking(&self, s: usize) -> Vec<u32> {
        let mut m = vec![0; self.gspn.num_places()];
        self.store.decode(self.tangible_rg[s] as usize, &mut m);
        m
    }

    /// Distribution over tangible markings reached from `M0` in zero time.
    pub fn initial_distribution(&self) -> &[(u32, f64)] {
        &self.initial
    }

    /// Tangible states of each bottom strongly connected component (empty
    /// list of lists when the chain is irreducible: one component, all states).
    pub fn bottom_components(&self) -> &[Vec<u32>] {
        &self.bottoms
    }

    /// Whether the chain is irreducible (ergodic).
    pub fn is_ergodic(&self) -> bool {
        self.components.len() == 1
    }

    /// Approximate heap bytes of the compiled chain.
    pub fn heap_bytes(&self) -> usize {
        self.store.heap_bytes()
            + self.tangible_rg.capacity() * 4
            + (self.out_offsets.capacity() + self.in_offsets.capacity()) * 8
            + (self.out_dst.capacity() + self.out_trans.capacity()) * 4
            + (self.in_src.capacity() + self.in_trans.capacity()) * 4
            + self.out_coeff.as_ref().map_or(0, |c| c.capacity() * 8)
            + self.in_coeff.as_ref().map_or(0, |c| c.capacity() * 8)
            + self.components.comp.capacity() * 4
    }

    /// Evaluates the rates from the net's parameters with `overrides`, and
    /// solves.
    pub fn solve(
        &self,
        overrides: &Params,
        default_rate: Option<f64>,
        params: &SolveParams,
    ) -> Result<Solution> {
        let rates = self.gspn.rates(overrides, default_rate)?;
        self.solve_rates(&rates, params)
    }

    /// Solves for a vector of rates indexed by transition (entries of
    /// immediate transitions are ignored). Nothing structural is rebuilt.
    pub fn solve_rates(&self, rates: &[f64], params: &SolveParams) -> Result<Solution> {
        let start = Instant::now();
        params.validate()?;
        if rates.len() != self.gspn.num_transitions() {
            return Err(Error::Invalid(format!(
                "{} rates given for {} transitions",
                rates.len(),
                self.gspn.num_transitions()
            )));
        }
        for (t, &r) in rates.iter().enumerate() {
            if !(self.gspn.is_immediate(TransitionId(t as u32)) || (r.is_finite() && r > 0.0)) {
                return Err(Error::InvalidValue {
                    element: format!("timed transition `{}`", self.gspn.transition_names()[t]),
                    what: "the rate",
                    requirement: "a finite number > 0",
                    value: r,
                });
            }
        }
        let n = self.num_tangible();
        let exit = self.exit_rates(rates);
        let rows = SymbolicRows {
            offsets: &self.in_offsets,
            src: &self.in_src,
            trans: &self.in_trans,
            coeff: self.in_coeff.as_deref(),
            rates,
            exit: &exit,
        };
        let mut pi = vec![0.0; n];
        let mut info;
        let mut absorption_residual = 0.0;
        let mut bottom_probabilities = Vec::new();
        if self.is_ergodic() {
            let (x, i) = steady_state::solve(&rows, None, params)?;
            pi = x;
            info = i;
            bottom_probabilities.push(1.0);
        } else {
            // Probability of ending in each bottom component.
            let mut init = vec![0.0; n];
            for &(s, p) in &self.initial {
                init[s as usize] += p;
            }
            let mut comp_prob = vec![0.0; self.components.len()];
            for (s, &p) in init.iter().enumerate() {
                comp_prob[self.components.comp[s] as usize] += p;
            }
            if !self.transient.is_empty() {
                let (sub, _) = self.sub_chain(&self.transient, rates, &exit);
                let b: Vec<f64> = self.transient.iter().map(|&s| init[s as usize]).collect();
                let (x, ai) = steady_state::solve(&sub, Some(&b), params)?;
                absorption_residual = ai.residual;
                for (&s, &xs) in self.transient.iter().zip(&x) {
                    let s = s as usize;
                    for k in self.out_offsets[s] as usize..self.out_offsets[s + 1] as usize {
                        let d = self.out_dst[k] as usize;
                        let c = self.components.comp[d] as usize;
                        if self.components.bottom[c] {
                            comp_prob[c] += xs * rates[self.out_trans[k] as usize] * self.out_c(k);
                        }
                    }
                }
            }
            info = SolveInfo {
                method: "trivial",
                ..SolveInfo::default()
            };
            let mut largest = 0;
            for states in &self.bottoms {
                let c = self.components.comp[states[0] as usize] as usize;
                let prob = comp_prob[c];
                bottom_probabilities.push(prob);
                let (sub, _) = self.sub_chain(states, rates, &exit);
                let (x, i) = steady_state::solve(&sub, None, params)?;
                if states.len() >= largest {
                    largest = states.len();
                    info.method = i.method;
                }
                info.iterations += i.iterations;
                for (&s, &v) in states.iter().zip(&x) {
                    pi[s as usize] = prob * v;
                }
            }
        }
        info.residual = steady_state::residual(&rows, &pi, None);
        info.seconds = start.elapsed().as_secs_f64();
        let throughput = self.throughputs(&pi, rates);
        let (mean_tokens, prob_nonempty) = self.place_measures(&pi);
        Ok(Solution {
            pi,
            rates: rates.to_vec(),
            throughput,
            mean_tokens,
            prob_nonempty,
            info,
            absorption_residual,
            bottom_probabilities,
        })
    }

    #[inline]
    fn out_c(&self, k: usize) -> f64 {
        self.out_coeff.as_ref().map_or(1.0, |c| c[k])
    }

    fn exit_rates(&self, rates: &[f64]) -> Vec<f64> {
        let n = self.num_tangible();
        let mut exit = vec![0.0; n];
        for (s, e) in exit.iter_mut().enumerate() {
            let (a, b) = (self.out_offsets[s] as usize, self.out_offsets[s + 1] as usize);
            let mut sum = 0.0;
            for k in a..b {
                if self.out_dst[k] as usize != s {
                    sum += rates[self.out_trans[k] as usize] * self.out_c(k);
                }
            }
            *e = sum;
        }
        exit
    }

    /// The chain restricted to `states` (sorted), with numeric entries; exit
    /// rates stay the full ones (flow leaving the subset counts as exit).
    fn sub_chain(&self, states: &[u32], rates: &[f64], exit: &[f64]) -> (NumericRows, Vec<u32>) {
        let n = self.num_tangible();
        let mut local = vec![NONE; n];
        for (i, &s) in states.iter().enumerate() {
            local[s as usize] = i as u32;
        }
        let mut entries = Vec::new();
        for (i, &s) in states.iter().enumerate() {
            let s = s as usize;
            for k in self.out_offsets[s] as usize..self.out_offsets[s + 1] as usize {
                let d = self.out_dst[k] as usize;
                if d != s && local[d] != NONE {
                    entries.push((
                        local[d],
                        i as u32,
                        rates[self.out_trans[k] as usize] * self.out_c(k),
                    ));
                }
            }
        }
        let ex = states.iter().map(|&s| exit[s as usize]).collect();
        (NumericRows::from_entries(states.len(), entries, ex), local)
    }

    fn throughputs(&self, pi: &[f64], rates: &[f64]) -> Vec<f64> {
        let mut x = vec![0.0; self.gspn.num_transitions()];
        for (s, &p) in pi.iter().enumerate() {
            if p == 0.0 {
                continue;
            }
            for k in self.out_offsets[s] as usize..self.out_offsets[s + 1] as usize {
                let t = self.out_trans[k] as usize;
                x[t] += p * rates[t] * self.out_c(k);
            }
        }
        let imm = &self.imm;
        for e in 0..imm.src.len() {
            let p = pi[imm.src[e] as usize];
            if p == 0.0 {
                continue;
            }
            let flow = p * rates[imm.trans[e] as usize] * imm.coeff[e];
            for &(u, count) in &imm.f_items[imm.f_start[e] as usize..imm.f_start[e + 1] as usize] {
                x[u as usize] += flow * count;
            }
        }
        x
    }

    fn place_measures(&self, pi: &[f64]) -> (Vec<f64>, Vec<f64>) {
        let np = self.gspn.num_places();
        let mut mean = vec![0.0; np];
        let mut nonempty = vec![0.0; np];
        for (s, &p) in pi.iter().enumerate() {
            if p == 0.0 {
                continue;
            }
            let i = self.tangible_rg[s] as usize;
            for q in 0..np {
                let k = self.store.tokens(i, q);
                if k > 0 {
                    mean[q] += p * f64::from(k);
                    nonempty[q] += p;
                }
            }
        }
        (mean, nonempty)
    }

    /// Long-run mean of a measure expression over tangible markings (the
    /// probability of a condition such as `#P1 = 1 and #P7 = 1`, or the mean
    /// of an arithmetic expression such as `#P1 + 2 * #P2`). Parameters in it
    /// take the net's bound values.
    pub fn measure(&self, solution: &Solution, expr: &Expr) -> Result<f64> {
        let names = self.gspn.place_names();
        let params = self.gspn.params();
        let compiled = expr.compile(&|n| names.iter().position(|p| p == n), &|n| {
            params.get(n).copied().flatten()
        })?;
        let mut m = vec![0; self.gspn.num_places()];
        let mut stack = Vec::new();
        let mut sum = 0.0;
        for (s, &p) in solution.pi.iter().enumerate() {
            if p == 0.0 {
                continue;
            }
            self.store.decode(self.tangible_rg[s] as usize, &mut m);
            sum += p * compiled.eval(&m, &mut stack);
        }
        Ok(sum)
    }
}
