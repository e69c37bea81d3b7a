//! Monte Carlo localization on a real map: the simulated Jinny-like robot
//! (181-beam laser, realistic odometry noise) drives a route of more than
//! 100 m through the corridors while the localizer follows it; prints the
//! position error of the estimate against the true pose, the time in
//! Warning, and the cost of the filter.
//!
//! ```text
//! cargo run --release -p localization --example mcl_drive -- building_31
//! cargo run --release -p localization --example mcl_drive -- levine
//! cargo run --release -p localization --example mcl_drive -- building_31 --people 20
//! cargo run --release -p localization --example mcl_drive -- building_31 --global
//! ```
//!
//! Options: `--people N` (a crowd of N people), `--seeds K` (K runs with
//! simulation seeds 1…K, summarised), `--log-product` (multiply the beam
//! probabilities instead of AMCL's sum of cubes), `--recovery` (random
//! particles, α_slow 0.001, α_fast 0.1), `--global` (global localization:
//! uniform particles, reports the distance travelled until the error stays
//! below 0.3 m), `--particles N`, `--alpha A` (all four `α`),
//! `--sigma-hit S`, `--max-beams N`, `--beam-skip`, `--speed V`,
//! `--margin M` and `--min-explained F` (status).

#[path = "../tests/common/mcl_harness.rs"]
mod harness;

use std::process::ExitCode;
use std::time::Instant;

use harness::{DriveSetup, DriveStats, median};
use localization::{BeamCombination, MatchOutcome, RecoveryParams};

/// Reads the options after the map name into `setup`; the number of
/// seeds, or `None` (after a message) on a bad option.
fn parse_options(options: &[String], setup: &mut DriveSetup) -> Option<u64> {
    let mut seeds = 1u64;
    let mut it = options.iter();
    while let Some(a) = it.next() {
        let mut value = |name: &str| -> Option<f64> {
            let v = it.next().and_then(|s| s.parse::<f64>().ok());
            if v.is_none() {
                eprintln!("{name} needs a number");
            }
            v
        };
        match a.as_str() {
            "--people" => match value("--people") {
                Some(v) => setup.people = v as usize,
                None => return None,
            },
            "--seeds" => match value("--seeds") {
                Some(v) => seeds = v.max(1.0) as u64,
                None => return None,
            },
            "--particles" => match value("--particles") {
                Some(v) => setup.params.particles = v as usize,
                None => return None,
            },
            "--margin" => match value("--margin") {
                Some(v) => setup.params.status.margin = v,
                None => return None,
            },
            "--min-explained" => match value("--min-explained") {
                Some(v) => setup.params.status.min_explained = v,
                None => return None,
            },
            "--alpha" => match value("--alpha") {
                Some(v) => {
                    setup.params.motion = localization::OdometryMotionModel {
                        alpha1: v,
                        alpha2: v,
                        alpha3: v,
                        alpha4: v,
                    }
                }
                None => return None,
            },
            "--sigma-hit" => match value("--sigma-hit") {
                Some(v) => setup.params.field.sigma_hit_m = v,
                None => return None,
            },
            "--max-beams" => match value("--max-beams") {
                Some(v) => setup.params.max_beams = v as usize,
                None => return None,
            },
            "--speed" => match value("--speed") {
                Some(v) => setup.speed_mps = v,
                None => return None,
            },
            "--beam-skip" => setup.params.field.beam_skip = Some(localization::BeamSkip::default()),
            "--log-product" => setup.params.field.combination = BeamCombination::LogProduct,
            "--recovery" => {
                setup.params.recovery = RecoveryParams {
                    alpha_slow: 0.001,
                    alpha_fast: 0.1,
                }
            }
            "--global" => setup.init = None,
            other => {
                eprintln!("unknown option {other}");
                return None;
            }
        }
    }
    Some(seeds)
}

