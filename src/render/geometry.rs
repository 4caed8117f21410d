//! The geometry stage: everything done per vertex and per triangle before rasterization.
//!
//! Per object: vertices are transformed once (to eye-relative world space for lighting and to
//! clip space for rasterization) and, for Gouraud objects, lit once. Per triangle: facing is
//! decided in homogeneous coordinates (valid even across w = 0), back faces are culled when the
//! object asks, flat-shaded triangles are lit once at their centroid, and the triangle is
//! clipped, projected, snapped and set up for the rasterizer.
//!
//! World positions are made relative to the eye in `f64` before anything is rounded to `f32`, so
//! a scene far from the origin (camera included) keeps its precision.
//!
//! Vertices are processed in parallel and triangles in fixed-size chunks; the outputs are
//! concatenated in chunk order, so the result does not depend on the thread count.

use glam::{DMat3, DMat4, DVec3, Mat3, Mat4, Vec2, Vec3, Vec4, Vec4Swizzles};
use rayon::prelude::*;

use std::sync::Arc;

use crate::lighting::{LightingTerms, ShadingLight, ShadingLightKind, illuminate_with_visibility};
use crate::render::DebugView;
use crate::render::clip::{Clipped, clip_triangle};
use crate::render::raster::{GUARD_BAND_PIXELS, RasterTriangle, SamplePattern, ScreenVertex, setup_triangle};
use crate::render::shadow::ShadowMap;
use crate::scene::presets::default_material;
use crate::scene::{
    BackFaces, Camera, Light, LightingComponent, Material, NormalInterpolation, Object, Projection, Scene,
    Shading,
};
use crate::texture::Texture;

/// Triangles per parallel work item: large enough to amortise scheduling, small enough to
/// balance two to a few dozen cores. Fixed, so that output order never depends on threads.
const TRIANGLE_CHUNK: usize = 4096;

/// Everything the tiles need to rasterize and shade one frame.
#[derive(Debug, Clone)]
pub struct Frame {
    pub vertices: Vec<FrameVertex>,
    /// One per scene triangle, in scene order; `RasterTriangle::source` indexes this.
    pub triangles: Vec<FrameTriangle>,
    pub raster: Vec<RasterTriangle>,
    pub materials: Vec<Material>,
    /// Every texture of the frame; the materials' bindings index this.
    pub textures: Vec<Arc<Texture>>,
    /// One per scene object; `FrameTriangle::object` indexes this.
    pub objects: Vec<ObjectStyle>,
    pub lights: Vec<ShadingLight>,
    pub ambient_light: Vec3,
    pub viewer: Viewer,
    /// Unit view direction, for the depth view.
    pub forward: Vec3,
    pub debug_view: Option<DebugView>,
    /// Per light, its shadow map (for lights that cast shadows).
    pub shadows: Vec<Option<Arc<ShadowMap>>>,
    /// False for a depth-only frame (a shadow map): nothing is lit and nothing culled.
    pub lit: bool,
}

/// A vertex in eye-relative world space (the eye at the origin, world axes).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrameVertex {
    pub position: Vec3,
    /// Unit normal, or zero when the mesh gives none usable.
    pub normal: Vec3,
    /// Gouraud objects: the vertex's lit colour (front side) for the frame's view; with a
    /// texture, only the part the texture does not modulate (specular and emission).
    pub color: Vec3,
    /// Gouraud objects with a texture: the ambient and diffuse part, which the texture
    /// multiplies per pixel (seeds 000 and 004).
    pub color_textured: Vec3,
    pub uv: Vec2,
    pub uv1: Vec2,
    /// The mesh's vertex colour (glTF `COLOR_0`), white where there is none: multiplies `k_d`.
    pub tint: Vec3,
    /// Unit tangent (eye-relative world axes) and bitangent handedness, for normal maps.
    pub tangent: Vec4,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrameTriangle {
    /// Indices into `Frame::vertices`, counter-clockwise from the front.
    pub vertices: [u32; 3],
    pub material: u32,
    /// Index into `Frame::objects`.
    pub object: u32,
    /// Unit geometric normal of the front side, zero for a degenerate triangle.
    pub face_normal: Vec3,
    /// Flat and constant objects: the colour of the side that faces the camera (with a texture:
    /// its specular and emission part).
    pub flat_color: Vec3,
    /// Flat objects with a texture: the ambient and diffuse part, multiplied by the texture per
    /// pixel.
    pub flat_textured: Vec3,
}

