//! The illumination equations of the seeds (000, 001, 002, 004), evaluated at one surface point.
//!
//! ```text
//! I = k_e + k_a·I_a + Σ_lights att·spot·( k_d·I_l·max(N·L, 0) + k_s·I_l·spec )
//!     spec = max(R·V, 0)^n            Phong,       R = 2(N·L)N − L
//!     spec = max(N·H, 0)^n            Blinn-Phong, H = (L + V) / |L + V|
//!     spec is 0 where N·L ≤ 0 (a surface facing away from a light has no highlight from it)
//!     att  = 1 / (c + l·d + q·d²)      positional lights only
//!     spot = max(−L·D, 0)^exponent     inside the cone (−L·D ≥ cos cutoff), 0 outside
//! ```
//!
//! All vectors are in the same space (the renderer uses world space shifted so the eye is at the
//! origin). The terms are returned separately so the debug views can show each one.
//!
//! Degenerate inputs have defined results and never produce NaN:
//! - a zero normal gives `N·L = 0`: no diffuse or specular, only emission and ambient;
//! - a light exactly at the shaded point has no direction and contributes nothing;
//! - a zero half vector (`L = −V`) gives `N·H = 0`;
//! - `x^0 = 1` for every `x ≥ 0`, `0^0` included, so shininess 0 is a uniform specular term over
//!   the lit side;
//! - the attenuation denominator is at least [`MIN_ATTENUATION_DENOMINATOR`].

use glam::Vec3;

use crate::render::power;
use crate::scene::{Attenuation, LightingModel, Material};

/// Keeps `1 / (c + l·d + q·d²)` finite when a light sits on the surface with `c = 0`.
pub const MIN_ATTENUATION_DENOMINATOR: f32 = 1e-6;

/// A light prepared for shading: positions in shading space, directions unit length, the spot
/// cone as a cosine. Built once per frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShadingLight {
    pub color: Vec3,
    pub kind: ShadingLightKind,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ShadingLightKind {
    /// `to_light` is the unit vector from any surface point towards the light.
    Directional { to_light: Vec3 },
    Point {
        position: Vec3,
        attenuation: Attenuation,
    },
    Spot {
        position: Vec3,
        /// Unit direction the spot points in.
        axis: Vec3,
        cos_cutoff: f32,
        exponent: f32,
        attenuation: Attenuation,
    },
}

/// The terms of the lighting equation at one point, each an RGB intensity.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct LightingTerms {
    pub emission: Vec3,
    pub ambient: Vec3,
    pub diffuse: Vec3,
    pub specular: Vec3,
}

impl LightingTerms {
    /// The colour: the sum of every term (not clamped: clamping is the output stage's job).
    pub fn total(&self) -> Vec3 {
        self.emission + self.ambient + self.diffuse + self.specular
    }
}

/// Evaluates the lighting equation.
///
/// `position` is the surface point, `normal` its unit normal (or zero), `to_viewer` the unit
/// vector from the point towards the viewer, all in the space the lights were prepared in.
pub fn illuminate(
    material: &Material,
    lights: &[ShadingLight],
    ambient_light: Vec3,
    position: Vec3,
    normal: Vec3,
    to_viewer: Vec3,
) -> LightingTerms {
    illuminate_with_visibility(
        material,
        lights,
        ambient_light,
        position,
        normal,
        to_viewer,
        |_, _| 1.0,
    )
}

/// [`illuminate`] with the seeds' shadow term `S_i`: `visibility(i, L)` is the share of light
/// `i` that reaches the point (1 lit, 0 in shadow), asked only for lights that face the surface.
pub fn illuminate_with_visibility(
    material: &Material,
    lights: &[ShadingLight],
    ambient_light: Vec3,
    position: Vec3,
    normal: Vec3,
    to_viewer: Vec3,
    visibility: impl Fn(usize, Vec3) -> f32,
) -> LightingTerms {
    illuminate_each_light(
        material,
        lights,
        ambient_light,
        position,
        normal,
        to_viewer,
        visibility,
        |_, _| {},
    )
}

