//! Vertex normals: computed for meshes that come without them, and repaired where a file's
//! own normals are unusable.
//!
//! # Design
//!
//! A vertex normal stands for the normal of the smooth surface the triangles approximate.
//! It is computed per triangle *corner*, and vertices are then split so that every distinct
//! (position, normal) pair is one vertex:
//!
//! * **Crease angle.** A corner's normal averages the face normals of the triangles around
//!   its position whose normal lies within the crease angle of the corner's *own* face
//!   normal. Faces meeting at a sharper angle keep separate normals: a cube (90° > 60°)
//!   keeps hard edges while a finely tessellated sphere comes out smooth. Angles within
//!   [`CREASE_COSINE_TOLERANCE`] of the crease count as inside, so that coplanar faces
//!   still merge at a crease angle of 0.
//! * **Angle weighting.** Each face normal is weighted by the triangle's interior angle at
//!   the corner (Thürmer and Wüthrich, 1998). Area weighting was rejected: it depends on how
//!   the surface next to the vertex happens to be cut up (one long sliver outweighs a fan of
//!   small triangles covering the same directions); the angle a face subtends at the vertex
//!   does not. Plain averaging was rejected for the same reason.
//! * **Grouping by position value.** Corners are grouped by the bits of their position
//!   (with -0 equal to +0), not by position index: the OBJ loader's vertices are unique
//!   (position, texture coordinate, normal) triples and glTF files duplicate vertices along
//!   texture seams, so grouping by index would turn every seam into a crease. Grouping is a
//!   hash map plus a counting sort; the crease test then costs Σ(corners per position)²,
//!   linear for meshes of bounded valence. A position shared by more than
//!   `MAX_CORNERS_FOR_EXACT_CREASE` corners (the centre of a huge triangle fan) switches to
//!   greedy clustering (each corner joins the first cluster whose seed normal is within the
//!   crease angle), which is linear in practice and equal to the exact rule whenever the
//!   faces around the position form well separated groups.
//! * **Degenerate triangles** (zero area, or too large to measure) have no face normal and
//!   contribute nothing. They are kept: triangle counts are part of the contract.
//! * **Other per-vertex data travels with its vertex.** Texture coordinates, vertex colours and
//!   tangents ([`VertexAttributes`]) are copied to every vertex split from an input vertex,
//!   and two input vertices are merged only when their positions, normals *and* all of these
//!   are bit-for-bit equal: a vertex on a UV seam stays two vertices (one per side), while the
//!   normal is still smoothed across the seam, since normals are grouped by position alone.
//!
//! # Fallbacks
//!
//! A corner's normal is never NaN. Whichever of these is first non-zero wins:
//! 1. the crease-limited angle-weighted average described above (only for a corner of a
//!    non-degenerate triangle);
//! 2. the corner's own face normal (possible only when faces beyond 90° cancel out);
//! 3. the angle-weighted average of every non-degenerate face at the position, ignoring the
//!    crease angle (the normal a corner of a degenerate triangle gets);
//! 4. the first non-degenerate face normal at the position;
//! 5. [`FALLBACK_NORMAL`] (+Z), for positions touched only by degenerate triangles.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};
use std::ops::Range;

use glam::{Vec2, Vec3, Vec4};
use rayon::prelude::*;

use super::{Mesh, atan};
use crate::render::lanes::{Floats, LANES, Mask, Real, Vec3s};

/// The crease angle used when a scene does not set one: between the 90° of a box's edges
/// (kept hard) and the few degrees between neighbouring faces of a tessellated curve
/// (smoothed).
pub const DEFAULT_CREASE_ANGLE_DEGREES: f32 = 60.0;

/// The normal of a vertex whose triangles are all degenerate: any unit vector is as right
/// as any other, and +Z is at least predictable.
pub const FALLBACK_NORMAL: Vec3 = Vec3::Z;

/// How far (in cosine) beyond the crease angle a face may be and still count as inside:
/// about 0.08° near 0°, so normals of coplanar faces, equal up to rounding, always merge.
pub const CREASE_COSINE_TOLERANCE: f32 = 1e-6;

/// Every two face normals have a dot product above this: they are unit to within a few units in
/// the last place, so their dot product is more than −1 − 2⁻²⁰ (tested). A crease cosine at or
/// below it (a crease angle of 180°, less the tolerance) lets every pair of faces through.
const LEAST_DOT_OF_UNIT_NORMALS: f32 = -1.0 - 1.0 / 1_048_576.0;

/// Above this many corners at one position, exact per-corner crease tests (quadratic in the
/// corner count) give way to greedy clustering.
const MAX_CORNERS_FOR_EXACT_CREASE: usize = 128;

/// A hash map keyed by small arrays of whole numbers (bits of positions and normals,
/// indices), hashed with [`WordHasher`].
pub(super) type WordMap<K, V> = HashMap<K, V, BuildHasherDefault<WordHasher>>;

pub(super) fn word_map<K, V>(capacity: usize) -> WordMap<K, V> {
    HashMap::with_capacity_and_hasher(capacity, BuildHasherDefault::default())
}

/// A hasher for keys made of a few machine words: each word is mixed in with a multiplication,
/// and the result goes through MurmurHash3's finaliser so that every bit of every word reaches
/// the low bits the table indexes by (positions on a grid have long runs of zero bits). Much
/// cheaper than the standard SipHash for these keys, which were a fifth of the time spent on
/// normals; SipHash's defence against crafted collisions buys nothing when the worst a crafted
/// mesh file can do is load slowly.
#[derive(Debug, Default, Clone, Copy)]
pub(super) struct WordHasher(u64);

impl WordHasher {
    fn add(&mut self, word: u64) {
        self.0 = (self.0.rotate_left(23) ^ word).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    }
}

impl Hasher for WordHasher {
    fn write(&mut self, bytes: &[u8]) {
        let mut words = bytes.chunks_exact(8);
        for word in &mut words {
            self.add(u64::from_le_bytes(word.try_into().unwrap_or_default()));
        }
        let mut last = [0u8; 8];
        last[..words.remainder().len()].copy_from_slice(words.remainder());
        self.add(u64::from_le_bytes(last));
    }

    fn write_u32(&mut self, word: u32) {
        self.add(u64::from(word));
    }

    fn write_usize(&mut self, word: usize) {
        self.add(word as u64);
    }

    fn finish(&self) -> u64 {
        let mut hash = self.0;
        hash ^= hash >> 33;
        hash = hash.wrapping_mul(0xFF51_AFD7_ED55_8CCD);
        hash ^= hash >> 33;
        hash = hash.wrapping_mul(0xC4CE_B9FE_1A85_EC53);
        hash ^ (hash >> 33)
    }
}

/// The unit normal of the triangle `(a, b, c)`, front side counter-clockwise:
/// `normalize((b − a) × (c − a))`. The zero vector when the triangle is degenerate (zero
/// area) or too large for its cross product to be finite; never NaN.
pub fn face_normal(a: Vec3, b: Vec3, c: Vec3) -> Vec3 {
    unit_or_zero((b - a).cross(c - a))
}

/// `v` scaled to unit length, or zero when `v` has no direction (zero or not finite).
///
/// Dividing by the largest component first keeps the squared length from underflowing for
/// tiny vectors (a thin triangle's cross product) and from overflowing for huge ones.
pub fn unit_or_zero(v: Vec3) -> Vec3 {
    if !v.is_finite() {
        return Vec3::ZERO;
    }
    let largest = v.abs().max_element();
    if largest > 0.0 {
        (v / largest).normalize()
    } else {
        Vec3::ZERO
    }
}

/// The per-vertex data, besides positions and normals, that follows each vertex when
/// vertices are split or merged. Each slice is empty (the mesh has no such data) or holds one
/// entry per position; a shorter one is read as if padded with zeros (white for colours).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct VertexAttributes<'a> {
    pub uvs: &'a [Vec2],
    pub uvs1: &'a [Vec2],
    pub colors: &'a [Vec4],
    pub tangents: &'a [Vec4],
}

impl VertexAttributes<'_> {
    fn is_empty(&self) -> bool {
        self.uvs.is_empty() && self.uvs1.is_empty() && self.colors.is_empty() && self.tangents.is_empty()
    }

    fn uv(&self, vertex: usize) -> Vec2 {
        self.uvs.get(vertex).copied().unwrap_or(Vec2::ZERO)
    }

    fn uv1(&self, vertex: usize) -> Vec2 {
        self.uvs1.get(vertex).copied().unwrap_or(Vec2::ZERO)
    }

    fn color(&self, vertex: usize) -> Vec4 {
        self.colors.get(vertex).copied().unwrap_or(Vec4::ONE)
    }

    fn tangent(&self, vertex: usize) -> Vec4 {
        self.tangents.get(vertex).copied().unwrap_or(Vec4::ZERO)
    }

    /// The bits of everything this vertex carries, equal exactly when the data is equal
    /// (absent arrays contribute zeros).
    fn key(&self, vertex: usize) -> [u32; 12] {
        let [u, v] = self.uv(vertex).to_array().map(zero_normalised_bits);
        let [u1, v1] = self.uv1(vertex).to_array().map(zero_normalised_bits);
        let [r, g, b, a] = self.color(vertex).to_array().map(zero_normalised_bits);
        let [tx, ty, tz, tw] = self.tangent(vertex).to_array().map(zero_normalised_bits);
        [u, v, u1, v1, r, g, b, a, tx, ty, tz, tw]
    }

    /// Appends this vertex's data to the arrays of `mesh` that this set has.
    fn push_vertex(&self, vertex: usize, mesh: &mut Mesh) {
        if !self.uvs.is_empty() {
            mesh.uvs.push(self.uv(vertex));
        }
        if !self.uvs1.is_empty() {
            mesh.uvs1.push(self.uv1(vertex));
        }
        if !self.colors.is_empty() {
            mesh.colors.push(self.color(vertex));
        }
        if !self.tangents.is_empty() {
            mesh.tangents.push(self.tangent(vertex));
        }
    }
}

