//! How a pixel's normal is formed from its triangle's vertex normals: interpolated component by
//! component and renormalised (Nlerp), or along great arcs (Slerp, seed 000, generalised to a
//! triangle), then bent by a normal map. The scalar forms here are the specification; the
//! lanes (`shade_fast`, `surface_lanes`) are held to them bit for bit.

use glam::{Vec3, Vec4};

use crate::render::trig;

/// A tangent-space normal map texel (`rgb` in [0, 1], encoding [−1, 1]) applied to the
/// interpolated frame: `normalize(T·x·s + B·y·s + N·z)` with `B = (N × T)·w` (glTF's
/// convention, `s` its `scale`). Without a usable tangent the normal is left as it is.
pub fn perturb_normal(normal: Vec3, tangent: Vec4, texel: Vec3, scale: f32) -> Vec3 {
    let t = (tangent.truncate() - normal * normal.dot(tangent.truncate())).normalize_or_zero();
    if t == Vec3::ZERO || !texel.is_finite() {
        return normal;
    }
    let handedness = if tangent.w < 0.0 { -1.0 } else { 1.0 };
    let bitangent = normal.cross(t) * handedness;
    let mapped = texel * 2.0 - Vec3::ONE;
    let perturbed = t * (mapped.x * scale) + bitangent * (mapped.y * scale) + normal * mapped.z;
    perturbed.try_normalize().unwrap_or(normal)
}

/// `v` scaled to unit length; where it has (almost) none, as when the vertex normals of an
/// edge point in opposite directions, `fallback()` (the face normal).
#[inline]
pub(crate) fn renormalize_or_else(v: Vec3, fallback: impl FnOnce() -> Vec3) -> Vec3 {
    let length_squared = v.length_squared();
    if length_squared > 1e-12 {
        v / length_squared.sqrt()
    } else {
        fallback()
    }
}

/// Spherical interpolation of three unit normals with barycentric `weights` (seed 000's SLERP,
/// generalised to a triangle): first between the first two in the ratio of their weights, then
/// from that towards the third by its weight. On an edge it is exactly the seed's two-point
/// SLERP; inside it keeps unit length and equal angles per step along each of those arcs.
pub fn slerp_triangle(normals: [Vec3; 3], weights: Vec3) -> Vec3 {
    slerp_triangle_along(&NormalArc::new(normals[0], normals[1]), normals[2], weights)
}

/// [`slerp_triangle`] with the arc between the first two normals given: it is the same at every
/// point of a triangle, so the per-pixel shading forms it once per triangle.
#[inline]
pub fn slerp_triangle_along(first_two: &NormalArc, third: Vec3, weights: Vec3) -> Vec3 {
    let first_two_weight = weights.x + weights.y;
    let edge = if first_two_weight > 0.0 {
        first_two.at(weights.y / first_two_weight)
    } else {
        first_two.start()
    };
    NormalArc::new(edge, third).at(weights.z)
}

/// Seed 000's `n(t) = (sin((1 − t)θ)·n₀ + sin(tθ)·n₁) / sin θ`, evaluated in the equivalent
/// form `n(t) = cos(tθ)·n₀ + sin(tθ)·u`, with `u` the unit vector perpendicular to `n₀` in the
/// plane of the two, towards `n₁`. Dividing by `sin θ` loses all precision as θ nears π (θ
/// itself is accurate, from `atan2(|n₀×n₁|, n₀·n₁)`, but `sin θ` then carries the rounding of π);
/// this form stays unit length and exact at t = 0 for every θ. Near θ = 0 the chord is the arc:
/// linear interpolation, renormalised. At θ = π every great circle joins the two: the arc turns
/// about an axis perpendicular to `n₀`, chosen from `n₀` alone so the result is deterministic.
/// A zero input gives a linear interpolation. The sine, cosine and `atan2` are `trig`'s
/// polynomials (within 2 units of the last place), which the lanes evaluate with the same bits.
pub fn slerp(n0: Vec3, n1: Vec3, t: f32) -> Vec3 {
    NormalArc::new(n0, n1).at(t)
}

/// The path [`slerp`] takes from one normal to another, formed once for any number of `t`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum NormalArc {
    /// Normals (nearly) parallel, or a zero one: the chord, renormalised.
    Chord { start: Vec3, end: Vec3 },
    /// `n(t) = cos(tθ)·start + sin(tθ)·towards`.
    Turn { start: Vec3, towards: Vec3, angle: f32 },
}

