//! One scan of the M-of-N initiator's holding tracks (what Stone Soup's
//! `MultiMeasurementInitiator` with a GNN 2-D assignment over a Mahalanobis distance
//! hypothesiser and a Kalman updater computes for a scan), over arrays:
//!
//! 1. **Prediction** of each holding row `(x, P)`: `x̂ = F x`, `P̂ = F P Fᵀ + Q` with its
//!    interval's transition.
//! 2. **Gate**: for each row and each detection `z_j` (measured by model `g_j`):
//!    `ẑ = h(x̂)`, `H` (the model matrix or Jacobian, see [`MeasurementModel::linearise`]),
//!    `C = P̂ Hᵀ`, `S = H C + R`, `δ = −(z_j − ẑ)` (a bearing wrapped to `[−π, π)`) and
//!    `d² = δᵀ S⁻¹ δ`; the distance is `d = √d²` (or `d²` for the squared measure); the pair
//!    is a hypothesis when `d < missed_distance` (or always, with `include_all`).
//! 3. **Assignment**: the rows with at least one hypothesis, in row order, against the
//!    detections and one "missed" column per such row (cost `missed_distance`), all other
//!    pairs forbidden; minimum total distance by [`super::assignment::assign`]. Rows without
//!    a hypothesis are missed.
//! 4. **Kalman update** of each assigned row: `K = C S⁻¹`, `x = x̂ + K (z − ẑ)` (bearing
//!    wrapped), `P = P̂ − (K S) Kᵀ` (then `(P + Pᵀ)/2` with `force_symmetric`).
//! 5. **M-of-N counts**: `points` grows by one per update (per state, unless `updates_only`);
//!    `since` (distinct times since the last detection) becomes 1 on an update and grows by
//!    one at a new time otherwise; a row is *released* when `points ≥ min_points` (whether
//!    an unreleased row is deleted is its deleter's verdict, decided by the caller).
//!
//! All loops run in index order on one thread: the same inputs give the same bits.

use super::assignment::assign;
use super::{check_detections, check_states, predict, push_row_major};
use crate::error::{ModelError, Result};
#[cfg(test)]
use crate::kalman::Jacobian;
use crate::kalman::{mod_bearing, MeasurementModel};
use crate::memory;
use nalgebra::{DMatrix, DVector};

/// One scan's inputs (row-major slices); `H = points.len()` rows, `M = model_index.len()`
/// detections.
#[derive(Debug, Clone, Copy)]
pub struct InitiatorInput<'a> {
    /// State dimension D.
    pub dim: usize,
    /// The rows' last states: means H×D, covariances H×D×D.
    pub means: &'a [f64],
    pub covars: &'a [f64],
    /// Per row, its transition among `matrices` / `noises` (K×D×D each).
    pub transition_index: &'a [usize],
    pub matrices: &'a [f64],
    pub noises: &'a [f64],
    /// Detections, M×m (every model has m measured values).
    pub detections: &'a [f64],
    /// Per detection, its model among the call's models.
    pub model_index: &'a [usize],
    pub missed_distance: f64,
    /// The squared Mahalanobis measure (else the Mahalanobis distance).
    pub squared: bool,
    pub include_all: bool,
    pub force_symmetric: bool,
    /// Per row: states counted towards release, distinct times since the last detection.
    pub points: &'a [i64],
    pub since: &'a [i64],
    /// Per row: whether the scan's time is one the row has no state at yet.
    pub new_time: &'a [bool],
    pub updates_only: bool,
    pub min_points: i64,
}

/// One scan's results, row-major; `U` rows were updated (in row order).
#[derive(Debug, Clone, Default)]
pub struct InitiatorOutput {
    /// Predictions, H×D and H×D×D.
    pub pred_means: Vec<f64>,
    pub pred_covars: Vec<f64>,
    /// Each row's new last state (its update, else its prediction), H×D and H×D×D.
    pub means: Vec<f64>,
    pub covars: Vec<f64>,
    /// Per row, the assigned detection, or −1 (missed).
    pub assigned: Vec<i64>,
    /// Per updated row: the distance, ẑ (U×m), S (U×m×m), C (U×D×m).
    pub distances: Vec<f64>,
    pub meas_means: Vec<f64>,
    pub meas_covars: Vec<f64>,
    pub cross_covars: Vec<f64>,
    /// Per row: the new counts and verdicts.
    pub points: Vec<i64>,
    pub since: Vec<i64>,
    pub released: Vec<bool>,
}

