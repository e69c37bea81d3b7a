//! `petrinav guide …`: the tour-guide robot's mission log and what its
//! supervisor learns from it.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use clap::Subcommand;
use nav::supervisor::learning::{self, Learned};
use nav::supervisor::log::{Entry, StateName};

use crate::outln;
use crate::output::{Table, num};

#[derive(Subcommand, Debug)]
pub enum GuideCommand {
    /// The mission log: one row per calibration run and mission, then the rates learnt.
    ///
    /// A log is kept by `petrinav nav go … --log LOG` (and `lab run tourguide` writes its
    /// campaigns' logs in `out/tourguide/logs/`). A last line cut mid-write is reported, and
    /// the file left as it is. Example:
    ///
    ///   petrinav guide log show out/tourguide/logs/moderate-campaign0.jsonl
    #[command(subcommand)]
    Log(LogCommand),
    /// The supervisor's rates λ1…λ11 learnt from a mission log, and the behaviours'
    /// references (mean time, speed, trajectory length).
    ///
    ///   petrinav guide learn missions.jsonl --json
    Learn {
        /// The mission log (JSON lines).
        log: PathBuf,
        /// Print JSON.
        #[arg(long)]
        json: bool,
    },
}

#[derive(Subcommand, Debug)]
pub enum LogCommand {
    /// Shows a mission log.
    Show {
        /// The mission log (JSON lines).
        log: PathBuf,
        /// Print the entries as JSON lines (as read), and the rates.
        #[arg(long)]
        json: bool,
    },
}

pub fn run(cmd: GuideCommand) -> Result<()> {
    match cmd {
        GuideCommand::Log(LogCommand::Show { log, json }) => show(&log, json),
        GuideCommand::Learn { log, json } => learn(&log, json),
    }
}

/// Reads a log of the shipped supervisor net, reporting a torn last line.
pub fn read(path: &Path) -> Result<Vec<Entry>> {
    lab::tours::read_log(path)
}

fn sojourn_total(s: &[nav::supervisor::log::Sojourn], state: StateName) -> (usize, f64) {
    let of: Vec<_> = s.iter().filter(|x| x.state == state).collect();
    (
        of.iter().filter(|x| x.ended).count(),
        of.iter().map(|x| x.duration_s).sum(),
    )
}

fn rates_text(l: &Learned) -> String {
    let mut t = Table::new(["rate", "value", "meaning"]);
    let meaning = [
        "switch to contour (fixed per hypothesis)",
        "switch to AutoMove (fixed per hypothesis)",
        "localizer Success → Warning",
        "localizer Warning → Success",
        "planner Normal → Abnormal",
        "planner Abnormal → Normal",
        "AutoMove completes (1 / mean reference time)",
        "contour tracking completes",
        "AutoMove fails",
        "contour tracking fails",
        "re-initialisation (fixed)",
    ];
    for (i, m) in meaning.iter().enumerate() {
        t.row([
            format!("λ{}", i + 1),
            format!("{:.6}", l.rates.get(i + 1)),
            m.to_string(),
        ]);
    }
    t.render()
}

fn show(path: &Path, json: bool) -> Result<()> {
    let entries = read(path)?;
    let learned = learning::learn(&entries);
    if json {
        for e in &entries {
            outln!("{}", serde_json::to_string(e)?)?;
        }
        match &learned {
            Ok(l) => outln!("{}", serde_json::json!({ "learned": l }))?,
            Err(e) => outln!(
                "{}",
                serde_json::json!({ "learned": null, "error": e.to_string() })
            )?,
        }
        return Ok(());
    }
    let mut t = Table::new([
        "#",
        "entry",
        "outcome",
        "time (s)",
        "warnings",
        "in Warning (s)",
        "abnormal",
        "Abnormal (s)",
        "automove (s)",
        "contour (s)",
        "decisions",
    ]);
    for (k, e) in entries.iter().enumerate() {
        match e {
            Entry::Calibration(c) => t.row([
                (k + 1).to_string(),
                format!("calibration {:?}", c.behaviour).to_lowercase(),
                if c.success { "goal" } else { "failed" }.to_string(),
                num(c.duration_s),
                "-".into(),
                "-".into(),
                "-".into(),
                "-".into(),
                "-".into(),
                "-".into(),
                "-".into(),
            ]),
            Entry::Mission(m) => {
                let (warnings, _) = sojourn_total(&m.localizer, StateName::Success);
                let (_, warn_s) = sojourn_total(&m.localizer, StateName::Warning);
                let (abnormal, _) = sojourn_total(&m.planner, StateName::Normal);
                let (_, abn_s) = sojourn_total(&m.planner, StateName::Abnormal);
                let auto = m
                    .decisions
                    .iter()
                    .filter(|d| d.choice == nav::supervisor::Behaviour::AutoMove)
                    .count();
                let first = m
                    .decisions
                    .first()
                    .map(|d| format!("{:?}", d.choice).to_lowercase());
                t.row([
                    (k + 1).to_string(),
                    format!("mission {}", m.mission),
                    m.outcome.replace('_', " "),
                    num(m.duration_s),
                    warnings.to_string(),
                    num(warn_s),
                    abnormal.to_string(),
                    num(abn_s),
                    num(m.time_automove_s),
                    num(m.time_contour_s),
                    match first {
                        None => "-".into(),
                        Some(f) => format!(
                            "{} (start {f}; automove {auto}, contour {})",
                            m.decisions.len(),
                            m.decisions.len() - auto
                        ),
                    },
                ]);
            }
        }
    }
    outln!("{}", t.render().trim_end())?;
    outln!()?;
    match learned {
        Ok(l) => {
            outln!(
                "learnt from {} missions ({} reached the goal) and the calibration runs:",
                l.missions,
                l.successes
            )?;
            outln!("{}", rates_text(&l).trim_end())?;
        }
        Err(e) => outln!("no rates yet: {e}")?,
    }
    Ok(())
}

fn learn(path: &Path, json: bool) -> Result<()> {
    let entries = read(path)?;
    let l = learning::learn(&entries).with_context(|| format!("learning from {}", path.display()))?;
    if json {
        outln!("{}", serde_json::to_string_pretty(&l)?)?;
        return Ok(());
    }
    outln!("{}", rates_text(&l).trim_end())?;
    outln!(
        "references: AutoMove {} s at {} m/s over {} m; contour tracking {} s at {} m/s over {} m",
        num(l.automove.mean_time_s),
        num(l.automove.mean_speed_mps),
        num(l.automove.length_m()),
        num(l.contour.mean_time_s),
        num(l.contour.mean_speed_mps),
        num(l.contour.length_m())
    )?;
    Ok(())
}
