//! The common case of per-pixel shading, without the general path's branches per pixel.
//!
//! Most pixels of most scenes are Phong-shaded (interpolated normals, lit per pixel) with a
//! Phong or Blinn-Phong material. For those, everything that does not change from pixel to
//! pixel is decided once per triangle ([`FastPhong::new`] returns `None` for anything else, and
//! the general path in `shade` handles it), and the lighting loop is specialised per light kind
//! and model. Textures, vertex colours and normal maps are not the lighting's business: the
//! surface stage (`surface_lanes`) turns them into each lane's `k_a`, `k_d` and normal first
//! ([`SurfaceBatch`], [`FastLighting::light_surface_lanes`]).
//!
//! The arithmetic is the general path's (`lighting::illuminate_with_visibility` followed by the
//! split of `Frame::light_material`), operation for operation and in the same order, so a pixel
//! has the same bits whichever path shaded it; a test holds the two together.
//!
//! Eight points are lit at once ([`FastLighting::light_lanes`]), each scalar step of
//! `lighting::incidence` and `illuminate_with_visibility` becoming the same IEEE operation on
//! every lane (`render::lanes`), and each `continue` a mask:
//!
//! ```text
//! directional  L = to_light                      strength = 1                  every lane
//! point        d = |p_l − p|, L = (p_l − p)/d    strength = att(d)             where 0 < d < ∞
//! spot         as point, c = −(L·D)              strength = spot(c)·att(d)     where 0 < d < ∞
//!                                                                              and not c < cos cutoff
//! att(d)  = 1 / max(k_c + d·(k_l + d·k_q), 1e−6)   the max as a select: NaN gives 1e−6, as f32::max
//! spot(c) = max(c, 0)^e, spec = max(cos, 0)^n      by squaring where the exponent is whole
//!                                                  (`power_by_squaring`: the scalar multiplications
//!                                                  in the scalar order), else `powf` lane by lane
//! lit     = reaches ∧ ¬(N·L ≤ 0 ∨ strength ≤ 0)    outside the cone `incidence` gives strength 0,
//!                                                  so "does not reach" turns the same lanes away
//! shadow  strength ·= S(p, N, L), lit ∧= ¬(strength ≤ 0)   S the map's PCF visibility in
//!                                                  lanes (`shadow_visibility_lanes`), looked up only
//!                                                  where lit, as the general path asks only lights
//!                                                  facing the point
//! ```
//!
//! `powf` has no lane-wise form with the scalar bits, so an exponent that is not a whole number
//! up to `MAX_SQUARED_EXPONENT` (the OpenGL table's shininess 76.8, a spot exponent of 2.5) costs
//! one call per lane that needs it.

use glam::Vec3;

use crate::lighting::{
    MIN_ATTENUATION_DENOMINATOR, ShadingLightKind, incidence, power_by_squaring, reflect, specular_power,
    whole_exponent,
};
use crate::render::frame::{Frame, FrameTriangle, ObjectStyle, Viewer};
use crate::render::lanes::{Floats, LANES, Mask, Vec3s};
use crate::render::shade::renormalize_or_else;
use crate::render::shadow::shadow_visibility_lanes;
use crate::render::surface_lanes::{
    RasterPlane, SurfaceLanes, SurfacePoints, WeightLanes, surface_lanes, varies,
};
use crate::scene::{
    Attenuation, BackFaces, LightingComponent, LightingModel, Material, NormalInterpolation, Shading,
};

/// Eight points lit, split as `Frame::light_material` splits a point's light: the part a
/// colour texture multiplies (ambient and diffuse) and the rest (specular and emission). Their
/// sum is the colour.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LitLanes {
    pub textured: Vec3s,
    pub rest: Vec3s,
}

/// A lighting model the fast path evaluates.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Specular {
    /// `k_s = 0`: no specular term at all.
    None,
    /// `max(R·V, 0)^n`.
    Phong,
    /// `max(N·H, 0)^n`.
    BlinnPhong,
}

/// The lighting of one material on one side of an object, for the fast paths: what does not
/// change from point to point decided once, and the loop specialised per model.
#[derive(Clone, Copy)]
pub struct FastLighting<'f> {
    frame: &'f Frame,
    material: &'f Material,
    specular: Specular,
}

impl<'f> FastLighting<'f> {
    /// The fast lighting of `material` on an object of `style` shaded with `shading`, or `None`
    /// when it needs the general path: a Phong or Blinn-Phong material, all lighting
    /// components, and a side that is lit. Textures and vertex colours are the caller's: it
    /// lights the surface they make ([`FastLighting::light_surface_lanes`]). Only for frames
    /// that [`FastPhong::frame_allows`].
    pub fn new(
        frame: &'f Frame,
        material: u32,
        style: &ObjectStyle,
        shading: Shading,
        back_facing: bool,
    ) -> Option<Self> {
        debug_assert!(FastPhong::frame_allows(frame));
        let material = &frame.materials[material as usize];
        let specular = match material.model {
            _ if material.specular == Vec3::ZERO => Specular::None,
            LightingModel::Phong => Specular::Phong,
            LightingModel::BlinnPhong => Specular::BlinnPhong,
            _ => return None,
        };
        let eligible = style.shading == shading
            && style.component == LightingComponent::All
            && matches!(material.model, LightingModel::Phong | LightingModel::BlinnPhong)
            && !(back_facing && style.back_faces == BackFaces::Unlit);
        eligible.then_some(FastLighting {
            frame,
            material,
            specular,
        })
    }

