//! The pixel inspector: what the frame drew at one pixel, and why it has its colour.
//!
//! Computed on demand, for one pixel, through the frame's own code: the geometry stage builds
//! the frame (with its shadow maps), the rasterizer fills the visibility buffer of the one tile
//! holding the pixel (same setup, fill rule and depth test, so the same triangle wins), the
//! shade stage shades that tile (so the colour reported is the one the frame wrote), and the
//! shading point of each triangle the pixel shows is found by the multisample pass's own code.
//! Then the point is lit again through the scalar specification the lanes are held to
//! (`shade::phong_surface`, `Frame::light_side_terms`, `lighting::illuminate_each_light`),
//! keeping every light's part of the sums as it is added. So the parts add up, in the order
//! given, to the frame's bits: nothing here is a second, approximate renderer. Rendering
//! itself never calls this module; a frame costs nothing more for it.
//!
//! What a pixel's colour is made of, by shading mode:
//! - Phong: the lighting of the pixel's own point, with its interpolated (and normal-mapped)
//!   normal and its textured material;
//! - Flat: the lighting of the triangle's centroid with its face normal (the texture, if any,
//!   multiplies the ambient and diffuse part at the pixel);
//! - Gouraud: the lighting of each of the three vertices, interpolated to the pixel;
//! - Constant: the lighting of the object's centre with the camera's view (`geometry`).
//!
//! With multisampling a pixel shows up to one triangle per sample: each is reported with its
//! sample count and shading point, and the pixel is their mean weighted by sample count, the
//! background filling the samples no triangle covers.

use glam::{DVec3, Vec3};

use crate::lighting::{LightContribution, LightingTerms};
use crate::render::frame::{Frame, has_color_texture, select_component_split, tinted};
use crate::render::framebuffer::TileTarget;
use crate::render::raster::{SUBPIXEL_ONE, SamplePattern, rasterize_tile};
use crate::render::shade::{self, PhongSurface, TexelRead, TileScratch, source_weights};
use crate::render::{DebugView, RenderOptions, TILE_SIZE, geometry, shadow};
use crate::scene::{LightingComponent, Material, Scene, Shading};

/// Everything about one pixel of a frame.
#[derive(Debug, Clone, PartialEq)]
pub struct PixelInspection {
    pub x: u32,
    pub y: u32,
    /// Samples per pixel of the frame.
    pub samples: u32,
    /// The pixel's linear colour as the frame wrote it, before clamping and quantising.
    pub color: Vec3,
    /// The scene's background colour, which fills the samples no triangle covers.
    pub background: Vec3,
    /// Samples no triangle covers.
    pub background_samples: u32,
    /// The debug view the frame shows, if any (the depth view's colours are normalised over the
    /// whole frame afterwards; `color` is then the distance before that).
    pub debug_view: Option<DebugView>,
    /// Each distinct triangle the pixel's samples show, in the order of their first samples;
    /// empty for a background pixel.
    pub surfaces: Vec<SurfaceInspection>,
}

/// One triangle as a pixel sees it.
#[derive(Debug, Clone, PartialEq)]
pub struct SurfaceInspection {
    /// The scene object (index into `Scene::objects`).
    pub object: usize,
    /// The triangle's number in its object's mesh (`Mesh::triangles`).
    pub mesh_triangle: usize,
    /// The mesh's vertex numbers of the triangle, in the mesh's order.
    pub mesh_vertices: [u32; 3],
    /// Perspective-correct barycentric weights of `mesh_vertices` at the shading point.
    pub barycentrics: Vec3,
    /// Samples of the pixel that show this triangle.
    pub sample_count: u32,
    /// Where it is shaded, in pixels from the image's top-left corner.
    pub shading_point: (f64, f64),
    /// Reversed-Z depth of its first sample (1 at the near plane, 0 at the far plane).
    pub depth: f32,
    /// Distance from the eye along the view direction.
    pub view_distance: f32,
    /// World position of the shading point.
    pub position: DVec3,
    /// The interpolated normal (front side; normal-mapped where the material has a normal
    /// map); the face normal for flat and constant shading.
    pub normal: Vec3,
    /// The triangle's face normal (front side).
    pub geometric_normal: Vec3,
    pub back_facing: bool,
    pub shading: Shading,
    pub component: LightingComponent,
    /// Where the material comes from.
    pub material_origin: MaterialOrigin,
    /// The material as lit: coefficients multiplied by textures and vertex colours where the
    /// shading mode does so at the point (Phong).
    pub material: Material,
    /// The texture lookups of the point (Phong), or of the pixel's colour texture (flat,
    /// Gouraud).
    pub texels: Vec<TexelRead>,
    pub lighting: SurfaceLighting,
    /// This triangle's colour at the pixel, as the frame computed it for this shading point.
    pub color: Vec3,
}

