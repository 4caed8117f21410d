//! Limits, and the memory estimate that lets the loader refuse a scene before rendering it
//! would exhaust memory.
//!
//! The estimate is made at load time, from what the scene asks for, before the big buffers
//! exist: a built-in sphere is sized from its segment count before it is generated, a mesh
//! file from its size before it is parsed, and the whole render (image, shadow maps, the
//! transformed geometry of every object) once the meshes are known, before `render` runs.
//! Byte counts come from the renderer's own types (`size_of`), so they follow the code; what
//! they do not itemise (the allocator's rounding, per-tile buffers, loaders' temporaries) is
//! covered by a share of the rest and a fixed amount for the process, so that the estimate is
//! at least the process's real peak: `tests/memory.rs` measures it for scenes of each kind.
//! A scene over the budget is a located error naming the biggest part and the flag that
//! raises the budget, `--max-memory`.

use std::mem::size_of;

use glam::{Vec2, Vec3, Vec4};

use std::sync::atomic::AtomicBool;

use crate::render::TILE_SIZE;
use crate::render::frame::{FrameVertex, VertexAttributes};
use crate::render::geometry::{ProjectedVertex, TRIANGLE_CHUNK};
use crate::render::raster::RasterTriangle;
use crate::scene::{ImageSettings, Light, Object};

/// How far from the origin objects may reach (world units, after their transforms). The
/// renderer works in `f32` eye-relative coordinates and squares distances: at 10¹⁵ a square is
/// 10³⁰, far from `f32`'s 3.4·10³⁸, while a sphere scaled by 10³⁷ gave NaN pixels (found by
/// the `render` fuzz target). Scenes translated by 10⁶ (issue 6) are well inside.
pub const MAX_WORLD_EXTENT: f64 = 1e15;

/// The largest colour component, material coefficient (`ka`, `kd`, `ks`) and light intensity a
/// scene may give. Lighting is `f32`: a coefficient times a light's colour × intensity × an
/// attenuation (at most 10⁶, [`crate::lighting::MIN_ATTENUATION_DENOMINATOR`]) stays below
/// 10³⁰ under this bound, so no product overflows and no `∞ · 0` turns a pixel NaN (`ks` 8.6·10²⁹
/// with an intensity of 1.9·10²⁹ did, found by the `render` fuzz target). Far above what any
/// pixel can show: a value of 10⁶ already saturates to white under a light of 10⁻⁶.
pub const MAX_LIGHTING_VALUE: f64 = 1e6;

/// The memory a render may need when `--max-memory` is not given: the largest image
/// (16384 × 16384, 4.75 GiB) with a few million triangles, or some 30 million triangles at a
/// usual size. A scene above it is almost certainly a typo (an extra zero in a size or a
/// segment count); one that means it raises the budget.
pub const DEFAULT_MEMORY_BUDGET: u64 = 12 << 30;

/// Bytes per image pixel: the frame buffer's colour and coverage, the 8-bit image handed to
/// the encoder, and the encoder's filtered rows and output (at most the image again).
pub const BYTES_PER_PIXEL: u64 = (size_of::<Vec3>() + size_of::<bool>() + 2 * 3) as u64;

/// Bytes per vertex of a mesh: the mesh's arrays (positions, normals, UVs, second UVs,
/// colours, tangents; the optional ones counted as present) and what the renderer keeps per
/// vertex for a frame: the transformed vertex, its colours lit per vertex (plain and for
/// textures), its attributes, its projection, and whether a triangle uses it.
pub const BYTES_PER_VERTEX: u64 = (2 * size_of::<Vec3>()
    + 2 * size_of::<Vec2>()
    + 2 * size_of::<Vec4>()
    + size_of::<FrameVertex>()
    + 2 * size_of::<Vec3>()
    + size_of::<VertexAttributes>()
    + size_of::<ProjectedVertex>()
    + size_of::<AtomicBool>()) as u64;

/// Bytes per triangle: the mesh's indices and material index, one raster triangle (a shadow
/// map's depth frame culls nothing, so every triangle may have one; clipping rarely makes
/// more; it carries its frame triangle), and its entries in two tiles' bins.
pub const BYTES_PER_TRIANGLE: u64 =
    (size_of::<[u32; 3]>() + size_of::<u32>() + size_of::<RasterTriangle>() + 2 * size_of::<u32>()) as u64;

