//! Reports: summaries per scenario, tables (Markdown, CSV, text), pictures
//! of trajectories, and an `index.html` that opens offline.
//!
//! Everything is recomputed from a results folder: `suite.json` (which
//! scenarios, runs, seed) and `results.jsonl` (one record per run). Pictures
//! re-simulate a few runs with tracing on — runs are reproducible from their
//! seeds, so this draws exactly the runs that were counted.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use robot::Vec2;
use serde_json::Value;
use sim::render::{MarkerKind, Picture};
use sim::{Cell, CellIndex, OccupancyGrid, Trace, TraceParams};

use crate::experiment::{Prepared, RunRecord};
use crate::runner;
use crate::stats::{Mean, Proportion};
use crate::suite::{Suite, SuiteInfo, SuiteKind};

/// Confidence level of every interval in reports.
pub const CONFIDENCE: f64 = 0.95;

/// The summary of one scenario's runs.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Summary {
    /// Scenario.
    pub scenario: String,
    /// Runs found.
    pub runs: usize,
    /// Reliability index `I_R` = successes / runs, with its Wilson interval.
    pub reliability: Proportion,
    /// Time index `I_T`: mean time to goal over successful runs, seconds.
    pub time: Mean,
    /// Mean path length of successful runs, metres.
    pub path_length: Mean,
    /// Runs ended by a collision.
    pub collisions: usize,
    /// Runs ended by the time limit.
    pub timeouts: usize,
    /// Runs in which the controller gave up.
    pub gave_up: usize,
    /// Runs in which the controller stopped away from the goal, believing
    /// it had arrived (odometry error).
    pub lost: usize,
    /// Mean dead-locks detected per run.
    pub deadlocks_per_run: f64,
    /// Failed runs in which no dead-lock was detected.
    pub failures_without_deadlock: usize,
    /// Share of control time of each behaviour/action over all runs.
    pub behaviour_share: BTreeMap<String, f64>,
}

/// Run-by-run comparison of two scenarios of a batch (common random
/// numbers: run k of both met the same draws).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
pub struct Paired {
    /// Run indices found in both.
    pub runs: usize,
    /// Runs that succeeded in the second scenario and failed in the first.
    pub wins: usize,
    /// Runs that failed in the second and succeeded in the first.
    pub losses: usize,
    /// Runs whose records are identical in both.
    pub identical: usize,
}

/// The records of a results file by scenario: `(run index, record)` in
/// the file's order.
pub type Runs = BTreeMap<String, Vec<(u32, RunRecord)>>;

/// Parses the lines of a results file ([`runner::read_results`]) once, for
/// the summaries and the run-by-run comparisons.
pub fn group(records: &[Value]) -> Result<Runs> {
    let mut by = Runs::new();
    for r in records {
        let name = r
            .get("scenario")
            .and_then(Value::as_str)
            .context("record without scenario")?;
        let run = r
            .get("run")
            .and_then(Value::as_u64)
            .and_then(|k| u32::try_from(k).ok())
            .with_context(|| format!("record of {name} without a run index"))?;
        let rec: RunRecord =
            serde_json::from_value(r.clone()).with_context(|| format!("record of {name}"))?;
        by.entry(name.to_string()).or_default().push((run, rec));
    }
    Ok(by)
}

/// Compares scenario `b` with scenario `a` run by run.
pub fn paired(runs: &Runs, a: &str, b: &str) -> Paired {
    let empty = Vec::new();
    let ra = runs.get(a).unwrap_or(&empty);
    let rb: BTreeMap<u32, &RunRecord> = runs
        .get(b)
        .unwrap_or(&empty)
        .iter()
        .map(|(k, r)| (*k, r))
        .collect();
    let mut p = Paired::default();
    for (run, x) in ra {
        let Some(y) = rb.get(run) else { continue };
        p.runs += 1;
        match (x.success, y.success) {
            (false, true) => p.wins += 1,
            (true, false) => p.losses += 1,
            _ => {}
        }
        if x == *y {
            p.identical += 1;
        }
    }
    p
}

