//! `render --pick X,Y` and the preview's `GET /api/pick`: one pixel inspected
//! (`render::inspect`), joined with where its object, material, mesh and lights are written in
//! the scene's files, as JSON (the schema is `docs/pick.md`).
//!
//! The renderer's `Scene` carries no source locations (an architecture invariant); the loader's
//! `Sources` keep the texts it read, so the locations are found here, after the fact, by
//! `scene::locate` on those texts, as diagnostics find theirs.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::{Vec2, Vec3, Vec4};
use serde::Serialize;

use crate::diag::{Sources, line_column};
use crate::lighting::LightContribution;
use crate::output::{Encoding, linear_to_srgb, quantize_channel};
use crate::render::inspect::{
    LightingBreakdown, MaterialOrigin, PickError, PixelInspection, SurfaceInspection, SurfaceLighting,
    inspect_pixel,
};
use crate::render::shade::TexelRead;
use crate::render::{DebugView, RenderOptions};
use crate::ron_path;
use crate::scene::load::{LoadOptions, scene_materials};
use crate::scene::locate::{PathSegment, locate};
use crate::scene::{
    Light, LightingComponent, LightingModel, Material, MicrofacetDistribution, Scene, Shading,
};
use crate::texture::MipChoice;

/// What made an image, kept beside it so that its pixels can be inspected later: the scene as
/// loaded (overrides applied), the texts the loader read, and the settings of the render. The
/// watch session hands one to the preview server with each image it publishes.
#[derive(Debug, Clone)]
pub struct ImageOrigin {
    pub scene: Arc<Scene>,
    pub sources: Arc<Sources>,
    /// How the scene's files were read (for the material tables of its includes).
    pub load_options: LoadOptions,
    pub render_options: RenderOptions,
    /// How the image's 8-bit values store light.
    pub encoding: Encoding,
}

impl ImageOrigin {
    /// The pick JSON of pixel `(x, y)` (see `docs/pick.md`).
    pub fn pick(&self, x: u32, y: u32) -> Result<PickReport, PickError> {
        let inspection = inspect_pixel(&self.scene, &self.render_options, x, y)?;
        Ok(report(self, &inspection))
    }

    /// The path of the scene file (the first file the loader read).
    fn scene_path(&self) -> Option<&Path> {
        self.sources.iter().next().map(|(_, path, _)| path)
    }
}

/// A place in a file: absolute path, 1-based line and column (in characters).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SourceLocation {
    pub path: PathBuf,
    pub line: usize,
    pub column: usize,
}

/// The answer to a pick (`docs/pick.md` describes every field).
#[derive(Debug, Clone, Serialize)]
pub struct PickReport {
    pub x: u32,
    pub y: u32,
    pub width: u32,
    pub height: u32,
    pub samples: u32,
    pub scene: Option<PathBuf>,
    pub debug_view: Option<&'static str>,
    pub background: bool,
    pub background_samples: u32,
    pub background_color: [f32; 3],
    pub color: PixelColor,
    pub surfaces: Vec<SurfaceReport>,
}

#[derive(Debug, Clone, Serialize)]
pub struct PixelColor {
    /// Linear, before clamping: what the frame wrote.
    pub linear: [f32; 3],
    /// What the 8-bit image holds.
    pub rgb8: [u8; 3],
    pub encoding: &'static str,
}

#[derive(Debug, Clone, Serialize)]
pub struct SurfaceReport {
    pub object: ObjectReport,
    pub mesh: MeshReport,
    pub samples: u32,
    pub shading_point: [f64; 2],
    pub depth: f32,
    pub view_distance: f32,
    pub position: [f64; 3],
    pub normal: [f32; 3],
    pub geometric_normal: [f32; 3],
    pub back_facing: bool,
    pub shading: &'static str,
    pub component: &'static str,
    pub lighting_model: String,
    pub material: MaterialReport,
    pub texels: Vec<TexelReport>,
    pub lighting: LightingReport,
    pub color: [f32; 3],
}

#[derive(Debug, Clone, Serialize)]
pub struct ObjectReport {
    pub index: usize,
    /// Its `name`, or the loader's `object N` for an object without one.
    pub name: String,
    pub defined_at: Option<SourceLocation>,
}

