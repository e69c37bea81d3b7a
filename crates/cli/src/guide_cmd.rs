//! `petrinav guide …`: the tour-guide robot's mission log and what its
//! supervisor learns from it.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use clap::Subcommand;
use guide::supervisor::Supervisor;
use guide::supervisor::learning::{self, Learned};
use guide::supervisor::log::{Entry, MissionLog, StateName};

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
    /// Checks a supervisor net with petrinav's own engine before any robot uses it: every
    /// place bounded, no dead marking, every transition live, a home state — for the net as
    /// written and for every hypothesis the supervisor solves (each leaves transitions out).
    ///
    /// Without NET, both shipped nets (models/supervisor.toml, the source's;
    /// models/supervisor_credit.toml, the crediting one). A NET file (.toml, .pnpro,
    /// .pnml) is checked as a crediting net if it has the transition `t15`, else as the
    /// source's. The robot refuses a net that fails, naming the property; so does this
    /// command (exit code 1). Examples:
    ///
    ///   petrinav guide check
    ///
    ///   petrinav guide check my_supervisor.toml --json
    Check {
        /// A supervisor net file; both shipped nets if left out.
        net: Option<PathBuf>,
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
        GuideCommand::Check { net, json } => check(net.as_deref(), json),
    }
}

/// Which supervisor a net or a log is for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    Source,
    Credit,
}

fn check(path: Option<&Path>, json: bool) -> Result<()> {
    use guide::supervisor::check::check_net;
    use guide::supervisor::credit::{CREDIT_MODEL, credit_variants};
    use guide::supervisor::{MODEL, source_variants};
    let nets: Vec<(String, petri::Net)> = match path {
        Some(p) => vec![(
            p.display().to_string(),
            petri::io::read_file(p).with_context(|| format!("loading {}", p.display()))?,
        )],
        None => vec![
            (
                "models/supervisor.toml".into(),
                petri::io::read_str(MODEL, petri::io::Format::Toml, "models/supervisor.toml")?,
            ),
            (
                "models/supervisor_credit.toml".into(),
                petri::io::read_str(
                    CREDIT_MODEL,
                    petri::io::Format::Toml,
                    "models/supervisor_credit.toml",
                )?,
            ),
        ],
    };
    let mut verdicts = Vec::new();
    let mut refused = Vec::new();
    for (name, net) in &nets {
        let kind = if net.transition_id("t15").is_some() {
            Kind::Credit
        } else {
            Kind::Source
        };
        let c = match kind {
            Kind::Credit => check_net(net, &credit_variants()),
            Kind::Source => check_net(net, &source_variants()),
        };
        if let Err(e) = c.require() {
            refused.push(format!("{name}: {e}"));
        }
        verdicts.push((name.clone(), kind, c));
    }
    if json {
        let v: Vec<serde_json::Value> = verdicts
            .iter()
            .map(|(name, kind, c)| {
                serde_json::json!({
                    "file": name,
                    "supervisor": match kind { Kind::Credit => "credit", Kind::Source => "source" },
                    "accepted": c.passed(),
                    "refused": c.require().err().map(|e| e.to_string()),
                    "check": c,
                })
            })
            .collect();
        outln!("{}", serde_json::to_string_pretty(&v)?)?;
    } else {
        for (name, kind, c) in &verdicts {
            outln!(
                "{name} ({} supervisor, net `{}`)",
                match kind {
                    Kind::Credit => "crediting",
                    Kind::Source => "the source's",
                },
                c.net
            )?;
            let mut t = Table::new([
                "variant",
                "left out",
                "markings",
                "bounded",
                "dead markings",
                "live",
                "home state",
                "M0 home state",
            ]);
            for v in &c.variants {
                t.row([
                    v.variant.clone(),
                    if v.without.is_empty() {
                        "-".into()
                    } else {
                        v.without.join(", ")
                    },
                    v.markings.map_or("-".into(), |m| m.to_string()),
                    yes_no(v.bounded),
                    v.dead_markings.to_string(),
                    if v.not_live.is_empty() {
                        "yes".into()
                    } else {
                        format!("no: {}", v.not_live.join(", "))
                    },
                    yes_no(v.home_state),
                    yes_no(v.reversible),
                ]);
            }
            outln!("{}", t.render().trim_end())?;
            match c.require() {
                Ok(()) => outln!("verdict: accepted\n")?,
                Err(e) => outln!("verdict: REFUSED — {}: {}\n", e.variant, e.property)?,
            }
        }
    }
    if !refused.is_empty() {
        anyhow::bail!("{}", refused.join("; "));
    }
    Ok(())
}

