//! Experiments: scenarios, suites, batch runs, metrics and reports.
//!
//! The generic core: a [`scenario::Scenario`] (a TOML file) describes a
//! world, a robot, a controller and a task; a [`suite::Suite`] is a set of
//! runs — independent, or campaigns whose state carries over — that the
//! [`runner`] executes as one resumable, shardable batch into one record
//! per run ([`record::RunRecord`]); [`report`] turns a results folder into
//! summaries, tables, pictures and an offline HTML page. One replayed run
//! ([`pictures::Replay`]) can be watched: [`viewer`] writes it as a
//! self-contained page with a time slider, [`foxglove`] as an MCAP file for
//! Foxglove.
//!
//! The suites themselves live in [`suites`], one folder each, listed in
//! [`suites::REGISTRY`]; nothing outside that module names one. Robot runs
//! that more than one suite, or a suite and a command, share (guide
//! missions, topological explorations and routes) live in [`runs`], between
//! the core and the suites.
//!
//! The work behind the command line's commands, shared with the Python
//! package (`crates/py`) so that both say and print the same: [`gspn`]
//! (loading, solving, analysing, simulating nets; the supervisor's
//! decision), [`optimize`] (nets with decisions and DRN files optimised,
//! policies), [`engine`] (which GSPN engine solves a net), [`tours`]
//! (the guide robot between named places),
//! [`batch`] (a suite run into a results folder), [`map_file`] (map
//! files).
#![warn(missing_docs)]

pub mod batch;
pub mod charts;
pub mod encode;
pub mod engine;
pub mod experiment;
pub mod foxglove;
pub mod gspn;
pub mod map_file;
pub mod net_view;
pub mod optimize;
pub mod page;
pub mod pictures;
pub mod record;
pub mod report;
pub mod runner;
pub mod runs;
pub mod scenario;
pub mod scenario_suite;
pub mod slurm;
pub mod stats;
pub mod suite;
pub mod suites;
pub mod summary;
pub mod tables;
#[cfg(test)]
mod test_replays;
pub mod tours;
pub mod traps;
pub mod viewer;
