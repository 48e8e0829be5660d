"""DuplicateTrackDeleter (the track-to-track χ² test, one track of each duplicate pair
deleted) and ctxmodels' CompositeDeleter (Stone Soup's, also taking members that compare
tracks), on their own and on ArrayJPDATracker's array path against the component path."""
from __future__ import annotations

import copy
import datetime
import math
import random

import numpy as np
import pytest
from stonesoup.deleter.error import CovarianceBasedDeleter
from stonesoup.deleter.multi import CompositeDeleter as StockCompositeDeleter
from stonesoup.deleter.time import UpdateTimeDeleter, UpdateTimeStepsDeleter
from stonesoup.types.detection import Detection
from stonesoup.types.hypothesis import SingleHypothesis
from stonesoup.types.prediction import GaussianStatePrediction
from stonesoup.types.track import Track
from stonesoup.types.update import GaussianStateUpdate

from ctxmodels.stonesoup import CompositeDeleter, DuplicateTrackDeleter
from .array_setups import RTOL, _lengths, pair, run_side_by_side, tutorial_pair, two_rate_scans
from .setups import T0

SECOND = datetime.timedelta(seconds=1)


def state(x, y, t=T0, var=(0.5, 0.5), backed=False, vx=0.0):
    """A 4-D state [x, vx, y, vy] at ``t`` with position variances ``var``: an update with a
    detection (``backed``) or a prediction."""
    vector = np.array([[x], [vx], [y], [0.0]])
    covar = np.diag([var[0], 1.0, var[1], 1.0])
    if backed:
        return GaussianStateUpdate(vector, covar, SingleHypothesis(
            None, Detection(np.zeros((2, 1)), timestamp=t)), timestamp=t)
    return GaussianStatePrediction(vector, covar, timestamp=t)


def track(x, y, updates=1, born=T0 - 10 * SECOND, **kwargs):
    """A track born at ``born`` with ``updates`` detection-backed states, ending at (x, y)
    at T0."""
    states = [state(x, y, t=born + k * datetime.timedelta(milliseconds=10), backed=True)
              for k in range(updates)]
    return Track(states + [state(x, y, **kwargs)])


# --- the statistic ---------------------------------------------------------------------------------
def test_d2_is_the_track_to_track_statistic_with_a_strict_gate():
    """P₁ = P₂ = diag(0.5, 2) (position): S = diag(1, 4); Δ = (2, 2): d² = 4 + 1 = 5."""
    a, b = track(0.0, 0.0, var=(0.5, 2.0)), track(2.0, 2.0, var=(0.5, 2.0))
    assert DuplicateTrackDeleter(threshold=5.0).delete_tracks({a, b}) == set()
    assert len(DuplicateTrackDeleter(threshold=np.nextafter(5.0, 6.0)).delete_tracks({a, b})) == 1
    # the default gate (χ²₂ 99 %) and its documented value
    assert DuplicateTrackDeleter().threshold == 9.21
    assert math.isclose(-2 * math.log(0.01), 9.21, abs_tol=1e-3)


def test_mapping_selects_the_compared_components():
    a, b = track(0.0, 0.0, vx=0.0), track(0.0, 0.0, vx=100.0)
    assert len(DuplicateTrackDeleter().delete_tracks([a, b])) == 1  # same position
    assert DuplicateTrackDeleter(mapping=[0, 1]).delete_tracks([a, b]) == set()


def test_only_tracks_whose_latest_states_share_a_time_are_compared():
    a = track(0.0, 0.0)
    b = Track([state(0.0, 0.0, t=T0 - SECOND, backed=True), state(0.0, 0.0, t=T0 + SECOND)])
    assert DuplicateTrackDeleter().delete_tracks([a, b]) == set()


def test_a_singular_sum_of_covariances_is_not_a_duplicate():
    a, b = track(0.0, 0.0, var=(0.0, 0.0)), track(0.0, 0.0, var=(0.0, 0.0))
    c, d = track(50.0, 0.0), track(50.0, 0.0, updates=3)  # (another pair in the same batch)
    assert DuplicateTrackDeleter().delete_tracks([a, b, c, d]) == {c}


