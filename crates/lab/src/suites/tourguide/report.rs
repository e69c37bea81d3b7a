//! The tour-guide suite's report: the source's experiment (one campaign of
//! 24 missions at moderate density), the learnt rates and decisions, one
//! mission's trajectory, the comparison of the strategies, and an
//! explanation — every figure from the batch's records.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use anyhow::{Context, Result};
use nav::supervisor::log::{Entry, Line};
use robot::Event;
use sim::TraceParams;

use super::{CALIBRATION_RUNS, DENSITIES, MISSIONS, STRATEGIES, TourGuideSuite, metric};
use crate::charts::{self, Bar, Series};
use crate::page::{Block, Figure};
use crate::pictures;
use crate::record::{RunRecord, Runs};
use crate::runner::Job;
use crate::stats::{Mean, Proportion, median};
use crate::suite::{ReportContext, Suite, SuiteReport};
use crate::summary::CONFIDENCE;
use crate::tables::{self, MetricColumn};

/// The records of `scenario` by run index.
fn by_run<'a>(runs: &'a Runs, scenario: &str) -> BTreeMap<u32, &'a RunRecord> {
    runs.get(scenario)
        .map(|v| v.iter().map(|(k, r)| (*k, r)).collect())
        .unwrap_or_default()
}

/// The first decision of a mission (at its start).
fn start_decision(r: &RunRecord) -> Option<&Event> {
    r.events
        .iter()
        .find(|e| e.kind == "decision" && e.text("reason") == Some("start"))
}

fn num(e: Option<&Event>, key: &str) -> f64 {
    e.and_then(|e| e.number(key)).unwrap_or(f64::NAN)
}

fn fmt_rate(x: f64) -> String {
    if x.is_finite() {
        format!("{x:.4}")
    } else {
        "-".into()
    }
}

/// The source's experiment: campaign 0 of the supervisor at moderate
/// density, mission by mission.
fn source_table(runs: &Runs) -> (String, Vec<&RunRecord>) {
    let rs = by_run(runs, "moderate/supervisor");
    let missions: Vec<&RunRecord> = (0..MISSIONS).filter_map(|m| rs.get(&m).copied()).collect();
    let mut md = String::from(
        "| mission | outcome | time (s) | λ3 | λ4 | λ5 | λ6 | f_auto | f_cont | choice | warnings | switches |\n|---:|---|---:|---:|---:|---:|---:|---:|---:|---|---:|---:|\n",
    );
    for (m, r) in missions.iter().enumerate() {
        let d = start_decision(r);
        let _ = writeln!(
            md,
            "| {} | {} | {:.1} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            m + 1,
            r.outcome.replace('_', " "),
            r.time_s,
            fmt_rate(num(d, "lambda3")),
            fmt_rate(num(d, "lambda4")),
            fmt_rate(num(d, "lambda5")),
            fmt_rate(num(d, "lambda6")),
            fmt_rate(num(d, "f_auto")),
            fmt_rate(num(d, "f_cont")),
            d.and_then(|e| e.text("choice")).unwrap_or("-"),
            r.metric(metric::WARNINGS).unwrap_or(0.0),
            r.metric(metric::SWITCHES).unwrap_or(0.0),
        );
    }
    (md, missions)
}

/// Mean over the campaigns of `scenario` of a start decision's value, per
/// mission.
fn per_mission_mean(runs: &Runs, scenario: &str, key: &str) -> Vec<(f64, f64)> {
    let rs = runs.get(scenario).map(Vec::as_slice).unwrap_or_default();
    (0..MISSIONS)
        .map(|m| {
            let v: Vec<f64> = rs
                .iter()
                .filter(|(k, _)| k % MISSIONS == m)
                .map(|(_, r)| num(start_decision(r), key))
                .filter(|x| x.is_finite())
                .collect();
            let mean = if v.is_empty() {
                f64::NAN
            } else {
                v.iter().sum::<f64>() / v.len() as f64
            };
            (f64::from(m + 1), mean)
        })
        .collect()
}

fn series(name: &str, points: Vec<(f64, f64)>) -> Series {
    Series {
        name: name.into(),
        points,
    }
}

/// Writes an SVG chart into the report folder and returns its figure.
fn save_svg(
    ctx: &ReportContext<'_>,
    file: &str,
    title: &str,
    svg: &str,
    files: &mut Vec<std::path::PathBuf>,
) -> Result<Figure> {
    let (path, src) = ctx.picture_path(file)?;
    std::fs::write(&path, svg).with_context(|| format!("writing {}", path.display()))?;
    files.push(path);
    Ok(Figure {
        title: title.into(),
        src,
        runs: Vec::new(),
    })
}

