//! Discrete-event stochastic simulation of a GSPN, estimating the same
//! long-run measures as the analytic solver — mean tokens, probability that a
//! place is marked, throughputs, user measures — with confidence intervals.
//! Used to cross-check the solver, and for nets too large (or unbounded) to
//! solve.
//!
//! ```
//! use petri::{Expr, Net, Params};
//! use petri::simulation::{simulate, SimParams};
//!
//! // M/M/1/3: arrivals at rate 1 while the queue holds fewer than 3, service at rate 2.
//! let mut net = Net::new("mm13");
//! let q = net.add_place("queue", 0u32);
//! let arrive = net.add_timed("arrive", 1.0);
//! let serve = net.add_timed("serve", 2.0);
//! net.output(arrive, q);
//! net.add_arc(petri::ArcKind::Inhibitor, q, arrive, 3u32);
//! net.input(q, serve);
//! let gspn = net.instantiate(&Params::new())?;
//! let rates = gspn.rates(&Params::new(), None)?;
//!
//! let params = SimParams { warmup: 100.0, seed: 7, ..SimParams::new(20_000.0) };
//! let result = simulate(&gspn, &rates, &[], &params)?;
//! let busy = result.prob_nonempty[q.index()];
//! // P{n > 0} = 1 − P{0} = 1 − (1 − ρ)/(1 − ρ⁴) with ρ = ½, i.e. 7/15.
//! assert!((busy.mean - 7.0 / 15.0).abs() < 4.0 * busy.half_width);
//! # Ok::<(), petri::Error>(())
//! ```
//!
//! # The run
//!
//! The simulation starts in the initial marking at time 0 and follows the
//! GSPN semantics of [`Gspn::firable`]:
//!
//! - in a **vanishing** marking one of the enabled immediate transitions of
//!   the highest priority fires, in zero time, chosen with probability
//!   `w_t / Σ w`;
//! - in a **tangible** marking the enabled timed transitions race. With the
//!   total rate `R(M) = Σ_t λ_t · s_t(M)` (`s_t` the server factor of
//!   [`Gspn::server_factor`]), the marking is held for a time drawn from
//!   `Exp(R)` — by inversion, `−ln(1 − U)/R` with `U` uniform on `[0, 1)`, so
//!   `U = 0` gives 0, never `∞` — and then `t` fires with probability
//!   `λ_t s_t(M) / R`. By memorylessness this is exactly the race of
//!   independent exponential clocks, whatever the memory policy;
//! - a tangible marking in which nothing is enabled is **absorbing**
//!   (a dead marking): time runs on in it to the end of the run.
//!
//! A run is cut at [`SimParams::end_time`]; what happens before
//! [`SimParams::warmup`] is discarded to reduce the bias of the initial
//! marking.
//!
//! # Estimators
//!
//! For a function `f` of the marking (the tokens of a place, `[#p > 0]`, a
//! user measure) the long-run mean is estimated by its time average; for a
//! transition `t` the throughput by its number of firings per unit time
//! (immediate transitions included; a firing at a vanishing marking counts at
//! the time it happens).
//!
//! **Batch means** (default, [`SimParams::replications`] = 1): the measured
//! window `[w, T]` is split into `B` batches of equal length
//! `L = (T − w)/B`, `[b_{j−1}, b_j)`; a sojourn that straddles a boundary is
//! split exactly. Batch `j` gives one observation
//!
//! ```text
//! Y_j = (1/L) ∫_{b_{j−1}}^{b_j} f(M(s)) ds        or        Y_j = N_t[b_{j−1}, b_j) / L
//! ```
//!
//! **Independent replications** ([`SimParams::replications`] = `n ≥ 2`):
//! `n` runs from the initial marking, one after the other with the same
//! random stream (hence independent), each giving one observation over its
//! whole window `[w, T]`; [`SimParams::batches`] is then not used.
//!
//! Either way, from the `n` observations (`n = B` or the number of
//! replications), the point estimate, sample variance and half-width of the
//! `c`-level confidence interval are (e.g. Law, *Simulation Modeling and
//! Analysis*, 5th ed., §9.4.1 and §9.5.3)
//!
//! ```text
//! Ȳ = (1/n) Σ Y_j,   S² = 1/(n−1) Σ (Y_j − Ȳ)²,   h = t_{n−1, (1+c)/2} · S / √n
//! ```
//!
//! with `t_{ν, p}` the Student-t quantile ([`student_t_quantile`]); the
//! variance is accumulated with Welford's algorithm, so no observation is
//! stored and memory does not grow with `B`.
//!
//! # Assumptions
//!
//! The interval is exact when the observations are independent and normally
//! distributed. For batch means that holds only approximately, when each
//! batch is long compared with the time the process takes to forget its
//! state (its mixing time): keep `B` between about 10 and 30 and make the
//! run long, rather than increasing `B` (Schmeiser, "Batch size effects in
//! the analysis of simulation output", *Operations Research* 30(3), 1982).
//! Too short batches are positively correlated and give intervals that are
//! too narrow. Rare events (rates spanning orders of magnitude) need runs
//! much longer than the slowest time scale.
//!
//! The analytic long-run distribution of a non-ergodic net is the mixture
//! `Σ_B P(reach B from M0) · π_B` over its bottom strongly connected
//! components (dead markings included). One batch-means run estimates only
//! the behaviour of the component it happens to enter (its batches are then
//! equal or nearly so, and the interval is misleadingly narrow);
//! independent replications estimate the mixture. [`SimResult::absorbed_runs`]
//! tells how many runs ended in a dead marking.
//!
//! # Cost
//!
//! Per firing: [`Gspn::firable`] (linear in the number of transitions and
//! their arcs), two uniform draws from ChaCha8, the user measures evaluated
//! once per tangible marking entered, and time integrals updated lazily for
//! the places the firing changes only. The loop allocates nothing. The same
//! seed gives bit-identical results.

