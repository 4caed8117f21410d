//! The geometry stage: everything done per vertex and per triangle before rasterization.
//!
//! Per object: vertices are transformed once (to eye-relative world space for lighting and to
//! clip space for rasterization). Per triangle: facing is decided in homogeneous coordinates
//! (valid even across w = 0), back faces are culled when the object asks, and the triangle is
//! clipped, projected, snapped and set up for the rasterizer. Then the vertices of Gouraud
//! objects that some rasterized triangle uses are lit, each once. (Flat triangles are lit
//! later, by the tiles that show them.)
//!
//! World positions are made relative to the eye in `f64` before anything is rounded to `f32`, so
//! a scene far from the origin (camera included) keeps its precision.
//!
//! Vertices are processed in parallel and triangles in fixed-size chunks; the outputs are
//! concatenated in chunk order, so the result does not depend on the thread count.

use glam::{DMat3, DMat4, DVec3, Mat3, Mat4, Vec2, Vec3, Vec4, Vec4Swizzles};
use rayon::prelude::*;

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use crate::lighting::{ShadingLight, ShadingLightKind};
use crate::render::DebugView;
use crate::render::bin::{RasterChunk, TileGrid};
use crate::render::clip::{Clipped, clip_triangle};
use crate::render::frame::{
    Frame, FrameTriangle, FrameVertex, ObjectStyle, VertexAttributes, Viewer, has_color_texture, tinted,
};
use crate::render::lanes::{LANES, Vec3s};
use crate::render::raster::{
    GUARD_BAND_PIXELS, RasterTriangle, SamplePattern, ScreenVertex, SnappedVertex, SourceTriangle,
    sample_bounds, setup_triangle, setup_within,
};
use crate::render::shade_fast::FastLighting;
use crate::render::shadow::ShadowMap;
use crate::render::surface_lanes::SurfaceLanes;
use crate::scene::presets::default_material;
use crate::scene::{BackFaces, Camera, Light, Object, Projection, Scene, Shading};

/// Triangles per parallel work item: large enough to amortise scheduling and per-chunk bins,
/// small enough to balance two to a few dozen cores. Chunks cut the scene's whole triangle
/// stream (objects one after another), so their boundaries depend only on the scene.
pub const TRIANGLE_CHUNK: usize = 4096;

/// Runs the geometry stage for the whole scene, as its camera sees it.
pub fn build_frame(
    scene: &Scene,
    pattern: SamplePattern,
    debug_view: Option<DebugView>,
    shadows: Vec<Option<Arc<ShadowMap>>>,
) -> Frame {
    build_frame_in(scene, pattern, debug_view, shadows, &mut SpareBuffers::default())
}

/// [`build_frame`] in the arrays of an earlier frame, taken from `spare`.
pub fn build_frame_in(
    scene: &Scene,
    pattern: SamplePattern,
    debug_view: Option<DebugView>,
    shadows: Vec<Option<Arc<ShadowMap>>>,
    spare: &mut SpareBuffers,
) -> Frame {
    build(scene, pattern, debug_view, shadows, spare)
}

/// The big arrays of a finished frame, emptied but with their capacity, to build the next frame
/// in: a stream of frames (`bench`'s) then allocates and page-faults nothing big after the
/// first. Which arrays are reused changes no result.
#[derive(Default)]
pub struct SpareBuffers {
    vertices: Vec<FrameVertex>,
    vertex_colors: Vec<Vec3>,
    /// The chunks' bin arrays, and their triangle arrays (taken back by the next frame's chunk
    /// of the same index).
    raster: Vec<RasterChunk>,
    projected: Vec<ProjectedVertex>,
    seen_vertices: Vec<AtomicBool>,
}

impl SpareBuffers {
    /// Keeps `frame`'s arrays for the next frame.
    pub fn keep(&mut self, frame: Frame) {
        self.vertices = frame.vertices;
        self.vertex_colors = frame.vertex_colors;
        self.raster = frame.raster;
    }

    /// The raster chunks and projected vertices, for the shadow pass (`depth`), which runs
    /// before the frame's geometry and leaves them for it: the two never need them at once, so
    /// a frame with shadow maps holds no second set of triangle arrays.
    pub(crate) fn depth_pass_arrays(&mut self) -> (&mut Vec<RasterChunk>, &mut Vec<ProjectedVertex>) {
        (&mut self.raster, &mut self.projected)
    }
}

/// `vector` emptied, with room for at least `count` elements.
fn emptied<T>(mut vector: Vec<T>, count: usize) -> Vec<T> {
    vector.clear();
    vector.reserve(count);
    vector
}

