//! How well the scan-consistency score ([`localization::consistency`])
//! tells a wrong pose from a right one among museum visitors:
//!
//! ```text
//! cargo run --release -p lab --example status_roc -- 60 6
//! ```
//!
//! Arguments: visitors, missions (the tour-guide suite's seeds at that
//! density), then optionally the hit distance, the through tolerance and
//! its growth per metre (0.1 m, 0.25 m, 0.035 rad). Each mission is driven by AutoMove with its scans recorded;
//! every tenth tick the scan is scored at the localizer's estimate (plain
//! tracking: the source's status rule, no recovery), at the true pose and at poses off by
//! 0.5, 1 and 2 m (random direction) and by 20°, 45° and 90° (random
//! sign). Prints, per offset, the quantiles of the contradiction and of the
//! evidence beams, and how often the contradiction exceeds each threshold.

use anyhow::{Context, Result};
use guide::Policy;
use guide::supervisor::Behaviour;
use lab::runs::mission::{self, LegSpec, MissionSetup, PeoplePlan};
use lab::suites::tourguide::{EXHIBITS, GOAL, MISSION_TIME_LIMIT_S, START, museum};
use localization::{ConsistencyTolerances, LikelihoodField};
use rand::{RngExt, SeedableRng};
use robot::Pose;
use sim::TraceParams;

/// The 5, 25, 50, 75 and 95 % quantiles of `v` (sorted in place).
fn quantiles(v: &mut [f64]) -> String {
    v.sort_by(f64::total_cmp);
    let q = |p: f64| v[((v.len() - 1) as f64 * p).round() as usize];
    format!(
        "p5 {:.3} p25 {:.3} p50 {:.3} p75 {:.3} p95 {:.3}",
        q(0.05),
        q(0.25),
        q(0.5),
        q(0.75),
        q(0.95)
    )
}

/// The museum with `people` visitors around the exhibits, its localizer
/// tracking without judging by contradiction (the source's rule, no
/// recovery), so that its estimates are those of plain tracking.
fn museum_setup(people: usize) -> Result<MissionSetup> {
    let mut setup = MissionSetup::new(museum()?, MISSION_TIME_LIMIT_S);
    setup.guide.mcl.status = localization::StatusParams::explained();
    setup.prepare()?;
    if people > 0 {
        setup.people = Some(PeoplePlan {
            count: people,
            anchors: EXHIBITS.to_vec(),
            spread_m: 2.5,
            keep_clear_m: 1.0,
        });
    }
    Ok(setup)
}

/// The scores gathered over the missions: per offset the contradictions
/// and evidence beams, the unmapped objects at the truth, and the time the
/// scoring took.
struct Scores {
    contradiction: Vec<Vec<f64>>,
    evidence: Vec<Vec<f64>>,
    objects: Vec<f64>,
    timing: std::time::Duration,
    evaluations: u32,
}

