//! The path planner of AutoMove: a navigation function and its gradient.
//!
//! K. Konolige, *A gradient method for realtime robot control*, IROS 2000;
//! ROS `navfn` / `global_planner` for the wavefront and the interpolated
//! gradient. Over a window of the occupancy grid, a cost map gives every
//! cell an intrinsic cost growing near obstacles; a wavefront from the goal
//! gives the navigation function `N`, the least cost to the goal; the robot
//! follows `−∇N`.
//!
//! | module | what it computes |
//! |---|---|
//! | [`window`] | the rectangle of map cells planned over (10 m × 10 m around the robot, or the whole map) |
//! | [`distance_transform`] | exact Euclidean distance to the nearest obstacle cell (Felzenszwalb–Huttenlocher) |
//! | [`cost_map`] | lethal cells (obstacles, unknown, laser endpoints, within the inscribed radius) and the intrinsic cost near obstacles |
//! | [`static_layer`] | the map's part of every cost map, once per map; a window's cost map is then a copy plus the sensed obstacles |
//! | [`navigation_function`] | `N`: Dijkstra from the goal on the 8-connected grid, edge cost `ℓ · (1 + mean intrinsic cost)`; or `A*` aimed at the robot, the same values where settled |
//! | [`gradient`] | the interpolated `−∇N` and the path down it, never through a lethal cell (settling `N` as it reads it) |
//! | [`global_route`] | the whole-map route and its intermediate goals (at corners, ≤ 4 m apart) |
//! | [`local_planner`] | one control cycle: cost map (on the static layer), `N` towards the robot and the path in the window around it |
//!
//! ```
//! use planning::{LocalPlanner, LocalPlannerParams};
//! use robot::{Cell, GridMap, Pose, Vec2};
//!
//! // A 12 m × 12 m room at 0.05 m with a wall from (6, 0) to (6, 8) m.
//! let (w, h) = (240, 240);
//! let mut cells = vec![Cell::Free; w * h];
//! for j in 0..160 {
//!     cells[j * w + 120] = Cell::Occupied;
//! }
//! let map = GridMap::new(w, h, 0.05, Pose::default(), cells)?;
//!
//! let mut planner = LocalPlanner::new(LocalPlannerParams::default())?;
//! let robot = Vec2::new(4.0, 4.0);
//! let plan = planner.plan(&map, robot, Vec2::new(8.0, 4.0), &[])?;
//! // The wall is in the way: the path goes round its end at y = 8 m.
//! assert!(planner.path().iter().any(|p| p.y > 8.0));
//! assert!(plan.direction.y > 0.5);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![warn(missing_docs)]

mod bucket_queue;
pub mod cost_map;
pub mod cost_model;
pub mod distance_transform;
pub mod global_route;
pub mod gradient;
pub mod local_planner;
pub mod navigation_function;
pub mod static_layer;
pub mod window;

pub use cost_map::{Blocked, CostMap, CostMapInfo, laser_endpoints};
pub use cost_model::CostParams;
pub use global_route::{GlobalPlanner, Route, RouteParams, intermediate_goals};
pub use gradient::{DescentInfo, GradientParams, descend, descend_settling, descent_direction_at, direction};
pub use local_planner::{LocalPlan, LocalPlanner, LocalPlannerParams};
pub use navigation_function::{NavigationFunction, NavigationInfo};
pub use static_layer::StaticCostLayer;
pub use window::Window;

use robot::{CellIndex, Vec2};

