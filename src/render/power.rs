//! `x^y`, `2^t`, `log₂ x` and `e^x` as fixed sequences of `f32` operations, written once over
//! [`Real`], so that eight lanes (`Floats`) get exactly the bits one `f32` gets: a shininess or a
//! spot exponent that is not a whole number (the OpenGL table's 76.8, a glTF material's
//! `2/α⁴ − 2`, a glTF spot cone's exponent) and Beckmann's distribution run lane-wise with the
//! scalar specification's bits. libm's `powf` and `expf` have no lane form (one call per lane
//! was a fifth of an S1 frame at shininess 76.8), and their results may differ between libm
//! versions; these do not.
//!
//! ```text
//! log2(x):  x = 2^e·m, m ∈ [1, 2)                      from the bits; a subnormal x is first
//!                                                      scaled by 2²⁴
//!           m > √2: m ← m/2, e ← e + 1                 so m ∈ (√½, √2]
//!           s = (m − 1)/(m + 1), z = s², |s| ≤ 0.1716  m − 1 is exact there
//!           log2(x) = e + s·L(z)                       L(z) ≈ log₂((1+s)/(1−s))/s = (2/ln 2)·atanh(s)/s,
//!                                                      a cubic in z fitted at Chebyshev nodes
//! exp2(t):  n = t rounded to the nearest whole number, f = t − n ∈ [−½, ½] (exact)
//!           2^t = E(f)·2^n                             E a degree-6 polynomial fitted at
//!                                                      Chebyshev nodes, 2^n written into the bits
//!           t ≤ −126 (or NaN): 0; t > 127: +∞           results below 2⁻¹²⁶ are flushed to 0
//! pow(x, y) = exp2(y·log2(x)) for x > 0, 0 for x = 0   (y > 0: `lighting::specular_power` raises
//!                                                      0 and the whole exponents by squaring)
//! exp(x)    = exp2(x·log₂e)
//! ```
//!
//! Branches are selects: both sides are computed and one kept, in the lanes and the float
//! alike. Error, measured against `f64` (`tests`; `log2` over every positive float): `log2`
//! within [`LOG2_ERROR`] relatively (two units of the last place), `exp2` within
//! [`EXP2_ERROR`] relatively. A power's relative error grows with the size of `t = y·log₂x`,
//! whose own rounding it magnifies (as in every `exp2(y·log2 x)`): within
//! [`POW_ERROR_PER_OCTAVE`]·(1 + |t|), so about 5·10⁻⁶ at a highlight's faint edge (`t = −20`,
//! `x^y = 10⁻⁶`), and never more than [`POW_ABSOLUTE_ERROR`] absolutely for `x ≤ 1`: a
//! twenty-thousandth of one level of an 8-bit image. [`exp`] has the same relative bound with
//! `t = x·log₂e`.

use crate::render::lanes::Real;

/// Largest relative error of [`log2`] (on every positive float).
pub const LOG2_ERROR: f64 = 2.3e-7;

/// Largest relative error of [`exp2`] for `t` in (−126, 127].
pub const EXP2_ERROR: f64 = 1.5e-7;

/// [`pow`]'s relative error is within this times `1 + |y·log₂x|` (and [`exp`]'s within this
/// times `1 + |x·log₂e|`).
pub const POW_ERROR_PER_OCTAVE: f64 = 2.5e-7;

/// Largest absolute error of [`pow`] for `x` in [0, 1] and `y > 0`.
pub const POW_ABSOLUTE_ERROR: f64 = 2e-7;

/// √2, rounded down to a float: significands above it are halved.
const SQRT_2: f32 = std::f32::consts::SQRT_2;

/// `L(z)`, `log₂((1+s)/(1−s))/s` in `z = s²` for `z ≤ 0.02944` (|s| ≤ (√2 − 1)/(√2 + 1)); the
/// first is 2/ln 2.
const LOG2_POLYNOMIAL: [f32; 4] = [2.885_39, 0.961_798_85, 0.576_714_5, 0.431_733_13];

/// `E(f) ≈ 2^f` for `f ∈ [−½, ½]`, from the constant term up.
const EXP2_POLYNOMIAL: [f32; 7] = [
    1.0,
    std::f32::consts::LN_2,
    0.240_226_5,
    0.055_503_27,
    0.009_618_025,
    0.001_340_043_3,
    0.000_154_697_29,
];

