//! The shading stage: one colour for every visible pixel of a tile.
//!
//! The rasterizer left, per pixel, the nearest raster triangle. Here its edge functions give the
//! screen-space barycentrics λ, which are made perspective-correct (`bᵢ = (λᵢ/wᵢ) / Σ λⱼ/wⱼ`;
//! seed 002 names plain screen-space interpolation as a flaw), then mapped through the clipper's
//! weights to the source triangle's three vertices. Then, by the object's shading mode:
//! - `Flat`: the triangle's colour, lit once at its centroid with its face normal, when a pixel
//!   first shows it (hidden triangles are never lit);
//! - `Gouraud`: the vertex colours, interpolated with the same perspective correction in one
//!   division per pixel (`GouraudColors`);
//! - `Phong`: position and normal interpolated, the normal renormalised, lit here.
//!
//! Back faces are lit from behind with the normal flipped. Gouraud back colours are lit lazily
//! here, for the few back faces that are actually visible, instead of for every vertex. Colours
//! lit per triangle are kept in a small per-tile cache, so each is lit about once per tile.

use glam::{Vec2, Vec3, Vec3A, Vec4};

use crate::render::DebugView;
use crate::render::TILE_SIZE;
use crate::render::frame::{Frame, FrameTriangle, ObjectStyle, VertexAttributes, has_color_texture, tinted};
use crate::render::framebuffer::TileTarget;
use crate::render::lanes::{
    Backend, Floats, Ints, LANES, LaneWork, Mask, Native, Vec3s, Wides, fill_vec3s, mark_shown, prefetch,
    run_widest, samples_showing,
};
use crate::render::normals::{perturb_normal, renormalize_or_else, slerp_triangle};
use crate::render::raster::{
    Corners, EdgePlanes, NO_TRIANGLE, PixelRect, RasterTriangle, SUBPIXEL_ONE, SampleSubset, Visibility,
    edge_steps_x, edge_steps_y, edge_values,
};
use crate::render::shade_fast::{FastLighting, FastPhong, LightingMemo, PhongBatch, PhongRows, SurfaceBatch};
use crate::render::surface_lanes::{
    EdgeQueue, QueuedPixels, RasterPlane, SurfaceLanes, SurfacePoints, WeightLanes, texture_colors,
};
use crate::scene::{Material, NormalInterpolation, Shading, TextureBinding};

/// Colours lit per triangle while shading a tile, so that each is lit once however many pixels
/// show it: a small direct-mapped table keyed by the triangle's id. The neighbours of a pixel
/// nearly always show the same few triangles, so a small table catches almost every repeat.
struct TriangleColorCache<T: Copy> {
    keys: [u32; TRIANGLE_CACHE_SIZE],
    values: [T; TRIANGLE_CACHE_SIZE],
}

const TRIANGLE_CACHE_SIZE: usize = 64;

/// How many of a tile's triangles ahead of the one being shaded the vertices are prefetched of.
const VERTEX_PREFETCH: usize = 12;

/// Asks for the vertices (and their colours) of the tile's triangle `local`, if there is one,
/// before its shader reads them: a dense mesh's triangles in a tile use vertices scattered over
/// arrays far larger than the cache.
#[inline(always)]
fn prefetch_vertices(frame: &Frame, visibility: &Visibility, local: usize) {
    if local < visibility.raster_ids.len() {
        let ahead = frame.raster_triangle(visibility.raster_id(local as u32));
        for v in ahead.triangle.vertices {
            prefetch(&frame.vertices, v as usize);
            prefetch(&frame.vertex_colors, v as usize);
        }
    }
}

/// [`samples_showing`]'s mask of a group of [`LANES`] pixels that all show one triangle.
const ALL_LANES: u32 = (1 << LANES) - 1;

impl<T: Copy + Default> TriangleColorCache<T> {
    fn new() -> Self {
        TriangleColorCache {
            keys: [NO_TRIANGLE; TRIANGLE_CACHE_SIZE],
            values: [T::default(); TRIANGLE_CACHE_SIZE],
        }
    }

    #[inline]
    fn get(&self, key: u32) -> Option<T> {
        let slot = key as usize % TRIANGLE_CACHE_SIZE;
        (self.keys[slot] == key).then_some(self.values[slot])
    }

    #[inline]
    fn insert(&mut self, key: u32, value: T) {
        let slot = key as usize % TRIANGLE_CACHE_SIZE;
        self.keys[slot] = key;
        self.values[slot] = value;
    }

    #[inline]
    fn get_or_insert_with(&mut self, key: u32, make: impl FnOnce() -> T) -> T {
        let slot = key as usize % TRIANGLE_CACHE_SIZE;
        if self.keys[slot] != key {
            self.values[slot] = make();
            self.keys[slot] = key;
        }
        self.values[slot]
    }
}

/// Per tile: flat-shaded triangles' colours, and the Gouraud colours of back sides (lit on
/// demand, since most back faces are never seen). Each is (the part a colour texture
/// multiplies, the rest); see `Frame::light_material`.
struct TileCaches {
    flat: TriangleColorCache<(Vec3, Vec3)>,
    back: TriangleColorCache<[(Vec3, Vec3); 3]>,
    /// Flat triangles waiting in [`FlatBatch`]: their index there.
    flat_waiting: TriangleColorCache<u16>,
}

/// What the shading of a band's tiles keeps from tile to tile, so a frame allocates it once per
/// band rather than once per tile. Every table is indexed by the tile's triangles (the values of
/// `Visibility::triangle`).
#[derive(Default)]
pub struct TileScratch<'f> {
    flat: FlatBatch<'f>,
    lightings: LightingMemo<'f>,
    /// Per triangle of the tile: whether a pixel shows it (one more entry, never read, for the
    /// pixels that show nothing).
    seen: Vec<bool>,
    /// Per triangle of the tile: its colour when one colour fills its pixels; the last entry is
    /// the background.
    fills: Vec<Vec3>,
    /// Per triangle of the tile: where its pixels' colours come from in the last pass over the
    /// pixels (the background entry is `Fill`).
    sources: Vec<PixelSource>,
    /// The Gouraud triangles the last pass interpolates, numbered by `PixelSource::Gouraud`.
    gouraud: Vec<GouraudPlane>,
    /// The small Phong triangles the last pass shades, numbered by `PixelSource::Phong`.
    phong: Vec<PhongPlane<'f>>,
    /// Triangles whose colours wait in `flat`: (triangle, index in the batch).
    flat_waiting: Vec<(u32, u16)>,
    /// Triangles with a colour texture whose colours wait in `flat`: (triangle, what
    /// modulates it, index in the batch). Their points are shaded once the batch is lit.
    flat_modulated: Vec<(u32, Modulation<'f>, u16)>,
    /// With several samples per pixel: what the tile's pixels shade, and their colours.
    points: ShadingPoints,
}

/// A multisampled tile's shading points: one per distinct triangle per covered pixel, in pixel
/// order and, within a pixel, in the order of the triangles' first samples (the order the
/// resolve adds them in).
#[derive(Default)]
struct ShadingPoints {
    points: Vec<ShadingPoint>,
    /// Per pixel of the tile (row-major), its first point; one more entry ends the last.
    pixel_start: Vec<u32>,
    /// The points grouped by triangle (each triangle's in pixel order), so that each
    /// triangle's shader is chosen once and runs over all its points.
    by_triangle: Vec<u32>,
    /// Per triangle of the tile, its first entry in `by_triangle`; one more entry ends the last.
    triangle_start: Vec<u32>,
    /// Per point, its shaded colour.
    colors: Vec<Vec3>,
    /// Per triangle of the tile: whether it shows one colour; see [`PointTables`].
    one_colour: Vec<bool>,
    /// Per pixel without points: see [`PointTables`].
    whole: Vec<u32>,
    /// Per triangle of the tile: see [`PointTables`].
    whole_seen: Vec<bool>,
    /// Per triangle of the tile, the resolved colour of a pixel it covers at every sample (for
    /// one-colour triangles that `whole_seen` marks); the last entry is the background.
    whole_colors: Vec<Vec3>,
}

/// A triangle as seen by one pixel's samples.
#[derive(Clone, Copy, Default)]
struct ShadingPoint {
    /// The triangle, numbered within the tile.
    local: u32,
    /// How many of the pixel's samples it covers.
    count: u32,
    /// Where it is shaded, in 1/256 pixel: the mean of its covered samples' positions.
    at: (i64, i64),
}

/// How the last pass over a tile's pixels colours the pixels that show a triangle.
#[derive(Debug, Clone, Copy, PartialEq)]
enum PixelSource {
    /// They are written already (shaded triangle by triangle).
    Shaded,
    /// One colour, in `TileScratch::fills`.
    Fill,
    /// Interpolated from `TileScratch::gouraud[i]` (a tile shows at most `TILE_SIZE²`
    /// triangles, so `u16` numbers them).
    Gouraud(u16),
    /// Shaded from `TileScratch::phong[i]`, through the tile's Phong batch.
    Phong(u16),
}

/// A triangle's edge functions over a tile's pixel centres, as planes: exact integers, the
/// values `edge_values` gives, at any pixel in two products and two sums per edge.
#[derive(Clone, Copy)]
struct TileEdges {
    /// The edge functions at the tile's first pixel centre, and their steps one pixel right
    /// and one pixel down.
    origin: [i64; 3],
    step_x: [i64; 3],
    step_y: [i64; 3],
}

impl TileEdges {
    #[inline]
    fn new(raster: &RasterTriangle, rect: PixelRect) -> Self {
        TileEdges {
            origin: edge_values(raster, pixel_centre(rect.x0), pixel_centre(rect.y0)),
            step_x: edge_steps_x(raster),
            step_y: edge_steps_y(raster),
        }
    }

    /// The edge functions at the centre of the tile's pixel `(column, row)`.
    #[inline(always)]
    fn at(&self, column: i64, row: i64) -> [i64; 3] {
        std::array::from_fn(|k| self.origin[k] + self.step_x[k] * column + self.step_y[k] * row)
    }
}

/// A Phong triangle narrower than a group of lanes in its tile, for the last pass over the
/// tile's pixels, which queues its pixels in the tile's Phong batch in pixel order: walked
/// triangle by triangle, most of a small triangle's bounds are pixels of other triangles, and
/// each costs a mispredicted branch.
struct PhongPlane<'f> {
    edges: TileEdges,
    raster: &'f RasterTriangle,
    corners: Corners,
    shader: FastPhong<'f>,
}

impl PhongPlane<'_> {
    /// The source-triangle weights at the centre of the tile's pixel `(column, row)`: what
    /// [`source_weights`] gives there.
    #[inline(always)]
    fn weights_at(&self, column: i64, row: i64) -> Vec3 {
        weights_from_edges(self.raster, &self.corners, self.edges.at(column, row))
    }
}

/// A Gouraud triangle of a tile, for the interpolation of its colours in pixel order: its edge
/// functions as planes over the tile's pixel centres (exact integers: the values
/// `edge_values` gives) and its colours, in one record.
struct GouraudPlane {
    edges: TileEdges,
    colors: GouraudColors,
    /// The lanes' steps along a row (for [`GouraudPlane::group_colors`]), formed once per
    /// triangle and tile: where the triangle is a group of lanes wide in the tile and its edge
    /// values over the tile are held exactly in `f64` lanes.
    lane_steps: Option<LaneSteps>,
}

impl GouraudPlane {
    fn new(raster: &RasterTriangle, rect: PixelRect, colors: GouraudColors) -> Self {
        GouraudPlane {
            edges: TileEdges::new(raster, rect),
            colors,
            // Only a triangle a group wide can show in a whole group.
            lane_steps: raster
                .bounds
                .intersect(&rect)
                .filter(|area| area.width() as usize >= LANES)
                .and_then(|_| LaneSteps::over(raster, rect)),
        }
    }

    /// The colour at the pixel `(column, row)` of the tile: what [`shade_sample`] gives there,
    /// bit for bit.
    #[inline]
    fn color_at(&self, column: i64, row: i64) -> Vec3 {
        self.colors.at(self.edges.at(column, row))
    }

    /// [`GouraudPlane::color_at`] of the [`LANES`] pixels of row `row` from column `column`
    /// on (within the tile's row), lane-wise and bit for bit; `None` where the edge values are
    /// not held exactly in `f64` lanes (a triangle reaching far off the tile, or one narrower
    /// than a group, which has no lane steps). Lanes outside the triangle get the colours its
    /// planes extend to there.
    #[inline(always)]
    fn group_colors<B: Backend>(&self, column: i64, row: i64) -> Option<Vec3s<B>> {
        let lane_steps = self.lane_steps.as_ref()?;
        Some(
            self.colors
                .at_lanes(lane_steps.edges::<B>(self.edges.at(column, row))),
        )
    }
}

/// A Gouraud triangle's colours, ready to interpolate perspective-correctly: each corner's
/// colour over its `w`, and the corners' `1/w`.
///
/// With `eₖ` the edge functions at a point (`eₖ/A` its screen-space barycentrics), the
/// perspective-correct colour `Σ cₖ·bₖ` with `bₖ = (eₖ/wₖ) / Σ eⱼ/wⱼ` is
/// `Σ (cₖ/wₖ)·eₖ / Σ eⱼ/wⱼ`: the area cancels and the weights need not be formed, so a pixel
/// costs one division (of the colour's three channels at once) instead of three. Every path
/// that interpolates Gouraud colours goes through [`GouraudColors::at`], so a pixel has the same
/// bits whichever path shaded it.
#[derive(Clone, Copy)]
struct GouraudColors {
    over_w: [Vec3A; 3],
    inv_w: [f32; 3],
    /// The colour where the denominator is not positive (see [`GouraudColors::at`]).
    degenerate: Vec3,
}

impl GouraudColors {
    /// `colors` are the source triangle's vertex colours; `corners` map them to the raster
    /// triangle's corners.
    #[inline]
    fn new(raster: &RasterTriangle, corners: &Corners, colors: [Vec3; 3]) -> Self {
        let corner_colors = corners.corner_values(colors);
        let over_w: [Vec3A; 3] = std::array::from_fn(|k| Vec3A::from(corner_colors[k]) * raster.inv_w[k]);
        let [w0, w1, w2] = raster.inv_w;
        GouraudColors {
            over_w,
            inv_w: raster.inv_w,
            degenerate: Vec3::from((over_w[0] + over_w[1] + over_w[2]) / (w0 + w1 + w2)),
        }
    }

    /// The colour where the raster triangle's edge functions take the values `edges`.
    /// Inside the triangle (`eₖ ≥ 0`, `1/wₖ > 0`) the denominator is positive; where it is not
    /// (only on degenerate input) the colour is the corners' mean weighted by `1/w`, a colour
    /// of the triangle all the same.
    #[inline]
    fn at(&self, edges: [i64; 3]) -> Vec3 {
        let [e0, e1, e2] = edges.map(|e| e as f32);
        let [w0, w1, w2] = self.inv_w;
        let [c0, c1, c2] = self.over_w;
        let denominator = e0 * w0 + e1 * w1 + e2 * w2;
        if denominator > 0.0 {
            Vec3::from((c0 * e0 + c1 * e1 + c2 * e2) / denominator)
        } else {
            self.degenerate
        }
    }