mod stats;

use std::ops::ControlFlow;
use std::time::Instant;

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::error::{Error, Result};
use crate::expr::CompiledExpr;
use crate::gspn::{Gspn, MarkingKind};
use crate::net::TransitionId;

pub use stats::student_t_quantile;

/// Firings between two looks at the clock and at the observer of
/// [`simulate_observed`] (a power of two; some milliseconds of simulation).
pub const CHECK_EVERY: u64 = 1 << 16;

/// Where a running simulation is, as reported to the observer of
/// [`simulate_observed`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimProgress {
    /// Firings so far, all runs.
    pub events: u64,
    /// The current run, from 1.
    pub run: usize,
    /// Number of runs ([`SimParams::replications`]).
    pub runs: usize,
    /// Simulated time within the current run.
    pub time: f64,
    /// End time of each run ([`SimParams::end_time`]).
    pub end_time: f64,
}

impl SimProgress {
    /// Share of the whole simulated time done, in [0, 1].
    pub fn fraction(&self) -> f64 {
        let done =
            (self.run.saturating_sub(1) as f64 + (self.time / self.end_time).min(1.0)) / self.runs as f64;
        done.clamp(0.0, 1.0)
    }

    /// Firings the whole simulation would need at the rate seen so far
    /// (infinite before any simulated time has passed).
    pub fn projected_events(&self) -> f64 {
        let f = self.fraction();
        if f > 0.0 {
            self.events as f64 / f
        } else {
            f64::INFINITY
        }
    }
}

/// The largest [`SimParams::batches`] and [`SimParams::replications`]
/// accepted: far beyond what makes statistical sense, low enough that a typo
/// cannot make a run spin on boundaries.
pub const MAX_OBSERVATIONS: usize = 1_000_000;

/// Parameters of a simulation. Build with [`SimParams::new`] (or set
/// [`end_time`](SimParams::end_time) on the [`Default`]); all times are in
/// the time unit of the net's rates.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct SimParams {
    /// Length of each run, from time 0, in simulated time units (the inverse
    /// of the rates' unit). **No default**: the default value 0 is rejected;
    /// it must be a finite number `> warmup`.
    pub end_time: f64,
    /// Initial part of each run discarded before measuring, in simulated time
    /// units. Default 0; must be finite, `≥ 0` and `< end_time`.
    pub warmup: f64,
    /// Number of batches `B` the measured window `[warmup, end_time]` is cut
    /// into for batch means (with `replications` = 1). Default 20; at least
    /// 2, at most [`MAX_OBSERVATIONS`].
    pub batches: usize,
    /// Number of independent runs. Default 1, meaning one run analysed by
    /// batch means; with `n ≥ 2` each run gives one observation and
    /// `batches` is not used. At most [`MAX_OBSERVATIONS`].
    pub replications: usize,
    /// Level of the confidence intervals, a probability. Default 0.95; must
    /// be strictly between 0 and 1.
    pub confidence: f64,
    /// Seed of the random stream (ChaCha8). Default 0. Same seed, same
    /// results, bit for bit.
    pub seed: u64,
    /// Safety cap on the number of transition firings over all runs (timed
    /// and immediate, warmup included). Reaching it is an error,
    /// [`Error::EventLimit`], not a silent truncation (a truncated window
    /// would bias the batches). Default 10⁹; at least 1.
    pub max_events: u64,
    /// This many immediate firings in a row, without time advancing, is taken
    /// to be a timeless trap ([`Error::TimelessTrap`]). Default 10⁶; at least 1.
    pub max_immediate_chain: u64,
    /// Wall-clock budget of the whole simulation, seconds; `None` (the
    /// default) for none. Checked every [`CHECK_EVERY`] firings; running
    /// out is an error, [`Error::WallTimeLimit`], which tells how many
    /// firings the runs would need at the rate seen so far. Must be finite
    /// and > 0.
    pub max_wall_s: Option<f64>,
}

