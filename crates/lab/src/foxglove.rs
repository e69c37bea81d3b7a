//! A replayed run as an MCAP file in Foxglove's well-known JSON schemas, so
//! that it opens in Foxglove (or any MCAP reader) the way a rosbag does.
//!
//! Frames: `map` (the world frame) and `base_link` (the robot's true pose).
//! Topics, one message per tick unless said otherwise, each timestamped
//! with the simulation time of its tick (log time = publish time = the
//! message's `timestamp`, nanoseconds from 0):
//!
//! | topic | schema | what |
//! |---|---|---|
//! | `/map` | `foxglove.Grid` | the run's own grid, once at time 0: one `UINT8` field `occupancy`, 0 free, 50 unknown, 100 occupied (as ROS occupancy percentages; colour it by a gradient over 0–100) |
//! | `/markers` | `foxglove.SceneUpdate` | once: start and goal (`map`), the footprint and a heading arrow (`base_link`, frame-locked) |
//! | `/tf` | `foxglove.FrameTransform` | `map` → `base_link` |
//! | `/pose` | `foxglove.PoseInFrame` | the true pose in `map` |
//! | `/pose_estimate` | `foxglove.PoseInFrame` | the controller's own estimate (odometry or localizer) in `map` |
//! | `/scan` (`/scan1`…) | `foxglove.LaserScan` | each laser's scan in `base_link`, its mount as `pose`; no return or a drop-out is 0 |
//! | `/ranges` | `foxglove.SceneUpdate` | sonar cones to their echo and IR beams (red when triggered) in `base_link`, for robots with sonar or IR |
//! | `/people` | `foxglove.SceneUpdate` | people as cylinders in `map`, when the trace has people |
//! | `/particles` (`/NAME`) | `foxglove.PosesInFrame` | each point set the controller noted (the localizer's particle cloud, as RViz shows AMCL's `particlecloud`), at the ticks it noted one, in `map` |
//! | `/notes` | `petrinav.Notes` | the controller's notes: behaviour, named values, events, command, wheels, contact |
//! | `/events` | `foxglove.Log` | one line per event (kind and payload), at its tick |
//!
//! A metadata record `petrinav` names the suite, the run and its seed.
//! Chunks are not compressed (the crate is built without its zstd and lz4
//! features: C libraries to compile, not needed here); the file is
//! the same bytes for the same run. Sizes: the voting run `e4/field12#0`
//! (54.4 s, 3 sonars and 7 IR detectors, 2,722 messages) is 1.96 MB; a
//! 600 s exploration of the 16-sonar robot 32 MB.

use std::collections::BTreeMap;
use std::io::{Seek, Write};
use std::path::Path;

use anyhow::{Context, Result, bail};
use mcap::records::{MessageHeader, Metadata};
use robot::{EventValue, Pose, Vec2};
use serde_json::{Value, json};

use crate::encode;
use crate::pictures::Replay;

/// What was written.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Written {
    /// Messages per topic (every channel, with none too), by topic.
    pub messages: BTreeMap<String, u64>,
    /// File size, bytes.
    pub bytes: u64,
}

/// Nanoseconds of `t_s` seconds (times before 0 are 0).
pub fn nanos(t_s: f64) -> u64 {
    (t_s.max(0.0) * 1e9).round() as u64
}

fn stamp(ns: u64) -> Value {
    json!({"sec": ns / 1_000_000_000, "nsec": ns % 1_000_000_000})
}

fn vec3(x: f64, y: f64, z: f64) -> Value {
    json!({"x": x, "y": y, "z": z})
}

fn quat_yaw(theta: f64) -> Value {
    let h = theta / 2.0;
    json!({"x": 0.0, "y": 0.0, "z": h.sin(), "w": h.cos()})
}

fn pose(p: Pose) -> Value {
    json!({"position": vec3(p.x_m, p.y_m, 0.0), "orientation": quat_yaw(p.theta_rad)})
}

fn colour(r: f64, g: f64, b: f64, a: f64) -> Value {
    json!({"r": r, "g": g, "b": b, "a": a})
}

