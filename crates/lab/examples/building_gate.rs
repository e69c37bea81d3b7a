//! The gate of a building for the learning supervisor, from the fixed
//! strategies alone, on any map with places: tours of the places with
//! AutoMove, contour tracking, AutoMove-then-contour and the rule, on
//! common random numbers (leg `k` of tour `t` has the same seed under every
//! strategy), and the hindsight oracle (per leg, the best of them on that
//! leg). How `maps/building_31` was measured before the galleries were
//! designed (`crates/guide/EXPERIMENTS.md`):
//!
//! ```text
//! cargo run --release -p lab --example building_gate -- MAP.yaml PLACES.yaml PEOPLE TOURS [THREADS [ANCHORS.yaml]]
//! ```
//!
//! People gather around the places (or the `ANCHORS.yaml` places), with the
//! physical disturbances of every guide suite. Prints one line per leg and
//! strategy, then per leg the mean cost of each strategy and the oracle,
//! then the tour costs (a failed leg costs the time limit) and the
//! headroom: the oracle against the best single strategy.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use guide::Policy;
use guide::supervisor::Behaviour;
use lab::runs::mission::{self, LegOutcome, LegRun, MissionSetup, Stop};
use lab::tours::{self, GuideOptions};
use rayon::prelude::*;

const STRATEGIES: [&str; 4] = ["automove", "contour", "automove_then_contour", "rule"];

fn policy(name: &str) -> Policy {
    match name {
        "automove" => Policy::Fixed(Behaviour::AutoMove),
        "contour" => Policy::Fixed(Behaviour::Contour),
        "automove_then_contour" => Policy::AutoMoveThenContour,
        _ => Policy::Rule,
    }
}

/// One leg as the gate keeps it.
struct Leg {
    reached: bool,
    cost_s: f64,
    line: String,
}

fn leg(l: &LegRun, limit: f64) -> Leg {
    let count = |k: &str| l.trace.events.iter().filter(|e| e.kind == k).count();
    let dist = |k: &str| l.disturbances.iter().filter(|d| d.kind.name() == k).count();
    let r = &l.result;
    Leg {
        reached: r.outcome == LegOutcome::Reached,
        cost_s: if r.outcome == LegOutcome::Reached {
            r.time_s
        } else {
            limit
        },
        line: format!(
            "{:>24} → {:<24} {:?} {:.1} warn {} ask {} push {} surround {} lost_s {:.0} path {:.1} err {:.2}",
            r.from,
            r.to,
            r.outcome,
            r.time_s,
            count("warning"),
            count("ask"),
            dist("push"),
            dist("surround"),
            r.localization.lost_s,
            r.path_m,
            r.final_error_m
        ),
    }
}

/// The map's setup, its places and where people gather.
fn setup(args: &[String], people: usize) -> Result<(MissionSetup, Vec<Stop>)> {
    let mut options = GuideOptions::new(PathBuf::from(args.first().context("MAP.yaml")?));
    options.goals = Some(PathBuf::from(args.get(1).context("PLACES.yaml")?));
    options.people = people;
    let grid = tours::load_map(&options.map)?;
    let stops: Vec<Stop> = tours::load_places(&options)?
        .context("places")?
        .iter()
        .map(|p| Stop {
            name: p.name.clone(),
            pose: p.pose,
        })
        .collect();
    let anchors: Vec<robot::Vec2> = match args.get(5) {
        Some(f) => sim::Places::load(Path::new(f))?
            .iter()
            .map(|p| p.pose.position())
            .collect(),
        None => stops.iter().map(|s| s.pose.position()).collect(),
    };
    let mut setup = tours::setup(&options, grid, &anchors, stops[0].pose.position())?;
    setup.disturbances = mission::visitor_disturbances(people, &[], 0.0);
    setup.prepare()?;
    Ok((setup, stops))
}

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let people: usize = args.get(2).map_or(Ok(0), |s| s.parse())?;
    let tours_n: u64 = args.get(3).map_or(Ok(4), |s| s.parse())?;
    let threads: usize = args.get(4).map_or(Ok(2), |s| s.parse())?;
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build_global()?;
    let (setup, stops) = setup(&args, people)?;
    let limit = setup.time_limit_s;
    let jobs: Vec<(u64, usize)> = (0..tours_n)
        .flat_map(|t| (0..STRATEGIES.len()).map(move |s| (t, s)))
        .collect();
    // legs[t][s][k]
    let mut legs: Vec<Vec<Vec<Leg>>> = (0..tours_n)
        .map(|_| (0..STRATEGIES.len()).map(|_| Vec::new()).collect())
        .collect();
    let ran: Vec<((u64, usize), Vec<Leg>)> = jobs
        .par_iter()
        .map(|&(t, s)| {
            let run = mission::run_tour(&setup, &stops, policy(STRATEGIES[s]), 1000 + t)?;
            Ok(((t, s), run.iter().map(|l| leg(l, limit)).collect()))
        })
        .collect::<Result<_>>()?;
    for ((t, s), r) in ran {
        for (k, l) in r.iter().enumerate() {
            println!("tour {t} {:>22} leg {k:2} {}", STRATEGIES[s], l.line);
        }
        legs[t as usize][s] = r;
    }
    summarise(&legs, &stops);
    Ok(())
}

