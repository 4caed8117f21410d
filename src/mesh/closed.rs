//! Whether a mesh file's surface is closed, so that its back faces may be culled.
//!
//! A surface bounds a volume, with every front face seen from outside, when
//! - every edge is shared by exactly two triangles that run along it in opposite directions
//!   (consistent winding; no border, no fin of three or more triangles), and
//! - each connected piece encloses a positive signed volume (its counter-clockwise sides face
//!   outwards; an inside-out piece has its front faces inside).
//!
//! Vertices are compared by position, not by index: loaders split a vertex wherever its normal or
//! texture coordinates change (a UV seam, a hard edge), which leaves the surface closed but its
//! indices apart. Triangles whose corners share a position have no area and bound nothing; they
//! are left out. Several closed pieces together are closed too: a ray from outside all of them
//! meets each piece's front face before its back faces, whatever the pieces do to each other.
//!
//! The primitives know that they are closed; mesh files are tested once at load
//! (`Mesh::closed`), and the geometry stage then skips their back faces when the eye cannot be
//! inside or the near plane cut them open (`render::geometry`).

use glam::Vec3;

use super::normals::{WordMap, word_map};

/// Whether the surface of `triangles` over `positions` is closed and faces outwards (module
/// documentation). An empty surface is not closed; an index past the positions, or a position
/// that is not finite, makes it open.
///
/// Linear in the triangles: positions are welded through a hash map, and each position's
/// outgoing edges are gathered by a counting sort, so an edge's reverse is looked up among the
/// few edges leaving its end (a handful on a scan). Sorting every directed edge, as this once
/// did, took a third of the koala scan's load.
pub fn is_closed(positions: &[Vec3], triangles: &[[u32; 3]]) -> bool {
    is_closed_in_parts(positions, &[triangles])
}

/// [`is_closed`] on the triangles of `parts` one after the other (the ranges of an OBJ file's
/// lines, tested before they are assembled into one list).
pub fn is_closed_in_parts(positions: &[Vec3], parts: &[&[[u32; 3]]]) -> bool {
    let triangles = || parts.iter().flat_map(|part| part.iter().copied());
    let triangle_count = parts.iter().map(|part| part.len()).sum();
    let Some((corners, position_count)) = welded_corners(positions, triangles(), triangle_count) else {
        return false;
    };
    let edges = OutgoingEdges::new(&corners, position_count);
    if edges.is_empty() {
        return false;
    }
    // Closed when no position has two edges to the same neighbour (no two triangles run the same
    // way along an edge, no fin) and every edge `from → to` has its reverse `to → from`: each
    // edge's other triangle runs the other way. With no edge twice, it is enough that each edge
    // running up (`from < to`) finds its reverse and that as many run down: the reverses found
    // are then every edge running down. An edge and its reverse join their triangles' pieces.
    let mut pieces = Pieces::new(triangle_count);
    let mut edges_up = 0;
    for from in 0..position_count {
        let leaving = edges.leaving(from);
        if leaving.windows(2).any(|pair| pair[0].to == pair[1].to) {
            return false;
        }
        // Sorted by `to`: the edges running up come last.
        let up = &leaving[leaving.partition_point(|edge| (edge.to as usize) < from)..];
        for edge in up {
            let Some(reverse) = edges.find(edge.to as usize, from as u32) else {
                return false; // a border edge
            };
            pieces.join(edge.triangle as usize, reverse.triangle as usize);
        }
        edges_up += up.len();
    }
    if 2 * edges_up != edges.len() {
        return false; // some edge running down has no reverse: a border edge
    }
    // Six times each piece's signed volume: the sum of `p_a · (p_b × p_c)` over its triangles,
    // added in triangle order into its piece's root (the piece's first triangle).
    let mut volumes = vec![0.0f64; triangle_count];
    for (triangle, vertices) in triangles().enumerate() {
        if corners[triangle].is_some() {
            let [pa, pb, pc] = vertices.map(|v| positions[v as usize].as_dvec3());
            volumes[pieces.root(triangle)] += pa.dot(pb.cross(pc));
        }
    }
    (0..triangle_count)
        .filter(|&triangle| corners[triangle].is_some() && pieces.root(triangle) == triangle)
        .all(|root| volumes[root] > 0.0)
}

