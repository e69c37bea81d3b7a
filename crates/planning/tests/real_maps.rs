//! The global route on the two real SLAM maps of `maps/`
//! against the shortest grid path, and the planners' errors on them.
//!
//! **How lengths are compared.** For each start/goal pair (corridor points,
//! each moved to the cell of largest clearance within 0.75 m so that it
//! lies on the corridor's centre line), the reference is the length of the
//! shortest 8-connected grid path between the two cells, by a plain
//! Dijkstra (in this file, independent of the planner) over the cells that
//! are not lethal for the robot (same inscribed radius, 0.35 m, so both
//! avoid the same walls) with **zero inflation cost**: moves cost 1 or √2
//! cells, diagonals not cutting past lethal cells. The route's length is the
//! length of its gradient-descent polyline (`Route::length_m`), and also of
//! the polyline through its intermediate goals (`Route::goals_length_m`);
//! both must be within 10 % of the reference. The route is longer where the
//! inflation cost pulls it to corridor centres and rounds corners wider, and
//! shorter where the gradient cuts the 8-connected staircase (a diagonal
//! stretch costs up to 8 % more on the grid than in the plane).

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use planning::{
    Blocked, CostMap, CostParams, GlobalPlanner, LocalPlanner, LocalPlannerParams, PlanningError,
    RouteParams, Window, global_route::segment_clear,
};
use robot::{CellIndex, GridMap, Vec2};
use sim::{DistanceField, OccupancyGrid, map_server};

fn load(name: &str) -> (OccupancyGrid, GridMap) {
    let path = format!("{}/../../maps/{name}/{name}.yaml", env!("CARGO_MANIFEST_DIR"));
    let grid = map_server::load(path).expect("the test maps load").grid;
    let map = grid.grid_map();
    (grid, map)
}

/// The centre of the cell of largest clearance within 0.75 m of `p` (first
/// in row order on ties).
fn snap(map: &GridMap, field: &DistanceField, p: Vec2) -> Vec2 {
    let c = map.cell_of(p);
    let r = (0.75 / map.resolution_m()).ceil() as i64;
    let mut best = (f64::NEG_INFINITY, map.cell_center(c));
    for dj in -r..=r {
        for di in -r..=r {
            let q = CellIndex {
                i: c.i + di,
                j: c.j + dj,
            };
            let centre = map.cell_center(q);
            if map.blocked(q) || centre.dist(p) > 0.75 {
                continue;
            }
            let d = field.distance_m(centre);
            if d > best.0 {
                best = (d, centre);
            }
        }
    }
    best.1
}

/// Length in metres of the shortest 8-connected path between two cells over
/// the cells of `cost` with a finite cost, moves of 1 or √2 cells, no corner
/// cutting; `None` if there is none.
fn shortest_grid_path_m(cost: &CostMap, from: CellIndex, to: CellIndex) -> Option<f64> {
    let w = cost.window();
    let (width, height) = (w.width() as i64, w.height() as i64);
    let free =
        |i: i64, j: i64| i >= 0 && j >= 0 && i < width && j < height && !cost.is_lethal(CellIndex { i, j });
    let idx = |i: i64, j: i64| (j * width + i) as usize;
    let mut dist = vec![u64::MAX; (width * height) as usize];
    // Distances in units of 2⁻³² cell, as integers: exact comparisons.
    let unit = |cells: f64| (cells * 4_294_967_296.0).round() as u64;
    let (orth, diag) = (unit(1.0), unit(std::f64::consts::SQRT_2));
    let mut heap = BinaryHeap::new();
    dist[idx(from.i, from.j)] = 0;
    heap.push(Reverse((0u64, from.i, from.j)));
    while let Some(Reverse((d, i, j))) = heap.pop() {
        if d > dist[idx(i, j)] {
            continue;
        }
        if (i, j) == (to.i, to.j) {
            return Some(d as f64 / 4_294_967_296.0 * w.resolution_m());
        }
        for (di, dj) in [
            (1, 0),
            (-1, 0),
            (0, 1),
            (0, -1),
            (1, 1),
            (1, -1),
            (-1, 1),
            (-1, -1),
        ] {
            let (ni, nj) = (i + di, j + dj);
            if !free(ni, nj) {
                continue;
            }
            let step = if di != 0 && dj != 0 {
                if !(free(i + di, j) && free(i, j + dj)) {
                    continue;
                }
                diag
            } else {
                orth
            };
            let nd = d + step;
            if nd < dist[idx(ni, nj)] {
                dist[idx(ni, nj)] = nd;
                heap.push(Reverse((nd, ni, nj)));
            }
        }
    }
    None
}

