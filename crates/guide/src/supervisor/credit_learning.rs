//! Learning the crediting supervisor's rates ([`super::credit`]) from the
//! mission log: every failure credited to the behaviour responsible, every
//! rate learnt per crowd context where the data show it matters.
//!
//! **What a mission leaves.** The guide controller cuts its mission into
//! [`Segment`]s: stretches with one behaviour in control, one localizer
//! state (localized or not), one planner state and one crowd context, each
//! with its duration, how it ended and — for the crediting supervisor's
//! own missions — the progress made towards the goal (the drop of the
//! remaining length along AutoMove's reference trajectory). Calibration
//! runs leave segments too (without progress).
//!
//! **Crowd context.** What the robot can see of the crowd: the unmapped
//! objects per scan (runs of beams ending short of the map,
//! [`localization::ScanConsistency::unmapped_objects`]), averaged
//! over about ten seconds ([`CrowdMeter`]), in three bins
//! ([`CROWD_BINS`]): *quiet* (< 2: nobody or a passer-by), *busy* (2–7:
//! a few people near), *crowded* (≥ 7). Measured on the museum's scans
//! with the true pose (`cargo run --release -p lab --example status_roc`):
//! median 5 objects with 25 visitors, 9 with 60.
//!
//! **Decision — who failed.** A mission that ended by a collision, by
//! arriving where the goal is not or by the lost watchdog failed in the
//! state it ended in: the failure is credited to the last segment's
//! behaviour, localizer state and context. A mission that ran out of time
//! failed because of all of it: one failure is shared among its segments
//! in proportion to their durations. The failure rate of a class is its
//! credited failures over its exposure time (the maximum-likelihood rate
//! of an exponential hazard).
//!
//! | rate | class |
//! |---|---|
//! | λ9 | AutoMove, planner Abnormal |
//! | λ12 | AutoMove, localizer Warning |
//! | λ13 | AutoMove, localized and Normal |
//! | λ10 | contour tracking, localizer Warning |
//! | λ14 | contour tracking, localized |
//! | λ3, λ4 | leaving Success, leaving Warning (per unit time in it) |
//! | λ5, λ6 | leaving Normal, leaving Abnormal (AutoMove's time) |
//! | λ7, λ8 | progress speed of each behaviour while localized over the remaining length |
//!
//! **Decision — per context, where the data show it.** Each rate is
//! estimated per context with one pseudo-event at a smoother rate:
//! `λ_c = (n_c + 1)/(T_c + 1/μ_c)`. A context with little exposure takes
//! the smoother's rate; one with much takes its own. For the localizer's
//! and the planner's rates (λ3–λ6) and AutoMove's Abnormal failures (λ9)
//! the smoother is the pooled rate (all contexts together, itself with one
//! pseudo-event at the model file's prior). For the rates that come in a
//! pair, one per behaviour — the failures while localized (λ13, λ14), the
//! failures in Warning (λ12, λ10) and the progress speeds (λ7, λ8) — the
//! smoother is a main-effects model, `μ_bc = a_b · g_c`: the crowd
//! multiplies both behaviours' rates alike unless their own data say
//! otherwise ([`main_effects`], fitted by iterative proportional fitting
//! with the prior spread over the contexts as one pseudo-event per
//! behaviour). Reason: a supervisor that has driven AutoMove through
//! crowds but contour tracking only in empty halls would otherwise take
//! contour tracking's empty-hall speed and safety for the crowd's — and
//! the museum day showed it starting missions in contour tracking among 60
//! visitors, where it fails (`crates/guide/EXPERIMENTS.md`).
//! Progress speeds likewise, with 30 s of pseudo-exposure at the model's
//! speed, the model having 30 s per behaviour at its calibration speed
//! (reference length over mean time). Nothing learnt is ever 0, infinite
//! or NaN.

use robot::Vec2;

use super::Behaviour;
use super::credit::CreditRates;
use super::learning::LearnError;
use super::log::Entry;
use super::reference::{MIN_REMAINING_S, Reference};

/// Unmapped objects per scan separating the crowd contexts: quiet below
/// the first, busy below the second, crowded from it on.
pub const CROWD_BINS: [f64; 2] = [2.0, 7.0];

/// Number of crowd contexts.
pub const CONTEXTS: usize = 3;

/// The contexts' names, in bin order.
pub const CONTEXT_NAMES: [&str; CONTEXTS] = ["quiet", "busy", "crowded"];

