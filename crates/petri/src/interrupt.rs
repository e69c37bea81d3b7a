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
//! The same checkpoints publish **progress** when the [`Interrupt`] carries
//! a [`Progress`] ([`Interrupt::with_progress`]): a few atomic counters —
//! the stage, the markings and edges generated so far, the solver's
//! iteration and residual — that another thread reads with
//! [`Progress::snapshot`] (a command line's progress bar polls them a few
//! times a second). Publishing is a relaxed atomic store per round of
//! generation or per iteration: nothing measurable next to the work
//! between two checkpoints, and nothing at all without a `Progress`. The
//! engine itself prints nothing.
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

use std::sync::atomic::{AtomicBool, AtomicU8, AtomicU64, AtomicUsize, Ordering};

use crate::error::{Error, Result};

/// What [`Error::Cancelled`] says a stopped solve was doing.
pub(crate) const SOLVING: &str = "solving the steady state";

/// What a computation observed through [`Progress`] is doing.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[repr(u8)]
pub enum Stage {
    /// Nothing started yet.
    #[default]
    Idle,
    /// Generating the reachability graph ([`ProgressSnapshot::markings`] and
    /// [`ProgressSnapshot::edges`] grow).
    Generating,
    /// Compiling the CTMC (eliminating vanishing markings, transposing).
    Compiling,
    /// Solving a linear system ([`ProgressSnapshot::iteration`] and
    /// [`ProgressSnapshot::residual`] change for iterative methods).
    Solving,
    /// Finding the product structure of the reachable set and building the
    /// structured engine's descriptor ([`crate::StructuredGspn::build`];
    /// [`ProgressSnapshot::markings`] is the reachable count once known).
    Structuring,
}

impl Stage {
    fn from_u8(v: u8) -> Stage {
        match v {
            1 => Stage::Generating,
            2 => Stage::Compiling,
            3 => Stage::Solving,
            4 => Stage::Structuring,
            _ => Stage::Idle,
        }
    }
}

/// Counters a computation publishes at its checkpoints, for another thread
/// to read ([`snapshot`](Self::snapshot)); hand it over with
/// [`Interrupt::with_progress`]. All loads and stores are relaxed: a
/// snapshot's fields are each recent, not necessarily from the same
/// instant.
#[derive(Debug, Default)]
pub struct Progress {
    stage: AtomicU8,
    markings: AtomicUsize,
    edges: AtomicUsize,
    iteration: AtomicUsize,
    residual: AtomicU64,
}

/// The counters of a [`Progress`] at one moment.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ProgressSnapshot {
    /// The current stage.
    pub stage: Stage,
    /// Markings (tangible and vanishing) stored so far, published after
    /// each round of generation; the total once generation has ended.
    pub markings: usize,
    /// Edges of the reachability graph so far, as `markings`.
    pub edges: usize,
    /// Iterations of the current iterative solve (0 before the first, and
    /// for direct methods).
    pub iteration: usize,
    /// The iterative solver's own estimate of its residual after that
    /// iteration (BiCGSTAB: the 2-norm of the residual of its pinned
    /// system; Gauss–Seidel: the relative imbalance of the sweep); the
    /// solution's reported residual is computed separately at the end.
    /// Infinity before the first iteration.
    pub residual: f64,
}

impl Progress {
    /// Counters at zero, stage [`Stage::Idle`].
    pub fn new() -> Progress {
        Progress::default()
    }

    /// The counters now.
    pub fn snapshot(&self) -> ProgressSnapshot {
        let iteration = self.iteration.load(Ordering::Relaxed);
        ProgressSnapshot {
            stage: Stage::from_u8(self.stage.load(Ordering::Relaxed)),
            markings: self.markings.load(Ordering::Relaxed),
            edges: self.edges.load(Ordering::Relaxed),
            iteration,
            residual: if iteration == 0 {
                f64::INFINITY
            } else {
                f64::from_bits(self.residual.load(Ordering::Relaxed))
            },
        }
    }
}

/// A flag, raised by another thread, that stops a computation at its next
/// checkpoint; [`Interrupt::NEVER`] for none. Cheap to copy and to check
/// (one relaxed atomic load).
/// It may also carry a [`Progress`] that the checkpoints update.
#[derive(Debug, Clone, Copy, Default)]
pub struct Interrupt<'a> {
    flag: Option<&'a AtomicBool>,
    progress: Option<&'a Progress>,
}

impl<'a> Interrupt<'a> {
    /// No flag: the computation runs to its end.
    pub const NEVER: Interrupt<'static> = Interrupt {
        flag: None,
        progress: None,
    };

    /// Stops the computation once `flag` is `true`.
    pub fn new(flag: &'a AtomicBool) -> Interrupt<'a> {
        Interrupt {
            flag: Some(flag),
            progress: None,
        }
    }

    /// The same, also publishing the computation's progress in `progress`.
    ///
    /// ```
    /// use petri::{ExploreParams, Interrupt, Progress, ReachabilityGraph, Stage};
    ///
    /// let gspn = petri::families::kanban(2).instantiate(&petri::Params::new())?;
    /// let progress = Progress::new();
    /// let stop = Interrupt::NEVER.with_progress(&progress);
    /// let rg = ReachabilityGraph::explore_interruptible(&gspn, &ExploreParams::default(), stop)?;
    /// let seen = progress.snapshot();
    /// assert_eq!((seen.stage, seen.markings), (Stage::Generating, rg.num_markings()));
    /// # Ok::<(), petri::Error>(())
    /// ```
    pub fn with_progress(self, progress: &'a Progress) -> Interrupt<'a> {
        Interrupt {
            progress: Some(progress),
            ..self
        }
    }

    /// Whether the flag has been raised.
    pub fn is_raised(self) -> bool {
        self.flag.is_some_and(|f| f.load(Ordering::Relaxed))
    }

    /// Publishes the start of `stage` (the solver's counters reset).
    pub(crate) fn stage(self, stage: Stage) {
        if let Some(p) = self.progress {
            if stage == Stage::Solving {
                p.iteration.store(0, Ordering::Relaxed);
            }
            p.stage.store(stage as u8, Ordering::Relaxed);
        }
    }

    /// Publishes the size of the graph generated so far.
    pub(crate) fn generated(self, markings: usize, edges: usize) {
        if let Some(p) = self.progress {
            p.markings.store(markings, Ordering::Relaxed);
            p.edges.store(edges, Ordering::Relaxed);
        }
    }

    /// Publishes an iterative solver's iteration and residual estimate.
    pub(crate) fn iterated(self, iteration: usize, residual: f64) {
        if let Some(p) = self.progress {
            p.residual.store(residual.to_bits(), Ordering::Relaxed);
            p.iteration.store(iteration, Ordering::Relaxed);
        }
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
