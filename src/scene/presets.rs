//! Built-in materials, usable by name in any scene without a definition.
//!
//! Two families, from the seed documents:
//! - the OpenGL material table of seed 000 (`emerald` … `chrome`): explicit ambient, diffuse and
//!   specular RGB coefficients. The seed's table gives four rows per material: R, G, B and a
//!   fourth row that is the material's alpha (we render opaque surfaces, so it is not used). The
//!   shininess is not in the seed's table; it comes from the standard OpenGL/VRML table the seed's
//!   values are taken from, where it is a fraction of 128 (emerald 0.6 → 76.8).
//! - the MATLAB presets of seed 002's demo (`shiny`, `metal`, `diffuse` alias `dull`, `ambient`):
//!   a surface `color` with scalar strengths `ka`, `kd`, `ks`, an exponent, and a specular colour
//!   reflectance `scr`. These are the seed's own values, which differ from MATLAB's built-in
//!   `material shiny` etc.
//!
//! A [`MaterialRecipe`] keeps both styles until the last moment so that `base: "shiny"` plus a
//! `color` works the way MATLAB's `material shiny` works on a coloured surface.

use glam::Vec3;

use crate::scene::{LightingModel, Material, MaterialTextures, Microfacet, MicrofacetDistribution};

/// A material before its coefficients are computed: MATLAB-style colour and strengths, and
/// OpenGL-style explicit coefficients that take precedence where present.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MaterialRecipe {
    pub color: Vec3,
    pub ka: f32,
    pub kd: f32,
    pub ks: f32,
    /// MATLAB's `SpecularColorReflectance`: 1 = specular highlights take the light's colour,
    /// 0 = they take the surface colour too.
    pub specular_color_reflectance: f32,
    pub ambient: Option<Vec3>,
    pub diffuse: Option<Vec3>,
    pub specular: Option<Vec3>,
    pub shininess: f32,
    pub emission: Vec3,
    pub model: LightingModel,
    /// Cook-Torrance only: roughness `m` (Beckmann) or `α` (GGX).
    pub roughness: f32,
    /// Cook-Torrance only: 0 = dielectric (F0 = 0.04), 1 = metal (F0 = the diffuse colour, no
    /// diffuse term), in between a blend (glTF's metallic-roughness convention).
    pub metallic: f32,
    /// Cook-Torrance only: an explicit `F0`, instead of the one `metallic` implies.
    pub fresnel: Option<Vec3>,
    pub distribution: MicrofacetDistribution,
    /// Textures (bindings into the scene's texture list).
    pub textures: MaterialTextures,
}

/// `F0` of dielectrics (water, plastics, glass: about 4% reflected at normal incidence).
pub const DIELECTRIC_FRESNEL: f32 = 0.04;

impl MaterialRecipe {
    /// The coefficients of the lighting equation:
    /// `k_a = ka·color`, `k_d = kd·color`, `k_s = ks·(scr + (1 − scr)·color)`,
    /// each replaced by the explicit coefficient when one is set.
    pub fn resolve(&self) -> Material {
        let scr = self.specular_color_reflectance;
        let mut material = Material {
            ambient: self.ambient.unwrap_or(self.ka * self.color),
            diffuse: self.diffuse.unwrap_or(self.kd * self.color),
            specular: self
                .specular
                .unwrap_or(self.ks * (Vec3::splat(scr) + (1.0 - scr) * self.color)),
            shininess: self.shininess,
            emission: self.emission,
            model: self.model,
            textures: self.textures,
        };
        if let LightingModel::CookTorrance(_) = self.model {
            let base = material.diffuse;
            // F0 is a reflectance: above 1, Schlick's F exceeds 1 and the diffuse weight 1 − F
            // turns negative (a diffuse colour of 10^30 gave −∞ pixels in the `render` fuzz
            // target), so it is clamped to [0, 1] whether given or derived from the colour.
            let fresnel = self
                .fresnel
                .unwrap_or_else(|| Vec3::splat(DIELECTRIC_FRESNEL).lerp(base, self.metallic))
                .clamp(Vec3::ZERO, Vec3::ONE);
            material.diffuse = base * (1.0 - self.metallic);
            material.model = LightingModel::CookTorrance(Microfacet {
                roughness: self.roughness,
                fresnel,
                distribution: self.distribution,
            });
        }
        material
    }

    /// True when `ambient`, `diffuse` and `specular` are all explicit, so `color` and the
    /// strengths have no effect.
    pub fn is_fully_explicit(&self) -> bool {
        self.ambient.is_some() && self.diffuse.is_some() && self.specular.is_some()
    }
}

