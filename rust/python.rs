//! The only module that knows about Python: converts arguments at the boundary, releases
//! the GIL around evaluation, and turns core errors (and, defensively, panics) into Python
//! exceptions. Input arrays arrive as C-contiguous float64 (the Python layer converts;
//! unaligned ones are copied here); particle arrays may also be Fortran-ordered. Arrays are borrowed with numpy's fallible borrows and no
//! `unwrap`: an `out=` that overlaps an input, or that another thread's call is writing, is
//! a ValueError, not a panic.

use crate::batch::PositionMapping;
use crate::clutter::{ClutterFactor, ClutterModel, MetadataThreshold};
use crate::coast::CoastalBand;
use crate::cubature::Rule;
use crate::detection::{DetectionFactor, DetectionModel};
use crate::error::ModelError;
use crate::land::{LandMask, Polygon};
use crate::pose::{Mounting, Pose};
use crate::range_bands::RangeBands;
use crate::sector::AngularSector;
use crate::sight::LineOfSight;
use numpy::ndarray::Dimension;
use numpy::{
    BorrowError, PyArray, PyArray1, PyArray2, PyArray3, PyArrayMethods, PyReadonlyArray, PyReadwriteArray1,
    PyUntypedArrayMethods,
};
use pyo3::exceptions::{PyMemoryError, PyRuntimeError, PyTypeError, PyValueError};
use pyo3::prelude::*;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::Arc;

mod at_pose;
mod clutter_map;
mod detection_estimate;
mod gmphd;
mod initiation;
mod jpda;
mod kalman;
mod particles;

pyo3::create_exception!(
    ctxmodels._core,
    NotPositiveDefiniteError,
    PyValueError,
    "A covariance the computation needs positive definite is not (a ValueError naming the argument)."
);

pyo3::create_exception!(
    ctxmodels._core,
    InfeasibleAssignmentError,
    PyValueError,
    "An assignment problem has no complete assignment of finite cost (a ValueError naming the argument)."
);

fn to_py(err: ModelError) -> PyErr {
    match err {
        ModelError::Memory { .. } => PyMemoryError::new_err(err.to_string()),
        ModelError::NotPositiveDefinite { .. } => NotPositiveDefiniteError::new_err(err.to_string()),
        ModelError::Infeasible { .. } => InfeasibleAssignmentError::new_err(err.to_string()),
        _ => PyValueError::new_err(err.to_string()),
    }
}

