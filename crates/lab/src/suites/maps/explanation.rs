//! The maps suite's explanation: what crowds do to the localizer, and what
//! each behaviour makes of the same tours — every figure computed from the
//! batch's records.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use super::{BEHAVIOURS, CROWDS, MAPS, metric};
use crate::page::Block;
use crate::record::{RunRecord, Runs};
use crate::summary::Summary;
use crate::tables;

fn name(map: usize, behaviour: usize, people: usize) -> String {
    format!("{}/{}/{}p", MAPS[map], BEHAVIOURS[behaviour].1, CROWDS[people])
}

fn records<'a>(runs: &'a Runs, scenario: &str) -> Vec<&'a RunRecord> {
    runs.get(scenario)
        .map(|v| v.iter().map(|(_, r)| r).collect())
        .unwrap_or_default()
}

/// Share of the driving time spent in Warning, over all legs.
fn warning_share(rs: &[&RunRecord]) -> f64 {
    let time: f64 = rs.iter().map(|r| r.time_s).sum();
    let warn: f64 = rs.iter().filter_map(|r| r.metric(metric::WARNING_S)).sum();
    if time > 0.0 { warn / time } else { f64::NAN }
}

/// Largest true error over all legs.
fn max_error(rs: &[&RunRecord]) -> f64 {
    rs.iter()
        .filter_map(|r| r.metric(metric::LOC_MAX))
        .fold(f64::NAN, f64::max)
}

/// Mean over legs of a metric.
fn mean(rs: &[&RunRecord], m: &str) -> f64 {
    let v: Vec<f64> = rs.iter().filter_map(|r| r.metric(m)).collect();
    if v.is_empty() {
        f64::NAN
    } else {
        v.iter().sum::<f64>() / v.len() as f64
    }
}

fn pct(x: f64) -> String {
    if x.is_finite() {
        format!("{:.0} %", 100.0 * x)
    } else {
        "-".into()
    }
}

/// The table of the localizer against crowds (AutoMove's tours), Markdown.
pub fn localizer_table(runs: &Runs) -> String {
    let mut md = String::from(
        "| map | people | legs | time in Warning | warnings/leg | true error mean (m) | true error max (m) |\n|---|---:|---:|---:|---:|---:|---:|\n",
    );
    for (map, map_name) in MAPS.iter().enumerate() {
        for (people, count) in CROWDS.iter().enumerate() {
            let rs = records(runs, &name(map, 0, people));
            if rs.is_empty() {
                continue;
            }
            let _ = writeln!(
                md,
                "| {} | {} | {} | {} | {:.2} | {:.3} | {:.3} |",
                map_name,
                count,
                rs.len(),
                pct(warning_share(&rs)),
                mean(&rs, metric::WARNINGS),
                mean(&rs, metric::LOC_MEAN),
                max_error(&rs)
            );
        }
    }
    md
}

/// Legs reached by both behaviours in the same tour, leg and crowd: the
/// ratio of contour tracking's time to AutoMove's, median.
fn paired_time_ratio(runs: &Runs, map: usize, people: usize) -> (usize, f64) {
    let auto: BTreeMap<u32, &RunRecord> = runs
        .get(&name(map, 0, people))
        .map(|v| v.iter().map(|(k, r)| (*k, r)).collect())
        .unwrap_or_default();
    let mut ratios: Vec<f64> = runs
        .get(&name(map, 1, people))
        .map(|v| {
            v.iter()
                .filter_map(|(k, c)| {
                    let a = auto.get(k)?;
                    (a.success && c.success && a.time_s > 0.0).then(|| c.time_s / a.time_s)
                })
                .collect()
        })
        .unwrap_or_default();
    ratios.sort_by(f64::total_cmp);
    let n = ratios.len();
    let median = if n == 0 {
        f64::NAN
    } else if n % 2 == 1 {
        ratios[n / 2]
    } else {
        0.5 * (ratios[n / 2 - 1] + ratios[n / 2])
    };
    (n, median)
}

