"""Coverage in 3-D: states with a height (a three-index ``position_mapping``) against
independent NumPy/Shapely references — slant-range bands, elevation sectors (atan2),
bearings on the plane, the radar horizon at each target's height (the spherical Earth's
tangent geometry), land below the target — for random factor stacks; the 3-D integration
rules against their own nodes; poses and mountings with heights; errors naming the
argument."""
from __future__ import annotations

import datetime
import math

import numpy as np
import pytest
import shapely
from numpy.polynomial.hermite_e import hermegauss
from stonesoup.types.numeric import Probability
from stonesoup.types.state import GaussianState, State

from ctxmodels import (AngularSector, ArgumentError, ClutterDensityModel, DetectionProbabilityModel,
                       ElevationSector, LandMask, LineOfSight, Mounting, NavigationTrack,
                       NonFiniteError, Pose, RadarEquation, RadarHorizon, RangeBands, SensorModel)

ISLAND = [[300.0, -200.0], [600.0, -200.0], [600.0, 200.0], [300.0, 200.0]]
POSE = Pose(x=-20.0, y=35.0, heading=1.1, z=40.0)


def _states(rng, n):
    states = np.column_stack([rng.uniform(-1500, 1500, n), rng.normal(0, 3, n),
                              rng.uniform(-1500, 1500, n), rng.normal(0, 3, n),
                              rng.uniform(-200, 1200, n), rng.normal(0, 1, n)])
    return states


def _offsets(states, pose=POSE):
    dx, dy, dz = states[:, 0] - pose.x, states[:, 2] - pose.y, states[:, 4] - pose.z
    return dx, dy, dz


def _reference(factors, states, pose=POSE):
    """The product of the factors, each computed directly: what the model must give."""
    dx, dy, dz = _offsets(states, pose)
    plane = np.hypot(dx, dy)
    slant = np.sqrt(dx * dx + dy * dy + dz * dz)
    elevation = np.arctan2(dz, plane)
    bearing = np.arctan2(dy, dx) - pose.heading
    pd = np.ones(len(states))
    for f in factors:
        if isinstance(f, float):
            pd *= f
        elif isinstance(f, RangeBands):
            pd *= f(slant)
        elif isinstance(f, RadarEquation):
            pd *= f(slant)
        elif isinstance(f, ElevationSector):
            inside = (elevation >= f.lower) & (elevation <= f.upper)
            pd *= np.where(inside, f.inside, f.outside)
        elif isinstance(f, AngularSector):
            off = np.abs(np.remainder(bearing - f.centre + math.pi, 2 * math.pi) - math.pi)
            pd *= np.where(off <= f.width / 2, f.inside, f.outside)
        elif isinstance(f, RadarHorizon):
            scale = 2 * f.k * f.earth_radius
            reach = math.sqrt(scale * f.antenna_height) + np.sqrt(scale * np.maximum(states[:, 4], 0))
            pd *= plane <= reach
        elif isinstance(f, LandMask):
            pd *= ~shapely.covers(shapely.Polygon(ISLAND), shapely.points(states[:, 0], states[:, 2]))
        else:
            raise AssertionError(f)
    return pd, elevation, plane


def _factor_pool():
    return [
        0.9,
        RangeBands(edges=(300.0, 1100.0), values=(0.95, 0.6, 0.1), upper_owns=(True, False)),
        ElevationSector(lower=math.radians(-3), upper=math.radians(35)),
        ElevationSector(lower=math.radians(5), upper=math.pi / 2, inside=0.7, outside=0.2),
        AngularSector.blind(math.pi, math.radians(65)),
        RadarHorizon(antenna_height=30.0, target_height=None, earth_radius=20_000.0),
        RadarEquation(reference_snr=12.0, reference_range=900.0, false_alarm_probability=1e-6,
                      swerling=1),
        LandMask(polygons=[ISLAND]),
    ]


@pytest.mark.parametrize("seed", range(12))
def test_random_factor_stacks_in_3d_match_the_numpy_product(seed):
    rng = np.random.default_rng(seed)
    pool = _factor_pool()
    picks = rng.choice(len(pool), size=rng.integers(1, 5), replace=False)
    factors = [pool[i] for i in picks]
    states = _states(rng, 20_000)
    want, elevation, plane = _reference(factors, states)
    model = DetectionProbabilityModel(factors=factors)
    got = model.evaluate(POSE, states, (0, 2, 4))
    # Targets within rounding of an edge (elevation limits, bearings, ranges, the horizon)
    # may fall either way: left out, and few.
    near = np.zeros(len(states), dtype=bool)
    for f in factors:
        if isinstance(f, ElevationSector):
            near |= (np.abs(elevation - f.lower) < 1e-9) | (np.abs(elevation - f.upper) < 1e-9)
    ok = np.isclose(got, want, rtol=1e-12, atol=0) | near
    assert ok.all(), (factors, int((~ok).sum()))
    assert near.mean() < 1e-3
    # every path gives the same bits: particles (both orders) and the scan's context
    np.testing.assert_array_equal(model.evaluate_particles(POSE, states.T.copy(), (0, 2, 4)), got)
    np.testing.assert_array_equal(model.evaluate_particles(POSE, np.asfortranarray(states.T),
                                                           (0, 2, 4)), got)
    context = SensorModel(detection=model, clutter=ClutterDensityModel(factors=[1e-4]),
                          position_mapping=(0, 2, 4)).context(POSE)
    np.testing.assert_array_equal(context.prob_detection_array(states), got)
    single = context.prob_detection(State(states[7].reshape(-1, 1)))
    assert single.log_value == Probability(got[7]).log_value


