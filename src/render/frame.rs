//! The frame: what the geometry stage hands to the tiles, and the lighting of a point of it.
//!
//! The geometry stage (`geometry`) builds a [`Frame`] once per image: the vertices in
//! eye-relative world space, the raster triangles binned into tiles, the materials, lights,
//! shadow maps and per-object styles. The tiles (`raster`, `shade`) only read it. The lighting
//! of one surface point of the frame ([`Frame::light_material`]: `lighting` with the frame's
//! lights, shadow maps, viewer, back-face mode and component) lives here, beside the data it
//! reads, so that neither geometry (Gouraud vertices) nor shading (flat triangles, pixels)
//! calls back into the other.

use std::sync::Arc;

use glam::{Vec2, Vec3, Vec4};

use crate::lighting::{LightContribution, LightingTerms, ShadingLight, illuminate_each_light};
use crate::render::DebugView;
use crate::render::bin::{self, RasterChunk, TileGrid};
pub use crate::render::raster::FrameTriangle;
use crate::render::raster::{Corners, RasterTriangle};
use crate::render::shadow::ShadowMap;
use crate::scene::{BackFaces, LightingComponent, Material, NormalInterpolation, Object, Shading};
use crate::texture::Texture;

/// Everything the tiles need to rasterize and shade one frame.
#[derive(Debug, Clone)]
pub struct Frame {
    pub vertices: Vec<FrameVertex>,
    /// Per vertex, the lit colour of Gouraud objects (see [`VertexColors::color`]); empty when
    /// no object is Gouraud-shaded.
    pub vertex_colors: Vec<Vec3>,
    /// Per vertex, [`VertexColors::color_textured`]; empty unless a material has a colour
    /// texture. Apart from `vertex_colors` because it is rarely needed: the common frame
    /// writes, and its tiles read, half the bytes.
    pub vertex_colors_textured: Vec<Vec3>,
    /// Per vertex, texture coordinates, tint and tangent; empty when no mesh has any of them.
    pub vertex_attributes: Vec<VertexAttributes>,
    /// The raster triangles of each chunk of the triangle stream, binned into tiles.
    pub raster: Vec<RasterChunk>,
    pub tiles: TileGrid,
    pub materials: Vec<Material>,
    /// Per material, the colour of constant-shaded objects (unused for the others).
    pub constant_colors: Vec<Vec3>,
    /// Every texture of the frame; the materials' bindings index this.
    pub textures: Vec<Arc<Texture>>,
    /// Added to every texture lookup's level of detail (`ImageSettings::mip_bias`).
    pub mip_bias: f32,
    /// One per scene object; `FrameTriangle::object` indexes this.
    pub objects: Vec<ObjectStyle>,
    pub lights: Vec<ShadingLight>,
    pub ambient_light: Vec3,
    pub viewer: Viewer,
    /// Unit view direction, for the depth view.
    pub forward: Vec3,
    pub debug_view: Option<DebugView>,
    /// Per light, its shadow map (for lights that cast shadows).
    pub shadows: Vec<Option<Arc<ShadowMap>>>,
}

/// A vertex in eye-relative world space (the eye at the origin, world axes).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct FrameVertex {
    pub position: Vec3,
    /// Unit normal, or zero when the mesh gives none usable, or when nothing reads it (objects
    /// shaded flat or constant, depth-only frames, Gouraud vertices no rasterized triangle
    /// uses).
    pub normal: Vec3,
}

/// A Gouraud vertex's lit colour (front side) for the frame's view.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct VertexColors {
    /// Without a colour texture, the whole colour; with one, only the part the texture does
    /// not modulate (specular and emission).
    pub color: Vec3,
    /// With a colour texture: the ambient and diffuse part, which the texture multiplies per
    /// pixel (seeds 000 and 004).
    pub color_textured: Vec3,
}

/// The attributes only textured, tinted or normal-mapped meshes have.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VertexAttributes {
    pub uv: Vec2,
    pub uv1: Vec2,
    /// The mesh's vertex colour (glTF `COLOR_0`), white where there is none: multiplies `k_d`.
    pub tint: Vec3,
    /// Unit tangent (eye-relative world axes) and bitangent handedness, for normal maps.
    pub tangent: Vec4,
}

impl Default for VertexAttributes {
    fn default() -> Self {
        VertexAttributes {
            uv: Vec2::ZERO,
            uv1: Vec2::ZERO,
            tint: Vec3::ONE,
            tangent: Vec4::ZERO,
        }
    }
}

/// How an object is shaded: the settings the shading stage reads per pixel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ObjectStyle {
    pub shading: Shading,
    pub back_faces: BackFaces,
    pub component: LightingComponent,
    pub normal_interpolation: NormalInterpolation,
}

