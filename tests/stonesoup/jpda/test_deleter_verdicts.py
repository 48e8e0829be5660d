"""The deletion rules as verdicts from counts (ctxmodels.stonesoup.jpda.deleter's
time_steps_verdict, update_time_verdict, covariance_verdict,
ExpectedMissesDeleter.deletes_after; composite_deleter.composite_verdicts), held against the
deleters whose rules they are: Stone Soup's own ``check_for_deletion`` on random tracks and
covariances, at the boundaries. Both the component path (ctxmodels' deleters) and the array
paths reach their verdicts through these functions."""
from __future__ import annotations

import datetime
import itertools
import math

import numpy as np
import pytest
from stonesoup.deleter.error import CovarianceBasedDeleter
from stonesoup.deleter.multi import CompositeDeleter as StockCompositeDeleter
from stonesoup.deleter.time import UpdateTimeDeleter
from stonesoup.deleter.time import UpdateTimeStepsDeleter as StockUpdateTimeStepsDeleter
from stonesoup.types.detection import Detection, MissedDetection
from stonesoup.types.hypothesis import SingleHypothesis
from stonesoup.types.prediction import GaussianStatePrediction
from stonesoup.types.state import GaussianState
from stonesoup.types.track import Track
from stonesoup.types.update import GaussianStateUpdate

from ctxmodels.stonesoup import (ArrayJPDATracker, CompositeDeleter, ExpectedMissesDeleter,
                                 UpdateTimeStepsDeleter)
from ctxmodels.stonesoup.jpda.composite_deleter import composite_verdicts
from ctxmodels.stonesoup.jpda.deleter import (covariance_verdict, latest_detection_time,
                                              time_steps_verdict, times_since_detection,
                                              update_time_verdict)
from .setups import T0

SECOND = datetime.timedelta(seconds=1)


def _random_track(rng, n):
    """``n`` states: detection-backed updates, updates without a detection and predictions,
    at times that may repeat (two sensors at one instant) or go back."""
    prediction = GaussianStatePrediction(np.zeros((4, 1)), np.eye(4), timestamp=T0)
    states, t = [], 0
    for _ in range(n):
        t += int(rng.integers(-1, 3)) if rng.random() < 0.1 else int(rng.integers(0, 2))
        stamp = T0 + t * SECOND
        kind = rng.integers(3)
        if kind == 2:
            states.append(GaussianStatePrediction(np.zeros((4, 1)), np.eye(4), stamp))
            continue
        measurement = Detection(np.zeros((2, 1)), timestamp=stamp) if kind == 0 \
            else MissedDetection(timestamp=stamp)
        states.append(GaussianStateUpdate(np.zeros((4, 1)), np.eye(4),
                                          SingleHypothesis(prediction, measurement), stamp))
    return Track(states)


@pytest.fixture(scope="module")
def tracks():
    rng = np.random.default_rng(35)
    return [_random_track(rng, int(rng.integers(1, 14))) for _ in range(400)]


# --- the time rules ------------------------------------------------------------------------------
@pytest.mark.parametrize("steps", [0, 1, 2, 3, 5, 2.5])
def test_time_steps_verdict_is_stone_soups(tracks, steps):
    stock = StockUpdateTimeStepsDeleter(time_steps_since_update=steps)
    ours = UpdateTimeStepsDeleter(time_steps_since_update=steps)
    verdicts = [stock.check_for_deletion(t) for t in tracks]
    assert [bool(time_steps_verdict(stock, len(times_since_detection(t.states))))
            for t in tracks] == verdicts
    assert [ours.check_for_deletion(t) for t in tracks] == verdicts
    counts = np.array([len(times_since_detection(t.states)) for t in tracks])
    assert time_steps_verdict(stock, counts).tolist() == verdicts  # elementwise
    if steps:
        assert 0 < sum(verdicts) < len(verdicts)
    assert not ours.check_for_deletion(Track([])) and not stock.check_for_deletion(Track([]))


@pytest.mark.parametrize("seconds", [0.0, 1.0, 2.0, 3.5, -1.0])
def test_update_time_verdict_is_stone_soups(tracks, seconds):
    deleter = UpdateTimeDeleter(time_since_update=datetime.timedelta(seconds=seconds))
    verdicts = [deleter.check_for_deletion(t) for t in tracks]
    assert [update_time_verdict(deleter, latest_detection_time(t.states), t.timestamp)
            for t in tracks] == verdicts
    if seconds > 0:
        assert 0 < sum(verdicts) < len(verdicts)


