"""Which GM-PHD configurations the scan core runs, and what each asks of it.

:class:`~ctxmodels.stonesoup.ArrayPointProcessTracker` reads its components every scan
into a :class:`_Plan` — the numbers the core's predict, update and reduce take — or learns
that the configuration is one the core does not cover (see that tracker's docstring for
the list), and runs the scan through the component path instead.
"""
from __future__ import annotations

import numpy as np
from stonesoup.hypothesiser.distance import DistanceHypothesiser
from stonesoup.hypothesiser.gaussianmixture import GaussianMixtureHypothesiser
from stonesoup.measures import Mahalanobis, SquaredMahalanobis
from stonesoup.mixturereducer.gaussianmixture import GaussianMixtureReducer
from stonesoup.models.measurement.linear import LinearGaussian
from stonesoup.updater.kalman import ExtendedKalmanUpdater, KalmanUpdater
from stonesoup.updater.pointprocess import PHDUpdater as _StockPHDUpdater

from .._batch import supports_predictor
from ..models import core_measurement_model
from .updater import PHDUpdater

_KALMAN = (KalmanUpdater, ExtendedKalmanUpdater)
#: Core measurement models by (model value, state dimension, updater types).
_SCAN_MODELS: dict = {}
_MISSING = object()
_UINT64_MAX = int(np.iinfo(np.uint64).max)


def _plain_kalman(updater) -> bool:
    return (type(updater) in _KALMAN and not updater.use_joseph_cov
            and not updater.force_positive_definite_covariance)


class _Plan:
    """What a supported configuration asks of the core, read from the components."""

    def __init__(self, hypothesiser, updater, reducer):
        self._read(hypothesiser.hypothesiser, updater, updater.updater, reducer)

    def _read(self, inner, updater, measurement_updater, reducer) -> None:
        self.predictor = inner.predictor
        self.measurement_updater = measurement_updater
        self.gate_updater = inner.updater
        self.missed_distance = float(inner.missed_distance)
        self.squared = type(inner.measure) is SquaredMahalanobis
        self.include_all = bool(inner.include_all)
        self.prob_survival = float(updater.prob_survival)
        self.prob_detection = float(updater.prob_detection)
        self.clutter = float(updater.clutter_spatial_density)
        self.normalise = bool(updater.normalisation)
        self.force_symmetric = bool(measurement_updater.force_symmetric_covariance)
        self.reduce = dict(
            pruning=bool(reducer.pruning), prune_threshold=float(reducer.prune_threshold),
            merging=bool(reducer.merging), merge_threshold=float(reducer.merge_threshold),
            truncating=bool(reducer.truncating),
            max_components=int(min(reducer.max_number_components, _UINT64_MAX)),
            kdtree_max_distance=(None if reducer.kdtree_max_distance is None
                                 else float(reducer.kdtree_max_distance)))

    @classmethod
    def read(cls, tracker) -> _Plan | str:
        """The plan of ``tracker``'s configuration, or why the core does not run it (a
        string, as :meth:`refusal`). Runs every scan, so each component's Properties are
        read once for both."""
        hypothesiser, updater, reducer = tracker.hypothesiser, tracker.updater, tracker.reducer
        refusal = cls._refusal(hypothesiser, updater, reducer)
        if refusal is not None:
            return refusal
        plan = object.__new__(cls)
        plan._read(hypothesiser.hypothesiser, updater, updater.updater, reducer)
        return plan

    @classmethod
    def of(cls, tracker) -> _Plan | None:
        if cls.refusal(tracker) is not None:
            return None
        return cls(tracker.hypothesiser, tracker.updater, tracker.reducer)

    @classmethod
    def refusal(cls, tracker) -> str | None:
        """Why the core does not run this configuration (None: it does)."""
        return cls._refusal(tracker.hypothesiser, tracker.updater, tracker.reducer)

    @staticmethod
    def _refusal(hypothesiser, updater, reducer) -> str | None:
        if type(hypothesiser) is not GaussianMixtureHypothesiser \
                or not hypothesiser.order_by_detection:
            return ("the hypothesiser is not a GaussianMixtureHypothesiser with "
                    "order_by_detection=True")
        inner = hypothesiser.hypothesiser
        if type(inner) is not DistanceHypothesiser or inner.predict_with_measurements:
            return "the inner hypothesiser is not a DistanceHypothesiser"
        measure = inner.measure
        if type(measure) not in (Mahalanobis, SquaredMahalanobis) or measure.mapping is not None \
                or getattr(measure, "mapping2", None) is not None:
            return "the measure is not a (Squared)Mahalanobis without mapping"
        if not supports_predictor(inner.predictor):
            return ("the predictor is not a Kalman one with a linear Gaussian transition "
                    "model")
        if type(updater) not in (PHDUpdater, _StockPHDUpdater):
            return f"the updater is a {type(updater).__name__}, not a PHD updater"
        if not (_plain_kalman(updater.updater) and _plain_kalman(inner.updater)):
            return ("the Kalman updaters are not plain (extended) Kalman updaters without "
                    "Joseph form or forced positive definiteness")
        if type(reducer) is not GaussianMixtureReducer:
            return "the reducer is not a GaussianMixtureReducer"
        return None

    def scan_model(self, model, ndim: int, key=None):
        """The core's form of one measurement model, or None if it has none (both updaters
        must linearise it as the core does). ``key``: the model's
        :func:`~ctxmodels.model_key.measurement_model_key`, if known; a value key (equal keys
        are bit-identical models) finds the core model built for an earlier scan."""
        cache_key = None
        if type(key) is tuple:
            cache_key = (key, ndim, type(self.measurement_updater), type(self.gate_updater))
            found = _SCAN_MODELS.get(cache_key, _MISSING)
            if found is not _MISSING:
                return found
        scan_model = self._scan_model(model, ndim)
        if cache_key is not None:
            if len(_SCAN_MODELS) >= 64:
                _SCAN_MODELS.clear()
            _SCAN_MODELS[cache_key] = scan_model  # (immutable, like the model's value)
        return scan_model

    def _scan_model(self, model, ndim: int):
        kinds = {type(self.measurement_updater), type(self.gate_updater)}
        if getattr(model, "ndim_state", None) != ndim or \
                (type(model) is not LinearGaussian and kinds != {ExtendedKalmanUpdater}):
            return None
        return core_measurement_model(model)[0]
