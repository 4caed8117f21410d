//! Screen tiles and binning: which triangles each tile must rasterize.
//!
//! The geometry stage cuts the scene's triangle stream into fixed chunks and each chunk bins its
//! own raster triangles, in parallel with the others: a counting sort by tile, so a chunk's bins
//! are two flat arrays (offsets per tile, then triangle indices), not a vector per tile. A tile
//! then walks the chunks in order, and within each chunk its triangles in order, so it sees the
//! triangles in submission order and the depth test resolves ties (first drawn wins) the same way
//! whatever thread runs the chunk or the tile.
//!
//! A raster triangle's id, as stored in visibility buffers, is its chunk and its index within
//! the chunk packed into a `u32` ([`raster_id`]).

use glam::Vec3;

use crate::render::TILE_SIZE;
use crate::render::raster::{Corners, NO_TRIANGLE, PixelRect, RasterTriangle};

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

    /// Calls `visit(tile)` for every tile `bounds` touches, row by row. Nearly every triangle
    /// touches one tile, which takes no loop.
    #[inline(always)]
    fn for_each_tile_touched(&self, bounds: &PixelRect, mut visit: impl FnMut(usize)) {
        let (row0, row1) = (bounds.y0 / TILE_SIZE, (bounds.y1 - 1) / TILE_SIZE);
        let (column0, column1) = (bounds.x0 / TILE_SIZE, (bounds.x1 - 1) / TILE_SIZE);
        if row0 == row1 && column0 == column1 {
            visit((row0 * self.columns + column0) as usize);
            return;
        }
        for row in row0..=row1 {
            for column in column0..=column1 {
                visit((row * self.columns + column) as usize);
            }
        }
    }
}

/// Bits of a raster id that hold the index within the chunk. A chunk of
/// [`crate::render::geometry::TRIANGLE_CHUNK`] = 4096 scene triangles makes at most 7 raster
/// triangles of each (a triangle clipped by six planes is a 9-gon), fewer than 2^15.
const INDEX_BITS: u32 = 15;

/// The id of triangle `index` of chunk `chunk`.
#[inline]
pub fn raster_id(chunk: usize, index: usize) -> u32 {
    let id = ((chunk as u32) << INDEX_BITS) | index as u32;
    debug_assert!(index < 1 << INDEX_BITS && id != NO_TRIANGLE);
    id
}

/// The chunk and index of the raster triangle `id`.
#[inline]
pub fn split_raster_id(id: u32) -> (usize, usize) {
    (
        (id >> INDEX_BITS) as usize,
        (id & ((1 << INDEX_BITS) - 1)) as usize,
    )
}

/// The raster triangles of one chunk of the triangle stream, with their bins.
#[derive(Debug, Clone, Default)]
pub struct RasterChunk {
    pub triangles: Vec<RasterTriangle>,
    /// The corner weights of this chunk's clipped triangles (see `CornerWeights`).
    pub clipped_weights: Vec<[Vec3; 3]>,
    /// Tile `t`'s triangles are `entries[offsets[t]..offsets[t + 1]]`; empty when the chunk
    /// has no triangle.
    offsets: Vec<u32>,
    /// Indices into `triangles`, grouped by tile, in order within each tile.
    entries: Vec<u32>,
}

impl RasterChunk {
    /// Bins `triangles` into the tiles of `grid` (a counting sort by tile).
    pub fn new(triangles: Vec<RasterTriangle>, grid: &TileGrid) -> Self {
        let mut chunk = RasterChunk::default();
        chunk.rebin(triangles, grid);
        chunk
    }

    /// Takes `triangles` and bins them into the tiles of `grid` (a counting sort by tile),
    /// reusing this chunk's bin arrays; the triangles it held are dropped.
    pub fn rebin(&mut self, triangles: Vec<RasterTriangle>, grid: &TileGrid) {
        self.triangles = triangles;
        self.offsets.clear();
        self.entries.clear();
        if self.triangles.is_empty() {
            return;
        }
        let offsets = &mut self.offsets;
        offsets.resize(grid.count() + 1, 0);
        for triangle in &self.triangles {
            grid.for_each_tile_touched(&triangle.bounds, |tile| offsets[tile + 1] += 1);
        }
        for t in 1..offsets.len() {
            offsets[t] += offsets[t - 1];
        }
        let mut cursor = offsets.clone();
        self.entries.resize(offsets[grid.count()] as usize, 0);
        for (index, triangle) in self.triangles.iter().enumerate() {
            grid.for_each_tile_touched(&triangle.bounds, |tile| {
                self.entries[cursor[tile] as usize] = index as u32;
                cursor[tile] += 1;
            });
        }
    }

    /// Empties the chunk and hands back its triangle array (capacity kept) for the next frame.
    pub fn take_triangles(&mut self) -> Vec<RasterTriangle> {
        let mut triangles = std::mem::take(&mut self.triangles);
        triangles.clear();
        triangles
    }

    /// The corner weights of raster triangle `index` of this chunk.
    #[inline]
    pub fn corner_weights(&self, index: usize) -> Corners {
        self.triangles[index]
            .corner_weights
            .resolve(&self.clipped_weights)
    }

    /// Indices (into `triangles`) of the triangles touching tile `tile`, in order.
    #[inline]
    pub fn tile_triangles(&self, tile: usize) -> &[u32] {
        match self.offsets.get(tile..tile + 2) {
            Some(&[start, end]) => &self.entries[start as usize..end as usize],
            _ => &[],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::raster::{SamplePattern, ScreenVertex, setup_triangle};
    use glam::Vec3;

    fn triangle(x0: f32, y0: f32, size: f32) -> RasterTriangle {
        let vertex = |x, y| ScreenVertex {
            x,
            y,
            depth: 0.5,
            inv_w: 1.0,
            weights: Vec3::ZERO,
        };
        let corners = [vertex(x0, y0), vertex(x0 + size, y0), vertex(x0, y0 + size)];
        setup_triangle(
            corners,
            200,
            150,
            SamplePattern::SINGLE,
            Default::default(),
            &mut Vec::new(),
        )
        .expect("visible")
    }

    #[test]
    fn every_triangle_lands_in_exactly_the_tiles_its_bounds_touch_in_order() {
        let grid = TileGrid::new(200, 150);
        let triangles = vec![
            triangle(10.0, 10.0, 5.0),   // tile 0 only
            triangle(60.0, 60.0, 10.0),  // tiles 0, 1, 4, 5
            triangle(150.0, 70.0, 60.0), // tiles 6, 7, 10, 11 (cut at the right edge, x = 200)
            triangle(20.0, 20.0, 3.0),   // tile 0 again, after the first
        ];
        let chunk = RasterChunk::new(triangles, &grid);
        assert_eq!(grid.count(), 12);
        let expected: [&[u32]; 12] = [
            &[0, 1, 3],
            &[1],
            &[],
            &[],
            &[1],
            &[1],
            &[2],
            &[2],
            &[],
            &[],
            &[2],
            &[2],
        ];
        for (tile, want) in expected.iter().enumerate() {
            assert_eq!(chunk.tile_triangles(tile), *want, "tile {tile}");
        }
    }

    #[test]
    fn an_empty_chunk_has_empty_bins() {
        let chunk = RasterChunk::new(Vec::new(), &TileGrid::new(64, 64));
        assert!(chunk.tile_triangles(0).is_empty());
    }

    #[test]
    fn raster_ids_round_trip() {
        for (chunk, index) in [(0, 0), (1, 5), (70_000, (1 << INDEX_BITS) - 1)] {
            assert_eq!(split_raster_id(raster_id(chunk, index)), (chunk, index));
        }
    }
}
