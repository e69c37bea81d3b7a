//! Experiments: scenarios, suites, batch runs, metrics and reports.
#![warn(missing_docs)]

pub mod runner;
pub mod stats;
