"""Detections that carry their own measurement-model objects run on the array path: the
array trackers group a scan by the models' *values* (``ctxmodels.model_key``), never by
object identity, and count and announce (once) the scans that still fall back."""
from __future__ import annotations

import copy
import datetime
import math
import warnings

import numpy as np
import pytest
from stonesoup.models.measurement.linear import LinearGaussian
from stonesoup.models.measurement.nonlinear import CartesianToBearingRange
from stonesoup.models.transition.linear import (CombinedLinearGaussianTransitionModel,
                                                ConstantVelocity)
from stonesoup.platform.base import MovingPlatform
from stonesoup.sensor.radar.radar import RadarBearingRange
from stonesoup.types.array import StateVector
from stonesoup.types.groundtruth import GroundTruthState
from stonesoup.types.state import State

from ctxmodels import NavigationTrack, SensorModel
from ctxmodels.experiment.scenarios import make_scenario
from ctxmodels.experiment.sensors import paper_sensor_models
from ctxmodels.trackers import paper_tracker
from ctxmodels.model_key import measurement_model_key
from ctxmodels.stonesoup import (AnalyticCartesianToBearingRange, ArrayJPDATracker,
                                 ArrayPointProcessTracker, ComponentPathWarning,
                                 in_track_order, sensor_pose)

TRACKERS = {"gmphd-context": ArrayPointProcessTracker, "jpda-context": ArrayJPDATracker}


# --- helpers ------------------------------------------------------------------------------------
def _fresh(detection):
    """The detection with a fresh, equal measurement model of its own (new arrays too)."""
    new = copy.copy(detection)
    new.measurement_model = copy.deepcopy(detection.measurement_model)
    return new


def _streams(run, change=lambda t, detections: detections):
    return {sensor: [(s.timestamp, set(change(s.timestamp, list(s.detections)))) for s in scans]
            for sensor, scans in (("radar", run.radar_scans), ("lidar", run.lidar_scans))}


def _navigation(run):
    return NavigationTrack(timestamps=run.ego.timestamps, positions=run.ego.positions,
                           headings=run.ego.headings)


def _run(name, streams, navigation, models=None):
    """Runs the study's tracker over the streams: (the array tracker, per scan the tracks'
    states and covariances in track order)."""
    tracker = paper_tracker(name, streams, models or paper_sensor_models(), navigation,
                            primary="radar")
    inner = getattr(tracker, "tracker", tracker)
    assert type(inner) is TRACKERS[name]
    out = []
    for _, tracks in tracker:
        out.append([[(s.state_vector, s.covar) for s in track.states]
                    for track in in_track_order(tracks)])
    return inner, out


def _assert_bit_identical(a, b):
    assert len(a) == len(b)
    for scan_a, scan_b in zip(a, b):
        assert len(scan_a) == len(scan_b)
        for track_a, track_b in zip(scan_a, scan_b):
            assert len(track_a) == len(track_b)
            for (x_a, p_a), (x_b, p_b) in zip(track_a, track_b):
                assert np.array_equal(x_a, x_b) and np.array_equal(p_a, p_b)


@pytest.fixture(scope="module")
def scenario():
    return make_scenario("mixed-range", 0, 20.0)


# --- one model object per detection: array speed, the same tracks -----------------------------------
@pytest.mark.parametrize("name", list(TRACKERS))
def test_a_model_object_per_detection_gives_the_per_scan_tracks_on_the_array_path(name, scenario):
    per_scan = _streams(scenario)
    per_detection = _streams(scenario, lambda t, dets: [_fresh(d) for d in dets])
    radar = [d for _, dets in per_detection["radar"] for d in dets]
    assert len({id(d.measurement_model) for d in radar}) == len(radar) > 100
    reference, expected = _run(name, per_scan, _navigation(scenario))
    with warnings.catch_warnings():
        warnings.simplefilter("error", ComponentPathWarning)
        tracker, got = _run(name, per_detection, _navigation(scenario))
    assert reference.component_scans == tracker.component_scans == 0
    assert tracker.array_scans == reference.array_scans > 20 and tracker.array_path
    assert sum(len(scan) for scan in expected) > 0  # it tracked
    _assert_bit_identical(got, expected)


# --- genuinely different models in one scan: counted, warned once --------------------------------
def _two_sensors(every):
    """Scans ``every`` (seconds since the start) with half their radar detections measured
    from 1 m further east: two sensors' offsets in one scan."""
    def change(t, detections):
        if not every(t) or len(detections) < 2:
            return detections
        moved = []
        for k, detection in enumerate(detections):
            detection = _fresh(detection)
            if k % 2 and isinstance(detection.measurement_model, CartesianToBearingRange):
                detection.measurement_model.translation_offset = \
                    detection.measurement_model.translation_offset + StateVector([1.0, 0.0])
            moved.append(detection)
        return moved
    return change


