"""Range-rate blind zones (RangeRateNotch) against a direct NumPy computation of the radial
speed, planar and in 3-D, with a moving platform; every path gives the same bits; the
velocity comes from the state's velocity_mapping and the platform's from its pose (a
navigation log's segment, a Stone Soup platform's state); errors name the argument."""
from __future__ import annotations

import datetime
import math

import numpy as np
import pytest
from stonesoup.types.numeric import Probability
from stonesoup.types.state import GaussianState, State

from ctxmodels import (ArgumentError, ClutterDensityModel, DetectionProbabilityModel,
                       ElevationSector, NavigationTrack, NonFiniteError, Pose, RangeBands,
                       RangeRateNotch, SensorModel)

T0 = datetime.datetime(2026, 1, 1)


def _states(rng, n, raised):
    cols = [rng.uniform(-3000, 3000, n), rng.uniform(-40, 40, n), rng.uniform(-3000, 3000, n),
            rng.uniform(-40, 40, n)]
    if raised:
        cols += [rng.uniform(0, 1500, n), rng.uniform(-10, 10, n)]
    return np.column_stack(cols)


def _radial_speed(states, pose, raised):
    dp = [states[:, 0] - pose.x, states[:, 2] - pose.y]
    dv = [states[:, 1] - pose.vx, states[:, 3] - pose.vy]
    if raised:
        dp.append(states[:, 4] - pose.z)
        dv.append(states[:, 5] - pose.vz)
    dp, dv = np.array(dp), np.array(dv)
    return np.sum(dp * dv, axis=0) / np.linalg.norm(dp, axis=0)


def _notched(speed, notch):
    near = np.abs(speed) <= notch.width
    if notch.blind_speed is not None:
        for k in range(1, notch.multiples + 1):
            near |= np.abs(np.abs(speed) - k * notch.blind_speed) <= notch.width
    return near


@pytest.mark.parametrize("raised", [False, True])
@pytest.mark.parametrize("blind", [None, 23.0])
def test_the_notch_is_numpys_radial_speed_test(raised, blind):
    rng = np.random.default_rng(7 + raised + 2 * (blind is None))
    notch = RangeRateNotch(width=1.5, blind_speed=blind, multiples=2, inside=0.05)
    factors = [0.9, RangeBands(edges=(2500.0,), values=(1.0, 0.3)), notch]
    if raised:
        factors.append(ElevationSector(lower=-0.2, upper=1.2))
    mapping, velocity = ((0, 2, 4), (1, 3, 5)) if raised else ((0, 2), (1, 3))
    pose = Pose(x=40.0, y=-25.0, heading=0.4, z=20.0, vx=6.0, vy=-2.5, vz=0.5)
    states = _states(rng, 40_000, raised)
    # a share of them on the line of sight at the notch's speeds, to test both sides
    k = np.arange(0, 40_000, 10)
    towards = np.column_stack([states[k, 0] - pose.x, states[k, 2] - pose.y])
    towards /= np.linalg.norm(towards, axis=1)[:, None]
    speed = rng.choice([0.0, 1.0, 2.0, 22.0, 24.0, 46.0, 69.0], len(k))
    states[k, 1] = pose.vx + speed * towards[:, 0]
    states[k, 3] = pose.vy + speed * towards[:, 1]
    if raised:
        states[k, 4] = pose.z
        states[k, 5] = pose.vz
    model = SensorModel(detection=DetectionProbabilityModel(factors=factors),
                        clutter=ClutterDensityModel(factors=[1e-6]), position_mapping=mapping,
                        velocity_mapping=velocity)
    context = model.context(pose, T0)
    got = context.prob_detection_array(states)
    radial = _radial_speed(states, pose, raised)
    dx, dy = states[:, 0] - pose.x, states[:, 2] - pose.y
    dz = states[:, 4] - pose.z if raised else 0.0
    slant = np.sqrt(dx * dx + dy * dy + dz * dz)
    want = 0.9 * np.where(slant <= 2500.0, 1.0, 0.3) * np.where(_notched(radial, notch), 0.05, 1.0)
    if raised:
        elevation = np.arctan2(dz, np.hypot(dx, dy))
        want *= (elevation >= -0.2) & (elevation <= 1.2)
    # within rounding of a notch edge either side is right: left out, and few
    edges = [notch.width] + ([] if blind is None else [k * blind + s * notch.width
                                                         for k in (1, 2) for s in (-1, 1)])
    near = np.zeros(len(states), bool)
    for e in edges:
        near |= np.abs(np.abs(radial) - e) < 1e-9
    assert near.mean() < 1e-3
    np.testing.assert_allclose(got[~near], want[~near], rtol=1e-12, atol=0)
    assert (got == 0.05 * 0.9).sum() > 1000 and (got == 0.9).sum() > 1000  # both sides
    np.testing.assert_array_equal(context.prob_detection_particles(states.T.copy()), got)
    np.testing.assert_array_equal(context.prob_detection_particles(np.asfortranarray(states.T)),
                                  got)
    single = context.prob_detection(State(states[5].reshape(-1, 1)))
    assert single.log_value == Probability(got[5]).log_value


def test_a_crossing_boat_is_notched_and_a_moving_platform_counts():
    notch = DetectionProbabilityModel(factors=[RangeRateNotch(width=1.0)])
    boat = np.array([[1000.0, 0.0, 0.0, 5.0]])  # 1 km east, crossing north at 5 m/s
    still = Pose(x=0.0, y=0.0)
    assert notch.evaluate(still, boat, velocity_mapping=(1, 3)).tolist() == [0.0]
    # a radar ship sailing east at 5 m/s sees it close at 5 m/s: not notched
    sailing = Pose(x=0.0, y=0.0, vx=5.0)
    assert notch.evaluate(sailing, boat, velocity_mapping=(1, 3)).tolist() == [1.0]


