//! The exact reference: the scene's analytic shapes ray-cast in `f64`, lit per sample with the
//! exact surface normal. It is the ground truth that tessellation, shading modes and `f32`
//! arithmetic approximate, and what [`crate::metrics`] measures the rasterizer against.
//!
//! What is exact, and what is the same as the rasterizer:
//! - **Shapes.** `Sphere(N)` is the true unit sphere (whatever `N`), `Plane` the true square,
//!   `Cube` the true cube, each under the object's transform (an ellipsoid for a non-uniform
//!   scale). The ray is taken to model space by the inverse transform, where every shape is a
//!   quadric or a set of slabs with a closed-form intersection; the normal comes back through
//!   the inverse transpose, like the rasterizer's vertex normals.
//! - **Camera.** Each sample's ray runs from the near plane to the far plane through the
//!   inverse of the rasterizer's own clip matrix (`render::geometry::CameraSetup`), so
//!   projection, aspect ratio, pixel centres (`x + ½`) and clipping at `near` and `far` match.
//!   Rays are parameterised by `t ∈ [0, 1]` from near to far, which is the visible range.
//! - **Samples.** The rasterizer's own sample pattern (`render::raster::SamplePattern`); every
//!   sample is shaded (true supersampling), and the pixel is the mean of its samples,
//!   background included, as `render::shade::shade_tile` averages.
//! - **Visibility.** The nearest hit wins, the first object on a tie (like the rasterizer's
//!   strict depth test in submission order); back faces (`N·D > 0` for the ray direction `D`)
//!   follow the object's `back_faces` mode, `Cull` skipping them.
//! - **Lighting.** [`exact_lighting`], the `f64` transcription of [`crate::lighting`], with
//!   every light type, attenuation, spot, every model, emission, the object's `component`. The
//!   shading mode is ignored: the reference is what every mode approximates.
//!
//! Not supported, each reported rather than approximated: mesh files (OBJ, glTF: an error
//! naming the object, since they have no analytic surface) and textured materials (an error;
//! the analytic shapes have no texture coordinates). Shadows are not computed (a warning): the
//! reference is of the local illumination only.
//!
//! Shapes are recognised by their mesh: a mesh equal to `mesh::primitives::sphere(N)`,
//! `plane()` or `cube()` is that primitive. This needs nothing from the loader (the scene keeps
//! no record of how a mesh was written) and is exact: a mesh file holding exactly a primitive's
//! vertices is that primitive.

pub mod exact_lighting;

use std::path::Path;
use std::time::Instant;

use glam::{DMat3, DMat4, DVec3, DVec4, Vec3};
use rayon::prelude::*;

use crate::diag::Diagnostic;
use crate::mesh::{Mesh, primitives};
use crate::pipeline::RenderedScene;
use crate::render::frame::Viewer;
use crate::render::geometry::CameraSetup;
use crate::render::raster::SamplePattern;
use crate::render::{FrameBuffer, RenderStats};
use crate::scene::load::{LoadError, LoadOptions, load_scene};
use crate::scene::locate::{PathSegment, locate};
use crate::scene::{BackFaces, LightingComponent, Material, Object, Scene, presets};
use exact_lighting::{ExactLight, illuminate_exact};

/// An analytic surface in its model space.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Shape {
    /// The unit sphere at the origin.
    Sphere,
    /// The square `[−1, 1]²` in the XZ plane, facing +Y.
    Plane,
    /// The cube `[−1, 1]³`.
    Cube,
}

/// Why an object cannot be rendered exactly.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Unsupported {
    /// Index in the scene's `objects`.
    pub object: usize,
    /// The object's field at fault (`mesh` or `material`), where the diagnostic points.
    pub field: &'static str,
    pub message: String,
    pub hint: String,
}

/// The analytic shape `mesh` is, if it is one of the built-in primitives.
pub fn recognize_shape(mesh: &Mesh) -> Option<Shape> {
    if !mesh.materials.is_empty() {
        return None;
    }
    let vertices = mesh.positions.len();
    let root = (vertices as f64).sqrt().round() as usize;
    if root * root == vertices && root > primitives::MIN_SPHERE_SEGMENTS as usize {
        let segments = (root - 1) as u32;
        if segments <= primitives::MAX_SPHERE_SEGMENTS && *mesh == primitives::sphere(segments) {
            return Some(Shape::Sphere);
        }
    }
    if *mesh == primitives::plane() {
        return Some(Shape::Plane);
    }
    if *mesh == primitives::cube() {
        return Some(Shape::Cube);
    }
    None
}

