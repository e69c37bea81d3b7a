//! The localizer's Success / Warning state machine (tour-guide.md,
//! *Localizer*).
//!
//! At every filter iteration the scan is scored against the map at two
//! poses — the localizer's new estimate and "the pose dead-reckoned from
//! odometry" — and the iteration is judged ([`MatchOutcome`]):
//!
//! - *Warning* is raised after **two consecutive** iterations in which
//!   matching fails;
//! - *Success* is declared after two consecutive iterations in which the
//!   scan matches.
//!
//! The machine starts in *Success*. An iteration without any valid beam
//! ([`MatchOutcome::NoData`]) breaks both runs, and so does any change of
//! outcome, so alternating outcomes never flip the state.
//!
//! **Decision (a): the odometry pose** is the *prediction*: the previous
//! estimate moved by the odometry increment since the previous filter
//! iteration — where the robot is if odometry alone is trusted since the
//! last correction. Raw dead reckoning from the start drifts without bound,
//! so after a few tens of metres every comparison would favour the
//! estimate whatever the scan shows.
//!
//! **Decision (b): the score** is the fraction of the scan the map
//! explains ([`super::LikelihoodField::explained_fraction`]): the share of
//! all valid beams (all 181, not the filter's subset) whose endpoint lies
//! within [`StatusParams::explained_within_m`] (0.1 m) of a wall.
//!
//! **Decision (c): the judgement.** The scan *matches* when the estimate's
//! score beats the prediction's by more than [`StatusParams::margin`]
//! (0.02, about 4 of 181 beams); matching *fails* when it falls short by
//! more than the margin. When the two are within the margin — by far the
//! most common case, since a well-tuned filter moves its estimate by
//! millimetres per iteration — the scan cannot tell the two poses apart
//! and the level decides: it matches if the map explains at least
//! [`StatusParams::min_explained`] (0.8) of the beams at the estimate, and
//! fails otherwise (people, or anything not on the map, hide the walls).
//!
//! The level rule is needed. A pure comparison is a coin toss for a
//! localizer that tracks well: its estimate and the prediction are
//! equally far from the truth (0.040–0.042 m on average on building_31,
//! with or without people), because the filter is not pulled by people, it
//! only loses evidence. With ties counted as matches (`min_explained = 0`,
//! the comparison alone) the robot spent 0.9 %, 0.3 % and 0.6 % of its
//! filter iterations in Warning with 0, 20 and 60 people; with the level
//! rule 0.9 %, 13.8 % and 46.8 % (five 135.8 m drives each; the command is
//! in [`super`]).

/// The localizer's state (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LocalizationStatus {
    /// The scan matches the map at the estimate (the start state).
    #[default]
    Success,
    /// Matching has failed twice in a row. A warning, not a loss.
    Warning,
}

/// How one filter iteration's scan matched (module docs, decision (c)).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MatchOutcome {
    /// Better at the estimate than at the odometry pose, or as good and
    /// explained by the map.
    Matched,
    /// Worse at the estimate, or as good but not explained by the map.
    Failed,
    /// No valid beam: nothing to judge.
    NoData,
}

/// Parameters of the judgement (module docs).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct StatusParams {
    /// A beam is explained by the map when its endpoint is within this
    /// distance of a wall, metres, ≥ 0. Default 0.1.
    pub explained_within_m: f64,
    /// Margin of the comparison, as a fraction of the beams, in [0, 1].
    /// Default 0.02.
    pub margin: f64,
    /// Within the margin, the scan matches if at least this fraction of
    /// its beams is explained at the estimate, in [0, 1]. Default 0.8.
    pub min_explained: f64,
}

impl Default for StatusParams {
    fn default() -> StatusParams {
        StatusParams {
            explained_within_m: 0.1,
            margin: 0.02,
            min_explained: 0.8,
        }
    }
}

