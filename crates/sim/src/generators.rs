//! Procedural worlds for benchmarks and tests: an office floor and a
//! cluttered field, of any size, deterministic.

use robot::{Pose, Vec2};

use crate::error::{Error, Result};
use crate::grid::{Cell, CellIndex, OccupancyGrid};
use crate::noise::RandomStream;
use crate::validate;

/// Largest grid the generators make, cells.
pub const MAX_CELLS: usize = 1 << 28;

/// Checks a generator's size and resolution.
fn check(width: usize, height: usize, resolution_m: f64) -> Result<()> {
    validate::positive("resolution_m", resolution_m)?;
    if width.checked_mul(height).is_none_or(|n| n > MAX_CELLS) {
        return Err(Error::InvalidValue {
            what: "grid cells (width × height)".to_string(),
            requirement: "at most 2^28",
            value: width as f64 * height as f64,
        });
    }
    Ok(())
}

/// Sets the cells whose centres lie in the rectangle `[x0, x1] × [y0, y1]`
/// (map frame, metres).
fn fill(g: &mut OccupancyGrid, x0: f64, y0: f64, x1: f64, y1: f64, v: Cell) {
    let r = g.resolution_m();
    let lo = |a: f64| ((a / r) - 0.5).ceil().max(0.0) as i64;
    let hi = |a: f64, n: usize| (((a / r) - 0.5).floor() as i64).min(n as i64 - 1);
    for j in lo(y0.min(y1))..=hi(y0.max(y1), g.height()) {
        for i in lo(x0.min(x1))..=hi(x0.max(x1), g.width()) {
            g.set(CellIndex { i, j }, v);
        }
    }
}

/// Wall thickness of the office, metres.
const WALL_M: f64 = 0.15;

/// An office floor of `width × height` cells of `resolution_m`, origin at
/// (0, 0): rooms off two corridors, like a real building map (the
/// `building_31` SLAM map is 693 × 648 cells at 0.05 m, see
/// [`building_31_like`]).
///
/// Layout, with `W × H` the size in metres: 0.15 m walls around; corridor A
/// 2 m wide centred at `y = H/3`, corridor B at `y = 2H/3`, both the full
/// width; the floor is cut into 4 m slots along x; below A, between A and B
/// (two rows, split at `y = H/2`) and above B, each slot is a room with a
/// 1 m door onto the nearer corridor and a 1.2 m × 0.6 m table in its
/// middle; the middle slot between the corridors is an open hall joining
/// them.
///
/// Errors: [`Error::InvalidValue`] for a resolution that is not > 0 or more
/// than [`MAX_CELLS`] cells.
pub fn office(width: usize, height: usize, resolution_m: f64) -> Result<OccupancyGrid> {
    check(width, height, resolution_m)?;
    let mut g = OccupancyGrid::new(width, height, resolution_m, Pose::default());
    let (w, h) = (width as f64 * resolution_m, height as f64 * resolution_m);
    let t = WALL_M;
    let occ = Cell::Occupied;
    // Outer walls.
    fill(&mut g, 0.0, 0.0, w, t, occ);
    fill(&mut g, 0.0, h - t, w, h, occ);
    fill(&mut g, 0.0, 0.0, t, h, occ);
    fill(&mut g, w - t, 0.0, w, h, occ);
    let (ya, yb, ymid) = (h / 3.0, 2.0 * h / 3.0, h / 2.0);
    // Room rows: (bottom, top, y of the wall with the doors).
    let rows = [
        (t, ya - 1.0, ya - 1.0),
        (ya + 1.0, ymid, ya + 1.0),
        (ymid, yb - 1.0, yb - 1.0),
        (yb + 1.0, h - t, yb + 1.0),
    ];
    let slot = 4.0;
    let slots = (((w - 2.0 * t) / slot).floor() as usize).max(1);
    let hall = slots / 2;
    for (row, &(y0, y1, door_y)) in rows.iter().enumerate() {
        let between = row == 1 || row == 2;
        // The wall on the corridor side, and the middle wall.
        fill(&mut g, 0.0, door_y - t / 2.0, w, door_y + t / 2.0, occ);
        if row == 1 {
            fill(&mut g, 0.0, ymid - t / 2.0, w, ymid + t / 2.0, occ);
        }
        for k in 0..slots {
            let x0 = t + k as f64 * slot;
            let x1 = if k + 1 == slots { w - t } else { x0 + slot };
            if between && k == hall {
                continue;
            }
            // Side wall at the slot's right end.
            if k + 1 < slots {
                fill(&mut g, x1 - t / 2.0, y0, x1 + t / 2.0, y1, occ);
            }
            let xc = 0.5 * (x0 + x1);
            fill(&mut g, xc - 0.5, door_y - t, xc + 0.5, door_y + t, Cell::Free);
            let yc = 0.5 * (y0 + y1);
            fill(&mut g, xc - 0.6, yc - 0.3, xc + 0.6, yc + 0.3, occ);
        }
    }
    // The hall: open from corridor A to corridor B.
    let x0 = t + hall as f64 * slot;
    fill(
        &mut g,
        x0 + t / 2.0,
        ya + 1.0 - t,
        x0 + slot - t / 2.0,
        yb - 1.0 + t,
        Cell::Free,
    );
    // Its side walls.
    fill(&mut g, x0 - t / 2.0, ya + 1.0, x0 + t / 2.0, yb - 1.0, occ);
    fill(
        &mut g,
        x0 + slot - t / 2.0,
        ya + 1.0,
        x0 + slot + t / 2.0,
        yb - 1.0,
        occ,
    );
    Ok(g)
}