/// `vector` with exactly `count` elements, for a pass that overwrites every one of them: the
/// elements it already has are kept as they are, so a stream of same-sized frames fills
/// nothing (a fill of the vertex arrays was 40 MB of `memset` a frame on S2).
fn overwritable<T: Default + Clone>(mut vector: Vec<T>, count: usize) -> Vec<T> {
    vector.resize(count, T::default());
    vector
}

fn build(
    scene: &Scene,
    pattern: SamplePattern,
    debug_view: Option<DebugView>,
    shadows: Vec<Option<Arc<ShadowMap>>>,
    spare: &mut SpareBuffers,
) -> Frame {
    let (width, height) = (scene.image.width, scene.image.height);
    let eye = scene.camera.eye;
    let camera = CameraSetup::new(&scene.camera, width as f64 / height as f64);
    let vertex_count: usize = scene.objects.iter().map(|o| o.mesh.positions.len()).sum();
    let needs_colors = scene.objects.iter().any(|o| o.shading == Shading::Gouraud);
    let needs_attributes = scene.objects.iter().any(|o| {
        let mesh = &o.mesh;
        !mesh.uvs.is_empty() || !mesh.uvs1.is_empty() || !mesh.colors.is_empty() || !mesh.tangents.is_empty()
    });
    let mut frame = Frame {
        vertices: overwritable(std::mem::take(&mut spare.vertices), vertex_count),
        vertex_colors: if needs_colors {
            // `light_gouraud_vertices` writes every element.
            overwritable(std::mem::take(&mut spare.vertex_colors), vertex_count)
        } else {
            emptied(std::mem::take(&mut spare.vertex_colors), 0)
        },
        vertex_colors_textured: Vec::new(),
        vertex_attributes: Vec::with_capacity(if needs_attributes { vertex_count } else { 0 }),
        raster: Vec::new(),
        tiles: TileGrid::new(width, height),
        materials: Vec::new(),
        constant_colors: Vec::new(),
        textures: scene.textures.clone(),
        mip_bias: scene.image.mip_bias,
        objects: scene.objects.iter().map(ObjectStyle::of).collect(),
        lights: scene.lights.iter().map(|l| shading_light(l, eye)).collect(),
        ambient_light: scene.ambient_light,
        viewer: camera.viewer,
        forward: camera.forward.as_vec3(),
        debug_view,
        shadows,
    };
    let viewport = Viewport::new(width, height, pattern);
    let mut projected = overwritable(std::mem::take(&mut spare.projected), vertex_count);
    let mut vertex_base = 0;
    let placed: Vec<PlacedObject> = scene
        .objects
        .iter()
        .enumerate()
        .map(|(index, object)| {
            let place = add_object_vertices(
                &mut frame,
                &mut projected,
                vertex_base,
                index as u32,
                object,
                &camera,
                &viewport,
            );
            vertex_base += place.vertex_count;
            place
        })
        .collect();
    // Gouraud vertices are lit after the triangles are known, and only those that a triangle
    // reaching the rasterizer uses: hidden back faces, culled and off-screen triangles need none.
    let mut seen_vertices = std::mem::take(&mut spare.seen_vertices);
    seen_vertices.clear();
    if needs_colors {
        seen_vertices.resize_with(vertex_count, || AtomicBool::new(false));
    }
    let spare_chunks = std::mem::take(&mut spare.raster);
    add_triangles(
        &mut frame,
        scene,
        &placed,
        &projected,
        &viewport,
        &seen_vertices,
        spare_chunks,
    );
    if needs_colors {
        light_gouraud_vertices(&mut frame, scene, &placed, &seen_vertices);
    }
    spare.projected = projected;
    spare.seen_vertices = seen_vertices;
    frame
}

