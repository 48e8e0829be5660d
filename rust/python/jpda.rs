//! Python binding of the whole-scan JPDA core ([`crate::jpda`]): `jpda_predict`, `jpda_scan`
//! and `jpda_marginals` (the initiator's scan: `super::initiation`). Arguments are converted as in the parent
//! module (C-contiguous float64, fallible borrows, errors naming the argument); the work runs
//! with the GIL released and a panic becomes a RuntimeError.

use super::at_pose::PyDetectionAtPose;
use super::kalman::PyMeasurementModel;
use super::{borrow, detached, shape_error, slice, to_py, value_error};
use crate::jpda::{self, ScanInput};
use numpy::{PyArray1, PyArray2, PyArray3, PyArrayMethods, PyReadonlyArray3, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;

pub(super) fn array2<'py>(
    py: Python<'py>,
    data: Vec<f64>,
    rows: usize,
    cols: usize,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    PyArray1::from_vec(py, data).reshape([rows, cols])
}

pub(super) fn array3<'py>(
    py: Python<'py>,
    data: Vec<f64>,
    n: usize,
    rows: usize,
    cols: usize,
) -> PyResult<Bound<'py, PyArray3<f64>>> {
    PyArray1::from_vec(py, data).reshape([n, rows, cols])
}

pub(super) fn check_covars(
    means: &Bound<'_, PyArray2<f64>>,
    covars: &Bound<'_, PyArray3<f64>>,
) -> PyResult<(usize, usize)> {
    let (n, dim) = (means.shape()[0], means.shape()[1]);
    let shape = covars.shape();
    if shape != [n, dim, dim] {
        return Err(shape_error(
            "covars",
            format_args!("must have shape ({n}, {dim}, {dim}) to match means, got {shape:?}"),
        ));
    }
    Ok((n, dim))
}

/// Transition `transition_index[t]` of `transition_matrices` / `transition_covars` (K, D, D)
/// for each of `n` tracks of dimension `dim`, checked.
fn transitions<'a>(
    n: usize,
    dim: usize,
    transition_index: &[i64],
    matrices: &'a PyReadonlyArray3<'_, f64>,
    noises: &'a PyReadonlyArray3<'_, f64>,
) -> PyResult<(Vec<usize>, &'a [f64], &'a [f64])> {
    if transition_index.len() != n {
        return Err(shape_error(
            "transition_index",
            format_args!("must have {n} entries (one per track), got {}", transition_index.len()),
        ));
    }
    for (name, array) in [("transition_matrices", matrices), ("transition_covars", noises)] {
        let shape = array.shape();
        if shape[1] != dim || shape[2] != dim {
            return Err(shape_error(
                name,
                format_args!("must have shape (K, {dim}, {dim}), got {shape:?}"),
            ));
        }
    }
    let mut index = crate::memory::with_room("transition_index", n).map_err(to_py)?;
    for (t, &k) in transition_index.iter().enumerate() {
        index.push(
            usize::try_from(k)
                .map_err(|_| value_error("transition_index", format_args!("row {t}: must be >= 0, got {k}")))?,
        );
    }
    Ok((
        index,
        slice(matrices, "transition_matrices")?,
        slice(noises, "transition_covars")?,
    ))
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
    let matrices = borrow(&transition_matrices, "transition_matrices")?;
    let noises = borrow(&transition_covars, "transition_covars")?;
    let (index, f, q) = transitions(n, dim, &transition_index, &matrices, &noises)?;
    let means = borrow(&means, "means")?;
    let m = slice(&means, "means")?;
    let covars = borrow(&covars, "covars")?;
    let c = slice(&covars, "covars")?;
    let (x, p) = detached(py, || jpda::predict(dim, m, c, &index, f, q))?;
    Ok((array2(py, x, n, dim)?, array3(py, p, n, dim, dim)?))
}