# --- which track goes ------------------------------------------------------------------------------
def test_the_track_with_fewer_detections_goes():
    old, new = track(0.0, 0.0, updates=2, born=T0 - 9 * SECOND), track(0.5, 0.0, updates=3)
    assert DuplicateTrackDeleter().delete_tracks([old, new]) == {old}


def test_on_equal_detections_the_younger_goes():
    old, young = track(0.0, 0.0, updates=2), track(0.5, 0.0, updates=2, born=T0 - 5 * SECOND)
    assert DuplicateTrackDeleter().delete_tracks([young, old]) == {young}


def test_on_equal_age_the_later_in_content_order_goes():
    a, b = track(0.0, 0.0, updates=2), track(0.5, 0.0, updates=2)  # first states differ in x
    assert DuplicateTrackDeleter().delete_tracks([b, a]) == {b}
    twin = copy.copy(a)  # equal content: the track id decides
    twin.id = "0" + a.id if a.id > "0" else a.id + "0"
    gone, = DuplicateTrackDeleter().delete_tracks([a, twin])
    assert gone is max((a, twin), key=lambda t: t.id)


def test_chains_resolve_by_increasing_distance_and_the_deleted_delete_nothing():
    """A–B at d² 1, B–C at d² 4, A–C apart (d² 9 ≥ the gate): A–B first."""
    def line(updates):
        return [track(0.0, 0.0, updates=updates[0]), track(1.0, 0.0, updates=updates[1]),
                track(3.0, 0.0, updates=updates[2])]
    deleter = DuplicateTrackDeleter(threshold=8.0)
    a, b, c = line((3, 1, 2))  # B loses to A; B–C skipped: C stays, though B's duplicate
    assert deleter.delete_tracks([c, b, a]) == {b}
    a, b, c = line((1, 3, 2))  # A loses to B, then C to B
    assert deleter.delete_tracks([c, a, b]) == {a, c}
    a, b, c = line((2, 1, 3))  # B loses to A; C is left, and A is not compared with C
    assert deleter.delete_tracks([b, c, a]) == {b}


def _crowd(seed):
    """Eighteen tracks in clusters of one to four around six points: near, chained and
    separate pairs, random histories."""
    rng = np.random.default_rng(seed)
    tracks = []
    for _ in range(6):
        cx, cy = rng.uniform(-50, 50, size=2)
        for _ in range(rng.integers(1, 5)):
            x, y = cx + rng.normal(0, 1.0), cy + rng.normal(0, 1.0)
            tracks.append(track(x, y, updates=int(rng.integers(1, 4)),
                                born=T0 - int(rng.integers(5, 8)) * SECOND,
                                var=tuple(rng.uniform(0.3, 2.0, size=2))))
    return tracks


@pytest.mark.parametrize("seed", range(4))
def test_verdicts_do_not_depend_on_the_order_of_the_tracks(seed):
    tracks = _crowd(seed)
    deleter = DuplicateTrackDeleter()
    expected = deleter.delete_tracks(tracks)
    assert 0 < len(expected) < len(tracks)
    shuffler = random.Random(seed)
    for _ in range(30):
        order = list(tracks)
        shuffler.shuffle(order)
        assert deleter.delete_tracks(order) == expected
        assert deleter.delete_tracks(set(order)) == expected
    # copies (other addresses, so other set orders) of the same tracks: the same ones go
    copies = {id(t): copy.copy(t) for t in tracks}
    assert {copies[id(t)] for t in expected} == deleter.delete_tracks(set(copies.values()))


# --- the deleter interface -------------------------------------------------------------------------
def test_a_pairwise_deleter_judges_no_track_alone():
    a, b = track(0.0, 0.0), track(0.0, 0.0, updates=2)
    with pytest.raises(TypeError, match="ctxmodels.stonesoup.CompositeDeleter"):
        DuplicateTrackDeleter().check_for_deletion(a)
    stock = StockCompositeDeleter(intersect=False, deleters=[DuplicateTrackDeleter()])
    with pytest.raises(TypeError, match="compares tracks with each other"):
        stock.delete_tracks({a, b})