    /// The material lit.
    #[inline]
    pub fn material(&self) -> &'f Material {
        self.material
    }

    /// Whether `other` lights exactly as `self` does (the same material, so points of both may
    /// share one [`FastLighting::light_lanes`] call).
    #[inline]
    pub fn same_as(&self, other: &FastLighting) -> bool {
        std::ptr::eq(self.material, other.material) && std::ptr::eq(self.frame, other.frame)
    }

    /// The lighting at `position` with the (side) normal `normal`: `Frame::light_material`'s
    /// two parts, summed. The renderer lights through [`FastLighting::light_lanes`]; this
    /// one-point form is the specification the lanes are tested against, operation for operation
    /// the general path's.
    #[inline]
    pub fn light(&self, position: Vec3, normal: Vec3, to_viewer: Vec3) -> Vec3 {
        match self.specular {
            Specular::None => self.light_model::<0>(position, normal, to_viewer),
            Specular::Phong => self.light_model::<1>(position, normal, to_viewer),
            Specular::BlinnPhong => self.light_model::<2>(position, normal, to_viewer),
        }
    }

    /// [`FastLighting::light`] of `LANES` points at once (the viewer's direction computed here),
    /// with the same bits per point as the one-point call; many times faster per point.
    #[inline]
    pub fn light_lanes(&self, positions: &[Vec3; LANES], normals: &[Vec3; LANES]) -> [Vec3; LANES] {
        self.light_lanes_of(Vec3s::from_array(positions), Vec3s::from_array(normals))
    }

    /// [`FastLighting::light_lanes`] of points already in lanes.
    #[inline]
    pub fn light_lanes_of(&self, position: Vec3s, normal: Vec3s) -> [Vec3; LANES] {
        let surface = SurfaceLanes::of(self.material);
        let to_viewer = self.viewer_directions(position);
        let lit = match self.specular {
            Specular::None => self.light_model_lanes::<0>(position, normal, to_viewer, &surface),
            Specular::Phong => self.light_model_lanes::<1>(position, normal, to_viewer, &surface),
            Specular::BlinnPhong => self.light_model_lanes::<2>(position, normal, to_viewer, &surface),
        };
        (lit.textured + lit.rest).to_array()
    }

    /// `Viewer::to_viewer` of each lane's position.
    #[inline(always)]
    fn viewer_directions(&self, position: Vec3s) -> Vec3s {
        match self.frame.viewer {
            Viewer::Local => (-position).normalize_or_zero(),
            Viewer::Infinite { to_viewer } => Vec3s::splat(to_viewer),
        }
    }

    /// The lighting of points whose `k_a` and `k_d` vary from lane to lane (vertex colours,
    /// textures: `surface_lanes`), in `Frame::light_material`'s two parts; each lane has the
    /// bits of the general path's lighting of the material it sees.
    #[inline]
    pub fn light_surface_lanes(&self, position: Vec3s, normal: Vec3s, surface: &SurfaceLanes) -> LitLanes {
        let to_viewer = self.viewer_directions(position);
        match self.specular {
            Specular::None => self.light_model_lanes::<0>(position, normal, to_viewer, surface),
            Specular::Phong => self.light_model_lanes::<1>(position, normal, to_viewer, surface),
            Specular::BlinnPhong => self.light_model_lanes::<2>(position, normal, to_viewer, surface),
        }
    }

    /// [`FastLighting::light_model`] lane by lane: the same operations in the same order, its
    /// `continue`s turned into masks (a masked-off lane keeps its sums untouched, not `+ 0`),
    /// with each lane's own `k_a` and `k_d` (`surface`).
    #[inline(always)]
    fn light_model_lanes<const SPECULAR: u8>(
        &self,
        position: Vec3s,
        normal: Vec3s,
        to_viewer: Vec3s,
        surface: &SurfaceLanes,
    ) -> LitLanes {
        let material = self.material;
        let ambient = surface.ambient * Vec3s::splat(self.frame.ambient_light);
        let mut diffuse = Vec3s::splat(Vec3::ZERO);
        let mut specular = Vec3s::splat(Vec3::ZERO);
        for (index, light) in self.frame.lights.iter().enumerate() {
            let (to_light, strength, reaches) = match light.kind {
                ShadingLightKind::Directional { to_light } => {
                    (Vec3s::splat(to_light), Floats::splat(1.0), Mask::ALL)
                }
                ShadingLightKind::Point {
                    position: light_position,
                    attenuation,
                } => {
                    let (to_light, distance, reaches) =
                        direction_and_distance_lanes(light_position, position);
                    (to_light, attenuate_lanes(attenuation, distance), reaches)
                }
                ShadingLightKind::Spot {
                    position: light_position,
                    axis,
                    cos_cutoff,
                    exponent,
                    attenuation,
                } => {
                    let (to_light, distance, reaches) =
                        direction_and_distance_lanes(light_position, position);
                    let cos_angle = -to_light.dot(Vec3s::splat(axis));
                    // Outside the cone `incidence` gives strength 0, which the `strength <= 0`
                    // test below turns away: the lane does not reach. `cos_cutoff > cos_angle` is
                    // `cos_angle < cos_cutoff`, false for NaN as there.
                    let reaches = reaches.and(!Floats::splat(cos_cutoff).gt(cos_angle));
                    let spot = specular_power_lanes(cos_angle, exponent, reaches);
                    (to_light, spot * attenuate_lanes(attenuation, distance), reaches)
                }
            };
            let n_dot_l = normal.dot(to_light);
            let unlit = n_dot_l.le(Floats::splat(0.0)).or(strength.le(Floats::splat(0.0)));
            let mut lit = reaches.and(!unlit);
            if !lit.any() {
                continue;
            }
            // The shadow term: the map's visibility where the light reaches a lane, asked only
            // there, as the general path asks it only for lights that face the surface; then
            // its `strength <= 0` test, which turns away the lanes in full shadow.
            let map = self.frame.shadows.get(index).and_then(Option::as_deref);
            let strength = strength * shadow_visibility_lanes(map, position, normal, to_light, lit);
            lit = lit.and(!strength.le(Floats::splat(0.0)));
            if !lit.any() {
                continue;
            }
            let color = Vec3s::splat(light.color);
            let irradiance = color.scale(strength).scale(n_dot_l);
            diffuse = lit.select3(diffuse + surface.diffuse * irradiance, diffuse);
            if SPECULAR != 0 {
                let cosine = if SPECULAR == 2 {
                    normal.dot((to_light + to_viewer).normalize_or_zero())
                } else {
                    let reflected = normal.scale(Floats::splat(2.0) * normal.dot(to_light)) - to_light;
                    reflected.dot(to_viewer)
                };
                let intensity = color.scale(strength);
                let power = specular_power_lanes(cosine, material.shininess, lit);
                let added = specular + (Vec3s::splat(material.specular) * intensity).scale(power);
                specular = lit.select3(added, specular);
            }
        }
        LitLanes {
            textured: ambient + diffuse,
            rest: specular + Vec3s::splat(material.emission),
        }
    }

    /// `illuminate_with_visibility` for a Phong or Blinn-Phong material, then
    /// `(ambient + diffuse) + (specular + emission)`. `SPECULAR` is [`Specular`] as a number so
    /// each model gets its own loop. Each light's direction and strength (attenuation, spot
    /// factor) come from the general path's own `incidence`.
    #[inline]
    fn light_model<const SPECULAR: u8>(&self, position: Vec3, normal: Vec3, to_viewer: Vec3) -> Vec3 {
        let material = self.material;
        let ambient = material.ambient * self.frame.ambient_light;
        let mut diffuse = Vec3::ZERO;
        let mut specular = Vec3::ZERO;
        for (index, light) in self.frame.lights.iter().enumerate() {
            let Some((to_light, strength)) = incidence(light, position) else {
                continue;
            };
            let n_dot_l = normal.dot(to_light);
            if n_dot_l <= 0.0 || strength <= 0.0 {
                continue;
            }
            let visibility = match self.frame.shadows.get(index) {
                Some(Some(map)) => map.visibility(position, normal, to_light),
                _ => 1.0,
            };
            let strength = strength * visibility;
            if strength <= 0.0 {
                continue;
            }
            let irradiance = light.color * strength * n_dot_l;
            diffuse += material.diffuse * irradiance;
            if SPECULAR != 0 {
                let cosine = if SPECULAR == 2 {
                    normal.dot((to_light + to_viewer).normalize_or_zero())
                } else {
                    reflect(to_light, normal).dot(to_viewer)
                };
                let intensity = light.color * strength;
                specular += material.specular * intensity * specular_power(cosine, material.shininess);
            }
        }
        (ambient + diffuse) + (specular + material.emission)
    }
}

