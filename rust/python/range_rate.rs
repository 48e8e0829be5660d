//! The range-rate notch ([`crate::range_rate`]) as the Python class `RangeRateNotch`.

use super::to_py;
use crate::range_rate::RangeRateNotch;
use pyo3::prelude::*;

#[pyclass(name = "RangeRateNotch", module = "ctxmodels._core", frozen, skip_from_py_object)]
pub struct PyRangeRateNotch(pub(super) RangeRateNotch);

#[pymethods]
impl PyRangeRateNotch {
    #[new]
    #[pyo3(signature = (width, blind_speed, multiples, inside, outside))]
    fn new(width: f64, blind_speed: Option<f64>, multiples: u32, inside: f64, outside: f64) -> PyResult<Self> {
        Ok(PyRangeRateNotch(
            RangeRateNotch::new(width, blind_speed, multiples, inside, outside).map_err(to_py)?,
        ))
    }
}
