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
