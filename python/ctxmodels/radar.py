r"""The radar equation's detection probability: P_D from the signal-to-noise ratio at range,
for a Swerling target and a detector summing pulses."""
from __future__ import annotations

import numpy as np
from stonesoup.base import Property

from . import _core
from ._component import ModelComponent, as_array, as_float, as_int
from .errors import ArgumentError, ArgumentTypeError

#: Most pulses summed (the detection sums cost O(pulses) per state).
MAX_PULSES = 1024


class RadarEquation(ModelComponent):
    r"""P_D of a radar against a Swerling target, from its SNR at the target's range.

    The per-pulse signal-to-noise ratio falls with the fourth power of range,

    .. math::
        S(r) = S_0 \left(\frac{r_0}{r}\right)^{4} / L,

    from ``reference_snr`` :math:`S_0` (dB) at ``reference_range`` :math:`r_0` and a
    ``loss`` :math:`L` (dB). A square-law detector sums the powers of ``pulses``
    :math:`n` pulses (non-coherent integration), noise power 1 per pulse, against the
    threshold :math:`T` of the false-alarm probability: :math:`Q(n, T) = P_{FA}`, with
    :math:`Q` the regularised upper incomplete gamma function (:math:`T = -\ln P_{FA}` for
    one pulse). :math:`P_D(r) = P(y > T)` for the sum :math:`y` with signal, by the target's
    fluctuation (``swerling``):

    * 0, steady: :math:`P_D = \sum_k e^{-nS} (nS)^k / k! \; Q(n + k, T)` (Marcum's
      :math:`Q_n(\sqrt{2nS}, \sqrt{2T})`);
    * 1, exponential cross-section, constant over the pulses (scan to scan):
      :math:`P_D = Q(n - 1, T) + e^{-T/\gamma} X_{n-1}(1 - 1/\gamma, T)`,
      :math:`\gamma = 1 + nS`; one pulse: :math:`P_D = P_{FA}^{1/(1+S)}`;
    * 2, exponential, independent per pulse: :math:`P_D = Q(n, T / (1 + S))`;
    * 3, χ² with four degrees of freedom, scan to scan: with :math:`\delta = 1 + nS/2`,
      :math:`c = 1 - 1/\delta`, :math:`a = n - 2`,
      :math:`P_D = Q(a, T) + e^{-T/\delta}\left[(1 + T/\delta) X_a(c, T)
      - (a/\delta) X_{a+1}(c, T)\right]` (:math:`n = 2`: :math:`e^{-T/\delta}(1 + T/\delta)`;
      :math:`n = 1`: :math:`e^{-T/\delta}(1 + cT/\delta)`);
    * 4, χ² four degrees of freedom, per pulse: with :math:`\beta = 1 + S/2`,
      :math:`P_D = \sum_{k=0}^{n} \binom{n}{k} \beta^{-k} (1 - 1/\beta)^{n-k}\,
      Q(2n - k, T/\beta)`,

    where :math:`X_a(c, T) = c^{-a} P(a, cT)`. These are exact (finite sums, or series
    summed to double precision; no table, no approximation): held against SciPy's
    non-central χ² averaged over each case's cross-section distribution in the tests. P_D
    falls from 1 at the sensor to :math:`P_{FA}` far away; 0 on the sensor's own position
    is :math:`S = \infty`, P_D 1.

    Combine it with a range band for the instrumented range and a :class:`RadarHorizon`:
    ``DetectionProbabilityModel(factors=[RadarEquation(reference_snr=13.0,
    reference_range=1500.0, false_alarm_probability=1e-6, swerling=1),
    RadarHorizon(antenna_height=20.0, target_height=5.0)])``.
    """

    reference_snr: float = Property(doc="Per-pulse SNR at ``reference_range``, dB.")
    reference_range: float = Property(
        doc="Range at which the SNR is ``reference_snr``, metres, within [1e-6, 1e12).")
    false_alarm_probability: float = Property(
        doc="The detector's false-alarm probability per resolution cell, in (1e-300, 0.5].")
    swerling: int = Property(default=1, doc="Swerling case of the target, 0–4.")
    pulses: int = Property(default=1, doc=f"Pulses summed non-coherently, 1–{MAX_PULSES}.")
    loss: float = Property(default=0.0, doc="System loss, dB (≥ 0), subtracted from the SNR.")

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._replace("swerling", as_int(self.swerling, "swerling", high=4))
        self._replace("pulses", as_int(self.pulses, "pulses", low=1, high=MAX_PULSES))
        self._compiled()

    def _compiled(self) -> _core.RadarEquation:
        return self._cached("core", lambda: _core.RadarEquation(
            as_float(self.reference_snr, "reference_snr"),
            as_float(self.reference_range, "reference_range"),
            as_float(self.loss, "loss"),
            as_float(self.false_alarm_probability, "false_alarm_probability"),
            self.swerling, self.pulses))

    @property
    def threshold(self) -> float:
        """The detection threshold :math:`T` on the summed pulse powers (noise power 1)."""
        return self._compiled().threshold

    def snr(self, ranges) -> np.ndarray:
        """The per-pulse SNR :math:`S(r)` (linear, not dB) at each range (metres)."""
        return self._compiled().snr(_ranges(ranges))

    def __call__(self, ranges) -> np.ndarray:
        """P_D at each range (array-like, metres); NaN gives NaN."""
        return self._compiled().at(_ranges(ranges))


def _ranges(ranges) -> np.ndarray:
    """Ranges (metres, ≥ 0; NaN passes) as a 1-D float64 array, or an error naming them."""
    if isinstance(ranges, (str, bytes)):
        raise ArgumentTypeError("ranges", f"expected numbers, got {type(ranges).__name__}")
    try:
        values = np.atleast_1d(np.asarray(ranges))
    except (TypeError, ValueError) as err:  # ragged lists and the like
        raise ArgumentTypeError("ranges", f"cannot be read as numbers ({err})") from None
    r = as_array(values, "ranges", 1, "a 1-D array of ranges")
    if np.any(r < 0):
        raise ArgumentError("ranges", f"must be >= 0 metres, got {r[r < 0][0]}")
    return r
