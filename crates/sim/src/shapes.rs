//! Worlds described by shapes — rectangles, circles, polygons and thick wall
//! segments — rasterised to an occupancy grid at a chosen resolution.
//!
//! The description deserialises from a scenario's `[world]` table (unknown
//! keys are errors). All lengths are metres in the world frame, angles
//! degrees counter-clockwise:
//!
//! ```toml
//! [world]
//! width_m = 10.0
//! height_m = 6.0
//! resolution_m = 0.05      # default 0.05
//! origin = [0.0, 0.0]      # world position of the lower-left corner; default [0, 0]
//! walls = true             # outer walls inside the border; default false
//! wall_thickness_m = 0.1   # default: one cell
//!
//! [[world.rect]]           # corner (x, y), size w × h, turned by angle_deg about the corner
//! x = 2.0
//! y = 0.0
//! w = 0.2
//! h = 3.0
//! angle_deg = 0.0          # default 0
//!
//! [[world.circle]]         # centre (x, y), radius r
//! x = 5.0
//! y = 3.0
//! r = 0.4
//!
//! [[world.polygon]]        # vertices in order (even-odd fill if it crosses itself)
//! points = [[7.0, 1.0], [9.0, 1.0], [8.0, 2.5]]
//!
//! [[world.segment]]        # wall from → to, thickness across, square ends
//! from = [1.0, 5.0]
//! to = [6.0, 5.0]
//! thickness = 0.1
//! ```
//!
//! ```
//! let spec: sim::shapes::WorldSpec = toml::from_str(
//!     "width_m = 2.0\nheight_m = 1.0\nresolution_m = 0.1\n[[rect]]\nx = 0.5\ny = 0.0\nw = 1.0\nh = 0.5\n",
//! ).unwrap();
//! let grid = spec.rasterise().unwrap();
//! assert_eq!((grid.width(), grid.height()), (20, 10));
//! assert_eq!(grid.counts().occupied, 50);
//! ```
//!
//! # Rasterisation rule
//!
//! A cell is occupied when a shape covers part of its interior: precisely,
//! when the closed shape meets the cell's square shrunk by 1 nm on every
//! side. So
//!
//! * shapes that only touch a cell along its border leave it free: a 1 m
//!   square aligned with a 0.1 m grid fills exactly 100 cells;
//! * anything thinner than a cell still blocks every cell it passes through
//!   (conservative): a 1 cm wall on a 5 cm grid is a line of occupied cells,
//!   never a gap.
//!
//! Polygons (rectangles and segments become polygons) are filled in two
//! passes: every edge marks the cells it crosses (clipped row by row), then
//! cells whose centre is inside (even-odd rule) are filled; a cell that no
//! edge crosses lies wholly inside or wholly outside, so its centre decides.
//! Circles: a cell is occupied when its shrunk square's nearest point to the
//! centre is within the radius. Cost: `O(cells covered + rows × edges)`.

use robot::{Pose, Vec2};

use crate::error::{Error, Result};
use crate::grid::{Cell, OccupancyGrid};

/// How far inside a cell's border a shape must reach to occupy it, metres.
const INSET_M: f64 = 1e-9;

/// Largest grid built from shapes, in cells.
const MAX_CELLS: usize = 200_000_000;

