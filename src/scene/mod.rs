//! The scene: the file format ([`format`]), built-in materials ([`presets`]), and the loader
//! ([`load`]) that turns a RON file into the plain [`Scene`] the renderer draws.
//!
//! Architecture invariant: the types in this file carry no serde derives and no source
//! locations. Everything in a `Scene` has been validated (finite numbers, sizes in range,
//! materials resolved, meshes loaded), so rendering a `Scene` cannot fail.

pub mod access;
pub mod field_docs;
pub mod format;
pub mod limits;
pub mod load;
pub mod locate;
pub mod presets;

use std::sync::Arc;

use glam::{DMat4, DVec3, Vec3};

use crate::mesh::Mesh;

pub use load::{LoadError, LoadOptions, LoadedScene, load_scene, load_scene_from_str};

/// A scene ready to render.
#[derive(Debug, Clone)]
pub struct Scene {
    pub image: ImageSettings,
    pub camera: Camera,
    /// The global ambient light intensity `I_a` (seeds: `k_a·I_a`).
    pub ambient_light: Vec3,
    pub lights: Vec<Light>,
    pub objects: Vec<Object>,
    /// Textures the scene's own materials use (`TextureBinding::texture` indexes this).
    pub textures: Vec<Arc<crate::texture::Texture>>,
}

impl Scene {
    pub fn triangle_count(&self) -> usize {
        self.objects.iter().map(|o| o.mesh.triangle_count()).sum()
    }

    /// Gives every material of every object the lighting model `model` (the command line's
    /// `--model`): the object's own material, the mesh's materials, or the default material.
    /// Cook-Torrance materials asked for Cook-Torrance keep their own parameters (see
    /// [`LightingModel::overridden_by`]). A mesh shared with a cache is copied before its
    /// materials change.
    pub fn override_lighting_model(&mut self, model: LightingModel) {
        for object in &mut self.objects {
            match &mut object.material {
                Some(material) => material.model = material.model.overridden_by(model),
                None if object.mesh.materials.is_empty() => {
                    let material = presets::default_material();
                    object.material = Some(Material {
                        model: material.model.overridden_by(model),
                        ..material
                    });
                }
                None => {
                    let changes = |material: &Material| material.model.overridden_by(model) != material.model;
                    if object.mesh.materials.iter().any(changes) {
                        for material in &mut Arc::make_mut(&mut object.mesh).materials {
                            material.model = material.model.overridden_by(model);
                        }
                    }
                }
            }
        }
    }

    /// Gives every object the shading mode `shading` (the command line's `--shading`).
    pub fn override_shading(&mut self, shading: Shading) {
        for object in &mut self.objects {
            object.shading = shading;
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImageSettings {
    pub width: u32,
    pub height: u32,
    /// Linear RGB of pixels no geometry covers.
    pub background: Vec3,
    /// Samples per pixel (anti-aliasing): 1, 2, 4, 8 or 16.
    pub samples: u32,
    /// Added to every texture lookup's mip level of detail: positive blurs, negative sharpens.
    pub mip_bias: f32,
}

/// A camera in world space. Positions are `f64` so that scenes far from the origin keep
/// their precision: the renderer works relative to `eye`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    pub eye: DVec3,
    pub target: DVec3,
    /// Unit vector, not parallel to `target - eye`.
    pub up: DVec3,
    pub projection: Projection,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Projection {
    Perspective {
        /// Vertical field of view.
        fov_y_degrees: f64,
        near: f64,
        far: f64,
    },
    Orthographic {
        /// Height of the view volume in world units; the width follows the aspect ratio.
        height: f64,
        near: f64,
        far: f64,
    },
}

impl Projection {
    pub fn near_far(&self) -> (f64, f64) {
        match *self {
            Projection::Perspective { near, far, .. } | Projection::Orthographic { near, far, .. } => {
                (near, far)
            }
        }
    }
}

/// Distance attenuation of positional lights: `1 / (constant + linear·d + quadratic·d²)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Attenuation {
    pub constant: f32,
    pub linear: f32,
    pub quadratic: f32,
}

impl Attenuation {
    pub const NONE: Attenuation = Attenuation {
        constant: 1.0,
        linear: 0.0,
        quadratic: 0.0,
    };
}

/// A light in world space (OpenGL semantics, seed 001). `color` is the light's intensity
/// `I_l`, used for both its diffuse and specular contributions. `shadow`, when set, makes the
/// light cast shadows (seed 001's `S_i` term) through a shadow map with those settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Light {
    /// Infinitely far away; `direction` is the unit direction the light travels in.
    Directional {
        direction: Vec3,
        color: Vec3,
        shadow: Option<ShadowSettings>,
    },
    Point {
        position: DVec3,
        color: Vec3,
        attenuation: Attenuation,
        shadow: Option<ShadowSettings>,
    },
    Spot {
        position: DVec3,
        /// Unit direction of the cone's axis (where the spot points).
        direction: Vec3,
        color: Vec3,
        /// Half-angle of the cone, in [0, 90].
        cutoff_degrees: f32,
        /// Falloff `max(-L·D, 0)^exponent` inside the cone.
        exponent: f32,
        attenuation: Attenuation,
        shadow: Option<ShadowSettings>,
    },
}

impl Light {
    pub fn shadow(&self) -> Option<ShadowSettings> {
        match *self {
            Light::Directional { shadow, .. } | Light::Point { shadow, .. } | Light::Spot { shadow, .. } => {
                shadow
            }
        }
    }
}

/// How a light's shadow map is made and read.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShadowSettings {
    /// Texels along each side of the map (of each of the six faces for a point light).
    pub resolution: u32,
    /// Normal-offset bias, in texels: before the depth test the shaded point is moved along its
    /// normal by the filter's reach (`filter_radius + ½` texels, which clears the filter
    /// footprint on any slope) plus this many shadow-map texels (for the tessellation and
    /// rasterization error). This removes shadow acne without the peter-panning of a large
    /// constant depth offset.
    pub bias: f32,
    /// Percentage-closer filtering radius in texels: the test is done on a (2r+1)² block and the
    /// share that is lit is the light's visibility, softening the edge. 0 = a hard edge.
    pub filter_radius: u32,
}

