//! The voting suite's charts, as the source shows its results: `I_R` per
//! field for the experiments side by side (grouped bars, whiskers the 95 %
//! Wilson interval), and `I_T` per field likewise (whiskers the Student-t
//! interval of the mean over the successful runs). The SVG goes inline into
//! `index.html`; its `<desc>` lists every bar's numbers, one line each, so
//! that the chart can be checked against `summary.json`.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use anyhow::Result;

use crate::charts::{self, Bar};
use crate::summary::Summary;

/// What one chart draws: groups (fields) × series (experiments).
#[derive(Debug, Clone, PartialEq)]
pub struct ChartData {
    /// Field names, in the suite's order (`field01` …).
    pub fields: Vec<String>,
    /// Experiment names (`e1` …).
    pub experiments: Vec<String>,
    /// `bars[f][e]`: the bar of experiment `e` on field `f` (NaN value: no
    /// bar — no runs, or no successful run for `I_T`).
    pub bars: Vec<Vec<Bar>>,
}

/// Which index a chart shows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Index {
    /// Reliability `I_R`.
    Reliability,
    /// Time to goal `I_T`, seconds.
    Time,
}

impl Index {
    /// The index's name in the chart's data lines.
    pub fn name(self) -> &'static str {
        match self {
            Index::Reliability => "I_R",
            Index::Time => "I_T",
        }
    }

    /// The bar of one summary.
    pub fn bar(self, s: &Summary) -> Bar {
        match self {
            Index::Reliability if s.runs == 0 => Bar {
                value: f64::NAN,
                low: f64::NAN,
                high: f64::NAN,
            },
            Index::Reliability => Bar {
                value: s.reliability.value,
                low: s.reliability.low,
                high: s.reliability.high,
            },
            Index::Time if s.time.n == 0 => Bar {
                value: f64::NAN,
                low: f64::NAN,
                high: f64::NAN,
            },
            Index::Time => Bar {
                value: s.time.mean,
                low: s.time.mean - s.time.half_width,
                high: s.time.mean + s.time.half_width,
            },
        }
    }
}

/// The bars of `index` from the summaries (scenarios named `eK/fieldNN`).
pub fn data(summaries: &[Summary], index: Index) -> ChartData {
    let mut fields: Vec<String> = Vec::new();
    let mut experiments: Vec<String> = Vec::new();
    let mut by: BTreeMap<(&str, &str), &Summary> = BTreeMap::new();
    for s in summaries {
        if let Some((e, f)) = s.scenario.split_once('/') {
            if !fields.iter().any(|x| x == f) {
                fields.push(f.to_string());
            }
            if !experiments.iter().any(|x| x == e) {
                experiments.push(e.to_string());
            }
            by.insert((e, f), s);
        }
    }
    let none = Bar {
        value: f64::NAN,
        low: f64::NAN,
        high: f64::NAN,
    };
    let bars = fields
        .iter()
        .map(|f| {
            experiments
                .iter()
                .map(|e| by.get(&(e.as_str(), f.as_str())).map_or(none, |s| index.bar(s)))
                .collect()
        })
        .collect();
    ChartData {
        fields,
        experiments,
        bars,
    }
}

/// One data line per bar: `eK fieldNN I_R value low high` (NaN for none),
/// three decimals.
pub fn data_lines(d: &ChartData, index: Index) -> String {
    let mut out = String::new();
    for (f, row) in d.fields.iter().zip(&d.bars) {
        for (e, b) in d.experiments.iter().zip(row) {
            let _ = writeln!(
                out,
                "{e} {f} {} {:.3} {:.3} {:.3}",
                index.name(),
                b.value,
                b.low,
                b.high
            );
        }
    }
    out
}

/// The chart of `index` as SVG (scalable: it has a `viewBox`), with the
/// data lines in its `<desc>`.
pub fn svg(summaries: &[Summary], index: Index, label: impl Fn(&str) -> String) -> Result<String> {
    let d = data(summaries, index);
    let groups: Vec<String> = d
        .fields
        .iter()
        .map(|f| f.trim_start_matches("field").trim_start_matches('0').to_string())
        .collect();
    let series: Vec<String> = d
        .experiments
        .iter()
        .map(|e| format!("{e} {}", label(e)))
        .collect();
    let (title, y, y_max) = match index {
        Index::Reliability => (
            "I_R per field (whiskers: 95 % interval)",
            "I_R = successes / runs",
            Some(1.0),
        ),
        Index::Time => {
            // The axis follows the bars; a whisker of a field with one or
            // two successes can be many times longer and is cut at the top.
            let tallest = d
                .bars
                .iter()
                .flatten()
                .map(|b| b.value)
                .filter(|v| v.is_finite())
                .fold(0.0, f64::max);
            (
                "I_T per field, successful runs only (whiskers: 95 % interval, cut at the top)",
                "I_T (s)",
                (tallest > 0.0).then_some(tallest * 1.15),
            )
        }
    };
    let size = (1100, 400);
    let opts = charts::BarOptions {
        y_max,
        legend_px: Some(240),
    };
    let svg = charts::bars_with(title, y, &groups, &series, &d.bars, size, opts)?;
    Ok(charts::scalable(&svg, size, &data_lines(&d, index)))
}
