//! The structured engine: the steady state of a GSPN whose reachable set is
//! a product of components' local spaces ([`crate::structure`]), solved
//! without building the generator.
//!
//! ```
//! use petri::{Params, SolveParams, StructuredGspn, StructuredParams, families};
//!
//! let gspn = families::kanban(3).instantiate(&Params::new())?;
//! let s = StructuredGspn::build(&gspn, &StructuredParams::default(), petri::Interrupt::NEVER)?;
//! assert_eq!(s.stats().tangible, 58_400);
//! let rates = gspn.rates(&Params::new(), None)?;
//! let solution = s.solve_rates(&rates, &SolveParams::default(), petri::Interrupt::NEVER)?;
//! let busy = s.measure(&solution, &petri::Expr::parse("#Pm1 >= 1")?)?;
//! assert!((busy - 0.2774656738).abs() < 1e-9);
//! # Ok::<(), petri::Error>(())
//! ```
//!
//! **Pipeline.** [`StructuredGspn::build`] finds the components and their
//! local spaces (a symbolic search), builds the Kronecker descriptor (local
//! maps per transition and component, `crate::descriptor`), and checks
//! that the chain is irreducible: for a net without immediate transitions
//! the symbolic search also shows `M0` is reached back from every marking;
//! with immediate transitions, explicit searches over the product
//! (`crate::product_search`) find the markings the GSPN reaches and
//! classify them (the solver keeps vanishing markings as states, see
//! `crate::sweep`). Anything else — no product structure, a component too
//! large, a chain that is not irreducible — is [`Error::Unstructured`] with
//! the reason, and the explicit engine ([`crate::CompiledGspn`]) is the one
//! to use. [`StructuredGspn::solve_rates`] iterates (`crate::sweep`) on
//! one vector of `f64` per product state — the only allocation that grows
//! with the chain besides, for nets with immediate transitions, two bytes
//! of class per state.
//!
//! **Iteration.** Gauss–Seidel sweeps, relaxed once the convergence rate
//! has been measured over a window of sweeps: ω moves from 1 by steps of
//! 0.1 — upwards when Gauss–Seidel converges, downwards when it stagnates
//! (an iteration matrix with other eigenvalues of modulus 1, met on some
//! orderings) — as long as each window converges faster than the last, and
//! once settled it is lowered again by any window that does not converge
//! (SOR diverges past some ω on these chains: `EXPERIMENTS.md`). With
//! [`Method::GaussSeidel`] ω is [`SolveParams::omega`], fixed. The stopping
//! rule and the residual are the explicit engine's: `‖xQ‖₁ / Σ_j exit_j
//! x_j` (for nets with immediate transitions, over the chain with its
//! vanishing states), checked by a separate pass once the sweep's own
//! estimate is below the tolerance.
//!
//! **Measures** come from marginals: one pass over the vector sums it by
//! the local states of the components a measure reads (one component for a
//! place's mean, the components a transition touches for its throughput),
//! so no marking is decoded per state unless a measure reads components
//! whose joint space exceeds [`MAX_JOINT`] states.

use std::cell::RefCell;
use std::time::Instant;

use crate::descriptor::Descriptor;
use crate::error::{Error, Result};
use crate::expr::Expr;
use crate::gspn::Gspn;
use crate::interrupt::{Interrupt, SOLVING, Stage};
use crate::net::TransitionId;
use crate::product_search;
use crate::steady_state::{Method, SolveInfo, SolveParams};
use crate::structure::{Structure, StructureParams};
use crate::sweep::{Kinds, Plan, TANGIBLE, UNREACHABLE};

/// Largest joint space of the components a measure reads that is summed
/// as a marginal; beyond, the measure decodes every state.
pub const MAX_JOINT: usize = 1 << 22;