/// Where an object's material comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MaterialOrigin {
    /// The object's `material` (a name or an inline material).
    Object,
    /// The mesh file's own material with this index (MTL, glTF).
    Mesh(u32),
    /// Neither: the default material.
    Default,
}

/// How a surface's colour at the pixel is made from lighting.
#[derive(Debug, Clone, PartialEq)]
pub enum SurfaceLighting {
    /// Lit at the pixel (Phong).
    Pixel(LightingBreakdown),
    /// Lit once for the triangle, at its centroid (flat).
    Triangle(LightingBreakdown),
    /// Lit once for the object, at its centre with the normal facing the viewer (constant).
    Object(LightingBreakdown),
    /// Lit at the three vertices (Gouraud), in `mesh_vertices` order, and interpolated.
    Vertices(Box<[LightingBreakdown; 3]>),
    /// A debug view of the normal or the depth: no lighting.
    DebugView,
}

/// The lighting of one point, term by term and light by light.
#[derive(Debug, Clone, PartialEq)]
pub struct LightingBreakdown {
    /// The terms' sums: `diffuse` and `specular` are the lights' parts added in order from zero.
    pub terms: LightingTerms,
    /// Per light of the scene, in order, its part (zero when it does not reach the point).
    pub lights: Vec<LightContribution>,
    /// The side's normal the point is lit with (flipped for the back of a two-sided object).
    pub normal: Vec3,
    /// Whether the lights reach the side (not the back of an object with unlit back faces).
    pub lit_side: bool,
    /// The terms shown, split as the frame splits them: (ambient + diffuse, the part a colour
    /// texture multiplies; specular + emission).
    pub shown: (Vec3, Vec3),
    /// The colour: `shown.0 + shown.1` (times the texture for a textured flat or Gouraud pixel,
    /// see [`SurfaceInspection::color`]).
    pub color: Vec3,
}

/// Why a pixel cannot be inspected.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum PickError {
    #[error("pixel ({x}, {y}) is outside the {width}×{height} image")]
    OutOfRange { x: u32, y: u32, width: u32, height: u32 },
}

/// Inspects pixel `(x, y)` of `scene` rendered with `options` (see the module documentation).
pub fn inspect_pixel(
    scene: &Scene,
    options: &RenderOptions,
    x: u32,
    y: u32,
) -> Result<PixelInspection, PickError> {
    let (width, height) = (scene.image.width, scene.image.height);
    if x >= width || y >= height {
        return Err(PickError::OutOfRange { x, y, width, height });
    }
    let pattern = SamplePattern::new(scene.image.samples).unwrap_or(SamplePattern::SINGLE);
    let mut spare = geometry::SpareBuffers::default();
    let shadows = shadow::render_shadow_maps(scene, scene.camera.eye, &mut Default::default(), &mut spare);
    let frame = geometry::build_frame_in(scene, pattern, options.debug_view, shadows, &mut spare);
    let tile = (y / TILE_SIZE) as usize * frame.tiles.columns as usize + (x / TILE_SIZE) as usize;
    let rect = frame.tiles.rect(tile);
    let visibility = rasterize_tile(rect, pattern, &frame.raster, tile);

    // The tile shaded as the frame shades it, into rows as wide as the image.
    let stride = width as usize;
    let rows = rect.height() as usize;
    let mut color = vec![Vec3::ZERO; rows * stride];
    let mut covered = vec![false; rows * stride];
    let mut target = TileTarget {
        color: &mut color,
        covered: &mut covered,
        stride,
    };
    shade::shade_tile(
        &frame,
        &visibility,
        scene.image.background,
        &mut target,
        &mut TileScratch::default(),
    );
    let pixel_color = color[(y - rect.y0) as usize * stride + x as usize];

    let pixel = ((y - rect.y0) * rect.width() + (x - rect.x0)) as usize;
    let first_samples = &visibility.triangle[pixel * pattern.len()..(pixel + 1) * pattern.len()];
    let depths = &visibility.depth[pixel * pattern.len()..(pixel + 1) * pattern.len()];
    let points = shade::pixel_shading_points(&visibility, x, y);
    let surfaces = points
        .iter()
        .map(|&(local, count, at)| {
            let first = first_samples.iter().position(|&id| id == local).unwrap_or(0);
            inspect_surface(
                scene,
                &frame,
                visibility.raster_id(local),
                count,
                at,
                depths[first],
            )
        })
        .collect::<Vec<_>>();
    let covered_samples: u32 = surfaces.iter().map(|s| s.sample_count).sum();
    Ok(PixelInspection {
        x,
        y,
        samples: pattern.len() as u32,
        color: pixel_color,
        background: scene.image.background,
        background_samples: pattern.len() as u32 - covered_samples,
        debug_view: options.debug_view,
        surfaces,
    })
}

