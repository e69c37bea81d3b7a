//! `petrinav sim drive`, run as a user would.

use std::path::PathBuf;
use std::process::Command;

fn petrinav(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_petrinav"))
        .args(args)
        .output()
        .expect("the petrinav binary runs")
}

/// Writes the test world under a name of its own (tests run in parallel).
fn world(name: &str) -> PathBuf {
    let path = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("drive_world_{name}.toml"));
    std::fs::write(
        &path,
        "[world]\nwidth_m = 6.0\nheight_m = 4.0\nresolution_m = 0.05\nwalls = true\n\
         [[world.rect]]\nx = 3.0\ny = 1.0\nw = 0.5\nh = 2.0\n",
    )
    .unwrap();
    path
}

#[test]
fn a_scripted_drive_is_drawn_and_reported() {
    let w = world("drawn");
    let png = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("drive.png");
    let out = petrinav(&[
        "sim",
        "drive",
        w.to_str().unwrap(),
        "--start",
        "1,2,0",
        "--commands",
        "0.3,0,4; 0,0.8,2; 0.3,0,2",
        "-o",
        png.to_str().unwrap(),
        "--json",
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let r = &v["result"];
    assert_eq!(r["outcome"], "time_limit");
    // 1.2 m straight, a turn on the spot, 0.6 m: about 1.8 m of path.
    let len = r["path_length_m"].as_f64().unwrap();
    assert!((len - 1.8).abs() < 0.1, "{len}");
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[1..4], b"PNG");
    // Same seed, same run.
    let again = petrinav(&[
        "sim",
        "drive",
        w.to_str().unwrap(),
        "--start",
        "1,2,0",
        "--commands",
        "0.3,0,4; 0,0.8,2; 0.3,0,2",
        "--json",
    ]);
    assert_eq!(out.stdout, again.stdout);
}

#[test]
fn driving_into_the_obstacle_ends_in_a_collision() {
    let w = world("collision");
    let out = petrinav(&[
        "sim",
        "drive",
        w.to_str().unwrap(),
        "--start",
        "1,2,0",
        "--commands",
        "0.3,0,20",
        "--json",
    ]);
    assert!(out.status.success());
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["result"]["outcome"], "collision");
}

#[test]
fn bad_geometry_and_scripts_are_clear_errors() {
    let w = world("errors");
    for (args, needle) in [
        (
            vec!["--start", "3.2,2,0", "--commands", "0.3,0,1"],
            "overlaps an obstacle",
        ),
        (vec!["--start", "1,2", "--commands", "0.3,0,1"], "--start"),
        (vec!["--start", "1,2,0", "--commands", "0.3,0"], "segment 1"),
        (vec!["--start", "1,2,0", "--commands", "0.3,0,-1"], "duration"),
        // Recorded step by step: 1e9 s had grown to 14 GB.
        (
            vec!["--start", "1,2,0", "--commands", "0,0,80000;0,0,7000"],
            "a day",
        ),
        (vec!["--start", "1,2,0"], "--commands"),
    ] {
        let mut all = vec!["sim", "drive", w.to_str().unwrap()];
        all.extend(args);
        let out = petrinav(&all);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{all:?}");
        assert_ne!(out.status.code(), Some(101), "{all:?} panicked: {err}");
        assert!(err.contains(needle), "{all:?}: {err}");
    }
}
