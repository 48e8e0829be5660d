//! One JPDA scan over arrays: what Stone Soup's `PDAHypothesiser` + `JPDAwithEHM2` +
//! `MultiTargetMixtureTracker` compute for a scan, without a Python object per hypothesis.
//!
//! For `T` predicted tracks `(x̂_t, P̂_t)` and `M` detections `z_j` measured by one model:
//!
//! 1. **Measurement prediction** per track: `ẑ_t = h(x̂_t)`, `H_t` (the model matrix, Stone
//!    Soup's forward finite-difference Jacobian reproduced operation for operation, or the
//!    closed-form bearing–range Jacobian), `C_t = P̂_t H_tᵀ`, `S_t = H_t C_t + R`.
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

use crate::error::{ModelError, Result};
use nalgebra::{DMatrix, DVector};
use std::collections::BTreeMap;
use std::f64::consts::PI;

const TWO_PI: f64 = 2.0 * PI;
const LOG_TWO_PI: f64 = 1.837_877_066_409_345_5; // ln(2π)

/// Stone Soup's `mod_bearing`: `((x + π) mod 2π) − π`, the floored modulo of Python/NumPy.
pub fn mod_bearing(x: f64) -> f64 {
    (x + PI).rem_euclid(TWO_PI) - PI
}

/// NumPy's `spacing`: the distance from `x` to the next float away from zero (negative for
/// negative `x`).
fn spacing(x: f64) -> f64 {
    if !x.is_finite() {
        return f64::NAN;
    }
    let magnitude = x.abs();
    let next = f64::from_bits(magnitude.to_bits() + 1);
    let step = next - magnitude;
    if x.is_sign_negative() {
        -step
    } else {
        step
    }
}

/// How the bearing–range model is linearised.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Jacobian {
    /// Stone Soup's `jacobian()`: forward differences with step `max(10⁸·spacing(x_i), 10⁻⁸)`.
    FiniteDifference,
    /// `∂φ/∂x_{m_k} = (r₀R₁ₖ − r₁R₀ₖ)/ρ²`, `∂ρ/∂x_{m_k} = (r₀R₀ₖ + r₁R₁ₖ)/ρ`, `r = R·[x−t₀, y−t₁, 0]`.
    Analytic,
}

/// The measurement model of a scan's detections.
#[derive(Debug, Clone)]
pub enum MeasurementModel {
    /// `z = H x + v`, `v ~ N(0, R)`.
    Linear { matrix: DMatrix<f64>, noise: DMatrix<f64> },
    /// Stone Soup's `CartesianToBearingRange` in 2-D: `r = R·[x_{m₀} − t₀, x_{m₁} − t₁, 0]`,
    /// `z = [atan2(r₁, r₀), √(r₀² + r₁²)]`, bearing wrapped to `[−π, π)`.
    BearingRange { mapping: [usize; 2], offset: [f64; 2], rotation: [[f64; 3]; 3], noise: DMatrix<f64>, jacobian: Jacobian },
}

fn check_finite(argument: &'static str, values: &[f64]) -> Result<()> {
    if let Some(i) = values.iter().position(|v| !v.is_finite()) {
        return Err(ModelError::invalid(argument, format!("element {i} is not finite ({})", values[i])));
    }
    Ok(())
}

/// `len` copies of `value` (`None`: a size that overflowed), or None when the allocation
/// fails: sizes that come from the inputs (tracks × detections, a cluster's tree) are
/// allocated fallibly, so that an input too large for memory is an error, not an abort.
fn try_filled<T: Clone>(len: Option<usize>, value: T) -> Option<Vec<T>> {
    let len = len?;
    let mut out = Vec::new();
    out.try_reserve_exact(len).ok()?;
    out.resize(len, value);
    Some(out)
}

/// The error of a scan whose `tracks × detections` arrays cannot be allocated.
fn too_large(tracks: usize, dets: usize) -> ModelError {
    ModelError::invalid("detections", format!("{tracks} tracks × {dets} detections: the scan's association arrays could not be allocated"))
}

impl MeasurementModel {
    /// A linear Gaussian model from its row-major `rows × cols` matrix and `rows × rows` noise.
    pub fn linear(matrix: &[f64], rows: usize, cols: usize, noise: &[f64]) -> Result<Self> {
        if rows == 0 || cols == 0 || matrix.len() != rows * cols {
            return Err(ModelError::shape("matrix", format!("must be a non-empty ({rows}, {cols}) matrix, got {} values", matrix.len())));
        }
        if noise.len() != rows * rows {
            return Err(ModelError::shape("noise_covar", format!("must be ({rows}, {rows}) to match the matrix, got {} values", noise.len())));
        }
        check_finite("matrix", matrix)?;
        check_finite("noise_covar", noise)?;
        Ok(MeasurementModel::Linear { matrix: DMatrix::from_row_slice(rows, cols, matrix), noise: DMatrix::from_row_slice(rows, rows, noise) })
    }

    /// A 2-D bearing–range model: `rotation` is the row-major 3×3 rotation matrix, `noise`
    /// the 2×2 covariance of (bearing, range).
    pub fn bearing_range(mapping: [usize; 2], offset: [f64; 2], rotation: &[f64], noise: &[f64], jacobian: Jacobian) -> Result<Self> {
        if rotation.len() != 9 {
            return Err(ModelError::shape("rotation_matrix", format!("must be 3×3, got {} values", rotation.len())));
        }
        if noise.len() != 4 {
            return Err(ModelError::shape("noise_covar", format!("must be 2×2, got {} values", noise.len())));
        }
        if mapping[0] == mapping[1] {
            return Err(ModelError::invalid("mapping", format!("x and y must be different state indices, got {mapping:?}")));
        }
        check_finite("translation_offset", &offset)?;
        check_finite("rotation_matrix", rotation)?;
        check_finite("noise_covar", noise)?;
        let r = |i: usize, j: usize| rotation[3 * i + j];
        let rotation = [[r(0, 0), r(0, 1), r(0, 2)], [r(1, 0), r(1, 1), r(1, 2)], [r(2, 0), r(2, 1), r(2, 2)]];
        Ok(MeasurementModel::BearingRange { mapping, offset, rotation, noise: DMatrix::from_row_slice(2, 2, noise), jacobian })
    }