impl ShadowSettings {
    /// Chosen from `report speed-error --knobs` on the Duck scene and the three bundled shadow
    /// scenes (`docs/scene-format.md`, "Shadows"): halving 2048 raises the shadow-edge error
    /// 1.4–1.8× and doubling it costs about 2–8× the time; PCF radius 1
    /// has the lowest FLIP p99 of 0–3; bias ½ lowers FLIP p99 and the shadow-edge error against
    /// 1 on all four without raising any region's error (¼ is lower still on shadow edges but
    /// starts acne on the Duck's texture).
    pub const DEFAULT: ShadowSettings = ShadowSettings {
        resolution: 2048,
        bias: 0.5,
        filter_radius: 1,
    };
}

/// How a surface reflects light: the coefficients of the seeds' Phong equation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Material {
    /// `k_a`, multiplies the global ambient light.
    pub ambient: Vec3,
    /// `k_d`.
    pub diffuse: Vec3,
    /// `k_s`.
    pub specular: Vec3,
    /// `n`, the specular exponent, `>= 0`.
    pub shininess: f32,
    /// `k_e`, added whatever the lights.
    pub emission: Vec3,
    pub model: LightingModel,
    /// Textures that modulate the coefficients (seeds 000 and 004: `k_a` and `k_d`) and perturb
    /// the normal.
    pub textures: MaterialTextures,
}

/// The textures of a material; each multiplies or replaces one input of the lighting.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct MaterialTextures {
    /// Multiplies `k_d` (MTL `map_Kd`, glTF `baseColorTexture`).
    pub diffuse: Option<TextureBinding>,
    /// Multiplies `k_a` (MTL `map_Ka`); when absent, the diffuse texture multiplies `k_a` too.
    pub ambient: Option<TextureBinding>,
    /// A tangent-space normal map (glTF `normalTexture`).
    pub normal: Option<TextureBinding>,
}

/// One texture used by a material: which, through which UV set, sampled how.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TextureBinding {
    /// Index into the texture list of whatever owns the material (`Mesh::textures` for a mesh's
    /// materials, `Scene::textures` for a scene's).
    pub texture: u32,
    /// 0 for `Mesh::uvs`, 1 for `Mesh::uvs1`.
    pub uv_set: u8,
    pub sampler: crate::texture::Sampler,
    /// Normal maps: glTF's `normalTexture.scale`, which scales the map's X and Y. 1 otherwise.
    pub scale: f32,
}

/// The specular term (and whether there is lighting at all).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LightingModel {
    /// `k_s·I_l·max(R·V, 0)^n`, the seeds' Phong model.
    Phong,
    /// `k_s·I_l·max(N·H, 0)^n` with the half vector `H`.
    BlinnPhong,
    /// Ambient and diffuse only.
    Lambert,
    /// No lighting: the diffuse colour plus emission.
    Unlit,
    /// The microfacet model of seed 002: specular `F·D·G / (4(N·V)(N·L))`, diffuse weighted by
    /// `1 − F` (the seed's `k_s + k_d = 1`). See [`crate::lighting`] for the exact terms.
    CookTorrance(Microfacet),
}

impl LightingModel {
    /// The model a material lit by `self` gets when `--model` asks for `requested`: the requested
    /// one, except that a Cook-Torrance material asked for Cook-Torrance keeps its own roughness,
    /// Fresnel and distribution (the request carries only defaults for materials that had none).
    pub fn overridden_by(self, requested: LightingModel) -> LightingModel {
        match (self, requested) {
            (LightingModel::CookTorrance(_), LightingModel::CookTorrance(_)) => self,
            _ => requested,
        }
    }
}