/// What the estimate does not itemise, as a share of what it does (one part in this many):
/// the allocator's rounding and the memory it keeps, per-tile buffers, the mesh loaders'
/// temporary arrays, clipped triangles. `tests/memory.rs` measures the peak of scenes of
/// each kind against the estimate.
pub const UNITEMISED_SHARE: u64 = 8;

/// The process itself: code, thread stacks, the thread pool, small allocations.
pub const PROCESS_BYTES: u64 = 48 << 20;

/// Parsing a mesh file holds the text, the parser's arrays and the baked mesh at once: about
/// this many bytes of memory per byte of file, at worst (an OBJ face line `f 1 2 3` is 8 bytes
/// and becomes a triangle of about `BYTES_PER_TRIANGLE` bytes plus the parser's copy).
pub const MESH_FILE_EXPANSION: u64 = 64;

/// The memory a part of the scene needs, for the error message.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct MemoryEstimate {
    pub image: u64,
    pub shadow_maps: u64,
    pub geometry: u64,
    /// The process, and what the parts above do not itemise ([`UNITEMISED_SHARE`]).
    pub other: u64,
}

impl MemoryEstimate {
    pub fn total(&self) -> u64 {
        self.image
            .saturating_add(self.shadow_maps)
            .saturating_add(self.geometry)
            .saturating_add(self.other)
    }

    /// "image 7.5 GiB, shadow maps 0 B, geometry 1.2 GiB, other 2.2 GiB".
    pub fn parts(&self) -> String {
        format!(
            "image {}, shadow maps {}, geometry {}, other {}",
            human_bytes(self.image),
            human_bytes(self.shadow_maps),
            human_bytes(self.geometry),
            human_bytes(self.other)
        )
    }
}

/// What rendering a scene of this image, these lights and these objects needs, at most.
pub fn scene_memory(image: &ImageSettings, lights: &[Light], objects: &[Object]) -> MemoryEstimate {
    let shadow_faces: Vec<(u32, bool)> = lights
        .iter()
        .filter_map(|light| Some((light.shadow()?.resolution, matches!(light, Light::Point { .. }))))
        .collect();
    // The largest face rendered, which is the side of its map (half of it for a cube's face):
    // its tile grid's bins count like the image's.
    let largest_face = shadow_faces
        .iter()
        .map(|&(resolution, cube)| if cube { resolution / 2 } else { resolution })
        .max()
        .unwrap_or(0);
    // A map is rendered straight into its own depths (see `render::shadow`); the depth-only
    // pass's working arrays (per-block depth bounds, the back faces it defers, arrays kept for
    // the next frame) are bounded by one more face of the largest size (tests/memory.rs holds
    // the estimate above the measured peak).
    let shadow_maps = shadow_faces
        .iter()
        .map(|&(resolution, cube)| shadow_map_bytes(resolution, cube))
        .fold(0, u64::saturating_add)
        .saturating_add(if shadow_faces.is_empty() {
            0
        } else {
            shadow_map_bytes(largest_face, false)
        });
    let triangles: u64 = objects
        .iter()
        .map(|object| object.mesh.triangle_count() as u64)
        .sum();
    let geometry = objects
        .iter()
        .map(|object| {
            mesh_bytes(
                object.mesh.positions.len() as u64,
                object.mesh.triangle_count() as u64,
            )
        })
        .fold(0, u64::saturating_add)
        .saturating_add(bin_bytes(
            triangles,
            image.width.max(largest_face),
            image.height.max(largest_face),
        ));
    let mut estimate = MemoryEstimate {
        image: image_bytes(image.width, image.height),
        shadow_maps,
        geometry,
        other: 0,
    };
    estimate.other = PROCESS_BYTES.saturating_add(estimate.total() / UNITEMISED_SHARE);
    estimate
}

/// The bins' tile tables: every chunk of the triangle stream has an offset per tile.
pub fn bin_bytes(triangles: u64, width: u32, height: u32) -> u64 {
    let tiles = u64::from(width.div_ceil(TILE_SIZE)) * u64::from(height.div_ceil(TILE_SIZE)) + 1;
    let chunks = triangles.div_ceil(TRIANGLE_CHUNK as u64);
    chunks
        .saturating_mul(tiles)
        .saturating_mul(size_of::<u32>() as u64)
}

/// Memory for the image itself (independent of the samples per pixel: samples live in
/// per-tile buffers only).
pub fn image_bytes(width: u32, height: u32) -> u64 {
    u64::from(width) * u64::from(height) * BYTES_PER_PIXEL
}

