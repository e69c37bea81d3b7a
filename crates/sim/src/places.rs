//! Named places on a map: the goal files ROS users keep next to their
//! map_server maps.
//!
//! A YAML mapping from a place's name to its pose in the map frame, one
//! place per line, in metres and radians:
//!
//! ```yaml
//! # building_31: places for guided tours
//! entrance: [1.2, -3.5, 0.0]
//! "coffee corner": [12.0, 4.25, 1.5708]
//! ```
//!
//! Block sequences (`entrance:` then `- 1.2` lines) are read too. The order
//! of the file is kept (a tour visits the places in that order). Errors name
//! the file and the line: a name used twice, a value that is not three
//! finite numbers, anything but a mapping at the top. Whether a place is
//! usable on a given map — free, known, away from walls — is checked
//! separately ([`Places::check`]), place by place, so one bad place does not
//! hide the others.

use std::path::Path;

use robot::{Pose, Vec2};
use yaml_rust2::parser::{Event, MarkedEventReceiver, Parser};
use yaml_rust2::scanner::Marker;

use crate::error::{Error, Result};
use crate::grid::{Cell, OccupancyGrid};

/// One named place.
#[derive(Debug, Clone, PartialEq)]
pub struct Place {
    /// Its name.
    pub name: String,
    /// Its pose in the map (world) frame.
    pub pose: Pose,
    /// The line of the file it is on (1-based).
    pub line: usize,
}

/// The places of a file, in the file's order.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Places {
    places: Vec<Place>,
}

/// Why a place cannot be used on a map.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum PlaceProblem {
    /// Outside the map.
    OutsideMap,
    /// In an occupied cell.
    InObstacle,
    /// In an unknown cell.
    InUnknown,
    /// Free, but the robot's footprint there touches a wall.
    TooCloseToWall,
}

impl std::fmt::Display for PlaceProblem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            PlaceProblem::OutsideMap => "outside the map",
            PlaceProblem::InObstacle => "inside an obstacle",
            PlaceProblem::InUnknown => "in unknown (unmapped) space",
            PlaceProblem::TooCloseToWall => "too close to a wall for the robot's footprint",
        })
    }
}

/// Collects the events of the YAML document with their positions.
#[derive(Default)]
struct Events(Vec<(Event, Marker)>);

impl MarkedEventReceiver for Events {
    fn on_event(&mut self, ev: Event, mark: Marker) {
        self.0.push((ev, mark));
    }
}

fn format_error(source: &str, line: usize, message: impl Into<String>) -> Error {
    Error::Format {
        location: format!("{source}:{line}"),
        message: message.into(),
    }
}

impl Places {
    /// Parses a places file; `source` names it in errors.
    pub fn parse(text: &str, source: &str) -> Result<Places> {
        let mut events = Events::default();
        Parser::new_from_str(text)
            .load(&mut events, false)
            .map_err(|e| format_error(source, e.marker().line(), e.info().to_string()))?;
        let mut it = events
            .0
            .into_iter()
            .filter(|(e, _)| !matches!(e, Event::StreamStart | Event::DocumentStart | Event::Nothing))
            .peekable();
        let mut places = Places::default();
        match it.next() {
            Some((Event::MappingStart(..), _)) => {}
            Some((Event::StreamEnd | Event::DocumentEnd, _)) | None => return Ok(places),
            Some((Event::Scalar(v, ..), m)) if v.is_empty() || v == "~" => {
                let _ = m;
                return Ok(places);
            }
            Some((_, m)) => {
                return Err(format_error(
                    source,
                    m.line(),
                    "expected a mapping of place names to [x, y, theta]",
                ));
            }
        }
        loop {
            let (name, line) = match it.next() {
                Some((Event::MappingEnd, _)) => break,
                Some((Event::Scalar(name, ..), m)) => (name, m.line()),
                Some((_, m)) => {
                    return Err(format_error(
                        source,
                        m.line(),
                        "a place's name must be a plain text",
                    ));
                }
                None => return Err(format_error(source, 0, "unexpected end of file")),
            };
            if let Some(first) = places.places.iter().find(|p| p.name == name) {
                return Err(format_error(
                    source,
                    line,
                    format!("place `{name}` is already defined on line {}", first.line),
                ));
            }
            let bad = || {
                format_error(
                    source,
                    line,
                    format!("place `{name}`: expected [x, y, theta] (metres, metres, radians)"),
                )
            };
            match it.next() {
                Some((Event::SequenceStart(..), _)) => {}
                _ => return Err(bad()),
            }
            let mut values = Vec::with_capacity(3);
            loop {
                match it.next() {
                    Some((Event::SequenceEnd, _)) => break,
                    Some((Event::Scalar(v, ..), _)) => {
                        let x: f64 = v.trim().parse().map_err(|_| {
                            format_error(source, line, format!("place `{name}`: `{v}` is not a number"))
                        })?;
                        if !x.is_finite() {
                            return Err(format_error(
                                source,
                                line,
                                format!("place `{name}`: `{v}` is not a finite number"),
                            ));
                        }
                        values.push(x);
                    }
                    _ => return Err(bad()),
                }
            }
            let [x, y, theta] = values[..] else {
                return Err(format_error(
                    source,
                    line,
                    format!(
                        "place `{name}`: expected 3 numbers [x, y, theta], got {}",
                        values.len()
                    ),
                ));
            };
            places.places.push(Place {
                name,
                pose: Pose::new(x, y, theta),
                line,
            });
        }
        Ok(places)
    }

