//! Triangle setup and the per-tile rasterizer: the hot loop.
//!
//! # Coordinates
//! Screen space has its origin at the image's top-left corner, x right, y down, one unit per
//! pixel; pixel (px, py) is sampled at its centre (px + ½, py + ½), as in OpenGL. Vertices are
//! snapped to fixed point with [`SUBPIXEL_BITS`] = 8 fractional bits (1/256 pixel) and stored
//! as `i32`.
//!
//! # Edge functions
//! For an edge from `a` to `b`, `E(p) = (b.x − a.x)(p.y − a.y) − (b.y − a.y)(p.x − a.x)`.
//! With the corners ordered so the doubled area `A = E₀₁(v₂) > 0`, a point is inside when all
//! three edge functions are ≥ 0, and `λᵢ = Eᵢ / A` (Eᵢ the edge opposite vertex i) are its
//! screen-space barycentric coordinates. Stepping one pixel right adds `−(b.y − a.y)·256`, one
//! pixel down adds `(b.x − a.x)·256`: the loop walks rows with additions only.
//!
//! # Precision
//! The clipper's guard band keeps |x|, |y| ≤ [`GUARD_BAND_PIXELS`] = 2^20 px, so fixed-point
//! coordinates are below 2^28 in magnitude, their differences below 2^29, each product below
//! 2^58 and an edge function below 2^59: exact in `i64`. Exact integer edge functions make
//! coverage exact: no cracks and no double hits along shared edges, whatever the triangle.
//!
//! # Fill rule
//! A sample exactly on an edge (E = 0) belongs to the triangle only if the edge is a *top*
//! edge (horizontal, with the triangle below it) or a *left* edge. With y down and A > 0, top
//! edges run in +x (dy = 0, dx > 0) and left edges run upwards (dy < 0). Two triangles sharing
//! an edge traverse it in opposite directions, so exactly one of them owns samples on it.
//!
//! # Depth
//! Reversed-Z: depth = z_clip / w_clip is 1 at the near plane and 0 at the far plane, stored as
//! `f32`, where floating point has most of its precision near 0: distant surfaces 10⁻³ apart at
//! distance 100 with near = 10⁻³ stay distinct. Depth is the convex combination
//! `Σ λᵢ·depthᵢ`, so it never leaves the triangle's depth range. The test is strict (`>`):
//! on a tie the first triangle in submission order wins.

use crate::render::TILE_SIZE;
use crate::render::bin::{RasterChunk, raster_id};
use crate::render::lanes::{
    Backend, Floats, Ints, LANES, LaneWork, Mask, Wides, load_rows_to_blend, prefetch_item, run_widest,
};
use glam::Vec3;

/// Fractional bits of the fixed-point screen coordinates.
pub const SUBPIXEL_BITS: u32 = 8;
/// One pixel in fixed point.
pub const SUBPIXEL_ONE: i64 = 1 << SUBPIXEL_BITS;
/// Half a pixel: the offset of a pixel's centre.
const SUBPIXEL_HALF: i64 = SUBPIXEL_ONE / 2;
/// Projected coordinates never exceed this many pixels from the origin (the clipper's guard band).
pub const GUARD_BAND_PIXELS: f32 = (1 << 20) as f32;

/// A rectangle of pixels, `x0..x1` × `y0..y1` (exclusive ends).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct PixelRect {
    pub x0: u32,
    pub y0: u32,
    pub x1: u32,
    pub y1: u32,
}

impl PixelRect {
    pub fn width(&self) -> u32 {
        self.x1 - self.x0
    }

    pub fn height(&self) -> u32 {
        self.y1 - self.y0
    }

    pub fn intersect(&self, other: &PixelRect) -> Option<PixelRect> {
        let rect = PixelRect {
            x0: self.x0.max(other.x0),
            y0: self.y0.max(other.y0),
            x1: self.x1.min(other.x1),
            y1: self.y1.min(other.y1),
        };
        (rect.x0 < rect.x1 && rect.y0 < rect.y1).then_some(rect)
    }
}

/// A projected vertex, before snapping.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScreenVertex {
    /// Pixels, origin top-left, y down.
    pub x: f32,
    pub y: f32,
    /// Reversed-Z depth in [0, 1].
    pub depth: f32,
    /// 1 / w_clip, for perspective-correct interpolation.
    pub inv_w: f32,
    /// Barycentric weights of this vertex with respect to the source triangle's vertices.
    pub weights: Vec3,
}

/// A triangle ready to rasterize: snapped, ordered with positive area, with its bounds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RasterTriangle {
    /// Fixed-point corners.
    pub x: [i32; 3],
    pub y: [i32; 3],
    pub depth: [f32; 3],
    pub inv_w: [f32; 3],
    /// Barycentric weights of each corner with respect to the source triangle's vertices.
    pub corner_weights: CornerWeights,
    /// 1 / A, with A the doubled fixed-point area.
    pub inv_area: f32,
    /// The pixels whose centres may be covered, clipped to the image.
    pub bounds: PixelRect,
    /// Index of the source triangle in the frame (the key of per-triangle caches).
    pub source: u32,
    /// The source triangle's vertices, material and object: what shading reads of it, carried
    /// here so that shading a run of pixels reads nothing but this triangle (no lookup in a
    /// frame-wide triangle array, which would miss the cache on dense meshes).
    pub triangle: FrameTriangle,
    /// The source triangle is seen from behind.
    pub back_facing: bool,
}

/// How a raster triangle's corners map to its source triangle's vertices (the barycentric
/// weights of each corner): the identity for an unclipped triangle, the identity with corners 1
/// and 2 swapped when setup reordered them, or a row of its chunk's table for the pieces of a
/// clipped triangle. Nearly every triangle is unclipped, so the 36 bytes of weights are stored
/// only for the few that need them, and the raster triangles the stages stream through memory
/// stay small.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CornerWeights(u32);

impl CornerWeights {
    const IDENTITY: CornerWeights = CornerWeights(u32::MAX);
    const SWAPPED: CornerWeights = CornerWeights(u32::MAX - 1);
    const SWAPPED_AXES: [Vec3; 3] = [Vec3::X, Vec3::Z, Vec3::Y];

    /// `weights`, kept in `table` unless they are one of the two permutations of the identity
    /// (compared bit for bit, so resolving gives back exactly `weights`).
    pub fn store(weights: [Vec3; 3], table: &mut Vec<[Vec3; 3]>) -> Self {
        let bits = |w: [Vec3; 3]| w.map(|v| v.to_array().map(f32::to_bits));
        if bits(weights) == bits(Vec3::AXES) {
            CornerWeights::IDENTITY
        } else if bits(weights) == bits(Self::SWAPPED_AXES) {
            CornerWeights::SWAPPED
        } else {
            table.push(weights);
            CornerWeights(table.len() as u32 - 1)
        }
    }

    /// The weights, given the table of the chunk the triangle belongs to.
    #[inline]
    pub fn resolve(self, table: &[[Vec3; 3]]) -> Corners {
        match self {
            CornerWeights::IDENTITY => Corners::Identity,
            CornerWeights::SWAPPED => Corners::Swapped,
            CornerWeights(row) => Corners::Clipped(table[row as usize]),
        }
    }
}

/// A raster triangle's corner weights (see [`CornerWeights`]), resolved.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Corners {
    /// `[X, Y, Z]`: an unclipped triangle.
    Identity,
    /// `[X, Z, Y]`: an unclipped triangle whose corners 1 and 2 setup swapped.
    Swapped,
    /// The weights of a piece of a clipped triangle.
    Clipped([Vec3; 3]),
}

impl Corners {
    /// The weights of each corner (what `CornerWeights::store` was given).
    #[cfg(test)]
    fn to_array(self) -> [Vec3; 3] {
        match self {
            Corners::Identity => Vec3::AXES,
            Corners::Swapped => CornerWeights::SWAPPED_AXES,
            Corners::Clipped(weights) => weights,
        }
    }

    /// The source-triangle weights of the point with weights `w` over the corners:
    /// `c₀·w.x + c₁·w.y + c₂·w.z`. For the identity and its swap that sum adds exact zeros to
    /// each component of `w` (or its swap): it is that component, bit for bit, unless the
    /// component is −0 or a term is NaN, which the weights of a triangle's points never are
    /// (they are `+0` or more at the centres it covers, and finite elsewhere). So the sum is
    /// skipped for them: nearly every triangle is unclipped.
    #[inline]
    pub fn apply(&self, w: Vec3) -> Vec3 {
        match self {
            Corners::Identity => w,
            Corners::Swapped => Vec3::new(w.x, w.z, w.y),
            Corners::Clipped([a, b, c]) => *a * w.x + *b * w.y + *c * w.z,
        }
    }

    /// The values at the triangle's corners of a quantity given at the source triangle's
    /// vertices (`values`): the identity keeps them, its swap swaps the last two, and a clipped
    /// piece's corner `k` gets `v₀·cₖ.x + v₁·cₖ.y + v₂·cₖ.z`.
    #[inline]
    pub fn corner_values(&self, values: [Vec3; 3]) -> [Vec3; 3] {
        let [a, b, c] = values;
        match self {
            Corners::Identity => values,
            Corners::Swapped => [a, c, b],
            Corners::Clipped(weights) => weights.map(|w| a * w.x + b * w.y + c * w.z),
        }
    }
}

/// A triangle of the frame: its vertices (indices into `Frame::vertices`, counter-clockwise from
/// the front), material and object (index into `Frame::objects`).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct FrameTriangle {
    pub vertices: [u32; 3],
    pub material: u32,
    pub object: u32,
}

/// Where a raster triangle comes from: its frame triangle, that triangle's index in the
/// frame's stream, and the side the camera sees.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SourceTriangle {
    pub index: u32,
    pub triangle: FrameTriangle,
    pub back_facing: bool,
}

/// Snaps and orders a projected triangle; `None` when it has zero area or covers no pixel
/// centre of a `width` × `height` image.
pub fn setup_triangle(
    corners: [ScreenVertex; 3],
    width: u32,
    height: u32,
    pattern: SamplePattern,
    source: SourceTriangle,
    weights_table: &mut Vec<[Vec3; 3]>,
) -> Option<RasterTriangle> {
    let corners = corners.map(|c| SnappedVertex::snap(&c));
    let weights = [corners[0].1, corners[1].1, corners[2].1];
    let snapped = corners.map(|c| c.0);
    let bounds = sample_bounds(&snapped, width, height, pattern.reach())?;
    setup_within(snapped, Some(weights), bounds, source, weights_table)
}

/// A projected vertex snapped to fixed point: what setup needs of it besides its weights.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SnappedVertex {
    /// 1/256 pixel.
    pub x: i32,
    pub y: i32,
    pub depth: f32,
    pub inv_w: f32,
}

impl SnappedVertex {
    /// The vertex snapped, and its weights.
    #[inline]
    pub fn snap(vertex: &ScreenVertex) -> (SnappedVertex, Vec3) {
        let snap = |v: f32| round_to_i32(v * SUBPIXEL_ONE as f32);
        (
            SnappedVertex {
                x: snap(vertex.x),
                y: snap(vertex.y),
                depth: vertex.depth,
                inv_w: vertex.inv_w,
            },
            vertex.weights,
        )
    }
}

/// The pixels of a `width` × `height` image that have a sample within the bounding box of the
/// snapped `corners`, with samples up to `reach` from their pixel's centre
/// ([`SamplePattern::reach`]); `None` when there are none, and then the triangle covers no
/// sample (most triangles of a dense mesh cover no pixel centre).
#[inline]
pub fn sample_bounds(corners: &[SnappedVertex; 3], width: u32, height: u32, reach: i64) -> Option<PixelRect> {
    pixel_bounds(corners.map(|c| c.x), corners.map(|c| c.y), width, height, reach)
}

/// Orders snapped corners and sets the triangle up, its [`sample_bounds`] known to be `bounds`
/// (which the order of the corners does not change); `None` when it has zero area. The
/// geometry stage snaps each vertex once, not once per triangle that uses it, and comes here
/// directly. `weights` are the corners' weights, `None` for the identity (an unclipped
/// triangle).
#[inline]
pub fn setup_within(
    corners: [SnappedVertex; 3],
    weights: Option<[Vec3; 3]>,
    bounds: PixelRect,
    source: SourceTriangle,
    weights_table: &mut Vec<[Vec3; 3]>,
) -> Option<RasterTriangle> {
    let (mut corners, mut weights) = (corners, weights);
    let mut area = doubled_area(corners.map(|c| c.x), corners.map(|c| c.y));
    if area == 0 {
        return None;
    }
    let swapped = area < 0;
    if swapped {
        corners.swap(1, 2);
        if let Some(weights) = &mut weights {
            weights.swap(1, 2);
        }
        area = -area;
    }
    Some(RasterTriangle {
        x: corners.map(|c| c.x),
        y: corners.map(|c| c.y),
        depth: corners.map(|c| c.depth),
        inv_w: corners.map(|c| c.inv_w),
        corner_weights: match weights {
            None if swapped => CornerWeights::SWAPPED,
            None => CornerWeights::IDENTITY,
            Some(weights) => CornerWeights::store(weights, weights_table),
        },
        inv_area: 1.0 / area as f32,
        bounds,
        source: source.index,
        triangle: source.triangle,
        back_facing: source.back_facing,
    })
}

/// Rounds to the nearest integer, ties to even, for |v| < 2^31. Adding and subtracting 1.5·2^52
/// in `f64` leaves exactly the rounded value (the sum's last bit is a unit), in two additions:
/// `f32::round` is a call into libm on CPUs without SSE4.1, and this runs per vertex.
#[inline]
fn round_to_i32(v: f32) -> i32 {
    const ROUNDING: f64 = 6_755_399_441_055_744.0; // 1.5 · 2^52
    ((f64::from(v) + ROUNDING) - ROUNDING) as i32
}

fn doubled_area(x: [i32; 3], y: [i32; 3]) -> i64 {
    let [x0, x1, x2] = x.map(i64::from);
    let [y0, y1, y2] = y.map(i64::from);
    (x1 - x0) * (y2 - y0) - (y1 - y0) * (x2 - x0)
}

/// Pixels with a sample within the fixed-point bounding box, clipped to the image. `reach` is how
/// far (in 1/256 pixel) samples lie from their pixel's centre.
fn pixel_bounds(x: [i32; 3], y: [i32; 3], width: u32, height: u32, reach: i64) -> Option<PixelRect> {
    // Pixel p's centre is p·256 + 128 and its samples lie within ±reach of it: the first pixel
    // with a sample ≥ lo is ceil((lo − 128 − reach) / 256), the last with one ≤ hi is
    // floor((hi − 128 + reach) / 256).
    // (An arithmetic shift right is the floor of the division by 256, in one instruction.)
    let first = |lo: i32| -((SUBPIXEL_HALF + reach - i64::from(lo)) >> SUBPIXEL_BITS);
    let last = |hi: i32| (i64::from(hi) - SUBPIXEL_HALF + reach) >> SUBPIXEL_BITS;
    let x0 = first(x[0].min(x[1]).min(x[2])).max(0);
    let y0 = first(y[0].min(y[1]).min(y[2])).max(0);
    let x1 = (last(x[0].max(x[1]).max(x[2])) + 1).min(i64::from(width));
    let y1 = (last(y[0].max(y[1]).max(y[2])) + 1).min(i64::from(height));
    (x0 < x1 && y0 < y1).then_some(PixelRect {
        x0: x0 as u32,
        y0: y0 as u32,
        x1: x1 as u32,
        y1: y1 as u32,
    })
}

/// One edge function, ready to evaluate and step.
#[derive(Debug, Clone, Copy)]
struct Edge {
    /// Value at the first pixel centre of the current row.
    row_start: i64,
    /// Change per 1/256 pixel in x and y (for sample offsets).
    along_x: i64,
    along_y: i64,
    step_x: i64,
    step_y: i64,
    /// 0 for top-left edges (E = 0 is inside), 1 otherwise (E must be > 0).
    min_inside: i64,
}

impl Edge {
    /// The edge from `(ax, ay)` to `(bx, by)`, evaluated at the centre of pixel `(px, py)`.
    fn new(ax: i32, ay: i32, bx: i32, by: i32, px: u32, py: u32) -> Edge {
        let (ax, ay, bx, by) = (i64::from(ax), i64::from(ay), i64::from(bx), i64::from(by));
        let (dx, dy) = (bx - ax, by - ay);
        let sample_x = i64::from(px) * SUBPIXEL_ONE + SUBPIXEL_HALF;
        let sample_y = i64::from(py) * SUBPIXEL_ONE + SUBPIXEL_HALF;
        let is_top_left = (dy == 0 && dx > 0) || dy < 0;
        Edge {
            row_start: dx * (sample_y - ay) - dy * (sample_x - ax),
            along_x: -dy,
            along_y: dx,
            step_x: -dy * SUBPIXEL_ONE,
            step_y: dx * SUBPIXEL_ONE,
            min_inside: if is_top_left { 0 } else { 1 },
        }
    }

