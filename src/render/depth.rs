//! The shadow pass: a scene's depth as a light sees it, and nothing else.
//!
//! A shadow map needs the nearest depth at each texel centre and no more: no attributes, no
//! lighting, no triangle numbers, no colour. So the pass projects vertices only
//! into the light's clip space, and sets triangles up and rasterizes them with the image's own
//! code (`geometry::set_up_raster_triangles`: clipping, snapping, setup; `raster`: the
//! single-sample coverage loop), so that coverage and precision are the image's, straight into
//! the map: bands of tile rows in parallel, each band's tiles in order, as the image's tiles.
//!
//! Keeping only depth makes the order of the triangles irrelevant: the nearest of a set is the
//! same value whichever comes first. (The one exception, `+0` against `−0`, needs a depth of 0,
//! the far plane, which lies beyond the whole scene in every map; and a lookup compares the two
//! alike anyway.) Each tile uses that to skip most of the triangles that face away from the
//! light: it draws those facing the light first (the sign of `det[x y w]`, as for the image),
//! takes the farthest depth of each 8×8 block of texels, and then draws a triangle facing away
//! only if some block it touches holds something farther than the nearest depth it can write
//! ([`depth_bound`]); elsewhere its depth test would fail at every texel. Seen from the light, a
//! closed mesh's back faces lie behind its front faces except along its outline, so most of them
//! stop at a few comparisons.
//!
//! The back faces of an object whose mesh is closed and lies wholly beyond the light's near plane
//! are not even set up (`geometry::back_faces_hidden`, the test the image's geometry culls with):
//! every ray from the light meets a front face of it first, so its back faces could only win a
//! texel where rounding put one ahead of the front face it meets at the outline. On a map of
//! S1's spheres that is half the triangles the pass sets up and bins.
//!
//! A map's array is reused from frame to frame (`shadow::ShadowBuffers`) with a flag per tile
//! that says it holds only −∞: a tile that no triangle reaches and that is blank already is
//! not written at all: on a map of a few objects, most of its tiles (S1's 2048² map is 16 MB
//! of texels, of which the two spheres cover about a quarter).
//!
//! The map is the one that rasterizing every triangle in order would give, bit for bit (a test
//! holds the two together, closed meshes culled or not). Building only the triangles facing the
//! light first and setting up
//! the others after them, against the whole map, was tried: it set up a sixth of the triangles
//! less but cost more than it saved (a second walk of the map, more triangles kept at block
//! edges).

use glam::Vec3;
use rayon::prelude::*;

use crate::render::TILE_SIZE;
use crate::render::bin::{RasterChunk, TileGrid};
use crate::render::frame::FrameTriangle;
use crate::render::geometry::{
    CameraSetup, ObjectTransforms, ProjectedVertex, RasterOutput, SpareBuffers, TRIANGLE_CHUNK, Viewport,
    back_faces_hidden_within, homogeneous_facing, set_up_raster_triangles,
};
use crate::render::lanes::{Backend, LaneWork, run_widest};
use crate::render::raster::{
    PixelRect, RasterTriangle, SamplePattern, SourceTriangle, depth_bound, prefetch_triangle_ahead,
    rasterize_depth_only,
};
use crate::scene::{Camera, Scene};

/// Vertices per parallel work item of the vertex pass.
const VERTEX_CHUNK: usize = 4096;

/// Renders the depth of `scene` as `camera` sees it into the `size`² texels of `depth`
/// (row-major from the top; −∞ where nothing is), in the image's spare arrays (which arrays are
/// reused changes nothing: every element the pass reads, it wrote).
///
/// `blank_tiles` marks, per tile of the map (row-major), the tiles whose texels `depth` holds
/// all at −∞ already: those the pass leaves alone if no triangle reaches them (on a map of a
/// few objects, most of its tiles, frame after frame). The pass sets it to the tiles it leaves
/// blank. Any other length counts as no tile known blank.
///
/// `mesh_bounds` holds each object's [`Mesh::bounds`](crate::mesh::Mesh::bounds), which the
/// shadow maps' fit found already.
pub fn render_depth(
    scene: &Scene,
    mesh_bounds: &[Option<(Vec3, Vec3)>],
    camera: &Camera,
    size: u32,
    depth: &mut [f32],
    blank_tiles: &mut Vec<bool>,
    spare: &mut SpareBuffers,
) {
    let camera = CameraSetup::new(camera, 1.0);
    let viewport = Viewport::new(size, size, SamplePattern::SINGLE);
    let side = size as usize;
    debug_assert_eq!(depth.len(), side * side);
    let (chunks, projected) = spare.depth_pass_arrays();
    let mirrored = project_vertices(scene, &camera, &viewport, projected);
    let hidden_back_faces: Vec<bool> = scene
        .objects
        .iter()
        .zip(mesh_bounds)
        .map(|(object, &bounds)| back_faces_hidden_within(object, bounds, &camera))
        .collect();
    set_up_triangles(scene, &mirrored, &hidden_back_faces, &viewport, projected, chunks);
    let grid = TileGrid::new(size, size);
    if blank_tiles.len() != grid.count() {
        blank_tiles.clear();
        blank_tiles.resize(grid.count(), false);
    }
    let chunks = &*chunks;
    let columns = grid.columns as usize;
    depth
        .par_chunks_mut(TILE_SIZE as usize * side)
        .zip(blank_tiles.par_chunks_mut(columns))
        .enumerate()
        .for_each(|(tile_row, (band, blank))| {
            for (column, blank) in blank.iter_mut().enumerate() {
                let tile = tile_row * columns + column;
                *blank = rasterize_tile(grid.rect(tile), chunks, tile, band, side, *blank);
            }
        });
}

