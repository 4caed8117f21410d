//! The exact reference: a second renderer beside the pipeline, in `f64`, of what the
//! rasterizer's image converges to. It shares only the scene, the camera (the rasterizer's own
//! clip matrix) and the lighting equations (their `f64` transcription, [`exact_lighting`]);
//! [`crate::metrics`] measures the rasterizer against it.
//!
//! What is exact, and what is the same as the rasterizer:
//! - **Analytic shapes.** `Sphere(N)` is the true unit sphere (whatever `N`), `Plane` the true
//!   square, `Cube` the true cube, each under the object's transform ([`analytic`]), so
//!   tessellation error stays measurable. With [`ReferenceGeometry::Mesh`] (`--reference=mesh`)
//!   they are ray-cast as their tessellation instead, which separates tessellation from
//!   rasterization error. A textured primitive is always its tessellation (the texture lives on
//!   its vertices' coordinates); a note says so.
//! - **Meshes.** Every other object's own triangles, in one BVH ([`mesh`], [`bvh`]), hit in
//!   `f64`; normals, texture coordinates, vertex colours and tangents interpolated from the
//!   exact barycentrics (perspective-correct by construction).
//! - **Camera.** Each sample's ray runs from the near plane to the far plane through the
//!   inverse of the rasterizer's own clip matrix (`render::geometry::CameraSetup`), so
//!   projection, aspect ratio, pixel centres (`x + ½`) and clipping at `near` and `far` match.
//!   Rays are parameterised by `t ∈ [0, 1]` from near to far, which is the visible range.
//! - **Samples.** By default the rasterizer's own sample pattern, every sample shaded (true
//!   supersampling), the pixel the mean of its samples, background included, as
//!   `render::shade::shade_tile` averages. With [`ReferenceOptions::samples`] `= N`
//!   (`--reference-samples N`): N×N stratified samples (one jittered point per cell of an N×N
//!   grid over the pixel, the jitter a hash of pixel and cell, so the image is the same on every
//!   run), the ideal box filter that anti-aliasing approximates.
//! - **Visibility.** The nearest hit wins, the first object (then triangle) on a tie, like the
//!   rasterizer's strict depth test in submission order; back faces (`N·D > 0` for the ray
//!   direction `D` and the geometric normal `N`) follow the object's `back_faces` mode, `Cull`
//!   skipping them.
//! - **Shadows.** For every shadow-casting light, a shadow ray from the point to the light
//!   (towards it, for a directional light) against every object, both faces: the exact
//!   visibility (0 or 1) that shadow maps, their bias and PCF approximate. The ray starts
//!   10⁻⁹ of the scene's size off the surface, along the geometric normal on the light's side,
//!   and ignores the hit triangle itself. A mesh therefore shadows itself facet by facet where
//!   its interpolated normal faces the light and its flat triangles do not (the "shadow
//!   terminator"): that is the limit of a shadow map as its resolution grows and its bias
//!   shrinks, and the bias that hides it is part of what the reference measures.
//! - **Textures.** Level 0, bilinear, in `f64` ([`surface`]); with the rasterizer's sample
//!   pattern, each sample's texels are the mean over a [`ReferenceOptions::texture_samples`]²
//!   grid over the pixel (16×16 by default) on the plane of the hit triangle (extended past its
//!   edges, as the rasterizer's footprint is): the texel footprint integrated, which mipmapping
//!   approximates. With N×N samples each sample reads its own point (the samples integrate).
//!   Normal maps are read at the sample's point.
//! - **Lighting.** [`exact_lighting`], the `f64` transcription of [`crate::lighting`], with every
//!   light type, attenuation, spot, every model, emission, the object's `component`, colour
//!   textures and vertex colours as the rasterizer's Phong shading applies them. The shading
//!   mode is ignored: the reference is the limit every mode approaches as the mesh and the
//!   pixels get finer (per-sample lighting of the interpolated normal, Nlerp or Slerp as the
//!   object asks).
//!
//! - **What the samples saw.** With [`ReferenceOptions::features`], each pixel also keeps
//!   [`PixelFeatures`]: per shadow-casting light whether some sample's shadow ray was blocked
//!   and whether some reached the light, the mean specular luminance, and whether a texture
//!   colours it; `metrics::regions` finds shadow edges, highlight peaks and texture detail
//!   from them.
//!
//! The image is the same for any thread count: every pixel is computed on its own.

pub mod analytic;
pub mod bvh;
pub mod exact_lighting;
pub mod mesh;
pub mod surface;

use std::cell::{Cell, OnceCell, RefCell};
use std::path::Path;
use std::sync::Arc;
use std::time::{Duration, Instant};

use glam::{DVec2, DVec3, DVec4, Vec3};
use rayon::prelude::*;

use crate::diag::Diagnostic;
use crate::pipeline::RenderedScene;
use crate::render::frame::Viewer;
use crate::render::geometry::CameraSetup;
use crate::render::raster::SamplePattern;
use crate::render::{FrameBuffer, RenderProgress, RenderStats};
use crate::scene::limits::{DEFAULT_MEMORY_BUDGET, human_bytes};
use crate::scene::load::{LoadError, LoadOptions, load_scene};
use crate::scene::locate::{PathSegment, locate};
use crate::scene::{BackFaces, LightingComponent, Material, Scene, TextureBinding, bounding_sphere};
use analytic::Surface;
pub use analytic::{Shape, recognize_shape, recognize_textured_shape};
use exact_lighting::{ExactLight, ExactLightKind, illuminate_exact_with_visibility};
use mesh::{MeshHit, MeshObject, MeshTriangles};
use surface::{bilinear_level0, perturb_normal};

/// The arithmetic of the reference's lighting (the geometry is always `f64`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum LightingPrecision {
    /// [`exact_lighting`]: the reference proper.
    #[default]
    F64,
    /// The renderer's own [`crate::lighting`] in `f32`, at the exact point and normal (rounded
    /// to `f32`, eye-relative as the renderer has them): measures what `f32` lighting costs.
    F32,
}

/// What the analytic primitives are ray-cast as.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum ReferenceGeometry {
    /// Their true shapes (`--reference`).
    #[default]
    Exact,
    /// Their tessellation, like every mesh (`--reference=mesh`).
    Mesh,
}

/// Texels averaged per pixel side by default: 16×16 bilinear lookups at level 0.
pub const DEFAULT_TEXTURE_SAMPLES: u32 = 16;

/// The largest N of N×N samples per pixel, and of the texture grid.
pub const MAX_REFERENCE_SAMPLES: u32 = 64;

