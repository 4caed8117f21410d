//! The surface stage: what vertex colours, colour textures and normal maps make of a material
//! at eight points, before they are lit.
//!
//! The general path (`shade::shade_sample`) builds, per Phong pixel, the material the lighting
//! sees: `k_d` times the interpolated vertex colour (`frame::tinted`, in frames with vertex
//! attributes), then `k_d`, and `k_a` when there is no ambient texture, times the diffuse
//! texture's texel, `k_a` times the ambient texture's, and the interpolated normal perturbed by
//! the normal map (`normals::perturb_normal`). Here the same operations run on eight points at
//! once. Each point brings its source triangle's vertices and its weights and those of its
//! neighbours one pixel to the right and one down ([`WeightLanes`], from its raster triangle's
//! edge functions and [`RasterPlane`]), from which the texture coordinates' derivatives
//! follow; the stage gathers the vertex attributes, interpolates them,
//! samples each texture through `texture_lanes::sample_lanes`, and hands the lighting `k_a` and
//! `k_d` per lane ([`SurfaceLanes`]) and the perturbed normals. Flat and Gouraud pixels take
//! only the diffuse texture's modulation from here ([`texture_colors`]).
//!
//! Which of the steps run is decided once per batch of points from the material (all points
//! of a batch share it), never per point.

use glam::Vec3;

use crate::render::frame::{Frame, VertexAttributes};
use crate::render::lanes::{Backend, Floats, LANES, Mask, Native, Vec2s, Vec3s};
use crate::render::raster::Corners;
use crate::render::texture_lanes::sample_lanes;
use crate::scene::{Material, TextureBinding};

/// `k_a` and `k_d` per lane: the material's, modulated by vertex colours and textures.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfaceLanes<B = Native> {
    pub ambient: Vec3s<B>,
    pub diffuse: Vec3s<B>,
}

impl<B: Backend> SurfaceLanes<B> {
    /// `material`'s own coefficients on every lane.
    #[inline(always)]
    pub fn of(material: &Material) -> Self {
        SurfaceLanes {
            ambient: Vec3s::splat(material.ambient),
            diffuse: Vec3s::splat(material.diffuse),
        }
    }

    /// The same lanes, for backend `C`'s operations.
    #[inline(always)]
    pub fn on<C: Backend>(&self) -> SurfaceLanes<C> {
        SurfaceLanes {
            ambient: self.ambient.on(),
            diffuse: self.diffuse.on(),
        }
    }
}

/// A raster triangle, for interpolating lane-wise at its pixels: how its edge functions change
/// one pixel to the right and one pixel down (exact integers, so a pixel's neighbours have its
/// edge functions plus a step: the texture footprint's points), and its `1/area`, `1/w` and
/// corner weights, which turn edge functions into source weights (`shade::weights_from_edges`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RasterPlane {
    /// One pixel right, one pixel down.
    pub steps: [[i64; 3]; 2],
    pub inv_area: f32,
    pub inv_w: [f32; 3],
    pub corners: Corners,
}

impl Default for RasterPlane {
    fn default() -> Self {
        RasterPlane {
            steps: [[0; 3]; 2],
            inv_area: 0.0,
            inv_w: [0.0; 3],
            corners: Corners::Identity,
        }
    }
}

/// The source weights of eight points (`at`) and of their neighbours one pixel right and one
/// down, one lane array per vertex of their triangles.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WeightLanes<B = Native> {
    pub at: [Floats<B>; 3],
    pub right: [Floats<B>; 3],
    pub down: [Floats<B>; 3],
}

