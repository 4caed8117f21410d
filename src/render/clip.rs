//! Clipping in homogeneous clip space, before the divide by w.
//!
//! A triangle is clipped against six planes: near and far (so nothing behind the eye or across
//! w = 0 is ever projected: such a triangle would otherwise be stretched across the screen) and
//! a guard band in x and y far outside the viewport (so projected coordinates always fit the
//! rasterizer's fixed-point range). Triangles inside every plane, nearly all of them, skip the
//! clipper. The rest go through Sutherland–Hodgman; every clipped vertex carries its barycentric
//! weights with respect to the original triangle, so attributes are interpolated from the
//! original vertices, not re-derived per clipped vertex.
//!
//! The depth convention is reversed-Z (near → 1, far → 0), so inside means `0 ≤ z ≤ w`.

use glam::{Vec3, Vec4};

/// A polygon vertex: position in clip space and barycentric weights of the original triangle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClipVertex {
    pub position: Vec4,
    pub weights: Vec3,
}

/// A triangle clipped by six planes has at most 3 + 6 vertices.
pub const MAX_POLYGON_VERTICES: usize = 9;

/// The result of clipping one triangle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClippedPolygon {
    vertices: [ClipVertex; MAX_POLYGON_VERTICES],
    len: usize,
}

impl ClippedPolygon {
    pub fn vertices(&self) -> &[ClipVertex] {
        &self.vertices[..self.len]
    }
}

/// What clipping made of a triangle.
// The polygon is returned by value and consumed at once; boxing it would allocate per clipped
// triangle for nothing.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Clipped {
    /// Inside every plane: draw as it is.
    Inside,
    /// Entirely outside one plane: nothing to draw.
    Outside,
    /// Partly inside: a convex polygon (drawn as a fan), possibly with fewer than 3 vertices
    /// when only an edge or a point touches the volume.
    Polygon(ClippedPolygon),
}

/// Signed distances of a clip-space point to the six planes; inside when all are `>= 0`.
fn plane_distances(p: Vec4, guard_x: f32, guard_y: f32) -> [f32; 6] {
    [
        p.w - p.z,           // near (reversed-Z: depth 1)
        p.z,                 // far (depth 0)
        p.x + guard_x * p.w, // left guard band
        guard_x * p.w - p.x, // right guard band
        p.y + guard_y * p.w, // bottom guard band
        guard_y * p.w - p.y, // top guard band
    ]
}

/// Clips a triangle given in clip space. `guard_x` and `guard_y` are the guard band's half
/// extents in NDC units (the viewport is 1).
pub fn clip_triangle(corners: [Vec4; 3], guard_x: f32, guard_y: f32) -> Clipped {
    let distances = corners.map(|p| plane_distances(p, guard_x, guard_y));
    let mut any_outside = false;
    for plane in 0..6 {
        // `is_nan` too: a NaN vertex is outside every plane.
        let outside = distances
            .iter()
            .filter(|d| d[plane] < 0.0 || d[plane].is_nan())
            .count();
        if outside == 3 {
            return Clipped::Outside;
        }
        any_outside |= outside > 0;
    }
    if !any_outside {
        return Clipped::Inside;
    }

    let mut polygon = ClippedPolygon {
        vertices: [ClipVertex {
            position: Vec4::ZERO,
            weights: Vec3::ZERO,
        }; MAX_POLYGON_VERTICES],
        len: 3,
    };
    for (i, &position) in corners.iter().enumerate() {
        let mut weights = Vec3::ZERO;
        weights[i] = 1.0;
        polygon.vertices[i] = ClipVertex { position, weights };
    }
    for plane in 0..6 {
        polygon = clip_polygon_by_plane(&polygon, plane, guard_x, guard_y);
        if polygon.len == 0 {
            break;
        }
    }
    Clipped::Polygon(polygon)
}