/// What can go wrong while planning.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PlanningError {
    /// A parameter out of its range.
    #[error("{name} = {value}: expected {expected}")]
    BadParam {
        /// The parameter.
        name: &'static str,
        /// The value given.
        value: f64,
        /// What is accepted.
        expected: &'static str,
    },
    /// A point that is not finite, or absurdly far from the map.
    #[error("{what} ({}, {}) m: not a usable point (not finite, or more than 2^40 cells from the map)", .point.x, .point.y)]
    BadPoint {
        /// Which point.
        what: &'static str,
        /// The point.
        point: Vec2,
    },
    /// A window with no cell or too many.
    #[error("window of {width} × {height} cells: {reason}")]
    BadWindow {
        /// Columns asked for.
        width: usize,
        /// Rows asked for.
        height: usize,
        /// What is wrong.
        reason: &'static str,
    },
    /// A window of another map (other resolution or origin).
    #[error("the window belongs to another map (other resolution or origin)")]
    WindowMapMismatch,
    /// No cell of the window can be entered.
    #[error("no free cell in the {}×{} window at cell ({}, {}): everything is an obstacle, unknown or within the inscribed radius", .window.width(), .window.height(), .window.min().i, .window.min().j)]
    NoFreeCell {
        /// The window.
        window: Window,
    },
    /// No goal given, or the navigation function has none.
    #[error("no goal: the navigation function was not computed")]
    NoGoal,
    /// The goal's cell is not in the window.
    #[error("goal ({:.3}, {:.3}) m (cell {}, {}) lies outside the planning window", .goal.x, .goal.y, .cell.i, .cell.j)]
    GoalOutsideWindow {
        /// The goal.
        goal: Vec2,
        /// Its cell.
        cell: CellIndex,
    },
    /// The goal's cell is lethal (for the local planner with a sensed
    /// obstacle: the spec's *goal occupation*).
    #[error("goal ({:.3}, {:.3}) m (cell {}, {}) is blocked: {why}", .goal.x, .goal.y, .cell.i, .cell.j)]
    GoalBlocked {
        /// The goal.
        goal: Vec2,
        /// Its cell.
        cell: CellIndex,
        /// Why the cell is lethal.
        why: Blocked,
    },
    /// The start's cell is not in the window.
    #[error("start ({:.3}, {:.3}) m (cell {}, {}) lies outside the planning window", .start.x, .start.y, .cell.i, .cell.j)]
    StartOutsideWindow {
        /// The start.
        start: Vec2,
        /// Its cell.
        cell: CellIndex,
    },
    /// The start's cell is lethal.
    #[error("start ({:.3}, {:.3}) m (cell {}, {}) is blocked: {why}", .start.x, .start.y, .cell.i, .cell.j)]
    StartBlocked {
        /// The start.
        start: Vec2,
        /// Its cell.
        cell: CellIndex,
        /// Why the cell is lethal.
        why: Blocked,
    },
    /// No collision-free path from the start to the goal (the spec's *path
    /// blocking*); from [`descend`] alone, the start may also be lethal.
    #[error("no collision-free path from ({:.3}, {:.3}) m (cell {}, {}) to the goal", .start.x, .start.y, .cell.i, .cell.j)]
    Unreachable {
        /// The start.
        start: Vec2,
        /// Its cell.
        cell: CellIndex,
    },
    /// A cost map other than the one a navigation function computed towards
    /// a start was computed on (another window).
    #[error("the cost map is not the one the navigation function was computed on (another window)")]
    OtherCostMap,
    /// A descent needs the value of a cell that a navigation function
    /// computed towards a start has not settled (complete it, or descend
    /// with `descend_settling`).
    #[error("the navigation function has not settled cell ({}, {}) yet: it was computed towards another start", .cell.i, .cell.j)]
    Unsettled {
        /// The cell.
        cell: CellIndex,
    },
    /// Rounding left a cell with a finite value but no lower neighbour
    /// (possible only with extreme intrinsic costs).
    #[error("no descent from cell ({}, {}): intrinsic costs too large for the precision of the navigation function", .cell.i, .cell.j)]
    NoDescent {
        /// The cell.
        cell: CellIndex,
    },
}

/// The cell of a start or goal point, which must be a window cell with a
/// finite cost; `blocked` makes the error otherwise (cells outside the
/// window are [`Blocked::OutsideMap`] for a whole-map window).
fn check_endpoint(
    cost: &CostMap,
    what: &'static str,
    p: Vec2,
    blocked: impl Fn(CellIndex, Blocked) -> PlanningError,
) -> Result<CellIndex, PlanningError> {
    let window = cost.window();
    let cell = window.cell_of(what, p)?;
    if !window.contains(cell) {
        return Err(blocked(cell, Blocked::OutsideMap));
    }
    match cost.why_lethal(cell) {
        Some(why) => Err(blocked(cell, why)),
        None => Ok(cell),
    }
}

/// The centre of the cell nearest `p` that is not lethal, within
/// `radius_m` (ties to the first in row-major order).
pub(crate) fn nearest_free(cost: &CostMap, p: Vec2, radius_m: f64) -> Option<Vec2> {
    let window = cost.window();
    let r = window.resolution_m();
    let c = window.cell_of("start", p).ok()?;
    let reach = (radius_m / r).ceil() as i64;
    let mut best: Option<(f64, Vec2)> = None;
    for dj in -reach..=reach {
        for di in -reach..=reach {
            let q = robot::CellIndex {
                i: c.i + di,
                j: c.j + dj,
            };
            if !window.contains(q) || cost.cost(q).is_infinite() {
                continue;
            }
            let at = window.cell_center(q);
            let d = at.dist(p);
            if d <= radius_m && best.is_none_or(|(b, _)| d < b) {
                best = Some((d, at));
            }
        }
    }
    best.map(|(_, at)| at)
}

/// [`check_endpoint`] for a start.
fn check_start(cost: &CostMap, start: Vec2) -> Result<CellIndex, PlanningError> {
    check_endpoint(cost, "start", start, |cell, why| PlanningError::StartBlocked {
        start,
        cell,
        why,
    })
}
