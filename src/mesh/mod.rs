//! Triangle meshes: the built-in primitives and the OBJ / glTF loaders, all producing [`Mesh`].
//!
//! Code map: [`primitives`] (sphere, plane, cube), [`obj`] (OBJ text through our own parser
//! in `obj_parse`, MTL through `tobj`), [`gltf`] (glTF 2.0 through `gltf`), [`normals`] (face
//! normals, crease-angle vertex normals, repair of file normals) and [`tangents`] (tangent
//! frames for normal maps), which the loaders share. Loaders merge everything a file holds
//! into one [`Mesh`], decode the textures its materials use ([`crate::texture`]), record every
//! file they read or looked for, and report problems that do not stop the load (a missing
//! texture, say) as warnings. A file is loaded in two stages ([`ParsedMeshFile`]): read and
//! parse once, then build the mesh for each crease angle that objects ask for.
//!
//! Architecture invariant: every `Mesh` leaving this module is renderable as it is
//! ([`Mesh::check_invariant`] tests all of it):
//! * positions and normals are finite, normals have unit length, every index is in range,
//!   and triangles are wound counter-clockwise when seen from their front side;
//! * every per-vertex array (`normals`, `uvs`, `uvs1`, `colors`, `tangents`) holds one
//!   finite entry per position, except `uvs`, `uvs1`, `colors` and `tangents`, which may also
//!   be empty; tangents are unit, perpendicular to their normal, with `w = ±1`;
//! * `triangle_materials` is empty or has one entry per triangle, each indexing `materials`;
//! * every [`TextureBinding`](crate::scene::TextureBinding) of a material indexes
//!   `textures`, and reads a UV set the mesh has (uv_set 0 only when `uvs` is non-empty, 1
//!   only when `uvs1` is); a material with a normal map comes with `tangents`.

mod atan;
pub mod closed;
pub mod gltf;
mod gltf_accessor;
pub mod normals;
pub mod obj;
mod obj_parse;
pub mod primitives;
pub mod tangents;

use std::path::{Path, PathBuf};

use std::sync::Arc;

use glam::{DMat4, DVec3, Vec2, Vec3, Vec4};

use crate::scene::access::FileAccess;
use crate::texture::Texture;

use crate::scene::{Attenuation, Light, Material};

/// An indexed triangle mesh in its own model space.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Unit vertex normals, one per position.
    pub normals: Vec<Vec3>,
    /// Counter-clockwise (front-facing) triangles as indices into `positions`.
    pub triangles: Vec<[u32; 3]>,
    /// For each triangle, an index into `materials`; empty when `materials` is empty.
    pub triangle_materials: Vec<u32>,
    /// Materials that came with the file (MTL, glTF); empty for primitives.
    pub materials: Vec<Material>,
    /// Texture coordinates (OBJ `vt`, glTF `TEXCOORD_0`), one per position, or empty.
    /// OBJ and glTF put v = 0 at different edges of the image; loaders convert to the glTF
    /// convention: (0, 0) is the top-left corner of the image (OBJ's v becomes 1 − v).
    pub uvs: Vec<Vec2>,
    /// A second texture-coordinate set (glTF `TEXCOORD_1`), one per position, or empty.
    pub uvs1: Vec<Vec2>,
    /// Linear RGBA vertex colours (glTF `COLOR_0`) that multiply the diffuse colour, or empty.
    pub colors: Vec<Vec4>,
    /// Unit tangents with the bitangent's handedness in `w` (±1), for normal maps, or empty:
    /// the bitangent is `w · (normal × tangent)` (glTF's convention; see [`tangents`]).
    pub tangents: Vec<Vec4>,
    /// Textures the materials' `TextureBinding`s index.
    pub textures: Vec<Arc<Texture>>,
    /// The surface is known to be closed (it bounds a volume, every front face seen from
    /// outside): seen from outside its bounds, its back faces are always hidden behind its
    /// front faces. Set by the primitives that are, and for mesh files by [`closed::is_closed`]
    /// when they are loaded.
    pub closed: bool,
}

