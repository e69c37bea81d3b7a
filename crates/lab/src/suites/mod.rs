//! The registry: every suite, listed once.
//!
//! A suite lives in its own folder here (its scenarios, metrics, report
//! and explanation) and registers itself with one line in [`REGISTRY`];
//! the generic core (runner, records, summaries, tables, pictures, page)
//! knows no suite by name. ARCHITECTURE.md lists the steps to add one.

pub mod deadlock;
pub mod files;
pub mod maps;
pub mod shared;
pub mod topo;
pub mod tourguide;
pub mod voting;

use anyhow::{Result, bail};

use crate::suite::{Registration, Suite, SuiteArgs, SuiteInfo};

/// Every suite, by name.
pub const REGISTRY: &[Registration] = &[
    voting::REGISTRATION,
    deadlock::REGISTRATION,
    maps::REGISTRATION,
    tourguide::REGISTRATION,
    topo::REGISTRATION,
    files::REGISTRATION,
];

/// The suite registered as `name`.
pub fn find(name: &str) -> Option<&'static Registration> {
    REGISTRY.iter().find(|r| r.name == name)
}

/// The names of the registered suites, for messages.
pub fn names() -> String {
    REGISTRY
        .iter()
        .map(|r| format!("`{}`", r.name))
        .collect::<Vec<_>>()
        .join(", ")
}

/// `; did you mean `NAME`?` for the suite closest to `name`, if one is
/// close.
fn did_you_mean(name: &str) -> String {
    let known: Vec<&str> = REGISTRY.iter().map(|r| r.name).collect();
    petri::closest(name, &known).map_or(String::new(), |c| format!("; did you mean `{c}`?"))
}

/// Builds the suite `name` with `args`.
pub fn build(name: &str, args: &SuiteArgs) -> Result<Box<dyn Suite>> {
    match find(name) {
        Some(r) => (r.build)(args),
        None => bail!(
            "unknown suite `{name}`{}; the suites are {}",
            did_you_mean(name),
            names()
        ),
    }
}

/// Rebuilds the suite a results folder describes.
pub fn rebuild(info: &SuiteInfo) -> Result<Box<dyn Suite>> {
    let suite = build(&info.suite, &SuiteArgs::of(info)?)?;
    if !suite.info().same_batch(info) {
        bail!(
            "the suite `{}` is no longer the one that wrote this folder (its scenarios, runs or seed changed)",
            info.suite
        );
    }
    Ok(suite)
}

/// The suite `what` names on a command line: one registered suite, or
/// scenario files (`.toml`) run as the `files` suite.
pub fn load<S: AsRef<str>>(what: &[S], runs: Option<u32>) -> Result<Box<dyn Suite>> {
    if let [name] = what
        && !name.as_ref().ends_with(".toml")
    {
        if find(name.as_ref()).is_none() {
            bail!(
                "unknown suite `{}`{}; the suites are {}; or give scenario files (.toml)",
                name.as_ref(),
                did_you_mean(name.as_ref()),
                names()
            );
        }
        return build(
            name.as_ref(),
            &SuiteArgs {
                runs,
                files: Vec::new(),
            },
        );
    }
    if let Some(bad) = what.iter().map(AsRef::as_ref).find(|w| !w.ends_with(".toml")) {
        let given = what.iter().map(AsRef::as_ref).collect::<Vec<_>>().join(" ");
        if find(bad).is_some() {
            bail!(
                "`{given}`: a batch is one suite (`{bad}` is one) or scenario files (.toml), not several suites or a suite and files: run each suite on its own"
            );
        }
        bail!(
            "unknown suite `{bad}`{}; the suites are {}; or give scenario files (.toml)",
            did_you_mean(bad),
            names()
        );
    }
    build(
        files::REGISTRATION.name,
        &SuiteArgs {
            runs,
            files: what
                .iter()
                .map(|w| std::path::PathBuf::from(w.as_ref()))
                .collect(),
        },
    )
}