/// Builds a mesh with vertex normals from positions and counter-clockwise triangles that
/// have none, following the crease and weighting rules of the module documentation.
///
/// The result has the same triangles in the same order (so a caller's per-triangle
/// material list stays valid), with vertices split or merged so that each distinct
/// (position, normal, attributes) combination is one vertex; positions no triangle uses are
/// dropped. `attributes` are carried to the new vertices (module documentation). Its
/// `materials`, `triangle_materials` and `textures` are empty.
///
/// Every index in `triangles` must be less than `positions.len()` (loaders check this
/// before calling). `crease_angle_degrees` is clamped to [0, 180].
pub fn compute_vertex_normals(
    positions: &[Vec3],
    attributes: VertexAttributes,
    triangles: &[[u32; 3]],
    crease_angle_degrees: f32,
) -> Mesh {
    let corners = CornersByPosition::new(positions, triangles);
    let normals = corner_normals(positions, triangles, &corners, crease_angle_degrees);
    split_vertices(positions, attributes, triangles, &corners, |slot| normals[slot])
}

/// A mesh whose file-provided normals were checked, with how many had to be replaced.
#[derive(Debug, Clone, PartialEq)]
pub struct RepairedNormals {
    /// The mesh, with `materials` and `triangle_materials` empty.
    pub mesh: Mesh,
    /// How many vertices used by triangles had a zero-length or non-finite normal.
    pub replaced_count: usize,
}

/// Takes normals that came with a file (`normals[i]` belongs to `positions[i]`) and makes
/// them safe to render: non-unit normals are renormalised, and a zero-length or non-finite
/// one (or a missing one, when `normals` is shorter than `positions`) is replaced, at every
/// corner that uses it, by the normal [`compute_vertex_normals`] would give that corner.
///
/// When nothing needs replacing the vertices are returned as they are (with `attributes`);
/// otherwise vertices are split by (position, normal, attributes) as in
/// [`compute_vertex_normals`]. Triangles keep their order. Every index in `triangles` must be
/// less than `positions.len()`.
pub fn repair_normals(
    positions: &[Vec3],
    normals: &[Vec3],
    attributes: VertexAttributes,
    triangles: &[[u32; 3]],
    crease_angle_degrees: f32,
) -> RepairedNormals {
    let file_normal = |vertex: usize| normals.get(vertex).copied().map_or(Vec3::ZERO, unit_or_zero);
    let mut is_broken = vec![false; positions.len()];
    for &vertex in triangles.iter().flatten() {
        let vertex = vertex as usize;
        is_broken[vertex] = file_normal(vertex) == Vec3::ZERO;
    }
    let replaced_count = is_broken.iter().filter(|&&broken| broken).count();

    let mesh = if replaced_count == 0 {
        // Only vertices that some triangle uses were checked: one that none uses is never
        // drawn, but a zero file normal there would still break the unit-normal invariant
        // (found by the `gltf` fuzz target), so it gets any unit normal.
        let kept_normal = |vertex: usize| match file_normal(vertex) {
            Vec3::ZERO => Vec3::Z,
            normal => normal,
        };
        let mut mesh = Mesh {
            positions: positions.to_vec(),
            normals: (0..positions.len()).map(kept_normal).collect(),
            triangles: triangles.to_vec(),
            ..Mesh::default()
        };
        for vertex in 0..positions.len() {
            attributes.push_vertex(vertex, &mut mesh);
        }
        mesh
    } else {
        let corners = CornersByPosition::new(positions, triangles);
        let computed = corner_normals(positions, triangles, &corners, crease_angle_degrees);
        split_vertices(positions, attributes, triangles, &corners, |slot| {
            let vertex = corners.vertex_at(triangles, slot) as usize;
            if is_broken[vertex] {
                computed[slot]
            } else {
                file_normal(vertex)
            }
        })
    };
    RepairedNormals { mesh, replaced_count }
}

/// Vertices grouped by the exact value of their position.
struct PositionGroups {
    /// For each vertex, the index of its group; groups are numbered in order of first use.
    group_of_vertex: Vec<u32>,
    group_count: usize,
}

impl PositionGroups {
    fn new(positions: &[Vec3]) -> Self {
        let mut group_by_bits: WordMap<[u32; 3], u32> = word_map(positions.len());
        let group_of_vertex = positions
            .iter()
            .map(|&position| {
                let next = group_by_bits.len() as u32;
                *group_by_bits.entry(exact_key(position)).or_insert(next)
            })
            .collect();
        PositionGroups {
            group_of_vertex,
            group_count: group_by_bits.len(),
        }
    }

    fn of(&self, vertex: u32) -> u32 {
        self.group_of_vertex[vertex as usize]
    }
}

/// The triangle corners (`3 · triangle + k`) sorted by the position group of their vertex
/// (a counting sort, so each group's corners stay in corner order): what the per-position
/// passes read. A corner's place in this order is its *slot*; per-corner results are kept by
/// slot. Corners are `u32` (a mesh has fewer than 2³² corners: its indices are `u32`); the
/// arrays per corner are most of the memory computing normals takes, and on a mesh of a
/// million triangles fresh memory costs as much as the arithmetic (the kernel zeroes every new
/// page).
struct CornersByPosition {
    /// The slots of group g are `group_start[g]..group_start[g + 1]`.
    group_start: Vec<u32>,
    /// The corner at each slot.
    corners_by_group: Vec<u32>,
    /// The slot of each corner.
    slot_of_corner: Vec<u32>,
}

impl CornersByPosition {
    fn new(positions: &[Vec3], triangles: &[[u32; 3]]) -> Self {
        let groups = PositionGroups::new(positions);
        let corner_count = triangles.len() * 3;
        let corner_groups = || {
            triangles
                .iter()
                .flatten()
                .map(|&vertex| groups.of(vertex) as usize)
        };
        let mut group_start = vec![0u32; groups.group_count + 1];
        for group in corner_groups() {
            group_start[group + 1] += 1;
        }
        for group in 0..groups.group_count {
            group_start[group + 1] += group_start[group];
        }
        let mut next_slot = group_start.clone();
        let mut corners_by_group = vec![0u32; corner_count];
        let mut slot_of_corner = vec![0u32; corner_count];
        for (corner, group) in corner_groups().enumerate() {
            let slot = next_slot[group];
            next_slot[group] += 1;
            corners_by_group[slot as usize] = corner as u32;
            slot_of_corner[corner] = slot;
        }
        CornersByPosition {
            group_start,
            corners_by_group,
            slot_of_corner,
        }
    }

    fn corner_count(&self) -> usize {
        self.corners_by_group.len()
    }

    /// The vertex of the corner at `slot`.
    fn vertex_at(&self, triangles: &[[u32; 3]], slot: usize) -> u32 {
        let corner = self.corners_by_group[slot] as usize;
        triangles[corner / 3][corner % 3]
    }

    /// Calls `per_group(first_slot, corners, outputs, scratch)` for every group with its first
    /// slot, its corners and their outputs (`sorted` holds one per slot), in parallel over
    /// blocks of whole groups with about equal numbers of corners; `scratch` is the block's
    /// own.
    fn for_each_group<T: Send, S: Default>(
        &self,
        sorted: &mut [T],
        per_group: impl Fn(usize, &[u32], &mut [T], &mut S) + Sync,
    ) {
        let corner_count = self.corner_count();
        let group_count = self.group_start.len() - 1;
        let block_count = if corner_count < PARALLEL_THRESHOLD {
            1
        } else {
            4 * rayon::current_num_threads()
        };
        let start = |group: usize| self.group_start[group] as usize;
        let mut blocks = Vec::with_capacity(block_count);
        let mut rest = sorted;
        let mut first_group = 0;
        for block in 1..=block_count {
            let end_group = if block == block_count {
                group_count
            } else {
                // The first group starting at or after this block's share of the corners.
                let wanted_end = corner_count * block / block_count;
                self.group_start
                    .partition_point(|&slot| (slot as usize) < wanted_end)
                    .max(first_group)
            };
            let (mine, after) = rest.split_at_mut(start(end_group) - start(first_group));
            blocks.push((first_group..end_group, mine));
            rest = after;
            first_group = end_group;
        }
        let run_block = |(groups, outputs): (Range<usize>, &mut [T])| {
            let offset = start(groups.start);
            let mut scratch = S::default();
            for group in groups {
                let slots = start(group)..start(group + 1);
                let group_outputs = &mut outputs[slots.start - offset..slots.end - offset];
                per_group(
                    slots.start,
                    &self.corners_by_group[slots],
                    group_outputs,
                    &mut scratch,
                );
            }
        };
        if block_count == 1 {
            blocks.into_iter().for_each(run_block);
        } else {
            blocks.into_par_iter().for_each(run_block);
        }
    }
}

