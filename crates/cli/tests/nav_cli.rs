//! `petrinav nav`, run as a user would: a leg on a real map with its JSON,
//! picture and trace; the same seed giving the same run; every kind of bad
//! input a clear error with a non-zero exit code.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn petrinav(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_petrinav"))
        .args(args)
        .output()
        .expect("the petrinav binary runs")
}

fn repo(path: &str) -> String {
    format!("{}/../../{path}", env!("CARGO_MANIFEST_DIR"))
}

fn fresh(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("nav_{name}"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn b31() -> (String, String) {
    (
        repo("maps/building_31/building_31.yaml"),
        repo("maps/building_31/places.yaml"),
    )
}

fn go(extra: &[&str]) -> Output {
    let (map, places) = b31();
    let mut args = vec![
        "nav",
        "go",
        map.as_str(),
        "--goals",
        places.as_str(),
        "--from",
        "entrance",
        "--to",
        "west_corridor_south",
    ];
    args.extend_from_slice(extra);
    petrinav(&args)
}

#[test]
fn a_leg_reaches_its_place_with_json_picture_and_trace() {
    let dir = fresh("leg");
    let (png, trace) = (dir.join("leg.png"), dir.join("leg.jsonl"));
    let out = go(&[
        "--json",
        "-o",
        png.to_str().unwrap(),
        "--trace",
        trace.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let leg: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    for key in [
        "from",
        "to",
        "outcome",
        "time_s",
        "path_m",
        "final_error_m",
        "localization",
        "planner",
    ] {
        assert!(leg.get(key).is_some(), "key {key} in {leg}");
    }
    for key in ["mean_error_m", "max_error_m", "warnings", "time_in_warning_s"] {
        assert!(leg["localization"].get(key).is_some(), "localization.{key}");
    }
    for key in ["abnormal_episodes", "time_abnormal_s"] {
        assert!(leg["planner"].get(key).is_some(), "planner.{key}");
    }
    assert_eq!(leg["outcome"], "reached");
    assert!(leg["final_error_m"].as_f64().unwrap() <= 0.3);
    assert!(leg["localization"]["max_error_m"].as_f64().unwrap() < 0.3);
    // 5.6 m between the places: the path is about that long.
    let path = leg["path_m"].as_f64().unwrap();
    assert!((5.0..7.0).contains(&path), "{path}");
    let image = image::open(&png).expect("a PNG picture");
    assert!(image.width() > 200 && image.height() > 200);
    let ticks = std::fs::read_to_string(&trace).unwrap();
    let first: serde_json::Value = serde_json::from_str(ticks.lines().next().unwrap()).unwrap();
    for key in [
        "time_s",
        "true_pose",
        "estimate",
        "state",
        "events",
        "command",
        "notes",
    ] {
        assert!(first.get(key).is_some(), "trace key {key}");
    }
    // The controller's notes: the localizer's, every tick.
    for line in ticks.lines() {
        let tick: serde_json::Value = serde_json::from_str(line).unwrap();
        let ess = tick["notes"]["effective_sample_size"].as_f64();
        assert!(ess.is_some_and(|n| n > 0.0), "notes in {tick}");
    }
    let n = ticks.lines().count() as f64;
    assert!(
        (n - leg["time_s"].as_f64().unwrap() / 0.1).abs() <= 1.0,
        "one line per tick"
    );
}

#[test]
fn a_leg_can_be_watched_in_a_viewer_page() {
    let dir = fresh("html");
    let html = dir.join("leg.html");
    let out = go(&["--behaviour", "contour", "--html", html.to_str().unwrap()]);
    assert!(out.status.success(), "{}", stderr(&out));
    let page = std::fs::read_to_string(&html).expect("the page is written");
    assert!(page.starts_with("<!DOCTYPE html>") || page.starts_with("<!doctype html>"));
    assert!(
        page.contains("entrance → west_corridor_south (seed 1)"),
        "the leg's title"
    );
    // A folder that does not exist is refused before the leg is run.
    let missing = dir.join("no/such/folder/leg.html");
    let out = go(&["--html", missing.to_str().unwrap()]);
    assert!(!out.status.success());
    assert!(stderr(&out).contains("there is no folder"), "{}", stderr(&out));
}

#[test]
fn the_same_seed_gives_the_same_leg_and_trace() {
    let dir = fresh("determinism");
    let run = |seed: &str, name: &str| {
        let trace = dir.join(name);
        let out = go(&[
            "--json",
            "--people",
            "10",
            "--seed",
            seed,
            "--trace",
            trace.to_str().unwrap(),
        ]);
        assert!(out.status.success(), "{}", stderr(&out));
        (out.stdout, std::fs::read(trace).unwrap())
    };
    let a = run("7", "a.jsonl");
    let b = run("7", "b.jsonl");
    let c = run("8", "c.jsonl");
    assert_eq!(a, b, "same seed, same leg and trace");
    assert_ne!(a.1, c.1, "another seed, another run");
}

#[test]
fn a_tour_reports_every_leg_and_a_summary() {
    let dir = fresh("tour");
    let places = dir.join("places.yaml");
    std::fs::write(
        &places,
        "# three places along the west corridor\nentrance: [-17.2, -4.0, 1.5708]\nwest_corridor_south: [-17.1, 1.6, 1.5708]\nwest_corridor_middle: [-17.35, 8.3, 1.5708]\n",
    )
    .unwrap();
    let (map, _) = b31();
    let out = petrinav(&["nav", "tour", &map, "--goals", places.to_str().unwrap(), "--json"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let lines: Vec<serde_json::Value> = String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(lines.len(), 3, "two legs and a summary");
    assert_eq!(lines[0]["from"], "entrance");
    assert_eq!(lines[1]["to"], "west_corridor_middle");
    assert_eq!(lines[2]["summary"]["legs"], 2);
    assert_eq!(lines[2]["summary"]["reached"], 2);
}

/// A 2 m × 2 m map at 0.05 m: walls round the border, free inside, an
/// unknown (grey) square at its upper right; or everything occupied.
fn small_map(dir: &Path, all_occupied: bool) -> String {
    let n = 40;
    let mut pixels = Vec::with_capacity(n * n);
    for row in 0..n {
        for col in 0..n {
            let border = row == 0 || col == 0 || row == n - 1 || col == n - 1;
            let grey = (5..12).contains(&row) && (28..35).contains(&col);
            pixels.push(if all_occupied || border {
                0u8
            } else if grey {
                205
            } else {
                254
            });
        }
    }
    let mut pgm = format!("P5\n{n} {n}\n255\n").into_bytes();
    pgm.extend(pixels);
    let name = if all_occupied { "full" } else { "small" };
    std::fs::write(dir.join(format!("{name}.pgm")), pgm).unwrap();
    let yaml = dir.join(format!("{name}.yaml"));
    std::fs::write(
        &yaml,
        format!("image: {name}.pgm\nresolution: 0.05\norigin: [0.0, 0.0, 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n"),
    )
    .unwrap();
    yaml.display().to_string()
}

/// Runs petrinav with `args`, which must fail with an error message (no
/// panic) that contains each of `expect`.
fn fails(args: &[&str], expect: &[&str]) {
    let out = petrinav(args);
    assert!(!out.status.success(), "{args:?} should fail");
    let err = stderr(&out);
    assert!(err.starts_with("error:"), "{args:?}: {err}");
    for e in expect {
        assert!(err.contains(e), "{args:?}: `{e}` not in: {err}");
    }
    assert!(!err.contains("panicked"), "{err}");
}

#[test]
fn bad_places_are_a_clear_error() {
    let dir = fresh("bad");
    let (map, places) = b31();
    // A malformed places file names its line.
    let bad_places = dir.join("bad.yaml");
    std::fs::write(&bad_places, "a: [1, 2, 0]\nb: [1, two, 0]\n").unwrap();
    let bp = bad_places.to_str().unwrap();
    fails(
        &["nav", "go", &map, "--goals", bp, "--from", "a", "--to", "b"],
        &["bad.yaml:2", "`two`"],
    );
    // An unknown place lists the known ones.
    fails(
        &[
            "nav",
            "go",
            &map,
            "--goals",
            &places,
            "--from",
            "entrance",
            "--to",
            "cafeteria",
        ],
        &["no place `cafeteria`", "hall_north"],
    );
    // Names without a places file.
    fails(
        &["nav", "go", &map, "--from", "entrance", "--to", "1,1,0"],
        &["no --goals"],
    );
}

#[test]
fn places_off_the_free_space_are_a_clear_error() {
    let dir = fresh("bad_spaces");
    // A place in a wall, in unknown space, off the map; a start in a wall.
    let small = small_map(&dir, false);
    let walls = dir.join("walls.yaml");
    std::fs::write(
        &walls,
        "ok: [0.6, 0.6, 0]\nwall: [0.02, 1.0, 0]\nunknown: [1.55, 1.55, 0]\noff: [5.0, 5.0, 0]\n",
    )
    .unwrap();
    let w = walls.to_str().unwrap();
    fails(
        &["nav", "go", &small, "--goals", w, "--from", "ok", "--to", "wall"],
        &["`wall`", "inside an obstacle"],
    );
    fails(
        &[
            "nav", "go", &small, "--goals", w, "--from", "ok", "--to", "unknown",
        ],
        &["`unknown`", "unknown"],
    );
    fails(
        &["nav", "go", &small, "--goals", w, "--from", "ok", "--to", "off"],
        &["`off`", "outside the map"],
    );
    fails(
        &["nav", "go", &small, "--from", "0.02,0.02,0", "--to", "ok"],
        &["no --goals"],
    );
    fails(
        &[
            "nav",
            "go",
            &small,
            "--goals",
            w,
            "--from",
            "0.02,1.0,0",
            "--to",
            "ok",
        ],
        &["inside an obstacle"],
    );
    fails(
        &["nav", "tour", &small, "--goals", w],
        &["`wall`", "`unknown`", "`off`"],
    );
    // A map without free space.
    let full = small_map(&dir, true);
    fails(
        &["nav", "go", &full, "--from", "1,1,0", "--to", "1.2,1,0"],
        &["no free cell"],
    );
}

#[test]
fn impossible_numbers_and_tours_are_a_clear_error() {
    let dir = fresh("bad_numbers");
    let (map, places) = b31();
    // Impossible numbers.
    fails(
        &[
            "nav",
            "go",
            &map,
            "--goals",
            &places,
            "--from",
            "entrance",
            "--to",
            "hall_north",
            "--time-limit",
            "-5",
        ],
        &["--time-limit"],
    );
    fails(
        &[
            "nav",
            "go",
            &map,
            "--goals",
            &places,
            "--from",
            "entrance",
            "--to",
            "hall_north",
            "--time-limit",
            "NaN",
        ],
        &["--time-limit"],
    );
    fails(
        &[
            "nav",
            "go",
            &map,
            "--goals",
            &places,
            "--from",
            "nan,1,0",
            "--to",
            "hall_north",
        ],
        &["finite"],
    );
    fails(
        &[
            "nav",
            "go",
            &map,
            "--goals",
            &places,
            "--from",
            "entrance",
            "--to",
            "hall_north",
            "--people",
            "100000",
        ],
        &["people"],
    );
    // A tour of one place.
    let one = dir.join("one.yaml");
    std::fs::write(&one, "only: [-17.2, -4.0, 0]\n").unwrap();
    fails(
        &["nav", "tour", &map, "--goals", one.to_str().unwrap()],
        &["at least two places"],
    );
}