/// Sweeps per window of the relaxation control (two aggregation cycles).
const WINDOW: usize = 8;
/// Sweeps after a change of ω not counted in its window.
const SETTLE: usize = 8;
/// Sweeps at ω = 1 before its first window (the first sweeps converge
/// faster than the asymptotic rate, and over-relaxation slower).
const WARMUP: usize = 16;
/// Step of ω between windows.
const OMEGA_STEP: f64 = 0.05;
/// Largest ω tried.
const MAX_OMEGA: f64 = 1.15;
/// A new ω is kept when its window's convergence speed (`−ln` of the
/// imbalance's factor per sweep) is at least this fraction of the previous
/// window's: later windows converge more slowly at any ω (the fast
/// components of the error are gone), so demanding a gain would stop the
/// search below the best ω (`EXPERIMENTS.md`).
const GAIN: f64 = 0.8;
/// Sweeps between two aggregation steps.
const AGGREGATE_EVERY: usize = 4;

/// Options of the structured engine.
#[derive(Debug, Clone)]
pub struct StructuredParams {
    /// How the structure is found (a partition given by the user).
    pub structure: StructureParams,
    /// Bytes the engine may allocate for its vectors and tables (the
    /// explicit engine's guard, [`crate::ExploreParams::max_memory`]).
    pub max_memory: u64,
}

impl Default for StructuredParams {
    fn default() -> Self {
        StructuredParams {
            structure: StructureParams::default(),
            max_memory: crate::reachability::default_max_memory(),
        }
    }
}

/// Sizes and timings of a structured build.
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct StructuredStats {
    /// Local states of each component, outermost first.
    pub components: Vec<usize>,
    /// States of the product space (the length of the solution vector).
    pub states: u64,
    /// Tangible markings.
    pub tangible: u64,
    /// Vanishing markings (kept as states of the chain).
    pub vanishing: u64,
    /// Seconds spent finding the structure.
    pub structure_seconds: f64,
    /// Seconds spent building the descriptor and the searches.
    pub build_seconds: f64,
    /// Decision-diagram nodes of the symbolic search.
    pub mdd_nodes: usize,
    /// Heap bytes of the descriptor's local maps and local spaces.
    pub descriptor_bytes: u64,
    /// Heap bytes of the state classes (nets with immediate transitions).
    pub class_bytes: u64,
    /// What the engine estimated before allocating: vector, classes,
    /// search bits, tables.
    pub estimate_bytes: u64,
}

/// A GSPN prepared for the structured engine.
#[derive(Debug)]
pub struct StructuredGspn {
    gspn: Gspn,
    structure: Structure,
    desc: Descriptor,
    kinds: Option<Kinds>,
    stats: StructuredStats,
}

/// The long-run solution of the structured engine.
#[derive(Debug, Clone)]
pub struct StructuredSolution {
    /// Rates used, by transition (0 for immediate ones).
    pub rates: Vec<f64>,
    /// Mean firings per unit time, by transition.
    pub throughput: Vec<f64>,
    /// `E[#p]`, by place.
    pub mean_tokens: Vec<f64>,
    /// `P{#p > 0}`, by place.
    pub prob_nonempty: Vec<f64>,
    /// How the equations were solved (method `"structured-sor"` or
    /// `"structured-gauss-seidel"`).
    pub info: SolveInfo,
    /// The relaxation factor at the end.
    pub omega: f64,
    /// Sweeps at each ω tried, in order.
    pub omega_history: Vec<(f64, usize)>,
    /// Aggregation steps done (each over every component).
    pub aggregations: usize,
    /// Probability of each product state (0 for unreachable and vanishing
    /// ones; vanishing ones hold their flow per unit time).
    x: Vec<f64>,
}

impl StructuredSolution {
    /// Throughput of `t`.
    pub fn throughput(&self, t: TransitionId) -> f64 {
        self.throughput[t.index()]
    }
}

fn unstructured(reason: impl Into<String>) -> Error {
    Error::Unstructured {
        reason: reason.into(),
    }
}

