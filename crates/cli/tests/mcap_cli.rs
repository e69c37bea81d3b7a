//! `lab replay --mcap`, read back with the `mcap` crate: the channels and
//! their schemas, one pose, transform, scan and notes message per tick
//! timestamped with the tick's simulation time, the events, the time range,
//! and the same bytes for the same run.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

fn petrinav(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_petrinav"))
        .args(args)
        .output()
        .expect("the petrinav binary runs")
}

fn fresh(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("mcap_{name}"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn replay(results: &Path, run: &str, extra: &[&str]) -> std::process::Output {
    let mut args = vec!["lab", "replay", results.to_str().unwrap(), run];
    args.extend_from_slice(extra);
    petrinav(&args)
}

#[test]
fn the_mcap_of_a_voting_run_has_one_pose_and_one_scan_per_tick_at_simulation_time() {
    let dir = fresh("voting");
    let results = dir.join("voting");
    let out = petrinav(&[
        "lab",
        "run",
        "voting",
        "--runs",
        "1",
        "--no-pictures",
        "--out",
        results.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(check_export(&dir, &results, "e4/field12#0"), 0);
    // The same field with the activity-trace layer: CP events, a dead-lock.
    assert!(check_export(&dir, &results, "e5/field12#0") > 2);
}

/// Checks the export of `run` against its trace; the number of events.
fn check_export(dir: &Path, results: &Path, run: &str) -> usize {
    let name = run.replace(['/', '#'], "-");
    let (file, trace) = (
        dir.join(format!("{name}.mcap")),
        dir.join(format!("{name}.jsonl")),
    );
    let out = replay(
        results,
        run,
        &[
            "--mcap",
            file.to_str().unwrap(),
            "--trace",
            trace.to_str().unwrap(),
        ],
    );
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(String::from_utf8_lossy(&out.stderr).contains("messages on 8 topics"));

    let ticks: Vec<serde_json::Value> = std::fs::read_to_string(&trace)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    let times_ns: Vec<u64> = ticks
        .iter()
        .map(|t| (t["time_s"].as_f64().unwrap() * 1e9).round() as u64)
        .collect();
    let events: usize = ticks
        .iter()
        .map(|t| t.get("events").and_then(|e| e.as_array()).map_or(0, Vec::len))
        .sum();
    let n = ticks.len() as u64;
    assert!(n > 300, "{n} ticks");

    let bytes = std::fs::read(&file).unwrap();
    let summary = mcap::Summary::read(&bytes).unwrap().expect("a summary section");
    let mut schema_of: BTreeMap<String, String> = BTreeMap::new();
    let mut id_of: BTreeMap<String, u16> = BTreeMap::new();
    for c in summary.channels.values() {
        assert_eq!(c.message_encoding, "json");
        let s = c.schema.as_ref().expect("every channel has a schema");
        assert_eq!(s.encoding, "jsonschema");
        let parsed: serde_json::Value = serde_json::from_slice(&s.data).unwrap();
        assert_eq!(parsed["title"], s.name.as_str());
        schema_of.insert(c.topic.clone(), s.name.clone());
        id_of.insert(c.topic.clone(), c.id);
    }
    let expected: BTreeMap<String, String> = [
        ("/events", "foxglove.Log"),
        ("/map", "foxglove.Grid"),
        ("/markers", "foxglove.SceneUpdate"),
        ("/notes", "petrinav.Notes"),
        ("/pose", "foxglove.PoseInFrame"),
        ("/pose_estimate", "foxglove.PoseInFrame"),
        ("/ranges", "foxglove.SceneUpdate"),
        ("/tf", "foxglove.FrameTransform"),
    ]
    .into_iter()
    .map(|(a, b)| (a.to_string(), b.to_string()))
    .collect();
    assert_eq!(
        schema_of, expected,
        "the voting robot has sonar and IR, no laser, no people"
    );

    let stats = summary.stats.expect("statistics");
    let count = |topic: &str| {
        stats
            .channel_message_counts
            .get(&id_of[topic])
            .copied()
            .unwrap_or(0)
    };
    for topic in ["/pose", "/pose_estimate", "/tf", "/ranges", "/notes"] {
        assert_eq!(count(topic), n, "{topic}");
    }
    assert_eq!((count("/map"), count("/markers")), (1, 1));
    assert_eq!(count("/events") as usize, events);
    assert_eq!(stats.message_start_time, 0);
    assert_eq!(stats.message_end_time, *times_ns.last().unwrap());

    // Every pose at its tick's time, where the trace says the robot was.
    let mut poses = Vec::new();
    let mut scans = 0;
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        assert_eq!(m.log_time, m.publish_time);
        let v: serde_json::Value = serde_json::from_slice(&m.data).unwrap();
        if let Some(ts) = v.get("timestamp") {
            let ns = ts["sec"].as_u64().unwrap() * 1_000_000_000 + ts["nsec"].as_u64().unwrap();
            assert_eq!(ns, m.log_time, "{}", m.channel.topic);
        }
        match m.channel.topic.as_str() {
            "/pose" => poses.push((m.log_time, v)),
            "/ranges" => {
                assert_eq!(m.log_time, times_ns[scans]);
                scans += 1;
            }
            _ => {}
        }
    }
    assert_eq!(scans as u64, n);
    assert_eq!(poses.len(), ticks.len());
    for ((ns, pose), tick) in poses.iter().zip(&ticks) {
        let at = (tick["time_s"].as_f64().unwrap() * 1e9).round() as u64;
        assert_eq!(*ns, at);
        let p = &pose["pose"]["position"];
        assert_eq!(p["x"], tick["true_pose"]["x_m"]);
        assert_eq!(p["y"], tick["true_pose"]["y_m"]);
        let q = &pose["pose"]["orientation"];
        let yaw = 2.0 * q["z"].as_f64().unwrap().atan2(q["w"].as_f64().unwrap());
        let theta = tick["true_pose"]["theta_rad"].as_f64().unwrap();
        assert!((yaw - theta).abs() < 1e-9, "{yaw} vs {theta}");
    }

    // The same run, the same bytes.
    let again = dir.join(format!("{name}-again.mcap"));
    assert!(
        replay(results, run, &["--mcap", again.to_str().unwrap()])
            .status
            .success()
    );
    assert!(
        std::fs::read(&again).unwrap() == bytes,
        "two exports of {run} differ"
    );
    events
}