/// Start/goal pairs in the corridors (before snapping), metres.
fn pairs(name: &str) -> Vec<(Vec2, Vec2)> {
    let v = Vec2::new;
    match name {
        // Left corridor (x ≈ −17.2), central corridor (x ≈ −11), the top
        // corridor (y ≈ 17.8), the cross corridor (y ≈ −1.2) and the hall
        // (x > −6).
        "building_31" => vec![
            (v(-17.2, 14.0), v(-11.0, -3.0)),
            (v(-17.2, -3.0), v(-11.0, 14.0)),
            (v(-11.0, 14.0), v(3.0, 10.0)),
            (v(-17.2, 5.0), v(4.0, -3.0)),
            (v(5.0, 15.0), v(-17.2, -4.0)),
        ],
        // The corridor loop around the inner block: the west corridor
        // (x ≈ −13.6), the north and south ones (y ≈ 8.7, y ≈ −0.1), the
        // east one (x ≈ 9.75) and the stub going east (y ≈ 0.4).
        "levine" => vec![
            (v(-13.6, 12.0), v(9.75, -3.0)),
            (v(-13.6, -6.0), v(5.0, 8.7)),
            (v(-8.0, 8.7), v(0.0, -0.1)),
            (v(15.0, 0.4), v(-13.6, 3.0)),
        ],
        _ => unreachable!("a map of the test data"),
    }
}

fn check_routes(name: &str) {
    let (grid, map) = load(name);
    let field = DistanceField::new(&grid);
    let mut planner = GlobalPlanner::new(&map, RouteParams::default()).expect("default parameters");
    let reference_params = CostParams {
        max_cost: 0.0,
        ..CostParams::default()
    };
    let reference = CostMap::build(reference_params, &map, Window::whole(&map).unwrap(), &[]).unwrap();
    for (a, b) in pairs(name) {
        let (start, goal) = (snap(&map, &field, a), snap(&map, &field, b));
        let route = planner
            .plan(start, goal)
            .unwrap_or_else(|e| panic!("{name}: {start:?} → {goal:?}: {e}"));
        let grid_m = shortest_grid_path_m(&reference, map.cell_of(start), map.cell_of(goal))
            .expect("the reference finds a path too");
        let ratio = route.length_m / grid_m;
        let goals_ratio = route.goals_length_m / grid_m;
        eprintln!(
            "{name}: ({:.2}, {:.2}) → ({:.2}, {:.2}): grid {grid_m:.2} m, route {:.2} m ({ratio:.3}), through {} goals {:.2} m ({goals_ratio:.3})",
            start.x,
            start.y,
            goal.x,
            goal.y,
            route.length_m,
            route.goals.len(),
            route.goals_length_m,
        );
        assert!(grid_m > 10.0, "{name}: pairs should be far apart ({grid_m} m)");
        assert!((ratio - 1.0).abs() <= 0.10, "{name}: route/grid = {ratio}");
        assert!(
            (goals_ratio - 1.0).abs() <= 0.10,
            "{name}: goals/grid = {goals_ratio}"
        );
        // Goals: within 4 m along the route of each other, chords clear.
        let mut prev = start;
        for &g in &route.goals {
            assert!(prev.dist(g) <= 4.0 + 1e-9, "{name}: goals {prev:?} → {g:?}");
            assert!(
                segment_clear(planner.cost_map(), prev, g),
                "{name}: chord {prev:?} → {g:?}"
            );
            prev = g;
        }
        assert_eq!(*route.goals.last().unwrap(), goal);
        for p in &route.path {
            assert!(!planner.cost_map().is_lethal(map.cell_of(*p)), "{name}: {p:?}");
        }
    }
}

#[test]
fn building_31_routes_are_within_10_percent_of_the_shortest_grid_path() {
    check_routes("building_31");
}

#[test]
fn levine_routes_are_within_10_percent_of_the_shortest_grid_path() {
    check_routes("levine");
}

