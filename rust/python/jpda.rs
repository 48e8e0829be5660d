//! Python binding of the whole-scan JPDA core ([`crate::jpda`]): `JPDAMeasurementModel`,
//! `jpda_predict`, `jpda_scan` and `jpda_marginals` (the initiator's scan: `super::initiation`). Arguments are converted as in the parent
//! module (C-contiguous float64, fallible borrows, errors naming the argument); the work runs
//! with the GIL released and a panic becomes a RuntimeError.

use super::{borrow, detached, slice, to_py, value_error};
use crate::jpda::{self, Jacobian, MeasurementModel, ScanInput};
use numpy::{PyArray1, PyArray2, PyArray3, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;

#[pyclass(name = "JPDAMeasurementModel", module = "ctxmodels._core", frozen)]
pub struct PyJPDAMeasurementModel(pub(super) MeasurementModel);

fn matrix_of(array: &Bound<'_, PyArray2<f64>>, argument: &str) -> PyResult<(Vec<f64>, usize, usize)> {
    let (rows, cols) = (array.shape()[0], array.shape()[1]);
    let view = borrow(array, argument)?;
    // (a measurement model's matrix: as large as the array given)
    Ok((slice(&view, argument)?.to_vec(), rows, cols))
}

#[pymethods]
impl PyJPDAMeasurementModel {
    /// A linear Gaussian model: `matrix` (m, D), `noise_covar` (m, m).
    #[staticmethod]
    fn linear(matrix: Bound<'_, PyArray2<f64>>, noise_covar: Bound<'_, PyArray2<f64>>) -> PyResult<Self> {
        let (h, rows, cols) = matrix_of(&matrix, "matrix")?;
        let (r, r_rows, r_cols) = matrix_of(&noise_covar, "noise_covar")?;
        if (r_rows, r_cols) != (rows, rows) {
            return Err(value_error("noise_covar", format_args!("must have shape ({rows}, {rows}) to match matrix, got ({r_rows}, {r_cols})")));
        }
        Ok(PyJPDAMeasurementModel(MeasurementModel::linear(&h, rows, cols, &r).map_err(to_py)?))
    }

    /// A 2-D bearing–range model (Stone Soup's `CartesianToBearingRange`): state indices
    /// `mapping` of x and y, `translation_offset` (x, y), `rotation_matrix` (3, 3),
    /// `noise_covar` (2, 2); `jacobian` 'finite-difference' (Stone Soup's) or 'analytic'.
    #[staticmethod]
    #[pyo3(signature = (mapping, translation_offset, rotation_matrix, noise_covar, jacobian = "finite-difference"))]
    fn bearing_range(
        mapping: (i64, i64),
        translation_offset: (f64, f64),
        rotation_matrix: Bound<'_, PyArray2<f64>>,
        noise_covar: Bound<'_, PyArray2<f64>>,
        jacobian: &str,
    ) -> PyResult<Self> {
        let index = |i: i64| usize::try_from(i).map_err(|_| value_error("mapping", format_args!("indices must be >= 0, got {mapping:?}")));
        let mapping = [index(mapping.0)?, index(mapping.1)?];
        let jacobian = match jacobian {
            "finite-difference" => Jacobian::FiniteDifference,
            "analytic" => Jacobian::Analytic,
            other => return Err(value_error("jacobian", format_args!("must be 'finite-difference' or 'analytic', got {other:?}"))),
        };
        let (rotation, r_rows, r_cols) = matrix_of(&rotation_matrix, "rotation_matrix")?;
        if (r_rows, r_cols) != (3, 3) {
            return Err(value_error("rotation_matrix", format_args!("must have shape (3, 3), got ({r_rows}, {r_cols})")));
        }
        let (noise, n_rows, n_cols) = matrix_of(&noise_covar, "noise_covar")?;
        if (n_rows, n_cols) != (2, 2) {
            return Err(value_error("noise_covar", format_args!("must have shape (2, 2), got ({n_rows}, {n_cols})")));
        }
        let offset = [translation_offset.0, translation_offset.1];
        Ok(PyJPDAMeasurementModel(MeasurementModel::bearing_range(mapping, offset, &rotation, &noise, jacobian).map_err(to_py)?))
    }

    /// Number of measured values per detection.
    #[getter]
    fn ndim_meas(&self) -> usize {
        self.0.ndim_meas()
    }
}

pub(super) fn array2<'py>(py: Python<'py>, data: Vec<f64>, rows: usize, cols: usize) -> PyResult<Bound<'py, PyArray2<f64>>> {
    PyArray1::from_vec(py, data).reshape([rows, cols])
}

