"""Hostile inputs to ``paper_tracker``: streams, sensor models, tracker names, primary sensor,
region radius and pose sources that it cannot use are refused naming the argument, and a
bad scan, a missing lidar area or a pose source that ends too early names the sensor and
the scan, at construction or as the tracker runs; good streams still track."""
from __future__ import annotations

import datetime

import numpy as np
import pytest

from ..hostile import _navigation, _paper_models, names_argument, T0

NAN, INF = float("nan"), float("inf")


def _lidar_detection(time, area=12.0):
    from stonesoup.models.measurement.linear import LinearGaussian
    from stonesoup.types.detection import Detection
    model = LinearGaussian(ndim_state=4, mapping=(0, 2), noise_covar=np.eye(2))
    return Detection([[10.0], [5.0]], timestamp=time, measurement_model=model,
                     metadata={} if area is None else {"area": area})


def _times(n):
    return [T0 + datetime.timedelta(seconds=k) for k in range(n)]


_DEFAULT = object()


def _paper(name="gmphd-context", streams=_DEFAULT, models=_DEFAULT, pose=_DEFAULT, **options):
    from ctxmodels.trackers import paper_tracker
    streams = {"radar": [(t, set()) for t in _times(3)],
               "lidar": [(t, {_lidar_detection(t)}) for t in _times(3)]} \
        if streams is _DEFAULT else streams
    return paper_tracker(name, streams, _paper_models() if models is _DEFAULT else models,
                         _navigation() if pose is _DEFAULT else pose, **options)


@pytest.mark.parametrize("streams", [[("radar", [])], [], None, "radar", 5,
                                     [(T0, set())]], ids=repr)
def test_paper_tracker_names_streams_that_are_not_a_mapping(streams):
    names_argument(lambda: _paper(streams=streams), TypeError, "streams")


@pytest.mark.parametrize("stream", [None, 5, "scans", {"t": 1}], ids=repr)
def test_paper_tracker_names_a_stream_that_is_not_scans(stream):
    message = names_argument(lambda: _paper(streams={"radar": stream}), TypeError, "streams")
    assert "'radar'" in message


@pytest.mark.parametrize("models", [[("radar", None)], "radar", 5], ids=repr)
def test_paper_tracker_names_sensor_models_that_are_not_a_mapping(models):
    names_argument(lambda: _paper(models=models), TypeError, "sensor_models")


def test_paper_tracker_names_sensor_models_missing_where_read():
    """None is accepted for trackers that read no model, and named where one is read."""
    names_argument(lambda: _paper(models=None), ValueError, "sensor_models")


@pytest.mark.parametrize("name", ["kalman", None, 5, "", "GMPHD-CONTEXT", ["gmphd-context"]],
                         ids=repr)
def test_paper_tracker_names_an_unknown_tracker(name):
    names_argument(lambda: _paper(name=name), ValueError, "name")


@pytest.mark.parametrize("primary", [5, ["radar"], True, "sonar", ""], ids=repr)
def test_paper_tracker_names_a_bad_primary(primary):
    names_argument(lambda: _paper(primary=primary), (ValueError, TypeError), "primary")


@pytest.mark.parametrize("fast", [None, 1, "yes", 0.0], ids=repr)
def test_paper_tracker_names_a_bad_fast(fast):
    names_argument(lambda: _paper(fast=fast), TypeError, "fast")


@pytest.mark.parametrize("radius", [True, "far", NAN, INF, -1.0, 0, [3000.0]], ids=repr)
def test_paper_tracker_names_a_bad_region_radius(radius):
    names_argument(lambda: _paper(region_radius=radius), ValueError, "region_radius")


@pytest.mark.parametrize("pose", [None, 5, "nav", object()], ids=repr)
def test_paper_tracker_names_a_bad_pose_source(pose):
    from ctxmodels.trackers import paper_tracker
    names_argument(lambda: paper_tracker("gmphd-context", {"radar": []}, _paper_models(), pose),
                   TypeError, "pose_source")


BAD_SCANS = {
    "none": lambda t: (t, None),
    "string-set": lambda t: (t, {"detection"}),
    "string": lambda t: (t, "detections"),
    "int": lambda t: (t, 5),
    "lone-detection": lambda t: (t, _lidar_detection(t)),
    "list-of-none": lambda t: (t, [None]),
    "triple": lambda t: (t, set(), 1),
    "none-item": lambda t: None,
    "float-time": lambda t: (1.5, set()),
}


