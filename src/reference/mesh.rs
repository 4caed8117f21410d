//! The scene's own triangles for the reference: every mesh object's triangles in eye-relative
//! world space in `f64`, in one [`Bvh`], intersected exactly and interpolated at the hit from the
//! exact barycentrics.
//!
//! - **Intersection.** Möller–Trumbore in `f64`, edges included (`u, v ≥ 0`, `u + v ≤ 1`), so a
//!   ray through a shared edge hits both triangles and the tie rule picks one; the nearest hit
//!   wins, and on equal `t` the first triangle in submission order (object, then triangle), as
//!   the rasterizer's strict depth test keeps the first. Degenerate triangles (zero area) are
//!   never hit, as the rasterizer never draws them.
//! - **Facing.** A triangle's front is its counter-clockwise side in model space; under a
//!   mirroring transform that is the clockwise side in world space (the rasterizer swaps the
//!   corners of mirrored objects for the same reason). Back faces follow the object's mode,
//!   `Cull` skipping them.
//! - **Attributes.** The barycentrics of the hit on the triangle in world space are the
//!   perspective-correct weights the rasterizer approximates; normals (Nlerp or Slerp, the
//!   object's choice), texture coordinates, vertex colours and tangents are interpolated with
//!   them in `f64`.

use std::sync::Arc;

use glam::{DMat3, DMat4, DVec2, DVec3, DVec4};
use rayon::prelude::*;

use super::bvh::{Aabb, Bvh};
use super::surface::slerp_triangle;
use crate::mesh::Mesh;
use crate::scene::{BackFaces, LightingComponent, Material, NormalInterpolation, Object, presets};
use crate::texture::Texture;

/// A mesh object prepared for the reference.
pub struct MeshObject {
    /// Index in the scene's objects.
    pub object: u32,
    pub mesh: Arc<Mesh>,
    /// Model-space normals to eye-relative world space (the inverse transpose).
    normal_to_world: DMat3,
    /// Model-space tangents to world space (the linear part of the transform).
    tangent_to_world: DMat3,
    mirrored: bool,
    /// The materials its triangles index (the object's own, else the mesh's, else the
    /// default) and the textures their bindings index.
    pub materials: Vec<Material>,
    pub textures: Vec<Arc<Texture>>,
    pub back_faces: BackFaces,
    pub component: LightingComponent,
    normal_interpolation: NormalInterpolation,
}

impl MeshObject {
    pub fn new(index: usize, object: &Object, scene_textures: &[Arc<Texture>]) -> MeshObject {
        let mesh = Arc::clone(&object.mesh);
        let (materials, textures) = match (&object.material, mesh.materials.is_empty()) {
            (Some(material), _) => (vec![*material], scene_textures.to_vec()),
            (None, true) => (vec![presets::default_material()], scene_textures.to_vec()),
            (None, false) => (mesh.materials.clone(), mesh.textures.clone()),
        };
        let linear = DMat3::from_mat4(object.transform);
        MeshObject {
            object: index as u32,
            mesh,
            normal_to_world: linear.inverse().transpose(),
            tangent_to_world: linear,
            mirrored: linear.determinant() < 0.0,
            materials,
            textures,
            back_faces: object.back_faces,
            component: object.component,
            normal_interpolation: object.normal_interpolation,
        }
    }

    /// The material of the object's triangle `triangle`.
    pub fn material(&self, triangle: u32) -> &Material {
        let index = self
            .mesh
            .triangle_materials
            .get(triangle as usize)
            .copied()
            .unwrap_or(0) as usize;
        &self.materials[index.min(self.materials.len() - 1)]
    }
}

/// One triangle in eye-relative world space, as Möller–Trumbore reads it.
#[derive(Debug, Clone, Copy)]
pub struct WorldTriangle {
    p0: DVec3,
    e1: DVec3,
    e2: DVec3,
    /// Index into [`MeshTriangles::objects`].
    pub mesh_object: u32,
    /// The triangle's number in its mesh.
    pub triangle: u32,
}

impl WorldTriangle {
    /// `(t, u, v)` where the line `origin + t·direction` meets the triangle's plane, `u` and `v`
    /// the weights of the second and third corners (unbounded: outside the triangle too).
    #[inline]
    pub fn plane_hit(&self, origin: DVec3, direction: DVec3) -> Option<(f64, f64, f64)> {
        let p = direction.cross(self.e2);
        let determinant = self.e1.dot(p);
        if determinant == 0.0 || !determinant.is_finite() {
            return None;
        }
        let inverse = 1.0 / determinant;
        let s = origin - self.p0;
        let u = s.dot(p) * inverse;
        let q = s.cross(self.e1);
        let v = direction.dot(q) * inverse;
        let t = self.e2.dot(q) * inverse;
        Some((t, u, v))
    }

