//! The learned clutter map at the boundary: one estimator shared (not copied) with every
//! clutter model built from it.

use super::{array_of, borrow, guarded, points_slice, pose_of, slice, value_error, PoseTuple};
use crate::clutter::{read_map, SharedMap};
use crate::clutter_map::{ClutterMap, MapSpace, Pooling};
use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use std::sync::{Arc, RwLock};

#[pyclass(name = "ClutterMap", module = "ctxmodels._core", frozen)]
pub struct PyClutterMap(pub(super) SharedMap);

#[pymethods]
impl PyClutterMap {
    /// `space`: "bearing-range", "body-xy" or "world-xy"; `edges0`, `edges1`: the grid's
    /// edges on each axis (bearing or x, then range or y); the prior's intensity and weight
    /// in scans; the forgetting factor per scan; optionally a saved state; the pooling
    /// ("none", "range" or "grid") and its weight in scans (None: estimated per pool).
    #[new]
    #[pyo3(signature = (space, edges0, edges1, prior_intensity, prior_scans, forgetting, counts = None, deficit = None, exposure = 0.0, scale = 1.0, pooling = "none", pooling_scans = Some(10.0)))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        space: &str,
        edges0: Vec<f64>,
        edges1: Vec<f64>,
        prior_intensity: f64,
        prior_scans: f64,
        forgetting: f64,
        counts: Option<Vec<f64>>,
        deficit: Option<Vec<f64>>,
        exposure: f64,
        scale: f64,
        pooling: &str,
        pooling_scans: Option<f64>,
    ) -> PyResult<Self> {
        let space = match space {
            "bearing-range" => MapSpace::BearingRange,
            "body-xy" => MapSpace::BodyXY,
            "world-xy" => MapSpace::WorldXY,
            other => {
                return Err(value_error(
                    "space",
                    format!("must be 'bearing-range', 'body-xy' or 'world-xy', got {other:?}"),
                ))
            }
        };
        let pooling = match pooling {
            "none" => Pooling::None,
            "range" => Pooling::Range,
            "grid" => Pooling::Grid,
            other => {
                return Err(value_error(
                    "pooling",
                    format!("must be 'none', 'range' or 'grid', got {other:?}"),
                ))
            }
        };
        let map = guarded(|| {
            let map = ClutterMap::new(space, [edges0, edges1], prior_intensity, prior_scans, forgetting)?
                .with_pooling(pooling, pooling_scans)?;
            map.with_saved(counts, deficit, exposure, scale)
        })?;
        Ok(PyClutterMap(Arc::new(RwLock::new(map))))
    }

    #[getter]
    fn shape(&self) -> (usize, usize) {
        let [a, b] = read_map(&self.0).shape();
        (a, b)
    }

    /// One scan: its detections' world `positions` (M, 2), measured `ranges` (M,) or None
    /// (NaN entries: from the position), `gates` (G, 3: x, y, radius) around tracks, and
    /// optionally each detection's clutter probability `weights` (M,) in [0, 1].
    #[pyo3(signature = (pose, positions, ranges = None, gates = None, weights = None))]
    fn update(
        &self,
        pose: PoseTuple,
        positions: Bound<'_, PyArray2<f64>>,
        ranges: Option<Bound<'_, PyArray1<f64>>>,
        gates: Option<Bound<'_, PyArray2<f64>>>,
        weights: Option<Bound<'_, PyArray1<f64>>>,
    ) -> PyResult<()> {
        let pose = pose_of(pose)?;
        let positions = borrow(&positions, "positions")?;
        let p = points_slice(&positions, "positions")?;
        let ranges = ranges.map(|r| borrow(&r, "ranges")).transpose()?;
        let r = ranges.as_ref().map(|r| slice(r, "ranges")).transpose()?;
        let gates = gates.map(|g| borrow(&g, "gates")).transpose()?;
        let g = gates.as_ref().map(|g| slice(g, "gates")).transpose()?.unwrap_or(&[]);
        let weights = weights.map(|w| borrow(&w, "weights")).transpose()?;
        let w = weights.as_ref().map(|w| slice(w, "weights")).transpose()?;
        let map = &self.0;
        guarded(|| {
            map.write()
                .unwrap_or_else(|poisoned| poisoned.into_inner())
                .update_weighted(&pose, p, r, w, g)
        })
    }

    /// λ of the map alone at world `positions` (M, 2) (the prior outside the grid).
    #[pyo3(signature = (pose, positions, ranges = None))]
    fn intensity<'py>(
        &self,
        py: Python<'py>,
        pose: PoseTuple,
        positions: Bound<'py, PyArray2<f64>>,
        ranges: Option<Bound<'py, PyArray1<f64>>>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let pose = pose_of(pose)?;
        let positions = borrow(&positions, "positions")?;
        let p = points_slice(&positions, "positions")?;
        let ranges = ranges.map(|r| borrow(&r, "ranges")).transpose()?;
        let r = ranges.as_ref().map(|r| slice(r, "ranges")).transpose()?;
        let map = read_map(&self.0);
        Ok(PyArray1::from_vec(py, guarded(|| map.intensity_at(&pose, p, r))?))
    }

    /// The posterior mean λ of every cell, (n0 · n1,) row-major.
    fn intensities<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        Ok(PyArray1::from_vec(py, guarded(|| read_map(&self.0).intensities())?))
    }

    /// (counts, deficit, exposure, scale): the state an update changes, as stored (see the
    /// core).
    #[allow(clippy::type_complexity)]
    fn state<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<(Bound<'py, PyArray1<f64>>, Bound<'py, PyArray1<f64>>, f64, f64)> {
        let map = read_map(&self.0);
        let (counts, deficit, exposure, scale) = map.state();
        Ok((
            array_of(py, "counts", counts)?,
            array_of(py, "deficit", deficit)?,
            exposure,
            scale,
        ))
    }
}
