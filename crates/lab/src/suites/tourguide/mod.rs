//! The tour-guide suite (docs/tour-guide.md, "The museum experiment"): the
//! guide robot takes visitors from the start (8.1, 6.4) to the goal
//! (8.5, 27.5) of a 15 m × 35 m museum hall (`museum.toml`), mission after
//! mission, among visitors, with six strategies:
//!
//! | strategy | behaviour |
//! |---|---|
//! | `automove` | AutoMove only |
//! | `automove_then_contour` | AutoMove, and contour tracking from the localizer's first Warning on |
//! | `contour` | contour tracking only |
//! | `rule` | the rule alone: contour tracking while the localizer warns, AutoMove while it succeeds |
//! | `supervisor` | the crediting GSPN supervisor ([`guide::supervisor::credit`]): the net decides at the start, at every Warning and at every return to Success, with failure rates credited to each behaviour and learnt per crowd context from the campaign's log |
//! | `supervisor_source` | the source's supervisor and localizer: the rule, and `f_auto` against `f_cont` at the start and on returns to Success, the localizer warning by the explained fraction |
//!
//! All but `supervisor_source` run the localizer whose Warning means lost
//! (the contradiction rule, `localization::status`).
//!
//! **Conditions.** Three crowd densities and a museum day: `empty` (nobody),
//! `moderate` (25 visitors), `packed` (60), and `day`, whose 24 missions
//! meet 0, 25, 60 and 25 visitors by quarters (the museum opens, fills, is
//! packed at midday, empties) — the right behaviour may change within one
//! campaign, and the supervisor must learn it online. In every condition
//! the physical causes of true loss occur at their rates
//! ([`disturbances`]): visitors pushing the braked robot, wheel slip on
//! the polished threshold between the galleries, groups closing round the
//! robot.
//!
//! A **campaign** is sequential: for each supervisor, ten calibration runs
//! (each behaviour alone five times, as the source did; at the campaign's
//! first density) then 24 missions, each learning from the log of all
//! before it — the campaign's earlier records carry their log entries
//! (`state`), so a resumed campaign learns exactly what it would have. The
//! other strategies learn nothing and run their 24 missions only. Mission
//! `m` of campaign `c` in a condition meets the same visitors, noise and
//! disturbance draws under every strategy (common random numbers), so the
//! strategies are compared mission by mission.
//!
//! **The source's experiment** is its own scenario, `source/…`: one
//! campaign of `supervisor_source` among 25 visitors without the
//! disturbances (the source reports none), on the seeds the moderate
//! campaign 0 has always had — its table (the source's Table IV: the
//! learnt λ3…λ6, `f_auto`, `f_cont` and the choice mission by mission)
//! reproduces run for run.
//!
//! **Decision — densities.** The hall's free area is about 449 m²:
//! `moderate` 25 visitors (5.6 per 100 m²: a few people at most exhibits),
//! `packed` 60 (13 per 100 m²: groups at every exhibit and people in every
//! passage). Visitors walk between the exhibits, gather around them and
//! linger, and step aside when the robot asks.

pub mod galleries;
mod galleries_report;
mod report;

use std::collections::BTreeMap;
use std::sync::{Arc, OnceLock};

use anyhow::{Context, Result, bail};
use guide::supervisor::credit::CreditSupervisor;
use guide::supervisor::credit_learning::CreditModel;
use guide::supervisor::log::Entry;
use guide::supervisor::{Behaviour, Supervisor, learning};
use guide::{CreditPlan, GuideParams, Policy, SupervisorPlan};
use localization::StatusParams;
use robot::{Event, Pose, Vec2};
use sim::shapes::WorldSpec;
use sim::{CrowdParams, DisturbanceKind, DisturbanceParams, SlipPatch, TraceParams, World};

use crate::pictures::{EventMarker, MarkerPlace, Replay};
use crate::record::RunRecord;
use crate::runner::{Campaign, Job, derive_seed};
use crate::runs::mission::{self, LegRun, LegSpec, MissionSetup, PeoplePlan};
use crate::suite::{Registration, ReportContext, Suite, SuiteArgs, SuiteInfo, SuiteReport};