/// `log₂ x` for `x > 0`: −151 for `x = 0` (and for negative `x`, of no meaning).
#[inline(always)]
pub fn log2<R: Real>(x: R) -> R {
    let c = R::splat;
    let subnormal = c(f32::MIN_POSITIVE).gt(x);
    let (exponent, significand) = R::select(subnormal, x * c(16_777_216.0), x).exponent_and_significand();
    let exponent = R::select(subnormal, exponent - c(24.0), exponent);
    let high = significand.gt(c(SQRT_2));
    let m = R::select(high, significand * c(0.5), significand);
    let e = R::select(high, exponent + c(1.0), exponent);
    let s = (m - c(1.0)) / (m + c(1.0));
    let z = s * s;
    let [l0, l1, l2, l3] = LOG2_POLYNOMIAL.map(c);
    e + s * (((l3 * z + l2) * z + l1) * z + l0)
}

/// `2^t`: 0 for `t ≤ −126` (and NaN), +∞ for `t > 127`.
#[inline(always)]
pub fn exp2<R: Real>(t: R) -> R {
    let c = R::splat;
    let in_range = t.gt(c(-126.0));
    let overflows = t.gt(c(127.0));
    let clamped = R::select(in_range, R::select(overflows, c(127.0), t), c(-126.0));
    let whole = (clamped + R::select(clamped.gt(c(0.0)), c(0.5), c(-0.5))).trunc();
    let f = clamped - whole;
    let [e0, e1, e2, e3, e4, e5, e6] = EXP2_POLYNOMIAL.map(c);
    let fraction = (((((e6 * f + e5) * f + e4) * f + e3) * f + e2) * f + e1) * f + e0;
    let power = fraction * R::exp2_whole(whole);
    R::select(overflows, c(f32::INFINITY), R::select(in_range, power, c(0.0)))
}

/// `x^y` for `x ≥ 0` and `y > 0` (0 for `x = 0`).
#[inline(always)]
pub fn pow<R: Real>(x: R, y: R) -> R {
    let c = R::splat;
    R::select(x.gt(c(0.0)), exp2(y * log2(x)), c(0.0))
}

