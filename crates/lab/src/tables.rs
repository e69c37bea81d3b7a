//! Tables of summaries: the one-row-per-scenario table every suite can
//! show (with the metric columns the suite chooses), CSV, and the number
//! formats every report uses ([`sig`], [`rate`], [`num`]).

use std::collections::BTreeSet;
use std::fmt::Write as _;

use crate::summary::Summary;

/// A metric shown as a column of the generic table: its mean per run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MetricColumn {
    /// The metric's name in the records.
    pub metric: &'static str,
    /// Column heading in Markdown and HTML.
    pub heading: &'static str,
    /// Column heading in the terminal table (short).
    pub short: &'static str,
    /// Decimals shown.
    pub decimals: usize,
}

/// `v` with at most `digits` significant digits (1 to 17), trailing zeros
/// dropped: in plain form when `1e-4 ≤ |v| < 1e7` (`0.0123`, `2.5`,
/// `123457`), else in scientific form (`6.67e-5`, `1.5e9`). The one
/// formatter of the numbers the reports print in prose and tables, so that
/// no report shows a float's every digit (`0.0000666666666667`).
///
/// ```
/// use lab::tables::sig;
/// assert_eq!(sig(1.0 / 15_000.0, 3), "6.67e-5");
/// assert_eq!(sig(0.005, 3), "0.005");
/// assert_eq!(sig(2.0 / 3.0, 6), "0.666667");
/// assert_eq!(sig(1_234_567.0, 3), "1230000");
/// assert_eq!(sig(-0.5, 2), "-0.5");
/// ```
pub fn sig(v: f64, digits: usize) -> String {
    if v == 0.0 {
        return "0".into();
    }
    if !v.is_finite() {
        return format!("{v}");
    }
    let digits = digits.clamp(1, 17);
    // Round first, so that 9.9996 with 4 digits is 10 (two integer digits).
    let rounded: f64 = format!("{v:.prec$e}", prec = digits - 1).parse().unwrap_or(v);
    let a = rounded.abs();
    if (1e-4..1e7).contains(&a) {
        let magnitude = a.log10().floor() as i32;
        let decimals = (digits as i32 - 1 - magnitude).max(0) as usize;
        let s = format!("{rounded:.decimals$}");
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        }
    } else {
        let s = format!("{rounded:.prec$e}", prec = digits - 1);
        match s.split_once('e') {
            Some((mantissa, exp)) if mantissa.contains('.') => {
                let m = mantissa.trim_end_matches('0').trim_end_matches('.');
                format!("{m}e{exp}")
            }
            _ => s,
        }
    }
}

/// A number with six significant digits, in plain form when
/// `1e-4 ≤ |v| < 1e7` (whole numbers up to 1e7 in full) and in scientific
/// form with its six digits otherwise (`2.50000e-9`): the command line's
/// tables of measures (`gspn solve`), whose columns keep one width.
pub fn num(v: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    if !v.is_finite() {
        return format!("{v}");
    }
    let a = v.abs();
    if (1e-4..1e7).contains(&a) {
        let digits = (5 - a.log10().floor() as i32).clamp(0, 10) as usize;
        let s = format!("{v:.digits$}");
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        }
    } else {
        format!("{v:.5e}")
    }
}

/// A rate or a probability in prose: three significant digits ([`sig`];
/// `0.000066667` is `6.67e-5`).
pub fn rate(v: f64) -> String {
    sig(v, 3)
}

/// `n` runs that ended with `outcome`, in words (`3 time limits`, `1 collision`, `2 lost`).
pub fn outcome_in_words(outcome: &str, n: usize) -> String {
    let plural = if n == 1 { "" } else { "s" };
    match outcome {
        "time_limit" => format!("{n} time limit{plural}"),
        "collision" => format!("{n} collision{plural}"),
        "gave_up" => format!("{n} gave up"),
        other => format!("{n} {}", other.replace('_', " ")),
    }
}

/// `I_R` with two decimals, `-` without runs.
pub fn fmt_ir(s: &Summary) -> String {
    if s.runs == 0 {
        "-".into()
    } else {
        format!("{:.2}", s.reliability.value)
    }
}

/// `I_T` with one decimal, `-` without successful runs.
pub fn fmt_it(s: &Summary) -> String {
    if s.time.n == 0 {
        "-".into()
    } else {
        format!("{:.1}", s.time.mean)
    }
}

/// Smallest width of the scenario column of the terminal table.
const NAME_WIDTH: usize = 24;

/// Column widths of the terminal table after the scenario's.
const WIDTHS: [usize; 9] = [5, 6, 15, 8, 6, 8, 10, 8, 5];

/// Smallest width of a metric column in the terminal table.
const METRIC_WIDTH: usize = 9;

