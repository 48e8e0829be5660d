//! The Kalman filter pieces both scan cores share (the GM-PHD's [`crate::gmphd`], the
//! JPDA's and the M-of-N initiator's [`crate::jpda`]): the prediction of a Gaussian state,
//! the measurement models with their Jacobians, and the small row-major matrix helpers.
//!
//! * [`predict_state`]: `x ← F x`, `P ← (F P) Fᵀ + Q`, the product `(F P) Fᵀ` formed on
//!   its lower triangle and mirrored, so a predicted covariance is symmetric to the bit;
//! * [`MeasurementModel`]: linear Gaussian and 2-D bearing–range, each with `h(x)` and its
//!   matrix or Jacobian, rounded as Stone Soup's reference path rounds them (see
//!   [`measurement`]).
//!
//! Plain loops in a fixed order, no runtime CPU dispatch: the same inputs give the same
//! bits on every machine.

pub mod linalg;
pub mod measurement;

pub use measurement::{mod_bearing, spacing, Jacobian, MeasurementModel};

/// Kalman prediction of one state in place: `x ← F x`, `P ← (F P) Fᵀ + Q` (`f`, `q`, `p`
/// D×D row-major). `scratch` holds at least `2·D² + D` values.
pub fn predict_state(f: &[f64], q: &[f64], x: &mut [f64], p: &mut [f64], scratch: &mut [f64]) {
    let d = x.len();
    let d2 = d * d;
    let (mean, rest) = scratch.split_at_mut(d);
    let (fp, rest) = rest.split_at_mut(d2);
    let fpf = &mut rest[..d2];
    linalg::matvec(f, x, d, d, mean);
    x.copy_from_slice(mean);
    linalg::matmul(f, p, d, d, d, fp);
    linalg::symmetric_product(fp, f, d, d, fpf); // (F P) Fᵀ
    for k in 0..d2 {
        p[k] = fpf[k] + q[k];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn prediction_is_f_x_and_f_p_ft_plus_q_symmetric_to_the_bit() {
        let f = [1.0, 0.7, 0.0, 1.0];
        let q = [0.1, 0.2, 0.2, 0.5];
        let mut x = [3.0, -2.0];
        let mut p = [2.0, 0.3, 0.3, 1.1];
        let mut scratch = [0.0; 10];
        predict_state(&f, &q, &mut x, &mut p, &mut scratch);
        assert_eq!(x, [3.0 + 0.7 * -2.0, -2.0]);
        // F P Fᵀ by hand: [[2 + 0.42 + 0.49·1.1 + 0.42, 0.3 + 0.77], [sym, 1.1]]
        let expected = [
            2.0 + 2.0 * 0.7 * 0.3 + 0.49 * 1.1 + 0.1,
            0.3 + 0.7 * 1.1 + 0.2,
            0.0,
            1.1 + 0.5,
        ];
        assert!((p[0] - expected[0]).abs() < 1e-12 && (p[1] - expected[1]).abs() < 1e-12);
        assert_eq!(p[1], p[2]);
        assert!((p[3] - expected[3]).abs() < 1e-12);
    }
}
