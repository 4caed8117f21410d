//! The lighting equation of [`crate::lighting`], evaluated in `f64` for the reference renderer.
//!
//! This is a line-by-line transcription of `lighting::illuminate_with_visibility` (the shadow
//! term a callback here too, which the reference answers with shadow rays), kept apart instead
//! of making `lighting` generic over the scalar: the renderer's `f32` code is the hot loop the
//! lead is rewriting for speed, and a generic layer (glam has no vector type generic over the
//! scalar) would sit in its way. The two are kept equal by the
//! cross-check test at the bottom of this file, which evaluates both on thousands of random
//! points, lights and materials of every model and light type and compares them. A change to
//! the equation in one place fails that test until the other follows.
//!
//! Material coefficients stay `f32` (they come from the scene as `f32`); everything computed
//! from them (vectors, dot products, powers, attenuation) is `f64`.

use glam::{DVec3, Vec3};

use crate::lighting::{MIN_ATTENUATION_DENOMINATOR, ShadingLight, ShadingLightKind};
use crate::scene::{Attenuation, Light, LightingModel, Material, Microfacet, MicrofacetDistribution};

/// A light prepared for exact shading: eye-relative position, unit directions, in `f64`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExactLight {
    pub color: DVec3,
    pub kind: ExactLightKind,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ExactLightKind {
    Directional {
        to_light: DVec3,
    },
    Point {
        position: DVec3,
        attenuation: Attenuation,
    },
    Spot {
        position: DVec3,
        axis: DVec3,
        cos_cutoff: f64,
        exponent: f64,
        attenuation: Attenuation,
    },
}

impl ExactLight {
    /// The scene light `light` relative to the eye at `eye` (as the renderer's shading space,
    /// but the subtraction is done in `f64` and kept in `f64`).
    pub fn new(light: &Light, eye: DVec3) -> Self {
        match *light {
            Light::Directional { direction, color, .. } => ExactLight {
                color: color.as_dvec3(),
                kind: ExactLightKind::Directional {
                    to_light: -direction.as_dvec3().normalize_or_zero(),
                },
            },
            Light::Point {
                position,
                color,
                attenuation,
                ..
            } => ExactLight {
                color: color.as_dvec3(),
                kind: ExactLightKind::Point {
                    position: position - eye,
                    attenuation,
                },
            },
            Light::Spot {
                position,
                direction,
                color,
                cutoff_degrees,
                exponent,
                attenuation,
                ..
            } => ExactLight {
                color: color.as_dvec3(),
                kind: ExactLightKind::Spot {
                    position: position - eye,
                    axis: direction.as_dvec3().normalize_or_zero(),
                    cos_cutoff: f64::from(cutoff_degrees).to_radians().cos(),
                    exponent: f64::from(exponent),
                    attenuation,
                },
            },
        }
    }

    /// The same light rounded to the renderer's `f32` form (to measure `f32` lighting).
    pub fn to_f32(&self) -> ShadingLight {
        ShadingLight {
            color: self.color.as_vec3(),
            kind: match self.kind {
                ExactLightKind::Directional { to_light } => ShadingLightKind::Directional {
                    to_light: to_light.as_vec3(),
                },
                ExactLightKind::Point {
                    position,
                    attenuation,
                } => ShadingLightKind::Point {
                    position: position.as_vec3(),
                    attenuation,
                },
                ExactLightKind::Spot {
                    position,
                    axis,
                    cos_cutoff,
                    exponent,
                    attenuation,
                } => ShadingLightKind::Spot {
                    position: position.as_vec3(),
                    axis: axis.as_vec3(),
                    cos_cutoff: cos_cutoff as f32,
                    exponent: exponent as f32,
                    attenuation,
                },
            },
        }
    }
}

/// The terms of the lighting equation at one point, in `f64`.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ExactTerms {
    pub emission: DVec3,
    pub ambient: DVec3,
    pub diffuse: DVec3,
    pub specular: DVec3,
}

fn wide(v: Vec3) -> DVec3 {
    v.as_dvec3()
}

/// `lighting::illuminate` in `f64`; same arguments, same degenerate-input rules.
pub fn illuminate_exact(
    material: &Material,
    lights: &[ExactLight],
    ambient_light: DVec3,
    position: DVec3,
    normal: DVec3,
    to_viewer: DVec3,
) -> ExactTerms {
    illuminate_exact_with_visibility(
        material,
        lights,
        ambient_light,
        position,
        normal,
        to_viewer,
        |_, _| 1.0,
    )
}

