//! What a viewer page embeds: what its runs share ([`PageData`]: maps,
//! view, markers, behaviours, the list of runs) and each replayed run
//! ([`RunData`]) as compact JSON, column by column (one array per quantity,
//! one entry per tick), numbers rounded to what a screen shows.
//!
//! Rounding: positions to the millimetre, angles to the milliradian, times
//! to the millisecond, speeds to the mm/s, the controller's values and
//! event payloads to 4 significant digits; ranges as whole centimetres
//! (`-1`: nothing within range, `-2`: a drop-out), people's positions and
//! the controller's point sets (a particle cloud, thinned to at most
//! [`CLOUD_POINTS`]) in centimetres. Sensor geometry (mounts, cones, beam angles) is written
//! once per distinct geometry, each tick naming its own by index.
//!
//! Order is the trace's (labels and value names in order of first
//! appearance), so the same run gives the same bytes.

use std::collections::BTreeMap;

use anyhow::Result;
use robot::{Command, EventValue, LaserScan, Perception, Pose, Vec2};
use serde::Serialize;
use sim::render::MarkerKind;

use crate::encode;
use crate::pictures::{EventMarker, MarkerPlace, Replay};

/// Radius people are drawn with, metres: the simulator's default (the trace
/// keeps positions only).
pub fn person_radius_m() -> f64 {
    sim::CrowdParams::default().radius_m
}

/// `v` rounded to `decimals` decimals (the double nearest the decimal, so
/// that JSON writes it short).
pub fn round_to(v: f64, decimals: i32) -> f64 {
    let f = 10f64.powi(decimals);
    (v * f).round() / f
}

/// `v` rounded to 4 significant digits (non-finite values unchanged).
pub fn round_sig4(v: f64) -> f64 {
    if !v.is_finite() || v == 0.0 {
        return v;
    }
    let e = v.abs().log10().floor() as i32;
    if e >= 3 {
        let f = 10f64.powi(e - 3);
        (v / f).round() * f
    } else {
        round_to(v, 3 - e)
    }
}

fn mm(v: f64) -> f64 {
    round_to(v, 3)
}

/// A range in whole centimetres: `-1` nothing within range, `-2` a
/// drop-out.
fn cm(range_m: f64) -> i32 {
    if range_m.is_nan() {
        -2
    } else if range_m.is_infinite() {
        -1
    } else {
        (range_m * 100.0).round() as i32
    }
}

fn pose(p: Pose) -> [f64; 3] {
    [mm(p.x_m), mm(p.y_m), mm(p.theta_rad)]
}

/// The map: the grid as a PNG data URI and where it lies.
#[derive(Debug, PartialEq, Serialize)]
pub struct MapData {
    /// `data:image/png;base64,…`, one pixel per cell, top row the map's last.
    pub png: String,
    /// Cells across.
    pub width: usize,
    /// Cells up.
    pub height: usize,
    /// Cell size, metres.
    pub resolution_m: f64,
    /// The pose of the map's corner (cell (0, 0)'s outer corner).
    pub origin: [f64; 3],
}

/// One laser's geometry.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LaserGeometry {
    /// Mount on the robot `[x, y, θ]`.
    pub mount: [f64; 3],
    /// First beam's angle, radians.
    pub angle_min: f64,
    /// Angle between beams, radians.
    pub angle_increment: f64,
    /// Maximum range, metres.
    pub range_max: f64,
    /// Beams.
    pub beams: usize,
}

/// One sonar's geometry.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SonarGeometry {
    /// Mount on the robot `[x, y, θ]`.
    pub mount: [f64; 3],
    /// Full cone width, radians.
    pub cone: f64,
}

/// One infrared detector's geometry.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct IrGeometry {
    /// Mount on the robot `[x, y, θ]`.
    pub mount: [f64; 3],
    /// Detection range, metres.
    pub range: f64,
}

/// The sensors of a perception, without their readings.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Geometry {
    /// Lasers.
    pub lasers: Vec<LaserGeometry>,
    /// Sonar transducers.
    pub sonar: Vec<SonarGeometry>,
    /// Infrared detectors.
    pub ir: Vec<IrGeometry>,
}