/// A finite number, or `null` (JSON has no infinities or NaN).
fn finite(v: f64) -> Value {
    if v.is_finite() { json!(v) } else { Value::Null }
}

/// A `foxglove.SceneEntity` with the primitives given (the others empty).
fn entity(ns: u64, frame: &str, id: &str, frame_locked: bool, primitives: &[(&str, Vec<Value>)]) -> Value {
    let mut e = json!({
        "timestamp": stamp(ns),
        "frame_id": frame,
        "id": id,
        "lifetime": {"sec": 0, "nsec": 0},
        "frame_locked": frame_locked,
        "metadata": [],
        "arrows": [], "cubes": [], "spheres": [], "cylinders": [],
        "lines": [], "triangles": [], "texts": [], "models": [],
    });
    for (kind, items) in primitives {
        e[*kind] = Value::Array(items.clone());
    }
    e
}

fn scene(entities: Vec<Value>) -> Value {
    json!({"deletions": [], "entities": entities})
}

fn line(kind: u8, points: &[(f64, f64)], thickness_px: f64, c: Value) -> Value {
    json!({
        "type": kind,
        "pose": pose(Pose::default()),
        "thickness": thickness_px,
        "scale_invariant": true,
        "points": points.iter().map(|&(x, y)| json!({"x": x, "y": y, "z": 0})).collect::<Vec<_>>(),
        "color": c,
        "colors": [],
        "indices": [],
    })
}

fn cylinder(at: Vec2, radius_m: f64, height_m: f64, c: Value) -> Value {
    json!({
        "pose": pose(Pose::new(at.x, at.y, 0.0)),
        "size": vec3(2.0 * radius_m, 2.0 * radius_m, height_m),
        "bottom_scale": 1.0,
        "top_scale": 1.0,
        "color": c,
    })
}

/// The JSON schemas, written for the fields this module fills (Foxglove
/// recognises the schema by its name).
mod schema {
    use serde_json::{Value, json};

    fn num() -> Value {
        json!({"type": "number"})
    }
    fn text() -> Value {
        json!({"type": "string"})
    }
    fn int() -> Value {
        json!({"type": "integer", "minimum": 0})
    }
    fn array(items: Value) -> Value {
        json!({"type": "array", "items": items})
    }
    fn object(title: &str, properties: Value) -> Value {
        json!({"title": title, "type": "object", "properties": properties})
    }
    pub fn time() -> Value {
        json!({"type": "object", "title": "time", "properties": {
            "sec": {"type": "integer", "minimum": 0},
            "nsec": {"type": "integer", "minimum": 0, "maximum": 999_999_999}}})
    }
    fn duration() -> Value {
        json!({"type": "object", "title": "duration", "properties": {
            "sec": {"type": "integer"}, "nsec": {"type": "integer", "minimum": 0, "maximum": 999_999_999}}})
    }
    fn vector3() -> Value {
        object("foxglove.Vector3", json!({"x": num(), "y": num(), "z": num()}))
    }
    fn quaternion() -> Value {
        object(
            "foxglove.Quaternion",
            json!({"x": num(), "y": num(), "z": num(), "w": num()}),
        )
    }
    pub fn pose() -> Value {
        object(
            "foxglove.Pose",
            json!({"position": vector3(), "orientation": quaternion()}),
        )
    }
    fn color() -> Value {
        object(
            "foxglove.Color",
            json!({"r": num(), "g": num(), "b": num(), "a": num()}),
        )
    }
    fn top(title: &str, description: &str, properties: Value) -> Value {
        let mut v = object(title, properties);
        v["description"] = json!(description);
        v
    }

