//! The control loop: one robot, its sensors and a crowd in a world, run
//! tick by tick against a [`Controller`].
//!
//! Each control tick (period `control_period_s`, time `t = ticks · period`):
//!
//! 1. the sensors read the scene at the true pose (each at its own period)
//!    into the reused [`Perception`] — no allocation;
//! 2. the controller answers ([`Step`]); `GiveUp` ends the run;
//! 3. for each of `physics_substeps` sub-steps: the wheel speeds move
//!    towards the command within the drive's limits, the robot moves along
//!    the exact arc, the encoders measure the wheels, the new footprint is
//!    checked against the grid ([`OccupancyGrid::disc_blocked`]) and the
//!    people's discs (the same discs the sensors see), then the people move
//!    (never into the robot);
//! 4. goal (true position within `goal_tolerance_m`); a controller that
//!    answered `Done` away from the goal ends the run as `Lost`; time limit.
//!
//! With disturbances ([`Simulation::with_disturbances`],
//! [`crate::disturbance`]) a sub-step also applies the slip of a floor
//! patch the centre is in (the pose moves with slipped wheels, the
//! encoders measure the commanded ones), moves a robot being pushed instead
//! of driving it (wheels held at 0), and at its end updates the braked
//! clock and the push hazard and sends a curious group to the robot when
//! one is due. Without them none of this runs.
//!
//! **Collision rule.** A footprint that overlaps a blocked cell or a person
//! after a sub-step is a collision. If `collision_fatal` (the default) the
//! run ends there (outcome [`Outcome::Collision`], the robot left where it
//! touched). Otherwise the sub-step is undone, the wheels stall (speed 0;
//! the encoders still counted the turn, so odometry drifts), the bumper is
//! pressed at the next tick and the run goes on; `collisions` counts the
//! contact episodes (ticks with contact after a tick without).
//!
//! The end is decided in this order: collision, then goal, then time limit.
//! A goal already within tolerance at the start ends the run at once.

use robot::{Command, Controller, Notes, Perception, Pose, Request, Step, Vec2};

use crate::disturbance::{DisturbanceCounts, DisturbanceEvent, DisturbanceParams, Disturbances};
use crate::error::{Error, Result};
use crate::grid::OccupancyGrid;
use crate::noise::{RandomStream, streams};
use crate::people::Crowd;
use crate::robot_params::RobotParams;
use crate::sensors::{Ir, Laser, Odometry, Scene, Sonar};
use crate::trace::{StepKind, Trace, TraceParams, TraceTick};
use crate::validate;
use crate::world::World;
use crate::{fast_math, kinematics};

/// How a run is clocked and judged.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RunParams {
    /// Control period, seconds. Default 0.1.
    pub control_period_s: f64,
    /// Physics sub-steps per control period (robot, odometry, people,
    /// collisions), at least 1. Default 1.
    pub physics_substeps: usize,
    /// The run ends after this long, seconds. Default 300.
    pub time_limit_s: f64,
    /// The goal is reached when the true position is this close, metres.
    /// Default 0.3.
    pub goal_tolerance_m: f64,
    /// A collision ends the run as a failure. Default `true`.
    pub collision_fatal: bool,
    /// What to record. Default: nothing.
    pub trace: TraceParams,
}

impl Default for RunParams {
    fn default() -> RunParams {
        RunParams {
            control_period_s: 0.1,
            physics_substeps: 1,
            time_limit_s: 300.0,
            goal_tolerance_m: 0.3,
            collision_fatal: true,
            trace: TraceParams::default(),
        }
    }
}

impl RunParams {
    /// Checks every field.
    pub fn validate(&self) -> Result<()> {
        validate::positive("run.control_period_s", self.control_period_s)?;
        validate::count_at_least("run.physics_substeps", self.physics_substeps, 1, "at least 1")?;
        validate::non_negative("run.time_limit_s", self.time_limit_s)?;
        validate::non_negative("run.goal_tolerance_m", self.goal_tolerance_m)
    }
}

/// Where the robot starts and where it should go.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Task {
    /// True start pose (the odometry starts there too).
    pub start: Pose,
    /// The goal, if any (without one a run ends only by collision, time
    /// limit or giving up).
    pub goal: Option<Vec2>,
}

/// How a run ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Outcome {
    /// The true position came within the goal tolerance.
    Goal,
    /// A fatal collision.
    Collision,
    /// The time limit passed.
    TimeLimit,
    /// The controller gave up.
    GaveUp,
    /// The controller declared the task done ([`Step::Done`]) while the
    /// true position is not within the goal tolerance: its own position
    /// estimate (odometry) is wrong, and it has stopped where it believes
    /// the goal is.
    Lost,
}