impl Mesh {
    /// Number of triangles, zero-area ones included.
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// Gives every vertex one material: a vertex that triangles of several materials share
    /// is copied, with all its attributes, for each material after the first one to use it,
    /// and those triangles are pointed at the copy. Per-vertex lighting (Gouraud) then lights
    /// each triangle's corners with the triangle's own material, as renderers that draw a
    /// file's material groups as separate meshes do, instead of letting one material's colour
    /// bleed across the boundary. Copies change nothing else: positions, normals and UVs are
    /// the same values, so every other mode interpolates the same bits.
    pub fn split_vertices_shared_by_materials(&mut self) {
        if self.triangle_materials.is_empty() {
            return;
        }
        const UNUSED: u32 = u32::MAX;
        // The material each vertex keeps (the first to use it), and the copies made so far.
        let mut owner = vec![UNUSED; self.positions.len()];
        let mut copies: std::collections::HashMap<(u32, u32), u32> = std::collections::HashMap::new();
        for (triangle, &material) in self.triangles.iter_mut().zip(&self.triangle_materials) {
            for corner in triangle.iter_mut() {
                let vertex = *corner as usize;
                if owner[vertex] == UNUSED {
                    owner[vertex] = material;
                } else if owner[vertex] != material {
                    *corner = *copies.entry((*corner, material)).or_insert_with(|| {
                        let copy = self.positions.len() as u32;
                        self.positions.push(self.positions[vertex]);
                        self.normals.push(self.normals[vertex]);
                        for uvs in [&mut self.uvs, &mut self.uvs1] {
                            if !uvs.is_empty() {
                                uvs.push(uvs[vertex]);
                            }
                        }
                        if !self.colors.is_empty() {
                            self.colors.push(self.colors[vertex]);
                        }
                        if !self.tangents.is_empty() {
                            self.tangents.push(self.tangents[vertex]);
                        }
                        copy
                    });
                }
            }
        }
    }

    /// Checks the module's invariant, naming the first thing that breaks it. Loaders' tests
    /// run it on everything they load; the loaders themselves establish it by construction.
    pub fn check_invariant(&self) -> Result<(), String> {
        let vertex_count = self.positions.len();
        if let Some(i) = self.positions.iter().position(|p| !p.is_finite()) {
            return Err(format!("position {i} is not finite"));
        }
        if self.normals.len() != vertex_count {
            return Err(format!(
                "{} normals for {vertex_count} positions",
                self.normals.len()
            ));
        }
        if let Some(i) = self
            .normals
            .iter()
            .position(|n| !n.is_finite() || (n.length() - 1.0).abs() >= 1e-4)
        {
            return Err(format!("normal {i} ({}) is not unit", self.normals[i]));
        }
        if let Some(t) = self
            .triangles
            .iter()
            .find(|t| t.iter().any(|&v| v as usize >= vertex_count))
        {
            return Err(format!("triangle {t:?} indexes past {vertex_count} vertices"));
        }
        let optional_lengths = [
            ("uvs", self.uvs.len()),
            ("uvs1", self.uvs1.len()),
            ("colors", self.colors.len()),
            ("tangents", self.tangents.len()),
        ];
        for (name, length) in optional_lengths {
            if length != 0 && length != vertex_count {
                return Err(format!("{length} {name} for {vertex_count} positions"));
            }
        }
        if !self.uvs.iter().chain(&self.uvs1).all(|uv| uv.is_finite()) {
            return Err("a texture coordinate is not finite".to_string());
        }
        if !self.colors.iter().all(|c| c.is_finite()) {
            return Err("a vertex colour is not finite".to_string());
        }
        for (i, (tangent, normal)) in self.tangents.iter().zip(&self.normals).enumerate() {
            let t = tangent.truncate();
            let unit = (t.length() - 1.0).abs() < 1e-4 && t.dot(*normal).abs() < 1e-3;
            if !unit || tangent.w.abs() != 1.0 {
                return Err(format!(
                    "tangent {i} ({tangent}) is not unit, perpendicular, with w = ±1"
                ));
            }
        }
        // One material index per triangle when the mesh has materials, none when it has none.
        let expected_indices = if self.materials.is_empty() {
            0
        } else {
            self.triangles.len()
        };
        if self.triangle_materials.len() != expected_indices {
            return Err(format!(
                "{} triangle materials for {} triangles and {} materials",
                self.triangle_materials.len(),
                self.triangles.len(),
                self.materials.len()
            ));
        }
        if let Some(m) = self
            .triangle_materials
            .iter()
            .find(|&&m| m as usize >= self.materials.len())
        {
            return Err(format!(
                "material index {m} past {} materials",
                self.materials.len()
            ));
        }
        for (index, material) in self.materials.iter().enumerate() {
            let textures = &material.textures;
            let bindings = [textures.diffuse, textures.ambient, textures.normal];
            for binding in bindings.into_iter().flatten() {
                if binding.texture as usize >= self.textures.len() {
                    return Err(format!(
                        "material {index} uses texture {} of {}",
                        binding.texture,
                        self.textures.len()
                    ));
                }
                let has_set = match binding.uv_set {
                    0 => !self.uvs.is_empty(),
                    1 => !self.uvs1.is_empty(),
                    _ => false,
                };
                if !has_set {
                    return Err(format!(
                        "material {index} reads UV set {}, which the mesh lacks",
                        binding.uv_set
                    ));
                }
            }
            if textures.normal.is_some() && self.tangents.is_empty() {
                return Err(format!(
                    "material {index} has a normal map but the mesh has no tangents"
                ));
            }
        }
        Ok(())
    }

