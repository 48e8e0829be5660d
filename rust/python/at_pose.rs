//! The detection and clutter models fixed at one sensor pose (and position mapping): what
//! a detector context evaluates, prepared once per scan (pose frame, factor steps), so that
//! each call converts nothing but its arrays. The thin entry points of `DetectorContext`:
//! they take the common case only (C-contiguous, aligned float64 arrays; one finite state
//! vector) and return None for anything else, which the Python layer then converts and
//! checks, raising its errors that name the argument.

use super::models::{PyClutterModel, PyDetectionModel};
use super::{
    borrow, detached, guarded, mapping_of, output, pose_of, rule_of, slice, value_error, MappingTuple, PoseTuple,
};
use crate::batch::PositionMapping;
use crate::cubature::Rule;
use crate::detection::ScanDetection;
use crate::pose::Pose;
use numpy::{PyArray1, PyArray2, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::prelude::*;

/// Rows below which a call keeps the GIL: releasing and retaking it costs more than
/// evaluating them (the core splits work over threads only far above this).
pub(super) const DETACH_ROWS: usize = 4096;

#[pyclass(name = "DetectionAtPose", module = "ctxmodels._core", frozen)]
pub struct PyDetectionAtPose {
    scan: ScanDetection,
    mapping: PositionMapping,
    /// The context's integration rule for the expected P_D of a Gaussian.
    rule: Rule,
}

#[pymethods]
impl PyDetectionAtPose {
    #[new]
    #[pyo3(signature = (model, pose, position_mapping = MappingTuple::Flat((0, 2)), rule = "mean", order = 3))]
    fn new(
        model: &Bound<'_, PyDetectionModel>,
        pose: PoseTuple,
        position_mapping: MappingTuple,
        rule: &str,
        order: i64,
    ) -> PyResult<Self> {
        let pose = pose_of(pose)?;
        let mapping = mapping_of(position_mapping)?;
        let rule = rule_of(rule, order)?;
        Ok(PyDetectionAtPose {
            scan: model.get().0.at_pose(&pose),
            mapping,
            rule,
        })
    }

    /// P_D at each row of `states` (N, D), into `out` if given; None (nothing evaluated)
    /// unless `states` is a C-contiguous, aligned float64 2-D array.
    /// An `out` that is not a float64 (N,) C-contiguous, aligned array also returns None
    /// (the Python layer's check names what is wrong with it).
    #[pyo3(signature = (states, out = None))]
    fn evaluate<'py>(
        &self,
        py: Python<'py>,
        states: &Bound<'py, PyAny>,
        out: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Option<Bound<'py, PyArray1<f64>>>> {
        let Ok(states) = states.cast::<PyArray2<f64>>() else {
            return Ok(None);
        };
        if !(states.is_c_contiguous() && states.is_aligned()) {
            return Ok(None);
        }
        let (n, ncols) = (states.shape()[0], states.shape()[1]);
        let Some(out) = common_out(out, n) else { return Ok(None) };
        let states = borrow(states, "states")?;
        let data = slice(&states, "states")?;
        let mut out = output(py, out, n, &[("states", data)])?;
        let result = Bound::clone(&out);
        let buffer = out
            .as_slice_mut()
            .map_err(|_| value_error("out", "must be C-contiguous"))?;
        let (scan, mapping) = (&self.scan, self.mapping);
        if n < DETACH_ROWS {
            guarded(|| scan.at_states(data, ncols, mapping, buffer))?;
        } else {
            detached(py, || scan.at_states(data, ncols, mapping, buffer))?;
        }
        Ok(Some(result))
    }

    /// P_D at one state vector, a float64 (D, 1) column or (D,) array whose position is
    /// finite: the same bits as a row of [`Self::evaluate`]. None for anything else.
    fn at(&self, vector: &Bound<'_, PyAny>) -> Option<f64> {
        let (row, width) = self.read(vector)?;
        let mut pd = [0.0];
        self.scan.at_states(&row[..width], width, self.packed(), &mut pd).ok()?;
        Some(pd[0])
    }

    /// Expected P_D under the rule over one Gaussian: `vector` a float64 (D, 1) column or
    /// (D,) array, the mean of `state`, whose `covar` is read only then (a particle state
    /// computes it) and must be a float64 (D, D) array; the same bits as a row of the
    /// model's `expected`. None for anything else, or a position or covariance block the
    /// general path refuses (it then names the fault).
    fn expected_at(&self, vector: &Bound<'_, PyAny>, state: &Bound<'_, PyAny>) -> Option<f64> {
        let (row, width) = self.read(vector)?;
        let covar = state.getattr(pyo3::intern!(state.py(), "covar")).ok()?;
        let covar = covar.cast::<PyArray2<f64>>().ok()?;
        let d = covar.shape()[0];
        if covar.shape()[1] != d || vector.len().ok()? != d {
            return None;
        }
        // The packed row's covariance: the blocks of the positions and of the velocity a
        // notch reads (integrated given the position); the rest never is read.
        let (axes, _) = self.axes();
        let mut block = [0.0; 36];
        for a in 0..width {
            for b in 0..width {
                block[a * width + b] = covar.get_owned([axes[a], axes[b]])?;
            }
        }
        let mut pd = [0.0];
        self.scan
            .expected_at_gaussians(
                &row[..width],
                &block[..width * width],
                width,
                self.packed(),
                &self.rule,
                &mut pd,
            )
            .ok()?;
        Some(pd[0])
    }
}

