//! Run records: what one run produced, as one line of a results file.
//!
//! Every record has the measures every suite shares (outcome, time, path,
//! collisions, clearance, …), then what is a suite's or a controller's own:
//! `metrics`, named numbers (`{"deadlocks": 3.0}`) summarised generically
//! (mean and interval per scenario), and `events`, the typed events the
//! suite chose to keep (a decision, a warning; [`robot::Event`]). The runner
//! adds `key`, `scenario`, `run` and `seed` to the line.

use std::collections::BTreeMap;

use anyhow::{Context, Result, bail};
use robot::Event;
use serde_json::Value;

use crate::traps::DrawnTrap;

/// What one run produced (one line of a results file).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RunRecord {
    /// Reached the goal.
    pub success: bool,
    /// `goal`, `collision`, `time_limit`, `gave_up` or `lost`.
    pub outcome: String,
    /// Simulated time, seconds.
    pub time_s: f64,
    /// Length of the true path, metres.
    pub path_length_m: f64,
    /// Contact episodes.
    pub collisions: u32,
    /// Smallest clearance to walls and people, metres.
    pub min_clearance_m: f64,
    /// Final distance between the true and dead-reckoned positions, metres.
    pub odometry_error_m: f64,
    /// Final distance to the goal, metres.
    pub goal_distance_m: f64,
    /// Control ticks.
    pub ticks: u64,
    /// Ticks during which each behaviour / action was in control.
    pub behaviour_ticks: BTreeMap<String, u64>,
    /// The suite's and the controller's own measures, by name (finite
    /// numbers; see [`RunRecord::set_metric`]).
    #[serde(default)]
    pub metrics: BTreeMap<String, f64>,
    /// The events the suite keeps in its records (by kind), in time order.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub events: Vec<Event>,
    /// The start pose actually used (after jitter).
    pub start: [f64; 3],
    /// The trap drawn for this run, if the scenario has one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub trap: Option<DrawnTrap>,
    /// What a campaign's next run starts from (the suite's own data: where
    /// the robot stopped, what it learnt), if the suite keeps any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub state: Option<Value>,
}

impl RunRecord {
    /// Sets a metric; a value that is not finite (JSON cannot hold it) is
    /// an error naming the metric.
    pub fn set_metric(&mut self, name: &str, value: f64) -> Result<()> {
        if !value.is_finite() {
            bail!("metric `{name}` is {value}: metrics must be finite numbers");
        }
        self.metrics.insert(name.to_string(), value);
        Ok(())
    }

    /// A metric, if the record has it.
    pub fn metric(&self, name: &str) -> Option<f64> {
        self.metrics.get(name).copied()
    }
}

/// The records of a results file by scenario: `(run index, record)` in the
/// file's order.
pub type Runs = BTreeMap<String, Vec<(u32, RunRecord)>>;

/// The run index and scenario a runner added to a results line.
fn place(line: &Value) -> Result<(&str, u32)> {
    let name = line
        .get("scenario")
        .and_then(Value::as_str)
        .context("record without scenario")?;
    let run = line
        .get("run")
        .and_then(Value::as_u64)
        .and_then(|k| u32::try_from(k).ok())
        .with_context(|| format!("record of {name} without a run index"))?;
    Ok((name, run))
}

/// A results line as a typed record.
pub fn parse(line: &Value) -> Result<RunRecord> {
    let (name, run) = place(line)?;
    serde_json::from_value(line.clone()).with_context(|| format!("record {name}#{run}"))
}

/// Checks the lines of a results file (`path`, as read by
/// [`crate::runner::read_results`]: line `k + 1` is `lines[k]`) against
/// the suite that reads it, before any summary is made of them: every
/// record has a `key` that is one of the suite's runs (`keys`, from
/// [`crate::runner::keys`]; `suite` names it) and agrees with its
/// `scenario` and `run`; no run is there twice; `success` is true exactly
/// when `outcome` is `goal`; `time_s` and `path_length_m` are ≥ 0. Each
/// error names the file, the line and the field. Runs of the suite that
/// are missing are not an error (a batch in progress, or merged shards
/// with gaps).
pub fn check_lines(path: &std::path::Path, lines: &[Value], keys: &[String], suite: &str) -> Result<()> {
    let wanted: std::collections::HashSet<&str> = keys.iter().map(String::as_str).collect();
    let mut seen: std::collections::HashMap<&str, usize> = std::collections::HashMap::new();
    for (k, line) in lines.iter().enumerate() {
        let at = format!("{}:{}", path.display(), k + 1);
        let key = line.get("key").and_then(Value::as_str).with_context(|| {
            format!(
                "{at}: a record without a `key` (a results file's lines are written by `petrinav lab run`)"
            )
        })?;
        if let Some(first) = seen.insert(key, k + 1) {
            bail!(
                "{at}: run `{key}` is already on line {first}: a results file holds each run once (`petrinav lab merge` puts the folders of a sharded batch together)"
            );
        }
        if !wanted.contains(key) {
            bail!(
                "{at}: run `{key}` is not a run of the suite `{suite}` as its suite.json describes it (scenarios, runs, seed): the file holds another batch's or another suite's records"
            );
        }
        let (scenario, run) = place(line).with_context(|| format!("{at}: run `{key}`"))?;
        if key != format!("{scenario}#{run}") {
            bail!("{at}: `key` is `{key}` but `scenario` and `run` say `{scenario}#{run}`");
        }
        let outcome = line.get("outcome").and_then(Value::as_str);
        let success = line.get("success").and_then(Value::as_bool);
        if let (Some(outcome), Some(success)) = (outcome, success)
            && (outcome == "goal") != success
        {
            bail!(
                "{at}: run `{key}`: `success` is {success} but `outcome` is `{outcome}`: a run succeeds exactly when it ends at the goal"
            );
        }
        for field in ["time_s", "path_length_m"] {
            if let Some(v) = line.get(field).and_then(Value::as_f64)
                && v < 0.0
            {
                bail!("{at}: run `{key}`: `{field}` is {v}: it is a length or a time, ≥ 0");
            }
        }
    }
    Ok(())
}

/// Parses the lines of a results file ([`crate::runner::read_results`])
/// once, for the summaries and the run-by-run comparisons.
pub fn group(lines: &[Value]) -> Result<Runs> {
    let mut by = Runs::new();
    for line in lines {
        let (name, run) = place(line)?;
        by.entry(name.to_string()).or_default().push((run, parse(line)?));
    }
    Ok(by)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn metrics_must_be_finite_and_records_round_trip() {
        let mut r = RunRecord {
            success: true,
            outcome: "goal".into(),
            time_s: 1.0,
            path_length_m: 1.0,
            collisions: 0,
            min_clearance_m: 0.5,
            odometry_error_m: 0.0,
            goal_distance_m: 0.1,
            ticks: 10,
            behaviour_ticks: BTreeMap::new(),
            metrics: BTreeMap::new(),
            events: vec![Event::new("warning", 0.5).with("score", 0.25)],
            start: [0.0; 3],
            trap: None,
            state: None,
        };
        r.set_metric("warnings", 1.0).unwrap();
        let err = r.set_metric("ratio", f64::NAN).unwrap_err().to_string();
        assert!(err.contains("ratio"), "{err}");
        let mut line = serde_json::to_value(&r).unwrap();
        line["scenario"] = "a".into();
        line["run"] = 0.into();
        assert_eq!(parse(&line).unwrap(), r);
        let runs = group(&[line]).unwrap();
        assert_eq!(runs["a"][0].1.metric("warnings"), Some(1.0));
    }
}