    /// The hit `(t, u, v)` within the triangle, edges included, and `t` in `[t_min, t_max]`.
    #[inline]
    pub fn hit(&self, origin: DVec3, direction: DVec3, t_min: f64, t_max: f64) -> Option<(f64, f64, f64)> {
        let (t, u, v) = self.plane_hit(origin, direction)?;
        (u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t >= t_min && t <= t_max).then_some((t, u, v))
    }

    fn corners(&self) -> [DVec3; 3] {
        [self.p0, self.p0 + self.e1, self.p0 + self.e2]
    }
}

/// The most the reference holds per triangle while it builds: the triangles before and after
/// their reordering into leaf order, and the BVH's boxes, build items and nodes.
pub const PEAK_BYTES_PER_TRIANGLE: u64 =
    (2 * std::mem::size_of::<WorldTriangle>() + super::bvh::BUILD_BYTES_PER_PRIMITIVE) as u64;

/// Every mesh object's triangles in one BVH.
pub struct MeshTriangles {
    pub objects: Vec<MeshObject>,
    /// In the BVH's leaf order.
    triangles: Vec<WorldTriangle>,
    bvh: Bvh,
}

/// The nearest mesh hit of a ray.
#[derive(Debug, Clone, Copy)]
pub struct MeshHit {
    pub t: f64,
    /// Index into the triangles in leaf order.
    pub triangle: usize,
    pub u: f64,
    pub v: f64,
}

/// What a mesh hit's corners say at the hit, in eye-relative world space.
pub struct Interpolated {
    /// Unit normal of the triangle's front side.
    pub face_normal: DVec3,
    /// The interpolated vertex normal (unit; the face normal where it vanishes).
    pub normal: DVec3,
    /// The corners' weights at the hit.
    pub weights: DVec3,
}

impl MeshTriangles {
    /// The triangles of `objects` (with `eye` at the origin), and their BVH.
    pub fn build(objects: Vec<MeshObject>, transforms: &[DMat4], eye: DVec3) -> MeshTriangles {
        let mut triangles: Vec<WorldTriangle> = Vec::new();
        for (number, object) in objects.iter().enumerate() {
            let world_from_model = DMat4::from_translation(-eye) * transforms[object.object as usize];
            let positions: Vec<DVec3> = object
                .mesh
                .positions
                .par_iter()
                .map(|p| world_from_model.transform_point3(p.as_dvec3()))
                .collect();
            triangles.par_extend(
                object
                    .mesh
                    .triangles
                    .par_iter()
                    .enumerate()
                    .map(|(index, &[a, b, c])| {
                        let [p0, p1, p2] = [a, b, c].map(|v| positions[v as usize]);
                        WorldTriangle {
                            p0,
                            e1: p1 - p0,
                            e2: p2 - p0,
                            mesh_object: number as u32,
                            triangle: index as u32,
                        }
                    }),
            );
        }
        let bounds: Vec<Aabb> = triangles
            .par_iter()
            .map(|triangle| Aabb::of_points(&triangle.corners()))
            .collect();
        let bvh = Bvh::build(&bounds);
        let triangles = bvh
            .order()
            .par_iter()
            .map(|&index| triangles[index as usize])
            .collect();
        MeshTriangles {
            objects,
            triangles,
            bvh,
        }
    }

    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    pub fn triangle(&self, index: usize) -> &WorldTriangle {
        &self.triangles[index]
    }

    /// The submission order of a triangle: its object's index in the scene, then its number.
    pub fn order_key(&self, index: usize) -> u64 {
        let triangle = &self.triangles[index];
        let object = self.objects[triangle.mesh_object as usize].object;
        (u64::from(object) << 32) | u64::from(triangle.triangle)
    }

    /// Whether the ray meets the front (`false`) or back (`true`) of a triangle.
    fn back_facing(&self, triangle: &WorldTriangle, direction: DVec3) -> bool {
        let object = &self.objects[triangle.mesh_object as usize];
        let facing = triangle.e1.cross(triangle.e2).dot(direction);
        (facing > 0.0) != object.mirrored
    }

    /// The nearest visible hit of `origin + t·direction`, `t` in `[0, 1]`, nearer than
    /// `(t_max, key)` (a hit of submission order `key` already found at `t_max`: a mesh hit at
    /// the same `t` wins only if submitted before it).
    pub fn nearest(&self, origin: DVec3, direction: DVec3, t_max: f64, key: u64) -> Option<MeshHit> {
        let mut best: Option<MeshHit> = None;
        let mut best_key = key;
        self.bvh.nearest(origin, direction, t_max, |index, t_max| {
            let triangle = &self.triangles[index];
            let Some((t, u, v)) = triangle.hit(origin, direction, 0.0, t_max) else {
                return t_max;
            };
            let order = self.order_key(index);
            let bound = best.map_or(t_max, |hit| hit.t);
            if t == bound && order > best_key {
                return t_max;
            }
            let object = &self.objects[triangle.mesh_object as usize];
            if object.back_faces == BackFaces::Cull && self.back_facing(triangle, direction) {
                return t_max;
            }
            best = Some(MeshHit {
                t,
                triangle: index,
                u,
                v,
            });
            best_key = order;
            t
        });
        best
    }

