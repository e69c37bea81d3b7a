//! Stopping a long computation from another thread.
//!
//! State-space generation, compilation and iterative solves can take
//! minutes on large nets. A caller that must be able to stop them (a
//! Python binding on Ctrl-C, a server whose client went away) raises an
//! [`AtomicBool`] that the computation polls at its natural checkpoints,
//! through an [`Interrupt`]; the computation then returns
//! [`Error::Cancelled`], leaving nothing half-built. The checkpoints:
//!
//! | computation | checked |
//! |---|---|
//! | [`ReachabilityGraph::explore_interruptible`](crate::ReachabilityGraph::explore_interruptible) | before each round of markings expanded (at most a few thousand markings per thread) |
//! | [`CompiledGspn::from_graph_interruptible`](crate::CompiledGspn::from_graph_interruptible) | before and after the elimination of vanishing markings, and before the strongly connected components |
//! | [`CompiledGspn::solve_rates_interruptible`](crate::CompiledGspn::solve_rates_interruptible) | before each linear solve and at every sweep of BiCGSTAB and Gauss–Seidel (a direct solve runs to its end) |
//!
//! Simulation has its own observer with progress
//! ([`simulate_observed`](crate::simulate_observed)).
//!
//! ```
//! use std::sync::atomic::{AtomicBool, Ordering};
//! use petri::{ExploreParams, Interrupt, ReachabilityGraph};
//!
//! let net = petri::families::kanban(2);
//! let gspn = net.instantiate(&petri::Params::new())?;
//! let stop = AtomicBool::new(true); // raised before it starts
//! let r = ReachabilityGraph::explore_interruptible(&gspn, &ExploreParams::default(), Interrupt::new(&stop));
//! assert!(matches!(r, Err(petri::Error::Cancelled { .. })));
//! # Ok::<(), petri::Error>(())
//! ```

use std::sync::atomic::{AtomicBool, Ordering};

use crate::error::{Error, Result};

/// What [`Error::Cancelled`] says a stopped solve was doing.
pub(crate) const SOLVING: &str = "solving the steady state";

/// A flag, raised by another thread, that stops a computation at its next
/// checkpoint; [`Interrupt::NEVER`] for none. Cheap to copy and to check
/// (one relaxed atomic load).
#[derive(Debug, Clone, Copy, Default)]
pub struct Interrupt<'a>(Option<&'a AtomicBool>);

impl<'a> Interrupt<'a> {
    /// No flag: the computation runs to its end.
    pub const NEVER: Interrupt<'static> = Interrupt(None);

    /// Stops the computation once `flag` is `true`.
    pub fn new(flag: &'a AtomicBool) -> Interrupt<'a> {
        Interrupt(Some(flag))
    }

    /// Whether the flag has been raised.
    pub fn is_raised(self) -> bool {
        self.0.is_some_and(|f| f.load(Ordering::Relaxed))
    }

    /// [`Error::Cancelled`] if the flag has been raised; `during` says what
    /// was being done ("generating the reachability graph").
    pub fn check(self, during: &'static str) -> Result<()> {
        if self.is_raised() {
            Err(Error::Cancelled { during })
        } else {
            Ok(())
        }
    }
}
