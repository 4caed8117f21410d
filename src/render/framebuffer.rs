//! The frame buffer: the rendered image, in which a tile no triangle reaches is a flag rather
//! than pixels.
//!
//! Most of a frame is often background: a model in the middle of a 1080p image leaves most of
//! its 510 tiles empty. Filling them pixel by pixel (13 bytes a pixel of colour and coverage)
//! cost 2 ms of a 2-thread frame, more than many small models take to draw. So the renderer only
//! records that such a tile is blank, and whoever reads the image gets the background there
//! through the accessors. Consumers that care for speed read it a row at a time in spans
//! ([`FrameBuffer::row_spans`]): a blank span is one value for many pixels (the 8-bit
//! quantiser writes the background's three bytes for the whole span).
//!
//! The pixels are stored tile by tile: band after band (a band is a row of tiles), and within
//! a band each tile's pixels as one block, row-major with the tile's width as its stride. A
//! tile's rows are then adjacent in memory and the renderer writes each tile as one run. Into an
//! image-wide row-major array, a tile's 64-pixel row is 768 bytes followed by a jump of a whole
//! image row, and those stores cost about a fifth of a flat frame of a model that fills the image
//! (docs/performance.md: cow-close flat 0.82× its time with tile blocks). Readers never see
//! the layout: every read goes through the methods below, by pixel or by row.
//!
//! Invariant: a tile is either **blank** — every pixel of it is the background, uncovered, and
//! the stored colour and coverage there are whatever an earlier frame left, never read — or
//! **drawn**, and then every one of its stored pixels was written by this frame. Every read goes
//! through the methods below, which give the background for blank tiles, so no reader can see
//! what an earlier frame left (a `Renderer` reuses its frame buffer from frame to frame).

use std::fmt;
use std::iter;

use glam::Vec3;

use crate::render::TILE_SIZE;

/// The rendered image in linear RGB, not clamped, and which pixels geometry covers (used by
/// error metrics and the depth view), read row-major from the top-left pixel. See the module
/// documentation for the storage by tiles, the blank tiles and the invariant that keeps them.
#[derive(Clone, Default)]
pub struct FrameBuffer {
    width: u32,
    height: u32,
    /// What a blank tile's pixels read as.
    background: Vec3,
    /// Per pixel, by tiles ([`FrameBuffer::index`]); meaningful in drawn tiles only.
    color: Vec<Vec3>,
    /// Per pixel, by tiles; meaningful in drawn tiles only.
    covered: Vec<bool>,
    /// Per tile of the `TILE_SIZE` grid (row-major, `width.div_ceil(TILE_SIZE)` a row): whether
    /// it is blank.
    blank: Vec<bool>,
}

/// A run of pixels of one row, from [`FrameBuffer::row_spans`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum RowSpan<'a> {
    /// This many pixels of blank tiles: the background, uncovered.
    Blank(usize),
    /// The row's pixels in one drawn tile, as stored.
    Drawn { color: &'a [Vec3], covered: &'a [bool] },
}

impl<'a> RowSpan<'a> {
    /// The span's colours, one a pixel.
    fn colors(self, background: Vec3) -> impl Iterator<Item = Vec3> + 'a {
        let (blank, drawn) = match self {
            RowSpan::Blank(count) => (count, &[][..]),
            RowSpan::Drawn { color, .. } => (0, color),
        };
        iter::repeat_n(background, blank).chain(drawn.iter().copied())
    }

    /// The span's coverage, one a pixel.
    fn coverage(self) -> impl Iterator<Item = bool> + 'a {
        let (blank, drawn) = match self {
            RowSpan::Blank(count) => (count, &[][..]),
            RowSpan::Drawn { covered, .. } => (0, covered),
        };
        iter::repeat_n(false, blank).chain(drawn.iter().copied())
    }
}

/// One band of tile rows of a frame under way, for one worker to render: its pixels (tile by
/// tile, see the module documentation) and its tiles' blank flags (one per column).
pub(crate) struct Band<'a> {
    color: &'a mut [Vec3],
    covered: &'a mut [bool],
    pub blank: &'a mut [bool],
    /// The image's width in pixels.
    width: usize,
}

