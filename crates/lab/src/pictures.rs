//! Pictures of runs: trajectories over the world, coloured by the behaviour
//! in control, with the events a suite chooses drawn as markers.
//!
//! Runs are re-simulated from their seeds with tracing on ([`Replay`]), so a
//! picture draws exactly the runs that were counted.

use std::path::Path;

use anyhow::{Context, Result};
use robot::{Pose, Vec2};
use sim::render::{MarkerKind, Picture};
use sim::{Cell, CellIndex, OccupancyGrid, Trace};

use crate::record::RunRecord;

/// A run re-simulated with its trace, and what is needed to draw it.
#[derive(Debug, Clone)]
pub struct Replay {
    /// The run's record (identical to its results line's fields).
    pub record: RunRecord,
    /// The per-tick trace.
    pub trace: Trace,
    /// The run's own world grid (with its per-run variation).
    pub grid: OccupancyGrid,
    /// The goal, if the run had one.
    pub goal: Option<Vec2>,
    /// The robot's footprint radius, metres.
    pub robot_radius_m: f64,
    /// The control period, seconds.
    pub control_period_s: f64,
    /// A net to draw beside the run, its marking from the run's values
    /// (the tour-guide supervisor's), if any.
    pub net: Option<crate::net_view::NetView>,
}

/// Where an event's marker goes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MarkerPlace {
    /// At the robot's true position at the tick of the event.
    Robot,
    /// At the event's own position (in the controller's frame), when it
    /// has one.
    Event,
}

/// How one kind of event is drawn.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EventMarker {
    /// The event kind ([`robot::Event::kind`]).
    pub kind: &'static str,
    /// The marker.
    pub marker: MarkerKind,
    /// Where.
    pub place: MarkerPlace,
    /// Only on the picture of a single run (not on overlays of many).
    pub single_run_only: bool,
}

/// Draws a run's trajectory coloured by the behaviour in control, its start,
/// and its events as `markers` say (in the order of `markers`: later kinds
/// are drawn on top). Returns the true poses.
fn draw_run(pic: &mut Picture<'_>, replay: &Replay, markers: &[EventMarker], single: bool) -> Vec<Pose> {
    let trace = &replay.trace;
    let poses: Vec<Pose> = trace.ticks.iter().map(|t| t.true_pose).collect();
    let labels: Vec<&str> = trace
        .ticks
        .iter()
        .map(|t| t.behaviour.unwrap_or("none"))
        .collect();
    pic.trajectory(&poses, Some(&labels));
    let start = replay.record.start;
    pic.marker(Vec2::new(start[0], start[1]), MarkerKind::Start);
    for m in markers.iter().filter(|m| single || !m.single_run_only) {
        for t in &trace.ticks {
            for e in t.events.iter().filter(|e| e.kind == m.kind) {
                let at = match m.place {
                    MarkerPlace::Robot => Some(t.true_pose.position()),
                    MarkerPlace::Event => e.position,
                };
                if let Some(at) = at {
                    pic.marker(at, m.marker);
                }
            }
        }
    }
    poses
}

/// Cells blocked in every grid stay occupied; cells blocked in some only
/// become unknown (grey). Grids of another size than the first are left out.
fn composite_grid(grids: &[&OccupancyGrid]) -> Option<OccupancyGrid> {
    let base = grids.first()?;
    let runs: Vec<&&OccupancyGrid> = grids
        .iter()
        .filter(|g| g.width() == base.width() && g.height() == base.height())
        .collect();
    let mut out = (*base).clone();
    for j in 0..base.height() as i64 {
        for i in 0..base.width() as i64 {
            let c = CellIndex { i, j };
            let hits = runs.iter().filter(|g| g.get(c) == Cell::Occupied).count();
            let v = if hits == runs.len() {
                Cell::Occupied
            } else if hits > 0 {
                Cell::Unknown
            } else {
                Cell::Free
            };
            out.set(c, v);
        }
    }
    Some(out)
}

/// Draws several runs of one scenario over each other: obstacles black
/// where they stand in every run and grey where the per-run variation put
/// them in some runs only; a run that ended in a collision ends with a
/// small square; events as `markers` say (their `single_run_only` kinds
/// left out). PNG or SVG by extension.
pub fn overlay_picture(replays: &[Replay], markers: &[EventMarker], path: &Path) -> Result<()> {
    let grids: Vec<&OccupancyGrid> = replays.iter().map(|r| &r.grid).collect();
    let grid = composite_grid(&grids).context("no run to draw")?;
    let mut pic = Picture::new(&grid);
    if let Some(goal) = replays[0].goal {
        pic.marker(goal, MarkerKind::Goal);
    }
    for r in replays {
        let poses = draw_run(&mut pic, r, markers, false);
        if r.record.outcome == "collision"
            && let Some(last) = poses.last()
        {
            pic.marker(last.position(), MarkerKind::Point);
        }
    }
    pic.save(path)
        .with_context(|| format!("writing {}", path.display()))?;
    Ok(())
}

/// The picture of one run in its own world: trajectory coloured by the
/// behaviour in control, the footprint every 2 s and at the end, and its
/// events as `markers` say. PNG or SVG by extension.
pub fn run_picture(replay: &Replay, markers: &[EventMarker], path: &Path) -> Result<()> {
    let mut pic = Picture::new(&replay.grid);
    if let Some(goal) = replay.goal {
        pic.marker(goal, MarkerKind::Goal);
    }
    let every = (2.0 / replay.control_period_s).round().max(1.0) as usize;
    let ticks = &replay.trace.ticks;
    for (k, t) in ticks.iter().enumerate() {
        if k % every == 0 || k + 1 == ticks.len() {
            pic.robot(t.true_pose, replay.robot_radius_m);
        }
    }
    draw_run(&mut pic, replay, markers, true);
    pic.save(path)
        .with_context(|| format!("writing {}", path.display()))?;
    Ok(())
}
