//! Generalized Stochastic Petri Nets.
#![warn(missing_docs)]

pub mod ctmc;
pub mod error;
pub mod expr;
pub mod families;
pub mod gspn;
pub mod incidence;
pub mod invariants;
pub mod io;
pub mod krylov;
mod linear;
mod marking;
pub mod net;
pub mod properties;
pub mod reachability;
mod rows;
mod scc;
pub mod simulation;
pub mod steady_state;
mod vanishing;

pub use ctmc::{CompileStats, CompiledGspn, Solution};
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
pub use properties::Properties;
pub use reachability::{Edge, ExploreParams, ExploreStats, MarkingId, ReachabilityGraph};
pub use simulation::{Estimate, SimParams, SimResult, simulate};
pub use steady_state::{Method, SolveInfo, SolveParams};