/// Summarises the records of each scenario, in the suite's order.
pub fn summarise(info: &SuiteInfo, runs: &Runs) -> Vec<Summary> {
    info.scenarios
        .iter()
        .map(|name| {
            let rs: Vec<&RunRecord> = runs
                .get(name)
                .map_or(Vec::new(), |v| v.iter().map(|(_, r)| r).collect());
            let ok: Vec<&RunRecord> = rs.iter().copied().filter(|r| r.success).collect();
            let times: Vec<f64> = ok.iter().map(|r| r.time_s).collect();
            let lengths: Vec<f64> = ok.iter().map(|r| r.path_length_m).collect();
            let mut share: BTreeMap<String, f64> = BTreeMap::new();
            let total: u64 = rs.iter().flat_map(|r| r.behaviour_ticks.values()).sum();
            for r in &rs {
                for (k, &v) in &r.behaviour_ticks {
                    *share.entry(k.clone()).or_insert(0.0) += v as f64;
                }
            }
            if total > 0 {
                share.values_mut().for_each(|v| *v /= total as f64);
            }
            let count = |o: &str| rs.iter().filter(|r| r.outcome == o).count();
            Summary {
                scenario: name.clone(),
                runs: rs.len(),
                reliability: Proportion::new(ok.len(), rs.len(), CONFIDENCE),
                time: Mean::new(&times, CONFIDENCE),
                path_length: Mean::new(&lengths, CONFIDENCE),
                collisions: count("collision"),
                timeouts: count("time_limit"),
                gave_up: count("gave_up"),
                lost: count("lost"),
                deadlocks_per_run: if rs.is_empty() {
                    f64::NAN
                } else {
                    rs.iter().map(|r| f64::from(r.deadlocks)).sum::<f64>() / rs.len() as f64
                },
                failures_without_deadlock: rs.iter().filter(|r| !r.success && r.deadlocks == 0).count(),
                behaviour_share: share,
            }
        })
        .collect()
}

fn fmt_ir(s: &Summary) -> String {
    if s.runs == 0 {
        "-".into()
    } else {
        format!("{:.2}", s.reliability.value)
    }
}

fn fmt_it(s: &Summary) -> String {
    if s.time.n == 0 {
        "-".into()
    } else {
        format!("{:.1}", s.time.mean)
    }
}

/// The voting suite's four `I_R`/`I_T` tables side by side: one row per
/// field, two columns per combination. Returns (text, markdown).
pub fn voting_tables(summaries: &[Summary]) -> (String, String) {
    let by: BTreeMap<&str, &Summary> = summaries.iter().map(|s| (s.scenario.as_str(), s)).collect();
    let mut fields: Vec<&str> = Vec::new();
    let mut experiments: Vec<&str> = Vec::new();
    for s in summaries {
        if let Some((e, f)) = s.scenario.split_once('/') {
            if !fields.contains(&f) {
                fields.push(f);
            }
            if !experiments.contains(&e) {
                experiments.push(e);
            }
        }
    }
    let mut md = String::from("| field |");
    for e in &experiments {
        let _ = write!(md, " {e} I_R | {e} I_T (s) |");
    }
    md.push_str("\n|---|");
    md.push_str(&"---:|---:|".repeat(experiments.len()));
    md.push('\n');
    let mut txt = String::new();
    let _ = write!(txt, "{:<8}", "");
    for e in &experiments {
        let label = crate::suite::experiment_label(e).unwrap_or_default();
        let _ = write!(txt, "  {:<22}", format!("{e} {label}"));
    }
    txt.push('\n');
    let _ = write!(txt, "{:<8}", "field");
    for _ in &experiments {
        let _ = write!(txt, "  {:>8} {:>13}", "I_R", "I_T (s)");
    }
    txt.push('\n');
    for f in &fields {
        let _ = write!(md, "| {f} |");
        let _ = write!(txt, "{f:<8}");
        for e in &experiments {
            match by.get(format!("{e}/{f}").as_str()) {
                Some(s) => {
                    let _ = write!(md, " {} | {} |", fmt_ir(s), fmt_it(s));
                    let _ = write!(txt, "  {:>8} {:>13}", fmt_ir(s), fmt_it(s));
                }
                None => {
                    md.push_str(" - | - |");
                    let _ = write!(txt, "  {:>8} {:>13}", "-", "-");
                }
            }
        }
        md.push('\n');
        txt.push('\n');
    }
    (txt, md)
}