/// Prints the time per score, the unmapped objects at the truth, and per
/// offset the quantiles of the contradiction and the evidence and how
/// often the contradiction exceeds each threshold.
fn report(people: usize, missions: u32, offsets: &[(&str, f64, f64)], scores: &mut Scores) {
    let Scores {
        contradiction,
        evidence,
        objects,
        timing,
        evaluations,
    } = scores;
    println!(
        "{people} visitors, {missions} missions, {} scans; one score {:.1} µs",
        contradiction[0].len(),
        timing.as_secs_f64() * 1e6 / f64::from((*evaluations).max(1))
    );
    println!("unmapped objects at the truth: {}", quantiles(objects));
    for (k, (name, _, _)) in offsets.iter().enumerate() {
        let above = |x: f64| {
            contradiction[k].iter().filter(|&&c| c > x).count() as f64 / contradiction[k].len() as f64
        };
        println!(
            "{name:6} contradiction {} | evidence {} | > 0.05: {:.3} > 0.1: {:.3} > 0.15: {:.3} > 0.2: {:.3} > 0.3: {:.3}",
            quantiles(&mut contradiction[k].clone()),
            quantiles(&mut evidence[k]),
            above(0.05),
            above(0.1),
            above(0.15),
            above(0.2),
            above(0.3)
        );
    }
}

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let people: usize = args.first().map_or(Ok(60), |s| s.parse()).context("visitors")?;
    let missions: u32 = args.get(1).map_or(Ok(6), |s| s.parse()).context("missions")?;
    let tol = ConsistencyTolerances {
        hit_within_m: args.get(2).map_or(Ok(0.1), |s| s.parse())?,
        through_tolerance_m: args.get(3).map_or(Ok(0.25), |s| s.parse())?,
        through_tolerance_rad: args.get(4).map_or(Ok(0.035), |s| s.parse())?,
    };
    let setup = museum_setup(people)?;
    let field = LikelihoodField::new(&setup.world.grid().grid_map(), 2.0);
    let density = match people {
        0 => "empty",
        25 => "moderate",
        60 => "packed",
        _ => "other",
    };
    // Offsets from the truth; the first row is the controller's own
    // estimate at that tick (what the localizer judges).
    let offsets: [(&str, f64, f64); 8] = [
        ("estimate", f64::NAN, 0.0),
        ("truth", 0.0, 0.0),
        ("0.5 m", 0.5, 0.0),
        ("1 m", 1.0, 0.0),
        ("2 m", 2.0, 0.0),
        ("20°", 0.0, 20.0),
        ("45°", 0.0, 45.0),
        ("90°", 0.0, 90.0),
    ];
    let mut contradiction: Vec<Vec<f64>> = vec![Vec::new(); offsets.len()];
    let mut evidence: Vec<Vec<f64>> = vec![Vec::new(); offsets.len()];
    let mut objects = Vec::new();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
    let mut timing = std::time::Duration::ZERO;
    let mut evaluations = 0u32;
    for m in 0..missions {
        let seed = lab::runner::derive_seed(7, &format!("{density} campaign {}", m / 24), m % 24);
        let leg = mission::run_leg(
            &setup,
            &LegSpec {
                from: "start",
                to: "goal",
                start: START,
                believed: START,
                goal: GOAL,
                policy: Policy::Fixed(Behaviour::AutoMove),
                seed,
                trace: TraceParams {
                    enabled: true,
                    perception: true,
                    people: false,
                },
            },
        )?;
        let trace = leg.sim.and_then(|s| s.trace).context("no trace")?;
        for tick in trace.ticks.iter().step_by(10) {
            let Some(scan) = tick.perception.as_ref().and_then(|p| p.lasers.first()) else {
                continue;
            };
            let truth = tick.true_pose;
            let value = |name: &str| tick.values.iter().find(|(n, _)| *n == name).map(|(_, v)| *v);
            let estimate = match (
                value("estimate_x_m"),
                value("estimate_y_m"),
                value("estimate_theta_rad"),
            ) {
                (Some(x), Some(y), Some(t)) => Pose::new(x, y, t),
                _ => continue,
            };
            for (k, &(_, d, a)) in offsets.iter().enumerate() {
                let dir = rng.random::<f64>() * std::f64::consts::TAU;
                let sign = if rng.random::<bool>() { 1.0 } else { -1.0 };
                let pose = if d.is_nan() {
                    estimate
                } else {
                    Pose::new(
                        truth.x_m + d * dir.cos(),
                        truth.y_m + d * dir.sin(),
                        truth.theta_rad + sign * a.to_radians(),
                    )
                };
                let t0 = std::time::Instant::now();
                let c = field.consistency(&pose, scan, tol);
                timing += t0.elapsed();
                evaluations += 1;
                contradiction[k].push(c.contradiction());
                evidence[k].push(c.evidence() as f64);
                if k == 1 {
                    objects.push(c.unmapped_objects as f64);
                }
            }
        }
        eprintln!("mission {m}: {:?}", leg.result.outcome);
    }
    report(
        people,
        missions,
        &offsets,
        &mut Scores {
            contradiction,
            evidence,
            objects,
            timing,
            evaluations,
        },
    );
    Ok(())
}