pub(super) fn array3<'py>(py: Python<'py>, data: Vec<f64>, n: usize, rows: usize, cols: usize) -> PyResult<Bound<'py, PyArray3<f64>>> {
    PyArray1::from_vec(py, data).reshape([n, rows, cols])
}

pub(super) fn check_covars(means: &Bound<'_, PyArray2<f64>>, covars: &Bound<'_, PyArray3<f64>>) -> PyResult<(usize, usize)> {
    let (n, dim) = (means.shape()[0], means.shape()[1]);
    let shape = covars.shape();
    if shape != [n, dim, dim] {
        return Err(value_error("covars", format_args!("must have shape ({n}, {dim}, {dim}) to match means, got {shape:?}")));
    }
    Ok((n, dim))
}

/// Predicted means (T, D) and covariances (T, D, D).
type Predicted<'py> = (Bound<'py, PyArray2<f64>>, Bound<'py, PyArray3<f64>>);

/// Kalman prediction of `means` (T, D) / `covars` (T, D, D): track t with the transition
/// `transition_index[t]` of `transition_matrices` / `transition_covars` (K, D, D).
#[pyfunction]
fn jpda_predict<'py>(
    py: Python<'py>,
    means: Bound<'py, PyArray2<f64>>,
    covars: Bound<'py, PyArray3<f64>>,
    transition_index: Vec<i64>,
    transition_matrices: Bound<'py, PyArray3<f64>>,
    transition_covars: Bound<'py, PyArray3<f64>>,
) -> PyResult<Predicted<'py>> {
    let (n, dim) = check_covars(&means, &covars)?;
    if transition_index.len() != n {
        return Err(value_error("transition_index", format_args!("must have {n} entries (one per track), got {}", transition_index.len())));
    }
    for (name, array) in [("transition_matrices", &transition_matrices), ("transition_covars", &transition_covars)] {
        let shape = array.shape();
        if shape[1] != dim || shape[2] != dim {
            return Err(value_error(name, format_args!("must have shape (K, {dim}, {dim}), got {shape:?}")));
        }
    }
    let mut index = crate::memory::with_room("transition_index", transition_index.len()).map_err(to_py)?;
    for (t, &k) in transition_index.iter().enumerate() {
        index.push(usize::try_from(k).map_err(|_| value_error("transition_index", format_args!("row {t}: must be >= 0, got {k}")))?);
    }
    let means = borrow(&means, "means")?;
    let m = slice(&means, "means")?;
    let covars = borrow(&covars, "covars")?;
    let c = slice(&covars, "covars")?;
    let matrices = borrow(&transition_matrices, "transition_matrices")?;
    let f = slice(&matrices, "transition_matrices")?;
    let noises = borrow(&transition_covars, "transition_covars")?;
    let q = slice(&noises, "transition_covars")?;
    let (x, p) = detached(py, || jpda::predict(dim, m, c, &index, f, q))?;
    Ok((array2(py, x, n, dim)?, array3(py, p, n, dim, dim)?))
}

