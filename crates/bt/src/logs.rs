//! Leaf parameters from execution logs (`petrinav bt fit`).
//!
//! Three forms are read, each reduced to status transitions
//! `(time, node key, new status)` in order of time:
//!
//! - **our JSONL**: one object per line, `{"t": 12.5, "node": "FollowPath",
//!   "status": "RUNNING"}` (`t` in seconds; `node` the sidecar key — the
//!   node's `name`, else its type; `status` one of IDLE, RUNNING, SUCCESS,
//!   FAILURE, SKIPPED); a line `{"run": …}` (any value) starts a new run;
//! - **BehaviorTree.CPP 4's `FileLogger2`** (`.btlog`): the tree's XML with
//!   each node's `_uid`, then 9-byte records (48-bit microseconds since the
//!   first, 16-bit uid, status byte);
//! - **BehaviorTree.CPP's `MinitraceLogger`** (Chrome trace JSON, v3 and
//!   v4): begin/end events per node name. It records no outcome, so it
//!   yields durations only (outcome counts stay empty).
//!
//! BehaviorTree.CPP 4's `SqliteLogger` (`.db3`) is not read: reading SQLite
//! needs either the C library (a `cc` build of ~250k lines, minutes on two
//! cores) or a file-format reader of our own; see docs/behaviour-trees.md, *Logs*.
//!
//! An action's episode runs from RUNNING to SUCCESS or FAILURE (or is
//! instantaneous when it goes from IDLE straight to a result); a halted one
//! (RUNNING → IDLE) is counted apart and not used. A condition's evaluations
//! give `p_true` (the fraction that succeeded) and `change_rate`, from the
//! changes between consecutive evaluations in a run: with a two-state
//! process, `P(change within Δt) ≈ 2p(1−p)·ρ·Δt` for short gaps, so
//! `ρ ≈ changes / (2p(1−p) Σ Δt)` — a rough, documented estimate.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use serde::Serialize;

use crate::error::{Error, Result};
use crate::tree::{Kind, Tree};

/// A node's status in a log.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum LogStatus {
    /// Not running.
    Idle,
    /// Running.
    Running,
    /// Succeeded.
    Success,
    /// Failed.
    Failure,
    /// Skipped (v4).
    Skipped,
}

/// One status change.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Transition {
    /// Run number (a log file, or a `run` line of our JSONL).
    pub run: usize,
    /// Seconds.
    pub t: f64,
    /// The node's key (`name`, else type).
    pub node: String,
    /// Its new status (`None`: a Minitrace end, outcome unknown).
    pub status: Option<LogStatus>,
}

fn status_of(s: &str) -> Option<LogStatus> {
    Some(match s.trim().to_ascii_uppercase().as_str() {
        "IDLE" => LogStatus::Idle,
        "RUNNING" => LogStatus::Running,
        "SUCCESS" => LogStatus::Success,
        "FAILURE" => LogStatus::Failure,
        "SKIPPED" => LogStatus::Skipped,
        _ => return None,
    })
}

/// Reads our JSONL log.
pub fn read_jsonl(text: &str, file: &str) -> Result<Vec<Transition>> {
    let mut out = Vec::new();
    let mut run = 0;
    for (i, line) in text.lines().enumerate() {
        let err = |message: String| Error::Log {
            file: file.to_string(),
            location: format!("line {}", i + 1),
            message,
        };
        if line.trim().is_empty() {
            continue;
        }
        let v: serde_json::Value = serde_json::from_str(line).map_err(|e| err(format!("not JSON: {e}")))?;
        if v.get("run").is_some() {
            run += 1;
            continue;
        }
        let t = v
            .get("t")
            .and_then(serde_json::Value::as_f64)
            .filter(|t| t.is_finite())
            .ok_or_else(|| err("`t` (seconds, a finite number) is missing".into()))?;
        let node = v
            .get("node")
            .and_then(serde_json::Value::as_str)
            .ok_or_else(|| err("`node` (a string) is missing".into()))?;
        let s = v
            .get("status")
            .and_then(serde_json::Value::as_str)
            .ok_or_else(|| err("`status` is missing".into()))?;
        let status = status_of(s).ok_or_else(|| {
            err(format!(
                "`status` = `{s}`: IDLE, RUNNING, SUCCESS, FAILURE or SKIPPED"
            ))
        })?;
        out.push(Transition {
            run,
            t,
            node: node.to_string(),
            status: Some(status),
        });
    }
    Ok(out)
}

