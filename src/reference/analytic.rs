//! The analytic shapes: `Sphere`, `Plane` and `Cube` recognised by their meshes and
//! intersected in closed form in model space (see the `reference` module documentation).

use glam::{DMat3, DMat4, DVec3};

use crate::mesh::{Mesh, primitives};
use crate::scene::{BackFaces, LightingComponent, Material, Object, presets};

/// An analytic surface in its model space.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Shape {
    /// The unit sphere at the origin.
    Sphere,
    /// The square `[−1, 1]²` in the XZ plane, facing +Y.
    Plane,
    /// The cube `[−1, 1]³`.
    Cube,
}

pub fn recognize_shape(mesh: &Mesh) -> Option<Shape> {
    if !mesh.materials.is_empty() {
        return None;
    }
    let vertices = mesh.positions.len();
    let root = (vertices as f64).sqrt().round() as usize;
    if root * root == vertices && root > primitives::MIN_SPHERE_SEGMENTS as usize {
        let segments = (root - 1) as u32;
        if segments <= primitives::MAX_SPHERE_SEGMENTS && *mesh == primitives::sphere(segments) {
            return Some(Shape::Sphere);
        }
    }
    if *mesh == primitives::plane() {
        return Some(Shape::Plane);
    }
    if *mesh == primitives::cube() {
        return Some(Shape::Cube);
    }
    None
}

/// The analytic shape of a textured primitive (`textured_sphere`, `textured_plane`,
/// `textured_cube`: a primitive's mesh with texture coordinates and tangents added).
pub fn recognize_textured_shape(mesh: &Mesh) -> Option<Shape> {
    if mesh.uvs.is_empty() || !mesh.materials.is_empty() {
        return None;
    }
    let vertices = mesh.positions.len();
    let root = (vertices as f64).sqrt().round() as usize;
    let sphere_sized = root * root == vertices && root <= primitives::MAX_SPHERE_SEGMENTS as usize + 1;
    if !sphere_sized
        && vertices != primitives::plane().positions.len()
        && vertices != primitives::cube().positions.len()
    {
        return None;
    }
    let bare = Mesh {
        uvs: Vec::new(),
        tangents: Vec::new(),
        ..mesh.clone()
    };
    recognize_shape(&bare)
}

/// One analytic object, ready to be hit by rays in eye-relative world space.
pub struct Surface {
    /// Index in the scene's objects.
    pub object: u32,
    pub shape: Shape,
    /// From eye-relative world space to model space.
    model_from_world: DMat4,
    /// Model-space normals to world space (the inverse transpose of the linear part).
    normal_to_world: DMat3,
    pub material: Material,
    pub back_faces: BackFaces,
    pub component: LightingComponent,
}

impl Surface {
    /// The object `object` (number `index`), a `shape`, with the eye at `eye`.
    pub fn new(index: usize, object: &Object, shape: Shape, eye: DVec3) -> Surface {
        let world_from_model = DMat4::from_translation(-eye) * object.transform;
        let linear = DMat3::from_mat4(object.transform);
        Surface {
            object: index as u32,
            shape,
            model_from_world: world_from_model.inverse(),
            normal_to_world: linear.inverse().transpose(),
            material: object.material.unwrap_or_else(presets::default_material),
            back_faces: object.back_faces,
            component: object.component,
        }
    }

    /// A model-space normal in world space, unit.
    pub fn world_normal(&self, model_normal: DVec3) -> DVec3 {
        (self.normal_to_world * model_normal).normalize_or_zero()
    }

    /// Calls `found(t, model-space outward normal)` for every intersection of the ray
    /// `origin + t·direction` (eye-relative world space) with the shape, `t` in `[0, 1]`.
    pub fn intersect(&self, origin: DVec3, direction: DVec3, mut found: impl FnMut(f64, DVec3)) {
        let o = self.model_from_world.transform_point3(origin);
        let d = self.model_from_world.transform_vector3(direction);
        let mut report = |t: f64, normal: DVec3| {
            if (0.0..=1.0).contains(&t) {
                found(t, normal);
            }
        };
        match self.shape {
            Shape::Sphere => {
                // |o + s·u|² = 1 along the unit direction u: s² − 2bs + c = 0 with b = −o·u,
                // c = |o|² − 1. The discriminant b² − c is computed as 1 − |o + b·u|² (the
                // squared distance of the ray from the centre), which does not cancel when the
                // origin is far away or the shape very flat; the roots are q and c/q with
                // q = b + sign(b)·√(b² − c) (Ray Tracing Gems, chapter 7).
                let length = d.length();
                if length == 0.0 {
                    return;
                }
                let unit = d / length;
                let b = -o.dot(unit);
                let closest = o + b * unit;
                let discriminant = 1.0 - closest.dot(closest);
                if discriminant < 0.0 {
                    return;
                }
                let c = o.dot(o) - 1.0;
                let q = b + if b < 0.0 { -1.0 } else { 1.0 } * discriminant.sqrt();
                let distances = if q == 0.0 { [0.0, 0.0] } else { [q, c / q] };
                for distance in distances {
                    let t = distance / length;
                    report(t, o + t * d);
                }
            }
            Shape::Plane => {
                if d.y != 0.0 {
                    let t = -o.y / d.y;
                    let p = o + t * d;
                    if p.x.abs() <= 1.0 && p.z.abs() <= 1.0 {
                        report(t, DVec3::Y);
                    }
                }
            }
            Shape::Cube => {
                let (mut enter, mut exit) = (f64::NEG_INFINITY, f64::INFINITY);
                let (mut enter_normal, mut exit_normal) = (DVec3::ZERO, DVec3::ZERO);
                for axis in 0..3 {
                    let (origin, step) = (o[axis], d[axis]);
                    if step == 0.0 {
                        if origin.abs() > 1.0 {
                            return;
                        }
                        continue;
                    }
                    let (t0, t1) = ((-1.0 - origin) / step, (1.0 - origin) / step);
                    let outward = DVec3::AXES[axis] * step.signum();
                    if t0.min(t1) > enter {
                        enter = t0.min(t1);
                        enter_normal = -outward;
                    }
                    if t0.max(t1) < exit {
                        exit = t0.max(t1);
                        exit_normal = outward;
                    }
                }
                if enter <= exit {
                    report(enter, enter_normal);
                    report(exit, exit_normal);
                }
            }
        }
    }
}