fn value_error(argument: &str, message: impl std::fmt::Display) -> PyErr {
    PyValueError::new_err(format!("{argument}: {message}"))
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

fn pose_of(pose: (f64, f64, f64)) -> PyResult<Pose> {
    Pose::new(pose.0, pose.1, pose.2).map_err(to_py)
}

fn mapping_of(mapping: (i64, i64)) -> PyResult<PositionMapping> {
    let index = |i: i64| {
        usize::try_from(i).map_err(|_| {
            value_error(
                "position_mapping",
                format_args!("indices must be >= 0, got {mapping:?}"),
            )
        })
    };
    PositionMapping::new(index(mapping.0)?, index(mapping.1)?).map_err(to_py)
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
                return Err(value_error(
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

#[pyclass(name = "RangeBands", module = "ctxmodels._core", frozen, skip_from_py_object)]
pub struct PyRangeBands(RangeBands);

#[pymethods]
impl PyRangeBands {
    #[new]
    fn new(edges: Vec<f64>, values: Vec<f64>, upper_owns: Vec<bool>) -> PyResult<Self> {
        Ok(PyRangeBands(RangeBands::new(edges, values, upper_owns).map_err(to_py)?))
    }

    /// Values at each of `ranges` (±inf lie beyond / before every edge; NaN is an error).
    fn at<'py>(&self, py: Python<'py>, ranges: Bound<'py, PyArray1<f64>>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let ranges = borrow(&ranges, "ranges")?;
        let r = slice(&ranges, "ranges")?;
        // NaN passes no edge, so it would silently get the first band.
        if let Some(row) = r.iter().position(|x| x.is_nan()) {
            return Err(to_py(ModelError::non_finite("ranges", row, "NaN")));
        }
        Ok(PyArray1::from_vec(
            py,
            crate::memory::collected("ranges", r.iter().map(|&x| self.0.at(x))).map_err(to_py)?,
        ))
    }
}

#[pyclass(name = "AngularSector", module = "ctxmodels._core", frozen, skip_from_py_object)]
pub struct PyAngularSector(AngularSector);

#[pymethods]
impl PyAngularSector {
    #[new]
    fn new(centre: f64, width: f64, inside: f64, outside: f64) -> PyResult<Self> {
        Ok(PyAngularSector(
            AngularSector::new(centre, width, inside, outside).map_err(to_py)?,
        ))
    }
}

#[pyclass(name = "LandMask", module = "ctxmodels._core", frozen)]
pub struct PyLandMask(Arc<LandMask>);

fn ring_of(ring: &Bound<'_, PyAny>) -> PyResult<Vec<[f64; 2]>> {
    let array = ring
        .cast::<PyArray2<f64>>()
        .map_err(|_| PyTypeError::new_err("polygons: every ring must be a (K, 2) float64 array"))?;
    if array.shape()[1] != 2 {
        return Err(value_error(
            "polygons",
            format_args!("every ring must have shape (K, 2), got {:?}", array.shape()),
        ));
    }
    let array = borrow(array, "polygons")?;
    crate::memory::collected(
        "polygons",
        slice(&array, "polygons")?.chunks_exact(2).map(|r| [r[0], r[1]]),
    )
    .map_err(to_py)
}

#[pymethods]
impl PyLandMask {
    /// `polygons`: list of (shell, [holes]) with rings as (K, 2) float64 arrays.
    #[new]
    fn new(py: Python<'_>, polygons: Vec<(Bound<'_, PyAny>, Vec<Bound<'_, PyAny>>)>) -> PyResult<Self> {
        // (one entry per polygon of the Python list, which exists)
        let mut converted = Vec::with_capacity(polygons.len());
        for (shell, holes) in &polygons {
            converted.push(Polygon {
                shell: ring_of(shell)?,
                holes: holes.iter().map(ring_of).collect::<PyResult<_>>()?,
            });
        }
        Ok(PyLandMask(Arc::new(detached(py, || LandMask::new(converted))?)))
    }

    /// Whether each (x, y) row of `points` is on land (boundary included).
    fn contains<'py>(
        &self,
        py: Python<'py>,
        points: Bound<'py, PyArray2<f64>>,
    ) -> PyResult<Bound<'py, PyArray1<bool>>> {
        let points = borrow(&points, "points")?;
        let p = finite_points(&points, "points")?;
        let land = &self.0;
        let inside = detached(py, || {
            crate::memory::collected("points", p.chunks_exact(2).map(|q| land.contains([q[0], q[1]])))
        })?;
        Ok(PyArray1::from_vec(py, inside))
    }

    #[getter]
    fn vertex_count(&self) -> usize {
        self.0.vertex_count()
    }
}

/// (M, 2) rows of `points` as a slice.
fn points_slice<'a>(points: &'a PyReadonlyArray<'_, f64, numpy::Ix2>, argument: &'static str) -> PyResult<&'a [f64]> {
    if points.shape()[1] != 2 {
        return Err(value_error(
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

#[pyclass(name = "LineOfSight", module = "ctxmodels._core", frozen)]
pub struct PyLineOfSight(Arc<LineOfSight>);

#[pymethods]
impl PyLineOfSight {
    #[new]
    fn new(py: Python<'_>, land: &PyLandMask) -> PyResult<Self> {
        let land = land.0.clone();
        Ok(PyLineOfSight(Arc::new(detached(py, || LineOfSight::new(land))?)))
    }

    /// Whether each target row of `targets` (M, 2) is visible from `sensor` (x, y).
    fn visible<'py>(
        &self,
        py: Python<'py>,
        sensor: (f64, f64),
        targets: Bound<'py, PyArray2<f64>>,
    ) -> PyResult<Bound<'py, PyArray1<bool>>> {
        if !(sensor.0.is_finite() && sensor.1.is_finite()) {
            return Err(value_error(
                "sensor",
                format_args!("must be a finite (x, y) position, got {sensor:?}"),
            ));
        }
        let targets = borrow(&targets, "targets")?;
        let t = finite_points(&targets, "targets")?;
        let sight = &self.0;
        let s = [sensor.0, sensor.1];
        let visible = detached(py, || {
            crate::memory::collected("targets", t.chunks_exact(2).map(|q| sight.visible(s, [q[0], q[1]])))
        })?;
        Ok(PyArray1::from_vec(py, visible))
    }
}

#[pyclass(name = "DetectionModel", module = "ctxmodels._core", frozen)]
pub struct PyDetectionModel(DetectionModel);

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
        other => Err(PyValueError::new_err(format!(
            "rule: must be one of 'mean', 'cubature', 'unscented', 'gauss-hermite', got {other:?}"
        ))),
    }
}

