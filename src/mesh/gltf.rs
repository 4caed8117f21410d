//! glTF 2.0 meshes (`.gltf` with external or `data:` buffers, and `.glb`), baked into one
//! [`Mesh`] in the file's scene space.
//!
//! # Design
//!
//! * **Parsing.** `gltf::Gltf::from_slice` parses and validates the document; buffers are
//!   then loaded one by one (the loop `gltf::import_buffers` runs, inlined so that each
//!   external `.bin` file is recorded in `files_read` and named in errors). Only the images
//!   that the drawn textures use are decoded (`gltf::import` would decode every one, and read
//!   files without telling us which). A required extension the loader does not support is an
//!   error naming it.
//! * **Accessors** are read by [`gltf_accessor`](super::gltf_accessor): tightly packed ones
//!   in bulk, strided, normalized-integer and sparse ones element by element, every byte
//!   range checked against its view and buffer (an error names the accessor, view and
//!   buffer file).
//! * **No panics.** `gltf` can panic on malformed input (out-of-range accessors, bad
//!   percent-encoding in a URI); every accessor is checked before it is read (component
//!   type, element size, stride, count) and every index against the vertex count, and the
//!   whole load also runs under `catch_unwind`, reported as "malformed glTF". The node
//!   hierarchy is walked with an explicit stack and a visited set, so a cyclic or shared
//!   hierarchy (invalid glTF) is an error instead of a stack overflow.
//! * **Scene.** The default scene is drawn, else scene 0, else (a file without scenes) every
//!   root node. Each node's world matrix is `parent · local`, composed in `f64`. Every
//!   TRIANGLES, TRIANGLE_STRIP and TRIANGLE_FAN primitive of every node instance is baked:
//!   positions by the world matrix, normals by its inverse transpose (computed as the
//!   cofactor matrix, which stays finite for singular matrices) and renormalised; when
//!   the matrix mirrors (negative determinant) every triangle's winding is reversed so the
//!   front stays counter-clockwise. Strips and fans follow the glTF spec's vertex order,
//!   which keeps alternate strip triangles facing the same way. POINTS and LINES
//!   primitives are skipped with a warning. A mesh used by two nodes is baked twice, so
//!   the triangle count is per node instance.
//! * **Normals** are handled per primitive instance: a non-finite file normal is an error (as
//!   a non-finite position is), zero ones are repaired
//!   ([`normals::repair_normals`]), missing ones computed with the crease angle
//!   ([`normals::compute_vertex_normals`]) after the transform, so the crease angle applies
//!   to what is drawn.
//! * **`KHR_mesh_quantization`** (required or used) also allows 8- and 16-bit integer
//!   positions (normalized or not: the node transform dequantizes them), normalized signed
//!   byte and short normals and tangents, and signed or unnormalized integer texture
//!   coordinates, all converted to floats by the specification's formulas
//!   ([`gltf_accessor`](super::gltf_accessor)).
//! * **Other vertex attributes.** `TEXCOORD_0` → [`Mesh::uvs`], `TEXCOORD_1` →
//!   [`Mesh::uvs1`] (float, or normalised unsigned byte or short; glTF's (0, 0) is already
//!   the top-left of the image), `COLOR_0` → [`Mesh::colors`] (RGB or RGBA, float or
//!   normalised unsigned byte or short; glTF vertex colours are linear, alpha 1 when absent),
//!   `TANGENT` → [`Mesh::tangents`]: the direction by the node's linear part, like an edge
//!   between positions, and `w` negated under a mirroring node (the bitangent `n × t` turns
//!   with the winding), then made unit and perpendicular to the final normal
//!   ([`tangents::orthonormalize_tangent`]). An attribute with a type glTF does not allow for
//!   it, or the wrong count, is ignored with a warning: the mesh is still drawn. They all
//!   follow their vertices through the normal computation. Primitives that lack an attribute
//!   another one has get zeros for texture coordinates, white for colours (no effect) and
//!   [`tangents::fallback_tangent`] for tangents, so every array has one entry per vertex;
//!   a textured primitive that lacks its texture coordinates gets a warning.
//! * **Tangents for normal maps.** When a primitive's material has a `normalTexture` and the
//!   primitive has no `TANGENT`, tangents are computed from the final positions, normals and
//!   the normal map's UV set ([`tangents::compute_tangents`]), as the glTF specification asks.
//!
//! * **Lights and cameras.** Every node instance of the drawn scene with a
//!   `KHR_lights_punctual` light or a `camera` gives an [`ImportedLight`] or
//!   [`ImportedCamera`] in [`LoadedMesh::lights`] / [`LoadedMesh::cameras`], placed by the
//!   node's world matrix like the positions: position = the node's origin, direction = its
//!   −Z (lights travel and cameras look that way), camera up = its +Y, all renormalised.
//!   Spot cone angles are converted from the file's radians to degrees; `znear`, `zfar` and
//!   `ymag` are scaled by how much the node stretches −Z and +Y (a viewer using the node's
//!   inverse as its view matrix sees the same). A light or camera whose values are not finite,
//!   or a camera whose projection cannot be used, is left out with a warning; a light with a
//!   `range` gets a warning that the range is not applied. How they become scene lights:
//!   [`ImportedLight::to_light`].
//!
//! # Textures
//!
//! `baseColorTexture` is decoded as sRGB and bound to `textures.diffuse`; `normalTexture` as
//! linear data, bound to `textures.normal` with its `scale`. The binding takes the texture's
//! `texCoord` (0 or 1; a higher set is not loaded, with a warning) and its sampler's `wrapS` /
//! `wrapT` (default `REPEAT`); `minFilter` / `magFilter` are not used (every texture is
//! filtered trilinearly, see [`crate::texture`]). Images come from external files (relative
//! URIs, percent-decoded, read relative to the glTF file and recorded in `files_read` even
//! when missing), `data:` URIs, or buffer views (GLB); PNG and JPEG are decoded
//! ([`Texture::from_encoded`]), each image once per colour space however many textures and
//! materials use it. An image that is missing or cannot be decoded is a warning naming it,
//! and its materials are drawn without it. A texture whose UV set no primitive has is not
//! bound (a warning says so). `metallicRoughnessTexture`, `occlusionTexture` and
//! `emissiveTexture` are not sampled yet (a warning names them when a material has them).
//!
//! # Metallic-roughness to [`Material`]
//!
//! glTF's `pbrMetallicRoughness` maps onto the Cook-Torrance model with the GGX distribution
//! (the BRDF the glTF specification describes), not onto a Phong approximation:
//!
//! * roughness `α = r²` from the perceptual roughness `r` (floored at 10⁻³: a perfect mirror
//!   has no finite distribution);
//! * `F0 = lerp(0.04, baseColor, metallic)`: 4 % for dielectrics, the base colour for metals;
//! * diffuse = `baseColor·(1 − metallic)` (metals have no diffuse term), further weighted by
//!   `1 − F` when lit (the seed's energy conservation `k_s + k_d = 1`);
//! * ambient = `baseColor`, specular (used only by the debug views of other models) = `F0`;
//! * shininess = [`blinn_phong_exponent`] (used if the scene switches the model to Phong);
//! * emission = `emissiveFactor` × `KHR_materials_emissive_strength` (default 1).
//!
//! The metallic-roughness texture is not sampled yet, so the factors stand for metallic and
//! roughness, except in one case: with a `metallicRoughnessTexture`, `metallicFactor` only
//! scales the texture and its default of 1 would turn every textured model into a metal, so
//! metallic is taken as 0 there (a warning says so). The base colour texture multiplies
//! `baseColor` where it is used (diffuse and ambient, through `textures.diffuse`); `F0` keeps
//! the factor. A primitive without a material uses the glTF default
//! material (base colour 1, metallic 1, roughness 1: a white rough metal), appended after
//! the file's materials when some primitive needs it.

use std::borrow::Cow;
use std::collections::HashMap;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::{DMat3, DMat4, DVec3, Mat4, Vec2, Vec3, Vec4};
use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::Mode;

use super::gltf_accessor::{read_floats, read_indices};
use super::normals::VertexAttributes;
use super::{FileContent, USE_GLTF_HINT, first_bytes};
use super::{
    ImportedCamera, ImportedLight, ImportedLightKind, ImportedProjection, LoadedMesh, Mesh, MeshError,
    MeshOptions, normals, tangents,
};
use crate::scene::access::{FileAccess, ReadError};
use crate::scene::limits::MAX_LIGHTING_VALUE;
use crate::scene::{LightingModel, Material, Microfacet, MicrofacetDistribution, TextureBinding};
use crate::texture::{ColorSpace, Sampler, Texture, Wrap};

/// Required extensions a file may list and still load: both are understood by the `gltf`
/// crate as built here, and neither changes the geometry (`KHR_lights_punctual` adds lights,
/// returned in [`LoadedMesh::lights`]).
const SUPPORTED_REQUIRED_EXTENSIONS: [&str; 3] = [
    "KHR_materials_emissive_strength",
    "KHR_lights_punctual",
    MESH_QUANTIZATION,
];

/// The extension that allows 8- and 16-bit integer positions, normals, tangents and texture
/// coordinates (module documentation); the `gltf` crate does not know it.
const MESH_QUANTIZATION: &str = "KHR_mesh_quantization";

/// The Blinn-Phong exponent equivalent to a glTF perceptual roughness (clamped to [0, 1]):
/// with `α = r²` (the GGX remapping glTF uses), the Beckmann-matched exponent
/// `n = 2/α² − 2`, clamped to [1, 1000] (α² is floored at 1e-4 first so a mirror does
/// not divide by zero).
pub fn blinn_phong_exponent(roughness: f32) -> f32 {
    let r = if roughness.is_finite() {
        roughness.clamp(0.0, 1.0)
    } else {
        1.0
    };
    let alpha = r * r;
    (2.0 / (alpha * alpha).max(1e-4) - 2.0).clamp(1.0, 1000.0)
}

/// A glTF material's factors as a [`Material`] (module documentation). `metallic` and
/// `roughness` are clamped to [0, 1]; non-finite inputs fall back to the glTF defaults.
pub fn material_from_factors(base_color: Vec3, metallic: f32, roughness: f32, emission: Vec3) -> Material {
    let base_color = if base_color.is_finite() {
        lighting_value(base_color)
    } else {
        Vec3::ONE
    };
    let metallic = if metallic.is_finite() {
        metallic.clamp(0.0, 1.0)
    } else {
        1.0
    };
    let roughness = if roughness.is_finite() {
        roughness.clamp(0.0, 1.0)
    } else {
        1.0
    };
    let fresnel = Vec3::splat(0.04).lerp(base_color, metallic);
    Material {
        ambient: base_color,
        diffuse: base_color * (1.0 - metallic),
        specular: fresnel,
        shininess: blinn_phong_exponent(roughness),
        emission: if emission.is_finite() {
            lighting_value(emission)
        } else {
            Vec3::ZERO
        },
        model: LightingModel::CookTorrance(Microfacet {
            roughness: (roughness * roughness).max(1e-3),
            fresnel,
            distribution: MicrofacetDistribution::Ggx,
        }),
        textures: Default::default(),
    }
}

/// `value` held to `[0, MAX_LIGHTING_VALUE]`, the range a scene file may give colours and
/// intensities in (NaN stays NaN, for the callers' finiteness checks).
fn lighting_value(value: Vec3) -> Vec3 {
    value.clamp(Vec3::ZERO, Vec3::splat(MAX_LIGHTING_VALUE as f32))
}

/// The material of primitives that have none: glTF's default material (base colour 1,
/// metallic 1, roughness 1, no emission) through [`material_from_factors`].
pub fn default_material() -> Material {
    material_from_factors(Vec3::ONE, 1.0, 1.0, Vec3::ZERO)
}

/// Loads a `.gltf` or `.glb` file into one [`Mesh`]; see the module documentation.
pub fn load_gltf(path: &Path, options: &MeshOptions) -> Result<LoadedMesh, MeshError> {
    parse_gltf(path, &options.access)?.build(options.crease_angle_degrees)
}

/// [`load_gltf`] on the bytes of the file at `path`, already read (external buffers and images
/// are still read relative to `path`): the entry point of the fuzzer and of tests that build
/// files in memory. The same code path as `load_gltf`, panics contained the same way.
pub fn load_gltf_from_bytes(
    path: &Path,
    bytes: &[u8],
    options: &MeshOptions,
) -> Result<LoadedMesh, MeshError> {
    parse_gltf_bytes(path, bytes, &options.access)?.build(options.crease_angle_degrees)
}

/// Reads and parses a glTF or GLB file and its buffers: the part of a load that does not
/// depend on the crease angle. [`ParsedGltf::build`] makes the mesh.
pub fn parse_gltf(path: &Path, access: &FileAccess) -> Result<ParsedGltf, MeshError> {
    let bytes = access
        .read(path)
        .map_err(|error| MeshError::new(path, format!("cannot read mesh file: {error}")))?;
    parse_gltf_bytes(path, &bytes, access)
}

/// A glTF file read and parsed, with its buffers; its images are decoded by the build.
#[derive(Debug, Clone)]
pub struct ParsedGltf {
    path: PathBuf,
    document: gltf::Document,
    buffers: Vec<Vec<u8>>,
    /// The file and its buffer files.
    files_read: Vec<PathBuf>,
    access: FileAccess,
}

impl ParsedGltf {
    /// The mesh for one crease angle (module documentation).
    pub fn build(&self, crease_angle_degrees: f32) -> Result<LoadedMesh, MeshError> {
        contain_panics(&self.path, || self.build_unguarded(crease_angle_degrees))
    }
}

/// Runs a step of loading the glTF file at `path`, turning a panic of the `gltf` crate into
/// "malformed glTF".
fn contain_panics<T>(path: &Path, step: impl FnOnce() -> Result<T, MeshError>) -> Result<T, MeshError> {
    catch_unwind(AssertUnwindSafe(step)).unwrap_or_else(|panic| {
        let reason = panic
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| panic.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "the glTF reader gave up on this file".to_string());
        Err(MeshError::new(path, format!("malformed glTF: {reason}")))
    })
}

fn parse_gltf_bytes(path: &Path, bytes: &[u8], access: &FileAccess) -> Result<ParsedGltf, MeshError> {
    contain_panics(path, || {
        let fail = |message: String| MeshError::new(path, message);
        check_content(bytes).map_err(|(message, other_kind)| match other_kind {
            true => fail(message).with_hint(USE_GLTF_HINT),
            false => fail(message),
        })?;
        let (document, blob) = parse_document(bytes).map_err(fail)?;
        let mut files_read = vec![path.to_path_buf()];
        let directory = path.parent().unwrap_or(Path::new(""));
        let buffers = load_buffers(&document, blob, directory, access, &mut files_read).map_err(fail)?;
        Ok(ParsedGltf {
            path: path.to_path_buf(),
            document,
            buffers,
            files_read,
            access: access.clone(),
        })
    })
}

