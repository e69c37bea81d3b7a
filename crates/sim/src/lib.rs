//! The world every navigation experiment runs in: occupancy grids (real
//! ROS `map_server` maps too), a differential-drive robot, range sensors,
//! odometry that drifts, and people who walk about.
//!
//! ```
//! use robot::Vec2;
//! use sim::{cast, map_server, render::Picture, shapes::WorldSpec};
//!
//! // A real building map (ROS map_server YAML + image)…
//! let map = map_server::load(concat!(
//!     env!("CARGO_MANIFEST_DIR"),
//!     "/tests/data/maps/building_31/building_31.yaml"
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
//! | [`clearance`] | distance to the nearest obstacle per cell, kept in sync with the grid |
//! | [`render`] | SVG and PNG pictures with trajectories, robots, rays, people, markers |
#![warn(missing_docs)]

pub mod clearance;
pub mod error;
mod font;
pub mod grid;
pub mod map_server;
pub mod raycast;
pub mod render;
pub mod shapes;

pub use error::{Error, Result};
pub use grid::{Cell, CellCounts, CellIndex, OccupancyGrid};
pub use raycast::{cast, cast_many, cast_traversal};
