//! The only module that knows about Python: converts arguments at the boundary, releases
//! the GIL around evaluation, and turns core errors (and, defensively, panics) into Python
//! exceptions. Input arrays arrive as C-contiguous float64 (the Python layer converts;
//! unaligned ones are copied here); particle arrays may also be Fortran-ordered. Arrays are borrowed with numpy's fallible borrows and no
//! `unwrap`: an `out=` that overlaps an input, or that another thread's call is writing, is
//! a ValueError, not a panic.
//!
//! This file holds what the binding's files share (the errors' conversion, the conversions
//! and checks below) and the `_core` module: its three functions and the registration of
//! every class. The classes are in its submodules (`models`: the detection and clutter
//! models and their factors; the rest a file per core module bound).

use crate::batch::PositionMapping;
use crate::cubature::Rule;
use crate::error::ModelError;
use crate::pose::{Mounting, Pose};
use numpy::ndarray::Dimension;
use numpy::{
    BorrowError, PyArray, PyArray1, PyArrayMethods, PyReadonlyArray, PyReadwriteArray1, PyUntypedArrayMethods,
};
use pyo3::exceptions::{PyMemoryError, PyRuntimeError};
use pyo3::prelude::*;
use std::panic::{catch_unwind, AssertUnwindSafe};

mod at_pose;
mod clutter_map;
mod detection_estimate;
mod gmphd;
mod heights;
mod initiation;
mod jpda;
mod kalman;
mod models;
mod particles;
mod radar;
mod range_rate;

// The exception classes are Python's (`ctxmodels.errors`, documented there): each kind of
// core error maps to one, built from the error's fields, so callers read attributes, never
// message text.
pyo3::import_exception!(ctxmodels.errors, ArgumentError);
pyo3::import_exception!(ctxmodels.errors, ArgumentTypeError);
pyo3::import_exception!(ctxmodels.errors, ShapeError);
pyo3::import_exception!(ctxmodels.errors, NonFiniteError);
pyo3::import_exception!(ctxmodels.errors, InvalidLandError);
pyo3::import_exception!(ctxmodels.errors, NotPositiveDefiniteError);
pyo3::import_exception!(ctxmodels.errors, InfeasibleAssignmentError);

fn to_py(err: ModelError) -> PyErr {
    let text = err.to_string();
    // What follows "argument: " in the message.
    let detail = text[err.argument().len() + 2..].to_string();
    match err {
        ModelError::Memory { .. } => PyMemoryError::new_err(text),
        ModelError::InvalidArgument { argument, .. } => ArgumentError::new_err((argument, detail)),
        ModelError::Shape { argument, .. } => ShapeError::new_err((argument, detail)),
        ModelError::NonFinite { argument, row, .. } => NonFiniteError::new_err((argument, detail, row)),
        ModelError::NotPositiveDefinite { argument, .. } => NotPositiveDefiniteError::new_err((argument, detail)),
        ModelError::Infeasible { argument, .. } => InfeasibleAssignmentError::new_err((argument, detail)),
        ModelError::InvalidLand {
            argument,
            polygon,
            ring,
            message,
        } => InvalidLandError::new_err((argument, detail, polygon, ring, message)),
    }
}

/// A [`ShapeError`] about `argument` raised by the binding's own checks of array shapes.
fn shape_error(argument: &str, message: impl std::fmt::Display) -> PyErr {
    ShapeError::new_err((argument.to_string(), message.to_string()))
}

/// An [`ArgumentTypeError`] (a TypeError) about `argument` raised by the binding's own checks.
fn type_error(argument: &str, message: impl std::fmt::Display) -> PyErr {
    ArgumentTypeError::new_err((argument.to_string(), message.to_string()))
}

/// An [`ArgumentError`] about `argument` raised by the binding's own checks.
fn value_error(argument: &str, message: impl std::fmt::Display) -> PyErr {
    ArgumentError::new_err((argument.to_string(), message.to_string()))
}

/// Runs `f` with the GIL released; a panic becomes a RuntimeError instead of unwinding
/// into the interpreter.
fn detached<T: Send>(py: Python<'_>, f: impl FnOnce() -> crate::Result<T> + Send) -> PyResult<T> {
    py.detach(|| guarded(f))
}