/// The suite in the registry.
pub const REGISTRATION: Registration = Registration {
    name: "tourguide",
    about: "the tour-guide robot in a crowded museum: 6 strategies (the crediting GSPN supervisor, the source's, the rule, each behaviour alone) × 4 conditions (empty, moderate, packed, a museum day) × 6 campaigns of 24 missions, with pushes, slips and groups causing true losses",
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

/// A condition: its name and the visitors of each quarter of a campaign's
/// missions.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Condition {
    /// Name (`empty`, `moderate`, `packed`, `day`).
    pub name: &'static str,
    /// Visitors during each quarter of the missions (the calibration runs
    /// meet the first quarter's).
    pub visitors: [usize; 4],
}

impl Condition {
    /// Visitors during mission `m` (from 0).
    pub fn visitors_at(&self, m: u32) -> usize {
        self.visitors[((m * 4) / MISSIONS).min(3) as usize]
    }

    /// Whether the density changes during a campaign.
    pub fn changes(&self) -> bool {
        self.visitors.iter().any(|&v| v != self.visitors[0])
    }
}

/// The conditions compared, in the report's order.
pub const CONDITIONS: [Condition; 4] = [
    Condition {
        name: "empty",
        visitors: [0; 4],
    },
    Condition {
        name: "moderate",
        visitors: [25; 4],
    },
    Condition {
        name: "packed",
        visitors: [60; 4],
    },
    Condition {
        name: "day",
        visitors: [0, 25, 60, 25],
    },
];

/// The source's experiment's scenario prefix (moderate, no disturbances).
pub const SOURCE: &str = "source";

/// The strategies compared, in the report's order.
pub const STRATEGIES: [&str; 6] = [
    "automove",
    "automove_then_contour",
    "contour",
    "rule",
    "supervisor",
    "supervisor_source",
];

/// The strategies that learn nothing (fixed policies).
pub const FIXED: [&str; 4] = ["automove", "automove_then_contour", "contour", "rule"];

/// Calibration runs per behaviour.
pub const CALIBRATION_RUNS: u32 = 5;

/// Missions per campaign.
pub const MISSIONS: u32 = 24;

/// Campaigns per condition and strategy by default.
pub const DEFAULT_CAMPAIGNS: u32 = 6;

/// How often a visitor in sight and within 8 m comes to see the robot, per
/// second (the crowd model's `robot_interest_rate_per_s`).
pub const ROBOT_INTEREST_RATE_PER_S: f64 = 0.003;

/// Largest share of its turn a wheel loses on the museum's polished
/// threshold ([`disturbances`]).
pub const SLIP_MAX: f64 = 0.1;

/// A mission ends lost when the estimate stays more than 2 m off for this
/// long, seconds: long enough for the localizer to find itself again after
/// a push (it starts global localization 20 s into a recovery that has not
/// converged).
pub const LOST_AFTER_S: f64 = 30.0;

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
    /// Time truly lost (error over 0.5 m or 20°), seconds.
    pub const LOST_S: &str = "time_lost_s";
    /// Time in Warning while truly lost, seconds.
    pub const WARNING_LOST_S: &str = "time_warning_lost_s";
    /// Time with the true error under 0.2 m, seconds.
    pub const FINE_S: &str = "time_fine_s";
    /// Time in Warning with the true error under 0.2 m, seconds.
    pub const WARNING_FINE_S: &str = "time_warning_fine_s";
    /// Visitors in the hall.
    pub const VISITORS: &str = "visitors";
    /// Pushes.
    pub const PUSHES: &str = "pushes";
    /// Slip-patch crossings.
    pub const SLIPS: &str = "slips";
    /// Groups closing round the robot.
    pub const SURROUNDS: &str = "surrounds";
}

/// What a job is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    /// Calibration run `k` of the source's supervisor (AutoMove for
    /// `k < 5`, contour tracking after).
    Calibration { k: u32 },
    /// Mission `m` (from 0) of a strategy.
    Mission(usize, u32),
}