fn yes_no(b: bool) -> String {
    if b { "yes" } else { "no" }.to_string()
}

/// Reads a log of either shipped supervisor net (the one its lines name).
fn read_any(path: &Path) -> Result<(Vec<Entry>, Kind)> {
    if !path.exists() {
        anyhow::bail!("{}: no such mission log", path.display());
    }
    let source = Supervisor::new()?.net_id().to_string();
    let credit = guide::supervisor::credit::CreditSupervisor::new()?
        .net_id()
        .to_string();
    let first_net = std::fs::read_to_string(path)
        .ok()
        .and_then(|t| {
            t.lines()
                .find(|l| !l.trim().is_empty())
                .and_then(|l| serde_json::from_str::<serde_json::Value>(l).ok())
        })
        .and_then(|v| v.get("net").and_then(|n| n.as_str()).map(str::to_string));
    let (net, kind) = if first_net.as_deref() == Some(credit.as_str()) {
        (credit, Kind::Credit)
    } else {
        (source, Kind::Source)
    };
    let log = MissionLog::read(path, &net)?;
    if let Some(t) = log.torn() {
        eprintln!(
            "warning: {}:{}: the last line was cut mid-write ({} bytes); it is not an entry and is left out",
            path.display(),
            t.line,
            t.bytes
        );
    }
    Ok((log.entries().to_vec(), kind))
}

/// The crediting supervisor's rates per route and crowd context: the
/// localizer's and the failure rates, and the progress speeds.
fn credit_text(entries: &[Entry]) -> Result<String> {
    use guide::supervisor::credit_learning::{CONTEXT_NAMES, CreditModel};
    let m = CreditModel::learn(entries)?;
    let mut routes: Vec<String> = m.progress.routes.keys().cloned().collect();
    if routes.is_empty() {
        routes.push(String::new());
    }
    let meaning = [
        (3, "localizer Success → Warning"),
        (4, "localizer Warning → Success"),
        (5, "planner Normal → Abnormal"),
        (6, "planner Abnormal → Normal"),
        (9, "AutoMove fails, planner Abnormal"),
        (10, "contour tracking fails, lost"),
        (12, "AutoMove fails, lost"),
        (13, "AutoMove fails, localized"),
        (14, "contour tracking fails, localized"),
    ];
    let mut out = format!(
        "learnt from {} missions ({} reached the goal) and the calibration runs:\n",
        m.missions, m.successes
    );
    for route in routes {
        let mut t = Table::new(["rate", "quiet", "busy", "crowded", "meaning"]);
        let rates: Vec<_> = (0..CONTEXT_NAMES.len())
            .map(|c| m.rates(&route, c, 1.0, 1.0))
            .collect();
        for (i, what) in meaning {
            let cell = |c: usize| {
                let (a, k) = (rates[c].automove.get(i), rates[c].contour.get(i));
                if i <= 4 {
                    format!("{a:.6} / {k:.6}")
                } else {
                    format!("{a:.6}")
                }
            };
            let what = if i <= 4 {
                format!("{what} (AutoMove / contour tracking)")
            } else {
                what.to_string()
            };
            t.row([format!("λ{i}"), cell(0), cell(1), cell(2), what]);
        }
        for (b, name) in [(0, "AutoMove"), (1, "contour tracking")] {
            t.row([
                format!("speed {}", b + 1),
                format!("{:.3}", rates[0].speeds[b].rate),
                format!("{:.3}", rates[1].speeds[b].rate),
                format!("{:.3}", rates[2].speeds[b].rate),
                format!(
                    "{name}'s progress along AutoMove's route, m/s (λ{} = speed / remaining length)",
                    7 + b
                ),
            ]);
        }
        let title = if route.is_empty() {
            "the log's route".to_string()
        } else {
            format!("route {route}")
        };
        out.push_str(&format!("{title}:\n{}\n", t.render()));
    }
    Ok(out)
}