/// Per triangle, its corners as position ids (equal positions, equal ids), or `None` when two
/// corners are one position; and how many ids there are. `None` for the whole when an index is
/// out of range or a position is not finite.
fn welded_corners(
    positions: &[Vec3],
    triangles: impl Iterator<Item = [u32; 3]>,
    triangle_count: usize,
) -> Option<(Vec<Option<[u32; 3]>>, usize)> {
    if positions.iter().any(|p| !p.is_finite()) {
        return None;
    }
    // +0.0 for −0.0, so that the two zeros are one position.
    let key = |p: Vec3| (p + Vec3::ZERO).to_array().map(f32::to_bits);
    let mut id_by_position: WordMap<[u32; 3], u32> = word_map(positions.len());
    let id_of_index: Vec<u32> = positions
        .iter()
        .map(|&position| {
            let next = id_by_position.len() as u32;
            *id_by_position.entry(key(position)).or_insert(next)
        })
        .collect();
    // Sized up front: collecting from the parts' chained triangles would grow it by doubling.
    let mut corners = Vec::with_capacity(triangle_count);
    for triangle in triangles {
        let [a, b, c] = triangle.map(|v| id_of_index.get(v as usize).copied());
        let [a, b, c] = [a?, b?, c?];
        corners.push((a != b && b != c && c != a).then_some([a, b, c]));
    }
    Some((corners, id_by_position.len()))
}

/// A directed edge of a triangle, kept with the position it leaves from.
#[derive(Debug, Clone, Copy)]
struct Edge {
    to: u32,
    triangle: u32,
}

/// Every directed edge of the non-degenerate triangles, grouped by the position it leaves from
/// (a counting sort) and sorted by the position it goes to within each group.
struct OutgoingEdges {
    /// The edges leaving position p are `edges[start[p]..start[p + 1]]`.
    start: Vec<u32>,
    edges: Vec<Edge>,
}

impl OutgoingEdges {
    fn new(corners: &[Option<[u32; 3]>], position_count: usize) -> Self {
        let directed = || {
            corners.iter().enumerate().filter_map(|(triangle, corners)| {
                corners.map(|[a, b, c]| (triangle as u32, [(a, b), (b, c), (c, a)]))
            })
        };
        let mut start = vec![0u32; position_count + 1];
        for (_, triangle_edges) in directed() {
            for (from, _) in triangle_edges {
                start[from as usize + 1] += 1;
            }
        }
        for position in 0..position_count {
            start[position + 1] += start[position];
        }
        let mut next = start.clone();
        let mut edges = vec![Edge { to: 0, triangle: 0 }; start[position_count] as usize];
        for (triangle, triangle_edges) in directed() {
            for (from, to) in triangle_edges {
                let slot = &mut next[from as usize];
                edges[*slot as usize] = Edge { to, triangle };
                *slot += 1;
            }
        }
        let mut outgoing = OutgoingEdges { start, edges };
        for position in 0..position_count {
            let range = outgoing.range(position);
            outgoing.edges[range].sort_unstable_by_key(|edge| edge.to);
        }
        outgoing
    }

    fn is_empty(&self) -> bool {
        self.edges.is_empty()
    }

    fn len(&self) -> usize {
        self.edges.len()
    }

    fn range(&self, from: usize) -> std::ops::Range<usize> {
        self.start[from] as usize..self.start[from + 1] as usize
    }

    /// The edges leaving `from`, sorted by the position they go to.
    fn leaving(&self, from: usize) -> &[Edge] {
        &self.edges[self.range(from)]
    }

    /// The edge `from → to`, if there is one (the first, should there be several).
    fn find(&self, from: usize, to: u32) -> Option<Edge> {
        let leaving = self.leaving(from);
        let index = leaving.partition_point(|edge| edge.to < to);
        leaving.get(index).filter(|edge| edge.to == to).copied()
    }
}

/// Connected pieces of triangles (union-find with path halving): a piece's root is its first
/// triangle.
struct Pieces {
    /// Triangle numbers as `u32` (a mesh's indices are): half the memory of `usize` on a
    /// million triangles, where these lookups miss the cache.
    parent: Vec<u32>,
}

impl Pieces {
    fn new(count: usize) -> Self {
        Pieces {
            parent: (0..count as u32).collect(),
        }
    }

    fn root(&mut self, item: usize) -> usize {
        let mut item = item as u32;
        while self.parent[item as usize] != item {
            let grandparent = self.parent[self.parent[item as usize] as usize];
            self.parent[item as usize] = grandparent;
            item = grandparent;
        }
        item as usize
    }

    fn join(&mut self, a: usize, b: usize) {
        let (a, b) = (self.root(a), self.root(b));
        if a != b {
            self.parent[a.max(b)] = a.min(b) as u32;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A unit cube's eight corners and twelve counter-clockwise (outward) triangles.
    fn cube() -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let positions = (0..8)
            .map(|i| Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32))
            .collect();
        let quads = [
            [0, 2, 3, 1], // z = 0, facing −z
            [4, 5, 7, 6], // z = 1
            [0, 1, 5, 4], // y = 0
            [2, 6, 7, 3], // y = 1
            [0, 4, 6, 2], // x = 0
            [1, 3, 7, 5], // x = 1
        ];
        let triangles = quads
            .iter()
            .flat_map(|&[a, b, c, d]| [[a, b, c], [a, c, d]])
            .collect();
        (positions, triangles)
    }

    fn inside_out(triangles: &[[u32; 3]]) -> Vec<[u32; 3]> {
        triangles.iter().map(|&[a, b, c]| [a, c, b]).collect()
    }

