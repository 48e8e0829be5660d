"""Stone Soup's UpdateTimeDeleter on the array path: ArrayJPDATracker (plain and as a
composite member) and ArrayMultiMeasurementInitiator (the holding tracks' deleter) reach its
verdicts from each track's latest detection-backed time, without walking the track.

The deleter deletes when no detection-backed Update lies in ``track[last - window:]``, and
Stone Soup's time slice keeps ``timestamp >= start``: a track last updated exactly
``window`` ago is kept. The runs below hit that boundary (timestamps in whole
microseconds, so the equality is exact), and the direct tests put tracks on it.

"Same tracks" is :func:`array_setups.run_side_by_side`'s: after every scan the
same tracks in content order, state for state (type, time, metadata, numbers to 1e-9).
"""
from __future__ import annotations

import datetime

import numpy as np
import pytest
from stonesoup.dataassociator.neighbour import GNNWith2DAssignment
from stonesoup.deleter.error import CovarianceBasedDeleter
from stonesoup.deleter.multi import CompositeDeleter as StockCompositeDeleter
from stonesoup.deleter.time import UpdateTimeDeleter
from stonesoup.hypothesiser.distance import DistanceHypothesiser
from stonesoup.measures import Mahalanobis
from stonesoup.predictor.kalman import KalmanPredictor
from stonesoup.types.detection import Detection
from stonesoup.types.hypothesis import SingleHypothesis
from stonesoup.types.prediction import GaussianStatePrediction
from stonesoup.types.track import Track
from stonesoup.types.update import GaussianStateUpdate
from stonesoup.updater.kalman import KalmanUpdater

from ctxmodels.stonesoup import (
    ArrayJPDATracker,
    ArrayMultiMeasurementInitiator,
    CompositeDeleter,
    MultiMeasurementInitiator,
    UpdateTimeStepsDeleter,
)
from .array_setups import (PRIOR, RTOL, _lengths, assert_same_tracks, pair, run_side_by_side,
                           two_rate_scans)
from .setups import MEASUREMENT, T0, TRANSITION

SECOND = datetime.timedelta(seconds=1)
MICROSECOND = datetime.timedelta(microseconds=1)


def _time(seconds):
    return lambda: UpdateTimeDeleter(datetime.timedelta(seconds=seconds))


#: (tracker deleter, holding deleter) factories; windows of whole scan periods put tracks
#: exactly on the boundary.
CONFIGS = {
    "time-plain": (_time(1.2), lambda: UpdateTimeStepsDeleter(2)),
    "time-holding": (lambda: UpdateTimeStepsDeleter(4), _time(0.8)),
    "time-both": (_time(2.0), _time(1.0)),
    "stock-composite": (lambda: StockCompositeDeleter(intersect=False, deleters=[
        _time(2.0)(), CovarianceBasedDeleter(covar_trace_thresh=8.0, mapping=[0, 2])]),
        _time(0.8)),
    "ctxmodels-composite-intersect": (lambda: CompositeDeleter(intersect=True, deleters=[
        UpdateTimeStepsDeleter(2), _time(1.2)()]), _time(1.0)),
}


@pytest.mark.parametrize("name", list(CONFIGS))
def test_time_deleters_on_the_array_path_give_the_component_paths_tracks(name):
    deleter, holding = CONFIGS[name]
    ours, reference = pair(deleter, holding, two_rate_scans())
    worst, scans = run_side_by_side(ours, reference)
    assert worst <= RTOL
    assert ours.array_scans == scans and ours.component_scans == 0
    assert ours._plan is not None and ours._plan.deleter is ours.deleter  # not called
    assert ours.initiator.array_calls == scans and ours.initiator.component_calls == 0


@pytest.mark.parametrize("where", ["tracker", "holding"])
def test_runs_reach_the_inclusive_boundary(where):
    """A window one microsecond shorter deletes other tracks: some track was last updated
    exactly one window before a scan, and was kept (on both paths, by the test above)."""
    def lengths(seconds):
        window = datetime.timedelta(seconds=seconds)
        if where == "tracker":
            made = pair(lambda: UpdateTimeDeleter(window), lambda: UpdateTimeStepsDeleter(2),
                        two_rate_scans())
        else:
            made = pair(lambda: UpdateTimeStepsDeleter(4), lambda: UpdateTimeDeleter(window),
                        two_rate_scans())
        return _lengths(made[0])
    seconds = 1.2 if where == "tracker" else 0.8
    assert lengths(seconds) != lengths(seconds - 1e-6)


# --- the boundary, directly ------------------------------------------------------------------------
def _update(t):
    return GaussianStateUpdate(np.zeros((4, 1)), np.eye(4),
                               SingleHypothesis(None, Detection(np.zeros((2, 1)), timestamp=t)),
                               timestamp=t)


