//! Eight shading points at once: `f32` and `Vec3` arithmetic over fixed-size lane arrays.
//!
//! Every operation is the scalar one applied lane by lane (the same IEEE operations in the same
//! order as glam's `Vec3`), so a lane's result has the same bits as the scalar code on the same
//! input; branches become per-lane masks and selects. The operations come from a [`Backend`],
//! a type parameter of the lane types that defaults to the target's own ([`Native`]):
//! [`Sse`] on x86-64 (SSE instructions on the two four-lane halves of each array),
//! [`Portable`] elsewhere (plain loops over the arrays, left to the compiler's vectoriser).
//! Both compute the same IEEE operations and are checked against each other and against glam
//! below. The portable loops were the only backend at first; on the baseline x86-64 target the
//! compiler turned them into a mix of scalar and shuffled partial vectors, about 1.7 times the
//! instructions of the SSE backend in the lighting (`FastLighting::light_lanes`).
//!
//! Where the processor has AVX2, [`run_widest`] runs a piece of lane code ([`LaneWork`],
//! generic over the backend) on a third backend, `Avx`, inside an `avx2` function: one 256-bit
//! instruction per operation, half the SSE backend's. Elsewhere it runs the same code on the
//! native backend: the same operations, so the same bits, on every machine. What runs there
//! comes in units of a few hundred operations or more: a tile's rasterization (one sample or
//! several, and a shadow map's tiles), a tile's last shading pass, the lighting with the Phong
//! interpolation around it (with a one-face shadow map's lookups), and a batch of pixels whose
//! surface varies (weights, texture sampling, the surface stage). The rest stays on the native
//! backend (the whole program built for AVX2 was slower on flat and Gouraud frames:
//! docs/performance.md).

use std::fmt::Debug;
use std::marker::PhantomData;
use std::ops::{Add, Div, Mul, Neg, Not, Sub};

use glam::{Mat3, Vec2, Vec3};

/// How many points are processed together. Eight fills an AVX register, or two SSE registers on
/// the baseline x86-64 target.
pub const LANES: usize = 8;

/// The lane operations a backend provides, on the arrays of [`Floats`] and [`Mask`]: each one
/// the scalar IEEE operation lane by lane, bit for bit, on `f32`, integer and `f64` lanes
/// ([`Floats`], [`Ints`], [`Wides`]).
pub trait Backend: Copy + Default + Debug + PartialEq + Send + Sync + 'static {
    fn add(a: [f32; LANES], b: [f32; LANES]) -> [f32; LANES];
    fn sub(a: [f32; LANES], b: [f32; LANES]) -> [f32; LANES];
    fn mul(a: [f32; LANES], b: [f32; LANES]) -> [f32; LANES];
    fn div(a: [f32; LANES], b: [f32; LANES]) -> [f32; LANES];
    fn sqrt(a: [f32; LANES]) -> [f32; LANES];
    /// The sign flipped (`-a`: `-0.0` stays distinct from `0.0 - 0.0`).
    fn neg(a: [f32; LANES]) -> [f32; LANES];
    /// The sign cleared (`f32::abs`).
    fn abs(a: [f32; LANES]) -> [f32; LANES];
    /// Towards zero, as [`truncate`].
    fn trunc(a: [f32; LANES]) -> [f32; LANES];
    /// `>`, ordered (false where either side is NaN), as mask bits.
    fn gt(a: [f32; LANES], b: [f32; LANES]) -> [u32; LANES];
    /// `<=`, ordered.
    fn le(a: [f32; LANES], b: [f32; LANES]) -> [u32; LANES];
    /// `==`, ordered (true for `-0.0 == 0.0`).
    fn eq(a: [f32; LANES], b: [f32; LANES]) -> [u32; LANES];
    /// `f32::is_finite`.
    fn is_finite(a: [f32; LANES]) -> [u32; LANES];
    fn and(a: [u32; LANES], b: [u32; LANES]) -> [u32; LANES];
    fn or(a: [u32; LANES], b: [u32; LANES]) -> [u32; LANES];
    /// Every bit flipped.
    fn not(a: [u32; LANES]) -> [u32; LANES];
    /// Whether any lane is set.
    fn any(mask: [u32; LANES]) -> bool;
    /// `if_true`'s bits where `mask` is set, `if_false`'s elsewhere.
    fn select(mask: [u32; LANES], if_true: [f32; LANES], if_false: [f32; LANES]) -> [f32; LANES];
    /// `i32::wrapping_add`.
    fn add_ints(a: [i32; LANES], b: [i32; LANES]) -> [i32; LANES];
    /// `i32::wrapping_sub`.
    fn sub_ints(a: [i32; LANES], b: [i32; LANES]) -> [i32; LANES];
    fn and_ints(a: [i32; LANES], b: [i32; LANES]) -> [i32; LANES];
    /// `i32::wrapping_mul`.
    fn mul_ints(a: [i32; LANES], b: [i32; LANES]) -> [i32; LANES];
    /// `>`, signed.
    fn gt_ints(a: [i32; LANES], b: [i32; LANES]) -> [u32; LANES];
    fn eq_ints(a: [i32; LANES], b: [i32; LANES]) -> [u32; LANES];
    /// `as f32`: to nearest, ties to even.
    fn ints_to_floats(a: [i32; LANES]) -> [f32; LANES];
    /// Towards zero, −2³¹ out of range and for NaN (as [`truncate`]).
    fn truncate_to_ints(a: [f32; LANES]) -> [i32; LANES];
    fn add_wides(a: [f64; LANES], b: [f64; LANES]) -> [f64; LANES];
    /// `>`, ordered.
    fn gt_wides(a: [f64; LANES], b: [f64; LANES]) -> [u32; LANES];
    /// `as f32`: to nearest, ties to even.
    fn wides_to_floats(a: [f64; LANES]) -> [f32; LANES];
    /// `slots`, read so that a select of them stored back stays a blend and a whole store
    /// (see [`Floats::load_to_blend`]): a plain load, but on the `Avx` backend.
    #[inline(always)]
    fn load_to_blend(slots: &[u32; LANES]) -> [u32; LANES] {
        *slots
    }
    /// `low` then `high` as one group of lanes, read as [`Backend::load_to_blend`] reads.
    #[inline(always)]
    fn load_halves_to_blend(low: &[u32; LANES / 2], high: &[u32; LANES / 2]) -> [u32; LANES] {
        std::array::from_fn(|lane| {
            if lane < LANES / 2 {
                low[lane]
            } else {
                high[lane - LANES / 2]
            }
        })
    }
}

/// The target's own backend: the one every lane type uses unless told otherwise.
#[cfg(target_arch = "x86_64")]
pub type Native = Sse;

/// The target's own backend: the one every lane type uses unless told otherwise.
#[cfg(not(target_arch = "x86_64"))]
pub type Native = Portable;

pub use portable::Portable;
#[cfg(target_arch = "x86_64")]
pub use sse::Sse;

/// One `f32` per lane.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Floats<B = Native>(pub [f32; LANES], PhantomData<B>);

/// Where a condition holds, per lane: all bits set or none, as SIMD compares produce, so
/// selects compile to bitwise `and`/`or` rather than branches per lane.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Mask<B = Native>([u32; LANES], PhantomData<B>);

/// One `i32` per lane (texel indices, edge functions), with wrapping arithmetic.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Ints<B = Native>(pub [i32; LANES], PhantomData<B>);

/// One `f64` per lane, for whole numbers: exact below 2⁵³ in magnitude, where `i32` lanes are
/// too narrow (the one-sample rasterizer's edge functions on large triangles).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Wides<B = Native>(pub [f64; LANES], PhantomData<B>);

/// Lane code generic over the backend, for [`run_widest`]: what it computes must not depend on
/// `B` (every backend has the same bits), only how fast it runs.
pub trait LaneWork {
    type Output;
    /// The work on backend `B`. Everything it calls on lanes must inline into it (be
    /// `#[inline(always)]`), or that part is compiled for the baseline target after all.
    fn run<B: Backend>(self) -> Self::Output;
}

/// `work` on the widest lanes the processor has: the `Avx` backend where it has AVX2 (and
/// POPCNT), else the native backend. The result has the same bits either way. A call costs a
/// feature test, and its lanes cross in memory: worth it for a few hundred operations, not for
/// a few dozen.
#[inline(always)]
pub fn run_widest<W: LaneWork>(work: W) -> W::Output {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("popcnt") {
        return avx2::run(work);
    }
    work.run::<Native>()
}

/// [`run_widest`]'s AVX2 path: the lane operations as 256-bit AVX instructions, one per
/// operation, and the one place that enters code compiled for a feature the baseline target
/// lacks. The portable loops compiled for AVX2 were tried first: the compiler vectorised them
/// in the lighting alone, but fell back to scalar code once interpolation shared the function.
///
/// Soundness: [`Avx`](avx2::Avx) is private to this file, so lane code can only be
/// instantiated with it by [`run_widest`], inside `run_on_avx2`, which runs only after the
/// processor was found to have AVX2 and POPCNT. Its operations' intrinsics therefore run only
/// there.
#[cfg(target_arch = "x86_64")]
#[allow(unsafe_code)]
mod avx2 {
    use std::arch::x86_64::{
        __m128i, __m256, __m256d, __m256i, _CMP_EQ_OQ, _CMP_GT_OQ, _CMP_LE_OQ, _mm256_add_epi32,
        _mm256_add_pd, _mm256_add_ps, _mm256_and_ps, _mm256_and_si256, _mm256_andnot_ps, _mm256_blendv_ps,
        _mm256_castpd_ps, _mm256_cmp_pd, _mm256_cmp_ps, _mm256_cmpeq_epi32, _mm256_cmpgt_epi32,
        _mm256_cvtepi32_ps, _mm256_cvtpd_ps, _mm256_cvttps_epi32, _mm256_div_ps, _mm256_movemask_ps,
        _mm256_mul_ps, _mm256_mullo_epi32, _mm256_or_ps, _mm256_permute4x64_pd, _mm256_set_m128,
        _mm256_set1_epi32, _mm256_shuffle_ps, _mm256_sqrt_ps, _mm256_sub_epi32, _mm256_sub_ps, _mm256_xor_ps,
    };

    use super::{Backend, LANES, LaneWork};

    /// AVX on all eight lanes at once.
    #[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
    pub(super) struct Avx;

    #[inline(always)]
    pub fn run<W: LaneWork>(work: W) -> W::Output {
        // SAFETY: the caller has checked that the processor has AVX2 and POPCNT.
        unsafe { run_on_avx2(work) }
    }

    /// `work` on the [`Avx`] backend, compiled with AVX2 and POPCNT enabled (every processor
    /// with AVX2 has POPCNT; without it `count_ones`, as in the shadow lookups' texel counts, is
    /// a dozen instructions). Called only where the processor has both.
    #[target_feature(enable = "avx2,popcnt")]
    unsafe fn run_on_avx2<W: LaneWork>(work: W) -> W::Output {
        work.run::<Avx>()
    }

    /// Applies an AVX operation to one or two lane arrays (of `f32` or mask bits).
    macro_rules! wide {
        ($op:ident$(::<$imm:ident>)?($($arg:expr),+)) => {{
            // SAFETY: `Avx`'s operations run only inside `run_on_avx2` (see the module).
            bytemuck::cast(unsafe { $op$(::<$imm>)?($(bytemuck::cast::<_, __m256>($arg)),+) })
        }};
    }

