//! Following the negative gradient of the navigation function.
//!
//! K. Konolige (IROS 2000) drives the robot along `−∇N`; ROS `navfn`
//! (`NavFn::calcPath`, `gradCell`) extracts the path the same way, and so
//! does this module:
//!
//! * the gradient at a cell centre is the central difference of `N` along
//!   each axis (one-sided next to an unreachable or lethal neighbour, 0 with
//!   neither neighbour finite); at a lethal or unreachable cell it points
//!   into the cell from each finite neighbour, so `−∇N` pushes away from
//!   obstacles; each cell's gradient is normalised to unit length;
//! * at any point, the gradient is the **bilinear interpolation** of the
//!   four surrounding cell-centre gradients, and the path advances
//!   `step_cells` cells (default 0.5, as navfn's `pathStep`) along its
//!   negative, normalised.
//!
//! Guarantees, checked on every step (navfn too falls back to the best
//! neighbour near obstacles and on oscillation):
//!
//! * a step that leaves the current cell must enter a cell with a strictly
//!   smaller `N` (so finite: never a lethal or unreachable cell), and a
//!   diagonal one only when both cells it cuts past are finite too — the
//!   polyline never crosses a lethal cell;
//! * when the interpolated gradient vanishes, the step is refused, or the
//!   path has stayed [`MAX_STEPS_IN_CELL`] steps in one cell (oscillation
//!   at a ridge), it moves instead to the centre of the allowed neighbour
//!   with the smallest `N`, which is smaller than the current cell's (its
//!   Dijkstra predecessor is a candidate);
//! * so `N` of the current cell decreases at every change of cell and the
//!   path reaches a goal cell (`N = 0`) from any cell with a finite `N`, in
//!   at most `(MAX_STEPS_IN_CELL + 1) ·` (cells reached) steps.
//!
//! The path ends at the goal point (or the goal cell's centre). Each step is
//! `O(1)`.
//!
//! [`descend_settling`] follows the same path on a navigation function
//! computed towards the start
//! ([`NavigationFunction::compute_towards`]): every value it reads, it first
//! has the wavefront settle, so it reads the very values of the whole
//! computation. The descent keeps the last cell gradients it computed (a
//! step reads four, the next steps mostly the same ones).

use robot::{CellIndex, Vec2};

use super::{CostMap, NavigationFunction, PlanningError, Window};

/// Steps allowed inside one cell before moving to its best neighbour.
pub const MAX_STEPS_IN_CELL: usize = 4;

/// Parameters of the gradient descent.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct GradientParams {
    /// Length of a step along the gradient, cells, in (0, 1]. Default 0.5.
    pub step_cells: f64,
}

impl Default for GradientParams {
    fn default() -> Self {
        GradientParams { step_cells: 0.5 }
    }
}

impl GradientParams {
    /// `step_cells` must be a number in (0, 1].
    pub fn validate(&self) -> Result<(), PlanningError> {
        if self.step_cells > 0.0 && self.step_cells <= 1.0 {
            Ok(())
        } else {
            Err(PlanningError::BadParam {
                name: "step_cells",
                value: self.step_cells,
                expected: "a number in (0, 1]",
            })
        }
    }
}

/// What a descent did.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct DescentInfo {
    /// `N` at the start, cost-weighted metres.
    pub start_value: f64,
    /// Steps along the interpolated gradient.
    pub gradient_steps: usize,
    /// Moves to the best neighbour instead.
    pub fallback_steps: usize,
    /// Length of the polyline, metres.
    pub length_m: f64,
}

/// The path from `start` down `N` to the goal, as a polyline in the world
/// frame written into `path` (cleared first; `path[0] == start`, the last
/// point is the goal point, or the goal cell's centre for goal cells).
///
/// Errors: invalid parameters, no goal ([`PlanningError::NoGoal`]: the
/// function was never computed or its computation failed), a non-finite
/// start, [`PlanningError::StartOutsideWindow`],
/// [`PlanningError::Unreachable`] (the start's cell has `N = ∞`: it is
/// lethal or cut off from the goal; the planners tell the two apart with the
/// cost map), [`PlanningError::NoDescent`] if rounding left a cell without a
/// lower neighbour (only with extreme intrinsic costs), and
/// [`PlanningError::Unsettled`] if the descent needs a value a function
/// computed towards a start has not settled ([`descend_settling`] settles
/// it).
pub fn descend(
    nf: &NavigationFunction,
    start: Vec2,
    params: &GradientParams,
    path: &mut Vec<Vec2>,
) -> Result<DescentInfo, PlanningError> {
    descend_up_to(&mut Settled(nf), start, params, path, usize::MAX)
}