/// The report's blocks after the table of all scenarios.
pub fn explanation(summaries: &[Summary], runs: &Runs) -> Vec<Block> {
    let by: BTreeMap<&str, &Summary> = summaries.iter().map(|s| (s.scenario.as_str(), s)).collect();
    let mut blocks = vec![
        Block::Heading("The localizer among people".into()),
        Block::Text(
            "People are not in the map: they hide the walls from the laser and put echoes where the map has none. A beam cut short by a person is no evidence against the pose, so the localizer warns only when the scan contradicts its estimate: of at least 15 beams that can tell, more than 10 % pass through a mapped wall or end on a wall where the map has free space, on two consecutive checks. With AutoMove on every leg of the same tours:\n\n".into(),
        ),
        Block::Table(localizer_table(runs)),
    ];
    let mut out = String::new();
    for (map, map_name) in MAPS.iter().enumerate() {
        let shares: Vec<f64> = (0..CROWDS.len())
            .map(|p| warning_share(&records(runs, &name(map, 0, p))))
            .collect();
        if shares.iter().any(|s| !s.is_finite()) {
            continue;
        }
        let rising = shares.windows(2).all(|w| w[1] > w[0]);
        let errors: Vec<f64> = (0..CROWDS.len())
            .map(|p| max_error(&records(runs, &name(map, 0, p))))
            .collect();
        let _ = writeln!(
            out,
            "\nOn {}, the time in Warning goes from {} without people to {} with {} and {} with {} — {}. The true error stays {}: its worst over every leg is {:.2} m, {:.2} m and {:.2} m. The large ones come from visitors pushing the braked robot (a move odometry does not see); how well the Warning tells such a loss is in the last section.",
            map_name,
            pct(shares[0]),
            pct(shares[1]),
            CROWDS[1],
            pct(shares[2]),
            CROWDS[2],
            if rising {
                "it rises with the crowd"
            } else {
                "it does NOT rise steadily with the crowd"
            },
            if errors.iter().all(|e| *e < 0.3) {
                "small"
            } else {
                "small on most legs but not all"
            },
            errors[0],
            errors[1],
            errors[2],
        );
    }
    blocks.push(Block::Text(std::mem::take(&mut out)));
    blocks.push(Block::Heading(
        "AutoMove and contour tracking on the same tours".into(),
    ));
    for (map, map_name) in MAPS.iter().enumerate() {
        for (people, count) in CROWDS.iter().enumerate() {
            let (Some(a), Some(c)) = (
                by.get(name(map, 0, people).as_str()),
                by.get(name(map, 1, people).as_str()),
            ) else {
                continue;
            };
            if a.runs == 0 || c.runs == 0 {
                continue;
            }
            let (n, ratio) = paired_time_ratio(runs, map, people);
            let abnormal = mean(&records(runs, &name(map, 0, people)), metric::ABNORMAL_S);
            let _ = writeln!(
                out,
                "{} with {} people: AutoMove reached {} of {} legs ({}, {}, {} lost), contour tracking {} of {} ({}, {}, {} lost). On the {n} legs both reached, contour tracking took {} AutoMove's time (median of the ratios). AutoMove was Abnormal {:.1} s a leg on average, stopped and asking people to step aside.\n",
                map_name,
                count,
                a.reliability.successes,
                a.runs,
                tables::outcome_in_words("collision", a.collisions),
                tables::outcome_in_words("time_limit", a.timeouts),
                a.lost,
                c.reliability.successes,
                c.runs,
                tables::outcome_in_words("collision", c.collisions),
                tables::outcome_in_words("time_limit", c.timeouts),
                c.lost,
                if ratio.is_finite() {
                    format!("{ratio:.2}×")
                } else {
                    "-".into()
                },
                abnormal,
            );
        }
    }
    out.push_str(
        "Contour tracking follows walls, exhibits — and people — from the raw scan, and leaves a contour for the goal when the way is clear and the goal nearer than where it started following (Bug2's rule). It is slower because its path hugs contours and it drives at 0.4 m/s against AutoMove's 0.5 m/s. It has no map: a gap in a wall and a passage look alike until the robot is in them, and a person is a contour like a wall — among people it circles them, which the time limits above count. `petrinav lab replay out/maps 'MAP/contour/Np#K' -o leg.png` draws any leg.\n",
    );
    blocks.push(Block::Text(out));
    blocks
}

/// The Warning against true losses, per map and crowd (both behaviours
/// together): precision (share of the time in Warning truly lost: error
/// over 0.5 m or 20°), recall (share of the time truly lost in Warning),
/// and the share of the time with a good estimate (under 0.2 m) spent in
/// Warning.
pub fn warning_against_loss(runs: &Runs) -> Vec<Block> {
    let sum = |rs: &[&RunRecord], m: &str| -> f64 { rs.iter().filter_map(|r| r.metric(m)).sum() };
    let ratio = |a: f64, b: f64| {
        if b > 0.0 {
            format!("{:.2}", a / b)
        } else {
            "-".into()
        }
    };
    let mut md = String::from(
        "| map | people | legs | pushes | groups | in Warning (s) | truly lost (s) | precision | recall | Warning while the error < 0.2 m |\n|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    let (mut w_all, mut l_all, mut h_all) = (0.0, 0.0, 0.0);
    for map in MAPS {
        for people in CROWDS {
            let rs: Vec<&RunRecord> = runs
                .iter()
                .filter(|(s, _)| s.starts_with(&format!("{map}/")) && s.ends_with(&format!("/{people}p")))
                .flat_map(|(_, v)| v.iter().map(|(_, r)| r))
                .collect();
            if rs.is_empty() {
                continue;
            }
            let w = sum(&rs, metric::WARNING_S);
            let l = sum(&rs, metric::LOST_S);
            let h = sum(&rs, metric::WARNING_LOST_S);
            if people > 0 {
                w_all += w;
                l_all += l;
                h_all += h;
            }
            let _ = writeln!(
                md,
                "| {map} | {people} | {} | {} | {} | {:.1} | {:.1} | {} | {} | {} |",
                rs.len(),
                sum(&rs, metric::PUSHES),
                sum(&rs, metric::SURROUNDS),
                w,
                l,
                ratio(h, w),
                ratio(h, l),
                ratio(sum(&rs, metric::WARNING_FINE_S), sum(&rs, metric::FINE_S)),
            );
        }
    }
    vec![
        Block::Heading("What a Warning means".into()),
        Block::Text(format!(
            "Visitors push the standing robot and close round it at the museum's rates (one push per 200 s of a visitor within reach, one group per 15 000 visitor-seconds). Over the legs with people: precision {}, recall {} — the time in Warning while truly lost (error over 0.5 m or 20°) over the time in Warning, and over the time truly lost.\n\n",
            ratio(h_all, w_all),
            ratio(h_all, l_all)
        )),
        Block::Table(md),
    ]
}
