//! AutoMove: the map-based planner of the tour-guide robot (docs/tour-guide.md).
//!
//! A global route on the static map ([`GlobalPlanner`]) gives intermediate
//! goals at most 4 m apart; every control cycle a navigation function over a
//! 10 m × 10 m window around the robot, with the current laser endpoints as
//! obstacles (so people appear), is propagated from the current
//! intermediate goal ([`LocalPlanner`]), and the robot steers at a point a
//! little way down its negative gradient. The velocity controller keeps to
//! the drive's limits: speeds capped, accelerations limited per cycle.
//!
//! **Exceptions.** *Path blocking*: no path in the window from the robot to
//! the current intermediate goal (people closing a corridor, a person
//! pressed against the robot). *Goal occupation*: the goal's cell is blocked
//! by what the laser sees (a person standing there). On either the robot
//! stops and asks the people around it to step aside
//! ([`robot::Request::StepAside`]); it keeps re-planning every cycle and
//! drives on as soon as a path exists. The planner is *Abnormal* only when
//! an exception has lasted `abnormal_after_s` (3 s by default, so that a
//! person crossing the path does not make it chatter), *Normal* otherwise.
//! An intermediate goal occupied by a person is skipped for the next one
//! when that one is in the window; only the final goal can be "occupied".
//!
//! **Obstacles.** The static map, plus the laser's echoes that the map does
//! not explain: an echo within `echo_tolerance_m` of a mapped wall is that
//! wall seen (the localizer's few centimetres of error and grazing beams put
//! echoes a cell or two in front of it), and counting it would only thicken
//! the wall and close the narrow gaps the route goes through.
//!
//! The robot's position comes from its localizer: a wrong estimate puts the
//! window, the goals and the laser endpoints in the wrong place — which is
//! why the supervisor switches to contour tracking when the localizer
//! warns.

use std::sync::Arc;

use robot::{Cell, Command, GridMap, LaserScan, Pose, Request, Vec2, wrap_angle};

use super::scan;
use planning::distance_transform::{BEYOND, DistanceTransform};
use planning::{
    Blocked, GlobalPlanner, LocalPlanner, LocalPlannerParams, PlanningError, Route, RouteParams,
    StaticCostLayer, laser_endpoints,
};

/// Parameters of AutoMove.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct AutoMoveParams {
    /// The local planner (window 10 m; its `cost.inscribed_radius_m` is the
    /// footprint kept clear of obstacles). Default: a 10 m window, an
    /// inscribed radius of 0.42 m between cell centres (Jinny's 0.35 m, half
    /// a cell, and 5 cm for the localizer's error: narrower than 0.79 m
    /// between walls is closed), inflation to 1 m.
    pub local: LocalPlannerParams,
    /// The global route (same cost model; intermediate goals ≤ 4 m apart).
    pub route: RouteParams,
    /// The robot's footprint radius, metres (for the speed in narrow
    /// places). Default 0.35.
    pub robot_radius_m: f64,
    /// Cruise speed, m/s. Default 0.5 (Jinny's); slower near the goal and
    /// where less than 0.4 m is left beside the footprint.
    pub cruise_mps: f64,
    /// Largest turn rate, rad/s. Default 1.0.
    pub max_turn_radps: f64,
    /// Largest change of the forward speed, m/s². Default 0.5.
    pub max_accel_mps2: f64,
    /// Largest change of the turn rate, rad/s². Default 2.0.
    pub max_turn_accel_radps2: f64,
    /// Gain from heading error to turn rate, 1/s. Default 2.0.
    pub k_heading: f64,
    /// The robot steers at the point this far down the gradient path,
    /// metres. Default 0.35 (longer cuts the corners of the path).
    pub lookahead_m: f64,
    /// An intermediate goal is passed within this distance, metres.
    /// Default 1.0.
    pub pass_goal_m: f64,
    /// An exception makes the planner Abnormal after this long, seconds.
    /// Default 3.
    pub abnormal_after_s: f64,
    /// Radius of the request to step aside, metres. Default 1.5.
    pub ask_radius_m: f64,
    /// The speed is kept low enough to stop (at 80 % of `max_accel_mps2`)
    /// before the footprint grown by this much touches anything the scan
    /// shows (a person stepping in front), metres. Default 0.06 (a
    /// remembered echo lies up to a cell from the nearest point of its
    /// wall).
    pub safety_margin_m: f64,
    /// Laser echoes within this distance of a mapped obstacle are that
    /// obstacle seen, not a new one, metres. Default 0.15 (the localizer's
    /// error and the spread of echoes at grazing angles).
    pub echo_tolerance_m: f64,
}