/// A world made of shapes: the `[world]` table of a scenario.
#[derive(Debug, Clone, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WorldSpec {
    /// Width (x), metres; > 0.
    pub width_m: f64,
    /// Height (y), metres; > 0.
    pub height_m: f64,
    /// Side of a cell, metres; > 0. Default 0.05.
    #[serde(default = "default_resolution")]
    pub resolution_m: f64,
    /// World position of the lower-left corner, metres. Default `[0, 0]`.
    #[serde(default)]
    pub origin: [f64; 2],
    /// Outer walls along the inside of the border. Default false (outside
    /// the grid counts as blocked anyway; walls make it visible).
    #[serde(default)]
    pub walls: bool,
    /// Thickness of the outer walls, metres. Default: one cell.
    #[serde(default)]
    pub wall_thickness_m: Option<f64>,
    /// Rectangles (`[[world.rect]]`).
    #[serde(default, rename = "rect")]
    pub rects: Vec<RectSpec>,
    /// Circles (`[[world.circle]]`).
    #[serde(default, rename = "circle")]
    pub circles: Vec<CircleSpec>,
    /// Polygons (`[[world.polygon]]`).
    #[serde(default, rename = "polygon")]
    pub polygons: Vec<PolygonSpec>,
    /// Wall segments (`[[world.segment]]`).
    #[serde(default, rename = "segment")]
    pub segments: Vec<SegmentSpec>,
}

fn default_resolution() -> f64 {
    0.05
}

/// A rectangle: corner `(x, y)`, size `w × h`, turned by `angle_deg` about
/// that corner (so the other corners are `(x, y) + R(angle) · (w, 0)`, etc.).
#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RectSpec {
    /// Corner x, metres.
    pub x: f64,
    /// Corner y, metres.
    pub y: f64,
    /// Width along the rectangle's own x axis, metres; > 0.
    pub w: f64,
    /// Height along its own y axis, metres; > 0.
    pub h: f64,
    /// Rotation about the corner, degrees counter-clockwise. Default 0.
    #[serde(default)]
    pub angle_deg: f64,
}

/// A disc: centre `(x, y)`, radius `r`.
#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CircleSpec {
    /// Centre x, metres.
    pub x: f64,
    /// Centre y, metres.
    pub y: f64,
    /// Radius, metres; > 0.
    pub r: f64,
}

/// A polygon, vertices in order (either orientation); filled by the
/// even-odd rule if it crosses itself.
#[derive(Debug, Clone, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PolygonSpec {
    /// Vertices `[x, y]`, metres; at least 3, enclosing a non-zero area.
    pub points: Vec<[f64; 2]>,
}

/// A straight wall: from `from` to `to`, `thickness` across, with square
/// ends (extended by half the thickness, so walls that meet at an end join
/// without a notch).
#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SegmentSpec {
    /// Start `[x, y]`, metres.
    pub from: [f64; 2],
    /// End `[x, y]`, metres; not equal to `from`.
    pub to: [f64; 2],
    /// Thickness, metres; > 0.
    pub thickness: f64,
}

impl WorldSpec {
    /// An empty world of `width_m × height_m` at `resolution_m`, lower-left
    /// corner at the world origin, no walls.
    pub fn new(width_m: f64, height_m: f64, resolution_m: f64) -> WorldSpec {
        WorldSpec {
            width_m,
            height_m,
            resolution_m,
            origin: [0.0, 0.0],
            walls: false,
            wall_thickness_m: None,
            rects: Vec::new(),
            circles: Vec::new(),
            polygons: Vec::new(),
            segments: Vec::new(),
        }
    }

    /// Grid size in cells: `size / resolution`, rounded up unless within
    /// 1e-6 of a whole number.
    fn cells_along(size_m: f64, resolution_m: f64) -> usize {
        let n = size_m / resolution_m;
        if (n - n.round()).abs() < 1e-6 {
            n.round().max(1.0) as usize
        } else {
            n.ceil() as usize
        }
    }