impl Default for SimParams {
    fn default() -> Self {
        SimParams {
            end_time: 0.0,
            warmup: 0.0,
            batches: 20,
            replications: 1,
            confidence: 0.95,
            seed: 0,
            max_events: 1_000_000_000,
            max_immediate_chain: 1_000_000,
            max_wall_s: None,
        }
    }
}

impl SimParams {
    /// The defaults, with runs of length `end_time` (simulated time units).
    pub fn new(end_time: f64) -> SimParams {
        SimParams {
            end_time,
            ..SimParams::default()
        }
    }

    /// Checks every field against the rules documented on it.
    pub fn validate(&self) -> Result<()> {
        let bad = |what: &'static str, requirement: &'static str, value: f64| Error::InvalidValue {
            element: "the simulation parameters".into(),
            what,
            requirement,
            value,
        };
        if !(self.end_time.is_finite() && self.end_time > 0.0) {
            return Err(bad(
                "`end_time`",
                "a finite number of time units > 0 (it has no default)",
                self.end_time,
            ));
        }
        if !(self.warmup.is_finite() && self.warmup >= 0.0 && self.warmup < self.end_time) {
            return Err(bad(
                "`warmup`",
                "a finite number ≥ 0 and < `end_time`",
                self.warmup,
            ));
        }
        if !(1..=MAX_OBSERVATIONS).contains(&self.replications) {
            return Err(bad(
                "`replications`",
                "a whole number from 1 to 1000000",
                self.replications as f64,
            ));
        }
        let batches = if self.replications == 1 {
            if !(2..=MAX_OBSERVATIONS).contains(&self.batches) {
                return Err(bad(
                    "`batches`",
                    "a whole number from 2 to 1000000",
                    self.batches as f64,
                ));
            }
            self.batches
        } else {
            1
        };
        if !(self.confidence > 0.0 && self.confidence < 1.0) {
            return Err(bad("`confidence`", "strictly between 0 and 1", self.confidence));
        }
        if self.max_events == 0 {
            return Err(bad("`max_events`", "at least 1", 0.0));
        }
        if self.max_immediate_chain == 0 {
            return Err(bad("`max_immediate_chain`", "at least 1", 0.0));
        }
        if let Some(w) = self.max_wall_s {
            if !(w.is_finite() && w > 0.0) {
                return Err(bad("`max_wall_s`", "a finite number of seconds > 0", w));
            }
        }
        // Batch boundaries must be distinct numbers (not so with a huge
        // warmup and a tiny window, in floating point).
        let window = Window::new(self.warmup, self.end_time, batches);
        let mut previous = window.bound(0);
        for k in 1..=batches {
            let b = window.bound(k);
            if b <= previous {
                return Err(bad(
                    "`batches`",
                    "small enough that the batch boundaries are distinct floating-point numbers",
                    batches as f64,
                ));
            }
            previous = b;
        }
        Ok(())
    }
}

/// A point estimate with its confidence interval `mean ± half_width`.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Estimate {
    /// The point estimate: mean of the batch (or replication) means.
    pub mean: f64,
    /// Half-width of the confidence interval at the level of
    /// [`SimResult::confidence`].
    pub half_width: f64,
    /// Number of observations (batches, or replications) it comes from.
    pub batches: usize,
}

impl Estimate {
    /// Whether `x` lies in the confidence interval.
    pub fn contains(&self, x: f64) -> bool {
        (x - self.mean).abs() <= self.half_width
    }

