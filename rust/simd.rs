//! Four f64 lanes for the P_D and clutter kernels, two ways: AVX2 registers (x86-64 CPUs
//! that have AVX2, detected at run time) and plain arrays (every other CPU, and the
//! reference the AVX2 path is tested against). A kernel is written once, generic over
//! [`Lanes`], and [`dispatch`] runs the build for this CPU.
//!
//! Only exactly rounded operations are offered — add, subtract, multiply, square root,
//! comparisons, bit selects and one exact bit shift — and no fused multiply-add, so every backend gives the same
//! bits as the scalar formulas they replace.
//!
//! `CTXMODELS_SIMD=portable` in the environment (read once) forces the array backend, to
//! compare the two from Python or on a machine whose AVX2 path is suspect.

use std::ops::{Add, Mul, Sub};
use std::sync::OnceLock;

/// Four f64 values processed together, with a mask type for per-lane conditions.
/// Comparisons are ordered: false when either side is NaN, as in scalar Rust.
pub trait Lanes: Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> {
    type Mask: Copy;

    fn splat(v: f64) -> Self;
    fn from_array(a: [f64; 4]) -> Self;
    fn to_array(self) -> [f64; 4];
    /// The first four values of `s` (at least four long).
    fn load(s: &[f64]) -> Self;
    /// Into the first four values of `s`.
    fn store(self, s: &mut [f64]);
    /// Columns 0 and 2 of four consecutive rows of four values: the positions of four
    /// Stone Soup constant-velocity states [x, vx, y, vy], read straight from the rows.
    fn rows4_columns02(rows: &[f64]) -> (Self, Self);
    /// Columns 1 and 3 of the same four rows: their velocities (vx, vy).
    fn rows4_columns13(rows: &[f64]) -> (Self, Self);
    /// Columns 0, 2 and 4 of four consecutive rows of six values: the positions of four
    /// Stone Soup 3-D constant-velocity states [x, vx, y, vy, z, vz].
    fn rows4_columns024(rows: &[f64]) -> (Self, Self, Self);
    /// The x and y of four consecutive (x, y) pairs.
    fn pairs(xy: &[f64]) -> (Self, Self);
    /// The x, y and z of four consecutive (x, y, z) triples: 3-D detections' rows.
    fn triples(xyz: &[f64]) -> (Self, Self, Self);
    fn sqrt(self) -> Self;
    fn div(self, other: Self) -> Self;
    fn abs(self) -> Self;
    /// The larger of two values that are not NaN (either zero when ±0 compare equal).
    fn max(self, other: Self) -> Self;
    /// Each value's bits shifted left by 52 (the low bits of the significand become the
    /// exponent field): 2^k from the bits of 2⁵² + 1023 + k, an exact bit operation.
    fn shift_to_exponent(self) -> Self;

    fn gt(self, other: Self) -> Self::Mask;
    fn ge(self, other: Self) -> Self::Mask;
    fn lt(self, other: Self) -> Self::Mask;
    fn le(self, other: Self) -> Self::Mask;
    fn is_nan(self) -> Self::Mask;
    /// Infinite or NaN: every exponent bit set.
    fn non_finite(self) -> Self::Mask;
    fn and(a: Self::Mask, b: Self::Mask) -> Self::Mask;
    fn or(a: Self::Mask, b: Self::Mask) -> Self::Mask;
    fn none() -> Self::Mask;
    fn any(m: Self::Mask) -> bool;
    /// `a` where `m` holds, else `b`, lane by lane (exact: a bit select).
    fn select(m: Self::Mask, a: Self, b: Self) -> Self;
}

/// A kernel generic over the lanes type. `run` must be `#[inline(always)]`, so that its
/// body is compiled inside [`dispatch`]'s AVX2 entry point with AVX2 enabled.
pub trait LaneKernel {
    type Output;
    fn run<L: Lanes>(self) -> Self::Output;
}

/// Which build of the kernels runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Backend {
    Avx2,
    Portable,
}