    /// Number of measured values per detection.
    pub fn ndim_meas(&self) -> usize {
        match self {
            MeasurementModel::Linear { matrix, .. } => matrix.nrows(),
            MeasurementModel::BearingRange { .. } => 2,
        }
    }

    fn noise(&self) -> &DMatrix<f64> {
        match self {
            MeasurementModel::Linear { noise, .. } | MeasurementModel::BearingRange { noise, .. } => noise,
        }
    }

    /// The measurement row holding an angle (wrapped in differences), if any.
    fn angle_row(&self) -> Option<usize> {
        match self {
            MeasurementModel::Linear { .. } => None,
            MeasurementModel::BearingRange { .. } => Some(0),
        }
    }

    fn check_dim(&self, dim: usize) -> Result<()> {
        match self {
            MeasurementModel::Linear { matrix, .. } if matrix.ncols() != dim => {
                Err(ModelError::shape("model", format!("the measurement matrix has {} columns, the states {dim}", matrix.ncols())))
            }
            MeasurementModel::BearingRange { mapping, .. } if mapping.iter().any(|&m| m >= dim) => {
                Err(ModelError::shape("model", format!("mapping {mapping:?} is out of range for states of {dim} values")))
            }
            _ => Ok(()),
        }
    }

    /// Predicted measurement `h(x)` and measurement matrix / Jacobian at `x`.
    pub fn linearise(&self, x: &DVector<f64>) -> (DVector<f64>, DMatrix<f64>) {
        match self {
            MeasurementModel::Linear { matrix, .. } => (matrix * x, matrix.clone()),
            MeasurementModel::BearingRange { mapping, offset, rotation, jacobian, .. } => {
                let dim = x.len();
                // One column through a 3×3 @ 3×1 product, as NumPy's matrix-vector kernel
                // rounds it here (a fused multiply-add onto the second term).
                let a = x[mapping[0]] - offset[0];
                let b = x[mapping[1]] - offset[1];
                let r0 = rotation[0][0].mul_add(a, rotation[0][1] * b);
                let r1 = rotation[1][0].mul_add(a, rotation[1][1] * b);
                let rho = (r0 * r0 + r1 * r1).sqrt();
                let phi = r1.atan2(r0);
                let z = DVector::from_vec(vec![mod_bearing(0.0 + phi), 0.0 + rho]);
                let mut h = DMatrix::zeros(2, dim);
                match jacobian {
                    Jacobian::Analytic => {
                        let rho2 = r0 * r0 + r1 * r1;
                        for k in 0..2 {
                            h[(0, mapping[k])] = (r0 * rotation[1][k] - r1 * rotation[0][k]) / rho2;
                            h[(1, mapping[k])] = (r0 * rotation[0][k] + r1 * rotation[1][k]) / rho;
                        }
                    }
                    Jacobian::FiniteDifference => {
                        // Columns 0..D of Stone Soup's perturbed states (x + δ_i e_i) and column D
                        // (x itself), through the model function as NumPy's matrix-matrix kernel
                        // rounds a 3×3 @ 3×(D+1) product (a fused multiply-add onto the first term).
                        let bearing_range = |state_a: f64, state_b: f64| {
                            let a = state_a - offset[0];
                            let b = state_b - offset[1];
                            let r0 = rotation[0][1].mul_add(b, rotation[0][0] * a);
                            let r1 = rotation[1][1].mul_add(b, rotation[1][0] * a);
                            (mod_bearing(0.0 + r1.atan2(r0)), 0.0 + (r0 * r0 + r1 * r1).sqrt())
                        };
                        let (base_phi, base_rho) = bearing_range(x[mapping[0]] + 0.0, x[mapping[1]] + 0.0);
                        for i in 0..dim {
                            let mut delta = 1e8 * spacing(x[i]);
                            if delta < 1e-8 {
                                delta = 1e-8;
                            }
                            let at = |k: usize| if k == i { x[k] + delta } else { x[k] + 0.0 };
                            let (phi_i, rho_i) = bearing_range(at(mapping[0]), at(mapping[1]));
                            h[(0, i)] = mod_bearing(phi_i - base_phi) / delta;
                            h[(1, i)] = (rho_i - base_rho) / delta;
                        }
                    }
                }
                (z, h)
            }
        }
    }
}

