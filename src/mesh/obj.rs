//! Wavefront OBJ meshes and their MTL materials: the text parsed by [`super::obj_parse`], the
//! MTL files by `tobj`.
//!
//! # Design
//!
//! Loading has two stages, so that a file several objects name with different crease angles
//! is read and parsed once ([`parse_obj`], then [`ParsedObj::build`] per crease angle):
//!
//! 1. **Parse.** A file that is not OBJ text (a GLB, a glTF's JSON, any binary file) is
//!    refused with what it is ([`FileContent`]). The text is parsed and checked in parallel
//!    ranges of lines ([`super::obj_parse`]: every error with its line and column; polygons
//!    fanned into triangles, so convex polygons only); polyline (`l`) lines are skipped with a
//!    warning. The faces are assembled into one mesh with `tobj`'s grouping and vertex rules
//!    (one vertex per distinct position/texture/normal triple within each model).
//! 2. **Materials.** MTL files are read by this module's own loader when an `mtllib` line names
//!    them, which records each file read (so a watcher follows it) and pre-checks it: colours
//!    with a single number are expanded to grey as the MTL spec allows (`tobj` would panic on
//!    them), and other malformed numbers are reported with their line; `tobj` then parses it
//!    (under `catch_unwind`, as a last line of defence). A missing or malformed MTL file is a
//!    warning, never an error: its materials are absent, and when no library loads the mesh
//!    has no materials at all (the scene then supplies its default).
//!    A library that is named but missing is still recorded in `files_read`, so that a
//!    watcher reloads the mesh when it appears.
//! 3. **Texture coordinates.** `vt` values become [`Mesh::uvs`] with v flipped to the glTF
//!    convention the renderer uses (v' = 1 − v: OBJ's v = 0 is the bottom of the image,
//!    glTF's the top; non-finite ones were rejected by the parser). A model where only some
//!    face vertices have one cannot be trusted: its coordinates are dropped with a warning.
//!    Models without any get zeros when another model has some, so the array stays one per
//!    vertex.
//! 4. **Normals** (the build, per crease angle). When every vertex has a file normal they are
//!    used, renormalised, and any zero or non-finite one is recomputed
//!    ([`normals::repair_normals`]). When none or only some have one, all normals are computed
//!    with the crease angle ([`normals::compute_vertex_normals`]); mixing file and computed
//!    normals across one surface would show a seam, and "only some" usually means a broken
//!    export (a warning says so). Either way the texture coordinates follow their vertices,
//!    and vertices on a UV seam stay apart.
//! 5. **Textures.** `map_Kd` and `map_Ka` are decoded as sRGB colour textures
//!    ([`Texture::load`]) into [`Mesh::textures`], once per file, and bound to the material's
//!    `textures.diffuse` / `textures.ambient` (UV set 0, scale 1, wrap `Repeat`, or
//!    `ClampToEdge` under the statement's `-clamp on` option). Paths are relative to the MTL
//!    file that names them. The statement's options (`-bm 1`, `-o u v w`, ...: see
//!    `texture_file_name`) are skipped; what follows them is the file name, spaces
//!    included, as `tobj` reads it. On Unix a backslash is read as a folder separator, as
//!    Windows exporters write them. A texture that is missing or cannot be decoded is a
//!    warning naming the file, and the material is drawn without it; the file is recorded in
//!    `files_read` either way. A texture on a mesh without texture coordinates is not loaded
//!    (a warning says why). Other maps (`map_Ks`, `bump`, `map_d`, ...) are not used.
//!
//! # MTL to [`Material`]
//!
//! `Ka`→ambient, `Kd`→diffuse, `Ks`→specular, `Ns`→shininess, `Ke`→emission (`tobj` 4.0.5
//! parses `Ke` itself). `illum 0`→[`LightingModel::Unlit`], `1`→[`LightingModel::Lambert`],
//! `2` and above→[`LightingModel::BlinnPhong`] (the MTL spec's illum 2 specular uses the half
//! vector). Missing values, as many OBJ viewers treat them: `Kd` 0.8 grey ([`DEFAULT_DIFFUSE`],
//! also OpenGL's default), `Ka` equal to the diffuse colour (so unlit sides keep the object's
//! colour rather than going black), `Ks` and `Ke` black, `Ns` [`DEFAULT_SHININESS`], no
//! `illum` → Blinn-Phong (with black `Ks` that is plain Lambert). Non-finite numbers are
//! replaced by these defaults with a warning, and a negative `Ns` becomes 0. Faces with no
//! material, or naming one no library defines, use [`default_material`], appended after the
//! file's materials only when some face needs it; when no face names a material the mesh
//! carries none.

use std::borrow::Cow;
use std::io::Cursor;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};

use std::collections::HashMap;
use std::sync::Arc;

use glam::Vec3;

use super::closed::is_closed_in_parts;
use super::normals::VertexAttributes;
use super::obj_parse::{FileNormals, ObjGeometry, ObjText, assemble, parse_obj_text};
use super::{FileContent, LoadedMesh, MeshError, MeshOptions, USE_GLTF_HINT, first_bytes, normals};
use crate::scene::access::FileAccess;
use crate::scene::limits::MAX_LIGHTING_VALUE;
use crate::scene::{LightingModel, Material, TextureBinding};
use crate::texture::{ColorSpace, Sampler, Texture, Wrap};

/// Diffuse colour of an MTL material without `Kd`.
pub const DEFAULT_DIFFUSE: Vec3 = Vec3::splat(0.8);

/// Specular exponent of an MTL material without `Ns`: a moderate highlight, visible only
/// when the material has a `Ks`.
pub const DEFAULT_SHININESS: f32 = 32.0;

/// The material of OBJ faces that name none (or an undefined one) in a file that has
/// materials; also the source of every value an MTL material leaves out.
pub fn default_material() -> Material {
    Material {
        ambient: DEFAULT_DIFFUSE,
        diffuse: DEFAULT_DIFFUSE,
        specular: Vec3::ZERO,
        shininess: DEFAULT_SHININESS,
        emission: Vec3::ZERO,
        model: LightingModel::BlinnPhong,
        textures: Default::default(),
    }
}

/// Loads an OBJ file and the MTL files it names into one [`Mesh`]; see the module
/// documentation for what is checked, computed and defaulted.
pub fn load_obj(path: &Path, options: &MeshOptions) -> Result<LoadedMesh, MeshError> {
    Ok(parse_and_build_obj(path, &options.access, options.crease_angle_degrees)?.1)
}

/// [`load_obj`] on the bytes of the file at `path`, already read (MTL files and textures are
/// still read relative to `path`): the entry point of the fuzzer. The same code path.
pub fn load_obj_from_bytes(
    path: &Path,
    bytes: &[u8],
    options: &MeshOptions,
) -> Result<LoadedMesh, MeshError> {
    let text = parse_text(path, bytes)?;
    let crease = options.crease_angle_degrees;
    let (parsed, loaded) = finish_load(path, text, &options.access, Some(crease))?;
    Ok(loaded.unwrap_or_else(|| parsed.build(crease)))
}

/// Reads and parses an OBJ file, its MTL files and its textures: everything of a load that
/// does not depend on the crease angle (module documentation, steps 1 to 3 and 5).
pub fn parse_obj(path: &Path, access: &FileAccess) -> Result<ParsedObj, MeshError> {
    Ok(finish_load(path, read_and_parse_text(path, access)?, access, None)?.0)
}

/// [`parse_obj`] and then [`ParsedObj::build`] for `crease_angle_degrees`, with the first core
/// free for the build sooner (see [`finish_load`]).
pub fn parse_and_build_obj(
    path: &Path,
    access: &FileAccess,
    crease_angle_degrees: f32,
) -> Result<(ParsedObj, LoadedMesh), MeshError> {
    let text = read_and_parse_text(path, access)?;
    let (parsed, loaded) = finish_load(path, text, access, Some(crease_angle_degrees))?;
    let loaded = loaded.unwrap_or_else(|| parsed.build(crease_angle_degrees));
    Ok((parsed, loaded))
}

