//! The GM-PHD measurement update of one scan (see the module docs of [`super`]).

use super::{Mixture, BIRTH};
use crate::error::{ModelError, Result};
use crate::kalman::linalg::{
    general_inverse_into, matmul, matmul_bt, matvec, quadratic_form, spd_inverse_into, symmetric_product,
};
use crate::kalman::MeasurementModel;
use crate::memory;

/// The settings of the stock components that take part in the update.
#[derive(Debug, Clone, Copy)]
pub struct UpdateParams {
    /// `PHDUpdater.prob_survival` (applied to every non-birth term).
    pub prob_survival: f64,
    /// `DistanceHypothesiser.missed_distance`: a pair is gated when its distance is below it.
    pub gate: f64,
    /// The gate measures the squared Mahalanobis distance (`SquaredMahalanobis`).
    pub squared: bool,
    /// `DistanceHypothesiser.include_all`: every pair is gated.
    pub include_all: bool,
    /// `PHDUpdater.normalisation`.
    pub normalise: bool,
    /// A pair whose component has `P_D = 0` makes no term (the context-aware updater);
    /// otherwise it makes a zero-weight one, as the stock updater does.
    pub skip_undetectable: bool,
    /// Time given to every updated component (the scan's).
    pub time: i64,
    /// The Kalman updater's `force_symmetric_covariance`: posteriors `(P + Pᵀ) / 2`.
    pub force_symmetric: bool,
}

/// Per-component measurement prediction.
///
/// Round-off makes covariances slightly non-symmetric, and the standard-form update can grow
/// that asymmetry; the stock semantics are kept for such matrices too: the gate and the gain
/// use the plain inverse of `S` (NumPy's `inv`), the likelihood reads `S`'s lower triangle
/// (SciPy's `eigh`).
struct Linearised {
    predicted: Vec<f64>,         // N×m
    cross: Vec<f64>,             // N×D×m, P Hᵀ
    innovation: Vec<f64>,        // N×m×m, S = H P Hᵀ + R
    inverse: Vec<f64>,           // N×m×m, S⁻¹
    symmetric_inverse: Vec<f64>, // N×m×m, the inverse of S's lower triangle, mirrored
    log_det: Vec<f64>,           // N, of S's lower triangle; NaN: not positive definite
}

/// The measurement prediction of every component: what the gate and the likelihoods need.
fn linearise(mixture: &Mixture, model: &MeasurementModel) -> Result<Linearised> {
    let (n, d, m) = (mixture.len(), mixture.ndim, model.ndim_meas());
    let zeros = |sizes: &[usize]| memory::filled("means", memory::product("means", sizes)?, 0.0);
    let mut out = Linearised {
        predicted: zeros(&[n, m])?,
        cross: zeros(&[n, d, m])?,
        innovation: zeros(&[n, m, m])?,
        inverse: zeros(&[n, m, m])?,
        symmetric_inverse: zeros(&[n, m, m])?,
        log_det: zeros(&[n])?,
    };
    let noise = model.noise();
    let mut h = zeros(&[m, d])?;
    let mut scratch = zeros(&[2, m, m.max(1)])?;
    for i in 0..n {
        let x = mixture.mean(i);
        let p = mixture.covar(i);
        model.linearise(x, &mut out.predicted[i * m..(i + 1) * m], &mut h);
        let cross = &mut out.cross[i * d * m..(i + 1) * d * m];
        matmul_bt(p, &h, d, d, m, cross); // P Hᵀ
        let innovation = &mut out.innovation[i * m * m..(i + 1) * m * m];
        matmul(&h, cross, m, d, m, innovation); // H (P Hᵀ)
        for k in 0..m * m {
            innovation[k] += noise[k];
        }
        let symmetric_inverse = &mut out.symmetric_inverse[i * m * m..(i + 1) * m * m];
        out.log_det[i] = spd_inverse_into(innovation, m, symmetric_inverse, &mut scratch).unwrap_or(f64::NAN);
        let inverse = &mut out.inverse[i * m * m..(i + 1) * m * m];
        let symmetric = (0..m).all(|r| (0..r).all(|c| innovation[r * m + c] == innovation[c * m + r]));
        if symmetric && !out.log_det[i].is_nan() {
            inverse.copy_from_slice(symmetric_inverse);
        } else {
            general_inverse_into(innovation, m, inverse, &mut scratch);
        }
    }
    Ok(out)
}