/// Mean and interval of a value over missions.
fn mean_of(rs: &[&RunRecord], f: impl Fn(&RunRecord) -> Option<f64>) -> Mean {
    let v: Vec<f64> = rs.iter().filter_map(|r| f(r)).collect();
    Mean::new(&v, CONFIDENCE)
}

/// What the comparison measures for a density and a strategy.
struct Cell {
    success: Proportion,
    time: Mean,
    warning: Mean,
    contour_share: f64,
    lost: usize,
    collisions: usize,
    timeouts: usize,
    missions: usize,
}

fn cell(rs: &[&RunRecord]) -> Cell {
    let ok: Vec<&RunRecord> = rs.iter().copied().filter(|r| r.success).collect();
    let drive: f64 = rs
        .iter()
        .map(|r| r.metric(metric::AUTOMOVE_S).unwrap_or(0.0) + r.metric(metric::CONTOUR_S).unwrap_or(0.0))
        .sum();
    let contour: f64 = rs.iter().filter_map(|r| r.metric(metric::CONTOUR_S)).sum();
    Cell {
        success: Proportion::new(ok.len(), rs.len(), CONFIDENCE),
        time: mean_of(&ok, |r| Some(r.time_s)),
        warning: mean_of(rs, |r| r.metric(metric::WARNING_S)),
        contour_share: if drive > 0.0 { contour / drive } else { f64::NAN },
        lost: rs.iter().filter(|r| r.outcome == "lost").count(),
        collisions: rs.iter().filter(|r| r.outcome == "collision").count(),
        timeouts: rs.iter().filter(|r| r.outcome == "time_limit").count(),
        missions: rs.len(),
    }
}

/// Mission by mission against the supervisor (same density, campaign and
/// mission: the same visitors and noise): successes gained and lost, and
/// the time difference on missions both completed.
struct Versus {
    both: usize,
    supervisor_only: usize,
    other_only: usize,
    /// Supervisor's time minus the other's, on missions both completed.
    time_diff: Mean,
}

fn versus(runs: &Runs, density: &str, other: &str) -> Versus {
    let sup = by_run(runs, &format!("{density}/supervisor"));
    let oth = by_run(runs, &format!("{density}/{other}"));
    let mut v = Versus {
        both: 0,
        supervisor_only: 0,
        other_only: 0,
        time_diff: Mean::new(&[], CONFIDENCE),
    };
    let mut diffs = Vec::new();
    for (k, a) in &sup {
        let Some(b) = oth.get(k) else { continue };
        v.both += 1;
        match (a.success, b.success) {
            (true, false) => v.supervisor_only += 1,
            (false, true) => v.other_only += 1,
            (true, true) => diffs.push(a.time_s - b.time_s),
            _ => {}
        }
    }
    v.time_diff = Mean::new(&diffs, CONFIDENCE);
    v
}