#[derive(Debug, Clone, Serialize)]
pub struct MeshReport {
    /// The object's `mesh` value as written (`Sphere(segments: 64)`, `Obj("teapot.obj")`).
    pub source: Option<String>,
    /// The mesh file, when the mesh is read from one.
    pub file: Option<PathBuf>,
    pub defined_at: Option<SourceLocation>,
    pub triangle: usize,
    pub vertices: [u32; 3],
    pub barycentrics: [f32; 3],
}

#[derive(Debug, Clone, Serialize)]
pub struct MaterialReport {
    pub name: Option<String>,
    /// `scene`, `include`, `preset`, `inline`, `mesh` or `default`.
    pub origin: &'static str,
    pub defined_at: Option<SourceLocation>,
    pub mesh_material: Option<u32>,
    pub ambient: [f32; 3],
    pub diffuse: [f32; 3],
    pub specular: [f32; 3],
    pub shininess: f32,
    pub emission: [f32; 3],
}

#[derive(Debug, Clone, Serialize)]
pub struct TexelReport {
    /// `diffuse`, `ambient` or `normal`.
    pub role: &'static str,
    /// Index into the textures of the material's owner (scene or mesh file).
    pub texture: u32,
    /// The image file the texture was read from; `null` for an image embedded in a glTF file.
    pub file: Option<PathBuf>,
    pub uv: [f32; 2],
    /// `log₂` of the pixel's footprint in texels of level 0, before the bias.
    pub level_of_detail: f32,
    /// The scene's `image.mip_bias`, added to `level_of_detail` to choose the level.
    pub mip_bias: f32,
    /// The level read, blended towards the next one by `level_fraction`.
    pub level: usize,
    pub level_fraction: f32,
    pub level_size: [u32; 2],
    pub texel: [f32; 2],
    pub value: [f32; 4],
}

#[derive(Debug, Clone, Serialize)]
pub struct LightingReport {
    /// `pixel` (Phong), `centroid` (flat), `object` (constant), `vertices` (Gouraud) or `none`
    /// (a normals or depth view).
    pub at: &'static str,
    pub points: Vec<PointLighting>,
}

#[derive(Debug, Clone, Serialize)]
pub struct PointLighting {
    pub normal: [f32; 3],
    pub lit_side: bool,
    pub emission: [f32; 3],
    pub ambient: [f32; 3],
    pub lights: Vec<LightReport>,
    pub diffuse: [f32; 3],
    pub specular: [f32; 3],
    pub shown_ambient_diffuse: [f32; 3],
    pub shown_specular_emission: [f32; 3],
    pub color: [f32; 3],
}

#[derive(Debug, Clone, Serialize)]
pub struct LightReport {
    pub index: usize,
    pub kind: &'static str,
    pub defined_at: Option<SourceLocation>,
    pub reaches: bool,
    pub to_light: [f32; 3],
    pub n_dot_l: f32,
    pub attenuation: f32,
    pub spot: f32,
    pub shadow: f32,
    pub diffuse: [f32; 3],
    pub specular: [f32; 3],
}

impl PickReport {
    /// The report as indented JSON.
    pub fn to_json_pretty(&self) -> String {
        // Numbers, strings, options and lists of them always serialise.
        serde_json::to_string_pretty(self).unwrap_or_else(|_| String::from("{}"))
    }

    /// The report as compact JSON.
    pub fn to_json(&self) -> String {
        serde_json::to_string(self).unwrap_or_else(|_| String::from("{}"))
    }
}

fn v3(v: Vec3) -> [f32; 3] {
    v.to_array()
}

