//! Shading in lanes: pixels, flat triangles and Gouraud vertices, textured or not.
//!
//! What does not change from point to point is decided once per triangle or material, as a
//! choice of stages rather than branches per pixel: the lighting model ([`FastLighting::new`]
//! picks one loop per model), the terms shown (the object's component or the debug view), the
//! side (an unlit back side is one colour), how normals are interpolated (Nlerp or Slerp) and
//! what a pixel shows ([`PixelOutput`]: the lit colour, or the normals or depth debug view).
//! Textures, vertex colours and normal maps are not the lighting's business: the surface stage
//! (`surface_lanes`) turns them into each lane's `k_a`, `k_d` and normal first
//! ([`SurfaceBatch`], [`FastLighting::light_surface_lanes`]), with Nlerp or Slerp normals; a
//! lighting that is one colour (unlit materials, unlit back sides, the ambient term alone) is
//! formed per lane there from each point's own coefficients. Every lit Phong pixel is shaded
//! here; the general path in `shade` is the specification the lanes are tested against.
//!
//! The arithmetic is the general path's (`lighting::illuminate_with_visibility` followed by the
//! split of `Frame::light_side`), operation for operation and in the same order, so a pixel
//! has the same bits whichever path shaded it; tests hold the two together.
//!
//! Eight points are lit at once ([`FastLighting::light_lanes`]), each scalar step of
//! `lighting::incidence` and `illuminate_with_visibility` becoming the same IEEE operation on
//! every lane (`render::lanes`), and each `continue` a mask. The lighting is written once,
//! generic over the lanes' backend, and runs on the widest lanes the processor has
//! (`lanes::run_widest`: 256-bit AVX where it has AVX2), together with the work around it that
//! is large enough to pay for the call: a Phong triangle's rows ([`PhongRows::shade`]:
//! weights, interpolation, renormalisation) and a Phong batch's normals, Slerp included:
//!
//! ```text
//! directional  L = to_light                      strength = 1                  every lane
//! point        d = |p_l − p|, L = (p_l − p)/d    strength = att(d)             where 0 < d < ∞
//! spot         as point, c = −(L·D)              strength = spot(c)·att(d)     where 0 < d < ∞
//!                                                                              and not c < cos cutoff
//! att(d)  = 1 / max(k_c + d·(k_l + d·k_q), 1e−6)   the max as a select: NaN gives 1e−6, as f32::max
//! spot(c) = max(c, 0)^e, spec = max(cos, 0)^n      by squaring where the exponent is whole
//!                                                  (`power_by_squaring`: the scalar multiplications
//!                                                  in the scalar order), else `power::pow`, the
//!                                                  shininess's kind sorted once per material
//! lit     = reaches ∧ ¬(N·L ≤ 0 ∨ strength ≤ 0)    outside the cone `incidence` gives strength 0,
//!                                                  so "does not reach" turns the same lanes away
//! shadow  strength ·= S(p, N, L), lit ∧= ¬(strength ≤ 0)   S the map's PCF visibility in
//!                                                  lanes (`shadow_visibility_lanes`), looked up only
//!                                                  where lit, as the general path asks only lights
//!                                                  facing the point
//! ```
//!
//! Then each model adds its terms where a lane is lit ([`Reflectance`], one implementation per
//! model):
//!
//! ```text
//! Lambert          k_d·I·(N·L)                         (also Phong and Blinn-Phong with k_s = 0)
//! Phong            + k_s·I·max(R·V, 0)^n
//! Blinn-Phong      + k_s·I·max(N·H, 0)^n
//! Cook-Torrance    k_d·(1 − F)·I·(N·L) + π·F·D·G/(4(N·V)(N·L))·I·(N·L)   F by squaring ((1 − V·H)^5
//!                  is `powi(5)`'s multiplications), G as one minimum of three ratios
//!                  (`f32::min` lane by lane), D lane-wise (Beckmann's `exp` is `power::exp`)
//! unlit, or an unlit back side, or the ambient term alone: one colour, lit once (on a
//!                  varying surface: k_d, or k_a·I_a, per lane, with the emission)
//! ```
//!
//! libm's `powf` and `expf` have no lane-wise form, so the specification raises an exponent that
//! is not a whole number up to `MAX_SQUARED_EXPONENT` (the OpenGL table's shininess 76.8, a
//! spot exponent of 2.5), and Beckmann's `exp`, with `power`'s fixed sequences of float
//! operations, which every lane repeats with the same bits.

use std::f32::consts::PI;

use glam::Vec3;

use crate::lighting::{MIN_ATTENUATION_DENOMINATOR, ShadingLightKind, power_by_squaring, whole_exponent};
use crate::render::DebugView;
use crate::render::frame::{Frame, FrameTriangle, ObjectStyle, Viewer, shown_component};
use crate::render::lanes::{Backend, Floats, LANES, LaneWork, Mask, Native, Vec3s, run_widest};
use crate::render::normals::{NormalArc, SMALL_SINE, renormalize_or_else, slerp_triangle_along};
use crate::render::power;
use crate::render::raster::Corners;
use crate::render::shadow::shadow_visibility_lanes;
use crate::render::surface_lanes::{
    EdgeQueue, QueuedPixels, RasterPlane, SurfaceLanes, SurfacePoints, WeightLanes, surface_lanes, varies,
};
use crate::render::trig;
use crate::scene::{
    Attenuation, BackFaces, LightingComponent, LightingModel, Material, Microfacet, MicrofacetDistribution,
    NormalInterpolation, Shading,
};

/// Eight points lit, split as `Frame::light_side` splits a point's light: the part a colour
/// texture multiplies (ambient and diffuse, or the shown terms of them) and the rest (specular
/// and emission). Their sum is the colour.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LitLanes<B = Native> {
    pub textured: Vec3s<B>,
    pub rest: Vec3s<B>,
}

impl<B: Backend> LitLanes<B> {
    /// The same lanes, for backend `C`'s operations.
    #[inline(always)]
    fn on<C: Backend>(self) -> LitLanes<C> {
        LitLanes {
            textured: self.textured.on(),
            rest: self.rest.on(),
        }
    }
}

/// How a material reflects light, as the lanes evaluate it: chosen once per material and side.
#[derive(Debug, Clone, Copy, PartialEq)]
enum LaneModel {
    /// The same colour at every point (`Frame::light_side`'s two parts, computed once): an
    /// unlit material, the back side of an object whose back faces are unlit, or the ambient
    /// term alone, on a surface that does not vary.
    Constant {
        textured: Vec3,
        rest: Vec3,
    },
    /// What `Constant` is, on a surface whose `k_a` and `k_d` vary from point to point (the
    /// surface stage's Phong pixels): formed per lane from each point's own coefficients
    /// ([`FastLighting::one_colour_lanes`]).
    SurfaceConstant,
    /// Lambert's diffuse term alone; also Phong and Blinn-Phong without a specular colour, which
    /// add nothing else.
    Lambert,
    /// With the material's shininess, sorted once.
    Phong(Exponent),
    BlinnPhong(Exponent),
    /// Cook-Torrance with Beckmann's distribution (the material's `Microfacet`).
    Beckmann,
    /// Cook-Torrance with the GGX distribution.
    Ggx,
}

/// The lighting of one material on one side of an object, in lanes: what does not change from
/// point to point decided once, and the loop specialised per model.
#[derive(Clone, Copy)]
pub struct FastLighting<'f> {
    frame: &'f Frame,
    material: &'f Material,
    model: LaneModel,
    /// The terms shown: the debug view's, or else the object's.
    component: LightingComponent,
    /// Whether the frame's lights reach the side (all but unlit back sides).
    lit_side: bool,
}

impl<'f> FastLighting<'f> {
    /// The lighting of `material` on an object of `style` shaded with `shading`, or `None` when
    /// it needs the general path: a lighting that is one colour (an unlit material, an unlit
    /// back side, the ambient term alone) on a surface that varies (`surface_lanes::varies`),
    /// whose colour would differ from point to point. Textures and vertex colours are the
    /// caller's: it lights the surface they make ([`FastLighting::light_surface_lanes`]).
    #[inline]
    pub fn new(
        frame: &'f Frame,
        material: u32,
        style: &ObjectStyle,
        shading: Shading,
        back_facing: bool,
    ) -> Option<Self> {
        let material = &frame.materials[material as usize];
        if style.shading != shading {
            return None;
        }
        let mut lighting = FastLighting {
            frame,
            material,
            model: LaneModel::Lambert,
            component: shown_component(frame.debug_view, style.component),
            lit_side: !(back_facing && style.back_faces == BackFaces::Unlit),
        };
        let one_colour = !lighting.lit_side
            || lighting.component == LightingComponent::Ambient
            || material.model == LightingModel::Unlit;
        if one_colour && varies(frame, material) {
            // Per lane where the points' own coefficients are at hand: the surface stage's
            // Phong pixels. Flat and Gouraud triangles take their colours from
            // `Frame::flat_colors` and the vertices' lighting.
            if shading != Shading::Phong {
                return None;
            }
            lighting.model = LaneModel::SurfaceConstant;
            return Some(lighting);
        }
        lighting.model = match material.model {
            _ if one_colour => lighting.constant(),
            LightingModel::Unlit => lighting.constant(),
            LightingModel::Phong | LightingModel::BlinnPhong if material.specular == Vec3::ZERO => {
                LaneModel::Lambert
            }
            LightingModel::Lambert => LaneModel::Lambert,
            LightingModel::Phong => LaneModel::Phong(Exponent::of(material.shininess)),
            LightingModel::BlinnPhong => LaneModel::BlinnPhong(Exponent::of(material.shininess)),
            LightingModel::CookTorrance(surface) => match surface.distribution {
                MicrofacetDistribution::Beckmann => LaneModel::Beckmann,
                MicrofacetDistribution::Ggx => LaneModel::Ggx,
            },
        };
        Some(lighting)
    }