/// Column widths of the text table after the scenario's (24).
const WIDTHS: [usize; 10] = [5, 6, 15, 8, 6, 8, 10, 8, 5, 9];

/// One row per scenario, for any suite: (text, markdown).
pub fn generic_table(summaries: &[Summary]) -> (String, String) {
    let mut md = String::from(
        "| scenario | runs | I_R | 95% CI | I_T (s) | ± | path (m) | collisions | timeouts | lost | dead-locks/run |\n|---|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    const HEADS: [&str; 11] = [
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
        "deadlocks",
    ];
    let mut txt = format!("{:<24}", HEADS[0]);
    for (h, w) in HEADS[1..].iter().zip(WIDTHS) {
        let _ = write!(txt, " {h:>w$}");
    }
    txt.push('\n');
    for s in summaries {
        let ci = format!("{:.2}–{:.2}", s.reliability.low, s.reliability.high);
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
        let cells = [
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
            format!("{:.2}", s.deadlocks_per_run),
        ];
        let _ = writeln!(md, "| {} |", cells.join(" | "));
        let _ = write!(txt, "{:<24}", cells[0]);
        for (c, w) in cells[1..].iter().zip(WIDTHS) {
            let _ = write!(txt, " {c:>w$}");
        }
        txt.push('\n');
    }
    (txt, md)
}

/// The summaries as CSV (one row per scenario).
pub fn csv(summaries: &[Summary]) -> String {
    let mut out = String::from(
        "scenario,runs,successes,I_R,I_R_low,I_R_high,I_T_s,I_T_half_width_s,path_length_m,collisions,timeouts,gave_up,lost,deadlocks_per_run\n",
    );
    for s in summaries {
        let _ = writeln!(
            out,
            "{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
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
            s.deadlocks_per_run
        );
    }
    out
}

/// Runs drawn per picture.
pub const RUNS_PER_PICTURE: u32 = 8;

/// Draws the first runs of a scenario (re-simulated with tracing on),
/// trajectories coloured by the behaviour/action in control; saves PNG.
///
/// Obstacles are drawn black where they stand in every drawn run and grey
/// where the per-run jitter put them in some runs only; a run that ended in
/// a collision ends with a small square, dead-locks detected are marked
/// with a small square too.
pub fn picture(suite: &Suite, scenario: &str, runs: u32, path: &Path) -> Result<()> {
    let prep = suite
        .scenario(scenario)
        .with_context(|| format!("unknown scenario `{scenario}`"))?;
    let s = prep.scenario();
    let trace_params = TraceParams {
        enabled: true,
        perception: false,
        people: false,
    };
    let mut outputs = Vec::new();
    for run in 0..runs.min(suite.runs) {
        outputs.push(prep.run_detailed(suite.seeds(run), trace_params)?);
    }
    let grid = composite_grid(prep.base_grid()?, outputs.iter().filter_map(|o| o.grid.as_ref()));
    let mut pic = Picture::new(&grid);
    pic.marker(Vec2::new(s.goal.x, s.goal.y), MarkerKind::Goal);
    for out in &outputs {
        let Some(trace) = &out.trace else { continue };
        let poses = draw_run(&mut pic, &out.record, trace, false);
        if out.record.outcome == "collision"
            && let Some(last) = poses.last()
        {
            pic.marker(last.position(), MarkerKind::Point);
        }
    }
    pic.save(path)
        .with_context(|| format!("writing {}", path.display()))?;
    Ok(())
}

