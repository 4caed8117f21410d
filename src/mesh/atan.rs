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
    let a = COEFFICIENTS;
    let z = reduced * reduced;
    let w = z * z;
    let odd = z * (a[0] + w * (a[2] + w * (a[4] + w * (a[6] + w * (a[8] + w * a[10])))));
    let even = w * (a[1] + w * (a[3] + w * (a[5] + w * (a[7] + w * a[9]))));
    match identity {
        None => reduced - reduced * (odd + even),
        Some(k) => {
            let angle = ATAN_HIGH[k] - ((reduced * (odd + even) - ATAN_LOW[k]) - reduced);
            if signed_bits < 0 { -angle } else { angle }
        }
    }
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The arguments the checksum is taken over: a million random bit patterns for each of
    /// `y` and `x` (NaN, infinities, zeros and subnormals among them), and a million pairs
    /// from the vertex normals' domain, `y = |u × v| ∈ [0, 1]`, `x = u · v ∈ [−1, 1]`.
    fn sample_pairs() -> impl Iterator<Item = (f32, f32)> {
        let mut state = 0x2545_F491_4F6C_DD1Du64;
        (0..1_000_000).flat_map(move |_| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
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