impl Default for AutoMoveParams {
    fn default() -> AutoMoveParams {
        let mut local = LocalPlannerParams::default();
        local.cost.inscribed_radius_m = 0.42;
        let mut route = RouteParams::default();
        route.cost.inscribed_radius_m = 0.44;
        AutoMoveParams {
            local,
            route,
            robot_radius_m: 0.35,
            cruise_mps: 0.5,
            max_turn_radps: 1.0,
            max_accel_mps2: 0.5,
            max_turn_accel_radps2: 2.0,
            k_heading: 2.0,
            lookahead_m: 0.35,
            pass_goal_m: 1.0,
            abnormal_after_s: 3.0,
            ask_radius_m: 1.5,
            safety_margin_m: 0.03,
            echo_tolerance_m: 0.15,
        }
    }
}

impl AutoMoveParams {
    /// Checks every field.
    pub fn validate(&self) -> Result<(), String> {
        self.local
            .validate()
            .map_err(|e| format!("automove.local: {e}"))?;
        self.route
            .validate()
            .map_err(|e| format!("automove.route: {e}"))?;
        for (name, v) in [
            ("robot_radius_m", self.robot_radius_m),
            ("cruise_mps", self.cruise_mps),
            ("max_turn_radps", self.max_turn_radps),
            ("max_accel_mps2", self.max_accel_mps2),
            ("max_turn_accel_radps2", self.max_turn_accel_radps2),
            ("k_heading", self.k_heading),
            ("lookahead_m", self.lookahead_m),
            ("pass_goal_m", self.pass_goal_m),
            ("ask_radius_m", self.ask_radius_m),
            ("safety_margin_m", self.safety_margin_m),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(format!("automove.{name} must be a finite number > 0, got {v}"));
            }
        }
        if !(self.echo_tolerance_m.is_finite() && (0.0..=5.0).contains(&self.echo_tolerance_m)) {
            return Err(format!(
                "automove.echo_tolerance_m must be within [0, 5] m, got {}",
                self.echo_tolerance_m
            ));
        }
        if !(self.abnormal_after_s.is_finite() && self.abnormal_after_s >= 0.0) {
            return Err(format!(
                "automove.abnormal_after_s must be a finite number ≥ 0, got {}",
                self.abnormal_after_s
            ));
        }
        Ok(())
    }
}

/// Speed falls within this distance of the last goal, metres.
const SLOW_NEAR_GOAL_M: f64 = 1.0;

/// The least fraction of cruise speed kept near the last goal.
const SLOW_NEAR_GOAL_MIN: f64 = 0.3;

/// Full speed with this much room to spare beyond the footprint, metres
/// (speed falls with less).
const SPARE_FOR_FULL_SPEED_M: f64 = 0.4;

/// The least fraction of cruise speed kept when scraping by a narrow place.
const SLOW_WHEN_NARROW_MIN: f64 = 0.35;

/// The safety layer plans braking at this fraction of `max_accel_mps2`
/// (dimensionless).
const BRAKING_FRACTION: f64 = 0.8;

/// An exception of the planner.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Exception {
    /// No path to the current intermediate goal.
    PathBlocking,
    /// The final goal is occupied.
    GoalOccupation,
}

impl Exception {
    /// Its name in events.
    pub fn name(self) -> &'static str {
        match self {
            Exception::PathBlocking => "path_blocking",
            Exception::GoalOccupation => "goal_occupation",
        }
    }
}

/// One cycle's output.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AutoMoveStep {
    /// The velocity command.
    pub command: Command,
    /// The exception this cycle, if any.
    pub exception: Option<Exception>,
    /// Abnormal: an exception has lasted `abnormal_after_s`.
    pub abnormal: bool,
    /// What to ask of the people around.
    pub request: Option<Request>,
    /// The intermediate goal steered at.
    pub goal: Vec2,
}

/// Why AutoMove cannot go somewhere at all.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum AutoMoveError {
    /// Bad parameters.
    #[error("{0}")]
    Params(String),
    /// No route on the static map.
    #[error("no route on the map: {0}")]
    Route(#[from] PlanningError),
}

/// AutoMove (module docs).
#[derive(Debug, Clone)]
pub struct AutoMove {
    p: AutoMoveParams,
    /// The map and what is built from it (below) are shared by the
    /// AutoMoves on one map ([`AutoMove::on_same_map`]).
    map: Arc<GridMap>,
    global: GlobalPlanner,
    local: LocalPlanner,
    route: Option<Route>,
    /// Index of the intermediate goal steered at.
    next: usize,
    /// When the current exception began.
    since_s: Option<f64>,
    /// The last command's speeds.
    last: (f64, f64),
    endpoints: Vec<Vec2>,
    /// Map cells within `echo_tolerance_m` of a blocked cell, row-major.
    near_wall: Arc<[bool]>,
    /// The scan's points near the robot, and recent ones out of view.
    nearby: scan::NearbyPoints,
}