fn report(origin: &ImageOrigin, inspection: &PixelInspection) -> PickReport {
    let scene = &origin.scene;
    let rgb8 = {
        let color = match origin.encoding {
            Encoding::Linear => inspection.color,
            Encoding::Srgb => inspection.color.clamp(Vec3::ZERO, Vec3::ONE).map(linear_to_srgb),
        };
        color.to_array().map(quantize_channel)
    };
    let texts = SceneTexts::new(origin);
    PickReport {
        x: inspection.x,
        y: inspection.y,
        width: scene.image.width,
        height: scene.image.height,
        samples: inspection.samples,
        scene: origin.scene_path().map(absolute),
        debug_view: inspection.debug_view.map(debug_view_name),
        background: inspection.surfaces.is_empty(),
        background_samples: inspection.background_samples,
        background_color: v3(inspection.background),
        color: PixelColor {
            linear: v3(inspection.color),
            rgb8,
            encoding: match origin.encoding {
                Encoding::Linear => "linear",
                Encoding::Srgb => "srgb",
            },
        },
        surfaces: inspection
            .surfaces
            .iter()
            .map(|surface| surface_report(scene, &texts, surface))
            .collect(),
    }
}

/// The scene file's text and what is looked up in it, once per pick.
struct SceneTexts<'a> {
    path: Option<PathBuf>,
    text: &'a str,
    /// Every material the scene can name, with where it is defined.
    materials: Vec<crate::scene::load::NamedMaterial>,
}

impl<'a> SceneTexts<'a> {
    fn new(origin: &'a ImageOrigin) -> Self {
        let first = origin.sources.iter().next();
        let path = first.map(|(_, path, _)| path.to_path_buf());
        let text = first.map_or("", |(_, _, text)| text);
        let materials = path
            .as_deref()
            .map(|path| scene_materials(path, text, &origin.load_options))
            .unwrap_or_default();
        SceneTexts {
            path,
            text,
            materials,
        }
    }

    /// Where the value at `path` starts in the scene file, and its text.
    fn find(&self, path: &[PathSegment]) -> Option<(SourceLocation, &'a str)> {
        let range = locate(self.text, path)?;
        let file = self.path.as_deref()?;
        Some((location(file, self.text, range.start), &self.text[range]))
    }
}

fn location(path: &Path, text: &str, offset: usize) -> SourceLocation {
    let (line, column) = line_column(text, offset);
    SourceLocation {
        path: absolute(path),
        line,
        column,
    }
}

/// `path` made absolute (an editor link needs one), without resolving symbolic links.
fn absolute(path: &Path) -> PathBuf {
    std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf())
}

fn surface_report(scene: &Scene, texts: &SceneTexts, surface: &SurfaceInspection) -> SurfaceReport {
    let index = surface.object;
    let object = &scene.objects[index];
    let object_at = texts.find(&ron_path!["objects", index]).map(|(at, _)| at);
    let mesh_value = texts.find(&ron_path!["objects", index, "mesh"]);
    let mesh_file = mesh_value.as_ref().and_then(|(_, text)| {
        let quoted = text.split('"').nth(1)?;
        let base = texts.path.as_deref()?.parent()?;
        Some(absolute(&base.join(quoted)))
    });
    SurfaceReport {
        object: ObjectReport {
            index,
            name: object.name.clone(),
            defined_at: object_at,
        },
        mesh: MeshReport {
            source: mesh_value.as_ref().map(|(_, text)| text.to_string()),
            file: mesh_file,
            defined_at: mesh_value.map(|(at, _)| at),
            triangle: surface.mesh_triangle,
            vertices: surface.mesh_vertices,
            barycentrics: v3(surface.barycentrics),
        },
        samples: surface.sample_count,
        shading_point: [surface.shading_point.0, surface.shading_point.1],
        depth: surface.depth,
        view_distance: surface.view_distance,
        position: surface.position.to_array(),
        normal: v3(surface.normal),
        geometric_normal: v3(surface.geometric_normal),
        back_facing: surface.back_facing,
        shading: shading_name(surface.shading),
        component: component_name(surface.component),
        lighting_model: model_name(surface.material.model),
        material: material_report(texts, index, surface),
        texels: surface
            .texels
            .iter()
            .map(|texel| texel_report(scene, object, &surface.material, texel))
            .collect(),
        lighting: lighting_report(scene, texts, &surface.lighting),
        color: v3(surface.color),
    }
}