def test_delete_last_pred_drops_the_deleted_tracks_last_prediction():
    a, b = track(0.0, 0.0), track(0.0, 0.0, updates=2)
    assert DuplicateTrackDeleter(delete_last_pred=True).delete_tracks([a, b]) == {a}
    assert len(a) == 1 and len(a.metadatas) == 1 and len(b) == 3


@pytest.mark.parametrize("bad, error", [
    (dict(threshold=0.0), ValueError), (dict(threshold=-1.0), ValueError),
    (dict(threshold=math.nan), ValueError), (dict(threshold=math.inf), ValueError),
    (dict(threshold="9.21"), TypeError), (dict(threshold=True), TypeError),
    (dict(mapping=[]), ValueError), (dict(mapping=()), ValueError),
    (dict(mapping=None), TypeError), (dict(mapping=[0, 0]), ValueError),
    (dict(mapping=[0.0, 2]), TypeError), (dict(mapping=[-1, 2]), TypeError),
])
def test_bad_arguments_raise_naming_them(bad, error):
    name, = bad
    with pytest.raises(error, match=f"^{name}: "):
        DuplicateTrackDeleter(**bad)


def test_numpy_integer_mapping_is_accepted():
    a, b = track(0.0, 0.0), track(0.0, 0.0, updates=2)
    assert DuplicateTrackDeleter(mapping=np.array([0, 2])).delete_tracks([a, b]) == {a}


# --- ctxmodels' CompositeDeleter ----------------------------------------------------------------
def _mixed_tracks():
    """Tracks with 0–3 misses since their last detection and various position variances."""
    tracks = []
    for misses in range(4):
        for var in (0.5, 3.0, 9.0):
            states = [state(0.0, 0.0, t=T0, backed=True)]
            states += [state(0.0, 0.0, t=T0 + (k + 1) * SECOND, var=(var, var))
                       for k in range(misses)]
            tracks.append(Track(states))
    return tracks


@pytest.mark.parametrize("intersect", [True, False])
def test_per_track_members_give_stone_soups_verdicts(intersect):
    members = [UpdateTimeStepsDeleter(2), CovarianceBasedDeleter(covar_trace_thresh=7.0,
                                                                 mapping=[0, 2]),
               UpdateTimeDeleter(1.5 * SECOND)]
    tracks = _mixed_tracks()
    ours = CompositeDeleter(intersect=intersect, deleters=members).delete_tracks(tracks)
    stock = StockCompositeDeleter(intersect=intersect, deleters=members).delete_tracks(tracks)
    assert ours == stock and 0 < len(ours) < len(tracks)
    assert CompositeDeleter(deleters=members).check_for_deletion(tracks[-1]) == \
        StockCompositeDeleter(deleters=members).check_for_deletion(tracks[-1])


def test_a_pairwise_member_is_asked_about_the_whole_set():
    recent = T0 - SECOND
    a, b = track(0.0, 0.0, born=recent), track(0.0, 0.0, updates=2, born=recent)
    far = track(90.0, 0.0, born=recent)
    late = Track([state(0.0, 0.0, t=T0 - 3 * SECOND, backed=True), state(90.0, 9.0)])
    tracks = [a, b, far, late]
    time = UpdateTimeDeleter(2 * SECOND)
    union = CompositeDeleter(intersect=False, deleters=[time, DuplicateTrackDeleter()])
    assert union.delete_tracks(tracks) == {a, late}
    both = CompositeDeleter(intersect=True, deleters=[time, DuplicateTrackDeleter()])
    assert both.delete_tracks(tracks) == set()
    nested = CompositeDeleter(intersect=False, deleters=[
        CompositeDeleter(deleters=[DuplicateTrackDeleter()]), time])
    assert nested.delete_tracks(tracks) == {a, late}
    with pytest.raises(TypeError, match="CompositeDeleter compares tracks"):
        union.check_for_deletion(a)


