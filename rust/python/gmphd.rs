//! Binding of the GM-PHD scan core ([`crate::gmphd`]): a mutable Gaussian mixture kept as
//! arrays between scans.

use super::at_pose::{PyDetectionAtPose, DETACH_ROWS};
use super::kalman::PyMeasurementModel;
use super::{borrow, detached, guarded, shape_error, slice, value_error};
use crate::gmphd::{Mixture, ReduceParams, UpdateParams};
use numpy::{PyArray1, PyArray2, PyArray3, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyTuple;

/// Gaussian components as arrays, updated scan by scan in place (see `ctxmodels.gmphd`).
#[pyclass(name = "GaussianMixtureArrays", module = "ctxmodels._core")]
pub struct PyGaussianMixtureArrays(Mixture);

fn wrong_shape(argument: &str, expected: String, got: &[usize]) -> PyErr {
    shape_error(argument, format_args!("must have shape {expected}, got {got:?}"))
}

#[pymethods]
impl PyGaussianMixtureArrays {
    #[new]
    fn new(ndim: usize) -> PyResult<Self> {
        if ndim == 0 {
            return Err(value_error("ndim", "must be at least 1"));
        }
        Ok(Self(Mixture::new(ndim)))
    }

    fn __len__(&self) -> usize {
        self.0.len()
    }

    #[getter]
    fn ndim(&self) -> usize {
        self.0.ndim
    }

    #[getter]
    fn next_tag(&self) -> u64 {
        self.0.next_tag
    }

    /// `count` fresh tags; returns the first.
    fn reserve_tags(&mut self, count: u64) -> u64 {
        self.0.reserve_tags(count)
    }

    /// Appends components: `means` (N, D), `covars` (N, D, D), `weights` (N,), `tags`
    /// (0 = birth, others reserved), `times` (integer clock).
    fn extend(
        &mut self,
        means: Bound<'_, PyArray2<f64>>,
        covars: Bound<'_, PyArray3<f64>>,
        weights: Bound<'_, PyArray1<f64>>,
        tags: Vec<u64>,
        times: Vec<i64>,
    ) -> PyResult<()> {
        let (n, d) = (weights.len(), self.0.ndim);
        if means.shape() != [n, d] {
            return Err(wrong_shape("means", format!("({n}, {d})"), means.shape()));
        }
        if covars.shape() != [n, d, d] {
            return Err(wrong_shape("covars", format!("({n}, {d}, {d})"), covars.shape()));
        }
        let (m, c, w) = (
            borrow(&means, "means")?,
            borrow(&covars, "covars")?,
            borrow(&weights, "weights")?,
        );
        self.0
            .extend(
                slice(&m, "means")?,
                slice(&c, "covars")?,
                slice(&w, "weights")?,
                &tags,
                &times,
            )
            .map_err(super::to_py)
    }

    /// Births at the `means` rows (N, D), each with `covar` (D, D), its `weights` entry, tag 0 and
    /// `time`; with `circle` = `(position_mapping, centre, radius)` only those inside it (as
    /// `retain_inside_circle`). What extending a fresh mixture, keeping its components in the
    /// circle and taking them all does, in one call.
    #[pyo3(signature = (means, covar, weights, time, circle = None))]
    #[allow(clippy::type_complexity)]
    fn extend_births(
        &mut self,
        means: Bound<'_, PyArray2<f64>>,
        covar: Bound<'_, PyArray2<f64>>,
        weights: Bound<'_, PyArray1<f64>>,
        time: i64,
        circle: Option<((usize, usize), (f64, f64), f64)>,
    ) -> PyResult<()> {
        let d = self.0.ndim;
        if means.shape()[1] != d {
            return Err(wrong_shape("means", format!("(N, {d})"), means.shape()));
        }
        if covar.shape() != [d, d] {
            return Err(wrong_shape("covar", format!("({d}, {d})"), covar.shape()));
        }
        let (m, c, w) = (
            borrow(&means, "means")?,
            borrow(&covar, "covar")?,
            borrow(&weights, "weights")?,
        );
        let circle = circle.map(|(p, c, r)| ([p.0, p.1], [c.0, c.1], r));
        self.0
            .extend_births(
                slice(&m, "means")?,
                slice(&c, "covar")?,
                slice(&w, "weights")?,
                time,
                circle,
            )
            .map_err(super::to_py)
    }

    /// The distinct component times, ascending.
    fn distinct_times(&self) -> PyResult<Vec<i64>> {
        self.0.distinct_times().map_err(super::to_py)
    }

    /// Kalman prediction to `now`: components stamped `from_times[g]` use
    /// `transitions[g]`, `noises[g]`; all then take the time `now`.
    fn predict(
        &mut self,
        py: Python<'_>,
        from_times: Vec<i64>,
        now: i64,
        transitions: Bound<'_, PyArray3<f64>>,
        noises: Bound<'_, PyArray3<f64>>,
    ) -> PyResult<()> {
        let d = self.0.ndim;
        let g = from_times.len();
        if transitions.shape() != [g, d, d] || noises.shape() != [g, d, d] {
            return Err(wrong_shape(
                "transitions",
                format!("({g}, {d}, {d}) for both transitions and noises"),
                transitions.shape(),
            ));
        }
        let (f, q) = (borrow(&transitions, "transitions")?, borrow(&noises, "noises")?);
        let (f, q) = (slice(&f, "transitions")?, slice(&q, "noises")?);
        let mixture = &mut self.0;
        detached(py, || mixture.predict_from(&from_times, now, f, q))
    }

    /// The GM-PHD update with one scan's `detections` (M, m), `prob_detection` per
    /// component and `clutter` (λ) per detection; returns each detection's posterior
    /// clutter probability (M,).
    #[pyo3(signature = (model, detections, prob_detection, clutter, *, prob_survival, missed_distance, squared, include_all, normalise, skip_undetectable, time, force_symmetric = false))]
    #[allow(clippy::too_many_arguments)]
    fn update<'py>(
        &mut self,
        py: Python<'py>,
        model: &PyMeasurementModel,
        detections: Bound<'_, PyArray2<f64>>,
        prob_detection: Bound<'_, PyArray1<f64>>,
        clutter: Bound<'_, PyArray1<f64>>,
        prob_survival: f64,
        missed_distance: f64,
        squared: bool,
        include_all: bool,
        normalise: bool,
        skip_undetectable: bool,
        time: i64,
        force_symmetric: bool,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let m = model.0.ndim_meas();
        if detections.shape()[1] != m && detections.len() > 0 {
            return Err(wrong_shape("detections", format!("(M, {m})"), detections.shape()));
        }
        let (z, pd, lam) = (
            borrow(&detections, "detections")?,
            borrow(&prob_detection, "prob_detection")?,
            borrow(&clutter, "clutter")?,
        );
        let (z, pd, lam) = (
            slice(&z, "detections")?,
            slice(&pd, "prob_detection")?,
            slice(&lam, "clutter")?,
        );
        let params = UpdateParams {
            prob_survival,
            gate: missed_distance,
            squared,
            include_all,
            normalise,
            skip_undetectable,
            time,
            force_symmetric,
        };
        let mixture = &mut self.0;
        let model = &model.0;
        let clutter_probability = detached(py, || mixture.update(model, z, pd, lam, &params))?;
        Ok(PyArray1::from_vec(py, clutter_probability))
    }

    /// P_D at each component's mean from a context's `DetectionAtPose`, read in place: the
    /// same bits as `at_pose.evaluate(self.means())`, without the copy. None when the core
    /// cannot evaluate them (a position not finite, a mapping beyond the dimension): the
    /// caller's general route then says why.
    fn prob_detection<'py>(
        &self,
        py: Python<'py>,
        at_pose: &Bound<'py, PyDetectionAtPose>,
    ) -> PyResult<Option<Bound<'py, PyArray1<f64>>>> {
        let (n, d, at_pose) = (self.0.len(), self.0.ndim, at_pose.get());
        let mut pd = crate::memory::filled("means", n, 0.0).map_err(super::to_py)?;
        let means = &self.0.means;
        // (a panic is a RuntimeError, as in every call; the core's refusal is None)
        let run = || Ok(at_pose.at_rows(means, d, &mut pd));
        let evaluated = if n < DETACH_ROWS {
            guarded(run)?
        } else {
            detached(py, run)?
        };
        Ok(evaluated.ok().map(|()| PyArray1::from_vec(py, pd)))
    }

    /// Keeps the components whose flag is true.
    fn retain(&mut self, keep: Vec<bool>) -> PyResult<()> {
        self.0.retain(&keep).map_err(super::to_py)
    }

    /// Keeps the components whose `position_mapping` x/y lies in the disc of `radius`
    /// around `centre` (boundary included).
    fn retain_inside_circle(
        &mut self,
        position_mapping: (usize, usize),
        centre: (f64, f64),
        radius: f64,
    ) -> PyResult<()> {
        self.0
            .retain_inside_circle([position_mapping.0, position_mapping.1], [centre.0, centre.1], radius)
            .map_err(super::to_py)
    }

    /// Moves the components of `other` whose flag in `take` is true to the end of this
    /// mixture, in order; the others stay in `other`.
    fn take_from(&mut self, other: &Bound<'_, Self>, take: Vec<bool>) -> PyResult<()> {
        let mut other = other
            .try_borrow_mut()
            .map_err(|_| value_error("other", "must be another mixture than this one"))?;
        self.0.take_from(&mut other.0, &take).map_err(super::to_py)
    }

    /// Keeps the components with `√(tr P_xy / 2) ≤ max_std`.
    fn retain_position_std(&mut self, position_mapping: (usize, usize), max_std: f64) -> PyResult<()> {
        if !(max_std.is_finite() && max_std > 0.0) {
            return Err(value_error(
                "max_position_std",
                format_args!("must be finite and > 0, got {max_std}"),
            ));
        }
        self.0
            .retain_position_std([position_mapping.0, position_mapping.1], max_std)
            .map_err(super::to_py)
    }

    /// Prune, merge (and make tags unique), truncate, as `GaussianMixtureReducer`.
    #[pyo3(signature = (*, pruning, prune_threshold, merging, merge_threshold, truncating, max_components, kdtree_max_distance = None))]
    #[allow(clippy::too_many_arguments)]
    fn reduce(
        &mut self,
        py: Python<'_>,
        pruning: bool,
        prune_threshold: f64,
        merging: bool,
        merge_threshold: f64,
        truncating: bool,
        max_components: u64,
        kdtree_max_distance: Option<f64>,
    ) -> PyResult<()> {
        let params = ReduceParams {
            pruning,
            prune_threshold,
            merging,
            merge_threshold,
            truncating,
            max_components: usize::try_from(max_components).unwrap_or(usize::MAX),
            max_distance: kdtree_max_distance,
        };
        let mixture = &mut self.0;
        detached(py, || mixture.reduce(&params))
    }

    /// The components that extend or start tracks (see `Mixture::track_rows`) as `(tags,
    /// weights, means (k, D, 1), covars (k, D, D))`, and the `tracked` tags that left.
    #[allow(clippy::type_complexity)]
    fn track_states<'py>(
        &self,
        py: Python<'py>,
        tracked: Vec<u64>,
        threshold: f64,
    ) -> PyResult<(
        Vec<u64>,
        Vec<f64>,
        Bound<'py, PyArray3<f64>>,
        Bound<'py, PyArray3<f64>>,
        Vec<u64>,
    )> {
        let mixture = &self.0;
        let d = mixture.ndim;
        let (rows, gone) = mixture.track_rows(&tracked, threshold).map_err(super::to_py)?;
        // (the mixture holds these rows already: sizes cannot overflow)
        let room = |n: usize| crate::memory::with_room::<f64>("means", n).map_err(super::to_py);
        let (mut means, mut covars) = (room(rows.len() * d)?, room(rows.len() * d * d)?);
        for &i in &rows {
            means.extend_from_slice(mixture.mean(i));
            covars.extend_from_slice(mixture.covar(i));
        }
        let k = rows.len();
        let tags = crate::memory::collected("means", rows.iter().map(|&i| mixture.tags[i])).map_err(super::to_py)?;
        let weights =
            crate::memory::collected("means", rows.iter().map(|&i| mixture.weights[i])).map_err(super::to_py)?;
        Ok((
            tags,
            weights,
            PyArray1::from_vec(py, means).reshape([k, d, 1])?,
            PyArray1::from_vec(py, covars).reshape([k, d, d])?,
            gone,
        ))
    }

    fn means<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let (n, d) = (self.0.len(), self.0.ndim);
        super::array_of(py, "means", &self.0.means)?.reshape([n, d])
    }

    fn covars<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray3<f64>>> {
        let (n, d) = (self.0.len(), self.0.ndim);
        super::array_of(py, "covars", &self.0.covars)?.reshape([n, d, d])
    }

    fn weights<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        super::array_of(py, "weights", &self.0.weights)
    }

    fn tags<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<u64>>> {
        super::array_of(py, "tags", &self.0.tags)
    }

    fn times<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<i64>>> {
        super::array_of(py, "times", &self.0.times)
    }

    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyTuple>> {
        let py = slf.py();
        let this = slf.borrow();
        // (tags and times as lists for pickling: Python's own objects, MemoryError on failure)
        let state = (
            this.means(py)?,
            this.covars(py)?,
            this.weights(py)?,
            this.tags(py)?.to_vec()?,
            this.times(py)?.to_vec()?,
            this.0.next_tag,
        );
        (slf.get_type(), (this.0.ndim,), state).into_pyobject(py)
    }

    fn __setstate__(&mut self, state: PickledMixture<'_>) -> PyResult<()> {
        let (means, covars, weights, tags, times, next_tag) = state;
        let mut mixture = Mixture::new(self.0.ndim);
        mixture.next_tag = next_tag;
        std::mem::swap(&mut self.0, &mut mixture);
        let result = self.extend(means, covars, weights, tags, times);
        if result.is_err() {
            std::mem::swap(&mut self.0, &mut mixture);
        }
        result
    }
}

/// What a mixture pickles as: means, covariances, weights, tags, times and the next tag.
type PickledMixture<'py> = (
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray3<f64>>,
    Bound<'py, PyArray1<f64>>,
    Vec<u64>,
    Vec<i64>,
    u64,
);

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyGaussianMixtureArrays>()?;
    Ok(())
}
