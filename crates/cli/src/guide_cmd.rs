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
    use guide::supervisor::check::check_supervisor;
    use guide::supervisor::credit::{CREDIT_MODEL, CREDIT_RATE_BINDING, CreditSupervisor, credit_variants};
    use guide::supervisor::{MODEL, RATE_BINDING, source_variants};
    let nets: Vec<(String, petri::Net)> = match path {
        Some(p) => vec![(p.display().to_string(), lab::gspn::read_net(p)?)],
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
            Kind::Credit => check_supervisor(net, &credit_variants(), &CREDIT_RATE_BINDING),
            Kind::Source => check_supervisor(net, &source_variants(), &RATE_BINDING),
        };
        // What the check leaves to the supervisor itself: the places and
        // transitions it reads, compiled as it will be.
        let verdict = match c.require() {
            Err(e) => Err(format!("{}: {}", e.variant, e.property)),
            Ok(()) => match kind {
                Kind::Credit => CreditSupervisor::from_net(net).map(drop),
                Kind::Source => Supervisor::from_net(net).map(drop),
            }
            .map_err(|e| format!("the supervisor cannot use it: {e}")),
        };
        if let Err(why) = &verdict {
            refused.push(format!(
                "{name}: the supervisor net `{}` is refused: {why}",
                c.net
            ));
        }
        verdicts.push((name.clone(), kind, c, verdict));
    }
    if json {
        let v: Vec<serde_json::Value> = verdicts
            .iter()
            .map(|(name, kind, c, verdict)| {
                serde_json::json!({
                    "file": name,
                    "supervisor": match kind { Kind::Credit => "credit", Kind::Source => "source" },
                    "accepted": verdict.is_ok(),
                    "refused": verdict.as_ref().err(),
                    "check": c,
                })
            })
            .collect();
        outln!("{}", serde_json::to_string_pretty(&v)?)?;
    } else {
        for (name, kind, c, verdict) in &verdicts {
            outln!(
                "{name} ({} supervisor, net `{}`)",
                match kind {
                    Kind::Credit => "crediting",
                    Kind::Source => "the source's",
                },
                c.net
            )?;
            outln!("{}", check_table(c).trim_end())?;
            match verdict {
                Ok(()) => outln!("verdict: accepted\n")?,
                Err(why) => outln!("verdict: REFUSED — {why}\n")?,
            }
        }
    }
    if !refused.is_empty() {
        anyhow::bail!("{}", refused.join("; "));
    }
    Ok(())
}

/// The check's table: a row per variant, `-` where a property could not be
/// computed, and each row's first failure (or `ok`); the rates the
/// supervisor cannot bind listed under it.
fn check_table(c: &guide::supervisor::check::NetCheck) -> String {
    let mut t = Table::new([
        "variant",
        "left out",
        "rates, weights",
        "markings",
        "bounded",
        "dead markings",
        "live",
        "home state",
        "M0 home state",
        "verdict",
    ]);
    for v in &c.variants {
        let explored = v.markings.is_some();
        let known = |s: String| if explored { s } else { "-".into() };
        t.row([
            v.variant.clone(),
            if v.without.is_empty() {
                "-".into()
            } else {
                v.without.join(", ")
            },
            match v.values.as_slice() {
                [] => "ok".into(),
                bad => {
                    let mut names: Vec<&str> = bad.iter().map(|p| p.transition.as_str()).collect();
                    names.dedup();
                    format!("no: {}", names.join(", "))
                }
            },
            v.markings.map_or("-".into(), |m| m.to_string()),
            if v.error.is_some() {
                "-".into()
            } else {
                yes_no(v.bounded)
            },
            known(v.dead_markings.to_string()),
            known(if v.not_live.is_empty() {
                "yes".into()
            } else {
                format!("no: {}", v.not_live.join(", "))
            }),
            known(yes_no(v.home_state)),
            known(yes_no(v.reversible)),
            v.failure().unwrap_or_else(|| "ok".into()),
        ]);
    }
    let mut text = t.render();
    for p in &c.bound_rates {
        text.push_str(&format!("not a rate the supervisor learns: {p}\n"));
    }
    text
}

fn yes_no(b: bool) -> String {
    if b { "yes" } else { "no" }.to_string()
}

