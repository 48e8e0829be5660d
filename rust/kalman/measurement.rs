//! The measurement models of the Kalman filters (GM-PHD scan, JPDA scan, M-of-N initiator):
//! linear Gaussian, and Stone Soup's 2-D `CartesianToBearingRange` with its forward
//! finite-difference Jacobian or the closed-form one.
//!
//! **Rounding.** Each value is computed with the operations Stone Soup's reference path
//! performs, in its order: the model function's `R·[x − t, 0]` is NumPy's 3×3 by 3×1
//! product for one state (`r₀ = fma(R₀₀, a, R₀₁ b)`) and its 3×3 by 3×(D+1) product for the
//! finite difference's perturbed states (`r₀ = fma(R₀₁, b, R₀₀ a)`), as OpenBLAS's kernels
//! round them on x86-64 with FMA; `ρ = √(r₀² + r₁²)`, the bearing `atan2(r₁, r₀)` wrapped by
//! `mod_bearing(0 + φ)`. The closed-form Jacobian is
//! [`AnalyticCartesianToBearingRange.jacobian`]'s: `ρ = hypot(r₀, r₁)`, `u = r/ρ`,
//! `∂φ/∂x_{m_k} = (u₀R₁ₖ − u₁R₀ₖ)/ρ`, `∂ρ/∂x_{m_k} = u₀R₀ₖ + u₁R₁ₖ`, and the finite
//! difference at the sensor (`ρ = 0`). What still differs from Stone Soup in the last bit:
//! NumPy's own `arctan2` against the C library's `atan2` (a few per cent of arguments), which
//! the finite difference divides by steps of 10⁻⁸–10⁻⁶ (so ~10⁻⁵ relative in its bearing
//! row), and platforms whose BLAS rounds the products another way.
//!
//! [`AnalyticCartesianToBearingRange.jacobian`]: ../../python/ctxmodels/stonesoup/models.py

use crate::error::{ModelError, Result};
use nalgebra::{DMatrix, DVector, Matrix3};
use std::f64::consts::PI;

const TWO_PI: f64 = 2.0 * PI;

/// How a bearing–range model is linearised.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Jacobian {
    /// Stone Soup's `compute_jac`: step `max(1e8·spacing(x_i), 1e-8)`, bearing differences
    /// wrapped. Its round-off (~1e-8 relative) follows the last bit of the state.
    FiniteDifference,
    /// The closed form (the finite difference at `ρ = 0`, where bearing has no derivative).
    Analytic,
}

/// A measurement model (validated at construction: finite, consistent shapes).
#[derive(Debug, Clone)]
pub enum MeasurementModel {
    /// `z = H x + v`, `v ~ N(0, R)`: `matrix` (m×D) and `noise` (m×m) row-major; `H⁺`
    /// (D×m) of new tracks when the caller gives it (see [`MeasurementModel::with_inverse`]).
    Linear {
        matrix: Vec<f64>,
        noise: Vec<f64>,
        ndim_meas: usize,
        pseudo_inverse: Option<Vec<f64>>,
    },
    /// `z = (φ, ρ)` of `r = R·[x_{m₀} − t₀, x_{m₁} − t₁, 0]`, bearing wrapped to `[−π, π)`;
    /// `rotation` R and `noise` (2×2) row-major; `R⁻¹` of the inverse function (new tracks),
    /// None if `R` is singular.
    BearingRange {
        mapping: [usize; 2],
        offset: [f64; 2],
        rotation: [f64; 9],
        noise: [f64; 4],
        jacobian: Jacobian,
        inverse_rotation: Option<[f64; 9]>,
    },
}