/// Pseudo-exposure of the speed estimates, seconds (module docs).
pub const SPEED_PRIOR_S: f64 = 30.0;

/// The context of a crowd measure (unmapped objects per scan).
pub fn crowd_context(objects: f64) -> usize {
    CROWD_BINS.iter().filter(|&&b| objects >= b).count()
}

/// A running mean of the unmapped objects per scan, over about
/// `window_s` seconds (an exponential average in time).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CrowdMeter {
    window_s: f64,
    mean: Option<f64>,
    last_s: f64,
}

impl CrowdMeter {
    /// A meter averaging over `window_s` seconds (> 0).
    pub fn new(window_s: f64) -> CrowdMeter {
        CrowdMeter {
            window_s: window_s.max(1e-3),
            mean: None,
            last_s: 0.0,
        }
    }

    /// Takes the objects counted on a scan at `time_s`.
    pub fn observe(&mut self, time_s: f64, objects: f64) {
        self.mean = Some(match self.mean {
            None => objects,
            Some(m) => {
                let a = 1.0 - (-(time_s - self.last_s).max(0.0) / self.window_s).exp();
                m + a * (objects - m)
            }
        });
        self.last_s = time_s;
    }

    /// The mean so far (0 before any scan).
    pub fn mean(&self) -> f64 {
        self.mean.unwrap_or(0.0)
    }

    /// The context of the mean.
    pub fn context(&self) -> usize {
        crowd_context(self.mean())
    }
}

/// How a segment ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SegmentEnd {
    /// The localizer changed state.
    Localizer,
    /// The planner changed state.
    Planner,
    /// The behaviour changed.
    Behaviour,
    /// The crowd context changed.
    Context,
    /// The mission ended.
    Mission,
}

/// A stretch of a mission in one state (module docs).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Segment {
    /// The behaviour in control.
    pub behaviour: Behaviour,
    /// The localizer in Success.
    pub localized: bool,
    /// AutoMove's planner Normal (always true for contour tracking).
    pub normal: bool,
    /// The crowd context (0 quiet, 1 busy, 2 crowded).
    pub context: usize,
    /// Duration, seconds.
    pub duration_s: f64,
    /// Progress towards the goal along AutoMove's reference, metres
    /// (`None` where there was no reference to measure it on).
    pub progress_m: Option<f64>,
    /// How it ended.
    pub end: SegmentEnd,
}

/// Time exposed and events (fractional: shared failures).
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct Exposure {
    /// Seconds.
    pub time_s: f64,
    /// Events.
    pub events: f64,
}

impl Exposure {
    fn add(&mut self, other: &Exposure) {
        self.time_s += other.time_s;
        self.events += other.events;
    }

    /// `(events + 1) / (time + 1/prior)`.
    pub fn rate(&self, prior: f64) -> f64 {
        (self.events + 1.0) / (self.time_s + 1.0 / prior)
    }
}

/// Index of the failure classes in [`ContextData::failures`].
const FAIL_AUTO_ABNORMAL: usize = 0;
const FAIL_CONT_WARNING: usize = 1;
const FAIL_AUTO_WARNING: usize = 2;
const FAIL_AUTO_OK: usize = 3;
const FAIL_CONT_OK: usize = 4;

/// The λ of each failure class.
const FAIL_RATE: [usize; 5] = [9, 10, 12, 13, 14];

fn failure_class(s: &Segment) -> usize {
    match (s.behaviour, s.localized, s.normal) {
        (Behaviour::AutoMove, false, _) => FAIL_AUTO_WARNING,
        (Behaviour::AutoMove, true, false) => FAIL_AUTO_ABNORMAL,
        (Behaviour::AutoMove, true, true) => FAIL_AUTO_OK,
        (Behaviour::Contour, false, _) => FAIL_CONT_WARNING,
        (Behaviour::Contour, true, _) => FAIL_CONT_OK,
    }
}

/// What the log says about one crowd context.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct ContextData {
    /// Localized time and exits to Warning.
    pub success: Exposure,
    /// Warning time and exits to Success.
    pub warning: Exposure,
    /// AutoMove's Normal time and exits to Abnormal.
    pub normal: Exposure,
    /// AutoMove's Abnormal time and exits to Normal.
    pub abnormal: Exposure,
    /// Per failure class (λ9, λ10, λ12, λ13, λ14): exposure and credited
    /// failures.
    pub failures: [Exposure; 5],
    /// Per behaviour (AutoMove, contour): localized time with progress
    /// measured, and the progress, metres.
    pub progress: [(f64, f64); 2],
}