/// One object, ready to be hit by rays in eye-relative world space.
struct Surface {
    shape: Shape,
    /// From eye-relative world space to model space.
    model_from_world: DMat4,
    /// Model-space normals to world space (the inverse transpose of the linear part).
    normal_to_world: DMat3,
    material: Material,
    back_faces: BackFaces,
    component: LightingComponent,
}

/// A ray's nearest visible surface point.
struct Hit {
    t: f64,
    surface: usize,
    /// World-space unit normal on the outside of the shape.
    normal: DVec3,
}

/// Prepares every object, or says which ones have no exact rendering.
fn surfaces(scene: &Scene) -> Result<Vec<Surface>, Vec<Unsupported>> {
    let mut problems = Vec::new();
    let mut prepared = Vec::new();
    for (index, object) in scene.objects.iter().enumerate() {
        match surface(scene.camera.eye, object) {
            Ok(surface) => prepared.push(surface),
            Err((field, message, hint)) => problems.push(Unsupported {
                object: index,
                field,
                message,
                hint,
            }),
        }
    }
    if problems.is_empty() {
        Ok(prepared)
    } else {
        Err(problems)
    }
}

/// The object ready for rays, or (the field at fault, the message, a hint).
fn surface(eye: DVec3, object: &Object) -> Result<Surface, (&'static str, String, String)> {
    let Some(shape) = recognize_shape(&object.mesh) else {
        return Err((
            "mesh",
            format!(
                "`{}` is drawn from a mesh file, which has no exact surface for the reference",
                object.name
            ),
            "the reference renders only `Sphere`, `Plane` and `Cube`; render without --reference".to_string(),
        ));
    };
    let material = object.material.unwrap_or_else(presets::default_material);
    let textures = material.textures;
    if textures.diffuse.is_some() || textures.ambient.is_some() || textures.normal.is_some() {
        return Err((
            "material",
            format!(
                "`{}` has a textured material, which the reference does not support",
                object.name
            ),
            "remove the texture, or render without --reference".to_string(),
        ));
    }
    let world_from_model = DMat4::from_translation(-eye) * object.transform;
    let linear = DMat3::from_mat4(object.transform);
    Ok(Surface {
        shape,
        model_from_world: world_from_model.inverse(),
        normal_to_world: linear.inverse().transpose(),
        material,
        back_faces: object.back_faces,
        component: object.component,
    })
}

impl Surface {
    /// Calls `found(t, model-space outward normal)` for every intersection of the ray
    /// `origin + t·direction` (eye-relative world space) with the shape, `t` in `[0, 1]`.
    fn intersect(&self, origin: DVec3, direction: DVec3, mut found: impl FnMut(f64, DVec3)) {
        let o = self.model_from_world.transform_point3(origin);
        let d = self.model_from_world.transform_vector3(direction);
        let mut report = |t: f64, normal: DVec3| {
            if (0.0..=1.0).contains(&t) {
                found(t, normal);
            }
        };
        match self.shape {
            Shape::Sphere => {
                // |o + s·u|² = 1 along the unit direction u: s² − 2bs + c = 0 with b = −o·u,
                // c = |o|² − 1. The discriminant b² − c is computed as 1 − |o + b·u|² (the
                // squared distance of the ray from the centre), which does not cancel when the
                // origin is far away or the shape very flat; the roots are q and c/q with
                // q = b + sign(b)·√(b² − c) (Ray Tracing Gems, chapter 7).
                let length = d.length();
                if length == 0.0 {
                    return;
                }
                let unit = d / length;
                let b = -o.dot(unit);
                let closest = o + b * unit;
                let discriminant = 1.0 - closest.dot(closest);
                if discriminant < 0.0 {
                    return;
                }
                let c = o.dot(o) - 1.0;
                let q = b + if b < 0.0 { -1.0 } else { 1.0 } * discriminant.sqrt();
                let distances = if q == 0.0 { [0.0, 0.0] } else { [q, c / q] };
                for distance in distances {
                    let t = distance / length;
                    report(t, o + t * d);
                }
            }
            Shape::Plane => {
                if d.y != 0.0 {
                    let t = -o.y / d.y;
                    let p = o + t * d;
                    if p.x.abs() <= 1.0 && p.z.abs() <= 1.0 {
                        report(t, DVec3::Y);
                    }
                }
            }
            Shape::Cube => {
                let (mut enter, mut exit) = (f64::NEG_INFINITY, f64::INFINITY);
                let (mut enter_normal, mut exit_normal) = (DVec3::ZERO, DVec3::ZERO);
                for axis in 0..3 {
                    let (origin, step) = (o[axis], d[axis]);
                    if step == 0.0 {
                        if origin.abs() > 1.0 {
                            return;
                        }
                        continue;
                    }
                    let (t0, t1) = ((-1.0 - origin) / step, (1.0 - origin) / step);
                    let outward = DVec3::AXES[axis] * step.signum();
                    if t0.min(t1) > enter {
                        enter = t0.min(t1);
                        enter_normal = -outward;
                    }
                    if t0.max(t1) < exit {
                        exit = t0.max(t1);
                        exit_normal = outward;
                    }
                }
                if enter <= exit {
                    report(enter, enter_normal);
                    report(exit, exit_normal);
                }
            }
        }
    }
}

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