fn check_finite(argument: &'static str, values: &[f64]) -> Result<()> {
    match values.iter().position(|v| !v.is_finite()) {
        Some(i) => Err(ModelError::invalid(
            argument,
            format!("element {i} is not finite ({})", values[i]),
        )),
        None => Ok(()),
    }
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
    /// A linear Gaussian model from its row-major `rows × cols` matrix and `rows × rows` noise.
    pub fn linear(matrix: &[f64], rows: usize, cols: usize, noise: &[f64]) -> Result<Self> {
        if rows == 0 || cols == 0 || matrix.len() != rows * cols {
            return Err(ModelError::shape(
                "matrix",
                format!(
                    "must be a non-empty ({rows}, {cols}) matrix, got {} values",
                    matrix.len()
                ),
            ));
        }
        if noise.len() != rows * rows {
            return Err(ModelError::shape(
                "noise_covar",
                format!(
                    "must be ({rows}, {rows}) to match the matrix, got {} values",
                    noise.len()
                ),
            ));
        }
        check_finite("matrix", matrix)?;
        check_finite("noise_covar", noise)?;
        Ok(MeasurementModel::Linear {
            matrix: matrix.to_vec(),
            noise: noise.to_vec(),
            ndim_meas: rows,
            pseudo_inverse: None,
        })
    }

    /// A 2-D bearing–range model: `rotation` is the row-major 3×3 rotation matrix, `noise`
    /// the 2×2 covariance of (bearing, range).
    pub fn bearing_range(
        mapping: [usize; 2],
        offset: [f64; 2],
        rotation: &[f64],
        noise: &[f64],
        jacobian: Jacobian,
    ) -> Result<Self> {
        let rotation: [f64; 9] = rotation
            .try_into()
            .map_err(|_| ModelError::shape("rotation_matrix", format!("must be 3×3, got {} values", rotation.len())))?;
        let noise: [f64; 4] = noise
            .try_into()
            .map_err(|_| ModelError::shape("noise_covar", format!("must be 2×2, got {} values", noise.len())))?;
        if mapping[0] == mapping[1] {
            return Err(ModelError::invalid(
                "mapping",
                format!("x and y must be different state indices, got {mapping:?}"),
            ));
        }
        check_finite("translation_offset", &offset)?;
        check_finite("rotation_matrix", &rotation)?;
        check_finite("noise_covar", &noise)?;
        let inverse_rotation = Matrix3::from_row_slice(&rotation)
            .try_inverse()
            .map(|inverse| std::array::from_fn(|k| inverse[(k / 3, k % 3)]));
        Ok(MeasurementModel::BearingRange {
            mapping,
            offset,
            rotation,
            noise,
            jacobian,
            inverse_rotation,
        })
    }

    /// The model with the inverse of its measurement as the caller computes it: `H⁺`
    /// (row-major D×m) of a linear model, `R⁻¹` (row-major 3×3) of a bearing–range one.
    /// Stone Soup computes both with NumPy (`pinv`, `inv`); given them, a new track's mean is
    /// Stone Soup's to the bit (and so is a finite-difference Jacobian there, which one ulp of
    /// the mean moves by ~10⁻⁵).
    pub fn with_inverse(mut self, inverse: &[f64]) -> Result<Self> {
        check_finite("inverse", inverse)?;
        match &mut self {
            MeasurementModel::Linear {
                matrix,
                ndim_meas,
                pseudo_inverse,
                ..
            } => {
                if inverse.len() != matrix.len() {
                    let cols = matrix.len() / *ndim_meas;
                    return Err(ModelError::shape(
                        "inverse",
                        format!("must be ({cols}, {ndim_meas}), got {} values", inverse.len()),
                    ));
                }
                *pseudo_inverse = Some(inverse.to_vec());
            }
            MeasurementModel::BearingRange { inverse_rotation, .. } => {
                let inverse: [f64; 9] = inverse
                    .try_into()
                    .map_err(|_| ModelError::shape("inverse", format!("must be 3×3, got {} values", inverse.len())))?;
                *inverse_rotation = Some(inverse);
            }
        }
        Ok(self)
    }

    /// Number of measured values per detection.
    pub fn ndim_meas(&self) -> usize {
        match self {
            MeasurementModel::Linear { ndim_meas, .. } => *ndim_meas,
            MeasurementModel::BearingRange { .. } => 2,
        }
    }

    /// The noise covariance `R` (m×m, row-major).
    pub fn noise(&self) -> &[f64] {
        match self {
            MeasurementModel::Linear { noise, .. } => noise,
            MeasurementModel::BearingRange { noise, .. } => noise,
        }
    }

    /// `R` as a matrix.
    pub fn noise_matrix(&self) -> DMatrix<f64> {
        let m = self.ndim_meas();
        DMatrix::from_row_slice(m, m, self.noise())
    }

    /// The measurement row holding an angle (wrapped in differences), if any.
    pub fn angle_row(&self) -> Option<usize> {
        match self {
            MeasurementModel::Linear { .. } => None,
            MeasurementModel::BearingRange { .. } => Some(0),
        }
    }

    /// Whether the model reads states of `dim` values.
    pub fn check_dim(&self, dim: usize) -> Result<()> {
        match self {
            MeasurementModel::Linear { matrix, ndim_meas, .. } if matrix.len() != ndim_meas * dim => {
                Err(ModelError::shape(
                    "model",
                    format!(
                        "the measurement matrix has {} columns, the states {dim}",
                        matrix.len() / ndim_meas
                    ),
                ))
            }
            MeasurementModel::BearingRange { mapping, .. } if mapping.iter().any(|&m| m >= dim) => {
                Err(ModelError::shape(
                    "model",
                    format!("mapping {mapping:?} is out of range for states of {dim} values"),
                ))
            }
            _ => Ok(()),
        }
    }

    /// Predicted measurement `z` (m) and measurement matrix or Jacobian `h` (m×D, row-major)
    /// at the state `x` (D).
    pub fn linearise(&self, x: &[f64], z: &mut [f64], h: &mut [f64]) {
        match self {
            MeasurementModel::Linear { matrix, ndim_meas, .. } => {
                super::linalg::matvec(matrix, x, *ndim_meas, x.len(), z);
                h.copy_from_slice(matrix);
            }
            MeasurementModel::BearingRange { jacobian, .. } => {
                let (r0, r1) = self.rotated(x[self.mapping()[0]], x[self.mapping()[1]]);
                let (phi, rho) = polar(r0, r1);
                z[0] = phi;
                z[1] = rho;
                if !(*jacobian == Jacobian::Analytic && self.analytic_jacobian(r0, r1, x.len(), h)) {
                    self.finite_difference_jacobian(x, h);
                }
            }
        }
    }

    /// [`linearise`](Self::linearise) into nalgebra types.
    pub fn linearised(&self, x: &DVector<f64>) -> (DVector<f64>, DMatrix<f64>) {
        let (m, d) = (self.ndim_meas(), x.len());
        let mut z = vec![0.0; m];
        let mut h = vec![0.0; m * d];
        self.linearise(x.as_slice(), &mut z, &mut h);
        (DVector::from_vec(z), DMatrix::from_row_slice(m, d, &h))
    }

    /// `a − b` of two measurements, the bearing row wrapped as Stone Soup's angle types do.
    pub fn difference(&self, a: &[f64], b: &[f64], out: &mut [f64]) {
        for i in 0..out.len() {
            out[i] = a[i] - b[i];
        }
        if let Some(row) = self.angle_row() {
            out[row] = mod_bearing(out[row]);
        }
    }

    fn mapping(&self) -> [usize; 2] {
        match self {
            MeasurementModel::BearingRange { mapping, .. } => *mapping,
            MeasurementModel::Linear { .. } => [0, 0],
        }
    }

    /// `(r₀, r₁)` of one state, as NumPy's 3×3 by 3×1 product rounds it.
    fn rotated(&self, xa: f64, xb: f64) -> (f64, f64) {
        let MeasurementModel::BearingRange { offset, rotation, .. } = self else {
            return (f64::NAN, f64::NAN); // (only called for a bearing–range model)
        };
        let a = xa - offset[0];
        let b = xb - offset[1];
        (
            rotation[0].mul_add(a, rotation[1] * b),
            rotation[3].mul_add(a, rotation[4] * b),
        )
    }

    /// Stone Soup's forward finite difference: the perturbed states `x + δᵢ eᵢ` and `x`
    /// itself through the model function as NumPy's 3×3 by 3×(D+1) product rounds it.
    fn finite_difference_jacobian(&self, x: &[f64], h: &mut [f64]) {
        let MeasurementModel::BearingRange {
            mapping,
            offset,
            rotation,
            ..
        } = self
        else {
            return;
        };
        let through = |xa: f64, xb: f64| {
            let a = xa - offset[0];
            let b = xb - offset[1];
            polar(
                rotation[1].mul_add(b, rotation[0] * a),
                rotation[4].mul_add(b, rotation[3] * a),
            )
        };
        let (phi, rho) = through(x[mapping[0]] + 0.0, x[mapping[1]] + 0.0);
        let dim = x.len();
        for i in 0..dim {
            let mut delta = 1e8 * spacing(x[i]);
            if delta < 1e-8 {
                delta = 1e-8;
            }
            let at = |k: usize| if k == i { x[k] + delta } else { x[k] + 0.0 };
            let (phi_i, rho_i) = through(at(mapping[0]), at(mapping[1]));
            h[i] = mod_bearing(phi_i - phi) / delta;
            h[dim + i] = (rho_i - rho) / delta;
        }
    }

    /// The closed form at the sensor-frame point `(r₀, r₁)`; false (h untouched) at `ρ = 0`.
    fn analytic_jacobian(&self, r0: f64, r1: f64, dim: usize, h: &mut [f64]) -> bool {
        let MeasurementModel::BearingRange { mapping, rotation, .. } = self else {
            return false;
        };
        let rho = r0.hypot(r1);
        if rho == 0.0 {
            return false;
        }
        let (cos, sin) = (r0 / rho, r1 / rho);
        h.iter_mut().for_each(|v| *v = 0.0);
        for (k, &column) in mapping.iter().enumerate() {
            let (along_x, along_y) = (rotation[k], rotation[3 + k]);
            h[column] += (cos * along_y - sin * along_x) / rho;
            h[dim + column] += cos * along_x + sin * along_y;
        }
        true
    }
}

/// `(mod_bearing(0 + atan2(r₁, r₀)), 0 + √(r₀² + r₁²))`, as the typed model function adds
/// its zero `Bearing` and float.
fn polar(r0: f64, r1: f64) -> (f64, f64) {
    (mod_bearing(0.0 + r1.atan2(r0)), 0.0 + (r0 * r0 + r1 * r1).sqrt())
}

#[cfg(test)]
mod tests;
