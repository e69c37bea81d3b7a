//! Properties of the navigation function and its gradient on random grids.
//!
//! * `N` equals shortest-path costs computed by an independent, plain
//!   Dijkstra (an `O(V²)` array scan over the same 8-connected graph, with
//!   its own neighbour enumeration and bounds checks), to 1e-9, with and
//!   without intrinsic cost;
//! * from every cell with a finite `N`, the gradient descent reaches the
//!   goal without entering a lethal cell and without its segments crossing
//!   one;
//! * the same input gives the same output, bit for bit;
//! * a cost map built on the map's static layer plus the obstacle points
//!   equals the one built from the map, bit for bit;
//! * computed towards a start, the navigation function's settled values are
//!   those of the whole computation and the descent from that start (which
//!   settles what it reads) is the same path, bit for bit, from every cell;
//!   completed, the function is the whole computation's.

use std::sync::Arc;

use planning::{
    CostMap, CostParams, GradientParams, NavigationFunction, PlanningError, StaticCostLayer, Window, descend,
    descend_settling, global_route::segment_clear,
};
use proptest::prelude::*;
use proptest::strategy::ValueTree;
use robot::{Cell, CellIndex, GridMap, Pose, Vec2};

/// A random map and everything planned on it.
#[derive(Debug, Clone)]
struct Case {
    map: GridMap,
    window: Window,
    obstacles: Vec<Vec2>,
    params: CostParams,
    /// Picks the goal among the window's cells with a finite cost.
    goal_pick: usize,
}

fn case(with_cost: bool) -> impl Strategy<Value = Case> {
    (
        (3usize..32, 3usize..32),
        prop_oneof![Just(0.05), Just(0.1), Just(0.25)],
        (-3.0f64..3.0, -3.0f64..3.0, -3.2f64..3.2),
        (0.0f64..0.25, 0.0f64..0.08),
        any::<u64>(),
        (
            0.0f64..1.6,
            0.0f64..3.0,
            prop_oneof![3 => 0.0f64..8.0, 1 => 0.0f64..1000.0],
            0.0f64..10.0,
        ),
        any::<bool>(),
        (-4i64..4, -4i64..4, 1usize..30, 1usize..30),
        0usize..8,
        any::<usize>(),
    )
        .prop_map(
            move |((w, h), res, (ox, oy, th), (p_occ, p_unk), seed, radii, whole, sub, n_pts, goal_pick)| {
                let mut s = seed | 1;
                let mut next = move || {
                    s ^= s << 13;
                    s ^= s >> 7;
                    s ^= s << 17;
                    (s >> 11) as f64 / (1u64 << 53) as f64
                };
                let cells: Vec<Cell> = (0..w * h)
                    .map(|_| {
                        let u = next();
                        if u < p_occ {
                            Cell::Occupied
                        } else if u < p_occ + p_unk {
                            Cell::Unknown
                        } else {
                            Cell::Free
                        }
                    })
                    .collect();
                let map = GridMap::new(w, h, res, Pose::new(ox, oy, th), cells).expect("valid map");
                // Radii in cells, so that they matter at every resolution.
                let (ins_cells, extra_cells, max_cost, decay_cells) = radii;
                let params = CostParams {
                    inscribed_radius_m: ins_cells * res,
                    inflation_radius_m: (ins_cells + extra_cells) * res,
                    max_cost: if with_cost { max_cost } else { 0.0 },
                    decay_per_m: decay_cells / res / 10.0,
                };
                let window = if whole {
                    Window::whole(&map).expect("whole window")
                } else {
                    Window::new(&map, CellIndex { i: sub.0, j: sub.1 }, sub.2, sub.3).expect("window")
                };
                let obstacles = (0..n_pts)
                    .map(|_| map.to_world(Vec2::new(next() * w as f64 * res, next() * h as f64 * res)))
                    .collect();
                Case {
                    map,
                    window,
                    obstacles,
                    params,
                    goal_pick,
                }
            },
        )
}

