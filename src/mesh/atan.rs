//! `atan2` for `f32` as fdlibm computes it, operation for operation, so that it gives the bits
//! glibc's `atan2f` gives (glibc 2.36 has fdlibm's `e_atan2f.c` and `s_atanf.c`, with the
//! constants below, read from its `libm.so.6`): the angle weights of vertex normals
//! ([`super::normals`]) keep the bits they had when they called libm.
//!
//! Why not libm: a vertex normal needs three angles a triangle, and the call (through glibc's
//! error-setting wrapper, then `atanf`) cost about 130 instructions an angle, a tenth of loading
//! a scan; inlined, the whole angle (cross and dot products included) takes about 90. The
//! weights also no longer depend on the platform's libm, whose `atan2f` differs between C
//! libraries and versions.
//!
//! Agreement with glibc 2.36's `atan2f` and `atanf` was checked bit for bit on 329 M `atanf`
//! arguments (every 13th finite `f32`, both signs) and 100 M `atan2f` pairs (random bit
//! patterns, NaN and infinities included, and the normals' domain `y ∈ [0, 1]`, `x ∈ [−1, 1]`);
//! the tests pin a checksum of those bits.
//!
//! [`atan2_lanes`] is the same function eight lanes at a time, for the face angles of eight
//! triangles at once (a third of computing a scan's normals was these calls). Its branches are
//! selects: the four argument reductions share one division (`t / 1` is `t`, so the
//! unreduced argument divides too), and the polynomial is written once over [`Real`] for
//! both forms. The arguments fdlibm treats specially (zeros, infinities, NaN, `x = 1`) are
//! rare among face angles, and a lane holding one is measured by [`atan2`] itself; tests
//! compare the lanes with it bit for bit.

use crate::render::lanes::{Floats, Ints, LANES, Real};

/// `atan(0.5)`, `atan(1)`, `atan(1.5)` and `atan(∞)`, each as a high part ...
const ATAN_HIGH: [f32; 4] = [
    f32::from_bits(0x3eed_6338),
    f32::from_bits(0x3f49_0fda),
    f32::from_bits(0x3f7b_985e),
    f32::from_bits(0x3fc9_0fda),
];

/// ... and the rest.
const ATAN_LOW: [f32; 4] = [
    f32::from_bits(0x31ac_3769),
    f32::from_bits(0x3322_2168),
    f32::from_bits(0x3314_0fb4),
    f32::from_bits(0x33a2_2168),
];

/// The coefficients of `atan(x) ≈ x − x·Σ aₖ·x^(2k+2)` on |x| < 7/16.
const COEFFICIENTS: [f32; 11] = [
    f32::from_bits(0x3eaa_aaab),
    f32::from_bits(0xbe4c_cccd),
    f32::from_bits(0x3e12_4925),
    f32::from_bits(0xbde3_8e38),
    f32::from_bits(0x3dba_2e6e),
    f32::from_bits(0xbd9d_8795),
    f32::from_bits(0x3d88_6b35),
    f32::from_bits(0xbd6e_f16b),
    f32::from_bits(0x3d4b_da59),
    f32::from_bits(0xbd15_a221),
    f32::from_bits(0x3c85_69d7),
];

const PI: f32 = f32::from_bits(0x4049_0fdb);
/// `π − PI`.
const PI_LOW: f32 = f32::from_bits(0xb3bb_bd2e);
const HALF_PI: f32 = f32::from_bits(0x3fc9_0fdb);
const QUARTER_PI: f32 = f32::from_bits(0x3f49_0fdb);

