//! An online detection-probability estimate: P_D learned per range band from whether the
//! tracks a sensor should have seen at a scan were detected.
//!
//! Band b = [e_b, e_(b+1)) of range from the sensor holds a Beta posterior over its P_D p_b.
//! The prior Beta(p₀ s₀, (1 − p₀) s₀) has mean p₀ and is worth s₀ trials. A trial is one
//! track at one scan: a hit d ∈ {0, 1} (a detection was associated with it) and a weight
//! w ∈ [0, 1], the product of the sensor's *other* P_D factors at the track (0 in a blind
//! sector or behind land: a miss there says nothing about p_b). Discounting every earlier
//! trial by the forgetting factor γ ∈ (0, 1] per update (a power prior), the estimate after
//! update k is
//!
//! ```text
//! p_b = (p₀ s₀ + H_b) / (s₀ + T_b),   H_b = Σ_{j: w_j > 0} γ^(k−j) d_j,   T_b = Σ_j γ^(k−j) w_j,
//! ```
//!
//! clamped to [0, 1]. A trial of weight 0 is no evidence, hit or miss: it changes neither
//! H nor T. With weights 0 or 1 (the usual case: sectors, land and line of sight are
//! 0 or 1) this is the Beta posterior mean exactly; with fractional weights it is the ratio
//! estimator Σd / Σw of p_b shrunk to the prior, which can exceed 1 before clamping.
//! Where p₀ s₀ + H_b would overflow or leave the normal doubles (s₀ or a restored state
//! near f64's limits), p_b is formed as p₀ · s₀/(s₀ + T_b) + H_b/(s₀ + T_b): finite for
//! every accepted configuration.
//! Outside the bands the factor is a fixed `outside` value (the sensor's range limits are
//! specification, not something to learn from tracks). Few bands: an update multiplies
//! every band by γ, O(bands + trials).

use crate::error::{ModelError, Result};
use crate::memory;
use crate::pose::Pose;
use crate::range_bands::RangeBands;
use std::sync::{Arc, RwLock, RwLockReadGuard};

#[derive(Debug, Clone, PartialEq)]
pub struct DetectionEstimate {
    edges: Vec<f64>,
    prior_probability: f64,
    prior_trials: f64,
    forgetting: f64,
    outside: f64,
    /// H_b: the discounted hits per band.
    hits: Vec<f64>,
    /// T_b: the discounted trial weights per band.
    trials: Vec<f64>,
}

/// An estimate shared between the detection models that read it and the learner that
/// updates it between scans.
pub type SharedEstimate = Arc<RwLock<DetectionEstimate>>;

/// Reads a shared estimate ([`DetectionEstimate::update`] checks its inputs before changing
/// anything, so a poisoned lock holds a whole state).
pub fn read_estimate(estimate: &SharedEstimate) -> RwLockReadGuard<'_, DetectionEstimate> {
    estimate.read().unwrap_or_else(|poisoned| poisoned.into_inner())
}

fn probability(argument: &'static str, value: f64, open: bool) -> Result<()> {
    let inside = if open {
        value > 0.0 && value < 1.0
    } else {
        (0.0..=1.0).contains(&value)
    };
    if !inside {
        let interval = if open { "(0, 1)" } else { "[0, 1]" };
        return Err(ModelError::invalid(
            argument,
            format!("must lie in {interval}, got {value}"),
        ));
    }
    Ok(())
}

impl DetectionEstimate {
    /// A fresh estimate (the prior in every band). `edges`: at least 2, strictly increasing,
    /// finite, ≥ 0 (metres of range).
    pub fn new(
        edges: Vec<f64>,
        prior_probability: f64,
        prior_trials: f64,
        forgetting: f64,
        outside: f64,
    ) -> Result<Self> {
        if edges.len() < 2 {
            return Err(ModelError::invalid(
                "edges",
                format!("needs at least 2 edges (one band), got {}", edges.len()),
            ));
        }
        if let Some(e) = edges.iter().find(|e| !(e.is_finite() && **e >= 0.0)) {
            return Err(ModelError::invalid(
                "edges",
                format!("edges must be finite and >= 0, got {e}"),
            ));
        }
        if edges.windows(2).any(|w| w[0] >= w[1]) {
            return Err(ModelError::invalid("edges", "edges must be strictly increasing"));
        }
        probability("prior_probability", prior_probability, true)?;
        if !(prior_trials.is_finite() && prior_trials > 0.0) {
            return Err(ModelError::invalid(
                "prior_trials",
                format!("must be finite and > 0, got {prior_trials}"),
            ));
        }
        if !(forgetting > 0.0 && forgetting <= 1.0) {
            return Err(ModelError::invalid(
                "forgetting",
                format!("must be in (0, 1], got {forgetting}"),
            ));
        }
        probability("outside", outside, false)?;
        let bands = edges.len() - 1;
        let (hits, trials) = (
            memory::filled("edges", bands, 0.0)?,
            memory::filled("edges", bands, 0.0)?,
        );
        Ok(DetectionEstimate {
            edges,
            prior_probability,
            prior_trials,
            forgetting,
            outside,
            hits,
            trials,
        })
    }