def test_the_horizon_at_each_targets_height_is_the_spherical_earths():
    rng = np.random.default_rng(5)
    horizon = RadarHorizon(antenna_height=25.0, target_height=None)
    big = horizon.k * horizon.earth_radius
    heights = rng.uniform(0, 1000, 4000)
    direct = big * (math.acos(big / (big + 25.0)) + np.arccos(big / (big + heights)))
    bearing = rng.uniform(-math.pi, math.pi, 4000)
    for scale, want in ((0.998, 1.0), (1.002, 0.0)):
        states = np.zeros((4000, 6))
        states[:, 0] = scale * direct * np.cos(bearing)
        states[:, 2] = scale * direct * np.sin(bearing)
        states[:, 4] = heights
        pd = DetectionProbabilityModel(factors=[horizon]).evaluate(Pose(x=0.0, y=0.0), states,
                                                                    (0, 2, 4))
        assert (pd == want).all()
    # a target below the sea is at it
    below = np.array([[0.999 * horizon.range, 0, 0, 0, -50.0, 0],
                      [1.001 * horizon.range, 0, 0, 0, -50.0, 0]])
    assert DetectionProbabilityModel(factors=[horizon]).evaluate(
        Pose(x=0.0, y=0.0), below, (0, 2, 4)).tolist() == [1.0, 0.0]


@pytest.mark.parametrize("rule, order", [("mean", 3), ("cubature", 3), ("unscented", 3),
                                         ("gauss-hermite", 4), ("gauss-hermite", 9)])
def test_expected_pd_integrates_the_rule_over_the_height(rule, order):
    """A Gaussian spread in height only, under an elevation beam: the expected P_D is the
    rule's weighted count of its height nodes inside the beam, built here from NumPy's
    Gauss–Hermite nodes and the rules' definitions."""
    sector = ElevationSector(lower=math.radians(-2), upper=math.radians(20))
    model = DetectionProbabilityModel(factors=[sector])
    sigma = 150.0
    mean = np.array([[800.0, 0, 0.0, 0, 100.0, 0]])
    covar = np.diag([0.0, 1.0, 0.0, 1.0, sigma ** 2, 1.0])[None]
    if rule == "mean":
        nodes, weights = np.array([0.0]), np.array([1.0])
    elif rule == "cubature":  # 6 points at ±√3, two of them on the height axis
        nodes, weights = np.array([0.0, math.sqrt(3), -math.sqrt(3)]), np.array([4, 1, 1]) / 6
    elif rule == "unscented":  # κ = 1: centre 1/4, 6 points at ±2
        nodes, weights = np.array([0.0, 0.0, 2.0, -2.0]), np.array([0.25, 0.5, 0.125, 0.125])
    else:
        x, w = hermegauss(order)
        nodes, weights = x, w / w.sum()
    heights = mean[0, 4] + sigma * nodes
    elevation = np.arctan2(heights - POSE.z, np.hypot(800.0 - POSE.x, 0.0 - POSE.y))
    want = float(np.sum(weights * ((elevation >= sector.lower) & (elevation <= sector.upper))))
    got = model.expected(POSE, mean, covar, (0, 2, 4), rule, order)[0]
    assert got == pytest.approx(want, abs=1e-12)


def test_poses_mountings_and_navigation_carry_heights():
    platform = Pose(x=1.0, y=2.0, heading=0.5, z=10.0)
    sensor = Mounting(forward=2.0, up=4.5).apply(platform)
    assert sensor.z == 14.5
    assert (sensor.x, sensor.y) == pytest.approx((1 + 2 * math.cos(0.5), 2 + 2 * math.sin(0.5)))
    model = SensorModel(detection=DetectionProbabilityModel(factors=[ElevationSector(
        lower=0.0, upper=math.pi / 2)]), clutter=ClutterDensityModel(factors=[1e-4]),
        position_mapping=(0, 2, 4), mounting=Mounting(up=4.5))
    context = model.context(platform)
    assert context.pose.z == 14.5
    # just below and just above the antenna, 100 m out
    x = sensor.x + 100.0
    rows = np.array([[x, 0, sensor.y, 0, 14.0, 0], [x, 0, sensor.y, 0, 15.0, 0]])
    assert context.prob_detection_array(rows).tolist() == [0.0, 1.0]
    t0 = datetime.datetime(2026, 1, 1)
    track = NavigationTrack(timestamps=[t0, t0 + datetime.timedelta(seconds=10)],
                            positions=[[0.0, 0.0, 0.0], [100.0, 0.0, 50.0]], headings=[0.0, 0.0])
    assert track.pose_at(t0 + datetime.timedelta(seconds=4)).z == pytest.approx(20.0)


