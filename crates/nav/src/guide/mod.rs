//! The tour-guide robot's navigation (docs/tour-guide.md): contour tracking,
//! AutoMove, and the controller that runs them with the localizer.

pub mod automove;
pub mod contour;
pub mod controller;
pub mod scan;

pub use automove::{AutoMove, AutoMoveError, AutoMoveParams, AutoMoveStep, Exception};
pub use contour::{ContourMode, ContourParams, ContourStep, ContourTracker, Side};
pub use controller::{
    CreditPlan, GuideController, GuideError, GuideMap, GuideParams, GuideStats, GuideSummary,
    PARTICLES_CLOUD, Policy, SupervisorPlan,
};