    /// The estimate with a saved state (see [`state`](Self::state)).
    pub fn with_state(mut self, hits: Vec<f64>, trials: Vec<f64>) -> Result<Self> {
        for (argument, values) in [("hits", &hits), ("trials", &trials)] {
            if values.len() != self.hits.len() {
                return Err(ModelError::shape(
                    argument,
                    format!(
                        "must have one entry per band ({}), got {}",
                        self.hits.len(),
                        values.len()
                    ),
                ));
            }
            if let Some(v) = values.iter().find(|v| !(v.is_finite() && **v >= 0.0)) {
                return Err(ModelError::invalid(
                    argument,
                    format!("must be finite and >= 0, got {v}"),
                ));
            }
        }
        self.hits = hits;
        self.trials = trials;
        Ok(self)
    }

    /// (H, T): everything an update changes.
    pub fn state(&self) -> (&[f64], &[f64]) {
        (&self.hits, &self.trials)
    }

    /// The band holding range `r`, if any.
    fn band(&self, r: f64) -> Option<usize> {
        let last = self.edges.len() - 1;
        if !(r >= self.edges[0] && r < self.edges[last]) {
            return None;
        }
        Some(self.edges.partition_point(|e| *e <= r) - 1)
    }

    /// The posterior mean P_D of band `b`, in [0, 1].
    fn probability(&self, b: usize) -> f64 {
        let (p0, s0, h, t) = (self.prior_probability, self.prior_trials, self.hits[b], self.trials[b]);
        let direct = (p0 * s0 + h) / (s0 + t);
        if direct.is_finite() && (direct == 0.0 || direct >= f64::MIN_POSITIVE) {
            return direct.clamp(0.0, 1.0);
        }
        // (s0 + t > 0: s0 > 0, t >= 0; at f64's limit it is MAX or inf, never NaN)
        let total = s0 + t;
        let share = if total.is_infinite() {
            if t.is_infinite() {
                0.0
            } else {
                1.0
            }
        } else {
            s0 / total
        };
        let rate = if h.is_infinite() {
            1.0
        } else if total.is_infinite() {
            0.0
        } else {
            h / total
        };
        (p0 * share + rate).clamp(0.0, 1.0)
    }

    /// The posterior mean P_D of every band.
    pub fn probabilities(&self) -> Result<Vec<f64>> {
        memory::collected("edges", (0..self.hits.len()).map(|b| self.probability(b)))
    }

    /// The estimate as it stands, as range bands: `outside` below the first edge and from
    /// the last one on; each edge belongs to the band above it.
    pub fn bands(&self) -> RangeBands {
        // (as long as the edges the estimate already holds: its size was allocated once, at
        // construction; a failure here is the process's memory running out, not a user's size)
        let mut values = Vec::with_capacity(self.edges.len() + 1);
        values.push(self.outside);
        values.extend((0..self.hits.len()).map(|b| self.probability(b)));
        values.push(self.outside);
        // (the edges were checked at construction, every value is in [0, 1]: valid bands)
        RangeBands::new(self.edges.clone(), values, vec![true; self.edges.len()])
            .expect("checked edges and probabilities make valid bands")
    }

