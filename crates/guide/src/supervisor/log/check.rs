//! What a mission log's entry must hold to be learnt from: each entry
//! consistent in itself, checked as the log is read ([`super`]), so
//! that a hand-edited or corrupted log is an error naming its line and
//! field instead of rates silently learnt from nonsense.
//!
//! | entry | checked |
//! |---|---|
//! | every duration (a run, a sojourn, a segment, time per behaviour) | a finite number of seconds in `[0, MAX_DURATION_S]` |
//! | calibration run | `path_m` in `[0, MAX_LENGTH_M]`; `outcome` empty (the source's logs) or one of [`OUTCOMES`] and `goal` exactly when `success`; its segments within its duration |
//! | mission | numbered from 1; `outcome` one of [`OUTCOMES`], `goal` exactly when `success`; the localizer's sojourns in `success`/`warning`, the planner's in `normal`/`abnormal`, each sequence, the segments and the time per behaviour within the duration; decisions in time order within it, with 11 or 15 rates (finite, > 0), throughputs finite and ≥ 0, probabilities in `[0, 1]`, a crowd context below [`CONTEXTS`]; the crediting supervisor's contour rates (none or as many as `rates`, finite, > 0), a route not empty, the marking `P0`, one of `P5`/`P6`, one of `P7`/`P8` |
//! | segment | crowd context below [`CONTEXTS`] |
//! | the log | mission numbers strictly increasing (unique, in order) — checked by the reader |
//!
//! "Within the duration" allows [`TIME_SLACK`] of it (sums of a mission's
//! ticks round differently from its clock).
//!
//! **Decision — what is skipped, not refused.** One entry only: a
//! *successful calibration run of 0 s* (a run started at its goal). It is a
//! true record, but it says nothing of how long the way to the goal takes:
//! the learners leave it out of the reference (as they always did), and
//! the reader reports it as a warning naming its line
//! ([`super::MissionLog::skipped`]), counted in what `petrinav guide
//! log show` prints. Everything else that fails a check above is an error.

use super::super::shrinkage::CONTEXTS;
use super::Segment;
use super::{CalibrationRun, DecisionLog, Entry, MissionRecord, Sojourn, StateName};

/// The longest a run or any part of one may last, seconds: 10⁹ s, about
/// 32 years. Nothing a robot logs lasts longer; and sums of many such
/// durations stay far from overflowing (a 1e308 s "duration" made the
/// mean time infinite and λ7 = 0).
pub const MAX_DURATION_S: f64 = 1e9;

/// The longest path a calibration run may report, metres (10⁹ m).
pub const MAX_LENGTH_M: f64 = 1e9;

/// How far a part of a mission may exceed its duration, as a fraction of
/// it (plus one microsecond): rounding, not time.
pub const TIME_SLACK: f64 = 1e-6;

/// How a run may end, as the lab writes it (`lab::runs::mission::outcome_name`).
pub const OUTCOMES: [&str; 6] = [
    "goal",
    "collision",
    "time_limit",
    "lost",
    "unreachable",
    "gave_up",
];

/// Why an entry cannot be learnt from: the field at fault and what is wrong.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Inconsistent {
    /// The field, as written in the line (`duration_s`,
    /// `localizer[2].duration_s`, `decisions[0].time_s`, …).
    pub field: String,
    /// What is wrong.
    pub message: String,
}

/// What the check says of a sound entry.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Verdict {
    /// Learnt from.
    Kept,
    /// Read, shown, but left out of the learning, and why (module docs).
    Skipped(String),
}

type Checked = Result<(), Inconsistent>;

fn fail(field: impl Into<String>, message: impl Into<String>) -> Inconsistent {
    Inconsistent {
        field: field.into(),
        message: message.into(),
    }
}