impl StructuredGspn {
    /// Finds the structure of `gspn` and prepares the solver (see the
    /// module docs); [`Error::Unstructured`] says why it does not apply.
    pub fn build(gspn: &Gspn, params: &StructuredParams, stop: Interrupt<'_>) -> Result<StructuredGspn> {
        stop.check("finding the structure")?;
        if gspn.has_decisions() {
            // A choice between decisions is not a random switch: the
            // explicit engine solves such a net under a policy, or
            // `gspn optimize` finds the best one.
            return Err(unstructured(
                "the net has decision transitions (a Markov decision process, not a chain); solve it under a policy with the explicit engine, or optimise it with `gspn optimize`",
            ));
        }
        stop.stage(Stage::Structuring);
        let mut structure = Structure::detect(gspn, &params.structure).map_err(|e| match e {
            Error::Invalid(m) => unstructured(m),
            other => other,
        })?;
        if !structure.is_exact() {
            return Err(unstructured(format!(
                "the components' product ({} states) is not the reachable set ({})",
                structure.product(),
                structure.reachable()
            )));
        }
        let states = u64::try_from(structure.product()).unwrap_or(u64::MAX);
        stop.generated(usize::try_from(states).unwrap_or(usize::MAX), 0);
        if gspn.num_immediate() == 0 && structure.reversible() == Some(false) {
            return Err(unstructured(
                "the initial marking is not reached back from every marking (the chain is not irreducible)",
            ));
        }
        let start = Instant::now();
        stop.check("building the descriptor")?;
        let immediate = gspn.num_immediate() > 0;
        let tables: u64 = structure
            .components()
            .iter()
            .map(|c| c.heap_bytes() as u64)
            .sum::<u64>()
            * 4;
        let per_state = 8.0 + if immediate { 2.0 + 3.0 / 8.0 } else { 0.0 };
        let estimate = (states as f64 * per_state) as u64 + tables + (1 << 20);
        if estimate > params.max_memory {
            return Err(Error::MemoryLimit {
                estimate,
                limit: params.max_memory,
                markings: usize::try_from(states).unwrap_or(usize::MAX),
                edges: 0,
            });
        }
        let desc = Descriptor::with_flow_order(gspn, &mut structure).map_err(|e| match e {
            Error::Invalid(m) => unstructured(m),
            other => other,
        })?;
        let m0 = structure
            .locals_of(gspn.initial_marking())
            .map(|l| desc.index(&l.iter().map(|&v| v as u32).collect::<Vec<_>>()))
            .ok_or_else(|| unstructured("internal: the initial marking is not a product state"))?;
        let (kinds, tangible, vanishing) = if immediate {
            let (kinds, t, v) = product_search::classify(&desc, m0, stop)?;
            if t == 0 {
                return Err(unstructured("no tangible marking is reachable"));
            }
            if !product_search::reaches_back(&desc, &kinds, m0, stop)? {
                return Err(unstructured(
                    "the initial marking is not reached back from every marking (the chain is not irreducible, or has a timeless trap)",
                ));
            }
            (Some(kinds), t, v)
        } else {
            (None, states, 0)
        };
        let stats = StructuredStats {
            components: structure.components().iter().map(|c| c.len()).collect(),
            states,
            tangible,
            vanishing,
            structure_seconds: structure.seconds(),
            build_seconds: start.elapsed().as_secs_f64(),
            mdd_nodes: structure.mdd_nodes(),
            descriptor_bytes: (desc.heap_bytes()
                + structure
                    .components()
                    .iter()
                    .map(|c| c.heap_bytes())
                    .sum::<usize>()) as u64,
            class_bytes: kinds.as_ref().map_or(0, |k| k.class.capacity() as u64 * 2),
            estimate_bytes: estimate,
        };
        Ok(StructuredGspn {
            gspn: gspn.clone(),
            structure,
            desc,
            kinds,
            stats,
        })
    }

    /// The instantiated net.
    pub fn gspn(&self) -> &Gspn {
        &self.gspn
    }

    /// The structure found.
    pub fn structure(&self) -> &Structure {
        &self.structure
    }

    /// Sizes and timings.
    pub fn stats(&self) -> &StructuredStats {
        &self.stats
    }

    /// Bytes a solve allocates: the vector of the product space.
    pub fn solve_bytes(&self) -> u64 {
        self.desc.states * 8
    }