#[pymethods]
impl PyDetectionModel {
    /// `factors`: floats (constants), RangeBands, AngularSector, LandMask (0 on land),
    /// LineOfSight (0 when shadowed), DetectionEstimate (shared, read as it stands). P_D is
    /// their product.
    #[new]
    fn new(factors: Vec<Bound<'_, PyAny>>) -> PyResult<Self> {
        // (one entry per factor of the Python list, which exists)
        let mut converted = Vec::with_capacity(factors.len());
        for (i, f) in factors.iter().enumerate() {
            converted.push(if let Ok(b) = f.cast::<PyRangeBands>() {
                DetectionFactor::Range(b.get().0.clone())
            } else if let Ok(s) = f.cast::<PyAngularSector>() {
                DetectionFactor::Sector(s.get().0.clone())
            } else if let Ok(l) = f.cast::<PyLandMask>() {
                DetectionFactor::Land(l.get().0.clone())
            } else if let Ok(l) = f.cast::<PyLineOfSight>() {
                DetectionFactor::Sight(l.get().0.clone())
            } else if let Ok(e) = f.cast::<detection_estimate::PyDetectionEstimate>() {
                DetectionFactor::Estimate(e.get().0.clone())
            } else if let Ok(v) = f.extract::<f64>() {
                DetectionFactor::Constant(v)
            } else {
                return Err(PyTypeError::new_err(format!(
                    "factors: factor {i} is a {}, expected a float, RangeBands, AngularSector, LandMask, LineOfSight or DetectionEstimate",
                    f.get_type().name()?
                )));
            });
        }
        Ok(PyDetectionModel(DetectionModel::new(converted).map_err(to_py)?))
    }

    /// P_D at the positions of `states` (N, D) for a sensor at `pose` (x, y, heading).
    #[pyo3(signature = (pose, states, position_mapping = (0, 2), out = None))]
    fn evaluate<'py>(
        &self,
        py: Python<'py>,
        pose: (f64, f64, f64),
        states: Bound<'py, PyArray2<f64>>,
        position_mapping: (i64, i64),
        out: Option<Bound<'py, PyArray1<f64>>>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let pose = pose_of(pose)?;
        let mapping = mapping_of(position_mapping)?;
        let (n, ncols) = (states.shape()[0], states.shape()[1]);
        let states = borrow(&states, "states")?;
        let data = slice(&states, "states")?;
        let mut out = output(py, out, n, &[("states", data)])?;
        let result = Bound::clone(&out);
        let buffer = out
            .as_slice_mut()
            .map_err(|_| value_error("out", "must be C-contiguous"))?;
        let model = &self.0;
        detached(py, || {
            if n == 0 {
                return Ok(());
            }
            model.at_pose(&pose).at_states(data, ncols, mapping, buffer)
        })?;
        Ok(result)
    }

    /// P_D at each particle of `particles` (D, N), C- or Fortran-ordered, read in place;
    /// `log`: log P_D (log 0 = -inf, NumPy's bits); `missed`: also 1 − P_D (or its log),
    /// returned as a pair.
    #[pyo3(signature = (pose, particles, position_mapping = (0, 2), log = false, missed = false))]
    fn evaluate_particles<'py>(
        &self,
        py: Python<'py>,
        pose: (f64, f64, f64),
        particles: Bound<'py, PyArray2<f64>>,
        position_mapping: (i64, i64),
        log: bool,
        missed: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        particles::evaluate(py, &self.0, pose, particles, position_mapping, log, missed)
    }

    /// Expected P_D of Gaussians (`means` (N, D), `covars` (N, D, D)) under `rule`.
    #[pyo3(signature = (pose, means, covars, position_mapping = (0, 2), rule = "cubature", order = 3, out = None))]
    #[allow(clippy::too_many_arguments)]
    fn expected<'py>(
        &self,
        py: Python<'py>,
        pose: (f64, f64, f64),
        means: Bound<'py, PyArray2<f64>>,
        covars: Bound<'py, PyArray3<f64>>,
        position_mapping: (i64, i64),
        rule: &str,
        order: i64,
        out: Option<Bound<'py, PyArray1<f64>>>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let pose = pose_of(pose)?;
        let mapping = mapping_of(position_mapping)?;
        let rule = rule_of(rule, order)?;
        let (n, ncols) = (means.shape()[0], means.shape()[1]);
        let cshape = covars.shape();
        if cshape[0] != n || cshape[1] != ncols || cshape[2] != ncols {
            return Err(value_error(
                "covars",
                format_args!("must have shape ({n}, {ncols}, {ncols}) to match means, got {cshape:?}"),
            ));
        }
        let means = borrow(&means, "means")?;
        let m = slice(&means, "means")?;
        let covars = borrow(&covars, "covars")?;
        let c = slice(&covars, "covars")?;
        let mut out = output(py, out, n, &[("means", m), ("covars", c)])?;
        let result = Bound::clone(&out);
        let buffer = out
            .as_slice_mut()
            .map_err(|_| value_error("out", "must be C-contiguous"))?;
        let model = &self.0;
        detached(py, || {
            if n == 0 {
                return Ok(());
            }
            model
                .at_pose(&pose)
                .expected_at_gaussians(m, c, ncols, mapping, &rule, buffer)
        })?;
        Ok(result)
    }
}