/// The report (module docs).
pub fn report(suite: &TourGuideSuite, ctx: &ReportContext<'_>) -> Result<SuiteReport> {
    let runs = ctx.runs;
    let mut blocks = Vec::new();
    let mut files = Vec::new();
    // The table of all scenarios.
    let columns = [
        MetricColumn {
            metric: metric::WARNING_S,
            heading: "in Warning (s)",
            short: "warn(s)",
            decimals: 1,
        },
        MetricColumn {
            metric: metric::CONTOUR_S,
            heading: "contour (s)",
            short: "cont(s)",
            decimals: 1,
        },
        MetricColumn {
            metric: metric::SWITCHES,
            heading: "switches",
            short: "switches",
            decimals: 2,
        },
        MetricColumn {
            metric: metric::LOC_MAX,
            heading: "true error max (m)",
            short: "err(m)",
            decimals: 2,
        },
    ];
    let (table_text, all) = tables::generic_table(ctx.summaries, &columns);

    // 1. The source's experiment.
    let (source_md, source) = source_table(runs);
    blocks.push(Block::Heading(
        "The source's experiment: 24 missions at moderate density".into(),
    ));
    let reached = source.iter().filter(|r| r.success).count();
    let auto_choices = source
        .iter()
        .filter(|r| start_decision(r).and_then(|e| e.text("choice")) == Some("automove"))
        .count();
    let f_cont: Vec<f64> = source.iter().map(|r| num(start_decision(r), "f_cont")).collect();
    let f_auto: Vec<f64> = source.iter().map(|r| num(start_decision(r), "f_auto")).collect();
    let spread = |v: &[f64]| {
        let f: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
        let (lo, hi) = f.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
            (a.min(x), b.max(x))
        });
        (lo, hi)
    };
    let (fc_lo, fc_hi) = spread(&f_cont);
    let (fa_lo, fa_hi) = spread(&f_auto);
    blocks.push(Block::Text(format!(
        "Campaign 0 of the GSPN supervisor at moderate density: {} calibration runs (each behaviour alone, {} times), then {} missions from (8.1, 6.4) to (8.5, 27.5), each deciding with the rates learnt from the log of all runs before it (the source ran 24 missions; 20 reached the goal). Here {reached} of {} reached the goal; at the start of the missions the supervisor chose AutoMove {auto_choices} times. Over the missions `f_cont` stayed within {fc_lo:.5}–{fc_hi:.5} while `f_auto` moved within {fa_lo:.5}–{fa_hi:.5}: {}.\n\n",
        2 * CALIBRATION_RUNS,
        CALIBRATION_RUNS,
        MISSIONS,
        source.len(),
        if fc_hi - fc_lo < 0.25 * (fa_hi - fa_lo) {
            "as in the source, f_cont is nearly constant while the localizer's and the planner's learnt rates move f_auto"
        } else {
            "NOT as in the source: f_cont moves as much as f_auto"
        },
    )));
    blocks.push(Block::Table(source_md));

    // Charts of the decisions over the missions.
    let mut figures = Vec::new();
    let per = |key: &str| -> Vec<(f64, f64)> {
        source
            .iter()
            .enumerate()
            .map(|(m, r)| ((m + 1) as f64, num(start_decision(r), key)))
            .collect()
    };
    let svg = charts::lines(
        "f_auto and f_cont at the start of each mission",
        "mission",
        "throughput (1/s)",
        &[
            series("f_auto (campaign 0)", per("f_auto")),
            series("f_cont (campaign 0)", per("f_cont")),
            series(
                "f_auto (mean of the campaigns)",
                per_mission_mean(runs, "moderate/supervisor", "f_auto"),
            ),
            series(
                "f_cont (mean of the campaigns)",
                per_mission_mean(runs, "moderate/supervisor", "f_cont"),
            ),
        ],
        false,
        (760, 380),
    )?;
    figures.push(save_svg(
        ctx,
        "f_over_missions.svg",
        "f_auto and f_cont over the missions",
        &svg,
        &mut files,
    )?);
    let svg = charts::lines(
        "Learnt rates at the start of each mission (campaign 0)",
        "mission",
        "rate (1/s)",
        &[
            series("λ3 Success → Warning", per("lambda3")),
            series("λ4 Warning → Success", per("lambda4")),
            series("λ5 Normal → Abnormal", per("lambda5")),
            series("λ6 Abnormal → Normal", per("lambda6")),
        ],
        true,
        (760, 380),
    )?;
    figures.push(save_svg(
        ctx,
        "rates_over_missions.svg",
        "the learnt rates λ3…λ6",
        &svg,
        &mut files,
    )?);
    let svg = charts::lines(
        "The localizer's states in the chosen hypothesis",
        "mission",
        "probability",
        &[
            series("P_loc,succ", per("p_loc_succ")),
            series("P_loc,warn", per("p_loc_warn")),
        ],
        false,
        (760, 380),
    )?;
    figures.push(save_svg(
        ctx,
        "ploc_over_missions.svg",
        "P_loc,succ and P_loc,warn",
        &svg,
        &mut files,
    )?);
    blocks.push(Block::Charts {
        heading: "Decisions over the missions".into(),
        caption: "At the start of every mission the supervisor solves the net under both hypotheses with the rates learnt so far: λ3, λ4 from the localizer's sojourns, λ5, λ6 from the planner's, λ7, λ8 from the calibration runs, λ9, λ10 from failures and successes.".into(),
        figures,
    });

    // One mission's trajectory, with its switches.
    if ctx.pictures
        && let Some(figure) = mission_picture(suite, ctx, &source, &mut files)?
    {
        blocks.push(Block::Charts {
            heading: "One mission".into(),
            caption: "The first mission of campaign 0 in which the behaviour switched, re-simulated from its seed: the true trajectory coloured by the behaviour driving, the robot every 2 s, the localizer's warnings (orange squares) and the supervisor's decisions (purple rings). `petrinav lab replay out/tourguide 'moderate/supervisor#K' --trace t.jsonl` gives every event.".into(),
            figures: vec![figure],
        });
    }

    // 2. The comparison.
    blocks.push(Block::Heading("The comparison the source never made".into()));
    let mut md = String::from(
        "| density | strategy | missions | success (95 % CI) | time to goal (s) | in Warning (s) | contour share | true losses | collisions | time limits |\n|---|---|---:|---|---:|---:|---:|---:|---:|---:|\n",
    );
    let mut cells: BTreeMap<(usize, usize), Cell> = BTreeMap::new();
    for (d, (density, _)) in DENSITIES.iter().enumerate() {
        for (s, strategy) in STRATEGIES.iter().enumerate() {
            let rs: Vec<&RunRecord> = runs
                .get(&format!("{density}/{strategy}"))
                .map(|v| v.iter().map(|(_, r)| r).collect())
                .unwrap_or_default();
            let c = cell(&rs);
            let _ = writeln!(
                md,
                "| {density} | {strategy} | {} | {} | {} | {} | {} | {} | {} | {} |",
                c.missions,
                percent(&c.success),
                one_decimal(&c.time),
                one_decimal(&c.warning),
                if c.contour_share.is_finite() {
                    format!("{:.0} %", 100.0 * c.contour_share)
                } else {
                    "-".into()
                },
                c.lost,
                c.collisions,
                c.timeouts
            );
            cells.insert((d, s), c);
        }
    }
    blocks.push(Block::Text(format!(
        "{} campaigns of {MISSIONS} missions per density and strategy; mission m of campaign c meets the same visitors and noise under every strategy. Success with its Wilson interval, time to goal over the missions that reached it with its Student-t interval, time the localizer spent in Warning per mission, the share of driving time in contour tracking, true losses (the robot declared arrival where the goal was not, or its estimate stayed over 2 m off for 5 s).\n\n",
        suite.info().runs
    )));
    blocks.push(Block::Table(md));
    let groups: Vec<String> = DENSITIES.iter().map(|(d, _)| d.to_string()).collect();
    let names: Vec<String> = STRATEGIES.iter().map(|s| s.to_string()).collect();
    let success_bars: Vec<Vec<Bar>> = (0..DENSITIES.len())
        .map(|d| {
            (0..STRATEGIES.len())
                .map(|s| {
                    let p = &cells[&(d, s)].success;
                    Bar {
                        value: p.value,
                        low: p.low,
                        high: p.high,
                    }
                })
                .collect()
        })
        .collect();
    let time_bars: Vec<Vec<Bar>> = (0..DENSITIES.len())
        .map(|d| {
            (0..STRATEGIES.len())
                .map(|s| {
                    let m = &cells[&(d, s)].time;
                    Bar {
                        value: if m.n > 0 { m.mean } else { f64::NAN },
                        low: m.mean - m.half_width,
                        high: m.mean + m.half_width,
                    }
                })
                .collect()
        })
        .collect();
    let mut figures = vec![save_svg(
        ctx,
        "comparison_success.svg",
        "success by density and strategy",
        &charts::bars(
            "Missions that reached the goal",
            "share",
            &groups,
            &names,
            &success_bars,
            (760, 400),
        )?,
        &mut files,
    )?];
    figures.push(save_svg(
        ctx,
        "comparison_time.svg",
        "time to goal by density and strategy",
        &charts::bars(
            "Time to goal (missions that reached it)",
            "seconds",
            &groups,
            &names,
            &time_bars,
            (760, 400),
        )?,
        &mut files,
    )?);
    blocks.push(Block::Charts {
        heading: "The comparison, charted".into(),
        caption: "Bars: the value; whiskers: its 95 % interval.".into(),
        figures,
    });

    // 3. The explanation.
    blocks.push(Block::Heading(
        "What the supervisor gains or loses, and why".into(),
    ));
    let mut text = String::new();
    for (d, (density, _)) in DENSITIES.iter().enumerate() {
        // The first of the best (ties go to the earlier strategy, not to the
        // supervisor, which comes last).
        let best_success = (0..STRATEGIES.len())
            .rev()
            .max_by(|&a, &b| {
                cells[&(d, a)]
                    .success
                    .value
                    .total_cmp(&cells[&(d, b)].success.value)
            })
            .unwrap_or(0);
        let best_time = (0..STRATEGIES.len())
            .filter(|s| cells[&(d, *s)].time.n > 0)
            .min_by(|&a, &b| cells[&(d, a)].time.mean.total_cmp(&cells[&(d, b)].time.mean))
            .unwrap_or(0);
        let sup = &cells[&(d, 4)];
        let bs = &cells[&(d, best_success)];
        let bt = &cells[&(d, best_time)];
        let overlap = |a: &Proportion, b: &Proportion| a.low <= b.high && b.low <= a.high;
        let close_in_time =
            |a: &Mean, b: &Mean| a.n > 0 && b.n > 0 && (a.mean - b.mean).abs() <= a.half_width + b.half_width;
        let tied = |best: usize, same: &dyn Fn(&Cell) -> bool| -> String {
            let names: Vec<&str> = (0..STRATEGIES.len())
                .filter(|&s| s != best && same(&cells[&(d, s)]))
                .map(|s| STRATEGIES[s])
                .collect();
            if names.is_empty() {
                String::new()
            } else {
                format!("; within its interval: {}", names.join(", "))
            }
        };
        let _ = write!(
            text,
            "**{density}.** Most successful: {} ({}{}). Fastest: {} ({} s{}). The supervisor: {} success, {} s, {} of its driving in contour tracking, {:.1} s in Warning per mission. Mission by mission against the supervisor: ",
            STRATEGIES[best_success],
            percent(&bs.success),
            tied(best_success, &|c: &Cell| overlap(&c.success, &bs.success)),
            STRATEGIES[best_time],
            one_decimal(&bt.time),
            tied(best_time, &|c: &Cell| close_in_time(&c.time, &bt.time)),
            percent(&sup.success),
            one_decimal(&sup.time),
            if sup.contour_share.is_finite() {
                format!("{:.0} %", 100.0 * sup.contour_share)
            } else {
                "-".into()
            },
            sup.warning.mean,
        );
        let parts: Vec<String> = STRATEGIES
            .iter()
            .take(4)
            .map(|other| {
                let v = versus(runs, density, other);
                format!(
                    "{other}: +{} −{} missions{}",
                    v.supervisor_only,
                    v.other_only,
                    if v.time_diff.n > 0 {
                        format!(
                            ", {:+.1} s (± {:.1}) on the {} both completed",
                            v.time_diff.mean,
                            if v.time_diff.half_width.is_finite() {
                                v.time_diff.half_width
                            } else {
                                0.0
                            },
                            v.time_diff.n
                        )
                    } else {
                        String::new()
                    }
                )
            })
            .collect();
        let _ = writeln!(text, "{}.\n", parts.join("; "));
    }
    text.push_str(
        "“+a −b” counts the missions (same campaign, same visitors) that only the supervisor reached (a) and that only the other strategy reached (b); the time difference is the supervisor's minus the other's on the missions both reached.\n\n",
    );
    for (d, (density, _)) in DENSITIES.iter().enumerate() {
        let _ = writeln!(text, "{}\n", why(runs, density, d, &cells));
    }
    text.push_str(
        "Any mission can be replayed with its decisions and switches and the rates it used: `petrinav lab replay out/tourguide 'DENSITY/supervisor#K' --trace t.jsonl`.\n",
    );
    blocks.push(Block::Text(text));
    blocks.push(Block::Heading("All scenarios".into()));
    blocks.push(Block::Table(all));

    // The campaigns' mission logs, as a robot would have kept them.
    write_logs(suite, ctx, &mut files)?;
    Ok(SuiteReport {
        text: table_text,
        intro: Some(format!(
            "{} campaigns per density and strategy, {MISSIONS} missions each (the supervisor's after {} calibration runs), base seed {}. The rows count missions (and calibration runs). The supervisor's mission logs are in `logs/` (`petrinav guide log show logs/moderate-campaign0.jsonl`).",
            suite.info().runs,
            2 * CALIBRATION_RUNS,
            suite.info().seed
        )),
        blocks,
        files,
    })
}