impl Band<'_> {
    /// Where the pixels of the band's tile in column `column` go.
    pub(crate) fn tile(&mut self, column: usize) -> TileTarget<'_> {
        let rows = self.color.len() / self.width;
        let (start, tile_width) = tile_block(self.width, rows, column);
        let x0 = column * TILE_SIZE as usize;
        // A target's pixel is at `row · stride + x` with `x` the image column, so its slices
        // begin `x0` pixels before the tile's block: that lies in the band, as `start` is
        // `x0 · rows`, and the pixels a tile writes (`x ≥ x0`) are its own block's.
        let pixels = start - x0..start + tile_width * rows;
        TileTarget {
            color: &mut self.color[pixels.clone()],
            covered: &mut self.covered[pixels],
            stride: tile_width,
        }
    }
}

/// Where a tile's pixels go: pixel `(x, row)` of the tile, `x` the image column and `row`
/// counted from the tile's first row, is element `row · stride + x` of both slices. A frame
/// buffer's tile target ([`Band::tile`]) holds the tile's own block, `stride` its width; the
/// tests and the pixel inspector shade a tile into rows as wide as the image.
pub struct TileTarget<'a> {
    pub color: &'a mut [Vec3],
    pub covered: &'a mut [bool],
    pub stride: usize,
}

impl FrameBuffer {
    /// A frame with every pixel given (no blank tiles): the reference renderer's, and tests'.
    ///
    /// Panics unless `color` and `covered` hold `width × height` pixels.
    pub fn from_pixels(width: u32, height: u32, color: Vec<Vec3>, covered: Vec<bool>) -> Self {
        let pixels = width as usize * height as usize;
        assert!(
            color.len() == pixels && covered.len() == pixels,
            "a {width}×{height} frame holds {pixels} pixels, not {} colours and {} coverage flags",
            color.len(),
            covered.len()
        );
        FrameBuffer {
            width,
            height,
            background: Vec3::ZERO,
            color: by_tiles(width, &color),
            covered: by_tiles(width, &covered),
            blank: vec![false; tile_count(width, height)],
        }
    }

    pub fn width(&self) -> u32 {
        self.width
    }

    pub fn height(&self) -> u32 {
        self.height
    }

    /// The colour of the pixels no geometry covers in blank tiles.
    pub fn background(&self) -> Vec3 {
        self.background
    }

    /// The colour of pixel (`x`, `y`). Panics outside the image.
    pub fn pixel(&self, x: u32, y: u32) -> Vec3 {
        let index = self.index(x, y);
        if self.is_in_blank_tile(x, y) {
            self.background
        } else {
            self.color[index]
        }
    }

    /// Whether geometry covers pixel (`x`, `y`). Panics outside the image.
    pub fn is_covered(&self, x: u32, y: u32) -> bool {
        let index = self.index(x, y);
        !self.is_in_blank_tile(x, y) && self.covered[index]
    }

    /// How many tiles are blank (none in a frame made [`FrameBuffer::from_pixels`]).
    pub fn blank_tiles(&self) -> usize {
        self.blank.iter().filter(|&&blank| blank).count()
    }

    /// Row `y` as runs of blank and drawn pixels, left to right, covering the row once: a run of
    /// blank tiles is one span (a row of blank tiles one for the whole row), a drawn tile's
    /// part of the row is a span of its own. Panics below the image.
    pub fn row_spans(&self, y: u32) -> impl Iterator<Item = RowSpan<'_>> + '_ {
        assert!(y < self.height, "row {y} of a frame {} rows high", self.height);
        let width = self.width as usize;
        let columns = tile_columns(self.width);
        let tile_row = (y / TILE_SIZE) as usize;
        let flags = &self.blank[tile_row * columns..(tile_row + 1) * columns];
        let band_start = tile_row * TILE_SIZE as usize * width;
        let band_rows = band_rows(self.height, tile_row);
        let local_y = (y % TILE_SIZE) as usize;
        let tile = TILE_SIZE as usize;
        let mut column = 0;
        iter::from_fn(move || {
            let &blank = flags.get(column)?;
            if blank {
                let run = flags[column..].iter().take_while(|&&other| other).count();
                let (x0, x1) = (column * tile, ((column + run) * tile).min(width));
                column += run;
                return Some(RowSpan::Blank(x1 - x0));
            }
            let (start, tile_width) = tile_block(width, band_rows, column);
            column += 1;
            let first = band_start + start + local_y * tile_width;
            let pixels = first..first + tile_width;
            Some(RowSpan::Drawn {
                color: &self.color[pixels.clone()],
                covered: &self.covered[pixels],
            })
        })
    }

