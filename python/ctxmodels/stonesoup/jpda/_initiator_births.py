r"""The new holding tracks of :class:`~ctxmodels.stonesoup.ArrayMultiMeasurementInitiator`:
what Stone Soup's :class:`~stonesoup.initiator.simple.SimpleMeasurementInitiator` returns for
a scan's unassociated detections, computed in the core
(:func:`ctxmodels._core.initiator_births`), and the tracks built without Stone Soup's
per-Property constructor.

A detection ``z`` measured by a model with mapped state indices ``m`` starts a track at

.. math::
    x = x_0' + h^{-1}(z), \qquad P = (J^+ R J^{+\mathsf T} + P_0') + l I,

with :math:`x_0', P_0'` the prior with the mapped entries zeroed, :math:`h^{-1}` the model's
inverse (:math:`H^+ z` for a linear model), :math:`J` its matrix or its Jacobian at
:math:`h^{-1}(z)` and :math:`l` the initiator's ``diag_load``. The means are Stone Soup's to
the bit (the core is given NumPy's :math:`H^+` and :math:`R^{-1}`); the covariances to
rounding with a linear model or the closed-form Jacobian, and to ~1e-5 relative with the
finite-difference Jacobian (see ``rust/jpda/births.rs``). Other initiators, other models and
detections the core cannot read run the stock initiator.
"""
from __future__ import annotations

import uuid
from itertools import compress

import numpy as np
from stonesoup.initiator.simple import SimpleMeasurementInitiator
from stonesoup.types.angle import Bearing
from stonesoup.types.array import CovarianceMatrix, StateVector
from stonesoup.types.hypothesis import SingleHypothesis
from stonesoup.types.state import GaussianState
from stonesoup.types.track import Track
from stonesoup.types.update import GaussianStateUpdate, Update

from ... import _core
from ..._upstream import (TRACK_ID, TRACK_INIT_METADATA, TRACK_METADATAS, TRACK_STATES,
                          update_track_metadata)
from ...model_key import models_by_value, scan_model_groups
from .._batch import ObjectFactory
from ..models import core_measurement_model

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
        track.__dict__ = {TRACK_STATES: [state], TRACK_ID: str(uuid.uuid4()),
                          TRACK_INIT_METADATA: {}, TRACK_METADATAS: []}
        update_track_metadata(track, state)
        return track

    def __call__(self, state):
        if self.fast is None:
            real = Track([state])
            built = self._build(state)
            ours, theirs = dict(built.__dict__), dict(real.__dict__)
            self.fast = (type(ours.pop(TRACK_ID, None)) is str
                         and type(theirs.pop(TRACK_ID, None)) is str and ours == theirs
                         and ours[TRACK_STATES][0] is theirs[TRACK_STATES][0])
            return real
        return self._build(state) if self.fast else Track([state])


