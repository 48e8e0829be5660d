//! Conservative gate screening of track × detection pairs for the M-of-N initiator
//! (`ctxmodels.stonesoup.array_initiator`): which pairs *may* pass a Mahalanobis gate.
//!
//! For predicted measurements `ẑ_n` with innovation covariances `S_n` and detections `z_k`,
//! the pair `(n, k)` is kept unless `d² − margin·Σ|terms| > threshold`, where `δ = −(z_k − ẑ_n)`
//! (a row marked in `wrap` is wrapped to `[−π, π)` by Stone Soup's `mod_bearing` after the
//! difference and again after the negation, as `Bearing` arithmetic wraps it),
//! `terms_ij = δ_i (S_n⁻¹)_ij δ_j` and `d² = Σ terms`. The exact distances are computed
//! afterwards by the caller for the kept pairs only; the relative `margin` covers the
//! rounding difference between this inverse (LU with partial pivoting) and the caller's. A
//! singular `S_n` keeps the whole row, and NaN never excludes a pair (the caller decides).
//!
//! A bearing element of `δ` within 1e-6 of ±π also keeps the pair: there a rounding
//! difference in `ẑ` could move the wrap to the other side.
//!
//! [`screen_states`] screens predicted *states* instead: it forms `ẑ_n` and `S_n = H P Hᵀ + R`
//! with the core's measurement model (the caller then computes the exact measurement
//! prediction of the rows that kept a pair only).
//!
//! The result does not depend on anything but the inputs (one thread, index order).

use super::measurement::{mod_bearing, MeasurementModel};
use super::{too_large, try_filled};
use crate::memory;
use crate::error::{ModelError, Result};
use nalgebra::DVector;
use std::cmp::Ordering;
use std::f64::consts::PI;

/// How close to ±π a wrapped element keeps its pair.
const WRAP_GUARD: f64 = 1e-6;

/// One screening problem (row-major slices): `N = means.len() / m` predicted measurements,
/// `K = detections.len() / m` detections.
#[derive(Debug, Clone, Copy)]
pub struct ScreenInput<'a> {
    /// Measurement dimension m.
    pub ndim_meas: usize,
    /// Predicted measurements, N×m.
    pub means: &'a [f64],
    /// Innovation covariances, N×m×m.
    pub covars: &'a [f64],
    /// Detections, K×m.
    pub detections: &'a [f64],
    /// K×m: whether element `(k, i)` of `z_k − ẑ_n` is a bearing (wrapped).
    pub wrap: &'a [bool],
    /// The gate on the squared distance.
    pub threshold: f64,
    /// Relative margin on `Σ|terms|`.
    pub margin: f64,
}

/// The `N×K` mask (row-major) of the pairs that may pass the gate.
pub fn screen_pairs(input: &ScreenInput) -> Result<Vec<bool>> {
    let m = input.ndim_meas;
    if m == 0 {
        return Err(ModelError::shape("means", "measurements must have at least one dimension"));
    }
    if !input.means.len().is_multiple_of(m) || !input.detections.len().is_multiple_of(m) {
        return Err(ModelError::shape("means", format!("means and detections must have {m} columns")));
    }
    let n = input.means.len() / m;
    let k = input.detections.len() / m;
    if input.covars.len() != n * m * m {
        return Err(ModelError::shape("covars", format!("must be ({n}, {m}, {m}), got {} values", input.covars.len())));
    }
    if input.wrap.len() != k * m {
        return Err(ModelError::shape("wrap", format!("must be ({k}, {m}), got {} values", input.wrap.len())));
    }
    let mut out = try_filled(n.checked_mul(k), true).ok_or_else(|| too_large(n, k))?;
    let mut delta = memory::filled("means", m, 0.0)?;
    let mut work = memory::filled("means", memory::product("means", &[2, m, m])?, 0.0)?;
    let mut inverse = memory::filled("means", m * m, 0.0)?; // (≤ work's size)
    for row in 0..n {
        if !invert(&input.covars[row * m * m..(row + 1) * m * m], m, &mut work, &mut inverse) {
            continue; // singular or not finite: every pair of the row stays a candidate
        }
        let zhat = &input.means[row * m..(row + 1) * m];
        for col in 0..k {
            let z = &input.detections[col * m..(col + 1) * m];
            let wrap = &input.wrap[col * m..(col + 1) * m];
            for i in 0..m {
                let mut d = z[i] - zhat[i];
                if wrap[i] {
                    d = mod_bearing(d);
                }
                d = -d;
                if wrap[i] {
                    d = mod_bearing(d);
                }
                delta[i] = d;
            }
            if (0..m).any(|i| wrap[i] && delta[i].abs() > PI - WRAP_GUARD) {
                continue; // at the wrap: a candidate
            }
            let (mut d2, mut magnitude) = (0.0, 0.0);
            for i in 0..m {
                for j in 0..m {
                    let term = delta[i] * inverse[i * m + j] * delta[j];
                    d2 += term;
                    magnitude += term.abs();
                }
            }
            // NaN is unordered: the pair stays a candidate
            out[row * k + col] = (d2 - input.margin * magnitude).partial_cmp(&input.threshold) != Some(Ordering::Greater);
        }
    }
    Ok(out)
}

