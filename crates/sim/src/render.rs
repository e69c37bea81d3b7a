//! Pictures of a world: the occupancy grid (free white, occupied black,
//! unknown and outside the map grey) with overlays — trajectories coloured
//! by a per-point label (e.g. the selected behaviour) with a legend, robot
//! footprints with a heading tick, sensor rays, people, start/goal markers
//! and text — as SVG or PNG.
//!
//! ```
//! use robot::{Pose, Vec2};
//! use sim::render::{MarkerKind, Picture};
//!
//! let grid = sim::OccupancyGrid::new(40, 30, 0.1, Pose::default());
//! let path = [Pose::new(0.5, 0.5, 0.0), Pose::new(2.0, 1.0, 0.3), Pose::new(3.5, 2.5, 0.8)];
//! let mut p = Picture::new(&grid);
//! p.scale(50.0)
//!     .trajectory(&path, Some(&["automove", "automove", "contour"]))
//!     .robot(path[2], 0.2)
//!     .marker(Vec2::new(0.5, 0.5), MarkerKind::Start)
//!     .marker(Vec2::new(3.5, 2.5), MarkerKind::Goal);
//! let svg = p.to_svg().unwrap();
//! assert!(svg.starts_with("<svg") && svg.contains("contour"));
//! let png = p.to_png().unwrap();
//! assert_eq!((png.width(), png.height()), (200, 150));
//! ```
//!
//! # Geometry
//!
//! The picture shows a world-frame rectangle (the map's bounding box, or
//! the [`Picture::crop`] rectangle) with +x to the right and +y **up**, at
//! [`Picture::scale`] pixels per metre; by default one pixel per cell, or
//! a whole number of pixels per cell so that the longer side has at least
//! 600 pixels. Maps with a rotated origin are drawn rotated.
//!
//! # Output
//!
//! * **SVG**: hand-written XML. The grid is one embedded PNG with one pixel
//!   per cell (a `data:` URI, placed and rotated by a transform and drawn
//!   with `image-rendering: pixelated`), so a 4-million-cell map stays a few
//!   tens of kilobytes; overlays are vector elements with coordinates
//!   rounded to 0.01 px.
//! * **PNG**: each pixel samples the cell under its centre; overlays are
//!   drawn with anti-aliased distance-based coverage (lines, circles) and a
//!   3 × 5 bitmap font scaled ×2 for text.
//!
//! Both are deterministic: the same picture gives the same bytes.

use std::fmt::Write as _;
use std::path::Path;

use robot::{Pose, Vec2};

use crate::error::{Error, Result};
use crate::font;
use crate::grid::{Cell, OccupancyGrid};

/// Largest PNG drawn, in pixels per side.
const MAX_SIDE_PX: f64 = 20_000.0;

/// Colours of the labels, in order of first appearance (Tableau 10).
const PALETTE: [[u8; 3]; 10] = [
    [78, 121, 167],
    [242, 142, 43],
    [225, 87, 89],
    [118, 183, 178],
    [89, 161, 79],
    [237, 201, 72],
    [176, 122, 161],
    [255, 157, 167],
    [156, 117, 95],
    [186, 176, 172],
];
const FREE: [u8; 3] = [255, 255, 255];
const OCCUPIED: [u8; 3] = [0, 0, 0];
const UNKNOWN: [u8; 3] = [205, 205, 205];
const ROBOT: [u8; 3] = [40, 40, 200];
const RAY: [u8; 3] = [230, 30, 30];
const PERSON: [u8; 3] = [240, 150, 30];
const TEXT: [u8; 3] = [20, 20, 20];

/// Kinds of point markers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MarkerKind {
    /// A start: green disc.
    Start,
    /// A goal: red cross in a ring.
    Goal,
    /// Any other point: small blue square.
    Point,
    /// A small square of this colour (RGB).
    Square([u8; 3]),
    /// A ring of this colour (RGB) with a dot at its centre, the size of a
    /// goal marker: a point to notice (a detected dead-lock, say).
    Ring([u8; 3]),
}

#[derive(Debug, Clone)]
enum Item {
    /// Polyline; `labels[k]` is the label index of segment k.
    Trajectory {
        points: Vec<Vec2>,
        labels: Vec<Option<usize>>,
    },
    Robot {
        pose: Pose,
        radius_m: f64,
    },
    Ray {
        from: Vec2,
        to: Vec2,
    },
    Person {
        center: Vec2,
        radius_m: f64,
    },
    Marker {
        at: Vec2,
        kind: MarkerKind,
    },
    Text {
        at: Vec2,
        text: String,
    },
}

