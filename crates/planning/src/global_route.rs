//! The global route on the static map, cut into intermediate goals.
//!
//! The local planner sees a 10 m window; a goal farther away is reached
//! through a chain of intermediate goals (docs/tour-guide.md, *AutoMove*). The
//! route is computed with the same cost model as the local planner, over
//! the whole map:
//!
//! 1. the cost map of the whole map ([`CostMap`], built once by
//!    [`GlobalPlanner::new`]: the static map does not change);
//! 2. the navigation function from the goal ([`NavigationFunction`],
//!    Dijkstra on the 8-connected grid);
//! 3. the path by gradient descent from the start ([`descend`]), a
//!    polyline that never crosses a lethal cell;
//! 4. **intermediate goals**: the path is simplified by Douglas–Peucker
//!    (D. Douglas, T. Peucker, *Algorithms for the reduction of the number
//!    of points required to represent a digitized line*, Cartographica 10,
//!    1973) with tolerance `corner_tolerance_m` (default 0.25 m), a chord
//!    being accepted only if it crosses no lethal cell, so the kept vertices
//!    are the corners; then every piece longer than `max_spacing_m`
//!    (default 4 m) *along the path* is cut into equal pieces by extra
//!    goals on the path. Consecutive goals (and the start and the first
//!    goal) are thus at most 4 m apart along the route: with the robot at
//!    one goal, the next one and the stretch of route between them lie
//!    inside the 10 m × 10 m window centred on it (4 m < 5 m), and the
//!    straight line between consecutive goals is clear of lethal cells.
//!
//! Cost: `O(n log n)` for the navigation function over the `n` free cells,
//! `O(p log p)` typically (`O(p²)` at worst) for the simplification of a
//! path of `p` points.

use std::sync::Arc;

use robot::{CellIndex, GridMap, Vec2};

use super::gradient::{DescentInfo, GradientParams, descend};
use super::{
    CostMap, CostParams, NavigationFunction, NavigationInfo, PlanningError, Window, check_endpoint,
    check_start,
};

/// Parameters of the global route.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RouteParams {
    /// The cost model (the local planner's, so that both agree). Default
    /// [`CostParams::default`].
    pub cost: CostParams,
    /// The gradient descent. Default [`GradientParams::default`].
    pub gradient: GradientParams,
    /// Largest distance along the route between consecutive intermediate
    /// goals (and from the start to the first), metres, > 0. Default 4 (for
    /// a 10 m × 10 m local window: less than its half-side).
    pub max_spacing_m: f64,
    /// Douglas–Peucker tolerance: the largest distance between the route
    /// and the straight lines between consecutive corner goals, metres,
    /// ≥ 0. Default 0.25.
    pub corner_tolerance_m: f64,
    /// A start lethal only by inflation (within the inscribed radius of an
    /// obstacle) descends from the nearest cell that is not lethal within
    /// this distance, metres, ≥ 0. Default 0.3.
    pub escape_radius_m: f64,
}

impl Default for RouteParams {
    fn default() -> Self {
        RouteParams {
            cost: CostParams::default(),
            gradient: GradientParams::default(),
            max_spacing_m: 4.0,
            corner_tolerance_m: 0.25,
            escape_radius_m: 0.3,
        }
    }
}

impl RouteParams {
    /// Checks every field.
    pub fn validate(&self) -> Result<(), PlanningError> {
        self.cost.validate()?;
        self.gradient.validate()?;
        if !(self.max_spacing_m.is_finite() && self.max_spacing_m > 0.0) {
            return Err(PlanningError::BadParam {
                name: "max_spacing_m",
                value: self.max_spacing_m,
                expected: "a finite number > 0",
            });
        }
        if !(self.corner_tolerance_m.is_finite() && self.corner_tolerance_m >= 0.0) {
            return Err(PlanningError::BadParam {
                name: "corner_tolerance_m",
                value: self.corner_tolerance_m,
                expected: "a finite number ≥ 0",
            });
        }
        if !(self.escape_radius_m.is_finite() && self.escape_radius_m >= 0.0) {
            return Err(PlanningError::BadParam {
                name: "escape_radius_m",
                value: self.escape_radius_m,
                expected: "a finite number ≥ 0",
            });
        }
        Ok(())
    }
}