/// Reads a BehaviorTree.CPP 4 `FileLogger2` log (`.btlog`); `run` numbers it.
pub fn read_btlog(bytes: &[u8], file: &str, run: usize) -> Result<Vec<Transition>> {
    let err = |at: usize, message: String| Error::Log {
        file: file.to_string(),
        location: format!("byte {at}"),
        message,
    };
    const MAGIC: &[u8] = b"BTCPP4-FileLogger2";
    if !bytes.starts_with(MAGIC) {
        return Err(err(
            0,
            "not a FileLogger2 log (it starts with `BTCPP4-FileLogger2`)".into(),
        ));
    }
    let mut at = MAGIC.len() + 1;
    let take = |at: usize, n: usize| -> Result<&[u8]> {
        bytes
            .get(at..at + n)
            .ok_or_else(|| err(at, format!("truncated: {n} more bytes expected")))
    };
    let size = i32::from_le_bytes(take(at, 4)?.try_into().unwrap_or([0; 4]));
    at += 4;
    if size < 0 {
        return Err(err(at - 4, format!("negative XML size {size}")));
    }
    let xml = std::str::from_utf8(take(at, size as usize)?)
        .map_err(|e| err(at, format!("the XML is not UTF-8: {e}")))?;
    at += size as usize;
    let names = uid_names(xml).map_err(|m| err(at - size as usize, m))?;
    take(at, 8)?;
    at += 8;
    let mut out = Vec::new();
    while at < bytes.len() {
        let rec = take(at, 9)?;
        let mut ts = [0u8; 8];
        ts[..6].copy_from_slice(&rec[..6]);
        let t = u64::from_le_bytes(ts) as f64 * 1e-6;
        let uid = u16::from_le_bytes([rec[6], rec[7]]);
        let status = match rec[8] {
            0 => LogStatus::Idle,
            1 => LogStatus::Running,
            2 => LogStatus::Success,
            3 => LogStatus::Failure,
            4 => LogStatus::Skipped,
            s => return Err(err(at + 8, format!("unknown status {s}"))),
        };
        let node = names
            .get(&uid)
            .ok_or_else(|| err(at + 6, format!("node uid {uid} is not in the log's tree")))?;
        out.push(Transition {
            run,
            t,
            node: node.clone(),
            status: Some(status),
        });
        at += 9;
    }
    Ok(out)
}

/// `_uid` → key (`name`, else element name) of the tree a logger embeds.
fn uid_names(xml: &str) -> std::result::Result<BTreeMap<u16, String>, String> {
    let doc = roxmltree::Document::parse(xml).map_err(|e| format!("the embedded XML: {e}"))?;
    let mut out = BTreeMap::new();
    for el in doc.descendants().filter(|e| e.is_element()) {
        if let Some(uid) = el.attribute("_uid").and_then(|u| u.trim().parse::<u16>().ok()) {
            let key = el.attribute("name").unwrap_or(el.tag_name().name()).to_string();
            out.insert(uid, key);
        }
    }
    Ok(out)
}

