//! The loader: a scene file and everything it names, read, checked and lowered into a [`Scene`].
//!
//! Stages, in order: read and parse the scene file (ron gives positions for syntax and type
//! errors); read included material libraries; resolve every material; load meshes; then the
//! camera and lights, whose defaults depend on where the objects are. Problems found after
//! parsing are located in the source text by the path of the offending value
//! ([`super::locate`]), so an unknown material or a NaN points at its line and column like a
//! syntax error does. All problems are collected; loading stops only where continuing could not
//! find more (a syntax error ends the file's checks).
//!
//! Every file read is recorded in [`LoadedScene::files_read`], the set a watcher follows.

use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::SystemTime;

use glam::{DMat4, DQuat, DVec3, EulerRot, Vec3};

use crate::diag::{Diagnostic, Schema, SourceId, Sources, from_ron_error};
use crate::mesh::{
    ImportedCamera, ImportedLight, ImportedProjection, LoadedMesh, Mesh, MeshError, ParsedMeshFile,
    primitives, tangents::compute_tangents,
};
use crate::render::raster::SamplePattern;
use crate::ron_path;
use crate::scene::access::{FileAccess, ReadError};
use crate::scene::format::{
    self, AttenuationFile, BackFacesFile, CameraFile, ComponentFile, DistributionFile, LightFile,
    LightingModelFile, MaterialFile, MaterialLibraryFile, MaterialRefFile, MeshFile, NameOrIndexFile,
    NormalInterpolationFile, OrderedMap, ScaleFile, SceneFile, ShadingFile, ShadowMapFile,
};
use crate::scene::limits;
use crate::scene::locate::{PathSegment, locate, locate_keys};
use crate::scene::presets::{self, DEFAULT_RECIPE, MaterialRecipe};
use crate::scene::{
    Attenuation, BackFaces, BoundingSphere, Camera, ImageSettings, Light, LightingComponent, LightingModel,
    Microfacet, MicrofacetDistribution, NormalInterpolation, Object, Projection, Scene, Shading,
    ShadowSettings, TextureBinding, bounding_sphere,
};
use crate::texture::{ColorSpace, Sampler, Texture};

/// Image size when the scene gives none.
pub const DEFAULT_WIDTH: u32 = 800;
pub const DEFAULT_HEIGHT: u32 = 600;
/// OpenGL's default global ambient light (`GL_LIGHT_MODEL_AMBIENT`).
pub const DEFAULT_AMBIENT: Vec3 = Vec3::splat(0.2);
pub const DEFAULT_SPHERE_SEGMENTS: u32 = 32;
/// `sphere(N)` has 2N² triangles: 4096 gives 33.5 million, beyond which a scene is almost
/// certainly a typo and would exhaust memory.
pub const MAX_SPHERE_SEGMENTS: u32 = 4096;
pub const DEFAULT_FOV_DEGREES: f64 = 45.0;
pub const DEFAULT_SPOT_CUTOFF_DEGREES: f32 = 30.0;
/// Included material libraries may include others, this deep at most.
pub const MAX_INCLUDE_DEPTH: usize = 16;
/// The largest `mip_bias` either way: 16 levels span every texture's chain (at most 4096 a
/// side, 13 levels).
pub const MAX_MIP_BIAS: f64 = 16.0;

/// `value` as a scene would write it: whole numbers in full, others with the shortest digits
/// that read back to the same `f32` when they are one (fields are `f32`, and `8.6e29` widened to
/// `f64` prints 30 digits), with an exponent when very large or small.
fn display_number(value: f64) -> String {
    let magnitude = value.abs();
    if value.fract() == 0.0 && magnitude < 1e16 {
        return format!("{value}");
    }
    let exponent = !(1e-4..1e7).contains(&magnitude);
    let narrow = value as f32;
    match (f64::from(narrow) == value, exponent) {
        (true, true) => format!("{narrow:e}"),
        (true, false) => format!("{narrow}"),
        (false, true) => format!("{value:e}"),
        (false, false) => format!("{value}"),
    }
}

/// Why colours, coefficients and intensities have an upper bound ([`limits::MAX_LIGHTING_VALUE`]).
const LIGHTING_VALUE_HINT: &str = "lighting is computed in 32-bit floats and larger values could overflow; \
     10⁶ already saturates to white (docs/limits.md)";

/// Settings from the command line that override the scene file.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LoadOptions {
    /// How the scene's files may be read (`--sandbox`).
    pub access: FileAccess,
    /// The memory budget in bytes (`--max-memory`); `None` is [`limits::DEFAULT_MEMORY_BUDGET`].
    pub max_memory: Option<u64>,
    pub width: Option<u32>,
    pub height: Option<u32>,
    /// Replaces every object's shading mode.
    pub shading: Option<Shading>,
    /// Replaces the scene's samples per pixel.
    pub samples: Option<u32>,
    /// Replaces the lighting model of every material.
    pub model: Option<LightingModel>,
}

/// A scene that loaded, with what it read and the warnings it produced.
#[derive(Debug, Clone)]
pub struct LoadedScene {
    pub scene: Scene,
    /// Every file read: scene, includes, meshes and the files they reference.
    pub files_read: Vec<PathBuf>,
    pub warnings: Vec<Diagnostic>,
    pub sources: Sources,
}

/// A scene that did not load: every problem found, and the texts they point into.
#[derive(Debug, Clone)]
pub struct LoadError {
    pub diagnostics: Vec<Diagnostic>,
    pub sources: Sources,
    /// Files read before the problems were found (a watcher follows them too).
    pub files_read: Vec<PathBuf>,
}

/// Meshes already loaded, reused while none of their files has changed: by later objects of
/// the same load (three objects on one mesh file parse it once) and by later loads (watch mode
/// re-renders a scene with a million-triangle mesh without reading the mesh again).
///
/// Entries are keyed by the file's canonical path (so `m.obj`, `./m.obj` and `sub/../m.obj`
/// are one file) and by the crease angle only when it shaped the mesh (a file with normals
/// is the same mesh for every crease angle).
#[derive(Debug, Default)]
pub struct MeshCache {
    entries: HashMap<MeshKey, CachedMesh>,
    /// Generated spheres by segment count and whether they carry texture coordinates: a
    /// `Sphere(segments: 180)` takes longer to build than the rest of its scene's load, which
    /// the preview repeats for every frame of a moving camera.
    spheres: HashMap<(u32, bool), Arc<Mesh>>,
    /// Mesh files parsed through this cache, over its life.
    files_parsed: usize,
}

impl MeshCache {
    /// The mesh this cache holds for the file at `path` (whatever crease angle it was built
    /// with), if a load put one there: what an editor's hover describes.
    pub fn mesh_of_file(&self, path: &Path) -> Option<Arc<Mesh>> {
        let key = canonical(path);
        self.entries
            .iter()
            .find(|(entry_key, _)| entry_key.path == key)
            .map(|(_, entry)| Arc::clone(&entry.mesh))
    }

    /// How many times a mesh file was parsed through this cache (a hit parses nothing): what
    /// tests count to show that a file is parsed once.
    pub fn files_parsed(&self) -> usize {
        self.files_parsed
    }
}

#[derive(Debug, Clone, PartialEq, Eq, Hash)]
struct MeshKey {
    /// The canonical path (`canonical`).
    path: PathBuf,
    /// The crease angle's bits, or `None` for a mesh the crease angle did not change.
    crease_angle_bits: Option<u32>,
}

#[derive(Debug)]
struct CachedMesh {
    /// Modification times of every file the mesh read, at load time.
    stamps: Vec<(PathBuf, Option<FileStamp>)>,
    mesh: Arc<Mesh>,
    /// The mesh with tangents computed from its UVs, for objects whose scene material has a
    /// normal map (a mesh file without tangents of its own); made the first time one asks.
    with_tangents: Option<Arc<Mesh>>,
    /// The mesh (or `with_tangents`, by the key's flag) without the arrays objects do not read,
    /// by what they read and whether a scene material replaces the mesh's own.
    trimmed: HashMap<(AttributesRead, bool, bool), Arc<Mesh>>,
    placed: Arc<Placed>,
    files_read: Vec<PathBuf>,
    warnings: Vec<String>,
}

/// What an object's scene material reads from its mesh, beyond positions and normals.
#[derive(Debug, Clone, Copy, Default)]
struct SurfaceNeeds {
    /// The object has a scene material, which replaces the mesh's own.
    scene_material: bool,
    /// A `texture`: texture coordinates.
    texture: bool,
    /// A `normal_map`: texture coordinates and tangents.
    normal_map: bool,
}

impl SurfaceNeeds {
    fn uvs(self) -> bool {
        self.texture || self.normal_map
    }
}

/// The per-vertex arrays besides positions, normals and colours that an object's materials
/// read: texture coordinates of set 0 and 1, and tangents (normal maps).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
struct AttributesRead {
    uvs: bool,
    uvs1: bool,
    tangents: bool,
}

impl AttributesRead {
    /// What the object reads from `mesh`: what its scene material reads, or else what the
    /// mesh's own materials do.
    fn of(mesh: &Mesh, needs: SurfaceNeeds) -> Self {
        if needs.scene_material {
            return AttributesRead {
                uvs: needs.uvs(),
                uvs1: false,
                tangents: needs.normal_map,
            };
        }
        let mut read = AttributesRead::default();
        for material in &mesh.materials {
            let textures = material.textures;
            for binding in [textures.diffuse, textures.ambient, textures.normal]
                .into_iter()
                .flatten()
            {
                match binding.uv_set {
                    0 => read.uvs = true,
                    _ => read.uvs1 = true,
                }
            }
            read.tangents |= textures.normal.is_some();
        }
        read
    }

    /// Whether `mesh` has an array this does not read.
    fn leaves_unread(self, mesh: &Mesh) -> bool {
        (!mesh.uvs.is_empty() && !self.uvs)
            || (!mesh.uvs1.is_empty() && !self.uvs1)
            || (!mesh.tangents.is_empty() && !self.tangents)
    }

    /// `mesh` without the arrays this does not read; with a scene material (which replaces
    /// the mesh's own), without the mesh's materials and textures too, whose bindings may
    /// read what was dropped.
    fn trim(self, mesh: &Mesh, scene_material: bool) -> Mesh {
        fn keep<T: Clone>(kept: bool, array: &[T]) -> Vec<T> {
            if kept { array.to_vec() } else { Vec::new() }
        }
        // Every field named, so that a new one gets a decision here.
        Mesh {
            positions: mesh.positions.clone(),
            normals: mesh.normals.clone(),
            triangles: mesh.triangles.clone(),
            triangle_materials: keep(!scene_material, &mesh.triangle_materials),
            materials: keep(!scene_material, &mesh.materials),
            uvs: keep(self.uvs, &mesh.uvs),
            uvs1: keep(self.uvs1, &mesh.uvs1),
            colors: mesh.colors.clone(),
            tangents: keep(self.tangents, &mesh.tangents),
            textures: keep(!scene_material, &mesh.textures),
            closed: mesh.closed,
        }
    }
}

/// The lights and cameras a mesh file places, in its model space.
#[derive(Debug, Default)]
struct Placed {
    lights: Vec<ImportedLight>,
    cameras: Vec<ImportedCamera>,
}

/// What an object that loaded brings besides its mesh, by its index in `objects`.
#[derive(Debug)]
struct ObjectPlacement {
    transform: DMat4,
    placed: Arc<Placed>,
}

/// What says a file changed: its modification time and its size (two saves within one tick of
/// a coarse file-system clock still differ in size more often than not).
type FileStamp = (SystemTime, u64);

fn modified(path: &Path) -> Option<FileStamp> {
    let metadata = std::fs::metadata(path).ok()?;
    Some((metadata.modified().ok()?, metadata.len()))
}

/// Loads the scene at `path`.
pub fn load_scene(path: &Path, options: &LoadOptions) -> Result<LoadedScene, LoadError> {
    load_scene_cached(path, options, &mut MeshCache::default())
}

/// Loads a scene whose text is `text`, as if it were the file at `path` (includes and meshes
/// are read relative to `path`): the entry point of the fuzzer. The same code path as
/// [`load_scene`] once the scene file is read.
pub fn load_scene_from_str(path: &Path, text: &str, options: &LoadOptions) -> Result<LoadedScene, LoadError> {
    load_scene_with(path, Some(text), options, &mut MeshCache::default())
}

/// Loads a scene whose text is `text`, as if it were the file at `path`, reusing unchanged
/// meshes from `cache`: what an editor's unsaved buffer is checked with (`lampshade lsp`).
pub fn load_scene_from_str_cached(
    path: &Path,
    text: &str,
    options: &LoadOptions,
    cache: &mut MeshCache,
) -> Result<LoadedScene, LoadError> {
    load_scene_with(path, Some(text), options, cache)
}

/// Only the first stage of loading `text` as the scene at `path`: ron's syntax and type
/// checks (unknown fields and variants included), with the loader's diagnostics. It reads no
/// other file, so an editor gets it within a keystroke whatever the scene names.
pub fn parse_scene_text(path: &Path, text: &str) -> Result<(), LoadError> {
    let mut cache = MeshCache::default();
    let mut loader = Loader::new(path, Some(text), &LoadOptions::default(), &mut cache);
    let parsed = loader
        .read_source(path, None)
        .and_then(|source| loader.parse::<SceneFile>(source, &format::SCENE_SCHEMA));
    match parsed {
        Some(_) => Ok(()),
        None => Err(LoadError {
            diagnostics: loader.diagnostics,
            sources: loader.sources,
            files_read: loader.files_read,
        }),
    }
}

