//! The surface stage: what vertex colours, colour textures and normal maps make of a material
//! at eight points, before they are lit.
//!
//! The general path (`shade::shade_sample`) builds, per Phong pixel, the material the lighting
//! sees: `k_d` times the interpolated vertex colour (`frame::tinted`, in frames with vertex
//! attributes), then `k_d`, and `k_a` when there is no ambient texture, times the diffuse
//! texture's texel, `k_a` times the ambient texture's, and the interpolated normal perturbed by
//! the normal map (`shade::perturb_normal`). Here the same operations run on eight points at
//! once. Each point brings its source triangle's vertices and its [`Footprint`] (the source
//! weights at it and one pixel to the right and one down, from which the texture coordinates'
//! derivatives follow); the stage gathers the vertex attributes, interpolates them lane-wise,
//! samples each texture through `texture_lanes::sample_lanes`, and hands the lighting `k_a` and
//! `k_d` per lane ([`SurfaceLanes`]) and the perturbed normals. Flat and Gouraud pixels take
//! only the diffuse texture's modulation from here ([`texture_colors`]).
//!
//! Which of the steps run is decided once per batch of points from the material (all points
//! of a batch share it), never per point.

use glam::Vec3;

use crate::render::frame::{Frame, VertexAttributes};
use crate::render::lanes::{Floats, LANES, Vec2s, Vec3s};
use crate::render::texture_lanes::sample_lanes;
use crate::scene::{Material, TextureBinding};

/// `k_a` and `k_d` per lane: the material's, modulated by vertex colours and textures.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfaceLanes {
    pub ambient: Vec3s,
    pub diffuse: Vec3s,
}

impl SurfaceLanes {
    /// `material`'s own coefficients on every lane.
    #[inline(always)]
    pub fn of(material: &Material) -> Self {
        SurfaceLanes {
            ambient: Vec3s::splat(material.ambient),
            diffuse: Vec3s::splat(material.diffuse),
        }
    }
}

/// The source-triangle weights of a shading point (`at`) and of the points one pixel to its
/// right and one pixel below (`shade::source_weights` there): the texture footprint.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Footprint {
    pub at: Vec3,
    pub right: Vec3,
    pub down: Vec3,
}

/// Whether the surface of `material` varies over a triangle of `frame` (a texture, or vertex
/// colours, which every frame with vertex attributes applies), so that it needs this stage.
#[inline]
pub fn varies(frame: &Frame, material: &Material) -> bool {
    !frame.vertex_attributes.is_empty() || has_texture(material)
}

/// Whether `material` samples a texture, so that its points need a [`Footprint`] beyond `at`.
#[inline]
fn has_texture(material: &Material) -> bool {
    let textures = &material.textures;
    textures.diffuse.is_some() || textures.ambient.is_some() || textures.normal.is_some()
}

/// Eight shading points: per lane its source triangle's vertices and its footprint (only
/// `at` is read unless the material has a texture).
pub struct SurfacePoints<'a> {
    pub vertices: &'a [[u32; 3]; LANES],
    pub footprints: &'a [Footprint; LANES],
}

/// The vertex attributes of the points' triangles, and the points' weights, in lanes.
struct Gathered {
    attributes: [[VertexAttributes; 3]; LANES],
    at: [Floats; 3],
}

impl Gathered {
    fn new(frame: &Frame, points: &SurfacePoints) -> Self {
        Gathered {
            attributes: points
                .vertices
                .map(|vertices| vertices.map(|v| frame.attributes(v))),
            at: weight_lanes(points.footprints, |footprint| footprint.at),
        }
    }

    /// A `Vec3` attribute interpolated with `weights`: `a·w₀ + b·w₁ + c·w₂`, as `Vec3`s.
    fn interpolate3(&self, weights: &[Floats; 3], attribute: impl Fn(&VertexAttributes) -> Vec3) -> Vec3s {
        let corner = |k: usize| Vec3s::from_array(&self.attributes.map(|vertices| attribute(&vertices[k])));
        corner(0).scale(weights[0]) + corner(1).scale(weights[1]) + corner(2).scale(weights[2])
    }

