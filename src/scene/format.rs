//! The scene file format: serde types that mirror the RON text and nothing else.
//!
//! Every field has a default (see `docs/scene-format.md`, which documents each one), unknown
//! fields and variants are errors, and enums are externally tagged (`Spot(...)`), because
//! untagged and internally tagged enums give poor error messages in ron. Values are checked and
//! turned into the internal [`crate::scene::Scene`] by [`crate::scene::load`]; nothing here
//! validates.

use std::fmt;
use std::marker::PhantomData;

use serde::Deserialize;
use serde::de::{self, Deserializer, MapAccess, SeqAccess, Visitor};

use crate::diag::Schema;

/// A position or direction, `(x, y, z)`.
pub type Vec3File = [f64; 3];
/// A linear RGB colour `(r, g, b)`.
pub type RgbFile = [f32; 3];

/// The top level of a scene file: `Scene(...)` or just `(...)`.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(rename = "Scene", deny_unknown_fields)]
pub struct SceneFile {
    /// Material-library files whose `materials` tables this scene may use.
    #[serde(default)]
    pub include: Vec<String>,
    #[serde(default)]
    pub image: ImageFile,
    /// When absent, a perspective camera frames every object.
    #[serde(default)]
    pub camera: Option<CameraFile>,
    /// Global ambient light `I_a`.
    #[serde(default)]
    pub ambient: Option<RgbFile>,
    #[serde(default)]
    pub materials: OrderedMap<MaterialFile>,
    /// When absent, one white directional light shines from the camera; `[]` means none.
    #[serde(default)]
    pub lights: Option<Vec<LightFile>>,
    #[serde(default)]
    pub objects: Vec<ObjectFile>,
}

/// A material library: `Materials(include: [...], materials: {...})`.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(rename = "Materials", deny_unknown_fields)]
pub struct MaterialLibraryFile {
    #[serde(default)]
    pub include: Vec<String>,
    #[serde(default)]
    pub materials: OrderedMap<MaterialFile>,
}

#[derive(Debug, Clone, Default, Deserialize)]
#[serde(rename = "Image", deny_unknown_fields)]
pub struct ImageFile {
    pub width: Option<u32>,
    pub height: Option<u32>,
    pub background: Option<RgbFile>,
    /// Samples per pixel: 1 (no anti-aliasing), 2, 4, 8 or 16.
    pub samples: Option<u32>,
    /// Added to every texture lookup's mip level of detail.
    pub mip_bias: Option<f32>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(rename = "Camera", deny_unknown_fields)]
pub enum CameraFile {
    Perspective {
        eye: Option<Vec3File>,
        target: Option<Vec3File>,
        up: Option<Vec3File>,
        /// Vertical field of view, degrees.
        fov: Option<f64>,
        near: Option<f64>,
        far: Option<f64>,
    },
    Orthographic {
        eye: Option<Vec3File>,
        target: Option<Vec3File>,
        up: Option<Vec3File>,
        /// Height of the view in world units.
        height: Option<f64>,
        near: Option<f64>,
        far: Option<f64>,
    },
    /// A camera placed in a glTF file: `Gltf(object: 0, camera: "Name")`.
    Gltf {
        /// The object whose mesh file holds the camera: its index in `objects` or its `name`.
        /// Default: the first object whose mesh brings a camera.
        object: Option<NameOrIndexFile>,
        /// The glTF camera: its name (or its node's name), or its index in the file's `cameras`.
        /// Default: the first camera of the object.
        camera: Option<NameOrIndexFile>,
    },
}

/// `"name"` or `3`: something referred to by name or by position.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum NameOrIndexFile {
    Name(String),
    Index(usize),
}

/// The lighting model names of the file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename = "LightingModel", deny_unknown_fields)]
pub enum LightingModelFile {
    Phong,
    BlinnPhong,
    Lambert,
    Unlit,
    CookTorrance,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename = "Distribution", deny_unknown_fields)]
pub enum DistributionFile {
    Beckmann,
    Ggx,
}

