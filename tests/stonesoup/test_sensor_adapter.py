"""Context models read off Stone Soup's own radars (ctxmodels.stonesoup.sensor_adapter):
P_D > 0 exactly where the sensor's own ``is_detectable`` says so, on 10⁴ random targets
per sensor type, mounted with offsets on fixed and moving platforms; the pose follows the
platform's states. (The 3-D radars: test_sensor_adapter_3d.py.)"""
from __future__ import annotations

import datetime
import math
import zlib

import numpy as np
import pytest
from stonesoup.models.transition.linear import (CombinedLinearGaussianTransitionModel,
                                                ConstantVelocity)
from stonesoup.platform.base import FixedPlatform, MovingPlatform
from stonesoup.sensor.radar.radar import (RadarBearing, RadarBearingRange, RadarRotatingBearing,
                                          RadarRotatingBearingRange)
from stonesoup.types.array import StateVector
from stonesoup.types.groundtruth import GroundTruthState
from stonesoup.types.state import State

from ctxmodels import SensorModel
from ctxmodels.stonesoup import (PlatformContextFeeder, SensorPose, sensor_model_from_stonesoup,
                                 sensor_pose)

T0 = datetime.datetime(2026, 1, 1)
N = 10_000
MOUNT = dict(mounting_offset=StateVector([5.0, 2.0]), rotation_offset=StateVector([0, 0, 0.3]))


def _sensors():
    """Every supported type, 2-D ones on [x, vx, y, vy] states."""
    common = dict(ndim_state=4, position_mapping=(0, 2), **MOUNT)
    rotating = dict(dwell_centre=StateVector([1.1]), rpm=20, fov_angle=math.radians(60))
    return {
        "RadarBearingRange": RadarBearingRange(noise_covar=np.eye(2), max_range=800, **common),
        "RadarRotatingBearingRange": RadarRotatingBearingRange(
            noise_covar=np.eye(2), max_range=800, **rotating, **common),
        "RadarBearing": RadarBearing(noise_covar=np.eye(1), max_range=650, **common),
        "RadarRotatingBearing": RadarRotatingBearing(
            noise_covar=np.eye(1), max_range=math.inf, **rotating, **common),
    }


def _fixed(sensor, yaw=0.7):
    FixedPlatform(states=[State(StateVector([100.0, 0, -50.0, 0]), timestamp=T0)],
                  position_mapping=(0, 2), orientation=StateVector([0, 0, yaw]), sensors=[sensor])
    return sensor


def _moving(sensor, steps=5):
    """On a platform moving north-east at 7 m/s, moved ``steps`` seconds along."""
    transition = CombinedLinearGaussianTransitionModel([ConstantVelocity(0.0)] * 2)
    platform = MovingPlatform(states=[State(StateVector([0.0, 5.0, 0.0, 5.0]), timestamp=T0)],
                              position_mapping=(0, 2), velocity_mapping=(1, 3),
                              transition_model=transition, sensors=[sensor])
    for k in range(1, steps + 1):
        platform.move(T0 + datetime.timedelta(seconds=k))
    return platform


def _agreement(sensor, states, ndim=4):
    model = SensorModel.from_stonesoup(sensor, prob_detection=0.9, clutter_density=1e-4)
    pd = model.context(sensor_pose(sensor), T0).prob_detection_array(states)
    detectable = np.array([bool(np.all(sensor.is_detectable(
        GroundTruthState(s.reshape(-1, 1), timestamp=T0)))) for s in states])
    return pd, detectable


def _targets(rng, centre, spread=1100.0):
    return np.column_stack([centre[0] + rng.uniform(-spread, spread, N), np.zeros(N),
                            centre[1] + rng.uniform(-spread, spread, N), np.zeros(N)])


@pytest.mark.parametrize("kind", ["RadarBearingRange", "RadarRotatingBearingRange",
                                  "RadarBearing", "RadarRotatingBearing"])