    /// Lower end of the interval.
    pub fn low(&self) -> f64 {
        self.mean - self.half_width
    }

    /// Upper end of the interval.
    pub fn high(&self) -> f64 {
        self.mean + self.half_width
    }
}

/// What a simulation estimated. Vectors are indexed by
/// [`PlaceId`](crate::PlaceId) or [`TransitionId`].
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct SimResult {
    /// Place names, by place index.
    pub place_names: Vec<String>,
    /// Transition names, by transition index.
    pub transition_names: Vec<String>,
    /// Long-run mean number of tokens `E[#p]` of each place.
    pub places: Vec<Estimate>,
    /// Long-run probability `P{#p > 0}` of each place.
    pub prob_nonempty: Vec<Estimate>,
    /// Throughput of each transition (timed and immediate): firings per time
    /// unit.
    pub throughputs: Vec<Estimate>,
    /// Long-run mean of each user measure (a probability for a condition),
    /// in the order given.
    pub measures: Vec<(String, Estimate)>,
    /// Transition firings, all runs, warmup included.
    pub events: u64,
    /// Simulated time, all runs, warmup included (`replications · end_time`).
    pub simulated_time: f64,
    /// Simulated time the estimates are based on
    /// (`replications · (end_time − warmup)`).
    pub measured_time: f64,
    /// Level of the confidence intervals.
    pub confidence: f64,
    /// Number of runs (1 with batch means).
    pub replications: usize,
    /// Runs that ended in a dead marking (nothing enabled) before `end_time`.
    pub absorbed_runs: usize,
}

impl SimResult {
    /// The mean-tokens estimate of the place called `name`.
    pub fn place(&self, name: &str) -> Option<&Estimate> {
        let i = self.place_names.iter().position(|n| n == name)?;
        self.places.get(i)
    }

    /// The throughput estimate of the transition called `name`.
    pub fn throughput(&self, name: &str) -> Option<&Estimate> {
        let i = self.transition_names.iter().position(|n| n == name)?;
        self.throughputs.get(i)
    }

    /// The estimate of the user measure called `name`.
    pub fn measure(&self, name: &str) -> Option<&Estimate> {
        self.measures.iter().find(|(n, _)| n == name).map(|(_, e)| e)
    }
}

/// Simulates `gspn` with `rates` (one per transition, as given by
/// [`Gspn::rates`]: the rate of each timed transition, finite and `> 0`;
/// entries of immediate transitions are ignored) and estimates the long-run
/// mean of every place, the probability that it is marked, the throughput of
/// every transition and the long-run mean of every `measure` (compiled for
/// this net's place indices). See the [module docs](self) for the method.
///
/// Errors: invalid `params` or `rates` ([`Error::InvalidValue`],
/// [`Error::Invalid`]), a timeless trap ([`Error::TimelessTrap`]), too many
/// firings ([`Error::EventLimit`]), a token count beyond `u32`
/// ([`Error::TokenOverflow`]).
pub fn simulate(
    gspn: &Gspn,
    rates: &[f64],
    measures: &[(String, CompiledExpr)],
    params: &SimParams,
) -> Result<SimResult> {
    simulate_observed(gspn, rates, measures, params, &mut |_| ControlFlow::Continue(()))
}

