//! The shading stage: one colour for every visible pixel of a tile.
//!
//! The rasterizer left, per pixel, the nearest raster triangle. Here its edge functions give the
//! screen-space barycentrics λ, which are made perspective-correct (`bᵢ = (λᵢ/wᵢ) / Σ λⱼ/wⱼ`;
//! seed 002 names plain screen-space interpolation as a flaw), then mapped through the clipper's
//! weights to the source triangle's three vertices. Then, by the object's shading mode:
//! - `Flat`: the triangle's colour, lit once at its centroid by the geometry stage;
//! - `Gouraud`: the vertex colours, interpolated;
//! - `Phong`: position and normal interpolated, the normal renormalised, lit here.
//!
//! Back faces are lit from behind with the normal flipped. Gouraud back colours are lit lazily
//! here, for the few back faces that are actually visible, instead of for every vertex.

use glam::Vec3;

use crate::render::DebugView;
use crate::render::geometry::{Frame, FrameTriangle};
use crate::render::raster::{NO_TRIANGLE, RasterTriangle, Visibility, edge_values};
use crate::scene::Shading;

/// The shaded pixels of one tile, row-major.
#[derive(Debug, Clone, PartialEq)]
pub struct TileImage {
    pub color: Vec<Vec3>,
    pub covered: Vec<bool>,
}

/// The Gouraud colours of the back side of the last back-facing triangle shaded.
type BackColorCache = Option<(u32, [Vec3; 3])>;

pub fn shade_tile(frame: &Frame, visibility: &Visibility, background: Vec3) -> TileImage {
    let rect = visibility.rect;
    let mut image = TileImage {
        color: vec![background; visibility.triangle.len()],
        covered: vec![false; visibility.triangle.len()],
    };
    let mut back_colors: BackColorCache = None;
    for (slot, &id) in visibility.triangle.iter().enumerate() {
        if id == NO_TRIANGLE {
            continue;
        }
        let px = rect.x0 + slot as u32 % rect.width();
        let py = rect.y0 + slot as u32 / rect.width();
        image.color[slot] = shade_pixel(frame, &frame.raster[id as usize], px, py, &mut back_colors);
        image.covered[slot] = true;
    }
    image
}

/// Perspective-correct barycentric weights of the source triangle's vertices at a pixel centre.
pub fn source_weights(triangle: &RasterTriangle, px: u32, py: u32) -> Vec3 {
    let [e0, e1, e2] = edge_values(triangle, px, py);
    let screen = Vec3::new(e0 as f32, e1 as f32, e2 as f32) * triangle.inv_area;
    let [w0, w1, w2] = triangle.inv_w;
    let over_w = screen * Vec3::new(w0, w1, w2);
    let sum = over_w.element_sum();
    let corner = if sum > 0.0 { over_w / sum } else { screen };
    triangle.weights[0] * corner.x + triangle.weights[1] * corner.y + triangle.weights[2] * corner.z
}

fn shade_pixel(
    frame: &Frame,
    raster: &RasterTriangle,
    px: u32,
    py: u32,
    back_colors: &mut BackColorCache,
) -> Vec3 {
    let weights = source_weights(raster, px, py);
    let triangle = &frame.triangles[raster.source as usize];
    let [a, b, c] = triangle.vertices.map(|v| &frame.vertices[v as usize]);
    let interpolate = |x: Vec3, y: Vec3, z: Vec3| x * weights.x + y * weights.y + z * weights.z;
    let side = if raster.back_facing { -1.0 } else { 1.0 };
    let position = interpolate(a.position, b.position, c.position);

    match frame.debug_view {
        Some(DebugView::Depth) => return Vec3::splat(position.dot(frame.forward)),
        Some(DebugView::Normals) => {
            let normal = match triangle.shading {
                Shading::Flat => triangle.face_normal,
                Shading::Gouraud | Shading::Phong => {
                    smooth_normal(triangle, interpolate(a.normal, b.normal, c.normal))
                }
            };
            return side * normal * 0.5 + 0.5;
        }
        _ => {}
    }

    match triangle.shading {
        Shading::Flat => triangle.flat_color,
        Shading::Gouraud if !raster.back_facing => interpolate(a.color, b.color, c.color),
        Shading::Gouraud => {
            let colors = match *back_colors {
                Some((source, colors)) if source == raster.source => colors,
                _ => {
                    let colors = [a, b, c].map(|v| frame.light(triangle.material, v.position, -v.normal));
                    *back_colors = Some((raster.source, colors));
                    colors
                }
            };
            interpolate(colors[0], colors[1], colors[2])
        }
        Shading::Phong => {
            let normal = side * smooth_normal(triangle, interpolate(a.normal, b.normal, c.normal));
            frame.light(triangle.material, position, normal)
        }
    }
}

/// The interpolated normal renormalised; where the vertex normals cancel out (opposite normals
/// on one edge), the face normal.
fn smooth_normal(triangle: &FrameTriangle, interpolated: Vec3) -> Vec3 {
    let length_squared = interpolated.length_squared();
    if length_squared > 1e-12 {
        interpolated / length_squared.sqrt()
    } else {
        triangle.face_normal
    }
}
