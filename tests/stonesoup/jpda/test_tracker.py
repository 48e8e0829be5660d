"""The (J)PDA mixture tracker and M-of-N initiator (ctxmodels.stonesoup.jpda.tracker), the
readable reference, equal the stock components run in the same stable order, and keep the
stock components' live sets and nested initiators."""
import numpy as np
import pytest
from stonesoup.dataassociator.neighbour import GNNWith2DAssignment
from stonesoup.dataassociator.probability import JPDAwithEHM2
from stonesoup.deleter.time import UpdateTimeStepsDeleter
from stonesoup.hypothesiser.distance import DistanceHypothesiser
from stonesoup.hypothesiser.probability import PDAHypothesiser
from stonesoup.initiator.simple import MultiMeasurementInitiator as StockInitiator
from stonesoup.measures import Mahalanobis
from stonesoup.predictor.kalman import KalmanPredictor
from stonesoup.tracker.simple import MultiTargetMixtureTracker as StockTracker
from stonesoup.types.state import GaussianState
from stonesoup.updater.kalman import KalmanUpdater

from ctxmodels.stonesoup import (MultiMeasurementInitiator, MultiTargetMixtureTracker,
                                 in_stable_order, in_track_order)
from ctxmodels.stonesoup.ordering import track_key

from .setups import MEASUREMENT, TRANSITION, _tracker as tutorial_tracker, tutorial_scans


class StockInStableOrder(StockTracker):
    """The stock loop, visiting tracks in the drop-in's order (creation scan, then content)
    instead of set order; it gets each scan's detections already in the stable order."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._first_seen, self._calls = {}, 0

    @property
    def tracks(self):
        self._calls += 1
        for track in self._tracks:
            self._first_seen.setdefault(track, self._calls)
        return sorted(self._tracks, key=lambda t: (self._first_seen[t], track_key(t)))


def _tracker(tracker_cls, initiator_cls, scans):
    predictor, updater = KalmanPredictor(TRANSITION), KalmanUpdater(MEASUREMENT)
    hypothesiser = PDAHypothesiser(predictor, updater, clutter_spatial_density=0.125,
                                   prob_detect=0.9)
    return tutorial_tracker(hypothesiser, UpdateTimeStepsDeleter(3), JPDAwithEHM2,
                            detector=scans, tracker_cls=tracker_cls,
                            initiator_cls=initiator_cls)


def _states(track):
    return [(type(s).__name__, s.timestamp, s.state_vector.tobytes(), s.covar.tobytes())
            for s in track.states]


@pytest.mark.parametrize("seed", [6, 11])
def test_mixture_tracker_equals_stock_loop_in_the_same_order(seed):
    scans = tutorial_scans(seed=seed, steps=20, clutter_max=5)
    ordered = [(t, in_stable_order(d)) for t, d in scans]
    ours = _tracker(MultiTargetMixtureTracker, MultiMeasurementInitiator, scans)
    stock = _tracker(StockInStableOrder, MultiMeasurementInitiator, ordered)
    live = 0
    for (t1, a), (t2, b) in zip(ours, stock):
        assert t1 == t2
        assert [_states(t) for t in in_track_order(a)] == [_states(t) for t in in_track_order(b)]
        live = max(live, len(a))
    assert live >= 2  # the targets were tracked, with clutter tracks coming and going


def test_initiator_equals_stock_initiator():
    """Per detection the stock initiator's work is independent of order, and its GNN
    association has no ties here: the same tracks are released, scan by scan."""
    scans = tutorial_scans(seed=9, steps=20, clutter_max=6)
    predictor, updater = KalmanPredictor(TRANSITION), KalmanUpdater(MEASUREMENT)

    def build(cls):
        return cls(prior_state=GaussianState(np.zeros((4, 1)), np.diag([0, 1, 0, 1])),
                   measurement_model=MEASUREMENT, deleter=UpdateTimeStepsDeleter(2),
                   data_associator=GNNWith2DAssignment(DistanceHypothesiser(
                       predictor, updater, Mahalanobis(), missed_distance=3)),
                   updater=updater, min_points=3)
    ours, stock = build(MultiMeasurementInitiator), build(StockInitiator)
    released = 0
    for time, detections in scans:
        a, b = ours.initiate(set(detections), time), stock.initiate(set(detections), time)
        assert [_states(t) for t in in_track_order(a)] == [_states(t) for t in in_track_order(b)]
        assert [_states(t) for t in in_track_order(ours.holding_tracks)] == \
            [_states(t) for t in in_track_order(stock.holding_tracks)]
        released += len(a)
    assert released >= 2


def test_drop_ins_keep_the_stock_live_sets_and_nested_initiators():
    """``tracks`` and ``holding_tracks`` are the live sets, as stock: what a user removes
    stays removed; a stock initiator nested inside the drop-in gets a set, as stock."""
    scans = tutorial_scans(seed=6, steps=12, clutter_max=3)
    tracker = _tracker(MultiTargetMixtureTracker, MultiMeasurementInitiator, scans)
    assert tracker.tracks is tracker._tracks
    removed = None
    for _, tracks in tracker:
        assert tracks is tracker.tracks and set(tracker.tracks_in_order) == tracks
        if removed is None and tracks:
            removed = next(iter(in_track_order(tracks)))
            tracker.tracks.remove(removed)
        assert removed not in tracker.tracks
    assert removed is not None
    holder = tracker.initiator
    assert holder.holding_tracks is not None and isinstance(holder.holding_tracks, set)
    # a stock M-of-N initiator as the inner one (it subtracts sets from what it is given)
    predictor, updater = KalmanPredictor(TRANSITION), KalmanUpdater(MEASUREMENT)
    inner = StockInitiator(prior_state=GaussianState(np.zeros((4, 1)), np.diag([0, 1, 0, 1])),
                           measurement_model=MEASUREMENT, deleter=UpdateTimeStepsDeleter(2),
                           data_associator=GNNWith2DAssignment(DistanceHypothesiser(
                               predictor, updater, Mahalanobis(), missed_distance=3)),
                           updater=updater, min_points=1)
    outer = MultiMeasurementInitiator(
        prior_state=inner.prior_state, measurement_model=MEASUREMENT,
        deleter=UpdateTimeStepsDeleter(2), data_associator=inner.data_associator,
        updater=updater, min_points=2, initiator=inner)
    released = 0
    for time, detections in scans:
        released += len(outer.initiate(set(detections), time))
    assert released > 0