/// [`simulate`], showing `observer` where the simulation is every
/// [`CHECK_EVERY`] firings (for a progress bar); the observer returning
/// [`ControlFlow::Break`] stops the simulation with [`Error::Interrupted`]
/// (for Ctrl-C). A stopped simulation gives no estimates: its batches would
/// not cover the window they stand for. The results do not depend on the
/// observer.
///
/// Errors: those of [`simulate`], [`Error::Interrupted`],
/// [`Error::WallTimeLimit`] when [`SimParams::max_wall_s`] runs out, and
/// [`Error::NotFinite`] when an estimate is not a finite number (token
/// counts or rates so large that their time integrals overflow, a measure
/// that divides by zero).
pub fn simulate_observed(
    gspn: &Gspn,
    rates: &[f64],
    measures: &[(String, CompiledExpr)],
    params: &SimParams,
    observer: &mut dyn FnMut(&SimProgress) -> ControlFlow<()>,
) -> Result<SimResult> {
    params.validate()?;
    let weights = race_weights(gspn, rates)?;
    let mut sim = Simulator::new(gspn, &weights, measures, params, observer);
    let mut rng = ChaCha8Rng::seed_from_u64(params.seed);
    if params.replications == 1 {
        sim.run(&mut rng, params.batches)?;
    } else {
        for _ in 0..params.replications {
            sim.run(&mut rng, 1)?;
        }
    }

    let t_value = stats::t_critical(params.confidence, (sim.stats.observations - 1) as f64);
    let estimate = |w: &stats::Welford| Estimate {
        mean: w.mean,
        half_width: t_value * (w.variance() / w.n as f64).sqrt(),
        batches: w.n,
    };
    let reps = params.replications as f64;
    let finite = |what: &str, names: &[String], estimates: &[stats::Welford]| -> Result<()> {
        for (name, w) in names.iter().zip(estimates) {
            let e = estimate(w);
            for (part, v) in [("estimate", e.mean), ("confidence interval", e.half_width)] {
                if !v.is_finite() {
                    return Err(Error::NotFinite {
                        what: format!("the {part} of {what} `{name}`"),
                        value: v,
                        cause: "its time integral overflows double precision (huge token counts or run length), or the measure divides by zero".into(),
                    });
                }
            }
        }
        Ok(())
    };
    finite("the mean tokens of place", gspn.place_names(), &sim.stats.tokens)?;
    finite(
        "the throughput of transition",
        gspn.transition_names(),
        &sim.stats.throughput,
    )?;
    let measure_names: Vec<String> = measures.iter().map(|(n, _)| n.clone()).collect();
    finite("the measure", &measure_names, &sim.stats.measures)?;
    Ok(SimResult {
        place_names: gspn.place_names().to_vec(),
        transition_names: gspn.transition_names().to_vec(),
        places: sim.stats.tokens.iter().map(estimate).collect(),
        prob_nonempty: sim.stats.nonempty.iter().map(estimate).collect(),
        throughputs: sim.stats.throughput.iter().map(estimate).collect(),
        measures: measures
            .iter()
            .zip(&sim.stats.measures)
            .map(|((name, _), w)| (name.clone(), estimate(w)))
            .collect(),
        events: sim.events,
        simulated_time: reps * params.end_time,
        measured_time: reps * (params.end_time - params.warmup),
        confidence: params.confidence,
        replications: params.replications,
        absorbed_runs: sim.absorbed_runs,
    })
}

/// What each firable transition weighs in the random choice: its rate for a
/// timed transition (times the server factor), its weight for an immediate
/// one. Checks the rates.
fn race_weights(gspn: &Gspn, rates: &[f64]) -> Result<Vec<f64>> {
    if rates.len() != gspn.num_transitions() {
        return Err(Error::Invalid(format!(
            "the simulation got {} rates for a net with {} transitions (one per transition is expected, as given by Gspn::rates)",
            rates.len(),
            gspn.num_transitions()
        )));
    }
    (0..gspn.num_transitions())
        .map(|i| {
            let t = TransitionId(i as u32);
            match gspn.weight(t) {
                Some(w) => Ok(w),
                None => {
                    let r = rates[i];
                    if r.is_finite() && r > 0.0 {
                        Ok(r)
                    } else {
                        Err(Error::InvalidValue {
                            element: format!("timed transition `{}`", gspn.transition_names()[i]),
                            what: "the rate",
                            requirement: "a finite number > 0",
                            value: r,
                        })
                    }
                }
            }
        })
        .collect()
}

/// The batch boundaries of one run: `bound(0)` = warmup, `bound(B)` = end.
#[derive(Debug, Clone, Copy)]
struct Window {
    warmup: f64,
    end: f64,
    batches: usize,
}

impl Window {
    fn new(warmup: f64, end: f64, batches: usize) -> Window {
        Window { warmup, end, batches }
    }

    #[inline]
    fn bound(&self, k: usize) -> f64 {
        if k == 0 {
            self.warmup
        } else if k >= self.batches {
            self.end
        } else {
            self.warmup + (self.end - self.warmup) * (k as f64 / self.batches as f64)
        }
    }
}

/// Running statistics of the observations (batch or replication means).
#[derive(Debug, Default)]
struct Observations {
    observations: usize,
    tokens: Vec<stats::Welford>,
    nonempty: Vec<stats::Welford>,
    throughput: Vec<stats::Welford>,
    measures: Vec<stats::Welford>,
}

