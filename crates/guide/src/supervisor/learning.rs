//! Learning the supervisor's rates from the mission log (docs/gspn.md,
//! "Parameters"; docs/tour-guide.md, "Learning across missions").
//!
//! | rate | from the log |
//! |---|---|
//! | λ3, λ4 | the localizer's sojourns in Success, resp. Warning |
//! | λ5, λ6 | the planner's sojourns in Normal, resp. Abnormal |
//! | λ7, λ8 | the calibration runs of AutoMove, resp. contour tracking: `1 / mean travel time` |
//! | λ9, λ10 | `λ7 · N_fail / N_succ`, resp. `λ8 · N_fail / N_succ`, over the missions |
//! | λ1, λ2, λ11 | fixed (the hypotheses set λ1, λ2) |
//!
//! **Decision — estimating a rate from sojourns.** The spec's rate is
//! `1 / mean sojourn time`. A mission that ends in a state cuts that
//! sojourn short (censoring), and a robot that never warned has no Warning
//! sojourn at all; so the rate is estimated as transitions out of the state
//! over the time spent in it — the maximum-likelihood estimate for an
//! exponential sojourn, which equals `1 / mean` when every sojourn ended —
//! with one pseudo-sojourn at the source's initial rate added (a conjugate
//! gamma prior of weight one event): `λ = (n + 1) / (T + 1/λ₀)`. Before any
//! experience this is the source's Λ; after a few missions the data decide;
//! it is never zero, infinite or NaN, whatever the log holds (zero time in a
//! state, no transition at all). Failure rates get the same treatment:
//! `N_fail / N_succ` becomes `(N_fail + r₀) / (N_succ + 1)`, `r₀` the
//! source's initial ratio λ9/λ7.
//!
//! **Missing calibration is an error** for [`learn`]: without reference
//! runs there is no λ7 or λ8, and a supervisor choosing between behaviours
//! it has never timed would only repeat the prior. A robot that must go on
//! anyway (a campaign whose five calibration runs of a behaviour all
//! failed) uses [`learn_or_prior`]: the source's λ7 or λ8 for the behaviour
//! without a successful run, and no reference trajectory for it.

use robot::Vec2;

use super::log::{CalibrationRun, Entry, StateName};
use super::reference::Reference;
use super::{Behaviour, NUM_RATES, Rates};

/// What can go wrong.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LearnError {
    /// No successful calibration run of a behaviour.
    #[error(
        "no successful calibration run of {0:?} in the log: run each behaviour alone first (the source used five runs each)"
    )]
    NoCalibration(Behaviour),
    /// A value in the log that is not a finite number ≥ 0.
    #[error("{what} = {value} in the log: expected a finite number ≥ 0")]
    BadValue {
        /// Which value.
        what: String,
        /// Its value.
        value: f64,
    },
    /// A rate learnt from values each within range that is still not a
    /// rate (their sum or mean overflowed, or underflowed to 0).
    #[error(
        "learnt λ{index} = {value}, which is not a rate (a finite number > 0): the log's durations are out of proportion (a reader checks each is at most 10⁹ s; entries not read from a log file are not checked)"
    )]
    LearntRate {
        /// 1-based index.
        index: usize,
        /// The value learnt.
        value: f64,
    },
}

/// What the log says, and the rates learnt from it.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Learned {
    /// λ1…λ11 (λ1, λ2 as the source's initial Λ; the supervisor sets them
    /// per hypothesis).
    pub rates: Rates,
    /// AutoMove's reference.
    pub automove: Reference,
    /// Contour tracking's reference.
    pub contour: Reference,
    /// Missions in the log.
    pub missions: usize,
    /// Of which reached the goal.
    pub successes: usize,
    /// Time in Success and transitions out of it, over all missions.
    pub success: Exposure,
    /// Time in Warning and transitions out of it.
    pub warning: Exposure,
    /// Time Normal and transitions out of it.
    pub normal: Exposure,
    /// Time Abnormal and transitions out of it.
    pub abnormal: Exposure,
}

/// Time spent in a state and the transitions out of it.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct Exposure {
    /// Seconds.
    pub time_s: f64,
    /// Transitions out.
    pub exits: usize,
}

impl Exposure {
    /// The rate with one pseudo-event at `prior` (module docs).
    pub fn rate(&self, prior: f64) -> f64 {
        (self.exits as f64 + 1.0) / (self.time_s + 1.0 / prior)
    }

    /// Mean sojourn time, seconds (`NaN` without a transition).
    pub fn mean_s(&self) -> f64 {
        self.time_s / self.exits as f64
    }
}

fn check(what: impl Fn() -> String, value: f64) -> Result<f64, LearnError> {
    if value.is_finite() && value >= 0.0 {
        Ok(value)
    } else {
        Err(LearnError::BadValue { what: what(), value })
    }
}