/// How the reference renders.
#[derive(Debug, Clone)]
pub struct ReferenceOptions {
    /// Worker threads (default: rayon's pool, one per core).
    pub threads: Option<usize>,
    pub precision: LightingPrecision,
    pub geometry: ReferenceGeometry,
    /// N for N×N stratified samples per pixel; `None`: the rasterizer's sample pattern.
    pub samples: Option<u32>,
    /// N for the N×N texel footprint grid (with the rasterizer's sample pattern).
    pub texture_samples: u32,
    /// Counts 64×64 tiles as they finish, for a progress bar.
    pub progress: Option<Arc<RenderProgress>>,
    /// Keep what each pixel's samples saw ([`Reference::features`]).
    pub features: bool,
}

impl Default for ReferenceOptions {
    fn default() -> Self {
        ReferenceOptions {
            threads: None,
            precision: LightingPrecision::F64,
            geometry: ReferenceGeometry::Exact,
            samples: None,
            texture_samples: DEFAULT_TEXTURE_SAMPLES,
            progress: None,
            features: false,
        }
    }
}

/// Something the reference did differently from what the scene suggests, for one object.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ReferenceNote {
    /// Index in the scene's objects.
    pub object: usize,
    /// The object's field it concerns, where a diagnostic points.
    pub field: &'static str,
    pub message: String,
}

/// A rendered reference and its notes.
#[derive(Debug, Clone)]
pub struct Reference {
    pub framebuffer: FrameBuffer,
    pub notes: Vec<ReferenceNote>,
    /// Preparing the geometry: the triangles in world space and their BVH (wall time).
    pub build_time: Duration,
    /// Casting and shading every pixel's rays (wall time).
    pub cast_time: Duration,
    /// Per pixel, row-major, what its samples saw: with [`ReferenceOptions::features`] only,
    /// empty otherwise.
    pub features: Vec<PixelFeatures>,
}

/// What the samples of one pixel saw, beyond its colour: what the error "where it matters"
/// (`metrics::regions`) is measured over.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct PixelFeatures {
    /// Bit `i mod 64` set when a sample facing shadow-casting light `i`, within its reach, had
    /// its shadow ray blocked.
    pub shadowed: u64,
    /// The same where the shadow ray reached the light.
    pub lit: u64,
    /// The specular term's luminance (Rec. 709 weights, linear), the mean over the pixel's
    /// samples with the background as 0.
    pub specular: f32,
    /// Some sample hit a surface whose colour a texture multiplies.
    pub textured: bool,
}

/// The luminance of a linear RGB colour (Rec. 709 weights).
pub fn luminance(color: DVec3) -> f64 {
    color.dot(DVec3::new(0.2126, 0.7152, 0.0722))
}

/// What one sample saw, summed into its pixel's [`PixelFeatures`].
#[derive(Default)]
struct SampleRecord {
    shadowed: Cell<u64>,
    lit: Cell<u64>,
    specular: Cell<f64>,
    textured: Cell<bool>,
}

impl SampleRecord {
    fn visibility(&self, light: usize, visible: f64) {
        let bit = 1u64 << (light % 64);
        let seen = if visible > 0.0 { &self.lit } else { &self.shadowed };
        seen.set(seen.get() | bit);
    }
}

/// The side of a 64×64 tile, the unit of work and of progress.
const TILE: u32 = 64;

/// The shadow ray's start off the surface, relative to the scene's size.
const SHADOW_OFFSET: f64 = 1e-9;

/// A ray's nearest visible hit.
enum Hit {
    Analytic {
        surface: usize,
        /// World-space unit normal on the outside of the shape.
        normal: DVec3,
    },
    Mesh(MeshHit),
}

/// A hit and where it is along the ray.
struct Nearest {
    t: f64,
    hit: Hit,
}

/// A surface point ready to light.
struct SurfacePoint {
    position: DVec3,
    /// Unit geometric normal of the front side.
    face_normal: DVec3,
    /// Unit shading normal of the front side.
    normal: DVec3,
    back_facing: bool,
    material: Material,
    back_faces: BackFaces,
    component: LightingComponent,
    /// The mesh triangle hit (a shadow ray ignores it).
    triangle: Option<usize>,
}

/// One pixel's texel footprint: the rays of its grid, made when a sample first needs them, and
/// the mean texels found so far. The mean depends only on the pixel, the triangle and the
/// texture, so samples of the pixel that hit the same triangle share it.
#[derive(Default)]
struct PixelFootprint {
    px: u32,
    py: u32,
    rays: OnceCell<Vec<(DVec3, DVec3)>>,
    /// ((triangle, texture slot: 0 colour, 1 ambient), mean texel).
    texels: RefCell<Vec<((usize, u8), DVec4)>>,
}

/// What the reference renders: the scene with its camera and lights, and its geometry.
struct ReferenceScene<'a> {
    scene: &'a Scene,
    surfaces: Vec<Surface>,
    meshes: MeshTriangles,
    lights: Vec<ExactLight>,
    lights_f32: Vec<crate::lighting::ShadingLight>,
    /// Per light, whether it casts shadows.
    casts_shadow: Vec<bool>,
    /// The length of a shadow ray towards a directional light: past everything from anywhere.
    directional_reach: f64,
    /// How far a shadow ray starts off the surface.
    shadow_offset: f64,
    precision: LightingPrecision,
    /// From NDC (x, y, depth) to eye-relative world space.
    world_from_clip: glam::DMat4,
    /// `V` for an orthographic camera (the viewer at infinity, in `f64`); `None` for a
    /// perspective one, where `V` points to the eye.
    infinite_viewer: Option<DVec3>,
    /// The sample positions within a pixel, from its top-left corner, when they are the same
    /// for every pixel (the rasterizer's pattern); `None` for jittered strata.
    pattern: Option<Vec<DVec2>>,
    strata: u32,
    texture_grid: u32,
}

