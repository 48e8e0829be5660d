//! The radar equation's P_D ([`crate::radar`]) as the Python class `RadarEquation`.

use super::{borrow, slice, to_py};
use crate::radar::{RadarEquation, Swerling};
use numpy::PyArray1;
use pyo3::prelude::*;

#[pyclass(name = "RadarEquation", module = "ctxmodels._core", frozen, skip_from_py_object)]
pub struct PyRadarEquation(pub(super) RadarEquation);

#[pymethods]
impl PyRadarEquation {
    #[new]
    fn new(
        reference_snr: f64,
        reference_range: f64,
        loss: f64,
        false_alarm_probability: f64,
        swerling: u8,
        pulses: u64,
    ) -> PyResult<Self> {
        let swerling = Swerling::from_case(swerling).map_err(to_py)?;
        RadarEquation::new(
            reference_snr,
            reference_range,
            loss,
            false_alarm_probability,
            swerling,
            pulses,
        )
        .map(PyRadarEquation)
        .map_err(to_py)
    }

    /// The detection threshold on the sum of the pulses' powers (noise power 1).
    #[getter]
    fn threshold(&self) -> f64 {
        self.0.threshold()
    }

    /// P_D at each of `ranges` (metres; NaN gives NaN).
    fn at<'py>(&self, py: Python<'py>, ranges: Bound<'py, PyArray1<f64>>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        self.each(py, ranges, |radar, r| radar.at(r))
    }

    /// The per-pulse SNR (linear) at each of `ranges`.
    fn snr<'py>(&self, py: Python<'py>, ranges: Bound<'py, PyArray1<f64>>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        self.each(py, ranges, |radar, r| radar.snr_at_squared(r * r))
    }
}

impl PyRadarEquation {
    fn each<'py>(
        &self,
        py: Python<'py>,
        ranges: Bound<'py, PyArray1<f64>>,
        f: impl Fn(&RadarEquation, f64) -> f64,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let ranges = borrow(&ranges, "ranges")?;
        let r = slice(&ranges, "ranges")?;
        let values = crate::memory::collected("ranges", r.iter().map(|&x| f(&self.0, x))).map_err(to_py)?;
        Ok(PyArray1::from_vec(py, values))
    }
}

pub(super) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyRadarEquation>()?;
    Ok(())
}
