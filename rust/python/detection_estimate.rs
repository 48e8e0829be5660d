//! The learned detection probability at the boundary: one estimate shared (not copied)
//! with every detection model built from it.

use super::{array_of, borrow, guarded, points_slice, pose_of, slice, PoseTuple};
use crate::detection_estimate::{read_estimate, DetectionEstimate, SharedEstimate};
use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use std::sync::{Arc, RwLock};

/// An estimate's (hits, trials) per band.
type HitsAndTrials<'py> = (Bound<'py, PyArray1<f64>>, Bound<'py, PyArray1<f64>>);

#[pyclass(name = "DetectionEstimate", module = "ctxmodels._core", frozen)]
pub struct PyDetectionEstimate(pub(super) SharedEstimate);

#[pymethods]
impl PyDetectionEstimate {
    /// Band `edges` (m of range); the prior's P_D and weight in trials; the forgetting
    /// factor per update; the value outside the bands; optionally a saved state.
    #[new]
    #[pyo3(signature = (edges, prior_probability, prior_trials, forgetting, outside, hits = None, trials = None))]
    fn new(
        edges: Vec<f64>,
        prior_probability: f64,
        prior_trials: f64,
        forgetting: f64,
        outside: f64,
        hits: Option<Vec<f64>>,
        trials: Option<Vec<f64>>,
    ) -> PyResult<Self> {
        let estimate = guarded(|| {
            let estimate = DetectionEstimate::new(edges, prior_probability, prior_trials, forgetting, outside)?;
            match (hits, trials) {
                (None, None) => Ok(estimate),
                (hits, trials) => {
                    let fresh = |saved: Option<Vec<f64>>, argument| {
                        saved.map_or_else(|| crate::memory::copied(argument, estimate.state().0), Ok)
                    };
                    let (hits, trials) = (fresh(hits, "hits")?, fresh(trials, "trials")?);
                    estimate.with_state(hits, trials)
                }
            }
        })?;
        Ok(PyDetectionEstimate(Arc::new(RwLock::new(estimate))))
    }

    /// One scan's trials: track `positions` (M, 2), `detected` (M,) 0/1, `weights` (M,).
    fn update(
        &self,
        pose: PoseTuple,
        positions: Bound<'_, PyArray2<f64>>,
        detected: Bound<'_, PyArray1<f64>>,
        weights: Bound<'_, PyArray1<f64>>,
    ) -> PyResult<()> {
        let pose = pose_of(pose)?;
        let positions = borrow(&positions, "positions")?;
        let p = points_slice(&positions, "positions")?;
        let detected = borrow(&detected, "detected")?;
        let weights = borrow(&weights, "weights")?;
        let (d, w) = (slice(&detected, "detected")?, slice(&weights, "weights")?);
        let estimate = &self.0;
        guarded(|| {
            estimate
                .write()
                .unwrap_or_else(|poisoned| poisoned.into_inner())
                .update(&pose, p, d, w)
        })
    }

    /// The posterior mean P_D of every band.
    fn probabilities<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        Ok(PyArray1::from_vec(
            py,
            guarded(|| read_estimate(&self.0).probabilities())?,
        ))
    }

    /// (hits, trials): the state an update changes.
    fn state<'py>(&self, py: Python<'py>) -> PyResult<HitsAndTrials<'py>> {
        let estimate = read_estimate(&self.0);
        let (hits, trials) = estimate.state();
        Ok((array_of(py, "hits", hits)?, array_of(py, "trials", trials)?))
    }
}
