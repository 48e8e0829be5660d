//! Python binding of the M-of-N initiator's scan ([`crate::jpda::initiator_scan`]) and new
//! tracks ([`crate::jpda::initiator_births`]): `initiator_scan`, `initiator_births`. Arguments are converted as in the parent module (C-contiguous arrays,
//! errors naming the argument); the work runs with the GIL released and a panic becomes a
//! RuntimeError.

use super::jpda::{array2, array3, check_covars};
use super::kalman::PyMeasurementModel;
use super::{borrow, detached, shape_error, slice, value_error};
use crate::jpda::{self, InitiatorInput};
use numpy::{Element, PyArray1, PyArray2, PyArray3, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// A 1-D array argument of `len` entries as a slice.
fn entries<'a, T: Element>(array: &'a PyReadonlyArray1<'_, T>, argument: &str, len: usize) -> PyResult<&'a [T]> {
    let values = array
        .as_slice()
        .map_err(|_| value_error(argument, "must be C-contiguous"))?;
    if values.len() != len {
        return Err(shape_error(
            argument,
            format_args!("must have {len} entries, got {}", values.len()),
        ));
    }
    Ok(values)
}

/// Indices (`>= 0`) of a 1-D int64 array argument.
fn indices(values: &[i64], argument: &str) -> PyResult<Vec<usize>> {
    values
        .iter()
        .enumerate()
        .map(|(k, &v)| {
            usize::try_from(v).map_err(|_| value_error(argument, format_args!("entry {k}: must be >= 0, got {v}")))
        })
        .collect()
}

/// One scan of the M-of-N initiator's holding rows (see `ctxmodels.stonesoup.array_initiator`):
/// the rows' last `means` (H, D) / `covars` (H, D, D), each row's transition
/// (`transition_index` into `transition_matrices` / `transition_covars`, (K, D, D)),
/// `detections` (M, m), each measured by `models[model_index[j]]`, the counts `points`,
/// `since` and `new_time` per row. A dict of arrays.
#[pyfunction]
#[pyo3(signature = (models, means, covars, transition_index, transition_matrices, transition_covars, detections, model_index, missed_distance, points, since, new_time, *, squared = false, include_all = false, force_symmetric = false, updates_only = false, min_points = 2))]
#[allow(clippy::too_many_arguments)]
fn initiator_scan<'py>(
    py: Python<'py>,
    models: Vec<PyRef<'py, PyMeasurementModel>>,
    means: Bound<'py, PyArray2<f64>>,
    covars: Bound<'py, PyArray3<f64>>,
    transition_index: PyReadonlyArray1<'py, i64>,
    transition_matrices: Bound<'py, PyArray3<f64>>,
    transition_covars: Bound<'py, PyArray3<f64>>,
    detections: Bound<'py, PyArray2<f64>>,
    model_index: PyReadonlyArray1<'py, i64>,
    missed_distance: f64,
    points: PyReadonlyArray1<'py, i64>,
    since: PyReadonlyArray1<'py, i64>,
    new_time: PyReadonlyArray1<'py, bool>,
    squared: bool,
    include_all: bool,
    force_symmetric: bool,
    updates_only: bool,
    min_points: i64,
) -> PyResult<Bound<'py, PyDict>> {
    let (rows, dim) = check_covars(&means, &covars)?;
    for (name, array) in [
        ("transition_matrices", &transition_matrices),
        ("transition_covars", &transition_covars),
    ] {
        let shape = array.shape();
        if shape[1] != dim || shape[2] != dim {
            return Err(shape_error(
                name,
                format_args!("must have shape (K, {dim}, {dim}), got {shape:?}"),
            ));
        }
    }
    if transition_matrices.shape() != transition_covars.shape() {
        return Err(shape_error(
            "transition_covars",
            "must have the shape of transition_matrices",
        ));
    }
    let dets = detections.shape()[0];
    let meas_dim = models
        .first()
        .map_or(detections.shape()[1], |model| model.0.ndim_meas());
    if detections.shape()[1] != meas_dim && dets > 0 {
        return Err(shape_error(
            "detections",
            format_args!(
                "must have {meas_dim} columns (the models' measurement size), got {}",
                detections.shape()[1]
            ),
        ));
    }
    let transition_index = indices(
        entries(&transition_index, "transition_index", rows)?,
        "transition_index",
    )?;
    let model_index = indices(entries(&model_index, "model_index", dets)?, "model_index")?;
    let points = entries(&points, "points", rows)?;
    let since = entries(&since, "since", rows)?;
    let new_time = entries(&new_time, "new_time", rows)?;
    let core: Vec<_> = models.iter().map(|model| model.0.clone()).collect();
    let means = borrow(&means, "means")?;
    let covars = borrow(&covars, "covars")?;
    let matrices = borrow(&transition_matrices, "transition_matrices")?;
    let noises = borrow(&transition_covars, "transition_covars")?;
    let detections = borrow(&detections, "detections")?;
    let input = InitiatorInput {
        dim,
        means: slice(&means, "means")?,
        covars: slice(&covars, "covars")?,
        transition_index: &transition_index,
        matrices: slice(&matrices, "transition_matrices")?,
        noises: slice(&noises, "transition_covars")?,
        detections: slice(&detections, "detections")?,
        model_index: &model_index,
        missed_distance,
        squared,
        include_all,
        force_symmetric,
        points,
        since,
        new_time,
        updates_only,
        min_points,
    };
    let out = detached(py, || jpda::initiator_scan(&core, &input))?;
    let updated = out.distances.len();
    let m = meas_dim;
    let result = PyDict::new(py);
    result.set_item("pred_means", array2(py, out.pred_means, rows, dim)?)?;
    result.set_item("pred_covars", array3(py, out.pred_covars, rows, dim, dim)?)?;
    result.set_item("means", array2(py, out.means, rows, dim)?)?;
    result.set_item("covars", array3(py, out.covars, rows, dim, dim)?)?;
    result.set_item("assigned", PyArray1::from_vec(py, out.assigned))?;
    result.set_item("distances", PyArray1::from_vec(py, out.distances))?;
    result.set_item("meas_means", array2(py, out.meas_means, updated, m)?)?;
    result.set_item("meas_covars", array3(py, out.meas_covars, updated, m, m)?)?;
    result.set_item("cross_covars", array3(py, out.cross_covars, updated, dim, m)?)?;
    result.set_item("points", PyArray1::from_vec(py, out.points))?;
    result.set_item("since", PyArray1::from_vec(py, out.since))?;
    result.set_item("released", PyArray1::from_vec(py, out.released))?;
    Ok(result)
}