/// Shortest-path cost from every window cell to `goal` over the same graph
/// as the navigation function, by the textbook O(V²) Dijkstra.
fn reference(cost: &CostMap, goal: CellIndex) -> Vec<f64> {
    let window = cost.window();
    let n = window.len();
    let res = window.resolution_m();
    let c: Vec<f64> = (0..n).map(|k| cost.cost(window.cell_at(k))).collect();
    let index = |i: i64, j: i64| window.index_of(CellIndex { i, j });
    let mut dist = vec![f64::INFINITY; n];
    let mut done = vec![false; n];
    dist[window.index_of(goal).expect("goal in window")] = 0.0;
    loop {
        // The unsettled cell with the smallest finite distance.
        let mut best: Option<usize> = None;
        for k in 0..n {
            if !done[k] && dist[k].is_finite() && best.is_none_or(|b| dist[k] < dist[b]) {
                best = Some(k);
            }
        }
        let Some(a) = best else { break };
        done[a] = true;
        let ca = window.cell_at(a);
        for di in -1i64..=1 {
            for dj in -1i64..=1 {
                if di == 0 && dj == 0 {
                    continue;
                }
                let Some(b) = index(ca.i + di, ca.j + dj) else {
                    continue;
                };
                if c[b].is_infinite() {
                    continue;
                }
                let step = if di != 0 && dj != 0 {
                    // No corner cutting: both orthogonal cells passable.
                    let side_a = index(ca.i + di, ca.j).is_some_and(|k| c[k].is_finite());
                    let side_b = index(ca.i, ca.j + dj).is_some_and(|k| c[k].is_finite());
                    if !(side_a && side_b) {
                        continue;
                    }
                    res * std::f64::consts::SQRT_2
                } else {
                    res
                };
                let candidate = dist[a] + step * (1.0 + 0.5 * (c[a] + c[b]));
                if candidate < dist[b] {
                    dist[b] = candidate;
                }
            }
        }
    }
    dist
}

/// The cost map of a case and its goal cell (`None`: no free cell).
fn setup(case: &Case) -> (CostMap, Option<CellIndex>) {
    let cost = CostMap::build(case.params, &case.map, case.window, &case.obstacles).expect("cost map");
    let window = cost.window();
    let free: Vec<CellIndex> = (0..window.len())
        .map(|k| window.cell_at(k))
        .filter(|&c| !cost.is_lethal(c))
        .collect();
    let goal = (!free.is_empty()).then(|| free[case.goal_pick % free.len()]);
    (cost, goal)
}