class Births:
    """What the inner initiator returns for a scan's detections (see the module docstring):
    one core call for the detections of the models the core takes, the inner initiator's
    own code for the rest."""

    def __init__(self):
        self._core_models: dict = {}  # model key -> (core model, bearing first) or None
        self._track = _TrackFactory()

    def __call__(self, inner, detections, timestamp) -> set:
        tracks, births = self.arrays(inner, detections, timestamp)
        tracks.update(self.track(*birth) for birth in births)
        return tracks

    def arrays(self, inner, detections, timestamp) -> tuple[set, list]:
        """What :meth:`__call__` returns, with the new tracks of the detections the core
        computes not yet built: ``(tracks the inner initiator built, births)``, a birth
        being the arguments of :meth:`track` (the detection, the state's mean ``(D, 1)``
        and covariance, the prior state)."""
        births: list = []
        if not isinstance(detections, list):
            detections = list(detections)
        prior = inner.prior_state
        if type(inner) is not SimpleMeasurementInitiator or not detections \
                or not _float_prior(prior):
            return (inner.initiate(set(detections), timestamp) if detections else set()), births
        # by value: equal models in different objects are one group (its first), each
        # model object keyed once (the scan's groups, when remembered on the collection)
        by_value = scan_model_groups(detections)
        if None in by_value:  # detections without a model: the inner initiator's
            fallback = inner.measurement_model
            by_value = models_by_value([
                fallback if det.measurement_model is None else det.measurement_model
                for det in detections])
        models, index, members_of = [], [], []
        other = []
        for key, (model, members) in by_value.items():
            core = self._core_model(model, key)
            if core is None or (models and core[0].ndim_meas != models[0][0].ndim_meas):
                other.extend(detections[i] for i in members)
                continue
            index.extend([len(models)] * len(members))
            members_of.extend(members)
            models.append(core)
        if models:
            z, readable = _rows(detections, members_of, [models[g][1] for g in index],
                                models[0][0].ndim_meas)
            if not readable.all():
                other.extend(detections[i] for i, ok in zip(members_of, readable) if not ok)
                members_of = list(compress(members_of, readable))
                index = list(compress(index, readable))
                z = z[readable]
        tracks = inner.initiate(set(other), timestamp) if other else set()
        if not members_of:
            return tracks, births
        try:
            means, covars = _core.initiator_births(
                [core for core, _ in models], z, np.array(index, dtype=np.int64),
                np.ascontiguousarray(prior.state_vector[:, 0], dtype=np.float64),
                np.ascontiguousarray(prior.covar, dtype=np.float64), float(inner.diag_load))
        except ValueError:  # (e.g. a non-finite detection: the stock code decides)
            return tracks | inner.initiate({detections[i] for i in members_of}, timestamp), births
        means = means[:, :, np.newaxis]
        births.extend((detections[i], mean, covar, prior)
                      for i, mean, covar in zip(members_of, means, covars))
        return tracks, births

    def _core_model(self, model, key):
        """(the core's model, whether it measures a bearing first) for ``model`` (of
        :func:`~ctxmodels.model_key.measurement_model_key` ``key``: equal models share an
        entry), or None when the core does not take it."""
        if key not in self._core_models:
            core, bearing_row = (None, None) if key is None else \
                core_measurement_model(model)
            if bearing_row is not None and not _rotates_in_plane(model):
                core = None  # (the stock inverse refuses a roll or pitch: its error, raised)
            if len(self._core_models) >= 64:
                self._core_models.clear()
            self._core_models[key] = None if core is None else (core, bearing_row is not None)
        return self._core_models[key]

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


def _rotates_in_plane(model) -> bool:
    """Whether a bearing–range model's rotation is about the vertical only, as its inverse
    function requires."""
    offset = model.rotation_offset
    return offset[0] == 0 and offset[1] == 0


def _float_prior(prior) -> bool:
    return type(prior) is GaussianState and prior.state_vector.dtype == np.float64 \
        and prior.covar.dtype == np.float64 and prior.state_vector.shape[1:] == (1,)


def _rows(detections, members, bearing, m):
    """The detections ``members`` as float rows (M, ``m``), and which of them the core
    reads: float values, with a :class:`Bearing` (or a float) first where its model
    measures a bearing first (``bearing``, per member)."""
    rows = np.zeros((len(members), m))
    readable = np.ones(len(members), dtype=bool)
    vectors = getattr(detections, "vectors", None)  # (an OrderedDetections' float rows)
    known = isinstance(vectors, np.ndarray) and vectors.dtype == np.float64 \
        and vectors.shape == (len(detections), m)
    for k, (i, first_is_bearing) in enumerate(zip(members, bearing)):
        vector = detections[i].state_vector
        if vector.shape != (m, 1):
            readable[k] = False
        elif vector.dtype == np.float64:
            rows[k] = vectors[i] if known else vector[:, 0]
        else:
            values = np.ndarray.ravel(vector).tolist()  # (the elements, not a subclass's ravel)
            if all(type(value) in _FLOATS or (row == 0 and first_is_bearing
                                               and type(value) is Bearing)
                   for row, value in enumerate(values)):
                rows[k] = [float(value) for value in values]
            else:
                readable[k] = False
    return rows, readable