/// Lights the vertices of Gouraud objects that `seen` marks, each once, with the material of
/// the triangles that use it (loaders give every vertex one material:
/// [`Mesh::split_vertices_shared_by_materials`](crate::mesh::Mesh::split_vertices_shared_by_materials));
/// the other vertices get a zero colour nothing reads. One
/// parallel pass over the whole vertex array, so many small objects still fill every core.
fn light_gouraud_vertices(frame: &mut Frame, scene: &Scene, placed: &[PlacedObject], seen: &[AtomicBool]) {
    // Per object whose triangles carry the mesh's materials: each vertex's material.
    let vertex_materials: Vec<Option<Vec<u32>>> = scene
        .objects
        .iter()
        .zip(placed)
        .map(|(object, place)| {
            let mesh = &object.mesh;
            let gouraud = object.shading == Shading::Gouraud;
            (gouraud && place.uses_mesh_materials).then(|| {
                let mut materials = vec![place.material_base; place.vertex_count as usize];
                for (t, triangle) in mesh.triangles.iter().enumerate().rev() {
                    let material = place.material_base + mesh.triangle_materials.get(t).copied().unwrap_or(0);
                    for &v in triangle {
                        materials[v as usize] = material;
                    }
                }
                materials
            })
        })
        .collect();
    let mut colors = std::mem::take(&mut frame.vertex_colors);
    colors.resize(frame.vertices.len(), Vec3::ZERO);
    // The vertices are moved out so that the pass can give normals to those that wait for one
    // while it reads the frame's lights and materials (which never read the vertices).
    let mut vertices = std::mem::take(&mut frame.vertices);
    let lit_frame = &*frame;
    // Per chunk, the textured parts of its vertices that have one (rare: allocated only then).
    let textured_parts: Vec<Vec<(usize, Vec3)>> = colors
        .par_chunks_mut(VERTEX_CHUNK)
        .zip(vertices.par_chunks_mut(VERTEX_CHUNK))
        .zip(seen.par_chunks(VERTEX_CHUNK))
        .enumerate()
        .map(|(chunk, ((colors, vertices), seen))| {
            let mut textured_parts = Vec::new();
            let first = chunk * VERTEX_CHUNK;
            let mut object = placed.partition_point(|place| place.vertex_base as usize <= first) - 1;
            // The fast lighting of the last (object, material) met, when it may take it.
            let mut fast: Option<(usize, u32, Option<FastLighting>)> = None;
            // Vertices waiting to be lit together by the fast lighting in `fast`.
            let mut batch = LightingBatch {
                chunk_start: first,
                ..LightingBatch::default()
            };
            for offset in 0..colors.len() {
                if !seen[offset].load(Ordering::Relaxed) {
                    // Never read; written so that no value of an earlier frame is left.
                    colors[offset] = Vec3::ZERO;
                    continue;
                }
                let vertex_index = first + offset;
                while vertex_index >= (placed[object].vertex_base + placed[object].vertex_count) as usize {
                    object += 1;
                }
                let place = &placed[object];
                let v = vertex_index - place.vertex_base as usize;
                let material = match &vertex_materials[object] {
                    Some(materials) => materials[v],
                    None => place.material_base,
                };
                // The model normal, when the vertex's normal is set here (see `normal_when_lit`).
                let model_normal = place.normal_when_lit.then(|| {
                    scene.objects[object]
                        .mesh
                        .normals
                        .get(v)
                        .copied()
                        .unwrap_or(Vec3::ZERO)
                });
                let style = &lit_frame.objects[object];
                let lighting = match fast {
                    Some((o, m, lighting)) if o == object && m == material => lighting,
                    _ => {
                        if let Some((.., Some(previous))) = fast {
                            batch.flush(&previous, colors, vertices, &mut textured_parts);
                        }
                        let lighting = FastLighting::new(lit_frame, material, style, Shading::Gouraud, false);
                        fast = Some((object, material, lighting));
                        batch.normal_matrix = place.normal_when_lit.then_some(place.normal_matrix);
                        batch.tinted = !scene.objects[object].mesh.colors.is_empty();
                        lighting
                    }
                };
                if let Some(lighting) = lighting {
                    // The front side's normal is the vertex normal (`side_normal(n, false)`).
                    let vertex = &vertices[offset];
                    let normal = model_normal.unwrap_or(vertex.normal);
                    // Multiplying by white keeps every bit: untinted vertices take it.
                    let tint = scene.objects[object]
                        .mesh
                        .colors
                        .get(v)
                        .map_or(Vec3::ONE, |tint| tint.truncate());
                    if batch.push(offset, vertex.position, normal, tint) {
                        batch.flush(&lighting, colors, vertices, &mut textured_parts);
                    }
                    continue;
                }
                let vertex = &mut vertices[offset];
                if let Some(normal) = model_normal {
                    vertex.normal = (place.normal_matrix * normal).normalize_or_zero();
                }
                let vertex = *vertex;
                let material = &lit_frame.materials[material as usize];
                let material = match scene.objects[object].mesh.colors.get(v) {
                    Some(tint) => tinted(material, tint.truncate()),
                    None => *material,
                };
                let (textured, rest) =
                    lit_frame.light_material(&material, style, vertex.position, vertex.normal, false);
                colors[offset] = if has_color_texture(&material) {
                    textured_parts.push((vertex_index, textured));
                    rest
                } else {
                    textured + rest
                };
            }
            if let Some((.., Some(lighting))) = fast {
                batch.flush(&lighting, colors, vertices, &mut textured_parts);
            }
            textured_parts
        })
        .collect();
    frame.vertices = vertices;
    frame.vertex_colors = colors;
    let mut textured_parts = textured_parts.into_iter().flatten().peekable();
    if textured_parts.peek().is_some() {
        let mut textured = vec![Vec3::ZERO; frame.vertices.len()];
        for (vertex, part) in textured_parts {
            textured[vertex] = part;
        }
        frame.vertex_colors_textured = textured;
    }
}

