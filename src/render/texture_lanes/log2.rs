//! `f32::log2` of eight lanes, with the bits of the `log2f` the scalar sampler calls.
//!
//! On x86-64 Linux, `f32::log2` is glibc's `log2f`, which on a processor with FMA runs its
//! FMA variant (an ifunc): Arm's optimized-routines algorithm (glibc's
//! `sysdeps/ieee754/flt-32/e_log2f.c` and `e_log2f_data.c`). With `x = 2ᵏ·z`, `z` in
//! [0x3f330000, 2·0x3f330000) by its bits and exact, and `c` the centre of the table's
//! subinterval that `z` falls in,
//!
//! ```text
//! log₂ x = k + log₂ c + log₁ₚ(z/c − 1)/ln 2,   r = z·(1/c) − 1,   y₀ = log₂ c + k
//! log₂ x ≈ (A₀·r² + (A₁·r + A₂))·r² + (A₃·r + y₀)      in f64, rounded once to f32
//! ```
//!
//! where the FMA build contracts every multiply-add into one fused operation (its disassembly:
//! `r = fma(z, invc, −1)`, then `A₁·r + A₂`, `A₀·r² + y`, `A₃·r + y₀` and `y·r² + p` fused;
//! `r²` a plain product). [`log2_lanes`] computes exactly that lane-wise with `f64::mul_add`,
//! in a function compiled for AVX2 and FMA (so that `mul_add` is the instruction rather than a
//! library call), for the inputs of the algorithm's main path: positive, normal, finite and
//! not 1. The others (zero, subnormals, infinities, NaN, negatives, and 1, which glibc returns
//! as +0 for every rounding mode) go to `f32::log2` lane by lane.
//!
//! The lanes are used only where they are known to be `log2f`'s bits: on x86-64 glibc with
//! AVX2 and FMA, and only when, at the first call, they agree with `f32::log2` on a sweep
//! of inputs across every binade ([`SAME_AS_LIBM`]: a guard against a different C library,
//! not a proof). On this machine a test holds them to `f32::log2` for all 2³² inputs. Elsewhere
//! every wanted lane calls `f32::log2`.

use std::sync::LazyLock;

use crate::render::lanes::{Backend, Floats, LANES, Mask, Native};

/// `log₂` of the lanes of `x` in `wanted`, each with the bits of `f32::log2`; other lanes 0.
/// Its lanes are computed in a function of their own, compiled for AVX2 and FMA, whatever
/// backend `B` the caller's lanes take.
#[inline(always)]
pub fn log2_lanes<B: Backend>(x: Floats<B>, wanted: Mask<B>) -> Floats<B> {
    log2_native(x.on(), wanted.on()).on()
}

#[inline]
fn log2_native(x: Floats<Native>, wanted: Mask<Native>) -> Floats<Native> {
    let mut log = Floats::splat(0.0);
    let mut by_libm = wanted;
    if *SAME_AS_LIBM && let Some((computed, regular)) = glibc_fma::log2(x) {
        log = computed;
        by_libm = wanted.and(!regular);
    }
    if by_libm.any() {
        for lane in 0..LANES {
            if by_libm.lane(lane) {
                log.0[lane] = x.0[lane].log2();
            }
        }
    }
    log
}

/// Whether [`glibc_fma::log2`] computes lanes here and gives `f32::log2`'s bits on a sweep
/// of inputs: every binade of the normal range, at mantissas spread over each of the table's
/// subintervals.
static SAME_AS_LIBM: LazyLock<bool> = LazyLock::new(|| {
    let inputs: Vec<f32> = (1u32..255)
        .flat_map(|exponent| (0u32..64).map(move |step| f32::from_bits((exponent << 23) | (step * 131_071))))
        .collect();
    inputs.chunks(LANES).all(|chunk| {
        let x = Floats::new(std::array::from_fn(|lane| chunk[lane % chunk.len()]));
        match glibc_fma::log2(x) {
            Some((log, regular)) => (0..LANES)
                .all(|lane| !regular.lane(lane) || log.0[lane].to_bits() == x.0[lane].log2().to_bits()),
            None => false,
        }
    })
});

