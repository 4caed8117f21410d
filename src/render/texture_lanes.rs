//! Texture sampling eight points at a time: [`Texture::sample`] lane by lane, with its bits.
//!
//! `Texture::sample` is the specification (`texture`'s module block derives the level of
//! detail, the filtering and the wrapping); [`sample_lanes`] computes the same IEEE operations
//! for each lane, and a test holds the two together bit for bit. What differs is how:
//!
//! - The footprint `ρ` and the choice between magnification and minification are lane-wise.
//!   `λ = log₂ ρ` is at most 0 exactly where `ρ ≤ 1` (`log2f` is exact at 1, and its error,
//!   below one unit in the last place, cannot change the sign of a logarithm whose magnitude
//!   is at least 2⁻²⁴/ln 2), so only lanes with `ρ > 1` need the logarithm (with a positive
//!   mip bias every lane with `ρ > 0`); either way the lane's `λ + bias` is the scalar's sum.
//!   The logarithm is lane-wise too where the C library's `log2f` is known ([`log2`]: glibc's
//!   algorithm in lanes, with its bits), else `log2f` per lane.
//! - Texel coordinates are the specification's `f64` ones, `x = u·w − ½` (exact: 24 by 32
//!   significant bits), but its `floor` and the wrap's `rem_euclid`, library calls that were
//!   two thirds of the scalar sampler's instructions, are integer operations here. For a whole
//!   `f64` below 2⁵³ in magnitude `floor`, `rem_euclid` (`fmod` is exact), the mirrored
//!   reflection and the clamp are exact, so the integers name the same texels; for a
//!   power-of-two size `rem_euclid` is a mask. With |u| < 2²⁰ and sizes below 2³², |x| stays
//!   below 2⁵² + ½; a lane with a coordinate beyond that (far outside any real texture
//!   coordinate) is sampled by `Texture::sample` itself.
//!
//! The texel fetches and the filter (`a + (b − a)·f`, then the blend between levels) stay per
//! lane, in `Vec4`s: each lane reads its own texels, at its own level. The lane-wise part is
//! generic over the lanes' backend, so a textured batch runs it on the widest lanes
//! (`lanes::run_widest`).

mod log2;

use glam::{Vec2, Vec4};

use crate::render::lanes::{Backend, Floats, Ints, LANES, Mask, Vec2s};
use crate::texture::{MipLevel, Sampler, Texture, Wrap};
use log2::log2_lanes;

/// Texture coordinates at least this far from 0 are sampled by the specification: below it,
/// texel coordinates on any level (fewer than 2³² texels a side) are whole `f64`s below 2⁵²,
/// where the floor by truncation and the integer wrap are exact.
const INTEGER_RANGE: f32 = (1u32 << 20) as f32;

