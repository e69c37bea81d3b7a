//! The maps suite: the tour-guide robot on the two real SLAM maps of
//! `maps/`, touring their places (`places.yaml`) with AutoMove and with
//! contour tracking, among 0, 20 and 60 people.
//!
//! A *tour* is a campaign: its legs run in sequence, each starting where the
//! last one stopped, the localizer from the last one's estimate (the state a
//! record carries in `state`). Tour `t` meets the same noise streams in every
//! scenario of its map (common random numbers: the behaviours and crowds are
//! compared on the same draws). Scenarios are named `MAP/BEHAVIOUR/Np`.
//!
//! After a leg that ends without arriving (collision, time-out, lost, no route), the
//! next starts at the place it was heading for, the robot put there by its
//! operator ([`crate::runs::mission`]'s decision), so that one failure does not
//! cascade through the rest of the tour (figures before and after:
//! `crates/lab/EXPERIMENTS.md`).
//!
//! Per leg it records the common measures and, as metrics, the localizer's
//! true error (`loc_mean_error_m`, `loc_max_error_m`), its warnings
//! (`warnings`, `time_in_warning_s`) and AutoMove's abnormal episodes
//! (`abnormal_episodes`, `time_abnormal_s`). The report puts side by side,
//! per map, what crowds do to the localizer and to each behaviour, and
//! explains it from the numbers. Its pictures draw each scenario's first
//! tour; under each, one link per leg opens the tour's viewer page at that
//! leg (`viewer/MAP-BEHAVIOUR-Np.html#run=K`, leg K + 1; a leg not run
//! because the robot was lost before it has none). The pages hold every
//! tick's laser scan, crowd and particle cloud: about 0.25–0.3 MB per
//! minute of a leg, 44 MB for the suite's twelve tours (the largest, contour
//! tracking among 60 people with six 300 s time-outs, 11 MB).

mod explanation;

use std::collections::BTreeMap;
use std::sync::OnceLock;

use anyhow::{Context, Result, bail};
use guide::Policy;
use guide::supervisor::Behaviour;
use sim::{CrowdParams, Places, TraceParams, World};

use crate::page::{Block, Figure, RunLink};
use crate::pictures::{EventMarker, Replay};
use crate::record::RunRecord;
use crate::runner::{Campaign, Job, derive_seed};
use crate::runs::mission::{self, LegRun, LegSpec, MissionSetup, PeoplePlan, Stop, Whereabouts};
use crate::suite::{Registration, ReportContext, Suite, SuiteArgs, SuiteInfo, SuiteReport};
use crate::tables::{self, MetricColumn};
use crate::viewer::PageRun;

/// A leg's record and replay, its metric names and markers: shared with
/// `petrinav nav go` (in [`crate::runs::mission`]).
pub use crate::runs::mission::{MARKERS, leg_record, leg_replay, metric};

/// The suite in the registry.
pub const REGISTRATION: Registration = Registration {
    name: "maps",
    about: "the tour-guide robot touring the places of two real SLAM maps: AutoMove and contour tracking among 0, 20, 60 people",
    build,
};

/// The maps, as shipped in the repository's `maps/`.
pub const MAPS: [&str; 2] = ["building_31", "levine"];

/// The maps' files, compiled in (map_server YAML, PNG, places), so that the
/// suite runs from anywhere.
const FILES: [(&str, &[u8], &str); 2] = [
    (
        include_str!("../../../../../maps/building_31/building_31.yaml"),
        include_bytes!("../../../../../maps/building_31/building_31.png"),
        include_str!("../../../../../maps/building_31/places.yaml"),
    ),
    (
        include_str!("../../../../../maps/levine/levine.yaml"),
        include_bytes!("../../../../../maps/levine/levine.png"),
        include_str!("../../../../../maps/levine/places.yaml"),
    ),
];

/// Crowd sizes.
pub const CROWDS: [usize; 3] = [0, 20, 60];

/// The behaviours compared.
pub const BEHAVIOURS: [(Behaviour, &str); 2] =
    [(Behaviour::AutoMove, "automove"), (Behaviour::Contour, "contour")];

/// Tours per scenario by default.
pub const DEFAULT_TOURS: u32 = 3;

