//! Radar-equation P_D: the detection probability of a square-law detector summing `n`
//! pulses non-coherently, for a target whose per-pulse signal-to-noise ratio falls with the
//! fourth power of range, for the Swerling cases 0–4.
//!
//! **SNR.** S(r) = S₀ (r₀ / r)⁴ / L, from the SNR S₀ at the reference range r₀ and a loss L
//! (all linear here; the component takes dB). S(0) = ∞ (P_D = 1).
//!
//! **Threshold.** Noise-only, each pulse's power is exponential with mean 1, so the sum y of
//! n pulses is Gamma(n, 1): the threshold T solves Q(n, T) = P_FA (Q the regularised upper
//! incomplete gamma; T = −ln P_FA for one pulse).
//!
//! **P_D = P(y > T)** with signal: each pulse's power p given its signal power σ has
//! E[e^{−tp}] = (1 + t)^{−1} exp(−tσ/(1 + t)) (2p is non-central χ² with 2 degrees of
//! freedom). Averaging over the Swerling case's fluctuation of σ (mean S) gives:
//!
//! * **Swerling 0** (no fluctuation): y is a Poisson(λ = nS) mixture of Gamma(n + k, 1):
//!   P_D = Σ_k e^{−λ} λ^k / k! · Q(n + k, T) (Marcum's Q_n(√(2nS), √(2T))).
//! * **Swerling 1** (exponential σ, constant over the n pulses): y = Gamma(n − 1, 1) +
//!   Exp(mean γ), γ = 1 + nS: P_D = Q(n − 1, T) + e^{−T/γ} X_{n−1}(1 − 1/γ, T), one pulse
//!   P_D = P_FA^{1/(1+S)}.
//! * **Swerling 2** (exponential σ, independent per pulse): y is Gamma(n, 1 + S):
//!   P_D = Q(n, T / (1 + S)).
//! * **Swerling 3** (χ² σ with 4 degrees of freedom, constant over the pulses): y =
//!   Gamma(n − 2, 1) + Gamma(2, δ), δ = 1 + nS/2: for n ≥ 3, with a = n − 2 and c = 1 − 1/δ,
//!   P_D = Q(a, T) + e^{−T/δ} [(1 + T/δ) X_a(c, T) − (a/δ) X_{a+1}(c, T)]; for n = 2,
//!   e^{−T/δ}(1 + T/δ); for n = 1, e^{−T/δ}(1 + cT/δ).
//! * **Swerling 4** (χ², 4 degrees of freedom, independent per pulse): E[e^{−ty}] =
//!   (1 + t)ⁿ / (1 + βt)^{2n}, β = 1 + S/2, is a binomial mixture of Gamma(2n − k, β):
//!   P_D = Σ_{k=0}^{n} C(n, k) β^{−k} (1 − 1/β)^{n−k} Q(2n − k, T/β).
//!
//! X_a(c, T) = c^{−a} P(a, cT) is evaluated without the division, in logs
//! ([`gamma::ln_scaled_lower`]).
//! Every sum has positive terms only, or is taken on the side (P_D or 1 − P_D) where it has:
//! P_D keeps its relative accuracy near P_FA (1e-12 against SciPy in the tests, down to
//! P_FA 1e-300 for a steady target; Swerling 3 with hundreds of pulses, whose bracket
//! cancels, 1e-10) and its absolute accuracy near 1. P_D is clamped to [P_FA, 1], the
//! bound the last bits of a sum could cross; it is monotone in range to within 1e-11.

use crate::error::{ModelError, Result};
use crate::simd::{exp, Lanes, Portable};

pub mod gamma;

/// Most pulses summed: the sums above cost O(n) per state.
pub const MAX_PULSES: u64 = 1024;

/// How the target's radar cross-section fluctuates (Swerling's cases).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Swerling {
    Zero,
    One,
    Two,
    Three,
    Four,
}

impl Swerling {
    pub fn from_case(case: u8) -> Result<Self> {
        Ok(match case {
            0 => Swerling::Zero,
            1 => Swerling::One,
            2 => Swerling::Two,
            3 => Swerling::Three,
            4 => Swerling::Four,
            _ => {
                return Err(ModelError::invalid(
                    "swerling",
                    format!("must be a case 0..4, got {case}"),
                ))
            }
        })
    }
}

