//! e^x over [`Lanes`], from the exactly rounded operations alone, so that every backend and
//! the scalar reference (the same function on [`Portable`](super::Portable)) give the same
//! bits. Within 2 ulp of the correctly rounded e^x on [−708, 709] (tested against the
//! platform's `exp`), and NaN gives NaN. Callers keep x within that range (the radar
//! equation's arguments lie in [−690.8, 0]); no clamp is spent on every value.
//!
//! x = k ln 2 + r with k = round(x / ln 2) and |r| ≤ ln 2 / 2 (Cody and Waite's two-part
//! ln 2, so that k ln 2 is exact), e^r by its Taylor series to degree 13 (the remainder is
//! below 4e-18 relative) summed by Estrin's scheme, and 2^k from its bits.

use super::Lanes;

const LOG2_E: f64 = std::f64::consts::LOG2_E;
/// ln 2 in two parts: the first has its last 11 bits zero, so k · LN2_HI is exact for |k| < 2¹¹.
const LN2_HI: f64 = f64::from_bits(0x3FE6_2E42_FEE0_0000);
const LN2_LO: f64 = f64::from_bits(0x3DEA_39EF_3579_3C76);
/// 1.5 · 2⁵²: adding it rounds a double below 2⁵¹ in magnitude to an integer (ties to even).
const SHIFTER: f64 = 6_755_399_441_055_744.0;

/// 2⁵² + 1023: added to an integer k in −1022..=1023, the sum's low mantissa bits are k + 1023.
const BIAS: f64 = 4_503_599_627_371_519.0;

/// 1/j! for j = 0..=13.
const TAYLOR: [f64; 14] = {
    let mut c = [1.0; 14];
    let mut j = 1;
    while j < 14 {
        c[j] = c[j - 1] / j as f64;
        j += 1;
    }
    c
};

/// e^x, lane by lane, for x within [−708, 709] or NaN (see the module docs); callers bound
/// their arguments (outside, 2^k's bits would wrap).
#[inline(always)]
pub fn exp<L: Lanes>(x: L) -> L {
    let kf = (x * L::splat(LOG2_E) + L::splat(SHIFTER)) - L::splat(SHIFTER);
    let r = (x - kf * L::splat(LN2_HI)) - kf * L::splat(LN2_LO);
    // Estrin's scheme: pairs, then quads and eights combined with r², r⁴ and r⁸, so that
    // the chain of dependent operations is 8 long, not Horner's 26.
    let c = |j: usize| L::splat(TAYLOR[j]);
    let (r2, pair) = (r * r, |j: usize| c(j) + c(j + 1) * r);
    let r4 = r2 * r2;
    let low = (pair(0) + pair(2) * r2) + (pair(4) + pair(6) * r2) * r4;
    let high = (pair(8) + pair(10) * r2) + pair(12) * r4;
    let p = low + high * (r4 * r4);
    // 2^k from the bits of kf + (2⁵² + 1023), whose low bits hold k + 1023 (in 1..=2046
    // for x in range; NaN stays NaN in p whatever its scale).
    p * (kf + L::splat(BIAS)).shift_to_exponent()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::simd::{Backend, LaneKernel, Portable};

    fn ulps(a: f64, b: f64) -> u64 {
        (a.to_bits() as i64 - b.to_bits() as i64).unsigned_abs()
    }

    #[test]
    fn the_two_parts_of_ln2_are_ln2() {
        assert_eq!(LN2_HI + LN2_LO, std::f64::consts::LN_2);
        assert_eq!(LN2_HI.to_bits() & 0x7ff, 0); // its last 11 bits are zero
    }

    #[test]
    fn within_two_ulp_of_the_platforms_exp() {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut worst = 0;
        for i in 0..400_000 {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let u = (state >> 11) as f64 / (1u64 << 53) as f64;
            let x = if i % 2 == 0 {
                -708.0 + 1417.0 * u
            } else {
                -1.0 + 2.0 * u
            };
            let got = exp(Portable::splat(x)).to_array()[0];
            worst = worst.max(ulps(got, x.exp()));
        }
        assert!(worst <= 2, "{worst} ulp");
        for x in [0.0, -0.0, 1.0, -1.0, std::f64::consts::LN_2, -690.0] {
            assert!(ulps(exp(Portable::splat(x)).to_array()[0], x.exp()) <= 1, "{x}");
        }
        assert_eq!(exp(Portable::splat(0.0)).to_array()[0], 1.0);
        assert!(exp(Portable::splat(f64::NAN)).to_array()[0].is_nan());
    }

    struct Exp([f64; 4]);
    impl LaneKernel for Exp {
        type Output = [f64; 4];
        #[inline(always)]
        fn run<L: Lanes>(self) -> [f64; 4] {
            exp(L::from_array(self.0)).to_array()
        }
    }

    #[test]
    fn every_backend_gives_the_portable_bits() {
        let inputs = [
            [-700.5, -0.3, 0.0, 12.25],
            [-1e-9, f64::NAN, -708.0, 709.0],
            [-37.0, -1.5, 1e-300, -0.0],
        ];
        for backend in [Backend::Portable, Backend::Avx2].into_iter().filter(|b| b.available()) {
            for x in inputs {
                let got = crate::simd::run_on(backend, Exp(x));
                let want = exp(Portable::from_array(x)).to_array();
                assert_eq!(got.map(f64::to_bits), want.map(f64::to_bits), "{backend:?}");
            }
        }
    }
}