/// A material, in either of two styles that may be mixed: OpenGL's explicit coefficients
/// (`ambient`, `diffuse`, `specular`) or MATLAB's surface `color` with scalar strengths
/// (`ka`, `kd`, `ks`, `specular_color_reflectance`). `base` starts from another material.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(rename = "Material", deny_unknown_fields)]
pub struct MaterialFile {
    pub base: Option<String>,
    pub color: Option<RgbFile>,
    pub ka: Option<f32>,
    pub kd: Option<f32>,
    pub ks: Option<f32>,
    pub specular_color_reflectance: Option<f32>,
    pub ambient: Option<RgbFile>,
    pub diffuse: Option<RgbFile>,
    pub specular: Option<RgbFile>,
    pub shininess: Option<f32>,
    pub emission: Option<RgbFile>,
    pub model: Option<LightingModelFile>,
    /// Cook-Torrance: microfacet roughness.
    pub roughness: Option<f32>,
    /// Cook-Torrance: 0 dielectric … 1 metal.
    pub metallic: Option<f32>,
    /// Cook-Torrance: Fresnel reflectance at normal incidence, `F0`.
    pub fresnel: Option<RgbFile>,
    /// Cook-Torrance: the microfacet distribution.
    pub distribution: Option<DistributionFile>,
    /// An image (sRGB) that multiplies the diffuse and ambient colours.
    pub texture: Option<String>,
    /// A tangent-space normal map (linear).
    pub normal_map: Option<String>,
}

/// `(constant: 1, linear: 0, quadratic: 0)`.
#[derive(Debug, Clone, Copy, Default, Deserialize)]
#[serde(rename = "Attenuation", deny_unknown_fields)]
pub struct AttenuationFile {
    pub constant: Option<f32>,
    pub linear: Option<f32>,
    pub quadratic: Option<f32>,
}

/// `(resolution: 2048, bias: 1.5, filter: 1)`.
#[derive(Debug, Clone, Copy, Default, Deserialize)]
#[serde(rename = "ShadowMap", deny_unknown_fields)]
pub struct ShadowMapFile {
    pub resolution: Option<u32>,
    pub bias: Option<f32>,
    pub filter: Option<u32>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(rename = "Light", deny_unknown_fields)]
pub enum LightFile {
    Directional {
        /// The direction the light travels in.
        direction: Option<Vec3File>,
        color: Option<RgbFile>,
        intensity: Option<f32>,
        /// Cast shadows (a shadow map).
        shadows: Option<bool>,
        /// Shadow-map settings.
        shadow_map: Option<ShadowMapFile>,
    },
    Point {
        position: Option<Vec3File>,
        color: Option<RgbFile>,
        intensity: Option<f32>,
        /// Cast shadows (a shadow map).
        shadows: Option<bool>,
        /// Shadow-map settings.
        shadow_map: Option<ShadowMapFile>,
        attenuation: Option<AttenuationFile>,
    },
    Spot {
        position: Option<Vec3File>,
        /// Where the cone points.
        direction: Option<Vec3File>,
        color: Option<RgbFile>,
        intensity: Option<f32>,
        /// Cast shadows (a shadow map).
        shadows: Option<bool>,
        /// Shadow-map settings.
        shadow_map: Option<ShadowMapFile>,
        /// Half-angle of the cone, degrees.
        cutoff: Option<f32>,
        exponent: Option<f32>,
        attenuation: Option<AttenuationFile>,
    },
}

#[derive(Debug, Clone, Deserialize)]
#[serde(rename = "Mesh", deny_unknown_fields)]
pub enum MeshFile {
    /// MATLAB's `sphere(N)`: a unit sphere around the origin, poles on ±Z.
    Sphere { segments: Option<u32> },
    /// The square [-1, 1]² in the XZ plane, facing +Y.
    Plane,
    /// The cube [-1, 1]³.
    Cube,
    /// A Wavefront OBJ file (path relative to the scene file).
    Obj(String),
    /// A glTF 2.0 file, `.gltf` or `.glb`.
    Gltf(String),
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename = "Shading", deny_unknown_fields)]
pub enum ShadingFile {
    Constant,
    Flat,
    Gouraud,
    Phong,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename = "BackFaces", deny_unknown_fields)]
pub enum BackFacesFile {
    ReverseLit,
    Lit,
    Unlit,
    Cull,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename = "Component", deny_unknown_fields)]
pub enum ComponentFile {
    All,
    Ambient,
    Diffuse,
    Specular,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename = "NormalInterpolation", deny_unknown_fields)]
pub enum NormalInterpolationFile {
    Nlerp,
    Slerp,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(rename = "Object", deny_unknown_fields)]
pub struct ObjectFile {
    pub name: Option<String>,
    pub mesh: MeshFile,
    pub translate: Option<Vec3File>,
    /// Degrees about X, then Y, then Z.
    pub rotate: Option<Vec3File>,
    pub scale: Option<ScaleFile>,
    pub material: Option<MaterialRefFile>,
    pub shading: Option<ShadingFile>,
    /// Degrees; used when normals are computed for a mesh file without them.
    pub crease_angle: Option<f32>,
    pub back_faces: Option<BackFacesFile>,
    pub component: Option<ComponentFile>,
    pub normal_interpolation: Option<NormalInterpolationFile>,
}