/// The one-pulse closed forms of the fluctuating cases (Swerling 1 and 2 coincide for one
/// pulse, as 3 and 4 do), evaluated four ranges at a time with the lanes' e^x.
#[derive(Debug, Clone, Copy, PartialEq)]
enum OnePulse {
    /// P_D = e^{−T/(1+S)} = P_FA^{1/(1+S)}.
    Exponential,
    /// P_D = e^{−T/δ}(1 + cT/δ), δ = 1 + S/2, c = 1 − 1/δ.
    ChiSquare4,
}

impl OnePulse {
    fn of(swerling: Swerling, pulses: u64) -> Option<Self> {
        match (swerling, pulses) {
            (Swerling::One | Swerling::Two, 1) => Some(OnePulse::Exponential),
            (Swerling::Three | Swerling::Four, 1) => Some(OnePulse::ChiSquare4),
            _ => None,
        }
    }

    /// P_D at per-pulse SNRs `s` against the threshold `t` (S = ∞ gives 1, NaN NaN).
    #[inline(always)]
    fn at<L: Lanes>(self, s: L, t: f64) -> L {
        let one = L::splat(1.0);
        match self {
            OnePulse::Exponential => closed_form::<L, true>(one.div(one + s), t),
            OnePulse::ChiSquare4 => closed_form::<L, false>(one.div(one + s * L::splat(0.5)), t),
        }
    }
}

/// The one-pulse closed forms from `near` ∈ [0, 1] (NaN kept): 1/(1 + S) for the
/// exponential form (`EXPONENTIAL`), 1/δ for the χ² one, against the threshold `t`.
#[inline(always)]
fn closed_form<L: Lanes, const EXPONENTIAL: bool>(near: L, t: f64) -> L {
    // T < 690.8 (P_FA > 1e-300): −q lies within the range of exp
    let q = L::splat(t) * near;
    let tail = exp(L::splat(0.0) - q);
    if EXPONENTIAL {
        tail
    } else {
        let one = L::splat(1.0);
        let pd = tail * (one + (one - near) * q);
        L::select(L::gt(pd, one), one, pd)
    }
}

/// A one-pulse closed form prepared for squared ranges. With c = S₀ r₀⁴ / L the SNR is
/// S = c / r⁴, so 1 / (1 + S) = r⁴ / (r⁴ + c) and (Swerling 3–4) 1/δ = r⁴ / (r⁴ + c/2):
/// one division per range, none for the SNR itself.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OnePulseAtRange {
    form: OnePulse,
    /// c for the exponential form, c/2 for the χ² one.
    scale: f64,
    threshold: f64,
}

impl OnePulseAtRange {
    /// P_D at four squared ranges (r² = 0 gives 1; r⁴ beyond the largest double, S = 0,
    /// gives P_FA; NaN gives NaN).
    #[inline(always)]
    pub fn lanes_at_squared<L: Lanes>(&self, r2: L) -> L {
        if self.is_exponential() {
            self.lanes_form::<L, true>(r2)
        } else {
            self.lanes_form::<L, false>(r2)
        }
    }

    /// Whether the form is Swerling 1–2's e^{−T/(1+S)}.
    pub fn is_exponential(&self) -> bool {
        self.form == OnePulse::Exponential
    }

    /// [`Self::lanes_at_squared`] with the form known at compile time (`EXPONENTIAL`: as
    /// [`Self::is_exponential`]), for loops that choose it once.
    #[inline(always)]
    pub fn lanes_form<L: Lanes, const EXPONENTIAL: bool>(&self, r2: L) -> L {
        let one = L::splat(1.0);
        let r4 = r2 * r2;
        // (where r⁴ overflows, r⁴/(r⁴ + c) would be ∞/∞)
        let near = L::select(L::gt(r4, L::splat(f64::MAX)), one, r4.div(r4 + L::splat(self.scale)));
        closed_form::<L, EXPONENTIAL>(near, self.threshold)
    }
}

/// P_D of the radar equation at every range (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct RadarEquation {
    /// S₀ / L, linear.
    snr: f64,
    /// r₀².
    reference_range2: f64,
    swerling: Swerling,
    pulses: u64,
    false_alarm: f64,
    threshold: f64,
    /// (Q(n, T), t_n(T)): where Swerling 0's sum starts for the SNRs whose Poisson window
    /// reaches k = 0 (most of a scan's), the same for every state.
    start: (f64, f64),
}