    pub fn pose_in_frame() -> Value {
        top(
            "foxglove.PoseInFrame",
            "A timestamped pose for an object or reference frame in 3D space",
            json!({"timestamp": time(), "frame_id": text(), "pose": pose()}),
        )
    }
    pub fn poses_in_frame() -> Value {
        top(
            "foxglove.PosesInFrame",
            "An array of timestamped poses for an object or reference frame in 3D space",
            json!({"timestamp": time(), "frame_id": text(), "poses": array(pose())}),
        )
    }
    pub fn frame_transform() -> Value {
        top(
            "foxglove.FrameTransform",
            "A transform between two reference frames in 3D space",
            json!({"timestamp": time(), "parent_frame_id": text(), "child_frame_id": text(),
                   "translation": vector3(), "rotation": quaternion()}),
        )
    }
    pub fn laser_scan() -> Value {
        top(
            "foxglove.LaserScan",
            "A single scan from a planar laser range-finder",
            json!({"timestamp": time(), "frame_id": text(), "pose": pose(),
                   "start_angle": num(), "end_angle": num(),
                   "ranges": array(num()), "intensities": array(num())}),
        )
    }
    pub fn grid() -> Value {
        let field = object(
            "foxglove.PackedElementField",
            json!({"name": text(), "offset": int(),
                   "type": {"title": "foxglove.NumericType", "type": "integer", "description": "1: UINT8"}}),
        );
        top(
            "foxglove.Grid",
            "A 2D grid of data",
            json!({"timestamp": time(), "frame_id": text(), "pose": pose(), "column_count": int(),
                   "cell_size": object("foxglove.Vector2", json!({"x": num(), "y": num()})),
                   "row_stride": int(), "cell_stride": int(), "fields": array(field),
                   "data": {"type": "string", "contentEncoding": "base64"}}),
        )
    }
    pub fn scene_update() -> Value {
        let point = object("foxglove.Point3", json!({"x": num(), "y": num(), "z": num()}));
        let line = object(
            "foxglove.LinePrimitive",
            json!({"type": {"title": "foxglove.LinePrimitive.Type", "type": "integer",
                            "description": "0 LINE_STRIP, 1 LINE_LOOP, 2 LINE_LIST"},
                   "pose": pose(), "thickness": num(), "scale_invariant": {"type": "boolean"},
                   "points": array(point), "color": color(), "colors": array(color()),
                   "indices": array(int())}),
        );
        let cylinder = object(
            "foxglove.CylinderPrimitive",
            json!({"pose": pose(), "size": vector3(), "bottom_scale": num(), "top_scale": num(), "color": color()}),
        );
        let sphere = object(
            "foxglove.SpherePrimitive",
            json!({"pose": pose(), "size": vector3(), "color": color()}),
        );
        let arrow = object(
            "foxglove.ArrowPrimitive",
            json!({"pose": pose(), "shaft_length": num(), "shaft_diameter": num(),
                   "head_length": num(), "head_diameter": num(), "color": color()}),
        );
        let other = json!({"type": "object"});
        let entity = object(
            "foxglove.SceneEntity",
            json!({"timestamp": time(), "frame_id": text(), "id": text(), "lifetime": duration(),
                   "frame_locked": {"type": "boolean"},
                   "metadata": array(object("foxglove.KeyValuePair", json!({"key": text(), "value": text()}))),
                   "arrows": array(arrow), "cubes": array(other.clone()), "spheres": array(sphere),
                   "cylinders": array(cylinder), "lines": array(line), "triangles": array(other.clone()),
                   "texts": array(other.clone()), "models": array(other)}),
        );
        top(
            "foxglove.SceneUpdate",
            "An update to the entities displayed in a 3D scene",
            json!({"deletions": array(json!({"type": "object"})), "entities": array(entity)}),
        )
    }
    pub fn log() -> Value {
        top(
            "foxglove.Log",
            "A log message",
            json!({"timestamp": time(), "level": {"title": "foxglove.LogLevel", "type": "integer",
                                                  "description": "1 DEBUG, 2 INFO, 3 WARNING, 4 ERROR, 5 FATAL"},
                   "message": text(), "name": text(), "file": text(), "line": int()}),
        )
    }
    pub fn notes() -> Value {
        top(
            "petrinav.Notes",
            "What the controller noted at one control tick (robot::Notes), with its command",
            json!({"timestamp": time(), "tick": int(), "time_s": num(),
                   "behaviour": {"type": ["string", "null"]},
                   "values": {"type": "object", "additionalProperties": {"type": ["number", "null"]}},
                   "events": array(json!({"type": "object"})),
                   "step": text(), "command": {"type": ["object", "null"]},
                   "wheels_mps": array(num()), "contact": {"type": "boolean"},
                   "request_radius_m": {"type": ["number", "null"]}}),
        )
    }
}