/// `lighting::direction_and_distance` lane-wise, from the points `position` towards the light at
/// `light_position`: the unit direction, the distance, and where the light has a direction
/// (a distance above 0 and finite; elsewhere the direction is not used).
#[inline(always)]
fn direction_and_distance_lanes(light_position: Vec3, position: Vec3s) -> (Vec3s, Floats, Mask) {
    let offset = Vec3s::splat(light_position) - position;
    let distance = offset.length();
    let reaches = distance.gt(Floats::splat(0.0)).and(distance.is_finite());
    (offset.divide(distance), distance, reaches)
}

/// `lighting::attenuate` lane-wise. Its `f32::max` against a positive constant is "the
/// denominator where it is larger", NaN giving the constant: a compare and a select.
#[inline(always)]
fn attenuate_lanes(attenuation: Attenuation, distance: Floats) -> Floats {
    let Attenuation {
        constant,
        linear,
        quadratic,
    } = attenuation;
    let denominator =
        Floats::splat(constant) + distance * (Floats::splat(linear) + distance * Floats::splat(quadratic));
    let least = Floats::splat(MIN_ATTENUATION_DENOMINATOR);
    Floats::splat(1.0) / denominator.gt(least).select(denominator, least)
}

/// `lighting::specular_power(base, exponent)` lane-wise, for the shininess and the spot
/// exponent: a whole exponent by the same squaring on every lane; another through `powf`, which
/// has no lane-wise form with the same bits, called only for the lanes in `wanted` (the others
/// are masked off by the caller and get 0).
#[inline(always)]
fn specular_power_lanes(base: Floats, exponent: f32, wanted: Mask) -> Floats {
    match whole_exponent(exponent) {
        Some(whole) => power_by_squaring(base.max(Floats::splat(0.0)), Floats::splat(1.0), whole),
        None => Floats(std::array::from_fn(|i| {
            if wanted.lane(i) {
                specular_power(base.0[i], exponent)
            } else {
                0.0
            }
        })),
    }
}

/// One Phong-shaded triangle, ready to shade pixel after pixel.
pub struct FastPhong<'f> {
    lighting: FastLighting<'f>,
    /// Whether vertex colours or textures make the material's `k_a`, `k_d` or normal vary
    /// from point to point (`surface_lanes::varies`).
    varies: bool,
    triangle: &'f FrameTriangle,
    style: &'f ObjectStyle,
    positions: [Vec3; 3],
    normals: [Vec3; 3],
    back_facing: bool,
}

/// Up to [`LANES`] pixels of fast-path Phong triangles with the same lighting, waiting to be lit
/// together by [`FastLighting::light_lanes`]: [`FastPhong::shade`] for each, with the same bits,
/// but the square roots, divisions and lighting done lane-wise. For surfaces that do not vary
/// (else [`SurfaceBatch`]).
#[derive(Default)]
pub struct PhongBatch<'f> {
    lighting: Option<FastLighting<'f>>,
    len: usize,
    /// Where each pixel's colour goes.
    offsets: [usize; LANES],
    positions: [Vec3; LANES],
    /// Interpolated, not yet renormalised.
    normals: [Vec3; LANES],
    triangles: [Option<&'f FrameTriangle>; LANES],
    reversed: [bool; LANES],
}

impl<'f> PhongBatch<'f> {
    /// Queues the pixel with source-triangle weights `weights` of `phong`'s triangle; its
    /// colour goes to `color[offset]` when the batch is lit (when full, when a pixel with other
    /// lighting comes, or on [`PhongBatch::flush`]).
    #[inline]
    pub fn push(&mut self, phong: &FastPhong<'f>, weights: Vec3, offset: usize, color: &mut [Vec3]) {
        debug_assert!(!phong.varies());
        if let Some(lighting) = self.lighting
            && !lighting.same_as(&phong.lighting)
        {
            self.flush(color);
        }
        self.lighting = Some(phong.lighting);
        let lane = self.len;
        let interpolate = |[a, b, c]: [Vec3; 3]| a * weights.x + b * weights.y + c * weights.z;
        self.offsets[lane] = offset;
        self.positions[lane] = interpolate(phong.positions);
        self.normals[lane] = interpolate(phong.normals);
        self.triangles[lane] = Some(phong.triangle);
        self.reversed[lane] = phong.style.reverses_normal(phong.back_facing);
        self.len += 1;
        if self.len == LANES {
            self.flush(color);
        }
    }

    /// Lights the waiting pixels into `color` and empties the batch.
    pub fn flush(&mut self, color: &mut [Vec3]) {
        let Some(lighting) = self.lighting else {
            return;
        };
        if self.len == 0 {
            return;
        }
        // The lanes past the last pixel repeat it; their results are dropped.
        for lane in self.len..LANES {
            self.positions[lane] = self.positions[self.len - 1];
            self.normals[lane] = self.normals[self.len - 1];
            self.triangles[lane] = self.triangles[self.len - 1];
            self.reversed[lane] = self.reversed[self.len - 1];
        }
        let normals = renormalize_lanes(lighting.frame, Vec3s::from_array(&self.normals), &self.triangles);
        let normals = Mask::from_bools(self.reversed)
            .select3(-normals, normals)
            .to_array();
        let lit = lighting.light_lanes(&self.positions, &normals);
        for (&offset, &lit) in self.offsets[..self.len].iter().zip(&lit) {
            color[offset] = lit;
        }
        self.len = 0;
    }
}