impl Geometry {
    fn of(p: &Perception) -> Geometry {
        Geometry {
            lasers: p.lasers.iter().map(laser_geometry).collect(),
            sonar: p
                .sonar
                .iter()
                .map(|s| SonarGeometry {
                    mount: pose(s.mount),
                    cone: mm(s.cone_rad),
                })
                .collect(),
            ir: p
                .ir
                .iter()
                .map(|d| IrGeometry {
                    mount: pose(d.mount),
                    range: mm(d.range_m),
                })
                .collect(),
        }
    }
}

fn laser_geometry(l: &LaserScan) -> LaserGeometry {
    LaserGeometry {
        mount: pose(l.mount),
        angle_min: l.angle_min_rad,
        angle_increment: l.angle_increment_rad,
        range_max: l.range_max_m,
        beams: l.ranges_m.len(),
    }
}

/// One tick's readings.
#[derive(Debug, Serialize)]
pub struct Readings {
    /// Index into [`RunData::geometries`].
    pub g: usize,
    /// Laser ranges, cm (see the module docs), one array per laser.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub laser: Vec<Vec<i32>>,
    /// Sonar ranges, cm.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub sonar: Vec<i32>,
    /// Infrared detectors triggered (1) or not (0).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub ir: Vec<u8>,
    /// The bumper is pressed.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub bumper: bool,
}

/// The per-tick columns.
#[derive(Debug, Default, Serialize)]
pub struct Ticks {
    /// Time, seconds.
    pub t: Vec<f64>,
    /// True pose `[x, y, θ]`.
    pub pose: Vec<[f64; 3]>,
    /// The controller's own pose estimate `[x, y, θ]`.
    pub estimate: Vec<[f64; 3]>,
    /// The command: `["twist", v, ω]`, `["wheels", left, right]`, `["stop"]`
    /// or `null` (the controller gave up).
    pub command: Vec<Option<CommandData>>,
    /// Wheel speeds driven `[left, right]`, m/s.
    pub wheels: Vec<[f64; 2]>,
    /// What the controller answered: `run`, `done`, `give_up`.
    pub step: Vec<&'static str>,
    /// Index into [`PageData::behaviours`], `-1` for none.
    pub behaviour: Vec<i32>,
    /// 1 when the footprint touched something during the tick.
    pub contact: Vec<u8>,
    /// The controller's values, one entry per [`RunData::keys`] (`null`
    /// where the tick has no such value).
    pub values: Vec<Vec<Option<f64>>>,
    /// Radius of a step-aside request, metres, if one was made.
    pub request: Vec<Option<f64>>,
    /// Sensor readings (`null` when the trace kept no perception).
    pub readings: Vec<Option<Readings>>,
    /// People's positions, centimetres, `[x0, y0, x1, y1, …]`.
    pub people: Vec<Vec<i32>>,
}

