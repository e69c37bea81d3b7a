//! The tour-guide robot's navigation (docs/tour-guide.md): contour tracking,
//! AutoMove, and the controller that runs them with the localizer; the GSPN
//! [`supervisor`] that chooses between the two behaviours, its mission log
//! and the learning of its rates.
//!
//! The supervisor decides, for a tour-guide robot, between the map-based
//! planner (AutoMove) and wall following (Contour tracking):
//!
//! ```
//! use guide::supervisor::{Rates, Supervisor};
//!
//! let supervisor = Supervisor::new()?;
//! let mut rates = Rates::initial();
//! rates.set(7, 1.0 / 122.33); // completion rate with AutoMove
//! rates.set(8, 1.0 / 186.98); // completion rate with Contour tracking
//! let d = supervisor.decide(&rates)?;
//! assert!((d.f_cont - 0.00535).abs() < 5e-6);
//! println!("{:?}: f_auto = {:.5}, f_cont = {:.5}", d.choice, d.f_auto, d.f_cont);
//! # Ok::<(), guide::supervisor::SupervisorError>(())
//! ```
//!
//! The supervisor is a module of this crate, not a crate of its own: the
//! controller drives it (decisions, the crediting net's segments, the log),
//! and it reads the localizer's status types; nothing else uses it but the
//! lab and the command line's `guide log / learn / check`.
#![warn(missing_docs)]

pub mod automove;
pub mod contour;
pub mod controller;
pub mod scan;
pub mod supervisor;

pub use automove::{AutoMove, AutoMoveError, AutoMoveParams, AutoMoveStep, Exception};
pub use contour::{ContourMode, ContourParams, ContourStep, ContourTracker, Side};
pub use controller::{
    CreditPlan, GuideController, GuideError, GuideMap, GuideParams, GuideStats, GuideSummary,
    PARTICLES_CLOUD, Policy, SupervisorPlan,
};
