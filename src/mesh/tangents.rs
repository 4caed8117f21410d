//! Tangent frames for normal maps: computed when a file has none, and cleaned up when it does.
//!
//! # Convention
//!
//! A tangent is `(t, w)` with `t` a unit vector perpendicular to the vertex normal `n`, and
//! the bitangent is `b = w · (n × t)`, `w = ±1` (glTF's `TANGENT`). A tangent-space normal
//! `(x, y, z)` read from a normal map means `x·t + y·b + z·n`. glTF normal maps put +X to the
//! right of the image and +Y *up*, while glTF texture coordinates have v growing *down*
//! ((0, 0) is the top-left texel, the convention of [`Mesh::uvs`](super::Mesh::uvs)): so `t`
//! follows the direction in which u grows on the surface, and `b` the direction in which v
//! *shrinks*. A mapping that is not mirrored gets `w = +1`.
//!
//! # Computation
//!
//! For each triangle, with edges `e₁ = p₁ − p₀`, `e₂ = p₂ − p₀` and UV differences `Δ₁`, `Δ₂`,
//! the surface directions of growing u and v solve `e = Δu·∂p/∂u + Δv·∂p/∂v`:
//!
//! ```text
//! ∂p/∂u = (Δv₂·e₁ − Δv₁·e₂) / det        ∂p/∂v = (Δu₁·e₂ − Δu₂·e₁) / det
//! det = Δu₁·Δv₂ − Δu₂·Δv₁
//! ```
//!
//! Only their directions matter: each is normalised and added to the triangle's three corner
//! vertices weighted by the corner's interior angle, as the normals are
//! ([`normals`](super::normals), for the same reason: independence from how the surface is
//! cut up). At each vertex, `t` is the sum made perpendicular to `n` (Gram–Schmidt) and
//! normalised, and `w` is the sign of `(n × t) · (−∂p/∂v)`. Triangles whose UVs have no area
//! (`det = 0`) or whose positions do not give a finite direction contribute nothing; a vertex
//! left with no usable direction takes `−(∂p/∂v sum) × n` when that exists, else any unit
//! vector perpendicular to `n`, with `w = +1`. Nothing here can produce a NaN.
//!
//! Accumulation is per vertex *index*, not per position: vertices on either side of a UV seam
//! are separate vertices with separate frames, as they must be.
//!
//! Rejected: MikkTSpace itself (the tangent space glTF recommends; a C library or a port of
//! one, for agreement with baking tools to the last bit, which matters most for low-poly
//! models with baked detail: here the same per-triangle directions with angle weighting agree
//! with the exporters' tangents of the bundled Avocado, see the tests). Known limit: a vertex
//! shared by triangles whose UVs are mirrored relative to each other (a mirrored UV layout
//! whose halves meet on the mirror line with equal UVs) averages opposite directions;
//! MikkTSpace splits such vertices, this does not.

use glam::{Vec2, Vec3, Vec4};

use super::normals::{interior_angles, unit_or_zero};

