//! Robot runs shared by suites and by the command layer: the middle layer
//! between the generic core and the suites.
//!
//! A module here runs a robot stack in the simulator and judges it by the
//! truth, for more than one suite or for a suite and a command
//! ([`crate::tours`], the command line's `nav go` and `topo explore / go`).
//! It may use the core (seeds from [`crate::runner`], [`crate::record`])
//! but no suite and no command module; the core does not use it
//! (`tests/layout.rs` holds both rules).
//!
//! | module | what it runs | used by |
//! |---|---|---|
//! | [`mission`] | the tour-guide robot's legs and tours on a map | suites `maps`, `tourguide`; [`crate::tours`] |
//! | [`topo`] | the ring robot's explorations and routes on topological maps | suite `topo`; `petrinav topo explore / go` |

pub mod mission;
pub mod topo;
