"""Hostile inputs to the feeders (``ContextFeeder``, ``MultiSensorFeeder``): bad feeders,
sensor names and scan times are refused naming the argument, and so are streams that mix
naive and timezone-aware times."""
from __future__ import annotations

import datetime

import numpy as np
import pytest
from stonesoup.types.detection import Detection

from ctxmodels import (ClutterDensityModel, ConstantPose, DetectionProbabilityModel, NavigationTrack,
                       Pose, SensorModel)
from ctxmodels.stonesoup import ContextFeeder, MultiSensorFeeder
from ..hostile import _navigation, _paper_models, names, names_argument, T0


@pytest.mark.parametrize("feeders", ["one", None, 5, "abc", {"a": 1}], ids=repr)
def test_multi_sensor_feeder_names_bad_feeders(feeders):
    from ctxmodels import ConstantPose, Pose
    from ctxmodels.stonesoup import ContextFeeder, MultiSensorFeeder
    one = ContextFeeder(reader=[], sensor_model=_paper_models()["radar"],
                        pose_source=ConstantPose(pose=Pose(x=0.0, y=0.0)))
    given = one if feeders == "one" else feeders
    names_argument(lambda: MultiSensorFeeder(feeders=given), TypeError, "feeders")


@pytest.mark.parametrize("names", ["ab", ["a"], [1, 2], 5], ids=repr)
def test_multi_sensor_feeder_names_bad_sensor_names(names):
    from ctxmodels.stonesoup import MultiSensorFeeder
    names_argument(lambda: MultiSensorFeeder(feeders=[[], []], sensor_names=names), TypeError,
                   "sensor_names")


@pytest.mark.parametrize("name", [None, 5, ["radar"]], ids=repr)
def test_context_feeder_names_a_bad_sensor_name(name):
    from ctxmodels import ConstantPose, Pose
    from ctxmodels.stonesoup import ContextFeeder
    names_argument(lambda: ContextFeeder(reader=[], sensor_model=_paper_models()["radar"],
                                         pose_source=ConstantPose(pose=Pose(x=0.0, y=0.0)),
                                         sensor_name=name), TypeError, "sensor_name")


@pytest.mark.parametrize("times", ["timedelta64", "float", "mixed-kinds"])
def test_context_feeder_names_scan_times_it_cannot_use(times):
    from ctxmodels.stonesoup import ContextFeeder
    aware = datetime.datetime(2026, 1, 1, tzinfo=datetime.timezone.utc)
    scans = {"timedelta64": [(np.timedelta64(1, "s"), set())],
             "float": [(1.0, set()), (0.5, set())],
             "mixed-kinds": [(T0, set()), (aware, set())]}[times]
    feeder = ContextFeeder(reader=scans, sensor_model=_paper_models()["radar"],
                           pose_source=_navigation(), sensor_name="radar")
    with pytest.raises((TypeError, ValueError)) as info:
        list(feeder)
    assert str(info.value).split(":")[0] in ("reader", "pose_source"), str(info.value)


# --- naive and timezone-aware scan times -------------------------------------------------------


NAIVE = datetime.datetime(2024, 1, 1, 12, 0, 0)
AWARE = datetime.datetime(2024, 1, 1, 12, 0, 0, tzinfo=datetime.timezone.utc)
SECOND = datetime.timedelta(seconds=1)


def _detections(t):
    return {Detection(np.array([[1.0], [2.0]]), timestamp=t)}


def test_feeders_mixing_naive_and_aware_scan_times_name_the_stream_and_time():
    sensor = SensorModel(detection=DetectionProbabilityModel(factors=[0.9]),
                         clutter=ClutterDensityModel(factors=[1e-3]), name="radar")
    pose = ConstantPose(pose=Pose(x=0.0, y=0.0))
    reader = [(NAIVE, _detections(NAIVE)), (AWARE + SECOND, _detections(AWARE + SECOND))]
    message = names(lambda: list(ContextFeeder(reader=reader, sensor_model=sensor, pose_source=pose)),
                    TypeError, "reader")
    assert "radar" in message and str(AWARE + SECOND) in message
    aware_log = NavigationTrack(timestamps=[AWARE, AWARE + 10 * SECOND], positions=[[0, 0], [10, 0]],
                                headings=[0, 0])
    message = names(lambda: list(ContextFeeder(reader=reader[:1], sensor_model=sensor,
                                               pose_source=aware_log)),
                    TypeError, "pose_source")
    assert "radar" in message and str(NAIVE) in message and "naive" in message
    naive = ContextFeeder(reader=[(NAIVE, _detections(NAIVE))], sensor_model=sensor, pose_source=pose)
    aware = [(AWARE + SECOND, _detections(AWARE + SECOND))]
    message = names(lambda: list(MultiSensorFeeder(feeders=[naive, aware])), TypeError, "feeders[1]")
    assert str(AWARE + SECOND) in message and "naive" in message