    /// Checks every number; the error names the offending field.
    pub fn validate(&self) -> Result<()> {
        positive("world.width_m", self.width_m)?;
        positive("world.height_m", self.height_m)?;
        positive("world.resolution_m", self.resolution_m)?;
        finite("world.origin", self.origin[0])?;
        finite("world.origin", self.origin[1])?;
        if let Some(t) = self.wall_thickness_m {
            positive("world.wall_thickness_m", t)?;
        }
        let (w, h) = (
            Self::cells_along(self.width_m, self.resolution_m),
            Self::cells_along(self.height_m, self.resolution_m),
        );
        if w.checked_mul(h).is_none_or(|n| n > MAX_CELLS) {
            return Err(Error::Geometry(format!(
                "world of {} × {} m at {} m per cell needs {w} × {h} cells, more than {MAX_CELLS}",
                self.width_m, self.height_m, self.resolution_m
            )));
        }
        crate::grid::check_resolution("world.resolution_m", self.resolution_m)?;
        let origin = Pose::new(self.origin[0], self.origin[1], 0.0);
        OccupancyGrid::check_geometry(w, h, self.resolution_m, origin)?;
        for (k, r) in self.rects.iter().enumerate() {
            finite(&format!("world.rect[{k}].x"), r.x)?;
            finite(&format!("world.rect[{k}].y"), r.y)?;
            positive(&format!("world.rect[{k}].w"), r.w)?;
            positive(&format!("world.rect[{k}].h"), r.h)?;
            finite(&format!("world.rect[{k}].angle_deg"), r.angle_deg)?;
        }
        for (k, c) in self.circles.iter().enumerate() {
            finite(&format!("world.circle[{k}].x"), c.x)?;
            finite(&format!("world.circle[{k}].y"), c.y)?;
            positive(&format!("world.circle[{k}].r"), c.r)?;
        }
        for (k, p) in self.polygons.iter().enumerate() {
            for q in &p.points {
                finite(&format!("world.polygon[{k}].points"), q[0])?;
                finite(&format!("world.polygon[{k}].points"), q[1])?;
            }
            if p.points.len() < 3 {
                return Err(Error::Geometry(format!(
                    "world.polygon[{k}] has {} points; a polygon needs at least 3",
                    p.points.len()
                )));
            }
            let pts: Vec<Vec2> = p.points.iter().map(|q| Vec2::new(q[0], q[1])).collect();
            if signed_area(&pts).abs() < 1e-12 {
                return Err(Error::Geometry(format!(
                    "world.polygon[{k}] is degenerate: its points enclose no area"
                )));
            }
        }
        for (k, s) in self.segments.iter().enumerate() {
            for v in s.from.iter().chain(&s.to) {
                finite(&format!("world.segment[{k}] end"), *v)?;
            }
            positive(&format!("world.segment[{k}].thickness"), s.thickness)?;
            if s.from == s.to {
                return Err(Error::Geometry(format!(
                    "world.segment[{k}] is degenerate: from and to are the same point"
                )));
            }
        }
        Ok(())
    }

    /// The occupancy grid of this world (see the module docs for the rule).
    pub fn rasterise(&self) -> Result<OccupancyGrid> {
        self.validate()?;
        let res = self.resolution_m;
        let (w, h) = (
            Self::cells_along(self.width_m, res),
            Self::cells_along(self.height_m, res),
        );
        let mut r = Raster {
            w,
            h,
            res,
            origin: Vec2::new(self.origin[0], self.origin[1]),
            cells: vec![Cell::Free; w * h],
        };
        if self.walls {
            let t = self.wall_thickness_m.unwrap_or(res);
            let (o, wm, hm) = (r.origin, w as f64 * res, h as f64 * res);
            for (x, y, rw, rh) in [
                (0.0, 0.0, wm, t),
                (0.0, hm - t, wm, t),
                (0.0, 0.0, t, hm),
                (wm - t, 0.0, t, hm),
            ] {
                r.polygon(&rect_points(o.x + x, o.y + y, rw, rh, 0.0));
            }
        }
        for s in &self.rects {
            r.polygon(&rect_points(s.x, s.y, s.w, s.h, s.angle_deg.to_radians()));
        }
        for p in &self.polygons {
            let pts: Vec<Vec2> = p.points.iter().map(|q| Vec2::new(q[0], q[1])).collect();
            r.polygon(&pts);
        }
        for s in &self.segments {
            r.polygon(&segment_points(s));
        }
        for c in &self.circles {
            r.circle(Vec2::new(c.x, c.y), c.r);
        }
        OccupancyGrid::from_cells(w, h, res, Pose::new(r.origin.x, r.origin.y, 0.0), r.cells)
    }
}