/// Runs `f` on the calling thread (GIL held: small inputs, where releasing it costs more
/// than the work); a panic becomes a RuntimeError, as in [`detached`].
fn guarded<T>(f: impl FnOnce() -> crate::Result<T>) -> PyResult<T> {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(inner) => inner.map_err(to_py),
        Err(_) => Err(PyRuntimeError::new_err(
            "ctxmodels internal error (a bug: please report it with the inputs)",
        )),
    }
}

/// A shared borrow of a float64 input array. numpy's borrow tracker refuses it while another
/// call (GIL released) writes the same memory as its `out=`: that is a ValueError naming the
/// argument, never a panic. Unaligned arrays are copied: the kernels read `&[f64]`.
fn borrow<'py, D: Dimension>(
    array: &Bound<'py, PyArray<f64, D>>,
    argument: &str,
) -> PyResult<PyReadonlyArray<'py, f64, D>> {
    // as_slice would also accept Fortran order, which would be read as rows: wrong numbers.
    if !array.is_c_contiguous() {
        return Err(value_error(argument, "must be C-contiguous"));
    }
    borrow_contiguous(array, argument)
}

/// [`borrow`] for callers that read the memory order (C or Fortran) from the borrowed array.
fn borrow_contiguous<'py, D: Dimension>(
    array: &Bound<'py, PyArray<f64, D>>,
    argument: &str,
) -> PyResult<PyReadonlyArray<'py, f64, D>> {
    if !array.is_contiguous() {
        return Err(value_error(argument, "must be C- or Fortran-contiguous"));
    }
    let view = array.try_readonly().map_err(|_| {
        value_error(
            argument,
            "is being written by another call (it is, or overlaps, an out= buffer in use)",
        )
    })?;
    if array.is_aligned() {
        return Ok(view);
    }
    // The shared borrow stays held while numpy copies, so no call can write it meanwhile;
    // order "K" keeps a Fortran-ordered array Fortran-ordered.
    let copy = array.call_method1("copy", ("K",))?.cast_into::<PyArray<f64, D>>()?;
    drop(view);
    copy.try_readonly()
        .map_err(|_| value_error(argument, "could not borrow an aligned copy"))
}

/// A new array holding a copy of `values` (MemoryError naming `argument` when it cannot be
/// allocated: numpy's own copy would panic).
fn array_of<'py, T: numpy::Element + Clone>(
    py: Python<'py>,
    argument: &'static str,
    values: &[T],
) -> PyResult<Bound<'py, PyArray1<T>>> {
    Ok(PyArray1::from_vec(
        py,
        crate::memory::copied(argument, values).map_err(to_py)?,
    ))
}

fn slice<'a, D: Dimension>(a: &'a PyReadonlyArray<'_, f64, D>, argument: &str) -> PyResult<&'a [f64]> {
    a.as_slice()
        .map_err(|_| value_error(argument, "must be C-contiguous and aligned"))
}

/// The first row of `rows` (of `width` values) holding NaN or ±inf.
fn first_non_finite(rows: &[f64], width: usize) -> Option<usize> {
    rows.chunks_exact(width)
        .position(|row| row.iter().any(|v| !v.is_finite()))
}

/// A pose from Python: (x, y, heading), (x, y, heading, z) with the sensor's height,
/// (x, y, heading, z, vx, vy, vz) with its velocity too, or (…, pitch, roll) tilted.
#[derive(FromPyObject)]
enum PoseTuple {
    Tilted((f64, f64, f64, f64, f64, f64, f64, f64, f64)),
    Moving((f64, f64, f64, f64, f64, f64, f64)),
    Raised((f64, f64, f64, f64)),
    Flat((f64, f64, f64)),
}

/// The state columns a model reads, from Python: (x, y) or, for states with a height,
/// (x, y, z); followed, when a factor reads velocities, by (vx, vy) or (vx, vy, vz).
#[derive(FromPyObject)]
enum MappingTuple {
    MovingRaised((i64, i64, i64, i64, i64, i64)),
    Moving((i64, i64, i64, i64)),
    Raised((i64, i64, i64)),
    Flat((i64, i64)),
}

