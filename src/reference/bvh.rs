//! A bounding-volume hierarchy in `f64` for the reference's ray casts: axis-aligned boxes, built
//! top-down by the surface area heuristic over binned centroids, traversed nearest child first.
//!
//! It knows nothing of triangles: it is built from one box per primitive and asks the caller
//! to intersect the primitives of the leaves a ray reaches, so the reference keeps its exact
//! intersection, tie-breaking and back-face rules in one place (`mesh`).
//!
//! Why our own and not a crate (`bvh`, `obvhs`): both build and traverse in `f32` (`obvhs`
//! also reorders and quantises for speed), while the reference's geometry is `f64` end to end;
//! a box test in `f32` would need its own conservative widening to never miss an `f64` hit.
//! The whole of what the reference needs (build, nearest hit, any hit) is this file, and a
//! binned build is fast enough: 1.12 M triangles in about a second on two cores.
//!
//! Exactness: a box is tested with the slab method in `f64`, and the far distance is widened by
//! `3γ` (PBRT's bound on the slab test's rounding, γ = 3ε/(1 − 3ε)), so a ray that touches a
//! primitive is never lost by rounding at the box of its leaf.

use glam::DVec3;

/// Primitives per leaf at most; a node with fewer is a leaf whenever splitting costs more.
const MAX_LEAF: usize = 4;

/// Centroid bins per axis of the binned SAH build.
const BINS: usize = 16;

/// Subtrees at least this large are built on two threads.
const PARALLEL_BUILD: usize = 16 * 1024;

/// The SAH's cost of one traversal step, relative to one primitive test.
const TRAVERSAL_COST: f64 = 1.0;

/// Relative widening of the far slab distance: 3γ with γ = 3ε/(1 − 3ε).
const SLAB_WIDENING: f64 = 1.0 + 3.0 * (3.0 * f64::EPSILON / (1.0 - 3.0 * f64::EPSILON));

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aabb {
    pub min: DVec3,
    pub max: DVec3,
}

impl Aabb {
    pub const EMPTY: Aabb = Aabb {
        min: DVec3::splat(f64::INFINITY),
        max: DVec3::splat(f64::NEG_INFINITY),
    };

    pub fn of_points(points: &[DVec3]) -> Aabb {
        points.iter().fold(Aabb::EMPTY, |bounds, &p| bounds.with_point(p))
    }

    fn with_point(self, p: DVec3) -> Aabb {
        Aabb {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }

    fn union(self, other: Aabb) -> Aabb {
        Aabb {
            min: self.min.min(other.min),
            max: self.max.max(other.max),
        }
    }

    fn center(&self) -> DVec3 {
        (self.min + self.max) * 0.5
    }

    /// Half the surface area (the SAH compares ratios only); zero for an empty box.
    fn half_area(&self) -> f64 {
        let size = (self.max - self.min).max(DVec3::ZERO);
        size.x * size.y + size.y * size.z + size.z * size.x
    }

    /// The entry distance of the ray into the box if it meets it within `[t_min, t_max]`.
    #[inline]
    fn entry(&self, origin: DVec3, inverse_direction: DVec3, t_min: f64, t_max: f64) -> Option<f64> {
        let t0 = (self.min - origin) * inverse_direction;
        let t1 = (self.max - origin) * inverse_direction;
        // `min`/`max` drop a NaN (an origin on a slab plane with a zero direction component):
        // that axis then does not constrain the ray, which is the right answer.
        let near = t0.min(t1);
        let far = t0.max(t1);
        let enter = near.x.max(near.y).max(near.z).max(t_min);
        let exit = far.x.min(far.y).min(far.z).min(t_max) * SLAB_WIDENING;
        (enter <= exit).then_some(enter)
    }
}

/// A node: a leaf holds `count > 0` primitives from `first` in [`Bvh::order`]; an interior node
/// (`count == 0`) has its children at `index + 1` and `first`.
#[derive(Debug, Clone, Copy)]
struct Node {
    bounds: Aabb,
    first: u32,
    count: u32,
}

/// The most a build holds per primitive: its box, its build item and (at worst) a node.
pub const BUILD_BYTES_PER_PRIMITIVE: usize =
    std::mem::size_of::<Aabb>() + std::mem::size_of::<Item>() + std::mem::size_of::<Node>() + 4;

#[derive(Debug, Clone, Default)]
pub struct Bvh {
    nodes: Vec<Node>,
    /// Primitive numbers in leaf order.
    order: Vec<u32>,
}

/// A primitive while building: its number, box and centroid.
#[derive(Debug, Clone, Copy)]
struct Item {
    primitive: u32,
    bounds: Aabb,
    center: DVec3,
}

impl Bvh {
    /// The hierarchy over primitives with these boxes (primitive `i` has `bounds[i]`).
    pub fn build(bounds: &[Aabb]) -> Bvh {
        let mut items: Vec<Item> = bounds
            .iter()
            .enumerate()
            .map(|(index, b)| Item {
                primitive: index as u32,
                bounds: *b,
                center: b.center(),
            })
            .collect();
        if items.is_empty() {
            return Bvh::default();
        }
        let nodes = build_subtree(&mut items);
        Bvh {
            nodes,
            order: items.iter().map(|item| item.primitive).collect(),
        }
    }

