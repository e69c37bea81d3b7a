//! Summaries per scenario and run-by-run comparisons, for any suite.

use std::collections::BTreeMap;

use crate::record::{RunRecord, Runs};
use crate::stats::{Mean, Proportion};

/// Confidence level of every interval in reports.
pub const CONFIDENCE: f64 = 0.95;

/// The summary of one scenario's runs.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Summary {
    /// Scenario.
    pub scenario: String,
    /// Runs found.
    pub runs: usize,
    /// Reliability index `I_R` = successes / runs, with its Wilson interval.
    pub reliability: Proportion,
    /// Time index `I_T`: mean time to goal over successful runs, seconds.
    pub time: Mean,
    /// Mean path length of successful runs, metres.
    pub path_length: Mean,
    /// Runs ended by a collision.
    pub collisions: usize,
    /// Runs ended by the time limit.
    pub timeouts: usize,
    /// Runs in which the controller gave up.
    pub gave_up: usize,
    /// Runs in which the controller stopped away from the goal, believing
    /// it had arrived (odometry error).
    pub lost: usize,
    /// Each metric's mean over the runs that have it, with its Student-t
    /// interval.
    pub metrics: BTreeMap<String, Mean>,
    /// Share of control time of each behaviour/action over all runs.
    pub behaviour_share: BTreeMap<String, f64>,
}

impl Summary {
    /// The mean of a metric (NaN when no run has it).
    pub fn metric_mean(&self, name: &str) -> f64 {
        self.metrics.get(name).map_or(f64::NAN, |m| m.mean)
    }

    /// Summarises one scenario's records.
    pub fn of(scenario: &str, rs: &[&RunRecord]) -> Summary {
        let ok: Vec<&RunRecord> = rs.iter().copied().filter(|r| r.success).collect();
        let times: Vec<f64> = ok.iter().map(|r| r.time_s).collect();
        let lengths: Vec<f64> = ok.iter().map(|r| r.path_length_m).collect();
        let mut share: BTreeMap<String, f64> = BTreeMap::new();
        let total: u64 = rs.iter().flat_map(|r| r.behaviour_ticks.values()).sum();
        for r in rs {
            for (k, &v) in &r.behaviour_ticks {
                *share.entry(k.clone()).or_insert(0.0) += v as f64;
            }
        }
        if total > 0 {
            share.values_mut().for_each(|v| *v /= total as f64);
        }
        let mut values: BTreeMap<&str, Vec<f64>> = BTreeMap::new();
        for r in rs {
            for (k, &v) in &r.metrics {
                values.entry(k.as_str()).or_default().push(v);
            }
        }
        let count = |o: &str| rs.iter().filter(|r| r.outcome == o).count();
        Summary {
            scenario: scenario.to_string(),
            runs: rs.len(),
            reliability: Proportion::new(ok.len(), rs.len(), CONFIDENCE),
            time: Mean::new(&times, CONFIDENCE),
            path_length: Mean::new(&lengths, CONFIDENCE),
            collisions: count("collision"),
            timeouts: count("time_limit"),
            gave_up: count("gave_up"),
            lost: count("lost"),
            metrics: values
                .into_iter()
                .map(|(k, v)| (k.to_string(), Mean::new(&v, CONFIDENCE)))
                .collect(),
            behaviour_share: share,
        }
    }
}

/// Summarises the records of each scenario, in the order given.
pub fn summarise(scenarios: &[String], runs: &Runs) -> Vec<Summary> {
    scenarios
        .iter()
        .map(|name| {
            let rs: Vec<&RunRecord> = runs
                .get(name)
                .map_or(Vec::new(), |v| v.iter().map(|(_, r)| r).collect());
            Summary::of(name, &rs)
        })
        .collect()
}

/// Run-by-run comparison of two scenarios of a batch (common random
/// numbers: run k of both met the same draws).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
pub struct Paired {
    /// Run indices found in both.
    pub runs: usize,
    /// Runs that succeeded in the second scenario and failed in the first.
    pub wins: usize,
    /// Runs that failed in the second and succeeded in the first.
    pub losses: usize,
    /// Runs whose records are identical in both.
    pub identical: usize,
}

/// Compares scenario `b` with scenario `a` run by run.
pub fn paired(runs: &Runs, a: &str, b: &str) -> Paired {
    let empty = Vec::new();
    let ra = runs.get(a).unwrap_or(&empty);
    let rb: BTreeMap<u32, &RunRecord> = runs
        .get(b)
        .unwrap_or(&empty)
        .iter()
        .map(|(k, r)| (*k, r))
        .collect();
    let mut p = Paired::default();
    for (run, x) in ra {
        let Some(y) = rb.get(run) else { continue };
        p.runs += 1;
        match (x.success, y.success) {
            (false, true) => p.wins += 1,
            (true, false) => p.losses += 1,
            _ => {}
        }
        if x == *y {
            p.identical += 1;
        }
    }
    p
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::record::group;

    fn record(success: bool, t: f64, deadlocks: f64) -> RunRecord {
        RunRecord {
            success,
            outcome: if success { "goal" } else { "time_limit" }.into(),
            time_s: t,
            path_length_m: 1.0,
            collisions: 0,
            min_clearance_m: 0.5,
            odometry_error_m: 0.0,
            goal_distance_m: 0.1,
            ticks: 10,
            behaviour_ticks: BTreeMap::new(),
            metrics: [("deadlocks".to_string(), deadlocks)].into(),
            events: Vec::new(),
            start: [0.0; 3],
            trap: None,
            state: None,
        }
    }

    #[test]
    fn paired_counts_wins_losses_and_identical_runs() {
        let rec = |scenario: &str, run: u32, success: bool, t: f64| {
            let mut v = serde_json::to_value(record(success, t, 0.0)).unwrap();
            v["scenario"] = scenario.into();
            v["key"] = format!("{scenario}#{run}").into();
            v["run"] = run.into();
            v
        };
        let records = vec![
            rec("a", 0, true, 10.0),
            rec("b", 0, true, 10.0),
            rec("a", 1, false, 120.0),
            rec("b", 1, true, 50.0),
            rec("a", 2, true, 20.0),
            rec("b", 2, false, 120.0),
            rec("a", 3, true, 20.0),
        ];
        let p = paired(&group(&records).unwrap(), "a", "b");
        assert_eq!(
            p,
            Paired {
                runs: 3,
                wins: 1,
                losses: 1,
                identical: 1
            }
        );
    }

    #[test]
    fn metrics_are_summarised_over_all_runs() {
        let rs = [
            record(true, 10.0, 1.0),
            record(false, 120.0, 3.0),
            record(true, 12.0, 2.0),
        ];
        let refs: Vec<&RunRecord> = rs.iter().collect();
        let s = Summary::of("x", &refs);
        assert_eq!(s.metric_mean("deadlocks"), 2.0);
        assert_eq!(s.metrics["deadlocks"].n, 3);
        assert!(s.metric_mean("warnings").is_nan());
        assert_eq!(s.time.mean, 11.0);
    }
}