    /// The material lit.
    #[inline]
    pub fn material(&self) -> &'f Material {
        self.material
    }

    /// The colour where no term shown depends on the point: lit once, anywhere.
    #[cold]
    #[inline(never)]
    fn constant(&self) -> LaneModel {
        let (textured, rest) = self.frame.light_side(
            self.material,
            self.component,
            Vec3::ZERO,
            Vec3::ZERO,
            self.lit_side,
        );
        LaneModel::Constant { textured, rest }
    }

    /// Whether `other` lights exactly as `self` does (the same material, terms and side, which
    /// decide the model, so points of both may share one [`FastLighting::light_lanes`] call).
    #[inline(always)]
    pub fn same_as(&self, other: &FastLighting) -> bool {
        std::ptr::eq(self.material, other.material)
            && std::ptr::eq(self.frame, other.frame)
            && self.component == other.component
            && self.lit_side == other.lit_side
    }

    /// The lighting at `position` with the side's normal `normal`: `Frame::light_side`, the
    /// general path itself. The renderer lights through [`FastLighting::light_lanes`]; this
    /// one-point form is the specification the lanes are tested against.
    pub fn light(&self, position: Vec3, normal: Vec3) -> Vec3 {
        let (textured, rest) =
            self.frame
                .light_side(self.material, self.component, position, normal, self.lit_side);
        textured + rest
    }

    /// [`FastLighting::light`] of `LANES` points at once, with the same bits per point as the
    /// one-point call; many times faster per point.
    #[inline]
    pub fn light_lanes(&self, positions: &[Vec3; LANES], normals: &[Vec3; LANES]) -> [Vec3; LANES] {
        let surface = SurfaceLanes::of(self.material);
        let lit =
            self.light_surface_lanes(Vec3s::from_array(positions), Vec3s::from_array(normals), &surface);
        (lit.textured + lit.rest).to_array()
    }

    /// [`FastLighting::light_lanes`] of points already in lanes of backend `B`, for lane code
    /// already running there.
    #[inline(always)]
    fn light_lanes_on<B: Backend>(&self, position: Vec3s<B>, normal: Vec3s<B>) -> [Vec3; LANES] {
        self.lit_lanes_on(position, normal).to_array()
    }

    /// [`FastLighting::light_lanes_on`], the colours left in lanes.
    #[inline(always)]
    fn lit_lanes_on<B: Backend>(&self, position: Vec3s<B>, normal: Vec3s<B>) -> Vec3s<B> {
        let lit = self.light_surface_lanes_on(position, normal, &SurfaceLanes::of(self.material));
        lit.textured + lit.rest
    }

    /// The lighting of points whose `k_a` and `k_d` may vary from lane to lane (vertex colours,
    /// textures: `surface_lanes`), in `Frame::light_side`'s two parts; each lane has the bits of
    /// the general path's lighting of the material it sees. It runs on the widest lanes the
    /// processor has (`lanes::run_widest`): the lighting is most of a Phong pixel's
    /// arithmetic, and half its instructions go where eight lanes fit one register.
    #[inline]
    pub fn light_surface_lanes(&self, position: Vec3s, normal: Vec3s, surface: &SurfaceLanes) -> LitLanes {
        run_widest(LightingWork {
            lighting: self,
            position,
            normal,
            surface,
        })
    }

    /// [`FastLighting::light_surface_lanes`] on backend `B`.
    #[inline(always)]
    fn light_surface_lanes_on<B: Backend>(
        &self,
        position: Vec3s<B>,
        normal: Vec3s<B>,
        surface: &SurfaceLanes<B>,
    ) -> LitLanes<B> {
        match self.model {
            LaneModel::Constant { textured, rest } => LitLanes {
                textured: Vec3s::splat(textured),
                rest: Vec3s::splat(rest),
            },
            LaneModel::SurfaceConstant => self.one_colour_lanes(surface),
            LaneModel::Lambert => self.light_model_lanes(Lambert, position, normal, surface),
            LaneModel::Phong(Exponent::Whole(n)) => {
                self.light_model_lanes(Phong(Squared(n)), position, normal, surface)
            }
            LaneModel::Phong(Exponent::Other(n)) => {
                self.light_model_lanes(Phong(Fractional(n)), position, normal, surface)
            }
            LaneModel::BlinnPhong(Exponent::Whole(n)) => {
                self.light_model_lanes(BlinnPhong(Squared(n)), position, normal, surface)
            }
            LaneModel::BlinnPhong(Exponent::Other(n)) => {
                self.light_model_lanes(BlinnPhong(Fractional(n)), position, normal, surface)
            }
            LaneModel::Beckmann => {
                let model = CookTorrance::<false>(self.microfacet());
                self.light_model_lanes(model, position, normal, surface)
            }
            LaneModel::Ggx => {
                let model = CookTorrance::<true>(self.microfacet());
                self.light_model_lanes(model, position, normal, surface)
            }
        }
    }

    /// `Frame::light_side` where no term shown depends on the point (an unlit material, an
    /// unlit back side, the ambient term alone), for each lane's own `k_a` and `k_d`: the terms
    /// `illuminate_each_light` forms for an unlit material (`k_d` and the emission) or without
    /// lights (`k_a·I_a` and the emission), split as `select_component_split` splits them. The
    /// light sums are zero: no light reaches an unlit side or material, and the ambient term
    /// alone does not show them.
    #[inline(always)]
    fn one_colour_lanes<B: Backend>(&self, surface: &SurfaceLanes<B>) -> LitLanes<B> {
        let none = Vec3s::splat(Vec3::ZERO);
        let (ambient, diffuse) = if self.material.model == LightingModel::Unlit {
            (none, surface.diffuse)
        } else {
            (surface.ambient * Vec3s::splat(self.frame.ambient_light), none)
        };
        let specular = none;
        let (textured, rest) = match self.component {
            LightingComponent::All => (ambient + diffuse, specular + Vec3s::splat(self.material.emission)),
            LightingComponent::Ambient => (ambient, none),
            LightingComponent::Diffuse => (diffuse, none),
            LightingComponent::Specular => (none, specular),
        };
        LitLanes { textured, rest }
    }

    /// The material's microfacet surface (a Cook-Torrance material's; unused for the others).
    #[inline]
    fn microfacet(&self) -> Microfacet {
        match self.material.model {
            LightingModel::CookTorrance(surface) => surface,
            _ => Microfacet {
                roughness: 1.0,
                fresnel: Vec3::ZERO,
                distribution: MicrofacetDistribution::Ggx,
            },
        }
    }

    /// `illuminate_with_visibility` lane by lane, with `reflectance` the model's terms and each
    /// lane's own `k_a` and `k_d` (`surface`), then the shown terms split as `Frame::light_side`
    /// splits them: the same operations in the same order, its `continue`s turned into masks (a
    /// masked-off lane keeps its sums untouched, not `+ 0`).
    #[inline(always)]
    fn light_model_lanes<B: Backend, R: Reflectance>(
        &self,
        reflectance: R,
        position: Vec3s<B>,
        normal: Vec3s<B>,
        surface: &SurfaceLanes<B>,
    ) -> LitLanes<B> {
        let to_viewer = match self.frame.viewer {
            Viewer::Local => (-position).normalize_or_zero(),
            Viewer::Infinite { to_viewer } => Vec3s::splat(to_viewer),
        };
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
                    let spot = specular_power_lanes(cos_angle, Exponent::of(exponent));
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
            let intensity = Vec3s::splat(light.color).scale(strength);
            let at = LightAtLanes {
                normal,
                to_light,
                to_viewer,
                n_dot_l,
                intensity,
                irradiance: intensity.scale(n_dot_l),
                lit,
            };
            let (diffuse_added, specular_added) = reflectance.reflect(material, surface, &at);
            diffuse = lit.select3(diffuse + diffuse_added, diffuse);
            if R::SPECULAR {
                specular = lit.select3(specular + specular_added, specular);
            }
        }
        let none = Vec3s::splat(Vec3::ZERO);
        // `select_component_split`'s two parts.
        let (textured, rest) = match self.component {
            LightingComponent::All => (ambient + diffuse, specular + Vec3s::splat(material.emission)),
            LightingComponent::Ambient => (ambient, none),
            LightingComponent::Diffuse => (diffuse, none),
            LightingComponent::Specular => (none, specular),
        };
        LitLanes { textured, rest }
    }
}

/// [`FastLighting::light_surface_lanes`]' arguments, for `lanes::run_widest`.
struct LightingWork<'l, 'f> {
    lighting: &'l FastLighting<'f>,
    position: Vec3s,
    normal: Vec3s,
    surface: &'l SurfaceLanes,
}

impl LaneWork for LightingWork<'_, '_> {
    type Output = LitLanes;

    #[inline(always)]
    fn run<B: Backend>(self) -> LitLanes {
        self.lighting
            .light_surface_lanes_on(self.position.on::<B>(), self.normal.on(), &self.surface.on())
            .on()
    }
}

/// The last lighting [`LightingMemo::get`] formed, kept for the next triangle: a tile's
/// triangles come in runs of one object, material and side, and forming a lighting anew costs
/// about as much as interpolating a pixel.
#[derive(Default)]
pub struct LightingMemo<'f> {
    last: Option<(LightingKey, Option<FastLighting<'f>>)>,
}

/// What a [`FastLighting`] depends on: (material, object, shading, back-facing).
type LightingKey = (u32, u32, Shading, bool);

impl<'f> LightingMemo<'f> {
    /// [`FastLighting::new`] for `triangle`'s material and object (of `frame`, the same at
    /// every call).
    #[inline(always)]
    pub fn get(
        &mut self,
        frame: &'f Frame,
        triangle: &FrameTriangle,
        shading: Shading,
        back_facing: bool,
    ) -> Option<FastLighting<'f>> {
        let key = (triangle.material, triangle.object, shading, back_facing);
        match self.last {
            Some((last, lighting)) if last == key => lighting,
            _ => self.form(frame, key),
        }
    }

    #[inline(never)]
    fn form(&mut self, frame: &'f Frame, key: LightingKey) -> Option<FastLighting<'f>> {
        let (material, object, shading, back_facing) = key;
        let style = &frame.objects[object as usize];
        let lighting = FastLighting::new(frame, material, style, shading, back_facing);
        self.last = Some((key, lighting));
        lighting
    }
}

/// One light at eight points, where [`Reflectance::reflect`] reads it.
struct LightAtLanes<B: Backend> {
    /// The side's normal `N`.
    normal: Vec3s<B>,
    /// `L`, towards the light.
    to_light: Vec3s<B>,
    /// `V`, towards the viewer.
    to_viewer: Vec3s<B>,
    n_dot_l: Floats<B>,
    /// The light's colour times its strength (attenuation, spot factor, shadow): `I`.
    intensity: Vec3s<B>,
    /// `I·(N·L)`, as `illuminate_with_visibility` forms it.
    irradiance: Vec3s<B>,
    /// Where the light reaches and faces the point: only these lanes' results are used.
    lit: Mask<B>,
}