    /// The primitive numbers in leaf order: `order()[k]` is the primitive a leaf calls `k`.
    pub fn order(&self) -> &[u32] {
        &self.order
    }

    /// Visits the leaves the ray `origin + t·direction` reaches within `[0, t_max]`, nearest
    /// child first, calling `test(k)` for each of their primitives by leaf position `k`;
    /// `test` returns the new `t_max` (the nearest hit so far). Boxes entered beyond the
    /// current `t_max` are skipped; one entered exactly at it is not, so ties reach the caller.
    pub fn nearest(
        &self,
        origin: DVec3,
        direction: DVec3,
        mut t_max: f64,
        mut test: impl FnMut(usize, f64) -> f64,
    ) {
        let inverse = direction.recip();
        let mut stack = [0u32; 64];
        let mut depth = 0usize;
        let Some(root) = self.nodes.first() else {
            return;
        };
        if root.bounds.entry(origin, inverse, 0.0, t_max).is_none() {
            return;
        }
        let mut index = 0usize;
        loop {
            let node = &self.nodes[index];
            if node.count > 0 {
                for k in node.first as usize..(node.first + node.count) as usize {
                    t_max = test(k, t_max);
                }
            } else {
                let (left, right) = (index + 1, node.first as usize);
                let hit_left = self.nodes[left].bounds.entry(origin, inverse, 0.0, t_max);
                let hit_right = self.nodes[right].bounds.entry(origin, inverse, 0.0, t_max);
                match (hit_left, hit_right) {
                    (Some(l), Some(r)) => {
                        let (near, far) = if l <= r { (left, right) } else { (right, left) };
                        if depth < stack.len() {
                            stack[depth] = far as u32;
                            depth += 1;
                            index = near;
                            continue;
                        }
                        // Deeper than any SAH build of a real mesh goes: finish this subtree
                        // by recursion instead of overflowing the stack array.
                        self.nearest_from(near, origin, inverse, &mut t_max, &mut test);
                        index = far;
                        continue;
                    }
                    (Some(_), None) => {
                        index = left;
                        continue;
                    }
                    (None, Some(_)) => {
                        index = right;
                        continue;
                    }
                    (None, None) => {}
                }
            }
            // Pop the next subtree still in reach.
            loop {
                if depth == 0 {
                    return;
                }
                depth -= 1;
                let next = stack[depth] as usize;
                if self.nodes[next]
                    .bounds
                    .entry(origin, inverse, 0.0, t_max)
                    .is_some()
                {
                    index = next;
                    break;
                }
            }
        }
    }

    /// [`Bvh::nearest`] from the node `index`, recursively.
    fn nearest_from(
        &self,
        index: usize,
        origin: DVec3,
        inverse: DVec3,
        t_max: &mut f64,
        test: &mut impl FnMut(usize, f64) -> f64,
    ) {
        let node = &self.nodes[index];
        if node.bounds.entry(origin, inverse, 0.0, *t_max).is_none() {
            return;
        }
        if node.count > 0 {
            for k in node.first as usize..(node.first + node.count) as usize {
                *t_max = test(k, *t_max);
            }
        } else {
            self.nearest_from(index + 1, origin, inverse, t_max, test);
            self.nearest_from(node.first as usize, origin, inverse, t_max, test);
        }
    }