/// One row per scenario, for any suite, with `metrics` as extra columns:
/// (terminal text, Markdown).
pub fn generic_table(summaries: &[Summary], metrics: &[MetricColumn]) -> (String, String) {
    let mut md = String::from(
        "| scenario | runs | I_R | 95% CI | I_T (s) | ± | path (m) | collisions | timeouts | lost |",
    );
    for m in metrics {
        let _ = write!(md, " {} |", m.heading);
    }
    md.push_str("\n|---|---:|---:|---|---:|---:|---:|---:|---:|---:|");
    md.push_str(&"---:|".repeat(metrics.len()));
    md.push('\n');
    const HEADS: [&str; 10] = [
        "scenario",
        "runs",
        "I_R",
        "95% CI",
        "I_T (s)",
        "±",
        "path(m)",
        "collisions",
        "timeouts",
        "lost",
    ];
    let widths: Vec<usize> = WIDTHS
        .iter()
        .copied()
        .chain(metrics.iter().map(|m| m.short.chars().count().max(METRIC_WIDTH)))
        .collect();
    let name_width = summaries
        .iter()
        .map(|s| s.scenario.chars().count())
        .max()
        .unwrap_or(0)
        .max(NAME_WIDTH);
    let mut txt = format!("{:<name_width$}", HEADS[0]);
    let heads = HEADS[1..].iter().copied().chain(metrics.iter().map(|m| m.short));
    for (h, w) in heads.zip(&widths) {
        let _ = write!(txt, " {h:>w$}");
    }
    txt.push('\n');
    for s in summaries {
        // A scenario not run yet (a shard's part, a partial batch) has no
        // interval: a dash, not `NaN–NaN`.
        let ci = if s.runs > 0 {
            format!("{:.2}–{:.2}", s.reliability.low, s.reliability.high)
        } else {
            "-".into()
        };
        let hw = if s.time.half_width.is_finite() {
            format!("{:.1}", s.time.half_width)
        } else {
            "-".into()
        };
        let path = if s.path_length.n > 0 {
            format!("{:.2}", s.path_length.mean)
        } else {
            "-".into()
        };
        let mut cells = vec![
            s.scenario.clone(),
            s.runs.to_string(),
            fmt_ir(s),
            ci,
            fmt_it(s),
            hw,
            path,
            s.collisions.to_string(),
            s.timeouts.to_string(),
            s.lost.to_string(),
        ];
        for m in metrics {
            let v = s.metric_mean(m.metric);
            cells.push(if v.is_finite() {
                format!("{v:.prec$}", prec = m.decimals)
            } else {
                "-".into()
            });
        }
        let _ = writeln!(md, "| {} |", cells.join(" | "));
        let _ = write!(txt, "{:<name_width$}", cells[0]);
        for (c, w) in cells[1..].iter().zip(&widths) {
            let _ = write!(txt, " {c:>w$}");
        }
        txt.push('\n');
    }
    (txt, md)
}

/// The summaries as CSV (one row per scenario); every metric found in
/// any summary gets a mean and a half-width column (`<name>_mean`,
/// `<name>_half_width`), in name order.
pub fn csv(summaries: &[Summary]) -> String {
    let names: BTreeSet<&str> = summaries
        .iter()
        .flat_map(|s| s.metrics.keys().map(String::as_str))
        .collect();
    let mut out = String::from(
        "scenario,runs,successes,I_R,I_R_low,I_R_high,I_T_s,I_T_half_width_s,path_length_m,collisions,timeouts,gave_up,lost",
    );
    for n in &names {
        let _ = write!(out, ",{n}_mean,{n}_half_width");
    }
    out.push('\n');
    for s in summaries {
        let _ = write!(
            out,
            "{},{},{},{},{},{},{},{},{},{},{},{},{}",
            s.scenario,
            s.runs,
            s.reliability.successes,
            s.reliability.value,
            s.reliability.low,
            s.reliability.high,
            s.time.mean,
            s.time.half_width,
            s.path_length.mean,
            s.collisions,
            s.timeouts,
            s.gave_up,
            s.lost,
        );
        for n in &names {
            match s.metrics.get(*n) {
                Some(m) => {
                    let _ = write!(out, ",{},{}", m.mean, m.half_width);
                }
                None => out.push_str(",,"),
            }
        }
        out.push('\n');
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::record::RunRecord;

    fn summary(name: &str, deadlocks: Option<f64>) -> Summary {
        let r = RunRecord {
            success: true,
            outcome: "goal".into(),
            time_s: 10.0,
            path_length_m: 2.0,
            collisions: 0,
            min_clearance_m: 0.5,
            odometry_error_m: 0.0,
            goal_distance_m: 0.1,
            ticks: 100,
            behaviour_ticks: Default::default(),
            metrics: deadlocks
                .map(|d| ("deadlocks".to_string(), d))
                .into_iter()
                .collect(),
            events: Vec::new(),
            start: [0.0; 3],
            trap: None,
            state: None,
        };
        Summary::of(name, &[&r])
    }

    #[test]
    fn a_scenario_not_run_yet_shows_dashes_not_nan() {
        let none = Summary::of("later", &[]);
        let (txt, md) = generic_table(&[summary("a", None), none], &[]);
        assert!(!md.contains("NaN") && !txt.contains("NaN"), "{md}\n{txt}");
        assert!(
            md.lines().nth(3).unwrap().starts_with("| later | 0 | - | - |"),
            "{md}"
        );
    }

    #[test]
    fn metric_columns_are_the_suites_choice_and_missing_values_show_as_dashes() {
        let col = MetricColumn {
            metric: "deadlocks",
            heading: "dead-locks/run",
            short: "deadlocks",
            decimals: 2,
        };
        let ss = [summary("a", Some(3.0)), summary("b", None)];
        let (txt, md) = generic_table(&ss, &[col]);
        assert!(
            md.starts_with("| scenario |") && md.contains("| dead-locks/run |"),
            "{md}"
        );
        assert!(
            md.contains("| 3.00 |") && md.lines().nth(3).unwrap().ends_with("| - |"),
            "{md}"
        );
        assert!(txt.lines().next().unwrap().ends_with("deadlocks"), "{txt}");
        let (_, plain) = generic_table(&ss, &[]);
        assert!(!plain.contains("dead-locks"));
        let csv = csv(&ss);
        assert!(
            csv.lines()
                .next()
                .unwrap()
                .ends_with(",lost,deadlocks_mean,deadlocks_half_width"),
            "{csv}"
        );
        assert!(csv.lines().nth(2).unwrap().ends_with(",,"), "{csv}");
    }
}