/// Checks `text` as the material library at `path`, on its own: its syntax and fields, its
/// includes (read from disk), duplicate names, `base` chains and every value, with the
/// diagnostics a scene including it would give. What an editor shows for an open library.
pub fn check_library_text(path: &Path, text: &str) -> Result<(), LoadError> {
    let mut cache = MeshCache::default();
    let mut loader = Loader::new(path, Some(text), &LoadOptions::default(), &mut cache);
    if let Some(source) = loader.read_source(path, None)
        && let Some(library) = loader.parse::<MaterialLibraryFile>(source, &format::LIBRARY_SCHEMA)
    {
        let mut table: HashMap<String, MaterialDefinition> = HashMap::new();
        let mut include_stack = vec![canonical(path)];
        loader.read_includes(&library.include, source, &[], &mut include_stack, &mut table);
        loader.add_materials(&library.materials, source, &[], &mut table);
        loader.resolve_table(&table);
    }
    if loader.diagnostics.is_empty() {
        return Ok(());
    }
    Err(LoadError {
        diagnostics: loader.diagnostics,
        sources: loader.sources,
        files_read: loader.files_read,
    })
}

/// A material a scene can name, resolved, and where it is defined.
#[derive(Debug, Clone)]
pub struct NamedMaterial {
    /// The name as its table writes it (a preset's own name for presets).
    pub name: String,
    pub material: crate::scene::Material,
    /// The file whose `materials` table defines it and the byte range of its key there;
    /// `None` for a built-in material.
    pub defined_at: Option<(PathBuf, std::ops::Range<usize>)>,
}

/// Every material the scene `text` (as the file at `path`) can name: its own table, its
/// includes (read from disk) and the presets, each resolved through its `base` chain by the
/// loader's own code. Names a table shadows come once, with the table's definition. Empty
/// when the text does not parse.
pub fn scene_materials(path: &Path, text: &str, options: &LoadOptions) -> Vec<NamedMaterial> {
    let mut cache = MeshCache::default();
    let mut loader = Loader::new(path, Some(text), options, &mut cache);
    let Some(source) = loader.read_source(path, None) else {
        return Vec::new();
    };
    let Some(file) = loader.parse::<SceneFile>(source, &format::SCENE_SCHEMA) else {
        return Vec::new();
    };
    let mut table: HashMap<String, MaterialDefinition> = HashMap::new();
    let mut include_stack = vec![canonical(path)];
    loader.read_includes(&file.include, source, &[], &mut include_stack, &mut table);
    loader.add_materials(&file.materials, source, &[], &mut table);
    let resolved = loader.resolve_table(&table);
    let mut materials: Vec<NamedMaterial> = table
        .iter()
        .filter_map(|(key, definition)| {
            let recipe = resolved.get(key)?;
            let Some(PathSegment::Key(name)) = definition.path.last() else {
                return None;
            };
            let text = loader.sources.text(definition.source);
            let map_path = &definition.path[..definition.path.len() - 1];
            let defined_at = locate_keys(text, map_path, name)
                .last()
                .cloned()
                .map(|span| (loader.sources.path(definition.source).to_path_buf(), span));
            Some(NamedMaterial {
                name: name.clone(),
                material: recipe.resolve(),
                defined_at,
            })
        })
        .collect();
    materials.sort_by(|a, b| a.name.cmp(&b.name));
    for name in presets::preset_names() {
        if !table.contains_key(name)
            && let Some(recipe) = presets::preset(name)
        {
            materials.push(NamedMaterial {
                name: name.to_owned(),
                material: recipe.resolve(),
                defined_at: None,
            });
        }
    }
    materials
}

/// Loads the scene at `path`, reusing unchanged meshes from `cache`.
pub fn load_scene_cached(
    path: &Path,
    options: &LoadOptions,
    cache: &mut MeshCache,
) -> Result<LoadedScene, LoadError> {
    load_scene_with(path, None, options, cache)
}

fn load_scene_with(
    path: &Path,
    text: Option<&str>,
    options: &LoadOptions,
    cache: &mut MeshCache,
) -> Result<LoadedScene, LoadError> {
    let mut loader = Loader::new(path, text, options, cache);
    let mut scene = loader.load(options);
    if let (Some(scene), Some(model)) = (&mut scene, options.model) {
        scene.override_lighting_model(model);
    }
    let (errors, warnings): (Vec<_>, Vec<_>) = loader.diagnostics.into_iter().partition(|d| d.is_error());
    match scene {
        Some(scene) if errors.is_empty() => Ok(LoadedScene {
            scene,
            files_read: loader.files_read,
            warnings,
            sources: loader.sources,
        }),
        _ => Err(LoadError {
            diagnostics: errors.into_iter().chain(warnings).collect(),
            sources: loader.sources,
            files_read: loader.files_read,
        }),
    }
}

struct Loader<'c> {
    /// Every file is read through it (`--sandbox`, regular files only).
    access: FileAccess,
    /// Bytes the render may need (`--max-memory`).
    memory_budget: u64,
    /// The scene's text when it was given rather than read from `scene_path`.
    scene_text: Option<String>,
    scene_path: PathBuf,
    sources: Sources,
    diagnostics: Vec<Diagnostic>,
    files_read: Vec<PathBuf>,
    cache: &'c mut MeshCache,
    /// The mesh files this load parsed (or failed to), by canonical path: objects naming a
    /// file with another crease angle build their mesh from the same parse.
    parsed_files: HashMap<PathBuf, ParseOutcome>,
    /// Meshes whose files and warnings this load has already reported (an object reusing a
    /// mesh does not repeat them).
    meshes_reported: HashSet<MeshKey>,
    /// Textures of the scene's own materials, and where each came from (to load each once).
    textures: Vec<Arc<Texture>>,
    texture_paths: HashMap<(PathBuf, bool), u32>,
}

/// A mesh file parsed, or why it could not be.
type ParseOutcome = Result<Arc<ParsedMeshFile>, Arc<MeshFailure>>;

/// Why a mesh file did not load, and the files it tried to read (a watcher follows them).
#[derive(Debug)]
struct MeshFailure {
    error: MeshError,
    attempted: Vec<PathBuf>,
}

/// A material defined in a table: where, so errors can point at it.
#[derive(Debug, Clone)]
struct MaterialDefinition {
    material: MaterialFile,
    source: SourceId,
    /// Path of the definition's value in its file.
    path: Vec<PathSegment>,
}

/// Where in which file a value sits.
#[derive(Debug, Clone, Copy)]
struct At<'p> {
    source: SourceId,
    path: &'p [PathSegment],
}

impl<'p> At<'p> {
    fn new(source: SourceId, path: &'p [PathSegment]) -> Self {
        At { source, path }
    }
}

impl<'c> Loader<'c> {
    fn new(path: &Path, text: Option<&str>, options: &LoadOptions, cache: &'c mut MeshCache) -> Self {
        Loader {
            access: options.access.clone(),
            memory_budget: options.max_memory.unwrap_or(limits::DEFAULT_MEMORY_BUDGET),
            scene_text: text.map(str::to_owned),
            scene_path: path.to_path_buf(),
            sources: Sources::new(),
            diagnostics: Vec::new(),
            files_read: Vec::new(),
            cache,
            parsed_files: HashMap::new(),
            meshes_reported: HashSet::new(),
            textures: Vec::new(),
            texture_paths: HashMap::new(),
        }
    }
}

