//! One JPDA scan over arrays: what Stone Soup's `PDAHypothesiser` + `JPDAwithEHM2` +
//! `MultiTargetMixtureTracker` compute for a scan, without a Python object per hypothesis.
//!
//! For `T` predicted tracks `(x̂_t, P̂_t)` and `M` detections `z_j` measured by one model:
//!
//! 1. **Measurement prediction** per track: `ẑ_t = h(x̂_t)`, `H_t` (the model matrix or its
//!    Jacobian, see [`crate::kalman::measurement`]), `C_t = P̂_t H_tᵀ`, `S_t = H_t C_t + R`.
//! 2. **Single-hypothesis weights** as `PDAHypothesiser` computes them: missed detection
//!    `1 − P_D,t·P_G`; detection `j`, if its squared Mahalanobis distance is within the χ²
//!    gate (or `include_all`), `P_D,t·N(z_j; ẑ_t, S_t)/λ_j`. Bearing rows of `z_j − ẑ_t`
//!    are wrapped to `[−π, π)` as Stone Soup's `Bearing` arithmetic wraps them. Each track's
//!    weights are kept relative to its largest (log space, then one `exp`), which changes no
//!    marginal: every joint event holds exactly one hypothesis per track.
//! 3. **Joint association marginals** (exact, as `JPDAwithEHM2`'s): tracks are split into
//!    clusters sharing no gated detection; each cluster is solved by efficient hypothesis
//!    management (EHM2: a tree of tracks, one node per set of already-used detections that
//!    still matter below it; backward weights up, forward weights down). Levels are
//!    rescaled by powers of two, which is exact, so no product of weights under- or
//!    overflows. A cluster whose tree would exceed [`MAX_TREE_NODES`] nodes or
//!    [`MAX_TREE_EDGES`] links (≈ 1 GB) is an error naming its tracks and detections, and
//!    sizes taken from the inputs are allocated fallibly: an intractable scan is a Python
//!    `ValueError`, never an abort. [`brute_force_marginals`] enumerates the joint events
//!    instead (tests).
//! 4. **Posterior** per track: the Kalman update of each gated detection
//!    (`K = C S⁻¹`, `x_j = x̂ + K ν_j`, `P = P̂ − K S Kᵀ`) and the missed prediction, reduced to
//!    one Gaussian with the marginals as weights (Stone Soup's `gm_reduce_single`). A track's
//!    posterior is an *update* when some detection's marginal exceeds the missed
//!    detection's, and such a detection counts as *taken* (not handed to the initiator).
//!
//! All loops run in index order on one thread: the same inputs give the same bits.
//!
//! Beside the scan's steps 1, 2 and 4 and its input and output types, this file holds what
//! its submodules share (the prediction, the input checks, fallible allocation), hence its
//! length; the parts with an algorithm of their own (marginals, assignment, the initiator's
//! scan and its births) are the submodules.

mod assignment;
mod births;
mod initiation;
mod marginals;
#[cfg(test)]
mod tests;

pub use assignment::assign;
pub use births::{initiator_births, BirthPrior};
pub use initiation::{initiator_scan, InitiatorInput, InitiatorOutput};
pub use marginals::{brute_force_marginals, joint_marginals, MAX_TREE_EDGES, MAX_TREE_NODES};

use crate::error::{ModelError, Result};
use crate::kalman::{self, mod_bearing, MeasurementModel};
use crate::memory;
use nalgebra::{DMatrix, DVector};

const LOG_TWO_PI: f64 = 1.837_877_066_409_345_5; // ln(2π)

fn check_finite(argument: &'static str, values: &[f64]) -> Result<()> {
    if let Some(i) = values.iter().position(|v| !v.is_finite()) {
        return Err(ModelError::invalid(
            argument,
            format!("element {i} is not finite ({})", values[i]),
        ));
    }
    Ok(())
}