/// `scale: 2` or `scale: (1, 2, 1)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ScaleFile {
    Uniform(f64),
    PerAxis(Vec3File),
}

/// `material: "ruby"` (a name) or `material: (diffuse: ...)` (inline).
#[derive(Debug, Clone)]
pub enum MaterialRefFile {
    Named(String),
    Inline(Box<MaterialFile>),
}

/// A RON map `{ "key": value, ... }` read in file order, keeping duplicate keys so the loader
/// can report them (a `BTreeMap` would silently keep the last one).
#[derive(Debug, Clone)]
pub struct OrderedMap<V>(pub Vec<(String, V)>);

impl<V> Default for OrderedMap<V> {
    fn default() -> Self {
        OrderedMap(Vec::new())
    }
}

impl<'de, V: Deserialize<'de>> Deserialize<'de> for OrderedMap<V> {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct MapVisitor<V>(PhantomData<V>);
        impl<'de, V: Deserialize<'de>> Visitor<'de> for MapVisitor<V> {
            type Value = OrderedMap<V>;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a map of names to materials, like { \"red\": (diffuse: (1, 0, 0)) }")
            }
            fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Self::Value, A::Error> {
                let mut entries = Vec::new();
                while let Some(entry) = map.next_entry::<String, V>()? {
                    entries.push(entry);
                }
                Ok(OrderedMap(entries))
            }
        }
        deserializer.deserialize_map(MapVisitor(PhantomData))
    }
}

impl<'de> Deserialize<'de> for ScaleFile {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct ScaleVisitor;
        impl<'de> Visitor<'de> for ScaleVisitor {
            type Value = ScaleFile;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a uniform scale like `2` or a per-axis scale like `(1, 2, 1)`")
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<ScaleFile, E> {
                Ok(ScaleFile::Uniform(v))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<ScaleFile, E> {
                Ok(ScaleFile::Uniform(v as f64))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<ScaleFile, E> {
                Ok(ScaleFile::Uniform(v as f64))
            }
            fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<ScaleFile, A::Error> {
                Vec3File::deserialize(de::value::SeqAccessDeserializer::new(seq)).map(ScaleFile::PerAxis)
            }
        }
        deserializer.deserialize_any(ScaleVisitor)
    }
}

impl<'de> Deserialize<'de> for NameOrIndexFile {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct NameOrIndexVisitor;
        impl<'de> Visitor<'de> for NameOrIndexVisitor {
            type Value = NameOrIndexFile;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a name like \"Camera\" or an index like 0")
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<NameOrIndexFile, E> {
                Ok(NameOrIndexFile::Name(v.to_owned()))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<NameOrIndexFile, E> {
                usize::try_from(v)
                    .map(NameOrIndexFile::Index)
                    .map_err(|_| E::invalid_value(de::Unexpected::Unsigned(v), &self))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<NameOrIndexFile, E> {
                match u64::try_from(v) {
                    Ok(v) => self.visit_u64(v),
                    Err(_) => Err(E::invalid_value(de::Unexpected::Signed(v), &self)),
                }
            }
        }
        deserializer.deserialize_any(NameOrIndexVisitor)
    }
}

impl<'de> Deserialize<'de> for MaterialRefFile {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct MaterialRefVisitor;
        impl<'de> Visitor<'de> for MaterialRefVisitor {
            type Value = MaterialRefFile;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a material name like \"ruby\" or an inline material like (diffuse: (1, 0, 0))")
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<MaterialRefFile, E> {
                Ok(MaterialRefFile::Named(v.to_owned()))
            }
            fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<MaterialRefFile, A::Error> {
                MaterialFile::deserialize(de::value::MapAccessDeserializer::new(map))
                    .map(|m| MaterialRefFile::Inline(Box::new(m)))
            }
        }
        deserializer.deserialize_any(MaterialRefVisitor)
    }
}

/// The ron options every scene file is read with: `Some(...)` may be left out around
/// optional values, so a hand-written file says `eye: (0, 0, 5)`, not `eye: Some((0, 0, 5))`.
pub fn ron_options() -> ron::Options {
    ron::Options::default().with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME)
}

/// What the scene file's types expect, for error hints that show the right form: the
/// fields and variants are asked of the serde types themselves (through ron's own "unknown
/// field" and "unknown variant" errors), so the hints cannot drift from the format.
pub const SCENE_SCHEMA: Schema = Schema {
    fields: scene_fields,
    variants: scene_variants,
    what: "a scene",
    example: "(objects: [(mesh: Sphere())])",
};

