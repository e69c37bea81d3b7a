//! The tour-guide suite (tour-guide.md, "The museum experiment"): the
//! guide robot takes visitors from the start (8.1, 6.4) to the goal
//! (8.5, 27.5) of a 15 m × 35 m museum hall (`museum.toml`), mission after
//! mission, among visitors at three densities, with five strategies:
//!
//! | strategy | behaviour |
//! |---|---|
//! | `automove` | AutoMove only |
//! | `automove_then_contour` | AutoMove, and contour tracking from the localizer's first Warning on |
//! | `contour` | contour tracking only |
//! | `rule` | the rule alone: contour tracking while the localizer warns, AutoMove while it succeeds |
//! | `supervisor` | the GSPN supervisor: the rule, and `f_auto` against `f_cont` at the start of a mission and on every return from Warning to Success, with rates learnt from the mission log |
//!
//! A **campaign** is sequential: for the supervisor, ten calibration runs
//! (each behaviour alone five times, as the source did) then 24 missions,
//! each learning from the log of all before it — the campaign's earlier
//! records carry their log entries (`state`), so a resumed campaign learns
//! exactly what it would have. The other strategies learn nothing and run
//! their 24 missions only. Mission `m` of campaign `c` at a density meets
//! the same visitors and noise under every strategy (common random numbers),
//! so the strategies are compared mission by mission. Campaign 0 of the
//! supervisor at moderate density is the source's experiment.
//!
//! **Decision — densities.** The hall's free area is about 449 m²: `empty`
//! is nobody, `moderate` 25 visitors (5.6 per 100 m²: a few people at most
//! exhibits), `packed` 60 (13 per 100 m²: groups at every exhibit and
//! people in every passage). Visitors walk between the exhibits, gather
//! around them and linger, and step aside when the robot asks.

mod report;

use std::collections::BTreeMap;
use std::sync::OnceLock;

use anyhow::{Context, Result, bail};
use nav::guide::{Policy, SupervisorPlan};
use nav::supervisor::log::Entry;
use nav::supervisor::{Behaviour, Supervisor, learning};
use robot::{Pose, Vec2};
use sim::shapes::WorldSpec;
use sim::{CrowdParams, TraceParams, World};

use crate::mission::{self, LegRun, LegSpec, MissionSetup, PeoplePlan};
use crate::pictures::{EventMarker, MarkerPlace, Replay};
use crate::record::RunRecord;
use crate::runner::{Campaign, Job, derive_seed};
use crate::suite::{Registration, ReportContext, Suite, SuiteArgs, SuiteInfo, SuiteReport};

/// The suite in the registry.
pub const REGISTRATION: Registration = Registration {
    name: "tourguide",
    about: "the tour-guide robot in a crowded museum: 5 strategies (GSPN supervisor learning its rates, the rule, each behaviour alone) × 3 densities × 20 campaigns of 24 missions",
    build,
};

/// The museum, as shipped.
pub const MUSEUM: &str = include_str!("museum.toml");

/// Where every mission starts (heading north).
pub const START: Pose = Pose {
    x_m: 8.1,
    y_m: 6.4,
    theta_rad: std::f64::consts::FRAC_PI_2,
};

/// Where every mission goes.
pub const GOAL: Vec2 = Vec2 { x: 8.5, y: 27.5 };

/// Where visitors gather: in front of each exhibit of `museum.toml`.
pub const EXHIBITS: [Vec2; 12] = [
    Vec2 { x: 1.8, y: 7.5 },
    Vec2 { x: 1.8, y: 22.0 },
    Vec2 { x: 13.2, y: 11.0 },
    Vec2 { x: 13.2, y: 26.0 },
    Vec2 { x: 8.0, y: 9.6 },
    Vec2 { x: 8.0, y: 13.9 },
    Vec2 { x: 3.0, y: 9.6 },
    Vec2 { x: 12.0, y: 14.6 },
    Vec2 { x: 8.5, y: 21.1 },
    Vec2 { x: 4.0, y: 20.7 },
    Vec2 { x: 4.5, y: 27.8 },
    Vec2 { x: 12.0, y: 30.3 },
];

/// Crowd densities: name and visitors.
pub const DENSITIES: [(&str, usize); 3] = [("empty", 0), ("moderate", 25), ("packed", 60)];

/// The strategies compared, in the report's order.
pub const STRATEGIES: [&str; 5] = [
    "automove",
    "automove_then_contour",
    "contour",
    "rule",
    "supervisor",
];