#[pyclass(name = "CoastalBand", module = "ctxmodels._core", frozen)]
pub struct PyCoastalBand(Arc<CoastalBand>);

#[pymethods]
impl PyCoastalBand {
    /// λ × `inside` within `width` m of `land`'s coastline (`seen_only`: coast the sensor
    /// sees), × 1 elsewhere.
    #[new]
    fn new(land: &Bound<'_, PyLandMask>, width: f64, inside: f64, seen_only: bool) -> PyResult<Self> {
        let land = land.get().0.clone();
        Ok(PyCoastalBand(Arc::new(guarded(|| {
            CoastalBand::new(land, width, inside, seen_only)
        })?)))
    }

    /// The factor at world `positions` (M, 2) for a sensor at `pose`.
    fn evaluate<'py>(
        &self,
        py: Python<'py>,
        pose: (f64, f64, f64),
        positions: Bound<'py, PyArray2<f64>>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let pose = pose_of(pose)?;
        let positions = borrow(&positions, "positions")?;
        let p = points_slice(&positions, "positions")?;
        let band = &self.0;
        Ok(PyArray1::from_vec(py, guarded(|| band.evaluate([pose.x, pose.y], p))?))
    }
}

#[pyclass(name = "MetadataThreshold", module = "ctxmodels._core", frozen, skip_from_py_object)]
pub struct PyMetadataThreshold(MetadataThreshold);

#[pymethods]
impl PyMetadataThreshold {
    #[new]
    #[pyo3(signature = (column, threshold, below, at_or_above, missing = None))]
    fn new(column: usize, threshold: f64, below: f64, at_or_above: f64, missing: Option<f64>) -> Self {
        PyMetadataThreshold(MetadataThreshold {
            column,
            threshold,
            below,
            at_or_above,
            missing,
        })
    }
}

#[pyclass(name = "ClutterModel", module = "ctxmodels._core", frozen)]
pub struct PyClutterModel(ClutterModel);

#[pymethods]
impl PyClutterModel {
    /// `factors`: floats (constants), RangeBands (over range from the sensor) and
    /// MetadataThreshold rules. λ is their product.
    #[new]
    fn new(factors: Vec<Bound<'_, PyAny>>) -> PyResult<Self> {
        // (one entry per factor of the Python list, which exists)
        let mut converted = Vec::with_capacity(factors.len());
        for (i, f) in factors.iter().enumerate() {
            converted.push(if let Ok(b) = f.cast::<PyRangeBands>() {
                ClutterFactor::Range(b.get().0.clone())
            } else if let Ok(m) = f.cast::<PyMetadataThreshold>() {
                ClutterFactor::Metadata(m.get().0.clone())
            } else if let Ok(map) = f.cast::<clutter_map::PyClutterMap>() {
                ClutterFactor::Map(map.get().0.clone())
            } else if let Ok(band) = f.cast::<PyCoastalBand>() {
                ClutterFactor::Coast(band.get().0.clone())
            } else if let Ok(v) = f.extract::<f64>() {
                ClutterFactor::Constant(v)
            } else {
                return Err(PyTypeError::new_err(format!(
                    "factors: factor {i} is a {}, expected a float, RangeBands, MetadataThreshold, ClutterMap or CoastalBand",
                    f.get_type().name()?
                )));
            });
        }
        Ok(PyClutterModel(ClutterModel::new(converted).map_err(to_py)?))
    }

