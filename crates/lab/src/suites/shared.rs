//! What the suites that run activity-trace controllers share (voting,
//! dead-lock, scenario files): the dead-lock metric, its table column, and
//! how characteristic events and dead-locks are drawn.

use anyhow::Result;
use sim::render::MarkerKind;

use crate::experiment::RunOutput;
use crate::pictures::{EventMarker, MarkerPlace};
use crate::record::RunRecord;
use crate::scenario_suite::RUNS_PER_PICTURE;
use crate::tables::MetricColumn;

/// The metric: dead-locks detected in the run (`deadlock` events of
/// `activity` and `voting::trace_layer`).
pub const DEADLOCKS: &str = "deadlocks";

/// The dead-lock column of the generic table: mean per run.
pub const DEADLOCK_COLUMN: MetricColumn = MetricColumn {
    metric: DEADLOCKS,
    heading: "dead-locks/run",
    short: "deadlocks",
    decimals: 2,
};

/// Counts the run's dead-lock events into the [`DEADLOCKS`] metric.
pub fn deadlock_metric(out: &RunOutput, record: &mut RunRecord) -> Result<()> {
    let n = out.events.iter().filter(|e| e.kind == "deadlock").count();
    record.set_metric(DEADLOCKS, n as f64)
}

/// Colour of `CP2` markers (goal tracking takes control).
pub const CP2_RGB: [u8; 3] = [255, 127, 14];
/// Colour of `CP3` markers (blocked with the goal ahead).
pub const CP3_RGB: [u8; 3] = [148, 103, 189];
/// Colour of detected dead-locks.
pub const DEADLOCK_RGB: [u8; 3] = [227, 0, 140];

/// The activity trace on pictures: on a single run, a small square where
/// each `CP2` (orange) and `CP3` (purple) happened; on every picture, a
/// magenta ring at each detected dead-lock (the centroid of its
/// `CP2, CP3, CP2` chunk, in the controller's odometry frame). The rarer
/// the event, the later it is drawn.
pub const ACTIVITY_MARKERS: [EventMarker; 3] = [
    EventMarker {
        kind: "CP2",
        marker: MarkerKind::Square(CP2_RGB),
        place: MarkerPlace::Robot,
        single_run_only: true,
    },
    EventMarker {
        kind: "CP3",
        marker: MarkerKind::Square(CP3_RGB),
        place: MarkerPlace::Robot,
        single_run_only: true,
    },
    EventMarker {
        kind: "deadlock",
        marker: MarkerKind::Ring(DEADLOCK_RGB),
        place: MarkerPlace::Event,
        single_run_only: false,
    },
];

/// What the trajectory pictures of these suites show.
pub fn pictures_caption() -> String {
    format!(
        "The first {RUNS_PER_PICTURE} runs of each scenario, re-simulated from their seeds, coloured by the action or behaviour in control (legend in each picture); start green, goal red, detected dead-locks as magenta rings at the centroid of their `CP2, CP3, CP2` chunk. `petrinav lab replay` draws a single run with its whole activity trace: `CP2` orange squares, `CP3` purple. A picture opens the run viewer, which holds the runs it draws; `#0`, `#1` … under it open each run."
    )
}