impl ContextData {
    fn add(&mut self, o: &ContextData) {
        self.success.add(&o.success);
        self.warning.add(&o.warning);
        self.normal.add(&o.normal);
        self.abnormal.add(&o.abnormal);
        for (a, b) in self.failures.iter_mut().zip(&o.failures) {
            a.add(b);
        }
        for (a, b) in self.progress.iter_mut().zip(&o.progress) {
            a.0 += b.0;
            a.1 += b.1;
        }
    }
}

fn behaviour_index(b: Behaviour) -> usize {
    match b {
        Behaviour::AutoMove => 0,
        Behaviour::Contour => 1,
    }
}

/// What the crediting supervisor learnt from a log.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct CreditModel {
    /// Per context.
    pub contexts: [ContextData; CONTEXTS],
    /// All contexts together.
    pub pooled: ContextData,
    /// AutoMove's reference (its median calibration run): the remaining
    /// length is measured along it.
    pub reference: Reference,
    /// Calibration speed of each behaviour (AutoMove, contour): reference
    /// length over mean time, m/s.
    pub calibration_speed_mps: [f64; 2],
    /// Missions in the log, and how many reached the goal.
    pub missions: usize,
    /// Of which reached the goal.
    pub successes: usize,
}

fn check(what: &str, v: f64) -> Result<f64, LearnError> {
    if v.is_finite() && v >= 0.0 {
        Ok(v)
    } else {
        Err(LearnError::BadValue {
            what: what.to_string(),
            value: v,
        })
    }
}

impl CreditModel {
    /// Learns from the entries of a log (module docs). Needs a successful
    /// calibration run of each behaviour ([`LearnError::NoCalibration`]).
    pub fn learn(entries: &[Entry]) -> Result<CreditModel, LearnError> {
        CreditModel::learn_with(entries, false)
    }

    /// [`CreditModel::learn`], going on without a successful calibration
    /// run of a behaviour: its calibration speed is then the model file's
    /// prior (λ7 = 0.0082, λ8 = 0.0053 per second over the reference), and
    /// without a successful AutoMove run the reference is the longest
    /// calibration trajectory of either behaviour. Still an error without
    /// any calibration run.
    pub fn learn_or_prior(entries: &[Entry]) -> Result<CreditModel, LearnError> {
        CreditModel::learn_with(entries, true)
    }

    fn learn_with(entries: &[Entry], lenient: bool) -> Result<CreditModel, LearnError> {
        let (calibration, missions) = super::log::split_entries(entries);
        let reference = match super::learning::reference_of(&calibration, Behaviour::AutoMove) {
            Ok(r) => r,
            Err(LearnError::NoCalibration(b)) if lenient => {
                let longest = calibration
                    .iter()
                    .max_by(|a, b| a.trajectory.len().cmp(&b.trajectory.len()))
                    .ok_or(LearnError::NoCalibration(b))?;
                Reference {
                    mean_time_s: 1.0 / CreditRates::initial().get(7),
                    mean_speed_mps: 1e-3,
                    trajectory: longest.trajectory.iter().map(|p| Vec2::new(p[0], p[1])).collect(),
                }
            }
            Err(e) => return Err(e),
        };
        let length = reference.length_m().max(1e-3);
        let mut calibration_speed_mps = [0.0; 2];
        for (k, (b, prior)) in [(Behaviour::AutoMove, 7), (Behaviour::Contour, 8)]
            .into_iter()
            .enumerate()
        {
            let time = match super::learning::reference_of(&calibration, b) {
                Ok(r) => r.mean_time_s,
                Err(LearnError::NoCalibration(_)) if lenient => 1.0 / CreditRates::initial().get(prior),
                Err(e) => return Err(e),
            };
            calibration_speed_mps[k] = length / time.max(MIN_REMAINING_S);
        }
        let mut contexts = [ContextData::default(); CONTEXTS];
        for c in &calibration {
            credit(&mut contexts, &c.segments, &c.outcome, c.success)?;
        }
        for m in &missions {
            credit(&mut contexts, &m.segments, &m.outcome, m.success)?;
        }
        let mut pooled = ContextData::default();
        for c in &contexts {
            pooled.add(c);
        }
        Ok(CreditModel {
            contexts,
            pooled,
            reference,
            calibration_speed_mps,
            missions: missions.len(),
            successes: missions.iter().filter(|m| m.success).count(),
        })
    }

