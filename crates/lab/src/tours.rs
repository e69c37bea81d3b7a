//! The tour-guide robot between named places on a map, as `petrinav nav go`
//! and `nav tour` run it — shared with the Python package (`crates/py`):
//! the map and places files, stops checked against the map, the crowd,
//! the navigation policy (learnt from a mission log for the supervisor),
//! the legs appended to the log. Error messages are the command line's
//! (they name its options).
//!
//! ```no_run
//! use lab::tours::{self, GuideOptions};
//!
//! let mut options = GuideOptions::new("maps/levine/levine.yaml".into());
//! options.goals = Some("maps/levine/places.yaml".into());
//! options.people = 20;
//! let tour = tours::tour(&options)?;
//! for leg in &tour.legs {
//!     println!("{}", serde_json::to_string(&leg.result)?);
//! }
//! # Ok::<(), anyhow::Error>(())
//! ```

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

use anyhow::{Context, Result, bail};
use guide::supervisor::credit::CreditSupervisor;
use guide::supervisor::credit_learning::CreditModel;
use guide::supervisor::log::{Entry, MissionLog};
use guide::supervisor::{Behaviour, Supervisor, learning};
use guide::{CreditPlan, Policy, SupervisorPlan};
use robot::{Pose, Vec2};
use serde_json::{Value, json};
use sim::{CrowdParams, OccupancyGrid, Places, World};

use crate::runs::mission::{self, LegOutcome, LegRun, MissionSetup, PeoplePlan, Stop};
use crate::tables::num;

/// The navigation behaviour of a guide run (`--behaviour`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BehaviourChoice {
    /// The map-based planner: global route, navigation function in a 10 m window.
    AutoMove,
    /// Wall following from the raw scan, leaving walls towards the goal.
    Contour,
    /// AutoMove until the localizer first warns, contour tracking from then on.
    AutoMoveThenContour,
    /// Contour tracking while the localizer warns, AutoMove while it succeeds.
    Rule,
    /// The GSPN supervisor with the rates learnt from the mission log.
    Supervisor,
}

impl BehaviourChoice {
    /// Every choice.
    pub const ALL: [BehaviourChoice; 5] = [
        BehaviourChoice::AutoMove,
        BehaviourChoice::Contour,
        BehaviourChoice::AutoMoveThenContour,
        BehaviourChoice::Rule,
        BehaviourChoice::Supervisor,
    ];

    /// The name the command line gives it: `automove`, `contour`,
    /// `automove-then-contour`, `rule`, `supervisor`.
    pub fn name(self) -> &'static str {
        match self {
            BehaviourChoice::AutoMove => "automove",
            BehaviourChoice::Contour => "contour",
            BehaviourChoice::AutoMoveThenContour => "automove-then-contour",
            BehaviourChoice::Rule => "rule",
            BehaviourChoice::Supervisor => "supervisor",
        }
    }

    /// The choice called `name` ([`name`](Self::name); `_` for `-` too).
    pub fn from_name(name: &str) -> Result<BehaviourChoice> {
        let wanted = name.replace('_', "-");
        Self::ALL
            .into_iter()
            .find(|b| b.name() == wanted)
            .with_context(|| {
                format!(
                    "unknown behaviour `{name}`: {}",
                    Self::ALL.map(BehaviourChoice::name).join(", ")
                )
            })
    }
}

/// Which supervisor net (`--net`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NetChoice {
    /// `models/supervisor_credit.toml`: failures credited to each
    /// behaviour, per crowd context.
    Credit,
    /// `models/supervisor.toml`: the source's net.
    Source,
}

impl NetChoice {
    /// The net's id, which the log's lines name.
    pub fn net_id(self) -> Result<String> {
        Ok(match self {
            NetChoice::Credit => CreditSupervisor::new()?.net_id().to_string(),
            NetChoice::Source => Supervisor::new()?.net_id().to_string(),
        })
    }
}

/// The options shared by `nav go` and `nav tour`.
#[derive(Debug, Clone)]
pub struct GuideOptions {
    /// The map: a ROS map_server `.yaml` (or a `.toml` world of shapes).
    pub map: PathBuf,
    /// Named places: YAML, one `name: [x, y, theta]` per line (`--goals`).
    pub goals: Option<PathBuf>,
    /// The navigation behaviour (`--behaviour`, default AutoMove).
    pub behaviour: BehaviourChoice,
    /// People in the building (`--people`, default 0).
    pub people: usize,
    /// Seed of the run (`--seed`, default 1).
    pub seed: u64,
    /// Time limit per leg, seconds (`--time-limit`, default 300).
    pub time_limit_s: f64,
    /// The robot's mission log (`--log`): the supervisor learns from it, and
    /// every leg is appended to it.
    pub log: Option<PathBuf>,
    /// Log the legs as calibration runs of the behaviour (`--calibration`).
    pub calibration: bool,
    /// The supervisor net the log belongs to and the supervisor decides
    /// with (`--net`, default the crediting one).
    pub net: NetChoice,
    /// The localizer warns as the source's did, by the explained fraction
    /// (`--warning explained`), instead of on contradictions.
    pub explained_warning: bool,
    /// Stops a tour before its next leg when raised (from another thread,
    /// e.g. on Ctrl-C); nothing is logged then.
    pub stop: Option<Arc<AtomicBool>>,
}