    /// Whether this edge's values from the row start over `columns` steps along x and `rows`
    /// along y, each plus up to `margin` in magnitude, are at most `limit` in magnitude. The
    /// sum of each term's magnitude bounds them in a few instructions and suffices for a
    /// mesh's small triangles; where it does not, the exact bound: the function is linear, so
    /// its largest magnitude over the box is at a corner, and the sum can be up to twice that,
    /// which sent triangles of a hundred pixels or so (a close-up's) to wider lanes for
    /// nothing. A step the lanes hold on its own (a lane's offset, a block's steps) is at most
    /// half the box's width of steps, so at most the largest value at its corners.
    #[inline(always)]
    fn within(&self, columns: i64, rows: i64, margin: i64, limit: i64) -> bool {
        if self.within_either_side(columns, rows, margin, limit) {
            return true;
        }
        let (far_x, far_y) = (columns * self.step_x, rows * self.step_y);
        self.largest_at_corners(far_x, far_y) + margin <= limit
    }

    /// [`Edge::within`]'s quick bound alone, the sum of the terms' magnitudes: it holds for
    /// the box reflected to the left of and above the row start too (up to `columns` and
    /// `rows` steps either way), where the exact bound at the box's corners says nothing.
    #[inline(always)]
    fn within_either_side(&self, columns: i64, rows: i64, margin: i64, limit: i64) -> bool {
        let (far_x, far_y) = (columns * self.step_x, rows * self.step_y);
        self.row_start.abs() + far_x.abs() + far_y.abs() + margin <= limit
    }

    /// The largest magnitude of the edge's values at the corners of the box from the row
    /// start to `far_x` and `far_y` further (out of line: only large triangles ask).
    #[cold]
    #[inline(never)]
    fn largest_at_corners(&self, far_x: i64, far_y: i64) -> i64 {
        let corner = |x: i64, y: i64| (self.row_start + x + y).abs();
        corner(0, 0)
            .max(corner(far_x, 0))
            .max(corner(0, far_y))
            .max(corner(far_x, far_y))
    }
}

/// The three edge functions of `triangle` at the fixed-point point `(x, y)` (1/256 pixel):
/// `E₀` (edge v1→v2, opposite v0), `E₁` (v2→v0), `E₂` (v0→v1). Their sum is the doubled area.
pub fn edge_values(triangle: &RasterTriangle, x: i64, y: i64) -> [i64; 3] {
    let [x0, x1, x2] = triangle.x.map(i64::from);
    let [y0, y1, y2] = triangle.y.map(i64::from);
    let edge = |ax: i64, ay: i64, bx: i64, by: i64| (bx - ax) * (y - ay) - (by - ay) * (x - ax);
    [edge(x1, y1, x2, y2), edge(x2, y2, x0, y0), edge(x0, y0, x1, y1)]
}

/// A triangle's three edge functions as planes, `Eₖ(x, y) = aₖ·x + bₖ·y + cₖ`: [`edge_values`]
/// at any point in two products and two sums per edge, for shading points scattered over a
/// tile (set up once per triangle). The same integers: with |x|, |y| < 2²⁸ (the guard band)
/// and corner differences below 2²⁹, the products are below 2⁵⁷, |cₖ| below 2⁵⁸, and every
/// partial sum is exact in `i64`.
#[derive(Debug, Clone, Copy)]
pub struct EdgePlanes {
    along_x: [i64; 3],
    along_y: [i64; 3],
    at_origin: [i64; 3],
}

impl EdgePlanes {
    pub fn new(triangle: &RasterTriangle) -> Self {
        let [x0, x1, x2] = triangle.x.map(i64::from);
        let [y0, y1, y2] = triangle.y.map(i64::from);
        // (b − a)ₓ·(y − a_y) − (b − a)_y·(x − a_x), with its terms in x, in y and constant.
        let plane =
            |ax: i64, ay: i64, bx: i64, by: i64| (-(by - ay), bx - ax, (by - ay) * ax - (bx - ax) * ay);
        let planes = [
            plane(x1, y1, x2, y2),
            plane(x2, y2, x0, y0),
            plane(x0, y0, x1, y1),
        ];
        EdgePlanes {
            along_x: planes.map(|p| p.0),
            along_y: planes.map(|p| p.1),
            at_origin: planes.map(|p| p.2),
        }
    }

    /// [`edge_values`] at the fixed-point point `(x, y)`.
    #[inline]
    pub fn at(&self, x: i64, y: i64) -> [i64; 3] {
        std::array::from_fn(|k| self.along_x[k] * x + self.along_y[k] * y + self.at_origin[k])
    }
}

/// How much [`edge_values`] change from one pixel centre to the next one to the right (one
/// pixel, 256 units, along x): stepping by these gives exactly the values at each centre.
#[inline]
pub fn edge_steps_x(triangle: &RasterTriangle) -> [i64; 3] {
    let [y0, y1, y2] = triangle.y.map(i64::from);
    [-(y2 - y1), -(y0 - y2), -(y1 - y0)].map(|dy| dy * SUBPIXEL_ONE)
}

/// How much [`edge_values`] change from one pixel centre to the next one down.
#[inline]
pub fn edge_steps_y(triangle: &RasterTriangle) -> [i64; 3] {
    let [x0, x1, x2] = triangle.x.map(i64::from);
    [x2 - x1, x0 - x2, x1 - x0].map(|dx| dx * SUBPIXEL_ONE)
}

/// Where a pixel is sampled: fixed offsets from its centre, in 1/256 pixel, the same for every
/// pixel (so the image does not depend on anything but the scene). The positions are Direct3D's
/// standard multisample patterns (scaled from 1/16 pixel): rotated grids that resolve
/// near-horizontal and near-vertical edges with as many levels as there are samples.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SamplePattern {
    offsets: &'static [(i32, i32)],
    /// [`SamplePattern::subset`] of every mask, for patterns of up to eight samples (a table of
    /// 2^16 entries for sixteen would not stay in cache); empty for sixteen.
    subsets: &'static [SampleSubset],
    /// The samples as the multisample lanes lay them out ([`SampleLanes`]).
    lanes: &'static SampleLanes,
}

/// A pattern's samples in the slots of [`rasterize_sample_lanes`]' groups: slot `s` of the
/// two groups (`s = group·LANES + lane`) holds sample `s mod S` of the block's pixel `s / S`.
/// Per group, each slot's sample offset from its pixel's centre (1/256 pixel) and its pixel.
/// From these `LaneEdges::new` forms a triangle's lane offsets with a few lane operations.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SampleLanes {
    x: [[i32; LANES]; 2],
    y: [[i32; LANES]; 2],
    pixel: [[i32; LANES]; 2],
}

/// The [`SampleLanes`] of the `N` samples of `offsets`.
const fn sample_lanes<const N: usize>(offsets: &[(i32, i32); N]) -> SampleLanes {
    let mut lanes = SampleLanes {
        x: [[0; LANES]; 2],
        y: [[0; LANES]; 2],
        pixel: [[0; LANES]; 2],
    };
    let mut sample = 0;
    while sample < N {
        let (x, y) = offsets[sample];
        // `LaneEdges::new` forms its lane offsets in `f32` on this bound.
        assert!(x.abs() <= SUBPIXEL_HALF as i32 && y.abs() <= SUBPIXEL_HALF as i32);
        sample += 1;
    }
    let mut slot = 0;
    while slot < 2 * LANES {
        let (group, lane) = (slot / LANES, slot % LANES);
        lanes.x[group][lane] = offsets[slot % N].0;
        lanes.y[group][lane] = offsets[slot % N].1;
        lanes.pixel[group][lane] = (slot / N) as i32;
        slot += 1;
    }
    lanes
}

/// Some of a pixel's samples: how many, and the mean of their offsets from the pixel's centre
/// (1/256 pixel), each coordinate's sum over the count rounded down (`div_euclid`): where a
/// triangle covering just those samples is shaded.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct SampleSubset {
    pub count: u32,
    pub mean_x: i32,
    pub mean_y: i32,
}

/// The [`SampleSubset`] of the samples of `offsets` whose bits are set in `mask` (bit `i` for
/// sample `i`); the empty subset's mean is zero.
const fn sample_subset(offsets: &[(i32, i32)], mask: u32) -> SampleSubset {
    let (mut count, mut sum_x, mut sum_y) = (0i32, 0, 0);
    let mut sample = 0;
    while sample < offsets.len() {
        if mask & (1 << sample) != 0 {
            count += 1;
            sum_x += offsets[sample].0;
            sum_y += offsets[sample].1;
        }
        sample += 1;
    }
    if count == 0 {
        return SampleSubset {
            count: 0,
            mean_x: 0,
            mean_y: 0,
        };
    }
    SampleSubset {
        count: count as u32,
        mean_x: sum_x.div_euclid(count),
        mean_y: sum_y.div_euclid(count),
    }
}

/// [`sample_subset`] of every mask of the `N` samples of `offsets` (`SUBSETS` = 2^N entries).
const fn subset_table<const N: usize, const SUBSETS: usize>(
    offsets: &[(i32, i32); N],
) -> [SampleSubset; SUBSETS] {
    let mut table = [SampleSubset {
        count: 0,
        mean_x: 0,
        mean_y: 0,
    }; SUBSETS];
    let mut mask = 0;
    while mask < SUBSETS {
        table[mask] = sample_subset(offsets, mask as u32);
        mask += 1;
    }
    table
}

const fn scaled<const N: usize>(sixteenths: [(i32, i32); N]) -> [(i32, i32); N] {
    let mut out = sixteenths;
    let mut i = 0;
    while i < N {
        out[i] = (sixteenths[i].0 * 16, sixteenths[i].1 * 16);
        i += 1;
    }
    out
}

const PATTERN_1: [(i32, i32); 1] = [(0, 0)];
const PATTERN_2: [(i32, i32); 2] = scaled([(4, 4), (-4, -4)]);
const PATTERN_4: [(i32, i32); 4] = scaled([(-2, -6), (6, -2), (-6, 2), (2, 6)]);
const PATTERN_8: [(i32, i32); 8] = scaled([
    (1, -3),
    (-1, 3),
    (5, 1),
    (-3, -5),
    (-5, 5),
    (-7, -1),
    (3, 7),
    (7, -7),
]);
const PATTERN_16: [(i32, i32); 16] = scaled([
    (1, 1),
    (-1, -3),
    (-3, 2),
    (4, -1),
    (-5, -2),
    (2, 5),
    (5, 3),
    (3, -5),
    (-2, 6),
    (0, -7),
    (-4, -6),
    (-6, 4),
    (-8, 0),
    (7, -4),
    (6, 7),
    (-7, -8),
]);

const SUBSETS_1: [SampleSubset; 2] = subset_table(&PATTERN_1);
const SUBSETS_2: [SampleSubset; 4] = subset_table(&PATTERN_2);
const SUBSETS_4: [SampleSubset; 16] = subset_table(&PATTERN_4);
const SUBSETS_8: [SampleSubset; 256] = subset_table(&PATTERN_8);

const LANES_1: SampleLanes = sample_lanes(&PATTERN_1);
const LANES_2: SampleLanes = sample_lanes(&PATTERN_2);
const LANES_4: SampleLanes = sample_lanes(&PATTERN_4);
const LANES_8: SampleLanes = sample_lanes(&PATTERN_8);
const LANES_16: SampleLanes = sample_lanes(&PATTERN_16);

impl SamplePattern {
    /// One sample at the pixel centre: no anti-aliasing.
    pub const SINGLE: SamplePattern = SamplePattern {
        offsets: &PATTERN_1,
        subsets: &SUBSETS_1,
        lanes: &LANES_1,
    };

    /// The pattern with `samples` samples per pixel: 1, 2, 4, 8 or 16.
    pub fn new(samples: u32) -> Option<SamplePattern> {
        let (offsets, subsets, lanes): (&'static [(i32, i32)], &'static [SampleSubset], _) = match samples {
            1 => (&PATTERN_1, &SUBSETS_1, &LANES_1),
            2 => (&PATTERN_2, &SUBSETS_2, &LANES_2),
            4 => (&PATTERN_4, &SUBSETS_4, &LANES_4),
            8 => (&PATTERN_8, &SUBSETS_8, &LANES_8),
            16 => (&PATTERN_16, &[], &LANES_16),
            _ => return None,
        };
        Some(SamplePattern {
            offsets,
            subsets,
            lanes,
        })
    }

    /// The samples whose bits are set in `mask` (bit `i` for sample `i`): their count and mean
    /// offset, looked up where the pattern has a table.
    #[inline]
    pub fn subset(&self, mask: u32) -> SampleSubset {
        match self.subsets.get(mask as usize) {
            Some(&subset) => subset,
            None => sample_subset(self.offsets, mask),
        }
    }

    pub fn len(&self) -> usize {
        self.offsets.len()
    }

    pub fn is_empty(&self) -> bool {
        self.offsets.is_empty()
    }

    pub fn offsets(&self) -> &'static [(i32, i32)] {
        self.offsets
    }

    /// The largest distance of a sample from its pixel's centre along x or y, in 1/256 pixel.
    pub fn reach(&self) -> i64 {
        self.offsets
            .iter()
            .map(|&(x, y)| i64::from(x.abs().max(y.abs())))
            .max()
            .unwrap_or(0)
    }
}

/// The most samples per pixel a pattern has.
pub const MAX_SAMPLES: usize = 16;

/// Sentinel triangle id of a pixel no triangle covers.
pub const NO_TRIANGLE: u32 = u32::MAX;

/// The nearest triangle at each sample of one tile.
///
/// Triangles are named by their index in `raster_ids` (the tile's triangles in the order they
/// were rasterized), not by their frame-wide raster id: shading keeps a dense table per tile
/// indexed by them (one shader or colour per triangle, no hashing).
#[derive(Debug, Clone, PartialEq)]
pub struct Visibility {
    pub rect: PixelRect,
    pub pattern: SamplePattern,
    /// Reversed-Z depth of the nearest surface (−∞ where none), `pattern.len()` per pixel.
    pub depth: Vec<f32>,
    /// Index into `raster_ids`, or [`NO_TRIANGLE`], `pattern.len()` per pixel.
    pub triangle: Vec<u32>,
    /// The frame's raster id of each triangle rasterized into the tile, in order.
    pub raster_ids: Vec<u32>,
}

impl Visibility {
    /// An empty buffer, to rasterize tiles into with [`Visibility::rasterize`].
    pub fn new() -> Self {
        Visibility {
            rect: PixelRect::default(),
            pattern: SamplePattern::SINGLE,
            depth: Vec::new(),
            triangle: Vec::new(),
            raster_ids: Vec::new(),
        }
    }

    /// Rasterizes tile `tile` (the pixels `rect`) into this buffer, replacing what it held:
    /// every chunk's triangles binned to it, chunk by chunk and in order within each, keeping
    /// the nearest at every sample (at one sample, on the widest lanes: [`SingleSampleTile`]).
    /// The arrays keep their capacity from tile to tile. Always
    /// inlined into the frame's band loop, as `shade::shade_tile` is (the inspector calls both).
    #[inline(always)]
    pub fn rasterize(
        &mut self,
        rect: PixelRect,
        pattern: SamplePattern,
        chunks: &[RasterChunk],
        tile: usize,
    ) {
        let sample_count = (rect.width() * rect.height()) as usize * pattern.len();
        self.rect = rect;
        self.pattern = pattern;
        self.depth.clear();
        self.depth.resize(sample_count, f32::NEG_INFINITY);
        self.triangle.clear();
        self.triangle.resize(sample_count, NO_TRIANGLE);
        self.raster_ids.clear();
        debug_assert!(rect.width() <= TILE_SIZE);
        run_widest(TileTriangles {
            visibility: self,
            chunks,
            tile,
        });
    }

