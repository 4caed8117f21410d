//! What the reference reads from a surface besides its geometry, in `f64`: textures at level 0,
//! normal maps and Slerp, each the transcription of the rasterizer's definition
//! (`texture::Texture::sample`'s bilinear step and wrap modes, `render::normals::perturb_normal`,
//! `render::normals::slerp`) without its `f32` rounding or its mipmaps.

use glam::{DVec2, DVec3, DVec4};

use crate::texture::{Sampler, Texture, wrap_index};

/// The bilinear value of `texture`'s level 0 at `uv`, wrapped per `sampler`: the texture
/// itself, which mipmapping approximates. Zero for a texture without levels.
pub fn bilinear_level0(texture: &Texture, uv: DVec2, sampler: &Sampler) -> DVec4 {
    let Some(level) = texture.levels.first() else {
        return DVec4::ZERO;
    };
    let uv = if uv.is_finite() { uv } else { DVec2::ZERO };
    let pair = |t: f64, size: u32, wrap| {
        let size = f64::from(size.max(1));
        let x = t * size - 0.5;
        let first = x.floor();
        (
            wrap_index(first, size, wrap),
            wrap_index(first + 1.0, size, wrap),
            x - first,
        )
    };
    let (x0, x1, fx) = pair(uv.x, level.width, sampler.wrap_s);
    let (y0, y1, fy) = pair(uv.y, level.height, sampler.wrap_t);
    let texel = |x, y| level.texel(x, y).as_dvec4();
    let top = texel(x0, y0).lerp(texel(x1, y0), fx);
    let bottom = texel(x0, y1).lerp(texel(x1, y1), fx);
    top.lerp(bottom, fy)
}

/// `render::normals::perturb_normal` in `f64`: the tangent-space texel (`rgb` in [0, 1]) applied
/// to the frame of `normal` and `tangent` (`w` the bitangent's handedness), `scale` glTF's.
pub fn perturb_normal(normal: DVec3, tangent: DVec4, texel: DVec3, scale: f64) -> DVec3 {
    let t = (tangent.truncate() - normal * normal.dot(tangent.truncate())).normalize_or_zero();
    if t == DVec3::ZERO || !texel.is_finite() {
        return normal;
    }
    let handedness = if tangent.w < 0.0 { -1.0 } else { 1.0 };
    let bitangent = normal.cross(t) * handedness;
    let mapped = texel * 2.0 - DVec3::ONE;
    let perturbed = t * (mapped.x * scale) + bitangent * (mapped.y * scale) + normal * mapped.z;
    perturbed.try_normalize().unwrap_or(normal)
}

/// `render::normals::slerp_triangle` in `f64`: the first two normals slerped by their weights,
/// then the result towards the third.
pub fn slerp_triangle(normals: [DVec3; 3], weights: DVec3) -> DVec3 {
    let first_two = weights.x + weights.y;
    let edge = if first_two > 0.0 {
        slerp(normals[0], normals[1], weights.y / first_two)
    } else {
        normals[0]
    };
    slerp(edge, normals[2], weights.z)
}

/// `render::normals::slerp` in `f64` (the same form, stable near 0 and π).
fn slerp(n0: DVec3, n1: DVec3, t: f64) -> DVec3 {
    const SMALL_SINE: f64 = 1e-12;
    let cos = n0.dot(n1);
    let cross = n0.cross(n1);
    let sin = cross.length();
    if n0 == DVec3::ZERO || n1 == DVec3::ZERO || (sin < SMALL_SINE && cos > 0.0) {
        return n0.lerp(n1, t).normalize_or_zero();
    }
    let (theta, towards) = if sin < SMALL_SINE {
        (std::f64::consts::PI, n0.any_orthonormal_vector())
    } else {
        (sin.atan2(cos), (cross / sin).cross(n0))
    };
    let (sin_t, cos_t) = (t * theta).sin_cos();
    n0 * cos_t + towards * sin_t
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{Vec2, Vec3, Vec4};

    fn checker(size: u32) -> Texture {
        let texels = (0..size * size)
            .map(|i| Vec4::splat(((i % size + i / size) % 2) as f32))
            .collect();
        Texture::from_texels(size, size, texels).unwrap()
    }

    /// Level 0 bilinear agrees with the rasterizer's sampler when it magnifies (it uses level 0
    /// then too), to `f32` rounding.
    #[test]
    fn bilinear_matches_the_samplers_magnified_lookups() {
        let texture = checker(8);
        let sampler = Sampler::default();
        for (u, v) in [(0.01, 0.02), (0.5, 0.5), (0.3, 0.77), (-0.2, 1.4), (0.999, 0.0)] {
            let exact = bilinear_level0(&texture, DVec2::new(u, v), &sampler);
            let sampled = texture.sample(Vec2::new(u as f32, v as f32), Vec2::ZERO, Vec2::ZERO, &sampler);
            assert!((exact - sampled.as_dvec4()).abs().max_element() < 1e-5, "{u} {v}");
        }
    }

    #[test]
    fn slerp_and_perturbation_agree_with_the_rasterizers() {
        let normals = [
            Vec3::new(0.0, 0.0, 1.0),
            Vec3::new(1.0, 0.0, 1.0).normalize(),
            Vec3::new(0.0, 1.0, 0.2).normalize(),
        ];
        let weights = Vec3::new(0.2, 0.3, 0.5);
        let exact = slerp_triangle(normals.map(|n| n.as_dvec3()), weights.as_dvec3());
        let raster = crate::render::normals::slerp_triangle(normals, weights);
        assert!((exact - raster.as_dvec3()).length() < 1e-6);
        let tangent = Vec4::new(1.0, 0.0, 0.0, -1.0);
        let texel = Vec3::new(0.7, 0.3, 0.9);
        let exact = perturb_normal(DVec3::Z, tangent.as_dvec4(), texel.as_dvec3(), 0.8);
        let raster = crate::render::normals::perturb_normal(Vec3::Z, tangent, texel, 0.8);
        assert!((exact - raster.as_dvec3()).length() < 1e-6);
    }
}