/// [`Texture::sample`] of each lane: the filtered value at `uv` for a pixel whose footprint
/// spans `uv_dx` and `uv_dy`, with the bits of the scalar call on the lane's inputs. On lanes
/// of backend `B` (see `lanes::run_widest`).
#[inline(always)]
pub fn sample_lanes<B: Backend>(
    texture: &Texture,
    uv: Vec2s<B>,
    uv_dx: Vec2s<B>,
    uv_dy: Vec2s<B>,
    sampler: &Sampler,
    mip_bias: f32,
) -> [Vec4; LANES] {
    let Some(base) = texture.levels.first() else {
        return [Vec4::ZERO; LANES];
    };
    let at = finite_or_zero(uv);
    let size = Vec2s {
        x: Floats::splat(base.width as f32),
        y: Floats::splat(base.height as f32),
    };
    // `f32::max` of the two lengths: neither is NaN (the lengths of finite vectors are finite
    // or +∞) nor −0, so the larger by `>` is the same value.
    let (along_x, along_y) = (texel_length(uv_dx, size), texel_length(uv_dy, size));
    let footprint = along_x.gt(along_y).select(along_x, along_y);
    let last_level = texture.levels.len() - 1;
    // With a bias of at most 0, `λ + bias > 0` needs `ρ > 1`; a positive bias can make any
    // footprint above 0 minified.
    let may_be_minified = Floats::splat(if mip_bias > 0.0 { 0.0 } else { 1.0 });
    let minified = if last_level == 0 {
        !Mask::<B>::ALL
    } else {
        footprint.gt(may_be_minified)
    };
    // Per lane, `Texture::sample`'s choice of levels: bilinear in `lower`, and where `blend`
    // is above 0 in `lower + 1` too, blended by it. The logarithm is taken of minified lanes only;
    // the rest is lane-wise: λ's clamp to the last level (`f32::min`, λ not NaN), its floor
    // by the rounding of `texel_pairs` (λ is below 2²²), and the fraction left.
    let zero = Floats::splat(0.0);
    let lod = if minified.any() {
        minified.select(log2_lanes(footprint, minified) + Floats::splat(mip_bias), zero)
    } else {
        zero
    };
    let minified = lod.gt(zero);
    let last = Floats::splat(last_level as f32);
    let lod = lod.gt(last).select(last, lod);
    let (floor, level) = floor_lanes(lod);
    let fraction = lod - floor;
    let last_index = Ints::splat(last_level as i32);
    let lower = minified.select_ints(level, Ints::splat(0));
    let blended = minified.and(last_index.gt(lower)).and(fraction.gt(zero));
    // Lanes beyond the integer range are sampled by `Texture::sample`; the lanes take 0 there.
    let limit = Floats::splat(INTEGER_RANGE);
    let integral = within(at.x, limit).and(within(at.y, limit));
    let at = Vec2s {
        x: integral.select(at.x, zero),
        y: integral.select(at.y, zero),
    };
    let mut near = [Vec4::ZERO; LANES];
    bilinear_lanes(texture, lower, at, sampler, |lane, value| near[lane] = value);
    if blended.any() {
        // Lanes that are not blended read the level of the first blended lane (their values
        // are not used), so that a batch whose blended lanes share a level reads one level.
        let first_blended = (0..LANES).find(|&lane| blended.lane(lane)).unwrap_or(0);
        let upper = lower + Ints::splat(1);
        let upper = blended.select_ints(upper, Ints::splat(upper.0[first_blended]));
        // Each far value blended into the near one as it is filtered.
        bilinear_lanes(texture, upper, at, sampler, |lane, far| {
            if blended.lane(lane) {
                let near = &mut near[lane];
                *near = *near + (far - *near) * fraction.0[lane];
            }
        });
    }
    if integral.all() {
        return near;
    }
    for (lane, value) in near.iter_mut().enumerate() {
        if !integral.lane(lane) {
            let pick = |v: Vec2s<B>| Vec2::new(v.x.0[lane], v.y.0[lane]);
            *value = texture.sample_biased(pick(uv), pick(uv_dx), pick(uv_dy), sampler, mip_bias);
        }
    }
    near
}

/// The length of the change `d` in texture coordinates, in texels of a level of `size`
/// (non-finite components taken as 0).
#[inline(always)]
fn texel_length<B: Backend>(d: Vec2s<B>, size: Vec2s<B>) -> Floats<B> {
    let d = finite_or_zero(d);
    Vec2s {
        x: d.x * size.x,
        y: d.y * size.y,
    }
    .length()
}

/// Whether each lane of `t` lies strictly between `−limit` and `limit`.
#[inline(always)]
fn within<B: Backend>(t: Floats<B>, limit: Floats<B>) -> Mask<B> {
    limit.gt(t).and(t.gt(-limit))
}

/// Each component where it is finite, else 0 (`texture::finite_or_zero`).
#[inline(always)]
fn finite_or_zero<B: Backend>(v: Vec2s<B>) -> Vec2s<B> {
    let zero = Floats::splat(0.0);
    Vec2s {
        x: v.x.is_finite().select(v.x, zero),
        y: v.y.is_finite().select(v.y, zero),
    }
}

/// `1.5·2²³`: added to an `f32` below 2²² in magnitude, the sum lies in [2²³, 2²⁴), whose
/// spacing is 1, so the addition rounds the value to a whole number (ties to even), which
/// subtracting it again leaves exact, and which the sum's low bits hold as an integer.
const ROUND: f32 = 12_582_912.0;

