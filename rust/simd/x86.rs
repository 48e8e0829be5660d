//! The AVX2 build of [`Lanes`](super::Lanes). Its values exist only inside [`run_avx2`],
//! which is entered only after the CPU was found to have AVX2; every method is inlined
//! into that function. The module is private to the crate (so are the generic lane
//! functions of the factor types), so code outside it has no way to make an `Avx2` value.

use super::{LaneKernel, Lanes};
use std::arch::x86_64::*;
use std::ops::{Add, Mul, Sub};

#[derive(Debug, Clone, Copy)]
pub(crate) struct Avx2(__m256d);

/// A lane mask: all bits set where the condition holds.
#[derive(Debug, Clone, Copy)]
pub struct Mask(__m256d);

/// # Safety
/// The CPU must have AVX2.
#[target_feature(enable = "avx2")]
pub(super) unsafe fn run_avx2<K: LaneKernel>(kernel: K) -> K::Output {
    kernel.run::<Avx2>()
}

// SAFETY (every `unsafe` below): an `Avx2` or `Mask` value is only made inside
// `run_avx2`, so AVX2 is present whenever these run; loads and stores go through
// slices whose length is checked first.
impl Add for Avx2 {
    type Output = Self;
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        Avx2(unsafe { _mm256_add_pd(self.0, o.0) })
    }
}

impl Sub for Avx2 {
    type Output = Self;
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        Avx2(unsafe { _mm256_sub_pd(self.0, o.0) })
    }
}

impl Mul for Avx2 {
    type Output = Self;
    #[inline(always)]
    fn mul(self, o: Self) -> Self {
        Avx2(unsafe { _mm256_mul_pd(self.0, o.0) })
    }
}

impl Avx2 {
    #[inline(always)]
    fn cmp<const P: i32>(self, o: Self) -> Mask {
        Mask(unsafe { _mm256_cmp_pd::<P>(self.0, o.0) })
    }
}

impl Lanes for Avx2 {
    type Mask = Mask;

