//! Test harness for the localizer: drives the simulated Jinny-like robot
//! along a route through a real map while a [`Localizer`] follows it from
//! the perceptions alone, and measures the estimate's error against the
//! simulator's true pose.
//!
//! The robot is steered with the TRUE pose (a pure-pursuit follower on a
//! path planned over the map's clearance) and waits for people in its way
//! using their TRUE positions: this tests the localizer, not a planner or
//! an obstacle avoider. Shared by `tests/localization.rs` and
//! `examples/mcl_drive.rs` (hence the `dead_code` allowance: each uses a
//! part).

#![allow(dead_code)]

use std::cmp::Reverse;
use std::collections::BinaryHeap;
use std::path::PathBuf;

use localization::{LocalizationStatus, Localizer, MclParams, UpdateInfo};
use robot::{Command, Controller, GridMap, Notes, Perception, Pose, Step, Vec2};
use sim::{CellIndex, CrowdParams, CrowdSize, RobotParams, RunParams, Simulation, Task, World};

/// A real map of `maps/`.
pub fn map_path(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../maps")
        .join(name)
        .join(format!("{name}.yaml"))
}

/// The world (for the simulator) and the static map (for the localizer).
pub fn load(name: &str) -> (World, GridMap) {
    let m = sim::map_server::load(map_path(name)).expect("the map loads");
    let map = m.grid.grid_map();
    (World::new(m.grid), map)
}

/// Waypoints of a route through the corridors of each map (world frame,
/// metres); the path between consecutive waypoints is planned over the
/// clearance. The first waypoint is the start.
pub fn waypoints(name: &str) -> Vec<Vec2> {
    let v = |x, y| Vec2::new(x, y);
    match name {
        // The left corridor up, the top corridor east, the middle corridor
        // down, the bottom corridor east, up through the hall and back
        // along the top and down the left corridor.
        "building_31" => vec![
            v(-17.2, -3.0),
            v(-17.2, 17.7),
            v(-11.0, 17.7),
            v(-11.0, 3.5),
            v(-1.0, 3.0),
            v(0.0, 15.0),
            v(0.0, -4.0),
            v(-1.0, 3.0),
            v(-11.0, 3.5),
            v(-11.0, 17.7),
            v(-17.2, 17.7),
            v(-17.2, 2.0),
        ],
        // Twice round the corridor loop.
        "levine" => vec![
            v(-13.7, 2.0),
            v(-13.7, 8.7),
            v(9.7, 8.7),
            v(9.7, -0.1),
            v(-13.7, -0.1),
            v(-13.7, 8.7),
            v(9.7, 8.7),
            v(9.7, -0.1),
            v(-13.7, -0.1),
            v(-13.7, 4.0),
        ],
        other => panic!("no route for map {other}"),
    }
}

/// A shortest path (8-connected cells, cost growing near walls) through
/// cells with at least `clearance_m` to the nearest obstacle, through
/// every waypoint in turn; points every ~0.2 m. `None` if a leg has no path.
pub fn plan(world: &World, waypoints: &[Vec2], clearance_m: f64) -> Option<Vec<Vec2>> {
    let g = world.grid();
    let (w, h) = (g.width(), g.height());
    let field = world.distance_field();
    let clear: Vec<f64> = (0..w * h)
        .map(|k| {
            let c = CellIndex {
                i: (k % w) as i64,
                j: (k / w) as i64,
            };
            if g.blocked(c) {
                0.0
            } else {
                field.distance_m(g.cell_center(c))
            }
        })
        .collect();
    let mut path: Vec<Vec2> = Vec::new();
    for leg in waypoints.windows(2) {
        let (a, b) = (g.cell_of(leg[0]), g.cell_of(leg[1]));
        if !g.contains(a) || !g.contains(b) {
            return None;
        }
        let idx = |c: CellIndex| c.j as usize * w + c.i as usize;
        let (sa, sb) = (idx(a), idx(b));
        if clear[sa] < clearance_m || clear[sb] < clearance_m {
            return None;
        }
        let mut dist = vec![f64::INFINITY; w * h];
        let mut prev = vec![usize::MAX; w * h];
        let mut heap = BinaryHeap::new();
        dist[sa] = 0.0;
        heap.push(Reverse((0u64, sa)));
        let scale = 1e6;
        while let Some(Reverse((d, k))) = heap.pop() {
            let d = d as f64 / scale;
            if d > dist[k] {
                continue;
            }
            if k == sb {
                break;
            }
            let (i, j) = ((k % w) as i64, (k / w) as i64);
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
                if ni < 0 || nj < 0 || ni >= w as i64 || nj >= h as i64 {
                    continue;
                }
                let n = nj as usize * w + ni as usize;
                if clear[n] < clearance_m {
                    continue;
                }
                let len = if di != 0 && dj != 0 {
                    std::f64::consts::SQRT_2
                } else {
                    1.0
                };
                let penalty = 1.0 + 4.0 * (1.2 - clear[n]).max(0.0);
                let nd = d + len * penalty;
                if nd < dist[n] {
                    dist[n] = nd;
                    prev[n] = k;
                    heap.push(Reverse(((nd * scale) as u64, n)));
                }
            }
        }
        if dist[sb].is_infinite() {
            return None;
        }
        let mut cells = vec![sb];
        while *cells.last().unwrap() != sa {
            cells.push(prev[*cells.last().unwrap()]);
        }
        cells.reverse();
        for (n, &k) in cells.iter().enumerate() {
            if n % 4 == 0 || n + 1 == cells.len() {
                let p = g.cell_center(CellIndex {
                    i: (k % w) as i64,
                    j: (k / w) as i64,
                });
                if path.last() != Some(&p) {
                    path.push(p);
                }
            }
        }
    }
    Some(path)
}