/// 1/c and log₂ c of the table's sixteen subintervals (`__log2f_data.tab`), as the bits of
/// glibc's hexadecimal constants.
const TABLE: [(u64, u64); 16] = [
    (0x3ff6_61ec_79f8_f3be, 0xbfde_fec6_5b96_3019), // 0x1.661ec79f8f3bep+0, -0x1.efec65b963019p-2
    (0x3ff5_71ed_4aaf_883d, 0xbfdb_0b68_32d4_fca4), // 0x1.571ed4aaf883dp+0, -0x1.b0b6832d4fca4p-2
    (0x3ff4_9539_f0f0_10b0, 0xbfd7_418b_0a1f_b77b), // 0x1.49539f0f010bp+0, -0x1.7418b0a1fb77bp-2
    (0x3ff3_c995_b0b8_0385, 0xbfd3_9de9_1a6d_cf7b), // 0x1.3c995b0b80385p+0, -0x1.39de91a6dcf7bp-2
    (0x3ff3_0d19_0c88_64a5, 0xbfd0_1d9b_f3f2_b631), // 0x1.30d190c8864a5p+0, -0x1.01d9bf3f2b631p-2
    (0x3ff2_5e22_7b0b_8ea0, 0xbfc9_7c1d_1b3b_7af0), // 0x1.25e227b0b8eap+0, -0x1.97c1d1b3b7afp-3
    (0x3ff1_bb4a_4a1a_343f, 0xbfc2_f9e3_93af_3c9f), // 0x1.1bb4a4a1a343fp+0, -0x1.2f9e393af3c9fp-3
    (0x3ff1_2358_f08a_e5ba, 0xbfb9_60cb_bf78_8d5c), // 0x1.12358f08ae5bap+0, -0x1.960cbbf788d5cp-4
    (0x3ff0_953f_4199_00a7, 0xbfaa_6f9d_b647_5fce), // 0x1.0953f419900a7p+0, -0x1.a6f9db6475fcep-5
    (0x3ff0_0000_0000_0000, 0x0000_0000_0000_0000), // 0x1p+0, 0x0p+0
    (0x3fee_608c_fd9a_47ac, 0x3fb3_38ca_9f24_f53d), // 0x1.e608cfd9a47acp-1, 0x1.338ca9f24f53dp-4
    (0x3fec_a4b3_1f02_6aa0, 0x3fc4_76a9_5438_91ba), // 0x1.ca4b31f026aap-1, 0x1.476a9543891bap-3
    (0x3feb_2036_576a_fce6, 0x3fce_840b_4ac4_e4d2), // 0x1.b2036576afce6p-1, 0x1.e840b4ac4e4d2p-3
    (0x3fe9_c2d1_63a1_aa2d, 0x3fd4_0645_f0c6_651c), // 0x1.9c2d163a1aa2dp-1, 0x1.40645f0c6651cp-2
    (0x3fe8_86e6_0378_41ed, 0x3fd8_8e9c_2c1b_9ff8), // 0x1.886e6037841edp-1, 0x1.88e9c2c1b9ff8p-2
    (0x3fe7_67dc_f553_4862, 0x3fdc_e0a4_4eb1_7bcc), // 0x1.767dcf5534862p-1, 0x1.ce0a44eb17bccp-2
];

/// The polynomial's coefficients `A₀..A₃` (`__log2f_data.poly`): -0x1.712b6f70a7e4dp-2,
/// 0x1.ecabf496832ep-2, -0x1.715479ffae3dep-1, 0x1.715475f35c8b8p0.
const POLY: [u64; 4] = [
    0xbfd7_12b6_f70a_7e4d,
    0x3fde_cabf_4968_32e0,
    0xbfe7_1547_9ffa_e3de,
    0x3ff7_1547_5f35_c8b8,
];

/// The bits of the subintervals' origin: `z` ranges over [OFF, 2·OFF) by its bits.
const OFF: u32 = 0x3f33_0000;

/// glibc's main path for one input: its bits, the table entry, the polynomial, each
/// multiply-add fused as the FMA build fuses it.
#[inline(always)]
fn main_path(x: f32) -> f32 {
    let ix = x.to_bits();
    let tmp = ix.wrapping_sub(OFF);
    let (inv_c, log_c) = TABLE[((tmp >> 19) % 16) as usize];
    let top = tmp & 0xff80_0000;
    let z = f64::from(f32::from_bits(ix.wrapping_sub(top)));
    let k = (tmp as i32) >> 23;
    let a = POLY.map(f64::from_bits);
    let r = z.mul_add(f64::from_bits(inv_c), -1.0);
    let y0 = f64::from_bits(log_c) + f64::from(k);
    let r2 = r * r;
    let y = a[1].mul_add(r, a[2]);
    let y = a[0].mul_add(r2, y);
    let p = a[3].mul_add(r, y0);
    y.mul_add(r2, p) as f32
}

/// Whether `x` takes glibc's main path: positive, normal, finite, and not 1.
#[inline(always)]
fn is_regular(x: f32) -> bool {
    let ix = x.to_bits();
    ix.wrapping_sub(0x0080_0000) < 0x7f80_0000 - 0x0080_0000 && ix != 1f32.to_bits()
}