/// How an object is shaded: the settings the shading stage reads per pixel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ObjectStyle {
    pub shading: Shading,
    pub back_faces: BackFaces,
    pub component: LightingComponent,
    pub normal_interpolation: NormalInterpolation,
}

impl ObjectStyle {
    fn of(object: &Object) -> Self {
        ObjectStyle {
            shading: object.shading,
            back_faces: object.back_faces,
            component: object.component,
            normal_interpolation: object.normal_interpolation,
        }
    }

    /// The normal lighting uses on the side being shaded: flipped towards the viewer for back
    /// faces of `ReverseLit` objects, as it is otherwise.
    pub fn side_normal(&self, normal: Vec3, back_facing: bool) -> Vec3 {
        if back_facing && matches!(self.back_faces, BackFaces::ReverseLit | BackFaces::Cull) {
            -normal
        } else {
            normal
        }
    }
}

/// Where the viewer is, for the view vector `V`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Viewer {
    /// Perspective: the eye is at the origin, `V = normalize(−P)`.
    Local,
    /// Orthographic: the viewer is at infinity, `V` is the same everywhere.
    Infinite { to_viewer: Vec3 },
}

impl Viewer {
    pub fn to_viewer(&self, position: Vec3) -> Vec3 {
        match *self {
            Viewer::Local => (-position).normalize_or_zero(),
            Viewer::Infinite { to_viewer } => to_viewer,
        }
    }
}

impl Frame {
    /// Lights a surface point of an object with `style`, on its front or back side, and returns
    /// the colour the frame's view and the object's component ask for. `normal` is the surface's
    /// own (front) normal; the back-face mode decides what the back side uses.
    pub fn light(
        &self,
        material: u32,
        style: &ObjectStyle,
        position: Vec3,
        normal: Vec3,
        back_facing: bool,
    ) -> Vec3 {
        let (textured, rest) = self.light_material(
            &self.materials[material as usize],
            style,
            position,
            normal,
            back_facing,
        );
        textured + rest
    }

    /// Lights with an explicit material (coefficients already modulated by textures and vertex
    /// colours) and returns the selected terms split in two: the ambient and diffuse part, which
    /// a texture multiplies, and the rest (specular and emission).
    pub fn light_material(
        &self,
        material: &Material,
        style: &ObjectStyle,
        position: Vec3,
        normal: Vec3,
        back_facing: bool,
    ) -> (Vec3, Vec3) {
        let unlit = back_facing && style.back_faces == BackFaces::Unlit;
        let normal = style.side_normal(normal, back_facing);
        let terms = illuminate_with_visibility(
            material,
            if unlit { &[] } else { &self.lights },
            self.ambient_light,
            position,
            normal,
            self.viewer.to_viewer(position),
            |light, to_light| match self.shadows.get(light) {
                Some(Some(map)) => map.visibility(position, normal, to_light),
                _ => 1.0,
            },
        );
        select_component_split(self.debug_view, style.component, &terms)
    }
}

/// The component a pixel shows: the debug view's if one is asked, else the object's.
fn shown_component(view: Option<DebugView>, component: LightingComponent) -> LightingComponent {
    match view {
        Some(DebugView::Ambient) => LightingComponent::Ambient,
        Some(DebugView::Diffuse) => LightingComponent::Diffuse,
        Some(DebugView::Specular) => LightingComponent::Specular,
        None | Some(DebugView::Normals) | Some(DebugView::Depth) => component,
    }
}

