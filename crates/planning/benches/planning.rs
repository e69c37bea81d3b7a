//! Path-planning speed on the real `building_31` and `levine` maps.
//!
//! **Local cycle** (`local_*`): what AutoMove does every control cycle on
//! `building_31` (693 × 648 cells at 0.05 m): the 10 m × 10 m window
//! (200 × 200 cells) around the robot, a 181-beam laser scan over 180°
//! (30 m) whose endpoints become obstacles, the cost map, the navigation
//! function to the next intermediate goal and the gradient. The robot
//! stands at the intermediate goals of five global routes (the pairs of
//! `tests/real_maps.rs`), facing the next one, which is the goal; two
//! people (discs of 0.25 m) stand 2 m ahead, 0.9 m to each side, unless
//! they would block the way. That makes 53 cycles; one more is left out,
//! where the scan's endpoints — some land in the free cell in front of a
//! wall — thicken a door's jambs by a cell and close it to the 0.7 m robot
//! (the planner reports `Unreachable`, path blocking). Each iteration is
//! one cycle, the cycles taken in turn. Target: ≤ 2 ms for `local_cycle`.
//! The allocation counter shows that a warm cycle allocates nothing (the
//! planners are warmed up by one cycle, which makes the map's static
//! layer).
//!
//! * `local_cycle`: scan → endpoints → cost map → `N` → descent (the
//!   direction and the whole path to the goal) with [`LocalPlanner::plan`];
//! * `local_cycle_unexplained`: the same with only the echoes the static
//!   map does not explain, as AutoMove passes them (`guide/automove.rs`:
//!   an echo within 0.15 m of a blocked map cell is that wall seen and
//!   dropped) — the two people, about 15 points a cycle instead of 181;
//! * `local_cycle_blocked`: path blocking, the worst case — a ring of
//!   points 1 m around the robot (people all round it), the goal outside
//!   (the cycles whose goal is more than 1.5 m away, 43 of the 53): the
//!   planner must explore everything the goal reaches before it can say
//!   `Unreachable`;
//! * `local_cost_map`, `local_navigation_function`, `local_direction`: the
//!   three stages alone (the direction is one gradient step); the cost map
//!   on the map's [`StaticCostLayer`], as the planner builds it, and
//!   `local_cost_map_from_map` the same cost map built from the map alone
//!   (the distance transform over the window and its margin); `N` over the
//!   whole window, and `local_navigation_towards_robot` `N` towards the
//!   robot with the descent to the goal that settles what it reads, as the
//!   planner computes them (the same path);
//! * `static_layer`: the one-off static layer of a whole map (the first
//!   cycle on a map makes it).
//!
//! **Global route** (`global_*`, one-off): the whole-map cost map
//! ([`GlobalPlanner::new`]), and a route between corridor points with its
//! intermediate goals ([`GlobalPlanner::plan`]), on `building_31` and
//! `levine` (2048 × 2048 cells).
//!
//! Run with `cargo bench -p planning --bench planning`. Figures (medians on the
//! shared 2-core machine: `local_cycle` ≈ 0.1 ms, 1.0 ms before the static
//! layer and the wavefront aimed at the robot; `global_route` 12 ms on
//! `building_31` and 150 ms on `levine`) in `crates/planning/BENCHMARKS.md`.

use std::f64::consts::PI;
use std::sync::Arc;

use divan::Bencher;
use planning::distance_transform::{BEYOND, DistanceTransform};
use planning::{
    CostMap, GlobalPlanner, GradientParams, LocalPlanner, LocalPlannerParams, NavigationFunction,
    RouteParams, StaticCostLayer, Window, descend_settling, direction, laser_endpoints,
};
use robot::{Cell, GridMap, LaserScan, Pose, Vec2};
use sim::{OccupancyGrid, cast_many, map_server};

#[global_allocator]
static ALLOC: divan::AllocProfiler = divan::AllocProfiler::system();

fn main() {
    divan::main();
}

const BEAMS: usize = 181;
const RANGE_M: f64 = 30.0;
const PERSON_RADIUS_M: f64 = 0.25;

fn load(name: &str) -> (OccupancyGrid, GridMap) {
    let path = format!("{}/../../maps/{name}/{name}.yaml", env!("CARGO_MANIFEST_DIR"));
    let grid = map_server::load(path).expect("the test maps load").grid;
    let map = grid.grid_map();
    (grid, map)
}