/// `renormalize_or_else` lane-wise: `v / |v|` where `|v|² > 1e-12`, else the face normal of the
/// lane's triangle.
#[inline(always)]
fn renormalize_lanes(
    frame: &Frame,
    interpolated: Vec3s,
    triangles: &[Option<&FrameTriangle>; LANES],
) -> Vec3s {
    let length_squared = interpolated.dot(interpolated);
    let usable = length_squared.gt(Floats::splat(1e-12));
    let mut normals = interpolated.divide(length_squared.sqrt()).to_array();
    for (lane, (normal, triangle)) in normals.iter_mut().zip(triangles).enumerate() {
        if !usable.lane(lane) {
            *normal = frame.face_normal(triangle.expect("every lane holds a pixel"));
        }
    }
    Vec3s::from_array(&normals)
}

/// Up to [`LANES`] pixels of fast-path Phong triangles whose surface varies (textures, vertex
/// colours, normal maps) with the same lighting, waiting to be shaded together: each pixel's
/// edge functions and triangle, from which its weights, position and normal are interpolated
/// lane-wise, then the surface stage (`surface_lanes`) and the lighting
/// ([`FastLighting::light_surface_lanes`]). Each pixel gets the bits `shade::shade_sample`
/// gives it. The pixels of a triangle come after [`SurfaceBatch::begin`] names it.
#[derive(Default)]
pub struct SurfaceBatch<'f> {
    lighting: Option<FastLighting<'f>>,
    len: usize,
    /// Where each pixel's colour goes.
    offsets: [usize; LANES],
    /// Each pixel's raster triangle's edge functions there.
    edges: [[i64; 3]; LANES],
    /// Each pixel's triangle, in `triangles`.
    triangle_of: [u8; LANES],
    /// The triangles of the waiting pixels.
    triangles: [SurfaceTriangle<'f>; LANES],
    triangle_count: usize,
    /// The triangle of the pixels to come, and its entry in `triangles` once one waits.
    current: SurfaceTriangle<'f>,
    current_entry: Option<u8>,
}

/// `FastPhong::shade`'s interpolation, lane-wise: per lane the `corner`s of its triangle
/// weighted by `weights`.
#[inline(always)]
fn interpolate_corners<T>(
    triangles: &[&T; LANES],
    weights: &[Floats; 3],
    corner: impl Fn(&T, usize) -> Vec3,
) -> Vec3s {
    let at = |k: usize| Vec3s::gather(triangles, |triangle| corner(triangle, k));
    at(0).scale(weights[0]) + at(1).scale(weights[1]) + at(2).scale(weights[2])
}

/// A triangle of a [`SurfaceBatch`]'s pixels: what their interpolation reads of it.
#[derive(Clone, Copy, Default)]
struct SurfaceTriangle<'f> {
    triangle: Option<&'f FrameTriangle>,
    plane: RasterPlane,
    positions: [Vec3; 3],
    normals: [Vec3; 3],
    /// Whether the lit side's normal is the reversed one (`ObjectStyle::reverses_normal`).
    reversed: bool,
}

impl<'f> SurfaceBatch<'f> {
    /// Names the triangle the next pixels are of: `phong`'s, whose raster triangle is `plane`
    /// (flushing the waiting pixels into `color` first if it lights otherwise).
    #[inline]
    pub fn begin(&mut self, phong: &FastPhong<'f>, plane: RasterPlane, color: &mut [Vec3]) {
        if let Some(lighting) = self.lighting
            && !lighting.same_as(&phong.lighting)
        {
            self.flush(color);
        }
        self.lighting = Some(phong.lighting);
        self.current = SurfaceTriangle {
            triangle: Some(phong.triangle),
            plane,
            positions: phong.positions,
            normals: phong.normals,
            reversed: phong.style.reverses_normal(phong.back_facing),
        };
        self.current_entry = None;
    }

    /// Queues the pixel of the current triangle where its edge functions take the values
    /// `edges`; its colour goes to `color[offset]` when the batch is shaded (when full, when a
    /// triangle with other lighting begins, or on [`SurfaceBatch::flush`]).
    #[inline]
    pub fn push(&mut self, edges: [i64; 3], offset: usize, color: &mut [Vec3]) {
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
        if self.len == LANES {
            self.flush(color);
        }
    }

    /// Shades the waiting pixels into `color` and empties the batch.
    pub fn flush(&mut self, color: &mut [Vec3]) {
        let Some(lighting) = self.lighting else {
            return;
        };
        if self.len == 0 {
            return;
        }
        // The lanes past the last pixel repeat it; their results are dropped.
        for lane in self.len..LANES {
            self.edges[lane] = self.edges[self.len - 1];
            self.triangle_of[lane] = self.triangle_of[self.len - 1];
        }
        let frame = lighting.frame;
        let triangles: [&SurfaceTriangle; LANES] =
            std::array::from_fn(|lane| &self.triangles[usize::from(self.triangle_of[lane])]);
        let weights = WeightLanes::of(&self.edges, &triangles.map(|triangle| &triangle.plane));
        let frame_triangles = triangles.map(|triangle| triangle.triangle);
        let vertices = frame_triangles.map(|triangle| triangle.expect("every lane holds a pixel").vertices);
        let positions = interpolate_corners(&triangles, &weights.at, |triangle, k| triangle.positions[k]);
        let normals = interpolate_corners(&triangles, &weights.at, |triangle, k| triangle.normals[k]);
        let normals = renormalize_lanes(frame, normals, &frame_triangles);
        // The normal map perturbs the front normal, before the side is chosen.
        let points = SurfacePoints {
            vertices: &vertices,
            weights: &weights,
        };
        let (surface, normals) = surface_lanes(frame, lighting.material, &points, normals);
        let reversed = Mask::from_bools(triangles.map(|triangle| triangle.reversed));
        let normals = reversed.select3(-normals, normals);
        let lit = lighting.light_surface_lanes(positions, normals, &surface);
        let lit = (lit.textured + lit.rest).to_array();
        for (&offset, &lit) in self.offsets[..self.len].iter().zip(&lit) {
            color[offset] = lit;
        }
        self.len = 0;
        self.triangle_count = 0;
        self.current_entry = None;
    }
}

