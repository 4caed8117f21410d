//! Triangle meshes: the built-in primitives and the OBJ / glTF loaders, all producing [`Mesh`].
//!
//! Code map: [`primitives`] (sphere, plane, cube), [`obj`] (OBJ + MTL through `tobj`),
//! [`gltf`] (glTF 2.0 through `gltf`), and [`normals`] (face normals, crease-angle vertex
//! normals, repair of file normals), which both loaders share. Loaders merge everything a
//! file holds into one [`Mesh`], record every file they read, and report problems that do
//! not stop the load as warnings.
//!
//! Architecture invariant: every `Mesh` leaving this module is renderable as it is:
//! positions and normals are finite, normals have unit length, every index is in range,
//! and triangles are wound counter-clockwise when seen from their front side.

pub mod gltf;
pub mod normals;
pub mod obj;
pub mod primitives;

use std::path::{Path, PathBuf};

use glam::Vec3;

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
}

impl Mesh {
    /// Number of triangles, zero-area ones included.
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
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
    /// Every file the load read, the mesh file first.
    pub files_read: Vec<PathBuf>,
    /// Problems that did not stop the load (a missing MTL file, skipped primitives, ...).
    pub warnings: Vec<String>,
}