fn check_against_reference(case: &Case) -> Result<(), TestCaseError> {
    let (cost, goal) = setup(case);
    let window = cost.window();
    let mut nf = NavigationFunction::new();
    let Some(goal) = goal else {
        let r = nf.compute(&cost, window.cell_center(CellIndex { i: 0, j: 0 }));
        let no_free_cell = matches!(r, Err(PlanningError::NoFreeCell { .. }));
        prop_assert!(no_free_cell, "{:?}", r);
        return Ok(());
    };
    nf.compute(&cost, window.cell_center(goal)).expect("goal is free");
    let expected = reference(&cost, goal);
    for (k, &e) in expected.iter().enumerate() {
        let got = nf.value(window.cell_at(k));
        prop_assert!(
            (got.is_infinite() && e.is_infinite()) || (got - e).abs() <= 1e-9,
            "cell {:?}: N = {got}, reference {e}",
            window.cell_at(k)
        );
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    #[test]
    fn without_intrinsic_cost_n_is_the_shortest_grid_path(case in case(false)) {
        check_against_reference(&case)?;
    }

    #[test]
    fn with_intrinsic_cost_n_is_the_cheapest_grid_path(case in case(true)) {
        check_against_reference(&case)?;
    }

    #[test]
    fn descent_reaches_the_goal_from_every_reachable_cell(case in case(true), frac in (0.0f64..1.0, 0.0f64..1.0)) {
        let (cost, goal) = setup(&case);
        let Some(goal) = goal else { return Ok(()) };
        let window = cost.window();
        let goal_point = window.cell_center(goal);
        let mut nf = NavigationFunction::new();
        nf.compute(&cost, goal_point).expect("goal is free");
        let params = GradientParams::default();
        let mut path = Vec::new();
        for k in 0..window.len() {
            let c = window.cell_at(k);
            if nf.value(c).is_infinite() {
                // Lethal or cut off: the descent says so, without panicking.
                let r = descend(&nf, window.cell_center(c), &params, &mut path);
                let unreachable = matches!(r, Err(PlanningError::Unreachable { .. }));
                prop_assert!(unreachable, "{:?}", r);
                continue;
            }
            // From the centre and from a point off the centre.
            let off = window.from_window(
                (c.i - window.min().i) as f64 + frac.0,
                (c.j - window.min().j) as f64 + frac.1,
            );
            for start in [window.cell_center(c), off] {
                if window.cell_of("start", start).expect("finite") != c {
                    continue; // rounding put the point in the next cell
                }
                let info = descend(&nf, start, &params, &mut path)
                    .map_err(|e| TestCaseError::fail(format!("from {c:?}: {e}")))?;
                prop_assert_eq!(path[0], start);
                prop_assert_eq!(*path.last().expect("a point"), goal_point);
                prop_assert_eq!(window.cell_of("end", *path.last().unwrap()).unwrap(), goal);
                for p in &path {
                    let pc = window.cell_of("p", *p).expect("finite");
                    prop_assert!(!cost.is_lethal(pc), "from {:?}: {:?} in lethal cell {:?}", c, p, pc);
                }
                for seg in path.windows(2) {
                    prop_assert!(
                        segment_clear(&cost, seg[0], seg[1]),
                        "from {:?}: segment {:?} → {:?} crosses a lethal cell", c, seg[0], seg[1]
                    );
                }
                let length: f64 = path.windows(2).map(|s| s[0].dist(s[1])).sum();
                prop_assert!((length - info.length_m).abs() < 1e-9);
                // The path cannot be shorter than the straight line.
                prop_assert!(info.length_m + 1e-9 >= start.dist(goal_point));
            }
        }
    }

    #[test]
    fn same_input_same_output(case in case(true)) {
        let run = || {
            let (cost, goal) = setup(&case);
            let goal = goal?;
            let window = cost.window();
            let mut nf = NavigationFunction::new();
            nf.compute(&cost, window.cell_center(goal)).ok()?;
            let values: Vec<u64> = (0..window.len()).map(|k| nf.value(window.cell_at(k)).to_bits()).collect();
            let mut paths = Vec::new();
            for k in (0..window.len()).step_by(7) {
                let mut path = Vec::new();
                let r = descend(&nf, window.cell_center(window.cell_at(k)), &GradientParams::default(), &mut path);
                paths.push((r.map(|i| i.length_m.to_bits()), path.iter().map(|p| (p.x.to_bits(), p.y.to_bits())).collect::<Vec<_>>()));
            }
            Some((values, paths))
        };
        prop_assert_eq!(run(), run());
    }
}

/// Everything a cost map answers, for every cell of its window and a ring
/// around it, is the same in both.
fn assert_same_cost_maps(a: &CostMap, b: &CostMap) -> Result<(), TestCaseError> {
    prop_assert_eq!(a.window(), b.window());
    prop_assert_eq!(a.info(), b.info());
    let w = a.window();
    for j in w.min().j - 1..=w.min().j + w.height() as i64 {
        for i in w.min().i - 1..=w.min().i + w.width() as i64 {
            let c = CellIndex { i, j };
            prop_assert_eq!(a.cost(c).to_bits(), b.cost(c).to_bits(), "cost of {:?}", c);
            prop_assert_eq!(a.why_lethal(c), b.why_lethal(c), "why {:?} is lethal", c);
            prop_assert_eq!(a.clearance_m(c), b.clearance_m(c), "clearance of {:?}", c);
        }
    }
    Ok(())
}

/// Obstacle points of a case plus points around and outside the window
/// (in its margin, off the map, not finite), several in one cell.
fn more_points(case: &Case, extra: &[(f64, f64)]) -> Vec<Vec2> {
    let w = case.window;
    let mut points = case.obstacles.clone();
    for &(fx, fy) in extra {
        // From 1.5 window sides left/below to 1.5 right/above.
        let x = (fx * 4.0 - 1.5) * w.width() as f64;
        let y = (fy * 4.0 - 1.5) * w.height() as f64;
        points.push(w.from_window(x, y));
        points.push(w.from_window(x.floor() + 0.5, y.floor() + 0.5));
    }
    points.push(Vec2::new(f64::NAN, 0.0));
    points
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    #[test]
    fn a_cost_map_on_the_static_layer_equals_one_built_from_the_map(
        case in case(true),
        extra in proptest::collection::vec((0.0f64..1.0, 0.0f64..1.0), 0..12),
    ) {
        let points = more_points(&case, &extra);
        let built = CostMap::build(case.params, &case.map, case.window, &points).expect("cost map");
        let layer = Arc::new(StaticCostLayer::new(case.params, &case.map).expect("layer"));
        prop_assert!(layer.matches(&case.map, &case.window));
        let on_layer = CostMap::build_on(&layer, case.window, &points).expect("cost map on the layer");
        assert_same_cost_maps(&built, &on_layer)?;
        // Rebuilt in place, from a cost map of another window and points.
        let mut reused = CostMap::build_on(&layer, Window::whole(&case.map).unwrap(), &case.obstacles)
            .expect("whole map");
        reused.rebuild_on(&layer, case.window, &points).expect("rebuild");
        assert_same_cost_maps(&built, &reused)?;
        // From the map again, after a layer of another cost model: the
        // first model's table must not linger.
        let mut other = case.params;
        other.max_cost = case.params.max_cost / 2.0 + 0.5;
        let other_layer = Arc::new(StaticCostLayer::new(other, &case.map).expect("layer"));
        let mut switched = CostMap::build(case.params, &case.map, case.window, &points).expect("cost map");
        switched.rebuild_on(&other_layer, case.window, &points).expect("rebuild on the other");
        prop_assert_eq!(switched.params(), &other);
        switched.rebuild(&case.map, case.window, &points).expect("rebuild from the map");
        let other_built = CostMap::build(other, &case.map, case.window, &points).expect("cost map");
        assert_same_cost_maps(&other_built, &switched)?;
    }
}

/// The bits of a descent's outcome.
fn bits(r: &Result<planning::DescentInfo, PlanningError>, path: &[Vec2]) -> (String, Vec<(u64, u64)>) {
    let outcome = match r {
        Ok(i) => format!(
            "ok {:x} {:x} {} {}",
            i.start_value.to_bits(),
            i.length_m.to_bits(),
            i.gradient_steps,
            i.fallback_steps
        ),
        Err(e) => format!("{e:?}"),
    };
    (
        outcome,
        path.iter().map(|p| (p.x.to_bits(), p.y.to_bits())).collect(),
    )
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    #[test]
    fn computed_towards_a_start_the_descent_is_the_same(
        case in case(true),
        frac in (0.0f64..1.0, 0.0f64..1.0),
    ) {
        let (cost, goal) = setup(&case);
        let Some(goal) = goal else { return Ok(()) };
        let window = cost.window();
        let goal_point = window.cell_center(goal);
        let mut whole = NavigationFunction::new();
        whole.compute(&cost, goal_point).expect("goal is free");
        let params = GradientParams::default();
        let (mut expected, mut got) = (Vec::new(), Vec::new());
        let mut towards = NavigationFunction::new();
        for k in 0..window.len() {
            let c = window.cell_at(k);
            // From a point off the centre: lethal, unreachable and free
            // cells alike.
            let start = window.from_window(
                (c.i - window.min().i) as f64 + frac.0,
                (c.j - window.min().j) as f64 + frac.1,
            );
            if window.cell_of("start", start).expect("finite") != c {
                continue; // rounding put the point in the next cell
            }
            let r_whole = descend(&whole, start, &params, &mut expected);
            towards.compute_towards(&cost, goal_point, start).expect("goal is free");
            prop_assert!(towards.is_settled(c));
            prop_assert_eq!(towards.value(c).to_bits(), whole.value(c).to_bits());
            let r_towards = descend_settling(&mut towards, &cost, start, &params, &mut got);
            prop_assert_eq!(bits(&r_whole, &expected), bits(&r_towards, &got), "from {:?}", c);
            // Whatever is settled is final.
            for q in 0..window.len() {
                let q = window.cell_at(q);
                if towards.is_settled(q) {
                    prop_assert_eq!(towards.value(q).to_bits(), whole.value(q).to_bits(), "{:?}", q);
                } else {
                    prop_assert_eq!(towards.value(q), f64::INFINITY);
                }
            }
        }
        // Completed, it is the whole computation.
        towards.complete(&cost).expect("same cost map");
        prop_assert!(towards.is_complete());
        for q in 0..window.len() {
            let q = window.cell_at(q);
            prop_assert_eq!(towards.value(q).to_bits(), whole.value(q).to_bits(), "{:?}", q);
        }
        prop_assert_eq!(towards.info().reached_cells, whole.info().reached_cells);
    }
}

/// A map that differs from the layer's in the window or its margin does not
/// match; one that differs farther away does.
#[test]
fn the_static_layer_matches_only_its_own_map_near_the_window() {
    use robot::{Cell, GridMap, Pose};
    let (w, h) = (60, 50);
    let map = GridMap::new(w, h, 0.1, Pose::default(), vec![Cell::Free; w * h]).unwrap();
    let params = CostParams::default(); // 1 m of inflation: 10 cells
    let layer = StaticCostLayer::new(params, &map).unwrap();
    let window = Window::new(&map, CellIndex { i: 20, j: 15 }, 20, 20).unwrap();
    assert!(layer.matches(&map, &window));
    let with = |i: usize, j: usize| {
        let mut cells = map.cells().to_vec();
        cells[j * w + i] = Cell::Occupied;
        GridMap::new(w, h, 0.1, Pose::default(), cells).unwrap()
    };
    assert!(!layer.matches(&with(25, 20), &window), "in the window");
    assert!(!layer.matches(&with(10, 15), &window), "in the margin");
    assert!(layer.matches(&with(9, 15), &window), "beyond the margin");
    assert!(layer.matches(&with(50, 45), &window), "beyond the margin");
    let moved = GridMap::new(w, h, 0.1, Pose::new(0.1, 0.0, 0.0), map.cells().to_vec()).unwrap();
    assert!(!layer.matches(
        &moved,
        &Window::new(&moved, CellIndex { i: 20, j: 15 }, 20, 20).unwrap()
    ));
}

/// A cost map rebuilt in place equals one built afresh (the planner reuses
/// its buffers every cycle).
#[test]
fn rebuilding_in_place_equals_building_afresh() {
    let mut runner = proptest::test_runner::TestRunner::deterministic();
    let strategy = case(true);
    let mut reused: Option<CostMap> = None;
    let mut nf_reused = NavigationFunction::new();
    for _ in 0..100 {
        let case = strategy.new_tree(&mut runner).expect("a case").current();
        let fresh = CostMap::build(case.params, &case.map, case.window, &case.obstacles).expect("cost map");
        let cm = match reused.as_mut() {
            Some(c) if c.params() == &case.params => {
                c.rebuild(&case.map, case.window, &case.obstacles)
                    .expect("rebuild");
                c
            }
            _ => reused.insert(fresh.clone()),
        };
        let window = fresh.window();
        for k in 0..window.len() {
            let c = window.cell_at(k);
            assert_eq!(cm.cost(c).to_bits(), fresh.cost(c).to_bits());
            assert_eq!(cm.why_lethal(c), fresh.why_lethal(c));
        }
        assert_eq!(cm.info(), fresh.info());
        let (_, goal) = setup(&case);
        if let Some(goal) = goal {
            let mut nf_fresh = NavigationFunction::new();
            nf_fresh.compute(&fresh, window.cell_center(goal)).unwrap();
            nf_reused.compute(cm, window.cell_center(goal)).unwrap();
            for k in 0..window.len() {
                let c = window.cell_at(k);
                assert_eq!(nf_fresh.value(c).to_bits(), nf_reused.value(c).to_bits());
            }
        }
    }
}
