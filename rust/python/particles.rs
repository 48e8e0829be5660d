//! Binding of P_D over particles ([`ScanDetection::at_particles`]): Stone Soup's (D, N)
//! `StateVectors` read in place in either memory order, and log P_D / log(1 − P_D) from
//! the core's table of distinct P_D values ([`Distinct`]), the table filled by NumPy's own
//! `log`: the particle updaters' numbers stay NumPy's bit for bit (NumPy's AVX-512 log and
//! libm's `ln` differ in the last bit for some values), while the per-particle work runs
//! here with the GIL released.
//!
//! [`ScanDetection::at_particles`]: crate::detection::ScanDetection::at_particles

use super::{borrow_contiguous, detached, mapping_of, pose_of, slice, MappingTuple, PoseTuple};
use crate::batch::MemoryOrder;
use crate::detection::DetectionModel;
use crate::distinct::{Distinct, MAX_DISTINCT};
use numpy::{PyArray1, PyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyTuple;

/// P_D (or log P_D) at each particle; with `missed` also 1 − P_D (or its log), as a pair.
pub(super) fn evaluate<'py>(
    py: Python<'py>,
    model: &DetectionModel,
    pose: PoseTuple,
    particles: Bound<'py, PyArray2<f64>>,
    position_mapping: MappingTuple,
    log: bool,
    missed: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let pose = pose_of(pose)?;
    let mapping = mapping_of(position_mapping)?;
    let (ndim, n) = (particles.shape()[0], particles.shape()[1]);
    let particles = borrow_contiguous(&particles, "particles")?;
    // A (D, 1) or (1, N) array is both; C is then right, as for any C-ordered one.
    let order = if particles.is_c_contiguous() {
        MemoryOrder::C
    } else {
        MemoryOrder::F
    };
    let data = slice(&particles, "particles")?;
    let want_table = log && n > 0;
    let (pd, table) = detached(py, || {
        let mut pd = crate::memory::filled("particles", n, 0.0)?;
        model.at_pose(&pose).at_particles(data, ndim, order, mapping, &mut pd)?;
        let table = if want_table {
            Distinct::of(&pd, MAX_DISTINCT)
        } else {
            None
        };
        Ok((pd, table))
    })?;

    let (detected, not_detected) = match (log, table) {
        (false, _) => {
            let complement = missed
                .then(|| crate::memory::collected("particles", pd.iter().map(|p| 1.0 - p)))
                .transpose()
                .map_err(super::to_py)?;
            (pd, complement)
        }
        (true, Some(table)) => {
            // Logs of the few distinct values from NumPy; the per-particle lookup in the core.
            let log_pd = numpy_log(py, table.values())?;
            let log_missed = if missed {
                // (a table holds at most MAX_DISTINCT values)
                Some(numpy_log(
                    py,
                    &table.values().iter().map(|p| 1.0 - p).collect::<Vec<_>>(),
                )?)
            } else {
                None
            };
            detached(py, || {
                let mut pd = pd;
                // The complement first, from P_D; then P_D's own buffer becomes its log.
                let missed_out = match &log_missed {
                    Some(image) => {
                        let mut out = crate::memory::copied("particles", &pd)?;
                        table.apply(&mut out, image)?;
                        Some(out)
                    }
                    None => None,
                };
                table.apply(&mut pd, &log_pd)?;
                Ok((pd, missed_out))
            })?
        }
        // More distinct values than a table is worth (or none at all): NumPy on every value.
        (true, None) => {
            let complement =
                |pd: &[f64]| crate::memory::collected("particles", pd.iter().map(|p| 1.0 - p)).map_err(super::to_py);
            let log_missed = if missed {
                Some(numpy_log(py, &complement(&pd)?)?)
            } else {
                None
            };
            (numpy_log(py, &pd)?, log_missed)
        }
    };
    let detected = PyArray1::from_vec(py, detected).into_any();
    match not_detected {
        None => Ok(detected),
        Some(other) => Ok(PyTuple::new(py, [detected, PyArray1::from_vec(py, other).into_any()])?.into_any()),
    }
}

/// `numpy.log` of each value, log ±0 = -inf as NumPy gives it but without its divide-by-zero
/// warning: NumPy sees the non-zero values only, as one contiguous array (its log is the
/// same function of each value whatever the array's length or alignment).
fn numpy_log(py: Python<'_>, values: &[f64]) -> PyResult<Vec<f64>> {
    let nonzero: Vec<f64> =
        crate::memory::collected("particles", values.iter().copied().filter(|v| *v != 0.0)).map_err(super::to_py)?;
    let logs = py
        .import("numpy")?
        .getattr("log")?
        .call1((PyArray1::from_vec(py, nonzero),))?;
    let logs = logs.cast_into::<PyArray1<f64>>()?;
    let logs = super::borrow(&logs, "log")?;
    let mut logs = slice(&logs, "log")?.iter();
    crate::memory::collected(
        "particles",
        values.iter().map(|v| {
            if *v == 0.0 {
                f64::NEG_INFINITY
            } else {
                *logs.next().unwrap_or(&f64::NAN)
            }
        }),
    )
    .map_err(super::to_py)
}