impl GuideOptions {
    /// The command line's defaults on `map`.
    pub fn new(map: PathBuf) -> GuideOptions {
        GuideOptions {
            map,
            goals: None,
            behaviour: BehaviourChoice::AutoMove,
            people: 0,
            seed: 1,
            time_limit_s: 300.0,
            log: None,
            calibration: false,
            net: NetChoice::Credit,
            explained_warning: false,
            stop: None,
        }
    }
}

/// Most legs a tour may have: each is a whole simulated mission (a second
/// or more of computing), and a tour of thousands is a mistake in the
/// places file more often than a plan; several tours do the same.
pub const MAX_TOUR_LEGS: usize = 1000;

/// The longest time limit a leg may have, seconds of simulated time (a
/// day; the default is 300 s). A leg runs until its goal or its limit, at
/// ten control ticks per simulated second.
pub const MAX_TIME_LIMIT_S: f64 = 86_400.0;

/// The map, checked to have free space.
pub fn load_map(path: &Path) -> Result<OccupancyGrid> {
    let grid = crate::map_file::load_grid(path)?;
    if grid.counts().free == 0 {
        bail!(
            "{}: the map has no free cell: there is nowhere to drive",
            path.display()
        );
    }
    Ok(grid)
}

/// The places file, if one is given.
pub fn load_places(options: &GuideOptions) -> Result<Option<Places>> {
    options
        .goals
        .as_deref()
        .map(Places::load)
        .transpose()
        .map_err(Into::into)
}

