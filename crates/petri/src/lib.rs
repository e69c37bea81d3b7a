//! Generalized Stochastic Petri Nets.
#![warn(missing_docs)]

pub mod error;
pub mod expr;
pub mod gspn;
pub mod net;
pub mod simulation;

pub use error::{Error, Result};
pub use expr::{CompiledExpr, Expr};
pub use gspn::{Gspn, MarkingKind, Timing};
pub use net::{
    Arc, ArcKind, Net, Param, ParamKind, Params, Place, PlaceId, Servers, Transition, TransitionId,
    TransitionKind,
};
pub use simulation::{Estimate, SimParams, SimResult, simulate};