impl<B: Backend> WeightLanes<B> {
    /// `shade::weights_from_edges` at each point, where the edge functions of its raster
    /// triangle `planes[lane]` take the values `edges[lane]`, and at its two neighbours:
    /// lane-wise, `perspective_weights`' operations in its order (from the edge functions
    /// converted to `f32`, its first step), then the corner weights (`Corners::apply`: a swap
    /// of two lane arrays where setup swapped corners, the sum lane by lane where a triangle
    /// was clipped).
    #[inline(always)]
    pub fn of(edges: &[[i64; 3]; LANES], planes: &[&RasterPlane; LANES]) -> Self {
        let inv_area = Floats::gather(planes, |p| p.inv_area);
        let inv_w: [Floats<B>; 3] = std::array::from_fn(|k| Floats::gather(planes, |p| p.inv_w[k]));
        let swapped = Mask::from_bools(std::array::from_fn(|lane| {
            matches!(planes[lane].corners, Corners::Swapped)
        }));
        let clipped = planes.iter().any(|p| matches!(p.corners, Corners::Clipped(_)));
        // The edge functions at each point and its two neighbours, converted to `f32`.
        let mut converted = [[[0.0; LANES]; 3]; 3];
        for (lane, (edges, plane)) in edges.iter().zip(planes).enumerate() {
            for k in 0..3 {
                converted[0][k][lane] = edges[k] as f32;
                converted[1][k][lane] = (edges[k] + plane.steps[0][k]) as f32;
                converted[2][k][lane] = (edges[k] + plane.steps[1][k]) as f32;
            }
        }
        WeightLanes {
            at: source_weights(&converted[0], inv_area, &inv_w, swapped, clipped, planes),
            right: source_weights(&converted[1], inv_area, &inv_w, swapped, clipped, planes),
            down: source_weights(&converted[2], inv_area, &inv_w, swapped, clipped, planes),
        }
    }
}

/// `perspective_weights` lane-wise from edge functions converted to `f32`, then the corner
/// weights (see [`WeightLanes::of`]).
#[inline(always)]
fn source_weights<B: Backend>(
    edges: &[[f32; LANES]; 3],
    inv_area: Floats<B>,
    inv_w: &[Floats<B>; 3],
    swapped: Mask<B>,
    clipped: bool,
    planes: &[&RasterPlane; LANES],
) -> [Floats<B>; 3] {
    let screen = [
        Floats::new(edges[0]) * inv_area,
        Floats::new(edges[1]) * inv_area,
        Floats::new(edges[2]) * inv_area,
    ];
    let over_w = [screen[0] * inv_w[0], screen[1] * inv_w[1], screen[2] * inv_w[2]];
    let sum = over_w[0] + over_w[1] + over_w[2];
    let positive = sum.gt(Floats::splat(0.0));
    let x = positive.select(over_w[0] / sum, screen[0]);
    let y = positive.select(over_w[1] / sum, screen[1]);
    let z = positive.select(over_w[2] / sum, screen[2]);
    let (y, z) = (swapped.select(z, y), swapped.select(y, z));
    if !clipped {
        return [x, y, z];
    }
    let mut lanes = Vec3s { x, y, z }.to_array();
    for (weights, plane) in lanes.iter_mut().zip(planes) {
        if let Corners::Clipped(_) = plane.corners {
            *weights = plane.corners.apply(*weights);
        }
    }
    let lanes = Vec3s::<B>::from_array(&lanes);
    [lanes.x, lanes.y, lanes.z]
}

/// Up to [`LANES`] pixels waiting for the surface stage, each known by where its colour goes
/// and its raster triangle's edge functions there (from which the stage computes its weights
/// and footprint), and its triangle's data `T`, stored once per triangle: the shared queue of
/// the batches that shade varying surfaces (`shade_fast::SurfaceBatch`, and the modulated flat
/// and Gouraud pixels in `shade`). The pixels of a triangle come after [`EdgeQueue::begin`]
/// names it.
#[derive(Default)]
pub struct EdgeQueue<T> {
    len: usize,
    /// Where each pixel's colour goes.
    offsets: [usize; LANES],
    /// Each pixel's raster triangle's edge functions there.
    edges: [[i64; 3]; LANES],
    /// Each pixel's triangle, in `triangles`.
    triangle_of: [u8; LANES],
    /// The triangles of the waiting pixels.
    triangles: [T; LANES],
    triangle_count: usize,
    /// The triangle of the pixels to come, and its entry in `triangles` once one waits.
    current: T,
    current_entry: Option<u8>,
}