/// The triangle with raster id `id` at the shading point `at` (1/256 pixel).
fn inspect_surface(
    scene: &Scene,
    frame: &Frame,
    id: u32,
    sample_count: u32,
    at: (i64, i64),
    depth: f32,
) -> SurfaceInspection {
    let raster = frame.raster_triangle(id);
    let corners = frame.corner_weights(id);
    let triangle = &raster.triangle;
    let object_index = triangle.object as usize;
    let object = &scene.objects[object_index];
    let style = &frame.objects[object_index];
    let back = raster.back_facing;

    // The frame's triangle stream is the objects' meshes one after another; the vertices too.
    let first_triangle: usize = scene.objects[..object_index]
        .iter()
        .map(|o| o.mesh.triangles.len())
        .sum();
    let vertex_base: u32 = scene.objects[..object_index]
        .iter()
        .map(|o| o.mesh.positions.len() as u32)
        .sum();
    let mesh_triangle = raster.source as usize - first_triangle;
    let mesh_vertices = object.mesh.triangles[mesh_triangle];
    // The frame's corners are the mesh's, reordered for a mirroring transform: put the weights
    // back in the mesh's order.
    let weights = source_weights(raster, &corners, at);
    let frame_corners = triangle.vertices.map(|v| v - vertex_base);
    let in_mesh_order = |values: [Vec3; 3]| -> [Vec3; 3] {
        mesh_vertices.map(|v| {
            let k = frame_corners.iter().position(|&c| c == v).unwrap_or(0);
            values[k]
        })
    };
    let weight_list = in_mesh_order([
        Vec3::splat(weights.x),
        Vec3::splat(weights.y),
        Vec3::splat(weights.z),
    ]);
    let barycentrics = Vec3::new(weight_list[0].x, weight_list[1].x, weight_list[2].x);

    let [a, b, c] = triangle.vertices.map(|v| &frame.vertices[v as usize]);
    let position = a.position * weights.x + b.position * weights.y + c.position * weights.z;
    let geometric_normal = frame.face_normal(triangle);
    let material_origin = match (&object.material, object.mesh.materials.is_empty()) {
        (Some(_), _) => MaterialOrigin::Object,
        (None, false) => MaterialOrigin::Mesh(
            object
                .mesh
                .triangle_materials
                .get(mesh_triangle)
                .copied()
                .unwrap_or(0),
        ),
        (None, true) => MaterialOrigin::Default,
    };
    let frame_material = frame.materials[triangle.material as usize];
    let footprint = (
        source_weights(raster, &corners, (at.0 + SUBPIXEL_ONE, at.1)),
        source_weights(raster, &corners, (at.0, at.1 + SUBPIXEL_ONE)),
    );
    let surface = shade::phong_surface(frame, raster, weights, footprint);
    let debug_view = matches!(frame.debug_view, Some(DebugView::Normals | DebugView::Depth));

    let explain = |material: &Material, position: Vec3, normal: Vec3, back: bool| -> LightingBreakdown {
        let lit_side = !(back && style.back_faces == crate::scene::BackFaces::Unlit);
        let normal = style.side_normal(normal, back);
        let mut lights = vec![LightContribution::default(); frame.lights.len()];
        let terms = frame.light_side_terms(material, position, normal, lit_side, |index, part| {
            lights[index] = *part;
        });
        let shown = select_component_split(frame.debug_view, style.component, &terms);
        LightingBreakdown {
            terms,
            lights,
            normal,
            lit_side,
            shown,
            color: shown.0 + shown.1,
        }
    };
    let texture_at_pixel: Vec<TexelRead> = surface.texels[0].into_iter().collect();
    let (material, normal, texels, lighting, color) = if debug_view {
        let frame_color = surface_color_of_frame(frame, raster, &corners, at, &surface);
        (
            frame_material,
            surface.normal,
            Vec::new(),
            SurfaceLighting::DebugView,
            frame_color,
        )
    } else {
        match style.shading {
            Shading::Phong => {
                let breakdown = explain(&surface.material, position, surface.normal, back);
                let color = breakdown.color;
                let texels = surface.texels.iter().flatten().copied().collect();
                (
                    surface.material,
                    surface.normal,
                    texels,
                    SurfaceLighting::Pixel(breakdown),
                    color,
                )
            }
            Shading::Flat => {
                let [p0, p1, p2] = triangle.vertices.map(|v| frame.vertices[v as usize].position);
                let centroid = (p0 + p1 + p2) / 3.0;
                let material = if frame.vertex_attributes.is_empty() {
                    frame_material
                } else {
                    tinted(&frame_material, frame.flat_tint(triangle))
                };
                let breakdown = explain(&material, centroid, geometric_normal, back);
                let color = modulated(&material, breakdown.shown, &surface);
                let texels = if has_color_texture(&material) {
                    texture_at_pixel
                } else {
                    Vec::new()
                };
                (
                    material,
                    geometric_normal,
                    texels,
                    SurfaceLighting::Triangle(breakdown),
                    color,
                )
            }
            Shading::Gouraud => {
                let per_vertex = triangle.vertices.map(|v| {
                    let vertex = &frame.vertices[v as usize];
                    let material = tinted(&frame_material, frame.attributes(v).tint);
                    explain(&material, vertex.position, vertex.normal, back)
                });
                let parts = per_vertex.clone().map(|breakdown| {
                    if has_color_texture(&frame_material) {
                        breakdown.shown
                    } else {
                        (Vec3::ZERO, breakdown.color)
                    }
                });
                let rest = shade::gouraud_color_at(raster, &corners, parts.map(|p| p.1), at);
                let color = if has_color_texture(&frame_material) {
                    let textured = shade::gouraud_color_at(raster, &corners, parts.map(|p| p.0), at);
                    rest + textured * modulation(&surface)
                } else {
                    rest
                };
                let [v0, v1, v2] = per_vertex;
                let reorder = in_mesh_order([Vec3::X, Vec3::Y, Vec3::Z]);
                let pick = |axis: Vec3| match axis {
                    a if a == Vec3::X => v0.clone(),
                    a if a == Vec3::Y => v1.clone(),
                    _ => v2.clone(),
                };
                let vertices = reorder.map(pick);
                let texels = if has_color_texture(&frame_material) {
                    texture_at_pixel
                } else {
                    Vec::new()
                };
                let normal = surface.normal;
                (
                    frame_material,
                    normal,
                    texels,
                    SurfaceLighting::Vertices(Box::new(vertices)),
                    color,
                )
            }
            Shading::Constant => {
                // Lit once for the object, from its front (`geometry`).
                let (centre, normal) = geometry::constant_lighting_point(object, scene, &frame.viewer);
                let breakdown = explain(&frame_material, centre, normal, false);
                let color = frame.constant_colors[triangle.material as usize];
                (
                    frame_material,
                    geometric_normal,
                    Vec::new(),
                    SurfaceLighting::Object(breakdown),
                    color,
                )
            }
        }
    };
    let eye = scene.camera.eye;
    SurfaceInspection {
        object: object_index,
        mesh_triangle,
        mesh_vertices,
        barycentrics,
        sample_count,
        shading_point: (
            at.0 as f64 / SUBPIXEL_ONE as f64,
            at.1 as f64 / SUBPIXEL_ONE as f64,
        ),
        depth,
        view_distance: position.dot(frame.forward),
        position: eye + position.as_dvec3(),
        normal,
        geometric_normal,
        back_facing: back,
        shading: style.shading,
        component: style.component,
        material_origin,
        material,
        texels,
        lighting,
        color,
    }
}