/// Base seed.
pub const SEED: u64 = 11;

/// Time limit of a leg, seconds.
pub const LEG_TIME_LIMIT_S: f64 = 300.0;

/// One map: its world (with the crowd's waypoints), places, and a leg's
/// setup without people, the map prepared for the guide controller once.
struct MapData {
    world: World,
    stops: Vec<Stop>,
    setup: MissionSetup,
}

fn load_map(k: usize) -> Result<MapData> {
    let name = MAPS[k];
    let (yaml, png, places) = FILES[k];
    let yaml = sim::map_server::parse_yaml(yaml, &format!("maps/{name}/{name}.yaml"))?;
    let pixels = sim::map_server::decode_image(png).map_err(anyhow::Error::msg)?;
    let (grid, _) = sim::map_server::grid_from_pixels(&yaml, &pixels)?;
    let places = Places::parse(places, &format!("maps/{name}/places.yaml"))?;
    let stops: Vec<Stop> = places
        .iter()
        .map(|p| Stop {
            name: p.name.clone(),
            pose: p.pose,
        })
        .collect();
    let world = World::new(grid).with_crowd(CrowdParams {
        waypoints: stops.iter().map(|s| s.pose.position()).collect(),
        gather_radius_m: 1.5,
        ..CrowdParams::default()
    })?;
    let mut setup = MissionSetup::new(world.clone(), LEG_TIME_LIMIT_S);
    setup.prepare()?;
    Ok(MapData { world, stops, setup })
}

/// A scenario: map, behaviour, crowd.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Scenario {
    map: usize,
    behaviour: usize,
    people: usize,
}

impl Scenario {
    fn name(&self) -> String {
        format!(
            "{}/{}/{}p",
            MAPS[self.map], BEHAVIOURS[self.behaviour].1, CROWDS[self.people]
        )
    }
}

/// The maps suite (module docs).
pub struct MapsSuite {
    info: SuiteInfo,
    scenarios: Vec<Scenario>,
    maps: [OnceLock<Result<MapData, String>>; 2],
}

fn build(args: &SuiteArgs) -> Result<Box<dyn Suite>> {
    Ok(Box::new(MapsSuite::new(args.runs.unwrap_or(DEFAULT_TOURS))?))
}

impl MapsSuite {
    /// The suite with `tours` tours per scenario.
    pub fn new(tours: u32) -> Result<MapsSuite> {
        if tours == 0 {
            bail!("the maps suite needs at least one tour per scenario");
        }
        let mut scenarios = Vec::new();
        for map in 0..MAPS.len() {
            for behaviour in 0..BEHAVIOURS.len() {
                for people in 0..CROWDS.len() {
                    scenarios.push(Scenario {
                        map,
                        behaviour,
                        people,
                    });
                }
            }
        }
        Ok(MapsSuite {
            info: SuiteInfo {
                name: REGISTRATION.name.into(),
                suite: REGISTRATION.name.into(),
                runs: tours,
                seed: SEED,
                scenarios: scenarios.iter().map(Scenario::name).collect(),
                sources: BTreeMap::new(),
            },
            scenarios,
            maps: [OnceLock::new(), OnceLock::new()],
        })
    }

    fn map(&self, k: usize) -> Result<&MapData> {
        self.maps[k]
            .get_or_init(|| load_map(k).map_err(|e| format!("{e:#}")))
            .as_ref()
            .map_err(|e| anyhow::anyhow!("{e}"))
    }

    fn scenario(&self, name: &str) -> Result<Scenario> {
        self.scenarios
            .iter()
            .copied()
            .find(|s| s.name() == name)
            .with_context(|| format!("no scenario `{name}` in the maps suite"))
    }

    /// Legs per tour on map `k`.
    fn legs(&self, k: usize) -> Result<u32> {
        Ok(self.map(k)?.stops.len().saturating_sub(1) as u32)
    }