/// The lanes on x86-64 glibc, whose `log2f` on a processor with FMA is the variant above.
#[cfg(all(target_arch = "x86_64", target_os = "linux", target_env = "gnu"))]
#[allow(unsafe_code)]
mod glibc_fma {
    use super::{Floats, LANES, Mask, is_regular, main_path};

    /// [`main_path`] of every lane and which lanes it holds for ([`is_regular`]); `None`
    /// without AVX2 and FMA, where glibc runs another variant.
    #[inline]
    pub fn log2(x: Floats) -> Option<(Floats, Mask)> {
        if is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma") {
            // SAFETY: the processor has the features the function is compiled for.
            Some(unsafe { log2_fused(x) })
        } else {
            None
        }
    }

    #[target_feature(enable = "avx2,fma")]
    fn log2_fused(x: Floats) -> (Floats, Mask) {
        let mut log = [0.0; LANES];
        for (log, &x) in log.iter_mut().zip(&x.0) {
            *log = main_path(x);
        }
        (Floats::new(log), Mask::from_bools(x.0.map(is_regular)))
    }
}

/// Elsewhere `log2f` is some other library's: the lanes call it.
#[cfg(not(all(target_arch = "x86_64", target_os = "linux", target_env = "gnu")))]
mod glibc_fma {
    use super::{Floats, Mask};

    #[inline]
    pub fn log2(_: Floats) -> Option<(Floats, Mask)> {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every lane of `log2_lanes` over the bit patterns `patterns` (eight at a time) against
    /// `f32::log2`, bit for bit.
    fn check(patterns: impl Iterator<Item = u32>) -> u64 {
        let mut checked = 0;
        let mut lanes = [0.0; LANES];
        let mut filled = 0;
        let compare = |lanes: &[f32; LANES], filled: usize| {
            let log = log2_lanes(Floats::<Native>::new(*lanes), Mask::ALL);
            for (lane, &x) in lanes.iter().enumerate().take(filled) {
                let expected = x.log2();
                assert_eq!(
                    log.0[lane].to_bits(),
                    expected.to_bits(),
                    "log2 of {x:e} ({:#010x}): {} against {expected}",
                    x.to_bits(),
                    log.0[lane]
                );
            }
            filled as u64
        };
        for bits in patterns {
            lanes[filled] = f32::from_bits(bits);
            filled += 1;
            if filled == LANES {
                checked += compare(&lanes, filled);
                filled = 0;
            }
        }
        if filled > 0 {
            checked += compare(&lanes, filled);
        }
        checked
    }

    /// Where glibc runs its FMA variant, the lanes compute (rather than every lane calling
    /// `log2f`): otherwise the tests below would compare `log2f` with itself.
    #[test]
    fn the_lanes_compute_where_glibc_runs_its_fma_variant() {
        let expected = cfg!(all(
            target_arch = "x86_64",
            target_os = "linux",
            target_env = "gnu"
        )) && fma_detected();
        assert_eq!(*SAME_AS_LIBM, expected);
    }

    fn fma_detected() -> bool {
        #[cfg(target_arch = "x86_64")]
        return is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma");
        #[cfg(not(target_arch = "x86_64"))]
        return false;
    }

    /// A sample of all 2³² inputs (every 65,537th pattern, which visits every exponent at
    /// varied mantissas), the patterns around each table boundary, 1 and the limits of the
    /// main path; `log2_of_every_f32_equals_the_libm_one` checks them all.
    #[test]
    fn log2_of_sampled_f32_equals_the_libm_one() {
        let sampled = (0..=u32::MAX).step_by(65_537);
        let boundaries = (0..16u32).flat_map(|i| {
            let start = OFF + (i << 19);
            (start - 4..start + 4).chain((start - 4..start + 4).map(|b| b + (20 << 23)))
        });
        let limits = [
            0,
            1,
            0x007f_ffff,
            0x0080_0000,
            0x0080_0001,
            0x3f7f_ffff,
            0x3f80_0000,
            0x3f80_0001,
            0x7f7f_ffff,
            0x7f80_0000,
            0x7f80_0001,
            0x7fc0_0000,
            0x8000_0000,
            0xbf80_0000,
            0xff80_0000,
            0xffff_ffff,
        ];
        let checked = check(sampled.chain(boundaries).chain(limits));
        assert!(checked > 65_000);
    }

    /// Every `f32`, bit for bit (40 s in the optimised test profile: `cargo test --lib
    /// log2_of_every -- --ignored`).
    #[test]
    #[ignore = "all 2³² inputs: run by hand"]
    fn log2_of_every_f32_equals_the_libm_one() {
        assert_eq!(check(0..=u32::MAX), 1 << 32);
    }
}