/// The channels, in the file's order.
struct Channels {
    ids: BTreeMap<String, u16>,
    sequence: BTreeMap<u16, u32>,
    counts: BTreeMap<String, u64>,
}

impl Channels {
    fn add<W: Write + Seek>(
        &mut self,
        w: &mut mcap::Writer<W>,
        topic: &str,
        schema_name: &str,
        schema: &Value,
    ) -> Result<()> {
        let data = serde_json::to_vec(schema)?;
        let s = w.add_schema(schema_name, "jsonschema", &data)?;
        let c = w.add_channel(s, topic, "json", &BTreeMap::new())?;
        self.ids.insert(topic.to_string(), c);
        self.counts.insert(topic.to_string(), 0);
        Ok(())
    }

    fn write<W: Write + Seek>(
        &mut self,
        w: &mut mcap::Writer<W>,
        topic: &str,
        ns: u64,
        msg: &Value,
    ) -> Result<()> {
        let id = self.ids[topic];
        let seq = self.sequence.entry(id).or_insert(0);
        w.write_to_known_channel(
            &MessageHeader {
                channel_id: id,
                sequence: *seq,
                log_time: ns,
                publish_time: ns,
            },
            &serde_json::to_vec(msg)?,
        )?;
        *seq += 1;
        *self.counts.entry(topic.to_string()).or_insert(0) += 1;
        Ok(())
    }
}

fn grid_message(replay: &Replay) -> Value {
    let g = &replay.grid;
    let cells = encode::grid_cells_bottom_up(g);
    let data: Vec<u8> = cells
        .into_iter()
        .map(|c| match c {
            encode::FREE_GREY => 0,
            encode::OCCUPIED_GREY => 100,
            _ => 50,
        })
        .collect();
    json!({
        "timestamp": stamp(0),
        "frame_id": "map",
        "pose": pose(g.origin()),
        "column_count": g.width(),
        "cell_size": {"x": g.resolution_m(), "y": g.resolution_m()},
        "row_stride": g.width(),
        "cell_stride": 1,
        "fields": [{"name": "occupancy", "offset": 0, "type": 1}],
        "data": encode::base64(&data),
    })
}

fn markers_message(replay: &Replay) -> Value {
    let s = replay.record.start;
    let mut map_spheres = vec![json!({
        "pose": pose(Pose::new(s[0], s[1], 0.0)),
        "size": vec3(0.15, 0.15, 0.15),
        "color": colour(0.16, 0.63, 0.24, 1.0),
    })];
    if let Some(goal) = replay.goal {
        map_spheres.push(json!({
            "pose": pose(Pose::new(goal.x, goal.y, 0.0)),
            "size": vec3(0.25, 0.25, 0.25),
            "color": colour(0.82, 0.12, 0.12, 1.0),
        }));
    }
    let r = replay.robot_radius_m;
    scene(vec![
        entity(0, "map", "start_goal", false, &[("spheres", map_spheres)]),
        entity(
            0,
            "base_link",
            "footprint",
            true,
            &[
                (
                    "cylinders",
                    vec![cylinder(
                        Vec2::new(0.0, 0.0),
                        r,
                        0.1,
                        colour(0.24, 0.47, 0.86, 0.6),
                    )],
                ),
                (
                    "arrows",
                    vec![json!({
                        "pose": pose(Pose::new(0.0, 0.0, 0.0)),
                        "shaft_length": r, "shaft_diameter": r / 5.0,
                        "head_length": r / 2.0, "head_diameter": r / 2.5,
                        "color": colour(0.04, 0.16, 0.38, 1.0),
                    })],
                ),
            ],
        ),
    ])
}

