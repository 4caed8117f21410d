//! Shadow maps: the seeds' shadow term `S_i` (seed 001), one depth image per shadow-casting light.
//!
//! Each map is rendered by the depth pass (`depth`: the image's clipping, setup and coverage
//! loop, depth only, nothing culled), from the light's point of view:
//! - a directional light looks along its direction with an orthographic projection that just
//!   contains the bounding sphere of every object;
//! - a spot light looks down its axis with a perspective projection covering its cone (up to a
//!   60° cutoff; wider cones use the point-light cube);
//! - a point light renders six 92° perspective faces, one per axis direction (a cube map; the 2°
//!   overlap keeps filter footprints inside a face at the seams).
//!
//! A surface point is tested against the map like this: it is moved along its normal by `bias`
//! texels of the map at its distance (normal-offset bias, which removes self-shadowing "acne"
//! on slopes without the detached shadows, "peter-panning", of a large depth offset), projected
//! into the light's clip space, and compared with the (2r+1)² nearest texels
//! (percentage-closer filtering): the share of texels that do not hold a nearer surface is the
//! light's visibility, between 0 and 1. Points outside a map are lit. The lane lighting looks
//! eight points up at once ([`ShadowMap::visibility_lanes`]: the projection, the tests that a
//! point is in the map and that its block is inside it lane-wise; a 3×3 block read a row of
//! four texels at a time and compared at once, a 5×5 one gathered into lanes and compared
//! lane-wise), with the bits of the one-point lookup.
//!
//! Depth is reversed (1 at the light's near plane), so "nearer to the light" is "greater".
//! Everything is computed in the frame's eye-relative space, and the maps are deterministic
//! like the image.

use std::sync::Arc;

use glam::{DMat4, DVec3, Mat4, Vec3, Vec4, Vec4Swizzles};

use crate::render::depth::render_depth;
use crate::render::geometry::{CameraSetup, SpareBuffers};
use crate::render::lanes::{Backend, Floats, Ints, LANES, Mask, Native, Real, Vec3s};
use crate::scene::{BoundingSphere, Camera, Light, Projection, Scene, ShadowSettings, sphere_around_boxes};

/// Spot lights with a wider cutoff than this use the six-face cube, like point lights: a single
/// perspective face would need a field of view too wide to keep texels usefully small.
const MAX_SINGLE_FACE_CUTOFF_DEGREES: f32 = 60.0;
/// Field of view of each cube face: 90° plus a margin so filtering at a face's edge stays inside.
const CUBE_FACE_FOV_DEGREES: f64 = 92.0;

/// The depth image of one view from a light.
#[derive(Debug, Clone, PartialEq)]
struct ShadowFace {
    /// From the frame's eye-relative space to this face's clip space.
    clip_from_frame: Mat4,
    size: u32,
    /// Reversed-Z depth of the nearest surface per texel, row-major from the top; −∞ where none.
    depth: Vec<f32>,
    /// Per tile of the map, whether every texel of it is −∞ (see `depth::render_depth`): kept
    /// with `depth` for the next frame's map.
    blank_tiles: Vec<bool>,
    /// World size of one texel: at unit distance along `forward` (perspective) or everywhere
    /// (orthographic).
    texel_size: f32,
    perspective: bool,
    /// The last row of `clip_from_frame` is `(0, 0, 0, 1)` (an orthographic face): `w` is 1.
    affine: bool,
    /// Where the light is (perspective) in the frame's eye-relative space, and where it looks.
    origin: Vec3,
    forward: Vec3,
}

/// Where eight points are compared with a face ([`ShadowFace::lookup_lanes`]): the lanes
/// looked up, their texels' columns and rows (meaningless in the other lanes) and depths.
#[derive(Debug, Clone, Copy)]
struct TexelLanes<B: Backend> {
    looked_up: Mask<B>,
    columns: Ints<B>,
    rows: Ints<B>,
    depth: Floats<B>,
}

/// A light's shadow map: one face, or six for a point light.
#[derive(Debug, Clone, PartialEq)]
pub struct ShadowMap {
    faces: Vec<ShadowFace>,
    settings: ShadowSettings,
}

impl ShadowMap {
    /// The share of the light that reaches `position` (eye-relative), whose shading normal is
    /// `normal`, from the direction `to_light`: 1 lit, 0 in shadow.
    pub fn visibility(&self, position: Vec3, normal: Vec3, to_light: Vec3) -> f32 {
        match self.face_towards(to_light) {
            Some(face) => self.faces[face].visibility(position, normal, &self.settings),
            None => 1.0,
        }
    }

    /// How many faces the map has: one, or six for a cube.
    pub fn face_count(&self) -> usize {
        self.faces.len()
    }

    /// [`ShadowMap::visibility`] of eight points at once, where `wanted` holds (1 elsewhere):
    /// each lane has the bits of the one-point call. The projection into the light's view, the
    /// normal offset and the tests that the point is in the map are computed lane-wise; for
    /// filters up to radius 2 each lane's block is counted with one bounds check
    /// (`ShadowFace::lit_lanes`; radius 3 and up, and eight points of which some block
    /// reaches over the map's border, count lane after lane, clamping). A one-face map is looked up
    /// on the caller's backend `B`; a cube on the native one, out of line.
    #[inline(always)]
    pub fn visibility_lanes<B: Backend>(
        &self,
        position: Vec3s<B>,
        normal: Vec3s<B>,
        to_light: Vec3s<B>,
        wanted: Mask<B>,
    ) -> Floats<B> {
        match self.faces.as_slice() {
            [face] => face.visibility_lanes(position, normal, &self.settings, wanted),
            _ => self
                .cube_visibility_lanes(position.on(), normal.on(), to_light.on(), wanted.on())
                .on(),
        }
    }

    /// [`ShadowMap::visibility_lanes`] of a cube: each lane's face picked as the one-point call
    /// picks it, then the lanes of each face that some lane looks at, together. Out of line, so
    /// that the one-face lookup stays small where the lighting inlines it.
    #[inline(never)]
    fn cube_visibility_lanes(&self, position: Vec3s, normal: Vec3s, to_light: Vec3s, wanted: Mask) -> Floats {
        let directions = to_light.to_array();
        let faces: [Option<usize>; LANES] = std::array::from_fn(|lane| {
            wanted
                .lane(lane)
                .then(|| self.face_towards(directions[lane]))
                .flatten()
        });
        let mut visibility = Floats::splat(1.0);
        for (index, face) in self.faces.iter().enumerate() {
            let on_face = Mask::from_bools(faces.map(|f| f == Some(index)));
            if on_face.any() {
                let seen = face.visibility_lanes(position, normal, &self.settings, on_face);
                visibility = on_face.select(seen, visibility);
            }
        }
        visibility
    }