/// [`descend`] on a function computed towards a start
/// ([`NavigationFunction::compute_towards`]), settling the values it reads
/// as it goes: every value it reads is final, so the path is the one
/// [`descend`] gives on the complete function, bit for bit. `cost` must be
/// the cost map the function was computed on, unchanged.
///
/// Errors: those of [`descend`] but [`PlanningError::Unsettled`], and
/// [`PlanningError::OtherCostMap`] for a cost map of another window.
pub fn descend_settling(
    nf: &mut NavigationFunction,
    cost: &CostMap,
    start: Vec2,
    params: &GradientParams,
    path: &mut Vec<Vec2>,
) -> Result<DescentInfo, PlanningError> {
    if nf.window().is_some_and(|w| w != cost.window()) {
        return Err(PlanningError::OtherCostMap);
    }
    let mut values = Settling {
        nf,
        costs: cost.padded_costs(),
    };
    descend_up_to(&mut values, start, params, path, usize::MAX)
}

/// The direction to drive from `start`: the unit vector (world frame) of the
/// first step of [`descend`], or zero at the goal point. Errors as
/// [`descend`].
pub fn direction(
    nf: &NavigationFunction,
    start: Vec2,
    params: &GradientParams,
) -> Result<Vec2, PlanningError> {
    let mut path = Vec::with_capacity(2);
    descend_up_to(&mut Settled(nf), start, params, &mut path, 2)?;
    Ok(match path.as_slice() {
        [a, b, ..] if a.dist(*b) > 0.0 => (*b - *a).scale(1.0 / a.dist(*b)),
        _ => Vec2::default(),
    })
}

/// The interpolated `−∇N` at a point, normalised (world frame): `None`
/// outside the window, without a goal, where the interpolated gradient
/// vanishes, or where it needs a value not settled yet (a function computed
/// towards a start).
pub fn descent_direction_at(nf: &NavigationFunction, p: Vec2) -> Option<Vec2> {
    let window = nf.window()?;
    let (x, y) = window.to_window(p);
    if !(x >= 0.0 && y >= 0.0 && x < window.width() as f64 && y < window.height() as f64) {
        return None;
    }
    let g = Field::new(Settled(nf), window).descent(x, y).ok()??;
    let a = window.from_window(x, y);
    let b = window.from_window(x + g.0, y + g.1);
    Some((b - a).scale(1.0 / window.resolution_m()))
}

/// Where the descent reads `N`, by padded cell `(u, v)` (window cell
/// `(u − 1, v − 1)`); every value given is final.
trait Values {
    /// The navigation function.
    fn nf(&self) -> &NavigationFunction;
    /// `N` at padded cell `(u, v)`.
    fn at(&mut self, u: usize, v: usize) -> Result<f64, PlanningError>;
}

impl<V: Values> Values for &mut V {
    fn nf(&self) -> &NavigationFunction {
        (**self).nf()
    }

    #[inline]
    fn at(&mut self, u: usize, v: usize) -> Result<f64, PlanningError> {
        (**self).at(u, v)
    }
}

/// The values already settled; an error for any other.
struct Settled<'a>(&'a NavigationFunction);

impl Values for Settled<'_> {
    fn nf(&self) -> &NavigationFunction {
        self.0
    }

    #[inline]
    fn at(&mut self, u: usize, v: usize) -> Result<f64, PlanningError> {
        self.0.settled_value(u, v).ok_or_else(|| {
            let min = self.0.window().map_or(CellIndex { i: 0, j: 0 }, |w| w.min());
            PlanningError::Unsettled {
                cell: CellIndex {
                    i: min.i + u as i64 - 1,
                    j: min.j + v as i64 - 1,
                },
            }
        })
    }
}

/// Every value, settled on demand.
struct Settling<'a> {
    nf: &'a mut NavigationFunction,
    costs: &'a [f64],
}