/// Reads the OBJ file at `path` and parses its text (module documentation, step 1).
fn read_and_parse_text(path: &Path, access: &FileAccess) -> Result<ObjText, MeshError> {
    let bytes = access
        .read(path)
        .map_err(|error| MeshError::new(path, format!("cannot read mesh file: {error}")))?;
    // The bytes are freed before the rest of the load allocates (`obj_parse`'s
    // documentation: memory).
    parse_text(path, &bytes)
}

/// The rest of a load once the text is parsed: [`finish_parse`], and the mesh built for the
/// crease angle if one is given, on one core; on the other, whether the surface is closed,
/// tested on the parsed text.
///
/// Closedness depends only on the triangles' positions by value, in file order, which the
/// assembly and the build keep (vertices are only split or merged, triangles keep their order),
/// so the text's faces, resolved to position indices, give the mesh's answer. Testing it there
/// lets it start before the faces are assembled: the assembly and the serial stretches of the
/// normals (grouping positions, numbering the vertices) then have the second core busy beside
/// them rather than idle. The price is that the parsed text (positions and face indices, about
/// 2 MB for a scan of 100k triangles) stays allocated until the build ends instead of being
/// freed after the assembly.
fn finish_load(
    path: &Path,
    text: ObjText,
    access: &FileAccess,
    crease_angle_degrees: Option<f32>,
) -> Result<(ParsedObj, Option<LoadedMesh>), MeshError> {
    let (finished, closed) = rayon::join(
        || {
            let parsed = finish_parse(path, &text, access)?;
            let loaded = crease_angle_degrees.map(|crease| parsed.build_surface(crease));
            Ok::<_, MeshError>((parsed, loaded))
        },
        || is_closed_in_parts(text.positions(), &text.triangle_positions()),
    );
    let (mut parsed, mut loaded) = finished?;
    parsed.closed = closed;
    if let Some(loaded) = &mut loaded {
        loaded.mesh.closed = closed;
    }
    Ok((parsed, loaded))
}

/// An OBJ file read and parsed with its materials and textures; [`ParsedObj::build`] makes
/// its mesh for a crease angle.
#[derive(Debug, Clone)]
pub struct ParsedObj {
    geometry: ObjGeometry,
    materials: Vec<Material>,
    /// Per triangle, its index in `materials`; empty when the mesh has no materials.
    triangle_materials: Vec<u32>,
    textures: Vec<Arc<Texture>>,
    files_read: Vec<PathBuf>,
    /// Warnings of the file's text and libraries, then those of its materials and textures
    /// (the build's normals warnings come between them).
    text_warnings: Vec<String>,
    material_warnings: Vec<String>,
    /// Whether the surface is closed ([`Mesh::closed`](super::Mesh::closed)): the same for
    /// every crease angle.
    closed: bool,
}

impl ParsedObj {
    /// The mesh, with its normals as the module documentation says (step 4), and whether it
    /// is closed ([`Mesh::closed`](super::Mesh::closed), tested once at parse).
    pub fn build(&self, crease_angle_degrees: f32) -> LoadedMesh {
        let mut loaded = self.build_surface(crease_angle_degrees);
        loaded.mesh.closed = self.closed;
        loaded
    }

    fn build_surface(&self, crease_angle_degrees: f32) -> LoadedMesh {
        let geometry = &self.geometry;
        let crease = crease_angle_degrees;
        let attributes = VertexAttributes {
            uvs: &geometry.uvs,
            ..VertexAttributes::default()
        };
        let mut warnings = self.text_warnings.clone();
        // Computed normals depend on the crease angle; file normals do not.
        let mut crease_angle_used = true;
        let mut mesh = match &geometry.normals {
            FileNormals::All(file_normals) => {
                let repaired = normals::repair_normals(
                    &geometry.positions,
                    file_normals,
                    attributes,
                    &geometry.triangles,
                    crease,
                );
                crease_angle_used = repaired.replaced_count > 0;
                if repaired.replaced_count > 0 {
                    warnings.push(format!(
                        "{} vertex normals in the file were zero or not finite and were recomputed",
                        repaired.replaced_count
                    ));
                }
                repaired.mesh
            }
            FileNormals::Some => {
                warnings.push(format!(
                    "only some face vertices have normals; all normals were computed (crease angle {crease}°)"
                ));
                normals::compute_vertex_normals(&geometry.positions, attributes, &geometry.triangles, crease)
            }
            FileNormals::None => {
                normals::compute_vertex_normals(&geometry.positions, attributes, &geometry.triangles, crease)
            }
        };
        mesh.materials.clone_from(&self.materials);
        mesh.triangle_materials.clone_from(&self.triangle_materials);
        mesh.split_vertices_shared_by_materials();
        mesh.textures.clone_from(&self.textures);
        warnings.extend(self.material_warnings.iter().cloned());
        LoadedMesh {
            mesh,
            files_read: self.files_read.clone(),
            warnings,
            lights: Vec::new(),
            cameras: Vec::new(),
            crease_angle_used,
        }
    }
}

/// The text of the OBJ file at `path`, parsed and checked (module documentation, step 1).
fn parse_text(path: &Path, bytes: &[u8]) -> Result<ObjText, MeshError> {
    // A glTF or binary file named as `Obj(...)` would otherwise give "contains no triangles"
    // or a confusing line error: say what it is.
    match FileContent::of(bytes) {
        content @ (FileContent::BinaryGltf | FileContent::Json) => {
            return Err(MeshError::new(
                path,
                format!("this is {}, not an OBJ file", content.description()),
            )
            .with_hint(USE_GLTF_HINT));
        }
        FileContent::Binary => {
            return Err(MeshError::new(
                path,
                format!(
                    "this is a binary file (it starts with {}), not an OBJ file, which is text",
                    first_bytes(bytes)
                ),
            )
            .with_hint(USE_GLTF_HINT));
        }
        FileContent::ObjText | FileContent::OtherText => {}
    }
    parse_obj_text(bytes).map_err(|error| MeshError::at(path, error.line, error.column, error.message))
}

/// The rest of [`parse_obj`] once the text is parsed: models, materials, textures.
fn finish_parse(path: &Path, parsed: &ObjText, access: &FileAccess) -> Result<ParsedObj, MeshError> {
    let mut text_warnings = Vec::new();
    if let Some(&first) = parsed.polyline_lines.first() {
        text_warnings.push(format!(
            "ignored {} polyline ('l') elements (first at line {first}): lines are not drawn",
            parsed.polyline_lines.len()
        ));
    }

    let mut libraries = MaterialLibraries {
        access,
        refused: None,
        directory: path.parent().unwrap_or(Path::new("")).to_path_buf(),
        files_read: Vec::new(),
        warnings: Vec::new(),
        materials: Vec::new(),
        material_directories: Vec::new(),
    };
    let geometry = assemble(parsed, |file, line| libraries.load(file, line))
        .map_err(|message| MeshError::new(path, message))?;
    // A library outside the sandbox is an error, not the warning of a missing one: the
    // sandbox must never be silently worked around.
    if let Some((library, line, problem)) = libraries.refused {
        return Err(MeshError::at_line(
            path,
            line,
            format!("mtllib `{library}`: refused: {problem}"),
        ));
    }
    let mut files_read = vec![path.to_path_buf()];
    files_read.extend(libraries.files_read);
    text_warnings.extend(libraries.warnings);
    if !geometry.models_with_partial_uvs.is_empty() {
        text_warnings.push(format!(
            "only some face vertices have texture coordinates in {}; those texture coordinates were dropped",
            geometry
                .models_with_partial_uvs
                .iter()
                .map(|name| format!("'{name}'"))
                .collect::<Vec<_>>()
                .join(", ")
        ));
    }
    if geometry.triangles.is_empty() {
        return Err(MeshError::new(path, "contains no triangles"));
    }

    let library_materials = libraries.materials;
    let mut material_warnings = Vec::new();
    let (mut materials, triangle_materials) =
        assign_materials(&geometry, &library_materials, &mut material_warnings);
    // `assign_materials` keeps the libraries' order: material i is library material i.
    let mut textures = TextureFiles {
        access: access.clone(),
        ..TextureFiles::default()
    };
    let has_uvs = !geometry.uvs.is_empty();
    let with_directories = library_materials.iter().zip(&libraries.material_directories);
    for (material, (mtl, directory)) in materials.iter_mut().zip(with_directories) {
        bind_textures(
            material,
            mtl,
            directory,
            has_uvs,
            &mut textures,
            &mut material_warnings,
        );
    }
    if let Some(problem) = textures.refused {
        return Err(MeshError::new(path, problem));
    }
    files_read.extend(textures.files_read);
    if !library_materials.is_empty() {
        let mut reported: Vec<&str> = Vec::new();
        for (name, line) in &parsed.material_uses {
            let defined = library_materials.iter().any(|material| &material.name == name);
            if !defined && !reported.contains(&name.as_str()) {
                reported.push(name);
                material_warnings.push(format!(
                    "line {line}: material '{name}' is not defined in the material libraries; its faces use the default material"
                ));
            }
        }
    }

    Ok(ParsedObj {
        geometry,
        materials,
        triangle_materials,
        textures: textures.loaded,
        files_read,
        text_warnings,
        material_warnings,
        // Tested beside the assembly and set by `finish_load`.
        closed: false,
    })
}

