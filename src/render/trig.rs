//! `sin`, `cos` and `atan2` as fixed sequences of `f32` operations, written once over
//! [`Real`], so that eight lanes (`Floats`) get exactly the bits one `f32` gets: Slerp's
//! trigonometry (`normals::NormalArc`) runs lane-wise with the scalar specification's bits.
//! libm's `sinf`/`atan2f` have no lane form (one call per lane costs more than the rest of a
//! slerped pixel), and their results may differ between libm versions; these do not.
//!
//! ```text
//! sin_cos(x):  a = |x|, k = trunc(a·2/π + ½)             the nearest quarter turn (a ≥ 0)
//!              r = ((a − k·P₁) − k·P₂) − k·P₃             Cody-Waite: P₁ + P₂ + P₃ = π/2, P₁ and
//!                                                         P₂ short, so k·P₁, k·P₂ are exact
//!              S(r) = r + r·z·(s₁ + z·(s₂ + z·s₃))        z = r², |r| ≤ π/4 (Cephes `sinf`)
//!              C(r) = 1 − z/2 + z²·(c₁ + z·(c₂ + z·c₃))   (Cephes `cosf`)
//!              k mod 4 = 0: ( S,  C)   1: ( C, −S)   2: (−S, −C)   3: (−C,  S)
//!              sin(−a) = −sin(a), cos(−a) = cos(a)
//! atan2(y, x): t = min/max of |x|, |y| ∈ [0, 1]           0 where both are 0
//!              atan(t) = A(t)                 t ≤ tan(π/8)
//!                      = π/4 + A((t−1)/(t+1)) otherwise   A(u) = u + u·z·(a₁ + z·(a₂ + z·(a₃ + z·a₄)))
//!              then π/2 − · where |y| > |x|, π − · where x < 0, − · where y < 0
//! ```
//!
//! Branches are selects: both sides are computed and one kept, in the lanes and the float
//! alike. Error, measured against `f64` over dense sweeps (`tests`): `sin` and `cos` within
//! [`SIN_COS_ERROR`] of the exact values for |x| ≤ 4π (the arguments Slerp takes are t·θ with
//! t ∈ [0, 1], θ ∈ [0, π]), and `sin` within [`RELATIVE_ERROR`] of it relatively on (0, 3];
//! `atan2` within [`ATAN2_ERROR`] radians, and within [`RELATIVE_ERROR`] relatively: one or two
//! units of the last place, as libm's `f32` functions are (they are correctly rounded or
//! nearly), which moves a slerped normal by less than 10⁻⁶ and a pixel by no 8-bit level.

use crate::render::lanes::Real;

/// Largest error of [`sin_cos`]'s sine and cosine for |x| ≤ 4π (absolute; 1.3 units of the
/// last place of 1).
pub const SIN_COS_ERROR: f64 = 8e-8;

/// Largest error of [`atan2`] (radians; 1.2 units of the last place of π).
pub const ATAN2_ERROR: f64 = 3e-7;

/// Largest relative error of the sine on (0, 3] and of [`atan2`] (1.7 units of the last place).
pub const RELATIVE_ERROR: f64 = 2.1e-7;

/// π/2 in three parts, the first two with few significant bits (Cephes' `DP1`–`DP3`, doubled).
const HALF_PI_1: f32 = 1.570_312_5;
const HALF_PI_2: f32 = 4.837_513e-4;
const HALF_PI_3: f32 = 7.549_79e-8;

/// `(sin x, cos x)`.
#[inline(always)]
pub fn sin_cos<R: Real>(x: R) -> (R, R) {
    let c = R::splat;
    let a = x.abs();
    let k = (a * c(std::f32::consts::FRAC_2_PI) + c(0.5)).trunc();
    let r = ((a - k * c(HALF_PI_1)) - k * c(HALF_PI_2)) - k * c(HALF_PI_3);
    let z = r * r;
    let sine = ((c(-1.951_529_6e-4) * z + c(8.332_161e-3)) * z - c(1.666_665_5e-1)) * z * r + r;
    let cosine =
        ((c(2.443_315_7e-5) * z - c(1.388_731_6e-3)) * z + c(4.166_664_6e-2)) * z * z - c(0.5) * z + c(1.0);
    // The quarter turn, k mod 2 and k mod 4, in whole floats.
    let odd = (k - (k * c(0.5)).trunc() * c(2.0)).gt(c(0.5));
    let quarter = k - (k * c(0.25)).trunc() * c(4.0);
    let (sin_base, cos_base) = (R::select(odd, cosine, sine), R::select(odd, sine, cosine));
    let sin_negative = quarter.gt(c(1.5));
    let cos_negative = R::and(quarter.gt(c(0.5)), !quarter.gt(c(2.5)));
    let sin_a = R::select(sin_negative, -sin_base, sin_base);
    let cos_a = R::select(cos_negative, -cos_base, cos_base);
    (R::select(c(0.0).gt(x), -sin_a, sin_a), cos_a)
}