    /// [`GouraudColors::at`] for eight points, the edge functions' values (already `f32`)
    /// in lanes: each channel's products, sums and division in the scalar's order, lane by
    /// lane.
    #[inline(always)]
    fn at_lanes<B: Backend>(&self, edges: [Floats<B>; 3]) -> Vec3s<B> {
        let [e0, e1, e2] = edges;
        let [w0, w1, w2] = self.inv_w.map(Floats::splat);
        let [c0, c1, c2] = self.over_w.map(|c| Vec3s::splat(Vec3::from(c)));
        let denominator = e0 * w0 + e1 * w1 + e2 * w2;
        let inside = denominator.gt(Floats::splat(0.0));
        let interpolated = (c0.scale(e0) + c1.scale(e1) + c2.scale(e2)).divide(denominator);
        // Inside a triangle every lane's denominator is positive: the select is for degenerate
        // input only.
        if inside.all() {
            interpolated
        } else {
            inside.select3(interpolated, Vec3s::splat(self.degenerate))
        }
    }
}

/// The Gouraud colour a pixel of `raster` shows at the fixed-point point `at`, from the source
/// triangle's vertex colours `colors`: [`GouraudColors::at`], as every Gouraud pixel is made.
pub(crate) fn gouraud_color_at(
    raster: &RasterTriangle,
    corners: &Corners,
    colors: [Vec3; 3],
    at: (i64, i64),
) -> Vec3 {
    GouraudColors::new(raster, corners, colors).at(edge_values(raster, at.0, at.1))
}

/// Where the frame shades pixel `(x, y)` of the tile `visibility` holds: per distinct triangle
/// its samples show (in the order of their first samples), the tile's number of the triangle,
/// how many samples it covers and the point it is shaded at (1/256 pixel). The first pass of
/// [`shade_multisampled`] itself, run over the tile; with one sample, the pixel's centre.
pub(crate) fn pixel_shading_points(visibility: &Visibility, x: u32, y: u32) -> Vec<(u32, u32, (i64, i64))> {
    let rect = visibility.rect;
    let pixel = ((y - rect.y0) * rect.width() + (x - rect.x0)) as usize;
    let samples = visibility.pattern.len();
    if samples == 1 {
        let local = visibility.triangle[pixel];
        return if local == NO_TRIANGLE {
            Vec::new()
        } else {
            vec![(local, 1, (pixel_centre(x), pixel_centre(y)))]
        };
    }
    let pixel_count = (rect.width() * rect.height()) as usize;
    let mut points = vec![ShadingPoint::default(); pixel_count * samples];
    let mut pixel_start = vec![0; pixel_count + 1];
    let count = visibility.raster_ids.len();
    let mut triangle_start = vec![0; count + 2];
    // Every triangle's whole pixels get their point (none is taken as one colour).
    let point_count = find_points_of_pattern(
        samples,
        visibility,
        PointTables {
            one_colour: &vec![false; count],
            points: &mut points,
            pixel_start: &mut pixel_start,
            triangle_start: &mut triangle_start,
            whole: &mut vec![0; pixel_count],
            whole_seen: &mut vec![false; count],
        },
    );
    pixel_start[pixel_count] = point_count as u32;
    points[pixel_start[pixel] as usize..pixel_start[pixel + 1] as usize]
        .iter()
        .map(|point| (point.local, point.count, point.at))
        .collect()
}

/// A Gouraud triangle's colours split as for a colour texture: the part it multiplies and the
/// rest, each interpolated as [`GouraudColors`].
struct SplitGouraudColors {
    textured: GouraudColors,
    rest: GouraudColors,
}

impl SplitGouraudColors {
    /// `colors` are the source triangle's vertex colours as (textured part, rest).
    fn new(raster: &RasterTriangle, corners: &Corners, colors: [(Vec3, Vec3); 3]) -> Self {
        SplitGouraudColors {
            textured: GouraudColors::new(raster, corners, colors.map(|(textured, _)| textured)),
            rest: GouraudColors::new(raster, corners, colors.map(|(_, rest)| rest)),
        }
    }

    /// (textured part, rest) where the edge functions take the values `edges`.
    #[inline]
    fn at(&self, edges: [i64; 3]) -> (Vec3, Vec3) {
        (self.textured.at(edges), self.rest.at(edges))
    }
}

/// The fast-path flat triangles a tile shows, lit together once the tile's pixels are known.
/// One at a time, each triangle waits on its own cache misses (its corners) and its own chain of
/// square roots and divisions; together, the corner loads overlap and the arithmetic runs
/// [`LANES`] wide.
#[derive(Default)]
struct FlatBatch<'f> {
    /// Per waiting triangle: its lighting, the triangle and its side.
    waiting: Vec<(FastLighting<'f>, FrameTriangle, bool)>,
    /// Per lit triangle, its colour split as `Frame::flat_colors` splits it: (the part a colour
    /// texture multiplies, the rest); without a colour texture the first is zero and the
    /// second the whole colour.
    colors: Vec<(Vec3, Vec3)>,
}

// A tile's pixels show at most `TILE_SIZE²` triangles, so those waiting are numbered by `u16`.
const _: () = assert!(TILE_SIZE * TILE_SIZE <= u16::MAX as u32);

impl<'f> FlatBatch<'f> {
    fn clear(&mut self) {
        self.waiting.clear();
        self.colors.clear();
    }

    /// Queues `triangle`, seen from the back if `back_facing`; returns its index.
    fn add(&mut self, lighting: FastLighting<'f>, triangle: FrameTriangle, back_facing: bool) -> u16 {
        self.waiting.push((lighting, triangle, back_facing));
        (self.waiting.len() - 1) as u16
    }

    /// The colour of every waiting triangle, into `colors`.
    fn light(&mut self, frame: &Frame) {
        self.colors.clear();
        let count = self.waiting.len();
        let mut start = 0;
        while start < count {
            let lighting = self.waiting[start].0;
            let mut end = start + 1;
            while end < count && end - start < LANES && lighting.same_as(&self.waiting[end].0) {
                end += 1;
            }
            // The lanes past the last triangle repeat it; their results are dropped.
            let waiting = |lane: usize| self.waiting[start + lane.min(end - start - 1)];
            let mut centroids = [Vec3::ZERO; LANES];
            let mut crossed = [Vec3::ZERO; LANES];
            let mut reversed = [false; LANES];
            for lane in 0..LANES {
                let (_, triangle, back_facing) = waiting(lane);
                let [p0, p1, p2] = triangle.vertices.map(|v| frame.vertices[v as usize].position);
                centroids[lane] = (p0 + p1 + p2) / 3.0;
                crossed[lane] = (p1 - p0).cross(p2 - p0);
                let style = &frame.objects[triangle.object as usize];
                reversed[lane] = style.reverses_normal(back_facing);
            }
            // `Frame::face_normal`'s normalisation and `ObjectStyle::side_normal`, lane-wise.
            let face_normals = Vec3s::from_array(&crossed).normalize_or_zero();
            let normals = Mask::from_bools(reversed).select3(-face_normals, face_normals);
            let centroids = Vec3s::from_array(&centroids);
            let mut surface = SurfaceLanes::of(lighting.material());
            if !frame.vertex_attributes.is_empty() {
                // `Frame::flat_colors`' tinted material.
                let tints = std::array::from_fn(|lane| frame.flat_tint(&waiting(lane).1));
                surface.diffuse = surface.diffuse * Vec3s::from_array(&tints);
            }
            let lit = lighting.light_surface_lanes(centroids, normals, &surface);
            let lit = if has_color_texture(lighting.material()) {
                let (textured, rest) = (lit.textured.to_array(), lit.rest.to_array());
                std::array::from_fn(|lane| (textured[lane], rest[lane]))
            } else {
                (lit.textured + lit.rest)
                    .to_array()
                    .map(|color| (Vec3::ZERO, color))
            };
            self.colors.extend_from_slice(&lit[..end - start]);
            start = end;
        }
    }
}

/// Shades every pixel of a tile.
///
/// With several samples per pixel (multisampling), each distinct triangle seen by a pixel's
/// samples is shaded once, at the mean position of the samples it covers (a convex combination
/// of covered points, so inside the triangle: no extrapolated attributes), and the pixel is
/// the average of its samples in linear light, background included. One sample per pixel is
/// the same computation with the pixel centre.
///
/// Writes every pixel of the tile into `target` (the background where nothing is seen) and
/// returns the number of shading evaluations (one per distinct triangle per covered pixel).
///
/// Always inlined: the pixel inspector calls it too, and with a second caller it was left out of
/// line in the frame's band loop, which then ran 1–2 % more instructions (callgrind, S1).
#[inline(always)]
pub fn shade_tile<'f>(
    frame: &'f Frame,
    visibility: &Visibility,
    background: Vec3,
    target: &mut TileTarget,
    scratch: &mut TileScratch<'f>,
) -> usize {
    let mut caches = TileCaches {
        flat: TriangleColorCache::new(),
        back: TriangleColorCache::new(),
        flat_waiting: TriangleColorCache::new(),
    };
    if visibility.pattern.len() == 1 {
        shade_single_sample(frame, visibility, background, target, scratch, &mut caches)
    } else {
        shade_multisampled(frame, visibility, background, target, scratch, &mut caches)
    }
}

/// Writes the pixels `rect` of `target` as a tile no triangle reaches: the background,
/// uncovered. Only a lone tile's shading (the inspector's) writes such a tile: the frame leaves
/// it blank in the frame buffer, unwritten.
fn fill_background(rect: PixelRect, background: Vec3, target: &mut TileTarget) {
    let tile_width = rect.width() as usize;
    for row in 0..rect.height() as usize {
        let row_start = row * target.stride + rect.x0 as usize;
        target.color[row_start..row_start + tile_width].fill(background);
        target.covered[row_start..row_start + tile_width].fill(false);
    }
}

/// [`shade_tile`] with several samples per pixel, in three passes. The first finds each pixel's
/// distinct triangles and where each is shaded: the mean of the offsets of the samples it
/// covers, rounded down to 1/256 pixel. The second shades those points triangle by triangle
/// through the shaders one sample per pixel uses ([`TriangleShader`]: fills, Gouraud planes,
/// Phong lanes, and the general [`shade_sample`] only where a single sample takes it too), so
/// each point has the bits `shade_sample` gives there. The last resolves each pixel: its
/// points' colours weighted by their sample counts and added in the order of their first
/// samples, the background for the samples nothing covers, over the sample count. A pixel
/// that a triangle of one colour (flat or constant, no colour texture) covers at every sample
/// has no point: it takes the triangle's resolved colour, formed once per triangle by the
/// same operations.
fn shade_multisampled<'f>(
    frame: &'f Frame,
    visibility: &Visibility,
    background: Vec3,
    target: &mut TileTarget,
    scratch: &mut TileScratch<'f>,
    caches: &mut TileCaches,
) -> usize {
    let rect = visibility.rect;
    let pattern = visibility.pattern;
    let samples = pattern.len();
    let pixel_count = (rect.width() * rect.height()) as usize;
    let tile_width = rect.width() as usize;
    let stride = target.stride;
    let count = visibility.raster_ids.len();
    let TileScratch {
        flat,
        lightings,
        flat_waiting,
        flat_modulated,
        points: tile,
        ..
    } = scratch;
    let ShadingPoints {
        points,
        pixel_start,
        by_triangle,
        triangle_start,
        colors,
        one_colour,
        whole,
        whole_seen,
        whole_colors,
    } = tile;

    // Each pixel's points. The buffers only grow: every entry up to `point_count` is written below before it is
    // read, so they are not cleared (clearing showed as a memset per tile).
    if points.len() < pixel_count * samples {
        points.resize(pixel_count * samples, ShadingPoint::default());
    }
    pixel_start.resize(pixel_count + 1, 0);
    triangle_start.clear();
    triangle_start.resize(count + 2, 0);
    one_colour.clear();
    one_colour.extend((0..count as u32).map(|local| {
        TriangleShader::is_one_colour(frame, frame.raster_triangle(visibility.raster_id(local)))
    }));
    // Like `pixel_start`, `whole` is written for every pixel that reads it.
    if whole.len() < pixel_count {
        whole.resize(pixel_count, 0);
    }
    whole_seen.clear();
    whole_seen.resize(count, false);
    whole_colors.resize(count + 1, Vec3::ZERO);
    whole_colors[count] = background;
    let point_count = find_points_of_pattern(
        samples,
        visibility,
        PointTables {
            one_colour,
            points,
            pixel_start,
            triangle_start,
            whole,
            whole_seen,
        },
    );
    pixel_start[pixel_count] = point_count as u32;
    let points = &points[..point_count];

    // Group the points by triangle (a counting sort: `triangle_start[t + 2]` counted
    // triangle `t`'s points; after the prefix sums `triangle_start[t + 1]` is where they go,
    // and after the scatter it is where they end).
    for local in 2..count + 2 {
        triangle_start[local] += triangle_start[local - 1];
    }
    if by_triangle.len() < points.len() {
        by_triangle.resize(points.len(), 0);
    }
    for (index, point) in points.iter().enumerate() {
        let next = &mut triangle_start[point.local as usize + 1];
        by_triangle[*next as usize] = index as u32;
        *next += 1;
    }
    triangle_start.truncate(count + 1);

    // Shade every point, triangle by triangle, in the order they were rasterized.
    if colors.len() < points.len() {
        colors.resize(points.len(), Vec3::ZERO);
    }
    flat.clear();
    flat_waiting.clear();
    flat_modulated.clear();
    let mut phong = PhongBatch::default();
    let mut surface = SurfaceBatch::default();
    let mut modulated = ModulatedBatch::default();
    for local in 0..count {
        prefetch_vertices(frame, visibility, local + VERTEX_PREFETCH);
        let mine = &by_triangle[triangle_start[local] as usize..triangle_start[local + 1] as usize];
        if mine.is_empty() && !whole_seen[local] {
            continue;
        }
        let id = visibility.raster_id(local as u32);
        let raster = frame.raster_triangle(id);
        let point_at = |index: u32| points[index as usize].at;
        let shader = TriangleShader::new(frame, raster, caches, flat, lightings);
        debug_assert_eq!(
            matches!(shader, TriangleShader::Solid(_) | TriangleShader::FlatWaiting(_)),
            one_colour[local],
            "`TriangleShader::is_one_colour` agrees with `TriangleShader::new`"
        );
        match shader {
            TriangleShader::Solid(color) => {
                whole_colors[local] = resolve_whole(color, samples, background);
                for &index in mine {
                    colors[index as usize] = color;
                }
            }
            TriangleShader::FlatWaiting(batch_index) => flat_waiting.push((local as u32, batch_index)),
            TriangleShader::Gouraud(vertex_colors) => {
                let interpolated = GouraudColors::new(raster, &frame.corner_weights(id), vertex_colors);
                // The edge functions at points scattered over the tile, as planes.
                let planes = EdgePlanes::new(raster);
                for &index in mine {
                    let (x, y) = point_at(index);
                    colors[index as usize] = interpolated.at(planes.at(x, y));
                }
            }
            TriangleShader::Phong(fast) => {
                let corners = frame.corner_weights(id);
                let planes = EdgePlanes::new(raster);
                for &index in mine {
                    let (x, y) = point_at(index);
                    let weights = weights_from_edges(raster, &corners, planes.at(x, y));
                    phong.push(&fast, weights, index as usize, colors);
                }
            }
            TriangleShader::ModulatedFlatWaiting(modulation, batch_index) => {
                flat_modulated.push((local as u32, modulation, batch_index));
            }
            TriangleShader::Varying(shader) => {
                let points = SampledPoints {
                    raster,
                    indices: mine,
                    points,
                };
                let corners = frame.corner_weights(id);
                shade_varying(
                    frame,
                    raster,
                    &corners,
                    shader,
                    points,
                    &mut surface,
                    &mut modulated,
                    colors,
                );
            }
            TriangleShader::General => {
                let corners = frame.corner_weights(id);
                for &index in mine {
                    colors[index as usize] = shade_sample(frame, raster, &corners, point_at(index), caches);
                }
            }
        }
    }
    phong.flush(colors);
    surface.flush(colors);
    flat.light(frame);
    for &(local, batch_index) in flat_waiting.iter() {
        let (_, color) = flat.colors[usize::from(batch_index)];
        let local = local as usize;
        whole_colors[local] = resolve_whole(color, samples, background);
        for &index in &by_triangle[triangle_start[local] as usize..triangle_start[local + 1] as usize] {
            colors[index as usize] = color;
        }
    }
    for &(local, modulation, batch_index) in flat_modulated.iter() {
        let id = visibility.raster_id(local);
        let raster = frame.raster_triangle(id);
        let local = local as usize;
        let points = SampledPoints {
            raster,
            indices: &by_triangle[triangle_start[local] as usize..triangle_start[local + 1] as usize],
            points,
        };
        let shader = VaryingShader::Flat(modulation, flat.colors[usize::from(batch_index)]);
        let corners = frame.corner_weights(id);
        shade_varying(
            frame,
            raster,
            &corners,
            shader,
            points,
            &mut surface,
            &mut modulated,
            colors,
        );
    }
    modulated.flush(frame, colors);

    // The resolve, in the order of operations of one pixel at a time; a pixel without points
    // takes its whole colour, resolved the same way once per triangle.
    let depth_view = frame.debug_view == Some(DebugView::Depth);
    let mut whole_pixels = 0;
    for row in 0..rect.height() as usize {
        let row_start = row * stride + rect.x0 as usize;
        let starts = &pixel_start[row * tile_width..=(row + 1) * tile_width];
        let pixels = target.color[row_start..row_start + tile_width]
            .iter_mut()
            .zip(&mut target.covered[row_start..row_start + tile_width])
            .zip(&whole[row * tile_width..(row + 1) * tile_width]);
        for (((color, covered), &whole), start) in pixels.zip(starts.windows(2)) {
            let (first, last) = (start[0] as usize, start[1] as usize);
            if first == last {
                let shows_one = whole as usize != count;
                whole_pixels += usize::from(shows_one);
                *covered = shows_one;
                *color = whole_colors[whole as usize];
                continue;
            }
            *covered = true;
            let shown = points[first..last].iter().zip(&colors[first..last]);
            *color = resolve_pixel(
                shown.map(|(point, &color)| (color, point.count)),
                samples,
                background,
                depth_view,
            );
        }
    }
    points.len() + whole_pixels
}