    /// Axis-aligned bounds of the positions, `None` for an empty mesh.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        let first = *self.positions.first()?;
        Some(
            self.positions
                .iter()
                .fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p))),
        )
    }
}

/// How a mesh file is turned into a [`Mesh`]: the settings that change the result,
/// so that a cache keyed by path and options is exact.
#[derive(Debug, Clone, PartialEq)]
pub struct MeshOptions {
    /// Faces meeting at more than this angle keep separate vertex normals (a hard edge)
    /// when normals are computed because the file has none.
    pub crease_angle_degrees: f32,
    /// How the files the mesh names (MTL libraries, textures, buffers, images) may be read.
    pub access: crate::scene::access::FileAccess,
}

impl Default for MeshOptions {
    fn default() -> Self {
        MeshOptions {
            crease_angle_degrees: normals::DEFAULT_CREASE_ANGLE_DEGREES,
            access: Default::default(),
        }
    }
}

/// A problem with a mesh file: which file, what, and where in it when known.
#[derive(Debug, Clone, PartialEq)]
pub struct MeshError {
    /// The file the problem is in (an MTL or .bin file's problems name the mesh file that
    /// referenced it, and mention the other file in `message`).
    pub path: PathBuf,
    /// 1-based line in the file, when the format has lines and the problem has one.
    pub line: Option<usize>,
    /// 1-based column (in chars) on `line`, when the problem has one.
    pub column: Option<usize>,
    /// What is wrong, as a sentence fragment without the path (the caller adds location).
    pub message: String,
    /// What to do about it, when there is something to say ("name it as `Gltf(...)`").
    pub hint: Option<String>,
}

impl MeshError {
    /// A problem with the whole file, or one whose line is unknown.
    pub fn new(path: &Path, message: impl Into<String>) -> Self {
        MeshError {
            path: path.to_path_buf(),
            line: None,
            column: None,
            message: message.into(),
            hint: None,
        }
    }

    /// A problem at a 1-based line of the file.
    pub fn at_line(path: &Path, line: usize, message: impl Into<String>) -> Self {
        MeshError {
            line: Some(line),
            ..MeshError::new(path, message)
        }
    }

    /// A problem at a 1-based line and column (in chars) of the file.
    pub fn at(path: &Path, line: usize, column: usize, message: impl Into<String>) -> Self {
        MeshError {
            line: Some(line),
            column: Some(column),
            ..MeshError::new(path, message)
        }
    }

    /// Adds what to do about it.
    pub fn with_hint(mut self, hint: impl Into<String>) -> Self {
        self.hint = Some(hint.into());
        self
    }

    /// The file could not be read at all: "cannot read mesh file: No such file or directory".
    pub fn cannot_read(path: &Path, error: &std::io::Error) -> Self {
        MeshError::new(path, format!("cannot read mesh file: {}", io_error_text(error)))
    }
}