/// Reads the MTL files `mtllib` lines name, relative to the OBJ's directory, recording what
/// was read and what went wrong.
struct MaterialLibraries<'a> {
    access: &'a FileAccess,
    /// A library the sandbox refused (as named in the OBJ file), its line, and why: an error.
    refused: Option<(String, usize, String)>,
    directory: PathBuf,
    /// Libraries read, and libraries named but missing (for a watcher).
    files_read: Vec<PathBuf>,
    warnings: Vec<String>,
    /// The materials of every library that loaded, in order.
    materials: Vec<tobj::Material>,
    /// The folder of the library of each material (texture paths are relative to it).
    material_directories: Vec<PathBuf>,
}

impl MaterialLibraries<'_> {
    /// Loads the library `library` (named at `line`) and returns its material names, or
    /// `None` (after a warning, or an error for the sandbox) when it cannot be used.
    fn load(&mut self, library: &str, line: usize) -> Option<Vec<String>> {
        let path = self.directory.join(library);
        let warn = |warnings: &mut Vec<String>, problem: String| {
            warnings.push(format!(
                "material library {}: {problem}; its materials are not used",
                path.display()
            ));
        };
        // Recorded even when it cannot be read: a watcher then reloads when it appears.
        if !self.files_read.contains(&path) {
            self.files_read.push(path.clone());
        }
        let bytes = match self.access.read(&path) {
            Ok(bytes) => bytes,
            Err(error) if error.is_sandbox() => {
                self.refused
                    .get_or_insert_with(|| (library.to_string(), line, error.to_string()));
                return None;
            }
            Err(error) => {
                warn(&mut self.warnings, format!("cannot read it: {error}"));
                return None;
            }
        };
        let text = String::from_utf8_lossy(&bytes);
        let text = match prepare_mtl(&text) {
            Ok(text) => text,
            Err((line, message)) => {
                warn(&mut self.warnings, format!("line {line}: {message}"));
                return None;
            }
        };
        let parsed = catch_unwind(AssertUnwindSafe(|| {
            tobj::load_mtl_buf(&mut Cursor::new(text.as_bytes()))
        }));
        let materials = match parsed {
            Ok(Ok((materials, _))) => materials,
            Ok(Err(error)) => {
                warn(&mut self.warnings, error.to_string());
                return None;
            }
            Err(_) => {
                warn(
                    &mut self.warnings,
                    "the MTL parser gave up on this file".to_string(),
                );
                return None;
            }
        };
        let directory = path.parent().unwrap_or(Path::new("")).to_path_buf();
        self.material_directories
            .extend(std::iter::repeat_n(directory, materials.len()));
        let names = materials.iter().map(|material| material.name.clone()).collect();
        self.materials.extend(materials);
        Some(names)
    }
}

/// Checks the numeric MTL statements `tobj` parses, reporting the line of a bad one, and
/// expands single-number colours (`Kd 0.5` means `Kd 0.5 0.5 0.5` in the MTL spec; `tobj`
/// would panic on it).
fn prepare_mtl(text: &str) -> Result<Cow<'_, str>, (usize, String)> {
    let mut expanded: Vec<(usize, String)> = Vec::new();
    for (index, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace().take_while(|word| !word.starts_with('#'));
        let Some(keyword) = words.next() else {
            continue;
        };
        let arguments: Vec<&str> = words.collect();
        let fail = |message: String| (index + 1, message);
        match keyword {
            "Ka" | "Kd" | "Ks" | "Ke" => {
                let numbers = arguments
                    .iter()
                    .take(3)
                    .filter(|w| w.parse::<f32>().is_ok())
                    .count();
                match (arguments.len(), numbers) {
                    (1, 1) => expanded.push((index, format!("{keyword} {0} {0} {0}", arguments[0]))),
                    (3.., 3) => {}
                    _ if matches!(arguments.first(), Some(&"spectral") | Some(&"xyz")) => {
                        return Err(fail(format!(
                            "{keyword}: spectral and xyz colours are not supported"
                        )));
                    }
                    _ => return Err(fail(format!("{keyword} needs one number or three (r g b)"))),
                }
            }
            "Ns" | "Ni" | "d" if arguments.first().is_none_or(|w| w.parse::<f32>().is_err()) => {
                return Err(fail(format!("{keyword} needs a number")));
            }
            "illum" if arguments.first().is_none_or(|w| w.parse::<u8>().is_err()) => {
                return Err(fail("illum needs a whole number from 0 to 10".to_string()));
            }
            "newmtl" if arguments.is_empty() => {
                return Err(fail("newmtl needs a name".to_string()));
            }
            _ => {}
        }
    }
    if expanded.is_empty() {
        return Ok(Cow::Borrowed(text));
    }
    let mut replacements = expanded.into_iter().peekable();
    let lines: Vec<Cow<str>> = text
        .lines()
        .enumerate()
        .map(
            |(index, line)| match replacements.next_if(|(at, _)| *at == index) {
                Some((_, replacement)) => Cow::Owned(replacement),
                None => Cow::Borrowed(line),
            },
        )
        .collect();
    Ok(Cow::Owned(lines.join("\n")))
}

/// The mesh's materials and per-triangle material indices from the libraries' materials
/// (module documentation: "MTL to Material"); both empty when no face names a known material.
fn assign_materials(
    geometry: &ObjGeometry,
    library_materials: &[tobj::Material],
    warnings: &mut Vec<String>,
) -> (Vec<Material>, Vec<u32>) {
    let known = |id: &Option<usize>| id.filter(|&id| id < library_materials.len());
    let runs = &geometry.material_runs;
    if library_materials.is_empty() || runs.iter().all(|(_, id)| known(id).is_none()) {
        return (Vec::new(), Vec::new());
    }
    let mut materials: Vec<Material> = library_materials
        .iter()
        .map(|material| material_from_mtl(material, warnings))
        .collect();
    let default_index = materials.len() as u32;
    let triangle_materials: Vec<u32> = geometry
        .triangle_material_ids()
        .map(|id| known(&id).map_or(default_index, |id| id as u32))
        .collect();
    if triangle_materials.contains(&default_index) {
        materials.push(default_material());
    }
    (materials, triangle_materials)
}