/// Sonar cones (an outline from the transducer to its echo, one line list
/// for all) and IR beams (one line list for those triggered, red, one for
/// the others), points to the millimetre.
fn ranges_message(ns: u64, p: &robot::Perception) -> Value {
    let mm = |v: f64| (v * 1000.0).round() / 1000.0;
    let mut cones = Vec::new();
    for s in &p.sonar {
        if !s.range_m.is_finite() {
            continue;
        }
        let m = s.mount;
        let arc: Vec<(f64, f64)> = (0..=2)
            .map(|k| {
                let a = m.theta_rad - s.cone_rad / 2.0 + s.cone_rad * f64::from(k) / 2.0;
                (mm(m.x_m + s.range_m * a.cos()), mm(m.y_m + s.range_m * a.sin()))
            })
            .collect();
        let at = (mm(m.x_m), mm(m.y_m));
        cones.extend([at, arc[0], at, arc[2]]);
        for pair in arc.windows(2) {
            cones.extend([pair[0], pair[1]]);
        }
    }
    let (mut on, mut off) = (Vec::new(), Vec::new());
    for d in &p.ir {
        let m = d.mount;
        let beam = [
            (mm(m.x_m), mm(m.y_m)),
            (
                mm(m.x_m + d.range_m * m.theta_rad.cos()),
                mm(m.y_m + d.range_m * m.theta_rad.sin()),
            ),
        ];
        if d.triggered { &mut on } else { &mut off }.extend(beam);
    }
    let mut lines = Vec::new();
    for (points, thickness, c) in [
        (cones, 1.5, colour(0.12, 0.39, 0.86, 0.8)),
        (on, 3.0, colour(0.86, 0.08, 0.08, 1.0)),
        (off, 1.0, colour(0.08, 0.59, 0.24, 0.5)),
    ] {
        if !points.is_empty() {
            lines.push(line(2, &points, thickness, c));
        }
    }
    scene(vec![entity(
        ns,
        "base_link",
        "ranges",
        false,
        &[("lines", lines)],
    )])
}

fn event_value(v: &EventValue) -> Value {
    match v {
        EventValue::Bool(b) => json!(b),
        EventValue::Number(x) => finite(*x),
        EventValue::Text(s) => json!(s),
    }
}

fn command_value(c: Option<robot::Command>) -> Value {
    match c {
        None => Value::Null,
        Some(robot::Command::Twist { v_mps, omega_radps }) => {
            json!({"kind": "twist", "v_mps": finite(v_mps), "omega_radps": finite(omega_radps)})
        }
        Some(robot::Command::Wheels { left_mps, right_mps }) => {
            json!({"kind": "wheels", "left_mps": finite(left_mps), "right_mps": finite(right_mps)})
        }
        Some(robot::Command::Stop) => json!({"kind": "stop"}),
    }
}

/// What topics a replay has beyond the fixed ones: its lasers, whether it
/// has range sensors and people, its point clouds (in order of first
/// appearance).
struct Topics {
    lasers: usize,
    ranges: bool,
    people: bool,
    clouds: Vec<&'static str>,
}

impl Topics {
    /// The topics of `ticks`.
    fn of(ticks: &[sim::TraceTick]) -> Topics {
        let lasers = ticks
            .iter()
            .filter_map(|t| t.perception.as_ref())
            .map(|p| p.lasers.len())
            .max()
            .unwrap_or(0);
        let ranges = ticks
            .iter()
            .filter_map(|t| t.perception.as_ref())
            .any(|p| !p.sonar.is_empty() || !p.ir.is_empty());
        let people = ticks.iter().any(|t| !t.people.is_empty());
        let mut clouds: Vec<&'static str> = Vec::new();
        for t in ticks {
            for (name, _) in &t.clouds {
                if !clouds.contains(name) {
                    clouds.push(name);
                }
            }
        }
        Topics {
            lasers,
            ranges,
            people,
            clouds,
        }
    }
}

/// The topic of laser `k`: `/scan`, `/scan1`, …
fn scan_topic(k: usize) -> String {
    if k == 0 {
        "/scan".to_string()
    } else {
        format!("/scan{k}")
    }
}