impl Outcome {
    /// Whether the run reached its goal.
    pub fn is_success(self) -> bool {
        self == Outcome::Goal
    }
}

/// The summary of a run.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct RunResult {
    /// The run's seed.
    pub seed: u64,
    /// How it ended (`None` while still running).
    pub outcome: Option<Outcome>,
    /// Simulated time, seconds.
    pub time_s: f64,
    /// Control ticks executed.
    pub ticks: u64,
    /// Length of the true path of the robot's centre, metres (a push's
    /// included: [`crate::disturbance`]).
    pub path_length_m: f64,
    /// Contact episodes (module docs).
    pub collisions: u32,
    /// Smallest gap between the footprint and the nearest wall or person
    /// over the run (at the start and after every tick), metres; 0 after a
    /// collision. Walls via the distance field (exact to a small fraction
    /// of a cell).
    pub min_clearance_m: f64,
    /// Final true pose.
    pub final_pose: Pose,
    /// Final dead-reckoned pose.
    pub final_estimate: Pose,
    /// Distance between the final true and estimated positions, metres.
    pub odometry_error_m: f64,
    /// Final distance from the true position to the goal, metres.
    pub goal_distance_m: Option<f64>,
    /// Totals of the disturbances ([`Simulation::with_disturbances`]); all
    /// zero, and left out of the serialised summary, without them.
    #[serde(skip_serializing_if = "DisturbanceCounts::is_zero")]
    pub disturbances: DisturbanceCounts,
}

/// One run in progress (module docs).
///
/// ```
/// use sim::{OccupancyGrid, RobotParams, RunParams, ScriptedController, Simulation, Task, World};
/// use robot::{Command, Pose, Vec2};
///
/// let world = World::new(OccupancyGrid::new(100, 100, 0.05, Pose::default()));
/// let task = Task { start: Pose::new(1.0, 2.5, 0.0), goal: Some(Vec2::new(3.0, 2.5)) };
/// let mut sim = Simulation::new(&world, RobotParams::aibot(), RunParams::default(), task, 7)?;
/// let mut drive = ScriptedController::new(vec![(Command::Twist { v_mps: 0.3, omega_radps: 0.0 }, 20.0)])?;
/// let result = sim.run(&mut drive);
/// assert_eq!(result.outcome, Some(sim::Outcome::Goal));
/// # Ok::<(), sim::Error>(())
/// ```
#[derive(Debug, Clone)]
pub struct Simulation {
    world: World,
    robot: RobotParams,
    run: RunParams,
    task: Task,
    seed: u64,
    pose: Pose,
    wheels_mps: (f64, f64),
    crowd: Crowd,
    lasers: Vec<Laser>,
    sonar: Sonar,
    ir: Ir,
    odometry: Odometry,
    perception: Perception,
    notes: Notes,
    trace: Option<Trace>,
    ticks: u64,
    path_length_m: f64,
    collisions: u32,
    min_clearance_m: f64,
    contact: bool,
    outcome: Option<Outcome>,
    disturbance: Option<Disturbances>,
}