/// The floor of each lane (below 2²² in magnitude), as a float and as an integer: the value
/// rounded by [`ROUND`], one less where that rounded up.
#[inline(always)]
fn floor_lanes<B: Backend>(x: Floats<B>) -> (Floats<B>, Ints<B>) {
    let sum = x + Floats::splat(ROUND);
    let nearest = sum - Floats::splat(ROUND);
    let above = nearest.gt(x);
    let floor = above.select(nearest - Floats::splat(1.0), nearest);
    // `above` is −1 where it holds.
    let integer = sum.to_bits() - Ints::splat(ROUND.to_bits() as i32) + above.to_ints();
    (floor, integer)
}

/// `texture::bilinear` of each lane at `uv` in its level `levels.0[lane]` of `texture`, handed
/// to `put` with its lane: the same texels, weights and filter, the texel pairs found lane-wise
/// ([`texel_pairs`]). Lanes with coordinates beyond [`INTEGER_RANGE`] get a value that is not
/// used.
#[inline(always)]
fn bilinear_lanes<B: Backend>(
    texture: &Texture,
    levels: Ints<B>,
    uv: Vec2s<B>,
    sampler: &Sampler,
    mut put: impl FnMut(usize, Vec4),
) {
    let level = |lane: usize| &texture.levels[levels.0[lane] as usize];
    if levels.0.iter().all(|&l| l == levels.0[0]) {
        let level = level(0);
        let (width, height) = (level.width, level.height);
        let xs = texel_pairs(uv.x, Sizes::splat(width), sampler.wrap_s);
        let ys = texel_pairs(uv.y, Sizes::splat(height), sampler.wrap_t);
        if xs.exact.and(ys.exact).all() && holds_every_texel(level) {
            // The common case: one level, every index wrapped into it lane-wise, so each
            // texel is at `y·width + x`, inside the level (`MipLevel::texel` without its tests,
            // which the wrap and the level's size make true).
            let (width, texels) = (width as usize, &level.texels[..]);
            for lane in 0..LANES {
                let ((x0, x1, fx), (y0, y1, fy)) = (xs.exact_lane(lane), ys.exact_lane(lane));
                let (row0, row1) = (y0 * width, y1 * width);
                let top = lerp(texels[row0 + x0], texels[row0 + x1], fx);
                let bottom = lerp(texels[row1 + x0], texels[row1 + x1], fx);
                put(lane, lerp(top, bottom, fy));
            }
            return;
        }
    }
    // Lanes at different levels, or some not `exact`: the pairs of each lane's own level.
    let widths: [u32; LANES] = std::array::from_fn(|lane| level(lane).width);
    let heights: [u32; LANES] = std::array::from_fn(|lane| level(lane).height);
    let xs = texel_pairs(uv.x, Sizes::of(&widths), sampler.wrap_s);
    let ys = texel_pairs(uv.y, Sizes::of(&heights), sampler.wrap_t);
    for lane in 0..LANES {
        let level = level(lane);
        let (x0, x1, fx) = xs.lane(lane, uv.x, &widths, sampler.wrap_s);
        let (y0, y1, fy) = ys.lane(lane, uv.y, &heights, sampler.wrap_t);
        let top = lerp(level.texel(x0, y0), level.texel(x1, y0), fx);
        let bottom = lerp(level.texel(x0, y1), level.texel(x1, y1), fx);
        put(lane, lerp(top, bottom, fy));
    }
}

/// `a + (b − a)·f`, `texture::bilinear`'s filter step.
#[inline(always)]
fn lerp(a: Vec4, b: Vec4, f: f32) -> Vec4 {
    a + (b - a) * f
}

/// Whether `level` holds its `width·height` texels (`MipLevel`'s invariant, which every
/// constructor keeps; its fields are public, so the fast path checks it once per lookup).
#[inline(always)]
fn holds_every_texel(level: &MipLevel) -> bool {
    level.texels.len() as u64 == u64::from(level.width) * u64::from(level.height)
}

/// The sizes of an axis of each lane's level, as integers (those above 2²⁴, which are not
/// exact as `f32`, marked as no power of two) and as floats.
#[derive(Clone, Copy)]
struct Sizes<B: Backend> {
    integers: Ints<B>,
    floats: Floats<B>,
}

impl<B: Backend> Sizes<B> {
    #[inline(always)]
    fn integer(size: u32) -> i32 {
        if size <= 1 << 24 { size as i32 } else { 3 }
    }