/// `lighting::illuminate_with_visibility` in `f64`: `visibility(i, L)` is the share of light
/// `i` that reaches the point, asked only for lights that face the surface (the reference
/// answers it with a shadow ray).
pub fn illuminate_exact_with_visibility(
    material: &Material,
    lights: &[ExactLight],
    ambient_light: DVec3,
    position: DVec3,
    normal: DVec3,
    to_viewer: DVec3,
    visibility: impl Fn(usize, DVec3) -> f64,
) -> ExactTerms {
    let mut terms = ExactTerms {
        emission: wide(material.emission),
        ..ExactTerms::default()
    };
    if material.model == LightingModel::Unlit {
        terms.diffuse = wide(material.diffuse);
        return terms;
    }
    terms.ambient = wide(material.ambient) * ambient_light;
    let has_specular = material.specular != Vec3::ZERO;
    let shininess = f64::from(material.shininess);
    for (index, light) in lights.iter().enumerate() {
        let Some((to_light, strength)) = incidence(light, position) else {
            continue;
        };
        let n_dot_l = normal.dot(to_light);
        if n_dot_l <= 0.0 || strength <= 0.0 {
            continue;
        }
        let strength = strength * visibility(index, to_light);
        if strength <= 0.0 {
            continue;
        }
        let irradiance = light.color * strength * n_dot_l;
        match material.model {
            LightingModel::Unlit => {}
            LightingModel::Lambert => terms.diffuse += wide(material.diffuse) * irradiance,
            LightingModel::Phong | LightingModel::BlinnPhong => {
                terms.diffuse += wide(material.diffuse) * irradiance;
                if has_specular {
                    let cosine = if material.model == LightingModel::BlinnPhong {
                        normal.dot((to_light + to_viewer).normalize_or_zero())
                    } else {
                        (2.0 * normal.dot(to_light) * normal - to_light).dot(to_viewer)
                    };
                    let intensity = light.color * strength;
                    terms.specular += wide(material.specular) * intensity * specular_power(cosine, shininess);
                }
            }
            LightingModel::CookTorrance(surface) => {
                let (fresnel, specular) = cook_torrance(&surface, normal, to_light, to_viewer);
                terms.diffuse += wide(material.diffuse) * (DVec3::ONE - fresnel) * irradiance;
                terms.specular += specular * irradiance;
            }
        }
    }
    terms
}

/// `lighting::cook_torrance` in `f64`: (Fresnel F, the specular factor).
fn cook_torrance(surface: &Microfacet, normal: DVec3, to_light: DVec3, to_viewer: DVec3) -> (DVec3, DVec3) {
    let f0 = wide(surface.fresnel);
    let half = (to_light + to_viewer).normalize_or_zero();
    let v_dot_h = to_viewer.dot(half).max(0.0);
    let fresnel = f0 + (DVec3::ONE - f0) * (1.0 - v_dot_h).powi(5);
    let n_dot_v = normal.dot(to_viewer);
    let n_dot_l = normal.dot(to_light);
    let n_dot_h = normal.dot(half);
    if n_dot_v <= 0.0 || n_dot_l <= 0.0 || n_dot_h <= 0.0 || v_dot_h <= 0.0 {
        return (fresnel, DVec3::ZERO);
    }
    let distribution = microfacet_distribution(surface, n_dot_h);
    let g_over_nv_nl = (1.0 / (n_dot_v * n_dot_l))
        .min(2.0 * n_dot_h / (v_dot_h * n_dot_l))
        .min(2.0 * n_dot_h / (v_dot_h * n_dot_v));
    let specular = fresnel * (std::f64::consts::PI * distribution * g_over_nv_nl / 4.0);
    (fresnel, specular)
}

fn microfacet_distribution(surface: &Microfacet, n_dot_h: f64) -> f64 {
    use std::f64::consts::PI;
    let roughness = f64::from(surface.roughness);
    let m2 = roughness * roughness;
    let cos2 = n_dot_h * n_dot_h;
    match surface.distribution {
        MicrofacetDistribution::Beckmann => {
            if cos2 <= 0.0 {
                return 0.0;
            }
            ((cos2 - 1.0) / (m2 * cos2)).exp() / (PI * m2 * cos2 * cos2)
        }
        MicrofacetDistribution::Ggx => {
            let d = cos2 * (m2 - 1.0) + 1.0;
            m2 / (PI * d * d)
        }
    }
}

/// `max(cosine, 0)^shininess`, with `0^0 = 1`.
fn specular_power(cosine: f64, shininess: f64) -> f64 {
    cosine.max(0.0).powf(shininess)
}

