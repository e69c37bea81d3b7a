//! The topological-map suite (docs/topo-fpn.md, "Experiments"): a robot with
//! only a ring of 16 sonars and odometry explores an office, builds its
//! fuzzy Petri net from its own stops, and then drives routes between the
//! places it knows — with the map, and, for comparison, by wall following
//! alone; the true grid's shortest path is the bound neither can reach.
//!
//! Worlds (design in `office.toml`'s header and [`floor`]):
//!
//! | world | what | exploration |
//! |---|---|---|
//! | `office` | 10 m × 5 m (50 m², the source's size): a corridor, three rooms with doors, furniture | 600 s |
//! | `floor` | a generated office floor of 20 m × 18 m: two corridors, 16 rooms with 1 m doors and a table each, a hall between the corridors | 1,800 s |
//! | `office_slips` | the office, with the simulator's default odometry (large wheel slips) | 600 s |
//!
//! A **campaign** is one exploration and then [`ROUTES`] routes on its map:
//! job 0 (`WORLD/explore`) explores and keeps the map and the true pose of
//! every place in its record's `state`; then, for each route `k`, a pair
//! of distinct places with a planned route is drawn from the campaign's
//! seed, and `WORLD/map` drives it with the map (the map it learnt on
//! earlier routes: thresholds lowered by failures, places added), and
//! `WORLD/wall_following` drives the same pair by right-hand wall
//! following. Both start at the true pose where the start place was
//! recorded and meet the same simulator noise (common random numbers).
//! The judging is [`crate::runs::topo`]'s: recognition against true poses,
//! arrival within 0.5 m of where the goal place was recorded, and every
//! leg of a route by the map against where the planned place truly is
//! (a `leg` event per leg in the route's record: the places, the true
//! poses at its start and end, whether it truly ended at the planned
//! place), from which the report counts the failures' causes.
//!
//! **Decision — exploration time.** 600 s in the office (about 100 m of
//! driving, 23 stops). Rejected: longer explorations (1,200 s, 1,800 s),
//! because each place approached from another heading is another place,
//! so the map keeps growing, routes get longer, and every extra
//! transition on a route is another chance of a surprise: routes by the
//! map arrived less often (`crates/lab/EXPERIMENTS.md`).
//!
//! **Decision — connectivity, reported both ways.** A net is *connected*
//! when its graph, arcs taken either way, is in one piece, and *strongly
//! connected* when every place can reach every other (Murata 1989's two
//! notions; [`crate::runs::topo::connectivity`]). The report gives both, and the
//! share of the places in the largest strongly connected part, because
//! neither alone says what the map is worth: an exploration is one walk,
//! so its net is connected unless a leg failed (the robot then starts
//! again from nowhere known), while the first places (met from wherever
//! the robot happened to start) and the last ones (found just before the
//! time ran out) are rarely reached again, so a whole net is seldom
//! strongly connected. The `explore` rows' `I_R` stays the strong
//! notion (figures: `crates/lab/EXPERIMENTS.md`).
//!
//! **Decision — the odometry** is calibrated (slips of σ 1 % per wheel and
//! step, no large slips; [`crate::runs::topo`]'s docs), as in the dead-lock
//! suite's main rows; `office_slips` repeats the office with the
//! simulator's default odometry, whose large slips drift the robot by a
//! metre over one corridor — the reason for the source's concave places.

mod report;

use std::collections::BTreeMap;
use std::sync::OnceLock;

use ::topo::{FuzzyPetriNet, NavigateParams, PlaceId, TopoParams};
use anyhow::{Context, Result, bail};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use robot::{Event, Pose};
use sim::{TraceParams, World};

use crate::pictures::{EventMarker, Replay};
use crate::record::RunRecord;
use crate::runner::{Campaign, Job, derive_seed};
use crate::runs::topo::{self, ExploreSpec, RouteMethod, RouteOutcome, RouteSpec};
use crate::suite::{Registration, ReportContext, Suite, SuiteArgs, SuiteInfo, SuiteReport};

/// The worlds, shared with `petrinav topo explore / go` (in [`crate::runs::topo`]).
pub use crate::runs::topo::{OFFICE, WORLDS, floor, office};