    /// The depth test of `triangle`, the tile's triangle `local`, at every sample of the tile,
    /// by the loop written for the pattern's sample count, on lanes of backend `B`.
    #[inline(always)]
    fn rasterize_triangle<B: Backend>(&mut self, triangle: &RasterTriangle, local: u32) {
        match self.pattern.len() {
            1 => rasterize_single_sample::<B>(triangle, local, self),
            2 => rasterize_samples::<2, B>(triangle, local, self),
            4 => rasterize_samples::<4, B>(triangle, local, self),
            8 => rasterize_samples::<8, B>(triangle, local, self),
            16 => rasterize_samples::<16, B>(triangle, local, self),
            _ => self.rasterize_any_samples(triangle, local),
        }
    }

    /// The depth test of one triangle at every sample of the tile, for any pattern: the
    /// specification [`rasterize_samples`] is tested against.
    fn rasterize_any_samples(&mut self, triangle: &RasterTriangle, local: u32) {
        let (rect, samples) = (self.rect, self.pattern.len());
        let tile_width = rect.width() as usize;
        for_each_covered_sample(triangle, rect, self.pattern, |px, py, sample, depth| {
            let slot = ((py - rect.y0) as usize * tile_width + (px - rect.x0) as usize) * samples + sample;
            if depth > self.depth[slot] {
                self.depth[slot] = depth;
                self.triangle[slot] = local;
            }
        });
    }

    /// The frame's raster id of the tile's triangle `local` (a value of `triangle`).
    #[inline]
    pub fn raster_id(&self, local: u32) -> u32 {
        self.raster_ids[local as usize]
    }
}

/// How many of a tile's triangles ahead of the one being rasterized are prefetched.
const TRIANGLE_PREFETCH: usize = 4;

/// Asks for the raster triangle [`TRIANGLE_PREFETCH`] places after `indices[position]` (the
/// one being rasterized) in a tile's list of `chunk`, if there is one, before the raster reads
/// it: a tile's triangles were set up long before, so on a mesh of many triangles their records
/// have left the cache, and each one's first read would stall the raster.
#[inline(always)]
pub(crate) fn prefetch_triangle_ahead(chunk: &RasterChunk, indices: &[u32], position: usize) {
    if let Some(&ahead) = indices.get(position + TRIANGLE_PREFETCH) {
        prefetch_item(&chunk.triangles, ahead as usize);
    }
}

/// A tile's triangles rasterized on the widest lanes (see [`Visibility::rasterize`]): one call
/// of [`run_widest`] per tile, so that its cost is spread over every triangle.
struct TileTriangles<'v> {
    visibility: &'v mut Visibility,
    chunks: &'v [RasterChunk],
    tile: usize,
}

impl LaneWork for TileTriangles<'_> {
    type Output = ();

    #[inline(always)]
    fn run<B: Backend>(self) {
        let TileTriangles {
            visibility,
            chunks,
            tile,
        } = self;
        for (chunk_index, chunk) in chunks.iter().enumerate() {
            let indices = chunk.tile_triangles(tile);
            for (position, &index) in indices.iter().enumerate() {
                prefetch_triangle_ahead(chunk, indices, position);
                let triangle = &chunk.triangles[index as usize];
                let local = visibility.raster_ids.len() as u32;
                visibility.raster_ids.push(raster_id(chunk_index, index as usize));
                visibility.rasterize_triangle::<B>(triangle, local);
            }
        }
    }
}

impl Default for Visibility {
    fn default() -> Self {
        Visibility::new()
    }
}

/// Rasterizes tile `tile` (the pixels `rect`) into a new [`Visibility`].
pub fn rasterize_tile(
    rect: PixelRect,
    pattern: SamplePattern,
    chunks: &[RasterChunk],
    tile: usize,
) -> Visibility {
    let mut visibility = Visibility::new();
    visibility.rasterize(rect, pattern, chunks, tile);
    visibility
}

/// The three edge functions of `triangle` (`E₀` opposite v0, `E₁`, `E₂`) at the centre of pixel
/// `(px, py)`, ready to step. Always inlined: with the multisample loops it has several callers,
/// and once it was left out of line the single-sample loop ran 5 % more instructions (the
/// edges came back through memory).
#[inline(always)]
fn triangle_edges(triangle: &RasterTriangle, px: u32, py: u32) -> [Edge; 3] {
    let [x0, x1, x2] = triangle.x;
    let [y0, y1, y2] = triangle.y;
    [
        Edge::new(x1, y1, x2, y2, px, py),
        Edge::new(x2, y2, x0, y0, px, py),
        Edge::new(x0, y0, x1, y1, px, py),
    ]
}

/// Each of a pattern's `S` sample offsets (1/256 pixel) as offsets of the three edge functions.
#[inline(always)]
fn sample_edge_offsets<const S: usize>(edges: &[Edge; 3], pattern: &[(i32, i32)]) -> [[i64; 3]; S] {
    std::array::from_fn(|sample| {
        let (ox, oy) = pattern[sample];
        edges.map(|e| e.along_x * i64::from(ox) + e.along_y * i64::from(oy))
    })
}

/// The depth test of one triangle at the `S` samples of every pixel of the tile:
/// [`for_each_covered_sample`] written as [`rasterize_single_sample`] is, with `S` a constant so
/// that the loop over a pixel's samples unrolls. Each sample's offset becomes edge-function
/// offsets once per triangle, with the fill rule's bias folded into a second copy, so the inside
/// test is one sign check of a bitwise or; depth comes from the unbiased values, exactly as the
/// general loop computes it, and the buffers are walked as slices a row at a time instead of
/// indexed per sample. At 4, 8 and 16 samples a triangle is tested in lanes instead
/// ([`rasterize_sample_lanes`]): in `i32` lanes where its edge values over the tile fit them
/// (nearly every triangle of a mesh), else in `f64` lanes where they stay below 2⁵³ (a ground
/// plane of two triangles, a close-up's large ones); the loop here takes two samples, areas of
/// an odd tile width and triangles reaching past that.
#[inline(always)]
fn rasterize_samples<const S: usize, B: Backend>(
    triangle: &RasterTriangle,
    id: u32,
    visibility: &mut Visibility,
) {
    let rect = visibility.rect;
    let Some(area) = triangle.bounds.intersect(&rect) else {
        return;
    };
    debug_assert_eq!(visibility.pattern.len(), S);
    let pattern = visibility.pattern.offsets();
    // Eight samples at a time: in `i32` for most triangles of a mesh, in `f64` for large ones.
    if S.is_multiple_of(LANES / 2)
        && let Some(lane_area) = whole_blocks::<S>(area, rect)
    {
        let samples = visibility.pattern;
        if let Some(lane_edges) = LaneEdges::<Ints<B>>::new::<S>(triangle, &samples, lane_area) {
            rasterize_sample_lanes::<S, Ints<B>>(&lane_edges, triangle, lane_area, id, visibility);
            return;
        }
        if let Some(lane_edges) = LaneEdges::<Wides<B>>::new::<S>(triangle, &samples, lane_area) {
            rasterize_sample_lanes::<S, Wides<B>>(&lane_edges, triangle, lane_area, id, visibility);
            return;
        }
    }
    let mut edges = triangle_edges(triangle, area.x0, area.y0);
    let [d0, d1, d2] = triangle.depth;
    let inv_area = triangle.inv_area;
    let offsets: [[i64; 3]; S] = sample_edge_offsets(&edges, pattern);
    let biased = offsets.map(|offset| std::array::from_fn::<i64, 3, _>(|k| offset[k] - edges[k].min_inside));
    // Per edge, the bias of the sample nearest its inside and of the one farthest from it: a
    // pixel whose best sample is outside an edge has no sample inside, and one whose worst
    // sample is inside every edge has all of them inside (the per-sample test is then the
    // same for every sample, and is skipped).
    let [nearest, farthest]: [[i64; 3]; 2] = [
        std::array::from_fn(|k| biased.iter().map(|b| b[k]).max().unwrap_or(0)),
        std::array::from_fn(|k| biased.iter().map(|b| b[k]).min().unwrap_or(0)),
    ];
    let tile_width = rect.width() as usize;
    let columns = (area.x1 - area.x0) as usize;
    for py in area.y0..area.y1 {
        let row = ((py - rect.y0) as usize * tile_width + (area.x0 - rect.x0) as usize) * S;
        let depths = &mut visibility.depth[row..row + columns * S];
        let ids = &mut visibility.triangle[row..row + columns * S];
        let mut centre = edges.map(|e| e.row_start);
        for (pixel_depths, pixel_ids) in depths.chunks_exact_mut(S).zip(ids.chunks_exact_mut(S)) {
            let some_inside =
                ((centre[0] + nearest[0]) | (centre[1] + nearest[1]) | (centre[2] + nearest[2])) >= 0;
            if some_inside {
                let all_inside =
                    ((centre[0] + farthest[0]) | (centre[1] + farthest[1]) | (centre[2] + farthest[2])) >= 0;
                for sample in 0..S {
                    let [b0, b1, b2] = biased[sample];
                    if all_inside || ((centre[0] + b0) | (centre[1] + b1) | (centre[2] + b2)) >= 0 {
                        let [o0, o1, o2] = offsets[sample];
                        let [e0, e1, e2] = [centre[0] + o0, centre[1] + o1, centre[2] + o2];
                        let depth = (e0 as f32 * d0 + e1 as f32 * d1 + e2 as f32 * d2) * inv_area;
                        if depth > pixel_depths[sample] {
                            pixel_depths[sample] = depth;
                            pixel_ids[sample] = id;
                        }
                    }
                }
            }
            centre = std::array::from_fn(|k| centre[k] + edges[k].step_x);
        }
        for edge in &mut edges {
            edge.row_start += edge.step_y;
        }
    }
}

/// A triangle's edge functions over one tile area in lanes `E` (`i32` or `f64`), laid out for
/// [`rasterize_sample_lanes`]: a block of pixels (two at four samples, one at eight or more)
/// whose samples fill whole groups of [`LANES`] slots of the visibility buffer. The rows and
/// blocks are stepped in exact scalars as wide as the lanes ([`EdgeLanes::Whole`]), splatted
/// once per group.
struct LaneEdges<E: EdgeLanes> {
    /// Each edge's value at the centre of the area's first pixel.
    row_start: [E::Whole; 3],
    step_x: [E::Whole; 3],
    step_y: [E::Whole; 3],
    /// Per group of a block and edge, each lane's offset from the block's first pixel centre:
    /// its sample's offset plus its pixel's steps.
    offsets: [[E; 3]; 2],
    /// The same minus the fill rule's bias (`min_inside`): the lane's sample is inside where
    /// all three are ≥ 0 once the centre is added.
    biased: [[E; 3]; 2],
    /// Per pixel of a block and edge, the bias of the sample nearest the edge's inside (from
    /// the block's first pixel centre): no sample of the pixel is inside if one is negative.
    nearest: [[E::Whole; 3]; LANES / 4],
}

/// `area` (the triangle's part of the tile `rect`) widened, at four samples, by one pixel
/// where its rows have an odd number of pixels, so that they are whole blocks of two for
/// [`rasterize_sample_lanes`]: on the right where the tile goes on, else on the left. Either
/// way the pixel added lies outside the triangle's bounds (the side widened is the bounds' own
/// edge), so none of its samples is inside and the lanes leave it as it was. `None` where the
/// area spans a tile of odd width (the `i64` loop takes the triangle).
#[inline(always)]
fn whole_blocks<const S: usize>(area: PixelRect, rect: PixelRect) -> Option<PixelRect> {
    let block_pixels = (LANES / S).max(1) as u32;
    if (area.x1 - area.x0).is_multiple_of(block_pixels) {
        Some(area)
    } else if area.x1 < rect.x1 {
        Some(PixelRect {
            x1: area.x1 + 1,
            ..area
        })
    } else if area.x0 > rect.x0 {
        Some(PixelRect {
            x0: area.x0 - 1,
            ..area
        })
    } else {
        None
    }
}

/// The largest span, in 1/256 pixel, of a box holding a triangle's corners and every point
/// the lane loop evaluates its edge functions at, for which those values fit in `i32`: each is
/// `dx·(y − a_y) − dy·(x − a_x)` with all four factors within the span, so at most
/// `2·span² < 2³¹ − 1` in magnitude (the fill rule's bias adds one).
const LANE_SPAN: i64 = 32_767;
// `LaneEdges::new` forms a small triangle's lane offsets in `f32`, exact below 2²⁴.
const _: () = assert!(2 * LANE_SPAN * SUBPIXEL_HALF + LANE_SPAN * SUBPIXEL_ONE < 1 << 24);

impl<E: EdgeLanes> LaneEdges<E> {
    /// Whether a box no wider or taller than [`LANE_SPAN`] holds the triangle's corners and
    /// every point the lane loop evaluates over `area`: the pixel centres, one block past the
    /// last column and one row past the last, each with its samples' offsets (at most half a
    /// pixel). A few comparisons, where [`LaneEdges::fit`] bounds each edge; nearly every
    /// triangle of a mesh passes.
    #[inline(always)]
    fn small(triangle: &RasterTriangle, area: PixelRect) -> bool {
        let span = |corners: [i32; 3], first: u32, end: u32| {
            let low = i64::from(corners[0].min(corners[1]).min(corners[2]));
            let high = i64::from(corners[0].max(corners[1]).max(corners[2]));
            // A pixel's samples lie within its own square; two more pixels past the end cover
            // the steps past the last block or row.
            let points_low = i64::from(first) * SUBPIXEL_ONE;
            let points_high = (i64::from(end) + 2) * SUBPIXEL_ONE;
            high.max(points_high) - low.min(points_low)
        };
        span(triangle.x, area.x0, area.x1) <= LANE_SPAN && span(triangle.y, area.y0, area.y1) <= LANE_SPAN
    }

    /// Whether every value the lane loop forms over `area`, for `S` samples per pixel with
    /// edge-function offsets `sample_offsets`, is held exactly by the lanes `E` (at most
    /// [`EdgeLanes::LIMIT`] in magnitude). Converting such a lane to `f32` rounds exactly as
    /// converting the same value held in an `i64`, so the depths keep their bits.
    #[inline(always)]
    fn fit<const S: usize>(edges: &[Edge; 3], sample_offsets: &[[i64; 3]; S], area: PixelRect) -> bool {
        let block_pixels = (LANES / S).max(1);
        let (columns, rows) = (i64::from(area.x1 - area.x0), i64::from(area.y1 - area.y0));
        // Every value formed is a centre (the row's start plus whole steps, one block past the
        // last column and one row past the last) plus a lane's offset (its sample's offset plus
        // at most a block's steps) and the bias (0 or 1).
        edges.iter().enumerate().all(|(k, edge)| {
            let reach = sample_offsets
                .iter()
                .map(|offset| offset[k].abs())
                .max()
                .unwrap_or(0);
            edge.within(columns + 2 * block_pixels as i64, rows + 1, reach + 1, E::LIMIT)
        })
    }

    /// The layout of `triangle` over `area` (whole blocks: [`whole_blocks`]) for `S` samples
    /// per pixel at the offsets of `samples`, where the lanes `E` hold its values exactly
    /// ([`LaneEdges::small`], which suffices for `i32` and so for `f64`, else
    /// [`LaneEdges::fit`]).
    #[inline(always)]
    fn new<const S: usize>(
        triangle: &RasterTriangle,
        samples: &SamplePattern,
        area: PixelRect,
    ) -> Option<Self> {
        let edges = triangle_edges(triangle, area.x0, area.y0);
        let groups = (S * (LANES / S).max(1)) / LANES;
        let step_x = edges.map(|edge| edge.step_x);
        let min_inside = edges.map(|edge| edge.min_inside);
        let mut offsets = [[E::splat_whole(0); 3]; 2];
        // Per edge, the largest offset of a sample of the block's first pixel.
        let largest: [i64; 3];
        if Self::small(triangle, area) {
            // Each lane's offset `along_x·x + along_y·y + step_x·pixel` is formed in `f32`
            // lanes, exactly: the edge's deltas are within the triangle's span (below 2¹⁵), the
            // samples' offsets at most half a pixel (2⁷, `sample_lanes`) and `pixel` 0 or 1,
            // so every product, sum and the result is a whole number below
            // `2·2¹⁵·2⁷ + 2¹⁵·2⁸ < 2²⁴` in magnitude ([`LANE_SPAN`]).
            let lanes = samples.lanes;
            let mut most = [f32::NEG_INFINITY; 3];
            for (group, group_offsets) in offsets.iter_mut().enumerate().take(groups) {
                let [x, y, pixel] =
                    [lanes.x[group], lanes.y[group], lanes.pixel[group]].map(|l| Ints::new(l).to_floats());
                for (k, edge) in edges.iter().enumerate() {
                    let [along_x, along_y, step] =
                        [edge.along_x, edge.along_y, edge.step_x].map(|value| Floats::splat(value as f32));
                    let offset = along_x * x + along_y * y + step * pixel;
                    group_offsets[k] = E::from_whole_floats(offset);
                    for (lane, &value) in offset.0.iter().enumerate() {
                        if group * LANES + lane < S && value > most[k] {
                            most[k] = value;
                        }
                    }
                }
            }
            largest = most.map(|value| value as i64);
        } else {
            let sample_offsets: [[i64; 3]; S] = sample_edge_offsets(&edges, samples.offsets());
            if !Self::fit(&edges, &sample_offsets, area) {
                return None;
            }
            // Every value below is among those `fit` bounds.
            for (group, offsets) in offsets.iter_mut().enumerate().take(groups) {
                for (k, offset) in offsets.iter_mut().enumerate() {
                    *offset = E::from_whole(|lane| {
                        let slot = group * LANES + lane;
                        sample_offsets[slot % S][k] + (slot / S) as i64 * step_x[k]
                    });
                }
            }
            largest =
                std::array::from_fn(|k| sample_offsets.iter().map(|offset| offset[k]).max().unwrap_or(0));
        }
        let biased = offsets.map(|group| std::array::from_fn(|k| group[k] + E::splat_whole(-min_inside[k])));
        let best: [i64; 3] = std::array::from_fn(|k| largest[k] - min_inside[k]);
        let narrow = E::Whole::narrow;
        let nearest =
            std::array::from_fn(|pixel| std::array::from_fn(|k| narrow(best[k] + pixel as i64 * step_x[k])));
        Some(LaneEdges {
            row_start: edges.map(|edge| narrow(edge.row_start)),
            step_x: step_x.map(narrow),
            step_y: edges.map(|edge| narrow(edge.step_y)),
            offsets,
            biased,
            nearest,
        })
    }
}