    /// The face that holds what the light sees in the direction opposite to `to_light`: the only
    /// one, or the cube face whose axis is closest to that direction.
    #[inline]
    fn face_towards(&self, to_light: Vec3) -> Option<usize> {
        if self.faces.len() == 1 {
            return Some(0);
        }
        let direction = -to_light;
        self.faces
            .iter()
            .enumerate()
            .max_by(|(_, a), (_, b)| a.forward.dot(direction).total_cmp(&b.forward.dot(direction)))
            .map(|(index, _)| index)
    }
}

/// The visibility of eight points from a light with shadow map `map`
/// ([`ShadowMap::visibility_lanes`] where `wanted` holds, 1 elsewhere), or 1 everywhere for a
/// light without one.
#[inline(always)]
pub fn shadow_visibility_lanes<B: Backend>(
    map: Option<&ShadowMap>,
    position: Vec3s<B>,
    normal: Vec3s<B>,
    to_light: Vec3s<B>,
    wanted: Mask<B>,
) -> Floats<B> {
    match map {
        Some(map) => map.visibility_lanes(position, normal, to_light, wanted),
        None => Floats::splat(1.0),
    }
}

impl ShadowFace {
    fn visibility(&self, position: Vec3, normal: Vec3, settings: &ShadowSettings) -> f32 {
        let Some((x, y, depth)) = self.lookup(position, normal, settings) else {
            return 1.0;
        };
        let radius = i64::from(settings.filter_radius);
        let side = 2 * radius + 1;
        let lit = lit_texels(&self.depth, i64::from(self.size), x, y, radius, depth);
        lit as f32 / (side * side) as u32 as f32
    }

    /// Where the point at `position` with the shading normal `normal` is compared with the map:
    /// its texel (column, row) and its depth; `None` outside the face (lit).
    #[inline]
    fn lookup(&self, position: Vec3, normal: Vec3, settings: &ShadowSettings) -> Option<(i64, i64, f32)> {
        let texel = if self.perspective {
            self.texel_size * (position - self.origin).dot(self.forward).max(0.0)
        } else {
            self.texel_size
        };
        // A point `b` above a plane tilted by θ from the light clears every texel within `d` of
        // it when b > d·sin θ: the filter reaches r + ½ texels (nearest-texel rounding), so the
        // offset is the filter's reach plus the user's bias, which covers every slope.
        let reach = settings.filter_radius as f32 + 0.5;
        let offset = position + normal * ((settings.bias + reach) * texel);
        let clip = self.clip_from_frame * offset.extend(1.0);
        if clip.w.is_nan() || clip.w <= 0.0 {
            return None;
        }
        let ndc = clip.xyz() / clip.w;
        if !ndc.is_finite() || ndc.x.abs() > 1.0 || ndc.y.abs() > 1.0 || ndc.z > 1.0 {
            return None;
        }
        let size = self.size as i64;
        let x = (((ndc.x + 1.0) * 0.5 * self.size as f32) as i64).clamp(0, size - 1);
        let y = (((1.0 - ndc.y) * 0.5 * self.size as f32) as i64).clamp(0, size - 1);
        Some((x, y, ndc.z))
    }

    /// [`ShadowFace::visibility`] lane by lane where `wanted` holds (1 elsewhere).
    #[inline(always)]
    fn visibility_lanes<B: Backend>(
        &self,
        position: Vec3s<B>,
        normal: Vec3s<B>,
        settings: &ShadowSettings,
        wanted: Mask<B>,
    ) -> Floats<B> {
        let one = Floats::splat(1.0);
        let texels = self.lookup_lanes(position, normal, settings, wanted);
        if !texels.looked_up.any() {
            return one;
        }
        let lit = match settings.filter_radius {
            0 => self.lit_lanes::<B, 1>(texels),
            1 => self.lit_lanes::<B, 3>(texels),
            2 => self.lit_lanes::<B, 5>(texels),
            radius => self.lit_lanes_clamped(texels.on(), i64::from(radius)).on(),
        };
        let side = 2 * i64::from(settings.filter_radius) + 1;
        texels
            .looked_up
            .select(lit / Floats::splat((side * side) as u32 as f32), one)
    }

    /// [`lit_texels`] of the `SIDE`² blocks (`SIDE` = 2r + 1) around the texels of the lanes
    /// looked up (anything elsewhere), as floats. When every such block lies inside the map
    /// (nearly always), the border is tested once per lane, lane-wise, and each block is read
    /// with one bounds check: up to four texels wide a row at a time
    /// ([`ShadowFace::lit_in_rows_of_four`]), else gathered into lanes and compared texel by
    /// texel; the count is the same integer. Otherwise lane by lane, clamping at the border.
    #[inline(always)]
    fn lit_lanes<B: Backend, const SIDE: usize>(&self, texels: TexelLanes<B>) -> Floats<B> {
        let TexelLanes {
            looked_up,
            columns,
            rows,
            depth,
        } = texels;
        let radius = (SIDE / 2) as i32;
        // A block is inside when its first column and row are at least 0 and its last ones at
        // most size − 1 (the size is below 2²³, so nothing wraps).
        let (low, high) = (Ints::splat(radius - 1), Ints::splat(self.size as i32 - radius));
        let inside = columns
            .gt(low)
            .and(rows.gt(low))
            .and(high.gt(columns))
            .and(high.gt(rows));
        if looked_up.and(!inside).any() {
            return self.lit_lanes_clamped(texels.on(), i64::from(radius)).on();
        }
        // The lanes not looked up read the map's first block (some lane's block is inside, so
        // the map holds one); their counts are not used.
        let first_columns = looked_up.select_ints(columns - Ints::splat(radius), Ints::splat(0));
        let first_rows = looked_up.select_ints(rows - Ints::splat(radius), Ints::splat(0));
        let stride = self.size as usize;
        if SIDE <= 4
            && let Some(lit) = self.lit_in_rows_of_four::<SIDE>(first_rows.0, first_columns.0, depth.0)
        {
            return Ints::<B>::new(lit).to_floats();
        }
        // Each lane's block, by row and column.
        let mut blocks = [[[0.0f32; LANES]; SIDE]; SIDE];
        let firsts = first_rows.0.iter().zip(&first_columns.0);
        for (lane, (&first_row, &first_column)) in firsts.enumerate() {
            let first = first_row as usize * stride + first_column as usize;
            let block = &self.depth[first..first + (SIDE - 1) * stride + SIDE];
            for (row, block_row) in blocks.iter_mut().enumerate() {
                let start = row * stride;
                for (lanes, &texel) in block_row.iter_mut().zip(&block[start..start + SIDE]) {
                    lanes[lane] = texel;
                }
            }
        }
        // A mask is −1 where it holds: subtracting each texel's counts it.
        let mut lit = Ints::splat(0);
        for &texels in blocks.iter().flatten() {
            lit = lit - Floats::new(texels).le(depth).to_ints();
        }
        lit.to_floats()
    }