/// [`illuminate_with_visibility`], also handing `each` every light's part of the sums, in the
/// order they are added: the terms' diffuse and specular sums are exactly the per-light parts
/// added one after the other from zero. The renderer passes a closure that does nothing (it
/// inlines away); the pixel inspector (`render::inspect`) keeps the parts, so its breakdown is
/// the frame's own arithmetic, not a copy of it.
#[allow(clippy::too_many_arguments)]
#[inline]
pub fn illuminate_each_light(
    material: &Material,
    lights: &[ShadingLight],
    ambient_light: Vec3,
    position: Vec3,
    normal: Vec3,
    to_viewer: Vec3,
    visibility: impl Fn(usize, Vec3) -> f32,
    mut each: impl FnMut(usize, &LightContribution),
) -> LightingTerms {
    let mut terms = LightingTerms {
        emission: material.emission,
        ..LightingTerms::default()
    };
    if material.model == LightingModel::Unlit {
        terms.diffuse = material.diffuse;
        return terms;
    }
    terms.ambient = material.ambient * ambient_light;
    for (index, light) in lights.iter().enumerate() {
        let contribution = light_contribution(material, light, position, normal, to_viewer, |to_light| {
            visibility(index, to_light)
        });
        each(index, &contribution);
        if contribution.reaches {
            terms.diffuse += contribution.diffuse;
            terms.specular += contribution.specular;
        }
    }
    terms
}

/// What one light adds at a point, with the factors it is made of:
/// `diffuse = k_d·I·att·spot·S·(N·L)`, `specular = k_s·I·att·spot·S·spec` (Phong, Blinn-Phong;
/// Cook-Torrance as [`cook_torrance`] gives it).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct LightContribution {
    /// Unit vector from the point towards the light; zero where the light has no direction
    /// (it sits on the point).
    pub to_light: Vec3,
    /// `N·L`, with the normal the side is lit with.
    pub n_dot_l: f32,
    /// Distance attenuation (1 for directional lights).
    pub attenuation: f32,
    /// The spot cone's factor (1 for other lights, 0 outside the cone).
    pub spot: f32,
    /// The shadow term `S`: 1 where the light is not asked (it does not face the surface, or
    /// its cone or attenuation leaves nothing) or casts no shadow.
    pub visibility: f32,
    pub diffuse: Vec3,
    pub specular: Vec3,
    /// Whether the light adds anything (`diffuse` and `specular` are zero when it does not).
    pub reaches: bool,
}

/// One light's part of [`illuminate_each_light`]'s sums at a point of a lit model (not
/// `Unlit`); `visibility(L)` is asked only when the light faces the surface with some strength.
#[inline]
pub fn light_contribution(
    material: &Material,
    light: &ShadingLight,
    position: Vec3,
    normal: Vec3,
    to_viewer: Vec3,
    visibility: impl FnOnce(Vec3) -> f32,
) -> LightContribution {
    let mut contribution = LightContribution {
        attenuation: 1.0,
        spot: 1.0,
        visibility: 1.0,
        ..LightContribution::default()
    };
    let Some(incidence) = incidence_factors(light, position) else {
        return contribution;
    };
    let to_light = incidence.to_light;
    contribution.to_light = to_light;
    contribution.attenuation = incidence.attenuation;
    contribution.spot = incidence.spot;
    let strength = incidence.strength();
    let n_dot_l = normal.dot(to_light);
    contribution.n_dot_l = n_dot_l;
    if n_dot_l <= 0.0 || strength <= 0.0 {
        return contribution;
    }
    contribution.visibility = visibility(to_light);
    let strength = strength * contribution.visibility;
    if strength <= 0.0 {
        return contribution;
    }
    contribution.reaches = true;
    let irradiance = light.color * strength * n_dot_l;
    match material.model {
        LightingModel::Unlit => contribution.reaches = false,
        LightingModel::Lambert => contribution.diffuse = material.diffuse * irradiance,
        LightingModel::Phong | LightingModel::BlinnPhong => {
            contribution.diffuse = material.diffuse * irradiance;
            if material.specular != Vec3::ZERO {
                let cosine = if material.model == LightingModel::BlinnPhong {
                    normal.dot((to_light + to_viewer).normalize_or_zero())
                } else {
                    reflect(to_light, normal).dot(to_viewer)
                };
                // The seeds' specular term has no N·L factor: undo the one in `irradiance`.
                let intensity = light.color * strength;
                contribution.specular =
                    material.specular * intensity * specular_power(cosine, material.shininess);
            }
        }
        LightingModel::CookTorrance(surface) => {
            let reflection = cook_torrance(&surface, normal, to_light, to_viewer);
            contribution.diffuse = material.diffuse * (Vec3::ONE - reflection.fresnel) * irradiance;
            contribution.specular = reflection.specular * irradiance;
        }
    }
    contribution
}

