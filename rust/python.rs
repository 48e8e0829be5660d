//! The only module that knows about Python: converts arguments at the boundary, releases
//! the GIL around evaluation, and turns core errors (and, defensively, panics) into Python
//! exceptions. Input arrays arrive as C-contiguous float64 (the Python layer converts).

use crate::batch::PositionMapping;
use crate::clutter::{ClutterFactor, ClutterModel, MetadataThreshold};
use crate::cubature::Rule;
use crate::detection::{DetectionFactor, DetectionModel};
use crate::error::ModelError;
use crate::land::{LandMask, Polygon};
use crate::pose::{Mounting, Pose};
use crate::range_bands::RangeBands;
use crate::sector::AngularSector;
use crate::sight::LineOfSight;
use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2, PyReadonlyArray3, PyReadwriteArray1, PyUntypedArrayMethods};
use pyo3::exceptions::{PyRuntimeError, PyTypeError, PyValueError};
use pyo3::prelude::*;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::Arc;

fn to_py(err: ModelError) -> PyErr {
    PyValueError::new_err(err.to_string())
}

/// Runs `f` with the GIL released; a panic becomes a RuntimeError instead of unwinding
/// into the interpreter.
fn detached<T: Send>(py: Python<'_>, f: impl FnOnce() -> crate::Result<T> + Send) -> PyResult<T> {
    let result = py.detach(|| catch_unwind(AssertUnwindSafe(f)));
    match result {
        Ok(inner) => inner.map_err(to_py),
        Err(_) => Err(PyRuntimeError::new_err("ctxmodels internal error (a bug: please report it with the inputs)")),
    }
}

fn slice<'a, T: numpy::Element>(a: &'a PyReadonlyArray2<'_, T>, argument: &str) -> PyResult<&'a [T]> {
    // as_slice also accepts Fortran order, which would be read as rows: wrong numbers.
    if !a.is_c_contiguous() {
        return Err(PyValueError::new_err(format!("{argument}: must be C-contiguous")));
    }
    a.as_slice().map_err(|_| PyValueError::new_err(format!("{argument}: must be C-contiguous")))
}

fn pose_of(pose: (f64, f64, f64)) -> PyResult<Pose> {
    Pose::new(pose.0, pose.1, pose.2).map_err(to_py)
}

fn mapping_of(mapping: (i64, i64)) -> PyResult<PositionMapping> {
    if mapping.0 < 0 || mapping.1 < 0 {
        return Err(PyValueError::new_err(format!("position_mapping: indices must be >= 0, got {mapping:?}")));
    }
    PositionMapping::new(mapping.0 as usize, mapping.1 as usize).map_err(to_py)
}

/// The output buffer: the caller's `out` (checked) or a new array.
fn output<'py>(py: Python<'py>, out: Option<PyReadwriteArray1<'py, f64>>, n: usize) -> PyResult<Bound<'py, PyArray1<f64>>> {
    match out {
        Some(out) => {
            if out.len() != n {
                return Err(PyValueError::new_err(format!("out: must have {n} entries, got {}", out.len())));
            }
            if !out.is_c_contiguous() {
                return Err(PyValueError::new_err("out: must be C-contiguous"));
            }
            Ok(out.as_array_bound())
        }
        None => Ok(PyArray1::zeros(py, [n], false)),
    }
}

trait AsBound<'py> {
    fn as_array_bound(&self) -> Bound<'py, PyArray1<f64>>;
}

impl<'py> AsBound<'py> for PyReadwriteArray1<'py, f64> {
    fn as_array_bound(&self) -> Bound<'py, PyArray1<f64>> {
        let readonly: &Bound<'py, PyArray1<f64>> = self;
        readonly.clone()
    }
}

#[pyclass(name = "RangeBands", module = "ctxmodels._core", frozen, skip_from_py_object)]
pub struct PyRangeBands(RangeBands);

#[pymethods]
impl PyRangeBands {
    #[new]
    fn new(edges: Vec<f64>, values: Vec<f64>, upper_owns: Vec<bool>) -> PyResult<Self> {
        Ok(PyRangeBands(RangeBands::new(edges, values, upper_owns).map_err(to_py)?))
    }

    /// Values at each of `ranges`.
    fn at<'py>(&self, py: Python<'py>, ranges: PyReadonlyArray1<'py, f64>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let r = ranges.as_slice().map_err(|_| PyValueError::new_err("ranges: must be contiguous"))?;
        Ok(PyArray1::from_vec(py, r.iter().map(|&x| self.0.at(x)).collect()))
    }
}

#[pyclass(name = "AngularSector", module = "ctxmodels._core", frozen, skip_from_py_object)]
pub struct PyAngularSector(AngularSector);

#[pymethods]
impl PyAngularSector {
    #[new]
    fn new(centre: f64, width: f64, inside: f64, outside: f64) -> PyResult<Self> {
        Ok(PyAngularSector(AngularSector::new(centre, width, inside, outside).map_err(to_py)?))
    }
}

#[pyclass(name = "LandMask", module = "ctxmodels._core", frozen)]
pub struct PyLandMask(Arc<LandMask>);