/// A multisampled pixel's colour from its points' colours and sample counts, in order: their
/// sum weighted by the counts, plus the background for the samples nothing covers, over the
/// sample count (in the depth view, distances over the covered samples only: the background
/// has none).
#[inline(always)]
fn resolve_pixel(
    shown: impl Iterator<Item = (Vec3, u32)>,
    samples: usize,
    background: Vec3,
    depth_view: bool,
) -> Vec3 {
    let mut sum = Vec3::ZERO;
    let mut covered_samples = 0;
    for (color, count) in shown {
        sum += color * count as f32;
        covered_samples += count;
    }
    if depth_view {
        sum / covered_samples as f32
    } else {
        (sum + background * (samples as u32 - covered_samples) as f32) / samples as f32
    }
}

/// [`resolve_pixel`] of a pixel whose every sample shows one triangle of colour `color`: the
/// same operations, so the same bits, as a point covering all the samples.
#[inline]
fn resolve_whole(color: Vec3, samples: usize, background: Vec3) -> Vec3 {
    resolve_pixel(
        std::iter::once((color, samples as u32)),
        samples,
        background,
        false,
    )
}

/// [`find_points`] for the tile's pattern of `samples` samples a pixel.
fn find_points_of_pattern(samples: usize, visibility: &Visibility, found: PointTables) -> usize {
    let find = match samples {
        2 => find_points::<2>,
        4 => find_points::<4>,
        8 => find_points::<8>,
        16 => find_points::<16>,
        _ => unreachable!("sample patterns have 1, 2, 4, 8 or 16 samples (`SamplePattern::new`)"),
    };
    find(visibility, found)
}

/// What [`find_points`] reads and writes, each indexed as [`ShadingPoints`] is.
struct PointTables<'a> {
    /// Per triangle of the tile: whether it shows one colour ([`TriangleShader::is_one_colour`]).
    /// Pixels such a triangle covers at every sample get no point: `whole` names it.
    one_colour: &'a [bool],
    points: &'a mut [ShadingPoint],
    pixel_start: &'a mut [u32],
    /// Per triangle of the tile, two entries on (see [`shade_multisampled`]): its count of points.
    triangle_start: &'a mut [u32],
    /// Per pixel without points: the one-colour triangle covering all its samples, or the
    /// tile's triangle count for none (the background). Not written for pixels with points.
    whole: &'a mut [u32],
    /// Per triangle of the tile: set where a pixel is wholly the triangle's and has no point.
    whole_seen: &'a mut [bool],
}

/// The first pass of [`shade_multisampled`] for `S` samples per pixel (a constant, so that the
/// comparisons of a pixel's samples unroll): each pixel's points into `points` from its entry
/// of `pixel_start` on, and each triangle's count of points into `triangle_start[t + 2]`.
/// Returns the number of points. Most pixels of a mesh lie inside one triangle: all their
/// samples show it, with no search; a one-colour triangle's such pixel is named in `whole`
/// (resolved from the triangle's colour), another's gets one point at the mean of the whole
/// pattern. In the other pixels each distinct triangle, taken in the order of its first
/// sample, is compared with all samples at once into a mask of the samples it covers, and the
/// mask names its count and shading point in the pattern's table ([`SamplePattern::subset`]).
fn find_points<const S: usize>(visibility: &Visibility, found: PointTables) -> usize {
    let PointTables {
        one_colour,
        points,
        pixel_start,
        triangle_start,
        whole,
        whole_seen,
    } = found;
    let rect = visibility.rect;
    let tile_width = rect.width() as usize;
    let pattern = visibility.pattern;
    let background = visibility.raster_ids.len() as u32;
    let all_samples = (1u32 << S) - 1;
    let whole_pixel = pattern.subset(all_samples);
    let mut point_count = 0;
    let rows = visibility.triangle.chunks_exact(S * tile_width);
    let pixels = pixel_start
        .chunks_exact_mut(tile_width)
        .zip(whole.chunks_exact_mut(tile_width));
    for ((row, row_ids), (row_starts, row_whole)) in rows.enumerate().zip(pixels) {
        let centre_y = pixel_centre(rect.y0 + row as u32);
        let columns = row_ids
            .as_chunks::<S>()
            .0
            .iter()
            .zip(row_starts.iter_mut().zip(row_whole));
        for (column, (ids, (start, whole))) in columns.enumerate() {
            *start = point_count as u32;
            let centre_x = pixel_centre(rect.x0 + column as u32);
            let mut push = |local: u32, subset: SampleSubset| {
                points[point_count] = ShadingPoint {
                    local,
                    count: subset.count,
                    at: (
                        centre_x + i64::from(subset.mean_x),
                        centre_y + i64::from(subset.mean_y),
                    ),
                };
                point_count += 1;
                triangle_start[local as usize + 2] += 1;
            };
            let first = ids[0];
            if samples_showing(ids, first) == all_samples {
                if first == NO_TRIANGLE {
                    *whole = background;
                } else if one_colour[first as usize] {
                    *whole = first;
                    whole_seen[first as usize] = true;
                } else {
                    push(first, whole_pixel);
                }
                continue;
            }
            let mut remaining = all_samples & !samples_showing(ids, NO_TRIANGLE);
            while remaining != 0 {
                let local = ids[remaining.trailing_zeros() as usize];
                let covered = samples_showing(ids, local);
                remaining &= !covered;
                push(local, pattern.subset(covered));
            }
        }
    }
    point_count
}

/// [`shade_tile`] with one sample at each pixel centre: the general loop with `seen` holding one
/// entry at offset zero, and the same result bit for bit, computed triangle by triangle instead
/// of pixel by pixel. A pass over the pixels finds the triangles they show (the rasterizer
/// numbered the tile's triangles, so tables indexed by that number replace caches); each of
/// those gets its shader once; a Phong triangle at least a group of lanes wide shades the
/// pixels of its bounds that show it, at once; the triangles of one colour (flat, constant) are
/// lit eight at a time, and they, the background, the Gouraud triangles' interpolated colours
/// and the narrower Phong triangles' pixels (queued in the Phong batch) are written in one
/// last pass over the pixels, in pixel order (a small triangle's bounds hold more pixels that
/// do not show it than pixels that do, and each costs a mispredicted branch when walked
/// triangle by triangle). No decision is taken per run of pixels (runs are two or three pixels long on
/// dense meshes).
fn shade_single_sample<'f>(
    frame: &'f Frame,
    visibility: &Visibility,
    background: Vec3,
    target: &mut TileTarget,
    scratch: &mut TileScratch<'f>,
    caches: &mut TileCaches,
) -> usize {
    let rect = visibility.rect;
    let tile_width = rect.width() as usize;
    let stride = target.stride;
    let count = visibility.raster_ids.len();
    if count == 0 {
        fill_background(rect, background, target);
        return 0;
    }
    let TileScratch {
        flat,
        lightings,
        seen,
        fills,
        sources,
        gouraud,
        phong: phong_planes,
        flat_waiting,
        flat_modulated,
        points: _,
    } = scratch;
    flat.clear();
    flat_waiting.clear();
    flat_modulated.clear();
    gouraud.clear();
    phong_planes.clear();
    sources.clear();
    // Unseen triangles keep `Fill`: no pixel reads it, and the last pass can then take its
    // fill-only form when every seen triangle is one colour.
    sources.resize(count + 1, PixelSource::Fill);
    seen.clear();
    seen.resize(count + 1, false);
    fills.clear();
    fills.resize(count + 1, Vec3::ZERO);
    fills[count] = background;
    // `NO_TRIANGLE` (u32::MAX) becomes `count`: the background's entry.
    let entry = |id: u32| (id as usize).min(count);

    // Coverage, and which triangles are seen: a group of pixels showing one triangle (inside a
    // large one, or the background) marks it once.
    let mut shaded = 0;
    for (row, ids) in visibility.triangle.chunks_exact(tile_width).enumerate() {
        let row_start = row * stride + rect.x0 as usize;
        let covered = &mut target.covered[row_start..row_start + tile_width];
        let (covered_groups, covered_rest) = covered.as_chunks_mut::<LANES>();
        let (id_groups, id_rest) = ids.as_chunks::<LANES>();
        for (covered, group) in covered_groups.iter_mut().zip(id_groups) {
            shaded += mark_shown(group, NO_TRIANGLE, covered);
            if samples_showing(group, group[0]) == ALL_LANES {
                seen[entry(group[0])] = true;
            } else {
                for &id in group {
                    seen[entry(id)] = true;
                }
            }
        }
        for (covered, &id) in covered_rest.iter_mut().zip(id_rest) {
            *covered = id != NO_TRIANGLE;
            shaded += usize::from(*covered);
            seen[entry(id)] = true;
        }
    }

    // One shader per seen triangle, in the order they were rasterized. Triangles shaded pixel by
    // pixel are shaded at once; the others get their colour in `fills`.
    let mut phong = PhongBatch::default();
    let mut surface = SurfaceBatch::default();
    let mut modulated = ModulatedBatch::default();
    for local in 0..count {
        prefetch_vertices(frame, visibility, local + VERTEX_PREFETCH);
        if !seen[local] {
            continue;
        }
        let id = visibility.raster_id(local as u32);
        let raster = frame.raster_triangle(id);
        let shader = TriangleShader::new(frame, raster, caches, flat, lightings);
        let corners = match shader {
            TriangleShader::Solid(color) => {
                fills[local] = color;
                sources[local] = PixelSource::Fill;
                continue;
            }
            TriangleShader::FlatWaiting(index) => {
                flat_waiting.push((local as u32, index));
                sources[local] = PixelSource::Fill;
                continue;
            }
            TriangleShader::ModulatedFlatWaiting(modulation, index) => {
                flat_modulated.push((local as u32, modulation, index));
                sources[local] = PixelSource::Shaded;
                continue;
            }
            _ => frame.corner_weights(id),
        };
        // Gouraud pixels are interpolated in the last pass, in pixel order: walking each small
        // triangle's bounds here would take a branch per pixel on which triangle it shows.
        if let TriangleShader::Gouraud(colors) = shader {
            sources[local] = PixelSource::Gouraud(gouraud.len() as u16);
            gouraud.push(GouraudPlane::new(
                raster,
                rect,
                GouraudColors::new(raster, &corners, colors),
            ));
            continue;
        }
        let Some(area) = raster.bounds.intersect(&rect) else {
            sources[local] = PixelSource::Shaded;
            continue;
        };
        // A Phong triangle narrower than a group of lanes waits for the last pass, if its
        // pixels can share a batch with the others waiting (one material of one object: a
        // mesh's, nearly always), so that the batch fills its lanes in pixel order.
        let shader = match shader {
            TriangleShader::Phong(fast)
                if (area.width() as usize) < LANES
                    && phong_planes
                        .first()
                        .is_none_or(|first| first.shader.shares_batch(&fast)) =>
            {
                sources[local] = PixelSource::Phong(phong_planes.len() as u16);
                phong_planes.push(PhongPlane {
                    edges: TileEdges::new(raster, rect),
                    raster,
                    corners,
                    shader: fast,
                });
                continue;
            }
            shader => shader,
        };
        sources[local] = PixelSource::Shaded;
        let pixels = ShownPixels {
            visibility,
            local: local as u32,
            raster,
            area,
            stride,
        };
        match shader {
            TriangleShader::Phong(fast) => {
                match PhongRows::of(&fast, raster.inv_area, raster.inv_w, corners) {
                    Some(rows) if area.width() as usize >= LANES => {
                        let mut gathered = GatheredPixels::default();
                        pixels.for_each_group(|group| {
                            if group.shown.all() {
                                let colors: &mut [Vec3; LANES] = (&mut target.color
                                    [group.first..group.first + LANES])
                                    .try_into()
                                    .expect("a group of lanes");
                                rows.shade_into(|| group.edges(), colors);
                                return;
                            }
                            // A group showing the triangle in some lanes only (its edges) would
                            // light lanes that are thrown away: its pixels are gathered into
                            // full lanes of the same rows.
                            for lane in (0..LANES).filter(|&lane| group.shown.lane(lane)) {
                                if gathered.push(group.first + lane, group.edges_at(lane)) {
                                    let colors = rows.shade(|| gathered.edges());
                                    for (&offset, color) in gathered.offsets.iter().zip(colors) {
                                        target.color[offset] = color;
                                    }
                                    gathered.len = 0;
                                }
                            }
                        });
                        // The last few wait in the batch, which fills its lanes across triangles.
                        for lane in 0..gathered.len {
                            let edges = std::array::from_fn(|k| gathered.edges[k][lane]);
                            let weights = weights_from_edges(raster, &corners, edges);
                            phong.push(&fast, weights, gathered.offsets[lane], target.color);
                        }
                    }
                    _ => pixels.for_each(|offset, _, edges| {
                        let weights = weights_from_edges(raster, &corners, edges);
                        phong.push(&fast, weights, offset, target.color);
                    }),
                }
            }
            TriangleShader::Varying(shader) => shade_varying(
                frame,
                raster,
                &corners,
                shader,
                pixels,
                &mut surface,
                &mut modulated,
                target.color,
            ),
            TriangleShader::General => pixels.for_each(|offset, at, _| {
                target.color[offset] = shade_sample(frame, raster, &corners, at, caches);
            }),
            TriangleShader::Solid(_)
            | TriangleShader::FlatWaiting(_)
            | TriangleShader::ModulatedFlatWaiting(..)
            | TriangleShader::Gouraud(_) => {}
        }
    }
    phong.flush(target.color);
    surface.flush(target.color);
    flat.light(frame);
    for &(local, index) in flat_waiting.iter() {
        fills[local as usize] = flat.colors[usize::from(index)].1;
    }
    // The flat triangles with a colour texture, now that their colours are known.
    for &(local, modulation, index) in flat_modulated.iter() {
        let id = visibility.raster_id(local);
        let raster = frame.raster_triangle(id);
        let Some(area) = raster.bounds.intersect(&rect) else {
            continue;
        };
        let pixels = ShownPixels {
            visibility,
            local,
            raster,
            area,
            stride,
        };
        let shader = VaryingShader::Flat(modulation, flat.colors[usize::from(index)]);
        let corners = frame.corner_weights(id);
        shade_varying(
            frame,
            raster,
            &corners,
            shader,
            pixels,
            &mut surface,
            &mut modulated,
            target.color,
        );
    }
    modulated.flush(frame, target.color);

    // The background, the one-colour triangles and the Gouraud ones, in one pass over the pixels.
    let per_pixel = sources.iter().any(|&source| source != PixelSource::Fill);
    let pass = LastPass {
        sources,
        fills,
        gouraud,
        stride,
    };
    if !phong_planes.is_empty() {
        last_pass_with_phong(visibility, &pass, phong_planes, &mut phong, target.color);
        phong.flush(target.color);
        return shaded;
    }
    if per_pixel {
        // On the widest lanes, for the Gouraud groups.
        run_widest(LastPassRows {
            visibility,
            pass: &pass,
            color: target.color,
        });
        return shaded;
    }
    for (row, ids) in visibility.triangle.chunks_exact(tile_width).enumerate() {
        let row_start = row * stride + rect.x0 as usize;
        let colors = &mut target.color[row_start..row_start + tile_width];
        for (colors, ids) in colors.chunks_mut(LANES).zip(ids.chunks(LANES)) {
            // A group showing one triangle takes its colour once.
            if let Ok(group_ids) = <&[u32; LANES]>::try_from(ids)
                && samples_showing(group_ids, group_ids[0]) == ALL_LANES
            {
                fill_group(colors, fills[entry(group_ids[0])]);
                continue;
            }
            for (color, &id) in colors.iter_mut().zip(ids) {
                *color = fills[entry(id)];
            }
        }
    }
    shaded
}