impl Backend {
    /// What the Python binding reports (`ctxmodels._core.simd_backend()`).
    #[cfg_attr(not(feature = "python"), allow(dead_code))]
    pub fn name(self) -> &'static str {
        match self {
            Backend::Avx2 => "avx2",
            Backend::Portable => "portable",
        }
    }

    /// Whether this CPU can run the backend.
    pub fn available(self) -> bool {
        match self {
            Backend::Portable => true,
            #[cfg(target_arch = "x86_64")]
            Backend::Avx2 => std::arch::is_x86_feature_detected!("avx2"),
            #[cfg(not(target_arch = "x86_64"))]
            Backend::Avx2 => false,
        }
    }
}

/// The backend [`dispatch`] uses: AVX2 when the CPU has it, unless `CTXMODELS_SIMD=portable`.
pub fn backend() -> Backend {
    static CHOSEN: OnceLock<Backend> = OnceLock::new();
    *CHOSEN.get_or_init(|| {
        let forced_portable = std::env::var("CTXMODELS_SIMD").is_ok_and(|v| v.eq_ignore_ascii_case("portable"));
        if !forced_portable && Backend::Avx2.available() {
            Backend::Avx2
        } else {
            Backend::Portable
        }
    })
}

/// Runs `kernel` with the lanes of [`backend`].
#[inline]
pub fn dispatch<K: LaneKernel>(kernel: K) -> K::Output {
    #[cfg(test)]
    if let Some(forced) = FORCED.with(|f| f.get()) {
        return run_on(forced, kernel);
    }
    run_on(backend(), kernel)
}

#[cfg(test)]
thread_local! {
    static FORCED: std::cell::Cell<Option<Backend>> = const { std::cell::Cell::new(None) };
}

/// Runs `f` with [`dispatch`] on `backend` on this thread: a whole model (its kernels
/// called from this thread) tested on each build.
#[cfg(test)]
pub fn on_backend<T>(backend: Backend, f: impl FnOnce() -> T) -> T {
    FORCED.with(|forced| forced.set(Some(backend)));
    let out = f();
    FORCED.with(|forced| forced.set(None));
    out
}

/// Runs `kernel` on `backend`, which must be [`Backend::available`] (else the portable
/// build runs). Tests use it to compare the builds on the same input.
pub fn run_on<K: LaneKernel>(backend: Backend, kernel: K) -> K::Output {
    #[cfg(target_arch = "x86_64")]
    if backend == Backend::Avx2 && Backend::Avx2.available() {
        // SAFETY: the CPU has AVX2 (checked just above).
        return unsafe { x86::run_avx2(kernel) };
    }
    let _ = backend;
    kernel.run::<Portable>()
}

/// The array backend: plain loops the compiler may vectorise for the baseline target.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Portable([f64; 4]);

impl Add for Portable {
    type Output = Self;
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        Portable(std::array::from_fn(|i| self.0[i] + o.0[i]))
    }
}

impl Sub for Portable {
    type Output = Self;
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        Portable(std::array::from_fn(|i| self.0[i] - o.0[i]))
    }
}

impl Mul for Portable {
    type Output = Self;
    #[inline(always)]
    fn mul(self, o: Self) -> Self {
        Portable(std::array::from_fn(|i| self.0[i] * o.0[i]))
    }
}

impl Lanes for Portable {
    type Mask = [bool; 4];