fn ring_of(ring: &Bound<'_, PyAny>) -> PyResult<Vec<[f64; 2]>> {
    let array: PyReadonlyArray2<f64> = ring
        .extract()
        .map_err(|_| PyTypeError::new_err("polygons: every ring must be a (K, 2) float64 array"))?;
    if array.shape()[1] != 2 {
        return Err(PyValueError::new_err(format!("polygons: every ring must have shape (K, 2), got {:?}", array.shape())));
    }
    let a = array.as_array();
    Ok(a.rows().into_iter().map(|r| [r[0], r[1]]).collect())
}

#[pymethods]
impl PyLandMask {
    /// `polygons`: list of (shell, [holes]) with rings as (K, 2) float64 arrays.
    #[new]
    fn new(py: Python<'_>, polygons: Vec<(Bound<'_, PyAny>, Vec<Bound<'_, PyAny>>)>) -> PyResult<Self> {
        let mut converted = Vec::with_capacity(polygons.len());
        for (shell, holes) in &polygons {
            converted.push(Polygon { shell: ring_of(shell)?, holes: holes.iter().map(ring_of).collect::<PyResult<_>>()? });
        }
        Ok(PyLandMask(Arc::new(detached(py, || LandMask::new(converted))?)))
    }

    /// Whether each (x, y) row of `points` is on land (boundary included).
    fn contains<'py>(&self, py: Python<'py>, points: PyReadonlyArray2<'py, f64>) -> PyResult<Bound<'py, PyArray1<bool>>> {
        let p = points_slice(&points, "points")?;
        let land = &self.0;
        let inside = detached(py, || Ok(p.chunks_exact(2).map(|q| land.contains([q[0], q[1]])).collect::<Vec<_>>()))?;
        Ok(PyArray1::from_vec(py, inside))
    }

    #[getter]
    fn vertex_count(&self) -> usize {
        self.0.vertex_count()
    }
}

fn points_slice<'a>(points: &'a PyReadonlyArray2<'_, f64>, argument: &str) -> PyResult<&'a [f64]> {
    if points.shape()[1] != 2 {
        return Err(PyValueError::new_err(format!("{argument}: must have shape (M, 2), got {:?}", points.shape())));
    }
    slice(points, argument)
}

#[pyclass(name = "LineOfSight", module = "ctxmodels._core", frozen)]
pub struct PyLineOfSight(Arc<LineOfSight>);

#[pymethods]
impl PyLineOfSight {
    #[new]
    fn new(py: Python<'_>, land: &PyLandMask) -> PyResult<Self> {
        let land = land.0.clone();
        Ok(PyLineOfSight(Arc::new(detached(py, || Ok(LineOfSight::new(land)))?)))
    }

    /// Whether each target row of `targets` (M, 2) is visible from `sensor` (x, y).
    fn visible<'py>(&self, py: Python<'py>, sensor: (f64, f64), targets: PyReadonlyArray2<'py, f64>) -> PyResult<Bound<'py, PyArray1<bool>>> {
        let t = points_slice(&targets, "targets")?;
        let sight = &self.0;
        let s = [sensor.0, sensor.1];
        let visible = detached(py, || Ok(t.chunks_exact(2).map(|q| sight.visible(s, [q[0], q[1]])).collect::<Vec<_>>()))?;
        Ok(PyArray1::from_vec(py, visible))
    }
}

#[pyclass(name = "DetectionModel", module = "ctxmodels._core", frozen)]
pub struct PyDetectionModel(DetectionModel);