/// A log read: its entries, the supervisor it is for, and how many of its
/// entries were read but left out of the learning (each reported on
/// standard error as it is read).
struct ReadLog {
    entries: Vec<Entry>,
    kind: Kind,
    skipped: usize,
}

/// Reads a log of either shipped supervisor net (the one its first line
/// names); what the reader reports (a last line cut mid-write, entries
/// skipped) goes to standard error as warnings naming the line.
fn read_any(path: &Path) -> Result<ReadLog> {
    use std::io::BufRead as _;
    if !path.exists() {
        anyhow::bail!("{}: no such mission log", path.display());
    }
    let source = Supervisor::new()?.net_id().to_string();
    let credit = guide::supervisor::credit::CreditSupervisor::new()?
        .net_id()
        .to_string();
    // The first line that is not blank names the net (a malformed one is
    // reported by the reader below).
    let file = std::fs::File::open(path).with_context(|| format!("opening {}", path.display()))?;
    let first_net = std::io::BufReader::new(file)
        .lines()
        .map_while(std::result::Result::ok)
        .find(|l| !l.trim().is_empty())
        .and_then(|l| serde_json::from_str::<serde_json::Value>(&l).ok())
        .and_then(|v| v.get("net").and_then(|n| n.as_str()).map(str::to_string));
    let (net, kind) = if first_net.as_deref() == Some(credit.as_str()) {
        (credit, Kind::Credit)
    } else {
        (source, Kind::Source)
    };
    let log = MissionLog::read(path, &net)?;
    for notice in log.notices() {
        eprintln!("warning: {notice}");
    }
    Ok(ReadLog {
        entries: log.entries().to_vec(),
        kind,
        skipped: log.skipped().len(),
    })
}

/// Prints `N entries read but left out of the learning (see the
/// warnings)` when there are any.
fn print_skipped(skipped: usize) -> Result<()> {
    match skipped {
        0 => {}
        1 => outln!("1 entry read but left out of the learning (see the warning)")?,
        n => outln!("{n} entries read but left out of the learning (see the warnings)")?,
    }
    Ok(())
}

/// The learnt line of `--json`, with `"skipped": N` when entries were
/// left out of the learning.
fn with_skipped(mut v: serde_json::Value, skipped: usize) -> serde_json::Value {
    if skipped > 0
        && let Some(o) = v.as_object_mut()
    {
        o.insert("skipped".into(), skipped.into());
    }
    v
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
    let ReadLog {
        entries,
        kind,
        skipped,
    } = read_any(path)?;
    if kind == Kind::Credit && !json {
        return show_credit(&entries, skipped);
    }
    if kind == Kind::Credit {
        return show_credit_json(&entries, skipped);
    }
    let learned = learning::learn(&entries);
    if json {
        for e in &entries {
            outln!("{}", serde_json::to_string(e)?)?;
        }
        match &learned {
            Ok(l) => outln!("{}", with_skipped(serde_json::json!({ "learned": l }), skipped))?,
            Err(e) => outln!(
                "{}",
                with_skipped(
                    serde_json::json!({ "learned": null, "error": e.to_string() }),
                    skipped
                )
            )?,
        }
        return Ok(());
    }
    let t = entries_table(&entries);
    outln!("{}", t.trim_end())?;
    print_skipped(skipped)?;
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
fn show_credit(entries: &[Entry], skipped: usize) -> Result<()> {
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
    print_skipped(skipped)?;
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
fn show_credit_json(entries: &[Entry], skipped: usize) -> Result<()> {
    for e in entries {
        outln!("{}", serde_json::to_string(e)?)?;
    }
    let m = guide::supervisor::credit_learning::CreditModel::learn(entries);
    match &m {
        Ok(m) => outln!("{}", with_skipped(serde_json::json!({ "learned": m }), skipped))?,
        Err(e) => outln!(
            "{}",
            with_skipped(
                serde_json::json!({ "learned": null, "error": e.to_string() }),
                skipped
            )
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
    let ReadLog {
        entries,
        kind,
        skipped,
    } = read_any(path)?;
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
            print_skipped(skipped)?;
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
    print_skipped(skipped)?;
    Ok(())
}
