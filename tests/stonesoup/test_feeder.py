"""ContextFeeder and MultiSensorFeeder: contexts on every scan, time-ordered interleaving."""

import datetime
import math

import numpy as np
import pytest
from stonesoup.feeder.base import DetectionFeeder
from stonesoup.models.measurement.linear import LinearGaussian
from stonesoup.models.transition.linear import (
    CombinedLinearGaussianTransitionModel,
    ConstantVelocity,
)
from stonesoup.reader import DetectionReader
from stonesoup.simulator.simple import SimpleDetectionSimulator, SingleTargetGroundTruthSimulator
from stonesoup.types.detection import Detection
from stonesoup.types.state import GaussianState, State

from ctxmodels import (
    AngularSector,
    ClutterDensityModel,
    ConstantPose,
    DetectionProbabilityModel,
    DetectionSet,
    DetectorContext,
    Mounting,
    NavigationTrack,
    Pose,
    SensorModel,
)
from ctxmodels.stonesoup import ContextFeeder, MultiSensorFeeder

T0 = datetime.datetime(2024, 5, 1, 12, 0, 0)
MODEL = LinearGaussian(4, (0, 2), np.eye(2))


def at(seconds):
    return T0 + datetime.timedelta(seconds=seconds)


def det(x, y, t):
    return Detection(np.array([[x], [y]]), timestamp=t, measurement_model=MODEL)


# A sensor blind astern (90° sector), so P_D reveals which way the platform pointed.
STERN_BLIND = SensorModel(
    detection=DetectionProbabilityModel(
        factors=[AngularSector(centre=math.pi, width=math.pi / 2)]),
    clutter=ClutterDensityModel(factors=[1e-3]),
    mounting=Mounting(forward=2.0, left=0.5),
    name="stern-blind")


@pytest.fixture
def navigation():
    # Platform moves east 10 m/s for 10 s, turning from heading 0 to π/2.
    times = [at(0), at(5), at(10)]
    return NavigationTrack(timestamps=times,
                           positions=np.array([[0.0, 0.0], [50.0, 0.0], [100.0, 0.0]]),
                           headings=np.array([0.0, math.pi / 4, math.pi / 2]))


def test_context_feeder_attaches_contexts_at_navigation_poses_to_every_scan(navigation):
    scans = [(at(0.5), {det(1, 2, at(0.5))}),
             (at(2.0), set()),                       # empty scan: still gets a context
             (at(7.5), {det(3, 4, at(7.5)), det(5, 6, at(7.5))}),
             (at(9.0), set())]
    feeder = ContextFeeder(scans, sensor_model=STERN_BLIND, pose_source=navigation)
    assert isinstance(feeder, DetectionReader)

    out = list(feeder)
    assert [t for t, _ in out] == [t for t, _ in scans]
    for (time, detections), (_, original) in zip(out, scans):
        assert isinstance(detections, DetectionSet)
        assert set(detections) == original
        context = detections.detector_context
        assert isinstance(context, DetectorContext)
        assert context.timestamp == time
        assert context.sensor_model is STERN_BLIND
        # The sensor's pose: the navigation pose at the scan time, with the mounting applied.
        expected = STERN_BLIND.mounting.apply(navigation.pose_at(time))
        assert context.pose == expected
        # ...and P_D uses it: 100 m ahead seen, 100 m astern blind.
        h = expected.heading
        dx, dy = 100 * math.cos(h), 100 * math.sin(h)
        ahead = State([[expected.x + dx], [0], [expected.y + dy], [0]])
        astern = State([[expected.x - dx], [0], [expected.y - dy], [0]])
        assert float(context.prob_detection(ahead)) == 1.0
        assert float(context.prob_detection(astern)) == 0.0
    # Interpolated, not snapped to a log entry: 7.5 s is half-way through the turn.
    assert out[2][1].detector_context.pose.heading == pytest.approx(3 * math.pi / 8)
    # Every scan has its own context.
    assert len({id(d.detector_context) for _, d in out}) == len(out)
    # The DetectionReader interface: `detections` is the current scan.
    assert feeder.detections is out[-1][1]