impl Loader<'_> {
    fn load(&mut self, options: &LoadOptions) -> Option<Scene> {
        let scene_path = self.scene_path.clone();
        let source = self.read_source(&scene_path, None)?;
        let file: SceneFile = self.parse(source, &format::SCENE_SCHEMA)?;

        // Materials: included libraries first, then the scene's own table, later overriding earlier.
        let mut table: HashMap<String, MaterialDefinition> = HashMap::new();
        let mut include_stack = vec![canonical(&scene_path)];
        self.read_includes(&file.include, source, &[], &mut include_stack, &mut table);
        self.add_materials(&file.materials, source, &[], &mut table);
        let materials = self.resolve_table(&table);

        let image = self.image(&file, source, options);
        let mut objects = Vec::new();
        // The index in `file.objects` of each loaded object.
        let mut file_indices = Vec::new();
        let mut placements = Vec::new();
        for (index, object) in file.objects.iter().enumerate() {
            let loaded = self.object(object, index, source, &table, &materials, options);
            placements.push(loaded.map(|(object, placed)| {
                let transform = object.transform;
                objects.push(object);
                file_indices.push(index);
                ObjectPlacement { transform, placed }
            }));
        }
        let bounds = bounding_sphere(&objects);
        let extent = bounds.center.length() + bounds.radius;
        if extent.is_nan() || extent > limits::MAX_WORLD_EXTENT {
            self.world_extent_error(&file.objects, &objects, &file_indices, extent, source);
            return None;
        }
        let camera = match &file.camera {
            Some(CameraFile::Gltf { object, camera }) => self.gltf_camera(
                object.as_ref(),
                camera.as_ref(),
                source,
                bounds,
                &file.objects,
                &placements,
            ),
            camera => self.camera(camera.as_ref(), source, bounds, image),
        };
        let ambient = match file.ambient {
            Some(ambient) => self.color(
                ambient,
                At {
                    source,
                    path: &ron_path!["ambient"],
                },
            ),
            None => Some(DEFAULT_AMBIENT),
        };
        // Lights that mesh files place come after the scene's own, always; the default
        // headlight is only for scenes without any light.
        let imported: Vec<Light> = placements
            .iter()
            .flatten()
            .flat_map(|p| p.placed.lights.iter().map(|light| light.to_light(p.transform)))
            .collect();
        let lights = match (&file.lights, camera) {
            (Some(lights), Some(camera)) => lights
                .iter()
                .enumerate()
                .filter_map(|(i, light)| self.light(light, i, source, &camera))
                .chain(imported)
                .collect(),
            (None, Some(_)) if !imported.is_empty() => imported,
            (None, Some(camera)) => vec![Light::Directional {
                direction: (camera.target - camera.eye).normalize().as_vec3(),
                color: Vec3::ONE,
                shadow: None,
            }],
            (_, None) => Vec::new(),
        };
        if let Some(image) = image {
            self.check_memory(image, &lights, &objects, source);
        }
        if file.objects.is_empty() {
            self.diagnostics.push(
                Diagnostic::warning(&scene_path, "the scene has no objects: the image will be empty")
                    .with_hint("add `objects: [(mesh: Sphere())]`"),
            );
        }
        Some(Scene {
            image: image?,
            camera: camera?,
            ambient_light: ambient?,
            lights,
            objects,
            textures: std::mem::take(&mut self.textures),
        })
    }

    /// The objects reach farther than [`limits::MAX_WORLD_EXTENT`]: points at the value that
    /// puts the farthest object there (its `translate`, else its `scale`, else its mesh).
    fn world_extent_error(
        &mut self,
        files: &[format::ObjectFile],
        objects: &[Object],
        file_indices: &[usize],
        extent: f64,
        source: SourceId,
    ) {
        let reach = |object: &Object| {
            let bounds = bounding_sphere(std::slice::from_ref(object));
            let reach = bounds.center.length() + bounds.radius;
            // NaN counts as the farthest: it is what makes the scene undrawable.
            if reach.is_nan() { f64::INFINITY } else { reach }
        };
        let farthest = objects
            .iter()
            .zip(file_indices)
            .max_by(|(a, _), (b, _)| reach(a).total_cmp(&reach(b)));
        let message = format!(
            "the objects reach {extent:.3e} units from the origin; lampshade draws scenes within {:e} units",
            limits::MAX_WORLD_EXTENT
        );
        let hint = "check the objects' `scale` and `translate`, and the mesh files' coordinates";
        let Some((object, &index)) = farthest else {
            let path = self.sources.path(source).to_path_buf();
            self.diagnostics
                .push(Diagnostic::error(path, message).with_hint(hint));
            return;
        };
        let file = &files[index];
        let translation = object.transform.w_axis.truncate().length();
        // A NaN translation is the culprit too.
        let field =
            if file.translate.is_some() && (translation.is_nan() || translation >= reach(object) / 2.0) {
                "translate"
            } else if file.scale.is_some() {
                "scale"
            } else {
                "mesh"
            };
        let label = format!("puts `{}` {:.1e} units away", object.name, reach(object));
        self.error(
            At::new(source, &ron_path!["objects", index, field]),
            message,
            Some(&label),
            Some(hint.to_owned()),
        );
    }

    // ----- reading and parsing -----

    /// Reads a text file into `sources`. `referenced_at` is where another file named it.
    fn read_source(&mut self, path: &Path, referenced_at: Option<At>) -> Option<SourceId> {
        self.files_read.push(path.to_path_buf());
        if referenced_at.is_none()
            && let Some(text) = self.scene_text.take()
        {
            return Some(self.sources.add(path.to_path_buf(), text));
        }
        let problem = match self.access.read(path) {
            Ok(bytes) => match String::from_utf8(bytes) {
                Ok(text) => return Some(self.sources.add(path.to_path_buf(), text)),
                Err(error) => {
                    let valid = &error.as_bytes()[..error.utf8_error().valid_up_to()];
                    let line = 1 + valid.iter().filter(|&&b| b == b'\n').count();
                    Diagnostic::error(path, "the file is not UTF-8 text")
                        .with_line(line)
                        .with_hint("scene files are UTF-8 text; was a binary file given by mistake?")
                }
            },
            Err(ReadError::IsDirectory) => Diagnostic::error(path, "this is a directory, not a file"),
            Err(error @ ReadError::OutsideSandbox { .. }) => {
                Diagnostic::error(path, format!("refused to read `{}`: {error}", path.display()))
                    .with_hint("--sandbox allows only files inside its folder")
            }
            Err(error) => Diagnostic::error(path, format!("cannot read the file: {error}")),
        };
        let problem = match referenced_at {
            Some(at) => self.locate(problem, at),
            None => problem,
        };
        self.diagnostics.push(problem);
        None
    }

    fn parse<T: serde::de::DeserializeOwned>(&mut self, source: SourceId, schema: &Schema) -> Option<T> {
        match format::ron_options().from_str::<T>(self.sources.text(source)) {
            Ok(value) => Some(value),
            Err(error) => {
                let diagnostic = from_ron_error(source, &self.sources, &error, schema);
                self.diagnostics.push(diagnostic);
                None
            }
        }
    }

    /// Points `diagnostic` at the value `at` when it can be found in the text.
    fn locate(&self, diagnostic: Diagnostic, at: At) -> Diagnostic {
        match locate(self.sources.text(at.source), at.path) {
            Some(span) => diagnostic.at(at.source, span),
            None => diagnostic,
        }
    }

    fn error(&mut self, at: At, message: impl Into<String>, label: Option<&str>, hint: Option<String>) {
        let path = self.sources.path(at.source).to_path_buf();
        let mut diagnostic = self.locate(Diagnostic::error(path, message), at);
        if let Some(label) = label {
            diagnostic = diagnostic.with_label(label);
        }
        if let Some(hint) = hint {
            diagnostic = diagnostic.with_hint(hint);
        }
        self.diagnostics.push(diagnostic);
    }

    // ----- numbers -----

    /// `value` when it is finite; otherwise an error that quotes what the file says (`1e39`,
    /// not the `inf` ron made of it).
    fn finite(&mut self, value: f64, at: At) -> Option<f64> {
        if value.is_finite() {
            return Some(value);
        }
        let written = locate(self.sources.text(at.source), at.path)
            .and_then(|span| self.sources.text(at.source).get(span))
            .map(str::to_owned);
        let (message, label, hint) = match written.as_deref().map(|w| (w, w.replace('_', "").parse::<f64>()))
        {
            // Finite as written, infinite as read: too large for the field's 32-bit float.
            Some((written, Ok(parsed))) if parsed.is_finite() => (
                format!("`{written}` is out of range for a 32-bit number"),
                "too large",
                "this field is a 32-bit float, at most about 3.4e38".to_owned(),
            ),
            Some((written, Ok(parsed))) if parsed.is_infinite() && !written.contains("inf") => (
                format!("`{written}` is out of range for a 64-bit number"),
                "too large",
                "this field is a 64-bit float, at most about 1.8e308".to_owned(),
            ),
            Some((written, _)) => (
                format!("`{written}` is not a finite number"),
                "must be finite",
                "NaN and infinities have no meaning here".to_owned(),
            ),
            None => (
                format!("`{value}` is not a finite number"),
                "must be finite",
                "NaN and infinities, and numbers too large for the field, have no meaning here".to_owned(),
            ),
        };
        self.error(at, message, Some(label), Some(hint));
        None
    }

    fn vector(&mut self, value: [f64; 3], at: At) -> Option<DVec3> {
        let mut ok = true;
        for (i, &component) in value.iter().enumerate() {
            let path = [at.path, &[PathSegment::Index(i)]].concat();
            ok &= self
                .finite(
                    component,
                    At {
                        source: at.source,
                        path: &path,
                    },
                )
                .is_some();
        }
        ok.then(|| DVec3::from(value))
    }

    fn direction(&mut self, value: [f64; 3], at: At) -> Option<DVec3> {
        let vector = self.vector(value, at)?;
        let length = vector.length();
        if length.is_nan() || length <= 1e-12 || !length.is_finite() {
            self.error(
                at,
                "a direction cannot be the zero vector",
                Some("zero length"),
                None,
            );
            return None;
        }
        Some(vector / length)
    }

    /// An RGB triple with components in `[0, limits::MAX_LIGHTING_VALUE]`.
    fn color(&mut self, value: [f32; 3], at: At) -> Option<Vec3> {
        let vector = self.vector(value.map(f64::from), at)?;
        if vector.min_element() < 0.0 {
            self.error(
                at,
                "colour components cannot be negative",
                Some("negative component"),
                None,
            );
            return None;
        }
        if vector.max_element() > limits::MAX_LIGHTING_VALUE {
            self.error(
                at,
                format!(
                    "colour components must be at most {}, not {:e}",
                    limits::MAX_LIGHTING_VALUE,
                    vector.max_element()
                ),
                Some("too large"),
                Some(LIGHTING_VALUE_HINT.into()),
            );
            return None;
        }
        Some(vector.as_vec3())
    }

    /// A number in `[min, max]`.
    fn ranged(&mut self, value: f64, min: f64, max: f64, at: At, what: &str) -> Option<f64> {
        let value = self.finite(value, at)?;
        if value < min || value > max {
            let range = if max == f64::INFINITY {
                format!("at least {min}")
            } else {
                format!("between {min} and {max}")
            };
            let hint = (max == limits::MAX_LIGHTING_VALUE && value > max).then(|| LIGHTING_VALUE_HINT.into());
            self.error(
                at,
                format!("{what} must be {range}, not {}", display_number(value)),
                Some("out of range"),
                hint,
            );
            return None;
        }
        Some(value)
    }

    // ----- materials -----

    fn read_includes(
        &mut self,
        includes: &[String],
        source: SourceId,
        path_prefix: &[PathSegment],
        stack: &mut Vec<PathBuf>,
        table: &mut HashMap<String, MaterialDefinition>,
    ) {
        let base = self
            .sources
            .path(source)
            .parent()
            .map(Path::to_path_buf)
            .unwrap_or_default();
        for (index, include) in includes.iter().enumerate() {
            let at_path = [path_prefix, &ron_path!["include", index]].concat();
            let at = At {
                source,
                path: &at_path,
            };
            let path = base.join(include);
            let key = canonical(&path);
            if stack.contains(&key) {
                self.error(
                    at,
                    format!("include cycle: `{include}` is already being included"),
                    Some("includes itself, directly or through other files"),
                    None,
                );
                continue;
            }
            if stack.len() > MAX_INCLUDE_DEPTH {
                self.error(
                    at,
                    format!("includes nest deeper than {MAX_INCLUDE_DEPTH} files"),
                    None,
                    None,
                );
                continue;
            }
            let Some(library_source) = self.read_source(&path, Some(at)) else {
                continue;
            };
            let Some(library) = self.parse::<MaterialLibraryFile>(library_source, &format::LIBRARY_SCHEMA)
            else {
                continue;
            };
            stack.push(key);
            self.read_includes(&library.include, library_source, &[], stack, table);
            stack.pop();
            self.add_materials(&library.materials, library_source, &[], table);
        }
    }

    fn add_materials(
        &mut self,
        materials: &OrderedMap<MaterialFile>,
        source: SourceId,
        path_prefix: &[PathSegment],
        table: &mut HashMap<String, MaterialDefinition>,
    ) {
        let mut seen = HashSet::new();
        let map_path = [path_prefix, &ron_path!["materials"]].concat();
        for (name, material) in &materials.0 {
            if !seen.insert(name.clone()) {
                let keys = locate_keys(self.sources.text(source), &map_path, name);
                let mut diagnostic = Diagnostic::error(
                    self.sources.path(source),
                    format!("material `{name}` is defined twice"),
                )
                .with_hint("rename one of them or remove the duplicate");
                if let Some(span) = keys.get(1).cloned() {
                    diagnostic = diagnostic.at(source, span).with_label("second definition");
                }
                self.diagnostics.push(diagnostic);
                continue;
            }
            let path = [map_path.as_slice(), &[PathSegment::key(name.clone())]].concat();
            table.insert(
                presets::normalize_name(name),
                MaterialDefinition {
                    material: material.clone(),
                    source,
                    path,
                },
            );
        }
    }

    /// Resolves every table material (following `base` chains) to a recipe.
    fn resolve_table(
        &mut self,
        table: &HashMap<String, MaterialDefinition>,
    ) -> HashMap<String, MaterialRecipe> {
        let mut resolved = HashMap::new();
        let mut names: Vec<&String> = table.keys().collect();
        names.sort(); // a stable order for the diagnostics
        for name in names {
            let mut chain = Vec::new();
            self.resolve_named(name, table, &mut resolved, &mut chain);
        }
        resolved
    }

    fn resolve_named(
        &mut self,
        name: &str,
        table: &HashMap<String, MaterialDefinition>,
        resolved: &mut HashMap<String, MaterialRecipe>,
        chain: &mut Vec<String>,
    ) -> Option<MaterialRecipe> {
        let key = presets::normalize_name(name);
        if let Some(recipe) = resolved.get(&key) {
            return Some(*recipe);
        }
        let Some(definition) = table.get(&key) else {
            return presets::preset(&key);
        };
        if chain.contains(&key) {
            let at = At {
                source: definition.source,
                path: &definition.path,
            };
            self.error(
                at,
                format!("material `{name}` is its own base"),
                Some("`base` chain loops"),
                None,
            );
            return None;
        }
        chain.push(key.clone());
        let definition = definition.clone();
        let recipe = self.recipe(
            &definition.material,
            definition.source,
            &definition.path,
            table,
            resolved,
            chain,
        );
        chain.pop();
        if let Some(recipe) = recipe {
            resolved.insert(key, recipe);
        }
        recipe
    }

    /// Builds a recipe from a material written in a file: its base (or the default), then
    /// each field it sets.
    fn recipe(
        &mut self,
        material: &MaterialFile,
        source: SourceId,
        path: &[PathSegment],
        table: &HashMap<String, MaterialDefinition>,
        resolved: &mut HashMap<String, MaterialRecipe>,
        chain: &mut Vec<String>,
    ) -> Option<MaterialRecipe> {
        let field = |name: &str| [path, &[PathSegment::Field(name.to_owned())]].concat();
        let mut recipe = match &material.base {
            None => DEFAULT_RECIPE,
            Some(base) => match self.resolve_named(base, table, resolved, chain) {
                Some(recipe) => recipe,
                None => {
                    if table.contains_key(&presets::normalize_name(base)) {
                        return None; // the base itself failed and said why
                    }
                    let at_path = field("base");
                    self.unknown_material(
                        base,
                        At {
                            source,
                            path: &at_path,
                        },
                        table,
                    );
                    return None;
                }
            },
        };
        let mut ok = true;
        let mut strength = |loader: &mut Self, value: Option<f32>, name: &str, max: f64| -> Option<f32> {
            let value = value?;
            let at_path = field(name);
            let checked = loader.ranged(
                f64::from(value),
                0.0,
                max,
                At {
                    source,
                    path: &at_path,
                },
                &format!("`{name}`"),
            );
            ok &= checked.is_some();
            checked.map(|v| v as f32)
        };
        let ka = strength(self, material.ka, "ka", limits::MAX_LIGHTING_VALUE);
        let kd = strength(self, material.kd, "kd", limits::MAX_LIGHTING_VALUE);
        let ks = strength(self, material.ks, "ks", limits::MAX_LIGHTING_VALUE);
        let scr = strength(
            self,
            material.specular_color_reflectance,
            "specular_color_reflectance",
            1.0,
        );
        let shininess = strength(self, material.shininess, "shininess", f64::INFINITY);
        let metallic = strength(self, material.metallic, "metallic", 1.0);
        let roughness = match material.roughness {
            Some(value) => {
                let at_path = field("roughness");
                let checked = self.ranged(
                    f64::from(value),
                    1e-3,
                    1.0,
                    At::new(source, &at_path),
                    "`roughness`",
                );
                ok &= checked.is_some();
                checked.map(|v| v as f32)
            }
            None => None,
        };
        let mut color_field = |loader: &mut Self, value: Option<[f32; 3]>, name: &str| -> Option<Vec3> {
            let value = value?;
            let at_path = field(name);
            let checked = loader.color(
                value,
                At {
                    source,
                    path: &at_path,
                },
            );
            ok &= checked.is_some();
            checked
        };
        let color = color_field(self, material.color, "color");
        let ambient = color_field(self, material.ambient, "ambient");
        let diffuse = color_field(self, material.diffuse, "diffuse");
        let specular = color_field(self, material.specular, "specular");
        let emission = color_field(self, material.emission, "emission");
        let fresnel = color_field(self, material.fresnel, "fresnel");
        if !ok {
            return None;
        }

        let matlab_style = [
            ("color", color.is_some()),
            ("ka", ka.is_some()),
            ("kd", kd.is_some()),
            ("ks", ks.is_some()),
            ("specular_color_reflectance", scr.is_some()),
        ];
        if recipe.is_fully_explicit()
            && ambient.is_none()
            && diffuse.is_none()
            && specular.is_none()
            && let Some((name, _)) = matlab_style.iter().find(|(_, set)| *set)
        {
            let at_path = field(name);
            self.error(
                At { source, path: &at_path },
                format!("`{name}` has no effect: the base material sets `ambient`, `diffuse` and `specular` directly"),
                Some("ignored"),
                Some("set `ambient`, `diffuse` or `specular` instead, or use a MATLAB-style base such as \"shiny\"".into()),
            );
            return None;
        }
        recipe.color = color.unwrap_or(recipe.color);
        recipe.ka = ka.unwrap_or(recipe.ka);
        recipe.kd = kd.unwrap_or(recipe.kd);
        recipe.ks = ks.unwrap_or(recipe.ks);
        recipe.specular_color_reflectance = scr.unwrap_or(recipe.specular_color_reflectance);
        recipe.ambient = ambient.or(recipe.ambient);
        recipe.diffuse = diffuse.or(recipe.diffuse);
        recipe.specular = specular.or(recipe.specular);
        recipe.shininess = shininess.unwrap_or(recipe.shininess);
        recipe.emission = emission.unwrap_or(recipe.emission);
        if let Some(model) = material.model {
            recipe.model = match model {
                LightingModelFile::Phong => LightingModel::Phong,
                LightingModelFile::BlinnPhong => LightingModel::BlinnPhong,
                LightingModelFile::Lambert => LightingModel::Lambert,
                LightingModelFile::Unlit => LightingModel::Unlit,
                // The parameters are filled in when the recipe is resolved.
                LightingModelFile::CookTorrance => LightingModel::CookTorrance(Microfacet {
                    roughness: 0.0,
                    fresnel: Vec3::ZERO,
                    distribution: MicrofacetDistribution::Beckmann,
                }),
            };
        }
        for (file, slot, color_space, name) in [
            (&material.texture, 0, ColorSpace::Srgb, "texture"),
            (&material.normal_map, 1, ColorSpace::Linear, "normal_map"),
        ] {
            let Some(file) = file else { continue };
            let at_path = field(name);
            let texture = self.texture(file, color_space, At::new(source, &at_path))?;
            let binding = Some(TextureBinding {
                texture,
                uv_set: 0,
                sampler: Sampler::default(),
                scale: 1.0,
            });
            if slot == 0 {
                recipe.textures.diffuse = binding;
            } else {
                recipe.textures.normal = binding;
            }
        }
        recipe.roughness = roughness.unwrap_or(recipe.roughness);
        recipe.metallic = metallic.unwrap_or(recipe.metallic);
        recipe.fresnel = fresnel.or(recipe.fresnel);
        if let Some(distribution) = material.distribution {
            recipe.distribution = match distribution {
                DistributionFile::Beckmann => MicrofacetDistribution::Beckmann,
                DistributionFile::Ggx => MicrofacetDistribution::Ggx,
            };
        }
        Some(recipe)
    }

    /// Loads (once) the texture `file`, relative to the file `at` is in; its index in the
    /// scene's texture list.
    fn texture(&mut self, file: &str, color_space: ColorSpace, at: At) -> Option<u32> {
        let base = self
            .sources
            .path(at.source)
            .parent()
            .map(Path::to_path_buf)
            .unwrap_or_default();
        let path = base.join(file);
        let key = (path.clone(), color_space == ColorSpace::Srgb);
        if let Some(&index) = self.texture_paths.get(&key) {
            return Some(index);
        }
        self.files_read.push(path.clone());
        let loaded = match self.access.read(&path) {
            Ok(bytes) => Texture::from_encoded(&bytes, color_space).map(|texture| texture.read_from(&path)),
            Err(error @ ReadError::OutsideSandbox { .. }) => Err(format!("refused: {error}")),
            Err(error) => Err(format!("cannot read it: {error}")),
        };
        match loaded {
            Ok(texture) => {
                let index = self.textures.len() as u32;
                self.textures.push(Arc::new(texture));
                self.texture_paths.insert(key, index);
                Some(index)
            }
            Err(reason) => {
                let why = reason;
                self.error(
                    at,
                    format!("cannot load texture `{}`: {why}", path.display()),
                    Some("not loaded"),
                    Some(
                        "textures are PNG or JPEG images; paths are relative to the file that names them"
                            .into(),
                    ),
                );
                None
            }
        }
    }

    fn unknown_material(&mut self, name: &str, at: At, table: &HashMap<String, MaterialDefinition>) {
        let mut candidates: Vec<String> = table.keys().cloned().collect();
        candidates.extend(presets::preset_names().map(String::from));
        let normalized = presets::normalize_name(name);
        let closest = candidates
            .iter()
            .map(|c| (edit_distance(&normalized, c), c))
            .filter(|(d, c)| *d <= 2.max(c.len() / 3))
            .min();
        let hint = match closest {
            Some((_, candidate)) => format!("did you mean \"{candidate}\"?"),
            None => format!(
                "define it under `materials: {{ \"{name}\": (...) }}` or use a built-in material: {}",
                presets::preset_names().collect::<Vec<_>>().join(", ")
            ),
        };
        self.error(
            at,
            format!("unknown material `{name}`"),
            Some("not defined in this scene, its includes, or the presets"),
            Some(hint),
        );
    }

    // ----- image, objects -----

    fn image(&mut self, file: &SceneFile, source: SourceId, options: &LoadOptions) -> Option<ImageSettings> {
        let max = f64::from(crate::render::MAX_IMAGE_DIMENSION);
        let size =
            |loader: &mut Self, value: Option<u32>, overridden: Option<u32>, default: u32, name: &str| {
                if let Some(value) = overridden {
                    if value == 0 || f64::from(value) > max {
                        loader.diagnostics.push(Diagnostic::error(
                            &loader.scene_path,
                            format!("--{name} must be between 1 and {max}, not {value}"),
                        ));
                        return None;
                    }
                    return Some(value);
                }
                let at_path = ron_path!["image", name];
                let value = value.unwrap_or(default);
                loader
                    .ranged(
                        f64::from(value),
                        1.0,
                        max,
                        At {
                            source,
                            path: &at_path,
                        },
                        &format!("image {name}"),
                    )
                    .map(|v| v as u32)
            };
        let width = size(self, file.image.width, options.width, DEFAULT_WIDTH, "width");
        let height = size(self, file.image.height, options.height, DEFAULT_HEIGHT, "height");
        let background = match file.image.background {
            Some(color) => self.color(
                color,
                At {
                    source,
                    path: &ron_path!["image", "background"],
                },
            ),
            None => Some(Vec3::ZERO),
        };
        let samples = match (options.samples, file.image.samples) {
            (Some(samples), _) => {
                if SamplePattern::new(samples).is_none() {
                    self.diagnostics.push(Diagnostic::error(
                        &self.scene_path,
                        format!("--samples must be 1, 2, 4, 8 or 16, not {samples}"),
                    ));
                    return None;
                }
                Some(samples)
            }
            (None, Some(samples)) if SamplePattern::new(samples).is_none() => {
                self.error(
                    At::new(source, &ron_path!["image", "samples"]),
                    format!("`samples` must be 1, 2, 4, 8 or 16, not {samples}"),
                    Some("no such sample pattern"),
                    None,
                );
                None
            }
            (None, samples) => Some(samples.unwrap_or(1)),
        };
        let mip_bias = match file.image.mip_bias {
            Some(bias) => self
                .ranged(
                    f64::from(bias),
                    -MAX_MIP_BIAS,
                    MAX_MIP_BIAS,
                    At::new(source, &ron_path!["image", "mip_bias"]),
                    "`mip_bias`",
                )
                .map(|bias| bias as f32),
            None => Some(0.0),
        };
        Some(ImageSettings {
            width: width?,
            height: height?,
            background: background?,
            samples: samples?,
            mip_bias: mip_bias?,
        })
    }

    fn object(
        &mut self,
        object: &format::ObjectFile,
        index: usize,
        source: SourceId,
        table: &HashMap<String, MaterialDefinition>,
        materials: &HashMap<String, MaterialRecipe>,
        options: &LoadOptions,
    ) -> Option<(Object, Arc<Placed>)> {
        let field = |name: &str| ron_path!["objects", index, name];
        let crease_angle = match object.crease_angle {
            Some(angle) => self
                .ranged(
                    f64::from(angle),
                    0.0,
                    180.0,
                    At {
                        source,
                        path: &field("crease_angle"),
                    },
                    "`crease_angle`",
                )
                .map(|a| a as f32),
            None => Some(crate::mesh::normals::DEFAULT_CREASE_ANGLE_DEGREES),
        };
        let transform = self.transform(object, index, source);
        let material = match &object.material {
            None => Some(None),
            Some(MaterialRefFile::Named(name)) => {
                let key = presets::normalize_name(name);
                match materials.get(&key).copied().or_else(|| {
                    (!table.contains_key(&key))
                        .then(|| presets::preset(&key))
                        .flatten()
                }) {
                    Some(recipe) => Some(Some(recipe.resolve())),
                    None if table.contains_key(&key) => None, // its definition failed and said why
                    None => {
                        self.unknown_material(
                            name,
                            At {
                                source,
                                path: &field("material"),
                            },
                            table,
                        );
                        None
                    }
                }
            }
            Some(MaterialRefFile::Inline(material)) => {
                let mut resolved = materials.clone();
                let mut chain = Vec::new();
                self.recipe(
                    material,
                    source,
                    &field("material"),
                    table,
                    &mut resolved,
                    &mut chain,
                )
                .map(|recipe| Some(recipe.resolve()))
            }
        };
        // The material first: a texture or normal map decides what the mesh must carry.
        let needs = match &material {
            Some(Some(material)) => SurfaceNeeds {
                scene_material: true,
                texture: material.textures.diffuse.is_some(),
                normal_map: material.textures.normal.is_some(),
            },
            _ => SurfaceNeeds::default(),
        };
        let mesh = self.mesh(&object.mesh, index, source, crease_angle?, needs);
        let mesh = match mesh {
            Some((mesh, placed)) if needs.uvs() => {
                Some((self.check_surface(mesh, needs, object, index, source), placed))
            }
            other => other,
        };
        let shading = options.shading.unwrap_or(match object.shading {
            None | Some(ShadingFile::Phong) => Shading::Phong,
            Some(ShadingFile::Gouraud) => Shading::Gouraud,
            Some(ShadingFile::Flat) => Shading::Flat,
            Some(ShadingFile::Constant) => Shading::Constant,
        });
        let back_faces = match object.back_faces {
            None | Some(BackFacesFile::ReverseLit) => BackFaces::ReverseLit,
            Some(BackFacesFile::Lit) => BackFaces::Lit,
            Some(BackFacesFile::Unlit) => BackFaces::Unlit,
            Some(BackFacesFile::Cull) => BackFaces::Cull,
        };
        let component = match object.component {
            None | Some(ComponentFile::All) => LightingComponent::All,
            Some(ComponentFile::Ambient) => LightingComponent::Ambient,
            Some(ComponentFile::Diffuse) => LightingComponent::Diffuse,
            Some(ComponentFile::Specular) => LightingComponent::Specular,
        };
        let normal_interpolation = match object.normal_interpolation {
            None | Some(NormalInterpolationFile::Nlerp) => NormalInterpolation::Nlerp,
            Some(NormalInterpolationFile::Slerp) => NormalInterpolation::Slerp,
        };
        let name = object.name.clone().unwrap_or_else(|| format!("object {index}"));
        let (mesh, placed) = mesh?;
        let object = Object {
            name,
            mesh,
            transform: transform?,
            shading,
            material: material?,
            back_faces,
            component,
            normal_interpolation,
        };
        Some((object, placed))
    }

    fn transform(&mut self, object: &format::ObjectFile, index: usize, source: SourceId) -> Option<DMat4> {
        let field = |name: &str| ron_path!["objects", index, name];
        let translate = match object.translate {
            Some(v) => self.vector(
                v,
                At {
                    source,
                    path: &field("translate"),
                },
            ),
            None => Some(DVec3::ZERO),
        };
        let rotate = match object.rotate {
            Some(v) => self.vector(
                v,
                At {
                    source,
                    path: &field("rotate"),
                },
            ),
            None => Some(DVec3::ZERO),
        };
        let scale_path = field("scale");
        let scale_at = At {
            source,
            path: &scale_path,
        };
        let scale = match object.scale {
            None => Some(DVec3::ONE),
            Some(ScaleFile::Uniform(s)) => self.finite(s, scale_at).map(DVec3::splat),
            Some(ScaleFile::PerAxis(v)) => self.vector(v, scale_at),
        };
        let scale = scale?;
        if scale.abs().min_element() < 1e-12 {
            self.error(
                scale_at,
                "scale cannot be zero",
                Some("flattens the object to nothing"),
                None,
            );
            return None;
        }
        let rotate = rotate?;
        let rotation = DQuat::from_euler(
            EulerRot::ZYX,
            rotate.z.to_radians(),
            rotate.y.to_radians(),
            rotate.x.to_radians(),
        );
        Some(DMat4::from_scale_rotation_translation(
            scale, rotation, translate?,
        ))
    }

    fn mesh(
        &mut self,
        mesh: &MeshFile,
        index: usize,
        source: SourceId,
        crease_angle: f32,
        needs: SurfaceNeeds,
    ) -> Option<(Arc<Mesh>, Arc<Placed>)> {
        let mesh_path = ron_path!["objects", index, "mesh"];
        let nothing_placed = || Arc::new(Placed::default());
        match mesh {
            MeshFile::Sphere { segments } => {
                let segments = segments.unwrap_or(DEFAULT_SPHERE_SEGMENTS);
                let at_path = [mesh_path.as_slice(), &ron_path!["segments"]].concat();
                let at = At {
                    source,
                    path: &at_path,
                };
                self.ranged(
                    f64::from(segments),
                    3.0,
                    f64::from(MAX_SPHERE_SEGMENTS),
                    at,
                    "sphere `segments`",
                )?;
                // Refused before it is generated: `sphere(4096)` alone is 33 million triangles.
                let (vertices, triangles) = limits::sphere_size(segments);
                let bytes = limits::mesh_bytes(vertices, triangles);
                if bytes > self.memory_budget {
                    self.error(
                        at,
                        format!(
                            "`Sphere(segments: {segments})` has {triangles} triangles and needs about {} to draw, more than the memory budget of {}",
                            limits::human_bytes(bytes),
                            limits::human_bytes(self.memory_budget)
                        ),
                        Some("too many triangles"),
                        Some("use fewer segments, or raise the budget with --max-memory".into()),
                    );
                    return None;
                }
                // Texture coordinates and tangents only for a material that reads them: an
                // untextured object is the plain mesh, which the renderer draws without a
                // per-vertex attribute pass.
                let textured = needs.uvs();
                let sphere = self.cache.spheres.entry((segments, textured)).or_insert_with(|| {
                    Arc::new(match textured {
                        true => primitives::textured_sphere(segments),
                        false => primitives::sphere(segments),
                    })
                });
                Some((Arc::clone(sphere), nothing_placed()))
            }
            MeshFile::Plane => {
                let plane = if needs.uvs() {
                    primitives::textured_plane()
                } else {
                    primitives::plane()
                };
                Some((Arc::new(plane), nothing_placed()))
            }
            MeshFile::Cube => {
                let cube = if needs.uvs() {
                    primitives::textured_cube()
                } else {
                    primitives::cube()
                };
                Some((Arc::new(cube), nothing_placed()))
            }
            MeshFile::Obj(file) | MeshFile::Gltf(file) => {
                let at_path = [mesh_path.as_slice(), &ron_path![0]].concat();
                let at = At {
                    source,
                    path: &at_path,
                };
                let base = self
                    .sources
                    .path(source)
                    .parent()
                    .map(Path::to_path_buf)
                    .unwrap_or_default();
                let path = base.join(file);
                let metadata = match self.access.metadata(&path) {
                    Ok(metadata) => metadata,
                    Err(error) => {
                        let (why, label, hint) = match &error {
                            ReadError::NotFound => (
                                "does not exist".to_string(),
                                "not found",
                                "paths are relative to the scene file's folder",
                            ),
                            ReadError::OutsideSandbox { .. } => (
                                format!("is refused: {error}"),
                                "outside the sandbox",
                                "--sandbox allows only files inside its folder",
                            ),
                            _ => (
                                error.to_string(),
                                "cannot be read",
                                "name an OBJ, glTF or GLB file",
                            ),
                        };
                        self.error(
                            at,
                            format!("mesh file `{}` {why}", path.display()),
                            Some(label),
                            Some(hint.into()),
                        );
                        self.files_read.push(path);
                        return None;
                    }
                };
                let parse_bytes = metadata.len().saturating_mul(limits::MESH_FILE_EXPANSION);
                if parse_bytes > self.memory_budget {
                    self.error(
                        at,
                        format!(
                            "mesh file `{}` is {} and may need up to {} to load, more than the memory budget of {}",
                            path.display(),
                            limits::human_bytes(metadata.len()),
                            limits::human_bytes(parse_bytes),
                            limits::human_bytes(self.memory_budget)
                        ),
                        Some("too large"),
                        Some("raise the budget with --max-memory".into()),
                    );
                    self.files_read.push(path);
                    return None;
                }
                let is_obj = matches!(mesh, MeshFile::Obj(_));
                self.load_mesh_file(&path, is_obj, crease_angle, needs, at)
            }
        }
    }

    fn load_mesh_file(
        &mut self,
        path: &Path,
        is_obj: bool,
        crease_angle: f32,
        needs: SurfaceNeeds,
        at: At,
    ) -> Option<(Arc<Mesh>, Arc<Placed>)> {
        let canonical_path = canonical(path);
        let keys = [None, Some(crease_angle.to_bits())].map(|crease_angle_bits| MeshKey {
            path: canonical_path.clone(),
            crease_angle_bits,
        });
        // Fresh when every file it read is unchanged, and every file it looked for but did not
        // find (a missing texture) is still missing: creating one makes it stale.
        let fresh = keys.iter().find(|key| {
            self.cache
                .entries
                .get(key)
                .is_some_and(|cached| cached.stamps.iter().all(|(file, stamp)| modified(file) == *stamp))
        });
        let key = match fresh {
            Some(key) => key.clone(),
            None => {
                // A failed load names the file it failed on, not every file it read or looked for
                // before failing (its MTL, `.bin`, images): the recording access keeps them, so
                // that a watcher follows them and sees a missing one come back.
                let (access, attempted) = self.access.recording();
                let failure = |error| {
                    let attempted = attempted.paths();
                    Arc::new(MeshFailure { error, attempted })
                };
                // A file parsed for the first time is built in the same go (an OBJ file's
                // closedness is tested beside its assembly then); one parsed before is built
                // from its parse.
                let loaded = match self.parsed_files.get(&canonical_path) {
                    Some(Ok(parsed)) => parsed.build(crease_angle).map_err(failure),
                    Some(Err(parse_failure)) => Err(parse_failure.clone()),
                    None => {
                        self.cache.files_parsed += 1;
                        match ParsedMeshFile::parse_and_build(path, is_obj, &access, crease_angle) {
                            Ok((parsed, loaded)) => {
                                self.parsed_files
                                    .insert(canonical_path.clone(), Ok(Arc::new(parsed)));
                                loaded.map_err(failure)
                            }
                            Err(error) => {
                                let parse_failure = failure(error);
                                self.parsed_files
                                    .insert(canonical_path.clone(), Err(parse_failure.clone()));
                                Err(parse_failure)
                            }
                        }
                    }
                };
                match loaded {
                    Ok(LoadedMesh {
                        mesh,
                        files_read,
                        warnings,
                        lights,
                        cameras,
                        crease_angle_used,
                    }) => {
                        let mut stamped: Vec<PathBuf> = files_read.clone();
                        if !stamped.iter().any(|f| f == path) {
                            stamped.push(path.to_path_buf());
                        }
                        let key = keys[usize::from(crease_angle_used)].clone();
                        // A stale entry under the other key must not outlive this one.
                        for stale in &keys {
                            self.cache.entries.remove(stale);
                        }
                        self.meshes_reported.remove(&key);
                        self.cache.entries.insert(
                            key.clone(),
                            CachedMesh {
                                stamps: stamped.iter().map(|f| (f.clone(), modified(f))).collect(),
                                mesh: Arc::new(mesh),
                                with_tangents: None,
                                trimmed: HashMap::new(),
                                placed: Arc::new(Placed { lights, cameras }),
                                files_read,
                                warnings,
                            },
                        );
                        key
                    }
                    Err(failure) => {
                        self.files_read.push(path.to_path_buf());
                        self.files_read.extend(failure.attempted.iter().cloned());
                        self.mesh_error(failure.error.clone(), at);
                        return None;
                    }
                }
            }
        };
        let Some(cached) = self.cache.entries.get_mut(&key) else {
            return None; // inserted or found just above
        };
        // A scene normal map on a mesh with UVs but no tangents: computed once per mesh.
        let wants_tangents =
            needs.normal_map && !cached.mesh.uvs.is_empty() && cached.mesh.tangents.is_empty();
        let mesh = match (&cached.with_tangents, wants_tangents) {
            (Some(with_tangents), true) => with_tangents.clone(),
            (None, true) => {
                let mut mesh = (*cached.mesh).clone();
                mesh.tangents = compute_tangents(&mesh.positions, &mesh.normals, &mesh.uvs, &mesh.triangles);
                let mesh = Arc::new(mesh);
                cached.with_tangents = Some(mesh.clone());
                mesh
            }
            (_, false) => cached.mesh.clone(),
        };
        // Texture coordinates and tangents that none of the object's materials reads are left
        // out: the renderer takes its fast shading paths only for frames without such
        // per-vertex arrays, and most scans and exports carry texture coordinates (an untextured
        // cow from an OBJ with `vt`, Phong: 2.4× the frame time). Made once per mesh and need.
        let read = AttributesRead::of(&mesh, needs);
        let mesh = if read.leaves_unread(&mesh) {
            let key = (read, wants_tangents, needs.scene_material);
            let trimmed = cached
                .trimmed
                .entry(key)
                .or_insert_with(|| Arc::new(read.trim(&mesh, needs.scene_material)));
            trimmed.clone()
        } else {
            mesh
        };
        let placed = cached.placed.clone();
        // Files and warnings once per load, however many objects use the mesh.
        if self.meshes_reported.insert(key) {
            let files_read = cached.files_read.clone();
            let warnings = cached.warnings.clone();
            self.files_read.push(path.to_path_buf());
            self.files_read.extend(files_read);
            for warning in warnings {
                self.diagnostics.push(Diagnostic::warning(path, warning));
            }
        }
        Some((mesh, placed))
    }

    /// Checks that the mesh of an object whose scene material has a `texture` or
    /// `normal_map` has what they read: without texture coordinates they cannot be applied,
    /// which is worth a warning at the material (the object is still drawn, untextured).
    /// Returns the mesh to draw.
    fn check_surface(
        &mut self,
        mesh: Arc<Mesh>,
        needs: SurfaceNeeds,
        object: &format::ObjectFile,
        index: usize,
        source: SourceId,
    ) -> Arc<Mesh> {
        if !mesh.uvs.is_empty() {
            return mesh;
        }
        let what = match (needs.texture, needs.normal_map) {
            (true, true) => "`texture` and `normal_map` have",
            (true, false) => "`texture` has",
            _ => "`normal_map` has",
        };
        // At the field in an inline material; at the material's name otherwise.
        let at_path = match &object.material {
            Some(MaterialRefFile::Inline(material)) if material.texture.is_some() && needs.texture => {
                ron_path!["objects", index, "material", "texture"].to_vec()
            }
            Some(MaterialRefFile::Inline(material)) if material.normal_map.is_some() => {
                ron_path!["objects", index, "material", "normal_map"].to_vec()
            }
            _ => ron_path!["objects", index, "material"].to_vec(),
        };
        let mesh_name = match &object.mesh {
            MeshFile::Obj(file) | MeshFile::Gltf(file) => format!("mesh file `{file}`"),
            _ => "the mesh".to_string(),
        };
        let diagnostic = Diagnostic::warning(
            self.sources.path(source),
            format!("{what} no effect: {mesh_name} has no texture coordinates; the object is drawn without them"),
        )
        .with_label("needs texture coordinates")
        .with_hint(
            "give the mesh texture coordinates (`vt` in OBJ, `TEXCOORD_0` in glTF), or use a built-in `Sphere`, `Cube` or `Plane`, which have them",
        );
        let diagnostic = self.locate(diagnostic, At::new(source, &at_path));
        self.diagnostics.push(diagnostic);
        mesh
    }

    /// A mesh file that did not load: one diagnostic, saying where in the mesh file (line and
    /// column when the format has them) and pointing at the object that names it.
    fn mesh_error(&mut self, error: MeshError, at: At) {
        let place = match (error.line, error.column) {
            (Some(line), Some(column)) => format!("{}:{line}:{column}", error.path.display()),
            (Some(line), None) => format!("{}:{line}", error.path.display()),
            _ => error.path.display().to_string(),
        };
        let mut diagnostic = Diagnostic::error(
            self.sources.path(at.source),
            format!("{place}: {}", error.message),
        )
        .with_label("this mesh could not be loaded");
        if let Some(hint) = error.hint {
            diagnostic = diagnostic.with_hint(hint);
        }
        let diagnostic = self.locate(diagnostic, at);
        self.diagnostics.push(diagnostic);
    }

    /// Refuses a scene whose render would need more memory than the budget, before it runs.
    fn check_memory(&mut self, image: ImageSettings, lights: &[Light], objects: &[Object], source: SourceId) {
        let estimate = limits::scene_memory(&image, lights, objects);
        if estimate.total() <= self.memory_budget {
            return;
        }
        let triangles: usize = objects.iter().map(|o| o.mesh.triangle_count()).sum();
        let message = format!(
            "rendering this scene needs about {} ({}; {} triangles, {}×{} px), more than the memory budget of {}",
            limits::human_bytes(estimate.total()),
            estimate.parts(),
            triangles,
            image.width,
            image.height,
            limits::human_bytes(self.memory_budget)
        );
        let hint = "make the image smaller, use fewer triangles or smaller shadow maps, or raise the budget with --max-memory";
        // Point at the image when it is the largest part, else at the file.
        if estimate.image >= estimate.geometry.max(estimate.shadow_maps) {
            self.error(
                At::new(source, &ron_path!["image"]),
                message,
                Some("too large"),
                Some(hint.into()),
            );
        } else {
            self.diagnostics
                .push(Diagnostic::error(self.sources.path(source), message).with_hint(hint));
        }
    }

    // ----- camera and lights -----

    fn camera(
        &mut self,
        camera: Option<&CameraFile>,
        source: SourceId,
        bounds: BoundingSphere,
        image: Option<ImageSettings>,
    ) -> Option<Camera> {
        let field = |name: &str| ron_path!["camera", name];
        let (eye, target, up, near, far) = match camera {
            None | Some(CameraFile::Gltf { .. }) => (None, None, None, None, None),
            Some(CameraFile::Perspective {
                eye,
                target,
                up,
                near,
                far,
                ..
            })
            | Some(CameraFile::Orthographic {
                eye,
                target,
                up,
                near,
                far,
                ..
            }) => (*eye, *target, *up, *near, *far),
        };
        let (up_given, eye_given, target_given) = (up.is_some(), eye.is_some(), target.is_some());
        let up = match up {
            Some(up) => self.direction(up, At::new(source, &field("up")))?,
            None => DVec3::Y,
        };
        let target = match target {
            Some(target) => self.vector(target, At::new(source, &field("target")))?,
            None => bounds.center,
        };
        let fov = match camera {
            Some(CameraFile::Perspective { fov: Some(fov), .. }) => {
                self.ranged(*fov, 1e-3, 179.0, At::new(source, &field("fov")), "`fov`")?
            }
            _ => DEFAULT_FOV_DEGREES,
        };
        let aspect = image.map_or(1.0, |i| f64::from(i.width) / f64::from(i.height));
        let eye = match eye {
            Some(eye) => self.vector(eye, At::new(source, &field("eye")))?,
            None => auto_eye(bounds, target, up, fov, aspect),
        };
        let offset = target - eye;
        if offset.length() < 1e-12 {
            self.error(
                At::new(source, &field("target")),
                "the camera's `target` is the same point as its `eye`",
                Some("nothing to look at"),
                None,
            );
            return None;
        }
        if offset.normalize().cross(up).length() < 1e-9 {
            // Without an `up`, the default (0, 1, 0) is parallel: point at what set the view
            // direction (the eye, else the target, else the camera).
            let culprit = match (up_given, eye_given, target_given) {
                (true, _, _) => field("up").to_vec(),
                (false, true, _) => field("eye").to_vec(),
                (false, false, true) => field("target").to_vec(),
                _ => ron_path!["camera"].to_vec(),
            };
            let (label, hint) = if up_given {
                (
                    "parallel to `target - eye`",
                    "pick an `up` that is not along the line of sight, e.g. (0, 0, 1) when looking along Y",
                )
            } else {
                (
                    "looks along Y, the default `up`",
                    "add an `up` that is not along the line of sight, e.g. `up: (0, 0, 1)`",
                )
            };
            self.error(
                At::new(source, &culprit),
                "the camera's `up` is parallel to its view direction",
                Some(label),
                Some(hint.into()),
            );
            return None;
        }
        // Defaults reach from just in front of the eye past the far side of every object.
        let reach = (bounds.center - eye).length() + bounds.radius;
        let far = match far {
            Some(far) => self.ranged(far, 1e-12, f64::INFINITY, At::new(source, &field("far")), "`far`")?,
            None => (2.0 * reach).max(1e-3),
        };
        let near = match near {
            Some(near) => self.ranged(
                near,
                1e-12,
                f64::INFINITY,
                At::new(source, &field("near")),
                "`near`",
            )?,
            None => far / 10_000.0,
        };
        if near >= far {
            self.error(
                At::new(source, &field("near")),
                format!("`near` ({near}) must be less than `far` ({far})"),
                Some("not in front of `far`"),
                None,
            );
            return None;
        }
        let projection = match camera {
            Some(CameraFile::Orthographic { height, .. }) => Projection::Orthographic {
                height: match height {
                    Some(h) => self.ranged(
                        *h,
                        1e-12,
                        f64::INFINITY,
                        At::new(source, &field("height")),
                        "`height`",
                    )?,
                    None => 2.2 * bounds.radius.max(1e-6),
                },
                near,
                far,
            },
            _ => Projection::Perspective {
                fov_y_degrees: fov,
                near,
                far,
            },
        };
        Some(Camera {
            eye,
            target,
            up,
            projection,
        })
    }

    /// `camera: Gltf(object: ..., camera: ...)`: a camera that an object's mesh file places,
    /// moved by the object's transform (see [`ImportedCamera::transformed`]).
    fn gltf_camera(
        &mut self,
        object: Option<&NameOrIndexFile>,
        camera: Option<&NameOrIndexFile>,
        source: SourceId,
        bounds: BoundingSphere,
        objects: &[format::ObjectFile],
        placements: &[Option<ObjectPlacement>],
    ) -> Option<Camera> {
        let describe = |index: usize| match &objects[index].name {
            Some(name) => format!("{index} \"{name}\""),
            None => index.to_string(),
        };
        let candidates: Vec<usize> = (0..placements.len())
            .filter(|&i| {
                placements[i]
                    .as_ref()
                    .is_some_and(|p| !p.placed.cameras.is_empty())
            })
            .collect();
        let all_loaded = placements.iter().all(Option::is_some);
        let listing = if candidates.is_empty() {
            "no object brings a camera: cameras come from glTF files (`mesh: Gltf(...)`) whose scene has camera nodes"
                .to_string()
        } else {
            let names: Vec<String> = candidates.iter().map(|&i| describe(i)).collect();
            format!("objects with cameras (by index or name): {}", names.join(", "))
        };
        let object_path = ron_path!["camera", "object"];
        let index = match object {
            None => match candidates.first() {
                Some(&index) => index,
                None if all_loaded => {
                    self.error(
                        At::new(source, &ron_path!["camera"]),
                        "`Gltf` camera: no object of the scene brings a camera",
                        Some("no camera to take"),
                        Some(listing),
                    );
                    return None;
                }
                None => return None, // an object that failed to load may have had one
            },
            Some(NameOrIndexFile::Index(index)) if *index >= objects.len() => {
                self.error(
                    At::new(source, &object_path),
                    format!(
                        "`Gltf` camera: there is no object {index}; the scene has {} objects",
                        objects.len()
                    ),
                    Some("no such object"),
                    Some(listing),
                );
                return None;
            }
            Some(NameOrIndexFile::Index(index)) => *index,
            Some(NameOrIndexFile::Name(name)) => {
                match objects
                    .iter()
                    .position(|o| o.name.as_deref() == Some(name.as_str()))
                {
                    Some(index) => index,
                    None => {
                        self.error(
                            At::new(source, &object_path),
                            format!("`Gltf` camera: no object is named `{name}`"),
                            Some("no such object"),
                            Some(listing),
                        );
                        return None;
                    }
                }
            }
        };
        // An object that did not load has said why already.
        let placement = placements[index].as_ref()?;
        let cameras = &placement.placed.cameras;
        if cameras.is_empty() {
            self.error(
                At::new(source, &object_path),
                format!("`Gltf` camera: object {} brings no camera", describe(index)),
                Some("no cameras in its mesh"),
                Some(listing),
            );
            return None;
        }
        let chosen = match camera {
            None => Some(&cameras[0]),
            Some(NameOrIndexFile::Index(wanted)) => cameras.iter().find(|c| c.index == *wanted),
            Some(NameOrIndexFile::Name(wanted)) => cameras.iter().find(|c| c.is_named(wanted)),
        };
        let Some(chosen) = chosen else {
            let what = match camera {
                Some(NameOrIndexFile::Name(name)) => format!("named `{name}`"),
                Some(NameOrIndexFile::Index(wanted)) => wanted.to_string(),
                None => unreachable!("the first camera exists"),
            };
            let available: Vec<String> = cameras.iter().map(ImportedCamera::label).collect();
            self.error(
                At::new(source, &ron_path!["camera", "camera"]),
                format!("`Gltf` camera: object {} has no camera {what}", describe(index)),
                Some("no such camera"),
                Some(format!(
                    "its cameras (by index in the glTF `cameras` list, or by name): {}",
                    available.join(", ")
                )),
            );
            return None;
        };
        let placed = chosen.transformed(placement.transform);
        if placed.forward.cross(placed.up).length() < 1e-9 {
            self.error(
                At::new(source, &ron_path!["camera"]),
                format!(
                    "`Gltf` camera: the transform of object {} makes the camera's up parallel to its view direction",
                    describe(index)
                ),
                Some("degenerate camera"),
                None,
            );
            return None;
        }
        let eye = placed.eye;
        // Defaults as for our own cameras: past the far side of every object.
        let reach = (bounds.center - eye).length() + bounds.radius;
        let projection = match placed.projection {
            ImportedProjection::Perspective {
                fov_y_degrees,
                near,
                far,
            } => Projection::Perspective {
                fov_y_degrees: fov_y_degrees.clamp(1e-3, 179.0),
                near,
                far: far.unwrap_or_else(|| (2.0 * reach).max(10.0 * near)),
            },
            ImportedProjection::Orthographic { height, near, far } => Projection::Orthographic {
                height,
                near: if near > 0.0 { near } else { far / 10_000.0 },
                far,
            },
        };
        Some(Camera {
            eye,
            target: eye + placed.forward,
            up: placed.up,
            projection,
        })
    }

    fn light(&mut self, light: &LightFile, index: usize, source: SourceId, camera: &Camera) -> Option<Light> {
        let field = |name: &str| ron_path!["lights", index, name];
        let toward_target = (camera.target - camera.eye).normalize();
        let (color, intensity, shadows, shadow_map) = match light {
            LightFile::Directional {
                color,
                intensity,
                shadows,
                shadow_map,
                ..
            }
            | LightFile::Point {
                color,
                intensity,
                shadows,
                shadow_map,
                ..
            }
            | LightFile::Spot {
                color,
                intensity,
                shadows,
                shadow_map,
                ..
            } => (*color, *intensity, *shadows, *shadow_map),
        };
        let shadow = self.shadow_settings(shadows, shadow_map, index, source);
        let color = match color {
            Some(color) => self.color(color, At::new(source, &field("color"))),
            None => Some(Vec3::ONE),
        };
        let intensity = match intensity {
            Some(i) => self.ranged(
                f64::from(i),
                0.0,
                limits::MAX_LIGHTING_VALUE,
                At::new(source, &field("intensity")),
                "`intensity`",
            ),
            None => Some(1.0),
        };
        let color = color? * intensity? as f32;
        match light {
            LightFile::Directional { direction, .. } => {
                let direction = match direction {
                    Some(d) => self.direction(*d, At::new(source, &field("direction")))?,
                    None => toward_target,
                };
                Some(Light::Directional {
                    direction: direction.as_vec3(),
                    color,
                    shadow: shadow?,
                })
            }
            LightFile::Point {
                position,
                attenuation,
                ..
            } => {
                let position = match position {
                    Some(p) => self.vector(*p, At::new(source, &field("position")))?,
                    None => camera.eye,
                };
                let attenuation = self.attenuation(attenuation.as_ref(), index, source)?;
                Some(Light::Point {
                    position,
                    color,
                    attenuation,
                    shadow: shadow?,
                })
            }
            LightFile::Spot {
                position,
                direction,
                cutoff,
                exponent,
                attenuation,
                ..
            } => {
                let position = match position {
                    Some(p) => self.vector(*p, At::new(source, &field("position"))),
                    None => Some(camera.eye),
                };
                let direction = match direction {
                    Some(d) => self.direction(*d, At::new(source, &field("direction"))),
                    None => Some(toward_target),
                };
                let cutoff = match cutoff {
                    Some(c) => self.ranged(
                        f64::from(*c),
                        0.0,
                        90.0,
                        At::new(source, &field("cutoff")),
                        "spot `cutoff`",
                    ),
                    None => Some(f64::from(DEFAULT_SPOT_CUTOFF_DEGREES)),
                };
                let exponent = match exponent {
                    Some(e) => self.ranged(
                        f64::from(*e),
                        0.0,
                        f64::INFINITY,
                        At::new(source, &field("exponent")),
                        "spot `exponent`",
                    ),
                    None => Some(0.0),
                };
                let attenuation = self.attenuation(attenuation.as_ref(), index, source);
                Some(Light::Spot {
                    position: position?,
                    direction: direction?.as_vec3(),
                    color,
                    cutoff_degrees: cutoff? as f32,
                    exponent: exponent? as f32,
                    attenuation: attenuation?,
                    shadow: shadow?,
                })
            }
        }
    }

    /// `shadows: true` turns a light's shadow map on; `shadow_map` tunes it (and is an error
    /// without `shadows: true`, where it would silently do nothing).
    fn shadow_settings(
        &mut self,
        shadows: Option<bool>,
        settings: Option<ShadowMapFile>,
        index: usize,
        source: SourceId,
    ) -> Option<Option<ShadowSettings>> {
        let path = ron_path!["lights", index, "shadow_map"];
        let Some(true) = shadows else {
            if settings.is_some() {
                self.error(
                    At::new(source, &path),
                    "`shadow_map` has no effect without `shadows: true`",
                    Some("ignored"),
                    Some("add `shadows: true` to this light".into()),
                );
                return None;
            }
            return Some(None);
        };
        let file = settings.unwrap_or_default();
        let default = ShadowSettings::DEFAULT;
        let at = |name: &str| [path.as_slice(), &ron_path![name]].concat();
        let resolution = match file.resolution {
            Some(r) => self
                .ranged(
                    f64::from(r),
                    16.0,
                    8192.0,
                    At::new(source, &at("resolution")),
                    "shadow map `resolution`",
                )
                .map(|r| r as u32),
            None => Some(default.resolution),
        };
        let bias = match file.bias {
            Some(b) => self
                .ranged(
                    f64::from(b),
                    0.0,
                    100.0,
                    At::new(source, &at("bias")),
                    "shadow map `bias`",
                )
                .map(|b| b as f32),
            None => Some(default.bias),
        };
        let filter_radius = match file.filter {
            Some(f) => self
                .ranged(
                    f64::from(f),
                    0.0,
                    8.0,
                    At::new(source, &at("filter")),
                    "shadow map `filter`",
                )
                .map(|f| f as u32),
            None => Some(default.filter_radius),
        };
        Some(Some(ShadowSettings {
            resolution: resolution?,
            bias: bias?,
            filter_radius: filter_radius?,
        }))
    }

    fn attenuation(
        &mut self,
        attenuation: Option<&AttenuationFile>,
        index: usize,
        source: SourceId,
    ) -> Option<Attenuation> {
        let Some(file) = attenuation else {
            return Some(Attenuation::NONE);
        };
        let coefficient = |loader: &mut Self, value: Option<f32>, name: &str, default: f32| -> Option<f32> {
            let Some(value) = value else {
                return Some(default);
            };
            let path = ron_path!["lights", index, "attenuation", name];
            loader
                .ranged(
                    f64::from(value),
                    0.0,
                    f64::INFINITY,
                    At { source, path: &path },
                    &format!("attenuation `{name}`"),
                )
                .map(|v| v as f32)
        };
        let constant = coefficient(self, file.constant, "constant", 1.0);
        let linear = coefficient(self, file.linear, "linear", 0.0);
        let quadratic = coefficient(self, file.quadratic, "quadratic", 0.0);
        let attenuation = Attenuation {
            constant: constant?,
            linear: linear?,
            quadratic: quadratic?,
        };
        if attenuation.constant + attenuation.linear + attenuation.quadratic <= 0.0 {
            let path = ron_path!["lights", index, "attenuation"];
            self.error(
                At { source, path: &path },
                "attenuation coefficients cannot all be zero",
                Some("1 / 0 everywhere"),
                None,
            );
            return None;
        }
        Some(attenuation)
    }
}