    /// Applies an AVX2 integer operation to two integer lane arrays.
    macro_rules! int_wide {
        ($op:ident($a:expr, $b:expr)) => {{
            // SAFETY: `Avx`'s operations run only inside `run_on_avx2` (see the module).
            bytemuck::cast(unsafe { $op(bytemuck::cast::<_, __m256i>($a), bytemuck::cast::<_, __m256i>($b)) })
        }};
    }

    impl Backend for Avx {
        #[inline(always)]
        fn add(a: [f32; LANES], b: [f32; LANES]) -> [f32; LANES] {
            wide!(_mm256_add_ps(a, b))
        }

        #[inline(always)]
        fn sub(a: [f32; LANES], b: [f32; LANES]) -> [f32; LANES] {
            wide!(_mm256_sub_ps(a, b))
        }

        #[inline(always)]
        fn mul(a: [f32; LANES], b: [f32; LANES]) -> [f32; LANES] {
            wide!(_mm256_mul_ps(a, b))
        }

        #[inline(always)]
        fn div(a: [f32; LANES], b: [f32; LANES]) -> [f32; LANES] {
            wide!(_mm256_div_ps(a, b))
        }

        #[inline(always)]
        fn sqrt(a: [f32; LANES]) -> [f32; LANES] {
            wide!(_mm256_sqrt_ps(a))
        }

        /// The sign bit flipped.
        #[inline(always)]
        fn neg(a: [f32; LANES]) -> [f32; LANES] {
            let sign = [-0.0f32; LANES];
            wide!(_mm256_xor_ps(a, sign))
        }

        /// The sign bit cleared.
        #[inline(always)]
        fn abs(a: [f32; LANES]) -> [f32; LANES] {
            let sign = [-0.0f32; LANES];
            wide!(_mm256_andnot_ps(sign, a))
        }

        /// `vcvttps2dq` and back: towards zero, −2³¹ out of range ([`super::truncate`]).
        #[inline(always)]
        fn trunc(a: [f32; LANES]) -> [f32; LANES] {
            // SAFETY: as `wide!`'s.
            bytemuck::cast(unsafe { _mm256_cvtepi32_ps(_mm256_cvttps_epi32(bytemuck::cast(a))) })
        }

        /// Ordered and quiet, as Rust's `>`: false where either side is NaN.
        #[inline(always)]
        fn gt(a: [f32; LANES], b: [f32; LANES]) -> [u32; LANES] {
            wide!(_mm256_cmp_ps::<_CMP_GT_OQ>(a, b))
        }

        #[inline(always)]
        fn le(a: [f32; LANES], b: [f32; LANES]) -> [u32; LANES] {
            wide!(_mm256_cmp_ps::<_CMP_LE_OQ>(a, b))
        }

        #[inline(always)]
        fn eq(a: [f32; LANES], b: [f32; LANES]) -> [u32; LANES] {
            wide!(_mm256_cmp_ps::<_CMP_EQ_OQ>(a, b))
        }

        /// The magnitude's bits below infinity's, compared as integers.
        #[inline(always)]
        fn is_finite(a: [f32; LANES]) -> [u32; LANES] {
            let bits: __m256i = bytemuck::cast(a);
            // SAFETY: as `wide!`'s.
            bytemuck::cast(unsafe {
                _mm256_cmpgt_epi32(
                    _mm256_set1_epi32(0x7f80_0000),
                    _mm256_and_si256(bits, _mm256_set1_epi32(0x7fff_ffff)),
                )
            })
        }

        #[inline(always)]
        fn and(a: [u32; LANES], b: [u32; LANES]) -> [u32; LANES] {
            wide!(_mm256_and_ps(a, b))
        }

        #[inline(always)]
        fn or(a: [u32; LANES], b: [u32; LANES]) -> [u32; LANES] {
            wide!(_mm256_or_ps(a, b))
        }

        #[inline(always)]
        fn not(a: [u32; LANES]) -> [u32; LANES] {
            let ones = [u32::MAX; LANES];
            wide!(_mm256_xor_ps(a, ones))
        }

        #[inline(always)]
        fn any(mask: [u32; LANES]) -> bool {
            // SAFETY: as `wide!`'s.
            unsafe { _mm256_movemask_ps(bytemuck::cast(mask)) != 0 }
        }

        /// `vblendvps`, which picks by each lane's sign bit: a mask lane is all ones or none.
        #[inline(always)]
        fn select(mask: [u32; LANES], if_true: [f32; LANES], if_false: [f32; LANES]) -> [f32; LANES] {
            wide!(_mm256_blendv_ps(if_false, if_true, mask))
        }

        #[inline(always)]
        fn add_ints(a: [i32; LANES], b: [i32; LANES]) -> [i32; LANES] {
            int_wide!(_mm256_add_epi32(a, b))
        }

        #[inline(always)]
        fn sub_ints(a: [i32; LANES], b: [i32; LANES]) -> [i32; LANES] {
            int_wide!(_mm256_sub_epi32(a, b))
        }

        #[inline(always)]
        fn and_ints(a: [i32; LANES], b: [i32; LANES]) -> [i32; LANES] {
            int_wide!(_mm256_and_si256(a, b))
        }

        #[inline(always)]
        fn mul_ints(a: [i32; LANES], b: [i32; LANES]) -> [i32; LANES] {
            int_wide!(_mm256_mullo_epi32(a, b))
        }

        #[inline(always)]
        fn gt_ints(a: [i32; LANES], b: [i32; LANES]) -> [u32; LANES] {
            int_wide!(_mm256_cmpgt_epi32(a, b))
        }

        #[inline(always)]
        fn eq_ints(a: [i32; LANES], b: [i32; LANES]) -> [u32; LANES] {
            int_wide!(_mm256_cmpeq_epi32(a, b))
        }

        /// `vcvtdq2ps`: to nearest, ties to even, as the MXCSR says.
        #[inline(always)]
        fn ints_to_floats(a: [i32; LANES]) -> [f32; LANES] {
            // SAFETY: as `wide!`'s.
            bytemuck::cast(unsafe { _mm256_cvtepi32_ps(bytemuck::cast(a)) })
        }

        /// `vcvttps2dq`: towards zero, −2³¹ out of range ([`super::truncate`]).
        #[inline(always)]
        fn truncate_to_ints(a: [f32; LANES]) -> [i32; LANES] {
            // SAFETY: as `wide!`'s.
            bytemuck::cast(unsafe { _mm256_cvttps_epi32(bytemuck::cast(a)) })
        }

        /// Four lanes per register: two `vaddpd`.
        #[inline(always)]
        fn add_wides(a: [f64; LANES], b: [f64; LANES]) -> [f64; LANES] {
            let (a, b): ([__m256d; 2], [__m256d; 2]) = (bytemuck::cast(a), bytemuck::cast(b));
            // SAFETY: as `wide!`'s.
            let half = |i: usize| unsafe { _mm256_add_pd(a[i], b[i]) };
            bytemuck::cast([half(0), half(1)])
        }

        /// Two `vcmppd` (ordered, quiet), their 64-bit masks narrowed to 32 bits by taking
        /// each one's low half: `vshufps` interleaves the halves' pairs within each 128 bits,
        /// `vpermpd` puts the pairs back in lane order.
        #[inline(always)]
        fn gt_wides(a: [f64; LANES], b: [f64; LANES]) -> [u32; LANES] {
            let (a, b): ([__m256d; 2], [__m256d; 2]) = (bytemuck::cast(a), bytemuck::cast(b));
            // SAFETY: as `wide!`'s.
            bytemuck::cast(unsafe {
                let low = _mm256_castpd_ps(_mm256_cmp_pd::<_CMP_GT_OQ>(a[0], b[0]));
                let high = _mm256_castpd_ps(_mm256_cmp_pd::<_CMP_GT_OQ>(a[1], b[1]));
                let pairs: __m256d = bytemuck::cast(_mm256_shuffle_ps::<0b10_00_10_00>(low, high));
                _mm256_permute4x64_pd::<0b11_01_10_00>(pairs)
            })
        }

        /// Two `vcvtpd2ps`: to nearest, ties to even, as the MXCSR says.
        #[inline(always)]
        fn wides_to_floats(a: [f64; LANES]) -> [f32; LANES] {
            let halves: [__m256d; 2] = bytemuck::cast(a);
            // SAFETY: as `wide!`'s.
            bytemuck::cast(unsafe { _mm256_set_m128(_mm256_cvtpd_ps(halves[1]), _mm256_cvtpd_ps(halves[0])) })
        }

        /// Volatile loads: written as a plain load, a select and a store back to the same
        /// place, LLVM's x86 back end folds the three into a masked store (`vmaskmovps`),
        /// which on AMD's Zen cores takes about four times as long as the load, blend and
        /// store it replaces; it does not fold a volatile load.
        #[inline(always)]
        fn load_to_blend(slots: &[u32; LANES]) -> [u32; LANES] {
            bytemuck::cast(read_unaligned_volatile::<__m256i, _>(slots))
        }

        #[inline(always)]
        fn load_halves_to_blend(low: &[u32; LANES / 2], high: &[u32; LANES / 2]) -> [u32; LANES] {
            let halves = [low, high].map(read_unaligned_volatile::<__m128i, _>);
            bytemuck::cast(halves)
        }
    }

    /// A vector type at byte alignment, for [`read_unaligned_volatile`].
    #[repr(C, packed)]
    #[derive(Clone, Copy)]
    struct Unaligned<V: Copy>(V);

    /// The bytes of `from` as a `V` of the same size, by one volatile load (`vmovdqu`).
    #[inline(always)]
    fn read_unaligned_volatile<V: Copy, T>(from: &T) -> V {
        const { assert!(size_of::<V>() == size_of::<T>()) };
        // SAFETY: `from` is valid for reads of `size_of::<T>()` bytes, as many as `V` has, and
        // `Unaligned<V>` needs no alignment; every bit pattern is a valid vector.
        let Unaligned(value) =
            unsafe { std::ptr::read_volatile(std::ptr::from_ref(from).cast::<Unaligned<V>>()) };
        value
    }
}

impl<B: Backend> Wides<B> {
    /// The lanes `lanes`.
    #[inline(always)]
    pub const fn new(lanes: [f64; LANES]) -> Self {
        Wides(lanes, PhantomData)
    }

    #[inline(always)]
    pub const fn splat(value: f64) -> Self {
        Wides::new([value; LANES])
    }

    /// The same lanes, for backend `C`'s operations.
    #[inline(always)]
    pub fn on<C: Backend>(self) -> Wides<C> {
        Wides::new(self.0)
    }

    /// `>` per lane.
    #[inline(always)]
    pub fn gt(self, other: Self) -> Mask<B> {
        Mask::from_bits(B::gt_wides(self.0, other.0))
    }

    /// Each lane `as f32`: rounded once, to nearest, ties to even (so a whole number below 2⁵³
    /// converts exactly as the same integer held in an `i64` does).
    #[inline(always)]
    pub fn to_floats(self) -> Floats<B> {
        Floats::new(B::wides_to_floats(self.0))
    }
}

/// `+` per lane.
impl<B: Backend> Add for Wides<B> {
    type Output = Wides<B>;
    #[inline(always)]
    fn add(self, other: Wides<B>) -> Wides<B> {
        Wides::new(B::add_wides(self.0, other.0))
    }
}