/// Up to [`LANES`] vertices of one (object, material) waiting to be lit together, and where
/// their colours go in the chunk.
#[derive(Default)]
struct LightingBatch {
    /// The frame's index of the chunk's first vertex.
    chunk_start: usize,
    len: usize,
    slots: [usize; LANES],
    positions: [Vec3; LANES],
    /// Model normals when `normal_matrix` is set, else the vertices' normals.
    normals: [Vec3; LANES],
    /// The mesh's vertex colours (white where it has none), which multiply `k_d`.
    tints: [Vec3; LANES],
    /// Whether the object's mesh has vertex colours (else `tints` are not read).
    tinted: bool,
    /// The object's normal matrix when the batch sets its vertices' normals (`normal_when_lit`):
    /// they are transformed and normalised lane-wise, with the scalar path's bits.
    normal_matrix: Option<Mat3>,
}

impl LightingBatch {
    /// Adds a vertex; true when the batch is full and must be flushed.
    fn push(&mut self, slot: usize, position: Vec3, normal: Vec3, tint: Vec3) -> bool {
        self.slots[self.len] = slot;
        self.positions[self.len] = position;
        self.normals[self.len] = normal;
        self.tints[self.len] = tint;
        self.len += 1;
        self.len == LANES
    }

    /// Lights the waiting vertices into `colors` (setting their normals in `vertices` first,
    /// when the batch has a normal matrix) and empties the batch. With a colour texture,
    /// `colors` gets the part it does not multiply and `textured_parts` the rest, by vertex
    /// index in the frame. The unused lanes of a partial batch repeat its first vertex, and
    /// their results are dropped.
    fn flush(
        &mut self,
        lighting: &FastLighting,
        colors: &mut [Vec3],
        vertices: &mut [FrameVertex],
        textured_parts: &mut Vec<(usize, Vec3)>,
    ) {
        if self.len == 0 {
            return;
        }
        for lane in self.len..LANES {
            self.positions[lane] = self.positions[0];
            self.normals[lane] = self.normals[0];
            self.tints[lane] = self.tints[0];
        }
        let slots = &self.slots[..self.len];
        let mut normals = Vec3s::from_array(&self.normals);
        if let Some(matrix) = self.normal_matrix {
            normals = normals.transformed_by(matrix).normalize_or_zero();
            for (&slot, normal) in slots.iter().zip(normals.to_array()) {
                vertices[slot].normal = normal;
            }
        }
        let mut surface = SurfaceLanes::of(lighting.material());
        if self.tinted {
            surface.diffuse = surface.diffuse * Vec3s::from_array(&self.tints);
        }
        let lit = lighting.light_surface_lanes(Vec3s::from_array(&self.positions), normals, &surface);
        if has_color_texture(lighting.material()) {
            let (textured, rest) = (lit.textured.to_array(), lit.rest.to_array());
            for (lane, &slot) in slots.iter().enumerate() {
                colors[slot] = rest[lane];
                textured_parts.push((self.chunk_start + slot, textured[lane]));
            }
        } else {
            for (&slot, &color) in slots.iter().zip(&(lit.textured + lit.rest).to_array()) {
                colors[slot] = color;
            }
        }
        self.len = 0;
    }
}

/// The image triangles are set up for: its size, sample pattern and guard band.
pub(crate) struct Viewport {
    pub(crate) width: u32,
    pub(crate) height: u32,
    pattern: SamplePattern,
    /// `pattern.reach()`, asked once per triangle.
    sample_reach: i64,
    /// The guard band's half extents in NDC units (the viewport is 1).
    pub(crate) guard_x: f32,
    pub(crate) guard_y: f32,
}

impl Viewport {
    pub(crate) fn new(width: u32, height: u32, pattern: SamplePattern) -> Self {
        Viewport {
            width,
            height,
            pattern,
            sample_reach: pattern.reach(),
            guard_x: GUARD_BAND_PIXELS / width as f32,
            guard_y: GUARD_BAND_PIXELS / height as f32,
        }
    }
}

/// A vertex of the frame in clip space, and projected to the screen when it lies inside every
/// clip plane (so triangles that need no clipping reuse it instead of projecting their corners
/// again).
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct ProjectedVertex {
    pub(crate) clip: Vec4,
    /// Snapped to fixed point; meaningful only when `inside`.
    pub(crate) screen: SnappedVertex,
    pub(crate) inside: bool,
}

impl ProjectedVertex {
    /// The vertex at `clip` on a `width` × `height` image whose guard band reaches `guard_x`,
    /// `guard_y` (NDC units).
    #[inline]
    pub(crate) fn new(clip: Vec4, guard_x: f32, guard_y: f32, width: f32, height: f32) -> Self {
        let inside = inside_clip_volume(clip, guard_x, guard_y);
        ProjectedVertex {
            clip,
            screen: if inside {
                SnappedVertex::snap(&project(clip, Vec3::ZERO, width, height)).0
            } else {
                SnappedVertex::default()
            },
            inside,
        }
    }
}