/// A flat pixel's colour from its triangle's lighting split `shown`: the part a colour texture
/// multiplies times the texture at the pixel, plus the rest (as the frame's flat shaders do).
fn modulated(material: &Material, shown: (Vec3, Vec3), surface: &PhongSurface) -> Vec3 {
    if has_color_texture(material) {
        shown.1 + shown.0 * modulation(surface)
    } else {
        shown.0 + shown.1
    }
}

/// What multiplies the textured part of a flat or Gouraud pixel: the diffuse texture's value at
/// the pixel, white without one.
fn modulation(surface: &PhongSurface) -> Vec3 {
    surface.texels[0].map_or(Vec3::ONE, |texel| texel.value.truncate())
}

/// The normals or depth view's value of a point, as `shade_sample` computes it.
fn surface_color_of_frame(
    frame: &Frame,
    raster: &crate::render::raster::RasterTriangle,
    corners: &crate::render::raster::Corners,
    at: (i64, i64),
    surface: &PhongSurface,
) -> Vec3 {
    let triangle = &raster.triangle;
    let style = &frame.objects[triangle.object as usize];
    let weights = source_weights(raster, corners, at);
    let [a, b, c] = triangle.vertices.map(|v| frame.vertices[v as usize].position);
    let position = a * weights.x + b * weights.y + c * weights.z;
    match frame.debug_view {
        Some(DebugView::Depth) => Vec3::splat(position.dot(frame.forward)),
        _ => {
            let normal = match style.shading {
                Shading::Flat | Shading::Constant => frame.face_normal(triangle),
                Shading::Gouraud | Shading::Phong => surface.normal,
            };
            style.side_normal(normal, raster.back_facing) * 0.5 + 0.5
        }
    }
}