/// A behaviour's reference from its successful calibration runs: mean time
/// and speed, and the median-time run's trajectory;
/// [`LearnError::NoCalibration`] without one.
pub fn reference_of(runs: &[&CalibrationRun], behaviour: Behaviour) -> Result<Reference, LearnError> {
    let ok: Vec<&&CalibrationRun> = runs
        .iter()
        .filter(|r| r.behaviour == behaviour && r.success && r.duration_s > 0.0)
        .collect();
    if ok.is_empty() {
        return Err(LearnError::NoCalibration(behaviour));
    }
    for r in &ok {
        check(|| "calibration duration_s".into(), r.duration_s)?;
        check(|| "calibration path_m".into(), r.path_m)?;
    }
    let n = ok.len() as f64;
    let mean_time_s = ok.iter().map(|r| r.duration_s).sum::<f64>() / n;
    let mean_speed_mps = ok.iter().map(|r| r.path_m / r.duration_s).sum::<f64>() / n;
    let mut by_time: Vec<&&&CalibrationRun> = ok.iter().collect();
    by_time.sort_by(|a, b| a.duration_s.total_cmp(&b.duration_s));
    let median = by_time[by_time.len() / 2];
    Ok(Reference {
        mean_time_s,
        mean_speed_mps: if mean_speed_mps > 0.0 {
            mean_speed_mps
        } else {
            1e-3
        },
        trajectory: median.trajectory.iter().map(|p| Vec2::new(p[0], p[1])).collect(),
    })
}

/// Learns the rates from the entries of a log (module docs).
pub fn learn(entries: &[Entry]) -> Result<Learned, LearnError> {
    learn_with(entries, false)
}

/// [`learn`], falling back to the source's λ7 or λ8 for a behaviour without
/// a successful calibration run (module docs).
pub fn learn_or_prior(entries: &[Entry]) -> Result<Learned, LearnError> {
    learn_with(entries, true)
}