/// Every vertex of the scene in the light's clip space, projected and snapped where it needs no
/// clipping: `geometry`'s vertex pass without world positions or normals. Returns, per object,
/// whether its transform mirrors it (turning its triangles clockwise).
fn project_vertices(
    scene: &Scene,
    camera: &CameraSetup,
    viewport: &Viewport,
    projected: &mut Vec<ProjectedVertex>,
) -> Vec<bool> {
    let vertex_count = scene.objects.iter().map(|o| o.mesh.positions.len()).sum();
    // Every element is written below.
    projected.resize(vertex_count, ProjectedVertex::default());
    let (width, height) = (viewport.width as f32, viewport.height as f32);
    let mut vertex_base = 0;
    let mut mirrored = Vec::with_capacity(scene.objects.len());
    for object in &scene.objects {
        let positions = &object.mesh.positions;
        let transforms = ObjectTransforms::new(object, camera);
        let clip_from_model = transforms.clip_from_model;
        mirrored.push(transforms.mirrored);
        projected[vertex_base..vertex_base + positions.len()]
            .par_chunks_mut(VERTEX_CHUNK)
            .zip(positions.par_chunks(VERTEX_CHUNK))
            .for_each(|(projected, positions)| {
                for (projected, &p) in projected.iter_mut().zip(positions) {
                    let clip = clip_from_model * p.extend(1.0);
                    *projected =
                        ProjectedVertex::new(clip, viewport.guard_x, viewport.guard_y, width, height);
                }
            });
        vertex_base += positions.len();
    }
    mirrored
}

/// Per chunk of the scene's triangle stream (in parallel), its triangles (corners in
/// `projected`) set up and binned into `chunks`, each marked with the side the light sees.
/// Edge-on, degenerate and non-finite triangles are dropped, as the image's geometry drops
/// them, and so are the back faces of the objects whose `hidden_back_faces` holds.
fn set_up_triangles(
    scene: &Scene,
    mirrored: &[bool],
    hidden_back_faces: &[bool],
    viewport: &Viewport,
    projected: &[ProjectedVertex],
    chunks: &mut Vec<RasterChunk>,
) {
    // Where each object's triangles and vertices start.
    let mut starts = Vec::with_capacity(scene.objects.len() + 1);
    let (mut triangles, mut vertices) = (0usize, 0u32);
    for object in &scene.objects {
        starts.push((triangles, vertices));
        triangles += object.mesh.triangles.len();
        vertices += object.mesh.positions.len() as u32;
    }
    starts.push((triangles, vertices));
    // Exactly one per chunk: a longer list from a larger frame would add stale triangles.
    chunks.resize_with(triangles.div_ceil(TRIANGLE_CHUNK), RasterChunk::default);
    let grid = TileGrid::new(viewport.width, viewport.height);
    chunks
        .par_iter_mut()
        .enumerate()
        .for_each(|(chunk, raster_chunk)| {
            let mut raster = RasterOutput {
                triangles: raster_chunk.take_triangles(),
                clipped_weights: std::mem::take(&mut raster_chunk.clipped_weights),
            };
            raster.clipped_weights.clear();
            let first = chunk * TRIANGLE_CHUNK;
            let last = (first + TRIANGLE_CHUNK).min(triangles);
            raster.triangles.reserve(last - first);
            // The chunk in runs of one object each: what depends on the object is looked up
            // once per run.
            let mut object = starts.partition_point(|&(start, _)| start <= first) - 1;
            let mut run_start = first;
            while run_start < last {
                while run_start >= starts[object + 1].0 {
                    object += 1;
                }
                let (triangle_base, vertex_base) = starts[object];
                let run_end = starts[object + 1].0.min(last);
                let mesh_triangles =
                    &scene.objects[object].mesh.triangles[run_start - triangle_base..run_end - triangle_base];
                let (mirrored, hidden_back_faces) = (mirrored[object], hidden_back_faces[object]);
                for (index, &[a, b, c]) in (run_start..).zip(mesh_triangles) {
                    let vertices = if mirrored { [a, c, b] } else { [a, b, c] };
                    let corners = vertices.map(|v| &projected[(v + vertex_base) as usize]);
                    let facing = homogeneous_facing(corners.map(|v| v.clip));
                    let back_facing = facing < 0.0;
                    if facing == 0.0 || facing.is_nan() || (back_facing && hidden_back_faces) {
                        continue;
                    }
                    let source = SourceTriangle {
                        index: index as u32,
                        triangle: FrameTriangle::default(),
                        back_facing,
                    };
                    set_up_raster_triangles(corners, source, viewport, &mut raster);
                }
                run_start = run_end;
            }
            raster_chunk.rebin(raster.triangles, &grid);
            raster_chunk.clipped_weights = raster.clipped_weights;
        });
}

