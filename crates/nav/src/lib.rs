//! Navigation: behaviours, controllers and the supervisor that chooses
//! between them.
//!
//! The GSPN [`supervisor`] decides, for a tour-guide robot, between the
//! map-based planner (AutoMove) and wall following (Contour tracking):
//!
//! ```
//! use nav::supervisor::{Supervisor, Rates};
//!
//! let supervisor = Supervisor::new()?;
//! let mut rates = Rates::initial();
//! rates.set(7, 1.0 / 122.33); // completion rate with AutoMove
//! rates.set(8, 1.0 / 186.98); // completion rate with Contour tracking
//! let d = supervisor.decide(&rates)?;
//! assert!((d.f_cont - 0.00535).abs() < 5e-6);
//! println!("{:?}: f_auto = {:.5}, f_cont = {:.5}", d.choice, d.f_auto, d.f_cont);
//! # Ok::<(), nav::supervisor::SupervisorError>(())
//! ```
#![warn(missing_docs)]

pub mod activity;
pub mod guide;
pub mod localization;
pub mod planning;
pub mod sectors;
pub mod supervisor;
pub mod topo;
pub mod voting;
