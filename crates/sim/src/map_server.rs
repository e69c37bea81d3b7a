//! ROS `map_server` maps: a YAML file that describes an image of the map.
//!
//! ```yaml
//! image: building_31.png      # relative to the YAML file's folder, or absolute
//! resolution: 0.05            # metres per pixel (cell)
//! origin: [-26.0, -11.0, 0.0] # pose of the lower-left pixel's corner: x, y (m), yaw (rad)
//! negate: 0                   # 1: white is occupied, black is free
//! occupied_thresh: 0.65
//! free_thresh: 0.196
//! mode: trinary               # optional: trinary (default), scale or raw
//! ```
//!
//! # How pixels become cells
//!
//! Exactly as ROS 1 `map_server` (`image_loader.cpp`) computes the occupancy
//! values it publishes, which [`MapServerMap::occupancy`] keeps:
//!
//! * `avg` is the mean of the pixel's channels. In `trinary` mode, or when
//!   the image has no alpha channel, the alpha channel (if any) is averaged in
//!   too; in `scale` and `raw` mode with alpha it is left out.
//! * With `negate`, `avg ← 255 − avg`.
//! * `raw`: the value is `avg` truncated to a byte, as a signed byte (so 255
//!   is −1).
//! * Otherwise `p = (255 − avg) / 255`: occupied (100) if `p >
//!   occupied_thresh`, free (0) if `p < free_thresh`, else unknown (−1) — or,
//!   in `scale` mode for an opaque pixel, `1 + 98 · (p − free) / (occ − free)`
//!   truncated. (map_server takes "opaque" from the last byte of the pixel,
//!   which for an RGB image without alpha is the blue channel; so does this
//!   loader.)
//! * Image row 0 is the top of the map; the grid's row 0 is the bottom.
//!
//! The grid's cell is then free for the value 0, occupied for 100 and
//! unknown for anything else (−1, intermediate `scale` values, other `raw`
//! values), as AMCL reads a map (`amcl_node.cpp`, `convertMap`).
//!
//! # Images
//!
//! * **PNG** (grey, grey + alpha, RGB, RGBA, palette; 8 or 16 bits), decoded
//!   with the `image` crate. As SDL_image does for map_server, 16-bit samples
//!   keep their high byte and grey + alpha counts as RGBA with three equal
//!   colour channels. Palette images are expanded to their colours, whereas
//!   map_server reads palette *indices* (which equal the grey level for the
//!   usual greyscale palettes).
//! * **PGM**, binary (`P5`) or ASCII (`P2`), 8-bit (maxval ≤ 255; a smaller
//!   maxval is scaled to 0–255 by `v · 255 / maxval`, as SDL_image does),
//!   read by this module. 16-bit PGM and the other Netpbm variants (`P1`,
//!   `P3`, `P4`, `P6`, `P7`) are refused with an error that says so.
//!
//! # Writing
//!
//! [`save`] writes what ROS 1 `map_saver` writes: a binary PGM with free 254,
//! occupied 0 and unknown 205, and a YAML file with `negate: 0`,
//! `occupied_thresh: 0.65`, `free_thresh: 0.196`, which loads back to the same
//! grid.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use robot::Pose;
use yaml_rust2::{Yaml, YamlLoader};

use crate::error::{Error, Result};
use crate::grid::{Cell, OccupancyGrid};

/// How map_server turns pixel values into occupancy values (`mode:`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum MapMode {
    /// Occupied, free or unknown by the two thresholds (the default).
    #[default]
    Trinary,
    /// As trinary, but values between the thresholds become intermediate
    /// occupancy values 1–99 (unknown cells in the grid).
    Scale,
    /// The pixel value is the occupancy value.
    Raw,
}

impl MapMode {
    /// The name used in YAML files.
    pub fn name(self) -> &'static str {
        match self {
            MapMode::Trinary => "trinary",
            MapMode::Scale => "scale",
            MapMode::Raw => "raw",
        }
    }
}

