//! The renderer: a pure function from a validated [`Scene`] to a linear-light [`FrameBuffer`].
//!
//! ```text
//! geometry (parallel over each object's vertices, then over chunks of the triangle stream)
//!   transform · project · per-vertex lighting (Gouraud)        once per vertex
//!   facing · clip · snap · setup · bin into tiles               per triangle, per chunk
//!     └─► RasterChunk list: raster triangles and their tile bins, in submission order
//! tiles    bands of tile rows taken from a queue by every core, the most work first; each
//!          band's tiles in order, into the band's rows:
//!   raster   fixed-point edge functions, top-left rule, depth test → visibility buffer
//!   shade    each visible pixel once: flat / Gouraud / Phong, written into the frame
//! ```
//!
//! Architecture invariants:
//! - `render` does no I/O and cannot fail: the loader has validated the scene.
//! - The result is bit-identical for any thread count: work is split into chunks and tiles whose
//!   boundaries depend only on the scene and image size, every tile owns its buffers, and results
//!   are stitched in a fixed order. No floating-point reduction crosses a thread boundary.
//! - Each visible pixel is shaded once (a visibility buffer per tile), so overdraw costs depth
//!   tests, not lighting.

pub mod bin;
pub mod clip;
pub mod depth;
pub mod frame;
pub mod framebuffer;
pub mod geometry;
pub mod inspect;
pub mod lanes;
pub mod normals;
pub mod power;
pub mod raster;
pub mod shade;
pub mod shade_fast;
pub mod shadow;
pub mod surface_lanes;
pub mod texture_lanes;
pub mod trig;

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use crate::scene::Scene;

pub use framebuffer::{FrameBuffer, RowSpan};

/// Tiles are square; 64×64 pixels keep a tile's depth, id and colour buffers (80 KiB) in L2.
pub const TILE_SIZE: u32 = 64;

/// The largest width or height accepted. The fixed-point rasterizer itself allows a guard band of
/// ±2^20 pixels (see [`raster`]); this smaller limit keeps the guard band at least 64 images wide,
/// so triangles are clipped against x/y only when they reach far off screen, and keeps the frame
/// buffer (16 bytes a pixel) within a few GiB.
pub const MAX_IMAGE_DIMENSION: u32 = 16384;

/// Instead of the lit colour, show one ingredient of it (the seeds' shader "modes").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum DebugView {
    /// `k_a·I_a` only.
    Ambient,
    /// The diffuse sum only.
    Diffuse,
    /// The specular sum only.
    Specular,
    /// The shading normal, mapped from [-1, 1] to [0, 1] per axis (world space).
    Normals,
    /// Distance along the view axis, nearest visible point white, farthest black.
    Depth,
}

#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct RenderOptions {
    /// Worker threads; `None` uses rayon's global pool (one per core).
    pub threads: Option<usize>,
    pub debug_view: Option<DebugView>,
}

/// What a render did and where its time went.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct RenderStats {
    /// Triangles in the scene's meshes.
    pub triangles: usize,
    /// Triangles that reached the rasterizer (after culling, clipping and dropping zero-area ones;
    /// a clipped triangle may count more than once).
    pub raster_triangles: usize,
    /// Rendering the shadow maps (wall time).
    pub shadow_maps: Duration,
    /// Shadow-map faces rendered (six per point light).
    pub shadow_faces: usize,
    /// Transform, lighting per vertex, clipping, setup and binning (wall time).
    pub geometry: Duration,
    /// Rasterizing and shading every tile, and stitching them (wall time).
    pub raster_shade: Duration,
    /// Of `raster_shade`: rasterizing, summed over the tiles (thread time, not wall time).
    pub raster_thread_time: Duration,
    /// Of `raster_shade`: shading, summed over the tiles (thread time, not wall time).
    pub shade_thread_time: Duration,
    /// Of `raster_shade`: what follows the tiles (the depth view's normalisation); tiles write
    /// straight into the frame, so there is nothing to copy (wall time).
    pub resolve: Duration,
    /// Pixels shaded (a pixel seeing several triangles through its samples counts once each).
    pub shaded_pixels: usize,
    pub threads: usize,
}

/// Renders `scene`. Never fails; see the module documentation for the invariants.
pub fn render(scene: &Scene, options: &RenderOptions) -> (FrameBuffer, RenderStats) {
    let mut renderer = Renderer::default();
    let stats = renderer.render(scene, options);
    (renderer.framebuffer, stats)
}

/// Renders frame after frame, building each frame in the arrays of the last (see
/// [`geometry::SpareBuffers`]) and into the same frame buffer, so that a stream of frames
/// (`bench`'s) allocates nothing big after the first. The images are [`render`]'s.
#[derive(Default)]
pub struct Renderer {
    spare: geometry::SpareBuffers,
    shadow_buffers: shadow::ShadowBuffers,
    framebuffer: FrameBuffer,
    progress: Arc<RenderProgress>,
}