def test_update_time_verdict_keeps_a_track_updated_exactly_one_window_ago():
    window = datetime.timedelta(seconds=1.2)
    deleter = UpdateTimeDeleter(time_since_update=window)
    tick = datetime.timedelta(microseconds=1)
    assert not update_time_verdict(deleter, T0, T0 + window)
    assert update_time_verdict(deleter, T0, T0 + window + tick)
    assert not update_time_verdict(deleter, T0, T0 + window - tick)
    assert update_time_verdict(deleter, None, T0)


# --- the expected misses ------------------------------------------------------------------------------
def test_deletes_after_sums_newest_first_and_stops_at_the_threshold():
    deleter = ExpectedMissesDeleter(expected_misses=1.0)
    assert not deleter.deletes_after([0.5, 0.25]) and deleter.deletes_after([0.5, 0.25, 0.25])
    assert deleter.deletes_after([1.0]) and not deleter.deletes_after([])
    # newest first: 0.1 + 0.2 + 0.7 is 1.0, while 0.7 + 0.2 + 0.1 is 0.9999999999999999
    assert 0.1 + 0.2 + 0.7 >= 1.0 > 0.7 + 0.2 + 0.1
    assert deleter.deletes_after([0.1, 0.2, 0.7]) and not deleter.deletes_after([0.7, 0.2, 0.1])

    def values():  # read only as far as the verdict needs
        yield 1.0
        raise AssertionError("read past the threshold")
    assert deleter.deletes_after(values())


def test_deletes_after_is_check_for_deletion_on_the_tracks_p_d(tracks):
    """With a default P_D, each track's verdict from its P_D (newest first) is the deleter's,
    and the sum it stops at is expected_misses_since_detection's."""
    rng = np.random.default_rng(3)
    for threshold, default in ((1.0, 1.0), (2.5, 0.35), (0.7, 0.1), (3.0, 0.0)):
        deleter = ExpectedMissesDeleter(expected_misses=threshold, default_prob_detect=default)
        with pytest.warns(Warning):
            verdicts = [deleter.check_for_deletion(t) for t in tracks]
        values = [deleter.prob_detect_since_detection(t) for t in tracks]
        assert [deleter.deletes_after(reversed(v)) for v in values] == verdicts
        assert [deleter.expected_misses_since_detection(t, stop_at=threshold) >= threshold
                for t in tracks] == verdicts
        if default:
            assert 0 < sum(verdicts) < len(verdicts)
        # zeros dropped (as the array tracker keeps them): the same verdicts
        assert [deleter.deletes_after(reversed([p for p in v if p != 0.0]))
                for v in values] == verdicts
    deleter = ExpectedMissesDeleter(expected_misses=2.0)
    draws = [rng.random(int(rng.integers(0, 8))).tolist() for _ in range(500)]
    for v in draws:
        total = 0.0
        for p in reversed(v):
            total += p
            if total >= 2.0:
                break
        assert deleter.deletes_after(reversed(v)) == (total >= 2.0)


# --- the covariance ----------------------------------------------------------------------------------
MAPPINGS = ([0, 2], [2, 0], [0], [-4, -2], [np.int64(0), 2], None, [], (2,), 1,
            [True, False, True, False], [[0, 2]])


def _stock(deleter, covar):
    return deleter.check_for_deletion(Track([GaussianState(np.zeros((len(covar), 1)), covar)]))


def test_covariance_verdict_is_stone_soups_at_the_threshold():
    """Strictly greater deletes: at the threshold, a value either side of it, for every
    mapping form Stone Soup indexes with; a stack gives each row's verdict."""
    threshold = 2.0 * 200.0 ** 2
    above = np.nextafter(40000.0, np.inf)  # (+ 40000 rounds back to the threshold)
    covars = np.stack([np.diag([pxx, 1.0, 40000.0, 1.0]) for pxx in (
        40000.0, np.nextafter(40000.0, 0.0), above, np.nextafter(above, np.inf), 7e4, 1e3)])
    for mapping in MAPPINGS:
        deleter = CovarianceBasedDeleter(covar_trace_thresh=threshold, mapping=mapping)
        expected = [_stock(deleter, c) for c in covars]
        assert [covariance_verdict(deleter, c) for c in covars] == expected
        assert covariance_verdict(deleter, covars).tolist() == expected
    deleter = CovarianceBasedDeleter(covar_trace_thresh=threshold, mapping=[0, 2])
    assert [covariance_verdict(deleter, c) for c in covars] == \
        [False, False, False, True, True, False]