    /// The rates for a decision in crowd context `context`, `remaining_m`
    /// metres from the goal (along the reference).
    pub fn rates(&self, context: usize, remaining_m: f64) -> CreditRates {
        let prior = CreditRates::initial();
        let ctx = context.min(CONTEXTS - 1);
        let c = &self.contexts[ctx];
        let p = &self.pooled;
        let shrunk = |ctx: &Exposure, pool: &Exposure, prior_rate: f64| ctx.rate(pool.rate(prior_rate));
        let mut r = prior;
        let mut set = |i: usize, v: f64| {
            // Learnt rates are finite and > 0 by construction; keep the
            // prior should one not be.
            let _ = r.try_set(i, v);
        };
        set(3, shrunk(&c.success, &p.success, prior.get(3)));
        set(4, shrunk(&c.warning, &p.warning, prior.get(4)));
        set(5, shrunk(&c.normal, &p.normal, prior.get(5)));
        set(6, shrunk(&c.abnormal, &p.abnormal, prior.get(6)));
        set(
            9,
            shrunk(
                &c.failures[FAIL_AUTO_ABNORMAL],
                &p.failures[FAIL_AUTO_ABNORMAL],
                prior.get(9),
            ),
        );
        // Failure pairs: (AutoMove's class, contour's class).
        for (auto, cont) in [
            (FAIL_AUTO_OK, FAIL_CONT_OK),
            (FAIL_AUTO_WARNING, FAIL_CONT_WARNING),
        ] {
            let classes = [auto, cont];
            let table = |f: fn(&Exposure) -> f64| {
                classes.map(|k| std::array::from_fn(|j| f(&self.contexts[j].failures[k])))
            };
            let priors = classes.map(|k| prior.get(FAIL_RATE[k]));
            let mu = main_effects(
                table(|e| e.events),
                table(|e| e.time_s),
                priors.map(|r| (1.0, 1.0 / r)),
            );
            for (b, &k) in classes.iter().enumerate() {
                set(FAIL_RATE[k], c.failures[k].rate(mu[b][ctx]));
            }
        }
        let remaining = remaining_m.max(0.0);
        let progress = |f: fn(&(f64, f64)) -> f64| -> [[f64; CONTEXTS]; 2] {
            std::array::from_fn(|b| std::array::from_fn(|j| f(&self.contexts[j].progress[b])))
        };
        let v0 = self.calibration_speed_mps.map(|v| v.max(1e-3));
        let mu = main_effects(
            progress(|p| p.1.max(0.0)),
            progress(|p| p.0),
            v0.map(|v| (v * SPEED_PRIOR_S, SPEED_PRIOR_S)),
        );
        for (k, i) in [(0usize, 7usize), (1, 8)] {
            let (ct, cm) = c.progress[k];
            let v = ((cm + mu[k][ctx] * SPEED_PRIOR_S) / (ct + SPEED_PRIOR_S)).max(1e-3);
            set(i, 1.0 / (remaining / v).max(MIN_REMAINING_S));
        }
        // λ15 (the failure cost) stays the model's.
        r
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

/// Adds a run's segments and its credited failure to `contexts`.
fn credit(
    contexts: &mut [ContextData; CONTEXTS],
    segments: &[Segment],
    outcome: &str,
    success: bool,
) -> Result<(), LearnError> {
    for (k, s) in segments.iter().enumerate() {
        let d = check(&format!("segment {k} duration_s"), s.duration_s)?;
        let c = &mut contexts[s.context.min(CONTEXTS - 1)];
        let last = k + 1 == segments.len();
        let next = segments.get(k + 1);
        let changed_loc = s.end == SegmentEnd::Localizer || next.is_some_and(|n| n.localized != s.localized);
        let changed_plan = s.end == SegmentEnd::Planner || next.is_some_and(|n| n.normal != s.normal);
        let loc = if s.localized {
            &mut c.success
        } else {
            &mut c.warning
        };
        loc.time_s += d;
        if !last && changed_loc {
            loc.events += 1.0;
        }
        if s.behaviour == Behaviour::AutoMove {
            let plan = if s.normal { &mut c.normal } else { &mut c.abnormal };
            plan.time_s += d;
            if !last && changed_plan {
                plan.events += 1.0;
            }
        }
        c.failures[failure_class(s)].time_s += d;
        if let (true, Some(p)) = (s.localized, s.progress_m)
            && p.is_finite()
        {
            let b = behaviour_index(s.behaviour);
            c.progress[b].0 += d;
            c.progress[b].1 += p;
        }
    }
    if success || segments.is_empty() {
        return Ok(());
    }
    if outcome == "time_limit" {
        let total: f64 = segments.iter().map(|s| s.duration_s).sum();
        if total > 0.0 {
            for s in segments {
                contexts[s.context.min(CONTEXTS - 1)].failures[failure_class(s)].events +=
                    s.duration_s / total;
            }
        }
    } else if let Some(s) = segments.last() {
        contexts[s.context.min(CONTEXTS - 1)].failures[failure_class(s)].events += 1.0;
    }
    Ok(())
}

/// The remaining length to the goal from `at` along `reference`, metres.
pub fn remaining_m(reference: &Reference, at: Vec2) -> f64 {
    reference.remaining_m(at)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::supervisor::log::{CalibrationRun, MissionRecord};

    fn seg(b: Behaviour, localized: bool, context: usize, d: f64, progress: f64, end: SegmentEnd) -> Segment {
        Segment {
            behaviour: b,
            localized,
            normal: true,
            context,
            duration_s: d,
            progress_m: Some(progress),
            end,
        }
    }

    fn calibration(b: Behaviour, t: f64) -> Entry {
        Entry::Calibration(CalibrationRun {
            behaviour: b,
            success: true,
            duration_s: t,
            path_m: 20.0,
            trajectory: vec![[0.0, 0.0], [20.0, 0.0]],
            outcome: "goal".into(),
            segments: Vec::new(),
        })
    }

    fn mission(k: u32, outcome: &str, segments: Vec<Segment>) -> Entry {
        Entry::Mission(MissionRecord {
            mission: k,
            success: outcome == "goal",
            outcome: outcome.into(),
            duration_s: segments.iter().map(|s| s.duration_s).sum(),
            localizer: Vec::new(),
            planner: Vec::new(),
            time_automove_s: 0.0,
            time_contour_s: 0.0,
            decisions: Vec::new(),
            segments,
        })
    }

    #[test]
    fn contexts_and_the_meter() {
        assert_eq!(crowd_context(0.0), 0);
        assert_eq!(crowd_context(1.99), 0);
        assert_eq!(crowd_context(2.0), 1);
        assert_eq!(crowd_context(7.0), 2);
        let mut m = CrowdMeter::new(10.0);
        m.observe(0.0, 10.0);
        assert_eq!(m.mean(), 10.0);
        m.observe(10.0, 0.0);
        assert!((m.mean() - 10.0 * (-1.0f64).exp()).abs() < 1e-12);
    }

    #[test]
    fn failures_are_credited_to_the_behaviour_and_state_responsible() {
        use SegmentEnd::{Behaviour as SwitchedBehaviour, Localizer, Mission};
        let (a, c) = (Behaviour::AutoMove, Behaviour::Contour);
        let log = vec![
            calibration(a, 40.0),
            calibration(c, 80.0),
            // A collision while AutoMove drove, lost, in a crowd.
            mission(
                1,
                "collision",
                vec![
                    seg(a, true, 2, 30.0, 10.0, Localizer),
                    seg(a, false, 2, 5.0, 1.0, Mission),
                ],
            ),
            // A time limit: shared 3 : 1 between AutoMove and contour.
            mission(
                2,
                "time_limit",
                vec![
                    seg(a, true, 1, 225.0, 10.0, SwitchedBehaviour),
                    seg(c, true, 1, 75.0, 5.0, Mission),
                ],
            ),
            mission(3, "goal", vec![seg(a, true, 0, 40.0, 20.0, Mission)]),
        ];
        let m = CreditModel::learn(&log).unwrap();
        assert_eq!((m.missions, m.successes), (3, 1));
        let crowded = &m.contexts[2];
        assert_eq!(crowded.failures[FAIL_AUTO_WARNING].events, 1.0);
        assert_eq!(crowded.failures[FAIL_AUTO_WARNING].time_s, 5.0);
        assert_eq!(crowded.failures[FAIL_AUTO_OK].events, 0.0);
        assert_eq!(crowded.success.events, 1.0);
        let busy = &m.contexts[1];
        assert!((busy.failures[FAIL_AUTO_OK].events - 0.75).abs() < 1e-12);
        assert!((busy.failures[FAIL_CONT_OK].events - 0.25).abs() < 1e-12);
        // Rates: λ12 in the crowd from 1 failure in 5 s, shrunk towards the
        // main-effects model of the Warning failures (AutoMove's 1 in 5 s
        // in the crowd, contour never in Warning; priors 0.001 and λ10's).
        let r = m.rates(2, 10.0);
        let prior = CreditRates::initial();
        let mut n = [[0.0; CONTEXTS]; 2];
        let mut t = [[0.0; CONTEXTS]; 2];
        n[0][2] = 1.0;
        t[0][2] = 5.0;
        let mu = main_effects(n, t, [(1.0, 1.0 / prior.get(12)), (1.0, 1.0 / prior.get(10))]);
        assert!((r.get(12) - 2.0 / (5.0 + 1.0 / mu[0][2])).abs() < 1e-12);
        assert!(mu[0][2] > prior.get(12) && mu[0][2] < 2.0 / 5.0, "{}", mu[0][2]);
        // Progress speed in the quiet context: 20 m in 40 s, with 30 s at
        // the pooled speed.
        let v0 = 20.0 / 40.0;
        let pooled_v = (40.0 + v0 * 30.0) / (40.0 + 30.0 + 225.0 + 30.0 - 30.0);
        let _ = pooled_v;
        let r0 = m.rates(0, 10.0);
        assert!(r0.get(7) > 1.0 / 40.0 && r0.get(7) < 1.0 / 10.0, "{}", r0.get(7));
        for i in 1..=15 {
            assert!(r.get(i).is_finite() && r.get(i) > 0.0, "λ{i}");
        }
    }

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
    fn a_behaviour_never_seen_in_a_crowd_inherits_what_the_crowd_does_to_the_other() {
        use SegmentEnd::Mission;
        let (a, c) = (Behaviour::AutoMove, Behaviour::Contour);
        let mut log = vec![calibration(a, 40.0), calibration(c, 80.0)];
        // Both behaviours in the quiet hall: AutoMove 0.5 m/s, contour
        // 0.25 m/s, neither fails. AutoMove in crowds: 0.2 m/s, one
        // failure in 400 s localized.
        for k in 0..10 {
            log.push(mission(k, "goal", vec![seg(a, true, 0, 40.0, 20.0, Mission)]));
            log.push(mission(
                100 + k,
                "goal",
                vec![seg(c, true, 0, 80.0, 20.0, Mission)],
            ));
            let outcome = if k < 5 { "goal" } else { "collision" };
            log.push(mission(
                200 + k,
                outcome,
                vec![seg(a, true, 2, 80.0, 16.0, Mission)],
            ));
        }
        let m = CreditModel::learn(&log).unwrap();
        let (quiet, crowded) = (m.rates(0, 20.0), m.rates(2, 20.0));
        // Contour tracking's speed in the crowd is taken down by about
        // AutoMove's factor (0.2 / 0.5), its failure rate up with it.
        let slow = crowded.get(8) / quiet.get(8);
        assert!(slow > 0.3 && slow < 0.6, "{slow}");
        let worse = crowded.get(14) / quiet.get(14);
        assert!(worse > 3.0, "{worse}");
        // AutoMove's own rates stay close to its data.
        let v = 20.0 * crowded.get(7);
        assert!((v - 0.2).abs() < 0.03, "{v}");
    }

    #[test]
    fn without_missions_the_rates_are_the_prior_but_for_the_speeds() {
        let log = vec![
            calibration(Behaviour::AutoMove, 40.0),
            calibration(Behaviour::Contour, 80.0),
        ];
        let m = CreditModel::learn(&log).unwrap();
        let r = m.rates(1, 20.0);
        let prior = CreditRates::initial();
        for i in [3, 4, 5, 6, 9, 10, 12, 13, 14] {
            assert!((r.get(i) - prior.get(i)).abs() / prior.get(i) < 1e-12, "λ{i}");
        }
        // The whole reference left: the calibration time.
        assert!((r.get(7) - 1.0 / 40.0).abs() < 1e-12);
        assert!((r.get(8) - 1.0 / 80.0).abs() < 1e-12);
        assert!(CreditModel::learn(&log[..1]).is_err());
    }
}
