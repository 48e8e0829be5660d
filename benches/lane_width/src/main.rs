//! How fast can a lone radar-equation (Swerling 1, one pulse) or horizon factor go on one
//! core, at 4 lanes (AVX2, as the library) and at 8 (AVX-512F), with the operations the
//! library allows (exactly rounded, no FMA) and its algorithm (r² from [x, vx, y, vy] rows;
//! 1/(1 + S) = r⁴/(r⁴ + c); e^x by Cody–Waite and a 13th-degree Taylor polynomial)?
//! Minimum over 2 000 passes of 10⁴ states in cache, one thread: the floor a call can
//! approach, without the binding's or the thread pool's costs. The two widths' results are
//! asserted equal, bit for bit. docs/benchmarks.md compares these floors with NumPy's times.
//!
//! Needs an x86-64 CPU with AVX2 and AVX-512F.
use ctxmodels::radar::{RadarEquation, Swerling};
use std::arch::x86_64::*;
use std::time::Instant;
const LOG2_E: f64 = std::f64::consts::LOG2_E;
const LN2_HI: f64 = f64::from_bits(0x3FE6_2E42_FEE0_0000);
const LN2_LO: f64 = f64::from_bits(0x3DEA_39EF_3579_3C76);
const SHIFTER: f64 = 6_755_399_441_055_744.0;
const BIAS: f64 = 4_503_599_627_371_519.0;
const TAYLOR: [f64; 14] = {
    let mut c = [1.0; 14];
    let mut j = 1;
    while j < 14 {
        c[j] = c[j - 1] / j as f64;
        j += 1;
    }
    c
};

macro_rules! exp_body {
    ($x:expr, $s:ident, $add:ident, $sub:ident, $mul:ident, $shift:expr) => {{
        let x = $x;
        let kf = $sub($add($mul(x, $s(LOG2_E)), $s(SHIFTER)), $s(SHIFTER));
        let r = $sub($sub(x, $mul(kf, $s(LN2_HI))), $mul(kf, $s(LN2_LO)));
        let c = |j: usize| $s(TAYLOR[j]);
        let r2 = $mul(r, r);
        let pair = |j: usize| $add(c(j), $mul(c(j + 1), r));
        let r4 = $mul(r2, r2);
        let low = $add(
            $add(pair(0), $mul(pair(2), r2)),
            $mul($add(pair(4), $mul(pair(6), r2)), r4),
        );
        let high = $add($add(pair(8), $mul(pair(10), r2)), $mul(pair(12), r4));
        let p = $add(low, $mul(high, $mul(r4, r4)));
        $mul(p, $shift($add(kf, $s(BIAS))))
    }};
}

#[inline(always)]
unsafe fn s4(v: f64) -> __m256d {
    _mm256_set1_pd(v)
}
#[inline(always)]
unsafe fn a4(a: __m256d, b: __m256d) -> __m256d {
    _mm256_add_pd(a, b)
}
#[inline(always)]
unsafe fn b4(a: __m256d, b: __m256d) -> __m256d {
    _mm256_sub_pd(a, b)
}
#[inline(always)]
unsafe fn m4(a: __m256d, b: __m256d) -> __m256d {
    _mm256_mul_pd(a, b)
}
#[inline(always)]
unsafe fn sh4(a: __m256d) -> __m256d {
    _mm256_castsi256_pd(_mm256_slli_epi64::<52>(_mm256_castpd_si256(a)))
}
#[inline(always)]
unsafe fn s8(v: f64) -> __m512d {
    _mm512_set1_pd(v)
}
#[inline(always)]
unsafe fn a8(a: __m512d, b: __m512d) -> __m512d {
    _mm512_add_pd(a, b)
}
#[inline(always)]
unsafe fn b8(a: __m512d, b: __m512d) -> __m512d {
    _mm512_sub_pd(a, b)
}
#[inline(always)]
unsafe fn m8(a: __m512d, b: __m512d) -> __m512d {
    _mm512_mul_pd(a, b)
}
#[inline(always)]
unsafe fn sh8(a: __m512d) -> __m512d {
    _mm512_castsi512_pd(_mm512_slli_epi64::<52>(_mm512_castpd_si512(a)))
}