/// The inverse of the row-major `m × m` matrix `s` into `out` by Gauss–Jordan elimination
/// with partial pivoting (`work`: 2m² scratch); false when `s` is singular or not finite.
fn invert(s: &[f64], m: usize, work: &mut [f64], out: &mut [f64]) -> bool {
    if s.iter().any(|v| !v.is_finite()) {
        return false;
    }
    let w = 2 * m;
    for i in 0..m {
        for j in 0..m {
            work[i * w + j] = s[i * m + j];
            work[i * w + m + j] = if i == j { 1.0 } else { 0.0 };
        }
    }
    for col in 0..m {
        let pivot = (col..m).max_by(|&a, &b| work[a * w + col].abs().total_cmp(&work[b * w + col].abs())).unwrap_or(col);
        let value = work[pivot * w + col];
        if value == 0.0 || !value.is_finite() {
            return false;
        }
        if pivot != col {
            for j in 0..w {
                work.swap(pivot * w + j, col * w + j);
            }
        }
        for j in 0..w {
            work[col * w + j] /= value;
        }
        for r in 0..m {
            let factor = work[r * w + col];
            if r != col && factor != 0.0 {
                for j in 0..w {
                    work[r * w + j] -= factor * work[col * w + j];
                }
            }
        }
    }
    for i in 0..m {
        out[i * m..(i + 1) * m].copy_from_slice(&work[i * w + m..(i + 1) * w]);
    }
    out.iter().all(|v| v.is_finite())
}