impl StatusParams {
    /// Judges one iteration from the scores (explained fractions) at the
    /// estimate and at the odometry pose, over `valid_beams` beams
    /// (decision (c)). NaN scores count as no data.
    pub fn judge(&self, score_estimate: f64, score_odometry: f64, valid_beams: usize) -> MatchOutcome {
        if valid_beams == 0 || score_estimate.is_nan() || score_odometry.is_nan() {
            return MatchOutcome::NoData;
        }
        let diff = score_estimate - score_odometry;
        if diff > self.margin {
            MatchOutcome::Matched
        } else if diff < -self.margin {
            MatchOutcome::Failed
        } else if score_estimate >= self.min_explained {
            MatchOutcome::Matched
        } else {
            MatchOutcome::Failed
        }
    }
}

/// Consecutive outcomes needed to change state.
pub const CONSECUTIVE: u32 = 2;

/// The state machine (module docs). Pure: outcomes in, state out.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct StatusMachine {
    status: LocalizationStatus,
    matched_run: u32,
    failed_run: u32,
}

impl StatusMachine {
    /// A machine in the start state, *Success*.
    pub fn new() -> StatusMachine {
        StatusMachine::default()
    }

    /// The current state.
    pub fn status(&self) -> LocalizationStatus {
        self.status
    }

    /// Takes one iteration's outcome; returns the new state.
    pub fn observe(&mut self, outcome: MatchOutcome) -> LocalizationStatus {
        match outcome {
            MatchOutcome::Matched => {
                self.matched_run = self.matched_run.saturating_add(1);
                self.failed_run = 0;
                if self.matched_run >= CONSECUTIVE {
                    self.status = LocalizationStatus::Success;
                }
            }
            MatchOutcome::Failed => {
                self.failed_run = self.failed_run.saturating_add(1);
                self.matched_run = 0;
                if self.failed_run >= CONSECUTIVE {
                    self.status = LocalizationStatus::Warning;
                }
            }
            MatchOutcome::NoData => {
                self.matched_run = 0;
                self.failed_run = 0;
            }
        }
        self.status
    }
}

#[cfg(test)]
mod tests {
    use super::LocalizationStatus::{Success as S, Warning as W};
    use super::MatchOutcome::{Failed as F, Matched as M, NoData as N};
    use super::*;

    fn run(seq: &[MatchOutcome]) -> Vec<LocalizationStatus> {
        let mut m = StatusMachine::new();
        seq.iter().map(|&c| m.observe(c)).collect()
    }

    #[test]
    fn starts_in_success() {
        assert_eq!(StatusMachine::new().status(), S);
    }

    #[test]
    fn two_failures_in_a_row_raise_a_warning_and_two_matches_clear_it() {
        assert_eq!(run(&[F, F, F, M, M, M]), vec![S, W, W, W, S, S]);
    }

    #[test]
    fn a_single_failure_or_match_changes_nothing() {
        assert_eq!(run(&[F, M, F, N, F, M]), vec![S; 6]);
        assert_eq!(run(&[F, F, M, F, M, N, M, F]), vec![S, W, W, W, W, W, W, W]);
    }

    #[test]
    fn alternating_outcomes_never_flip_the_state() {
        let alt: Vec<MatchOutcome> = (0..20).map(|k| if k % 2 == 0 { F } else { M }).collect();
        assert!(run(&alt).iter().all(|&s| s == S));
        let mut m = StatusMachine::new();
        m.observe(F);
        m.observe(F);
        for k in 0..20 {
            assert_eq!(m.observe(if k % 2 == 0 { M } else { F }), W);
        }
    }

    #[test]
    fn no_data_breaks_a_run() {
        assert_eq!(run(&[F, N, F, N, F]), vec![S; 5]);
        assert_eq!(run(&[F, F, M, N, M, M]), vec![S, W, W, W, W, S]);
    }

    #[test]
    fn judgement_by_comparison_then_by_level() {
        let p = StatusParams::default();
        // Clearly better or worse at the estimate: the comparison decides.
        assert_eq!(p.judge(0.60, 0.55, 100), M);
        assert_eq!(p.judge(0.95, 0.99, 100), F);
        // Within the margin: the level decides.
        assert_eq!(p.judge(0.95, 0.94, 100), M);
        assert_eq!(p.judge(0.80, 0.80, 100), M);
        assert_eq!(p.judge(0.70, 0.71, 100), F);
        // Nothing to judge.
        assert_eq!(p.judge(0.0, 0.0, 0), N);
        assert_eq!(p.judge(f64::NAN, 0.5, 10), N);
    }
}
