r"""Context-aware Bernoulli particle and SMC-PHD updaters.

Drop-ins for :class:`stonesoup.updater.particle.BernoulliParticleUpdater` and
:class:`stonesoup.updater.particle.SMCPHDUpdater` (Stone Soup 1.9.1): P_D is evaluated at
*every particle* of the prediction in one
:meth:`~ctxmodels.DetectorContext.prob_detection_particles` call into the Rust core (the
(D, N) particles read in place, log P_D and log(1 - P_D) taken there), and the clutter
intensity :math:`\lambda(z; S)` of every detection in one
:meth:`~ctxmodels.DetectorContext.clutter_spatial_density_detections` call. A context of
another kind needs only ``prob_detection_array``: it gets the transposed particles and
NumPy's log, with the same numbers.

**How the context reaches them.** Stone Soup 1.9.1 has no Bernoulli or SMC-PHD tracker: the
Bernoulli example builds ``MultipleHypothesis([SingleHypothesis(prediction, detection) for
detection in detections])`` and calls ``updater.update(hypotheses)``; the
:class:`~stonesoup.initiator.particle.SMCPHDInitiator` hypothesises with a
``SimpleHypothesiser`` and calls ``updater.get_log_weights_per_hypothesis(hypotheses)`` and
``updater.update(hypotheses)`` — neither forwards anything but the hypotheses, and a
hypothesis holds single detections, not the scan's :class:`~ctxmodels.DetectionSet`. So the
context is taken, in this order, from

1. the ``detector_context`` keyword of ``update`` / ``get_log_weights_per_hypothesis``
   (pass ``detections.detector_context`` when you build the hypotheses yourself), or
2. the scan context set with ``with updater.scan_context(detections.detector_context):``
   around code that calls the updater for you (e.g. ``SMCPHDInitiator.initiate``).

With neither, each updater is exactly the stock one.
"""
from __future__ import annotations

import contextlib

import numpy as np
from scipy.special import logsumexp
from stonesoup.types.update import Update
from stonesoup.updater.particle import BernoulliParticleUpdater as _StockBernoulliUpdater
from stonesoup.updater.particle import SMCPHDUpdater as _StockSMCPHDUpdater

from .._upstream import log_space_product, measurement_loglikelihoods
from ..foreign import as_array_context


