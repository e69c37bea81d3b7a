//! Scenario files (TOML): the world, the robot, the controller, the task,
//! and how runs vary. Everything has a sensible default, so a scenario can be
//! a few lines:
//!
//! ```toml
//! name = "corridor"
//! [world]                 # a world of shapes (see sim::shapes), or:
//! width_m = 6.0           # map = "maps/building.yaml" (map_server, relative to this file)
//! height_m = 2.0
//! walls = true
//! [start]
//! x = 0.5
//! y = 1.0
//! [goal]
//! x = 5.5
//! y = 1.0
//! ```
//!
//! | key | meaning | default |
//! |---|---|---|
//! | `name`, `description` | identification | the file stem, empty |
//! | `runs`, `seed` | runs of a batch and base seed | 50, 1 |
//! | `time_limit_s` | simulated time before a timeout | 120 |
//! | `control_period_s` | control period | 0.1 |
//! | `goal_tolerance_m` | goal reached within | 0.3 |
//! | `collision_fatal` | a collision ends the run (a failure) | true |
//! | `[world]` or `map` | shapes, or a map_server YAML | required |
//! | `[robot] preset` | `aibot` (7 IR, 3 sonar), `jinny` (laser) or `ring` (16 sonars all round) | `aibot` |
//! | `[robot.odometry]` | odometry error model in place of the preset's ([`sim::sensors::OdometryParams`]) | the preset's |
//! | `[robot.ir]` | infrared detectors in place of the preset's ([`sim::sensors::IrParams`]) | the preset's |
//! | `[robot.sonar]` | sonar array in place of the preset's ([`sim::sensors::SonarParams`]) | the preset's |
//! | `[start] x, y, theta_deg, jitter_m, jitter_deg` | start pose and its per-run spread (uniform in a disc / an interval) | θ 0, no spread |
//! | `[goal] x, y` | goal | required |
//! | `[jitter] obstacles_m` | each shape moved by up to this per run (uniform in a disc) | 0 |
//! | `[people] count, density` | people walking about (count, or per 100 m² of free space) | none |
//! | `[trap]` | a dead-end trap drawn per run on the course ([`crate::traps::TrapSpec`]) | none |
//! | `[controller] kind` | `voting` or `priority` | `voting` |
//! | `[controller.voting]` | [`voting::VotingParams`] | defaults |
//! | `[controller.priority]` | [`activity::PriorityParams`] | defaults |
//! | `[controller.trace_layer]` | activity-trace layer on the voting controller | off |
//!
//! Unknown keys are errors naming the key and its line.

use std::path::{Path, PathBuf};

use activity::PriorityParams;
use anyhow::{Context, Result, bail};
use sim::shapes::WorldSpec;
use voting::VotingParams;

/// Where the robot starts, and how much that varies between runs.
#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StartSpec {
    /// x, metres.
    pub x: f64,
    /// y, metres.
    pub y: f64,
    /// Heading, degrees counter-clockwise from +x. Default 0.
    #[serde(default)]
    pub theta_deg: f64,
    /// Position spread: uniform in a disc of this radius, metres. Default 0.
    #[serde(default)]
    pub jitter_m: f64,
    /// Heading spread: uniform in ± this, degrees. Default 0.
    #[serde(default)]
    pub jitter_deg: f64,
}

/// The goal.
#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GoalSpec {
    /// x, metres.
    pub x: f64,
    /// y, metres.
    pub y: f64,
}

/// Per-run variation of the world.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JitterSpec {
    /// Each shape is moved by up to this much (uniform in a disc), metres.
    #[serde(default)]
    pub obstacles_m: f64,
}

/// People walking about.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PeopleSpec {
    /// How many.
    #[serde(default)]
    pub count: Option<usize>,
    /// Or how dense: people per 100 m² of free space.
    #[serde(default)]
    pub density: Option<f64>,
}

/// Robot presets.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Preset {
    /// The AIBOT-like robot of the voting experiments.
    #[default]
    Aibot,
    /// The Jinny-like tour-guide robot with a laser.
    Jinny,
    /// An AIBOT-sized base with a ring of 16 sonars (the dead-lock suite's
    /// robot, [`sim::RobotParams::sonar_ring`]).
    Ring,
}

impl Preset {
    /// The simulated robot of this preset.
    pub fn robot_params(self) -> sim::RobotParams {
        match self {
            Preset::Aibot => sim::RobotParams::aibot(),
            Preset::Jinny => sim::RobotParams::jinny(),
            Preset::Ring => sim::RobotParams::sonar_ring(),
        }
    }
}