/// `len` copies of `value` (`None`: a size that overflowed), or None when the allocation
/// fails: sizes that come from the inputs (tracks × detections, a cluster's tree) are
/// allocated fallibly, so that an input too large for memory is an error, not an abort.
fn try_filled<T: Clone>(len: Option<usize>, value: T) -> Option<Vec<T>> {
    memory::filled("detections", len?, value).ok()
}

/// The error of a scan whose `tracks × detections` arrays cannot be allocated (a
/// MemoryError in Python, naming `detections`).
fn too_large(tracks: usize, dets: usize) -> ModelError {
    ModelError::memory("detections", tracks as u128 * (dets as u128 + 1) * 8)
}

/// Kalman prediction `x' = F x`, `P' = F P Fᵀ + Q` of `T` states (`means` T×D, `covars`
/// T×D×D, row-major), state `t` with the transition `index[t]` of `matrices`/`noises`
/// (K×D×D each).
pub fn predict(
    dim: usize,
    means: &[f64],
    covars: &[f64],
    index: &[usize],
    matrices: &[f64],
    noises: &[f64],
) -> Result<(Vec<f64>, Vec<f64>)> {
    let tracks = index.len();
    check_states(dim, tracks, means, covars)?;
    let dd = dim * dim;
    if !matrices.len().is_multiple_of(dd.max(1)) || matrices.len() != noises.len() {
        return Err(ModelError::shape(
            "transition_matrices",
            format!("must be (K, {dim}, {dim}) like transition_covars"),
        ));
    }
    let kinds = matrices.len() / dd.max(1);
    if let Some(t) = index.iter().position(|&k| k >= kinds) {
        return Err(ModelError::invalid(
            "transition_index",
            format!("row {t}: index {} is out of range for {kinds} transitions", index[t]),
        ));
    }
    check_finite("transition_matrices", matrices)?;
    check_finite("transition_covars", noises)?;
    let mut out_means = memory::copied("means", means)?;
    let mut out_covars = memory::copied("covars", covars)?;
    let mut scratch = memory::filled("means", 2 * dd + dim, 0.0)?;
    for (t, &k) in index.iter().enumerate() {
        kalman::predict_state(
            &matrices[k * dd..(k + 1) * dd],
            &noises[k * dd..(k + 1) * dd],
            &mut out_means[t * dim..(t + 1) * dim],
            &mut out_covars[t * dd..(t + 1) * dd],
            &mut scratch,
        );
    }
    Ok((out_means, out_covars))
}

/// Checks a call's `models` against states of `dim` values and its `detections` (M×m,
/// detection `j` measured by `models[model_index[j]]`); returns m.
fn check_detections(
    models: &[MeasurementModel],
    dim: usize,
    detections: &[f64],
    model_index: &[usize],
) -> Result<usize> {
    let m = models.first().map_or(0, MeasurementModel::ndim_meas);
    for model in models {
        if model.ndim_meas() != m {
            return Err(ModelError::shape(
                "models",
                "every model must measure the same number of values",
            ));
        }
        model.check_dim(dim)?;
    }
    let dets = model_index.len();
    if dets > 0 && models.is_empty() {
        return Err(ModelError::shape("models", "detections need at least one model"));
    }
    if let Some(j) = model_index.iter().position(|&g| g >= models.len()) {
        return Err(ModelError::invalid(
            "model_index",
            format!(
                "detection {j}: index {} is out of range for {} models",
                model_index[j],
                models.len()
            ),
        ));
    }
    if detections.len() != dets * m {
        return Err(ModelError::shape(
            "detections",
            format!("must be ({dets}, {m}), got {} values", detections.len()),
        ));
    }
    check_finite("detections", detections).map(|()| m)
}

fn push_row_major(out: &mut Vec<f64>, m: &DMatrix<f64>) {
    for i in 0..m.nrows() {
        for j in 0..m.ncols() {
            out.push(m[(i, j)]);
        }
    }
}