/// Kalman gains `K = P Hᵀ S⁻¹` (N×D×m) and posterior covariances `P − K S Kᵀ` (N×D×D,
/// symmetrised on request), computed only for the components in `needed` (those some
/// detection updates): most components of a scan are gated by none.
fn gains(
    mixture: &Mixture,
    lin: &Linearised,
    m: usize,
    needed: &[bool],
    force_symmetric: bool,
) -> Result<(Vec<f64>, Vec<f64>)> {
    let (n, d) = (needed.len(), mixture.ndim);
    let zeros = |sizes: &[usize]| memory::filled("means", memory::product("means", sizes)?, 0.0);
    let mut gain = zeros(&[n, d, m])?;
    let mut posterior = zeros(&[n, d, d])?;
    let mut gain_s = zeros(&[d, m])?;
    let mut correction = zeros(&[d, d])?;
    for i in (0..n).filter(|&i| needed[i]) {
        // (`needed` is empty when the scan has no detections)
        let p = mixture.covar(i);
        let k = &mut gain[i * d * m..(i + 1) * d * m];
        matmul(
            &lin.cross[i * d * m..(i + 1) * d * m],
            &lin.inverse[i * m * m..(i + 1) * m * m],
            d,
            m,
            m,
            k,
        );
        matmul(k, &lin.innovation[i * m * m..(i + 1) * m * m], d, m, m, &mut gain_s); // K S
        symmetric_product(&gain_s, k, d, m, &mut correction); // (K S) Kᵀ
        let posterior = &mut posterior[i * d * d..(i + 1) * d * d];
        for (k, value) in posterior.iter_mut().enumerate() {
            *value = p[k] - correction[k];
        }
        if force_symmetric {
            for r in 0..d {
                for c in 0..r {
                    let mean = (posterior[r * d + c] + posterior[c * d + r]) / 2.0;
                    posterior[r * d + c] = mean;
                    posterior[c * d + r] = mean;
                }
            }
        }
    }
    Ok((gain, posterior))
}

fn check_inputs(
    mixture: &Mixture,
    model: &MeasurementModel,
    detections: &[f64],
    prob_detection: &[f64],
    clutter: &[f64],
    params: &UpdateParams,
) -> Result<usize> {
    model.check_dim(mixture.ndim)?;
    let m = model.ndim_meas();
    if !detections.len().is_multiple_of(m) {
        return Err(ModelError::shape("detections", format!("expected rows of {m} values")));
    }
    let count = detections.len() / m;
    if let Some(row) = (0..count).find(|&j| !detections[j * m..(j + 1) * m].iter().all(|v| v.is_finite())) {
        return Err(ModelError::non_finite(
            "detections",
            row,
            "measurement vectors must be finite",
        ));
    }
    if prob_detection.len() != mixture.len() {
        return Err(ModelError::shape(
            "prob_detection",
            format!(
                "expected one value per component ({}), got {}",
                mixture.len(),
                prob_detection.len()
            ),
        ));
    }
    if let Some(row) = prob_detection.iter().position(|p| !(0.0..=1.0).contains(p)) {
        return Err(ModelError::invalid(
            "prob_detection",
            format!("row {row} is not a probability in [0, 1]: {}", prob_detection[row]),
        ));
    }
    if clutter.len() != count {
        return Err(ModelError::shape(
            "clutter",
            format!("expected one value per detection ({count}), got {}", clutter.len()),
        ));
    }
    if let Some(row) = clutter.iter().position(|c| !c.is_finite() || *c < 0.0) {
        return Err(ModelError::invalid(
            "clutter",
            format!("row {row} must be finite and >= 0, got {}", clutter[row]),
        ));
    }
    if !(params.prob_survival.is_finite() && (0.0..=1.0).contains(&params.prob_survival)) {
        return Err(ModelError::invalid(
            "prob_survival",
            format!("must be a probability in [0, 1], got {}", params.prob_survival),
        ));
    }
    if params.gate.is_nan() {
        return Err(ModelError::invalid("missed_distance", "must not be NaN"));
    }
    Ok(count)
}