/// How far the frame under way has got, readable from another thread while it renders (the
/// command line's progress bar). Counting costs one relaxed atomic add per 64×64 tile.
#[derive(Debug, Default)]
pub struct RenderProgress {
    tiles_total: AtomicUsize,
    tiles_done: AtomicUsize,
}

impl RenderProgress {
    /// `(done, total)` tiles of the frame under way; the total is 0 while its geometry is built.
    pub fn tiles(&self) -> (usize, usize) {
        (
            self.tiles_done.load(Ordering::Relaxed),
            self.tiles_total.load(Ordering::Relaxed),
        )
    }

    pub(crate) fn start_geometry(&self) {
        self.tiles_total.store(0, Ordering::Relaxed);
        self.tiles_done.store(0, Ordering::Relaxed);
    }

    pub(crate) fn start_tiles(&self, total: usize) {
        self.tiles_total.store(total, Ordering::Relaxed);
    }

    pub(crate) fn tile_done(&self) {
        self.tiles_done.fetch_add(1, Ordering::Relaxed);
    }
}

impl Renderer {
    /// Renders `scene` into [`Renderer::framebuffer`]. Never fails.
    pub fn render(&mut self, scene: &Scene, options: &RenderOptions) -> RenderStats {
        if let Some(threads) = options.threads
            && let Ok(pool) = rayon::ThreadPoolBuilder::new().num_threads(threads).build()
        {
            return pool.install(|| self.render_in_current_pool(scene, options));
        }
        self.render_in_current_pool(scene, options)
    }

    /// The progress of the frame under way, to watch from another thread.
    pub fn progress(&self) -> Arc<RenderProgress> {
        Arc::clone(&self.progress)
    }

    /// The last frame rendered (empty before the first).
    pub fn framebuffer(&self) -> &FrameBuffer {
        &self.framebuffer
    }

    /// The last frame rendered, moved out (the next frame gets a new frame buffer).
    pub fn take_framebuffer(&mut self) -> FrameBuffer {
        std::mem::take(&mut self.framebuffer)
    }

    /// Gives back a frame buffer taken earlier, for the next frame to reuse if its size fits.
    pub fn reuse_framebuffer(&mut self, framebuffer: FrameBuffer) {
        self.framebuffer = framebuffer;
    }

    fn render_in_current_pool(&mut self, scene: &Scene, options: &RenderOptions) -> RenderStats {
        let (stats, mut frame) = render_frame(
            scene,
            options,
            &mut self.spare,
            &mut self.shadow_buffers,
            &mut self.framebuffer,
            &self.progress,
        );
        self.shadow_buffers.keep(std::mem::take(&mut frame.shadows));
        self.spare.keep(frame);
        stats
    }
}