/// `atan(x)`: fdlibm's `atanf`. The argument is reduced to |x| < 7/16 by one of four
/// identities around `atan(0.5)`, `atan(1)`, `atan(1.5)` and `atan(∞)`, then the odd and even
/// halves of the polynomial are summed.
#[inline(always)]
fn atan(x: f32) -> f32 {
    let signed_bits = x.to_bits() as i32;
    let magnitude_bits = signed_bits & 0x7fff_ffff;
    if magnitude_bits >= 0x4c00_0000 {
        // |x| ≥ 2²⁵, or NaN.
        if magnitude_bits > 0x7f80_0000 {
            return x + x;
        }
        return if signed_bits > 0 {
            ATAN_HIGH[3] + ATAN_LOW[3]
        } else {
            -ATAN_HIGH[3] - ATAN_LOW[3]
        };
    }
    let (reduced, identity) = if magnitude_bits < 0x3ee0_0000 {
        // |x| < 7/16; below 2⁻²⁹ atan(x) rounds to x.
        if magnitude_bits < 0x3100_0000 {
            return x;
        }
        (x, None)
    } else {
        let x = x.abs();
        if magnitude_bits < 0x3f30_0000 {
            // 7/16 ≤ |x| < 11/16
            ((2.0 * x - 1.0) / (2.0 + x), Some(0))
        } else if magnitude_bits < 0x3f98_0000 {
            // 11/16 ≤ |x| < 19/16
            ((x - 1.0) / (x + 1.0), Some(1))
        } else if magnitude_bits < 0x401c_0000 {
            // 19/16 ≤ |x| < 39/16
            ((x - 1.5) / (1.0 + 1.5 * x), Some(2))
        } else {
            (-1.0 / x, Some(3))
        }
    };
    let series = series(reduced);
    match identity {
        None => reduced - series,
        Some(k) => {
            let angle = ATAN_HIGH[k] - ((series - ATAN_LOW[k]) - reduced);
            if signed_bits < 0 { -angle } else { angle }
        }
    }
}

/// `x·Σ aₖ·x^(2k+2)`, so that `atan(x) ≈ x − series(x)` on |x| < 7/16: the odd and even halves
/// of the polynomial in `x⁴`, summed, as fdlibm orders the operations.
#[inline(always)]
fn series<R: Real>(reduced: R) -> R {
    let a = COEFFICIENTS.map(R::splat);
    let z = reduced * reduced;
    let w = z * z;
    let odd = z * (a[0] + w * (a[2] + w * (a[4] + w * (a[6] + w * (a[8] + w * a[10])))));
    let even = w * (a[1] + w * (a[3] + w * (a[5] + w * (a[7] + w * a[9]))));
    reduced * (odd + even)
}

/// `atan2(y, x)`, the angle of `(x, y)` from the x axis in [−π, π]: fdlibm's `atan2f`, with
/// C's conventions for zeros (`atan2(±0, −0) = ±π`), infinities and NaN.
#[inline(always)]
pub fn atan2(y: f32, x: f32) -> f32 {
    let (x_bits, y_bits) = (x.to_bits() as i32, y.to_bits() as i32);
    let (x_magnitude, y_magnitude) = (x_bits & 0x7fff_ffff, y_bits & 0x7fff_ffff);
    if x_magnitude > 0x7f80_0000 || y_magnitude > 0x7f80_0000 {
        return x + y;
    }
    if x_bits == 0x3f80_0000 {
        return atan(y);
    }
    // 2·(x < 0) + (y < 0), by sign bits.
    let quadrant = ((y_bits >> 31) & 1) | ((x_bits >> 30) & 2);
    if y_magnitude == 0 {
        return match quadrant {
            0 | 1 => y,
            2 => PI,
            _ => -PI,
        };
    }
    if x_magnitude == 0 {
        return if y_bits < 0 { -HALF_PI } else { HALF_PI };
    }
    if x_magnitude == 0x7f80_0000 {
        return if y_magnitude == 0x7f80_0000 {
            match quadrant {
                0 => QUARTER_PI,
                1 => -QUARTER_PI,
                2 => 3.0 * QUARTER_PI,
                _ => -3.0 * QUARTER_PI,
            }
        } else {
            match quadrant {
                0 => 0.0,
                1 => -0.0,
                2 => PI,
                _ => -PI,
            }
        };
    }
    if y_magnitude == 0x7f80_0000 {
        return if y_bits < 0 { -HALF_PI } else { HALF_PI };
    }
    let exponent_difference = (y_magnitude - x_magnitude) >> 23;
    let angle = if exponent_difference > 60 {
        HALF_PI + 0.5 * PI_LOW
    } else if x_bits < 0 && exponent_difference < -60 {
        0.0
    } else {
        atan((y / x).abs())
    };
    match quadrant {
        0 => angle,
        1 => -angle,
        2 => PI - (angle - PI_LOW),
        _ => (angle - PI_LOW) - PI,
    }
}