/// The behaviour driving when a mission ended: the last switch's target,
/// or the choice at the start.
fn final_behaviour(r: &RunRecord) -> Option<&str> {
    r.events.iter().rev().find_map(|e| match e.kind.as_str() {
        "switch" => e.text("to"),
        "decision" if e.text("reason") == Some("start") => e.text("choice"),
        _ => None,
    })
}

/// Why the supervisor did as it did at a density, from its records: what
/// it decided and on which values, how its failed missions ended, whether
/// the net's premise (a warning localizer hurts AutoMove) held for AutoMove
/// alone, and what the contour hypothesis was learnt from.
fn why(runs: &Runs, density: &str, d: usize, cells: &BTreeMap<(usize, usize), Cell>) -> String {
    let records = |strategy: &str| -> Vec<&RunRecord> {
        runs.get(&format!("{density}/{strategy}"))
            .map(|v| v.iter().map(|(_, r)| r).collect())
            .unwrap_or_default()
    };
    let index = |name: &str| STRATEGIES.iter().position(|s| *s == name).unwrap_or(0);
    let sup = records("supervisor");
    if sup.is_empty() {
        return format!("**{density}, why.** No supervisor missions in the results.");
    }
    let decisions: Vec<&Event> = sup
        .iter()
        .flat_map(|r| r.events.iter().filter(|e| e.kind == "decision"))
        .collect();
    let starts: Vec<&Event> = decisions
        .iter()
        .copied()
        .filter(|e| e.text("reason") == Some("start"))
        .collect();
    let contour_choices = decisions
        .iter()
        .filter(|e| e.text("choice") == Some("contour"))
        .count();
    let contour_starts = starts
        .iter()
        .filter(|e| e.text("choice") == Some("contour"))
        .count();
    let at_start = |key: &str| median(starts.iter().map(|e| num(Some(e), key)));
    let failed: Vec<&RunRecord> = sup.iter().copied().filter(|r| !r.success).collect();
    let failed_in_contour = failed
        .iter()
        .filter(|r| final_behaviour(r) == Some("contour"))
        .count();
    let timeouts = failed.iter().filter(|r| r.outcome == "time_limit").count();
    let collisions = failed.iter().filter(|r| r.outcome == "collision").count();
    let mut out = format!(
        "**{density}, why.** The supervisor took {} decisions ({} at mission starts, {} on returns to Success) and chose contour tracking in {} of them ({} of the starts). At the starts the median `f_auto` was {:.5} against `f_cont` {:.5}, with the learnt `P_loc,warn` at {:.2}. ",
        decisions.len(),
        starts.len(),
        decisions.len() - starts.len(),
        contour_choices,
        contour_starts,
        at_start("f_auto"),
        at_start("f_cont"),
        at_start("p_loc_warn"),
    );
    if failed.is_empty() {
        out.push_str("It failed no mission. ");
    } else {
        let _ = write!(
            out,
            "Of its {} failed missions {} ran out of time and {} ended in a collision; {} of them were in contour tracking when they ended. ",
            failed.len(),
            timeouts,
            collisions,
            failed_in_contour,
        );
    }
    // The net's premise, tested on AutoMove alone.
    let auto = records("automove");
    let auto_cell = &cells[&(d, index("automove"))];
    let contour_cell = &cells[&(d, index("contour"))];
    let rule_cell = &cells[&(d, index("rule"))];
    let sup_cell = &cells[&(d, index("supervisor"))];
    let loc_mean = mean_of(&auto, |r| r.metric(metric::LOC_MEAN));
    let loc_max = auto
        .iter()
        .filter_map(|r| r.metric(metric::LOC_MAX))
        .fold(f64::NEG_INFINITY, f64::max);
    if auto_cell.warning.n > 0 && auto_cell.warning.mean > 1.0 {
        let _ = write!(
            out,
            "AutoMove alone spent {:.1} s per mission with the localizer in Warning, yet its true error stayed at {:.3} m on average ({:.2} m at most) and it reached {}. ",
            auto_cell.warning.mean,
            loc_mean.mean,
            loc_max,
            percent(&auto_cell.success),
        );
        if loc_max < 0.5 && auto_cell.success.low > rule_cell.success.high.min(sup_cell.success.high) {
            out.push_str(
                "Here a Warning means that visitors hide the walls from the laser, not that the estimate is wrong: the net's AutoMove hypothesis hands the robot to contour tracking at every Warning (t3), so the more the localizer warns, the lower `f_auto` — a premise this localizer does not bear out, and the supervisor pays for trusting it. ",
            );
        }
    }
    // What the contour hypothesis was learnt from.
    let contour_calibration: Vec<&RunRecord> = runs
        .get(&format!("{density}/calibration"))
        .map(|v| {
            v.iter()
                .filter(|(k, _)| k % (2 * CALIBRATION_RUNS) >= CALIBRATION_RUNS)
                .map(|(_, r)| r)
                .collect()
        })
        .unwrap_or_default();
    if !contour_calibration.is_empty() {
        let ok = contour_calibration.iter().filter(|r| r.success).count();
        let _ = write!(
            out,
            "The contour hypothesis rests on the calibration runs that reached the goal ({} of {} contour runs here: λ8 is one over their mean time) and fails only while the localizer warns (t12, λ10 from the share of failed missions). Contour tracking alone reached {} of its missions at this density ({} time limits, {} collisions): ",
            ok,
            contour_calibration.len(),
            percent(&contour_cell.success),
            contour_cell.timeouts,
            contour_cell.collisions,
        );
        out.push_str(
            if contour_cell.success.value < 0.9 && contour_cell.success.high < auto_cell.success.low {
                "it fails by being blocked (by visitors, circling them until the time runs out), a way of failing the net has no transition for, so the net overrates it."
            } else {
                "about as reliable as the net assumes."
            },
        );
    }
    out
}