impl RadarEquation {
    /// From the SNR `reference_snr_db` (dB) at `reference_range` (m), a `loss_db` (dB, ≥ 0),
    /// the false-alarm probability, the Swerling case and the pulses summed.
    pub fn new(
        reference_snr_db: f64,
        reference_range: f64,
        loss_db: f64,
        false_alarm_probability: f64,
        swerling: Swerling,
        pulses: u64,
    ) -> Result<Self> {
        if !(-100.0..=200.0).contains(&reference_snr_db) {
            return Err(ModelError::invalid(
                "reference_snr",
                format!("must be a finite SNR in dB within -100..200, got {reference_snr_db}"),
            ));
        }
        if !(1e-6..1e12).contains(&reference_range) {
            return Err(ModelError::invalid(
                "reference_range",
                format!("must be a range in metres within [1e-6, 1e12), got {reference_range:e}"),
            ));
        }
        if !(0.0..=200.0).contains(&loss_db) {
            return Err(ModelError::invalid(
                "loss",
                format!("must be a loss in dB within 0..200, got {loss_db}"),
            ));
        }
        if !(false_alarm_probability > 1e-300 && false_alarm_probability <= 0.5) {
            return Err(ModelError::invalid(
                "false_alarm_probability",
                format!("must lie in (1e-300, 0.5], got {false_alarm_probability:e}"),
            ));
        }
        if !(1..=MAX_PULSES).contains(&pulses) {
            return Err(ModelError::invalid(
                "pulses",
                format!("must be an integer in 1..{MAX_PULSES}, got {pulses}"),
            ));
        }
        let threshold = gamma::inverse_upper(pulses, false_alarm_probability);
        Ok(RadarEquation {
            snr: 10f64.powf((reference_snr_db - loss_db) / 10.0),
            reference_range2: reference_range * reference_range,
            swerling,
            pulses,
            false_alarm: false_alarm_probability,
            threshold,
            start: gamma::upper_and_term(pulses, threshold),
        })
    }

    /// The detection threshold T on the sum of the pulses' powers (noise power 1).
    pub fn threshold(&self) -> f64 {
        self.threshold
    }

    /// The per-pulse SNR (linear) at squared range `r2`.
    #[inline]
    pub fn snr_at_squared(&self, r2: f64) -> f64 {
        let ratio = self.reference_range2 / r2;
        self.snr * (ratio * ratio)
    }

    /// The one-pulse closed form at squared ranges, if the radar has one (one pulse,
    /// Swerling 1–4).
    pub fn one_pulse(&self) -> Option<OnePulseAtRange> {
        let form = OnePulse::of(self.swerling, self.pulses)?;
        let c = self.snr * (self.reference_range2 * self.reference_range2);
        let scale = match form {
            OnePulse::Exponential => c,
            OnePulse::ChiSquare4 => c * 0.5,
        };
        Some(OnePulseAtRange {
            form,
            scale,
            threshold: self.threshold,
        })
    }

    /// P_D at squared range `r2` (NaN stays NaN): the reference [`Self::lanes_at_squared`]
    /// gives the bits of.
    pub fn at_squared(&self, r2: f64) -> f64 {
        if let Some(form) = self.one_pulse() {
            return form.lanes_at_squared(Portable::splat(r2)).to_array()[0];
        }
        // (NaN r² gives a NaN SNR, which detection_probability keeps)
        summed(
            self.swerling,
            self.pulses,
            self.snr_at_squared(r2),
            self.threshold,
            self.false_alarm,
            self.start,
        )
    }

    /// P_D at four squared ranges: the one-pulse closed forms in lanes, the sums one lane
    /// after another (their length depends on the range).
    #[inline(always)]
    pub fn lanes_at_squared<L: Lanes>(&self, r2: L) -> L {
        match self.one_pulse() {
            Some(form) => form.lanes_at_squared(r2),
            None => {
                let r2 = r2.to_array();
                L::from_array(std::array::from_fn(|k| self.at_squared(r2[k])))
            }
        }
    }

    /// P_D at range `r`.
    pub fn at(&self, r: f64) -> f64 {
        self.at_squared(r * r)
    }
}