/// [`shade_single_sample`]'s last pass over a tile whose pixels are not all fills (and which
/// has no small Phong triangle): the fills, the Gouraud planes' groups in lanes and their
/// pixels one by one, as lane work (one call of [`run_widest`] a tile).
struct LastPassRows<'p> {
    visibility: &'p Visibility,
    pass: &'p LastPass<'p>,
    color: &'p mut [Vec3],
}

impl LaneWork for LastPassRows<'_> {
    type Output = ();

    #[inline(always)]
    fn run<B: Backend>(self) {
        let LastPassRows {
            visibility,
            pass,
            color,
        } = self;
        let rect = visibility.rect;
        let tile_width = rect.width() as usize;
        for (row, ids) in visibility.triangle.chunks_exact(tile_width).enumerate() {
            let row_start = row * pass.stride + rect.x0 as usize;
            let colors = &mut color[row_start..row_start + tile_width];
            for (group, (colors, ids)) in colors.chunks_mut(LANES).zip(ids.chunks(LANES)).enumerate() {
                let first_column = group * LANES;
                if let Ok(group_ids) = <&[u32; LANES]>::try_from(ids)
                    && let Ok(group) = <&mut [Vec3; LANES]>::try_from(&mut *colors)
                    && (pass.write_whole_group::<B>(group_ids, first_column, row, group)
                        || pass.write_two_triangle_group::<B>(group_ids, first_column, row, group))
                {
                    continue;
                }
                for (column, (color, &id)) in (first_column..).zip(colors.iter_mut().zip(ids)) {
                    // No Phong source here: tiles with small Phong triangles take
                    // `last_pass_with_phong`.
                    pass.write_pixel(id, column, row, color);
                }
            }
        }
    }
}

/// What the last pass over a single-sample tile's pixels reads: each triangle's source, the
/// one-colour triangles' colours and the Gouraud planes.
struct LastPass<'s> {
    sources: &'s [PixelSource],
    fills: &'s [Vec3],
    gouraud: &'s [GouraudPlane],
    /// Pixels per row of the band the tile is written into.
    stride: usize,
}

impl LastPass<'_> {
    /// The entry of the tile's triangle `id` in `sources` and `fills`: `NO_TRIANGLE`
    /// (`u32::MAX`) becomes the background's, the last.
    #[inline(always)]
    fn entry(&self, id: u32) -> usize {
        (id as usize).min(self.sources.len() - 1)
    }

    /// Writes the colours of a group of [`LANES`] pixels of row `row` from column
    /// `first_column` on where all show one triangle (inside a large one) whose source gives
    /// them at once: a fill, or a Gouraud plane in lanes. False (nothing written) for any other
    /// group, whose pixels are taken one by one.
    #[inline(always)]
    fn write_whole_group<B: Backend>(
        &self,
        ids: &[u32; LANES],
        first_column: usize,
        row: usize,
        colors: &mut [Vec3; LANES],
    ) -> bool {
        if samples_showing(ids, ids[0]) != ALL_LANES {
            return false;
        }
        let id = ids[0];
        match self.sources[self.entry(id)] {
            PixelSource::Fill => {
                fill_vec3s(colors, self.fills[self.entry(id)]);
                true
            }
            PixelSource::Gouraud(_) => {
                let Some(group) = self.source_lanes::<B>(id, first_column, row) else {
                    return false;
                };
                group.write_to(colors);
                true
            }
            PixelSource::Phong(_) => false,
            PixelSource::Shaded => true,
        }
    }

    /// Writes the colours of a group of [`LANES`] pixels of row `row` from column
    /// `first_column` on that show two triangles, its first lane's and its last lane's (along
    /// an edge of a large triangle: with another, or with the background), where both sources
    /// give their colours in lanes: each formed for the whole group, then blended by the lanes
    /// that show the first. False (nothing written) for any other group. A group of three or
    /// more triangles (most of a scan's) stays one pixel at a time: forming lane steps for
    /// every narrow triangle cost more than their lanes saved.
    #[inline(always)]
    fn write_two_triangle_group<B: Backend>(
        &self,
        ids: &[u32; LANES],
        first_column: usize,
        row: usize,
        colors: &mut [Vec3; LANES],
    ) -> bool {
        let (first, last) = (ids[0], ids[LANES - 1]);
        if samples_showing(ids, first) | samples_showing(ids, last) != ALL_LANES {
            return false;
        }
        let (Some(first_colors), Some(last_colors)) = (
            self.source_lanes::<B>(first, first_column, row),
            self.source_lanes::<B>(last, first_column, row),
        ) else {
            return false;
        };
        let shows_first = Ints::<B>::new(bytemuck::cast(*ids)).eq(Ints::splat(first as i32));
        shows_first.select3(first_colors, last_colors).write_to(colors);
        true
    }

    /// The colours the source of the tile's triangle `id` gives the group of row `row` from
    /// column `first_column` on, in lanes: a fill's, or a Gouraud plane's where it has lane
    /// steps; `None` for any other source.
    #[inline(always)]
    fn source_lanes<B: Backend>(&self, id: u32, first_column: usize, row: usize) -> Option<Vec3s<B>> {
        match self.sources[self.entry(id)] {
            PixelSource::Fill => Some(Vec3s::splat(self.fills[self.entry(id)])),
            PixelSource::Gouraud(plane) => {
                self.gouraud[usize::from(plane)].group_colors::<B>(first_column as i64, row as i64)
            }
            PixelSource::Phong(_) | PixelSource::Shaded => None,
        }
    }

    /// Writes the colour of the pixel `(column, row)`, which shows the tile's triangle `id`,
    /// where its source is a fill or a Gouraud plane; a shaded pixel already has its colour,
    /// and a small Phong triangle's pixel is the caller's.
    #[inline(always)]
    fn write_pixel(&self, id: u32, column: usize, row: usize, color: &mut Vec3) {
        match self.sources[self.entry(id)] {
            PixelSource::Fill => *color = self.fills[self.entry(id)],
            PixelSource::Gouraud(plane) => {
                *color = self.gouraud[usize::from(plane)].color_at(column as i64, row as i64)
            }
            PixelSource::Phong(_) | PixelSource::Shaded => {}
        }
    }
}

/// [`shade_single_sample`]'s last pass over a tile with small Phong triangles
/// ([`PhongPlane`]s): their pixels are queued in `phong` as the pass meets them, so the frame's
/// colours are written by index (the batch writes them too) instead of through a row slice,
/// which costs the tiles without such triangles (flat and Gouraud ones) about 2 % of their
/// instructions; they take the slice loop.
fn last_pass_with_phong<'f>(
    visibility: &Visibility,
    pass: &LastPass<'_>,
    planes: &[PhongPlane<'f>],
    phong: &mut PhongBatch<'f>,
    color: &mut [Vec3],
) {
    let rect = visibility.rect;
    let tile_width = rect.width() as usize;
    for (row, ids) in visibility.triangle.chunks_exact(tile_width).enumerate() {
        let row_start = row * pass.stride + rect.x0 as usize;
        for (group, ids) in ids.chunks(LANES).enumerate() {
            let first_column = group * LANES;
            let first = row_start + first_column;
            if let Ok(group_ids) = <&[u32; LANES]>::try_from(ids) {
                let colors: &mut [Vec3; LANES] = (&mut color[first..first + LANES])
                    .try_into()
                    .expect("a group of lanes");
                if pass.write_whole_group::<Native>(group_ids, first_column, row, colors) {
                    continue;
                }
            }
            for (column, &id) in (first_column..).zip(ids) {
                let offset = row_start + column;
                match pass.sources[pass.entry(id)] {
                    PixelSource::Phong(plane) => {
                        let plane = &planes[usize::from(plane)];
                        let weights = plane.weights_at(column as i64, row as i64);
                        phong.push(&plane.shader, weights, offset, color);
                    }
                    _ => pass.write_pixel(id, column, row, &mut color[offset]),
                }
            }
        }
    }
}

/// The pixels of `area` (within the tile of `visibility`) that show the tile's triangle `local`,
/// which is `raster`.
struct ShownPixels<'v> {
    visibility: &'v Visibility,
    local: u32,
    raster: &'v RasterTriangle,
    area: PixelRect,
    /// Pixels per row of the band the tile is written into.
    stride: usize,
}

impl ShownPixels<'_> {
    /// Calls `visit(offset, at, edges)` for each, row by row: `offset` in the band, `at` the
    /// pixel centre in 1/256 pixel, `edges` the triangle's edge functions there (stepped
    /// along the row: exact integers, the values `edge_values` gives).
    #[inline]
    fn for_each(&self, mut visit: impl FnMut(usize, (i64, i64), [i64; 3])) {
        let rect = self.visibility.rect;
        let tile_width = rect.width() as usize;
        let (first, last) = (
            (self.area.x0 - rect.x0) as usize,
            (self.area.x1 - rect.x0) as usize,
        );
        let (step, step_down) = (edge_steps_x(self.raster), edge_steps_y(self.raster));
        // Each row's first values one step down from the last row's: the same integers as
        // `edge_values` there, without its products.
        let mut row_start = edge_values(
            self.raster,
            pixel_centre(self.area.x0),
            pixel_centre(self.area.y0),
        );
        for py in self.area.y0..self.area.y1 {
            let row = (py - rect.y0) as usize;
            let ids = &self.visibility.triangle[row * tile_width..][first..last];
            let y = pixel_centre(py);
            let mut edges = row_start;
            for (px, &id) in (self.area.x0..).zip(ids) {
                if id == self.local {
                    visit(row * self.stride + px as usize, (pixel_centre(px), y), edges);
                }
                edges = [edges[0] + step[0], edges[1] + step[1], edges[2] + step[2]];
            }
            row_start = std::array::from_fn(|k| row_start[k] + step_down[k]);
        }
    }
}

impl ShownPixels<'_> {
    /// Calls `visit` for each group of [`LANES`] neighbouring pixels of a row of the area,
    /// from its first column, where at least one shows the triangle (see [`PixelGroup`]).
    #[inline(always)]
    fn for_each_group(&self, mut visit: impl FnMut(PixelGroup<'_>)) {
        let rect = self.visibility.rect;
        let tile_width = rect.width() as usize;
        let (first, last) = (
            (self.area.x0 - rect.x0) as usize,
            (self.area.x1 - rect.x0) as usize,
        );
        let (step, step_down) = (edge_steps_x(self.raster), edge_steps_y(self.raster));
        let lane_steps = LaneSteps::over(self.raster, self.area);
        let local = Ints::splat(self.local as i32);
        let mut row_start = edge_values(
            self.raster,
            pixel_centre(self.area.x0),
            pixel_centre(self.area.y0),
        );
        for py in self.area.y0..self.area.y1 {
            let row = (py - rect.y0) as usize;
            let ids = &self.visibility.triangle[row * tile_width..][first..last];
            let mut start = row_start;
            row_start = std::array::from_fn(|k| row_start[k] + step_down[k]);
            // Whole groups compared in lanes; the row's last, shorter group lane by lane.
            let (whole_groups, rest) = ids.as_chunks::<LANES>();
            let groups = whole_groups
                .iter()
                .map(|ids| Ints::new(bytemuck::cast(*ids)).eq(local))
                .chain((!rest.is_empty()).then(|| {
                    Mask::from_bools(std::array::from_fn(|lane| rest.get(lane) == Some(&self.local)))
                }));
            for (group, shown) in groups.enumerate() {
                if shown.any() {
                    visit(PixelGroup {
                        first: row * self.stride + self.area.x0 as usize + group * LANES,
                        shown,
                        start,
                        step,
                        lane_steps: lane_steps.as_ref(),
                    });
                }
                start = std::array::from_fn(|k| start[k] + step[k] * LANES as i64);
            }
        }
    }
}

/// Fills a group of pixels (at most [`LANES`]) with one colour: a whole group in wide stores
/// ([`fill_vec3s`]).
#[inline(always)]
fn fill_group(colors: &mut [Vec3], value: Vec3) {
    match <&mut [Vec3; LANES]>::try_from(&mut *colors) {
        Ok(group) => fill_vec3s(group, value),
        Err(_) => colors.fill(value),
    }
}

/// Per edge, each lane's step from the first pixel of a group of a row, `step_x·lane`, in
/// `f64` lanes: for a triangle whose edge functions over an area (and a group past its last
/// column) stay below 2⁵³, so that a group's values are summed exactly in `f64` and rounded
/// once to `f32`, as converting the same `i64` rounds.
struct LaneSteps([Wides; 3]);

impl LaneSteps {
    /// `None` where the edge functions of `raster` over `area` outgrow `f64`'s exact integers
    /// (a triangle reaching far off the tile).
    #[inline]
    fn over(raster: &RasterTriangle, area: PixelRect) -> Option<Self> {
        LaneSteps::exact_over(raster, area).then(|| LaneSteps::of(edge_steps_x(raster)))
    }

