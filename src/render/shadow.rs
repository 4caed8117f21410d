//! Shadow maps: the seeds' shadow term `S_i` (seed 001), one depth image per shadow-casting light.
//!
//! Each map is rendered with the same geometry stage and tiled rasterizer as the image (depth
//! only: nothing lit, nothing culled), from the light's point of view:
//! - a directional light looks along its direction with an orthographic projection that just
//!   contains the bounding sphere of every object;
//! - a spot light looks down its axis with a perspective projection covering its cone (up to a
//!   60° cutoff; wider cones use the point-light cube);
//! - a point light renders six 92° perspective faces, one per axis direction (a cube map; the 2°
//!   overlap keeps filter footprints inside a face at the seams).
//!
//! A surface point is tested against the map like this: it is moved along its normal by `bias`
//! texels of the map at its distance (normal-offset bias, which removes self-shadowing "acne"
//! on slopes without the detached shadows, "peter-panning", of a large depth offset), projected
//! into the light's clip space, and compared with the (2r+1)² nearest texels
//! (percentage-closer filtering): the share of texels that do not hold a nearer surface is the
//! light's visibility, between 0 and 1. Points outside a map are lit.
//!
//! Depth is reversed (1 at the light's near plane), so "nearer to the light" is "greater".
//! Everything is computed in the frame's eye-relative space, and the maps are deterministic
//! like the image.

use std::sync::Arc;

use glam::{DMat4, DVec3, Mat4, Vec3, Vec4Swizzles};
use rayon::prelude::*;

use crate::render::TILE_SIZE;
use crate::render::geometry::{CameraSetup, build_depth_frame};
use crate::render::raster::{SamplePattern, Visibility};
use crate::scene::{BoundingSphere, Camera, Light, Projection, Scene, ShadowSettings, bounding_sphere};

/// Spot lights with a wider cutoff than this use the six-face cube, like point lights: a single
/// perspective face would need a field of view too wide to keep texels usefully small.
const MAX_SINGLE_FACE_CUTOFF_DEGREES: f32 = 60.0;
/// Field of view of each cube face: 90° plus a margin so filtering at a face's edge stays inside.
const CUBE_FACE_FOV_DEGREES: f64 = 92.0;

/// The depth image of one view from a light.
#[derive(Debug, Clone, PartialEq)]
struct ShadowFace {
    /// From the frame's eye-relative space to this face's clip space.
    clip_from_frame: Mat4,
    size: u32,
    /// Reversed-Z depth of the nearest surface per texel, row-major from the top; −∞ where none.
    depth: Vec<f32>,
    /// World size of one texel: at unit distance along `forward` (perspective) or everywhere
    /// (orthographic).
    texel_size: f32,
    perspective: bool,
    /// Where the light is (perspective) in the frame's eye-relative space, and where it looks.
    origin: Vec3,
    forward: Vec3,
}

/// A light's shadow map: one face, or six for a point light.
#[derive(Debug, Clone, PartialEq)]
pub struct ShadowMap {
    faces: Vec<ShadowFace>,
    settings: ShadowSettings,
}

impl ShadowMap {
    /// The share of the light that reaches `position` (eye-relative), whose shading normal is
    /// `normal`, from the direction `to_light`: 1 lit, 0 in shadow.
    pub fn visibility(&self, position: Vec3, normal: Vec3, to_light: Vec3) -> f32 {
        let face = if self.faces.len() == 1 {
            &self.faces[0]
        } else {
            // The cube face whose axis is closest to the direction from the light to the point.
            let direction = -to_light;
            let Some(face) = self
                .faces
                .iter()
                .max_by(|a, b| a.forward.dot(direction).total_cmp(&b.forward.dot(direction)))
            else {
                return 1.0;
            };
            face
        };
        face.visibility(position, normal, &self.settings)
    }
}