/// Corridor start/goal pairs (the snapped pairs of `tests/real_maps.rs`).
fn pairs(name: &str) -> Vec<(Vec2, Vec2)> {
    let v = Vec2::new;
    match name {
        "building_31" => vec![
            (v(-17.17, 14.73), v(-10.88, -2.42)),
            (v(-17.07, -2.62), v(-11.02, 14.73)),
            (v(-11.02, 14.73), v(2.28, 10.08)),
            (v(-17.12, 4.28), v(3.28, -2.88)),
            (v(4.28, 14.83), v(-17.17, -3.47)),
        ],
        _ => vec![
            (v(-13.65, 11.30), v(9.75, -3.30)),
            (v(-13.65, -6.70), v(4.30, 8.65)),
            (v(-8.70, 8.65), v(-0.70, -0.15)),
            (v(14.30, 0.30), v(-13.70, 3.70)),
        ],
    }
}

/// Distance along a unit ray from `o` in direction `d` to a disc, if hit.
fn ray_disc(o: Vec2, d: Vec2, c: Vec2, r: f64) -> Option<f64> {
    let oc = c - o;
    let along = oc.dot(d);
    let perp2 = oc.dot(oc) - along * along;
    let h2 = r * r - perp2;
    (h2 >= 0.0 && along - h2.sqrt() > 0.0).then(|| along - h2.sqrt())
}

/// A 181-beam scan over 180° from `pose`: the map's walls, and the people.
fn scan(grid: &OccupancyGrid, pose: Pose, people: &[Vec2]) -> LaserScan {
    let angles: Vec<f64> = (0..BEAMS)
        .map(|k| pose.theta_rad - PI / 2.0 + k as f64 * PI / (BEAMS - 1) as f64)
        .collect();
    let mut walls = Vec::with_capacity(BEAMS);
    cast_many(grid, pose.position(), &angles, RANGE_M, &mut walls);
    let ranges_m = angles
        .iter()
        .zip(&walls)
        .map(|(&a, &w)| {
            let d = Vec2::new(a.cos(), a.sin());
            people
                .iter()
                .filter_map(|&c| ray_disc(pose.position(), d, c, PERSON_RADIUS_M))
                .chain(w)
                .fold(f64::INFINITY, f64::min)
        })
        .collect();
    LaserScan {
        mount: Pose::default(),
        angle_min_rad: -PI / 2.0,
        angle_increment_rad: PI / (BEAMS - 1) as f64,
        range_max_m: RANGE_M,
        ranges_m,
    }
}

/// One control cycle's input.
struct Cycle {
    pose: Pose,
    goal: Vec2,
    scan: LaserScan,
}

/// The cycles of the local benchmarks: the robot at each intermediate goal
/// of the routes, facing the next; people 2 m ahead, 0.9 m to each side,
/// kept only if the plan still succeeds (they must not block the corridor).
fn cycles(grid: &OccupancyGrid, map: &GridMap) -> Vec<Cycle> {
    let mut global = GlobalPlanner::new(map, RouteParams::default()).expect("default parameters");
    let mut local = LocalPlanner::new(LocalPlannerParams::default()).expect("default parameters");
    let mut out = Vec::new();
    let mut points = Vec::new();
    let mut skipped = 0;
    for (start, goal) in pairs("building_31") {
        let route = global.plan(start, goal).expect("the routes of the tests");
        let mut at = start;
        for &g in &route.goals {
            let heading = (g - at).angle();
            let pose = Pose::new(at.x, at.y, heading);
            let (ahead, side) = (
                Vec2::new(heading.cos(), heading.sin()),
                Vec2::new(-heading.sin(), heading.cos()),
            );
            let mut people = Vec::new();
            for s in [0.9, -0.9] {
                let person = at + ahead.scale(2.0) + side.scale(s);
                let trial: Vec<Vec2> = people.iter().copied().chain([person]).collect();
                points.clear();
                laser_endpoints(pose, &scan(grid, pose, &trial), &mut points);
                if local.plan(map, at, g, &points).is_ok() {
                    people = trial;
                }
            }
            let sc = scan(grid, pose, &people);
            points.clear();
            laser_endpoints(pose, &sc, &mut points);
            if local.plan(map, at, g, &points).is_ok() {
                out.push(Cycle {
                    pose,
                    goal: g,
                    scan: sc,
                });
            } else {
                skipped += 1;
            }
            at = g;
        }
    }
    assert_eq!((out.len(), skipped), (53, 1), "the cycles of the module docs");
    out
}

/// A local planner that has planned one cycle (and so made the map's
/// static layer).
fn warm_planner(map: &GridMap, c: &Cycle) -> LocalPlanner {
    let mut planner = LocalPlanner::new(LocalPlannerParams::default()).unwrap();
    let mut points = Vec::new();
    laser_endpoints(c.pose, &c.scan, &mut points);
    planner
        .plan(map, c.pose.position(), c.goal, &points)
        .expect("a plan");
    planner
}