    #[inline(always)]
    fn splat(v: f64) -> Self {
        Portable([v; 4])
    }
    #[inline(always)]
    fn from_array(a: [f64; 4]) -> Self {
        Portable(a)
    }
    #[inline(always)]
    fn to_array(self) -> [f64; 4] {
        self.0
    }
    #[inline(always)]
    fn load(s: &[f64]) -> Self {
        Portable([s[0], s[1], s[2], s[3]])
    }
    #[inline(always)]
    fn store(self, s: &mut [f64]) {
        s[..4].copy_from_slice(&self.0);
    }
    #[inline(always)]
    fn rows4_columns02(rows: &[f64]) -> (Self, Self) {
        let r = &rows[..16];
        (
            Portable([r[0], r[4], r[8], r[12]]),
            Portable([r[2], r[6], r[10], r[14]]),
        )
    }
    #[inline(always)]
    fn rows4_columns13(rows: &[f64]) -> (Self, Self) {
        let r = &rows[..16];
        (
            Portable([r[1], r[5], r[9], r[13]]),
            Portable([r[3], r[7], r[11], r[15]]),
        )
    }
    #[inline(always)]
    fn rows4_columns024(rows: &[f64]) -> (Self, Self, Self) {
        let r = &rows[..24];
        (
            Portable([r[0], r[6], r[12], r[18]]),
            Portable([r[2], r[8], r[14], r[20]]),
            Portable([r[4], r[10], r[16], r[22]]),
        )
    }
    #[inline(always)]
    fn pairs(xy: &[f64]) -> (Self, Self) {
        let p = &xy[..8];
        (Portable([p[0], p[2], p[4], p[6]]), Portable([p[1], p[3], p[5], p[7]]))
    }
    #[inline(always)]
    fn triples(xyz: &[f64]) -> (Self, Self, Self) {
        let p = &xyz[..12];
        (
            Portable([p[0], p[3], p[6], p[9]]),
            Portable([p[1], p[4], p[7], p[10]]),
            Portable([p[2], p[5], p[8], p[11]]),
        )
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        Portable(self.0.map(f64::sqrt))
    }
    #[inline(always)]
    fn div(self, o: Self) -> Self {
        Portable(std::array::from_fn(|i| self.0[i] / o.0[i]))
    }
    #[inline(always)]
    fn abs(self) -> Self {
        Portable(self.0.map(f64::abs))
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        Portable(std::array::from_fn(
            |i| if self.0[i] > o.0[i] { self.0[i] } else { o.0[i] },
        ))
    }
    #[inline(always)]
    fn shift_to_exponent(self) -> Self {
        Portable(self.0.map(|v| f64::from_bits(v.to_bits() << 52)))
    }
    #[inline(always)]
    fn gt(self, o: Self) -> [bool; 4] {
        std::array::from_fn(|i| self.0[i] > o.0[i])
    }
    #[inline(always)]
    fn ge(self, o: Self) -> [bool; 4] {
        std::array::from_fn(|i| self.0[i] >= o.0[i])
    }
    #[inline(always)]
    fn lt(self, o: Self) -> [bool; 4] {
        std::array::from_fn(|i| self.0[i] < o.0[i])
    }
    #[inline(always)]
    fn le(self, o: Self) -> [bool; 4] {
        std::array::from_fn(|i| self.0[i] <= o.0[i])
    }
    #[inline(always)]
    fn is_nan(self) -> [bool; 4] {
        self.0.map(f64::is_nan)
    }
    #[inline(always)]
    fn non_finite(self) -> [bool; 4] {
        const EXPONENT: u64 = 0x7ff0_0000_0000_0000;
        self.0.map(|v| v.to_bits() & EXPONENT == EXPONENT)
    }
    #[inline(always)]
    fn and(a: [bool; 4], b: [bool; 4]) -> [bool; 4] {
        std::array::from_fn(|i| a[i] & b[i])
    }
    #[inline(always)]
    fn or(a: [bool; 4], b: [bool; 4]) -> [bool; 4] {
        std::array::from_fn(|i| a[i] | b[i])
    }
    #[inline(always)]
    fn none() -> [bool; 4] {
        [false; 4]
    }
    #[inline(always)]
    fn any(m: [bool; 4]) -> bool {
        m[0] | m[1] | m[2] | m[3]
    }
    #[inline(always)]
    fn select(m: [bool; 4], a: Self, b: Self) -> Self {
        Portable(std::array::from_fn(|i| {
            let mask = (m[i] as u64).wrapping_neg();
            f64::from_bits((a.0[i].to_bits() & mask) | (b.0[i].to_bits() & !mask))
        }))
    }
}

mod exp;
pub use exp::exp;

#[cfg(target_arch = "x86_64")]
mod x86;

#[cfg(test)]
mod tests {
    use super::*;

    /// Every operation of every available backend against scalar Rust, bit for bit, on
    /// values that include signed zeros, infinities, NaN and subnormals.
    struct AllOps(Vec<f64>);