/// The suite in the registry.
pub const REGISTRATION: Registration = Registration {
    name: "topo",
    about: "topological maps as fuzzy Petri nets: a sonar-ring robot explores two offices, then drives routes between known places with its map, against wall following and the grid's shortest path",
    build,
};

/// The robot of world `w`.
fn robot_of(w: usize) -> sim::RobotParams {
    if WORLDS[w].0.ends_with("_slips") {
        topo::slipping_robot()
    } else {
        topo::robot()
    }
}

/// Routes per exploration.
pub const ROUTES: u32 = 10;

/// Explorations per world by default.
pub const DEFAULT_EXPLORATIONS: u32 = 10;

/// Time limit of a route, seconds.
pub const ROUTE_TIME_LIMIT_S: f64 = 300.0;

/// Base seed.
pub const SEED: u64 = 13;

/// The ways a route is driven, in the report's order.
pub const METHODS: [&str; 2] = ["map", "wall_following"];

/// Metric names.
pub mod metric {
    /// Places of the map after exploring.
    pub const PLACES: &str = "places";
    /// Transitions of the map after exploring.
    pub const TRANSITIONS: &str = "transitions";
    /// Stops at reference places while exploring.
    pub const STOPS: &str = "stops";
    /// 1 when the map is connected (its graph in one piece, arcs taken
    /// either way), else 0.
    pub const CONNECTED: &str = "connected";
    /// The share of the map's places in its largest strongly connected
    /// part.
    pub const STRONG_SHARE: &str = "largest_strong_share";
    /// Recognition: true positives.
    pub const TP: &str = "recognition_tp";
    /// Recognition: false positives.
    pub const FP: &str = "recognition_fp";
    /// Recognition: false negatives.
    pub const FN: &str = "recognition_fn";
    /// Recognition: true negatives.
    pub const TN: &str = "recognition_tn";
    /// Odometry recalibrations at concave places.
    pub const RECALIBRATIONS: &str = "recalibrations";
    /// Legs that found no place.
    pub const FAILED_LEGS: &str = "failed_legs";
    /// Transitions of the route first planned.
    pub const PLANNED: &str = "planned_transitions";
    /// Legs driven (transitions taken).
    pub const LEGS: &str = "legs";
    /// Legs that ended where the plan did not say.
    pub const REPLANS: &str = "replans";
    /// Places with no route onward (an untried action played).
    pub const NO_ROUTE: &str = "no_route";
    /// The shortest path on the true grid, metres.
    pub const SHORTEST_M: &str = "shortest_path_m";
    /// The shortest path's time at free movement's cruise speed, seconds.
    pub const BOUND_S: &str = "bound_time_s";
    /// The start place's id.
    pub const FROM: &str = "from_place";
    /// The goal place's id.
    pub const TO: &str = "to_place";
}

/// What a campaign's later runs need from its exploration.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
struct Explored {
    /// The map as a map file (JSON).
    map: String,
    /// The true pose where each place was recorded.
    truth: Vec<[f64; 3]>,
}

/// What a route by the map hands on: the map it learnt.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
struct Learnt {
    map: String,
}

/// What a job is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    Explore,
    /// Route `k` of its campaign, by method `m`.
    Route(u32, usize),
}

/// The topological suite (module docs).
pub struct TopoSuite {
    info: SuiteInfo,
    worlds: [OnceLock<Result<World, String>>; 3],
}

fn build(args: &SuiteArgs) -> Result<Box<dyn Suite>> {
    Ok(Box::new(TopoSuite::new(
        args.runs.unwrap_or(DEFAULT_EXPLORATIONS),
    )?))
}

impl TopoSuite {
    /// The suite with `explorations` explorations (campaigns) per world.
    pub fn new(explorations: u32) -> Result<TopoSuite> {
        if explorations == 0 {
            bail!("the topological suite needs at least one exploration per world");
        }
        let mut scenarios = Vec::new();
        for (w, _, _) in WORLDS {
            scenarios.push(format!("{w}/explore"));
            for m in METHODS {
                scenarios.push(format!("{w}/{m}"));
            }
        }
        Ok(TopoSuite {
            info: SuiteInfo {
                name: REGISTRATION.name.into(),
                suite: REGISTRATION.name.into(),
                runs: explorations,
                seed: SEED,
                scenarios,
                sources: BTreeMap::new(),
            },
            worlds: [OnceLock::new(), OnceLock::new(), OnceLock::new()],
        })
    }