/// What a lighting model adds for one light at a lit point: the model's arm of
/// `illuminate_with_visibility`'s loop, lane-wise. One implementation per model, chosen once
/// per material ([`LaneModel`]), so the light loop has no branch on the model.
trait Reflectance: Copy {
    /// Whether the model adds to the specular sum at all.
    const SPECULAR: bool;
    /// (what is added to the diffuse sum, what is added to the specular sum) at each lane.
    fn reflect<B: Backend>(
        self,
        material: &Material,
        surface: &SurfaceLanes<B>,
        light: &LightAtLanes<B>,
    ) -> (Vec3s<B>, Vec3s<B>);
}

/// `k_d·I·(N·L)`.
#[derive(Clone, Copy)]
struct Lambert;

impl Reflectance for Lambert {
    const SPECULAR: bool = false;

    #[inline(always)]
    fn reflect<B: Backend>(
        self,
        _: &Material,
        surface: &SurfaceLanes<B>,
        light: &LightAtLanes<B>,
    ) -> (Vec3s<B>, Vec3s<B>) {
        (surface.diffuse * light.irradiance, Vec3s::splat(Vec3::ZERO))
    }
}

/// Lambert's term and `k_s·I·max(R·V, 0)^n`, `R = 2(N·L)N − L`, with the material's
/// shininess `n`.
#[derive(Clone, Copy)]
struct Phong<P: Power>(P);

impl<P: Power> Reflectance for Phong<P> {
    const SPECULAR: bool = true;

    #[inline(always)]
    fn reflect<B: Backend>(
        self,
        material: &Material,
        surface: &SurfaceLanes<B>,
        light: &LightAtLanes<B>,
    ) -> (Vec3s<B>, Vec3s<B>) {
        let reflected = light.normal.scale(Floats::splat(2.0) * light.n_dot_l) - light.to_light;
        let cosine = reflected.dot(light.to_viewer);
        (
            Lambert.reflect(material, surface, light).0,
            phong_specular_lanes(material, self.0, light, cosine),
        )
    }
}

/// Lambert's term and `k_s·I·max(N·H, 0)^n`, `H = (L + V)/|L + V|`, with the material's
/// shininess `n`.
#[derive(Clone, Copy)]
struct BlinnPhong<P: Power>(P);

impl<P: Power> Reflectance for BlinnPhong<P> {
    const SPECULAR: bool = true;

    #[inline(always)]
    fn reflect<B: Backend>(
        self,
        material: &Material,
        surface: &SurfaceLanes<B>,
        light: &LightAtLanes<B>,
    ) -> (Vec3s<B>, Vec3s<B>) {
        let cosine = light
            .normal
            .dot((light.to_light + light.to_viewer).normalize_or_zero());
        (
            Lambert.reflect(material, surface, light).0,
            phong_specular_lanes(material, self.0, light, cosine),
        )
    }
}

/// `k_s·I·max(cosine, 0)^n`, for the lanes where `light` is lit.
#[inline(always)]
fn phong_specular_lanes<B: Backend>(
    material: &Material,
    shininess: impl Power,
    light: &LightAtLanes<B>,
    cosine: Floats<B>,
) -> Vec3s<B> {
    let power = shininess.raise(cosine.max(Floats::splat(0.0)));
    (Vec3s::splat(material.specular) * light.intensity).scale(power)
}

/// `lighting::cook_torrance` and its use in `illuminate_with_visibility`: the diffuse term
/// weighted by `1 − F`, and the microfacet term; `GGX` picks the distribution.
#[derive(Clone, Copy)]
struct CookTorrance<const GGX: bool>(Microfacet);

impl<const GGX: bool> Reflectance for CookTorrance<GGX> {
    const SPECULAR: bool = true;

    #[inline(always)]
    fn reflect<B: Backend>(
        self,
        _: &Material,
        surface: &SurfaceLanes<B>,
        light: &LightAtLanes<B>,
    ) -> (Vec3s<B>, Vec3s<B>) {
        let (fresnel, specular) = self.reflection(light);
        let diffuse = surface.diffuse * (Vec3s::splat(Vec3::ONE) - fresnel) * light.irradiance;
        (diffuse, specular * light.irradiance)
    }
}

impl<const GGX: bool> CookTorrance<GGX> {
    /// `lighting::cook_torrance`'s `(F, π·F·D·G / (4(N·V)(N·L)))` lane-wise. Its early return
    /// (a viewer, light or half vector below the surface: no microfacet term) is a select.
    #[inline(always)]
    fn reflection<B: Backend>(self, light: &LightAtLanes<B>) -> (Vec3s<B>, Vec3s<B>) {
        let surface = self.0;
        let (zero, one) = (Floats::splat(0.0), Floats::splat(1.0));
        let LightAtLanes {
            normal,
            to_light,
            to_viewer,
            n_dot_l,
            lit,
            ..
        } = *light;
        let half = (to_light + to_viewer).normalize_or_zero();
        let v_dot_h = to_viewer.dot(half).max(zero);
        // `powi(5)` multiplies as binary exponentiation does: x·(x²)².
        let grazing = power_by_squaring(one - v_dot_h, one, 5);
        let fresnel =
            Vec3s::splat(surface.fresnel) + Vec3s::splat(Vec3::ONE - surface.fresnel).scale(grazing);
        let n_dot_v = normal.dot(to_viewer);
        let n_dot_h = normal.dot(half);
        let away = n_dot_v
            .le(zero)
            .or(n_dot_l.le(zero))
            .or(n_dot_h.le(zero))
            .or(v_dot_h.le(zero));
        let reflects = lit.and(!away);
        let distribution = if GGX {
            ggx_lanes(&surface, n_dot_h)
        } else {
            beckmann_lanes(&surface, n_dot_h)
        };
        let two = Floats::splat(2.0);
        let g_over_nv_nl = (one / (n_dot_v * n_dot_l))
            .min(two * n_dot_h / (v_dot_h * n_dot_l))
            .min(two * n_dot_h / (v_dot_h * n_dot_v));
        let factor = Floats::splat(PI) * distribution * g_over_nv_nl / Floats::splat(4.0);
        let specular = reflects.select3(fresnel.scale(factor), Vec3s::splat(Vec3::ZERO));
        (fresnel, specular)
    }
}

/// `lighting::microfacet_distribution` for Beckmann's `exp((cos²α − 1)/(m² cos²α)) / (π m² cos⁴α)`
/// lane-wise, `exp` as `power::exp`.
#[inline(always)]
fn beckmann_lanes<B: Backend>(surface: &Microfacet, n_dot_h: Floats<B>) -> Floats<B> {
    let m2 = surface.roughness * surface.roughness;
    let cos2 = n_dot_h * n_dot_h;
    let exponential = power::exp((cos2 - Floats::splat(1.0)) / (Floats::splat(m2) * cos2));
    let zero = Floats::splat(0.0);
    let distribution = exponential / (Floats::splat(PI * m2) * cos2 * cos2);
    cos2.le(zero).select(zero, distribution)
}

/// `lighting::microfacet_distribution` for GGX's `α² / (π((N·H)²(α² − 1) + 1)²)` lane-wise.
#[inline(always)]
fn ggx_lanes<B: Backend>(surface: &Microfacet, n_dot_h: Floats<B>) -> Floats<B> {
    let m2 = surface.roughness * surface.roughness;
    let cos2 = n_dot_h * n_dot_h;
    let d = cos2 * Floats::splat(m2 - 1.0) + Floats::splat(1.0);
    Floats::splat(m2) / (Floats::splat(PI) * d * d)
}
/// `lighting::direction_and_distance` lane-wise, from the points `position` towards the light at
/// `light_position`: the unit direction, the distance, and where the light has a direction
/// (a distance above 0 and finite; elsewhere the direction is not used).
#[inline(always)]
fn direction_and_distance_lanes<B: Backend>(
    light_position: Vec3,
    position: Vec3s<B>,
) -> (Vec3s<B>, Floats<B>, Mask<B>) {
    let offset = Vec3s::splat(light_position) - position;
    let distance = offset.length();
    let reaches = distance.gt(Floats::splat(0.0)).and(distance.is_finite());
    (offset.divide(distance), distance, reaches)
}

/// `lighting::attenuate` lane-wise. Its `f32::max` against a positive constant is "the
/// denominator where it is larger", NaN giving the constant: a compare and a select.
#[inline(always)]
fn attenuate_lanes<B: Backend>(attenuation: Attenuation, distance: Floats<B>) -> Floats<B> {
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

/// An exponent of `lighting::specular_power`, sorted once (per material for the shininess):
/// whole ones up to `MAX_SQUARED_EXPONENT` are raised by squaring, the others by `power::pow`.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Exponent {
    Whole(u32),
    Other(f32),
}

impl Exponent {
    #[inline(always)]
    fn of(exponent: f32) -> Self {
        match whole_exponent(exponent) {
            Some(whole) => Exponent::Whole(whole),
            None => Exponent::Other(exponent),
        }
    }
}

/// `lighting::specular_power(base, exponent)` lane-wise, for the spot exponent (which may
/// differ from light to light): a whole exponent by the same squaring on every lane, another by
/// the same `power::pow`.
#[inline(always)]
fn specular_power_lanes<B: Backend>(base: Floats<B>, exponent: Exponent) -> Floats<B> {
    let base = base.max(Floats::splat(0.0));
    match exponent {
        Exponent::Whole(whole) => Squared(whole).raise(base),
        Exponent::Other(exponent) => Fractional(exponent).raise(base),
    }
}

/// `lighting::specular_power` of bases already `max(·, 0)`, for a shininess sorted once per
/// material into a type, so that a light loop holds only its own kind of power.
trait Power: Copy {
    fn raise<B: Backend>(self, base: Floats<B>) -> Floats<B>;
}

/// A whole exponent up to `MAX_SQUARED_EXPONENT`: raised by squaring.
#[derive(Clone, Copy)]
struct Squared(u32);

impl Power for Squared {
    #[inline(always)]
    fn raise<B: Backend>(self, base: Floats<B>) -> Floats<B> {
        power_by_squaring(base, Floats::splat(1.0), self.0)
    }
}