    /// [`lit_texels`] of the `SIDE`² blocks (`SIDE` ≤ 4) whose first rows and columns are
    /// `first_rows` and `first_columns`, each lane against its `depth`: each row of a block read
    /// as four texels and compared at once (`cmpleps`), the comparisons' bits beyond the block
    /// masked off and counted. `None` when some lane's last row has fewer than four texels
    /// left in the map (the blocks at its last texel), which the caller counts another way.
    /// The counts are the same integers.
    #[inline(always)]
    fn lit_in_rows_of_four<const SIDE: usize>(
        &self,
        first_rows: [i32; LANES],
        first_columns: [i32; LANES],
        depth: [f32; LANES],
    ) -> Option<[i32; LANES]> {
        let stride = self.size as usize;
        let in_block = (1u32 << SIDE) - 1;
        let mut lit = [0i32; LANES];
        for lane in 0..LANES {
            let first = first_rows[lane] as usize * stride + first_columns[lane] as usize;
            let block = self.depth.get(first..first + (SIDE - 1) * stride + 4)?;
            let depth = Vec4::splat(depth[lane]);
            for row in 0..SIDE {
                let texels = Vec4::from_slice(&block[row * stride..]);
                lit[lane] += (texels.cmple(depth).bitmask() & in_block).count_ones() as i32;
            }
        }
        Some(lit)
    }

    /// [`lit_texels`] of the lanes looked up (0 elsewhere) one lane at a time, as floats: out
    /// of line, on the native backend.
    #[inline(never)]
    fn lit_lanes_clamped(&self, texels: TexelLanes<Native>, radius: i64) -> Floats {
        Floats::new(std::array::from_fn(|lane| {
            if !texels.looked_up.lane(lane) {
                return 0.0;
            }
            let (x, y) = (i64::from(texels.columns.0[lane]), i64::from(texels.rows.0[lane]));
            lit_texels(
                &self.depth,
                i64::from(self.size),
                x,
                y,
                radius,
                texels.depth.0[lane],
            ) as f32
        }))
    }

    /// [`ShadowFace::lookup`] of eight points, where `wanted` holds. The same
    /// operations in the same order, glam's `Mat4 * Vec4` being
    /// `((x_axis·x + y_axis·y) + z_axis·z) + w_axis·w`, each `None` a mask.
    #[inline(always)]
    fn lookup_lanes<B: Backend>(
        &self,
        position: Vec3s<B>,
        normal: Vec3s<B>,
        settings: &ShadowSettings,
        wanted: Mask<B>,
    ) -> TexelLanes<B> {
        let texel = if self.perspective {
            let along = (position - Vec3s::splat(self.origin)).dot(Vec3s::splat(self.forward));
            Floats::splat(self.texel_size) * along.max(Floats::splat(0.0))
        } else {
            Floats::splat(self.texel_size)
        };
        let reach = settings.filter_radius as f32 + 0.5;
        let offset = position + normal.scale(Floats::splat(settings.bias + reach) * texel);
        let matrix = &self.clip_from_frame;
        let clip = Vec3s {
            x: matrix_row(matrix, 0, offset),
            y: matrix_row(matrix, 1, offset),
            z: matrix_row(matrix, 2, offset),
        };
        let (ndc, in_front) = if self.affine {
            // `w = ((0·x + 0·y) + 0·z) + 1·1` is exactly 1 for a finite offset, and dividing by
            // 1 changes nothing. A non-finite offset makes x, y and z non-finite too (`0·∞` and
            // `a·∞` both are), which the test below turns away as the scalar test of `w` does.
            (clip, Mask::ALL)
        } else {
            let w = matrix_row(matrix, 3, offset);
            // `w > 0` is false for NaN: the scalar test's `is_nan() || <= 0`, negated.
            (clip.divide(w), w.gt(Floats::splat(0.0)))
        };
        let (one, minus_one) = (Floats::splat(1.0), Floats::splat(-1.0));
        // For finite values `|v| > 1` is `v > 1 ∨ v < −1`.
        let inside = ndc
            .x
            .is_finite()
            .and(ndc.y.is_finite())
            .and(ndc.z.is_finite())
            .and(ndc.x.le(one))
            .and(minus_one.le(ndc.x))
            .and(ndc.y.le(one))
            .and(minus_one.le(ndc.y))
            .and(!ndc.z.gt(one));
        let looked_up = wanted.and(in_front).and(inside);
        let (half, scale) = (Floats::splat(0.5), Floats::splat(self.size as f32));
        let columns = ((ndc.x + one) * half) * scale;
        let rows = ((one - ndc.y) * half) * scale;
        // In a lane looked up, `columns` and `rows` lie in [0, size] (the point's `ndc` in
        // [−1, 1]): limited to the last texel and truncated, they are the scalar lookup's
        // conversion clamped to the map. Every lane at once: the truncated value, a whole
        // number below 2²³ (maps are at most 8192 texels a side), plus 2²³ has the number in
        // the low bits of its mantissa.
        debug_assert!(self.size <= 1 << 23);
        let last = Floats::splat((self.size - 1) as f32);
        TexelLanes {
            looked_up,
            columns: texel_index(columns, last),
            rows: texel_index(rows, last),
            depth: ndc.z,
        }
    }
}