@pytest.mark.parametrize("platform", ["fixed", "moving"])
def test_pd_is_nonzero_exactly_where_the_sensor_can_detect(kind, platform):
    sensor = _sensors()[kind]
    if platform == "fixed":
        _fixed(sensor)
    else:
        _moving(sensor)
    rng = np.random.default_rng(zlib.crc32(f"{kind} {platform}".encode()))  # not hash(): salted
    position = np.asarray(sensor.position, dtype=float).ravel()
    pd, detectable = _agreement(sensor, _targets(rng, position))
    assert np.array_equal(pd > 0, detectable), int(((pd > 0) != detectable).sum())
    assert set(np.unique(pd)) <= {0.0, 0.9}
    assert 0.02 < detectable.mean() < 0.98  # both sides of the coverage were asked about


def test_the_pose_follows_the_platforms_states():
    sensor = RadarRotatingBearingRange(ndim_state=4, position_mapping=(0, 2), noise_covar=np.eye(2),
                                       dwell_centre=StateVector([0.4]), rpm=20,
                                       fov_angle=math.radians(60), max_range=800)
    platform = _moving(sensor, steps=0)
    for k in range(1, 6):
        platform.move(T0 + datetime.timedelta(seconds=k))
        state = platform.states[-1].state_vector.ravel()
        pose = sensor_pose(sensor)
        # an unmounted sensor sits on the platform's position, heading along its velocity,
        # its antenna turned by the dwell centre
        assert (pose.x, pose.y) == pytest.approx((state[0], state[2]), abs=1e-9)
        assert pose.heading == pytest.approx(math.atan2(state[3], state[1]) + 0.4, abs=1e-12)
    assert platform.states[-1].timestamp == T0 + datetime.timedelta(seconds=5)


def test_what_cannot_be_read_raises_naming_it():
    sensor = _fixed(_sensors()["RadarBearingRange"])
    with pytest.raises(ValueError, match="prob_detection: must lie in"):
        sensor_model_from_stonesoup(sensor, 1.5, 1e-4)
    with pytest.raises(TypeError, match="sensor: .* not a Stone Soup sensor read here"):
        sensor_model_from_stonesoup(object(), 0.9, 1e-4)
    tilted = RadarBearingRange(ndim_state=4, position_mapping=(0, 2), noise_covar=np.eye(2),
                               max_range=800, rotation_offset=StateVector([0.1, 0, 0]))
    _fixed(tilted)
    with pytest.raises(ValueError, match="roll .* tilt the coverage"):
        sensor_pose(tilted)
    # A subclass of a supported radar may add coverage rules (a raster-scanning radar's
    # frame): refused, not read as its parent.
    from stonesoup.sensor.radar.radar import RadarRasterScanBearingRange
    raster = RadarRasterScanBearingRange(
        ndim_state=4, position_mapping=(0, 2), noise_covar=np.eye(2), max_range=800,
        dwell_centre=StateVector([0.0]), rpm=20, fov_angle=math.radians(60),
        for_angle=math.radians(120))
    with pytest.raises(TypeError, match="RadarRasterScanBearingRange is not a Stone"):
        sensor_model_from_stonesoup(raster, 0.9, 1e-4)
    unmounted = RadarBearingRange(ndim_state=4, position_mapping=(0, 2), noise_covar=np.eye(2),
                                  max_range=800)
    with pytest.raises(ValueError, match="sensor: has no position or orientation"):
        sensor_pose(unmounted)
    blocked = _fixed(RadarBearingRange(ndim_state=4, position_mapping=(0, 2),
                                       noise_covar=np.eye(2), max_range=800))
    blocked.obstacles = ["a wall"]  # any obstacle: its occlusion would be dropped
    with pytest.raises(ValueError, match="sensor: has obstacles"):
        sensor_model_from_stonesoup(blocked, 0.9, 1e-4)


