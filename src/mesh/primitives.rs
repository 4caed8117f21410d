//! Built-in primitives: a sphere, a plane and a cube, each with exact vertex normals.
//!
//! # Design
//!
//! The sphere reproduces MATLAB's `sphere(N)` vertex for vertex and triangle for triangle,
//! because benchmarks compare triangle counts and images with OpenGL programs built on that
//! grid. That includes its two weaknesses, kept on purpose: the seam and the poles are
//! stored as separate vertices with equal positions, and the 2N triangles touching the
//! poles have zero area. Like MATLAB's `sphere.m`, `cos φ` is set to exactly 0 at the poles
//! and `sin θ` to exactly 0 on the seam, so those duplicated vertices are bitwise equal: a
//! rasterizer sees the seam's shared edges as identical and leaves no crack.
//!
//! The plane and the cube give every face its own four vertices, so the normals stay those
//! of the faces and the edges stay hard. All triangles are counter-clockwise seen from
//! outside (for the plane: from +Y).

use std::f64::consts::{FRAC_PI_2, PI};

use glam::Vec3;

use super::Mesh;

/// The fewest segments a sphere may have: below 3 the grid has no volume (and 0 divides
/// by zero).
pub const MIN_SPHERE_SEGMENTS: u32 = 3;

/// The most segments a sphere may have: `(N + 1)²` vertex indices must fit in `u32`.
/// (Memory runs out long before; callers should set a practical limit of their own.)
pub const MAX_SPHERE_SEGMENTS: u32 = 65_535;

/// The unit sphere centred at the origin, z-up (poles on ±Z), exactly like MATLAB's
/// `sphere(segments)`.
///
/// With `N = segments`: `θ_j = (−N + 2j)/N · π` and `φ_i = (−N + 2i)/N · π/2` for
/// `i, j = 0..=N`; vertex `i·(N+1) + j` is `(cos φ_i cos θ_j, cos φ_i sin θ_j, sin φ_i)` and
/// its normal is its normalised position. Each grid cell `(i, j)`, row by row from the south
/// pole (`i = 0`), gives the triangles `(v(i,j), v(i,j+1), v(i+1,j+1))` and
/// `(v(i,j), v(i+1,j+1), v(i+1,j))`: `(N+1)²` vertices and `2N²` triangles, of which the
/// `2N` touching the poles have zero area.
///
/// `segments` must lie in [`MIN_SPHERE_SEGMENTS`]`..=`[`MAX_SPHERE_SEGMENTS`]; the scene
/// loader checks this, and values outside are clamped (a debug build panics instead).
pub fn sphere(segments: u32) -> Mesh {
    debug_assert!(
        (MIN_SPHERE_SEGMENTS..=MAX_SPHERE_SEGMENTS).contains(&segments),
        "sphere segments {segments} out of range"
    );
    let n = segments.clamp(MIN_SPHERE_SEGMENTS, MAX_SPHERE_SEGMENTS);
    let row_length = n as usize + 1;
    let grid_angle = |k: u32| (2.0 * f64::from(k) - f64::from(n)) / f64::from(n);

    let mut positions = Vec::with_capacity(row_length * row_length);
    for i in 0..=n {
        let phi = grid_angle(i) * FRAC_PI_2;
        let cos_phi = if i == 0 || i == n { 0.0 } else { phi.cos() };
        let sin_phi = phi.sin();
        for j in 0..=n {
            let theta = grid_angle(j) * PI;
            let sin_theta = if j == 0 || j == n { 0.0 } else { theta.sin() };
            positions.push(Vec3::new(
                (cos_phi * theta.cos()) as f32,
                (cos_phi * sin_theta) as f32,
                sin_phi as f32,
            ));
        }
    }
    let normals = positions.iter().map(|p| p.normalize()).collect();

    let vertex = |i: u32, j: u32| i * (n + 1) + j;
    let mut triangles = Vec::with_capacity(2 * (n as usize) * (n as usize));
    for i in 0..n {
        for j in 0..n {
            triangles.push([vertex(i, j), vertex(i, j + 1), vertex(i + 1, j + 1)]);
            triangles.push([vertex(i, j), vertex(i + 1, j + 1), vertex(i + 1, j)]);
        }
    }

    Mesh {
        positions,
        normals,
        triangles,
        closed: true,
        ..Mesh::default()
    }
}

/// The square `[-1, 1] × [-1, 1]` in the XZ plane (y = 0), facing +Y: 4 vertices with
/// normal +Y and 2 triangles, counter-clockwise seen from +Y.
pub fn plane() -> Mesh {
    let mut mesh = Mesh::default();
    push_square(&mut mesh, Vec3::ZERO, Vec3::Z, Vec3::X);
    mesh
}

/// The cube `[-1, 1]³`: 6 faces of 4 vertices each (24), every vertex carrying its face's
/// normal so the edges stay hard, and 12 triangles counter-clockwise seen from outside.
/// Faces come in the order +X, −X, +Y, −Y, +Z, −Z.
pub fn cube() -> Mesh {
    // (u, v) per face, chosen so that u × v is the outward normal.
    let faces = [
        (Vec3::Y, Vec3::Z),
        (Vec3::Z, Vec3::Y),
        (Vec3::Z, Vec3::X),
        (Vec3::X, Vec3::Z),
        (Vec3::X, Vec3::Y),
        (Vec3::Y, Vec3::X),
    ];
    let mut mesh = Mesh {
        closed: true,
        ..Mesh::default()
    };
    for (u, v) in faces {
        push_square(&mut mesh, u.cross(v), u, v);
    }
    mesh
}