impl Values for Settling<'_> {
    fn nf(&self) -> &NavigationFunction {
        self.nf
    }

    #[inline]
    fn at(&mut self, u: usize, v: usize) -> Result<f64, PlanningError> {
        Ok(self.nf.settled_value_with(self.costs, u, v))
    }
}

/// The values of a navigation function and their geometry, in padded
/// coordinates (window cell `(u, v)` is padded cell `(u + 1, v + 1)`).
struct Field<V> {
    values: V,
    pw: usize,
    ph: usize,
    /// The cell gradients last computed, by `(u mod 4, v mod 4)`: a step
    /// of the descent reads the gradients of four cells, the next steps
    /// mostly the same ones (the values they come from are final, so a
    /// gradient never changes).
    cache: [((usize, usize), (f64, f64)); 16],
}

impl<V: Values> Field<V> {
    fn new(values: V, window: Window) -> Field<V> {
        Field {
            values,
            pw: window.width() + 2,
            ph: window.height() + 2,
            cache: [((usize::MAX, usize::MAX), (0.0, 0.0)); 16],
        }
    }

    /// `N` at padded cell `(u, v)`.
    #[inline]
    fn at(&mut self, u: usize, v: usize) -> Result<f64, PlanningError> {
        self.values.at(u, v)
    }

    /// Normalised gradient of `N` at padded cell `(pu, pv)` (module docs);
    /// zero on the padding ring.
    fn cell_gradient(&mut self, pu: usize, pv: usize) -> Result<(f64, f64), PlanningError> {
        let slot = (pu & 3) | (pv & 3) << 2;
        if self.cache[slot].0 == (pu, pv) {
            return Ok(self.cache[slot].1);
        }
        let g = self.compute_cell_gradient(pu, pv)?;
        self.cache[slot] = ((pu, pv), g);
        Ok(g)
    }

    /// [`Field::cell_gradient`], computed.
    fn compute_cell_gradient(&mut self, pu: usize, pv: usize) -> Result<(f64, f64), PlanningError> {
        if pu == 0 || pv == 0 || pu + 1 >= self.pw || pv + 1 >= self.ph {
            return Ok((0.0, 0.0));
        }
        let axis = |lo: f64, c: f64, hi: f64| -> f64 {
            if c.is_finite() {
                match (lo.is_finite(), hi.is_finite()) {
                    (true, true) => 0.5 * (hi - lo),
                    (false, true) => hi - c,
                    (true, false) => c - lo,
                    (false, false) => 0.0,
                }
            } else {
                f64::from(u8::from(lo.is_finite())) - f64::from(u8::from(hi.is_finite()))
            }
        };
        let c = self.at(pu, pv)?;
        let gx = axis(self.at(pu - 1, pv)?, c, self.at(pu + 1, pv)?);
        let gy = axis(self.at(pu, pv - 1)?, c, self.at(pu, pv + 1)?);
        let n = gx.hypot(gy);
        Ok(if n > 0.0 { (gx / n, gy / n) } else { (0.0, 0.0) })
    }

    /// Unit `−∇N` at window point `(x, y)` by bilinear interpolation of the
    /// four surrounding cell-centre gradients; `None` where it vanishes.
    fn descent(&mut self, x: f64, y: f64) -> Result<Option<(f64, f64)>, PlanningError> {
        // Padded coordinates; centres at (pu + 0.5, pv + 0.5).
        let (px, py) = (x + 1.0 - 0.5, y + 1.0 - 0.5);
        let (u0, v0) = (px.floor(), py.floor());
        let (fx, fy) = (px - u0, py - v0);
        let (u0, v0) = (u0 as usize, v0 as usize);
        let g00 = self.cell_gradient(u0, v0)?;
        let g10 = self.cell_gradient(u0 + 1, v0)?;
        let g01 = self.cell_gradient(u0, v0 + 1)?;
        let g11 = self.cell_gradient(u0 + 1, v0 + 1)?;
        let gx = (1.0 - fy) * ((1.0 - fx) * g00.0 + fx * g10.0) + fy * ((1.0 - fx) * g01.0 + fx * g11.0);
        let gy = (1.0 - fy) * ((1.0 - fx) * g00.1 + fx * g10.1) + fy * ((1.0 - fx) * g01.1 + fx * g11.1);
        let n = gx.hypot(gy);
        Ok((n > 1e-9).then(|| (-gx / n, -gy / n)))
    }

