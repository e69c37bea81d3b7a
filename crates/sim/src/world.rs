//! A world: the static map, what is precomputed from it, and the crowd that
//! walks in it.

use std::sync::Arc;

use robot::Vec2;

use crate::crowd_params::CrowdParams;
use crate::distance_field::DistanceField;
use crate::error::Result;
use crate::grid::OccupancyGrid;
use crate::routes::Routes;

/// The static part of every run in one place: the occupancy grid, its
/// distance field (built once here), the crowd's parameters and the
/// people's routes to their waypoints.
///
/// Cloning is cheap (the grid and the field are shared), so one world can be
/// given to thousands of runs on any number of threads, and variants (other
/// crowd densities) made with [`World::with_crowd`] share the map.
///
/// ```
/// use sim::{CrowdParams, CrowdSize, OccupancyGrid, World};
/// let grid = OccupancyGrid::new(100, 80, 0.05, robot::Pose::default());
/// let empty = World::new(grid);
/// let busy = empty.clone().with_crowd(CrowdParams {
///     size: CrowdSize::PerArea { people_per_100m2: 20.0 },
///     ..CrowdParams::default()
/// })?;
/// assert_eq!(busy.grid().width(), 100);
/// # Ok::<(), sim::Error>(())
/// ```
#[derive(Debug, Clone)]
pub struct World {
    grid: Arc<OccupancyGrid>,
    field: Arc<DistanceField>,
    free_area_m2: f64,
    crowd: CrowdParams,
    routes: Arc<Routes>,
}

impl World {
    /// A world on `grid`, without people. Builds the distance field:
    /// `O(cells)`, about 10 ms for a 700 × 650 map.
    pub fn new(grid: OccupancyGrid) -> World {
        let field = DistanceField::new(&grid);
        let free_area_m2 = grid.free_area_m2();
        let routes = Routes::new(&grid, &field, &[], CrowdParams::default().radius_m);
        World {
            grid: Arc::new(grid),
            field: Arc::new(field),
            free_area_m2,
            crowd: CrowdParams::default(),
            routes: Arc::new(routes),
        }
    }

    /// The same map with this crowd (parameters checked, waypoints must lie
    /// on the map). Builds the people's routes to the waypoints
    /// ([`Routes`]): a few milliseconds per waypoint.
    pub fn with_crowd(mut self, crowd: CrowdParams) -> Result<World> {
        crowd.validate()?;
        for (k, w) in crowd.waypoints.iter().enumerate() {
            if !self.on_map(*w) {
                return Err(crate::Error::Geometry(format!(
                    "crowd waypoint {k} ({:.3}, {:.3}) is outside the map",
                    w.x, w.y
                )));
            }
        }
        self.routes = Arc::new(Routes::new(
            &self.grid,
            &self.field,
            &crowd.waypoints,
            crowd.radius_m,
        ));
        self.crowd = crowd;
        Ok(self)
    }

    /// The same world with the people placed at `positions` (the crowd's
    /// [`CrowdParams::positions`] replaced; its routes, which do not depend
    /// on them, are shared, not rebuilt).
    pub fn with_positions(&self, positions: Vec<Vec2>) -> Result<World> {
        let crowd = CrowdParams {
            positions,
            ..self.crowd.clone()
        };
        crowd.validate()?;
        Ok(World {
            crowd,
            ..self.clone()
        })
    }

    /// The people's routes to the crowd's waypoints.
    pub fn routes(&self) -> &Routes {
        &self.routes
    }

    /// The occupancy grid.
    pub fn grid(&self) -> &OccupancyGrid {
        &self.grid
    }

    /// The distance field of the grid.
    pub fn distance_field(&self) -> &DistanceField {
        &self.field
    }

    /// The crowd's parameters.
    pub fn crowd(&self) -> &CrowdParams {
        &self.crowd
    }

    /// Free area of the map, m² (cached).
    pub fn free_area_m2(&self) -> f64 {
        self.free_area_m2
    }

    /// Whether a world point lies inside the map's rectangle.
    pub fn on_map(&self, p: Vec2) -> bool {
        self.grid.contains(self.grid.cell_of(p))
    }

    /// The world-frame axis-aligned bounding box of the map, `(min, max)`.
    pub fn bounds(&self) -> (Vec2, Vec2) {
        let g = &self.grid;
        let (w, h) = (
            g.width() as f64 * g.resolution_m(),
            g.height() as f64 * g.resolution_m(),
        );
        let corners = [
            g.to_world(Vec2::new(0.0, 0.0)),
            g.to_world(Vec2::new(w, 0.0)),
            g.to_world(Vec2::new(0.0, h)),
            g.to_world(Vec2::new(w, h)),
        ];
        let mut lo = corners[0];
        let mut hi = corners[0];
        for c in &corners[1..] {
            lo = Vec2::new(lo.x.min(c.x), lo.y.min(c.y));
            hi = Vec2::new(hi.x.max(c.x), hi.y.max(c.y));
        }
        (lo, hi)
    }
}