impl Simulation {
    /// Sets up a run of `robot` in `world` for `task`, everything random
    /// drawn from `seed` (people's placement and motion, sensor noise,
    /// odometry; see [`crate::noise`]).
    ///
    /// Errors: [`Error::InvalidValue`] for a bad parameter or a crowd that
    /// does not fit; [`Error::Geometry`] when the start pose is off the map
    /// or its footprint touches an obstacle, or the goal is off the map or
    /// in a blocked cell.
    pub fn new(
        world: &World,
        robot: RobotParams,
        run: RunParams,
        task: Task,
        seed: u64,
    ) -> Result<Simulation> {
        robot.validate()?;
        run.validate()?;
        validate::pose("task.start", &task.start)?;
        if let Some(g) = task.goal {
            validate::point("task.goal", g)?;
        }
        let grid = world.grid();
        let r = robot.drive.radius_m;
        let start = Pose::new(task.start.x_m, task.start.y_m, task.start.theta_rad);
        let at = start.position();
        if !world.on_map(at) {
            return Err(Error::Geometry(format!(
                "start position ({:.3}, {:.3}) is outside the map",
                at.x, at.y
            )));
        }
        if grid.disc_blocked(at, r) {
            return Err(Error::Geometry(format!(
                "start pose ({:.3}, {:.3}): the robot's footprint (radius {r} m) overlaps an obstacle",
                at.x, at.y
            )));
        }
        if let Some(g) = task.goal {
            if !world.on_map(g) {
                return Err(Error::Geometry(format!(
                    "goal ({:.3}, {:.3}) is outside the map",
                    g.x, g.y
                )));
            }
            if grid.blocked_at(g) {
                return Err(Error::Geometry(format!(
                    "goal ({:.3}, {:.3}) is inside an obstacle",
                    g.x, g.y
                )));
            }
        }
        let crowd = Crowd::new(world, seed, &[(at, r)])?;
        let lasers = robot
            .lasers
            .iter()
            .enumerate()
            .map(|(k, p)| Laser::new(p.clone(), RandomStream::new(seed, streams::LASER0 + k as u64)))
            .collect::<Result<Vec<_>>>()?;
        let sonar = Sonar::new(robot.sonar.clone(), RandomStream::new(seed, streams::SONAR))?;
        let ir = Ir::new(robot.ir.clone(), RandomStream::new(seed, streams::IR))?;
        let odometry = Odometry::new(robot.odometry, start, RandomStream::new(seed, streams::ODOMETRY))?;
        let perception = Perception {
            time_s: 0.0,
            odometry: start,
            wheel_speeds_mps: (0.0, 0.0),
            goal: task.goal,
            lasers: lasers.iter().map(Laser::empty_scan).collect(),
            sonar: sonar.empty_readings(),
            ir: ir.empty_readings(),
            bumper: false,
        };
        let trace = run.trace.enabled.then(|| Trace {
            seed,
            ticks: Vec::new(),
        });
        let notes = if run.trace.enabled {
            Notes::enabled()
        } else {
            Notes::disabled()
        };
        let mut sim = Simulation {
            world: world.clone(),
            run,
            task: Task {
                start,
                goal: task.goal,
            },
            seed,
            pose: start,
            wheels_mps: (0.0, 0.0),
            crowd,
            lasers,
            sonar,
            ir,
            odometry,
            perception,
            notes,
            trace,
            ticks: 0,
            path_length_m: 0.0,
            collisions: 0,
            min_clearance_m: f64::INFINITY,
            contact: false,
            outcome: None,
            disturbance: None,
            robot,
        };
        sim.min_clearance_m = sim.clearance_m();
        if sim.goal_reached() {
            sim.outcome = Some(Outcome::Goal);
        }
        Ok(sim)
    }

    /// The same run with physical disturbances ([`crate::disturbance`]):
    /// pushes while braked, wheel slip on floor patches, groups closing
    /// round the robot. Their processes start at the current time (call it
    /// before the first tick); they replace any given before, and the
    /// default ([`DisturbanceParams::default`], all off) leaves the run
    /// exactly as without them.
    ///
    /// Errors: [`Error::InvalidValue`] naming a bad parameter.
    pub fn with_disturbances(mut self, params: DisturbanceParams) -> Result<Simulation> {
        self.disturbance = Disturbances::new(params, self.seed, self.time_s())?;
        Ok(self)
    }

    /// The disturbances' parameters, if any is on.
    pub fn disturbance_params(&self) -> Option<&DisturbanceParams> {
        self.disturbance.as_ref().map(Disturbances::params)
    }

    /// Every disturbance so far, in the order they began (empty without
    /// them).
    pub fn disturbances(&self) -> &[DisturbanceEvent] {
        self.disturbance.as_ref().map_or(&[], Disturbances::events)
    }

    /// Whether the robot is being pushed now (held: wheels at 0).
    pub fn pushed(&self) -> bool {
        self.disturbance.as_ref().is_some_and(Disturbances::held)
    }

    /// The world.
    pub fn world(&self) -> &World {
        &self.world
    }

    /// The robot's parameters.
    pub fn robot(&self) -> &RobotParams {
        &self.robot
    }

    /// The run's parameters.
    pub fn run_params(&self) -> &RunParams {
        &self.run
    }

    /// The task.
    pub fn task(&self) -> &Task {
        &self.task
    }

    /// The true pose now.
    pub fn pose(&self) -> Pose {
        self.pose
    }

    /// The dead-reckoned pose now.
    pub fn estimate(&self) -> Pose {
        self.odometry.estimate()
    }

    /// The wheel rim speeds being driven, m/s (left, right).
    pub fn wheels_mps(&self) -> (f64, f64) {
        self.wheels_mps
    }

    /// Simulated time now, seconds.
    pub fn time_s(&self) -> f64 {
        self.ticks as f64 * self.run.control_period_s
    }

    /// The people now.
    pub fn crowd(&self) -> &Crowd {
        &self.crowd
    }

    /// The perception of the last tick (what the controller saw).
    pub fn perception(&self) -> &Perception {
        &self.perception
    }