/// The contents of a map_server YAML file.
#[derive(Debug, Clone, PartialEq)]
pub struct MapYaml {
    /// The image file as written (relative to the YAML file's folder unless
    /// absolute).
    pub image: PathBuf,
    /// Side of a cell (one pixel), metres; finite and > 0.
    pub resolution_m: f64,
    /// Pose of the map's lower-left corner in the world (x, y in metres,
    /// yaw in radians).
    pub origin: Pose,
    /// Whether white means occupied.
    pub negate: bool,
    /// Occupancy probability above which a pixel is occupied, in [0, 1].
    pub occupied_thresh: f64,
    /// Occupancy probability below which a pixel is free, in [0, 1] and not
    /// above `occupied_thresh`.
    pub free_thresh: f64,
    /// How values are interpreted.
    pub mode: MapMode,
}

/// A loaded map: the description, the grid, and the occupancy values
/// map_server would publish.
#[derive(Debug, Clone)]
pub struct MapServerMap {
    /// The YAML description.
    pub yaml: MapYaml,
    /// The image file that was read (the YAML's `image` resolved).
    pub image_path: PathBuf,
    /// The occupancy grid (row 0 at the bottom).
    pub grid: OccupancyGrid,
    /// The `nav_msgs/OccupancyGrid` data map_server publishes for this map:
    /// one value per cell, rows from the bottom, −1 unknown, 0–100 occupancy.
    pub occupancy: Vec<i8>,
}

/// Loads a map_server YAML file and its image.
pub fn load(yaml_path: impl AsRef<Path>) -> Result<MapServerMap> {
    let yaml_path = yaml_path.as_ref();
    let text = std::fs::read_to_string(yaml_path).map_err(|source| Error::Io {
        path: yaml_path.to_path_buf(),
        source,
    })?;
    let yaml = parse_yaml(&text, &yaml_path.display().to_string())?;
    let image_path = if yaml.image.is_absolute() {
        yaml.image.clone()
    } else {
        yaml_path.parent().unwrap_or(Path::new("")).join(&yaml.image)
    };
    let bytes = std::fs::read(&image_path).map_err(|source| Error::Io {
        path: image_path.clone(),
        source,
    })?;
    let pixels = decode_image(&bytes).map_err(|message| Error::Format {
        location: image_path.display().to_string(),
        message,
    })?;
    let (grid, occupancy) = grid_from_pixels(&yaml, &pixels).map_err(|e| match e {
        Error::Geometry(message) => Error::Format {
            location: format!("{} (image {})", yaml_path.display(), image_path.display()),
            message,
        },
        other => other,
    })?;
    Ok(MapServerMap {
        yaml,
        image_path,
        grid,
        occupancy,
    })
}

/// Parses the text of a map_server YAML file; `source` names it in errors.
pub fn parse_yaml(text: &str, source: &str) -> Result<MapYaml> {
    let docs = YamlLoader::load_from_str(text).map_err(|e| Error::Format {
        location: format!(
            "{source}, line {} column {}",
            e.marker().line(),
            e.marker().col() + 1
        ),
        message: format!("invalid YAML: {}", e.info()),
    })?;
    let doc = match docs.as_slice() {
        [] => {
            return Err(format_error(
                source,
                "empty file: expected the keys of a map_server map".into(),
            ));
        }
        [doc] => doc,
        _ => return Err(format_error(source, "more than one YAML document".into())),
    };
    if !matches!(doc, Yaml::Hash(_)) {
        return Err(format_error(
            source,
            "expected a mapping of keys (image, resolution, origin, …)".into(),
        ));
    }
    let keys = YamlKeys { doc, source };
    let format = |message: String| format_error(source, message);
    let image = match keys.key("image")? {
        Yaml::String(s) if !s.trim().is_empty() => PathBuf::from(s.trim()),
        v => {
            return Err(format(format!(
                "key `image`: expected a file name, got {}",
                show(v)
            )));
        }
    };
    let resolution_m = keys.number("resolution", keys.key("resolution")?)?;
    crate::grid::check_resolution(&format!("{source}: resolution"), resolution_m)?;
    let origin = match keys.key("origin")? {
        Yaml::Array(a) if a.len() == 3 => {
            let x = keys.number("origin", &a[0])?;
            let y = keys.number("origin", &a[1])?;
            let yaw = keys.number("origin", &a[2])?;
            let origin = Pose::new(x, y, yaw);
            crate::grid::check_origin(&format!("{source}: origin"), origin)?;
            origin
        }
        v => {
            return Err(format(format!(
                "key `origin`: expected [x, y, yaw], got {}",
                show(v)
            )));
        }
    };
    let negate = match keys.key("negate")? {
        Yaml::Integer(i) => *i != 0,
        Yaml::Boolean(b) => *b,
        v => return Err(format(format!("key `negate`: expected 0 or 1, got {}", show(v)))),
    };
    let (occupied_thresh, free_thresh) = keys.thresholds()?;
    let mode = keys.mode()?;
    Ok(MapYaml {
        image,
        resolution_m,
        origin,
        negate,
        occupied_thresh,
        free_thresh,
        mode,
    })
}