/// A route from a start to a goal.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Route {
    /// The gradient-descent path, world frame, from the start to the goal
    /// (points about `step_cells` cells apart).
    pub path: Vec<Vec2>,
    /// The intermediate goals, in order, the last one the goal itself (the
    /// start is not included).
    pub goals: Vec<Vec2>,
    /// Length of `path`, metres.
    pub length_m: f64,
    /// Length of the polyline start → goals, metres.
    pub goals_length_m: f64,
    /// The navigation function at the start (cost-weighted metres).
    pub cost: f64,
    /// The descent.
    pub descent: DescentInfo,
    /// The navigation function's computation.
    pub navigation: NavigationInfo,
}

/// Global routes on one static map (module docs); keeps the cost map and
/// the navigation function's memory between routes.
#[derive(Debug, Clone)]
pub struct GlobalPlanner {
    params: RouteParams,
    /// Shared by the planners on one map ([`GlobalPlanner::on_same_map`]).
    cost_map: Arc<CostMap>,
    nf: NavigationFunction,
}

impl GlobalPlanner {
    /// Builds the cost map of the whole `map`. Errors: invalid parameters.
    pub fn new(map: &GridMap, params: RouteParams) -> Result<GlobalPlanner, PlanningError> {
        params.validate()?;
        let cost_map = Arc::new(CostMap::build(params.cost, map, Window::whole(map)?, &[])?);
        Ok(GlobalPlanner {
            params,
            cost_map,
            nf: NavigationFunction::new(),
        })
    }

    /// A new planner on this one's map with its parameters, the cost map
    /// shared (not built again), no route's memory.
    pub fn on_same_map(&self) -> GlobalPlanner {
        GlobalPlanner {
            params: self.params,
            cost_map: Arc::clone(&self.cost_map),
            nf: NavigationFunction::new(),
        }
    }

    /// The parameters.
    pub fn params(&self) -> &RouteParams {
        &self.params
    }

    /// The cost map of the whole map.
    pub fn cost_map(&self) -> &CostMap {
        &self.cost_map
    }

    /// The navigation function of the last route.
    pub fn navigation_function(&self) -> &NavigationFunction {
        &self.nf
    }

    /// The route from `start` to `goal` (world frame).
    ///
    /// Errors: a non-finite point ([`PlanningError::BadPoint`]);
    /// [`PlanningError::StartBlocked`] / [`PlanningError::GoalBlocked`] for a
    /// start or goal in a wall, in unknown space, outside the map or within
    /// the robot's inscribed radius of an obstacle (the reason says which);
    /// [`PlanningError::NoFreeCell`] for a map without free space;
    /// [`PlanningError::Unreachable`] when no collision-free path joins them.
    pub fn plan(&mut self, start: Vec2, goal: Vec2) -> Result<Route, PlanningError> {
        if self.cost_map.info().free_cells == 0 {
            return Err(PlanningError::NoFreeCell {
                window: self.cost_map.window(),
            });
        }
        // A start within the inscribed radius of an obstacle (a robot that
        // stopped close to a wall) descends from the nearest free cell.
        let (from, start_cell) = match check_start(&self.cost_map, start) {
            Ok(cell) => (start, cell),
            Err(
                e @ PlanningError::StartBlocked {
                    why: super::Blocked::Inflated { .. },
                    cell,
                    ..
                },
            ) => (
                super::nearest_free(&self.cost_map, start, self.params.escape_radius_m).ok_or(e)?,
                cell,
            ),
            Err(e) => return Err(e),
        };
        check_endpoint(&self.cost_map, "goal", goal, |cell, why| {
            PlanningError::GoalBlocked { goal, cell, why }
        })?;
        let navigation = self.nf.compute(&self.cost_map, goal)?;
        let mut path = Vec::new();
        let descent = descend(&self.nf, from, &self.params.gradient, &mut path).map_err(|e| match e {
            PlanningError::Unreachable { .. } => PlanningError::Unreachable {
                start,
                cell: start_cell,
            },
            e => e,
        })?;
        if from != start {
            path.insert(0, start);
        }
        let goals = intermediate_goals(
            &self.cost_map,
            &path,
            self.params.max_spacing_m,
            self.params.corner_tolerance_m,
        );
        let goals_length_m = polyline_length(std::iter::once(start).chain(goals.iter().copied()));
        Ok(Route {
            length_m: descent.length_m,
            cost: descent.start_value,
            goals_length_m,
            goals,
            path,
            descent,
            navigation,
        })
    }
}