/// Per leg and per tour: the strategies' mean costs, the oracle's, the
/// headroom.
fn summarise(legs: &[Vec<Vec<Leg>>], stops: &[Stop]) {
    let n = legs.len() as f64;
    let k_legs = stops.len() - 1;
    let oracle_leg = |t: usize, k: usize| {
        (0..STRATEGIES.len())
            .map(|s| legs[t][s][k].cost_s)
            .fold(f64::INFINITY, f64::min)
    };
    println!("\nper leg, mean cost (s) and successes of {n}:");
    for k in 0..k_legs {
        let mut line = format!("{:>24} → {:<24}", stops[k].name, stops[k + 1].name);
        for (s, name) in STRATEGIES.iter().enumerate() {
            let m: f64 = legs.iter().map(|t| t[s][k].cost_s).sum::<f64>() / n;
            let w = legs.iter().filter(|t| t[s][k].reached).count();
            line += &format!(" {name:>10} {m:6.1} ({w})");
        }
        let o: f64 = (0..legs.len()).map(|t| oracle_leg(t, k)).sum::<f64>() / n;
        println!("{line}  oracle {o:6.1}");
    }
    let tour_cost = |s: usize| {
        legs.iter()
            .map(|t| t[s].iter().map(|l| l.cost_s).sum::<f64>())
            .sum::<f64>()
            / n
    };
    let success = |s: usize| {
        legs.iter()
            .map(|t| t[s].iter().filter(|l| l.reached).count() as f64)
            .sum::<f64>()
            / (n * k_legs as f64)
    };
    let oracle: f64 = (0..legs.len())
        .map(|t| (0..k_legs).map(|k| oracle_leg(t, k)).sum::<f64>())
        .sum::<f64>()
        / n;
    let oracle_success = legs
        .iter()
        .map(|t| (0..k_legs).filter(|&k| t.iter().any(|s| s[k].reached)).count() as f64)
        .sum::<f64>()
        / (n * k_legs as f64);
    println!();
    let mut best = (f64::INFINITY, "");
    let mut best_success = 0.0f64;
    for (s, name) in STRATEGIES.iter().enumerate() {
        println!(
            "{name:>22}: tour cost {:7.1} s, legs reached {:.3}",
            tour_cost(s),
            success(s)
        );
        if tour_cost(s) < best.0 {
            best = (tour_cost(s), name);
        }
        best_success = best_success.max(success(s));
    }
    println!(
        "{:>22}: tour cost {oracle:7.1} s, legs reached {oracle_success:.3}",
        "oracle"
    );
    println!(
        "headroom: {:.1} % of the best fixed tour cost ({}), {:+.3} in success",
        100.0 * (best.0 - oracle) / best.0,
        best.1,
        oracle_success - best_success
    );
}