fn pose_of(pose: PoseTuple) -> PyResult<Pose> {
    match pose {
        PoseTuple::Flat((x, y, heading)) => Pose::new(x, y, heading),
        PoseTuple::Raised((x, y, heading, z)) => Pose::raised(x, y, heading, z),
        PoseTuple::Moving((x, y, heading, z, vx, vy, vz)) => {
            Pose::raised(x, y, heading, z).and_then(|p| p.moving([vx, vy, vz]))
        }
        PoseTuple::Tilted((x, y, heading, z, vx, vy, vz, pitch, roll)) => Pose::raised(x, y, heading, z)
            .and_then(|p| p.moving([vx, vy, vz]))
            .and_then(|p| p.tilted(pitch, roll)),
    }
    .map_err(to_py)
}

fn mapping_of(mapping: MappingTuple) -> PyResult<PositionMapping> {
    let (indices, positions): (&[i64], usize) = match &mapping {
        MappingTuple::Flat((x, y)) => (&[*x, *y], 2),
        MappingTuple::Raised((x, y, z)) => (&[*x, *y, *z], 3),
        MappingTuple::Moving((x, y, vx, vy)) => (&[*x, *y, *vx, *vy], 2),
        MappingTuple::MovingRaised((x, y, z, vx, vy, vz)) => (&[*x, *y, *z, *vx, *vy, *vz], 3),
    };
    let mut checked = [0usize; 6];
    for (k, (c, &i)) in checked.iter_mut().zip(indices).enumerate() {
        let argument = if k < positions {
            "position_mapping"
        } else {
            "velocity_mapping"
        };
        *c = usize::try_from(i)
            .map_err(|_| value_error(argument, format_args!("indices must be >= 0, got {indices:?}")))?;
    }
    let [x, y, z, ..] = checked;
    let mapping = if positions == 3 {
        PositionMapping::raised(x, y, z)
    } else {
        PositionMapping::new(x, y)
    }
    .map_err(to_py)?;
    if indices.len() == positions {
        return Ok(mapping);
    }
    let velocity = &checked[positions..indices.len()];
    mapping
        .with_velocity(crate::batch::VelocityMapping {
            vx: velocity[0],
            vy: velocity[1],
            vz: velocity.get(2).copied(),
        })
        .map_err(to_py)
}

/// The output buffer, borrowed for writing: the caller's `out` (checked) or a new array.
/// `inputs` are this call's input slices: Rust must never write memory it also reads.
fn output<'py>(
    py: Python<'py>,
    out: Option<Bound<'py, PyArray1<f64>>>,
    n: usize,
    inputs: &[(&str, &[f64])],
) -> PyResult<PyReadwriteArray1<'py, f64>> {
    let array = match out {
        // (numpy's own allocation would panic on failure: a Vec that can fail, then handed over)
        None => PyArray1::from_vec(py, crate::memory::filled("out", n, 0.0).map_err(to_py)?),
        Some(out) => {
            if out.len() != n {
                return Err(shape_error(
                    "out",
                    format_args!("must have {n} entries, got {}", out.len()),
                ));
            }
            if !out.is_c_contiguous() {
                return Err(value_error("out", "must be C-contiguous"));
            }
            if !out.is_aligned() {
                return Err(value_error("out", "must be aligned (allocate it with numpy.empty)"));
            }
            // By address, so views the borrow tracker cannot relate (two arrays over one
            // buffer) are caught too; inputs are contiguous, so spans are exact.
            let start = out.data() as usize;
            let end = start + n * std::mem::size_of::<f64>();
            for (name, data) in inputs {
                let (s, e) = (
                    data.as_ptr() as usize,
                    data.as_ptr() as usize + std::mem::size_of_val(*data),
                );
                if n > 0 && !data.is_empty() && s < end && start < e {
                    return Err(value_error(
                        "out",
                        format_args!("overlaps {name}, an input of the same call; pass a separate buffer"),
                    ));
                }
            }
            out
        }
    };
    array.try_readwrite().map_err(|err| match err {
        BorrowError::NotWriteable => value_error("out", "must be writeable"),
        _ => value_error(
            "out",
            "is in use by another call or overlaps one of this call's inputs; give each concurrent call its own buffer",
        ),
    })
}

/// (M, 2) rows of `points` as a slice.
fn points_slice<'a>(points: &'a PyReadonlyArray<'_, f64, numpy::Ix2>, argument: &'static str) -> PyResult<&'a [f64]> {
    if points.shape()[1] != 2 {
        return Err(shape_error(
            argument,
            format_args!("must have shape (M, 2), got {:?}", points.shape()),
        ));
    }
    slice(points, argument)
}

