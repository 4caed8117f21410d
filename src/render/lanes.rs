//! Eight shading points at once: `f32` and `Vec3` arithmetic over fixed-size lane arrays.
//!
//! Every operation is the scalar one applied lane by lane (the same IEEE operations in the same
//! order as glam's `Vec3`), written as plain loops over arrays that the compiler turns into SIMD
//! instructions (`addps`, `mulps`, `divps`, `sqrtps`, …) for whatever the build targets. So a
//! lane's result has the same bits as the scalar code on the same input, with no `unsafe` and no
//! per-architecture code; branches become per-lane masks and selects.

use std::ops::{Add, Div, Mul, Neg, Not, Sub};

use glam::Vec3;

/// How many points are processed together. Eight fills an AVX register, or two SSE registers on
/// the baseline x86-64 target.
pub const LANES: usize = 8;

/// One `f32` per lane.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Floats(pub [f32; LANES]);

/// Where a condition holds, per lane: all bits set or none, as SIMD compares produce, so
/// selects compile to bitwise `and`/`or` rather than branches per lane.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Mask([u32; LANES]);

impl Floats {
    #[inline(always)]
    pub fn splat(value: f32) -> Self {
        Floats([value; LANES])
    }

    #[inline(always)]
    fn map(self, f: impl Fn(f32) -> f32) -> Self {
        Floats(self.0.map(f))
    }

    #[inline(always)]
    fn zip(self, other: Self, f: impl Fn(f32, f32) -> f32) -> Self {
        Floats(std::array::from_fn(|i| f(self.0[i], other.0[i])))
    }

    #[inline(always)]
    fn compare(self, other: Self, f: impl Fn(f32, f32) -> bool) -> Mask {
        Mask::from_bools(std::array::from_fn(|i| f(self.0[i], other.0[i])))
    }

    #[inline(always)]
    pub fn sqrt(self) -> Self {
        self.map(f32::sqrt)
    }

    /// `f32::max` per lane (the other operand where one is NaN).
    #[inline(always)]
    pub fn max(self, other: Self) -> Self {
        self.zip(other, f32::max)
    }

    #[inline(always)]
    pub fn gt(self, other: Self) -> Mask {
        self.compare(other, |a, b| a > b)
    }

    #[inline(always)]
    pub fn le(self, other: Self) -> Mask {
        self.compare(other, |a, b| a <= b)
    }

    /// `f32::is_finite` per lane, as an integer compare of the bits.
    #[inline(always)]
    pub fn is_finite(self) -> Mask {
        Mask::from_bools(self.0.map(|a| (a.to_bits() & 0x7fff_ffff) < 0x7f80_0000))
    }
}

impl Mask {
    /// Every lane.
    pub const ALL: Mask = Mask([u32::MAX; LANES]);

    #[inline(always)]
    pub fn from_bools(lanes: [bool; LANES]) -> Self {
        Mask(lanes.map(|on| if on { u32::MAX } else { 0 }))
    }

    /// Whether the condition holds in `lane`.
    #[inline(always)]
    pub fn lane(self, lane: usize) -> bool {
        self.0[lane] != 0
    }

    #[inline(always)]
    pub fn and(self, other: Self) -> Self {
        Mask(std::array::from_fn(|i| self.0[i] & other.0[i]))
    }

    #[inline(always)]
    pub fn or(self, other: Self) -> Self {
        Mask(std::array::from_fn(|i| self.0[i] | other.0[i]))
    }

    #[inline(always)]
    pub fn any(self) -> bool {
        self.0.iter().fold(0, |any, &m| any | m) != 0
    }

    /// Per lane, `if_true` where the mask holds and `if_false` elsewhere (bit for bit).
    #[inline(always)]
    pub fn select(self, if_true: Floats, if_false: Floats) -> Floats {
        Floats(std::array::from_fn(|i| {
            f32::from_bits((if_true.0[i].to_bits() & self.0[i]) | (if_false.0[i].to_bits() & !self.0[i]))
        }))
    }