fn incidence(light: &ExactLight, position: DVec3) -> Option<(DVec3, f64)> {
    match light.kind {
        ExactLightKind::Directional { to_light } => Some((to_light, 1.0)),
        ExactLightKind::Point {
            position: light_position,
            attenuation,
        } => {
            let (to_light, distance) = direction_and_distance(light_position - position)?;
            Some((to_light, attenuate(attenuation, distance)))
        }
        ExactLightKind::Spot {
            position: light_position,
            axis,
            cos_cutoff,
            exponent,
            attenuation,
        } => {
            let (to_light, distance) = direction_and_distance(light_position - position)?;
            let cos_angle = -to_light.dot(axis);
            if cos_angle < cos_cutoff {
                return Some((to_light, 0.0));
            }
            Some((
                to_light,
                specular_power(cos_angle, exponent) * attenuate(attenuation, distance),
            ))
        }
    }
}

fn direction_and_distance(offset: DVec3) -> Option<(DVec3, f64)> {
    let distance = offset.length();
    (distance > 0.0 && distance.is_finite()).then(|| (offset / distance, distance))
}

fn attenuate(attenuation: Attenuation, distance: f64) -> f64 {
    let denominator = f64::from(attenuation.constant)
        + distance * (f64::from(attenuation.linear) + distance * f64::from(attenuation.quadratic));
    1.0 / denominator.max(f64::from(MIN_ATTENUATION_DENOMINATOR))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lighting::{ShadingLightKind, illuminate};
    use crate::scene::MaterialTextures;

    /// Uniform values from a fixed xorshift sequence, so the cross-check is the same on every run.
    struct Random(crate::test_support::XorShift64);

    impl Random {
        fn next(&mut self) -> f64 {
            (self.0.next_u64() >> 11) as f64 / (1u64 << 53) as f64
        }
        fn range(&mut self, lo: f64, hi: f64) -> f64 {
            lo + (hi - lo) * self.next()
        }
        fn unit(&mut self) -> DVec3 {
            loop {
                let v = DVec3::new(
                    self.range(-1.0, 1.0),
                    self.range(-1.0, 1.0),
                    self.range(-1.0, 1.0),
                );
                if v.length() > 0.1 && v.length() < 1.0 {
                    return v.normalize();
                }
            }
        }
        fn color(&mut self) -> Vec3 {
            Vec3::new(self.next() as f32, self.next() as f32, self.next() as f32)
        }
    }

    /// The `f64` transcription agrees with `lighting::illuminate` on random inputs of every
    /// model and light type. Points where a gate (N·L > 0, the spot cone, R·V > 0) is within
    /// rounding of switching are skipped: there the two may legitimately take different sides.
    /// The tolerance, 10⁻³ relative, is what `f32` rounding reaches where Cook-Torrance's
    /// `1/((N·V)(N·L))` amplifies it near grazing angles; a different equation (a missing factor,
    /// another exponent, a swapped vector) misses it by orders of magnitude.
    #[test]
    fn agrees_with_the_f32_lighting_everywhere_but_at_gates() {
        let mut random = Random(crate::test_support::XorShift64::new(0x9e37_79b9_7f4a_7c15));
        let mut compared = 0;
        for case in 0..20_000 {
            let model = match case % 6 {
                0 => LightingModel::Phong,
                1 => LightingModel::BlinnPhong,
                2 => LightingModel::Lambert,
                3 => LightingModel::Unlit,
                4 => LightingModel::CookTorrance(Microfacet {
                    roughness: random.range(0.05, 1.0) as f32,
                    fresnel: random.color(),
                    distribution: MicrofacetDistribution::Beckmann,
                }),
                _ => LightingModel::CookTorrance(Microfacet {
                    roughness: random.range(0.05, 1.0) as f32,
                    fresnel: random.color(),
                    distribution: MicrofacetDistribution::Ggx,
                }),
            };
            let material = Material {
                ambient: random.color(),
                diffuse: random.color(),
                specular: random.color(),
                shininess: random.range(0.0, 200.0) as f32,
                emission: random.color() * 0.1,
                model,
                textures: MaterialTextures::default(),
            };
            let attenuation = Attenuation {
                constant: random.range(0.0, 1.0) as f32,
                linear: random.range(0.0, 0.5) as f32,
                quadratic: random.range(0.0, 0.2) as f32 + 0.01,
            };
            let position = random.unit() * random.range(0.5, 3.0);
            let light = match case % 3 {
                0 => ExactLightKind::Directional {
                    to_light: random.unit(),
                },
                1 => ExactLightKind::Point {
                    position: random.unit() * 4.0,
                    attenuation,
                },
                _ => ExactLightKind::Spot {
                    position: random.unit() * 4.0,
                    axis: random.unit(),
                    cos_cutoff: random.range(0.0, 90.0).to_radians().cos(),
                    exponent: random.range(0.0, 20.0),
                    attenuation,
                },
            };
            let exact_light = ExactLight {
                color: DVec3::new(
                    random.range(0.0, 2.0),
                    random.range(0.0, 2.0),
                    random.range(0.0, 2.0),
                ),
                kind: light,
            };
            // Round the inputs to f32 first, so both evaluate the same point.
            let (normal, to_viewer) = (random.unit().as_vec3(), random.unit().as_vec3());
            let ambient = random.color();
            let light32 = exact_light.to_f32();
            let exact_light = ExactLight {
                color: light32.color.as_dvec3(),
                kind: f64_kind(light32.kind),
            };
            let near_gate = {
                let (to_light, _) =
                    incidence(&exact_light, position.as_vec3().as_dvec3()).unwrap_or((DVec3::ZERO, 0.0));
                let n_dot_l = normal.as_dvec3().dot(to_light);
                let reflected = 2.0 * n_dot_l * normal.as_dvec3() - to_light;
                let cone = match exact_light.kind {
                    ExactLightKind::Spot { axis, cos_cutoff, .. } => -to_light.dot(axis) - cos_cutoff,
                    _ => 1.0,
                };
                n_dot_l.abs() < 1e-3 || cone.abs() < 1e-3 || reflected.dot(to_viewer.as_dvec3()).abs() < 1e-3
            };
            if near_gate {
                continue;
            }
            let fast = illuminate(
                &material,
                &[light32],
                ambient,
                position.as_vec3(),
                normal,
                to_viewer,
            );
            let exact = illuminate_exact(
                &material,
                &[exact_light],
                ambient.as_dvec3(),
                position.as_vec3().as_dvec3(),
                normal.as_dvec3(),
                to_viewer.as_dvec3(),
            );
            for (name, a, b) in [
                ("emission", fast.emission, exact.emission),
                ("ambient", fast.ambient, exact.ambient),
                ("diffuse", fast.diffuse, exact.diffuse),
                ("specular", fast.specular, exact.specular),
            ] {
                let difference = (a.as_dvec3() - b).abs().max_element();
                assert!(
                    difference <= 1e-3 * b.abs().max_element().max(1.0),
                    "case {case}, {name}: f32 {a} against f64 {b} ({model:?}, {exact_light:?})"
                );
            }
            compared += 1;
        }
        assert!(
            compared > 15_000,
            "only {compared} cases were away from the gates"
        );
    }

    fn f64_kind(kind: ShadingLightKind) -> ExactLightKind {
        match kind {
            ShadingLightKind::Directional { to_light } => ExactLightKind::Directional {
                to_light: to_light.as_dvec3(),
            },
            ShadingLightKind::Point {
                position,
                attenuation,
            } => ExactLightKind::Point {
                position: position.as_dvec3(),
                attenuation,
            },
            ShadingLightKind::Spot {
                position,
                axis,
                cos_cutoff,
                exponent,
                attenuation,
            } => ExactLightKind::Spot {
                position: position.as_dvec3(),
                axis: axis.as_dvec3(),
                cos_cutoff: f64::from(cos_cutoff),
                exponent: f64::from(exponent),
                attenuation,
            },
        }
    }

    /// The degenerate inputs of `lighting`'s module documentation give the same defined,
    /// finite results in `f64`.
    #[test]
    fn degenerate_inputs_are_finite() {
        let material = |shininess: f32, model| Material {
            ambient: Vec3::splat(0.1),
            diffuse: Vec3::splat(0.6),
            specular: Vec3::splat(0.7),
            shininess,
            emission: Vec3::ZERO,
            model,
            textures: MaterialTextures::default(),
        };
        let light_here = ExactLight {
            color: DVec3::ONE,
            kind: ExactLightKind::Point {
                position: DVec3::ZERO,
                attenuation: Attenuation {
                    constant: 0.0,
                    linear: 0.0,
                    quadratic: 1.0,
                },
            },
        };
        let opposite = ExactLight {
            color: DVec3::ONE,
            kind: ExactLightKind::Directional { to_light: DVec3::Z },
        };
        for model in [LightingModel::Phong, LightingModel::BlinnPhong] {
            for shininess in [0.0, 1.0, 1e4, 1e6] {
                for normal in [DVec3::ZERO, DVec3::Z] {
                    let terms = illuminate_exact(
                        &material(shininess, model),
                        &[light_here, opposite],
                        DVec3::ONE,
                        DVec3::ZERO,
                        normal,
                        -DVec3::Z,
                    );
                    let total = terms.emission + terms.ambient + terms.diffuse + terms.specular;
                    assert!(total.is_finite(), "{model:?} {shininess} {normal}: {terms:?}");
                }
            }
        }
    }
}
