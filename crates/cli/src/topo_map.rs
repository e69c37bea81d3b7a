//! A topological map file and its places as the `petrinav topo` commands
//! take them: shared by `topo_cmd.rs` (plan, convert) and `topo_run.rs`
//! (explore, go), which otherwise do not use each other's items.

use std::path::Path;

use anyhow::{Result, anyhow, bail};
use clap::ValueEnum;
use topo::{FuzzyPetriNet, PlaceId, PlanMode};

/// The stopping rule of the propagation.
#[derive(ValueEnum, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ModeArg {
    /// To the fixed point: the cheapest route.
    #[default]
    Optimal,
    /// The source's rule: stop as soon as the start has a value (after the fewest transitions).
    Paper,
}

impl From<ModeArg> for PlanMode {
    fn from(m: ModeArg) -> PlanMode {
        match m {
            ModeArg::Optimal => PlanMode::Optimal,
            ModeArg::Paper => PlanMode::Paper,
        }
    }
}

/// Reads and checks a map file; errors name the file and what is wrong.
pub fn load_map(path: &Path) -> Result<FuzzyPetriNet> {
    // The library's errors name the file already.
    FuzzyPetriNet::load(path).map_err(|e| anyhow!("{e}"))
}

/// The place named `name`, or an error naming the option, the map and the
/// places it has.
pub fn find_place(net: &FuzzyPetriNet, name: &str, option: &str, map: &Path) -> Result<PlaceId> {
    if let Some(p) = net.place_id(name) {
        return Ok(p);
    }
    let names: Vec<&str> = net.places().iter().map(|p| p.name.as_str()).collect();
    let hint = petri::closest(name, &names).map_or(String::new(), |s| format!(" (did you mean `{s}`?)"));
    const SHOWN: usize = 12;
    let listed = if names.is_empty() {
        "it has no places".to_string()
    } else if names.len() <= SHOWN {
        format!("its places are {}", names.join(", "))
    } else {
        format!(
            "its {} places are {} and {} more",
            names.len(),
            names[..SHOWN - 2].join(", "),
            names.len() - (SHOWN - 2)
        )
    };
    bail!(
        "{option}: no place named `{name}` in {}{hint}; {listed}",
        map.display()
    )
}