impl PyDetectionAtPose {
    /// P_D at each of the `rows` (N×`ncols`, N = `out.len()`): [`Self::evaluate`]'s
    /// computation on memory the core already holds (a mixture's means).
    pub(super) fn at_rows(&self, rows: &[f64], ncols: usize, out: &mut [f64]) -> crate::Result<()> {
        self.scan.at_states(rows, ncols, self.mapping, out)
    }

    /// The state indices the mapping reads, in order: x, y, the height's if mapped, then
    /// the velocity's if mapped (at most six).
    fn axes(&self) -> ([usize; 6], usize) {
        let PositionMapping { x, y, z, velocity } = self.mapping;
        let v = velocity.map(|v| [Some(v.vx), Some(v.vy), v.vz]).unwrap_or_default();
        let (mut axes, mut n) = ([0; 6], 0);
        for i in [Some(x), Some(y), z].into_iter().chain(v).flatten() {
            axes[n] = i;
            n += 1;
        }
        (axes, n)
    }

    /// The mapping of a row packing [`Self::axes`] in that order.
    fn packed(&self) -> PositionMapping {
        let positions = if self.mapping.z.is_some() {
            PositionMapping::raised(0, 1, 2)
        } else {
            PositionMapping::new(0, 1)
        }
        .unwrap_or_default();
        let Some(v) = self.mapping.velocity else {
            return positions;
        };
        let first = 2 + usize::from(self.mapping.z.is_some());
        let velocity = crate::batch::VelocityMapping {
            vx: first,
            vy: first + 1,
            vz: v.vz.map(|_| first + 2),
        };
        positions.with_velocity(velocity).unwrap_or(positions)
    }

    /// The values at [`Self::axes`] of a float64 (D, 1) column or (D,) array, and how
    /// many there are; None for anything else.
    fn read(&self, vector: &Bound<'_, PyAny>) -> Option<([f64; 6], usize)> {
        let (axes, n) = self.axes();
        let axes = &axes[..n];
        let mut row = [0.0; 6];
        if let Ok(column) = vector.cast::<PyArray2<f64>>() {
            if column.shape()[1] != 1 {
                return None;
            }
            for (p, &i) in row.iter_mut().zip(axes) {
                *p = column.get_owned([i, 0])?;
            }
        } else if let Ok(flat) = vector.cast::<PyArray1<f64>>() {
            for (p, &i) in row.iter_mut().zip(axes) {
                *p = flat.get_owned([i])?;
            }
        } else {
            return None;
        }
        Some((row, n))
    }
}

