//! One control cycle of AutoMove: plan in a window centred on the robot.
//!
//! Every cycle (Konolige's LAGR/Pioneer scheme, tour-guide spec): build the
//! [`CostMap`] of a 10 m × 10 m window of the static map around the robot
//! with the latest laser endpoints as extra obstacles, propagate the
//! [`NavigationFunction`] from the current (intermediate) goal, and follow
//! its negative gradient from the robot ([`descend`]): the first step gives
//! the direction to drive, the whole descent the path to show. The
//! [`LocalPlanner`] keeps every buffer between cycles, so a cycle allocates
//! nothing once warm.
//!
//! The wavefront is aimed at the robot and settles only what the descent
//! reads ([`NavigationFunction::compute_towards`], [`descend_settling`]):
//! the same direction and path as with `N` over the whole window, bit for
//! bit (see [`super::navigation_function`]), for about a twentieth of the
//! cells. [`LocalPlanner::navigation_function`] completes `N` on demand.
//!
//! [`descend`]: super::descend
//!
//! The map's part of the cost map is computed once, on the first cycle on a
//! map: a [`StaticCostLayer`] of the whole map, kept. Each cycle copies the
//! window from it and adds the obstacle points ([`CostMap::rebuild_on`]:
//! the same costs as building the window from the map, bit for bit). A
//! cycle checks that the map it is given has, over the window and its
//! inflation margin, the cells the layer was made from; if not (another
//! map), it makes the layer again. Planners on the same map can share one
//! ([`LocalPlanner::with_static_layer`]).
//!
//! The spec's exceptions map to errors: *goal occupation* is
//! [`PlanningError::GoalBlocked`] with [`Blocked::Sensed`] (or
//! [`Blocked::Inflated`] next to a sensed obstacle); *path blocking* is
//! [`PlanningError::Unreachable`].
//!
//! [`Blocked::Sensed`]: super::Blocked::Sensed
//! [`Blocked::Inflated`]: super::Blocked::Inflated

use std::sync::Arc;

use robot::{GridMap, Vec2};

use super::gradient::{DescentInfo, GradientParams, descend_settling};
use super::{
    CostMap, CostMapInfo, CostParams, NavigationFunction, NavigationInfo, PlanningError, StaticCostLayer,
    Window, check_start,
};

/// Parameters of the local planner.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LocalPlannerParams {
    /// Side of the square window centred on the robot, metres (rounded to
    /// whole cells). Default 10.
    pub window_size_m: f64,
    /// The cost model. Default [`CostParams::default`].
    pub cost: CostParams,
    /// The gradient descent. Default [`GradientParams::default`].
    pub gradient: GradientParams,
    /// A robot whose own cell is lethal only by inflation (within the
    /// inscribed radius of an obstacle, not in it) starts from the nearest
    /// cell that is not lethal within this distance, metres. Default 0.3.
    pub escape_radius_m: f64,
}

impl Default for LocalPlannerParams {
    fn default() -> Self {
        LocalPlannerParams {
            window_size_m: 10.0,
            cost: CostParams::default(),
            gradient: GradientParams::default(),
            escape_radius_m: 0.3,
        }
    }
}

impl LocalPlannerParams {
    /// Checks every field (`window_size_m` a finite number > 0).
    pub fn validate(&self) -> Result<(), PlanningError> {
        if !(self.window_size_m.is_finite() && self.window_size_m > 0.0) {
            return Err(PlanningError::BadParam {
                name: "window_size_m",
                value: self.window_size_m,
                expected: "a finite number > 0",
            });
        }
        if !(self.escape_radius_m.is_finite() && self.escape_radius_m >= 0.0) {
            return Err(PlanningError::BadParam {
                name: "escape_radius_m",
                value: self.escape_radius_m,
                expected: "a finite number ≥ 0",
            });
        }
        self.cost.validate()?;
        self.gradient.validate()
    }
}

/// The outcome of one cycle.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct LocalPlan {
    /// Unit vector (world frame) to drive along: the first step down the
    /// gradient; zero when the robot is on the goal point.
    pub direction: Vec2,
    /// The window planned over.
    pub window: Window,
    /// The cost map's build.
    pub cost_map: CostMapInfo,
    /// The navigation function's computation.
    pub navigation: NavigationInfo,
    /// The descent from the robot (its `start_value` is `N` at the robot).
    pub descent: DescentInfo,
}