/// The new holding tracks of the M-of-N initiator (see `ctxmodels.stonesoup.array_initiator`):
/// for `detections` (M, m), each measured by `models[model_index[j]]`, what Stone Soup's
/// `SimpleMeasurementInitiator` builds from `prior_mean` (D,), `prior_covar` (D, D) and
/// `diag_load`. Returns the means (M, D) and covariances (M, D, D).
#[pyfunction]
#[pyo3(signature = (models, detections, model_index, prior_mean, prior_covar, diag_load = 0.0))]
#[allow(clippy::type_complexity)]
fn initiator_births<'py>(
    py: Python<'py>,
    models: Vec<PyRef<'py, PyMeasurementModel>>,
    detections: PyReadonlyArray2<'py, f64>,
    model_index: PyReadonlyArray1<'py, i64>,
    prior_mean: PyReadonlyArray1<'py, f64>,
    prior_covar: PyReadonlyArray2<'py, f64>,
    diag_load: f64,
) -> PyResult<(Bound<'py, PyArray2<f64>>, Bound<'py, PyArray3<f64>>)> {
    let dets = detections.shape()[0];
    let model_index = indices(entries(&model_index, "model_index", dets)?, "model_index")?;
    let dim = prior_mean.len();
    if prior_covar.shape() != [dim, dim] {
        return Err(shape_error(
            "prior_covar",
            format_args!("must have shape ({dim}, {dim}), got {:?}", prior_covar.shape()),
        ));
    }
    let contiguous = |name: &str| value_error(name, "must be C-contiguous");
    let core: Vec<_> = models.iter().map(|model| model.0.clone()).collect();
    let z = detections.as_slice().map_err(|_| contiguous("detections"))?;
    let mean = prior_mean.as_slice().map_err(|_| contiguous("prior_mean"))?;
    let covar = prior_covar.as_slice().map_err(|_| contiguous("prior_covar"))?;
    let prior = jpda::BirthPrior { mean, covar, diag_load };
    let (means, covars) = detached(py, || jpda::initiator_births(&core, z, &model_index, prior))?;
    Ok((array2(py, means, dets, dim)?, array3(py, covars, dets, dim, dim)?))
}

pub(super) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(initiator_scan, m)?)?;
    m.add_function(wrap_pyfunction!(initiator_births, m)?)?;
    Ok(())
}