impl ParsedGltf {
    fn build_unguarded(&self, crease_angle_degrees: f32) -> Result<LoadedMesh, MeshError> {
        let path = self.path.as_path();
        let fail = |message: String| MeshError::new(path, message);
        let document = &self.document;
        let buffers = &self.buffers;
        let mut files_read = self.files_read.clone();
        let directory = path.parent().unwrap_or(Path::new(""));
        let options = MeshOptions {
            crease_angle_degrees,
            access: self.access.clone(),
        };

        let mut baker = Baker {
            buffers,
            crease_angle_degrees: options.crease_angle_degrees,
            default_material_index: document.materials().len() as u32,
            quantized: document.extensions_used().any(|name| name == MESH_QUANTIZATION),
            mesh: Mesh::default(),
            skipped_primitives: Vec::new(),
            repaired_normals: 0,
            computed_normals: false,
            missing_uv_sets: Vec::new(),
            warnings: Vec::new(),
        };
        let mut lights = Vec::new();
        let mut cameras = Vec::new();
        let mut placement_warnings = Vec::new();
        for (node, world) in scene_instances(document).map_err(fail)? {
            if let Some(mesh) = node.mesh() {
                for primitive in mesh.primitives() {
                    baker.bake(&mesh, &primitive, world).map_err(fail)?;
                }
            }
            if let Some(light) = node.light() {
                match imported_light(&light, world) {
                    Some(light) => lights.push(light),
                    None => placement_warnings.push(format!(
                        "light {} (node {}) has a non-finite colour, intensity or placement and is ignored",
                        light.index(),
                        node.index()
                    )),
                }
            }
            if let Some(camera) = node.camera() {
                match imported_camera(&camera, node.name(), world) {
                Some(camera) => cameras.push(camera),
                None => placement_warnings.push(format!(
                    "camera {} (node {}) has non-finite or invalid settings or placement and cannot be used",
                    camera.index(),
                    node.index()
                )),
            }
            }
        }
        if baker.mesh.triangles.is_empty() {
            return Err(fail("contains no triangles".to_string()));
        }

        let Baker {
            mut mesh,
            mut warnings,
            skipped_primitives,
            repaired_normals,
            computed_normals,
            default_material_index,
            missing_uv_sets,
            ..
        } = baker;
        let crease_angle_used = computed_normals || repaired_normals > 0;
        if !skipped_primitives.is_empty() {
            warnings.push(format!(
                "skipped {} point or line primitives (mesh, primitive: {}): only triangles are drawn",
                skipped_primitives.len(),
                skipped_primitives
                    .iter()
                    .map(|(mesh, primitive)| format!("{mesh}, {primitive}"))
                    .collect::<Vec<_>>()
                    .join("; ")
            ));
        }
        warnings.extend(placement_warnings);
        let ranged: Vec<String> = lights
            .iter()
            .filter(|light| light.range.is_some())
            .map(|light| light.index.to_string())
            .collect();
        if !ranged.is_empty() {
            warnings.push(format!(
                "lights {} have a `range`, which is not applied: they fall off as 1/d² everywhere",
                ranged.join(", ")
            ));
        }
        if repaired_normals > 0 {
            warnings.push(format!(
                "{repaired_normals} vertex normals in the file were zero and were recomputed"
            ));
        }

        // A primitive lacking the UV set its material reads is worth a warning only when the
        // mesh has that set at all; otherwise the binding is dropped below, with its own warning.
        for (here, set) in missing_uv_sets {
            let has_set = if set == 0 { &mesh.uvs } else { &mesh.uvs1 };
            if !has_set.is_empty() {
                warnings.push(format!(
                "{here}: its material's texture reads TEXCOORD_{set}, which the primitive lacks; it reads the texture's corner (0, 0)"
            ));
            }
        }

        let mut images = ImageLoader {
            buffers,
            access: &options.access,
            refused: None,
            directory,
            index_by_image: HashMap::new(),
            textures: Vec::new(),
            files_read: Vec::new(),
            warnings: Vec::new(),
        };
        mesh.materials = document
            .materials()
            .map(|material| {
                let mut lowered = material_from_gltf(&material);
                bind_textures(&material, &mut lowered, &mesh, &mut images, &mut warnings);
                lowered
            })
            .collect();
        if mesh.triangle_materials.contains(&default_material_index) {
            mesh.materials.push(default_material());
        }
        // An image outside the sandbox is an error, not the warning of a missing one.
        if let Some(problem) = images.refused {
            return Err(fail(problem));
        }
        mesh.textures = images.textures;
        files_read.extend(images.files_read);
        warnings.extend(images.warnings);
        // A normal-mapped material that no drawn primitive uses leaves the mesh without
        // tangents; the invariant wants them, and any perpendicular unit vectors do.
        let normal_mapped = mesh.materials.iter().any(|m| m.textures.normal.is_some());
        if normal_mapped && mesh.tangents.is_empty() {
            mesh.tangents = mesh
                .normals
                .iter()
                .map(|&n| tangents::fallback_tangent(n))
                .collect();
        }

        Ok(LoadedMesh {
            mesh,
            files_read,
            warnings,
            lights,
            cameras,
            crease_angle_used,
        })
    }
}

/// A `KHR_lights_punctual` light at a node with world matrix `world`; `None` when something
/// is not finite. Negative colours or intensities (invalid glTF) are taken as 0, and both are
/// held to [`MAX_LIGHTING_VALUE`] like a scene file's.
fn imported_light(light: &gltf::khr_lights_punctual::Light, world: DMat4) -> Option<ImportedLight> {
    use gltf::khr_lights_punctual::Kind;
    let color = lighting_value(Vec3::from(light.color())) * lighting_value(Vec3::splat(light.intensity()));
    let kind = match light.kind() {
        Kind::Directional => ImportedLightKind::Directional,
        Kind::Point => ImportedLightKind::Point,
        Kind::Spot {
            inner_cone_angle,
            outer_cone_angle,
        } => {
            let outer = outer_cone_angle.to_degrees().clamp(0.0, 90.0);
            ImportedLightKind::Spot {
                inner_cone_degrees: inner_cone_angle.to_degrees().clamp(0.0, outer),
                outer_cone_degrees: outer,
            }
        }
    };
    let position = world.transform_point3(DVec3::ZERO);
    // A node that scales to nothing keeps glTF's own −Z.
    let direction = world
        .transform_vector3(DVec3::NEG_Z)
        .try_normalize()
        .unwrap_or(DVec3::NEG_Z);
    let finite = color.is_finite()
        && position.is_finite()
        && match kind {
            ImportedLightKind::Spot {
                inner_cone_degrees,
                outer_cone_degrees,
            } => inner_cone_degrees.is_finite() && outer_cone_degrees.is_finite(),
            _ => true,
        };
    finite.then(|| ImportedLight {
        name: light.name().map(str::to_owned),
        index: light.index(),
        kind,
        color,
        position,
        direction,
        range: light.range().filter(|range| range.is_finite() && *range > 0.0),
    })
}

/// A camera at a node with world matrix `world`: the eye at the node's origin looking down its
/// −Z with +Y up; `zfar`, `znear` and `ymag` scaled by how much the node stretches the view
/// and up directions (as a viewer whose view matrix is the node's inverse sees it). `None`
/// when the placement or the projection cannot make a camera (not finite, `znear ≤ 0`,
/// `zfar ≤ znear`, a field of view outside (0°, 180°), `ymag = 0`, or a node that flattens
/// the view or up direction or makes them parallel).
fn imported_camera(camera: &gltf::Camera, node_name: Option<&str>, world: DMat4) -> Option<ImportedCamera> {
    let eye = world.transform_point3(DVec3::ZERO);
    let forward = world.transform_vector3(DVec3::NEG_Z);
    let up = world.transform_vector3(DVec3::Y);
    let (depth_scale, height_scale) = (forward.length(), up.length());
    let (forward, up) = (forward.try_normalize()?, up.try_normalize()?);
    if !eye.is_finite() || forward.cross(up).length() < 1e-9 {
        return None;
    }
    let projection = match camera.projection() {
        gltf::camera::Projection::Perspective(perspective) => {
            let fov_y_degrees = f64::from(perspective.yfov()).to_degrees();
            let near = f64::from(perspective.znear()) * depth_scale;
            let far = perspective.zfar().map(|far| f64::from(far) * depth_scale);
            let valid = fov_y_degrees > 0.0
                && fov_y_degrees < 180.0
                && near > 0.0
                && near.is_finite()
                && far.is_none_or(|far| far > near && far.is_finite());
            valid.then_some(ImportedProjection::Perspective {
                fov_y_degrees,
                near,
                far,
            })?
        }
        gltf::camera::Projection::Orthographic(orthographic) => {
            let height = 2.0 * f64::from(orthographic.ymag()).abs() * height_scale;
            let near = f64::from(orthographic.znear()) * depth_scale;
            let far = f64::from(orthographic.zfar()) * depth_scale;
            let valid = height > 0.0 && height.is_finite() && near >= 0.0 && far > near && far.is_finite();
            valid.then_some(ImportedProjection::Orthographic { height, near, far })?
        }
    };
    Some(ImportedCamera {
        name: camera.name().map(str::to_owned),
        node_name: node_name.map(str::to_owned),
        index: camera.index(),
        eye,
        forward,
        up,
        projection,
    })
}

/// Bytes in a GLB header: magic, version, total length.
const GLB_HEADER_BYTES: usize = 12;
/// Bytes in a GLB chunk header: length, type.
const GLB_CHUNK_HEADER_BYTES: usize = 8;

/// Refuses what is not a glTF file, saying what it is (an OBJ, some binary file), and checks
/// a GLB's container (version, total length, chunk lengths and types) with the sizes
/// involved, which the `gltf` crate reports as "expected value at line 1 column 1" (a JSON
/// message for a binary file) or "could not completely read the object". The error says
/// whether the file may be of the other mesh kind (worth a hint at `Obj(...)`).
fn check_content(bytes: &[u8]) -> Result<(), (String, bool)> {
    let other_kind = |message: String| (message, true);
    match FileContent::of(bytes) {
        FileContent::BinaryGltf => check_glb_container(bytes).map_err(|message| (message, false)),
        FileContent::Json => Ok(()),
        content @ FileContent::ObjText => Err(other_kind(format!(
            "this is {}, not a glTF file",
            content.description()
        ))),
        FileContent::Binary | FileContent::OtherText if bytes.is_empty() => Err(other_kind(
            "the file is empty: a glTF file is JSON and a GLB file starts with the bytes `glTF`".to_string(),
        )),
        content @ (FileContent::Binary | FileContent::OtherText) => Err(other_kind(format!(
            "this is {} starting with {}, not glTF: a .gltf file is JSON (it starts with `{{`) and a .glb file starts with the bytes `glTF` (67 6C 54 46)",
            content.description(),
            first_bytes(bytes)
        ))),
    }
}

/// The GLB container of a file that starts with the magic `glTF` (glTF 2.0 specification,
/// "GLB File Format Specification").
fn check_glb_container(bytes: &[u8]) -> Result<(), String> {
    let length = bytes.len();
    let word = |at: usize| -> Option<u32> {
        let word = bytes.get(at..at + 4)?;
        Some(u32::from_le_bytes([word[0], word[1], word[2], word[3]]))
    };
    let (Some(version), Some(declared)) = (word(4), word(8)) else {
        return Err(format!(
            "broken binary glTF: the file has {length} bytes, less than the {GLB_HEADER_BYTES}-byte GLB header"
        ));
    };
    if version != 2 {
        return Err(format!(
            "binary glTF version {version}: only version 2 (glTF 2.0) is supported"
        ));
    }
    let declared = declared as usize;
    if declared != length {
        let what = if declared > length {
            "it is truncated"
        } else {
            "it is damaged or has bytes appended"
        };
        return Err(format!(
            "broken binary glTF: the header says {declared} bytes, the file has {length}: {what}"
        ));
    }
    let mut offset = GLB_HEADER_BYTES;
    let mut index = 0;
    while offset < length {
        let (Some(chunk_length), Some(kind)) = (word(offset), bytes.get(offset + 4..offset + 8)) else {
            return Err(format!(
                "broken binary glTF: chunk {index} at byte {offset} has {} bytes left for its {GLB_CHUNK_HEADER_BYTES}-byte header",
                length - offset
            ));
        };
        let kind_text = String::from_utf8_lossy(kind).replace('\0', "\\0");
        let room = length - offset - GLB_CHUNK_HEADER_BYTES;
        if chunk_length as usize > room {
            return Err(format!(
                "broken binary glTF: the `{kind_text}` chunk at byte {offset} says {chunk_length} bytes, but only {room} follow it"
            ));
        }
        // Chunks after the first may have types a reader does not know (it skips them).
        if index == 0 && kind != b"JSON" {
            return Err(format!(
                "broken binary glTF: the first chunk has the type `{kind_text}`, expected `JSON`"
            ));
        }
        offset += GLB_CHUNK_HEADER_BYTES + chunk_length as usize;
        index += 1;
    }
    if index == 0 {
        return Err("broken binary glTF: the file has a header but no JSON chunk".to_string());
    }
    Ok(())
}

/// Parses and validates the document, returning it with the .glb binary chunk if any. An
/// unsupported required extension is named.
fn parse_document(bytes: &[u8]) -> Result<(gltf::Document, Option<Vec<u8>>), String> {
    let gltf::Gltf { document, blob } = gltf::Gltf::from_slice_without_validation(bytes)
        .map_err(|error| format!("malformed glTF: {error}"))?;
    let mut json = document.into_json();
    // Checked before validation, which reports an unknown required extension tersely.
    if let Some(name) = json
        .extensions_required
        .iter()
        .find(|name| !SUPPORTED_REQUIRED_EXTENSIONS.contains(&name.as_str()))
    {
        return Err(format!(
            "requires the glTF extension {name}, which is not supported"
        ));
    }
    // gltf-json's validation refuses required extensions it does not know; this one needs
    // nothing from it (the accessors are read here).
    json.extensions_required.retain(|name| name != MESH_QUANTIZATION);
    // gltf-json 1.4's validation indexes a primitive's POSITION accessor before checking
    // that it exists, and panics; check attribute indices first.
    for (mesh_index, mesh) in json.meshes.iter().enumerate() {
        for (primitive_index, primitive) in mesh.primitives.iter().enumerate() {
            if let Some(index) = primitive
                .attributes
                .values()
                .find(|index| index.value() >= json.accessors.len())
            {
                return Err(format!(
                    "malformed glTF: mesh {mesh_index} primitive {primitive_index} refers to accessor {}, but there are {}",
                    index.value(),
                    json.accessors.len()
                ));
            }
        }
    }
    let document = gltf::Document::from_json(json).map_err(|error| format!("malformed glTF: {error}"))?;
    Ok((document, blob))
}