/// A picture of a grid with overlays, built step by step, then written as
/// SVG or PNG. Overlays are drawn in the order they were added, the legend
/// (if any trajectory has labels) last.
#[derive(Debug, Clone)]
pub struct Picture<'a> {
    grid: &'a OccupancyGrid,
    px_per_m: Option<f64>,
    crop: Option<(Vec2, Vec2)>,
    items: Vec<Item>,
    labels: Vec<String>,
}

/// The world rectangle shown and the scale.
#[derive(Debug, Clone, Copy)]
struct View {
    xmin: f64,
    ymax: f64,
    s: f64,
    w: u32,
    h: u32,
}

impl View {
    #[inline]
    fn px(&self, p: Vec2) -> (f64, f64) {
        ((p.x - self.xmin) * self.s, (self.ymax - p.y) * self.s)
    }
}

impl<'a> Picture<'a> {
    /// A picture of `grid` with no overlays.
    pub fn new(grid: &'a OccupancyGrid) -> Picture<'a> {
        Picture {
            grid,
            px_per_m: None,
            crop: None,
            items: Vec::new(),
            labels: Vec::new(),
        }
    }

    /// Pixels per metre (see the module docs for the default).
    pub fn scale(&mut self, px_per_m: f64) -> &mut Self {
        self.px_per_m = Some(px_per_m);
        self
    }

    /// Shows only the world rectangle between two corners.
    pub fn crop(&mut self, corner_a: Vec2, corner_b: Vec2) -> &mut Self {
        self.crop = Some((
            Vec2::new(corner_a.x.min(corner_b.x), corner_a.y.min(corner_b.y)),
            Vec2::new(corner_a.x.max(corner_b.x), corner_a.y.max(corner_b.y)),
        ));
        self
    }

    /// A path through the poses' positions. With `labels` (one per pose; a
    /// missing one leaves the rest unlabelled), the segment from pose `k` to
    /// `k + 1` takes the colour of label `k`, and the labels appear in the
    /// legend in order of first appearance.
    pub fn trajectory(&mut self, poses: &[Pose], labels: Option<&[&str]>) -> &mut Self {
        let points: Vec<Vec2> = poses.iter().map(Pose::position).collect();
        let labels = (0..points.len())
            .map(|k| labels.and_then(|l| l.get(k)).map(|name| self.label_index(name)))
            .collect();
        self.items.push(Item::Trajectory { points, labels });
        self
    }

    fn label_index(&mut self, name: &str) -> usize {
        if let Some(k) = self.labels.iter().position(|l| l == name) {
            k
        } else {
            self.labels.push(name.to_string());
            self.labels.len() - 1
        }
    }

    /// A robot's circular footprint with a tick from the centre along its
    /// heading.
    pub fn robot(&mut self, pose: Pose, radius_m: f64) -> &mut Self {
        self.items.push(Item::Robot { pose, radius_m });
        self
    }

    /// A sensor ray.
    pub fn ray(&mut self, from: Vec2, to: Vec2) -> &mut Self {
        self.items.push(Item::Ray { from, to });
        self
    }

    /// A person (filled disc).
    pub fn person(&mut self, center: Vec2, radius_m: f64) -> &mut Self {
        self.items.push(Item::Person { center, radius_m });
        self
    }

    /// A start, goal or other point.
    pub fn marker(&mut self, at: Vec2, kind: MarkerKind) -> &mut Self {
        self.items.push(Item::Marker { at, kind });
        self
    }

    /// Text whose lower-left corner is at a world point.
    pub fn text(&mut self, at: Vec2, text: &str) -> &mut Self {
        self.items.push(Item::Text {
            at,
            text: text.to_string(),
        });
        self
    }

    /// The map's corners in the world.
    fn map_bounds(&self) -> (Vec2, Vec2) {
        let g = self.grid;
        let (wm, hm) = (
            g.width() as f64 * g.resolution_m(),
            g.height() as f64 * g.resolution_m(),
        );
        let corners = [(0.0, 0.0), (wm, 0.0), (0.0, hm), (wm, hm)].map(|(x, y)| g.to_world(Vec2::new(x, y)));
        let lo = corners
            .iter()
            .fold(Vec2::new(f64::INFINITY, f64::INFINITY), |a, c| {
                Vec2::new(a.x.min(c.x), a.y.min(c.y))
            });
        let hi = corners
            .iter()
            .fold(Vec2::new(f64::NEG_INFINITY, f64::NEG_INFINITY), |a, c| {
                Vec2::new(a.x.max(c.x), a.y.max(c.y))
            });
        (lo, hi)
    }

    fn view(&self) -> Result<View> {
        let (lo, hi) = self.crop.unwrap_or_else(|| self.map_bounds());
        let (wm, hm) = (hi.x - lo.x, hi.y - lo.y);
        if !(wm.is_finite() && hm.is_finite() && wm > 0.0 && hm > 0.0) {
            return Err(Error::Geometry(format!(
                "nothing to draw: the picture's rectangle is {wm} × {hm} m"
            )));
        }
        let s = match self.px_per_m {
            Some(s) => s,
            None => {
                let cell_px = 1.0 / self.grid.resolution_m();
                let longest_cells = wm.max(hm) * cell_px;
                cell_px * (600.0 / longest_cells).ceil().max(1.0)
            }
        };
        if !(s.is_finite() && s > 0.0) {
            return Err(Error::InvalidValue {
                what: "picture scale (px/m)".into(),
                requirement: "finite and > 0",
                value: s,
            });
        }
        let (w, h) = ((wm * s - 1e-6).ceil().max(1.0), (hm * s - 1e-6).ceil().max(1.0));
        if w > MAX_SIDE_PX || h > MAX_SIDE_PX {
            return Err(Error::Geometry(format!(
                "a picture of {w} × {h} pixels is too large (at most {MAX_SIDE_PX} per side): lower the scale"
            )));
        }
        Ok(View {
            xmin: lo.x,
            ymax: hi.y,
            s,
            w: w as u32,
            h: h as u32,
        })
    }

    fn label_colour(&self, label: Option<usize>) -> [u8; 3] {
        label.map_or(PALETTE[0], |k| PALETTE[k % PALETTE.len()])
    }

    /// The picture as an SVG document.
    pub fn to_svg(&self) -> Result<String> {
        let v = self.view()?;
        let mut s = String::new();
        let _ = writeln!(
            s,
            "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" viewBox=\"0 0 {w} {h}\">",
            w = v.w,
            h = v.h
        );
        let _ = writeln!(
            s,
            "<rect width=\"100%\" height=\"100%\" fill=\"{}\"/>",
            hex(UNKNOWN)
        );
        self.svg_grid(&mut s, &v)?;
        let line_w = (v.s * 0.04).clamp(1.0, 4.0);
        for item in &self.items {
            self.svg_item(&mut s, &v, item, line_w);
        }
        self.svg_legend(&mut s);
        s.push_str("</svg>\n");
        Ok(s)
    }

    /// The grid into the SVG document `s`: one PNG pixel per cell, top row
    /// first, placed at the map's top-left corner and turned with the map.
    fn svg_grid(&self, s: &mut String, v: &View) -> Result<()> {
        let g = self.grid;
        let o = g.origin();
        let (ox, oy) = v.px(o.position());
        let (gw, gh) = (
            g.width() as f64 * g.resolution_m() * v.s,
            g.height() as f64 * g.resolution_m() * v.s,
        );
        let _ = writeln!(
            s,
            "<g transform=\"translate({} {}) rotate({})\"><image x=\"0\" y=\"{}\" width=\"{}\" height=\"{}\" \
             preserveAspectRatio=\"none\" style=\"image-rendering:pixelated\" href=\"data:image/png;base64,{}\"/></g>",
            f(ox),
            f(oy),
            f(-o.theta_rad.to_degrees()),
            f(-gh),
            f(gw),
            f(gh),
            base64(&grid_png(g)?)
        );
        Ok(())
    }

    /// One item into the SVG document `s`, lines `line_w` pixels wide.
    fn svg_item(&self, s: &mut String, v: &View, item: &Item, line_w: f64) {
        match item {
            Item::Trajectory { points, labels } => self.svg_trajectory(s, v, points, labels, line_w),
            Item::Robot { pose, radius_m } => {
                let (x, y) = v.px(pose.position());
                let tip = pose.transform(Vec2::new(*radius_m, 0.0));
                let (tx, ty) = v.px(tip);
                let _ = writeln!(
                    s,
                    "<g stroke=\"{c}\" stroke-width=\"{w}\"><circle cx=\"{}\" cy=\"{}\" r=\"{}\" fill=\"{c}\" \
                     fill-opacity=\"0.25\"/><line x1=\"{}\" y1=\"{}\" x2=\"{}\" y2=\"{}\"/></g>",
                    f(x),
                    f(y),
                    f(radius_m * v.s),
                    f(x),
                    f(y),
                    f(tx),
                    f(ty),
                    c = hex(ROBOT),
                    w = f(line_w)
                );
            }
            Item::Ray { from, to } => {
                let ((x1, y1), (x2, y2)) = (v.px(*from), v.px(*to));
                let _ = writeln!(
                    s,
                    "<line x1=\"{}\" y1=\"{}\" x2=\"{}\" y2=\"{}\" stroke=\"{}\" stroke-opacity=\"0.6\" \
                     stroke-width=\"1\"/>",
                    f(x1),
                    f(y1),
                    f(x2),
                    f(y2),
                    hex(RAY)
                );
            }
            Item::Person { center, radius_m } => {
                let (x, y) = v.px(*center);
                let _ = writeln!(
                    s,
                    "<circle cx=\"{}\" cy=\"{}\" r=\"{}\" fill=\"{}\"/>",
                    f(x),
                    f(y),
                    f(radius_m * v.s),
                    hex(PERSON)
                );
            }
            Item::Marker { at, kind } => svg_marker(s, v, *at, kind),
            Item::Text { at, text } => {
                let (x, y) = v.px(*at);
                let _ = writeln!(
                    s,
                    "<text x=\"{}\" y=\"{}\" font-family=\"sans-serif\" font-size=\"12\" fill=\"{}\">{}</text>",
                    f(x),
                    f(y),
                    hex(TEXT),
                    xml_escape(text)
                );
            }
        }
    }

    /// A trajectory into the SVG document `s`: one polyline per run of
    /// equal labels, in the label's colour.
    fn svg_trajectory(
        &self,
        s: &mut String,
        v: &View,
        points: &[Vec2],
        labels: &[Option<usize>],
        line_w: f64,
    ) {
        // One polyline per run of equal labels.
        let mut k = 0;
        while k + 1 < points.len() {
            let mut end = k + 1;
            while end + 1 < points.len() && labels[end] == labels[k] {
                end += 1;
            }
            let pts: Vec<String> = points[k..=end]
                .iter()
                .map(|p| {
                    let (x, y) = v.px(*p);
                    format!("{},{}", f(x), f(y))
                })
                .collect();
            let _ = writeln!(
                s,
                "<polyline points=\"{}\" fill=\"none\" stroke=\"{}\" stroke-width=\"{}\" \
                 stroke-linejoin=\"round\" stroke-linecap=\"round\"/>",
                pts.join(" "),
                hex(self.label_colour(labels[k])),
                f(line_w)
            );
            k = end;
        }
    }

    /// The legend (the labels and their colours) into the SVG document
    /// `s`, if there are labels.
    fn svg_legend(&self, s: &mut String) {
        if !self.labels.is_empty() {
            let width = 30.0 + 7.0 * self.labels.iter().map(|l| l.chars().count()).max().unwrap_or(0) as f64;
            let _ = writeln!(
                s,
                "<g font-family=\"sans-serif\" font-size=\"12\"><rect x=\"4\" y=\"4\" width=\"{}\" height=\"{}\" \
                 fill=\"white\" fill-opacity=\"0.85\" stroke=\"#888\"/>",
                f(width),
                f(8.0 + 16.0 * self.labels.len() as f64)
            );
            for (k, label) in self.labels.iter().enumerate() {
                let y = 16.0 + 16.0 * k as f64;
                let _ = writeln!(
                    s,
                    "<line x1=\"10\" y1=\"{y}\" x2=\"26\" y2=\"{y}\" stroke=\"{}\" stroke-width=\"3\"/>\
                     <text x=\"30\" y=\"{}\" fill=\"{}\">{}</text>",
                    hex(self.label_colour(Some(k))),
                    f(y + 4.0),
                    hex(TEXT),
                    xml_escape(label),
                    y = f(y)
                );
            }
            s.push_str("</g>\n");
        }
    }

    /// The picture as an RGB image.
    pub fn to_png(&self) -> Result<image::RgbImage> {
        let v = self.view()?;
        let g = self.grid;
        let mut c = Canvas {
            img: image::RgbImage::new(v.w, v.h),
        };
        // The grid: the cell under each pixel's centre.
        let o = g.origin();
        let (sn, cs) = o.theta_rad.sin_cos();
        let inv_res = 1.0 / g.resolution_m();
        for py in 0..v.h {
            let wy = v.ymax - (py as f64 + 0.5) / v.s;
            for px in 0..v.w {
                let wx = v.xmin + (px as f64 + 0.5) / v.s;
                let (dx, dy) = (wx - o.x_m, wy - o.y_m);
                let (mx, my) = (cs * dx + sn * dy, -sn * dx + cs * dy);
                let cell = crate::grid::CellIndex {
                    i: (mx * inv_res).floor() as i64,
                    j: (my * inv_res).floor() as i64,
                };
                let colour = if g.contains(cell) {
                    match g.get(cell) {
                        Cell::Free => FREE,
                        Cell::Occupied => OCCUPIED,
                        Cell::Unknown => UNKNOWN,
                    }
                } else {
                    UNKNOWN
                };
                c.img.put_pixel(px, py, image::Rgb(colour));
            }
        }
        let line_w = (v.s * 0.04).clamp(1.0, 4.0);
        for item in &self.items {
            match item {
                Item::Trajectory { points, labels } => {
                    for k in 0..points.len().saturating_sub(1) {
                        let colour = self.label_colour(labels[k]);
                        c.line(v.px(points[k]), v.px(points[k + 1]), line_w, colour, 1.0);
                    }
                }
                Item::Robot { pose, radius_m } => {
                    let centre = v.px(pose.position());
                    let r = radius_m * v.s;
                    c.disc(centre, r, ROBOT, 0.25);
                    c.ring(centre, r, line_w, ROBOT);
                    c.line(
                        centre,
                        v.px(pose.transform(Vec2::new(*radius_m, 0.0))),
                        line_w,
                        ROBOT,
                        1.0,
                    );
                }
                Item::Ray { from, to } => c.line(v.px(*from), v.px(*to), 1.0, RAY, 0.6),
                Item::Person { center, radius_m } => c.disc(v.px(*center), radius_m * v.s, PERSON, 1.0),
                Item::Marker { at, kind } => {
                    let (x, y) = v.px(*at);
                    let r = marker_radius_px(v.s);
                    match kind {
                        MarkerKind::Start => {
                            c.disc((x, y), r + 1.0, FREE, 1.0);
                            c.disc((x, y), r, [44, 160, 44], 1.0);
                        }
                        MarkerKind::Goal => {
                            let red = [214, 39, 40];
                            c.ring((x, y), r, 2.0, red);
                            let d = r * 0.6;
                            c.line((x - d, y - d), (x + d, y + d), 2.0, red, 1.0);
                            c.line((x - d, y + d), (x + d, y - d), 2.0, red, 1.0);
                        }
                        MarkerKind::Point => {
                            c.rect(
                                (x - r * 0.5, y - r * 0.5),
                                (x + r * 0.5, y + r * 0.5),
                                [31, 119, 180],
                            );
                        }
                        MarkerKind::Square(rgb) => {
                            c.rect((x - r * 0.5, y - r * 0.5), (x + r * 0.5, y + r * 0.5), *rgb);
                        }
                        MarkerKind::Ring(rgb) => {
                            c.ring((x, y), r, 2.0, *rgb);
                            c.disc((x, y), r * 0.25, *rgb, 1.0);
                        }
                    }
                }
                Item::Text { at, text } => {
                    let (x, y) = v.px(*at);
                    c.text(x, y - (font::GLYPH_H * 2) as f64, text, TEXT);
                }
            }
        }
        if !self.labels.is_empty() {
            let longest = self.labels.iter().map(|l| l.chars().count()).max().unwrap_or(0);
            let (w, h) = (34.0 + (longest * 8) as f64, 6.0 + 16.0 * self.labels.len() as f64);
            c.rect((4.0, 4.0), (4.0 + w, 4.0 + h), [136, 136, 136]);
            c.rect((5.0, 5.0), (3.0 + w, 3.0 + h), FREE);
            for (k, label) in self.labels.iter().enumerate() {
                let y = 12.0 + 16.0 * k as f64;
                c.line(
                    (10.0, y + 4.0),
                    (26.0, y + 4.0),
                    3.0,
                    self.label_colour(Some(k)),
                    1.0,
                );
                c.text(30.0, y - 1.0, label, TEXT);
            }
        }
        Ok(c.img)
    }

    /// Writes the picture as SVG (`.svg`) or PNG (`.png`), by extension.
    pub fn save(&self, path: impl AsRef<Path>) -> Result<()> {
        let path = path.as_ref();
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        let bytes = match ext.as_deref() {
            Some("svg") => self.to_svg()?.into_bytes(),
            Some("png") => {
                let img = self.to_png()?;
                encode_png(
                    img.as_raw(),
                    img.width(),
                    img.height(),
                    image::ExtendedColorType::Rgb8,
                )?
            }
            _ => {
                return Err(Error::Geometry(format!(
                    "{}: unknown picture format; use .png or .svg",
                    path.display()
                )));
            }
        };
        std::fs::write(path, bytes).map_err(|source| Error::Io {
            path: path.to_path_buf(),
            source,
        })
    }
}

fn marker_radius_px(s: f64) -> f64 {
    (0.15 * s).clamp(4.0, 12.0)
}

/// A number for SVG: two decimals, no trailing zeros.
fn f(v: f64) -> String {
    let s = format!("{v:.2}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" { "0".into() } else { s.to_string() }
}

fn hex(c: [u8; 3]) -> String {
    format!("#{:02x}{:02x}{:02x}", c[0], c[1], c[2])
}

fn xml_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

fn encode_png(data: &[u8], w: u32, h: u32, colour: image::ExtendedColorType) -> Result<Vec<u8>> {
    use image::ImageEncoder as _;
    let mut out = Vec::new();
    image::codecs::png::PngEncoder::new(&mut out)
        .write_image(data, w, h, colour)
        .map_err(|e| Error::Geometry(format!("cannot encode the PNG: {e}")))?;
    Ok(out)
}

/// The grid as a greyscale PNG, one pixel per cell, top row first.
fn grid_png(g: &OccupancyGrid) -> Result<Vec<u8>> {
    let (w, h) = (g.width(), g.height());
    let mut data = Vec::with_capacity(w * h);
    for row in g.cells().chunks_exact(w.max(1)).rev() {
        data.extend(row.iter().map(|c| match c {
            Cell::Free => FREE[0],
            Cell::Occupied => OCCUPIED[0],
            Cell::Unknown => UNKNOWN[0],
        }));
    }
    encode_png(&data, w as u32, h as u32, image::ExtendedColorType::L8)
}

/// Base64 with the standard alphabet and `=` padding (RFC 4648 §4), as
/// data URIs want it.
pub fn base64(bytes: &[u8]) -> String {
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for chunk in bytes.chunks(3) {
        let b = [chunk[0], *chunk.get(1).unwrap_or(&0), *chunk.get(2).unwrap_or(&0)];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        for k in 0..4 {
            if k <= chunk.len() {
                out.push(A[(n >> (18 - 6 * k)) as usize & 63] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

/// Simple anti-aliased drawing on an RGB image (pixel centres at +0.5).
struct Canvas {
    img: image::RgbImage,
}

impl Canvas {
    fn blend(&mut self, x: i64, y: i64, c: [u8; 3], alpha: f64) {
        if x < 0
            || y < 0
            || x >= i64::from(self.img.width())
            || y >= i64::from(self.img.height())
            || alpha <= 0.0
        {
            return;
        }
        let a = alpha.min(1.0);
        let p = self.img.get_pixel_mut(x as u32, y as u32);
        for (v, &target) in p.0.iter_mut().zip(&c) {
            *v = (f64::from(*v) * (1.0 - a) + f64::from(target) * a).round() as u8;
        }
    }

    /// Calls `cover(px, py)` (coverage in 0..1 at the pixel centre) over a box.
    fn shade(
        &mut self,
        lo: (f64, f64),
        hi: (f64, f64),
        c: [u8; 3],
        alpha: f64,
        cover: impl Fn(f64, f64) -> f64,
    ) {
        let (w, h) = (f64::from(self.img.width()), f64::from(self.img.height()));
        let (x0, x1) = (lo.0.floor().max(0.0), hi.0.ceil().min(w));
        let (y0, y1) = (lo.1.floor().max(0.0), hi.1.ceil().min(h));
        if !(x0 < x1 && y0 < y1) {
            return;
        }
        for y in y0 as i64..y1 as i64 {
            for x in x0 as i64..x1 as i64 {
                let k = cover(x as f64 + 0.5, y as f64 + 0.5);
                self.blend(x, y, c, k * alpha);
            }
        }
    }

    fn line(&mut self, a: (f64, f64), b: (f64, f64), width: f64, c: [u8; 3], alpha: f64) {
        let half = width / 2.0;
        let (dx, dy) = (b.0 - a.0, b.1 - a.1);
        let len2 = dx * dx + dy * dy;
        let pad = half + 1.0;
        self.shade(
            (a.0.min(b.0) - pad, a.1.min(b.1) - pad),
            (a.0.max(b.0) + pad, a.1.max(b.1) + pad),
            c,
            alpha,
            |x, y| {
                let t = if len2 > 0.0 {
                    (((x - a.0) * dx + (y - a.1) * dy) / len2).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                let d = (x - a.0 - t * dx).hypot(y - a.1 - t * dy);
                (half + 0.5 - d).clamp(0.0, 1.0)
            },
        );
    }

    fn disc(&mut self, centre: (f64, f64), r: f64, c: [u8; 3], alpha: f64) {
        let pad = r + 1.0;
        self.shade(
            (centre.0 - pad, centre.1 - pad),
            (centre.0 + pad, centre.1 + pad),
            c,
            alpha,
            |x, y| (r + 0.5 - (x - centre.0).hypot(y - centre.1)).clamp(0.0, 1.0),
        );
    }

    fn ring(&mut self, centre: (f64, f64), r: f64, width: f64, c: [u8; 3]) {
        let pad = r + width + 1.0;
        self.shade(
            (centre.0 - pad, centre.1 - pad),
            (centre.0 + pad, centre.1 + pad),
            c,
            1.0,
            |x, y| (width / 2.0 + 0.5 - ((x - centre.0).hypot(y - centre.1) - r).abs()).clamp(0.0, 1.0),
        );
    }

    fn rect(&mut self, lo: (f64, f64), hi: (f64, f64), c: [u8; 3]) {
        self.shade(lo, hi, c, 1.0, |_, _| 1.0);
    }

    /// Text with its top-left corner at (x, y), glyphs scaled ×2.
    fn text(&mut self, x: f64, y: f64, text: &str, c: [u8; 3]) {
        let (x0, y0) = (x.round() as i64, y.round() as i64);
        for (n, ch) in text.chars().enumerate() {
            let gx = x0 + n as i64 * ((font::GLYPH_W as i64 + 1) * 2);
            for (row, bits) in font::glyph(ch).iter().enumerate() {
                for (col, &on) in bits.iter().enumerate() {
                    if on {
                        for (ddx, ddy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                            self.blend(gx + col as i64 * 2 + ddx, y0 + row as i64 * 2 + ddy, c, 1.0);
                        }
                    }
                }
            }
        }
    }
}

/// A marker at `at` (world frame) into the SVG document `s`.
fn svg_marker(s: &mut String, v: &View, at: Vec2, kind: &MarkerKind) {
    let (x, y) = v.px(at);
    let r = marker_radius_px(v.s);
    let _ = match kind {
        MarkerKind::Start => writeln!(
            s,
            "<circle cx=\"{}\" cy=\"{}\" r=\"{}\" fill=\"#2ca02c\" stroke=\"white\"/>",
            f(x),
            f(y),
            f(r)
        ),
        MarkerKind::Goal => writeln!(
            s,
            "<g stroke=\"#d62728\" stroke-width=\"2\" fill=\"none\"><circle cx=\"{x}\" cy=\"{y}\" \
             r=\"{r}\"/><path d=\"M{a} {b}L{c} {d}M{a} {d}L{c} {b}\"/></g>",
            x = f(x),
            y = f(y),
            r = f(r),
            a = f(x - r * 0.6),
            b = f(y - r * 0.6),
            c = f(x + r * 0.6),
            d = f(y + r * 0.6)
        ),
        MarkerKind::Point => writeln!(
            s,
            "<rect x=\"{}\" y=\"{}\" width=\"{w}\" height=\"{w}\" fill=\"#1f77b4\"/>",
            f(x - r * 0.5),
            f(y - r * 0.5),
            w = f(r)
        ),
        MarkerKind::Square(rgb) => writeln!(
            s,
            "<rect x=\"{}\" y=\"{}\" width=\"{w}\" height=\"{w}\" fill=\"{}\"/>",
            f(x - r * 0.5),
            f(y - r * 0.5),
            hex(*rgb),
            w = f(r)
        ),
        MarkerKind::Ring(rgb) => writeln!(
            s,
            "<g stroke=\"{c}\" stroke-width=\"2\" fill=\"none\"><circle cx=\"{x}\" cy=\"{y}\" \
             r=\"{r}\"/><circle cx=\"{x}\" cy=\"{y}\" r=\"{d}\" fill=\"{c}\"/></g>",
            c = hex(*rgb),
            x = f(x),
            y = f(y),
            r = f(r),
            d = f(r * 0.25)
        ),
    };
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::CellIndex;

    #[test]
    fn base64_matches_the_rfc_examples() {
        for (plain, coded) in [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ] {
            assert_eq!(base64(plain.as_bytes()), coded);
        }
    }

    #[test]
    fn png_pixels_follow_the_grid_with_y_up() {
        let mut g = OccupancyGrid::new(4, 3, 1.0, Pose::default());
        g.set(CellIndex { i: 0, j: 2 }, Cell::Occupied); // top-left
        g.set(CellIndex { i: 3, j: 0 }, Cell::Unknown); // bottom-right
        let mut p = Picture::new(&g);
        p.scale(2.0);
        let img = p.to_png().unwrap();
        assert_eq!(img.dimensions(), (8, 6));
        assert_eq!(img.get_pixel(0, 0).0, OCCUPIED);
        assert_eq!(img.get_pixel(7, 5).0, UNKNOWN);
        assert_eq!(img.get_pixel(3, 3).0, FREE);
    }

    #[test]
    fn same_picture_same_bytes_and_labels_in_the_legend() {
        let g = OccupancyGrid::new(50, 40, 0.1, Pose::new(1.0, 2.0, 0.3));
        let poses = [
            Pose::new(2.0, 3.0, 0.0),
            Pose::new(3.0, 4.0, 0.0),
            Pose::new(4.0, 4.5, 0.0),
        ];
        let build = || {
            let mut p = Picture::new(&g);
            p.trajectory(&poses, Some(&["goal <seeking>", "contour", "contour"]))
                .robot(poses[2], 0.3)
                .ray(Vec2::new(4.0, 4.5), Vec2::new(5.0, 4.0))
                .person(Vec2::new(3.0, 3.0), 0.25)
                .marker(poses[0].position(), MarkerKind::Start)
                .marker(poses[2].position(), MarkerKind::Goal)
                .marker(Vec2::new(2.5, 4.0), MarkerKind::Point)
                .text(Vec2::new(2.0, 5.0), "run 7");
            (p.to_svg().unwrap(), p.to_png().unwrap())
        };
        let (svg, png) = build();
        let (svg2, png2) = build();
        assert_eq!(svg, svg2);
        assert_eq!(png, png2);
        assert!(
            svg.contains("goal &lt;seeking&gt;") && svg.contains(">contour<"),
            "{svg}"
        );
        assert!(svg.contains("rotate(-17.19)"), "the map is turned by 0.3 rad");
        assert_eq!(
            svg.matches("<polyline").count(),
            2,
            "one polyline per run of a label"
        );
    }

    #[test]
    fn crop_scale_and_format_errors() {
        let g = OccupancyGrid::new(100, 100, 0.05, Pose::default());
        let mut p = Picture::new(&g);
        assert_eq!(
            p.to_png().unwrap().dimensions(),
            (600, 600),
            "default: 6 px per cell"
        );
        p.crop(Vec2::new(1.0, 1.0), Vec2::new(2.0, 1.5)).scale(100.0);
        assert_eq!(p.to_png().unwrap().dimensions(), (100, 50));
        p.scale(0.0);
        assert!(
            p.to_png()
                .unwrap_err()
                .to_string()
                .contains("must be finite and > 0")
        );
        p.scale(1e9);
        assert!(p.to_svg().unwrap_err().to_string().contains("too large"));
        let e = Picture::new(&g).save("picture.gif").unwrap_err().to_string();
        assert!(e.contains("use .png or .svg"), "{e}");
    }
}
