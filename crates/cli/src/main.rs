//! `petrinav`: the command-line entry point. Parsing and dispatch only; each
//! command lives in its own module.

mod bt_cmd;
mod gspn;
mod guide_cmd;
mod interrupt;
mod lab_cmd;
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
    #[command(subcommand)]
    command: Command,
}

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
    /// Behaviour trees (BehaviorTree.CPP v3/v4, Nav2): check, analyse through
    /// their GSPN, simulate, fit leaf parameters to logs.
    #[command(subcommand)]
    Bt(bt_cmd::BtCommand),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Gspn(cmd) => gspn::run(cmd),
        Command::Map(cmd) => map::run(cmd),
        Command::Sim(cmd) => sim_cmd::run(cmd),
        Command::Lab(cmd) => lab_cmd::run(cmd),
        Command::Nav(cmd) => nav_cmd::run(cmd),
        Command::Guide(cmd) => guide_cmd::run(cmd),
        Command::Topo(cmd) => topo_cmd::run(cmd),
        Command::Bt(cmd) => match bt_cmd::run(cmd) {
            Ok(code) => return code,
            Err(e) => Err(e),
        },
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            if broken_pipe(&e) {
                return ExitCode::SUCCESS;
            }
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

/// Whether an error is a closed pipe (`petrinav … | head`), which is not an error.
pub(crate) fn broken_pipe(e: &anyhow::Error) -> bool {
    e.chain()
        .filter_map(|c| c.downcast_ref::<std::io::Error>())
        .any(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
}