    /// Reads a places file.
    pub fn load(path: &Path) -> Result<Places> {
        let text = std::fs::read_to_string(path).map_err(|source| Error::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Places::parse(&text, &path.display().to_string())
    }

    /// The places, in the file's order.
    pub fn iter(&self) -> impl Iterator<Item = &Place> {
        self.places.iter()
    }

    /// How many.
    pub fn len(&self) -> usize {
        self.places.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.places.is_empty()
    }

    /// The place called `name`.
    pub fn get(&self, name: &str) -> Option<&Place> {
        self.places.iter().find(|p| p.name == name)
    }

    /// Whether a robot of footprint `radius_m` can stand at `at` on `grid`:
    /// `None` if it can, else why not.
    pub fn problem_at(grid: &OccupancyGrid, at: Vec2, radius_m: f64) -> Option<PlaceProblem> {
        let c = grid.cell_of(at);
        if !grid.contains(c) {
            return Some(PlaceProblem::OutsideMap);
        }
        match grid.get(c) {
            Cell::Occupied => Some(PlaceProblem::InObstacle),
            Cell::Unknown => Some(PlaceProblem::InUnknown),
            Cell::Free if grid.disc_blocked(at, radius_m) => Some(PlaceProblem::TooCloseToWall),
            Cell::Free => None,
        }
    }

    /// The places a robot of footprint `radius_m` cannot stand at on
    /// `grid`, with why (empty when every place is usable).
    pub fn check(&self, grid: &OccupancyGrid, radius_m: f64) -> Vec<(&Place, PlaceProblem)> {
        self.places
            .iter()
            .filter_map(|p| Places::problem_at(grid, p.pose.position(), radius_m).map(|e| (p, e)))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::CellIndex;

    #[test]
    fn flow_and_block_styles_keep_the_file_order_and_lines() {
        let text = "# places\nzulu: [1.0, 2.0, 0.5]\n\"coffee corner\": [ -3, 4.25, 3.0 ]\nalpha:\n  - 0\n  - 0\n  - -1.25\n";
        let p = Places::parse(text, "t.yaml").unwrap();
        let names: Vec<&str> = p.iter().map(|q| q.name.as_str()).collect();
        assert_eq!(names, ["zulu", "coffee corner", "alpha"]);
        let lines: Vec<usize> = p.iter().map(|q| q.line).collect();
        assert_eq!(lines, [2, 3, 4]);
        assert_eq!(
            p.get("coffee corner").unwrap().pose.position(),
            Vec2::new(-3.0, 4.25)
        );
        assert!((p.get("alpha").unwrap().pose.theta_rad + 1.25).abs() < 1e-12);
        assert!(Places::parse("", "e.yaml").unwrap().is_empty());
        assert!(Places::parse("# nothing\n", "e.yaml").unwrap().is_empty());
    }

    #[test]
    fn malformed_files_name_the_line() {
        let err = |text: &str| Places::parse(text, "p.yaml").unwrap_err().to_string();
        let e = err("a: [1, 2, 3]\nb: [1, 2]\n");
        assert!(e.starts_with("p.yaml:2:") && e.contains("got 2"), "{e}");
        let e = err("a: [1, 2, 3]\n\nb: [1, x, 3]\n");
        assert!(e.starts_with("p.yaml:3:") && e.contains("`x`"), "{e}");
        let e = err("a: [1, 2, 3]\na: [4, 5, 6]\n");
        assert!(e.starts_with("p.yaml:2:") && e.contains("line 1"), "{e}");
        let e = err("a: [1, 2, nan]\n");
        assert!(e.contains("finite"), "{e}");
        let e = err("- [1, 2, 3]\n");
        assert!(e.contains("mapping"), "{e}");
        let e = err("a: 3\n");
        assert!(e.starts_with("p.yaml:1:") && e.contains("[x, y, theta]"), "{e}");
        let e = err("a: [1, 2, 3\nb: [");
        assert!(e.starts_with("p.yaml:"), "{e}");
        let e = err("a: {x: 1}\n");
        assert!(e.contains("[x, y, theta]"), "{e}");
    }

    #[test]
    fn places_in_walls_unknown_space_or_off_the_map_are_named() {
        let mut g = OccupancyGrid::new(40, 40, 0.05, Pose::default());
        g.set(CellIndex { i: 10, j: 10 }, Cell::Occupied);
        g.set(CellIndex { i: 30, j: 30 }, Cell::Unknown);
        let text = "ok: [1.0, 1.5, 0]\nwall: [0.525, 0.525, 0]\nunknown: [1.525, 1.525, 0]\noff: [5, 5, 0]\nnear: [0.525, 0.7, 0]\n";
        let p = Places::parse(text, "p.yaml").unwrap();
        let problems: Vec<(&str, PlaceProblem)> = p
            .check(&g, 0.3)
            .into_iter()
            .map(|(q, e)| (q.name.as_str(), e))
            .collect();
        assert_eq!(
            problems,
            [
                ("wall", PlaceProblem::InObstacle),
                ("unknown", PlaceProblem::InUnknown),
                ("off", PlaceProblem::OutsideMap),
                ("near", PlaceProblem::TooCloseToWall),
            ]
        );
    }
}