/// What the reference renders: the scene with its camera and lights, and the surfaces.
struct ReferenceScene<'a> {
    scene: &'a Scene,
    surfaces: Vec<Surface>,
    lights: Vec<ExactLight>,
    lights_f32: Vec<crate::lighting::ShadingLight>,
    precision: LightingPrecision,
    /// From NDC (x, y, depth) to eye-relative world space.
    world_from_clip: DMat4,
    /// `V` for an orthographic camera (the viewer at infinity, in `f64`); `None` for a
    /// perspective one, where `V` points to the eye.
    infinite_viewer: Option<DVec3>,
    pattern: SamplePattern,
}

impl ReferenceScene<'_> {
    /// The nearest visible hit of the ray through the screen point (`x`, `y`) in pixels.
    fn trace(&self, x: f64, y: f64) -> Option<(Hit, DVec3, DVec3)> {
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
        let direction = unproject(0.0) - origin;
        let mut nearest: Option<Hit> = None;
        for (index, surface) in self.surfaces.iter().enumerate() {
            surface.intersect(origin, direction, |t, model_normal| {
                if nearest.as_ref().is_some_and(|hit| hit.t <= t) {
                    return; // strictly nearer only: the first object wins a tie
                }
                let normal = (surface.normal_to_world * model_normal).normalize_or_zero();
                let back_facing = normal.dot(direction) > 0.0;
                if back_facing && surface.back_faces == BackFaces::Cull {
                    return;
                }
                nearest = Some(Hit {
                    t,
                    surface: index,
                    normal,
                });
            });
        }
        nearest.map(|hit| {
            let position = origin + hit.t * direction;
            (hit, position, direction)
        })
    }

    /// The colour of the sample at the screen point (`x`, `y`), or `None` for the background.
    fn shade_sample(&self, x: f64, y: f64) -> Option<DVec3> {
        let (hit, position, direction) = self.trace(x, y)?;
        let surface = &self.surfaces[hit.surface];
        let back_facing = hit.normal.dot(direction) > 0.0;
        let normal = if back_facing && matches!(surface.back_faces, BackFaces::ReverseLit | BackFaces::Cull) {
            -hit.normal
        } else {
            hit.normal
        };
        let unlit = back_facing && surface.back_faces == BackFaces::Unlit;
        let to_viewer = self
            .infinite_viewer
            .unwrap_or_else(|| (-position).normalize_or_zero());
        if self.precision == LightingPrecision::F32 {
            let terms = crate::lighting::illuminate(
                &surface.material,
                if unlit { &[] } else { &self.lights_f32 },
                self.scene.ambient_light,
                position.as_vec3(),
                normal.as_vec3(),
                to_viewer.as_vec3(),
            );
            let (textured, rest) =
                crate::render::frame::select_component_split(None, surface.component, &terms);
            return Some((textured + rest).as_dvec3());
        }
        let terms = illuminate_exact(
            &surface.material,
            if unlit { &[] } else { &self.lights },
            self.scene.ambient_light.as_dvec3(),
            position,
            normal,
            to_viewer,
        );
        Some(select_exact(surface.component, &terms))
    }

    /// One pixel: the mean of its samples, background included; whether any sample hit.
    fn shade_pixel(&self, px: u32, py: u32) -> (Vec3, bool) {
        let background = self.scene.image.background.as_dvec3();
        let mut sum = DVec3::ZERO;
        let mut covered = false;
        for &(ox, oy) in self.pattern.offsets() {
            let x = f64::from(px) + 0.5 + f64::from(ox) / 256.0;
            let y = f64::from(py) + 0.5 + f64::from(oy) / 256.0;
            match self.shade_sample(x, y) {
                Some(color) => {
                    sum += color;
                    covered = true;
                }
                None => sum += background,
            }
        }
        ((sum / self.pattern.len() as f64).as_vec3(), covered)
    }
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