/// The terms a pixel shows, split into (ambient + diffuse, specular + emission): the first part
/// is what a colour texture multiplies. Their sum is the pixel's colour.
pub fn select_component_split(
    view: Option<DebugView>,
    component: LightingComponent,
    terms: &LightingTerms,
) -> (Vec3, Vec3) {
    match shown_component(view, component) {
        LightingComponent::All => (terms.ambient + terms.diffuse, terms.specular + terms.emission),
        LightingComponent::Ambient => (terms.ambient, Vec3::ZERO),
        LightingComponent::Diffuse => (terms.diffuse, Vec3::ZERO),
        LightingComponent::Specular => (Vec3::ZERO, terms.specular),
    }
}

/// Runs the geometry stage for the whole scene, as its camera sees it.
pub fn build_frame(
    scene: &Scene,
    pattern: SamplePattern,
    debug_view: Option<DebugView>,
    shadows: Vec<Option<Arc<ShadowMap>>>,
) -> Frame {
    let (width, height) = (scene.image.width, scene.image.height);
    build(
        scene,
        &scene.camera,
        width,
        height,
        pattern,
        debug_view,
        shadows,
        true,
    )
}

/// The scene's geometry as `camera` sees it on a `size`×`size` image, for depth only: nothing is
/// lit and no face is culled (a shadow map needs every surface that can block light).
pub fn build_depth_frame(scene: &Scene, camera: &Camera, size: u32) -> Frame {
    build(
        scene,
        camera,
        size,
        size,
        SamplePattern::SINGLE,
        None,
        Vec::new(),
        false,
    )
}

#[allow(clippy::too_many_arguments)]
fn build(
    scene: &Scene,
    camera: &Camera,
    width: u32,
    height: u32,
    pattern: SamplePattern,
    debug_view: Option<DebugView>,
    shadows: Vec<Option<Arc<ShadowMap>>>,
    lit: bool,
) -> Frame {
    let eye = camera.eye;
    let camera = CameraSetup::new(camera, width as f64 / height as f64);
    let mut frame = Frame {
        vertices: Vec::with_capacity(scene.objects.iter().map(|o| o.mesh.positions.len()).sum()),
        triangles: Vec::with_capacity(scene.triangle_count()),
        raster: Vec::new(),
        materials: Vec::new(),
        textures: scene.textures.clone(),
        objects: scene.objects.iter().map(ObjectStyle::of).collect(),
        lights: scene.lights.iter().map(|l| shading_light(l, eye)).collect(),
        ambient_light: scene.ambient_light,
        viewer: camera.viewer,
        forward: camera.forward.as_vec3(),
        debug_view,
        shadows,
        lit,
    };
    let viewport = Viewport {
        width,
        height,
        pattern,
        guard_x: GUARD_BAND_PIXELS / width as f32,
        guard_y: GUARD_BAND_PIXELS / height as f32,
    };
    for (index, object) in scene.objects.iter().enumerate() {
        add_object(&mut frame, index as u32, object, &camera, &viewport);
    }
    frame
}

struct Viewport {
    width: u32,
    height: u32,
    pattern: SamplePattern,
    guard_x: f32,
    guard_y: f32,
}

/// The camera's matrices with the eye moved to the origin.
pub(crate) struct CameraSetup {
    pub(crate) eye: DVec3,
    /// From eye-relative world space to clip space.
    pub(crate) clip_from_world: DMat4,
    pub(crate) forward: DVec3,
    pub(crate) viewer: Viewer,
}

