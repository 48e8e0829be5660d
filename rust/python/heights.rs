//! The factors that read a target's height, as Python classes: `ElevationSector`
//! ([`crate::elevation`]) and `Horizon` ([`crate::horizon`], the radar horizon at each
//! target's own height).

use super::to_py;
use crate::elevation::ElevationSector;
use crate::horizon::Horizon;
use pyo3::prelude::*;

#[pyclass(name = "ElevationSector", module = "ctxmodels._core", frozen, skip_from_py_object)]
pub struct PyElevationSector(pub(super) ElevationSector);

#[pymethods]
impl PyElevationSector {
    #[new]
    fn new(lower: f64, upper: f64, inside: f64, outside: f64) -> PyResult<Self> {
        Ok(PyElevationSector(
            ElevationSector::new(lower, upper, inside, outside).map_err(to_py)?,
        ))
    }
}

#[pyclass(name = "Horizon", module = "ctxmodels._core", frozen, skip_from_py_object)]
pub struct PyHorizon(pub(super) Horizon);

#[pymethods]
impl PyHorizon {
    #[new]
    fn new(antenna_reach: f64, scale: f64) -> PyResult<Self> {
        Ok(PyHorizon(Horizon::new(antenna_reach, scale).map_err(to_py)?))
    }
}
