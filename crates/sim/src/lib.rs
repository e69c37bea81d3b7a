//! The world every navigation experiment runs in: occupancy grids (real
//! ROS `map_server` maps too), a differential-drive robot, range sensors,
//! odometry that drifts, and people who walk about.
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
