r"""The stock (J)PDA mixture tracker and M-of-N initiator, in a reproducible order.

Drop-ins for :class:`stonesoup.tracker.simple.MultiTargetMixtureTracker` and
:class:`stonesoup.initiator.simple.MultiMeasurementInitiator` (Stone Soup 1.9.1), with the
same Properties and the same arithmetic. The stock classes keep tracks and detections in
sets, which iterate in memory-address order; JPDA then sums joint-association
probabilities, and the initiator's association solves ties, in an order that changes from
process to process (see :mod:`ctxmodels.stonesoup.ordering`). These keep tracks in creation
order and put each scan's detections in value order before anything iterates them, so the
same detections give the same tracks, bit for bit, in every process. Run in the same order,
the stock classes give the same numbers (the tests check it).

Per scan :math:`k` the tracker does what the stock one does: associate the tracks with the
scan's detections; replace each track's mixture of hypotheses by its moment-matched
Gaussian (an update if some detection outweighs the missed detection, else a prediction);
delete tracks; hand the detections no track took (those not outweighing the missed
detection) to the initiator. The scan's ``detector_context`` (a
:class:`~ctxmodels.DetectionSet`'s) stays with the ordered detections, so context-aware
hypothesisers read it as before.
"""
from __future__ import annotations

import datetime

import numpy as np
from stonesoup.functions import gm_reduce_single
from stonesoup.initiator.simple import MultiMeasurementInitiator as _StockMultiMeasurementInitiator
from stonesoup.models.base import LinearModel, ReversibleModel
from stonesoup.tracker.simple import MultiTargetMixtureTracker as _StockMixtureTracker
from stonesoup.types.array import StateVectors
from stonesoup.types.prediction import GaussianStatePrediction
from stonesoup.types.track import Track
from stonesoup.types.update import GaussianStateUpdate, Update

from .ordering import in_stable_order, in_track_order


class MultiTargetMixtureTracker(_StockMixtureTracker):
    """:class:`stonesoup.tracker.simple.MultiTargetMixtureTracker` with tracks kept in
    creation order and each scan's detections in value order (see the module docstring).
    ``tracks`` is a ``set``, as stock; :attr:`tracks_in_order` lists them in creation
    order."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._ordered: dict[Track, None] = {}  # creation order (a dict keeps it)

    @property
    def tracks(self) -> set[Track]:
        return set(self._ordered)

    @property
    def tracks_in_order(self) -> list[Track]:
        """The live tracks in creation order (new tracks of one scan in
        :func:`~ctxmodels.stonesoup.ordering.track_key` order)."""
        return list(self._ordered)

    def __next__(self) -> tuple[datetime.datetime, set[Track]]:
        time, detections = next(self.detector_iter)
        detections = in_stable_order(detections)
        tracks = list(self._ordered)
        associations = self.data_associator.associate(tracks, detections, time)
        taken = set()
        for track in tracks:
            multihypothesis = associations[track]
            track.append(self._posterior(multihypothesis))
            missed_weight = next(hyp.weight for hyp in multihypothesis if not hyp)
            taken.update(id(hyp.measurement) for hyp in multihypothesis
                         if hyp and hyp.weight > missed_weight)
        for track in self.deleter.delete_tracks(set(tracks)):
            self._ordered.pop(track, None)
        unassociated = [d for d in detections if id(d) not in taken]
        for track in in_track_order(self.initiator.initiate(set(unassociated), time)):
            self._ordered[track] = None
        return time, self.tracks

    def _posterior(self, multihypothesis):
        """The stock tracker's moment-matched state of one track's hypotheses."""
        states, weights = [], []
        for hypothesis in multihypothesis:
            states.append(self.updater.update(hypothesis) if hypothesis
                          else hypothesis.prediction)
            weights.append(hypothesis.probability)
        means = StateVectors([state.state_vector for state in states])
        covars = np.stack([state.covar for state in states], axis=2)
        mean, covar = gm_reduce_single(means, covars, np.asarray(weights))
        missed_weight = next(hyp.weight for hyp in multihypothesis if not hyp)
        if any(hypothesis.weight > missed_weight for hypothesis in multihypothesis):
            return GaussianStateUpdate(mean, covar, multihypothesis,
                                       multihypothesis[0].measurement.timestamp)
        return GaussianStatePrediction(mean, covar, multihypothesis[0].prediction.timestamp)


class MultiMeasurementInitiator(_StockMultiMeasurementInitiator):
    """:class:`stonesoup.initiator.simple.MultiMeasurementInitiator` with its holding tracks
    kept in creation order and the detections in value order (see the module docstring).

    ``holding_tracks`` is a ``set``, as stock. A holding track is released (returned) once
    it has ``min_points`` states (updates only, with ``updates_only``)."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._holding: dict[Track, int] = {}  # holding track -> its number of points

    @property
    def holding_tracks(self) -> set[Track]:
        return set(self._holding)

    @holding_tracks.setter
    def holding_tracks(self, tracks) -> None:
        # The stock constructor assigns an empty set; any assignment keeps a stable order.
        self._holding = {track: self._points(track) for track in in_track_order(tracks)}

    def _counts(self, state) -> bool:
        return not self.updates_only or isinstance(state, Update)

    def _points(self, track) -> int:
        return sum(1 for state in track.states if self._counts(state))

    def initiate(self, detections, timestamp, **kwargs) -> set[Track]:
        detections = in_stable_order(detections)
        if self.skip_non_reversible:
            detections = [d for d in detections
                          if isinstance(d.measurement_model, (ReversibleModel, LinearModel))]
        sure_tracks = set()
        associated = set()
        if self._holding:
            holding = list(self._holding)
            associations = self.data_associator.associate(holding, detections, timestamp)
            for track in holding:
                hypothesis = associations[track]
                if hypothesis:
                    state = self.updater.update(hypothesis)
                    associated.add(id(hypothesis.measurement))
                else:
                    state = hypothesis.prediction
                track.append(state)
                # a running count of the track's points, not a walk over its states
                points = self._holding[track] + self._counts(state)
                if points >= self.min_points:
                    sure_tracks.add(track)
                    del self._holding[track]
                else:
                    self._holding[track] = points
            for track in self.deleter.delete_tracks(set(self._holding)):
                del self._holding[track]
        remaining = [d for d in detections if id(d) not in associated]
        for track in in_track_order(self.initiator.initiate(remaining, timestamp)):
            self._holding[track] = self._points(track)
        return sure_tracks


__all__ = ["MultiMeasurementInitiator", "MultiTargetMixtureTracker"]