/// `e^x`.
#[inline(always)]
pub fn exp<R: Real>(x: R) -> R {
    exp2(x * R::splat(std::f32::consts::LOG2_E))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::lanes::{Floats, LANES};

    /// Every `step`-th positive float from 2⁻¹⁴⁹ to `limit`, by bits.
    fn floats_up_to(limit: f32, step: u32) -> impl Iterator<Item = f32> {
        (1..=limit.to_bits()).step_by(step as usize).map(f32::from_bits)
    }

    fn relative(got: f32, exact: f64) -> f64 {
        ((f64::from(got) - exact) / exact).abs()
    }

    /// The largest relative error of `log2` over every `step`-th positive finite float.
    fn log2_error(step: u32) -> f64 {
        let mut worst = 0.0f64;
        for x in floats_up_to(f32::MAX, step) {
            let exact = f64::from(x).log2();
            if exact != 0.0 {
                worst = worst.max(relative(log2(x), exact));
            }
        }
        worst
    }

    /// Every positive float: `cargo test --release --lib log2_of_every_positive -- --ignored`.
    #[test]
    #[ignore = "all 2³¹ positive floats: about 30 seconds in release"]
    fn log2_of_every_positive_float_is_within_its_stated_error() {
        let worst = log2_error(1);
        assert!(worst <= LOG2_ERROR, "{worst:e}");
    }

    #[test]
    fn log2_is_within_its_stated_error() {
        let worst = log2_error(1_009);
        assert!(worst <= LOG2_ERROR, "{worst:e}");
        assert_eq!(log2(1.0f32), 0.0);
        assert_eq!(log2(0.5f32), -1.0);
        assert_eq!(log2(1024.0f32), 10.0);
        assert_eq!(log2(f32::from_bits(1)), -149.0);
    }

    #[test]
    fn exp2_is_within_its_stated_error() {
        let mut worst = 0.0f64;
        for i in 0..=2_530_000 {
            let t = (-126.0 + f64::from(i) * 1e-4) as f32;
            if t > -126.0 {
                worst = worst.max(relative(exp2(t), f64::from(t).exp2()));
            }
        }
        assert!(worst <= EXP2_ERROR, "{worst:e}");
        for n in -125..=127 {
            assert_eq!(exp2(n as f32), (n as f32).exp2(), "{n}");
        }
        assert_eq!(exp2(-126.0f32), 0.0);
        assert_eq!(exp2(-1000.0f32), 0.0);
        assert_eq!(exp2(f32::NEG_INFINITY), 0.0);
        assert_eq!(exp2(f32::NAN), 0.0);
        assert_eq!(exp2(127.5f32), f32::INFINITY);
        assert_eq!(exp2(f32::INFINITY), f32::INFINITY);
    }

    /// Exponents as scenes have them: the OpenGL table's, glTF's `2/α⁴ − 2`, MTL files' `Ns`,
    /// spot exponents, and a few extreme ones.
    const EXPONENTS: [f32; 12] = [
        0.01, 0.5, 1.5, 2.5, 9.846_15, 12.8, 27.897_436, 76.8, 89.6, 998.0, 1024.5, 1e5,
    ];

    #[test]
    fn pow_is_within_its_stated_error() {
        for y in EXPONENTS {
            let (mut worst_relative, mut worst_absolute) = (0.0f64, 0.0f64);
            for x in floats_up_to(1.0, 1_013).chain([1.0, 1.000_000_1, 1.5, 2.0, 1e3]) {
                let exact = f64::from(x).powf(f64::from(y));
                let got = pow(x, y);
                if exact.log2() <= -126.0 {
                    assert!(f64::from(got) <= 2f64.powi(-126), "{x}^{y}");
                    continue;
                }
                if exact >= 2f64.powi(127) {
                    continue;
                }
                let octaves = 1.0 + (f64::from(y) * f64::from(x).log2()).abs();
                worst_relative = worst_relative.max(relative(got, exact) / octaves);
                if x <= 1.0 {
                    worst_absolute = worst_absolute.max((f64::from(got) - exact).abs());
                }
            }
            assert!(worst_relative <= POW_ERROR_PER_OCTAVE, "{y}: {worst_relative:e}");
            assert!(worst_absolute <= POW_ABSOLUTE_ERROR, "{y}: {worst_absolute:e}");
            assert_eq!(pow(0.0f32, y), 0.0);
            assert_eq!(pow(1.0f32, y), 1.0);
        }
    }

    #[test]
    fn exp_is_within_its_stated_error() {
        let mut worst = 0.0f64;
        for i in 0..=2_000_000 {
            let x = (-87.0 + f64::from(i) * 8.7e-5) as f32;
            let exact = f64::from(x).exp();
            let octaves = 1.0 + (f64::from(x) * std::f64::consts::LOG2_E).abs();
            worst = worst.max(relative(exp(x), exact) / octaves);
        }
        assert!(worst <= POW_ERROR_PER_OCTAVE, "{worst:e}");
        assert_eq!(exp(0.0f32), 1.0);
    }

    /// Lanes against single floats, bit for bit, on awkward arguments.
    #[test]
    fn lanes_equal_single_floats_bit_for_bit() {
        let values = [
            0.0f32,
            -0.0,
            1e-45,
            1e-39,
            1e-30,
            0.3,
            0.707_106_77,
            std::f32::consts::FRAC_1_SQRT_2,
            0.999_999_94,
            1.0,
            1.000_000_1,
            3.5,
            1e30,
            f32::MAX,
            f32::INFINITY,
            f32::NAN,
            -2.5,
        ];
        for (i, window) in values.windows(LANES).enumerate() {
            let x: Floats = Floats::new(std::array::from_fn(|lane| window[lane]));
            let y = Floats::new(std::array::from_fn(|lane| {
                EXPONENTS[(i + 3 * lane) % EXPONENTS.len()]
            }));
            let t: Floats = Floats::new(std::array::from_fn(|lane| (window[lane] - 0.5) * 300.0));
            let (logs, powers, exps) = (log2(x), pow(x, y), exp2(t));
            for lane in 0..LANES {
                let (x, y, t) = (x.0[lane], y.0[lane], t.0[lane]);
                assert_eq!(logs.0[lane].to_bits(), log2(x).to_bits(), "log2 {x}");
                assert_eq!(powers.0[lane].to_bits(), pow(x, y).to_bits(), "pow {x} {y}");
                assert_eq!(exps.0[lane].to_bits(), exp2(t).to_bits(), "exp2 {t}");
            }
        }
    }
}
