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
//!
//! # Texture coordinates and tangents
//!
//! [`textured_sphere`], [`textured_plane`] and [`textured_cube`] are the same meshes, vertex
//! for vertex, with [`Mesh::uvs`] and [`Mesh::tangents`] added (glTF's convention: (0, 0) is
//! the top-left of the image, and the tangent follows growing u with `w = +1`, no mirroring):
//! * sphere: longitude and latitude, `u = j/N` (θ from −π to π, so u = 0 and u = 1 on the
//!   seam at −X) and `v = 1 − i/N` (the north pole, +Z, at the top of the image): an
//!   equirectangular image wraps the sphere upright, as MATLAB's `surf(x, y, z, flipud(img),
//!   'FaceColor', 'texturemap')` on `sphere(N)` shows it. The grid already keeps the seam's
//!   and the poles' vertices apart, so u runs 0 → 1 across every triangle without wrapping,
//!   and each pole vertex has the u of its column. The tangent is the unit `∂p/∂θ`,
//!   `(−sin θ, cos θ, 0)`, which is defined at the poles too.
//! * cube: every face the whole image, upright seen from outside: on the four side faces the
//!   image's up is +Y; on the top (+Y) face it is −Z and on the bottom face +Z, so the top
//!   and bottom continue the front (+Z) face's image across its edges.
//! * plane: the whole image over the square, seen from above (+Y) with up = −Z, like the
//!   cube's top face.
//!
//! The untextured meshes stay without them (objects without a texture never carry the
//! arrays, and the renderer then skips the per-vertex attribute pass).

use std::f64::consts::{FRAC_PI_2, PI};

use glam::{Vec2, Vec3, Vec4};

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

/// [`sphere`] with longitude/latitude texture coordinates and tangents (module
/// documentation).
pub fn textured_sphere(segments: u32) -> Mesh {
    let mut mesh = sphere(segments);
    let n = segments.clamp(MIN_SPHERE_SEGMENTS, MAX_SPHERE_SEGMENTS);
    let row_length = n as usize + 1;
    mesh.uvs = Vec::with_capacity(row_length * row_length);
    mesh.tangents = Vec::with_capacity(row_length * row_length);
    for i in 0..=n {
        let v = 1.0 - f64::from(i) / f64::from(n);
        for j in 0..=n {
            let u = f64::from(j) / f64::from(n);
            // θ and the forced zero on the seam exactly as `sphere` computes them.
            let theta = (2.0 * f64::from(j) - f64::from(n)) / f64::from(n) * PI;
            let sin_theta = if j == 0 || j == n { 0.0 } else { theta.sin() };
            mesh.uvs.push(Vec2::new(u as f32, v as f32));
            mesh.tangents
                .push(Vec4::new(-sin_theta as f32, theta.cos() as f32, 0.0, 1.0));
        }
    }
    mesh
}

/// [`plane`] with the whole image over the square and tangents (module documentation).
pub fn textured_plane() -> Mesh {
    let mut mesh = plane();
    add_face_coordinates(&mut mesh);
    mesh
}

/// [`cube`] with the whole image on every face and tangents (module documentation).
pub fn textured_cube() -> Mesh {
    let mut mesh = cube();
    add_face_coordinates(&mut mesh);
    mesh
}