/// The schema of a material library file.
pub const LIBRARY_SCHEMA: Schema = Schema {
    what: "a material library",
    example: "Materials(materials: { \"red\": (color: (1, 0, 0)) })",
    ..SCENE_SCHEMA
};

/// A name no type of the format accepts, to make ron list what they do accept.
const PROBE: &str = "lampshade_probe";

/// The field names ron reports when `probe` (a struct with the field [`PROBE`]) is read as `T`.
pub fn probe_fields<T: de::DeserializeOwned>(probe: &str) -> Option<&'static [&'static str]> {
    match ron_options().from_str::<T>(probe) {
        Err(ron::error::SpannedError {
            code: ron::Error::NoSuchStructField { expected, .. },
            ..
        }) => Some(expected),
        _ => None,
    }
}

/// The variant names ron reports when an unknown variant is read as `T`.
pub fn probe_variants<T: de::DeserializeOwned>() -> Option<&'static [&'static str]> {
    match ron_options().from_str::<T>(PROBE) {
        Err(ron::error::SpannedError {
            code: ron::Error::NoSuchEnumVariant { expected, .. },
            ..
        }) => Some(expected),
        _ => None,
    }
}

/// The fields of the struct that the value of field `holder` is, or of the struct variant
/// `name` written there (`Sphere`, `Spot`, `Perspective`...).
fn scene_fields(holder: Option<&str>, name: Option<&str>) -> Option<&'static [&'static str]> {
    let struct_probe = format!("({PROBE}: 0)");
    let variant_probe = |variant: &str| format!("{variant}({PROBE}: 0)");
    match (holder, name) {
        (Some("mesh") | None, Some(variant @ "Sphere")) => probe_fields::<MeshFile>(&variant_probe(variant)),
        (Some("camera") | None, Some(variant @ ("Perspective" | "Orthographic" | "Gltf"))) => {
            probe_fields::<CameraFile>(&variant_probe(variant))
        }
        (Some("lights") | None, Some(variant @ ("Directional" | "Point" | "Spot"))) => {
            probe_fields::<LightFile>(&variant_probe(variant))
        }
        (None, None | Some("Scene")) => probe_fields::<SceneFile>(&struct_probe),
        (None, Some("Materials")) => probe_fields::<MaterialLibraryFile>(&struct_probe),
        (Some("image"), _) => probe_fields::<ImageFile>(&struct_probe),
        (Some("attenuation"), _) => probe_fields::<AttenuationFile>(&struct_probe),
        (Some("shadow_map"), _) => probe_fields::<ShadowMapFile>(&struct_probe),
        (Some("material" | "materials"), _) => probe_fields::<MaterialFile>(&struct_probe),
        (Some("objects"), _) => probe_fields::<ObjectFile>(&struct_probe),
        _ => None,
    }
}

