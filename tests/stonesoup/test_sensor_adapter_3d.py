"""Stone Soup's 3-D radars read in 3-D (ctxmodels.stonesoup.sensor_adapter): the model reads
the state's (x, y, z), the pose has the sensor's height (and its pitch and roll), and
P_D > 0 exactly where the sensor's own ``is_detectable`` says so on 10⁴ random targets at
random heights per sensor type, mounted with offsets on fixed, moving and climbing
platforms, level and pitched and rolled (a rotating antenna's tilt too)."""
from __future__ import annotations

import datetime
import math
import zlib

import numpy as np
import pytest
from stonesoup.models.transition.linear import (CombinedLinearGaussianTransitionModel,
                                                ConstantVelocity)
from stonesoup.platform.base import FixedPlatform, MovingPlatform
from stonesoup.sensor.radar.radar import (RadarElevationBearingRange,
                                          RadarElevationBearingRangeRate,
                                          RadarRotatingElevationBearingRange)
from stonesoup.types.array import StateVector
from stonesoup.types.groundtruth import GroundTruthState
from stonesoup.types.state import GaussianState, State

from ctxmodels import ElevationSector, Pose, SensorModel
from ctxmodels.stonesoup import sensor_context, sensor_pose

T0 = datetime.datetime(2026, 1, 1)
N = 10_000
MOUNT = dict(mounting_offset=StateVector([5.0, 2.0, 3.0]), rotation_offset=StateVector([0, 0, 0.3]))
#: rolled 0.2 rad and pitched down 0.15 rad on its platform
TILTED = dict(mounting_offset=StateVector([5.0, 2.0, 3.0]),
              rotation_offset=StateVector([0.2, -0.15, 0.3]))


def _sensor(kind: str, mount=None, tilt: float = 0.0):
    common = dict(ndim_state=6, position_mapping=(0, 2, 4), max_range=800, **(mount or MOUNT))
    if kind == "RadarElevationBearingRange":
        return RadarElevationBearingRange(noise_covar=np.eye(3), **common)
    if kind == "RadarElevationBearingRangeRate":
        return RadarElevationBearingRangeRate(noise_covar=np.eye(4), velocity_mapping=(1, 3, 5),
                                              **common)
    return RadarRotatingElevationBearingRange(
        noise_covar=np.eye(3), dwell_centre=StateVector([1.1]), tilt_centre=StateVector([tilt]),
        rpm=20, fov_angle=math.radians(100), vertical_extent=math.radians(30), **common)


def _mount(sensor, platform: str):
    if platform == "fixed":
        FixedPlatform(states=[State(StateVector([100.0, 0, -50.0, 0, 12.0, 0]), timestamp=T0)],
                      position_mapping=(0, 2, 4), orientation=StateVector([0, 0, 0.7]),
                      sensors=[sensor])
        return
    # north-east at 7 m/s, 40 m up, moved five seconds along; a climbing platform (3 m/s
    # up) is pitched by Stone Soup, and its sensors with it
    climb = 3.0 if platform == "climbing" else 0.0
    transition = CombinedLinearGaussianTransitionModel([ConstantVelocity(0.0)] * 3)
    moving = MovingPlatform(states=[State(StateVector([0.0, 5.0, 0.0, 5.0, 40.0, climb]),
                                          timestamp=T0)],
                            position_mapping=(0, 2, 4), velocity_mapping=(1, 3, 5),
                            transition_model=transition, sensors=[sensor])
    for k in range(1, 6):
        moving.move(T0 + datetime.timedelta(seconds=k))


def _targets(rng, centre):
    return np.column_stack([centre[0] + rng.uniform(-900, 900, N), rng.normal(0, 5, N),
                            centre[1] + rng.uniform(-900, 900, N), rng.normal(0, 5, N),
                            centre[2] + rng.uniform(-400, 400, N), rng.normal(0, 5, N)])