impl<'f> FastPhong<'f> {
    /// Whether any triangle of `frame` may take the fast path: no debug view. Every light
    /// kind, shadowed or not, is lit in lanes, and textures, vertex colours and normal maps
    /// applied in lanes. Asked once per tile.
    pub fn frame_allows(frame: &Frame) -> bool {
        frame.debug_view.is_none()
    }

    /// The fast path for `triangle` seen from the front or the back, or `None` when it needs the
    /// general path: another shading mode or model, Slerp, or a single lighting component (see
    /// [`FastLighting::new`]). Only for frames that [`FastPhong::frame_allows`].
    pub fn new(frame: &'f Frame, triangle: &'f FrameTriangle, back_facing: bool) -> Option<Self> {
        let style = &frame.objects[triangle.object as usize];
        if style.normal_interpolation != NormalInterpolation::Nlerp {
            return None;
        }
        let lighting = FastLighting::new(frame, triangle.material, style, Shading::Phong, back_facing)?;
        let vertices = triangle.vertices.map(|v| &frame.vertices[v as usize]);
        Some(FastPhong {
            lighting,
            varies: varies(frame, lighting.material),
            triangle,
            style,
            positions: vertices.map(|v| v.position),
            normals: vertices.map(|v| v.normal),
            back_facing,
        })
    }

    /// Whether vertex colours or textures make the triangle's surface vary: its pixels are
    /// shaded through a [`SurfaceBatch`], not a [`PhongBatch`].
    #[inline]
    pub fn varies(&self) -> bool {
        self.varies
    }