    /// A texture's coordinates interpolated with `weights`, as `Vec2`s.
    fn uv(&self, weights: &[Floats; 3], binding: &TextureBinding) -> Vec2s {
        let corner = |k: usize| {
            Vec2s::from_array(&self.attributes.map(|vertices| {
                let vertex = &vertices[k];
                if binding.uv_set == 1 {
                    vertex.uv1
                } else {
                    vertex.uv
                }
            }))
        };
        corner(0).scale(weights[0]) + corner(1).scale(weights[1]) + corner(2).scale(weights[2])
    }

    /// The texel of `binding` at each point: its coordinates and their changes one pixel
    /// right and one down, sampled lane by lane (the general path's `sample`).
    fn sample(&self, frame: &Frame, points: &SurfacePoints, binding: &TextureBinding) -> Vec3s {
        let uv = self.uv(&self.at, binding);
        let right = self.uv(&weight_lanes(points.footprints, |f| f.right), binding);
        let down = self.uv(&weight_lanes(points.footprints, |f| f.down), binding);
        let texels = sample_lanes(
            &frame.textures[binding.texture as usize],
            uv,
            right - uv,
            down - uv,
            &binding.sampler,
        );
        Vec3s::from_array(&texels.map(|texel| texel.truncate()))
    }
}

/// The weights of each footprint's point `which`, one lane array per vertex.
#[inline(always)]
fn weight_lanes(footprints: &[Footprint; LANES], which: impl Fn(&Footprint) -> Vec3) -> [Floats; 3] {
    let weights = footprints.map(|footprint| which(&footprint));
    [
        Floats(weights.map(|w| w.x)),
        Floats(weights.map(|w| w.y)),
        Floats(weights.map(|w| w.z)),
    ]
}

/// The surface of `material` at `points` of `frame`, whose interpolated and renormalised
/// (front) normals are `normals`: per lane `k_a` and `k_d`, and the normal after the normal
/// map. Each lane has the bits the general path's material and normal have at its point.
pub fn surface_lanes(
    frame: &Frame,
    material: &Material,
    points: &SurfacePoints,
    normals: Vec3s,
) -> (SurfaceLanes, Vec3s) {
    let mut surface = SurfaceLanes::of(material);
    if !varies(frame, material) {
        return (surface, normals);
    }
    let gathered = Gathered::new(frame, points);
    if !frame.vertex_attributes.is_empty() {
        surface.diffuse = surface.diffuse * gathered.interpolate3(&gathered.at, |v| v.tint);
    }
    let textures = &material.textures;
    if let Some(binding) = textures.diffuse {
        let texel = gathered.sample(frame, points, &binding);
        surface.diffuse = surface.diffuse * texel;
        if textures.ambient.is_none() {
            surface.ambient = surface.ambient * texel;
        }
    }
    if let Some(binding) = textures.ambient {
        surface.ambient = surface.ambient * gathered.sample(frame, points, &binding);
    }
    let normals = match textures.normal {
        Some(binding) => {
            let tangent = gathered.interpolate3(&gathered.at, |v| v.tangent.truncate());
            let handedness = gathered.interpolate_w(&gathered.at);
            let texel = gathered.sample(frame, points, &binding);
            perturb_normal_lanes(normals, tangent, handedness, texel, binding.scale)
        }
        None => normals,
    };
    (surface, normals)
}

impl Gathered {
    /// The tangents' `w` (the bitangent's handedness) interpolated with `weights`, the fourth
    /// component of the general path's `Vec4` interpolation.
    fn interpolate_w(&self, weights: &[Floats; 3]) -> Floats {
        let corner = |k: usize| Floats(self.attributes.map(|vertices| vertices[k].tangent.w));
        corner(0) * weights[0] + corner(1) * weights[1] + corner(2) * weights[2]
    }
}

/// The diffuse texture's colour (its texel's RGB) at each point: what multiplies the textured
/// part of a flat or Gouraud pixel.
pub fn texture_colors(frame: &Frame, binding: &TextureBinding, points: &SurfacePoints) -> Vec3s {
    Gathered::new(frame, points).sample(frame, points, binding)
}