/// What a mesh file's first bytes say it is. Read before parsing, so that a file named as
/// the wrong kind (a GLB given to `Obj(...)`, an OBJ given to `Gltf(...)`) or a damaged one
/// gets an error saying what it is, instead of the message of a parser that expected
/// something else ("expected value at line 1 column 1" for a binary file).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FileContent {
    /// Starts with the GLB magic `glTF`.
    BinaryGltf,
    /// Text starting with `{`: a `.gltf` file (or some other JSON).
    Json,
    /// Text with OBJ statements (`v`, `f`, `o`, `mtllib`, ...) near the top.
    ObjText,
    /// Other text.
    OtherText,
    /// Not text: a NUL byte near the top.
    Binary,
}

/// How much of a file [`FileContent::of`] looks at.
const SNIFF_BYTES: usize = 4096;

impl FileContent {
    /// Classifies `bytes` by their first few kilobytes.
    pub fn of(bytes: &[u8]) -> FileContent {
        if bytes.starts_with(b"glTF") {
            return FileContent::BinaryGltf;
        }
        let head = &bytes[..bytes.len().min(SNIFF_BYTES)];
        if head.contains(&0) {
            return FileContent::Binary;
        }
        let text = String::from_utf8_lossy(head);
        let text = text.trim_start_matches('\u{feff}').trim_start();
        if text.starts_with('{') {
            return FileContent::Json;
        }
        const OBJ_STATEMENTS: [&str; 10] = ["v", "vt", "vn", "f", "o", "g", "s", "l", "mtllib", "usemtl"];
        let obj_like = text.lines().any(|line| {
            line.split_whitespace()
                .next()
                .is_some_and(|word| OBJ_STATEMENTS.contains(&word))
        });
        if obj_like {
            FileContent::ObjText
        } else {
            FileContent::OtherText
        }
    }

    /// "a binary glTF (GLB) file", for "this is ..., not ..." messages.
    pub fn description(self) -> &'static str {
        match self {
            FileContent::BinaryGltf => "a binary glTF (GLB) file",
            FileContent::Json => "a JSON (glTF) file",
            FileContent::ObjText => "an OBJ file (text with `v` and `f` lines)",
            FileContent::OtherText => "a text file with neither OBJ statements nor JSON",
            FileContent::Binary => "a binary file",
        }
    }
}

/// The first bytes of a file as a user can compare them with a format's magic number:
/// `67 4C 54 46 ("gLTF")`.
pub fn first_bytes(bytes: &[u8]) -> String {
    let head = &bytes[..bytes.len().min(4)];
    let hex: Vec<String> = head.iter().map(|b| format!("{b:02X}")).collect();
    let ascii: String = head
        .iter()
        .map(|&b| {
            if b.is_ascii_graphic() || b == b' ' {
                b as char
            } else {
                '.'
            }
        })
        .collect();
    format!("{} (\"{ascii}\")", hex.join(" "))
}

/// The hint for a mesh file of the other kind.
pub const USE_GLTF_HINT: &str =
    "glTF and GLB files are named with `Gltf(\"...\")`, OBJ files with `Obj(\"...\")`";

/// An I/O error as a user reads it: the operating system's text without the
/// "(os error N)" suffix that Rust appends.
pub(crate) fn io_error_text(error: &std::io::Error) -> String {
    let text = error.to_string();
    match text.find(" (os error") {
        Some(end) => text[..end].to_string(),
        None => text,
    }
}

/// A mesh file read and parsed with what it names (material libraries and textures, buffers):
/// the part of a load that does not depend on the crease angle. Objects that name one file
/// with different crease angles share one parse and [`build`](ParsedMeshFile::build) a mesh
/// each.
#[derive(Debug, Clone)]
pub enum ParsedMeshFile {
    Obj(Box<obj::ParsedObj>),
    Gltf(Box<gltf::ParsedGltf>),
}

impl ParsedMeshFile {
    /// Reads and parses the OBJ (`is_obj`) or glTF/GLB file at `path`, reading what it names
    /// through `access`.
    pub fn parse(path: &Path, is_obj: bool, access: &FileAccess) -> Result<Self, MeshError> {
        Ok(if is_obj {
            ParsedMeshFile::Obj(Box::new(obj::parse_obj(path, access)?))
        } else {
            ParsedMeshFile::Gltf(Box::new(gltf::parse_gltf(path, access)?))
        })
    }