/// What a Cook-Torrance surface reflects towards the viewer from one light.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CookTorranceReflection {
    /// `F`: the share of light reflected specularly at this angle; `1 − F` is left for diffuse.
    pub fresnel: Vec3,
    /// `π·F·D·G / (4(N·V)(N·L))`: multiplied by the light's `I·(N·L)` it is the specular term.
    /// The π matches the Lambert term `k_d·I·(N·L)` used without its 1/π, so both terms share
    /// units and a white, smooth, normal-incidence mirror returns `F0·I`.
    pub specular: Vec3,
}

/// Cook-Torrance's microfacet BRDF (seed 002) for unit vectors `normal`, `to_light`,
/// `to_viewer`, with `N·L > 0`:
///
/// ```text
/// F = F0 + (1 − F0)(1 − V·H)^5                                  Schlick
/// D = exp((cos²α − 1)/(m² cos²α)) / (π m² cos⁴α), cos α = N·H    Beckmann
///   = α² / (π ((N·H)²(α² − 1) + 1)²)                             GGX
/// G = min(1, 2(N·H)(N·V)/(V·H), 2(N·H)(N·L)/(V·H))               Cook-Torrance
/// ```
///
/// `G / ((N·V)(N·L))` is evaluated as one minimum of three ratios, so grazing angles
/// (N·V → 0 or N·L → 0) stay finite. A viewer below the surface (N·V ≤ 0) sees no highlight.
pub fn cook_torrance(
    surface: &crate::scene::Microfacet,
    normal: Vec3,
    to_light: Vec3,
    to_viewer: Vec3,
) -> CookTorranceReflection {
    let half = (to_light + to_viewer).normalize_or_zero();
    let v_dot_h = to_viewer.dot(half).max(0.0);
    let fresnel = surface.fresnel + (Vec3::ONE - surface.fresnel) * (1.0 - v_dot_h).powi(5);
    let n_dot_v = normal.dot(to_viewer);
    let n_dot_l = normal.dot(to_light);
    let n_dot_h = normal.dot(half);
    if n_dot_v <= 0.0 || n_dot_l <= 0.0 || n_dot_h <= 0.0 || v_dot_h <= 0.0 {
        return CookTorranceReflection {
            fresnel,
            specular: Vec3::ZERO,
        };
    }
    let distribution = microfacet_distribution(surface, n_dot_h);
    let g_over_nv_nl = (1.0 / (n_dot_v * n_dot_l))
        .min(2.0 * n_dot_h / (v_dot_h * n_dot_l))
        .min(2.0 * n_dot_h / (v_dot_h * n_dot_v));
    let specular = fresnel * (std::f32::consts::PI * distribution * g_over_nv_nl / 4.0);
    CookTorranceReflection { fresnel, specular }
}

/// `D(N·H)` of the surface's distribution.
pub fn microfacet_distribution(surface: &crate::scene::Microfacet, n_dot_h: f32) -> f32 {
    use std::f32::consts::PI;
    let m2 = surface.roughness * surface.roughness;
    let cos2 = n_dot_h * n_dot_h;
    match surface.distribution {
        crate::scene::MicrofacetDistribution::Beckmann => {
            if cos2 <= 0.0 {
                return 0.0;
            }
            power::exp((cos2 - 1.0) / (m2 * cos2)) / (PI * m2 * cos2 * cos2)
        }
        crate::scene::MicrofacetDistribution::Ggx => {
            let d = cos2 * (m2 - 1.0) + 1.0;
            m2 / (PI * d * d)
        }
    }
}