/// [`rasterize_samples`]'s loop in lanes for `S` = 4, 8 or 16 samples per pixel, over a
/// triangle whose edge values the lanes `E` hold exactly ([`LaneEdges::new`]) and an area of
/// whole blocks ([`whole_blocks`]): a block's samples (two pixels at four samples, else one
/// pixel) are tested and their depths interpolated eight at a time, in the same operations as
/// the scalar loop, and the nearer ones written with a select.
#[inline(always)]
fn rasterize_sample_lanes<const S: usize, E: EdgeLanes>(
    edges: &LaneEdges<E>,
    triangle: &RasterTriangle,
    area: PixelRect,
    id: u32,
    visibility: &mut Visibility,
) {
    let ([d0, d1, d2], inv_area) = (triangle.depth, triangle.inv_area);
    let rect = visibility.rect;
    let block_pixels = (LANES / S).max(1);
    let block_slots = block_pixels * S;
    let groups = block_slots / LANES;
    let tile_width = rect.width() as usize;
    let columns = (area.x1 - area.x0) as usize;
    debug_assert!(columns.is_multiple_of(block_pixels));
    let [weight0, weight1, weight2, inv_area_lanes] = [d0, d1, d2, inv_area].map(Floats::splat);
    let not_negative = E::splat_whole(-1);
    let id_lanes = Ints::splat(id as i32);
    let (zero, block_step) = (E::Whole::narrow(0), E::Whole::narrow(block_pixels as i64));
    let mut row_start = edges.row_start;
    for py in area.y0..area.y1 {
        let row = ((py - rect.y0) as usize * tile_width + (area.x0 - rect.x0) as usize) * S;
        let depths = &mut visibility.depth[row..row + columns * S];
        let ids = &mut visibility.triangle[row..row + columns * S];
        let mut centre = row_start;
        let depth_blocks = depths.chunks_exact_mut(block_slots);
        let id_blocks = ids.chunks_exact_mut(block_slots);
        for (block_depths, block_ids) in depth_blocks.zip(id_blocks) {
            let some_inside = edges.nearest[..block_pixels].iter().any(|nearest| {
                ((centre[0] + nearest[0]) | (centre[1] + nearest[1]) | (centre[2] + nearest[2])) >= zero
            });
            if some_inside {
                for group in 0..groups {
                    let at = |k: usize| E::splat(centre[k]);
                    let [o0, o1, o2] = edges.offsets[group];
                    let [b0, b1, b2] = edges.biased[group];
                    let inside = (at(0) + b0)
                        .gt(not_negative)
                        .and((at(1) + b1).gt(not_negative))
                        .and((at(2) + b2).gt(not_negative));
                    let depth = ((at(0) + o0).to_floats() * weight0
                        + (at(1) + o1).to_floats() * weight1
                        + (at(2) + o2).to_floats() * weight2)
                        * inv_area_lanes;
                    let slots = group * LANES..(group + 1) * LANES;
                    let group_depths: &mut [f32; LANES] = (&mut block_depths[slots.clone()])
                        .try_into()
                        .expect("a group of lanes");
                    let group_ids: &mut [u32; LANES] =
                        (&mut block_ids[slots]).try_into().expect("a group of lanes");
                    let old = Floats::load_to_blend(group_depths);
                    let nearer = inside.and(depth.gt(old));
                    if nearer.any() {
                        *group_depths = nearer.select(depth, old).0;
                        let old_ids = Ints::load_to_blend(group_ids);
                        *group_ids = bytemuck::cast(nearer.select_ints(id_lanes, old_ids).0);
                    }
                }
            }
            centre = std::array::from_fn(|k| centre[k] + block_step * edges.step_x[k]);
        }
        row_start = std::array::from_fn(|k| row_start[k] + edges.step_y[k]);
    }
}

/// The depth test of one triangle at every pixel centre of the tile: [`for_each_covered_sample`]
/// with one sample, written for the common case (see [`depth_test_single_sample`]), on lanes of
/// backend `B`.
#[inline(always)]
fn rasterize_single_sample<B: Backend>(triangle: &RasterTriangle, id: u32, visibility: &mut Visibility) {
    let rect = visibility.rect;
    let rows = RowLayout {
        stride: rect.width() as usize,
        x_origin: rect.x0,
    };
    depth_test_single_sample::<true, B>(
        triangle,
        rect,
        rows,
        &mut visibility.depth,
        &mut visibility.triangle,
        id,
    );
}

/// The depth test of `triangle` at every pixel centre of `rect` (within a tile), straight into
/// `depth`, the image's rows from `rect.y0` on, `stride` apart (a band of a shadow map): where
/// the triangle is nearer than what a texel holds, the texel gets its depth, as in
/// [`Visibility::rasterize`] with one sample, and nothing else is written (no triangle numbers,
/// no buffer of the tile's own). On lanes of backend `B` (see [`run_widest`]).
#[inline(always)]
pub fn rasterize_depth_only<B: Backend>(
    triangle: &RasterTriangle,
    rect: PixelRect,
    depth: &mut [f32],
    stride: usize,
) {
    debug_assert!(rect.width() <= TILE_SIZE);
    let rows = RowLayout { stride, x_origin: 0 };
    depth_test_single_sample::<false, B>(triangle, rect, rows, depth, &mut [], 0);
}

/// A bound on the depth a triangle with corner depths `depths` can write: no depth
/// interpolated at a covered centre exceeds it. That depth is `((e₀·d₀ + e₁·d₁) + e₂·d₂)·(1/A)`
/// with integer `eᵢ ≥ 0` summing to `A`, so exactly it is at most `max dᵢ`; the roundings on
/// the way (three conversions, two products and two sums, the reciprocal of `A` and the last
/// product) add under `8·2⁻²⁴·max |dᵢ|` to it, and the bound adds `2⁻²⁰·max |dᵢ|` (which the
/// rounding of its own sum cannot halve).
#[inline]
pub fn depth_bound(depths: [f32; 3]) -> f32 {
    let [d0, d1, d2] = depths;
    let nearest = d0.max(d1).max(d2);
    let magnitude = d0.abs().max(d1.abs()).max(d2.abs());
    nearest + magnitude * (1.0 / (1 << 20) as f32)
}

/// Where the pixels of a rect lie in a depth buffer: pixel `(px, py)` at
/// `(py − rect.y0)·stride + px − x_origin`.
#[derive(Debug, Clone, Copy)]
struct RowLayout {
    stride: usize,
    x_origin: u32,
}

/// The narrowest part of a triangle, in pixels of a tile's row, that the one-sample depth test
/// takes in lanes (see [`depth_test_single_sample`]).
const LANE_COLUMNS: usize = LANES / 2;

/// Which [`BlockLanes`] take a triangle's area over a tile, if any: areas at most half a group
/// wide and two rows or more tall in blocks of two rows, areas of one group in blocks of one,
/// areas of two groups in two blocks of one across.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum NarrowArea {
    Blocks4,
    Blocks8,
    Blocks16,
    No,
}

impl NarrowArea {
    /// For an area of `columns` by `rows` pixels. A single row of one to three pixels stays
    /// in the scalar loop: a block of eight there changed the far koala's and nefertiti's
    /// instructions by under 0.3 %, either way.
    #[inline(always)]
    fn of(columns: usize, rows: usize) -> NarrowArea {
        if columns <= LANES / 2 && rows >= 2 {
            NarrowArea::Blocks4
        } else if (LANE_COLUMNS..=LANES).contains(&columns) {
            NarrowArea::Blocks8
        } else if (LANES + 1..=2 * LANES).contains(&columns) {
            NarrowArea::Blocks16
        } else {
            NarrowArea::No
        }
    }
}

/// The depth test of one triangle at every pixel centre of `rect`: [`for_each_covered_sample`]
/// with one sample, written for the common case, into `depth` laid out as `rows` says; with
/// `IDS`, the winning pixels of `ids` (laid out alike) get `id`, else `ids` is not touched. The
/// fill rule's bias is folded into the edge values (`E − min_inside ≥ 0`), so the inside test is
/// one sign check of their bitwise or. Depth is computed from the unbiased values, exactly as
/// the general loop does.
#[inline(always)]
fn depth_test_single_sample<const IDS: bool, B: Backend>(
    triangle: &RasterTriangle,
    rect: PixelRect,
    rows: RowLayout,
    depth: &mut [f32],
    ids: &mut [u32],
    id: u32,
) {
    let Some(area) = triangle.bounds.intersect(&rect) else {
        return;
    };
    let mut edges = triangle_edges(triangle, area.x0, area.y0);
    let [d0, d1, d2] = triangle.depth;
    let inv_area = triangle.inv_area;
    let columns = (area.x1 - area.x0) as usize;
    // Eight pixels at a time wherever that pays, in `i32` lanes where the edge functions fit,
    // else (large triangles) in `f64` lanes. Lanes cost no branch per pixel on whether it is
    // inside, which mispredicts on a scan's small triangles (the koala's raster and a shadow
    // map's pass took about 0.9 of the time they took in the scalar loop).
    // - Areas at most two groups wide (most of a mesh's and a shadow map's triangles): blocks
    //   of two rows of four pixels, or rows of one or two groups (`BlockLanes`; a single row of
    //   one to three pixels stays scalar).
    // - Wider areas in rows of groups (`RowLanes`), each row only where its `RowSpan` reaches;
    //   and areas whose blocks do not fit their tile, whole.
    let narrow = NarrowArea::of(columns, (area.y1 - area.y0) as usize);
    if narrow != NarrowArea::No && RowLanes::<Ints<B>>::fits_either_side(&edges, area) {
        // `if let`s, not closures: a closure's lane operations would be compiled out of line,
        // without the lanes' target features.
        let depths = triangle.depth;
        match narrow {
            NarrowArea::Blocks4 => {
                if let Some(blocks) =
                    BlockLanes::<B, { LANES / 2 }, 1>::place(&edges, area, rect, depths, inv_area)
                {
                    blocks.depth_test::<IDS>(rect, rows, depth, ids, id);
                    return;
                }
            }
            NarrowArea::Blocks8 => {
                if let Some(blocks) = BlockLanes::<B, LANES, 1>::place(&edges, area, rect, depths, inv_area) {
                    blocks.depth_test::<IDS>(rect, rows, depth, ids, id);
                    return;
                }
            }
            _ => {
                if let Some(blocks) = BlockLanes::<B, LANES, 2>::place(&edges, area, rect, depths, inv_area) {
                    blocks.depth_test::<IDS>(rect, rows, depth, ids, id);
                    return;
                }
            }
        }
    }
    if (LANE_COLUMNS..=2 * LANES).contains(&columns) && RowLanes::<Ints<B>>::fit(&edges, area) {
        let lanes = RowLanes::<Ints<B>>::new::<false>(&edges, triangle.depth, inv_area);
        lanes.depth_test::<IDS, false>(rect, area, rows, depth, ids, id);
        return;
    }
    if columns > 2 * LANES {
        if RowLanes::<Ints<B>>::fit(&edges, area) {
            let lanes = RowLanes::<Ints<B>>::new::<true>(&edges, triangle.depth, inv_area);
            lanes.depth_test::<IDS, true>(rect, area, rows, depth, ids, id);
            return;
        }
        if RowLanes::<Wides<B>>::fit(&edges, area) {
            let lanes = RowLanes::<Wides<B>>::new::<true>(&edges, triangle.depth, inv_area);
            lanes.depth_test::<IDS, true>(rect, area, rows, depth, ids, id);
            return;
        }
    } else if columns >= LANE_COLUMNS && RowLanes::<Wides<B>>::fit(&edges, area) {
        let lanes = RowLanes::<Wides<B>>::new::<false>(&edges, triangle.depth, inv_area);
        lanes.depth_test::<IDS, false>(rect, area, rows, depth, ids, id);
        return;
    }
    let [m0, m1, m2] = edges.map(|e| e.min_inside);
    // The depth where the edge values put a pixel centre inside the triangle.
    let covered_depth = |[e0, e1, e2]: [i64; 3]| {
        let inside = ((e0 - m0) | (e1 - m1) | (e2 - m2)) >= 0;
        // Computed only inside: most pixels of a bounding box are outside.
        if inside {
            Some((e0 as f32 * d0 + e1 as f32 * d1 + e2 as f32 * d2) * inv_area)
        } else {
            None
        }
    };
    let steps = edges.map(|e| e.step_x);
    for py in area.y0..area.y1 {
        let row = (py - rect.y0) as usize * rows.stride + (area.x0 - rows.x_origin) as usize;
        let depths = &mut depth[row..row + columns];
        let mut e = edges.map(|e| e.row_start);
        if IDS {
            let ids = &mut ids[row..row + columns];
            for (depth_slot, id_slot) in depths.iter_mut().zip(ids.iter_mut()) {
                if let Some(depth) = covered_depth(e)
                    && depth > *depth_slot
                {
                    *depth_slot = depth;
                    *id_slot = id;
                }
                e = [e[0] + steps[0], e[1] + steps[1], e[2] + steps[2]];
            }
        } else {
            for depth_slot in depths.iter_mut() {
                if let Some(depth) = covered_depth(e)
                    && depth > *depth_slot
                {
                    *depth_slot = depth;
                }
                e = [e[0] + steps[0], e[1] + steps[1], e[2] + steps[2]];
            }
        }
        for edge in &mut edges {
            edge.row_start += edge.step_y;
        }
    }
}

/// Whole numbers in lanes, as [`RowLanes`] holds edge functions: `i32` lanes where a
/// triangle's values over the area fit (the cheaper), `f64` lanes (exact below 2⁵³) for large
/// triangles, whose edge functions grow with their size squared.
trait EdgeLanes: Copy + std::ops::Add<Output = Self> {
    /// Whose operations the lanes take, and so the depths and masks formed from them.
    type Backend: Backend;
    /// The largest magnitude a lane holds exactly.
    const LIMIT: i64;
    /// The scalar beside the lanes, as wide as they are: a loop over `i32` lanes steps its rows
    /// and tests its blocks in `i32` too.
    type Whole: Whole;
    /// `value` in every lane.
    fn splat(value: Self::Whole) -> Self;
    /// `value` in every lane (`|value| ≤ LIMIT`).
    fn splat_whole(value: i64) -> Self;
    /// Each lane's `value(lane)` (`|value| ≤ LIMIT`).
    fn from_whole(value: impl Fn(usize) -> i64) -> Self;
    /// Each lane of `whole`, whose lanes hold whole numbers below 2²⁴ in magnitude.
    fn from_whole_floats(whole: Floats<Self::Backend>) -> Self;
    fn gt(self, other: Self) -> Mask<Self::Backend>;
    /// Each lane as `f32`, rounded as converting the same `i64` rounds.
    fn to_floats(self) -> Floats<Self::Backend>;
}