/// The picture of one run in its own world: trajectory coloured by the
/// behaviour in control, the footprint every 2 s and at the end, the
/// activity trace (`CP2` orange and `CP3` purple squares where they
/// happened) and detected dead-locks (magenta rings); PNG or SVG by
/// extension.
pub fn run_picture(
    prep: &Prepared,
    grid: &OccupancyGrid,
    record: &RunRecord,
    trace: &Trace,
    path: &Path,
) -> Result<()> {
    let s = prep.scenario();
    let radius = s.robot.robot_params().drive.radius_m;
    let mut pic = Picture::new(grid);
    pic.marker(Vec2::new(s.goal.x, s.goal.y), MarkerKind::Goal);
    let every = (2.0 / s.control_period_s).round().max(1.0) as usize;
    for (k, t) in trace.ticks.iter().enumerate() {
        if k % every == 0 || k + 1 == trace.ticks.len() {
            pic.robot(t.true_pose, radius);
        }
    }
    draw_run(&mut pic, record, trace, true);
    pic.save(path)
        .with_context(|| format!("writing {}", path.display()))?;
    Ok(())
}

/// Colour of `CP2` markers (goal tracking takes control).
pub const CP2_RGB: [u8; 3] = [255, 127, 14];
/// Colour of `CP3` markers (blocked with the goal ahead).
pub const CP3_RGB: [u8; 3] = [148, 103, 189];
/// Colour of detected dead-locks.
pub const DEADLOCK_RGB: [u8; 3] = [227, 0, 140];

/// Where a controller's `deadlock at (x, y)` event put the dead-lock (the
/// centroid of its `CP2, CP3, CP2` chunk, in the controller's odometry
/// frame).
pub fn deadlock_point(event: &str) -> Option<Vec2> {
    let inner = event.strip_prefix("deadlock at (")?.strip_suffix(')')?;
    let (x, y) = inner.split_once(',')?;
    Some(Vec2::new(x.trim().parse().ok()?, y.trim().parse().ok()?))
}

/// Draws a run's trajectory coloured by the behaviour in control, its
/// start, the dead-locks it detected (rings at the chunks' centroids) and,
/// with `events`, its activity trace: a small square where each `CP2`
/// (orange) and `CP3` (purple) happened. Returns the poses.
fn draw_run(pic: &mut Picture<'_>, record: &RunRecord, trace: &Trace, events: bool) -> Vec<robot::Pose> {
    let poses: Vec<robot::Pose> = trace.ticks.iter().map(|t| t.true_pose).collect();
    let labels: Vec<&str> = trace
        .ticks
        .iter()
        .map(|t| t.behaviour.unwrap_or("none"))
        .collect();
    pic.trajectory(&poses, Some(&labels));
    pic.marker(Vec2::new(record.start[0], record.start[1]), MarkerKind::Start);
    // CP2 first, then CP3 over them, then dead-locks on top: the rarer the
    // event, the later it is drawn.
    let mut cp2 = Vec::new();
    let mut cp3 = Vec::new();
    let mut deadlocks = Vec::new();
    for t in &trace.ticks {
        for e in &t.events {
            match e.as_str() {
                "CP2" if events => cp2.push(t.true_pose.position()),
                "CP3" if events => cp3.push(t.true_pose.position()),
                _ => deadlocks.extend(deadlock_point(e)),
            }
        }
    }
    for &at in &cp2 {
        pic.marker(at, MarkerKind::Square(CP2_RGB));
    }
    for &at in &cp3 {
        pic.marker(at, MarkerKind::Square(CP3_RGB));
    }
    for &at in &deadlocks {
        pic.marker(at, MarkerKind::Ring(DEADLOCK_RGB));
    }
    poses
}

/// Cells blocked in every grid stay occupied; cells blocked in some only
/// become unknown (grey). All grids have the same geometry.
fn composite_grid<'a>(base: OccupancyGrid, runs: impl Iterator<Item = &'a OccupancyGrid>) -> OccupancyGrid {
    let runs: Vec<&OccupancyGrid> = runs
        .filter(|g| g.width() == base.width() && g.height() == base.height())
        .collect();
    if runs.is_empty() {
        return base;
    }
    let mut out = base.clone();
    for j in 0..base.height() as i64 {
        for i in 0..base.width() as i64 {
            let c = CellIndex { i, j };
            let hits = runs.iter().filter(|g| g.get(c) == Cell::Occupied).count();
            let v = if hits == runs.len() {
                Cell::Occupied
            } else if hits > 0 {
                Cell::Unknown
            } else {
                Cell::Free
            };
            out.set(c, v);
        }
    }
    out
}