impl AutoMove {
    /// AutoMove on a static map: the whole map's cost map (global routes)
    /// and static cost layer (local windows) are built here, once.
    pub fn new(map: &GridMap, params: AutoMoveParams) -> Result<AutoMove, AutoMoveError> {
        params.validate().map_err(AutoMoveError::Params)?;
        let blocked: Vec<u8> = map.cells().iter().map(|&c| u8::from(c != Cell::Free)).collect();
        let cap = (params.echo_tolerance_m / map.resolution_m()).round() as u32;
        let mut d2 = Vec::new();
        DistanceTransform::new().compute(&blocked, map.width(), map.height(), cap, &mut d2);
        let near_wall = d2.iter().map(|&d| d != BEYOND && d <= cap * cap).collect();
        let layer = Arc::new(StaticCostLayer::new(params.local.cost, map)?);
        Ok(AutoMove {
            p: params,
            map: Arc::new(map.clone()),
            global: GlobalPlanner::new(map, params.route)?,
            local: LocalPlanner::with_static_layer(params.local, layer)?,
            route: None,
            next: 0,
            since_s: None,
            last: (0.0, 0.0),
            endpoints: Vec::new(),
            near_wall,
            nearby: scan::NearbyPoints::default(),
        })
    }

    /// A new AutoMove on this one's map with its parameters: the same as
    /// [`AutoMove::new`] on the map (no route, nothing of this one's
    /// state), without building the map's cost map, static layer and wall
    /// mask again — they are shared. For missions after missions on one
    /// map.
    pub fn on_same_map(&self) -> AutoMove {
        AutoMove {
            p: self.p,
            map: Arc::clone(&self.map),
            global: self.global.on_same_map(),
            local: self.local.sharing_layer(),
            route: None,
            next: 0,
            since_s: None,
            last: (0.0, 0.0),
            endpoints: Vec::new(),
            near_wall: Arc::clone(&self.near_wall),
            nearby: scan::NearbyPoints::default(),
        }
    }

    /// The parameters.
    pub fn params(&self) -> &AutoMoveParams {
        &self.p
    }

    /// The static map.
    pub fn map(&self) -> &GridMap {
        &self.map
    }

    /// Plans the global route from `from` to `goal`.
    pub fn set_goal(&mut self, from: Vec2, goal: Vec2) -> Result<&Route, AutoMoveError> {
        let route = self.global.plan(from, goal)?;
        self.next = 0;
        self.since_s = None;
        Ok(self.route.insert(route))
    }

    /// The route, once a goal is set.
    pub fn route(&self) -> Option<&Route> {
        self.route.as_ref()
    }

    /// The gradient path of the last cycle, from the robot down to the goal
    /// steered at (world frame; empty after an exception).
    pub fn path(&self) -> &[Vec2] {
        self.local.path()
    }

    /// Forgets the exception timer and the last speeds (after another
    /// behaviour drove).
    pub fn resume(&mut self, v_mps: f64, omega_radps: f64) {
        self.since_s = None;
        self.last = (v_mps, omega_radps);
    }