/// Another exponent: raised by `power::pow`.
#[derive(Clone, Copy)]
struct Fractional(f32);

impl Power for Fractional {
    #[inline(always)]
    fn raise<B: Backend>(self, base: Floats<B>) -> Floats<B> {
        power::pow(base, Floats::splat(self.0))
    }
}

/// What the pixels of a triangle shaded one by one show, decided once per triangle.
#[derive(Clone, Copy)]
pub enum PixelOutput<'f> {
    /// The lit colour.
    Lit(FastLighting<'f>),
    /// The normals debug view: the side's normal mapped from [−1, 1] to [0, 1] per axis.
    Normals,
    /// The depth debug view: the distance along the view axis (the frame scales it afterwards).
    Depth,
}

/// What the pixels of one batch share (in one frame): the material and object (which decide
/// the lighting and how normals are interpolated), and the side or the view. Two integers,
/// compared per pixel.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct BatchKey {
    /// The material and object.
    surface: u64,
    /// 0 and 1 for the front and back of a lit surface, 2 and 3 for the normals and depth views.
    output: u8,
}

impl BatchKey {
    /// No pixel's key: an empty batch's.
    const NONE: BatchKey = BatchKey {
        surface: u64::MAX,
        output: u8::MAX,
    };

    #[inline(always)]
    fn of(output: &PixelOutput, triangle: &FrameTriangle, back_facing: bool) -> Self {
        BatchKey {
            surface: u64::from(triangle.material) | u64::from(triangle.object) << 32,
            output: match output {
                PixelOutput::Lit(_) => u8::from(back_facing),
                PixelOutput::Normals => 2,
                PixelOutput::Depth => 3,
            },
        }
    }
}

/// One triangle shaded pixel by pixel (Phong shading, and every mode's normals and depth views),
/// its stages chosen once: how the normal is interpolated, and what a pixel shows.
pub struct FastPhong<'f> {
    frame: &'f Frame,
    output: PixelOutput<'f>,
    batch_key: BatchKey,
    triangle: &'f FrameTriangle,
    positions: [Vec3; 3],
    normals: NormalStage,
    /// Whether the side shaded uses the surface's normal flipped (`ObjectStyle::side_normal`).
    reversed: bool,
    /// Whether vertex colours or textures make the material's `k_a`, `k_d` or normal vary
    /// from point to point (`surface_lanes::varies`): the pixels are then lit through a
    /// [`SurfaceBatch`], not a [`PhongBatch`].
    varies: bool,
}

/// How a triangle's pixels interpolate its vertex normals (before renormalising), chosen once.
#[derive(Clone, Copy)]
enum NormalStage {
    /// Component by component: the vertex normals.
    Nlerp([Vec3; 3]),
    /// `slerp_triangle`: the arc between the first two normals (the same at every pixel), and
    /// the third normal.
    Slerp { first_two: NormalArc, third: Vec3 },
}

/// Up to [`LANES`] pixels of [`FastPhong`] triangles with the same output, waiting to be computed
/// together: [`FastPhong::shade`] for each, with the same bits, but the square roots, divisions
/// and lighting done lane-wise. For surfaces that do not vary (else [`SurfaceBatch`]).
pub struct PhongBatch<'f> {
    /// The frame and what the waiting pixels show.
    shader: Option<(&'f Frame, PixelOutput<'f>)>,
    /// `shader`'s [`BatchKey`] ([`BatchKey::NONE`] while there is none).
    key: BatchKey,
    /// Whether the waiting pixels' normals are slerped (they are of one object).
    slerp: bool,
    len: usize,
    /// Where each pixel's colour goes.
    offsets: [usize; LANES],
    positions: [Vec3; LANES],
    /// With Nlerp: interpolated, not yet renormalised.
    normals: [Vec3; LANES],
    /// With Slerp: each pixel's weights and its triangle's first arc and third normal.
    weights: [Vec3; LANES],
    arcs: [NormalArc; LANES],
    thirds: [Vec3; LANES],
    triangles: [Option<&'f FrameTriangle>; LANES],
    reversed: [bool; LANES],
}

impl Default for PhongBatch<'_> {
    fn default() -> Self {
        PhongBatch {
            shader: None,
            key: BatchKey::NONE,
            slerp: false,
            len: 0,
            offsets: [0; LANES],
            positions: [Vec3::ZERO; LANES],
            normals: [Vec3::ZERO; LANES],
            weights: [Vec3::ZERO; LANES],
            arcs: [NormalArc::Chord {
                start: Vec3::ZERO,
                end: Vec3::ZERO,
            }; LANES],
            thirds: [Vec3::ZERO; LANES],
            triangles: [None; LANES],
            reversed: [false; LANES],
        }
    }
}

impl<'f> PhongBatch<'f> {
    /// Queues the pixel with source-triangle weights `weights` of `phong`'s triangle; its
    /// colour goes to `color[offset]` when the batch is computed (when full, when a pixel with
    /// another output comes, or on [`PhongBatch::flush`]).
    #[inline(always)]
    pub fn push(&mut self, phong: &FastPhong<'f>, weights: Vec3, offset: usize, color: &mut [Vec3]) {
        debug_assert!(!phong.varies());
        if self.key != phong.batch_key {
            self.flush(color);
            self.shader = Some((phong.frame, phong.output));
            self.key = phong.batch_key;
            self.slerp = matches!(phong.normals, NormalStage::Slerp { .. });
        }
        let lane = self.len;
        self.offsets[lane] = offset;
        self.positions[lane] = interpolate(phong.positions, weights);
        match phong.normals {
            NormalStage::Nlerp(normals) => self.normals[lane] = interpolate(normals, weights),
            NormalStage::Slerp { first_two, third } => {
                self.weights[lane] = weights;
                self.arcs[lane] = first_two;
                self.thirds[lane] = third;
            }
        }
        self.triangles[lane] = Some(phong.triangle);
        self.reversed[lane] = phong.reversed;
        self.len += 1;
        if self.len == LANES {
            self.flush(color);
        }
    }

    /// Computes the waiting pixels into `color` and empties the batch.
    pub fn flush(&mut self, color: &mut [Vec3]) {
        let Some((frame, output)) = self.shader else {
            return;
        };
        if self.len == 0 {
            return;
        }
        // The lanes past the last pixel repeat it; their results are dropped.
        for lane in self.len..LANES {
            self.positions[lane] = self.positions[self.len - 1];
            self.normals[lane] = self.normals[self.len - 1];
            self.weights[lane] = self.weights[self.len - 1];
            self.arcs[lane] = self.arcs[self.len - 1];
            self.thirds[lane] = self.thirds[self.len - 1];
            self.triangles[lane] = self.triangles[self.len - 1];
            self.reversed[lane] = self.reversed[self.len - 1];
        }
        let shaded = match output {
            PixelOutput::Depth => {
                let depth: Floats = Vec3s::from_array(&self.positions).dot(Vec3s::splat(frame.forward));
                depth.0.map(Vec3::splat)
            }
            PixelOutput::Lit(lighting) => run_widest(PhongBatchWork {
                batch: self,
                frame,
                lighting,
            }),
            PixelOutput::Normals => {
                let normals: Vec3s = self.side_normals(frame);
                let half = Floats::splat(0.5);
                (normals.scale(half) + Vec3s::splat(Vec3::splat(0.5))).to_array()
            }
        };
        for (&offset, &shaded) in self.offsets[..self.len].iter().zip(&shaded) {
            color[offset] = shaded;
        }
        self.len = 0;
    }

    /// The waiting pixels' normals renormalised (`renormalize_or_else`, lane-wise: `v / |v|`
    /// where `|v|² > 1e-12`, else the face normal) and turned to the side shaded.
    #[inline(always)]
    fn side_normals<B: Backend>(&self, frame: &Frame) -> Vec3s<B> {
        let interpolated = if self.slerp {
            slerp_triangle_lanes(&self.arcs, &self.thirds, &self.weights)
        } else {
            Vec3s::from_array(&self.normals)
        };
        let normals = renormalize_lanes(frame, interpolated, &self.triangles);
        Mask::from_bools(self.reversed).select3(-normals, normals)
    }
}

/// A [`PhongBatch`]'s lit pixels, for `lanes::run_widest`: normals (Slerp included) and
/// lighting on the widest lanes.
struct PhongBatchWork<'b, 'f> {
    batch: &'b PhongBatch<'f>,
    frame: &'f Frame,
    lighting: FastLighting<'f>,
}

impl LaneWork for PhongBatchWork<'_, '_> {
    type Output = [Vec3; LANES];

    #[inline(always)]
    fn run<B: Backend>(self) -> [Vec3; LANES] {
        let normals = self.batch.side_normals::<B>(self.frame);
        self.lighting
            .light_lanes_on(Vec3s::from_array(&self.batch.positions), normals)
    }
}

/// `slerp_triangle_along` for the lanes' weights, first arcs and third normals: lane by lane
/// the same operations, `trig`'s sine, cosine and `atan2` included.
#[inline(always)]
fn slerp_triangle_lanes<B: Backend>(
    arcs: &[NormalArc; LANES],
    thirds: &[Vec3; LANES],
    weights: &[Vec3; LANES],
) -> Vec3s<B> {
    let weights = Vec3s::from_array(weights);
    let first = ArcLanes::of(arcs);
    let first_two_weight = weights.x + weights.y;
    let on_edge = first_two_weight.gt(Floats::splat(0.0));
    let edge = on_edge.select3(first.at(weights.y / first_two_weight), first.start);
    ArcLanes::new(edge, Vec3s::from_array(thirds)).at(weights.z)
}

/// [`NormalArc`]s in lanes: where each starts, where it goes (a chord's end, a turn's
/// `towards`), its angle (a turn's), and which lanes are chords.
struct ArcLanes<B: Backend> {
    start: Vec3s<B>,
    other: Vec3s<B>,
    angle: Floats<B>,
    chord: Mask<B>,
}