/// Calibration runs per behaviour.
pub const CALIBRATION_RUNS: u32 = 5;

/// Missions per campaign.
pub const MISSIONS: u32 = 24;

/// Campaigns per density and strategy by default.
pub const DEFAULT_CAMPAIGNS: u32 = 20;

/// How often a visitor in sight and within 8 m comes to see the robot, per
/// second (the crowd model's `robot_interest_rate_per_s`).
pub const ROBOT_INTEREST_RATE_PER_S: f64 = 0.003;

/// Base seed.
pub const SEED: u64 = 7;

/// Time limit of a mission, seconds.
pub const MISSION_TIME_LIMIT_S: f64 = 300.0;

/// Metric names.
pub mod metric {
    /// Time the localizer spent in Warning, seconds.
    pub const WARNING_S: &str = "time_in_warning_s";
    /// Warnings of the localizer.
    pub const WARNINGS: &str = "warnings";
    /// Time AutoMove was Abnormal, seconds.
    pub const ABNORMAL_S: &str = "time_abnormal_s";
    /// Time AutoMove drove, seconds.
    pub const AUTOMOVE_S: &str = "time_automove_s";
    /// Time contour tracking drove, seconds.
    pub const CONTOUR_S: &str = "time_contour_s";
    /// The localizer's mean true error, metres.
    pub const LOC_MEAN: &str = "loc_mean_error_m";
    /// The localizer's largest true error, metres.
    pub const LOC_MAX: &str = "loc_max_error_m";
    /// Decisions of the supervisor.
    pub const DECISIONS: &str = "decisions";
    /// Switches between behaviours.
    pub const SWITCHES: &str = "switches";
}

/// What a job is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    /// Calibration run `k` (AutoMove for `k < 5`, contour tracking after).
    Calibration(u32),
    /// Mission `m` (from 0) of a strategy.
    Mission(usize, u32),
}

/// The tour-guide suite (module docs).
pub struct TourGuideSuite {
    info: SuiteInfo,
    world: OnceLock<Result<World, String>>,
    /// The museum prepared for the guide controller, shared by all missions.
    setup: OnceLock<Result<MissionSetup, String>>,
    supervisor: OnceLock<Result<Supervisor, String>>,
}

fn build(args: &SuiteArgs) -> Result<Box<dyn Suite>> {
    Ok(Box::new(TourGuideSuite::new(
        args.runs.unwrap_or(DEFAULT_CAMPAIGNS),
    )?))
}

/// The museum world with its visitors' parameters (positions are drawn per
/// mission).
pub fn museum() -> Result<World> {
    #[derive(serde::Deserialize)]
    struct File {
        world: WorldSpec,
    }
    let file: File = toml::from_str(MUSEUM).context("museum.toml")?;
    let grid = file.world.rasterise()?;
    Ok(World::new(grid).with_crowd(CrowdParams {
        waypoints: EXHIBITS.to_vec(),
        gather_radius_m: 1.2,
        linger_probability: 0.7,
        linger_mean_s: 30.0,
        // "Visitors … sometimes surround the robot": a visitor in sight and
        // within 8 m comes over with probability 1 − e^(−0.3) ≈ 26 % during
        // 100 s, stands 0.9 m from it for 20 s on average (or until asked
        // aside); a few per mission at moderate density.
        robot_interest_rate_per_s: ROBOT_INTEREST_RATE_PER_S,
        ..CrowdParams::default()
    })?)
}

impl TourGuideSuite {
    /// The suite with `campaigns` campaigns per density and strategy.
    pub fn new(campaigns: u32) -> Result<TourGuideSuite> {
        if campaigns == 0 {
            bail!("the tour-guide suite needs at least one campaign");
        }
        let mut scenarios = Vec::new();
        for (d, _) in DENSITIES {
            scenarios.push(format!("{d}/calibration"));
            for s in STRATEGIES {
                scenarios.push(format!("{d}/{s}"));
            }
        }
        Ok(TourGuideSuite {
            info: SuiteInfo {
                name: REGISTRATION.name.into(),
                suite: REGISTRATION.name.into(),
                runs: campaigns,
                seed: SEED,
                scenarios,
                sources: BTreeMap::new(),
            },
            world: OnceLock::new(),
            setup: OnceLock::new(),
            supervisor: OnceLock::new(),
        })
    }

    fn world(&self) -> Result<&World> {
        self.world
            .get_or_init(|| museum().map_err(|e| format!("{e:#}")))
            .as_ref()
            .map_err(|e| anyhow::anyhow!("{e}"))
    }