/// Pure pursuit along a path with the TRUE pose (set before every tick);
/// stops short of people in the way (their true positions, set before
/// every tick) and turns on the spot until they have gone.
pub struct Follower {
    path: Vec<Vec2>,
    cursor: usize,
    /// The true pose, set by the harness before each tick.
    pub truth: Pose,
    /// The people's true positions, set by the harness before each tick.
    pub people: Vec<Vec2>,
    lookahead_m: f64,
    speed_mps: f64,
    done: bool,
}

impl Follower {
    /// A follower of `path` at `speed_mps`.
    pub fn new(path: Vec<Vec2>, speed_mps: f64) -> Follower {
        Follower {
            path,
            cursor: 0,
            truth: Pose::default(),
            people: Vec::new(),
            lookahead_m: 0.8,
            speed_mps,
            done: false,
        }
    }

    /// Whether the end of the path was reached.
    pub fn done(&self) -> bool {
        self.done
    }
}

impl Controller for Follower {
    fn step(&mut self, _p: &Perception, _notes: &mut Notes) -> Step {
        let at = self.truth.position();
        // Advance to the nearest path point a little way ahead.
        let end = (self.cursor + 30).min(self.path.len());
        let mut best = self.cursor;
        for k in self.cursor..end {
            if self.path[k].dist(at) < self.path[best].dist(at) {
                best = k;
            }
        }
        self.cursor = best;
        let last = *self.path.last().unwrap();
        if self.cursor + 1 >= self.path.len() && last.dist(at) < 0.25 {
            self.done = true;
            return Step::Run(Command::Stop);
        }
        let target = self.path[self.cursor..]
            .iter()
            .copied()
            .find(|q| q.dist(at) >= self.lookahead_m)
            .unwrap_or(last);
        let local = self.truth.inverse_transform(target);
        if local.x < 0.1 * local.norm() {
            // Behind or beside: turn on the spot.
            return Step::Run(Command::Twist {
                v_mps: 0.0,
                omega_radps: 0.6 * local.y.signum(),
            });
        }
        let kappa = 2.0 * local.y / local.dot(local).max(1e-9);
        let mut v = self.speed_mps / (1.0 + 0.8 * kappa.abs());
        // Someone in the corridor the robot sweeps ahead (true positions):
        // slow down to stop 0.15 m short (the drive needs ~0.25 m to stop
        // from 0.5 m/s).
        let reach = ROBOT_RADIUS_M + PERSON_RADIUS_M;
        let ahead = self
            .people
            .iter()
            .map(|q| self.truth.inverse_transform(*q))
            .filter(|l| l.x > 0.0 && l.y.abs() < reach + 0.05)
            .map(|l| l.x - reach)
            .fold(f64::INFINITY, f64::min);
        v = v.min((0.8 * (ahead - 0.15)).max(0.0));
        // Blocked: turn towards the target on the spot (a circular robot
        // turning in place touches nothing).
        let omega = if v > 0.05 {
            v * kappa
        } else {
            (1.5 * local.angle()).clamp(-0.6, 0.6)
        };
        Step::Run(Command::Twist {
            v_mps: v,
            omega_radps: omega,
        })
    }
}