@pytest.mark.parametrize("name", list(TRACKERS))
def test_scans_with_different_models_fall_back_counted_and_warn_once(name, scenario):
    start = scenario.radar_scans[0].timestamp
    picked = {scenario.radar_scans[k].timestamp for k in (4, 9)}
    streams = _streams(scenario)
    streams["radar"] = [(t, set(_two_sensors(lambda t: t in picked)(t, list(dets))))
                        for t, dets in streams["radar"]]
    with pytest.warns(ComponentPathWarning,
                      match="detections with 2 distinct measurement models") as caught:
        tracker, _ = _run(name, streams, _navigation(scenario))
    assert len([w for w in caught if w.category is ComponentPathWarning]) == 1
    assert tracker.component_scans == 2 and tracker.array_scans > 20
    assert not tracker.array_path
    assert start not in picked


# --- Stone Soup's own radar on a moving platform ----------------------------------------------
T0 = datetime.datetime(2026, 1, 1)


def _platform_scans(per_truth, steps=25):
    """A RadarBearingRange (mounted off-centre) on a platform sailing north-east, measuring
    three targets each second: (scans, pose log, the radar). ``per_truth``: one ``measure``
    call per target (a model object per detection) instead of one per scan."""
    np.random.seed(7)
    radar = RadarBearingRange(ndim_state=4, position_mapping=(0, 2), noise_covar=np.diag(
        [math.radians(0.5) ** 2, 4.0]), max_range=2000.0,
        mounting_offset=StateVector([3.0, 1.0]), rotation_offset=StateVector([0.0, 0.0, 0.0]))
    transition = CombinedLinearGaussianTransitionModel([ConstantVelocity(0.0)] * 2)
    platform = MovingPlatform(states=[State(StateVector([0.0, 4.0, 0.0, 3.0]), timestamp=T0)],
                              position_mapping=(0, 2), velocity_mapping=(1, 3),
                              transition_model=transition, sensors=[radar])
    starts = [(300.0, -2.0, 200.0, 1.0), (-250.0, 1.5, 400.0, -1.0), (500.0, 0.0, -300.0, 2.0)]
    scans, times, positions, headings = [], [], [], []
    for k in range(steps):
        t = T0 + datetime.timedelta(seconds=k)
        if k:
            platform.move(t)
        truths = {GroundTruthState(StateVector([x + vx * k, vx, y + vy * k, vy]), timestamp=t)
                  for x, vx, y, vy in starts}
        if per_truth:
            detections = set()
            for truth in sorted(truths, key=lambda s: s.state_vector[0, 0]):
                detections |= radar.measure({truth}, noise=True)
        else:
            detections = radar.measure(truths, noise=True)
        scans.append((t, detections))
        pose = sensor_pose(radar)
        times.append(t)
        positions.append([pose.x, pose.y])
        headings.append(pose.heading)
    return scans, NavigationTrack(timestamps=times, positions=positions, headings=headings), radar


@pytest.mark.parametrize("name", list(TRACKERS))
@pytest.mark.parametrize("per_truth", [False, True], ids=["measure-per-scan", "measure-per-target"])
def test_stone_soup_radar_on_a_moving_platform_runs_on_the_array_path(name, per_truth):
    scans, navigation, radar = _platform_scans(per_truth)
    models = [d.measurement_model for _, dets in scans for d in dets]
    per_scan_objects = {len({id(d.measurement_model) for d in dets}) for _, dets in scans}
    # Stone Soup 1.9.1's sensor builds one model per measure() call (shared by its
    # detections): per scan with one call, per detection with one call per target.
    assert per_scan_objects == ({3} if per_truth else {1})
    assert len({measurement_model_key(m) for m in models}) == len(scans)  # it moved
    assert any(np.any(m.rotation_offset) for m in models)  # (its heading turns the model)
    sensor_model = SensorModel.from_stonesoup(radar, prob_detection=0.9, clutter_density=1e-6)
    with warnings.catch_warnings():
        warnings.simplefilter("error", ComponentPathWarning)
        tracker, out = _run(name, {"radar": scans}, navigation, {"radar": sensor_model})
    assert tracker.component_scans == 0 and tracker.array_scans == len(scans)
    assert tracker.array_path
    assert len(out[-1]) >= 1  # it tracked