/// Kalman prediction `x' = F x`, `P' = F P Fᵀ + Q` of `T` states (`means` T×D, `covars`
/// T×D×D, row-major), state `t` with the transition `index[t]` of `matrices`/`noises`
/// (K×D×D each).
pub fn predict(dim: usize, means: &[f64], covars: &[f64], index: &[usize], matrices: &[f64], noises: &[f64]) -> Result<(Vec<f64>, Vec<f64>)> {
    let tracks = index.len();
    check_states(dim, tracks, means, covars)?;
    let dd = dim * dim;
    if !matrices.len().is_multiple_of(dd.max(1)) || matrices.len() != noises.len() {
        return Err(ModelError::shape("transition_matrices", format!("must be (K, {dim}, {dim}) like transition_covars")));
    }
    let kinds = matrices.len() / dd.max(1);
    if let Some(t) = index.iter().position(|&k| k >= kinds) {
        return Err(ModelError::invalid("transition_index", format!("row {t}: index {} is out of range for {kinds} transitions", index[t])));
    }
    check_finite("transition_matrices", matrices)?;
    check_finite("transition_covars", noises)?;
    let f: Vec<DMatrix<f64>> = (0..kinds).map(|k| DMatrix::from_row_slice(dim, dim, &matrices[k * dd..(k + 1) * dd])).collect();
    let q: Vec<DMatrix<f64>> = (0..kinds).map(|k| DMatrix::from_row_slice(dim, dim, &noises[k * dd..(k + 1) * dd])).collect();
    let mut out_means = Vec::with_capacity(tracks * dim);
    let mut out_covars = Vec::with_capacity(tracks * dd);
    for (t, &k) in index.iter().enumerate() {
        let x = DVector::from_row_slice(&means[t * dim..(t + 1) * dim]);
        let p = DMatrix::from_row_slice(dim, dim, &covars[t * dd..(t + 1) * dd]);
        let x = &f[k] * x;
        let p = (&f[k] * p) * f[k].transpose() + &q[k];
        out_means.extend(x.iter());
        push_row_major(&mut out_covars, &p);
    }
    Ok((out_means, out_covars))
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
        return Err(ModelError::shape("means", format!("must be ({tracks}, {dim}), got {} values", means.len())));
    }
    if covars.len() != tracks * dim * dim {
        return Err(ModelError::shape("covars", format!("must be ({tracks}, {dim}, {dim}), got {} values", covars.len())));
    }
    if let Some(row) = means.chunks_exact(dim).position(|r| r.iter().any(|v| !v.is_finite())) {
        return Err(ModelError::non_finite("means", row, "a state mean holds NaN or infinity"));
    }
    if let Some(row) = covars.chunks_exact(dim * dim).position(|r| r.iter().any(|v| !v.is_finite())) {
        return Err(ModelError::non_finite("covars", row, "a covariance holds NaN or infinity"));
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
    let (dim, tracks, dets, m) = (input.dim, input.prob_detect.len(), input.clutter.len(), model.ndim_meas());
    check_states(dim, tracks, input.means, input.covars)?;
    model.check_dim(dim)?;
    if input.detections.len() != dets * m {
        return Err(ModelError::shape("detections", format!("must be ({dets}, {m}) to match clutter_density and the model, got {} values", input.detections.len())));
    }
    if let Some(row) = input.detections.chunks_exact(m).position(|r| r.iter().any(|v| !v.is_finite())) {
        return Err(ModelError::non_finite("detections", row, "a measurement holds NaN or infinity"));
    }
    if let Some(t) = input.prob_detect.iter().position(|p| !(0.0..=1.0).contains(p)) {
        return Err(ModelError::invalid("prob_detect", format!("row {t}: P_D must lie in [0, 1], got {}", input.prob_detect[t])));
    }
    if let Some(j) = input.clutter.iter().position(|l| !(l.is_finite() && *l > 0.0)) {
        return Err(ModelError::invalid("clutter_density", format!("row {j}: must be finite and > 0 (weights divide by it), got {}", input.clutter[j])));
    }
    if !(0.0..=1.0).contains(&input.prob_gate) {
        return Err(ModelError::invalid("prob_gate", format!("must lie in [0, 1], got {}", input.prob_gate)));
    }
    if input.gate_threshold.is_nan() || input.gate_threshold < 0.0 {
        return Err(ModelError::invalid("gate_threshold", format!("must be >= 0 (inf: no gate), got {}", input.gate_threshold)));
    }
    Ok(())
}

