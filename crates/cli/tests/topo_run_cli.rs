//! `petrinav topo explore` and `topo go`, run as a user would: the ring
//! robot explores the shipped office and writes a map that `topo plan`
//! reads, drives a route on it, the same seed gives the same map, and bad
//! input is a clear error with a non-zero exit code.

use std::path::PathBuf;
use std::process::{Command, Output};

use serde_json::Value;

fn petrinav(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_petrinav"))
        .args(args)
        .output()
        .expect("the petrinav binary runs")
}

fn fresh(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("topo_run_{name}"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

#[test]
fn explore_writes_a_map_that_plans_and_drives() {
    let dir = fresh("explore");
    let map = dir.join("office.fpn.json");
    let picture = dir.join("office.png");
    let m = map.to_str().unwrap();
    let o = petrinav(&[
        "topo",
        "explore",
        "office",
        "--time",
        "240",
        "--seed",
        "1",
        "-o",
        m,
        "--picture",
        picture.to_str().unwrap(),
        "--json",
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    for key in [
        "places",
        "transitions",
        "stops",
        "strongly_connected",
        "recognition",
        "odometry_error_m",
    ] {
        assert!(v.get(key).is_some(), "no `{key}` in {v}");
    }
    assert!(v["places"].as_u64().unwrap() >= 3);
    assert!(picture.metadata().unwrap().len() > 1000);
    // The same seed, the same map.
    let again = dir.join("again.fpn.json");
    let o = petrinav(&[
        "topo",
        "explore",
        "office",
        "--time",
        "240",
        "--seed",
        "1",
        "-o",
        again.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert_eq!(std::fs::read(&map).unwrap(), std::fs::read(&again).unwrap());
    // A route on it: an outcome with stable keys, exit 0 whatever it is.
    let o = petrinav(&[
        "topo",
        "go",
        "office",
        m,
        "--from",
        "p1",
        "--to",
        "p2",
        "--time-limit",
        "120",
        "--json",
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    let outcome = v["outcome"].as_str().unwrap();
    assert!(
        ["goal", "wrong_place", "time_limit", "gave_up"].contains(&outcome),
        "{outcome}"
    );
    for key in [
        "time_s",
        "path_m",
        "final_distance_m",
        "planned",
        "legs",
        "replans",
    ] {
        assert!(v.get(key).is_some(), "no `{key}` in {v}");
    }
}

#[test]
fn bad_input_is_a_clear_error() {
    let dir = fresh("bad");
    let map = dir.join("m.fpn.json");
    let m = map.to_str().unwrap();
    // A world from a file needs a start; a start in a wall is refused.
    let world = dir.join("room.toml");
    std::fs::write(
        &world,
        "[world]\nwidth_m = 4.0\nheight_m = 3.0\nresolution_m = 0.05\nwalls = true\n",
    )
    .unwrap();
    let w = world.to_str().unwrap();
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (vec!["topo", "explore", w, "-o", m], "--start"),
        (vec!["topo", "explore", w, "--start", "0,0,0", "-o", m], "start"),
        (
            vec!["topo", "explore", "office", "--time", "-5", "-o", m],
            "--time",
        ),
        (
            vec!["topo", "explore", "office", "--time", "NaN", "-o", m],
            "--time",
        ),
        (vec!["topo", "explore", "nowhere.toml", "-o", m], "nowhere.toml"),
        (
            vec![
                "topo",
                "go",
                "office",
                "missing.fpn.json",
                "--from",
                "p1",
                "--to",
                "p2",
            ],
            "missing.fpn.json",
        ),
    ];
    for (args, needle) in cases {
        let o = petrinav(&args);
        let err = text(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
        assert!(
            err.contains(needle),
            "{args:?}: `{err}` does not mention {needle}"
        );
        assert!(!err.contains("panicked"), "{args:?}: {err}");
    }
    // Unknown places on a real map.
    let o = petrinav(&["topo", "explore", "office", "--time", "120", "-o", m]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let o = petrinav(&["topo", "go", "office", m, "--from", "p1", "--to", "nowhere"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(text(&o.stderr).contains("nowhere"), "{}", text(&o.stderr));
    // A map from another world: the start place fits nowhere near.
    let tiny = dir.join("tiny.toml");
    std::fs::write(
        &tiny,
        "[world]\nwidth_m = 0.5\nheight_m = 0.5\nresolution_m = 0.05\nwalls = true\n",
    )
    .unwrap();
    let o = petrinav(&[
        "topo",
        "go",
        tiny.to_str().unwrap(),
        m,
        "--from",
        "p1",
        "--to",
        "p2",
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(text(&o.stderr).contains("fits nowhere"), "{}", text(&o.stderr));
}