/// A number as a message shows it: plain, or in scientific notation when
/// very large or small (`1e308`, not 309 digits).
fn shown(v: f64) -> String {
    if v != 0.0 && v.is_finite() && !(1e-6..1e15).contains(&v.abs()) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

fn duration(field: &str, v: f64) -> Checked {
    if v.is_finite() && (0.0..=MAX_DURATION_S).contains(&v) {
        Ok(())
    } else {
        Err(fail(
            field,
            format!(
                "{} s: a duration is a finite number of seconds from 0 to {MAX_DURATION_S:e} (about 32 years)",
                shown(v)
            ),
        ))
    }
}

fn within(field: &str, part_s: f64, whole_s: f64) -> Checked {
    if part_s <= whole_s * (1.0 + TIME_SLACK) + 1e-6 {
        Ok(())
    } else {
        Err(fail(
            field,
            format!(
                "{} s, more than the run's duration_s ({} s)",
                shown(part_s),
                shown(whole_s)
            ),
        ))
    }
}

fn outcome_agrees(outcome: &str, success: bool, may_be_empty: bool) -> Checked {
    if outcome.is_empty() && may_be_empty {
        return Ok(());
    }
    if !OUTCOMES.contains(&outcome) {
        let hint =
            petri::closest(outcome, &OUTCOMES).map_or(String::new(), |c| format!("; did you mean `{c}`?"));
        return Err(fail(
            "outcome",
            format!(
                "`{outcome}` is not an outcome: one of {}{hint}",
                OUTCOMES.join(", ")
            ),
        ));
    }
    if (outcome == "goal") != success {
        return Err(fail(
            "success",
            format!(
                "`success` is {success} but `outcome` is `{outcome}`: a run succeeds exactly when it ends at the goal"
            ),
        ));
    }
    Ok(())
}

fn segments(list: &[Segment], whole_s: f64) -> Checked {
    let mut total = 0.0;
    for (k, s) in list.iter().enumerate() {
        duration(&format!("segments[{k}].duration_s"), s.duration_s)?;
        if s.context >= CONTEXTS {
            return Err(fail(
                format!("segments[{k}].context"),
                format!(
                    "{}: crowd contexts are 0 (quiet), 1 (busy) and 2 (crowded)",
                    s.context
                ),
            ));
        }
        total += s.duration_s;
    }
    within("segments (their durations' sum)", total, whole_s)
}

fn sojourns(name: &str, list: &[Sojourn], states: [StateName; 2], whole_s: f64) -> Checked {
    let mut total = 0.0;
    for (k, s) in list.iter().enumerate() {
        if !states.contains(&s.state) {
            return Err(fail(
                format!("{name}[{k}].state"),
                format!(
                    "{:?} is not a state of the {name} ({:?} or {:?})",
                    s.state, states[0], states[1]
                )
                .to_lowercase(),
            ));
        }
        duration(&format!("{name}[{k}].duration_s"), s.duration_s)?;
        total += s.duration_s;
    }
    within(&format!("{name} (its sojourns' sum)"), total, whole_s)
}

fn decisions(list: &[DecisionLog], whole_s: f64) -> Checked {
    let mut last = 0.0;
    for (k, d) in list.iter().enumerate() {
        let field = |f: &str| format!("decisions[{k}].{f}");
        duration(&field("time_s"), d.time_s)?;
        within(&field("time_s"), d.time_s, whole_s)?;
        if d.time_s < last {
            return Err(fail(
                field("time_s"),
                format!("{} s, before the previous decision ({last} s)", d.time_s),
            ));
        }
        last = d.time_s;
        if ![11, 15].contains(&d.rates.len()) {
            return Err(fail(
                field("rates"),
                format!("{} rates: a decision logs λ1…λ11 or λ1…λ15", d.rates.len()),
            ));
        }
        positive_rates(&field("rates"), &d.rates)?;
        for (name, v) in [("f_auto", d.f_auto), ("f_cont", d.f_cont)] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(fail(
                    field(name),
                    format!("{v}: a throughput is a finite number ≥ 0"),
                ));
            }
        }
        for (name, v) in [("p_loc_succ", d.p_loc_succ), ("p_loc_warn", d.p_loc_warn)] {
            if !(0.0..=1.0).contains(&v) {
                return Err(fail(field(name), format!("{v}: a probability is in [0, 1]")));
            }
        }
        if let Some(c) = d.context.filter(|&c| c >= CONTEXTS) {
            return Err(fail(
                field("context"),
                format!("{c}: crowd contexts are 0 (quiet), 1 (busy) and 2 (crowded)"),
            ));
        }
        crediting_fields(d, &field)?;
    }
    Ok(())
}