/// Appends the square `centre ± u ± v` facing `u × v` (u and v orthogonal unit vectors):
/// four vertices with that normal and two triangles counter-clockwise around it.
fn push_square(mesh: &mut Mesh, centre: Vec3, u: Vec3, v: Vec3) {
    let normal = u.cross(v);
    let first = mesh.positions.len() as u32;
    for corner in [-u - v, u - v, u + v, -u + v] {
        mesh.positions.push(centre + corner);
        mesh.normals.push(normal);
    }
    mesh.triangles.push([first, first + 1, first + 2]);
    mesh.triangles.push([first, first + 2, first + 3]);
}

#[cfg(test)]
mod tests {
    use super::super::normals::face_normal;
    use super::*;

    /// Checks the counts, that indices are in range and normals unit length, and that every
    /// non-degenerate triangle's geometric normal `(V1−V0)×(V2−V0)` points the same way as
    /// each of its vertex normals (outward, for counter-clockwise-from-outside winding).
    fn check(mesh: &Mesh, vertices: usize, triangles: usize, degenerate_triangles: usize) {
        assert_eq!(mesh.positions.len(), vertices, "vertex count");
        assert_eq!(mesh.normals.len(), vertices, "normal count");
        assert_eq!(mesh.triangles.len(), triangles, "triangle count");
        assert!(mesh.materials.is_empty() && mesh.triangle_materials.is_empty());
        for n in &mesh.normals {
            assert!((n.length() - 1.0).abs() < 1e-6, "normal {n} is not unit");
        }
        let mut degenerate = 0;
        for triangle in &mesh.triangles {
            assert!(triangle.iter().all(|&v| (v as usize) < vertices), "{triangle:?}");
            let [a, b, c] = triangle.map(|v| mesh.positions[v as usize]);
            let geometric = face_normal(a, b, c);
            if geometric == Vec3::ZERO {
                degenerate += 1;
                continue;
            }
            for &v in triangle {
                let vertex_normal = mesh.normals[v as usize];
                assert!(geometric.dot(vertex_normal) > 0.0, "{triangle:?} faces inward");
            }
        }
        assert_eq!(degenerate, degenerate_triangles, "degenerate triangles");
    }

    #[test]
    fn sphere_has_matlab_counts_with_zero_area_pole_triangles() {
        for n in [3, 4, 16, 33] {
            let count = n as usize;
            check(
                &sphere(n),
                (count + 1) * (count + 1),
                2 * count * count,
                2 * count,
            );
        }
    }

    #[test]
    fn sphere_vertices_follow_matlab_grid() {
        let mesh = sphere(4);
        let at = |i: usize, j: usize| mesh.positions[i * 5 + j];
        assert_eq!(
            at(0, 3),
            Vec3::new(0.0, 0.0, -1.0),
            "south pole, cos φ forced to 0"
        );
        assert_eq!(at(4, 1), Vec3::new(0.0, 0.0, 1.0), "north pole");
        assert_eq!(at(2, 0), Vec3::new(-1.0, 0.0, 0.0), "θ = −π, sin θ forced to 0");
        assert_eq!(at(2, 4), at(2, 0), "the seam closes exactly");
        assert!(at(2, 2).distance(Vec3::X) < 1e-7, "θ = 0 on the equator");
        assert!(at(2, 3).distance(Vec3::Y) < 1e-7, "θ = π/2");
        let c = std::f32::consts::FRAC_1_SQRT_2;
        assert!(at(1, 2).distance(Vec3::new(c, 0.0, -c)) < 1e-7, "φ = −π/4");
        for (p, n) in mesh.positions.iter().zip(&mesh.normals) {
            assert!((p.length() - 1.0).abs() < 1e-6 && p.distance(*n) < 1e-6);
        }
    }

    #[test]
    fn sphere_triangles_go_row_by_row() {
        let mesh = sphere(3);
        // Row length 4: cell (0, 0), then cell (0, 1), ..., then cell (1, 0).
        assert_eq!(mesh.triangles[0], [0, 1, 5]);
        assert_eq!(mesh.triangles[1], [0, 5, 4]);
        assert_eq!(mesh.triangles[2], [1, 2, 6]);
        assert_eq!(mesh.triangles[6], [4, 5, 9]);
        assert_eq!(*mesh.triangles.last().unwrap_or(&[0; 3]), [10, 15, 14]);
    }

    #[test]
    fn plane_faces_up_in_xz() {
        let mesh = plane();
        check(&mesh, 4, 2, 0);
        assert!(mesh.normals.iter().all(|&n| n == Vec3::Y));
        assert_eq!(
            mesh.bounds(),
            Some((Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 0.0, 1.0)))
        );
    }

    #[test]
    fn cube_has_hard_outward_faces() {
        let mesh = cube();
        check(&mesh, 24, 12, 0);
        assert_eq!(mesh.bounds(), Some((-Vec3::ONE, Vec3::ONE)));
        for (p, n) in mesh.positions.iter().zip(&mesh.normals) {
            // A face's vertices lie on the face: their coordinate along the normal is 1.
            assert_eq!(p.dot(*n), 1.0, "vertex {p} with normal {n}");
        }
        for axis in [Vec3::X, Vec3::Y, Vec3::Z] {
            for normal in [axis, -axis] {
                assert_eq!(mesh.normals.iter().filter(|&&n| n == normal).count(), 4);
            }
        }
    }
}