    /// Runs leg `job.run` of its tour; returns it with where the robot was
    /// before it.
    fn leg(&self, job: &Job, earlier: &[RunRecord], trace: TraceParams) -> Result<(LegRun, Whereabouts)> {
        let s = self.scenario(&job.scenario)?;
        let data = self.map(s.map)?;
        let legs = self.legs(s.map)?;
        let k = (job.run % legs) as usize;
        if earlier.len() != k {
            bail!("leg {k} of its tour got {} earlier legs", earlier.len());
        }
        let here = match earlier.last() {
            None => Whereabouts::at(&data.stops[0]),
            Some(r) => serde_json::from_value(r.state.clone().context("an earlier leg without its state")?)
                .context("the state of an earlier leg")?,
        };
        let mut setup = data.setup.clone();
        // Visitors push the standing robot and close round it as in the
        // museum (no slip patches on these maps).
        setup.disturbances = mission::visitor_disturbances(CROWDS[s.people], &[], 0.0);
        if CROWDS[s.people] > 0 {
            setup.people = Some(PeoplePlan {
                count: CROWDS[s.people],
                anchors: data.stops.iter().map(|p| p.pose.position()).collect(),
                spread_m: 4.0,
                keep_clear_m: 1.0,
            });
        }
        let to = &data.stops[k + 1];
        let leg = mission::run_leg(
            &setup,
            &LegSpec {
                from: &here.name,
                to: &to.name,
                start: here.pose,
                believed: here.estimate,
                goal: to.pose.position(),
                policy: Policy::Fixed(BEHAVIOURS[s.behaviour].0),
                seed: job.seed,
                trace,
            },
        )?;
        Ok((leg, here))
    }

    /// The record of a leg run from `before`.
    fn record(&self, job: &Job, leg: &LegRun, before: &Whereabouts) -> Result<RunRecord> {
        let s = self.scenario(&job.scenario)?;
        let data = self.map(s.map)?;
        let k = (job.run % self.legs(s.map)?) as usize;
        let after = before.after(leg, &data.stops[k + 1]);
        let mut record = leg_record(leg)?;
        record.state = Some(serde_json::to_value(&after)?);
        Ok(record)
    }
}

impl Suite for MapsSuite {
    fn info(&self) -> &SuiteInfo {
        &self.info
    }

    fn campaigns(&self) -> Vec<Campaign> {
        let mut out = Vec::new();
        for s in &self.scenarios {
            let Ok(legs) = self.legs(s.map) else {
                continue;
            };
            for tour in 0..self.info.runs {
                let stream = format!("{} tour {tour}", MAPS[s.map]);
                out.push(Campaign {
                    jobs: (0..legs)
                        .map(|leg| Job {
                            scenario: s.name(),
                            run: tour * legs + leg,
                            seed: derive_seed(self.info.seed, &stream, leg),
                        })
                        .collect(),
                });
            }
        }
        out
    }

    fn run(&self, job: &Job, earlier: &[RunRecord]) -> Result<RunRecord> {
        let (leg, before) = self.leg(job, earlier, TraceParams::default())?;
        self.record(job, &leg, &before)
    }

    fn replay(&self, job: &Job, earlier: &[RunRecord], trace: TraceParams) -> Result<Replay> {
        let trace = TraceParams {
            enabled: true,
            ..trace
        };
        let (mut leg, before) = self.leg(job, earlier, trace)?;
        self.replay_of(job, &mut leg, &before)
    }

    fn markers(&self) -> &[EventMarker] {
        &MARKERS
    }