impl CameraSetup {
    pub(crate) fn new(camera: &Camera, aspect: f64) -> Self {
        let forward = (camera.target - camera.eye).normalize();
        let view = DMat4::look_to_rh(DVec3::ZERO, forward, camera.up);
        let (projection, viewer) = match camera.projection {
            Projection::Perspective {
                fov_y_degrees,
                near,
                far,
            } => (
                reversed_z_perspective(fov_y_degrees.to_radians(), aspect, near, far),
                Viewer::Local,
            ),
            Projection::Orthographic { height, near, far } => (
                reversed_z_orthographic(height * aspect, height, near, far),
                Viewer::Infinite {
                    to_viewer: (-forward).as_vec3(),
                },
            ),
        };
        CameraSetup {
            eye: camera.eye,
            clip_from_world: projection * view,
            forward,
            viewer,
        }
    }
}

/// OpenGL's `gluPerspective` with depth mapped to [1, 0] (near → 1): `z_clip = (n·z + n·f)/(f − n)`,
/// `w_clip = −z`.
fn reversed_z_perspective(fov_y: f64, aspect: f64, near: f64, far: f64) -> DMat4 {
    let focal = 1.0 / (fov_y / 2.0).tan();
    let depth_scale = near / (far - near);
    DMat4::from_cols_array(&[
        focal / aspect,
        0.0,
        0.0,
        0.0,
        0.0,
        focal,
        0.0,
        0.0,
        0.0,
        0.0,
        depth_scale,
        -1.0,
        0.0,
        0.0,
        far * depth_scale,
        0.0,
    ])
}

/// An orthographic projection with depth mapped to [1, 0]: `z_clip = (z + f)/(f − n)`.
fn reversed_z_orthographic(width: f64, height: f64, near: f64, far: f64) -> DMat4 {
    let depth_scale = 1.0 / (far - near);
    DMat4::from_cols_array(&[
        2.0 / width,
        0.0,
        0.0,
        0.0,
        0.0,
        2.0 / height,
        0.0,
        0.0,
        0.0,
        0.0,
        depth_scale,
        0.0,
        0.0,
        0.0,
        far * depth_scale,
        1.0,
    ])
}

/// A scene light in eye-relative world space.
fn shading_light(light: &Light, eye: DVec3) -> ShadingLight {
    let relative = |p: DVec3| (p - eye).as_vec3();
    match *light {
        Light::Directional { direction, color, .. } => ShadingLight {
            color,
            kind: ShadingLightKind::Directional {
                to_light: -direction.normalize_or_zero(),
            },
        },
        Light::Point {
            position,
            color,
            attenuation,
            ..
        } => ShadingLight {
            color,
            kind: ShadingLightKind::Point {
                position: relative(position),
                attenuation,
            },
        },
        Light::Spot {
            position,
            direction,
            color,
            cutoff_degrees,
            exponent,
            attenuation,
            ..
        } => ShadingLight {
            color,
            kind: ShadingLightKind::Spot {
                position: relative(position),
                axis: direction.normalize_or_zero(),
                cos_cutoff: cutoff_degrees.to_radians().cos(),
                exponent,
                attenuation,
            },
        },
    }
}

/// The matrices of one object.
struct ObjectTransforms {
    world_from_model: Mat4,
    clip_from_model: Mat4,
    normal_matrix: Mat3,
    /// A mirroring transform turns counter-clockwise triangles clockwise.
    mirrored: bool,
}

impl ObjectTransforms {
    fn new(object: &Object, camera: &CameraSetup) -> Self {
        let world_from_model = DMat4::from_translation(-camera.eye) * object.transform;
        let linear = DMat3::from_mat4(object.transform);
        ObjectTransforms {
            world_from_model: world_from_model.as_mat4(),
            clip_from_model: (camera.clip_from_world * world_from_model).as_mat4(),
            normal_matrix: linear.inverse().transpose().as_mat3(),
            mirrored: linear.determinant() < 0.0,
        }
    }
}

