//! Range-rate blind zones: a pulse-Doppler or MTI radar cancels echoes whose radial speed
//! relative to it is near zero (the clutter notch) — and, for a pulsed MTI, near each
//! multiple of its blind speed v_b = λ·PRF/2.
//!
//! A target at offset Δp from the sensor, moving at Δv relative to it, closes or opens at
//! ṙ = Δp·Δv / |Δp|. The factor takes `inside` where |ṙ| ≤ w (the notch's half-width),
//! decided without a square root as (Δp·Δv)² ≤ w² |Δp|², and, with blind speeds, where
//! ||ṙ| − k v_b| ≤ w for k = 1…K, decided as (k v_b − w)² |Δp|² ≤ (Δp·Δv)² ≤
//! (k v_b + w)² |Δp|² (k v_b > w, as v_b > 2w); `outside` elsewhere. A target at the sensor (Δp = 0) has
//! no radial speed: inside the notch.
//!
//! For a target whose velocity is uncertain — normal given its position, Δv ~ N(μ, C) — ṙ
//! is normal with mean Δp·μ/|Δp| and variance ΔpᵀCΔp/|Δp|², and the factor's expectation
//! is exact: outside + (inside − outside)·P(ṙ in a notch), the probability summed over the
//! notch and the blind speeds' intervals (disjoint: v_b > 2w).

use crate::error::{ModelError, Result};
use crate::range_bands::select;
use crate::simd::Lanes;

#[derive(Debug, Clone, PartialEq)]
pub struct RangeRateNotch {
    width: f64,
    blind_speed: Option<f64>,
    multiples: u32,
    inside: f64,
    outside: f64,
    /// (k v_b − w)² and (k v_b + w)² for k = 1…multiples: the blind intervals of ṙ².
    blind: Vec<[f64; 2]>,
}

/// The most blind-speed multiples a notch tests (beyond them a radar's PRF staggering or
/// the targets' speeds make them moot).
pub const MAX_MULTIPLES: u32 = 64;

impl RangeRateNotch {
    /// A notch of half-width `width` (m/s) around zero radial speed and, with a
    /// `blind_speed` v_b (m/s), around its first `multiples` multiples.
    pub fn new(width: f64, blind_speed: Option<f64>, multiples: u32, inside: f64, outside: f64) -> Result<Self> {
        if !(width.is_finite() && width >= 0.0) {
            return Err(ModelError::invalid(
                "width",
                format!("must be a finite speed ≥ 0 m/s, got {width}"),
            ));
        }
        if let Some(v) = blind_speed {
            if !(v.is_finite() && v > 2.0 * width) {
                return Err(ModelError::invalid(
                    "blind_speed",
                    format!(
                        "must be a finite speed above twice the notch width ({}) m/s, got {v}",
                        2.0 * width
                    ),
                ));
            }
        }
        if !(1..=MAX_MULTIPLES).contains(&multiples) {
            return Err(ModelError::invalid(
                "multiples",
                format!("must be in 1..={MAX_MULTIPLES}, got {multiples}"),
            ));
        }
        for (name, v) in [("inside", inside), ("outside", outside)] {
            if !v.is_finite() {
                return Err(ModelError::invalid(name, format!("must be finite, got {v}")));
            }
        }
        let blind = blind_speed
            .map(|v| {
                (1..=multiples)
                    .map(|k| {
                        let centre = f64::from(k) * v;
                        [(centre - width) * (centre - width), (centre + width) * (centre + width)]
                    })
                    .collect()
            })
            .unwrap_or_default();
        Ok(RangeRateNotch {
            width,
            blind_speed,
            multiples,
            inside,
            outside,
            blind,
        })
    }

    pub fn values(&self) -> [f64; 2] {
        [self.inside, self.outside]
    }

    /// The value for Δp·Δv = `dot` at squared range `r2`.
    #[inline(always)]
    pub fn at(&self, dot: f64, r2: f64) -> f64 {
        let squared = dot * dot;
        let mut notched = squared <= self.width * self.width * r2;
        for &[low, high] in &self.blind {
            notched |= (low * r2 <= squared) & (squared <= high * r2);
        }
        select(notched, self.inside, self.outside)
    }

    /// The expectation of [`Self::at`] at Δp·Δv = `dot` and squared range `r2` when the
    /// radial speed ṙ = `dot`/r is normal with variance `speed_var`: [`Self::at`] itself
    /// where that variance is 0 (or not a number above 0), or the target is at the sensor
    /// or its offsets are not finite. An infinite variance puts no mass in any interval.
    pub fn expected_at(&self, dot: f64, r2: f64, speed_var: f64) -> f64 {
        if !(speed_var > 0.0 && r2 > 0.0 && r2.is_finite() && dot.is_finite()) {
            return self.at(dot, r2);
        }
        // In m/s, so that no bound overflows: the notch is |ṙ| ≤ w, a blind speed |ṙ ∓ k v_b| ≤ w.
        let (mean, s, w) = (dot / r2.sqrt(), speed_var.sqrt(), self.width);
        let mut inside = normal_mass((-w - mean) / s, (w - mean) / s);
        if let Some(v) = self.blind_speed {
            for k in 1..=self.multiples {
                let centre = f64::from(k) * v;
                inside += normal_mass((centre - w - mean) / s, (centre + w - mean) / s)
                    + normal_mass((-centre - w - mean) / s, (-centre + w - mean) / s);
            }
        }
        let inside = inside.clamp(0.0, 1.0);
        self.outside + (self.inside - self.outside) * inside
    }