    /// One control cycle from the pose estimate, the scan, the odometry (for
    /// the short memory of points out of the laser's view) and the time.
    pub fn step(
        &mut self,
        estimate: Pose,
        scan: &LaserScan,
        odometry: Pose,
        dt_s: f64,
        time_s: f64,
    ) -> AutoMoveStep {
        let here = estimate.position();
        let Some(route) = &self.route else {
            return self.stopped(here, Some(Exception::PathBlocking), dt_s, time_s);
        };
        let goals = route.goals.clone();
        let last = goals.len().saturating_sub(1);
        // Pass the intermediate goals already reached, or overtaken: a
        // later goal nearer than the current one.
        while self.next < last
            && (here.dist(goals[self.next]) <= self.p.pass_goal_m
                || here.dist(goals[self.next + 1]) < here.dist(goals[self.next]) - 0.5)
        {
            self.next += 1;
        }
        self.endpoints.clear();
        laser_endpoints(estimate, scan, &mut self.endpoints);
        // Echoes of the map's own walls add nothing but thickness: keep
        // only what the map does not have — people, things moved.
        let (map, near) = (&self.map, &self.near_wall);
        self.endpoints.retain(|&q| {
            let c = map.cell_of(q);
            map.contains(c) && !near[c.j as usize * map.width() + c.i as usize]
        });
        let mut k = self.next;
        let outcome = loop {
            let goal = goals[k];
            match self.local.plan(&self.map, here, goal, &self.endpoints) {
                Err(PlanningError::GoalBlocked { why, .. })
                    if k < last && matches!(why, Blocked::Sensed | Blocked::Inflated { .. }) =>
                {
                    // A person on an intermediate goal: aim at the next one.
                    k += 1;
                }
                Err(PlanningError::GoalOutsideWindow { .. }) => {
                    // Far off the route (a poor estimate): plan it again
                    // from here next cycle.
                    break Err(Exception::PathBlocking);
                }
                Err(PlanningError::GoalBlocked { .. }) if k == last => break Err(Exception::GoalOccupation),
                Err(_) => break Err(Exception::PathBlocking),
                Ok(_) => break Ok(goal),
            }
        };
        match outcome {
            Ok(goal) => {
                let target = self.lookahead(here);
                let psi = wrap_angle((target - here).angle() - estimate.theta_rad);
                let omega = (self.p.k_heading * psi).clamp(-self.p.max_turn_radps, self.p.max_turn_radps);
                let slow_near_goal =
                    (here.dist(goals[last]) / SLOW_NEAR_GOAL_M).clamp(SLOW_NEAR_GOAL_MIN, 1.0);
                // Slow in narrow places: full speed with 0.4 m to spare
                // beyond the footprint, a third of it when scraping by.
                let spare = self
                    .local
                    .cost_map()
                    .and_then(|c| c.clearance_m(self.map.cell_of(here)))
                    .map_or(f64::INFINITY, |c| c - self.p.robot_radius_m);
                let slow_when_narrow = (spare / SPARE_FOR_FULL_SPEED_M).clamp(SLOW_WHEN_NARROW_MIN, 1.0);
                let wanted =
                    self.p.cruise_mps * psi.cos().max(0.0).powi(2) * slow_near_goal * slow_when_narrow;
                // Safety: stop in time for what the laser sees, or saw
                // beside the robot (out of a 180° laser's view now).
                let points = self.nearby.update(scan, odometry, time_s);
                let radius = self.p.robot_radius_m + self.p.safety_margin_m;
                let v = wanted.min(scan::safe_speed(
                    points,
                    wanted,
                    omega,
                    radius,
                    BRAKING_FRACTION * self.p.max_accel_mps2,
                    dt_s,
                ));
                self.since_s = None;
                let command = self.limit(v, omega, dt_s);
                AutoMoveStep {
                    command,
                    exception: None,
                    abnormal: false,
                    request: None,
                    goal,
                }
            }
            Err(e) => {
                if e == Exception::PathBlocking && self.route.is_some() {
                    // A poor estimate may have taken the robot off the
                    // route: plan it again from here (kept when it fails).
                    let final_goal = goals[last];
                    if here.dist(goals[self.next]) > self.p.local.window_size_m / 2.0
                        && let Ok(r) = self.global.plan(here, final_goal)
                    {
                        self.route = Some(r);
                        self.next = 0;
                    }
                }
                self.stopped(here, Some(e), dt_s, time_s)
            }
        }
    }

    /// The point `lookahead_m` down the last gradient path.
    fn lookahead(&self, here: Vec2) -> Vec2 {
        let path = self.local.path();
        let mut left = self.p.lookahead_m;
        let mut at = here;
        for &q in path.iter().skip(1) {
            let d = at.dist(q);
            if d >= left {
                return at + (q - at).scale(left / d);
            }
            left -= d;
            at = q;
        }
        path.last().copied().unwrap_or(here)
    }

    /// Speeds limited in rate and size.
    fn limit(&mut self, v: f64, omega: f64, dt_s: f64) -> Command {
        let (v0, w0) = self.last;
        let dv = self.p.max_accel_mps2 * dt_s;
        let dw = self.p.max_turn_accel_radps2 * dt_s;
        let v = v.clamp(v0 - dv, v0 + dv).clamp(0.0, self.p.cruise_mps);
        let omega = omega
            .clamp(w0 - dw, w0 + dw)
            .clamp(-self.p.max_turn_radps, self.p.max_turn_radps);
        self.last = (v, omega);
        Command::Twist {
            v_mps: v,
            omega_radps: omega,
        }
    }

    /// Stops (within the acceleration limits) on an exception and asks the
    /// people around to step aside.
    fn stopped(&mut self, here: Vec2, exception: Option<Exception>, dt_s: f64, time_s: f64) -> AutoMoveStep {
        let since = *self.since_s.get_or_insert(time_s);
        let command = self.limit(0.0, 0.0, dt_s);
        let goal = self
            .route
            .as_ref()
            .and_then(|r| r.goals.get(self.next).copied())
            .unwrap_or(here);
        AutoMoveStep {
            command,
            exception,
            abnormal: time_s - since >= self.p.abnormal_after_s,
            request: Some(Request::StepAside {
                radius_m: self.p.ask_radius_m,
            }),
            goal,
        }
    }
}