impl<B: Backend> Floats<B> {
    /// The lanes `lanes`.
    #[inline(always)]
    pub const fn new(lanes: [f32; LANES]) -> Self {
        Floats(lanes, PhantomData)
    }

    /// The lanes of `slots`, to be blended with new values and stored back whole, as a depth
    /// test does: `*slots = nearer.select(new, Floats::load_to_blend(slots)).0`. A plain read
    /// gives the same lanes, but on the `Avx` backend LLVM folds that read, select and store
    /// into a masked store, slow on AMD processors (see its `load_to_blend`).
    #[inline(always)]
    pub fn load_to_blend(slots: &[f32; LANES]) -> Self {
        Floats::new(bytemuck::cast(B::load_to_blend(bytemuck::cast_ref(slots))))
    }

    #[inline(always)]
    pub const fn splat(value: f32) -> Self {
        Floats::new([value; LANES])
    }

    /// The same lanes, for backend `C`'s operations.
    #[inline(always)]
    pub fn on<C: Backend>(self) -> Floats<C> {
        Floats::new(self.0)
    }

    /// Each lane's `value` of the entry of `items` in that lane (read in place: mapping the
    /// array by value would copy it for every call).
    #[inline(always)]
    pub fn gather<T>(items: &[T; LANES], value: impl Fn(&T) -> f32) -> Self {
        let mut lanes = [0.0; LANES];
        for (lane, item) in lanes.iter_mut().zip(items) {
            *lane = value(item);
        }
        Floats::new(lanes)
    }

    #[inline(always)]
    pub fn sqrt(self) -> Self {
        Floats::new(B::sqrt(self.0))
    }

    /// `f32::max` per lane (the other operand where one is NaN). Left to the compiler on every
    /// backend: an SSE `maxps` treats NaN and signed zeros differently from `f32::max`.
    #[inline(always)]
    pub fn max(self, other: Self) -> Self {
        Floats::new(std::array::from_fn(|i| self.0[i].max(other.0[i])))
    }

    /// `f32::min` per lane (the other operand where one is NaN), left to the compiler as
    /// [`Floats::max`] is.
    #[inline(always)]
    pub fn min(self, other: Self) -> Self {
        Floats::new(std::array::from_fn(|i| self.0[i].min(other.0[i])))
    }

    /// `>` per lane: false where either side is NaN.
    #[inline(always)]
    pub fn gt(self, other: Self) -> Mask<B> {
        Mask::from_bits(B::gt(self.0, other.0))
    }

    /// `<=` per lane: false where either side is NaN.
    #[inline(always)]
    pub fn le(self, other: Self) -> Mask<B> {
        Mask::from_bits(B::le(self.0, other.0))
    }

    /// `==` per lane: false where either side is NaN, true for `-0.0 == 0.0`.
    #[inline(always)]
    pub fn eq(self, other: Self) -> Mask<B> {
        Mask::from_bits(<B as Backend>::eq(self.0, other.0))
    }

    /// `f32::is_finite` per lane, as an integer compare of the bits.
    #[inline(always)]
    pub fn is_finite(self) -> Mask<B> {
        Mask::from_bits(B::is_finite(self.0))
    }
}

impl<B: Backend> Floats<B> {
    /// The floats whose bits the lanes of `bits` are (`f32::from_bits`).
    #[inline(always)]
    pub fn from_bits(bits: Ints<B>) -> Self {
        Floats::new(bytemuck::cast(bits.0))
    }

    /// Each lane's bits, as an integer (`f32::to_bits`).
    #[inline(always)]
    pub fn to_bits(self) -> Ints<B> {
        Ints::new(bytemuck::cast(self.0))
    }

    /// Each lane rounded towards zero to an `i32` (`as i32` for |x| < 2³¹; −2³¹ beyond that
    /// and for NaN, as [`truncate`]).
    #[inline(always)]
    pub fn truncate_to_ints(self) -> Ints<B> {
        Ints::new(B::truncate_to_ints(self.0))
    }
}

impl<B: Backend> Ints<B> {
    /// The lanes `lanes`.
    #[inline(always)]
    pub const fn new(lanes: [i32; LANES]) -> Self {
        Ints(lanes, PhantomData)
    }

    /// The lanes of `slots` (as `i32`), read as [`Floats::load_to_blend`] reads.
    #[inline(always)]
    pub fn load_to_blend(slots: &[u32; LANES]) -> Self {
        Ints::new(bytemuck::cast(B::load_to_blend(slots)))
    }

    #[inline(always)]
    pub const fn splat(value: i32) -> Self {
        Ints::new([value; LANES])
    }

    /// The same lanes, for backend `C`'s operations.
    #[inline(always)]
    pub fn on<C: Backend>(self) -> Ints<C> {
        Ints::new(self.0)
    }

    /// Each lane's `value` of the entry of `items` in that lane (see [`Floats::gather`]).
    #[inline(always)]
    pub fn gather<T>(items: &[T; LANES], value: impl Fn(&T) -> i32) -> Self {
        let mut lanes = [0; LANES];
        for (lane, item) in lanes.iter_mut().zip(items) {
            *lane = value(item);
        }
        Ints::new(lanes)
    }

    /// `&` per lane.
    #[inline(always)]
    pub fn and(self, other: Self) -> Self {
        Ints::new(B::and_ints(self.0, other.0))
    }

    /// `i32::wrapping_mul` per lane.
    #[inline(always)]
    pub fn wrapping_mul(self, other: Self) -> Self {
        Ints::new(B::mul_ints(self.0, other.0))
    }

    /// `>` per lane.
    #[inline(always)]
    pub fn gt(self, other: Self) -> Mask<B> {
        Mask::from_bits(B::gt_ints(self.0, other.0))
    }

    /// `==` per lane.
    #[inline(always)]
    pub fn eq(self, other: Self) -> Mask<B> {
        Mask::from_bits(B::eq_ints(self.0, other.0))
    }

    /// Each lane `as f32` (rounded to nearest, ties to even, as Rust's conversion is).
    #[inline(always)]
    pub fn to_floats(self) -> Floats<B> {
        Floats::new(B::ints_to_floats(self.0))
    }
}

impl<B: Backend> Mask<B> {
    /// Every lane.
    pub const ALL: Self = Mask([u32::MAX; LANES], PhantomData);

    /// The mask whose lanes have the bits `bits` (each all ones or all zeros).
    #[inline(always)]
    const fn from_bits(bits: [u32; LANES]) -> Self {
        Mask(bits, PhantomData)
    }

    #[inline(always)]
    pub fn from_bools(lanes: [bool; LANES]) -> Self {
        Mask::from_bits(lanes.map(|on| 0u32.wrapping_sub(u32::from(on))))
    }

    /// The same lanes, for backend `C`'s operations.
    #[inline(always)]
    pub fn on<C: Backend>(self) -> Mask<C> {
        Mask::from_bits(self.0)
    }

    /// Whether the condition holds in `lane`.
    #[inline(always)]
    pub fn lane(self, lane: usize) -> bool {
        self.0[lane] != 0
    }

    #[inline(always)]
    pub fn and(self, other: Self) -> Self {
        Mask::from_bits(B::and(self.0, other.0))
    }

    #[inline(always)]
    pub fn or(self, other: Self) -> Self {
        Mask::from_bits(B::or(self.0, other.0))
    }

    #[inline(always)]
    pub fn any(self) -> bool {
        B::any(self.0)
    }

    /// How many lanes the condition holds in.
    #[inline(always)]
    pub fn count(self) -> usize {
        self.0.iter().filter(|&&lane| lane != 0).count()
    }

    /// Whether the condition holds in every lane.
    #[inline(always)]
    pub fn all(self) -> bool {
        !(!self).any()
    }

    /// Per lane, `if_true` where the mask holds and `if_false` elsewhere (bit for bit).
    #[inline(always)]
    pub fn select(self, if_true: Floats<B>, if_false: Floats<B>) -> Floats<B> {
        Floats::new(B::select(self.0, if_true.0, if_false.0))
    }

    #[inline(always)]
    pub fn select3(self, if_true: Vec3s<B>, if_false: Vec3s<B>) -> Vec3s<B> {
        Vec3s {
            x: self.select(if_true.x, if_false.x),
            y: self.select(if_true.y, if_false.y),
            z: self.select(if_true.z, if_false.z),
        }
    }
}

impl<B: Backend> Mask<B> {
    /// Per lane, `if_true` where the mask holds and `if_false` elsewhere.
    #[inline(always)]
    pub fn select_ints(self, if_true: Ints<B>, if_false: Ints<B>) -> Ints<B> {
        Ints::new(bytemuck::cast(B::select(
            self.0,
            bytemuck::cast(if_true.0),
            bytemuck::cast(if_false.0),
        )))
    }

    /// −1 where the mask holds, 0 elsewhere (its bits, as integers).
    #[inline(always)]
    pub fn to_ints(self) -> Ints<B> {
        Ints::new(bytemuck::cast(self.0))
    }
}

impl<B: Backend> Not for Mask<B> {
    type Output = Mask<B>;
    #[inline(always)]
    fn not(self) -> Mask<B> {
        Mask::from_bits(B::not(self.0))
    }
}

macro_rules! lane_operator {
    ($trait:ident, $method:ident) => {
        impl<B: Backend> $trait for Floats<B> {
            type Output = Floats<B>;
            #[inline(always)]
            fn $method(self, other: Floats<B>) -> Floats<B> {
                Floats::new(B::$method(self.0, other.0))
            }
        }
    };
}

lane_operator!(Add, add);
lane_operator!(Sub, sub);
lane_operator!(Mul, mul);
lane_operator!(Div, div);

/// Which of a multisampled pixel's `S` samples show triangle `id`: bit `i` is set where
/// `ids[i] == id` (the tile's triangle numbers of `raster::Visibility`). Compared four samples
/// at a time where the backend has the instructions.
#[inline(always)]
pub fn samples_showing<const S: usize>(ids: &[u32; S], id: u32) -> u32 {
    native::samples_showing(ids, id)
}

/// Whether each of a group's triangle numbers names a triangle (is not `none`), into
/// `shown`; returns how many do. One compare, two packs and one 8-byte store where the backend
/// has them: as a loop of `bool` stores it was a tenth of a flat close-up's frame.
#[inline(always)]
pub fn mark_shown(ids: &[u32; LANES], none: u32, shown: &mut [bool; LANES]) -> usize {
    native::mark_shown(ids, none, shown)
}

/// Sets every entry of `out` to `value`, as four entries' worth of floats twice: six 16-byte
/// stores of the three patterns (`x y z x`, `y z x y`, `z x y z`) that four `Vec3`s make,
/// where the backend has them. `slice::fill` (and the compiler, given the patterns in plain
/// code) writes each `Vec3` as an 8-byte and a 4-byte store: a fifth of a flat close-up's
/// frame went there.
#[inline(always)]
pub fn fill_vec3s(out: &mut [Vec3; LANES], value: Vec3) {
    native::fill_vec3s(out, value)
}

/// The `LANES / COLUMNS` rows of `COLUMNS` values of `buffer` from `first` on, `stride` apart,
/// as one group of lanes (row after row; `COLUMNS` is `LANES` or `LANES / 2`), read as
/// [`Floats::load_to_blend`] reads.
#[inline(always)]
pub fn load_rows_to_blend<B: Backend, const COLUMNS: usize>(
    buffer: &[u32],
    first: usize,
    stride: usize,
) -> [u32; LANES] {
    const { assert!(COLUMNS == LANES || COLUMNS == LANES / 2) };
    let row = |index: usize| &buffer[first + index * stride..][..COLUMNS];
    if COLUMNS == LANES {
        B::load_to_blend(row(0).try_into().expect("a row of a group"))
    } else {
        let half = |index| row(index).try_into().expect("a row of half a group");
        B::load_halves_to_blend(half(0), half(1))
    }
}