    #[test]
    fn a_cube_is_closed_and_inside_out_it_is_not() {
        let (positions, triangles) = cube();
        assert!(is_closed(&positions, &triangles));
        assert!(!is_closed(&positions, &inside_out(&triangles)));
    }

    #[test]
    fn triangles_in_parts_are_tested_as_one_list() {
        let (positions, triangles) = cube();
        let reversed = inside_out(&triangles);
        for split in 0..triangles.len() {
            let (first, second) = triangles.split_at(split);
            assert!(is_closed_in_parts(&positions, &[first, &[], second]));
            assert!(
                !is_closed_in_parts(&positions, &[first, &second[1..]]),
                "one face missing"
            );
            let (first, second) = reversed.split_at(split);
            assert!(!is_closed_in_parts(&positions, &[first, second]), "inside out");
        }
        assert!(!is_closed_in_parts(&positions, &[]));
    }

    #[test]
    fn a_missing_face_a_flipped_face_or_a_fin_opens_it() {
        let (positions, triangles) = cube();
        assert!(!is_closed(&positions, &triangles[..10]), "one face missing");
        let mut flipped = triangles.clone();
        flipped[3] = [flipped[3][0], flipped[3][2], flipped[3][1]];
        assert!(
            !is_closed(&positions, &flipped),
            "one triangle wound the other way"
        );
        let mut fin = positions.clone();
        fin.push(Vec3::new(0.5, 0.5, 3.0));
        let mut with_fin = triangles.clone();
        with_fin.push([4, 5, 8]);
        assert!(!is_closed(&fin, &with_fin), "a third triangle on an edge");
    }

    #[test]
    fn vertices_split_at_seams_are_welded_by_position() {
        // Every triangle gets its own three vertices, as a loader does at hard edges.
        let (positions, triangles) = cube();
        let split_positions: Vec<Vec3> = triangles
            .iter()
            .flat_map(|t| t.map(|v| positions[v as usize]))
            .collect();
        let split_triangles: Vec<[u32; 3]> = (0..triangles.len() as u32)
            .map(|t| [3 * t, 3 * t + 1, 3 * t + 2])
            .collect();
        assert!(is_closed(&split_positions, &split_triangles));
        // −0.0 and +0.0 are one position.
        let mut signed_zeros = split_positions.clone();
        signed_zeros[0].x = -0.0;
        assert!(is_closed(&signed_zeros, &split_triangles));
    }

    #[test]
    fn separate_closed_pieces_are_closed_unless_one_is_inside_out() {
        let (positions, triangles) = cube();
        let mut two = positions.clone();
        two.extend(positions.iter().map(|p| *p + Vec3::new(3.0, 0.0, 0.0)));
        let shifted = |t: &[[u32; 3]]| t.iter().map(|f| f.map(|v| v + 8)).collect::<Vec<_>>();
        let both = [triangles.clone(), shifted(&triangles)].concat();
        assert!(is_closed(&two, &both));
        let one_inverted = [triangles.clone(), shifted(&inside_out(&triangles))].concat();
        assert!(!is_closed(&two, &one_inverted));
    }

    /// A double cone: two fans of `sides` triangles around the apexes at z = ±1, sharing the
    /// rim; the apexes have far more edges than a scan's vertices.
    fn double_cone(sides: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let mut positions = vec![Vec3::Z, -Vec3::Z];
        positions.extend((0..sides).map(|i| {
            let angle = i as f32 / sides as f32 * std::f32::consts::TAU;
            Vec3::new(angle.cos(), angle.sin(), 0.0)
        }));
        let rim = |i: u32| 2 + i % sides;
        let triangles = (0..sides)
            .flat_map(|i| [[0, rim(i), rim(i + 1)], [1, rim(i + 1), rim(i)]])
            .collect();
        (positions, triangles)
    }

    #[test]
    fn positions_with_many_edges_are_paired_like_any_other() {
        let (positions, triangles) = double_cone(300);
        assert!(is_closed(&positions, &triangles));
        assert!(!is_closed(&positions, &triangles[1..]), "one triangle missing");
        let mut doubled = triangles.clone();
        doubled.push(triangles[7]);
        assert!(!is_closed(&positions, &doubled), "an edge run twice the same way");
        assert!(!is_closed(&positions, &inside_out(&triangles)));
    }

    #[test]
    fn degenerate_triangles_are_ignored_and_bad_input_is_open() {
        let (positions, mut triangles) = cube();
        triangles.push([0, 0, 1]);
        assert!(
            is_closed(&positions, &triangles),
            "a zero-area triangle bounds nothing"
        );
        assert!(
            !is_closed(&positions, &[[0, 1, 99]]),
            "an index past the positions"
        );
        let mut not_finite = positions.clone();
        not_finite[0].x = f32::NAN;
        assert!(!is_closed(&not_finite, &triangles));
        assert!(!is_closed(&[], &[]));
    }
}
