r"""A context-aware drop-in for Stone Soup's PDA hypothesiser (PDA and the JPDA family).

Stone Soup 1.9.1's :class:`~stonesoup.hypothesiser.probability.PDAHypothesiser` takes one
global :math:`P_D` and one clutter density :math:`\lambda`. With a detector context on the
scan, :class:`PDAHypothesiser` uses :math:`P_D(\hat{x}; S)` at each track's prediction and
:math:`\lambda(z_j; S)` at each detection instead; with no context it *is* the stock class.

How the context reaches it with stock components (checked against stonesoup 1.9.1):
:class:`~stonesoup.tracker.simple.MultiTargetMixtureTracker` hands the detector's set to the
associator unchanged, and :class:`~stonesoup.dataassociator.probability.PDA`, ``JPDA``,
``JPDAwithLBP``, ``JPDAwithEHM`` and ``JPDAwithEHM2`` pass that same object to
``hypothesise``; so a :class:`~ctxmodels.DetectionSet` from a
:class:`~ctxmodels.stonesoup.ContextFeeder` arrives with its context and no tracker or
associator subclass is needed. (The tracker gives its *initiator* a plain ``set`` of the
unassociated detections: a hypothesiser used inside an initiator sees no context and falls
back to the stock constants.) A context can also be passed explicitly as the keyword
argument ``detector_context``, which ``PDA``/``JPDA``/``JPDAwithEHM``'s ``associate``
forwards; it takes precedence over the set's.
"""
from __future__ import annotations

import numpy as np
from stonesoup.functions import batch_multivariate_normal_logpdf
from stonesoup.hypothesiser.probability import PDAHypothesiser as _StockPDAHypothesiser
from stonesoup.measures import SquaredMahalanobis
from stonesoup.types.detection import Detection, MissedDetection
from stonesoup.types.hypothesis import SingleProbabilityHypothesis
from stonesoup.types.multihypothesis import MultipleHypothesis
from stonesoup.types.numeric import Probability
from stonesoup.types.state import State, StateMutableSequence
from stonesoup.types.update import Update

from ..._upstream import gate_threshold
from ...foreign import PerCallContext, as_array_context
from ..scan_context import scan_context
from ._pd_record import PDRecord


def is_detection_backed(state) -> bool:
    """Whether a track state came from at least one detection (Stone Soup's deleters'
    criterion: an :class:`~stonesoup.types.update.Update` with a non-empty hypothesis)."""
    return isinstance(state, Update) and bool(state.hypothesis)


def prob_detect_at(context, prediction) -> float:
    """P_D of one prediction from an array context (:func:`~ctxmodels.foreign.as_array_context`)
    as the raw float the model computed: going through ``Probability`` (log space) and back
    can change the last bit of a value such as 0.35."""
    vector = getattr(prediction, "state_vector", None)
    if isinstance(context, PerCallContext) or (
            vector is not None and np.ndim(vector) == 2 and np.shape(vector)[1] == 1):
        return float(context.prob_detection_states([prediction])[0])
    return float(context.prob_detection(prediction))  # ctxmodels, particles


def _like(template, value: float):
    """``value`` in the numeric type of ``template`` (``prob_detect``), so that the stock
    arithmetic (``Probability`` in log space, or plain floats) is reproduced bit for bit."""
    if isinstance(template, Probability):
        return Probability(value)
    if isinstance(template, np.floating):
        return type(template)(value)
    return float(value)