fn check_states(dim: usize, tracks: usize, means: &[f64], covars: &[f64]) -> Result<()> {
    if dim == 0 {
        return Err(ModelError::shape("means", "states must have at least one dimension"));
    }
    if means.len() != tracks * dim {
        return Err(ModelError::shape(
            "means",
            format!("must be ({tracks}, {dim}), got {} values", means.len()),
        ));
    }
    if covars.len() != tracks * dim * dim {
        return Err(ModelError::shape(
            "covars",
            format!("must be ({tracks}, {dim}, {dim}), got {} values", covars.len()),
        ));
    }
    if let Some(row) = means.chunks_exact(dim).position(|r| r.iter().any(|v| !v.is_finite())) {
        return Err(ModelError::non_finite(
            "means",
            row,
            "a state mean holds NaN or infinity",
        ));
    }
    if let Some(row) = covars
        .chunks_exact(dim * dim)
        .position(|r| r.iter().any(|v| !v.is_finite()))
    {
        return Err(ModelError::non_finite(
            "covars",
            row,
            "a covariance holds NaN or infinity",
        ));
    }
    Ok(())
}

/// One scan's inputs (row-major slices). `T` is `prob_detect.len()`, `M` is `clutter.len()`.
#[derive(Debug, Clone, Copy)]
pub struct ScanInput<'a> {
    /// State dimension D.
    pub dim: usize,
    /// Predicted means, T×D.
    pub means: &'a [f64],
    /// Predicted covariances, T×D×D.
    pub covars: &'a [f64],
    /// Measurement vectors, M×m.
    pub detections: &'a [f64],
    /// P_D per track, T.
    pub prob_detect: &'a [f64],
    /// Clutter spatial density λ per detection, M.
    pub clutter: &'a [f64],
    /// P_G: probability that the gate holds a detected target's measurement.
    pub prob_gate: f64,
    /// The gate on the squared Mahalanobis distance (χ² quantile of P_G with m dof).
    pub gate_threshold: f64,
    /// Keep every detection's hypothesis, gated or not.
    pub include_all: bool,
    /// The Kalman updater's `force_symmetric_covariance`: updates' covariances `(P + Pᵀ)/2`.
    pub force_symmetric: bool,
}

/// One scan's results, row-major. Column 0 of `weights`/`marginals` is the missed detection,
/// column `1 + j` detection `j` (0 where `gated[t, j]` is false).
#[derive(Debug, Clone, Default)]
pub struct ScanOutput {
    pub tracks: usize,
    pub detections: usize,
    pub dim: usize,
    pub meas_dim: usize,
    /// Predicted measurements ẑ, T×m.
    pub meas_means: Vec<f64>,
    /// Innovation covariances S, T×m×m.
    pub meas_covars: Vec<f64>,
    /// Cross covariances P̂ Hᵀ, T×D×m.
    pub cross_covars: Vec<f64>,
    /// Whether track t has a hypothesis for detection j, T×M.
    pub gated: Vec<bool>,
    /// Single-hypothesis (PDA) weights, normalised per track, T×(M+1).
    pub weights: Vec<f64>,
    /// Joint association marginals, T×(M+1).
    pub marginals: Vec<f64>,
    /// Posterior (reduced mixture) means, T×D, and covariances, T×D×D.
    pub means: Vec<f64>,
    pub covars: Vec<f64>,
    /// Whether a detection outweighs the missed detection, per track.
    pub is_update: Vec<bool>,
    /// Whether a detection outweighs some track's missed detection, per detection.
    pub taken: Vec<bool>,
}