/// Radius of the Jinny-like robot, metres.
const ROBOT_RADIUS_M: f64 = 0.35;

/// Radius of a person (the crowd's default), metres.
const PERSON_RADIUS_M: f64 = 0.25;

/// What a drive measured.
#[derive(Debug, Clone, Default)]
pub struct DriveStats {
    /// The tick of the kidnap, if one happened ([`DriveSetup::kidnap`]).
    pub kidnapped_at_tick: Option<usize>,
    /// The localizer's state at every tick.
    pub statuses: Vec<LocalizationStatus>,
    /// Length of the true path, metres.
    pub distance_m: f64,
    /// Control ticks.
    pub ticks: usize,
    /// Position error of the estimate at every tick, metres.
    pub errors_m: Vec<f64>,
    /// Heading error at every tick, radians.
    pub heading_errors_rad: Vec<f64>,
    /// Error of the estimate in the true robot frame (forward, left) at
    /// every tick, metres.
    pub errors_robot_frame: Vec<(f64, f64)>,
    /// Filter iterations.
    pub iterations: usize,
    /// Filter iterations that ended in Warning.
    pub warning_iterations: usize,
    /// Ticks spent in Warning.
    pub warning_ticks: usize,
    /// Success → Warning transitions.
    pub warnings_raised: usize,
    /// Distance travelled (true path) when the error last went from above
    /// `converged_m` to below it (global localization), metres.
    pub converged_at_m: Option<f64>,
    /// Whether the run ended by reaching the end of the route.
    pub finished: bool,
    /// Contacts with people or walls.
    pub collisions: u32,
    /// Every filter iteration's info.
    pub infos: Vec<UpdateInfo>,
}

/// The median of `v`.
pub fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    if s.is_empty() { f64::NAN } else { s[s.len() / 2] }
}

/// The largest value of `v`.
pub fn max(v: &[f64]) -> f64 {
    v.iter().copied().fold(0.0, f64::max)
}

impl DriveStats {
    /// Median position error, metres.
    pub fn median_error_m(&self) -> f64 {
        median(&self.errors_m)
    }

    /// Largest position error, metres.
    pub fn max_error_m(&self) -> f64 {
        max(&self.errors_m)
    }

    /// Fraction of the filter iterations in Warning.
    pub fn warning_fraction(&self) -> f64 {
        self.warning_iterations as f64 / self.iterations.max(1) as f64
    }
}

/// How a drive is set up.
#[derive(Debug, Clone)]
pub struct DriveSetup {
    /// Map name.
    pub map: String,
    /// People in the world.
    pub people: usize,
    /// Simulation seed (people, sensor noise, odometry).
    pub sim_seed: u64,
    /// Localizer seed.
    pub mcl_seed: u64,
    /// Localizer parameters.
    pub params: MclParams,
    /// `None`: global localization; else the initial cloud's deviations
    /// `(xy m, θ rad)` around the true start.
    pub init: Option<(f64, f64)>,
    /// Stop after this many metres (the route may be longer).
    pub max_distance_m: f64,
    /// Errors below this count as converged (global localization), metres.
    pub converged_m: f64,
    /// Cruise speed, m/s.
    pub speed_mps: f64,
    /// The drive ends after this long, seconds.
    pub time_limit_s: f64,
    /// A kidnap the odometry does not see: after this many metres, the
    /// localizer is re-initialised at its estimate moved by `(dx, dy, dθ)`
    /// (metres, radians) — as if the robot had been pushed by the opposite.
    pub kidnap: Option<(f64, (f64, f64, f64))>,
    /// Feed the localizer with the clock ([`Localizer::update_at`]: status
    /// checks while standing, timed recovery iterations).
    pub timed: bool,
}