fn html_escape(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;")
}

/// Markdown table rows to an HTML table.
fn md_table_to_html(md: &str) -> String {
    let mut out = String::from("<table>\n");
    for (i, line) in md.lines().enumerate() {
        if i == 1 {
            continue;
        }
        let cells: Vec<&str> = line.trim().trim_matches('|').split('|').map(str::trim).collect();
        let tag = if i == 0 { "th" } else { "td" };
        out.push_str("<tr>");
        for c in cells {
            let _ = write!(out, "<{tag}>{}</{tag}>", html_escape(c));
        }
        out.push_str("</tr>\n");
    }
    out.push_str("</table>\n");
    out
}

/// What the written report contains.
#[derive(Debug, Clone)]
pub struct Written {
    /// The text tables printed to the terminal.
    pub text: String,
    /// Files written.
    pub files: Vec<PathBuf>,
}

/// Writes the report of a results folder: `summary.json`, `summary.csv`,
/// `tables.md`, pictures in `pictures/`, and `index.html`.
pub fn write(dir: &Path, suite: &Suite, info: &SuiteInfo, pictures: bool) -> Result<Written> {
    let (records, _) = runner::read_results(&dir.join("results.jsonl"))?;
    let runs = group(&records)?;
    let summaries = summarise(info, &runs);
    let mut files = Vec::new();
    let save = |files: &mut Vec<PathBuf>, name: &str, text: &str| -> Result<()> {
        let p = dir.join(name);
        std::fs::write(&p, text).with_context(|| format!("writing {}", p.display()))?;
        files.push(p);
        Ok(())
    };
    save(
        &mut files,
        "summary.json",
        &serde_json::to_string_pretty(&summaries)?,
    )?;
    save(&mut files, "summary.csv", &csv(&summaries))?;
    let (gtxt, gmd) = generic_table(&summaries);
    let (text, main_md) = match info.kind {
        SuiteKind::Voting => voting_tables(&summaries),
        SuiteKind::Custom | SuiteKind::Deadlock => (gtxt.clone(), gmd.clone()),
    };
    let explanation = match info.kind {
        SuiteKind::Voting => crate::voting_report::explanation(&summaries, &runs),
        SuiteKind::Deadlock => crate::deadlock_report::explanation(&summaries, &runs),
        SuiteKind::Custom => String::new(),
    };
    let mut md = format!(
        "# {} — results\n\n{} runs per scenario, base seed {}.\n\n",
        info.name, info.runs, info.seed
    );
    md.push_str(&main_md);
    md.push('\n');
    if info.kind == SuiteKind::Voting {
        md.push_str("\n## All scenarios\n\n");
        md.push_str(&gmd);
    }
    md.push_str(&explanation);
    save(&mut files, "tables.md", &md)?;

    let mut images = Vec::new();
    if pictures {
        let pdir = dir.join("pictures");
        std::fs::create_dir_all(&pdir)?;
        for name in &info.scenarios {
            let file = format!("{}.png", name.replace('/', "-"));
            picture(suite, name, RUNS_PER_PICTURE, &pdir.join(&file))?;
            images.push((name.clone(), format!("pictures/{file}")));
            files.push(pdir.join(file));
        }
    }

    let mut html = String::new();
    let _ = write!(
        html,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{0} — petrinav report</title>\n<style>\nbody{{font-family:system-ui,sans-serif;max-width:1200px;margin:2em auto;padding:0 1em;color:#222}}\ntable{{border-collapse:collapse;margin:1em 0;font-size:14px}}\ntd,th{{border:1px solid #ccc;padding:3px 8px;text-align:right}}\ntd:first-child,th:first-child{{text-align:left}}\nth{{background:#f2f2f2}}\n.pics{{display:flex;flex-wrap:wrap;gap:12px}}\nfigure{{margin:0;width:280px}}\nfigure img{{width:280px;border:1px solid #ccc}}\nfigcaption{{font-size:13px}}\n</style></head><body>\n<h1>{0}</h1>\n<p>{1} runs per scenario, base seed {2}. Intervals are {3}% (Wilson for I_R, Student-t for I_T). Raw data: <a href=\"results.jsonl\">results.jsonl</a>, <a href=\"summary.csv\">summary.csv</a>, <a href=\"summary.json\">summary.json</a>, <a href=\"tables.md\">tables.md</a>.</p>\n",
        html_escape(&info.name),
        info.runs,
        info.seed,
        CONFIDENCE * 100.0
    );
    html.push_str(&md_table_to_html(&main_md));
    if info.kind == SuiteKind::Voting {
        html.push_str("<h2>All scenarios</h2>\n");
        html.push_str(&md_table_to_html(&gmd));
    }
    for para in explanation.split("\n\n").filter(|p| !p.trim().is_empty()) {
        let p = para.trim();
        if let Some(h) = p.strip_prefix("## ") {
            let _ = writeln!(html, "<h2>{}</h2>", html_escape(h));
        } else {
            let _ = writeln!(html, "<p>{}</p>", html_escape(&p.replace('\n', " ")));
        }
    }
    if !images.is_empty() {
        let _ = writeln!(
            html,
            "<h2>Trajectories</h2>\n<p>The first {RUNS_PER_PICTURE} runs of each scenario, re-simulated from their seeds, coloured by the action or behaviour in control (legend in each picture); start green, goal red, detected dead-locks as magenta rings at the centroid of their `CP2, CP3, CP2` chunk. `petrinav lab replay` draws a single run with its whole activity trace: `CP2` orange squares, `CP3` purple.</p>\n<div class=\"pics\">"
        );
        for (name, src) in &images {
            let _ = writeln!(
                html,
                "<figure><a href=\"{src}\"><img src=\"{src}\" alt=\"{0}\"></a><figcaption>{0}</figcaption></figure>",
                html_escape(name)
            );
        }
        html.push_str("</div>\n");
    }
    html.push_str("</body></html>\n");
    save(&mut files, "index.html", &html)?;
    Ok(Written { text, files })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn deadlock_events_give_their_centroid() {
        // The format both controllers write (nav::activity, trace_layer).
        let e = format!("deadlock at ({:.2}, {:.2})", 2.191, -1.4349);
        assert_eq!(deadlock_point(&e), Some(Vec2::new(2.19, -1.43)));
        assert_eq!(deadlock_point("CP2"), None);
        assert_eq!(deadlock_point("deadlock at (x, 1)"), None);
    }

    #[test]
    fn paired_counts_wins_losses_and_identical_runs() {
        let rec = |scenario: &str, run: u32, success: bool, t: f64| {
            let r = RunRecord {
                success,
                outcome: if success { "goal" } else { "time_limit" }.into(),
                time_s: t,
                path_length_m: 1.0,
                collisions: 0,
                min_clearance_m: 0.5,
                odometry_error_m: 0.0,
                goal_distance_m: 0.1,
                ticks: 10,
                behaviour_ticks: BTreeMap::new(),
                deadlocks: 0,
                start: [0.0; 3],
                trap: None,
            };
            let mut v = serde_json::to_value(r).unwrap();
            v["scenario"] = scenario.into();
            v["key"] = format!("{scenario}#{run}").into();
            v["run"] = run.into();
            v
        };
        let records = vec![
            rec("a", 0, true, 10.0),
            rec("b", 0, true, 10.0),
            rec("a", 1, false, 120.0),
            rec("b", 1, true, 50.0),
            rec("a", 2, true, 20.0),
            rec("b", 2, false, 120.0),
            rec("a", 3, true, 20.0),
        ];
        let p = paired(&group(&records).unwrap(), "a", "b");
        assert_eq!(
            p,
            Paired {
                runs: 3,
                wins: 1,
                losses: 1,
                identical: 1
            }
        );
    }
}