/// The material of objects that name none and whose mesh has none: MATLAB's `material
/// default` strengths (ka 0.3, kd 0.6, ks 0.9, exponent 10, scr 1) on a light grey surface.
pub const DEFAULT_RECIPE: MaterialRecipe = MaterialRecipe {
    color: Vec3::splat(0.8),
    ka: 0.3,
    kd: 0.6,
    ks: 0.9,
    specular_color_reflectance: 1.0,
    ambient: None,
    diffuse: None,
    specular: None,
    shininess: 10.0,
    emission: Vec3::ZERO,
    model: LightingModel::Phong,
    roughness: 0.3,
    metallic: 0.0,
    fresnel: None,
    distribution: MicrofacetDistribution::Beckmann,
    textures: MaterialTextures {
        diffuse: None,
        ambient: None,
        normal: None,
    },
};

/// The Cook-Torrance parameters of a material that names none (`--model cook-torrance` on a
/// Phong material): the format's defaults, roughness 0.3, a dielectric's `F0` and Beckmann's `D`.
pub fn default_microfacet() -> Microfacet {
    Microfacet {
        roughness: DEFAULT_RECIPE.roughness,
        fresnel: Vec3::splat(DIELECTRIC_FRESNEL),
        distribution: DEFAULT_RECIPE.distribution,
    }
}

pub fn default_material() -> Material {
    DEFAULT_RECIPE.resolve()
}