    /// Where the memory goes (the explicit engine's account, with the
    /// structured engine's parts): the local spaces and maps and the state
    /// classes while building, the vector while solving.
    pub fn memory_account(&self, solution: Option<&StructuredSolution>) -> crate::MemoryAccount {
        let n = self.stats.tangible.max(1) as f64;
        let part = |component: &'static str, stage: &'static str, bytes: u64| crate::MemoryPart {
            component,
            stage,
            bytes,
            bytes_per_marking: bytes as f64 / n,
        };
        let tables = self.stats.descriptor_bytes;
        let classes = self.stats.class_bytes;
        let vector = solution.map_or(self.solve_bytes(), |s| s.info.vector_bytes);
        let parts = vec![
            part("local spaces and transitions' local maps", "chain", tables),
            part("state classes (vanishing markings)", "chain", classes),
            part("probability vector over the product space", "solve", vector),
        ];
        crate::MemoryAccount {
            tangible_markings: self.stats.tangible as usize,
            parts,
            generation_bytes: tables + classes,
            compile_bytes: tables + classes,
            solve_bytes: tables + classes + vector,
            peak_bytes: tables + classes + vector,
            guard_estimate_bytes: self.stats.estimate_bytes,
        }
    }

    /// Solves for `rates` (by transition; immediate ones ignored).
    pub fn solve_rates(
        &self,
        rates: &[f64],
        params: &SolveParams,
        stop: Interrupt<'_>,
    ) -> Result<StructuredSolution> {
        params.validate()?;
        self.gspn.check_rates(rates)?;
        let omega_fixed = match params.method {
            Method::Auto => None,
            Method::GaussSeidel => Some(params.omega),
            m => {
                return Err(Error::Invalid(format!(
                    "the structured engine solves by Gauss–Seidel / SOR (method auto or gauss-seidel), not {m:?}"
                )));
            }
        };
        stop.check(SOLVING)?;
        stop.stage(Stage::Solving);
        let start = Instant::now();
        let scale = self.rate_scale(rates)?;
        let scaled: Vec<f64> = rates.iter().map(|r| r / scale).collect();
        let plan = Plan::new(&self.desc, self.kinds.as_ref(), &scaled);
        let mut x = self.initial_vector();
        let aggregate = self.kinds.is_none() && self.desc.levels() > 1;
        let run = iterate(
            &plan,
            &mut x,
            params,
            omega_fixed,
            stop,
            aggregate.then_some((&self.desc, &scaled[..])),
        )?;
        // Normalise over the tangible states.
        let mass = self.tangible_mass(&x);
        if !(mass.is_finite() && mass > 0.0) {
            return Err(Error::NotFinite {
                what: "the total probability of the tangible markings".into(),
                value: mass,
                cause: "the iteration lost all precision".into(),
            });
        }
        x.iter_mut().for_each(|v| *v /= mass);
        let final_sums = plan.residual(&x);
        let residual = if final_sums.flow > 0.0 {
            final_sums.imbalance / final_sums.flow
        } else {
            final_sums.imbalance
        };
        // Vanishing states hold flows per unit of the scaled time: back to
        // the model's time unit (the immediate transitions' throughputs).
        if let Some(k) = &self.kinds {
            for (v, &c) in x.iter_mut().zip(&k.class) {
                if c != TANGIBLE {
                    *v *= scale;
                }
            }
        }
        let info = SolveInfo {
            method: if run.omega == 1.0 && run.history.len() <= 1 {
                "structured-gauss-seidel"
            } else {
                "structured-sor"
            },
            iterations: run.sweeps,
            residual,
            seconds: start.elapsed().as_secs_f64(),
            vector_bytes: x.capacity() as u64 * 8,
        };
        let mut solution = StructuredSolution {
            rates: rates.to_vec(),
            throughput: Vec::new(),
            mean_tokens: Vec::new(),
            prob_nonempty: Vec::new(),
            info,
            omega: run.omega,
            omega_history: run.history,
            aggregations: run.aggregations,
            x,
        };
        self.fill_measures(&mut solution, rates);
        Ok(solution)
    }