impl<T: Copy + Default> EdgeQueue<T> {
    /// Names the triangle the next pixels are of.
    #[inline]
    pub fn begin(&mut self, triangle: T) {
        self.current = triangle;
        self.current_entry = None;
    }

    /// Queues the pixel of the current triangle where its edge functions take the values
    /// `edges`, its colour for `offset`; returns its lane. The caller empties a full queue
    /// ([`EdgeQueue::is_full`]) before the next push.
    #[inline]
    pub fn push(&mut self, edges: [i64; 3], offset: usize) -> usize {
        let entry = match self.current_entry {
            Some(entry) => entry,
            None => {
                self.triangles[self.triangle_count] = self.current;
                self.triangle_count += 1;
                let entry = (self.triangle_count - 1) as u8;
                self.current_entry = Some(entry);
                entry
            }
        };
        let lane = self.len;
        self.offsets[lane] = offset;
        self.edges[lane] = edges;
        self.triangle_of[lane] = entry;
        self.len += 1;
        lane
    }

    #[inline]
    pub fn is_full(&self) -> bool {
        self.len == LANES
    }

    #[inline]
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The waiting pixels, with the lanes past the last one repeating it (their results are
    /// dropped): each lane's edge functions and triangle, and where each waiting pixel's colour
    /// goes (`len` entries). The queue is empty afterwards; the current triangle stays named.
    #[inline]
    pub fn take(&mut self) -> QueuedPixels<'_, T> {
        debug_assert!(!self.is_empty());
        let len = self.len;
        for lane in len..LANES {
            self.edges[lane] = self.edges[len - 1];
            self.triangle_of[lane] = self.triangle_of[len - 1];
        }
        self.len = 0;
        self.triangle_count = 0;
        self.current_entry = None;
        QueuedPixels {
            offsets: &self.offsets[..len],
            edges: &self.edges,
            triangles: std::array::from_fn(|lane| &self.triangles[usize::from(self.triangle_of[lane])]),
        }
    }
}

/// What [`EdgeQueue::take`] hands the stage.
pub struct QueuedPixels<'q, T> {
    pub offsets: &'q [usize],
    pub edges: &'q [[i64; 3]; LANES],
    pub triangles: [&'q T; LANES],
}

/// Whether the surface of `material` varies over a triangle of `frame` (a texture, or vertex
/// colours, which every frame with vertex attributes applies), so that it needs this stage.
#[inline]
pub fn varies(frame: &Frame, material: &Material) -> bool {
    !frame.vertex_attributes.is_empty() || has_texture(material)
}

/// Whether `material` samples a texture.
#[inline]
fn has_texture(material: &Material) -> bool {
    let textures = &material.textures;
    textures.diffuse.is_some() || textures.ambient.is_some() || textures.normal.is_some()
}

/// Eight shading points: per lane its source triangle's vertices, and the weights of the
/// point and its neighbours.
pub struct SurfacePoints<'a, B: Backend = Native> {
    pub vertices: &'a [[u32; 3]; LANES],
    pub weights: &'a WeightLanes<B>,
}

/// A texture's coordinates at eight points, and their changes one pixel right and one down.
#[derive(Clone, Copy)]
struct UvFootprint<B: Backend> {
    at: Vec2s<B>,
    right: Vec2s<B>,
    down: Vec2s<B>,
}

/// What the stage reads of eight points, gathered into lanes as it is first needed: weights,
/// each vertex attribute, each texture coordinate set.
struct Gathered<'a, B: Backend> {
    points: &'a SurfacePoints<'a, B>,
    /// The frame's vertex attributes (empty when no mesh has any: every vertex then has
    /// `VertexAttributes::default()`, as `Frame::attributes` gives).
    attributes: &'a [VertexAttributes],
    /// Per texture coordinate set, once a texture asks for it.
    uvs: [Option<UvFootprint<B>>; 2],
}

