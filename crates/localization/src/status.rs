//! The localizer's Success / Warning state machine (docs/tour-guide.md,
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
//! The level rule is needed: a pure comparison is a coin toss for a
//! localizer that tracks well — its estimate and the prediction are
//! equally far from the truth, because people do not pull the filter,
//! they only hide evidence — so the comparison alone leaves the Warning
//! rate unchanged by crowds (the table in [`super`], *Figures*).
//!
//! **Decision (d): what a Warning means — the contradiction rule, the
//! default.** Decisions (b) and (c) are the source's reading, kept as
//! [`StatusRule::Explained`] so that its experiment still reproduces. With
//! them a Warning means "the map explains little of the scan", which among
//! visitors is nearly always true and says nothing about the pose (above:
//! 46.8 % of the iterations with 60 people, the estimate within 0.1 m).
//! A robot needs to tell *crowded* from *lost*, so by default an iteration
//! is judged by the scan's consistency with the map at the estimate alone
//! ([`super::consistency`]): a beam that ends short of its mapped wall is
//! no evidence (people only shorten beams), a beam that sees past a mapped
//! wall is. The scan *fails* when more than `max_contradiction` (0.1) of
//! its hit-or-through beams are through, *matches* otherwise, and says
//! nothing with fewer than `min_evidence_beams` (15) of them (a group
//! round the robot). The odometry pose plays no part: after a push or a
//! slip the prediction is as wrong as the estimate, so a comparison of the
//! two cannot see the loss. At the true pose the contradiction stays near
//! 0 among 60 visitors, and it exceeds 0.1 at nearly every pose off by
//! 0.5 m or 20° (`cargo run --release -p lab --example status_roc -- 60 4`;
//! figures in `crates/localization/EXPERIMENTS.md`). Because the robot may be
//! pushed while it stands still (no filter iteration runs then), the scan
//! is also judged at the current estimate every `check_period_s` (0.25 s)
//! between iterations.

use super::consistency::{ConsistencyTolerances, Neighbourhood, ScanConsistency};

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

/// Which evidence judges an iteration (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StatusRule {
    /// The source's: the explained fraction at the estimate against the
    /// odometry pose, and its level (decisions (b), (c)). People hiding
    /// the walls raise Warnings.
    Explained,
    /// The contradiction of the scan at the estimate (decision (d),
    /// [`super::consistency`]): Warning means the scan sees past the
    /// mapped walls — the robot is lost — and people hiding the walls
    /// raise none. The default.
    #[default]
    Contradiction,
}

/// Parameters of the judgement (module docs).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct StatusParams {
    /// Which evidence judges. Default [`StatusRule::Contradiction`].
    pub rule: StatusRule,
    /// A beam is explained by the map when its endpoint is within this
    /// distance of a wall, metres, ≥ 0 (both rules: the contradiction
    /// rule's *hit*). Default 0.1.
    pub explained_within_m: f64,
    /// [`StatusRule::Explained`]: margin of the comparison, as a fraction
    /// of the beams, in [0, 1]. Default 0.02.
    pub margin: f64,
    /// [`StatusRule::Explained`]: within the margin, the scan matches if at
    /// least this fraction of its beams is explained at the estimate, in
    /// [0, 1]. Default 0.8.
    pub min_explained: f64,
    /// [`StatusRule::Contradiction`]: a beam is *through* when it crosses
    /// a mapped wall at least this far before its endpoint, metres, ≥ 0.
    /// Default 0.25 (six times the tracking error, half the error that
    /// counts as lost).
    pub through_tolerance_m: f64,
    /// [`StatusRule::Contradiction`]: the through tolerance grows by this
    /// much per metre of range (a heading error, radians), ≥ 0. Default
    /// 0.035 (2°).
    pub through_tolerance_rad: f64,
    /// [`StatusRule::Contradiction`]: the scan fails when more than this
    /// share of its hit-or-through beams is through, in [0, 1]. Default
    /// 0.1.
    pub max_contradiction: f64,
    /// [`StatusRule::Contradiction`]: with fewer hit-or-through beams than
    /// this the scan says nothing (no data). Default 15.
    pub min_evidence_beams: usize,
    /// [`StatusRule::Contradiction`]: a scan clears a Warning, or a pose
    /// of the neighbourhood counts as a correction, only with at least this
    /// many hit-or-through beams. Default 40 (a crowd leaves a few walls in
    /// view, and a wrong pose agrees with a few walls easily).
    pub min_evidence_to_clear: usize,
    /// [`StatusRule::Contradiction`]: a contradicted scan is tried at these
    /// poses around the estimate before it counts against it (a 3 × 3 grid
    /// 0.3 m apart, ±15° in 5° steps).
    pub neighbourhood: Neighbourhood,
    /// [`StatusRule::Contradiction`]: while no filter iteration runs (the
    /// robot stands still), the scan is judged at the current estimate
    /// this often, seconds, ≥ 0 (0: only at filter iterations). Default
    /// 0.25.
    pub check_period_s: f64,
}