/// `R = 2(N·L)N − L`: the direction `to_light` mirrors into about `normal` (seed 000).
pub fn reflect(to_light: Vec3, normal: Vec3) -> Vec3 {
    2.0 * normal.dot(to_light) * normal - to_light
}

/// `max(cosine, 0)^shininess`, with `0^0 = 1`. A whole exponent up to
/// [`MAX_SQUARED_EXPONENT`] (the usual 5, 20, 32, 128) is raised by squaring; other exponents
/// (the OpenGL table's 76.8, glTF's `2/α⁴ − 2`) by [`power::pow`], `2^(n·log₂ x)` as a fixed
/// sequence of float operations. The eight-lane lighting repeats both lane-wise with the same
/// bits. Squaring rounds once per multiplication, so its relative error stays below `n·2⁻²⁴`
/// (6·10⁻⁵ at 1024); `pow`'s absolute error stays below 2·10⁻⁷: both far below one level of an
/// 8-bit image.
pub fn specular_power(cosine: f32, shininess: f32) -> f32 {
    let base = cosine.max(0.0);
    match whole_exponent(shininess) {
        Some(exponent) => power_by_squaring(base, 1.0, exponent),
        None => power::pow(base, shininess),
    }
}

/// The largest exponent [`specular_power`] raises by squaring.
pub const MAX_SQUARED_EXPONENT: u32 = 1024;

/// `shininess` as a whole number, when it is one from 0 to [`MAX_SQUARED_EXPONENT`].
/// Whole when truncating it changes nothing: in that range the conversions are exact, and
/// they are two instructions, where `f32::fract` is a call into libm on x86-64 without
/// SSE4.1 (the lane lighting asks once per light and group of eight pixels).
#[inline]
pub fn whole_exponent(shininess: f32) -> Option<u32> {
    if !(0.0..=MAX_SQUARED_EXPONENT as f32).contains(&shininess) {
        return None;
    }
    let whole = shininess as u32;
    (whole as f32 == shininess).then_some(whole)
}

/// `base^exponent` by binary exponentiation, `one` being the multiplicative identity: for an
/// `f32`, or lane-wise for the eight-lane lighting (`FastLighting`), with the same
/// multiplications in the same order, so the same bits per lane.
#[inline]
pub fn power_by_squaring<T: Copy + std::ops::Mul<Output = T>>(base: T, one: T, exponent: u32) -> T {
    let (mut result, mut square, mut rest) = (one, base, exponent);
    while rest > 0 {
        if rest & 1 == 1 {
            result = result * square;
        }
        rest >>= 1;
        if rest > 0 {
            square = square * square;
        }
    }
    result
}

/// The unit direction towards `light` from `position` and the light's strength there
/// (spot factor × attenuation), or `None` when the light has no direction at that point. The
/// fast lighting's one-point form calls it too; its lanes repeat it operation for operation.
pub fn incidence(light: &ShadingLight, position: Vec3) -> Option<(Vec3, f32)> {
    incidence_factors(light, position).map(|incidence| (incidence.to_light, incidence.strength()))
}

/// How a light arrives at a point: its direction, and its strength's two factors.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Incidence {
    /// Unit vector towards the light.
    pub to_light: Vec3,
    /// The spot cone's factor: 1 for directional and point lights, 0 outside a spot's cone.
    pub spot: f32,
    /// `1 / (c + l·d + q·d²)`; 1 for directional lights.
    pub attenuation: f32,
}

impl Incidence {
    /// `spot × attenuation` (exactly the attenuation for a point light, `1·a = a`).
    #[inline]
    pub fn strength(&self) -> f32 {
        self.spot * self.attenuation
    }
}