#[divan::bench(sample_count = 200)]
fn local_cycle(b: Bencher) {
    let (grid, map) = load("building_31");
    let cycles = cycles(&grid, &map);
    let mut planner = warm_planner(&map, &cycles[0]);
    let mut points = Vec::with_capacity(BEAMS);
    let mut k = 0;
    b.bench_local(|| {
        let c = &cycles[k % cycles.len()];
        k += 1;
        points.clear();
        laser_endpoints(c.pose, &c.scan, &mut points);
        let plan = planner
            .plan(&map, c.pose.position(), c.goal, &points)
            .expect("a plan");
        divan::black_box(plan.direction);
    });
}

/// Map cells within 0.15 m of a blocked cell (AutoMove's default
/// `echo_tolerance_m`), computed as `AutoMove::new` does.
fn near_wall(map: &GridMap) -> Vec<bool> {
    let blocked: Vec<u8> = map.cells().iter().map(|&c| u8::from(c != Cell::Free)).collect();
    let cap = (0.15 / map.resolution_m()).round() as u32;
    let mut d2 = Vec::new();
    DistanceTransform::new().compute(&blocked, map.width(), map.height(), cap, &mut d2);
    d2.iter().map(|&d| d != BEYOND && d <= cap * cap).collect()
}

/// Keeps the endpoints the map does not explain (AutoMove's filter).
fn unexplained(map: &GridMap, near_wall: &[bool], points: &mut Vec<Vec2>) {
    points.retain(|&q| {
        let c = map.cell_of(q);
        map.contains(c) && !near_wall[c.j as usize * map.width() + c.i as usize]
    });
}

#[divan::bench(sample_count = 200)]
fn local_cycle_unexplained(b: Bencher) {
    let (grid, map) = load("building_31");
    let cycles = cycles(&grid, &map);
    let near = near_wall(&map);
    let mut planner = warm_planner(&map, &cycles[0]);
    let mut points = Vec::with_capacity(BEAMS);
    let mut k = 0;
    b.bench_local(|| {
        let c = &cycles[k % cycles.len()];
        k += 1;
        points.clear();
        laser_endpoints(c.pose, &c.scan, &mut points);
        unexplained(&map, &near, &mut points);
        let plan = planner
            .plan(&map, c.pose.position(), c.goal, &points)
            .expect("a plan");
        divan::black_box(plan.direction);
    });
}

#[divan::bench(sample_count = 200)]
fn local_cycle_blocked(b: Bencher) {
    let (grid, map) = load("building_31");
    let mut cycles = cycles(&grid, &map);
    cycles.retain(|c| c.pose.position().dist(c.goal) > 1.5);
    assert_eq!(cycles.len(), 43, "the cycles of the module docs");
    let mut planner = LocalPlanner::new(LocalPlannerParams::default()).unwrap();
    let ring = |at: Vec2| -> Vec<Vec2> {
        (0..360)
            .map(|k| {
                let a = (k as f64).to_radians();
                at + Vec2::new(a.cos(), a.sin())
            })
            .collect()
    };
    // Warm: the map's static layer made.
    let c = &cycles[0];
    let _ = planner.plan(&map, c.pose.position(), c.goal, &ring(c.pose.position()));
    let rings: Vec<Vec<Vec2>> = cycles.iter().map(|c| ring(c.pose.position())).collect();
    let mut k = 0;
    b.bench_local(|| {
        let i = k % cycles.len();
        k += 1;
        let c = &cycles[i];
        let r = planner.plan(&map, c.pose.position(), c.goal, &rings[i]);
        assert!(
            matches!(r, Err(planning::PlanningError::Unreachable { .. })),
            "{r:?}"
        );
    });
}

/// Cost maps of every cycle, built once.
fn cost_maps(map: &GridMap, cycles: &[Cycle]) -> Vec<CostMap> {
    let params = LocalPlannerParams::default();
    let mut points = Vec::new();
    cycles
        .iter()
        .map(|c| {
            points.clear();
            laser_endpoints(c.pose, &c.scan, &mut points);
            let window = Window::centred(map, c.pose.position(), params.window_size_m).unwrap();
            CostMap::build(params.cost, map, window, &points).unwrap()
        })
        .collect()
}