    /// Whether any triangle but `skip` meets `origin + t·direction` for `t` in `[t_min, t_max]`,
    /// whichever side faces the ray (both sides cast shadows).
    pub fn occluded(
        &self,
        origin: DVec3,
        direction: DVec3,
        t_min: f64,
        t_max: f64,
        skip: Option<usize>,
    ) -> bool {
        self.bvh.any(origin, direction, t_min, t_max, |index| {
            Some(index) != skip
                && self.triangles[index]
                    .hit(origin, direction, t_min, t_max)
                    .is_some()
        })
    }

    /// Whether the hit sees the back of its triangle from `direction`.
    pub fn hit_back_facing(&self, hit: &MeshHit, direction: DVec3) -> bool {
        self.back_facing(&self.triangles[hit.triangle], direction)
    }

    /// The object of a hit.
    pub fn object_of(&self, hit: &MeshHit) -> &MeshObject {
        &self.objects[self.triangles[hit.triangle].mesh_object as usize]
    }

    /// The corners' vertex numbers of a hit's triangle.
    fn corner_vertices(&self, triangle: &WorldTriangle) -> [usize; 3] {
        let object = &self.objects[triangle.mesh_object as usize];
        object.mesh.triangles[triangle.triangle as usize].map(|v| v as usize)
    }

    /// Face normal, interpolated normal and corner weights at weights `(1 − u − v, u, v)`.
    pub fn interpolate(&self, triangle_index: usize, u: f64, v: f64) -> Interpolated {
        let triangle = &self.triangles[triangle_index];
        let object = &self.objects[triangle.mesh_object as usize];
        let mut face_normal = triangle.e1.cross(triangle.e2).normalize_or_zero();
        if object.mirrored {
            face_normal = -face_normal;
        }
        let weights = DVec3::new(1.0 - u - v, u, v);
        let corners = self.corner_vertices(triangle);
        let normals = corners.map(|v| {
            let model = object.mesh.normals.get(v).copied().unwrap_or_default().as_dvec3();
            (object.normal_to_world * model).normalize_or_zero()
        });
        let interpolated = match object.normal_interpolation {
            NormalInterpolation::Nlerp => {
                normals[0] * weights.x + normals[1] * weights.y + normals[2] * weights.z
            }
            NormalInterpolation::Slerp => slerp_triangle(normals, weights),
        };
        Interpolated {
            face_normal,
            normal: interpolated.try_normalize().unwrap_or(face_normal),
            weights,
        }
    }

    /// The texture coordinates of set `uv_set` at corner weights `weights` (zero where the mesh
    /// has none).
    pub fn uv(&self, triangle_index: usize, uv_set: u8, weights: DVec3) -> DVec2 {
        let triangle = &self.triangles[triangle_index];
        let mesh = &self.objects[triangle.mesh_object as usize].mesh;
        let set = if uv_set == 1 { &mesh.uvs1 } else { &mesh.uvs };
        let [a, b, c] = self
            .corner_vertices(triangle)
            .map(|v| set.get(v).copied().unwrap_or_default().as_dvec2());
        a * weights.x + b * weights.y + c * weights.z
    }

    /// The vertex colour (glTF `COLOR_0`, white where there is none) at `weights`.
    pub fn tint(&self, triangle_index: usize, weights: DVec3) -> DVec3 {
        let triangle = &self.triangles[triangle_index];
        let mesh = &self.objects[triangle.mesh_object as usize].mesh;
        if mesh.colors.is_empty() {
            return DVec3::ONE;
        }
        let [a, b, c] = self
            .corner_vertices(triangle)
            .map(|v| mesh.colors.get(v).map_or(DVec3::ONE, |c| c.truncate().as_dvec3()));
        a * weights.x + b * weights.y + c * weights.z
    }

    /// The interpolated tangent (world axes, not renormalised, as the rasterizer has it) and
    /// handedness at `weights`; zero where the mesh has none.
    pub fn tangent(&self, triangle_index: usize, weights: DVec3) -> DVec4 {
        let triangle = &self.triangles[triangle_index];
        let object = &self.objects[triangle.mesh_object as usize];
        let [a, b, c] = self.corner_vertices(triangle).map(|v| {
            object.mesh.tangents.get(v).map_or(DVec4::ZERO, |t| {
                let direction = (object.tangent_to_world * t.truncate().as_dvec3()).normalize_or_zero();
                let handedness = if object.mirrored { -t.w } else { t.w };
                direction.extend(f64::from(handedness))
            })
        });
        a * weights.x + b * weights.y + c * weights.z
    }
}