fn add_object(
    frame: &mut Frame,
    object_index: u32,
    object: &Object,
    camera: &CameraSetup,
    viewport: &Viewport,
) {
    let mesh = &*object.mesh;
    let transforms = ObjectTransforms::new(object, camera);
    let style = frame.objects[object_index as usize];

    // Materials: the object's own, else the mesh's, else the default.
    let material_base = frame.materials.len() as u32;
    match (&object.material, mesh.materials.is_empty()) {
        (Some(material), _) => frame.materials.push(*material),
        (None, true) => frame.materials.push(default_material()),
        (None, false) => {
            // The mesh's texture bindings index its own list: move them to the frame's.
            let texture_base = frame.textures.len() as u32;
            frame.textures.extend(mesh.textures.iter().cloned());
            frame.materials.extend(mesh.materials.iter().map(|material| {
                let mut material = *material;
                let textures = &mut material.textures;
                for binding in [&mut textures.diffuse, &mut textures.ambient, &mut textures.normal]
                    .into_iter()
                    .flatten()
                {
                    binding.texture += texture_base;
                }
                material
            }));
        }
    }
    let material_count = frame.materials.len() as u32 - material_base;
    let uses_mesh_materials = object.material.is_none() && !mesh.materials.is_empty();
    let triangle_material = |t: usize| -> u32 {
        if uses_mesh_materials {
            material_base + mesh.triangle_materials.get(t).copied().unwrap_or(0)
        } else {
            material_base
        }
    };

    // Vertices: transformed once each, lit once each for Gouraud.
    let vertex_base = frame.vertices.len() as u32;
    let vertex_materials: Vec<u32> = if object.shading == Shading::Gouraud {
        let mut materials = vec![material_base; mesh.positions.len()];
        for (t, triangle) in mesh.triangles.iter().enumerate().rev() {
            for &v in triangle {
                materials[v as usize] = triangle_material(t);
            }
        }
        materials
    } else {
        Vec::new()
    };
    let clip_positions: Vec<Vec4> = mesh
        .positions
        .par_iter()
        .map(|&p| transforms.clip_from_model * p.extend(1.0))
        .collect();
    let new_vertices: Vec<FrameVertex> = mesh
        .positions
        .par_iter()
        .zip(&mesh.normals)
        .enumerate()
        .map(|(v, (&p, &n))| {
            let position = transforms.world_from_model.transform_point3(p);
            let normal = (transforms.normal_matrix * n).normalize_or_zero();
            let tint = mesh.colors.get(v).map_or(Vec3::ONE, |c| c.truncate());
            let (color_textured, color) = if frame.lit && style.shading == Shading::Gouraud {
                let material = tinted(&frame.materials[vertex_materials[v] as usize], tint);
                let (textured, rest) = frame.light_material(&material, &style, position, normal, false);
                if has_color_texture(&material) {
                    (textured, rest)
                } else {
                    (Vec3::ZERO, textured + rest)
                }
            } else {
                (Vec3::ZERO, Vec3::ZERO)
            };
            let tangent = mesh.tangents.get(v).map_or(Vec4::ZERO, |t| {
                let direction = transforms
                    .world_from_model
                    .transform_vector3(t.truncate())
                    .normalize_or_zero();
                let handedness = if transforms.mirrored { -t.w } else { t.w };
                direction.extend(handedness)
            });
            FrameVertex {
                position,
                normal,
                color,
                color_textured,
                uv: mesh.uvs.get(v).copied().unwrap_or(Vec2::ZERO),
                uv1: mesh.uvs1.get(v).copied().unwrap_or(Vec2::ZERO),
                tint,
                tangent,
            }
        })
        .collect();
    frame.vertices.extend(new_vertices);

    // Constant shading: one colour per material for the whole object, lit at the centre of its
    // bounds with the normal facing the viewer.
    let constant_colors: Vec<Vec3> = if frame.lit && style.shading == Shading::Constant {
        let (lo, hi) = mesh.bounds().unwrap_or((Vec3::ZERO, Vec3::ZERO));
        let center = transforms.world_from_model.transform_point3((lo + hi) / 2.0);
        let normal = frame.viewer.to_viewer(center);
        (material_base..material_base + material_count)
            .map(|material| frame.light(material, &style, center, normal, false))
            .collect()
    } else {
        Vec::new()
    };

    // Triangles, in fixed-size chunks.
    let triangle_base = frame.triangles.len();
    let frame_ref = &*frame;
    let chunks: Vec<(Vec<FrameTriangle>, Vec<RasterTriangle>)> = mesh
        .triangles
        .par_chunks(TRIANGLE_CHUNK)
        .enumerate()
        .map(|(chunk, triangles)| {
            let mut frame_triangles = Vec::with_capacity(triangles.len());
            let mut raster = Vec::new();
            for (offset, &corners) in triangles.iter().enumerate() {
                let t = chunk * TRIANGLE_CHUNK + offset;
                let corners = if transforms.mirrored {
                    [corners[0], corners[2], corners[1]]
                } else {
                    corners
                };
                let source = (triangle_base + t) as u32;
                let material = triangle_material(t);
                let triangle = FrameTriangleInput {
                    corners,
                    vertex_base,
                    material,
                    object: object_index,
                    constant_color: constant_colors.get((material - material_base) as usize).copied(),
                    source,
                };
                frame_triangles.push(process_triangle(
                    frame_ref,
                    &triangle,
                    &clip_positions,
                    viewport,
                    &mut raster,
                ));
            }
            (frame_triangles, raster)
        })
        .collect();
    for (triangles, raster) in chunks {
        frame.triangles.extend(triangles);
        frame.raster.extend(raster);
    }
}