/// The picture of the first mission of `source` with a switch.
fn mission_picture(
    suite: &TourGuideSuite,
    ctx: &ReportContext<'_>,
    source: &[&RunRecord],
    files: &mut Vec<std::path::PathBuf>,
) -> Result<Option<Figure>> {
    let Some(m) = source
        .iter()
        .position(|r| r.metric(metric::SWITCHES).unwrap_or(0.0) > 0.0)
    else {
        return Ok(None);
    };
    let key = format!("moderate/supervisor#{m}");
    let (job, earlier_keys): (Job, Vec<String>) = crate::suite::find_job(suite, &key)?;
    let all: BTreeMap<String, &RunRecord> = ctx
        .runs
        .iter()
        .flat_map(|(s, v)| v.iter().map(move |(k, r)| (format!("{s}#{k}"), r)))
        .collect();
    let earlier: Vec<RunRecord> = earlier_keys
        .iter()
        .map(|k| {
            all.get(k)
                .map(|r| (*r).clone())
                .with_context(|| format!("no record {k}"))
        })
        .collect::<Result<_>>()?;
    let replay = suite.replay(&job, &earlier, TraceParams::full())?;
    let (path, src) = ctx.picture_path("mission.png")?;
    pictures::run_picture(&replay, suite.markers(), &path)?;
    files.push(path);
    let (page, link) = ctx.viewer_page(&replay, suite.markers(), &key, "the mission")?;
    files.push(page);
    Ok(Some(Figure {
        title: format!("mission {} of campaign 0 (moderate)", m + 1),
        src,
        runs: vec![link],
    }))
}

