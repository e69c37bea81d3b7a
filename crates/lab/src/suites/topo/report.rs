//! The topological suite's report: the explorations (the nets, their size
//! over time, place recognition against the true poses), one planned route
//! as the source tabulates it, the routes by map against wall following and
//! the grid's shortest path, and an explanation — every figure from the
//! batch's records.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use ::topo::{FuzzyPetriNet, PlaceId, PlanMode, plan};
use anyhow::Result;
use robot::Pose;

use super::{Explored, METHODS, ROUTES, TopoSuite, WORLDS, metric};
use crate::charts::{self, Series};
use crate::page::{Block, Figure};
use crate::record::{RunRecord, Runs};
use crate::runs::topo;
use crate::stats::{Mean, Proportion, median};
use crate::suite::{ReportContext, Suite, SuiteReport};
use crate::summary::CONFIDENCE;
use crate::tables::{self, MetricColumn};

fn records<'a>(runs: &'a Runs, scenario: &str) -> Vec<(u32, &'a RunRecord)> {
    runs.get(scenario)
        .map(|v| v.iter().map(|(k, r)| (*k, r)).collect())
        .unwrap_or_default()
}

fn metric_sum(rs: &[(u32, &RunRecord)], name: &str) -> f64 {
    rs.iter().filter_map(|(_, r)| r.metric(name)).sum()
}

fn mean_metric(rs: &[(u32, &RunRecord)], name: &str) -> Mean {
    let v: Vec<f64> = rs.iter().filter_map(|(_, r)| r.metric(name)).collect();
    Mean::new(&v, CONFIDENCE)
}

fn explored(r: &RunRecord) -> Option<(FuzzyPetriNet, Vec<Pose>)> {
    let e: Explored = serde_json::from_value(r.state.clone()?).ok()?;
    let map = FuzzyPetriNet::from_json(&e.map).ok()?;
    Some((map, e.truth.iter().map(|p| Pose::new(p[0], p[1], p[2])).collect()))
}

/// What the legs of routes by the map say about the failures, from their
/// `leg` events (one per leg that ended at a place, judged against the
/// true poses by [`topo::route`]).
#[derive(Debug, Default)]
struct LegCauses {
    /// Legs that played a planned transition.
    planned: usize,
    /// Of those, legs that ended elsewhere than planned.
    surprises: usize,
    /// Surprises truly elsewhere.
    truly_elsewhere: usize,
    /// Surprises truly at the planned place.
    truly_there: usize,
    /// Surprises with a planned place added after the exploration.
    unjudged: usize,
    /// Failed routes where one transition ended elsewhere at least twice.
    failed_repeating: usize,
    /// Failed routes with at least half of their legs unplanned.
    failed_off_net: usize,
}

impl LegCauses {
    fn of<'a>(routes: impl Iterator<Item = &'a RunRecord>) -> LegCauses {
        let mut c = LegCauses::default();
        for r in routes {
            let legs: Vec<&robot::Event> = r.events.iter().filter(|e| e.kind == "leg").collect();
            let mut failed_again: BTreeMap<(String, String), u32> = BTreeMap::new();
            let mut unplanned = 0;
            for e in &legs {
                let Some(to) = e.text("planned_to") else {
                    unplanned += 1;
                    continue;
                };
                c.planned += 1;
                if e.flag("as_planned") == Some(true) {
                    continue;
                }
                c.surprises += 1;
                match e.flag("truly_at_planned") {
                    Some(true) => c.truly_there += 1,
                    Some(false) => c.truly_elsewhere += 1,
                    None => c.unjudged += 1,
                }
                let from = e.text("from").unwrap_or("").to_string();
                *failed_again.entry((from, to.to_string())).or_default() += 1;
            }
            if !r.success {
                if failed_again.values().any(|&n| n >= 2) {
                    c.failed_repeating += 1;
                }
                if !legs.is_empty() && 2 * unplanned >= legs.len() {
                    c.failed_off_net += 1;
                }
            }
        }
        c
    }
}