/// A hashable key equal for equal vectors. Adding +0 turns -0 into +0 (and changes nothing
/// else), so that the two zeros, equal as numbers, share a key.
fn exact_key(v: Vec3) -> [u32; 3] {
    v.to_array().map(zero_normalised_bits)
}

/// The bits of `x`, with -0 turned into +0 (adding +0 does that and changes nothing else).
fn zero_normalised_bits(x: f32) -> u32 {
    (x + 0.0).to_bits()
}

/// The interior angle of a triangle at `corner`, between the edges towards `next` and
/// `previous`; 0 when an edge has no length. `atan2(|u×v|, u·v)` stays accurate near 0 and
/// π, where `acos(u·v)` loses precision; it is [`atan::atan2`], libm's bits inlined.
fn interior_angle(corner: Vec3, next: Vec3, previous: Vec3) -> f32 {
    let u = unit_or_zero(next - corner);
    let v = unit_or_zero(previous - corner);
    angle_between_units(u, v)
}

/// The angle between two unit (or zero) vectors, as [`interior_angle`] measures it.
fn angle_between_units(u: Vec3, v: Vec3) -> f32 {
    atan::atan2(u.cross(v).length(), u.dot(v))
}

/// `[interior_angle(a, b, c), interior_angle(b, c, a), interior_angle(c, a, b)]` with the same
/// bits, normalising each edge once instead of twice: `c − a` is exactly `−(a − c)` and
/// [`unit_or_zero`] commutes with negation, so an edge's direction seen from its other end is
/// its negation. The negation can only turn a zero component's sign, which changes no non-zero
/// sum and no square; the dot product's zero sign would matter only where the cross product is
/// zero too, which needs a zero edge, and then the angles are measured one by one.
pub(super) fn interior_angles(a: Vec3, b: Vec3, c: Vec3) -> [f32; 3] {
    let along_ab = unit_or_zero(b - a);
    let along_bc = unit_or_zero(c - b);
    let along_ca = unit_or_zero(a - c);
    if along_ab == Vec3::ZERO || along_bc == Vec3::ZERO || along_ca == Vec3::ZERO {
        return [
            interior_angle(a, b, c),
            interior_angle(b, c, a),
            interior_angle(c, a, b),
        ];
    }
    [
        angle_between_units(along_ab, -along_ca),
        angle_between_units(along_bc, -along_ab),
        angle_between_units(along_ca, -along_bc),
    ]
}

/// A triangle's unit face normal (zero when it is degenerate) and its interior angles at its
/// three corners (zero for a degenerate triangle): what each corner's weighted normal is made of.
type FaceAndAngles = (Vec3, [f32; 3]);

/// The face normal and interior angles of one triangle: the specification
/// [`faces_and_angles`] computes eight at a time.
fn face_and_angles(positions: &[Vec3], triangle: [u32; 3]) -> FaceAndAngles {
    let [a, b, c] = triangle.map(|vertex| positions[vertex as usize]);
    let face = face_normal(a, b, c);
    let angles = if face == Vec3::ZERO {
        [0.0; 3]
    } else {
        interior_angles(a, b, c)
    };
    (face, angles)
}

/// How many triangles one parallel task of [`corner_normals`]' face pass takes (a multiple of
/// [`LANES`]).
const FACE_CHUNK: usize = 1024;

/// [`face_and_angles`] of each triangle into `faces`, eight triangles at a time in lanes: the
/// same operations on [`Vec3s`] as [`face_normal`] and [`interior_angles`] make on `Vec3`s, and
/// [`atan::atan2_lanes`] for the angles, so every bit is the same. A triangle the lanes do not
/// follow (degenerate, or with an edge too long or too short to have a direction: the
/// branches of [`interior_angles`]) is measured again by [`face_and_angles`]; the rest of the
/// triangles, fewer than eight, are measured that way too.
fn faces_and_angles(positions: &[Vec3], triangles: &[[u32; 3]], faces: &mut [FaceAndAngles]) {
    let (eights, rest) = triangles.as_chunks::<LANES>();
    let (face_eights, face_rest) = faces.as_chunks_mut::<LANES>();
    for (triangles, faces) in eights.iter().zip(face_eights) {
        let corner = |k: usize| Vec3s::gather(triangles, |triangle| positions[triangle[k] as usize]);
        let (a, b, c) = (corner(0), corner(1), corner(2));
        let (face, has_face) = unit_or_zero_lanes((b - a).cross(c - a));
        let (along_ab, ab) = unit_or_zero_lanes(b - a);
        let (along_bc, bc) = unit_or_zero_lanes(c - b);
        let (along_ca, ca) = unit_or_zero_lanes(a - c);
        let angle = |u: Vec3s, v: Vec3s| atan::atan2_lanes(u.cross(v).length(), u.dot(v));
        let angles = [
            angle(along_ab, -along_ca),
            angle(along_bc, -along_ab),
            angle(along_ca, -along_bc),
        ];
        let followed = has_face.and(ab).and(bc).and(ca);
        let face = face.to_array();
        for (lane, (output, triangle)) in faces.iter_mut().zip(triangles).enumerate() {
            *output = if followed.lane(lane) {
                (face[lane], angles.map(|angles| angles.0[lane]))
            } else {
                face_and_angles(positions, *triangle)
            };
        }
    }
    for (output, &triangle) in face_rest.iter_mut().zip(rest) {
        *output = face_and_angles(positions, triangle);
    }
}

/// [`unit_or_zero`] in lanes, and where the result is not zero.
#[inline(always)]
fn unit_or_zero_lanes(v: Vec3s) -> (Vec3s, Mask) {
    let finite = v.x.is_finite().and(v.y.is_finite()).and(v.z.is_finite());
    // `Vec3::max_element`: `max(x, max(y, z))` with `if a > b { a } else { b }`.
    let max = |a: Floats, b: Floats| a.gt(b).select(a, b);
    let largest = max(v.x.abs(), max(v.y.abs(), v.z.abs()));
    let has_direction = finite.and(largest.gt(Floats::splat(0.0)));
    // `Vec3::normalize`: times `1 / length`.
    let scaled = v.divide(largest);
    let unit = scaled.scale(Floats::splat(1.0) / scaled.length());
    (
        has_direction.select3(unit, Vec3s::splat(Vec3::ZERO)),
        has_direction,
    )
}

/// Below this many triangles (or corners) the per-triangle and per-position passes run on the
/// calling thread: rayon's task set-up would cost more than the work.
const PARALLEL_THRESHOLD: usize = 4096;

/// The normal of every triangle corner, per the module documentation, by slot
/// ([`CornersByPosition`]).
///
/// Each triangle's face normal and angles, and each position's corner normals, depend on
/// nothing else, so both passes run in parallel with the serial arithmetic (the sums over a
/// position's corners are added in corner order, as before).
fn corner_normals(
    positions: &[Vec3],
    triangles: &[[u32; 3]],
    corners: &CornersByPosition,
    crease_angle_degrees: f32,
) -> Vec<Vec3> {
    let mut faces = vec![(Vec3::ZERO, [0.0; 3]); triangles.len()];
    let fill = |(faces, triangles): (&mut [FaceAndAngles], &[[u32; 3]])| {
        faces_and_angles(positions, triangles, faces);
    };
    if triangles.len() < PARALLEL_THRESHOLD {
        fill((&mut faces, triangles));
    } else {
        faces
            .par_chunks_mut(FACE_CHUNK)
            .zip(triangles.par_chunks(FACE_CHUNK))
            .for_each(fill);
    }
    let faces = CornerFaces { faces: &faces };

    let crease_cosine = crease_angle_degrees.clamp(0.0, 180.0).to_radians().cos() - CREASE_COSINE_TOLERANCE;
    let mut normals = vec![Vec3::ZERO; corners.corner_count()];
    corners.for_each_group(
        &mut normals,
        |_, group_corners, normals, crease_sums: &mut Vec<Vec3>| {
            if !smooth_normals_at_position(group_corners, faces, crease_cosine, normals) {
                normals_at_position(group_corners, faces, crease_cosine, crease_sums);
                normals.copy_from_slice(crease_sums);
            }
        },
    );
    normals
}

/// The face normal and interior angles of each triangle, read by corner.
#[derive(Clone, Copy)]
struct CornerFaces<'a> {
    faces: &'a [FaceAndAngles],
}

