//! A batch of museum missions (the tour-guide suite's hall, visitors and
//! mission seeds) with one behaviour alone, for measuring a behaviour
//! without the whole suite:
//!
//! ```text
//! cargo run --release -p lab --example museum_batch -- contour 25 20 [picture_dir]
//! ```
//!
//! Arguments: `automove` or `contour`, visitors, missions; with a folder,
//! a picture of every mission that failed (of every mission with a fifth
//! argument). Mission `m` has the seed of mission `m % 24` of campaign
//! `m / 24` of the suite at that density (25: moderate, 60: packed). Prints
//! one line per mission and the success rate.

use anyhow::{Context, Result, bail};
use guide::Policy;
use guide::supervisor::Behaviour;
use lab::runs::mission::{self, LegOutcome, LegSpec, MissionSetup, PeoplePlan, Stop};
use lab::suites::tourguide::{EXHIBITS, GOAL, MISSION_TIME_LIMIT_S, START, museum};
use sim::TraceParams;

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let behaviour = match args.first().map(String::as_str) {
        Some("automove") => Behaviour::AutoMove,
        Some("contour") | None => Behaviour::Contour,
        Some(other) => bail!("no behaviour `{other}` (automove or contour)"),
    };
    let people: usize = args.get(1).map_or(Ok(25), |s| s.parse()).context("visitors")?;
    let missions: u32 = args.get(2).map_or(Ok(20), |s| s.parse()).context("missions")?;
    let pictures = args.get(3).map(std::path::PathBuf::from);
    let mut setup = MissionSetup::new(museum()?, MISSION_TIME_LIMIT_S);
    setup.prepare()?;
    if people > 0 {
        setup.people = Some(PeoplePlan {
            count: people,
            anchors: EXHIBITS.to_vec(),
            spread_m: 2.5,
            keep_clear_m: 1.0,
        });
    }
    let (mut reached, mut time) = (0, 0.0);
    for m in 0..missions {
        // The suite's seeds: campaign m / 24, mission m % 24 at this density.
        let density = match people {
            0 => "empty",
            25 => "moderate",
            60 => "packed",
            _ => "other",
        };
        let seed = lab::runner::derive_seed(7, &format!("{density} campaign {}", m / 24), m % 24);
        let leg = mission::run_leg(
            &setup,
            &LegSpec {
                from: "start",
                to: "goal",
                start: START,
                believed: START,
                goal: GOAL,
                policy: Policy::Fixed(behaviour),
                seed,
                trace: TraceParams::default(),
            },
        )?;
        let r = &leg.result;
        let asks = leg.trace.events.iter().filter(|e| e.kind == "ask").count();
        println!(
            "mission {m:3} seed {seed:20}: {:?} in {:6.1} s, path {:5.1} m, asked {asks}",
            r.outcome, r.time_s, r.path_m
        );
        if r.outcome == LegOutcome::Reached {
            reached += 1;
            time += r.time_s;
        }
        if let Some(dir) = pictures
            .as_ref()
            .filter(|_| r.outcome != LegOutcome::Reached || args.get(4).is_some())
        {
            std::fs::create_dir_all(dir)?;
            let stops = [
                Stop {
                    name: "start".into(),
                    pose: START,
                },
                Stop {
                    name: "goal".into(),
                    pose: robot::Pose::new(GOAL.x, GOAL.y, 0.0),
                },
            ];
            mission::picture(
                setup.world.grid(),
                &[leg],
                &stops,
                &dir.join(format!("mission_{m}.png")),
            )?;
        }
    }
    println!(
        "reached {reached}/{missions} ({:.0} %), mean time {:.1} s",
        100.0 * f64::from(reached) / f64::from(missions.max(1)),
        if reached > 0 {
            time / f64::from(reached)
        } else {
            f64::NAN
        }
    );
    Ok(())
}
