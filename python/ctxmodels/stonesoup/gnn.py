r"""A batched drop-in for Stone Soup's global-nearest-neighbour 2-D assignment associator.

:class:`FastGNNWith2DAssignment` takes the same Properties as
:class:`~stonesoup.dataassociator.neighbour.GNNWith2DAssignment` (a
:class:`~stonesoup.hypothesiser.distance.DistanceHypothesiser`) and returns the same
track → hypothesis mapping. The stock associator asks its hypothesiser for one track at a
time, and the hypothesiser predicts the track, predicts the measurement and evaluates the
distance for each detection in turn, in Python. This one works a scan at a time: for
:math:`N` tracks with last states :math:`(x_n, P_n)` and :math:`M` detections :math:`z_j`,

* all tracks are predicted to each distinct time of the scan in stacked arrays
  (:func:`~ctxmodels.stonesoup._batch.predict_batch`),
* the predicted measurements :math:`\hat z_n` and innovation covariances :math:`S_n` of all
  tracks are computed once per measurement model
  (:func:`~ctxmodels.stonesoup._batch.measurement_batch`), and
* the squared Mahalanobis distances of all :math:`N \times M` pairs,

  .. math::
      d^2_{nj} = \delta_{nj}^T\, S_n^{+}\, \delta_{nj}, \qquad
      \delta_{nj} = \hat z_n - z_j \ \text{(angle rows wrapped)},

  come from one array expression, :math:`S_n^{+}` the pseudo-inverse the stock measure uses.

These array distances only *screen* the pairs: a pair whose :math:`d^2_{nj}` exceeds the
gate (``missed_distance``, squared for :class:`~stonesoup.measures.Mahalanobis`) by more
than :math:`10^{-6} \sum_{k,l} |\delta_k S^{+}_{kl} \delta_l|` cannot pass it — the array
sum and the stock one differ only in summation order, a few units in the last place of that
bound. Every other pair (typically a handful per scan) gets its distance from the stock
measure on the stock-equal measurement prediction, so the hypotheses carry the stock
distances bit for bit and the gate decides exactly as the stock one does. The assignment
then runs the stock algorithm on the stock cost matrix (rows: tracks with a detection
hypothesis, in input order; columns: detections in iteration order, then one
missed-detection column per row), so ties are broken identically.

Object semantics follow the stock caches (the predictor's and updater's ``lru_cache``):
per track, one prediction per distinct time (the missed-detection hypothesis shares it
with detections stamped at the scan time) and one measurement prediction per prediction
and measurement model, shared by that track's hypotheses. Predictions are built as
``Prediction.from_state`` builds them (transition model, prior, and the prior's weak
reference to its own predecessor).

Configurations it does not reproduce run the stock code: extra keyword arguments, a
hypothesiser other than a plain :class:`~stonesoup.hypothesiser.distance.DistanceHypothesiser`,
``predict_with_measurements``, measures other than (squared) Mahalanobis without a
mapping, predictors other than a Kalman / extended Kalman predictor with a linear Gaussian
transition model, detections with value equality. Tracks whose state is not a plain
Gaussian (one whose prediction is a
:class:`~stonesoup.types.prediction.GaussianStatePrediction`) are hypothesised by the stock
hypothesiser, the rest batched. Measurement models other than linear Gaussian and (extended
Kalman) bearing–range (the stock model or
:class:`~ctxmodels.stonesoup.models.AnalyticCartesianToBearingRange`) use the stock
``predict_measurement`` on the batched predictions.
"""
from __future__ import annotations

import weakref

import numpy as np
from stonesoup.dataassociator import neighbour as _stock_neighbour
from stonesoup.dataassociator.neighbour import GNNWith2DAssignment
from stonesoup.hypothesiser.distance import DistanceHypothesiser
from stonesoup.measures import Mahalanobis, SquaredMahalanobis
from stonesoup.models.measurement.linear import LinearGaussian
from stonesoup.models.measurement.nonlinear import CartesianToBearingRange
from stonesoup.types.array import CovarianceMatrix, Matrix, StateVector
from stonesoup.types.detection import MissedDetection
from stonesoup.types.hypothesis import SingleDistanceHypothesis
from stonesoup.types.multihypothesis import MultipleHypothesis
from stonesoup.types.prediction import (
    GaussianMeasurementPrediction,
    GaussianStatePrediction,
    Prediction,
)
from stonesoup.types.state import GaussianState, State, StateMutableSequence
from stonesoup.updater.kalman import ExtendedKalmanUpdater