# --- the value key ------------------------------------------------------------------------------
def _bearing_range(kind=CartesianToBearingRange, **changes):
    properties = dict(ndim_state=4, mapping=(0, 2), noise_covar=np.diag([1e-4, 4.0]),
                      translation_offset=StateVector([10.0, -5.0]),
                      rotation_offset=StateVector([0.0, 0.0, 0.25]))
    return kind(**{**properties, **changes})


def _linear(**changes):
    properties = dict(ndim_state=4, mapping=(0, 2), noise_covar=np.diag([1.0, 2.0]))
    return LinearGaussian(**{**properties, **changes})


@pytest.mark.parametrize("build", [_bearing_range, _linear,
                                   lambda **c: _bearing_range(AnalyticCartesianToBearingRange, **c)])
def test_equal_models_have_equal_keys(build):
    a, b = build(), build()
    assert a is not b and measurement_model_key(a) == measurement_model_key(b)
    assert hash(measurement_model_key(a)) == hash(measurement_model_key(b))
    assert measurement_model_key(copy.deepcopy(a)) == measurement_model_key(a)


@pytest.mark.parametrize("changes", [
    dict(noise_covar=np.diag([1e-4, 4.0 + 1e-12])),
    dict(translation_offset=StateVector([10.0, -5.000001])),
    dict(rotation_offset=StateVector([0.0, 0.0, -0.25])),
    dict(mapping=(2, 0)),
    dict(ndim_state=6),
    dict(noise_covar=np.diag([1e-4, 4.0]).astype(np.float32)),
    dict(seed=3),
], ids=["noise", "offset", "rotation", "mapping", "ndim_state", "noise-dtype", "seed"])
def test_models_differing_in_one_parameter_have_different_keys(changes):
    assert measurement_model_key(_bearing_range(**changes)) != measurement_model_key(_bearing_range())


def test_linear_models_differing_in_one_parameter_have_different_keys():
    base = measurement_model_key(_linear())
    for changes in (dict(noise_covar=np.diag([1.0, 2.5])), dict(mapping=(0, 1)),
                    dict(ndim_state=6)):
        assert measurement_model_key(_linear(**changes)) != base


def test_the_model_type_is_part_of_the_key():
    stock, analytic = _bearing_range(), _bearing_range(AnalyticCartesianToBearingRange)
    assert measurement_model_key(stock) != measurement_model_key(analytic)


def test_other_model_types_are_keyed_by_identity():
    class Mine(CartesianToBearingRange):  # (a subclass may read more than its Properties)
        pass
    a, b = _bearing_range(Mine), _bearing_range(Mine)
    assert measurement_model_key(a) == measurement_model_key(a)
    assert measurement_model_key(a) != measurement_model_key(b)
    assert measurement_model_key(None) is None


def test_groups_carried_to_a_subset_are_the_subsets_own():
    """``carry_model_groups`` cuts a scan's remembered groups down to some of its
    detections: the same groups, order, members and representatives as grouping the
    subset afresh; a subset whose models differ from the remembered ones is grouped
    afresh."""
    import random

    from stonesoup.types.detection import Detection

    from ctxmodels.model_key import carry_model_groups, scan_model_groups
    from ctxmodels.stonesoup.ordering import OrderedDetections

    rng = random.Random(5)
    shared = [_bearing_range(), _linear(), None]
    for _ in range(200):
        models = [rng.choice(shared + [_bearing_range(), _linear()])
                  for _ in range(rng.randint(0, 8))]
        scan = OrderedDetections([Detection(StateVector([0.0, 0.0]), measurement_model=m)
                                  for m in models])
        scan_model_groups(scan)  # (remembered on the scan)
        kept = sorted(rng.sample(range(len(scan)), rng.randint(0, len(scan))))
        carried = OrderedDetections([scan[k] for k in kept])
        carry_model_groups(scan, carried, kept)
        fresh = OrderedDetections(list(carried))
        got, expected = scan_model_groups(carried), scan_model_groups(fresh)
        assert list(got) == list(expected)
        for key in expected:
            assert got[key][0] is expected[key][0] and got[key][1] == expected[key][1]
    scan = OrderedDetections([Detection(StateVector([0.0, 0.0]), measurement_model=_linear())
                              for _ in range(2)])
    scan_model_groups(scan)
    moved = OrderedDetections([Detection(StateVector([0.0, 0.0]),
                                         measurement_model=_bearing_range())])
    carry_model_groups(scan, moved, [0])  # (not the scan's detection: its model differs)
    (model, members), = scan_model_groups(moved).values()
    assert model is moved[0].measurement_model and members == [0]