impl<B: Backend> ArcLanes<B> {
    /// The lanes of `arcs`.
    #[inline(always)]
    fn of(arcs: &[NormalArc; LANES]) -> Self {
        let mut other = [Vec3::ZERO; LANES];
        let mut angle = [0.0; LANES];
        let mut chord = [false; LANES];
        for (lane, arc) in arcs.iter().enumerate() {
            match *arc {
                NormalArc::Chord { end, .. } => (other[lane], chord[lane]) = (end, true),
                NormalArc::Turn {
                    towards, angle: a, ..
                } => (other[lane], angle[lane]) = (towards, a),
            }
        }
        ArcLanes {
            start: Vec3s::from_array(&arcs.map(|arc| arc.start())),
            other: Vec3s::from_array(&other),
            angle: Floats::new(angle),
            chord: Mask::from_bools(chord),
        }
    }

    /// `NormalArc::new` lane by lane; a half turn's perpendicular (`any_orthonormal_vector`)
    /// per lane where one occurs.
    #[inline(always)]
    fn new(n0: Vec3s<B>, n1: Vec3s<B>) -> Self {
        let zero = Floats::splat(0.0);
        let cos = n0.dot(n1);
        let cross = n0.cross(n1);
        let sin = cross.length();
        let small = Floats::splat(SMALL_SINE).gt(sin);
        let chord = n0.is_zero().or(n1.is_zero()).or(small.and(cos.gt(zero)));
        let half_turn = small.and(!chord);
        let mut towards = cross.divide(sin).cross(n0);
        if half_turn.any() {
            let (starts, mut perpendiculars) = (n0.to_array(), towards.to_array());
            for lane in (0..LANES).filter(|&lane| half_turn.lane(lane)) {
                perpendiculars[lane] = starts[lane].any_orthonormal_vector();
            }
            towards = Vec3s::from_array(&perpendiculars);
        }
        ArcLanes {
            start: n0,
            other: chord.select3(n1, towards),
            angle: small.select(Floats::splat(std::f32::consts::PI), trig::atan2(sin, cos)),
            chord,
        }
    }

    /// `NormalArc::at(t)` lane by lane (the chord only where a lane has one: rare, normals
    /// nearly parallel).
    #[inline(always)]
    fn at(&self, t: Floats<B>) -> Vec3s<B> {
        let (sine, cosine) = trig::sin_cos(t * self.angle);
        let turn = self.start.scale(cosine) + self.other.scale(sine);
        if !self.chord.any() {
            return turn;
        }
        let one = Floats::splat(1.0);
        let chord = (self.start.scale(one - t) + self.other.scale(t)).normalize_or_zero();
        self.chord.select3(chord, turn)
    }
}

/// The value at barycentric `weights` of a triangle whose corners have `values`.
#[inline(always)]
fn interpolate([a, b, c]: [Vec3; 3], weights: Vec3) -> Vec3 {
    a * weights.x + b * weights.y + c * weights.z
}

/// `renormalize_or_else` lane-wise: `v / |v|` where `|v|² > 1e-12`, else the face normal of the
/// lane's triangle.
#[inline(always)]
fn renormalize_lanes<B: Backend>(
    frame: &Frame,
    interpolated: Vec3s<B>,
    triangles: &[Option<&FrameTriangle>; LANES],
) -> Vec3s<B> {
    let length_squared = interpolated.dot(interpolated);
    let usable = length_squared.gt(Floats::splat(1e-12));
    let normals = interpolated.divide(length_squared.sqrt());
    // Rare (opposite vertex normals): one test for the whole batch.
    if usable.all() {
        return normals;
    }
    let mut normals = normals.to_array();
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
    pixels: EdgeQueue<SurfaceTriangle<'f>>,
    /// Whether a triangle named so far slerps its normals (else no lane does). Never cleared:
    /// a triangle's pixels may go on past a flush, and a batch lives for one tile.
    slerping: bool,
}

/// `FastPhong::shade`'s interpolation, lane-wise: per lane the `corner`s of its triangle
/// weighted by `weights`.
#[inline(always)]
fn interpolate_corners<B: Backend, T>(
    triangles: &[&T; LANES],
    weights: &[Floats<B>; 3],
    corner: impl Fn(&T, usize) -> Vec3,
) -> Vec3s<B> {
    let at = |k: usize| Vec3s::gather(triangles, |triangle| corner(triangle, k));
    at(0).scale(weights[0]) + at(1).scale(weights[1]) + at(2).scale(weights[2])
}

/// A triangle of a [`SurfaceBatch`]'s pixels: what their interpolation reads of it.
#[derive(Clone, Copy, Default)]
struct SurfaceTriangle<'f> {
    triangle: Option<&'f FrameTriangle>,
    plane: RasterPlane,
    positions: [Vec3; 3],
    /// With Nlerp: the vertex normals.
    normals: [Vec3; 3],
    /// With Slerp: the first arc and the third normal (as [`NormalStage::Slerp`]).
    slerp: Option<(NormalArc, Vec3)>,
    /// Whether the lit side's normal is the reversed one (`ObjectStyle::reverses_normal`).
    reversed: bool,
}

impl<'f> SurfaceBatch<'f> {
    /// Names the triangle the next pixels are of: `phong`'s, whose raster triangle is `plane`
    /// (flushing the waiting pixels into `color` first if it lights otherwise).
    #[inline]
    pub fn begin(&mut self, phong: &FastPhong<'f>, plane: RasterPlane, color: &mut [Vec3]) {
        // `FastPhong::new` lets a surface vary only where it lights it.
        let PixelOutput::Lit(lighting) = phong.output else {
            unreachable!("a varying surface is lit");
        };
        let (normals, slerp) = match phong.normals {
            NormalStage::Nlerp(normals) => (normals, None),
            NormalStage::Slerp { first_two, third } => ([Vec3::ZERO; 3], Some((first_two, third))),
        };
        if let Some(waiting) = self.lighting
            && !waiting.same_as(&lighting)
        {
            self.flush(color);
        }
        self.lighting = Some(lighting);
        self.slerping |= slerp.is_some();
        self.pixels.begin(SurfaceTriangle {
            triangle: Some(phong.triangle),
            plane,
            positions: phong.positions,
            normals,
            slerp,
            reversed: phong.reversed,
        });
    }

    /// Queues the pixel of the current triangle where its edge functions take the values
    /// `edges`; its colour goes to `color[offset]` when the batch is shaded (when full, when a
    /// triangle with other lighting begins, or on [`SurfaceBatch::flush`]).
    #[inline]
    pub fn push(&mut self, edges: [i64; 3], offset: usize, color: &mut [Vec3]) {
        self.pixels.push(edges, offset);
        if self.pixels.is_full() {
            self.flush(color);
        }
    }

    /// Shades the waiting pixels into `color` and empties the batch.
    pub fn flush(&mut self, color: &mut [Vec3]) {
        let Some(lighting) = self.lighting else {
            return;
        };
        if self.pixels.is_empty() {
            return;
        }
        let QueuedPixels {
            offsets,
            edges,
            triangles,
        } = self.pixels.take();
        run_widest(SurfaceLanesWork {
            lighting,
            slerping: self.slerping,
            offsets,
            edges,
            triangles,
            color,
        });
    }
}

/// A [`SurfaceBatch`]'s waiting pixels shaded into `color`, as lane work: weights,
/// interpolation, the surface stage and the lighting, a few thousand operations a batch.
struct SurfaceLanesWork<'q, 'f, 'c> {
    lighting: FastLighting<'f>,
    slerping: bool,
    offsets: &'q [usize],
    edges: &'q [[i64; 3]; LANES],
    triangles: [&'q SurfaceTriangle<'f>; LANES],
    color: &'c mut [Vec3],
}

impl LaneWork for SurfaceLanesWork<'_, '_, '_> {
    type Output = ();

    #[inline(always)]
    fn run<B: Backend>(self) {
        let Self {
            lighting,
            slerping,
            offsets,
            edges,
            triangles,
            color,
        } = self;
        let frame = lighting.frame;
        let weights = WeightLanes::<B>::of(edges, &triangles.map(|triangle| &triangle.plane));
        let frame_triangles = triangles.map(|triangle| triangle.triangle);
        let vertices = frame_triangles.map(|triangle| triangle.expect("every lane holds a pixel").vertices);
        let positions = interpolate_corners(&triangles, &weights.at, |triangle, k| triangle.positions[k]);
        let normals = if slerping {
            surface_normals(&triangles, &weights.at)
        } else {
            nlerped_normals(&triangles, &weights.at)
        };
        let normals = renormalize_lanes(frame, normals, &frame_triangles);
        // The normal map perturbs the front normal, before the side is chosen.
        let points = SurfacePoints {
            vertices: &vertices,
            weights: &weights,
        };
        let (surface, normals) = surface_lanes(frame, lighting.material, &points, normals);
        let reversed = Mask::from_bools(triangles.map(|triangle| triangle.reversed));
        let normals = reversed.select3(-normals, normals);
        let lit = lighting.light_surface_lanes_on(positions, normals, &surface);
        let lit = (lit.textured + lit.rest).to_array();
        for (&offset, &lit) in offsets.iter().zip(&lit) {
            color[offset] = lit;
        }
    }
}

/// The interpolated normals (before renormalising) of a [`SurfaceBatch`]'s lanes at source
/// weights `weights`, each as its triangle interpolates them: component by component, or
/// slerped (`slerp_triangle_lanes`; a batch may hold triangles of both kinds where two objects
/// light alike, so each lane takes its own).
#[inline(always)]
fn surface_normals<B: Backend>(triangles: &[&SurfaceTriangle; LANES], weights: &[Floats<B>; 3]) -> Vec3s<B> {
    let Some(any_arc) = triangles.iter().find_map(|triangle| triangle.slerp) else {
        return nlerped_normals(triangles, weights);
    };
    // Lanes with Nlerp take another lane's arc for the slerp, whose result they drop.
    let arcs = triangles.map(|triangle| triangle.slerp.unwrap_or(any_arc));
    let point_weights = Vec3s {
        x: weights[0],
        y: weights[1],
        z: weights[2],
    }
    .to_array();
    let slerped = slerp_triangle_lanes(
        &arcs.map(|(arc, _)| arc),
        &arcs.map(|(_, third)| third),
        &point_weights,
    );
    let slerping = Mask::from_bools(triangles.map(|triangle| triangle.slerp.is_some()));
    if slerping.all() {
        slerped
    } else {
        slerping.select3(slerped, nlerped_normals(triangles, weights))
    }
}

