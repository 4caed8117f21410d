//! Screen tiles and binning: which triangles each tile must rasterize.
//!
//! Each tile's list keeps submission order, so the depth test resolves ties (first drawn wins)
//! the same way whatever thread rasterizes the tile.

use crate::render::TILE_SIZE;
use crate::render::raster::{PixelRect, RasterTriangle};

/// The image cut into `TILE_SIZE` squares (smaller at the right and bottom edges), numbered
/// row by row from the top-left.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TileGrid {
    pub width: u32,
    pub height: u32,
    pub columns: u32,
    pub rows: u32,
}

impl TileGrid {
    pub fn new(width: u32, height: u32) -> Self {
        TileGrid {
            width,
            height,
            columns: width.div_ceil(TILE_SIZE),
            rows: height.div_ceil(TILE_SIZE),
        }
    }

    pub fn count(&self) -> usize {
        self.columns as usize * self.rows as usize
    }

    /// The pixels of tile `index`.
    pub fn rect(&self, index: usize) -> PixelRect {
        let column = index as u32 % self.columns;
        let row = index as u32 / self.columns;
        let x0 = column * TILE_SIZE;
        let y0 = row * TILE_SIZE;
        PixelRect {
            x0,
            y0,
            x1: (x0 + TILE_SIZE).min(self.width),
            y1: (y0 + TILE_SIZE).min(self.height),
        }
    }
}

/// For each tile, the indices of the triangles whose pixel bounds overlap it, in order.
pub fn bin_triangles(grid: &TileGrid, triangles: &[RasterTriangle]) -> Vec<Vec<u32>> {
    let mut bins = vec![Vec::new(); grid.count()];
    for (index, triangle) in triangles.iter().enumerate() {
        let bounds = triangle.bounds;
        for row in bounds.y0 / TILE_SIZE..=(bounds.y1 - 1) / TILE_SIZE {
            for column in bounds.x0 / TILE_SIZE..=(bounds.x1 - 1) / TILE_SIZE {
                bins[(row * grid.columns + column) as usize].push(index as u32);
            }
        }
    }
    bins
}
