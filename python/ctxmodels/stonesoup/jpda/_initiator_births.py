"""The new holding tracks of :class:`~ctxmodels.stonesoup.ArrayMultiMeasurementInitiator`:
what Stone Soup's :class:`~stonesoup.initiator.simple.SimpleMeasurementInitiator` returns for
a scan's unassociated detections, computed per measurement model in stacked arrays with the
stock operations (the same numbers, bit for bit), and the tracks built without Stone Soup's
per-Property constructor.
"""
from __future__ import annotations

import uuid

import numpy as np
from stonesoup.initiator.simple import SimpleMeasurementInitiator
from stonesoup.models.measurement import nonlinear as _nonlinear
from stonesoup.models.measurement.linear import LinearGaussian
from stonesoup.models.measurement.nonlinear import CartesianToBearingRange
from stonesoup.types.angle import Bearing
from stonesoup.types.array import CovarianceMatrix, StateVector
from stonesoup.types.hypothesis import SingleHypothesis
from stonesoup.types.state import GaussianState
from stonesoup.types.track import Track
from stonesoup.types.update import GaussianStateUpdate, Update

from ...model_key import models_by_value, scan_model_groups
from .._batch import ObjectFactory, _analytic_bearing_range_batch, _bearing_range_batch
from ..measurement import AnalyticCartesianToBearingRange

#: An update as ``Update.from_state`` builds it from a Gaussian prediction or prior state.
UPDATE_STATE = ObjectFactory(GaussianStateUpdate, dict(
    state_vector=StateVector([0.0]), covar=CovarianceMatrix([[1.0]]),
    hypothesis=SingleHypothesis(None, None), timestamp=None))

#: The initiator's hypothesis of a detection (no prediction).
_HYPOTHESIS = ObjectFactory(SingleHypothesis, dict(prediction=None, measurement=None))

_FLOATS = (float, np.float64)


class _TrackFactory:
    """``Track([state])`` for a :class:`Track` (exactly): the instance dictionary its
    constructor builds (states, a fresh uuid4 id, empty initial metadata, the metadata
    history from the state, by the stock method), checked once against the constructor;
    the constructor itself if the two ever differ."""

    def __init__(self):
        self.fast = None  # unknown until the first track

    def _build(self, state):
        track = object.__new__(Track)
        track.__dict__ = {"_property_states": [state], "_property_id": str(uuid.uuid4()),
                          "_property_init_metadata": {}, "metadatas": []}
        Track._update_metadata_from_state(track, state)
        return track

    def __call__(self, state):
        if self.fast is None:
            real = Track([state])
            built = self._build(state)
            ours, theirs = dict(built.__dict__), dict(real.__dict__)
            self.fast = (type(ours.pop("_property_id", None)) is str
                         and type(theirs.pop("_property_id", None)) is str and ours == theirs
                         and ours["_property_states"][0] is theirs["_property_states"][0])
            return real
        return self._build(state) if self.fast else Track([state])


def inverse_bearing_range(model, detections, rows=None) -> list:
    """``model.inverse_function(det)`` of a 2-D bearing–range model for each detection, with
    the same operations. A detection typed (Bearing, float), as the model's own measurements
    are, runs the stock code on object arrays: ``ρ cos φ`` and ``ρ sin φ`` (the Bearing's own
    NumPy cosine and sine), then the inverse rotation as an object product (Python floats,
    ``(a₀x + a₁y) + a₂·0``, in order) plus the offset; float arrays compute the same bits
    for all such detections at once. Others take the stock function's steps one by one.
    ``rows``: the detections' vectors converted to float rows ``(M, 2)``, if known."""
    if not (model.rotation_offset[0] == 0 and model.rotation_offset[1] == 0):
        return [model.inverse_function(det) for det in detections]  # the stock error
    inverse_rotation = _nonlinear.inv(model.rotation_matrix)
    offset = model.translation_offset[:2, :]
    mapping = model.mapping[:2]
    out: list = [None] * len(detections)
    typed = [k for k, det in enumerate(detections) if _bearing_typed(det.state_vector)]
    if typed and type(inverse_rotation) is np.ndarray and inverse_rotation.shape == (3, 3) \
            and inverse_rotation.dtype == np.float64 and offset.dtype == np.float64:
        if rows is not None:
            z = rows[typed]
        else:
            z = np.array([detections[k].state_vector for k in typed], dtype=np.float64)[:, :, 0]
        x, y = z[:, 1] * np.cos(z[:, 0]), z[:, 1] * np.sin(z[:, 0])
        vectors = np.zeros((len(typed), model.ndim_state, 1))
        for r in range(2):
            a = inverse_rotation[r]
            vectors[:, mapping[r], 0] = ((a[0] * x + a[1] * y) + a[2] * 0.0) + offset[r, 0]
        for k, vector in zip(typed, vectors):
            out[k] = vector.view(StateVector)
    for k, det in enumerate(detections):
        if out[k] is None:
            vector = det.state_vector
            x, y = _nonlinear.pol2cart(vector[1, :], vector[0, :])
            xyz = inverse_rotation @ np.array([x, y, np.zeros(vector.shape[1])])
            res = np.zeros((model.ndim_state, vector.shape[1])).view(StateVector)
            res[mapping, :] = xyz[0:2] + offset
            out[k] = res
    return out


def _bearing_typed(vector) -> bool:
    if vector.dtype != object or vector.shape != (2, 1):
        return False
    (phi,), (rho,) = vector.tolist()  # (an object array's own elements)
    return type(phi) is Bearing and type(rho) in _FLOATS