/// The report (module docs).
pub fn report(suite: &TopoSuite, ctx: &ReportContext<'_>) -> Result<SuiteReport> {
    let runs = ctx.runs;
    let mut blocks = Vec::new();
    let mut files = Vec::new();
    let columns = [
        MetricColumn {
            metric: metric::PLACES,
            heading: "places",
            short: "places",
            decimals: 1,
        },
        MetricColumn {
            metric: metric::TRANSITIONS,
            heading: "transitions",
            short: "trans",
            decimals: 1,
        },
        MetricColumn {
            metric: metric::LEGS,
            heading: "legs/route",
            short: "legs",
            decimals: 1,
        },
        MetricColumn {
            metric: metric::REPLANS,
            heading: "replans/route",
            short: "replans",
            decimals: 2,
        },
        MetricColumn {
            metric: metric::BOUND_S,
            heading: "shortest path (s)",
            short: "bound(s)",
            decimals: 1,
        },
    ];
    let (text, table) = tables::generic_table(ctx.summaries, &columns);
    blocks.push(Block::Text(
        "In the `explore` rows a run is an exploration and `I_R` the share whose net is strongly connected (every place can reach every other); `I_T` is the exploration time. In the `map` and `wall_following` rows a run is a route and `I_R` the share that arrived; `lost` counts routes whose follower declared arrival where the goal is not; the shortest path's time is at free movement's cruise speed (0.3 m/s).\n\n".into(),
    ));
    blocks.push(Block::Table(table));

    // 1. Explorations.
    blocks.extend(exploration_blocks(suite, ctx, &mut files)?);

    // 2. One route as the source tabulates it.
    if let Some(table) = route_table(runs) {
        blocks.push(Block::Heading(
            "A planned route, as the source tabulates it".into(),
        ));
        blocks.extend(table);
    }

    // 3. Routes.
    blocks.extend(route_blocks(runs));
    Ok(SuiteReport {
        text,
        intro: Some(format!(
            "{} explorations per world, each followed by {ROUTES} routes between random pairs of the places it found (pairs with a planned route), driven with the map and by wall following; base seed {}. Any run replays from its seed: `petrinav lab replay out/topo 'office/map#K' -o route.png --trace route.jsonl`.",
            suite.info().runs,
            suite.info().seed
        )),
        blocks,
        files,
    })
}

