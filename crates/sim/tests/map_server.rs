//! Loading and saving ROS map_server maps: the two real building maps, every
//! image kind and mode, and every error a user file can cause.

use std::path::{Path, PathBuf};

use robot::{Pose, Vec2};
use sim::map_server::{self, MapMode};
use sim::{Cell, CellIndex, Error, OccupancyGrid};

fn data(path: &str) -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../maps")).join(path)
}

/// A fresh folder for one test's files.
fn folder(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
        .join("map_server")
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn write(dir: &Path, name: &str, bytes: impl AsRef<[u8]>) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    path
}

const YAML: &str = "image: map.pgm\nresolution: 0.1\norigin: [1.0, 2.0, 0.0]\nnegate: 0\n\
                    occupied_thresh: 0.65\nfree_thresh: 0.196\n";

/// A map whose YAML is `yaml` and whose image (named `map.pgm` or as the
/// YAML says) holds `image`; returns the load result.
fn load_with(
    name: &str,
    yaml: &str,
    image_name: &str,
    image: &[u8],
) -> sim::Result<map_server::MapServerMap> {
    let dir = folder(name);
    write(&dir, image_name, image);
    map_server::load(write(&dir, "map.yaml", yaml))
}

fn message(r: sim::Result<map_server::MapServerMap>) -> String {
    match r {
        Ok(_) => panic!("should fail"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn building_31_loads_with_its_size_origin_and_counts() {
    let m = map_server::load(data("building_31/building_31.yaml")).unwrap();
    let g = &m.grid;
    assert_eq!((g.width(), g.height()), (693, 648));
    assert_eq!(g.resolution_m(), 0.05);
    assert_eq!(g.origin(), Pose::new(-26.0, -11.0, 0.0));
    assert_eq!(m.yaml.mode, MapMode::Trinary);
    // Pixel values 0 and 64 are occupied, 128 and 191 unknown, 255 free;
    // the counts agree with an independent decoder (zlib + PNG filters in
    // Python): free 431063, occupied 17353 + 197, unknown 210 + 238.
    let n = g.counts();
    assert_eq!((n.free, n.occupied, n.unknown), (431_063, 17_553, 448));
    assert_eq!(m.occupancy.iter().filter(|&&v| v == 100).count(), 17_553);
    assert!((g.free_area_m2() - 431_063.0 * 0.0025).abs() < 1e-6);
    // Image row 0 is the top: its first black pixel, column 50, is cell
    // (50, 647), world (−26 + 50.5 · 0.05, −11 + 647.5 · 0.05).
    assert_eq!(g.get(CellIndex { i: 50, j: 647 }), Cell::Occupied);
    assert!(g.blocked_at(Vec2::new(-26.0 + 50.5 * 0.05, -11.0 + 647.5 * 0.05)));
    assert_eq!(g.get(CellIndex { i: 0, j: 647 }), Cell::Free);
    assert_eq!(m.image_path, data("building_31/building_31.png"));
}

#[test]
fn levine_loads_with_its_size_origin_and_counts() {
    let m = map_server::load(data("levine/levine.yaml")).unwrap();
    let g = &m.grid;
    assert_eq!((g.width(), g.height()), (2048, 2048));
    assert_eq!(g.resolution_m(), 0.05);
    assert_eq!(g.origin(), Pose::new(-51.224998, -51.224998, 0.0));
    // The grey background (216: p = 0.153) is free; checked in Python too.
    let n = g.counts();
    assert_eq!((n.free, n.occupied, n.unknown), (4_187_468, 6_836, 0));
    // First black pixel from the top: row 737, column 697.
    assert_eq!(
        g.get(CellIndex {
            i: 697,
            j: 2047 - 737
        }),
        Cell::Occupied
    );
    assert_eq!(
        g.get(CellIndex {
            i: 696,
            j: 2047 - 737
        }),
        Cell::Free
    );
}

#[test]
fn pgm_binary_and_ascii_with_thresholds_and_negate() {
    // One row of values across the thresholds: 255 → p 0 (free), 205 →
    // p 0.196 (unknown: not below 0.196), 206 → p 0.192 (free), 89 → p 0.651
    // (occupied), 90 → p 0.647 (unknown), 0 → occupied.
    let values = [255u8, 205, 206, 89, 90, 0];
    let mut p5 = b"P5\n# a comment\n6 1\n255\n".to_vec();
    p5.extend_from_slice(&values);
    let want = [0i8, -1, 0, 100, -1, 100];
    let m = load_with("p5", YAML, "map.pgm", &p5).unwrap();
    assert_eq!(m.occupancy, want);
    assert_eq!(m.grid.get(CellIndex { i: 0, j: 0 }), Cell::Free);
    assert_eq!(m.grid.get(CellIndex { i: 1, j: 0 }), Cell::Unknown);
    assert_eq!(m.grid.get(CellIndex { i: 3, j: 0 }), Cell::Occupied);
    let p2 = "P2\n6 1\n# comment\n255\n255 205 206\n89 90 0\n";
    assert_eq!(
        load_with("p2", YAML, "map.pgm", p2.as_bytes()).unwrap().occupancy,
        want
    );
    // Negate: p = value / 255.
    let negated = YAML.replace("negate: 0", "negate: 1");
    assert_eq!(
        load_with("negate", &negated, "map.pgm", &p5).unwrap().occupancy,
        [100, 100, 100, -1, -1, 0]
    );
    // maxval 15 scales as SDL_image does: 15 → 255, 7 → 119 (p 0.533).
    let m = load_with("maxval", YAML, "map.pgm", b"P2 2 1 15 15 7").unwrap();
    assert_eq!(m.occupancy, [0, -1]);
}

#[test]
fn image_rows_are_flipped_so_row_zero_is_the_bottom() {
    // Two rows: top row black, bottom row white.
    let m = load_with("flip", YAML, "map.pgm", b"P2 2 2 255 0 0 255 255").unwrap();
    let g = &m.grid;
    assert_eq!(g.get(CellIndex { i: 0, j: 1 }), Cell::Occupied);
    assert_eq!(g.get(CellIndex { i: 1, j: 0 }), Cell::Free);
    assert_eq!(m.occupancy, [0, 0, 100, 100]);
    // Origin (1, 2): the top-left cell's centre is at (1.05, 2.15).
    assert!(g.blocked_at(Vec2::new(1.05, 2.15)));
    assert!(!g.blocked_at(Vec2::new(1.05, 2.05)));
}

fn png(dir: &Path, name: &str, img: image::DynamicImage) -> PathBuf {
    let path = dir.join(name);
    img.save_with_format(&path, image::ImageFormat::Png).unwrap();
    path
}

#[test]
fn png_colour_and_alpha_follow_map_server() {
    use image::{DynamicImage, ImageBuffer, LumaA, Rgb, Rgba};
    let dir = folder("png_colour");
    let yaml = |mode: &str| YAML.replace("map.pgm", "map.png") + &format!("mode: {mode}\n");
    // RGB: the mean of the channels. (255, 255, 0) → 170 → p 0.333: unknown;
    // (255, 255, 200) → 236.7 → p 0.072: free; (30, 30, 30) → occupied.
    let rgb = ImageBuffer::from_fn(3, 1, |x, _| {
        Rgb([[255, 255, 0], [255, 255, 200], [30, 30, 30]][x as usize])
    });
    png(&dir, "map.png", DynamicImage::ImageRgb8(rgb));
    let m = map_server::load(write(&dir, "map.yaml", yaml("trinary"))).unwrap();
    assert_eq!(m.occupancy, [-1, 0, 100]);
    // RGBA in trinary mode averages alpha in: transparent white (255, 255,
    // 255, 0) → 191.25 → p 0.25: unknown; opaque white: free.
    let rgba = ImageBuffer::from_fn(2, 1, |x, _| {
        Rgba([[255, 255, 255, 0], [255, 255, 255, 255]][x as usize])
    });
    png(&dir, "map.png", DynamicImage::ImageRgba8(rgba));
    let m = map_server::load(write(&dir, "map.yaml", yaml("trinary"))).unwrap();
    assert_eq!(m.occupancy, [-1, 0]);
    // In scale mode alpha is left out of the mean: transparent white is free.
    let m = map_server::load(write(&dir, "map.yaml", yaml("scale"))).unwrap();
    assert_eq!(m.occupancy, [0, 0]);
    // Grey + alpha counts as RGBA with equal colours.
    let la = ImageBuffer::from_fn(1, 1, |_, _| LumaA([255u8, 0]));
    png(&dir, "map.png", DynamicImage::ImageLumaA8(la));
    let m = map_server::load(write(&dir, "map.yaml", yaml("trinary"))).unwrap();
    assert_eq!(m.occupancy, [-1]);
}

#[test]
fn scale_and_raw_modes() {
    let pgm = b"P2 4 1 255 255 128 0 100";
    // scale: 128 → p 0.498 → 1 + 98 · (0.498 − 0.196) / (0.65 − 0.196) = 66.2 → 66;
    // 100 → p 0.608 → 89.9 → 89.
    let scale = YAML.to_string() + "mode: scale\n";
    let m = load_with("scale", &scale, "map.pgm", pgm).unwrap();
    assert_eq!(m.occupancy, [0, 66, 100, 89]);
    assert_eq!(m.grid.get(CellIndex { i: 1, j: 0 }), Cell::Unknown);
    // raw: the value itself; 255 is −1 (unknown), 0 free, 100 occupied.
    let raw = YAML.to_string() + "mode: raw\n";
    let m = load_with("raw", &raw, "map.pgm", pgm).unwrap();
    assert_eq!(m.occupancy, [-1, -128, 0, 100]);
    let cells: Vec<Cell> = m.grid.cells().to_vec();
    assert_eq!(cells, [Cell::Unknown, Cell::Unknown, Cell::Free, Cell::Occupied]);
}

#[test]
fn save_and_load_round_trip() {
    let dir = folder("save");
    let mut g = OccupancyGrid::new(7, 5, 0.05, Pose::new(-1.5, 2.25, 0.5));
    g.set(CellIndex { i: 0, j: 0 }, Cell::Occupied);
    g.set(CellIndex { i: 6, j: 4 }, Cell::Unknown);
    g.set(CellIndex { i: 3, j: 2 }, Cell::Occupied);
    let image = map_server::save(&g, dir.join("saved.yaml")).unwrap();
    assert_eq!(image, dir.join("saved.pgm"));
    let back = map_server::load(dir.join("saved.yaml")).unwrap();
    assert_eq!(back.grid, g);
    let text = std::fs::read_to_string(dir.join("saved.yaml")).unwrap();
    assert!(text.contains("image: \"saved.pgm\""), "{text}");
    // The real map survives a round trip too.
    let m = map_server::load(data("building_31/building_31.yaml")).unwrap();
    map_server::save(&m.grid, dir.join("b31.yaml")).unwrap();
    assert_eq!(map_server::load(dir.join("b31.yaml")).unwrap().grid, m.grid);
}

#[test]
fn missing_files_name_the_path() {
    let dir = folder("missing");
    let yaml = write(&dir, "map.yaml", YAML);
    let e = map_server::load(&yaml).unwrap_err();
    assert!(matches!(e, Error::Io { .. }), "{e}");
    let msg = e.to_string();
    assert!(msg.contains(&dir.join("map.pgm").display().to_string()), "{msg}");
    let msg = map_server::load(dir.join("nope.yaml")).unwrap_err().to_string();
    assert!(msg.contains("nope.yaml"), "{msg}");
}

#[test]
fn bad_yaml_gives_the_line() {
    let text = "image: map.pgm\nresolution: 0.1\norigin: [1.0, 2.0, 0.0\nnegate: 0\n";
    let msg = map_server::parse_yaml(text, "bad.yaml").unwrap_err().to_string();
    // The unclosed list is noticed on the next line.
    assert!(
        msg.starts_with("bad.yaml, line 4 column 7: invalid YAML"),
        "{msg}"
    );
    assert!(msg.contains("invalid YAML"), "{msg}");
    let msg = map_server::parse_yaml("", "empty.yaml").unwrap_err().to_string();
    assert!(msg.contains("empty"), "{msg}");
    let msg = map_server::parse_yaml("- 1\n- 2\n", "list.yaml")
        .unwrap_err()
        .to_string();
    assert!(msg.contains("mapping"), "{msg}");
}

#[test]
fn missing_and_invalid_keys_are_named() {
    for key in [
        "image",
        "resolution",
        "origin",
        "negate",
        "occupied_thresh",
        "free_thresh",
    ] {
        let text: String = YAML
            .lines()
            .filter(|l| !l.starts_with(key))
            .map(|l| format!("{l}\n"))
            .collect();
        let msg = map_server::parse_yaml(&text, "m.yaml").unwrap_err().to_string();
        assert!(msg.contains(&format!("missing key `{key}`")), "{key}: {msg}");
    }
    for (from, to, key) in [
        ("resolution: 0.1", "resolution: fine", "resolution"),
        ("resolution: 0.1", "resolution: .nan", "resolution"),
        ("origin: [1.0, 2.0, 0.0]", "origin: [1.0, 2.0]", "origin"),
        ("origin: [1.0, 2.0, 0.0]", "origin: [1.0, x, 0.0]", "origin"),
        ("negate: 0", "negate: maybe", "negate"),
        ("image: map.pgm", "image: [a]", "image"),
        ("free_thresh: 0.196", "free_thresh: low", "free_thresh"),
    ] {
        let msg = map_server::parse_yaml(&YAML.replace(from, to), "m.yaml")
            .unwrap_err()
            .to_string();
        assert!(msg.contains(&format!("key `{key}`")), "{to}: {msg}");
    }
    let msg = map_server::parse_yaml(&(YAML.to_string() + "mode: fancy\n"), "m.yaml")
        .unwrap_err()
        .to_string();
    assert!(msg.contains("key `mode`") && msg.contains("fancy"), "{msg}");
    // Accepted variants: integers for reals, booleans for negate, quoted numbers.
    let ok = YAML
        .replace("resolution: 0.1", "resolution: \"0.1\"")
        .replace("origin: [1.0, 2.0, 0.0]", "origin: [1, 2, 0]")
        .replace("negate: 0", "negate: true");
    let y = map_server::parse_yaml(&ok, "m.yaml").unwrap();
    assert_eq!(
        (y.resolution_m, y.origin, y.negate),
        (0.1, Pose::new(1.0, 2.0, 0.0), true)
    );
}

#[test]
fn zero_or_negative_resolution_is_refused() {
    for r in ["0", "-0.05", "0.0"] {
        let e = map_server::parse_yaml(&YAML.replace("0.1", r), "m.yaml").unwrap_err();
        assert!(matches!(e, Error::InvalidValue { .. }), "{e}");
        assert!(e.to_string().contains("resolution must be between"), "{e}");
    }
}

#[test]
fn thresholds_out_of_range_are_refused() {
    for (from, to, name) in [
        ("occupied_thresh: 0.65", "occupied_thresh: 1.5", "occupied_thresh"),
        ("free_thresh: 0.196", "free_thresh: -0.1", "free_thresh"),
    ] {
        let msg = map_server::parse_yaml(&YAML.replace(from, to), "m.yaml")
            .unwrap_err()
            .to_string();
        assert!(msg.contains(name) && msg.contains("between 0 and 1"), "{msg}");
    }
    let msg = map_server::parse_yaml(&YAML.replace("0.196", "0.7"), "m.yaml")
        .unwrap_err()
        .to_string();
    assert!(
        msg.contains("free_thresh (0.7) is above occupied_thresh (0.65)"),
        "{msg}"
    );
}

#[test]
fn unsupported_pgm_variants_are_refused() {
    let mut p16 = b"P5 2 1 65535\n".to_vec();
    p16.extend_from_slice(&[0, 0, 255, 255]);
    let msg = message(load_with("p16", YAML, "map.pgm", &p16));
    assert!(msg.contains("16-bit") && msg.contains("maxval 65535"), "{msg}");
    for (magic, what) in [
        ("P1", "PBM"),
        ("P4", "PBM"),
        ("P3", "PPM"),
        ("P6", "PPM"),
        ("P7", "P7"),
    ] {
        let msg = message(load_with(
            magic,
            YAML,
            "map.pgm",
            format!("{magic}\n1 1\n255\n\0\0\0").as_bytes(),
        ));
        assert!(
            msg.contains(&format!("unsupported PNM variant {magic}")) && msg.contains(what),
            "{msg}"
        );
        assert!(msg.contains("map.pgm"), "{msg}");
    }
}

#[test]
fn corrupt_and_empty_images_are_refused() {
    let msg = message(load_with(
        "png",
        &YAML.replace("map.pgm", "map.png"),
        "map.png",
        b"\x89PNG\r\n\x1a\nnot really",
    ));
    assert!(msg.contains("corrupt PNG image"), "{msg}");
    let msg = message(load_with("junk", YAML, "map.pgm", b"hello"));
    assert!(msg.contains("not a PNG or PGM image"), "{msg}");
    let msg = message(load_with("truncated", YAML, "map.pgm", b"P5 4 4 255\n\0\0\0"));
    assert!(msg.contains("truncated pixel data (3 of 16 bytes)"), "{msg}");
    let msg = message(load_with("header", YAML, "map.pgm", b"P5 4"));
    assert!(msg.contains("corrupt PGM header: bad height"), "{msg}");
    let msg = message(load_with("ascii", YAML, "map.pgm", b"P2 2 1 255 10 x"));
    assert!(msg.contains("pixel 1 of 2"), "{msg}");
    let msg = message(load_with("above", YAML, "map.pgm", b"P2 2 1 100 10 200"));
    assert!(msg.contains("above maxval 100"), "{msg}");
    let msg = message(load_with("empty", YAML, "map.pgm", b"P5 0 0 255\n"));
    assert!(msg.contains("empty image (0 × 0 pixels)"), "{msg}");
    let msg = message(load_with("empty_file", YAML, "map.pgm", b""));
    assert!(msg.contains("not a PNG or PGM image"), "{msg}");
}

/// CRC-32 of PNG chunks (ISO 3309), bit by bit: enough for a test.
fn crc32(bytes: &[u8]) -> u32 {
    let mut c = 0xffff_ffffu32;
    for &b in bytes {
        c ^= u32::from(b);
        for _ in 0..8 {
            c = if c & 1 == 1 {
                0xedb8_8320 ^ (c >> 1)
            } else {
                c >> 1
            };
        }
    }
    !c
}

/// Issue 17: a header claiming a huge image is refused from the header,
/// before the pixels are allocated (the limit is named).
#[test]
fn images_claiming_too_many_pixels_are_refused_before_allocating() {
    let msg = message(load_with(
        "huge_pgm",
        YAML,
        "map.pgm",
        b"P5 100000 100000 255\n\0\0\0",
    ));
    assert!(
        msg.contains("100000 × 100000 pixels is too large") && msg.contains("268435456"),
        "{msg}"
    );
    let msg = message(load_with(
        "overflow_pgm",
        YAML,
        "map.pgm",
        b"P2 18446744073709551615 3 255\n1 2 3",
    ));
    assert!(msg.contains("too large"), "{msg}");
    // A real 1 × 1 PNG whose IHDR is rewritten to 60000 × 60000 (CRC fixed).
    let mut bytes = Vec::new();
    image::DynamicImage::ImageLuma8(image::GrayImage::new(1, 1))
        .write_to(&mut std::io::Cursor::new(&mut bytes), image::ImageFormat::Png)
        .unwrap();
    assert_eq!(&bytes[12..16], b"IHDR");
    bytes[16..20].copy_from_slice(&60_000u32.to_be_bytes());
    bytes[20..24].copy_from_slice(&60_000u32.to_be_bytes());
    let crc = crc32(&bytes[12..29]);
    bytes[29..33].copy_from_slice(&crc.to_be_bytes());
    let msg = message(load_with(
        "huge_png",
        &YAML.replace("map.pgm", "map.png"),
        "map.png",
        &bytes,
    ));
    assert!(msg.contains("60000 × 60000 pixels is too large"), "{msg}");
    // At the limit's scale a hand-made pixel buffer is refused too.
    let yaml = map_server::parse_yaml(YAML, "map.yaml").unwrap();
    let pixels = map_server::Pixels {
        width: 1 << 15,
        height: 1 << 14,
        channels: 1,
        has_alpha: false,
        data: Vec::new(),
    };
    let err = map_server::grid_from_pixels(&yaml, &pixels)
        .unwrap_err()
        .to_string();
    assert!(err.contains("too large"), "{err}");
}
