"""The pending states of :class:`~ctxmodels.stonesoup.array_initiator.ArrayMultiMeasurementInitiator`'s
holding tracks: each scan is a block of the holding rows' predictions (arrays) and updates
(states); a holding track's Stone Soup states are appended from the blocks only when it is
updated, released or leaves the array path.
"""
from __future__ import annotations

from bisect import bisect_left

from stonesoup.types.array import CovarianceMatrix, StateVector
from stonesoup.types.prediction import GaussianStatePrediction

from .fast import ObjectFactory
from .fast_association import _copied_properties, _weaken_prior_chain

#: A prediction as ``Prediction.from_state`` builds it (transition model and prior).
PRIOR_PREDICTION = ObjectFactory(GaussianStatePrediction, dict(
    state_vector=StateVector([0.0]), covar=CovarianceMatrix([[1.0]]), timestamp=None,
    transition_model=None, prior=None))


class Holding:
    """A holding track: its Track (states up to the last materialisation), the first scan
    block whose states it does not hold yet, and its serial number (rows are kept in serial
    order, so a block finds a track's row by bisection)."""

    __slots__ = ("track", "pending_from", "serial")

    def __init__(self, track, pending_from, serial):
        self.track = track
        self.pending_from = pending_from
        self.serial = serial


class Block:
    """One scan of the holding tracks: their predictions (rows in ``serials`` order), the
    scan time, the updates of the rows that were updated and the rows given no state (by
    serial)."""

    __slots__ = ("means", "covars", "timestamp", "serials", "updates", "skipped")

    def __init__(self, means, covars, timestamp, serials):
        self.means, self.covars, self.timestamp = means, covars, timestamp
        self.serials = serials  # ascending
        self.updates: dict = {}  # serial -> update state (its prediction's prior unset)
        self.skipped: set = set()


def materialise(record: Holding, blocks: dict, end: int, transition) -> None:
    """Append to the record's track the states the component path would have appended in
    blocks ``record.pending_from`` to ``end - 1``: predictions (transition model, previous
    state as prior) and updates (their prediction's prior set to the previous state), in
    scan order."""
    if record.pending_from >= end:
        return
    track = record.track
    serial = record.serial
    prior = track.state
    for b in range(record.pending_from, end):
        block = blocks[b]
        if serial in block.skipped:
            continue
        _weaken_prior_chain(prior)
        update = block.updates.get(serial)
        if update is not None:
            update.hypothesis.prediction.prior = prior
            track.append(update)
            prior = update
            continue
        row = bisect_left(block.serials, serial)
        state = PRIOR_PREDICTION(
            state_vector=block.means[row].view(StateVector),
            covar=block.covars[row].view(CovarianceMatrix), timestamp=block.timestamp,
            transition_model=transition, prior=prior,
            **{name: getattr(prior, name) for name in _copied_properties(type(prior))})
        track.append(state)
        prior = state
    record.pending_from = end