impl CornerFaces<'_> {
    /// The face normal of the corner's triangle (zero when degenerate).
    fn face(self, corner: u32) -> Vec3 {
        self.faces[corner as usize / 3].0
    }

    /// The triangle's interior angle at the corner: the corner's weight.
    fn weight(self, corner: u32) -> f32 {
        self.faces[corner as usize / 3].1[corner as usize % 3]
    }
}

/// [`normals_at_position`] for a position whose faces all lie within the crease angle of each
/// other (a smooth surface, the usual case), into `normals` (one per corner): every
/// non-degenerate corner's sum is then the sum of all the faces, normalised once, and no
/// per-corner sums are kept. `false`, with nothing written, for any other position.
fn smooth_normals_at_position(
    corners: &[u32],
    faces: CornerFaces,
    crease_cosine: f32,
    normals: &mut [Vec3],
) -> bool {
    if corners.len() > MAX_CORNERS_FOR_EXACT_CREASE || !is_smooth(corners, faces, crease_cosine) {
        return false;
    }
    let unit = unit_or_zero(sum_of_weighted_faces(corners, faces));
    let mut smooth_normal_of_position = None;
    for (&corner, normal) in corners.iter().zip(normals) {
        let face = faces.face(corner);
        // The fallbacks of `normals_at_position`: a degenerate triangle's corner has a zero sum.
        *normal = if face == Vec3::ZERO {
            *smooth_normal_of_position.get_or_insert_with(|| smooth_normal_ignoring_crease(corners, faces))
        } else if unit != Vec3::ZERO {
            unit
        } else {
            face
        };
    }
    true
}

/// The normals of the corners of one position (in the order given), per the module
/// documentation, into `normals` (cleared first).
fn normals_at_position(corners: &[u32], faces: CornerFaces, crease_cosine: f32, normals: &mut Vec<Vec3>) {
    normals.clear();
    if corners.len() <= MAX_CORNERS_FOR_EXACT_CREASE {
        sum_within_crease_exact(corners, faces, crease_cosine, normals);
    } else {
        sum_within_crease_clustered(corners, faces, crease_cosine, normals);
    }
    let mut smooth_normal_of_position = None;
    // On a smooth surface every corner has the same sum: it is normalised once.
    let mut last_normalised: Option<([u32; 3], Vec3)> = None;
    for (&corner, normal) in corners.iter().zip(normals.iter_mut()) {
        let sum_bits = normal.to_array().map(f32::to_bits);
        let from_crease = match last_normalised {
            Some((bits, unit)) if bits == sum_bits => unit,
            _ => {
                let unit = unit_or_zero(*normal);
                last_normalised = Some((sum_bits, unit));
                unit
            }
        };
        *normal = if from_crease != Vec3::ZERO {
            from_crease
        } else if faces.face(corner) != Vec3::ZERO {
            faces.face(corner)
        } else {
            *smooth_normal_of_position.get_or_insert_with(|| smooth_normal_ignoring_crease(corners, faces))
        };
    }
}

/// For each corner of one position, the angle-weighted sum of the face normals within the
/// crease angle of its own face normal (zero for a corner of a degenerate triangle).
///
/// When every two of the position's faces lie within the crease angle (a smooth surface, the
/// usual case), every corner's sum is the sum of all of them in the same order: it is added up
/// once, after testing each pair once (`a·b` and `b·a` have the same bits).
fn sum_within_crease_exact(corners: &[u32], faces: CornerFaces, crease_cosine: f32, sums: &mut Vec<Vec3>) {
    if is_smooth(corners, faces, crease_cosine) {
        let sum = sum_of_weighted_faces(corners, faces);
        sums.extend(corners.iter().map(|&corner| {
            if faces.face(corner) == Vec3::ZERO {
                Vec3::ZERO
            } else {
                sum
            }
        }));
        return;
    }
    for &corner in corners {
        let own_face = faces.face(corner);
        let mut sum = Vec3::ZERO;
        if own_face != Vec3::ZERO {
            for &other in corners {
                let other_face = faces.face(other);
                if other_face != Vec3::ZERO && (other == corner || own_face.dot(other_face) >= crease_cosine)
                {
                    sum += faces.weight(other) * other_face;
                }
            }
        }
        sums.push(sum);
    }
}

/// Whether every two of the non-degenerate faces at a position lie within the crease angle.
fn is_smooth(corners: &[u32], faces: CornerFaces, crease_cosine: f32) -> bool {
    // At a crease angle of 180° no pair can fail the test (see `LEAST_DOT_OF_UNIT_NORMALS`):
    // the scans' usual setting skips the pairwise products.
    crease_cosine <= LEAST_DOT_OF_UNIT_NORMALS
        || corners.iter().enumerate().all(|(index, &corner)| {
            let face = faces.face(corner);
            face == Vec3::ZERO
                || corners[index + 1..].iter().all(|&other| {
                    let other_face = faces.face(other);
                    other_face == Vec3::ZERO || face.dot(other_face) >= crease_cosine
                })
        })
}

/// The angle-weighted sum of the non-degenerate faces at a position, in corner order.
fn sum_of_weighted_faces(corners: &[u32], faces: CornerFaces) -> Vec3 {
    let mut sum = Vec3::ZERO;
    for &other in corners {
        let other_face = faces.face(other);
        if other_face != Vec3::ZERO {
            sum += faces.weight(other) * other_face;
        }
    }
    sum
}

/// Like [`sum_within_crease_exact`] for positions with very many corners: each corner joins
/// the first cluster whose seed (the face normal that opened it) is within the crease
/// angle, and gets its cluster's sum.
fn sum_within_crease_clustered(
    corners: &[u32],
    faces: CornerFaces,
    crease_cosine: f32,
    sums: &mut Vec<Vec3>,
) {
    struct Cluster {
        seed: Vec3,
        sum: Vec3,
    }
    let mut clusters: Vec<Cluster> = Vec::new();
    let mut cluster_of_corner = Vec::with_capacity(corners.len());
    for &corner in corners {
        let face = faces.face(corner);
        if face == Vec3::ZERO {
            cluster_of_corner.push(None);
            continue;
        }
        let index = match clusters
            .iter()
            .position(|cluster| cluster.seed.dot(face) >= crease_cosine)
        {
            Some(index) => index,
            None => {
                clusters.push(Cluster {
                    seed: face,
                    sum: Vec3::ZERO,
                });
                clusters.len() - 1
            }
        };
        clusters[index].sum += faces.weight(corner) * face;
        cluster_of_corner.push(Some(index));
    }
    sums.extend(
        cluster_of_corner
            .iter()
            .map(|cluster| cluster.map_or(Vec3::ZERO, |index| clusters[index].sum)),
    );
}

/// Fallbacks 3 to 5 of the module documentation for one position.
fn smooth_normal_ignoring_crease(corners: &[u32], faces: CornerFaces) -> Vec3 {
    let weighted_sum: Vec3 = corners
        .iter()
        .map(|&corner| faces.weight(corner) * faces.face(corner))
        .sum();
    let average = unit_or_zero(weighted_sum);
    if average != Vec3::ZERO {
        return average;
    }
    corners
        .iter()
        .map(|&corner| faces.face(corner))
        .find(|&face| face != Vec3::ZERO)
        .unwrap_or(FALLBACK_NORMAL)
}