/// The robot.
#[derive(Debug, Clone, PartialEq, Default, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RobotSpec {
    /// Which robot. Default `aibot`.
    #[serde(default)]
    pub preset: Preset,
    /// The odometry error model, in place of the preset's
    /// ([`sim::sensors::OdometryParams`]; keys left out keep their defaults).
    #[serde(default)]
    pub odometry: Option<sim::sensors::OdometryParams>,
    /// The infrared detectors, in place of the preset's
    /// ([`sim::sensors::IrParams`]; keys left out keep their defaults).
    #[serde(default)]
    pub ir: Option<sim::sensors::IrParams>,
    /// The sonar array, in place of the preset's
    /// ([`sim::sensors::SonarParams`]; keys left out keep their defaults).
    #[serde(default)]
    pub sonar: Option<sim::sensors::SonarParams>,
}

impl RobotSpec {
    /// The simulated robot: the preset, with the odometry model replaced
    /// when the scenario gives one.
    pub fn robot_params(&self) -> sim::RobotParams {
        let mut r = self.preset.robot_params();
        if let Some(o) = self.odometry {
            r.odometry = o;
        }
        if let Some(ir) = &self.ir {
            r.ir = ir.clone();
        }
        if let Some(sonar) = &self.sonar {
            r.sonar = sonar.clone();
        }
        r
    }
}

/// Which controller drives the robot.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum ControllerKind {
    /// Dynamic weighted voting.
    #[default]
    Voting,
    /// Priority arbitration with the activity trace.
    Priority,
}

/// The activity-trace layer on the voting controller.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TraceLayerSpec {
    /// Detect dead-locks from the voting outcome and recover.
    #[serde(default)]
    pub enabled: bool,
}

/// The controller and its parameters.
#[derive(Debug, Clone, PartialEq, Default, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ControllerSpec {
    /// Which controller. Default `voting`.
    #[serde(default)]
    pub kind: ControllerKind,
    /// Parameters of the voting controller.
    #[serde(default)]
    pub voting: VotingParams,
    /// Parameters of the priority controller.
    #[serde(default)]
    pub priority: PriorityParams,
    /// The activity-trace layer on the voting controller.
    #[serde(default)]
    pub trace_layer: TraceLayerSpec,
}

/// Most runs of a scenario in a batch: a million runs of every scenario
/// is far beyond any experiment here (the suites run 10–200), and keeps
/// the batch's job list (one entry per run, made before the first run)
/// small; `runs = 4000000000` would ask for some 200 GB of it.
pub const MAX_RUNS: u32 = 1_000_000;

fn default_runs() -> u32 {
    50
}
fn default_seed() -> u64 {
    1
}
fn default_time_limit() -> f64 {
    120.0
}
fn default_period() -> f64 {
    0.1
}
fn default_tolerance() -> f64 {
    0.3
}
fn default_true() -> bool {
    true
}

/// A scenario.
#[derive(Debug, Clone, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scenario {
    /// Name (unique within a suite). Default: the file stem.
    #[serde(default)]
    pub name: String,
    /// What it is about.
    #[serde(default)]
    pub description: String,
    /// Runs of a batch, 1 to [`MAX_RUNS`]. Default 50.
    #[serde(default = "default_runs")]
    pub runs: u32,
    /// Base seed. Default 1.
    #[serde(default = "default_seed")]
    pub seed: u64,
    /// Simulated seconds before a timeout. Default 120.
    #[serde(default = "default_time_limit")]
    pub time_limit_s: f64,
    /// Control period, seconds. Default 0.1.
    #[serde(default = "default_period")]
    pub control_period_s: f64,
    /// Goal reached within this distance, metres. Default 0.3.
    #[serde(default = "default_tolerance")]
    pub goal_tolerance_m: f64,
    /// A collision ends the run as a failure. Default true.
    #[serde(default = "default_true")]
    pub collision_fatal: bool,
    /// A world of shapes.
    #[serde(default)]
    pub world: Option<WorldSpec>,
    /// Or a map_server YAML map (relative to the scenario file).
    #[serde(default)]
    pub map: Option<PathBuf>,
    /// The robot.
    #[serde(default)]
    pub robot: RobotSpec,
    /// The start pose.
    pub start: StartSpec,
    /// The goal.
    pub goal: GoalSpec,
    /// Per-run variation of the world.
    #[serde(default)]
    pub jitter: JitterSpec,
    /// People.
    #[serde(default)]
    pub people: PeopleSpec,
    /// A dead-end trap drawn per run on the course (shape worlds only).
    #[serde(default)]
    pub trap: Option<crate::traps::TrapSpec>,
    /// The controller.
    #[serde(default)]
    pub controller: ControllerSpec,
}