    impl LaneKernel for AllOps {
        type Output = Vec<u64>;
        #[inline(always)]
        fn run<L: Lanes>(self) -> Vec<u64> {
            let v = &self.0;
            let mut bits = Vec::new();
            for i in (0..v.len() - 8).step_by(3) {
                let (a, b) = (L::load(&v[i..]), L::load(&v[i + 4..]));
                let mask_bits = |m: L::Mask| L::select(m, L::splat(1.0), L::splat(0.0)).to_array();
                let (x, y) = L::pairs(&v[i..]);
                for lanes in [
                    a + b,
                    a - b,
                    a * b,
                    a.div(b),
                    a.sqrt(),
                    a.abs(),
                    L::max(a, b),
                    a.shift_to_exponent(),
                    x,
                    y,
                ] {
                    bits.extend(lanes.to_array().map(f64::to_bits));
                }
                for m in [
                    a.gt(b),
                    a.ge(b),
                    a.lt(b),
                    a.le(b),
                    a.is_nan(),
                    a.non_finite(),
                    L::and(a.gt(b), b.non_finite()),
                    L::or(a.lt(b), a.is_nan()),
                    L::none(),
                ] {
                    bits.extend(mask_bits(m).map(f64::to_bits));
                    bits.push(L::any(m) as u64);
                }
                if i + 16 <= v.len() {
                    let (x, y) = L::rows4_columns02(&v[i..]);
                    bits.extend(x.to_array().into_iter().chain(y.to_array()).map(f64::to_bits));
                    let (x, y, z) = L::triples(&v[i..]);
                    bits.extend([x, y, z].into_iter().flat_map(|l| l.to_array()).map(f64::to_bits));
                }
            }
            bits
        }
    }

    fn awkward_values() -> Vec<f64> {
        let special = [
            0.0,
            -0.0,
            1.0,
            -1.0,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
            f64::MIN_POSITIVE / 8.0,
            1e308,
            -3.5,
            2.0,
            2.0,
        ];
        let mut v: Vec<f64> = special.to_vec();
        v.extend((0..200).map(|k| ((k as f64) * 0.618_033_988_749_895).sin() * 1e3));
        v.extend(special.iter().rev());
        v
    }

    #[test]
    fn backends_agree_bit_for_bit() {
        let portable = run_on(Backend::Portable, AllOps(awkward_values()));
        // The scalar meaning of a few lanes, so the portable build is itself checked.
        let v = awkward_values();
        assert_eq!(portable[0], (v[0] + v[4]).to_bits());
        assert_eq!(portable[4], (v[0] - v[4]).to_bits());
        if Backend::Avx2.available() {
            assert_eq!(run_on(Backend::Avx2, AllOps(awkward_values())), portable);
        }
    }

    #[test]
    fn gathers_read_the_right_columns() {
        let rows: Vec<f64> = (0..16).map(|k| k as f64).collect();
        struct Gather(Vec<f64>);
        impl LaneKernel for Gather {
            type Output = ([f64; 4], [f64; 4], [f64; 4], [f64; 4], [[f64; 4]; 3]);
            #[inline(always)]
            fn run<L: Lanes>(self) -> Self::Output {
                let (x, y) = L::rows4_columns02(&self.0);
                let (px, py) = L::pairs(&self.0);
                let (tx, ty, tz) = L::triples(&self.0);
                let triples = [tx.to_array(), ty.to_array(), tz.to_array()];
                (x.to_array(), y.to_array(), px.to_array(), py.to_array(), triples)
            }
        }
        for backend in [Backend::Portable, Backend::Avx2].into_iter().filter(|b| b.available()) {
            let (x, y, px, py, triples) = run_on(backend, Gather(rows.clone()));
            let third = |from: f64| [from, from + 3.0, from + 6.0, from + 9.0];
            assert_eq!(triples, [third(0.0), third(1.0), third(2.0)], "{backend:?}");
            assert_eq!(x, [0.0, 4.0, 8.0, 12.0], "{backend:?}");
            assert_eq!(y, [2.0, 6.0, 10.0, 14.0], "{backend:?}");
            assert_eq!(px, [0.0, 2.0, 4.0, 6.0], "{backend:?}");
            assert_eq!(py, [1.0, 3.0, 5.0, 7.0], "{backend:?}");
        }
    }
}