    /// How the run ended, if it has.
    pub fn outcome(&self) -> Option<Outcome> {
        self.outcome
    }

    /// The trace so far, if recording.
    pub fn trace(&self) -> Option<&Trace> {
        self.trace.as_ref()
    }

    /// Takes the trace out (recording stops).
    pub fn take_trace(&mut self) -> Option<Trace> {
        self.trace.take()
    }

    /// The summary so far.
    pub fn result(&self) -> RunResult {
        let est = self.odometry.estimate();
        RunResult {
            seed: self.seed,
            outcome: self.outcome,
            time_s: self.time_s(),
            ticks: self.ticks,
            path_length_m: self.path_length_m,
            collisions: self.collisions,
            min_clearance_m: self.min_clearance_m,
            final_pose: self.pose,
            final_estimate: est,
            odometry_error_m: self.pose.position().dist(est.position()),
            goal_distance_m: self.task.goal.map(|g| g.dist(self.pose.position())),
            disturbances: self
                .disturbance
                .as_ref()
                .map_or_else(DisturbanceCounts::default, Disturbances::counts),
        }
    }

    /// Runs ticks until the run ends; returns the summary.
    pub fn run<C: Controller + ?Sized>(&mut self, controller: &mut C) -> RunResult {
        while self.tick(controller).is_none() {}
        self.result()
    }

    fn goal_reached(&self) -> bool {
        self.task
            .goal
            .is_some_and(|g| fast_math::dist(g, self.pose.position()) <= self.run.goal_tolerance_m)
    }

    /// Gap between the footprint and the nearest wall or person, metres.
    fn clearance_m(&self) -> f64 {
        let at = self.pose.position();
        let r = self.robot.drive.radius_m;
        let walls = self.world.distance_field().distance_m(at) - r;
        walls.min(self.crowd.gap_m(at, r)).max(0.0)
    }

    fn footprint_hits(&self, grid: &OccupancyGrid, at: Vec2, radius_m: f64) -> bool {
        grid.disc_blocked(at, radius_m) || self.crowd.overlaps(at, radius_m)
    }

    /// Reads every sensor into the perception.
    fn sense(&mut self, time_s: f64) {
        let scene = Scene {
            grid: self.world.grid(),
            field: Some(self.world.distance_field()),
            people: self.crowd.people(),
            person_radius_m: self.crowd.radius_m(),
        };
        let p = &mut self.perception;
        p.time_s = time_s;
        p.odometry = self.odometry.estimate();
        p.wheel_speeds_mps = self.odometry.wheel_speeds_mps();
        p.goal = self.task.goal;
        for (laser, scan) in self.lasers.iter_mut().zip(p.lasers.iter_mut()) {
            laser.read(&scene, &self.pose, time_s, scan);
        }
        self.sonar.read(&scene, &self.pose, time_s, &mut p.sonar);
        self.ir.read(&scene, &self.pose, time_s, &mut p.ir);
        let b = &self.robot.bumper;
        p.bumper = b.enabled && {
            let r = self.robot.drive.radius_m;
            let at = self.pose.position();
            self.contact
                || (b.margin_m > 0.0
                    && (scene.grid.disc_blocked(at, r + b.margin_m)
                        || self.crowd.overlaps(at, r + b.margin_m)))
        };
    }