    fn world(&self, w: usize) -> Result<&World> {
        self.worlds[w]
            .get_or_init(|| {
                let made = if w == 1 { floor() } else { office() };
                made.map_err(|e| format!("{e:#}"))
            })
            .as_ref()
            .map_err(|e| anyhow::anyhow!("{e}"))
    }

    /// The grid of the world named `name`.
    fn world_grid(&self, name: &str) -> Result<&sim::OccupancyGrid> {
        let w = WORLDS
            .iter()
            .position(|(n, _, _)| *n == name)
            .with_context(|| format!("no world `{name}`"))?;
        Ok(self.world(w)?.grid())
    }

    fn parse(&self, job: &Job) -> Result<(usize, Kind)> {
        let (world, what) = job
            .scenario
            .split_once('/')
            .with_context(|| format!("`{}` is not a scenario of the topological suite", job.scenario))?;
        let w = WORLDS
            .iter()
            .position(|(n, _, _)| *n == world)
            .with_context(|| format!("no world `{world}`"))?;
        let kind = if what == "explore" {
            Kind::Explore
        } else {
            let m = METHODS
                .iter()
                .position(|n| *n == what)
                .with_context(|| format!("no method `{what}`"))?;
            Kind::Route(job.run % ROUTES, m)
        };
        Ok((w, kind))
    }

    /// The exploration of a campaign, and the map to drive with (the last
    /// one a route by the map learnt, or the explored one).
    fn campaign_state(earlier: &[RunRecord]) -> Result<(FuzzyPetriNet, FuzzyPetriNet, Vec<Pose>)> {
        let first = earlier.first().context("a route without its exploration")?;
        let explored: Explored =
            serde_json::from_value(first.state.clone().context("an exploration without its map")?)
                .context("the exploration's state")?;
        let map = FuzzyPetriNet::from_json(&explored.map).context("the explored map")?;
        let truth = explored
            .truth
            .iter()
            .map(|p| Pose::new(p[0], p[1], p[2]))
            .collect();
        let mut current = map.clone();
        for r in earlier[1..].iter().rev() {
            if let Some(state) = &r.state
                && let Ok(l) = serde_json::from_value::<Learnt>(state.clone())
            {
                current = FuzzyPetriNet::from_json(&l.map).context("a learnt map")?;
                break;
            }
        }
        Ok((map, current, truth))
    }

    /// The pair of route `k`: drawn among the explored map's pairs with a
    /// route, from the campaign's seed (the same for both methods).
    fn pair(&self, w: usize, campaign: u32, k: u32, map: &FuzzyPetriNet) -> Result<(PlaceId, PlaceId)> {
        let pairs = topo::routable_pairs(map);
        if pairs.is_empty() {
            bail!("the explored map has no pair of places with a route");
        }
        let seed = derive_seed(self.info.seed, &format!("{} pairs {campaign}", WORLDS[w].0), k);
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        Ok(pairs[rng.random_range(0..pairs.len())])
    }