/// A format error at `source`.
fn format_error(source: &str, message: String) -> Error {
    Error::Format {
        location: source.to_string(),
        message,
    }
}

/// The keys of a map_server YAML document, read with errors that name the
/// file.
struct YamlKeys<'a> {
    doc: &'a Yaml,
    /// The file, for errors.
    source: &'a str,
}

impl YamlKeys<'_> {
    /// The value of a required key.
    fn key(&self, name: &str) -> Result<&Yaml> {
        match &self.doc[name] {
            Yaml::BadValue => Err(format_error(self.source, format!("missing key `{name}`"))),
            v => Ok(v),
        }
    }

    /// The finite number `v` of key `name`.
    fn number(&self, name: &str, v: &Yaml) -> Result<f64> {
        let x = match v {
            Yaml::Real(s) | Yaml::String(s) => s.trim().parse::<f64>().ok(),
            Yaml::Integer(i) => Some(*i as f64),
            _ => None,
        };
        match x {
            Some(x) if x.is_finite() => Ok(x),
            _ => Err(format_error(
                self.source,
                format!("key `{name}`: expected a finite number, got {}", show(v)),
            )),
        }
    }

    /// `occupied_thresh` and `free_thresh`, each between 0 and 1, the free
    /// one not above the occupied one.
    fn thresholds(&self) -> Result<(f64, f64)> {
        let source = self.source;
        let occupied_thresh = self.number("occupied_thresh", self.key("occupied_thresh")?)?;
        let free_thresh = self.number("free_thresh", self.key("free_thresh")?)?;
        for (name, value) in [("occupied_thresh", occupied_thresh), ("free_thresh", free_thresh)] {
            if !(0.0..=1.0).contains(&value) {
                return Err(Error::InvalidValue {
                    what: format!("{source}: {name}"),
                    requirement: "between 0 and 1",
                    value,
                });
            }
        }
        if free_thresh > occupied_thresh {
            return Err(format_error(
                source,
                format!("free_thresh ({free_thresh}) is above occupied_thresh ({occupied_thresh})"),
            ));
        }
        Ok((occupied_thresh, free_thresh))
    }

    /// The optional `mode` (trinary by default).
    fn mode(&self) -> Result<MapMode> {
        let format = |message: String| format_error(self.source, message);
        Ok(match &self.doc["mode"] {
            Yaml::BadValue => MapMode::Trinary,
            Yaml::String(s) => match s.as_str() {
                "trinary" => MapMode::Trinary,
                "scale" => MapMode::Scale,
                "raw" => MapMode::Raw,
                other => {
                    return Err(format(format!(
                        "key `mode`: expected trinary, scale or raw, got `{other}`"
                    )));
                }
            },
            v => {
                return Err(format(format!(
                    "key `mode`: expected trinary, scale or raw, got {}",
                    show(v)
                )));
            }
        })
    }
}

/// A YAML value, briefly, for error messages.
fn show(v: &Yaml) -> String {
    match v {
        Yaml::Real(s) => s.clone(),
        Yaml::Integer(i) => i.to_string(),
        Yaml::String(s) => format!("\"{s}\""),
        Yaml::Boolean(b) => b.to_string(),
        Yaml::Array(a) => format!("a list of {}", a.len()),
        Yaml::Hash(_) => "a mapping".into(),
        Yaml::Null => "nothing".into(),
        Yaml::Alias(_) | Yaml::BadValue => "an unsupported value".into(),
    }
}