/// Writes `replay` as MCAP to `out` (see the module docs for the topics).
/// Returns the messages written per topic and `out`, flushed by the MCAP
/// writer (a `BufWriter` still holds what it buffered).
pub fn write<W: Write + Seek>(
    replay: &Replay,
    suite: &str,
    key: &str,
    out: W,
) -> Result<(BTreeMap<String, u64>, W)> {
    let ticks = &replay.trace.ticks;
    if ticks.is_empty() {
        bail!("run `{key}` has no tick to export");
    }
    let mut w = mcap::WriteOptions::new()
        .compression(None)
        .profile("")
        .create(out)
        .context("starting the MCAP file")?;
    let mut ch = Channels {
        ids: BTreeMap::new(),
        sequence: BTreeMap::new(),
        counts: BTreeMap::new(),
    };
    let topics = Topics::of(ticks);
    add_channels(&mut ch, &mut w, &topics)?;
    w.write_metadata(&Metadata {
        name: "petrinav".into(),
        metadata: BTreeMap::from([
            ("suite".to_string(), suite.to_string()),
            ("run".to_string(), key.to_string()),
            ("seed".to_string(), replay.trace.seed.to_string()),
            ("outcome".to_string(), replay.record.outcome.clone()),
        ]),
    })?;
    let t0 = nanos(ticks[0].time_s);
    ch.write(&mut w, "/map", t0, &grid_message(replay))?;
    ch.write(&mut w, "/markers", t0, &markers_message(replay))?;
    for (n, t) in ticks.iter().enumerate() {
        write_tick(&mut ch, &mut w, &topics, n, t)?;
    }
    w.finish().context("finishing the MCAP file")?;
    Ok((ch.counts, w.into_inner()))
}

/// Adds the channels of the fixed topics and of `topics`, in the file's
/// order.
fn add_channels<W: Write + Seek>(ch: &mut Channels, w: &mut mcap::Writer<W>, topics: &Topics) -> Result<()> {
    ch.add(w, "/map", "foxglove.Grid", &schema::grid())?;
    ch.add(w, "/markers", "foxglove.SceneUpdate", &schema::scene_update())?;
    ch.add(w, "/tf", "foxglove.FrameTransform", &schema::frame_transform())?;
    ch.add(w, "/pose", "foxglove.PoseInFrame", &schema::pose_in_frame())?;
    ch.add(
        w,
        "/pose_estimate",
        "foxglove.PoseInFrame",
        &schema::pose_in_frame(),
    )?;
    for k in 0..topics.lasers {
        ch.add(w, &scan_topic(k), "foxglove.LaserScan", &schema::laser_scan())?;
    }
    if topics.ranges {
        ch.add(w, "/ranges", "foxglove.SceneUpdate", &schema::scene_update())?;
    }
    if topics.people {
        ch.add(w, "/people", "foxglove.SceneUpdate", &schema::scene_update())?;
    }
    for name in &topics.clouds {
        ch.add(
            w,
            &format!("/{name}"),
            "foxglove.PosesInFrame",
            &schema::poses_in_frame(),
        )?;
    }
    ch.add(w, "/notes", "petrinav.Notes", &schema::notes())?;
    ch.add(w, "/events", "foxglove.Log", &schema::log())?;
    Ok(())
}

/// Writes the messages of tick `n`, `t`: the frames, the poses, the
/// scans, the ranges, the clouds, the people, the notes and the events.
fn write_tick<W: Write + Seek>(
    ch: &mut Channels,
    w: &mut mcap::Writer<W>,
    topics: &Topics,
    n: usize,
    t: &sim::TraceTick,
) -> Result<()> {
    let ns = nanos(t.time_s);
    let p = t.true_pose;
    ch.write(
        w,
        "/tf",
        ns,
        &json!({"timestamp": stamp(ns), "parent_frame_id": "map", "child_frame_id": "base_link",
                "translation": vec3(p.x_m, p.y_m, 0.0), "rotation": quat_yaw(p.theta_rad)}),
    )?;
    ch.write(
        w,
        "/pose",
        ns,
        &json!({"timestamp": stamp(ns), "frame_id": "map", "pose": pose(p)}),
    )?;
    ch.write(
        w,
        "/pose_estimate",
        ns,
        &json!({"timestamp": stamp(ns), "frame_id": "map", "pose": pose(t.estimated_pose)}),
    )?;
    if let Some(perception) = &t.perception {
        write_scans(ch, w, ns, perception)?;
        if topics.ranges {
            ch.write(w, "/ranges", ns, &ranges_message(ns, perception))?;
        }
    }
    for (name, cloud) in &t.clouds {
        let poses: Vec<Value> = cloud.iter().map(|&q| pose(q)).collect();
        ch.write(
            w,
            &format!("/{name}"),
            ns,
            &json!({"timestamp": stamp(ns), "frame_id": "map", "poses": poses}),
        )?;
    }
    if topics.people {
        let radius = crate::viewer::data::person_radius_m();
        let discs: Vec<Value> = t
            .people
            .iter()
            .map(|&q| cylinder(q, radius, 1.7, colour(0.94, 0.59, 0.12, 0.8)))
            .collect();
        ch.write(
            w,
            "/people",
            ns,
            &scene(vec![entity(ns, "map", "people", false, &[("cylinders", discs)])]),
        )?;
    }
    ch.write(w, "/notes", ns, &notes_message(n, ns, t))?;
    write_events(ch, w, ns, t)
}