def _prediction(t):
    return GaussianStatePrediction(np.zeros((4, 1)), np.eye(4), timestamp=t)


def _sequences(window):
    """State sequences around the boundary: the last detection exactly ``window`` before the
    last state, a microsecond either side, none, one out of time order, and a miss at the
    time of the last detection."""
    out = []
    for shift in (-MICROSECOND, datetime.timedelta(0), MICROSECOND):
        age = window + shift
        out.append([_update(T0), _prediction(T0 + age / 2), _prediction(T0 + age)])
        out.append([_update(T0 - SECOND), _update(T0), _prediction(T0 + age)])
    out.append([_prediction(T0), _prediction(T0 + SECOND)])
    out.append([_update(T0 + 5 * SECOND), _prediction(T0 + SECOND)])  # out of time order
    out.append([_update(T0), _prediction(T0)])
    out.append([_update(T0)])
    return out


@pytest.mark.parametrize("window", [datetime.timedelta(seconds=1.2), datetime.timedelta(0),
                                    datetime.timedelta(seconds=-1)])
@pytest.mark.parametrize("member", [False, True])
def test_tracker_verdicts_are_the_deleters_at_the_boundary(window, member):
    deleter = UpdateTimeDeleter(window)
    tracker = ArrayJPDATracker(
        initiator=None, detector=None, data_associator=None, updater=None,
        deleter=StockCompositeDeleter(intersect=True, deleters=[deleter]) if member else deleter)
    tracks = [Track(states) for states in _sequences(window)]
    expected = {t for t in tracks if deleter.check_for_deletion(t)}
    assert tracker._delete(set(tracks), []) == expected
    assert tracker._plan is not None
    if window == datetime.timedelta(seconds=1.2):
        verdicts = [deleter.check_for_deletion(t) for t in tracks[:6]]
        assert verdicts == [False, False, False, False, True, True]  # inclusive at the age


@pytest.mark.parametrize("window", [datetime.timedelta(seconds=0.8), datetime.timedelta(0)])
def test_initiator_verdicts_are_the_deleters_at_the_boundary(window):
    """Holding tracks handed in from outside, one scan without detections at a time placing
    their last detection just inside, on and just past the window: the array initiator
    keeps and deletes the tracks the component one does."""
    for shift in (-MICROSECOND, datetime.timedelta(0), MICROSECOND):
        held = [[_update(T0)], [_update(T0 - SECOND), _update(T0)]]  # states shared by both
        made = []
        for cls in (ArrayMultiMeasurementInitiator, MultiMeasurementInitiator):
            predictor, updater = KalmanPredictor(TRANSITION), KalmanUpdater(MEASUREMENT)
            initiator = cls(prior_state=PRIOR, measurement_model=MEASUREMENT,
                            deleter=UpdateTimeDeleter(window), updater=updater, min_points=5,
                            data_associator=GNNWith2DAssignment(DistanceHypothesiser(
                                predictor, updater, Mahalanobis(), missed_distance=3)))
            initiator.holding_tracks |= {Track(list(states)) for states in held}
            initiator.initiate(set(), T0 + window + shift)
            made.append(initiator)
        ours, reference = made
        assert ours.array_calls == 1
        kept = len(reference.holding_tracks)
        assert kept == (2 if shift <= datetime.timedelta(0) else 0)
        ours._materialise_all()
        # (the same tracks: see test_array_initiator's docstring)
        assert_same_tracks(ours.holding_tracks, reference.holding_tracks)


def test_a_window_that_is_not_a_timedelta_is_asked_of_the_deleter():
    """(Numeric times, say): the array path calls the deleter rather than assume datetimes."""
    class Window(datetime.timedelta):
        pass
    deleter = UpdateTimeDeleter(Window(seconds=1))
    tracker = ArrayJPDATracker(initiator=None, detector=None, data_associator=None,
                               updater=None, deleter=deleter)
    tracks = [Track(states) for states in _sequences(datetime.timedelta(seconds=1))]
    assert tracker._delete(set(tracks), []) == {t for t in tracks if deleter.check_for_deletion(t)}
    initiator = ArrayMultiMeasurementInitiator(
        prior_state=PRIOR, measurement_model=MEASUREMENT, deleter=deleter, min_points=2,
        updater=KalmanUpdater(MEASUREMENT), data_associator=GNNWith2DAssignment(
            DistanceHypothesiser(KalmanPredictor(TRANSITION), KalmanUpdater(MEASUREMENT),
                                 Mahalanobis(), missed_distance=3)))
    initiator.initiate({Detection(np.zeros((2, 1)), timestamp=T0)}, T0)
    assert initiator.component_calls == 1
