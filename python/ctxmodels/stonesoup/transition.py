"""A transition model that computes F(Δt) and Q(Δt) once per time interval.

Stone Soup rebuilds the transition matrix and noise covariance of a combined model (a
``scipy.linalg.block_diag`` per call) for every prediction of every track and component.
Asynchronous sensors produce only a handful of distinct scan intervals, so caching per
Δt removes that cost without changing a single number: the cached arrays are the ones the
stock model returns for that interval. :class:`ControlTerms` does the same for a Kalman
prediction's control terms (the array JPDA and initiator ask it whether there are any).
"""
from __future__ import annotations

import numpy as np
from stonesoup.models.control.linear import LinearControlModel
from stonesoup.models.transition.linear import CombinedLinearGaussianTransitionModel


class CachedCombinedLinearGaussianTransitionModel(CombinedLinearGaussianTransitionModel):
    """:class:`~stonesoup.models.transition.linear.CombinedLinearGaussianTransitionModel`
    with F and Q memoised per ``time_interval`` (returned read-only, so a caller that tried
    to modify a shared array would fail loudly instead of corrupting later predictions)."""

    #: Distinct intervals kept; asynchronous scans make a few, a long run a few hundred.
    max_cached = 4096

    def _memo(self, kind, compute, kwargs):
        # A linear Gaussian model's F and Q depend on Δt only; predictors also pass the
        # `prior`, which they do not use. Anything else: no caching.
        for name in kwargs:
            if name != "time_interval" and name != "prior":
                return compute(**kwargs)
        cache = self.__dict__.setdefault("_cached_arrays", {})
        key = (kind, kwargs.get("time_interval"))
        value = cache.get(key)
        if value is None:
            value = compute(**kwargs)
            value.flags.writeable = False
            if len(cache) >= self.max_cached:
                cache.clear()
            cache[key] = value
        return value

    def matrix(self, **kwargs):
        return self._memo("F", super().matrix, kwargs)

    def covar(self, **kwargs):
        return self._memo("Q", super().covar, kwargs)

    def __getstate__(self):
        state = dict(self.__dict__)
        state.pop("_cached_arrays", None)
        return state


class ControlTerms:
    """The control model's contribution to a Kalman prediction (the offset
    ``control.function(None, …)`` and the noise ``B Q_u Bᵀ``), as the predictor computes
    them, memoised per time interval for the stock :class:`LinearControlModel` (whose
    matrix and noise do not depend on the prior; the models are immutable, as the cached
    transition model assumes); any other control model is called every time."""

    def __init__(self):
        self._cache: dict = {}
        self._answers: dict = {}  # the same keys -> (control, adds_input's answer)

    def adds_input(self, control, prior, interval) -> bool:
        """Whether the terms over ``interval`` are not all zero (as float64 arrays), the
        answer kept with the terms (the stock model's)."""
        key = None
        if type(control) is LinearControlModel:
            key = (id(control), id(control.control_matrix), id(control.control_noise), interval)
            found = self._answers.get(key)
            if found is not None and found[0] is control:
                return found[1]
        offset, noise = self(control, prior, interval)
        answer = bool(np.asarray(offset, dtype=np.float64).any()
                      or np.asarray(noise, dtype=np.float64).any())
        if key is not None:
            if len(self._answers) >= 256:
                self._answers.clear()
            self._answers[key] = (control, answer)
        return answer

    def __call__(self, control, prior, interval):
        cacheable = type(control) is LinearControlModel
        if cacheable:
            key = (id(control), id(control.control_matrix), id(control.control_noise), interval)
            found = self._cache.get(key)
            if found is not None and found[0] is control:
                return found[1], found[2]
        offset = control.function(None, prior=prior, time_interval=interval)
        ctrl = control.matrix(control_input=None, prior=prior, time_interval=interval)
        noise = ctrl @ control.control_noise @ ctrl.T
        if cacheable:
            if len(self._cache) >= 256:
                self._cache.clear()
            self._cache[key] = (control, offset, noise)
        return offset, noise