/// Where the default camera stands: a three-quarter view from the front-right and above, far
/// enough back that the bounding sphere fits the narrower field of view with a margin.
fn auto_eye(bounds: BoundingSphere, target: DVec3, up: DVec3, fov_y_degrees: f64, aspect: f64) -> DVec3 {
    // In a +Y-up frame: right (+X), above (+Y), in front (+Z).
    let y_up_direction = DVec3::new(0.6, 0.45, 1.0).normalize();
    let direction = DQuat::from_rotation_arc(DVec3::Y, up) * y_up_direction;
    let half_fov_y = fov_y_degrees.to_radians() / 2.0;
    let half_fov_x = (half_fov_y.tan() * aspect).atan();
    let distance = 1.1 * bounds.radius / half_fov_y.min(half_fov_x).sin();
    target + direction * distance
}

fn canonical(path: &Path) -> PathBuf {
    std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf())
}

/// Levenshtein distance, for "did you mean" hints.
fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut previous: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut current = vec![i + 1; b.len() + 1];
        for (j, &cb) in b.iter().enumerate() {
            current[j + 1] = (previous[j] + usize::from(ca != cb))
                .min(previous[j + 1] + 1)
                .min(current[j] + 1);
        }
        previous = current;
    }
    previous[b.len()]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::diag::render_diagnostics;

    fn asset(relative: &str) -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("assets")
            .join(relative)
    }

    fn write(folder: &Path, name: &str, text: &str) -> PathBuf {
        let path = folder.join(name);
        std::fs::write(&path, text).unwrap();
        path
    }

    fn load_ok(path: &Path) -> LoadedScene {
        load_scene(path, &LoadOptions::default()).unwrap_or_else(|error| {
            panic!(
                "{}",
                render_diagnostics(&error.diagnostics, &error.sources, false)
            )
        })
    }

    fn close(a: DVec3, b: DVec3) -> bool {
        (a - b).length() < 1e-5
    }

    /// The Cameras sample with names: the perspective camera is "Persp", the orthographic
    /// camera's node is "OrthoNode" (its camera has no name).
    fn named_cameras(folder: &Path) {
        let text = std::fs::read_to_string(asset("gltf/Cameras/glTF/Cameras.gltf")).unwrap();
        let text = text
            .replacen(
                r#""type": "perspective","#,
                r#""type": "perspective", "name": "Persp","#,
                1,
            )
            .replacen(r#""camera" : 1"#, r#""camera" : 1, "name": "OrthoNode""#, 1);
        assert!(text.contains("Persp") && text.contains("OrthoNode"));
        write(folder, "Cameras.gltf", &text);
        std::fs::copy(
            asset("gltf/Cameras/glTF/simpleSquare.bin"),
            folder.join("simpleSquare.bin"),
        )
        .unwrap();
    }

    #[test]
    fn gltf_cameras_by_index_and_name_through_the_object_transform() {
        // The sample as it is (unnamed cameras), by index: both sit at (0.5, 0.5, 3) looking
        // down −Z; camera 1 is orthographic with ymag 1.
        let folder = tempfile::tempdir().unwrap();
        let sample = asset("gltf/Cameras/glTF/Cameras.gltf");
        let scene = |camera: &str, transform: &str| {
            format!(
                "(camera: {camera}, objects: [(mesh: Sphere()), (name: \"square\", mesh: Gltf({:?}){transform})])",
                sample.display().to_string()
            )
        };
        let load = |text: String| load_ok(&write(folder.path(), "scene.ron", &text)).scene;

        let camera = load(scene("Gltf(object: 1, camera: 1)", "")).camera;
        assert!(close(camera.eye, DVec3::new(0.5, 0.5, 3.0)), "{camera:?}");
        assert!(close(camera.target - camera.eye, DVec3::NEG_Z));
        assert!(close(camera.up, DVec3::Y));
        let Projection::Orthographic { height, near, far } = camera.projection else {
            panic!("orthographic expected: {camera:?}")
        };
        assert!((height - 2.0).abs() < 1e-6 && (near - 0.01).abs() < 1e-6 && (far - 100.0).abs() < 1e-4);

        // The default object (the first that brings cameras) and camera (the first one),
        // through translate, rotate and scale: the eye moves, near and far scale.
        let camera = load(scene(
            "Gltf()",
            ", translate: (1, 0, 0), rotate: (0, 90, 0), scale: 2",
        ))
        .camera;
        // Scaled (1, 1, 6), rotated 90° about Y: (6, 1, −1), translated: (7, 1, −1).
        assert!(close(camera.eye, DVec3::new(7.0, 1.0, -1.0)), "{camera:?}");
        assert!(close(camera.target - camera.eye, DVec3::NEG_X), "{camera:?}");
        assert!(close(camera.up, DVec3::Y));
        let Projection::Perspective {
            fov_y_degrees,
            near,
            far,
        } = camera.projection
        else {
            panic!("perspective expected: {camera:?}")
        };
        assert!(
            (fov_y_degrees - 0.7f64.to_degrees()).abs() < 1e-4,
            "{fov_y_degrees}"
        );
        assert!(
            (near - 0.02).abs() < 1e-6 && (far - 200.0).abs() < 1e-4,
            "{near} {far}"
        );

        // By name: a camera's name, or its node's name; the object by name.
        named_cameras(folder.path());
        let scene = |camera: &str| {
            format!(
                "(camera: {camera}, objects: [(mesh: Cube), (name: \"square\", mesh: Gltf(\"Cameras.gltf\"))])"
            )
        };
        let camera = load(scene(r#"Gltf(object: "square", camera: "Persp")"#)).camera;
        assert!(matches!(camera.projection, Projection::Perspective { .. }));
        let camera = load(scene(r#"Gltf(object: "square", camera: "OrthoNode")"#)).camera;
        assert!(
            matches!(camera.projection, Projection::Orthographic { height, .. } if (height - 2.0).abs() < 1e-6)
        );
        assert!(close(camera.eye, DVec3::new(0.5, 0.5, 3.0)));
    }

    #[test]
    fn unknown_gltf_cameras_and_objects_are_located_errors_listing_the_choices() {
        let folder = tempfile::tempdir().unwrap();
        named_cameras(folder.path());
        let check = |camera: &str, line: usize, expected: &[&str]| {
            let text = format!(
                "Scene(\n    objects: [(mesh: Cube), (name: \"square\", mesh: Gltf(\"Cameras.gltf\"))],\n    camera: {camera},\n)"
            );
            let path = write(folder.path(), "scene.ron", &text);
            let error = load_scene(&path, &LoadOptions::default()).unwrap_err();
            let rendered = render_diagnostics(&error.diagnostics, &error.sources, false);
            let (found_line, _) = error.diagnostics[0].line_column(&error.sources).expect("located");
            assert_eq!(found_line, line, "{rendered}");
            assert!(rendered.contains(&format!("scene.ron:{line}:")), "{rendered}");
            for part in expected {
                assert!(rendered.contains(part), "{part:?} missing from:\n{rendered}");
            }
        };
        check(
            r#"Gltf(object: "square", camera: "Front")"#,
            3,
            &[
                "object 1 \"square\" has no camera named `Front`",
                "its cameras (by index in the glTF `cameras` list, or by name): 0 \"Persp\", 1 \"OrthoNode\"",
            ],
        );
        check(
            "Gltf(object: 1, camera: 7)",
            3,
            &["has no camera 7", "0 \"Persp\", 1 \"OrthoNode\""],
        );
        check(
            r#"Gltf(object: "sqare")"#,
            3,
            &[
                "no object is named `sqare`",
                "objects with cameras (by index or name): 1 \"square\"",
            ],
        );
        check("Gltf(object: 0)", 3, &["object 0 brings no camera"]);
        check(
            "Gltf(object: 5)",
            3,
            &["there is no object 5; the scene has 2 objects"],
        );
    }

    /// A glTF file with the Cameras sample's square and three `KHR_lights_punctual` lights: a
    /// directional light pointing down, a point light at (1, 2, 3), and a spot light (inner
    /// 0.2, outer 0.5 radians) pointing down from (0, 4, 0) under a parent at (0, 0, −1).
    fn lights_fixture(folder: &Path) -> PathBuf {
        std::fs::copy(
            asset("gltf/Cameras/glTF/simpleSquare.bin"),
            folder.join("simpleSquare.bin"),
        )
        .unwrap();
        let down = "[-0.70710678, 0, 0, 0.70710678]";
        let text = format!(
            r#"{{
  "asset": {{"version": "2.0"}},
  "extensionsUsed": ["KHR_lights_punctual"],
  "extensionsRequired": ["KHR_lights_punctual"],
  "extensions": {{"KHR_lights_punctual": {{"lights": [
    {{"type": "directional", "color": [1, 0.5, 0.25], "intensity": 2}},
    {{"type": "point", "intensity": 10}},
    {{"type": "spot", "name": "Spot", "intensity": 5, "spot": {{"innerConeAngle": 0.2, "outerConeAngle": 0.5}}}}
  ]}}}},
  "scene": 0,
  "scenes": [{{"nodes": [0, 1, 2, 4]}}],
  "nodes": [
    {{"mesh": 0}},
    {{"rotation": {down}, "extensions": {{"KHR_lights_punctual": {{"light": 0}}}}}},
    {{"translation": [1, 2, 3], "extensions": {{"KHR_lights_punctual": {{"light": 1}}}}}},
    {{"translation": [0, 4, 0], "rotation": {down}, "extensions": {{"KHR_lights_punctual": {{"light": 2}}}}}},
    {{"translation": [0, 0, -1], "children": [3]}}
  ],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 1}}, "indices": 0}}]}}],
  "buffers": [{{"uri": "simpleSquare.bin", "byteLength": 60}}],
  "bufferViews": [
    {{"buffer": 0, "byteOffset": 0, "byteLength": 12, "target": 34963}},
    {{"buffer": 0, "byteOffset": 12, "byteLength": 48, "target": 34962}}
  ],
  "accessors": [
    {{"bufferView": 0, "componentType": 5123, "count": 6, "type": "SCALAR"}},
    {{"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}}
  ]
}}"#
        );
        write(folder, "lights.gltf", &text)
    }

    #[test]
    fn gltf_lights_become_scene_lights_through_the_object_transform() {
        let folder = tempfile::tempdir().unwrap();
        lights_fixture(folder.path());
        // Scale 2, then 90° about Z ((x, y) → (−y, x)), then (1, 0, 0).
        let object = r#"(mesh: Gltf("lights.gltf"), scale: 2, rotate: (0, 0, 90), translate: (1, 0, 0))"#;
        let scene = write(
            folder.path(),
            "scene.ron",
            &format!("(lights: [Directional(direction: (0, 0, -1))], objects: [{object}])"),
        );
        let loaded = load_ok(&scene);
        assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
        let lights = &loaded.scene.lights;
        assert_eq!(lights.len(), 4, "the scene's light, then the file's: {lights:?}");
        assert!(matches!(lights[0], Light::Directional { direction, .. } if direction == Vec3::NEG_Z));
        let Light::Directional { direction, color, .. } = lights[1] else {
            panic!("directional expected: {:?}", lights[1])
        };
        assert!(direction.abs_diff_eq(Vec3::X, 1e-5), "{direction}");
        assert_eq!(color, Vec3::new(2.0, 1.0, 0.5));
        let Light::Point {
            position,
            color,
            attenuation,
            ..
        } = lights[2]
        else {
            panic!("point expected: {:?}", lights[2])
        };
        // (1, 2, 3) → (2, 4, 6) → (−4, 2, 6) → (−3, 2, 6).
        assert!(close(position, DVec3::new(-3.0, 2.0, 6.0)), "{position}");
        assert_eq!(color, Vec3::splat(10.0));
        assert_eq!(attenuation, crate::mesh::INVERSE_SQUARE);
        let Light::Spot {
            position,
            direction,
            color,
            cutoff_degrees,
            exponent,
            ..
        } = lights[3]
        else {
            panic!("spot expected: {:?}", lights[3])
        };
        // (0, 4, −1) → (0, 8, −2) → (−8, 0, −2) → (−7, 0, −2), pointing down → +X.
        assert!(close(position, DVec3::new(-7.0, 0.0, -2.0)), "{position}");
        assert!(direction.abs_diff_eq(Vec3::X, 1e-5), "{direction}");
        assert_eq!(color, Vec3::splat(5.0));
        assert!(
            (cutoff_degrees - 28.647_89).abs() < 1e-3,
            "0.5 rad in degrees: {cutoff_degrees}"
        );
        assert_eq!(
            exponent,
            crate::mesh::spot_exponent(0.2f32.to_degrees(), 0.5f32.to_degrees())
        );
        assert!(exponent > 0.0);

        // Without `lights`, the file's lights replace the default headlight...
        let scene = write(folder.path(), "scene.ron", &format!("(objects: [{object}])"));
        assert_eq!(load_ok(&scene).scene.lights.len(), 3);
        // ... which a glTF without lights still gets.
        let scene = write(
            folder.path(),
            "scene.ron",
            &format!(
                "(objects: [(mesh: Gltf({:?}))])",
                asset("gltf/Cameras/glTF/Cameras.gltf").display().to_string()
            ),
        );
        assert_eq!(load_ok(&scene).scene.lights.len(), 1);
    }

    #[test]
    fn each_mesh_file_is_parsed_once_per_load_however_it_is_named() {
        let folder = tempfile::tempdir().unwrap();
        let with_normals = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//1\n";
        write(folder.path(), "normals.obj", with_normals);
        write(folder.path(), "bare.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
        std::fs::create_dir(folder.path().join("sub")).unwrap();
        let scene = |objects: &str| {
            write(
                folder.path(),
                "scene.ron",
                &format!("(image: (width: 8, height: 8), objects: [{objects}])"),
            )
        };
        let parses = |path: &Path| {
            let mut cache = MeshCache::default();
            let loaded = load_scene_cached(path, &LoadOptions::default(), &mut cache).unwrap();
            let again = load_scene_cached(path, &LoadOptions::default(), &mut cache).unwrap();
            assert_eq!(loaded.scene.objects.len(), again.scene.objects.len());
            (cache.files_parsed(), loaded)
        };
        // One file under three names, with crease angles that cannot change it (it has
        // normals): one parse, one mesh shared by the objects, its warnings once.
        let (count, loaded) = parses(&scene(
            r#"(mesh: Obj("normals.obj")), (mesh: Obj("./normals.obj"), crease_angle: 10),
               (mesh: Obj("sub/../normals.obj"), crease_angle: 80)"#,
        ));
        assert_eq!(count, 1);
        let meshes: Vec<_> = loaded.scene.objects.iter().map(|o| o.mesh.clone()).collect();
        assert!(meshes.iter().all(|m| Arc::ptr_eq(m, &meshes[0])));
        // Without normals the crease angle shapes the mesh: one mesh per angle, built from
        // one parse of the file; the same for a glTF file.
        let triangle = asset("gltf/Triangle/glTF/Triangle.gltf");
        let (count, loaded) = parses(&scene(&format!(
            r#"(mesh: Obj("bare.obj")), (mesh: Obj("bare.obj")), (mesh: Obj("bare.obj"), crease_angle: 10),
               (mesh: Gltf({triangle:?})), (mesh: Gltf({triangle:?}), crease_angle: 5)"#,
        )));
        assert_eq!(count, 2, "one parse per file");
        let meshes: Vec<_> = loaded.scene.objects.iter().map(|o| o.mesh.clone()).collect();
        assert!(Arc::ptr_eq(&meshes[0], &meshes[1]) && !Arc::ptr_eq(&meshes[1], &meshes[2]));
        assert!(!Arc::ptr_eq(&meshes[3], &meshes[4]));
    }

    #[test]
    fn scene_normal_maps_get_tangents_and_textures_on_meshes_without_uvs_warn() {
        let folder = tempfile::tempdir().unwrap();
        let png = std::fs::read(asset("gltf/Avocado/glTF/Avocado_normal.png")).unwrap();
        std::fs::write(folder.path().join("n.png"), png).unwrap();
        write(
            folder.path(),
            "uv.obj",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1 2/2 3/3\n",
        );
        write(folder.path(), "bare.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
        let scene = write(
            folder.path(),
            "scene.ron",
            r#"(objects: [
                (mesh: Obj("uv.obj"), material: (normal_map: "n.png")),
                (mesh: Obj("uv.obj"), material: (normal_map: "n.png", texture: "n.png")),
                (mesh: Obj("uv.obj")),
                (mesh: Sphere(segments: 8), material: (normal_map: "n.png")),
                (mesh: Cube, material: (texture: "n.png")),
                (mesh: Plane),
                (mesh: Obj("bare.obj"), material: (texture: "n.png")),
            ])"#,
        );
        let loaded = load_ok(&scene);
        let objects = &loaded.scene.objects;
        for object in objects {
            object.mesh.check_invariant().unwrap();
        }
        // The normal-mapped objects share one mesh with tangents; the plain one keeps the file's.
        assert!(!objects[0].mesh.tangents.is_empty() && Arc::ptr_eq(&objects[0].mesh, &objects[1].mesh));
        assert!(objects[2].mesh.tangents.is_empty());
        let texture_ready = |mesh: &Mesh| !mesh.uvs.is_empty() && !mesh.tangents.is_empty();
        assert!(texture_ready(&objects[3].mesh) && texture_ready(&objects[4].mesh));
        assert_eq!(
            *objects[5].mesh,
            primitives::plane(),
            "untextured primitives stay plain"
        );
        let warnings: Vec<_> = loaded.warnings.iter().map(|w| w.message.as_str()).collect();
        assert_eq!(warnings.len(), 1, "{warnings:?}");
        assert!(
            warnings[0].contains("`texture` has no effect: mesh file `bare.obj` has no texture coordinates")
        );
        assert!(
            loaded.warnings[0].line_column(&loaded.sources).is_some(),
            "located"
        );
    }

    #[test]
    fn texture_coordinates_and_tangents_no_material_reads_are_left_out() {
        let folder = tempfile::tempdir().unwrap();
        let png = std::fs::read(asset("gltf/Avocado/glTF/Avocado_normal.png")).unwrap();
        std::fs::write(folder.path().join("t.png"), png).unwrap();
        write(
            folder.path(),
            "uv.obj",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1 2/2 3/3\n",
        );
        let avocado = asset("gltf/Avocado/glTF/Avocado.gltf");
        let duck = asset("gltf/Duck/glTF/Duck.gltf");
        let scene = write(
            folder.path(),
            "scene.ron",
            &format!(
                r#"(objects: [
                (mesh: Obj("uv.obj")),
                (mesh: Obj("uv.obj"), material: (diffuse: (1, 0, 0))),
                (mesh: Obj("uv.obj"), material: (texture: "t.png")),
                (mesh: Gltf({avocado:?})),
                (mesh: Gltf({duck:?}), material: (diffuse: (1, 1, 0))),
                (mesh: Gltf({duck:?})),
                (mesh: Obj("uv.obj")),
            ])"#
            ),
        );
        let loaded = load_ok(&scene);
        let meshes: Vec<&Mesh> = loaded.scene.objects.iter().map(|o| &*o.mesh).collect();
        for mesh in &meshes {
            mesh.check_invariant().unwrap();
        }
        let arrays = |mesh: &Mesh| {
            (
                !mesh.uvs.is_empty(),
                !mesh.tangents.is_empty(),
                mesh.materials.len(),
            )
        };
        // Nothing reads the OBJ's coordinates but the scene texture.
        assert_eq!(arrays(meshes[0]), (false, false, 0));
        assert_eq!(arrays(meshes[1]), (false, false, 0));
        assert_eq!(arrays(meshes[2]), (true, false, 0));
        // The Avocado's own materials have a base colour texture and a normal map; the Duck's
        // own texture goes with its material when a scene material replaces it.
        assert_eq!(arrays(meshes[3]), (true, true, 1));
        assert_eq!(arrays(meshes[4]), (false, false, 0));
        assert!(meshes[4].textures.is_empty() && meshes[4].triangle_materials.is_empty());
        assert_eq!(arrays(meshes[5]), (true, false, 1));
        // One trimmed mesh per mesh and need.
        let objects = &loaded.scene.objects;
        assert!(Arc::ptr_eq(&objects[0].mesh, &objects[6].mesh));
    }

    #[test]
    fn cached_meshes_keep_their_lights_and_cameras() {
        let folder = tempfile::tempdir().unwrap();
        lights_fixture(folder.path());
        named_cameras(folder.path());
        let scene = write(
            folder.path(),
            "scene.ron",
            r#"(camera: Gltf(object: 1, camera: "Persp"), objects: [(mesh: Gltf("lights.gltf")), (mesh: Gltf("Cameras.gltf"))])"#,
        );
        let mut cache = MeshCache::default();
        let first = load_scene_cached(&scene, &LoadOptions::default(), &mut cache).unwrap();
        let second = load_scene_cached(&scene, &LoadOptions::default(), &mut cache).unwrap();
        assert!(
            Arc::ptr_eq(&first.scene.objects[0].mesh, &second.scene.objects[0].mesh),
            "cached"
        );
        assert_eq!(first.scene.lights, second.scene.lights);
        assert_eq!(second.scene.lights.len(), 3);
        assert_eq!(first.scene.camera, second.scene.camera);
    }

    #[test]
    fn generated_spheres_are_cached_by_segments_and_texture_coordinates() {
        let text = r#"(objects: [
            (mesh: Sphere(segments: 40)),
            (mesh: Sphere(segments: 40), translate: (2, 0, 0)),
            (mesh: Sphere(segments: 40), material: (texture: "t.png")),
            (mesh: Sphere(segments: 41)),
        ])"#;
        let folder = tempfile::tempdir().unwrap();
        image::RgbImage::new(2, 2)
            .save(folder.path().join("t.png"))
            .unwrap();
        let path = folder.path().join("s.ron");
        let mut cache = MeshCache::default();
        let first = load_scene_from_str_cached(&path, text, &LoadOptions::default(), &mut cache).unwrap();
        let second = load_scene_from_str_cached(&path, text, &LoadOptions::default(), &mut cache).unwrap();
        let mesh = |loaded: &LoadedScene, index: usize| Arc::clone(&loaded.scene.objects[index].mesh);
        assert!(
            Arc::ptr_eq(&mesh(&first, 0), &mesh(&second, 0)),
            "kept between loads"
        );
        assert!(
            Arc::ptr_eq(&mesh(&first, 0), &mesh(&first, 1)),
            "shared within a scene"
        );
        assert!(!Arc::ptr_eq(&mesh(&first, 0), &mesh(&first, 2)), "textured apart");
        assert!(!mesh(&first, 2).uvs.is_empty());
        assert!(!Arc::ptr_eq(&mesh(&first, 0), &mesh(&first, 3)), "by segments");
        assert_eq!(
            *mesh(&first, 0),
            primitives::sphere(40),
            "the generated sphere itself"
        );
    }
}