/// P_D for `pulses` pulses of per-pulse SNR `snr` (linear) against `threshold`, whose
/// false-alarm probability is `false_alarm` (P_D at SNR 0).
pub fn detection_probability(swerling: Swerling, pulses: u64, snr: f64, threshold: f64, false_alarm: f64) -> f64 {
    // (Swerling 0's window may start at k = 0; the other cases need no start)
    let start = match swerling {
        Swerling::Zero => gamma::upper_and_term(pulses, threshold),
        _ => (f64::NAN, f64::NAN),
    };
    summed(swerling, pulses, snr, threshold, false_alarm, start)
}

/// [`detection_probability`] given `start` = (Q(n, T), t_n(T)).
fn summed(swerling: Swerling, pulses: u64, snr: f64, threshold: f64, false_alarm: f64, start: (f64, f64)) -> f64 {
    if let Some(form) = OnePulse::of(swerling, pulses) {
        return form.at(Portable::splat(snr), threshold).to_array()[0];
    }
    if snr == 0.0 {
        return false_alarm;
    }
    if snr.is_nan() {
        return f64::NAN;
    }
    let (n, t) = (pulses, threshold);
    let nf = n as f64;
    if !(nf * snr).is_finite() {
        return 1.0; // (S = ∞: every sum below would be ∞/∞)
    }
    let pd = match swerling {
        Swerling::Zero => swerling0(n, nf * snr, t, start),
        Swerling::One => {
            let gamma = 1.0 + nf * snr;
            let c = nf * snr / gamma;
            gamma::upper(n - 1, t) + (-t / gamma + gamma::ln_scaled_lower(n - 1, c, t)).exp()
        }
        Swerling::Two => gamma::upper(n, t / (1.0 + snr)),
        Swerling::Three => {
            let half = nf * snr / 2.0;
            let delta = 1.0 + half;
            let c = half / delta;
            let tail = (-t / delta).exp();
            match n {
                // (one pulse: OnePulse::ChiSquare4)
                2 => tail * (1.0 + t / delta),
                _ => {
                    // e^{−T/δ} X in logs: X overflows for many pulses, e^{−T/δ} underflows
                    let a = n - 2;
                    let xa = (-t / delta + gamma::ln_scaled_lower(a, c, t)).exp();
                    let xa1 = (-t / delta + gamma::ln_scaled_lower(a + 1, c, t)).exp();
                    gamma::upper(a, t) + (1.0 + t / delta) * xa - (a as f64 / delta) * xa1
                }
            }
        }
        Swerling::Four => swerling4(n, snr, t),
    };
    // P_D ≥ P_FA (a signal only adds power): the bound the sums' last-bit rounding can cross
    pd.clamp(false_alarm, 1.0)
}