@pytest.mark.parametrize("make, argument", [
    (lambda: ElevationSector(lower=-0.03, upper=30.0), "upper"),  # degrees
    (lambda: ElevationSector(lower=0.3, upper=0.1), "upper"),
    (lambda: ElevationSector(lower=float("nan"), upper=0.1), "lower"),
    (lambda: ElevationSector(lower=0.0, upper=0.1, inside=1.5), "factors"),
    (lambda: Pose(x=0.0, y=0.0, z=float("inf")), "z"),
    (lambda: Mounting(up=float("nan")), "up"),
    (lambda: RadarHorizon(antenna_height=-1.0, target_height=None), "antenna_height"),
    (lambda: RadarHorizon(antenna_height=1.0, target_height=None, k=0.0), "k"),
    (lambda: SensorModel(detection=DetectionProbabilityModel(factors=[0.9]),
                         clutter=ClutterDensityModel(factors=[1.0]), position_mapping=(0, 2, 2)),
     "position_mapping"),
    (lambda: SensorModel(detection=DetectionProbabilityModel(factors=[0.9]),
                         clutter=ClutterDensityModel(factors=[1.0]),
                         position_mapping=(0, 2, 4, 5)), "position_mapping"),
    (lambda: NavigationTrack(timestamps=[datetime.datetime(2026, 1, 1)], positions=[[0.0] * 4],
                             headings=[0.0]), "positions"),
])
def test_bad_heights_and_mappings_name_their_argument(make, argument):
    with pytest.raises((ArgumentError, TypeError, ValueError)) as info:
        factor = make()
        if isinstance(factor, ElevationSector):
            DetectionProbabilityModel(factors=[factor])
    assert str(info.value).startswith(argument), str(info.value)


def test_bad_states_for_a_3d_model_name_their_argument():
    model = SensorModel(detection=DetectionProbabilityModel(factors=[
        0.9, ElevationSector(lower=0.0, upper=0.5),
        RadarHorizon(antenna_height=20.0, target_height=None)]),
        clutter=ClutterDensityModel(factors=[1e-4]), position_mapping=(0, 2, 4))
    context = model.context(POSE)
    states = _states(np.random.default_rng(1), 10)
    states[6, 4] = np.nan
    with pytest.raises(NonFiniteError) as info:
        context.prob_detection_array(states)
    assert (info.value.argument, info.value.row) == ("means", 6)
    with pytest.raises(ArgumentError, match="particles: particle 6"):
        context.prob_detection_particles(states.T.copy())
    with pytest.raises(ArgumentError, match=r"means: position_mapping \(0, 2, 4\) is out of range"):
        context.prob_detection_array(np.zeros((2, 4)))  # a 2-D state for a 3-D model
    with pytest.raises(ArgumentError, match="position_mapping"):
        context.prob_detection(GaussianState(np.zeros((4, 1)), np.eye(4)))
    # the horizon at each target's height needs the height: named by a planar sensor model,
    # and by a planar evaluation
    with pytest.raises(ArgumentError) as info:
        SensorModel(detection=model.detection, clutter=model.clutter)
    assert info.value.argument == "position_mapping"
    with pytest.raises(ArgumentError) as info:
        model.detection.evaluate(POSE, np.zeros((2, 4)))
    assert info.value.argument == "position_mapping"
    bad_covar = np.tile(np.eye(6), (10, 1, 1))
    bad_covar[3, 4, 4] = -5.0
    cubature = SensorModel(detection=model.detection, clutter=model.clutter,
                           position_mapping=(0, 2, 4), pd_evaluation="cubature").context(POSE)
    states[6, 4] = 10.0
    with pytest.raises(ArgumentError, match="covars: row 3"):
        cubature.prob_detection_array(states, bad_covar)


def test_land_and_line_of_sight_are_read_below_the_target():
    land = LandMask(polygons=[ISLAND])
    model = DetectionProbabilityModel(factors=[LineOfSight(land=land)])
    # behind the island, high or low: line of sight is planar (terrain heights are not known)
    rows = np.array([[800.0, 0, 0.0, 0, 0.0, 0], [800.0, 0, 0.0, 0, 3000.0, 0]])
    assert model.evaluate(Pose(x=0.0, y=0.0, z=40.0), rows, (0, 2, 4)).tolist() == [0.0, 0.0]
