//! `petrinav`: the command-line entry point. Parsing and dispatch only; each
//! command lives in its own module.

mod gspn;
mod guide_cmd;
mod interrupt;
mod lab_cmd;
mod lab_slurm;
mod map;
mod nav_cmd;
mod output;
mod sim_cmd;
mod topo_cmd;
mod topo_map;
mod topo_run;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// A workbench for behaviour-based robot navigation whose coordination logic
/// can be analysed formally.
#[derive(Parser, Debug)]
#[command(name = "petrinav", version, about, long_about = None, propagate_version = true)]
struct Cli {
    /// None: `petrinav` alone prints [`INTRODUCTION`].
    #[command(subcommand)]
    command: Option<Command>,
}

/// What `petrinav` alone prints, on standard output with exit code 0 (a
/// request for orientation, not a mistake — as `cargo` or `docker` alone):
/// what it is and the first five commands of the README's tour. `petrinav
/// --help` lists every command.
const INTRODUCTION: &str = "\
petrinav: a workbench for behaviour-based mobile-robot navigation whose
coordination logic is analysed as generalized stochastic Petri nets (GSPN):
a GSPN engine, robot controllers, a 2D simulator, and experiment suites
with reports that open in any browser.

Five commands to start with (the README's tour):
  petrinav lab run voting
      the main job: 3,500 navigation runs; report in out/voting/index.html
  petrinav gspn solve models/supervisor.toml
      the steady state of a GSPN (.toml, .pnpro, .pnml)
  petrinav nav tour maps/levine/levine.yaml --goals maps/levine/places.yaml --people 20
      the tour-guide robot on a real building map, among 20 people
  petrinav topo explore office -o office.fpn.json --picture office.png
      a sonar robot builds a topological map (a fuzzy Petri net)
  petrinav lab replay out/voting 'e4/field12#0' --html run.html
      one run of the first command, to watch in a browser

Every command: petrinav --help; each has --help with examples.
Documentation: README.md and the book in docs/ (mdbook build docs).
";

#[derive(Subcommand, Debug)]
enum Command {
    /// Generalized Stochastic Petri Nets: analyse, solve, simulate, convert, draw.
    #[command(subcommand)]
    Gspn(gspn::GspnCommand),
    /// Occupancy grid maps (ROS map_server YAML, or a TOML world of shapes):
    /// describe, draw.
    #[command(subcommand)]
    Map(map::MapCommand),
    /// Experiments: run suites and scenario files as batches, write reports.
    #[command(subcommand)]
    Lab(lab_cmd::LabCommand),
    /// The simulator: drive a robot through a world.
    #[command(subcommand)]
    Sim(sim_cmd::SimCommand),
    /// The tour-guide robot on a map: drive between named places, or a guided tour.
    #[command(subcommand)]
    Nav(nav_cmd::NavCommand),
    /// The tour-guide robot's mission log and the supervisor's learnt rates.
    #[command(subcommand)]
    Guide(guide_cmd::GuideCommand),
    /// Topological maps as fuzzy Petri nets: explore a world, plan and drive routes, convert, generate.
    #[command(subcommand)]
    Topo(topo_cmd::TopoCommand),
}

fn main() -> ExitCode {
    let Some(command) = Cli::parse().command else {
        // A closed pipe (`petrinav | head -1`) is not an error.
        let _ = std::io::Write::write_all(&mut std::io::stdout(), INTRODUCTION.as_bytes());
        return ExitCode::SUCCESS;
    };
    let result = match command {
        Command::Gspn(cmd) => gspn::run(cmd),
        Command::Map(cmd) => map::run(cmd),
        Command::Sim(cmd) => sim_cmd::run(cmd),
        Command::Lab(cmd) => lab_cmd::run(cmd),
        Command::Nav(cmd) => nav_cmd::run(cmd),
        Command::Guide(cmd) => guide_cmd::run(cmd),
        Command::Topo(cmd) => topo_cmd::run(cmd),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            // A closed pipe (`petrinav … | head`) is not an error.
            let broken_pipe = e
                .chain()
                .filter_map(|c| c.downcast_ref::<std::io::Error>())
                .any(|io| io.kind() == std::io::ErrorKind::BrokenPipe);
            if broken_pipe {
                return ExitCode::SUCCESS;
            }
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