from .._upstream import check_measurement_model
from ._batch import (
    KALMAN_UPDATERS,
    ObjectFactory,
    apply_wrap,
    covariance_views,
    detection_vectors,
    from_state_target,
    measurement_batch,
    predict_batch,
    supports_predictor,
    vector_views,
    wrap_plan,
)
from .models import AnalyticCartesianToBearingRange

#: Screening margin, relative to :math:`\sum |\delta_k S^+_{kl} \delta_l|` (see module doc).
SCREEN_MARGIN = 1e-6

_PREDICTION = ObjectFactory(GaussianStatePrediction, dict(
    state_vector=StateVector([0.0]), covar=CovarianceMatrix([[1.0]]), timestamp=None,
    transition_model=None, prior=None))
_HYPOTHESIS = ObjectFactory(SingleDistanceHypothesis,
                            dict(prediction=None, measurement=None, distance=1.0))
_MISSED = ObjectFactory(MissedDetection, dict(timestamp=None))
_MULTIPLE = ObjectFactory(MultipleHypothesis, dict(single_hypotheses=[]))
_MEASUREMENT_PREDICTION = ObjectFactory(GaussianMeasurementPrediction, dict(
    state_vector=StateVector([0.0]), covar=CovarianceMatrix([[1.0]]), timestamp=None,
    cross_covar=Matrix([[1.0]])))
_GIVEN = frozenset(("state_vector", "covar", "timestamp", "transition_model", "prior"))
_COPIED: dict = {}


def _copied_properties(state_type: type):
    """Names of the Properties ``Prediction.from_state`` copies from a prior of
    ``state_type`` (beyond those the predictor passes), or ``None`` when its prediction is
    not a plain :class:`GaussianStatePrediction`."""
    if state_type not in _COPIED:
        copied = None
        if issubclass(state_type, GaussianState):
            try:
                target = from_state_target(Prediction, state_type)
            except TypeError:
                target = None
            if target is GaussianStatePrediction:
                copied = tuple(name for name in state_type.properties
                               if name in target.properties and name not in _GIVEN)
        _COPIED[state_type] = copied
    return _COPIED[state_type]


def _identity_equality(detections) -> bool:
    """Whether every detection compares by identity (as the stock ``list.index`` lookup
    then finds exactly that object)."""
    return all(kind.__eq__ is object.__eq__ for kind in {type(d) for d in detections})


def _batchable_model(updater, model) -> bool:
    kind = type(updater)
    if kind not in KALMAN_UPDATERS:
        return False
    if type(model) is LinearGaussian:
        return True
    if kind is not ExtendedKalmanUpdater:
        return False
    if type(model) is AnalyticCartesianToBearingRange:
        return True
    return type(model) is CartesianToBearingRange and len(model.mapping) == 2


class _Predictions:
    """Batched predictions of the fast tracks to one time, turned into Stone Soup objects on
    demand (one per track, as the predictor's cache would return)."""

    def __init__(self, predictor, priors, means, covars, timestamp):
        self.timestamp = timestamp
        self.priors = priors
        self.transition_model = predictor.transition_model
        self.means, self.covars = predict_batch(predictor, priors, means, covars, timestamp)
        self._vectors = vector_views(self.means)
        self._covs = covariance_views(self.covars)
        self._objects = [None] * len(priors)

    def __getitem__(self, n):
        prediction = self._objects[n]
        if prediction is None:
            prior = self.priors[n]
            copied = _copied_properties(type(prior))
            prediction = _PREDICTION(
                state_vector=self._vectors[n], covar=self._covs[n], timestamp=self.timestamp,
                transition_model=self.transition_model, prior=prior,
                **{name: getattr(prior, name) for name in copied})
            _weaken_prior_chain(prior)
            self._objects[n] = prediction
        return prediction


def _weaken_prior_chain(prior):
    """What constructing a :class:`Prediction` does to its prior: the prediction the prior
    was updated from keeps its own prior only by weak reference (memory of long tracks)."""
    hypothesis = getattr(prior, "hypothesis", None)
    if hasattr(hypothesis, "prediction"):
        earlier = getattr(hypothesis.prediction, "prior", None)
        if earlier is not None:
            hypothesis.prediction.prior = weakref.ref(earlier)


def _measurement_prediction(batch, n, timestamp):
    """The updater's ``predict_measurement`` result for track ``n`` of ``batch``: the cross
    covariance stays the plain :class:`Matrix` the stock product ``P @ H.T`` gives."""
    return _MEASUREMENT_PREDICTION(
        state_vector=batch.typed_vector(n), covar=batch.covars[n].view(CovarianceMatrix),
        timestamp=timestamp, cross_covar=batch.cross_covars[n].view(Matrix))