/// Every rate of a decision's list finite and > 0 (named λ1, λ2, …).
fn positive_rates(field: &str, rates: &[f64]) -> Checked {
    match rates
        .iter()
        .enumerate()
        .find(|(_, v)| !(v.is_finite() && **v > 0.0))
    {
        Some((i, v)) => Err(fail(
            field,
            format!("λ{} = {}: rates are finite numbers > 0", i + 1, shown(*v)),
        )),
        None => Ok(()),
    }
}

/// What the crediting supervisor adds to a decision: the contour
/// hypothesis's rates (none, or as many as `rates`, each finite and > 0),
/// the route (not empty when given) and the marking at the decision (`P0`,
/// one localizer place — `P5` or `P6` — and one planner place — `P7` or
/// `P8`).
fn crediting_fields(d: &DecisionLog, field: &dyn Fn(&str) -> String) -> Checked {
    if !d.contour_rates.is_empty() && d.contour_rates.len() != d.rates.len() {
        return Err(fail(
            field("contour_rates"),
            format!(
                "{} rates beside {} in `rates`: the contour hypothesis logs as many",
                d.contour_rates.len(),
                d.rates.len()
            ),
        ));
    }
    positive_rates(&field("contour_rates"), &d.contour_rates)?;
    if d.route.as_deref().is_some_and(|r| r.trim().is_empty()) {
        return Err(fail(
            field("route"),
            "an empty route: leave the field out instead",
        ));
    }
    if d.marking.is_empty() {
        return Ok(());
    }
    let has = |p: &str| d.marking.iter().any(|m| m == p);
    let count = |ps: [&str; 2]| ps.iter().filter(|p| has(p)).count();
    let known = ["P0", "P5", "P6", "P7", "P8"];
    if let Some(p) = d.marking.iter().find(|m| !known.contains(&m.as_str())) {
        return Err(fail(
            field("marking"),
            format!("{p:?}: a decision's marking names P0 and the localizer's and planner's places (P5–P8)"),
        ));
    }
    if d.marking.len() != 3 || !has("P0") || count(["P5", "P6"]) != 1 || count(["P7", "P8"]) != 1 {
        return Err(fail(
            field("marking"),
            format!(
                "[{}]: a decision's marking is P0, one of P5/P6 (localizer) and one of P7/P8 (planner)",
                d.marking.join(", ")
            ),
        ));
    }
    Ok(())
}

fn calibration(c: &CalibrationRun) -> Result<Verdict, Inconsistent> {
    duration("duration_s", c.duration_s)?;
    if !(c.path_m.is_finite() && (0.0..=MAX_LENGTH_M).contains(&c.path_m)) {
        return Err(fail(
            "path_m",
            format!(
                "{} m: a path length is a finite number of metres from 0 to {MAX_LENGTH_M:e}",
                shown(c.path_m)
            ),
        ));
    }
    outcome_agrees(&c.outcome, c.success, true)?;
    segments(&c.segments, c.duration_s)?;
    Ok(if c.success && c.duration_s == 0.0 {
        Verdict::Skipped(
            "a successful calibration run of 0 s (started at its goal) says nothing of the time to the goal: left out of the reference".into(),
        )
    } else {
        Verdict::Kept
    })
}

