//! Byte encodings shared by the run viewer and the MCAP export: base64
//! (RFC 4648, with padding; the simulator's) and an occupancy grid as a
//! grey PNG, one pixel per cell.

use anyhow::{Context, Result};
use sim::{Cell, OccupancyGrid};

/// Grey level of a free cell in [`grid_png`].
pub const FREE_GREY: u8 = 255;
/// Grey level of an occupied cell in [`grid_png`].
pub const OCCUPIED_GREY: u8 = 0;
/// Grey level of an unknown cell in [`grid_png`].
pub const UNKNOWN_GREY: u8 = 205;

/// Base64 with the standard alphabet and `=` padding (RFC 4648 §4): the
/// simulator's, which its SVG pictures embed PNGs with.
pub use sim::render::base64;

/// The grid's cells as grey levels, row `j = 0` (the map's bottom, next to
/// its origin) first: free [`FREE_GREY`], occupied [`OCCUPIED_GREY`],
/// unknown [`UNKNOWN_GREY`].
pub fn grid_cells_bottom_up(grid: &OccupancyGrid) -> Vec<u8> {
    grid.cells()
        .iter()
        .map(|c| match c {
            Cell::Free => FREE_GREY,
            Cell::Occupied => OCCUPIED_GREY,
            Cell::Unknown => UNKNOWN_GREY,
        })
        .collect()
}

/// The grid as an 8-bit grey PNG, one pixel per cell, its top row the
/// map's last row (`j = height − 1`), as an image of the map is seen.
pub fn grid_png(grid: &OccupancyGrid) -> Result<Vec<u8>> {
    let (w, h) = (grid.width(), grid.height());
    let cells = grid_cells_bottom_up(grid);
    let mut top_down = Vec::with_capacity(cells.len());
    for row in cells.chunks(w.max(1)).rev() {
        top_down.extend_from_slice(row);
    }
    let mut png = Vec::new();
    image::ImageEncoder::write_image(
        image::codecs::png::PngEncoder::new_with_quality(
            &mut png,
            image::codecs::png::CompressionType::Best,
            image::codecs::png::FilterType::Adaptive,
        ),
        &top_down,
        u32::try_from(w).context("the grid is too wide for a PNG")?,
        u32::try_from(h).context("the grid is too tall for a PNG")?,
        image::ExtendedColorType::L8,
    )
    .context("encoding the map as PNG")?;
    Ok(png)
}

#[cfg(test)]
mod tests {
    use super::*;
    use sim::CellIndex;

    #[test]
    fn the_png_is_the_grid_upside_down() {
        let mut g = OccupancyGrid::new(3, 2, 0.5, robot::Pose::default());
        g.set(CellIndex { i: 0, j: 0 }, Cell::Occupied);
        g.set(CellIndex { i: 2, j: 1 }, Cell::Unknown);
        assert_eq!(grid_cells_bottom_up(&g), vec![0, 255, 255, 255, 255, 205]);
        let png = grid_png(&g).unwrap();
        let img = image::load_from_memory(&png).unwrap().to_luma8();
        assert_eq!((img.width(), img.height()), (3, 2));
        assert_eq!(img.get_pixel(0, 1).0, [0]);
        assert_eq!(img.get_pixel(2, 0).0, [205]);
        assert_eq!(img.get_pixel(1, 0).0, [255]);
    }
}