impl Default for StatusParams {
    fn default() -> StatusParams {
        StatusParams {
            rule: StatusRule::Contradiction,
            explained_within_m: 0.1,
            margin: 0.02,
            min_explained: 0.8,
            through_tolerance_m: 0.25,
            through_tolerance_rad: 0.035,
            max_contradiction: 0.1,
            min_evidence_beams: 15,
            min_evidence_to_clear: 40,
            neighbourhood: Neighbourhood::default(),
            check_period_s: 0.25,
        }
    }
}

impl StatusParams {
    /// The source's judgement ([`StatusRule::Explained`], decisions (a)–(c)),
    /// with its thresholds and no checks between filter iterations.
    pub fn explained() -> StatusParams {
        StatusParams {
            rule: StatusRule::Explained,
            check_period_s: 0.0,
            ..StatusParams::default()
        }
    }

    /// Judges one iteration from the scores (explained fractions) at the
    /// estimate and at the odometry pose, over `valid_beams` beams
    /// ([`StatusRule::Explained`], decision (c)). NaN scores count as no
    /// data.
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

    /// Judges `scan` at `estimate` by the contradiction rule (decision
    /// (d)): its consistency there; in Warning (`warning`) a match needs
    /// `min_evidence_to_clear` beams of evidence (else no data); out of
    /// Warning a contradicted scan is tried at the neighbourhood, whose
    /// least contradicted pose with that much evidence makes it a match
    /// (off, not lost) and is returned as a correction.
    pub fn judge_scan(
        &self,
        field: &super::LikelihoodField,
        estimate: &robot::Pose,
        scan: &robot::LaserScan,
        warning: bool,
    ) -> (MatchOutcome, ScanConsistency, Option<robot::Pose>) {
        let tol = self.tolerances();
        let c = field.consistency(estimate, scan, tol);
        match self.judge_consistency(&c) {
            MatchOutcome::Matched if warning && c.evidence() < self.min_evidence_to_clear => {
                (MatchOutcome::NoData, c, None)
            }
            MatchOutcome::Failed if !warning => match field.nearest_consistent(
                estimate,
                scan,
                tol,
                self.max_contradiction,
                self.min_evidence_to_clear.max(self.min_evidence_beams),
                &self.neighbourhood,
            ) {
                Some((q, _)) => (MatchOutcome::Matched, c, Some(q)),
                None => (MatchOutcome::Failed, c, None),
            },
            outcome => (outcome, c, None),
        }
    }

    /// Judges one scan from its consistency with the map at the estimate
    /// alone ([`StatusRule::Contradiction`], decision (d), without the
    /// neighbourhood).
    pub fn judge_consistency(&self, c: &ScanConsistency) -> MatchOutcome {
        if c.evidence() < self.min_evidence_beams.max(1) {
            MatchOutcome::NoData
        } else if c.contradiction() > self.max_contradiction {
            MatchOutcome::Failed
        } else {
            MatchOutcome::Matched
        }
    }

    /// The tolerances of the consistency classification.
    pub fn tolerances(&self) -> ConsistencyTolerances {
        ConsistencyTolerances {
            hit_within_m: self.explained_within_m,
            through_tolerance_m: self.through_tolerance_m,
            through_tolerance_rad: self.through_tolerance_rad,
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