impl ObjectStyle {
    pub(crate) fn of(object: &Object) -> Self {
        ObjectStyle {
            shading: object.shading,
            back_faces: object.back_faces,
            component: object.component,
            normal_interpolation: object.normal_interpolation,
        }
    }

    /// The normal lighting uses on the side being shaded: flipped towards the viewer for back
    /// faces of `ReverseLit` objects, as it is otherwise.
    pub fn side_normal(&self, normal: Vec3, back_facing: bool) -> Vec3 {
        if self.reverses_normal(back_facing) {
            -normal
        } else {
            normal
        }
    }

    /// Whether [`ObjectStyle::side_normal`] flips the normal of a side.
    #[inline]
    pub fn reverses_normal(&self, back_facing: bool) -> bool {
        back_facing && matches!(self.back_faces, BackFaces::ReverseLit | BackFaces::Cull)
    }
}

/// Where the viewer is, for the view vector `V`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Viewer {
    /// Perspective: the eye is at the origin, `V = normalize(−P)`.
    Local,
    /// Orthographic: the viewer is at infinity, `V` is the same everywhere.
    Infinite { to_viewer: Vec3 },
}

impl Viewer {
    pub fn to_viewer(&self, position: Vec3) -> Vec3 {
        match *self {
            Viewer::Local => (-position).normalize_or_zero(),
            Viewer::Infinite { to_viewer } => to_viewer,
        }
    }
}

impl Frame {
    /// The raster triangle with id `id` (as stored in visibility buffers).
    #[inline]
    pub fn raster_triangle(&self, id: u32) -> &RasterTriangle {
        let (chunk, index) = bin::split_raster_id(id);
        &self.raster[chunk].triangles[index]
    }

    /// The corner weights of the raster triangle with id `id` (see `CornerWeights`).
    #[inline]
    pub fn corner_weights(&self, id: u32) -> Corners {
        let (chunk, index) = bin::split_raster_id(id);
        self.raster[chunk].corner_weights(index)
    }

    /// Every raster triangle, in submission order.
    pub fn raster_triangles(&self) -> impl Iterator<Item = &RasterTriangle> {
        self.raster.iter().flat_map(|chunk| &chunk.triangles)
    }

    pub fn raster_triangle_count(&self) -> usize {
        self.raster.iter().map(|chunk| chunk.triangles.len()).sum()
    }

    #[inline]
    pub fn attributes(&self, vertex: u32) -> VertexAttributes {
        self.vertex_attributes
            .get(vertex as usize)
            .copied()
            .unwrap_or_default()
    }

    /// [`VertexColors::color`] of `vertex`: the whole colour for a material without a colour
    /// texture.
    #[inline]
    pub fn color(&self, vertex: u32) -> Vec3 {
        self.vertex_colors
            .get(vertex as usize)
            .copied()
            .unwrap_or(Vec3::ZERO)
    }

    #[inline]
    pub fn colors(&self, vertex: u32) -> VertexColors {
        let at = |colors: &[Vec3]| colors.get(vertex as usize).copied().unwrap_or(Vec3::ZERO);
        VertexColors {
            color: at(&self.vertex_colors),
            color_textured: at(&self.vertex_colors_textured),
        }
    }

    /// Unit geometric normal of the triangle's front side, zero for a degenerate triangle.
    #[inline]
    pub fn face_normal(&self, triangle: &FrameTriangle) -> Vec3 {
        let [p0, p1, p2] = triangle.vertices.map(|v| self.vertices[v as usize].position);
        (p1 - p0).cross(p2 - p0).normalize_or_zero()
    }

    /// A flat-shaded triangle's colour, split into (the part a colour texture multiplies, the
    /// rest): lit once at its centroid with its face normal, on the side the camera sees.
    /// Computed when a pixel first shows the triangle, so hidden triangles cost nothing.
    pub fn flat_colors(&self, triangle: &FrameTriangle, back_facing: bool) -> (Vec3, Vec3) {
        let style = &self.objects[triangle.object as usize];
        let [p0, p1, p2] = triangle.vertices.map(|v| self.vertices[v as usize].position);
        let centroid = (p0 + p1 + p2) / 3.0;
        let material = &self.materials[triangle.material as usize];
        let material = if self.vertex_attributes.is_empty() {
            *material
        } else {
            tinted(material, self.flat_tint(triangle))
        };
        let (textured, rest) = self.light_material(
            &material,
            style,
            centroid,
            self.face_normal(triangle),
            back_facing,
        );
        if has_color_texture(&material) {
            (textured, rest)
        } else {
            (Vec3::ZERO, textured + rest)
        }
    }