def _stock_simulator():
    truth = SingleTargetGroundTruthSimulator(
        transition_model=CombinedLinearGaussianTransitionModel([ConstantVelocity(0.1)] * 2),
        initial_state=GaussianState([[0], [1], [0], [1]], np.diag([1, 0.1, 1, 0.1]), timestamp=T0),
        timestep=datetime.timedelta(seconds=1), number_steps=12)
    return SimpleDetectionSimulator(
        groundtruth=truth, measurement_model=MODEL, meas_range=np.array([[-50, 50], [-50, 50]]),
        detection_probability=0.5, clutter_rate=0.5, seed=9)


def test_context_feeder_wraps_a_stock_simulator():
    # The ground-truth simulator draws from NumPy's global generator: seed it per run.
    state = np.random.get_state()
    try:
        np.random.seed(4)
        reference = [(t, sorted(tuple(d.state_vector.ravel()) for d in dets))
                     for t, dets in _stock_simulator()]
        np.random.seed(4)
        feeder = ContextFeeder(_stock_simulator(), sensor_model=STERN_BLIND,
                               pose_source=ConstantPose(Pose(x=1.0, y=2.0, heading=0.3)))
        out = list(feeder)
    finally:
        np.random.set_state(state)
    assert any(not dets for _, dets in reference)  # the run has empty scans
    assert [(t, sorted(tuple(d.state_vector.ravel()) for d in dets)) for t, dets in out] \
        == reference
    assert all(isinstance(d, DetectionSet) and d.detector_context.timestamp == t
               for t, d in out)
    # Mounting 2 m forward, 0.5 m left of a platform at (1, 2) heading 0.3 rad.
    sensor = Pose(x=1.0 + 2.0 * math.cos(0.3) - 0.5 * math.sin(0.3),
                  y=2.0 + 2.0 * math.sin(0.3) + 0.5 * math.cos(0.3), heading=0.3)
    for _, d in out:
        pose = d.detector_context.pose
        assert (pose.x, pose.y, pose.heading) \
            == pytest.approx((sensor.x, sensor.y, 0.3), abs=1e-12)


def test_context_feeder_iterates_through_the_stone_soup_generator_method():
    scans = [(at(k), {det(k, 0, at(k))} if k % 2 else set()) for k in range(4)]
    feeder = ContextFeeder(scans, sensor_model=STERN_BLIND,
                           pose_source=ConstantPose(Pose(x=0, y=0)))
    via_gen = list(feeder.detections_gen())
    via_iter = list(feeder)
    assert [t for t, _ in via_gen] == [t for t, _ in via_iter] == [t for t, _ in scans]
    assert all(set(a) == set(b) == set(s)
               for (_, a), (_, b), (_, s) in zip(via_gen, via_iter, scans))
    assert all(isinstance(d, DetectionSet) for _, d in via_gen)


def test_context_feeder_replaces_an_incoming_context():
    stale = STERN_BLIND.context(Pose(x=0, y=0), at(0))
    scans = [(at(1), DetectionSet([det(0, 0, at(1))], stale))]
    (time, detections), = ContextFeeder(scans, sensor_model=STERN_BLIND,
                                       pose_source=ConstantPose(Pose(x=5, y=5)))
    assert detections.detector_context is not stale
    assert detections.detector_context.timestamp == at(1)


def test_context_feeder_errors_name_the_argument(navigation):
    with pytest.raises(TypeError, match="sensor_model"):
        ContextFeeder([], sensor_model="radar", pose_source=navigation)
    with pytest.raises(TypeError, match="pose_source"):
        ContextFeeder([], sensor_model=STERN_BLIND, pose_source=(0, 0, 0))
    with pytest.raises(TypeError, match="reader"):
        list(ContextFeeder(42, sensor_model=STERN_BLIND, pose_source=navigation))
    with pytest.raises(TypeError, match="reader"):
        list(ContextFeeder([at(1)], sensor_model=STERN_BLIND, pose_source=navigation))
    with pytest.raises(ValueError, match="reader.*time order"):
        list(ContextFeeder([(at(2), set()), (at(1), set())], sensor_model=STERN_BLIND,
                           pose_source=navigation))
    # A scan outside the navigation log is an error, not an extrapolation.
    with pytest.raises(ValueError, match="outside the navigation track"):
        list(ContextFeeder([(at(11), set())], sensor_model=STERN_BLIND, pose_source=navigation))