    /// Whether the path may move from padded cell `a` to its neighbour
    /// `b`: `N` strictly decreases, and a diagonal move does not cut past
    /// a cell with `N = ∞`.
    fn allowed(&mut self, a: (usize, usize), b: (usize, usize)) -> Result<bool, PlanningError> {
        if self.at(b.0, b.1)? >= self.at(a.0, a.1)? {
            return Ok(false);
        }
        Ok(a.0 == b.0 || a.1 == b.1 || (self.at(b.0, a.1)?.is_finite() && self.at(a.0, b.1)?.is_finite()))
    }
}

/// Smallest distance, in cells, between a path point and its cell's sides.
const INSET: f64 = 1e-6;

/// `t` moved at least [`INSET`] inside the unit interval of `⌊t⌋`.
fn inset(t: f64) -> f64 {
    let f = t.floor();
    t.clamp(f + INSET, f + 1.0 - INSET)
}

/// [`descend`], stopping after `max_points` points (at least 1).
fn descend_up_to<V: Values>(
    values: &mut V,
    start: Vec2,
    params: &GradientParams,
    path: &mut Vec<Vec2>,
    max_points: usize,
) -> Result<DescentInfo, PlanningError> {
    params.validate()?;
    path.clear();
    let nf = values.nf();
    let window = match nf.window() {
        Some(w) if !nf.goal_cells().is_empty() => w,
        _ => return Err(PlanningError::NoGoal),
    };
    let goal = nf.goal();
    let cell = window.cell_of("start", start)?;
    if !window.contains(cell) {
        return Err(PlanningError::StartOutsideWindow { start, cell });
    }
    let mut field = Field::new(values, window);
    // The current cell, in padded coordinates.
    let mut a = (
        (cell.i - window.min().i + 1) as usize,
        (cell.j - window.min().j + 1) as usize,
    );
    let start_value = field.at(a.0, a.1)?;
    if !start_value.is_finite() {
        return Err(PlanningError::Unreachable { start, cell });
    }
    let mut info = DescentInfo {
        start_value,
        ..DescentInfo::default()
    };
    let (mut x, mut y) = window.to_window(start);
    // Work from a point inside the start cell despite rounding.
    let (cu, cv) = ((cell.i - window.min().i) as f64, (cell.j - window.min().j) as f64);
    x = x.clamp(cu + INSET, cu + 1.0 - INSET);
    y = y.clamp(cv + INSET, cv + 1.0 - INSET);
    path.push(start);
    let mut last = start;
    let mut push = |p: Vec2, info: &mut DescentInfo, path: &mut Vec<Vec2>| {
        info.length_m += last.dist(p);
        last = p;
        path.push(p);
    };
    let step = params.step_cells;
    let mut in_cell = 0usize;
    while path.len() < max_points {
        if field.at(a.0, a.1)? == 0.0 {
            // A goal cell: end at the goal point (or the cell's centre).
            let end = goal.unwrap_or_else(|| window.from_window(a.0 as f64 - 0.5, a.1 as f64 - 0.5));
            if end != *path.last().unwrap_or(&start) {
                push(end, &mut info, path);
            }
            break;
        }
        let gradient = if in_cell < MAX_STEPS_IN_CELL {
            field.descent(x, y)?
        } else {
            None
        };
        let mut moved = false;
        if let Some((dx, dy)) = gradient {
            let (nx, ny) = (x + step * dx, y + step * dy);
            // Window point (nx, ny) lies in padded cell (⌊nx⌋ + 1, ⌊ny⌋ + 1);
            // a step of at most one cell stays within the padding ring.
            let b = ((nx.floor() + 1.0) as usize, (ny.floor() + 1.0) as usize);
            if b == a {
                in_cell += 1;
                moved = true;
            } else if field.allowed(a, b)? {
                a = b;
                in_cell = 0;
                moved = true;
            }
            if moved {
                // Keep the point at least INSET from its cell's sides, so that
                // the round trip through world coordinates cannot move it to
                // a neighbouring cell.
                x = inset(nx);
                y = inset(ny);
                info.gradient_steps += 1;
                push(window.from_window(x, y), &mut info, path);
            }
        }
        if !moved {
            // The allowed neighbour with the smallest N (first in this order
            // on ties).
            let (u, v) = a;
            let neighbours = [
                (u + 1, v),
                (u - 1, v),
                (u, v + 1),
                (u, v - 1),
                (u + 1, v + 1),
                (u - 1, v + 1),
                (u + 1, v - 1),
                (u - 1, v - 1),
            ];
            let mut best: Option<((usize, usize), f64)> = None;
            for b in neighbours {
                if field.allowed(a, b)? {
                    let nb = field.at(b.0, b.1)?;
                    if best.is_none_or(|(_, o)| nb < o) {
                        best = Some((b, nb));
                    }
                }
            }
            let Some((b, _)) = best else {
                let min = window.min();
                return Err(PlanningError::NoDescent {
                    cell: CellIndex {
                        i: min.i + a.0 as i64 - 1,
                        j: min.j + a.1 as i64 - 1,
                    },
                });
            };
            a = b;
            in_cell = 0;
            x = a.0 as f64 - 0.5;
            y = a.1 as f64 - 0.5;
            info.fallback_steps += 1;
            push(window.from_window(x, y), &mut info, path);
        }
    }
    Ok(info)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{CostMap, CostParams};
    use robot::{Cell, GridMap, Pose};

    fn ci(i: i64, j: i64) -> CellIndex {
        CellIndex { i, j }
    }

    #[test]
    fn on_open_floor_the_path_is_straight() {
        let m = GridMap::new(40, 40, 0.1, Pose::new(1.0, -2.0, 0.4), vec![Cell::Free; 1600]).unwrap();
        let p = CostParams {
            inscribed_radius_m: 0.0,
            inflation_radius_m: 0.0,
            ..CostParams::default()
        };
        let cm = CostMap::build(p, &m, Window::whole(&m).unwrap(), &[]).unwrap();
        let mut nf = NavigationFunction::new();
        let goal = m.cell_center(ci(30, 10));
        nf.compute(&cm, goal).unwrap();
        let start = m.cell_center(ci(10, 10));
        let mut path = Vec::new();
        let info = descend(&nf, start, &GradientParams::default(), &mut path).unwrap();
        assert_eq!(path[0], start);
        assert_eq!(*path.last().unwrap(), goal);
        assert!((info.length_m - 2.0).abs() < 1e-9, "{info:?}");
        let d = direction(&nf, start, &GradientParams::default()).unwrap();
        let expected = (goal - start).scale(0.5);
        assert!(d.dist(expected) < 1e-9, "{d:?} vs {expected:?}");
        let raw = descent_direction_at(&nf, start).unwrap();
        assert!(raw.dist(expected) < 1e-9);
        assert_eq!(
            direction(&nf, goal, &GradientParams::default()).unwrap(),
            Vec2::default()
        );
    }

    #[test]
    fn errors_without_goal_or_outside() {
        let m = GridMap::new(5, 5, 1.0, Pose::default(), vec![Cell::Free; 25]).unwrap();
        let nf = NavigationFunction::new();
        let mut path = Vec::new();
        assert_eq!(
            descend(&nf, Vec2::new(1.0, 1.0), &GradientParams::default(), &mut path),
            Err(PlanningError::NoGoal)
        );
        let p = CostParams {
            inscribed_radius_m: 0.0,
            inflation_radius_m: 0.0,
            ..CostParams::default()
        };
        let cm = CostMap::build(p, &m, Window::whole(&m).unwrap(), &[]).unwrap();
        let mut nf = NavigationFunction::new();
        nf.compute(&cm, Vec2::new(0.5, 0.5)).unwrap();
        assert!(matches!(
            descend(&nf, Vec2::new(9.0, 1.0), &GradientParams::default(), &mut path),
            Err(PlanningError::StartOutsideWindow { .. })
        ));
        assert!(matches!(
            descend(
                &nf,
                Vec2::new(1.0, 1.0),
                &GradientParams { step_cells: 0.0 },
                &mut path
            ),
            Err(PlanningError::BadParam { .. })
        ));
        assert!(matches!(
            descend(
                &nf,
                Vec2::new(1.0, 1.0),
                &GradientParams { step_cells: f64::NAN },
                &mut path
            ),
            Err(PlanningError::BadParam { .. })
        ));
    }
}