/// Tangents for every vertex from its position, unit normal and texture coordinates (module
/// documentation). `normals` and `uvs` hold one entry per position; missing entries (a shorter
/// array) and triangles with an out-of-range index are ignored, so that this never panics.
pub fn compute_tangents(
    positions: &[Vec3],
    normals: &[Vec3],
    uvs: &[Vec2],
    triangles: &[[u32; 3]],
) -> Vec<Vec4> {
    let mut along_u = vec![Vec3::ZERO; positions.len()];
    let mut along_v = vec![Vec3::ZERO; positions.len()];
    for triangle in triangles {
        let [i0, i1, i2] = triangle.map(|v| v as usize);
        let (Some(&p0), Some(&p1), Some(&p2)) = (positions.get(i0), positions.get(i1), positions.get(i2))
        else {
            continue;
        };
        let (Some(&uv0), Some(&uv1), Some(&uv2)) = (uvs.get(i0), uvs.get(i1), uvs.get(i2)) else {
            continue;
        };
        let (e1, e2) = (p1 - p0, p2 - p0);
        let (d1, d2) = (uv1 - uv0, uv2 - uv0);
        let det = d1.x * d2.y - d2.x * d1.y;
        if det == 0.0 || !det.is_finite() {
            continue;
        }
        // Dividing by det only scales; its sign is all that is kept.
        let sign = det.signum();
        let du = unit_or_zero(sign * (d2.y * e1 - d1.y * e2));
        let dv = unit_or_zero(sign * (d1.x * e2 - d2.x * e1));
        let angles = interior_angles(p0, p1, p2);
        for (vertex, angle) in [i0, i1, i2].into_iter().zip(angles) {
            along_u[vertex] += angle * du;
            along_v[vertex] += angle * dv;
        }
    }
    (0..positions.len())
        .map(|vertex| {
            let normal = normals.get(vertex).copied().unwrap_or(Vec3::Z);
            frame_from_directions(normal, along_u[vertex], along_v[vertex])
        })
        .collect()
}

/// A file's tangent made usable with `normal`: `t` perpendicular to the normal and unit, `w`
/// exactly ±1 (its sign; +1 when it has none). A tangent with no direction left once
/// perpendicular takes [`fallback_tangent`]'s.
pub fn orthonormalize_tangent(normal: Vec3, tangent: Vec4) -> Vec4 {
    let handedness = if tangent.w < 0.0 { -1.0 } else { 1.0 };
    let t = perpendicular_unit(normal, tangent.truncate());
    if t == Vec3::ZERO {
        fallback_tangent(normal)
    } else {
        t.extend(handedness)
    }
}

/// Some unit tangent perpendicular to `normal` (unit), with `w = +1`: for vertices whose
/// texture coordinates say nothing about a direction.
pub fn fallback_tangent(normal: Vec3) -> Vec4 {
    let normal = unit_or_zero(normal);
    let normal = if normal == Vec3::ZERO { Vec3::Z } else { normal };
    normal.any_orthonormal_vector().extend(1.0)
}

/// The tangent of a vertex from the angle-weighted sums of the directions of growing u and v.
fn frame_from_directions(normal: Vec3, along_u: Vec3, along_v: Vec3) -> Vec4 {
    let t = perpendicular_unit(normal, along_u);
    // "Up" in the image is the direction of shrinking v.
    let up = -along_v;
    if t != Vec3::ZERO {
        let handedness = if normal.cross(t).dot(up) < 0.0 { -1.0 } else { 1.0 };
        return t.extend(handedness);
    }
    // No u direction: with w = +1, b = n × t means t = b × n.
    let t = perpendicular_unit(normal, up.cross(normal));
    if t != Vec3::ZERO {
        t.extend(1.0)
    } else {
        fallback_tangent(normal)
    }
}