/// Asks the processor to bring `items[index]` into the cache, where the backend can (a
/// `prefetcht0`; nothing elsewhere, or for an index past the end): for data a loop will read a
/// few iterations on at an address it knows now, such as a dense mesh's vertices, scattered
/// over arrays far larger than the cache, of the triangles a tile shades.
#[inline(always)]
pub fn prefetch<T>(items: &[T], index: usize) {
    native::prefetch(items, index)
}

/// [`prefetch`] of every cache line `items[index]` lies on (a raster triangle is about a
/// hundred bytes, on two or three lines, and the raster reads fields at both ends of it).
#[inline(always)]
pub fn prefetch_item<T>(items: &[T], index: usize) {
    native::prefetch_item(items, index)
}

#[cfg(target_arch = "x86_64")]
use sse as native;

#[cfg(not(target_arch = "x86_64"))]
use portable as native;

/// The lane operations as loops over the arrays, for the compiler to vectorise: the backend of
/// targets without one of their own (compiled everywhere, so the tests can hold the others to
/// it).
#[cfg_attr(target_arch = "x86_64", allow(dead_code))]
mod portable {
    use glam::Vec3;

    use super::{Backend, LANES};

    /// The portable loops.
    #[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
    pub struct Portable;

    #[inline(always)]
    fn zip(a: [f32; LANES], b: [f32; LANES], f: impl Fn(f32, f32) -> f32) -> [f32; LANES] {
        std::array::from_fn(|i| f(a[i], b[i]))
    }

    /// A lane's bits from its comparison, straight (through a `[bool; LANES]` the compiler
    /// compared lane by lane and packed the results).
    #[inline(always)]
    fn compare(a: [f32; LANES], b: [f32; LANES], f: impl Fn(f32, f32) -> bool) -> [u32; LANES] {
        std::array::from_fn(|i| bits(f(a[i], b[i])))
    }

    #[inline(always)]
    fn bits(on: bool) -> u32 {
        0u32.wrapping_sub(u32::from(on))
    }

    impl Backend for Portable {
        #[inline(always)]
        fn add(a: [f32; LANES], b: [f32; LANES]) -> [f32; LANES] {
            zip(a, b, |a, b| a + b)
        }

        #[inline(always)]
        fn sub(a: [f32; LANES], b: [f32; LANES]) -> [f32; LANES] {
            zip(a, b, |a, b| a - b)
        }

        #[inline(always)]
        fn mul(a: [f32; LANES], b: [f32; LANES]) -> [f32; LANES] {
            zip(a, b, |a, b| a * b)
        }

        #[inline(always)]
        fn div(a: [f32; LANES], b: [f32; LANES]) -> [f32; LANES] {
            zip(a, b, |a, b| a / b)
        }

        #[inline(always)]
        fn sqrt(a: [f32; LANES]) -> [f32; LANES] {
            a.map(f32::sqrt)
        }

        #[inline(always)]
        fn neg(a: [f32; LANES]) -> [f32; LANES] {
            a.map(|a| -a)
        }

        #[inline(always)]
        fn abs(a: [f32; LANES]) -> [f32; LANES] {
            a.map(f32::abs)
        }

        #[inline(always)]
        fn trunc(a: [f32; LANES]) -> [f32; LANES] {
            a.map(super::truncate)
        }

        #[inline(always)]
        fn gt(a: [f32; LANES], b: [f32; LANES]) -> [u32; LANES] {
            compare(a, b, |a, b| a > b)
        }

        #[inline(always)]
        fn le(a: [f32; LANES], b: [f32; LANES]) -> [u32; LANES] {
            compare(a, b, |a, b| a <= b)
        }

        #[inline(always)]
        fn eq(a: [f32; LANES], b: [f32; LANES]) -> [u32; LANES] {
            compare(a, b, |a, b| a == b)
        }

        #[inline(always)]
        fn is_finite(a: [f32; LANES]) -> [u32; LANES] {
            a.map(|a| bits((a.to_bits() & 0x7fff_ffff) < 0x7f80_0000))
        }

        #[inline(always)]
        fn and(a: [u32; LANES], b: [u32; LANES]) -> [u32; LANES] {
            std::array::from_fn(|i| a[i] & b[i])
        }

        #[inline(always)]
        fn mul_ints(a: [i32; LANES], b: [i32; LANES]) -> [i32; LANES] {
            std::array::from_fn(|i| a[i].wrapping_mul(b[i]))
        }

        #[inline(always)]
        fn or(a: [u32; LANES], b: [u32; LANES]) -> [u32; LANES] {
            std::array::from_fn(|i| a[i] | b[i])
        }

        #[inline(always)]
        fn not(a: [u32; LANES]) -> [u32; LANES] {
            a.map(|m| !m)
        }

        #[inline(always)]
        fn any(mask: [u32; LANES]) -> bool {
            mask.iter().fold(0, |any, &m| any | m) != 0
        }

        #[inline(always)]
        fn select(mask: [u32; LANES], if_true: [f32; LANES], if_false: [f32; LANES]) -> [f32; LANES] {
            std::array::from_fn(|i| {
                f32::from_bits((if_true[i].to_bits() & mask[i]) | (if_false[i].to_bits() & !mask[i]))
            })
        }

        #[inline(always)]
        fn add_ints(a: [i32; LANES], b: [i32; LANES]) -> [i32; LANES] {
            std::array::from_fn(|i| a[i].wrapping_add(b[i]))
        }

        #[inline(always)]
        fn sub_ints(a: [i32; LANES], b: [i32; LANES]) -> [i32; LANES] {
            std::array::from_fn(|i| a[i].wrapping_sub(b[i]))
        }

        #[inline(always)]
        fn and_ints(a: [i32; LANES], b: [i32; LANES]) -> [i32; LANES] {
            std::array::from_fn(|i| a[i] & b[i])
        }

        #[inline(always)]
        fn gt_ints(a: [i32; LANES], b: [i32; LANES]) -> [u32; LANES] {
            std::array::from_fn(|i| bits(a[i] > b[i]))
        }

        #[inline(always)]
        fn eq_ints(a: [i32; LANES], b: [i32; LANES]) -> [u32; LANES] {
            std::array::from_fn(|i| bits(a[i] == b[i]))
        }

        #[inline(always)]
        fn ints_to_floats(a: [i32; LANES]) -> [f32; LANES] {
            a.map(|i| i as f32)
        }

        #[inline(always)]
        fn truncate_to_ints(a: [f32; LANES]) -> [i32; LANES] {
            a.map(|x| {
                if x.abs() < 2_147_483_648.0 {
                    x as i32
                } else {
                    i32::MIN
                }
            })
        }

        #[inline(always)]
        fn add_wides(a: [f64; LANES], b: [f64; LANES]) -> [f64; LANES] {
            std::array::from_fn(|i| a[i] + b[i])
        }

        #[inline(always)]
        fn gt_wides(a: [f64; LANES], b: [f64; LANES]) -> [u32; LANES] {
            std::array::from_fn(|i| bits(a[i] > b[i]))
        }

        #[inline(always)]
        fn wides_to_floats(a: [f64; LANES]) -> [f32; LANES] {
            a.map(|value| value as f32)
        }
    }

    #[inline(always)]
    pub fn samples_showing<const S: usize>(ids: &[u32; S], id: u32) -> u32 {
        (0..S).fold(0, |mask, sample| mask | (u32::from(ids[sample] == id) << sample))
    }

    #[inline(always)]
    pub fn mark_shown(ids: &[u32; LANES], none: u32, shown: &mut [bool; LANES]) -> usize {
        for (shown, &id) in shown.iter_mut().zip(ids) {
            *shown = id != none;
        }
        ids.iter().filter(|&&id| id != none).count()
    }

    #[inline(always)]
    pub fn fill_vec3s(out: &mut [Vec3; LANES], value: Vec3) {
        out.fill(value);
    }

    #[inline(always)]
    pub fn prefetch<T>(_items: &[T], _index: usize) {}

    #[inline(always)]
    pub fn prefetch_item<T>(_items: &[T], _index: usize) {}
}

/// The lane operations as SSE instructions on the two four-lane halves of the arrays. SSE and
/// SSE2 are part of the x86-64 baseline, enabled on every x86-64 target, so their intrinsics
/// are sound to call anywhere; Rust still asks for `unsafe` around them because the functions
/// calling them do not name the features themselves (and cannot while they are
/// `#[inline(always)]`). That is the only `unsafe` here but for `fill_vec3s`'s stores,
/// through a pointer into the array it is given, within its bounds.
#[cfg(target_arch = "x86_64")]
#[allow(unsafe_code)]
mod sse {
    use glam::Vec3;
    use std::arch::x86_64::{
        __m128, __m128d, __m128i, _MM_HINT_T0, _mm_add_epi32, _mm_add_pd, _mm_add_ps, _mm_and_ps,
        _mm_and_si128, _mm_andnot_ps, _mm_andnot_si128, _mm_castpd_ps, _mm_castsi128_ps, _mm_cmpeq_epi32,
        _mm_cmpeq_ps, _mm_cmpgt_epi32, _mm_cmpgt_pd, _mm_cmpgt_ps, _mm_cmple_ps, _mm_cmplt_epi32,
        _mm_cvtepi32_ps, _mm_cvtpd_ps, _mm_cvttps_epi32, _mm_div_ps, _mm_movelh_ps, _mm_movemask_epi8,
        _mm_movemask_ps, _mm_mul_ps, _mm_or_ps, _mm_packs_epi16, _mm_packs_epi32, _mm_prefetch,
        _mm_set1_epi8, _mm_set1_epi32, _mm_setr_ps, _mm_shuffle_ps, _mm_sqrt_ps, _mm_storel_epi64,
        _mm_storeu_ps, _mm_sub_epi32, _mm_sub_ps, _mm_xor_ps,
    };

    use super::{Backend, LANES};

    /// SSE on the two halves.
    #[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
    pub struct Sse;

    const _: () = assert!(LANES == 8, "the lanes are two SSE registers");

    /// Applies an SSE operation to both halves of one or two lane arrays (of `f32` or mask
    /// bits).
    macro_rules! halves {
        ($op:ident($($arg:expr),+)) => {{
            let args = ($(bytemuck::cast::<_, [__m128; 2]>($arg),)+);
            // SAFETY: SSE and SSE2 are enabled on every x86-64 target (see the module).
            let pair = |i: usize| unsafe { halves!(@call $op, args, i, $($arg),+) };
            bytemuck::cast([pair(0), pair(1)])
        }};
        (@call $op:ident, $args:ident, $i:ident, $a:expr) => { $op($args.0[$i]) };
        (@call $op:ident, $args:ident, $i:ident, $a:expr, $b:expr) => { $op($args.0[$i], $args.1[$i]) };
    }

    /// Applies an SSE2 integer operation to both halves of two integer lane arrays.
    macro_rules! int_halves {
        ($op:ident($a:expr, $b:expr)) => {{
            let (a, b): ([__m128i; 2], [__m128i; 2]) = (bytemuck::cast($a), bytemuck::cast($b));
            // SAFETY: SSE2 is enabled on every x86-64 target (see the module).
            let pair = |i: usize| unsafe { $op(a[i], b[i]) };
            bytemuck::cast([pair(0), pair(1)])
        }};
    }

