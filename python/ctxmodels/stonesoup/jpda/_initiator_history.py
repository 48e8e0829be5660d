"""The holding tracks' history in :class:`~ctxmodels.stonesoup.ArrayMultiMeasurementInitiator`:
each scan is a block of the core's arrays (every holding row's prediction, and for the rows
it updated: the update, the detection, the distance and the measurement prediction). A
holding track's Stone Soup states are built from the blocks only when it is released or
leaves the array path; the holding tracks the deleter drops (most of them: clutter) never
get any.
"""
from __future__ import annotations

from bisect import bisect_left

import numpy as np
from stonesoup.types.angle import Bearing
from stonesoup.types.array import CovarianceMatrix, Matrix, StateVector
from stonesoup.types.hypothesis import SingleDistanceHypothesis
from stonesoup.types.prediction import GaussianMeasurementPrediction, GaussianStatePrediction
from stonesoup.types.update import GaussianStateUpdate

from .._batch import ObjectFactory, plain_track_lists
from ..gnn import _copied_properties, _weaken_prior_chain

#: A prediction as ``Prediction.from_state`` builds it (transition model and prior).
PRIOR_PREDICTION = ObjectFactory(GaussianStatePrediction, dict(
    state_vector=StateVector([0.0]), covar=CovarianceMatrix([[1.0]]), timestamp=None,
    transition_model=None, prior=None))
_NEW_PRIOR_PREDICTION = PRIOR_PREDICTION.maker(
    "state_vector", "covar", "timestamp", "transition_model", "prior")
#: What the Kalman updater's ``predict_measurement`` returns.
_MEASUREMENT_PREDICTION = ObjectFactory(GaussianMeasurementPrediction, dict(
    state_vector=StateVector([0.0]), covar=CovarianceMatrix([[1.0]]), timestamp=None,
    cross_covar=Matrix([[1.0]])))
#: A hypothesis as the distance hypothesiser builds it.
_DISTANCE_HYPOTHESIS = ObjectFactory(SingleDistanceHypothesis, dict(
    prediction=None, measurement=None, distance=0.0, measurement_prediction=None))
#: An update as the Kalman updater builds it from a Gaussian prediction.
_UPDATE = ObjectFactory(GaussianStateUpdate, dict(
    state_vector=StateVector([0.0]), covar=CovarianceMatrix([[1.0]]), hypothesis=None,
    timestamp=None))


class Holding:
    """A holding track: its Track (states up to the last materialisation; None until
    built, then ``birth`` holds the arguments of
    :meth:`~ctxmodels.stonesoup.jpda._initiator_births.Births.track`), the first scan block whose
    states it does not hold yet, and its serial number (rows are kept in serial order, so a
    block finds a track's row by bisection)."""

    __slots__ = ("track", "pending_from", "serial", "birth")

    def __init__(self, track, pending_from, serial, birth=None):
        self.track = track
        self.pending_from = pending_from
        self.serial = serial
        self.birth = birth


class Update:
    """An update of one row in one scan, as arrays: the posterior ``(mean, covar)``, the
    detection, the distance and the measurement prediction ``(ẑ, S, C)``; ``bearing`` says
    whether ẑ's first element is a bearing."""

    __slots__ = ("mean", "covar", "detection", "distance", "z_hat", "innovation", "cross",
                 "bearing")

    def __init__(self, mean, covar, detection, distance, z_hat, innovation, cross, bearing):
        self.mean, self.covar, self.detection, self.distance = mean, covar, detection, distance
        self.z_hat, self.innovation, self.cross, self.bearing = z_hat, innovation, cross, bearing


class Block:
    """One scan of the holding rows: their predictions ``means`` (H, D, 1) / ``covars``
    (H, D, D) in ``serials`` order (ascending), the scan time and the updates by serial."""

    __slots__ = ("means", "covars", "timestamp", "serials", "updates")

    def __init__(self, means, covars, timestamp, serials):
        self.means, self.covars, self.timestamp = means, covars, timestamp
        self.serials = serials
        self.updates: dict[int, Update] = {}


def _typed(z_hat: np.ndarray, bearing: bool) -> StateVector:
    """ẑ as the stock model returns it: a float vector, or its first element a Bearing."""
    if not bearing:
        return z_hat.reshape(-1, 1).view(StateVector)
    column = np.empty((len(z_hat), 1), dtype=object)
    values = z_hat.tolist()
    column[0, 0] = Bearing(values[0])
    for row in range(1, len(values)):
        column[row, 0] = values[row]
    return column.view(StateVector)


def materialise(record: Holding, blocks: dict, end: int, transition) -> None:
    """Append to the record's track the states the component path would have appended in
    blocks ``record.pending_from`` to ``end - 1``: each scan's prediction (transition
    model, previous state as prior) or, where the row was updated, the update (its
    hypothesis holding that prediction, the detection, the distance and the measurement
    prediction)."""
    if record.pending_from >= end:
        return
    track = record.track
    serial = record.serial
    prior = track.state
    lists = plain_track_lists(track)  # (a prediction appended as Track.append does)
    for b in range(record.pending_from, end):
        block = blocks[b]
        _weaken_prior_chain(prior)
        row = bisect_left(block.serials, serial)
        copied = _copied_properties(type(prior))
        vector, covar = block.means[row].view(StateVector), block.covars[row].view(CovarianceMatrix)
        if copied != ():  # (a prior of a subclass: its extra Properties carried over)
            prediction = PRIOR_PREDICTION(
                state_vector=vector, covar=covar, timestamp=block.timestamp,
                transition_model=transition, prior=prior,
                **{name: getattr(prior, name) for name in copied})
        else:
            prediction = _NEW_PRIOR_PREDICTION(vector, covar, block.timestamp, transition, prior)
        update = block.updates.get(serial)
        if update is None:
            if lists is None:
                track.append(prediction)
            else:  # no Update: the metadata carried on unchanged
                states, metadatas = lists
                metadatas.append((metadatas[-1] if metadatas else track.init_metadata).copy())
                states.append(prediction)
            prior = prediction
            continue
        measurement_prediction = _MEASUREMENT_PREDICTION(
            state_vector=_typed(update.z_hat, update.bearing),
            covar=update.innovation.view(CovarianceMatrix), timestamp=block.timestamp,
            cross_covar=update.cross.view(Matrix))
        hypothesis = _DISTANCE_HYPOTHESIS(
            prediction=prediction, measurement=update.detection, distance=update.distance,
            measurement_prediction=measurement_prediction)
        state = _UPDATE(state_vector=update.mean.view(StateVector),
                        covar=update.covar.view(CovarianceMatrix), hypothesis=hypothesis,
                        timestamp=update.detection.timestamp)
        track.append(state)
        prior = state
    record.pending_from = end


__all__ = ["Block", "Holding", "PRIOR_PREDICTION", "Update", "materialise"]