fn finite(what: &str, value: f64) -> Result<()> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(Error::InvalidValue {
            what: what.to_string(),
            requirement: "a finite number",
            value,
        })
    }
}

fn positive(what: &str, value: f64) -> Result<()> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(Error::InvalidValue {
            what: what.to_string(),
            requirement: "finite and > 0",
            value,
        })
    }
}

/// Signed area of a polygon, m² (positive counter-clockwise).
fn signed_area(p: &[Vec2]) -> f64 {
    let n = p.len();
    (0..n)
        .map(|k| {
            let (a, b) = (p[k], p[(k + 1) % n]);
            a.x * b.y - b.x * a.y
        })
        .sum::<f64>()
        / 2.0
}

fn rect_points(x: f64, y: f64, w: f64, h: f64, angle_rad: f64) -> Vec<Vec2> {
    let pose = Pose {
        x_m: x,
        y_m: y,
        theta_rad: angle_rad,
    };
    [(0.0, 0.0), (w, 0.0), (w, h), (0.0, h)]
        .iter()
        .map(|&(u, v)| {
            if angle_rad == 0.0 {
                Vec2::new(x + u, y + v)
            } else {
                pose.transform(Vec2::new(u, v))
            }
        })
        .collect()
}

fn segment_points(s: &SegmentSpec) -> Vec<Vec2> {
    let (a, b) = (Vec2::new(s.from[0], s.from[1]), Vec2::new(s.to[0], s.to[1]));
    let d = b - a;
    let u = d.scale(1.0 / d.norm());
    let half = s.thickness / 2.0;
    let (along, across) = (u.scale(half), Vec2::new(-u.y, u.x).scale(half));
    let (a, b) = (a - along, b + along);
    vec![a - across, b - across, b + across, a + across]
}

/// A grid being filled, in world coordinates without rotation.
struct Raster {
    w: usize,
    h: usize,
    res: f64,
    origin: Vec2,
    cells: Vec<Cell>,
}

impl Raster {
    fn mark(&mut self, i: i64, j: i64) {
        if i >= 0 && j >= 0 && (i as usize) < self.w && (j as usize) < self.h {
            self.cells[j as usize * self.w + i as usize] = Cell::Occupied;
        }
    }

    /// Index range of cells along one axis that a closed interval `[lo, hi]`
    /// (grid coordinates, metres) meets inside their shrunk extent.
    fn span(&self, lo: f64, hi: f64, n: usize) -> std::ops::RangeInclusive<i64> {
        let r = self.res;
        let mut a = (lo / r).floor() as i64 - 1;
        let mut b = (hi / r).floor() as i64 + 1;
        while a <= b && (a + 1) as f64 * r - INSET_M < lo {
            a += 1;
        }
        while b >= a && (b as f64 * r + INSET_M) > hi {
            b -= 1;
        }
        a.max(0)..=b.min(n as i64 - 1)
    }