fn material_report(texts: &SceneTexts, object: usize, surface: &SurfaceInspection) -> MaterialReport {
    let material: &Material = &surface.material;
    let (name, origin, defined_at, mesh_material) = match surface.material_origin {
        MaterialOrigin::Object => match texts.find(&ron_path!["objects", object, "material"]) {
            Some((_, text)) if text.starts_with('"') => {
                let name = text.trim_matches('"').to_string();
                let definition = texts
                    .materials
                    .iter()
                    .find(|m| m.name == name)
                    .and_then(|m| m.defined_at.as_ref());
                match definition {
                    Some((path, range)) => {
                        let in_scene = texts.path.as_deref() == Some(path.as_path());
                        let origin = if in_scene { "scene" } else { "include" };
                        let included;
                        let text = if in_scene {
                            texts.text
                        } else {
                            included = std::fs::read_to_string(path).unwrap_or_default();
                            &included
                        };
                        (Some(name), origin, Some(location(path, text, range.start)), None)
                    }
                    None => (Some(name), "preset", None, None),
                }
            }
            Some((at, _)) => (None, "inline", Some(at), None),
            None => (None, "inline", None, None),
        },
        MaterialOrigin::Mesh(index) => (None, "mesh", None, Some(index)),
        MaterialOrigin::Default => (None, "default", None, None),
    };
    MaterialReport {
        name,
        origin,
        defined_at,
        mesh_material,
        ambient: v3(material.ambient),
        diffuse: v3(material.diffuse),
        specular: v3(material.specular),
        shininess: material.shininess,
        emission: v3(material.emission),
    }
}

fn texel_report(
    scene: &Scene,
    object: &crate::scene::Object,
    material: &Material,
    texel: &TexelRead,
) -> TexelReport {
    let role = if Some(texel.binding) == material.textures.diffuse {
        "diffuse"
    } else if Some(texel.binding) == material.textures.ambient {
        "ambient"
    } else {
        "normal"
    };
    // A scene material's textures are the scene's; a mesh file's, the mesh's.
    let textures = if object.material.is_some() {
        &scene.textures
    } else {
        &object.mesh.textures
    };
    let texture = textures.get(texel.binding.texture as usize);
    let level_of_detail = texture.map_or(0.0, |t| t.level_of_detail(texel.uv_dx, texel.uv_dy));
    // The frame's own choice of levels (`Texture::sample_biased`), bias included.
    let mip_bias = scene.image.mip_bias;
    let MipChoice { level, fraction } = texture
        .and_then(|t| t.mip_choice(texel.uv_dx, texel.uv_dy, mip_bias))
        .unwrap_or(MipChoice {
            level: 0,
            fraction: 0.0,
        });
    let size = texture
        .and_then(|t| t.levels.get(level))
        .map_or([0, 0], |l| [l.width, l.height]);
    let texel_at: Vec2 = texel.uv * Vec2::new(size[0] as f32, size[1] as f32);
    TexelReport {
        role,
        texture: texel.binding.texture,
        file: texture.and_then(|t| t.file.clone()),
        uv: texel.uv.to_array(),
        level_of_detail,
        mip_bias,
        level,
        level_fraction: fraction,
        level_size: size,
        texel: texel_at.to_array(),
        value: Vec4::to_array(&texel.value),
    }
}

fn lighting_report(scene: &Scene, texts: &SceneTexts, lighting: &SurfaceLighting) -> LightingReport {
    let point = |breakdown: &LightingBreakdown| point_report(scene, texts, breakdown);
    match lighting {
        SurfaceLighting::Pixel(b) => LightingReport {
            at: "pixel",
            points: vec![point(b)],
        },
        SurfaceLighting::Triangle(b) => LightingReport {
            at: "centroid",
            points: vec![point(b)],
        },
        SurfaceLighting::Object(b) => LightingReport {
            at: "object",
            points: vec![point(b)],
        },
        SurfaceLighting::Vertices(bs) => LightingReport {
            at: "vertices",
            points: bs.iter().map(point).collect(),
        },
        SurfaceLighting::DebugView => LightingReport {
            at: "none",
            points: Vec::new(),
        },
    }
}

