//! The dead-lock suite (docs/activity-trace.md): a dead-end trap drawn per run
//! (U, and V in two rows) on the course to the goal; priority arbitration
//! on the 16-sonar ring robot with and without dead-lock detection +
//! recovery (and with drifting odometry), voting on AIBOT with and without
//! the trace layer.
//!
//! Prints one row per scenario (success, time, path, failures, dead-locks
//! per run) and an explanation from the numbers (`explanation.rs`). The
//! scenarios in `scenarios/` here are compiled into the binary.

mod explanation;

use std::collections::BTreeMap;

use anyhow::Result;

use super::shared;
use crate::experiment::Prepared;
use crate::page::Block;
use crate::scenario::Scenario;
use crate::scenario_suite::{ScenarioHooks, ScenarioSuite};
use crate::suite::{Registration, ReportContext, Suite, SuiteArgs, SuiteReport};
use crate::tables;

/// The suite in the registry.
pub const REGISTRATION: Registration = Registration {
    name: "deadlock",
    about: "dead-end traps (U, V) × {priority, voting} × {with, without} dead-lock detection and recovery, 200 runs each",
    build,
};

/// The suite's scenarios, as shipped.
pub const SCENARIOS: [(&str, &str); 7] = [
    ("priority", include_str!("scenarios/priority.toml")),
    (
        "priority_recovery",
        include_str!("scenarios/priority_recovery.toml"),
    ),
    (
        "priority_recovery_slips",
        include_str!("scenarios/priority_recovery_slips.toml"),
    ),
    ("priority_v", include_str!("scenarios/priority_v.toml")),
    (
        "priority_v_recovery",
        include_str!("scenarios/priority_v_recovery.toml"),
    ),
    ("voting", include_str!("scenarios/voting.toml")),
    ("voting_trace", include_str!("scenarios/voting_trace.toml")),
];

/// The suite with `args.runs` runs per scenario (default 200, the files').
pub fn suite(args: &SuiteArgs) -> Result<ScenarioSuite> {
    let mut scenarios = Vec::new();
    let mut runs_default = 200;
    let mut seed = 1;
    for (name, text) in SCENARIOS {
        let s = Scenario::parse(
            text,
            &format!("crates/lab/src/suites/deadlock/scenarios/{name}.toml"),
            None,
        )?;
        runs_default = s.runs;
        seed = s.seed;
        scenarios.push(Prepared::new(s)?);
    }
    Ok(ScenarioSuite::new(
        REGISTRATION.name,
        REGISTRATION.name,
        args.runs.unwrap_or(runs_default),
        seed,
        scenarios,
        BTreeMap::new(),
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
    let mut blocks = vec![
        Block::Table(table),
        Block::Text(explanation::explanation(ctx.summaries, ctx.runs)),
    ];
    let mut files = Vec::new();
    blocks.extend(suite.pictures(ctx, &shared::pictures_caption(), &mut files)?);
    Ok(SuiteReport {
        text,
        intro: None,
        blocks,
        files,
    })
}
