//! Measurement models of the scan path: linear Gaussian, and 2-D bearing–range with either
//! Stone Soup's forward finite-difference Jacobian (reproduced operation for operation) or
//! the closed-form one.

use crate::error::{ModelError, Result};
use std::f64::consts::PI;

const TWO_PI: f64 = 2.0 * PI;

/// How a bearing–range model is linearised.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Jacobian {
    /// Stone Soup's `compute_jac`: step `max(1e8·spacing(x_i), 1e-8)`, bearing differences
    /// wrapped. Its round-off (~1e-8 relative) follows the last bit of the state.
    FiniteDifference,
    /// `∂φ/∂x = (r₀R₁ₖ − r₁R₀ₖ)/ρ²`, `∂ρ/∂x = (r₀R₀ₖ + r₁R₁ₖ)/ρ` (finite difference at ρ = 0).
    Analytic,
}

#[derive(Debug, Clone)]
pub enum MeasurementModel {
    /// `z = H x + v`, `v ~ N(0, R)`; `matrix` is (m×D) row-major, `noise` (m×m).
    Linear {
        matrix: Vec<f64>,
        noise: Vec<f64>,
        ndim_meas: usize,
    },
    /// `z = (φ, ρ)` of `r = R·[x_{m0} − t0, x_{m1} − t1, 0]`; `noise` (2×2).
    BearingRange {
        mapping: [usize; 2],
        offset: [f64; 2],
        rotation: [f64; 9],
        noise: [f64; 4],
        jacobian: Jacobian,
    },
}

/// Python's float `%` (the result takes the divisor's sign), as NumPy and Stone Soup use it.
fn python_mod(a: f64, b: f64) -> f64 {
    let m = a % b;
    if m != 0.0 {
        if (b < 0.0) != (m < 0.0) {
            m + b
        } else {
            m
        }
    } else {
        0.0_f64.copysign(b)
    }
}

/// Stone Soup's `mod_bearing`: `((x + π) mod 2π) − π`, the same floating-point operations.
pub fn mod_bearing(x: f64) -> f64 {
    python_mod(x + PI, TWO_PI) - PI
}

/// NumPy's `spacing`: the distance to the next float away from zero, signed like `x`.
pub fn spacing(x: f64) -> f64 {
    let magnitude = x.abs();
    let next = f64::from_bits(magnitude.to_bits() + 1);
    (next - magnitude).copysign(x)
}

impl MeasurementModel {
    pub fn ndim_meas(&self) -> usize {
        match self {
            MeasurementModel::Linear { ndim_meas, .. } => *ndim_meas,
            MeasurementModel::BearingRange { .. } => 2,
        }
    }

    pub fn noise(&self) -> &[f64] {
        match self {
            MeasurementModel::Linear { noise, .. } => noise,
            MeasurementModel::BearingRange { noise, .. } => noise,
        }
    }

    /// Whether row 0 of the measurement is a bearing (wrapped in differences).
    pub fn has_bearing(&self) -> bool {
        matches!(self, MeasurementModel::BearingRange { .. })
    }

    pub fn validate(&self, ndim_state: usize) -> Result<()> {
        let m = self.ndim_meas();
        let finite = |values: &[f64]| values.iter().all(|v| v.is_finite());
        match self {
            MeasurementModel::Linear { matrix, noise, .. } => {
                if m == 0 || matrix.len() != m * ndim_state || noise.len() != m * m {
                    return Err(ModelError::shape(
                        "measurement_model",
                        format!("a linear model needs an (m, {ndim_state}) matrix and an (m, m) covariance"),
                    ));
                }
                if !finite(matrix) || !finite(noise) {
                    return Err(ModelError::invalid(
                        "measurement_model",
                        "matrix and covariance must be finite",
                    ));
                }
            }
            MeasurementModel::BearingRange {
                mapping,
                offset,
                rotation,
                noise,
                ..
            } => {
                if mapping[0] >= ndim_state || mapping[1] >= ndim_state || mapping[0] == mapping[1] {
                    return Err(ModelError::invalid(
                        "measurement_model",
                        format!("mapping {mapping:?} must be two different indices < {ndim_state}"),
                    ));
                }
                if !finite(offset) || !finite(rotation) || !finite(noise) {
                    return Err(ModelError::invalid(
                        "measurement_model",
                        "offset, rotation and covariance must be finite",
                    ));
                }
            }
        }
        Ok(())
    }

    /// Predicted measurement `z` (m) and Jacobian `h` (m×D) at the state `x` (D).
    pub fn linearise(&self, x: &[f64], z: &mut [f64], h: &mut [f64]) {
        let ndim = x.len();
        match self {
            MeasurementModel::Linear { matrix, ndim_meas, .. } => {
                super::linalg::matvec(matrix, x, *ndim_meas, ndim, z);
                h.copy_from_slice(matrix);
            }
            MeasurementModel::BearingRange { jacobian, .. } => {
                let (phi, rho) = self.bearing_range(x, 0, 0.0);
                z[0] = phi;
                z[1] = rho;
                let analytic = *jacobian == Jacobian::Analytic && self.analytic_jacobian(x, h);
                if !analytic {
                    self.finite_difference_jacobian(x, phi, rho, h);
                }
            }
        }
    }