/// The texel arrays of the last frame's shadow maps, to render the next frame's maps in: a
/// stream of frames then allocates nothing big for its maps after the first (their triangles are
/// set up in the image's spare arrays, `geometry::SpareBuffers`), and the depth pass leaves the
/// tiles that stay empty alone. Which arrays are reused changes no texel: the depth pass writes
/// every texel it does not know to hold −∞ already.
#[derive(Default)]
pub struct ShadowBuffers {
    /// Each array with its blank tiles (`ShadowFace::blank_tiles`).
    texels: Vec<(Vec<f32>, Vec<bool>)>,
}

impl ShadowBuffers {
    /// Keeps the texel arrays of `maps` (those no one else holds) for the next frame.
    pub fn keep(&mut self, maps: Vec<Option<Arc<ShadowMap>>>) {
        for map in maps.into_iter().flatten() {
            if let Ok(map) = Arc::try_unwrap(map) {
                self.texels
                    .extend(map.faces.into_iter().map(|face| (face.depth, face.blank_tiles)));
            }
        }
    }

    /// A texel array of `count` elements, whose values are to be overwritten, with the tiles
    /// known to be blank in it (none, unless it held a map of the same size).
    fn texels(&mut self, count: usize) -> (Vec<f32>, Vec<bool>) {
        // An array of the same size first: its blank tiles stay known.
        let same = self.texels.iter().position(|(texels, _)| texels.len() == count);
        match same
            .map(|at| self.texels.swap_remove(at))
            .or_else(|| self.texels.pop())
        {
            Some((mut texels, mut blank_tiles)) => {
                if texels.len() != count {
                    texels.resize(count, 0.0);
                    blank_tiles.clear();
                }
                (texels, blank_tiles)
            }
            // Zeroed pages from the allocator, not a fill.
            None => (vec![0.0; count], Vec::new()),
        }
    }
}

/// Renders the shadow map of every light that casts shadows (`None` for the others), in the
/// eye-relative space of a frame whose eye is `frame_eye`, in the arrays of `buffers` and
/// `spare` (before the frame's geometry takes them).
pub fn render_shadow_maps(
    scene: &Scene,
    frame_eye: DVec3,
    buffers: &mut ShadowBuffers,
    spare: &mut SpareBuffers,
) -> Vec<Option<Arc<ShadowMap>>> {
    // Each mesh's bounds read all its vertices: found once, on the first light that casts a
    // shadow (never for a scene without shadows), for the test of which objects are seen, the
    // maps' fit and their back faces.
    let mut mesh_bounds = None;
    let mut seen = None;
    let mut fit = None;
    scene
        .lights
        .iter()
        .map(|light| {
            let settings = light.shadow()?;
            let mesh_bounds: &Vec<Option<(Vec3, Vec3)>> =
                mesh_bounds.get_or_insert_with(|| each_mesh_bounds(scene));
            let seen: &Vec<BoundingSphere> = seen.get_or_insert_with(|| seen_bounds(scene, mesh_bounds));
            if !lights_any(light, seen) {
                return None;
            }
            let fit = *fit.get_or_insert_with(|| {
                sphere_around_boxes(scene.objects.iter().zip(mesh_bounds.iter().copied()))
            });
            let casters = Casters { scene, mesh_bounds };
            Some(Arc::new(render_map(
                casters, light, settings, fit, frame_eye, buffers, spare,
            )))
        })
        .collect()
}

/// [`Mesh::bounds`](crate::mesh::Mesh::bounds) of each object's mesh, in the scene's order.
pub(crate) fn each_mesh_bounds(scene: &Scene) -> Vec<Option<(Vec3, Vec3)>> {
    scene.objects.iter().map(|object| object.mesh.bounds()).collect()
}

/// What the shadow maps are rendered of: the scene's objects, with their meshes' bounds
/// ([`Mesh::bounds`](crate::mesh::Mesh::bounds), one per object), found once for every map.
#[derive(Clone, Copy)]
struct Casters<'s> {
    scene: &'s Scene,
    mesh_bounds: &'s [Option<(Vec3, Vec3)>],
}

/// The shadow map of `light` with `settings`, fitted to `bounds`, the bounds of every object.
fn render_map(
    casters: Casters,
    light: &Light,
    settings: ShadowSettings,
    bounds: BoundingSphere,
    frame_eye: DVec3,
    buffers: &mut ShadowBuffers,
    spare: &mut SpareBuffers,
) -> ShadowMap {
    let faces = light_views(light, bounds, settings.resolution)
        .into_iter()
        .map(|(camera, size)| render_face(casters, &camera, size, frame_eye, buffers, spare))
        .collect();
    ShadowMap { faces, settings }
}

/// The bounding spheres of the objects whose bounds reach into the camera's view volume: only
/// points of those are ever lit (pixels, flat triangles and Gouraud vertices of triangles that
/// cover a sample, constant colours that are shown), so only they can read a shadow map. Each
/// object's mesh has the bounds `mesh_bounds` holds.
fn seen_bounds(scene: &Scene, mesh_bounds: &[Option<(Vec3, Vec3)>]) -> Vec<BoundingSphere> {
    let camera = CameraSetup::new(
        &scene.camera,
        f64::from(scene.image.width) / f64::from(scene.image.height),
    );
    // The six planes of the clip volume, `|x| ≤ w`, `|y| ≤ w`, `0 ≤ z ≤ w`, in eye-relative
    // world space.
    let matrix = camera.clip_from_world;
    let [x, y, z, w] = [0, 1, 2, 3].map(|row| matrix.row(row));
    let planes = [w + x, w - x, w + y, w - y, z, w - z];
    scene
        .objects
        .iter()
        .zip(mesh_bounds)
        .map(|(object, &bounds)| sphere_around_boxes([(object, bounds)]))
        .filter(|sphere| {
            let center = sphere.center - camera.eye;
            // A margin for the rounding of positions to `f32` on the way.
            let radius = sphere.radius * 1.001 + center.length() * 1e-6;
            planes.iter().all(|plane| {
                let normal = plane.truncate();
                normal.dot(center) + plane.w >= -radius * normal.length()
            })
        })
        .collect()
}

