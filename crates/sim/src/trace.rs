//! The per-tick record of a run, for reports and the replay viewer.
//!
//! Off by default; when off nothing is recorded and nothing allocated per
//! tick (the controller gets disabled [`robot::Notes`] too). When on, each
//! tick appends one [`TraceTick`]: the true and estimated pose at the time
//! the sensors read, the controller's answer, the wheel speeds driven, the
//! contact flag, the controller's notes (behaviour, named values, events)
//! and, optionally, the full perception and the people's positions.
//!
//! Serialised with serde; [`Trace::write_json_lines`] writes one JSON object
//! per line. JSON has no infinities or NaN: `f64::INFINITY` (nothing in
//! range) and `NaN` (laser drop-out) both come out as `null`.

use std::io::Write;

use robot::{Command, Event, Perception, Pose, Request, Vec2};

/// What a trace records.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TraceParams {
    /// Record a trace at all. Default `false`.
    pub enabled: bool,
    /// Also record the full perception of every tick (large: a 181-beam
    /// scan is ~1.5 kB per tick). Default `false`.
    pub perception: bool,
    /// Also record every person's position each tick. Default `false`.
    pub people: bool,
}

impl TraceParams {
    /// Poses, commands and notes, without perceptions or people.
    pub fn poses() -> TraceParams {
        TraceParams {
            enabled: true,
            perception: false,
            people: false,
        }
    }

    /// Everything.
    pub fn full() -> TraceParams {
        TraceParams {
            enabled: true,
            perception: true,
            people: true,
        }
    }
}

/// The controller's answer at a tick, without its command.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum StepKind {
    /// `Step::Run`.
    Run,
    /// `Step::Done`.
    Done,
    /// `Step::GiveUp`.
    GiveUp,
}

/// One control tick.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct TraceTick {
    /// Tick number, from 0.
    pub tick: u64,
    /// Time the sensors read, seconds.
    pub time_s: f64,
    /// True pose when the sensors read.
    pub true_pose: Pose,
    /// Dead-reckoned pose given to the controller.
    pub estimated_pose: Pose,
    /// What the controller answered.
    pub step: StepKind,
    /// The command (none when the controller gave up).
    pub command: Option<Command>,
    /// Wheel rim speeds driven at the end of the tick (after the limits),
    /// m/s.
    pub wheels_mps: (f64, f64),
    /// The footprint touched an obstacle or a person during the tick.
    pub contact: bool,
    /// Behaviour or action in control (from the controller's notes).
    pub behaviour: Option<&'static str>,
    /// Named values (votes, weights, activations…) from the notes.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub values: Vec<(&'static str, f64)>,
    /// Events (warnings, dead-locks…) from the notes.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub events: Vec<Event>,
    /// Named sets of poses (a particle cloud) from the notes.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub clouds: Vec<(&'static str, Vec<Pose>)>,
    /// What the controller asked of the people around the robot.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub request: Option<Request>,
    /// The perception given to the controller, if recorded.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub perception: Option<Perception>,
    /// People's positions when the sensors read, if recorded.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub people: Vec<Vec2>,
}

/// The trace of a run.
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize)]
pub struct Trace {
    /// The run's seed.
    pub seed: u64,
    /// One entry per tick.
    pub ticks: Vec<TraceTick>,
}

impl Trace {
    /// Writes one JSON object per tick, one per line.
    pub fn write_json_lines(&self, mut out: impl Write) -> std::io::Result<()> {
        for t in &self.ticks {
            serde_json::to_writer(&mut out, t)?;
            out.write_all(b"\n")?;
        }
        Ok(())
    }
}