    #[inline(always)]
    fn splat(v: f64) -> Self {
        Avx2(unsafe { _mm256_set1_pd(v) })
    }
    #[inline(always)]
    fn from_array(a: [f64; 4]) -> Self {
        // Built from registers: a vector load of four scalar stores would stall on
        // store forwarding.
        Avx2(unsafe { _mm256_set_pd(a[3], a[2], a[1], a[0]) })
    }
    #[inline(always)]
    fn to_array(self) -> [f64; 4] {
        let mut a = [0.0; 4];
        unsafe { _mm256_storeu_pd(a.as_mut_ptr(), self.0) };
        a
    }
    #[inline(always)]
    fn load(s: &[f64]) -> Self {
        let s = &s[..4];
        Avx2(unsafe { _mm256_loadu_pd(s.as_ptr()) })
    }
    #[inline(always)]
    fn store(self, s: &mut [f64]) {
        let s = &mut s[..4];
        unsafe { _mm256_storeu_pd(s.as_mut_ptr(), self.0) }
    }
    #[inline(always)]
    fn rows4_columns02(rows: &[f64]) -> (Self, Self) {
        let r = &rows[..16];
        unsafe {
            let (a, b) = (_mm256_loadu_pd(r.as_ptr()), _mm256_loadu_pd(r[4..].as_ptr()));
            let (c, d) = (_mm256_loadu_pd(r[8..].as_ptr()), _mm256_loadu_pd(r[12..].as_ptr()));
            // [x0, x1, y0, y1] and [x2, x3, y2, y3], then the 128-bit halves regrouped.
            let (ab, cd) = (_mm256_unpacklo_pd(a, b), _mm256_unpacklo_pd(c, d));
            (
                Avx2(_mm256_permute2f128_pd::<0x20>(ab, cd)),
                Avx2(_mm256_permute2f128_pd::<0x31>(ab, cd)),
            )
        }
    }
    #[inline(always)]
    fn rows4_columns13(rows: &[f64]) -> (Self, Self) {
        let r = &rows[..16];
        unsafe {
            let (a, b) = (_mm256_loadu_pd(r.as_ptr()), _mm256_loadu_pd(r[4..].as_ptr()));
            let (c, d) = (_mm256_loadu_pd(r[8..].as_ptr()), _mm256_loadu_pd(r[12..].as_ptr()));
            // [vx0, vx1, vy0, vy1] and [vx2, vx3, vy2, vy3], then the halves regrouped.
            let (ab, cd) = (_mm256_unpackhi_pd(a, b), _mm256_unpackhi_pd(c, d));
            (
                Avx2(_mm256_permute2f128_pd::<0x20>(ab, cd)),
                Avx2(_mm256_permute2f128_pd::<0x31>(ab, cd)),
            )
        }
    }
    #[inline(always)]
    fn rows4_columns024(rows: &[f64]) -> (Self, Self, Self) {
        let r = &rows[..24];
        unsafe {
            let load = |i: usize| _mm256_loadu_pd(r[i..].as_ptr());
            // Rows 0–1 are [x0 vx0 y0 vy0] [z0 vz0 x1 vx1] [y1 vy1 z1 vz1] (a, b, c), rows 2–3
            // the same (d, e, f): halves regrouped, then the even entries interleaved.
            let (a, b, c, d, e, f) = (load(0), load(4), load(8), load(12), load(16), load(20));
            let (ad_lo, ad_hi) = (
                _mm256_permute2f128_pd::<0x20>(a, d),
                _mm256_permute2f128_pd::<0x31>(a, d),
            );
            let (be_lo, be_hi) = (
                _mm256_permute2f128_pd::<0x20>(b, e),
                _mm256_permute2f128_pd::<0x31>(b, e),
            );
            let (cf_lo, cf_hi) = (
                _mm256_permute2f128_pd::<0x20>(c, f),
                _mm256_permute2f128_pd::<0x31>(c, f),
            );
            (
                Avx2(_mm256_unpacklo_pd(ad_lo, be_hi)),
                Avx2(_mm256_unpacklo_pd(ad_hi, cf_lo)),
                Avx2(_mm256_unpacklo_pd(be_lo, cf_hi)),
            )
        }
    }
    #[inline(always)]
    fn pairs(xy: &[f64]) -> (Self, Self) {
        let p = &xy[..8];
        unsafe {
            let (a, b) = (_mm256_loadu_pd(p.as_ptr()), _mm256_loadu_pd(p[4..].as_ptr()));
            // [x0, y0, x2, y2] and [x1, y1, x3, y3], then interleaved.
            let (even, odd) = (
                _mm256_permute2f128_pd::<0x20>(a, b),
                _mm256_permute2f128_pd::<0x31>(a, b),
            );
            (Avx2(_mm256_unpacklo_pd(even, odd)), Avx2(_mm256_unpackhi_pd(even, odd)))
        }
    }
    #[inline(always)]
    fn triples(xyz: &[f64]) -> (Self, Self, Self) {
        let p = &xyz[..12];
        unsafe {
            // Pairs of 128-bit halves: [x0 y0 | x2 y2], [z0 x1 | z2 x3], [y1 z1 | y3 z3] (each
            // upper half inserted from memory), then every value picked by one shuffle.
            let half = |i: usize| _mm_loadu_pd(p[i..].as_ptr());
            let (a, b, c) = (
                _mm256_set_m128d(half(6), half(0)),
                _mm256_set_m128d(half(8), half(2)),
                _mm256_set_m128d(half(10), half(4)),
            );
            (
                Avx2(_mm256_shuffle_pd::<0b1010>(a, b)),
                Avx2(_mm256_shuffle_pd::<0b0101>(a, c)),
                Avx2(_mm256_shuffle_pd::<0b1010>(b, c)),
            )
        }
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        Avx2(unsafe { _mm256_sqrt_pd(self.0) })
    }
    #[inline(always)]
    fn div(self, o: Self) -> Self {
        Avx2(unsafe { _mm256_div_pd(self.0, o.0) })
    }
    #[inline(always)]
    fn abs(self) -> Self {
        Avx2(unsafe { _mm256_andnot_pd(_mm256_set1_pd(-0.0), self.0) })
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        // vmaxpd returns its second operand unless the first is greater, as `Portable`.
        Avx2(unsafe { _mm256_max_pd(self.0, o.0) })
    }
    #[inline(always)]
    fn shift_to_exponent(self) -> Self {
        Avx2(unsafe { _mm256_castsi256_pd(_mm256_slli_epi64::<52>(_mm256_castpd_si256(self.0))) })
    }
    #[inline(always)]
    fn gt(self, o: Self) -> Mask {
        self.cmp::<_CMP_GT_OQ>(o)
    }
    #[inline(always)]
    fn ge(self, o: Self) -> Mask {
        self.cmp::<_CMP_GE_OQ>(o)
    }
    #[inline(always)]
    fn lt(self, o: Self) -> Mask {
        self.cmp::<_CMP_LT_OQ>(o)
    }
    #[inline(always)]
    fn le(self, o: Self) -> Mask {
        self.cmp::<_CMP_LE_OQ>(o)
    }
    #[inline(always)]
    fn is_nan(self) -> Mask {
        self.cmp::<_CMP_UNORD_Q>(self)
    }
    #[inline(always)]
    fn non_finite(self) -> Mask {
        // The exponent bits alone equal +inf's bits exactly when all are set.
        let inf = Self::splat(f64::INFINITY);
        Avx2(unsafe { _mm256_and_pd(self.0, inf.0) }).cmp::<_CMP_EQ_OQ>(inf)
    }
    #[inline(always)]
    fn and(a: Mask, b: Mask) -> Mask {
        Mask(unsafe { _mm256_and_pd(a.0, b.0) })
    }
    #[inline(always)]
    fn or(a: Mask, b: Mask) -> Mask {
        Mask(unsafe { _mm256_or_pd(a.0, b.0) })
    }
    #[inline(always)]
    fn none() -> Mask {
        Mask(unsafe { _mm256_setzero_pd() })
    }
    #[inline(always)]
    fn any(m: Mask) -> bool {
        unsafe { _mm256_movemask_pd(m.0) != 0 }
    }
    #[inline(always)]
    fn select(m: Mask, a: Self, b: Self) -> Self {
        Avx2(unsafe { _mm256_blendv_pd(b.0, a.0, m.0) })
    }
}