@pytest.mark.parametrize("ndim", range(1, 13))
def test_covariance_verdict_is_stone_soups_on_random_covariances(ndim):
    """Random covariances of 1 to 12 dimensions (entries over ten orders of magnitude, so
    that the order of the additions shows), random mappings, and thresholds at each
    covariance's own sum and one float either side: every verdict is the deleter's, for a
    single covariance and in a stack."""
    rng = np.random.default_rng(ndim)
    for _ in range(60):
        factor = rng.standard_normal((ndim, ndim)) * 10.0 ** rng.integers(-5, 6, size=(ndim, 1))
        covar = factor @ factor.T
        size = int(rng.integers(1, ndim + 1))
        mapping = None if rng.random() < 0.3 else rng.permutation(ndim)[:size].tolist()
        diagonal = np.diag(covar)
        total = np.sum(diagonal[mapping]) if mapping else np.sum(diagonal)
        stack = np.stack([covar] * 3)
        for threshold in (total, np.nextafter(total, -np.inf), np.nextafter(total, np.inf)):
            deleter = CovarianceBasedDeleter(covar_trace_thresh=float(threshold), mapping=mapping)
            expected = _stock(deleter, covar)
            assert covariance_verdict(deleter, covar) == expected
            assert covariance_verdict(deleter, stack).tolist() == [expected] * 3
        assert not covariance_verdict(
            CovarianceBasedDeleter(covar_trace_thresh=float(total), mapping=mapping), covar)


def test_covariance_verdict_raises_where_stone_soup_does():
    covar = np.eye(4)
    for mapping, error in (((0, 2), IndexError), ([7], IndexError),
                           (np.array([0, 2]), ValueError)):
        deleter = CovarianceBasedDeleter(covar_trace_thresh=1.0, mapping=mapping)
        with pytest.raises(error):
            _stock(deleter, covar)
        with pytest.raises(error):
            covariance_verdict(deleter, covar)
        with pytest.raises(error):
            covariance_verdict(deleter, covar[np.newaxis])


def test_the_array_trackers_covariance_verdicts_from_the_scans_covariances():
    """Given the scan's stacked posterior covariances (each plain track's last state holding
    its row), the array path's verdicts are the deleter's, at the boundary, for every
    mapping form; a track outside the scan, or not known to hold its row, is judged on its
    own last covariance."""
    from stonesoup.types.array import CovarianceMatrix
    threshold = 2.0 * 200.0 ** 2
    diagonals = [40000.0, np.nextafter(40000.0, 0.0), np.nextafter(40000.0, np.inf), 7e4, 1e3]
    covars = np.stack([np.diag([pxx, 1.0, 40000.0, 1.0]) for pxx in diagonals])
    tracks = [Track([GaussianState(np.zeros((4, 1)), covar.view(CovarianceMatrix))])
              for covar in covars]
    outside = Track([GaussianState(np.zeros((4, 1)), np.diag([5e4, 1.0, 4e4, 1.0]))])
    latest = (tracks, np.zeros((len(tracks), 4)), covars, None)
    for mapping in MAPPINGS:
        deleter = CovarianceBasedDeleter(covar_trace_thresh=threshold, mapping=mapping)
        tracker = ArrayJPDATracker(initiator=None, detector=None, data_associator=None,
                                   updater=None, deleter=deleter)
        expected = {t for t in tracks + [outside] if deleter.check_for_deletion(t)}
        assert tracker._delete(set(tracks) | {outside}, [], latest, set(tracks)) == expected
        assert tracker._delete(set(tracks) | {outside}, [], latest) == expected
        assert tracker._plan is not None


# --- composites ---------------------------------------------------------------------------------------
class _Scripted:
    """A per-track member whose verdicts are given, recording which tracks it was asked
    about."""

    def __init__(self, verdicts):
        self.script = verdicts
        self.asked = []

    def check_for_deletion(self, track, **kwargs):
        self.asked.append(track)
        return self.script[track]