/// Length of a polyline, metres.
fn polyline_length(points: impl IntoIterator<Item = Vec2>) -> f64 {
    let mut it = points.into_iter();
    let Some(mut last) = it.next() else {
        return 0.0;
    };
    let mut total = 0.0;
    for p in it {
        total += last.dist(p);
        last = p;
    }
    total
}

/// The intermediate goals of a path (module docs, step 4): corners by
/// Douglas–Peucker with `corner_tolerance_m` and chords clear of lethal
/// cells of `cost`, then extra goals so that no two consecutive ones are
/// more than `max_spacing_m` apart along the path. The start (`path[0]`) is
/// left out; the last goal is the path's last point. Empty for an empty
/// path.
pub fn intermediate_goals(
    cost: &CostMap,
    path: &[Vec2],
    max_spacing_m: f64,
    corner_tolerance_m: f64,
) -> Vec<Vec2> {
    let n = path.len();
    if n == 0 {
        return Vec::new();
    }
    if n == 1 {
        return vec![path[0]];
    }
    // Douglas–Peucker with an explicit stack.
    let mut keep = vec![false; n];
    keep[0] = true;
    keep[n - 1] = true;
    let mut stack = vec![(0usize, n - 1)];
    while let Some((a, b)) = stack.pop() {
        if b <= a + 1 {
            continue;
        }
        let (mut far, mut far_d) = (a + 1, -1.0f64);
        for (k, &p) in path.iter().enumerate().take(b).skip(a + 1) {
            let d = point_segment_distance(p, path[a], path[b]);
            if d > far_d {
                far = k;
                far_d = d;
            }
        }
        if far_d > corner_tolerance_m || !segment_clear(cost, path[a], path[b]) {
            keep[far] = true;
            stack.push((far, b));
            stack.push((a, far));
        }
    }
    // Arc length along the path.
    let mut s = Vec::with_capacity(n);
    s.push(0.0);
    for k in 1..n {
        s.push(s[k - 1] + path[k - 1].dist(path[k]));
    }
    let corners: Vec<usize> = (0..n).filter(|&k| keep[k]).collect();
    let mut goals = Vec::new();
    let mut seg = 0usize; // path segment holding the next inserted goal
    for pair in corners.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        let length = s[b] - s[a];
        let pieces = ((length / max_spacing_m) - 1e-9).ceil().max(1.0) as usize;
        for t in 1..pieces {
            let target = s[a] + length * t as f64 / pieces as f64;
            seg = seg.max(a);
            while seg + 1 < b && s[seg + 1] < target {
                seg += 1;
            }
            let span = s[seg + 1] - s[seg];
            let f = if span > 0.0 {
                ((target - s[seg]) / span).clamp(0.0, 1.0)
            } else {
                0.0
            };
            goals.push(path[seg] + (path[seg + 1] - path[seg]).scale(f));
        }
        goals.push(path[b]);
    }
    goals
}

/// Distance from `p` to the segment `ab`.
fn point_segment_distance(p: Vec2, a: Vec2, b: Vec2) -> f64 {
    let ab = b - a;
    let len2 = ab.dot(ab);
    if len2 == 0.0 {
        return p.dist(a);
    }
    let t = ((p - a).dot(ab) / len2).clamp(0.0, 1.0);
    p.dist(a + ab.scale(t))
}

