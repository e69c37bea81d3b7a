//! Map files as the command line and the Python package take them: a ROS
//! map_server `.yaml` map (with its PGM or PNG image), or a `.toml` world
//! of shapes (a `[world]` table, as in a scenario, or the world's keys at
//! the top level).

use std::path::Path;

use anyhow::{Context, Result, anyhow, bail};
use sim::OccupancyGrid;
use sim::map_server::{self, MapServerMap};
use sim::shapes::WorldSpec;

/// A loaded map and what its file said.
#[derive(Debug, Clone)]
pub struct MapFile {
    /// The occupancy grid.
    pub grid: OccupancyGrid,
    /// map_server details, for `.yaml` maps.
    pub map_server: Option<MapServerMap>,
}

/// A scenario-like file: the world under `[world]`, other tables ignored.
#[derive(serde::Deserialize)]
struct WithWorld {
    world: WorldSpec,
}

/// An error reading a map file: what went wrong, said as it is (its
/// display and sources are the inner error's), under a type of its own so
/// that a caller can tell map errors from others.
#[derive(Debug, thiserror::Error)]
#[error(transparent)]
pub struct MapFileError(#[from] anyhow::Error);

/// Loads a map_server `.yaml` map or a `.toml` world (by extension);
/// errors name the file and are [`MapFileError`]s.
pub fn load(path: &Path) -> Result<MapFile> {
    read(path).map_err(|e| MapFileError(e).into())
}

fn read(path: &Path) -> Result<MapFile> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("yaml" | "yml") => {
            let m = map_server::load(path)?;
            Ok(MapFile {
                grid: m.grid.clone(),
                map_server: Some(m),
            })
        }
        Some("toml") => {
            let text =
                std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
            let table: toml::Table = toml::from_str(&text).with_context(|| format!("{}", path.display()))?;
            let spec = if table.contains_key("world") {
                toml::from_str::<WithWorld>(&text)
                    .with_context(|| format!("{}", path.display()))?
                    .world
            } else {
                toml::from_str::<WorldSpec>(&text).with_context(|| format!("{}", path.display()))?
            };
            let grid = spec.rasterise().map_err(|e| anyhow!("{}: {e}", path.display()))?;
            Ok(MapFile {
                grid,
                map_server: None,
            })
        }
        _ => bail!(
            "{}: unknown map format; expected a map_server .yaml or a .toml world",
            path.display()
        ),
    }
}

/// The occupancy grid of a map file ([`load`]).
pub fn load_grid(path: &Path) -> Result<OccupancyGrid> {
    Ok(load(path)?.grid)
}