    /// The vertex colour of a flat-shaded triangle: its vertices' mean.
    #[inline]
    pub fn flat_tint(&self, triangle: &FrameTriangle) -> Vec3 {
        triangle
            .vertices
            .map(|v| self.attributes(v).tint)
            .iter()
            .sum::<Vec3>()
            / 3.0
    }

    /// Lights a surface point of an object with `style`, on its front or back side, and returns
    /// the colour the frame's view and the object's component ask for. `normal` is the surface's
    /// own (front) normal; the back-face mode decides what the back side uses.
    pub fn light(
        &self,
        material: u32,
        style: &ObjectStyle,
        position: Vec3,
        normal: Vec3,
        back_facing: bool,
    ) -> Vec3 {
        let (textured, rest) = self.light_material(
            &self.materials[material as usize],
            style,
            position,
            normal,
            back_facing,
        );
        textured + rest
    }

    /// Lights with an explicit material (coefficients already modulated by textures and vertex
    /// colours) and returns the selected terms split in two: the ambient and diffuse part, which
    /// a texture multiplies, and the rest (specular and emission).
    pub fn light_material(
        &self,
        material: &Material,
        style: &ObjectStyle,
        position: Vec3,
        normal: Vec3,
        back_facing: bool,
    ) -> (Vec3, Vec3) {
        let lit_side = !(back_facing && style.back_faces == BackFaces::Unlit);
        let normal = style.side_normal(normal, back_facing);
        self.light_side(material, style.component, position, normal, lit_side)
    }

    /// [`Frame::light_material`] on a side already chosen: `normal` is the side's normal (flipped
    /// or not), and the frame's lights reach the side only if `lit_side` (not the back of an
    /// object whose back faces are unlit). The specification the lanes are held to
    /// (`shade_fast::FastLighting`).
    pub fn light_side(
        &self,
        material: &Material,
        component: LightingComponent,
        position: Vec3,
        normal: Vec3,
        lit_side: bool,
    ) -> (Vec3, Vec3) {
        let terms = self.light_side_terms(material, position, normal, lit_side, |_, _| {});
        select_component_split(self.debug_view, component, &terms)
    }

    /// Every term of the lighting [`Frame::light_side`] selects from, handing `each` every
    /// light's part of the sums (`lighting::illuminate_each_light`): the one computation both
    /// the frame and the pixel inspector run.
    #[inline]
    pub fn light_side_terms(
        &self,
        material: &Material,
        position: Vec3,
        normal: Vec3,
        lit_side: bool,
        each: impl FnMut(usize, &LightContribution),
    ) -> LightingTerms {
        illuminate_each_light(
            material,
            if lit_side { &self.lights } else { &[] },
            self.ambient_light,
            position,
            normal,
            self.viewer.to_viewer(position),
            |light, to_light| match self.shadows.get(light) {
                Some(Some(map)) => map.visibility(position, normal, to_light),
                _ => 1.0,
            },
            each,
        )
    }
}

/// The component a pixel shows: the debug view's if one is asked, else the object's.
pub(crate) fn shown_component(view: Option<DebugView>, component: LightingComponent) -> LightingComponent {
    match view {
        Some(DebugView::Ambient) => LightingComponent::Ambient,
        Some(DebugView::Diffuse) => LightingComponent::Diffuse,
        Some(DebugView::Specular) => LightingComponent::Specular,
        None | Some(DebugView::Normals) | Some(DebugView::Depth) => component,
    }
}

/// The terms a pixel shows, split into (ambient + diffuse, specular + emission): the first part
/// is what a colour texture multiplies. Their sum is the pixel's colour.
pub fn select_component_split(
    view: Option<DebugView>,
    component: LightingComponent,
    terms: &LightingTerms,
) -> (Vec3, Vec3) {
    match shown_component(view, component) {
        LightingComponent::All => (terms.ambient + terms.diffuse, terms.specular + terms.emission),
        LightingComponent::Ambient => (terms.ambient, Vec3::ZERO),
        LightingComponent::Diffuse => (terms.diffuse, Vec3::ZERO),
        LightingComponent::Specular => (Vec3::ZERO, terms.specular),
    }
}

/// `material` with its diffuse colour multiplied by a vertex colour (glTF `COLOR_0`).
pub fn tinted(material: &Material, tint: Vec3) -> Material {
    Material {
        diffuse: material.diffuse * tint,
        ..*material
    }
}

/// Whether a texture multiplies the material's ambient or diffuse colour.
pub fn has_color_texture(material: &Material) -> bool {
    material.textures.diffuse.is_some() || material.textures.ambient.is_some()
}