/// Σ_k Poisson(k; λ) Q(n + k, T) over the k whose Poisson weight is at least 1e-18 of the
/// mode's (the tails left out hold below ~1e-17 of the mass: they fall faster than
/// geometrically), and upwards on while a weight is above 1e-18 of the sum so far (so that
/// a P_D near a small P_FA keeps its relative accuracy). Summed upwards (Q grows with k) for P_D below ½, else as
/// 1 − Σ_k Poisson(k; λ) P(n + k, T) summed downwards (P falls with k), so that every
/// recurrence adds; the side is guessed from the mean of the summed power, n + λ, against
/// T, and the other side summed only when the guess was wrong.
///
/// The weights are kept relative to the mode's (w_mode = 1, w_{k+1} = w_k λ/(k + 1)) and
/// each sum is divided by its weights' total: the common factor e^{−λ} λ^m / m! cancels,
/// so it is never formed, and neither is the rounding it would pass to every weight.
/// `start` is (Q(n, T), t_n(T)), the model's own, for a window from k = 0.
fn swerling0(n: u64, lambda: f64, t: f64, start: (f64, f64)) -> f64 {
    if lambda > 1e15 {
        // T < 1e4 (Q(n, T) ≥ 1e-300, n ≤ 1024): no Poisson mass where P(n + k, T) is not 0
        return 1.0;
    }
    // A sure lower end first (below it lies < 1e-20 of the Poisson mass): where every
    // k above it misses with probability < 1e-18, P_D is 1 to double precision. (At 0 it
    // would ask whether 1 − P_FA < 1e-18: never.)
    let floor = (lambda - 10.0 * lambda.sqrt() - 10.0).max(0.0) as u64;
    if floor > 0 && gamma::regularized(n + floor, t).0 < 1e-18 {
        return 1.0;
    }
    let mode = lambda.floor() as u64;
    let inverse_lambda = 1.0 / lambda;
    // (counters kept as floats too where they scale a weight: exact below 2⁵³, and no
    // integer conversion in the loops)
    let (mut lo, mut w_lo, mut lo_f) = (mode, 1.0, mode as f64);
    while lo > 0 && w_lo > 1e-18 {
        w_lo *= lo_f * inverse_lambda;
        lo -= 1;
        lo_f -= 1.0;
    }
    // t_a = e^{−T} T^a / a!, with t_{a+1} = t_a T / (a + 1)
    let detected = || {
        let (mut q, mut step) = if lo == 0 {
            start
        } else {
            gamma::upper_and_term(n + lo, t)
        };
        let (mut weight, mut pd, mut total) = (w_lo, 0.0, 0.0);
        let mut k = lo;
        // to where the weights fall below 1e-18 of the mode's, and past it while they still
        // matter next to P_D itself (Q grows with k, so a small P_D needs the tail)
        loop {
            pd += weight * q;
            total += weight;
            if !(k <= mode || weight > 1e-18 || (weight > 1e-18 * pd && weight > 0.0)) {
                break;
            }
            q += step;
            step *= t * gamma::reciprocal(n + k + 1);
            weight *= lambda * gamma::reciprocal(k + 1);
            k += 1;
        }
        pd / total
    };
    let missed = || {
        let (mut hi, mut weight) = (mode, 1.0);
        while weight > 1e-18 {
            hi += 1;
            weight *= lambda * gamma::reciprocal(hi);
        }
        // t_{n+k−1}: P(n+k−1) = P(n+k) + t_{n+k−1}
        let (mut p, mut step) = gamma::lower_and_term_below(n + hi, t);
        let (mut miss, mut total) = (0.0, 0.0);
        let (mut k, mut k_f, mut shape) = (hi, hi as f64, (n + hi) as f64);
        let inverse_t = 1.0 / t;
        loop {
            miss += weight * p;
            total += weight;
            if k == lo {
                break;
            }
            p += step;
            // w_{k−1} = w_k k / λ, t_{n+k−2} = t_{n+k−1} (n + k − 1) / T
            k -= 1;
            weight *= k_f * inverse_lambda;
            k_f -= 1.0;
            shape -= 1.0;
            step *= shape * inverse_t;
        }
        miss / total
    };
    if t >= n as f64 + lambda {
        let pd = detected();
        if pd < 0.5 {
            return pd;
        }
        1.0 - missed()
    } else {
        let miss = missed();
        if miss <= 0.5 {
            return 1.0 - miss;
        }
        detected()
    }
}

/// Σ_{k=0}^{n} C(n, k) β^{−k} (1 − 1/β)^{n−k} Q(2n − k, T/β), β = 1 + S/2 (S > 0).
fn swerling4(n: u64, snr: f64, t: f64) -> f64 {
    let beta = 1.0 + snr / 2.0;
    let x = t / beta;
    let (ln_near, ln_far) = (-beta.ln(), (snr / (2.0 + snr)).ln()); // ln β^{−1}, ln(1 − 1/β)
    let ln_n = gamma::ln_factorial(n);
    // from k = n (shape n) to k = 0 (shape 2n): Q grows by t_a at each step
    let mut q = gamma::upper(n, x);
    let mut step = gamma::term(n, x);
    let (mut pd, mut total) = (0.0, 0.0);
    for k in (0..=n).rev() {
        let ln_weight =
            ln_n - gamma::ln_factorial(k) - gamma::ln_factorial(n - k) + k as f64 * ln_near + (n - k) as f64 * ln_far;
        let weight = ln_weight.exp();
        pd += weight * q;
        total += weight;
        let a = 2 * n - k; // the shape just used
        q += step;
        step *= x / (a + 1) as f64;
    }
    // The weights sum to 1: dividing by their computed sum removes the rounding of their
    // logs (5e-13 with a thousand pulses), which would otherwise show where P_D ≈ 1.
    pd / total
}

#[cfg(test)]
mod tests;
