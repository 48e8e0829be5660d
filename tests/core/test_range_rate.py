"""Range-rate blind zones (RangeRateNotch) against a direct NumPy computation of the radial
speed, planar and in 3-D, with a moving platform; every path gives the same bits; the
velocity comes from the state's velocity_mapping and the platform's from its pose (a
navigation log's segment, a Stone Soup platform's state); errors name the argument."""
from __future__ import annotations

import datetime
import math

import numpy as np
import pytest
from scipy.stats import norm
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


def test_a_newborns_unknown_velocity_is_integrated_exactly():
    """A Gaussian known in position, with a velocity spread: ṙ is normal, and the expected
    P_D is 1 − P(|ṙ| ≤ w), here from scipy's normal CDF (a birth at zero velocity with a
    20 m/s spread is rarely in the notch, though its mean is)."""
    model = SensorModel(detection=DetectionProbabilityModel(factors=[RangeRateNotch(width=1.0)]),
                        clutter=ClutterDensityModel(factors=[1e-6]), velocity_mapping=(1, 3),
                        pd_evaluation="cubature")
    context = model.context(Pose(x=0.0, y=0.0), T0)
    mean = np.array([[1000.0, 0.5, 0.0, 0.0]])
    covar = np.diag([0.0, 400.0, 0.0, 400.0])  # ṙ = vx ~ N(0.5, 20²)
    want = 1 - (norm.cdf((1 - 0.5) / 20) - norm.cdf((-1 - 0.5) / 20))
    got = context.prob_detection_array(mean, covar[None])
    assert got[0] == pytest.approx(want, rel=0, abs=1e-15)
    assert float(context.prob_detection(GaussianState(mean.T, covar))) == got[0]
    # a velocity known exactly: the notch read at the mean, as P_D at the mean reads it
    assert context.prob_detection_array(mean, np.diag([100.0, 0, 100.0, 0])[None]).tolist() == [0.0]


def _joint_covariances(rng, n, raised):
    d = 6 if raised else 4
    scale = np.where(np.arange(d) % 2 == 0, 60.0, 3.0)  # metres, m/s
    a = np.tril(rng.normal(0, 1, (n, d, d))) * scale[:, None]
    return a @ np.swapaxes(a, 1, 2)


def _rao_blackwell(model, pose, means, covars, raised, points, weights):
    """Σ_k w_k P_D(p_k, v̄_k) with the notch replaced by 1 − (1 − inside)·P(ṙ in a notch),
    ṙ normal given p_k: NumPy's conditional Gaussian and scipy's normal CDF."""
    notch = next(f for f in model.factors if isinstance(f, RangeRateNotch))
    rest = DetectionProbabilityModel(factors=[f for f in model.factors if f is not notch])
    pos, vel = ([0, 2, 4], [1, 3, 5]) if raised else ([0, 2], [1, 3])
    origin = np.array([pose.x, pose.y, pose.z][:len(pos)])
    platform = np.array([pose.vx, pose.vy, pose.vz][:len(pos)])
    out = np.zeros(len(means))
    for i, (m, c) in enumerate(zip(means, covars)):
        chol = np.linalg.cholesky(c[np.ix_(pos, pos)])
        gain = c[np.ix_(vel, pos)] @ np.linalg.inv(c[np.ix_(pos, pos)])
        left = c[np.ix_(vel, vel)] - gain @ c[np.ix_(pos, vel)]
        for u, w in zip(points, weights):
            p = m[pos] + chol @ u
            v = m[vel] + gain @ (p - m[pos])
            state = np.zeros(len(m))
            state[pos], state[vel] = p, v
            value = rest.evaluate(pose, state[None], pos, velocity_mapping=vel)[0]
            dp = p - origin
            r = np.linalg.norm(dp)
            mu, sd = dp @ (v - platform) / r, np.sqrt(dp @ left @ dp) / r
            centres = [0.0]
            if notch.blind_speed is not None:
                centres += [s * k * notch.blind_speed for k in range(1, notch.multiples + 1)
                            for s in (1, -1)]
            inside = sum(norm.cdf((c0 + notch.width - mu) / sd) - norm.cdf((c0 - notch.width - mu) / sd)
                         for c0 in centres)
            out[i] += w * value * (notch.outside + (notch.inside - notch.outside) * inside)
    return np.clip(out, 0, 1)