impl<B: Backend> EdgeLanes for Ints<B> {
    type Backend = B;
    const LIMIT: i64 = i32::MAX as i64;
    type Whole = i32;
    #[inline(always)]
    fn splat(value: i32) -> Self {
        Ints::splat(value)
    }
    #[inline(always)]
    fn splat_whole(value: i64) -> Self {
        Ints::splat(value as i32)
    }
    #[inline(always)]
    fn from_whole(value: impl Fn(usize) -> i64) -> Self {
        Ints::new(std::array::from_fn(|lane| value(lane) as i32))
    }
    #[inline(always)]
    fn from_whole_floats(whole: Floats<B>) -> Self {
        whole.truncate_to_ints()
    }
    #[inline(always)]
    fn gt(self, other: Self) -> Mask<B> {
        Ints::gt(self, other)
    }
    #[inline(always)]
    fn to_floats(self) -> Floats<B> {
        Ints::to_floats(self)
    }
}

impl<B: Backend> EdgeLanes for Wides<B> {
    type Backend = B;
    const LIMIT: i64 = 1 << 53;
    type Whole = i64;
    #[inline(always)]
    fn splat(value: i64) -> Self {
        Wides::splat(value as f64)
    }
    #[inline(always)]
    fn splat_whole(value: i64) -> Self {
        Wides::splat(value as f64)
    }
    #[inline(always)]
    fn from_whole(value: impl Fn(usize) -> i64) -> Self {
        Wides::new(std::array::from_fn(|lane| value(lane) as f64))
    }
    #[inline(always)]
    fn from_whole_floats(whole: Floats<B>) -> Self {
        Wides::new(whole.0.map(f64::from))
    }
    #[inline(always)]
    fn gt(self, other: Self) -> Mask<B> {
        Wides::gt(self, other)
    }
    #[inline(always)]
    fn to_floats(self) -> Floats<B> {
        Wides::to_floats(self)
    }
}

/// A whole number of an [`EdgeLanes`] type's scalar: `i32` or `i64`.
trait Whole:
    Copy
    + std::ops::Add<Output = Self>
    + std::ops::Mul<Output = Self>
    + std::ops::BitOr<Output = Self>
    + PartialOrd
{
    /// `value`, which the caller's bounds keep within the type.
    fn narrow(value: i64) -> Self;
}

impl Whole for i32 {
    #[inline(always)]
    fn narrow(value: i64) -> Self {
        value as i32
    }
}

impl Whole for i64 {
    #[inline(always)]
    fn narrow(value: i64) -> Self {
        value
    }
}

/// A triangle's edge functions in lanes `E` over the rows of one tile area, for
/// [`depth_test_single_sample`]: each row is walked in groups of [`LANES`] pixels from the
/// area's first column, lane `i` at the `i`-th pixel of its group. The rows and groups are
/// stepped in exact `i64` scalars, splatted once per group.
struct RowLanes<E: EdgeLanes> {
    /// Each edge's value at the centre of the area's first pixel.
    row_start: [i64; 3],
    step_y: [i64; 3],
    /// One group's step along a row: `LANES` pixels.
    group_step: [i64; 3],
    /// Per edge, each lane's offset from its group's first pixel centre.
    offsets: [E; 3],
    /// Per edge, the fill rule's bound: a lane's centre is inside where each edge value is
    /// above it (`E > min_inside − 1` is `E ≥ min_inside`).
    above: [E; 3],
    corner_depths: [Floats<E::Backend>; 3],
    inv_area: Floats<E::Backend>,
    /// Where along each row the triangle can be: see [`RowSpan`].
    span: RowSpan,
}

/// A triangle's edges as bounds along a row, for skipping the groups of a row that lie wholly
/// outside it (a large triangle's bounds over a tile are mostly outside it along its sloping
/// edges). Edge `k` is inside at the row's `i`-th pixel where `margin + step_x·i ≥ 0`, with
/// `margin` its value at the row's first pixel less the fill rule's `min_inside`: from
/// `i ≥ −margin/step_x` (`step_x > 0`) or `i ≤ −margin/step_x` (`step_x < 0`), or at every
/// pixel or none (`step_x = 0`).
#[derive(Debug, Clone, Copy)]
struct RowSpan {
    min_inside: [i64; 3],
    step_x: [i64; 3],
    /// `1/step_x` (0 where `step_x` is 0).
    inv_step_x: [f64; 3],
}

impl RowSpan {
    /// No span, for lanes whose rows are tested whole.
    const NONE: RowSpan = RowSpan {
        min_inside: [0; 3],
        step_x: [0; 3],
        inv_step_x: [0.0; 3],
    };

    fn new(edges: &[Edge; 3]) -> Self {
        RowSpan {
            min_inside: edges.map(|edge| edge.min_inside),
            step_x: edges.map(|edge| edge.step_x),
            inv_step_x: edges.map(|edge| {
                if edge.step_x == 0 {
                    0.0
                } else {
                    1.0 / edge.step_x as f64
                }
            }),
        }
    }

    /// The first and last of a row's `columns` pixels (counted from 0) between which every
    /// pixel inside the triangle lies, when the row's first pixel has edge values `start`; or
    /// `None` when no pixel of the row can be inside. A bound, not the exact span: `−margin/
    /// step_x` is taken in `f64` (`margin` is exact there, below 2⁵³ by [`RowLanes::fit`], and
    /// the product with the rounded `1/step_x` is off by under 2⁻⁵¹ of itself: by far less than
    /// a pixel wherever it falls within the row, and beyond the row where it falls beyond), then
    /// truncated, and each end is widened by a pixel: the span holds every inside pixel and at
    /// most two outside ones at each end. Also a span every pixel of which is inside, narrowed
    /// by two pixels at each end from the same crossings ([`RowRange::inner`]).
    #[inline(always)]
    fn of_row(&self, start: [i64; 3], columns: usize) -> Option<RowRange> {
        let (mut first, mut last) = (0i64, columns as i64 - 1);
        let (mut inner_first, mut inner_last) = (first, last);
        let edges = start
            .iter()
            .zip(&self.min_inside)
            .zip(&self.step_x)
            .zip(&self.inv_step_x);
        for (((&value, &min_inside), &step), &inv_step) in edges {
            let margin = value - min_inside;
            if step == 0 {
                if margin < 0 {
                    return None;
                }
                continue;
            }
            // Saturating: a crossing far off the row clamps to a bound that keeps or empties it.
            let crossing = (-(margin as f64) * inv_step) as i64;
            if step > 0 {
                first = first.max(crossing.saturating_sub(1));
                inner_first = inner_first.max(crossing.saturating_add(2));
            } else {
                last = last.min(crossing.saturating_add(1));
                inner_last = inner_last.min(crossing.saturating_sub(2));
            }
        }
        (first <= last).then_some(RowRange {
            first: first as usize,
            last: last as usize,
            inner: (inner_first <= inner_last).then_some((inner_first as usize, inner_last as usize)),
        })
    }
}

/// What [`RowSpan::of_row`] finds of a row: where its inside pixels can be, and where they
/// surely are.
#[derive(Debug, Clone, Copy, PartialEq)]
struct RowRange {
    /// Every pixel inside the triangle lies in `first..=last`.
    first: usize,
    last: usize,
    /// Every pixel of this span is inside the triangle, if any is surely inside. The true
    /// crossing `t = −margin/step_x` of an edge is within a quarter pixel of its `f64` value
    /// where `|t| < 2⁵⁰` (and beyond the row, on the same side, where not), and truncation
    /// moves it by less than one: so a pixel two past the truncated crossing is inside the
    /// edge.
    inner: Option<(usize, usize)>,
}

impl<E: EdgeLanes> RowLanes<E> {
    /// Whether every value the lanes form over `area` is held exactly in `E`: a centre up to a
    /// group past the last column and a row past the last row, plus a lane's offset. Where not
    /// (a triangle reaching far off the tile) a wider kind or the `i64` loop takes it. A whole
    /// number held exactly converts to `f32` as the same `i64` does, so the depths keep their
    /// bits.
    #[inline(always)]
    fn fit(edges: &[Edge; 3], area: PixelRect) -> bool {
        let (columns, rows) = Self::reach(area);
        edges.iter().all(|edge| edge.within(columns, rows, 1, E::LIMIT))
    }

    /// [`RowLanes::fit`] by the quick bound alone ([`Edge::within_either_side`]), which holds
    /// as far to the left of and above the area's first pixel as to its right and below: for
    /// [`BlockLanes`], whose blocks may be shifted there. Triangles it turns away (large edge
    /// values, which only the exact bound might admit) take `RowLanes`.
    #[inline(always)]
    fn fits_either_side(edges: &[Edge; 3], area: PixelRect) -> bool {
        let (columns, rows) = Self::reach(area);
        edges
            .iter()
            .all(|edge| edge.within_either_side(columns, rows, 1, E::LIMIT))
    }

    /// The steps from `area`'s first pixel that the lanes' values may lie at: up to two groups
    /// past its last column and a row past its last row.
    #[inline(always)]
    fn reach(area: PixelRect) -> (i64, i64) {
        (
            i64::from(area.x1 - area.x0) + 2 * LANES as i64,
            i64::from(area.y1 - area.y0) + 1,
        )
    }

    /// The lanes of a triangle whose edges [`RowLanes::fit`] the area, with corner depths
    /// `depths` and `1/A` `inv_area`. `SPANS`: whether rows are narrowed to their [`RowSpan`] (areas of more than two groups);
    /// else it is not formed.
    #[inline(always)]
    fn new<const SPANS: bool>(edges: &[Edge; 3], depths: [f32; 3], inv_area: f32) -> Self {
        RowLanes {
            row_start: edges.map(|edge| edge.row_start),
            step_y: edges.map(|edge| edge.step_y),
            group_step: edges.map(|edge| edge.step_x * LANES as i64),
            offsets: edges.map(|edge| E::from_whole(|lane| edge.step_x * lane as i64)),
            above: edges.map(|edge| E::splat_whole(edge.min_inside - 1)),
            corner_depths: depths.map(Floats::splat),
            inv_area: Floats::splat(inv_area),
            span: if SPANS { RowSpan::new(edges) } else { RowSpan::NONE },
        }
    }

    /// The depth test over `area` (within `rect`), as [`depth_test_single_sample`] states it:
    /// per group, the inside test and the depth `(e₀·d₀ + e₁·d₁ + e₂·d₂)·(1/A)` in the scalar
    /// loop's operations, lane by lane, and the nearer depths (and `id`) written with a select.
    /// Groups wholly outside the row's [`RowSpan`] are skipped when a row has three groups or
    /// more (they would test empty).
    /// A group that would run past the tile's row is tested on a copy padded with depths
    /// nothing is nearer than; one that ends past the area but within the row is tested in
    /// place, its extra lanes outside the triangle's bounds and so outside the triangle (the
    /// edge functions are exact).
    #[inline(always)]
    fn depth_test<const IDS: bool, const SPANS: bool>(
        &self,
        rect: PixelRect,
        area: PixelRect,
        rows: RowLayout,
        depth: &mut [f32],
        ids: &mut [u32],
        id: u32,
    ) {
        let columns = (area.x1 - area.x0) as usize;
        let groups = columns.div_ceil(LANES);
        // The pixels from the area's first column to the tile's last.
        let row_length = (rect.x1 - area.x0) as usize;
        let full_groups = (row_length / LANES).min(groups);
        let id_lanes = Ints::splat(id as i32);
        let mut row_start = self.row_start;
        for py in area.y0..area.y1 {
            let row = (py - rect.y0) as usize * rows.stride + (area.x0 - rows.x_origin) as usize;
            let start = row_start;
            row_start = std::array::from_fn(|k| row_start[k] + self.step_y[k]);
            // Only the groups that reach the row's span: the others are outside the triangle.
            // A row of one or two groups is tested whole: finding its span costs about as
            // much as testing a group.
            let span = if SPANS && groups > 2 {
                self.span.of_row(start, columns)
            } else {
                Some(RowRange {
                    first: 0,
                    last: columns - 1,
                    inner: None,
                })
            };
            let Some(RowRange {
                first: first_column,
                last: last_column,
                inner,
            }) = span
            else {
                continue;
            };
            // The groups wholly inside the triangle, whose inside test is skipped.
            let (first_inside, last_inside) = match inner {
                Some((first, last)) => (first.div_ceil(LANES), (last + 1) / LANES),
                None => (1, 0),
            };
            let (first_group, last_group) = (first_column / LANES, last_column / LANES);
            let mut centre: [i64; 3] =
                std::array::from_fn(|k| start[k] + first_group as i64 * self.group_step[k]);
            for group in first_group..=last_group {
                let first = row + group * LANES;
                if group < full_groups {
                    let group_depths = (&mut depth[first..first + LANES])
                        .try_into()
                        .expect("a group of lanes");
                    let group_ids = IDS.then(|| {
                        (&mut ids[first..first + LANES])
                            .try_into()
                            .expect("a group of lanes")
                    });
                    if (first_inside..last_inside).contains(&group) {
                        self.test_group::<true>(centre, group_depths, group_ids, id_lanes);
                    } else {
                        self.test_group::<false>(centre, group_depths, group_ids, id_lanes);
                    }
                } else {
                    let count = row_length - group * LANES;
                    let mut padded_depths = [f32::INFINITY; LANES];
                    let mut padded_ids = [NO_TRIANGLE; LANES];
                    padded_depths[..count].copy_from_slice(&depth[first..first + count]);
                    if IDS {
                        padded_ids[..count].copy_from_slice(&ids[first..first + count]);
                    }
                    self.test_group::<false>(
                        centre,
                        &mut padded_depths,
                        IDS.then_some(&mut padded_ids),
                        id_lanes,
                    );
                    depth[first..first + count].copy_from_slice(&padded_depths[..count]);
                    if IDS {
                        ids[first..first + count].copy_from_slice(&padded_ids[..count]);
                    }
                }
                centre = std::array::from_fn(|k| centre[k] + self.group_step[k]);
            }
        }
    }

    /// The depth test of one group of pixels whose first centre has edge values `centre`:
    /// where a lane is inside and nearer than `depths`, its depth goes there and `id` into
    /// `ids` (when given). `INSIDE`: the group is known to lie wholly inside the triangle
    /// ([`RowRange::inner`]), so its lanes are not tested against the edges.
    #[inline(always)]
    fn test_group<const INSIDE: bool>(
        &self,
        centre: [i64; 3],
        depths: &mut [f32; LANES],
        ids: Option<&mut [u32; LANES]>,
        id: Ints<E::Backend>,
    ) {
        let [e0, e1, e2]: [E; 3] = std::array::from_fn(|k| E::splat_whole(centre[k]) + self.offsets[k]);
        let inside = if INSIDE {
            Mask::<E::Backend>::ALL
        } else {
            e0.gt(self.above[0])
                .and(e1.gt(self.above[1]))
                .and(e2.gt(self.above[2]))
        };
        // Most groups of a large triangle's bounds outside it are skipped here.
        if !INSIDE && !inside.any() {
            return;
        }
        let [d0, d1, d2] = self.corner_depths;
        let depth = (e0.to_floats() * d0 + e1.to_floats() * d1 + e2.to_floats() * d2) * self.inv_area;
        let old = Floats::load_to_blend(depths);
        let nearer = inside.and(depth.gt(old));
        *depths = nearer.select(depth, old).0;
        if let Some(ids) = ids {
            *ids = bytemuck::cast(nearer.select_ints(id, Ints::load_to_blend(ids)).0);
        }
    }
}

/// A triangle at most `COLUMNS·ACROSS` pixels wide over a tile, for
/// [`depth_test_single_sample`]: its area tested in blocks of [`LANES`] pixels, `LANES /
/// COLUMNS` rows of `COLUMNS`, lane `i` at column `i % COLUMNS` and row `i / COLUMNS` of its
/// block, `ACROSS` blocks side by side, down the area. A scan's
/// and a shadow map's triangles are a few pixels wide and several tall: one row per group
/// (most of [`RowLanes`]' groups a row's only one) left half the lanes idle, and each row paid
/// for its indices and edge values in `i64` scalars. Here the edge values stay in lanes from
/// block to block (one addition per edge), and the blocks are placed so that they never leave
/// the tile: shifted left and up where the area ends near its right or bottom side. The
/// shifted lanes lie outside the triangle's bounds, so outside the triangle (the edge
/// functions are exact), and their pixels are left as they are.
struct BlockLanes<B: Backend, const COLUMNS: usize, const ACROSS: usize> {
    /// The first block's top-left pixel and the number of rows of blocks.
    x0: u32,
    y0: u32,
    blocks: u32,
    /// Per edge, each lane's value in the first block.
    edges: [Ints<B>; 3],
    /// Per edge, one block's step down: `LANES / COLUMNS` rows.
    block_step: [Ints<B>; 3],
    /// Per edge, one block's step across: `COLUMNS` pixels.
    across_step: [Ints<B>; 3],
    /// Per edge, the fill rule's bound, as in [`RowLanes`].
    above: [Ints<B>; 3],
    corner_depths: [Floats<B>; 3],
    inv_area: Floats<B>,
}