/// One MTL material as a [`Material`] (module documentation: "MTL to Material").
fn material_from_mtl(mtl: &tobj::Material, warnings: &mut Vec<String>) -> Material {
    let defaults = default_material();
    let mut colour = |value: Option<[f32; 3]>, statement: &str, default: Vec3| match value.map(Vec3::from) {
        None => default,
        Some(colour) if !colour.is_finite() => {
            warnings.push(format!(
                "material '{}': {statement} is not finite; the default is used",
                mtl.name
            ));
            default
        }
        Some(colour) => {
            let max = MAX_LIGHTING_VALUE as f32;
            if colour.min_element() < 0.0 || colour.max_element() > max {
                warnings.push(format!(
                    "material '{}': {statement} has components outside [0, {max}]; they are clamped",
                    mtl.name
                ));
            }
            colour.clamp(Vec3::ZERO, Vec3::splat(max))
        }
    };
    let diffuse = colour(mtl.diffuse, "Kd", defaults.diffuse);
    let ambient = colour(mtl.ambient, "Ka", diffuse);
    let specular = colour(mtl.specular, "Ks", defaults.specular);
    let emission = colour(mtl.emissive, "Ke", defaults.emission);
    let shininess = match mtl.shininess {
        None => defaults.shininess,
        Some(ns) if ns.is_finite() => ns.max(0.0),
        Some(_) => {
            warnings.push(format!(
                "material '{}': Ns is not finite; the default is used",
                mtl.name
            ));
            defaults.shininess
        }
    };
    let model = match mtl.illumination_model {
        Some(0) => LightingModel::Unlit,
        Some(1) => LightingModel::Lambert,
        _ => LightingModel::BlinnPhong,
    };
    Material {
        ambient,
        diffuse,
        specular,
        shininess,
        emission,
        model,
        textures: Default::default(),
    }
}

/// The textures of one OBJ load: each file decoded once, whatever the number of materials
/// and statements naming it.
#[derive(Default)]
struct TextureFiles {
    /// Becomes [`Mesh::textures`].
    loaded: Vec<Arc<Texture>>,
    /// Each file tried, with its index in `loaded`, or `None` when it failed (and was
    /// reported).
    index_by_path: HashMap<PathBuf, Option<u32>>,
    /// Every texture file tried, found or not, in order.
    files_read: Vec<PathBuf>,
    access: FileAccess,
    /// The first texture the sandbox refused: an error, not a warning.
    refused: Option<String>,
}

impl TextureFiles {
    /// The index of the texture in `path`, loading it the first time; `None` (after one
    /// warning naming the file) when it is missing or cannot be decoded.
    fn index_of(
        &mut self,
        path: &Path,
        statement: &str,
        material: &str,
        warnings: &mut Vec<String>,
    ) -> Option<u32> {
        if let Some(&known) = self.index_by_path.get(path) {
            return known;
        }
        self.files_read.push(path.to_path_buf());
        let loaded = match self.access.read(path) {
            Ok(bytes) => {
                Texture::from_encoded(&bytes, ColorSpace::Srgb).map(|texture| texture.read_from(path))
            }
            Err(error) if error.is_sandbox() => {
                self.refused.get_or_insert_with(|| {
                    format!(
                        "texture {} ({statement} of material '{material}'): refused: {error}",
                        path.display()
                    )
                });
                Err(error.to_string())
            }
            Err(error) => Err(format!("cannot read it: {error}")),
        };
        let index = match loaded {
            Ok(texture) => {
                self.loaded.push(Arc::new(texture));
                Some((self.loaded.len() - 1) as u32)
            }
            Err(problem) => {
                warnings.push(format!(
                    "texture {} ({statement} of material '{material}'): {problem}; materials using it are drawn without it",
                    path.display()
                ));
                None
            }
        };
        self.index_by_path.insert(path.to_path_buf(), index);
        index
    }
}

/// Binds the `map_Kd` and `map_Ka` textures of one MTL material, whose library is in
/// `directory` (module documentation, step 6). Without texture coordinates (`has_uvs`
/// false) nothing is loaded.
fn bind_textures(
    material: &mut Material,
    mtl: &tobj::Material,
    directory: &Path,
    has_uvs: bool,
    textures: &mut TextureFiles,
    warnings: &mut Vec<String>,
) {
    let statements = [
        ("map_Kd", mtl.diffuse_texture.as_deref()),
        ("map_Ka", mtl.ambient_texture.as_deref()),
    ];
    for (statement, arguments) in statements {
        let Some(arguments) = arguments else {
            continue;
        };
        if !has_uvs {
            warnings.push(format!(
                "material '{}': {statement} is not used: the OBJ file has no texture coordinates (vt)",
                mtl.name
            ));
            continue;
        }
        let Some(file) = texture_file_name(arguments) else {
            warnings.push(format!(
                "material '{}': {statement} names no file after its options; it is not used",
                mtl.name
            ));
            continue;
        };
        let Some(texture) = textures.index_of(&directory.join(file.name), statement, &mtl.name, warnings)
        else {
            continue;
        };
        let wrap = if file.clamp {
            Wrap::ClampToEdge
        } else {
            Wrap::Repeat
        };
        let binding = TextureBinding {
            texture,
            uv_set: 0,
            sampler: Sampler {
                wrap_s: wrap,
                wrap_t: wrap,
            },
            scale: 1.0,
        };
        if statement == "map_Kd" {
            material.textures.diffuse = Some(binding);
        } else {
            material.textures.ambient = Some(binding);
        }
    }
}

/// What a `map_*` statement names, once its options are read.
#[derive(Debug, PartialEq)]
struct TextureFileName {
    /// The file, relative to the MTL file's folder.
    name: String,
    /// `-clamp on`: coordinates outside [0, 1] are clamped rather than repeated.
    clamp: bool,
}

/// Reads the arguments of a `map_Kd`-style statement (everything after the keyword): the
/// MTL options first (`-blendu`, `-blendv`, `-bm`, `-boost`, `-cc`, `-clamp`, `-imfchan`,
/// `-texres` and `-type` take one value, `-mm` two, `-o`, `-s` and `-t` one to three
/// numbers), then the file name, which may contain spaces. An unknown option is taken as the
/// start of the file name. `None` when no file name is left.
fn texture_file_name(arguments: &str) -> Option<TextureFileName> {
    let mut rest = arguments.trim();
    let mut clamp = false;
    while rest.starts_with('-') {
        let (option, after) = split_word(rest);
        let (values, numbers_only) = match option {
            "-blendu" | "-blendv" | "-bm" | "-boost" | "-cc" | "-clamp" | "-imfchan" | "-texres"
            | "-type" => (1, false),
            "-mm" => (2, false),
            "-o" | "-s" | "-t" => (3, true),
            _ => break,
        };
        rest = after;
        for taken in 0..values {
            let (value, after) = split_word(rest);
            // -o, -s and -t take one to three numbers: stop at the first word that is not.
            if numbers_only && taken > 0 && value.parse::<f32>().is_err() {
                break;
            }
            if option == "-clamp" {
                clamp = value == "on";
            }
            rest = after;
        }
    }
    let name = rest.trim();
    if name.is_empty() {
        return None;
    }
    let name = if cfg!(windows) {
        name.to_string()
    } else {
        name.replace('\\', "/")
    };
    Some(TextureFileName { name, clamp })
}