/// One JPDA scan (see `ctxmodels.stonesoup.array_jpda`): `means` (T, D) and `covars`
/// (T, D, D), `detections` (M, m) of `model`, P_D per track, λ per detection.
///
/// With `transition_index` (and `transition_matrices` / `transition_covars`, as in
/// `jpda_predict`) the states are the tracks' last ones, predicted here first; else they
/// are the prediction. `prob_detect`: an array (T,), or a context's `DetectionAtPose`, read
/// in the core at each predicted mean. The result holds the prediction (`pred_means`,
/// `pred_covars`) and the P_D used (`prob_detect`) beside the scan's arrays.
#[pyfunction]
#[pyo3(signature = (model, means, covars, detections, prob_detect, clutter_density, prob_gate, gate_threshold, include_all = false, *, transition_index = None, transition_matrices = None, transition_covars = None, force_symmetric = false))]
#[allow(clippy::too_many_arguments)]
fn jpda_scan<'py>(
    py: Python<'py>,
    model: &PyMeasurementModel,
    means: Bound<'py, PyArray2<f64>>,
    covars: Bound<'py, PyArray3<f64>>,
    detections: Bound<'py, PyArray2<f64>>,
    prob_detect: Bound<'py, PyAny>,
    clutter_density: Bound<'py, PyArray1<f64>>,
    prob_gate: f64,
    gate_threshold: f64,
    include_all: bool,
    transition_index: Option<Vec<i64>>,
    transition_matrices: Option<Bound<'py, PyArray3<f64>>>,
    transition_covars: Option<Bound<'py, PyArray3<f64>>>,
    force_symmetric: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let (n, dim) = check_covars(&means, &covars)?;
    let meas_dim = model.0.ndim_meas();
    let (n_dets, det_cols) = (detections.shape()[0], detections.shape()[1]);
    if det_cols != meas_dim && n_dets > 0 {
        return Err(shape_error(
            "detections",
            format_args!("must have {meas_dim} columns (the model's measurement size), got {det_cols}"),
        ));
    }
    let at_pose = prob_detect
        .cast::<PyDetectionAtPose>()
        .ok()
        .map(|at_pose| at_pose.get());
    let given = match at_pose {
        Some(_) => None,
        None => {
            let array = prob_detect.cast::<PyArray1<f64>>().map_err(|_| {
                value_error(
                    "prob_detect",
                    "must be a float64 array (one P_D per track) or a DetectionAtPose",
                )
            })?;
            if array.len() != n {
                return Err(shape_error(
                    "prob_detect",
                    format_args!("must have {n} entries (one per track), got {}", array.len()),
                ));
            }
            Some(borrow(array, "prob_detect")?)
        }
    };
    if clutter_density.len() != n_dets {
        return Err(shape_error(
            "clutter_density",
            format_args!(
                "must have {n_dets} entries (one per detection), got {}",
                clutter_density.len()
            ),
        ));
    }
    let (matrices, noises) = match (transition_matrices, transition_covars) {
        (Some(f), Some(q)) if transition_index.is_some() => (
            Some(borrow(&f, "transition_matrices")?),
            Some(borrow(&q, "transition_covars")?),
        ),
        (None, None) if transition_index.is_none() => (None, None),
        _ => {
            return Err(value_error(
                "transition_index",
                "transition_index, transition_matrices and transition_covars come together",
            ))
        }
    };
    let prediction = match (&transition_index, &matrices, &noises) {
        (Some(index), Some(f), Some(q)) => Some(transitions(n, dim, index, f, q)?),
        _ => None,
    };
    let means = borrow(&means, "means")?;
    let m = slice(&means, "means")?;
    let covars = borrow(&covars, "covars")?;
    let c = slice(&covars, "covars")?;
    let detections = borrow(&detections, "detections")?;
    let z = slice(&detections, "detections")?;
    let given = match &given {
        Some(array) => Some(slice(array, "prob_detect")?),
        None => None,
    };
    let clutter_density = borrow(&clutter_density, "clutter_density")?;
    let lam = slice(&clutter_density, "clutter_density")?;
    let core = &model.0;
    let (predicted, pd, out) = detached(py, || {
        let predicted = match &prediction {
            Some((index, f, q)) => Some(jpda::predict(dim, m, c, index, f, q)?),
            None => None,
        };
        let (x, p) = predicted.as_ref().map_or((m, c), |(x, p)| (x.as_slice(), p.as_slice()));
        let pd = match (given, at_pose) {
            (Some(given), _) => given.to_vec(),
            (None, Some(at_pose)) => {
                let mut pd = crate::memory::filled("prob_detect", n, 0.0)?;
                at_pose.at_rows(x, dim, &mut pd)?;
                pd
            }
            (None, None) => unreachable!("prob_detect is an array or a DetectionAtPose"),
        };
        let input = ScanInput {
            dim,
            means: x,
            covars: p,
            detections: z,
            prob_detect: &pd,
            clutter: lam,
            prob_gate,
            gate_threshold,
            include_all,
            force_symmetric,
        };
        let out = jpda::scan(core, &input)?;
        Ok((predicted, pd, out))
    })?;
    let result = PyDict::new(py);
    let (t, k) = (out.tracks, out.detections);
    if let Some((x, p)) = predicted {
        result.set_item("pred_means", array2(py, x, n, dim)?)?;
        result.set_item("pred_covars", array3(py, p, n, dim, dim)?)?;
    }
    result.set_item("prob_detect", PyArray1::from_vec(py, pd))?;
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
fn jpda_marginals<'py>(
    py: Python<'py>,
    weights: Bound<'py, PyArray2<f64>>,
    gated: Bound<'py, PyArray2<bool>>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let (t, columns) = (weights.shape()[0], weights.shape()[1]);
    if columns == 0 {
        return Err(value_error(
            "weights",
            "must have at least one column (the missed detection)",
        ));
    }
    let k = columns - 1;
    if gated.shape() != [t, k] {
        return Err(shape_error(
            "gated",
            format_args!("must have shape ({t}, {k}) to match weights, got {:?}", gated.shape()),
        ));
    }
    if !gated.is_c_contiguous() {
        return Err(value_error("gated", "must be C-contiguous"));
    }
    let valid = gated
        .try_readonly()
        .map_err(|_| value_error("gated", "is being written by another call"))?;
    let valid = crate::memory::copied(
        "gated",
        valid
            .as_slice()
            .map_err(|_| value_error("gated", "must be C-contiguous and aligned"))?,
    )
    .map_err(to_py)?;
    let weights = borrow(&weights, "weights")?;
    let w = slice(&weights, "weights")?;
    let out = detached(py, || jpda::joint_marginals(w, &valid, t, k))?;
    array2(py, out, t, k + 1)
}

pub(super) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(jpda_predict, m)?)?;
    m.add_function(wrap_pyfunction!(jpda_scan, m)?)?;
    m.add_function(wrap_pyfunction!(jpda_marginals, m)?)?;
    Ok(())
}