#[inline(always)]
unsafe fn xy4(r: *const f64) -> (__m256d, __m256d) {
    let (a, b) = (_mm256_loadu_pd(r), _mm256_loadu_pd(r.add(4)));
    let (c, d) = (_mm256_loadu_pd(r.add(8)), _mm256_loadu_pd(r.add(12)));
    let (ab, cd) = (_mm256_unpacklo_pd(a, b), _mm256_unpacklo_pd(c, d));
    (
        _mm256_permute2f128_pd::<0x20>(ab, cd),
        _mm256_permute2f128_pd::<0x31>(ab, cd),
    )
}
#[inline(always)]
unsafe fn xy8(r: *const f64) -> (__m512d, __m512d) {
    // four zmm of two rows each (x at 0 and 4): a two-source permute gathers four x and four y,
    // then 256-bit halves are paired
    let (a, b, c, d) = (
        _mm512_loadu_pd(r),
        _mm512_loadu_pd(r.add(8)),
        _mm512_loadu_pd(r.add(16)),
        _mm512_loadu_pd(r.add(24)),
    );
    let ix = _mm512_set_epi64(14, 10, 6, 2, 12, 8, 4, 0); // from (a, b): x0..x3 then y0..y3
    let ab = _mm512_permutex2var_pd(a, ix, b); // [x0 x1 x2 x3 y0 y1 y2 y3]
    let cd = _mm512_permutex2var_pd(c, ix, d); // [x4.. x7 y4.. y7]
    let x = _mm512_shuffle_f64x2::<0b01_00_01_00>(ab, cd);
    let y = _mm512_shuffle_f64x2::<0b11_10_11_10>(ab, cd);
    (x, y)
}

#[target_feature(enable = "avx2")]
unsafe fn sw1_4(rows: &[f64], out: &mut [f64], c: f64, t: f64) -> bool {
    let mut bad = _mm256_setzero_pd();
    for (j, o) in out.chunks_exact_mut(4).enumerate() {
        let (x, y) = xy4(rows.as_ptr().add(16 * j));
        let r2 = a4(m4(x, x), m4(y, y));
        let r4 = m4(r2, r2);
        let near = _mm256_blendv_pd(
            _mm256_div_pd(r4, a4(r4, s4(c))),
            s4(1.0),
            _mm256_cmp_pd::<_CMP_GT_OQ>(r4, s4(f64::MAX)),
        );
        let q = m4(s4(t), near);
        let e = exp_body!(b4(s4(0.0), q), s4, a4, b4, m4, sh4);
        bad = _mm256_or_pd(
            bad,
            _mm256_cmp_pd::<_CMP_EQ_OQ>(_mm256_and_pd(r2, s4(f64::INFINITY)), s4(f64::INFINITY)),
        );
        _mm256_storeu_pd(o.as_mut_ptr(), e);
    }
    _mm256_movemask_pd(bad) != 0
}
#[target_feature(enable = "avx512f")]
unsafe fn sw1_8(rows: &[f64], out: &mut [f64], c: f64, t: f64) -> bool {
    let mut bad: __mmask8 = 0;
    for (j, o) in out.chunks_exact_mut(8).enumerate() {
        let (x, y) = xy8(rows.as_ptr().add(32 * j));
        let r2 = a8(m8(x, x), m8(y, y));
        let r4 = m8(r2, r2);
        let over = _mm512_cmp_pd_mask::<_CMP_GT_OQ>(r4, s8(f64::MAX));
        let near = _mm512_mask_blend_pd(over, _mm512_div_pd(r4, a8(r4, s8(c))), s8(1.0));
        let q = m8(s8(t), near);
        let e = exp_body!(b8(s8(0.0), q), s8, a8, b8, m8, sh8);
        bad |= _mm512_cmp_pd_mask::<_CMP_EQ_OQ>(
            _mm512_castsi512_pd(_mm512_and_si512(
                _mm512_castpd_si512(r2),
                _mm512_castpd_si512(s8(f64::INFINITY)),
            )),
            s8(f64::INFINITY),
        );
        _mm512_storeu_pd(o.as_mut_ptr(), e);
    }
    bad != 0
}
#[target_feature(enable = "avx2")]
unsafe fn hz_4(rows: &[f64], out: &mut [f64], d2: f64) -> bool {
    let mut bad = _mm256_setzero_pd();
    for (j, o) in out.chunks_exact_mut(4).enumerate() {
        let (x, y) = xy4(rows.as_ptr().add(16 * j));
        let r2 = a4(m4(x, x), m4(y, y));
        let v = _mm256_blendv_pd(s4(0.0), s4(1.0), _mm256_cmp_pd::<_CMP_LE_OQ>(r2, s4(d2)));
        bad = _mm256_or_pd(
            bad,
            _mm256_cmp_pd::<_CMP_EQ_OQ>(_mm256_and_pd(r2, s4(f64::INFINITY)), s4(f64::INFINITY)),
        );
        _mm256_storeu_pd(o.as_mut_ptr(), v);
    }
    _mm256_movemask_pd(bad) != 0
}
#[target_feature(enable = "avx512f")]
unsafe fn hz_8(rows: &[f64], out: &mut [f64], d2: f64) -> bool {
    let mut bad: __mmask8 = 0;
    for (j, o) in out.chunks_exact_mut(8).enumerate() {
        let (x, y) = xy8(rows.as_ptr().add(32 * j));
        let r2 = a8(m8(x, x), m8(y, y));
        let inside = _mm512_cmp_pd_mask::<_CMP_LE_OQ>(r2, s8(d2));
        let v = _mm512_mask_blend_pd(inside, s8(0.0), s8(1.0));
        bad |= _mm512_cmp_pd_mask::<_CMP_EQ_OQ>(
            _mm512_castsi512_pd(_mm512_and_si512(
                _mm512_castpd_si512(r2),
                _mm512_castpd_si512(s8(f64::INFINITY)),
            )),
            s8(f64::INFINITY),
        );
        _mm512_storeu_pd(o.as_mut_ptr(), v);
    }
    bad != 0
}