/// [`incidence`] with its factors apart, for the lighting's breakdown per light.
#[inline]
pub fn incidence_factors(light: &ShadingLight, position: Vec3) -> Option<Incidence> {
    match light.kind {
        ShadingLightKind::Directional { to_light } => Some(Incidence {
            to_light,
            spot: 1.0,
            attenuation: 1.0,
        }),
        ShadingLightKind::Point {
            position: light_position,
            attenuation,
        } => {
            let (to_light, distance) = direction_and_distance(light_position - position)?;
            Some(Incidence {
                to_light,
                spot: 1.0,
                attenuation: attenuate(attenuation, distance),
            })
        }
        ShadingLightKind::Spot {
            position: light_position,
            axis,
            cos_cutoff,
            exponent,
            attenuation,
        } => {
            let (to_light, distance) = direction_and_distance(light_position - position)?;
            let cos_angle = -to_light.dot(axis);
            let spot = if cos_angle < cos_cutoff {
                0.0
            } else {
                specular_power(cos_angle, exponent)
            };
            Some(Incidence {
                to_light,
                spot,
                attenuation: attenuate(attenuation, distance),
            })
        }
    }
}

fn direction_and_distance(offset: Vec3) -> Option<(Vec3, f32)> {
    let distance = offset.length();
    (distance > 0.0 && distance.is_finite()).then(|| (offset / distance, distance))
}

/// `1 / (c + l·d + q·d²)`.
pub fn attenuate(attenuation: Attenuation, distance: f32) -> f32 {
    let Attenuation {
        constant,
        linear,
        quadratic,
    } = attenuation;
    let denominator = constant + distance * (linear + distance * quadratic);
    1.0 / denominator.max(MIN_ATTENUATION_DENOMINATOR)
}

#[cfg(test)]
mod tests {
    use super::*;

    const WHITE: Vec3 = Vec3::ONE;

    fn material(model: LightingModel) -> Material {
        Material {
            ambient: Vec3::new(0.1, 0.0, 0.0),
            diffuse: Vec3::new(0.0, 0.6, 0.0),
            specular: Vec3::new(0.0, 0.0, 0.7),
            shininess: 5.0,
            emission: Vec3::ZERO,
            model,
            textures: Default::default(),
        }
    }

    fn directional(to_light: Vec3) -> ShadingLight {
        ShadingLight {
            color: WHITE,
            kind: ShadingLightKind::Directional {
                to_light: to_light.normalize(),
            },
        }
    }

    fn check(got: Vec3, expected: Vec3) {
        assert!(
            (got - expected).abs().max_element() < 1e-5,
            "got {got:?}, expected {expected:?}"
        );
    }

    /// A surface facing +Z seen from straight above, lit from 45° in the XZ plane.
    /// N·L = cos 45°; R = (−sin 45°, 0, cos 45°), so R·V = cos 45°; H is halfway between
    /// L and V: N·H = cos 22.5°.
    #[test]
    fn phong_and_blinn_phong_by_hand() {
        let n = Vec3::Z;
        let v = Vec3::Z;
        let light = directional(Vec3::new(1.0, 0.0, 1.0));
        let c45 = std::f32::consts::FRAC_1_SQRT_2;
        let phong = illuminate(
            &material(LightingModel::Phong),
            &[light],
            Vec3::splat(0.5),
            Vec3::ZERO,
            n,
            v,
        );
        check(phong.ambient, Vec3::new(0.05, 0.0, 0.0));
        check(phong.diffuse, Vec3::new(0.0, 0.6 * c45, 0.0));
        check(phong.specular, Vec3::new(0.0, 0.0, 0.7 * c45.powf(5.0)));
        let blinn = illuminate(
            &material(LightingModel::BlinnPhong),
            &[light],
            Vec3::ZERO,
            Vec3::ZERO,
            n,
            v,
        );
        let c22 = (std::f32::consts::PI / 8.0).cos();
        check(blinn.specular, Vec3::new(0.0, 0.0, 0.7 * c22.powf(5.0)));
        check(blinn.total(), blinn.diffuse + blinn.specular);
    }

    #[test]
    fn several_lights_add_up() {
        let lights = [directional(Vec3::Z), directional(Vec3::new(0.0, 1.0, 1.0))];
        let terms = illuminate(
            &material(LightingModel::Lambert),
            &lights,
            Vec3::ZERO,
            Vec3::ZERO,
            Vec3::Z,
            Vec3::Z,
        );
        check(
            terms.diffuse,
            Vec3::new(0.0, 0.6 * (1.0 + std::f32::consts::FRAC_1_SQRT_2), 0.0),
        );
        assert_eq!(terms.specular, Vec3::ZERO);
    }