/// Writes the scans of `perception` at `ns`, ranges in millimetres.
fn write_scans<W: Write + Seek>(
    ch: &mut Channels,
    w: &mut mcap::Writer<W>,
    ns: u64,
    perception: &robot::Perception,
) -> Result<()> {
    for (k, l) in perception.lasers.iter().enumerate() {
        let n_beams = l.ranges_m.len();
        let ranges: Vec<f64> = l
            .ranges_m
            .iter()
            .map(|&r| {
                if r.is_finite() {
                    (r * 1000.0).round() / 1000.0
                } else {
                    0.0
                }
            })
            .collect();
        ch.write(
            w,
            &scan_topic(k),
            ns,
            &json!({"timestamp": stamp(ns), "frame_id": "base_link", "pose": pose(l.mount),
                    "start_angle": l.angle_min_rad,
                    "end_angle": l.angle_min_rad + l.angle_increment_rad * n_beams.saturating_sub(1) as f64,
                    "ranges": ranges, "intensities": []}),
        )?;
    }
    Ok(())
}

/// The `/notes` message of tick `n`, `t`: its values, events, step,
/// command, wheels, contact and request.
fn notes_message(n: usize, ns: u64, t: &sim::TraceTick) -> Value {
    let values: serde_json::Map<String, Value> = t
        .values
        .iter()
        .map(|(k, v)| (k.to_string(), finite(*v)))
        .collect();
    let events: Vec<Value> = t
        .events
        .iter()
        .map(|e| {
            let payload: serde_json::Map<String, Value> = e
                .payload
                .iter()
                .map(|(k, v)| (k.clone(), event_value(v)))
                .collect();
            json!({"kind": e.kind, "time_s": e.time_s,
                   "position": e.position.map(|q| json!({"x": q.x, "y": q.y})), "payload": payload})
        })
        .collect();
    json!({"timestamp": stamp(ns), "tick": n, "time_s": t.time_s, "behaviour": t.behaviour,
        "values": values, "events": events,
        "step": match t.step { sim::StepKind::Run => "run", sim::StepKind::Done => "done", sim::StepKind::GiveUp => "give_up" },
        "command": command_value(t.command),
        "wheels_mps": [t.wheels_mps.0, t.wheels_mps.1], "contact": t.contact,
        "request_radius_m": t.request.map(|r| match r { robot::Request::StepAside { radius_m } => radius_m })})
}

/// Writes the events of tick `t` as `/events` log lines at `ns`.
fn write_events<W: Write + Seek>(
    ch: &mut Channels,
    w: &mut mcap::Writer<W>,
    ns: u64,
    t: &sim::TraceTick,
) -> Result<()> {
    for e in &t.events {
        let payload: Vec<String> = e
            .payload
            .iter()
            .map(|(k, v)| match v {
                EventValue::Bool(b) => format!("{k} {b}"),
                EventValue::Number(x) => format!("{k} {x}"),
                EventValue::Text(s) => format!("{k} {s}"),
            })
            .collect();
        let message = if payload.is_empty() {
            e.kind.clone()
        } else {
            format!("{}: {}", e.kind, payload.join(", "))
        };
        ch.write(
            w,
            "/events",
            ns,
            &json!({"timestamp": stamp(ns), "level": 2, "message": message,
                    "name": "controller", "file": "", "line": 0}),
        )?;
    }
    Ok(())
}

