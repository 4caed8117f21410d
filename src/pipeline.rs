//! One scene file, loaded and rendered: the build that `render`, `check` and `watch` share.
//!
//! Writing the image is left to the caller (each command writes it differently: beside the
//! scene, nowhere, or atomically on every save), so this stage does no output I/O.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

use crate::diag::{Diagnostic, Sources};
use crate::render::{FrameBuffer, RenderOptions, RenderStats, Renderer};
use crate::scene::load::{LoadError, LoadOptions, MeshCache, load_scene_cached};
use crate::scene::{Camera, Scene};

/// A scene file that loaded and rendered.
#[derive(Debug, Clone)]
pub struct RenderedScene {
    /// The scene as loaded and rendered (command-line overrides applied), kept so that the
    /// image's pixels can be inspected afterwards (`inspect`).
    pub scene: Arc<Scene>,
    pub framebuffer: FrameBuffer,
    pub stats: RenderStats,
    /// Reading, parsing, checking and mesh loading.
    pub load_time: Duration,
    pub warnings: Vec<Diagnostic>,
    pub sources: Sources,
    /// Every file the scene read (scene, includes, meshes and what they reference).
    pub files_read: Vec<PathBuf>,
    /// The camera the image was rendered with.
    pub camera: Camera,
}

/// What one build keeps for the next: the meshes whose files have not changed, and the
/// renderer's frame arrays (a re-render of the same scene, as in watch mode, builds its frame in
/// the last one's memory instead of allocating and faulting in hundreds of megabytes again).
#[derive(Default)]
pub struct BuildCache {
    pub meshes: MeshCache,
    pub renderer: Renderer,
}

/// Loads `path` and renders it, reusing what `cache` kept from earlier builds.
pub fn render_scene_file(
    path: &Path,
    load_options: &LoadOptions,
    render_options: &RenderOptions,
    cache: &mut BuildCache,
) -> Result<RenderedScene, LoadError> {
    let started = Instant::now();
    let loaded = load_scene_cached(path, load_options, &mut cache.meshes)?;
    let load_time = started.elapsed();
    let stats = cache.renderer.render(&loaded.scene, render_options);
    Ok(RenderedScene {
        camera: loaded.scene.camera,
        scene: Arc::new(loaded.scene),
        framebuffer: cache.renderer.take_framebuffer(),
        stats,
        load_time,
        warnings: loaded.warnings,
        sources: loaded.sources,
        files_read: loaded.files_read,
    })
}