    /// Whether `hits(k)` holds for some primitive of a leaf the ray reaches within
    /// `[t_min, t_max]` (shadow rays: any hit ends the search).
    pub fn any(
        &self,
        origin: DVec3,
        direction: DVec3,
        t_min: f64,
        t_max: f64,
        mut hits: impl FnMut(usize) -> bool,
    ) -> bool {
        let inverse = direction.recip();
        let mut stack = Vec::with_capacity(64);
        if !self.nodes.is_empty() {
            stack.push(0usize);
        }
        while let Some(index) = stack.pop() {
            let node = &self.nodes[index];
            if node.bounds.entry(origin, inverse, t_min, t_max).is_none() {
                continue;
            }
            if node.count > 0 {
                if (node.first as usize..(node.first + node.count) as usize).any(&mut hits) {
                    return true;
                }
            } else {
                stack.push(node.first as usize);
                stack.push(index + 1);
            }
        }
        false
    }
}

/// The nodes of the subtree over `items` (reordered into leaf order), its root first; leaf
/// `first`s count from the start of `items`, child indices from the subtree's root.
fn build_subtree(items: &mut [Item]) -> Vec<Node> {
    let bounds = items.iter().fold(Aabb::EMPTY, |b, item| b.union(item.bounds));
    let count = items.len();
    let leaf = || {
        vec![Node {
            bounds,
            first: 0,
            count: count as u32,
        }]
    };
    if items.len() <= 1 {
        return leaf();
    }
    let Some(split) = best_split(items, &bounds) else {
        return leaf();
    };
    let middle = partition(items, |item| split.goes_left(item.center));
    // A split that leaves a side empty (all centroids in one bin's range after rounding) would
    // recurse forever: halve by order instead.
    let middle = if middle == 0 || middle == items.len() {
        if items.len() <= MAX_LEAF {
            return leaf();
        }
        items.len() / 2
    } else {
        middle
    };
    let (left_items, right_items) = items.split_at_mut(middle);
    let (left, right) = if left_items.len() + right_items.len() >= PARALLEL_BUILD {
        rayon::join(|| build_subtree(left_items), || build_subtree(right_items))
    } else {
        (build_subtree(left_items), build_subtree(right_items))
    };
    let mut nodes = Vec::with_capacity(1 + left.len() + right.len());
    nodes.push(Node {
        bounds,
        first: (1 + left.len()) as u32,
        count: 0,
    });
    let shift = |node: Node, node_base: usize, item_base: usize| {
        if node.count > 0 {
            Node {
                first: node.first + item_base as u32,
                ..node
            }
        } else {
            Node {
                first: node.first + node_base as u32,
                ..node
            }
        }
    };
    nodes.extend(left.iter().map(|&node| shift(node, 1, 0)));
    let right_base = nodes.len();
    nodes.extend(right.iter().map(|&node| shift(node, right_base, middle)));
    nodes
}

/// A split plane: centroids below `bin` on `axis` go left.
struct Split {
    axis: usize,
    bin: usize,
    low: f64,
    scale: f64,
}

impl Split {
    fn bin_of(axis_low: f64, scale: f64, value: f64) -> usize {
        (((value - axis_low) * scale) as usize).min(BINS - 1)
    }