/// Whether `light` may light some point of the spheres `seen`, so that some lookup may read its
/// shadow map: a spot light lights only its cone (elsewhere the lighting asks no visibility),
/// the other lights every point that faces them.
fn lights_any(light: &Light, seen: &[BoundingSphere]) -> bool {
    let Light::Spot {
        position,
        direction,
        cutoff_degrees,
        ..
    } = *light
    else {
        return !seen.is_empty();
    };
    let axis = direction.as_dvec3().normalize_or_zero();
    if axis == DVec3::ZERO {
        return !seen.is_empty();
    }
    // The lighting compares `f32` cosines: a margin of a thousandth of a radian covers their
    // rounding.
    let cone = f64::from(cutoff_degrees).to_radians() + 1e-3;
    seen.iter().any(|sphere| {
        let offset = sphere.center - position;
        let distance = offset.length();
        let radius = sphere.radius * 1.001;
        if distance <= radius {
            return true;
        }
        let angle = (offset.dot(axis) / distance).clamp(-1.0, 1.0).acos();
        angle <= cone + (radius / distance).asin()
    })
}

/// Any unit vector not parallel to `forward`, for a camera's `up`.
fn up_for(forward: DVec3) -> DVec3 {
    if forward.y.abs() < 0.9 { DVec3::Y } else { DVec3::Z }
}

/// Row `axis` of `matrix · (offset, 1)` in lanes, in glam's order for `Mat4 * Vec4`:
/// `((x_axis·x + y_axis·y) + z_axis·z) + w_axis·1`. A function rather than a closure, so that
/// it inlines into the widest lanes' code.
#[inline(always)]
fn matrix_row<B: Backend>(matrix: &Mat4, axis: usize, offset: Vec3s<B>) -> Floats<B> {
    let column = |c: glam::Vec4| Floats::<B>::splat(c[axis]);
    ((column(matrix.x_axis) * offset.x + column(matrix.y_axis) * offset.y) + column(matrix.z_axis) * offset.z)
        + column(matrix.w_axis * 1.0)
}

/// The texel of each lane's `coordinate` (in [0, size]), limited to the last texel `last` and
/// truncated: the truncated value, a whole number below 2²³, plus 2²³ has the number in the
/// low bits of its mantissa.
#[inline(always)]
fn texel_index<B: Backend>(coordinate: Floats<B>, last: Floats<B>) -> Ints<B> {
    let mantissa = Floats::splat((1 << 23) as f32);
    (coordinate.min(last).trunc() + mantissa).to_bits() - mantissa.to_bits()
}

impl<B: Backend> TexelLanes<B> {
    /// The same lanes on backend `C`.
    #[inline(always)]
    fn on<C: Backend>(self) -> TexelLanes<C> {
        TexelLanes {
            looked_up: self.looked_up.on(),
            columns: self.columns.on(),
            rows: self.rows.on(),
            depth: self.depth.on(),
        }
    }
}

/// How many texels of the (2r+1)² block centred on texel `(x, y)` of a `size`² map do not hold a
/// surface nearer the light than `depth` (reversed Z: nearer is greater); texels beyond the
/// border repeat the nearest edge texel.
#[inline(always)]
fn lit_texels(map: &[f32], size: i64, x: i64, y: i64, radius: i64, depth: f32) -> u32 {
    if x >= radius && y >= radius && x + radius < size && y + radius < size {
        // The whole block inside the map (nearly every lookup): its rows as slices, no clamping
        // per texel, and for the common radii rows of a known length. The count is the same
        // integer either way.
        let first = ((y - radius) * size + x - radius) as usize;
        let stride = size as usize;
        match radius {
            1 => lit_in_block::<3>(map, first, stride, depth),
            2 => lit_in_block::<5>(map, first, stride, depth),
            _ => {
                let side = (2 * radius + 1) as usize;
                (0..side)
                    .map(|row| {
                        let start = first + row * stride;
                        let texels = &map[start..start + side];
                        texels
                            .iter()
                            .map(|&occluder| u32::from(occluder <= depth))
                            .sum::<u32>()
                    })
                    .sum()
            }
        }
    } else {
        let mut lit = 0u32;
        for dy in -radius..=radius {
            for dx in -radius..=radius {
                let (tx, ty) = ((x + dx).clamp(0, size - 1), (y + dy).clamp(0, size - 1));
                lit += u32::from(map[(ty * size + tx) as usize] <= depth);
            }
        }
        lit
    }
}

/// [`lit_texels`] of a `SIDE`² block wholly inside the map whose first texel is `map[first]`,
/// its rows `stride` apart: each row one bounds check, its texels compared unrolled.
#[inline(always)]
fn lit_in_block<const SIDE: usize>(map: &[f32], first: usize, stride: usize, depth: f32) -> u32 {
    let mut lit = 0;
    for row in 0..SIDE {
        let start = first + row * stride;
        let texels: &[f32; SIDE] = map[start..start + SIDE]
            .try_into()
            .expect("a slice of SIDE texels");
        for &occluder in texels {
            lit += u32::from(occluder <= depth);
        }
    }
    lit
}