/// Memory for a shadow map of `resolution` texels a side: one `f32` depth per texel; a point
/// light's six cube faces have half the resolution each (1.5 times one face).
pub fn shadow_map_bytes(resolution: u32, cube: bool) -> u64 {
    let face = u64::from(resolution) * u64::from(resolution) * size_of::<f32>() as u64;
    if cube { face * 3 / 2 } else { face }
}

/// Memory for drawing a mesh of this size once.
pub fn mesh_bytes(vertices: u64, triangles: u64) -> u64 {
    vertices
        .saturating_mul(BYTES_PER_VERTEX)
        .saturating_add(triangles.saturating_mul(BYTES_PER_TRIANGLE))
}

/// Vertices and triangles of MATLAB's `sphere(n)`: an (n + 1)² grid, 2n² triangles.
pub fn sphere_size(segments: u32) -> (u64, u64) {
    let n = u64::from(segments);
    ((n + 1) * (n + 1), 2 * n * n)
}

/// Parses a size for `--max-memory`: bytes, or a number with `K`, `M`, `G` or `T` (powers of
/// 1024, an optional `B` or `iB` after them): `512M`, `1.5G`, `8GiB`.
pub fn parse_memory_size(text: &str) -> Result<u64, String> {
    let trimmed = text.trim();
    let upper = trimmed.to_ascii_uppercase();
    let without_b = upper
        .strip_suffix("IB")
        .or_else(|| upper.strip_suffix('B'))
        .unwrap_or(&upper);
    let (number, scale) = match without_b.chars().last() {
        Some('K') => (&without_b[..without_b.len() - 1], 1u64 << 10),
        Some('M') => (&without_b[..without_b.len() - 1], 1 << 20),
        Some('G') => (&without_b[..without_b.len() - 1], 1 << 30),
        Some('T') => (&without_b[..without_b.len() - 1], 1 << 40),
        _ => (without_b, 1),
    };
    let value: f64 = number.trim().parse().map_err(|_| {
        format!("`{text}` is not a size: write bytes or a number with K, M, G or T (`512M`, `16G`)")
    })?;
    let bytes = value * scale as f64;
    if !bytes.is_finite() || bytes < 1.0 || bytes >= u64::MAX as f64 {
        return Err(format!("`{text}` is not a usable memory size"));
    }
    Ok(bytes as u64)
}

/// `8589934592` → `8.0 GiB`.
pub fn human_bytes(bytes: u64) -> String {
    const UNITS: [&str; 5] = ["B", "KiB", "MiB", "GiB", "TiB"];
    let mut value = bytes as f64;
    let mut unit = 0;
    while value >= 1024.0 && unit + 1 < UNITS.len() {
        value /= 1024.0;
        unit += 1;
    }
    if unit == 0 {
        format!("{bytes} B")
    } else {
        format!("{value:.1} {}", UNITS[unit])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse_with_binary_units() {
        assert_eq!(parse_memory_size("512M"), Ok(512 << 20));
        assert_eq!(parse_memory_size("16G"), Ok(16 << 30));
        assert_eq!(parse_memory_size("8GiB"), Ok(8 << 30));
        assert_eq!(parse_memory_size("1.5g"), Ok(3 << 29));
        assert_eq!(parse_memory_size("1000"), Ok(1000));
        for bad in ["", "G", "-1G", "lots", "0", "1e400"] {
            assert!(parse_memory_size(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn the_largest_image_and_the_largest_sphere_fit_the_default_budget_but_not_together() {
        let max = crate::render::MAX_IMAGE_DIMENSION;
        let image = image_bytes(max, max);
        assert!(image < DEFAULT_MEMORY_BUDGET);
        let (vertices, triangles) = sphere_size(crate::scene::load::MAX_SPHERE_SEGMENTS);
        assert_eq!(triangles, 33_554_432);
        let sphere = mesh_bytes(vertices, triangles);
        assert!(sphere < DEFAULT_MEMORY_BUDGET);
        assert!(image + sphere > DEFAULT_MEMORY_BUDGET);
        // The bundled scenes' `Sphere(segments: 180)` is far below it.
        let (vertices, triangles) = sphere_size(180);
        assert!(mesh_bytes(vertices, triangles) < DEFAULT_MEMORY_BUDGET / 100);
    }

    #[test]
    fn human_sizes() {
        assert_eq!(human_bytes(512), "512 B");
        assert_eq!(human_bytes(8 << 30), "8.0 GiB");
        assert_eq!(human_bytes(3 << 19), "1.5 MiB");
    }
}
