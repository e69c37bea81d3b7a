//! Generalized Stochastic Petri Nets.
#![warn(missing_docs)]

pub mod error;
pub mod expr;
pub mod gspn;
pub mod incidence;
pub mod invariants;
pub mod net;

pub use error::{Error, Result};
pub use expr::{CompiledExpr, Expr};
pub use gspn::{Gspn, MarkingKind, Timing};
pub use incidence::{DisplayIncidence, Incidence};
pub use invariants::{
    DisplayInvariant, DisplayInvariants, FarkasInfo, FarkasParams, InvariantKind, Invariants, NamedInvariant,
    NamedTerm, p_invariants, structural_bounds, t_invariants,
};
pub use net::{
    Arc, ArcKind, Net, Param, ParamKind, Params, Place, PlaceId, Servers, Transition, TransitionId,
    TransitionKind,
};