impl ShadowFace {
    fn visibility(&self, position: Vec3, normal: Vec3, settings: &ShadowSettings) -> f32 {
        let texel = if self.perspective {
            self.texel_size * (position - self.origin).dot(self.forward).max(0.0)
        } else {
            self.texel_size
        };
        // A point `b` above a plane tilted by θ from the light clears every texel within `d` of
        // it when b > d·sin θ: the filter reaches r + ½ texels (nearest-texel rounding), so the
        // offset is the filter's reach plus the user's bias, which covers every slope.
        let reach = settings.filter_radius as f32 + 0.5;
        let offset = position + normal * ((settings.bias + reach) * texel);
        let clip = self.clip_from_frame * offset.extend(1.0);
        if clip.w.is_nan() || clip.w <= 0.0 {
            return 1.0;
        }
        let ndc = clip.xyz() / clip.w;
        if !ndc.is_finite() || ndc.x.abs() > 1.0 || ndc.y.abs() > 1.0 || ndc.z > 1.0 {
            return 1.0;
        }
        let size = self.size as i64;
        let x = (((ndc.x + 1.0) * 0.5 * self.size as f32) as i64).clamp(0, size - 1);
        let y = (((1.0 - ndc.y) * 0.5 * self.size as f32) as i64).clamp(0, size - 1);
        let radius = i64::from(settings.filter_radius);
        let side = 2 * radius + 1;
        let lit = lit_texels(&self.depth, size, x, y, radius, ndc.z);
        lit as f32 / (side * side) as u32 as f32
    }
}

/// Renders the shadow map of every light that casts shadows (`None` for the others), in the
/// eye-relative space of a frame whose eye is `frame_eye`.
pub fn render_shadow_maps(scene: &Scene, frame_eye: DVec3) -> Vec<Option<Arc<ShadowMap>>> {
    // The bounds read every vertex of the scene: computed on the first light that casts a
    // shadow, and never for a scene without shadows.
    let mut bounds = None;
    scene
        .lights
        .iter()
        .map(|light| {
            let settings = light.shadow()?;
            let bounds = *bounds.get_or_insert_with(|| bounding_sphere(&scene.objects));
            let faces = light_views(light, bounds, settings.resolution)
                .into_iter()
                .map(|(camera, size)| render_face(scene, &camera, size, frame_eye))
                .collect();
            Some(Arc::new(ShadowMap { faces, settings }))
        })
        .collect()
}

/// Any unit vector not parallel to `forward`, for a camera's `up`.
fn up_for(forward: DVec3) -> DVec3 {
    if forward.y.abs() < 0.9 { DVec3::Y } else { DVec3::Z }
}

/// How many texels of the (2r+1)² block centred on texel `(x, y)` of a `size`² map do not hold a
/// surface nearer the light than `depth` (reversed Z: nearer is greater); texels beyond the
/// border repeat the nearest edge texel.
fn lit_texels(map: &[f32], size: i64, x: i64, y: i64, radius: i64, depth: f32) -> u32 {
    if x >= radius && y >= radius && x + radius < size && y + radius < size {
        // The whole block inside the map (nearly every lookup): its rows as slices, no clamping
        // per texel. The count is the same integer either way.
        let side = (2 * radius + 1) as usize;
        (y - radius..=y + radius)
            .map(|row| {
                let start = (row * size + x - radius) as usize;
                map[start..start + side]
                    .iter()
                    .filter(|&&occluder| occluder <= depth)
                    .count() as u32
            })
            .sum()
    } else {
        let mut lit = 0u32;
        for dy in -radius..=radius {
            for dx in -radius..=radius {
                let (tx, ty) = ((x + dx).clamp(0, size - 1), (y + dy).clamp(0, size - 1));
                lit += u32::from(map[(ty * size + tx) as usize] <= depth);
            }
        }
        lit
    }
}

/// The cameras (and map sizes) a light's shadow map is rendered from.
fn light_views(light: &Light, bounds: BoundingSphere, resolution: u32) -> Vec<(Camera, u32)> {
    let cube = |position: DVec3| -> Vec<(Camera, u32)> {
        let reach = (bounds.center - position).length() + bounds.radius;
        [DVec3::X, -DVec3::X, DVec3::Y, -DVec3::Y, DVec3::Z, -DVec3::Z]
            .into_iter()
            .map(|axis| {
                let camera = Camera {
                    eye: position,
                    target: position + axis,
                    up: up_for(axis),
                    projection: Projection::Perspective {
                        fov_y_degrees: CUBE_FACE_FOV_DEGREES,
                        near: (reach * 1e-5).max(1e-6),
                        far: reach * 1.01 + 1e-6,
                    },
                };
                (camera, (resolution / 2).max(16))
            })
            .collect()
    };
    match *light {
        Light::Directional { direction, .. } => {
            let direction = direction.as_dvec3().normalize_or(DVec3::NEG_Y);
            let eye = bounds.center - direction * (2.0 * bounds.radius);
            let camera = Camera {
                eye,
                target: bounds.center,
                up: up_for(direction),
                projection: Projection::Orthographic {
                    height: 2.0 * bounds.radius * 1.01,
                    near: bounds.radius * 0.5,
                    far: bounds.radius * 3.5,
                },
            };
            vec![(camera, resolution)]
        }
        Light::Point { position, .. } => cube(position),
        Light::Spot {
            position,
            direction,
            cutoff_degrees,
            ..
        } => {
            if cutoff_degrees > MAX_SINGLE_FACE_CUTOFF_DEGREES {
                return cube(position);
            }
            let axis = direction.as_dvec3().normalize_or(DVec3::NEG_Y);
            let reach = (bounds.center - position).length() + bounds.radius;
            let camera = Camera {
                eye: position,
                target: position + axis,
                up: up_for(axis),
                projection: Projection::Perspective {
                    fov_y_degrees: f64::from(2.0 * cutoff_degrees + 4.0),
                    near: (reach * 1e-5).max(1e-6),
                    far: reach * 1.01 + 1e-6,
                },
            };
            vec![(camera, resolution)]
        }
    }
}