fn check_scan(model: &MeasurementModel, input: &ScanInput) -> Result<()> {
    let (dim, tracks, dets, m) = (
        input.dim,
        input.prob_detect.len(),
        input.clutter.len(),
        model.ndim_meas(),
    );
    check_states(dim, tracks, input.means, input.covars)?;
    model.check_dim(dim)?;
    if input.detections.len() != dets * m {
        return Err(ModelError::shape(
            "detections",
            format!(
                "must be ({dets}, {m}) to match clutter_density and the model, got {} values",
                input.detections.len()
            ),
        ));
    }
    if let Some(row) = input
        .detections
        .chunks_exact(m)
        .position(|r| r.iter().any(|v| !v.is_finite()))
    {
        return Err(ModelError::non_finite(
            "detections",
            row,
            "a measurement holds NaN or infinity",
        ));
    }
    if let Some(t) = input.prob_detect.iter().position(|p| !(0.0..=1.0).contains(p)) {
        return Err(ModelError::invalid(
            "prob_detect",
            format!("row {t}: P_D must lie in [0, 1], got {}", input.prob_detect[t]),
        ));
    }
    if let Some(j) = input.clutter.iter().position(|l| !(l.is_finite() && *l > 0.0)) {
        return Err(ModelError::invalid(
            "clutter_density",
            format!(
                "row {j}: must be finite and > 0 (weights divide by it), got {}",
                input.clutter[j]
            ),
        ));
    }
    if !(0.0..=1.0).contains(&input.prob_gate) {
        return Err(ModelError::invalid(
            "prob_gate",
            format!("must lie in [0, 1], got {}", input.prob_gate),
        ));
    }
    if input.gate_threshold.is_nan() || input.gate_threshold < 0.0 {
        return Err(ModelError::invalid(
            "gate_threshold",
            format!("must be >= 0 (inf: no gate), got {}", input.gate_threshold),
        ));
    }
    Ok(())
}