/// [`screen_pairs`] of `N` predicted states `means` (N×D) / `covars` (N×D×D)
/// under `model`: `ẑ_n = h(x_n)`, `S_n = H_n P_n H_nᵀ + R`. (`input.means`/`input.covars`
/// are ignored.) A state with NaN or infinity keeps all its pairs.
pub fn screen_states(model: &MeasurementModel, dim: usize, means: &[f64], covars: &[f64], input: &ScreenInput) -> Result<Vec<bool>> {
    let m = model.ndim_meas();
    if input.ndim_meas != m {
        return Err(ModelError::shape("detections", format!("must have {m} columns (the model's measurement size), got {}", input.ndim_meas)));
    }
    if dim == 0 || !means.len().is_multiple_of(dim) {
        return Err(ModelError::shape("means", format!("must be (N, {dim}) with {dim} > 0, got {} values", means.len())));
    }
    let n = means.len() / dim;
    if covars.len() != n * dim * dim {
        return Err(ModelError::shape("covars", format!("must be ({n}, {dim}, {dim}), got {} values", covars.len())));
    }
    model.check_dim(dim)?;
    let noise = model.noise();
    let mut zhat = try_filled(n.checked_mul(m), f64::NAN).ok_or_else(|| too_large(n, 1))?;
    let mut innovation = try_filled(n.checked_mul(m * m), f64::NAN).ok_or_else(|| too_large(n, 1))?;
    for row in 0..n {
        let x = &means[row * dim..(row + 1) * dim];
        let p = &covars[row * dim * dim..(row + 1) * dim * dim];
        if x.iter().chain(p).any(|v| !v.is_finite()) {
            continue; // NaN: every pair stays a candidate
        }
        let (z, h) = model.linearise(&DVector::from_row_slice(x));
        zhat[row * m..(row + 1) * m].copy_from_slice(z.as_slice());
        // S = H P Hᵀ + R without temporaries (the zero entries of H skipped: finite P)
        for i in 0..m {
            for j in 0..m {
                let mut sum = noise[(i, j)];
                for a in 0..dim {
                    let hia = h[(i, a)];
                    if hia == 0.0 {
                        continue;
                    }
                    let pa = &p[a * dim..(a + 1) * dim];
                    for (b, &pab) in pa.iter().enumerate() {
                        sum += hia * pab * h[(j, b)];
                    }
                }
                innovation[(row * m + i) * m + j] = sum;
            }
        }
    }
    screen_pairs(&ScreenInput { means: &zhat, covars: &innovation, ..*input })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn input<'a>(means: &'a [f64], covars: &'a [f64], dets: &'a [f64], wrap: &'a [bool], threshold: f64) -> ScreenInput<'a> {
        ScreenInput { ndim_meas: 2, means, covars, detections: dets, wrap, threshold, margin: 1e-6 }
    }

    #[test]
    fn keeps_the_pairs_within_the_gate() {
        // S = diag(1, 4): d² of (1, 2) is 1 + 1 = 2
        let means = [0.0, 0.0, 10.0, 10.0];
        let covars = [1.0, 0.0, 0.0, 4.0, 1.0, 0.0, 0.0, 4.0];
        let dets = [1.0, 2.0, 10.0, 10.0, 3.0, 0.0];
        let wrap = [false; 6];
        let out = screen_pairs(&input(&means, &covars, &dets, &wrap, 2.5)).unwrap();
        assert_eq!(out, vec![true, false, false, false, true, false]);
        // exactly at the gate: the margin keeps it
        let out = screen_pairs(&input(&means, &covars, &dets, &wrap, 2.0 - 1e-9)).unwrap();
        assert!(out[0]);
    }

    #[test]
    fn equals_an_exact_evaluation_away_from_the_margin() {
        let (n, k) = (7usize, 5usize);
        let mut state = 12345u64;
        let mut next = || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((state >> 11) as f64) / ((1u64 << 53) as f64)
        };
        let means: Vec<f64> = (0..n * 2).map(|_| next() * 6.0 - 3.0).collect();
        let mut covars = Vec::new();
        for _ in 0..n {
            let (a, b, c) = (next() + 0.1, next() - 0.5, next() + 0.1);
            // S = L Lᵀ with L = [[a, 0], [b, c]]
            covars.extend([a * a, a * b, a * b, b * b + c * c]);
        }
        let dets: Vec<f64> = (0..k * 2).map(|_| next() * 6.0 - 3.0).collect();
        let wrap: Vec<bool> = (0..k * 2).map(|i| i % 2 == 0).collect();
        let out = screen_pairs(&input(&means, &covars, &dets, &wrap, 9.0)).unwrap();
        for row in 0..n {
            let s = &covars[row * 4..row * 4 + 4];
            let det = s[0] * s[3] - s[1] * s[2];
            for col in 0..k {
                let mut d = [dets[col * 2] - means[row * 2], dets[col * 2 + 1] - means[row * 2 + 1]];
                d[0] = mod_bearing(-mod_bearing(d[0]));
                d[1] = -d[1];
                let d2 = (d[0] * d[0] * s[3] - 2.0 * d[0] * d[1] * s[1] + d[1] * d[1] * s[0]) / det;
                if (d2 - 9.0).abs() > 1e-6 * (1.0 + d2) {
                    assert_eq!(out[row * k + col], d2 <= 9.0, "pair ({row}, {col}): d² = {d2}");
                }
            }
        }
    }

    #[test]
    fn states_screen_as_their_measurement_predictions() {
        // linear model H = [[1, 0, 0, 0], [0, 0, 1, 0]], R = I: ẑ = (x0, x2), S = diag(P00 + 1, P22 + 1)
        let model = MeasurementModel::linear(&[1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0], 2, 4, &[1.0, 0.0, 0.0, 1.0]).unwrap();
        let means = [0.0, 5.0, 0.0, 5.0, 10.0, 0.0, 10.0, 0.0, f64::NAN, 0.0, 0.0, 0.0];
        let mut covars = vec![0.0; 48];
        for row in 0..3 {
            for i in 0..4 {
                covars[row * 16 + i * 5] = 1.0;
            }
        }
        let dets = [1.0, 1.0, 10.0, 10.0];
        let wrap = [false; 4];
        let probe = input(&[], &[], &dets, &wrap, 2.0);
        let out = screen_states(&model, 4, &means, &covars, &probe).unwrap();
        // d² of (1, 1) from (0, 0) with S = 2I is 1: kept; from (10, 10): 81
        assert_eq!(out, vec![true, false, false, true, true, true]);
        assert!(screen_states(&model, 3, &means[..9], &covars[..27], &probe).is_err());
        assert!(screen_states(&model, 4, &means, &covars[..20], &probe).is_err());
        let three = ScreenInput { ndim_meas: 3, ..probe };
        assert!(screen_states(&model, 4, &means, &covars, &three).is_err());
    }

    #[test]
    fn a_bearing_at_the_wrap_stays_a_candidate() {
        let means = [0.0, 5.0];
        let covars = [1e-6, 0.0, 0.0, 1e-6];
        let dets = [PI - 1e-9, 5.0];
        let out = screen_pairs(&input(&means, &covars, &dets, &[true, false], 1.0)).unwrap();
        assert_eq!(out, vec![true]);
        let dets = [PI - 0.1, 5.0];
        let out = screen_pairs(&input(&means, &covars, &dets, &[true, false], 1.0)).unwrap();
        assert_eq!(out, vec![false]);
    }

    #[test]
    fn inverts_as_lu_does() {
        let mut work = vec![0.0; 18];
        let mut out = vec![0.0; 9];
        let s = [4.0, 1.0, 0.5, 1.0, 3.0, 0.2, 0.5, 0.2, 2.0];
        assert!(invert(&s, 3, &mut work, &mut out));
        let reference = nalgebra::DMatrix::from_row_slice(3, 3, &s).lu().try_inverse().unwrap();
        for i in 0..3 {
            for j in 0..3 {
                assert!((out[i * 3 + j] - reference[(i, j)]).abs() < 1e-15);
            }
        }
        // a zero first pivot needs the row swap
        let s = [0.0, 2.0, 3.0, 1.0];
        assert!(invert(&s, 2, &mut work, &mut out));
        assert_eq!(&out[..4], &[-1.0 / 6.0, 1.0 / 3.0, 0.5, 0.0]);
        assert!(!invert(&[1.0, 2.0, 2.0, 4.0], 2, &mut work, &mut out));
        assert!(!invert(&[f64::NAN, 0.0, 0.0, 1.0], 2, &mut work, &mut out));
        assert!(!invert(&[1e308, 0.0, 0.0, 1e-320], 2, &mut work, &mut out));
    }

    #[test]
    fn wraps_bearings() {
        // bearing difference 2π − 0.2 wraps to −0.2: within the gate
        let means = [PI - 0.1, 5.0];
        let covars = [1.0, 0.0, 0.0, 1.0];
        let dets = [-PI + 0.1, 5.0];
        let out = screen_pairs(&input(&means, &covars, &dets, &[true, false], 1.0)).unwrap();
        assert_eq!(out, vec![true]);
        let out = screen_pairs(&input(&means, &covars, &dets, &[false, false], 1.0)).unwrap();
        assert_eq!(out, vec![false]);
    }

    #[test]
    fn singular_rows_and_nan_stay_candidates() {
        let means = [0.0, 0.0, 0.0, 0.0, f64::NAN, 0.0];
        let covars = [1.0, 1.0, 1.0, 1.0, 1.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 1.0];
        let dets = [100.0, 100.0];
        let out = screen_pairs(&input(&means, &covars, &dets, &[false, false], 1.0)).unwrap();
        assert_eq!(out, vec![true, false, true]);
    }

    #[test]
    fn bad_shapes_are_errors_and_empty_inputs_are_fine() {
        assert!(screen_pairs(&input(&[0.0, 0.0], &[1.0], &[], &[], 1.0)).is_err());
        assert!(screen_pairs(&input(&[0.0, 0.0], &[1.0, 0.0, 0.0, 1.0], &[0.0, 0.0], &[false], 1.0)).is_err());
        assert!(screen_pairs(&input(&[0.0], &[1.0, 0.0, 0.0, 1.0], &[], &[], 1.0)).is_err());
        let bad = ScreenInput { ndim_meas: 0, means: &[], covars: &[], detections: &[], wrap: &[], threshold: 1.0, margin: 0.0 };
        assert!(screen_pairs(&bad).is_err());
        assert_eq!(screen_pairs(&input(&[], &[], &[0.0, 0.0], &[false, false], 1.0)).unwrap(), Vec::<bool>::new());
        assert_eq!(screen_pairs(&input(&[0.0, 0.0], &[1.0, 0.0, 0.0, 1.0], &[], &[], 1.0)).unwrap(), Vec::<bool>::new());
    }
}
