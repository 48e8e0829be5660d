r"""A batched drop-in for Stone Soup's Gaussian-mixture hypothesiser.

:class:`FastGaussianMixtureHypothesiser` takes the same Properties as
:class:`~stonesoup.hypothesiser.gaussianmixture.GaussianMixtureHypothesiser` (an underlying
:class:`~stonesoup.hypothesiser.distance.DistanceHypothesiser` and ``order_by_detection``) and
returns the same list of :class:`~stonesoup.types.multihypothesis.MultipleHypothesis`, but
computes a scan at once: all :math:`N` components predicted in stacked arrays, the
measurement prediction of each component under each measurement model of the scan, and the
distance of all :math:`N \times M` component–detection pairs,

.. math::
    d_{nj} = \sqrt{(\hat z_n - z_j)^T\, S_n^{-1}\, (\hat z_n - z_j)}

(squared for :class:`~stonesoup.measures.SquaredMahalanobis`), angle rows of
:math:`\hat z_n - z_j` wrapped as Stone Soup's angle types wrap them. A pair becomes a
:class:`~stonesoup.types.hypothesis.SingleDistanceHypothesis` when
:math:`d_{nj} <` ``missed_distance`` (all pairs with ``include_all``); every component also
gets its missed-detection hypothesis at distance ``missed_distance``. Python objects are
built only for the hypotheses that survive the gate.

Configurations it cannot reproduce exactly (another measure or predictor type, a measure
``mapping``, ``predict_with_measurements``, extra keyword arguments, non-Gaussian
components) run the stock code unchanged.
"""
from __future__ import annotations

import numpy as np
from stonesoup.hypothesiser.distance import DistanceHypothesiser
from stonesoup.hypothesiser.gaussianmixture import GaussianMixtureHypothesiser
from stonesoup.measures import Mahalanobis, SquaredMahalanobis
from stonesoup.types.detection import MissedDetection
from stonesoup.types.hypothesis import SingleDistanceHypothesis
from stonesoup.types.multihypothesis import MultipleHypothesis
from stonesoup.types.prediction import (
    GaussianStatePrediction,
    Prediction,
    TaggedWeightedGaussianStatePrediction,
    WeightedGaussianStatePrediction,
)
from stonesoup.types.array import CovarianceMatrix, StateVector
from stonesoup.types.state import GaussianState, TaggedWeightedGaussianState

from .fast import (
    ObjectFactory,
    apply_wrap,
    covariance_views,
    detection_vectors,
    from_state_target,
    gaussian_arrays,
    measurement_batch,
    predict_batch,
    supports_predictor,
    vector_views,
    wrap_plan,
)

_PLAIN_PREDICTIONS = (GaussianStatePrediction, WeightedGaussianStatePrediction,
                      TaggedWeightedGaussianStatePrediction)
_PROBE_STATE = dict(state_vector=StateVector([0.0]), covar=CovarianceMatrix([[1.0]]),
                    timestamp=None)
_PREDICTION_FACTORIES = {
    GaussianStatePrediction: ObjectFactory(GaussianStatePrediction, _PROBE_STATE),
    WeightedGaussianStatePrediction: ObjectFactory(WeightedGaussianStatePrediction,
                                                   dict(_PROBE_STATE, weight=0.5)),
    TaggedWeightedGaussianStatePrediction: ObjectFactory(
        TaggedWeightedGaussianStatePrediction, dict(_PROBE_STATE, weight=0.5, tag="probe")),
}
_HYPOTHESIS = ObjectFactory(SingleDistanceHypothesis,
                            dict(prediction=None, measurement=None, distance=1.0))
_MISSED_DETECTION = ObjectFactory(MissedDetection, dict(timestamp=None))
_GIVEN = frozenset(("state_vector", "covar", "timestamp"))
_PLAN_CACHE: dict = {}


