//! `petrinav nav …`: the tour-guide robot on a map, between named places.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::{Args, Subcommand, ValueEnum};
use lab::mission::{self, LegOutcome, LegRun, LegSpec, MissionSetup, PeoplePlan, Stop};
use nav::guide::{CreditPlan, Policy, SupervisorPlan};
use nav::supervisor::Behaviour;
use nav::supervisor::Supervisor;
use nav::supervisor::credit::CreditSupervisor;
use nav::supervisor::credit_learning::CreditModel;
use nav::supervisor::learning;
use nav::supervisor::log::MissionLog;
use robot::{Pose, Vec2};
use sim::{CrowdParams, OccupancyGrid, Places, World};

use crate::outln;
use crate::output::{Table, num};

#[derive(Subcommand, Debug)]
pub enum NavCommand {
    /// Drives the tour-guide robot (laser, Monte Carlo localization, AutoMove or contour
    /// tracking) from one place to another on a map.
    ///
    /// Places are NAMEs from the --goals file (YAML, `name: [x, y, theta]` per line, map
    /// frame) or poses `x,y,theta` (metres, radians). The robot knows its start; it never
    /// sees its true pose afterwards. Examples:
    ///
    ///   petrinav nav go maps/building_31/building_31.yaml --goals maps/building_31/places.yaml --from entrance --to hall_north -o run.png
    ///
    ///   petrinav nav go map.yaml --from 1,2,0 --to 8,3,0 --behaviour contour --people 20 --json
    Go(GoArgs),
    /// A guided tour: starts at the first place of the --goals file and visits every place
    /// in the file's order, one result per leg and a summary.
    ///
    ///   petrinav nav tour maps/levine/levine.yaml --goals maps/levine/places.yaml --people 20 -o tour.png
    Tour(TourArgs),
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
enum BehaviourArg {
    /// The map-based planner: global route, navigation function in a 10 m window.
    Automove,
    /// Wall following from the raw scan, leaving walls towards the goal.
    Contour,
    /// AutoMove until the localizer first warns, contour tracking from then on.
    AutomoveThenContour,
    /// Contour tracking while the localizer warns, AutoMove while it succeeds.
    Rule,
    /// The GSPN supervisor of --net with the rates learnt from --log (which needs
    /// calibration runs): the crediting net decides at the start, at every Warning and at
    /// every return to Success; the source's net as the source did.
    Supervisor,
}

#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
enum NetArg {
    /// models/supervisor_credit.toml: failures credited to each behaviour, per crowd context.
    Credit,
    /// models/supervisor.toml: the source's net.
    Source,
}

#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
enum WarningArg {
    /// Warning when the scan sees past the mapped walls: the robot is lost (default).
    Contradiction,
    /// The source's: Warning when the map explains less than 80 % of the scan (people
    /// hiding the walls raise it).
    Explained,
}

#[derive(Args, Debug)]
struct Common {
    /// The map: a ROS map_server .yaml (or a .toml world of shapes).
    map: PathBuf,
    /// Named places: YAML, one `name: [x, y, theta]` per line.
    #[arg(long, value_name = "PLACES.yaml")]
    goals: Option<PathBuf>,
    /// The navigation behaviour.
    #[arg(long, value_enum, default_value_t = BehaviourArg::Automove)]
    behaviour: BehaviourArg,
    /// People in the building: they gather around the places (or the start and goal)
    /// and walk between them.
    #[arg(long, default_value_t = 0)]
    people: usize,
    /// Seed of the run (sensor noise, odometry slips, people, the localizer).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Time limit per leg, seconds.
    #[arg(long, default_value_t = 300.0, allow_negative_numbers = true)]
    time_limit: f64,
    /// Picture of the run: the map, the trajectory coloured by behaviour and localizer
    /// state, the particle cloud at each warning (.png or .svg).
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Print JSON (one object per leg; stable keys).
    #[arg(long)]
    json: bool,
    /// The robot's mission log (JSON lines): the supervisor learns from it, and every leg is
    /// appended to it (a mission; a calibration run with --calibration).
    #[arg(long, value_name = "LOG")]
    log: Option<PathBuf>,
    /// Log the legs as calibration runs of the behaviour (automove or contour).
    #[arg(long, requires = "log")]
    calibration: bool,
    /// The supervisor net the log belongs to and `--behaviour supervisor` decides with.
    #[arg(long, value_enum, default_value_t = NetArg::Credit)]
    net: NetArg,
    /// What makes the localizer warn.
    #[arg(long, value_enum, default_value_t = WarningArg::Contradiction)]
    warning: WarningArg,
}

#[derive(Args, Debug)]
pub struct GoArgs {
    #[command(flatten)]
    common: Common,
    /// Where the robot starts: a place's NAME, or `x,y,theta`.
    #[arg(long, value_name = "NAME|X,Y,THETA", allow_hyphen_values = true)]
    from: String,
    /// Where it goes: a place's NAME, or `x,y,theta`.
    #[arg(long, value_name = "NAME|X,Y,THETA", allow_hyphen_values = true)]
    to: String,
    /// Per-tick trace as JSON lines: time, true pose, estimate, state, events,
    /// the command and the controller's notes (`notes`: MCL's scores and
    /// effective sample size, Warning, contour tracking's mode, distance,
    /// centred, gap).
    #[arg(long, value_name = "FILE")]
    trace: Option<PathBuf>,
    /// Watch the leg: one HTML file that opens offline in any browser, with the map, the
    /// trajectory so far, the laser beams, people, the particle cloud, a time slider and the
    /// controller's notes per tick (contour tracking's mode, distance, gap; the localizer's
    /// scores).
    #[arg(long, value_name = "FILE")]
    html: Option<PathBuf>,
}

#[derive(Args, Debug)]
pub struct TourArgs {
    #[command(flatten)]
    common: Common,
}

pub fn run(cmd: NavCommand) -> Result<()> {
    match cmd {
        NavCommand::Go(a) => go(&a),
        NavCommand::Tour(a) => tour(&a),
    }
}

/// The map, checked to have free space.
fn load_map(path: &Path) -> Result<OccupancyGrid> {
    let grid = crate::map::load_grid(path)?;
    if grid.counts().free == 0 {
        bail!(
            "{}: the map has no free cell: there is nowhere to drive",
            path.display()
        );
    }
    Ok(grid)
}

fn load_places(c: &Common) -> Result<Option<Places>> {
    c.goals
        .as_deref()
        .map(Places::load)
        .transpose()
        .map_err(Into::into)
}

/// A place's name or a pose `x,y,theta`.
fn resolve(spec: &str, places: Option<&Places>, what: &str) -> Result<Stop> {
    let numbers: Vec<&str> = spec.split(',').map(str::trim).collect();
    if numbers.len() == 3
        && let Ok(v) = numbers
            .iter()
            .map(|s| s.parse::<f64>())
            .collect::<Result<Vec<f64>, _>>()
    {
        if v.iter().any(|x| !x.is_finite()) {
            bail!("{what} `{spec}`: x, y and theta must be finite numbers");
        }
        return Ok(Stop {
            name: format!("{},{},{}", v[0], v[1], v[2]),
            pose: Pose::new(v[0], v[1], v[2]),
        });
    }
    let Some(places) = places else {
        bail!("{what} `{spec}` is not x,y,theta, and no --goals file names places");
    };
    match places.get(spec) {
        Some(p) => Ok(Stop {
            name: p.name.clone(),
            pose: p.pose,
        }),
        None => bail!(
            "{what}: no place `{spec}` in the goals file; it has: {}",
            places
                .iter()
                .map(|p| p.name.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
}

/// Checks that the robot can stand at every stop; names every one it cannot.
fn check_stops(grid: &OccupancyGrid, stops: &[Stop], radius_m: f64) -> Result<()> {
    let bad: Vec<String> = stops
        .iter()
        .filter_map(|s| {
            Places::problem_at(grid, s.pose.position(), radius_m)
                .map(|why| format!("`{}` ({}, {}) is {why}", s.name, num(s.pose.x_m), num(s.pose.y_m)))
        })
        .collect();
    if !bad.is_empty() {
        bail!(
            "the robot (radius {radius_m} m) cannot stand there: {}",
            bad.join("; ")
        );
    }
    Ok(())
}

/// The mission's world: the map, and `people` gathered around `anchors`
/// walking between them.
fn setup(c: &Common, grid: OccupancyGrid, anchors: &[Vec2], start: Vec2) -> Result<MissionSetup> {
    if !(c.time_limit.is_finite() && c.time_limit > 0.0) {
        bail!(
            "--time-limit must be a finite number of seconds > 0, got {}",
            c.time_limit
        );
    }
    let mut world = World::new(grid);
    let mut people = None;
    let r = CrowdParams::default().radius_m;
    let most = world.free_area_m2() / (2.0 * 3f64.sqrt() * r * r);
    if c.people as f64 > most {
        bail!(
            "--people {}: more than the {} that the map's free space could hold at the densest packing",
            c.people,
            most.floor()
        );
    }
    if c.people > 0 {
        world = world.with_crowd(CrowdParams {
            waypoints: anchors.to_vec(),
            gather_radius_m: 1.5,
            ..CrowdParams::default()
        })?;
        let plan = PeoplePlan {
            count: c.people,
            anchors: anchors.to_vec(),
            spread_m: 4.0,
            keep_clear_m: 1.0,
        };
        let fit = mission::crowd_near(&world, anchors, c.people, plan.spread_m, start, 1.5, c.seed);
        if fit.len() < c.people {
            bail!(
                "--people {}: only {} fit around the places without overlapping walls or each other",
                c.people,
                fit.len()
            );
        }
        people = Some(plan);
    }
    let mut setup = MissionSetup::new(world, c.time_limit);
    setup.people = people;
    if c.warning == WarningArg::Explained {
        setup.guide.mcl.status = nav::localization::StatusParams::explained();
    }
    Ok(setup)
}

/// The policy, learnt from the log for the supervisor.
fn policy(c: &Common) -> Result<Policy> {
    Ok(match c.behaviour {
        BehaviourArg::Automove => Policy::Fixed(Behaviour::AutoMove),
        BehaviourArg::Contour => Policy::Fixed(Behaviour::Contour),
        BehaviourArg::AutomoveThenContour => Policy::AutoMoveThenContour,
        BehaviourArg::Rule => Policy::Rule,
        BehaviourArg::Supervisor => {
            let Some(path) = &c.log else {
                bail!(
                    "--behaviour supervisor learns its rates from a mission log: give --log LOG (calibrate first with --calibration)"
                );
            };
            let entries = crate::guide_cmd::read(path)?;
            match c.net {
                NetArg::Source => {
                    let learned = learning::learn(&entries)
                        .with_context(|| format!("learning from {}", path.display()))?;
                    Policy::SupervisorSource(Box::new(SupervisorPlan {
                        supervisor: Supervisor::new()?,
                        rates: learned.rates,
                        automove: learned.automove,
                        contour: learned.contour,
                    }))
                }
                NetArg::Credit => {
                    let model = CreditModel::learn(&entries)
                        .with_context(|| format!("learning from {}", path.display()))?;
                    Policy::Supervisor(Box::new(CreditPlan {
                        supervisor: CreditSupervisor::new()?,
                        model,
                    }))
                }
            }
        }
    })
}

/// Appends the legs to the mission log, if one is kept.
fn log_legs(c: &Common, legs: &[LegRun], policy: &Policy) -> Result<()> {
    let Some(path) = &c.log else {
        return Ok(());
    };
    let net = match c.net {
        NetArg::Source => Supervisor::new()?.net_id().to_string(),
        NetArg::Credit => CreditSupervisor::new()?.net_id().to_string(),
    };
    let mut log = MissionLog::open(path, &net)?;
    if let Some(t) = log.torn() {
        eprintln!(
            "warning: {}:{}: a last line cut mid-write ({} bytes) was dropped; the entries before it are kept",
            path.display(),
            t.line,
            t.bytes
        );
    }
    for leg in legs
        .iter()
        .filter(|l| l.result.outcome != LegOutcome::Unreachable)
    {
        let entry = match (c.calibration, policy) {
            (true, Policy::Fixed(b)) if c.net == NetArg::Source => mission::calibration_entry(leg, *b),
            (true, Policy::Fixed(b)) => mission::credit_calibration_entry(leg, *b),
            (true, _) => bail!("--calibration runs one behaviour alone: --behaviour automove or contour"),
            (false, _) => mission::mission_entry(leg, log.missions() + 1),
        };
        log.append(entry)?;
    }
    Ok(())
}

fn print_legs(legs: &[LegRun], json: bool) -> Result<()> {
    if json {
        for l in legs {
            outln!("{}", serde_json::to_string(&l.result)?)?;
        }
        return Ok(());
    }
    let mut t = Table::new([
        "from",
        "to",
        "outcome",
        "time (s)",
        "path (m)",
        "final err (m)",
        "loc err mean/max (m)",
        "warnings",
        "warning (s)",
        "abnormal",
        "abnormal (s)",
    ]);
    for l in legs {
        let r = &l.result;
        t.row([
            r.from.clone(),
            r.to.clone(),
            serde_json::to_value(r.outcome)?
                .as_str()
                .unwrap_or("?")
                .to_string(),
            num(r.time_s),
            num(r.path_m),
            num(r.final_error_m),
            format!(
                "{:.2}/{:.2}",
                r.localization.mean_error_m, r.localization.max_error_m
            ),
            r.localization.warnings.to_string(),
            num(r.localization.time_in_warning_s),
            r.planner.abnormal_episodes.to_string(),
            num(r.planner.time_abnormal_s),
        ]);
    }
    outln!("{}", t.render().trim_end())?;
    Ok(())
}

fn go(a: &GoArgs) -> Result<()> {
    let c = &a.common;
    for path in [&a.trace, &a.html, &c.output].into_iter().flatten() {
        crate::lab_cmd::check_output(path)?;
    }
    let grid = load_map(&c.map)?;
    let places = load_places(c)?;
    let from = resolve(&a.from, places.as_ref(), "--from")?;
    let to = resolve(&a.to, places.as_ref(), "--to")?;
    let radius = sim::RobotParams::jinny().drive.radius_m;
    check_stops(&grid, &[from.clone(), to.clone()], radius)?;
    let anchors: Vec<Vec2> = match &places {
        Some(p) => p.iter().map(|q| q.pose.position()).collect(),
        None => vec![from.pose.position(), to.pose.position()],
    };
    let setup = setup(c, grid, &anchors, from.pose.position())?;
    let policy = policy(c)?;
    let mut leg = mission::run_leg(
        &setup,
        &LegSpec {
            from: &from.name,
            to: &to.name,
            start: from.pose,
            believed: from.pose,
            goal: to.pose.position(),
            policy: policy.clone(),
            seed: c.seed,
            trace: if a.html.is_some() {
                sim::TraceParams::full()
            } else if a.trace.is_some() {
                sim::TraceParams::poses()
            } else {
                sim::TraceParams::default()
            },
        },
    )?;
    if let Some(path) = &a.trace {
        let f = std::fs::File::create(path).with_context(|| format!("writing {}", path.display()))?;
        let sim_trace = leg.sim.as_ref().and_then(|s| s.trace.as_ref());
        leg.trace
            .write_json_lines(sim_trace, std::io::BufWriter::new(f))
            .with_context(|| format!("writing {}", path.display()))?;
    }
    if let Some(path) = &c.output {
        mission::picture(
            setup.world.grid(),
            std::slice::from_ref(&leg),
            &[from.clone(), to.clone()],
            path,
        )?;
    }
    log_legs(c, std::slice::from_ref(&leg), &policy)?;
    print_legs(std::slice::from_ref(&leg), c.json)?;
    if let Some(path) = &a.html {
        let record = lab::suites::maps::leg_record(&leg)?;
        let replay = lab::suites::maps::leg_replay(record, &setup, &mut leg, to.pose.position())?;
        let key = format!("{} → {} (seed {})", from.name, to.name, c.seed);
        lab::viewer::write_page(&replay, &lab::suites::maps::MARKERS, "nav go", &key, path)?;
    }
    exit_status(&[leg])
}

fn tour(a: &TourArgs) -> Result<()> {
    let c = &a.common;
    let grid = load_map(&c.map)?;
    let Some(places) = load_places(c)? else {
        bail!("a tour needs the places to visit: give --goals PLACES.yaml");
    };
    if places.len() < 2 {
        bail!(
            "a tour needs at least two places; the goals file has {}",
            places.len()
        );
    }
    let stops: Vec<Stop> = places
        .iter()
        .map(|p| Stop {
            name: p.name.clone(),
            pose: p.pose,
        })
        .collect();
    let radius = sim::RobotParams::jinny().drive.radius_m;
    check_stops(&grid, &stops, radius)?;
    let anchors: Vec<Vec2> = stops.iter().map(|s| s.pose.position()).collect();
    let setup = setup(c, grid, &anchors, stops[0].pose.position())?;
    let policy = policy(c)?;
    let legs = mission::run_tour(&setup, &stops, policy.clone(), c.seed)?;
    log_legs(c, &legs, &policy)?;
    if let Some(path) = &c.output {
        mission::picture(setup.world.grid(), &legs, &stops, path)?;
    }
    print_legs(&legs, c.json)?;
    let reached = legs
        .iter()
        .filter(|l| l.result.outcome == LegOutcome::Reached)
        .count();
    let total: f64 = legs.iter().map(|l| l.result.time_s).sum();
    if c.json {
        outln!(
            "{}",
            serde_json::json!({"summary": {"legs": legs.len(), "reached": reached, "total_time_s": total}})
        )?;
    } else {
        outln!(
            "{reached} of {} legs reached, {} s in all",
            legs.len(),
            num(total)
        )?;
    }
    Ok(())
}

/// A single leg that did not reach its goal is a non-zero exit (a script
/// can test it); its result has been printed.
fn exit_status(legs: &[LegRun]) -> Result<()> {
    match legs.iter().find(|l| l.result.outcome == LegOutcome::Unreachable) {
        Some(l) => bail!(
            "no route from `{}` to `{}` on the map",
            l.result.from,
            l.result.to
        ),
        None => Ok(()),
    }
}