/// The simulator's state and reusable buffers.
struct Simulator<'a> {
    gspn: &'a Gspn,
    /// Rate (timed) or weight (immediate) of each transition.
    weights: &'a [f64],
    measures: &'a [(String, CompiledExpr)],
    max_events: u64,
    max_chain: u64,
    warmup: f64,
    end: f64,

    marking: Vec<u32>,
    firable: Vec<TransitionId>,
    /// Cumulative weights of `firable`.
    cumulative: Vec<f64>,
    stack: Vec<f64>,

    // Integrals over the current batch.
    /// `∫ #p` up to `last[p]`.
    tokens: Vec<f64>,
    /// `∫ [#p > 0]` up to `last[p]`.
    nonempty: Vec<f64>,
    /// Time up to which place `p` is integrated (updated lazily, when `p`
    /// changes and at batch boundaries).
    last: Vec<f64>,
    fired: Vec<u64>,
    /// Values of the measures in the current tangible marking.
    measure_values: Vec<f64>,
    /// `∫ measure` up to `measure_last`.
    measure_integrals: Vec<f64>,
    measure_last: f64,

    stats: Observations,
    events: u64,
    absorbed_runs: usize,

    /// The current run, from 1, of `runs`.
    run: usize,
    runs: usize,
    started: Instant,
    max_wall_s: Option<f64>,
    observer: &'a mut dyn FnMut(&SimProgress) -> ControlFlow<()>,
}

impl<'a> Simulator<'a> {
    fn new(
        gspn: &'a Gspn,
        weights: &'a [f64],
        measures: &'a [(String, CompiledExpr)],
        params: &SimParams,
        observer: &'a mut dyn FnMut(&SimProgress) -> ControlFlow<()>,
    ) -> Self {
        let (np, nt, nm) = (gspn.num_places(), gspn.num_transitions(), measures.len());
        Simulator {
            gspn,
            weights,
            measures,
            max_events: params.max_events,
            max_chain: params.max_immediate_chain,
            warmup: params.warmup,
            end: params.end_time,
            marking: gspn.initial_marking().to_vec(),
            firable: Vec::with_capacity(nt),
            cumulative: Vec::with_capacity(nt),
            stack: Vec::with_capacity(16),
            tokens: vec![0.0; np],
            nonempty: vec![0.0; np],
            last: vec![0.0; np],
            fired: vec![0; nt],
            measure_values: vec![0.0; nm],
            measure_integrals: vec![0.0; nm],
            measure_last: 0.0,
            stats: Observations {
                observations: 0,
                tokens: vec![stats::Welford::default(); np],
                nonempty: vec![stats::Welford::default(); np],
                throughput: vec![stats::Welford::default(); nt],
                measures: vec![stats::Welford::default(); nm],
            },
            events: 0,
            absorbed_runs: 0,
            run: 0,
            runs: params.replications,
            started: Instant::now(),
            max_wall_s: params.max_wall_s,
            observer,
        }
    }

    /// Every [`CHECK_EVERY`] firings: the wall-clock budget and the
    /// observer.
    #[cold]
    fn checkpoint(&mut self, now: f64) -> Result<()> {
        let progress = SimProgress {
            events: self.events,
            run: self.run,
            runs: self.runs,
            time: now,
            end_time: self.end,
        };
        if let Some(limit_s) = self.max_wall_s {
            if self.started.elapsed().as_secs_f64() > limit_s {
                return Err(Error::WallTimeLimit {
                    limit_s,
                    events: self.events,
                    time: now,
                    run: self.run,
                    end_time: self.end,
                    projected: progress.projected_events(),
                });
            }
        }
        if (self.observer)(&progress).is_break() {
            return Err(Error::Interrupted {
                events: self.events,
                time: now,
                run: self.run,
                end_time: self.end,
            });
        }
        Ok(())
    }