/// A command, as the page shows it.
#[derive(Debug, Serialize)]
#[serde(untagged)]
pub enum CommandData {
    /// `["twist", v, ω]` or `["wheels", left, right]`.
    Two(&'static str, f64, f64),
    /// `["stop"]`.
    Stop((&'static str,)),
}

/// One event, at its tick.
#[derive(Debug, Serialize)]
pub struct EventData {
    /// Tick index.
    pub tick: usize,
    /// Time, seconds.
    pub t: f64,
    /// Kind.
    pub kind: String,
    /// Where it is drawn `[x, y]` (the suite's markers say: the robot's true
    /// position, or the event's own position), if anywhere.
    pub at: Option<[f64; 2]>,
    /// Payload, values rounded.
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    pub payload: BTreeMap<String, serde_json::Value>,
}

/// How an event kind is drawn: the suite's marker as colour and shape.
#[derive(Debug, Serialize)]
pub struct MarkerStyle {
    /// `#rrggbb`.
    pub colour: String,
    /// `square`, `ring`, `point`, `start` or `goal`.
    pub shape: &'static str,
}

/// What the runs of a page share: the suite, the maps, the area shown
/// and how events are drawn.
#[derive(Debug, Serialize)]
pub struct PageData {
    /// The suite's name.
    pub suite: String,
    /// What the page shows (a run's key, or a scenario's name when it
    /// shows several of its runs).
    pub title: String,
    /// The distinct maps of the runs (a run names its own by index: runs
    /// of a scenario differ when its world varies per run).
    pub maps: Vec<MapData>,
    /// The area to show first `[xmin, ymin, xmax, ymax]`, metres: every
    /// map and every run's poses, a margin of a robot radius.
    pub view: [f64; 4],
    /// People's radius, metres.
    pub person_radius_m: f64,
    /// How the suite draws its event kinds.
    pub markers: BTreeMap<String, MarkerStyle>,
    /// Labels of the behaviour in control, in order of first appearance
    /// over the runs (so that a behaviour keeps its colour from run to
    /// run).
    pub behaviours: Vec<&'static str>,
    /// The runs, in the page's order (its `#run=K`).
    pub runs: Vec<RunEntry>,
}

/// A run as the page's run selector lists it (its ticks are elsewhere:
/// [`RunData`]).
#[derive(Debug, Serialize)]
pub struct RunEntry {
    /// The run's key (`SCENARIO#INDEX`).
    pub key: String,
    /// One line: outcome, time, path.
    pub summary: String,
}

/// Everything a viewer page shows of one run.
#[derive(Debug, Serialize)]
pub struct RunData {
    /// The run's key (`SCENARIO#INDEX`).
    pub key: String,
    /// One line: outcome, time, path.
    pub summary: String,
    /// The record's numbers (outcome first, then measures and metrics).
    pub record: Vec<(String, serde_json::Value)>,
    /// Index into [`PageData::maps`].
    pub map: usize,
    /// Robot footprint radius, metres.
    pub robot_radius_m: f64,
    /// Control period, seconds.
    pub dt_s: f64,
    /// Start pose.
    pub start: [f64; 3],
    /// Goal.
    pub goal: Option<[f64; 2]>,
    /// Names of the controller's values, in order of first appearance.
    pub keys: Vec<&'static str>,
    /// Distinct sensor geometries.
    pub geometries: Vec<Geometry>,
    /// Per-tick columns.
    pub ticks: Ticks,
    /// Every event.
    pub events: Vec<EventData>,
    /// The controller's point sets (a particle cloud), at the ticks it
    /// noted them; the page shows each name's latest at or before the
    /// current tick.
    pub clouds: Vec<CloudData>,
    /// A net drawn beside the map, its marking from the values
    /// ([`crate::net_view`]), if the run has one.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub net: Option<crate::net_view::NetView>,
}

/// Most points of a cloud a page keeps (every k-th of a larger cloud):
/// enough to show its spread and shape, a 500-particle filter noted at
/// every iteration would otherwise outweigh the rest of the page.
pub const CLOUD_POINTS: usize = 200;

/// A point set the controller noted at one tick.
#[derive(Debug, Serialize)]
pub struct CloudData {
    /// Tick index.
    pub tick: usize,
    /// The set's name (`particles`).
    pub name: &'static str,
    /// How many poses the controller noted (before thinning).
    pub size: usize,
    /// Positions, centimetres, `[x0, y0, x1, y1, …]`: at most
    /// [`CLOUD_POINTS`], every k-th pose.
    pub points: Vec<i32>,
}

/// A position in whole centimetres `[x, y]`.
fn centimetres(p: Vec2) -> [i32; 2] {
    [(p.x * 100.0).round() as i32, (p.y * 100.0).round() as i32]
}

/// `cloud` thinned to at most [`CLOUD_POINTS`] positions in centimetres.
fn cloud_points(cloud: &[Pose]) -> Vec<i32> {
    let stride = cloud.len().div_ceil(CLOUD_POINTS).max(1);
    cloud
        .iter()
        .step_by(stride)
        .flat_map(|p| centimetres(p.position()))
        .collect()
}

fn hex(c: [u8; 3]) -> String {
    format!("#{:02x}{:02x}{:02x}", c[0], c[1], c[2])
}

fn marker_style(kind: MarkerKind) -> MarkerStyle {
    let (colour, shape) = match kind {
        MarkerKind::Start => ([40, 160, 60], "start"),
        MarkerKind::Goal => ([210, 30, 30], "goal"),
        MarkerKind::Point => ([40, 90, 200], "point"),
        MarkerKind::Square(c) => (c, "square"),
        MarkerKind::Ring(c) => (c, "ring"),
    };
    MarkerStyle {
        colour: hex(colour),
        shape,
    }
}

fn payload_value(v: &EventValue) -> serde_json::Value {
    match v {
        EventValue::Bool(b) => serde_json::Value::Bool(*b),
        EventValue::Number(x) => serde_json::json!(round_sig4(*x)),
        EventValue::Text(s) => serde_json::Value::String(s.clone()),
    }
}

fn command(c: Option<Command>) -> Option<CommandData> {
    c.map(|c| match c {
        Command::Twist { v_mps, omega_radps } => CommandData::Two("twist", mm(v_mps), mm(omega_radps)),
        Command::Wheels { left_mps, right_mps } => CommandData::Two("wheels", mm(left_mps), mm(right_mps)),
        Command::Stop => CommandData::Stop(("stop",)),
    })
}

/// Every map's corners and every run's poses, a margin of the largest
/// robot radius.
fn view(replays: &[&Replay]) -> [f64; 4] {
    let mut b = [f64::INFINITY, f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY];
    let mut add = |x: f64, y: f64| {
        b[0] = b[0].min(x);
        b[1] = b[1].min(y);
        b[2] = b[2].max(x);
        b[3] = b[3].max(y);
    };
    let mut margin: f64 = 0.0;
    for replay in replays {
        let g = &replay.grid;
        let o = g.origin();
        let (w, h) = (
            g.width() as f64 * g.resolution_m(),
            g.height() as f64 * g.resolution_m(),
        );
        for (cx, cy) in [(0.0, 0.0), (w, 0.0), (0.0, h), (w, h)] {
            let p = o.transform(robot::Vec2::new(cx, cy));
            add(p.x, p.y);
        }
        for t in &replay.trace.ticks {
            add(t.true_pose.x_m, t.true_pose.y_m);
        }
        margin = margin.max(replay.robot_radius_m);
    }
    let m = margin;
    [mm(b[0] - m), mm(b[1] - m), mm(b[2] + m), mm(b[3] + m)]
}

fn record_rows(replay: &Replay) -> Vec<(String, serde_json::Value)> {
    let r = &replay.record;
    let mut rows = vec![
        ("outcome".to_string(), serde_json::json!(r.outcome)),
        ("time_s".to_string(), serde_json::json!(round_sig4(r.time_s))),
        (
            "path_length_m".to_string(),
            serde_json::json!(mm(r.path_length_m)),
        ),
        ("collisions".to_string(), serde_json::json!(r.collisions)),
        (
            "min_clearance_m".to_string(),
            serde_json::json!(mm(r.min_clearance_m)),
        ),
        (
            "goal_distance_m".to_string(),
            serde_json::json!(mm(r.goal_distance_m)),
        ),
        (
            "odometry_error_m".to_string(),
            serde_json::json!(mm(r.odometry_error_m)),
        ),
        ("ticks".to_string(), serde_json::json!(r.ticks)),
        (
            "seed".to_string(),
            serde_json::json!(replay.trace.seed.to_string()),
        ),
    ];
    for (k, v) in &r.metrics {
        rows.push((k.clone(), serde_json::json!(round_sig4(*v))));
    }
    rows
}

/// One run of a page: its replay and its key.
#[derive(Debug, Clone, Copy)]
pub struct PageRun<'a> {
    /// The replayed run.
    pub replay: &'a Replay,
    /// Its key (`SCENARIO#INDEX`).
    pub key: &'a str,
}

fn map_data(g: &sim::OccupancyGrid) -> Result<MapData> {
    Ok(MapData {
        png: format!("data:image/png;base64,{}", encode::base64(&encode::grid_png(g)?)),
        width: g.width(),
        height: g.height(),
        resolution_m: g.resolution_m(),
        origin: pose(g.origin()),
    })
}

fn summary(r: &crate::record::RunRecord) -> String {
    format!(
        "{} after {:.1} s, path {:.2} m, {} collisions",
        r.outcome.replace('_', " "),
        r.time_s,
        r.path_length_m,
        r.collisions
    )
}

/// The data of a page titled `title` for `suite` showing `runs`: what they
/// share, and each run's own; events are placed as `markers` say (an event
/// of another kind at its own position, or the robot's).
pub fn page_data(
    runs: &[PageRun<'_>],
    markers: &[EventMarker],
    suite: &str,
    title: &str,
) -> Result<(PageData, Vec<RunData>)> {
    let replays: Vec<&Replay> = runs.iter().map(|r| r.replay).collect();
    let behaviours = behaviours_of(&replays);
    let mut maps: Vec<MapData> = Vec::new();
    let mut data = Vec::new();
    for run in runs {
        let map = map_data(&run.replay.grid)?;
        let index = match maps.iter().position(|m| *m == map) {
            Some(i) => i,
            None => {
                maps.push(map);
                maps.len() - 1
            }
        };
        data.push(run_data(run.replay, markers, run.key, index, &behaviours));
    }
    let page = PageData {
        suite: suite.to_string(),
        title: title.to_string(),
        maps,
        view: view(&replays),
        person_radius_m: person_radius_m(),
        markers: markers
            .iter()
            .map(|m| (m.kind.to_string(), marker_style(m.marker)))
            .collect(),
        behaviours,
        runs: data
            .iter()
            .map(|d| RunEntry {
                key: d.key.clone(),
                summary: d.summary.clone(),
            })
            .collect(),
    };
    Ok((page, data))
}

/// The labels of the behaviours in control over `replays`, in order of
/// first appearance.
fn behaviours_of(replays: &[&Replay]) -> Vec<&'static str> {
    let mut behaviours: Vec<&'static str> = Vec::new();
    for t in replays.iter().flat_map(|r| &r.trace.ticks) {
        if let Some(b) = t.behaviour
            && !behaviours.contains(&b)
        {
            behaviours.push(b);
        }
    }
    behaviours
}

/// The data of `replay`, keyed `key`, on the map of index `map`, its
/// behaviours counted in `behaviours` (the page's); events are placed as
/// `markers` say.
pub fn run_data(
    replay: &Replay,
    markers: &[EventMarker],
    key: &str,
    map: usize,
    behaviours: &[&'static str],
) -> RunData {
    let mut keys: Vec<&'static str> = Vec::new();
    for t in &replay.trace.ticks {
        for (k, _) in &t.values {
            if !keys.contains(k) {
                keys.push(k);
            }
        }
    }
    let mut ticks = Ticks::default();
    let mut geometries: Vec<Geometry> = Vec::new();
    let mut events = Vec::new();
    let mut clouds = Vec::new();
    for (n, t) in replay.trace.ticks.iter().enumerate() {
        ticks.t.push(round_to(t.time_s, 3));
        ticks.pose.push(pose(t.true_pose));
        ticks.estimate.push(pose(t.estimated_pose));
        ticks.command.push(command(t.command));
        ticks.wheels.push([mm(t.wheels_mps.0), mm(t.wheels_mps.1)]);
        ticks.step.push(match t.step {
            sim::StepKind::Run => "run",
            sim::StepKind::Done => "done",
            sim::StepKind::GiveUp => "give_up",
        });
        ticks.behaviour.push(
            t.behaviour
                .and_then(|b| behaviours.iter().position(|x| *x == b))
                .map_or(-1, |i| i as i32),
        );
        ticks.contact.push(u8::from(t.contact));
        let mut row = vec![None; keys.len()];
        for (k, v) in &t.values {
            if let Some(i) = keys.iter().position(|x| x == k) {
                row[i] = v.is_finite().then(|| round_sig4(*v));
            }
        }
        ticks.values.push(row);
        ticks.request.push(t.request.map(|r| match r {
            robot::Request::StepAside { radius_m } => mm(radius_m),
        }));
        ticks.readings.push(t.perception.as_ref().map(|p| {
            let geometry = Geometry::of(p);
            let g = match geometries.iter().position(|x| *x == geometry) {
                Some(i) => i,
                None => {
                    geometries.push(geometry);
                    geometries.len() - 1
                }
            };
            Readings {
                g,
                laser: p
                    .lasers
                    .iter()
                    .map(|l| l.ranges_m.iter().map(|&r| cm(r)).collect())
                    .collect(),
                sonar: p.sonar.iter().map(|s| cm(s.range_m)).collect(),
                ir: p.ir.iter().map(|d| u8::from(d.triggered)).collect(),
                bumper: p.bumper,
            }
        }));
        ticks
            .people
            .push(t.people.iter().flat_map(|&p| centimetres(p)).collect());
        for (name, cloud) in &t.clouds {
            clouds.push(CloudData {
                tick: n,
                name,
                size: cloud.len(),
                points: cloud_points(cloud),
            });
        }
        for e in &t.events {
            let place = markers
                .iter()
                .find(|m| m.kind == e.kind)
                .map_or(MarkerPlace::Event, |m| m.place);
            let at = match (place, e.position) {
                (MarkerPlace::Event, Some(p)) => Some(p),
                _ => Some(t.true_pose.position()),
            };
            events.push(EventData {
                tick: n,
                t: round_to(e.time_s, 3),
                kind: e.kind.clone(),
                at: at.map(|p| [mm(p.x), mm(p.y)]),
                payload: e
                    .payload
                    .iter()
                    .map(|(k, v)| (k.clone(), payload_value(v)))
                    .collect(),
            });
        }
    }
    let r = &replay.record;
    RunData {
        key: key.to_string(),
        summary: summary(r),
        record: record_rows(replay),
        map,
        robot_radius_m: replay.robot_radius_m,
        dt_s: replay.control_period_s,
        start: [mm(r.start[0]), mm(r.start[1]), mm(r.start[2])],
        goal: replay.goal.map(|g| [mm(g.x), mm(g.y)]),
        keys,
        geometries,
        ticks,
        events,
        clouds,
        net: replay.net.clone(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_are_rounded_to_short_decimals() {
        assert_eq!(round_to(1.23456, 3), 1.235);
        assert_eq!(serde_json::to_string(&round_to(0.1 + 0.2, 3)).unwrap(), "0.3");
        assert_eq!(round_sig4(0.000123456), 0.0001235);
        assert_eq!(round_sig4(-4.567891), -4.568);
        assert_eq!(round_sig4(123456.0), 123500.0);
        assert_eq!(round_sig4(0.0), 0.0);
        assert!(round_sig4(f64::NAN).is_nan());
        assert_eq!((cm(1.234), cm(f64::INFINITY), cm(f64::NAN)), (123, -1, -2));
    }

    #[test]
    fn a_cloud_is_thinned_to_every_kth_pose() {
        let cloud: Vec<Pose> = (0..500)
            .map(|i| Pose::new(f64::from(i) * 0.01, -0.5, 0.0))
            .collect();
        let points = cloud_points(&cloud);
        // 500 poses → every 3rd: 167 positions.
        assert_eq!(points.len(), 2 * 167);
        assert_eq!(&points[..4], &[0, -50, 3, -50]);
        assert!(points.len() / 2 <= CLOUD_POINTS);
        assert_eq!(cloud_points(&cloud[..10]).len(), 20);
        assert!(cloud_points(&[]).is_empty());
    }

    #[test]
    fn a_noted_cloud_reaches_the_page_at_its_tick() {
        let mut replay = crate::test_replays::laser_replay();
        let big: Vec<Pose> = (0..450)
            .map(|i| Pose::new(1.0, f64::from(i) * 0.001, 0.0))
            .collect();
        replay.trace.ticks[2].clouds.push(("particles", big));
        let d = run_data(&replay, &[], "toy#0", 0, &["go"]);
        let at: Vec<(usize, &str, usize, usize)> = d
            .clouds
            .iter()
            .map(|c| (c.tick, c.name, c.size, c.points.len() / 2))
            .collect();
        assert_eq!(at, vec![(1, "particles", 2, 2), (2, "particles", 450, 150)]);
        assert_eq!(&d.clouds[0].points, &[110, 100, 120, 90]);
    }
}
