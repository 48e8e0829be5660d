"""ctxmodels' trackers fed hostile scans: the four ctxmodels trackers (component-path JPDA,
ArrayJPDATracker, component-path GM-PHD, ArrayPointProcessTracker) refuse the same bad scans
with the same message, naming the scan (its index in the run and its time) and the
detection; the documented-equivalent array and component paths agree. See
ctxmodels.stonesoup.scan_checks.
"""
from __future__ import annotations

import contextlib
import datetime
import math

import numpy as np
import pytest
from stonesoup.dataassociator.probability import JPDAwithEHM2
from stonesoup.deleter.time import UpdateTimeStepsDeleter
from stonesoup.initiator.simple import SimpleMeasurementInitiator
from stonesoup.predictor.kalman import KalmanPredictor
from stonesoup.types.detection import Detection
from stonesoup.types.state import GaussianState, State
from stonesoup.updater.kalman import KalmanUpdater

from ctxmodels import DetectionSet
from ctxmodels.stonesoup import (
    ArrayJPDATracker,
    ArrayPointProcessTracker,
    ComponentPathWarning,
    MultiTargetMixtureTracker,
    PDAHypothesiser,
    PointProcessMultiTargetTracker,
)

from .gmphd.setups import birth_component, stock_components, tutorial_scenario
from .jpda.setups import CLUTTER, MEASUREMENT, PD, T0, TRANSITION, track_at

UTC = datetime.timezone.utc


# --- the four trackers ------------------------------------------------------------------------
def _first_time(scans):
    try:
        time = scans[0][0]
    except (IndexError, TypeError, KeyError):
        return None
    return time if isinstance(time, datetime.datetime) else None


def _jpda(cls, scans, updater_model=MEASUREMENT, track_time=None):
    if track_time is None:  # the track on the first scan's clock (naive or aware)
        first = _first_time(scans)
        track_time = T0.replace(tzinfo=first.tzinfo if first is not None else None)
    predictor, updater = KalmanPredictor(TRANSITION), KalmanUpdater(updater_model)
    hypothesiser = PDAHypothesiser(predictor, updater, clutter_spatial_density=CLUTTER,
                                   prob_detect=PD)
    initiator = SimpleMeasurementInitiator(
        GaussianState(np.zeros((4, 1)), np.diag([1.5, 0.5, 1.5, 0.5])), MEASUREMENT)
    tracker = cls(initiator=initiator, deleter=UpdateTimeStepsDeleter(3), detector=scans,
                  data_associator=JPDAwithEHM2(hypothesiser), updater=updater)
    tracker._tracks.add(track_at(0.0, 0.0, t=track_time))  # a track: the hypothesiser runs
    return tracker


def _gmphd(cls, scans, **_):
    scenario = tutorial_scenario(n_scans=2)
    return cls(detector=scans, birth_component=birth_component(scenario),
               extraction_threshold=0.5, **stock_components(scenario, context_updater=True))


TRACKERS = {
    "jpda-component": lambda scans, **kw: _jpda(MultiTargetMixtureTracker, scans, **kw),
    "jpda-array": lambda scans, **kw: _jpda(ArrayJPDATracker, scans, **kw),
    "gmphd-component": lambda scans, **kw: _gmphd(PointProcessMultiTargetTracker, scans),
    "gmphd-array": lambda scans, **kw: _gmphd(ArrayPointProcessTracker, scans),
}


def at(seconds, tz=None):
    return (T0 + datetime.timedelta(seconds=seconds)).replace(tzinfo=tz)


def det(values, seconds=1.0, tz=None, model=MEASUREMENT):
    return Detection(np.array(values, dtype=float).reshape(-1, 1), timestamp=at(seconds, tz),
                     measurement_model=model)


def good(seconds, tz=None):
    return (at(seconds, tz), {det([1.0, 1.0], seconds, tz), det([3.0, -2.0], seconds, tz)})


def _falls_back(kind, reason):
    """An array tracker's scan that runs the component path (as intended): its one
    ComponentPathWarning, naming ``reason``; nothing for the component trackers."""
    if "array" not in kind:
        return contextlib.nullcontext()
    return pytest.warns(ComponentPathWarning, match=reason)


def _refusal(tracker, exception):
    with pytest.raises(exception) as info:
        list(tracker)
    return str(info.value)


