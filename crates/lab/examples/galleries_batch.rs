//! The tour-guide suite's galleries alone (its campaigns whose scenario
//! starts with `galleries/`, optionally only some strategies), run into a
//! results folder and reported as the suite reports them — for measuring
//! the galleries without the museum:
//!
//! ```text
//! cargo run --release -p lab --example galleries_batch -- OUT CAMPAIGNS [JOBS [STRATEGY…]]
//! ```
//!
//! A STRATEGY names a galleries strategy (`supervisor`), or any of the
//! suite's scenarios whole (`day/supervisor`); none, every galleries
//! strategy. The records are those `lab run tourguide
//! --runs CAMPAIGNS` writes for these scenarios (same jobs, same seeds);
//! the report is written into OUT beside them. A folder already holding
//! some of the runs is resumed.

use std::path::PathBuf;

use anyhow::{Context, Result};
use lab::runner::{self, BatchParams};
use lab::suite::Suite;
use lab::suites::tourguide::TourGuideSuite;

/// Whether a campaign of `scenario` is run: a galleries scenario whose
/// strategy is listed (all of them if none is), or a scenario named whole
/// (`condition/strategy`, e.g. `day/supervisor`: the museum's too).
fn selected(scenario: &str, strategies: &[&str]) -> bool {
    let galleries = scenario
        .strip_prefix("galleries/")
        .is_some_and(|s| strategies.is_empty() || strategies.contains(&s));
    galleries || strategies.contains(&scenario)
}

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let out = PathBuf::from(args.first().context("OUT")?);
    let campaigns: u32 = args.get(1).map_or(Ok(2), |s| s.parse())?;
    let jobs: usize = args.get(2).map_or(Ok(2), |s| s.parse())?;
    let strategies: Vec<&str> = args.iter().skip(3).map(String::as_str).collect();
    let suite = TourGuideSuite::new(campaigns)?;
    let chosen: Vec<runner::Campaign> = suite
        .campaigns()
        .into_iter()
        .filter(|c| c.jobs.first().is_some_and(|j| selected(&j.scenario, &strategies)))
        .collect();
    std::fs::create_dir_all(&out)?;
    lab::batch::write_info(&out, suite.info(), None)?;
    let params = BatchParams {
        results: out.join("results.jsonl"),
        resume: out.join("results.jsonl").exists(),
        jobs: Some(jobs),
        progress: false,
        stop: None,
    };
    let summary = runner::run_batch(&chosen, &params, |job, earlier: &[serde_json::Value]| {
        let earlier = earlier
            .iter()
            .map(lab::record::parse)
            .collect::<Result<Vec<_>>>()?;
        Ok(serde_json::to_value(suite.run(job, &earlier)?)?)
    })?;
    eprintln!("{summary:?}");
    lab::report::write(&out, &suite, false)?;
    Ok(())
}