/// The normals of a [`SurfaceBatch`]'s lanes interpolated component by component (Nlerp,
/// before renormalising). A function rather than a closure: lane code in a closure is compiled
/// apart from `run_widest`'s `avx2` function, its intrinsics then calls.
#[inline(always)]
fn nlerped_normals<B: Backend>(triangles: &[&SurfaceTriangle; LANES], weights: &[Floats<B>; 3]) -> Vec3s<B> {
    interpolate_corners(triangles, weights, |triangle, k| triangle.normals[k])
}

/// The lit pixels of one [`FastPhong`] triangle with Nlerp normals, shaded a group of
/// [`LANES`] neighbouring pixels of a row at a time: the triangle's corners, `1/w` and `1/A`
/// splatted once, so that a group's weights, position and normal are interpolated lane-wise
/// with no per-pixel gathering or queueing. Each pixel gets the bits [`FastPhong::shade`]
/// gives it: `shade::weights_from_edges` and the interpolation are the same operations in the
/// same order, lane by lane. For triangles whose rows span groups of pixels; the small ones
/// of dense meshes go through a [`PhongBatch`], which fills its lanes across triangles.
pub struct PhongRows<'f> {
    lighting: FastLighting<'f>,
    triangle: &'f FrameTriangle,
    positions: [Vec3s; 3],
    normals: [Vec3s; 3],
    reversed: bool,
    inv_area: Floats,
    inv_w: [Floats; 3],
    corners: Corners,
}

impl<'f> PhongRows<'f> {
    /// The rows of `phong`'s triangle, whose raster triangle (or a piece of it) has `1/A`
    /// `inv_area`, corners' `1/w` `inv_w` and corner weights `corners`; `None` unless its
    /// pixels are lit (not a debug view) with normals interpolated component by component
    /// on a surface that does not vary.
    #[inline]
    pub fn of(phong: &FastPhong<'f>, inv_area: f32, inv_w: [f32; 3], corners: Corners) -> Option<Self> {
        let (PixelOutput::Lit(lighting), NormalStage::Nlerp(normals), false) =
            (phong.output, phong.normals, phong.varies)
        else {
            return None;
        };
        Some(PhongRows {
            lighting,
            triangle: phong.triangle,
            positions: phong.positions.map(Vec3s::splat),
            normals: normals.map(Vec3s::splat),
            reversed: phong.reversed,
            inv_area: Floats::splat(inv_area),
            inv_w: inv_w.map(Floats::splat),
            corners,
        })
    }

    /// The colours of the pixels where the raster triangle's edge functions take the values
    /// `edges` gives (converted to `f32`, one pixel per lane). Lanes outside the triangle get a
    /// colour too, which the caller drops. Interpolated and lit on the widest lanes the
    /// processor has (`lanes::run_widest`); `edges` runs there too, so that its values reach
    /// the wide lanes in registers (stored as two halves and loaded whole, they would wait
    /// for the stores).
    #[inline]
    pub fn shade(&self, edges: impl Fn() -> [Floats; 3]) -> [Vec3; LANES] {
        run_widest(PhongRowsWork { rows: self, edges })
    }

    /// [`PhongRows::shade`] written straight into `out`, a group of the frame's pixels: the
    /// colours go from the lanes to the frame (`Vec3s::write_to`), not through an array whose
    /// copy would load them whole from stores too recent to forward.
    #[inline]
    pub fn shade_into(&self, edges: impl Fn() -> [Floats; 3], out: &mut [Vec3; LANES]) {
        run_widest(PhongRowsInto {
            rows: self,
            edges,
            out,
        })
    }

    /// [`PhongRows::shade`] on backend `B`.
    #[inline(always)]
    fn shade_on<B: Backend>(&self, edges: [Floats<B>; 3]) -> [Vec3; LANES] {
        self.lit_on(edges).to_array()
    }

    /// [`PhongRows::shade_on`], the colours left in lanes.
    #[inline(always)]
    fn lit_on<B: Backend>(&self, edges: [Floats<B>; 3]) -> Vec3s<B> {
        // `shade::perspective_weights`, then `Corners::apply`.
        let screen = edges.map(|edge| edge * self.inv_area.on());
        let over_w: [Floats<B>; 3] = std::array::from_fn(|k| screen[k] * self.inv_w[k].on());
        let sum = over_w[0] + over_w[1] + over_w[2];
        let positive = sum.gt(Floats::splat(0.0));
        let [x, y, z]: [Floats<B>; 3] = std::array::from_fn(|k| positive.select(over_w[k] / sum, screen[k]));
        let [x, y, z] = match self.corners {
            Corners::Identity => [x, y, z],
            Corners::Swapped => [x, z, y],
            Corners::Clipped(_) => {
                let weights = Vec3s { x, y, z }.to_array().map(|w| self.corners.apply(w));
                let weights = Vec3s::from_array(&weights);
                [weights.x, weights.y, weights.z]
            }
        };
        let weights = [x, y, z];
        let position = interpolate_lanes(self.positions, weights);
        let normals = renormalize_lanes(
            self.lighting.frame,
            interpolate_lanes(self.normals, weights),
            &[Some(self.triangle); LANES],
        );
        let normals = if self.reversed { -normals } else { normals };
        self.lighting.lit_lanes_on(position, normals)
    }
}

/// `a·x + b·y + c·z` lane-wise, for corners `[a, b, c]` and weights `[x, y, z]` (as
/// `interpolate`).
#[inline(always)]
fn interpolate_lanes<B: Backend>([a, b, c]: [Vec3s; 3], [x, y, z]: [Floats<B>; 3]) -> Vec3s<B> {
    a.on::<B>().scale(x) + b.on().scale(y) + c.on().scale(z)
}

/// [`PhongRows::shade`]'s arguments, for `lanes::run_widest`.
struct PhongRowsWork<'r, 'f, E> {
    rows: &'r PhongRows<'f>,
    edges: E,
}

impl<E: Fn() -> [Floats; 3]> LaneWork for PhongRowsWork<'_, '_, E> {
    type Output = [Vec3; LANES];

    #[inline(always)]
    fn run<B: Backend>(self) -> [Vec3; LANES] {
        self.rows.shade_on((self.edges)().map(Floats::on::<B>))
    }
}

/// [`PhongRows::shade_into`]'s arguments, for `lanes::run_widest`.
struct PhongRowsInto<'r, 'f, 'o, E> {
    rows: &'r PhongRows<'f>,
    edges: E,
    out: &'o mut [Vec3; LANES],
}

impl<E: Fn() -> [Floats; 3]> LaneWork for PhongRowsInto<'_, '_, '_, E> {
    type Output = ();

    #[inline(always)]
    fn run<B: Backend>(self) {
        self.rows
            .lit_on((self.edges)().map(Floats::on::<B>))
            .write_to(self.out);
    }
}

impl<'f> FastPhong<'f> {
    /// Whether this triangle's pixels and `other`'s can wait in one [`PhongBatch`].
    #[inline]
    pub fn shares_batch(&self, other: &FastPhong<'_>) -> bool {
        self.batch_key == other.batch_key
    }

    /// The per-pixel shading of `triangle` seen from the front or the back, or `None` when it
    /// needs the general path: a lit pixel whose lighting does not take lanes (see
    /// [`FastLighting::new`]). The debug views of normals and
    /// depth take any triangle; the caller asks them for every mode whose pixels they vary over
    /// (depth: all; normals: Gouraud and Phong). `lightings` forms the lighting.
    #[inline(always)]
    pub fn new(
        frame: &'f Frame,
        triangle: &'f FrameTriangle,
        back_facing: bool,
        lightings: &mut LightingMemo<'f>,
    ) -> Option<Self> {
        let style = &frame.objects[triangle.object as usize];
        let output = match frame.debug_view {
            Some(DebugView::Depth) => PixelOutput::Depth,
            Some(DebugView::Normals) => PixelOutput::Normals,
            _ => PixelOutput::Lit(lightings.get(frame, triangle, Shading::Phong, back_facing)?),
        };
        let varies = matches!(output, PixelOutput::Lit(lighting) if varies(frame, lighting.material));
        let vertices = triangle.vertices.map(|v| &frame.vertices[v as usize]);
        let [n0, n1, n2] = vertices.map(|v| v.normal);
        let normals = match style.normal_interpolation {
            NormalInterpolation::Nlerp => NormalStage::Nlerp([n0, n1, n2]),
            NormalInterpolation::Slerp => NormalStage::Slerp {
                first_two: NormalArc::new(n0, n1),
                third: n2,
            },
        };
        Some(FastPhong {
            frame,
            output,
            batch_key: BatchKey::of(&output, triangle, back_facing),
            varies,
            triangle,
            positions: vertices.map(|v| v.position),
            normals,
            reversed: style.reverses_normal(back_facing),
        })
    }

    /// Whether vertex colours or textures make the triangle's surface vary: its pixels are
    /// shaded through a [`SurfaceBatch`], not a [`PhongBatch`].
    #[inline]
    pub fn varies(&self) -> bool {
        self.varies
    }

    /// The normal at `weights` as the object interpolates it, before renormalisation.
    fn interpolated_normal(&self, weights: Vec3) -> Vec3 {
        match &self.normals {
            NormalStage::Nlerp(normals) => interpolate(*normals, weights),
            NormalStage::Slerp { first_two, third } => slerp_triangle_along(first_two, *third, weights),
        }
    }

