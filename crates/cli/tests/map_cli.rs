//! The `petrinav map` commands, run as a user would.

use std::path::PathBuf;
use std::process::{Command, Output};

use serde_json::Value;

fn petrinav(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_petrinav"))
        .args(args)
        .output()
        .expect("the petrinav binary runs")
}

fn map(name: &str) -> String {
    format!("{}/../../maps/{name}/{name}.yaml", env!("CARGO_MANIFEST_DIR"))
}

fn tmp(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name)
}

fn succeeds(args: &[&str]) -> String {
    let out = petrinav(args);
    assert!(
        out.status.success(),
        "{args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

/// Runs a command that must fail; returns its error message.
fn fails(args: &[&str]) -> String {
    let out = petrinav(args);
    assert!(!out.status.success(), "{args:?} should fail");
    assert_ne!(out.status.code(), Some(101), "{args:?} panicked");
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(err.starts_with("error: "), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    err
}

#[test]
fn info_describes_building_31() {
    let text = succeeds(&["map", "info", &map("building_31")]);
    for line in [
        "size        693 × 648 cells\n",
        "resolution  0.05 m/cell\n",
        "extent      34.65 × 32.4 m\n",
        "origin      x -26 m, y -11 m, yaw 0 rad\n",
        "free        431063 cells, 1077.66 m²\n",
        "occupied    17553 cells\n",
        "unknown     448 cells\n",
        "mode        trinary (negate 0, occupied > 0.65, free < 0.196)\n",
    ] {
        assert!(text.contains(line), "missing {line:?} in\n{text}");
    }
}

#[test]
fn info_json_has_stable_keys() {
    let v: Value = serde_json::from_str(&succeeds(&["map", "info", &map("levine"), "--json"])).unwrap();
    assert_eq!(v["width_cells"], 2048);
    assert_eq!(v["height_cells"], 2048);
    assert_eq!(v["resolution_m"], 0.05);
    assert_eq!(v["origin"]["x_m"], -51.224998);
    assert_eq!(v["origin"]["yaw_rad"], 0.0);
    assert_eq!(v["free_cells"], 4_187_468);
    assert_eq!(v["occupied_cells"], 6_836);
    assert_eq!(v["unknown_cells"], 0);
    assert!((v["free_area_m2"].as_f64().unwrap() - 10_468.67).abs() < 1e-6);
    assert_eq!(v["map_server"]["mode"], "trinary");
    assert_eq!(v["map_server"]["negate"], false);
}

#[test]
fn render_building_31_as_png_and_svg() {
    let png = tmp("b31.png");
    succeeds(&["map", "render", &map("building_31"), "-o", png.to_str().unwrap()]);
    let img = image::open(&png).unwrap();
    assert_eq!((img.width(), img.height()), (693, 648));
    // Same pixels as the original image (it is a clean trinary map): black
    // walls, white free space, grey unknown.
    let original = image::open(map("building_31").replace(".yaml", ".png"))
        .unwrap()
        .to_luma8();
    let drawn = img.to_luma8();
    let differ = original.pixels().zip(drawn.pixels()).filter(|(a, b)| {
        let expect = match a.0[0] {
            0 | 64 => 0,
            255 => 255,
            _ => 205,
        };
        b.0[0] != expect
    });
    assert_eq!(differ.count(), 0);
    let scaled = tmp("b31x2.png");
    succeeds(&[
        "map",
        "render",
        &map("building_31"),
        "-o",
        scaled.to_str().unwrap(),
        "--scale",
        "40",
    ]);
    assert_eq!(image::image_dimensions(&scaled).unwrap(), (1386, 1296));
    let svg = tmp("b31.svg");
    succeeds(&["map", "render", &map("building_31"), "-o", svg.to_str().unwrap()]);
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(text.starts_with("<svg") && text.contains("data:image/png;base64,"));
    assert!(text.len() < 40_000, "{} bytes", text.len());
}

#[test]
fn toml_worlds_render_and_describe() {
    let world = tmp("field.toml");
    std::fs::write(
        &world,
        "[world]\nwidth_m = 4.0\nheight_m = 3.0\nresolution_m = 0.1\nwalls = true\n\
         [[world.rect]]\nx = 1.0\ny = 1.0\nw = 1.0\nh = 1.0\n[robot]\nradius_m = 0.2\n",
    )
    .unwrap();
    let v: Value =
        serde_json::from_str(&succeeds(&["map", "info", world.to_str().unwrap(), "--json"])).unwrap();
    assert_eq!(
        (v["width_cells"].as_u64(), v["height_cells"].as_u64()),
        (Some(40), Some(30))
    );
    assert_eq!(v["occupied_cells"], 40 * 30 - 38 * 28 + 100);
    assert!(v.get("map_server").is_none());
    let png = tmp("field.png");
    succeeds(&[
        "map",
        "render",
        world.to_str().unwrap(),
        "-o",
        png.to_str().unwrap(),
    ]);
    assert_eq!(image::image_dimensions(&png).unwrap(), (600, 450));
}

#[test]
fn bad_inputs_give_messages() {
    let err = fails(&["map", "info", "/nonexistent/map.yaml"]);
    assert!(err.contains("/nonexistent/map.yaml"), "{err}");
    let err = fails(&["map", "info", "map.gif"]);
    assert!(err.contains("unknown map format"), "{err}");
    let bad = tmp("bad.yaml");
    std::fs::write(
        &bad,
        "image: x.pgm\nresolution: -1\norigin: [0, 0, 0]\nnegate: 0\n",
    )
    .unwrap();
    let err = fails(&["map", "info", bad.to_str().unwrap()]);
    assert!(err.contains("resolution must be between"), "{err}");
    let world = tmp("bad_world.toml");
    std::fs::write(
        &world,
        "[world]\nwidth_m = 4.0\nheight_m = 3.0\ncolour = \"red\"\n",
    )
    .unwrap();
    let err = fails(&["map", "info", world.to_str().unwrap()]);
    assert!(err.contains("unknown field `colour`"), "{err}");
    let err = fails(&[
        "map",
        "render",
        &map("building_31"),
        "-o",
        tmp("x.jpg").to_str().unwrap(),
    ]);
    assert!(err.contains("use .png or .svg"), "{err}");
    let err = fails(&[
        "map",
        "render",
        &map("building_31"),
        "-o",
        tmp("x.png").to_str().unwrap(),
        "--scale=-3",
    ]);
    assert!(err.contains("scale"), "{err}");
}