/// The cameras (and map sizes) a light's shadow map is rendered from.
pub(crate) fn light_views(light: &Light, bounds: BoundingSphere, resolution: u32) -> Vec<(Camera, u32)> {
    let cube = |position: DVec3| -> Vec<(Camera, u32)> {
        let reach = (bounds.center - position).length() + bounds.radius;
        [DVec3::X, -DVec3::X, DVec3::Y, -DVec3::Y, DVec3::Z, -DVec3::Z]
            .into_iter()
            .map(|axis| {
                let camera = Camera {
                    eye: position,
                    target: position + axis,
                    up: up_for(axis),
                    projection: Projection::Perspective {
                        fov_y_degrees: CUBE_FACE_FOV_DEGREES,
                        near: (reach * 1e-5).max(1e-6),
                        far: reach * 1.01 + 1e-6,
                    },
                };
                (camera, (resolution / 2).max(16))
            })
            .collect()
    };
    match *light {
        Light::Directional { direction, .. } => {
            let direction = direction.as_dvec3().normalize_or(DVec3::NEG_Y);
            let eye = bounds.center - direction * (2.0 * bounds.radius);
            let camera = Camera {
                eye,
                target: bounds.center,
                up: up_for(direction),
                projection: Projection::Orthographic {
                    height: 2.0 * bounds.radius * 1.01,
                    near: bounds.radius * 0.5,
                    far: bounds.radius * 3.5,
                },
            };
            vec![(camera, resolution)]
        }
        Light::Point { position, .. } => cube(position),
        Light::Spot {
            position,
            direction,
            cutoff_degrees,
            ..
        } => {
            if cutoff_degrees > MAX_SINGLE_FACE_CUTOFF_DEGREES {
                return cube(position);
            }
            let axis = direction.as_dvec3().normalize_or(DVec3::NEG_Y);
            let reach = (bounds.center - position).length() + bounds.radius;
            let camera = Camera {
                eye: position,
                target: position + axis,
                up: up_for(axis),
                projection: Projection::Perspective {
                    fov_y_degrees: f64::from(2.0 * cutoff_degrees + 4.0),
                    near: (reach * 1e-5).max(1e-6),
                    far: reach * 1.01 + 1e-6,
                },
            };
            vec![(camera, resolution)]
        }
    }
}