/// Following the route with the local planner: from each intermediate goal,
/// the next one is inside the 10 m window and reachable.
#[test]
fn the_local_planner_reaches_each_next_goal_on_building_31() {
    let (grid, map) = load("building_31");
    let field = DistanceField::new(&grid);
    let mut global = GlobalPlanner::new(&map, RouteParams::default()).unwrap();
    let (start, goal) = (
        snap(&map, &field, Vec2::new(-17.2, 14.0)),
        snap(&map, &field, Vec2::new(4.0, -3.0)),
    );
    let route = global.plan(start, goal).unwrap();
    let mut local = LocalPlanner::new(LocalPlannerParams::default()).unwrap();
    let mut at = start;
    for &g in &route.goals {
        let plan = local
            .plan(&map, at, g, &[])
            .unwrap_or_else(|e| panic!("{at:?} → {g:?}: {e}"));
        assert_eq!(*local.path().last().unwrap(), g);
        assert!(plan.direction.norm() > 0.99 || at == g);
        at = g;
    }
}

#[test]
fn errors_on_a_real_map() {
    let (_, map) = load("building_31");
    let mut planner = GlobalPlanner::new(&map, RouteParams::default()).unwrap();
    let corridor = Vec2::new(-17.2, 5.0);
    // A wall: the left corridor's west wall is at x ≈ −18.1. Find a wall
    // cell on the row.
    let row = map.cell_of(corridor);
    let wall = (0..60)
        .map(|k| CellIndex {
            i: row.i - k,
            j: row.j,
        })
        .find(|&c| map.get(c) == robot::Cell::Occupied)
        .map(|c| map.cell_center(c))
        .expect("a wall west of the corridor");
    let unknown = (0..map.width() * map.height())
        .map(|k| CellIndex {
            i: (k % map.width()) as i64,
            j: (k / map.width()) as i64,
        })
        .find(|&c| map.get(c) == robot::Cell::Unknown)
        .map(|c| map.cell_center(c))
        .expect("building_31 has unknown cells");
    let goal_err = |g| planner.clone().plan(corridor, g);
    assert!(matches!(
        goal_err(wall),
        Err(PlanningError::GoalBlocked {
            why: Blocked::Occupied,
            ..
        })
    ));
    assert!(matches!(
        goal_err(unknown),
        Err(PlanningError::GoalBlocked {
            why: Blocked::Unknown,
            ..
        })
    ));
    assert!(matches!(
        goal_err(Vec2::new(100.0, 0.0)),
        Err(PlanningError::GoalBlocked {
            why: Blocked::OutsideMap,
            ..
        })
    ));
    assert!(matches!(
        goal_err(Vec2::new(f64::NAN, 0.0)),
        Err(PlanningError::BadPoint { .. })
    ));
    assert!(matches!(
        planner.plan(wall, corridor),
        Err(PlanningError::StartBlocked {
            why: Blocked::Occupied,
            ..
        })
    ));
    let e = planner.plan(corridor, wall).unwrap_err();
    assert!(e.to_string().contains("occupied"), "{e}");

    // Unreachable: a free pocket cut off from the corridors. Find a free
    // cell whose navigation function towards the corridor is infinite.
    planner.plan(corridor, corridor).unwrap();
    let nf = planner.navigation_function();
    let cm = planner.cost_map();
    let pocket = (0..map.width() * map.height())
        .map(|k| CellIndex {
            i: (k % map.width()) as i64,
            j: (k / map.width()) as i64,
        })
        .find(|&c| !cm.is_lethal(c) && nf.value(c).is_infinite())
        .map(|c| map.cell_center(c))
        .expect("building_31 has free pockets cut off from the corridors");
    assert!(matches!(
        planner.plan(pocket, corridor),
        Err(PlanningError::Unreachable { .. })
    ));

    // A window with no free cell: far outside the map.
    let mut local = LocalPlanner::new(LocalPlannerParams::default()).unwrap();
    assert!(matches!(
        local.plan(&map, Vec2::new(500.0, 500.0), Vec2::new(501.0, 500.0), &[]),
        Err(PlanningError::NoFreeCell { .. })
    ));
    // A window inside a thick wall region: all lethal.
    let mut tiny = LocalPlanner::new(LocalPlannerParams {
        window_size_m: 0.2,
        ..LocalPlannerParams::default()
    })
    .unwrap();
    assert!(matches!(
        tiny.plan(&map, wall, wall, &[]),
        Err(PlanningError::NoFreeCell { .. })
    ));
}

#[test]
fn routes_are_deterministic() {
    let (_, map) = load("building_31");
    let run = || {
        let mut planner = GlobalPlanner::new(&map, RouteParams::default()).unwrap();
        planner
            .plan(Vec2::new(-17.2, 14.0), Vec2::new(3.0, 10.0))
            .unwrap()
    };
    let (a, b) = (run(), run());
    assert_eq!(a, b);
}
