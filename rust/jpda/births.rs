//! The M-of-N initiator's new holding tracks: what Stone Soup's `SimpleMeasurementInitiator`
//! builds from each detection that no holding track took.
//!
//! For a detection `z` measured by a model with mapped state indices `m` (the columns its
//! matrix or Jacobian reads), a prior `(x₀, P₀)` and a diagonal load `l`:
//!
//! * `x₀'` and `P₀'` are the prior with the mapped entries (rows and columns of `P₀`) set
//!   to zero;
//! * **linear** `z = H x + v`: `x = x₀' + H⁺ z` and `J = H`;
//! * **bearing–range**: the inverse of the measurement function, `(x_{m₀}, x_{m₁}) =
//!   (R⁻¹ [ρ cos φ, ρ sin φ, 0]ᵀ)_{0,1} + t` and zeros elsewhere, is `u`; `x = x₀' + u` and
//!   `J` is the model's Jacobian at `u`, as the scans linearise (see [`crate::kalman`]);
//! * `P = (J⁺ R J⁺ᵀ + P₀') + l I`, with `J⁺` the Moore–Penrose pseudo-inverse (singular
//!   values below `10⁻¹⁵ σ_max` dropped, as NumPy's `pinv`).
//!
//! The mean is Stone Soup's to the bit when the model carries NumPy's `H⁺` or `R⁻¹`
//! ([`MeasurementModel::with_inverse`]); the covariance is Stone Soup's to rounding with a
//! linear model or the closed-form Jacobian (the Jacobian's pseudo-inverse comes from
//! nalgebra's SVD where NumPy calls LAPACK's), and to ~10⁻⁵ relative with the finite
//! difference, whose bearing row divides differences of `atan2` by steps of 10⁻⁸: NumPy's own
//! `arctan2` and the C library's differ in the last bit for a few per cent of arguments.

use super::{check_detections, check_finite, push_row_major};
use crate::error::{ModelError, Result};
use crate::kalman::MeasurementModel;
use nalgebra::{DMatrix, DVector, Matrix3, Vector3, SVD};

/// The prior of every new track: mean (D), covariance (D×D, row-major), diagonal load.
#[derive(Debug, Clone, Copy)]
pub struct BirthPrior<'a> {
    pub mean: &'a [f64],
    pub covar: &'a [f64],
    pub diag_load: f64,
}

/// New tracks' means (M×D) and covariances (M×D×D), row-major, for `detections` (M×m),
/// detection `j` measured by `models[model_index[j]]`.
pub fn initiator_births(
    models: &[MeasurementModel],
    detections: &[f64],
    model_index: &[usize],
    prior: BirthPrior,
) -> Result<(Vec<f64>, Vec<f64>)> {
    let dim = prior.mean.len();
    if dim == 0 || prior.covar.len() != dim * dim {
        return Err(ModelError::shape(
            "prior_covar",
            format!("must be ({dim}, {dim}) to match a prior mean of {dim} values"),
        ));
    }
    check_finite("prior_mean", prior.mean)?;
    check_finite("prior_covar", prior.covar)?;
    if !prior.diag_load.is_finite() {
        return Err(ModelError::invalid(
            "diag_load",
            format!("must be finite, got {}", prior.diag_load),
        ));
    }
    let m = check_detections(models, dim, detections, model_index)?;
    let prepared = models
        .iter()
        .map(|model| Prepared::new(model, dim))
        .collect::<Result<Vec<_>>>()?;
    let mut means = Vec::with_capacity(model_index.len() * dim);
    let mut covars = Vec::with_capacity(model_index.len() * dim * dim);
    for (j, &g) in model_index.iter().enumerate() {
        let z = &detections[j * m..(j + 1) * m];
        let (mean, covar) = prepared[g].birth(&models[g], z, prior)?;
        means.extend(mean.iter());
        push_row_major(&mut covars, &covar);
    }
    Ok((means, covars))
}