fn learn_with(entries: &[Entry], lenient: bool) -> Result<Learned, LearnError> {
    let prior = Rates::initial();
    let (calibration, missions) = super::log::split_entries(entries);
    let with_prior = |b: Behaviour, rate: f64| match reference_of(&calibration, b) {
        Err(LearnError::NoCalibration(_)) if lenient => Ok(Reference::prior(1.0 / rate)),
        other => other,
    };
    let automove = with_prior(Behaviour::AutoMove, prior.get(7))?;
    let contour = with_prior(Behaviour::Contour, prior.get(8))?;
    let mut exposure = [Exposure::default(); 4];
    for m in &missions {
        for s in m.localizer.iter().chain(&m.planner) {
            let d = check(
                || format!("mission {} sojourn duration_s", m.mission),
                s.duration_s,
            )?;
            let k = match s.state {
                StateName::Success => 0,
                StateName::Warning => 1,
                StateName::Normal => 2,
                StateName::Abnormal => 3,
            };
            exposure[k].time_s += d;
            exposure[k].exits += usize::from(s.ended);
        }
    }
    let successes = missions.iter().filter(|m| m.success).count();
    let failures = missions.len() - successes;
    let mut lambda = prior.as_array();
    lambda[2] = exposure[0].rate(prior.get(3));
    lambda[3] = exposure[1].rate(prior.get(4));
    lambda[4] = exposure[2].rate(prior.get(5));
    lambda[5] = exposure[3].rate(prior.get(6));
    lambda[6] = 1.0 / automove.mean_time_s;
    lambda[7] = 1.0 / contour.mean_time_s;
    let r0 = prior.get(9) / prior.get(7);
    let ratio = (failures as f64 + r0) / (successes as f64 + 1.0);
    lambda[8] = lambda[6] * ratio;
    lambda[9] = lambda[7] * ratio;
    let mut rates = Rates::initial();
    for (i, &v) in lambda.iter().enumerate().take(NUM_RATES) {
        rates.try_set(i + 1, v).map_err(|_| LearnError::LearntRate {
            index: i + 1,
            value: v,
        })?;
    }
    Ok(Learned {
        rates,
        automove,
        contour,
        missions: missions.len(),
        successes,
        success: exposure[0],
        warning: exposure[1],
        normal: exposure[2],
        abnormal: exposure[3],
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::supervisor::log::{MissionRecord, Sojourn};

    fn calibration(b: Behaviour, t: f64, len: f64) -> Entry {
        Entry::Calibration(CalibrationRun {
            behaviour: b,
            success: true,
            duration_s: t,
            path_m: len,
            trajectory: vec![[0.0, 0.0], [len, 0.0]],
            outcome: String::new(),
            segments: Vec::new(),
            route: None,
        })
    }

    fn sojourn(state: StateName, d: f64, ended: bool) -> Sojourn {
        Sojourn {
            state,
            duration_s: d,
            ended,
        }
    }

    fn mission(k: u32, success: bool, localizer: Vec<Sojourn>, planner: Vec<Sojourn>) -> Entry {
        Entry::Mission(MissionRecord {
            mission: k,
            success,
            outcome: if success { "goal" } else { "time_limit" }.into(),
            duration_s: 100.0,
            localizer,
            planner,
            time_automove_s: 100.0,
            time_contour_s: 0.0,
            decisions: Vec::new(),
            segments: Vec::new(),
            route: None,
        })
    }

    #[test]
    fn a_hand_made_log_gives_the_expected_rates() {
        use StateName::*;
        let log = vec![
            calibration(Behaviour::AutoMove, 100.0, 20.0),
            calibration(Behaviour::AutoMove, 140.0, 22.0),
            calibration(Behaviour::Contour, 200.0, 30.0),
            // Mission 1: Success 40 s, Warning 10 s, Success 50 s (open);
            // planner Normal 70 s, Abnormal 5 s, Normal 25 s (open).
            mission(
                1,
                true,
                vec![
                    sojourn(Success, 40.0, true),
                    sojourn(Warning, 10.0, true),
                    sojourn(Success, 50.0, false),
                ],
                vec![
                    sojourn(Normal, 70.0, true),
                    sojourn(Abnormal, 5.0, true),
                    sojourn(Normal, 25.0, false),
                ],
            ),
            // Mission 2 failed: Success 30 s, Warning 70 s (open).
            mission(
                2,
                false,
                vec![sojourn(Success, 30.0, true), sojourn(Warning, 70.0, false)],
                vec![sojourn(Normal, 100.0, false)],
            ),
        ];
        let l = learn(&log).unwrap();
        let r = l.rates;
        // λ3: 2 exits from Success in 120 s, prior 1/0.001 s.
        assert!((r.get(3) - 3.0 / (120.0 + 1000.0)).abs() < 1e-15);
        // λ4: 1 exit from Warning in 80 s, prior rate 1000.
        assert!((r.get(4) - 2.0 / (80.0 + 0.001)).abs() < 1e-15);
        assert!((r.get(5) - 2.0 / (195.0 + 1000.0)).abs() < 1e-15);
        assert!((r.get(6) - 2.0 / (5.0 + 0.001)).abs() < 1e-15);
        // λ7, λ8 from the reference runs.
        assert!((r.get(7) - 1.0 / 120.0).abs() < 1e-15);
        assert!((r.get(8) - 1.0 / 200.0).abs() < 1e-15);
        // λ9 = λ7 (N_fail + r0) / (N_succ + 1).
        let r0 = 0.001 / 0.0082;
        assert!((r.get(9) - r.get(7) * (1.0 + r0) / 2.0).abs() < 1e-15);
        assert!((r.get(10) - r.get(8) * (1.0 + r0) / 2.0).abs() < 1e-15);
        assert_eq!((r.get(1), r.get(2), r.get(11)), (0.001, 1000.0, 1000.0));
        assert_eq!((l.missions, l.successes), (2, 1));
        assert!((l.automove.mean_speed_mps - 0.5 * (0.2 + 22.0 / 140.0)).abs() < 1e-12);
        // The reference trajectory is the median-time run's.
        assert_eq!(l.automove.trajectory.last().copied(), Some(Vec2::new(22.0, 0.0)));
    }

    #[test]
    fn no_experience_gives_the_prior_and_nothing_is_ever_nan() {
        let log = vec![
            calibration(Behaviour::AutoMove, 122.33, 21.0),
            calibration(Behaviour::Contour, 186.98, 27.0),
            // A mission of zero duration: zero sojourn times.
            mission(1, true, vec![sojourn(StateName::Success, 0.0, false)], Vec::new()),
        ];
        let l = learn(&log).unwrap();
        for i in 1..=11 {
            assert!(l.rates.get(i).is_finite() && l.rates.get(i) > 0.0, "λ{i}");
        }
        assert_eq!(l.rates.get(3), 0.001);
        assert_eq!(l.rates.get(4), 1000.0);
    }

    #[test]
    fn missing_calibration_and_bad_values_are_errors() {
        let only_auto = vec![calibration(Behaviour::AutoMove, 100.0, 20.0)];
        assert_eq!(
            learn(&only_auto),
            Err(LearnError::NoCalibration(Behaviour::Contour))
        );
        assert!(matches!(
            learn(&[]),
            Err(LearnError::NoCalibration(Behaviour::AutoMove))
        ));
        let bad = vec![
            calibration(Behaviour::AutoMove, 100.0, 20.0),
            calibration(Behaviour::Contour, 200.0, 30.0),
            mission(1, true, vec![sojourn(StateName::Warning, -3.0, true)], Vec::new()),
        ];
        assert!(matches!(learn(&bad), Err(LearnError::BadValue { .. })));
        // Leniently, the prior stands in for a missing calibration.
        let l = learn_or_prior(&only_auto).unwrap();
        assert_eq!(l.rates.get(8), 0.0053);
        assert!(l.contour.trajectory.is_empty());
        assert_eq!(l.contour.rate_from(Vec2::new(5.0, 5.0)), 0.0053);
    }
}