impl Mixture {
    /// Replaces the (predicted) mixture by its update with the detections of one scan:
    /// `detections` (M×m, bearings as floats), `prob_detection` per component, `clutter`
    /// (λ) per detection. Returns each detection's posterior clutter probability
    /// λ(z) / (λ(z) + Σᵢ p_S P_D,ᵢ wᵢ N(z; ẑᵢ, Sᵢ)) over the components that gate it — 1 for
    /// a detection that no component explains (what it adds to the map of
    /// a clutter learner, in expectation).
    #[allow(clippy::neg_cmp_op_on_partial_ord)] // `!(a > b)` on purpose: NaN fails the test
    pub fn update(
        &mut self,
        model: &MeasurementModel,
        detections: &[f64],
        prob_detection: &[f64],
        clutter: &[f64],
        params: &UpdateParams,
    ) -> Result<Vec<f64>> {
        let count = check_inputs(self, model, detections, prob_detection, clutter, params)?;
        let (n, d, m) = (self.len(), self.ndim, model.ndim_meas());
        // (no detections: only the missed-detection terms, nothing to linearise)
        let lin = if count > 0 {
            linearise(self, model)?
        } else {
            linearise(&Mixture::new(d), model)?
        };

        // The gate, pair by pair: d(ẑ, z) with ẑ − z wrapped, as the stock measure takes it.
        let mut gated: Vec<Vec<usize>> = memory::filled("detections", count, Vec::new())?;
        let mut delta = memory::filled("detections", m, 0.0)?;
        for i in 0..if count > 0 { n } else { 0 } {
            let predicted = &lin.predicted[i * m..(i + 1) * m];
            let inverse = &lin.inverse[i * m * m..(i + 1) * m * m];
            for (j, members) in gated.iter_mut().enumerate() {
                if !params.include_all {
                    model.difference(predicted, &detections[j * m..(j + 1) * m], &mut delta);
                    let squared = quadratic_form(inverse, &delta, m);
                    let distance = if params.squared { squared } else { squared.sqrt() };
                    if !(distance < params.gate) {
                        continue;
                    }
                }
                // (room for one more, fallibly: n × detections pairs can gate)
                members
                    .try_reserve(1)
                    .map_err(|_| ModelError::memory("detections", (members.len() as u128 + 1) * 8))?;
                members.push(i);
            }
        }

        let mut needed = memory::filled("means", if count > 0 { n } else { 0 }, false)?;
        for &i in gated.iter().flatten() {
            needed[i] |= !(params.skip_undetectable && prob_detection[i] == 0.0);
        }
        let (gain, posterior) = gains(self, &lin, m, &needed, params.force_symmetric)?;

        // the posterior's components: at most one per gated pair and one per component
        let most = gated.iter().map(Vec::len).sum::<usize>() + n;
        let mut out = Mixture {
            ndim: d,
            next_tag: self.next_tag,
            means: memory::with_room("detections", memory::product("detections", &[most, d])?)?,
            covars: memory::with_room("detections", memory::product("detections", &[most, d, d])?)?,
            weights: memory::with_room("detections", most)?,
            tags: memory::with_room("detections", most)?,
            times: memory::with_room("detections", most)?,
        };
        let log_norm = m as f64 * (2.0 * std::f64::consts::PI).ln();
        let mut raw = memory::filled("detections", m, 0.0)?;
        let mut innovation = memory::filled("detections", m, 0.0)?;
        let mut correction = memory::filled("means", d, 0.0)?;
        let mut clutter_probability = memory::filled("detections", count, 1.0)?;
        for (j, members) in gated.iter().enumerate() {
            let z = &detections[j * m..(j + 1) * m];
            let first = out.len();
            let mut weight_sum = 0.0;
            for &i in members {
                let pd = prob_detection[i];
                if params.skip_undetectable && pd == 0.0 {
                    continue;
                }
                if lin.log_det[i].is_nan() {
                    return Err(ModelError::not_positive_definite(
                        "measurement_model",
                        format!("the innovation covariance of component {i} is not positive definite, so detection {j}'s likelihood is undefined (its covariance has lost positive definiteness)"),
                    ));
                }
                let predicted = &lin.predicted[i * m..(i + 1) * m];
                let inverse = &lin.symmetric_inverse[i * m * m..(i + 1) * m * m];
                // N(z; ẑ, S) on the plain values (the stock pdf sees floats: no wrap)
                for k in 0..m {
                    raw[k] = z[k] - predicted[k];
                }
                let likelihood = (-0.5 * (log_norm + lin.log_det[i] + quadratic_form(inverse, &raw, m))).exp();
                // p_S applies to detected births too: the stock hypothesiser hands their
                // detection hypotheses predictions with a fresh tag, not the birth tag
                let weight = pd * self.weights[i] * likelihood * params.prob_survival;
                weight_sum += weight;
                // Kalman posterior with the wrapped innovation z − ẑ
                model.difference(z, predicted, &mut innovation);
                matvec(&gain[i * d * m..(i + 1) * d * m], &innovation, d, m, &mut correction);
                let x = self.mean(i);
                out.means.extend(x.iter().zip(&correction).map(|(a, b)| a + b));
                out.covars.extend_from_slice(&posterior[i * d * d..(i + 1) * d * d]);
                out.weights.push(weight);
                let tag = if self.tags[i] == BIRTH {
                    out.fresh_tag()
                } else {
                    self.tags[i]
                };
                out.tags.push(tag);
                out.times.push(params.time);
            }
            if weight_sum > 0.0 {
                clutter_probability[j] = clutter[j] / (weight_sum + clutter[j]);
            }
            if params.normalise {
                let normaliser = weight_sum + clutter[j];
                for weight in &mut out.weights[first..] {
                    *weight /= normaliser;
                }
            }
        }
        for (i, &pd) in prob_detection.iter().enumerate().take(n) {
            if self.tags[i] == BIRTH {
                continue;
            }
            out.means.extend_from_slice(self.mean(i));
            out.covars.extend_from_slice(self.covar(i));
            out.weights
                .push(self.weights[i] * (1.0 - pd) * 1.0 * params.prob_survival);
            out.tags.push(self.tags[i]);
            out.times.push(params.time);
        }
        // As stock: no zero weights (the reducer would divide by them).
        for weight in &mut out.weights {
            if *weight == 0.0 {
                *weight = f64::EPSILON;
            }
        }
        *self = out;
        Ok(clutter_probability)
    }
}