/// Reads a `MinitraceLogger` trace (durations only); `run` numbers it.
pub fn read_minitrace(text: &str, file: &str, run: usize) -> Result<Vec<Transition>> {
    let err = |location: String, message: String| Error::Log {
        file: file.to_string(),
        location,
        message,
    };
    let v: serde_json::Value = serde_json::from_str(text)
        .map_err(|e| err(format!("line {}", e.line()), format!("not JSON: {e}")))?;
    let events = v
        .get("traceEvents")
        .and_then(serde_json::Value::as_array)
        .ok_or_else(|| err("top level".into(), "no `traceEvents` array".into()))?;
    let mut out = Vec::new();
    for (i, e) in events.iter().enumerate() {
        let (Some(ph), Some(name), Some(ts)) = (
            e.get("ph").and_then(serde_json::Value::as_str),
            e.get("name").and_then(serde_json::Value::as_str),
            e.get("ts").and_then(serde_json::Value::as_f64),
        ) else {
            return Err(err(
                format!("event {i}"),
                "an event needs `ph`, `name` and `ts`".into(),
            ));
        };
        let status = match ph {
            "B" => Some(LogStatus::Running),
            "E" | "I" | "i" => None,
            _ => continue,
        };
        if ph != "B" && ph != "E" {
            // An instant: a node that finished within its tick.
            out.push(Transition {
                run,
                t: ts * 1e-6,
                node: name.to_string(),
                status: Some(LogStatus::Running),
            });
        }
        out.push(Transition {
            run,
            t: ts * 1e-6,
            node: name.to_string(),
            status,
        });
    }
    Ok(out)
}

/// What the logs say about one action.
#[derive(Debug, Clone, Default, Serialize)]
pub struct ActionFit {
    /// Episodes that succeeded.
    pub successes: usize,
    /// Episodes that failed.
    pub failures: usize,
    /// Episodes whose outcome the log does not give (Minitrace).
    pub unknown: usize,
    /// Episodes halted before they ended.
    pub halted: usize,
    /// Total duration of the successful episodes (seconds).
    pub time_success: f64,
    /// Total duration of the failed episodes.
    pub time_failure: f64,
    /// Total duration of the episodes of unknown outcome.
    pub time_unknown: f64,
}

/// What the logs say about one condition.
#[derive(Debug, Clone, Default, Serialize)]
pub struct ConditionFit {
    /// Evaluations that succeeded.
    pub holds: usize,
    /// Evaluations that failed.
    pub fails: usize,
    /// Changes between consecutive evaluations in a run.
    pub changes: usize,
    /// Total time between consecutive evaluations in a run.
    pub gap_time: f64,
}

/// Estimates from logs, by node key.
#[derive(Debug, Clone, Default, Serialize)]
pub struct Fit {
    /// Actions.
    pub actions: BTreeMap<String, ActionFit>,
    /// Conditions.
    pub conditions: BTreeMap<String, ConditionFit>,
}

/// Estimates the parameters of `tree`'s leaves from `transitions` (in
/// order of time within each run). Keys no leaf of the tree has are ignored.
pub fn fit(tree: &Tree, transitions: &[Transition]) -> Fit {
    let mut kinds: BTreeMap<&str, bool> = BTreeMap::new();
    for n in &tree.nodes {
        match n.kind {
            Kind::Action => {
                kinds.insert(n.param_key(), true);
            }
            Kind::Condition => {
                kinds.insert(n.param_key(), false);
            }
            _ => {}
        }
    }
    let mut fit = Fit::default();
    // (run, key) → running since; (run, key) → last evaluation (time, held).
    let mut since: BTreeMap<(usize, &str), f64> = BTreeMap::new();
    let mut last: BTreeMap<(usize, &str), (f64, bool)> = BTreeMap::new();
    for tr in transitions {
        let Some(&is_action) = kinds.get(tr.node.as_str()) else {
            continue;
        };
        let key = (tr.run, tr.node.as_str());
        if is_action {
            let a = fit.actions.entry(tr.node.clone()).or_default();
            match tr.status {
                Some(LogStatus::Running) => {
                    since.entry(key).or_insert(tr.t);
                }
                Some(LogStatus::Idle) => {
                    if since.remove(&key).is_some() {
                        a.halted += 1;
                    }
                }
                Some(LogStatus::Skipped) => {}
                end => {
                    let d = since.remove(&key).map_or(0.0, |s| (tr.t - s).max(0.0));
                    match end {
                        Some(LogStatus::Success) => {
                            a.successes += 1;
                            a.time_success += d;
                        }
                        Some(LogStatus::Failure) => {
                            a.failures += 1;
                            a.time_failure += d;
                        }
                        _ => {
                            a.unknown += 1;
                            a.time_unknown += d;
                        }
                    }
                }
            }
        } else {
            let held = match tr.status {
                Some(LogStatus::Success) => true,
                Some(LogStatus::Failure) => false,
                _ => continue,
            };
            let c = fit.conditions.entry(tr.node.clone()).or_default();
            if held {
                c.holds += 1;
            } else {
                c.fails += 1;
            }
            if let Some((t0, h0)) = last.insert(key, (tr.t, held)) {
                c.gap_time += (tr.t - t0).max(0.0);
                c.changes += usize::from(h0 != held);
            }
        }
    }
    fit
}