impl ReferenceScene<'_> {
    /// The ray through the screen point (`x`, `y`) in pixels: origin on the near plane and
    /// the step to the far plane.
    fn ray(&self, x: f64, y: f64) -> (DVec3, DVec3) {
        let (width, height) = (
            f64::from(self.scene.image.width),
            f64::from(self.scene.image.height),
        );
        let ndc_x = x / width * 2.0 - 1.0;
        let ndc_y = 1.0 - y / height * 2.0;
        let unproject = |depth: f64| {
            let p = self.world_from_clip * DVec4::new(ndc_x, ndc_y, depth, 1.0);
            p.truncate() / p.w
        };
        // Reversed Z: depth 1 is the near plane, 0 the far plane.
        let origin = unproject(1.0);
        (origin, unproject(0.0) - origin)
    }

    /// The nearest visible hit of a camera ray.
    fn trace(&self, origin: DVec3, direction: DVec3) -> Option<Nearest> {
        let mut nearest: Option<Nearest> = None;
        for (index, surface) in self.surfaces.iter().enumerate() {
            surface.intersect(origin, direction, |t, model_normal| {
                if nearest.as_ref().is_some_and(|hit| hit.t <= t) {
                    return; // strictly nearer only: the first object wins a tie
                }
                let normal = surface.world_normal(model_normal);
                let back_facing = normal.dot(direction) > 0.0;
                if back_facing && surface.back_faces == BackFaces::Cull {
                    return;
                }
                nearest = Some(Nearest {
                    t,
                    hit: Hit::Analytic {
                        surface: index,
                        normal,
                    },
                });
            });
        }
        if !self.meshes.is_empty() {
            let (t_max, key) = match &nearest {
                Some(Nearest {
                    t,
                    hit: Hit::Analytic { surface, .. },
                }) => (*t, u64::from(self.surfaces[*surface].object) << 32),
                _ => (1.0, u64::MAX),
            };
            if let Some(hit) = self.meshes.nearest(origin, direction, t_max, key) {
                nearest = Some(Nearest {
                    t: hit.t,
                    hit: Hit::Mesh(hit),
                });
            }
        }
        nearest
    }

    /// The surface at a hit: position, normals, material with its textures and vertex colours.
    fn surface_point(
        &self,
        nearest: &Nearest,
        origin: DVec3,
        direction: DVec3,
        footprint: Option<&PixelFootprint>,
    ) -> SurfacePoint {
        let position = origin + nearest.t * direction;
        match &nearest.hit {
            Hit::Analytic { surface, normal } => {
                let surface = &self.surfaces[*surface];
                SurfacePoint {
                    position,
                    face_normal: *normal,
                    normal: *normal,
                    back_facing: normal.dot(direction) > 0.0,
                    material: surface.material,
                    back_faces: surface.back_faces,
                    component: surface.component,
                    triangle: None,
                }
            }
            Hit::Mesh(hit) => {
                let object = self.meshes.object_of(hit);
                let triangle_number = self.meshes.triangle(hit.triangle).triangle;
                let interpolated = self.meshes.interpolate(hit.triangle, hit.u, hit.v);
                let base = *object.material(triangle_number);
                let mut material = base;
                let tint = self.meshes.tint(hit.triangle, interpolated.weights);
                if tint != DVec3::ONE {
                    material.diffuse = (base.diffuse.as_dvec3() * tint).as_vec3();
                }
                let textures = base.textures;
                // The footprint's corner weights, shared by the material's textures.
                let grid_weights = OnceCell::new();
                let texel = |binding: &TextureBinding, slot: u8| -> DVec4 {
                    let Some(texture) = object.textures.get(binding.texture as usize) else {
                        return DVec4::ONE;
                    };
                    let at = |weights: DVec3| {
                        bilinear_level0(
                            texture,
                            self.meshes.uv(hit.triangle, binding.uv_set, weights),
                            &binding.sampler,
                        )
                    };
                    let Some(footprint) = footprint else {
                        return at(interpolated.weights);
                    };
                    let key = (hit.triangle, slot);
                    if let Some(&(_, mean)) = footprint.texels.borrow().iter().find(|(k, _)| *k == key) {
                        return mean;
                    }
                    let weights: &Vec<DVec3> = grid_weights.get_or_init(|| {
                        let rays = footprint
                            .rays
                            .get_or_init(|| self.footprint_rays(footprint.px, footprint.py));
                        let triangle = self.meshes.triangle(hit.triangle);
                        rays.iter()
                            .filter_map(|&(o, d)| triangle.plane_hit(o, d))
                            .filter(|&(t, u, v)| t > 0.0 && t.is_finite() && u.is_finite() && v.is_finite())
                            .map(|(_, u, v)| DVec3::new(1.0 - u - v, u, v))
                            .collect()
                    });
                    let mean = if weights.is_empty() {
                        at(interpolated.weights)
                    } else {
                        weights.iter().map(|&w| at(w)).sum::<DVec4>() / weights.len() as f64
                    };
                    footprint.texels.borrow_mut().push((key, mean));
                    mean
                };
                if let Some(binding) = textures.diffuse {
                    let color = texel(&binding, 0).truncate();
                    material.diffuse = (material.diffuse.as_dvec3() * color).as_vec3();
                    if textures.ambient.is_none() {
                        material.ambient = (material.ambient.as_dvec3() * color).as_vec3();
                    }
                }
                if let Some(binding) = textures.ambient {
                    material.ambient =
                        (material.ambient.as_dvec3() * texel(&binding, 1).truncate()).as_vec3();
                }
                let mut normal = interpolated.normal;
                if let Some(binding) = textures.normal
                    && let Some(texture) = object.textures.get(binding.texture as usize)
                {
                    let uv = self.meshes.uv(hit.triangle, binding.uv_set, interpolated.weights);
                    let tangent = self.meshes.tangent(hit.triangle, interpolated.weights);
                    let value = bilinear_level0(texture, uv, &binding.sampler).truncate();
                    normal = perturb_normal(normal, tangent, value, f64::from(binding.scale));
                }
                SurfacePoint {
                    position,
                    face_normal: interpolated.face_normal,
                    normal,
                    back_facing: self.meshes.hit_back_facing(hit, direction),
                    material,
                    back_faces: object.back_faces,
                    component: object.component,
                    triangle: Some(hit.triangle),
                }
            }
        }
    }

    /// The rays of the pixel's texel footprint grid: one through the centre of each cell.
    fn footprint_rays(&self, px: u32, py: u32) -> Vec<(DVec3, DVec3)> {
        let n = self.texture_grid;
        let step = 1.0 / f64::from(n);
        (0..n * n)
            .map(|cell| {
                let x = f64::from(px) + (f64::from(cell % n) + 0.5) * step;
                let y = f64::from(py) + (f64::from(cell / n) + 0.5) * step;
                self.ray(x, y)
            })
            .collect()
    }

    /// Whether light `light` reaches `point` unblocked: 1 or 0 (1 for a light without shadows).
    fn visibility(&self, light: usize, point: &SurfacePoint) -> f64 {
        if !self.casts_shadow[light] {
            return 1.0;
        }
        let (to_light, reach) = match self.lights[light].kind {
            ExactLightKind::Directional { to_light } => (to_light, None),
            ExactLightKind::Point { position, .. } | ExactLightKind::Spot { position, .. } => {
                ((position - point.position).normalize_or_zero(), Some(position))
            }
        };
        let side = if point.face_normal.dot(to_light) >= 0.0 {
            1.0
        } else {
            -1.0
        };
        let origin = point.position + point.face_normal * (side * self.shadow_offset);
        let (direction, t_max) = match reach {
            Some(light_position) => (light_position - origin, 1.0),
            None => (to_light * self.directional_reach, 1.0),
        };
        let blocked_by_shape = self.surfaces.iter().any(|surface| {
            let mut blocked = false;
            surface.intersect(origin, direction, |t, _| blocked |= t > 0.0 && t < t_max);
            blocked
        });
        if blocked_by_shape
            || self
                .meshes
                .occluded(origin, direction, 0.0, t_max, point.triangle)
        {
            0.0
        } else {
            1.0
        }
    }

    /// The colour of the sample at the screen point (`x`, `y`), or `None` for the background;
    /// what it saw goes into `record`.
    fn shade_sample(
        &self,
        x: f64,
        y: f64,
        footprint: Option<&PixelFootprint>,
        record: &SampleRecord,
    ) -> Option<DVec3> {
        let (origin, direction) = self.ray(x, y);
        let nearest = self.trace(origin, direction)?;
        let point = self.surface_point(&nearest, origin, direction, footprint);
        if point.material.textures.diffuse.is_some() || point.material.textures.ambient.is_some() {
            record.textured.set(true);
        }
        let visibility = |light: usize| {
            let visible = self.visibility(light, &point);
            if self.casts_shadow[light] {
                record.visibility(light, visible);
            }
            visible
        };
        let back_facing = point.back_facing;
        let normal = if back_facing && matches!(point.back_faces, BackFaces::ReverseLit | BackFaces::Cull) {
            -point.normal
        } else {
            point.normal
        };
        let unlit = back_facing && point.back_faces == BackFaces::Unlit;
        let position = point.position;
        let to_viewer = self
            .infinite_viewer
            .unwrap_or_else(|| (-position).normalize_or_zero());
        if self.precision == LightingPrecision::F32 {
            let terms = crate::lighting::illuminate_with_visibility(
                &point.material,
                if unlit { &[] } else { &self.lights_f32 },
                self.scene.ambient_light,
                position.as_vec3(),
                normal.as_vec3(),
                to_viewer.as_vec3(),
                |light, _| visibility(light) as f32,
            );
            record
                .specular
                .set(record.specular.get() + luminance(terms.specular.as_dvec3()));
            let (textured, rest) =
                crate::render::frame::select_component_split(None, point.component, &terms);
            return Some((textured + rest).as_dvec3());
        }
        let terms = illuminate_exact_with_visibility(
            &point.material,
            if unlit { &[] } else { &self.lights },
            self.scene.ambient_light.as_dvec3(),
            position,
            normal,
            to_viewer,
            |light, _| visibility(light),
        );
        record
            .specular
            .set(record.specular.get() + luminance(terms.specular));
        Some(select_exact(point.component, &terms))
    }

    /// One pixel: the mean of its samples, background included; whether any sample hit; what
    /// its samples saw.
    fn shade_pixel(&self, px: u32, py: u32) -> (Vec3, bool, PixelFeatures) {
        let record = SampleRecord::default();
        let background = self.scene.image.background.as_dvec3();
        let mut sum = DVec3::ZERO;
        let mut covered = false;
        let footprint = PixelFootprint {
            px,
            py,
            ..PixelFootprint::default()
        };
        let mut add = |color: Option<DVec3>| match color {
            Some(color) => {
                sum += color;
                covered = true;
            }
            None => sum += background,
        };
        let corner = DVec2::new(f64::from(px), f64::from(py));
        let count = match &self.pattern {
            Some(offsets) => {
                for offset in offsets {
                    let at = corner + *offset;
                    add(self.shade_sample(at.x, at.y, Some(&footprint), &record));
                }
                offsets.len()
            }
            None => {
                let n = self.strata;
                for cell in 0..n * n {
                    let jitter = stratum_jitter(px, py, cell);
                    let at = corner
                        + (DVec2::new(f64::from(cell % n), f64::from(cell / n)) + jitter) / f64::from(n);
                    add(self.shade_sample(at.x, at.y, None, &record));
                }
                (n * n) as usize
            }
        };
        let features = PixelFeatures {
            shadowed: record.shadowed.get(),
            lit: record.lit.get(),
            specular: (record.specular.get() / count as f64) as f32,
            textured: record.textured.get(),
        };
        ((sum / count as f64).as_vec3(), covered, features)
    }
}