    /// The fastest rate of a timed transition that moves the chain, as a
    /// power of two (exact scaling), after the spread check of the explicit
    /// engine.
    fn rate_scale(&self, rates: &[f64]) -> Result<f64> {
        let timed: Vec<usize> = self
            .desc
            .events
            .iter()
            .filter(|e| e.immediate.is_none() && !e.self_loop)
            .map(|e| e.transition as usize)
            .collect();
        let fastest = timed
            .iter()
            .copied()
            .max_by(|&a, &b| rates[a].total_cmp(&rates[b]));
        let slowest = timed
            .iter()
            .copied()
            .min_by(|&a, &b| rates[a].total_cmp(&rates[b]));
        let (Some(f), Some(s)) = (fastest, slowest) else {
            return Ok(1.0);
        };
        let ratio = rates[f] / rates[s];
        if ratio > crate::ctmc::MAX_RATE_SPREAD {
            let names = self.gspn.transition_names();
            return Err(Error::RateSpread {
                fastest: names[f].clone(),
                max: rates[f],
                slowest: names[s].clone(),
                min: rates[s],
                ratio,
                limit: crate::ctmc::MAX_RATE_SPREAD,
            });
        }
        let e = rates[f].log2().floor().clamp(-1022.0, 1023.0) as i64;
        Ok(f64::from_bits(((e + 1023) as u64) << 52))
    }

    /// 1 on every reachable state, 0 elsewhere.
    fn initial_vector(&self) -> Vec<f64> {
        match &self.kinds {
            None => vec![1.0; self.desc.states as usize],
            Some(k) => k
                .class
                .iter()
                .map(|&c| if c == UNREACHABLE { 0.0 } else { 1.0 })
                .collect(),
        }
    }

    fn tangible_mass(&self, x: &[f64]) -> f64 {
        match &self.kinds {
            None => x.iter().sum(),
            Some(k) => x
                .iter()
                .zip(&k.class)
                .filter(|&(_, &c)| c == TANGIBLE)
                .map(|(v, _)| v)
                .sum(),
        }
    }

    /// The probability mass of `x` counted for measures at state `i`.
    #[inline]
    fn weight(&self, x: &[f64], i: usize) -> f64 {
        match &self.kinds {
            Some(k) if k.class[i] != TANGIBLE => 0.0,
            _ => x[i],
        }
    }

    /// Joint marginals of the tangible mass over each subset of levels
    /// (ascending), one pass over the vector.
    fn marginals(&self, x: &[f64], subsets: &[Vec<usize>]) -> Vec<Vec<f64>> {
        let sizes = &self.desc.sizes;
        let k = sizes.len();
        let n = sizes[k - 1];
        let strides: Vec<Vec<usize>> = subsets
            .iter()
            .map(|s| {
                let mut st = vec![0usize; k];
                let mut acc = 1;
                for &lev in s.iter().rev() {
                    st[lev] = acc;
                    acc *= sizes[lev];
                }
                st
            })
            .collect();
        let mut out: Vec<Vec<f64>> = subsets
            .iter()
            .map(|s| vec![0.0; s.iter().map(|&l| sizes[l]).product()])
            .collect();
        let mut locals = vec![0usize; k];
        for r in 0..(self.desc.states as usize / n) {
            let mut rem = r;
            for lev in (0..k - 1).rev() {
                locals[lev] = rem % sizes[lev];
                rem /= sizes[lev];
            }
            let start = r * n;
            let mut row_sum = None;
            for (s, (st, arr)) in subsets.iter().zip(strides.iter().zip(out.iter_mut())) {
                let base: usize = s.iter().filter(|&&l| l < k - 1).map(|&l| locals[l] * st[l]).sum();
                if s.contains(&(k - 1)) {
                    for c in 0..n {
                        arr[base + c] += self.weight(x, start + c);
                    }
                } else {
                    let sum = *row_sum
                        .get_or_insert_with(|| (0..n).map(|c| self.weight(x, start + c)).sum::<f64>());
                    arr[base] += sum;
                }
            }
        }
        out
    }