/// `atan2(y, x)`: the angle of `(x, y)` from the x axis, in [−π, π]; 0 at the origin.
#[inline(always)]
pub fn atan2<R: Real>(y: R, x: R) -> R {
    use std::f32::consts::{FRAC_PI_2, FRAC_PI_4, PI};
    let c = R::splat;
    let (ax, ay) = (x.abs(), y.abs());
    let steep = ay.gt(ax);
    let (least, most) = (R::select(steep, ax, ay), R::select(steep, ay, ax));
    let t = R::select(most.gt(c(0.0)), least / most, c(0.0));
    let past_eighth = t.gt(c(0.414_213_57));
    let u = R::select(past_eighth, (t - c(1.0)) / (t + c(1.0)), t);
    let z = u * u;
    let poly =
        (((c(8.053_744_5e-2) * z - c(1.387_768_6e-1)) * z + c(1.997_771_1e-1)) * z - c(3.333_295e-1)) * z * u
            + u;
    let first = R::select(past_eighth, c(FRAC_PI_4) + poly, poly);
    let octant = R::select(steep, c(FRAC_PI_2) - first, first);
    let half = R::select(c(0.0).gt(x), c(PI) - octant, octant);
    R::select(c(0.0).gt(y), -half, half)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::lanes::{Floats, LANES};

    /// The largest error of `sin_cos` against `f64` over `n` points of [−limit, limit].
    fn sin_cos_error(limit: f64, n: usize) -> (f64, f64) {
        let (mut sine, mut cosine) = (0.0f64, 0.0f64);
        for i in 0..=n {
            let x = (-limit + 2.0 * limit * i as f64 / n as f64) as f32;
            let (s, c) = sin_cos(x);
            let exact = f64::from(x);
            sine = sine.max((f64::from(s) - exact.sin()).abs());
            cosine = cosine.max((f64::from(c) - exact.cos()).abs());
        }
        (sine, cosine)
    }

    #[test]
    fn sin_and_cos_are_within_their_stated_error() {
        let (sine, cosine) = sin_cos_error(4.0 * std::f64::consts::PI, 2_000_000);
        assert!(
            sine <= SIN_COS_ERROR && cosine <= SIN_COS_ERROR,
            "{sine:e} {cosine:e}"
        );
        let mut relative = 0.0f64;
        for i in 1..=200_000 {
            let x = (i as f64 * 1.5e-5) as f32;
            let exact = f64::from(x).sin();
            relative = relative.max((f64::from(sin_cos(x).0) - exact).abs() / exact);
        }
        assert!(relative <= RELATIVE_ERROR, "{relative:e}");
        // Small arguments keep their relative precision: sin x = x below 2⁻¹².
        for x in [1e-30f32, 1e-7, -3e-5, 2.4e-4] {
            assert_eq!(sin_cos(x).0, x);
            assert_eq!(sin_cos(x).1, 1.0);
        }
        assert_eq!(sin_cos(0.0f32), (0.0, 1.0));
    }

    #[test]
    fn atan2_is_within_its_stated_error() {
        let mut worst = 0.0f64;
        let n = 2_000;
        for i in 0..=n {
            for j in 0..=n {
                let (x, y) = (
                    (-1.0 + 2.0 * i as f64 / n as f64) as f32,
                    (-1.0 + 2.0 * j as f64 / n as f64) as f32,
                );
                if x == 0.0 && y == 0.0 {
                    continue;
                }
                let exact = f64::from(y).atan2(f64::from(x));
                worst = worst.max((f64::from(atan2(y, x)) - exact).abs());
            }
        }
        assert!(worst <= ATAN2_ERROR, "{worst:e}");
        // Small angles keep their relative precision (Slerp between close normals).
        let mut relative = 0.0f64;
        for i in 1..=200_000 {
            let y = (i as f64 * 1e-5) as f32;
            let exact = f64::from(y).atan2(1.0);
            relative = relative.max((f64::from(atan2(y, 1.0)) - exact).abs() / exact);
        }
        assert!(relative <= RELATIVE_ERROR, "{relative:e}");
        for (y, x) in [
            (1e-6f32, 1.0f32),
            (1e-6, -1.0),
            (1.0, 1e-30),
            (3e-38, 2e-38),
            (1.0, 0.0),
        ] {
            let exact = f64::from(y).atan2(f64::from(x));
            assert!((f64::from(atan2(y, x)) - exact).abs() <= ATAN2_ERROR, "{y} {x}");
        }
        assert_eq!(atan2(0.0f32, 0.0), 0.0);
        assert_eq!(atan2(0.0f32, -1.0), std::f32::consts::PI);
    }

    /// Lanes against single floats, bit for bit, on awkward arguments.
    #[test]
    fn lanes_equal_single_floats_bit_for_bit() {
        let values = [
            0.0f32,
            -0.0,
            1e-30,
            -2.5,
            std::f32::consts::FRAC_PI_4,
            std::f32::consts::PI,
            -7.0 * std::f32::consts::FRAC_PI_2,
            12.3,
            1e-7,
            0.414_213_57,
            -3e5,
            f32::NAN,
            f32::INFINITY,
            0.785,
            2.356,
            -1.0,
        ];
        for (i, window) in values.windows(LANES).enumerate() {
            let x: Floats = Floats::new(std::array::from_fn(|lane| window[lane]));
            let y = Floats::new(std::array::from_fn(|lane| values[(i + 3 * lane) % values.len()]));
            let (sines, cosines) = sin_cos(x);
            let angles = atan2(y, x);
            for lane in 0..LANES {
                let (s, c) = sin_cos(x.0[lane]);
                assert_eq!(sines.0[lane].to_bits(), s.to_bits(), "sin {}", x.0[lane]);
                assert_eq!(cosines.0[lane].to_bits(), c.to_bits(), "cos {}", x.0[lane]);
                let a = atan2(y.0[lane], x.0[lane]);
                assert_eq!(
                    angles.0[lane].to_bits(),
                    a.to_bits(),
                    "atan2 {} {}",
                    y.0[lane],
                    x.0[lane]
                );
            }
        }
    }
}