/// Builds the output mesh: one vertex per distinct (position group, attribute group, normal)
/// combination, created in the order corners are met, and the triangles re-indexed onto them.
/// `normal_of_slot` gives each corner's normal by its slot ([`CornersByPosition`]).
///
/// Each position's corners find the first of them with the same attributes and normal (in
/// parallel over positions: a short list, or a hash map at a position with very many
/// corners); then one pass in corner order numbers the vertices at those first corners.
fn split_vertices(
    positions: &[Vec3],
    attributes: VertexAttributes,
    triangles: &[[u32; 3]],
    corners: &CornersByPosition,
    normal_of_slot: impl Fn(usize) -> Vec3 + Sync,
) -> Mesh {
    let attribute_group_of_vertex = attribute_groups(positions.len(), attributes);
    let key_of_slot = |slot: usize| {
        // Without attributes every vertex is in group 0: the corner's vertex is not looked up.
        let attribute_group = if attribute_group_of_vertex.is_empty() {
            0
        } else {
            let vertex = corners.vertex_at(triangles, slot);
            attribute_group_of_vertex
                .get(vertex as usize)
                .copied()
                .unwrap_or(0)
        };
        (attribute_group, exact_key(normal_of_slot(slot)))
    };
    // For each slot, the slot of the first corner at its position with the same key (a group's
    // slots are in corner order).
    let mut first_slots = vec![0u32; corners.corner_count()];
    corners.for_each_group(
        &mut first_slots,
        |first_slot, group_corners, firsts, seen: &mut FirstSlots| {
            // A position no triangle uses has no corners (and `first_slot` is the next one's).
            if group_corners.is_empty() {
                return;
            }
            // Usually every corner at a position has one key (a smooth surface away from seams):
            // the first slot is then every slot's first, found without the search.
            let first_key = key_of_slot(first_slot);
            let mut others = first_slot + 1..first_slot + group_corners.len();
            if others.all(|slot| key_of_slot(slot) == first_key) {
                firsts.fill(first_slot as u32);
                return;
            }
            seen.clear();
            for (slot, first) in (first_slot..first_slot + group_corners.len()).zip(firsts) {
                *first = seen.first_with(key_of_slot(slot), slot as u32);
            }
        },
    );

    // Usually about one vertex per position (more on creases and seams).
    let mut mesh = Mesh {
        positions: Vec::with_capacity(positions.len()),
        normals: Vec::with_capacity(positions.len()),
        ..Mesh::default()
    };
    let mut new_triangles = vec![[0; 3]; triangles.len()];
    // Once a first slot's vertex is made, its entry becomes that vertex's number: a later corner
    // with the same key reads it there. (A slot's own entry is itself exactly when it is a first
    // slot, and each slot is met once, so the two kinds of entry are never confused.)
    let mut vertex_of_first = first_slots;
    let (slots_by_triangle, _) = corners.slot_of_corner.as_chunks::<3>();
    for ((triangle, slots), new_triangle) in triangles.iter().zip(slots_by_triangle).zip(&mut new_triangles) {
        for ((&vertex, &slot), new_vertex) in triangle.iter().zip(slots).zip(new_triangle) {
            let first = vertex_of_first[slot as usize];
            *new_vertex = if first == slot {
                let vertex = vertex as usize;
                mesh.positions.push(positions[vertex]);
                mesh.normals.push(normal_of_slot(slot as usize));
                attributes.push_vertex(vertex, &mut mesh);
                let new_vertex = (mesh.positions.len() - 1) as u32;
                vertex_of_first[slot as usize] = new_vertex;
                new_vertex
            } else {
                // The first corner comes earlier: its new vertex is made.
                vertex_of_first[first as usize]
            };
        }
    }
    mesh.triangles = new_triangles;
    mesh
}

/// The distinct (attribute group, normal bits) keys met so far at one position, each with the
/// slot of the first corner that had it.
#[derive(Default)]
struct FirstSlots {
    keys: Vec<((u32, [u32; 3]), u32)>,
    /// The same, once there are more than [`MAX_KEYS_SEARCHED`] (a fan's centre).
    map: WordMap<(u32, [u32; 3]), u32>,
}

/// Up to this many distinct keys at one position are searched one by one.
const MAX_KEYS_SEARCHED: usize = 16;

impl FirstSlots {
    fn clear(&mut self) {
        self.keys.clear();
        self.map.clear();
    }

    /// The first slot seen with `key`: `slot` itself when the key is new.
    fn first_with(&mut self, key: (u32, [u32; 3]), slot: u32) -> u32 {
        if self.keys.len() <= MAX_KEYS_SEARCHED {
            if let Some(&(_, first)) = self.keys.iter().find(|(seen, _)| *seen == key) {
                return first;
            }
            self.keys.push((key, slot));
            if self.keys.len() > MAX_KEYS_SEARCHED {
                self.map.extend(self.keys.iter().copied());
            }
            return slot;
        }
        *self.map.entry(key).or_insert(slot)
    }
}