fn point_report(scene: &Scene, texts: &SceneTexts, breakdown: &LightingBreakdown) -> PointLighting {
    let lights_written = texts.find(&ron_path!["lights"]).is_some();
    PointLighting {
        normal: v3(breakdown.normal),
        lit_side: breakdown.lit_side,
        emission: v3(breakdown.terms.emission),
        ambient: v3(breakdown.terms.ambient),
        lights: breakdown
            .lights
            .iter()
            .enumerate()
            .map(|(index, part): (usize, &LightContribution)| LightReport {
                index,
                kind: match scene.lights.get(index) {
                    Some(Light::Directional { .. }) => "directional",
                    Some(Light::Point { .. }) => "point",
                    Some(Light::Spot { .. }) => "spot",
                    None => "unknown",
                },
                defined_at: lights_written
                    .then(|| texts.find(&ron_path!["lights", index]).map(|(at, _)| at))
                    .flatten(),
                reaches: part.reaches,
                to_light: v3(part.to_light),
                n_dot_l: part.n_dot_l,
                attenuation: part.attenuation,
                spot: part.spot,
                shadow: part.visibility,
                diffuse: v3(part.diffuse),
                specular: v3(part.specular),
            })
            .collect(),
        diffuse: v3(breakdown.terms.diffuse),
        specular: v3(breakdown.terms.specular),
        shown_ambient_diffuse: v3(breakdown.shown.0),
        shown_specular_emission: v3(breakdown.shown.1),
        color: v3(breakdown.color),
    }
}

fn debug_view_name(view: DebugView) -> &'static str {
    match view {
        DebugView::Ambient => "ambient",
        DebugView::Diffuse => "diffuse",
        DebugView::Specular => "specular",
        DebugView::Normals => "normals",
        DebugView::Depth => "depth",
    }
}

fn shading_name(shading: Shading) -> &'static str {
    match shading {
        Shading::Constant => "Constant",
        Shading::Flat => "Flat",
        Shading::Gouraud => "Gouraud",
        Shading::Phong => "Phong",
    }
}

fn component_name(component: LightingComponent) -> &'static str {
    match component {
        LightingComponent::All => "All",
        LightingComponent::Ambient => "Ambient",
        LightingComponent::Diffuse => "Diffuse",
        LightingComponent::Specular => "Specular",
    }
}