    /// Four samples per `pcmpeqd` and `movmskps`; patterns whose sample count is not a
    /// multiple of four (two samples) take the portable loop.
    #[inline(always)]
    pub fn samples_showing<const S: usize>(ids: &[u32; S], id: u32) -> u32 {
        if !S.is_multiple_of(4) {
            return super::portable::samples_showing(ids, id);
        }
        let (quads, _) = ids.as_chunks::<4>();
        // SAFETY: SSE and SSE2 are enabled on every x86-64 target (see the module).
        let wanted = unsafe { _mm_set1_epi32(id as i32) };
        quads.iter().enumerate().fold(0, |mask, (quad, ids)| {
            let ids: __m128i = bytemuck::cast(*ids);
            // SAFETY: as above.
            let equal = unsafe { _mm_movemask_ps(_mm_castsi128_ps(_mm_cmpeq_epi32(ids, wanted))) };
            mask | ((equal as u32) << (4 * quad))
        })
    }

    /// `pcmpeqd` on each half, the masks packed to bytes (`packssdw`, `packsswb`: −1 stays
    /// −1), turned to 0 or 1 (`pandn`) and stored as eight `bool`s (`movq`).
    #[inline(always)]
    pub fn mark_shown(ids: &[u32; LANES], none: u32, shown: &mut [bool; LANES]) -> usize {
        let [low, high]: [__m128i; 2] = bytemuck::cast(*ids);
        // SAFETY: SSE2 is enabled on every x86-64 target (see the module); the store writes
        // eight bytes, `shown`'s eight `bool`s, each 0 or 1.
        unsafe {
            let none = _mm_set1_epi32(none as i32);
            let words = _mm_packs_epi32(_mm_cmpeq_epi32(low, none), _mm_cmpeq_epi32(high, none));
            let bytes = _mm_packs_epi16(words, words);
            let flags = _mm_andnot_si128(bytes, _mm_set1_epi8(1));
            _mm_storel_epi64(shown.as_mut_ptr().cast::<__m128i>(), flags);
            LANES - (_mm_movemask_epi8(bytes) as u32 & 0xff).count_ones() as usize
        }
    }

    /// One `prefetcht0`, within the slice.
    #[inline(always)]
    pub fn prefetch<T>(items: &[T], index: usize) {
        if let Some(item) = items.get(index) {
            // SAFETY: SSE is enabled on every x86-64 target (see the module); a prefetch reads
            // nothing the program sees, and the address is that of an element of `items`.
            unsafe { _mm_prefetch::<_MM_HINT_T0>(std::ptr::from_ref(item).cast::<i8>()) }
        }
    }

    /// A `prefetcht0` of the item's bytes 64 apart and of its last byte, within the slice: one
    /// on each cache line the item lies on.
    #[inline(always)]
    pub fn prefetch_item<T>(items: &[T], index: usize) {
        if let Some(item) = items.get(index) {
            let first = std::ptr::from_ref(item).cast::<i8>();
            let last = size_of::<T>().saturating_sub(1);
            for offset in (0..last).step_by(64).chain([last]) {
                // SAFETY: as in `prefetch`; every offset lies within the element.
                unsafe { _mm_prefetch::<_MM_HINT_T0>(first.add(offset)) }
            }
        }
    }

    /// Six `movups` of the three patterns four `Vec3`s make.
    #[inline(always)]
    pub fn fill_vec3s(out: &mut [Vec3; LANES], value: Vec3) {
        let [x, y, z] = value.to_array();
        // SAFETY: SSE is enabled on every x86-64 target (see the module), and the six stores
        // of four floats each lie within `out`'s 24 floats (`LANES` is 8).
        unsafe {
            let patterns = [
                _mm_setr_ps(x, y, z, x),
                _mm_setr_ps(y, z, x, y),
                _mm_setr_ps(z, x, y, z),
            ];
            let floats = out.as_mut_ptr().cast::<f32>();
            for quad in 0..3 * LANES / 4 {
                _mm_storeu_ps(floats.add(4 * quad), patterns[quad % 3]);
            }
        }
    }

    impl Backend for Sse {
        #[inline(always)]
        fn add(a: [f32; LANES], b: [f32; LANES]) -> [f32; LANES] {
            halves!(_mm_add_ps(a, b))
        }

        #[inline(always)]
        fn sub(a: [f32; LANES], b: [f32; LANES]) -> [f32; LANES] {
            halves!(_mm_sub_ps(a, b))
        }

        #[inline(always)]
        fn mul(a: [f32; LANES], b: [f32; LANES]) -> [f32; LANES] {
            halves!(_mm_mul_ps(a, b))
        }

        #[inline(always)]
        fn div(a: [f32; LANES], b: [f32; LANES]) -> [f32; LANES] {
            halves!(_mm_div_ps(a, b))
        }

        #[inline(always)]
        fn sqrt(a: [f32; LANES]) -> [f32; LANES] {
            halves!(_mm_sqrt_ps(a))
        }

        /// The sign bit flipped (`xorps`).
        #[inline(always)]
        fn neg(a: [f32; LANES]) -> [f32; LANES] {
            let sign = [-0.0f32; LANES];
            halves!(_mm_xor_ps(a, sign))
        }

        /// The sign bit cleared (`andnps`).
        #[inline(always)]
        fn abs(a: [f32; LANES]) -> [f32; LANES] {
            let sign = [-0.0f32; LANES];
            halves!(_mm_andnot_ps(sign, a))
        }

        /// `cvttps2dq` and back: towards zero, −2³¹ out of range ([`super::truncate`]).
        #[inline(always)]
        fn trunc(a: [f32; LANES]) -> [f32; LANES] {
            let halves: [__m128; 2] = bytemuck::cast(a);
            // SAFETY: SSE2 is enabled on every x86-64 target (see the module).
            let truncated = |half: __m128| unsafe { _mm_cvtepi32_ps(_mm_cvttps_epi32(half)) };
            bytemuck::cast(halves.map(truncated))
        }

        /// An ordered compare, as Rust's `>`: false where either side is NaN.
        #[inline(always)]
        fn gt(a: [f32; LANES], b: [f32; LANES]) -> [u32; LANES] {
            halves!(_mm_cmpgt_ps(a, b))
        }

        /// An ordered compare, as Rust's `<=`.
        #[inline(always)]
        fn le(a: [f32; LANES], b: [f32; LANES]) -> [u32; LANES] {
            halves!(_mm_cmple_ps(a, b))
        }

        /// An ordered compare, as Rust's `==`.
        #[inline(always)]
        fn eq(a: [f32; LANES], b: [f32; LANES]) -> [u32; LANES] {
            halves!(_mm_cmpeq_ps(a, b))
        }

        /// The magnitude's bits below infinity's, compared as integers.
        #[inline(always)]
        fn is_finite(a: [f32; LANES]) -> [u32; LANES] {
            let halves: [__m128i; 2] = bytemuck::cast(a);
            // SAFETY: SSE2 is enabled on every x86-64 target (see the module).
            let finite = |half: __m128i| unsafe {
                _mm_cmplt_epi32(
                    _mm_and_si128(half, _mm_set1_epi32(0x7fff_ffff)),
                    _mm_set1_epi32(0x7f80_0000),
                )
            };
            bytemuck::cast(halves.map(finite))
        }

        #[inline(always)]
        fn and(a: [u32; LANES], b: [u32; LANES]) -> [u32; LANES] {
            halves!(_mm_and_ps(a, b))
        }

        #[inline(always)]
        fn or(a: [u32; LANES], b: [u32; LANES]) -> [u32; LANES] {
            halves!(_mm_or_ps(a, b))
        }

        #[inline(always)]
        fn not(a: [u32; LANES]) -> [u32; LANES] {
            let ones = [u32::MAX; LANES];
            halves!(_mm_xor_ps(a, ones))
        }

        #[inline(always)]
        fn any(mask: [u32; LANES]) -> bool {
            let [low, high]: [__m128; 2] = bytemuck::cast(mask);
            // SAFETY: SSE is enabled on every x86-64 target (see the module).
            unsafe { _mm_movemask_ps(_mm_or_ps(low, high)) != 0 }
        }

        #[inline(always)]
        fn select(mask: [u32; LANES], if_true: [f32; LANES], if_false: [f32; LANES]) -> [f32; LANES] {
            let mask: [__m128; 2] = bytemuck::cast(mask);
            let (if_true, if_false): ([__m128; 2], [__m128; 2]) =
                (bytemuck::cast(if_true), bytemuck::cast(if_false));
            // SAFETY: SSE is enabled on every x86-64 target (see the module).
            let pick = |i: usize| unsafe {
                _mm_or_ps(
                    _mm_and_ps(mask[i], if_true[i]),
                    _mm_andnot_ps(mask[i], if_false[i]),
                )
            };
            bytemuck::cast([pick(0), pick(1)])
        }

        #[inline(always)]
        fn add_ints(a: [i32; LANES], b: [i32; LANES]) -> [i32; LANES] {
            int_halves!(_mm_add_epi32(a, b))
        }

        #[inline(always)]
        fn sub_ints(a: [i32; LANES], b: [i32; LANES]) -> [i32; LANES] {
            int_halves!(_mm_sub_epi32(a, b))
        }

        #[inline(always)]
        fn and_ints(a: [i32; LANES], b: [i32; LANES]) -> [i32; LANES] {
            int_halves!(_mm_and_si128(a, b))
        }

        /// SSE2 has no 32-bit product (`pmulld` is SSE4.1): the portable loop.
        #[inline(always)]
        fn mul_ints(a: [i32; LANES], b: [i32; LANES]) -> [i32; LANES] {
            std::array::from_fn(|i| a[i].wrapping_mul(b[i]))
        }

        #[inline(always)]
        fn gt_ints(a: [i32; LANES], b: [i32; LANES]) -> [u32; LANES] {
            int_halves!(_mm_cmpgt_epi32(a, b))
        }

        #[inline(always)]
        fn eq_ints(a: [i32; LANES], b: [i32; LANES]) -> [u32; LANES] {
            int_halves!(_mm_cmpeq_epi32(a, b))
        }

        /// `cvtdq2ps`, which rounds as the MXCSR says: to nearest, ties to even, as Rust's
        /// `as f32`.
        #[inline(always)]
        fn ints_to_floats(a: [i32; LANES]) -> [f32; LANES] {
            let halves: [__m128i; 2] = bytemuck::cast(a);
            // SAFETY: SSE2 is enabled on every x86-64 target (see the module).
            let converted = |half: __m128i| unsafe { _mm_cvtepi32_ps(half) };
            bytemuck::cast(halves.map(converted))
        }

        /// `cvttps2dq`: towards zero, −2³¹ out of range ([`super::truncate`]).
        #[inline(always)]
        fn truncate_to_ints(a: [f32; LANES]) -> [i32; LANES] {
            let halves: [__m128; 2] = bytemuck::cast(a);
            // SAFETY: SSE2 is enabled on every x86-64 target (see the module).
            let truncated = |half: __m128| unsafe { _mm_cvttps_epi32(half) };
            bytemuck::cast(halves.map(truncated))
        }