/// The local planner and its buffers (module docs).
#[derive(Debug, Clone)]
pub struct LocalPlanner {
    params: LocalPlannerParams,
    /// The static layer of the map of the last cycles.
    layer: Option<Arc<StaticCostLayer>>,
    cost_map: Option<CostMap>,
    nf: NavigationFunction,
    path: Vec<Vec2>,
}

impl LocalPlanner {
    /// A planner. Errors: invalid parameters.
    pub fn new(params: LocalPlannerParams) -> Result<LocalPlanner, PlanningError> {
        params.validate()?;
        Ok(LocalPlanner {
            params,
            layer: None,
            cost_map: None,
            nf: NavigationFunction::new(),
            path: Vec::new(),
        })
    }

    /// A planner starting with a static layer made beforehand (to share one
    /// between planners on the same map: it is immutable). A cycle on a map
    /// the layer does not match, or with another cost model, makes its own.
    /// Errors: invalid parameters.
    pub fn with_static_layer(
        params: LocalPlannerParams,
        layer: Arc<StaticCostLayer>,
    ) -> Result<LocalPlanner, PlanningError> {
        let mut planner = LocalPlanner::new(params)?;
        planner.layer = Some(layer);
        Ok(planner)
    }

    /// A new planner with this one's parameters and static layer (shared),
    /// none of its buffers: what [`LocalPlanner::with_static_layer`] makes
    /// with them, without checking the parameters again.
    pub fn sharing_layer(&self) -> LocalPlanner {
        LocalPlanner {
            params: self.params,
            layer: self.layer.clone(),
            cost_map: None,
            nf: NavigationFunction::new(),
            path: Vec::new(),
        }
    }

    /// The parameters.
    pub fn params(&self) -> &LocalPlannerParams {
        &self.params
    }

    /// The static layer of the map of the last cycles (`None` before the
    /// first).
    pub fn static_layer(&self) -> Option<&Arc<StaticCostLayer>> {
        self.layer.as_ref()
    }

    /// One cycle: the window of `map` centred on `robot`, `obstacles`
    /// (world points, e.g. [`super::laser_endpoints`]) added, the navigation
    /// function towards `goal`, and the descent from `robot` (kept in
    /// [`LocalPlanner::path`]).
    ///
    /// The first cycle on a map makes its [`StaticCostLayer`] (one distance
    /// transform of the whole map, module docs).
    ///
    /// Errors: a non-finite point ([`PlanningError::BadPoint`]),
    /// [`PlanningError::StartBlocked`] (the robot's cell is lethal — in an
    /// obstacle or within its inscribed radius of one),
    /// [`PlanningError::NoFreeCell`], [`PlanningError::GoalOutsideWindow`],
    /// [`PlanningError::GoalBlocked`] (goal occupation),
    /// [`PlanningError::Unreachable`] (path blocking). After an error,
    /// [`LocalPlanner::path`] is empty.
    pub fn plan(
        &mut self,
        map: &GridMap,
        robot: Vec2,
        goal: Vec2,
        obstacles: &[Vec2],
    ) -> Result<LocalPlan, PlanningError> {
        self.path.clear();
        // Until computed on this cycle's cost map, no navigation function.
        self.nf.forget();
        let window = Window::centred(map, robot, self.params.window_size_m)?;
        let layer = match &self.layer {
            Some(l) if l.params() == &self.params.cost && l.matches(map, &window) => l,
            _ => self
                .layer
                .insert(Arc::new(StaticCostLayer::new(self.params.cost, map)?)),
        };
        let cost_map = match &mut self.cost_map {
            Some(c) => {
                c.rebuild_on(layer, window, obstacles)?;
                c
            }
            None => self.cost_map.insert(CostMap::build_on(layer, window, obstacles)?),
        };
        if cost_map.info().free_cells == 0 {
            return Err(PlanningError::NoFreeCell { window });
        }
        // A robot that has come within the inscribed radius of an obstacle
        // (a person stepped close, the estimate shifted) starts its descent
        // from the nearest cell that is not lethal, if one is near enough.
        let start = match check_start(cost_map, robot) {
            Ok(_) => robot,
            Err(
                e @ PlanningError::StartBlocked {
                    why: super::Blocked::Inflated { .. },
                    ..
                },
            ) => super::nearest_free(cost_map, robot, self.params.escape_radius_m).ok_or(e)?,
            Err(e) => return Err(e),
        };
        // N towards the start: only what the descent reads is settled, and
        // the descent is the one on the whole window's N (module docs).
        self.nf.compute_towards(cost_map, goal, start)?;
        let descent = descend_settling(
            &mut self.nf,
            cost_map,
            start,
            &self.params.gradient,
            &mut self.path,
        )?;
        let navigation = self.nf.info();
        if start != robot {
            self.path.insert(0, robot);
        }
        let direction = match self.path.as_slice() {
            [a, b, ..] if a.dist(*b) > 0.0 => (*b - *a).scale(1.0 / a.dist(*b)),
            _ => Vec2::default(),
        };
        Ok(LocalPlan {
            direction,
            window,
            cost_map: cost_map.info(),
            navigation,
            descent,
        })
    }