/// One JPDA scan (see `ctxmodels.stonesoup.array_jpda`): predicted `means` (T, D) and
/// `covars` (T, D, D), `detections` (M, m) of `model`, P_D per track, λ per detection.
#[pyfunction]
#[pyo3(signature = (model, means, covars, detections, prob_detect, clutter_density, prob_gate, gate_threshold, include_all = false, *, force_symmetric = false))]
#[allow(clippy::too_many_arguments)]
fn jpda_scan<'py>(
    py: Python<'py>,
    model: &PyJPDAMeasurementModel,
    means: Bound<'py, PyArray2<f64>>,
    covars: Bound<'py, PyArray3<f64>>,
    detections: Bound<'py, PyArray2<f64>>,
    prob_detect: Bound<'py, PyArray1<f64>>,
    clutter_density: Bound<'py, PyArray1<f64>>,
    prob_gate: f64,
    gate_threshold: f64,
    include_all: bool,
    force_symmetric: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let (n, dim) = check_covars(&means, &covars)?;
    let meas_dim = model.0.ndim_meas();
    let (n_dets, det_cols) = (detections.shape()[0], detections.shape()[1]);
    if det_cols != meas_dim && n_dets > 0 {
        return Err(value_error("detections", format_args!("must have {meas_dim} columns (the model's measurement size), got {det_cols}")));
    }
    if prob_detect.len() != n {
        return Err(value_error("prob_detect", format_args!("must have {n} entries (one per track), got {}", prob_detect.len())));
    }
    if clutter_density.len() != n_dets {
        return Err(value_error("clutter_density", format_args!("must have {n_dets} entries (one per detection), got {}", clutter_density.len())));
    }
    let means = borrow(&means, "means")?;
    let m = slice(&means, "means")?;
    let covars = borrow(&covars, "covars")?;
    let c = slice(&covars, "covars")?;
    let detections = borrow(&detections, "detections")?;
    let z = slice(&detections, "detections")?;
    let prob_detect = borrow(&prob_detect, "prob_detect")?;
    let pd = slice(&prob_detect, "prob_detect")?;
    let clutter_density = borrow(&clutter_density, "clutter_density")?;
    let lam = slice(&clutter_density, "clutter_density")?;
    let input = ScanInput { dim, means: m, covars: c, detections: z, prob_detect: pd, clutter: lam, prob_gate, gate_threshold, include_all, force_symmetric };
    let core = &model.0;
    let out = detached(py, || jpda::scan(core, &input))?;
    let result = PyDict::new(py);
    let (t, k) = (out.tracks, out.detections);
    result.set_item("means", array2(py, out.means, t, dim)?)?;
    result.set_item("covars", array3(py, out.covars, t, dim, dim)?)?;
    result.set_item("is_update", PyArray1::from_vec(py, out.is_update))?;
    result.set_item("taken", PyArray1::from_vec(py, out.taken))?;
    result.set_item("gated", PyArray1::from_vec(py, out.gated).reshape([t, k])?)?;
    result.set_item("weights", array2(py, out.weights, t, k + 1)?)?;
    result.set_item("marginals", array2(py, out.marginals, t, k + 1)?)?;
    result.set_item("meas_means", array2(py, out.meas_means, t, meas_dim)?)?;
    result.set_item("meas_covars", array3(py, out.meas_covars, t, meas_dim, meas_dim)?)?;
    result.set_item("cross_covars", array3(py, out.cross_covars, t, dim, meas_dim)?)?;
    Ok(result)
}

/// Exact joint association marginals: `weights` (T, M+1) single-hypothesis weights (column
/// 0 the missed detection), `gated` (T, M) which detection hypotheses exist.
#[pyfunction]
fn jpda_marginals<'py>(py: Python<'py>, weights: Bound<'py, PyArray2<f64>>, gated: Bound<'py, PyArray2<bool>>) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let (t, columns) = (weights.shape()[0], weights.shape()[1]);
    if columns == 0 {
        return Err(value_error("weights", "must have at least one column (the missed detection)"));
    }
    let k = columns - 1;
    if gated.shape() != [t, k] {
        return Err(value_error("gated", format_args!("must have shape ({t}, {k}) to match weights, got {:?}", gated.shape())));
    }
    if !gated.is_c_contiguous() {
        return Err(value_error("gated", "must be C-contiguous"));
    }
    let valid = gated.try_readonly().map_err(|_| value_error("gated", "is being written by another call"))?;
    let valid = crate::memory::copied("gated", valid.as_slice().map_err(|_| value_error("gated", "must be C-contiguous and aligned"))?).map_err(to_py)?;
    let weights = borrow(&weights, "weights")?;
    let w = slice(&weights, "weights")?;
    let out = detached(py, || jpda::joint_marginals(w, &valid, t, k))?;
    array2(py, out, t, k + 1)
}

pub(super) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyJPDAMeasurementModel>()?;
    m.add_function(wrap_pyfunction!(jpda_predict, m)?)?;
    m.add_function(wrap_pyfunction!(jpda_scan, m)?)?;
    m.add_function(wrap_pyfunction!(jpda_marginals, m)?)?;
    Ok(())
}