    /// One run from the initial marking over `[0, end]`, adding `batches`
    /// observations.
    fn run(&mut self, rng: &mut ChaCha8Rng, batches: usize) -> Result<()> {
        let window = Window::new(self.warmup, self.end, batches);
        self.run += 1;
        self.marking.copy_from_slice(self.gspn.initial_marking());
        let mut now = 0.0;
        // Index of the next boundary to cross: 0 is the end of the warmup,
        // k ≥ 1 the end of batch k. Measuring while it is ≥ 1.
        let mut next_k = 0;
        let mut next_bound = window.bound(0);
        while next_k <= batches && next_bound <= now {
            self.cross(&window, next_k);
            next_k += 1;
            next_bound = window.bound(next_k);
        }
        let mut chain = 0u64;
        loop {
            let kind = self.gspn.firable_decided(&self.marking, &mut self.firable)?;
            let measuring = next_k >= 1;
            match kind {
                MarkingKind::Vanishing => {
                    chain += 1;
                    if chain > self.max_chain {
                        return Err(self.timeless_trap(rng));
                    }
                    let total = self.accumulate_weights(false);
                    let t = self.pick(rng.random::<f64>() * total);
                    self.fire(t, now, measuring)?;
                }
                MarkingKind::Tangible => {
                    chain = 0;
                    for (v, (_, e)) in self.measure_values.iter_mut().zip(self.measures) {
                        *v = e.eval(&self.marking, &mut self.stack);
                    }
                    let total = self.accumulate_weights(true);
                    let next = if self.firable.is_empty() {
                        f64::INFINITY
                    } else {
                        // Exp(total) by inversion; 1 − U ∈ (0, 1].
                        now - (-rng.random::<f64>()).ln_1p() / total
                    };
                    while next_k <= batches && next_bound <= next {
                        self.cross(&window, next_k);
                        next_k += 1;
                        next_bound = window.bound(next_k);
                    }
                    if next_k > batches {
                        if self.firable.is_empty() {
                            self.absorbed_runs += 1;
                        }
                        return Ok(());
                    }
                    let t = self.pick(rng.random::<f64>() * total);
                    let measuring = next_k >= 1;
                    if measuring {
                        let dt = next - self.measure_last;
                        for (acc, v) in self.measure_integrals.iter_mut().zip(&self.measure_values) {
                            *acc += v * dt;
                        }
                        self.measure_last = next;
                    }
                    now = next;
                    self.fire(t, now, measuring)?;
                }
            }
        }
    }

    /// Fills `cumulative` with the running sums of the firable transitions'
    /// weights (rates times server factors when `timed`) and returns the
    /// total.
    #[inline]
    fn accumulate_weights(&mut self, timed: bool) -> f64 {
        self.cumulative.clear();
        let mut total = 0.0;
        for &t in &self.firable {
            let mut w = self.weights[t.index()];
            if timed {
                w *= self.gspn.server_factor(t, &self.marking);
            }
            total += w;
            self.cumulative.push(total);
        }
        total
    }

    /// The firable transition whose cumulative-weight interval holds
    /// `target` (the last one if rounding puts `target` at the total).
    #[inline]
    fn pick(&self, target: f64) -> TransitionId {
        let i = self
            .cumulative
            .iter()
            .position(|&c| target < c)
            .unwrap_or(self.cumulative.len().saturating_sub(1));
        self.firable[i]
    }

    /// Fires `t` at time `now`, integrating the places it changes first.
    #[inline]
    fn fire(&mut self, t: TransitionId, now: f64, measuring: bool) -> Result<()> {
        if self.events >= self.max_events {
            return Err(Error::EventLimit {
                limit: self.max_events,
                time: now,
                end_time: self.end,
            });
        }
        if measuring {
            self.fired[t.index()] += 1;
            for &(p, _) in self.gspn.delta(t) {
                let p = p as usize;
                let dt = now - self.last[p];
                let m = self.marking[p];
                self.tokens[p] += f64::from(m) * dt;
                if m > 0 {
                    self.nonempty[p] += dt;
                }
                self.last[p] = now;
            }
        }
        self.gspn.fire(t, &mut self.marking)?;
        self.events += 1;
        if self.events % CHECK_EVERY == 0 {
            self.checkpoint(now)?;
        }
        Ok(())
    }

    /// Crosses boundary `k` of `window` (at its time): the end of the warmup
    /// (`k = 0`) starts measuring; the end of batch `k ≥ 1` records its
    /// means. Either way the integrals restart there.
    fn cross(&mut self, window: &Window, k: usize) {
        let b = window.bound(k);
        if k >= 1 {
            let len = b - window.bound(k - 1);
            for p in 0..self.marking.len() {
                let dt = b - self.last[p];
                let m = self.marking[p];
                let tokens = self.tokens[p] + f64::from(m) * dt;
                let nonempty = self.nonempty[p] + if m > 0 { dt } else { 0.0 };
                self.stats.tokens[p].push(tokens / len);
                self.stats.nonempty[p].push(nonempty / len);
            }
            for (w, &n) in self.stats.throughput.iter_mut().zip(&self.fired) {
                w.push(n as f64 / len);
            }
            let dt = b - self.measure_last;
            for ((w, acc), v) in self
                .stats
                .measures
                .iter_mut()
                .zip(&self.measure_integrals)
                .zip(&self.measure_values)
            {
                w.push((acc + v * dt) / len);
            }
            self.stats.observations += 1;
        }
        self.tokens.fill(0.0);
        self.nonempty.fill(0.0);
        self.last.fill(b);
        self.fired.fill(0);
        self.measure_integrals.fill(0.0);
        self.measure_last = b;
    }

