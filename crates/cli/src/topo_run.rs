//! `petrinav topo explore` and `petrinav topo go`: the 16-sonar ring robot
//! building a topological map in the simulator, and following a route on
//! one (`lab::runs::topo` does the work; this is argument handling and output).

use std::path::{Path, PathBuf};

use ::topo::{FuzzyPetriNet, NavigateParams, TopoParams};
use anyhow::{Context, Result, bail};
use clap::Args;
use lab::runs::topo::{self, ExploreSpec, RouteMethod, RouteOutcome, RouteSpec};
use robot::Pose;
use serde_json::json;
use sim::{TraceParams, World};

use crate::output::{fields, num};
use crate::topo_map::{ModeArg, find_place, load_map};
use crate::{out, outln};

/// The world of a command: `office` or `floor` (the topological suite's),
/// or a map_server `.yaml` map or a `.toml` world of shapes; and the
/// default start of an exploration in it, if it has one.
fn world(name: &Path) -> Result<(World, Option<Pose>)> {
    let shipped = lab::runs::topo::WORLDS
        .iter()
        .find(|(n, _, _)| Path::new(n) == name);
    if let Some(&(n, _, start)) = shipped {
        let w = if n == "office" {
            lab::runs::topo::office()?
        } else {
            lab::runs::topo::floor()?
        };
        return Ok((w, Some(start)));
    }
    Ok((World::new(crate::map::load_grid(name)?), None))
}

fn pose_arg(text: &str, what: &str) -> Result<Pose> {
    let v = crate::sim_cmd::numbers(text, 3, what)?;
    Ok(Pose::new(v[0], v[1], v[2]))
}

#[derive(Args, Debug)]
pub struct ExploreArgs {
    /// The world: `office` (the 50 m² office of the topo suite), `floor` (its 20 m × 18 m
    /// generated floor), a map_server .yaml map or a .toml world of shapes.
    #[arg(value_name = "WORLD")]
    world: PathBuf,
    /// How long the robot explores, seconds.
    #[arg(long, default_value_t = 600.0, allow_hyphen_values = true)]
    time: f64,
    /// Where it starts: x,y,theta (metres, radians) [default: the shipped world's start;
    /// required for a file].
    #[arg(long, value_name = "X,Y,TH", allow_hyphen_values = true)]
    start: Option<String>,
    /// Seed of the run (simulator noise and the explorer's choices).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// The map file to write (.fpn.json).
    #[arg(short, long, value_name = "MAP.fpn.json")]
    output: PathBuf,
    /// Also draw the net over the world (.png or .svg).
    #[arg(long, value_name = "FILE")]
    picture: Option<PathBuf>,
    /// Print JSON instead of text (stable keys).
    #[arg(long)]
    json: bool,
}

#[derive(Args, Debug)]
pub struct GoArgs {
    /// The world the map was made in (as for `topo explore`).
    #[arg(value_name = "WORLD")]
    world: PathBuf,
    /// The map (.fpn.json).
    #[arg(value_name = "MAP.fpn.json")]
    map: PathBuf,
    /// The place the robot stands at: it is put at the place's map position and heading.
    #[arg(long, value_name = "PLACE", allow_hyphen_values = true)]
    from: String,
    /// The goal place.
    #[arg(long, value_name = "PLACE", allow_hyphen_values = true)]
    to: String,
    /// The stopping rule of the route planning.
    #[arg(long, value_enum, default_value_t = ModeArg::Optimal)]
    mode: ModeArg,
    /// Time limit, seconds.
    #[arg(long, default_value_t = 300.0, allow_hyphen_values = true)]
    time_limit: f64,
    /// Seed of the run.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Write the map as the robot left it (thresholds lowered, places added).
    #[arg(long, value_name = "MAP.fpn.json")]
    save_map: Option<PathBuf>,
    /// Draw the run: the trajectory under the net (.png or .svg).
    #[arg(short, long, value_name = "FILE")]
    output: Option<PathBuf>,
    /// Write the per-tick trace as JSON lines.
    #[arg(long, value_name = "FILE")]
    trace: Option<PathBuf>,
    /// Print JSON instead of text (stable keys).
    #[arg(long)]
    json: bool,
}

fn trajectory(trace: Option<&sim::Trace>) -> Option<Vec<Pose>> {
    trace.map(|t| t.ticks.iter().map(|k| k.true_pose).collect())
}