/// Pixels as map_server's SDL surface holds them: `channels` bytes per
/// pixel (1 grey, 3 RGB, 4 RGBA), rows from the top.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Pixels {
    /// Columns.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Bytes per pixel: 1, 3 or 4.
    pub channels: usize,
    /// Whether the last channel is alpha.
    pub has_alpha: bool,
    /// `width · height · channels` bytes, rows from the top.
    pub data: Vec<u8>,
}

/// Decodes a PNG or PGM image as map_server sees it; the error says why not.
pub fn decode_image(bytes: &[u8]) -> std::result::Result<Pixels, String> {
    let pixels = if bytes.starts_with(b"\x89PNG") {
        decode_png(bytes)?
    } else if bytes.first() == Some(&b'P') && bytes.get(1).is_some_and(u8::is_ascii_digit) {
        decode_pgm(bytes)?
    } else {
        return Err("not a PNG or PGM image".into());
    };
    if pixels.width == 0 || pixels.height == 0 {
        return Err(format!(
            "empty image ({} × {} pixels)",
            pixels.width, pixels.height
        ));
    }
    Ok(pixels)
}

/// Most pixels an image may have: 2^28 (268 M, e.g. 16,384 × 16,384 —
/// 820 m square at 5 cm), the generators' largest grid too
/// ([`crate::generators::MAX_CELLS`]); the real maps have 0.45 M
/// (building_31) and 4.2 M (levine). Checked from the image's header,
/// before its pixels are allocated: a header that claims more is refused
/// with an error naming the limit.
pub const MAX_PIXELS: usize = 1 << 28;

fn check_size(width: usize, height: usize) -> std::result::Result<(), String> {
    match width.checked_mul(height) {
        Some(n) if n <= MAX_PIXELS => Ok(()),
        _ => Err(format!(
            "image of {width} × {height} pixels is too large: at most {MAX_PIXELS} pixels (2^28) are read"
        )),
    }
}

fn decode_png(bytes: &[u8]) -> std::result::Result<Pixels, String> {
    use image::DynamicImage as D;
    use image::ImageDecoder as _;
    let corrupt = |e: image::ImageError| format!("corrupt PNG image: {e}");
    let decoder = image::codecs::png::PngDecoder::new(std::io::Cursor::new(bytes)).map_err(corrupt)?;
    let (w, h) = decoder.dimensions();
    check_size(w as usize, h as usize)?;
    let img = D::from_decoder(decoder).map_err(corrupt)?;
    let (width, height) = (img.width() as usize, img.height() as usize);
    let hi = |v: &u16| (v >> 8) as u8;
    let (channels, has_alpha, data) = match img {
        D::ImageLuma8(b) => (1, false, b.into_raw()),
        D::ImageLuma16(b) => (1, false, b.as_raw().iter().map(hi).collect()),
        D::ImageRgb8(b) => (3, false, b.into_raw()),
        D::ImageRgb16(b) => (3, false, b.as_raw().iter().map(hi).collect()),
        D::ImageRgba8(b) => (4, true, b.into_raw()),
        D::ImageRgba16(b) => (4, true, b.as_raw().iter().map(hi).collect()),
        D::ImageLumaA8(b) => (4, true, grey_alpha_to_rgba(b.as_raw().iter().copied())),
        D::ImageLumaA16(b) => (4, true, grey_alpha_to_rgba(b.as_raw().iter().map(hi))),
        other => (4, true, other.to_rgba8().into_raw()),
    };
    Ok(Pixels {
        width,
        height,
        channels,
        has_alpha,
        data,
    })
}

fn grey_alpha_to_rgba(samples: impl Iterator<Item = u8>) -> Vec<u8> {
    let samples: Vec<u8> = samples.collect();
    samples
        .chunks_exact(2)
        .flat_map(|ga| [ga[0], ga[0], ga[0], ga[1]])
        .collect()
}

