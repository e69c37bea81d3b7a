//! Reports: everything is recomputed from a results folder — `suite.json`
//! (which suite, scenarios, runs, seed) and `results.jsonl` (one record per
//! run). The core writes the summaries (`summary.json`, `summary.csv`); the
//! suite adds its tables, explanation and pictures ([`Suite::report`]); the
//! page goes out as `tables.md` and an offline `index.html`.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

use crate::page::Page;
use crate::record;
use crate::runner;
use crate::suite::{ReportContext, Suite};
use crate::summary::{self, CONFIDENCE};
use crate::tables;

/// What the written report contains.
#[derive(Debug, Clone)]
pub struct Written {
    /// The text tables printed to the terminal.
    pub text: String,
    /// Files written.
    pub files: Vec<PathBuf>,
}

/// Writes the report of a results folder: `summary.json`, `summary.csv`,
/// `tables.md`, the suite's pictures in `pictures/`, and `index.html`.
pub fn write(dir: &Path, suite: &dyn Suite, pictures: bool) -> Result<Written> {
    let info = suite.info();
    let results = dir.join("results.jsonl");
    let (lines, _) = runner::read_results(&results)?;
    record::check_lines(&results, &lines, &runner::keys(&suite.campaigns()), &info.name)?;
    let runs = record::group(&lines)?;
    let summaries = summary::summarise(&info.scenarios, &runs);
    let mut files = Vec::new();
    save(
        dir,
        "summary.json",
        &serde_json::to_string_pretty(&summaries)?,
        &mut files,
    )?;
    save(dir, "summary.csv", &tables::csv(&summaries), &mut files)?;
    let ctx = ReportContext {
        dir,
        info,
        runs: &runs,
        summaries: &summaries,
        pictures,
    };
    let part = suite.report(&ctx)?;
    let page = Page {
        title: info.name.clone(),
        intro: part
            .intro
            .clone()
            .unwrap_or_else(|| format!("{} runs per scenario, base seed {}.", info.runs, info.seed)),
        raw_data: format!(
            "Intervals are {}% (Wilson for I_R, Student-t for I_T). Raw data: <a href=\"results.jsonl\">results.jsonl</a>, <a href=\"summary.csv\">summary.csv</a>, <a href=\"summary.json\">summary.json</a>, <a href=\"tables.md\">tables.md</a>.",
            CONFIDENCE * 100.0
        ),
        blocks: part.blocks,
    };
    save(dir, "tables.md", &page.markdown(), &mut files)?;
    files.extend(part.files);
    save(dir, "index.html", &page.html(), &mut files)?;
    Ok(Written {
        text: part.text,
        files,
    })
}

fn save(dir: &Path, name: &str, text: &str, files: &mut Vec<PathBuf>) -> Result<()> {
    let p = dir.join(name);
    std::fs::write(&p, text).with_context(|| format!("writing {}", p.display()))?;
    files.push(p);
    Ok(())
}