    /// The path of the last successful cycle, world frame, from the robot
    /// to the goal (empty after an error).
    pub fn path(&self) -> &[Vec2] {
        &self.path
    }

    /// The cost map of the last cycle (`None` before the first).
    pub fn cost_map(&self) -> Option<&CostMap> {
        self.cost_map.as_ref()
    }

    /// The navigation function of the last cycle, over the whole window:
    /// the cycle settled only what the descent needed, this settles the rest
    /// first (the same values as [`NavigationFunction::compute`]). Empty
    /// (no goal) if the last cycle failed before computing it.
    pub fn navigation_function(&mut self) -> &NavigationFunction {
        if let Some(cost_map) = &self.cost_map {
            // The function was computed on this cost map: it cannot fail.
            let _ = self.nf.complete(cost_map);
        }
        &self.nf
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Blocked;
    use robot::{Cell, CellIndex, Pose};

    /// A 20 m × 20 m free map at 0.05 m with a 4 m wall at x = 12 m.
    fn map() -> GridMap {
        let (w, h) = (400, 400);
        let mut cells = vec![Cell::Free; w * h];
        for j in 160..240 {
            cells[j * w + 240] = Cell::Occupied;
        }
        GridMap::new(w, h, 0.05, Pose::default(), cells).unwrap()
    }

    #[test]
    fn a_cycle_plans_round_a_wall_and_a_person() {
        let m = map();
        let mut lp = LocalPlanner::new(LocalPlannerParams::default()).unwrap();
        let robot = Vec2::new(9.0, 10.0);
        let goal = Vec2::new(13.5, 10.0);
        let plan = lp.plan(&m, robot, goal, &[]).unwrap();
        assert_eq!((plan.window.width(), plan.window.height()), (200, 200));
        assert_eq!(
            plan.window.index_of(CellIndex { i: 180, j: 200 }),
            Some(100 * 200 + 100)
        );
        let path = lp.path();
        assert_eq!(path[0], robot);
        assert_eq!(*path.last().unwrap(), goal);
        assert!((plan.direction.norm() - 1.0).abs() < 1e-9);
        // Round the wall's end (y = 8 m or 12 m), never through it.
        assert!(path.iter().any(|p| p.y > 12.3 || p.y < 7.7));
        let cm = lp.cost_map().unwrap();
        for p in path {
            assert!(!cm.is_lethal(m.cell_of(*p)), "{p:?}");
        }
        // A person standing on the goal: goal occupation.
        let person = [goal + Vec2::new(0.02, 0.0)];
        assert!(matches!(
            lp.plan(&m, robot, goal, &person),
            Err(PlanningError::GoalBlocked {
                why: Blocked::Sensed,
                ..
            })
        ));
        assert!(lp.path().is_empty());
        // A goal beyond the window.
        assert!(matches!(
            lp.plan(&m, robot, Vec2::new(16.0, 10.0), &[]),
            Err(PlanningError::GoalOutsideWindow { .. })
        ));
        // The robot within the inscribed radius of the wall starts from the
        // nearest cell that is not lethal.
        let near = Vec2::new(11.9, 10.0);
        lp.plan(&m, near, Vec2::new(9.0, 10.0), &[]).unwrap();
        let path = lp.path().to_vec();
        assert_eq!(path[0], near);
        let cm = lp.cost_map().unwrap();
        assert!(cm.is_lethal(m.cell_of(near)) && !cm.is_lethal(m.cell_of(path[1])));
        assert!(path[1].dist(near) <= LocalPlannerParams::default().escape_radius_m);
        // Not without the escape, and never from inside the wall.
        let mut strict = LocalPlanner::new(LocalPlannerParams {
            escape_radius_m: 0.0,
            ..LocalPlannerParams::default()
        })
        .unwrap();
        assert!(matches!(
            strict.plan(&m, near, Vec2::new(9.0, 10.0), &[]),
            Err(PlanningError::StartBlocked {
                why: Blocked::Inflated { .. },
                ..
            })
        ));
        assert!(matches!(
            lp.plan(&m, Vec2::new(12.02, 10.0), Vec2::new(9.0, 10.0), &[]),
            Err(PlanningError::StartBlocked {
                why: Blocked::Occupied,
                ..
            })
        ));
    }

    #[test]
    fn the_navigation_function_of_a_cycle_is_the_whole_windows() {
        let m = map();
        let mut lp = LocalPlanner::new(LocalPlannerParams::default()).unwrap();
        let (robot, goal) = (Vec2::new(9.0, 10.0), Vec2::new(13.5, 10.0));
        let plan = lp.plan(&m, robot, goal, &[Vec2::new(10.0, 11.0)]).unwrap();
        let mut whole = NavigationFunction::new();
        let cost_map = lp.cost_map().unwrap().clone();
        let info = whole.compute(&cost_map, goal).unwrap();
        // The cycle settled a small part of the window.
        assert!(plan.navigation.reached_cells * 4 < info.reached_cells, "{plan:?}");
        let mut path = Vec::new();
        crate::descend(&whole, robot, &LocalPlannerParams::default().gradient, &mut path).unwrap();
        assert_eq!(lp.path(), path.as_slice());
        let nf = lp.navigation_function();
        assert!(nf.is_complete());
        for k in 0..plan.window.len() {
            let c = plan.window.cell_at(k);
            assert_eq!(nf.value(c).to_bits(), whole.value(c).to_bits(), "{c:?}");
        }
        // After a cycle that failed before computing it: none.
        assert!(lp.plan(&m, Vec2::new(12.02, 10.0), goal, &[]).is_err());
        assert!(lp.navigation_function().goal_cells().is_empty());
    }

    #[test]
    fn another_map_makes_the_static_layer_again() {
        let m = map();
        let mut lp = LocalPlanner::new(LocalPlannerParams::default()).unwrap();
        let (robot, goal) = (Vec2::new(9.0, 10.0), Vec2::new(13.5, 10.0));
        lp.plan(&m, robot, goal, &[]).unwrap();
        // The same frame, the wall gone: a straight path now.
        let open = GridMap::new(400, 400, 0.05, Pose::default(), vec![Cell::Free; 400 * 400]).unwrap();
        lp.plan(&open, robot, goal, &[]).unwrap();
        assert!(lp.path().iter().all(|p| (p.y - 10.0).abs() < 0.1));
        let mut fresh = LocalPlanner::new(LocalPlannerParams::default()).unwrap();
        fresh.plan(&open, robot, goal, &[]).unwrap();
        assert_eq!(lp.path(), fresh.path());
        // And back: round the wall again.
        lp.plan(&m, robot, goal, &[]).unwrap();
        assert!(lp.path().iter().any(|p| p.y > 12.3 || p.y < 7.7));
        // A layer shared with another planner: used as it is.
        let layer = Arc::clone(lp.static_layer().unwrap());
        let mut shared =
            LocalPlanner::with_static_layer(LocalPlannerParams::default(), Arc::clone(&layer)).unwrap();
        shared.plan(&m, robot, goal, &[]).unwrap();
        assert!(Arc::ptr_eq(shared.static_layer().unwrap(), &layer));
        assert_eq!(shared.path(), lp.path());
        // With another cost model, the planner makes its own.
        let mut other = LocalPlannerParams::default();
        other.cost.inscribed_radius_m = 0.42;
        let mut own = LocalPlanner::with_static_layer(other, Arc::clone(&layer)).unwrap();
        own.plan(&m, robot, goal, &[]).unwrap();
        assert!(!Arc::ptr_eq(own.static_layer().unwrap(), &layer));
        assert_eq!(own.static_layer().unwrap().params(), &other.cost);
    }

    #[test]
    fn a_ring_of_people_blocks_the_path() {
        let m = map();
        let mut lp = LocalPlanner::new(LocalPlannerParams::default()).unwrap();
        let robot = Vec2::new(5.0, 5.0);
        let ring: Vec<Vec2> = (0..400)
            .map(|k| {
                let a = k as f64 * std::f64::consts::TAU / 400.0;
                robot + Vec2::new(1.5 * a.cos(), 1.5 * a.sin())
            })
            .collect();
        assert!(matches!(
            lp.plan(&m, robot, Vec2::new(8.0, 5.0), &ring),
            Err(PlanningError::Unreachable { .. })
        ));
    }

    #[test]
    fn bad_window_size_is_an_error() {
        for s in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            let p = LocalPlannerParams {
                window_size_m: s,
                ..LocalPlannerParams::default()
            };
            assert!(matches!(
                LocalPlanner::new(p),
                Err(PlanningError::BadParam { .. })
            ));
        }
    }
}