    #[test]
    fn no_specular_where_the_light_is_behind_the_surface() {
        // The viewer sits on the reflection of a light below the horizon: R·V would be 1.
        let light = directional(Vec3::new(0.0, 0.0, -1.0));
        let terms = illuminate(
            &material(LightingModel::Phong),
            &[light],
            Vec3::ZERO,
            Vec3::ZERO,
            Vec3::Z,
            -Vec3::Z,
        );
        assert_eq!(terms.diffuse + terms.specular, Vec3::ZERO);
    }

    #[test]
    fn point_light_attenuation_and_spot_cone() {
        let attenuation = Attenuation {
            constant: 1.0,
            linear: 0.5,
            quadratic: 0.25,
        };
        let point = ShadingLight {
            color: WHITE,
            kind: ShadingLightKind::Point {
                position: Vec3::new(0.0, 0.0, 2.0),
                attenuation,
            },
        };
        let lambert = material(LightingModel::Lambert);
        let terms = illuminate(&lambert, &[point], Vec3::ZERO, Vec3::ZERO, Vec3::Z, Vec3::Z);
        // d = 2: 1 / (1 + 1 + 1) = 1/3.
        check(terms.diffuse, Vec3::new(0.0, 0.6 / 3.0, 0.0));

        let spot = |cutoff_degrees: f32, exponent: f32| ShadingLight {
            color: WHITE,
            kind: ShadingLightKind::Spot {
                position: Vec3::new(0.0, 0.0, 1.0),
                axis: Vec3::new(0.0, 0.0, -1.0),
                cos_cutoff: cutoff_degrees.to_radians().cos(),
                exponent,
                attenuation: Attenuation::NONE,
            },
        };
        // A point 1 unit off-axis, 1 unit below: 45° from the spot's axis, N·L = cos 45°.
        let off_axis = Vec3::new(1.0, 0.0, 0.0);
        let c45 = std::f32::consts::FRAC_1_SQRT_2;
        let inside = illuminate(
            &lambert,
            &[spot(50.0, 2.0)],
            Vec3::ZERO,
            off_axis,
            Vec3::Z,
            Vec3::Z,
        );
        check(inside.diffuse, Vec3::new(0.0, 0.6 * c45 * c45 * c45, 0.0));
        let outside = illuminate(
            &lambert,
            &[spot(40.0, 2.0)],
            Vec3::ZERO,
            off_axis,
            Vec3::Z,
            Vec3::Z,
        );
        assert_eq!(outside.diffuse, Vec3::ZERO);
        let on_axis_zero_cutoff = illuminate(
            &lambert,
            &[spot(0.0, 1.0)],
            Vec3::ZERO,
            Vec3::ZERO,
            Vec3::Z,
            Vec3::Z,
        );
        check(on_axis_zero_cutoff.diffuse, Vec3::new(0.0, 0.6, 0.0));
    }

    #[test]
    fn degenerate_inputs_are_finite() {
        let light_here = ShadingLight {
            color: WHITE,
            kind: ShadingLightKind::Point {
                position: Vec3::ZERO,
                attenuation: Attenuation {
                    constant: 0.0,
                    linear: 0.0,
                    quadratic: 1.0,
                },
            },
        };
        let opposite = directional(-Vec3::Z);
        let lights = [light_here, opposite, directional(Vec3::Z)];
        for model in [LightingModel::Phong, LightingModel::BlinnPhong] {
            for shininess in [0.0, 1.0, 1e4, 1e6] {
                for normal in [Vec3::ZERO, Vec3::Z] {
                    let m = Material {
                        shininess,
                        ..material(model)
                    };
                    // Viewer exactly opposite to the last light: L + V = 0 for the Blinn half vector.
                    let terms = illuminate(&m, &lights, Vec3::ONE, Vec3::ZERO, normal, -Vec3::Z);
                    assert!(
                        terms.total().is_finite(),
                        "{model:?} n={shininess} N={normal}: {terms:?}"
                    );
                }
            }
        }
        assert_eq!(specular_power(0.0, 0.0), 1.0);
        assert_eq!(specular_power(f32::NAN, 5.0), 0.0);
        assert!(
            attenuate(
                Attenuation {
                    constant: 0.0,
                    linear: 0.0,
                    quadratic: 1.0
                },
                0.0
            )
            .is_finite()
        );
    }

