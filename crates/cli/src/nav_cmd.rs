//! `petrinav nav …`: the tour-guide robot on a map, between named places.

use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use clap::{Args, Subcommand, ValueEnum};
use lab::runs::mission::{self, LegOutcome, LegRun, LegSpec};
use lab::tours::{self, BehaviourChoice, GuideOptions, NetChoice};
use robot::Vec2;

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

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
enum NetArg {
    /// models/supervisor_credit.toml: failures credited to each behaviour, per crowd context.
    Credit,
    /// models/supervisor.toml: the source's net.
    Source,
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
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

/// The library's options for these arguments.
fn options(c: &Common) -> GuideOptions {
    GuideOptions {
        map: c.map.clone(),
        goals: c.goals.clone(),
        behaviour: match c.behaviour {
            BehaviourArg::Automove => BehaviourChoice::AutoMove,
            BehaviourArg::Contour => BehaviourChoice::Contour,
            BehaviourArg::AutomoveThenContour => BehaviourChoice::AutoMoveThenContour,
            BehaviourArg::Rule => BehaviourChoice::Rule,
            BehaviourArg::Supervisor => BehaviourChoice::Supervisor,
        },
        people: c.people,
        seed: c.seed,
        time_limit_s: c.time_limit,
        log: c.log.clone(),
        calibration: c.calibration,
        net: match c.net {
            NetArg::Credit => NetChoice::Credit,
            NetArg::Source => NetChoice::Source,
        },
        explained_warning: c.warning == WarningArg::Explained,
        stop: None,
    }
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
    let o = options(c);
    for path in [&a.trace, &a.html, &c.output].into_iter().flatten() {
        crate::lab_cmd::check_output(path)?;
    }
    let grid = tours::load_map(&c.map)?;
    let places = tours::load_places(&o)?;
    let from = tours::resolve(&a.from, places.as_ref(), "--from")?;
    let to = tours::resolve(&a.to, places.as_ref(), "--to")?;
    let radius = sim::RobotParams::jinny().drive.radius_m;
    tours::check_stops(&grid, &[from.clone(), to.clone()], radius)?;
    let anchors: Vec<Vec2> = match &places {
        Some(p) => p.iter().map(|q| q.pose.position()).collect(),
        None => vec![from.pose.position(), to.pose.position()],
    };
    let setup = tours::setup(&o, grid, &anchors, from.pose.position())?;
    let policy = tours::policy(&o)?;
    let mut leg = mission::run_leg(
        &setup,
        &LegSpec {
            from: &from.name,
            to: &to.name,
            start: from.pose,
            believed: from.pose,
            goal: to.pose.position(),
            policy: policy
                .clone()
                .on_route(&mission::route_name(&from.name, &to.name)),
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
    tours::log_legs(&o, std::slice::from_ref(&leg), &policy)?;
    print_legs(std::slice::from_ref(&leg), c.json)?;
    if let Some(path) = &a.html {
        let record = lab::runs::mission::leg_record(&leg)?;
        let mut replay = lab::runs::mission::leg_replay(record, &setup, &mut leg, to.pose.position())?;
        if matches!(policy, guide::Policy::Supervisor(_)) {
            replay.net = Some(lab::runs::mission::supervisor_net_view()?);
        }
        let key = format!("{} → {} (seed {})", from.name, to.name, c.seed);
        lab::viewer::write_page(&replay, &lab::runs::mission::MARKERS, "nav go", &key, path)?;
    }
    exit_status(&[leg])
}

fn tour(a: &TourArgs) -> Result<()> {
    let c = &a.common;
    let tour = tours::tour(&options(c))?;
    if let Some(path) = &c.output {
        mission::picture(tour.setup.world.grid(), &tour.legs, &tour.stops, path)?;
    }
    print_legs(&tour.legs, c.json)?;
    if c.json {
        outln!("{}", tour.summary_json())?;
    } else {
        let total: f64 = tour.legs.iter().map(|l| l.result.time_s).sum();
        outln!(
            "{} of {} legs reached, {} s in all",
            tour.reached(),
            tour.legs.len(),
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
