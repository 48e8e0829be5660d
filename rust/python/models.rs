//! The detection and clutter models and the factors they are built from, as Python classes:
//! RangeBands, AngularSector, LandMask, LineOfSight, DetectionModel, CoastalBand,
//! MetadataThreshold, Zone and ClutterModel. One file: a model's constructor tells its factors
//! apart by their classes and reads what they hold, so the factor classes sit beside the
//! two models that take them.

use super::{
    borrow, clutter_map, detached, detection_estimate, finite_points, guarded, mapping_of, output, particles,
    points_slice, pose_of, rule_of, shape_error, slice, to_py, type_error, value_error, MappingTuple, PoseTuple,
};
use crate::clutter::{ClutterFactor, ClutterModel, MetadataThreshold};
use crate::coast::CoastalBand;
use crate::detection::{DetectionFactor, DetectionModel};
use crate::error::ModelError;
use crate::land::{LandMask, Polygon};
use crate::range_bands::RangeBands;
use crate::sector::AngularSector;
use crate::sight::LineOfSight;
use crate::zone::Zone;
use numpy::{PyArray1, PyArray2, PyArray3, PyUntypedArrayMethods};
use pyo3::prelude::*;
use std::sync::Arc;

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
        .map_err(|_| type_error("polygons", "every ring must be a (K, 2) float64 array"))?;
    if array.shape()[1] != 2 {
        return Err(shape_error(
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

#[pyclass(name = "LineOfSight", module = "ctxmodels._core", frozen)]
pub struct PyLineOfSight(Arc<LineOfSight>);

#[pymethods]
impl PyLineOfSight {
    #[new]
    #[pyo3(signature = (land, clearance = 0.0))]
    fn new(py: Python<'_>, land: &PyLandMask, clearance: f64) -> PyResult<Self> {
        let land = land.0.clone();
        Ok(PyLineOfSight(Arc::new(detached(py, || {
            LineOfSight::with_clearance(land, clearance)
        })?)))
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
pub struct PyDetectionModel(pub(super) DetectionModel);

#[pymethods]
impl PyDetectionModel {
    /// `factors`: floats (constants), RangeBands, AngularSector, RadarEquation, ElevationSector,
    /// Horizon, LandMask (0 on land),
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
            } else if let Ok(r) = f.cast::<super::radar::PyRadarEquation>() {
                DetectionFactor::Radar(r.get().0.clone())
            } else if let Ok(e) = f.cast::<super::heights::PyElevationSector>() {
                DetectionFactor::Elevation(e.get().0.clone())
            } else if let Ok(h) = f.cast::<super::heights::PyHorizon>() {
                DetectionFactor::Horizon(h.get().0.clone())
            } else if let Ok(n) = f.cast::<super::range_rate::PyRangeRateNotch>() {
                DetectionFactor::RangeRate(n.get().0.clone())
            } else if let Ok(l) = f.cast::<PyLandMask>() {
                DetectionFactor::Land(l.get().0.clone())
            } else if let Ok(l) = f.cast::<PyLineOfSight>() {
                DetectionFactor::Sight(l.get().0.clone())
            } else if let Ok(e) = f.cast::<detection_estimate::PyDetectionEstimate>() {
                DetectionFactor::Estimate(e.get().0.clone())
            } else if let Ok(v) = f.extract::<f64>() {
                DetectionFactor::Constant(v)
            } else {
                return Err(type_error(
                    "factors",
                    format_args!(
                        "factor {i} is a {}, expected a float, RangeBands, AngularSector, RadarEquation, ElevationSector, Horizon, RangeRateNotch, LandMask, LineOfSight or DetectionEstimate",
                        f.get_type().name()?
                    ),
                ));
            });
        }
        Ok(PyDetectionModel(DetectionModel::new(converted).map_err(to_py)?))
    }

    /// P_D at the positions of `states` (N, D) for a sensor at `pose` (x, y, heading).
    #[pyo3(signature = (pose, states, position_mapping = MappingTuple::Flat((0, 2)), out = None))]
    fn evaluate<'py>(
        &self,
        py: Python<'py>,
        pose: PoseTuple,
        states: Bound<'py, PyArray2<f64>>,
        position_mapping: MappingTuple,
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
    #[pyo3(signature = (pose, particles, position_mapping = MappingTuple::Flat((0, 2)), log = false, missed = false))]
    fn evaluate_particles<'py>(
        &self,
        py: Python<'py>,
        pose: PoseTuple,
        particles: Bound<'py, PyArray2<f64>>,
        position_mapping: MappingTuple,
        log: bool,
        missed: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        particles::evaluate(py, &self.0, pose, particles, position_mapping, log, missed)
    }

    /// Expected P_D of Gaussians (`means` (N, D), `covars` (N, D, D)) under `rule`.
    #[pyo3(signature = (pose, means, covars, position_mapping = MappingTuple::Flat((0, 2)), rule = "cubature", order = 3, out = None))]
    #[allow(clippy::too_many_arguments)]
    fn expected<'py>(
        &self,
        py: Python<'py>,
        pose: PoseTuple,
        means: Bound<'py, PyArray2<f64>>,
        covars: Bound<'py, PyArray3<f64>>,
        position_mapping: MappingTuple,
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
            return Err(shape_error(
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

#[pyclass(name = "Zone", module = "ctxmodels._core", frozen)]
pub struct PyZone(Arc<Zone>);

#[pymethods]
impl PyZone {
    /// `inside` within `polygons` (boundary included), `outside` elsewhere.
    #[new]
    fn new(polygons: &Bound<'_, PyLandMask>, inside: f64, outside: f64) -> PyResult<Self> {
        let polygons = polygons.get().0.clone();
        Ok(PyZone(Arc::new(Zone::new(polygons, inside, outside).map_err(to_py)?)))
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
        pose: PoseTuple,
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
pub struct PyClutterModel(pub(super) ClutterModel);

#[pymethods]
impl PyClutterModel {
    /// `factors`: floats (constants), RangeBands (over range from the sensor),
    /// MetadataThreshold rules, clutter maps, coastal bands, zones and elevation sectors.
    /// λ is their product.
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
            } else if let Ok(zone) = f.cast::<PyZone>() {
                ClutterFactor::Zone(zone.get().0.clone())
            } else if let Ok(e) = f.cast::<super::heights::PyElevationSector>() {
                ClutterFactor::Elevation(e.get().0.clone())
            } else if let Ok(v) = f.extract::<f64>() {
                ClutterFactor::Constant(v)
            } else {
                return Err(type_error(
                    "factors",
                    format_args!(
                        "factor {i} is a {}, expected a float, RangeBands, MetadataThreshold, ClutterMap, CoastalBand, Zone or ElevationSector",
                        f.get_type().name()?
                    ),
                ));
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

    #[getter]
    fn uses_height(&self) -> bool {
        self.0.uses_height()
    }

    /// λ at world `positions` (M, 2), or (M, 3) with heights (slant ranges, elevations),
    /// with `metadata` (M, metadata_columns), NaN = missing; range bands read `ranges[i]`
    /// (a measured range) where given and not NaN.
    #[pyo3(signature = (pose, positions, metadata, out = None, ranges = None))]
    fn evaluate<'py>(
        &self,
        py: Python<'py>,
        pose: PoseTuple,
        positions: Bound<'py, PyArray2<f64>>,
        metadata: Bound<'py, PyArray2<f64>>,
        out: Option<Bound<'py, PyArray1<f64>>>,
        ranges: Option<Bound<'py, PyArray1<f64>>>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let pose = pose_of(pose)?;
        let n = positions.shape()[0];
        let ncols = positions.shape()[1];
        if !(ncols == 2 || ncols == 3) {
            return Err(shape_error(
                "positions",
                format_args!("must have shape (M, 2) or (M, 3), got {:?}", positions.shape()),
            ));
        }
        let positions = borrow(&positions, "positions")?;
        let p = slice(&positions, "positions")?;
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
        detached(py, || model.evaluate_rows(&pose, p, ncols, m, r, buffer))?;
        Ok(result)
    }
}