@pytest.mark.parametrize("tracker", ["gmphd-context", "gmphd-uniform", "jpda"])
@pytest.mark.parametrize("bad", list(BAD_SCANS))
def test_paper_tracker_names_the_sensor_and_scan_of_a_bad_scan_at_construction(bad, tracker):
    times = _times(3)
    lidar = [(t, {_lidar_detection(t)}) for t in times]
    lidar[1] = BAD_SCANS[bad](times[1])
    streams = {"radar": [(t, set()) for t in times], "lidar": lidar}
    message = names_argument(lambda: _paper(name=tracker, streams=streams), TypeError, "streams")
    assert "'lidar'" in message
    if bad not in ("triple", "none-item", "float-time"):
        assert str(times[1]) in message


@pytest.mark.parametrize("tracker", ["gmphd-context", "gmphd-uniform"])
@pytest.mark.parametrize("bad", ["none", "string-set", "string", "lone-detection"])
def test_paper_tracker_names_the_sensor_and_scan_of_a_bad_scan_read_from_a_reader(bad, tracker):
    """Readers (not lists) are read as the tracker runs: the feeders name the scan."""
    times = _times(3)

    class Reader:
        def __iter__(self):
            yield times[0], {_lidar_detection(times[0])}
            yield BAD_SCANS[bad](times[1])

    tracker = _paper(name=tracker, streams={"radar": [(t, set()) for t in times],
                                            "lidar": Reader()})
    with pytest.raises(TypeError) as info:
        list(tracker)
    assert "(sensor 'lidar')" in str(info.value) and str(times[1]) in str(info.value)


@pytest.mark.parametrize("area", [None, "12", True, [12.0]], ids=repr)
def test_a_missing_or_bad_lidar_area_names_the_sensor_and_scan(area):
    times = _times(3)
    lidar = [(t, {_lidar_detection(t)}) for t in times]
    lidar[2] = (times[2], {_lidar_detection(times[2], area=area)})
    message = names_argument(lambda: _paper(streams={"radar": [], "lidar": lidar}),
                             (ValueError, TypeError), "streams")
    assert "'lidar'" in message and str(times[2]) in message and "'area'" in message


def test_a_missing_lidar_area_in_a_reader_names_the_sensor_and_scan_as_it_runs():
    times = _times(3)
    tracker = _paper(streams={"lidar": iter([(times[0], {_lidar_detection(times[0], None)})])})
    with pytest.raises(ValueError) as info:
        list(tracker)
    message = str(info.value)
    assert message.startswith("reader:") and "(sensor 'lidar')" in message \
        and str(times[0]) in message and "'area'" in message


@pytest.mark.parametrize("tracker", ["gmphd-context", "gmphd-uniform", "gmphd-pd-aware"])
def test_a_navigation_log_that_ends_too_early_names_the_sensor_and_scan(tracker):
    times = _times(5)  # the log covers 0..2 s
    streams = {"radar": [(t, set()) for t in times[:2]],
               "lidar": [(t, {_lidar_detection(t)}) for t in times]}
    message = names_argument(lambda: _paper(name=tracker, streams=streams), ValueError,
                             "pose_source")
    assert "'lidar'" in message and str(times[3]) in message


def test_a_pose_source_that_ends_too_early_names_the_sensor_and_scan_as_it_runs():
    navigation = _navigation()

    class Poses:  # not a NavigationTrack: asked as the scans come
        def pose_at(self, timestamp):
            return navigation.pose_at(timestamp)

    times = _times(5)
    tracker = _paper(streams={"lidar": [(t, {_lidar_detection(t)}) for t in times]},
                     pose=Poses())
    with pytest.raises(ValueError) as info:
        list(tracker)
    assert str(info.value).startswith("pose_source:") and "(sensor 'lidar')" in str(info.value) \
        and str(times[3]) in str(info.value)


def test_good_streams_still_track():
    tracker = _paper()
    assert [time for time, _ in tracker] == [t for t in _times(3) for _ in range(2)]