    #[inline(always)]
    pub fn select3(self, if_true: Vec3s, if_false: Vec3s) -> Vec3s {
        Vec3s {
            x: self.select(if_true.x, if_false.x),
            y: self.select(if_true.y, if_false.y),
            z: self.select(if_true.z, if_false.z),
        }
    }
}

impl Not for Mask {
    type Output = Mask;
    #[inline(always)]
    fn not(self) -> Mask {
        Mask(self.0.map(|m| !m))
    }
}

macro_rules! lane_operator {
    ($trait:ident, $method:ident, $op:tt) => {
        impl $trait for Floats {
            type Output = Floats;
            #[inline(always)]
            fn $method(self, other: Floats) -> Floats {
                self.zip(other, |a, b| a $op b)
            }
        }
    };
}

lane_operator!(Add, add, +);
lane_operator!(Sub, sub, -);
lane_operator!(Mul, mul, *);
lane_operator!(Div, div, /);

/// One `Vec3` per lane, stored as three lane arrays.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Vec3s {
    pub x: Floats,
    pub y: Floats,
    pub z: Floats,
}

impl Vec3s {
    #[inline(always)]
    pub fn splat(v: Vec3) -> Self {
        Vec3s {
            x: Floats::splat(v.x),
            y: Floats::splat(v.y),
            z: Floats::splat(v.z),
        }
    }

    /// The lanes from `vectors`.
    #[inline(always)]
    pub fn from_array(vectors: &[Vec3; LANES]) -> Self {
        Vec3s {
            x: Floats(vectors.map(|v| v.x)),
            y: Floats(vectors.map(|v| v.y)),
            z: Floats(vectors.map(|v| v.z)),
        }
    }

    #[inline(always)]
    pub fn to_array(self) -> [Vec3; LANES] {
        std::array::from_fn(|i| Vec3::new(self.x.0[i], self.y.0[i], self.z.0[i]))
    }

    /// `Vec3::dot`: `(x·x') + (y·y') + (z·z')`, summed left to right.
    #[inline(always)]
    pub fn dot(self, other: Self) -> Floats {
        self.x * other.x + self.y * other.y + self.z * other.z
    }

    /// `Vec3::length`.
    #[inline(always)]
    pub fn length(self) -> Floats {
        self.dot(self).sqrt()
    }

    /// Each component times the lane's `factor` (`Vec3 * f32`).
    #[inline(always)]
    pub fn scale(self, factor: Floats) -> Self {
        Vec3s {
            x: self.x * factor,
            y: self.y * factor,
            z: self.z * factor,
        }
    }

    /// Each component over the lane's `divisor` (`Vec3 / f32`: three divisions, not a
    /// reciprocal).
    #[inline(always)]
    pub fn divide(self, divisor: Floats) -> Self {
        Vec3s {
            x: self.x / divisor,
            y: self.y / divisor,
            z: self.z / divisor,
        }
    }

    /// `Vec3::normalize_or_zero`: times `1 / length` where that is finite and positive.
    #[inline(always)]
    pub fn normalize_or_zero(self) -> Self {
        let reciprocal = Floats::splat(1.0) / self.length();
        let usable = reciprocal.is_finite().and(reciprocal.gt(Floats::splat(0.0)));
        usable.select3(self.scale(reciprocal), Vec3s::splat(Vec3::ZERO))
    }
}

/// `-v`: a sign flip, so `-0.0` stays distinct from `0.0 - 0.0` as in the scalar code.
impl Neg for Vec3s {
    type Output = Vec3s;
    #[inline(always)]
    fn neg(self) -> Vec3s {
        Vec3s {
            x: self.x.map(|a| -a),
            y: self.y.map(|a| -a),
            z: self.z.map(|a| -a),
        }
    }
}