# (id, scans, exception, message prefix, texts the message must hold)
HOSTILE_SCANS = [
    ("detections-None", [(at(1), None)], TypeError, "detector:", ["scan 0", str(at(1)), "NoneType"]),
    ("detections-str", [(at(1), "detections")], TypeError, "detector:", ["scan 0", "str"]),
    ("detections-bytes", [(at(1), b"\x00")], TypeError, "detector:", ["scan 0", "bytes"]),
    ("detections-int", [(at(1), 5)], TypeError, "detector:", ["scan 0", "int"]),
    ("item-str", [(at(1), ["abc"])], TypeError, "detections:", ["item 0", "scan 0", "str"]),
    ("item-None", [(at(1), [det([1, 1]), None])], TypeError, "detections:", ["item 1", "NoneType"]),
    ("item-State", [(at(1), [State([[1.0], [1.0]], timestamp=at(1))])], TypeError,
     "detections:", ["item 0", "State"]),
    ("item-array", [(at(1), [np.array([[1.0], [1.0]])])], TypeError, "detections:",
     ["item 0", "ndarray"]),
    ("scan-not-a-pair", [{det([1, 1])}], TypeError, "detector:", ["scan 0", "pair"]),
    ("scan-three-items", [(at(1), set(), "x")], TypeError, "detector:", ["scan 0", "3 items"]),
    ("scan-None", [None], TypeError, "detector:", ["scan 0", "NoneType"]),
    ("time-None", [(None, {det([1, 1])})], TypeError, "detector:", ["scan 0", "datetime"]),
    ("time-str", [("2024-05-01 12:00:01", {det([1, 1])})], TypeError, "detector:",
     ["scan 0", "str"]),
    ("time-float", [(1.0, set())], TypeError, "detector:", ["scan 0", "float"]),
    ("time-date", [(datetime.date(2024, 5, 1), set())], TypeError, "detector:", ["scan 0", "date"]),
    ("nan-x", [good(1), (at(2), {det([math.nan, 5.0], 2), det([1.0, 1.0], 2)})], ValueError,
     "detections:", ["scan 1", str(at(2)), "not finite", "nan"]),
    ("nan-y", [(at(1), {det([5.0, math.nan])})], ValueError, "detections:",
     ["row 0", "scan 0", "not finite"]),
    ("plus-inf", [(at(1), {det([math.inf, 5.0])})], ValueError, "detections:", ["not finite", "inf"]),
    ("minus-inf", [(at(1), {det([1.0, -math.inf]), det([0.0, 0.0])})], ValueError,
     "detections:", ["not finite", "-inf"]),
    ("huge-overflowing", [(at(1), {Detection(np.array([[1e308 * 10], [0.0]]), timestamp=at(1),
                                             measurement_model=MEASUREMENT)})],
     ValueError, "detections:", ["not finite"]),
    ("three-elements", [(at(1), {det([1.0, 1.0, 3.0])})], ValueError, "detections:",
     ["row 0", "scan 0", "3 elements", "measures 2"]),
    ("one-element", [good(1), (at(2), {det([1.0], 2), det([1.0, 2.0], 2)})], ValueError,
     "detections:", ["scan 1", "1 elements", "measures 2"]),
    ("backwards", [good(2), good(1)], ValueError, "detector:",
     ["scan 1", str(at(1)), "earlier", str(at(2))]),
    ("backwards-later", [good(1), good(3), good(2)], ValueError, "detector:", ["scan 2"]),
    ("naive-then-aware", [good(1), good(2, UTC)], ValueError, "detector:",
     ["scan 1", "timezone-aware", str(at(1))]),
    ("aware-then-naive", [good(1, UTC), good(2)], ValueError, "detector:",
     ["scan 1", "timezone-naive"]),
    ("aware-detection-in-naive-scan", [(at(1), {det([1.0, 1.0], 1, UTC)})], ValueError,
     "detections:", ["scan 0", "timezone-aware", "[1.0, 1.0]"]),
    ("naive-detection-in-aware-scan",
     [(at(1, UTC), {det([1.0, 1.0], 1, UTC), det([2.0, 1.0], 1)})], ValueError,
     "detections:", ["scan 0", "timezone-naive", "[2.0, 1.0]"]),
]


