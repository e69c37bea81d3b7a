//! Generalized Stochastic Petri Nets: models, state spaces, CTMC solvers,
//! measures, structural properties, simulation and file formats.
//!
//! Load a net, solve its CTMC, read a throughput:
//!
//! ```
//! use petri::{CompiledGspn, ExploreParams, Params, SolveParams};
//!
//! // The supervisor net of the tour-guide robot, in petrinav's TOML format
//! // (`io::read_file` reads .toml, .pnpro and .pnml files the same way).
//! let text = include_str!("../../../models/supervisor.toml");
//! let net = petri::io::read_str(text, petri::io::Format::Toml, "supervisor.toml")?;
//! let gspn = net.instantiate(&Params::new())?;
//! let compiled = CompiledGspn::build(&gspn, &ExploreParams::default())?;
//! assert_eq!(compiled.num_tangible(), 13);
//!
//! // Compile once, solve for any rates: only the rates are re-bound.
//! let rates = Params::new().with("lambda7", 1.0 / 122.33);
//! let solution = compiled.solve(&rates, None, &SolveParams::default())?;
//! let t9 = gspn.transition("t9")?;
//! println!("AutoMove completions per second: {:.5}", solution.throughput(t9));
//! assert!(solution.info.residual < 1e-10);
//! # Ok::<(), petri::Error>(())
//! ```
//!
//! | step | module |
//! |---|---|
//! | read and write nets (PNPRO, PNML, TOML, DOT) | [`io`] |
//! | the net as written, with parameters | [`net`], [`expr`] |
//! | the net instantiated, firing rule | [`gspn`] |
//! | reachability graph | [`reachability`] |
//! | vanishing elimination, CTMC, long-run solution, measures | [`ctmc`] |
//! | nets that finish: end probabilities, mean time, its distribution | [`absorption`], [`survival`] |
//! | steady-state methods (GTH, LU, BiCGSTAB, Gauss–Seidel) | [`steady_state`], [`krylov`] |
//! | structural analysis | [`incidence`], [`invariants`] |
//! | behavioural properties | [`properties`] |
//! | discrete-event simulation | [`simulation`] |
//! | stopping a long computation from another thread | [`interrupt`] |
//! | scalable benchmark nets | [`families`] |
//! | the closest valid name, for messages | [`suggest`] |
#![warn(missing_docs)]

pub mod absorption;
mod aggregation;
mod blocks;
pub mod ctmc;
pub mod decision;
mod descriptor;
pub mod error;
pub mod expr;
pub mod families;
pub mod gspn;
pub mod incidence;
pub mod interrupt;
pub mod invariants;
pub mod io;
pub mod krylov;
mod linear;
mod marginals;
mod marking;
mod mdd;
pub mod mdp;
pub mod net;
mod product_search;
mod profile_lu;
pub use gspn::policy;
pub mod properties;
pub mod reachability;
mod rows;
pub mod scc;
pub mod simulation;
pub mod steady_state;
pub mod structure;
pub mod structured;
pub mod suggest;
pub mod survival;
mod sweep;
mod vanishing;

pub use absorption::{Absorbing, Absorption};
pub use ctmc::{CompileStats, CompiledGspn, MemoryAccount, MemoryPart, Solution};
pub use decision::{ChoiceReport, DecisionNet, NetObjective};
pub use error::{Error, Result};
pub use expr::{CompiledExpr, Expr};
pub use gspn::{Gspn, MarkingKind, Timing};
pub use incidence::{DisplayIncidence, Incidence};
pub use interrupt::{Interrupt, Progress, ProgressSnapshot, Stage};
pub use invariants::{
    DisplayInvariant, DisplayInvariants, FarkasInfo, FarkasParams, InvariantKind, Invariants, NamedInvariant,
    NamedTerm, p_invariants, structural_bounds, t_invariants,
};
pub use net::{
    Arc, ArcKind, Label, Net, Param, ParamKind, Params, Place, PlaceId, RewardModel, Servers, Transition,
    TransitionId, TransitionKind,
};
pub use policy::{Action, Policy};
pub use properties::Properties;
pub use reachability::{
    COMPILE_BYTES_PER_EDGE, COMPILE_BYTES_PER_STATE, Edge, ExploreParams, ExploreStats, FALLBACK_MAX_MEMORY,
    FIXED_BYTES, MarkingId, ReachabilityGraph, SOLVE_BYTES_PER_EDGE, SOLVE_BYTES_PER_STATE,
    default_max_memory, estimated_bytes, guard_bytes,
};
pub use simulation::{Estimate, SimParams, SimProgress, SimResult, simulate, simulate_observed};
pub use steady_state::{Method, SolveInfo, SolveParams};
pub use structure::{Component, GroupInfo, Structure, StructureParams};
pub use structured::{StructuredGspn, StructuredParams, StructuredSolution, StructuredStats};
pub use suggest::closest;