    /// Throughputs, mean tokens and P{#p > 0} of a solution.
    fn fill_measures(&self, sol: &mut StructuredSolution, rates: &[f64]) {
        let np = self.gspn.num_places();
        let k = self.desc.levels();
        let mut subsets: Vec<Vec<usize>> = (0..k).map(|l| vec![l]).collect();
        for e in &self.desc.events {
            let s: Vec<usize> = e.maps.iter().map(|m| m.level).collect();
            if s.len() > 1 && !subsets.contains(&s) {
                subsets.push(s);
            }
        }
        let marg = self.marginals(&sol.x, &subsets);
        let mut mean = vec![0.0; np];
        let mut nonempty = vec![0.0; np];
        for (lev, comp) in self.structure.components().iter().enumerate() {
            for (l, &p) in marg[lev].iter().enumerate() {
                if p == 0.0 {
                    continue;
                }
                for (i, place) in comp.places.iter().enumerate() {
                    let v = comp.state(l)[i];
                    if v > 0 {
                        mean[place.index()] += p * f64::from(v);
                        nonempty[place.index()] += p;
                    }
                }
            }
        }
        let mut thr = vec![0.0; self.gspn.num_transitions()];
        let mut locals = vec![0u32; k];
        for e in &self.desc.events {
            if e.immediate.is_some() {
                continue;
            }
            let s: Vec<usize> = e.maps.iter().map(|m| m.level).collect();
            let mut sum = 0.0;
            match s.len() {
                0 => sum = 1.0,
                1 => {
                    for (l, &p) in marg[s[0]].iter().enumerate() {
                        locals[s[0]] = l as u32;
                        if p != 0.0 && e.enabled_at(&locals) {
                            sum += p * e.factor_at(&locals);
                        }
                    }
                }
                _ => {
                    let idx = subsets.iter().position(|x| *x == s).unwrap_or(0);
                    for (j, &p) in marg[idx].iter().enumerate() {
                        if p == 0.0 {
                            continue;
                        }
                        let mut rem = j;
                        for &lev in s.iter().rev() {
                            locals[lev] = (rem % self.desc.sizes[lev]) as u32;
                            rem /= self.desc.sizes[lev];
                        }
                        if e.enabled_at(&locals) {
                            sum += p * e.factor_at(&locals);
                        }
                    }
                }
            }
            thr[e.transition as usize] = sum * rates[e.transition as usize];
        }
        if let Some(kinds) = &self.kinds {
            self.immediate_throughputs(&sol.x, kinds, &mut thr);
        }
        sol.throughput = thr;
        sol.mean_tokens = mean;
        sol.prob_nonempty = nonempty;
    }

    /// Flow of the immediate transitions through the vanishing states.
    fn immediate_throughputs(&self, x: &[f64], kinds: &Kinds, thr: &mut [f64]) {
        let mut l = vec![0u32; self.desc.levels()];
        for (i, &c) in kinds.class.iter().enumerate() {
            if c == UNREACHABLE || c == TANGIBLE || x[i] == 0.0 {
                continue;
            }
            let class = kinds.classes[c as usize];
            self.desc.locals(i as u64, &mut l);
            for e in &self.desc.events {
                if let Some((prio, w)) = e.immediate {
                    if prio == class.priority && e.enabled_at(&l) {
                        thr[e.transition as usize] += x[i] * w / class.weight_sum;
                    }
                }
            }
        }
    }