impl<'a, B: Backend> Gathered<'a, B> {
    #[inline(always)]
    fn new(frame: &'a Frame, points: &'a SurfacePoints<'a, B>) -> Self {
        Gathered {
            points,
            attributes: &frame.vertex_attributes,
            uvs: [None, None],
        }
    }

    /// The attributes of each point's triangle's vertex `k`.
    #[inline(always)]
    fn vertex(&self, vertices: &[u32; 3], k: usize) -> &VertexAttributes {
        const DEFAULT: &VertexAttributes = &VertexAttributes {
            uv: glam::Vec2::ZERO,
            uv1: glam::Vec2::ZERO,
            tint: Vec3::ONE,
            tangent: glam::Vec4::ZERO,
        };
        self.attributes.get(vertices[k] as usize).unwrap_or(DEFAULT)
    }

    /// `attribute` of each point's triangle's three vertices, one lane array per vertex. A
    /// batch's points come in runs of one triangle: a lane of the previous lane's triangle
    /// copies its values rather than looking its vertices up again.
    #[inline(always)]
    fn corners<V: Copy + Default>(&self, attribute: impl Fn(&VertexAttributes) -> V) -> [[V; LANES]; 3] {
        let vertices = self.points.vertices;
        let mut corners = [[V::default(); LANES]; 3];
        for lane in 0..LANES {
            let same_triangle = lane > 0 && vertices[lane] == vertices[lane - 1];
            for (k, corner) in corners.iter_mut().enumerate() {
                corner[lane] = if same_triangle {
                    corner[lane - 1]
                } else {
                    attribute(self.vertex(&vertices[lane], k))
                };
            }
        }
        corners
    }

    /// A `Vec3` attribute interpolated with `weights`: `a·w₀ + b·w₁ + c·w₂`, as `Vec3`s.
    #[inline(always)]
    fn interpolate3(
        &self,
        weights: &[Floats<B>; 3],
        attribute: impl Fn(&VertexAttributes) -> Vec3,
    ) -> Vec3s<B> {
        let [a, b, c] = self.corners(attribute).map(|corner| Vec3s::from_array(&corner));
        a.scale(weights[0]) + b.scale(weights[1]) + c.scale(weights[2])
    }

    /// The tangents' `w` (the bitangent's handedness) interpolated with `weights`, the fourth
    /// component of the general path's `Vec4` interpolation.
    #[inline(always)]
    fn interpolate_w(&self, weights: &[Floats<B>; 3]) -> Floats<B> {
        let [a, b, c] = self.corners(|vertex| vertex.tangent.w).map(Floats::new);
        a * weights[0] + b * weights[1] + c * weights[2]
    }

    /// The coordinates of set `uv_set` and their footprint (the general path's `uv_at` at the
    /// point and its neighbours, less the point's).
    #[inline(always)]
    fn uv(&mut self, uv_set: u8) -> UvFootprint<B> {
        let set = usize::from(uv_set == 1);
        if let Some(uv) = self.uvs[set] {
            return uv;
        }
        let corners = self
            .corners(|vertex| if set == 1 { vertex.uv1 } else { vertex.uv })
            .map(|corner| Vec2s::from_array(&corner));
        let weights = self.points.weights;
        let uv = interpolate2(&corners, &weights.at);
        let footprint = UvFootprint {
            at: uv,
            right: interpolate2(&corners, &weights.right) - uv,
            down: interpolate2(&corners, &weights.down) - uv,
        };
        self.uvs[set] = Some(footprint);
        footprint
    }

    /// The texel of `binding` at each point (the general path's `sample`), its RGB.
    #[inline(always)]
    fn sample(&mut self, frame: &Frame, binding: &TextureBinding) -> Vec3s<B> {
        let uv = self.uv(binding.uv_set);
        let texels = sample_lanes(
            &frame.textures[binding.texture as usize],
            uv.at,
            uv.right,
            uv.down,
            &binding.sampler,
            frame.mip_bias,
        );
        Vec3s::from_array(&texels.map(|texel| texel.truncate()))
    }
}