    /// The colour at the point with source-triangle weights `weights`: what [`PhongBatch`]
    /// computes for each pixel it queues (the renderer shades through the batch; tests hold the
    /// two, and this and the general path, together bit for bit).
    pub fn shade(&self, weights: Vec3) -> Vec3 {
        let frame = self.frame;
        debug_assert!(!self.varies);
        let position = interpolate(self.positions, weights);
        let normal = renormalize_or_else(self.interpolated_normal(weights), || {
            frame.face_normal(self.triangle)
        });
        let normal = if self.reversed { -normal } else { normal };
        match self.output {
            PixelOutput::Lit(lighting) => lighting.light(position, normal),
            PixelOutput::Normals => normal * 0.5 + 0.5,
            PixelOutput::Depth => Vec3::splat(position.dot(frame.forward)),
        }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use std::sync::Arc;

    use glam::{DVec3, Vec2, Vec4};

    use super::*;
    use crate::lighting::{cook_torrance, incidence};
    use crate::mesh::primitives;
    use crate::render::frame::{has_color_texture, tinted};
    use crate::render::normals::slerp_triangle;
    use crate::render::raster::SamplePattern;
    use crate::render::{RenderOptions, geometry::build_frame, render};
    use crate::scene::{
        Attenuation, Camera, ImageSettings, Light, Object, Projection, Scene, ShadowSettings, TextureBinding,
    };
    use crate::texture::{Sampler, Texture, Wrap};

    /// A rough Cook-Torrance surface with a coloured Fresnel term, under `distribution`.
    pub(crate) const fn microfacet(distribution: MicrofacetDistribution) -> LightingModel {
        LightingModel::CookTorrance(Microfacet {
            roughness: 0.35,
            fresnel: Vec3::new(0.04, 0.3, 0.9),
            distribution,
        })
    }

    /// Every lighting model with the specular colour it is tested with: Phong and Blinn-Phong
    /// with and without a specular term, Lambert, Cook-Torrance with each distribution, unlit.
    pub(crate) const MODELS: [(LightingModel, Vec3); 7] = [
        (LightingModel::Phong, Vec3::splat(0.7)),
        (LightingModel::BlinnPhong, Vec3::splat(0.7)),
        (LightingModel::Phong, Vec3::ZERO),
        (LightingModel::Lambert, Vec3::splat(0.7)),
        (microfacet(MicrofacetDistribution::Beckmann), Vec3::splat(0.7)),
        (microfacet(MicrofacetDistribution::Ggx), Vec3::splat(0.7)),
        (LightingModel::Unlit, Vec3::splat(0.7)),
    ];

    /// What an object shows and how it interpolates normals, beside its lighting: a component,
    /// Nlerp or Slerp, and the frame's debug view.
    #[derive(Debug, Clone, Copy, PartialEq)]
    pub(crate) struct Look {
        pub component: LightingComponent,
        pub interpolation: NormalInterpolation,
        pub view: Option<DebugView>,
    }

    pub(crate) const PLAIN: Look = Look {
        component: LightingComponent::All,
        interpolation: NormalInterpolation::Nlerp,
        view: None,
    };

    /// Every component, both interpolations and every debug view, each at least once.
    pub(crate) const LOOKS: [Look; 9] = {
        use DebugView as V;
        use LightingComponent as C;
        use NormalInterpolation::{Nlerp, Slerp};
        [
            PLAIN,
            Look::new(C::All, Slerp, None),
            Look::new(C::Ambient, Nlerp, None),
            Look::new(C::Diffuse, Slerp, None),
            Look::new(C::Specular, Nlerp, None),
            Look::new(C::All, Nlerp, Some(V::Diffuse)),
            Look::new(C::Diffuse, Slerp, Some(V::Specular)),
            Look::new(C::All, Slerp, Some(V::Normals)),
            Look::new(C::Specular, Nlerp, Some(V::Depth)),
        ]
    };

    impl Look {
        const fn new(
            component: LightingComponent,
            interpolation: NormalInterpolation,
            view: Option<DebugView>,
        ) -> Self {
            Look {
                component,
                interpolation,
                view,
            }
        }

        /// `scene` with every object showing `self` (the view is the frame's: see [`frame_of`]).
        pub(crate) fn apply(self, scene: &mut Scene) {
            for object in &mut scene.objects {
                object.component = self.component;
                object.normal_interpolation = self.interpolation;
            }
        }
    }

    /// The light sets the fast path is held to the general path under.
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    pub(crate) enum Lights {
        /// A directional light and an attenuated point light.
        DirectionalAndPoint,
        /// A directional light and two attenuated spot lights, each with its cone's edge across
        /// one sphere: one with a whole exponent (squared lane-wise), one with a fractional
        /// exponent (`power::pow`).
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
                mip_bias: 0.0,
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
    /// Points of every triangle, both sides, shaded per pixel in lanes ([`PhongBatch`], and
    /// `FastPhong::shade`) against the general path's pieces (`Frame::light` with the normal
    /// interpolated as the object asks, or the debug view's value), bit for bit: every model,
    /// light set and back-face mode, and for two models every component, interpolation and view.
    #[test]
    fn fast_path_equals_the_general_lighting_bit_for_bit() {
        let cases = MODELS.into_iter().enumerate().flat_map(|(index, model)| {
            let looks: &[Look] = if matches!(index, 0 | 5) { &LOOKS } else { &[PLAIN] };
            looks
                .iter()
                .flat_map(move |&look| LIGHTS.map(|lights| (model, look, lights)))
        });
        for ((model, specular), look, lights) in cases {
            for back_faces in [BackFaces::ReverseLit, BackFaces::Lit, BackFaces::Unlit] {
                let mut scene = scene(model, specular, back_faces, lights);
                look.apply(&mut scene);
                let frame = frame_of(&scene, look.view);
                let mut points = Vec::new();
                let (mut expected, mut batch) = (Vec::new(), PhongBatch::default());
                let triangles = frame_triangles(&frame);
                let mut colors = vec![Vec3::NAN; 6 * triangles.len()];
                for triangle in &triangles {
                    for back_facing in [false, true] {
                        let fast =
                            FastPhong::new(&frame, triangle, back_facing, &mut LightingMemo::default())
                                .expect("eligible");
                        for weights in [Vec3::new(0.2, 0.3, 0.5), Vec3::splat(1.0 / 3.0), Vec3::X] {
                            let [a, b, c] = triangle.vertices.map(|v| frame.vertices[v as usize]);
                            let position =
                                a.position * weights.x + b.position * weights.y + c.position * weights.z;
                            let interpolated = match look.interpolation {
                                NormalInterpolation::Nlerp => {
                                    a.normal * weights.x + b.normal * weights.y + c.normal * weights.z
                                }
                                NormalInterpolation::Slerp => {
                                    slerp_triangle([a.normal, b.normal, c.normal], weights)
                                }
                            };
                            let normal = renormalize_or_else(interpolated, || frame.face_normal(triangle));
                            let style = &frame.objects[triangle.object as usize];
                            let general = match look.view {
                                Some(DebugView::Depth) => Vec3::splat(position.dot(frame.forward)),
                                Some(DebugView::Normals) => {
                                    style.side_normal(normal, back_facing) * 0.5 + 0.5
                                }
                                _ => frame.light(triangle.material, style, position, normal, back_facing),
                            };
                            let bits = |v: Vec3| v.to_array().map(f32::to_bits);
                            assert_eq!(
                                bits(fast.shade(weights)),
                                bits(general),
                                "{model:?} {look:?} {back_faces:?} {lights:?}"
                            );
                            batch.push(&fast, weights, expected.len(), &mut colors);
                            expected.push(general);
                            points.push((position, style.side_normal(normal, back_facing)));
                        }
                    }
                }
                batch.flush(&mut colors);
                for (lanes, general) in colors.iter().zip(&expected) {
                    let bits = |v: Vec3| v.to_array().map(f32::to_bits);
                    assert_eq!(
                        bits(*lanes),
                        bits(*general),
                        "{model:?} {look:?} {back_faces:?} {lights:?}, in lanes"
                    );
                }
                assert!(expected.len() > 1000);
                if lights == Lights::Shadowed {
                    assert_shadows_cross(&frame, &points, 20);
                }
                if lights == Lights::DirectionalAndSpots {
                    assert_cones_cross(&frame, &points, 100);
                }
                if let LightingModel::CookTorrance(surface) = model {
                    assert_microfacets_cross(&frame, &surface, &points, 50);
                }
            }
        }
    }

    /// How many of `points` (position, side normal) lit by some light of `frame` get a
    /// microfacet term from `surface`, and how many none (the viewer, or the half vector, below
    /// the surface), asserting both are at least `least`: a comparison over those points then
    /// covers both sides of `cook_torrance`'s early return.
    fn assert_microfacets_cross(frame: &Frame, surface: &Microfacet, points: &[(Vec3, Vec3)], least: usize) {
        let (mut reflecting, mut turned_away) = (0, 0);
        for &(position, normal) in points {
            for light in &frame.lights {
                if let Some((to_light, strength)) = incidence(light, position)
                    && normal.dot(to_light) > 0.0
                    && strength > 0.0
                {
                    let to_viewer = frame.viewer.to_viewer(position);
                    if cook_torrance(surface, normal, to_light, to_viewer)
                        .specular
                        .max_element()
                        > 0.0
                    {
                        reflecting += 1;
                    } else {
                        turned_away += 1;
                    }
                }
            }
        }
        assert!(
            reflecting >= least && turned_away >= least,
            "{reflecting} lit points with a microfacet term, {turned_away} without"
        );
    }

    /// Eight points lit at once, on the widest lanes and on the native backend, against the
    /// one-point lighting (the general path's), bit for bit, per model, component, side and
    /// debug view, with both viewers, unlit lanes, reversed normals and a zero normal among
    /// them.
    #[test]
    fn lighting_eight_points_at_once_equals_lighting_each_bit_for_bit() {
        // A whole shininess is raised by squaring, lane-wise; another goes through `power::pow`.
        let shininesses = MODELS.into_iter().flat_map(|m| [(m, 17.0), (m, 17.5)]);
        // (the object's component, the debug view, the side, the back-face mode)
        let sides = [
            (LightingComponent::All, None, false, BackFaces::ReverseLit),
            (LightingComponent::Diffuse, None, false, BackFaces::ReverseLit),
            (LightingComponent::Specular, None, false, BackFaces::ReverseLit),
            (LightingComponent::Ambient, None, false, BackFaces::ReverseLit),
            (
                LightingComponent::All,
                Some(DebugView::Specular),
                false,
                BackFaces::ReverseLit,
            ),
            (LightingComponent::All, None, true, BackFaces::Unlit),
        ];
        for (((model, specular), shininess), lights) in shininesses.flat_map(|s| LIGHTS.map(|l| (s, l))) {
            for (component, view, back_facing, back_faces) in sides {
                let mut scene = scene(model, specular, back_faces, lights);
                for object in &mut scene.objects {
                    object.material.as_mut().expect("a material").shininess = shininess;
                    object.component = component;
                }
                let mut frame = frame_of(&scene, view);
                for viewer in [
                    frame.viewer,
                    crate::render::frame::Viewer::Infinite { to_viewer: Vec3::Z },
                ] {
                    frame.viewer = viewer;
                    let style = &frame.objects[0];
                    let lighting =
                        FastLighting::new(&frame, 0, style, Shading::Phong, back_facing).expect("eligible");
                    let mut compared = 0;
                    let mut points = Vec::new();
                    for (group, vertices) in frame.vertices.chunks_exact(LANES).enumerate() {
                        let positions: [Vec3; LANES] = std::array::from_fn(|i| vertices[i].position);
                        let normals: [Vec3; LANES] = std::array::from_fn(|i| match (group + i) % 5 {
                            0 => -vertices[i].normal,
                            1 if group % 7 == 0 => Vec3::ZERO,
                            _ => vertices[i].normal,
                        });
                        // The widest lanes (AVX2 where the processor has it) and the native
                        // backend's, each against the one-point lighting.
                        let lit = lighting.light_lanes(&positions, &normals);
                        let native = lighting.light_surface_lanes_on::<Native>(
                            Vec3s::from_array(&positions),
                            Vec3s::from_array(&normals),
                            &SurfaceLanes::of(lighting.material),
                        );
                        let native = (native.textured + native.rest).to_array();
                        for i in 0..LANES {
                            let one = lighting.light(positions[i], normals[i]);
                            for (lanes, backend) in [(lit, "widest"), (native, "native")] {
                                assert_eq!(
                                    lanes[i].to_array().map(f32::to_bits),
                                    one.to_array().map(f32::to_bits),
                                    "{model:?} {component:?} {view:?} back {back_facing} {lights:?}, \
                                     point {i} of group {group}, {backend} lanes"
                                );
                            }
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
    }

    /// Pixels lit in batches (of mixed triangles, both objects' lightings and interpolations,
    /// partial batches, and normals that cancel out so the face normal stands in) against
    /// `FastPhong::shade`, lit and in the normals and depth views.
    #[test]
    fn phong_batches_equal_shading_each_pixel_bit_for_bit() {
        let models = [
            LightingModel::Phong,
            LightingModel::BlinnPhong,
            microfacet(MicrofacetDistribution::Ggx),
        ];
        let views = [None, Some(DebugView::Normals), Some(DebugView::Depth)];
        let cases = models
            .into_iter()
            .flat_map(|m| views.map(|v| (m, v)))
            .flat_map(|(m, v)| LIGHTS.map(|l| (m, v, l)));
        for (model, view, lights) in cases {
            let mut scene = scene(model, Vec3::splat(0.7), BackFaces::ReverseLit, lights);
            // Batches of the debug views mix the two objects' interpolations.
            scene.objects[1].normal_interpolation = NormalInterpolation::Slerp;
            let frame = frame_of(&scene, view);
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
            let mut fallbacks = 0;
            for (n, triangle) in triangles.iter().step_by(stride.max(1)).enumerate() {
                let mut fast = FastPhong::new(&frame, triangle, n % 3 == 0, &mut LightingMemo::default())
                    .expect("eligible");
                if n % 4 == 1 && matches!(fast.normals, NormalStage::Nlerp(_)) {
                    // Opposite vertex normals: halfway between the first two, nothing is left.
                    fast.normals = NormalStage::Nlerp([Vec3::X, -Vec3::X, Vec3::Y]);
                    fallbacks += 1;
                }
                let count = 1 + n % 3;
                for &w in &weights[..count] {
                    batch.push(&fast, w, expected.len(), &mut colors);
                    expected.push(fast.shade(w));
                }
            }
            batch.flush(&mut colors);
            assert!(expected.len() > 20 && fallbacks > 1);
            for (i, want) in expected.iter().enumerate() {
                let bits = |v: Vec3| v.to_array().map(f32::to_bits);
                assert_eq!(
                    bits(colors[i]),
                    bits(*want),
                    "{model:?} {view:?} {lights:?}, pixel {i}"
                );
            }
        }
    }

    /// Slerp in lanes, on the widest lanes and the native ones, against `slerp_triangle`
    /// (`NormalArc`) on awkward triangles, bit for bit: normals parallel, nearly parallel,
    /// opposite (the half turn), zero, unnormalised, and weights on corners and edges (a zero
    /// weight for the first two).
    #[test]
    fn slerp_in_lanes_equals_slerp_bit_for_bit() {
        let tilt = |angle: f32| Vec3::new(angle.sin(), 0.0, angle.cos());
        let normal_sets = [
            [Vec3::X, Vec3::Y, Vec3::Z],
            [Vec3::Z, Vec3::Z, Vec3::Z],
            [Vec3::Z, tilt(1e-7), tilt(2e-6)],
            [Vec3::Z, -Vec3::Z, Vec3::X],
            [Vec3::Z, tilt(std::f32::consts::PI - 1e-7), -Vec3::Z],
            [Vec3::ZERO, Vec3::Y, Vec3::Z],
            [Vec3::X, Vec3::ZERO, -Vec3::X],
            [
                Vec3::new(0.6, 0.0, 0.8),
                Vec3::new(0.0, 0.6, 0.8),
                Vec3::new(-0.48, -0.6, 0.64),
            ],
            [tilt(0.3), tilt(-2.9), Vec3::new(1.0, 2.0, -0.5)],
        ];
        let weights = [
            Vec3::new(0.2, 0.3, 0.5),
            Vec3::X,
            Vec3::Y,
            Vec3::Z,
            Vec3::new(0.5, 0.5, 0.0),
            Vec3::new(0.0, 0.25, 0.75),
            Vec3::splat(1.0 / 3.0),
            Vec3::new(0.7, 0.0, 0.3),
        ];
        let mut compared = 0;
        for (set, normals) in normal_sets.iter().enumerate() {
            // Each lane another triangle of the sets, each with its own weights.
            let lanes: [([Vec3; 3], Vec3); LANES] =
                std::array::from_fn(|lane| (normal_sets[(set + lane) % normal_sets.len()], weights[lane]));
            let arcs = lanes.map(|(n, _)| NormalArc::new(n[0], n[1]));
            let slerp = Slerp {
                arcs,
                thirds: lanes.map(|(n, _)| n[2]),
                weights: lanes.map(|(_, w)| w),
            };
            // On the widest lanes (AVX where the processor has it) and the native ones.
            for (slerped, backend) in [(run_widest(slerp), "widest"), (slerp.run::<Native>(), "native")] {
                for (lane, (normals, weights)) in lanes.iter().enumerate() {
                    let bits = |v: Vec3| v.to_array().map(f32::to_bits);
                    assert_eq!(
                        bits(slerped[lane]),
                        bits(slerp_triangle(*normals, *weights)),
                        "{normals:?} at {weights}, {backend} lanes"
                    );
                    compared += 1;
                }
            }
            assert!(normals.iter().all(|n| n.is_finite()));
        }
        assert_eq!(compared, 2 * normal_sets.len() * LANES);
    }

    /// `slerp_triangle_lanes`' arguments, to run it on any backend.
    #[derive(Clone, Copy)]
    struct Slerp {
        arcs: [NormalArc; LANES],
        thirds: [Vec3; LANES],
        weights: [Vec3; LANES],
    }

    impl LaneWork for Slerp {
        type Output = [Vec3; LANES];

        fn run<B: Backend>(self) -> [Vec3; LANES] {
            slerp_triangle_lanes::<B>(&self.arcs, &self.thirds, &self.weights).to_array()
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

    /// Every Phong triangle takes the lanes: a textured or tinted surface is lit through the
    /// surface stage (`varies`), with Nlerp or Slerp, and where its lighting is one colour (an
    /// unlit back side, the ambient term alone) too; an untextured one takes the lanes with
    /// Slerp too; the normals and depth views take every triangle, reading no texture.
    #[test]
    fn which_triangles_take_the_lanes() {
        let mut scene = scene(
            LightingModel::Phong,
            Vec3::ONE,
            BackFaces::Unlit,
            Lights::DirectionalAndPoint,
        );
        vary_surfaces(&mut scene, Surfaces::Textured);
        fn fast<'f>(
            frame: &'f Frame,
            triangle: &'f FrameTriangle,
            back_facing: bool,
        ) -> Option<FastPhong<'f>> {
            FastPhong::new(frame, triangle, back_facing, &mut LightingMemo::default())
        }
        for view in [None, Some(DebugView::Specular), Some(DebugView::Diffuse)] {
            let frame = frame_of(&scene, view);
            for triangle in &frame_triangles(&frame) {
                let front = fast(&frame, triangle, false).expect("a lit front side takes the lanes");
                assert!(front.varies(), "{view:?}");
                let back = fast(&frame, triangle, true).expect("an unlit back side takes the lanes");
                assert!(back.varies(), "an unlit back side, {view:?}");
            }
        }
        let frame = frame_of(&scene, Some(DebugView::Ambient));
        assert!(
            frame_triangles(&frame)
                .iter()
                .all(|t| fast(&frame, t, false).is_some_and(|shader| shader.varies())),
            "the ambient term alone of a varying surface takes the surface lanes"
        );
        for view in [DebugView::Normals, DebugView::Depth] {
            let frame = frame_of(&scene, Some(view));
            for triangle in &frame_triangles(&frame) {
                for back_facing in [false, true] {
                    let shader = fast(&frame, triangle, back_facing).expect("debug views take the lanes");
                    assert!(!shader.varies(), "{view:?}");
                }
            }
        }
        let mut slerped = scene.clone();
        slerped.objects[1].normal_interpolation = NormalInterpolation::Slerp;
        let frame = frame_of(&slerped, None);
        let triangles = frame_triangles(&frame);
        let (first, last) = (&triangles[0], triangles.last().expect("triangles"));
        assert!(fast(&frame, first, false).is_some_and(|shader| shader.varies()));
        assert!(
            fast(&frame, last, false).is_some_and(|shader| shader.varies()),
            "a varying surface with Slerp takes the surface lanes"
        );
        // Without textures or tints, Slerp and the unlit back side take the lanes.
        let mut plain = self::scene(
            LightingModel::Phong,
            Vec3::ONE,
            BackFaces::Unlit,
            Lights::DirectionalAndPoint,
        );
        plain.objects[1].normal_interpolation = NormalInterpolation::Slerp;
        let frame = frame_of(&plain, None);
        for triangle in &frame_triangles(&frame) {
            for back_facing in [false, true] {
                let shader =
                    fast(&frame, triangle, back_facing).expect("an untextured surface takes the lanes");
                assert!(!shader.varies());
            }
        }
        let tinted = scene;
        let (image, _) = render(&tinted, &RenderOptions::default());
        assert!(image.to_coverage().iter().any(|&c| c));
    }
}