/// [`points_slice`], refusing NaN/±inf rows: containment and sight have no answer for them
/// (and would otherwise say "water" or "visible").
fn finite_points<'a>(points: &'a PyReadonlyArray<'_, f64, numpy::Ix2>, argument: &'static str) -> PyResult<&'a [f64]> {
    let p = points_slice(points, argument)?;
    match first_non_finite(p, 2) {
        Some(row) => Err(to_py(ModelError::non_finite(
            argument,
            row,
            "x or y is NaN or infinite",
        ))),
        None => Ok(p),
    }
}

/// Largest Gauss–Hermite order ([`Rule::gauss_hermite`]'s limit).
const MAX_ORDER: usize = 32;

fn rule_of(rule: &str, order: i64) -> PyResult<Rule> {
    // Checked for every rule (as the Python layer does), not only where it is used.
    let order = usize::try_from(order)
        .ok()
        .filter(|o| (1..=MAX_ORDER).contains(o))
        .ok_or_else(|| {
            value_error(
                "order",
                format_args!("must be an integer in 1..{MAX_ORDER}, got {order}"),
            )
        })?;
    match rule {
        "mean" => Ok(Rule::mean()),
        "cubature" => Ok(Rule::cubature()),
        "unscented" => Ok(Rule::unscented()),
        "gauss-hermite" => Rule::gauss_hermite(order).map_err(to_py),
        other => Err(value_error(
            "rule",
            format_args!("must be one of 'mean', 'cubature', 'unscented', 'gauss-hermite', got {other:?}"),
        )),
    }
}

/// The pose (x, y, heading, z) of a sensor mounted on a platform at `pose`.
#[pyfunction]
#[pyo3(signature = (pose, forward, left, yaw, up = 0.0))]
fn mount(pose: PoseTuple, forward: f64, left: f64, yaw: f64, up: f64) -> PyResult<(f64, f64, f64, f64)> {
    let mounted = pose_of(pose)?
        .mount(&Mounting::raised(forward, left, yaw, up).map_err(to_py)?)
        .map_err(to_py)?;
    Ok((mounted.x, mounted.y, mounted.heading, mounted.z))
}

/// The build of the array kernels this process runs: "avx2" or "portable" (see
/// `crate::simd`; `CTXMODELS_SIMD=portable` forces the latter). Both give the same bits.
#[pyfunction]
fn simd_backend() -> &'static str {
    crate::simd::backend().name()
}

/// A rule's points (x, y) and weights.
type RulePoints = (Vec<(f64, f64)>, Vec<f64>);

/// Points and weights of an integration rule in standard-normal space.
#[pyfunction]
#[pyo3(signature = (rule, order = 3))]
fn rule_points(rule: &str, order: i64) -> PyResult<RulePoints> {
    let r = rule_of(rule, order)?;
    // (a rule has at most MAX_ORDER² = 1024 points)
    Ok((r.points().iter().map(|p| (p[0], p[1])).collect(), r.weights().to_vec()))
}

#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<models::PyRangeBands>()?;
    m.add_class::<models::PyAngularSector>()?;
    m.add_class::<models::PyLandMask>()?;
    m.add_class::<models::PyLineOfSight>()?;
    m.add_class::<heights::PyElevationSector>()?;
    m.add_class::<heights::PyHorizon>()?;
    m.add_class::<range_rate::PyRangeRateNotch>()?;
    m.add_class::<models::PyDetectionModel>()?;
    m.add_class::<at_pose::PyDetectionAtPose>()?;
    m.add_class::<at_pose::PyClutterAtPose>()?;
    m.add_class::<models::PyMetadataThreshold>()?;
    m.add_class::<models::PyClutterModel>()?;
    m.add_class::<clutter_map::PyClutterMap>()?;
    m.add_class::<models::PyCoastalBand>()?;
    m.add_class::<models::PyZone>()?;
    m.add_class::<detection_estimate::PyDetectionEstimate>()?;
    m.add_function(wrap_pyfunction!(mount, m)?)?;
    m.add_function(wrap_pyfunction!(rule_points, m)?)?;
    m.add_function(wrap_pyfunction!(simd_backend, m)?)?;
    kalman::register(m)?;
    radar::register(m)?;
    gmphd::register(m)?;
    jpda::register(m)?;
    initiation::register(m)?;
    Ok(())
}