/// Renders the exact reference of `scene` on `threads` workers (default: rayon's pool), or
/// says which objects it cannot render. Rows are computed independently, so the image is the
/// same for any thread count.
pub fn render_reference(scene: &Scene, threads: Option<usize>) -> Result<FrameBuffer, Vec<Unsupported>> {
    render_reference_with(scene, threads, LightingPrecision::F64)
}

/// [`render_reference`] with the lighting evaluated at `precision`.
pub fn render_reference_with(
    scene: &Scene,
    threads: Option<usize>,
    precision: LightingPrecision,
) -> Result<FrameBuffer, Vec<Unsupported>> {
    let surfaces = surfaces(scene)?;
    let lights: Vec<ExactLight> = scene
        .lights
        .iter()
        .map(|light| ExactLight::new(light, scene.camera.eye))
        .collect();
    let (width, height) = (scene.image.width, scene.image.height);
    let camera = CameraSetup::new(&scene.camera, f64::from(width) / f64::from(height));
    let reference = ReferenceScene {
        scene,
        surfaces,
        lights_f32: lights.iter().map(ExactLight::to_f32).collect(),
        lights,
        precision,
        world_from_clip: camera.clip_from_world.inverse(),
        infinite_viewer: match camera.viewer {
            Viewer::Local => None,
            Viewer::Infinite { .. } => Some(-camera.forward),
        },
        pattern: SamplePattern::new(scene.image.samples).unwrap_or(SamplePattern::SINGLE),
    };
    let run = || {
        let rows: Vec<Vec<(Vec3, bool)>> = (0..height)
            .into_par_iter()
            .map(|py| (0..width).map(|px| reference.shade_pixel(px, py)).collect())
            .collect();
        let (color, covered) = rows.into_iter().flatten().unzip();
        FrameBuffer {
            width,
            height,
            color,
            covered,
        }
    };
    if let Some(threads) = threads
        && let Ok(pool) = rayon::ThreadPoolBuilder::new().num_threads(threads).build()
    {
        return Ok(pool.install(run));
    }
    Ok(run())
}