@pytest.mark.parametrize("intersect", [True, False])
def test_composite_verdicts_are_stone_soups_and_ask_what_it_asks(intersect):
    """Every combination of three members' verdicts on a track: the verdict of Stone Soup's
    composite, each member asked about exactly the tracks Stone Soup's asks it about."""
    combos = list(itertools.product([False, True], repeat=3))
    tracks = [Track([GaussianState(np.zeros((1, 1)), np.eye(1), timestamp=T0 + k * SECOND)])
              for k in range(len(combos))]
    runs = {}
    for name in ("stock", "ours", "function"):
        members = [_Scripted({t: c[j] for t, c in zip(tracks, combos)}) for j in range(3)]
        if name == "stock":
            deleter = StockCompositeDeleter(intersect=intersect, deleters=members)
            verdicts = [deleter.check_for_deletion(t) for t in tracks]
        elif name == "ours":
            deleter = CompositeDeleter(intersect=intersect, deleters=members)
            asked = [m.asked for m in members]
            one_by_one = [deleter.check_for_deletion(t) for t in tracks]
            one_by_one_asked = [set(a) for a in asked]
            for a in asked:
                a.clear()
            deleted = deleter.delete_tracks(tracks)
            verdicts = [t in deleted for t in tracks]
            assert one_by_one == verdicts
            assert one_by_one_asked == [set(a) for a in asked]
        else:
            verdicts = composite_verdicts(intersect, [
                lambda rows, m=m: [m.check_for_deletion(tracks[r]) for r in rows]
                for m in members], len(tracks))
        runs[name] = (verdicts, [set(m.asked) for m in members])
    expected = [all(c) if intersect else any(c) for c in combos]
    assert runs["stock"][0] == expected
    assert runs["ours"] == runs["stock"] and runs["function"] == runs["stock"]


def test_composite_verdicts_stop_asking_once_every_track_is_decided():
    def never(rows):
        raise AssertionError("asked after every track was decided")
    assert composite_verdicts(False, [lambda rows: [True] * len(rows), never], 3) == [True] * 3
    assert composite_verdicts(True, [lambda rows: [0] * len(rows), never], 2) == [False] * 2
    assert composite_verdicts(True, [], 2) == [True, True]
    assert composite_verdicts(False, [], 2) == [False, False]
    assert composite_verdicts(True, [never], 0) == []


def test_verdict_functions_need_no_track():
    """What each takes: counts, times, covariances — no track."""
    assert time_steps_verdict(StockUpdateTimeStepsDeleter(time_steps_since_update=3), 4)
    assert not time_steps_verdict(StockUpdateTimeStepsDeleter(time_steps_since_update=3), 3)
    assert update_time_verdict(UpdateTimeDeleter(time_since_update=SECOND), T0, T0 + 2 * SECOND)
    assert covariance_verdict(CovarianceBasedDeleter(covar_trace_thresh=1.0), np.eye(2))
    assert ExpectedMissesDeleter(expected_misses=math.pi).deletes_after([1.0] * 4)


# --- the array paths ask the same verdicts -----------------------------------------------------------
def test_both_array_paths_ask_the_deleters_own_verdict(monkeypatch):
    """ArrayJPDATracker's deletion (from its per-track counters) and the array initiator's
    holding rows (from their per-row counts) both reach the ExpectedMissesDeleter's verdict
    through its deletes_after, and agree with its check_for_deletion."""
    from ctxmodels.stonesoup import MissesNotWeighedWarning
    from ctxmodels.stonesoup.jpda._initiator_deletion import HoldingCounts
    asked = []
    original = ExpectedMissesDeleter.deletes_after

    def deletes_after(self, prob_detect):
        asked.append(self)
        return original(self, prob_detect)
    monkeypatch.setattr(ExpectedMissesDeleter, "deletes_after", deletes_after)
    deleter = ExpectedMissesDeleter(expected_misses=1.0, default_prob_detect=0.6)
    update = GaussianStateUpdate(np.zeros((4, 1)), np.eye(4), SingleHypothesis(
        None, Detection(np.zeros((2, 1)), timestamp=T0)), timestamp=T0)
    tracks = [Track([update] + [GaussianStatePrediction(np.zeros((4, 1)), np.eye(4),
                                                        timestamp=T0 + (k + 1) * SECOND)
                                for k in range(misses)]) for misses in (0, 1, 2)]
    tracker = ArrayJPDATracker(initiator=None, detector=None, data_associator=None,
                               updater=None, deleter=deleter)
    with pytest.warns(MissesNotWeighedWarning):
        assert tracker._delete(set(tracks), []) == {tracks[2]}
    assert [deleter.check_for_deletion(t) for t in tracks] == [False, False, True]
    assert asked.count(deleter) == 6 and tracker._plan is not None
    rows = HoldingCounts()
    rows.add([(1, T0)] * 3, [[], [0.6], [0.6, 0.6]])
    asked.clear()
    assert rows.expired(deleter, [T0] * 3).tolist() == [False, False, True]
    assert asked == [deleter] * 3
    steps = StockUpdateTimeStepsDeleter(time_steps_since_update=2)
    rows.since = np.array([1, 2, 3])
    assert rows.expired(steps, [T0] * 3).tolist() == [False, False, True]