impl Fit {
    /// The estimates as a TOML sidecar ([`crate::params`]), with the counts
    /// as comments. Leaves with no usable episode are left out.
    pub fn to_toml(&self) -> String {
        let mut s = String::from("# Leaf parameters estimated from logs by `petrinav bt fit`.\n");
        for (key, a) in &self.actions {
            let n = a.successes + a.failures;
            let all = n + a.unknown;
            if all == 0 {
                continue;
            }
            let _ = writeln!(
                s,
                "\n# {} successes, {} failures, {} of unknown outcome, {} halted",
                a.successes, a.failures, a.unknown, a.halted
            );
            let _ = writeln!(s, "[leaf.{}]", toml_key(key));
            if n > 0 {
                let _ = writeln!(s, "p_success = {}", a.successes as f64 / n as f64);
            }
            let overall = (a.time_success + a.time_failure + a.time_unknown) / all as f64;
            let ms = if a.successes > 0 {
                a.time_success / a.successes as f64
            } else {
                overall
            };
            let mf = if a.failures > 0 {
                a.time_failure / a.failures as f64
            } else {
                overall
            };
            let _ = writeln!(s, "mean_time_success = {ms}");
            let _ = writeln!(s, "mean_time_failure = {mf}");
        }
        for (key, c) in &self.conditions {
            let n = c.holds + c.fails;
            if n == 0 {
                continue;
            }
            let p = c.holds as f64 / n as f64;
            let rate = if p > 0.0 && p < 1.0 && c.gap_time > 0.0 {
                c.changes as f64 / (2.0 * p * (1.0 - p) * c.gap_time)
            } else {
                0.0
            };
            let _ = writeln!(
                s,
                "\n# {} evaluations, {} changes over {:.3} s between them",
                n, c.changes, c.gap_time
            );
            let _ = writeln!(s, "[leaf.{}]", toml_key(key));
            let _ = writeln!(s, "p_true = {p}");
            let _ = writeln!(s, "change_rate = {rate}");
        }
        s
    }
}

fn toml_key(k: &str) -> String {
    if !k.is_empty()
        && k.chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
    {
        k.to_string()
    } else {
        format!("{k:?}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn jsonl_errors_name_the_line() {
        let e = read_jsonl(
            "{\"t\": 1, \"node\": \"A\", \"status\": \"RUNNING\"}\n{\"t\": 2}\n",
            "l.jsonl",
        )
        .unwrap_err()
        .to_string();
        assert!(e.starts_with("l.jsonl: line 2:"), "{e}");
    }

    #[test]
    fn btlog_truncated_is_an_error() {
        let mut b = b"BTCPP4-FileLogger2".to_vec();
        b.push(1);
        b.extend_from_slice(&100i32.to_le_bytes());
        let e = read_btlog(&b, "x.btlog", 0).unwrap_err().to_string();
        assert!(e.contains("truncated"), "{e}");
    }
}