        #[inline(always)]
        fn add_wides(a: [f64; LANES], b: [f64; LANES]) -> [f64; LANES] {
            let (a, b): ([__m128d; 4], [__m128d; 4]) = (bytemuck::cast(a), bytemuck::cast(b));
            // SAFETY: SSE2 is enabled on every x86-64 target (see the module).
            let quarter = |i: usize| unsafe { _mm_add_pd(a[i], b[i]) };
            bytemuck::cast([quarter(0), quarter(1), quarter(2), quarter(3)])
        }

        /// Two `cmpgtpd` per half, their 64-bit masks narrowed to 32 bits by taking each one's
        /// low half (all ones or all zeros, like the whole).
        #[inline(always)]
        fn gt_wides(a: [f64; LANES], b: [f64; LANES]) -> [u32; LANES] {
            let (a, b): ([__m128d; 4], [__m128d; 4]) = (bytemuck::cast(a), bytemuck::cast(b));
            // SAFETY: SSE2 is enabled on every x86-64 target (see the module).
            let half = |i: usize| unsafe {
                let low = _mm_castpd_ps(_mm_cmpgt_pd(a[2 * i], b[2 * i]));
                let high = _mm_castpd_ps(_mm_cmpgt_pd(a[2 * i + 1], b[2 * i + 1]));
                _mm_shuffle_ps::<0b10_00_10_00>(low, high)
            };
            bytemuck::cast([half(0), half(1)])
        }

        /// `cvtpd2ps`, which rounds as the MXCSR says: to nearest, ties to even, as Rust's
        /// `as f32`.
        #[inline(always)]
        fn wides_to_floats(a: [f64; LANES]) -> [f32; LANES] {
            let quarters: [__m128d; 4] = bytemuck::cast(a);
            // SAFETY: SSE2 is enabled on every x86-64 target (see the module).
            let half = |i: usize| unsafe {
                _mm_movelh_ps(_mm_cvtpd_ps(quarters[2 * i]), _mm_cvtpd_ps(quarters[2 * i + 1]))
            };
            bytemuck::cast([half(0), half(1)])
        }
    }
}

/// One `Vec3` per lane, stored as three lane arrays.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Vec3s<B = Native> {
    pub x: Floats<B>,
    pub y: Floats<B>,
    pub z: Floats<B>,
}

impl<B: Backend> Vec3s<B> {
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
            x: Floats::new(vectors.map(|v| v.x)),
            y: Floats::new(vectors.map(|v| v.y)),
            z: Floats::new(vectors.map(|v| v.z)),
        }
    }

    /// The same lanes, for backend `C`'s operations.
    #[inline(always)]
    pub fn on<C: Backend>(self) -> Vec3s<C> {
        Vec3s {
            x: self.x.on(),
            y: self.y.on(),
            z: self.z.on(),
        }
    }

    /// Each lane's `value` of the entry of `items` in that lane (see [`Floats::gather`]).
    #[inline(always)]
    pub fn gather<T>(items: &[T; LANES], value: impl Fn(&T) -> Vec3) -> Self {
        let mut lanes = Vec3s::splat(Vec3::ZERO);
        for (lane, item) in items.iter().enumerate() {
            let v = value(item);
            (lanes.x.0[lane], lanes.y.0[lane], lanes.z.0[lane]) = (v.x, v.y, v.z);
        }
        lanes
    }

    #[inline(always)]
    pub fn to_array(self) -> [Vec3; LANES] {
        std::array::from_fn(|i| Vec3::new(self.x.0[i], self.y.0[i], self.z.0[i]))
    }

    /// Lane `lane` as a `Vec3`.
    #[inline(always)]
    pub fn lane(&self, lane: usize) -> Vec3 {
        Vec3::new(self.x.0[lane], self.y.0[lane], self.z.0[lane])
    }

    /// [`Vec3s::to_array`] written straight into `out`. Building the array and copying it
    /// into a frame's row instead left the copy to `memcpy`, whose wide loads of the lanes
    /// just stored cannot be forwarded from those stores: a quarter of the time of a
    /// Gouraud close-up, in a call that counts as a few instructions.
    #[inline(always)]
    pub fn write_to(self, out: &mut [Vec3; LANES]) {
        for (lane, v) in out.iter_mut().enumerate() {
            *v = Vec3::new(self.x.0[lane], self.y.0[lane], self.z.0[lane]);
        }
    }

    /// `Vec3::dot`: `(x·x') + (y·y') + (z·z')`, summed left to right.
    #[inline(always)]
    pub fn dot(self, other: Self) -> Floats<B> {
        self.x * other.x + self.y * other.y + self.z * other.z
    }

    /// `Vec3::cross`, component by component as glam writes it.
    #[inline(always)]
    pub fn cross(self, other: Self) -> Self {
        Vec3s {
            x: self.y * other.z - other.y * self.z,
            y: self.z * other.x - other.z * self.x,
            z: self.x * other.y - other.x * self.y,
        }
    }

    /// `v == Vec3::ZERO` per lane (each component `== 0.0`: true for `-0.0`, false for NaN).
    #[inline(always)]
    pub fn is_zero(self) -> Mask<B> {
        let zero = Floats::splat(0.0);
        self.x.eq(zero).and(self.y.eq(zero)).and(self.z.eq(zero))
    }

    /// `Vec3::length`.
    #[inline(always)]
    pub fn length(self) -> Floats<B> {
        self.dot(self).sqrt()
    }

    /// Each component times the lane's `factor` (`Vec3 * f32`).
    #[inline(always)]
    pub fn scale(self, factor: Floats<B>) -> Self {
        Vec3s {
            x: self.x * factor,
            y: self.y * factor,
            z: self.z * factor,
        }
    }

    /// Each component over the lane's `divisor` (`Vec3 / f32`: three divisions, not a
    /// reciprocal).
    #[inline(always)]
    pub fn divide(self, divisor: Floats<B>) -> Self {
        Vec3s {
            x: self.x / divisor,
            y: self.y / divisor,
            z: self.z / divisor,
        }
    }

    /// `matrix * v` (glam's `Mat3::mul_vec3`: the columns scaled by `x`, `y`, `z`, summed in
    /// that order).
    #[inline(always)]
    pub fn transformed_by(self, matrix: Mat3) -> Self {
        let column = |axis: Vec3, factor: Floats<B>| Vec3s::splat(axis).scale(factor);
        column(matrix.x_axis, self.x) + column(matrix.y_axis, self.y) + column(matrix.z_axis, self.z)
    }

    /// `Vec3::normalize_or_zero`: times `1 / length` where that is finite and positive.
    #[inline(always)]
    pub fn normalize_or_zero(self) -> Self {
        let reciprocal = Floats::splat(1.0) / self.length();
        let usable = reciprocal.is_finite().and(reciprocal.gt(Floats::splat(0.0)));
        usable.select3(self.scale(reciprocal), Vec3s::splat(Vec3::ZERO))
    }
}

/// One `Vec2` per lane (texture coordinates), stored as two lane arrays.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Vec2s<B = Native> {
    pub x: Floats<B>,
    pub y: Floats<B>,
}

impl<B: Backend> Vec2s<B> {
    /// The lanes from `vectors`.
    #[inline(always)]
    pub fn from_array(vectors: &[Vec2; LANES]) -> Self {
        Vec2s::gather(vectors, |v| *v)
    }

    /// Each lane's `value` of the entry of `items` in that lane (see [`Floats::gather`]).
    #[inline(always)]
    pub fn gather<T>(items: &[T; LANES], value: impl Fn(&T) -> Vec2) -> Self {
        let mut lanes = Vec2s {
            x: Floats::splat(0.0),
            y: Floats::splat(0.0),
        };
        for (lane, item) in items.iter().enumerate() {
            let v = value(item);
            (lanes.x.0[lane], lanes.y.0[lane]) = (v.x, v.y);
        }
        lanes
    }

    /// The same lanes, for backend `C`'s operations.
    #[inline(always)]
    pub fn on<C: Backend>(self) -> Vec2s<C> {
        Vec2s {
            x: self.x.on(),
            y: self.y.on(),
        }
    }

    /// Each component times the lane's `factor` (`Vec2 * f32`).
    #[inline(always)]
    pub fn scale(self, factor: Floats<B>) -> Self {
        Vec2s {
            x: self.x * factor,
            y: self.y * factor,
        }
    }

    /// `Vec2::length`: `sqrt((x·x) + (y·y))`.
    #[inline(always)]
    pub fn length(self) -> Floats<B> {
        (self.x * self.x + self.y * self.y).sqrt()
    }
}

impl<B: Backend> Add for Vec2s<B> {
    type Output = Vec2s<B>;
    #[inline(always)]
    fn add(self, other: Vec2s<B>) -> Vec2s<B> {
        Vec2s {
            x: self.x + other.x,
            y: self.y + other.y,
        }
    }
}

impl<B: Backend> Sub for Vec2s<B> {
    type Output = Vec2s<B>;
    #[inline(always)]
    fn sub(self, other: Vec2s<B>) -> Vec2s<B> {
        Vec2s {
            x: self.x - other.x,
            y: self.y - other.y,
        }
    }
}

/// `i32::wrapping_add` per lane.
impl<B: Backend> Add for Ints<B> {
    type Output = Ints<B>;
    #[inline(always)]
    fn add(self, other: Ints<B>) -> Ints<B> {
        Ints::new(B::add_ints(self.0, other.0))
    }
}

/// `i32::wrapping_sub` per lane.
impl<B: Backend> Sub for Ints<B> {
    type Output = Ints<B>;
    #[inline(always)]
    fn sub(self, other: Ints<B>) -> Ints<B> {
        Ints::new(B::sub_ints(self.0, other.0))
    }
}

/// `-a`: a sign flip, so `-0.0` stays distinct from `0.0 - 0.0` as in the scalar code.
impl<B: Backend> Neg for Floats<B> {
    type Output = Floats<B>;
    #[inline(always)]
    fn neg(self) -> Floats<B> {
        Floats::new(B::neg(self.0))
    }
}

/// `-v`: each component's sign flipped (see `Floats`' `-`).
impl<B: Backend> Neg for Vec3s<B> {
    type Output = Vec3s<B>;
    #[inline(always)]
    fn neg(self) -> Vec3s<B> {
        Vec3s {
            x: -self.x,
            y: -self.y,
            z: -self.z,
        }
    }
}

impl<B: Backend> Add for Vec3s<B> {
    type Output = Vec3s<B>;
    #[inline(always)]
    fn add(self, other: Vec3s<B>) -> Vec3s<B> {
        Vec3s {
            x: self.x + other.x,
            y: self.y + other.y,
            z: self.z + other.z,
        }
    }
}

impl<B: Backend> Sub for Vec3s<B> {
    type Output = Vec3s<B>;
    #[inline(always)]
    fn sub(self, other: Vec3s<B>) -> Vec3s<B> {
        Vec3s {
            x: self.x - other.x,
            y: self.y - other.y,
            z: self.z - other.z,
        }
    }
}

/// Component by component, as `Vec3 * Vec3`.
impl<B: Backend> Mul for Vec3s<B> {
    type Output = Vec3s<B>;
    #[inline(always)]
    fn mul(self, other: Vec3s<B>) -> Vec3s<B> {
        Vec3s {
            x: self.x * other.x,
            y: self.y * other.y,
            z: self.z * other.z,
        }
    }
}