/// `shade::perturb_normal` lane-wise: the tangent `tangent` (its `w`, the handedness, apart)
/// made perpendicular to `normal`, the texel mapped from [0, 1] to [−1, 1], and the normal
/// where the tangent is unusable, the texel not finite or the result of no length.
#[inline(always)]
fn perturb_normal_lanes(
    normal: Vec3s,
    tangent: Vec3s,
    handedness: Floats,
    texel: Vec3s,
    scale: f32,
) -> Vec3s {
    let zero = Floats::splat(0.0);
    let t = (tangent - normal.scale(normal.dot(tangent))).normalize_or_zero();
    let is_zero = |c: Floats| c.le(zero).and(zero.le(c));
    let no_tangent = is_zero(t.x).and(is_zero(t.y)).and(is_zero(t.z));
    let finite = texel
        .x
        .is_finite()
        .and(texel.y.is_finite())
        .and(texel.z.is_finite());
    let sign = zero
        .gt(handedness)
        .select(Floats::splat(-1.0), Floats::splat(1.0));
    let bitangent = normal.cross(t).scale(sign);
    let one = Floats::splat(1.0);
    let two = Floats::splat(2.0);
    let mapped = Vec3s {
        x: texel.x * two - one,
        y: texel.y * two - one,
        z: texel.z * two - one,
    };
    let scale = Floats::splat(scale);
    let perturbed = t.scale(mapped.x * scale) + bitangent.scale(mapped.y * scale) + normal.scale(mapped.z);
    // `try_normalize`: times `1 / length` where that is finite and positive.
    let reciprocal = one / perturbed.length();
    let normalizable = reciprocal.is_finite().and(reciprocal.gt(zero));
    let keep = no_tangent.or(!finite).or(!normalizable);
    keep.select3(normal, perturbed.scale(reciprocal))
}

#[cfg(test)]
mod tests {
    use glam::Vec4;

    use super::*;
    use crate::render::shade::perturb_normal;

    /// The normal map's lanes against `perturb_normal`, bit for bit, on awkward frames:
    /// tangents along the normal, zero, non-finite texels, both handednesses.
    #[test]
    fn perturbed_normals_equal_the_scalar_ones_bit_for_bit() {
        let normals = [
            Vec3::Z,
            Vec3::new(0.6, 0.0, 0.8),
            Vec3::new(-0.48, 0.6, 0.64),
            Vec3::Y,
            Vec3::X,
            Vec3::new(0.0, -0.6, 0.8),
            Vec3::Z,
            Vec3::new(1.0 / 3.0, 2.0 / 3.0, 2.0 / 3.0),
        ];
        let tangents = [
            Vec4::new(1.0, 0.0, 0.0, 1.0),
            Vec4::new(0.0, 1.0, 0.0, -1.0),
            Vec4::new(0.8, 0.6, 0.0, 1.0),
            Vec4::new(0.0, 1.0, 0.0, 1.0),
            Vec4::ZERO,
            Vec4::new(1.0, 0.2, -0.1, -0.5),
            Vec4::new(0.0, 0.0, 2.0, 1.0),
            Vec4::new(0.3, -0.9, 0.1, 0.0),
        ];
        let texels = [
            Vec3::new(0.5, 0.5, 1.0),
            Vec3::new(0.9, 0.2, 0.6),
            Vec3::new(0.0, 1.0, 0.5),
            Vec3::new(0.5, 0.5, 0.5),
            Vec3::new(0.7, 0.3, 0.9),
            Vec3::new(f32::NAN, 0.3, 0.9),
            Vec3::new(0.1, 0.8, 0.2),
            Vec3::new(0.5, 0.5, 0.0),
        ];
        for scale in [1.0, 0.4, -2.0, 0.0] {
            for rotation in 0..LANES {
                let mut t = tangents;
                t.rotate_left(rotation);
                let lanes = perturb_normal_lanes(
                    Vec3s::from_array(&normals),
                    Vec3s::from_array(&t.map(|t| t.truncate())),
                    Floats(t.map(|t| t.w)),
                    Vec3s::from_array(&texels),
                    scale,
                )
                .to_array();
                for lane in 0..LANES {
                    let scalar = perturb_normal(normals[lane], t[lane], texels[lane], scale);
                    assert_eq!(
                        lanes[lane].to_array().map(f32::to_bits),
                        scalar.to_array().map(f32::to_bits),
                        "scale {scale}, rotation {rotation}, lane {lane}"
                    );
                }
            }
        }
    }
}