fn render_frame(
    scene: &Scene,
    options: &RenderOptions,
    spare: &mut geometry::SpareBuffers,
    shadow_buffers: &mut shadow::ShadowBuffers,
    framebuffer: &mut FrameBuffer,
    progress: &RenderProgress,
) -> (RenderStats, frame::Frame) {
    let started = Instant::now();
    progress.start_geometry();
    let pattern = raster::SamplePattern::new(scene.image.samples).unwrap_or(raster::SamplePattern::SINGLE);
    let shadows = shadow::render_shadow_maps(scene, scene.camera.eye, shadow_buffers, spare);
    let shadow_time = started.elapsed();
    let shadow_faces = shadows.iter().flatten().map(|map| map.face_count()).sum();
    let started = Instant::now();
    let frame = geometry::build_frame_in(scene, pattern, options.debug_view, shadows, spare);
    let tiles = frame.tiles;
    // Binning is done by the geometry stage's chunks, in parallel with the rest of their work.
    let geometry_time = started.elapsed();

    // Each band of tile rows is rendered straight into its own slice of the frame, tile after
    // tile. No tile image is kept and nothing is copied afterwards.
    let started = Instant::now();
    framebuffer.start_frame(tiles.width, tiles.height, scene.image.background);
    progress.start_tiles(tiles.columns as usize * tiles.rows as usize);
    // Debug builds only: a seam that makes the worker threads panic, for the end-to-end test of
    // how a bug is reported (exit code 101, nothing written; tests/suite/robustness.rs).
    #[cfg(debug_assertions)]
    let simulate_panic = std::env::var_os("LAMPSHADE_SIMULATE_PANIC").is_some();
    let bands: Vec<Mutex<Option<framebuffer::Band>>> = framebuffer
        .bands_mut()
        .map(|band| Mutex::new(Some(band)))
        .collect();
    let queue = BandQueue::new(&frame, bands.len());
    let band_results: Vec<Mutex<BandTimes>> = bands.iter().map(|_| Mutex::default()).collect();
    // Every worker takes the next band from the queue until it is empty; a band's pixels do not
    // depend on which worker renders it, so the image is the same for any thread count and any
    // timing.
    let work_through_the_queue = || {
        let mut scratch = shade::TileScratch::default();
        let mut visibility = raster::Visibility::new();
        while let Some(tile_row) = queue.next() {
            #[cfg(debug_assertions)]
            if simulate_panic {
                panic!("simulated bug in band {tile_row} (LAMPSHADE_SIMULATE_PANIC)");
            }
            let Some(mut band) = lock(&bands[tile_row]).take() else {
                continue; // the queue hands out each band once
            };
            let mut times = BandTimes::default();
            for column in 0..tiles.columns as usize {
                let index = tile_row * tiles.columns as usize + column;
                let rect = tiles.rect(index);
                let raster_started = Instant::now();
                // A tile no triangle reaches stays blank (the frame buffer's flag, set for every
                // tile when the frame starts): none of its pixels is written, and its visibility
                // buffers (128 KiB at four samples) are neither cleared nor read.
                let empty = frame
                    .raster
                    .iter()
                    .all(|chunk| chunk.tile_triangles(index).is_empty());
                if !empty {
                    visibility.rasterize(rect, pattern, &frame.raster, index);
                }
                let shade_started = Instant::now();
                if !empty {
                    band.blank[column] = false;
                    times.shaded += shade::shade_tile(
                        &frame,
                        &visibility,
                        scene.image.background,
                        &mut band.tile(column),
                        &mut scratch,
                    );
                }
                times.raster += shade_started - raster_started;
                times.shade += shade_started.elapsed();
                progress.tile_done();
            }
            *lock(&band_results[tile_row]) = times;
        }
    };
    // One worker per pool thread, the calling thread among them. Spawned in a scope rather than
    // broadcast: a broadcast waits until every thread of the pool has run its share, so inside
    // `check`'s pool (one render per thread) each render would wait for the others to finish,
    // and a thread waiting for it would start other scenes meanwhile; a scope's jobs that no
    // other thread has taken are run by the caller itself (they find the queue empty).
    rayon::in_place_scope(|scope| {
        for _ in 1..rayon::current_num_threads() {
            scope.spawn(|_| work_through_the_queue());
        }
        work_through_the_queue();
    });
    let band_results: Vec<BandTimes> = band_results
        .into_iter()
        .map(|times| {
            times
                .into_inner()
                .unwrap_or_else(|poisoned| poisoned.into_inner())
        })
        .collect();
    let resolve_started = Instant::now();
    let raster_thread_time = band_results.iter().map(|band| band.raster).sum();
    let shade_thread_time = band_results.iter().map(|band| band.shade).sum();
    let shaded_pixels = band_results.iter().map(|band| band.shaded).sum();
    if options.debug_view == Some(DebugView::Depth) {
        framebuffer.normalize_depth();
    }
    let stats = RenderStats {
        triangles: scene.triangle_count(),
        raster_triangles: frame.raster_triangle_count(),
        shadow_maps: shadow_time,
        shadow_faces,
        geometry: geometry_time,
        raster_shade: started.elapsed(),
        raster_thread_time,
        shade_thread_time,
        resolve: resolve_started.elapsed(),
        shaded_pixels,
        threads: rayon::current_num_threads(),
    };
    (stats, frame)
}

/// What rendering one band took, summed over its tiles.
#[derive(Debug, Default, Clone, Copy)]
struct BandTimes {
    raster: Duration,
    shade: Duration,
    shaded: usize,
}

/// The bands of a frame in the order workers take them: the most work first (longest
/// processing time first), so that the last bands taken are short and no core waits long for
/// another to finish. A band's work is estimated from its bins: the triangles binned into its
/// tiles, plus a tile's worth for each tile (clearing and resolving cost something even when
/// empty). Ties keep the top-to-bottom order, so the order depends only on the frame.
struct BandQueue {
    order: Vec<usize>,
    next: AtomicUsize,
}

impl BandQueue {
    fn new(frame: &frame::Frame, bands: usize) -> Self {
        let columns = frame.tiles.columns as usize;
        let per_tile_floor = 16;
        let work = |band: usize| -> usize {
            (band * columns..(band + 1) * columns)
                .map(|tile| {
                    per_tile_floor
                        + frame
                            .raster
                            .iter()
                            .map(|chunk| chunk.tile_triangles(tile).len())
                            .sum::<usize>()
                })
                .sum()
        };
        let mut order: Vec<usize> = (0..bands).collect();
        order.sort_by_cached_key(|&band| std::cmp::Reverse(work(band)));
        BandQueue {
            order,
            next: AtomicUsize::new(0),
        }
    }

    /// The next band to render, `None` once every band has been handed out.
    fn next(&self) -> Option<usize> {
        self.order.get(self.next.fetch_add(1, Ordering::Relaxed)).copied()
    }
}

/// The value behind `mutex`, whether or not a worker panicked holding it (the panic is
/// re-raised by the scope anyway).
fn lock<T>(mutex: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    mutex.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}