    fn report(&self, ctx: &ReportContext<'_>) -> Result<SuiteReport> {
        let columns = [
            MetricColumn {
                metric: metric::LOC_MEAN,
                heading: "true error (m)",
                short: "err(m)",
                decimals: 3,
            },
            MetricColumn {
                metric: metric::WARNINGS,
                heading: "warnings/leg",
                short: "warnings",
                decimals: 2,
            },
            MetricColumn {
                metric: metric::WARNING_S,
                heading: "in Warning (s/leg)",
                short: "warn(s)",
                decimals: 1,
            },
            MetricColumn {
                metric: metric::ABNORMAL_S,
                heading: "Abnormal (s/leg)",
                short: "abn(s)",
                decimals: 1,
            },
        ];
        let (text, table) = tables::generic_table(ctx.summaries, &columns);
        let mut blocks = vec![Block::Table(table)];
        blocks.extend(explanation::explanation(ctx.summaries, ctx.runs));
        blocks.extend(explanation::warning_against_loss(ctx.runs));
        let mut files = Vec::new();
        if ctx.pictures {
            let mut figures = Vec::new();
            for s in &self.scenarios {
                let name = s.name();
                let data = self.map(s.map)?;
                let (path, src) = ctx.picture_path(&format!("{}.png", name.replace('/', "-")))?;
                let (legs, replays) = self.first_tour(s, ctx)?;
                mission::picture(data.world.grid(), &legs, &data.stops, &path)?;
                files.push(path);
                // Every leg of the tour in the viewer, one page (`#run=K`
                // opens leg K + 1).
                let page_runs: Vec<PageRun<'_>> = replays
                    .iter()
                    .map(|(_, key, replay)| PageRun { replay, key })
                    .collect();
                let mut runs = Vec::new();
                if !page_runs.is_empty() {
                    let (page, href) = ctx.viewer_runs_page(&page_runs, self.markers(), &name)?;
                    files.push(page);
                    runs = replays
                        .iter()
                        .enumerate()
                        .map(|(k, (leg, _, _))| RunLink {
                            label: format!("leg {leg}"),
                            href: format!("{href}#run={k}"),
                        })
                        .collect();
                }
                figures.push(Figure {
                    title: name,
                    src,
                    runs,
                });
            }
            blocks.push(Block::Figures {
                heading: "The first tour of each scenario".into(),
                caption: "Re-simulated from their seeds: the true trajectory of every leg coloured by the behaviour and the localizer's state (automove, contour, asking people to step aside, in Warning), the particle cloud (teal) at each warning, the places in tour order. Under each picture, one link per leg opens the tour's viewer page at that leg (laser, crowd, the particle cloud at every filter iteration).".into(),
                figures,
            });
        }
        Ok(SuiteReport {
            text,
            intro: Some(format!(
                "{} tours of every map's places per scenario (a leg from each place to the next: the rows count legs; after a leg that collided, timed out, got lost or had no route, the operator takes the robot to the place it was heading for and gives it its pose there), base seed {}.",
                self.info.runs, self.info.seed
            )),
            blocks,
            files,
        })
    }
}

/// A leg's replay: its number in the tour (from 1), its key, the replay.
type LegReplay = (usize, String, Replay);

impl MapsSuite {
    /// The legs of the first tour of `s`, re-run with full traces from the
    /// records on file, and the replays of the legs that ran (for the
    /// viewer), with their leg numbers from 1.
    fn first_tour(&self, s: &Scenario, ctx: &ReportContext<'_>) -> Result<(Vec<LegRun>, Vec<LegReplay>)> {
        let campaign = self
            .campaigns()
            .into_iter()
            .find(|c| c.jobs.first().is_some_and(|j| j.scenario == s.name()))
            .context("no tour")?;
        let on_file: BTreeMap<u32, &RunRecord> = ctx
            .runs
            .get(&s.name())
            .map(|v| v.iter().map(|(k, r)| (*k, r)).collect())
            .unwrap_or_default();
        let mut earlier: Vec<RunRecord> = Vec::new();
        let mut legs = Vec::new();
        let mut replays = Vec::new();
        for job in &campaign.jobs {
            let Some(&recorded) = on_file.get(&job.run) else {
                break;
            };
            let (mut leg, before) = self.leg(job, &earlier, TraceParams::full())?;
            // A leg not run (the robot was lost before it) has no trace.
            if leg.sim.is_some() {
                replays.push((legs.len() + 1, job.key(), self.replay_of(job, &mut leg, &before)?));
            }
            legs.push(leg);
            earlier.push(recorded.clone());
        }
        Ok((legs, replays))
    }

    /// The replay of `leg`, run from `before` with a trace (taken out of
    /// the leg).
    fn replay_of(&self, job: &Job, leg: &mut LegRun, before: &Whereabouts) -> Result<Replay> {
        let record = self.record(job, leg, before)?;
        let s = self.scenario(&job.scenario)?;
        let data = self.map(s.map)?;
        let k = (job.run % self.legs(s.map)?) as usize;
        leg_replay(record, &data.setup, leg, data.stops[k + 1].pose.position())
    }
}