class PDAHypothesiser(_StockPDAHypothesiser):
    r"""PDA hypothesiser with per-track :math:`P_D` and per-detection :math:`\lambda` from
    the scan's detector context; the stock one when the scan has no context.

    For a track with prediction :math:`\hat{x}` (and measurement prediction
    :math:`\hat{z}, S`) and the :math:`m` detections of a scan with context :math:`S`:

    .. math::
        w_0 = 1 - P_D(\hat{x}; S)\,P_G, \qquad
        w_j = \frac{P_D(\hat{x}; S)\,\mathcal{N}(z_j; \hat{z}, S)}{\lambda(z_j; S)},
        \quad j = 1..m \text{ (gated, or all with ``include_all``)},

    normalised when :attr:`normalise` is set: the stock weights with the global
    :attr:`prob_detect` and :attr:`clutter_spatial_density` replaced by their values at
    the track and at each detection. With a context those two Properties are not used
    (:attr:`prob_detect` only sets the numeric type, ``Probability`` or float, in which
    the arithmetic is done, so a context with the same constants reproduces the stock
    weights exactly). The gate and :attr:`prob_gate` are unchanged. A context with
    :math:`P_D = 0` at a track gives its missed-detection hypothesis all the mass.

    Cost: :math:`\lambda` of a scan's detections is one array call per scan (cached on the
    context and reused by the next tracks of the scan); :math:`P_D` is one call per track,
    because stock associators call ``hypothesise`` once per track.

    Every call records the :math:`P_D` used for the track (the context's, or
    :attr:`prob_detect` without one) against the index of the state the tracker is about
    to append; :meth:`recorded_prob_detect` reads it back, for
    :class:`~ctxmodels.stonesoup.ExpectedMissesDeleter`.
    """

    def hypothesise(self, track, detections, timestamp, **kwargs):
        """Hypotheses of ``track`` against ``detections`` at ``timestamp``: the missed
        detection first, then each gated detection. The context is the
        ``detector_context`` keyword or ``detections.detector_context``; without either,
        exactly the stock :class:`~stonesoup.hypothesiser.probability.PDAHypothesiser`."""
        given = scan_context(detections, kwargs)
        if given is None:
            hypotheses = super().hypothesise(track, detections, timestamp, **kwargs)
            self._record(track, timestamp, float(self.prob_detect))
            return hypotheses
        context = as_array_context(given, "prob_detection_states",
                                   "clutter_spatial_density_detections")

        detections = list(detections)
        prediction = self.predictor.predict(track, timestamp=timestamp, **kwargs)
        prob_detect = prob_detect_at(context, prediction)
        if not 0.0 <= prob_detect <= 1.0:
            raise ValueError(f"detector_context: P_D must lie in [0, 1], got {prob_detect} "
                             f"for a track at {timestamp}")
        self._record(track, timestamp, prob_detect)
        p_d = _like(self.prob_detect, prob_detect)

        hypotheses = [SingleProbabilityHypothesis(
            prediction, MissedDetection(timestamp=timestamp),
            Probability(1 - p_d * self.prob_gate))]
        if not detections:
            return MultipleHypothesis(hypotheses, normalise=self.normalise)

        clutter = self.scan_clutter(given, context, detections)
        # Predictions at each detection's own time, as the stock class does.
        predictions = [self.predictor.predict(track, timestamp=det.timestamp, **kwargs)
                       for det in detections]
        measurement_predictions = [
            self.updater.predict_measurement(pred, det.measurement_model, **kwargs)
            for pred, det in zip(predictions, detections)]
        log_likelihoods = batch_multivariate_normal_logpdf(
            [det.state_vector for det in detections], measurement_predictions)
        distance = SquaredMahalanobis(state_covar_inv_cache_size=None)
        for det, pred, meas_pred, log_l, lam in zip(
                detections, predictions, measurement_predictions, log_likelihoods, clutter):
            gated = distance(meas_pred, det) <= gate_threshold(self.prob_gate, meas_pred.ndim)
            if not (gated or self.include_all):
                continue
            weight = Probability(log_l, log_value=True)
            weight *= p_d
            weight /= lam
            hypotheses.append(SingleProbabilityHypothesis(pred, det, weight, meas_pred))
        return MultipleHypothesis(hypotheses, normalise=self.normalise)

    # --- clutter density per scan ---------------------------------------------------------
    def scan_clutter(self, given, context, detections) -> list:
        """λ of each detection, evaluated once per (context ``given``, detection) with its
        array form ``context`` (:func:`~ctxmodels.foreign.as_array_context`): the first track
        of a scan pays one array call, the others read the cache."""
        values: dict[object, float]
        cache = self.__dict__.get("_clutter_cache")
        if cache is not None and cache[0] is given:
            values = cache[1]
        else:
            values = {}
            self.__dict__["_clutter_cache"] = (given, values)
        missing = [det for det in detections if det not in values]
        if missing:
            lam = np.asarray(self._evaluate_clutter(context, missing), dtype=np.float64)
            if lam.shape != (len(missing),):
                raise ValueError(f"detector_context: expected {len(missing)} clutter "
                                 f"densities, got an array of shape {lam.shape}")
            if not np.all(np.isfinite(lam) & (lam > 0)):
                raise ValueError("detector_context: clutter spatial density must be finite "
                                 "and > 0 at every detection (weights divide by it)")
            values.update(zip(missing, lam.tolist()))
        return [values[det] for det in detections]

    def _evaluate_clutter(self, context, detections):
        clutter = getattr(getattr(context, "sensor_model", None), "clutter", None)
        if clutter is None or not clutter.uses_position \
                or all(det.measurement_model is not None for det in detections):
            return context.clutter_spatial_density_detections(detections)
        # Detections without their own model are measured by the updater's model: give
        # them that model, so every detection's λ follows one rule (position and range).
        default = self.updater.measurement_model
        return context.clutter_spatial_density_detections([
            det if det.measurement_model is not None else Detection(
                det.state_vector, timestamp=det.timestamp, measurement_model=default,
                metadata=det.metadata)
            for det in detections])

    # --- P_D record for observability-aware deletion ---------------------------------------
    def _record(self, track, timestamp, prob_detect: float) -> None:
        if not isinstance(track, StateMutableSequence) or isinstance(track, State):
            return  # a bare state as prior: no track to attach the record to
        n = len(track)
        self._record_at(track, n, bool(n) and is_detection_backed(track[-1]), timestamp,
                        prob_detect)

    def _record_at(self, track, length: int, last_backed: bool, timestamp,
                   prob_detect: float) -> None:
        """:meth:`_record` with the track's length and whether its last state is
        detection-backed already known (the array JPDA path knows both)."""
        log = self.__dict__.get("_pd_log")
        if log is None:
            log = self.__dict__["_pd_log"] = PDRecord()
        log.record(track, length, timestamp, prob_detect, restart=last_backed)

    def recorded_prob_detect(self, track, index: int = -1) -> float | None:
        """The :math:`P_D` this hypothesiser used for the state at ``index`` of ``track``
        (the state appended after the ``hypothesise`` call), or ``None`` if it produced no
        record for that state (another component made it, or its timestamp does not match
        the scan's). Records before the track's last detection-backed state are dropped."""
        if not isinstance(index, (int, np.integer)):
            raise TypeError(f"index: expected an int, got {type(index).__name__}")
        n = len(track)
        if index < 0:
            index += n
        if not 0 <= index < n:
            raise IndexError(f"index: {index} out of range for a track of {n} states")
        log = self.__dict__.get("_pd_log")
        return None if log is None else log.get(track, index, track[index].timestamp)

    def __getstate__(self):  # (without the per-scan clutter cache)
        return {k: v for k, v in self.__dict__.items() if k != "_clutter_cache"}


__all__ = ["PDAHypothesiser", "gate_threshold", "is_detection_backed", "prob_detect_at"]