    fn explore_record(
        &self,
        w: usize,
        job: &Job,
        trace: TraceParams,
    ) -> Result<(RunRecord, topo::Exploration)> {
        let (_, time_s, start) = WORLDS[w];
        let e = topo::explore(
            self.world(w)?,
            &ExploreSpec {
                params: TopoParams::default(),
                start,
                time_s,
                seed: job.seed,
                trace,
                robot: robot_of(w),
            },
        )?;
        let c = topo::connectivity(&e.map);
        let strong = c.strongly_connected();
        let mut record = base_record(&e.result, strong, if strong { "goal" } else { "gave_up" });
        record.set_metric(metric::CONNECTED, if c.connected { 1.0 } else { 0.0 })?;
        record.set_metric(
            metric::STRONG_SHARE,
            c.largest_strong as f64 / c.places.max(1) as f64,
        )?;
        record.set_metric(metric::PLACES, e.map.num_places() as f64)?;
        record.set_metric(metric::TRANSITIONS, e.map.num_transitions() as f64)?;
        record.set_metric(metric::STOPS, e.visits.len() as f64)?;
        let r = e.recognition;
        record.set_metric(metric::TP, f64::from(r.true_positives))?;
        record.set_metric(metric::FP, f64::from(r.false_positives))?;
        record.set_metric(metric::FN, f64::from(r.false_negatives))?;
        record.set_metric(metric::TN, f64::from(r.true_negatives))?;
        record.set_metric(metric::RECALIBRATIONS, f64::from(e.recalibrations))?;
        record.set_metric(metric::FAILED_LEGS, f64::from(e.failures))?;
        record.events = e
            .visits
            .iter()
            .zip(&e.growth)
            .map(|((v, truth), g)| {
                Event::new("stop", v.time_s)
                    .at(v.map_pose.position())
                    .with("place", e.map.place(v.place).name.clone())
                    .with("new", v.new)
                    .with("places", g.places as f64)
                    .with("transitions", g.transitions as f64)
                    .with("true_x_m", truth.x_m)
                    .with("true_y_m", truth.y_m)
            })
            .collect();
        record.state = Some(serde_json::to_value(Explored {
            map: e.map.to_json(),
            truth: e.truth.iter().map(|p| [p.x_m, p.y_m, p.theta_rad]).collect(),
        })?);
        Ok((record, e))
    }

    fn route_record(
        &self,
        w: usize,
        k: u32,
        m: usize,
        job: &Job,
        earlier: &[RunRecord],
        trace: TraceParams,
    ) -> Result<(RunRecord, topo::RouteRun)> {
        let (explored, current, truth) = Self::campaign_state(earlier)?;
        let campaign = job.run / ROUTES;
        let (from, to) = self.pair(w, campaign, k, &explored)?;
        let world = self.world(w)?;
        let params = NavigateParams::default();
        let method = if METHODS[m] == "map" {
            RouteMethod::Map(params)
        } else {
            RouteMethod::WallFollowing(params.topo.strategy)
        };
        let run = topo::route(
            world,
            &RouteSpec {
                map: &current,
                truth: &truth,
                from,
                to,
                method,
                time_limit_s: ROUTE_TIME_LIMIT_S,
                seed: job.seed,
                trace,
                robot: robot_of(w),
            },
        )?;
        let outcome = match run.outcome {
            RouteOutcome::Reached => "goal",
            RouteOutcome::WrongPlace => "lost",
            RouteOutcome::TimeLimit => "time_limit",
            RouteOutcome::GaveUp => "gave_up",
        };
        let mut record = base_record(&run.result, run.outcome == RouteOutcome::Reached, outcome);
        record.goal_distance_m = run.final_distance_m;
        let robot_radius = topo::robot().drive.radius_m;
        let (a, b) = (truth[from.0 as usize].position(), truth[to.0 as usize].position());
        let shortest = topo::shortest_path_m(world.grid(), a, b, robot_radius);
        if let Some(d) = shortest {
            record.set_metric(metric::SHORTEST_M, d)?;
            record.set_metric(metric::BOUND_S, d / params.topo.strategy.cruise_mps)?;
        }
        record.set_metric(metric::FROM, f64::from(from.0))?;
        record.set_metric(metric::TO, f64::from(to.0))?;
        if let Some(plan) = &run.plan {
            record.set_metric(metric::PLANNED, plan.route.len() as f64)?;
        }
        if let Some(s) = run.stats {
            record.set_metric(metric::LEGS, f64::from(s.legs))?;
            record.set_metric(metric::REPLANS, f64::from(s.replans))?;
            record.set_metric(metric::NO_ROUTE, f64::from(s.no_route))?;
            record.set_metric(metric::FAILED_LEGS, f64::from(s.failed_legs))?;
        }
        if let Some(map) = &run.map {
            record.state = Some(serde_json::to_value(Learnt { map: map.to_json() })?);
        }
        let name = |p: PlaceId| format!("p{}", p.0 + 1);
        record.events = run
            .legs
            .iter()
            .map(|l| {
                let mut e = Event::new("leg", l.time_s)
                    .at(l.end.position())
                    .with("arrived", name(l.arrived))
                    .with("new", l.new)
                    .with("as_planned", l.as_planned)
                    .with("true_x_m", l.end.x_m)
                    .with("true_y_m", l.end.y_m)
                    .with("true_heading_rad", l.end.theta_rad)
                    .with("start_x_m", l.start.x_m)
                    .with("start_y_m", l.start.y_m)
                    .with("start_heading_rad", l.start.theta_rad);
                if let Some(p) = l.from {
                    e = e.with("from", name(p));
                }
                if let Some(p) = l.planned_to {
                    e = e.with("planned_to", name(p));
                }
                if let Some(b) = l.truly_at_planned {
                    e = e.with("truly_at_planned", b);
                }
                if let Some(b) = l.started_at_origin {
                    e = e.with("started_at_origin", b);
                }
                e
            })
            .collect();
        Ok((record, run))
    }
}