struct FrameTriangleInput {
    /// Mesh-local vertex indices, counter-clockwise from the front in world space.
    corners: [u32; 3],
    vertex_base: u32,
    material: u32,
    object: u32,
    /// Constant-shaded objects: the object's colour for this material.
    constant_color: Option<Vec3>,
    source: u32,
}

/// Builds the frame triangle and appends its raster triangles (none if culled or invisible).
fn process_triangle(
    frame: &Frame,
    input: &FrameTriangleInput,
    clip_positions: &[Vec4],
    viewport: &Viewport,
    raster: &mut Vec<RasterTriangle>,
) -> FrameTriangle {
    let vertices = input.corners.map(|v| v + input.vertex_base);
    let [p0, p1, p2] = vertices.map(|v| frame.vertices[v as usize].position);
    let face_normal = (p1 - p0).cross(p2 - p0).normalize_or_zero();
    let clip = input.corners.map(|v| clip_positions[v as usize]);
    let style = &frame.objects[input.object as usize];
    let mut triangle = FrameTriangle {
        vertices,
        material: input.material,
        object: input.object,
        face_normal,
        flat_color: input.constant_color.unwrap_or(Vec3::ZERO),
        flat_textured: Vec3::ZERO,
    };

    let facing = homogeneous_facing(clip);
    let back_facing = facing < 0.0;
    let culled = frame.lit && back_facing && style.back_faces == BackFaces::Cull;
    if facing == 0.0 || facing.is_nan() || culled {
        return triangle; // edge-on, degenerate, non-finite, or culled
    }
    if frame.lit && style.shading == Shading::Flat {
        let centroid = (p0 + p1 + p2) / 3.0;
        let tint = vertices
            .map(|v| frame.vertices[v as usize].tint)
            .iter()
            .sum::<Vec3>()
            / 3.0;
        let material = tinted(&frame.materials[input.material as usize], tint);
        let (textured, rest) = frame.light_material(&material, style, centroid, face_normal, back_facing);
        if has_color_texture(&material) {
            (triangle.flat_textured, triangle.flat_color) = (textured, rest);
        } else {
            triangle.flat_color = textured + rest;
        }
    }

    let (width, height) = (viewport.width, viewport.height);
    let project = |position: Vec4, weights: Vec3| {
        let inv_w = 1.0 / position.w;
        let ndc = position.xyz() * inv_w;
        ScreenVertex {
            x: (ndc.x + 1.0) * 0.5 * width as f32,
            y: (1.0 - ndc.y) * 0.5 * height as f32,
            depth: ndc.z,
            inv_w,
            weights,
        }
    };
    let setup = |corners: [ScreenVertex; 3]| {
        setup_triangle(
            corners,
            width,
            height,
            viewport.pattern,
            input.source,
            back_facing,
        )
    };
    match clip_triangle(clip, viewport.guard_x, viewport.guard_y) {
        Clipped::Outside => {}
        Clipped::Inside => {
            let corners = [0, 1, 2].map(|i| project(clip[i], Vec3::AXES[i]));
            raster.extend(setup(corners));
        }
        Clipped::Polygon(polygon) => {
            let projected: Vec<ScreenVertex> = polygon
                .vertices()
                .iter()
                .map(|v| project(v.position, v.weights))
                .collect();
            for i in 1..projected.len().saturating_sub(1) {
                raster.extend(setup([projected[0], projected[i], projected[i + 1]]));
            }
        }
    }
    triangle
}