    /// Every pixel's colour, row-major.
    pub fn colors(&self) -> impl Iterator<Item = Vec3> + '_ {
        (0..self.height)
            .flat_map(|y| self.row_spans(y))
            .flat_map(|span| span.colors(self.background))
    }

    /// Every pixel's coverage, row-major.
    pub fn coverage(&self) -> impl Iterator<Item = bool> + '_ {
        (0..self.height)
            .flat_map(|y| self.row_spans(y))
            .flat_map(RowSpan::coverage)
    }

    /// Every pixel's colour, row-major, in one dense array.
    pub fn to_colors(&self) -> Vec<Vec3> {
        self.colors().collect()
    }

    /// Every pixel's coverage, row-major, in one dense array.
    pub fn to_coverage(&self) -> Vec<bool> {
        self.coverage().collect()
    }

    /// Makes this the frame buffer of a `width × height` frame on `background` with every tile
    /// blank, for the renderer to draw tiles into ([`FrameBuffer::bands_mut`]). The pixel
    /// arrays are reused as they are when the size fits: drawn tiles overwrite every pixel, and
    /// nothing reads a blank tile's.
    pub(crate) fn start_frame(&mut self, width: u32, height: u32, background: Vec3) {
        let pixels = width as usize * height as usize;
        if (self.width, self.height) != (width, height) || self.color.len() != pixels {
            // Zeroed allocations (`calloc`): fresh pages stay unmapped until a drawn tile
            // writes them, so a one-shot render never touches the pages that lie wholly in
            // blank tiles (`vec![Vec3::ZERO; n]` would write all of them first).
            self.color = bytemuck::zeroed_vec(pixels);
            self.covered = vec![false; pixels];
        }
        (self.width, self.height, self.background) = (width, height, background);
        self.blank.clear();
        self.blank.resize(tile_count(width, height), true);
    }

    /// The frame's bands of one tile row each, top to bottom. A worker that draws a tile writes
    /// all its pixels ([`Band::tile`]) and clears its blank flag.
    pub(crate) fn bands_mut(&mut self) -> impl Iterator<Item = Band<'_>> {
        let width = (self.width as usize).max(1);
        let band_pixels = TILE_SIZE as usize * width;
        let columns = tile_columns(self.width).max(1);
        self.color
            .chunks_mut(band_pixels)
            .zip(self.covered.chunks_mut(band_pixels))
            .zip(self.blank.chunks_mut(columns))
            .map(move |((color, covered), blank)| Band {
                color,
                covered,
                blank,
                width,
            })
    }

    /// The depth view's shader wrote view distances; maps them so the nearest covered pixel is
    /// white and the farthest black (a fixed range would show most scenes as one flat grey).
    /// Covered pixels lie in drawn tiles only.
    pub(crate) fn normalize_depth(&mut self) {
        let (mut nearest, mut farthest) = (f32::INFINITY, f32::NEG_INFINITY);
        for pixels in drawn_blocks(self.width, self.height, &self.blank) {
            for (color, &covered) in self.color[pixels.clone()].iter().zip(&self.covered[pixels]) {
                if covered {
                    (nearest, farthest) = (nearest.min(color.x), farthest.max(color.x));
                }
            }
        }
        let range = farthest - nearest;
        for pixels in drawn_blocks(self.width, self.height, &self.blank) {
            for (color, &covered) in self.color[pixels.clone()].iter_mut().zip(&self.covered[pixels]) {
                if covered {
                    let shade = if range > 0.0 {
                        1.0 - (color.x - nearest) / range
                    } else {
                        1.0
                    };
                    *color = Vec3::splat(shade);
                }
            }
        }
    }

    /// Where pixel (`x`, `y`) is stored: in its band, in its tile's block, in its row there.
    fn index(&self, x: u32, y: u32) -> usize {
        assert!(
            x < self.width && y < self.height,
            "pixel ({x}, {y}) of a {}×{} frame",
            self.width,
            self.height
        );
        let (tile, width) = (TILE_SIZE as usize, self.width as usize);
        let (column, tile_row) = ((x / TILE_SIZE) as usize, (y / TILE_SIZE) as usize);
        let (start, tile_width) = tile_block(width, band_rows(self.height, tile_row), column);
        tile_row * tile * width + start + (y as usize % tile) * tile_width + (x as usize % tile)
    }

    fn is_in_blank_tile(&self, x: u32, y: u32) -> bool {
        let tile = (y / TILE_SIZE) as usize * tile_columns(self.width) + (x / TILE_SIZE) as usize;
        self.blank[tile]
    }
}