# --- on the array path -----------------------------------------------------------------------------
def _tuned(seconds, threshold=9.21, dup=True):
    """The tuned JPDA's deleter: a time window or duplicates (the duplicate member off:
    the time window alone)."""
    window = UpdateTimeDeleter(datetime.timedelta(seconds=seconds))
    if not dup:
        return window
    return CompositeDeleter(intersect=False, deleters=[
        window, DuplicateTrackDeleter(threshold=threshold)])


@pytest.mark.parametrize("config", [
    dict(deleter=lambda h: _tuned(3.0)),
    dict(deleter=lambda h: _tuned(3.0, threshold=50.0)),
    dict(deleter=lambda h: DuplicateTrackDeleter(threshold=20.0, mapping=[0, 1, 2])),
    dict(deleter=lambda h: CompositeDeleter(intersect=True, deleters=[
        UpdateTimeStepsDeleter(1), DuplicateTrackDeleter()])),
])
def test_array_path_gives_the_component_paths_tracks(config):
    ours, reference = tutorial_pair(**config)
    worst, scans = run_side_by_side(ours, reference)
    assert worst <= RTOL
    assert ours.array_scans == scans and ours.component_scans == 0
    assert ours._plan is not None and ours._plan.deleter is ours.deleter  # not called


def test_the_duplicate_member_deletes_tracks_in_the_tutorial_run():
    with_duplicates, _ = tutorial_pair(deleter=lambda h: _tuned(3.0))
    without, _ = tutorial_pair(deleter=lambda h: _tuned(3.0, dup=False))
    assert _lengths(with_duplicates) != _lengths(without)


def test_tuned_jpda_with_time_windows_on_two_rate_scans():
    """The tuned JPDA's shape: holding and tracking windows in time, duplicates merged, on a
    1 Hz and a 2.5 Hz sensor."""
    ours, reference = pair(lambda: _tuned(2.0), lambda: UpdateTimeDeleter(SECOND),
                           two_rate_scans())
    worst, scans = run_side_by_side(ours, reference)
    assert worst <= RTOL
    assert ours.array_scans == scans and ours.component_scans == 0
    assert ours.initiator.component_calls == 0 and ours._plan is not None


def test_stone_soups_composite_with_a_pairwise_member_raises_on_both_paths():
    make = lambda h: StockCompositeDeleter(intersect=False, deleters=[  # noqa: E731
        UpdateTimeDeleter(3 * SECOND), DuplicateTrackDeleter()])
    ours, reference = tutorial_pair(deleter=make)
    for tracker in (ours, reference):
        with pytest.raises(TypeError, match="ctxmodels.stonesoup.CompositeDeleter"):
            for _ in tracker:
                pass
    assert ours._plan is None  # the deleter was called, as on the component path


def test_properties_set_after_construction_are_read_and_checked():
    a, b = track(0.0, 0.0, vx=0.0), track(0.0, 0.0, vx=100.0)
    deleter = DuplicateTrackDeleter()
    deleter.mapping = [0, 1]
    assert deleter.delete_tracks([a, b]) == set()
    deleter.threshold = -1.0
    with pytest.raises(ValueError, match="^threshold: "):
        deleter.delete_tracks([a, b])


def test_tuned_jpda_on_the_experiment_scenario():
    """The experiment's JPDA on 10 s of its mixed-range scenario (radar 0.8 Hz, lidar
    10 Hz; the closed-form bearing–range Jacobian, for agreement to RTOL) with the windows
    in time and duplicates deleted: the array path's tracks are the component path's."""
    from .array_setups import _scenario_pair
    ours, reference = _scenario_pair("jpda", 10.0, closed_form=True)
    for tracker in (ours, reference):
        tracker.initiator.deleter = UpdateTimeDeleter(datetime.timedelta(seconds=2.5))
        tracker.deleter = _tuned(2.5)
    worst, scans = run_side_by_side(ours, reference)
    assert worst <= RTOL
    assert ours.array_scans == scans > 100 and ours.component_scans == 0
    assert ours.initiator.component_calls == 0 and ours._plan is not None