/// `material` with its diffuse colour multiplied by a vertex colour (glTF `COLOR_0`).
pub fn tinted(material: &Material, tint: Vec3) -> Material {
    Material {
        diffuse: material.diffuse * tint,
        ..*material
    }
}

/// Whether a texture multiplies the material's ambient or diffuse colour.
pub fn has_color_texture(material: &Material) -> bool {
    material.textures.diffuse.is_some() || material.textures.ambient.is_some()
}

/// The sign of `det[x y w]` of the clip-space corners: positive when the triangle is seen from
/// its front (counter-clockwise), negative from behind, zero edge-on. Unlike a screen-space
/// area it is right even when corners lie behind the eye (Olano & Greer, homogeneous
/// rasterization). Computed in `f64` so that nearly edge-on triangles get a reliable sign.
fn homogeneous_facing(clip: [Vec4; 3]) -> f64 {
    let [a, b, c] = clip.map(|p| DVec3::new(p.x as f64, p.y as f64, p.w as f64));
    a.dot(b.cross(c))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn perspective_maps_near_to_one_and_far_to_zero() {
        let m = reversed_z_perspective(60f64.to_radians(), 1.5, 0.1, 100.0);
        let depth = |z: f64| {
            let clip = m * glam::DVec4::new(0.0, 0.0, z, 1.0);
            clip.z / clip.w
        };
        assert!((depth(-0.1) - 1.0).abs() < 1e-12);
        assert!(depth(-100.0).abs() < 1e-12);
        assert!(depth(-1.0) > depth(-2.0));
    }

    #[test]
    fn orthographic_maps_near_to_one_and_far_to_zero() {
        let m = reversed_z_orthographic(4.0, 2.0, 1.0, 11.0);
        let clip = |z: f64| m * glam::DVec4::new(1.0, 1.0, z, 1.0);
        assert!((clip(-1.0).z - 1.0).abs() < 1e-12 && clip(-11.0).z.abs() < 1e-12);
        assert!((clip(-1.0).x - 0.5).abs() < 1e-12 && (clip(-1.0).y - 1.0).abs() < 1e-12);
    }

    #[test]
    fn facing_sign_survives_a_vertex_behind_the_eye() {
        // Counter-clockwise seen from the eye, one vertex behind it (w < 0).
        let front = [
            Vec4::new(-1.0, -1.0, 0.5, 1.0),
            Vec4::new(1.0, -1.0, 0.5, 1.0),
            Vec4::new(0.0, 5.0, 0.0, -1.0),
        ];
        let a = homogeneous_facing([front[0], front[1], Vec4::new(0.0, 1.0, 0.5, 1.0)]);
        assert!(a > 0.0);
        let back = [front[0], front[2], front[1]];
        assert!(homogeneous_facing(back) * homogeneous_facing(front) < 0.0);
    }
}