/// Reads 8-bit PGM, `P5` (binary) or `P2` (ASCII).
fn decode_pgm(bytes: &[u8]) -> std::result::Result<Pixels, String> {
    let kind = bytes[1];
    let ascii = match kind {
        b'5' => false,
        b'2' => true,
        b'1' | b'4' => {
            return Err(format!(
                "unsupported PNM variant P{}: bitmap (PBM); only 8-bit greyscale PGM (P2, P5) is supported",
                kind as char
            ));
        }
        b'3' | b'6' => {
            return Err(format!(
                "unsupported PNM variant P{}: colour (PPM); only 8-bit greyscale PGM (P2, P5) is supported",
                kind as char
            ));
        }
        _ => {
            return Err(format!(
                "unsupported PNM variant P{}; only 8-bit greyscale PGM (P2, P5) is supported",
                kind as char
            ));
        }
    };
    let mut pos = 2;
    let mut header = [0usize; 3];
    for (n, name) in ["width", "height", "maxval"].iter().enumerate() {
        header[n] = pnm_number(bytes, &mut pos).ok_or_else(|| format!("corrupt PGM header: bad {name}"))?;
    }
    let [width, height, maxval] = header;
    if maxval == 0 {
        return Err("corrupt PGM header: maxval 0".into());
    }
    if maxval > 255 {
        return Err(format!(
            "unsupported PGM: 16-bit samples (maxval {maxval}); only 8-bit (maxval ≤ 255) is supported"
        ));
    }
    check_size(width, height)?;
    let count = width * height;
    let mut data = Vec::new();
    if ascii {
        for k in 0..count {
            let v = pnm_number(bytes, &mut pos)
                .ok_or_else(|| format!("corrupt PGM: pixel {k} of {count} is missing or not a number"))?;
            if v > maxval {
                return Err(format!("corrupt PGM: pixel {k} is {v}, above maxval {maxval}"));
            }
            data.push(v as u8);
        }
    } else {
        // Exactly one whitespace byte separates maxval from the samples.
        pos += 1;
        let body = bytes.get(pos..).unwrap_or(&[]);
        if body.len() < count {
            return Err(format!(
                "corrupt PGM: truncated pixel data ({} of {count} bytes)",
                body.len()
            ));
        }
        data.extend_from_slice(&body[..count]);
        if let Some(v) = data.iter().find(|&&v| v as usize > maxval) {
            return Err(format!("corrupt PGM: a pixel is {v}, above maxval {maxval}"));
        }
    }
    if maxval < 255 {
        for v in &mut data {
            *v = (*v as usize * 255 / maxval) as u8;
        }
    }
    Ok(Pixels {
        width,
        height,
        channels: 1,
        has_alpha: false,
        data,
    })
}

/// The next decimal number of a Netpbm header or ASCII body, skipping
/// whitespace and `#` comments.
fn pnm_number(bytes: &[u8], pos: &mut usize) -> Option<usize> {
    loop {
        match bytes.get(*pos)? {
            b'#' => {
                while *bytes.get(*pos)? != b'\n' {
                    *pos += 1;
                }
            }
            c if c.is_ascii_whitespace() => *pos += 1,
            _ => break,
        }
    }
    let start = *pos;
    while bytes.get(*pos).is_some_and(u8::is_ascii_digit) {
        *pos += 1;
    }
    std::str::from_utf8(&bytes[start..*pos]).ok()?.parse().ok()
}

/// The occupancy value map_server computes for one pixel (`p` = its bytes).
fn occupancy_value(yaml: &MapYaml, p: &[u8], has_alpha: bool) -> i8 {
    let n = p.len();
    let avg_channels = if yaml.mode == MapMode::Trinary || !has_alpha {
        n
    } else {
        n - 1
    };
    let sum: u32 = p[..avg_channels].iter().map(|&v| u32::from(v)).sum();
    let mut avg = f64::from(sum) / avg_channels as f64;
    let alpha = if n == 1 { 1 } else { p[n - 1] };
    if yaml.negate {
        avg = 255.0 - avg;
    }
    if yaml.mode == MapMode::Raw {
        return avg as u8 as i8;
    }
    let occ = (255.0 - avg) / 255.0;
    if occ > yaml.occupied_thresh {
        100
    } else if occ < yaml.free_thresh {
        0
    } else if yaml.mode == MapMode::Trinary || alpha < 1 {
        -1
    } else {
        let span = yaml.occupied_thresh - yaml.free_thresh;
        let ratio = if span > 0.0 {
            (occ - yaml.free_thresh) / span
        } else {
            0.0
        };
        (1.0 + 98.0 * ratio) as u8 as i8
    }
}