/// The bytes of every buffer, in document order. External files are read relative to
/// `directory` and recorded in `files_read`.
fn load_buffers(
    document: &gltf::Document,
    mut blob: Option<Vec<u8>>,
    directory: &Path,
    access: &FileAccess,
    files_read: &mut Vec<PathBuf>,
) -> Result<Vec<Vec<u8>>, String> {
    let mut buffers = Vec::new();
    for buffer in document.buffers() {
        let index = buffer.index();
        let data = match buffer.source() {
            gltf::buffer::Source::Bin => blob.take().ok_or_else(|| {
                format!("buffer {index} refers to the binary chunk of a .glb, and there is none")
            })?,
            gltf::buffer::Source::Uri(uri) if uri.starts_with("data:") => {
                gltf::buffer::Data::from_source(buffer.source(), None)
                    .map_err(|error| format!("buffer {index}: cannot decode its data URI: {error}"))?
                    .0
            }
            gltf::buffer::Source::Uri(uri) => {
                let relative =
                    percent_decode(uri).ok_or_else(|| format!("buffer {index}: malformed URI '{uri}'"))?;
                if relative.contains(':') {
                    return Err(format!(
                        "buffer {index}: unsupported URI '{uri}' (only relative paths and data: URIs)"
                    ));
                }
                let file = directory.join(relative);
                files_read.push(file.clone());
                access.read(&file).map_err(|error| match error {
                    ReadError::OutsideSandbox { .. } => {
                        format!("buffer {index} `{uri}`: refused: {error}")
                    }
                    _ => format!("cannot read buffer file {}: {error}", file.display()),
                })?
            }
        };
        if data.len() < buffer.length() {
            let name = match buffer.source() {
                gltf::buffer::Source::Uri(uri) if !uri.starts_with("data:") => format!(" `{uri}`"),
                _ => String::new(),
            };
            return Err(format!(
                "buffer {index}{name} has {} bytes but the file declares {}: it is truncated",
                data.len(),
                buffer.length()
            ));
        }
        buffers.push(data);
    }
    Ok(buffers)
}

/// Decodes `%XX` escapes of a URI path; `None` for a malformed escape or non-UTF-8 result.
fn percent_decode(uri: &str) -> Option<String> {
    let bytes = uri.as_bytes();
    let mut decoded = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = std::str::from_utf8(bytes.get(i + 1..i + 3)?).ok()?;
            decoded.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            decoded.push(bytes[i]);
            i += 1;
        }
    }
    String::from_utf8(decoded).ok()
}

/// Every node of the drawn scene with its world matrix, in depth-first order.
fn scene_instances(document: &gltf::Document) -> Result<Vec<(gltf::Node<'_>, DMat4)>, String> {
    let roots: Vec<gltf::Node> = match document.default_scene().or_else(|| document.scenes().next()) {
        Some(scene) => scene.nodes().collect(),
        None => {
            let mut is_child = vec![false; document.nodes().len()];
            for child in document.nodes().flat_map(|node| node.children()) {
                is_child[child.index()] = true;
            }
            document.nodes().filter(|node| !is_child[node.index()]).collect()
        }
    };
    let mut visited = vec![false; document.nodes().len()];
    let mut instances = Vec::new();
    let mut stack: Vec<(gltf::Node, DMat4)> = roots
        .into_iter()
        .rev()
        .map(|node| (node, DMat4::IDENTITY))
        .collect();
    while let Some((node, parent)) = stack.pop() {
        if std::mem::replace(&mut visited[node.index()], true) {
            return Err(format!(
                "malformed glTF: node {} is reached twice from the scene (node hierarchies must be trees)",
                node.index()
            ));
        }
        let local = Mat4::from_cols_array_2d(&node.transform().matrix()).as_dmat4();
        let world = parent * local;
        let children: Vec<gltf::Node> = node.children().collect();
        stack.extend(children.into_iter().rev().map(|child| (child, world)));
        instances.push((node, world));
    }
    Ok(instances)
}

/// Accumulates baked primitives into one mesh.
struct Baker<'a> {
    buffers: &'a [Vec<u8>],
    crease_angle_degrees: f32,
    /// The file uses `KHR_mesh_quantization`: integer attribute types are allowed.
    quantized: bool,
    /// Material index of primitives without a material: one past the file's materials.
    default_material_index: u32,
    mesh: Mesh,
    /// (mesh, primitive) indices of point and line primitives.
    skipped_primitives: Vec<(usize, usize)>,
    repaired_normals: usize,
    /// Some primitive had no normals, so they were computed with the crease angle.
    computed_normals: bool,
    /// Primitives (named "mesh m primitive p") whose material reads a UV set they lack.
    missing_uv_sets: Vec<(String, u32)>,
    warnings: Vec<String>,
}

impl Baker<'_> {
    /// Appends one primitive of one node instance, transformed by `world`.
    fn bake(&mut self, mesh: &gltf::Mesh, primitive: &gltf::Primitive, world: DMat4) -> Result<(), String> {
        let mode = primitive.mode();
        let here = format!("mesh {} primitive {}", mesh.index(), primitive.index());
        if !matches!(mode, Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan) {
            self.skipped_primitives.push((mesh.index(), primitive.index()));
            return Ok(());
        }
        let buffers = self.buffers;

        let Some(position_accessor) = primitive.get(&gltf::Semantic::Positions) else {
            self.warnings
                .push(format!("{here} has no POSITION attribute and was skipped"));
            return Ok(());
        };
        match self.quantized && quantized(&position_accessor, Dimensions::Vec3, true) {
            true => check_layout(&position_accessor),
            false => check_accessor(&position_accessor, DataType::F32, Dimensions::Vec3),
        }
        .map_err(|e| format!("{here}: POSITION {e}"))?;
        let vertex_count = position_accessor.count();
        let positions: Vec<Vec3> = read_floats::<3>(&position_accessor, buffers)
            .map_err(|e| format!("{here}: POSITION {e}"))?
            .into_iter()
            .map(|p| world.transform_point3(Vec3::from(p).as_dvec3()).as_vec3())
            .collect();
        if positions.len() != vertex_count {
            return Err(format!(
                "{here}: POSITION has {} of its {vertex_count} entries",
                positions.len()
            ));
        }
        if !positions.iter().all(|p| p.is_finite()) {
            return Err(format!(
                "{here}: a vertex position is not finite after the node transforms"
            ));
        }

        let indices: Vec<u32> = match primitive.indices() {
            None => (0..vertex_count as u32).collect(),
            Some(accessor) => {
                check_index_accessor(&accessor).map_err(|e| format!("{here}: indices {e}"))?;
                let indices = read_indices(&accessor, buffers).map_err(|e| format!("{here}: indices {e}"))?;
                if let Some(&bad) = indices.iter().find(|&&i| i as usize >= vertex_count) {
                    return Err(format!(
                        "{here}: index {bad} is out of range ({vertex_count} vertices)"
                    ));
                }
                indices
            }
        };
        let mut triangles = assemble_triangles(mode, &indices);
        if mode == Mode::Triangles && !indices.len().is_multiple_of(3) {
            self.warnings.push(format!(
                "{here}: ignored {} indices after the last whole triangle",
                indices.len() % 3
            ));
        }
        let linear = DMat3::from_mat4(world);
        let mirrored = linear.determinant() < 0.0;
        if mirrored {
            for triangle in &mut triangles {
                triangle.swap(1, 2);
            }
        }

        let file_normals = match primitive.get(&gltf::Semantic::Normals) {
            None => None,
            Some(accessor) => {
                match self.quantized && quantized(&accessor, Dimensions::Vec3, false) {
                    true => check_layout(&accessor),
                    false => check_accessor(&accessor, DataType::F32, Dimensions::Vec3),
                }
                .map_err(|e| format!("{here}: NORMAL {e}"))?;
                // Inverse transpose of the linear part, up to the positive factor |det|:
                // the cofactor matrix, sign-corrected, which stays finite when det = 0.
                let cofactor = DMat3::from_cols(
                    linear.y_axis.cross(linear.z_axis),
                    linear.z_axis.cross(linear.x_axis),
                    linear.x_axis.cross(linear.y_axis),
                ) * if mirrored { -1.0 } else { 1.0 };
                let raw = read_floats::<3>(&accessor, buffers).map_err(|e| format!("{here}: NORMAL {e}"))?;
                // Rejected like a non-finite position (issue 6), not repaired: a NaN normal is a
                // broken export. (Zero normals, which some exporters write, are recomputed.)
                if raw.iter().flatten().any(|c| !c.is_finite()) {
                    return Err(format!("{here}: a NORMAL is not finite (NaN or infinity)"));
                }
                let normals: Vec<Vec3> = raw
                    .into_iter()
                    .map(|n| normals::unit_or_zero((cofactor * DVec3::from(n.map(f64::from))).as_vec3()))
                    .collect();
                if normals.len() == vertex_count {
                    Some(normals)
                } else {
                    self.warnings.push(format!(
                        "{here}: NORMAL has {} entries for {vertex_count} vertices; normals were computed",
                        normals.len()
                    ));
                    None
                }
            }
        };

        let uvs = self.read_uvs(primitive, 0, vertex_count, &here)?;
        let uvs1 = self.read_uvs(primitive, 1, vertex_count, &here)?;
        let colors = self.read_colors(primitive, vertex_count, &here)?;
        let file_tangents = self
            .read_tangents(primitive, vertex_count, &here)?
            .map(|tangents| {
                // Directions transform like edges between positions, by the linear part.
                let handedness = if mirrored { -1.0 } else { 1.0 };
                tangents
                    .into_iter()
                    .map(|t| {
                        let direction = (linear * t.truncate().as_dvec3()).as_vec3();
                        let w = if t.w < 0.0 { -handedness } else { handedness };
                        direction.extend(w)
                    })
                    .collect::<Vec<Vec4>>()
            });
        let material = primitive.material();
        let normal_map_set = material.normal_texture().map(|normal| normal.tex_coord());
        let used_sets = [
            material
                .pbr_metallic_roughness()
                .base_color_texture()
                .map(|info| info.tex_coord()),
            normal_map_set,
        ];
        for set in used_sets.into_iter().flatten() {
            let present = match set {
                0 => uvs.is_some(),
                1 => uvs1.is_some(),
                _ => true, // not bound at all; the material reports it
            };
            if !present && !self.missing_uv_sets.contains(&(here.clone(), set)) {
                self.missing_uv_sets.push((here.clone(), set));
            }
        }

        let attributes = VertexAttributes {
            uvs: uvs.as_deref().unwrap_or_default(),
            uvs1: uvs1.as_deref().unwrap_or_default(),
            colors: colors.as_deref().unwrap_or_default(),
            tangents: file_tangents.as_deref().unwrap_or_default(),
        };
        let mut baked = match file_normals {
            Some(file_normals) => {
                let repaired = normals::repair_normals(
                    &positions,
                    &file_normals,
                    attributes,
                    &triangles,
                    self.crease_angle_degrees,
                );
                self.repaired_normals += repaired.replaced_count;
                repaired.mesh
            }
            None => {
                self.computed_normals = true;
                normals::compute_vertex_normals(&positions, attributes, &triangles, self.crease_angle_degrees)
            }
        };
        if !baked.tangents.is_empty() {
            for (tangent, &normal) in baked.tangents.iter_mut().zip(&baked.normals) {
                *tangent = tangents::orthonormalize_tangent(normal, *tangent);
            }
        } else if let Some(set) = normal_map_set {
            let uvs = if set == 0 { &baked.uvs } else { &baked.uvs1 };
            if !uvs.is_empty() {
                baked.tangents =
                    tangents::compute_tangents(&baked.positions, &baked.normals, uvs, &baked.triangles);
            }
        }
        self.append(
            baked,
            material.index().map_or(self.default_material_index, |i| i as u32),
        )
    }

    /// `TEXCOORD_<set>`, or `None` (with a warning when it exists but cannot be used).
    fn read_uvs(
        &mut self,
        primitive: &gltf::Primitive,
        set: u32,
        vertex_count: usize,
        here: &str,
    ) -> Result<Option<Vec<Vec2>>, String> {
        let Some(accessor) = primitive.get(&gltf::Semantic::TexCoords(set)) else {
            return Ok(None);
        };
        let name = format!("TEXCOORD_{set}");
        let allowed = accessor.dimensions() == Dimensions::Vec2
            && match accessor.data_type() {
                DataType::F32 => true,
                DataType::U8 | DataType::U16 => accessor.normalized() || self.quantized,
                DataType::I8 | DataType::I16 => self.quantized,
                DataType::U32 => false,
            };
        if !allowed {
            self.warn_attribute(
                here,
                &name,
                &accessor,
                "float or normalized unsigned byte/short VEC2",
            );
            return Ok(None);
        }
        let Some(uvs) = self.read_checked(here, &name, &accessor, |accessor, buffers| {
            Ok(read_floats::<2>(accessor, buffers)?
                .into_iter()
                .map(Vec2::from)
                .collect())
        }) else {
            return Ok(None);
        };
        // Rejected like a non-finite position or normal (issue 6): a broken export.
        if !uvs.iter().all(|uv| uv.is_finite()) {
            return Err(format!("{here}: a {name} is not finite (NaN or infinity)"));
        }
        Ok(self.check_count(here, &name, uvs, vertex_count))
    }

    /// `COLOR_0` as linear RGBA, or `None` (with a warning when it exists but cannot be used).
    fn read_colors(
        &mut self,
        primitive: &gltf::Primitive,
        vertex_count: usize,
        here: &str,
    ) -> Result<Option<Vec<Vec4>>, String> {
        let Some(accessor) = primitive.get(&gltf::Semantic::Colors(0)) else {
            return Ok(None);
        };
        let allowed = matches!(accessor.dimensions(), Dimensions::Vec3 | Dimensions::Vec4)
            && match accessor.data_type() {
                DataType::F32 => true,
                DataType::U8 | DataType::U16 => accessor.normalized(),
                _ => false,
            };
        if !allowed {
            self.warn_attribute(
                here,
                "COLOR_0",
                &accessor,
                "float or normalized unsigned byte/short VEC3 or VEC4",
            );
            return Ok(None);
        }
        let Some(colors) = self.read_checked(here, "COLOR_0", &accessor, |accessor, buffers| {
            Ok(match accessor.dimensions() {
                Dimensions::Vec3 => read_floats::<3>(accessor, buffers)?
                    .into_iter()
                    .map(|rgb| Vec3::from(rgb).extend(1.0))
                    .collect(),
                _ => read_floats::<4>(accessor, buffers)?
                    .into_iter()
                    .map(Vec4::from)
                    .collect(),
            })
        }) else {
            return Ok(None);
        };
        if !colors.iter().all(|color| color.is_finite()) {
            return Err(format!("{here}: a COLOR_0 is not finite (NaN or infinity)"));
        }
        Ok(self.check_count(here, "COLOR_0", colors, vertex_count))
    }

    /// `TANGENT` as stored (model space), or `None` (with a warning when it exists but
    /// cannot be used).
    fn read_tangents(
        &mut self,
        primitive: &gltf::Primitive,
        vertex_count: usize,
        here: &str,
    ) -> Result<Option<Vec<Vec4>>, String> {
        let Some(accessor) = primitive.get(&gltf::Semantic::Tangents) else {
            return Ok(None);
        };
        let float = accessor.dimensions() == Dimensions::Vec4 && accessor.data_type() == DataType::F32;
        let allowed = float || (self.quantized && quantized(&accessor, Dimensions::Vec4, false));
        if !allowed {
            self.warn_attribute(here, "TANGENT", &accessor, "float VEC4");
            return Ok(None);
        }
        let Some(tangents) = self.read_checked(here, "TANGENT", &accessor, |accessor, buffers| {
            Ok(read_floats::<4>(accessor, buffers)?
                .into_iter()
                .map(Vec4::from)
                .collect())
        }) else {
            return Ok(None);
        };
        if !tangents.iter().all(|tangent| tangent.is_finite()) {
            return Err(format!("{here}: a TANGENT is not finite (NaN or infinity)"));
        }
        Ok(self.check_count(here, "TANGENT", tangents, vertex_count))
    }

    fn warn_attribute(&mut self, here: &str, name: &str, accessor: &gltf::Accessor, expected: &str) {
        self.warnings.push(format!(
            "{here}: {name} (accessor {}) holds {}{:?} {:?}, but glTF allows {expected}; it is ignored",
            accessor.index(),
            if accessor.normalized() { "normalized " } else { "" },
            accessor.dimensions(),
            accessor.data_type()
        ));
    }

    /// Reads an optional attribute whose type was checked, after checking its layout; `None`
    /// with a warning when the layout is wrong or the data does not lie in its buffer.
    fn read_checked<T>(
        &mut self,
        here: &str,
        name: &str,
        accessor: &gltf::Accessor,
        read: impl FnOnce(&gltf::Accessor, &[Vec<u8>]) -> Result<Vec<T>, String>,
    ) -> Option<Vec<T>> {
        match check_layout(accessor).and_then(|()| read(accessor, self.buffers)) {
            Ok(values) => Some(values),
            Err(problem) => {
                self.warnings
                    .push(format!("{here}: {name} {problem}; it is ignored"));
                None
            }
        }
    }

    fn check_count<T>(
        &mut self,
        here: &str,
        name: &str,
        values: Vec<T>,
        vertex_count: usize,
    ) -> Option<Vec<T>> {
        if values.len() == vertex_count {
            Some(values)
        } else {
            self.warnings.push(format!(
                "{here}: {name} has {} entries for {vertex_count} vertices; it is ignored",
                values.len()
            ));
            None
        }
    }

    /// Appends a baked primitive. Per-vertex arrays that only one side has are filled on the
    /// other (module documentation) so that each stays one entry per vertex.
    fn append(&mut self, part: Mesh, material: u32) -> Result<(), String> {
        let offset = u32::try_from(self.mesh.positions.len())
            .ok()
            .filter(|offset| offset.checked_add(part.positions.len() as u32).is_some())
            .ok_or_else(|| "too many vertices (more than 2³²)".to_string())?;
        let (before, added) = (self.mesh.positions.len(), part.positions.len());
        self.mesh.positions.extend(part.positions);
        self.mesh.normals.extend(part.normals);
        let Mesh {
            normals,
            uvs,
            uvs1,
            colors,
            tangents: merged_tangents,
            ..
        } = &mut self.mesh;
        extend_attribute(uvs, part.uvs, before, added, |_| Vec2::ZERO);
        extend_attribute(uvs1, part.uvs1, before, added, |_| Vec2::ZERO);
        extend_attribute(colors, part.colors, before, added, |_| Vec4::ONE);
        extend_attribute(merged_tangents, part.tangents, before, added, |vertex| {
            tangents::fallback_tangent(normals[vertex])
        });
        self.mesh
            .triangles
            .extend(part.triangles.iter().map(|triangle| triangle.map(|v| v + offset)));
        self.mesh
            .triangle_materials
            .extend(std::iter::repeat_n(material, part.triangles.len()));
        Ok(())
    }
}