/// The variants of the enum that the value of field `holder` is.
fn scene_variants(holder: &str) -> Option<&'static [&'static str]> {
    match holder {
        "mesh" => probe_variants::<MeshFile>(),
        "camera" => probe_variants::<CameraFile>(),
        "lights" => probe_variants::<LightFile>(),
        "model" => probe_variants::<LightingModelFile>(),
        "distribution" => probe_variants::<DistributionFile>(),
        "shading" => probe_variants::<ShadingFile>(),
        "back_faces" => probe_variants::<BackFacesFile>(),
        "component" => probe_variants::<ComponentFile>(),
        "normal_interpolation" => probe_variants::<NormalInterpolationFile>(),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<SceneFile, ron::error::SpannedError> {
        ron_options().from_str(text)
    }

    #[test]
    fn minimal_scene_is_one_object() {
        let scene = parse("(objects: [(mesh: Sphere())])").unwrap();
        assert_eq!(scene.objects.len(), 1);
        assert!(scene.camera.is_none() && scene.lights.is_none());
        assert!(matches!(
            scene.objects[0].mesh,
            MeshFile::Sphere { segments: None }
        ));
    }

    #[test]
    fn material_reference_by_name_or_inline() {
        let scene = parse(
            r#"Scene(objects: [
                (mesh: Cube, material: "ruby"),
                (mesh: Cube, material: (diffuse: (1, 0, 0), shininess: 10)),
            ])"#,
        )
        .unwrap();
        assert!(matches!(&scene.objects[0].material, Some(MaterialRefFile::Named(n)) if n == "ruby"));
        let Some(MaterialRefFile::Inline(m)) = &scene.objects[1].material else {
            panic!("inline material expected")
        };
        assert_eq!(m.diffuse, Some([1.0, 0.0, 0.0]));
        assert_eq!(m.shininess, Some(10.0));
    }

    #[test]
    fn scale_is_uniform_or_per_axis() {
        let scene = parse("(objects: [(mesh: Cube, scale: 2), (mesh: Cube, scale: (1, 2.5, 3))])").unwrap();
        assert_eq!(scene.objects[0].scale, Some(ScaleFile::Uniform(2.0)));
        assert_eq!(scene.objects[1].scale, Some(ScaleFile::PerAxis([1.0, 2.5, 3.0])));
    }

    #[test]
    fn material_table_keeps_order_and_duplicates() {
        let scene = parse(r#"(materials: {"b": (), "a": (kd: 0.5), "b": ()})"#).unwrap();
        let names: Vec<&str> = scene.materials.0.iter().map(|(k, _)| k.as_str()).collect();
        assert_eq!(names, ["b", "a", "b"]);
    }

    #[test]
    fn unknown_fields_and_variants_are_errors() {
        let error = parse("(objects: [(mesh: Cube, shadng: Flat)])").unwrap_err();
        assert!(error.to_string().contains("shadng"), "{error}");
        let error = parse("(objects: [(mesh: Cone)])").unwrap_err();
        assert!(error.to_string().contains("Cone"), "{error}");
    }

    #[test]
    fn lights_of_every_kind() {
        let scene = parse(
            "(lights: [
                Directional(direction: (0, -1, 0)),
                Point(position: (1, 2, 3), attenuation: (quadratic: 0.1)),
                Spot(position: (0, 5, 0), direction: (0, -1, 0), cutoff: 20, exponent: 8),
            ])",
        )
        .unwrap();
        assert_eq!(scene.lights.unwrap().len(), 3);
    }

    #[test]
    fn gltf_camera_by_name_or_index() {
        let scene = parse(r#"(camera: Gltf(object: "house", camera: 2))"#).unwrap();
        let Some(CameraFile::Gltf { object, camera }) = scene.camera else {
            panic!("a glTF camera expected")
        };
        assert_eq!(object, Some(NameOrIndexFile::Name("house".into())));
        assert_eq!(camera, Some(NameOrIndexFile::Index(2)));
        let scene = parse("(camera: Gltf())").unwrap();
        assert!(matches!(
            scene.camera,
            Some(CameraFile::Gltf {
                object: None,
                camera: None
            })
        ));
        for bad in ["-1", "1.5", "(1, 2)"] {
            let error = parse(&format!("(camera: Gltf(camera: {bad}))")).unwrap_err();
            assert!(
                error
                    .to_string()
                    .contains(r#"a name like "Camera" or an index like 0"#),
                "{bad}: {error}"
            );
        }
    }

    #[test]
    fn the_schema_asks_the_types_themselves() {
        let fields = SCENE_SCHEMA.fields;
        assert_eq!(
            fields(Some("attenuation"), None),
            Some(&["constant", "linear", "quadratic"][..])
        );
        assert_eq!(fields(Some("mesh"), Some("Sphere")), Some(&["segments"][..]));
        assert_eq!(fields(Some("mesh"), Some("Gltf")), None, "a path, not fields");
        assert_eq!(
            fields(Some("camera"), Some("Gltf")),
            Some(&["object", "camera"][..])
        );
        for (holder, name) in [
            (None, None),
            (None, Some("Materials")),
            (Some("image"), None),
            (Some("shadow_map"), None),
            (Some("material"), None),
            (Some("materials"), None),
            (Some("objects"), None),
            (Some("camera"), Some("Perspective")),
            (Some("camera"), Some("Orthographic")),
            (Some("lights"), Some("Directional")),
            (Some("lights"), Some("Point")),
            (Some("lights"), Some("Spot")),
        ] {
            assert!(
                fields(holder, name).is_some_and(|f| !f.is_empty()),
                "{holder:?} {name:?}"
            );
        }
        for holder in [
            "mesh",
            "camera",
            "lights",
            "model",
            "distribution",
            "shading",
            "back_faces",
            "component",
            "normal_interpolation",
        ] {
            assert!(
                (SCENE_SCHEMA.variants)(holder).is_some_and(|v| !v.is_empty()),
                "{holder}"
            );
        }
        assert_eq!(
            (SCENE_SCHEMA.variants)("mesh"),
            Some(&["Sphere", "Plane", "Cube", "Obj", "Gltf"][..])
        );
        assert_eq!((SCENE_SCHEMA.variants)("width"), None);
    }
}