    #[inline(always)]
    fn splat(size: u32) -> Self {
        Sizes {
            integers: Ints::splat(Self::integer(size)),
            floats: Floats::splat(size as f32),
        }
    }

    #[inline(always)]
    fn of(sizes: &[u32; LANES]) -> Self {
        Sizes {
            integers: Ints::gather(sizes, |&size| Self::integer(size)),
            floats: Floats::gather(sizes, |&size| size as f32),
        }
    }
}

/// Texel pairs on one axis, lane-wise ([`texel_pairs`]): the two wrapped indices and the
/// weight of the second where `exact`.
struct TexelPairs<B: Backend> {
    first: Ints<B>,
    second: Ints<B>,
    fraction: Floats<B>,
    exact: Mask<B>,
}

impl<B: Backend> TexelPairs<B> {
    /// `texture::texel_pair` of `lane`, whose coordinate is in `t` and size in `sizes`.
    #[inline(always)]
    fn lane(&self, lane: usize, t: Floats<B>, sizes: &[u32; LANES], wrap: Wrap) -> (usize, usize, f32) {
        if self.exact.lane(lane) {
            self.exact_lane(lane)
        } else {
            texel_pair(t.0[lane], sizes[lane], wrap)
        }
    }

    /// The pair of `lane`, where it is `exact`.
    #[inline(always)]
    fn exact_lane(&self, lane: usize) -> (usize, usize, f32) {
        (
            self.first.0[lane] as usize,
            self.second.0[lane] as usize,
            self.fraction.0[lane],
        )
    }
}

/// `texture::texel_pair` of each lane for |t| < [`INTEGER_RANGE`]: the two texel indices
/// around `t` on an axis of `sizes` texels, wrapped, and the weight of the second.
///
/// The specification computes `x = t·size − ½` in `f64` (exactly), its floor `F`, and the
/// fraction `x − F` rounded to `f32`. Where the size is a power of two and `1 ≤ t·size < 2²²`,
/// the same is exact in `f32`, lane-wise: `t·size` only moves the exponent, `x` is a multiple
/// of the product's spacing (at most ¼) not below ½, so representable; `(x + 1.5·2²³) −
/// 1.5·2²³` rounds it to a whole number (the sum's spacing is 1), one less where that rounded
/// up is the floor, and `x − F`, the fractional part of a non-negative float, is exact too: the
/// specification's value, with its bits. The sum's low bits hold the rounded value as an
/// integer, and for a power of two the wrap is a mask. The other lanes (negative or tiny
/// coordinates, sizes that are no power of two) are not `exact`: they take the
/// specification's steps lane by lane ([`texel_pair`]).
#[inline(always)]
fn texel_pairs<B: Backend>(t: Floats<B>, sizes: Sizes<B>, wrap: Wrap) -> TexelPairs<B> {
    let Sizes {
        integers: size,
        floats,
    } = sizes;
    let product = t * floats;
    let x = product - Floats::splat(0.5);
    let (floor, first) = floor_lanes(x);
    let fraction = x - floor;
    let one = Ints::splat(1);
    let zero = Ints::splat(0);
    let last = size - one;
    let power_of_two = !size.and(last).gt(zero);
    let exact = Floats::splat(1.0)
        .le(product)
        .and(Floats::splat((1u32 << 22) as f32).gt(product))
        .and(power_of_two);
    TexelPairs {
        first: wrap_lanes(first, size, wrap),
        second: wrap_lanes(first + one, size, wrap),
        fraction,
        exact,
    }
}

/// Each lane's `index` wrapped into an axis of `size` texels (a power of two where the result
/// is used) as `wrap` says.
#[inline(always)]
fn wrap_lanes<B: Backend>(index: Ints<B>, size: Ints<B>, wrap: Wrap) -> Ints<B> {
    let zero = Ints::splat(0);
    let last = size - Ints::splat(1);
    match wrap {
        Wrap::Repeat => index.and(last),
        Wrap::MirroredRepeat => {
            let twice = size + last;
            let period = index.and(twice);
            period.gt(last).select_ints(twice - period, period)
        }
        Wrap::ClampToEdge => {
            let below = index.gt(last).select_ints(last, index);
            zero.gt(below).select_ints(zero, below)
        }
    }
}