/// Which pixels of `scene` rendered with `options` show object `object` (an index into
/// `Scene::objects`): per pixel, row-major from the top-left, whether any of its samples does.
/// The frame's own geometry and rasterizer, tile by tile; nothing is shaded.
pub fn object_mask(scene: &Scene, options: &RenderOptions, object: usize) -> Vec<bool> {
    let pattern = SamplePattern::new(scene.image.samples).unwrap_or(SamplePattern::SINGLE);
    // Shadows change no pixel's triangle: the frame is built without its maps.
    let frame = geometry::build_frame(scene, pattern, options.debug_view, Vec::new());
    let width = scene.image.width as usize;
    let mut mask = vec![false; width * scene.image.height as usize];
    for tile in 0..frame.tiles.count() {
        let rect = frame.tiles.rect(tile);
        let visibility = rasterize_tile(rect, pattern, &frame.raster, tile);
        let shows_object: Vec<bool> = visibility
            .raster_ids
            .iter()
            .map(|&id| frame.raster_triangle(id).triangle.object as usize == object)
            .collect();
        let samples = pattern.len();
        for (index, ids) in visibility.triangle.chunks_exact(samples).enumerate() {
            let (column, row) = (index % rect.width() as usize, index / rect.width() as usize);
            let pixel = (rect.y0 as usize + row) * width + rect.x0 as usize + column;
            mask[pixel] = ids
                .iter()
                .any(|&local| shows_object.get(local as usize).copied().unwrap_or(false));
        }
    }
    mask
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use glam::DVec3;

    use super::*;
    use crate::render::render;
    use crate::scene::load::{LoadOptions, load_scene_from_str};

    fn scene(text: &str) -> Scene {
        match load_scene_from_str(Path::new("inspect-test.ron"), text, &LoadOptions::default()) {
            Ok(loaded) => loaded.scene,
            Err(error) => panic!("{:?}", error.diagnostics),
        }
    }

    /// One unit sphere seen from +Z, one directional and one point light, Phong shading.
    const SPHERE: &str = r#"Scene(
        image: (width: 48, height: 48, background: (0.1, 0.2, 0.3)),
        camera: Perspective(eye: (0, 0, 6), target: (0, 0, 0), up: (0, 1, 0), fov: 30),
        ambient: (0.2, 0.2, 0.2),
        lights: [
            Directional(direction: (0, 0, -1), color: (0.5, 0.5, 0.5)),
            Point(position: (0, 3, 3), color: (1, 0.8, 0.6), attenuation: (constant: 1, linear: 0.1, quadratic: 0.05)),
        ],
        objects: [(name: "ball", mesh: Sphere(segments: 96),
                   material: (ambient: (0.3, 0.2, 0.1), diffuse: (0.6, 0.5, 0.4), specular: (0.5, 0.5, 0.5), shininess: 10))],
    )"#;

    /// The equations of `lighting`'s module documentation, worked out in `f64` from the point
    /// and normal alone.
    #[test]
    fn a_phong_pixel_is_lit_as_the_equations_say() {
        let scene = scene(SPHERE);
        let pick = inspect_pixel(&scene, &RenderOptions::default(), 26, 20).unwrap();
        assert_eq!(pick.surfaces.len(), 1);
        let surface = &pick.surfaces[0];
        assert_eq!((surface.object, surface.shading), (0, Shading::Phong));
        // The point lies on the unit sphere (to the tessellation's error), its normal is the
        // sphere's there, and it faces the camera.
        let p = surface.position;
        assert!((p.length() - 1.0).abs() < 2e-3, "{p}");
        let n = surface.normal.as_dvec3();
        assert!((n - p.normalize()).length() < 2e-2, "{n} at {p}");
        assert!(n.z > 0.5 && !surface.back_facing);

        let (ka, kd, ks, shininess) = (
            DVec3::new(0.3, 0.2, 0.1),
            DVec3::new(0.6, 0.5, 0.4),
            DVec3::splat(0.5),
            10,
        );
        let v = (DVec3::new(0.0, 0.0, 6.0) - p).normalize();
        let phong = |l: DVec3, intensity: DVec3, strength: f64| {
            let n_dot_l = n.dot(l);
            let r = 2.0 * n_dot_l * n - l;
            (
                kd * intensity * strength * n_dot_l,
                ks * intensity * strength * r.dot(v).max(0.0).powi(shininess),
                n_dot_l,
            )
        };
        let (diffuse_0, specular_0, n_dot_l_0) = phong(DVec3::Z, DVec3::splat(0.5), 1.0);
        let to_point = DVec3::new(0.0, 3.0, 3.0) - p;
        let d = to_point.length();
        let attenuation = 1.0 / (1.0 + 0.1 * d + 0.05 * d * d);
        let (diffuse_1, specular_1, n_dot_l_1) = phong(to_point / d, DVec3::new(1.0, 0.8, 0.6), attenuation);

        let SurfaceLighting::Pixel(lighting) = &surface.lighting else {
            panic!("a Phong pixel is lit at the pixel: {:?}", surface.lighting);
        };
        let close = |got: Vec3, expected: DVec3, what: &str| {
            assert!(
                (got.as_dvec3() - expected).abs().max_element() < 2e-5,
                "{what}: {got} against {expected} by hand"
            );
        };
        let [directional, point] = lighting.lights.as_slice() else {
            panic!("two lights");
        };
        assert!(directional.reaches && point.reaches);
        assert!((f64::from(directional.n_dot_l) - n_dot_l_0).abs() < 1e-6);
        assert!((f64::from(point.n_dot_l) - n_dot_l_1).abs() < 1e-6);
        assert_eq!(
            (directional.attenuation, directional.spot, directional.visibility),
            (1.0, 1.0, 1.0)
        );
        assert!((f64::from(point.attenuation) - attenuation).abs() < 1e-6);
        assert_eq!((point.spot, point.visibility), (1.0, 1.0));
        close(lighting.terms.ambient, ka * 0.2, "ambient");
        close(lighting.terms.emission, Vec3::ZERO.as_dvec3(), "emission");
        close(directional.diffuse, diffuse_0, "directional diffuse");
        close(directional.specular, specular_0, "directional specular");
        close(point.diffuse, diffuse_1, "point diffuse");
        close(point.specular, specular_1, "point specular");
        let total = ka * 0.2 + diffuse_0 + specular_0 + diffuse_1 + specular_1;
        close(pick.color, total, "the pixel");
    }

    /// The parts, added as the frame adds them, give the frame's pixel bit for bit.
    fn assert_parts_sum_to_the_pixel(lighting: &LightingBreakdown) {
        let (mut diffuse, mut specular) = (Vec3::ZERO, Vec3::ZERO);
        for light in lighting.lights.iter().filter(|light| light.reaches) {
            diffuse += light.diffuse;
            specular += light.specular;
        }
        assert_eq!(diffuse, lighting.terms.diffuse);
        assert_eq!(specular, lighting.terms.specular);
        let terms = &lighting.terms;
        assert_eq!(
            lighting.color,
            (terms.ambient + diffuse) + (specular + terms.emission),
            "every term shown"
        );
    }

    /// Every pixel of a grid, in every shading mode and with a back-lit, cut-open object: the
    /// pick's colour is the rendered frame's pixel, bit for bit, and so is the sum of its parts.
    #[test]
    fn the_parts_sum_to_the_frames_pixel_bit_for_bit() {
        for shading in ["Phong", "Gouraud", "Flat", "Constant"] {
            let text = SPHERE.replace(
                "objects: [(name: \"ball\",",
                &format!(
                    "objects: [(mesh: Cube, translate: (0.6, 0, 1.2), scale: 0.4, shading: {shading}, \
                     material: (diffuse: (0.2, 0.9, 0.2), emission: (0.05, 0, 0))), (name: \"ball\", shading: {shading},"
                ),
            );
            let scene = scene(&text);
            let (frame, _) = render(&scene, &RenderOptions::default());
            let mut surfaces = 0;
            for y in (1..48).step_by(5) {
                for x in (2..48).step_by(5) {
                    let pick = inspect_pixel(&scene, &RenderOptions::default(), x, y).unwrap();
                    let pixel = frame.pixel(x, y);
                    assert_eq!(pick.color, pixel, "{shading} ({x}, {y})");
                    let Some(surface) = pick.surfaces.first() else {
                        assert_eq!(pixel, scene.image.background);
                        continue;
                    };
                    surfaces += 1;
                    assert_eq!(surface.color, pixel, "{shading} ({x}, {y})");
                    match &surface.lighting {
                        SurfaceLighting::Pixel(lighting)
                        | SurfaceLighting::Triangle(lighting)
                        | SurfaceLighting::Object(lighting) => {
                            assert_parts_sum_to_the_pixel(lighting);
                            assert_eq!(lighting.color, pixel, "{shading} ({x}, {y})");
                        }
                        SurfaceLighting::Vertices(vertices) => {
                            vertices.iter().for_each(assert_parts_sum_to_the_pixel);
                        }
                        SurfaceLighting::DebugView => panic!("no debug view was asked for"),
                    }
                }
            }
            assert!(surfaces > 30, "{shading}: {surfaces} pixels show a surface");
        }
    }

    /// Gouraud on a mesh whose triangles alternate between two materials, so that every inner
    /// vertex is shared by triangles of both: each triangle's vertices are lit with its own
    /// material, and the parts still sum to the frame's pixel bit for bit.
    #[test]
    fn gouraud_vertices_shared_by_triangles_of_different_materials_sum_to_the_pixel() {
        let folder = tempfile::tempdir().unwrap();
        let mut obj = String::from("mtllib two.mtl\n");
        // A 5×5 grid of vertices on a bump, 32 triangles, materials alternating.
        for row in 0..5 {
            for column in 0..5 {
                let (x, y) = (column as f32 * 0.5 - 1.0, row as f32 * 0.5 - 1.0);
                let z = 0.6 * (1.0 - (x * x + y * y) / 2.0);
                obj.push_str(&format!("v {x} {y} {z}\n"));
            }
        }
        for row in 0..4 {
            for column in 0..4 {
                let corner = row * 5 + column + 1;
                let (a, b, c, d) = (corner, corner + 1, corner + 6, corner + 5);
                for (k, (p, q, r)) in [(a, b, c), (a, c, d)].into_iter().enumerate() {
                    let material = if (row + column + k) % 2 == 0 {
                        "red"
                    } else {
                        "blue"
                    };
                    obj.push_str(&format!("usemtl {material}\nf {p} {q} {r}\n"));
                }
            }
        }
        std::fs::write(folder.path().join("bump.obj"), obj).unwrap();
        std::fs::write(
            folder.path().join("two.mtl"),
            "newmtl red\nKa 0.3 0.1 0.1\nKd 0.9 0.2 0.1\nKs 0.6 0.6 0.6\nNs 30\n\
             newmtl blue\nKa 0.1 0.1 0.3\nKd 0.1 0.3 0.9\nKs 0.2 0.2 0.2\nNs 5\nKe 0.05 0 0.1\n",
        )
        .unwrap();
        let text = SPHERE.replace(
            "objects: [(name: \"ball\", mesh: Sphere(segments: 96),",
            "objects: [(name: \"bump\", mesh: Obj(\"bump.obj\"), shading: Gouraud, scale: 1.4),
                       (name: \"ball\", mesh: Sphere(segments: 8), translate: (0, 0, -9),",
        );
        let path = folder.path().join("scene.ron");
        std::fs::write(&path, &text).unwrap();
        let scene = match crate::scene::load::load_scene(&path, &LoadOptions::default()) {
            Ok(loaded) => loaded.scene,
            Err(error) => panic!("{:?}", error.diagnostics),
        };
        let materials = &scene.objects[0].mesh.triangle_materials;
        assert!(
            materials.iter().any(|&m| m != materials[0]),
            "two materials: {materials:?}"
        );
        let (frame, _) = render(&scene, &RenderOptions::default());
        let mut checked = 0;
        for y in (0..48).step_by(2) {
            for x in (0..48).step_by(2) {
                let pick = inspect_pixel(&scene, &RenderOptions::default(), x, y).unwrap();
                let pixel = frame.pixel(x, y);
                assert_eq!(pick.color, pixel, "({x}, {y})");
                let Some(surface) = pick.surfaces.first().filter(|s| s.object == 0) else {
                    continue;
                };
                assert_eq!(surface.color, pixel, "({x}, {y})");
                let SurfaceLighting::Vertices(vertices) = &surface.lighting else {
                    panic!("Gouraud lights the vertices");
                };
                vertices.iter().for_each(assert_parts_sum_to_the_pixel);
                checked += 1;
            }
        }
        assert!(checked > 100, "{checked} pixels of the bump");
    }

    /// With multisampling, each distinct triangle of a pixel is reported with its samples, and
    /// their colours resolve to the frame's pixel as the frame resolves them.
    #[test]
    fn multisampled_pixels_resolve_from_their_surfaces() {
        let scene = scene(&SPHERE.replace(
            "background: (0.1, 0.2, 0.3)",
            "background: (0.1, 0.2, 0.3), samples: 4",
        ));
        let (frame, _) = render(&scene, &RenderOptions::default());
        let mut edges = 0;
        for y in 0..48 {
            for x in 0..48 {
                let pick = inspect_pixel(&scene, &RenderOptions::default(), x, y).unwrap();
                let covered: u32 = pick.surfaces.iter().map(|s| s.sample_count).sum();
                assert_eq!(covered + pick.background_samples, 4);
                let mut sum = Vec3::ZERO;
                for surface in &pick.surfaces {
                    sum += surface.color * surface.sample_count as f32;
                }
                let resolved = (sum + pick.background * pick.background_samples as f32) / 4.0;
                let pixel = frame.pixel(x, y);
                assert_eq!(pick.color, pixel, "({x}, {y})");
                if !pick.surfaces.is_empty() {
                    assert_eq!(resolved, pixel, "({x}, {y})");
                }
                edges += usize::from(pick.background_samples > 0 && covered > 0);
            }
        }
        assert!(edges > 10, "{edges} pixels on the silhouette");
    }

    #[test]
    fn background_pixels_and_pixels_outside_the_image() {
        let scene = scene(SPHERE);
        let corner = inspect_pixel(&scene, &RenderOptions::default(), 0, 0).unwrap();
        assert!(corner.surfaces.is_empty());
        assert_eq!(
            (corner.color, corner.background_samples),
            (Vec3::new(0.1, 0.2, 0.3), 1)
        );
        assert_eq!(
            inspect_pixel(&scene, &RenderOptions::default(), 48, 3),
            Err(PickError::OutOfRange {
                x: 48,
                y: 3,
                width: 48,
                height: 48
            })
        );
    }

    #[test]
    fn the_object_mask_is_the_pixels_the_object_shows_in() {
        let scene = scene(SPHERE);
        let (frame, _) = render(&scene, &RenderOptions::default());
        assert_eq!(
            object_mask(&scene, &RenderOptions::default(), 0),
            frame.to_coverage()
        );
    }
}
