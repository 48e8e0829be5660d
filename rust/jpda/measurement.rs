//! The JPDA scan's measurement model: linear Gaussian, or Stone Soup's 2-D
//! `CartesianToBearingRange` with its finite-difference or the closed-form Jacobian.

use super::check_finite;
// The GM-PHD's bearing helpers, held against their definitions in
// tests::shared_bearing_helpers_are_the_jpda_formulae.
use crate::error::{ModelError, Result};
pub use crate::gmphd::measurement::mod_bearing;
pub(super) use crate::gmphd::measurement::spacing;
use nalgebra::{DMatrix, DVector, Matrix3};

/// How the bearing–range model is linearised: the GM-PHD's choice, the same two kinds.
pub use crate::gmphd::Jacobian;

/// The measurement model of a scan's detections.
#[derive(Debug, Clone)]
pub enum MeasurementModel {
    /// `z = H x + v`, `v ~ N(0, R)`; `H⁺` of new tracks when the caller gives it.
    Linear {
        matrix: DMatrix<f64>,
        noise: DMatrix<f64>,
        pseudo_inverse: Option<DMatrix<f64>>,
    },
    /// Stone Soup's `CartesianToBearingRange` in 2-D: `r = R·[x_{m₀} − t₀, x_{m₁} − t₁, 0]`,
    /// `z = [atan2(r₁, r₀), √(r₀² + r₁²)]`, bearing wrapped to `[−π, π)`.
    BearingRange {
        mapping: [usize; 2],
        offset: [f64; 2],
        rotation: [[f64; 3]; 3],
        noise: DMatrix<f64>,
        jacobian: Jacobian,
        /// `R⁻¹` of the inverse function (new tracks), None if `R` is singular.
        inverse_rotation: Option<[[f64; 3]; 3]>,
    },
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
            matrix: DMatrix::from_row_slice(rows, cols, matrix),
            noise: DMatrix::from_row_slice(rows, rows, noise),
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
        if rotation.len() != 9 {
            return Err(ModelError::shape(
                "rotation_matrix",
                format!("must be 3×3, got {} values", rotation.len()),
            ));
        }
        if noise.len() != 4 {
            return Err(ModelError::shape(
                "noise_covar",
                format!("must be 2×2, got {} values", noise.len()),
            ));
        }
        if mapping[0] == mapping[1] {
            return Err(ModelError::invalid(
                "mapping",
                format!("x and y must be different state indices, got {mapping:?}"),
            ));
        }
        check_finite("translation_offset", &offset)?;
        check_finite("rotation_matrix", rotation)?;
        check_finite("noise_covar", noise)?;
        let r = |i: usize, j: usize| rotation[3 * i + j];
        let rotation = [
            [r(0, 0), r(0, 1), r(0, 2)],
            [r(1, 0), r(1, 1), r(1, 2)],
            [r(2, 0), r(2, 1), r(2, 2)],
        ];
        let inverse_rotation = Matrix3::from_fn(|i, j| rotation[i][j])
            .try_inverse()
            .map(|inverse| std::array::from_fn(|i| std::array::from_fn(|j| inverse[(i, j)])));
        Ok(MeasurementModel::BearingRange {
            mapping,
            offset,
            rotation,
            noise: DMatrix::from_row_slice(2, 2, noise),
            jacobian,
            inverse_rotation,
        })
    }

    /// The model with the inverse of its measurement as the caller computes it: `H⁺`
    /// (row-major D×m) of a linear model, `R⁻¹` (row-major 3×3) of a bearing–range one.
    /// Stone Soup computes both with NumPy (`pinv`, `inv`); given them, a new track's mean is
    /// Stone Soup's to the bit (and so is a finite-difference Jacobian there, which one ulp of
    /// the mean moves by ~10⁻⁵).
    pub fn with_inverse(self, inverse: &[f64]) -> Result<Self> {
        check_finite("inverse", inverse)?;
        match self {
            MeasurementModel::Linear { matrix, noise, .. } => {
                let (rows, cols) = matrix.shape();
                if inverse.len() != rows * cols {
                    return Err(ModelError::shape(
                        "inverse",
                        format!("must be ({cols}, {rows}), got {} values", inverse.len()),
                    ));
                }
                Ok(MeasurementModel::Linear {
                    matrix,
                    noise,
                    pseudo_inverse: Some(DMatrix::from_row_slice(cols, rows, inverse)),
                })
            }
            MeasurementModel::BearingRange {
                mapping,
                offset,
                rotation,
                noise,
                jacobian,
                ..
            } => {
                if inverse.len() != 9 {
                    return Err(ModelError::shape(
                        "inverse",
                        format!("must be 3×3, got {} values", inverse.len()),
                    ));
                }
                Ok(MeasurementModel::BearingRange {
                    mapping,
                    offset,
                    rotation,
                    noise,
                    jacobian,
                    inverse_rotation: Some(std::array::from_fn(|i| std::array::from_fn(|j| inverse[3 * i + j]))),
                })
            }
        }
    }

    /// Number of measured values per detection.
    pub fn ndim_meas(&self) -> usize {
        match self {
            MeasurementModel::Linear { matrix, .. } => matrix.nrows(),
            MeasurementModel::BearingRange { .. } => 2,
        }
    }

    pub(super) fn noise(&self) -> &DMatrix<f64> {
        match self {
            MeasurementModel::Linear { noise, .. } | MeasurementModel::BearingRange { noise, .. } => noise,
        }
    }

    /// The measurement row holding an angle (wrapped in differences), if any.
    pub(super) fn angle_row(&self) -> Option<usize> {
        match self {
            MeasurementModel::Linear { .. } => None,
            MeasurementModel::BearingRange { .. } => Some(0),
        }
    }

    pub(super) fn check_dim(&self, dim: usize) -> Result<()> {
        match self {
            MeasurementModel::Linear { matrix, .. } if matrix.ncols() != dim => Err(ModelError::shape(
                "model",
                format!(
                    "the measurement matrix has {} columns, the states {dim}",
                    matrix.ncols()
                ),
            )),
            MeasurementModel::BearingRange { mapping, .. } if mapping.iter().any(|&m| m >= dim) => {
                Err(ModelError::shape(
                    "model",
                    format!("mapping {mapping:?} is out of range for states of {dim} values"),
                ))
            }
            _ => Ok(()),
        }
    }

    /// Predicted measurement `h(x)` and measurement matrix / Jacobian at `x`.
    pub fn linearise(&self, x: &DVector<f64>) -> (DVector<f64>, DMatrix<f64>) {
        match self {
            MeasurementModel::Linear { matrix, .. } => (matrix * x, matrix.clone()),
            MeasurementModel::BearingRange {
                mapping,
                offset,
                rotation,
                jacobian,
                ..
            } => {
                let dim = x.len();
                // One column through a 3×3 @ 3×1 product, as NumPy's matrix-vector kernel
                // rounds it here (a fused multiply-add onto the second term).
                let a = x[mapping[0]] - offset[0];
                let b = x[mapping[1]] - offset[1];
                let r0 = rotation[0][0].mul_add(a, rotation[0][1] * b);
                let r1 = rotation[1][0].mul_add(a, rotation[1][1] * b);
                let rho = (r0 * r0 + r1 * r1).sqrt();
                let phi = r1.atan2(r0);
                let z = DVector::from_vec(vec![mod_bearing(0.0 + phi), 0.0 + rho]);
                let mut h = DMatrix::zeros(2, dim);
                match jacobian {
                    Jacobian::Analytic => {
                        let rho2 = r0 * r0 + r1 * r1;
                        for k in 0..2 {
                            h[(0, mapping[k])] = (r0 * rotation[1][k] - r1 * rotation[0][k]) / rho2;
                            h[(1, mapping[k])] = (r0 * rotation[0][k] + r1 * rotation[1][k]) / rho;
                        }
                    }
                    Jacobian::FiniteDifference => {
                        // Columns 0..D of Stone Soup's perturbed states (x + δ_i e_i) and column D
                        // (x itself), through the model function as NumPy's matrix-matrix kernel
                        // rounds a 3×3 @ 3×(D+1) product (a fused multiply-add onto the first term).
                        let bearing_range = |state_a: f64, state_b: f64| {
                            let a = state_a - offset[0];
                            let b = state_b - offset[1];
                            let r0 = rotation[0][1].mul_add(b, rotation[0][0] * a);
                            let r1 = rotation[1][1].mul_add(b, rotation[1][0] * a);
                            (mod_bearing(0.0 + r1.atan2(r0)), 0.0 + (r0 * r0 + r1 * r1).sqrt())
                        };
                        let (base_phi, base_rho) = bearing_range(x[mapping[0]] + 0.0, x[mapping[1]] + 0.0);
                        for i in 0..dim {
                            let mut delta = 1e8 * spacing(x[i]);
                            if delta < 1e-8 {
                                delta = 1e-8;
                            }
                            let at = |k: usize| if k == i { x[k] + delta } else { x[k] + 0.0 };
                            let (phi_i, rho_i) = bearing_range(at(mapping[0]), at(mapping[1]));
                            h[(0, i)] = mod_bearing(phi_i - base_phi) / delta;
                            h[(1, i)] = (rho_i - base_rho) / delta;
                        }
                    }
                }
                (z, h)
            }
        }
    }
}