    fn goes_left(&self, center: DVec3) -> bool {
        Split::bin_of(self.low, self.scale, center[self.axis]) < self.bin
    }
}

/// The cheapest binned SAH split of `items`, or `None` when a leaf is cheaper (and allowed).
fn best_split(items: &[Item], bounds: &Aabb) -> Option<Split> {
    let centers = items
        .iter()
        .fold(Aabb::EMPTY, |b, item| b.with_point(item.center));
    let extent = centers.max - centers.min;
    let mut best: Option<(f64, Split)> = None;
    for axis in 0..3 {
        if extent[axis] <= 0.0 || !extent[axis].is_finite() {
            continue;
        }
        let scale = BINS as f64 / extent[axis];
        let low = centers.min[axis];
        let mut bin_bounds = [Aabb::EMPTY; BINS];
        let mut bin_counts = [0usize; BINS];
        for item in items {
            let bin = Split::bin_of(low, scale, item.center[axis]);
            bin_bounds[bin] = bin_bounds[bin].union(item.bounds);
            bin_counts[bin] += 1;
        }
        // Sweep from the right, keeping each suffix's area and count, then from the left.
        let mut right_area = [0.0; BINS];
        let mut right_count = [0usize; BINS];
        let (mut b, mut n) = (Aabb::EMPTY, 0);
        for bin in (1..BINS).rev() {
            b = b.union(bin_bounds[bin]);
            n += bin_counts[bin];
            right_area[bin] = b.half_area();
            right_count[bin] = n;
        }
        let (mut b, mut n) = (Aabb::EMPTY, 0);
        for bin in 1..BINS {
            b = b.union(bin_bounds[bin - 1]);
            n += bin_counts[bin - 1];
            if n == 0 || right_count[bin] == 0 {
                continue;
            }
            let cost = b.half_area() * n as f64 + right_area[bin] * right_count[bin] as f64;
            if best.as_ref().is_none_or(|(best_cost, _)| cost < *best_cost) {
                best = Some((
                    cost,
                    Split {
                        axis,
                        bin,
                        low,
                        scale,
                    },
                ));
            }
        }
    }
    let area = bounds.half_area();
    let leaf_cost = items.len() as f64;
    match best {
        Some((cost, split)) => {
            let split_cost = TRAVERSAL_COST + if area > 0.0 { cost / area } else { leaf_cost };
            (items.len() > MAX_LEAF || split_cost < leaf_cost).then_some(split)
        }
        // Every centroid at one point: split by order if the leaf would be too large.
        None if items.len() > MAX_LEAF => Some(Split {
            axis: 0,
            bin: 0,
            low: 0.0,
            scale: 0.0,
        }),
        None => None,
    }
}

/// Moves the items for which `left` holds to the front; returns how many there are.
fn partition(items: &mut [Item], left: impl Fn(&Item) -> bool) -> usize {
    let mut middle = 0;
    for index in 0..items.len() {
        if left(&items[index]) {
            items.swap(middle, index);
            middle += 1;
        }
    }
    middle
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Boxes along a line, and rays: the BVH reports the same nearest and any hits as testing
    /// every box.
    #[test]
    fn finds_what_testing_every_primitive_finds() {
        let mut rng = crate::test_support::XorShift64::new(0x2545_f491_4f6c_dd1du64);
        let mut random = || {
            let state = rng.next_u64();
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let boxes: Vec<Aabb> = (0..3000)
            .map(|_| {
                let c = DVec3::new(random(), random(), random()) * 10.0;
                let h = DVec3::new(random(), random(), random()) * 0.2;
                Aabb {
                    min: c - h,
                    max: c + h,
                }
            })
            .collect();
        let bvh = Bvh::build(&boxes);
        let mut sorted = bvh.order().to_vec();
        sorted.sort_unstable();
        assert_eq!(sorted, (0..3000).collect::<Vec<u32>>());
        for _ in 0..500 {
            let origin = DVec3::new(random(), random(), -1.0) * DVec3::new(10.0, 10.0, 1.0);
            let direction = DVec3::new(random() - 0.5, random() - 0.5, 1.0) * 12.0;
            let inverse = direction.recip();
            let expected = boxes
                .iter()
                .filter_map(|b| b.entry(origin, inverse, 0.0, 1.0))
                .fold(f64::INFINITY, f64::min);
            let mut found = f64::INFINITY;
            bvh.nearest(origin, direction, 1.0, |k, t_max| {
                let primitive = bvh.order()[k] as usize;
                match boxes[primitive].entry(origin, inverse, 0.0, t_max) {
                    Some(t) => {
                        found = found.min(t);
                        t
                    }
                    None => t_max,
                }
            });
            assert_eq!(found, expected);
            let any = bvh.any(origin, direction, 0.0, 1.0, |k| {
                boxes[bvh.order()[k] as usize]
                    .entry(origin, inverse, 0.0, 1.0)
                    .is_some()
            });
            assert_eq!(any, expected.is_finite());
        }
    }

    #[test]
    fn empty_and_coincident_primitives() {
        let bvh = Bvh::build(&[]);
        bvh.nearest(DVec3::ZERO, DVec3::X, 1.0, |_, _| panic!("no primitives"));
        let point = Aabb {
            min: DVec3::ONE,
            max: DVec3::ONE,
        };
        let bvh = Bvh::build(&[point; 100]);
        assert_eq!(bvh.order().len(), 100);
        let mut tested = 0;
        bvh.nearest(DVec3::ZERO, DVec3::splat(2.0), 1.0, |_, t| {
            tested += 1;
            t
        });
        assert_eq!(tested, 100);
    }
}