    #[getter]
    fn metadata_columns(&self) -> usize {
        self.0.metadata_columns()
    }

    #[getter]
    fn uses_position(&self) -> bool {
        self.0.uses_position()
    }

    /// λ at world `positions` (M, 2) with `metadata` (M, metadata_columns), NaN = missing;
    /// range bands read `ranges[i]` (a measured range) where given and not NaN.
    #[pyo3(signature = (pose, positions, metadata, out = None, ranges = None))]
    fn evaluate<'py>(
        &self,
        py: Python<'py>,
        pose: (f64, f64, f64),
        positions: Bound<'py, PyArray2<f64>>,
        metadata: Bound<'py, PyArray2<f64>>,
        out: Option<Bound<'py, PyArray1<f64>>>,
        ranges: Option<Bound<'py, PyArray1<f64>>>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let pose = pose_of(pose)?;
        let n = positions.shape()[0];
        let positions = borrow(&positions, "positions")?;
        let p = points_slice(&positions, "positions")?;
        let metadata = borrow(&metadata, "metadata")?;
        let m = slice(&metadata, "metadata")?;
        let ranges = ranges.map(|r| borrow(&r, "ranges")).transpose()?;
        let r = ranges.as_ref().map(|r| slice(r, "ranges")).transpose()?;
        let mut inputs = vec![("positions", p), ("metadata", m)];
        inputs.extend(r.map(|r| ("ranges", r)));
        let mut out = output(py, out, n, &inputs)?;
        let result = Bound::clone(&out);
        let buffer = out
            .as_slice_mut()
            .map_err(|_| value_error("out", "must be C-contiguous"))?;
        let model = &self.0;
        detached(py, || model.evaluate_with_ranges(&pose, p, m, r, buffer))?;
        Ok(result)
    }
}

/// The pose (x, y, heading) of a sensor mounted on a platform at `pose`.
#[pyfunction]
fn mount(pose: (f64, f64, f64), forward: f64, left: f64, yaw: f64) -> PyResult<(f64, f64, f64)> {
    let mounted = pose_of(pose)?
        .mount(&Mounting::new(forward, left, yaw).map_err(to_py)?)
        .map_err(to_py)?;
    Ok((mounted.x, mounted.y, mounted.heading))
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
    m.add_class::<PyRangeBands>()?;
    m.add_class::<PyAngularSector>()?;
    m.add_class::<PyLandMask>()?;
    m.add_class::<PyLineOfSight>()?;
    m.add_class::<PyDetectionModel>()?;
    m.add_class::<at_pose::PyDetectionAtPose>()?;
    m.add_class::<at_pose::PyClutterAtPose>()?;
    m.add_class::<PyMetadataThreshold>()?;
    m.add_class::<PyClutterModel>()?;
    m.add_class::<clutter_map::PyClutterMap>()?;
    m.add_class::<PyCoastalBand>()?;
    m.add_class::<detection_estimate::PyDetectionEstimate>()?;
    m.add_function(wrap_pyfunction!(mount, m)?)?;
    m.add_function(wrap_pyfunction!(rule_points, m)?)?;
    m.add_function(wrap_pyfunction!(simd_backend, m)?)?;
    m.add(
        "NotPositiveDefiniteError",
        m.py().get_type::<NotPositiveDefiniteError>(),
    )?;
    m.add(
        "InfeasibleAssignmentError",
        m.py().get_type::<InfeasibleAssignmentError>(),
    )?;
    kalman::register(m)?;
    gmphd::register(m)?;
    jpda::register(m)?;
    initiation::register(m)?;
    Ok(())
}