def test_multi_sensor_feeder_interleaves_scans_by_time_without_merging():
    radar = [(at(0.0), {det(100, 0, at(0.0))}), (at(1.25), set()),
             (at(2.5), {det(101, 0, at(2.5))})]
    lidar = [(at(k * 0.5), set() if k % 2 else {det(1, k, at(k * 0.5))}) for k in range(6)]
    feeder = MultiSensorFeeder([radar, lidar])
    assert isinstance(feeder, DetectionFeeder) and isinstance(feeder, DetectionReader)

    out = list(feeder)
    assert len(out) == len(radar) + len(lidar)
    assert [t for t, _ in out] == sorted(t for t, _ in radar + lidar)
    # Every scan is passed through as the same object: nothing merged or copied.
    ids = [id(d) for _, d in out]
    assert sorted(ids) == sorted(id(d) for _, d in radar + lidar)
    # Shared timestamps (0 s and 2.5 s): both scans, in the order of `feeders`.
    for shared in (at(0.0), at(2.5)):
        first, second = [d for t, d in out if t == shared]
        assert first is dict(radar)[shared] and second is dict(lidar)[shared]
    # Order of `feeders` decides ties: swapping them swaps the pair.
    swapped = list(MultiSensorFeeder([lidar, radar]))
    assert [d for t, d in swapped if t == at(0.0)] == [dict(lidar)[at(0.0)], dict(radar)[at(0.0)]]


def test_multi_sensor_feeder_merges_context_feeders_keeping_each_context():
    pose = ConstantPose(Pose(x=0, y=0))
    other = SensorModel(detection=DetectionProbabilityModel(factors=[0.5]),
                        clutter=ClutterDensityModel(factors=[1.0]), name="other")
    a = ContextFeeder([(at(k), set()) for k in range(3)], sensor_model=STERN_BLIND,
                      pose_source=pose)
    b = ContextFeeder([(at(k * 0.75), set()) for k in range(4)], sensor_model=other,
                      pose_source=pose)
    out = list(MultiSensorFeeder([a, b]))
    assert [(t, d.detector_context.sensor_model.name) for t, d in out] == [
        (at(0), "stern-blind"), (at(0), "other"), (at(0.75), "other"), (at(1), "stern-blind"),
        (at(1.5), "other"), (at(2), "stern-blind"), (at(2.25), "other")]
    assert all(d.detector_context.timestamp == t for t, d in out)


def test_multi_sensor_feeder_errors_name_the_argument():
    with pytest.raises(ValueError, match="feeders"):
        MultiSensorFeeder([])
    with pytest.raises(TypeError, match="feeders"):
        MultiSensorFeeder(5)
    with pytest.raises(TypeError, match=r"feeders\[1\]"):
        list(MultiSensorFeeder([[(at(0), set())], 3]))
    with pytest.raises(ValueError, match=r"feeders\[1\].*time order"):
        list(MultiSensorFeeder([[(at(0), set()), (at(3), set())],
                                [(at(1), set()), (at(0.5), set())]]))


def test_feeders_round_trip_through_yaml_around_a_stock_file_reader(tmp_path):
    path = tmp_path / "lidar.csv"
    path.write_text("t,x,y\n"
                    "2024-05-01T12:00:00,1.0,2.0\n"
                    "2024-05-01T12:00:00,3.0,4.0\n"
                    "2024-05-01T12:00:02,5.0,6.0\n")
    from stonesoup.reader.generic import CSVDetectionReader
    from stonesoup.serialise import YAML

    reader = CSVDetectionReader(path, state_vector_fields=("x", "y"), time_field="t")
    feeder = MultiSensorFeeder([
        ContextFeeder(reader, sensor_model=STERN_BLIND, pose_source=ConstantPose(Pose(x=1, y=2))),
        ContextFeeder([(at(1), set())], sensor_model=STERN_BLIND,
                      pose_source=ConstantPose(Pose(x=0, y=0)))])
    loaded = YAML().load(YAML().dumps(feeder))
    assert loaded.feeders[0].sensor_model == STERN_BLIND
    assert loaded.feeders[0].pose_source == feeder.feeders[0].pose_source
    for stream in (feeder, loaded):
        out = [(t, sorted(tuple(d.state_vector.ravel()) for d in dets),
                dets.detector_context.pose) for t, dets in stream]
        assert out == [
            (at(0), [(1.0, 2.0), (3.0, 4.0)], STERN_BLIND.sensor_pose(Pose(x=1, y=2))),
            (at(1), [], STERN_BLIND.sensor_pose(Pose(x=0, y=0))),
            (at(2), [(5.0, 6.0)], STERN_BLIND.sensor_pose(Pose(x=1, y=2)))]