#[divan::bench(sample_count = 200)]
fn local_cost_map(b: Bencher) {
    let (grid, map) = load("building_31");
    let cycles = cycles(&grid, &map);
    let params = LocalPlannerParams::default();
    let layer = Arc::new(StaticCostLayer::new(params.cost, &map).unwrap());
    let mut cost_map = cost_maps(&map, &cycles[..1]).pop().unwrap();
    let mut points = Vec::with_capacity(BEAMS);
    let mut k = 0;
    b.bench_local(|| {
        let c = &cycles[k % cycles.len()];
        k += 1;
        points.clear();
        laser_endpoints(c.pose, &c.scan, &mut points);
        let window = Window::centred(&map, c.pose.position(), params.window_size_m).unwrap();
        divan::black_box(cost_map.rebuild_on(&layer, window, &points).unwrap());
    });
}

#[divan::bench(sample_count = 200)]
fn local_cost_map_from_map(b: Bencher) {
    let (grid, map) = load("building_31");
    let cycles = cycles(&grid, &map);
    let params = LocalPlannerParams::default();
    let mut cost_map = cost_maps(&map, &cycles[..1]).pop().unwrap();
    let mut points = Vec::with_capacity(BEAMS);
    let mut k = 0;
    b.bench_local(|| {
        let c = &cycles[k % cycles.len()];
        k += 1;
        points.clear();
        laser_endpoints(c.pose, &c.scan, &mut points);
        let window = Window::centred(&map, c.pose.position(), params.window_size_m).unwrap();
        divan::black_box(cost_map.rebuild(&map, window, &points).unwrap());
    });
}

#[divan::bench(sample_count = 200)]
fn local_navigation_function(b: Bencher) {
    let (grid, map) = load("building_31");
    let cycles = cycles(&grid, &map);
    let cost_maps = cost_maps(&map, &cycles);
    let mut nf = NavigationFunction::new();
    let mut k = 0;
    b.bench_local(|| {
        let i = k % cycles.len();
        k += 1;
        divan::black_box(nf.compute(&cost_maps[i], cycles[i].goal).unwrap());
    });
}

#[divan::bench(sample_count = 200)]
fn local_navigation_towards_robot(b: Bencher) {
    let (grid, map) = load("building_31");
    let cycles = cycles(&grid, &map);
    let cost_maps = cost_maps(&map, &cycles);
    let params = LocalPlannerParams::default();
    let mut nf = NavigationFunction::new();
    let mut path = Vec::new();
    let mut k = 0;
    b.bench_local(|| {
        let i = k % cycles.len();
        k += 1;
        let robot = cycles[i].pose.position();
        nf.compute_towards(&cost_maps[i], cycles[i].goal, robot).unwrap();
        divan::black_box(
            descend_settling(&mut nf, &cost_maps[i], robot, &params.gradient, &mut path).unwrap(),
        );
    });
}

#[divan::bench(sample_count = 200)]
fn local_direction(b: Bencher) {
    let (grid, map) = load("building_31");
    let cycles = cycles(&grid, &map);
    let cost_maps = cost_maps(&map, &cycles);
    let functions: Vec<NavigationFunction> = cost_maps
        .iter()
        .zip(&cycles)
        .map(|(cm, c)| {
            let mut nf = NavigationFunction::new();
            nf.compute(cm, c.goal).unwrap();
            nf
        })
        .collect();
    let params = GradientParams::default();
    let mut k = 0;
    b.bench_local(|| {
        let i = k % cycles.len();
        k += 1;
        divan::black_box(direction(&functions[i], cycles[i].pose.position(), &params).unwrap());
    });
}

#[divan::bench(args = ["building_31", "levine"], sample_count = 10)]
fn static_layer(b: Bencher, name: &str) {
    let (_, map) = load(name);
    let params = LocalPlannerParams::default();
    b.bench_local(|| divan::black_box(StaticCostLayer::new(params.cost, &map).unwrap()));
}

#[divan::bench(args = ["building_31", "levine"], sample_count = 10)]
fn global_cost_map(b: Bencher, name: &str) {
    let (_, map) = load(name);
    b.bench_local(|| divan::black_box(GlobalPlanner::new(&map, RouteParams::default()).unwrap()));
}

#[divan::bench(args = ["building_31", "levine"], sample_count = 10)]
fn global_route(b: Bencher, name: &str) {
    let (_, map) = load(name);
    let pairs = pairs(name);
    let mut planner = GlobalPlanner::new(&map, RouteParams::default()).unwrap();
    let mut k = 0;
    b.bench_local(|| {
        let (start, goal) = pairs[k % pairs.len()];
        k += 1;
        divan::black_box(planner.plan(start, goal).unwrap().goals.len());
    });
}