    /// Long-run mean of a measure expression over the tangible markings
    /// (as [`crate::CompiledGspn::measure`]).
    pub fn measure(&self, solution: &StructuredSolution, expr: &Expr) -> Result<f64> {
        let names = self.gspn.place_names();
        let params = self.gspn.params();
        let used = RefCell::new(Vec::new());
        let compiled = expr.compile(
            &|n| {
                let p = names.iter().position(|p| p == n);
                if let Some(p) = p {
                    used.borrow_mut().push(p);
                }
                p
            },
            &|n| params.get(n).copied().flatten(),
        )?;
        let pos = self.structure.place_positions(names.len());
        let mut levels: Vec<usize> = used.borrow().iter().map(|&p| pos[p].0).collect();
        levels.sort_unstable();
        levels.dedup();
        let joint: usize = levels.iter().map(|&l| self.desc.sizes[l]).product();
        let mut marking = vec![0u32; names.len()];
        let mut stack = Vec::new();
        let mut sum = 0.0;
        let comps = self.structure.components();
        let mut eval = |marking: &[u32], p: f64| -> Result<()> {
            let v = compiled.eval(marking, &mut stack);
            if !v.is_finite() {
                return Err(Error::NotFinite {
                    what: format!(
                        "the measure `{expr}` in marking {}",
                        self.gspn.format_marking(marking)
                    ),
                    value: v,
                    cause: "the expression divides by zero or overflows there".into(),
                });
            }
            sum += p * v;
            Ok(())
        };
        if joint <= MAX_JOINT {
            let marg = if levels.is_empty() {
                vec![vec![1.0]]
            } else {
                self.marginals(&solution.x, std::slice::from_ref(&levels))
            };
            for (j, &p) in marg[0].iter().enumerate() {
                if p == 0.0 {
                    continue;
                }
                let mut rem = j;
                for &lev in levels.iter().rev() {
                    let l = rem % self.desc.sizes[lev];
                    rem /= self.desc.sizes[lev];
                    for (i, place) in comps[lev].places.iter().enumerate() {
                        marking[place.index()] = comps[lev].state(l)[i];
                    }
                }
                eval(&marking, p)?;
            }
        } else {
            let mut l = vec![0u32; self.desc.levels()];
            for i in 0..self.desc.states as usize {
                let p = self.weight(&solution.x, i);
                if p == 0.0 {
                    continue;
                }
                self.desc.locals(i as u64, &mut l);
                for (lev, c) in comps.iter().enumerate() {
                    for (k, place) in c.places.iter().enumerate() {
                        marking[place.index()] = c.state(l[lev] as usize)[k];
                    }
                }
                eval(&marking, p)?;
            }
        }
        if !sum.is_finite() {
            return Err(Error::NotFinite {
                what: format!("the long-run mean of `{expr}`"),
                value: sum,
                cause: "its values are too large to sum in double precision".into(),
            });
        }
        Ok(sum)
    }
}

/// What the iteration did.
struct Run {
    sweeps: usize,
    omega: f64,
    history: Vec<(f64, usize)>,
    aggregations: usize,
}

/// The relaxation control (see the module docs).
struct Relaxation {
    omega: f64,
    fixed: bool,
    /// Sweeps at the current ω, and the proxy at the start of its window.
    at: usize,
    window_start: f64,
    /// The best ω so far and its rate.
    best: Option<(f64, f64)>,
    /// [`OMEGA_STEP`] while searching upwards, minus it downwards, 0 once
    /// settled.
    step: f64,
    history: Vec<(f64, usize)>,
}

/// A window whose imbalance fell by less than this factor per sweep is
/// stagnating (Gauss–Seidel does not converge on every ordering of every
/// chain: an iteration matrix with eigenvalues of modulus 1 besides 1).
const STAGNATION: f64 = 0.9995;
/// Smallest ω tried.
const MIN_OMEGA: f64 = 0.5;

/// Whether a window of factor `rate` per sweep converges faster than one
/// of factor `than`, by [`GAIN`].
fn faster(rate: f64, than: f64) -> bool {
    rate < 1.0 && (than >= 1.0 || -rate.ln() > -than.ln() * GAIN)
}

impl Relaxation {
    fn new(fixed: Option<f64>) -> Relaxation {
        Relaxation {
            omega: fixed.unwrap_or(1.0),
            fixed: fixed.is_some(),
            at: 0,
            window_start: f64::NAN,
            best: None,
            step: 0.0,
            history: vec![(fixed.unwrap_or(1.0), 0)],
        }
    }

    fn set(&mut self, omega: f64, proxy: f64) {
        self.omega = (omega * 100.0).round() / 100.0;
        self.at = 0;
        self.window_start = proxy;
        self.history.push((self.omega, 0));
    }