    /// [`Self::at`] for four targets, the same bits.
    #[inline(always)]
    pub(crate) fn lanes_at<L: Lanes>(&self, dot: L, r2: L) -> L {
        let w = L::splat(self.width);
        let squared = dot * dot;
        let mut notched = squared.le(w * w * r2);
        for &[low, high] in &self.blind {
            notched = L::or(
                notched,
                L::and((L::splat(low) * r2).le(squared), squared.le(L::splat(high) * r2)),
            );
        }
        L::select(notched, L::splat(self.inside), L::splat(self.outside))
    }
}

/// P(a ≤ X ≤ b) for X standard normal, from the tail on the interval's side, so that a
/// mass far out keeps its digits: Φ(b) − Φ(a) = (erfc(−b/√2) − erfc(−a/√2))/2 below 0,
/// (erfc(a/√2) − erfc(b/√2))/2 above it.
fn normal_mass(a: f64, b: f64) -> f64 {
    use std::f64::consts::FRAC_1_SQRT_2;
    if a >= 0.0 {
        0.5 * (libm::erfc(a * FRAC_1_SQRT_2) - libm::erfc(b * FRAC_1_SQRT_2))
    } else if b <= 0.0 {
        0.5 * (libm::erfc(-b * FRAC_1_SQRT_2) - libm::erfc(-a * FRAC_1_SQRT_2))
    } else {
        1.0 - 0.5 * (libm::erfc(-a * FRAC_1_SQRT_2) + libm::erfc(b * FRAC_1_SQRT_2))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The value for a target 1 km out closing at `speed` m/s along the line of sight.
    fn at_speed(notch: &RangeRateNotch, speed: f64) -> f64 {
        notch.at(1000.0 * speed, 1000.0 * 1000.0)
    }

    #[test]
    fn the_notch_and_the_blind_speeds() {
        let mti = RangeRateNotch::new(2.0, Some(30.0), 3, 0.0, 1.0).unwrap();
        for (speed, want) in [
            (0.0, 0.0),
            (1.9, 0.0),
            (-1.9, 0.0),
            (2.1, 1.0),
            (15.0, 1.0),
            (29.0, 0.0),
            (-31.5, 0.0),
            (60.0, 0.0),
            (90.0, 0.0),
            (120.0, 1.0), // beyond the three multiples tested
            (45.0, 1.0),
        ] {
            assert_eq!(at_speed(&mti, speed), want, "{speed} m/s");
        }
        assert_eq!(mti.at(0.0, 0.0), 0.0, "a target at the sensor is in the notch");
        // crossing at right angles: no radial speed, notched however fast it moves
        assert_eq!(mti.at(0.0, 1e6), 0.0);
    }

    #[test]
    fn an_uncertain_radial_speed_gives_the_normal_masses() {
        let mti = RangeRateNotch::new(1.0, Some(10.0), 2, 0.0, 1.0).unwrap();
        let r2 = 1e6; // 1 km: Δp·Δv is 1000 ṙ
                      // no spread: the point value
        assert_eq!(mti.expected_at(500.0, r2, 0.0), mti.at(500.0, r2));
        // ṙ ~ N(0, 1): P(|ṙ| ≤ 1) = 0.682689492…, the blind intervals [9, 11] add 2·1.1e-19
        let e = mti.expected_at(0.0, r2, 1.0);
        assert!((e - (1.0 - 0.682_689_492_137_085_9)).abs() < 1e-15, "{e}");
        // ṙ ~ N(10, 0.5²): centred on the first blind speed, P(|ṙ − 10| ≤ 1) = 0.954499736…
        let e = mti.expected_at(10_000.0, r2, 0.25);
        assert!((e - (1.0 - 0.954_499_736_103_641_6)).abs() < 1e-15, "{e}");
        // far from every interval: outside, to the last bit
        assert_eq!(mti.expected_at(5_000.0, r2, 1e-10), 1.0);
        // at the sensor: in the notch whatever the spread
        assert_eq!(mti.expected_at(0.0, 0.0, 1.0), 0.0);
        // a spread so wide it overflows: no mass in the notch; a notch wider than any
        // speed far away: inside, not NaN
        assert_eq!(mti.expected_at(0.0, r2, f64::INFINITY), 1.0);
        let huge = RangeRateNotch::new(1e200, Some(3e200), 1, 0.0, 1.0).unwrap();
        assert_eq!(huge.expected_at(1e220, 1e220, 1.0), 0.0);
    }

    #[test]
    fn bad_notches_are_named() {
        assert_eq!(
            RangeRateNotch::new(-1.0, None, 1, 0.0, 1.0).unwrap_err().argument(),
            "width"
        );
        assert_eq!(
            RangeRateNotch::new(f64::NAN, None, 1, 0.0, 1.0).unwrap_err().argument(),
            "width"
        );
        assert_eq!(
            RangeRateNotch::new(2.0, Some(3.0), 1, 0.0, 1.0).unwrap_err().argument(),
            "blind_speed"
        );
        assert_eq!(
            RangeRateNotch::new(2.0, Some(30.0), 0, 0.0, 1.0)
                .unwrap_err()
                .argument(),
            "multiples"
        );
        assert_eq!(
            RangeRateNotch::new(2.0, None, 1, f64::NAN, 1.0).unwrap_err().argument(),
            "inside"
        );
    }
}
