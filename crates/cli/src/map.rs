//! `petrinav map …`: occupancy grid maps on the command line.
//!
//! A map is a ROS map_server YAML file (with its PGM or PNG image) or a
//! TOML file describing a world of shapes (a `[world]` table, as in a
//! scenario, or the world's keys at the top level).

use std::path::{Path, PathBuf};

use anyhow::{Result, anyhow};
use clap::Subcommand;
use serde_json::json;
use sim::OccupancyGrid;
use sim::render::Picture;

use crate::output::{fields, num};
use crate::{out, outln};

#[derive(Subcommand, Debug)]
pub enum MapCommand {
    /// Size, resolution, origin, and counts of free, occupied and unknown
    /// cells.
    ///
    /// Example: petrinav map info building_31.yaml --json
    Info {
        /// Map: map_server .yaml, or .toml world of shapes.
        map: PathBuf,
        /// Print JSON instead of aligned fields.
        #[arg(long)]
        json: bool,
    },
    /// Draws the map as PNG or SVG (chosen by the output's extension): free
    /// white, occupied black, unknown grey, +y up.
    ///
    /// Example: petrinav map render building_31.yaml -o building_31.png --scale 40
    Render {
        /// Map: map_server .yaml, or .toml world of shapes.
        map: PathBuf,
        /// Output file, .png or .svg.
        #[arg(short, long)]
        output: PathBuf,
        /// Pixels per metre. Default: one pixel per cell, or a whole number
        /// of pixels per cell giving at least 600 pixels on the longer side.
        #[arg(long, value_name = "PX_PER_M")]
        scale: Option<f64>,
    },
}

pub fn run(cmd: MapCommand) -> Result<()> {
    match cmd {
        MapCommand::Info { map, json } => info(&map, json),
        MapCommand::Render { map, output, scale } => render(&map, &output, scale),
    }
}

/// The occupancy grid of a map_server `.yaml` map or a `.toml` world.
pub(crate) fn load_grid(path: &Path) -> Result<OccupancyGrid> {
    lab::map_file::load_grid(path)
}

fn info(path: &Path, as_json: bool) -> Result<()> {
    let m = lab::map_file::load(path)?;
    let g = &m.grid;
    let n = g.counts();
    let r = g.resolution_m();
    let o = g.origin();
    let (wm, hm) = (g.width() as f64 * r, g.height() as f64 * r);
    if as_json {
        let mut v = json!({
            "file": path.display().to_string(),
            "width_cells": g.width(),
            "height_cells": g.height(),
            "resolution_m": r,
            "width_m": wm,
            "height_m": hm,
            "origin": { "x_m": o.x_m, "y_m": o.y_m, "yaw_rad": o.theta_rad },
            "free_cells": n.free,
            "occupied_cells": n.occupied,
            "unknown_cells": n.unknown,
            "free_area_m2": g.free_area_m2(),
        });
        if let Some(y) = &m.map_server {
            v["map_server"] = json!({
                "image": y.image_path.display().to_string(),
                "mode": y.yaml.mode.name(),
                "negate": y.yaml.negate,
                "occupied_thresh": y.yaml.occupied_thresh,
                "free_thresh": y.yaml.free_thresh,
            });
        }
        outln!("{}", serde_json::to_string_pretty(&v)?)?;
        return Ok(());
    }
    let mut rows = vec![("map", path.display().to_string())];
    if let Some(y) = &m.map_server {
        rows.push(("image", y.image_path.display().to_string()));
        rows.push((
            "mode",
            format!(
                "{} (negate {}, occupied > {}, free < {})",
                y.yaml.mode.name(),
                u8::from(y.yaml.negate),
                num(y.yaml.occupied_thresh),
                num(y.yaml.free_thresh)
            ),
        ));
    }
    rows.extend([
        ("size", format!("{} × {} cells", g.width(), g.height())),
        ("resolution", format!("{} m/cell", num(r))),
        ("extent", format!("{} × {} m", num(wm), num(hm))),
        (
            "origin",
            format!(
                "x {} m, y {} m, yaw {} rad",
                num(o.x_m),
                num(o.y_m),
                num(o.theta_rad)
            ),
        ),
        ("free", format!("{} cells, {} m²", n.free, num(g.free_area_m2()))),
        ("occupied", format!("{} cells", n.occupied)),
        ("unknown", format!("{} cells", n.unknown)),
    ]);
    out!("{}", fields(&rows))?;
    Ok(())
}

fn render(path: &Path, output: &Path, scale: Option<f64>) -> Result<()> {
    let m = lab::map_file::load(path)?;
    let mut picture = Picture::new(&m.grid);
    if let Some(s) = scale {
        picture.scale(s);
    }
    picture
        .save(output)
        .map_err(|e| anyhow!("cannot draw {}: {e}", path.display()))?;
    Ok(())
}