/// For each vertex, a number equal for vertices whose attributes are bit-for-bit equal; empty
/// (every vertex in group 0) when there are no attributes.
fn attribute_groups(vertex_count: usize, attributes: VertexAttributes) -> Vec<u32> {
    if attributes.is_empty() {
        return Vec::new();
    }
    let mut group_by_key: WordMap<[u32; 12], u32> = word_map(vertex_count);
    (0..vertex_count)
        .map(|vertex| {
            let next = group_by_key.len() as u32;
            *group_by_key.entry(attributes.key(vertex)).or_insert(next)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use std::f32::consts::FRAC_PI_4;

    use super::*;

    /// Computes normals and checks the result, as a set of (position, normal) vertices,
    /// against `expected`; also checks that triangles kept their count and corners.
    fn check(
        positions: &[Vec3],
        triangles: &[[u32; 3]],
        crease_angle_degrees: f32,
        expected: &[(Vec3, Vec3)],
    ) {
        let mesh = compute_vertex_normals(
            positions,
            VertexAttributes::default(),
            triangles,
            crease_angle_degrees,
        );
        check_vertices(&mesh, expected);
        check_same_corners(&mesh, positions, triangles);
    }

    fn check_vertices(mesh: &Mesh, expected: &[(Vec3, Vec3)]) {
        let actual: Vec<(Vec3, Vec3)> = mesh
            .positions
            .iter()
            .copied()
            .zip(mesh.normals.iter().copied())
            .collect();
        assert_eq!(actual.len(), expected.len(), "vertex count; got {actual:?}");
        for &(position, normal) in expected {
            let matches = actual
                .iter()
                .filter(|(p, n)| p.distance(position) < 1e-6 && n.distance(normal) < 1e-5)
                .count();
            assert_eq!(matches, 1, "vertex ({position}, {normal}) in {actual:?}");
        }
    }

    /// The output triangles reference the same positions, corner by corner, as the input.
    fn check_same_corners(mesh: &Mesh, positions: &[Vec3], triangles: &[[u32; 3]]) {
        assert_eq!(mesh.triangles.len(), triangles.len());
        for (new, old) in mesh.triangles.iter().zip(triangles) {
            for k in 0..3 {
                assert_eq!(mesh.positions[new[k] as usize], positions[old[k] as usize]);
            }
        }
        assert!(
            mesh.normals.iter().all(|n| (n.length() - 1.0).abs() < 1e-6),
            "unit normals"
        );
    }

    /// The cube [-1, 1]³ as 8 shared corners and 12 counter-clockwise triangles.
    fn shared_cube() -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let positions = (0..8)
            .map(|i| {
                Vec3::new(
                    if i & 1 == 0 { -1.0 } else { 1.0 },
                    if i & 2 == 0 { -1.0 } else { 1.0 },
                    if i & 4 == 0 { -1.0 } else { 1.0 },
                )
            })
            .collect();
        // Each face as a counter-clockwise quad seen from outside.
        let quads = [
            [1, 3, 7, 5],
            [0, 4, 6, 2],
            [2, 6, 7, 3],
            [0, 1, 5, 4],
            [4, 5, 7, 6],
            [0, 2, 3, 1],
        ];
        let triangles = quads
            .iter()
            .flat_map(|&[a, b, c, d]| [[a, b, c], [a, c, d]])
            .collect();
        (positions, triangles)
    }

    #[test]
    fn face_normal_follows_counter_clockwise_winding() {
        let (a, b, c) = (Vec3::ZERO, Vec3::X, Vec3::Y);
        assert_eq!(face_normal(a, b, c), Vec3::Z);
        assert_eq!(face_normal(a, c, b), -Vec3::Z);
    }

    #[test]
    fn face_normal_of_degenerate_or_huge_triangle_is_zero() {
        assert_eq!(face_normal(Vec3::ONE, Vec3::ONE, Vec3::ONE), Vec3::ZERO);
        assert_eq!(face_normal(Vec3::ZERO, Vec3::X, 2.0 * Vec3::X), Vec3::ZERO);
        assert_eq!(
            face_normal(Vec3::ZERO, Vec3::X * 3e38, Vec3::Y * 3e38),
            Vec3::ZERO
        );
        assert_eq!(face_normal(Vec3::ZERO, Vec3::X, Vec3::NAN), Vec3::ZERO);
    }

    #[test]
    fn face_normal_of_tiny_triangle_is_unit() {
        // The squared length of this cross product (1e-80) underflows f32.
        let n = face_normal(Vec3::ZERO, Vec3::X * 1e-20, Vec3::Y * 1e-20);
        assert_eq!(n, Vec3::Z);
    }

    #[test]
    fn cube_with_shared_corners_keeps_hard_edges() {
        let (positions, triangles) = shared_cube();
        let mut expected = Vec::new();
        for &p in &positions {
            for axis in [Vec3::X, Vec3::Y, Vec3::Z] {
                expected.push((p, axis * p.dot(axis).signum()));
            }
        }
        check(&positions, &triangles, DEFAULT_CREASE_ANGLE_DEGREES, &expected);
    }

    #[test]
    fn cube_beyond_crease_angle_is_smooth() {
        let (positions, triangles) = shared_cube();
        let expected: Vec<_> = positions.iter().map(|&p| (p, p.normalize())).collect();
        check(&positions, &triangles, 100.0, &expected);
    }

    #[test]
    fn tessellated_sphere_is_smooth() {
        // sphere(16) stores the seam and poles as separate vertices with equal positions;
        // grouping by position value must still weld them into one smooth vertex each.
        let sphere = super::super::primitives::sphere(16);
        let mesh = compute_vertex_normals(
            &sphere.positions,
            VertexAttributes::default(),
            &sphere.triangles,
            DEFAULT_CREASE_ANGLE_DEGREES,
        );
        check_same_corners(&mesh, &sphere.positions, &sphere.triangles);
        // 15 rings of 16 plus the two poles.
        assert_eq!(mesh.positions.len(), 15 * 16 + 2);
        for (p, n) in mesh.positions.iter().zip(&mesh.normals) {
            assert!(n.dot(p.normalize()) > 0.999, "normal {n} at {p}");
        }
    }

    #[test]
    fn face_normals_have_no_dot_product_below_the_least() {
        let mut rng = crate::test_support::XorShift64::new(0x9E37_79B9_7F4A_7C15u64);
        let mut coordinate = || {
            let state = rng.next_u64();
            (state >> 11) as f32 / (1u64 << 53) as f32 * 2.0 - 1.0
        };
        for _ in 0..200_000 {
            let [a, b, c] = [(); 3].map(|_| Vec3::new(coordinate(), coordinate(), coordinate()));
            let face = face_normal(a, b, c);
            // The same triangle wound the other way: the most opposed normal there is.
            let opposite = face_normal(a, c, b);
            let other = face_normal(b, a, c + Vec3::splat(coordinate() * 1e-3));
            for pair in [opposite, other] {
                assert!(face.dot(pair) > LEAST_DOT_OF_UNIT_NORMALS, "{face} {pair}");
            }
        }
        let crease_180 = 180f32.to_radians().cos() - CREASE_COSINE_TOLERANCE;
        assert!(crease_180 <= LEAST_DOT_OF_UNIT_NORMALS);
    }

    #[test]
    fn angles_of_a_triangle_have_the_bits_of_one_corner_at_a_time() {
        // Random triangles on a coarse grid (shared coordinates give zero components, coincident
        // corners and collinear triangles), scaled from tiny to huge, overflowing edges included.
        let mut rng = crate::test_support::XorShift64::new(0x2545_F491_4F6C_DD1Du64);
        let mut coordinate = || {
            let state = rng.next_u64();
            ((state >> 40) % 5) as f32 - 2.0
        };
        for scale in [1e-30, 1e-3, 1.0, 7.3, 1e30, 1.5e38] {
            for _ in 0..20_000 {
                let [a, b, c] = [(); 3].map(|_| scale * Vec3::new(coordinate(), coordinate(), coordinate()));
                let one_at_a_time = [
                    interior_angle(a, b, c),
                    interior_angle(b, c, a),
                    interior_angle(c, a, b),
                ];
                assert_eq!(
                    interior_angles(a, b, c).map(f32::to_bits),
                    one_at_a_time.map(f32::to_bits),
                    "{a} {b} {c}"
                );
            }
        }
    }

    #[test]
    fn faces_in_lanes_have_the_bits_of_one_triangle_at_a_time() {
        // Corners on a coarse grid (zero components, coincident corners, collinear and
        // sliver triangles) and anywhere in a cube, scaled from subnormal to overflowing, and a
        // few positions that are not finite; 8·k + 5 triangles, so that some are left over.
        let mut rng = crate::test_support::XorShift64::new(0x2545_F491_4F6C_DD1Du64);
        let mut next = || rng.next_u64();
        let mut positions = vec![
            Vec3::INFINITY,
            Vec3::new(0.0, f32::NAN, 1.0),
            Vec3::new(-0.0, 0.0, 0.0),
        ];
        for scale in [1e-40, 1e-30, 1e-3, 1.0, 7.3, 1e30, 1.5e38] {
            for _ in 0..2_000 {
                let [x, y, z] = [(); 3].map(|_| next() >> 40);
                positions.push(scale * Vec3::new(x as f32, y as f32, z as f32).map(|t| t % 5.0 - 2.0));
                positions
                    .push(scale * Vec3::new(x as f32, y as f32, z as f32).map(|t| t / 8_388_608.0 - 1.0));
            }
        }
        let count = positions.len() as u64;
        let mut triangles: Vec<[u32; 3]> = (0..200_005)
            .map(|_| [(); 3].map(|_| (next() % count) as u32))
            .collect();
        // Neighbours in the list share a scale: these are the usual, non-degenerate triangles.
        triangles.extend((0..13_000u32).map(|k| [2 * k + 4, 2 * k + 6, 2 * k + 8]));
        let mut faces = vec![(Vec3::ZERO, [0.0; 3]); triangles.len()];
        faces_and_angles(&positions, &triangles, &mut faces);
        let bits =
            |(face, angles): (Vec3, [f32; 3])| (face.to_array().map(f32::to_bits), angles.map(f32::to_bits));
        for (triangle, face) in triangles.iter().zip(faces) {
            assert_eq!(
                bits(face),
                bits(face_and_angles(&positions, *triangle)),
                "{:?}",
                triangle.map(|vertex| positions[vertex as usize])
            );
        }
    }

    #[test]
    fn weights_are_interior_angles_not_areas() {
        // Two triangles share the corner at the origin: a small one in the XY plane with a
        // 90° angle there, and a large one tilted 30° about X with a 45° angle there.
        let tilted_y = Vec3::new(0.0, 30f32.to_radians().cos(), 30f32.to_radians().sin());
        let tilted_normal = Vec3::X.cross(tilted_y);
        let positions = [
            Vec3::ZERO,
            Vec3::X,
            Vec3::Y,
            Vec3::ZERO,
            10.0 * Vec3::X,
            10.0 * (FRAC_PI_4.cos() * Vec3::X + FRAC_PI_4.sin() * tilted_y),
        ];
        let triangles = [[0, 1, 2], [3, 4, 5]];
        let mesh = compute_vertex_normals(
            &positions,
            VertexAttributes::default(),
            &triangles,
            DEFAULT_CREASE_ANGLE_DEGREES,
        );
        let at_origin = mesh.normals[mesh.triangles[0][0] as usize];
        assert_eq!(
            mesh.triangles[1][0], mesh.triangles[0][0],
            "one welded vertex at the origin"
        );

        let by_angle = (std::f32::consts::FRAC_PI_2 * Vec3::Z + FRAC_PI_4 * tilted_normal).normalize();
        let by_area = (0.5 * Vec3::Z + 50.0 * FRAC_PI_4.sin() * tilted_normal).normalize();
        assert!(at_origin.distance(by_angle) < 1e-5, "{at_origin} vs {by_angle}");
        assert!(
            at_origin.distance(by_area) > 0.1,
            "area weighting would give {by_area}"
        );
    }

    #[test]
    fn degenerate_triangle_alone_gets_fallback_normal() {
        let p = Vec3::new(1.0, 2.0, 3.0);
        check(
            &[p, p, p],
            &[[0, 1, 2]],
            DEFAULT_CREASE_ANGLE_DEGREES,
            &[(p, FALLBACK_NORMAL)],
        );
    }

    #[test]
    fn degenerate_triangle_takes_normals_of_its_neighbours() {
        // A sliver with all three corners on the x axis, attached to a triangle facing -Z.
        // The sliver's corners at 0 and X take the neighbour's -Z; its midpoint touches
        // only the sliver and gets the fallback (+Z, so distinguishable).
        let positions = [Vec3::ZERO, Vec3::X, Vec3::Y, 0.5 * Vec3::X];
        let triangles = [[0, 2, 1], [0, 3, 1]];
        let expected = [
            (Vec3::ZERO, -Vec3::Z),
            (Vec3::X, -Vec3::Z),
            (Vec3::Y, -Vec3::Z),
            (0.5 * Vec3::X, FALLBACK_NORMAL),
        ];
        check(&positions, &triangles, DEFAULT_CREASE_ANGLE_DEGREES, &expected);
    }

    #[test]
    fn crease_angle_zero_still_merges_coplanar_faces() {
        let positions = [Vec3::ZERO, Vec3::X, Vec3::ONE.with_z(0.0), Vec3::Y];
        let triangles = [[0, 1, 2], [0, 2, 3]];
        let expected = positions.map(|p| (p, Vec3::Z));
        check(&positions, &triangles, 0.0, &expected);
    }

    #[test]
    fn huge_fan_uses_clustering_and_keeps_crease() {
        // A closed cone: a fan of many triangles around the apex plus a flat base fan around
        // the base centre; apex and base centre each have more corners than the exact limit.
        let segments = 2 * MAX_CORNERS_FOR_EXACT_CREASE as u32;
        let mut positions = vec![Vec3::Z, Vec3::ZERO];
        for s in 0..segments {
            let angle = s as f32 / segments as f32 * std::f32::consts::TAU;
            positions.push(Vec3::new(angle.cos(), angle.sin(), 0.0));
        }
        let rim = |s: u32| 2 + s % segments;
        let mut triangles = Vec::new();
        for s in 0..segments {
            triangles.push([0, rim(s), rim(s + 1)]);
            triangles.push([1, rim(s + 1), rim(s)]);
        }
        let mesh = compute_vertex_normals(
            &positions,
            VertexAttributes::default(),
            &triangles,
            DEFAULT_CREASE_ANGLE_DEGREES,
        );
        check_same_corners(&mesh, &positions, &triangles);
        let base_centre = mesh.triangles[1][0] as usize;
        assert_eq!(mesh.normals[base_centre], -Vec3::Z);
        // The apex's side faces are 45° from +Z and spread over every direction, so
        // clusters (seeded 60° apart at most) give the apex a few distinct normals, all
        // pointing up and out of the base.
        let apex_normals: Vec<Vec3> = triangles
            .iter()
            .zip(&mesh.triangles)
            .filter(|(old, _)| old[0] == 0)
            .map(|(_, new)| mesh.normals[new[0] as usize])
            .collect();
        assert!(apex_normals.iter().all(|n| n.z > 0.5), "{apex_normals:?}");
        // Rim vertices: side and base meet at 135°, beyond the crease, so each rim position
        // has exactly two vertices.
        assert_eq!(
            mesh.positions.len() - 1 - count_distinct(&apex_normals),
            2 * segments as usize
        );
    }

    fn count_distinct(normals: &[Vec3]) -> usize {
        let mut keys: Vec<[u32; 3]> = normals.iter().map(|&n| exact_key(n)).collect();
        keys.sort_unstable();
        keys.dedup();
        keys.len()
    }

    #[test]
    fn positions_no_triangle_uses_are_dropped_first_middle_or_last() {
        let positions = [
            Vec3::splat(5.0),
            Vec3::ZERO,
            Vec3::splat(7.0),
            Vec3::X,
            Vec3::Y,
            Vec3::splat(9.0),
        ];
        let triangles = [[1, 3, 4]];
        let mesh = compute_vertex_normals(&positions, VertexAttributes::default(), &triangles, 60.0);
        assert_eq!(mesh.positions, vec![Vec3::ZERO, Vec3::X, Vec3::Y]);
        assert_eq!(mesh.normals, vec![Vec3::Z; 3]);
        assert_eq!(mesh.triangles, vec![[0, 1, 2]]);
    }

    #[test]
    fn repair_gives_an_unused_vertex_with_a_zero_normal_a_unit_one() {
        // Vertex 3 is in no triangle and has a zero file normal (fuzz regression, gltf target).
        let positions = [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::ONE];
        let normals = [Vec3::Z, Vec3::Z, Vec3::Z, Vec3::ZERO];
        let repaired = repair_normals(
            &positions,
            &normals,
            VertexAttributes::default(),
            &[[0, 1, 2]],
            DEFAULT_CREASE_ANGLE_DEGREES,
        );
        assert_eq!(repaired.replaced_count, 0);
        assert_eq!(repaired.mesh.check_invariant(), Ok(()));
    }

    #[test]
    fn repair_keeps_good_normals_and_renormalises() {
        let positions = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let normals = [Vec3::Z * 2.0, Vec3::new(0.0, 1.2, 1.6), Vec3::Z * 1e-30];
        let repaired = repair_normals(
            &positions,
            &normals,
            VertexAttributes::default(),
            &[[0, 1, 2]],
            DEFAULT_CREASE_ANGLE_DEGREES,
        );
        assert_eq!(repaired.replaced_count, 0);
        check_vertices(
            &repaired.mesh,
            &[
                (Vec3::ZERO, Vec3::Z),
                (Vec3::X, Vec3::new(0.0, 0.6, 0.8)),
                (Vec3::Y, Vec3::Z),
            ],
        );
        assert_eq!(repaired.mesh.triangles, vec![[0, 1, 2]]);
    }

    #[test]
    fn repair_replaces_zero_and_non_finite_normals_per_corner() {
        // The shared cube, where every vertex's file normal is broken: each corner gets its
        // own computed (hard-edged) normal, so the 8 vertices split into 24.
        let (positions, triangles) = shared_cube();
        let mut normals = vec![Vec3::ZERO; 8];
        normals[3] = Vec3::new(f32::NAN, 0.0, 1.0);
        normals[5] = Vec3::splat(f32::INFINITY);
        let repaired = repair_normals(
            &positions,
            &normals,
            VertexAttributes::default(),
            &triangles,
            DEFAULT_CREASE_ANGLE_DEGREES,
        );
        assert_eq!(repaired.replaced_count, 8);
        let expected: Vec<_> = positions
            .iter()
            .flat_map(|&p| [Vec3::X, Vec3::Y, Vec3::Z].map(|axis| (p, axis * p.dot(axis).signum())))
            .collect();
        check_vertices(&repaired.mesh, &expected);
        check_same_corners(&repaired.mesh, &positions, &triangles);
    }

    #[test]
    fn repair_mixes_file_and_computed_normals() {
        let positions = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let normals = [Vec3::new(0.0, 0.6, 0.8), Vec3::ZERO];
        let repaired = repair_normals(
            &positions,
            &normals,
            VertexAttributes::default(),
            &[[0, 1, 2]],
            DEFAULT_CREASE_ANGLE_DEGREES,
        );
        assert_eq!(repaired.replaced_count, 2, "one zero and one missing normal");
        check_vertices(
            &repaired.mesh,
            &[
                (Vec3::ZERO, Vec3::new(0.0, 0.6, 0.8)),
                (Vec3::X, Vec3::Z),
                (Vec3::Y, Vec3::Z),
            ],
        );
    }

    /// Per-vertex attributes that differ for every input vertex: vertex `i` has UV `(i, 0)`,
    /// UV1 `(0, i)`, colour `(i, i, i, 1)` and tangent `(1, 0, 0, ±1)`.
    fn distinct_attributes(count: usize) -> (Vec<Vec2>, Vec<Vec2>, Vec<Vec4>, Vec<Vec4>) {
        let uvs = (0..count).map(|i| Vec2::new(i as f32, 0.0)).collect();
        let uvs1 = (0..count).map(|i| Vec2::new(0.0, i as f32)).collect();
        let colors = (0..count)
            .map(|i| Vec4::new(i as f32, i as f32, i as f32, 1.0))
            .collect();
        let tangents = (0..count)
            .map(|i| Vec4::new(1.0, 0.0, 0.0, if i % 2 == 0 { 1.0 } else { -1.0 }))
            .collect();
        (uvs, uvs1, colors, tangents)
    }

    /// Every per-vertex array has one entry per position, and every corner of every output
    /// triangle carries the attributes of the input vertex at that corner.
    fn check_attributes_follow(mesh: &Mesh, attributes: VertexAttributes, triangles: &[[u32; 3]]) {
        let count = mesh.positions.len();
        assert_eq!(
            [
                mesh.uvs.len(),
                mesh.uvs1.len(),
                mesh.colors.len(),
                mesh.tangents.len()
            ],
            [count; 4]
        );
        for (new, old) in mesh.triangles.iter().zip(triangles) {
            for k in 0..3 {
                let (new, old) = (new[k] as usize, old[k] as usize);
                assert_eq!(mesh.uvs[new], attributes.uvs[old], "uv of input vertex {old}");
                assert_eq!(mesh.uvs1[new], attributes.uvs1[old]);
                assert_eq!(mesh.colors[new], attributes.colors[old]);
                assert_eq!(mesh.tangents[new], attributes.tangents[old]);
            }
        }
    }

    #[test]
    fn attributes_follow_their_vertices_through_crease_splits() {
        // The shared cube splits its 8 vertices into 24 (three normals each); every copy keeps
        // the attributes of the vertex it came from.
        let (positions, triangles) = shared_cube();
        let (uvs, uvs1, colors, tangents) = distinct_attributes(positions.len());
        let attributes = VertexAttributes {
            uvs: &uvs,
            uvs1: &uvs1,
            colors: &colors,
            tangents: &tangents,
        };
        let mesh = compute_vertex_normals(&positions, attributes, &triangles, DEFAULT_CREASE_ANGLE_DEGREES);
        assert_eq!(mesh.positions.len(), 24);
        check_same_corners(&mesh, &positions, &triangles);
        check_attributes_follow(&mesh, attributes, &triangles);
        // Only UVs: the other arrays stay empty.
        let only_uvs = VertexAttributes {
            uvs: &uvs,
            ..VertexAttributes::default()
        };
        let mesh = compute_vertex_normals(&positions, only_uvs, &triangles, DEFAULT_CREASE_ANGLE_DEGREES);
        assert_eq!(mesh.uvs.len(), mesh.positions.len());
        assert!(mesh.uvs1.is_empty() && mesh.colors.is_empty() && mesh.tangents.is_empty());
    }

    #[test]
    fn uv_seams_are_not_merged_but_normals_are_smooth_across_them() {
        // Two triangles folded 30° along the edge from the origin to Y. The edge's vertices
        // are duplicated with different UVs on each side (a seam), as OBJ and glTF files store
        // them; a third copy of the origin has the same UV as the first and must merge with it.
        let folded = Vec3::new(30f32.to_radians().cos(), 0.0, 30f32.to_radians().sin());
        let positions = [
            Vec3::ZERO,
            -Vec3::X,
            Vec3::Y,
            Vec3::ZERO,
            Vec3::Y,
            folded,
            Vec3::ZERO,
        ];
        let uvs = [
            Vec2::new(0.5, 1.0),
            Vec2::new(0.0, 1.0),
            Vec2::new(0.5, 0.0),
            Vec2::new(0.0, 1.0),
            Vec2::new(0.0, 0.0),
            Vec2::new(0.5, 1.0),
            Vec2::new(0.5, 1.0),
        ];
        let triangles = [[0, 2, 1], [3, 5, 4], [6, 2, 1]];
        let attributes = VertexAttributes {
            uvs: &uvs,
            ..VertexAttributes::default()
        };
        let mesh = compute_vertex_normals(&positions, attributes, &triangles, DEFAULT_CREASE_ANGLE_DEGREES);
        check_same_corners(&mesh, &positions, &triangles);
        assert_eq!(
            mesh.positions.len(),
            6,
            "vertices 0 and 6 merge; the seam keeps 3 and 4 apart"
        );
        assert_eq!(mesh.triangles[2], mesh.triangles[0]);
        for (new, old) in mesh.triangles.iter().zip(&triangles) {
            for k in 0..3 {
                assert_eq!(mesh.uvs[new[k] as usize], uvs[old[k] as usize]);
            }
        }
        // Both sides of the seam at the origin share one smoothed normal, between the faces'.
        let [left, right] = [mesh.triangles[0][0], mesh.triangles[1][0]].map(|v| mesh.normals[v as usize]);
        assert_ne!(mesh.triangles[0][0], mesh.triangles[1][0]);
        assert!(left.distance(right) < 1e-6, "{left} vs {right}");
        let faces = [
            face_normal(positions[0], positions[2], positions[1]),
            face_normal(positions[3], positions[5], positions[4]),
        ];
        assert!(
            left.dot(faces[0]) < 0.999 && left.dot(faces[1]) < 0.999,
            "smoothed: {left} {faces:?}"
        );
    }

    #[test]
    fn repair_carries_attributes_whether_or_not_it_splits() {
        let (positions, triangles) = shared_cube();
        let (uvs, uvs1, colors, tangents) = distinct_attributes(positions.len());
        let attributes = VertexAttributes {
            uvs: &uvs,
            uvs1: &uvs1,
            colors: &colors,
            tangents: &tangents,
        };
        // Good normals: vertices kept as they are.
        let outward: Vec<Vec3> = positions.iter().map(|p| p.normalize()).collect();
        let kept = repair_normals(
            &positions,
            &outward,
            attributes,
            &triangles,
            DEFAULT_CREASE_ANGLE_DEGREES,
        );
        assert_eq!((kept.replaced_count, kept.mesh.positions.len()), (0, 8));
        check_attributes_follow(&kept.mesh, attributes, &triangles);
        // One broken normal: that vertex is split by the crease rule, attributes follow.
        let mut broken = outward.clone();
        broken[5] = Vec3::ZERO;
        let split = repair_normals(
            &positions,
            &broken,
            attributes,
            &triangles,
            DEFAULT_CREASE_ANGLE_DEGREES,
        );
        assert_eq!((split.replaced_count, split.mesh.positions.len()), (1, 10));
        check_same_corners(&split.mesh, &positions, &triangles);
        check_attributes_follow(&split.mesh, attributes, &triangles);
    }

    /// The vertex split by its definition: corners in order, each (position, attributes,
    /// normal) key looked up in a hash map, a new vertex for a new key.
    fn split_by_hash_map(
        positions: &[Vec3],
        attributes: VertexAttributes,
        triangles: &[[u32; 3]],
        normal_of_corner: impl Fn(usize) -> Vec3,
    ) -> Mesh {
        // Position, attribute and normal bits.
        type Key = ([u32; 3], [u32; 12], [u32; 3]);
        let mut vertex_by_key: HashMap<Key, u32> = HashMap::new();
        let mut mesh = Mesh::default();
        for (index, triangle) in triangles.iter().enumerate() {
            let new_triangle = [0, 1, 2].map(|k| {
                let vertex = triangle[k] as usize;
                let normal = normal_of_corner(3 * index + k);
                let key = (
                    exact_key(positions[vertex]),
                    attributes.key(vertex),
                    exact_key(normal),
                );
                *vertex_by_key.entry(key).or_insert_with(|| {
                    mesh.positions.push(positions[vertex]);
                    mesh.normals.push(normal);
                    attributes.push_vertex(vertex, &mut mesh);
                    (mesh.positions.len() - 1) as u32
                })
            });
            mesh.triangles.push(new_triangle);
        }
        mesh
    }

    /// An OBJ asset's positions, texture coordinates and triangles, as the OBJ loader hands
    /// them to this module (its vertices are unique position/texture pairs).
    fn obj_asset(relative: &str) -> (Vec<Vec3>, Vec<Vec2>, Vec<[u32; 3]>) {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("assets/obj")
            .join(relative);
        let mesh = crate::mesh::obj::load_obj(&path, &Default::default())
            .unwrap_or_else(|error| panic!("{error:?}"))
            .mesh;
        (mesh.positions, mesh.uvs, mesh.triangles)
    }

    #[test]
    fn vertices_split_as_the_hash_map_definition_splits_them_on_any_pool() {
        // A fan centre with more distinct normals than are searched one by one, UV seams,
        // creases, degenerate triangles, -0 beside +0.
        let mut fan_positions = vec![Vec3::ZERO, Vec3::new(-0.0, 0.0, 0.0)];
        let mut fan = Vec::new();
        for k in 0..40u32 {
            let angle = k as f32 * 0.157;
            fan_positions.push(Vec3::new(angle.cos(), angle.sin(), (k % 3) as f32));
            fan.push([k % 2, k + 2, (k + 1) % 40 + 2]);
        }
        fan.push([0, 0, 5]);
        let cases = [
            obj_asset("spot/spot_triangulated.obj"),
            obj_asset("cornell-box/CornellBox-Original.obj"),
            obj_asset("teapot/teapot.obj"),
            (fan_positions, Vec::new(), fan),
        ];
        for (positions, uvs, triangles) in &cases {
            let attributes = VertexAttributes {
                uvs,
                ..VertexAttributes::default()
            };
            for crease in [0.0, 60.0, 180.0] {
                let corners = CornersByPosition::new(positions, triangles);
                let normals = corner_normals(positions, triangles, &corners, crease);
                let normal_of_corner = |corner: usize| normals[corners.slot_of_corner[corner] as usize];
                let expected = split_by_hash_map(positions, attributes, triangles, normal_of_corner);
                for threads in [1, 3] {
                    let pool = rayon::ThreadPoolBuilder::new()
                        .num_threads(threads)
                        .build()
                        .unwrap();
                    let mesh =
                        pool.install(|| compute_vertex_normals(positions, attributes, triangles, crease));
                    assert!(mesh == expected, "{threads} threads, crease {crease}°");
                }
            }
        }
    }

    /// The crease sums by their definition (module documentation): for each corner, the
    /// weighted faces within the crease angle of its own, in corner order.
    fn crease_sums_by_definition(corners: &[u32], faces: CornerFaces, crease_cosine: f32) -> Vec<Vec3> {
        corners
            .iter()
            .map(|&corner| {
                let own = faces.face(corner);
                let mut sum = Vec3::ZERO;
                if own != Vec3::ZERO {
                    for &other in corners {
                        let face = faces.face(other);
                        if face != Vec3::ZERO && (other == corner || own.dot(face) >= crease_cosine) {
                            sum += faces.weight(other) * face;
                        }
                    }
                }
                sum
            })
            .collect()
    }

    #[test]
    fn crease_sums_of_smooth_and_creased_positions_follow_the_definition() {
        // Fans of 3 to 12 faces around one position, nearly flat (smooth: one sum for all),
        // folded (creased) and with degenerate faces, at crease angles from 0° to 180°.
        let mut rng = crate::test_support::XorShift32::new(0x9E37_79B9u32);
        let mut random = || {
            let state = rng.next_u32();
            state as f32 / u32::MAX as f32
        };
        for case in 0..2000 {
            let count = 3 + case % 10;
            let tilt = [0.05, 0.6, 2.0][case % 3];
            let faces: Vec<(Vec3, [f32; 3])> = (0..count)
                .map(|k| {
                    let face = if k % 7 == 6 {
                        Vec3::ZERO
                    } else {
                        unit_or_zero(Vec3::new(tilt * (random() - 0.5), tilt * (random() - 0.5), 1.0))
                    };
                    (face, [random(), random(), random()])
                })
                .collect();
            let corners: Vec<u32> = (0..count as u32).map(|k| 3 * k + k % 3).collect();
            let faces = CornerFaces { faces: &faces };
            for crease in [0.0f32, 10.0, 60.0, 180.0] {
                let cosine = crease.to_radians().cos() - CREASE_COSINE_TOLERANCE;
                let mut sums = Vec::new();
                sum_within_crease_exact(&corners, faces, cosine, &mut sums);
                let bits = |sums: &[Vec3]| -> Vec<[u32; 3]> {
                    sums.iter().map(|v| v.to_array().map(f32::to_bits)).collect()
                };
                let expected = crease_sums_by_definition(&corners, faces, cosine);
                assert_eq!(bits(&sums), bits(&expected), "case {case}, {crease}°");
            }
        }
    }
}