impl DriveSetup {
    /// Tracking from a known start on `map`, no people.
    pub fn tracking(map: &str) -> DriveSetup {
        DriveSetup {
            map: map.to_string(),
            people: 0,
            sim_seed: 1,
            mcl_seed: 2,
            params: MclParams::default(),
            init: Some((0.1, 0.05)),
            max_distance_m: f64::INFINITY,
            converged_m: 0.3,
            speed_mps: sim::kinematics::JINNY_CRUISE_SPEED_MPS,
            time_limit_s: 1500.0,
            kidnap: None,
            timed: false,
        }
    }
}

/// Drives the route of `setup.map` with the localizer following (module docs).
pub fn drive(setup: &DriveSetup) -> DriveStats {
    let (world, map) = load(&setup.map);
    let route = waypoints(&setup.map);
    let path = plan(&world, &route, 0.4).expect("the route is drivable");
    drive_path(setup, world, &map, path)
}

/// [`drive`] on a given world, map and path.
pub fn drive_path(setup: &DriveSetup, world: World, map: &GridMap, path: Vec<Vec2>) -> DriveStats {
    let world = if setup.people > 0 {
        world
            .with_crowd(CrowdParams {
                size: CrowdSize::Count { people: setup.people },
                ..CrowdParams::default()
            })
            .expect("crowd")
    } else {
        world
    };
    let heading = (path[1] - path[0]).angle();
    let start = Pose::new(path[0].x, path[0].y, heading);
    let run = RunParams {
        time_limit_s: setup.time_limit_s,
        collision_fatal: false,
        ..RunParams::default()
    };
    let mut sim = Simulation::new(
        &world,
        RobotParams::jinny(),
        run,
        Task { start, goal: None },
        setup.sim_seed,
    )
    .expect("simulation");
    let mut mcl = Localizer::new(map, setup.params, setup.mcl_seed).expect("localizer");
    match setup.init {
        Some((xy, th)) => mcl.init_pose(start, xy, th).expect("init"),
        None => mcl.init_global(),
    }
    let mut follower = Follower::new(path, setup.speed_mps);
    let mut stats = DriveStats::default();
    let mut was_converged = false;
    let mut last_status = LocalizationStatus::Success;
    loop {
        let truth = sim.pose();
        follower.truth = truth;
        follower.people.clear();
        follower
            .people
            .extend(sim.crowd().people().iter().map(|q| q.position));
        if follower.done() || sim.result().path_length_m >= setup.max_distance_m {
            stats.finished = follower.done();
            break;
        }
        if sim.tick(&mut follower).is_some() {
            break;
        }
        if let Some((at_m, (dx, dy, dth))) = setup.kidnap
            && stats.kidnapped_at_tick.is_none()
            && sim.result().path_length_m >= at_m
        {
            let e = mcl.estimate();
            mcl.init_pose(Pose::new(e.x_m + dx, e.y_m + dy, e.theta_rad + dth), 0.05, 0.02)
                .expect("kidnap");
            stats.kidnapped_at_tick = Some(stats.errors_m.len());
        }
        let p = sim.perception();
        let info = if setup.timed {
            mcl.update_at(p.time_s, p.odometry, &p.lasers[0]).expect("update")
        } else {
            mcl.update(p.odometry, &p.lasers[0]).expect("update")
        };
        if let Some(info) = info {
            stats.iterations += 1;
            if info.status == LocalizationStatus::Warning {
                stats.warning_iterations += 1;
                if last_status == LocalizationStatus::Success {
                    stats.warnings_raised += 1;
                }
            }
            last_status = info.status;
            stats.infos.push(info);
        }
        if mcl.status() == LocalizationStatus::Warning {
            stats.warning_ticks += 1;
        }
        stats.statuses.push(mcl.status());
        let e = mcl.estimate();
        let err = e.position().dist(truth.position());
        stats.errors_m.push(err);
        let local = truth.inverse_transform(e.position());
        stats.errors_robot_frame.push((local.x, local.y));
        stats
            .heading_errors_rad
            .push(robot::wrap_angle(e.theta_rad - truth.theta_rad).abs());
        let converged = err < setup.converged_m;
        if converged && !was_converged {
            stats.converged_at_m = Some(sim.result().path_length_m);
        }
        was_converged = converged;
        stats.ticks += 1;
    }
    if !was_converged {
        stats.converged_at_m = None;
    }
    let r = sim.result();
    stats.distance_m = r.path_length_m;
    stats.collisions = r.collisions;
    stats
}