/// Vertices per parallel work item of the vertex pass.
const VERTEX_CHUNK: usize = 4096;

/// Where an object's vertices and materials landed in the frame, for its triangles.
struct PlacedObject {
    vertex_base: u32,
    vertex_count: u32,
    material_base: u32,
    uses_mesh_materials: bool,
    /// From model to eye-relative world normals (inverse transpose).
    normal_matrix: Mat3,
    /// The vertices' normals are left zero by the vertex pass and set when the vertex is lit
    /// (Gouraud; see `add_object_vertices`).
    normal_when_lit: bool,
    mirrored: bool,
    /// Back faces can never be seen: skip them (see [`back_faces_hidden`]).
    skip_back_faces: bool,
}

/// The camera's matrices with the eye moved to the origin.
pub(crate) struct CameraSetup {
    pub(crate) eye: DVec3,
    /// Distance from the eye to the near plane, along `forward`.
    pub(crate) near: f64,
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
        let near = match camera.projection {
            Projection::Perspective { near, .. } | Projection::Orthographic { near, .. } => near,
        };
        CameraSetup {
            eye: camera.eye,
            near,
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
pub(crate) struct ObjectTransforms {
    world_from_model: Mat4,
    pub(crate) clip_from_model: Mat4,
    normal_matrix: Mat3,
    /// A mirroring transform turns counter-clockwise triangles clockwise.
    pub(crate) mirrored: bool,
}

impl ObjectTransforms {
    pub(crate) fn new(object: &Object, camera: &CameraSetup) -> Self {
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

/// Materials, and the per-vertex work of one object: transform, projection, Gouraud lighting.
fn add_object_vertices(
    frame: &mut Frame,
    projected: &mut [ProjectedVertex],
    vertex_base: u32,
    object_index: u32,
    object: &Object,
    camera: &CameraSetup,
    viewport: &Viewport,
) -> PlacedObject {
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
    let vertex_count = mesh.positions.len();

    // Positions and normals, transformed and projected once per vertex (not per triangle
    // corner), in chunks: one parallel pass over the object's vertices, which writes every
    // element of its ranges of `frame.vertices` and `projected` (see `overwritable`).
    let range = vertex_base as usize..vertex_base as usize + vertex_count;
    let (width, height) = (viewport.width as f32, viewport.height as f32);
    // Only smooth shading reads vertex normals: flat and constant shading light with the face
    // normal. Gouraud shading reads only those of the
    // vertices it lights, which get theirs then (`light_gouraud_vertices`): the triangles
    // tell which (debug views read the others).
    let normal_when_lit = style.shading == Shading::Gouraud && frame.debug_view.is_none();
    let needs_normals = matches!(style.shading, Shading::Gouraud | Shading::Phong) && !normal_when_lit;
    frame.vertices[range.clone()]
        .par_chunks_mut(VERTEX_CHUNK)
        .zip(projected[range].par_chunks_mut(VERTEX_CHUNK))
        .enumerate()
        .for_each(|(chunk, (vertices, projected))| {
            let first = chunk * VERTEX_CHUNK;
            // The normals are read only when needed: on dense meshes this pass is bound by memory.
            let positions = &mesh.positions[first..];
            for (offset, ((vertex, projected), &p)) in
                vertices.iter_mut().zip(projected).zip(positions).enumerate()
            {
                *vertex = FrameVertex {
                    position: transforms.world_from_model.transform_point3(p),
                    normal: if needs_normals {
                        (transforms.normal_matrix * mesh.normals[first + offset]).normalize_or_zero()
                    } else {
                        Vec3::ZERO
                    },
                };
                let clip = transforms.clip_from_model * p.extend(1.0);
                *projected = ProjectedVertex::new(clip, viewport.guard_x, viewport.guard_y, width, height);
            }
        });

    let attributes =
        !mesh.uvs.is_empty() || !mesh.uvs1.is_empty() || !mesh.colors.is_empty() || !mesh.tangents.is_empty();
    if frame.vertex_attributes.capacity() > 0 {
        frame
            .vertex_attributes
            .resize(vertex_base as usize, VertexAttributes::default());
        frame.vertex_attributes.extend((0..vertex_count).map(|v| {
            if !attributes {
                return VertexAttributes::default();
            }
            let tangent = mesh.tangents.get(v).map_or(Vec4::ZERO, |t| {
                let direction = transforms
                    .world_from_model
                    .transform_vector3(t.truncate())
                    .normalize_or_zero();
                let handedness = if transforms.mirrored { -t.w } else { t.w };
                direction.extend(handedness)
            });
            VertexAttributes {
                uv: mesh.uvs.get(v).copied().unwrap_or(Vec2::ZERO),
                uv1: mesh.uvs1.get(v).copied().unwrap_or(Vec2::ZERO),
                tint: mesh.colors.get(v).map_or(Vec3::ONE, |c| c.truncate()),
                tangent,
            }
        }));
    }

    // Constant shading: one colour per material for the whole object, lit at the centre of its
    // bounds with the normal facing the viewer.
    frame.constant_colors.resize(frame.materials.len(), Vec3::ZERO);
    if style.shading == Shading::Constant {
        let (center, normal) = constant_point(mesh, &transforms, &frame.viewer);
        for material in material_base..material_base + material_count {
            frame.constant_colors[material as usize] = frame.light(material, &style, center, normal, false);
        }
    }
    PlacedObject {
        vertex_base,
        vertex_count: vertex_count as u32,
        material_base,
        uses_mesh_materials,
        normal_matrix: transforms.normal_matrix,
        normal_when_lit,
        mirrored: transforms.mirrored,
        skip_back_faces: back_faces_hidden(object, camera),
    }
}

/// Where a constant-shaded object is lit: the centre of its mesh's bounds (eye-relative), with
/// the normal facing the viewer.
fn constant_point(mesh: &crate::mesh::Mesh, transforms: &ObjectTransforms, viewer: &Viewer) -> (Vec3, Vec3) {
    let (lo, hi) = mesh.bounds().unwrap_or((Vec3::ZERO, Vec3::ZERO));
    let center = transforms.world_from_model.transform_point3((lo + hi) / 2.0);
    (center, viewer.to_viewer(center))
}

/// [`constant_point`] of a scene's object, for the pixel inspector.
pub(crate) fn constant_lighting_point(object: &Object, scene: &Scene, viewer: &Viewer) -> (Vec3, Vec3) {
    let camera = CameraSetup::new(
        &scene.camera,
        scene.image.width as f64 / scene.image.height as f64,
    );
    constant_point(&object.mesh, &ObjectTransforms::new(object, &camera), viewer)
}

/// Whether no back face of `object` can be seen: its mesh is closed and its bounding sphere lies
/// wholly beyond the near plane. Then the eye is outside the surface and no clipping plane cuts
/// it open (the far plane only removes what lies behind the front faces), so every ray meets a
/// front face before any back face, and skipping back faces changes no pixel but those where
/// rounding let a back face win at the silhouette. OpenGL programs enable face culling for such
/// meshes; this does it only when it is safe.
pub(crate) fn back_faces_hidden(object: &Object, camera: &CameraSetup) -> bool {
    // An open mesh's bounds are not needed: they cost a pass over its vertices.
    object.mesh.closed && back_faces_hidden_within(object, object.mesh.bounds(), camera)
}

/// [`back_faces_hidden`] of an object whose mesh's bounds are `mesh_bounds`
/// ([`Mesh::bounds`](crate::mesh::Mesh::bounds)), for a caller that has them already.
pub(crate) fn back_faces_hidden_within(
    object: &Object,
    mesh_bounds: Option<(Vec3, Vec3)>,
    camera: &CameraSetup,
) -> bool {
    let Some((lo, hi)) = mesh_bounds.filter(|_| object.mesh.closed) else {
        return false;
    };
    let center = object.transform.transform_point3(((lo + hi) / 2.0).as_dvec3()) - camera.eye;
    let linear = DMat3::from_mat4(object.transform);
    let largest_scale = [linear.x_axis, linear.y_axis, linear.z_axis]
        .map(DVec3::length)
        .into_iter()
        .fold(0.0, f64::max);
    let radius = f64::from((hi - lo).length() / 2.0) * largest_scale;
    // A little margin for the rounding of the transforms to f32.
    center.dot(camera.forward) - radius * 1.001 > camera.near
}

/// Whether a clip-space point lies inside the near and far planes and the guard band.
#[inline]
fn inside_clip_volume(p: Vec4, guard_x: f32, guard_y: f32) -> bool {
    // Written so that NaN compares false: a NaN vertex is never inside.
    p.z <= p.w && p.z >= 0.0 && p.x.abs() <= guard_x * p.w && p.y.abs() <= guard_y * p.w && p.w > 0.0
}

/// The perspective divide and viewport mapping of a clip-space point with `w > 0`.
#[inline]
pub(crate) fn project(position: Vec4, weights: Vec3, width: f32, height: f32) -> ScreenVertex {
    let inv_w = 1.0 / position.w;
    let ndc = position.xyz() * inv_w;
    ScreenVertex {
        x: (ndc.x + 1.0) * 0.5 * width,
        y: (1.0 - ndc.y) * 0.5 * height,
        depth: ndc.z,
        inv_w,
        weights,
    }
}

/// The per-triangle work: one frame triangle per scene triangle, and the raster triangles of
/// each chunk of the stream, binned into tiles by the chunk itself (in parallel).
fn add_triangles(
    frame: &mut Frame,
    scene: &Scene,
    placed: &[PlacedObject],
    projected: &[ProjectedVertex],
    viewport: &Viewport,
    seen_vertices: &[AtomicBool],
    mut spare_chunks: Vec<RasterChunk>,
) {
    // Where each object's triangles start in the scene's stream.
    let mut object_starts = Vec::with_capacity(scene.objects.len() + 1);
    let mut total = 0usize;
    for object in &scene.objects {
        object_starts.push(total);
        total += object.mesh.triangles.len();
    }
    object_starts.push(total);

    spare_chunks.resize_with(total.div_ceil(TRIANGLE_CHUNK), RasterChunk::default);
    let frame_ref = &*frame;
    spare_chunks
        .par_iter_mut()
        .enumerate()
        .for_each(|(chunk, raster_chunk)| {
            let first = chunk * TRIANGLE_CHUNK;
            let chunk_len = TRIANGLE_CHUNK.min(total - first);
            let mut raster = RasterOutput {
                triangles: raster_chunk.take_triangles(),
                clipped_weights: std::mem::take(&mut raster_chunk.clipped_weights),
            };
            raster.triangles.reserve(chunk_len);
            raster.clipped_weights.clear();
            // The chunk in runs of one object each: what depends on the object is looked up
            // once per run.
            let mut object = object_starts.partition_point(|&start| start <= first) - 1;
            let mut run_start = 0;
            while run_start < chunk_len {
                while first + run_start >= object_starts[object + 1] {
                    object += 1;
                }
                let run_end = (object_starts[object + 1] - first).min(chunk_len);
                let mesh = &scene.objects[object].mesh;
                let place = &placed[object];
                let style = &frame_ref.objects[object];
                let marks_vertices = style.shading == Shading::Gouraud;
                let cull_back_faces = style.back_faces == BackFaces::Cull || place.skip_back_faces;
                let first_t = first + run_start - object_starts[object];
                for t in first_t..first_t + (run_end - run_start) {
                    let corners = mesh.triangles[t];
                    let corners = if place.mirrored {
                        [corners[0], corners[2], corners[1]]
                    } else {
                        corners
                    };
                    let material = if place.uses_mesh_materials {
                        place.material_base + mesh.triangle_materials.get(t).copied().unwrap_or(0)
                    } else {
                        place.material_base
                    };
                    let triangle = FrameTriangle {
                        vertices: corners.map(|v| v + place.vertex_base),
                        material,
                        object: object as u32,
                    };
                    let before = raster.triangles.len();
                    let source = (object_starts[object] + t) as u32;
                    add_raster_triangles(
                        &triangle,
                        cull_back_faces,
                        source,
                        projected,
                        viewport,
                        &mut raster,
                    );
                    if marks_vertices && raster.triangles.len() > before {
                        for v in triangle.vertices {
                            seen_vertices[v as usize].store(true, Ordering::Relaxed);
                        }
                    }
                }
                run_start = run_end;
            }
            raster_chunk.rebin(raster.triangles, &frame_ref.tiles);
            raster_chunk.clipped_weights = raster.clipped_weights;
        });
    spare_chunks.truncate(total.div_ceil(TRIANGLE_CHUNK));
    frame.raster = spare_chunks;
}

/// A chunk's raster triangles as the geometry stage appends them, and the corner weights of
/// those that were clipped (see `CornerWeights`).
pub(crate) struct RasterOutput {
    pub(crate) triangles: Vec<RasterTriangle>,
    pub(crate) clipped_weights: Vec<[Vec3; 3]>,
}

/// Appends the raster triangles of one frame triangle: none if it is culled or invisible, one
/// if it needs no clipping, a fan if it does. `cull_back_faces`: whether a back-facing
/// triangle of its object is dropped (decided once per object, not per triangle).
fn add_raster_triangles(
    triangle: &FrameTriangle,
    cull_back_faces: bool,
    source: u32,
    projected: &[ProjectedVertex],
    viewport: &Viewport,
    raster: &mut RasterOutput,
) {
    let corners = triangle.vertices.map(|v| &projected[v as usize]);
    let facing = homogeneous_facing(corners.map(|v| v.clip));
    let back_facing = facing < 0.0;
    if facing == 0.0 || facing.is_nan() || (back_facing && cull_back_faces) {
        return; // edge-on, degenerate, non-finite, or culled
    }
    let source = SourceTriangle {
        index: source,
        triangle: *triangle,
        back_facing,
    };
    set_up_raster_triangles(corners, source, viewport, raster);
}

/// Appends the raster triangles of a triangle with the projected corners `corners`: none if it
/// covers no sample, one if it needs no clipping, a fan if it does.
#[inline(always)]
pub(crate) fn set_up_raster_triangles(
    corners: [&ProjectedVertex; 3],
    source: SourceTriangle,
    viewport: &Viewport,
    raster: &mut RasterOutput,
) {
    let (width, height) = (viewport.width, viewport.height);
    let clip = corners.map(|v| v.clip);
    if corners.iter().all(|v| v.inside) {
        let screen = corners.map(|v| v.screen);
        let setup = sample_bounds(&screen, width, height, viewport.sample_reach)
            .and_then(|bounds| setup_within(screen, None, bounds, source, &mut raster.clipped_weights));
        raster.triangles.extend(setup);
        return;
    }
    let weights = &mut raster.clipped_weights;
    let mut setup = |corners: [ScreenVertex; 3]| {
        setup_triangle(corners, width, height, viewport.pattern, source, weights)
    };
    let triangles = &mut raster.triangles;
    match clip_triangle(clip, viewport.guard_x, viewport.guard_y) {
        Clipped::Outside => {}
        Clipped::Inside => {
            let corners = [0, 1, 2].map(|i| project(clip[i], Vec3::AXES[i], width as f32, height as f32));
            triangles.extend(setup(corners));
        }
        Clipped::Polygon(polygon) => {
            let projected: Vec<ScreenVertex> = polygon
                .vertices()
                .iter()
                .map(|v| project(v.position, v.weights, width as f32, height as f32))
                .collect();
            for i in 1..projected.len().saturating_sub(1) {
                triangles.extend(setup([projected[0], projected[i], projected[i + 1]]));
            }
        }
    }
}

/// The sign of `det[x y w]` of the clip-space corners: positive when the triangle is seen from
/// its front (counter-clockwise), negative from behind, zero edge-on. Unlike a screen-space
/// area it is right even when corners lie behind the eye (Olano & Greer, homogeneous
/// rasterization). Computed in `f64` so that nearly edge-on triangles get a reliable sign.
pub(crate) fn homogeneous_facing(clip: [Vec4; 3]) -> f64 {
    let [a, b, c] = clip.map(|p| DVec3::new(p.x as f64, p.y as f64, p.w as f64));
    a.dot(b.cross(c))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{LightingComponent, NormalInterpolation};

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

    fn sphere_object(center: DVec3, scale: f64, mesh: crate::mesh::Mesh) -> Object {
        Object {
            name: "object".into(),
            mesh: Arc::new(mesh),
            transform: DMat4::from_translation(center) * DMat4::from_scale(DVec3::splat(scale)),
            shading: Shading::Phong,
            material: None,
            back_faces: BackFaces::ReverseLit,
            component: LightingComponent::All,
            normal_interpolation: NormalInterpolation::Nlerp,
        }
    }

    fn camera(near: f64) -> CameraSetup {
        let camera = Camera {
            eye: DVec3::new(0.0, 0.0, 10.0),
            target: DVec3::ZERO,
            up: DVec3::Y,
            projection: Projection::Perspective {
                fov_y_degrees: 60.0,
                near,
                far: 100.0,
            },
        };
        CameraSetup::new(&camera, 1.5)
    }

    #[test]
    fn back_faces_are_skipped_only_when_they_cannot_be_seen() {
        use crate::mesh::primitives;
        let sphere = || primitives::sphere(8);
        // A closed sphere well beyond the near plane: its back faces are hidden.
        assert!(back_faces_hidden(
            &sphere_object(DVec3::ZERO, 1.0, sphere()),
            &camera(0.1)
        ));
        assert!(back_faces_hidden(
            &sphere_object(DVec3::ZERO, 1.0, primitives::cube()),
            &camera(0.1)
        ));
        // The near plane cuts it open: the inside shows.
        assert!(!back_faces_hidden(
            &sphere_object(DVec3::ZERO, 1.0, sphere()),
            &camera(9.5)
        ));
        // The eye is inside it.
        assert!(!back_faces_hidden(
            &sphere_object(DVec3::ZERO, 20.0, sphere()),
            &camera(0.1)
        ));
        // Behind the eye: nothing of it is drawn anyway, and it is not beyond the near plane.
        assert!(!back_faces_hidden(
            &sphere_object(DVec3::new(0.0, 0.0, 20.0), 1.0, sphere()),
            &camera(0.1)
        ));
        // A plane is open: its back is seen from the other side.
        assert!(!back_faces_hidden(
            &sphere_object(DVec3::ZERO, 1.0, primitives::plane()),
            &camera(0.1)
        ));
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