    /// The error for a chain of immediate firings that reached the limit:
    /// walks on a little to report the vanishing markings it cycles through.
    fn timeless_trap(&mut self, rng: &mut ChaCha8Rng) -> Error {
        const STEPS: usize = 4096;
        const DISTINCT: usize = 64;
        const SHOWN: usize = 3;
        let mut seen: Vec<Vec<u32>> = Vec::new();
        for _ in 0..STEPS {
            let kind = self.gspn.firable_resolved(&self.marking, &mut self.firable);
            if kind.unwrap_or(MarkingKind::Tangible) != MarkingKind::Vanishing {
                break;
            }
            if seen.len() < DISTINCT && !seen.contains(&self.marking) {
                seen.push(self.marking.clone());
            }
            let total = self.accumulate_weights(false);
            let t = self.pick(rng.random::<f64>() * total);
            if self.gspn.fire(t, &mut self.marking).is_err() {
                break;
            }
        }
        if seen.is_empty() {
            seen.push(self.marking.clone());
        }
        let shown: Vec<String> = seen
            .iter()
            .take(SHOWN)
            .map(|m| self.gspn.format_marking(m))
            .collect();
        let more = if seen.len() > SHOWN { "; …" } else { "" };
        Error::TimelessTrap {
            count: seen.len(),
            markings: format!(
                "{}{more} (seen after {} immediate firings in a row in the simulation)",
                shown.join("; "),
                self.max_chain
            ),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Expr, Net, Params};

    fn two_state() -> (Gspn, Vec<f64>) {
        let mut n = Net::new("flip");
        let a = n.add_place("a", 1u32);
        let b = n.add_place("b", 0u32);
        let ab = n.add_timed("ab", 1.0);
        let ba = n.add_timed("ba", 3.0);
        n.input(a, ab);
        n.output(ab, b);
        n.input(b, ba);
        n.output(ba, a);
        let g = n.instantiate(&Params::new()).unwrap();
        let r = g.rates(&Params::new(), None).unwrap();
        (g, r)
    }

    #[test]
    fn boundaries_are_exact_at_both_ends() {
        let w = Window::new(0.1, 0.7, 3);
        assert_eq!(w.bound(0), 0.1);
        assert_eq!(w.bound(3), 0.7);
        assert!(w.bound(1) < w.bound(2));
    }

    #[test]
    fn straddling_sojourns_are_split_so_batch_integrals_add_up() {
        // Sum over batches of (mean × length) equals the total occupation time,
        // which equals the measured window for a conserved single token.
        let (g, r) = two_state();
        let p = SimParams {
            batches: 7,
            warmup: 3.3,
            seed: 3,
            ..SimParams::new(1000.0)
        };
        let res = simulate(&g, &r, &[], &p).unwrap();
        let total = res.places[0].mean + res.places[1].mean;
        assert!((total - 1.0).abs() < 1e-12, "{total}");
        // Two-state chain: P{a} = 3/4.
        assert!((res.places[0].mean - 0.75).abs() < 4.0 * res.places[0].half_width);
        // Flow balance: the two throughputs differ by at most one firing per batch.
        let d = (res.throughputs[0].mean - res.throughputs[1].mean).abs();
        assert!(d <= 1.0 / ((1000.0 - 3.3) / 7.0) + 1e-12, "{d}");
    }

    #[test]
    fn measures_are_time_averaged() {
        let (g, r) = two_state();
        let e = Expr::parse("2 * #b + 1")
            .unwrap()
            .compile(&|n| g.place(n).ok().map(|p| p.index()), &|_| None)
            .unwrap();
        let res = simulate(&g, &r, &[("m".into(), e)], &SimParams::new(500.0)).unwrap();
        let m = res.measure("m").unwrap();
        let b = res.place("b").unwrap();
        assert!((m.mean - (2.0 * b.mean + 1.0)).abs() < 1e-12);
        assert!((m.half_width - 2.0 * b.half_width).abs() < 1e-9);
        assert!(res.measure("zz").is_none());
    }
}