fn mission(m: &MissionRecord) -> Result<Verdict, Inconsistent> {
    if m.mission == 0 {
        return Err(fail("mission", "0: missions are numbered from 1"));
    }
    outcome_agrees(&m.outcome, m.success, false)?;
    duration("duration_s", m.duration_s)?;
    let d = m.duration_s;
    sojourns(
        "localizer",
        &m.localizer,
        [StateName::Success, StateName::Warning],
        d,
    )?;
    sojourns("planner", &m.planner, [StateName::Normal, StateName::Abnormal], d)?;
    duration("time_automove_s", m.time_automove_s)?;
    duration("time_contour_s", m.time_contour_s)?;
    within(
        "time_automove_s + time_contour_s",
        m.time_automove_s + m.time_contour_s,
        d,
    )?;
    decisions(&m.decisions, d)?;
    segments(&m.segments, d)?;
    Ok(Verdict::Kept)
}

/// Checks an entry in itself (module docs): kept, skipped with the reason,
/// or the field at fault.
pub fn check(entry: &Entry) -> Result<Verdict, Inconsistent> {
    match entry {
        Entry::Calibration(c) => calibration(c),
        Entry::Mission(m) => mission(m),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::supervisor::Behaviour;
    use crate::supervisor::log::SegmentEnd;

    fn calibration(success: bool, duration_s: f64) -> CalibrationRun {
        CalibrationRun {
            behaviour: Behaviour::AutoMove,
            success,
            duration_s,
            path_m: 20.0,
            trajectory: vec![[0.0, 0.0], [20.0, 0.0]],
            outcome: String::new(),
            segments: Vec::new(),
            route: None,
        }
    }

    fn sojourn(state: StateName, duration_s: f64) -> Sojourn {
        Sojourn {
            state,
            duration_s,
            ended: false,
        }
    }

    fn mission() -> MissionRecord {
        MissionRecord {
            mission: 1,
            success: true,
            outcome: "goal".into(),
            duration_s: 100.0,
            localizer: vec![sojourn(StateName::Success, 100.0)],
            planner: vec![sojourn(StateName::Normal, 100.0)],
            time_automove_s: 99.9,
            time_contour_s: 0.0,
            decisions: Vec::new(),
            segments: vec![Segment {
                behaviour: Behaviour::AutoMove,
                localized: true,
                normal: true,
                context: 0,
                duration_s: 99.9,
                progress_m: None,
                end: SegmentEnd::Mission,
            }],
            route: None,
        }
    }

    fn field(e: Result<Verdict, Inconsistent>) -> String {
        e.unwrap_err().field
    }

    #[test]
    fn a_sound_mission_and_calibration_run_are_kept() {
        assert_eq!(check(&Entry::Mission(mission())), Ok(Verdict::Kept));
        assert_eq!(
            check(&Entry::Calibration(calibration(true, 61.2))),
            Ok(Verdict::Kept)
        );
        // A failed run of 0 s is fine; a successful one is skipped.
        assert_eq!(
            check(&Entry::Calibration(calibration(false, 0.0))),
            Ok(Verdict::Kept)
        );
        assert!(matches!(
            check(&Entry::Calibration(calibration(true, 0.0))),
            Ok(Verdict::Skipped(_))
        ));
    }

    /// Regression (issue 51): these were read and learnt from.
    #[test]
    fn inconsistent_entries_name_their_field() {
        let c = |f: fn(&mut CalibrationRun)| {
            let mut r = calibration(true, 60.0);
            f(&mut r);
            field(check(&Entry::Calibration(r)))
        };
        assert_eq!(c(|r| r.duration_s = -49.9), "duration_s");
        assert_eq!(c(|r| r.duration_s = 1e308), "duration_s");
        assert_eq!(c(|r| r.path_m = -1.0), "path_m");
        assert_eq!(c(|r| r.outcome = "collision".into()), "success");
        assert_eq!(c(|r| r.outcome = "gaol".into()), "outcome");
        let m = |f: fn(&mut MissionRecord)| {
            let mut r = mission();
            f(&mut r);
            field(check(&Entry::Mission(r)))
        };
        assert_eq!(m(|r| r.success = false), "success");
        assert_eq!(m(|r| r.outcome = "lunch".into()), "outcome");
        assert_eq!(m(|r| r.mission = 0), "mission");
        assert_eq!(m(|r| r.duration_s = f64::NAN), "duration_s");
        assert_eq!(
            m(|r| r.localizer[0].duration_s = 150.0),
            "localizer (its sojourns' sum)"
        );
        assert_eq!(
            m(|r| r.localizer[0].state = StateName::Normal),
            "localizer[0].state"
        );
        assert_eq!(m(|r| r.planner[0].duration_s = -1.0), "planner[0].duration_s");
        assert_eq!(m(|r| r.time_contour_s = 50.0), "time_automove_s + time_contour_s");
        assert_eq!(m(|r| r.segments[0].context = 3), "segments[0].context");
        assert_eq!(
            m(|r| r.segments[0].duration_s = 101.0),
            "segments (their durations' sum)"
        );
        let decision = DecisionLog {
            time_s: 10.0,
            reason: "start".into(),
            rates: vec![1.0; 15],
            f_auto: 0.01,
            f_cont: 0.005,
            p_loc_succ: 0.9,
            p_loc_warn: 0.1,
            choice: Behaviour::AutoMove,
            context: Some(1),
            route: None,
            contour_rates: Vec::new(),
            marking: Vec::new(),
            explore: false,
        };
        let d = |f: fn(&mut DecisionLog)| {
            let mut r = mission();
            let mut d = decision.clone();
            f(&mut d);
            r.decisions = vec![d];
            check(&Entry::Mission(r)).map_err(|e| e.field)
        };
        assert_eq!(d(|_| {}), Ok(Verdict::Kept));
        assert_eq!(d(|d| d.time_s = 200.0), Err("decisions[0].time_s".into()));
        assert_eq!(d(|d| d.rates.truncate(3)), Err("decisions[0].rates".into()));
        assert_eq!(d(|d| d.rates[6] = 0.0), Err("decisions[0].rates".into()));
        assert_eq!(d(|d| d.p_loc_warn = 1.5), Err("decisions[0].p_loc_warn".into()));
        assert_eq!(d(|d| d.context = Some(5)), Err("decisions[0].context".into()));
        let crediting = |d: &mut DecisionLog| {
            d.contour_rates = vec![2.0; 15];
            d.route = Some("hall → gallery".into());
            d.marking = vec!["P0".into(), "P6".into(), "P7".into()];
            d.explore = true;
        };
        assert_eq!(d(crediting), Ok(Verdict::Kept));
        let e = |f: fn(&mut DecisionLog)| {
            let mut r = mission();
            let mut x = decision.clone();
            crediting(&mut x);
            f(&mut x);
            r.decisions = vec![x];
            check(&Entry::Mission(r)).map_err(|e| e.field)
        };
        let rates = Err("decisions[0].contour_rates".into());
        assert_eq!(e(|d| d.contour_rates.truncate(11)), rates.clone());
        assert_eq!(e(|d| d.contour_rates[3] = f64::NAN), rates);
        assert_eq!(
            e(|d| d.route = Some(" ".into())),
            Err("decisions[0].route".into())
        );
        let marking = Err("decisions[0].marking".into());
        assert_eq!(e(|d| d.marking[1] = "P5".into()), Ok(Verdict::Kept));
        assert_eq!(e(|d| d.marking[1] = "P9".into()), marking.clone());
        assert_eq!(e(|d| d.marking.push("P5".into())), marking.clone());
        assert_eq!(
            e(|d| {
                d.marking.remove(0);
            }),
            marking
        );
        // Rounding is not time.
        let mut r = mission();
        r.localizer[0].duration_s = 100.0 + 1e-9;
        assert_eq!(check(&Entry::Mission(r)), Ok(Verdict::Kept));
    }
}
