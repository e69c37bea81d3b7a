//! Experiments: scenarios, suites, batch runs, metrics and reports.
//!
//! A [`scenario::Scenario`] (a TOML file) describes a world, a robot, a
//! controller and a task; a [`suite::Suite`] is a set of them run as one
//! batch by the [`runner`]; [`report`] turns a results folder into tables,
//! pictures and an offline HTML page.
#![warn(missing_docs)]

pub mod deadlock_report;
pub mod experiment;
pub mod report;
pub mod runner;
pub mod scenario;
pub mod stats;
pub mod suite;
pub mod traps;
pub mod voting_report;