def _bearing_range(model) -> bool:
    return type(model) in (CartesianToBearingRange, AnalyticCartesianToBearingRange) \
        and len(model.mapping) == 2


class Births:
    """What the inner initiator returns for a scan's detections (see the module
    docstring). A linear model's pseudo-inverse and initial covariance are computed once
    while its numbers stay the same; a bearing–range model's Jacobians (finite difference
    or closed form), pseudo-inverses and covariances as stacked arrays (the stock
    expressions, matrix by matrix); other initiators and models run their own code."""

    def __init__(self):
        self._linear_cache: dict = {}
        self._track = _TrackFactory()

    def __call__(self, inner, detections, timestamp) -> set:
        tracks, births = self.arrays(inner, detections, timestamp)
        tracks.update(self.track(*birth) for birth in births)
        return tracks

    def arrays(self, inner, detections, timestamp) -> tuple[set, list]:
        """What :meth:`__call__` returns, with the new tracks of the detections this class
        computes itself not yet built: ``(tracks the inner initiator built, births)``, a
        birth being the arguments of :meth:`track` (the detection, the state's mean
        ``(D, 1)`` and covariance, the prior state)."""
        births: list = []
        if not isinstance(detections, list):
            detections = list(detections)
        if type(inner) is not SimpleMeasurementInitiator:
            return inner.initiate(set(detections), timestamp), births
        if not detections:
            return set(), births
        # by value: equal models in different objects are one group (its first), each
        # model object keyed once (the scan's groups, when remembered on the collection)
        by_value = scan_model_groups(detections)
        if None in by_value:  # detections without a model: the inner initiator's
            fallback = inner.measurement_model
            by_value = models_by_value([
                fallback if det.measurement_model is None else det.measurement_model
                for det in detections])
        rows = getattr(detections, "vectors", None)  # (an OrderedDetections' float rows)
        if not (isinstance(rows, np.ndarray) and rows.dtype == np.float64
                and rows.shape == (len(detections), 2)):
            rows = None
        groups = []
        other = []
        for model, members in by_value.values():
            if type(model) is LinearGaussian or _bearing_range(model):
                groups.append((model, [detections[i] for i in members],
                               None if rows is None else rows[members]))
            else:
                other.extend(detections[i] for i in members)
        tracks = inner.initiate(set(other), timestamp) if other else set()
        prior = inner.prior_state
        load = np.diag(np.array([inner.diag_load] * len(prior.state_vector)))
        for model, dets, dets_rows in groups:
            prior_vector = prior.state_vector.copy()
            prior_covar = prior.covar.copy()
            mapped = model.mapping
            prior_vector[mapped, :] = 0
            for dim in mapped:
                prior_covar[dim, :] = prior_covar[:, dim] = 0
            noise = model.covar()
            if type(model) is LinearGaussian:
                inverse, covar = self._linear(model, noise, prior_covar, load)
                vectors = [prior_vector + (inverse @ det.state_vector) for det in dets]
                covars = [covar.copy() for _ in dets]  # one array per state, as stock
            else:
                vectors = inverse_bearing_range(model, dets, dets_rows)
                means = np.array(vectors, dtype=np.float64)
                zeros = np.zeros((len(dets),) + (means.shape[1],) * 2)
                # the model's own Jacobian, state by state, bit for bit
                if type(model) is AnalyticCartesianToBearingRange:
                    jacobians = _analytic_bearing_range_batch(model, means, zeros, None,
                                                              jacobians_only=True)[3]
                else:
                    _, _, _, jacobians = _bearing_range_batch(model, means, zeros)
                inverses = np.linalg.pinv(jacobians)
                stacked = (inverses @ np.asarray(noise)[np.newaxis]) @ inverses.transpose(0, 2, 1)
                # (C + P₀) + L matrix by matrix, as the stock sum of the three
                covars = list((stacked + np.asarray(prior_covar)) + np.asarray(load))
                if prior_vector.dtype == np.float64:  # (as every vector: one addition for all)
                    vectors = [mean.view(StateVector) for mean in np.asarray(prior_vector) + means]
                else:
                    vectors = [prior_vector + vector for vector in vectors]
            births.extend((det, vector, covar, prior)
                          for det, vector, covar in zip(dets, vectors, covars))
        return tracks, births

    def _linear(self, model, noise, prior_covar, load):
        """The pseudo-inverse and covariance of a linear model, while its numbers are the same."""
        matrix = model.matrix()
        key = (matrix.tobytes(), np.asarray(noise).tobytes(), prior_covar.tobytes(),
               load.tobytes())
        cached = self._linear_cache.get(id(model))
        if cached is None or cached[0] is not model or cached[1] != key:
            inverse = np.linalg.pinv(matrix)
            covar = inverse @ noise @ inverse.T
            covar = covar + prior_covar + load
            cached = self._linear_cache[id(model)] = (model, key, inverse, covar)
            if len(self._linear_cache) > 16:
                self._linear_cache = {id(model): cached}
        return cached[2], cached[3]

    def track(self, detection, mean, covar, prior):
        """The inner initiator's track of one birth (see :meth:`arrays`): its one state,
        what ``Update.from_state`` builds from ``prior``."""
        if type(prior) is GaussianState:
            return self._track(UPDATE_STATE(
                state_vector=mean.view(StateVector), covar=covar.view(CovarianceMatrix),
                hypothesis=_HYPOTHESIS(prediction=None, measurement=detection),
                timestamp=detection.timestamp))
        return self._track(Update.from_state(
            prior, state_vector=mean, covar=covar,
            hypothesis=SingleHypothesis(None, detection), timestamp=detection.timestamp))
