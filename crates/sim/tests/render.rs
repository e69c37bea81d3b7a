//! Pictures of the real map with every kind of overlay.

use std::f64::consts::PI;
use std::path::PathBuf;

use robot::{Pose, Vec2};
use sim::render::{MarkerKind, Picture};
use sim::{cast_many, map_server};

#[test]
fn building_31_with_a_scan_a_path_and_people() {
    let m = map_server::load(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../maps/building_31/building_31.yaml"
    ))
    .unwrap();
    let g = &m.grid;
    // A walk down the left corridor (x ≈ −16 m), then right along the
    // bottom corridor.
    let path: Vec<Pose> = (0..=40)
        .map(|k| {
            let t = k as f64 / 40.0;
            if t < 0.5 {
                Pose::new(-16.6, 15.0 - 2.0 * t * 20.0, -PI / 2.0)
            } else {
                Pose::new(-16.6 + (t - 0.5) * 2.0 * 8.0, -5.0, 0.0)
            }
        })
        .collect();
    let labels: Vec<&str> = (0..path.len())
        .map(|k| if k % 14 < 9 { "automove" } else { "contour" })
        .collect();
    let robot = path[30];
    let angles: Vec<f64> = (0..181)
        .map(|k| robot.theta_rad - PI / 2.0 + k as f64 * PI / 180.0)
        .collect();
    let mut ranges = Vec::new();
    cast_many(g, robot.position(), &angles, 8.0, &mut ranges);
    let mut p = Picture::new(g);
    p.scale(30.0);
    for (a, r) in angles.iter().zip(&ranges).step_by(4) {
        let d = r.unwrap_or(8.0);
        p.ray(
            robot.position(),
            robot.position() + Vec2::new(a.cos(), a.sin()).scale(d),
        );
    }
    p.trajectory(&path, Some(&labels))
        .robot(robot, 0.35)
        .person(Vec2::new(-12.0, -4.6), 0.25)
        .person(Vec2::new(-11.0, -5.4), 0.25)
        .marker(path[0].position(), MarkerKind::Start)
        .marker(path[40].position(), MarkerKind::Goal)
        .marker(Vec2::new(-16.6, 0.0), MarkerKind::Point)
        .text(Vec2::new(-15.5, 10.0), "run 1: 12.5 s");
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR"));
    p.save(dir.join("building_31_overlays.png")).unwrap();
    p.save(dir.join("building_31_overlays.svg")).unwrap();
    let img = image::open(dir.join("building_31_overlays.png")).unwrap();
    assert_eq!((img.width(), img.height()), (1040, 972)); // 34.65 × 32.4 m at 30 px/m
    let svg = std::fs::read_to_string(dir.join("building_31_overlays.svg")).unwrap();
    assert!(svg.len() < 60_000, "{} bytes", svg.len());
    assert!(svg.contains(">automove<") && svg.contains(">contour<"));
    // Deterministic.
    let again = p.to_png().unwrap();
    assert_eq!(again.as_raw(), img.to_rgb8().as_raw());
}