/// A scenario name taken apart: the condition (`None` for the source's
/// experiment) and the job's kind.
#[derive(Debug, Clone, Copy)]
struct Parsed {
    condition: Option<usize>,
    kind: Kind,
}

/// The tour-guide suite (module docs).
pub struct TourGuideSuite {
    info: SuiteInfo,
    world: OnceLock<Result<(World, Vec<SlipPatch>), String>>,
    /// The museum prepared for the guide controller, shared by all
    /// missions: with the contradiction rule, and with the source's.
    setup: OnceLock<Result<MissionSetup, String>>,
    setup_source: OnceLock<Result<MissionSetup, String>>,
    supervisor: OnceLock<Result<Supervisor, String>>,
    credit: OnceLock<Result<Arc<CreditSupervisor>, String>>,
    /// The galleries and a leg's setup there (the map prepared once).
    galleries: OnceLock<Result<(galleries::Galleries, MissionSetup), String>>,
}

/// A leg run for a record: the leg, the state the record keeps, the
/// visitors it met, where it started and where it went.
struct Done {
    leg: LegRun,
    state: serde_json::Value,
    visitors: usize,
    start: Pose,
    goal: Vec2,
}

fn build(args: &SuiteArgs) -> Result<Box<dyn Suite>> {
    Ok(Box::new(TourGuideSuite::new(
        args.runs.unwrap_or(DEFAULT_CAMPAIGNS),
    )?))
}

/// The museum world with its visitors' parameters (positions are drawn per
/// mission) and its slip patches.
pub fn museum_with_patches() -> Result<(World, Vec<SlipPatch>)> {
    #[derive(serde::Deserialize)]
    struct File {
        world: WorldSpec,
        #[serde(default)]
        slip: Vec<SlipPatch>,
    }
    let file: File = toml::from_str(MUSEUM).context("museum.toml")?;
    let grid = file.world.rasterise()?;
    let world = World::new(grid).with_crowd(CrowdParams {
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
    })?;
    Ok((world, file.slip))
}

/// The museum world with its visitors' parameters.
pub fn museum() -> Result<World> {
    Ok(museum_with_patches()?.0)
}

/// The physical causes of true loss in the museum with `visitors`
/// visitors ([`mission::visitor_disturbances`]: pushes and groups at
/// rates from their causes), and its slip patch: the polished stone
/// threshold between the two galleries (`[[slip]]` in `museum.toml`) lets
/// each wheel slip by up to [`SLIP_MAX`] (10 %) of its turn, drawn per
/// crossing (rubber on a freshly polished or damp stone floor): every
/// mission crosses it.
pub fn disturbances(visitors: usize, patches: &[SlipPatch]) -> DisturbanceParams {
    mission::visitor_disturbances(visitors, patches, SLIP_MAX)
}

/// The guide's parameters of the source's robot: its localizer warns by
/// the explained fraction ([`StatusParams::explained`]).
pub fn source_guide() -> GuideParams {
    let mut g = GuideParams::default();
    g.mcl.status = StatusParams::explained();
    g
}