/// What a model's births share: the mapped indices, and `H⁺` (linear) or `R⁻¹`
/// (bearing–range).
struct Prepared {
    mapped: Vec<usize>,
    inverse: Inverse,
}

enum Inverse {
    Linear(DMatrix<f64>),
    Rotation(Matrix3<f64>),
}

impl Prepared {
    fn new(model: &MeasurementModel, dim: usize) -> Result<Self> {
        match model {
            MeasurementModel::Linear {
                matrix,
                ndim_meas,
                pseudo_inverse,
                ..
            } => {
                let matrix = DMatrix::from_row_slice(*ndim_meas, dim, matrix);
                let mapped = (0..dim)
                    .filter(|&c| matrix.column(c).iter().any(|&v| v != 0.0))
                    .collect();
                let inverse = match pseudo_inverse {
                    Some(given) => DMatrix::from_row_slice(dim, *ndim_meas, given),
                    None => pseudo_inverse_of("matrix", matrix)?,
                };
                Ok(Prepared {
                    mapped,
                    inverse: Inverse::Linear(inverse),
                })
            }
            MeasurementModel::BearingRange {
                mapping,
                inverse_rotation,
                ..
            } => {
                let inverse = inverse_rotation.ok_or_else(|| {
                    ModelError::invalid("rotation_matrix", "is singular, so the model has no inverse function")
                })?;
                Ok(Prepared {
                    mapped: mapping.to_vec(),
                    inverse: Inverse::Rotation(Matrix3::from_row_slice(&inverse)),
                })
            }
        }
    }

    fn birth(&self, model: &MeasurementModel, z: &[f64], prior: BirthPrior) -> Result<(DVector<f64>, DMatrix<f64>)> {
        let dim = prior.mean.len();
        let mut mean = DVector::from_column_slice(prior.mean);
        let mut covar = DMatrix::from_row_slice(dim, dim, prior.covar);
        for &i in &self.mapped {
            mean[i] = 0.0;
            covar.row_mut(i).fill(0.0);
            covar.column_mut(i).fill(0.0);
        }
        let (state, jacobian_inverse) = match &self.inverse {
            Inverse::Linear(inverse) => (inverse * DVector::from_column_slice(z), inverse.clone()),
            Inverse::Rotation(inverse) => {
                let (phi, rho) = (z[0], z[1]);
                let xyz = inverse * Vector3::new(rho * phi.cos(), rho * phi.sin(), 0.0);
                let mut state = DVector::zeros(dim);
                let (mapping, offset) = match model {
                    MeasurementModel::BearingRange { mapping, offset, .. } => (mapping, offset),
                    MeasurementModel::Linear { .. } => {
                        unreachable!("a rotation is prepared from a bearing–range model")
                    }
                };
                state[mapping[0]] = xyz[0] + offset[0];
                state[mapping[1]] = xyz[1] + offset[1];
                let jacobian = model.linearised(&state).1;
                (state, pseudo_inverse_of("jacobian", jacobian)?)
            }
        };
        mean += state;
        let spread = (&jacobian_inverse * model.noise_matrix()) * jacobian_inverse.transpose();
        let mut covar = spread + covar;
        for i in 0..dim {
            covar[(i, i)] += prior.diag_load;
        }
        Ok((mean, covar))
    }
}

/// The Moore–Penrose pseudo-inverse, singular values up to `10⁻¹⁵ σ_max` taken as zero.
fn pseudo_inverse_of(argument: &'static str, matrix: DMatrix<f64>) -> Result<DMatrix<f64>> {
    if let Some(i) = matrix.iter().position(|v| !v.is_finite()) {
        return Err(ModelError::invalid(
            argument,
            format!("element {i} is not finite, so it has no pseudo-inverse"),
        ));
    }
    let svd = SVD::new(matrix, true, true);
    let largest = svd.singular_values.iter().copied().fold(0.0, f64::max);
    svd.pseudo_inverse(1e-15 * largest)
        .map_err(|why| ModelError::invalid(argument, format!("has no pseudo-inverse: {why}")))
}