    #[test]
    fn unlit_is_diffuse_plus_emission() {
        let m = Material {
            emission: Vec3::splat(0.1),
            ..material(LightingModel::Unlit)
        };
        let terms = illuminate(
            &m,
            &[directional(Vec3::Z)],
            Vec3::ONE,
            Vec3::ZERO,
            Vec3::Z,
            Vec3::Z,
        );
        check(terms.total(), Vec3::new(0.1, 0.7, 0.1));
    }

    #[test]
    fn whole_exponents_are_squared_and_others_raised_within_their_stated_errors() {
        assert_eq!(whole_exponent(20.0), Some(20));
        assert_eq!(whole_exponent(0.0), Some(0));
        assert_eq!(whole_exponent(76.8), None);
        assert_eq!(whole_exponent(2048.0), None);
        assert_eq!(whole_exponent(f32::NAN), None);
        assert_eq!(whole_exponent(-2.0), None);
        assert_eq!(whole_exponent(-0.0), Some(0));
        assert_eq!(whole_exponent(1024.0), Some(MAX_SQUARED_EXPONENT));
        assert_eq!(whole_exponent(1023.5), None);
        assert_eq!(whole_exponent(0.5), None);
        assert_eq!(whole_exponent(f32::INFINITY), None);
        // Eighths over the range and a little beyond, and each whole number's neighbours,
        // against the definition.
        for eighths in -16..=1100 * 8 {
            let near = eighths as f32 / 8.0;
            for shininess in [near.next_down(), near, near.next_up()] {
                let expected = ((0.0..=1024.0).contains(&shininess) && shininess.fract() == 0.0)
                    .then_some(shininess as u32);
                assert_eq!(whole_exponent(shininess), expected, "{shininess}");
            }
        }
        for exponent in [0, 1, 2, 5, 17, 20, 128, 1000, MAX_SQUARED_EXPONENT] {
            for i in 0..=1000 {
                let base = i as f32 / 1000.0;
                let squared = power_by_squaring(base, 1.0, exponent);
                let exact = f64::from(base).powi(exponent as i32);
                let bound = exact * f64::from(exponent.max(1)) * f64::from(f32::EPSILON) + 1e-38;
                assert!(
                    (f64::from(squared) - exact).abs() <= bound,
                    "{base}^{exponent}: {squared} against {exact}"
                );
                assert_eq!(specular_power(base, exponent as f32), squared);
            }
        }
        // Other exponents go through `power::pow`, within its stated error; negative cosines
        // count as 0.
        for shininess in [0.5f32, 76.8, 1024.5, 3000.0] {
            for i in 1..=1000 {
                let base = i as f32 / 1000.0;
                let got = specular_power(base, shininess);
                assert_eq!(got, power::pow(base, shininess));
                let exact = f64::from(base).powf(f64::from(shininess));
                assert!(
                    (f64::from(got) - exact).abs() <= power::POW_ABSOLUTE_ERROR,
                    "{base}^{shininess}"
                );
            }
            assert_eq!(specular_power(-0.5, shininess), 0.0);
        }
    }
}

#[cfg(test)]
mod cook_torrance_tests {
    use super::*;
    use crate::scene::{Microfacet, MicrofacetDistribution};

    fn surface(roughness: f32, distribution: MicrofacetDistribution) -> Microfacet {
        Microfacet {
            roughness,
            fresnel: Vec3::splat(0.04),
            distribution,
        }
    }

    fn check(got: f32, expected: f32) {
        assert!(
            (got - expected).abs() < 1e-5 * expected.abs().max(1.0),
            "got {got}, expected {expected}"
        );
    }