    /// Whether the edge functions of `raster` over `area` (and a group past its last column)
    /// are whole numbers of at most 2⁵³.
    #[inline]
    fn exact_over(raster: &RasterTriangle, area: PixelRect) -> bool {
        let origin = edge_values(raster, pixel_centre(area.x0), pixel_centre(area.y0));
        let (step_x, step_y) = (edge_steps_x(raster), edge_steps_y(raster));
        let (columns, rows) = (u64::from(area.width()) + LANES as u64, u64::from(area.height()));
        (0..3).all(|k| {
            origin[k].unsigned_abs() + columns * step_x[k].unsigned_abs() + rows * step_y[k].unsigned_abs()
                <= 1 << 53
        })
    }

    /// The lanes' steps of edges stepping `step_x` a pixel, for a triangle that is
    /// [`LaneSteps::exact_over`] the area (so each product is a whole number below 2⁵³, exact).
    #[inline(always)]
    fn of(step_x: [i64; 3]) -> Self {
        LaneSteps(step_x.map(|step| Wides::new(std::array::from_fn(|lane| step as f64 * lane as f64))))
    }

    /// The edge functions at a group's pixels, the first pixel's values `start`, in `f32`.
    #[inline(always)]
    fn edges<B: Backend>(&self, start: [i64; 3]) -> [Floats<B>; 3] {
        std::array::from_fn(|k| (Wides::splat(start[k] as f64) + self.0[k].on::<B>()).to_floats())
    }
}

/// [`LANES`] neighbouring pixels of a row, some of which show a triangle.
struct PixelGroup<'s> {
    /// The first pixel's offset in the band.
    first: usize,
    /// Which lanes show the triangle (none past the area).
    shown: Mask,
    /// The triangle's edge functions at the first pixel's centre, and their step to the next
    /// pixel of the row.
    start: [i64; 3],
    step: [i64; 3],
    /// The steps in lanes, where the triangle's values over the area take them exactly.
    lane_steps: Option<&'s LaneSteps>,
}

impl PixelGroup<'_> {
    /// The edge functions at `lane`'s pixel centre: exact integers, the values `edge_values`
    /// gives.
    #[inline]
    fn edges_at(&self, lane: usize) -> [i64; 3] {
        std::array::from_fn(|k| self.start[k] + self.step[k] * lane as i64)
    }

    /// The edge functions at every lane's pixel centre, each exact in `i64` and then rounded
    /// once to `f32`.
    #[inline(always)]
    fn edges(&self) -> [Floats; 3] {
        match self.lane_steps {
            Some(lane_steps) => lane_steps.edges(self.start),
            None => std::array::from_fn(|k| {
                Floats::new(std::array::from_fn(|lane| self.edges_at(lane)[k] as f32))
            }),
        }
    }
}

/// Pixels of one triangle gathered from the groups that show it in some lanes only, to be
/// shaded [`LANES`] at a time through its [`PhongRows`], which shades each lane on its own.
#[derive(Default)]
struct GatheredPixels {
    len: usize,
    /// Where each pixel's colour goes in the band.
    offsets: [usize; LANES],
    /// Per edge, the triangle's edge function at each pixel's centre (exact).
    edges: [[i64; LANES]; 3],
}

impl GatheredPixels {
    /// Adds the pixel at `offset` whose edge functions are `edges`; whether the lanes are now
    /// full (to be shaded, then emptied by setting `len` to 0).
    #[inline(always)]
    fn push(&mut self, offset: usize, edges: [i64; 3]) -> bool {
        self.offsets[self.len] = offset;
        for (k, &edge) in edges.iter().enumerate() {
            self.edges[k][self.len] = edge;
        }
        self.len += 1;
        self.len == LANES
    }

    /// The full lanes' edge functions, each rounded once to `f32` (as [`PixelGroup::edges`]).
    #[inline(always)]
    fn edges(&self) -> [Floats; 3] {
        self.edges.map(|edge| Floats::new(edge.map(|value| value as f32)))
    }
}

/// The points a triangle's pixels are shaded at, for [`shade_varying`]: each with where its
/// colour goes and the triangle's edge functions there.
trait TrianglePoints {
    fn visit(&self, visit: impl FnMut(usize, [i64; 3]));
}

impl TrianglePoints for ShownPixels<'_> {
    #[inline]
    fn visit(&self, mut visit: impl FnMut(usize, [i64; 3])) {
        self.for_each(|offset, _, edges| visit(offset, edges));
    }
}

/// A multisampled tile's points of one triangle (`indices` into `points`), each colour going
/// to its index.
struct SampledPoints<'p> {
    raster: &'p RasterTriangle,
    indices: &'p [u32],
    points: &'p [ShadingPoint],
}

impl TrianglePoints for SampledPoints<'_> {
    #[inline]
    fn visit(&self, mut visit: impl FnMut(usize, [i64; 3])) {
        for &index in self.indices {
            let (x, y) = self.points[index as usize].at;
            visit(index as usize, edge_values(self.raster, x, y));
        }
    }
}

/// Shades the `points` of a triangle whose surface varies (textures, vertex colours), each
/// with where it lies in the triangle: Phong pixels into `surface`, flat and Gouraud ones into
/// `modulated`. Apart from the loops over the tile's triangles, which the common case keeps
/// small.
#[inline(never)]
#[allow(clippy::too_many_arguments)]
fn shade_varying<'f>(
    frame: &Frame,
    raster: &RasterTriangle,
    corners: &Corners,
    shader: VaryingShader<'f>,
    points: impl TrianglePoints,
    surface: &mut SurfaceBatch<'f>,
    modulated: &mut ModulatedBatch<'f>,
    color: &mut [Vec3],
) {
    let plane = RasterPlane {
        steps: [edge_steps_x(raster), edge_steps_y(raster)],
        inv_area: raster.inv_area,
        inv_w: raster.inv_w,
        corners: *corners,
    };
    match shader {
        VaryingShader::Phong(fast) => {
            surface.begin(&fast, plane, color);
            points.visit(|offset, edges| surface.push(edges, offset, color));
        }
        VaryingShader::Flat(modulation, colors) => {
            modulated.begin(frame, modulation, plane, color);
            points.visit(|offset, edges| modulated.push(frame, colors, edges, offset, color));
        }
        VaryingShader::Gouraud(modulation, colors) => {
            modulated.begin(frame, modulation, plane, color);
            let colors = SplitGouraudColors::new(raster, corners, colors);
            points.visit(|offset, edges| modulated.push(frame, colors.at(edges), edges, offset, color));
        }
    }
}

/// The centre of pixel row or column `p`, in 1/256 pixel.
#[inline]
pub(crate) fn pixel_centre(p: u32) -> i64 {
    i64::from(p) * SUBPIXEL_ONE + SUBPIXEL_ONE / 2
}