def _prediction_plan(component_type: type):
    """(prediction factory, tagged?, names of Properties copied from the component) for
    ``Prediction.from_state(component, ...)``, or ``None`` if not a plain Gaussian type."""
    plan = _PLAN_CACHE.get(component_type)
    if plan is None:
        target = from_state_target(Prediction, component_type)
        tagged = issubclass(component_type, TaggedWeightedGaussianState)
        given = _GIVEN | {"tag"} if tagged else _GIVEN
        copied = tuple(name for name in component_type.properties
                       if name in target.properties and name not in given)
        plan = (_PREDICTION_FACTORIES[target], tagged, copied) \
            if target in _PLAIN_PREDICTIONS else ()
        _PLAN_CACHE[component_type] = plan
    return plan or None


class FastGaussianMixtureHypothesiser(GaussianMixtureHypothesiser):
    r"""Gaussian-mixture hypothesiser computing a whole scan in stacked arrays.

    Same Properties, inputs and outputs as
    :class:`~stonesoup.hypothesiser.gaussianmixture.GaussianMixtureHypothesiser`; the fast
    path applies when :attr:`hypothesiser` is a
    :class:`~stonesoup.hypothesiser.distance.DistanceHypothesiser` with a
    :class:`~stonesoup.measures.Mahalanobis` or
    :class:`~stonesoup.measures.SquaredMahalanobis` measure (no mapping), a Kalman or
    extended Kalman predictor with a linear Gaussian transition model, and Gaussian
    components. Measurement models are batched for linear Gaussian and (with an extended
    Kalman updater) bearing–range models; others use the stock ``predict_measurement`` once
    per component and model. Everything else runs the stock code.

    For each component, in input order (repeated objects once, as the stock dictionary
    does): a missed-detection hypothesis at ``missed_distance`` and one hypothesis per
    detection inside the gate, ordered by distance; each carries a new prediction built from
    the component (``Prediction.from_state``), the birth component's detection hypotheses
    with a fresh tag. With ``order_by_detection`` the list holds one
    :class:`~stonesoup.types.multihypothesis.MultipleHypothesis` per detection (in the set's
    iteration order, components in input order) and the missed detections last.
    """

    def _fast_path_ok(self, components, kwargs) -> bool:
        inner = self.hypothesiser
        if kwargs or type(inner) is not DistanceHypothesiser or inner.predict_with_measurements:
            return False
        measure = inner.measure
        if type(measure) not in (Mahalanobis, SquaredMahalanobis) or measure.mapping is not None:
            return False
        if not supports_predictor(inner.predictor):
            return False
        return all(isinstance(c, GaussianState) and _prediction_plan(type(c)) is not None
                   for c in components)

    def hypothesise(self, components, detections, timestamp, **kwargs):
        """Form the hypotheses of all components and detections of a scan (see the class
        docstring); the stock :meth:`GaussianMixtureHypothesiser.hypothesise` contract."""
        timestamps = {detection.timestamp for detection in detections}
        if len(timestamps) > 1:
            raise ValueError("All detections must have the same timestamp")
        components = list(dict.fromkeys(components))  # the stock dict's de-duplication
        if not self._fast_path_ok(components, kwargs):
            return super().hypothesise(components, detections, timestamp, **kwargs)

        inner = self.hypothesiser
        dets = list(detections)
        n_comp, n_det = len(components), len(dets)
        det_time = next(iter(timestamps)) if dets else timestamp

        means, covars = gaussian_arrays(components)
        miss_means, miss_covars = predict_batch(inner.predictor, components, means, covars,
                                                timestamp)
        if det_time == timestamp:
            det_means, det_covars = miss_means, miss_covars
        else:
            det_means, det_covars = predict_batch(inner.predictor, components, means, covars,
                                                  det_time)

        # distances of all pairs, per measurement model of the scan
        distances = np.full((n_comp, n_det), np.inf)
        pair_group = np.zeros(n_det, dtype=np.intp)
        batches = []
        groups: dict = {}
        for j, det in enumerate(dets):
            model = inner.updater._check_measurement_model(det.measurement_model)
            groups.setdefault(id(model), (model, []))[1].append(j)
        squared = type(inner.measure) is SquaredMahalanobis
        for g, (model, members) in enumerate(groups.values()):
            pair_group[members] = g
            if n_comp == 0:
                batches.append(None)
                continue
            batch = measurement_batch(inner.updater, model, det_means, det_covars, det_time)
            batches.append(batch)
            z, kinds = detection_vectors([dets[j] for j in members])
            plan = wrap_plan(batch.angle_rows, kinds, z.shape[1])
            diff = apply_wrap(z[np.newaxis, :, :] - batch.means[:, np.newaxis, :], plan)
            delta = apply_wrap(-diff, plan)  # Mahalanobis negates the typed difference
            inverse = np.linalg.inv(batch.covars)
            d2 = np.einsum("nji,nik,njk->nj", delta, inverse, delta)
            distances[:, members] = d2 if squared else np.sqrt(d2)

        missed_distance = inner.missed_distance
        gate = (np.ones_like(distances, dtype=bool) if inner.include_all
                else distances < missed_distance)

        miss_vectors, miss_covs = vector_views(miss_means), covariance_views(miss_covars)
        if det_means is miss_means:
            det_vectors, det_covs = miss_vectors, miss_covs
        else:
            det_vectors, det_covs = vector_views(det_means), covariance_views(det_covars)
        typed_cache: dict = {}

        per_component = []
        for n, component in enumerate(components):
            target, tagged, copied = _prediction_plan(type(component))
            common = {name: getattr(component, name) for name in copied}
            birth = tagged and component.tag == component.BIRTH
            kept = np.flatnonzero(gate[n])
            # [missed, detections in set order], stably sorted by distance as the stock
            # sorted(..., reverse=True) on SingleDistanceHypothesis does
            entries = [(missed_distance, -1)] + [(distances[n, j], j) for j in kept]
            entries.sort(key=lambda entry: entry[0])
            hyps = []
            for distance, j in entries:
                if j < 0:
                    extra = {"tag": component.BIRTH if birth else component.tag} if tagged else {}
                    prediction = target(state_vector=miss_vectors[n], covar=miss_covs[n],
                                        timestamp=timestamp, **common, **extra)
                    hyps.append(_HYPOTHESIS(
                        prediction=prediction, measurement=_MISSED_DETECTION(timestamp=timestamp),
                        distance=missed_distance))
                    continue
                extra = {"tag": None if birth else component.tag} if tagged else {}
                prediction = target(state_vector=det_vectors[n], covar=det_covs[n],
                                    timestamp=det_time, **common, **extra)
                g = pair_group[j]
                key = (n, g)
                meas_pred = typed_cache.get(key)
                if meas_pred is None:
                    meas_pred = batches[g].measurement_prediction(n, det_time)
                    typed_cache[key] = meas_pred
                hyps.append(_HYPOTHESIS(
                    prediction=prediction, measurement=dets[j], distance=distance,
                    measurement_prediction=meas_pred))
            per_component.append(hyps)

        if not self.order_by_detection:
            # stock wraps each component's MultipleHypothesis in another one
            return [MultipleHypothesis(MultipleHypothesis(hyps)) for hyps in per_component]
        by_detection = [[] for _ in range(n_det)]
        missed = []
        index = {id(det): j for j, det in enumerate(dets)}
        for hyps in per_component:
            for hyp in hyps:
                if hyp:
                    by_detection[index[id(hyp.measurement)]].append(hyp)
                else:
                    missed.append(hyp)
        return [MultipleHypothesis(hyps) for hyps in by_detection] + [MultipleHypothesis(missed)]


__all__ = ["FastGaussianMixtureHypothesiser"]