pub fn explore(a: &ExploreArgs) -> Result<()> {
    let (world, default_start) = world(&a.world)?;
    let start = match (&a.start, default_start) {
        (Some(s), _) => pose_arg(s, "--start")?,
        (None, Some(p)) => p,
        (None, None) => bail!("give the robot's start with --start X,Y,TH for a world from a file"),
    };
    if !(a.time.is_finite() && a.time > 0.0 && a.time <= 1e6) {
        bail!("--time {}: expected seconds in (0, 1e6]", a.time);
    }
    let trace = if a.picture.is_some() {
        TraceParams::poses()
    } else {
        TraceParams::default()
    };
    let e = topo::explore(
        &world,
        &ExploreSpec {
            params: TopoParams::default(),
            start,
            time_s: a.time,
            seed: a.seed,
            trace,
            robot: topo::robot(),
        },
    )?;
    e.map.save(&a.output)?;
    if let Some(p) = &a.picture {
        let poses = trajectory(e.trace.as_ref());
        topo::picture(world.grid(), &e.map, Some(&e.truth), poses.as_deref(), p)?;
    }
    let r = e.recognition;
    let c = topo::connectivity(&e.map);
    let connected = c.strongly_connected();
    if a.json {
        outln!(
            "{}",
            json!({
                "map": a.output.display().to_string(),
                "time_s": e.result.time_s,
                "path_m": e.result.path_length_m,
                "places": e.map.num_places(),
                "transitions": e.map.num_transitions(),
                "stops": e.visits.len(),
                "connected": c.connected,
                "strongly_connected": connected,
                "largest_strongly_connected_places": c.largest_strong,
                "recognition": {
                    "true_positives": r.true_positives,
                    "false_positives": r.false_positives,
                    "false_negatives": r.false_negatives,
                    "true_negatives": r.true_negatives,
                    "precision": finite(r.precision()),
                    "recall": finite(r.recall()),
                },
                "recalibrations": e.recalibrations,
                "failed_legs": e.failures,
                "odometry_error_m": e.result.odometry_error_m,
                "collisions": e.result.collisions,
            })
        )?;
    } else {
        outln!(
            "{}",
            fields(&[
                ("map", a.output.display().to_string()),
                (
                    "explored",
                    format!(
                        "{} s, {} m driven",
                        num(e.result.time_s),
                        num(e.result.path_length_m)
                    )
                ),
                ("places", e.map.num_places().to_string()),
                ("transitions", e.map.num_transitions().to_string()),
                ("stops", e.visits.len().to_string()),
                (
                    "connected",
                    if c.connected {
                        "yes"
                    } else {
                        "no (the net is in pieces)"
                    }
                    .to_string()
                ),
                (
                    "strongly connected",
                    if connected {
                        "yes".to_string()
                    } else {
                        format!(
                            "no (the largest part whose places all reach each other holds {} of {})",
                            c.largest_strong, c.places
                        )
                    }
                ),
                (
                    "recognition",
                    format!(
                        "precision {}, recall {} ({} recognised, {} taken for another, {} missed; judged against the true poses)",
                        num(r.precision()),
                        num(r.recall()),
                        r.true_positives,
                        r.false_positives,
                        r.false_negatives
                    )
                ),
                ("recalibrations", e.recalibrations.to_string()),
                (
                    "odometry drift",
                    format!("{} m at the end", num(e.result.odometry_error_m))
                ),
            ])
        )?;
        if let Some(p) = &a.picture {
            outln!("picture: {}", p.display())?;
        }
    }
    Ok(())
}

/// The pose nearest `p` (same heading), within `reach_m`, where a disc of
/// `radius_m` fits, on a 1 cm spiral of rings.
fn nearest_fit(world: &World, p: Pose, radius_m: f64, reach_m: f64) -> Option<Pose> {
    let fits = |q: robot::Vec2| !world.grid().disc_blocked(q, radius_m);
    if fits(p.position()) {
        return Some(p);
    }
    let step = 0.01;
    let rings = (reach_m / step).ceil() as usize;
    for k in 1..=rings {
        let r = k as f64 * step;
        let n = (2.0 * std::f64::consts::PI * r / step).ceil().max(8.0) as usize;
        for i in 0..n {
            let a = i as f64 * 2.0 * std::f64::consts::PI / n as f64;
            let q = robot::Vec2::new(p.x_m + r * a.cos(), p.y_m + r * a.sin());
            if fits(q) {
                return Some(Pose::new(q.x, q.y, p.theta_rad));
            }
        }
    }
    None
}

fn finite(x: f64) -> serde_json::Value {
    if x.is_finite() {
        json!(x)
    } else {
        serde_json::Value::Null
    }
}

/// `topo go`: drives a route on a map in a world and prints how it went.
pub fn go(a: &GoArgs) -> Result<()> {
    let (world, _) = world(&a.world)?;
    let map: FuzzyPetriNet = load_map(&a.map)?;
    let from = find_place(&map, &a.from, "--from", &a.map)?;
    let to = find_place(&map, &a.to, "--to", &a.map)?;
    if !(a.time_limit.is_finite() && a.time_limit > 0.0 && a.time_limit <= 1e6) {
        bail!("--time-limit {}: expected seconds in (0, 1e6]", a.time_limit);
    }
    let truth = true_poses(&world, &map, from, a)?;
    let params = NavigateParams {
        mode: a.mode.into(),
        ..NavigateParams::default()
    };
    let trace = if a.trace.is_some() {
        TraceParams::full()
    } else if a.output.is_some() {
        TraceParams::poses()
    } else {
        TraceParams::default()
    };
    let run = topo::route(
        &world,
        &RouteSpec {
            map: &map,
            truth: &truth,
            from,
            to,
            method: RouteMethod::Map(params),
            time_limit_s: a.time_limit,
            seed: a.seed,
            trace,
            robot: topo::robot(),
        },
    )?;
    write_outputs(a, &world, &map, &run)?;
    print_route(a, &map, &run)?;
    // Not arriving is a result, not an error: the exit code is 0, the
    // outcome says what happened (as for `nav go`).
    Ok(())
}