/// Texture coordinates and tangents for the flat faces of the plane and the cube (positions
/// in [−1, 1]³, each vertex with its face's axis-aligned normal): the image's up is +Y on a
/// side face, −Z on a face looking up and +Z on one looking down; its right is `up × normal`,
/// which is right as seen from outside.
fn add_face_coordinates(mesh: &mut Mesh) {
    let (uvs, tangents) = mesh
        .positions
        .iter()
        .zip(&mesh.normals)
        .map(|(&p, &normal)| {
            let up = if normal.y.abs() > 0.5 {
                Vec3::new(0.0, 0.0, -normal.y)
            } else {
                Vec3::Y
            };
            let right = up.cross(normal);
            let uv = Vec2::new((p.dot(right) + 1.0) / 2.0, (1.0 - p.dot(up)) / 2.0);
            (uv, right.extend(1.0))
        })
        .unzip();
    mesh.uvs = uvs;
    mesh.tangents = tangents;
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

    /// The textured variant is the same mesh with valid UVs and tangents whose frame follows
    /// the image: on every non-degenerate triangle, the tangent points where u grows and
    /// `n × t` where v shrinks (computed from the triangle's own positions and UVs, as for
    /// mesh files), and every UV lies in [0, 1]².
    fn check_textured(plain: &Mesh, textured: &Mesh, max_span: f32) {
        assert_eq!(textured.positions, plain.positions);
        assert_eq!(textured.normals, plain.normals);
        assert_eq!(textured.triangles, plain.triangles);
        assert_eq!(textured.closed, plain.closed);
        textured.check_invariant().unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(textured.uvs.len(), textured.positions.len());
        assert!(
            textured
                .uvs
                .iter()
                .all(|uv| uv.cmpge(Vec2::ZERO).all() && uv.cmple(Vec2::ONE).all())
        );
        let from_uvs = super::super::tangents::compute_tangents(
            &textured.positions,
            &textured.normals,
            &textured.uvs,
            &textured.triangles,
        );
        for triangle in &textured.triangles {
            let [a, b, c] = triangle.map(|v| textured.positions[v as usize]);
            if face_normal(a, b, c) == Vec3::ZERO {
                continue;
            }
            // No triangle wraps around the image (a sphere's span one grid cell).
            let [ua, ub, uc] = triangle.map(|v| textured.uvs[v as usize]);
            let span = ua.max(ub).max(uc) - ua.min(ub).min(uc);
            assert!(span.max_element() <= max_span, "{triangle:?} spans {span}");
            for &v in triangle {
                let (ours, computed) = (textured.tangents[v as usize], from_uvs[v as usize]);
                assert!(
                    ours.truncate().dot(computed.truncate()) > 0.0 && ours.w == computed.w,
                    "vertex {v}: {ours} vs {computed} from the UVs"
                );
            }
        }
    }

    #[test]
    fn textured_primitives_are_the_same_meshes_with_a_consistent_frame() {
        for n in [3, 4, 16, 33] {
            check_textured(&sphere(n), &textured_sphere(n), 1.0 / n as f32 + 1e-6);
        }
        check_textured(&plane(), &textured_plane(), 1.0);
        check_textured(&cube(), &textured_cube(), 1.0);
    }

    #[test]
    fn sphere_uvs_are_longitude_and_latitude_with_the_north_pole_on_top() {
        let n = 8;
        let mesh = textured_sphere(n);
        let row = n as usize + 1;
        let at = |i: usize, j: usize| (mesh.positions[i * row + j], mesh.uvs[i * row + j]);
        // The seam: the same position at u = 0 and u = 1 (separate vertices).
        let (start, start_uv) = at(4, 0);
        let (end, end_uv) = at(4, n as usize);
        assert_eq!((start, start_uv.x, end_uv.x), (end, 0.0, 1.0));
        assert_eq!(start, Vec3::new(-1.0, 0.0, 0.0), "the seam is at −X");
        // +X (θ = 0) is the middle of the image, the equator its middle row.
        let (equator, uv) = at(4, 4);
        assert!(equator.distance(Vec3::X) < 1e-6 && uv == Vec2::new(0.5, 0.5));
        // Every north pole vertex is on the image's top row, each with its column's u.
        for j in 0..row {
            let (pole, uv) = at(n as usize, j);
            assert_eq!((pole, uv), (Vec3::Z, Vec2::new(j as f32 / n as f32, 0.0)));
            assert_eq!(at(0, j).1.y, 1.0, "south pole on the bottom row");
        }
    }

    #[test]
    fn cube_faces_each_hold_the_whole_image_upright() {
        let mesh = textured_cube();
        for face in 0..6 {
            let corners = &mesh.uvs[4 * face..4 * face + 4];
            let mut sorted: Vec<[u32; 2]> = corners.iter().map(|uv| [uv.x as u32, uv.y as u32]).collect();
            sorted.sort();
            assert_eq!(
                sorted,
                [[0, 0], [0, 1], [1, 0], [1, 1]],
                "face {face}: {corners:?}"
            );
            let normal = mesh.normals[4 * face];
            for v in 4 * face..4 * face + 4 {
                // Side faces: the top of the image (v = 0) is at +Y.
                if normal.y == 0.0 {
                    assert_eq!(mesh.uvs[v].y == 0.0, mesh.positions[v].y == 1.0, "vertex {v}");
                }
            }
        }
        // The front face (+Z) reads left to right along +X.
        let front: Vec<(Vec3, Vec2)> = (0..24)
            .filter(|&v| mesh.normals[v] == Vec3::Z)
            .map(|v| (mesh.positions[v], mesh.uvs[v]))
            .collect();
        assert!(front.iter().all(|(p, uv)| (uv.x == 1.0) == (p.x == 1.0)));
        let plane = textured_plane();
        assert!(
            plane
                .positions
                .iter()
                .zip(&plane.uvs)
                .all(|(p, uv)| { *uv == Vec2::new((p.x + 1.0) / 2.0, (p.z + 1.0) / 2.0) })
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