def screen_pairs(batch, dets, missed_distance: float, squared: bool,
                 invert=np.linalg.pinv) -> np.ndarray:
    """``(N, K)`` mask of the track × detection pairs that may pass the gate (see the module
    docstring), the innovation covariances inverted by ``invert`` (the stock measure's
    pinv by default); every pair when the arrays cannot be formed (the stock measure then
    decides, or raises its own error)."""
    everything = np.ones((len(batch.means), len(dets)), dtype=bool)
    try:
        z, kinds = detection_vectors(dets)
        if z.ndim != 2 or z.shape[1] != batch.means.shape[1]:
            return everything
        plan = wrap_plan(batch.angle_rows, kinds, z.shape[1])
        # the measure's  -(z - ẑ), each step wrapped as the typed vectors wrap it
        delta = apply_wrap(-apply_wrap(z[np.newaxis] - batch.means[:, np.newaxis], plan), plan)
        inverse = invert(batch.covars)
    except (ValueError, TypeError, np.linalg.LinAlgError):
        return everything
    terms = delta[:, :, :, np.newaxis] * inverse[:, np.newaxis] * delta[:, :, np.newaxis, :]
    d2 = terms.sum(axis=(2, 3))
    slack = SCREEN_MARGIN * np.abs(terms).sum(axis=(2, 3))
    if squared:
        threshold = missed_distance
    elif missed_distance > 0:
        threshold = missed_distance * missed_distance
    else:
        # a square root is never below a non-positive gate (NaN is not below anything)
        return np.zeros_like(everything)
    with np.errstate(invalid="ignore", over="ignore"):
        return ~(d2 - slack > threshold)  # NaN stays a candidate: the measure decides