/// Runs one JPDA scan (see the module documentation).
pub fn scan(model: &MeasurementModel, input: &ScanInput) -> Result<ScanOutput> {
    check_scan(model, input)?;
    let (dim, tracks, dets, m) = (input.dim, input.prob_detect.len(), input.clutter.len(), model.ndim_meas());
    let dd = dim * dim;
    let angle = model.angle_row();
    let noise = model.noise();
    let z: Vec<DVector<f64>> = input.detections.chunks_exact(m).map(DVector::from_row_slice).collect();
    let log_clutter: Vec<f64> = input.clutter.iter().map(|l| l.ln()).collect();

    let pairs = tracks.checked_mul(dets);
    let columns = tracks.checked_mul(dets + 1);
    let mut out = ScanOutput {
        tracks,
        detections: dets,
        dim,
        meas_dim: m,
        gated: try_filled(pairs, false).ok_or_else(|| too_large(tracks, dets))?,
        weights: try_filled(columns, 0.0).ok_or_else(|| too_large(tracks, dets))?,
        is_update: vec![false; tracks],
        taken: vec![false; dets],
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
    let mut updates = Vec::with_capacity(tracks);
    for t in 0..tracks {
        let x = DVector::from_row_slice(&input.means[t * dim..(t + 1) * dim]);
        let p = DMatrix::from_row_slice(dim, dim, &input.covars[t * dd..(t + 1) * dd]);
        let (z_hat, h) = model.linearise(&x);
        let cross = &p * h.transpose();
        let s = &h * &cross + noise;
        out.meas_means.extend(z_hat.iter());
        push_row_major(&mut out.meas_covars, &s);
        push_row_major(&mut out.cross_covars, &cross);
        let chol = s.clone().cholesky().ok_or_else(|| {
            ModelError::invalid("covars", format!("track {t}: the innovation covariance H P Hᵀ + R is not positive definite"))
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
                ModelError::invalid("covars", format!("track {t}: the innovation covariance H P Hᵀ + R is not positive definite"))
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
        let max = std::iter::once(row[0]).chain((0..dets).filter(|&j| gated[j]).map(|j| row[1 + j])).fold(f64::NEG_INFINITY, f64::max);
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
        updates.push(TrackUpdate { x, p, gain, p_updated, innovations });
    }

    out.marginals = joint_marginals(&out.weights, &out.gated, tracks, dets)?;

    // Gaussian mixture reduction of each track's hypotheses, weighted by the marginals.
    out.means.reserve(tracks * dim);
    out.covars.reserve(tracks * dd);
    for (t, u) in updates.iter().enumerate() {
        let beta = &out.marginals[t * (dets + 1)..(t + 1) * (dets + 1)];
        let missed = beta[0];
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

// --- joint association marginals ----------------------------------------------------------

/// A set of a cluster's detections (bit `k` of word `k / 64`).
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord)]
struct Bits(Vec<u64>);

impl Bits {
    fn empty(words: usize) -> Self {
        Bits(vec![0; words])
    }
    fn has(&self, k: usize) -> bool {
        self.0[k / 64] >> (k % 64) & 1 == 1
    }
    fn set(&mut self, k: usize) {
        self.0[k / 64] |= 1 << (k % 64);
    }
    fn intersects(&self, other: &Bits) -> bool {
        self.0.iter().zip(&other.0).any(|(a, b)| a & b != 0)
    }
    fn union(&self, other: &Bits) -> Bits {
        Bits(self.0.iter().zip(&other.0).map(|(a, b)| a | b).collect())
    }
    /// `(self ∪ {k}) ∩ mask` (`k = None`: no detection).
    fn with_masked(&self, k: Option<usize>, mask: &Bits) -> Bits {
        let mut out = self.clone();
        if let Some(k) = k {
            out.set(k);
        }
        for (o, m) in out.0.iter_mut().zip(&mask.0) {
            *o &= m;
        }
        out
    }
}

/// One track of a cluster's EHM2 tree.
struct Level {
    /// (cluster-local detection or None for the missed detection, weight)
    hyps: Vec<(Option<usize>, f64)>,
    /// Detections used by this track or any below it.
    acc: Bits,
    children: Vec<usize>,
    /// Used-detection set of each node (those that matter to this subtree).
    nodes: Vec<Bits>,
    index: BTreeMap<Bits, usize>,
    /// For node n, hypothesis h, child c: the child's node (`NONE` when h is not allowed at n).
    next: Vec<usize>,
    backward: Vec<f64>,
    forward: Vec<f64>,
}

const NONE: usize = usize::MAX;

impl Level {
    /// The node of `key`, created if new; `budget` counts the cluster's nodes still allowed.
    fn node(&mut self, key: Bits, budget: &mut TreeBudget) -> Result<usize> {
        if let Some(&n) = self.index.get(&key) {
            return Ok(n);
        }
        budget.take_nodes(1)?;
        let n = self.nodes.len();
        self.nodes.try_reserve(1).map_err(|_| budget.out_of_memory("the tree's nodes"))?;
        self.nodes.push(key.clone());
        self.index.insert(key, n);
        Ok(n)
    }
}

/// Most hypothesis-tree nodes one cluster may have (summed over its tracks' levels).
///
/// The tree is exact EHM2: a track's level has one node per distinct set of detections,
/// used by the tracks above it, that still matters below it, and that number grows
/// exponentially with the cluster's overlap. Unbounded, it took a context-aware JPDA whose
/// unseen tracks coasted for minutes (145 tracks sharing 35 detections) 21.7 s for one scan
/// and then more than 12 GB, until an allocation failed and aborted the process.
///
/// The budget comes from memory. A node costs ≈ 210 bytes (measured: 4.2 million nodes of a
/// dense 22 × 22 cluster held 1.28 GB of which 0.39 GB were links): its detection set twice
/// (the level's node list and its index key: a 24-byte `Vec<u64>` header and a heap block
/// of ≥ 32 bytes each), the index's B-tree entry and slack, its backward and forward
/// weights. 2²² ≈ 4.2 million nodes are thus ≈ 0.9 GB: what a machine with a few GB to spare
/// can hold beside other work, and far beyond what a tractable scan needs (the experiment's
/// bounded JPDAs stay orders of magnitude below; see `trackers.py`).
pub const MAX_TREE_NODES: usize = 1 << 22;

/// Most child-node links (node × hypothesis × child track, 8 bytes each) one cluster's tree
/// may hold: 2²⁴ ≈ 16.8 million links are 134 MB, so nodes and links together stay near
/// 1 GB. Links also bound the time: each is a set operation and an index look-up when built
/// (≈ 2 s for 16.8 million, measured on a dense cluster) and the forward pass costs links ×
/// children. Every node but the roots is reached through a link, so a tree within this
/// budget has at most this many nodes plus its roots; the node budget binds first only for
/// tracks with few hypotheses and children.
pub const MAX_TREE_EDGES: usize = 1 << 24;

/// What is left of one cluster's tree budget, and the cluster it is for (the error names it).
struct TreeBudget {
    limits: TreeLimits,
    nodes: usize,
    edges: usize,
    tracks: usize,
    dets: usize,
}

/// The most nodes and node links of one cluster's tree.
#[derive(Debug, Clone, Copy)]
struct TreeLimits {
    nodes: usize,
    edges: usize,
}

const TREE_LIMITS: TreeLimits = TreeLimits { nodes: MAX_TREE_NODES, edges: MAX_TREE_EDGES };

impl TreeBudget {
    fn new(limits: TreeLimits, tracks: usize, dets: usize) -> Self {
        TreeBudget { limits, nodes: limits.nodes, edges: limits.edges, tracks, dets }
    }

    fn intractable(&self, what: String) -> ModelError {
        ModelError::invalid(
            "weights",
            format!(
                "the association cluster of {} tracks and {} detections (tracks sharing gated detections) is intractable for exact JPDA: {what}; \
                 bound the tracks' uncertainty (a deleter on covariance) or gate more tightly",
                self.tracks, self.dets
            ),
        )
    }

    fn take_nodes(&mut self, count: usize) -> Result<()> {
        if count > self.nodes {
            return Err(self.intractable(format!("its hypothesis tree needs more than {} nodes", self.limits.nodes)));
        }
        self.nodes -= count;
        Ok(())
    }

    fn take_edges(&mut self, count: Option<usize>) -> Result<()> {
        match count {
            Some(count) if count <= self.edges => {
                self.edges -= count;
                Ok(())
            }
            _ => Err(self.intractable(format!("its hypothesis tree needs more than {} node links", self.limits.edges))),
        }
    }

    fn out_of_memory(&self, what: &str) -> ModelError {
        self.intractable(format!("allocating {what} failed"))
    }

    /// `len` copies of `value`, allocated fallibly.
    fn filled<T: Clone>(&self, len: usize, value: T, what: &str) -> Result<Vec<T>> {
        try_filled(Some(len), value).ok_or_else(|| self.out_of_memory(what))
    }
}

/// Multiplies `values` by the power of two that brings their largest near 1 (exact).
fn rescale(values: &mut [f64]) {
    let max = values.iter().copied().fold(0.0_f64, f64::max);
    if max > 0.0 && max.is_finite() {
        let exponent = (max.log2().floor() as i32).clamp(-1000, 1000);
        let factor = 2.0_f64.powi(-exponent);
        for v in values.iter_mut() {
            *v *= factor;
        }
    }
}

fn check_weights(weights: &[f64], valid: &[bool], tracks: usize, dets: usize) -> Result<()> {
    if weights.len() != tracks * (dets + 1) {
        return Err(ModelError::shape("weights", format!("must be ({tracks}, {}), got {} values", dets + 1, weights.len())));
    }
    if valid.len() != tracks * dets {
        return Err(ModelError::shape("gated", format!("must be ({tracks}, {dets}), got {} values", valid.len())));
    }
    for t in 0..tracks {
        let row = &weights[t * (dets + 1)..(t + 1) * (dets + 1)];
        let used = std::iter::once(0).chain((0..dets).filter(|&j| valid[t * dets + j]).map(|j| j + 1));
        for k in used {
            if !(row[k].is_finite() && row[k] >= 0.0) {
                return Err(ModelError::invalid("weights", format!("row {t}, column {k}: must be finite and >= 0, got {}", row[k])));
            }
        }
    }
    Ok(())
}

fn no_event(tracks: &[usize]) -> ModelError {
    ModelError::invalid("weights", format!("no joint association of tracks {tracks:?} has positive probability"))
}

/// Exact marginal association probabilities of `tracks` tracks and `dets` detections:
/// `weights` (T×(M+1), column 0 the missed detection) are the single-hypothesis weights,
/// `valid` (T×M) which detection hypotheses exist. Returns T×(M+1), each row summing to 1
/// over its hypotheses (0 elsewhere).
///
/// Each cluster's tree is bounded by [`MAX_TREE_NODES`] and [`MAX_TREE_EDGES`]: a cluster
/// beyond them is an error naming its numbers of tracks and detections (argument `weights`).
pub fn joint_marginals(weights: &[f64], valid: &[bool], tracks: usize, dets: usize) -> Result<Vec<f64>> {
    joint_marginals_within(TREE_LIMITS, weights, valid, tracks, dets)
}

fn joint_marginals_within(limits: TreeLimits, weights: &[f64], valid: &[bool], tracks: usize, dets: usize) -> Result<Vec<f64>> {
    check_weights(weights, valid, tracks, dets)?;
    let mut out = try_filled(tracks.checked_mul(dets + 1), 0.0).ok_or_else(|| too_large(tracks, dets))?;
    // Clusters: tracks connected through shared detections (union–find, smallest index as root).
    let mut parent: Vec<usize> = (0..tracks).collect();
    fn find(parent: &mut [usize], mut a: usize) -> usize {
        while parent[a] != a {
            parent[a] = parent[parent[a]];
            a = parent[a];
        }
        a
    }
    for j in 0..dets {
        let mut first = None;
        for t in 0..tracks {
            if valid[t * dets + j] {
                match first {
                    None => first = Some(t),
                    Some(f) => {
                        let (a, b) = (find(&mut parent, f), find(&mut parent, t));
                        if a != b {
                            parent[a.max(b)] = a.min(b);
                        }
                    }
                }
            }
        }
    }
    let mut clusters: BTreeMap<usize, Vec<usize>> = BTreeMap::new();
    for t in 0..tracks {
        let root = find(&mut parent, t);
        clusters.entry(root).or_default().push(t);
    }
    for members in clusters.values() {
        solve_cluster(limits, members, weights, valid, dets, &mut out)?;
    }
    Ok(out)
}

fn solve_cluster(limits: TreeLimits, members: &[usize], weights: &[f64], valid: &[bool], dets: usize, out: &mut [f64]) -> Result<()> {
    // The cluster's detections, in index order.
    let local: Vec<usize> = (0..dets).filter(|&j| members.iter().any(|&t| valid[t * dets + j])).collect();
    let words = local.len().div_ceil(64).max(1);
    let mut levels: Vec<Level> = members
        .iter()
        .map(|&t| {
            let row = &weights[t * (dets + 1)..(t + 1) * (dets + 1)];
            let mut hyps = vec![(None, row[0])];
            let mut meas = Bits::empty(words);
            for (k, &j) in local.iter().enumerate() {
                if valid[t * dets + j] {
                    hyps.push((Some(k), row[1 + j]));
                    meas.set(k);
                }
            }
            Level { hyps, acc: meas, children: Vec::new(), nodes: Vec::new(), index: BTreeMap::new(), next: Vec::new(), backward: Vec::new(), forward: Vec::new() }
        })
        .collect();
    let n = levels.len();

    // The tree, built from the last track up: a track's children are the current roots whose
    // detections (theirs and their descendants') meet its own; the others stay roots.
    let mut roots: Vec<usize> = Vec::new();
    for l in (0..n).rev() {
        let own = levels[l].acc.clone();
        let mut acc = own.clone();
        let mut children = Vec::new();
        let mut kept = vec![l];
        for &r in &roots {
            if own.intersects(&levels[r].acc) {
                acc = acc.union(&levels[r].acc);
                children.push(r);
            } else {
                kept.push(r);
            }
        }
        levels[l].acc = acc;
        levels[l].children = children;
        roots = kept;
    }

    // Nodes, top down (a parent's index is below its children's), within the budget.
    let mut budget = TreeBudget::new(limits, n, local.len());
    for &r in &roots {
        levels[r].node(Bits::empty(words), &mut budget)?;
    }
    for l in 0..n {
        let children = std::mem::take(&mut levels[l].children);
        let hyps = std::mem::take(&mut levels[l].hyps);
        let nodes = std::mem::take(&mut levels[l].nodes);
        let links = nodes.len().checked_mul(hyps.len()).and_then(|v| v.checked_mul(children.len()));
        budget.take_edges(links)?;
        let mut next = budget.filled(links.unwrap_or_default(), NONE, "the tree's node links")?;
        for (ni, used) in nodes.iter().enumerate() {
            for (h, &(det, _)) in hyps.iter().enumerate() {
                if det.is_some_and(|k| used.has(k)) {
                    continue;
                }
                for (ci, &c) in children.iter().enumerate() {
                    let key = used.with_masked(det, &levels[c].acc);
                    next[(ni * hyps.len() + h) * children.len() + ci] = levels[c].node(key, &mut budget)?;
                }
            }
        }
        let level = &mut levels[l];
        level.children = children;
        level.hyps = hyps;
        level.nodes = nodes;
        level.next = next;
    }

    let allowed = |level: &Level, ni: usize, h: usize| level.hyps[h].0.is_none_or(|k| !level.nodes[ni].has(k));

    // Backward weights, bottom up: B(n) = Σ_h w_h Π_c B(child node).
    for l in (0..n).rev() {
        let (nh, nc) = (levels[l].hyps.len(), levels[l].children.len());
        let mut backward = budget.filled(levels[l].nodes.len(), 0.0, "the backward weights")?;
        for (ni, b) in backward.iter_mut().enumerate() {
            for h in 0..nh {
                if !allowed(&levels[l], ni, h) {
                    continue;
                }
                let mut term = levels[l].hyps[h].1;
                for ci in 0..nc {
                    let c = levels[l].children[ci];
                    term *= levels[c].backward[levels[l].next[(ni * nh + h) * nc + ci]];
                }
                *b += term;
            }
        }
        rescale(&mut backward);
        levels[l].backward = backward;
    }

    // Forward weights, top down: each child node gathers F(parent) w_h Π_siblings B.
    for &r in &roots {
        levels[r].forward = budget.filled(levels[r].nodes.len(), 1.0, "the forward weights")?;
    }
    for l in 0..n {
        let (nh, nc) = (levels[l].hyps.len(), levels[l].children.len());
        rescale(&mut levels[l].forward);
        let children = levels[l].children.clone();
        for &c in &children {
            levels[c].forward = budget.filled(levels[c].nodes.len(), 0.0, "the forward weights")?;
        }
        for ni in 0..levels[l].nodes.len() {
            for h in 0..nh {
                if !allowed(&levels[l], ni, h) {
                    continue;
                }
                let base = levels[l].forward[ni] * levels[l].hyps[h].1;
                let child_nodes: Vec<usize> = (0..nc).map(|ci| levels[l].next[(ni * nh + h) * nc + ci]).collect();
                for ci in 0..nc {
                    let mut term = base;
                    for (si, &s) in children.iter().enumerate() {
                        if si != ci {
                            term *= levels[s].backward[child_nodes[si]];
                        }
                    }
                    levels[children[ci]].forward[child_nodes[ci]] += term;
                }
            }
        }
    }

    // Posterior of each hypothesis: w_h Σ_n F(n) Π_c B(child node), normalised per track.
    for (l, &t) in members.iter().enumerate() {
        let level = &levels[l];
        let (nh, nc) = (level.hyps.len(), level.children.len());
        let mut post = vec![0.0; nh];
        for (h, p) in post.iter_mut().enumerate() {
            let mut sum = 0.0;
            for ni in 0..level.nodes.len() {
                if !allowed(level, ni, h) {
                    continue;
                }
                let mut term = level.forward[ni];
                for ci in 0..nc {
                    term *= levels[level.children[ci]].backward[level.next[(ni * nh + h) * nc + ci]];
                }
                sum += term;
            }
            *p = level.hyps[h].1 * sum;
        }
        let total: f64 = post.iter().sum();
        if !(total > 0.0 && total.is_finite()) {
            return Err(no_event(members));
        }
        let row = &mut out[t * (dets + 1)..(t + 1) * (dets + 1)];
        for (h, &(det, _)) in level.hyps.iter().enumerate() {
            let column = det.map_or(0, |k| 1 + local[k]);
            row[column] = post[h] / total;
        }
    }
    Ok(())
}

/// The marginals by enumerating every joint event (each track: missed or one of its
/// hypotheses, no detection twice). Exponential: for tests and small inputs only.
pub fn brute_force_marginals(weights: &[f64], valid: &[bool], tracks: usize, dets: usize) -> Result<Vec<f64>> {
    check_weights(weights, valid, tracks, dets)?;
    let options: Vec<Vec<usize>> = (0..tracks).map(|t| std::iter::once(0).chain((0..dets).filter(|&j| valid[t * dets + j]).map(|j| j + 1)).collect()).collect();
    let mut sums = vec![0.0; tracks * (dets + 1)];
    let mut choice = vec![0usize; tracks];
    let mut total = 0.0;
    'events: loop {
        let mut used = vec![false; dets + 1];
        let mut ok = true;
        let mut product = 1.0;
        for t in 0..tracks {
            let column = options[t][choice[t]];
            if column > 0 {
                if used[column] {
                    ok = false;
                    break;
                }
                used[column] = true;
            }
            product *= weights[t * (dets + 1) + column];
        }
        if ok {
            total += product;
            for t in 0..tracks {
                sums[t * (dets + 1) + options[t][choice[t]]] += product;
            }
        }
        for t in 0..tracks {
            choice[t] += 1;
            if choice[t] < options[t].len() {
                continue 'events;
            }
            choice[t] = 0;
        }
        break;
    }
    if total.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return Err(no_event(&(0..tracks).collect::<Vec<_>>()));
    }
    Ok(sums.iter().map(|s| s / total).collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::rngs::StdRng;
    use rand::{Rng, SeedableRng};

    fn random_problem(rng: &mut StdRng, tracks: usize, dets: usize, density: f64) -> (Vec<f64>, Vec<bool>) {
        let valid: Vec<bool> = (0..tracks * dets).map(|_| rng.random::<f64>() < density).collect();
        let weights: Vec<f64> = (0..tracks * (dets + 1)).map(|_| rng.random::<f64>().powi(3) * 10.0 + 1e-12).collect();
        (weights, valid)
    }

    #[test]
    fn marginals_equal_brute_force_enumeration() {
        let mut rng = StdRng::seed_from_u64(7);
        for case in 0..300 {
            let tracks = 1 + case % 7;
            let dets = case % 9;
            let density = [0.2, 0.5, 0.9][case % 3];
            let (weights, valid) = random_problem(&mut rng, tracks, dets, density);
            let ehm = joint_marginals(&weights, &valid, tracks, dets).unwrap();
            let brute = brute_force_marginals(&weights, &valid, tracks, dets).unwrap();
            for (a, b) in ehm.iter().zip(&brute) {
                assert!((a - b).abs() <= 1e-12 * b.abs().max(1e-300) + 1e-15, "case {case}: {a} vs {b}");
            }
            for t in 0..tracks {
                let row: f64 = ehm[t * (dets + 1)..(t + 1) * (dets + 1)].iter().sum();
                assert!((row - 1.0).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn marginals_survive_weights_that_would_underflow_a_product() {
        // 40 tracks in one chain, each with weights around 1e-20: the product of one event
        // is 1e-800, far below f64; the per-level rescaling keeps every node representable.
        let (tracks, dets) = (40, 41);
        let mut weights = vec![0.0; tracks * (dets + 1)];
        let mut valid = vec![false; tracks * dets];
        for t in 0..tracks {
            weights[t * (dets + 1)] = 1e-20;
            for j in [t, t + 1] {
                valid[t * dets + j] = true;
                weights[t * (dets + 1) + 1 + j] = 3e-20 * (1.0 + j as f64 / 10.0);
            }
        }
        let marginals = joint_marginals(&weights, &valid, tracks, dets).unwrap();
        assert!(marginals.iter().all(|m| m.is_finite()));
        for t in 0..tracks {
            let row: f64 = marginals[t * (dets + 1)..(t + 1) * (dets + 1)].iter().sum();
            assert!((row - 1.0).abs() < 1e-12);
        }
        // Scaling every weight by one constant changes no marginal.
        let scaled: Vec<f64> = weights.iter().map(|w| w * 1e20).collect();
        let reference = joint_marginals(&scaled, &valid, tracks, dets).unwrap();
        for (a, b) in marginals.iter().zip(&reference) {
            assert!((a - b).abs() <= 1e-12);
        }
    }

    #[test]
    fn impossible_cluster_is_an_error_naming_the_weights() {
        // Two tracks, no missed-detection mass, one shared detection: no valid joint event.
        let weights = vec![0.0, 1.0, 0.0, 1.0];
        let valid = vec![true, true];
        let err = joint_marginals(&weights, &valid, 2, 1).unwrap_err();
        assert_eq!(err.argument(), "weights");
        assert_eq!(brute_force_marginals(&weights, &valid, 2, 1).unwrap_err().argument(), "weights");
    }

    /// `tracks` tracks each gating every one of `dets` detections: one cluster whose exact
    /// tree is the subsets of detections used so far (Σ_k C(M, k) nodes per level).
    fn dense_cluster(tracks: usize, dets: usize) -> (Vec<f64>, Vec<bool>) {
        let weights: Vec<f64> = (0..tracks * (dets + 1)).map(|i| 1.0 + (i % 7) as f64 / 10.0).collect();
        (weights, vec![true; tracks * dets])
    }

    #[test]
    fn intractable_cluster_is_an_error_naming_its_size() {
        // 60 tracks sharing 60 detections: C(60, 30) ≈ 1.2e17 used-detection sets; the link
        // budget stops the tree after a few hundred thousand nodes (< 0.2 GB, under a second).
        let (tracks, dets) = (60, 60);
        let (weights, valid) = dense_cluster(tracks, dets);
        let err = joint_marginals(&weights, &valid, tracks, dets).unwrap_err();
        assert_eq!(err.argument(), "weights");
        let message = err.to_string();
        assert!(message.contains("cluster of 60 tracks and 60 detections"), "{message}");
        assert!(message.contains("intractable"), "{message}");
        // A tractable cluster next to it in the same call is not the one named.
        let mut w = weights.clone();
        let mut v = valid.clone();
        w.extend([0.5, 0.0].iter().cycle().take(dets + 1));
        v.extend(std::iter::repeat_n(false, dets));
        let err = joint_marginals(&w, &v, tracks + 1, dets).unwrap_err();
        assert!(err.to_string().contains("cluster of 60 tracks and 60 detections"));
    }

    #[test]
    fn each_tree_budget_is_enforced_and_a_cluster_within_it_is_exact() {
        let (tracks, dets) = (6, 5);
        let (weights, valid) = dense_cluster(tracks, dets);
        // Nodes per level: 1, 6, 16, 26, 31, 32 (used sets of ≤ l of 5 detections): 112.
        let exact = brute_force_marginals(&weights, &valid, tracks, dets).unwrap();
        let ample = TreeLimits { nodes: 112, edges: 112 * 6 };
        let within = joint_marginals_within(ample, &weights, &valid, tracks, dets).unwrap();
        for (a, b) in within.iter().zip(&exact) {
            assert!((a - b).abs() <= 1e-12, "{a} vs {b}");
        }
        let nodes = joint_marginals_within(TreeLimits { nodes: 111, ..ample }, &weights, &valid, tracks, dets).unwrap_err();
        assert!(nodes.to_string().contains("cluster of 6 tracks and 5 detections"), "{nodes}");
        assert!(nodes.to_string().contains("more than 111 nodes"), "{nodes}");
        // Links: each level's nodes × 6 hypotheses × 1 child, the last level none: 80 × 6.
        let edges = joint_marginals_within(TreeLimits { edges: 80 * 6 - 1, ..ample }, &weights, &valid, tracks, dets).unwrap_err();
        assert!(edges.to_string().contains("more than 479 node links"), "{edges}");
        assert!(joint_marginals_within(TreeLimits { edges: 80 * 6, ..ample }, &weights, &valid, tracks, dets).is_ok());
    }

    #[test]
    fn scan_of_an_intractable_cluster_is_an_error_not_an_abort() {
        // 40 tracks at one place, 40 detections around it, an open gate: one cluster of all.
        let model = linear_model();
        let (tracks, dets) = (40, 40);
        let means = vec![0.0; tracks * 4];
        let covars: Vec<f64> = (0..tracks * 16).map(|k| if k % 16 % 5 == 0 { 100.0 } else { 0.0 }).collect();
        let detections: Vec<f64> = (0..dets * 2).map(|k| (k as f64 * 0.37).sin()).collect();
        let prob_detect = vec![0.9; tracks];
        let clutter = vec![1e-3; dets];
        let input = ScanInput {
            dim: 4,
            means: &means,
            covars: &covars,
            detections: &detections,
            prob_detect: &prob_detect,
            clutter: &clutter,
            prob_gate: 0.95,
            gate_threshold: f64::INFINITY,
            include_all: false,
            force_symmetric: false,
        };
        let err = scan(&model, &input).unwrap_err();
        assert_eq!(err.argument(), "weights");
        assert!(err.to_string().contains("cluster of 40 tracks and 40 detections"), "{err}");
    }

    #[test]
    fn mod_bearing_is_the_floored_modulo() {
        assert_eq!(mod_bearing(PI), -PI);
        assert_eq!(mod_bearing(-PI), -PI);
        assert_eq!(mod_bearing(0.5), 0.5);
        assert!((mod_bearing(3.0 * PI + 0.25) - (-PI + 0.25)).abs() < 1e-12);
        assert_eq!(spacing(1.0), f64::EPSILON);
        assert_eq!(spacing(-1.0), -f64::EPSILON);
    }

    fn bearing_range(jacobian: Jacobian) -> MeasurementModel {
        let h: f64 = 0.7;
        let rotation = [h.cos(), h.sin(), 0.0, -h.sin(), h.cos(), 0.0, 0.0, 0.0, 1.0];
        MeasurementModel::bearing_range([0, 2], [10.0, -5.0], &rotation, &[1e-4, 0.0, 0.0, 25.0], jacobian).unwrap()
    }

    #[test]
    fn analytic_and_finite_difference_jacobians_agree() {
        let x = DVector::from_vec(vec![300.0, 2.0, -150.0, 1.0]);
        let (z_fd, h_fd) = bearing_range(Jacobian::FiniteDifference).linearise(&x);
        let (z_an, h_an) = bearing_range(Jacobian::Analytic).linearise(&x);
        assert_eq!(z_fd, z_an);
        // Forward differences with steps of 1e-8 (negative coordinates) carry an error of
        // one ulp of the value over the step: ~6e-14 / 1e-8 for a range of 300 m (Stone Soup's
        // own Jacobian here is off by 3.7e-6 in ∂ρ/∂y).
        for (a, b) in h_fd.iter().zip(h_an.iter()) {
            assert!((a - b).abs() <= 1e-5, "{a} vs {b}");
        }
        assert_eq!(h_an[(0, 1)], 0.0);
        assert_eq!(h_fd[(1, 3)], 0.0);
    }

    fn linear_model() -> MeasurementModel {
        MeasurementModel::linear(&[1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0], 2, 4, &[0.75, 0.0, 0.0, 0.75]).unwrap()
    }

    #[test]
    fn scan_of_one_track_is_the_pda_update() {
        // One track, two detections: marginals are the normalised PDA weights, and the
        // posterior the mixture of the missed prediction and the two Kalman updates.
        let model = linear_model();
        let means = [0.0, 1.0, 0.0, 1.0];
        let covars = [1.5, 0.0, 0.0, 0.0, 0.0, 0.5, 0.0, 0.0, 0.0, 0.0, 1.5, 0.0, 0.0, 0.0, 0.0, 0.5];
        let detections = [0.5, -0.3, 1.2, 0.4];
        let input = ScanInput {
            dim: 4,
            means: &means,
            covars: &covars,
            detections: &detections,
            prob_detect: &[0.9],
            clutter: &[0.125, 0.125],
            prob_gate: 0.95,
            gate_threshold: 5.991464547107979,
            include_all: false,
            force_symmetric: false,
        };
        let out = scan(&model, &input).unwrap();
        assert_eq!(out.gated, vec![true, true]);
        for (w, m) in out.weights.iter().zip(&out.marginals) {
            assert!((w - m).abs() < 1e-14);
        }
        // By hand: S = P_xy + R = 2.25 I.
        let s = 2.25_f64;
        let lik = |dx: f64, dy: f64| (-(dx * dx + dy * dy) / (2.0 * s)).exp() / (2.0 * PI * s);
        let w = [1.0 - 0.9 * 0.95, 0.9 * lik(0.5, -0.3) / 0.125, 0.9 * lik(1.2, 0.4) / 0.125];
        let total: f64 = w.iter().sum();
        for (k, wk) in w.iter().enumerate() {
            assert!((out.weights[k] - wk / total).abs() < 1e-14);
        }
        let gain = 1.5 / s;
        let x0 = w[1] / total * gain * 0.5 + w[2] / total * gain * 1.2;
        assert!((out.means[0] - x0).abs() < 1e-14);
        assert!(out.is_update[0]);
        let taken: Vec<bool> = (0..2).map(|j| w[1 + j] > w[0]).collect();
        assert_eq!(out.taken, taken);
    }

    #[test]
    fn scan_without_detections_keeps_the_prediction() {
        let model = linear_model();
        let means = [1.0, 2.0, 3.0, 4.0];
        let covars: Vec<f64> = (0..16).map(|k| if k % 5 == 0 { 2.0 } else { 0.0 }).collect();
        let input = ScanInput { dim: 4, means: &means, covars: &covars, detections: &[], prob_detect: &[0.4], clutter: &[], prob_gate: 0.95, gate_threshold: 6.0, include_all: false, force_symmetric: false };
        let out = scan(&model, &input).unwrap();
        assert_eq!(out.means, means.to_vec());
        assert_eq!(out.covars, covars);
        assert!(!out.is_update[0]);
    }

    #[test]
    fn bad_inputs_name_their_argument() {
        let model = linear_model();
        let means = [0.0; 4];
        let covars: Vec<f64> = (0..16).map(|k| if k % 5 == 0 { 1.0 } else { 0.0 }).collect();
        let base = ScanInput { dim: 4, means: &means, covars: &covars, detections: &[0.0, 0.0], prob_detect: &[0.5], clutter: &[1.0], prob_gate: 0.95, gate_threshold: 6.0, include_all: false, force_symmetric: false };
        let cases: Vec<(ScanInput, &str)> = vec![
            (ScanInput { prob_detect: &[1.5], ..base }, "prob_detect"),
            (ScanInput { clutter: &[0.0], ..base }, "clutter_density"),
            (ScanInput { detections: &[f64::NAN, 0.0], ..base }, "detections"),
            (ScanInput { detections: &[0.0], ..base }, "detections"),
            (ScanInput { means: &[0.0, 0.0, f64::INFINITY, 0.0], ..base }, "means"),
            (ScanInput { covars: &covars[..15], ..base }, "covars"),
            (ScanInput { prob_gate: -0.1, ..base }, "prob_gate"),
            (ScanInput { gate_threshold: f64::NAN, ..base }, "gate_threshold"),
            (ScanInput { dim: 3, means: &[0.0; 3], covars: &[0.0; 9], ..base }, "model"),
        ];
        for (input, argument) in cases {
            assert_eq!(scan(&model, &input).unwrap_err().argument(), argument);
        }
        let singular = vec![0.0; 16];
        let zero_noise = MeasurementModel::linear(&[1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0], 2, 4, &[0.0; 4]).unwrap();
        assert_eq!(scan(&zero_noise, &ScanInput { covars: &singular, ..base }).unwrap_err().argument(), "covars");
        assert_eq!(MeasurementModel::linear(&[1.0], 2, 4, &[0.0; 4]).unwrap_err().argument(), "matrix");
        assert_eq!(MeasurementModel::bearing_range([0, 0], [0.0; 2], &[0.0; 9], &[0.0; 4], Jacobian::Analytic).unwrap_err().argument(), "mapping");
        assert_eq!(predict(4, &means, &covars, &[1], &covars, &covars).unwrap_err().argument(), "transition_index");
    }

    #[test]
    fn predict_is_the_kalman_prediction() {
        let f = [1.0, 1.0, 0.0, 1.0];
        let q = [0.25, 0.5, 0.5, 1.0];
        let (x, p) = predict(2, &[1.0, 2.0], &[1.0, 0.0, 0.0, 1.0], &[0], &f, &q).unwrap();
        assert_eq!(x, vec![3.0, 2.0]);
        assert_eq!(p, vec![2.25, 1.5, 1.5, 2.0]);
    }
}