@pytest.mark.parametrize("raised", [False, True])
def test_the_expected_notch_is_numpys_conditional_gaussian(raised):
    rng = np.random.default_rng(31 + raised)
    model = DetectionProbabilityModel(factors=[
        0.9, RangeBands(edges=(1500.0,), values=(1.0, 0.4)),
        RangeRateNotch(width=1.5, blind_speed=12.0, multiples=2, inside=0.1)])
    pose = Pose(x=30.0, y=-10.0, z=12.0, vx=2.0, vy=-1.0, vz=0.3)
    n = 300
    means = _states(rng, n, raised)
    means[:, [0, 2]] *= 0.5
    means[:, [1, 3]] *= 0.1  # slow: near the notch and the blind speeds
    covars = _joint_covariances(rng, n, raised)
    mapping, velocity = ((0, 2, 4), (1, 3, 5)) if raised else ((0, 2), (1, 3))
    got = model.expected(pose, means, covars, mapping, "cubature", velocity_mapping=velocity)
    d = len(mapping)
    points = np.vstack([np.sqrt(d) * np.eye(d), -np.sqrt(d) * np.eye(d)])
    want = _rao_blackwell(model, pose, means, covars, raised, points, np.full(2 * d, 1 / (2 * d)))
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-12)
    at_mean = model.expected(pose, means, covars * _position_block(d), mapping, "cubature",
                             velocity_mapping=velocity)
    assert np.mean(np.abs(got - at_mean) > 0.01) > 0.2  # the spread matters for these


def _position_block(d):
    """A mask keeping the position rows and columns of a [x, vx, y, vy(, z, vz)] covariance."""
    keep = np.arange(2 * d) % 2 == 0
    return np.outer(keep, keep).astype(float)


@pytest.mark.parametrize("raised", [False, True])
def test_the_expected_notch_is_monte_carlos(raised):
    """The joint Gaussian sampled (position and velocity together, 400 000 draws) against a
    Gauss–Hermite rule of order 8 over the position: the notch alone, so that what the rule
    integrates is smooth (a covariance with velocity of its own: one that ties the velocity
    to the position makes the notch a step in position, which a rule meets slowly)."""
    rng = np.random.default_rng(5 + raised)
    model = DetectionProbabilityModel(factors=[
        RangeRateNotch(width=1.5, blind_speed=9.0, multiples=2, inside=0.1)])
    pose = Pose(x=0.0, y=0.0, z=10.0, vx=1.0, vy=0.5)
    mapping, velocity = ((0, 2, 4), (1, 3, 5)) if raised else ((0, 2), (1, 3))
    mean = np.array([800.0, 1.0, 300.0, 0.5, 200.0, 0.2][:2 * len(mapping)])
    sd = np.array([50.0, 2.0, 40.0, 1.5, 30.0, 1.0])[:len(mean)]
    correlation = np.full((len(mean), len(mean)), 0.3) + 0.7 * np.eye(len(mean))
    correlation[0, 2] = correlation[2, 0] = -0.2
    covar = correlation * np.outer(sd, sd)
    got = model.expected(pose, mean[None], covar[None], mapping, "gauss-hermite", 8,
                         velocity_mapping=velocity)[0]
    draws = rng.multivariate_normal(mean, covar, 400_000)
    pd = model.evaluate(pose, draws, mapping, velocity_mapping=velocity)
    sd = pd.std() / np.sqrt(len(pd))
    assert abs(got - pd.mean()) <= 4 * sd + 1e-4, (got, pd.mean(), sd)
    assert 0.2 < got < 0.95  # a case where the notch is in play


def test_a_model_holds_one_notch():
    with pytest.raises(ArgumentError) as info:
        DetectionProbabilityModel(factors=[RangeRateNotch(width=1.0), RangeRateNotch(width=2.0)])
    assert info.value.argument == "factors"


def test_the_platforms_velocity_comes_from_its_navigation_log():
    track = NavigationTrack(timestamps=[T0, T0 + datetime.timedelta(seconds=10),
                                        T0 + datetime.timedelta(seconds=20)],
                            positions=[[0.0, 0.0], [50.0, 0.0], [50.0, 100.0]],
                            headings=[0.0, 0.0, math.pi / 2])
    assert track.pose_at(T0 + datetime.timedelta(seconds=3)).as_tuple()[4:7] == (5.0, 0.0, 0.0)
    assert track.pose_at(T0 + datetime.timedelta(seconds=10)).as_tuple()[4:7] == (0.0, 10.0, 0.0)
    assert track.pose_at(T0 + datetime.timedelta(seconds=20)).as_tuple()[4:7] == (0.0, 10.0, 0.0)


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