/// Below this `|n₀ × n₁|`, [`slerp`]'s normals are parallel or opposite.
pub const SMALL_SINE: f32 = 1e-6;

impl NormalArc {
    pub fn new(n0: Vec3, n1: Vec3) -> Self {
        let cos = n0.dot(n1);
        let cross = n0.cross(n1);
        let sin = cross.length();
        if n0 == Vec3::ZERO || n1 == Vec3::ZERO || (sin < SMALL_SINE && cos > 0.0) {
            return NormalArc::Chord { start: n0, end: n1 };
        }
        let (angle, towards) = if sin < SMALL_SINE {
            (std::f32::consts::PI, n0.any_orthonormal_vector())
        } else {
            (trig::atan2(sin, cos), (cross / sin).cross(n0))
        };
        NormalArc::Turn {
            start: n0,
            towards,
            angle,
        }
    }

    /// The normal a share `t` of the way along.
    #[inline]
    pub fn at(&self, t: f32) -> Vec3 {
        match *self {
            NormalArc::Chord { start, end } => start.lerp(end, t).normalize_or_zero(),
            NormalArc::Turn {
                start,
                towards,
                angle,
            } => {
                let (sin_t, cos_t) = trig::sin_cos(t * angle);
                start * cos_t + towards * sin_t
            }
        }
    }

    /// The normal it starts from.
    #[inline]
    pub fn start(&self) -> Vec3 {
        match *self {
            NormalArc::Chord { start, .. } | NormalArc::Turn { start, .. } => start,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slerp_takes_equal_angle_steps_where_nlerp_does_not() {
        let (n0, n1) = (Vec3::X, Vec3::Y);
        let quarter = slerp(n0, n1, 0.25);
        assert!((angle(n0, quarter) - std::f32::consts::FRAC_PI_8).abs() < 1e-6);
        let nlerp = n0.lerp(n1, 0.25).normalize();
        // Nlerp at t = 1/4 is only 18.4° along, not 22.5°.
        assert!((angle(n0, nlerp) - (0.25f32 / 0.75).atan()).abs() < 1e-6);
        assert!((angle(quarter, nlerp)).abs() > 0.06);
    }

    #[test]
    fn slerp_ends_and_unit_length() {
        let (n0, n1) = (Vec3::new(0.6, 0.8, 0.0), Vec3::new(0.0, 0.6, 0.8));
        assert!((slerp(n0, n1, 0.0) - n0).length() < 1e-6);
        assert!((slerp(n0, n1, 1.0) - n1).length() < 1e-6);
        for k in 0..=10 {
            assert!((slerp(n0, n1, k as f32 / 10.0).length() - 1.0).abs() < 1e-6);
        }
    }

    #[test]
    fn slerp_is_stable_near_zero_and_pi() {
        let n0 = Vec3::Z;
        for tiny in [0.0, 1e-9, 1e-6, 1e-4] {
            let near = Vec3::new(tiny, 0.0, 1.0).normalize();
            let opposite = Vec3::new(tiny, 0.0, -1.0).normalize();
            for t in [0.0, 0.3, 0.5, 1.0] {
                for n1 in [near, opposite] {
                    let n = slerp(n0, n1, t);
                    assert!(
                        n.is_finite() && (n.length() - 1.0).abs() < 1e-5,
                        "θ≈{tiny} t={t}: {n}"
                    );
                }
            }
            // Halfway between opposite normals is a quarter turn from both.
            let half = slerp(n0, opposite, 0.5);
            assert!((angle(n0, half) - std::f32::consts::FRAC_PI_2).abs() < 1e-3);
        }
        assert!(slerp(Vec3::ZERO, Vec3::Z, 0.5).is_finite());
    }

    #[test]
    fn triangle_slerp_matches_edges_and_corners() {
        let normals = [Vec3::X, Vec3::Y, Vec3::Z];
        for (i, corner) in normals.iter().enumerate() {
            let mut w = Vec3::ZERO;
            w[i] = 1.0;
            assert!((slerp_triangle(normals, w) - *corner).length() < 1e-6);
        }
        let edge = slerp_triangle(normals, Vec3::new(0.5, 0.5, 0.0));
        assert!((edge - slerp(Vec3::X, Vec3::Y, 0.5)).length() < 1e-6);
        let center = slerp_triangle(normals, Vec3::splat(1.0 / 3.0));
        assert!(center.is_finite() && (center.length() - 1.0).abs() < 1e-6);
    }

    fn angle(a: Vec3, b: Vec3) -> f32 {
        a.cross(b).length().atan2(a.dot(b))
    }
}