def _simulation(steps=40, seed=7):
    """Stone Soup's own simulation: targets from MultiTargetGroundTruthSimulator, a fixed
    radar and a rotating one on a moving platform."""
    from stonesoup.simulator.platform import PlatformDetectionSimulator
    from stonesoup.simulator.simple import MultiTargetGroundTruthSimulator
    from stonesoup.types.state import GaussianState

    transition = CombinedLinearGaussianTransitionModel([ConstantVelocity(0.5)] * 2)
    truths = MultiTargetGroundTruthSimulator(
        transition_model=transition,
        initial_state=GaussianState([[0], [0], [0], [0]], np.diag([400.0, 4.0, 400.0, 4.0]) ** 2,
                                    timestamp=T0),
        timestep=datetime.timedelta(seconds=1), number_steps=steps, birth_rate=0.4,
        death_probability=0.02, seed=seed)
    fixed = RadarBearingRange(ndim_state=4, position_mapping=(0, 2), noise_covar=np.eye(2),
                              max_range=600, **MOUNT)
    rotating = RadarRotatingBearingRange(ndim_state=4, position_mapping=(0, 2),
                                         noise_covar=np.eye(2), dwell_centre=StateVector([0.0]),
                                         rpm=10, fov_angle=math.radians(90), max_range=900)
    fixed_platform = FixedPlatform(states=[State(StateVector([100.0, 0, -50.0, 0]), timestamp=T0)],
                                   position_mapping=(0, 2), orientation=StateVector([0, 0, 0.7]),
                                   sensors=[fixed])
    moving_platform = _moving(rotating, steps=0)
    simulator = PlatformDetectionSimulator(groundtruth=truths,
                                           platforms=[fixed_platform, moving_platform])
    return simulator, truths, [fixed, rotating]


def test_platform_feeder_gives_each_scan_its_own_sensors_context():
    """Every scan of Stone Soup's PlatformDetectionSimulator comes with the context of the
    sensor that made it, at its pose then: P_D > 0 exactly at the live truths that sensor
    could detect at that time; SensorPose reads the same pose."""
    simulator, truths, sensors = _simulation()
    models = [SensorModel.from_stonesoup(s, 0.8, 1e-5) for s in sensors]
    feeder = PlatformContextFeeder(reader=simulator, sensor_models=models)
    scans, checked, detected = [0, 0], 0, 0
    for k, (time, scan) in enumerate(feeder):
        sensor = sensors[k % 2]
        scans[k % 2] += 1
        assert scan.detector_context.pose == sensor_pose(sensor) == \
            SensorPose(sensor=sensor).pose_at(time)
        assert scan.detector_context.sensor_model is models[k % 2]
        _, paths = truths.current
        for path in paths:
            state = path[-1]
            assert state.timestamp == time
            pd = scan.detector_context.prob_detection_array(
                np.asarray(state.state_vector, dtype=float).reshape(1, -1))[0]
            visible = bool(np.all(sensor.is_detectable(state)))
            assert (pd > 0) == visible
            checked, detected = checked + 1, detected + visible
    assert scans == [40, 40] and checked > 100 and 0 < detected < checked  # 40 steps
    with pytest.raises(ValueError, match="timestamp: the sensor's platform is at"):
        SensorPose(sensor=sensors[1]).pose_at(T0)


def test_platform_feeder_needs_one_model_per_sensor():
    simulator, _, sensors = _simulation(steps=2)
    with pytest.raises(ValueError, match="sensor_models: expected 2 SensorModels"):
        PlatformContextFeeder(reader=simulator,
                              sensor_models=[SensorModel.from_stonesoup(sensors[0], 0.8, 1e-5)])
    with pytest.raises(TypeError, match="reader: expected a Stone Soup PlatformDetectionSimulator"):
        PlatformContextFeeder(reader=[], sensor_models=[])
    from ctxmodels import Mounting
    mounted = [SensorModel.from_stonesoup(s, 0.8, 1e-5) for s in sensors]
    mounted[1] = SensorModel(detection=mounted[1].detection, clutter=mounted[1].clutter,
                             mounting=Mounting(forward=5.0))
    with pytest.raises(ValueError, match="sensor_models: the sensors' poses already hold"):
        PlatformContextFeeder(reader=simulator, sensor_models=mounted)