@pytest.mark.parametrize("kind", list(TRACKERS))
@pytest.mark.parametrize("name, scans, exception, prefix, texts", HOSTILE_SCANS,
                         ids=[case[0] for case in HOSTILE_SCANS])
def test_hostile_scans_are_refused_naming_the_scan(kind, name, scans, exception, prefix, texts):
    message = _refusal(TRACKERS[kind](scans), exception)
    assert message.startswith(prefix), message
    for text in texts:
        assert text in message, (text, message)


@pytest.mark.parametrize("name, scans, exception, prefix, texts", HOSTILE_SCANS,
                         ids=[case[0] for case in HOSTILE_SCANS])
def test_array_and_component_paths_refuse_with_the_same_message(name, scans, exception, prefix,
                                                                texts):
    """The documented-equivalent paths: one message, word for word (before, the component
    JPDA and GM-PHD silently dropped a NaN detection at constant λ)."""
    for component, array in (("jpda-component", "jpda-array"),
                             ("gmphd-component", "gmphd-array")):
        assert _refusal(TRACKERS[component](scans), exception) == \
            _refusal(TRACKERS[array](scans), exception)


@pytest.mark.parametrize("kind", list(TRACKERS))
def test_nan_detection_with_a_context_is_refused_the_same_way(kind):
    from .jpda.setups import ORIGIN, constant_sensor
    sensor = constant_sensor()
    scans = [(at(1), DetectionSet({det([math.nan, 5.0]), det([1.0, 1.0])},
                                  detector_context=sensor.context(ORIGIN.pose_at(at(1)))))]
    message = _refusal(TRACKERS[kind](scans), ValueError)
    assert message.startswith("detections: row 1 of scan 0 at ") and "not finite" in message


@pytest.mark.parametrize("kind", list(TRACKERS))
def test_detection_without_a_model_is_named_with_its_scan(kind):
    """No model on the detection and none on the updater: Stone Soup's bare "No
    measurement model specified", now with the scan and the detection."""
    scans = [good(1), (at(2), {det([1.0, 1.0], 2, model=None), det([0.5, 0.5], 2)})]
    with _falls_back(kind, "2 distinct measurement models"):
        message = _refusal(TRACKERS[kind](scans, updater_model=None), ValueError)
    assert message.startswith("detections: scan 1 at " + str(at(2))), message
    assert "row 0 ([0.5, 0.5])" not in message and "[1.0, 1.0]" in message
    assert "no measurement model" in message


@pytest.mark.parametrize("kind", ["jpda-component", "jpda-array"])
def test_aware_scan_against_a_naive_track_is_named(kind):
    message = _refusal(TRACKERS[kind]([good(1, UTC)], track_time=T0), ValueError)
    assert message.startswith(f"detector: scan 0 at {at(1, UTC)}:"), message
    assert "timezone-aware" in message


@pytest.mark.parametrize("kind", list(TRACKERS))
@pytest.mark.parametrize("name, scans", [
    ("empty-set", [(at(1), set())]),
    ("empty-list", [(at(1), [])]),
    ("empty-tuple", [(at(1), ())]),
    ("empty-detection-set", [(at(1), DetectionSet(set()))]),
    ("generator", [(at(1), (d for d in good(1)[1]))]),
    ("same-time-twice", [good(1), good(1), good(2)]),
    ("aware-throughout", "aware"),
    ("detection-time-not-the-scans", [(at(1), {det([1.0, 1.0], 3)})]),
])
def test_odd_but_valid_scans_run(kind, name, scans):
    if scans == "aware":
        scans = [good(1, UTC), good(2, UTC)]
    tracker = TRACKERS[kind](scans)
    with _falls_back(kind if name == "detection-time-not-the-scans" else "", "timestamps other"):
        out = list(tracker)
    assert [time for time, _ in out] == [time for time, _ in scans]


def test_refusal_happens_before_any_work():
    """A refused scan leaves the tracker as it was: the next good scan runs."""
    for kind in TRACKERS:
        tracker = TRACKERS[kind]([])
        tracker.update_tracker(*good(1))
        before = {id(t): len(t) for t in tracker.tracks}
        with pytest.raises(ValueError):
            tracker.update_tracker(at(2), {det([math.nan, 1.0], 2)})
        assert {id(t): len(t) for t in tracker.tracks} == before, kind
        tracker.update_tracker(*good(2))