/// How the pixels of one triangle are shaded, decided once per triangle and tile. Each case
/// computes exactly what [`shade_sample`] would, in the same order.
enum TriangleShader<'f> {
    /// One colour for the whole triangle: flat or constant shading without a colour texture
    /// lit outside the lanes, and the normals view of flat and constant triangles.
    Solid(Vec3),
    /// Flat shading in lanes: the triangle waits in the tile's [`FlatBatch`] at this index, and
    /// its pixels are written when the batch is lit.
    FlatWaiting(u16),
    /// Flat shading with a colour texture, the triangle's colours lit in lanes: it waits in the
    /// tile's [`FlatBatch`] at this index, and its pixels are shaded as
    /// [`VaryingShader::Flat`] once the batch is lit.
    ModulatedFlatWaiting(Modulation<'f>, u16),
    /// Gouraud shading without a colour texture: the three vertex colours, interpolated.
    Gouraud([Vec3; 3]),
    /// Pixel by pixel in lanes (see [`FastPhong`]): Phong shading of a surface that does not
    /// vary, and the depth and normals views of every mode whose pixels vary.
    Phong(FastPhong<'f>),
    /// A surface that textures or vertex colours vary pixel by pixel, in lanes.
    Varying(VaryingShader<'f>),
    /// `shade_sample` per pixel: what is left where [`FastPhong::new`] declines a triangle.
    /// Every lit Phong triangle takes the lanes now, so no scene's pixel comes here (the
    /// triangle-shader test asserts it); kept as the safe fallback of that match.
    General,
}

/// How the pixels of a triangle whose surface varies are shaded: lane by lane, each pixel with
/// its footprint ([`shade_varying`]).
enum VaryingShader<'f> {
    /// Phong shading (see [`FastPhong`]), the surface stage first.
    Phong(FastPhong<'f>),
    /// Flat shading with a colour texture: the triangle's colour as (the part the texture
    /// multiplies, the rest), the texture applied per pixel.
    Flat(Modulation<'f>, (Vec3, Vec3)),
    /// Gouraud shading with a colour texture: each vertex's colour as (the part the texture
    /// multiplies, the rest), both interpolated, the texture applied per pixel.
    Gouraud(Modulation<'f>, [(Vec3, Vec3); 3]),
}

impl<'f> TriangleShader<'f> {
    /// Whether [`TriangleShader::new`] gives `raster` one colour for all its pixels (`Solid` or
    /// `FlatWaiting`), decided without lighting it: the same match on the debug view, the
    /// shading mode and the colour texture. Multisampled tiles resolve the pixels such a
    /// triangle covers at every sample straight from that colour.
    #[inline]
    fn is_one_colour(frame: &Frame, raster: &RasterTriangle) -> bool {
        let triangle = &raster.triangle;
        let shading = frame.objects[triangle.object as usize].shading;
        match (frame.debug_view, shading) {
            (Some(DebugView::Depth), _) | (Some(DebugView::Normals), Shading::Gouraud | Shading::Phong) => {
                false
            }
            (Some(DebugView::Normals), Shading::Flat | Shading::Constant) => true,
            (_, Shading::Constant) => true,
            (_, Shading::Flat) => !has_color_texture(&frame.materials[triangle.material as usize]),
            (_, Shading::Gouraud | Shading::Phong) => false,
        }
    }

    fn new(
        frame: &'f Frame,
        raster: &'f RasterTriangle,
        caches: &mut TileCaches,
        flat: &mut FlatBatch<'f>,
        lightings: &mut LightingMemo<'f>,
    ) -> Self {
        let triangle = &raster.triangle;
        let style = &frame.objects[triangle.object as usize];
        let material = &frame.materials[triangle.material as usize];
        let mut per_pixel = || match FastPhong::new(frame, triangle, raster.back_facing, lightings) {
            Some(fast) if fast.varies() => TriangleShader::Varying(VaryingShader::Phong(fast)),
            Some(fast) => TriangleShader::Phong(fast),
            None => TriangleShader::General,
        };
        match (frame.debug_view, style.shading) {
            (Some(DebugView::Depth), _) | (Some(DebugView::Normals), Shading::Gouraud | Shading::Phong) => {
                return per_pixel();
            }
            (Some(DebugView::Normals), Shading::Flat | Shading::Constant) => {
                let normal = style.side_normal(frame.face_normal(triangle), raster.back_facing);
                return TriangleShader::Solid(normal * 0.5 + 0.5);
            }
            _ => {}
        }
        let plain = !has_color_texture(material);
        let modulation = || Modulation {
            vertices: triangle.vertices,
            texture: material.textures.diffuse.as_ref(),
        };
        match style.shading {
            // Textures and debug views of terms do not reach constant colours.
            Shading::Constant => TriangleShader::Solid(frame.constant_colors[triangle.material as usize]),
            Shading::Flat if plain => {
                if let Some(index) = caches.flat_waiting.get(raster.source) {
                    return TriangleShader::FlatWaiting(index);
                }
                let back_facing = raster.back_facing;
                if let Some(lighting) = lightings.get(frame, triangle, Shading::Flat, back_facing) {
                    let index = flat.add(lighting, raster.triangle, back_facing);
                    caches.flat_waiting.insert(raster.source, index);
                    return TriangleShader::FlatWaiting(index);
                }
                let (_, rest) = caches
                    .flat
                    .get_or_insert_with(raster.source, || frame.flat_colors(triangle, back_facing));
                TriangleShader::Solid(rest)
            }
            // With a colour texture: lit in the tile's batch too, where the fast path lights it.
            Shading::Flat => {
                let back_facing = raster.back_facing;
                let waiting = caches.flat_waiting.get(raster.source).or_else(|| {
                    let lighting = lightings.get(frame, triangle, Shading::Flat, back_facing)?;
                    let index = flat.add(lighting, raster.triangle, back_facing);
                    caches.flat_waiting.insert(raster.source, index);
                    Some(index)
                });
                if let Some(index) = waiting {
                    return TriangleShader::ModulatedFlatWaiting(modulation(), index);
                }
                let colors = caches
                    .flat
                    .get_or_insert_with(raster.source, || frame.flat_colors(triangle, raster.back_facing));
                TriangleShader::Varying(VaryingShader::Flat(modulation(), colors))
            }
            Shading::Gouraud if plain && raster.back_facing => {
                let colors = caches.back.get_or_insert_with(raster.source, || {
                    back_gouraud_colors(frame, triangle, material, style)
                });
                TriangleShader::Gouraud(colors.map(|(_, rest)| rest))
            }
            Shading::Gouraud if plain => TriangleShader::Gouraud(triangle.vertices.map(|v| frame.color(v))),
            Shading::Gouraud => {
                let colors = if raster.back_facing {
                    caches.back.get_or_insert_with(raster.source, || {
                        back_gouraud_colors(frame, triangle, material, style)
                    })
                } else {
                    triangle.vertices.map(|v| {
                        let colors = frame.colors(v);
                        (colors.color_textured, colors.color)
                    })
                };
                TriangleShader::Varying(VaryingShader::Gouraud(modulation(), colors))
            }
            Shading::Phong => per_pixel(),
        }
    }
}

/// What multiplies the textured part of a flat or Gouraud pixel of a triangle with a colour
/// texture: the diffuse texture through the triangle's texture coordinates, or nothing (white)
/// when its only colour texture is an ambient one (flat and Gouraud pixels take no other).
#[derive(Clone, Copy)]
struct Modulation<'f> {
    vertices: [u32; 3],
    texture: Option<&'f TextureBinding>,
}

/// Pixels of flat and Gouraud triangles with a colour texture, waiting to be modulated
/// [`LANES`] at a time: each pixel's colour is `rest + textured·texel`, the texel of the
/// batch's texture at the pixel (`surface_lanes::texture_colors`). The pixels of one batch
/// share the texture binding; the pixels of a triangle come after
/// [`ModulatedBatch::begin`] names it.
#[derive(Default)]
struct ModulatedBatch<'f> {
    texture: Option<&'f TextureBinding>,
    /// Whether the current triangle's pixels wait for a texture (else nothing modulates them
    /// and they are written at once).
    modulating: bool,
    /// The waiting pixels; per triangle its raster plane and vertices.
    pixels: EdgeQueue<(RasterPlane, [u32; 3])>,
    /// Each waiting pixel's colour as (the part the texture multiplies, the rest), by lane.
    colors: [(Vec3, Vec3); LANES],
}

impl<'f> ModulatedBatch<'f> {
    /// Names the triangle the next pixels are of: its `modulation`, its raster triangle
    /// `plane` (flushing the waiting pixels into `color` first if it samples another texture).
    #[inline]
    fn begin(&mut self, frame: &Frame, modulation: Modulation<'f>, plane: RasterPlane, color: &mut [Vec3]) {
        if let (Some(waiting), Some(texture)) = (self.texture, modulation.texture)
            && !std::ptr::eq(waiting, texture)
        {
            self.flush(frame, color);
        }
        if modulation.texture.is_some() {
            self.texture = modulation.texture;
        }
        self.modulating = modulation.texture.is_some();
        self.pixels.begin((plane, modulation.vertices));
    }

    /// The pixel of the current triangle whose colour is `colors` (textured part, rest), where
    /// its edge functions take the values `edges`: its colour goes to `color[offset]`, at once
    /// when nothing modulates it, else when the batch is lit (full, another texture coming,
    /// or [`ModulatedBatch::flush`]).
    #[inline]
    fn push(
        &mut self,
        frame: &Frame,
        (textured, rest): (Vec3, Vec3),
        edges: [i64; 3],
        offset: usize,
        color: &mut [Vec3],
    ) {
        if !self.modulating {
            color[offset] = rest + textured * Vec3::ONE;
            return;
        }
        let lane = self.pixels.push(edges, offset);
        self.colors[lane] = (textured, rest);
        if self.pixels.is_full() {
            self.flush(frame, color);
        }
    }

    /// Modulates the waiting pixels into `color` and empties the batch.
    fn flush(&mut self, frame: &Frame, color: &mut [Vec3]) {
        let Some(texture) = self.texture else {
            return;
        };
        if self.pixels.is_empty() {
            return;
        }
        let QueuedPixels {
            offsets,
            edges,
            triangles,
        } = self.pixels.take();
        run_widest(ModulatedLanes {
            frame,
            texture,
            offsets,
            edges,
            triangles,
            colors: &self.colors,
            color,
        });
    }
}

/// A [`ModulatedBatch`]'s waiting pixels modulated into `color`, as lane work: the pixels'
/// weights, their texels and the products, about two thousand operations a batch.
struct ModulatedLanes<'q, 'c> {
    frame: &'q Frame,
    texture: &'q TextureBinding,
    offsets: &'q [usize],
    edges: &'q [[i64; 3]; LANES],
    triangles: [&'q (RasterPlane, [u32; 3]); LANES],
    colors: &'q [(Vec3, Vec3); LANES],
    color: &'c mut [Vec3],
}

impl LaneWork for ModulatedLanes<'_, '_> {
    type Output = ();

    #[inline(always)]
    fn run<B: Backend>(self) {
        let planes = self.triangles.map(|(plane, _)| plane);
        let vertices = self.triangles.map(|(_, vertices)| *vertices);
        let points = SurfacePoints::<B> {
            vertices: &vertices,
            weights: &WeightLanes::of(self.edges, &planes),
        };
        // `rest + textured·texel` in lanes (each lane the `Vec3` operations' bits), each lane
        // then stored as a `Vec3`. Taking the texels apart as an array of `Vec3`s instead let
        // the compiler read them with 16-byte loads straddling the sampler's stores, which
        // cannot be forwarded: a sixth of a textured flat frame's time.
        let texels = texture_colors(self.frame, self.texture, &points);
        let part = |pick: fn(&(Vec3, Vec3)) -> Vec3| {
            Vec3s::<B>::from_array(&std::array::from_fn(|lane| pick(&self.colors[lane])))
        };
        let (textured, rest) = (part(|colors| colors.0), part(|colors| colors.1));
        let shaded = rest + textured * texels;
        for (lane, &offset) in self.offsets.iter().enumerate() {
            self.color[offset] = shaded.lane(lane);
        }
    }
}

/// The Gouraud colours of a triangle's back side, lit per vertex (on demand: most back faces
/// are never seen). Per vertex: (the part a colour texture multiplies, the rest).
fn back_gouraud_colors(
    frame: &Frame,
    triangle: &FrameTriangle,
    material: &Material,
    style: &ObjectStyle,
) -> [(Vec3, Vec3); 3] {
    triangle.vertices.map(|v| {
        let vertex = &frame.vertices[v as usize];
        let vertex_material = tinted(material, frame.attributes(v).tint);
        let (textured_part, rest) =
            frame.light_material(&vertex_material, style, vertex.position, vertex.normal, true);
        if has_color_texture(&vertex_material) {
            (textured_part, rest)
        } else {
            (Vec3::ZERO, textured_part + rest)
        }
    })
}

/// Perspective-correct barycentric weights of the source triangle's vertices at the fixed-point
/// point `at` (1/256 pixel); `corners` are the triangle's corner weights
/// (`Frame::corner_weights`).
pub fn source_weights(triangle: &RasterTriangle, corners: &Corners, at: (i64, i64)) -> Vec3 {
    weights_from_edges(triangle, corners, edge_values(triangle, at.0, at.1))
}

/// [`source_weights`] at a point where the edge functions take the values `edges`.
#[inline]
fn weights_from_edges(triangle: &RasterTriangle, corners: &Corners, edges: [i64; 3]) -> Vec3 {
    corners.apply(perspective_weights(triangle.inv_area, triangle.inv_w, edges))
}

/// The perspective-correct weights of a raster triangle's corners where its edge functions
/// take the values `edges` (`inv_area` and `inv_w` are the triangle's).
#[inline]
fn perspective_weights(inv_area: f32, inv_w: [f32; 3], edges: [i64; 3]) -> Vec3 {
    let [e0, e1, e2] = edges;
    let screen = Vec3::new(e0 as f32, e1 as f32, e2 as f32) * inv_area;
    let [w0, w1, w2] = inv_w;
    let over_w = screen * Vec3::new(w0, w1, w2);
    let sum = over_w.element_sum();
    if sum > 0.0 { over_w / sum } else { screen }
}

fn shade_sample(
    frame: &Frame,
    raster: &RasterTriangle,
    corners: &Corners,
    at: (i64, i64),
    caches: &mut TileCaches,
) -> Vec3 {
    let weights = source_weights(raster, corners, at);
    let triangle = &raster.triangle;
    let style = &frame.objects[triangle.object as usize];
    let [a, b, c] = triangle.vertices.map(|v| &frame.vertices[v as usize]);
    let interpolate = |x: Vec3, y: Vec3, z: Vec3| x * weights.x + y * weights.y + z * weights.z;
    let back = raster.back_facing;
    let position = interpolate(a.position, b.position, c.position);
    let smooth_normal = || {
        let interpolated = match style.normal_interpolation {
            NormalInterpolation::Nlerp => interpolate(a.normal, b.normal, c.normal),
            NormalInterpolation::Slerp => slerp_triangle([a.normal, b.normal, c.normal], weights),
        };
        renormalize_or_else(interpolated, || frame.face_normal(triangle))
    };

    match frame.debug_view {
        Some(DebugView::Depth) => return Vec3::splat(position.dot(frame.forward)),
        Some(DebugView::Normals) => {
            let normal = match style.shading {
                Shading::Flat | Shading::Constant => frame.face_normal(triangle),
                Shading::Gouraud | Shading::Phong => smooth_normal(),
            };
            return style.side_normal(normal, back) * 0.5 + 0.5;
        }
        _ => {}
    }

    let material = &frame.materials[triangle.material as usize];
    let color_texture = material.textures.diffuse;
    let textured =
        color_texture.is_some() || material.textures.ambient.is_some() || material.textures.normal.is_some();
    // Texture footprints: the source weights one pixel to the right and one down (the plane
    // equation extends past the triangle's edges, so this is valid at its border too).
    let (weights_dx, weights_dy) = if textured {
        (
            source_weights(raster, corners, (at.0 + SUBPIXEL_ONE, at.1)),
            source_weights(raster, corners, (at.0, at.1 + SUBPIXEL_ONE)),
        )
    } else {
        (weights, weights)
    };
    let attributes = || triangle.vertices.map(|v| frame.attributes(v));
    let sample = |binding: &TextureBinding| -> Vec4 {
        let [a, b, c] = attributes();
        let uv_of = |v: &VertexAttributes| if binding.uv_set == 1 { v.uv1 } else { v.uv };
        let uv_at = |w: Vec3| uv_of(&a) * w.x + uv_of(&b) * w.y + uv_of(&c) * w.z;
        let uv = uv_at(weights);
        frame.textures[binding.texture as usize].sample_biased(
            uv,
            uv_at(weights_dx) - uv,
            uv_at(weights_dy) - uv,
            &binding.sampler,
            frame.mip_bias,
        )
    };
    let modulation = || color_texture.map_or(Vec3::ONE, |binding| sample(&binding).truncate());

    match style.shading {
        Shading::Constant => frame.constant_colors[triangle.material as usize],
        Shading::Flat => {
            let (textured_part, rest) = caches
                .flat
                .get_or_insert_with(raster.source, || frame.flat_colors(triangle, back));
            if has_color_texture(material) {
                rest + textured_part * modulation()
            } else {
                rest
            }
        }
        Shading::Gouraud => {
            let colors = if back {
                caches.back.get_or_insert_with(raster.source, || {
                    triangle.vertices.map(|v| {
                        let vertex = &frame.vertices[v as usize];
                        let vertex_material = tinted(material, frame.attributes(v).tint);
                        let (textured_part, rest) = frame.light_material(
                            &vertex_material,
                            style,
                            vertex.position,
                            vertex.normal,
                            true,
                        );
                        if has_color_texture(&vertex_material) {
                            (textured_part, rest)
                        } else {
                            (Vec3::ZERO, textured_part + rest)
                        }
                    })
                })
            } else {
                triangle.vertices.map(|v| {
                    let colors = frame.colors(v);
                    (colors.color_textured, colors.color)
                })
            };
            let edges = edge_values(raster, at.0, at.1);
            let interpolate_colors =
                |colors: [Vec3; 3]| GouraudColors::new(raster, corners, colors).at(edges);
            let rest = interpolate_colors(colors.map(|(_, rest)| rest));
            if color_texture.is_some() || material.textures.ambient.is_some() {
                rest + interpolate_colors(colors.map(|(textured_part, _)| textured_part)) * modulation()
            } else {
                rest
            }
        }
        Shading::Phong => {
            let surface = phong_surface(frame, raster, weights, (weights_dx, weights_dy));
            let (textured_part, rest) =
                frame.light_material(&surface.material, style, position, surface.normal, back);
            textured_part + rest
        }
    }
}

/// What a Phong-shaded point is lit with, once textures, vertex colours and the normal map
/// have done their work.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PhongSurface {
    /// The material with `k_a` and `k_d` multiplied by the colour textures and the vertex
    /// colour.
    pub material: Material,
    /// The interpolated normal (Nlerp or Slerp, renormalised; the face normal where it
    /// vanishes), normal-mapped, of the front side.
    pub normal: Vec3,
    /// The texture coordinates and filtered value of each texture read: diffuse, ambient,
    /// normal map.
    pub texels: [Option<TexelRead>; 3],
}

/// One texture lookup of a point: where, with what footprint, and what it gave.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TexelRead {
    pub binding: TextureBinding,
    pub uv: Vec2,
    /// How far `uv` moves one pixel right and one pixel down.
    pub uv_dx: Vec2,
    pub uv_dy: Vec2,
    pub value: Vec4,
}

/// The surface [`shade_sample`] lights at a Phong point with the source weights `weights`
/// (and `footprint`, the weights one pixel right and one pixel down, read only when a texture
/// is). The pixel inspector reads the same surface.
pub fn phong_surface(
    frame: &Frame,
    raster: &RasterTriangle,
    weights: Vec3,
    footprint: (Vec3, Vec3),
) -> PhongSurface {
    let triangle = &raster.triangle;
    let style = &frame.objects[triangle.object as usize];
    let material = &frame.materials[triangle.material as usize];
    let [a, b, c] = triangle.vertices.map(|v| &frame.vertices[v as usize]);
    let interpolate = |x: Vec3, y: Vec3, z: Vec3| x * weights.x + y * weights.y + z * weights.z;
    let attributes = || triangle.vertices.map(|v| frame.attributes(v));
    let read = |binding: TextureBinding| -> TexelRead {
        let [a, b, c] = attributes();
        let uv_of = |v: &VertexAttributes| if binding.uv_set == 1 { v.uv1 } else { v.uv };
        let uv_at = |w: Vec3| uv_of(&a) * w.x + uv_of(&b) * w.y + uv_of(&c) * w.z;
        let uv = uv_at(weights);
        let (uv_dx, uv_dy) = (uv_at(footprint.0) - uv, uv_at(footprint.1) - uv);
        TexelRead {
            binding,
            uv,
            uv_dx,
            uv_dy,
            value: frame.textures[binding.texture as usize].sample(uv, uv_dx, uv_dy, &binding.sampler),
        }
    };
    let mut surface = if frame.vertex_attributes.is_empty() {
        *material
    } else {
        let [ta, tb, tc] = attributes();
        tinted(material, interpolate(ta.tint, tb.tint, tc.tint))
    };
    let mut texels = [None; 3];
    if let Some(binding) = material.textures.diffuse {
        let texel = read(binding);
        surface.diffuse *= texel.value.truncate();
        if material.textures.ambient.is_none() {
            surface.ambient *= texel.value.truncate();
        }
        texels[0] = Some(texel);
    }
    if let Some(binding) = material.textures.ambient {
        let texel = read(binding);
        surface.ambient *= texel.value.truncate();
        texels[1] = Some(texel);
    }
    let interpolated = match style.normal_interpolation {
        NormalInterpolation::Nlerp => interpolate(a.normal, b.normal, c.normal),
        NormalInterpolation::Slerp => slerp_triangle([a.normal, b.normal, c.normal], weights),
    };
    let mut normal = renormalize_or_else(interpolated, || frame.face_normal(triangle));
    if let Some(binding) = material.textures.normal {
        let [ta, tb, tc] = attributes();
        let tangent = ta.tangent * weights.x + tb.tangent * weights.y + tc.tangent * weights.z;
        let texel = read(binding);
        normal = perturb_normal(normal, tangent, texel.value.truncate(), binding.scale);
        texels[2] = Some(texel);
    }
    PhongSurface {
        material: surface,
        normal,
        texels,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::raster::{SamplePattern, rasterize_tile};
    use crate::render::{DebugView, shade_fast};

    /// The fast path's two-sphere scene, shaded `shading`, `size` pixels, on a coloured
    /// background, with the near plane cutting the spheres open so that back faces are seen too.
    fn cut_open_scene(
        model: LightingModel,
        back_faces: BackFaces,
        lights: shade_fast::tests::Lights,
        shading: [Shading; 2],
        (width, height): (u32, u32),
    ) -> crate::scene::Scene {
        let mut scene = shade_fast::tests::scene(model, Vec3::splat(0.5), back_faces, lights);
        scene.objects[0].shading = shading[0];
        scene.objects[1].shading = shading[1];
        scene.image.width = width;
        scene.image.height = height;
        scene.image.background = Vec3::new(0.25, 0.5, 0.75);
        scene.camera.projection = crate::scene::Projection::Perspective {
            fov_y_degrees: 40.0,
            near: 4.9,
            far: 100.0,
        };
        scene
    }
    use crate::scene::{BackFaces, LightingModel};
    use shade_fast::tests::Surfaces;

    /// One point, for shading a single pixel through [`shade_varying`].
    struct OnePoint {
        edges: [i64; 3],
    }

    impl TrianglePoints for OnePoint {
        fn visit(&self, mut visit: impl FnMut(usize, [i64; 3])) {
            visit(0, self.edges);
        }
    }

    /// The colour [`shade_varying`] gives the one point of `raster` at `at`, through batches of
    /// one.
    fn shade_one_varying<'f>(
        frame: &'f Frame,
        raster: &RasterTriangle,
        corners: &Corners,
        shader: VaryingShader<'f>,
        at: (i64, i64),
    ) -> Vec3 {
        let mut color = [Vec3::NAN];
        let (mut surface, mut modulated) = (SurfaceBatch::default(), ModulatedBatch::default());
        let point = OnePoint {
            edges: edge_values(raster, at.0, at.1),
        };
        shade_varying(
            frame,
            raster,
            corners,
            shader,
            point,
            &mut surface,
            &mut modulated,
            &mut color,
        );
        surface.flush(&mut color);
        modulated.flush(frame, &mut color);
        color[0]
    }

    /// The surfaces the tests shade: the fast path's plain materials, and those varied by
    /// vertex colours, textures and normal maps.
    const SURFACES: [Option<Surfaces>; 4] = [
        None,
        Some(Surfaces::Tinted),
        Some(Surfaces::Textured),
        Some(Surfaces::AmbientOrNormalOnly),
    ];

    /// Every visible pixel, shaded by the per-triangle shaders and by the general
    /// `shade_sample`: the same bits, for each shading mode, back-face mode and light set, with
    /// every lighting model, and with every component, interpolation and debug view (see
    /// `shade_fast::tests::LOOKS`), on plain surfaces and on surfaces that vertex colours,
    /// textures and normal maps vary. No pixel is left to the general path.
    #[test]
    fn triangle_shaders_equal_the_general_path_bit_for_bit() {
        use shade_fast::tests::{LIGHTS, LOOKS, Look, MODELS, PLAIN};
        let modes = [Shading::Constant, Shading::Flat, Shading::Gouraud, Shading::Phong];
        // Plain surfaces: every model and look. Varying ones: the looks and models whose
        // surfaces are handled apart (Slerp, one-colour lighting, Cook-Torrance, views).
        let varied_lightings = [
            ((LightingModel::BlinnPhong, Vec3::splat(0.5)), LOOKS[0]),
            ((LightingModel::BlinnPhong, Vec3::splat(0.5)), LOOKS[1]),
            ((LightingModel::BlinnPhong, Vec3::splat(0.5)), LOOKS[2]),
            ((LightingModel::BlinnPhong, Vec3::splat(0.5)), LOOKS[6]),
            ((LightingModel::BlinnPhong, Vec3::splat(0.5)), LOOKS[7]),
            (MODELS[5], PLAIN),
            (MODELS[6], PLAIN),
        ];
        let lightings = LOOKS
            .map(|look| ((LightingModel::BlinnPhong, Vec3::splat(0.5)), look))
            .into_iter()
            .chain(MODELS.map(|model| (model, PLAIN)))
            .map(|lighting| (lighting, None))
            .chain(
                SURFACES[1..]
                    .iter()
                    .flat_map(|&surfaces| varied_lightings.map(|lighting| (lighting, surfaces))),
            );
        let cases = lightings.flat_map(|lighting| modes.map(|mode| (lighting, mode)));
        let mut gouraud_in_lanes = 0;
        for ((((model, specular), look), surfaces), shading) in cases {
            let back_face_modes = [
                BackFaces::ReverseLit,
                BackFaces::Lit,
                BackFaces::Unlit,
                BackFaces::Cull,
            ];
            for (lights, back_faces) in LIGHTS.into_iter().flat_map(|l| back_face_modes.map(|b| (l, b))) {
                let mut scene = shade_fast::tests::scene(model, specular, back_faces, lights);
                if let Some(surfaces) = surfaces {
                    shade_fast::tests::vary_surfaces(&mut scene, surfaces);
                }
                scene.override_shading(shading);
                Look::apply(look, &mut scene);
                // Cut the spheres open so that back faces are seen too.
                scene.camera.projection = crate::scene::Projection::Perspective {
                    fov_y_degrees: 40.0,
                    near: 4.9,
                    far: 100.0,
                };
                let view = look.view;
                let frame = shade_fast::tests::frame_of(&scene, view);
                let new_caches = || TileCaches {
                    flat: TriangleColorCache::new(),
                    back: TriangleColorCache::new(),
                    flat_waiting: TriangleColorCache::new(),
                };
                let (mut run_caches, mut general_caches) = (new_caches(), new_caches());
                let mut flat = FlatBatch::default();
                let mut lightings = LightingMemo::default();
                let (mut flat_lit, mut varying, mut general_left, mut in_rows) = (0, 0, 0, 0);
                let (mut shaded, mut back_seen) = (0, 0);
                for tile in 0..frame.tiles.count() {
                    let rect = frame.tiles.rect(tile);
                    let visibility = rasterize_tile(rect, SamplePattern::SINGLE, &frame.raster, tile);
                    // Flat triangles wait per tile, as `shade_tile` has them.
                    flat.clear();
                    run_caches.flat_waiting = TriangleColorCache::new();
                    for (slot, &id) in visibility.triangle.iter().enumerate() {
                        if id == NO_TRIANGLE {
                            continue;
                        }
                        let px = i64::from(rect.x0 + slot as u32 % rect.width());
                        let py = i64::from(rect.y0 + slot as u32 / rect.width());
                        let at = (
                            px * SUBPIXEL_ONE + SUBPIXEL_ONE / 2,
                            py * SUBPIXEL_ONE + SUBPIXEL_ONE / 2,
                        );
                        let id = visibility.raster_id(id);
                        let raster = frame.raster_triangle(id);
                        let corners = frame.corner_weights(id);
                        let general = shade_sample(&frame, raster, &corners, at, &mut general_caches);
                        let run = match TriangleShader::new(
                            &frame,
                            raster,
                            &mut run_caches,
                            &mut flat,
                            &mut lightings,
                        ) {
                            TriangleShader::FlatWaiting(index) => {
                                if usize::from(index) >= flat.colors.len() {
                                    flat.light(&frame);
                                }
                                flat_lit += 1;
                                flat.colors[usize::from(index)].1
                            }
                            TriangleShader::Solid(color) => color,
                            TriangleShader::Gouraud(colors) => {
                                let colors = GouraudColors::new(raster, &corners, colors);
                                let color = colors.at(edge_values(raster, at.0, at.1));
                                // And in the last pass's lanes: the group of the tile's row
                                // holding this pixel, in the lane its column gives it.
                                let (column, row) = (px - i64::from(rect.x0), py - i64::from(rect.y0));
                                let lane = column as usize % LANES;
                                // (Lane steps for every triangle, narrow ones too.)
                                let plane = GouraudPlane {
                                    lane_steps: LaneSteps::over(raster, rect),
                                    ..GouraudPlane::new(raster, rect, colors)
                                };
                                let group = plane
                                    .group_colors::<Native>(column - lane as i64, row)
                                    .expect("the test's triangles are near their tiles")
                                    .to_array();
                                let bits = |v: Vec3| v.to_array().map(f32::to_bits);
                                assert_eq!(bits(group[lane]), bits(color), "Gouraud lanes at {px}, {py}");
                                // The same group on the widest lanes.
                                struct Widest<'p>(&'p GouraudPlane, i64, i64);
                                impl LaneWork for Widest<'_> {
                                    type Output = Option<[Vec3; LANES]>;
                                    #[inline(always)]
                                    fn run<B: Backend>(self) -> Self::Output {
                                        Some(self.0.group_colors::<B>(self.1, self.2)?.to_array())
                                    }
                                }
                                let widest = run_widest(Widest(&plane, column - lane as i64, row))
                                    .expect("the test's triangles are near their tiles");
                                assert_eq!(
                                    widest.map(bits),
                                    group.map(bits),
                                    "Gouraud widest lanes at {px}, {py}"
                                );
                                in_rows += 1;
                                color
                            }
                            TriangleShader::Phong(fast) => {
                                // Through the lanes: a batch of this one pixel.
                                let mut color = [Vec3::NAN];
                                let mut batch = PhongBatch::default();
                                batch.push(&fast, source_weights(raster, &corners, at), 0, &mut color);
                                batch.flush(&mut color);
                                // And through the rows of large triangles: a group of pixels
                                // around this one, in the lane its column gives it.
                                if let Some(rows) =
                                    PhongRows::of(&fast, raster.inv_area, raster.inv_w, corners)
                                {
                                    let lane = (px as usize) % LANES;
                                    let (centre, step) =
                                        (edge_values(raster, at.0, at.1), edge_steps_x(raster));
                                    let group = std::array::from_fn(|k| {
                                        Floats::new(std::array::from_fn(|l| {
                                            (centre[k] + step[k] * (l as i64 - lane as i64)) as f32
                                        }))
                                    });
                                    let bits = |v: Vec3| v.to_array().map(f32::to_bits);
                                    assert_eq!(
                                        bits(rows.shade(|| group)[lane]),
                                        bits(color[0]),
                                        "rows at {px}, {py}"
                                    );
                                    // And written straight into a group of the frame.
                                    let mut written = [Vec3::NAN; LANES];
                                    rows.shade_into(|| group, &mut written);
                                    assert_eq!(
                                        written.map(bits),
                                        rows.shade(|| group).map(bits),
                                        "rows written at {px}, {py}"
                                    );
                                    in_rows += 1;
                                }
                                color[0]
                            }
                            TriangleShader::ModulatedFlatWaiting(modulation, index) => {
                                if usize::from(index) >= flat.colors.len() {
                                    flat.light(&frame);
                                }
                                flat_lit += 1;
                                varying += 1;
                                let shader = VaryingShader::Flat(modulation, flat.colors[usize::from(index)]);
                                shade_one_varying(&frame, raster, &corners, shader, at)
                            }
                            TriangleShader::Varying(shader) => {
                                varying += 1;
                                shade_one_varying(&frame, raster, &corners, shader, at)
                            }
                            TriangleShader::General => {
                                general_left += 1;
                                back_seen += usize::from(raster.back_facing);
                                continue;
                            }
                        };
                        let bits = |v: Vec3| v.to_array().map(f32::to_bits);
                        assert_eq!(
                            bits(run),
                            bits(general),
                            "{shading:?} {model:?} {look:?} {surfaces:?} {back_faces:?} {lights:?} at {px}, {py}"
                        );
                        shaded += 1;
                        back_seen += usize::from(raster.back_facing);
                    }
                }
                assert!(
                    shaded + general_left > 100,
                    "{shading:?} {lights:?}: {shaded} pixels compared"
                );
                // The lanes leave nothing: varying surfaces with Slerp, and those whose lighting
                // is one colour (the ambient term alone, an unlit material, an unlit back side),
                // go through the surface lanes too.
                let one_colour = look.component == crate::scene::LightingComponent::Ambient
                    || model == LightingModel::Unlit;
                let slerp = look.interpolation == NormalInterpolation::Slerp;
                assert_eq!(
                    general_left, 0,
                    "{shading:?} {model:?} {look:?} {surfaces:?} {back_faces:?}: pixels left to the general path"
                );
                // Textured flat and Gouraud pixels, and varying Phong ones, are shaded in lanes.
                let lanes_expected = match surfaces {
                    Some(Surfaces::Tinted) => shading == Shading::Phong,
                    Some(_) => shading != Shading::Constant,
                    None => false,
                };
                if lanes_expected && look == PLAIN && !one_colour && back_faces != BackFaces::Unlit {
                    assert!(
                        varying > 100,
                        "{shading:?} {surfaces:?}: {varying} pixels with varying surfaces compared"
                    );
                }
                // One-colour lighting of varying Phong surfaces, per lane.
                if surfaces.is_some() && shading == Shading::Phong && look.view.is_none() && one_colour {
                    assert!(
                        varying > 100,
                        "{model:?} {look:?} {surfaces:?}: {varying} one-colour varying pixels compared"
                    );
                }
                if shading == Shading::Flat && view.is_none() && !(surfaces.is_some() && one_colour) {
                    assert!(
                        flat_lit + varying > 100,
                        "{back_faces:?}: {flat_lit} flat pixels lit in lanes, {varying} modulated"
                    );
                }
                if shading == Shading::Phong && view.is_none() && surfaces.is_none() && !slerp {
                    assert!(
                        in_rows > 100,
                        "{model:?} {look:?}: {in_rows} pixels shaded in rows"
                    );
                }
                if shading == Shading::Gouraud {
                    gouraud_in_lanes += in_rows;
                }
                // Culled back faces are not drawn.
                if back_faces != BackFaces::Cull {
                    assert!(
                        back_seen > 20,
                        "{shading:?}: {back_seen} back-facing pixels compared"
                    );
                }
            }
        }
        assert!(
            gouraud_in_lanes > 10_000,
            "{gouraud_in_lanes} Gouraud pixels in lanes"
        );
    }

    /// A group of the last pass that shows two triangles, its first lane's and its last
    /// lane's, is written in lanes (`LastPass::write_two_triangle_group`) with the bits its
    /// pixels get one by one (`LastPass::write_pixel`): two Gouraud planes along their shared
    /// edge, a plane beside the background, on the native and the widest lanes. Groups of three
    /// triangles, with a shaded pixel, or with a triangle narrower than a group are left to the
    /// pixels.
    #[test]
    fn two_triangle_groups_equal_their_pixels_bit_for_bit() {
        use crate::render::raster::{ScreenVertex, SourceTriangle, setup_triangle};
        let rect = PixelRect {
            x0: 64,
            y0: 64,
            x1: 128,
            y1: 128,
        };
        let mut weights_table = Vec::new();
        let mut triangle = |corners: [(f32, f32, f32); 3]| {
            let vertex = |(x, y, inv_w): (f32, f32, f32)| ScreenVertex {
                x,
                y,
                depth: 0.5,
                inv_w,
                weights: Vec3::ZERO,
            };
            let source = SourceTriangle {
                index: 0,
                triangle: FrameTriangle::default(),
                back_facing: false,
            };
            setup_triangle(
                corners.map(vertex),
                256,
                256,
                SamplePattern::SINGLE,
                source,
                &mut weights_table,
            )
            .expect("a triangle on the image")
        };
        // Two large triangles sharing the diagonal edge from (30, 20) to (170, 150); a sliver,
        // narrower than a group in the tile.
        let triangles = [
            triangle([(30.0, 20.0, 0.5), (170.0, 150.0, 0.25), (20.0, 170.0, 0.9)]),
            triangle([(30.0, 20.0, 0.5), (190.0, 30.0, 0.7), (170.0, 150.0, 0.25)]),
            triangle([(100.3, 60.0, 0.5), (103.9, 60.0, 0.6), (101.0, 140.0, 0.3)]),
        ];
        let corner_colors = [
            [
                Vec3::new(0.9, 0.1, 0.3),
                Vec3::new(0.2, 0.8, 0.4),
                Vec3::new(0.1, 0.3, 0.95),
            ],
            [
                Vec3::new(0.5, 0.5, 0.1),
                Vec3::new(0.05, 0.6, 0.7),
                Vec3::new(0.8, 0.2, 0.6),
            ],
            [
                Vec3::new(0.3, 0.3, 0.3),
                Vec3::new(0.7, 0.1, 0.2),
                Vec3::new(0.2, 0.9, 0.5),
            ],
        ];
        let gouraud: Vec<GouraudPlane> = triangles
            .iter()
            .zip(corner_colors)
            .map(|(raster, colors)| {
                let corners = raster.corner_weights.resolve(&weights_table);
                GouraudPlane::new(raster, rect, GouraudColors::new(raster, &corners, colors))
            })
            .collect();
        assert!(gouraud[2].lane_steps.is_none(), "the sliver has no lane steps");
        // Tile triangles 0–2 the planes, 3 a fill, 4 a shaded pixel; the background last.
        let sources = [
            PixelSource::Gouraud(0),
            PixelSource::Gouraud(1),
            PixelSource::Gouraud(2),
            PixelSource::Fill,
            PixelSource::Shaded,
            PixelSource::Fill,
        ];
        let fills = [
            Vec3::ZERO,
            Vec3::ZERO,
            Vec3::ZERO,
            Vec3::new(0.25, 0.5, 0.75),
            Vec3::ZERO,
            Vec3::ONE,
        ];
        let pass = LastPass {
            sources: &sources,
            fills: &fills,
            gouraud: &gouraud,
            stride: 64,
        };
        struct Group<'p>(&'p LastPass<'p>, [u32; LANES], usize, usize);
        impl LaneWork for Group<'_> {
            type Output = Option<[Vec3; LANES]>;
            #[inline(always)]
            fn run<B: Backend>(self) -> Self::Output {
                let Group(pass, ids, column, row) = self;
                let mut colors = [Vec3::NAN; LANES];
                pass.write_two_triangle_group::<B>(&ids, column, row, &mut colors)
                    .then_some(colors)
            }
        }
        let bits = |colors: [Vec3; LANES]| colors.map(|c| c.to_array().map(f32::to_bits));
        let none = NO_TRIANGLE;
        let mut in_lanes = 0;
        for row in 0..64 {
            for column in (0..64).step_by(LANES) {
                // What the rasterizer left there of the two large triangles, then variations.
                let shown: [u32; LANES] = std::array::from_fn(|lane| {
                    let at = (
                        pixel_centre(rect.x0 + (column + lane) as u32),
                        pixel_centre(rect.y0 + row as u32),
                    );
                    let inside = |t: &RasterTriangle| edge_values(t, at.0, at.1).iter().all(|&e| e >= 0);
                    if inside(&triangles[0]) {
                        0
                    } else if inside(&triangles[1]) {
                        1
                    } else {
                        none
                    }
                });
                let split = |first: u32, second: u32, at: usize| {
                    std::array::from_fn(|lane| if lane < at { first } else { second })
                };
                let groups = [
                    (
                        shown,
                        samples_showing(&shown, shown[0]) | samples_showing(&shown, shown[LANES - 1])
                            == ALL_LANES,
                    ),
                    (split(0, none, 3), true),
                    (split(3, 1, 5), true),
                    (split(0, 4, 4), false),
                    (split(2, 0, 2), false),
                    ([0, 0, 1, 1, 3, 3, 3, 3], false),
                ];
                for (ids, expected_in_lanes) in groups {
                    let mut expected = [Vec3::NAN; LANES];
                    for (lane, color) in expected.iter_mut().enumerate() {
                        pass.write_pixel(ids[lane], column + lane, row, color);
                    }
                    let native = Group(&pass, ids, column, row).run::<Native>();
                    let widest = run_widest(Group(&pass, ids, column, row));
                    assert_eq!(native.is_some(), expected_in_lanes, "{ids:?} at {column}, {row}");
                    assert_eq!(native.map(bits), widest.map(bits), "{ids:?} at {column}, {row}");
                    if let Some(colors) = native {
                        assert_eq!(bits(colors), bits(expected), "{ids:?} at {column}, {row}");
                        in_lanes += 1;
                    }
                }
            }
        }
        assert!(in_lanes > 1000, "{in_lanes} groups in lanes");
    }

    /// Whole tiles as `shade_tile` writes them, against the general path pixel by pixel: every
    /// pixel written with the general path's bits, the background where nothing is seen, and
    /// the coverage. The two spheres take different shading modes, so that tiles mix
    /// triangles of one colour with triangles shaded per pixel, and small Phong triangles
    /// (shaded in the last pass) with Gouraud ones, and the image is wider than the spheres,
    /// so that some tiles have no triangle at all.
    #[test]
    fn shade_tile_writes_the_general_paths_colours() {
        use Shading::{Constant, Flat, Gouraud, Phong};
        let modes = [
            (Flat, Gouraud),
            (Phong, Flat),
            (Constant, Phong),
            (Gouraud, Gouraud),
            (Flat, Flat),
            (Gouraud, Phong),
        ];
        for ((first, second), surfaces) in modes.into_iter().flat_map(|m| SURFACES.map(|s| (m, s))) {
            for (back_faces, lights) in [BackFaces::ReverseLit, BackFaces::Lit]
                .into_iter()
                .flat_map(|b| shade_fast::tests::LIGHTS.map(|l| (b, l)))
            {
                // Gouraud beside Phong: narrower, so that the gap between the spheres falls
                // inside a tile column and its tiles hold both.
                let width = if (first, second) == (Gouraud, Phong) {
                    200
                } else {
                    260
                };
                let mut scene = cut_open_scene(
                    LightingModel::BlinnPhong,
                    back_faces,
                    lights,
                    [first, second],
                    (width, 140),
                );
                // Zoomed in on the Phong pairs and on flat beside Gouraud, so that triangles
                // span several groups of lanes (`PhongRows`, the last pass's groups of one
                // triangle); the Gouraud pair and Gouraud beside Phong stay small (Phong
                // triangles narrower than a group, `PhongPlane`, in tiles with Gouraud ones).
                let zoomed = (first == Phong || second == Phong || (first, second) == (Flat, Gouraud))
                    && (first, second) != (Gouraud, Phong);
                if zoomed {
                    scene.camera.projection = crate::scene::Projection::Perspective {
                        fov_y_degrees: 8.0,
                        near: 4.9,
                        far: 100.0,
                    };
                }
                if let Some(surfaces) = surfaces {
                    shade_fast::tests::vary_surfaces(&mut scene, surfaces);
                }
                let background = scene.image.background;
                let frame = shade_fast::tests::frame_of(&scene, None);
                let width = scene.image.width as usize;
                let mut caches = TileCaches {
                    flat: TriangleColorCache::new(),
                    back: TriangleColorCache::new(),
                    flat_waiting: TriangleColorCache::new(),
                };
                let mut scratch = TileScratch::default();
                let (mut empty_tiles, mut covered_pixels) = (0, 0);
                for tile in 0..frame.tiles.count() {
                    let rect = frame.tiles.rect(tile);
                    let visibility = rasterize_tile(rect, SamplePattern::SINGLE, &frame.raster, tile);
                    // NaN and `true` everywhere: a pixel the tile does not write is caught.
                    let band = rect.height() as usize * width;
                    let (mut color, mut covered) = (vec![Vec3::NAN; band], vec![true; band]);
                    let mut target = TileTarget {
                        color: &mut color,
                        covered: &mut covered,
                        stride: width,
                    };
                    let shaded = shade_tile(&frame, &visibility, background, &mut target, &mut scratch);
                    empty_tiles += usize::from(visibility.raster_ids.is_empty());
                    let mut seen = 0;
                    for (slot, &id) in visibility.triangle.iter().enumerate() {
                        let px = rect.x0 + slot as u32 % rect.width();
                        let py = rect.y0 + slot as u32 / rect.width();
                        let offset = (py - rect.y0) as usize * width + px as usize;
                        let expected = if id == NO_TRIANGLE {
                            background
                        } else {
                            seen += 1;
                            let id = visibility.raster_id(id);
                            let at = (pixel_centre(px), pixel_centre(py));
                            let corners = frame.corner_weights(id);
                            shade_sample(&frame, frame.raster_triangle(id), &corners, at, &mut caches)
                        };
                        let bits = |v: Vec3| v.to_array().map(f32::to_bits);
                        assert_eq!(
                            bits(color[offset]),
                            bits(expected),
                            "{first:?}/{second:?} {back_faces:?} {lights:?} {surfaces:?} at {px}, {py}: {} \
                             against {expected}",
                            color[offset]
                        );
                        assert_eq!(covered[offset], id != NO_TRIANGLE);
                    }
                    assert_eq!(shaded, seen);
                    covered_pixels += seen;
                }
                assert!(
                    (zoomed || empty_tiles > 0) && covered_pixels > 2000,
                    "{empty_tiles} empty tiles, {covered_pixels} pixels"
                );
            }
        }
    }

    /// A multisampled pixel as the general path resolves it: each distinct triangle among its
    /// samples shaded by `shade_sample` at the mean offset of the samples it covers (rounded
    /// down to 1/256 pixel), weighted by their count and added in the order of their first
    /// samples, with the background for the rest; `None` where no sample is covered.
    fn general_multisampled_pixel(
        frame: &Frame,
        visibility: &Visibility,
        slot: usize,
        background: Vec3,
        caches: &mut TileCaches,
    ) -> Option<(Vec3, usize)> {
        let (rect, pattern) = (visibility.rect, visibility.pattern);
        let samples = pattern.len();
        let ids = &visibility.triangle[slot * samples..(slot + 1) * samples];
        let mut seen: Vec<(u32, i64, i64, i64)> = Vec::new();
        for (&id, &(ox, oy)) in ids.iter().zip(pattern.offsets()) {
            if id == NO_TRIANGLE {
                continue;
            }
            match seen.iter_mut().find(|entry| entry.0 == id) {
                Some(entry) => *entry = (id, entry.1 + 1, entry.2 + i64::from(ox), entry.3 + i64::from(oy)),
                None => seen.push((id, 1, i64::from(ox), i64::from(oy))),
            }
        }
        if seen.is_empty() {
            return None;
        }
        let px = rect.x0 + slot as u32 % rect.width();
        let py = rect.y0 + slot as u32 / rect.width();
        let (mut sum, mut covered) = (Vec3::ZERO, 0);
        for &(local, n, sum_x, sum_y) in &seen {
            let id = visibility.raster_id(local);
            let at = (
                pixel_centre(px) + sum_x.div_euclid(n),
                pixel_centre(py) + sum_y.div_euclid(n),
            );
            let color = shade_sample(
                frame,
                frame.raster_triangle(id),
                &frame.corner_weights(id),
                at,
                caches,
            );
            sum += color * n as f32;
            covered += n;
        }
        let color = if frame.debug_view == Some(DebugView::Depth) {
            sum / covered as f32
        } else {
            (sum + background * (samples as i64 - covered) as f32) / samples as f32
        };
        Some((color, seen.len()))
    }

    /// Multisampled tiles as `shade_tile` writes them (each pixel's triangles through the
    /// per-triangle shaders, then resolved) against the general path pixel by pixel, at 2, 4,
    /// 8 and 16 samples: the same bits everywhere, for every shading mode, every lighting
    /// model, the back-face modes, light sets, Slerp, a component, and the debug views (the
    /// depth view's mean leaves the background out). The spheres are small on the screen, so that many pixels lie on an
    /// edge between triangles, or between a triangle and the background.
    #[test]
    fn multisampled_tiles_equal_the_general_path_bit_for_bit() {
        use crate::scene::{LightingComponent, MicrofacetDistribution, NormalInterpolation};
        use Shading::{Constant, Flat, Gouraud, Phong};
        use shade_fast::tests::{Look, PLAIN, microfacet};
        let slerp = Look {
            interpolation: NormalInterpolation::Slerp,
            ..PLAIN
        };
        let view = |view| Look {
            view: Some(view),
            ..PLAIN
        };
        let cases = [
            (
                Flat,
                Gouraud,
                LightingModel::BlinnPhong,
                BackFaces::ReverseLit,
                PLAIN,
            ),
            (Phong, Flat, LightingModel::Phong, BackFaces::Lit, PLAIN),
            (
                Phong,
                Phong,
                LightingModel::BlinnPhong,
                BackFaces::ReverseLit,
                slerp,
            ),
            (Gouraud, Phong, LightingModel::Phong, BackFaces::Unlit, PLAIN),
            (
                Constant,
                Gouraud,
                LightingModel::BlinnPhong,
                BackFaces::Lit,
                PLAIN,
            ),
            (
                Gouraud,
                Flat,
                LightingModel::BlinnPhong,
                BackFaces::ReverseLit,
                view(DebugView::Depth),
            ),
            (
                Phong,
                Flat,
                microfacet(MicrofacetDistribution::Beckmann),
                BackFaces::Unlit,
                Look {
                    component: LightingComponent::Specular,
                    ..slerp
                },
            ),
            (
                Flat,
                Phong,
                microfacet(MicrofacetDistribution::Ggx),
                BackFaces::Lit,
                PLAIN,
            ),
            (
                Gouraud,
                Phong,
                LightingModel::Lambert,
                BackFaces::ReverseLit,
                view(DebugView::Normals),
            ),
            (
                Phong,
                Constant,
                LightingModel::Unlit,
                BackFaces::Lit,
                view(DebugView::Diffuse),
            ),
        ];
        for samples in [2, 4, 8, 16] {
            let pattern = SamplePattern::new(samples).expect("a sample count");
            for ((first, second, model, back_faces, look), surfaces) in
                cases.into_iter().flat_map(|c| SURFACES.map(|s| (c, s)))
            {
                for lights in shade_fast::tests::LIGHTS {
                    let mut scene = cut_open_scene(model, back_faces, lights, [first, second], (130, 70));
                    look.apply(&mut scene);
                    if let Some(surfaces) = surfaces {
                        shade_fast::tests::vary_surfaces(&mut scene, surfaces);
                    }
                    let view = look.view;
                    let background = scene.image.background;
                    let frame = shade_fast::tests::frame_sampled(&scene, pattern, view);
                    let width = scene.image.width as usize;
                    let mut caches = TileCaches {
                        flat: TriangleColorCache::new(),
                        back: TriangleColorCache::new(),
                        flat_waiting: TriangleColorCache::new(),
                    };
                    let mut scratch = TileScratch::default();
                    let (mut edge_pixels, mut back_pixels, mut covered_pixels) = (0, 0, 0);
                    for tile in 0..frame.tiles.count() {
                        let rect = frame.tiles.rect(tile);
                        let visibility = rasterize_tile(rect, pattern, &frame.raster, tile);
                        // NaN and `true` everywhere: a pixel the tile does not write is caught.
                        let band = rect.height() as usize * width;
                        let (mut color, mut covered) = (vec![Vec3::NAN; band], vec![true; band]);
                        let mut target = TileTarget {
                            color: &mut color,
                            covered: &mut covered,
                            stride: width,
                        };
                        let shaded = shade_tile(&frame, &visibility, background, &mut target, &mut scratch);
                        let mut expected_shaded = 0;
                        for slot in 0..(rect.width() * rect.height()) as usize {
                            let px = rect.x0 + slot as u32 % rect.width();
                            let py = rect.y0 + slot as u32 / rect.width();
                            let offset = (py - rect.y0) as usize * width + px as usize;
                            let ids = &visibility.triangle[slot * samples as usize..][..samples as usize];
                            let general = general_multisampled_pixel(
                                &frame,
                                &visibility,
                                slot,
                                background,
                                &mut caches,
                            );
                            let expected = general.map_or(background, |(color, _)| color);
                            let bits = |v: Vec3| v.to_array().map(f32::to_bits);
                            assert_eq!(
                                bits(color[offset]),
                                bits(expected),
                                "{samples} samples {first:?}/{second:?} {model:?} {back_faces:?} {look:?} \
                                 {lights:?} {surfaces:?} at {px}, {py}: {} against {expected}",
                                color[offset]
                            );
                            assert_eq!(covered[offset], general.is_some());
                            let distinct = general.map_or(0, |(_, distinct)| distinct);
                            expected_shaded += distinct;
                            covered_pixels += usize::from(general.is_some());
                            edge_pixels +=
                                usize::from(distinct > 1 || ids.contains(&NO_TRIANGLE) && distinct > 0);
                            back_pixels += usize::from(ids.iter().any(|&id| {
                                id != NO_TRIANGLE
                                    && frame.raster_triangle(visibility.raster_id(id)).back_facing
                            }));
                        }
                        assert_eq!(shaded, expected_shaded);
                    }
                    assert!(
                        covered_pixels > 1000 && edge_pixels > 500 && back_pixels > 10,
                        "{samples} samples: {covered_pixels} pixels, {edge_pixels} on edges, {back_pixels} back"
                    );
                }
            }
        }
    }
}
