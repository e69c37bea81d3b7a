//! Your own scenario files as a suite: `petrinav lab run a.toml b.toml`.
//!
//! Every file is a scenario ([`crate::scenario`]); the suite takes its runs
//! and seed from the first. The report is the table of all scenarios (with
//! dead-locks per run, for the controllers that detect them) and pictures.

use std::collections::{BTreeMap, BTreeSet};

use anyhow::{Context, Result, bail};

use super::shared;
use crate::experiment::Prepared;
use crate::page::Block;
use crate::scenario::Scenario;
use crate::scenario_suite::{ScenarioHooks, ScenarioSuite};
use crate::suite::{Registration, ReportContext, Suite, SuiteArgs, SuiteReport};
use crate::tables;

/// The suite in the registry.
pub const REGISTRATION: Registration = Registration {
    name: "files",
    about: "scenario files (.toml) given on the command line",
    build,
};

/// The suite of `args.files`; named after the scenario when there is one
/// file, `custom` otherwise.
pub fn suite(args: &SuiteArgs) -> Result<ScenarioSuite> {
    let mut scenarios = Vec::new();
    let mut sources = BTreeMap::new();
    let mut seen = BTreeSet::new();
    for p in &args.files {
        let s = Scenario::load(p)?;
        if !seen.insert(s.name.clone()) {
            bail!("two scenarios are named `{}`", s.name);
        }
        let abs = std::fs::canonicalize(p).unwrap_or_else(|_| p.clone());
        sources.insert(s.name.clone(), abs.display().to_string());
        scenarios.push(Prepared::new(s)?);
    }
    let first = scenarios.first().context("no scenario file given")?.scenario();
    let (runs, seed) = (first.runs, first.seed);
    let name = if args.files.len() == 1 {
        first.name.clone()
    } else {
        "custom".into()
    };
    Ok(ScenarioSuite::new(
        &name,
        REGISTRATION.name,
        args.runs.unwrap_or(runs),
        seed,
        scenarios,
        sources,
        ScenarioHooks {
            metrics: shared::deadlock_metric,
            keep_events: &[],
            markers: &shared::ACTIVITY_MARKERS,
            report,
        },
    ))
}

fn build(args: &SuiteArgs) -> Result<Box<dyn Suite>> {
    Ok(Box::new(suite(args)?))
}

fn report(suite: &ScenarioSuite, ctx: &ReportContext<'_>) -> Result<SuiteReport> {
    let (text, table) = tables::generic_table(ctx.summaries, &[shared::DEADLOCK_COLUMN]);
    let mut blocks = vec![Block::Table(table)];
    let mut files = Vec::new();
    blocks.extend(suite.pictures(ctx, &shared::pictures_caption(), &mut files)?);
    Ok(SuiteReport {
        text,
        intro: None,
        blocks,
        files,
    })
}