/// `x` rounded towards zero, as SSE2's conversion to a 32-bit integer and back does it: a whole
/// number for |x| < 2³¹; −2³¹ outside that range and for NaN (the instruction's "indefinite
/// integer"). One `f32` gets the lanes' result this way, on every target.
#[inline(always)]
pub fn truncate(x: f32) -> f32 {
    if x.abs() < 2_147_483_648.0 {
        x as i32 as f32
    } else {
        -2_147_483_648.0
    }
}

/// The operations a formula needs, on one `f32` or on eight lanes, so that one generic function
/// (`render::trig`) gives each lane exactly the bits it gives a single float.
pub trait Real:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Div<Output = Self> + Neg<Output = Self>
{
    /// Where a condition holds: `bool`, or a [`Mask`].
    type Mask: Copy + Not<Output = Self::Mask>;
    fn splat(value: f32) -> Self;
    /// `f32::abs`: the sign bit cleared.
    fn abs(self) -> Self;
    /// Towards zero ([`truncate`]).
    fn trunc(self) -> Self;
    /// `>`: false where either side is NaN.
    fn gt(self, other: Self) -> Self::Mask;
    fn and(a: Self::Mask, b: Self::Mask) -> Self::Mask;
    /// `if_true` where `mask` holds, `if_false` elsewhere.
    fn select(mask: Self::Mask, if_true: Self, if_false: Self) -> Self;
    /// `(e, m)` with `self = 2^e·m`, `m ∈ [1, 2)` and `e` whole, for a positive normal float
    /// (read from its bits: exact).
    fn exponent_and_significand(self) -> (Self, Self);
    /// `2^n` for a whole `n` in [−126, 127], exactly (written into the bits).
    fn exp2_whole(n: Self) -> Self;
}

/// The bits of a float's biased exponent, and of its significand.
const EXPONENT_BITS: i32 = 0x7F80_0000;
const SIGNIFICAND_BITS: i32 = 0x007F_FFFF;
/// The bits of 1.0: the biased exponent 127 alone.
const ONE_BITS: i32 = 0x3F80_0000;
/// 2²³, one unit of the biased exponent in a float's bits.
const EXPONENT_UNIT: f32 = 8_388_608.0;

impl Real for f32 {
    type Mask = bool;

    #[inline(always)]
    fn splat(value: f32) -> Self {
        value
    }

    #[inline(always)]
    fn abs(self) -> Self {
        f32::abs(self)
    }

    #[inline(always)]
    fn trunc(self) -> Self {
        truncate(self)
    }

    #[inline(always)]
    fn gt(self, other: Self) -> bool {
        self > other
    }

    #[inline(always)]
    fn and(a: bool, b: bool) -> bool {
        a && b
    }

    #[inline(always)]
    fn select(mask: bool, if_true: Self, if_false: Self) -> Self {
        if mask { if_true } else { if_false }
    }

    #[inline(always)]
    fn exponent_and_significand(self) -> (Self, Self) {
        let bits = self.to_bits() as i32;
        let exponent = (bits & EXPONENT_BITS) as f32 * (1.0 / EXPONENT_UNIT) - 127.0;
        (
            exponent,
            f32::from_bits(((bits & SIGNIFICAND_BITS) + ONE_BITS) as u32),
        )
    }

    #[inline(always)]
    fn exp2_whole(n: Self) -> Self {
        f32::from_bits(((n + 127.0) * EXPONENT_UNIT) as i32 as u32)
    }
}

impl<B: Backend> Real for Floats<B> {
    type Mask = Mask<B>;

    #[inline(always)]
    fn splat(value: f32) -> Self {
        Floats::splat(value)
    }

    #[inline(always)]
    fn abs(self) -> Self {
        Floats::new(B::abs(self.0))
    }

    #[inline(always)]
    fn trunc(self) -> Self {
        Floats::new(B::trunc(self.0))
    }

    #[inline(always)]
    fn gt(self, other: Self) -> Mask<B> {
        Floats::gt(self, other)
    }

    #[inline(always)]
    fn and(a: Mask<B>, b: Mask<B>) -> Mask<B> {
        a.and(b)
    }

    #[inline(always)]
    fn select(mask: Mask<B>, if_true: Self, if_false: Self) -> Self {
        mask.select(if_true, if_false)
    }

    #[inline(always)]
    fn exponent_and_significand(self) -> (Self, Self) {
        let bits = self.to_bits();
        let exponent = bits.and(Ints::splat(EXPONENT_BITS)).to_floats() * Floats::splat(1.0 / EXPONENT_UNIT)
            - Floats::splat(127.0);
        let significand = bits.and(Ints::splat(SIGNIFICAND_BITS)) + Ints::splat(ONE_BITS);
        (exponent, Floats::from_bits(significand))
    }