class FastGNNWith2DAssignment(GNNWith2DAssignment):
    r"""Global nearest neighbour by 2-D assignment, hypotheses computed a scan at a time.

    Same Properties, inputs and outputs as
    :class:`~stonesoup.dataassociator.neighbour.GNNWith2DAssignment`. With a
    :class:`~stonesoup.hypothesiser.distance.DistanceHypothesiser` using a
    :class:`~stonesoup.measures.Mahalanobis` or :class:`~stonesoup.measures.SquaredMahalanobis`
    measure and a Kalman predictor with a linear Gaussian transition model, the predictions,
    measurement predictions and distances of all tracks and detections of a scan are
    computed in stacked arrays; the hypotheses, their distances, the gate and the
    assignment equal the stock ones exactly (see the module docstring). Anything else runs
    the stock code.
    """

    def _batched(self, kwargs) -> bool:
        hypothesiser = self.hypothesiser
        if kwargs or type(hypothesiser) is not DistanceHypothesiser \
                or hypothesiser.predict_with_measurements:
            return False
        measure = hypothesiser.measure
        if type(measure) not in (Mahalanobis, SquaredMahalanobis) or measure.mapping is not None:
            return False
        return supports_predictor(hypothesiser.predictor)

    # --- hypotheses -------------------------------------------------------------------------
    def generate_hypotheses(self, tracks, detections, timestamp, **kwargs):
        """``{track: MultipleHypothesis}`` for every track, in iteration order: what the
        hypothesiser returns track by track, computed for the whole scan at once."""
        if not self._batched(kwargs):
            return super().generate_hypotheses(tracks, detections, timestamp, **kwargs)
        tracks = list(dict.fromkeys(tracks))  # the stock dict keeps each track once
        dets = list(detections)
        hypothesiser = self.hypothesiser
        ndim = hypothesiser.predictor.transition_model.ndim_state

        fast, priors = [], []
        for track in tracks:
            prior = track.state if isinstance(track, StateMutableSequence) \
                and not isinstance(track, State) else track
            vector, covar = getattr(prior, "state_vector", None), getattr(prior, "covar", None)
            if _copied_properties(type(prior)) is not None \
                    and isinstance(vector, np.ndarray) and vector.dtype == np.float64 \
                    and vector.shape == (ndim, 1) and isinstance(covar, np.ndarray) \
                    and covar.dtype == np.float64 and covar.shape == (ndim, ndim):
                fast.append(track)
                priors.append(prior)
        batched = self._hypothesise_batch(fast, priors, dets, timestamp) if fast else {}
        return {track: batched[track] if track in batched
                else hypothesiser.hypothesise(track, detections, timestamp)
                for track in tracks}

    def _hypothesise_batch(self, tracks, priors, dets, timestamp):
        hypothesiser = self.hypothesiser
        predictor, updater, measure = (hypothesiser.predictor, hypothesiser.updater,
                                       hypothesiser.measure)
        missed_distance = hypothesiser.missed_distance
        include_all = hypothesiser.include_all
        n_tracks = len(tracks)
        means = np.array([p.state_vector for p in priors], dtype=np.float64)
        covars = np.array([p.covar for p in priors], dtype=np.float64)

        # one prediction per distinct time, the scan time first (the missed detections')
        times = {timestamp: 0}
        det_time = [times.setdefault(d.timestamp, len(times)) for d in dets]
        predictions = [_Predictions(predictor, priors, means, covars, t) for t in times]

        # detections grouped by (time, measurement model): one measurement prediction per
        # track and group, as the updater's cache keys them
        groups: dict = {}
        for j, det in enumerate(dets):
            groups.setdefault((det_time[j], det.measurement_model), []).append(j)

        candidates = np.zeros((n_tracks, len(dets)), dtype=bool)
        group_of = np.empty(len(dets), dtype=np.intp)
        group_info = []
        for g, ((ti, raw_model), members) in enumerate(groups.items()):
            group_of[members] = g
            model = check_measurement_model(updater, raw_model)
            batch = None
            if _batchable_model(updater, model):
                batch = measurement_batch(updater, model, predictions[ti].means,
                                          predictions[ti].covars)
                if include_all:
                    candidates[:, members] = True
                else:
                    candidates[:, members] = self._screen(batch, [dets[j] for j in members])
            else:
                candidates[:, members] = True
            group_info.append((ti, raw_model, batch, {}))

        result = {}
        pairs = {}  # track → its candidate detections, in detection order
        for n, j in zip(*np.nonzero(candidates)):
            pairs.setdefault(int(n), []).append(int(j))
        for n, track in enumerate(tracks):
            hypotheses = [_HYPOTHESIS(prediction=predictions[0][n],
                                      measurement=_MISSED(timestamp=timestamp),
                                      distance=missed_distance)]
            for j in pairs.get(n, ()):
                ti, raw_model, batch, cache = group_info[group_of[j]]
                prediction = predictions[ti][n]
                measurement_prediction = cache.get(n)
                if measurement_prediction is None:
                    if batch is None:
                        measurement_prediction = updater.predict_measurement(prediction,
                                                                             raw_model)
                    else:
                        measurement_prediction = _measurement_prediction(
                            batch, n, prediction.timestamp)
                    cache[n] = measurement_prediction
                det = dets[j]
                distance = measure(measurement_prediction, det)
                if include_all or distance < missed_distance:
                    hypotheses.append(_HYPOTHESIS(
                        prediction=prediction, measurement=det, distance=distance,
                        measurement_prediction=measurement_prediction))
            result[track] = _MULTIPLE(single_hypotheses=sorted(hypotheses, reverse=True))
        return result

    def _screen(self, batch, dets) -> np.ndarray:
        """``(N, K)`` mask of the pairs that may pass the gate (see the module docstring)."""
        hypothesiser = self.hypothesiser
        return screen_pairs(batch, dets, float(hypothesiser.missed_distance),
                            type(hypothesiser.measure) is SquaredMahalanobis)

    # --- assignment ---------------------------------------------------------------------------
    def associate(self, tracks, detections, timestamp, **kwargs):
        """Associate detections with tracks: the stock
        :meth:`GNNWith2DAssignment.associate` result, from the batched hypotheses."""
        if not self._batched(kwargs) or not _identity_equality(detections):
            return super().associate(tracks, detections, timestamp, **kwargs)
        hypotheses = self.generate_hypotheses(tracks, detections, timestamp)

        detected = [track for track, multi in hypotheses.items() if any(multi)]
        associations = {}
        # undetected tracks first, in the order of the stock set difference, with their
        # (only) missed-detection hypothesis
        for track in hypotheses.keys() - set(detected):
            if hypotheses[track]:
                associations[track] = hypotheses[track][0]
        if not detected:
            return associations

        dets = list(detections)
        column_of = {}
        for j, det in enumerate(dets):
            column_of.setdefault(id(det), j)  # first occurrence, as list.index finds it
        n_dets = len(dets)
        costs = np.full((len(detected), n_dets + len(detected)), np.inf)
        chosen = []
        for i, track in enumerate(detected):
            cells = {}
            for hypothesis in hypotheses[track]:
                column = column_of[id(hypothesis.measurement)] if hypothesis else n_dets + i
                cells[column] = hypothesis
            for column, hypothesis in cells.items():
                costs[i, column] = hypothesis.distance
            chosen.append(cells)
        try:
            _, col4row = _stock_neighbour.linear_sum_assignment(costs, False)
        except ValueError:
            raise RuntimeError("Assignment was not feasible") from None
        for i, track in enumerate(detected):
            associations[track] = chosen[i].get(int(col4row[i]))
        return associations


__all__ = ["FastGNNWith2DAssignment"]