/// The grid and occupancy values of an image under a YAML description.
pub fn grid_from_pixels(yaml: &MapYaml, pixels: &Pixels) -> Result<(OccupancyGrid, Vec<i8>)> {
    let (w, h, n) = (pixels.width, pixels.height, pixels.channels);
    if w == 0 || h == 0 {
        return Err(Error::Geometry(format!("empty image ({w} × {h} pixels)")));
    }
    check_size(w, h).map_err(Error::Geometry)?;
    OccupancyGrid::check_geometry(w, h, yaml.resolution_m, yaml.origin)?;
    if !(1..=4).contains(&n) || pixels.data.len() != w * h * n {
        return Err(Error::Geometry(format!(
            "{} bytes of pixels for {w} × {h} pixels of {n} bytes",
            pixels.data.len()
        )));
    }
    let mut occupancy = vec![0i8; w * h];
    let mut cells = vec![Cell::Free; w * h];
    for (y, row) in pixels.data.chunks_exact(w * n).enumerate() {
        let j = h - 1 - y;
        for (i, p) in row.chunks_exact(n).enumerate() {
            let v = occupancy_value(yaml, p, pixels.has_alpha);
            occupancy[j * w + i] = v;
            cells[j * w + i] = match v {
                0 => Cell::Free,
                100 => Cell::Occupied,
                _ => Cell::Unknown,
            };
        }
    }
    let grid = OccupancyGrid::from_cells(w, h, yaml.resolution_m, yaml.origin, cells)?;
    Ok((grid, occupancy))
}

/// Writes a grid as a map_server map: `yaml_path` and, next to it, a PGM
/// image with the same stem. Returns the image's path.
pub fn save(grid: &OccupancyGrid, yaml_path: impl AsRef<Path>) -> Result<PathBuf> {
    let yaml_path = yaml_path.as_ref();
    let stem = yaml_path
        .file_stem()
        .ok_or_else(|| Error::Geometry(format!("{}: not a file name", yaml_path.display())))?;
    let image_name = PathBuf::from(stem).with_extension("pgm");
    let image_path = yaml_path.parent().unwrap_or(Path::new("")).join(&image_name);
    let (w, h) = (grid.width(), grid.height());
    let mut pgm = format!(
        "P5\n# CREATOR: petrinav sim::map_server::save {:.3} m/pix\n{w} {h}\n255\n",
        grid.resolution_m()
    )
    .into_bytes();
    pgm.reserve(w * h);
    for row in grid.cells().chunks_exact(w.max(1)).rev() {
        pgm.extend(row.iter().map(|c| match c {
            Cell::Free => 254u8,
            Cell::Occupied => 0,
            Cell::Unknown => 205,
        }));
    }
    let io = |path: &Path| {
        let path = path.to_path_buf();
        move |source| Error::Io { path, source }
    };
    std::fs::write(&image_path, pgm).map_err(io(&image_path))?;
    let o = grid.origin();
    let mut text = String::new();
    let name = image_name
        .display()
        .to_string()
        .replace('\\', "\\\\")
        .replace('"', "\\\"");
    let _ = writeln!(text, "image: \"{name}\"");
    let _ = writeln!(text, "mode: trinary");
    let _ = writeln!(text, "resolution: {}", grid.resolution_m());
    let _ = writeln!(text, "origin: [{}, {}, {}]", o.x_m, o.y_m, o.theta_rad);
    let _ = writeln!(text, "negate: 0");
    let _ = writeln!(text, "occupied_thresh: 0.65");
    let _ = writeln!(text, "free_thresh: 0.196");
    std::fs::write(yaml_path, text).map_err(io(yaml_path))?;
    Ok(image_path)
}