impl<B: Backend, const COLUMNS: usize, const ACROSS: usize> BlockLanes<B, COLUMNS, ACROSS> {
    /// Rows of a block.
    const ROWS: usize = LANES / COLUMNS;

    /// The blocks of a triangle whose `edges` (at the first pixel of `area`, its bounds within
    /// `rect`, at most `COLUMNS·ACROSS` wide) [`RowLanes::fits_either_side`] `i32` lanes; `None`
    /// where the blocks cannot be placed inside `rect` (a tile narrower than a row of blocks,
    /// or an area as tall as a tile of an odd height).
    ///
    /// Every lane holds its pixel's exact value: the blocks' pixels lie less than `2·LANES`
    /// columns to either side of the area's first pixel (the shift left, a row of blocks no
    /// wider than that), at most one row above it (the shift up) and within its rows below
    /// (the blocks' rows end inside the area or, when shifted, inside the tile, which ends less
    /// than a block below the area), where the bound holds on both sides. The lanes' products
    /// and sums wrap (`i32` arithmetic is exact modulo 2³², so only the results need to fit),
    /// and the sums after the last block of a row or column, one step further, are never
    /// used.
    #[inline(always)]
    fn place(
        edges: &[Edge; 3],
        area: PixelRect,
        rect: PixelRect,
        depths: [f32; 3],
        inv_area: f32,
    ) -> Option<Self> {
        let (block_columns, block_rows) = ((COLUMNS * ACROSS) as u32, Self::ROWS as u32);
        debug_assert!(area.x1 - area.x0 <= block_columns);
        let blocks = (area.y1 - area.y0).div_ceil(block_rows);
        if rect.width() < block_columns || rect.height() < blocks * block_rows {
            return None;
        }
        let x0 = area.x0.min(rect.x1 - block_columns);
        let y0 = area.y0.min(rect.y1 - blocks * block_rows);
        let (shift_x, shift_y) = (
            i64::from(x0) - i64::from(area.x0),
            i64::from(y0) - i64::from(area.y0),
        );
        let column = Ints::new(std::array::from_fn(|lane| (lane % COLUMNS) as i32));
        let row = Ints::new(std::array::from_fn(|lane| (lane / COLUMNS) as i32));
        let [a, b, c] = edges.map(|edge| {
            let first = edge.row_start + shift_x * edge.step_x + shift_y * edge.step_y;
            (first as i32, edge.step_x as i32, edge.step_y as i32)
        });
        Some(BlockLanes {
            x0,
            y0,
            blocks,
            edges: [
                block_edge_lanes(a, column, row),
                block_edge_lanes(b, column, row),
                block_edge_lanes(c, column, row),
            ],
            block_step: edges.map(|edge| Ints::splat((edge.step_y * Self::ROWS as i64) as i32)),
            across_step: edges.map(|edge| Ints::splat((edge.step_x * COLUMNS as i64) as i32)),
            above: edges.map(|edge| Ints::splat((edge.min_inside - 1) as i32)),
            corner_depths: depths.map(Floats::splat),
            inv_area: Floats::splat(inv_area),
        })
    }

    /// The depth test at every pixel of the blocks, as [`RowLanes::depth_test`] does it for a
    /// group (the same operations on the same values, lane by lane), into `depth` (and `ids`)
    /// within `rect`, laid out as `rows` says.
    #[inline(always)]
    fn depth_test<const IDS: bool>(
        &self,
        rect: PixelRect,
        rows: RowLayout,
        depth: &mut [f32],
        ids: &mut [u32],
        id: u32,
    ) {
        let id = Ints::<B>::splat(id as i32);
        let [d0, d1, d2] = self.corner_depths;
        let [above0, above1, above2] = self.above;
        let mut first = (self.y0 - rect.y0) as usize * rows.stride + (self.x0 - rows.x_origin) as usize;
        let [mut e0, mut e1, mut e2] = self.edges;
        for _ in 0..self.blocks {
            let [mut f0, mut f1, mut f2] = [e0, e1, e2];
            for block in 0..ACROSS {
                let inside = f0.gt(above0).and(f1.gt(above1)).and(f2.gt(above2));
                if inside.any() {
                    let values =
                        (f0.to_floats() * d0 + f1.to_floats() * d1 + f2.to_floats() * d2) * self.inv_area;
                    let at = first + block * COLUMNS;
                    let old = Floats::new(bytemuck::cast(load_rows_to_blend::<B, COLUMNS>(
                        bytemuck::cast_slice(depth),
                        at,
                        rows.stride,
                    )));
                    let nearer = inside.and(values.gt(old));
                    store_block::<f32, COLUMNS>(depth, at, rows.stride, nearer.select(values, old).0);
                    if IDS {
                        let old_ids = Ints::new(bytemuck::cast(load_rows_to_blend::<B, COLUMNS>(
                            ids,
                            at,
                            rows.stride,
                        )));
                        let new_ids = bytemuck::cast(nearer.select_ints(id, old_ids).0);
                        store_block::<u32, COLUMNS>(ids, at, rows.stride, new_ids);
                    }
                }
                if ACROSS > 1 {
                    f0 = f0 + self.across_step[0];
                    f1 = f1 + self.across_step[1];
                    f2 = f2 + self.across_step[2];
                }
            }
            e0 = e0 + self.block_step[0];
            e1 = e1 + self.block_step[1];
            e2 = e2 + self.block_step[2];
            first += Self::ROWS * rows.stride;
        }
    }
}

/// An edge's values in a block's lanes, from its value at the first pixel and its steps
/// along `x` and `y` (`(first, step_x, step_y)`), each lane `column` and `row` steps on.
#[inline(always)]
fn block_edge_lanes<B: Backend>(
    (first, step_x, step_y): (i32, i32, i32),
    column: Ints<B>,
    row: Ints<B>,
) -> Ints<B> {
    Ints::splat(first) + column.wrapping_mul(Ints::splat(step_x)) + row.wrapping_mul(Ints::splat(step_y))
}

/// [`load_rows_to_blend`]'s inverse: `lanes` back into the rows of `buffer`.
#[inline(always)]
fn store_block<T: Copy, const COLUMNS: usize>(
    buffer: &mut [T],
    first: usize,
    stride: usize,
    lanes: [T; LANES],
) {
    for (row, part) in lanes.chunks_exact(COLUMNS).enumerate() {
        buffer[first + row * stride..][..COLUMNS].copy_from_slice(part);
    }
}

/// Calls `visit(px, py, depth)` for every pixel of `rect` whose centre `triangle` covers.
pub fn for_each_covered_pixel(
    triangle: &RasterTriangle,
    rect: PixelRect,
    mut visit: impl FnMut(u32, u32, f32),
) {
    for_each_covered_sample(triangle, rect, SamplePattern::SINGLE, |px, py, _, depth| {
        visit(px, py, depth)
    });
}