/// Appends a part's per-vertex array to the merged one, which had `before` vertices; the part
/// has `added`. When only one side has the array, the other side's vertices get `fill(vertex)`
/// (vertex numbered in the merged mesh).
fn extend_attribute<T>(
    merged: &mut Vec<T>,
    part: Vec<T>,
    before: usize,
    added: usize,
    fill: impl Fn(usize) -> T,
) {
    if merged.is_empty() && part.is_empty() {
        return;
    }
    if merged.is_empty() {
        merged.extend((0..before).map(&fill));
    }
    if part.is_empty() {
        merged.extend((before..before + added).map(&fill));
    } else {
        merged.extend(part);
    }
}

/// Triangles from a primitive's index list, in the glTF spec's vertex order: strip triangle
/// `i` is `(v_i, v_{i+1+i%2}, v_{i+2−i%2})`, fan triangle `i` is `(v_{i+1}, v_{i+2}, v_0)`.
fn assemble_triangles(mode: Mode, indices: &[u32]) -> Vec<[u32; 3]> {
    let spans = indices.len().saturating_sub(2);
    match mode {
        Mode::TriangleStrip => (0..spans)
            .map(|i| [indices[i], indices[i + 1 + i % 2], indices[i + 2 - i % 2]])
            .collect(),
        Mode::TriangleFan => (0..spans)
            .map(|i| [indices[i + 1], indices[i + 2], indices[0]])
            .collect(),
        _ => indices.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
    }
}

/// Whether `accessor` holds `dimensions` of a type `KHR_mesh_quantization` adds: for positions
/// (`any_integer`) every 8- and 16-bit integer, normalized or not; for normals and tangents
/// normalized signed bytes and shorts.
fn quantized(accessor: &gltf::Accessor, dimensions: Dimensions, any_integer: bool) -> bool {
    let signed = matches!(accessor.data_type(), DataType::I8 | DataType::I16);
    let unsigned = matches!(accessor.data_type(), DataType::U8 | DataType::U16);
    accessor.dimensions() == dimensions
        && match any_integer {
            true => signed || unsigned,
            false => signed && accessor.normalized(),
        }
}

/// Checks an accessor before it is read: the element type, a count of at least one, and a
/// stride no smaller than an element.
fn check_accessor(
    accessor: &gltf::Accessor,
    data_type: DataType,
    dimensions: Dimensions,
) -> Result<(), String> {
    if accessor.data_type() != data_type || accessor.dimensions() != dimensions {
        return Err(format!(
            "accessor {} holds {:?} {:?}; expected {:?} {:?}",
            accessor.index(),
            accessor.dimensions(),
            accessor.data_type(),
            dimensions,
            data_type
        ));
    }
    check_layout(accessor)
}

fn check_index_accessor(accessor: &gltf::Accessor) -> Result<(), String> {
    let integer = matches!(accessor.data_type(), DataType::U8 | DataType::U16 | DataType::U32);
    if !integer || accessor.dimensions() != Dimensions::Scalar {
        return Err(format!(
            "accessor {} holds {:?} {:?}; expected unsigned integer scalars",
            accessor.index(),
            accessor.dimensions(),
            accessor.data_type()
        ));
    }
    check_layout(accessor)
}

fn check_layout(accessor: &gltf::Accessor) -> Result<(), String> {
    if accessor.count() == 0 {
        return Err(format!("accessor {} is empty", accessor.index()));
    }
    let too_narrow = accessor
        .view()
        .and_then(|view| view.stride())
        .filter(|&stride| stride < accessor.size());
    if let Some(stride) = too_narrow {
        return Err(format!(
            "accessor {}: stride {stride} is smaller than an element ({} bytes)",
            accessor.index(),
            accessor.size()
        ));
    }
    if accessor.view().is_none() && accessor.sparse().is_none() {
        return Err(format!("accessor {} has no data", accessor.index()));
    }
    Ok(())
}

/// One glTF material as a [`Material`] (module documentation).
fn material_from_gltf(material: &gltf::Material) -> Material {
    let pbr = material.pbr_metallic_roughness();
    let [r, g, b, _alpha] = pbr.base_color_factor();
    let metallic = if pbr.metallic_roughness_texture().is_some() {
        0.0
    } else {
        pbr.metallic_factor()
    };
    let emission = Vec3::from(material.emissive_factor()) * material.emissive_strength().unwrap_or(1.0);
    material_from_factors(Vec3::new(r, g, b), metallic, pbr.roughness_factor(), emission)
}

/// How a material is named in warnings: `'name'`, or `#index` when it has none.
fn material_label(material: &gltf::Material) -> String {
    match material.name() {
        Some(name) => format!("material '{name}'"),
        None => format!("material #{}", material.index().unwrap_or_default()),
    }
}

/// Binds the textures of one glTF material to its lowered [`Material`] (module
/// documentation, "Textures"), loading the images through `images`, and warns about the
/// textures that are not sampled. Materials no drawn triangle uses are left alone: their
/// images are not even read.
fn bind_textures(
    material: &gltf::Material,
    lowered: &mut Material,
    mesh: &Mesh,
    images: &mut ImageLoader,
    warnings: &mut Vec<String>,
) {
    let Some(index) = material.index() else {
        return;
    };
    if !mesh.triangle_materials.contains(&(index as u32)) {
        return;
    }
    let label = material_label(material);
    let pbr = material.pbr_metallic_roughness();
    if let Some(info) = pbr.base_color_texture() {
        let slot = TextureSlot {
            name: "baseColorTexture",
            tex_coord: info.tex_coord(),
            scale: 1.0,
            color_space: ColorSpace::Srgb,
        };
        lowered.textures.diffuse = bind_texture(&label, &slot, &info.texture(), mesh, images, warnings);
    }
    if let Some(normal) = material.normal_texture() {
        let slot = TextureSlot {
            name: "normalTexture",
            tex_coord: normal.tex_coord(),
            scale: normal.scale(),
            color_space: ColorSpace::Linear,
        };
        lowered.textures.normal = bind_texture(&label, &slot, &normal.texture(), mesh, images, warnings);
    }
    if pbr.metallic_roughness_texture().is_some() {
        warnings.push(format!(
            "{label}: its metallicRoughnessTexture is not sampled yet; metallic is taken as 0 and roughness as roughnessFactor ({})",
            pbr.roughness_factor()
        ));
    }
    for (name, present) in [
        ("occlusionTexture", material.occlusion_texture().is_some()),
        ("emissiveTexture", material.emissive_texture().is_some()),
    ] {
        if present {
            warnings.push(format!(
                "{label}: its {name} is not sampled yet; it is drawn without it"
            ));
        }
    }
}

/// What a material asks of one of its textures.
struct TextureSlot {
    /// The glTF property, for warnings.
    name: &'static str,
    tex_coord: u32,
    scale: f32,
    color_space: ColorSpace,
}

/// The binding of one texture of a material, or `None` (after a warning) when its UV set
/// is not available or its image cannot be loaded.
fn bind_texture(
    label: &str,
    slot: &TextureSlot,
    texture: &gltf::Texture,
    mesh: &Mesh,
    images: &mut ImageLoader,
    warnings: &mut Vec<String>,
) -> Option<TextureBinding> {
    let name = slot.name;
    let set = slot.tex_coord;
    let available = match set {
        0 => !mesh.uvs.is_empty(),
        1 => !mesh.uvs1.is_empty(),
        _ => {
            warnings.push(format!(
                "{label}: {name} reads TEXCOORD_{set}, but only TEXCOORD_0 and TEXCOORD_1 are supported; it is not used"
            ));
            return None;
        }
    };
    if !available {
        warnings.push(format!(
            "{label}: {name} reads TEXCOORD_{set}, which no drawn primitive has; it is not used"
        ));
        return None;
    }
    let index = images.texture_index(&texture.source(), slot.color_space)?;
    let sampler = texture.sampler();
    Some(TextureBinding {
        texture: index,
        uv_set: set as u8,
        sampler: Sampler {
            wrap_s: wrap_from_gltf(sampler.wrap_s()),
            wrap_t: wrap_from_gltf(sampler.wrap_t()),
        },
        scale: if slot.scale.is_finite() { slot.scale } else { 1.0 },
    })
}

fn wrap_from_gltf(mode: gltf::texture::WrappingMode) -> Wrap {
    match mode {
        gltf::texture::WrappingMode::Repeat => Wrap::Repeat,
        gltf::texture::WrappingMode::MirroredRepeat => Wrap::MirroredRepeat,
        gltf::texture::WrappingMode::ClampToEdge => Wrap::ClampToEdge,
    }
}

/// Decodes the images that textures use, each once per colour space, and records the files it
/// read or looked for.
struct ImageLoader<'a> {
    buffers: &'a [Vec<u8>],
    access: &'a FileAccess,
    /// The first image the sandbox refused: an error, not a warning.
    refused: Option<String>,
    /// The glTF file's folder, which relative URIs start from.
    directory: &'a Path,
    /// For each (image, colour space) tried: its index in `textures`, or `None` when it
    /// failed (and was reported).
    index_by_image: HashMap<(usize, ColorSpace), Option<u32>>,
    /// Becomes [`Mesh::textures`].
    textures: Vec<Arc<Texture>>,
    files_read: Vec<PathBuf>,
    warnings: Vec<String>,
}