fn model_name(model: LightingModel) -> String {
    match model {
        LightingModel::Phong => "Phong".into(),
        LightingModel::BlinnPhong => "BlinnPhong".into(),
        LightingModel::Lambert => "Lambert".into(),
        LightingModel::Unlit => "Unlit".into(),
        LightingModel::CookTorrance(surface) => format!(
            "CookTorrance({}, roughness {})",
            match surface.distribution {
                MicrofacetDistribution::Beckmann => "Beckmann",
                MicrofacetDistribution::Ggx => "GGX",
            },
            surface.roughness
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::load::load_scene;

    const LIBRARY: &str = "// Materials for the pick test.
Materials(
    materials: {
        \"brass\": (diffuse: (0.7, 0.5, 0.2), specular: (0.3, 0.3, 0.3), shininess: 20),
    },
)
";

    const SCENE: &str = r#"Scene(
    include: ["lib.ron"],
    image: (width: 40, height: 30),
    camera: Perspective(eye: (0, 0, 8), target: (0, 0, 0), up: (0, 1, 0), fov: 30),
    materials: {
        "chalk": (diffuse: (0.9, 0.9, 0.9)),
    },
    lights: [
        Directional(direction: (0, 0, -1)),
        Point(position: (0, 2, 3)),
    ],
    objects: [
        (name: "left", mesh: Sphere(segments: 32), translate: (-1.2, 0, 0), material: "brass"),
        (name: "right", mesh: Sphere(segments: 32), translate: (1.2, 0, 0), material: "chalk"),
        (mesh: Cube, translate: (0, 0, -3), scale: (5, 5, 0.1), material: "pearl"),
        (mesh: Cube, translate: (0, 1.6, 0), scale: 0.3, material: (diffuse: (0, 0, 1))),
    ],
)
"#;

    /// 1-based line and column (in chars) of the first occurrence of `needle` in `text`,
    /// counted here rather than by `diag`.
    fn position_of(text: &str, needle: &str) -> (usize, usize) {
        let offset = text
            .find(needle)
            .unwrap_or_else(|| panic!("{needle} is in the text"));
        let before = &text[..offset];
        let line = before.lines().count() + usize::from(before.ends_with('\n') || before.is_empty());
        let column = before.rsplit('\n').next().unwrap().chars().count() + 1;
        (line.max(1), column)
    }

    fn origin(folder: &Path) -> ImageOrigin {
        std::fs::write(folder.join("lib.ron"), LIBRARY).unwrap();
        std::fs::write(folder.join("scene.ron"), SCENE).unwrap();
        let loaded = load_scene(&folder.join("scene.ron"), &LoadOptions::default()).unwrap();
        ImageOrigin {
            scene: Arc::new(loaded.scene),
            sources: Arc::new(loaded.sources),
            load_options: LoadOptions::default(),
            render_options: RenderOptions::default(),
            encoding: Encoding::Linear,
        }
    }

    fn at(location: &Option<SourceLocation>) -> (PathBuf, usize, usize) {
        let location = location.as_ref().expect("a location");
        (location.path.clone(), location.line, location.column)
    }

    #[test]
    fn objects_materials_meshes_and_lights_point_at_their_definitions() {
        let folder = tempfile::tempdir().unwrap();
        let origin = origin(folder.path());
        let scene_file = std::path::absolute(folder.path().join("scene.ron")).unwrap();
        let library_file = std::path::absolute(folder.path().join("lib.ron")).unwrap();

        // The left sphere (its centre is 1.2 units left of the image's centre: about 8 pixels).
        let left = origin.pick(12, 15).unwrap();
        let surface = &left.surfaces[0];
        assert_eq!(surface.object.index, 0);
        assert_eq!(surface.object.name, "left");
        let (line, column) = position_of(SCENE, "(name: \"left\"");
        assert_eq!(at(&surface.object.defined_at), (scene_file.clone(), line, column));
        let (line, column) = position_of(SCENE, "Sphere(segments: 32), translate: (-1.2");
        assert_eq!(at(&surface.mesh.defined_at), (scene_file.clone(), line, column));
        assert_eq!(surface.mesh.source.as_deref(), Some("Sphere(segments: 32)"));
        assert_eq!(surface.material.name.as_deref(), Some("brass"));
        assert_eq!(surface.material.origin, "include");
        let (line, column) = position_of(LIBRARY, "\"brass\"");
        assert_eq!(at(&surface.material.defined_at), (library_file, line, column));
        assert_eq!(surface.material.diffuse, [0.7, 0.5, 0.2]);
        let point = &surface.lighting.points[0];
        assert_eq!(point.lights.len(), 2);
        let (line, column) = position_of(SCENE, "Point(position");
        assert_eq!(
            at(&point.lights[1].defined_at),
            (scene_file.clone(), line, column)
        );
        assert_eq!(
            (point.lights[0].kind, point.lights[1].kind),
            ("directional", "point")
        );
        assert!(surface.mesh.triangle < 32 * 32 * 2);

        let right = origin.pick(28, 15).unwrap();
        let surface = &right.surfaces[0];
        assert_eq!(surface.object.name, "right");
        assert_eq!(surface.material.origin, "scene");
        let (line, column) = position_of(SCENE, "\"chalk\": (");
        assert_eq!(
            at(&surface.material.defined_at),
            (scene_file.clone(), line, column)
        );

        let wall = origin.pick(1, 1).unwrap();
        let surface = &wall.surfaces[0];
        assert_eq!(
            (surface.object.index, surface.object.name.as_str()),
            (2, "object 2")
        );
        assert_eq!(surface.material.name.as_deref(), Some("pearl"));
        assert_eq!(
            (surface.material.origin, &surface.material.defined_at),
            ("preset", &None)
        );

        let top = origin.pick(20, 4).unwrap();
        let surface = &top.surfaces[0];
        assert_eq!(surface.object.index, 3);
        assert_eq!(surface.material.origin, "inline");
        let (line, column) = position_of(SCENE, "(diffuse: (0, 0, 1))");
        assert_eq!(at(&surface.material.defined_at), (scene_file, line, column));
    }

    #[test]
    fn the_json_has_every_documented_field() {
        let folder = tempfile::tempdir().unwrap();
        let json: serde_json::Value =
            serde_json::from_str(&origin(folder.path()).pick(12, 15).unwrap().to_json()).unwrap();
        for field in [
            "x",
            "y",
            "width",
            "height",
            "samples",
            "scene",
            "background",
            "color",
            "surfaces",
        ] {
            assert!(!json[field].is_null(), "{field}: {json}");
        }
        let surface = &json["surfaces"][0];
        for field in [
            "object",
            "mesh",
            "samples",
            "shading_point",
            "depth",
            "view_distance",
            "position",
            "normal",
            "geometric_normal",
            "back_facing",
            "shading",
            "component",
            "lighting_model",
            "material",
            "texels",
            "lighting",
            "color",
        ] {
            assert!(!surface[field].is_null(), "{field}: {surface}");
        }
        let light = &surface["lighting"]["points"][0]["lights"][0];
        for field in [
            "index",
            "kind",
            "reaches",
            "to_light",
            "n_dot_l",
            "attenuation",
            "spot",
            "shadow",
            "diffuse",
            "specular",
        ] {
            assert!(!light[field].is_null(), "{field}: {light}");
        }
    }

    #[test]
    fn texels_name_their_file_and_the_level_the_mip_bias_chose() {
        let folder = tempfile::tempdir().unwrap();
        let texture = folder.path().join("checker.png");
        image::RgbImage::from_fn(256, 128, |x, y| image::Rgb([((x ^ y) & 8) as u8 * 30, 90, 40]))
            .save(&texture)
            .unwrap();
        // A plane far away: the texture is minified, several levels down.
        let levels_at = |mip_bias: f32| {
            let text = format!(
                "(image: (width: 32, height: 24, mip_bias: {mip_bias}),
                  camera: Perspective(eye: (0, 6, 9), target: (0, 0, 0), up: (0, 1, 0), fov: 30),
                  objects: [(mesh: Plane, scale: 4, material: (texture: \"checker.png\"))])"
            );
            std::fs::write(folder.path().join("scene.ron"), text).unwrap();
            let loaded = load_scene(&folder.path().join("scene.ron"), &LoadOptions::default()).unwrap();
            let origin = ImageOrigin {
                scene: Arc::new(loaded.scene),
                sources: Arc::new(loaded.sources),
                load_options: LoadOptions::default(),
                render_options: RenderOptions::default(),
                encoding: Encoding::Linear,
            };
            let texel = origin.pick(16, 12).unwrap().surfaces[0].texels[0].clone();
            assert_eq!(texel.role, "diffuse");
            assert_eq!(
                texel.file.as_deref().map(std::path::absolute).map(Result::unwrap),
                Some(std::path::absolute(&texture).unwrap())
            );
            assert_eq!(texel.mip_bias, mip_bias);
            // The level the frame's sampler reads, counted here: ⌊λ + bias⌋ in [0, 8] (the
            // chain of a 256-texel-wide texture has 9 levels).
            let lod = texel.level_of_detail + mip_bias;
            let expected = if lod <= 0.0 {
                0
            } else {
                lod.min(8.0).floor() as usize
            };
            assert_eq!(texel.level, expected, "{texel:?}");
            assert_eq!(
                texel.level_size,
                [(256 >> expected).max(1), (128 >> expected).max(1)]
            );
            texel
        };
        let unbiased = levels_at(0.0);
        assert!(unbiased.level_of_detail > 1.0, "minified: {unbiased:?}");
        let biased = levels_at(2.5);
        assert_eq!(biased.level_of_detail, unbiased.level_of_detail);
        assert!(
            biased.level >= unbiased.level + 2,
            "{biased:?} against {unbiased:?}"
        );
        let sharpened = levels_at(-1.0);
        assert!(sharpened.level < unbiased.level, "{sharpened:?}");
    }
}