    /// One control tick (module docs). Returns the outcome once the run
    /// has ended (and then does nothing more).
    pub fn tick<C: Controller + ?Sized>(&mut self, controller: &mut C) -> Option<Outcome> {
        if self.outcome.is_some() {
            return self.outcome;
        }
        let period = self.run.control_period_s;
        let time_s = self.time_s();
        self.sense(time_s);
        let pose_at_sensing = self.pose;
        let people_at_sensing = match &self.trace {
            Some(_) if self.run.trace.people => self.crowd.people().iter().map(|q| q.position).collect(),
            _ => Vec::new(),
        };
        self.notes.clear();
        let step = controller.step(&self.perception, &mut self.notes);
        let request = controller.request();
        if let Some(Request::StepAside { radius_m }) = request {
            self.crowd
                .ask_to_step_aside(&self.world, self.pose.position(), radius_m, time_s);
        }
        let declared_done = matches!(step, Step::Done(_));
        let command = match step {
            Step::Run(c) | Step::Done(c) => Some(c),
            Step::GiveUp => None,
        };
        let mut contact = false;
        match command {
            None => self.outcome = Some(Outcome::GaveUp),
            Some(c) => contact = self.integrate(c, time_s),
        }
        self.odometry.end_period(period);
        self.ticks += 1;
        if contact && !self.contact {
            self.collisions += 1;
        }
        self.contact = contact;
        let clearance = if self.outcome == Some(Outcome::Collision) {
            0.0
        } else {
            self.clearance_m()
        };
        self.min_clearance_m = self.min_clearance_m.min(clearance);
        if self.outcome.is_none() {
            if self.goal_reached() {
                self.outcome = Some(Outcome::Goal);
            } else if declared_done && self.task.goal.is_some() {
                self.outcome = Some(Outcome::Lost);
            } else if self.time_s() >= self.run.time_limit_s - 1e-9 {
                self.outcome = Some(Outcome::TimeLimit);
            }
        }
        if let Some(trace) = &mut self.trace {
            trace.ticks.push(TraceTick {
                tick: self.ticks - 1,
                time_s,
                true_pose: pose_at_sensing,
                estimated_pose: self.perception.odometry,
                step: match step {
                    Step::Run(_) => StepKind::Run,
                    Step::Done(_) => StepKind::Done,
                    Step::GiveUp => StepKind::GiveUp,
                },
                command,
                wheels_mps: self.wheels_mps,
                contact,
                behaviour: self.notes.behaviour,
                values: self.notes.values.clone(),
                events: self.notes.events.clone(),
                clouds: self.notes.clouds.clone(),
                request,
                perception: self.run.trace.perception.then(|| self.perception.clone()),
                people: people_at_sensing,
            });
        }
        self.outcome
    }

    /// Drives one control period with command `c` from `time_s`; returns
    /// whether the footprint touched something.
    fn integrate(&mut self, c: Command, time_s: f64) -> bool {
        let drive = self.robot.drive;
        let n = self.run.physics_substeps;
        let dt = self.run.control_period_s / n as f64;
        let target = c.wheels(drive.wheel_base_m);
        let mut contact = false;
        for k in 0..n {
            let end_s = time_s + (k + 1) as f64 * dt;
            // Disturbances (module docs of `disturbance`): slip ratios of
            // a patch the centre is in, a push holding the robot.
            let (slip, held) = match &mut self.disturbance {
                Some(d) => (d.slip_at(self.pose.position(), time_s + k as f64 * dt), d.held()),
                None => (None, false),
            };
            if held {
                self.wheels_mps = (0.0, 0.0);
                self.odometry.step(self.wheels_mps, drive.wheel_base_m, dt);
                let (grid, crowd, radius) = (self.world.grid(), &self.crowd, drive.radius_m);
                if let Some(d) = &mut self.disturbance {
                    let before = self.pose.position();
                    self.pose = d.push_step(self.pose, dt, end_s, |at| {
                        grid.disc_blocked(at, radius) || crowd.overlaps(at, radius)
                    });
                    self.path_length_m += fast_math::dist(before, self.pose.position());
                }
            } else {
                self.wheels_mps = drive.limit(self.wheels_mps, target, dt);
                let (l, r) = self.wheels_mps;
                // The wheels' true rim travel: slipped in a patch.
                let (tl, tr) = match slip {
                    Some((sl, sr)) => ((1.0 - sl) * l, (1.0 - sr) * r),
                    None => (l, r),
                };
                let next = kinematics::integrate(self.pose, tl, tr, drive.wheel_base_m, dt);
                self.odometry.step(self.wheels_mps, drive.wheel_base_m, dt);
                let moved = if self.footprint_hits(self.world.grid(), next.position(), drive.radius_m) {
                    contact = true;
                    self.run.collision_fatal
                } else {
                    true
                };
                if moved {
                    self.path_length_m += kinematics::arc_length_m(tl, tr, dt);
                    self.pose = next;
                }
                if slip.is_some()
                    && let Some(d) = &mut self.disturbance
                {
                    let true_m = if moved {
                        kinematics::arc_length_m(tl, tr, dt)
                    } else {
                        0.0
                    };
                    d.slipped(true_m, kinematics::arc_length_m(l, r, dt));
                }
                if contact && self.run.collision_fatal {
                    self.outcome = Some(Outcome::Collision);
                    return true;
                }
                if !moved {
                    self.wheels_mps = (0.0, 0.0);
                }
            }
            let robot = Some((self.pose.position(), drive.radius_m));
            self.crowd.step(&self.world, robot, end_s, dt);
            if let Some(d) = &mut self.disturbance {
                d.after_substep(
                    &self.world,
                    &mut self.crowd,
                    self.pose,
                    drive.radius_m,
                    self.wheels_mps,
                    target,
                    end_s,
                    dt,
                );
            }
        }
        contact
    }
}