impl Add for Vec3s {
    type Output = Vec3s;
    #[inline(always)]
    fn add(self, other: Vec3s) -> Vec3s {
        Vec3s {
            x: self.x + other.x,
            y: self.y + other.y,
            z: self.z + other.z,
        }
    }
}

impl Sub for Vec3s {
    type Output = Vec3s;
    #[inline(always)]
    fn sub(self, other: Vec3s) -> Vec3s {
        Vec3s {
            x: self.x - other.x,
            y: self.y - other.y,
            z: self.z - other.z,
        }
    }
}

/// Component by component, as `Vec3 * Vec3`.
impl Mul for Vec3s {
    type Output = Vec3s;
    #[inline(always)]
    fn mul(self, other: Vec3s) -> Vec3s {
        Vec3s {
            x: self.x * other.x,
            y: self.y * other.y,
            z: self.z * other.z,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Awkward inputs: zero, tiny, huge, negative, subnormal and non-finite lengths.
    fn vectors() -> [Vec3; LANES] {
        [
            Vec3::new(0.3, -1.7, 2.9),
            Vec3::ZERO,
            Vec3::new(1e-30, 2e-31, -3e-30),
            Vec3::new(3e19, -2e19, 1e19),
            Vec3::new(-0.0, 1e-45, 0.0),
            Vec3::new(f32::INFINITY, 1.0, 0.0),
            Vec3::new(f32::NAN, 1.0, 2.0),
            Vec3::new(1.0 / 3.0, 2.0 / 3.0, -2.0 / 3.0),
        ]
    }

    fn same_bits(a: Vec3, b: Vec3) -> bool {
        a.to_array().map(f32::to_bits) == b.to_array().map(f32::to_bits)
    }

    #[test]
    fn each_lane_has_the_bits_of_glams_scalar_operation() {
        let a = vectors();
        let mut b = vectors();
        b.rotate_left(3);
        let (la, lb) = (Vec3s::from_array(&a), Vec3s::from_array(&b));
        let dots = la.dot(lb);
        let lengths = la.length();
        let normalized = la.normalize_or_zero().to_array();
        let divided = la.divide(lb.length()).to_array();
        let combined = (la + lb * la - lb).to_array();
        let negated = (-la).to_array();
        for i in 0..LANES {
            assert_eq!(dots.0[i].to_bits(), a[i].dot(b[i]).to_bits(), "dot, lane {i}");
            assert_eq!(
                lengths.0[i].to_bits(),
                a[i].length().to_bits(),
                "length, lane {i}"
            );
            assert!(
                same_bits(normalized[i], a[i].normalize_or_zero()),
                "normalize, lane {i}"
            );
            assert!(same_bits(divided[i], a[i] / b[i].length()), "divide, lane {i}");
            assert!(
                same_bits(combined[i], a[i] + b[i] * a[i] - b[i]),
                "arithmetic, lane {i}"
            );
            assert!(same_bits(negated[i], -a[i]), "negation, lane {i}");
        }
    }

    #[test]
    fn select_takes_each_lane_from_the_side_its_mask_names() {
        let mask = Mask::from_bools(std::array::from_fn(|i| i % 3 == 0));
        let picked = mask.select(Floats::splat(1.0), Floats::splat(2.0));
        for i in 0..LANES {
            assert_eq!(picked.0[i], if i % 3 == 0 { 1.0 } else { 2.0 });
        }
        assert!(mask.any() && !(!Mask::ALL).any());
        assert!((0..LANES).all(|i| mask.lane(i) == (i % 3 == 0)));
        assert_eq!((!mask).or(mask), Mask::ALL);
        assert_eq!((!mask).and(mask), !Mask::ALL);
        let finite = Floats([
            0.0,
            -1e38,
            f32::MAX,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            1e-45,
            -0.0,
        ]);
        let expected = finite.0.map(f32::is_finite);
        assert!((0..LANES).all(|i| finite.is_finite().lane(i) == expected[i]));
    }
}