/// A place's name or a pose `x,y,theta`; `what` names the option in errors.
pub fn resolve(spec: &str, places: Option<&Places>, what: &str) -> Result<Stop> {
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
            "{what}: no place `{spec}` in the goals file{}; it has: {}",
            petri::suggest::hint(spec, places.iter().map(|p| p.name.as_str())),
            places
                .iter()
                .map(|p| p.name.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
}

/// Checks that the robot can stand at every stop; names every one it cannot.
pub fn check_stops(grid: &OccupancyGrid, stops: &[Stop], radius_m: f64) -> Result<()> {
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

/// The mission's world: the map, and the people gathered around `anchors`
/// walking between them.
pub fn setup(
    options: &GuideOptions,
    grid: OccupancyGrid,
    anchors: &[Vec2],
    start: Vec2,
) -> Result<MissionSetup> {
    let c = options;
    if !(c.time_limit_s.is_finite() && c.time_limit_s > 0.0) {
        bail!(
            "--time-limit must be a finite number of seconds > 0, got {}",
            c.time_limit_s
        );
    }
    if c.time_limit_s > MAX_TIME_LIMIT_S {
        bail!(
            "--time-limit {}: more than the {MAX_TIME_LIMIT_S} s (a day of simulated time) a leg may last (lab::tours::MAX_TIME_LIMIT_S)",
            c.time_limit_s
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
    let mut setup = MissionSetup::new(world, c.time_limit_s);
    setup.people = people;
    if c.explained_warning {
        setup.guide.mcl.status = localization::StatusParams::explained();
    }
    Ok(setup)
}

/// Reads a mission log of the shipped source supervisor net; a last line
/// cut mid-write is reported on standard error and left out.
pub fn read_log(path: &Path) -> Result<Vec<Entry>> {
    read_log_of(path, NetChoice::Source)
}

/// Reads a mission log of a shipped supervisor net ([`read_log`]).
pub fn read_log_of(path: &Path, net: NetChoice) -> Result<Vec<Entry>> {
    if !path.exists() {
        bail!("{}: no such mission log", path.display());
    }
    let net = net.net_id()?;
    let log = MissionLog::read(path, &net)?;
    for notice in log.notices() {
        eprintln!("warning: {notice}");
    }
    Ok(log.entries().to_vec())
}

/// The policy, learnt from the log for the supervisor.
pub fn policy(options: &GuideOptions) -> Result<Policy> {
    if options.calibration
        && !matches!(
            options.behaviour,
            BehaviourChoice::AutoMove | BehaviourChoice::Contour
        )
    {
        bail!("--calibration runs one behaviour alone: --behaviour automove or contour");
    }
    Ok(match options.behaviour {
        BehaviourChoice::AutoMove => Policy::Fixed(Behaviour::AutoMove),
        BehaviourChoice::Contour => Policy::Fixed(Behaviour::Contour),
        BehaviourChoice::AutoMoveThenContour => Policy::AutoMoveThenContour,
        BehaviourChoice::Rule => Policy::Rule,
        BehaviourChoice::Supervisor => {
            let Some(path) = &options.log else {
                bail!(
                    "--behaviour supervisor learns its rates from a mission log: give --log LOG (calibrate first with --calibration)"
                );
            };
            let entries = read_log_of(path, options.net)?;
            match options.net {
                NetChoice::Source => {
                    let learned = learning::learn(&entries)
                        .with_context(|| format!("learning from {}", path.display()))?;
                    Policy::SupervisorSource(Box::new(SupervisorPlan {
                        supervisor: Supervisor::new()?,
                        rates: learned.rates,
                        automove: learned.automove,
                        contour: learned.contour,
                    }))
                }
                NetChoice::Credit => {
                    let model = CreditModel::learn(&entries)
                        .with_context(|| format!("learning from {}", path.display()))?;
                    // The route is the leg's: set for each leg it runs
                    // ([`Policy::on_route`]).
                    Policy::Supervisor(Box::new(CreditPlan {
                        planner: Arc::new(CreditSupervisor::new()?),
                        model,
                        route: String::new(),
                    }))
                }
            }
        }
    })
}

/// Appends the legs to the mission log, if one is kept.
pub fn log_legs(options: &GuideOptions, legs: &[LegRun], policy: &Policy) -> Result<()> {
    let Some(path) = &options.log else {
        return Ok(());
    };
    let net = options.net.net_id()?;
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
        let mut entry = match (options.calibration, policy) {
            (true, Policy::Fixed(b)) if options.net == NetChoice::Source => {
                mission::calibration_entry(leg, *b)
            }
            (true, Policy::Fixed(b)) => mission::credit_calibration_entry(leg, *b),
            (true, _) => bail!("--calibration runs one behaviour alone: --behaviour automove or contour"),
            (false, _) => mission::mission_entry(leg, log.next_mission()),
        };
        // The crediting supervisor learns per route: the leg's places.
        if options.net == NetChoice::Credit {
            let route = Some(mission::route_name(&leg.result.from, &leg.result.to));
            match &mut entry {
                Entry::Mission(m) => m.route = route,
                Entry::Calibration(c) => c.route = route,
            }
        }
        log.append(entry)?;
    }
    Ok(())
}

/// A tour that has been run.
#[derive(Debug)]
pub struct Tour {
    /// Its world.
    pub setup: MissionSetup,
    /// The places visited, in order (the first is the start).
    pub stops: Vec<Stop>,
    /// One run per leg.
    pub legs: Vec<LegRun>,
}

impl Tour {
    /// Legs that reached their goal.
    pub fn reached(&self) -> usize {
        self.legs
            .iter()
            .filter(|l| l.result.outcome == LegOutcome::Reached)
            .count()
    }

    /// The legs' results, as `nav tour --json` prints them (one object per leg).
    pub fn legs_json(&self) -> Result<Vec<Value>> {
        self.legs
            .iter()
            .map(|l| Ok(serde_json::to_value(&l.result)?))
            .collect()
    }

    /// The last line of `nav tour --json`: `{"summary": {legs, reached, total_time_s}}`.
    pub fn summary_json(&self) -> Value {
        let total: f64 = self.legs.iter().map(|l| l.result.time_s).sum();
        json!({"summary": {"legs": self.legs.len(), "reached": self.reached(), "total_time_s": total}})
    }
}

/// `nav tour`: from the first place of the goals file to every other in the
/// file's order; the legs are appended to the mission log if one is kept.
pub fn tour(options: &GuideOptions) -> Result<Tour> {
    let grid = load_map(&options.map)?;
    let Some(places) = load_places(options)? else {
        bail!("a tour needs the places to visit: give --goals PLACES.yaml");
    };
    if places.len() < 2 {
        bail!(
            "a tour needs at least two places; the goals file has {}",
            places.len()
        );
    }
    if places.len() - 1 > MAX_TOUR_LEGS {
        bail!(
            "{}: a tour of its {} places has {} legs, more than the {MAX_TOUR_LEGS} a tour may have (lab::tours::MAX_TOUR_LEGS): split the places into several tours",
            options
                .goals
                .as_deref()
                .unwrap_or(Path::new("the goals file"))
                .display(),
            places.len(),
            places.len() - 1
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
    let setup = setup(options, grid, &anchors, stops[0].pose.position())?;
    let policy = policy(options)?;
    let never = AtomicBool::new(false);
    let stop = options.stop.as_deref().unwrap_or(&never);
    let legs = mission::run_tour_interruptible(&setup, &stops, policy.clone(), options.seed, stop)?;
    log_legs(options, &legs, &policy)?;
    Ok(Tour { setup, stops, legs })
}