/// An OpenGL-table material: `(name, ambient, diffuse, specular, shininess / 128)`.
type GlEntry = (&'static str, [f32; 3], [f32; 3], [f32; 3], f32);

/// Seed 000's table, transposed to one RGB triple per coefficient.
const OPENGL_TABLE: [GlEntry; 12] = [
    (
        "emerald",
        [0.0215, 0.1745, 0.0215],
        [0.07568, 0.61424, 0.07568],
        [0.633, 0.727811, 0.633],
        0.6,
    ),
    (
        "jade",
        [0.135, 0.2225, 0.1575],
        [0.54, 0.89, 0.63],
        [0.316228, 0.316228, 0.316228],
        0.1,
    ),
    (
        "obsidian",
        [0.05375, 0.05, 0.06625],
        [0.18275, 0.17, 0.22525],
        [0.332741, 0.328634, 0.346435],
        0.3,
    ),
    (
        "pearl",
        [0.25, 0.20725, 0.20725],
        [1.0, 0.829, 0.829],
        [0.296648, 0.296648, 0.296648],
        0.088,
    ),
    (
        "ruby",
        [0.1745, 0.01175, 0.01175],
        [0.61424, 0.04136, 0.04136],
        [0.727811, 0.626959, 0.626959],
        0.6,
    ),
    (
        "turquoise",
        [0.1, 0.18725, 0.1745],
        [0.396, 0.74151, 0.69102],
        [0.297254, 0.30829, 0.306678],
        0.1,
    ),
    (
        "black-plastic",
        [0.0, 0.0, 0.0],
        [0.01, 0.01, 0.01],
        [0.50, 0.50, 0.50],
        0.25,
    ),
    (
        "black-rubber",
        [0.02, 0.02, 0.02],
        [0.01, 0.01, 0.01],
        [0.4, 0.4, 0.4],
        0.078125,
    ),
    (
        "brass",
        [0.329412, 0.223529, 0.027451],
        [0.780392, 0.568627, 0.113725],
        [0.992157, 0.941176, 0.807843],
        0.21794872,
    ),
    (
        "bronze",
        [0.2125, 0.1275, 0.054],
        [0.714, 0.4284, 0.18144],
        [0.393548, 0.271906, 0.166721],
        0.2,
    ),
    (
        "polished-bronze",
        [0.25, 0.148, 0.06475],
        [0.4, 0.2368, 0.1036],
        [0.774597, 0.458561, 0.200621],
        0.6,
    ),
    (
        "chrome",
        [0.25, 0.25, 0.25],
        [0.4, 0.4, 0.4],
        [0.774597, 0.774597, 0.774597],
        0.6,
    ),
];

/// A MATLAB-style preset: `(name, ka, kd, ks, exponent, specular colour reflectance)`.
type MatlabEntry = (&'static str, f32, f32, f32, f32, f32);

/// Seed 002's demo table (`PhongModel_main`).
const MATLAB_TABLE: [MatlabEntry; 5] = [
    ("shiny", 0.1, 0.6, 0.7, 5.0, 1.0),
    ("metal", 0.1, 0.1, 1.0, 5.0, 0.5),
    ("diffuse", 0.1, 0.7, 0.0, 1.0, 1.0),
    ("dull", 0.1, 0.7, 0.0, 1.0, 1.0),
    ("ambient", 1.0, 0.0, 0.0, 1.0, 1.0),
];

/// Names are matched without regard to case, and `_` or a space counts as `-`, so
/// `"Black Plastic"`, `"black_plastic"` and `"black-plastic"` are one preset.
pub fn normalize_name(name: &str) -> String {
    name.trim()
        .chars()
        .map(|c| match c {
            '_' | ' ' => '-',
            c => c.to_ascii_lowercase(),
        })
        .collect()
}

/// The built-in material called `name`, if any.
pub fn preset(name: &str) -> Option<MaterialRecipe> {
    let name = normalize_name(name);
    if let Some(&(_, ambient, diffuse, specular, fraction)) =
        OPENGL_TABLE.iter().find(|entry| entry.0 == name)
    {
        return Some(MaterialRecipe {
            ambient: Some(Vec3::from(ambient)),
            diffuse: Some(Vec3::from(diffuse)),
            specular: Some(Vec3::from(specular)),
            shininess: fraction * 128.0,
            ..DEFAULT_RECIPE
        });
    }
    MATLAB_TABLE
        .iter()
        .find(|entry| entry.0 == name)
        .map(|&(_, ka, kd, ks, exponent, scr)| MaterialRecipe {
            ka,
            kd,
            ks,
            shininess: exponent,
            specular_color_reflectance: scr,
            ..DEFAULT_RECIPE
        })
}

/// Every preset name, for "did you mean" hints and the documentation.
pub fn preset_names() -> impl Iterator<Item = &'static str> {
    OPENGL_TABLE
        .iter()
        .map(|entry| entry.0)
        .chain(MATLAB_TABLE.iter().map(|entry| entry.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check(name: &str, expected: Material) {
        let got = preset(name)
            .unwrap_or_else(|| panic!("no preset {name}"))
            .resolve();
        let close = |a: Vec3, b: Vec3| (a - b).abs().max_element() < 1e-6;
        assert!(
            close(got.ambient, expected.ambient)
                && close(got.diffuse, expected.diffuse)
                && close(got.specular, expected.specular)
                && (got.shininess - expected.shininess).abs() < 1e-4
                && got.model == expected.model,
            "{name}: got {got:?}, expected {expected:?}"
        );
    }

    #[test]
    fn opengl_table_transposed_from_seed() {
        check(
            "emerald",
            Material {
                ambient: Vec3::new(0.0215, 0.1745, 0.0215),
                diffuse: Vec3::new(0.07568, 0.61424, 0.07568),
                specular: Vec3::new(0.633, 0.727811, 0.633),
                shininess: 76.8,
                emission: Vec3::ZERO,
                model: LightingModel::Phong,
                textures: Default::default(),
            },
        );
        check(
            "Black Plastic",
            Material {
                ambient: Vec3::ZERO,
                diffuse: Vec3::splat(0.01),
                specular: Vec3::splat(0.5),
                shininess: 32.0,
                emission: Vec3::ZERO,
                model: LightingModel::Phong,
                textures: Default::default(),
            },
        );
        assert_eq!(OPENGL_TABLE.len(), 12);
    }

    #[test]
    fn matlab_presets_scale_the_surface_colour() {
        let blue = Vec3::new(0.0, 0.0, 1.0);
        let metal = MaterialRecipe {
            color: blue,
            ..preset("metal").unwrap()
        }
        .resolve();
        assert_eq!(metal.ambient, 0.1 * blue);
        assert_eq!(metal.diffuse, 0.1 * blue);
        // scr = 0.5: half the light's colour, half the surface's.
        assert_eq!(metal.specular, Vec3::new(0.5, 0.5, 1.0));
        assert_eq!(metal.shininess, 5.0);
        let shiny = MaterialRecipe {
            color: blue,
            ..preset("shiny").unwrap()
        }
        .resolve();
        assert_eq!(shiny.specular, Vec3::splat(0.7));
        assert_eq!(preset("dull"), preset("diffuse"));
    }

    #[test]
    fn unknown_names_are_none() {
        assert!(preset("emerld").is_none());
        assert_eq!(preset_names().count(), 17);
    }
}