class _ParticleContextMixin:
    """Context resolution (keyword, then the active update's, then ``scan_context``) and
    P_D over all particles in one array call."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._scan_context = None
        self._active_context = None

    @contextlib.contextmanager
    def scan_context(self, detector_context):
        """Use ``detector_context`` for every update made inside the ``with`` block (for
        callers that do not forward a context, like ``SMCPHDInitiator``). ``None`` is
        allowed: the stock behaviour."""
        if detector_context is not None:
            detector_context = as_array_context(detector_context, *_ARRAY_METHODS)
        previous, self._scan_context = self._scan_context, detector_context
        try:
            yield self
        finally:
            self._scan_context = previous

    def _context(self, detector_context):
        if detector_context is not None:
            return as_array_context(detector_context, *_ARRAY_METHODS)
        if self._active_context is not None:
            return self._active_context
        return self._scan_context

    @staticmethod
    def _particle_prob_detection(prediction, detector_context, *, missed=False):
        """log P_D at each particle, (N,), from one array call; with ``missed`` also
        log(1 - P_D), as a pair."""
        particles = np.asarray(prediction.state_vector, dtype=np.float64)
        in_core = getattr(detector_context, "prob_detection_particles", None)
        if in_core is not None:  # ctxmodels: (D, N) read in place, logs in the core
            return in_core(particles, log=True, missed=missed)
        # Any other context with the array method: rows for it, NumPy's log here.
        prob_detection = np.asarray(detector_context.prob_detection_array(particles.T),
                                    dtype=np.float64)
        log_pd = _log(prob_detection)
        return (log_pd, _log(1 - prob_detection)) if missed else log_pd


_ARRAY_METHODS = ("prob_detection_array", "clutter_spatial_density_detections")


def _log(values: np.ndarray) -> np.ndarray:
    with np.errstate(divide="ignore"):  # log 0 = -inf is meant: P_D = 0 / P_D = 1
        return np.log(values)


class BernoulliParticleUpdater(_ParticleContextMixin, _StockBernoulliUpdater):
    r"""Bernoulli particle filter updater (Ristic et al. 2013) with per-scan context.

    With a context, for particles :math:`x^{(i)}` with weights :math:`w^{(i)}`, existence
    :math:`r` and detections :math:`Z`:

    .. math::
        \delta = \sum_i P_D(x^{(i)}) w^{(i)}
                 - \sum_{z \in Z} \sum_i
                   \frac{P_D(x^{(i)})\, g(z|x^{(i)})\, w^{(i)}}{\lambda(z; S)},
        \qquad r' = \frac{1 - \delta}{1 - r\,\delta}\, r,

        w'^{(i)} \propto \Bigl[1 - P_D(x^{(i)}) + P_D(x^{(i)}) \sum_{z \in Z}
                 \frac{g(z|x^{(i)})}{\lambda(z; S)}\Bigr] w^{(i)},

    where the stock updater uses the constant ``detection_probability`` and
    ``clutter_rate * clutter_distribution``. An **empty scan with a context is a missed
    detection** (:math:`Z = \emptyset`: :math:`r` and the weights take the :math:`1 - P_D`
    factor) — the stock 1.9.1 updater leaves the state unchanged on an empty scan, which is
    what it still does without a context. With a constant context on a scan with
    detections the result is the stock one, bit for bit.
    """

    def get_log_detection_probability(self, prediction, detector_context=None):
        """Log P_D of every particle: from the context (one array call) when there is one,
        else the stock constant ``detection_probability``."""
        context = self._context(detector_context)
        if context is None:
            return super().get_log_detection_probability(prediction)
        return self._particle_prob_detection(prediction, context)

    def update(self, hypotheses, detector_context=None, **kwargs):
        """Bernoulli update of one scan; see the class docstring. Hypotheses as the stock
        updater takes them (one per detection; only a missed-detection one for an empty
        scan); missed-detection hypotheses among detections are ignored."""
        context = self._context(detector_context)
        if context is None:
            return super().update(hypotheses, **kwargs)
        return self._update_with_context(hypotheses, context)

    def _update_with_context(self, hypotheses, context):
        if not hypotheses.single_hypotheses:
            raise ValueError("hypotheses: needs at least one hypothesis (a missed-detection "
                             "hypothesis for an empty scan) to carry the prediction")
        prediction = hypotheses.single_hypotheses[0].prediction
        state = Update.from_state(state=prediction, hypothesis=hypotheses,
                                  timestamp=prediction.timestamp)
        detections = [h.measurement for h in hypotheses.single_hypotheses if h]
        log_pd = self.get_log_detection_probability(prediction, context)
        log_weight = state.log_weight
        existence = state.existence_probability
        log_missed = _log(1 - np.exp(log_pd))

        if detections:
            clutter = np.asarray(context.clutter_spatial_density_detections(detections),
                                 dtype=np.float64)
            log_clutter = np.log(clutter)
            log_likelihoods = [(d.measurement_model or self.measurement_model).logpdf(d, state)
                               for d in detections]
            # Operations in the stock order, so a constant context gives the stock bits.
            per_detection = [log_space_product(self, log_pd, ll - lc + log_weight)
                             for ll, lc in zip(log_likelihoods, log_clutter)]
            delta = np.exp(log_space_product(self, log_pd, log_weight)) \
                - np.exp(logsumexp(per_detection))
            if np.all(clutter == clutter[0]):
                log_detected = log_pd + logsumexp(log_likelihoods, axis=0) - log_clutter[0]
            else:
                log_detected = log_pd + logsumexp(
                    np.stack(log_likelihoods) - log_clutter[:, np.newaxis], axis=0)
            new_log_weight = np.logaddexp(log_detected, log_missed) + log_weight
        else:
            delta = np.exp(log_space_product(self, log_pd, log_weight))
            new_log_weight = log_missed + log_weight
        state.existence_probability = (1 - delta) / (1 - existence * delta) * existence
        state.log_weight = new_log_weight - logsumexp(new_log_weight)

        if self.constraint_func is not None:
            unconstrained = self.constraint_func(state)
            constrained = np.array(state.log_weight, copy=True)
            constrained[unconstrained] = -np.inf
            state.log_weight = constrained - logsumexp(constrained)
        if self.resampler is not None:
            state = self.resampler.resample(state, self.nsurv_particles)
        if detections and self.regulariser is not None:
            state = self.regulariser.regularise(state.parent, state)
        return state


class SMCPHDUpdater(_ParticleContextMixin, _StockSMCPHDUpdater):
    r"""SMC-PHD updater (Vo, Singh & Doucet 2003) with per-scan context.

    With a context, particle :math:`i` and detection :math:`z` get (Horridge & Maskell
    2011, eq. 20)

    .. math::
        w^{(i)}(z) = \frac{P_D(x^{(i)})\, g(z|x^{(i)})\, w^{(i)}}
                          {\lambda(z; S) + \sum_l P_D(x^{(l)})\, g(z|x^{(l)})\, w^{(l)}},
        \qquad w^{(i)}(\emptyset) = \bigl(1 - P_D(x^{(i)})\bigr) w^{(i)},

    where the stock updater uses the constant ``prob_detect`` and ``clutter_intensity``.
    Without a context it is the stock updater; a constant context gives the stock bits.
    """

    def update(self, hypotheses, detector_context=None, **kwargs):
        """SMC-PHD update of one scan (hypotheses as the stock updater takes them)."""
        context = self._context(detector_context)
        if context is None:
            return super().update(hypotheses, **kwargs)
        # The stock update calls get_log_weights_per_hypothesis(hypotheses): hand it the
        # context for the duration of this update.
        previous, self._active_context = self._active_context, context
        try:
            return super().update(hypotheses, **kwargs)
        finally:
            self._active_context = previous

    def get_log_weights_per_hypothesis(self, hypotheses, detector_context=None):
        """Log weight of every particle under every hypothesis, (N, 1 + detections); the
        first column is the missed detection."""
        context = self._context(detector_context)
        if context is None:
            return super().get_log_weights_per_hypothesis(hypotheses)
        prediction = hypotheses[0].prediction
        detections = [h.measurement for h in hypotheses if h]
        num_samples = prediction.state_vector.shape[1]
        log_pd, log_missed = self._particle_prob_detection(prediction, context, missed=True)
        log_weight = prediction.log_weight
        log_likelihood = measurement_loglikelihoods(self, prediction, detections)

        detected = log_pd[:, np.newaxis] + log_likelihood + log_weight[:, np.newaxis]
        weights = np.full((num_samples, len(detections) + 1), -np.inf)
        weights[:, 0] = log_missed + log_weight
        if detections:
            clutter = np.log(np.asarray(
                context.clutter_spatial_density_detections(detections), dtype=np.float64))
            weights[:, 1:] = detected - np.logaddexp(logsumexp(detected, axis=0), clutter)
        return weights


__all__ = ["BernoulliParticleUpdater", "SMCPHDUpdater"]