/// `a·w₀ + b·w₁ + c·w₂` of the three corners' `Vec2`s.
#[inline(always)]
fn interpolate2<B: Backend>(corners: &[Vec2s<B>; 3], w: &[Floats<B>; 3]) -> Vec2s<B> {
    corners[0].scale(w[0]) + corners[1].scale(w[1]) + corners[2].scale(w[2])
}

/// The surface of `material` at `points` of `frame`, whose interpolated and renormalised
/// (front) normals are `normals`: per lane `k_a` and `k_d`, and the normal after the normal
/// map. Each lane has the bits the general path's material and normal have at its point.
#[inline(always)]
pub fn surface_lanes<B: Backend>(
    frame: &Frame,
    material: &Material,
    points: &SurfacePoints<B>,
    normals: Vec3s<B>,
) -> (SurfaceLanes<B>, Vec3s<B>) {
    let mut surface = SurfaceLanes::of(material);
    if !varies(frame, material) {
        return (surface, normals);
    }
    let mut gathered = Gathered::new(frame, points);
    if !frame.vertex_attributes.is_empty() {
        surface.diffuse = surface.diffuse * gathered.interpolate3(&points.weights.at, |v| v.tint);
    }
    let textures = &material.textures;
    if let Some(binding) = textures.diffuse {
        let texel = gathered.sample(frame, &binding);
        surface.diffuse = surface.diffuse * texel;
        if textures.ambient.is_none() {
            surface.ambient = surface.ambient * texel;
        }
    }
    if let Some(binding) = textures.ambient {
        surface.ambient = surface.ambient * gathered.sample(frame, &binding);
    }
    let normals = match textures.normal {
        Some(binding) => {
            let tangent = gathered.interpolate3(&points.weights.at, |v| v.tangent.truncate());
            let handedness = gathered.interpolate_w(&points.weights.at);
            let texel = gathered.sample(frame, &binding);
            perturb_normal_lanes(normals, tangent, handedness, texel, binding.scale)
        }
        None => normals,
    };
    (surface, normals)
}

/// The diffuse texture's colour (its texel's RGB) at each point: what multiplies the textured
/// part of a flat or Gouraud pixel.
#[inline(always)]
pub fn texture_colors<B: Backend>(
    frame: &Frame,
    binding: &TextureBinding,
    points: &SurfacePoints<B>,
) -> Vec3s<B> {
    Gathered::new(frame, points).sample(frame, binding)
}

/// `normals::perturb_normal` lane-wise: the tangent `tangent` (its `w`, the handedness, apart)
/// made perpendicular to `normal`, the texel mapped from [0, 1] to [−1, 1], and the normal
/// where the tangent is unusable, the texel not finite or the result of no length.
#[inline(always)]
fn perturb_normal_lanes<B: Backend>(
    normal: Vec3s<B>,
    tangent: Vec3s<B>,
    handedness: Floats<B>,
    texel: Vec3s<B>,
    scale: f32,
) -> Vec3s<B> {
    let zero = Floats::splat(0.0);
    let t = (tangent - normal.scale(normal.dot(tangent))).normalize_or_zero();
    let no_tangent = is_zero(t.x).and(is_zero(t.y)).and(is_zero(t.z));
    let finite = texel
        .x
        .is_finite()
        .and(texel.y.is_finite())
        .and(texel.z.is_finite());
    let sign = zero
        .gt(handedness)
        .select(Floats::splat(-1.0), Floats::splat(1.0));
    let bitangent = normal.cross(t).scale(sign);
    let one = Floats::splat(1.0);
    let two = Floats::splat(2.0);
    let mapped = Vec3s {
        x: texel.x * two - one,
        y: texel.y * two - one,
        z: texel.z * two - one,
    };
    let scale = Floats::splat(scale);
    let perturbed = t.scale(mapped.x * scale) + bitangent.scale(mapped.y * scale) + normal.scale(mapped.z);
    // `try_normalize`: times `1 / length` where that is finite and positive.
    let reciprocal = one / perturbed.length();
    let normalizable = reciprocal.is_finite().and(reciprocal.gt(zero));
    let keep = no_tangent.or(!finite).or(!normalizable);
    keep.select3(normal, perturbed.scale(reciprocal))
}