/// A record from a run's summary, with the suite's success and outcome.
fn base_record(r: &sim::RunResult, success: bool, outcome: &str) -> RunRecord {
    RunRecord {
        success,
        outcome: outcome.to_string(),
        time_s: r.time_s,
        path_length_m: r.path_length_m,
        collisions: r.collisions,
        min_clearance_m: r.min_clearance_m,
        odometry_error_m: r.odometry_error_m,
        goal_distance_m: r.goal_distance_m.unwrap_or(f64::NAN).max(0.0),
        ticks: r.ticks,
        behaviour_ticks: BTreeMap::new(),
        metrics: BTreeMap::new(),
        events: Vec::new(),
        start: [r.final_pose.x_m, r.final_pose.y_m, r.final_pose.theta_rad],
        trap: None,
        state: None,
    }
}

impl Suite for TopoSuite {
    fn info(&self) -> &SuiteInfo {
        &self.info
    }

    fn campaigns(&self) -> Vec<Campaign> {
        let mut out = Vec::new();
        for (world, _, _) in WORLDS {
            for c in 0..self.info.runs {
                let stream = format!("{world} campaign {c}");
                let mut jobs = vec![Job {
                    scenario: format!("{world}/explore"),
                    run: c,
                    seed: derive_seed(self.info.seed, &stream, 0),
                }];
                for k in 0..ROUTES {
                    // Both methods meet the same noise on route k.
                    let seed = derive_seed(self.info.seed, &stream, 1 + k);
                    for m in METHODS {
                        jobs.push(Job {
                            scenario: format!("{world}/{m}"),
                            run: c * ROUTES + k,
                            seed,
                        });
                    }
                }
                out.push(Campaign { jobs });
            }
        }
        out
    }

    fn run(&self, job: &Job, earlier: &[RunRecord]) -> Result<RunRecord> {
        let (w, kind) = self.parse(job)?;
        Ok(match kind {
            Kind::Explore => self.explore_record(w, job, TraceParams::default())?.0,
            Kind::Route(k, m) => {
                self.route_record(w, k, m, job, earlier, TraceParams::default())?
                    .0
            }
        })
    }

    fn replay(&self, job: &Job, earlier: &[RunRecord], trace: TraceParams) -> Result<Replay> {
        let trace = TraceParams {
            enabled: true,
            ..trace
        };
        let (w, kind) = self.parse(job)?;
        let (record, run_trace, goal) = match kind {
            Kind::Explore => {
                let (r, e) = self.explore_record(w, job, trace)?;
                (r, e.trace, None)
            }
            Kind::Route(k, m) => {
                let (r, run) = self.route_record(w, k, m, job, earlier, trace)?;
                let (_, _, truth) = Self::campaign_state(earlier)?;
                let to = r.metric(metric::TO).unwrap_or(0.0) as usize;
                (r, run.trace, truth.get(to).map(|p| p.position()))
            }
        };
        Ok(Replay {
            record,
            trace: run_trace.context("the run kept no trace")?,
            grid: self.world(w)?.grid().clone(),
            goal,
            robot_radius_m: topo::robot().drive.radius_m,
            control_period_s: 0.1,
            net: None,
        })
    }

    fn markers(&self) -> &[EventMarker] {
        &MARKERS
    }

    fn report(&self, ctx: &ReportContext<'_>) -> Result<SuiteReport> {
        report::report(self, ctx)
    }
}

/// Stops drawn on `lab replay` pictures: new places orange, recognised
/// ones purple, at the robot.
const MARKERS: [EventMarker; 0] = [];