fn clip_polygon_by_plane(
    polygon: &ClippedPolygon,
    plane: usize,
    guard_x: f32,
    guard_y: f32,
) -> ClippedPolygon {
    let mut output = ClippedPolygon {
        vertices: polygon.vertices,
        len: 0,
    };
    let input = polygon.vertices();
    let distance = |v: &ClipVertex| plane_distances(v.position, guard_x, guard_y)[plane];
    for (i, current) in input.iter().enumerate() {
        let next = &input[(i + 1) % input.len()];
        let (d_current, d_next) = (distance(current), distance(next));
        let current_inside = d_current >= 0.0;
        if current_inside {
            push(&mut output, *current);
        }
        if current_inside != (d_next >= 0.0) {
            // The edge crosses the plane: d_current and d_next have opposite signs, so the
            // denominator is non-zero and t is in [0, 1].
            let t = d_current / (d_current - d_next);
            push(
                &mut output,
                ClipVertex {
                    position: current.position.lerp(next.position, t),
                    weights: current.weights.lerp(next.weights, t),
                },
            );
        }
    }
    output
}

fn push(polygon: &mut ClippedPolygon, vertex: ClipVertex) {
    // A convex polygon gains at most one vertex per plane, so this never overflows; the check
    // keeps a NaN-driven surprise from becoming a panic.
    if polygon.len < MAX_POLYGON_VERTICES {
        polygon.vertices[polygon.len] = vertex;
        polygon.len += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const GUARD: f32 = 100.0;

    #[test]
    fn inside_and_outside() {
        let inside = [
            Vec4::new(0.0, 0.0, 0.5, 1.0),
            Vec4::new(0.5, 0.0, 0.5, 1.0),
            Vec4::new(0.0, 0.5, 0.5, 1.0),
        ];
        assert_eq!(clip_triangle(inside, GUARD, GUARD), Clipped::Inside);
        let behind = inside.map(|p| Vec4::new(p.x, p.y, 2.0, 1.0));
        assert_eq!(clip_triangle(behind, GUARD, GUARD), Clipped::Outside);
    }

    #[test]
    fn crossing_the_near_plane_keeps_the_front_part_with_weights() {
        // One vertex in front (z < w), two behind the eye (w < 0).
        let corners = [
            Vec4::new(0.0, 0.0, 0.5, 1.0),
            Vec4::new(1.0, 0.0, 1.5, -1.0),
            Vec4::new(0.0, 1.0, 1.5, -1.0),
        ];
        let Clipped::Polygon(polygon) = clip_triangle(corners, GUARD, GUARD) else {
            panic!("expected a polygon")
        };
        assert_eq!(polygon.vertices().len(), 3);
        for v in polygon.vertices() {
            assert!(
                v.position.z <= v.position.w + 1e-6 && v.position.z >= 0.0 && v.position.w > 0.0,
                "{v:?}"
            );
            assert!((v.weights.element_sum() - 1.0).abs() < 1e-6);
            // Weights reproduce the clip position from the original corners.
            let rebuilt = corners[0] * v.weights.x + corners[1] * v.weights.y + corners[2] * v.weights.z;
            assert!((rebuilt - v.position).abs().max_element() < 1e-5);
        }
    }

    #[test]
    fn a_quad_comes_out_when_one_vertex_is_behind() {
        let corners = [
            Vec4::new(0.0, 0.0, 1.5, -1.0),
            Vec4::new(1.0, 0.0, 0.5, 1.0),
            Vec4::new(0.0, 1.0, 0.5, 1.0),
        ];
        let Clipped::Polygon(polygon) = clip_triangle(corners, GUARD, GUARD) else {
            panic!("expected a polygon")
        };
        assert_eq!(polygon.vertices().len(), 4);
    }

    #[test]
    fn nan_is_outside_not_a_panic() {
        let corners = [
            Vec4::splat(f32::NAN),
            Vec4::new(1.0, 0.0, 0.5, 1.0),
            Vec4::new(0.0, 1.0, 0.5, 1.0),
        ];
        let _ = clip_triangle(corners, GUARD, GUARD);
    }
}