/// Renders one face's depth, and its mapping from the frame's eye-relative space.
fn render_face(scene: &Scene, camera: &Camera, size: u32, frame_eye: DVec3) -> ShadowFace {
    let frame = build_depth_frame(scene, camera, size);
    let grid = frame.tiles;
    // As the image's tiles are: bands of tile rows in parallel, each band's tiles in order
    // through one visibility buffer, each tile's depths copied straight into the band's rows. No
    // tile's buffer outlives it, so rendering a map needs the map and a tile per thread.
    let side = size as usize;
    let mut depth = vec![f32::NEG_INFINITY; side * side];
    depth
        .par_chunks_mut(TILE_SIZE as usize * side)
        .enumerate()
        .for_each(|(tile_row, band)| {
            let mut visibility = Visibility::new();
            for column in 0..grid.columns as usize {
                let index = tile_row * grid.columns as usize + column;
                let rect = grid.rect(index);
                visibility.rasterize(rect, SamplePattern::SINGLE, &frame.raster, index);
                let width = rect.width() as usize;
                for row in 0..rect.height() as usize {
                    let start = row * side + rect.x0 as usize;
                    band[start..start + width]
                        .copy_from_slice(&visibility.depth[row * width..(row + 1) * width]);
                }
            }
        });
    let setup = CameraSetup::new(camera, 1.0);
    let clip_from_frame = setup.clip_from_world * DMat4::from_translation(frame_eye - camera.eye);
    let (texel_size, perspective) = match camera.projection {
        Projection::Perspective { fov_y_degrees, .. } => (
            (2.0 * (fov_y_degrees.to_radians() / 2.0).tan() / f64::from(size)) as f32,
            true,
        ),
        Projection::Orthographic { height, .. } => ((height / f64::from(size)) as f32, false),
    };
    ShadowFace {
        clip_from_frame: clip_from_frame.as_mat4(),
        size,
        depth,
        texel_size,
        perspective,
        origin: (camera.eye - frame_eye).as_vec3(),
        forward: setup.forward.as_vec3(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The block count, inside the map by rows and at its border by clamping, equals the
    /// definition (every texel of the block, clamped to the edge) at every texel of a small map,
    /// for every radius and depth.
    #[test]
    fn lit_texels_counts_the_clamped_block_everywhere() {
        let size = 9i64;
        // Depths in a fixed pseudo-random pattern, with ties at the compared depths.
        let map: Vec<f32> = (0..size * size)
            .map(|i| ((i * 37 + 11) % 17) as f32 / 16.0)
            .collect();
        for radius in 0..=3 {
            for y in 0..size {
                for x in 0..size {
                    for depth in [0.0, 0.25, 0.5, 0.8125, 1.0] {
                        let mut expected = 0;
                        for dy in -radius..=radius {
                            for dx in -radius..=radius {
                                let (tx, ty) = ((x + dx).clamp(0, size - 1), (y + dy).clamp(0, size - 1));
                                expected += u32::from(map[(ty * size + tx) as usize] <= depth);
                            }
                        }
                        assert_eq!(
                            lit_texels(&map, size, x, y, radius, depth),
                            expected,
                            "x {x}, y {y}, radius {radius}, depth {depth}"
                        );
                    }
                }
            }
        }
    }
}