/// Writes the supervisor campaigns' logs (`logs/DENSITY-campaignC.jsonl`).
fn write_logs(
    suite: &TourGuideSuite,
    ctx: &ReportContext<'_>,
    files: &mut Vec<std::path::PathBuf>,
) -> Result<()> {
    let dir = ctx.dir.join("logs");
    std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
    let net = suite.supervisor()?.net_id().to_string();
    for (density, _) in DENSITIES {
        let cal = by_run(ctx.runs, &format!("{density}/calibration"));
        let sup = by_run(ctx.runs, &format!("{density}/supervisor"));
        for c in 0..suite.info().runs {
            let mut text = String::new();
            let runs = (0..2 * CALIBRATION_RUNS)
                .map(|k| cal.get(&(c * 2 * CALIBRATION_RUNS + k)))
                .chain((0..MISSIONS).map(|m| sup.get(&(c * MISSIONS + m))));
            for r in runs.flatten() {
                let Some(state) = &r.state else { continue };
                let entry: Entry = serde_json::from_value(state.clone())?;
                text.push_str(&serde_json::to_string(&Line {
                    net: net.clone(),
                    entry,
                })?);
                text.push('\n');
            }
            if text.is_empty() {
                continue;
            }
            let path = dir.join(format!("{density}-campaign{c}.jsonl"));
            std::fs::write(&path, text).with_context(|| format!("writing {}", path.display()))?;
            files.push(path);
        }
    }
    Ok(())
}

fn percent(p: &Proportion) -> String {
    p.percent()
}

fn one_decimal(m: &Mean) -> String {
    m.one_decimal()
}