/// The first whitespace-separated word of `text` (which starts with it) and what follows,
/// trimmed at the start.
fn split_word(text: &str) -> (&str, &str) {
    let text = text.trim_start();
    let end = text.find(char::is_whitespace).unwrap_or(text.len());
    (&text[..end], text[end..].trim_start())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::Mesh;
    use glam::Vec2;

    fn asset(relative: &str) -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("assets/obj")
            .join(relative)
    }

    fn load(path: &Path) -> Result<LoadedMesh, MeshError> {
        load_obj(path, &MeshOptions::default())
    }

    /// Loads a copied asset and checks its triangle count (from `assets/LICENSES.md`) and
    /// the module invariant: finite positions, unit normals, indices in range, one
    /// material index per triangle when there are materials.
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

    /// A directory of its own under the system temporary directory, removed on drop.
    fn scratch_dir() -> tempfile::TempDir {
        tempfile::Builder::new()
            .prefix("lampshade-obj-test")
            .tempdir()
            .unwrap_or_else(|e| panic!("cannot create a temporary directory: {e}"))
    }

    fn write(dir: &Path, name: &str, text: impl AsRef<[u8]>) -> PathBuf {
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap_or_else(|e| panic!("cannot write {}: {e}", path.display()));
        path
    }

    /// Loads `obj` (written to a scratch directory with the given MTL files) and returns
    /// the result.
    fn load_text(obj: &str, mtl_files: &[(&str, &str)]) -> Result<LoadedMesh, MeshError> {
        let dir = scratch_dir();
        for (name, text) in mtl_files {
            write(dir.path(), name, text);
        }
        load(&write(dir.path(), "test.obj", obj))
    }

    /// Expects `obj` to be rejected with `message` (a substring) at `line`.
    fn check_error(obj: &str, line: Option<usize>, message: &str) {
        match load_text(obj, &[]) {
            Ok(loaded) => panic!(
                "expected an error, loaded {} triangles",
                loaded.mesh.triangle_count()
            ),
            Err(error) => {
                assert_eq!(error.line, line, "{error:?}");
                assert!(
                    error.message.contains(message),
                    "{error:?} should contain {message:?}"
                );
            }
        }
    }

    const TRIANGLE: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";

    #[test]
    fn triangle_counts_match_the_asset_list() {
        check_asset("cornell-box/CornellBox-Original.obj", 36);
        check_asset("teapot/teapot.obj", 6320);
        check_asset("spot/spot_triangulated.obj", 5856);
        check_asset("spot/spot_quadrangulated.obj", 5856);
        check_asset("spot/spot_control_mesh.obj", 372);
        check_asset("tobj-fixtures/cornell_box.obj", 36);
        check_asset("tobj-fixtures/quad.obj", 5);
        check_asset("tobj-fixtures/triangle.obj", 1);
    }

    #[test]
    fn closedness_of_the_parsed_geometry_is_that_of_the_built_mesh() {
        for (relative, closed) in [
            ("spot/spot_triangulated.obj", true),
            ("spot/spot_quadrangulated.obj", true),
            ("koala/koala.obj", true),
            ("teapot/teapot.obj", false),
            ("cornell-box/CornellBox-Original.obj", false),
        ] {
            let parsed = parse_obj(&asset(relative), &FileAccess::default())
                .unwrap_or_else(|e| panic!("{relative}: {e:?}"));
            for crease in [0.0, 60.0, 180.0] {
                let mesh = parsed.build(crease).mesh;
                assert_eq!(mesh.closed, closed, "{relative} at {crease}°");
                assert_eq!(
                    crate::mesh::closed::is_closed(&mesh.positions, &mesh.triangles),
                    closed,
                    "{relative} at {crease}°, tested on the built mesh"
                );
            }
        }
    }

    /// FNV-1a over the bits of everything a load gives a mesh, but its materials and textures.
    fn mesh_bits_hash(mesh: &Mesh) -> u64 {
        let floats = mesh
            .positions
            .iter()
            .chain(&mesh.normals)
            .flat_map(|v| v.to_array());
        let uvs = mesh.uvs.iter().flat_map(|v| v.to_array());
        let words = floats
            .chain(uvs)
            .map(f32::to_bits)
            .chain(mesh.triangles.iter().flatten().copied())
            .chain(mesh.triangle_materials.iter().copied())
            .chain([mesh.closed as u32]);
        words.fold(0xcbf2_9ce4_8422_2325u64, |hash, word| {
            (hash ^ u64::from(word)).wrapping_mul(0x0100_0000_01b3)
        })
    }

    /// Loading is made faster commit by commit, never by changing a bit of what it gives: the
    /// meshes of the scans and models, at the crease angles of their scenes and at 60°, hash
    /// as they did before (computed at `faf54e9`).
    #[test]
    fn loaded_meshes_keep_their_bits() {
        let mut hashes = Vec::new();
        for relative in [
            "koala/koala.obj",
            "nefertiti/nefertiti-lowres.obj",
            "spot/spot_triangulated.obj",
            "teapot/teapot.obj",
            "cornell-box/CornellBox-Original.obj",
        ] {
            let parsed = parse_obj(&asset(relative), &FileAccess::default())
                .unwrap_or_else(|e| panic!("{relative}: {e:?}"));
            for crease in [180.0, 60.0] {
                hashes.push((relative, crease, mesh_bits_hash(&parsed.build(crease).mesh)));
            }
        }
        let expected: [u64; 10] = [
            0x29b8_985f_2b79_d95d,
            0xab44_2d3c_4469_4fb4,
            0x5fce_be78_f619_61aa,
            0x8b31_a18b_1028_4166,
            0x530a_a15b_27e6_f056,
            0x21f6_c672_e3f4_4781,
            0x78d0_d450_7ed2_ce6f,
            0x9d24_0ddb_c185_bbaf,
            0xd0d6_a736_fa34_7e2d,
            0xbe58_5b3d_343e_99a9,
        ];
        for ((relative, crease, hash), expected) in hashes.into_iter().zip(expected) {
            assert_eq!(hash, expected, "{relative} at {crease}°");
        }
    }

    #[test]
    fn cornell_box_materials_come_from_its_mtl() {
        let loaded = check_asset("cornell-box/CornellBox-Original.obj", 36);
        let mesh = &loaded.mesh;
        assert_eq!(
            mesh.materials.len(),
            8,
            "every face has a material: no default appended"
        );
        assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
        assert_eq!(
            loaded.files_read,
            vec![
                asset("cornell-box/CornellBox-Original.obj"),
                asset("cornell-box/CornellBox-Original.mtl")
            ]
        );
        let light = mesh
            .materials
            .iter()
            .find(|m| m.emission != Vec3::ZERO)
            .unwrap_or_else(|| panic!("no emissive material"));
        assert_eq!(light.emission, Vec3::new(17.0, 12.0, 4.0));
        assert_eq!(light.diffuse, Vec3::splat(0.78));
        assert_eq!(light.model, LightingModel::BlinnPhong);
        let left_wall = mesh.materials[0];
        assert_eq!(left_wall.ambient, Vec3::new(0.63, 0.065, 0.05));
        assert_eq!(left_wall.specular, Vec3::ZERO);
        assert_eq!(left_wall.shininess, 10.0);
        // The box's faces are flat and meet at right angles: each face vertex keeps its
        // face's normal, so every corner normal is the triangle's own.
        for triangle in &mesh.triangles {
            let [a, b, c] = triangle.map(|v| mesh.positions[v as usize]);
            let face = normals::face_normal(a, b, c);
            for &v in triangle {
                assert!(mesh.normals[v as usize].dot(face) > 0.999);
            }
        }
    }

    #[test]
    fn negative_indices_count_back_from_the_last_vertex() {
        let loaded = check_asset("tobj-fixtures/triangle.obj", 1);
        let [a, b, c] = loaded.mesh.triangles[0].map(|v| loaded.mesh.positions[v as usize]);
        assert_eq!([a, b, c], [Vec3::ZERO, Vec3::X, Vec3::Y]);
        // Relative indices after more vertices: -3 -2 -1 are the last three defined.
        let obj = format!("v 9 9 9\n{TRIANGLE}f -3 -2 -1\nv 5 5 5\nf 1 2 -1\n");
        let mesh = load_text(&obj, &[])
            .map(|l| l.mesh)
            .unwrap_or_else(|e| panic!("{e:?}"));
        let corners = |t: usize| mesh.triangles[t].map(|v| mesh.positions[v as usize]);
        assert_eq!(corners(0), [Vec3::ZERO, Vec3::X, Vec3::Y]);
        assert_eq!(corners(1), [Vec3::splat(9.0), Vec3::ZERO, Vec3::splat(5.0)]);
    }

    #[test]
    fn tobj_fixture_materials_and_both_libraries_are_read() {
        let loaded = check_asset("tobj-fixtures/cornell_box.obj", 36);
        assert_eq!(loaded.files_read.len(), 3, "{:?}", loaded.files_read);
        let white = loaded
            .mesh
            .materials
            .iter()
            .find(|m| m.diffuse == Vec3::ONE && m.emission == Vec3::ONE);
        assert!(white.is_some(), "white has Ke 1 1 1: {:?}", loaded.mesh.materials);
    }

    #[test]
    fn teapot_without_normals_gets_unit_normals() {
        let loaded = check_asset("teapot/teapot.obj", 6320);
        assert!(loaded.mesh.materials.is_empty());
        assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
        // At the point of a smooth closed surface farthest along a direction, the normal
        // is that direction. The teapot is closed except for the spout's opening and
        // perhaps the base, so check the top (lid knob), the handle's back (-X) and the
        // body's sides (±Z).
        let mesh = &loaded.mesh;
        for direction in [Vec3::Y, -Vec3::X, Vec3::Z, -Vec3::Z] {
            let farthest = (0..mesh.positions.len())
                .max_by(|&a, &b| {
                    mesh.positions[a]
                        .dot(direction)
                        .total_cmp(&mesh.positions[b].dot(direction))
                })
                .unwrap_or_default();
            let normal = mesh.normals[farthest];
            assert!(
                normal.dot(direction) > 0.9,
                "normal {normal} at the point farthest along {direction}"
            );
        }
    }

    #[test]
    fn partial_normals_are_all_computed_with_a_warning() {
        let loaded = check_asset("tobj-fixtures/quad.obj", 5);
        assert!(
            loaded.warnings.iter().any(|w| w.contains("only some")),
            "{:?}",
            loaded.warnings
        );
        // Everything lies in z = 0 and faces +Z, whether the file said so or not.
        assert!(loaded.mesh.normals.iter().all(|&n| n == Vec3::Z));
    }

    #[test]
    fn file_normals_are_used_and_repaired() {
        let obj = format!("{TRIANGLE}vn 0 0 2\nvn 0 0 0\nf 1//1 2//1 3//2\n");
        let loaded = load_text(&obj, &[]).unwrap_or_else(|e| panic!("{e:?}"));
        check_invariant(&loaded.mesh);
        assert!(loaded.mesh.normals.iter().all(|&n| n == Vec3::Z));
        assert!(
            loaded.warnings.iter().any(|w| w.contains("1 vertex normals")),
            "{:?}",
            loaded.warnings
        );
        // A tilted file normal is kept as given (renormalised), not recomputed.
        let obj = format!("{TRIANGLE}vn 0 3 4\nf 1//1 2//1 3//1\n");
        let mesh = load_text(&obj, &[])
            .map(|l| l.mesh)
            .unwrap_or_else(|e| panic!("{e:?}"));
        assert!(
            mesh.normals
                .iter()
                .all(|n| n.distance(Vec3::new(0.0, 0.6, 0.8)) < 1e-6)
        );
    }

    #[test]
    fn missing_mtl_is_a_warning_and_leaves_no_materials() {
        let obj = format!("mtllib nowhere.mtl\nusemtl red\n{TRIANGLE}f 1 2 3\n");
        let loaded = load_text(&obj, &[]).unwrap_or_else(|e| panic!("{e:?}"));
        assert!(loaded.mesh.materials.is_empty() && loaded.mesh.triangle_materials.is_empty());
        assert_eq!(loaded.warnings.len(), 1, "{:?}", loaded.warnings);
        assert!(loaded.warnings[0].contains("nowhere.mtl") && loaded.warnings[0].contains("cannot read"));
        // Recorded all the same, so that a watcher reloads the mesh when it appears.
        assert_eq!(loaded.files_read.len(), 2, "{:?}", loaded.files_read);
        assert!(loaded.files_read[1].ends_with("nowhere.mtl"));
    }

    #[test]
    fn mtl_colours_beyond_the_lighting_limit_are_clamped_with_a_warning() {
        let mtl = "newmtl hot\nKd 1e30 0.5 -2\nKs 0.5 0.5 0.5\n";
        let obj = format!("mtllib hot.mtl\nusemtl hot\n{TRIANGLE}f 1 2 3\n");
        let loaded = load_text(&obj, &[("hot.mtl", mtl)]).unwrap_or_else(|e| panic!("{e:?}"));
        let material = loaded.mesh.materials[0];
        assert_eq!(material.diffuse, Vec3::new(MAX_LIGHTING_VALUE as f32, 0.5, 0.0));
        assert_eq!(material.specular, Vec3::splat(0.5));
        assert!(
            loaded
                .warnings
                .iter()
                .any(|w| w.contains("'hot'") && w.contains("Kd") && w.contains("clamped")),
            "{:?}",
            loaded.warnings
        );
    }

    #[test]
    fn malformed_mtl_is_a_warning_with_its_line() {
        let mtl = "newmtl red\nKd 1 0\n";
        let obj = format!("mtllib bad.mtl\nusemtl red\n{TRIANGLE}f 1 2 3\n");
        let loaded = load_text(&obj, &[("bad.mtl", mtl)]).unwrap_or_else(|e| panic!("{e:?}"));
        assert!(loaded.mesh.materials.is_empty());
        assert!(
            loaded
                .warnings
                .iter()
                .any(|w| w.contains("bad.mtl") && w.contains("line 2")),
            "{:?}",
            loaded.warnings
        );
        assert_eq!(loaded.files_read.len(), 2, "a malformed library was still read");
    }

    #[test]
    fn mtl_defaults_and_illumination_models() {
        let mtl = "newmtl flat\nKd 0.5\nillum 0\n\
                   newmtl matte\nKa 0.1 0.1 0.1\nillum 1\n\
                   newmtl shiny\nKs 1 1 1\nNs 200\nillum 2\n";
        let obj = format!(
            "mtllib m.mtl\n{TRIANGLE}usemtl flat\nf 1 2 3\nusemtl matte\nf 1 2 3\nusemtl shiny\nf 1 2 3\nusemtl nothing\nf 1 2 3\n"
        );
        let loaded = load_text(&obj, &[("m.mtl", mtl)]).unwrap_or_else(|e| panic!("{e:?}"));
        let mesh = &loaded.mesh;
        check_invariant(mesh);
        assert_eq!(
            mesh.triangle_materials,
            vec![0, 1, 2, 3],
            "undefined 'nothing' uses the appended default"
        );
        let [flat, matte, shiny, fallback] = [0, 1, 2, 3].map(|i| mesh.materials[i]);
        assert_eq!(
            (flat.diffuse, flat.ambient, flat.model),
            (Vec3::splat(0.5), Vec3::splat(0.5), LightingModel::Unlit)
        );
        assert_eq!(
            (matte.diffuse, matte.ambient, matte.model),
            (DEFAULT_DIFFUSE, Vec3::splat(0.1), LightingModel::Lambert)
        );
        assert_eq!(
            (shiny.specular, shiny.shininess, shiny.model),
            (Vec3::ONE, 200.0, LightingModel::BlinnPhong)
        );
        assert_eq!(fallback, default_material());
        assert!(
            loaded
                .warnings
                .iter()
                .any(|w| w.contains("'nothing'") && w.contains("line 11")),
            "{:?}",
            loaded.warnings
        );
    }

    #[test]
    fn faces_without_material_get_the_default_only_when_needed() {
        let mtl = "newmtl red\nKd 1 0 0\n";
        let obj = format!("mtllib m.mtl\n{TRIANGLE}f 1 2 3\nusemtl red\nf 1 3 2\n");
        let mesh = load_text(&obj, &[("m.mtl", mtl)])
            .map(|l| l.mesh)
            .unwrap_or_else(|e| panic!("{e:?}"));
        assert_eq!(mesh.materials.len(), 2);
        assert_eq!(mesh.triangle_materials, vec![1, 0]);
        // No face names a material: the library is irrelevant and the mesh carries none.
        let obj = format!("mtllib m.mtl\n{TRIANGLE}f 1 2 3\n");
        let mesh = load_text(&obj, &[("m.mtl", mtl)])
            .map(|l| l.mesh)
            .unwrap_or_else(|e| panic!("{e:?}"));
        assert!(mesh.materials.is_empty() && mesh.triangle_materials.is_empty());
    }

    #[test]
    fn out_of_range_and_zero_indices_are_errors_with_lines() {
        check_error(&format!("{TRIANGLE}f 1 2 4\n"), Some(4), "vertex 4, but only 3");
        check_error(&format!("{TRIANGLE}f 1 2 -4\n"), Some(4), "vertex -4");
        check_error(&format!("{TRIANGLE}f 0 1 2\n"), Some(4), "index 0");
        check_error(
            &format!("{TRIANGLE}f 1/1 2/1 3/1\n"),
            Some(4),
            "texture coordinate 1, but only 0",
        );
        check_error(
            &format!("{TRIANGLE}vn 0 0 1\nf 1//1 2//2 3//1\n"),
            Some(5),
            "normal 2",
        );
        check_error(
            &format!("{TRIANGLE}f 1 2 -99999999999999\n"),
            Some(4),
            "vertex -99999999999999",
        );
        check_error(
            &format!("{TRIANGLE}f 1 2 99999999999999999999\n"),
            Some(4),
            "malformed face vertex",
        );
        check_error(
            &format!("{TRIANGLE}f 1/2/3/4 2 3\n"),
            Some(4),
            "malformed face vertex",
        );
        // Forward references are not OBJ: the vertex must be defined above the face.
        check_error(
            "v 0 0 0\nv 1 0 0\nf 1 2 3\nv 0 1 0\n",
            Some(3),
            "vertex 3, but only 2",
        );
    }

    #[test]
    fn bad_positions_are_errors_with_lines() {
        check_error("v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n", Some(2), "not finite");
        check_error("v 0 0 0\nv 1 1e39 0\n", Some(2), "not finite");
        // Normals and texture coordinates too (issue 6): rejected, not repaired.
        check_error("v 0 0 0\nvn 0 NaN 1\n", Some(2), "normal is not finite");
        check_error("v 0 0 0\nvn 0 0 -inf\n", Some(2), "normal is not finite");
        check_error(
            "vt 0.5 0.5\nvt 1e39 0\n",
            Some(2),
            "texture coordinate is not finite",
        );
        // A face cut off after a slash, which tobj accepts.
        check_error(
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/1 3/",
            Some(5),
            "ends with '/'",
        );
        check_error(
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1/ 2/1 3/1\n",
            Some(5),
            "truncated",
        );
        check_error("v 0 0\n", Some(1), "three numbers");
        check_error("v 0 0 1 0\n", Some(1), "w must be non-zero");
    }

    #[test]
    fn files_that_cannot_be_meshes_are_errors() {
        check_error("# nothing\nv 0 0 0\n", None, "contains no triangles");
        check_error(&format!("{TRIANGLE}l 1 2 3\n"), None, "contains no triangles");
        let missing = scratch_dir().path().join("missing.obj");
        let error = load(&missing).err();
        assert_eq!(
            error.map(|e| e.message),
            Some("cannot read mesh file: no such file".to_string())
        );
    }

    #[test]
    fn polylines_are_dropped_with_a_warning() {
        let obj = format!("{TRIANGLE}l 1 2 3\nf 1 2 3\n");
        let loaded = load_text(&obj, &[]).unwrap_or_else(|e| panic!("{e:?}"));
        assert_eq!(loaded.mesh.triangle_count(), 1, "the polyline is not a triangle");
        assert_eq!(loaded.warnings.len(), 1, "{:?}", loaded.warnings);
        assert!(loaded.warnings[0].contains("line 4"));
    }

    #[test]
    fn faces_with_fewer_than_three_vertices_are_errors_with_line_and_column() {
        // Cut after a space, cut after the keyword, a two-vertex face in the middle of a
        // file, and one indented by a tab: each is the error, wherever it is.
        for (face, column, count) in [("f 1 3 ", 1, 2), ("f", 1, 0), ("f 1", 1, 1), ("\t f 2 3", 3, 2)] {
            for (text, line) in [
                (format!("{TRIANGLE}f 1 2 3\n{face}"), 5),
                (format!("{TRIANGLE}{face}\nf 1 2 3\n"), 4),
            ] {
                let error = load_text(&text, &[])
                    .err()
                    .unwrap_or_else(|| panic!("{text:?} loaded"));
                assert_eq!(
                    (error.line, error.column),
                    (Some(line), Some(column)),
                    "{text:?}: {error:?}"
                );
                assert!(
                    error
                        .message
                        .contains(&format!("at least 3 vertices, this one has {count}")),
                    "{error:?}"
                );
            }
        }
        // Columns count characters, and a bad vertex is pointed at itself.
        let error = load_text(&format!("{TRIANGLE}f 1 2 0\n"), &[]).err();
        assert_eq!(error.map(|e| (e.line, e.column)), Some((Some(4), Some(7))));
        let error = load_text(&format!("{TRIANGLE}# é\nvn 0 0 1\n  vt é 0\n"), &[]).err();
        assert_eq!(error.map(|e| (e.line, e.column)), Some((Some(6), Some(3))));
    }

    #[test]
    fn files_of_another_kind_say_what_they_are() {
        let dir = scratch_dir();
        let glb =
            std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/gltf/Box/glTF-Binary/Box.glb"))
                .unwrap_or_default();
        let cases: [(&[u8], &str); 3] = [
            (&glb, "this is a binary glTF (GLB) file, not an OBJ file"),
            (
                b" {\"asset\": {\"version\": \"2.0\"}}",
                "this is a JSON (glTF) file, not an OBJ file",
            ),
            (
                b"\x89PNG\r\n\x1a\n\0\0\0\rIHDR",
                "binary file (it starts with 89 50 4E 47 (\".PNG\"))",
            ),
        ];
        for (bytes, message) in cases {
            let error = load(&write(dir.path(), "mesh.obj", bytes)).err();
            let error = error.unwrap_or_else(|| panic!("{message}: loaded"));
            assert!(error.message.contains(message), "{error:?}");
            assert!(error.hint.is_some_and(|hint| hint.contains("Gltf(")), "{message}");
        }
    }

    #[test]
    fn degenerate_faces_are_kept_without_nan() {
        let obj = "v 1 1 1\nv 1 1 1\nv 1 1 1\nf 1 2 3\n";
        let mesh = load_text(obj, &[])
            .map(|l| l.mesh)
            .unwrap_or_else(|e| panic!("{e:?}"));
        check_invariant(&mesh);
        assert_eq!(mesh.normals, vec![normals::FALLBACK_NORMAL]);
    }

    // Texture coordinates and textures.

    /// The `vt` of every face corner of a triangulated OBJ file, in face order, as the file
    /// states them (v up): what the loader's UVs must match, flipped.
    fn file_corner_uvs(text: &str) -> Vec<(Vec3, Vec2)> {
        let mut positions = Vec::new();
        let mut uvs = Vec::new();
        let mut corners = Vec::new();
        let number = |w: &str| w.parse::<f32>().unwrap_or_else(|e| panic!("{w}: {e}"));
        for line in text.lines() {
            let words: Vec<&str> = line.split_whitespace().collect();
            match words.first() {
                Some(&"v") => positions.push(Vec3::new(number(words[1]), number(words[2]), number(words[3]))),
                Some(&"vt") => uvs.push(Vec2::new(number(words[1]), number(words[2]))),
                Some(&"f") => {
                    for corner in &words[1..] {
                        let mut parts = corner.split('/').map(|p| p.parse::<usize>().unwrap_or(0));
                        let (v, vt) = (parts.next().unwrap_or(0), parts.next().unwrap_or(0));
                        corners.push((positions[v - 1], uvs[vt - 1]));
                    }
                }
                _ => {}
            }
        }
        corners
    }

    /// spot_triangulated.obj with a material library naming its texture, in a scratch folder
    /// (the asset ships without one): `mtl` is the library's text.
    fn textured_spot(mtl: &str) -> (tempfile::TempDir, PathBuf) {
        let dir = scratch_dir();
        let obj =
            std::fs::read_to_string(asset("spot/spot_triangulated.obj")).unwrap_or_else(|e| panic!("{e}"));
        std::fs::copy(
            asset("spot/spot_texture.png"),
            dir.path().join("spot_texture.png"),
        )
        .unwrap_or_else(|e| panic!("{e}"));
        write(dir.path(), "spot.mtl", mtl);
        let path = write(
            dir.path(),
            "spot.obj",
            format!("mtllib spot.mtl\nusemtl spot\n{obj}"),
        );
        (dir, path)
    }

    #[test]
    fn spot_uvs_follow_their_corners_flipped_to_top_left() {
        let loaded = check_asset("spot/spot_triangulated.obj", 5856);
        let mesh = &loaded.mesh;
        assert_eq!(mesh.uvs.len(), mesh.positions.len());
        let text =
            std::fs::read_to_string(asset("spot/spot_triangulated.obj")).unwrap_or_else(|e| panic!("{e}"));
        let corners = file_corner_uvs(&text);
        assert_eq!(corners.len(), 3 * mesh.triangles.len());
        for (triangle, file) in mesh.triangles.iter().zip(corners.chunks_exact(3)) {
            for (&vertex, &(position, uv)) in triangle.iter().zip(file) {
                assert_eq!(mesh.positions[vertex as usize], position);
                assert_eq!(
                    mesh.uvs[vertex as usize],
                    Vec2::new(uv.x, 1.0 - uv.y),
                    "corner at {position}"
                );
            }
        }
        // UV seams keep their vertices apart: more vertices than distinct positions.
        let mut distinct: Vec<[u32; 3]> = mesh
            .positions
            .iter()
            .map(|p| p.to_array().map(f32::to_bits))
            .collect();
        distinct.sort_unstable();
        distinct.dedup();
        assert!(
            mesh.positions.len() > distinct.len(),
            "{} vs {}",
            mesh.positions.len(),
            distinct.len()
        );
    }

    #[test]
    fn spot_texture_is_loaded_relative_to_its_mtl_and_bound() {
        let (dir, path) = textured_spot("newmtl spot\nKd 1 1 1\nmap_Kd -bm 1 spot_texture.png\n");
        let loaded = load(&path).unwrap_or_else(|e| panic!("{e:?}"));
        check_invariant(&loaded.mesh);
        assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
        let mesh = &loaded.mesh;
        assert_eq!(mesh.textures.len(), 1);
        let texture = &mesh.textures[0];
        assert_eq!(
            (texture.width(), texture.height(), texture.levels.len()),
            (1024, 1024, 11)
        );
        let binding = mesh.materials[0]
            .textures
            .diffuse
            .unwrap_or_else(|| panic!("map_Kd is bound"));
        assert_eq!((binding.texture, binding.uv_set, binding.scale), (0, 0, 1.0));
        assert_eq!(binding.sampler, Sampler::default());
        assert_eq!(mesh.materials[0].textures.ambient, None);
        assert_eq!(
            loaded.files_read,
            vec![
                path.clone(),
                dir.path().join("spot.mtl"),
                dir.path().join("spot_texture.png")
            ]
        );
    }

    #[test]
    fn textures_are_loaded_once_per_file() {
        let mtl = "newmtl spot\nmap_Kd spot_texture.png\nmap_Ka -clamp on spot_texture.png\n\
                   newmtl other\nmap_Kd spot_texture.png\n";
        let (_dir, path) = textured_spot(mtl);
        let loaded = load(&path).unwrap_or_else(|e| panic!("{e:?}"));
        check_invariant(&loaded.mesh);
        let mesh = &loaded.mesh;
        assert_eq!(mesh.textures.len(), 1);
        assert_eq!(loaded.files_read.len(), 3, "{:?}", loaded.files_read);
        let spot = mesh.materials[0].textures;
        let (diffuse, ambient) = (spot.diffuse.map(|b| b.texture), spot.ambient.map(|b| b.texture));
        assert_eq!((diffuse, ambient), (Some(0), Some(0)));
        assert_eq!(spot.ambient.map(|b| b.sampler.wrap_s), Some(Wrap::ClampToEdge));
        assert_eq!(mesh.materials[1].textures.diffuse.map(|b| b.texture), Some(0));
    }

    #[test]
    fn missing_textures_warn_name_the_file_and_are_recorded() {
        // The tobj fixture libraries name texture files that do not exist, some with spaces
        // in their names; an OBJ with texture coordinates elsewhere uses them by absolute
        // path, so their textures resolve next to the libraries, not next to the OBJ.
        let library = asset("tobj-fixtures/cornell_box.mtl");
        let second_library = asset("tobj-fixtures/cornell_box2.mtl");
        let obj = format!(
            "mtllib {}\nmtllib {}\n{TRIANGLE}vt 0 0\nvt 1 0\nvt 0 1\nusemtl red\nf 1/1 2/2 3/3\nusemtl green\nf 1/1 2/2 3/3\n",
            library.display(),
            second_library.display()
        );
        let loaded = load_text(&obj, &[]).unwrap_or_else(|e| panic!("{e:?}"));
        check_invariant(&loaded.mesh);
        let fixtures = asset("tobj-fixtures");
        let expected = [
            "this diffuse texture has spaces.jpg",
            "this ambient texture has spaces.jpg",
            "dummy_texture.png",
        ];
        for name in expected {
            let file = fixtures.join(name);
            assert!(
                loaded.files_read.contains(&file),
                "{file:?} in {:?}",
                loaded.files_read
            );
            let warned = loaded
                .warnings
                .iter()
                .filter(|w| w.contains(&file.display().to_string()) && w.contains("no such file"))
                .count();
            assert_eq!(warned, 1, "one warning for {name}: {:?}", loaded.warnings);
        }
        assert_eq!(
            loaded.warnings.len(),
            3,
            "green's two statements name one file: {:?}",
            loaded.warnings
        );
        assert!(loaded.mesh.textures.is_empty());
        assert!(
            loaded
                .mesh
                .materials
                .iter()
                .all(|m| m.textures == Default::default())
        );
    }

    #[test]
    fn textures_without_texture_coordinates_are_not_loaded() {
        // The fixture itself has no vt: its textures are reported as unusable, not missing.
        let loaded = check_asset("tobj-fixtures/cornell_box.obj", 36);
        assert!(loaded.mesh.uvs.is_empty() && loaded.mesh.textures.is_empty());
        let unused: Vec<&String> = loaded
            .warnings
            .iter()
            .filter(|w| w.contains("no texture coordinates"))
            .collect();
        assert_eq!(
            unused.len(),
            4,
            "map_Kd and map_Ka of red and green: {:?}",
            loaded.warnings
        );
        assert_eq!(
            loaded.files_read.len(),
            3,
            "no texture was tried: {:?}",
            loaded.files_read
        );
    }

    #[test]
    fn texture_coordinates_are_flipped_sanitised_and_padded() {
        // Two objects, the second without vt: its vertices get zeros.
        let obj = format!("{TRIANGLE}vt 0.25 0.75\nvt 1 1\nvt 0 1\no a\nf 1/1 2/2 3/3\no b\nf 1 3 2\n");
        let loaded = load_text(&obj, &[]).unwrap_or_else(|e| panic!("{e:?}"));
        let mesh = &loaded.mesh;
        check_invariant(mesh);
        let first = mesh.triangles[0].map(|v| mesh.uvs[v as usize]);
        assert_eq!(
            first,
            [Vec2::new(0.25, 0.25), Vec2::new(1.0, 0.0), Vec2::new(0.0, 0.0)]
        );
        assert!(
            mesh.triangles[1]
                .iter()
                .all(|&v| mesh.uvs[v as usize] == Vec2::ZERO)
        );
        // Only some corners with vt: dropped with a warning.
        let obj = format!("{TRIANGLE}vt 0 0\nf 1/1 2 3\n");
        let loaded = load_text(&obj, &[]).unwrap_or_else(|e| panic!("{e:?}"));
        check_invariant(&loaded.mesh);
        assert!(loaded.mesh.uvs.is_empty());
        assert!(
            loaded
                .warnings
                .iter()
                .any(|w| w.contains("only some face vertices have texture coordinates"))
        );
    }

    #[test]
    fn texture_statement_options_are_skipped() {
        let check = |arguments: &str, name: &str, clamp: bool| {
            assert_eq!(
                texture_file_name(arguments),
                Some(TextureFileName {
                    name: name.to_string(),
                    clamp
                }),
                "{arguments}"
            );
        };
        check("wood.png", "wood.png", false);
        check("-bm 1 wood.png", "wood.png", false);
        check(
            "this diffuse texture has spaces.jpg",
            "this diffuse texture has spaces.jpg",
            false,
        );
        check("-o 0.5 0.5 0 -clamp on wood.png", "wood.png", true);
        check("-s 2 wood.png", "wood.png", false);
        check("-mm 0 1 -blendu off my wood.png", "my wood.png", false);
        check("-clamp off textures\\wood.png", "textures/wood.png", false);
        check("-unknown wood.png", "-unknown wood.png", false);
        assert_eq!(texture_file_name("-bm 1"), None);
        assert_eq!(texture_file_name("   "), None);
    }
}
