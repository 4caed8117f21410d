//! Triangle meshes: the built-in primitives and the OBJ / glTF loaders, all producing [`Mesh`].
//!
//! Code map: [`primitives`] (sphere, plane, cube), [`obj`] (OBJ + MTL through `tobj`),
//! [`gltf`] (glTF 2.0 through `gltf`), [`normals`] (face normals, crease-angle vertex
//! normals, repair of file normals) and [`tangents`] (tangent frames for normal maps), which
//! the loaders share. Loaders merge everything a file holds into one [`Mesh`], decode the
//! textures its materials use ([`crate::texture`]), record every file they read or looked
//! for, and report problems that do not stop the load (a missing texture, say) as warnings.
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

pub mod gltf;
pub mod normals;
pub mod obj;
pub mod primitives;
pub mod tangents;

use std::path::{Path, PathBuf};

use std::sync::Arc;

use glam::{Vec2, Vec3, Vec4};

use crate::texture::Texture;

use crate::scene::Material;

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
}

impl Mesh {
    /// Number of triangles, zero-area ones included.
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
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
        if !self.triangle_materials.is_empty() && self.triangle_materials.len() != self.triangles.len() {
            return Err(format!(
                "{} triangle materials for {} triangles",
                self.triangle_materials.len(),
                self.triangles.len()
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
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MeshOptions {
    /// Faces meeting at more than this angle keep separate vertex normals (a hard edge)
    /// when normals are computed because the file has none.
    pub crease_angle_degrees: f32,
}

impl Default for MeshOptions {
    fn default() -> Self {
        MeshOptions {
            crease_angle_degrees: normals::DEFAULT_CREASE_ANGLE_DEGREES,
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
    /// What is wrong, as a sentence fragment without the path (the caller adds location).
    pub message: String,
}

impl MeshError {
    /// A problem with the whole file, or one whose line is unknown.
    pub fn new(path: &Path, message: impl Into<String>) -> Self {
        MeshError {
            path: path.to_path_buf(),
            line: None,
            message: message.into(),
        }
    }

    /// A problem at a 1-based line of the file.
    pub fn at_line(path: &Path, line: usize, message: impl Into<String>) -> Self {
        MeshError {
            line: Some(line),
            ..MeshError::new(path, message)
        }
    }

    /// The file could not be read at all: "cannot read mesh file: No such file or directory".
    pub fn cannot_read(path: &Path, error: &std::io::Error) -> Self {
        MeshError::new(path, format!("cannot read mesh file: {}", io_error_text(error)))
    }
}

/// An I/O error as a user reads it: the operating system's text without the
/// "(os error N)" suffix that Rust appends.
pub(crate) fn io_error_text(error: &std::io::Error) -> String {
    let text = error.to_string();
    match text.find(" (os error") {
        Some(end) => text[..end].to_string(),
        None => text,
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
}