/// The places' true poses for a route without an exploration: where the
/// map says, the start moved to the nearest pose where the robot fits.
fn true_poses(world: &World, map: &FuzzyPetriNet, from: ::topo::PlaceId, a: &GoArgs) -> Result<Vec<Pose>> {
    // Without the true poses of an exploration, every place stands where
    // the map says: the robot starts at the start place's map pose, and
    // arrival is judged against the goal's map position.
    let truth: Vec<Pose> = map
        .places()
        .iter()
        .map(|p| Pose::new(p.x_m, p.y_m, p.heading_rad))
        .collect();
    let radius = topo::robot().drive.radius_m;
    let mut truth = truth;
    let mapped = truth[from.0 as usize];
    // A map position carries the exploration's drift and may lie in a
    // wall: the robot is put at the nearest pose within 1 m where it fits.
    let Some(start) = nearest_fit(world, mapped, radius, 1.0) else {
        bail!(
            "place {} is at ({}, {}) in the map, and the robot fits nowhere within 1 m of it in {}: is this the world the map was made in?",
            a.from,
            num(mapped.x_m),
            num(mapped.y_m),
            a.world.display()
        );
    };
    truth[from.0 as usize] = start;
    Ok(truth)
}

/// Writes what the options ask for: the map learnt, the trace, the
/// picture.
fn write_outputs(a: &GoArgs, world: &World, map: &FuzzyPetriNet, run: &topo::RouteRun) -> Result<()> {
    if let Some(path) = &a.save_map
        && let Some(m) = &run.map
    {
        m.save(path)?;
    }
    if let Some(path) = &a.trace
        && let Some(t) = &run.trace
    {
        let f = std::fs::File::create(path).with_context(|| format!("writing {}", path.display()))?;
        t.write_json_lines(std::io::BufWriter::new(f))
            .with_context(|| format!("writing {}", path.display()))?;
    }
    if let Some(path) = &a.output {
        let poses = trajectory(run.trace.as_ref());
        topo::picture(
            world.grid(),
            run.map.as_ref().unwrap_or(map),
            None,
            poses.as_deref(),
            path,
        )?;
    }
    Ok(())
}

/// Prints how the route went (`--json`: as one JSON object).
fn print_route(a: &GoArgs, map: &FuzzyPetriNet, run: &topo::RouteRun) -> Result<()> {
    let stats = run.stats.unwrap_or_default();
    let planned: Vec<String> = run
        .plan
        .as_ref()
        .map(|p| p.places.iter().map(|&q| map.place(q).name.clone()).collect())
        .unwrap_or_default();
    if a.json {
        outln!(
            "{}",
            json!({
                "from": a.from,
                "to": a.to,
                "outcome": run.outcome.name(),
                "time_s": run.result.time_s,
                "path_m": run.result.path_length_m,
                "final_distance_m": run.final_distance_m,
                "planned": planned,
                "legs": stats.legs,
                "as_planned": stats.as_planned,
                "replans": stats.replans,
                "no_route": stats.no_route,
                "failed_legs": stats.failed_legs,
                "collisions": run.result.collisions,
            })
        )?;
    } else {
        let outcome = match run.outcome {
            RouteOutcome::Reached => "arrived".to_string(),
            RouteOutcome::WrongPlace => format!(
                "declared arrival {} m from the goal's map position",
                num(run.final_distance_m)
            ),
            RouteOutcome::TimeLimit => "time limit".to_string(),
            RouteOutcome::GaveUp => "gave up (too many legs)".to_string(),
        };
        outln!(
            "{}",
            fields(&[
                ("route", format!("{} → {}", a.from, a.to)),
                ("planned", planned.join(" → ")),
                ("outcome", outcome),
                (
                    "time",
                    format!(
                        "{} s, {} m",
                        num(run.result.time_s),
                        num(run.result.path_length_m)
                    )
                ),
                (
                    "legs",
                    format!(
                        "{} ({} as planned, {} ended elsewhere, {} from places without a route)",
                        stats.legs, stats.as_planned, stats.replans, stats.no_route
                    )
                ),
            ])
        )?;
        if let Some(p) = &a.output {
            out!("picture: {}\n", p.display())?;
        }
    }
    Ok(())
}