    /// Takes the proxy residual after a sweep, and whether the iterate is
    /// positive; may change ω.
    fn observe(&mut self, proxy: f64, positive: bool) {
        if let Some(h) = self.history.last_mut() {
            h.1 += 1;
        }
        if self.fixed {
            return;
        }
        if !positive && self.omega > 1.0 {
            // Over-relaxation went too far: back to Gauss–Seidel for good.
            self.step = 0.0;
            self.best = Some((1.0, 1.0));
            self.set(1.0, proxy);
            return;
        }
        self.at += 1;
        let settle = if self.best.is_none() { WARMUP } else { SETTLE };
        if self.at == settle {
            self.window_start = proxy;
        }
        if self.at < settle + WINDOW {
            return;
        }
        let rate = (proxy / self.window_start).powf(1.0 / WINDOW as f64);
        self.at = settle;
        self.window_start = proxy;
        let rate = if rate.is_nan() { f64::INFINITY } else { rate };
        match self.best {
            None => {
                // The first window, at ω = 1: up if it converges, down if not.
                self.best = Some((self.omega, rate));
                self.step = if rate < STAGNATION {
                    OMEGA_STEP
                } else {
                    -OMEGA_STEP
                };
                self.set(self.omega + self.step, proxy);
            }
            Some((w, r)) if self.step != 0.0 => {
                let next = self.omega + self.step;
                if faster(rate, r) && (MIN_OMEGA - 1e-9..=MAX_OMEGA + 1e-9).contains(&next) {
                    self.best = Some((self.omega, rate));
                    self.set(next, proxy);
                } else if faster(rate, r) {
                    self.best = Some((self.omega, rate));
                    self.step = 0.0;
                } else {
                    self.step = 0.0;
                    self.set(w, proxy);
                }
            }
            Some(_) => {
                // Settled: a window that does not converge lowers ω.
                if rate >= STAGNATION && self.omega - OMEGA_STEP >= MIN_OMEGA {
                    self.best = Some((self.omega - OMEGA_STEP, rate));
                    self.set(self.omega - OMEGA_STEP, proxy);
                }
            }
        }
    }
}

/// Sweeps until the residual is at most the tolerance; every
/// [`AGGREGATE_EVERY`] sweeps, one aggregation step per component (when
/// `aggregate` gives the descriptor and the scaled rates, and the iterate
/// is positive: SOR may leave negative entries, on which the coarse chains
/// are not chains).
fn iterate(
    plan: &Plan<'_>,
    x: &mut [f64],
    params: &SolveParams,
    fixed: Option<f64>,
    stop: Interrupt<'_>,
    aggregate: Option<(&Descriptor, &[f64])>,
) -> Result<Run> {
    let mut relax = Relaxation::new(fixed);
    let mut last = f64::INFINITY;
    let mut aggregate = aggregate;
    let mut aggregations = 0;
    let mut positive = true;
    for it in 1..=params.max_iterations {
        stop.check(SOLVING)?;
        if let Some((desc, rates)) = aggregate.filter(|_| positive && it % AGGREGATE_EVERY == 0) {
            for level in 0..desc.levels() {
                if crate::aggregation::correct(desc, rates, x, level).is_err() {
                    // A coarse chain the solver refuses: go on without.
                    aggregate = None;
                    break;
                }
            }
            aggregations += 1;
        }
        let sums = plan.sweep(x, relax.omega);
        if !(sums.total.is_finite() && sums.total > 0.0) {
            break;
        }
        positive = sums.min > 0.0;
        if !(1e-200..=1e200).contains(&sums.total) {
            let s = 1.0 / sums.total;
            x.iter_mut().for_each(|v| *v *= s);
        }
        let proxy = if sums.flow > 0.0 {
            sums.imbalance / sums.flow
        } else {
            sums.imbalance
        };
        stop.iterated(it, proxy);
        relax.observe(proxy, positive);
        if proxy <= params.tolerance {
            let r = plan.residual(x);
            last = if r.flow > 0.0 {
                r.imbalance / r.flow
            } else {
                r.imbalance
            };
            if last <= params.tolerance {
                return Ok(Run {
                    sweeps: it,
                    omega: relax.omega,
                    history: relax.history,
                    aggregations,
                });
            }
        } else {
            last = proxy;
        }
        if !last.is_finite() {
            break;
        }
    }
    Err(Error::NoConvergence {
        solver: "structured SOR",
        iterations: params.max_iterations,
        residual: last,
        tolerance: params.tolerance,
    })
}