/// Rasterizes tile `tile` (the texels `rect`) into `depth`, the map's rows from `rect.y0` on,
/// `stride` apart, replacing what it held: the triangles facing the light, then those facing
/// away that [`FarthestInBlocks::may_be_nearer`] cannot rule out. On the widest lanes, one
/// call of [`run_widest`] per tile. `blank` says the tile's texels are all −∞ already; returns
/// whether they are now (no triangle reaches the tile).
fn rasterize_tile(
    rect: PixelRect,
    chunks: &[RasterChunk],
    tile: usize,
    depth: &mut [f32],
    stride: usize,
    blank: bool,
) -> bool {
    let empty = chunks.iter().all(|chunk| chunk.tile_triangles(tile).is_empty());
    if empty && blank {
        return true;
    }
    let (x0, width) = (rect.x0 as usize, rect.width() as usize);
    for row in 0..rect.height() as usize {
        depth[row * stride + x0..][..width].fill(f32::NEG_INFINITY);
    }
    if !empty {
        run_widest(DepthTile {
            rect,
            chunks,
            tile,
            depth,
            stride,
        });
    }
    empty
}

/// [`rasterize_tile`]'s triangles, as lane work.
struct DepthTile<'t> {
    rect: PixelRect,
    chunks: &'t [RasterChunk],
    tile: usize,
    depth: &'t mut [f32],
    stride: usize,
}

impl LaneWork for DepthTile<'_> {
    type Output = ();

    #[inline(always)]
    fn run<B: Backend>(self) {
        let DepthTile {
            rect,
            chunks,
            tile,
            depth,
            stride,
        } = self;
        let mut back_faces = false;
        for chunk in chunks {
            let indices = chunk.tile_triangles(tile);
            for (position, &index) in indices.iter().enumerate() {
                prefetch_triangle_ahead(chunk, indices, position);
                let triangle = &chunk.triangles[index as usize];
                if triangle.back_facing {
                    back_faces = true;
                } else {
                    rasterize_depth_only::<B>(triangle, rect, depth, stride);
                }
            }
        }
        if !back_faces {
            return;
        }
        let farthest = FarthestInBlocks::of(rect, depth, stride);
        for chunk in chunks {
            for &index in chunk.tile_triangles(tile) {
                let triangle = &chunk.triangles[index as usize];
                if triangle.back_facing && farthest.may_be_nearer(triangle, rect) {
                    rasterize_depth_only::<B>(triangle, rect, depth, stride);
                }
            }
        }
    }
}

/// Texels per side of the blocks of [`FarthestInBlocks`].
const DEPTH_BLOCK: u32 = 8;
/// Blocks per side of a tile.
const TILE_BLOCKS: usize = (TILE_SIZE / DEPTH_BLOCK) as usize;

/// The farthest depth in each 8×8 block of a tile's texels.
struct FarthestInBlocks {
    farthest: [f32; TILE_BLOCKS * TILE_BLOCKS],
}