/// Renders one face's depth, and its mapping from the frame's eye-relative space.
fn render_face(
    casters: Casters,
    camera: &Camera,
    size: u32,
    frame_eye: DVec3,
    buffers: &mut ShadowBuffers,
    spare: &mut SpareBuffers,
) -> ShadowFace {
    let side = size as usize;
    let (mut depth, mut blank_tiles) = buffers.texels(side * side);
    render_depth(
        casters.scene,
        casters.mesh_bounds,
        camera,
        size,
        &mut depth,
        &mut blank_tiles,
        spare,
    );
    let setup = CameraSetup::new(camera, 1.0);
    let clip_from_frame = setup.clip_from_world * DMat4::from_translation(frame_eye - camera.eye);
    let (texel_size, perspective) = match camera.projection {
        Projection::Perspective { fov_y_degrees, .. } => (
            (2.0 * (fov_y_degrees.to_radians() / 2.0).tan() / f64::from(size)) as f32,
            true,
        ),
        Projection::Orthographic { height, .. } => ((height / f64::from(size)) as f32, false),
    };
    ShadowFace {
        clip_from_frame: clip_from_frame.as_mat4(),
        affine: clip_from_frame.as_mat4().row(3) == glam::Vec4::W,
        size,
        depth,
        blank_tiles,
        texel_size,
        perspective,
        origin: (camera.eye - frame_eye).as_vec3(),
        forward: setup.forward.as_vec3(),
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::render::lanes::{LaneWork, run_widest};

    /// A shadow-casting light of each kind and map shape: directional (orthographic), a narrow
    /// spot (one perspective face), a wide spot and a point light (six cube faces); filters of
    /// radius 0, 1 and 2.
    pub(crate) fn shadowed_lights() -> Vec<Light> {
        use crate::scene::Attenuation;
        let settings = |filter_radius| {
            Some(ShadowSettings {
                resolution: 128,
                bias: 1.0,
                filter_radius,
            })
        };
        vec![
            Light::Directional {
                direction: Vec3::new(-1.0, 0.15, -0.25).normalize(),
                color: Vec3::ONE,
                shadow: settings(1),
            },
            Light::Spot {
                position: DVec3::new(4.0, -1.5, 0.8),
                direction: Vec3::new(-5.2, 1.5, -0.8).normalize(),
                color: Vec3::ONE,
                cutoff_degrees: 25.0,
                exponent: 2.0,
                attenuation: Attenuation::NONE,
                shadow: settings(2),
            },
            Light::Spot {
                position: DVec3::new(0.3, -0.4, 2.5),
                direction: Vec3::new(0.0, 0.1, -1.0).normalize(),
                color: Vec3::ONE,
                cutoff_degrees: 75.0,
                exponent: 2.0,
                attenuation: Attenuation::NONE,
                shadow: settings(0),
            },
            Light::Point {
                position: DVec3::new(0.1, -2.0, 0.4),
                color: Vec3::ONE,
                attenuation: Attenuation::NONE,
                shadow: settings(1),
            },
        ]
    }

    /// [`ShadowMap::visibility_lanes`] of eight points, as lane work.
    #[derive(Clone, Copy)]
    struct Lookup<'m> {
        map: &'m ShadowMap,
        positions: [Vec3; LANES],
        normals: [Vec3; LANES],
        to_light: [Vec3; LANES],
        wanted: [bool; LANES],
    }

    impl LaneWork for Lookup<'_> {
        type Output = [f32; LANES];

        fn run<B: Backend>(self) -> [f32; LANES] {
            self.map
                .visibility_lanes(
                    Vec3s::<B>::from_array(&self.positions),
                    Vec3s::from_array(&self.normals),
                    Vec3s::from_array(&self.to_light),
                    Mask::from_bools(self.wanted),
                )
                .0
        }
    }

    /// Eight points at once against the one-point lookup, bit for bit, on the native and the
    /// widest lanes, for every kind of light and map: points on the surfaces (with their
    /// normals, reversed, zero, and grazing the light), points all around and behind the light,
    /// points that fall on the map's border texels and just outside it, groups whose filter
    /// blocks all end at or reach over the border or end at the map's last texel, and lanes
    /// left out.
    #[test]
    fn lookups_in_lanes_equal_the_one_point_lookup_bit_for_bit() {
        use crate::render::shade_fast::tests::{LIGHTS, scene};
        use crate::scene::{BackFaces, LightingModel};
        let mut scene = scene(LightingModel::Phong, Vec3::ONE, BackFaces::Lit, LIGHTS[0]);
        scene.lights = shadowed_lights();
        let eye = scene.camera.eye;
        let maps = render_shadow_maps(
            &scene,
            eye,
            &mut ShadowBuffers::default(),
            &mut Default::default(),
        );
        let frame = crate::render::geometry::build_frame(
            &scene,
            crate::render::raster::SamplePattern::SINGLE,
            None,
            maps.clone(),
        );
        // A fixed pseudo-random sequence in [0, 1).
        let mut rng = crate::test_support::XorShift64::new(0x2545_f491_4f6c_dd1du64);
        let mut random = move || {
            let state = rng.next_u64();
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        for (light, map) in frame.lights.iter().zip(&maps) {
            let map = map.as_deref().expect("a shadow map");
            let to_light_from = |position: Vec3| match light.kind {
                crate::lighting::ShadingLightKind::Directional { to_light } => to_light,
                crate::lighting::ShadingLightKind::Point { position: at, .. }
                | crate::lighting::ShadingLightKind::Spot { position: at, .. } => {
                    (at - position).normalize_or_zero()
                }
            };
            // (position, normal) pairs.
            let mut points: Vec<(Vec3, Vec3)> = Vec::new();
            for (n, vertex) in frame.vertices.iter().enumerate() {
                let to_light = to_light_from(vertex.position);
                let grazing = (vertex.normal - to_light * vertex.normal.dot(to_light)).normalize_or_zero();
                let normal = match n % 4 {
                    0 => vertex.normal,
                    1 => -vertex.normal,
                    2 => grazing,
                    _ => Vec3::ZERO,
                };
                points.push((vertex.position, normal));
            }
            for _ in 0..2000 {
                let position =
                    Vec3::new(random(), random(), random()) * 16.0 - Vec3::splat(8.0) - eye.as_vec3();
                let normal = Vec3::new(random(), random(), random()) * 2.0 - Vec3::ONE;
                points.push((position, normal.normalize_or_zero()));
            }
            // Around each face's border: unprojected from just inside, on and just outside the
            // edges of its clip space (with no normal, so no offset moves them).
            for face in &map.faces {
                let frame_from_clip = face.clip_from_frame.inverse();
                for _ in 0..400 {
                    let edge = [1.0 - 1e-4, 1.0, 1.0 + 1e-4, 1.0 - 0.5 / face.size as f32]
                        [(random() * 4.0) as usize];
                    let along = random() * 2.0 - 1.0;
                    let side = if random() < 0.5 { -edge } else { edge };
                    let (x, y) = if random() < 0.5 {
                        (side, along)
                    } else {
                        (along, side)
                    };
                    let clip = frame_from_clip * glam::Vec4::new(x, y, random(), 1.0);
                    points.push((clip.truncate() / clip.w, Vec3::ZERO));
                }
            }
            // Groups of eight points at the centres of texels 0 to 3 in from one edge of a
            // face, each group at one distance: their filter blocks touch the border, reach over
            // it, or end just inside (the lane-wise block compares take those whole groups).
            while !points.len().is_multiple_of(LANES) {
                points.push((Vec3::ZERO, Vec3::ZERO));
            }
            for face in &map.faces {
                let frame_from_clip = face.clip_from_frame.inverse();
                for texels_in in 0..4 {
                    for edge in 0..4 {
                        let side = 1.0 - (texels_in as f32 + 0.5) * 2.0 / face.size as f32;
                        let side = if edge % 2 == 0 { side } else { -side };
                        for _ in 0..LANES {
                            let along = random() * 1.8 - 0.9;
                            let (x, y) = if edge < 2 { (side, along) } else { (along, side) };
                            let clip = frame_from_clip * glam::Vec4::new(x, y, random(), 1.0);
                            points.push((clip.truncate() / clip.w, Vec3::ZERO));
                        }
                    }
                }
            }
            // Groups of eight points at the centre of the texel `k` in from the last row and
            // column (the map's last corner): a block there ends within a texel or two of the
            // map's last texel, where a row of four texels would read past it.
            for face in &map.faces {
                let frame_from_clip = face.clip_from_frame.inverse();
                for k in 0..4 {
                    let side = 1.0 - (k as f32 + 0.5) * 2.0 / face.size as f32;
                    for _ in 0..LANES {
                        let clip = frame_from_clip * glam::Vec4::new(side, -side, random(), 1.0);
                        points.push((clip.truncate() / clip.w, Vec3::ZERO));
                    }
                }
            }
            let mut outcomes = [0usize; 3]; // dark, partly lit, lit
            let mut looked_up_count = 0;
            for (group, lanes) in points.chunks_exact(LANES).enumerate() {
                let positions: [Vec3; LANES] = std::array::from_fn(|i| lanes[i].0);
                let normals: [Vec3; LANES] = std::array::from_fn(|i| lanes[i].1);
                let to_light: [Vec3; LANES] = std::array::from_fn(|i| to_light_from(positions[i]));
                let wanted_lanes: [bool; LANES] = std::array::from_fn(|i| (group + i) % 11 != 0);
                let wanted = Mask::<Native>::from_bools(wanted_lanes);
                let work = Lookup {
                    map,
                    positions,
                    normals,
                    to_light,
                    wanted: wanted_lanes,
                };
                let (native, widest) = (work.run::<Native>(), run_widest(work));
                assert_eq!(
                    native.map(f32::to_bits),
                    widest.map(f32::to_bits),
                    "{light:?}: group {group} on the native and the widest lanes"
                );
                let lanes = Floats::<Native>::new(native);
                if let [face] = map.faces.as_slice() {
                    let TexelLanes {
                        looked_up,
                        columns,
                        rows,
                        depth: depths,
                    } = face.lookup_lanes(
                        Vec3s::from_array(&positions),
                        Vec3s::from_array(&normals),
                        &map.settings,
                        wanted,
                    );
                    for i in 0..LANES {
                        let one = face.lookup(positions[i], normals[i], &map.settings);
                        let lane = looked_up.lane(i).then(|| {
                            let texel = (i64::from(columns.0[i]), i64::from(rows.0[i]));
                            (texel, depths.0[i].to_bits())
                        });
                        let expected = one
                            .filter(|_| wanted.lane(i))
                            .map(|(x, y, depth)| ((x, y), depth.to_bits()));
                        assert_eq!(lane, expected, "{light:?}: lookup {i} of group {group}");
                        looked_up_count += usize::from(lane.is_some());
                    }
                }
                for i in 0..LANES {
                    let expected = if wanted.lane(i) {
                        map.visibility(positions[i], normals[i], to_light[i])
                    } else {
                        1.0
                    };
                    assert_eq!(
                        lanes.0[i].to_bits(),
                        expected.to_bits(),
                        "{light:?}: point {i} of group {group}, {:?}",
                        (positions[i], normals[i])
                    );
                    outcomes[usize::from(expected > 0.0) + usize::from(expected >= 1.0)] += 1;
                }
            }
            assert!(
                map.faces.len() > 1 || looked_up_count > 1000,
                "{looked_up_count} lookups"
            );
            // A filter of radius 0 has no partial shade.
            let partial_least = if map.settings.filter_radius == 0 { 0 } else { 20 };
            assert!(
                outcomes[0] > 20 && outcomes[1] >= partial_least && outcomes[2] > 20,
                "{light:?}: dark, partly lit, lit: {outcomes:?}"
            );
        }
    }

    /// A light that lights nothing the camera may see gets no map, and the image is the one
    /// every map gives, bit for bit: spot lights aimed beside the view and behind the camera
    /// are skipped, the others not, in every shading mode.
    #[test]
    fn maps_no_visible_point_reads_are_skipped_and_change_nothing() {
        use crate::render::framebuffer::TileTarget;
        use crate::render::raster::{SamplePattern, rasterize_tile};
        use crate::render::shade::{TileScratch, shade_tile};
        use crate::render::shade_fast::tests::{LIGHTS, scene};
        use crate::scene::{Attenuation, BackFaces, LightingModel, Shading};
        let mut scene = scene(LightingModel::Phong, Vec3::ONE, BackFaces::Lit, LIGHTS[2]);
        let spot = |position: DVec3, direction: Vec3, cutoff_degrees: f32| Light::Spot {
            position,
            direction: direction.normalize(),
            color: Vec3::splat(0.5),
            cutoff_degrees,
            exponent: 1.0,
            attenuation: Attenuation::NONE,
            shadow: Some(ShadowSettings {
                resolution: 64,
                bias: 1.0,
                filter_radius: 1,
            }),
        };
        let eye = scene.camera.eye;
        scene.lights.extend([
            // Beside the spheres, aimed away from them and from the view.
            spot(DVec3::new(6.0, 0.0, 0.0), Vec3::X, 20.0),
            // Behind the camera, aimed back at the scene through it: lights what it sees.
            spot(eye - DVec3::new(0.0, 2.0, 0.0), Vec3::new(0.0, 1.0, -0.2), 30.0),
            // Behind the camera, aimed further back: a wide cone (the cube) that lights nothing.
            spot(eye - DVec3::new(0.0, 2.0, 0.0), -Vec3::Y, 70.0),
        ]);
        let faces =
            |maps: &[Option<Arc<ShadowMap>>]| maps.iter().flatten().map(|m| m.face_count()).sum::<usize>();
        for shading in [Shading::Phong, Shading::Gouraud, Shading::Flat, Shading::Constant] {
            for object in &mut scene.objects {
                object.shading = shading;
            }
            let mut spare = SpareBuffers::default();
            let maps = render_shadow_maps(&scene, eye, &mut ShadowBuffers::default(), &mut spare);
            let skipped: Vec<bool> = maps.iter().map(Option::is_none).collect();
            assert_eq!(skipped, [false, false, true, false, true], "{shading:?}");
            let bounds = crate::scene::bounding_sphere(&scene.objects);
            let mesh_bounds = each_mesh_bounds(&scene);
            let casters = Casters {
                scene: &scene,
                mesh_bounds: &mesh_bounds,
            };
            let every: Vec<Option<Arc<ShadowMap>>> = scene
                .lights
                .iter()
                .map(|light| {
                    let settings = light.shadow().expect("every light casts shadows");
                    let mut buffers = ShadowBuffers::default();
                    Some(Arc::new(render_map(
                        casters,
                        light,
                        settings,
                        bounds,
                        eye,
                        &mut buffers,
                        &mut spare,
                    )))
                })
                .collect();
            assert!(faces(&every) > faces(&maps));
            let (image, _) = crate::render::render(&scene, &Default::default());
            let frame = crate::render::geometry::build_frame(&scene, SamplePattern::SINGLE, None, every);
            let width = scene.image.width as usize;
            let mut color = vec![Vec3::NAN; image.to_colors().len()];
            let mut covered = vec![false; image.to_colors().len()];
            let mut scratch = TileScratch::default();
            for tile in 0..frame.tiles.count() {
                let rect = frame.tiles.rect(tile);
                let visibility = rasterize_tile(rect, SamplePattern::SINGLE, &frame.raster, tile);
                let start = rect.y0 as usize * width;
                let end = start + rect.height() as usize * width;
                let mut target = TileTarget {
                    color: &mut color[start..end],
                    covered: &mut covered[start..end],
                    stride: width,
                };
                shade_tile(
                    &frame,
                    &visibility,
                    scene.image.background,
                    &mut target,
                    &mut scratch,
                );
            }
            let bits = |colors: &[Vec3]| {
                colors
                    .iter()
                    .map(|c| c.to_array().map(f32::to_bits))
                    .collect::<Vec<_>>()
            };
            assert!(
                bits(&color) == bits(&image.to_colors()),
                "{shading:?}: the images differ"
            );
            assert!(covered.iter().filter(|&&c| c).count() > 1000);
        }
    }

    /// The block count, inside the map by rows and at its border by clamping, equals the
    /// definition (every texel of the block, clamped to the edge) at every texel of a small map,
    /// for every radius and depth.
    #[test]
    fn lit_texels_counts_the_clamped_block_everywhere() {
        let size = 9i64;
        // Depths in a fixed pseudo-random pattern, with ties at the compared depths.
        let map: Vec<f32> = (0..size * size)
            .map(|i| ((i * 37 + 11) % 17) as f32 / 16.0)
            .collect();
        for radius in 0..=3 {
            for y in 0..size {
                for x in 0..size {
                    for depth in [0.0, 0.25, 0.5, 0.8125, 1.0] {
                        let mut expected = 0;
                        for dy in -radius..=radius {
                            for dx in -radius..=radius {
                                let (tx, ty) = ((x + dx).clamp(0, size - 1), (y + dy).clamp(0, size - 1));
                                expected += u32::from(map[(ty * size + tx) as usize] <= depth);
                            }
                        }
                        assert_eq!(
                            lit_texels(&map, size, x, y, radius, depth),
                            expected,
                            "x {x}, y {y}, radius {radius}, depth {depth}"
                        );
                    }
                }
            }
        }
    }
}