    #[inline(always)]
    fn exp2_whole(n: Self) -> Self {
        Floats::from_bits(((n + Floats::splat(127.0)) * Floats::splat(EXPONENT_UNIT)).truncate_to_ints())
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
        let (la, lb): (Vec3s, Vec3s) = (Vec3s::from_array(&a), Vec3s::from_array(&b));
        let dots = la.dot(lb);
        let lengths = la.length();
        let normalized = la.normalize_or_zero().to_array();
        let divided = la.divide(lb.length()).to_array();
        let combined = (la + lb * la - lb).to_array();
        let negated = (-la).to_array();
        let negated_dots = -la.dot(lb);
        let matrix = Mat3::from_cols(a[0], a[7], b[3]);
        let transformed = lb.transformed_by(matrix).to_array();
        let crossed = la.cross(lb).to_array();
        let planar_a = Vec2s::<Native>::gather(&a, |v| v.truncate());
        let planar_b = Vec2s::from_array(&b.map(|v| v.truncate()));
        let planar_lengths = planar_a.length();
        let planar = planar_a + planar_b.scale(Floats::splat(2.0)) - planar_a;
        let zero: Vec3s = Vec3s::from_array(&[
            Vec3::ZERO,
            Vec3::splat(-0.0),
            Vec3::X,
            a[4],
            a[6],
            -Vec3::Z,
            Vec3::NAN,
            a[1],
        ]);
        let (least, most) = (la.x.min(lb.y), la.x.max(lb.y));
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
            assert_eq!(
                negated_dots.0[i].to_bits(),
                (-a[i].dot(b[i])).to_bits(),
                "negated dot, lane {i}"
            );
            assert!(same_bits(transformed[i], matrix * b[i]), "transform, lane {i}");
            assert!(same_bits(crossed[i], a[i].cross(b[i])), "cross, lane {i}");
            let (u, v) = (a[i].truncate(), b[i].truncate());
            assert_eq!(
                planar_lengths.0[i].to_bits(),
                u.length().to_bits(),
                "Vec2 length, lane {i}"
            );
            let combined = (u + v * 2.0 - u).to_array().map(f32::to_bits);
            assert_eq!(
                [planar.x.0[i], planar.y.0[i]].map(f32::to_bits),
                combined,
                "Vec2 arithmetic, lane {i}"
            );
            assert_eq!(
                zero.is_zero().lane(i),
                zero.to_array()[i] == Vec3::ZERO,
                "is_zero, lane {i}"
            );
            assert_eq!(
                least.0[i].to_bits(),
                a[i].x.min(b[i].y).to_bits(),
                "min, lane {i}"
            );
            assert_eq!(most.0[i].to_bits(), a[i].x.max(b[i].y).to_bits(), "max, lane {i}");
        }
    }

    /// Integer lanes wrap as `i32::wrapping_*` does, compare as signed integers, and select
    /// bit for bit; a mask holds in all lanes or not.
    #[test]
    fn integer_lanes_and_masks() {
        let a: Ints = Ints::new([0, -1, i32::MAX, i32::MIN, 7, -8, 1 << 20, 3]);
        let b = Ints::new([1, 1, 1, 1, -7, 8, 12, -3]);
        let mask = a.gt(b);
        for i in 0..LANES {
            assert_eq!((a + b).0[i], a.0[i].wrapping_add(b.0[i]));
            assert_eq!((a - b).0[i], a.0[i].wrapping_sub(b.0[i]));
            assert_eq!(a.and(b).0[i], a.0[i] & b.0[i]);
            assert_eq!(mask.lane(i), a.0[i] > b.0[i]);
            assert_eq!(
                mask.select_ints(a, b).0[i],
                if a.0[i] > b.0[i] { a.0[i] } else { b.0[i] }
            );
            assert_eq!(mask.to_ints().0[i], -i32::from(a.0[i] > b.0[i]));
        }
        assert_eq!(
            Floats::<Native>::splat(1.5).to_bits(),
            Ints::splat(1.5f32.to_bits() as i32)
        );
        assert!(Mask::<Native>::ALL.all() && !mask.all() && !(!Mask::<Native>::ALL).all());
        let items = [3u32, 1, 4, 1, 5, 9, 2, 6];
        assert_eq!(
            Ints::<Native>::gather(&items, |&n| n as i32 * 2).0,
            items.map(|n| n as i32 * 2)
        );
        assert_eq!(
            Floats::<Native>::gather(&items, |&n| n as f32).0,
            items.map(|n| n as f32)
        );
    }

    /// Filling eight `Vec3`s in wide stores and writing lanes straight into an array give the
    /// values, bit for bit, that `[value; 8]` and `to_array` give, on every backend.
    #[test]
    fn filled_and_written_vec3s_equal_the_plain_arrays() {
        let values = [
            Vec3::new(0.25, -1.5, 3.0),
            Vec3::new(f32::NAN, -0.0, f32::INFINITY),
            Vec3::new(f32::MIN_POSITIVE / 2.0, f32::MAX, 1.0e-30),
        ];
        let bits = |vs: &[Vec3; LANES]| vs.map(|v| v.to_array().map(f32::to_bits));
        for value in values {
            let mut out = [Vec3::splat(7.0); LANES];
            fill_vec3s(&mut out, value);
            assert_eq!(bits(&out), bits(&[value; LANES]));
            let mut out = [Vec3::splat(7.0); LANES];
            portable::fill_vec3s(&mut out, value);
            assert_eq!(bits(&out), bits(&[value; LANES]));
        }
        let lanes: Vec3s = Vec3s::from_array(&std::array::from_fn(|i| {
            Vec3::new(i as f32, -(i as f32) * 0.5, values[i % 3].x)
        }));
        let mut out = [Vec3::ZERO; LANES];
        lanes.write_to(&mut out);
        assert_eq!(bits(&out), bits(&lanes.to_array()));
    }

    /// Wide lanes add, compare and convert to `f32` as the scalar operations do, per backend;
    /// whole numbers below 2⁵³ convert as the same `i64` does (ties to even included).
    #[test]
    fn wide_lanes_equal_the_scalar_operations() {
        let whole = [
            0i64,
            -1,
            (1 << 24) + 1,
            -(1 << 40) - 3,
            (1 << 52) + 7,
            3 << 25,
            -(5 << 30) + 1,
            1 << 31,
        ];
        let a: Wides = Wides::new(whole.map(|n| n as f64));
        let b = Wides::new([1.0, -1.0, 0.5, -2e12, 4e15, 3.0, -7.0, 2147483648.0]);
        let (pa, pb) = (a.on::<Portable>(), b.on::<Portable>());
        for (sum, mask, converted) in [
            ((a + b).0, a.gt(b).0, a.to_floats().0),
            ((pa + pb).0, pa.gt(pb).0, pa.to_floats().0),
        ] {
            for (i, &n) in whole.iter().enumerate() {
                assert_eq!(sum[i].to_bits(), (a.0[i] + b.0[i]).to_bits());
                assert_eq!(mask[i] != 0, a.0[i] > b.0[i]);
                assert_eq!(converted[i].to_bits(), (n as f32).to_bits(), "lane {i}");
            }
        }
    }

    /// Which samples show a triangle, per backend, against a plain comparison: every pattern's
    /// sample count, ids repeated in scattered samples, and the empty sample's `u32::MAX`.
    #[test]
    fn samples_showing_sets_the_bits_of_the_equal_ids() {
        fn check<const S: usize>() {
            let ids: [u32; S] =
                std::array::from_fn(|i| [7, u32::MAX, 7, 3, 0, 3, 3, u32::MAX][(i * 5 + i / 3) % 8]);
            for id in [7, u32::MAX, 3, 0, 12] {
                let expected = (0..S)
                    .filter(|&i| ids[i] == id)
                    .fold(0, |mask, i| mask | (1 << i));
                assert_eq!(samples_showing(&ids, id), expected, "{S} samples, id {id}");
                assert_eq!(
                    portable::samples_showing(&ids, id),
                    expected,
                    "{S} samples, id {id}"
                );
            }
        }
        check::<2>();
        check::<4>();
        check::<8>();
        check::<16>();
    }

    /// Coverage flags and counts, per backend, against a plain comparison: every number of
    /// shown lanes, in scattered places, with ids that agree with `none` in their low or
    /// high halves only (so a narrower compare would be caught).
    #[test]
    fn mark_shown_flags_and_counts_the_lanes_that_name_a_triangle() {
        let none = u32::MAX;
        for pattern in 0..=u8::MAX {
            let ids: [u32; LANES] = std::array::from_fn(|lane| {
                if pattern & (1 << lane) == 0 {
                    none
                } else {
                    [0, 0xffff, 0xffff_0000, 0x7fff_ffff, 5][lane % 5]
                }
            });
            let expected: [bool; LANES] = std::array::from_fn(|lane| pattern & (1 << lane) != 0);
            for mark in [mark_shown, portable::mark_shown] {
                let mut shown = expected.map(|lane| !lane);
                let count = mark(&ids, none, &mut shown);
                assert_eq!(shown, expected, "pattern {pattern:08b}");
                assert_eq!(count, pattern.count_ones() as usize, "pattern {pattern:08b}");
            }
        }
    }

    /// The backend in use against the portable loops, operation by operation, on awkward
    /// inputs (NaN lanes included: the same NaN bits too).
    #[test]
    fn the_backend_equals_the_portable_loops_bit_for_bit() {
        let a = vectors();
        let mut b = vectors();
        b.rotate_left(5);
        let (la, lb) = (Vec3s::from_array(&a), Vec3s::from_array(&b));
        let bits = |f: Floats| f.0.map(f32::to_bits);
        let portable_bits = |f: Floats<Portable>| f.0.map(f32::to_bits);
        for (x, y) in [
            (la.x, lb.x),
            (la.y, lb.y),
            (la.z, lb.z),
            (la.x, la.y),
            (lb.z, la.x),
        ] {
            let (px, py) = (x.on::<Portable>(), y.on::<Portable>());
            assert_eq!(bits(x + y), portable_bits(px + py), "add");
            assert_eq!(bits(x - y), portable_bits(px - py), "sub");
            assert_eq!(bits(x * y), portable_bits(px * py), "mul");
            assert_eq!(bits(x / y), portable_bits(px / py), "div");
            assert_eq!(bits(x.sqrt()), portable_bits(px.sqrt()), "sqrt");
            assert_eq!(bits(Real::trunc(x)), portable_bits(Real::trunc(px)), "trunc");
            assert_eq!(
                x.truncate_to_ints().0,
                px.truncate_to_ints().0,
                "truncate_to_ints"
            );
            assert_eq!(x.gt(y).0, px.gt(py).0, "gt");
            assert_eq!(x.le(y).0, px.le(py).0, "le");
            assert_eq!(x.eq(y).0, px.eq(py).0, "eq");
            assert_eq!(x.eq(x).0, px.eq(px).0, "eq");
            assert_eq!(x.is_finite().0, px.is_finite().0, "is_finite");
            let (m, n) = (x.gt(y), y.is_finite());
            let (pm, pn) = (m.on::<Portable>(), n.on::<Portable>());
            assert_eq!(m.and(n).0, pm.and(pn).0, "and");
            assert_eq!(m.or(n).0, pm.or(pn).0, "or");
            assert_eq!(m.any(), pm.any(), "any");
            assert_eq!(bits(m.select(x, y)), portable_bits(pm.select(px, py)), "select");
            let (i, j) = (x.to_bits(), y.to_bits());
            let (pi, pj) = (i.on::<Portable>(), j.on::<Portable>());
            assert_eq!((i + j).0, (pi + pj).0, "add_ints");
            assert_eq!((i - j).0, (pi - pj).0, "sub_ints");
            assert_eq!(i.and(j).0, pi.and(pj).0, "and_ints");
            assert_eq!(i.wrapping_mul(j).0, pi.wrapping_mul(pj).0, "mul_ints");
            assert_eq!(i.gt(j).0, pi.gt(pj).0, "gt_ints");
            let partly_i = Ints::new(std::array::from_fn(|lane| {
                if lane % 3 == 0 { i.0[lane] } else { j.0[lane] }
            }));
            assert_eq!(i.eq(partly_i).0, pi.eq(partly_i.on()).0, "eq_ints");
            assert_eq!(bits(i.to_floats()), portable_bits(pi.to_floats()), "to_floats");
        }
    }

    /// Every backend operation run by `run_widest` (on the AVX backend where the processor has
    /// AVX2) has the native backend's bits and the portable loops', on awkward inputs (NaN
    /// lanes included), and so does a formula of them.
    #[test]
    fn the_widest_lanes_equal_the_native_backend_bit_for_bit() {
        struct EveryOperation(Vec3s, Vec3s);
        impl LaneWork for EveryOperation {
            type Output = Vec<[u32; LANES]>;
            fn run<B: Backend>(self) -> Self::Output {
                let (a, b) = (self.0.on::<B>(), self.1.on::<B>());
                let mut results = Vec::new();
                for (x, y) in [(a.x, b.x), (a.y, b.y), (a.z, b.z), (a.x, a.y), (b.z, a.x)] {
                    let (m, n) = (x.gt(y), y.is_finite());
                    let floats = [
                        x + y,
                        x - y,
                        x * y,
                        x / y,
                        x.sqrt(),
                        -x,
                        Real::abs(x),
                        Real::trunc(x),
                        m.select(x, y),
                    ];
                    let masks = [m, x.le(y), x.eq(y), x.eq(x), n, m.and(n), m.or(n), !m];
                    results.extend(floats.map(|f| f.0.map(f32::to_bits)));
                    results.extend(masks.map(|m| m.0));
                    results.push([u32::from(m.any()), u32::from(m.and(!m).any()), 0, 0, 0, 0, 0, 0]);
                    // Integer lanes: the bits of one side against the other truncated.
                    let (i, j) = (x.to_bits(), y.truncate_to_ints());
                    let ints = [
                        i + j,
                        i - j,
                        i.and(j),
                        i.wrapping_mul(j),
                        m.select_ints(i, j),
                        i.gt(j).to_ints(),
                        i.eq(i).to_ints(),
                    ];
                    results.extend(ints.map(|lanes| lanes.0.map(|lane| lane as u32)));
                    results.extend([i.to_floats(), j.to_floats()].map(|f| f.0.map(f32::to_bits)));
                    // `f64` lanes, some of them not held by `f32` (each side scaled off its grid).
                    let (u, v) = (
                        Wides::<B>::new(x.0.map(|x| f64::from(x) * (1.0 + f64::EPSILON * 3.0))),
                        Wides::<B>::new(y.0.map(|y| f64::from(y) * 1_000_003.0)),
                    );
                    results.extend([u + v, v + u, u].map(|w| w.to_floats().0.map(f32::to_bits)));
                    results.extend([u.gt(v), v.gt(u), u.gt(u)].map(|m| m.0));
                    // Loads to blend: a group, a group as integers, two rows of half a group.
                    let bits = x.0.map(f32::to_bits);
                    let rows: Vec<u32> = bits.iter().chain(&y.0.map(f32::to_bits)).copied().collect();
                    results.push(Floats::<B>::load_to_blend(&x.0).0.map(f32::to_bits));
                    results.push(Ints::<B>::load_to_blend(&bits).0.map(|lane| lane as u32));
                    results.push(load_rows_to_blend::<B, LANES>(&rows, 3, 0));
                    results.push(load_rows_to_blend::<B, { LANES / 2 }>(&rows, 1, 9));
                }
                let normal = a.normalize_or_zero();
                let d = normal.dot(b).max(Floats::splat(0.0)) / b.length();
                let keep = d.gt(Floats::splat(0.25)).or(a.x.is_finite());
                let c = keep.select3(a.cross(b) - b.scale(d), -a);
                results.extend([d, c.x, c.y, c.z].map(|f| f.0.map(f32::to_bits)));
                results
            }
        }
        let a = vectors();
        let mut b = vectors();
        b.rotate_left(3);
        let every = || EveryOperation(Vec3s::from_array(&a), Vec3s::from_array(&b));
        let native = every().run::<Native>();
        assert_eq!(run_widest(every()), native);
        assert_eq!(every().run::<Portable>(), native);
    }

    #[test]
    fn truncation_is_the_same_for_lanes_and_one_float() {
        let edges = [
            [
                2.5f32,
                -2.5,
                0.999_999_94,
                -0.0,
                2_147_483_520.0,
                -2_147_483_648.0,
                2_147_483_648.0,
                -3e9,
            ],
            [
                f32::NAN,
                f32::INFINITY,
                f32::NEG_INFINITY,
                1e-45,
                16_777_217.0,
                -7.9,
                123_456.7,
                0.5,
            ],
        ];
        for values in edges {
            let truncated: Floats = Real::trunc(Floats::new(values));
            let integers = Floats::<Native>::new(values).truncate_to_ints();
            for (lane, &x) in values.iter().enumerate() {
                assert_eq!(truncated.0[lane].to_bits(), truncate(x).to_bits(), "{x}");
                assert_eq!(integers.0[lane] as f32, truncate(x), "{x}");
                if x.abs() < 2_147_483_648.0 {
                    assert_eq!(truncate(x), x.trunc(), "{x}");
                }
            }
            assert_eq!(
                Real::trunc(Floats::<Portable>::new(values)).0.map(f32::to_bits),
                truncated.0.map(f32::to_bits)
            );
        }
        assert_eq!(truncate(f32::NAN), -2_147_483_648.0);
        assert_eq!(truncate(3e9), -2_147_483_648.0);
    }

    #[test]
    fn select_takes_each_lane_from_the_side_its_mask_names() {
        let mask: Mask = Mask::from_bools(std::array::from_fn(|i| i % 3 == 0));
        let picked = mask.select(Floats::splat(1.0), Floats::splat(2.0));
        for i in 0..LANES {
            assert_eq!(picked.0[i], if i % 3 == 0 { 1.0 } else { 2.0 });
        }
        assert!(mask.any() && !(!Mask::<Native>::ALL).any());
        assert!((0..LANES).all(|i| mask.lane(i) == (i % 3 == 0)));
        assert_eq!((!mask).or(mask), Mask::ALL);
        assert_eq!((!mask).and(mask), !Mask::ALL);
        let finite: Floats = Floats::new([
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