    /// A mission's setup without its visitors: the museum, prepared once
    /// for the guide controller ([`MissionSetup::prepare`]).
    fn setup(&self) -> Result<&MissionSetup> {
        self.setup
            .get_or_init(|| {
                let world = self.world().map_err(|e| format!("{e:#}"))?.clone();
                let mut setup = MissionSetup::new(world, MISSION_TIME_LIMIT_S);
                setup.prepare().map_err(|e| format!("{e:#}"))?;
                Ok(setup)
            })
            .as_ref()
            .map_err(|e| anyhow::anyhow!("{e}"))
    }

    fn supervisor(&self) -> Result<&Supervisor> {
        self.supervisor
            .get_or_init(|| Supervisor::new().map_err(|e| e.to_string()))
            .as_ref()
            .map_err(|e| anyhow::anyhow!("{e}"))
    }

    /// The density index, and the job's kind, of a scenario name and run.
    fn parse(&self, job: &Job) -> Result<(usize, Kind)> {
        let (density, what) = job
            .scenario
            .split_once('/')
            .with_context(|| format!("`{}` is not a tour-guide scenario", job.scenario))?;
        let d = DENSITIES
            .iter()
            .position(|(n, _)| *n == density)
            .with_context(|| format!("no density `{density}`"))?;
        let kind = if what == "calibration" {
            Kind::Calibration(job.run % (2 * CALIBRATION_RUNS))
        } else {
            let s = STRATEGIES
                .iter()
                .position(|n| *n == what)
                .with_context(|| format!("no strategy `{what}`"))?;
            Kind::Mission(s, job.run % MISSIONS)
        };
        Ok((d, kind))
    }

    /// The seed of mission or calibration run `k` of campaign `c` at
    /// density `d`: the same for every strategy.
    fn seed(&self, d: usize, c: u32, calibration: bool, k: u32) -> u64 {
        let stream = format!(
            "{} campaign {c}{}",
            DENSITIES[d].0,
            if calibration { " calibration" } else { "" }
        );
        derive_seed(self.info.seed, &stream, k)
    }

    /// The log so far: the entries the earlier records of a campaign carry.
    fn log(earlier: &[RunRecord]) -> Result<Vec<Entry>> {
        earlier
            .iter()
            .map(|r| {
                let state = r.state.clone().context("an earlier run without its log entry")?;
                serde_json::from_value(state).context("the log entry of an earlier run")
            })
            .collect()
    }

    /// The policy of a mission of strategy `s`, learnt from `log`.
    fn policy(&self, s: usize, log: &[Entry]) -> Result<Policy> {
        Ok(match STRATEGIES[s] {
            "automove" => Policy::Fixed(Behaviour::AutoMove),
            "contour" => Policy::Fixed(Behaviour::Contour),
            "automove_then_contour" => Policy::AutoMoveThenContour,
            "rule" => Policy::Rule,
            _ => {
                let learned = learning::learn_or_prior(log)?;
                Policy::Supervisor(Box::new(SupervisorPlan {
                    supervisor: self.supervisor()?.clone(),
                    rates: learned.rates,
                    automove: learned.automove,
                    contour: learned.contour,
                }))
            }
        })
    }

    /// Runs a job.
    fn leg(&self, job: &Job, earlier: &[RunRecord], trace: TraceParams) -> Result<(LegRun, Entry)> {
        let (d, kind) = self.parse(job)?;
        let log = Self::log(earlier)?;
        let (policy, name) = match kind {
            Kind::Calibration(k) => {
                let b = if k < CALIBRATION_RUNS {
                    Behaviour::AutoMove
                } else {
                    Behaviour::Contour
                };
                (Policy::Fixed(b), format!("calibration {}", k + 1))
            }
            Kind::Mission(s, m) => (self.policy(s, &log)?, format!("mission {}", m + 1)),
        };
        let mut setup = self.setup()?.clone();
        let people = DENSITIES[d].1;
        if people > 0 {
            setup.people = Some(PeoplePlan {
                count: people,
                anchors: EXHIBITS.to_vec(),
                spread_m: 2.5,
                keep_clear_m: 1.0,
            });
        }
        let leg = mission::run_leg(
            &setup,
            &LegSpec {
                from: "start",
                to: &name,
                start: START,
                believed: START,
                goal: GOAL,
                policy: policy.clone(),
                seed: job.seed,
                trace,
            },
        )?;
        let entry = match (kind, &policy) {
            (Kind::Calibration(_), Policy::Fixed(b)) => mission::calibration_entry(&leg, *b),
            (Kind::Mission(_, m), _) => mission::mission_entry(&leg, m + 1),
            (Kind::Calibration(_), _) => bail!("a calibration run drives one behaviour"),
        };
        Ok((leg, entry))
    }