fn main() {
    assert!(
        is_x86_feature_detected!("avx2") && is_x86_feature_detected!("avx512f"),
        "this measurement needs AVX2 and AVX-512F"
    );
    let n = 10_000;
    let rows: Vec<f64> = (0..4 * n).map(|i| ((i * 7919) % 9001) as f64 - 4500.0).collect();
    let (c, t, d2) = (10f64.powf(1.3) * 1500f64.powi(4), -(1e-6f64).ln(), 3000.0 * 3000.0);
    let (mut o4, mut o8) = (vec![0.0; n], vec![0.0; n]);
    unsafe {
        sw1_4(&rows, &mut o4, c, t);
        sw1_8(&rows, &mut o8, c, t);
        assert!(o4.iter().zip(&o8).all(|(a, b)| a.to_bits() == b.to_bits()), "sw1 bits");
        // the 4-lane kernel is the library's computation: its RadarEquation, bit for bit
        let radar = RadarEquation::new(13.0, 1500.0, 0.0, 1e-6, Swerling::One, 1).unwrap();
        for (row, pd) in rows.chunks_exact(4).zip(&o4) {
            let r2 = row[0] * row[0] + row[2] * row[2];
            assert_eq!(
                pd.to_bits(),
                radar.at_squared(r2).to_bits(),
                "the library's bits at r² {r2}"
            );
        }
        hz_4(&rows, &mut o4, d2);
        hz_8(&rows, &mut o8, d2);
        assert!(
            o4.iter().zip(&o8).all(|(a, b)| a.to_bits() == b.to_bits()),
            "horizon bits"
        );
    }
    for round in 0..3 {
        let mut best = [f64::MAX; 4];
        for _ in 0..2000 {
            for (k, best) in best.iter_mut().enumerate() {
                let st = Instant::now();
                let b = unsafe {
                    match k {
                        0 => sw1_4(&rows, &mut o4, c, t),
                        1 => sw1_8(&rows, &mut o8, c, t),
                        2 => hz_4(&rows, &mut o4, d2),
                        _ => hz_8(&rows, &mut o8, d2),
                    }
                };
                std::hint::black_box(b);
                *best = best.min(st.elapsed().as_secs_f64());
            }
        }
        let ns = best.map(|b| b / n as f64 * 1e9);
        println!("round {round}: ns/state (min, 10^4, one core): Swerling 1 AVX2 {:.3} AVX-512 {:.3} | horizon AVX2 {:.3} AVX-512 {:.3}", ns[0], ns[1], ns[2], ns[3]);
    }
}