impl TourGuideSuite {
    /// The suite with `campaigns` campaigns per condition and strategy.
    pub fn new(campaigns: u32) -> Result<TourGuideSuite> {
        if campaigns == 0 {
            bail!("the tour-guide suite needs at least one campaign");
        }
        let mut scenarios = vec![
            format!("{SOURCE}/calibration_source"),
            format!("{SOURCE}/supervisor_source"),
        ];
        for c in CONDITIONS {
            scenarios.push(format!("{}/calibration_source", c.name));
            for s in STRATEGIES {
                scenarios.push(format!("{}/{s}", c.name));
            }
        }
        for s in galleries::STRATEGIES {
            scenarios.push(format!("{}/{s}", galleries::CONDITION));
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
            setup_source: OnceLock::new(),
            supervisor: OnceLock::new(),
            credit: OnceLock::new(),
            galleries: OnceLock::new(),
        })
    }

    /// The galleries, with a leg's setup there (no visitors yet; the map
    /// prepared once for the guide controller).
    fn galleries(&self) -> Result<&(galleries::Galleries, MissionSetup)> {
        self.galleries
            .get_or_init(|| {
                let g = galleries::galleries().map_err(|e| format!("{e:#}"))?;
                let mut setup = MissionSetup::new(g.world.clone(), galleries::LEG_TIME_LIMIT_S);
                setup.lost_after_s = LOST_AFTER_S;
                setup.prepare().map_err(|e| format!("{e:#}"))?;
                Ok((g, setup))
            })
            .as_ref()
            .map_err(|e| anyhow::anyhow!("{e}"))
    }

    /// Runs leg `k` of a galleries campaign with strategy `strategy`.
    fn galleries_leg(
        &self,
        strategy: &str,
        job: &Job,
        earlier: &[RunRecord],
        trace: TraceParams,
    ) -> Result<Done> {
        let (g, setup) = self.galleries()?;
        let k = job.run % galleries::CAMPAIGN_LEGS;
        let (t, j) = galleries::tour_leg(k);
        let from = galleries::start_of(g, k, earlier)?;
        let to = &g.stops[j as usize + 1];
        let route = galleries::route_name(&g.stops[j as usize].name, &to.name);
        let policy = if strategy == "supervisor" {
            let log = earlier
                .iter()
                .map(|r| Ok(galleries::LegState::of(r)?.entry))
                .collect::<Result<Vec<Entry>>>()?;
            Policy::Supervisor(Box::new(CreditPlan {
                planner: self.credit()?.clone(),
                model: CreditModel::learn(&log)?,
                route: route.clone(),
            }))
        } else {
            galleries::fixed_policy(strategy, k, earlier)?
        };
        let visitors = galleries::visitors_at(t);
        let mut setup = setup.clone();
        setup.disturbances = mission::visitor_disturbances(visitors, &[], 0.0);
        if visitors > 0 {
            setup.people = Some(PeoplePlan {
                count: visitors,
                anchors: g.exhibits.clone(),
                spread_m: 2.5,
                keep_clear_m: 1.0,
            });
        }
        let leg = mission::run_leg(
            &setup,
            &LegSpec {
                from: &from.name,
                to: &to.name,
                start: from.pose,
                believed: from.estimate,
                goal: to.pose.position(),
                policy,
                seed: job.seed,
                trace,
            },
        )?;
        let mut entry = mission::mission_entry(&leg, k + 1);
        if let Entry::Mission(m) = &mut entry {
            m.route = Some(route);
        }
        let state = galleries::LegState {
            at: from.after(&leg, to),
            entry,
        };
        Ok(Done {
            state: serde_json::to_value(&state)?,
            visitors,
            start: from.pose,
            goal: to.pose.position(),
            leg,
        })
    }

    fn world(&self) -> Result<&(World, Vec<SlipPatch>)> {
        self.world
            .get_or_init(|| museum_with_patches().map_err(|e| format!("{e:#}")))
            .as_ref()
            .map_err(|e| anyhow::anyhow!("{e}"))
    }

    /// A mission's setup without its visitors: the museum, prepared once
    /// for the guide controller ([`MissionSetup::prepare`]), with the
    /// contradiction rule or the source's localizer.
    fn setup(&self, source: bool) -> Result<&MissionSetup> {
        let cell = if source { &self.setup_source } else { &self.setup };
        cell.get_or_init(|| {
            let world = self.world().map_err(|e| format!("{e:#}"))?.0.clone();
            let mut setup = MissionSetup::new(world, MISSION_TIME_LIMIT_S);
            setup.lost_after_s = LOST_AFTER_S;
            if source {
                setup.guide = source_guide();
            }
            setup.prepare().map_err(|e| format!("{e:#}"))?;
            Ok(setup)
        })
        .as_ref()
        .map_err(|e| anyhow::anyhow!("{e}"))
    }

    pub(crate) fn supervisor(&self) -> Result<&Supervisor> {
        self.supervisor
            .get_or_init(|| Supervisor::new().map_err(|e| e.to_string()))
            .as_ref()
            .map_err(|e| anyhow::anyhow!("{e}"))
    }

    pub(crate) fn credit(&self) -> Result<&Arc<CreditSupervisor>> {
        self.credit
            .get_or_init(|| CreditSupervisor::new().map(Arc::new).map_err(|e| e.to_string()))
            .as_ref()
            .map_err(|e| anyhow::anyhow!("{e}"))
    }

    /// The condition and the job's kind of a scenario name and run.
    fn parse(&self, job: &Job) -> Result<Parsed> {
        let (prefix, what) = job
            .scenario
            .split_once('/')
            .with_context(|| format!("`{}` is not a tour-guide scenario", job.scenario))?;
        let condition = if prefix == SOURCE {
            None
        } else {
            Some(
                CONDITIONS
                    .iter()
                    .position(|c| c.name == prefix)
                    .with_context(|| format!("no condition `{prefix}`"))?,
            )
        };
        let kind = match what {
            "calibration_source" => Kind::Calibration {
                k: job.run % (2 * CALIBRATION_RUNS),
            },
            _ => {
                let s = STRATEGIES
                    .iter()
                    .position(|n| *n == what)
                    .with_context(|| format!("no strategy `{what}`"))?;
                Kind::Mission(s, job.run % MISSIONS)
            }
        };
        if condition.is_none() && !matches!(kind, Kind::Calibration { .. }) && what != "supervisor_source" {
            bail!("the source's experiment runs only `supervisor_source` and its calibration");
        }
        Ok(Parsed { condition, kind })
    }

    /// The seed of mission or calibration run `k` of campaign `c` in a
    /// condition: the same for every strategy. The source's experiment has
    /// the moderate campaign 0's seeds.
    fn seed(&self, condition: &str, c: u32, calibration: bool, k: u32) -> u64 {
        let stream = format!(
            "{condition} campaign {c}{}",
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
            "supervisor" => Policy::Supervisor(Box::new(CreditPlan {
                planner: self.credit()?.clone(),
                model: CreditModel::learn(log)?,
                route: String::new(),
            })),
            _ => {
                let learned = learning::learn_or_prior(log)?;
                Policy::SupervisorSource(Box::new(SupervisorPlan {
                    supervisor: self.supervisor()?.clone(),
                    rates: learned.rates,
                    automove: learned.automove,
                    contour: learned.contour,
                }))
            }
        })
    }

    /// Visitors and disturbances of a job.
    fn conditions_of(&self, parsed: &Parsed) -> Result<(usize, DisturbanceParams)> {
        let Some(c) = parsed.condition else {
            // The source's experiment: 25 visitors, no disturbances.
            return Ok((25, DisturbanceParams::default()));
        };
        let cond = CONDITIONS[c];
        let visitors = match parsed.kind {
            Kind::Calibration { .. } => cond.visitors[0],
            Kind::Mission(_, m) => cond.visitors_at(m),
        };
        Ok((visitors, disturbances(visitors, &self.world()?.1)))
    }

    /// Runs a job.
    fn leg(&self, job: &Job, earlier: &[RunRecord], trace: TraceParams) -> Result<Done> {
        if let Some(strategy) = job
            .scenario
            .strip_prefix(galleries::CONDITION)
            .and_then(|s| s.strip_prefix('/'))
        {
            return self.galleries_leg(strategy, job, earlier, trace);
        }
        let parsed = self.parse(job)?;
        let log = Self::log(earlier)?;
        let (policy, name, source) = match parsed.kind {
            Kind::Calibration { k } => {
                let b = if k < CALIBRATION_RUNS {
                    Behaviour::AutoMove
                } else {
                    Behaviour::Contour
                };
                (Policy::Fixed(b), format!("calibration {}", k + 1), true)
            }
            Kind::Mission(s, m) => (
                self.policy(s, &log)?,
                format!("mission {}", m + 1),
                STRATEGIES[s] == "supervisor_source",
            ),
        };
        let mut setup = self.setup(source)?.clone();
        let (visitors, disturbances) = self.conditions_of(&parsed)?;
        setup.disturbances = disturbances;
        if visitors > 0 {
            setup.people = Some(PeoplePlan {
                count: visitors,
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
        let entry = match (parsed.kind, &policy) {
            (Kind::Calibration { .. }, Policy::Fixed(b)) => mission::calibration_entry(&leg, *b),
            // The source's log as the source keeps it: no segments.
            (Kind::Mission(_, m), _) if source => match mission::mission_entry(&leg, m + 1) {
                Entry::Mission(r) => Entry::Mission(guide::supervisor::log::MissionRecord {
                    segments: Vec::new(),
                    ..r
                }),
                other => other,
            },
            (Kind::Mission(_, m), _) => mission::mission_entry(&leg, m + 1),
            (Kind::Calibration { .. }, _) => bail!("a calibration run drives one behaviour"),
        };
        Ok(Done {
            leg,
            state: serde_json::to_value(&entry)?,
            visitors,
            start: START,
            goal: GOAL,
        })
    }

    fn record(&self, done: &Done) -> Result<RunRecord> {
        let Done {
            leg,
            state,
            visitors,
            start,
            ..
        } = done;
        let visitors = *visitors;
        let r = &leg.result;
        let kept = ["decision", "switch", "warning", "success"];
        let mut events: Vec<Event> = leg
            .trace
            .events
            .iter()
            .filter(|e| kept.contains(&e.kind.as_str()))
            .cloned()
            .collect();
        events.extend(leg.disturbances.iter().filter_map(disturbance_event));
        events.sort_by(|a, b| a.time_s.total_cmp(&b.time_s));
        let mut record = RunRecord {
            events,
            start: [start.x_m, start.y_m, start.theta_rad],
            state: Some(state.clone()),
            ..mission::leg_base_record(leg)
        };
        let s = &leg.summary;
        let l = &r.localization;
        record.set_metric(metric::WARNING_S, l.time_in_warning_s)?;
        record.set_metric(metric::WARNINGS, f64::from(l.warnings))?;
        record.set_metric(metric::ABNORMAL_S, r.planner.time_abnormal_s)?;
        record.set_metric(metric::AUTOMOVE_S, s.time_automove_s)?;
        record.set_metric(metric::CONTOUR_S, s.time_contour_s)?;
        record.set_metric(metric::LOC_MEAN, l.mean_error_m)?;
        record.set_metric(metric::LOC_MAX, l.max_error_m)?;
        record.set_metric(metric::DECISIONS, s.decisions.len() as f64)?;
        let switches = leg.trace.events.iter().filter(|e| e.kind == "switch").count();
        record.set_metric(metric::SWITCHES, switches as f64)?;
        record.set_metric(metric::LOST_S, l.lost_s)?;
        record.set_metric(metric::WARNING_LOST_S, l.warning_lost_s)?;
        record.set_metric(metric::FINE_S, l.fine_s)?;
        record.set_metric(metric::WARNING_FINE_S, l.warning_fine_s)?;
        record.set_metric(metric::VISITORS, visitors as f64)?;
        let count = |kind: &str| leg.disturbances.iter().filter(|d| d.kind.name() == kind).count() as f64;
        record.set_metric(metric::PUSHES, count("push"))?;
        record.set_metric(metric::SLIPS, count("slip"))?;
        record.set_metric(metric::SURROUNDS, count("surround"))?;
        Ok(record)
    }
}

/// A disturbance as a record's event (`push`, `surround`; slips are
/// counted, not kept: every mission has one).
fn disturbance_event(d: &sim::DisturbanceEvent) -> Option<Event> {
    let e = Event::new(d.kind.name(), d.start_s);
    match &d.kind {
        DisturbanceKind::Push {
            applied_translation_m,
            applied_rotation_rad,
            ..
        } => Some(
            e.with("translation_m", *applied_translation_m)
                .with("rotation_rad", *applied_rotation_rad),
        ),
        DisturbanceKind::Surround {
            group_size,
            duration_s,
            ..
        } => Some(
            e.with("group_size", *group_size as f64)
                .with("duration_s", *duration_s),
        ),
        DisturbanceKind::Slip { .. } => None,
    }
}

impl Suite for TourGuideSuite {
    fn info(&self) -> &SuiteInfo {
        &self.info
    }

    fn campaigns(&self) -> Vec<Campaign> {
        let mut out = Vec::new();
        // The source's experiment: one campaign, the moderate campaign 0's
        // seeds.
        let mut jobs: Vec<Job> = (0..2 * CALIBRATION_RUNS)
            .map(|k| Job {
                scenario: format!("{SOURCE}/calibration_source"),
                run: k,
                seed: self.seed("moderate", 0, true, k),
            })
            .collect();
        jobs.extend((0..MISSIONS).map(|m| Job {
            scenario: format!("{SOURCE}/supervisor_source"),
            run: m,
            seed: self.seed("moderate", 0, false, m),
        }));
        out.push(Campaign { jobs });
        for cond in CONDITIONS {
            for strategy in STRATEGIES {
                for c in 0..self.info.runs {
                    let mut jobs = Vec::new();
                    let calibration = match strategy {
                        "supervisor_source" => Some("calibration_source"),
                        _ => None,
                    };
                    if let Some(cal) = calibration {
                        jobs.extend((0..2 * CALIBRATION_RUNS).map(|k| Job {
                            scenario: format!("{}/{cal}", cond.name),
                            run: c * 2 * CALIBRATION_RUNS + k,
                            seed: self.seed(cond.name, c, true, k),
                        }));
                    }
                    jobs.extend((0..MISSIONS).map(|m| Job {
                        scenario: format!("{}/{strategy}", cond.name),
                        run: c * MISSIONS + m,
                        seed: self.seed(cond.name, c, false, m),
                    }));
                    out.push(Campaign { jobs });
                }
            }
        }
        for strategy in galleries::STRATEGIES {
            for c in 0..self.info.runs {
                let stream = format!("{} campaign {c}", galleries::CONDITION);
                let jobs = (0..galleries::CAMPAIGN_LEGS)
                    .map(|k| Job {
                        scenario: format!("{}/{strategy}", galleries::CONDITION),
                        run: c * galleries::CAMPAIGN_LEGS + k,
                        seed: derive_seed(self.info.seed, &stream, k),
                    })
                    .collect();
                out.push(Campaign { jobs });
            }
        }
        out
    }

    fn run(&self, job: &Job, earlier: &[RunRecord]) -> Result<RunRecord> {
        let done = self.leg(job, earlier, TraceParams::default())?;
        self.record(&done)
    }

    fn replay(&self, job: &Job, earlier: &[RunRecord], trace: TraceParams) -> Result<Replay> {
        let trace = TraceParams {
            enabled: true,
            ..trace
        };
        let done = self.leg(job, earlier, trace)?;
        let record = self.record(&done)?;
        let grid = if job.scenario.starts_with(galleries::CONDITION) {
            self.galleries()?.0.world.grid().clone()
        } else {
            self.world()?.0.grid().clone()
        };
        Ok(Replay {
            record,
            trace: done
                .leg
                .sim
                .and_then(|s| s.trace)
                .context("the mission could not run")?,
            grid,
            goal: Some(done.goal),
            robot_radius_m: sim::RobotParams::jinny().drive.radius_m,
            control_period_s: 0.1,
            net: job
                .scenario
                .ends_with("/supervisor")
                .then(mission::supervisor_net_view)
                .transpose()?,
        })
    }

    fn markers(&self) -> &[EventMarker] {
        &MARKERS
    }

    fn report(&self, ctx: &ReportContext<'_>) -> Result<SuiteReport> {
        report::report(self, ctx)
    }
}

/// Decisions, warnings and pushes on pictures of a mission.
pub const MARKERS: [EventMarker; 3] = [
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
    EventMarker {
        kind: "push",
        marker: sim::render::MarkerKind::Square([200, 0, 0]),
        place: MarkerPlace::Robot,
        single_run_only: false,
    },
];