/// Two frames are equal when every pixel reads the same (colour and coverage), whatever they
/// store in blank tiles.
impl PartialEq for FrameBuffer {
    fn eq(&self, other: &Self) -> bool {
        (self.width, self.height) == (other.width, other.height)
            && self.coverage().eq(other.coverage())
            && self.colors().eq(other.colors())
    }
}

/// The size and the blank tiles, not millions of pixels.
impl fmt::Debug for FrameBuffer {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("FrameBuffer")
            .field("width", &self.width)
            .field("height", &self.height)
            .field("background", &self.background)
            .field("blank_tiles", &self.blank_tiles())
            .finish_non_exhaustive()
    }
}

/// The pixel rows of tile row `tile_row` of an image `height` pixels high (the last one may be
/// lower than a tile).
fn band_rows(height: u32, tile_row: usize) -> usize {
    let first = tile_row * TILE_SIZE as usize;
    (height as usize - first).min(TILE_SIZE as usize)
}

/// The index range of each drawn tile's pixels in a `width × height` frame with the blank flags
/// `blank`: its whole block.
fn drawn_blocks(
    width: u32,
    height: u32,
    blank: &[bool],
) -> impl Iterator<Item = std::ops::Range<usize>> + '_ {
    let columns = tile_columns(width);
    blank
        .iter()
        .enumerate()
        .filter(|&(_, &blank)| !blank)
        .map(move |(tile, _)| {
            let (tile_row, column) = (tile / columns, tile % columns);
            let rows = band_rows(height, tile_row);
            let (start, tile_width) = tile_block(width as usize, rows, column);
            let first = tile_row * TILE_SIZE as usize * width as usize + start;
            first..first + tile_width * rows
        })
}

/// Where the block of the tile in column `column` of a band `rows` pixels high of a
/// `width`-pixel image begins in the band, and the tile's width: the tiles before it are each
/// `TILE_SIZE` wide.
fn tile_block(width: usize, rows: usize, column: usize) -> (usize, usize) {
    let x0 = column * TILE_SIZE as usize;
    (x0 * rows, (width - x0).min(TILE_SIZE as usize))
}

/// The row-major pixels `row_major` of an image `width` pixels wide, stored by tiles.
fn by_tiles<T: Copy + Default>(width: u32, row_major: &[T]) -> Vec<T> {
    let (width, tile) = (width as usize, TILE_SIZE as usize);
    let mut tiled = vec![T::default(); row_major.len()];
    let band_pixels = tile * width.max(1);
    for (band, rows_of_band) in tiled.chunks_mut(band_pixels).zip(row_major.chunks(band_pixels)) {
        let rows = band.len() / width;
        for column in 0..tile_columns(width as u32) {
            let (start, tile_width) = tile_block(width, rows, column);
            let x0 = column * tile;
            for (local_y, row) in rows_of_band.chunks(width).enumerate() {
                let first = start + local_y * tile_width;
                band[first..first + tile_width].copy_from_slice(&row[x0..x0 + tile_width]);
            }
        }
    }
    tiled
}