/// Runs one JPDA scan (see the module documentation).
pub fn scan(model: &MeasurementModel, input: &ScanInput) -> Result<ScanOutput> {
    check_scan(model, input)?;
    let (dim, tracks, dets, m) = (
        input.dim,
        input.prob_detect.len(),
        input.clutter.len(),
        model.ndim_meas(),
    );
    let dd = dim * dim;
    let angle = model.angle_row();
    let noise = model.noise_matrix();
    let z: Vec<DVector<f64>> = memory::collected(
        "detections",
        input.detections.chunks_exact(m).map(DVector::from_row_slice),
    )?;
    let log_clutter: Vec<f64> = memory::collected("clutter", input.clutter.iter().map(|l| l.ln()))?;

    let pairs = tracks.checked_mul(dets);
    let columns = tracks.checked_mul(dets + 1);
    let mut out = ScanOutput {
        tracks,
        detections: dets,
        dim,
        meas_dim: m,
        gated: try_filled(pairs, false).ok_or_else(|| too_large(tracks, dets))?,
        weights: try_filled(columns, 0.0).ok_or_else(|| too_large(tracks, dets))?,
        is_update: memory::filled("means", tracks, false)?,
        taken: memory::filled("detections", dets, false)?,
        ..Default::default()
    };
    // Per track: prediction, gain-updated covariance, innovations of its gated detections.
    struct TrackUpdate {
        x: DVector<f64>,
        p: DMatrix<f64>,
        gain: DMatrix<f64>,
        p_updated: DMatrix<f64>,
        innovations: Vec<(usize, DVector<f64>)>,
    }
    let mut updates = memory::with_room("means", tracks)?;
    for t in 0..tracks {
        let x = DVector::from_row_slice(&input.means[t * dim..(t + 1) * dim]);
        let p = DMatrix::from_row_slice(dim, dim, &input.covars[t * dd..(t + 1) * dd]);
        let (z_hat, h) = model.linearised(&x);
        let cross = &p * h.transpose();
        let s = &h * &cross + &noise;
        out.meas_means.extend(z_hat.iter());
        push_row_major(&mut out.meas_covars, &s);
        push_row_major(&mut out.cross_covars, &cross);
        let chol = s.clone().cholesky().ok_or_else(|| {
            ModelError::not_positive_definite(
                "covars",
                format!("track {t}: the innovation covariance H P Hᵀ + R is not positive definite"),
            )
        })?;
        let lower = chol.l();
        let log_det = 2.0 * lower.diagonal().iter().map(|v| v.ln()).sum::<f64>();
        let pd = input.prob_detect[t];
        let log_pd = pd.ln();
        let row = &mut out.weights[t * (dets + 1)..(t + 1) * (dets + 1)];
        row[0] = (1.0 - pd * input.prob_gate).ln();
        let mut innovations = Vec::new();
        for (j, zj) in z.iter().enumerate() {
            let mut nu = zj - &z_hat;
            if let Some(a) = angle {
                nu[a] = mod_bearing(nu[a]);
            }
            let white = lower.solve_lower_triangular(&nu).ok_or_else(|| {
                ModelError::not_positive_definite(
                    "covars",
                    format!("track {t}: the innovation covariance H P Hᵀ + R is not positive definite"),
                )
            })?;
            let d2 = white.norm_squared();
            if d2 <= input.gate_threshold || input.include_all {
                out.gated[t * dets + j] = true;
                row[1 + j] = -0.5 * (log_det + d2 + m as f64 * LOG_TWO_PI) + log_pd - log_clutter[j];
                innovations.push((j, nu));
            }
        }
        // Log weights → weights relative to the largest, normalised to sum 1.
        let gated = &out.gated[t * dets..(t + 1) * dets];
        let max = std::iter::once(row[0])
            .chain((0..dets).filter(|&j| gated[j]).map(|j| row[1 + j]))
            .fold(f64::NEG_INFINITY, f64::max);
        if max == f64::NEG_INFINITY || max.is_nan() {
            return Err(ModelError::invalid(
                "prob_detect",
                format!("track {t}: every hypothesis has zero probability (P_D·P_G = 1 and no detection with a positive likelihood)"),
            ));
        }
        let mut sum = 0.0;
        row[0] = (row[0] - max).exp();
        sum += row[0];
        for j in 0..dets {
            if gated[j] {
                row[1 + j] = (row[1 + j] - max).exp();
                sum += row[1 + j];
            }
        }
        for w in row.iter_mut() {
            *w /= sum;
        }
        let s_inv = chol.inverse();
        let gain = &cross * s_inv;
        let mut p_updated = &p - (&gain * &s) * gain.transpose();
        if input.force_symmetric {
            p_updated = (&p_updated + p_updated.transpose()) / 2.0;
        }
        updates.push(TrackUpdate {
            x,
            p,
            gain,
            p_updated,
            innovations,
        });
    }

    out.marginals = joint_marginals(&out.weights, &out.gated, tracks, dets)?;

    // Gaussian mixture reduction of each track's hypotheses, weighted by the marginals.
    out.means = memory::with_room("means", input.means.len())?;
    out.covars = memory::with_room("covars", input.covars.len())?;
    for (t, u) in updates.iter().enumerate() {
        let beta = &out.marginals[t * (dets + 1)..(t + 1) * (dets + 1)];
        let missed = beta[0];
        // (one per gated detection of the track, whose innovations exist already)
        let mut components: Vec<(f64, DVector<f64>, &DMatrix<f64>)> = Vec::with_capacity(1 + u.innovations.len());
        components.push((missed, u.x.clone(), &u.p));
        for (j, nu) in &u.innovations {
            let b = beta[1 + j];
            if b > missed {
                out.is_update[t] = true;
                out.taken[*j] = true;
            }
            components.push((b, &u.x + &u.gain * nu, &u.p_updated));
        }
        let total: f64 = components.iter().map(|c| c.0).sum();
        let mut mean = DVector::zeros(dim);
        for (w, x, _) in &components {
            mean += x * (w / total);
        }
        let mut covar = DMatrix::zeros(dim, dim);
        for (w, x, p) in &components {
            let w = w / total;
            let delta = x - &mean;
            covar += *p * w + (&delta * delta.transpose()) * w;
        }
        out.means.extend(mean.iter());
        push_row_major(&mut out.covars, &covar);
    }
    Ok(out)
}