impl Scenario {
    /// Parses a scenario; `source` names it in errors, `dir` resolves `map`.
    pub fn parse(text: &str, source: &str, dir: Option<&Path>) -> Result<Scenario> {
        let mut s: Scenario = toml::from_str(text).map_err(|e| anyhow::anyhow!("{source}: {e}"))?;
        if s.name.is_empty() {
            s.name = Path::new(source)
                .file_stem()
                .and_then(|n| n.to_str())
                .unwrap_or("scenario")
                .to_string();
        }
        if let (Some(map), Some(dir)) = (&s.map, dir) {
            if map.is_relative() {
                s.map = Some(dir.join(map));
            }
        }
        s.validate().with_context(|| source.to_string())?;
        Ok(s)
    }

    /// Reads a scenario file.
    pub fn load(path: &Path) -> Result<Scenario> {
        let text = std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
        Scenario::parse(&text, &path.display().to_string(), path.parent())
    }

    /// Checks what the types cannot.
    pub fn validate(&self) -> Result<()> {
        match (&self.world, &self.map) {
            (None, None) => bail!("the scenario needs a [world] table or a `map` file"),
            (Some(_), Some(_)) => bail!("give either a [world] table or a `map` file, not both"),
            _ => {}
        }
        if let Some(w) = &self.world {
            w.validate()?;
        }
        if let Some(t) = &self.trap {
            if self.world.is_none() {
                bail!("[trap] needs a [world] of shapes");
            }
            t.validate().map_err(anyhow::Error::msg)?;
        }
        if let Some(ir) = &self.robot.ir {
            ir.validate().context("[robot.ir]")?;
        }
        if let Some(sonar) = &self.robot.sonar {
            sonar.validate().context("[robot.sonar]")?;
        }
        if let Some(o) = &self.robot.odometry {
            o.validate().context("[robot.odometry]")?;
        }
        if !(1..=MAX_RUNS).contains(&self.runs) {
            bail!("`runs` must be from 1 to {MAX_RUNS}, got {}", self.runs);
        }
        let positive = [
            ("time_limit_s", self.time_limit_s),
            ("control_period_s", self.control_period_s),
            ("goal_tolerance_m", self.goal_tolerance_m),
        ];
        for (what, v) in positive {
            if !(v.is_finite() && v > 0.0) {
                bail!("`{what}` must be a finite number > 0, got {v}");
            }
        }
        let non_negative = [
            ("start.jitter_m", self.start.jitter_m),
            ("start.jitter_deg", self.start.jitter_deg),
            ("jitter.obstacles_m", self.jitter.obstacles_m),
        ];
        for (what, v) in non_negative {
            if !(v.is_finite() && v >= 0.0) {
                bail!("`{what}` must be a finite number ≥ 0, got {v}");
            }
        }
        for (what, v) in [
            ("start.x", self.start.x),
            ("start.y", self.start.y),
            ("start.theta_deg", self.start.theta_deg),
            ("goal.x", self.goal.x),
            ("goal.y", self.goal.y),
        ] {
            if !v.is_finite() {
                bail!("`{what}` must be a finite number, got {v}");
            }
        }
        if let (Some(_), Some(_)) = (self.people.count, self.people.density) {
            bail!("[people]: give `count` or `density`, not both");
        }
        if let Some(d) = self.people.density {
            if !(d.is_finite() && d >= 0.0) {
                bail!("`people.density` must be ≥ 0, got {d}");
            }
        }
        self.controller
            .voting
            .validate()
            .map_err(|e| anyhow::anyhow!("[controller.voting]: {e}"))?;
        self.controller
            .priority
            .validate()
            .map_err(|e| anyhow::anyhow!("[controller.priority]: {e}"))?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SMALL: &str = "
[world]
width_m = 6.0
height_m = 2.0
walls = true
[start]
x = 0.5
y = 1.0
[goal]
x = 5.5
y = 1.0
";

    #[test]
    fn a_few_lines_are_enough() {
        let s = Scenario::parse(SMALL, "corridor.toml", None).unwrap();
        assert_eq!(s.name, "corridor");
        assert_eq!(s.runs, 50);
        assert_eq!(s.robot.preset, Preset::Aibot);
        assert_eq!(s.controller.kind, ControllerKind::Voting);
        assert!(s.collision_fatal);
    }

    #[test]
    fn a_typo_names_the_key_and_the_line() {
        let text = SMALL.replace("[goal]\n", "[goal]\nzz = 3\n");
        let err = format!("{:#}", Scenario::parse(&text, "bad.toml", None).unwrap_err());
        assert!(err.contains("zz") && err.contains("line 10"), "{err}");
        let text = SMALL.replace("walls = true", "walls = true\n[world.rect]\nx = 1");
        let err = format!("{:#}", Scenario::parse(&text, "bad.toml", None).unwrap_err());
        assert!(err.contains("bad.toml"), "{err}");
        let text = SMALL.replace("[controller]", "").to_string() + "[controller.voting]\nbeta_rad = -1\n";
        let err = format!("{:#}", Scenario::parse(&text, "bad.toml", None).unwrap_err());
        assert!(err.contains("beta_rad"), "{err}");
    }

    #[test]
    fn missing_world_and_bad_numbers_are_errors() {
        let text = "[start]\nx = 0\ny = 0\n[goal]\nx = 1\ny = 1\n";
        assert!(Scenario::parse(text, "s.toml", None).is_err());
        let text = SMALL.to_string() + "runs = 0\n";
        // `runs` after a table belongs to the table: a clear error too.
        assert!(Scenario::parse(&text, "s.toml", None).is_err());
        let text = "runs = 0\n".to_string() + SMALL;
        let err = format!("{:#}", Scenario::parse(&text, "s.toml", None).unwrap_err());
        assert!(err.contains("runs"), "{err}");
        // Issue 17: sizes are checked before anything is allocated.
        let text = "runs = 4000000000\n".to_string() + SMALL;
        let err = format!("{:#}", Scenario::parse(&text, "s.toml", None).unwrap_err());
        assert!(err.contains("from 1 to 1000000"), "{err}");
    }

    #[test]
    fn ir_and_sonar_overrides_are_read_and_checked() {
        let text =
            SMALL.to_string() + "[robot]\nir = { beam_rad = 0.0 }\nsonar = { dropout_probability = 0.1 }\n";
        let r = Scenario::parse(&text, "s.toml", None)
            .unwrap()
            .robot
            .robot_params();
        assert_eq!(r.ir.beam_rad, 0.0);
        assert_eq!(r.sonar.dropout_probability, 0.1);
        // Keys left out keep the defaults (the AIBOT's seven detectors).
        assert_eq!(r.ir.mounts.len(), 7);
        assert_eq!(r.sonar.mounts.len(), 3);
        let text = SMALL.to_string() + "[robot]\nir = { beam_rad = 2.0 }\n";
        let err = format!("{:#}", Scenario::parse(&text, "s.toml", None).unwrap_err());
        assert!(err.contains("beam_rad"), "{err}");
        let text = SMALL.to_string() + "[robot]\nsonar = { cone = 0.1 }\n";
        let err = format!("{:#}", Scenario::parse(&text, "s.toml", None).unwrap_err());
        assert!(err.contains("cone"), "{err}");
    }

    #[test]
    fn robot_preset_and_odometry_model_are_read_and_checked() {
        let text =
            SMALL.to_string() + "[robot]\npreset = \"ring\"\nodometry = { large_slip_probability = 0.0 }\n";
        let s = Scenario::parse(&text, "s.toml", None).unwrap();
        let r = s.robot.robot_params();
        assert_eq!(r.sonar.mounts.len(), sim::robot_params::SONAR_RING_COUNT);
        assert_eq!(r.odometry.large_slip_probability, 0.0);
        // Keys left out keep the model's defaults.
        assert_eq!(r.odometry.slip_sigma, sim::OdometryParams::default().slip_sigma);
        let text = SMALL.to_string() + "[robot]\nodometry = { large_slip_probability = 2.0 }\n";
        let err = format!("{:#}", Scenario::parse(&text, "s.toml", None).unwrap_err());
        assert!(err.contains("large_slip_probability"), "{err}");
        let text = SMALL.to_string() + "[controller.priority]\nprogress_m = inf\n";
        let s = Scenario::parse(&text, "s.toml", None).unwrap();
        assert_eq!(s.controller.priority.progress_m, f64::INFINITY);
        let text = SMALL.to_string() + "[controller.priority]\nprogress_m = -1.0\n";
        let err = format!("{:#}", Scenario::parse(&text, "s.toml", None).unwrap_err());
        assert!(err.contains("progress_m"), "{err}");
        let text = SMALL.to_string() + "[robot]\nodometry = { slip = 0.1 }\n";
        let err = format!("{:#}", Scenario::parse(&text, "s.toml", None).unwrap_err());
        assert!(err.contains("slip"), "{err}");
    }
}
