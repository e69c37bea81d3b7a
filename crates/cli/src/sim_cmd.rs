//! `petrinav sim …`: drive a simulated robot.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::{Args, Subcommand, ValueEnum};
use robot::{Command, Pose, Vec2};
use serde_json::json;
use sim::render::{MarkerKind, Picture};
use sim::{
    CrowdParams, CrowdSize, RobotParams, RunParams, ScriptedController, Simulation, Task, TraceParams, World,
};

use crate::output::{fields, num};
use crate::{out, outln};

#[derive(Subcommand, Debug)]
pub enum SimCommand {
    /// Drives a robot through a world with a scripted command sequence and
    /// draws the result.
    ///
    /// Segments are `v,omega,seconds` (m/s, rad/s counter-clockwise, s),
    /// separated by `;`. Example: petrinav sim drive world.toml --start 1,1,0
    /// --commands '0.3,0,5; 0,0.8,2; 0.3,0,4' -o run.png
    Drive(DriveArgs),
}

#[derive(ValueEnum, Clone, Copy, Debug)]
enum Preset {
    /// 7 IR, 3 sonar, odometry; radius 0.15 m.
    Aibot,
    /// 181-beam laser, odometry; radius 0.35 m.
    Jinny,
    /// 16 sonars all round, odometry; radius 0.15 m.
    Ring,
}

#[derive(Args, Debug)]
pub struct DriveArgs {
    /// The world: a map_server .yaml map or a .toml world of shapes.
    world: PathBuf,
    /// Start pose `x,y,theta` (metres, metres, radians).
    #[arg(long, value_name = "X,Y,THETA", allow_hyphen_values = true)]
    start: String,
    /// Command segments `v,omega,seconds;…` (at most a day, 86,400 s, in all).
    #[arg(
        long,
        value_name = "SEGMENTS",
        allow_hyphen_values = true,
        conflicts_with = "script"
    )]
    commands: Option<String>,
    /// A file of segments, one `v,omega,seconds` per line (`#` comments).
    #[arg(long, value_name = "FILE")]
    script: Option<PathBuf>,
    /// A goal `x,y`: the run ends when the robot gets within 0.3 m.
    #[arg(long, value_name = "X,Y", allow_hyphen_values = true)]
    goal: Option<String>,
    /// The robot.
    #[arg(long, value_enum, default_value_t = Preset::Aibot)]
    robot: Preset,
    /// People walking about.
    #[arg(long, default_value_t = 0)]
    people: usize,
    /// Seed of the run (noise, people).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Keep going after a collision (the robot stalls) instead of ending.
    #[arg(long)]
    survive_collisions: bool,
    /// Picture of the run (.png or .svg).
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Per-tick trace (JSON lines), perceptions included.
    #[arg(long, value_name = "FILE")]
    trace: Option<PathBuf>,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
}

pub fn run(cmd: SimCommand) -> Result<()> {
    match cmd {
        SimCommand::Drive(a) => drive(&a),
    }
}

pub(crate) fn numbers(text: &str, n: usize, what: &str) -> Result<Vec<f64>> {
    let v: Vec<f64> = text
        .split(',')
        .map(|s| s.trim().parse::<f64>())
        .collect::<std::result::Result<_, _>>()
        .with_context(|| format!("{what} `{text}`: expected {n} comma-separated numbers"))?;
    if v.len() != n || v.iter().any(|x| !x.is_finite()) {
        bail!("{what} `{text}`: expected {n} comma-separated finite numbers");
    }
    Ok(v)
}

fn segments(text: &str, source: &str) -> Result<Vec<(Command, f64)>> {
    let mut out = Vec::new();
    for (i, seg) in text.split([';', '\n']).enumerate() {
        let seg = seg.split('#').next().unwrap_or("").trim();
        if seg.is_empty() {
            continue;
        }
        let v = numbers(seg, 3, &format!("{source}, segment {}", i + 1))?;
        out.push((
            Command::Twist {
                v_mps: v[0],
                omega_radps: v[1],
            },
            v[2],
        ));
    }
    if out.is_empty() {
        bail!("{source}: no command segments");
    }
    if let Some((i, _)) = out.iter().enumerate().find(|(_, (_, t))| *t < 0.0) {
        bail!("{source}, segment {}: a duration must be ≥ 0 s", i + 1);
    }
    // The drive is recorded step by step: a day, as for `nav` and the lab.
    let total: f64 = out.iter().map(|(_, t)| t).sum();
    if total > lab::tours::MAX_TIME_LIMIT_S {
        bail!(
            "{source}: the segments last {total} s in all, more than {} s (a day of driving, recorded step by step)",
            lab::tours::MAX_TIME_LIMIT_S
        );
    }
    Ok(out)
}