    fn polygon(&mut self, world: &[Vec2]) {
        let pts: Vec<Vec2> = world.iter().map(|&p| p - self.origin).collect();
        let n = pts.len();
        let r = self.res;
        // Edges: the cells each crosses, clipped to every row's shrunk band.
        for k in 0..n {
            let (a, b) = (pts[k], pts[(k + 1) % n]);
            let rows = self.span(a.y.min(b.y), a.y.max(b.y), self.h);
            for j in rows {
                let (y0, y1) = (j as f64 * r + INSET_M, (j + 1) as f64 * r - INSET_M);
                let (xa, xb) = if a.y == b.y {
                    (a.x.min(b.x), a.x.max(b.x))
                } else {
                    let at = |y: f64| a.x + (b.x - a.x) * ((y - a.y) / (b.y - a.y));
                    let (lo, hi) = (y0.max(a.y.min(b.y)), y1.min(a.y.max(b.y)));
                    if lo > hi {
                        continue;
                    }
                    let (p, q) = (at(lo), at(hi));
                    (p.min(q), p.max(q))
                };
                for i in self.span(xa, xb, self.w) {
                    self.mark(i, j);
                }
            }
        }
        // Interior: cells whose centre is inside, row by row (even-odd).
        let (ymin, ymax) = pts
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
                (lo.min(p.y), hi.max(p.y))
            });
        let mut xs = Vec::new();
        for j in self.span(ymin, ymax, self.h) {
            let yc = (j as f64 + 0.5) * r;
            xs.clear();
            for k in 0..n {
                let (a, b) = (pts[k], pts[(k + 1) % n]);
                if (a.y > yc) != (b.y > yc) {
                    xs.push(a.x + (b.x - a.x) * ((yc - a.y) / (b.y - a.y)));
                }
            }
            xs.sort_by(f64::total_cmp);
            for pair in xs.chunks_exact(2) {
                // Centres (i + 0.5) r within [x0, x1].
                let i0 = ((pair[0] / r) - 0.5).ceil().max(0.0) as i64;
                let i1 = ((pair[1] / r) - 0.5).floor().min(self.w as f64 - 1.0) as i64;
                for i in i0..=i1 {
                    self.mark(i, j);
                }
            }
        }
    }

    fn circle(&mut self, world_center: Vec2, radius_m: f64) {
        let c = world_center - self.origin;
        let r = self.res;
        for j in self.span(c.y - radius_m, c.y + radius_m, self.h) {
            let (y0, y1) = (j as f64 * r + INSET_M, (j + 1) as f64 * r - INSET_M);
            let dy = c.y.clamp(y0, y1) - c.y;
            for i in self.span(c.x - radius_m, c.x + radius_m, self.w) {
                let (x0, x1) = (i as f64 * r + INSET_M, (i + 1) as f64 * r - INSET_M);
                let dx = c.x.clamp(x0, x1) - c.x;
                if dx * dx + dy * dy <= radius_m * radius_m {
                    self.mark(i, j);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::CellIndex;

    fn world(toml_text: &str) -> WorldSpec {
        toml::from_str(toml_text).unwrap()
    }

    fn occupied(g: &OccupancyGrid) -> usize {
        g.counts().occupied
    }

    #[test]
    fn aligned_squares_fill_exactly_their_cells() {
        let mut w = WorldSpec::new(5.0, 5.0, 0.1);
        w.rects.push(RectSpec {
            x: 1.0,
            y: 1.0,
            w: 1.0,
            h: 1.0,
            angle_deg: 0.0,
        });
        let g = w.rasterise().unwrap();
        assert_eq!((g.width(), g.height()), (50, 50));
        assert_eq!(occupied(&g), 100);
        assert!(g.blocked(CellIndex { i: 10, j: 10 }) && g.blocked(CellIndex { i: 19, j: 19 }));
        assert!(!g.blocked(CellIndex { i: 20, j: 15 }) && !g.blocked(CellIndex { i: 9, j: 15 }));
        // Shifted by half a cell it touches 11 × 11 cells.
        w.rects[0].x = 1.05;
        w.rects[0].y = 1.05;
        assert_eq!(occupied(&w.rasterise().unwrap()), 121);
    }

    #[test]
    fn thin_walls_never_vanish() {
        // A 1 cm wall on a 5 cm grid, on a cell boundary (x = 1.0): both
        // neighbouring columns, 2 m + 1 cm long with its square ends.
        let mut w = WorldSpec::new(3.0, 3.0, 0.05);
        w.segments.push(SegmentSpec {
            from: [1.0, 0.5],
            to: [1.0, 2.5],
            thickness: 0.01,
        });
        let g = w.rasterise().unwrap();
        assert_eq!(occupied(&g), 2 * 42);
        // Inside one column: one column.
        w.segments[0] = SegmentSpec {
            from: [1.02, 0.5],
            to: [1.02, 2.5],
            thickness: 0.01,
        };
        let g = w.rasterise().unwrap();
        assert_eq!(occupied(&g), 42);
        // A diagonal 1 cm wall is a connected staircase: a ray across it hits.
        w.segments[0] = SegmentSpec {
            from: [0.2, 0.3],
            to: [2.7, 2.9],
            thickness: 0.01,
        };
        let g = w.rasterise().unwrap();
        for k in 0..40 {
            let y = 0.6 + k as f64 * 0.05;
            assert!(crate::raycast::cast(&g, Vec2::new(2.9, y), std::f64::consts::PI, 10.0).unwrap() < 2.9);
        }
    }

    #[test]
    fn circles_cover_cells_that_reach_inside() {
        // Centre on a grid corner, radius 1 m, 0.1 m cells: in each quadrant
        // cell (m, n) is occupied when its nearest corner is inside: m² + n² < 100.
        let mut w = WorldSpec::new(4.0, 4.0, 0.1);
        w.circles.push(CircleSpec {
            x: 2.0,
            y: 2.0,
            r: 1.0,
        });
        let per_quadrant = (0..10)
            .flat_map(|m| (0..10).map(move |n| (m, n)))
            .filter(|(m, n)| m * m + n * n < 100)
            .count();
        assert_eq!(occupied(&w.rasterise().unwrap()), 4 * per_quadrant);
    }

    #[test]
    fn rotated_rectangles_and_polygons() {
        // A 45° square of side √2 about (2, 1): a diamond with corners
        // (2, 1), (3, 2), (2, 3), (1, 2).
        let mut w = WorldSpec::new(4.0, 4.0, 0.5);
        w.rects.push(RectSpec {
            x: 2.0,
            y: 1.0,
            w: 2f64.sqrt(),
            h: 2f64.sqrt(),
            angle_deg: 45.0,
        });
        let g = w.rasterise().unwrap();
        // The diamond meets the interior of the 4 × 4 cells of [1, 3]² except
        // the 4 corner cells: 12.
        assert_eq!(occupied(&g), 12);
        // The same as a polygon.
        let mut p = WorldSpec::new(4.0, 4.0, 0.5);
        p.polygons.push(PolygonSpec {
            points: vec![[2.0, 1.0], [3.0, 2.0], [2.0, 3.0], [1.0, 2.0]],
        });
        assert_eq!(p.rasterise().unwrap(), g);
        // A concave L, aligned: 3 + 1 cells of 1 m.
        let mut l = WorldSpec::new(4.0, 4.0, 1.0);
        l.polygons.push(PolygonSpec {
            points: vec![
                [0.0, 0.0],
                [3.0, 0.0],
                [3.0, 1.0],
                [1.0, 1.0],
                [1.0, 2.0],
                [0.0, 2.0],
            ],
        });
        let g = l.rasterise().unwrap();
        assert_eq!(occupied(&g), 4);
        assert!(!g.blocked(CellIndex { i: 1, j: 1 }));
    }

    #[test]
    fn outer_walls_and_origin() {
        let w =
            world("width_m = 2.0\nheight_m = 1.0\nresolution_m = 0.1\norigin = [-1.0, 5.0]\nwalls = true\n");
        let g = w.rasterise().unwrap();
        assert_eq!(occupied(&g), 20 * 10 - 18 * 8);
        assert_eq!(g.origin(), Pose::new(-1.0, 5.0, 0.0));
        assert!(g.blocked_at(Vec2::new(-0.95, 5.5)) && !g.blocked_at(Vec2::new(-0.85, 5.5)));
        let thick = world(
            "width_m = 2.0\nheight_m = 1.0\nresolution_m = 0.1\nwalls = true\nwall_thickness_m = 0.2\n",
        );
        assert_eq!(occupied(&thick.rasterise().unwrap()), 20 * 10 - 16 * 6);
    }

    #[test]
    fn scenario_tables_parse_and_refuse_unknown_keys() {
        #[derive(serde::Deserialize)]
        struct Scenario {
            world: WorldSpec,
        }
        let s: Scenario = toml::from_str(
            r#"
            [world]
            width_m = 10.0
            height_m = 6.0
            walls = true
            [[world.rect]]
            x = 2.0
            y = 0.0
            w = 0.2
            h = 3.0
            angle_deg = 10.0
            [[world.circle]]
            x = 5.0
            y = 3.0
            r = 0.4
            [[world.polygon]]
            points = [[7.0, 1.0], [9.0, 1.0], [8.0, 2.5]]
            [[world.segment]]
            from = [1.0, 5.0]
            to = [6.0, 5.0]
            thickness = 0.1
            "#,
        )
        .unwrap();
        assert_eq!(s.world.resolution_m, 0.05);
        assert_eq!(
            (
                s.world.rects.len(),
                s.world.circles.len(),
                s.world.polygons.len(),
                s.world.segments.len()
            ),
            (1, 1, 1, 1)
        );
        let g = s.world.rasterise().unwrap();
        assert_eq!((g.width(), g.height()), (200, 120));
        let e = toml::from_str::<WorldSpec>(
            "width_m = 1.0\nheight_m = 1.0\n[[rect]]\nx = 0.0\ny = 0.0\nw = 1.0\nh = 1.0\nangle = 3.0\n",
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("unknown field `angle`"), "{e}");
        let e = toml::from_str::<WorldSpec>("width_m = 1.0\nheight_m = 1.0\nwall = true\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("unknown field `wall`"), "{e}");
    }

    #[test]
    fn invalid_worlds_are_refused_with_the_field_named() {
        let cases: Vec<(&str, &str)> = vec![
            (
                "width_m = 1.0\nheight_m = 1.0\nresolution_m = 0.0\n",
                "world.resolution_m must be finite and > 0, got 0",
            ),
            (
                "width_m = -1.0\nheight_m = 1.0\n",
                "world.width_m must be finite and > 0, got -1",
            ),
            (
                "width_m = 1.0\nheight_m = 1.0\n[[rect]]\nx = 0.0\ny = 0.0\nw = -1.0\nh = 1.0\n",
                "world.rect[0].w must be finite and > 0",
            ),
            (
                "width_m = 1.0\nheight_m = 1.0\n[[circle]]\nx = 0.0\ny = 0.0\nr = 0.0\n",
                "world.circle[0].r must be",
            ),
            (
                "width_m = 1.0\nheight_m = 1.0\n[[polygon]]\npoints = [[0.0, 0.0], [1.0, 1.0]]\n",
                "needs at least 3",
            ),
            (
                "width_m = 1.0\nheight_m = 1.0\n[[polygon]]\npoints = [[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]]\n",
                "degenerate",
            ),
            (
                "width_m = 1.0\nheight_m = 1.0\n[[segment]]\nfrom = [0.0, 0.0]\nto = [0.0, 0.0]\nthickness = 0.1\n",
                "degenerate",
            ),
            (
                "width_m = 1.0\nheight_m = 1.0\n[[segment]]\nfrom = [0.0, 0.0]\nto = [1.0, 0.0]\nthickness = 0.0\n",
                "thickness must be",
            ),
            ("width_m = 1e6\nheight_m = 1e6\n", "more than"),
        ];
        for (text, want) in cases {
            let e = world(text).rasterise().unwrap_err().to_string();
            assert!(e.contains(want), "{text}: {e}");
        }
    }
}