/// A row's measurement prediction under one model.
struct Predicted {
    z_hat: DVector<f64>,
    s: DMatrix<f64>,
    s_inv: DMatrix<f64>,
    cross: DMatrix<f64>,
}

fn check(models: &[MeasurementModel], input: &InitiatorInput) -> Result<usize> {
    let rows = input.points.len();
    check_states(input.dim, rows, input.means, input.covars)?;
    if input.since.len() != rows || input.new_time.len() != rows || input.transition_index.len() != rows {
        return Err(ModelError::shape(
            "since",
            format!("since, new_time and transition_index must have {rows} entries (one per row)"),
        ));
    }
    let m = check_detections(models, input.dim, input.detections, input.model_index)?;
    if input.missed_distance.is_nan() {
        return Err(ModelError::invalid("missed_distance", "must not be NaN"));
    }
    if input.min_points < 0 {
        return Err(ModelError::invalid(
            "min_points",
            format!("must be >= 0, got {}", input.min_points),
        ));
    }
    Ok(m)
}

/// Runs one scan of the holding rows (see the module documentation).
pub fn initiator_scan(models: &[MeasurementModel], input: &InitiatorInput) -> Result<InitiatorOutput> {
    let m = check(models, input)?;
    let (dim, rows, dets) = (input.dim, input.points.len(), input.model_index.len());
    let dd = dim * dim;
    let (pred_means, pred_covars) = predict(
        dim,
        input.means,
        input.covars,
        input.transition_index,
        input.matrices,
        input.noises,
    )?;
    let z: Vec<DVector<f64>> = memory::collected(
        "detections",
        input
            .detections
            .chunks_exact(m.max(1))
            .take(dets)
            .map(DVector::from_row_slice),
    )?;
    let used: Vec<bool> = (0..models.len()).map(|g| input.model_index.contains(&g)).collect();

    // 2. gate: each row's hypotheses (detection, distance) and its measurement predictions
    let mut hypotheses: Vec<Vec<(usize, f64)>> = memory::collected("means", (0..rows).map(|_| Vec::new()))?;
    let mut predicted: Vec<Vec<Option<Predicted>>> = memory::with_room("means", rows)?;
    let mut delta = memory::filled("detections", m, 0.0)?;
    let noises: Vec<DMatrix<f64>> = models.iter().map(MeasurementModel::noise_matrix).collect();
    for (row, found) in hypotheses.iter_mut().enumerate() {
        let x = DVector::from_row_slice(&pred_means[row * dim..(row + 1) * dim]);
        let p = DMatrix::from_row_slice(dim, dim, &pred_covars[row * dd..(row + 1) * dd]);
        let mut per_model = Vec::with_capacity(models.len());
        for (g, model) in models.iter().enumerate() {
            if !used[g] {
                per_model.push(None);
                continue;
            }
            let (z_hat, h) = model.linearised(&x);
            let cross = &p * h.transpose();
            let s = &h * &cross + &noises[g];
            let s_inv = s.clone().try_inverse().ok_or_else(|| {
                ModelError::invalid(
                    "covars",
                    format!("row {row}: the innovation covariance H P Hᵀ + R is singular"),
                )
            })?;
            per_model.push(Some(Predicted { z_hat, s, s_inv, cross }));
        }
        for (j, zj) in z.iter().enumerate() {
            let g = input.model_index[j];
            let Some(pm) = &per_model[g] else { continue };
            innovation(&models[g], zj, &pm.z_hat, &mut delta);
            let d2 = quadratic(&pm.s_inv, &delta);
            let distance = if input.squared { d2 } else { d2.sqrt() };
            if input.include_all || distance < input.missed_distance {
                found.push((j, distance));
            }
        }
        predicted.push(per_model);
    }

    // 3. assignment of the rows with a hypothesis
    let detected: Vec<usize> = (0..rows).filter(|&r| !hypotheses[r].is_empty()).collect();
    let mut assigned = memory::filled("means", rows, -1i64)?;
    let mut chosen_distance = memory::filled("means", rows, 0.0)?;
    if !detected.is_empty() {
        let n = detected.len();
        let cols = dets + n;
        let size = n
            .checked_mul(cols)
            .ok_or_else(|| ModelError::memory("detections", (n as u128) * (cols as u128) * 8))?;
        let mut cost = memory::filled("detections", size, f64::INFINITY)?;
        for (i, &row) in detected.iter().enumerate() {
            cost[i * cols + dets + i] = input.missed_distance;
            for &(j, d) in &hypotheses[row] {
                cost[i * cols + j] = d;
            }
        }
        let col4row = assign(&cost, n, cols)
            .map_err(|e| ModelError::infeasible("missed_distance", format!("the assignment is not feasible ({e})")))?;
        for (i, &row) in detected.iter().enumerate() {
            let j = col4row[i];
            if j < dets {
                assigned[row] = j as i64;
                chosen_distance[row] = cost[i * cols + j];
            }
        }
    }

    // 4. updates, 5. counts
    let mut out = InitiatorOutput {
        means: memory::with_room("means", rows * dim)?,
        covars: memory::with_room("covars", rows * dd)?,
        points: memory::with_room("points", rows)?,
        since: memory::with_room("since", rows)?,
        released: memory::with_room("points", rows)?,
        ..Default::default()
    };
    for row in 0..rows {
        let updated = assigned[row] >= 0;
        if updated {
            let j = assigned[row] as usize;
            let g = input.model_index[j];
            let pm = predicted[row][g]
                .as_ref()
                .ok_or_else(|| ModelError::invalid("model_index", "an assigned detection's model was not predicted"))?;
            let x = DVector::from_row_slice(&pred_means[row * dim..(row + 1) * dim]);
            let p = DMatrix::from_row_slice(dim, dim, &pred_covars[row * dd..(row + 1) * dd]);
            let gain = &pm.cross * &pm.s_inv;
            let mut nu = &z[j] - &pm.z_hat;
            if let Some(a) = models[g].angle_row() {
                nu[a] = mod_bearing(nu[a]);
            }
            let mean = &x + &gain * nu;
            let mut covar = &p - (&gain * &pm.s) * gain.transpose();
            if input.force_symmetric {
                covar = (&covar + covar.transpose()) / 2.0;
            }
            out.means.extend(mean.iter());
            push_row_major(&mut out.covars, &covar);
            out.distances.push(chosen_distance[row]);
            out.meas_means.extend(pm.z_hat.iter());
            push_row_major(&mut out.meas_covars, &pm.s);
            push_row_major(&mut out.cross_covars, &pm.cross);
        } else {
            out.means.extend_from_slice(&pred_means[row * dim..(row + 1) * dim]);
            out.covars.extend_from_slice(&pred_covars[row * dd..(row + 1) * dd]);
        }
        let points = input.points[row] + i64::from(updated || !input.updates_only);
        let since = if updated {
            1
        } else {
            input.since[row] + i64::from(input.new_time[row])
        };
        let released = points >= input.min_points;
        out.points.push(points);
        out.since.push(since);
        out.released.push(released);
    }
    out.pred_means = pred_means;
    out.pred_covars = pred_covars;
    out.assigned = assigned;
    Ok(out)
}

/// `−(z − ẑ)` into `delta`, the bearing element wrapped after the difference and after the
/// negation (as Stone Soup's `Bearing` arithmetic wraps it).
fn innovation(model: &MeasurementModel, z: &DVector<f64>, z_hat: &DVector<f64>, delta: &mut [f64]) {
    let angle = model.angle_row();
    for (i, d) in delta.iter_mut().enumerate() {
        let diff = z[i] - z_hat[i];
        *d = if angle == Some(i) {
            mod_bearing(-mod_bearing(diff))
        } else {
            -diff
        };
    }
}

/// `δᵀ A δ`, summed row by row.
fn quadratic(a: &DMatrix<f64>, delta: &[f64]) -> f64 {
    let mut total = 0.0;
    for (i, di) in delta.iter().enumerate() {
        let mut row = 0.0;
        for (j, dj) in delta.iter().enumerate() {
            row += a[(i, j)] * dj;
        }
        total += di * row;
    }
    total
}

#[cfg(test)]
mod tests;