fn rule_of(rule: &str, order: usize) -> PyResult<Rule> {
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
    /// LineOfSight (0 when shadowed). P_D is their product.
    #[new]
    fn new(factors: Vec<Bound<'_, PyAny>>) -> PyResult<Self> {
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
            } else if let Ok(v) = f.extract::<f64>() {
                DetectionFactor::Constant(v)
            } else {
                return Err(PyTypeError::new_err(format!(
                    "factors: factor {i} is a {}, expected a float, RangeBands, AngularSector, LandMask or LineOfSight",
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
        states: PyReadonlyArray2<'py, f64>,
        position_mapping: (i64, i64),
        out: Option<PyReadwriteArray1<'py, f64>>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let pose = pose_of(pose)?;
        let mapping = mapping_of(position_mapping)?;
        let ncols = states.shape()[1];
        let n = states.shape()[0];
        let data = slice(&states, "states")?;
        let result = output(py, out, n)?;
        let mut rw = result.readwrite();
        let buffer = rw.as_slice_mut().map_err(|_| PyValueError::new_err("out: must be C-contiguous"))?;
        let model = &self.0;
        detached(py, || {
            if n == 0 {
                return Ok(());
            }
            model.at_pose(&pose).at_states(data, ncols, mapping, buffer)
        })?;
        drop(rw);
        Ok(result)
    }

    /// Expected P_D of Gaussians (`means` (N, D), `covars` (N, D, D)) under `rule`.
    #[pyo3(signature = (pose, means, covars, position_mapping = (0, 2), rule = "cubature", order = 3, out = None))]
    #[allow(clippy::too_many_arguments)]
    fn expected<'py>(
        &self,
        py: Python<'py>,
        pose: (f64, f64, f64),
        means: PyReadonlyArray2<'py, f64>,
        covars: PyReadonlyArray3<'py, f64>,
        position_mapping: (i64, i64),
        rule: &str,
        order: usize,
        out: Option<PyReadwriteArray1<'py, f64>>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let pose = pose_of(pose)?;
        let mapping = mapping_of(position_mapping)?;
        let rule = rule_of(rule, order)?;
        let (n, ncols) = (means.shape()[0], means.shape()[1]);
        let cshape = covars.shape();
        if cshape[0] != n || cshape[1] != ncols || cshape[2] != ncols {
            return Err(PyValueError::new_err(format!("covars: must have shape ({n}, {ncols}, {ncols}) to match means, got {cshape:?}")));
        }
        let m = slice(&means, "means")?;
        if !covars.is_c_contiguous() {
            return Err(PyValueError::new_err("covars: must be C-contiguous"));
        }
        let c = covars.as_slice().map_err(|_| PyValueError::new_err("covars: must be C-contiguous"))?;
        let result = output(py, out, n)?;
        let mut rw = result.readwrite();
        let buffer = rw.as_slice_mut().map_err(|_| PyValueError::new_err("out: must be C-contiguous"))?;
        let model = &self.0;
        detached(py, || {
            if n == 0 {
                return Ok(());
            }
            model.at_pose(&pose).expected_at_gaussians(m, c, ncols, mapping, &rule, buffer)
        })?;
        drop(rw);
        Ok(result)
    }
}

#[pyclass(name = "MetadataThreshold", module = "ctxmodels._core", frozen, skip_from_py_object)]
pub struct PyMetadataThreshold(MetadataThreshold);

#[pymethods]
impl PyMetadataThreshold {
    #[new]
    #[pyo3(signature = (column, threshold, below, at_or_above, missing = None))]
    fn new(column: usize, threshold: f64, below: f64, at_or_above: f64, missing: Option<f64>) -> Self {
        PyMetadataThreshold(MetadataThreshold { column, threshold, below, at_or_above, missing })
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
        let mut converted = Vec::with_capacity(factors.len());
        for (i, f) in factors.iter().enumerate() {
            converted.push(if let Ok(b) = f.cast::<PyRangeBands>() {
                ClutterFactor::Range(b.get().0.clone())
            } else if let Ok(m) = f.cast::<PyMetadataThreshold>() {
                ClutterFactor::Metadata(m.get().0.clone())
            } else if let Ok(v) = f.extract::<f64>() {
                ClutterFactor::Constant(v)
            } else {
                return Err(PyTypeError::new_err(format!(
                    "factors: factor {i} is a {}, expected a float, RangeBands or MetadataThreshold",
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

    /// λ at world `positions` (M, 2) with `metadata` (M, metadata_columns), NaN = missing.
    #[pyo3(signature = (pose, positions, metadata, out = None))]
    fn evaluate<'py>(
        &self,
        py: Python<'py>,
        pose: (f64, f64, f64),
        positions: PyReadonlyArray2<'py, f64>,
        metadata: PyReadonlyArray2<'py, f64>,
        out: Option<PyReadwriteArray1<'py, f64>>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let pose = pose_of(pose)?;
        let p = points_slice(&positions, "positions")?;
        let m = slice(&metadata, "metadata")?;
        let n = positions.shape()[0];
        let result = output(py, out, n)?;
        let mut rw = result.readwrite();
        let buffer = rw.as_slice_mut().map_err(|_| PyValueError::new_err("out: must be C-contiguous"))?;
        let model = &self.0;
        detached(py, || model.evaluate(&pose, p, m, buffer))?;
        drop(rw);
        Ok(result)
    }
}

/// The pose (x, y, heading) of a sensor mounted on a platform at `pose`.
#[pyfunction]
fn mount(pose: (f64, f64, f64), forward: f64, left: f64, yaw: f64) -> PyResult<(f64, f64, f64)> {
    let mounted = pose_of(pose)?.mount(&Mounting::new(forward, left, yaw).map_err(to_py)?);
    Ok((mounted.x, mounted.y, mounted.heading))
}

/// Points and weights of an integration rule in standard-normal space.
#[pyfunction]
#[pyo3(signature = (rule, order = 3))]
fn rule_points(rule: &str, order: usize) -> PyResult<(Vec<(f64, f64)>, Vec<f64>)> {
    let r = rule_of(rule, order)?;
    Ok((r.points().iter().map(|p| (p[0], p[1])).collect(), r.weights().to_vec()))
}

#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyRangeBands>()?;
    m.add_class::<PyAngularSector>()?;
    m.add_class::<PyLandMask>()?;
    m.add_class::<PyLineOfSight>()?;
    m.add_class::<PyDetectionModel>()?;
    m.add_class::<PyMetadataThreshold>()?;
    m.add_class::<PyClutterModel>()?;
    m.add_function(wrap_pyfunction!(mount, m)?)?;
    m.add_function(wrap_pyfunction!(rule_points, m)?)?;
    Ok(())
}