#[pyclass(name = "ClutterAtPose", module = "ctxmodels._core", frozen)]
pub struct PyClutterAtPose {
    model: Py<PyClutterModel>,
    pose: Pose,
}

#[pymethods]
impl PyClutterAtPose {
    #[new]
    fn new(model: Py<PyClutterModel>, pose: PoseTuple) -> PyResult<Self> {
        Ok(PyClutterAtPose {
            model,
            pose: pose_of(pose)?,
        })
    }

    /// λ at world `positions` (M, 2) — or (M, 3) with heights — with `metadata` (M, K) in the model's column order
    /// (None when the model reads no metadata), into `out` if given. None (nothing
    /// evaluated) unless every array is a C-contiguous, aligned float64 array of its shape.
    #[pyo3(signature = (positions, metadata = None, out = None))]
    fn evaluate<'py>(
        &self,
        py: Python<'py>,
        positions: &Bound<'py, PyAny>,
        metadata: Option<&Bound<'py, PyAny>>,
        out: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Option<Bound<'py, PyArray1<f64>>>> {
        let model = &self.model.get().0;
        let k = model.metadata_columns();
        let Some((positions, ncols)) = common_rows(positions, 2)
            .map(|p| (p, 2))
            .or_else(|| common_rows(positions, 3).map(|p| (p, 3)))
        else {
            return Ok(None);
        };
        let n = positions.shape()[0];
        let metadata = match metadata {
            None if k == 0 => None,
            None => return Ok(None),
            Some(m) => match common_rows(m, k) {
                Some(m) if m.shape()[0] == n => Some(m),
                _ => return Ok(None),
            },
        };
        let Some(out) = common_out(out, n) else { return Ok(None) };
        let positions = borrow(&positions, "positions")?;
        let p = slice(&positions, "positions")?;
        let metadata = metadata.map(|m| borrow(&m, "metadata")).transpose()?;
        let m = metadata
            .as_ref()
            .map(|m| slice(m, "metadata"))
            .transpose()?
            .unwrap_or(&[]);
        let mut out = output(py, out, n, &[("positions", p), ("metadata", m)])?;
        let result = Bound::clone(&out);
        let buffer = out
            .as_slice_mut()
            .map_err(|_| value_error("out", "must be C-contiguous"))?;
        let pose = &self.pose;
        if n < DETACH_ROWS {
            guarded(|| model.evaluate_rows(pose, p, ncols, m, None, buffer))?;
        } else {
            detached(py, || model.evaluate_rows(pose, p, ncols, m, None, buffer))?;
        }
        Ok(Some(result))
    }
}

/// `array` as a C-contiguous, aligned float64 (M, `ncols`) array; None otherwise.
fn common_rows<'py>(array: &Bound<'py, PyAny>, ncols: usize) -> Option<Bound<'py, PyArray2<f64>>> {
    let rows = array.cast::<PyArray2<f64>>().ok()?;
    (rows.is_c_contiguous() && rows.is_aligned() && rows.shape()[1] == ncols).then(|| rows.clone())
}

/// `Some(None)` for no `out`, `Some(out)` for a float64 (n,) C-contiguous aligned array,
/// None for anything else (the Python layer's check names the fault).
fn common_out<'py>(out: Option<&Bound<'py, PyAny>>, n: usize) -> Option<Option<Bound<'py, PyArray1<f64>>>> {
    match out {
        None => Some(None),
        Some(out) => {
            let out = out.cast::<PyArray1<f64>>().ok()?;
            (out.len() == n && out.is_c_contiguous() && out.is_aligned()).then(|| Some(out.clone()))
        }
    }
}
