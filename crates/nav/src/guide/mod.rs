//! The tour-guide robot's navigation (tour-guide.md): contour tracking,
//! AutoMove, and the controller that runs them with the localizer.

pub mod contour;
pub mod scan;

pub use contour::{ContourMode, ContourParams, ContourStep, ContourTracker, Side};