/// A point in the unit square for cell `cell` of pixel (`px`, `py`): SplitMix64 of the three,
/// so strata are jittered but the image is the same on every run.
fn stratum_jitter(px: u32, py: u32, cell: u32) -> DVec2 {
    let mix = |mut z: u64| {
        z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    };
    let seed = mix((u64::from(px) << 40) ^ (u64::from(py) << 16) ^ u64::from(cell));
    let unit = |bits: u64| (bits >> 11) as f64 / (1u64 << 53) as f64;
    DVec2::new(unit(seed), unit(mix(seed)))
}

/// The terms an object shows, in `f64` (the same selection as
/// `render::frame::select_component_split`, which works in `f32`).
fn select_exact(component: LightingComponent, terms: &exact_lighting::ExactTerms) -> DVec3 {
    match component {
        LightingComponent::All => terms.emission + terms.ambient + terms.diffuse + terms.specular,
        LightingComponent::Ambient => terms.ambient,
        LightingComponent::Diffuse => terms.diffuse,
        LightingComponent::Specular => terms.specular,
    }
}

/// Renders the exact reference of `scene` on `threads` workers (default: rayon's pool), with
/// the default options.
pub fn render_reference(scene: &Scene, threads: Option<usize>) -> FrameBuffer {
    render_reference_with(
        scene,
        &ReferenceOptions {
            threads,
            ..ReferenceOptions::default()
        },
    )
    .framebuffer
}

/// Renders the reference of `scene` as `options` ask. Never fails: every object has a
/// reference (its true shape or its triangles).
pub fn render_reference_with(scene: &Scene, options: &ReferenceOptions) -> Reference {
    let run = || render_in_current_pool(scene, options);
    if let Some(threads) = options.threads
        && let Ok(pool) = rayon::ThreadPoolBuilder::new().num_threads(threads).build()
    {
        return pool.install(run);
    }
    run()
}