/// Writes `replay` as MCAP to the file `path`.
pub fn write_file(replay: &Replay, suite: &str, key: &str, path: &Path) -> Result<Written> {
    let f = std::fs::File::create(path).with_context(|| format!("writing {}", path.display()))?;
    let (messages, mut out) = write(replay, suite, key, std::io::BufWriter::new(f))
        .with_context(|| format!("writing {}", path.display()))?;
    out.flush()
        .with_context(|| format!("writing {}", path.display()))?;
    let bytes = std::fs::metadata(path)
        .with_context(|| format!("reading {}", path.display()))?
        .len();
    Ok(Written { messages, bytes })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_replays::laser_replay;

    fn export(replay: &Replay) -> (BTreeMap<String, u64>, Vec<u8>) {
        let (counts, out) = write(replay, "toy", "toy#0", std::io::Cursor::new(Vec::new())).unwrap();
        (counts, out.into_inner())
    }

    #[test]
    fn a_laser_run_has_a_scan_and_the_people_every_tick() {
        let replay = laser_replay();
        let (counts, bytes) = export(&replay);
        let expected: BTreeMap<String, u64> = [
            ("/events", 1),
            ("/map", 1),
            ("/markers", 1),
            ("/notes", 3),
            ("/particles", 1),
            ("/people", 3),
            ("/pose", 3),
            ("/pose_estimate", 3),
            ("/scan", 3),
            ("/tf", 3),
        ]
        .into_iter()
        .map(|(k, v)| (k.to_string(), v))
        .collect();
        assert_eq!(counts, expected);
        let summary = mcap::Summary::read(&bytes).unwrap().unwrap();
        let stats = summary.stats.unwrap();
        assert_eq!(stats.message_count, 22);
        assert_eq!(
            (stats.message_start_time, stats.message_end_time),
            (0, 200_000_000)
        );
        let mut scans = Vec::new();
        let mut notes = Vec::new();
        for m in mcap::MessageStream::new(&bytes).unwrap() {
            let m = m.unwrap();
            let v: Value = serde_json::from_slice(&m.data).unwrap();
            match m.channel.topic.as_str() {
                "/scan" => scans.push(v),
                "/notes" => notes.push(v),
                "/map" => {
                    assert_eq!(v["column_count"], 40);
                    assert_eq!(v["data"].as_str().unwrap().len(), (40 * 30usize).div_ceil(3) * 4);
                }
                "/events" => assert_eq!(v["message"], "stuck: events 3"),
                "/particles" => {
                    assert_eq!(m.log_time, 100_000_000, "at the tick that noted it");
                    assert_eq!(v["poses"].as_array().unwrap().len(), 2);
                    assert_eq!(v["poses"][1]["position"]["x"], json!(1.2));
                }
                _ => {}
            }
        }
        assert_eq!(
            scans[1]["ranges"],
            json!([1.0, 1.235, 0.0, 0.0, 2.0]),
            "no return and drop-outs are 0, the rest to the mm"
        );
        assert_eq!(scans[1]["end_angle"], json!(1.0));
        assert_eq!(scans[1]["timestamp"], json!({"sec": 0, "nsec": 100_000_000}));
        assert_eq!(notes[0]["values"], json!({"inf": null, "w": 0.25}));
        assert_eq!(notes[2]["events"][0]["payload"], json!({"events": 3.0}));
    }

    #[test]
    fn the_same_run_gives_the_same_bytes() {
        let replay = laser_replay();
        assert_eq!(export(&replay).1, export(&replay).1);
    }

    #[test]
    fn a_run_without_ticks_is_refused() {
        let mut replay = laser_replay();
        replay.trace.ticks.clear();
        let err = write(&replay, "toy", "toy#0", std::io::Cursor::new(Vec::new())).unwrap_err();
        assert!(err.to_string().contains("no tick"), "{err}");
    }
}
