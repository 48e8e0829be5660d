//! Python binding of the Kalman filters' measurement models ([`crate::kalman`]):
//! `MeasurementModel`, taken by the GM-PHD scan, the JPDA scan and the M-of-N initiator.
//! Arguments are converted as in the parent module (C-contiguous float64, errors naming the
//! argument).

use super::{borrow, shape_error, slice, to_py, value_error};
use crate::kalman::{Jacobian, MeasurementModel};
use numpy::{PyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;

/// A measurement model of the scan cores (see `crate::kalman::measurement`).
#[pyclass(name = "MeasurementModel", module = "ctxmodels._core", frozen)]
pub struct PyMeasurementModel(pub(super) MeasurementModel);

fn matrix_of(array: &Bound<'_, PyArray2<f64>>, argument: &str) -> PyResult<(Vec<f64>, usize, usize)> {
    let (rows, cols) = (array.shape()[0], array.shape()[1]);
    let view = borrow(array, argument)?;
    // (a measurement model's matrix: as large as the array given)
    Ok((slice(&view, argument)?.to_vec(), rows, cols))
}

#[pymethods]
impl PyMeasurementModel {
    /// A linear Gaussian model: `matrix` (m, D), `noise_covar` (m, m); `pseudo_inverse`
    /// (D, m), the `H⁺` of new tracks (default: the core's SVD).
    #[staticmethod]
    #[pyo3(signature = (matrix, noise_covar, pseudo_inverse = None))]
    fn linear(
        matrix: Bound<'_, PyArray2<f64>>,
        noise_covar: Bound<'_, PyArray2<f64>>,
        pseudo_inverse: Option<Bound<'_, PyArray2<f64>>>,
    ) -> PyResult<Self> {
        let (h, rows, cols) = matrix_of(&matrix, "matrix")?;
        let (r, r_rows, r_cols) = matrix_of(&noise_covar, "noise_covar")?;
        if (r_rows, r_cols) != (rows, rows) {
            return Err(shape_error(
                "noise_covar",
                format_args!("must have shape ({rows}, {rows}) to match matrix, got ({r_rows}, {r_cols})"),
            ));
        }
        let model = MeasurementModel::linear(&h, rows, cols, &r).map_err(to_py)?;
        with_inverse(model, pseudo_inverse, "pseudo_inverse", (cols, rows))
    }

    /// A 2-D bearing–range model (Stone Soup's `CartesianToBearingRange`): state indices
    /// `mapping` of x and y, `translation_offset` (x, y), `rotation_matrix` (3, 3),
    /// `noise_covar` (2, 2); `jacobian` 'finite-difference' (Stone Soup's) or 'analytic';
    /// `inverse_rotation_matrix` (3, 3), the inverse function's `R⁻¹` (default: the core's
    /// inverse of `rotation_matrix`; Stone Soup's is NumPy's).
    #[staticmethod]
    #[pyo3(signature = (mapping, translation_offset, rotation_matrix, noise_covar, jacobian = "finite-difference", inverse_rotation_matrix = None))]
    fn bearing_range(
        mapping: (i64, i64),
        translation_offset: (f64, f64),
        rotation_matrix: Bound<'_, PyArray2<f64>>,
        noise_covar: Bound<'_, PyArray2<f64>>,
        jacobian: &str,
        inverse_rotation_matrix: Option<Bound<'_, PyArray2<f64>>>,
    ) -> PyResult<Self> {
        let index = |i: i64| {
            usize::try_from(i)
                .map_err(|_| value_error("mapping", format_args!("indices must be >= 0, got {mapping:?}")))
        };
        let mapping = [index(mapping.0)?, index(mapping.1)?];
        let jacobian = match jacobian {
            "finite-difference" => Jacobian::FiniteDifference,
            "analytic" => Jacobian::Analytic,
            other => {
                return Err(value_error(
                    "jacobian",
                    format_args!("must be 'finite-difference' or 'analytic', got {other:?}"),
                ))
            }
        };
        let (rotation, r_rows, r_cols) = matrix_of(&rotation_matrix, "rotation_matrix")?;
        if (r_rows, r_cols) != (3, 3) {
            return Err(shape_error(
                "rotation_matrix",
                format_args!("must have shape (3, 3), got ({r_rows}, {r_cols})"),
            ));
        }
        let (noise, n_rows, n_cols) = matrix_of(&noise_covar, "noise_covar")?;
        if (n_rows, n_cols) != (2, 2) {
            return Err(shape_error(
                "noise_covar",
                format_args!("must have shape (2, 2), got ({n_rows}, {n_cols})"),
            ));
        }
        let offset = [translation_offset.0, translation_offset.1];
        let model = MeasurementModel::bearing_range(mapping, offset, &rotation, &noise, jacobian).map_err(to_py)?;
        with_inverse(model, inverse_rotation_matrix, "inverse_rotation_matrix", (3, 3))
    }

    /// Number of measured values per detection.
    #[getter]
    fn ndim_meas(&self) -> usize {
        self.0.ndim_meas()
    }
}

/// `model` with the inverse the caller gave (`argument`, of `shape`), if any.
fn with_inverse(
    model: MeasurementModel,
    inverse: Option<Bound<'_, PyArray2<f64>>>,
    argument: &str,
    shape: (usize, usize),
) -> PyResult<PyMeasurementModel> {
    let Some(inverse) = inverse else {
        return Ok(PyMeasurementModel(model));
    };
    let (values, rows, cols) = matrix_of(&inverse, argument)?;
    if (rows, cols) != shape {
        return Err(shape_error(
            argument,
            format_args!("must have shape {shape:?}, got ({rows}, {cols})"),
        ));
    }
    if let Some(i) = values.iter().position(|v| !v.is_finite()) {
        return Err(value_error(argument, format_args!("element {i} is not finite")));
    }
    Ok(PyMeasurementModel(model.with_inverse(&values).map_err(to_py)?))
}

pub(super) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyMeasurementModel>()?;
    Ok(())
}