/// `c == 0` per lane, as `c ≤ 0 ∧ 0 ≤ c`.
#[inline(always)]
fn is_zero<B: Backend>(c: Floats<B>) -> Mask<B> {
    let zero = Floats::splat(0.0);
    c.le(zero).and(zero.le(c))
}

#[cfg(test)]
mod tests {
    use glam::Vec4;

    use super::*;
    use crate::render::lanes::{LaneWork, run_widest};
    use crate::render::normals::perturb_normal;

    /// [`perturb_normal_lanes`] of eight points, as lane work.
    #[derive(Clone, Copy)]
    struct Perturb {
        normals: [Vec3; LANES],
        tangents: [Vec4; LANES],
        texels: [Vec3; LANES],
        scale: f32,
    }

    impl LaneWork for Perturb {
        type Output = [Vec3; LANES];

        #[inline(always)]
        fn run<B: Backend>(self) -> [Vec3; LANES] {
            perturb_normal_lanes(
                Vec3s::<B>::from_array(&self.normals),
                Vec3s::from_array(&self.tangents.map(|t| t.truncate())),
                Floats::new(self.tangents.map(|t| t.w)),
                Vec3s::from_array(&self.texels),
                self.scale,
            )
            .to_array()
        }
    }

    /// The normal map's lanes, on the native backend and on the widest, against
    /// `perturb_normal`, bit for bit, on awkward frames:
    /// tangents along the normal, zero, non-finite texels, both handednesses.
    #[test]
    fn perturbed_normals_equal_the_scalar_ones_bit_for_bit() {
        let normals = [
            Vec3::Z,
            Vec3::new(0.6, 0.0, 0.8),
            Vec3::new(-0.48, 0.6, 0.64),
            Vec3::Y,
            Vec3::X,
            Vec3::new(0.0, -0.6, 0.8),
            Vec3::Z,
            Vec3::new(1.0 / 3.0, 2.0 / 3.0, 2.0 / 3.0),
        ];
        let tangents = [
            Vec4::new(1.0, 0.0, 0.0, 1.0),
            Vec4::new(0.0, 1.0, 0.0, -1.0),
            Vec4::new(0.8, 0.6, 0.0, 1.0),
            Vec4::new(0.0, 1.0, 0.0, 1.0),
            Vec4::ZERO,
            Vec4::new(1.0, 0.2, -0.1, -0.5),
            Vec4::new(0.0, 0.0, 2.0, 1.0),
            Vec4::new(0.3, -0.9, 0.1, 0.0),
        ];
        let texels = [
            Vec3::new(0.5, 0.5, 1.0),
            Vec3::new(0.9, 0.2, 0.6),
            Vec3::new(0.0, 1.0, 0.5),
            Vec3::new(0.5, 0.5, 0.5),
            Vec3::new(0.7, 0.3, 0.9),
            Vec3::new(f32::NAN, 0.3, 0.9),
            Vec3::new(0.1, 0.8, 0.2),
            Vec3::new(0.5, 0.5, 0.0),
        ];
        for scale in [1.0, 0.4, -2.0, 0.0] {
            for rotation in 0..LANES {
                let mut t = tangents;
                t.rotate_left(rotation);
                let work = Perturb {
                    normals,
                    tangents: t,
                    texels,
                    scale,
                };
                for (backend, lanes) in [("native", work.run::<Native>()), ("widest", run_widest(work))] {
                    for lane in 0..LANES {
                        let scalar = perturb_normal(normals[lane], t[lane], texels[lane], scale);
                        assert_eq!(
                            lanes[lane].to_array().map(f32::to_bits),
                            scalar.to_array().map(f32::to_bits),
                            "scale {scale}, rotation {rotation}, lane {lane}, {backend} lanes"
                        );
                    }
                }
            }
        }
    }
}