/// [`atan2`] in eight lanes, with its bits in every lane.
///
/// Where `y` and `x` are finite, non-zero and `x ≠ 1`, fdlibm's path is: the angle of
/// `t = |y / x|` (or π/2 or 0 when the exponents differ by more than 60), its reduction chosen
/// by the bits of `t` (which order as the values do, `t` being positive), then the quadrant.
/// Each choice is a select here. Other lanes are recomputed by [`atan2`].
#[inline(always)]
pub fn atan2_lanes(y: Floats, x: Floats) -> Floats {
    let c = Floats::splat;
    let zero = c(0.0);
    let ordinary = y
        .is_finite()
        .and(x.is_finite())
        .and(!y.eq(zero))
        .and(!x.eq(zero))
        .and(!x.eq(c(1.0)));

    let t = (y / x).abs();
    // Whether `t` is at or past a bound of fdlibm's `atan`, given by its bits.
    let band = |bits: u32| !c(f32::from_bits(bits)).gt(t);
    let past = [0x3ee0_0000, 0x3f30_0000, 0x3f98_0000, 0x401c_0000].map(band);
    let (mut numerator, mut denominator) = (t, c(1.0));
    let (mut high, mut low) = (zero, zero);
    let reductions = [
        (c(2.0) * t - c(1.0), c(2.0) + t),
        (t - c(1.0), t + c(1.0)),
        (t - c(1.5), c(1.0) + c(1.5) * t),
        (c(-1.0), t),
    ];
    for (k, (reduced_numerator, reduced_denominator)) in reductions.into_iter().enumerate() {
        numerator = past[k].select(reduced_numerator, numerator);
        denominator = past[k].select(reduced_denominator, denominator);
        high = past[k].select(c(ATAN_HIGH[k]), high);
        low = past[k].select(c(ATAN_LOW[k]), low);
    }
    let reduced = numerator / denominator;
    let series = series(reduced);
    let atan = past[0].select(high - ((series - low) - reduced), reduced - series);
    // Below 2⁻²⁹ the angle is `t`; from 2²⁵ on, π/2.
    let atan = band(0x3100_0000).select(atan, t);
    let atan = band(0x4c00_0000).select(c(ATAN_HIGH[3] + ATAN_LOW[3]), atan);

    // `(|y| bits − |x| bits) >> 23`, beyond ±60, compared before the shift.
    let exponent_gap = y.abs().to_bits() - x.abs().to_bits();
    let x_negative = zero.gt(x);
    let steep = exponent_gap.gt(Ints::splat((61 << 23) - 1));
    let flat = Ints::splat(-60 << 23).gt(exponent_gap).and(x_negative);
    let angle = steep.select(c(HALF_PI + 0.5 * PI_LOW), flat.select(zero, atan));

    let left = x_negative.select(c(PI) - (angle - c(PI_LOW)), angle);
    let left_below = (angle - c(PI_LOW)) - c(PI);
    let y_negative = zero.gt(y);
    let mut angles = y_negative.select(x_negative.select(left_below, -angle), left);
    if !ordinary.all() {
        for lane in 0..LANES {
            if !ordinary.lane(lane) {
                angles.0[lane] = atan2(y.0[lane], x.0[lane]);
            }
        }
    }
    angles
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The arguments the checksum is taken over: a million random bit patterns for each of
    /// `y` and `x` (NaN, infinities, zeros and subnormals among them), and a million pairs
    /// from the vertex normals' domain, `y = |u × v| ∈ [0, 1]`, `x = u · v ∈ [−1, 1]`.
    fn sample_pairs() -> impl Iterator<Item = (f32, f32)> {
        let mut rng = crate::test_support::XorShift64::new(0x2545_F491_4F6C_DD1Du64);
        (0..1_000_000).flat_map(move |_| {
            let state = rng.next_u64();
            let any = (f32::from_bits((state >> 32) as u32), f32::from_bits(state as u32));
            let domain = (
                (state >> 40) as f32 / 16_777_216.0,
                (state & 0xff_ffff) as f32 / 8_388_608.0 - 1.0,
            );
            [any, domain]
        })
    }

    #[test]
    fn atan2_has_the_bits_of_glibcs_atan2f() {
        // FNV-1a over the result bits (NaNs as one NaN), computed with glibc 2.36's `atan2f`.
        let mut hash = 0xcbf2_9ce4_8422_2325u64;
        for (y, x) in sample_pairs() {
            let angle = atan2(y, x);
            let bits = if angle.is_nan() { f32::NAN } else { angle }.to_bits();
            hash = (hash ^ u64::from(bits)).wrapping_mul(0x0100_0000_01b3);
        }
        assert_eq!(hash, 0x6b3e_9516_4446_136a);
    }

    /// `atan2_lanes` against `atan2`, lane by lane, on `pairs` taken eight at a time (NaNs
    /// compared as NaN).
    fn check_lanes(pairs: &[(f32, f32)]) {
        for eight in pairs.chunks(LANES) {
            let lane_pair = |lane: usize| eight[lane % eight.len()];
            let y = Floats::new(std::array::from_fn(|lane| lane_pair(lane).0));
            let x = Floats::new(std::array::from_fn(|lane| lane_pair(lane).1));
            let angles = atan2_lanes(y, x);
            for lane in 0..LANES {
                let (y, x) = lane_pair(lane);
                let (angle, expected) = (angles.0[lane], atan2(y, x));
                assert!(
                    angle.to_bits() == expected.to_bits() || angle.is_nan() && expected.is_nan(),
                    "atan2({y:e}, {x:e}): lanes {angle:e}, one float {expected:e}"
                );
            }
        }
    }

    #[test]
    fn lanes_have_the_bits_of_one_float() {
        check_lanes(&sample_pairs().collect::<Vec<_>>());
        // Every pair of awkward values: zeros, ±1, subnormals, tiny and huge, infinities, NaN,
        // the bounds of `atan`'s reductions and a unit in the last place either side, and
        // exponents 60 and 61 apart.
        let mut values = vec![
            0.0f32,
            1.0,
            2.0,
            0.5,
            1.5,
            f32::MIN_POSITIVE,
            1e-45,
            3e-39,
            1e-30,
            1e-10,
            1e10,
            1e30,
            f32::MAX,
            f32::INFINITY,
            f32::NAN,
            2f32.powi(60),
            2f32.powi(61),
            2f32.powi(-60),
            2f32.powi(-61),
            2f32.powi(-62),
            1.234_567,
            0.999_999_94,
            0.3,
        ];
        for bound in [
            0x3100_0000u32,
            0x3ee0_0000,
            0x3f30_0000,
            0x3f98_0000,
            0x401c_0000,
            0x4c00_0000,
        ] {
            values.extend([bound - 1, bound, bound + 1].map(f32::from_bits));
        }
        let signed: Vec<f32> = values.iter().flat_map(|&v| [v, -v]).collect();
        let pairs: Vec<(f32, f32)> = signed
            .iter()
            .flat_map(|&y| signed.iter().map(move |&x| (y, x)))
            .collect();
        check_lanes(&pairs);
        // Quotients landing on the bounds: `x = 1`, 2 and 0.5 times one of them.
        let near_bounds: Vec<(f32, f32)> = signed
            .iter()
            .flat_map(|&y| [(y, 1.0), (2.0 * y, 2.0), (0.5 * y, -0.5), (y * 3.0, 3.0)])
            .collect();
        check_lanes(&near_bounds);
    }

    #[test]
    fn atan2_is_within_two_units_in_the_last_place_and_keeps_cs_special_values() {
        for (y, x) in sample_pairs().filter(|(y, x)| y.is_finite() && x.is_finite()) {
            let exact = f64::from(y).atan2(f64::from(x));
            let angle = atan2(y, x);
            // At most twice the spacing of `f32`s at the result (fdlibm's `atan2f` is not
            // correctly rounded: after the quadrant's `π − …` the error passes one unit).
            let spacing = f64::from(angle.abs().max(f32::MIN_POSITIVE)) * f64::from(f32::EPSILON);
            assert!(
                (f64::from(angle) - exact).abs() <= 2.0 * spacing,
                "atan2({y:e}, {x:e}) = {angle:e}, not {exact:e}"
            );
        }
        use std::f32::consts::{FRAC_PI_2, FRAC_PI_4, PI};
        let inf = f32::INFINITY;
        for (y, x, angle) in [
            (0.0, 1.0, 0.0),
            (-0.0, 1.0, -0.0),
            (0.0, -0.0, PI),
            (-0.0, -1.0, -PI),
            (1.0, 0.0, FRAC_PI_2),
            (-1.0, -0.0, -FRAC_PI_2),
            (inf, inf, FRAC_PI_4),
            (-inf, -inf, -3.0 * FRAC_PI_4),
            (1.0, -inf, PI),
            (-1.0, inf, -0.0),
            (inf, 1.0, FRAC_PI_2),
        ] {
            assert_eq!(atan2(y, x).to_bits(), angle.to_bits(), "atan2({y}, {x})");
        }
        assert!(atan2(f32::NAN, 1.0).is_nan() && atan2(1.0, f32::NAN).is_nan());
    }
}