/// Prints what a run with `seed` measured (`wall` seconds of wall time):
/// distance, errors, iterations and Warning, the scan explained at the
/// estimate, the mean error in the robot frame, and global convergence.
fn print_run(seed: u64, setup: &DriveSetup, s: &DriveStats, wall: f64) {
    let count = |c: MatchOutcome| s.infos.iter().filter(|i| i.outcome == c).count();
    println!(
        "seed {seed}: {:.1} m in {} ticks{}; error median {:.3} m, max {:.3} m, heading median {:.2}°; \
         {} iterations, Warning {:.1} % of iterations ({:.1} % of time, raised {} times); \
         matched/failed/no data {}/{}/{}; {} contacts; {:.1} s wall",
        s.distance_m,
        s.ticks,
        if s.finished { "" } else { " (route not finished)" },
        s.median_error_m(),
        s.max_error_m(),
        median(&s.heading_errors_rad).to_degrees(),
        s.iterations,
        100.0 * s.warning_fraction(),
        100.0 * s.warning_ticks as f64 / s.ticks.max(1) as f64,
        s.warnings_raised,
        count(MatchOutcome::Matched),
        count(MatchOutcome::Failed),
        count(MatchOutcome::NoData),
        s.collisions,
        wall
    );
    let mut explained: Vec<f64> = s.infos.iter().map(|i| i.score_estimate).collect();
    explained.sort_by(f64::total_cmp);
    let q = |p: f64| {
        explained
            .get(((explained.len() as f64 - 1.0) * p).round() as usize)
            .copied()
            .unwrap_or(f64::NAN)
    };
    println!(
        "  fraction of the scan explained at the estimate, quantiles 5/25/50 %: {:.2} {:.2} {:.2}",
        q(0.05),
        q(0.25),
        q(0.5)
    );
    let nf = s.errors_robot_frame.len().max(1) as f64;
    let (fx, fy) = s
        .errors_robot_frame
        .iter()
        .fold((0.0, 0.0), |(a, b), &(x, y)| (a + x, b + y));
    println!(
        "  mean error in the robot frame: forward {:+.3} m, left {:+.3} m",
        fx / nf,
        fy / nf
    );
    if setup.init.is_none() {
        match s.converged_at_m {
            Some(d) => {
                let tail: Vec<f64> = s.errors_m.iter().rev().take(200).copied().collect();
                println!(
                    "  global: error below {} m from {d:.1} m travelled on (last 200 ticks: max {:.3} m)",
                    setup.converged_m,
                    harness::max(&tail)
                );
            }
            None => println!(
                "  global: not converged (final error {:.2} m)",
                s.errors_m.last().unwrap_or(&f64::NAN)
            ),
        }
    }
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(map) = args.first().cloned() else {
        eprintln!(
            "usage: mcl_drive building_31|levine [--people N] [--seeds K] [--log-product] [--recovery] [--global] [--particles N] [--alpha A] [--sigma-hit S] [--max-beams N] [--beam-skip] [--speed V] [--margin M] [--min-explained F]"
        );
        return ExitCode::FAILURE;
    };
    if map != "building_31" && map != "levine" {
        eprintln!("unknown map {map}: building_31 or levine");
        return ExitCode::FAILURE;
    }
    let mut setup = DriveSetup::tracking(&map);
    let Some(seeds) = parse_options(&args[1..], &mut setup) else {
        return ExitCode::FAILURE;
    };
    if let Err(e) = setup.params.validate() {
        eprintln!("{e}");
        return ExitCode::FAILURE;
    }
    println!(
        "map {map}, {} people, {} particles{}, {:?}, α {}, status: margin {}, min explained {}",
        setup.people,
        setup.params.particles,
        if setup.init.is_none() {
            format!(" ({} at the global start)", setup.params.global_particles)
        } else {
            String::new()
        },
        setup.params.field.combination,
        setup.params.motion.alpha1,
        setup.params.status.margin,
        setup.params.status.min_explained
    );
    let mut medians = Vec::new();
    let mut maxima = Vec::new();
    let mut warn = Vec::new();
    for seed in 1..=seeds {
        setup.sim_seed = seed;
        setup.mcl_seed = 1000 + seed;
        let t = Instant::now();
        let s = harness::drive(&setup);
        let wall = t.elapsed().as_secs_f64();
        print_run(seed, &setup, &s, wall);
        medians.push(s.median_error_m());
        maxima.push(s.max_error_m());
        warn.push(s.warning_fraction());
    }
    if seeds > 1 {
        println!(
            "over {seeds} seeds: median error (median of runs) {:.3} m, worst max {:.3} m, Warning {:.1} % of iterations (mean)",
            median(&medians),
            harness::max(&maxima),
            100.0 * warn.iter().sum::<f64>() / warn.len() as f64
        );
    }
    ExitCode::SUCCESS
}