    fn record(&self, leg: &LegRun, entry: &Entry) -> Result<RunRecord> {
        let r = &leg.result;
        let kept = ["decision", "switch", "warning", "success"];
        let mut record = RunRecord {
            events: leg
                .trace
                .events
                .iter()
                .filter(|e| kept.contains(&e.kind.as_str()))
                .cloned()
                .collect(),
            start: [START.x_m, START.y_m, START.theta_rad],
            state: Some(serde_json::to_value(entry)?),
            ..mission::leg_base_record(leg)
        };
        let s = &leg.summary;
        record.set_metric(metric::WARNING_S, r.localization.time_in_warning_s)?;
        record.set_metric(metric::WARNINGS, f64::from(r.localization.warnings))?;
        record.set_metric(metric::ABNORMAL_S, r.planner.time_abnormal_s)?;
        record.set_metric(metric::AUTOMOVE_S, s.time_automove_s)?;
        record.set_metric(metric::CONTOUR_S, s.time_contour_s)?;
        record.set_metric(metric::LOC_MEAN, r.localization.mean_error_m)?;
        record.set_metric(metric::LOC_MAX, r.localization.max_error_m)?;
        record.set_metric(metric::DECISIONS, s.decisions.len() as f64)?;
        let switches = leg.trace.events.iter().filter(|e| e.kind == "switch").count();
        record.set_metric(metric::SWITCHES, switches as f64)?;
        Ok(record)
    }
}

impl Suite for TourGuideSuite {
    fn info(&self) -> &SuiteInfo {
        &self.info
    }

    fn campaigns(&self) -> Vec<Campaign> {
        let mut out = Vec::new();
        for (d, (density, _)) in DENSITIES.iter().enumerate() {
            for (s, strategy) in STRATEGIES.iter().enumerate() {
                for c in 0..self.info.runs {
                    let mut jobs = Vec::new();
                    if STRATEGIES[s] == "supervisor" {
                        jobs.extend((0..2 * CALIBRATION_RUNS).map(|k| Job {
                            scenario: format!("{density}/calibration"),
                            run: c * 2 * CALIBRATION_RUNS + k,
                            seed: self.seed(d, c, true, k),
                        }));
                    }
                    jobs.extend((0..MISSIONS).map(|m| Job {
                        scenario: format!("{density}/{strategy}"),
                        run: c * MISSIONS + m,
                        seed: self.seed(d, c, false, m),
                    }));
                    out.push(Campaign { jobs });
                }
            }
        }
        out
    }

    fn run(&self, job: &Job, earlier: &[RunRecord]) -> Result<RunRecord> {
        let (leg, entry) = self.leg(job, earlier, TraceParams::default())?;
        self.record(&leg, &entry)
    }

    fn replay(&self, job: &Job, earlier: &[RunRecord], trace: TraceParams) -> Result<Replay> {
        let trace = TraceParams {
            enabled: true,
            ..trace
        };
        let (leg, entry) = self.leg(job, earlier, trace)?;
        let record = self.record(&leg, &entry)?;
        Ok(Replay {
            record,
            trace: leg
                .sim
                .and_then(|s| s.trace)
                .context("the mission could not run")?,
            grid: self.world()?.grid().clone(),
            goal: Some(GOAL),
            robot_radius_m: sim::RobotParams::jinny().drive.radius_m,
            control_period_s: 0.1,
        })
    }

    fn markers(&self) -> &[EventMarker] {
        &MARKERS
    }

    fn report(&self, ctx: &ReportContext<'_>) -> Result<SuiteReport> {
        report::report(self, ctx)
    }
}

/// Decisions and warnings on pictures of a mission.
pub const MARKERS: [EventMarker; 2] = [
    EventMarker {
        kind: "warning",
        marker: sim::render::MarkerKind::Square([230, 120, 0]),
        place: MarkerPlace::Robot,
        single_run_only: false,
    },
    EventMarker {
        kind: "decision",
        marker: sim::render::MarkerKind::Ring([120, 0, 160]),
        place: MarkerPlace::Robot,
        single_run_only: false,
    },
];