/// The parameters of a Cook-Torrance surface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Microfacet {
    /// Roughness `m`, the RMS slope of the microfacets (Beckmann) or GGX's `α`, in (0, 1].
    pub roughness: f32,
    /// `F0`, the Fresnel reflectance at normal incidence (Schlick's approximation).
    pub fresnel: Vec3,
    pub distribution: MicrofacetDistribution,
}

/// The microfacet normal distribution `D`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum MicrofacetDistribution {
    /// Beckmann's, as Cook and Torrance used (seed 002).
    Beckmann,
    /// Trowbridge-Reitz (GGX), as glTF's metallic-roughness model uses.
    Ggx,
}

/// Where lighting is evaluated (seeds 000, 001, 002).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Shading {
    /// Once per object (seed 001's constant shading): one colour for the whole object, lit at
    /// the centre of its bounds with the normal facing the viewer.
    Constant,
    /// Once per triangle, with the face normal at the centroid.
    Flat,
    /// Once per vertex with the vertex normals; colours interpolated.
    Gouraud,
    /// Normals interpolated and renormalised; lighting per pixel.
    Phong,
}

/// One mesh placed in the world.
#[derive(Debug, Clone)]
pub struct Object {
    pub name: String,
    /// Shared so that a mesh cache (watch mode) can hand the same mesh to several renders.
    pub mesh: Arc<Mesh>,
    /// Model-to-world transform.
    pub transform: DMat4,
    pub shading: Shading,
    /// When set, replaces every material of the mesh; otherwise the mesh's own materials
    /// are used, and [`presets::default_material`] where the mesh has none.
    pub material: Option<Material>,
    pub back_faces: BackFaces,
    /// Which terms of the lighting this object shows.
    pub component: LightingComponent,
    /// How Phong shading interpolates normals.
    pub normal_interpolation: NormalInterpolation,
}

/// What happens to triangles seen from behind (MATLAB's `BackFaceLighting`, seed 002, plus
/// culling).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum BackFaces {
    /// Lit with the normal flipped towards the viewer: two-sided lighting, seed 001's
    /// `BackColor` (MATLAB's default, `reverselit`).
    ReverseLit,
    /// Lit with the normal as it is, pointing away from the viewer (one-sided lighting, as
    /// OpenGL without two-sided lighting): usually dark.
    Lit,
    /// Not lit: ambient and emission only.
    Unlit,
    /// Not drawn (back-face culling).
    Cull,
}

/// The terms of the lighting equation an object shows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum LightingComponent {
    /// Everything: emission, ambient, diffuse and specular.
    All,
    Ambient,
    Diffuse,
    Specular,
}

/// How interpolated normals are formed (seed 000).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum NormalInterpolation {
    /// Interpolate component by component, then renormalise.
    Nlerp,
    /// Spherical linear interpolation: equal angles for equal steps.
    Slerp,
}

/// A sphere containing every object, in world space.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoundingSphere {
    pub center: DVec3,
    pub radius: f64,
}

/// The sphere around the world-space bounding box of `objects` (each mesh's box through its
/// transform); a unit sphere at the origin when there is nothing to bound.
pub fn bounding_sphere(objects: &[Object]) -> BoundingSphere {
    sphere_around_boxes(objects.iter().map(|object| (object, object.mesh.bounds())))
}

/// [`bounding_sphere`] of objects given with their meshes' bounds
/// ([`Mesh::bounds`](crate::mesh::Mesh::bounds)), for a caller that has them already: each is a
/// pass over every vertex of the mesh.
pub fn sphere_around_boxes<'a>(
    objects: impl IntoIterator<Item = (&'a Object, Option<(Vec3, Vec3)>)>,
) -> BoundingSphere {
    let mut lo = DVec3::splat(f64::INFINITY);
    let mut hi = DVec3::splat(f64::NEG_INFINITY);
    for (object, bounds) in objects {
        let Some((min, max)) = bounds else {
            continue;
        };
        for corner in 0..8 {
            let pick = |bit: u32, a: f32, b: f32| f64::from(if corner & bit == 0 { a } else { b });
            let local = DVec3::new(
                pick(1, min.x, max.x),
                pick(2, min.y, max.y),
                pick(4, min.z, max.z),
            );
            let world = object.transform.transform_point3(local);
            lo = lo.min(world);
            hi = hi.max(world);
        }
    }
    if lo.x.is_nan() || lo.x > hi.x {
        return BoundingSphere {
            center: DVec3::ZERO,
            radius: 1.0,
        };
    }
    BoundingSphere {
        center: (lo + hi) / 2.0,
        radius: ((hi - lo).length() / 2.0).max(1e-6),
    }
}