/// `v` with its component along `normal` removed, normalised; zero when nothing is left.
fn perpendicular_unit(normal: Vec3, v: Vec3) -> Vec3 {
    if !v.is_finite() || !normal.is_finite() {
        return Vec3::ZERO;
    }
    // Normalising first keeps the projection finite for huge sums.
    let v = unit_or_zero(v);
    unit_or_zero(v - normal * normal.dot(v))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Computes tangents for one triangle in the z = 0 plane (normal +Z) and checks the frame.
    fn check(uvs: [Vec2; 3], expected: Vec4) {
        let positions = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let tangents = compute_tangents(&positions, &[Vec3::Z; 3], &uvs, &[[0, 1, 2]]);
        for tangent in tangents {
            assert!(
                tangent.distance(expected) < 1e-6,
                "{tangent} vs {expected} for UVs {uvs:?}"
            );
        }
    }

    #[test]
    fn tangent_follows_u_and_handedness_follows_the_image() {
        // u grows along +X and the image's top is at +Y (v grows towards −Y): not mirrored.
        check(
            [Vec2::new(0.0, 1.0), Vec2::new(1.0, 1.0), Vec2::new(0.0, 0.0)],
            Vec4::new(1.0, 0.0, 0.0, 1.0),
        );
        // The image flipped vertically on the surface: mirrored, w = −1.
        check(
            [Vec2::new(0.0, 0.0), Vec2::new(1.0, 0.0), Vec2::new(0.0, 1.0)],
            Vec4::new(1.0, 0.0, 0.0, -1.0),
        );
        // Rotated a quarter turn: u grows along +Y.
        check(
            [Vec2::new(0.0, 0.0), Vec2::new(0.0, 1.0), Vec2::new(1.0, 0.0)],
            Vec4::new(0.0, 1.0, 0.0, 1.0),
        );
    }

    #[test]
    fn degenerate_uvs_give_some_perpendicular_unit_tangent() {
        let positions = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let normal = Vec3::new(0.0, 0.6, 0.8);
        for uvs in [
            [Vec2::ZERO; 3],
            [Vec2::ZERO, Vec2::X, 2.0 * Vec2::X],
            [Vec2::NAN; 3],
        ] {
            let tangents = compute_tangents(&positions, &[normal; 3], &uvs, &[[0, 1, 2]]);
            for t in tangents {
                assert!(t.is_finite() && t.w == 1.0, "{t}");
                assert!((t.truncate().length() - 1.0).abs() < 1e-6 && t.truncate().dot(normal).abs() < 1e-6);
            }
        }
        // Positions with no area, huge ones, and missing normals or UVs: still no NaN.
        let tangents = compute_tangents(
            &[Vec3::ONE, Vec3::ONE, Vec3::splat(3e38), Vec3::ZERO],
            &[Vec3::Z],
            &[Vec2::ZERO, Vec2::X, Vec2::Y],
            &[[0, 1, 2], [0, 2, 3], [0, 1, 9]],
        );
        assert_eq!(tangents.len(), 4);
        assert!(
            tangents
                .iter()
                .all(|t| t.is_finite() && (t.truncate().length() - 1.0).abs() < 1e-6)
        );
    }

    #[test]
    fn tangents_are_made_perpendicular_to_the_normal() {
        // A quad bent along its diagonal: the summed u direction is not in either face, and
        // the vertex normals lean; every tangent still ends up perpendicular to its normal.
        let positions = [Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.5), Vec3::Y];
        let uvs = [
            Vec2::new(0.0, 1.0),
            Vec2::new(1.0, 1.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(0.0, 0.0),
        ];
        let triangles = [[0, 1, 2], [0, 2, 3]];
        let normals = [Vec3::new(-0.2, -0.2, 1.0).normalize(); 4];
        let tangents = compute_tangents(&positions, &normals, &uvs, &triangles);
        for (t, n) in tangents.iter().zip(normals) {
            assert!(t.truncate().dot(n).abs() < 1e-6 && (t.truncate().length() - 1.0).abs() < 1e-6);
            assert!(t.x > 0.9 && t.w == 1.0, "{t}");
        }
    }

    #[test]
    fn file_tangents_are_orthonormalised_keeping_their_sign() {
        let t = orthonormalize_tangent(Vec3::Z, Vec4::new(2.0, 0.0, 1.0, -0.7));
        assert_eq!(t, Vec4::new(1.0, 0.0, 0.0, -1.0));
        // Parallel to the normal, zero or NaN: any perpendicular tangent, w = +1 for NaN.
        for bad in [Vec4::new(0.0, 0.0, 3.0, 1.0), Vec4::ZERO, Vec4::NAN] {
            let t = orthonormalize_tangent(Vec3::Z, bad);
            assert!(t.truncate().dot(Vec3::Z).abs() < 1e-6 && (t.truncate().length() - 1.0).abs() < 1e-6);
            assert!(t.w == 1.0, "{t}");
        }
    }
}