fn drive(a: &DriveArgs) -> Result<()> {
    let grid = crate::map::load_grid(&a.world)?;
    let s = numbers(&a.start, 3, "--start")?;
    let start = Pose::new(s[0], s[1], s[2]);
    let goal = a
        .goal
        .as_deref()
        .map(|g| numbers(g, 2, "--goal").map(|v| Vec2::new(v[0], v[1])))
        .transpose()?;
    let script = match (&a.commands, &a.script) {
        (Some(c), _) => segments(c, "--commands")?,
        (None, Some(path)) => {
            let text =
                std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
            segments(&text, &path.display().to_string())?
        }
        (None, None) => bail!("give the commands with --commands or --script"),
    };
    let mut world = World::new(grid);
    if a.people > 0 {
        world = world.with_crowd(CrowdParams {
            size: CrowdSize::Count { people: a.people },
            ..CrowdParams::default()
        })?;
    }
    let robot = match a.robot {
        Preset::Aibot => RobotParams::aibot(),
        Preset::Jinny => RobotParams::jinny(),
        Preset::Ring => RobotParams::sonar_ring(),
    };
    let radius = robot.drive.radius_m;
    let mut controller = ScriptedController::new(script)?;
    let run = RunParams {
        time_limit_s: controller.duration_s() + 0.05,
        collision_fatal: !a.survive_collisions,
        trace: TraceParams {
            enabled: true,
            perception: a.trace.is_some(),
            people: true,
        },
        ..RunParams::default()
    };
    let mut sim = Simulation::new(&world, robot, run, Task { start, goal }, a.seed)?;
    let result = sim.run(&mut controller);
    let trace = sim.take_trace().context("the run kept no trace")?;
    if let Some(path) = &a.trace {
        let f = std::fs::File::create(path).with_context(|| format!("writing {}", path.display()))?;
        trace
            .write_json_lines(std::io::BufWriter::new(f))
            .with_context(|| format!("writing {}", path.display()))?;
    }
    if let Some(path) = &a.output {
        picture(&world, &trace, start, goal, radius, &sim, path)?;
    }
    if a.json {
        outln!("{}", serde_json::to_string_pretty(&json!({ "result": result }))?)?;
        return Ok(());
    }
    let outcome = result.outcome.map_or("running".to_string(), |o| {
        serde_json::to_value(o)
            .ok()
            .and_then(|v| v.as_str().map(|s| s.replace('_', " ")))
            .unwrap_or_else(|| format!("{o:?}"))
    });
    let fp = result.final_pose;
    out!(
        "{}",
        fields(&[
            ("outcome", outcome),
            (
                "time",
                format!("{} s ({} ticks)", num(result.time_s), result.ticks)
            ),
            ("path length", format!("{} m", num(result.path_length_m))),
            ("collisions", result.collisions.to_string()),
            ("min clearance", format!("{} m", num(result.min_clearance_m))),
            (
                "final pose",
                format!("{}, {}, {} rad", num(fp.x_m), num(fp.y_m), num(fp.theta_rad))
            ),
            ("odometry error", format!("{} m", num(result.odometry_error_m))),
        ])
    )?;
    Ok(())
}

fn picture(
    world: &World,
    trace: &sim::Trace,
    start: Pose,
    goal: Option<Vec2>,
    radius: f64,
    sim: &Simulation,
    path: &Path,
) -> Result<()> {
    let poses: Vec<Pose> = trace.ticks.iter().map(|t| t.true_pose).collect();
    let names: Vec<String> = trace
        .ticks
        .iter()
        .map(|t| {
            t.values
                .iter()
                .find(|(k, _)| *k == "segment")
                .map_or("stopped".to_string(), |(_, v)| {
                    format!("segment {}", *v as usize + 1)
                })
        })
        .collect();
    let labels: Vec<&str> = names.iter().map(String::as_str).collect();
    let mut pic = Picture::new(world.grid());
    pic.trajectory(&poses, Some(&labels));
    pic.marker(start.position(), MarkerKind::Start);
    if let Some(g) = goal {
        pic.marker(g, MarkerKind::Goal);
    }
    pic.robot(start, radius);
    pic.robot(sim.pose(), radius);
    for p in sim.crowd().people() {
        pic.person(p.position, world.crowd().radius_m);
    }
    pic.save(path)
        .with_context(|| format!("writing {}", path.display()))?;
    Ok(())
}