fn render_in_current_pool(scene: &Scene, options: &ReferenceOptions) -> Reference {
    let started = Instant::now();
    let eye = scene.camera.eye;
    if let Some(progress) = &options.progress {
        progress.start_geometry();
    }
    let mut surfaces = Vec::new();
    let mut mesh_objects = Vec::new();
    let mut notes = Vec::new();
    for (index, object) in scene.objects.iter().enumerate() {
        let shape = match options.geometry {
            ReferenceGeometry::Exact => {
                recognize_shape(&object.mesh).or_else(|| recognize_textured_shape(&object.mesh))
            }
            ReferenceGeometry::Mesh => None,
        };
        let textured = object.material.is_some_and(|m| {
            let t = m.textures;
            t.diffuse.is_some() || t.ambient.is_some() || t.normal.is_some()
        });
        match shape {
            Some(_) if textured => {
                notes.push(ReferenceNote {
                    object: index,
                    field: "material",
                    message: format!(
                        "`{}` is textured: the reference ray-casts its tessellation, not the exact shape, \
                         since its texture coordinates live on the mesh's vertices",
                        object.name
                    ),
                });
                mesh_objects.push(MeshObject::new(index, object, &scene.textures));
            }
            Some(shape) => surfaces.push(Surface::new(index, object, shape, eye)),
            None => mesh_objects.push(MeshObject::new(index, object, &scene.textures)),
        }
    }
    let transforms: Vec<_> = scene.objects.iter().map(|object| object.transform).collect();
    let meshes = MeshTriangles::build(mesh_objects, &transforms, eye);
    let lights: Vec<ExactLight> = scene
        .lights
        .iter()
        .map(|light| ExactLight::new(light, eye))
        .collect();
    let bounds = bounding_sphere(&scene.objects);
    let scene_size = bounds.radius + (bounds.center - eye).length();
    let (width, height) = (scene.image.width, scene.image.height);
    let camera = CameraSetup::new(&scene.camera, f64::from(width) / f64::from(height));
    let pattern = match options.samples {
        Some(_) => None,
        None => {
            let pattern = SamplePattern::new(scene.image.samples).unwrap_or(SamplePattern::SINGLE);
            Some(
                pattern
                    .offsets()
                    .iter()
                    .map(|&(x, y)| DVec2::new(0.5 + f64::from(x) / 256.0, 0.5 + f64::from(y) / 256.0))
                    .collect(),
            )
        }
    };
    let reference = ReferenceScene {
        scene,
        surfaces,
        meshes,
        lights_f32: lights.iter().map(ExactLight::to_f32).collect(),
        casts_shadow: scene
            .lights
            .iter()
            .map(|light| light.shadow().is_some())
            .collect(),
        lights,
        directional_reach: 4.0 * scene_size.max(1.0),
        shadow_offset: SHADOW_OFFSET * scene_size.max(f64::MIN_POSITIVE),
        precision: options.precision,
        world_from_clip: camera.clip_from_world.inverse(),
        infinite_viewer: match camera.viewer {
            Viewer::Local => None,
            Viewer::Infinite { .. } => Some(-camera.forward),
        },
        pattern,
        strata: options.samples.unwrap_or(1).clamp(1, MAX_REFERENCE_SAMPLES),
        texture_grid: options.texture_samples.clamp(1, MAX_REFERENCE_SAMPLES),
    };
    let build_time = started.elapsed();
    let started = Instant::now();
    let (tiles_x, tiles_y) = (width.div_ceil(TILE), height.div_ceil(TILE));
    if let Some(progress) = &options.progress {
        progress.start_tiles((tiles_x * tiles_y) as usize);
    }
    let tiles: Vec<Vec<(Vec3, bool, PixelFeatures)>> = (0..tiles_x * tiles_y)
        .into_par_iter()
        .map(|tile| {
            let (x0, y0) = ((tile % tiles_x) * TILE, (tile / tiles_x) * TILE);
            let (x1, y1) = ((x0 + TILE).min(width), (y0 + TILE).min(height));
            let pixels = (y0..y1)
                .flat_map(|py| (x0..x1).map(move |px| (px, py)))
                .map(|(px, py)| reference.shade_pixel(px, py))
                .collect();
            if let Some(progress) = &options.progress {
                progress.tile_done();
            }
            pixels
        })
        .collect();
    let mut colors = vec![Vec3::ZERO; (width * height) as usize];
    let mut coverage = vec![false; (width * height) as usize];
    let mut features = if options.features {
        vec![PixelFeatures::default(); (width * height) as usize]
    } else {
        Vec::new()
    };
    for (tile, pixels) in tiles.into_iter().enumerate() {
        let tile = tile as u32;
        let (x0, y0) = ((tile % tiles_x) * TILE, (tile / tiles_x) * TILE);
        let tile_width = (x0 + TILE).min(width) - x0;
        for (offset, (color, covered, seen)) in pixels.into_iter().enumerate() {
            let (x, y) = (x0 + offset as u32 % tile_width, y0 + offset as u32 / tile_width);
            let index = (y * width + x) as usize;
            colors[index] = color;
            coverage[index] = covered;
            if let Some(slot) = features.get_mut(index) {
                *slot = seen;
            }
        }
    }
    Reference {
        framebuffer: FrameBuffer::from_pixels(width, height, colors, coverage),
        notes,
        build_time,
        cast_time: started.elapsed(),
        features,
    }
}

/// About the most memory the reference of `scene` takes beyond the loaded scene: its
/// triangles and BVH while it builds, and the image.
pub fn reference_bytes(scene: &Scene) -> u64 {
    let triangles = scene.triangle_count() as u64;
    let pixels = u64::from(scene.image.width) * u64::from(scene.image.height);
    triangles * mesh::PEAK_BYTES_PER_TRIANGLE + pixels * (2 * std::mem::size_of::<(Vec3, bool)>() as u64)
}