KINDS = ["RadarElevationBearingRange", "RadarRotatingElevationBearingRange",
         "RadarElevationBearingRangeRate"]


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("platform", ["fixed", "moving"])
def test_pd_is_nonzero_exactly_where_the_3d_sensor_can_detect(kind, platform):
    sensor = _sensor(kind)
    _mount(sensor, platform)
    _agrees_with_is_detectable(sensor, f"{kind} {platform}")


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("platform", ["fixed", "climbing"])
def test_a_pitched_and_rolled_3d_sensor_reads_its_own_frame(kind, platform):
    sensor = _sensor(kind, TILTED, tilt=0.25)
    _mount(sensor, platform)
    pose = sensor_pose(sensor)
    assert pose.roll == pytest.approx(0.2) and pose.pitch != 0.0
    states = _agrees_with_is_detectable(sensor, f"{kind} {platform} tilted")
    # read level, the same targets are not the same: the tilt matters for a good share
    level = Pose(x=pose.x, y=pose.y, heading=pose.heading, z=pose.z, vx=pose.vx, vy=pose.vy,
                 vz=pose.vz)
    model = SensorModel.from_stonesoup(sensor, prob_detection=0.9, clutter_density=1e-4)
    tilted = model.context(pose, T0).prob_detection_array(states)
    flat = model.context(level, T0).prob_detection_array(states)
    if kind == "RadarElevationBearingRangeRate" or kind == "RadarElevationBearingRange":
        assert np.array_equal(tilted, flat)  # a range limit alone: no direction is read
    else:
        assert ((tilted > 0) != (flat > 0)).mean() > 0.02


def _agrees_with_is_detectable(sensor, label: str) -> np.ndarray:
    """P_D > 0 exactly where the sensor's is_detectable says so, for 10⁴ targets around it
    and on both context paths; the targets."""
    model = SensorModel.from_stonesoup(sensor, prob_detection=0.9, clutter_density=1e-4)
    assert model.position_mapping == (0, 2, 4)
    position = np.asarray(sensor.position, dtype=float).ravel()
    pose = sensor_pose(sensor)
    assert pose.z == position[2] != 0
    rng = np.random.default_rng(zlib.crc32(label.encode()))
    states = _targets(rng, position)
    detectable = np.array([bool(np.all(sensor.is_detectable(
        GroundTruthState(s.reshape(-1, 1), timestamp=T0)))) for s in states])
    for context in (model.context(pose, T0), sensor_context(sensor, model, T0)):
        pd = context.prob_detection_array(states)
        assert np.array_equal(pd > 0, detectable), int(((pd > 0) != detectable).sum())
        assert set(np.unique(pd)) <= {0.0, 0.9}
    assert 0.05 < detectable.mean() < 0.95  # both sides of the coverage were asked about
    # The same targets at the sensor's height but read on the plane are not the same:
    # heights matter (slant range, elevation) for a good share of them.
    planar = SensorModel(detection=model.detection, clutter=model.clutter,
                         position_mapping=(0, 2)).context(pose, T0).prob_detection_array(states)
    assert ((planar > 0) != detectable).mean() > 0.02
    return states


def test_the_rotating_3d_radars_vertical_extent_is_an_elevation_sector():
    sensor = _sensor("RadarRotatingElevationBearingRange")
    _mount(sensor, "fixed")
    model = SensorModel.from_stonesoup(sensor, 0.9, 1e-4)
    (sector,) = [f for f in model.detection.factors if isinstance(f, ElevationSector)]
    assert (sector.lower, sector.upper) == (-math.radians(15), math.radians(15))
    # straight up from the antenna: outside the ±15° beam, whatever the range
    pose = sensor_pose(sensor)
    above = np.array([[pose.x, 0, pose.y, 0, pose.z + 100.0, 0]])
    assert model.context(pose, T0).prob_detection_array(above)[0] == 0.0


def test_a_2d_state_is_refused_naming_it():
    sensor = _sensor("RadarElevationBearingRange")
    _mount(sensor, "fixed")
    context = SensorModel.from_stonesoup(sensor, 0.9, 1e-4).context(sensor_pose(sensor), T0)
    with pytest.raises(ValueError, match=r"means: position_mapping \(0, 2, 4\) is out of range "
                                         r"for rows of 4 columns"):
        context.prob_detection_array(np.zeros((3, 4)))
    with pytest.raises(ValueError, match="position_mapping"):
        context.prob_detection(GaussianState(StateVector([0.0, 0, 0, 0]), np.eye(4)))


def test_a_planar_model_of_a_3d_radar_is_refused_by_its_context():
    """A model reading x/y only would put every target at the radar's height, where the
    radar decides on the slant range: P_D > 0 would no longer be where is_detectable says."""
    sensor = _sensor("RadarElevationBearingRange")
    _mount(sensor, "fixed")
    model = SensorModel.from_stonesoup(sensor, 0.9, 1e-4)
    planar = SensorModel(detection=model.detection, clutter=model.clutter, position_mapping=(0, 2))
    with pytest.raises(ValueError, match=r"sensor_model: position_mapping \(0, 2\) is not the "
                                         r"sensor's \(0, 2, 4\)"):
        sensor_context(sensor, planar, T0)