/// Whether every cell the segment `ab` passes through has a finite cost
/// (cell traversal, J. Amanatides, A. Woo, *A fast voxel traversal
/// algorithm*, Eurographics 1987; through a cell corner, both cells beside
/// it must be clear).
pub fn segment_clear(cost: &CostMap, a: Vec2, b: Vec2) -> bool {
    let window = cost.window();
    let (x0, y0) = window.to_window(a);
    let (x1, y1) = window.to_window(b);
    if !(x0.is_finite() && y0.is_finite() && x1.is_finite() && y1.is_finite()) {
        return false;
    }
    let min = window.min();
    let clear = |u: i64, v: i64| {
        cost.cost(CellIndex {
            i: min.i + u,
            j: min.j + v,
        })
        .is_finite()
    };
    let (mut u, mut v) = (x0.floor() as i64, y0.floor() as i64);
    let (ue, ve) = (x1.floor() as i64, y1.floor() as i64);
    if !clear(u, v) {
        return false;
    }
    let (dx, dy) = (x1 - x0, y1 - y0);
    let (su, sv) = (if dx > 0.0 { 1 } else { -1 }, if dy > 0.0 { 1 } else { -1 });
    let t_delta = |d: f64| if d != 0.0 { 1.0 / d.abs() } else { f64::INFINITY };
    let t_first = |p: f64, c: i64, s: i64, d: f64| {
        if d == 0.0 {
            f64::INFINITY
        } else {
            let edge = if s > 0 { c as f64 + 1.0 } else { c as f64 };
            (edge - p) / d
        }
    };
    let (dtx, dty) = (t_delta(dx), t_delta(dy));
    let (mut tx, mut ty) = (t_first(x0, u, su, dx), t_first(y0, v, sv, dy));
    let budget = (ue - u).unsigned_abs() + (ve - v).unsigned_abs() + 2;
    for _ in 0..budget {
        if (u, v) == (ue, ve) {
            return true;
        }
        if (tx - ty).abs() < 1e-12 {
            // Through a corner: both cells beside it, then the diagonal.
            if !clear(u + su, v) || !clear(u, v + sv) {
                return false;
            }
            u += su;
            v += sv;
            tx += dtx;
            ty += dty;
        } else if tx < ty {
            u += su;
            tx += dtx;
        } else {
            v += sv;
            ty += dty;
        }
        if !clear(u, v) {
            return false;
        }
    }
    (u, v) == (ue, ve)
}

#[cfg(test)]
mod tests {
    use super::*;
    use robot::{Cell, Pose};

    /// A 10 m × 6 m room at 0.1 m with a wall across x = 5 m from y = 0 to
    /// 4 m: going from the left half to the right means passing above it.
    fn room() -> GridMap {
        let (w, h) = (100, 60);
        let mut cells = vec![Cell::Free; w * h];
        for j in 0..40 {
            cells[j * w + 50] = Cell::Occupied;
        }
        GridMap::new(w, h, 0.1, Pose::default(), cells).unwrap()
    }

    fn params() -> RouteParams {
        RouteParams {
            cost: CostParams {
                inscribed_radius_m: 0.2,
                inflation_radius_m: 0.5,
                max_cost: 2.0,
                decay_per_m: 5.0,
            },
            ..RouteParams::default()
        }
    }

    #[test]
    fn a_route_round_a_wall_has_corner_goals_and_bounded_spacing() {
        let m = room();
        let mut planner = GlobalPlanner::new(&m, params()).unwrap();
        let (start, goal) = (Vec2::new(1.05, 1.05), Vec2::new(9.05, 1.05));
        let r = planner.plan(start, goal).unwrap();
        assert_eq!(r.path[0], start);
        assert_eq!(*r.path.last().unwrap(), goal);
        assert_eq!(*r.goals.last().unwrap(), goal);
        // Above the wall's end (y = 4 m) on the way.
        assert!(r.path.iter().any(|p| p.y > 4.0));
        assert!(
            r.goals.iter().any(|p| p.y > 4.0 && (p.x - 5.0).abs() < 1.0),
            "{:?}",
            r.goals
        );
        // Spacing along the path and clear chords.
        let mut prev = start;
        for &g in &r.goals {
            assert!(prev.dist(g) <= 4.0 + 1e-9);
            assert!(segment_clear(planner.cost_map(), prev, g), "{prev:?} → {g:?}");
            prev = g;
        }
        assert!(r.goals_length_m <= r.length_m + 1e-9);
        // Straight line 8 m; over the wall ≈ 2·√(4² + 3²) ≈ 10 m.
        assert!(r.length_m > 9.5 && r.length_m < 12.0, "{}", r.length_m);
    }