    /// [`ParsedMeshFile::parse`] and then [`ParsedMeshFile::build`] for `crease_angle_degrees`:
    /// an OBJ file's closedness is then tested beside its assembly ([`obj::parse_and_build_obj`]).
    pub fn parse_and_build(
        path: &Path,
        is_obj: bool,
        access: &FileAccess,
        crease_angle_degrees: f32,
    ) -> Result<(Self, Result<LoadedMesh, MeshError>), MeshError> {
        if is_obj {
            let (parsed, loaded) = obj::parse_and_build_obj(path, access, crease_angle_degrees)?;
            Ok((ParsedMeshFile::Obj(Box::new(parsed)), Ok(loaded)))
        } else {
            let parsed = Self::parse(path, is_obj, access)?;
            let loaded = parsed.build(crease_angle_degrees);
            Ok((parsed, loaded))
        }
    }

    /// The mesh with normals computed (where the file has none) with this crease angle, and
    /// [`Mesh::closed`] (whether its back faces may be culled: `render::geometry`), tested once
    /// per mesh built, or for an OBJ file once at parse.
    pub fn build(&self, crease_angle_degrees: f32) -> Result<LoadedMesh, MeshError> {
        match self {
            ParsedMeshFile::Obj(parsed) => Ok(parsed.build(crease_angle_degrees)),
            ParsedMeshFile::Gltf(parsed) => {
                let mut loaded = parsed.build(crease_angle_degrees)?;
                loaded.mesh.closed = closed::is_closed(&loaded.mesh.positions, &loaded.mesh.triangles);
                Ok(loaded)
            }
        }
    }
}

/// A mesh file that loaded, with the other files it read (MTL, .bin, textures) so that a
/// watcher can follow them, and warnings that did not stop the load.
#[derive(Debug, Clone)]
pub struct LoadedMesh {
    /// The mesh, satisfying the module's invariant.
    pub mesh: Mesh,
    /// Every file the load read, the mesh file first, and the files it looked for and did not
    /// find (a missing MTL or texture file), so that a watcher notices when they appear.
    pub files_read: Vec<PathBuf>,
    /// Problems that did not stop the load (a missing MTL or texture file, skipped
    /// primitives, ...).
    pub warnings: Vec<String>,
    /// Lights the file places (glTF `KHR_lights_punctual`), in the mesh's model space, in the
    /// order the drawn scene's nodes are visited; empty for OBJ files and primitives.
    pub lights: Vec<ImportedLight>,
    /// Cameras the file places (glTF nodes with a `camera`), in the mesh's model space, in the
    /// order the drawn scene's nodes are visited; empty for OBJ files and primitives.
    pub cameras: Vec<ImportedCamera>,
    /// Whether [`MeshOptions::crease_angle_degrees`] shaped the mesh (some normals were
    /// computed). When it did not, the mesh is the same for every crease angle, and a cache
    /// can give it to objects that ask with another one.
    pub crease_angle_used: bool,
}

/// A light a mesh file places (glTF `KHR_lights_punctual`), in the mesh's model space: the
/// node's world transform is applied, as to the positions.
#[derive(Debug, Clone, PartialEq)]
pub struct ImportedLight {
    /// The light's name in the file, if it has one.
    pub name: Option<String>,
    /// Index of the light in the file's light list (`KHR_lights_punctual.lights`).
    pub index: usize,
    pub kind: ImportedLightKind,
    /// Linear RGB `color × intensity` as the file gives them (lux for directional lights,
    /// candela for point and spot lights); see [`ImportedLight::to_light`] for the scale.
    pub color: Vec3,
    /// Where the light is (the node's origin); unused by directional lights.
    pub position: DVec3,
    /// Unit direction the light travels in (the node's local −Z); unused by point lights.
    pub direction: DVec3,
    /// Distance beyond which glTF says the light has no effect, when the file gives one.
    pub range: Option<f32>,
}

/// The kinds of light glTF has; spot angles converted from the file's radians to degrees.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ImportedLightKind {
    Directional,
    Point,
    Spot {
        /// Angle from the axis inside which the spot is at full strength, degrees.
        inner_cone_degrees: f32,
        /// Angle from the axis beyond which the spot gives no light, degrees.
        outer_cone_degrees: f32,
    },
}

/// glTF point and spot lights fall off with the inverse square of the distance.
pub const INVERSE_SQUARE: Attenuation = Attenuation {
    constant: 0.0,
    linear: 0.0,
    quadratic: 1.0,
};