    /// One scan's trials: tracks at world `positions` (x, y pairs, row-major), whether each
    /// was `detected` (0 or 1), and each one's `weights` (the other P_D factors, in [0, 1]).
    /// Every input is checked before anything changes. Forgets one scan, even with no trials.
    pub fn update(&mut self, pose: &Pose, positions: &[f64], detected: &[f64], weights: &[f64]) -> Result<()> {
        let n = positions.len() / 2;
        if !positions.len().is_multiple_of(2) {
            return Err(ModelError::shape("positions", "must be (M, 2)"));
        }
        for (argument, values) in [("detected", detected), ("weights", weights)] {
            if values.len() != n {
                return Err(ModelError::shape(
                    argument,
                    format!("must have one entry per position ({n}), got {}", values.len()),
                ));
            }
        }
        if let Some(i) = (0..n).find(|&i| !(positions[2 * i].is_finite() && positions[2 * i + 1].is_finite())) {
            return Err(ModelError::non_finite("positions", i, "position is NaN or infinite"));
        }
        if let Some(v) = detected.iter().find(|v| **v != 0.0 && **v != 1.0) {
            return Err(ModelError::invalid("detected", format!("must be 0 or 1, got {v}")));
        }
        if let Some(v) = weights.iter().find(|v| !(0.0..=1.0).contains(*v)) {
            return Err(ModelError::invalid("weights", format!("must lie in [0, 1], got {v}")));
        }
        for (h, t) in self.hits.iter_mut().zip(self.trials.iter_mut()) {
            *h *= self.forgetting;
            *t *= self.forgetting;
        }
        for i in 0..n {
            let range = (positions[2 * i] - pose.x).hypot(positions[2 * i + 1] - pose.y);
            // a trial of weight 0 is no evidence, hit or miss
            if let (Some(b), true) = (self.band(range), weights[i] > 0.0) {
                self.hits[b] += detected[i];
                self.trials[b] += weights[i];
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn origin() -> Pose {
        Pose::new(0.0, 0.0, 0.0).unwrap()
    }

    #[test]
    fn fresh_estimate_is_the_prior_inside_and_outside_beyond() {
        let e = DetectionEstimate::new(vec![50.0, 500.0, 1600.0], 0.5, 4.0, 0.99, 0.0).unwrap();
        assert_eq!(e.probabilities().unwrap(), vec![0.5, 0.5]);
        let bands = e.bands();
        assert_eq!(bands.at(49.9), 0.0);
        assert_eq!(bands.at(50.0), 0.5);
        assert_eq!(bands.at(1600.0), 0.0);
    }

    #[test]
    fn beta_posterior_mean_without_forgetting() {
        let mut e = DetectionEstimate::new(vec![0.0, 100.0, 200.0], 0.5, 2.0, 1.0, 0.0).unwrap();
        // band 0: 3 hits of 4; band 1: 0 of 2; one trial out of the bands; one with weight 0
        let positions = [
            10.0, 0.0, 20.0, 0.0, 0.0, 30.0, 40.0, 0.0, 150.0, 0.0, 0.0, -150.0, 500.0, 0.0, 60.0, 0.0,
        ];
        let detected = [1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0];
        let weights = [1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 0.0];
        e.update(&origin(), &positions, &detected, &weights).unwrap();
        let p = e.probabilities().unwrap();
        assert_eq!(p[0], (1.0 + 3.0) / (2.0 + 4.0));
        assert_eq!(p[1], 1.0 / (2.0 + 2.0));
    }

    #[test]
    fn forgetting_discounts_earlier_scans() {
        let mut e = DetectionEstimate::new(vec![0.0, 100.0], 0.5, 1.0, 0.5, 0.0).unwrap();
        e.update(&origin(), &[10.0, 0.0], &[1.0], &[1.0]).unwrap();
        e.update(&origin(), &[10.0, 0.0], &[0.0], &[1.0]).unwrap();
        let (h, t) = e.state();
        assert_eq!((h[0], t[0]), (0.5, 1.5));
        assert_eq!(e.probabilities().unwrap()[0], (0.5 + 0.5) / (1.0 + 1.5));
    }

    #[test]
    fn bad_inputs_change_nothing() {
        let mut e = DetectionEstimate::new(vec![0.0, 100.0], 0.5, 1.0, 0.9, 0.0).unwrap();
        let before = e.clone();
        assert!(e.update(&origin(), &[10.0, 0.0], &[0.5], &[1.0]).is_err());
        assert!(e.update(&origin(), &[10.0, 0.0], &[1.0], &[1.5]).is_err());
        assert!(e.update(&origin(), &[f64::NAN, 0.0], &[1.0], &[1.0]).is_err());
        assert!(e.update(&origin(), &[10.0, 0.0, 1.0], &[1.0], &[1.0]).is_err());
        assert_eq!(e, before);
    }

    #[test]
    fn bad_configuration_names_the_argument() {
        let err = |r: Result<DetectionEstimate>| r.unwrap_err().to_string();
        assert!(err(DetectionEstimate::new(vec![0.0], 0.5, 1.0, 0.9, 0.0)).starts_with("edges"));
        assert!(err(DetectionEstimate::new(vec![0.0, 0.0], 0.5, 1.0, 0.9, 0.0)).starts_with("edges"));
        assert!(err(DetectionEstimate::new(vec![0.0, 1.0], 1.0, 1.0, 0.9, 0.0)).starts_with("prior_probability"));
        assert!(err(DetectionEstimate::new(vec![0.0, 1.0], 0.5, 0.0, 0.9, 0.0)).starts_with("prior_trials"));
        assert!(err(DetectionEstimate::new(vec![0.0, 1.0], 0.5, 1.0, 0.0, 0.0)).starts_with("forgetting"));
        assert!(err(DetectionEstimate::new(vec![0.0, 1.0], 0.5, 1.0, 0.9, 1.5)).starts_with("outside"));
    }

    #[test]
    fn a_trial_of_weight_zero_is_no_evidence_hit_or_miss() {
        let mut e = DetectionEstimate::new(vec![0.0, 10.0], 0.5, 5.0, 0.99, 0.0).unwrap();
        for _ in 0..10 {
            e.update(&origin(), &[5.0, 0.0], &[1.0], &[0.0]).unwrap();
        }
        assert_eq!(e.probabilities().unwrap(), [0.5]);
        assert_eq!(e.state(), (&[0.0][..], &[0.0][..]));
        e.update(&origin(), &[5.0, 0.0, 6.0, 0.0], &[1.0, 0.0], &[0.5, 0.0])
            .unwrap();
        assert_eq!(e.state(), (&[1.0][..], &[0.5][..]));
    }

    mod finite {
        //! P_D in [0, 1] and a finite state over the whole accepted configuration and any
        //! updates, read through a detection model on every SIMD backend.
        use super::*;
        use crate::batch::PositionMapping;
        use crate::detection::{DetectionFactor, DetectionModel};
        use crate::simd::{on_backend, Backend};
        use proptest::prelude::*;
        use std::sync::{Arc, RwLock};

        fn anywhere(low: f64, high: f64) -> impl Strategy<Value = f64> {
            let (a, b) = (low.log10().max(-323.0), high.log10().min(308.2));
            prop_oneof![
                Just(low),
                Just(high),
                (a..b).prop_map(move |e| 10f64.powf(e).clamp(low, high))
            ]
        }

        fn weight() -> impl Strategy<Value = f64> {
            prop_oneof![Just(0.0), Just(1.0), Just(f64::from_bits(1)), (0.0..=1.0f64)]
        }

        proptest! {
            #[test]
            fn every_probability_stays_a_probability(
                prior_probability in prop_oneof![Just(f64::from_bits(1)), Just(1.0 - f64::EPSILON / 2.0), anywhere(f64::from_bits(1), 0.5), (0.0..1.0f64).prop_filter("open", |p| *p > 0.0)],
                prior_trials in anywhere(f64::from_bits(1), f64::MAX),
                forgetting in prop_oneof![Just(1.0), Just(f64::from_bits(1)), anywhere(f64::from_bits(1), 1.0), (0.5..1.0f64)],
                magnitude in -300.0..300.0f64,
                scans in prop::collection::vec(prop::collection::vec((0.0..1.5f64, any::<bool>(), weight()), 0..6), 1..40),
            ) {
                let size = 10f64.powf(magnitude);
                let edges = vec![0.0, size, 2.0 * size];
                let estimate = match DetectionEstimate::new(edges, prior_probability, prior_trials, forgetting, 0.0) {
                    Ok(e) => e,
                    Err(err) => { prop_assert_eq!(err.argument(), "edges"); return Ok(()); } // (edges overflowing f64)
                };
                let shared = Arc::new(RwLock::new(estimate));
                let model = DetectionModel::new(vec![DetectionFactor::Estimate(shared.clone())]).unwrap();
                let pose = Pose::new(0.0, 0.0, 0.0).unwrap();
                let mapping = PositionMapping::new(0, 1).unwrap();
                for trials in &scans {
                    let positions: Vec<f64> = trials.iter().flat_map(|(r, _, _)| [r * 2.0 * size, 0.0]).collect();
                    let detected: Vec<f64> = trials.iter().map(|t| if t.1 { 1.0 } else { 0.0 }).collect();
                    let weights: Vec<f64> = trials.iter().map(|t| t.2).collect();
                    shared.write().unwrap().update(&pose, &positions, &detected, &weights).unwrap();
                    let estimate = shared.read().unwrap().clone();
                    for p in estimate.probabilities().unwrap() {
                        prop_assert!((0.0..=1.0).contains(&p), "P_D {p:e}");
                    }
                    let (h, t) = estimate.state();
                    prop_assert!(h.iter().chain(t).all(|v| v.is_finite() && *v >= 0.0), "{h:?} {t:?}");
                    // the model reads the same values on every backend
                    let states = [0.5 * size, 0.0, 1.5 * size, 0.0, 0.0, 0.0, 1e300, 0.0, 0.25 * size, 0.0];
                    let mut seen = Vec::new();
                    for backend in [Backend::Portable, Backend::Avx2].into_iter().filter(|b| b.available()) {
                        let mut out = [0.0; 5];
                        on_backend(backend, || model.at_pose(&pose).at_states(&states, 2, mapping, &mut out)).unwrap();
                        prop_assert!(out.iter().all(|p| (0.0..=1.0).contains(p)), "{out:?}");
                        seen.push(out.map(f64::to_bits));
                    }
                    prop_assert!(seen.windows(2).all(|w| w[0] == w[1]));
                }
            }
        }
    }
}