    #[test]
    fn start_and_goal_errors() {
        let m = room();
        let mut planner = GlobalPlanner::new(&m, params()).unwrap();
        let free = Vec2::new(1.05, 1.05);
        let wall = Vec2::new(5.05, 1.05);
        assert!(matches!(
            planner.plan(wall, free),
            Err(PlanningError::StartBlocked {
                why: super::super::Blocked::Occupied,
                ..
            })
        ));
        assert!(matches!(
            planner.plan(free, wall),
            Err(PlanningError::GoalBlocked {
                why: super::super::Blocked::Occupied,
                ..
            })
        ));
        assert!(matches!(
            planner.plan(free, Vec2::new(20.0, 1.0)),
            Err(PlanningError::GoalBlocked {
                why: super::super::Blocked::OutsideMap,
                ..
            })
        ));
        assert!(matches!(
            planner.plan(free, Vec2::new(5.25, 1.05)),
            Err(PlanningError::GoalBlocked {
                why: super::super::Blocked::Inflated { .. },
                ..
            })
        ));
    }

    #[test]
    fn segment_clear_checks_every_cell_and_corners() {
        let mut cells = vec![Cell::Free; 100];
        cells[5 * 10 + 5] = Cell::Occupied;
        let m = GridMap::new(10, 10, 1.0, Pose::default(), cells).unwrap();
        let p = CostParams {
            inscribed_radius_m: 0.0,
            inflation_radius_m: 0.0,
            ..CostParams::default()
        };
        let cm = CostMap::build(p, &m, Window::whole(&m).unwrap(), &[]).unwrap();
        assert!(!segment_clear(&cm, Vec2::new(0.5, 5.5), Vec2::new(9.5, 5.5)));
        assert!(segment_clear(&cm, Vec2::new(0.5, 4.5), Vec2::new(9.5, 4.5)));
        // Through the corner (5, 5) of the blocked cell, diagonally.
        assert!(!segment_clear(&cm, Vec2::new(4.5, 5.5), Vec2::new(5.5, 4.5)));
        assert!(!segment_clear(&cm, Vec2::new(0.5, 0.5), Vec2::new(9.5, 9.5)));
        assert!(segment_clear(&cm, Vec2::new(0.5, 1.7), Vec2::new(8.5, 9.7)));
        // Touching only the blocked cell's corner (5, 6) is refused too.
        assert!(!segment_clear(&cm, Vec2::new(0.5, 1.5), Vec2::new(8.5, 9.5)));
        assert!(!segment_clear(&cm, Vec2::new(0.5, 0.5), Vec2::new(10.5, 0.5)));
    }

    #[test]
    fn spacing_cuts_long_straight_stretches_evenly() {
        let m = GridMap::new(200, 10, 0.1, Pose::default(), vec![Cell::Free; 2000]).unwrap();
        let p = CostParams {
            inscribed_radius_m: 0.0,
            inflation_radius_m: 0.0,
            ..CostParams::default()
        };
        let cm = CostMap::build(p, &m, Window::whole(&m).unwrap(), &[]).unwrap();
        let path: Vec<Vec2> = (0..=180).map(|k| Vec2::new(0.5 + 0.1 * k as f64, 0.55)).collect();
        let goals = intermediate_goals(&cm, &path, 4.0, 0.25);
        // 18 m in 5 pieces of 3.6 m.
        assert_eq!(goals.len(), 5);
        for (k, g) in goals.iter().enumerate() {
            assert!((g.x - (0.5 + 3.6 * (k + 1) as f64)).abs() < 1e-9, "{goals:?}");
        }
        assert_eq!(intermediate_goals(&cm, &path[..1], 4.0, 0.25), vec![path[0]]);
        assert!(intermediate_goals(&cm, &[], 4.0, 0.25).is_empty());
    }

    #[test]
    fn bad_parameters_are_errors() {
        let m = room();
        for p in [
            RouteParams {
                max_spacing_m: 0.0,
                ..RouteParams::default()
            },
            RouteParams {
                corner_tolerance_m: f64::NAN,
                ..RouteParams::default()
            },
            RouteParams {
                gradient: GradientParams { step_cells: 2.0 },
                ..RouteParams::default()
            },
        ] {
            assert!(matches!(
                GlobalPlanner::new(&m, p),
                Err(PlanningError::BadParam { .. })
            ));
        }
    }
}