fn sojourn_total(s: &[guide::supervisor::log::Sojourn], state: StateName) -> (usize, f64) {
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

/// Prints a log: per entry a line or a table row, then the rates learnt
/// from it (`json`: the entries and the learnt rates as JSON lines).
fn show(path: &Path, json: bool) -> Result<()> {
    let (entries, kind) = read_any(path)?;
    if kind == Kind::Credit && !json {
        return show_credit(&entries);
    }
    if kind == Kind::Credit {
        return show_credit_json(&entries);
    }
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
    let t = entries_table(&entries);
    outln!("{}", t.trim_end())?;
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

/// Prints a credit log: a line per entry, then the rates learnt from it.
fn show_credit(entries: &[Entry]) -> Result<()> {
    for (k, e) in entries.iter().enumerate() {
        let line = match e {
            Entry::Calibration(c) => format!(
                "{:>3}  calibration {:<8} {:<10} {} s",
                k + 1,
                format!("{:?}", c.behaviour).to_lowercase(),
                c.outcome,
                num(c.duration_s)
            ),
            Entry::Mission(m) => format!(
                "{:>3}  mission {:<12} {:<10} {} s, automove {} s, contour {} s, {} decisions, {} segments",
                k + 1,
                m.mission,
                m.outcome,
                num(m.duration_s),
                num(m.time_automove_s),
                num(m.time_contour_s),
                m.decisions.len(),
                m.segments.len()
            ),
        };
        outln!("{line}")?;
        if let Entry::Mission(m) = e {
            for d in &m.decisions {
                outln!("       {}", decision_line(d))?;
            }
        }
    }
    outln!()?;
    match credit_text(entries) {
        Ok(t) => outln!("{}", t.trim_end())?,
        Err(e) => outln!("no rates yet: {e}")?,
    }
    Ok(())
}

/// One decision of the crediting supervisor, as `guide log show` prints
/// it: when and why, the context (route, crowd), the net's marking, the
/// value of each choice (the expected time per completed mission, a
/// failure costing the time limit: `1 / f`), the choice, and the rates
/// used (λ3, λ4 each behaviour's; λ7, λ8 the completion rates from here).
fn decision_line(d: &guide::supervisor::log::DecisionLog) -> String {
    use guide::supervisor::credit_learning::CONTEXT_NAMES;
    let per = |f: f64| {
        if f > 0.0 {
            format!("{} s", num(1.0 / f))
        } else {
            "never".into()
        }
    };
    let rate = |r: &[f64], i: usize| r.get(i - 1).map_or("-".to_string(), |v| format!("{v:.4}"));
    let context = d
        .context
        .and_then(|c| CONTEXT_NAMES.get(c))
        .copied()
        .unwrap_or("-");
    format!(
        "decision at {} s ({}){}, {context}, marking {}: automove {} (f {:.5}), contour {} (f {:.5}) → {}{}; λ3 {}/{} λ4 {}/{} λ7 {} λ8 {} λ12 {} λ13 {} λ14 {}",
        num(d.time_s),
        d.reason,
        d.route.as_ref().map(|r| format!(" on {r}")).unwrap_or_default(),
        if d.marking.is_empty() {
            "-".into()
        } else {
            d.marking.join(" ")
        },
        per(d.f_auto),
        d.f_auto,
        per(d.f_cont),
        d.f_cont,
        format!("{:?}", d.choice).to_lowercase(),
        if d.explore { " (exploring)" } else { "" },
        rate(&d.rates, 3),
        rate(&d.contour_rates, 3),
        rate(&d.rates, 4),
        rate(&d.contour_rates, 4),
        rate(&d.rates, 7),
        rate(&d.rates, 8),
        rate(&d.rates, 12),
        rate(&d.rates, 13),
        rate(&d.rates, 14),
    )
}

/// Prints a credit log as JSON lines: the entries, then the model learnt
/// from them (or the error).
fn show_credit_json(entries: &[Entry]) -> Result<()> {
    for e in entries {
        outln!("{}", serde_json::to_string(e)?)?;
    }
    let m = guide::supervisor::credit_learning::CreditModel::learn(entries);
    match &m {
        Ok(m) => outln!("{}", serde_json::json!({ "learned": m }))?,
        Err(e) => outln!(
            "{}",
            serde_json::json!({ "learned": null, "error": e.to_string() })
        )?,
    }
    Ok(())
}

/// The table of a log's entries: outcome, time, warnings, Abnormal
/// episodes, time per behaviour and decisions of each.
fn entries_table(entries: &[Entry]) -> String {
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
                    .filter(|d| d.choice == guide::supervisor::Behaviour::AutoMove)
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
    t.render()
}

fn learn(path: &Path, json: bool) -> Result<()> {
    let (entries, kind) = read_any(path)?;
    if kind == Kind::Credit {
        if json {
            let m = guide::supervisor::credit_learning::CreditModel::learn(&entries)
                .with_context(|| format!("learning from {}", path.display()))?;
            outln!("{}", serde_json::to_string_pretty(&m)?)?;
        } else {
            outln!(
                "{}",
                credit_text(&entries)
                    .with_context(|| format!("learning from {}", path.display()))?
                    .trim_end()
            )?;
        }
        return Ok(());
    }
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