/// An office floor the size of the `building_31` map: 693 × 648 cells at
/// 0.05 m (34.65 m × 32.4 m). Corridor A runs along `y = 10.8 m`,
/// corridor B along `y = 21.6 m`.
pub fn building_31_like() -> OccupancyGrid {
    office(693, 648, 0.05).expect("a valid size")
}

/// A square field of side `side_m` with 0.1 m walls around and `obstacles`
/// boxes (sides 0.2–0.6 m, axis-aligned) at positions drawn from `seed`,
/// none within 1 m of the corners `(1, 1)` and `(side − 1, side − 1)` (start
/// and goal areas).
///
/// Errors: [`Error::InvalidValue`] for a side or resolution that is not
/// > 0, or more than [`MAX_CELLS`] cells.
pub fn cluttered_field(side_m: f64, resolution_m: f64, obstacles: usize, seed: u64) -> Result<OccupancyGrid> {
    validate::positive("side_m", side_m)?;
    validate::positive("resolution_m", resolution_m)?;
    let n = (side_m / resolution_m).round().clamp(1.0, MAX_CELLS as f64) as usize;
    check(n, n, resolution_m)?;
    let mut g = OccupancyGrid::new(n, n, resolution_m, Pose::default());
    let s = n as f64 * resolution_m;
    let occ = Cell::Occupied;
    fill(&mut g, 0.0, 0.0, s, 0.1, occ);
    fill(&mut g, 0.0, s - 0.1, s, s, occ);
    fill(&mut g, 0.0, 0.0, 0.1, s, occ);
    fill(&mut g, s - 0.1, 0.0, s, s, occ);
    let mut rng = RandomStream::new(seed, 0);
    let keep = [Vec2::new(1.0, 1.0), Vec2::new(s - 1.0, s - 1.0)];
    let mut placed = 0;
    let mut tries = 0;
    while placed < obstacles && tries < 100 * obstacles.max(1) {
        tries += 1;
        let (a, b) = (rng.uniform_in(0.2, 0.6), rng.uniform_in(0.2, 0.6));
        let c = Vec2::new(rng.uniform_in(0.3, s - 0.3), rng.uniform_in(0.3, s - 0.3));
        if keep.iter().any(|k| k.dist(c) < 1.0 + 0.5 * a.hypot(b)) {
            continue;
        }
        fill(
            &mut g,
            c.x - a / 2.0,
            c.y - b / 2.0,
            c.x + a / 2.0,
            c.y + b / 2.0,
            occ,
        );
        placed += 1;
    }
    Ok(g)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn office_has_open_corridors_and_rooms() {
        let g = building_31_like();
        assert_eq!((g.width(), g.height()), (693, 648));
        // Corridors are free along their centre lines.
        for k in 0..600 {
            let x = 0.5 + k as f64 * 0.05;
            assert!(!g.blocked_at(Vec2::new(x, 10.8)), "corridor A at {x}");
            assert!(!g.blocked_at(Vec2::new(x, 21.6)), "corridor B at {x}");
        }
        let free = g.free_area_m2();
        assert!(free > 0.7 * 34.65 * 32.4 && free < 0.98 * 34.65 * 32.4, "{free}");
        // A door of the first room below corridor A.
        assert!(!g.blocked_at(Vec2::new(2.15, 9.8)));
        assert!(g.blocked_at(Vec2::new(3.5, 9.8)));
    }

    #[test]
    fn field_keeps_start_and_goal_clear() {
        let g = cluttered_field(10.0, 0.05, 25, 1).unwrap();
        assert!(!g.disc_blocked(Vec2::new(1.0, 1.0), 0.5));
        assert!(!g.disc_blocked(Vec2::new(9.0, 9.0), 0.5));
        assert!(g.free_area_m2() < 99.0);
        assert!(cluttered_field(10.0, 0.0, 1, 1).is_err());
        assert!(office(1 << 20, 1 << 20, 0.05).is_err());
        assert!(office(10, 10, f64::NAN).is_err());
    }
}
