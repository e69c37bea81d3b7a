//! The world every navigation experiment runs in: occupancy grids (real
//! ROS `map_server` maps too), a differential-drive robot, range sensors,
//! odometry that drifts, and people who walk about.
//!
//! A run: a [`World`] (grid, distance field, crowd parameters), a robot
//! ([`RobotParams`]: drive and sensors), clocking and judging
//! ([`RunParams`]), a [`Task`] (start, goal) and a seed make a
//! [`Simulation`], which a [`robot::Controller`] drives tick by tick until
//! the goal, a collision, the time limit or the controller giving up. Same
//! seed, same run, bit for bit, on any thread.
//!
//! ```
//! use robot::{Command, Controller, Notes, Perception, Pose, Step, Vec2};
//! use sim::{generators, RobotParams, RunParams, Simulation, Task, World};
//!
//! /// Forward at cruise speed; turn left on the spot while a sonar sees
//! /// something within 0.5 m.
//! struct Bounce;
//! impl Controller for Bounce {
//!     fn step(&mut self, p: &Perception, notes: &mut Notes) -> Step {
//!         if p.sonar.iter().any(|s| s.range_m < 0.5) {
//!             notes.behaviour("turn");
//!             Step::Run(Command::Twist { v_mps: 0.0, omega_radps: 1.0 })
//!         } else {
//!             notes.behaviour("forward");
//!             Step::Run(Command::Twist { v_mps: 0.3, omega_radps: 0.0 })
//!         }
//!     }
//! }
//!
//! let world = World::new(generators::cluttered_field(10.0, 0.05, 0, 1)?);
//! let task = Task { start: Pose::new(1.0, 1.0, 0.0), goal: None };
//! let run = RunParams { time_limit_s: 60.0, ..RunParams::default() };
//! let mut sim = Simulation::new(&world, RobotParams::aibot(), run, task, 42)?;
//! let result = sim.run(&mut Bounce);
//! assert_eq!(result.outcome, Some(sim::Outcome::TimeLimit));
//! assert_eq!(result.ticks, 600);
//! # Ok::<(), sim::Error>(())
//! ```
//!
//! Maps, shapes, ray casting and pictures:
//!
//! ```
//! use robot::Vec2;
//! use sim::{cast, map_server, render::Picture, shapes::WorldSpec};
//!
//! // A real building map (ROS map_server YAML + image)…
//! let map = map_server::load(concat!(
//!     env!("CARGO_MANIFEST_DIR"),
//!     "/../../maps/building_31/building_31.yaml"
//! ))?;
//! assert_eq!((map.grid.width(), map.grid.height()), (693, 648));
//! // …or a world drawn with shapes, 5 cm cells.
//! let mut world = WorldSpec::new(6.0, 4.0, 0.05);
//! world.walls = true;
//! let grid = world.rasterise()?;
//! // Exact ray casting: from the middle towards +x, the wall's inner face
//! // is 2.95 m away.
//! let d = cast(&grid, Vec2::new(3.0, 2.0), 0.0, 10.0).unwrap();
//! assert!((d - 2.95).abs() < 1e-9);
//! // Pictures.
//! let svg = Picture::new(&grid).to_svg()?;
//! assert!(svg.starts_with("<svg"));
//! # Ok::<(), sim::Error>(())
//! ```
//!
//! | module | what it does |
//! |---|---|
//! | [`grid`] | occupancy grid: cells, map origin, world ↔ cell, disc collisions |
//! | [`map_server`] | ROS map_server YAML + PGM/PNG maps, read exactly as map_server does; saving |
//! | [`shapes`] | worlds from rectangles, circles, polygons and wall segments (`[world]` of a scenario) |
//! | [`raycast`] | exact ray casting by cell traversal, accelerated by the clearance field |
//! | [`clearance`] | empty square around each cell (ray-casting jumps), kept in sync with the grid |
//! | [`distance_field`] | nearest obstacle of every cell (feature transform): people's wall forces, clearance |
//! | [`render`] | SVG and PNG pictures with trajectories, robots, rays, people, markers |
//! | [`kinematics`] | exact arc integration, drive limits, AIBOT/Jinny presets |
//! | [`sensors`] | laser, sonar, IR, odometry, bumper |
//! | [`ray_disc`] | ray–disc and cone–disc ranges (people) |
//! | [`people`], [`spatial_hash`], [`routes`] | social-force crowd; neighbour buckets; walking-distance fields to exhibits |
//! | [`world`], [`robot_params`] | world and robot set-up |
//! | [`simulation`] | the control loop, outcomes, run summary |
//! | [`disturbance`] | pushes while braked, wheel slip on floor patches, groups closing round the robot: true localisation loss |
//! | [`trace`] | optional per-tick record, JSON lines |
//! | [`scripted`] | a controller playing a list of commands |
//! | [`noise`] | seeded random streams |
//! | [`generators`] | procedural office floor and cluttered field |
#![warn(missing_docs)]

pub mod clearance;
pub mod crowd_params;
pub mod distance_field;
pub mod disturbance;
pub mod error;
mod fast_math;
mod font;
pub mod generators;
pub mod geodesic;
pub mod grid;
pub mod kinematics;
pub mod map_server;
pub mod noise;
pub mod people;
pub mod places;
pub mod ray_disc;
pub mod raycast;
pub mod render;
pub mod robot_params;
pub mod routes;
pub mod scripted;
pub mod sensors;
pub mod shapes;
pub mod simulation;
pub mod spatial_hash;
pub mod trace;
mod validate;
pub mod world;

pub use crowd_params::{CrowdParams, CrowdSize};
pub use distance_field::{DistanceField, NearestObstacle};
pub use disturbance::{
    DisturbanceCounts, DisturbanceEvent, DisturbanceKind, DisturbanceParams, PushParams, SlipParams,
    SlipPatch, SurroundParams,
};
pub use error::{Error, Result};
pub use grid::{Cell, CellCounts, CellIndex, OccupancyGrid};
pub use kinematics::DriveParams;
pub use noise::RandomStream;
pub use people::{Activity, Asked, Crowd, Person};
pub use places::{Place, PlaceProblem, Places};
pub use raycast::{cast, cast_many, cast_traversal};
pub use robot_params::RobotParams;
pub use routes::Routes;
pub use scripted::ScriptedController;
pub use sensors::{BumperParams, IrParams, LaserParams, OdometryParams, Scene, SonarParams};
pub use simulation::{Outcome, RunParams, RunResult, Simulation, Task};
pub use trace::{StepKind, Trace, TraceParams, TraceTick};
pub use world::World;