impl ImportedLight {
    /// This light as a scene light, placed by `transform` (model to world): the position
    /// through the matrix, the direction through its linear part, renormalised.
    ///
    /// Mapping (documented in `docs/scene-format.md`, glTF section):
    /// * colour: `color × intensity` as it is, so 1 lux of a directional light and 1 candela
    ///   of a point or spot light seen from 1 unit away both light a white surface facing them
    ///   like our default `intensity: 1` light;
    /// * attenuation: [`INVERSE_SQUARE`] (`1/d²`), glTF's falloff; `range` is not applied (our
    ///   attenuation is a polynomial and cannot reach zero), so lights reach past it;
    /// * spot: `cutoff` = the outer cone angle; `exponent` from [`spot_exponent`], the one
    ///   whose cone carries the same power as glTF's smooth inner-to-outer falloff;
    /// * no shadows (glTF has no such setting).
    pub fn to_light(&self, transform: DMat4) -> Light {
        let position = transform.transform_point3(self.position);
        let direction = transform
            .transform_vector3(self.direction)
            .try_normalize()
            .unwrap_or(self.direction)
            .as_vec3();
        match self.kind {
            ImportedLightKind::Directional => Light::Directional {
                direction,
                color: self.color,
                shadow: None,
            },
            ImportedLightKind::Point => Light::Point {
                position,
                color: self.color,
                attenuation: INVERSE_SQUARE,
                shadow: None,
            },
            ImportedLightKind::Spot {
                inner_cone_degrees,
                outer_cone_degrees,
            } => Light::Spot {
                position,
                direction,
                color: self.color,
                cutoff_degrees: outer_cone_degrees,
                exponent: spot_exponent(inner_cone_degrees, outer_cone_degrees),
                attenuation: INVERSE_SQUARE,
                shadow: None,
            },
        }
    }
}

/// The exponent `e` of our spot falloff `cos^e θ` (cut off at the outer angle) that matches
/// glTF's falloff between the inner and outer cone angles (degrees): glTF's strength is 1
/// inside the inner cone and `t²` between the cones, with `t` going linearly in `cos θ` from 1
/// at the inner angle to 0 at the outer. `cos^e` cannot be flat and then fall, so `e` is chosen
/// so that both cones emit the same power: with `u = cos θ`, `c_o`, `c_i` the cosines of the
/// outer and inner angles, `∫_{c_o}^1 u^e du = (1 − c_i) + (c_i − c_o)/3`. Equal angles (a
/// hard-edged glTF spot) give `e = 0`, our hard-edged spot, exactly; glTF's default cone
/// (inner 0°, outer 45°) gives `e ≈ 8.9`. Solved by bisection (the left side falls as `e`
/// grows); at most 10⁸ (a cone narrower than about 0.01°).
pub fn spot_exponent(inner_degrees: f32, outer_degrees: f32) -> f32 {
    let outer = f64::from(outer_degrees.clamp(0.0, 90.0)).to_radians();
    let inner = f64::from(inner_degrees).to_radians().clamp(0.0, outer);
    let (cos_outer, cos_inner) = (outer.cos(), inner.cos());
    let target = (1.0 - cos_inner) + (cos_inner - cos_outer) / 3.0;
    let power = |e: f64| (1.0 - cos_outer.powf(e + 1.0)) / (e + 1.0);
    if 1.0 - cos_outer < 1e-9 || power(0.0) - target < 1e-9 * power(0.0) {
        return 0.0;
    }
    let (mut low, mut high) = (0.0_f64, 1e8_f64);
    if power(high) >= target {
        return high as f32;
    }
    for _ in 0..100 {
        let middle = 0.5 * (low + high);
        if power(middle) > target {
            low = middle;
        } else {
            high = middle;
        }
    }
    (0.5 * (low + high)) as f32
}

/// A camera a mesh file places (a glTF node with a `camera`), in the mesh's model space.
#[derive(Debug, Clone, PartialEq)]
pub struct ImportedCamera {
    /// The camera's name in the file, if it has one.
    pub name: Option<String>,
    /// The name of the node that places it, if it has one.
    pub node_name: Option<String>,
    /// Index of the camera in the file's `cameras` list.
    pub index: usize,
    /// The node's origin.
    pub eye: DVec3,
    /// Unit direction the camera looks in: the node's local −Z.
    pub forward: DVec3,
    /// Unit up direction: the node's local +Y.
    pub up: DVec3,
    /// Distances and sizes in the mesh's model space (the node's scale applied).
    pub projection: ImportedProjection,
}