/// `texture::texel_pair` for |t| < [`INTEGER_RANGE`], one lane: the specification's `f64`
/// coordinate, its floor by truncation (exact below 2⁵³), the wrap in integers.
#[inline(always)]
fn texel_pair(t: f32, size: u32, wrap: Wrap) -> (usize, usize, f32) {
    let x = f64::from(t) * f64::from(size) - 0.5;
    let truncated = x as i64;
    let first = truncated - i64::from(truncated as f64 > x);
    let fraction = (x - first as f64) as f32;
    let size = i64::from(size.max(1));
    (
        wrap_index(first, size, wrap),
        wrap_index(first + 1, size, wrap),
        fraction,
    )
}

/// `texture::wrap_index` of a whole index below 2⁵³ in magnitude, in integers.
#[inline(always)]
fn wrap_index(index: i64, size: i64, wrap: Wrap) -> usize {
    let wrapped = match wrap {
        Wrap::Repeat => modulo(index, size),
        Wrap::MirroredRepeat => {
            let period = modulo(index, 2 * size);
            if period >= size {
                2 * size - 1 - period
            } else {
                period
            }
        }
        Wrap::ClampToEdge => index.clamp(0, size - 1),
    };
    wrapped as usize
}

/// `index.rem_euclid(size)` for `size ≥ 1`: a mask when `size` is a power of two (two's
/// complement makes it the Euclidean remainder of negative indices too).
#[inline(always)]
fn modulo(index: i64, size: i64) -> i64 {
    if size & (size - 1) == 0 {
        index & (size - 1)
    } else {
        index.rem_euclid(size)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::lanes::{LaneWork, Native, run_widest};

    /// A texture of `width`×`height` texels whose every component differs from its
    /// neighbours', so that any wrong texel or weight shows.
    fn texture(width: u32, height: u32) -> Texture {
        let texels = (0..width * height)
            .map(|i| {
                let (x, y) = ((i % width) as f32, (i / width) as f32);
                Vec4::new(
                    (x * 0.37 + y * 0.11).sin(),
                    (x * 0.05 - y * 0.29).cos(),
                    x / width as f32 + 0.01 * y,
                    1.0 - y / height as f32,
                )
            })
            .collect();
        Texture::from_texels(width, height, texels).unwrap_or_else(|e| panic!("{e}"))
    }

    fn same_bits(a: Vec4, b: Vec4) -> bool {
        a.to_array().map(f32::to_bits) == b.to_array().map(f32::to_bits)
    }

    /// [`sample_lanes`] of eight points (uv, uv_dx, uv_dy), as lane work.
    #[derive(Clone, Copy)]
    struct Sample<'t> {
        texture: &'t Texture,
        points: [(Vec2, Vec2, Vec2); LANES],
        sampler: &'t Sampler,
        mip_bias: f32,
    }

    impl LaneWork for Sample<'_> {
        type Output = [Vec4; LANES];

        #[inline(always)]
        fn run<B: Backend>(self) -> [Vec4; LANES] {
            let lanes = |pick: fn(&(Vec2, Vec2, Vec2)) -> Vec2| Vec2s::<B>::gather(&self.points, pick);
            sample_lanes(
                self.texture,
                lanes(|p| p.0),
                lanes(|p| p.1),
                lanes(|p| p.2),
                self.sampler,
                self.mip_bias,
            )
        }
    }

    /// The lanes, on the native backend and on the widest (`run_widest`), against
    /// `Texture::sample`, lane by lane, for `points` (uv, uv_dx, uv_dy), eight at a time (the
    /// last group padded with the first points).
    fn check(texture: &Texture, sampler: &Sampler, mip_bias: f32, points: &[(Vec2, Vec2, Vec2)], what: &str) {
        for group in points.chunks(LANES) {
            let point = |lane: usize| group.get(lane).copied().unwrap_or(points[lane % points.len()]);
            let work = Sample {
                texture,
                points: std::array::from_fn(point),
                sampler,
                mip_bias,
            };
            for (backend, sampled) in [("native", work.run::<Native>()), ("widest", run_widest(work))] {
                for (lane, &value) in sampled.iter().enumerate() {
                    let (uv, dx, dy) = point(lane);
                    let expected = texture.sample_biased(uv, dx, dy, sampler, mip_bias);
                    assert!(
                        same_bits(value, expected),
                        "{what} {sampler:?} bias {mip_bias}, {backend} lanes: uv {uv} dx {dx} dy {dy}: {value} \
                         against {expected}"
                    );
                }
            }
        }
    }

    const WRAPS: [Wrap; 3] = [Wrap::Repeat, Wrap::MirroredRepeat, Wrap::ClampToEdge];

    /// Coordinates inside, on texel centres and edges, just outside, far outside and beyond
    /// the integer range, negative ones, and non-finite ones.
    fn coordinates(size: u32) -> Vec<f32> {
        let n = size as f32;
        let mut values = vec![
            0.0,
            -0.0,
            0.5,
            1.0,
            0.999_999_94,
            1.000_000_1,
            -1e-9,
            0.5 / n,
            1.5 / n,
            (n - 0.5) / n,
            -0.25 / n,
            0.3,
            -0.7,
            2.25,
            -3.6,
            17.0 + 0.5 / n,
            -1234.567,
            1e6 + 0.3,
            INTEGER_RANGE * 0.999,
            -INTEGER_RANGE * 0.999,
            INTEGER_RANGE,
            -INTEGER_RANGE,
            3e7,
            1e30,
            -1e30,
            f32::MAX,
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
        ];
        values.extend((0..40).map(|i| (i as f32 - 13.3) * 0.173));
        values
    }

    /// Footprints (per pixel step) from far magnified through exactly one texel to far
    /// minified, huge and non-finite, scaled to a texture of `size` texels.
    fn derivatives(size: u32) -> Vec<f32> {
        let texel = 1.0 / size as f32;
        let mut values: Vec<f32> = [
            0.0, 0.01, 0.5, 0.999_999, 1.0, 1.000_001, 1.5, 2.0, 3.7, 8.0, 100.0, 1e4,
        ]
        .map(|texels| texels * texel)
        .to_vec();
        values.extend([1e20, f32::MAX, f32::NAN, f32::INFINITY, -0.3, -1e-7]);
        values
    }

    #[test]
    fn lanes_equal_the_scalar_sampler_bit_for_bit() {
        // Powers of two and not, square and not, a single texel, a single row.
        let sizes = [
            (8, 8),
            (16, 4),
            (5, 3),
            (7, 12),
            (1, 1),
            (33, 1),
            (64, 64),
            (2, 2),
            (1, 16),
            (128, 2),
        ];
        for (width, height) in sizes {
            let texture = texture(width, height);
            let us = coordinates(width);
            let vs = coordinates(height);
            let ds = derivatives(width.max(height));
            for wrap_s in WRAPS {
                for wrap_t in WRAPS {
                    let sampler = Sampler { wrap_s, wrap_t };
                    let mut points = Vec::new();
                    for (i, &u) in us.iter().enumerate() {
                        for (j, &v) in vs.iter().enumerate().step_by(3) {
                            let d = ds[(i + j) % ds.len()];
                            let e = ds[(i * 7 + j) % ds.len()];
                            // Isotropic, along one axis, and skewed footprints.
                            points.push((Vec2::new(u, v), Vec2::new(d, 0.0), Vec2::new(0.0, e)));
                            points.push((Vec2::new(v, u), Vec2::new(d, e), Vec2::new(-e, d * 0.5)));
                        }
                    }
                    check(&texture, &sampler, 0.0, &points, &format!("{width}×{height}"));
                }
            }
        }
    }

    /// Eight lanes at one level of a mip chain, blended towards the next one or not, with
    /// pseudo-random coordinates near and far from the texture and every wrap: the case where
    /// all lanes share their levels, on powers of two and not, a single texel column.
    #[test]
    fn lanes_at_one_level_equal_the_scalar_sampler() {
        let mut rng = crate::test_support::XorShift32::new(0x2545_f491_u32);
        let mut random = move || {
            let state = rng.next_u32();
            state as f32 / u32::MAX as f32
        };
        for (width, height) in [(64, 32), (4, 256), (2, 2), (1, 8)] {
            let texture = texture(width, height);
            for wrap_s in WRAPS {
                for wrap_t in WRAPS {
                    let sampler = Sampler { wrap_s, wrap_t };
                    let mut points = Vec::new();
                    // Whole levels (magnified, exactly one texel, every level of the chain)
                    // and levels between two.
                    for lod in [-2.0, 0.0, 1.0, 2.0, 3.0, 0.25, 1.5, 2.75, 4.5, 6.0, 9.0] {
                        let footprint = 2f32.powf(lod) / width.max(height) as f32;
                        for spread in [1.0, 4.0, 300.0] {
                            points.extend((0..LANES).map(|_| {
                                let uv = Vec2::new(random() * spread, random() * spread - 0.5);
                                (uv, Vec2::new(footprint, 0.0), Vec2::new(0.0, footprint * 0.5))
                            }));
                        }
                    }
                    check(
                        &texture,
                        &sampler,
                        0.0,
                        &points,
                        &format!("{width}×{height} one level"),
                    );
                }
            }
        }
    }

    /// Every level of a mip chain is reached, and the blend between two levels is taken,
    /// in lanes that each pick their own level.
    #[test]
    fn lanes_at_different_levels_equal_the_scalar_sampler() {
        let texture = texture(64, 32);
        let sampler = Sampler {
            wrap_s: Wrap::Repeat,
            wrap_t: Wrap::MirroredRepeat,
        };
        let points: Vec<_> = (0..200)
            .map(|i| {
                let footprint = 2f32.powf(i as f32 * 0.047) / 64.0;
                let uv = Vec2::new(i as f32 * 0.0137 - 0.4, 0.9 - i as f32 * 0.011);
                (uv, Vec2::new(footprint, 0.0), Vec2::new(0.0, footprint * 0.5))
            })
            .collect();
        // Biases that move magnified lanes into the chain and minified ones back to level 0.
        for mip_bias in [0.0, -0.75, -3.0, 0.5, 1.25, 8.0] {
            check(&texture, &sampler, mip_bias, &points, "levels");
        }
        // The footprint is the longer derivative: equal lengths (across and along one axis),
        // zero and negative-zero ones, and lengths that overflow to +∞ on one side or both.
        let texel = 1.0 / 64.0;
        let mut footprints = Vec::new();
        for texels in [0.0, 0.7, 1.0, 1.9, 2.0, 3.0, 5.5, 64.0, 1e3] {
            let d = texels * texel;
            footprints.extend([
                (Vec2::new(d, 0.0), Vec2::new(0.0, 2.0 * d)),
                (Vec2::new(d, 0.0), Vec2::new(d, 0.0)),
                (Vec2::new(0.0, -d), Vec2::new(d, -0.0)),
                (Vec2::new(-0.0, -0.0), Vec2::new(d * 0.6, d * 0.8)),
                (Vec2::new(1e38, 0.0), Vec2::new(0.0, d)),
                (Vec2::new(d, d), Vec2::new(-1e38, 1e38)),
            ]);
        }
        let points: Vec<_> = footprints
            .iter()
            .enumerate()
            .map(|(i, &(dx, dy))| {
                (
                    Vec2::new(0.13 + i as f32 * 0.071, 0.77 - i as f32 * 0.029),
                    dx,
                    dy,
                )
            })
            .collect();
        for mip_bias in [0.0, -0.75, 0.5, 8.0] {
            check(&texture, &sampler, mip_bias, &points, "footprints");
        }
        // A level that lost texels (its fields are public) reads zero past its end, as
        // `MipLevel::texel` does, rather than taking the fast path.
        let mut short = texture.clone();
        short.levels[0].texels.truncate(64 * 20);
        short.levels[1].texels.truncate(7);
        for mip_bias in [0.0, 0.5] {
            check(&short, &sampler, mip_bias, &points, "short levels");
        }
        let empty = Texture {
            levels: Vec::new(),
            file: None,
        };
        let zero = Vec2s::<Native>::from_array(&[Vec2::ZERO; LANES]);
        assert_eq!(
            sample_lanes(&empty, zero, zero, zero, &sampler, 0.0),
            [Vec4::ZERO; LANES]
        );
    }
}