/// The explorations: their table and explanation, the map's growth over
/// the first exploration of each world, and the nets explored.
fn exploration_blocks(
    suite: &TopoSuite,
    ctx: &ReportContext<'_>,
    files: &mut Vec<std::path::PathBuf>,
) -> Result<Vec<Block>> {
    let runs = ctx.runs;
    let mut blocks = Vec::new();
    blocks.push(Block::Heading("Exploring: the nets the robot built".into()));
    let mut md = String::from(
        "| world | explorations | connected | strongly connected | largest strongly connected part | places | transitions | stops | recognition precision | recall | recalibrations | odometry drift at the end (m) |\n|---|---:|---|---|---:|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    let mut explanation = String::new();
    let mut figures = Vec::new();
    let mut growth_series = Vec::new();
    for (world, _, _) in WORLDS {
        let ex = records(runs, &format!("{world}/explore"));
        if ex.is_empty() {
            continue;
        }
        let (row, text) = exploration_row(world, &ex);
        md.push_str(&row);
        explanation.push_str(&text);
        // The size of the first exploration's map over time.
        if let Some((first, r)) = ex.first() {
            growth_series.extend(growth(world, r));
            if ctx.pictures
                && let Some(figure) = net_figure(suite, ctx, world, *first, r, files)?
            {
                figures.push(figure);
            }
        }
    }
    blocks.push(Block::Table(md));
    blocks.push(Block::Text(explanation));
    if !growth_series.is_empty() {
        let svg = charts::lines(
            "The map's size over the first exploration",
            "time (s)",
            "count",
            &growth_series,
            false,
            (760, 380),
        )?;
        let (path, src) = ctx.picture_path("growth.svg")?;
        std::fs::write(&path, svg)?;
        files.push(path);
        blocks.push(Block::Charts {
            heading: "The map as it grows".into(),
            caption: "Places and transitions after every stop of each world's first exploration.".into(),
            figures: vec![Figure {
                title: "map size over time".into(),
                src,
                runs: Vec::new(),
            }],
        });
    }
    if !figures.is_empty() {
        blocks.push(Block::Figures {
            heading: "The nets over the worlds".into(),
            caption: "Places (numbered as in the map) at the positions the robot believed, transitions as lines coloured by strategy; a thin line joins each place to where it truly was recorded — the odometry's drift.".into(),
            figures,
        });
    }
    Ok(blocks)
}

/// A world's row of the explorations' table and its paragraph.
fn exploration_row(world: &str, ex: &[(u32, &RunRecord)]) -> (String, String) {
    let mut md = String::new();
    let mut explanation = String::new();
    let connected = Proportion::new(ex.iter().filter(|(_, r)| r.success).count(), ex.len(), CONFIDENCE);
    let weakly = Proportion::new(
        ex.iter()
            .filter(|(_, r)| r.metric(metric::CONNECTED).is_some_and(|v| v > 0.5))
            .count(),
        ex.len(),
        CONFIDENCE,
    );
    let share = mean_metric(ex, metric::STRONG_SHARE);
    let (tp, fp, fn_) = (
        metric_sum(ex, metric::TP),
        metric_sum(ex, metric::FP),
        metric_sum(ex, metric::FN),
    );
    let precision = if tp + fp > 0.0 { tp / (tp + fp) } else { f64::NAN };
    let recall = if tp + fn_ > 0.0 { tp / (tp + fn_) } else { f64::NAN };
    let drift: Vec<f64> = ex.iter().map(|(_, r)| r.odometry_error_m).collect();
    let drift = Mean::new(&drift, CONFIDENCE);
    let _ = writeln!(
        md,
        "| {world} | {} | {} | {} | {:.0} % of the places | {} | {} | {} | {:.2} | {:.2} | {} | {} |",
        ex.len(),
        percent(&weakly),
        percent(&connected),
        100.0 * share.mean,
        one_decimal(&mean_metric(ex, metric::PLACES)),
        one_decimal(&mean_metric(ex, metric::TRANSITIONS)),
        one_decimal(&mean_metric(ex, metric::STOPS)),
        precision,
        recall,
        one_decimal(&mean_metric(ex, metric::RECALIBRATIONS)),
        one_decimal(&drift),
    );
    let _ = write!(
        explanation,
        "**{world}.** {} of {} explorations built a connected net (its graph in one piece) and {} a strongly connected one; on average the largest strongly connected part held {:.0} % of the places (the rest: places the robot left and never came back to, such as the first ones, found from where it happened to start, and the last ones, found just before the time ran out); {:.1} legs per exploration found no place, and after each the robot starts again from nowhere known, so the net falls into pieces unless it recognises the next place it stops at. Over all their stops the robot recognised a place it truly stood at {tp:.0} times, took a place for another {fp:.0} times and did not recognise one it knew {fn_:.0} times: precision {precision:.2}, recall {recall:.2} (a stop is at a known place when the true pose is within {} m of where that place was recorded and the robot faces the same way within 45°). ",
        weakly.successes,
        connected.n,
        connected.successes,
        100.0 * share.mean,
        mean_metric(ex, metric::FAILED_LEGS).mean,
        topo::SAME_PLACE_M
    );
    let _ = writeln!(
        explanation,
        "The dead-reckoned position ended {:.2} m from the truth on average, after {:.1} recalibrations at concave places per exploration: without them the map positions would drift further.\n",
        drift.mean,
        mean_metric(ex, metric::RECALIBRATIONS).mean,
    );
    (md, explanation)
}

/// Places and transitions after every stop of an exploration.
fn growth(world: &str, r: &RunRecord) -> [Series; 2] {
    let count = |key: &str| -> Vec<(f64, f64)> {
        r.events
            .iter()
            .filter(|e| e.kind == "stop")
            .filter_map(|e| Some((e.time_s, e.number(key)?)))
            .collect()
    };
    [
        Series {
            name: format!("{world}: places"),
            points: count("places"),
        },
        Series {
            name: format!("{world}: transitions"),
            points: count("transitions"),
        },
    ]
}

/// The picture of an exploration's net, with the exploration in the viewer.
fn net_figure(
    suite: &TopoSuite,
    ctx: &ReportContext<'_>,
    world: &str,
    first: u32,
    r: &RunRecord,
    files: &mut Vec<std::path::PathBuf>,
) -> Result<Option<Figure>> {
    let Some((map, truth)) = explored(r) else {
        return Ok(None);
    };
    let (path, src) = ctx.picture_path(&format!("{world}-net.png"))?;
    topo::picture(suite.world_grid(world)?, &map, Some(&truth), None, &path)?;
    files.push(path);
    // The exploration itself in the viewer (first in its
    // campaign: no earlier runs).
    let key = format!("{world}/explore#{first}");
    let (job, _) = crate::suite::find_job(suite, &key)?;
    let replay = suite.replay(&job, &[], sim::TraceParams::full())?;
    let (page, link) = ctx.viewer_page(&replay, suite.markers(), &key, "the exploration")?;
    files.push(page);
    Ok(Some(Figure {
        title: format!(
            "{world}: the net of exploration 0 ({} places, {} transitions)",
            map.num_places(),
            map.num_transitions()
        ),
        src,
        runs: vec![link],
    }))
}

/// The routes: by map and by wall following, and what the numbers say.
fn route_blocks(runs: &Runs) -> Vec<Block> {
    let mut blocks = Vec::new();
    blocks.push(Block::Heading("Routes between known places".into()));
    let mut md = String::from(
        "| world | method | routes | arrived (95 % CI) | time (s) | shortest path (s) | wrong place | time limits | gave up | replans/route |\n|---|---|---:|---|---:|---:|---:|---:|---:|---:|\n",
    );
    let mut why = String::new();
    for (world, _, _) in WORLDS {
        let (rows, rates) = route_rows(runs, world);
        md.push_str(&rows);
        why.push_str(&route_why(runs, world, &rates));
    }
    blocks.push(Block::Table(md));
    blocks.push(Block::Heading("What the numbers say".into()));
    blocks.push(Block::Text(why));
    blocks
}

/// A world's rows of the routes' table, and the share of routes each
/// method arrived on.
fn route_rows(runs: &Runs, world: &str) -> (String, BTreeMap<&'static str, Proportion>) {
    let mut md = String::new();
    let mut rates: BTreeMap<&str, Proportion> = BTreeMap::new();
    for m in METHODS {
        let rs = records(runs, &format!("{world}/{m}"));
        if rs.is_empty() {
            continue;
        }
        let ok: Vec<(u32, &RunRecord)> = rs.iter().copied().filter(|(_, r)| r.success).collect();
        let p = Proportion::new(ok.len(), rs.len(), CONFIDENCE);
        let time = Mean::new(&ok.iter().map(|(_, r)| r.time_s).collect::<Vec<_>>(), CONFIDENCE);
        let bound = mean_metric(&ok, metric::BOUND_S);
        let count = |o: &str| rs.iter().filter(|(_, r)| r.outcome == o).count();
        let _ = writeln!(
            md,
            "| {world} | {m} | {} | {} | {} | {} | {} | {} | {} | {} |",
            rs.len(),
            percent(&p),
            one_decimal(&time),
            one_decimal(&bound),
            count("lost"),
            count("time_limit"),
            count("gave_up"),
            if m == "map" {
                format!("{:.2}", mean_metric(&rs, metric::REPLANS).mean)
            } else {
                "-".into()
            },
        );
        rates.insert(m, p);
    }
    (md, rates)
}

/// A world's paragraph on the routes: the map's failures and their
/// causes, against wall following on the same routes.
fn route_why(runs: &Runs, world: &str, rates: &BTreeMap<&str, Proportion>) -> String {
    let mut why = String::new();
    // Paired: the same routes by both methods.
    let map_runs: BTreeMap<u32, &RunRecord> = records(runs, &format!("{world}/map")).into_iter().collect();
    let wall_runs: BTreeMap<u32, &RunRecord> = records(runs, &format!("{world}/wall_following"))
        .into_iter()
        .collect();
    let (mut only_map, mut only_wall, mut ratios, mut over_bound) = (0, 0, Vec::new(), Vec::new());
    for (k, a) in &map_runs {
        let Some(b) = wall_runs.get(k) else { continue };
        match (a.success, b.success) {
            (true, false) => only_map += 1,
            (false, true) => only_wall += 1,
            (true, true) => ratios.push(a.time_s / b.time_s),
            _ => {}
        }
        if a.success
            && let Some(bound) = a.metric(metric::BOUND_S)
            && bound > 0.0
        {
            over_bound.push(a.time_s / bound);
        }
    }
    let Some(p) = rates.get("map") else {
        return why;
    };
    let lost = map_runs.values().filter(|r| r.outcome == "lost").count();
    let timeouts = map_runs.values().filter(|r| r.outcome == "time_limit").count();
    let gave_up = map_runs.values().filter(|r| r.outcome == "gave_up").count();
    let replans = map_runs
        .values()
        .filter_map(|r| r.metric(metric::REPLANS))
        .sum::<f64>();
    let failed_with_replans = map_runs
        .values()
        .filter(|r| !r.success && r.metric(metric::REPLANS).unwrap_or(0.0) > 0.0)
        .count();
    let _ = write!(
        why,
        "**{world}.** With its map the robot arrived on {} of the routes. Of the {} routes that did not arrive, {lost} declared arrival at a place that was not the goal (a place recognised wrongly), {timeouts} ran out of time and {gave_up} gave up; {failed_with_replans} of these routes had arrived somewhere the plan did not say at least once (a strategy that did not lead where it had led while exploring: a door passed or missed, a wall's end seen or not), {replans:.0} such surprises over all routes. ",
        percent(p),
        map_runs.values().filter(|r| !r.success).count(),
    );
    let legs = LegCauses::of(map_runs.values().copied());
    if legs.planned > 0 {
        let _ = write!(
            why,
            "Judged against the true poses, {} of the {} planned legs ended elsewhere than planned: {} truly elsewhere (the driving: more than {} m or 45° from where the planned place was recorded), {} truly at the planned place but not recognised as it, {} at a place added after the exploration (no true pose to judge by). Of the routes that did not arrive, {} played a transition that had already ended elsewhere on the same route again and ended elsewhere again (a replay that reproduces the wrong outcome), and {} spent at least half of their legs at places without a route to the goal (off the net, playing untried actions). ",
            legs.surprises,
            legs.planned,
            legs.truly_elsewhere,
            topo::SAME_PLACE_M,
            legs.truly_there,
            legs.unjudged,
            legs.failed_repeating,
            legs.failed_off_net,
        );
    }
    if let Some(w) = rates.get("wall_following") {
        let _ = write!(
            why,
            "Wall following alone, judged by an oracle that stops it the moment it passes the goal, arrived on {}; on the same routes the map arrived where wall following did not {only_map} times and the other way round {only_wall} times. ",
            percent(w)
        );
    }
    if !ratios.is_empty() {
        let _ = write!(
            why,
            "Where both arrived, the map's route took {:.2}× wall following's time (median of the ratios). ",
            median(ratios)
        );
    }
    if !over_bound.is_empty() {
        let _ = write!(
            why,
            "Against the true grid's shortest path at cruise speed the map's successful routes took {:.1}× as long (median): the strategies follow walls and stop at every reference place, and the exit turns cost time.",
            median(over_bound)
        );
    }
    why.push_str("\n\n");
    why
}

/// The longest planned route of the first campaign of the first world,
/// on its explored map: the planned transitions with `C(t)`, `λ(t)` and
/// `f(t)`, in both modes.
fn route_table(runs: &Runs) -> Option<Vec<Block>> {
    let world = WORLDS[0].0;
    let ex = records(runs, &format!("{world}/explore"));
    let (_, first) = ex.first()?;
    let (map, _) = explored(first)?;
    let routes = records(runs, &format!("{world}/map"));
    let (_, longest) = routes.iter().filter(|(k, _)| *k < ROUTES).max_by(|a, b| {
        let n = |r: &RunRecord| r.metric(metric::PLANNED).unwrap_or(0.0);
        n(a.1).total_cmp(&n(b.1)).then(b.0.cmp(&a.0))
    })?;
    let from = PlaceId(longest.metric(metric::FROM)? as u32);
    let to = PlaceId(longest.metric(metric::TO)? as u32);
    let mut out = Vec::new();
    for mode in [PlanMode::Optimal, PlanMode::Paper] {
        let name = if mode == PlanMode::Optimal {
            "Optimal"
        } else {
            "Paper"
        };
        let Ok(p) = plan(&map, from, &[to], mode) else {
            out.push(Block::Text(format!("{name} mode: no route.\n")));
            continue;
        };
        out.push(Block::Text(format!(
            "{name} mode, from {} to {} on the map of {world}'s exploration 0: {} transition{}, Σ C = {:.4} ({} {}).\n\n",
            map.place(from).name,
            map.place(to).name,
            p.route.len(),
            if p.route.len() == 1 { "" } else { "s" },
            p.cost,
            p.iterations,
            if mode == PlanMode::Optimal { "places settled" } else { "rounds" },
        )));
        let mut md = String::from(
            "| transition | from | to | strategy | exit turn | C(t) | λ(t) | f(t) |\n|---|---|---|---|---|---:|---:|---:|\n",
        );
        for &t in &p.route {
            let tr = map.transition(t);
            let _ = writeln!(
                md,
                "| t{} | {} | {} | {} | {} | {:.4} | {:.3} | {:.4} |",
                t.0,
                map.place(tr.from).name,
                map.place(tr.to).name,
                tr.strategy.name(),
                tr.exit_turn.name(),
                map.weighted_cost(t),
                tr.lambda,
                p.f[t.0 as usize],
            );
        }
        out.push(Block::Table(md));
    }
    Some(out)
}

fn percent(p: &Proportion) -> String {
    p.percent()
}

fn one_decimal(m: &Mean) -> String {
    m.one_decimal()
}