/// Loads the scene file at `path` and renders its reference: `render_scene_file`'s twin for
/// `lampshade render --reference`. The reference's notes are warnings pointing at the object's
/// field in the scene file.
pub fn render_reference_file(
    path: &Path,
    load_options: &LoadOptions,
    options: &ReferenceOptions,
) -> Result<RenderedScene, LoadError> {
    let started = Instant::now();
    let loaded = load_scene(path, load_options)?;
    let load_time = started.elapsed();
    let budget = load_options.max_memory.unwrap_or(DEFAULT_MEMORY_BUDGET);
    let needed = reference_bytes(&loaded.scene);
    if needed > budget {
        let diagnostic = Diagnostic::error(
            path,
            format!(
                "the reference of this scene needs about {} of memory, more than the budget of {}",
                human_bytes(needed),
                human_bytes(budget)
            ),
        )
        .with_hint("raise --max-memory, or render the reference of a part of the scene");
        return Err(LoadError {
            diagnostics: vec![diagnostic],
            sources: loaded.sources,
            files_read: loaded.files_read,
        });
    }
    let scene_source = loaded.sources.find(path);
    let located = |diagnostic: Diagnostic, field: &str, object: usize| match scene_source {
        Some(source) => {
            let value_path = [
                PathSegment::from("objects"),
                PathSegment::Index(object),
                PathSegment::from(field),
            ];
            match locate(loaded.sources.text(source), &value_path) {
                Some(span) => diagnostic.at(source, span),
                None => diagnostic,
            }
        }
        None => diagnostic,
    };
    let reference = render_reference_with(&loaded.scene, options);
    let mut warnings = loaded.warnings;
    warnings.extend(
        reference
            .notes
            .into_iter()
            .map(|note| located(Diagnostic::warning(path, note.message), note.field, note.object)),
    );
    let stats = RenderStats {
        triangles: loaded.scene.triangle_count(),
        geometry: reference.build_time,
        raster_shade: reference.cast_time,
        threads: options.threads.unwrap_or_else(rayon::current_num_threads),
        ..RenderStats::default()
    };
    Ok(RenderedScene {
        camera: loaded.scene.camera,
        scene: std::sync::Arc::new(loaded.scene),
        framebuffer: reference.framebuffer,
        stats,
        load_time,
        warnings,
        sources: loaded.sources,
        files_read: loaded.files_read,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{Mesh, primitives};
    use crate::metrics::compare;
    use crate::render::{RenderOptions, render};
    use crate::texture::{Sampler, Texture};
    use glam::Vec4;

    fn load(text: &str) -> Scene {
        let folder = tempfile::tempdir().unwrap();
        let path = folder.path().join("scene.ron");
        std::fs::write(&path, text).unwrap();
        match load_scene(&path, &LoadOptions::default()) {
            Ok(loaded) => loaded.scene,
            Err(error) => panic!("{:?}", error.diagnostics),
        }
    }

    #[test]
    fn primitives_are_recognised_and_other_meshes_are_not() {
        for segments in [3, 8, 180] {
            assert_eq!(
                recognize_shape(&primitives::sphere(segments)),
                Some(Shape::Sphere)
            );
        }
        assert_eq!(recognize_shape(&primitives::plane()), Some(Shape::Plane));
        assert_eq!(recognize_shape(&primitives::cube()), Some(Shape::Cube));
        let mut dented = primitives::sphere(8);
        dented.positions[40] *= 0.9;
        assert_eq!(recognize_shape(&dented), None);
        assert_eq!(recognize_shape(&Mesh::default()), None);
    }

    /// An orthographic view of a unit sphere covers the pixels whose centres lie within one
    /// unit of its centre, exactly: the count is the lattice-point count of the disc.
    #[test]
    fn an_orthographic_sphere_covers_exactly_the_pixel_centres_inside_its_disc() {
        let scene = load(
            "(image: (width: 64, height: 64), \
             camera: Orthographic(eye: (0, 0, 5), target: (0, 0, 0), height: 2.56), \
             objects: [(mesh: Sphere(segments: 3))])",
        );
        let frame = render_reference(&scene, Some(1));
        for py in 0..64 {
            for px in 0..64 {
                // Pixel centres in world units: 2.56 / 64 = 0.04 per pixel.
                let x = (f64::from(px) + 0.5) * 0.04 - 1.28;
                let y = 1.28 - (f64::from(py) + 0.5) * 0.04;
                let inside = x * x + y * y <= 1.0;
                assert_eq!(frame.is_covered(px, py), inside, "pixel ({px}, {py})");
            }
        }
    }

    /// The rasterizer converges to the reference: Phong shading of a fine sphere is within a
    /// level or two almost everywhere, and a coarse one is measurably worse. Flat faces (a cube
    /// and a plane) are exact for the rasterizer too, except at their edges.
    #[test]
    fn the_rasterizer_converges_to_the_reference() {
        let scene_with = |segments: u32| {
            load(&format!(
                "(image: (width: 160, height: 120), \
                 camera: Perspective(eye: (0, -4, 2), target: (0, 0, 0), up: (0, 0, 1), fov: 40), \
                 lights: [Directional(direction: (-1, 1, -1)), \
                          Point(position: (2, -2, 3), attenuation: (constant: 1, linear: 0.1, quadratic: 0.02))], \
                 objects: [(mesh: Sphere(segments: {segments}), material: (base: \"shiny\", color: (0.2, 0.4, 1)))])"
            ))
        };
        let fine = scene_with(256);
        let reference = render_reference(&fine, Some(2));
        let (raster, _) = render(&fine, &RenderOptions::default());
        let fine_error = compare(&reference, &raster).unwrap();
        assert!(fine_error.mean_abs_all() < 0.2, "{fine_error:?}");
        assert!(fine_error.share_over_2 < 0.01, "{fine_error:?}");
        let coarse = scene_with(8);
        let (raster, _) = render(&coarse, &RenderOptions::default());
        let coarse_error = compare(&render_reference(&coarse, Some(2)), &raster).unwrap();
        assert!(
            coarse_error.mean_abs_all() > 5.0 * fine_error.mean_abs_all(),
            "{coarse_error:?}"
        );

        let boxes = load(
            "(image: (width: 160, height: 120), \
             camera: Perspective(eye: (3, -5, 4), target: (0, 0, 0), up: (0, 0, 1), fov: 50), \
             lights: [Spot(position: (1, -2, 4), direction: (-0.2, 0.4, -1), cutoff: 40, exponent: 4), \
                      Directional(direction: (1, 2, -1))], \
             objects: [(mesh: Cube, rotate: (10, 20, 30), scale: (1, 0.5, 0.7), material: \"ruby\"), \
                       (mesh: Plane, rotate: (90, 0, 0), translate: (0, 0, -1), scale: 3, \
                        material: (model: BlinnPhong, shininess: 40))])",
        );
        let reference = render_reference(&boxes, Some(2));
        let (raster, _) = render(&boxes, &RenderOptions::default());
        let error = compare(&reference, &raster).unwrap();
        assert!(error.pixels > 5000, "{error:?}");
        assert!(error.share_over_2 < 0.02, "{error:?}");
        assert!(error.mean_abs_all() < 0.5, "{error:?}");
    }

    /// Samples follow the rasterizer's pattern and are averaged with the background: a pixel
    /// half covered by a white plane (orthographic, edge through the pixel centres' column) is
    /// half white with 16 samples.
    #[test]
    fn multisampling_averages_the_samples_with_the_background() {
        let scene = load(
            "(image: (width: 4, height: 4, samples: 16), ambient: (0, 0, 0), lights: [], \
             camera: Orthographic(eye: (0, 5, 0), target: (0, 0, 0), up: (0, 0, -1), height: 4), \
             objects: [(mesh: Plane, translate: (0.5, 0, 0), material: (model: Unlit, color: (1, 1, 1), kd: 1))])",
        );
        let frame = render_reference(&scene, Some(1));
        // Pixels are one unit wide from x = −2; the plane spans x ∈ [−0.5, 1.5], edges
        // included: column 2 is inside, column 1 sees the samples right of (or on) its centre,
        // column 3 those left of (or on) it.
        let offsets = SamplePattern::new(16).unwrap().offsets();
        let share = |keep: fn(i32) -> bool| offsets.iter().filter(|&&(x, _)| keep(x)).count() as f32 / 16.0;
        let row = &frame.to_colors()[4..8];
        assert_eq!(row[0], Vec3::ZERO);
        assert_eq!(row[1], Vec3::splat(share(|x| x >= 0)), "{row:?}");
        assert_eq!(row[2], Vec3::ONE);
        assert_eq!(row[3], Vec3::splat(share(|x| x <= 0)), "{row:?}");
        assert_eq!(frame.to_coverage()[4..8], [false, true, true, true]);
    }

    /// Back faces follow the object's mode: from inside a sphere every hit is a back face.
    #[test]
    fn back_face_modes_inside_a_sphere() {
        let frame_for = |mode: &str| {
            let scene = load(&format!(
                "(image: (width: 8, height: 8), ambient: (0.5, 0.5, 0.5), \
                 camera: Perspective(eye: (0, 0, 0), target: (0, 0, -1), fov: 60, near: 0.01, far: 10), \
                 lights: [Point(position: (0, 0, 0))], \
                 objects: [(mesh: Sphere(), scale: 3, back_faces: {mode}, \
                            material: (ambient: (0.2, 0.2, 0.2), diffuse: (0.5, 0.5, 0.5), specular: (0, 0, 0)))])"
            ));
            render_reference(&scene, Some(1))
        };
        let centre = 4 * 8 + 4;
        // ReverseLit: the inside is lit by the light at the eye (normal flipped towards it).
        let reverse = frame_for("ReverseLit");
        assert!(
            reverse.to_colors()[centre].x > 0.1 + 0.4,
            "{:?}",
            reverse.to_colors()[centre]
        );
        // Lit: the outward normal faces away from the light: ambient only. Unlit: ambient only.
        assert!((frame_for("Lit").to_colors()[centre].x - 0.1).abs() < 1e-6);
        assert!((frame_for("Unlit").to_colors()[centre].x - 0.1).abs() < 1e-6);
        let culled = frame_for("Cull");
        assert!(culled.to_coverage().iter().all(|&c| !c));
    }

    fn options(geometry: ReferenceGeometry) -> ReferenceOptions {
        ReferenceOptions {
            threads: Some(2),
            geometry,
            ..ReferenceOptions::default()
        }
    }

    /// Whether the pixel and its eight neighbours are all covered: away from a silhouette.
    fn inside(frame: &FrameBuffer, x: u32, y: u32) -> bool {
        (y.saturating_sub(1)..=(y + 1).min(frame.height() - 1))
            .all(|y| (x.saturating_sub(1)..=(x + 1).min(frame.width() - 1)).all(|x| frame.is_covered(x, y)))
    }

    /// The ray-cast tessellation of `Sphere(512)` (`--reference=mesh`) agrees with the exact
    /// sphere to 2·10⁻³ (half an 8-bit level) on every pixel away from the silhouette, lit by a
    /// directional and a point light with a sharp highlight: the mesh path (BVH, barycentrics,
    /// interpolated normals) converges to the exact one.
    #[test]
    fn a_sphere_mesh_agrees_with_the_exact_sphere_away_from_its_silhouette() {
        let scene = load(
            "(image: (width: 200, height: 160), \
             camera: Perspective(eye: (0, -4, 1.5), target: (0, 0, 0), up: (0, 0, 1), fov: 35), \
             lights: [Directional(direction: (-1, 1, -1)), Point(position: (2, -2, 3))], \
             objects: [(mesh: Sphere(segments: 512), material: (base: \"shiny\", color: (0.2, 0.4, 1)))])",
        );
        let exact = render_reference_with(&scene, &options(ReferenceGeometry::Exact));
        let mesh = render_reference_with(&scene, &options(ReferenceGeometry::Mesh));
        assert!(exact.notes.is_empty() && mesh.notes.is_empty());
        let (exact, mesh) = (exact.framebuffer, mesh.framebuffer);
        let (mut worst, mut compared) = (0.0f32, 0);
        for y in 0..exact.height() {
            for x in 0..exact.width() {
                if inside(&exact, x, y) && inside(&mesh, x, y) {
                    worst = worst.max((exact.pixel(x, y) - mesh.pixel(x, y)).abs().max_element());
                    compared += 1;
                }
            }
        }
        assert!(compared > 10_000, "{compared}");
        assert!(worst < 2e-3, "{worst}");
    }

    /// A square occluder one unit above a ground plane, seen from straight above: the ground
    /// is black exactly where the square hides the light (the analytic shadow, from similar
    /// triangles) and lit everywhere else, for a directional, a point and a spot light, with
    /// the occluder exact or as triangles. Pixel centres are 1/40 unit from every boundary.
    #[test]
    fn shadow_rays_give_the_analytic_shadow_of_a_square() {
        let lights = [
            // To the light: (1, 1, 0); the ground point (x, 0, z) sees the square at x + 1.
            (
                "Directional(direction: (-1, -1, 0), shadows: true)",
                (-1.5, -0.5, 0.5),
            ),
            // From (0, 4, 0) the square's edge at 0.5 shadows the ground out to 0.5·4/3.
            (
                "Point(position: (0, 4, 0), shadows: true)",
                (-2.0 / 3.0, 2.0 / 3.0, 2.0 / 3.0),
            ),
            (
                "Spot(position: (0, 4, 0), direction: (0, -1, 0), cutoff: 70, shadows: true)",
                (-2.0 / 3.0, 2.0 / 3.0, 2.0 / 3.0),
            ),
        ];
        for (light, (x_low, x_high, z_half)) in lights {
            let scene = load(&format!(
                "(image: (width: 80, height: 80), ambient: (0, 0, 0), lights: [{light}], \
                 camera: Orthographic(eye: (0, 5, 0), target: (0, 0, 0), up: (0, 0, -1), height: 4), \
                 objects: [(mesh: Plane, scale: 3, \
                            material: (model: Lambert, ambient: (0, 0, 0), diffuse: (1, 1, 1), specular: (0, 0, 0))), \
                           (mesh: Plane, translate: (0, 1, 0), scale: 0.5, \
                            material: (model: Unlit, color: (0, 1, 0), kd: 1))])"
            ));
            for geometry in [ReferenceGeometry::Exact, ReferenceGeometry::Mesh] {
                let frame = render_reference_with(&scene, &options(geometry)).framebuffer;
                for py in 0..80 {
                    for px in 0..80 {
                        let x = (f64::from(px) + 0.5) * 0.05 - 2.0;
                        let z = (f64::from(py) + 0.5) * 0.05 - 2.0;
                        let color = frame.pixel(px, py);
                        let what = format!("{light}, {geometry:?}, pixel ({px}, {py})");
                        if x.abs() < 0.5 && z.abs() < 0.5 {
                            assert_eq!(color, Vec3::new(0.0, 1.0, 0.0), "{what}");
                        } else if x > x_low && x < x_high && z.abs() < z_half {
                            assert_eq!(color, Vec3::ZERO, "{what}: in the shadow");
                        } else {
                            assert!(color.x > 0.05, "{what}: lit, {color}");
                        }
                    }
                }
            }
        }
    }

    /// A checkerboard texture of 64×64 texels over a square of side 4 seen from above in 16×16
    /// pixels over its middle 2×2, shifted by a quarter texel: every pixel covers exactly one period (2×2 texels), so its
    /// box-filtered value is the checkerboard's mean, ½, whatever the shift. The footprint
    /// integration gets it to 10⁻³; a point lookup at the pixel centre does not (the aliasing
    /// the reference must not have); N×N stratified point samples converge to it.
    #[test]
    fn texture_supersampling_gives_the_box_filtered_checkerboard() {
        let mut scene = load(
            "(image: (width: 16, height: 16), ambient: (0, 0, 0), lights: [], \
             camera: Orthographic(eye: (0.015625, 5, 0.015625), target: (0.015625, 0, 0.015625), up: (0, 0, -1), height: 2), \
             objects: [(mesh: Plane, scale: 2, material: (model: Unlit, color: (1, 1, 1), kd: 1))])",
        );
        let texels = (0..64 * 64)
            .map(|i| Vec4::splat(((i % 64 + i / 64) % 2) as f32))
            .collect();
        scene.textures = vec![Arc::new(Texture::from_texels(64, 64, texels).unwrap())];
        let object = &mut scene.objects[0];
        object.mesh = Arc::new(primitives::textured_plane());
        let mut material = object.material.unwrap();
        material.textures.diffuse = Some(TextureBinding {
            texture: 0,
            uv_set: 0,
            sampler: Sampler::default(),
            scale: 1.0,
        });
        object.material = Some(material);
        let worst = |options: &ReferenceOptions| {
            let reference = render_reference_with(&scene, options);
            assert_eq!(reference.notes.len(), 1, "{:?}", reference.notes);
            let frame = reference.framebuffer;
            assert!(frame.to_coverage().iter().all(|&c| c));
            frame
                .to_colors()
                .iter()
                .map(|c| (c.x - 0.5).abs())
                .fold(0.0, f32::max)
        };
        let footprint = worst(&ReferenceOptions::default());
        assert!(footprint < 1e-3, "{footprint}");
        let point = worst(&ReferenceOptions {
            texture_samples: 1,
            ..ReferenceOptions::default()
        });
        assert!(point > 0.1, "{point}");
        let coarse = worst(&ReferenceOptions {
            samples: Some(2),
            ..ReferenceOptions::default()
        });
        let fine = worst(&ReferenceOptions {
            samples: Some(16),
            ..ReferenceOptions::default()
        });
        assert!(fine < 0.05 && fine < coarse / 2.0, "{coarse} {fine}");
    }

    /// The memory check counts every triangle at the build's peak, which `render --reference`
    /// compares with `--max-memory` before it builds anything.
    #[test]
    fn the_memory_estimate_counts_every_triangle_at_the_builds_peak() {
        let scene = load("(image: (width: 10, height: 10), objects: [(mesh: Sphere(segments: 100))])");
        let triangles = scene.triangle_count() as u64;
        let bytes = reference_bytes(&scene);
        const { assert!(mesh::PEAK_BYTES_PER_TRIANGLE >= 250) };
        assert!(
            bytes >= triangles * mesh::PEAK_BYTES_PER_TRIANGLE && bytes < triangles * 1000,
            "{bytes}"
        );
    }

    /// N×N stratified samples are the box filter: a pixel half covered by a plane's edge is
    /// half covered, to the strata's resolution.
    #[test]
    fn stratified_samples_are_the_box_filter() {
        let scene = load(
            "(image: (width: 4, height: 4), ambient: (0, 0, 0), lights: [], \
             camera: Orthographic(eye: (0, 5, 0), target: (0, 0, 0), up: (0, 0, -1), height: 4), \
             objects: [(mesh: Plane, translate: (0.5, 0, 0), material: (model: Unlit, color: (1, 1, 1), kd: 1))])",
        );
        let frame = render_reference_with(
            &scene,
            &ReferenceOptions {
                samples: Some(8),
                ..ReferenceOptions::default()
            },
        )
        .framebuffer;
        // Column 1's pixel is cut at its centre by the plane's edge x = −0.5 (rows 1 and 2 are
        // inside the plane's z ∈ [−1, 1]).
        for row in 1..3 {
            assert!(
                (frame.pixel(1, row).x - 0.5).abs() <= 1.0 / 16.0,
                "{:?}",
                frame.to_colors()
            );
            assert_eq!(frame.pixel(2, row), Vec3::ONE);
        }
        let again = render_reference_with(
            &scene,
            &ReferenceOptions {
                samples: Some(8),
                threads: Some(1),
                ..ReferenceOptions::default()
            },
        );
        assert_eq!(
            again.framebuffer.to_colors(),
            frame.to_colors(),
            "the same on every run"
        );
    }

    /// A mesh object (a single triangle, not a primitive) is ray-cast as itself, its front
    /// and back faces as the rasterizer decides them: a mirroring transform keeps the front on
    /// the side the model's normal points to, a half turn shows the back (culled here).
    #[test]
    fn mesh_triangles_face_the_way_the_rasterizer_sees_them() {
        let cases = [
            ("scale: (1, 1, 1)", true),
            ("scale: (-1, 1, 1)", true),
            ("rotate: (0, 180, 0)", false),
            ("scale: (-1, 1, 1), rotate: (0, 180, 0)", false),
        ];
        for (transform, front) in cases {
            let mut scene = load(&format!(
                "(image: (width: 8, height: 8), ambient: (0, 0, 0), lights: [], \
                 camera: Orthographic(eye: (0, 0, 5), target: (0, 0, 0), height: 2), \
                 objects: [(mesh: Sphere(), {transform}, back_faces: Cull, \
                            material: (model: Unlit, color: (1, 1, 1), kd: 1))])"
            ));
            let triangle = Mesh {
                positions: vec![
                    Vec3::new(-2.0, -2.0, 0.0),
                    Vec3::new(2.0, -2.0, 0.0),
                    Vec3::new(0.0, 3.0, 0.0),
                ],
                normals: vec![Vec3::Z; 3],
                triangles: vec![[0, 1, 2]],
                ..Mesh::default()
            };
            scene.objects[0].mesh = Arc::new(triangle);
            let frame = render_reference(&scene, Some(1));
            let (raster, _) = render(&scene, &RenderOptions::default());
            assert_eq!(frame.to_coverage()[4 * 8 + 4], front, "{transform}");
            assert_eq!(frame.to_coverage(), raster.to_coverage(), "{transform}");
        }
    }
}