fn tile_columns(width: u32) -> usize {
    width.div_ceil(TILE_SIZE) as usize
}

fn tile_count(width: u32, height: u32) -> usize {
    tile_columns(width) * height.div_ceil(TILE_SIZE) as usize
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// The colour a drawn pixel of [`frame_with_blank_tiles`] gets.
    fn drawn_color(x: u32, y: u32) -> Vec3 {
        Vec3::new(x as f32 / 97.0, y as f32 / 61.0, (x * y) as f32 / 5000.0)
    }

    /// Whether [`frame_with_blank_tiles`] draws tile (`column`, `row`): a checkerboard.
    fn is_drawn(column: usize, row: usize) -> bool {
        (column + row).is_multiple_of(2)
    }

    /// A `width × height` frame on `background` whose tiles are drawn in a checkerboard (their
    /// pixels [`drawn_color`], every other one covered), the others blank, drawn as the renderer
    /// draws into a reused buffer: over an earlier frame that drew every tile, covered, in
    /// another colour.
    pub(crate) fn frame_with_blank_tiles(width: u32, height: u32, background: Vec3) -> FrameBuffer {
        let mut frame = FrameBuffer::default();
        frame.start_frame(width, height, Vec3::ONE);
        draw_tiles(&mut frame, |_, _| true, |_, _| (Vec3::new(9.0, -9.0, 0.5), true));
        frame.start_frame(width, height, background);
        draw_tiles(&mut frame, is_drawn, |x, y| {
            (drawn_color(x, y), (x + y).is_multiple_of(2))
        });
        frame
    }

    /// Draws the tiles `drawn` picks as the renderer does: every pixel of them written, the
    /// blank flag cleared.
    fn draw_tiles(
        frame: &mut FrameBuffer,
        drawn: impl Fn(usize, usize) -> bool,
        pixel: impl Fn(u32, u32) -> (Vec3, bool),
    ) {
        let width = frame.width as usize;
        let tile = TILE_SIZE as usize;
        for (row, mut band) in frame.bands_mut().enumerate() {
            let rows = band.color.len() / width;
            for column in 0..band.blank.len() {
                if !drawn(column, row) {
                    continue;
                }
                band.blank[column] = false;
                let target = band.tile(column);
                let x_range = column * tile..((column + 1) * tile).min(width);
                for local_y in 0..rows {
                    for x in x_range.clone() {
                        let index = local_y * target.stride + x;
                        let (color, covered) = pixel(x as u32, (row * tile + local_y) as u32);
                        (target.color[index], target.covered[index]) = (color, covered);
                    }
                }
            }
        }
    }

    #[test]
    fn blank_tiles_read_as_the_background_through_every_accessor() {
        let background = Vec3::new(0.1, 0.2, 0.3);
        let (width, height) = (200, 130);
        let frame = frame_with_blank_tiles(width, height, background);
        // 4 × 3 tiles, the last column 8 pixels wide and the last row 2 pixels high.
        assert_eq!(frame.blank_tiles(), 6);
        let colors = frame.to_colors();
        let coverage = frame.to_coverage();
        assert_eq!(colors.len(), (width * height) as usize);
        assert!(frame.colors().eq(colors.iter().copied()));
        assert!(frame.coverage().eq(coverage.iter().copied()));
        for y in 0..height {
            let mut x = 0;
            for span in frame.row_spans(y) {
                match span {
                    RowSpan::Blank(count) => x += count as u32,
                    RowSpan::Drawn { color, covered } => {
                        assert_eq!(color.len(), covered.len());
                        for (offset, (&color, &covered)) in color.iter().zip(covered).enumerate() {
                            let at = x + offset as u32;
                            assert_eq!((color, covered), (frame.pixel(at, y), frame.is_covered(at, y)));
                        }
                        x += color.len() as u32;
                    }
                }
            }
            assert_eq!(x, width, "row {y}'s spans cover it once");
            for x in 0..width {
                let index = (y * width + x) as usize;
                let drawn = is_drawn((x / TILE_SIZE) as usize, (y / TILE_SIZE) as usize);
                let (expected_color, expected_covered) = if drawn {
                    (drawn_color(x, y), (x + y).is_multiple_of(2))
                } else {
                    (background, false)
                };
                assert_eq!(frame.pixel(x, y), expected_color, "({x}, {y})");
                assert_eq!(frame.is_covered(x, y), expected_covered, "({x}, {y})");
                assert_eq!(
                    (colors[index], coverage[index]),
                    (expected_color, expected_covered)
                );
            }
        }
        // Spans of one kind are merged: a row of tile row 1 is blank, drawn, blank, drawn.
        let kinds: Vec<bool> = frame
            .row_spans(70)
            .map(|span| matches!(span, RowSpan::Blank(_)))
            .collect();
        assert_eq!(kinds, [true, false, true, false]);
    }

    #[test]
    fn tile_targets_partition_the_frame_and_read_back_row_major() {
        // 4 × 3 tiles, the last column 8 pixels wide and the last row 2 pixels high: every
        // tile drawn, each pixel a colour of its own, written through the tiles' targets.
        let (width, height) = (200, 130);
        let mut frame = FrameBuffer::default();
        frame.start_frame(width, height, Vec3::ZERO);
        let tag = |x: u32, y: u32| Vec3::new(x as f32, y as f32, 0.0);
        draw_tiles(&mut frame, |_, _| true, |x, y| (tag(x, y), x < y));
        let row_major: Vec<Vec3> = (0..height)
            .flat_map(|y| (0..width).map(move |x| tag(x, y)))
            .collect();
        assert_eq!(frame.to_colors(), row_major);
        // Every stored pixel was written once: the targets neither overlap nor leave a gap.
        let mut tags: Vec<[u32; 2]> = frame.color.iter().map(|c| [c.x as u32, c.y as u32]).collect();
        tags.sort_unstable();
        tags.dedup();
        assert_eq!(tags.len(), (width * height) as usize);
        let dense = FrameBuffer::from_pixels(width, height, row_major, frame.to_coverage());
        assert_eq!(
            dense.color, frame.color,
            "from_pixels stores by tiles as the renderer does"
        );
        assert_eq!(dense.covered, frame.covered);
    }

    #[test]
    fn frames_are_equal_by_what_they_read_not_what_they_store() {
        let background = Vec3::new(0.1, 0.2, 0.3);
        let frame = frame_with_blank_tiles(130, 70, background);
        let dense = FrameBuffer::from_pixels(130, 70, frame.to_colors(), frame.to_coverage());
        assert_eq!(frame, dense);
        let mut colors = frame.to_colors();
        colors[129] += Vec3::X; // in a blank tile
        assert_ne!(
            frame,
            FrameBuffer::from_pixels(130, 70, colors, frame.to_coverage())
        );
    }

    #[test]
    fn the_depth_view_is_normalised_over_covered_pixels_of_drawn_tiles_only() {
        let mut frame = FrameBuffer::default();
        // An earlier frame left covered distances of 100 everywhere.
        frame.start_frame(130, 70, Vec3::ZERO);
        draw_tiles(&mut frame, |_, _| true, |_, _| (Vec3::splat(100.0), true));
        frame.start_frame(130, 70, Vec3::ZERO);
        draw_tiles(
            &mut frame,
            |column, row| (column, row) == (1, 0),
            |x, _| (Vec3::splat(x as f32), x.is_multiple_of(2)),
        );
        frame.normalize_depth();
        // Covered distances 64..=126 (even x) map to 1..=0; nothing stale counts.
        assert_eq!(frame.pixel(64, 3), Vec3::ONE);
        assert_eq!(frame.pixel(126, 3), Vec3::ZERO);
        assert_eq!(frame.pixel(65, 3), Vec3::splat(65.0));
        assert_eq!(frame.pixel(0, 0), Vec3::ZERO);
    }
}