    /// N = L = V: H = N, F = F0, G = 1, D = 1/(π m²) for both distributions, so the specular
    /// factor is F0·π·D/4 = F0/(4m²): with m = 0.5 exactly F0.
    #[test]
    fn normal_incidence_by_hand() {
        for distribution in [MicrofacetDistribution::Beckmann, MicrofacetDistribution::Ggx] {
            let r = cook_torrance(&surface(0.5, distribution), Vec3::Z, Vec3::Z, Vec3::Z);
            check(r.fresnel.x, 0.04);
            check(r.specular.x, 0.04);
            check(
                microfacet_distribution(&surface(0.5, distribution), 1.0),
                1.0 / (std::f32::consts::PI * 0.25),
            );
        }
    }

    /// L and V 30° either side of N: H = N still, V·H = cos 30°.
    /// F = 0.04 + 0.96(1 − cos 30°)^5, G = 1, spec = F·π·D/(4 cos² 30°) with π·D = 1/m² = 4.
    #[test]
    fn symmetric_reflection_by_hand() {
        let (s, c) = (30f32.to_radians().sin(), 30f32.to_radians().cos());
        let (l, v) = (Vec3::new(s, 0.0, c), Vec3::new(-s, 0.0, c));
        let r = cook_torrance(&surface(0.5, MicrofacetDistribution::Beckmann), Vec3::Z, l, v);
        let fresnel = 0.04 + 0.96 * (1.0 - c).powi(5);
        check(r.fresnel.x, fresnel);
        check(r.specular.x, fresnel * 4.0 / (4.0 * c * c));
    }

    /// Off the peak, Beckmann by hand: N·H = cos 20° gives D = exp(−tan² 20°/m²)/(π m² cos⁴ 20°).
    #[test]
    fn beckmann_off_peak_by_hand() {
        let m = 0.3f32;
        let cos = 20f32.to_radians().cos();
        let tan2 = 20f32.to_radians().tan().powi(2);
        let expected = (-tan2 / (m * m)).exp() / (std::f32::consts::PI * m * m * cos.powi(4));
        check(
            microfacet_distribution(&surface(m, MicrofacetDistribution::Beckmann), cos),
            expected,
        );
    }

    #[test]
    fn grazing_angles_stay_finite() {
        for distribution in [MicrofacetDistribution::Beckmann, MicrofacetDistribution::Ggx] {
            for roughness in [1e-3, 0.05, 0.5, 1.0] {
                for grazing in [0.0, 1e-7, 1e-4, 1e-2] {
                    let tilted = Vec3::new((1.0f32 - grazing * grazing).sqrt(), 0.0, grazing);
                    let opposite = Vec3::new(-tilted.x, 0.0, tilted.z);
                    for (l, v) in [
                        (tilted, Vec3::Z),
                        (Vec3::Z, tilted),
                        (tilted, opposite),
                        (tilted, tilted),
                    ] {
                        let r = cook_torrance(&surface(roughness, distribution), Vec3::Z, l, v);
                        assert!(
                            r.specular.is_finite() && r.fresnel.is_finite(),
                            "{distribution:?} m={roughness} {l} {v}: {r:?}"
                        );
                        assert!(r.specular.min_element() >= 0.0);
                    }
                }
            }
        }
    }

    #[test]
    fn energy_not_reflected_specularly_is_left_for_diffuse() {
        let material = Material {
            ambient: Vec3::ZERO,
            diffuse: Vec3::ONE,
            specular: Vec3::ZERO,
            shininess: 1.0,
            emission: Vec3::ZERO,
            model: LightingModel::CookTorrance(surface(0.5, MicrofacetDistribution::Beckmann)),
            textures: Default::default(),
        };
        let light = ShadingLight {
            color: Vec3::ONE,
            kind: ShadingLightKind::Directional { to_light: Vec3::Z },
        };
        let terms = illuminate(&material, &[light], Vec3::ZERO, Vec3::ZERO, Vec3::Z, Vec3::Z);
        check(terms.diffuse.x, 1.0 - 0.04);
        check(terms.specular.x, 0.04);
    }
}