/// Calls `visit(px, py, sample, depth)` for every sample of every pixel of `rect` that
/// `triangle` covers, row by row. This is the one coverage loop: the tile rasterizer and the
/// coverage tests both use it.
#[inline]
pub fn for_each_covered_sample(
    triangle: &RasterTriangle,
    rect: PixelRect,
    pattern: SamplePattern,
    mut visit: impl FnMut(u32, u32, usize, f32),
) {
    let Some(area) = triangle.bounds.intersect(&rect) else {
        return;
    };
    let mut edges = triangle_edges(triangle, area.x0, area.y0);
    let [d0, d1, d2] = triangle.depth;
    let inv_area = triangle.inv_area;
    // Each sample's offset turned into edge-function offsets, once per triangle.
    let mut offset_storage = [[0i64; 3]; MAX_SAMPLES];
    for (offset, &(ox, oy)) in offset_storage.iter_mut().zip(pattern.offsets()) {
        *offset = edges.map(|e| e.along_x * i64::from(ox) + e.along_y * i64::from(oy));
    }
    let sample_offsets = &offset_storage[..pattern.len()];
    let min_inside = edges.map(|e| e.min_inside);
    let inside = |e: [i64; 3]| e[0] >= min_inside[0] && e[1] >= min_inside[1] && e[2] >= min_inside[2];
    for py in area.y0..area.y1 {
        let mut centre = edges.map(|e| e.row_start);
        for px in area.x0..area.x1 {
            for (sample, offset) in sample_offsets.iter().enumerate() {
                let e = [
                    centre[0] + offset[0],
                    centre[1] + offset[1],
                    centre[2] + offset[2],
                ];
                if inside(e) {
                    let depth = (e[0] as f32 * d0 + e[1] as f32 * d1 + e[2] as f32 * d2) * inv_area;
                    visit(px, py, sample, depth);
                }
            }
            for (value, edge) in centre.iter_mut().zip(&edges) {
                *value += edge.step_x;
            }
        }
        for edge in &mut edges {
            edge.row_start += edge.step_y;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::lanes::Native;

    /// `triangle` (the tile's `local`) rasterized into `visibility` by the loops for its
    /// pattern on the native lanes, after checking that the widest lanes give the same bits.
    fn rasterize_on_both(visibility: &mut Visibility, triangle: &RasterTriangle, local: u32) {
        struct Widest<'v>(&'v mut Visibility, &'v RasterTriangle, u32);
        impl LaneWork for Widest<'_> {
            type Output = ();
            #[inline(always)]
            fn run<B: Backend>(self) {
                self.0.rasterize_triangle::<B>(self.1, self.2);
            }
        }
        let mut widest = visibility.clone();
        run_widest(Widest(&mut widest, triangle, local));
        visibility.rasterize_triangle::<Native>(triangle, local);
        assert_eq!(widest.triangle, visibility.triangle);
        let bits = |depths: &[f32]| depths.iter().map(|d| d.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&widest.depth), bits(&visibility.depth));
    }

    /// The one-sample raster triangles of `corners` in an 80×90 image (the degenerate ones
    /// dropped).
    fn set_up_in_80_by_90(corners: Vec<[ScreenVertex; 3]>) -> Vec<RasterTriangle> {
        corners
            .into_iter()
            .filter_map(|t| {
                setup_triangle(
                    t,
                    80,
                    90,
                    SamplePattern::SINGLE,
                    SourceTriangle::default(),
                    &mut Vec::new(),
                )
            })
            .collect()
    }

    /// A one-sample visibility buffer of `rect` with nothing drawn.
    fn empty_visibility(rect: PixelRect) -> Visibility {
        let pixels = (rect.width() * rect.height()) as usize;
        Visibility {
            rect,
            pattern: SamplePattern::SINGLE,
            depth: vec![f32::NEG_INFINITY; pixels],
            triangle: vec![NO_TRIANGLE; pixels],
            raster_ids: Vec::new(),
        }
    }

    fn vertex(x: f32, y: f32) -> ScreenVertex {
        ScreenVertex {
            x,
            y,
            depth: 0.5,
            inv_w: 1.0,
            weights: Vec3::ZERO,
        }
    }

    fn coverage(triangles: &[RasterTriangle], width: u32, height: u32) -> Vec<u32> {
        let rect = PixelRect {
            x0: 0,
            y0: 0,
            x1: width,
            y1: height,
        };
        let mut counts = vec![0; (width * height) as usize];
        for triangle in triangles {
            for_each_covered_pixel(triangle, rect, |x, y, _| counts[(y * width + x) as usize] += 1);
        }
        counts
    }

    #[test]
    fn two_triangles_of_a_square_cover_each_pixel_once() {
        // The diagonal passes exactly through pixel centres: the fill rule decides.
        let (a, b, c, d) = (
            vertex(0.0, 0.0),
            vertex(8.0, 0.0),
            vertex(8.0, 8.0),
            vertex(0.0, 8.0),
        );
        let triangles: Vec<_> = [[a, b, c], [a, c, d]]
            .into_iter()
            .filter_map(|t| {
                setup_triangle(
                    t,
                    8,
                    8,
                    SamplePattern::SINGLE,
                    SourceTriangle::default(),
                    &mut Vec::new(),
                )
            })
            .collect();
        assert!(coverage(&triangles, 8, 8).iter().all(|&n| n == 1));
    }

    #[test]
    fn pixel_centre_on_a_vertical_left_edge_is_inside_right_edge_is_not() {
        // The square [0.5, 2.5] × [0.5, 2.5] has pixel centres exactly on all four sides.
        let (a, b, c, d) = (
            vertex(0.5, 0.5),
            vertex(2.5, 0.5),
            vertex(2.5, 2.5),
            vertex(0.5, 2.5),
        );
        let triangles: Vec<_> = [[a, b, c], [a, c, d]]
            .into_iter()
            .filter_map(|t| {
                setup_triangle(
                    t,
                    4,
                    4,
                    SamplePattern::SINGLE,
                    SourceTriangle::default(),
                    &mut Vec::new(),
                )
            })
            .collect();
        let counts = coverage(&triangles, 4, 4);
        #[rustfmt::skip]
        let expected = [
            1, 1, 0, 0,
            1, 1, 0, 0,
            0, 0, 0, 0,
            0, 0, 0, 0,
        ];
        assert_eq!(counts, expected);
    }

    #[test]
    fn corner_weights_come_back_bit_for_bit_and_only_clipped_ones_are_stored() {
        let mut table = Vec::new();
        let swapped = [Vec3::X, Vec3::Z, Vec3::Y];
        let clipped = [Vec3::new(0.5, 0.5, 0.0), Vec3::Y, Vec3::new(0.25, 0.0, 0.75)];
        let negative_zero = [Vec3::new(1.0, -0.0, 0.0), Vec3::Y, Vec3::Z];
        let stored =
            [Vec3::AXES, swapped, clipped, negative_zero].map(|w| CornerWeights::store(w, &mut table));
        assert_eq!(table.len(), 2, "the identity and its swap take no row");
        for (weights, stored) in [Vec3::AXES, swapped, clipped, negative_zero].iter().zip(stored) {
            let bits = |w: &[Vec3; 3]| w.map(|v| v.to_array().map(f32::to_bits));
            assert_eq!(bits(&stored.resolve(&table).to_array()), bits(weights));
        }
    }

    /// Each pattern's subsets (tabled up to eight samples, computed at sixteen) against the
    /// mean of the chosen offsets in `i64`, rounded down, for every mask (every 257th at
    /// sixteen samples).
    #[test]
    fn sample_subsets_are_the_counts_and_floored_means_of_their_samples() {
        for samples in [1, 2, 4, 8, 16] {
            let pattern = SamplePattern::new(samples).expect("a sample count");
            let step = if samples == 16 { 257 } else { 1 };
            for mask in (1..1u32 << samples).step_by(step).chain([(1 << samples) - 1]) {
                let chosen: Vec<(i32, i32)> = (0..samples as usize)
                    .filter(|&sample| mask & (1 << sample) != 0)
                    .map(|sample| pattern.offsets()[sample])
                    .collect();
                let n = chosen.len() as i64;
                let mean = |coordinate: fn(&(i32, i32)) -> i32| {
                    chosen
                        .iter()
                        .map(|offset| i64::from(coordinate(offset)))
                        .sum::<i64>()
                        .div_euclid(n)
                };
                let subset = pattern.subset(mask);
                assert_eq!(subset.count as i64, n, "{samples} samples, mask {mask:#x}");
                assert_eq!(
                    i64::from(subset.mean_x),
                    mean(|o| o.0),
                    "{samples} samples, mask {mask:#x}"
                );
                assert_eq!(
                    i64::from(subset.mean_y),
                    mean(|o| o.1),
                    "{samples} samples, mask {mask:#x}"
                );
            }
        }
    }

    #[test]
    fn zero_area_triangles_are_dropped() {
        assert!(
            setup_triangle(
                [vertex(0.0, 0.0), vertex(4.0, 4.0), vertex(8.0, 8.0)],
                8,
                8,
                SamplePattern::SINGLE,
                SourceTriangle::default(),
                &mut Vec::new(),
            )
            .is_none()
        );
        assert!(
            setup_triangle(
                [vertex(1.0, 1.0); 3],
                8,
                8,
                SamplePattern::SINGLE,
                SourceTriangle::default(),
                &mut Vec::new()
            )
            .is_none()
        );
    }

    #[test]
    fn bounds_cover_only_pixel_centres_inside_the_box() {
        let t = setup_triangle(
            [vertex(0.6, 0.6), vertex(3.4, 0.6), vertex(0.6, 3.4)],
            8,
            8,
            SamplePattern::SINGLE,
            SourceTriangle::default(),
            &mut Vec::new(),
        )
        .unwrap();
        assert_eq!(
            t.bounds,
            PixelRect {
                x0: 1,
                y0: 1,
                x1: 3,
                y1: 3
            }
        );
        let edge = setup_triangle(
            [vertex(0.5, 0.5), vertex(3.5, 0.5), vertex(0.5, 3.5)],
            8,
            8,
            SamplePattern::SINGLE,
            SourceTriangle::default(),
            &mut Vec::new(),
        )
        .unwrap();
        assert_eq!(
            edge.bounds,
            PixelRect {
                x0: 0,
                y0: 0,
                x1: 4,
                y1: 4
            }
        );
    }

    /// The planes give `edge_values`' integers, for triangles from pixel size to the guard
    /// band's, at points near and far.
    #[test]
    fn edge_planes_equal_edge_values() {
        let reach = (GUARD_BAND_PIXELS as i64) * SUBPIXEL_ONE;
        let triangles = [
            [(1.3, 0.7), (10.6, 2.2), (4.1, 11.4)],
            [(-1.0e6, -9.0e5), (1.0e6, 3.5), (7.5, 1.0e6)],
            [(1919.9, 0.1), (0.2, 1079.8), (1919.9, 1079.9)],
        ];
        for corners in triangles {
            let t = setup_triangle(
                corners.map(|(x, y)| vertex(x, y)),
                1920,
                1080,
                SamplePattern::SINGLE,
                SourceTriangle::default(),
                &mut Vec::new(),
            )
            .expect("a triangle");
            let planes = EdgePlanes::new(&t);
            for (x, y) in [
                (0, 0),
                (3 * 256 + 131, 5 * 256 + 77),
                (-reach, reach),
                (reach, -reach),
                (reach, reach),
            ] {
                assert_eq!(
                    planes.at(x, y),
                    edge_values(&t, x, y),
                    "{corners:?} at ({x}, {y})"
                );
            }
        }
    }

    #[test]
    fn edge_values_sum_to_the_area() {
        let t = setup_triangle(
            [vertex(0.3, 0.2), vertex(7.1, 1.9), vertex(2.2, 6.6)],
            8,
            8,
            SamplePattern::SINGLE,
            SourceTriangle::default(),
            &mut Vec::new(),
        )
        .unwrap();
        let [e0, e1, e2] = edge_values(&t, 3 * 256 + 128, 3 * 256 + 128);
        assert!(((e0 + e1 + e2) as f32 * t.inv_area - 1.0).abs() < 1e-6);
    }

    /// `Edge::within`, which picks the lanes that hold a triangle's values, against every value
    /// of its box, for edges from a pixel to a few thousand pixels long: it must never pass a
    /// box whose values outgrow the limit (the lanes would wrap), and it passes every box that
    /// fits, the large triangles the loose bound alone turned away among them.
    #[test]
    fn edge_bounds_are_the_largest_value_of_their_box() {
        let mut rng = crate::test_support::XorShift64::new(0x9e37_79b9_7f4a_7c15);
        let limit = i64::from(i32::MAX);
        let (mut fitting, mut only_exact) = (0, 0);
        for _ in 0..4000 {
            let reach = [8, 300, 3000][(rng.next_u64() % 3) as usize] * SUBPIXEL_ONE;
            let mut coordinate = || (rng.next_u64() % (2 * reach as u64)) as i32 - reach as i32;
            let (ax, ay, bx, by) = (coordinate(), coordinate(), coordinate(), coordinate());
            let (px, py) = ((rng.next_u64() % 40) as u32, (rng.next_u64() % 40) as u32);
            let edge = Edge::new(ax, ay, bx, by, px, py);
            let (columns, rows) = (1 + (rng.next_u64() % 80) as i64, 1 + (rng.next_u64() % 65) as i64);
            let margin = (rng.next_u64() % 64) as i64;
            let largest = (0..=columns)
                .flat_map(|x| (0..=rows).map(move |y| (x, y)))
                .map(|(x, y)| (edge.row_start + x * edge.step_x + y * edge.step_y).abs())
                .max()
                .unwrap();
            let fits = largest + margin <= limit;
            assert_eq!(
                edge.within(columns, rows, margin, limit),
                fits,
                "{edge:?} over {columns}×{rows}"
            );
            fitting += usize::from(fits);
            let loose = edge.row_start.abs() + columns * edge.step_x.abs() + rows * edge.step_y.abs();
            only_exact += usize::from(fits && loose + margin > limit);
        }
        assert!(
            fitting > 1000 && only_exact > 50,
            "{fitting} fit, {only_exact} by the exact bound only"
        );
    }

    /// The depth-only rasterizer (shadow maps) against the visibility buffer's depths, bit for
    /// bit, on every tile of a frame (back faces culled, near-plane clipped), written over
    /// depths it must keep where they are nearer.
    #[test]
    fn depth_only_rasterizer_equals_the_visibility_buffers_depths() {
        use crate::render::geometry::build_frame;
        use crate::render::shade_fast;
        use crate::scene::{BackFaces, LightingModel};
        let mut scene = shade_fast::tests::scene(
            LightingModel::Phong,
            Vec3::splat(0.5),
            BackFaces::ReverseLit,
            shade_fast::tests::LIGHTS[0],
        );
        scene.camera.projection = crate::scene::Projection::Perspective {
            fov_y_degrees: 40.0,
            near: 4.9,
            far: 100.0,
        };
        let frame = build_frame(&scene, SamplePattern::SINGLE, None, vec![None; 2]);
        let grid = frame.tiles;
        let stride = grid.width as usize;
        // Depths already there: a nearer one on every seventh texel.
        let before = |x: usize, y: usize| {
            if (x + 3 * y).is_multiple_of(7) {
                0.9
            } else {
                f32::NEG_INFINITY
            }
        };
        let mut depth: Vec<f32> = (0..stride * grid.height as usize)
            .map(|i| before(i % stride, i / stride))
            .collect();
        for (tile_row, band) in depth.chunks_mut(TILE_SIZE as usize * stride).enumerate() {
            for column in 0..grid.columns as usize {
                let tile = tile_row * grid.columns as usize + column;
                for chunk in &frame.raster {
                    for &index in chunk.tile_triangles(tile) {
                        let triangle = &chunk.triangles[index as usize];
                        rasterize_depth_only::<Native>(triangle, grid.rect(tile), band, stride);
                    }
                }
            }
        }
        let (mut covered, mut kept) = (0, 0);
        for tile in 0..grid.count() {
            let rect = grid.rect(tile);
            let visibility = rasterize_tile(rect, SamplePattern::SINGLE, &frame.raster, tile);
            for y in rect.y0..rect.y1 {
                for x in rect.x0..rect.x1 {
                    let drawn = visibility.depth[((y - rect.y0) * rect.width() + x - rect.x0) as usize];
                    let old = before(x as usize, y as usize);
                    let expected = if drawn > old { drawn } else { old };
                    let found = depth[y as usize * stride + x as usize];
                    assert_eq!(found.to_bits(), expected.to_bits(), "pixel ({x}, {y})");
                    covered += usize::from(drawn > f32::NEG_INFINITY);
                    kept += usize::from(drawn > f32::NEG_INFINITY && old > drawn);
                }
            }
        }
        assert!(
            covered > 1500 && kept > 100,
            "{covered} pixels covered, {kept} kept"
        );
    }

    /// The one-sample depth test takes its `i32` lanes where a triangle is half a group of lanes
    /// wide and its edge values over the tile fit, `f64` lanes where they are exact there (a large
    /// triangle), and its `i64` loop elsewhere (narrow triangles, one reaching far off screen);
    /// all give the general loop's depths and triangles, bit for bit. The tile is 21 pixels wide, so groups run past its row and are tested on a copy;
    /// triangles overlap at staggered depths, so later ones are nearer in some pixels only;
    /// squares cut along a diagonal put pixel centres exactly on edges.
    #[test]
    fn single_sample_lanes_and_the_wide_loop_equal_the_general_loop() {
        let rect = PixelRect {
            x0: 40,
            y0: 64,
            x1: 61,
            y1: 77,
        };
        let at = |x: f32, y: f32, depth: f32| ScreenVertex {
            depth,
            ..vertex(x, y)
        };
        let mut corners = vec![
            [at(41.3, 64.7, 0.21), at(60.6, 66.2, 0.53), at(44.1, 76.4, 0.97)],
            [
                at(-500_000.0, -400_000.0, 0.21),
                at(600_000.0, 69.5, 0.53),
                at(46.5, 700_000.0, 0.97),
            ],
            [at(43.0, 65.0, 0.6), at(45.5, 75.0, 0.7), at(47.2, 66.0, 0.65)],
            // Large: its edge functions outgrow `i32` but not `f64`.
            [
                at(-300.0, -200.0, 0.3),
                at(55.0, 70.3, 0.6),
                at(-100.0, 600.0, 0.4),
            ],
            // Narrow in the rect but reaching far above and below it: rows of one or two
            // groups in `f64` lanes.
            [
                at(44.0, -5000.0, 0.3),
                at(52.5, 5000.0, 0.5),
                at(47.0, -5000.0, 0.4),
            ],
            // Slivers across the rect, whose rows' spans leave groups out on both sides.
            [at(30.0, 60.0, 0.4), at(72.0, 80.0, 0.5), at(31.5, 60.0, 0.45)],
            [at(70.0, 58.0, 0.4), at(35.0, 82.0, 0.5), at(72.5, 58.5, 0.45)],
        ];
        for k in 0..16u32 {
            let (x0, y0) = (38.0 + k as f32 * 1.5, 63.0 + (k % 5) as f32);
            let size = 2.0 + (k % 6) as f32 * 3.0;
            let corner = |x: f32, y: f32| at(x, y, 0.25 + 0.04 * k as f32 - 0.02 * (x - x0));
            let (a, b, c, d) = (
                corner(x0, y0),
                corner(x0 + size, y0),
                corner(x0 + size, y0 + size),
                corner(x0, y0 + size),
            );
            corners.extend([[a, b, c], [a, c, d], [c, b, a]]);
        }
        let triangles = set_up_in_80_by_90(corners);
        let (mut lanes, mut wide_lanes, mut wide, mut narrow) = (0, 0, 0, 0);
        for triangle in &triangles {
            let Some(area) = triangle.bounds.intersect(&rect) else {
                continue;
            };
            let edges = triangle_edges(triangle, area.x0, area.y0);
            let fits = (
                RowLanes::<Ints>::fit(&edges, area),
                RowLanes::<Wides>::fit(&edges, area),
            );
            match (area.width() as usize >= LANE_COLUMNS, fits) {
                (true, (true, _)) => lanes += 1,
                (true, (false, true)) => wide_lanes += 1,
                (true, (false, false)) => wide += 1,
                _ => narrow += 1,
            }
        }
        assert!(
            lanes > 20 && wide_lanes == 2 && wide == 1 && narrow > 5,
            "{lanes} in lanes, {wide_lanes} in wide lanes, {wide} wide, {narrow} narrow"
        );
        let (mut fast, mut general) = (empty_visibility(rect), empty_visibility(rect));
        for (local, triangle) in (0..).zip(&triangles) {
            rasterize_on_both(&mut fast, triangle, local);
            general.rasterize_any_samples(triangle, local);
        }
        let shown = |visibility: &Visibility| {
            let mut ids = visibility.triangle.clone();
            ids.sort_unstable();
            ids.dedup();
            ids.len()
        };
        assert!(shown(&general) > 12, "{} triangles shown", shown(&general));
        assert_eq!(fast.triangle, general.triangle);
        let bits = |depths: &[f32]| depths.iter().map(|d| d.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&fast.depth), bits(&general.depth));
    }

    /// Narrow areas take [`BlockLanes`]: blocks of two rows of four pixels (areas up to four
    /// wide and two or more tall), of one row of eight, or two of those across, shifted left where the area ends near
    /// the tile's right side and up near its bottom, and the other paths where no block fits
    /// (an area as tall as a tile of odd height). All give the general loop's depths and
    /// triangles bit for bit, on both backends, and the depth-only pass, into a map's band,
    /// the same depths. The tile is 21 by 13 pixels, so shifts and the odd height both occur.
    #[test]
    fn block_lanes_equal_the_general_loop() {
        let rect = PixelRect {
            x0: 40,
            y0: 64,
            x1: 61,
            y1: 77,
        };
        let mut rng = crate::test_support::XorShift32::new(0x9e37_79b9);
        let mut random =
            move |low: f32, high: f32| low + (high - low) * (rng.next_u32() as f32 / u32::MAX as f32);
        let mut corners = Vec::new();
        for k in 0..600 {
            let (width, height) = match k % 10 {
                // As tall as the tile and more.
                0 => (random(0.5, 4.5), random(13.0, 20.0)),
                // Two blocks of eight wide.
                1 | 2 => (random(8.5, 17.5), random(0.3, 15.0)),
                _ => (random(0.3, 9.5), random(0.3, 15.0)),
            };
            let (x, y) = (random(36.0, 62.0), random(58.0, 79.0));
            let (along, down) = (random(0.0, height), random(0.0, width));
            let depths = [random(0.05, 0.95), random(0.05, 0.95), random(0.05, 0.95)];
            let corner = |x: f32, y: f32, depth: f32| ScreenVertex {
                depth,
                ..vertex(x, y)
            };
            let (a, b, c) = (
                corner(x, y, depths[0]),
                corner(x + width, y + along, depths[1]),
                corner(x + down, y + height, depths[2]),
            );
            // Both windings: `setup_triangle` keeps one and turns the other.
            corners.push(if k % 2 == 0 { [a, b, c] } else { [a, c, b] });
        }
        // Slivers reaching far above and below the tile, a few pixels wide in it: edge values
        // near `i32`'s limit, some of them at the tile's right side, where blocks shift left.
        for k in 0..300 {
            let x = random(40.0, 62.0);
            let (reach, width) = (random(2e5, 9e5), random(0.5, 15.0));
            let lean = random(-3.0, 3.0);
            let depths = [random(0.05, 0.95), random(0.05, 0.95), random(0.05, 0.95)];
            let corner = |x: f32, y: f32, depth: f32| ScreenVertex {
                depth,
                ..vertex(x, y)
            };
            let (a, b, c) = (
                corner(x - lean, 70.0 - reach, depths[0]),
                corner(x + lean, 70.0 + reach, depths[1]),
                corner(x + width, 70.0 + random(-5.0, 5.0), depths[2]),
            );
            corners.push(if k % 2 == 0 { [a, b, c] } else { [a, c, b] });
        }
        let triangles = set_up_in_80_by_90(corners);
        // Which path each triangle takes: [blocks of 4, of 8, two blocks of 8 across, shifted
        // left, shifted up, no block fits].
        let mut paths = [0; 6];
        for triangle in &triangles {
            let Some(area) = triangle.bounds.intersect(&rect) else {
                continue;
            };
            let edges = triangle_edges(triangle, area.x0, area.y0);
            let (columns, rows) = (area.width() as usize, area.height() as usize);
            let narrow = NarrowArea::of(columns, rows);
            if narrow == NarrowArea::No || !RowLanes::<Ints>::fit(&edges, area) {
                continue;
            }
            let (depths, path) = (triangle.depth, narrow as usize);
            let placed = match narrow {
                NarrowArea::Blocks4 => BlockLanes::<Native, 4, 1>::place(&edges, area, rect, depths, 1.0)
                    .map(|blocks| (blocks.x0, blocks.y0)),
                NarrowArea::Blocks8 => BlockLanes::<Native, 8, 1>::place(&edges, area, rect, depths, 1.0)
                    .map(|blocks| (blocks.x0, blocks.y0)),
                _ => BlockLanes::<Native, 8, 2>::place(&edges, area, rect, depths, 1.0)
                    .map(|blocks| (blocks.x0, blocks.y0)),
            };
            match placed {
                Some((x0, y0)) => {
                    paths[path] += 1;
                    paths[3] += usize::from(x0 < area.x0);
                    paths[4] += usize::from(y0 < area.y0);
                }
                None => paths[5] += 1,
            }
        }
        assert!(paths.iter().all(|&n| n > 3), "paths taken: {paths:?}");
        let (mut fast, mut general) = (empty_visibility(rect), empty_visibility(rect));
        let bits = |depths: &[f32]| depths.iter().map(|d| d.to_bits()).collect::<Vec<_>>();
        // A map's band: rows 64 texels apart from column 0, with a depth already in every
        // fifth texel.
        let stride = 64;
        let before = |i: usize| {
            if i.is_multiple_of(5) {
                0.5
            } else {
                f32::NEG_INFINITY
            }
        };
        let mut band: Vec<f32> = (0..stride * 13).map(before).collect();
        let mut widest_band = band.clone();
        struct DepthOnly<'b>(&'b RasterTriangle, PixelRect, &'b mut [f32], usize);
        impl LaneWork for DepthOnly<'_> {
            type Output = ();
            #[inline(always)]
            fn run<B: Backend>(self) {
                rasterize_depth_only::<B>(self.0, self.1, self.2, self.3);
            }
        }
        for (local, triangle) in (0..).zip(&triangles) {
            rasterize_on_both(&mut fast, triangle, local);
            general.rasterize_any_samples(triangle, local);
            rasterize_depth_only::<Native>(triangle, rect, &mut band, stride);
            run_widest(DepthOnly(triangle, rect, &mut widest_band, stride));
        }
        assert_eq!(bits(&band), bits(&widest_band));
        assert_eq!(fast.triangle, general.triangle);
        assert_eq!(bits(&fast.depth), bits(&general.depth));
        for (i, &texel) in band.iter().enumerate() {
            let (x, y) = ((i % stride) as u32, (i / stride) as u32);
            let expected = if (rect.x0..rect.x1).contains(&x) {
                let drawn = general.depth[(y * rect.width() + x - rect.x0) as usize];
                if drawn > before(i) { drawn } else { before(i) }
            } else {
                before(i)
            };
            assert_eq!(texel.to_bits(), expected.to_bits(), "texel ({x}, {y})");
        }
    }

    /// A row's span holds every pixel inside all three edges, and at most two more at each end
    /// (none where the row has no inside pixel), for edges of every slope and fill rule
    /// crossing the row anywhere, at the ends, or not at all.
    #[test]
    fn row_spans_hold_every_inside_pixel_and_little_more() {
        let columns = 64;
        let mut rng = crate::test_support::XorShift64::new(0x2545_f491_4f6c_dd1du64);
        let mut next = move |range: i64| {
            let state = rng.next_u64();
            (state % (2 * range as u64 + 1)) as i64 - range
        };
        let (mut empty, mut partial, mut inner_rows) = (0, 0, 0);
        for case in 0..20_000 {
            // Steps from one subpixel to a long edge's; values from the row's middle to far off.
            let scale = [1, 256, 65_536, 1 << 24][case % 4];
            let edges: [Edge; 3] = std::array::from_fn(|k| {
                let step_x = if (case + k) % 7 == 0 { 0 } else { next(scale) };
                Edge {
                    row_start: next(40 * scale.max(256)) + if case % 5 == 0 { next(1 << 50) } else { 0 },
                    along_x: 0,
                    along_y: 0,
                    step_x,
                    step_y: 0,
                    min_inside: (case + k) as i64 % 2,
                }
            });
            let inside: Vec<usize> = (0..columns)
                .filter(|&i| {
                    edges
                        .iter()
                        .all(|edge| edge.row_start + edge.step_x * i as i64 >= edge.min_inside)
                })
                .collect();
            let range = RowSpan::new(&edges).of_row(edges.map(|edge| edge.row_start), columns);
            // Every pixel of the inner span is inside, and it misses at most two at each end.
            if let Some(RowRange {
                inner: Some((inner_first, inner_last)),
                ..
            }) = range
            {
                assert!(
                    (inner_first..=inner_last).all(|i| inside.contains(&i)),
                    "{edges:?}"
                );
                assert!(
                    inside.first().is_some_and(|&lo| inner_first <= lo + 3),
                    "{edges:?}"
                );
                assert!(inside.last().is_some_and(|&hi| hi <= inner_last + 3), "{edges:?}");
                inner_rows += 1;
            } else if let (Some(&lo), Some(&hi)) = (inside.first(), inside.last()) {
                // No inner span: the inside one is short (each end is narrowed by at most
                // three pixels).
                assert!(hi < lo + 13, "{edges:?}: inside {lo}..={hi}, no inner span");
            }
            let span = range.map(|range| (range.first, range.last));
            match (inside.first(), inside.last(), span) {
                (None, None, None) => empty += 1,
                (None, None, Some((first, last))) => assert!(last < first + 4, "{edges:?}: {first}..={last}"),
                (Some(&lo), Some(&hi), Some((first, last))) => {
                    assert!(
                        first <= lo && lo <= first + 2 && hi <= last && last <= hi + 2,
                        "{edges:?}"
                    );
                    partial += usize::from(lo > 0 || hi < columns - 1);
                }
                _ => panic!("{edges:?}: inside {inside:?}, span {span:?}"),
            }
        }
        assert!(inner_rows > 1_000, "{inner_rows} rows with an inner span");
        assert!(
            empty > 1_000 && partial > 1_000,
            "{empty} empty rows, {partial} partial"
        );
    }

    /// The multisample depth test takes its `i32` lanes where a triangle's edge values over the
    /// tile fit (a small triangle, by its span; a larger one, by the bound per edge), its `f64`
    /// lanes where they stay below 2⁵³ (a triangle thousands of pixels across), and its `i64`
    /// loop where neither holds them (one reaching far off screen, or an area of odd width that
    /// cannot be widened to whole blocks); all give the general loop's depths and triangles,
    /// bit for bit, and the lanes leave the pixel they add to an odd row as it was.
    #[test]
    fn multisample_lanes_and_the_wide_loop_equal_the_general_loop() {
        let tile = |x1: u32| PixelRect {
            x0: 0,
            y0: 0,
            x1,
            y1: 12,
        };
        // Corner depths that differ, so that the interpolated depths differ in their last bits.
        let at = |x: f32, y: f32, depth: f32| ScreenVertex {
            depth,
            ..vertex(x, y)
        };
        let small = [at(1.3, 0.7, 0.21), at(10.6, 2.2, 0.53), at(4.1, 11.4, 0.97)];
        // At four samples, bounds of nine columns (2..11), of eleven ending at the tile's
        // right edge (1..12), and of the whole of an 11-wide tile (0..11).
        let odd_right = [at(2.3, 0.7, 0.21), at(10.4, 3.2, 0.53), at(4.1, 11.4, 0.97)];
        let odd_left = [at(1.3, 0.7, 0.21), at(11.9, 2.2, 0.53), at(4.1, 11.4, 0.97)];
        let odd_tile = [at(0.2, 0.7, 0.21), at(11.9, 2.2, 0.53), at(4.1, 11.4, 0.97)];
        let large = [at(1.3, 0.7, 0.21), at(150.6, 2.2, 0.53), at(4.1, 130.4, 0.97)];
        // Corners spanning almost `LANE_SPAN`, the most a small triangle's `f32` lane offsets
        // are formed for (the largest edge deltas, times the samples' largest offsets).
        let widest_small = [at(0.3, 0.2, 0.21), at(127.7, 5.1, 0.53), at(3.2, 127.6, 0.97)];
        // Edge values of about 10¹², beyond `i32`, well within `f64`'s whole numbers.
        let big = [
            at(-3_000.0, -2_000.0, 0.21),
            at(4_000.0, 5.5, 0.53),
            at(6.5, 5_000.0, 0.97),
        ];
        // Edge values of about 10¹⁷, beyond `f64`'s whole numbers.
        let huge = [
            at(-500_000.0, -400_000.0, 0.21),
            at(600_000.0, 5.5, 0.53),
            at(6.5, 700_000.0, 0.97),
        ];
        // (corners, tile width, small, `i32` lanes at four samples, at eight and sixteen,
        // `f64` lanes where the area is whole blocks)
        let cases = [
            (small, 12, true, true, true, true),
            (odd_right, 12, true, true, true, true),
            (odd_left, 12, true, true, true, true),
            (odd_tile, 11, true, false, true, true),
            (widest_small, 12, true, true, true, true),
            (large, 12, false, true, true, true),
            (big, 12, false, false, false, true),
            (huge, 12, false, false, false, false),
        ];
        for samples in [4, 8, 16] {
            let pattern = SamplePattern::new(samples).expect("a sample count");
            for (case, &(corners, width, small, lanes_at_4, lanes_wider, wide_lanes)) in
                cases.iter().enumerate()
            {
                let rect = tile(width);
                let slots = (width * 12 * samples) as usize;
                let triangle = setup_triangle(
                    corners,
                    width,
                    12,
                    pattern,
                    SourceTriangle::default(),
                    &mut Vec::new(),
                )
                .expect("a triangle");
                let area = triangle.bounds.intersect(&rect).expect("in the tile");
                let lane_area = match samples {
                    4 => whole_blocks::<4>(area, rect),
                    8 => whole_blocks::<8>(area, rect),
                    _ => whole_blocks::<16>(area, rect),
                };
                fn lanes<E: EdgeLanes>(
                    triangle: &RasterTriangle,
                    pattern: SamplePattern,
                    area: PixelRect,
                ) -> bool {
                    match pattern.len() {
                        4 => LaneEdges::<E>::new::<4>(triangle, &pattern, area).is_some(),
                        8 => LaneEdges::<E>::new::<8>(triangle, &pattern, area).is_some(),
                        _ => LaneEdges::<E>::new::<16>(triangle, &pattern, area).is_some(),
                    }
                }
                let (narrow, wide) = lane_area.map_or((false, false), |lane_area| {
                    (
                        lanes::<Ints>(&triangle, pattern, lane_area),
                        lanes::<Wides>(&triangle, pattern, lane_area),
                    )
                });
                let expected = if samples == 4 { lanes_at_4 } else { lanes_wider };
                assert_eq!(narrow, expected, "{samples} samples, case {case}: i32 lanes");
                assert_eq!(
                    wide,
                    wide_lanes && lane_area.is_some(),
                    "{samples} samples, case {case}: f64 lanes"
                );
                if let Some(lane_area) = lane_area {
                    assert_eq!(
                        LaneEdges::<Ints>::small(&triangle, lane_area),
                        small,
                        "case {case}"
                    );
                }
                let empty = || Visibility {
                    rect,
                    pattern,
                    depth: vec![f32::NEG_INFINITY; slots],
                    triangle: vec![NO_TRIANGLE; slots],
                    raster_ids: Vec::new(),
                };
                let (mut fast, mut general) = (empty(), empty());
                // A farther triangle drawn before over the whole tile, so that the pixel a
                // block adds holds values the lanes must keep.
                let before = setup_triangle(
                    [at(0.0, 0.0, 0.15), at(24.0, 0.0, 0.05), at(0.0, 24.0, 0.15)],
                    width,
                    12,
                    pattern,
                    SourceTriangle::default(),
                    &mut Vec::new(),
                )
                .expect("a triangle");
                fast.rasterize_any_samples(&before, 1);
                general.rasterize_any_samples(&before, 1);
                rasterize_on_both(&mut fast, &triangle, 0);
                general.rasterize_any_samples(&triangle, 0);
                let covered = fast.triangle.iter().filter(|&&id| id == 0).count();
                assert!(
                    covered > slots / 8,
                    "{samples} samples, case {case}: {covered} covered"
                );
                assert_eq!(fast.triangle, general.triangle, "{samples} samples, case {case}");
                let bits = |depths: &[f32]| depths.iter().map(|d| d.to_bits()).collect::<Vec<_>>();
                assert_eq!(
                    bits(&fast.depth),
                    bits(&general.depth),
                    "{samples} samples, case {case}"
                );
            }
        }
    }

    /// The multisample depth test specialised per sample count against the general coverage
    /// loop, on every tile of two open spheres (near-plane clipped, so with slivers and back
    /// faces) at 2, 4, 8 and 16 samples: the same depths, bit for bit, and the same triangles.
    #[test]
    fn multisample_rasterizer_equals_the_general_loop() {
        use crate::render::{geometry::build_frame, shade_fast};
        use crate::scene::{BackFaces, LightingModel};
        let mut scene = shade_fast::tests::scene(
            LightingModel::BlinnPhong,
            Vec3::splat(0.5),
            BackFaces::Lit,
            shade_fast::tests::LIGHTS[0],
        );
        scene.image.width = 150;
        scene.image.height = 90;
        scene.camera.projection = crate::scene::Projection::Perspective {
            fov_y_degrees: 40.0,
            near: 4.9,
            far: 100.0,
        };
        let bits = |depths: &[f32]| depths.iter().map(|d| d.to_bits()).collect::<Vec<_>>();
        for samples in [2, 4, 8, 16] {
            let pattern = SamplePattern::new(samples).expect("a sample count");
            let frame = build_frame(&scene, pattern, None, vec![None; 3]);
            let (mut covered, mut partial) = (0, 0);
            for tile in 0..frame.tiles.count() {
                let rect = frame.tiles.rect(tile);
                let fast = rasterize_tile(rect, pattern, &frame.raster, tile);
                let mut general = Visibility::new();
                general.rect = rect;
                general.pattern = pattern;
                general.depth = vec![f32::NEG_INFINITY; fast.depth.len()];
                general.triangle = vec![NO_TRIANGLE; fast.triangle.len()];
                for (chunk_index, chunk) in frame.raster.iter().enumerate() {
                    for &index in chunk.tile_triangles(tile) {
                        let local = general.raster_ids.len() as u32;
                        general.raster_ids.push(raster_id(chunk_index, index as usize));
                        general.rasterize_any_samples(&chunk.triangles[index as usize], local);
                    }
                }
                assert_eq!(fast.raster_ids, general.raster_ids);
                assert_eq!(fast.triangle, general.triangle, "{samples} samples, tile {tile}");
                let bits = |depths: &[f32]| depths.iter().map(|d| d.to_bits()).collect::<Vec<_>>();
                assert_eq!(
                    bits(&fast.depth),
                    bits(&general.depth),
                    "{samples} samples, tile {tile}"
                );
                for ids in fast.triangle.chunks_exact(samples as usize) {
                    covered += ids.iter().filter(|&&id| id != NO_TRIANGLE).count();
                    partial += usize::from(ids.iter().any(|&id| id != ids[0]));
                }
            }
            assert!(
                covered > 2000 * samples as usize && partial > 200,
                "{samples} samples: {covered} samples covered, {partial} pixels with several"
            );

            // Samples exactly on edges, where only the fill rule decides: squares with corners
            // on the 1/16-pixel grid of the patterns, each cut along a diagonal, at staggered
            // depths so that they overlap.
            let triangles: Vec<_> = (0..12u32)
                .flat_map(|k| {
                    let (x0, y0) = (1.0 + k as f32 * 7.0 / 16.0, 0.5 + k as f32 * 5.0 / 16.0);
                    let size = 3.0 + (k % 4) as f32 * 0.375;
                    let corner = |x: f32, y: f32| ScreenVertex {
                        depth: 0.25 + 0.03 * k as f32,
                        ..vertex(x, y)
                    };
                    let (a, b, c, d) = (
                        corner(x0, y0),
                        corner(x0 + size, y0),
                        corner(x0 + size, y0 + size),
                        corner(x0, y0 + size),
                    );
                    [[a, b, c], [a, c, d]]
                })
                .filter_map(|t| {
                    setup_triangle(t, 12, 12, pattern, SourceTriangle::default(), &mut Vec::new())
                })
                .collect();
            let rect = PixelRect {
                x0: 0,
                y0: 0,
                x1: 12,
                y1: 12,
            };
            let empty = || {
                let mut visibility = Visibility::new();
                visibility.rect = rect;
                visibility.pattern = pattern;
                visibility.depth = vec![f32::NEG_INFINITY; 144 * samples as usize];
                visibility.triangle = vec![NO_TRIANGLE; 144 * samples as usize];
                visibility
            };
            let (mut fast, mut general) = (empty(), empty());
            for (local, triangle) in (0..).zip(&triangles) {
                rasterize_on_both(&mut fast, triangle, local);
                general.rasterize_any_samples(triangle, local);
            }
            assert_eq!(triangles.len(), 24);
            assert_eq!(fast.triangle, general.triangle, "{samples} samples on edges");
            assert_eq!(
                bits(&fast.depth),
                bits(&general.depth),
                "{samples} samples on edges"
            );
        }
    }
}