impl FarthestInBlocks {
    /// Of the texels `rect` of `depth` (laid out as in [`rasterize_tile`]).
    fn of(rect: PixelRect, depth: &[f32], stride: usize) -> Self {
        let mut farthest = [f32::INFINITY; TILE_BLOCKS * TILE_BLOCKS];
        for row in 0..rect.height() as usize {
            let texels = &depth[row * stride + rect.x0 as usize..][..rect.width() as usize];
            let blocks = &mut farthest[row / DEPTH_BLOCK as usize * TILE_BLOCKS..][..TILE_BLOCKS];
            for (block, texels) in blocks.iter_mut().zip(texels.chunks(DEPTH_BLOCK as usize)) {
                // `<` and not `f32::min`, so that the loop vectorises (no texel is NaN).
                *block = texels
                    .iter()
                    .fold(*block, |least, &d| if d < least { d } else { least });
            }
        }
        FarthestInBlocks { farthest }
    }

    /// Whether `triangle` may be nearer than what some texel of the blocks it touches within
    /// `rect` holds. If not, its depth test fails at every texel of the tile, now and after any
    /// other triangle (texels only get nearer), and it changes nothing.
    #[inline]
    fn may_be_nearer(&self, triangle: &RasterTriangle, rect: PixelRect) -> bool {
        let Some(area) = triangle.bounds.intersect(&rect) else {
            return false;
        };
        let bound = depth_bound(triangle.depth);
        let (x0, x1) = (
            (area.x0 - rect.x0) / DEPTH_BLOCK,
            (area.x1 - 1 - rect.x0) / DEPTH_BLOCK,
        );
        let (y0, y1) = (
            (area.y0 - rect.y0) / DEPTH_BLOCK,
            (area.y1 - 1 - rect.y0) / DEPTH_BLOCK,
        );
        (y0..=y1).any(|y| {
            let row = &self.farthest[y as usize * TILE_BLOCKS..][..TILE_BLOCKS];
            row[x0 as usize..=x1 as usize]
                .iter()
                .any(|&farthest| farthest < bound)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::lanes::Native;
    use crate::render::raster::Visibility;
    use glam::Vec3;

    /// The pass against rasterizing every triangle in the stream's order through the image's
    /// visibility buffer, bit for bit at every texel, from the lights of the shadow tests (an
    /// orthographic map, a narrow spot, a wide spot's and a point light's cube faces) and from
    /// a camera whose near plane cuts a sphere open (seen from inside, its back faces win),
    /// with spheres, a mirrored cube and an open plane seen from both sides, the closed meshes'
    /// back faces culled where the pass culls them and not; and most back faces are culled or
    /// skipped.
    #[test]
    fn the_pass_equals_rasterizing_every_triangle_in_order() {
        use crate::mesh::primitives;
        use crate::render::shade_fast::tests::{LIGHTS, scene};
        use crate::render::shadow::light_views;
        use crate::render::shadow::tests::shadowed_lights;
        use crate::scene::{BackFaces, LightingModel, bounding_sphere};
        use glam::{DMat4, DVec3};
        use std::sync::Arc;

        let mut scene = scene(LightingModel::Phong, Vec3::ONE, BackFaces::Lit, LIGHTS[0]);
        let mut cube = scene.objects[0].clone();
        cube.mesh = Arc::new(primitives::cube());
        cube.transform = DMat4::from_translation(DVec3::new(0.0, 1.5, -1.2))
            * DMat4::from_scale(DVec3::new(-0.7, 0.5, 0.4));
        let mut plane = scene.objects[0].clone();
        plane.mesh = Arc::new(primitives::plane());
        plane.transform =
            DMat4::from_translation(DVec3::new(0.0, 0.0, -1.2)) * DMat4::from_scale(DVec3::splat(3.0));
        scene.objects.extend([cube, plane]);
        let bounds = bounding_sphere(&scene.objects);
        let mut near_cut = Camera {
            eye: DVec3::new(-1.2, -2.0, 0.0),
            target: DVec3::new(-1.2, 0.0, 0.0),
            up: DVec3::Z,
            projection: crate::scene::Projection::Perspective {
                fov_y_degrees: 70.0,
                near: 1.5,
                far: 20.0,
            },
        };
        let mut views: Vec<(Camera, u32)> = shadowed_lights()
            .iter()
            .flat_map(|light| light_views(light, bounds, 96))
            .collect();
        views.push((near_cut, 80));
        near_cut.eye.z = 3.0;
        views.push((near_cut, 80));
        // The same objects with no mesh known to be closed: none of their back faces is culled.
        let mesh_bounds = crate::render::shadow::each_mesh_bounds(&scene);
        let mut open = scene.clone();
        for object in &mut open.objects {
            Arc::make_mut(&mut object.mesh).closed = false;
        }
        assert!(scene.objects.iter().filter(|object| object.mesh.closed).count() >= 3);
        let (mut back_faces, mut skipped, mut covered) = (0, 0, 0);
        let (mut set_up, mut set_up_open) = (0, 0);
        // Each size's map and its blank tiles, reused from view to view as a stream of frames
        // reuses them: every texel must come out as a fresh map's would.
        let mut reused: std::collections::HashMap<u32, (Vec<f32>, Vec<bool>)> = Default::default();
        let (mut left_blank, mut drawn_again) = (0, 0);
        for (camera, size) in views {
            let mut spare = SpareBuffers::default();
            let (depth, blank_tiles) = reused
                .entry(size)
                .or_insert_with(|| (vec![f32::NAN; (size * size) as usize], Vec::new()));
            let blank_before = blank_tiles.clone();
            render_depth(
                &scene,
                &mesh_bounds,
                &camera,
                size,
                depth,
                blank_tiles,
                &mut spare,
            );
            // Tiles left alone (blank before and after) and tiles blank before that a triangle
            // now reaches (filled again).
            for (&before, &after) in blank_before.iter().zip(blank_tiles.iter()) {
                left_blank += usize::from(before && after);
                drawn_again += usize::from(before && !after);
            }
            let depth = depth.clone();
            let triangles = |spare: &mut SpareBuffers| -> usize {
                spare
                    .depth_pass_arrays()
                    .0
                    .iter()
                    .map(|chunk| chunk.triangles.len())
                    .sum()
            };
            set_up += triangles(&mut spare);
            let mut open_depth = vec![f32::NAN; (size * size) as usize];
            render_depth(
                &open,
                &mesh_bounds,
                &camera,
                size,
                &mut open_depth,
                &mut Vec::new(),
                &mut spare,
            );
            set_up_open += triangles(&mut spare);

            // Every raster triangle of the open objects, in the stream's order (the chunks are
            // in that order).
            let grid = TileGrid::new(size, size);
            let every: Vec<RasterTriangle> = spare
                .depth_pass_arrays()
                .0
                .iter()
                .flat_map(|chunk| chunk.triangles.iter().copied())
                .collect();
            assert!(every.windows(2).all(|pair| pair[0].source <= pair[1].source));
            let every = [RasterChunk::new(every, &grid)];
            for tile in 0..grid.count() {
                let rect = grid.rect(tile);
                let mut visibility = Visibility::new();
                visibility.rasterize(rect, SamplePattern::SINGLE, &every, tile);
                // The tile's front faces alone, as the pass draws them first, and the back faces
                // their farthest blocks rule out.
                let mut fronts = vec![f32::NEG_INFINITY; depth.len()];
                let band = &mut fronts[(rect.y0 * size) as usize..];
                let tile_triangles = every[0]
                    .tile_triangles(tile)
                    .iter()
                    .map(|&i| &every[0].triangles[i as usize]);
                for triangle in tile_triangles.clone().filter(|t| !t.back_facing) {
                    rasterize_depth_only::<Native>(triangle, rect, band, size as usize);
                }
                let farthest = FarthestInBlocks::of(rect, band, size as usize);
                for triangle in tile_triangles.filter(|t| t.back_facing) {
                    back_faces += 1;
                    skipped += usize::from(!farthest.may_be_nearer(triangle, rect));
                }
                for y in rect.y0..rect.y1 {
                    for x in rect.x0..rect.x1 {
                        let expected =
                            visibility.depth[((y - rect.y0) * rect.width() + x - rect.x0) as usize];
                        for (found, culled) in [(&depth, "culled"), (&open_depth, "open")] {
                            assert_eq!(
                                found[(y * size + x) as usize].to_bits(),
                                expected.to_bits(),
                                "{camera:?}, back faces of closed meshes {culled}: texel ({x}, {y})"
                            );
                        }
                        covered += usize::from(expected > f32::NEG_INFINITY);
                    }
                }
            }
        }
        assert!(covered > 20_000, "{covered} texels covered");
        assert!(
            left_blank > 0 && drawn_again > 0,
            "{left_blank} blank tiles left alone, {drawn_again} drawn again"
        );
        // Nearly half the triangles are culled: every view but those that cut a sphere open
        // sees all three closed meshes from outside.
        assert!(
            set_up * 5 < set_up_open * 3,
            "{set_up} of {set_up_open} triangles set up"
        );
        assert!(
            skipped * 4 > back_faces,
            "{skipped} of {back_faces} back faces skipped"
        );
    }
}