/// Loads the scene file at `path` and renders its reference: `render_scene_file`'s twin for
/// `lampshade render --reference`. Objects the reference cannot render are errors pointing at
/// their `mesh` (or `material`) in the scene file; shadows are a warning.
pub fn render_reference_file(
    path: &Path,
    load_options: &LoadOptions,
    threads: Option<usize>,
) -> Result<RenderedScene, LoadError> {
    let started = Instant::now();
    let loaded = load_scene(path, load_options)?;
    let load_time = started.elapsed();
    let started = Instant::now();
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
    let framebuffer = match render_reference(&loaded.scene, threads) {
        Ok(framebuffer) => framebuffer,
        Err(problems) => {
            let diagnostics = problems
                .into_iter()
                .map(|problem| {
                    let diagnostic = Diagnostic::error(path, problem.message).with_hint(problem.hint);
                    located(diagnostic, problem.field, problem.object)
                })
                .collect();
            return Err(LoadError {
                diagnostics,
                sources: loaded.sources,
                files_read: loaded.files_read,
            });
        }
    };
    let mut warnings = loaded.warnings;
    if loaded.scene.lights.iter().any(|light| light.shadow().is_some()) {
        warnings.push(Diagnostic::warning(
            path,
            "the reference does not compute shadows: shadowed lights light everything they face",
        ));
    }
    let stats = RenderStats {
        raster_shade: started.elapsed(),
        threads: threads.unwrap_or_else(rayon::current_num_threads),
        ..RenderStats::default()
    };
    Ok(RenderedScene {
        framebuffer,
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
    use crate::metrics::compare;
    use crate::render::{RenderOptions, render};

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
        let frame = render_reference(&scene, Some(1)).unwrap();
        for py in 0..64 {
            for px in 0..64 {
                // Pixel centres in world units: 2.56 / 64 = 0.04 per pixel.
                let x = (f64::from(px) + 0.5) * 0.04 - 1.28;
                let y = 1.28 - (f64::from(py) + 0.5) * 0.04;
                let inside = x * x + y * y <= 1.0;
                assert_eq!(
                    frame.covered[(py * 64 + px) as usize],
                    inside,
                    "pixel ({px}, {py})"
                );
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
        let reference = render_reference(&fine, Some(2)).unwrap();
        let (raster, _) = render(&fine, &RenderOptions::default());
        let fine_error = compare(&reference, &raster).unwrap();
        assert!(fine_error.mean_abs_all() < 0.2, "{fine_error:?}");
        assert!(fine_error.share_over_2 < 0.01, "{fine_error:?}");
        let coarse = scene_with(8);
        let (raster, _) = render(&coarse, &RenderOptions::default());
        let coarse_error = compare(&render_reference(&coarse, Some(2)).unwrap(), &raster).unwrap();
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
        let reference = render_reference(&boxes, Some(2)).unwrap();
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
        let frame = render_reference(&scene, Some(1)).unwrap();
        // Pixels are one unit wide from x = −2; the plane spans x ∈ [−0.5, 1.5], edges
        // included: column 2 is inside, column 1 sees the samples right of (or on) its centre,
        // column 3 those left of (or on) it.
        let offsets = SamplePattern::new(16).unwrap().offsets();
        let share = |keep: fn(i32) -> bool| offsets.iter().filter(|&&(x, _)| keep(x)).count() as f32 / 16.0;
        let row = &frame.color[4..8];
        assert_eq!(row[0], Vec3::ZERO);
        assert_eq!(row[1], Vec3::splat(share(|x| x >= 0)), "{row:?}");
        assert_eq!(row[2], Vec3::ONE);
        assert_eq!(row[3], Vec3::splat(share(|x| x <= 0)), "{row:?}");
        assert_eq!(frame.covered[4..8], [false, true, true, true]);
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
            render_reference(&scene, Some(1)).unwrap()
        };
        let centre = 4 * 8 + 4;
        // ReverseLit: the inside is lit by the light at the eye (normal flipped towards it).
        let reverse = frame_for("ReverseLit");
        assert!(reverse.color[centre].x > 0.1 + 0.4, "{:?}", reverse.color[centre]);
        // Lit: the outward normal faces away from the light: ambient only. Unlit: ambient only.
        assert!((frame_for("Lit").color[centre].x - 0.1).abs() < 1e-6);
        assert!((frame_for("Unlit").color[centre].x - 0.1).abs() < 1e-6);
        let culled = frame_for("Cull");
        assert!(culled.covered.iter().all(|&c| !c));
    }

    #[test]
    fn mesh_files_and_textures_are_reported_with_the_object() {
        let mut scene = load("(objects: [(mesh: Sphere()), (name: \"tri\", mesh: Cube)])");
        let triangle = Mesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
            normals: vec![Vec3::Z; 3],
            triangles: vec![[0, 1, 2]],
            ..Mesh::default()
        };
        scene.objects[1].mesh = std::sync::Arc::new(triangle);
        let problems = render_reference(&scene, None).unwrap_err();
        assert_eq!(problems.len(), 1);
        assert_eq!((problems[0].object, problems[0].field), (1, "mesh"));
        assert!(problems[0].message.contains("`tri`"), "{problems:?}");
    }
}
