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
hypothesisers read it as before, and is also handed to the data associator, the deleter
and the initiator as the keyword ``detector_context`` when they declare that parameter
(see :func:`~ctxmodels.stonesoup.scan_context.context_kwargs`), as the upstream
DetectorContext proposal's trackers hand it on; stock components are called as stock.
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

from ..._upstream import live_tracks
from ..ordering import in_stable_order, in_track_order
from ..scan_context import context_kwargs, declares_context
from ..scan_checks import checked_scan_rows, naming_scan_errors


class MultiTargetMixtureTracker(_StockMixtureTracker):
    """:class:`stonesoup.tracker.simple.MultiTargetMixtureTracker` visiting its tracks in
    creation order and each scan's detections in value order (see the module docstring).
    ``tracks`` is the live ``set``, as stock; :attr:`tracks_in_order` lists it in creation
    order (tracks added to the set from outside join in
    :func:`~ctxmodels.stonesoup.ordering.track_key` order)."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._order: dict[Track, None] = {}  # creation order (a dict keeps it)

    @property
    def tracks_in_order(self) -> list[Track]:
        live = live_tracks(self)
        order = self._order
        if len(order) == len(live) and live.issuperset(order):
            return list(order)  # (the usual scan: no track deleted or added from outside)
        order = dict.fromkeys(t for t in order if t in live)
        order.update(dict.fromkeys(in_track_order(t for t in live if t not in order)))
        self._order = order
        return list(order)

    def __next__(self) -> tuple[datetime.datetime, set[Track]]:
        # the scan checked first (see ctxmodels.stonesoup.scan_checks), so the array and
        # component paths refuse the same scans with the same message
        time, detections, rows = checked_scan_rows(self, next(self.detector_iter))
        with naming_scan_errors(self, time, detections):
            return self._scan(time, in_stable_order(detections, rows))

    def _scan(self, time, detections) -> tuple[datetime.datetime, set[Track]]:
        """One scan of the stock loop on ``detections`` already in stable order."""
        tracks = self.tracks_in_order
        associator, deleter, initiator = self.data_associator, self.deleter, self.initiator
        # the scan's context, to each component that declares a detector_context parameter
        associations = associator.associate(tracks, detections, time,
                                            **context_kwargs(detections, associator.associate))
        taken = set()
        for track in tracks:
            multihypothesis = associations.get(track)
            if multihypothesis is None:
                continue  # stock updates the tracks the associator answered for
            track.append(self._posterior(multihypothesis))
            missed_weight = next(hyp.weight for hyp in multihypothesis if not hyp)
            taken.update(id(hyp.measurement) for hyp in multihypothesis
                         if hyp and hyp.weight > missed_weight)
        live = live_tracks(self)
        live -= deleter.delete_tracks(live, **context_kwargs(detections, deleter.delete_tracks))
        new = initiator.initiate({d for d in detections if id(d) not in taken}, time,
                                 **context_kwargs(detections, initiator.initiate))
        live |= new
        self._order.update(dict.fromkeys(in_track_order(new)))
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
    """:class:`stonesoup.initiator.simple.MultiMeasurementInitiator` visiting its holding
    tracks in creation order and the detections in value order (see the module docstring).

    ``holding_tracks`` is the live ``set``, as stock. A holding track is released (returned)
    once it has ``min_points`` states (updates only, with ``updates_only``), counted as
    states are appended here rather than by walking the track at every scan (so states
    added to a holding track from outside are not counted)."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._points: dict[Track, int] = {}  # holding track -> its points, creation order

    def _counts(self, state) -> bool:
        return not self.updates_only or isinstance(state, Update)

    def _holding_in_order(self) -> list[Track]:
        live = self.holding_tracks
        points = {t: n for t, n in self._points.items() if t in live}
        for track in in_track_order(t for t in live if t not in points):
            points[track] = sum(1 for state in track.states if self._counts(state))
        self._points = points
        return list(points)

    def initiate(self, detections, timestamp, detector_context=None, **kwargs) -> set[Track]:
        """The holding tracks confirmed by this scan's ``detections``. The scan's
        ``detector_context`` (the tracker passes the one it received) goes on to the
        deleter when it declares the parameter, so an
        :class:`~ctxmodels.stonesoup.ExpectedMissesDeleter` weighs a holding track's
        misses by P_D as it does a track's."""
        detections = in_stable_order(detections)
        if self.skip_non_reversible:
            detections = [d for d in detections
                          if isinstance(d.measurement_model, (ReversibleModel, LinearModel))]
        sure_tracks = set()
        associated = set()
        if self.holding_tracks:
            holding = self._holding_in_order()
            associations = self.data_associator.associate(holding, detections, timestamp)
            for track in holding:
                hypothesis = associations.get(track)
                if hypothesis is None:
                    continue  # stock updates the tracks the associator answered for
                if hypothesis:
                    state = self.updater.update(hypothesis)
                    associated.add(id(hypothesis.measurement))
                else:
                    state = hypothesis.prediction
                track.append(state)
                points = self._points[track] = self._points[track] + self._counts(state)
                if points >= self.min_points:
                    sure_tracks.add(track)
                    self.holding_tracks.remove(track)
            context = ({} if detector_context is None
                       or not declares_context(self.deleter.delete_tracks)
                       else {"detector_context": detector_context})
            self.holding_tracks -= self.deleter.delete_tracks(self.holding_tracks, **context)
        new = self.initiator.initiate({d for d in detections if id(d) not in associated},
                                      timestamp)
        self.holding_tracks |= new
        self._holding_in_order()  # counts the new tracks' points, in track_key order
        return sure_tracks


__all__ = ["MultiMeasurementInitiator", "MultiTargetMixtureTracker"]