    /// The colour at the point with source-triangle weights `weights`: what [`PhongBatch`]
    /// computes for each pixel it queues (the renderer shades through the batch; tests hold the
    /// two, and this and the general path, together bit for bit). For a surface that does not
    /// vary (no texture, no vertex colours; tests hold the batches of the others to the general
    /// path).
    #[inline]
    pub fn shade(&self, weights: Vec3) -> Vec3 {
        let frame = self.lighting.frame;
        debug_assert!(!self.varies);
        let interpolate = |[a, b, c]: [Vec3; 3]| a * weights.x + b * weights.y + c * weights.z;
        let position = interpolate(self.positions);
        let normal = renormalize_or_else(interpolate(self.normals), || frame.face_normal(self.triangle));
        let normal = self.style.side_normal(normal, self.back_facing);
        self.lighting
            .light(position, normal, frame.viewer.to_viewer(position))
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use std::sync::Arc;

    use glam::{DVec3, Vec2, Vec4};

    use super::*;
    use crate::mesh::primitives;
    use crate::render::frame::{has_color_texture, tinted};
    use crate::render::raster::SamplePattern;
    use crate::render::{RenderOptions, geometry::build_frame, render};
    use crate::scene::{
        Attenuation, Camera, ImageSettings, Light, Object, Projection, Scene, ShadowSettings, TextureBinding,
    };
    use crate::texture::{Sampler, Texture, Wrap};

    /// The lightings the fast path specialises: Phong, Blinn-Phong, and no specular term.
    const MODELS: [(LightingModel, Vec3); 3] = [
        (LightingModel::Phong, Vec3::splat(0.7)),
        (LightingModel::BlinnPhong, Vec3::splat(0.7)),
        (LightingModel::Phong, Vec3::ZERO),
    ];

    /// The light sets the fast path is held to the general path under.
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    pub(crate) enum Lights {
        /// A directional light and an attenuated point light.
        DirectionalAndPoint,
        /// A directional light and two attenuated spot lights, each with its cone's edge across
        /// one sphere: one with a whole exponent (squared lane-wise), one with a fractional
        /// exponent (`powf`).
        DirectionalAndSpots,
        /// A directional light and a spot light that both cast shadows (3×3 PCF), the right
        /// sphere shadowing the left one's side for each: points in full shadow, on the
        /// filtered edge and in light.
        Shadowed,
    }

    pub(crate) const LIGHTS: [Lights; 3] = [
        Lights::DirectionalAndPoint,
        Lights::DirectionalAndSpots,
        Lights::Shadowed,
    ];

    /// The frame of `scene` with its shadow maps, as `render` builds it.
    pub(crate) fn frame_of(scene: &Scene, view: Option<crate::render::DebugView>) -> Frame {
        frame_sampled(scene, SamplePattern::SINGLE, view)
    }

    /// [`frame_of`] with `pattern`'s samples per pixel.
    pub(crate) fn frame_sampled(
        scene: &Scene,
        pattern: SamplePattern,
        view: Option<crate::render::DebugView>,
    ) -> Frame {
        let shadows = crate::render::shadow::render_shadow_maps(
            scene,
            scene.camera.eye,
            &mut Default::default(),
            &mut Default::default(),
        );
        build_frame(scene, pattern, view, shadows)
    }

    /// How many of `points` (position, side normal) each shadow-casting light of `frame` leaves
    /// in full shadow, in part (the filtered edge) and in full light among those facing it,
    /// asserting the first and last are at least `least` and the edge (a thin band, so few of
    /// the sampled points) at least `least / 4`: a comparison over those points then covers
    /// every branch of the shadow term.
    fn assert_shadows_cross(frame: &Frame, points: &[(Vec3, Vec3)], least: usize) {
        let mut count = 0;
        for (light, map) in frame.lights.iter().zip(&frame.shadows) {
            let Some(map) = map else { continue };
            let (mut dark, mut edge, mut lit) = (0, 0, 0);
            for &(position, normal) in points {
                if let Some((to_light, strength)) = incidence(light, position)
                    && normal.dot(to_light) > 0.0
                    && strength > 0.0
                {
                    match map.visibility(position, normal, to_light) {
                        v if v <= 0.0 => dark += 1,
                        v if v >= 1.0 => lit += 1,
                        _ => edge += 1,
                    }
                }
            }
            assert!(
                dark >= least && edge >= least / 4 && lit >= least,
                "{light:?}: {dark} in shadow, {edge} on the edge, {lit} lit"
            );
            count += 1;
        }
        assert_eq!(count, 2, "two shadow-casting lights");
    }

    /// How many of `points` (position, side normal) each spot light of `frame` lights, and how
    /// many its cone leaves dark though they face it, asserting both are at least `least`: a
    /// comparison of the fast and general paths over those points then covers the inside of
    /// each cone, its edge and its outside.
    fn assert_cones_cross(frame: &Frame, points: &[(Vec3, Vec3)], least: usize) {
        let spots = frame
            .lights
            .iter()
            .filter(|light| matches!(light.kind, ShadingLightKind::Spot { .. }));
        let mut count = 0;
        for light in spots {
            let (mut inside, mut outside) = (0, 0);
            for &(position, normal) in points {
                if let Some((to_light, strength)) = incidence(light, position)
                    && normal.dot(to_light) > 0.0
                {
                    if strength > 0.0 {
                        inside += 1;
                    } else {
                        outside += 1;
                    }
                }
            }
            assert!(
                inside >= least && outside >= least,
                "{light:?}: {inside} points lit, {outside} outside the cone"
            );
            count += 1;
        }
        assert_eq!(count, 2, "two spot lights");
    }

    /// The frame triangles that reached the rasterizer, each once, in submission order.
    fn frame_triangles(frame: &Frame) -> Vec<FrameTriangle> {
        let mut seen = std::collections::HashSet::new();
        frame
            .raster_triangles()
            .filter(|raster| seen.insert(raster.source))
            .map(|raster| raster.triangle)
            .collect()
    }

    const SHADOW: ShadowSettings = ShadowSettings {
        resolution: 512,
        bias: 1.0,
        filter_radius: 1,
    };

    pub(crate) fn scene(
        model: LightingModel,
        specular: Vec3,
        back_faces: BackFaces,
        lights: Lights,
    ) -> Scene {
        let material = Material {
            ambient: Vec3::new(0.1, 0.05, 0.0),
            diffuse: Vec3::new(0.6, 0.3, 0.2),
            specular,
            shininess: 17.0,
            emission: Vec3::new(0.01, 0.02, 0.03),
            model,
            textures: Default::default(),
        };
        let sphere = Arc::new(primitives::sphere(24));
        let object = |x: f64| Object {
            name: "sphere".into(),
            mesh: sphere.clone(),
            transform: glam::DMat4::from_translation(DVec3::new(x, 0.0, 0.0)),
            shading: Shading::Phong,
            material: Some(material),
            back_faces,
            component: LightingComponent::All,
            normal_interpolation: NormalInterpolation::Nlerp,
        };
        Scene {
            image: ImageSettings {
                width: 96,
                height: 64,
                background: Vec3::ZERO,
                samples: 1,
            },
            camera: Camera {
                eye: DVec3::new(0.5, -5.0, 1.5),
                target: DVec3::ZERO,
                up: DVec3::Z,
                projection: Projection::Perspective {
                    fov_y_degrees: 40.0,
                    near: 0.1,
                    far: 100.0,
                },
            },
            ambient_light: Vec3::splat(0.5),
            lights: match lights {
                Lights::DirectionalAndPoint => vec![
                    Light::Directional {
                        direction: Vec3::new(-1.0, 1.0, -1.0).normalize(),
                        color: Vec3::new(1.0, 0.9, 0.8),
                        shadow: None,
                    },
                    Light::Point {
                        position: DVec3::new(1.0, -3.0, 2.0),
                        color: Vec3::ONE,
                        attenuation: Attenuation {
                            constant: 1.0,
                            linear: 0.1,
                            quadratic: 0.05,
                        },
                        shadow: None,
                    },
                ],
                Lights::DirectionalAndSpots => vec![
                    Light::Directional {
                        direction: Vec3::new(-1.0, 1.0, -1.0).normalize(),
                        color: Vec3::new(1.0, 0.9, 0.8),
                        shadow: None,
                    },
                    // Aimed at the left sphere's front from the right, 4 units away: the
                    // sphere spans 14° from the axis, the cone 9°.
                    Light::Spot {
                        position: DVec3::new(1.0, -3.0, 2.0),
                        direction: Vec3::new(-2.2, 3.0, -1.8).normalize(),
                        color: Vec3::ONE,
                        cutoff_degrees: 9.0,
                        exponent: 2.0,
                        attenuation: Attenuation {
                            constant: 1.0,
                            linear: 0.1,
                            quadratic: 0.05,
                        },
                        shadow: None,
                    },
                    // At the right sphere from below and the left.
                    Light::Spot {
                        position: DVec3::new(-0.5, -3.5, -1.0),
                        direction: Vec3::new(1.7, 3.5, 1.3).normalize(),
                        color: Vec3::new(0.9, 1.0, 0.7),
                        cutoff_degrees: 10.0,
                        exponent: 7.5,
                        attenuation: Attenuation {
                            constant: 0.5,
                            linear: 0.2,
                            quadratic: 0.0,
                        },
                        shadow: None,
                    },
                ],
                Lights::Shadowed => vec![
                    // From the right and a little above: the right sphere's shadow falls on
                    // the left one's right side.
                    Light::Directional {
                        direction: Vec3::new(-1.0, 0.15, -0.25).normalize(),
                        color: Vec3::new(1.0, 0.9, 0.8),
                        shadow: Some(SHADOW),
                    },
                    Light::Spot {
                        position: DVec3::new(4.0, -1.5, 0.8),
                        direction: Vec3::new(-5.2, 1.5, -0.8).normalize(),
                        color: Vec3::new(0.9, 1.0, 0.7),
                        cutoff_degrees: 25.0,
                        exponent: 2.0,
                        attenuation: Attenuation {
                            constant: 1.0,
                            linear: 0.1,
                            quadratic: 0.0,
                        },
                        shadow: Some(SHADOW),
                    },
                ],
            },
            objects: vec![object(-1.2), object(1.2)],
            textures: Vec::new(),
        }
    }

    /// What varies the surface of the two spheres of [`scene`] (made so by [`vary_surfaces`]).
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    pub(crate) enum Surfaces {
        /// Vertex colours (glTF `COLOR_0`) on both spheres, no texture.
        Tinted,
        /// The left sphere: a diffuse texture (repeated, minified) and a normal map; the right
        /// one: vertex colours, a diffuse texture of a size that is no power of two (mirrored
        /// and clamped, magnified) and an ambient texture through the second UV set.
        Textured,
        /// The left sphere: only an ambient texture; the right one: only a normal map.
        AmbientOrNormalOnly,
    }

    /// A texture whose every component changes from texel to texel, in [0, 1].
    fn pattern(width: u32, height: u32, seed: f32) -> Arc<Texture> {
        let texels = (0..width * height)
            .map(|i| {
                let (x, y) = ((i % width) as f32, (i / width) as f32);
                let wave = |a: f32, b: f32| 0.5 + 0.5 * (x * a + y * b + seed).sin();
                Vec4::new(wave(0.9, 0.3), wave(-0.4, 1.1), wave(0.2, -0.7), 1.0)
            })
            .collect();
        Arc::new(Texture::from_texels(width, height, texels).unwrap_or_else(|e| panic!("{e}")))
    }

    /// `scene`'s spheres with texture coordinates (two sets), tangents, and the textures and
    /// vertex colours `surfaces` asks for.
    pub(crate) fn vary_surfaces(scene: &mut Scene, surfaces: Surfaces) {
        scene.textures = vec![
            pattern(256, 128, 0.0),
            pattern(37, 23, 1.0),
            pattern(64, 64, 2.0),
            // A normal map: tangent-space normals around +Z.
            pattern(48, 48, 3.0),
        ];
        let binding = |texture: u32, uv_set: u8, wrap: [Wrap; 2], scale: f32| TextureBinding {
            texture,
            uv_set,
            sampler: Sampler {
                wrap_s: wrap[0],
                wrap_t: wrap[1],
            },
            scale,
        };
        let repeat = [Wrap::Repeat, Wrap::Repeat];
        for (index, object) in scene.objects.iter_mut().enumerate() {
            let mut mesh = primitives::textured_sphere(24);
            mesh.uvs1 = mesh.uvs.iter().map(|uv| *uv * 3.7 - Vec2::splat(1.2)).collect();
            let tinted = surfaces == Surfaces::Tinted || (surfaces == Surfaces::Textured && index == 1);
            if tinted {
                mesh.colors = mesh
                    .positions
                    .iter()
                    .map(|p| (p.abs() * 0.6 + Vec3::splat(0.4)).extend(1.0))
                    .collect();
            }
            object.mesh = Arc::new(mesh);
            let textures = &mut object.material.as_mut().expect("a material").textures;
            match (surfaces, index) {
                (Surfaces::Tinted, _) => {}
                (Surfaces::Textured, 0) => {
                    textures.diffuse = Some(binding(0, 0, repeat, 1.0));
                    textures.normal = Some(binding(3, 0, repeat, 0.7));
                }
                (Surfaces::Textured, _) => {
                    textures.diffuse = Some(binding(1, 0, [Wrap::MirroredRepeat, Wrap::ClampToEdge], 1.0));
                    textures.ambient = Some(binding(2, 1, [Wrap::MirroredRepeat, Wrap::Repeat], 1.0));
                }
                (Surfaces::AmbientOrNormalOnly, 0) => textures.ambient = Some(binding(2, 1, repeat, 1.0)),
                (Surfaces::AmbientOrNormalOnly, _) => textures.normal = Some(binding(3, 0, repeat, -1.3)),
            }
        }
    }

    /// Every visible pixel of the fast path's scenes against the general path (`Frame::light`
    /// with the same interpolated normal), bit for bit, per model and light set.
    #[test]
    fn fast_path_equals_the_general_lighting_bit_for_bit() {
        for ((model, specular), lights) in MODELS.into_iter().flat_map(|m| LIGHTS.map(|l| (m, l))) {
            for back_faces in [BackFaces::ReverseLit, BackFaces::Lit] {
                let scene = scene(model, specular, back_faces, lights);
                let frame = frame_of(&scene, None);
                let mut checked = 0;
                let mut points = Vec::new();
                for triangle in &frame_triangles(&frame) {
                    for back_facing in [false, true] {
                        let fast = FastPhong::new(&frame, triangle, back_facing).expect("eligible");
                        for weights in [Vec3::new(0.2, 0.3, 0.5), Vec3::splat(1.0 / 3.0), Vec3::X] {
                            let [a, b, c] = triangle.vertices.map(|v| frame.vertices[v as usize]);
                            let position =
                                a.position * weights.x + b.position * weights.y + c.position * weights.z;
                            let normal = renormalize_or_else(
                                a.normal * weights.x + b.normal * weights.y + c.normal * weights.z,
                                || frame.face_normal(triangle),
                            );
                            let style = &frame.objects[triangle.object as usize];
                            let general =
                                frame.light(triangle.material, style, position, normal, back_facing);
                            assert_eq!(
                                fast.shade(weights),
                                general,
                                "{model:?} {back_faces:?} {lights:?}"
                            );
                            points.push((position, style.side_normal(normal, back_facing)));
                            checked += 1;
                        }
                    }
                }
                assert!(checked > 1000);
                if lights == Lights::Shadowed {
                    assert_shadows_cross(&frame, &points, 20);
                }
                if lights == Lights::DirectionalAndSpots {
                    assert_cones_cross(&frame, &points, 100);
                }
            }
        }
    }

    /// Eight points lit at once against the one-point lighting, bit for bit, per model, with
    /// both viewers, unlit lanes, reversed normals and a zero normal among them.
    #[test]
    fn lighting_eight_points_at_once_equals_lighting_each_bit_for_bit() {
        // A whole shininess is raised by squaring, lane-wise; another goes through `powf`.
        let shininesses = MODELS.into_iter().flat_map(|m| [(m, 17.0), (m, 17.5)]);
        for (((model, specular), shininess), lights) in shininesses.flat_map(|s| LIGHTS.map(|l| (s, l))) {
            let mut scene = scene(model, specular, BackFaces::ReverseLit, lights);
            for object in &mut scene.objects {
                object.material.as_mut().expect("a material").shininess = shininess;
            }
            let mut frame = frame_of(&scene, None);
            for viewer in [
                frame.viewer,
                crate::render::frame::Viewer::Infinite { to_viewer: Vec3::Z },
            ] {
                frame.viewer = viewer;
                let style = &frame.objects[0];
                let lighting = FastLighting::new(&frame, 0, style, Shading::Phong, false).expect("eligible");
                let mut compared = 0;
                let mut points = Vec::new();
                for (group, vertices) in frame.vertices.chunks_exact(LANES).enumerate() {
                    let positions: [Vec3; LANES] = std::array::from_fn(|i| vertices[i].position);
                    let normals: [Vec3; LANES] = std::array::from_fn(|i| match (group + i) % 5 {
                        0 => -vertices[i].normal,
                        1 if group % 7 == 0 => Vec3::ZERO,
                        _ => vertices[i].normal,
                    });
                    let lit = lighting.light_lanes(&positions, &normals);
                    for i in 0..LANES {
                        let one =
                            lighting.light(positions[i], normals[i], frame.viewer.to_viewer(positions[i]));
                        assert_eq!(
                            lit[i].to_array().map(f32::to_bits),
                            one.to_array().map(f32::to_bits),
                            "{model:?} {lights:?}, point {i} of group {group}"
                        );
                        points.push((positions[i], normals[i]));
                        compared += 1;
                    }
                }
                assert!(compared > 500);
                if lights == Lights::DirectionalAndSpots {
                    assert_cones_cross(&frame, &points, 20);
                }
            }
        }
    }

    /// Pixels lit in batches (of mixed triangles, both objects' lightings, partial batches, and
    /// normals that cancel out so the face normal stands in) against `FastPhong::shade`.
    #[test]
    fn phong_batches_equal_shading_each_pixel_bit_for_bit() {
        let models = [LightingModel::Phong, LightingModel::BlinnPhong];
        for (model, lights) in models.into_iter().flat_map(|m| LIGHTS.map(|l| (m, l))) {
            let scene = scene(model, Vec3::splat(0.7), BackFaces::ReverseLit, lights);
            let frame = frame_of(&scene, None);
            let weights = [
                Vec3::new(0.2, 0.3, 0.5),
                Vec3::splat(1.0 / 3.0),
                Vec3::new(0.5, 0.5, 0.0),
            ];
            let mut expected = Vec::new();
            let mut batch = PhongBatch::default();
            let triangles = frame_triangles(&frame);
            let mut colors = vec![Vec3::splat(-1.0); 3 * triangles.len()];
            let stride = triangles.len() / 13; // visits both objects, alternating runs
            for (n, triangle) in triangles.iter().step_by(stride.max(1)).enumerate() {
                let mut fast = FastPhong::new(&frame, triangle, n % 3 == 0).expect("eligible");
                if n % 4 == 1 {
                    // Opposite vertex normals: halfway between the first two, nothing is left.
                    fast.normals = [Vec3::X, -Vec3::X, Vec3::Y];
                }
                let count = 1 + n % 3;
                for &w in &weights[..count] {
                    batch.push(&fast, w, expected.len(), &mut colors);
                    expected.push(fast.shade(w));
                }
            }
            batch.flush(&mut colors);
            assert!(expected.len() > 20);
            for (i, want) in expected.iter().enumerate() {
                let bits = |v: Vec3| v.to_array().map(f32::to_bits);
                assert_eq!(bits(colors[i]), bits(*want), "{model:?} {lights:?}, pixel {i}");
            }
        }
    }

    /// Gouraud vertex colours, lit by the fast path in the geometry stage, against the general
    /// `Frame::light_material`, bit for bit; and only vertices of rasterized triangles are lit.
    #[test]
    fn gouraud_vertices_lit_by_the_fast_path_equal_the_general_lighting_bit_for_bit() {
        let surfaces = [None, Some(Surfaces::Tinted), Some(Surfaces::Textured)];
        for (((model, specular), lights), surfaces) in MODELS
            .into_iter()
            .flat_map(|m| LIGHTS.map(|l| (m, l)))
            .flat_map(|c| surfaces.map(|s| (c, s)))
        {
            let mut scene = scene(model, specular, BackFaces::ReverseLit, lights);
            if let Some(surfaces) = surfaces {
                vary_surfaces(&mut scene, surfaces);
            }
            for object in &mut scene.objects {
                object.shading = Shading::Gouraud;
            }
            let frame = frame_of(&scene, None);
            assert!(FastPhong::frame_allows(&frame));
            let mut lit = 0;
            let mut points = Vec::new();
            for triangle in &frame_triangles(&frame) {
                for v in triangle.vertices {
                    let color = frame.vertex_colors[v as usize];
                    if color == Vec3::ZERO {
                        continue; // a vertex only hidden back faces use: never lit, never read
                    }
                    let vertex = frame.vertices[v as usize];
                    let style = &frame.objects[triangle.object as usize];
                    // The mesh's vertex colour (white, which changes no bit, where it has
                    // none) multiplies `k_d`; a colour texture's part is kept apart.
                    let material = tinted(
                        &frame.materials[triangle.material as usize],
                        frame.attributes(v).tint,
                    );
                    let (textured, rest) =
                        frame.light_material(&material, style, vertex.position, vertex.normal, false);
                    let bits = |v: Vec3| v.to_array().map(f32::to_bits);
                    if has_color_texture(&material) {
                        assert_eq!(bits(color), bits(rest), "{model:?} {lights:?} {surfaces:?}");
                        let textured_part = frame.vertex_colors_textured[v as usize];
                        assert_eq!(bits(textured_part), bits(textured), "{model:?} {lights:?}");
                    } else {
                        assert_eq!(
                            bits(color),
                            bits(textured + rest),
                            "{model:?} {lights:?} {surfaces:?}"
                        );
                    }
                    points.push((vertex.position, vertex.normal));
                    lit += 1;
                }
            }
            assert!(lit > 1000, "{lit}");
            if lights == Lights::DirectionalAndSpots {
                assert_cones_cross(&frame, &points, 20);
            }
            let unlit = frame.vertex_colors.iter().filter(|&&c| c == Vec3::ZERO).count();
            assert!(
                unlit > frame.vertices.len() / 4,
                "hidden back vertices are not lit: {unlit}"
            );
        }
    }

    #[test]
    fn slerp_and_debug_views_take_the_general_path_and_textures_do_not() {
        let mut scene = scene(
            LightingModel::Phong,
            Vec3::ONE,
            BackFaces::ReverseLit,
            Lights::DirectionalAndPoint,
        );
        vary_surfaces(&mut scene, Surfaces::Textured);
        scene.objects[0].normal_interpolation = NormalInterpolation::Slerp;
        let frame = build_frame(&scene, SamplePattern::SINGLE, None, vec![None, None]);
        assert!(FastPhong::frame_allows(&frame));
        let triangles = frame_triangles(&frame);
        let first = &triangles[0];
        assert!(FastPhong::new(&frame, first, false).is_none());
        let last = triangles.last().expect("triangles");
        let textured = FastPhong::new(&frame, last, false).expect("textures take the fast path");
        assert!(textured.varies());
        let debug = build_frame(
            &scene,
            SamplePattern::SINGLE,
            Some(crate::render::DebugView::Specular),
            vec![None, None],
        );
        assert!(!FastPhong::frame_allows(&debug));
        // The whole image is the same either way (the renderer picks per triangle).
        let (image, _) = render(&scene, &RenderOptions::default());
        assert!(image.covered.iter().any(|&c| c));
    }
}