    /// `(φ, ρ)` of `x` with `step` added to element `index` (as Stone Soup's function sees
    /// the perturbed state: every element gets `x + 0·δ` or `x + 1·δ`).
    fn bearing_range(&self, x: &[f64], index: usize, step: f64) -> (f64, f64) {
        let MeasurementModel::BearingRange {
            mapping,
            offset,
            rotation,
            ..
        } = self
        else {
            return (f64::NAN, f64::NAN); // (only called for a bearing–range model)
        };
        let at = |i: usize| if i == index { x[i] + step } else { x[i] + 0.0 };
        let dx = at(mapping[0]) - offset[0];
        let dy = at(mapping[1]) - offset[1];
        let r0 = rotation[0] * dx + rotation[1] * dy + rotation[2] * 0.0;
        let r1 = rotation[3] * dx + rotation[4] * dy + rotation[5] * 0.0;
        let rho = (r0 * r0 + r1 * r1).sqrt();
        let phi = r1.atan2(r0);
        (mod_bearing(0.0 + phi), 0.0 + rho)
    }

    fn finite_difference_jacobian(&self, x: &[f64], phi: f64, rho: f64, h: &mut [f64]) {
        let ndim = x.len();
        for i in 0..ndim {
            let mut delta = 1e8 * spacing(x[i]);
            if delta < 1e-8 {
                delta = 1e-8;
            }
            let (phi_i, rho_i) = self.bearing_range(x, i, delta);
            h[i] = mod_bearing(phi_i - phi) / delta;
            h[ndim + i] = (rho_i - rho) / delta;
        }
    }

    /// The closed-form Jacobian; false (h untouched) at ρ = 0, where it is undefined.
    fn analytic_jacobian(&self, x: &[f64], h: &mut [f64]) -> bool {
        let MeasurementModel::BearingRange {
            mapping,
            offset,
            rotation,
            ..
        } = self
        else {
            return false;
        };
        let ndim = x.len();
        let dx = x[mapping[0]] - offset[0];
        let dy = x[mapping[1]] - offset[1];
        let r0 = rotation[0] * dx + rotation[1] * dy;
        let r1 = rotation[3] * dx + rotation[4] * dy;
        let rho2 = r0 * r0 + r1 * r1;
        if rho2 == 0.0 {
            return false;
        }
        let rho = rho2.sqrt();
        h.iter_mut().for_each(|v| *v = 0.0);
        for (k, &column) in mapping.iter().enumerate() {
            h[column] = (r0 * rotation[3 + k] - r1 * rotation[k]) / rho2;
            h[ndim + column] = (r0 * rotation[k] + r1 * rotation[3 + k]) / rho;
        }
        true
    }

    /// `a − b` of two measurements, the bearing row wrapped as Stone Soup's angle types do.
    pub fn difference(&self, a: &[f64], b: &[f64], out: &mut [f64]) {
        for i in 0..out.len() {
            out[i] = a[i] - b[i];
        }
        if self.has_bearing() {
            out[0] = mod_bearing(out[0]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn radar(jacobian: Jacobian, yaw: f64) -> MeasurementModel {
        let (s, c) = yaw.sin_cos();
        // Stone Soup's rotation matrix for rotation_offset (0, 0, yaw) rotates world into
        // the sensor frame: R = Rz(−yaw).
        MeasurementModel::BearingRange {
            mapping: [0, 2],
            offset: [10.0, -20.0],
            rotation: [c, s, 0.0, -s, c, 0.0, 0.0, 0.0, 1.0],
            noise: [1e-4, 0.0, 0.0, 1.0],
            jacobian,
        }
    }

    #[test]
    fn python_modulo_semantics() {
        assert_eq!(python_mod(-1.0, TWO_PI), -1.0 + TWO_PI);
        assert_eq!(python_mod(7.0, TWO_PI), 7.0 % TWO_PI);
        assert_eq!(mod_bearing(PI), -PI);
        assert!(mod_bearing(-PI - 0.1) > 3.0);
    }

    #[test]
    fn spacing_matches_numpy() {
        assert_eq!(spacing(1.0), f64::EPSILON);
        assert_eq!(spacing(-1.0), -f64::EPSILON);
        assert_eq!(spacing(0.0), f64::from_bits(1));
    }

    #[test]
    fn analytic_and_finite_difference_jacobians_agree() {
        let x = [512.0, 3.0, -230.0, -1.5];
        for yaw in [0.0, 0.7, -2.9] {
            let mut z = [0.0; 2];
            let mut fd = [0.0; 8];
            let mut exact = [0.0; 8];
            radar(Jacobian::FiniteDifference, yaw).linearise(&x, &mut z, &mut fd);
            radar(Jacobian::Analytic, yaw).linearise(&x, &mut z, &mut exact);
            for (a, b) in fd.iter().zip(&exact) {
                // the finite difference's round-off: ε·|φ|/δ with δ = 1e-8 for negative
                // coordinates, ~1e-5 relative to a derivative of ~1e-3
                assert!((a - b).abs() <= 1e-4 * b.abs().max(1e-6), "{a} vs {b}");
            }
            assert_eq!(exact[1], 0.0);
            assert_eq!(exact[4 + 3], 0.0);
        }
    }

    #[test]
    fn analytic_falls_back_at_the_sensor() {
        let x = [10.0, 0.0, -20.0, 0.0];
        let mut z = [0.0; 2];
        let mut h = [f64::NAN; 8];
        radar(Jacobian::Analytic, 0.3).linearise(&x, &mut z, &mut h);
        assert!(h.iter().all(|v| v.is_finite()));
    }

    #[test]
    fn bearing_difference_is_wrapped() {
        let model = radar(Jacobian::Analytic, 0.0);
        let mut out = [0.0; 2];
        model.difference(&[3.1, 5.0], &[-3.1, 2.0], &mut out);
        assert!((out[0] - (6.2 - TWO_PI)).abs() < 1e-12);
        assert_eq!(out[1], 3.0);
    }
}