impl ImageLoader<'_> {
    /// The index of `image` decoded in `color_space`, decoding it the first time; `None`
    /// (after one warning naming the image) when it cannot be loaded.
    fn texture_index(&mut self, image: &gltf::Image, color_space: ColorSpace) -> Option<u32> {
        let key = (image.index(), color_space);
        if let Some(&known) = self.index_by_image.get(&key) {
            return known;
        }
        let index = match self.decode(image, color_space) {
            Ok(texture) => {
                self.textures.push(Arc::new(texture));
                Some((self.textures.len() - 1) as u32)
            }
            Err(problem) => {
                self.warnings
                    .push(format!("{problem}; materials using it are drawn without it"));
                None
            }
        };
        self.index_by_image.insert(key, index);
        index
    }

    /// Reads and decodes one image; the error names it (its file, or its index and source).
    fn decode(&mut self, image: &gltf::Image, color_space: ColorSpace) -> Result<Texture, String> {
        let label = match image.name() {
            Some(name) => format!("image {} ('{name}')", image.index()),
            None => format!("image {}", image.index()),
        };
        let (bytes, source): (Cow<[u8]>, String) = match image.source() {
            gltf::image::Source::View { view, .. } => {
                let source = format!("{label} (buffer view {})", view.index());
                let bytes = self
                    .buffers
                    .get(view.buffer().index())
                    .and_then(|buffer| buffer.get(view.offset()..view.offset().checked_add(view.length())?))
                    .ok_or_else(|| format!("{source}: the view lies outside its buffer"))?;
                (Cow::Borrowed(bytes), source)
            }
            gltf::image::Source::Uri { uri, .. } if uri.starts_with("data:") => {
                let source = format!("{label} (data URI)");
                let data = gltf::buffer::Data::from_source(gltf::buffer::Source::Uri(uri), None)
                    .map_err(|error| format!("{source}: cannot decode its data URI: {error}"))?;
                (Cow::Owned(data.0), source)
            }
            gltf::image::Source::Uri { uri, .. } => {
                let relative =
                    percent_decode(uri).ok_or_else(|| format!("{label}: malformed URI '{uri}'"))?;
                if relative.contains(':') {
                    return Err(format!(
                        "{label}: unsupported URI '{uri}' (only relative paths and data: URIs)"
                    ));
                }
                let file = self.directory.join(relative);
                // Recorded even when missing, so that a watcher reloads when it appears.
                if !self.files_read.contains(&file) {
                    self.files_read.push(file.clone());
                }
                return match self.access.read(&file) {
                    Ok(bytes) => {
                        Texture::from_encoded(&bytes, color_space).map(|texture| texture.read_from(&file))
                    }
                    Err(error @ ReadError::OutsideSandbox { .. }) => {
                        let problem = format!("{label} `{uri}`: refused: {error}");
                        self.refused.get_or_insert_with(|| problem.clone());
                        Err(problem)
                    }
                    Err(error) => Err(format!("cannot read it: {error}")),
                }
                .map_err(|problem| format!("texture image {}: {problem}", file.display()));
            }
        };
        Texture::from_encoded(&bytes, color_space).map_err(|problem| format!("{source}: {problem}"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn asset(relative: &str) -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("assets/gltf")
            .join(relative)
    }

    fn load(path: &Path) -> Result<LoadedMesh, MeshError> {
        load_gltf(path, &MeshOptions::default())
    }

    /// Loads an asset, checks the module invariant and the triangle count per node
    /// instance, and returns it.
    fn check_asset(relative: &str, triangles: usize) -> LoadedMesh {
        let loaded = load(&asset(relative)).unwrap_or_else(|e| panic!("{relative}: {e:?}"));
        check_invariant(&loaded.mesh);
        assert_eq!(loaded.mesh.triangle_count(), triangles, "{relative}");
        loaded
    }

    /// The module invariant, as `Mesh::check_invariant` states it (one definition for every
    /// loader and the renderer).
    fn check_invariant(mesh: &Mesh) {
        mesh.check_invariant()
            .unwrap_or_else(|e| panic!("invariant: {e}"));
    }

    /// Expects loading `path` to fail with a message containing `message`.
    fn check_error(path: &Path, message: &str) {
        match load(path) {
            Ok(loaded) => panic!(
                "expected an error, loaded {} triangles",
                loaded.mesh.triangle_count()
            ),
            Err(error) => assert!(
                error.message.contains(message),
                "{error:?} should contain {message:?}"
            ),
        }
    }

    #[test]
    fn triangle_counts_per_node_instance() {
        // assets/LICENSES.md counts triangles per mesh; these count per node instance of
        // the drawn scene, so they differ where a mesh is used twice or a scene is skipped:
        check_asset("Avocado/glTF/Avocado.gltf", 682);
        check_asset("Box/glTF/Box.gltf", 12);
        check_asset("Box/glTF-Binary/Box.glb", 12);
        check_asset("Box/glTF-Embedded/Box.gltf", 12);
        check_asset("BoxInterleaved/glTF/BoxInterleaved.gltf", 12);
        check_asset("BoxInterleaved/glTF-Binary/BoxInterleaved.glb", 12);
        check_asset("BoxTextured/glTF/BoxTextured.gltf", 12);
        check_asset("BoxTextured/glTF-Binary/BoxTextured.glb", 12);
        // Mesh 0 (a square) under a rotated node; the cameras carry no mesh.
        check_asset("Cameras/glTF/Cameras.gltf", 2);
        check_asset("Duck/glTF/Duck.gltf", 4212);
        check_asset("Duck/glTF-Binary/Duck.glb", 4212);
        // The default scene is scene 1 ("scene": 1), holding only the square (2
        // triangles); the table's 3 adds the triangle of scene 0, which is not drawn.
        check_asset("MultipleScenes/glTF/MultipleScenes.gltf", 2);
        // 13 nodes, each with its own mesh: per instance equals per mesh.
        check_asset("OrientationTest/glTF/OrientationTest.gltf", 524);
        check_asset("OrientationTest/glTF-Binary/OrientationTest.glb", 524);
        // One 1-triangle mesh used by two nodes: 2 instances.
        check_asset("SimpleMeshes/glTF/SimpleMeshes.gltf", 2);
        // 5 nodes, each with its own 2-triangle mesh.
        check_asset("TextureCoordinateTest/glTF-Binary/TextureCoordinateTest.glb", 10);
        check_asset(
            "TextureCoordinateTest/glTF-Embedded/TextureCoordinateTest.gltf",
            10,
        );
        check_asset("Triangle/glTF/Triangle.gltf", 1);
        check_asset("Triangle/glTF-Embedded/Triangle.gltf", 1);
        check_asset("TriangleWithoutIndices/glTF/TriangleWithoutIndices.gltf", 1);
        check_asset(
            "TriangleWithoutIndices/glTF-Embedded/TriangleWithoutIndices.gltf",
            1,
        );
    }

    #[test]
    fn box_variants_give_identical_meshes() {
        let external = check_asset("Box/glTF/Box.gltf", 12);
        for other in ["Box/glTF-Binary/Box.glb", "Box/glTF-Embedded/Box.gltf"] {
            assert_eq!(check_asset(other, 12).mesh, external.mesh, "{other}");
        }
        assert_eq!(
            check_asset("BoxInterleaved/glTF/BoxInterleaved.gltf", 12)
                .mesh
                .bounds(),
            external.mesh.bounds()
        );
    }

    #[test]
    fn files_read_lists_external_buffers_only() {
        let external = check_asset("Box/glTF/Box.gltf", 12);
        assert_eq!(
            external.files_read,
            vec![asset("Box/glTF/Box.gltf"), asset("Box/glTF/Box0.bin")]
        );
        let binary = check_asset("Box/glTF-Binary/Box.glb", 12);
        assert_eq!(binary.files_read, vec![asset("Box/glTF-Binary/Box.glb")]);
        let embedded = check_asset("Box/glTF-Embedded/Box.gltf", 12);
        assert_eq!(embedded.files_read, vec![asset("Box/glTF-Embedded/Box.gltf")]);
    }

    #[test]
    fn box_material_maps_metallic_roughness() {
        let loaded = check_asset("Box/glTF/Box.gltf", 12);
        // "Red": baseColorFactor 0.8 0 0, metallic 0, roughness 1 (default).
        assert_eq!(loaded.mesh.materials.len(), 1, "every primitive has a material");
        let red = loaded.mesh.materials[0];
        assert_eq!(
            (red.diffuse, red.ambient),
            (Vec3::new(0.8, 0.0, 0.0), Vec3::new(0.8, 0.0, 0.0))
        );
        assert!(red.specular.distance(Vec3::splat(0.04)) < 1e-7);
        let expected = Microfacet {
            roughness: 1.0,
            fresnel: Vec3::splat(0.04),
            distribution: MicrofacetDistribution::Ggx,
        };
        assert_eq!(red.model, LightingModel::CookTorrance(expected));
        assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
    }

    #[test]
    fn primitives_without_material_use_the_gltf_default() {
        let loaded = check_asset("Triangle/glTF/Triangle.gltf", 1);
        assert_eq!(loaded.mesh.materials, vec![default_material()]);
        let white_metal = default_material();
        // A metal: no diffuse term, F0 = the base colour.
        assert_eq!(
            (white_metal.diffuse, white_metal.specular, white_metal.ambient),
            (Vec3::ZERO, Vec3::ONE, Vec3::ONE)
        );
    }

    #[test]
    fn metallic_roughness_texture_warns_and_is_not_a_metal() {
        let loaded = check_asset("Avocado/glTF/Avocado.gltf", 682);
        let avocado = loaded.mesh.materials[0];
        assert!(
            avocado.specular.distance(Vec3::splat(0.04)) < 1e-7,
            "metallicRoughnessTexture: metallic 0"
        );
        assert_eq!(loaded.warnings.len(), 1, "{:?}", loaded.warnings);
        assert!(
            loaded.warnings[0].contains("metallicRoughnessTexture is not sampled"),
            "{:?}",
            loaded.warnings
        );
        // Without that texture, no such warning.
        let duck = check_asset("Duck/glTF/Duck.gltf", 4212);
        assert!(duck.warnings.is_empty(), "{:?}", duck.warnings);
    }

    #[test]
    fn roughness_maps_to_blinn_phong_exponent() {
        assert_eq!(blinn_phong_exponent(1.0), 1.0, "2/1 - 2 = 0, clamped up");
        assert_eq!(blinn_phong_exponent(0.5), 30.0, "α = 0.25, 2/0.0625 - 2");
        assert_eq!(blinn_phong_exponent(0.0), 1000.0);
        assert_eq!(blinn_phong_exponent(f32::NAN), 1.0);
        assert!(blinn_phong_exponent(0.3) > blinn_phong_exponent(0.4));
    }

    #[test]
    fn node_transforms_are_applied() {
        // Duck: the root node scales by 0.01; the raw positions reach about ±100.
        let duck = check_asset("Duck/glTF/Duck.gltf", 4212);
        let (lo, hi) = duck.mesh.bounds().unwrap_or_default();
        assert!(lo.min_element() > -2.0 && hi.max_element() < 2.0, "{lo} {hi}");
        assert!(hi.max_element() > 0.5, "{lo} {hi}");
        // SimpleMeshes: the triangle spans [0, 1]² in XY, and the second node moves it by +1 in x.
        let simple = check_asset("SimpleMeshes/glTF/SimpleMeshes.gltf", 2);
        assert_eq!(simple.mesh.bounds(), Some((Vec3::ZERO, Vec3::new(2.0, 1.0, 0.0))));
    }

    #[test]
    fn cameras_sample_gives_both_cameras_in_model_space() {
        let loaded = check_asset("Cameras/glTF/Cameras.gltf", 2);
        assert!(loaded.lights.is_empty());
        assert_eq!(loaded.cameras.len(), 2);
        for (index, camera) in loaded.cameras.iter().enumerate() {
            assert_eq!(camera.index, index);
            assert_eq!(
                (camera.name.as_deref(), camera.node_name.as_deref()),
                (None, None)
            );
            assert!((camera.eye - DVec3::new(0.5, 0.5, 3.0)).length() < 1e-6);
            assert_eq!((camera.forward, camera.up), (DVec3::NEG_Z, DVec3::Y));
        }
        let ImportedProjection::Perspective {
            fov_y_degrees,
            near,
            far,
        } = loaded.cameras[0].projection
        else {
            panic!("{:?}", loaded.cameras[0])
        };
        assert!((fov_y_degrees - 40.107).abs() < 1e-3, "0.7 rad: {fov_y_degrees}");
        assert!((near - 0.01).abs() < 1e-6 && far == Some(100.0));
        let ImportedProjection::Orthographic { height, near, far } = loaded.cameras[1].projection else {
            panic!("{:?}", loaded.cameras[1])
        };
        assert!((height - 2.0).abs() < 1e-9 && (near - 0.01).abs() < 1e-6 && far == 100.0);
        // The Duck's camera hangs under the root node, which scales by 0.01: so do its
        // position and depth range.
        let duck = check_asset("Duck/glTF/Duck.gltf", 4212);
        assert!(duck.lights.is_empty());
        assert_eq!(duck.cameras.len(), 1);
        let camera = &duck.cameras[0];
        assert!(
            (camera.eye - DVec3::new(4.00113, 4.63264, -4.31078)).length() < 1e-4,
            "{camera:?}"
        );
        let ImportedProjection::Perspective { near, far, .. } = camera.projection else {
            panic!("{camera:?}")
        };
        assert!(
            (near - 0.01).abs() < 1e-6 && (far.unwrap() - 100.0).abs() < 1e-3,
            "{camera:?}"
        );
    }

    #[test]
    fn camera_and_light_nodes_follow_the_hierarchy_and_scale_distances() {
        let dir = scratch_dir();
        let down = "[-0.70710678, 0, 0, 0.70710678]";
        let nodes = format!(
            r#"[{{"mesh": 0, "children": [1]}},
            {{"translation": [0, 0, 5], "scale": [2, 2, 2], "children": [2, 3]}},
            {{"name": "Top", "camera": 0, "translation": [0, 3, 0], "rotation": {down}}},
            {{"extensions": {{"KHR_lights_punctual": {{"light": 0}}}}, "rotation": {down}}}]"#
        );
        let extra = r#""extensionsUsed": ["KHR_lights_punctual"],
            "cameras": [{"type": "orthographic", "name": "Plan", "orthographic": {"xmag": 1, "ymag": 1.5, "znear": 0, "zfar": 10}}],
            "extensions": {"KHR_lights_punctual": {"lights": [
                {"type": "spot", "range": 4, "spot": {"innerConeAngle": 0.7853982, "outerConeAngle": 0.7853982}}
            ]}},"#;
        let blocks = [Block::Vec3(&SQUARE), Block::Indices(&[0, 1, 2, 2, 1, 3])];
        let path = write_fixture(dir.path(), &blocks, TRIANGLES, &nodes, extra);
        let loaded = load(&path).unwrap();
        let camera = &loaded.cameras[0];
        assert_eq!(
            (camera.name.as_deref(), camera.node_name.as_deref()),
            (Some("Plan"), Some("Top"))
        );
        assert!(
            (camera.eye - DVec3::new(0.0, 6.0, 5.0)).length() < 1e-6,
            "{camera:?}"
        );
        assert!((camera.forward - DVec3::NEG_Y).length() < 1e-6, "{camera:?}");
        assert!((camera.up - DVec3::NEG_Z).length() < 1e-6, "{camera:?}");
        let ImportedProjection::Orthographic { height, near, far } = camera.projection else {
            panic!("{camera:?}")
        };
        assert!(
            (height - 6.0).abs() < 1e-5 && near == 0.0 && (far - 20.0).abs() < 1e-5,
            "{camera:?}"
        );
        let light = &loaded.lights[0];
        assert_eq!(
            light.kind,
            ImportedLightKind::Spot {
                inner_cone_degrees: 45.0,
                outer_cone_degrees: 45.0
            }
        );
        assert!((light.position - DVec3::new(0.0, 0.0, 5.0)).length() < 1e-6);
        assert!((light.direction - DVec3::NEG_Y).length() < 1e-6);
        assert_eq!((light.color, light.range), (Vec3::ONE, Some(4.0)));
        assert!(
            loaded
                .warnings
                .iter()
                .any(|w| w.contains("lights 0 have a `range`, which is not applied")),
            "{:?}",
            loaded.warnings
        );
    }

    #[test]
    fn duck_normals_point_away_from_its_body() {
        let duck = check_asset("Duck/glTF-Binary/Duck.glb", 4212);
        let mesh = &duck.mesh;
        let agreeing = mesh
            .triangles
            .iter()
            .filter(|t| {
                let [a, b, c] = t.map(|v| mesh.positions[v as usize]);
                let face = normals::face_normal(a, b, c);
                t.iter().all(|&v| mesh.normals[v as usize].dot(face) > 0.0)
            })
            .count();
        assert!(
            agreeing * 100 > mesh.triangles.len() * 95,
            "{agreeing} of {}",
            mesh.triangles.len()
        );
    }

    #[test]
    fn broken_binary_files_say_what_is_wrong_with_sizes() {
        let dir = scratch_dir();
        let glb = std::fs::read(asset("Box/glTF-Binary/Box.glb")).unwrap_or_default();
        let length = glb.len();
        let with = |at: usize, bytes: &[u8]| {
            let mut changed = glb.clone();
            changed[at..at + bytes.len()].copy_from_slice(bytes);
            changed
        };
        let json_length = u32::from_le_bytes([glb[12], glb[13], glb[14], glb[15]]) as usize;
        let cases: Vec<(Vec<u8>, String)> = vec![
            (
                b"glTF\x02\x00\x00\x00\xff\xff".to_vec(),
                "the file has 10 bytes, less than the 12-byte GLB header".into(),
            ),
            (
                glb[..length / 2].to_vec(),
                format!(
                    "the header says {length} bytes, the file has {}: it is truncated",
                    length / 2
                ),
            ),
            (
                [glb.as_slice(), &[0; 8]].concat(),
                format!(
                    "the header says {length} bytes, the file has {}: it is damaged",
                    length + 8
                ),
            ),
            (with(4, &[1, 0, 0, 0]), "version 1: only version 2".into()),
            (
                with(12, &(length as u32).to_le_bytes()),
                format!(
                    "the `JSON` chunk at byte 12 says {length} bytes, but only {} follow it",
                    length - 20
                ),
            ),
            (
                with(16, b"XML\0"),
                "the first chunk has the type `XML\\0`, expected `JSON`".into(),
            ),
            (
                with(20 + json_length, &[0xff, 0xff, 0, 0]),
                format!("chunk at byte {} says 65535 bytes", 20 + json_length),
            ),
            (
                b"glTF\x02\x00\x00\x00\x0c\x00\x00\x00".to_vec(),
                "a header but no JSON chunk".into(),
            ),
            (
                b"glTF\x02\x00\x00\x00\x10\x00\x00\x00JSON".to_vec(),
                "chunk 0 at byte 12 has 4 bytes left for its 8-byte header".into(),
            ),
        ];
        for (bytes, message) in cases {
            let path = write(dir.path(), "broken.glb", &bytes);
            let error = load(&path).err().unwrap_or_else(|| panic!("{message}: loaded"));
            assert!(
                error.message.contains(&message),
                "{error:?} should contain {message:?}"
            );
            assert!(
                error.message.starts_with("broken binary glTF") || error.message.starts_with("binary glTF")
            );
            assert_eq!(error.hint, None, "a damaged GLB is not an OBJ: {message}");
        }
        check_error(
            &dir.path().join("missing.glb"),
            "cannot read mesh file: no such file",
        );
    }

    #[test]
    fn files_that_are_not_gltf_say_what_they_are() {
        let dir = scratch_dir();
        let cases: [(&[u8], &str); 4] = [
            (
                b"# exported\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
                "this is an OBJ file (text with `v` and `f` lines), not a glTF file",
            ),
            (
                b"gLTF\x02\x00\x00\x00\x10\x00\x00\x00\x00\x00\x00\x00",
                "binary file starting with 67 4C 54 46 (\"gLTF\"), not glTF",
            ),
            (
                b"solid cube\nendsolid\n",
                "text file with neither OBJ statements nor JSON starting with 73 6F 6C 69",
            ),
            (b"", "the file is empty"),
        ];
        for (bytes, message) in cases {
            let path = write(dir.path(), "mesh.glb", bytes);
            let error = load(&path).err().unwrap_or_else(|| panic!("{message}: loaded"));
            assert!(
                error.message.contains(message),
                "{error:?} should contain {message:?}"
            );
            assert!(error.hint.is_some_and(|hint| hint.contains("Obj(")), "{message}");
        }
    }

    // Synthetic files: one mesh with the given primitives, accessor i holding data block i,
    // written with an external .bin.

    fn scratch_dir() -> tempfile::TempDir {
        tempfile::Builder::new()
            .prefix("lampshade-gltf-test")
            .tempdir()
            .unwrap_or_else(|e| panic!("cannot create a temporary directory: {e}"))
    }

    fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
        let path = dir.join(name);
        std::fs::write(&path, bytes).unwrap_or_else(|e| panic!("cannot write {}: {e}", path.display()));
        path
    }

    /// One accessor's data.
    #[derive(Clone, Copy)]
    enum Block<'a> {
        Vec3(&'a [[f32; 3]]),
        Indices(&'a [u32]),
        /// Floats of the given accessor type ("VEC2", "VEC4").
        Floats(&'a [f32], &'static str),
        /// Normalized unsigned bytes of the given accessor type.
        Bytes(&'a [u8], &'static str),
        /// Normalized unsigned shorts of the given accessor type.
        Shorts(&'a [u16], &'static str),
    }

    /// Components per element of an accessor type.
    fn components(kind: &str) -> usize {
        match kind {
            "SCALAR" => 1,
            "VEC2" => 2,
            "VEC3" => 3,
            _ => 4,
        }
    }

    /// Writes `fixture.gltf` and `fixture.bin`, each block in its own buffer view and
    /// accessor. `primitives` and `nodes` are JSON arrays; `extra` is more top-level JSON
    /// members, each followed by a comma.
    fn write_fixture(dir: &Path, blocks: &[Block], primitives: &str, nodes: &str, extra: &str) -> PathBuf {
        let mut bin = Vec::new();
        let mut views = Vec::new();
        let mut accessors = Vec::new();
        for (index, block) in blocks.iter().enumerate() {
            let offset = bin.len();
            let accessor = match block {
                Block::Vec3(vectors) => {
                    bin.extend(vectors.iter().flatten().flat_map(|c| c.to_le_bytes()));
                    let (lo, hi) = vectors
                        .iter()
                        .fold(([f32::MAX; 3], [f32::MIN; 3]), |(lo, hi), p| {
                            (
                                [0, 1, 2].map(|k| lo[k].min(p[k])),
                                [0, 1, 2].map(|k| hi[k].max(p[k])),
                            )
                        });
                    format!(
                        r#"{{"bufferView": {index}, "componentType": 5126, "count": {}, "type": "VEC3", "min": {lo:?}, "max": {hi:?}}}"#,
                        vectors.len()
                    )
                }
                Block::Indices(indices) => {
                    bin.extend(indices.iter().flat_map(|i| i.to_le_bytes()));
                    format!(
                        r#"{{"bufferView": {index}, "componentType": 5125, "count": {}, "type": "SCALAR"}}"#,
                        indices.len()
                    )
                }
                Block::Floats(values, kind) => {
                    bin.extend(values.iter().flat_map(|v| v.to_le_bytes()));
                    format!(
                        r#"{{"bufferView": {index}, "componentType": 5126, "count": {}, "type": "{kind}"}}"#,
                        values.len() / components(kind)
                    )
                }
                Block::Bytes(values, kind) => {
                    bin.extend(values.iter());
                    format!(
                        r#"{{"bufferView": {index}, "componentType": 5121, "normalized": true, "count": {}, "type": "{kind}"}}"#,
                        values.len() / components(kind)
                    )
                }
                Block::Shorts(values, kind) => {
                    bin.extend(values.iter().flat_map(|v| v.to_le_bytes()));
                    format!(
                        r#"{{"bufferView": {index}, "componentType": 5123, "normalized": true, "count": {}, "type": "{kind}"}}"#,
                        values.len() / components(kind)
                    )
                }
            };
            views.push(format!(
                r#"{{"buffer": 0, "byteOffset": {offset}, "byteLength": {}}}"#,
                bin.len() - offset
            ));
            accessors.push(accessor);
            // Every view starts 4-byte aligned, as glTF requires of vertex attributes.
            bin.resize(bin.len().next_multiple_of(4), 0);
        }
        write(dir, "fixture.bin", &bin);
        let json = format!(
            r#"{{
  "asset": {{"version": "2.0"}}, {extra}
  "scene": 0,
  "scenes": [{{"nodes": [0]}}],
  "nodes": {nodes},
  "meshes": [{{"primitives": {primitives}}}],
  "buffers": [{{"uri": "fixture.bin", "byteLength": {}}}],
  "bufferViews": [{}],
  "accessors": [{}]
}}"#,
            bin.len(),
            views.join(", "),
            accessors.join(", "),
        );
        write(dir, "fixture.gltf", json.as_bytes())
    }

    const SQUARE: [[f32; 3]; 4] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]];
    const ONE_NODE: &str = r#"[{"mesh": 0}]"#;
    const TRIANGLES: &str = r#"[{"attributes": {"POSITION": 0}, "indices": 1}]"#;

    /// Loads a fixture and checks that every triangle faces +Z (geometric and vertex
    /// normals), returning the mesh.
    fn check_faces_up(path: &Path, triangles: usize) -> LoadedMesh {
        let loaded = load(path).unwrap_or_else(|e| panic!("{e:?}"));
        check_invariant(&loaded.mesh);
        let mesh = &loaded.mesh;
        assert_eq!(mesh.triangle_count(), triangles);
        for t in &mesh.triangles {
            let [a, b, c] = t.map(|v| mesh.positions[v as usize]);
            assert_eq!(normals::face_normal(a, b, c), Vec3::Z, "triangle {t:?}");
            assert!(t.iter().all(|&v| mesh.normals[v as usize] == Vec3::Z));
        }
        loaded
    }

    #[test]
    fn strips_keep_alternate_triangles_counter_clockwise() {
        let dir = scratch_dir();
        // Strip 0 1 2 3 over the square: (0 1 2) then (2 1 3) in spec order, both facing +Z.
        let path = write_fixture(
            dir.path(),
            &[Block::Vec3(&SQUARE), Block::Indices(&[0, 1, 2, 3])],
            r#"[{"attributes": {"POSITION": 0}, "indices": 1, "mode": 5}]"#,
            ONE_NODE,
            "",
        );
        check_faces_up(&path, 2);
    }

    #[test]
    fn fans_become_triangles() {
        let dir = scratch_dir();
        let path = write_fixture(
            dir.path(),
            &[Block::Vec3(&SQUARE), Block::Indices(&[0, 1, 3, 2])],
            r#"[{"attributes": {"POSITION": 0}, "indices": 1, "mode": 6}]"#,
            ONE_NODE,
            "",
        );
        check_faces_up(&path, 2);
    }

    #[test]
    fn non_indexed_triangles_and_skipped_points() {
        let dir = scratch_dir();
        let positions = [SQUARE[0], SQUARE[1], SQUARE[3]];
        let primitives = r#"[{"attributes": {"POSITION": 0}}, {"attributes": {"POSITION": 0}, "mode": 0}]"#;
        let loaded = check_faces_up(
            &write_fixture(dir.path(), &[Block::Vec3(&positions)], primitives, ONE_NODE, ""),
            1,
        );
        assert!(
            loaded
                .warnings
                .iter()
                .any(|w| w.contains("skipped 1 point or line")),
            "{:?}",
            loaded.warnings
        );
        assert_eq!(
            loaded.files_read,
            vec![dir.path().join("fixture.gltf"), dir.path().join("fixture.bin")]
        );
    }

    #[test]
    fn mirroring_node_keeps_front_faces_counter_clockwise() {
        let dir = scratch_dir();
        let facing_down = [SQUARE[0], SQUARE[2], SQUARE[1]];
        let primitive = r#"[{"attributes": {"POSITION": 0}}]"#;
        // A mirror in z turns the triangle to face +Z: the winding must be reversed and
        // the computed normals follow.
        let mirror_z = r#"[{"mesh": 0, "scale": [1, 1, -1]}]"#;
        check_faces_up(
            &write_fixture(dir.path(), &[Block::Vec3(&facing_down)], primitive, mirror_z, ""),
            1,
        );
        // The same with file normals, which go through the inverse transpose.
        let down = [[0.0, 0.0, -1.0]; 3];
        let with_normals = r#"[{"attributes": {"POSITION": 0, "NORMAL": 1}}]"#;
        let path = write_fixture(
            dir.path(),
            &[Block::Vec3(&facing_down), Block::Vec3(&down)],
            with_normals,
            mirror_z,
            "",
        );
        check_faces_up(&path, 1);
        // A mirror in x leaves z alone: the triangle keeps facing -Z once rewound.
        let mirror_x = r#"[{"mesh": 0, "scale": [-1, 1, 1]}]"#;
        let path = write_fixture(
            dir.path(),
            &[Block::Vec3(&facing_down), Block::Vec3(&down)],
            with_normals,
            mirror_x,
            "",
        );
        let loaded = load(&path).unwrap_or_else(|e| panic!("{e:?}"));
        let [a, b, c] = loaded.mesh.triangles[0].map(|v| loaded.mesh.positions[v as usize]);
        assert_eq!(normals::face_normal(a, b, c), -Vec3::Z);
        assert!(loaded.mesh.normals.iter().all(|&n| n == -Vec3::Z));
    }

    #[test]
    fn out_of_range_index_is_an_error() {
        let dir = scratch_dir();
        let path = write_fixture(
            dir.path(),
            &[Block::Vec3(&SQUARE), Block::Indices(&[0, 1, 7])],
            TRIANGLES,
            ONE_NODE,
            "",
        );
        check_error(&path, "index 7 is out of range (4 vertices)");
    }

    #[test]
    fn unsupported_required_extension_is_named() {
        let dir = scratch_dir();
        let extra = r#""extensionsUsed": ["KHR_draco_mesh_compression"], "extensionsRequired": ["KHR_draco_mesh_compression"],"#;
        let path = write_fixture(
            dir.path(),
            &[Block::Vec3(&SQUARE), Block::Indices(&[0, 1, 2])],
            TRIANGLES,
            ONE_NODE,
            extra,
        );
        check_error(&path, "requires the glTF extension KHR_draco_mesh_compression");
    }

    #[test]
    fn cyclic_node_hierarchy_is_an_error() {
        let dir = scratch_dir();
        let nodes = r#"[{"children": [1]}, {"children": [0], "mesh": 0}]"#;
        let path = write_fixture(
            dir.path(),
            &[Block::Vec3(&SQUARE), Block::Indices(&[0, 1, 2])],
            TRIANGLES,
            nodes,
            "",
        );
        check_error(&path, "node");
    }

    #[test]
    fn attribute_naming_a_missing_accessor_is_an_error_not_a_panic() {
        // gltf-json's own validation would index past the end here.
        let dir = scratch_dir();
        let json =
            r#"{"asset": {"version": "2.0"}, "meshes": [{"primitives": [{"attributes": {"POSITION": 5}}]}]}"#;
        let path = write(dir.path(), "missing-accessor.gltf", json.as_bytes());
        check_error(&path, "mesh 0 primitive 0 refers to accessor 5, but there are 0");
    }

    #[test]
    fn missing_buffer_file_is_named() {
        let dir = scratch_dir();
        let path = write_fixture(
            dir.path(),
            &[Block::Vec3(&SQUARE), Block::Indices(&[0, 1, 2])],
            TRIANGLES,
            ONE_NODE,
            "",
        );
        std::fs::remove_file(dir.path().join("fixture.bin")).unwrap_or_else(|e| panic!("{e}"));
        check_error(&path, "cannot read buffer file");
        check_error(&path, "fixture.bin: no such file");
    }

    #[test]
    fn percent_encoded_uris_are_decoded() {
        assert_eq!(percent_decode("my%20model.bin").as_deref(), Some("my model.bin"));
        assert_eq!(percent_decode("plain.bin").as_deref(), Some("plain.bin"));
        assert_eq!(percent_decode("bad%2").as_deref(), None);
        assert_eq!(percent_decode("bad%FF.bin").as_deref(), None, "not UTF-8");
    }

    // Vertex attributes and textures.

    /// A 2×2 PNG written to `dir/name`: (188, 0, 0), green / blue, white. 188 tells the
    /// colour spaces apart: about 0.5029 decoded as sRGB, 188/255 ≈ 0.737 as data.
    fn write_png(dir: &Path, name: &str) {
        let pixels = image::RgbImage::from_raw(2, 2, vec![188, 0, 0, 0, 255, 0, 0, 0, 255, 255, 255, 255])
            .unwrap_or_else(|| panic!("pixel buffer size"));
        pixels
            .save(dir.join(name))
            .unwrap_or_else(|e| panic!("cannot write {name}: {e}"));
    }

    /// Checks per-vertex arrays against positions and that the texture at `index` has the
    /// given size and a full mip chain.
    fn check_texture(mesh: &Mesh, index: u32, width: u32, height: u32) {
        let texture = &mesh.textures[index as usize];
        assert_eq!((texture.width(), texture.height()), (width, height));
        let expected_levels = 1 + width.max(height).ilog2() as usize;
        assert_eq!(texture.levels.len(), expected_levels);
        let last = &texture.levels[expected_levels - 1];
        assert_eq!((last.width, last.height), (1, 1));
    }

    #[test]
    fn box_textured_binds_its_texture_from_a_file_and_from_the_glb() {
        let external = check_asset("BoxTextured/glTF/BoxTextured.gltf", 12);
        let binary = check_asset("BoxTextured/glTF-Binary/BoxTextured.glb", 12);
        for loaded in [&external, &binary] {
            let mesh = &loaded.mesh;
            assert_eq!(mesh.uvs.len(), mesh.positions.len());
            assert!(mesh.uvs1.is_empty() && mesh.colors.is_empty() && mesh.tangents.is_empty());
            assert_eq!(mesh.textures.len(), 1);
            // CesiumLogoFlat.png is 256×256: levels 256, 128, ..., 1.
            check_texture(mesh, 0, 256, 256);
            let binding = mesh.materials[0]
                .textures
                .diffuse
                .unwrap_or_else(|| panic!("bound"));
            // The file's sampler: wrapS = wrapT = 10497 (REPEAT).
            assert_eq!((binding.texture, binding.uv_set), (0, 0));
            assert_eq!(binding.sampler, Sampler::default());
            assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
        }
        // The same texels; only the external image has a file to name.
        assert_eq!(
            external.mesh.textures[0].levels, binary.mesh.textures[0].levels,
            "same image, same texels"
        );
        assert_eq!(
            external.files_read,
            vec![
                asset("BoxTextured/glTF/BoxTextured.gltf"),
                asset("BoxTextured/glTF/BoxTextured0.bin"),
                asset("BoxTextured/glTF/CesiumLogoFlat.png"),
            ]
        );
        assert_eq!(
            binary.files_read,
            vec![asset("BoxTextured/glTF-Binary/BoxTextured.glb")]
        );
    }

    #[test]
    fn duck_base_color_texture_is_bound() {
        for relative in ["Duck/glTF/Duck.gltf", "Duck/glTF-Binary/Duck.glb"] {
            let loaded = check_asset(relative, 4212);
            let mesh = &loaded.mesh;
            assert_eq!(mesh.uvs.len(), mesh.positions.len(), "{relative}");
            let binding = mesh.materials[0]
                .textures
                .diffuse
                .unwrap_or_else(|| panic!("{relative}: bound"));
            check_texture(mesh, binding.texture, 512, 512);
            assert_eq!(mesh.materials[0].textures.normal, None);
        }
    }

    #[test]
    fn avocado_normal_map_is_bound_with_unit_perpendicular_tangents() {
        let loaded = check_asset("Avocado/glTF/Avocado.gltf", 682);
        let mesh = &loaded.mesh;
        let textures = mesh.materials[0].textures;
        let base = textures
            .diffuse
            .unwrap_or_else(|| panic!("baseColorTexture bound"));
        let normal = textures.normal.unwrap_or_else(|| panic!("normalTexture bound"));
        assert_ne!(base.texture, normal.texture);
        assert_eq!((normal.uv_set, normal.scale), (0, 1.0));
        check_texture(mesh, base.texture, 512, 512);
        check_texture(mesh, normal.texture, 512, 512);
        // The base colour is sRGB-decoded, the normal map kept linear: a flat normal map
        // averages near (0.5, 0.5, 1), which sRGB decoding would pull down to about 0.21.
        let normal_mean = mesh.textures[normal.texture as usize]
            .levels
            .last()
            .map(|l| l.texels[0]);
        let normal_mean = normal_mean.unwrap_or_default();
        assert!(
            normal_mean.x > 0.4 && normal_mean.y > 0.4 && normal_mean.z > 0.8,
            "{normal_mean}"
        );
        assert_eq!(mesh.tangents.len(), mesh.positions.len());
        for (tangent, normal) in mesh.tangents.iter().zip(&mesh.normals) {
            assert!((tangent.truncate().length() - 1.0).abs() < 1e-5);
            assert!(tangent.truncate().dot(*normal).abs() < 1e-5);
            assert!(tangent.w.abs() == 1.0);
        }
        // Only the used images are read: not the metallic-roughness one.
        let directory = asset("Avocado/glTF");
        assert_eq!(
            loaded.files_read,
            vec![
                directory.join("Avocado.gltf"),
                directory.join("Avocado.bin"),
                directory.join("Avocado_baseColor.png"),
                directory.join("Avocado_normal.png"),
            ]
        );
    }

    #[test]
    fn computed_tangents_agree_with_the_exported_ones() {
        // Avocado's exporter wrote tangents; the ones computed from its UVs must point the
        // same way with the same handedness, or normal maps would light from the wrong side.
        let mesh = check_asset("Avocado/glTF/Avocado.gltf", 682).mesh;
        let computed = tangents::compute_tangents(&mesh.positions, &mesh.normals, &mesh.uvs, &mesh.triangles);
        let agreeing = computed
            .iter()
            .zip(&mesh.tangents)
            .filter(|(c, f)| c.w == f.w && c.truncate().dot(f.truncate()) > 0.9)
            .count();
        assert!(
            agreeing * 100 >= mesh.tangents.len() * 95,
            "{agreeing} of {}",
            mesh.tangents.len()
        );
    }

    #[test]
    fn texture_coordinate_test_reads_images_from_data_uris_and_buffer_views() {
        for relative in [
            "TextureCoordinateTest/glTF-Embedded/TextureCoordinateTest.gltf",
            "TextureCoordinateTest/glTF-Binary/TextureCoordinateTest.glb",
        ] {
            let loaded = check_asset(relative, 10);
            let mesh = &loaded.mesh;
            assert!(loaded.warnings.is_empty(), "{relative}: {:?}", loaded.warnings);
            // The back plane has no TEXCOORD_0 (and no texture): its vertices get zeros.
            assert_eq!(mesh.uvs.len(), mesh.positions.len(), "{relative}");
            // Four materials share texture 0 (one image); the back plane's has none.
            assert_eq!(mesh.textures.len(), 1, "{relative}");
            let bound: Vec<_> = mesh.materials.iter().filter_map(|m| m.textures.diffuse).collect();
            assert_eq!(bound.len(), 4, "{relative}");
            // The file's only sampler is `{}`: wrapS and wrapT default to REPEAT.
            assert!(
                bound
                    .iter()
                    .all(|b| b.texture == 0 && b.sampler == Sampler::default())
            );
            assert_eq!(
                loaded.files_read.len(),
                1,
                "nothing outside the file: {:?}",
                loaded.files_read
            );
        }
    }

    /// A textured square: positions, indices, then `extra_blocks`, and a material JSON.
    fn write_textured_square(
        dir: &Path,
        attributes: &str,
        extra_blocks: &[Block],
        material: &str,
        nodes: &str,
        images: &str,
    ) -> PathBuf {
        let mut blocks = vec![Block::Vec3(&SQUARE), Block::Indices(&[0, 1, 2, 2, 1, 3])];
        blocks.extend_from_slice(extra_blocks);
        let primitives =
            format!(r#"[{{"attributes": {{"POSITION": 0, {attributes}}}, "indices": 1, "material": 0}}]"#);
        let extra = format!(
            r#""materials": [{material}], "textures": [{{"source": 0, "sampler": 0}}], "samplers": [{{"wrapS": 33648, "wrapT": 33071}}], "images": {images},"#
        );
        write_fixture(dir, &blocks, &primitives, nodes, &extra)
    }

    /// UVs of the square: u along +X, v growing towards −Y (the image upright on it).
    const SQUARE_UVS: [f32; 8] = [0.0, 1.0, 1.0, 1.0, 0.0, 0.0, 1.0, 0.0];

    #[test]
    fn normal_map_without_tangents_gets_computed_tangents() {
        let dir = scratch_dir();
        write_png(dir.path(), "normal.png");
        let material = r#"{"normalTexture": {"index": 0, "scale": 0.5}}"#;
        let images = r#"[{"uri": "normal.png"}]"#;
        let path = write_textured_square(
            dir.path(),
            r#""TEXCOORD_0": 2"#,
            &[Block::Floats(&SQUARE_UVS, "VEC2")],
            material,
            ONE_NODE,
            images,
        );
        let loaded = check_faces_up(&path, 2);
        let mesh = &loaded.mesh;
        let binding = mesh.materials[0]
            .textures
            .normal
            .unwrap_or_else(|| panic!("bound"));
        assert_eq!((binding.scale, binding.uv_set), (0.5, 0));
        // wrapS 33648 (MIRRORED_REPEAT), wrapT 33071 (CLAMP_TO_EDGE).
        assert_eq!(
            binding.sampler,
            Sampler {
                wrap_s: Wrap::MirroredRepeat,
                wrap_t: Wrap::ClampToEdge
            }
        );
        assert!(
            mesh.tangents.iter().all(|&t| t == Vec4::new(1.0, 0.0, 0.0, 1.0)),
            "{:?}",
            mesh.tangents
        );
        // A data texture: stored values, not sRGB-decoded.
        let texel = mesh.textures[0].levels[0].texels[0];
        assert!(
            texel.distance(Vec4::new(188.0 / 255.0, 0.0, 0.0, 1.0)) < 1e-6,
            "{texel}"
        );
        assert!(loaded.files_read.contains(&dir.path().join("normal.png")));
    }

    #[test]
    fn file_tangents_follow_the_node_and_flip_under_a_mirror() {
        let dir = scratch_dir();
        write_png(dir.path(), "normal.png");
        let tangents = [0.0, 2.0, 0.0, 1.0].repeat(4);
        let material = r#"{"normalTexture": {"index": 0}}"#;
        let images = r#"[{"uri": "normal.png"}]"#;
        // Rotated a quarter turn about Z, then mirrored in x: +Y becomes −X, then +X.
        let rotate = r#"[{"mesh": 0, "rotation": [0, 0, 0.70710678, 0.70710678]}]"#;
        let path = write_textured_square(
            dir.path(),
            r#""TEXCOORD_0": 2, "TANGENT": 3"#,
            &[
                Block::Floats(&SQUARE_UVS, "VEC2"),
                Block::Floats(&tangents, "VEC4"),
            ],
            material,
            rotate,
            images,
        );
        let loaded = check_faces_up(&path, 2);
        for t in &loaded.mesh.tangents {
            assert!(t.distance(Vec4::new(-1.0, 0.0, 0.0, 1.0)) < 1e-6, "{t}");
        }
        let mirror = r#"[{"mesh": 0, "matrix": [-1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]}]"#;
        let path = write_textured_square(
            dir.path(),
            r#""TEXCOORD_0": 2, "TANGENT": 3"#,
            &[
                Block::Floats(&SQUARE_UVS, "VEC2"),
                Block::Floats(&tangents, "VEC4"),
            ],
            material,
            mirror,
            images,
        );
        // Mirrored in x: rewound, the square still faces +Z; the tangent keeps +Y and w flips
        // (the bitangent n × t = −X must become +X, the mirror image of the file's).
        let loaded = check_faces_up(&path, 2);
        for t in &loaded.mesh.tangents {
            assert!(t.distance(Vec4::new(0.0, 1.0, 0.0, -1.0)) < 1e-6, "{t}");
        }
    }

    #[test]
    fn colors_and_second_uv_set_from_normalized_integers() {
        let dir = scratch_dir();
        write_png(dir.path(), "base.png");
        let colors: [u8; 16] = [255, 0, 0, 255, 0, 255, 0, 128, 0, 0, 255, 0, 255, 255, 255, 255];
        let uvs1: [u16; 8] = [0, 65535, 65535, 65535, 0, 0, 65535, 0];
        let material = r#"{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0, "texCoord": 1}}}"#;
        let path = write_textured_square(
            dir.path(),
            r#""COLOR_0": 2, "TEXCOORD_1": 3"#,
            &[Block::Bytes(&colors, "VEC4"), Block::Shorts(&uvs1, "VEC2")],
            material,
            ONE_NODE,
            r#"[{"uri": "base.png"}]"#,
        );
        let loaded = check_faces_up(&path, 2);
        let mesh = &loaded.mesh;
        assert!(mesh.uvs.is_empty(), "no TEXCOORD_0");
        let by_position = |p: [f32; 3]| {
            let vertex = mesh
                .positions
                .iter()
                .position(|&q| q == Vec3::from(p))
                .unwrap_or(usize::MAX);
            (mesh.colors[vertex], mesh.uvs1[vertex])
        };
        assert_eq!(
            by_position(SQUARE[0]),
            (Vec4::new(1.0, 0.0, 0.0, 1.0), Vec2::new(0.0, 1.0))
        );
        let (green, uv) = by_position(SQUARE[1]);
        assert!(green.distance(Vec4::new(0.0, 1.0, 0.0, 128.0 / 255.0)) < 1e-6 && uv == Vec2::ONE);
        let binding = mesh.materials[0]
            .textures
            .diffuse
            .unwrap_or_else(|| panic!("bound"));
        assert_eq!(binding.uv_set, 1);
        // A colour texture: sRGB-decoded.
        let texel = mesh.textures[0].levels[0].texels[0];
        assert!(
            texel.distance(Vec4::new(0.502_886, 0.0, 0.0, 1.0)) < 1e-5,
            "{texel}"
        );
    }

    #[test]
    fn float_rgb_colors_get_alpha_one_and_missing_ones_white() {
        let dir = scratch_dir();
        let blocks = [
            Block::Vec3(&SQUARE[..3]),
            Block::Vec3(&[[0.5, 0.25, 0.0], [0.0, 0.0, 0.0], [1.0, 1.0, 1.0]]),
            Block::Vec3(&[SQUARE[1], SQUARE[3], SQUARE[2]]),
        ];
        // Two primitives, only the first with COLOR_0.
        let primitives =
            r#"[{"attributes": {"POSITION": 0, "COLOR_0": 1}}, {"attributes": {"POSITION": 2}}]"#;
        let path = write_fixture(dir.path(), &blocks, primitives, ONE_NODE, "");
        let loaded = check_faces_up(&path, 2);
        let mesh = &loaded.mesh;
        assert_eq!(mesh.colors.len(), mesh.positions.len());
        let first = mesh.triangles[0].map(|v| mesh.colors[v as usize]);
        assert_eq!(first[0], Vec4::new(0.5, 0.25, 0.0, 1.0));
        assert!(
            mesh.triangles[1]
                .iter()
                .all(|&v| mesh.colors[v as usize] == Vec4::ONE)
        );
    }

    #[test]
    fn missing_and_broken_images_warn_and_leave_the_material_untextured() {
        let dir = scratch_dir();
        std::fs::write(dir.path().join("broken.png"), b"\x89PNG\r\n\x1a\n garbage")
            .unwrap_or_else(|e| panic!("{e}"));
        for (uri, problem) in [
            ("missing%20file.png", "no such file"),
            ("broken.png", "cannot decode"),
        ] {
            let material = r#"{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}"#;
            let path = write_textured_square(
                dir.path(),
                r#""TEXCOORD_0": 2"#,
                &[Block::Floats(&SQUARE_UVS, "VEC2")],
                material,
                ONE_NODE,
                &format!(r#"[{{"uri": "{uri}"}}]"#),
            );
            let loaded = check_faces_up(&path, 2);
            let file = dir.path().join(percent_decode(uri).unwrap_or_default());
            assert!(
                loaded.files_read.contains(&file),
                "{file:?} in {:?}",
                loaded.files_read
            );
            assert_eq!(loaded.warnings.len(), 1, "{:?}", loaded.warnings);
            let warning = &loaded.warnings[0];
            assert!(
                warning.contains(&file.display().to_string()) && warning.contains(problem),
                "{warning}"
            );
            assert_eq!(loaded.mesh.materials[0].textures, Default::default());
            assert!(loaded.mesh.textures.is_empty());
        }
    }

    #[test]
    fn textures_reading_absent_uv_sets_are_not_bound() {
        let dir = scratch_dir();
        write_png(dir.path(), "base.png");
        let material = r#"{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0, "texCoord": 1}}, "normalTexture": {"index": 0, "texCoord": 2}}"#;
        let path = write_textured_square(
            dir.path(),
            r#""TEXCOORD_0": 2"#,
            &[Block::Floats(&SQUARE_UVS, "VEC2")],
            material,
            ONE_NODE,
            r#"[{"uri": "base.png"}]"#,
        );
        let loaded = check_faces_up(&path, 2);
        assert_eq!(loaded.mesh.materials[0].textures, Default::default());
        assert!(
            loaded
                .warnings
                .iter()
                .any(|w| w.contains("TEXCOORD_1, which no drawn primitive has"))
        );
        assert!(
            loaded
                .warnings
                .iter()
                .any(|w| w.contains("only TEXCOORD_0 and TEXCOORD_1"))
        );
        assert!(
            !loaded.files_read.contains(&dir.path().join("base.png")),
            "not read for nothing"
        );
    }

    #[test]
    fn attributes_of_types_gltf_forbids_are_ignored_with_a_warning() {
        let dir = scratch_dir();
        let blocks = [
            Block::Vec3(&SQUARE),
            Block::Indices(&[0, 1, 2, 2, 1, 3]),
            Block::Floats(&SQUARE_UVS, "VEC2"),
        ];
        let primitives = r#"[{"attributes": {"POSITION": 0, "TEXCOORD_0": 2}, "indices": 1}]"#;
        let path = write_fixture(dir.path(), &blocks, primitives, ONE_NODE, "");
        // Unnormalized unsigned bytes are not texture coordinates glTF allows.
        let text = std::fs::read_to_string(&path).unwrap_or_default().replace(
            r#""componentType": 5126, "count": 4, "type": "VEC2""#,
            r#""componentType": 5121, "count": 4, "type": "VEC2""#,
        );
        std::fs::write(&path, text).unwrap_or_else(|e| panic!("{e}"));
        let loaded = check_faces_up(&path, 2);
        assert!(loaded.mesh.uvs.is_empty());
        assert!(
            loaded
                .warnings
                .iter()
                .any(|w| w.contains("TEXCOORD_0") && w.contains("ignored")),
            "{:?}",
            loaded.warnings
        );
    }

    /// Writes `interleaved.gltf` and `interleaved.bin`: the square facing +Z as one view of
    /// interleaved vertices (position, normal, normalized u16 uv, 4 bytes of padding: a
    /// 32-byte stride), whose last position is wrong in the view and put right by a sparse
    /// substitution, and u8 indices. `bin_length` cuts the .bin short.
    fn write_interleaved_square(dir: &Path, bin_length: Option<usize>) -> PathBuf {
        let uvs: [[u16; 2]; 4] = [[0, 65535], [65535, 65535], [0, 3], [257, 0]];
        let mut bin = Vec::new();
        for (vertex, (position, uv)) in SQUARE.iter().zip(uvs).enumerate() {
            let stored = if vertex == 3 { [9.0, 9.0, 9.0] } else { *position };
            bin.extend(
                stored
                    .iter()
                    .chain(&[0.0, 0.0, 1.0])
                    .flat_map(|c| c.to_le_bytes()),
            );
            bin.extend(uv.iter().flat_map(|c| c.to_le_bytes()));
            bin.extend([0xFF; 4]);
        }
        bin.extend([0u8, 1, 2, 2, 1, 3, 3, 0]); // indices at 128, sparse index 3 at 134
        bin.extend(SQUARE[3].iter().flat_map(|c| c.to_le_bytes())); // sparse value at 136
        let length = bin.len();
        bin.truncate(bin_length.unwrap_or(length));
        write(dir, "interleaved.bin", &bin);
        let json = format!(
            r#"{{
  "asset": {{"version": "2.0"}},
  "scene": 0, "scenes": [{{"nodes": [0]}}], "nodes": [{{"mesh": 0}}],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2}}, "indices": 3}}]}}],
  "buffers": [{{"uri": "interleaved.bin", "byteLength": {length}}}],
  "bufferViews": [
    {{"buffer": 0, "byteLength": 128, "byteStride": 32}},
    {{"buffer": 0, "byteOffset": 128, "byteLength": 6}},
    {{"buffer": 0, "byteOffset": 134, "byteLength": 1}},
    {{"buffer": 0, "byteOffset": 136, "byteLength": 12}}],
  "accessors": [
    {{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0],
      "sparse": {{"count": 1, "indices": {{"bufferView": 2, "componentType": 5121}}, "values": {{"bufferView": 3}}}}}},
    {{"bufferView": 0, "byteOffset": 12, "componentType": 5126, "count": 4, "type": "VEC3"}},
    {{"bufferView": 0, "byteOffset": 24, "componentType": 5123, "normalized": true, "count": 4, "type": "VEC2"}},
    {{"bufferView": 1, "componentType": 5121, "count": 6, "type": "SCALAR"}}]
}}"#
        );
        write(dir, "interleaved.gltf", json.as_bytes())
    }

    /// Strided attributes, a sparse position, normalized u16 texture coordinates and u8
    /// indices arrive exactly in the mesh.
    #[test]
    fn interleaved_sparse_and_normalized_attributes_load_exactly() {
        let dir = scratch_dir();
        let loaded = check_faces_up(&write_interleaved_square(dir.path(), None), 2);
        let mesh = &loaded.mesh;
        assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
        let expected_uvs = [
            [0.0, 1.0],
            [1.0, 1.0],
            [0.0, 3.0 / 65535.0],
            [257.0 / 65535.0, 0.0],
        ];
        for (position, uv) in SQUARE.iter().zip(expected_uvs) {
            let vertex = mesh
                .positions
                .iter()
                .position(|&p| p == Vec3::from(*position))
                .unwrap_or_else(|| panic!("{position:?} in {:?}", mesh.positions));
            assert_eq!(mesh.uvs[vertex], Vec2::from(uv), "{position:?}");
            assert_eq!(mesh.normals[vertex], Vec3::Z);
        }
        assert_eq!(mesh.triangles.len(), 2);
    }

    /// A .bin cut short (with the declared length, or inside a view) is an error naming the
    /// buffer file and the sizes, never a panic or a mesh missing data.
    #[test]
    fn truncated_buffer_files_are_named() {
        let dir = scratch_dir();
        check_error(
            &write_interleaved_square(dir.path(), Some(100)),
            "buffer 0 `interleaved.bin` has 100 bytes but the file declares 148: it is truncated",
        );
        // The declared length cut as well: the views now reach past the buffer.
        let path = write_interleaved_square(dir.path(), Some(100));
        let text = std::fs::read_to_string(&path)
            .unwrap_or_default()
            .replace(r#""byteLength": 148"#, r#""byteLength": 100"#);
        std::fs::write(&path, text).unwrap_or_else(|e| panic!("{e}"));
        check_error(
            &path,
            "POSITION buffer view 0 covers bytes 0..128 of buffer 0 (`interleaved.bin`), which has 100",
        );
    }

    /// With `KHR_mesh_quantization`, u16 positions, normalized i8 normals and normalized i16
    /// texture coordinates load by the specification's formulas; without it the normals are
    /// a type error.
    #[test]
    fn quantized_attributes_load_with_the_extension_only() {
        let dir = scratch_dir();
        let mut bin = Vec::new();
        for p in SQUARE {
            bin.extend(p.map(|c| c as u16).iter().flat_map(|c| c.to_le_bytes()));
        }
        bin.extend([0u8, 0, 127, 0].repeat(4)); // normals (0, 0, 1), 4-byte aligned elements
        let uvs: [i16; 8] = [0, 32767, -32768, 32767, 0, 0, 100, -1];
        bin.extend(uvs.iter().flat_map(|c| c.to_le_bytes()));
        bin.extend([0u8, 1, 2, 2, 1, 3]);
        let write_file = |extensions: &str| {
            write(dir.path(), "quantized.bin", &bin);
            let json = format!(
                r#"{{
  "asset": {{"version": "2.0"}}, {extensions}
  "scene": 0, "scenes": [{{"nodes": [0]}}], "nodes": [{{"mesh": 0}}],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2}}, "indices": 3}}]}}],
  "buffers": [{{"uri": "quantized.bin", "byteLength": {}}}],
  "bufferViews": [
    {{"buffer": 0, "byteLength": 24}},
    {{"buffer": 0, "byteOffset": 24, "byteLength": 16, "byteStride": 4}},
    {{"buffer": 0, "byteOffset": 40, "byteLength": 16}},
    {{"buffer": 0, "byteOffset": 56, "byteLength": 6}}],
  "accessors": [
    {{"bufferView": 0, "componentType": 5123, "count": 4, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}},
    {{"bufferView": 1, "componentType": 5120, "normalized": true, "count": 4, "type": "VEC3"}},
    {{"bufferView": 2, "componentType": 5122, "normalized": true, "count": 4, "type": "VEC2"}},
    {{"bufferView": 3, "componentType": 5121, "count": 6, "type": "SCALAR"}}]
}}"#,
                bin.len()
            );
            write(dir.path(), "quantized.gltf", json.as_bytes())
        };
        let path = write_file(
            r#""extensionsUsed": ["KHR_mesh_quantization"], "extensionsRequired": ["KHR_mesh_quantization"],"#,
        );
        let loaded = check_faces_up(&path, 2);
        assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
        let mesh = &loaded.mesh;
        let expected_uvs = [
            [0.0, 1.0],
            [-1.0, 1.0],
            [0.0, 0.0],
            [100.0 / 32767.0, -1.0 / 32767.0],
        ];
        for (position, uv) in SQUARE.iter().zip(expected_uvs) {
            let vertex = mesh
                .positions
                .iter()
                .position(|&p| p == Vec3::from(*position))
                .unwrap_or_else(|| panic!("{position:?} in {:?}", mesh.positions));
            assert_eq!(mesh.uvs[vertex], Vec2::from(uv), "{position:?}");
        }
        check_error(
            &write_file(""),
            "POSITION accessor 0 holds Vec3 U16; expected Vec3 F32",
        );
    }
}