def test_expected_pd_reads_the_velocity_at_the_mean():
    model = SensorModel(detection=DetectionProbabilityModel(factors=[RangeRateNotch(width=1.0)]),
                        clutter=ClutterDensityModel(factors=[1e-6]), velocity_mapping=(1, 3),
                        pd_evaluation="cubature")
    context = model.context(Pose(x=0.0, y=0.0), T0)
    mean = np.array([[1000.0, 0.5, 0.0, 0.0]])
    covar = np.diag([100.0, 400.0, 100.0, 400.0])  # a wide velocity spread, not integrated
    assert context.prob_detection_array(mean, covar[None]).tolist() == [0.0]
    assert float(context.prob_detection(GaussianState(mean.T, covar))) == 0.0


def test_the_platforms_velocity_comes_from_its_navigation_log():
    track = NavigationTrack(timestamps=[T0, T0 + datetime.timedelta(seconds=10),
                                        T0 + datetime.timedelta(seconds=20)],
                            positions=[[0.0, 0.0], [50.0, 0.0], [50.0, 100.0]],
                            headings=[0.0, 0.0, math.pi / 2])
    assert track.pose_at(T0 + datetime.timedelta(seconds=3)).as_tuple()[4:] == (5.0, 0.0, 0.0)
    assert track.pose_at(T0 + datetime.timedelta(seconds=10)).as_tuple()[4:] == (0.0, 10.0, 0.0)
    assert track.pose_at(T0 + datetime.timedelta(seconds=20)).as_tuple()[4:] == (0.0, 10.0, 0.0)


def test_a_stone_soup_platforms_velocity_is_the_poses():
    from stonesoup.models.transition.linear import (CombinedLinearGaussianTransitionModel,
                                                    ConstantVelocity)
    from stonesoup.platform.base import MovingPlatform
    from stonesoup.sensor.radar.radar import RadarBearingRange
    from stonesoup.types.array import StateVector

    from ctxmodels.stonesoup import sensor_pose
    radar = RadarBearingRange(ndim_state=4, position_mapping=(0, 2), noise_covar=np.eye(2),
                              max_range=800)
    MovingPlatform(states=[State(StateVector([0.0, 5.0, 0.0, 3.0]), timestamp=T0)],
                   position_mapping=(0, 2), velocity_mapping=(1, 3),
                   transition_model=CombinedLinearGaussianTransitionModel([ConstantVelocity(0)] * 2),
                   sensors=[radar])
    pose = sensor_pose(radar)
    assert (pose.vx, pose.vy, pose.vz) == (5.0, 3.0, 0.0)


@pytest.mark.parametrize("make, argument", [
    (lambda: RangeRateNotch(width=-1.0), "width"),
    (lambda: RangeRateNotch(width=float("nan")), "width"),
    (lambda: RangeRateNotch(width=2.0, blind_speed=3.0), "blind_speed"),
    (lambda: RangeRateNotch(width=2.0, blind_speed=30.0, multiples=0), "multiples"),
    (lambda: RangeRateNotch(width=2.0, blind_speed=30.0, multiples=65), "multiples"),
    (lambda: RangeRateNotch(width=2.0, multiples=1.5), "multiples"),
    (lambda: Pose(x=0.0, y=0.0, vx=float("inf")), "vx"),
    (lambda: SensorModel(detection=DetectionProbabilityModel(factors=[0.9]),
                         clutter=ClutterDensityModel(factors=[1.0]), velocity_mapping=(1, 3, 5)),
     "velocity_mapping"),
    (lambda: SensorModel(detection=DetectionProbabilityModel(factors=[0.9]),
                         clutter=ClutterDensityModel(factors=[1.0]), velocity_mapping=(1, 2)),
     "velocity_mapping"),
])
def test_bad_notches_and_velocity_mappings_name_their_argument(make, argument):
    with pytest.raises((TypeError, ValueError)) as info:
        make()
    assert str(info.value).startswith(argument), str(info.value)


def test_bad_velocities_name_the_state_and_a_missing_mapping_names_it():
    model = SensorModel(detection=DetectionProbabilityModel(factors=[RangeRateNotch(width=1.0)]),
                        clutter=ClutterDensityModel(factors=[1e-6]), velocity_mapping=(1, 3))
    context = model.context(Pose(x=0.0, y=0.0), T0)
    states = _states(np.random.default_rng(1), 10, False)
    states[4, 3] = np.nan
    with pytest.raises(NonFiniteError) as info:
        context.prob_detection_array(states)
    assert (info.value.argument, info.value.row) == ("means", 4)
    with pytest.raises(ArgumentError, match="particles: particle 4"):
        context.prob_detection_particles(states.T.copy())
    with pytest.raises(ArgumentError) as info:
        SensorModel(detection=model.detection, clutter=model.clutter)
    assert info.value.argument == "velocity_mapping"
    with pytest.raises(ArgumentError) as info:
        model.detection.evaluate(Pose(x=0, y=0), states)
    assert info.value.argument == "velocity_mapping"
    with pytest.raises(ArgumentError, match="means: .*out of range for rows of 3 columns"):
        context.prob_detection_array(np.zeros((2, 3)))
