"""Detector contexts that are not ctxmodels' own.

Stone Soup's interface (dstl/Stone-Soup#1291) asks a context two things, one at a time:
``prob_detection(hypothesis)`` and ``clutter_spatial_density(detection)``. ctxmodels' drop-ins
evaluate a whole scan in one array call, with the array methods of
:class:`~ctxmodels.DetectorContext`. :func:`as_array_context` gives them those methods for
any context: ctxmodels' own pass through; any other object with the two per-call methods is
wrapped in a :class:`PerCallContext`, which asks it once per state and once per detection, so
the drop-ins compute with the same values they would get from the context directly.

P_D belongs to the predicted state: the wrapper asks with a missed-detection hypothesis on
that state (a hypothesis without a measurement), the same for every hypothesis of one
prediction, as the drop-ins evaluate P_D once per prediction.
"""
from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from stonesoup.types.detection import MissedDetection
from stonesoup.types.hypothesis import SingleHypothesis
from stonesoup.types.prediction import GaussianStatePrediction, StatePrediction

#: The per-call methods of Stone Soup's interface.
CALL_METHODS = ("prob_detection", "clutter_spatial_density")


def as_array_context(detector_context, *methods: str):
    """``detector_context`` with the array ``methods`` a drop-in calls (ctxmodels'
    ``prob_detection_states``, ``prob_detection_array``, ``clutter_spatial_density_detections``):
    itself when it has them (a ctxmodels context, or a user's array context), else a
    :class:`PerCallContext` around it. TypeError naming ``detector_context`` when it has
    neither those nor Stone Soup's two per-call methods."""
    if all(callable(getattr(detector_context, m, None)) for m in methods):
        return detector_context
    if all(callable(getattr(detector_context, m, None)) for m in CALL_METHODS):
        return PerCallContext(detector_context)
    raise TypeError(f"detector_context: expected a detector context with "
                    f"prob_detection(hypothesis) and clutter_spatial_density(detection) (or "
                    f"the array methods {', '.join(methods)}), got "
                    f"{type(detector_context).__name__}")


def _hypothesis(prediction) -> SingleHypothesis:
    """A missed-detection hypothesis on ``prediction``: what P_D is asked about."""
    return SingleHypothesis(prediction, MissedDetection(timestamp=prediction.timestamp))


class PerCallContext:
    """Any context with ``prob_detection(hypothesis)`` and
    ``clutter_spatial_density(detection)``, seen through ctxmodels' array methods: a call per
    state and a call per detection, each answer checked (P_D a probability, λ finite and
    > 0), returned as float64 arrays."""

    def __init__(self, context):
        self.context = context

    def __repr__(self):
        return f"PerCallContext({self.context!r})"

    # --- the per-call interface, passed through ------------------------------------------
    def prob_detection(self, hypothesis):
        return self.context.prob_detection(hypothesis)

    def clutter_spatial_density(self, detection):
        return self.context.clutter_spatial_density(detection)

    # --- the array interface -------------------------------------------------------------
    def prob_detection_states(self, states: Sequence) -> np.ndarray:
        """P_D of each state (any Stone Soup state, Gaussian or particles)."""
        return self._probabilities([self.context.prob_detection(_hypothesis(s)) for s in states])

    def prob_detection_array(self, means, covars=None, *, out=None) -> np.ndarray:
        """P_D of N states given as (N, D) ``means`` (and, optionally, (N, D, D) ``covars``:
        the states are then Gaussian predictions)."""
        means = np.asarray(means, dtype=np.float64)
        if means.ndim != 2:
            raise ValueError(f"means: must be (N, D), got shape {means.shape}")
        if covars is None:
            states = [StatePrediction(row.reshape(-1, 1)) for row in means]
        else:
            covars = np.asarray(covars, dtype=np.float64)
            states = [GaussianStatePrediction(row.reshape(-1, 1), covar)
                      for row, covar in zip(means, covars)]
        values = self.prob_detection_states(states)
        if out is None:
            return values
        out[...] = values
        return out

    def clutter_spatial_density_detections(self, detections: Sequence,
                                           positions=None) -> np.ndarray:
        """λ of each detection (``positions`` is accepted for the array interface and not
        needed: the context reads the detections)."""
        values = [self.context.clutter_spatial_density(d) for d in detections]
        out = np.array([float(v) for v in values], dtype=np.float64)
        bad = [i for i, v in enumerate(out) if not (math.isfinite(v) and v > 0)]
        if bad:
            raise ValueError(f"detector_context: clutter_spatial_density must be finite and "
                             f"> 0, got {out[bad[0]]} for detection {bad[0]}")
        return out

    @staticmethod
    def _probabilities(values) -> np.ndarray:
        out = np.array([float(v) for v in values], dtype=np.float64)
        bad = [i for i, v in enumerate(out) if not 0.0 <= v <= 1.0]
        if bad:
            raise ValueError(f"detector_context: prob_detection (P_D) must lie in [0, 1], got "
                             f"{out[bad[0]]} for state {bad[0]}")
        return out


__all__ = ["CALL_METHODS", "PerCallContext", "as_array_context"]