/// A glTF camera's projection; the file's aspect ratio (`aspectRatio`, `xmag`) is not kept:
/// the image's aspect ratio decides the width.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ImportedProjection {
    Perspective {
        /// `yfov`, converted to degrees.
        fov_y_degrees: f64,
        near: f64,
        /// `None` for glTF's infinite projection (no `zfar`).
        far: Option<f64>,
    },
    Orthographic {
        /// `2 · ymag`.
        height: f64,
        near: f64,
        far: f64,
    },
}

impl ImportedCamera {
    /// `camera N`, with its name (or else its node's name) when it has one.
    pub fn label(&self) -> String {
        match self.name.as_ref().or(self.node_name.as_ref()) {
            Some(name) => format!("{} \"{name}\"", self.index),
            None => format!("{} (unnamed)", self.index),
        }
    }

    /// Whether `name` is the camera's name or its node's.
    pub fn is_named(&self, name: &str) -> bool {
        self.name.as_deref() == Some(name) || self.node_name.as_deref() == Some(name)
    }

    /// This camera placed by `transform` (model to world): the eye through the matrix, the
    /// view and up directions through its linear part (renormalised), and the distances and
    /// the orthographic height scaled by how much the transform stretches the view and up
    /// directions, so an object drawn through its own camera looks the same at any scale.
    pub fn transformed(&self, transform: DMat4) -> ImportedCamera {
        let forward = transform.transform_vector3(self.forward);
        let up = transform.transform_vector3(self.up);
        let (depth_scale, height_scale) = (forward.length(), up.length());
        let projection = match self.projection {
            ImportedProjection::Perspective {
                fov_y_degrees,
                near,
                far,
            } => ImportedProjection::Perspective {
                fov_y_degrees,
                near: near * depth_scale,
                far: far.map(|far| far * depth_scale),
            },
            ImportedProjection::Orthographic { height, near, far } => ImportedProjection::Orthographic {
                height: height * height_scale,
                near: near * depth_scale,
                far: far * depth_scale,
            },
        };
        ImportedCamera {
            name: self.name.clone(),
            node_name: self.node_name.clone(),
            index: self.index,
            eye: transform.transform_point3(self.eye),
            forward: forward.try_normalize().unwrap_or(self.forward),
            up: up.try_normalize().unwrap_or(self.up),
            projection,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The power of our cone, `∫_{cos outer}^1 u^e du`, and of glTF's falloff.
    fn powers(inner: f32, outer: f32, exponent: f32) -> (f64, f64) {
        let (ci, co) = (
            f64::from(inner).to_radians().cos(),
            f64::from(outer).to_radians().cos(),
        );
        let e = f64::from(exponent);
        ((1.0 - co.powf(e + 1.0)) / (e + 1.0), (1.0 - ci) + (ci - co) / 3.0)
    }

    /// Two quads side by side, the left red (material 0), the right blue (1), sharing the
    /// middle edge; the blue quad's second triangle also red, sharing a blue corner.
    #[test]
    fn vertices_shared_by_materials_are_copied_once_per_extra_material() {
        let positions: Vec<Vec3> = (0..6)
            .map(|i| Vec3::new((i % 3) as f32, (i / 3) as f32, 0.0))
            .collect();
        let mut mesh = Mesh {
            normals: vec![Vec3::Z; 6],
            uvs: positions.iter().map(|p| p.truncate() * 0.5).collect(),
            positions,
            triangles: vec![[0, 1, 4], [0, 4, 3], [1, 2, 5], [1, 5, 4]],
            triangle_materials: vec![0, 0, 1, 0],
            materials: vec![obj::default_material(); 2],
            ..Mesh::default()
        };
        let before = mesh.clone();
        mesh.split_vertices_shared_by_materials();
        mesh.check_invariant().unwrap();
        // Vertex 1 is red's first, so the blue triangle [1, 2, 5] gets a copy of it; 2 and 5
        // are blue's own; the red [1, 5, 4] then shares 1 and 4 with red, and gets a copy of 5.
        assert_eq!(mesh.triangles, vec![[0, 1, 4], [0, 4, 3], [6, 2, 5], [1, 7, 4]]);
        assert_eq!(mesh.positions.len(), 8);
        for (split, original) in mesh.triangles.iter().zip(&before.triangles) {
            for (&s, &o) in split.iter().zip(original) {
                let (s, o) = (s as usize, o as usize);
                assert_eq!(
                    (mesh.positions[s], mesh.normals[s], mesh.uvs[s]),
                    (before.positions[o], before.normals[o], before.uvs[o])
                );
            }
        }
        // Every vertex now belongs to one material.
        let mut owner = vec![None; mesh.positions.len()];
        for (triangle, &material) in mesh.triangles.iter().zip(&mesh.triangle_materials) {
            for &v in triangle {
                assert_eq!(*owner[v as usize].get_or_insert(material), material, "vertex {v}");
            }
        }
        // Without materials nothing changes.
        let mut plain = Mesh {
            triangle_materials: Vec::new(),
            ..before.clone()
        };
        plain.split_vertices_shared_by_materials();
        assert_eq!(plain.triangles, before.triangles);
    }

    #[test]
    fn spot_exponent_matches_the_power_of_gltf_falloff() {
        assert_eq!(spot_exponent(30.0, 30.0), 0.0, "hard edge");
        assert_eq!(spot_exponent(40.0, 30.0), 0.0, "inner past outer is a hard edge");
        assert_eq!(spot_exponent(0.0, 0.0), 0.0);
        let default = spot_exponent(0.0, 45.0);
        assert!((default - 8.91).abs() < 0.01, "{default}");
        for (inner, outer) in [(0.0, 45.0), (10.0, 20.0), (0.0, 90.0), (5.0, 6.0), (0.0, 1.0)] {
            let exponent = spot_exponent(inner, outer);
            let (ours, gltf) = powers(inner, outer, exponent);
            assert!(exponent.is_finite() && exponent >= 0.0);
            assert!(
                (ours - gltf).abs() < 1e-6 * gltf,
                "{inner}..{outer}: e = {exponent}"
            );
        }
        // A softer falloff (wider gap between the cones) is a larger exponent.
        assert!(spot_exponent(0.0, 30.0) > spot_exponent(20.0, 30.0));
    }

    #[test]
    fn imported_lights_and_cameras_follow_a_transform() {
        let transform = DMat4::from_scale_rotation_translation(
            DVec3::splat(3.0),
            glam::DQuat::from_rotation_y(std::f64::consts::FRAC_PI_2),
            DVec3::new(0.0, 1.0, 0.0),
        );
        let spot = ImportedLight {
            name: None,
            index: 0,
            kind: ImportedLightKind::Spot {
                inner_cone_degrees: 10.0,
                outer_cone_degrees: 20.0,
            },
            color: Vec3::ONE,
            position: DVec3::new(0.0, 0.0, 1.0),
            direction: DVec3::NEG_Z,
            range: None,
        };
        let Light::Spot {
            position,
            direction,
            cutoff_degrees,
            attenuation,
            ..
        } = spot.to_light(transform)
        else {
            panic!("a spot")
        };
        assert!(
            (position - DVec3::new(3.0, 1.0, 0.0)).length() < 1e-9,
            "{position}"
        );
        assert!(direction.abs_diff_eq(Vec3::NEG_X, 1e-6), "{direction}");
        assert_eq!((cutoff_degrees, attenuation), (20.0, INVERSE_SQUARE));
        let camera = ImportedCamera {
            name: Some("Cam".into()),
            node_name: None,
            index: 0,
            eye: DVec3::ZERO,
            forward: DVec3::NEG_Z,
            up: DVec3::Y,
            projection: ImportedProjection::Orthographic {
                height: 2.0,
                near: 0.5,
                far: 10.0,
            },
        }
        .transformed(transform);
        assert!((camera.forward - DVec3::NEG_X).length() < 1e-9);
        assert!((camera.up - DVec3::Y).length() < 1e-9);
        assert_eq!(
            camera.projection,
            ImportedProjection::Orthographic {
                height: 6.0,
                near: 1.5,
                far: 30.0
            }
        );
        assert!(camera.is_named("Cam") && !camera.is_named("cam"));
        assert_eq!(camera.label(), "0 \"Cam\"");
    }
}
