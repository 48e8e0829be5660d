"""The radar equation's P_D and the radar horizon against independent references: SciPy's
non-central χ² averaged over each Swerling case's cross-section distribution (numerical
quadrature, not the core's closed forms), SciPy's inverse incomplete gamma for the
threshold, and a direct spherical-Earth computation of the horizon."""
import math
import pickle

import numpy as np
import pytest
from scipy import integrate, special, stats
from stonesoup.serialise import YAML

import ctxmodels
from ctxmodels import (AngularSector, DetectionProbabilityModel, LandMask, Pose, RadarEquation,
                       RadarHorizon, RangeBands)
from ctxmodels.errors import ArgumentError, ArgumentTypeError

#: Stated agreement with the quadrature reference (which is asked for 1e-12).
RELATIVE = 1e-10


def _reference(case, pulses, snr, pfa):
    """P(y > T) with y the sum of `pulses` square-law pulse powers (noise power 1): given the
    summed signal-to-noise v, 2y is non-central χ² with 2n degrees of freedom and
    non-centrality 2 S v; v's distribution is the Swerling case's."""
    n = pulses
    threshold = special.gammainccinv(n, pfa)

    def given(v):
        return stats.ncx2.sf(2 * threshold, 2 * n, 2 * snr * v) if v > 0 else pfa

    if case == 0:
        return given(n)
    spread = {1: stats.expon(scale=n),            # one exponential σ for all pulses
              2: stats.gamma(n, scale=1.0),       # an exponential σ per pulse
              3: stats.gamma(2, scale=n / 2),     # one χ²(4) σ for all pulses
              4: stats.gamma(2 * n, scale=0.5)}[case]  # a χ²(4) σ per pulse
    value, _ = integrate.quad(lambda v: given(v) * spread.pdf(v), 0, np.inf,
                              epsabs=0, epsrel=1e-12, limit=500)
    return value


@pytest.mark.parametrize("case", range(5))
@pytest.mark.parametrize("pulses", [1, 3, 10])
@pytest.mark.parametrize("pfa", [1e-2, 1e-6, 1e-10])
def test_p_d_is_the_averaged_non_central_chi_squared(case, pulses, pfa):
    worst = 0.0
    for snr_db in np.arange(-10.0, 30.1, 5.0):
        radar = RadarEquation(reference_snr=snr_db, reference_range=1.0, false_alarm_probability=pfa,
                              swerling=case, pulses=pulses)
        snr = radar.snr([1.0])[0]
        assert snr == pytest.approx(10 ** (snr_db / 10), rel=1e-15)
        expected = _reference(case, pulses, snr, pfa)
        got = radar([1.0])[0]
        worst = max(worst, abs(got - expected) / expected)
    assert worst < RELATIVE, worst


@pytest.mark.parametrize("pfa", [1e-16, 1e-30, 1e-100, 1.0000001e-300])
@pytest.mark.parametrize("pulses", [1, 4])
def test_a_steady_targets_p_d_keeps_its_relative_accuracy_at_a_tiny_false_alarm_rate(pfa, pulses):
    """Far below the mode's window, the Poisson tail still carries a P_D near P_FA."""
    radar = RadarEquation(reference_snr=13.0, reference_range=1500.0, false_alarm_probability=pfa,
                          swerling=0, pulses=pulses)
    r = np.array([1304.55, 3000.0, 6000.0])
    expected = stats.ncx2.sf(2 * radar.threshold, 2 * pulses, 2 * pulses * radar.snr(r))
    np.testing.assert_allclose(radar(r), expected, rtol=1e-12)


@pytest.mark.parametrize("pulses", [1, 2, 7, 100, 1024])
@pytest.mark.parametrize("pfa", [0.5, 1e-2, 1e-6, 1e-10, 1e-200])
def test_the_threshold_is_the_inverse_incomplete_gamma(pulses, pfa):
    radar = RadarEquation(reference_snr=0.0, reference_range=1.0, false_alarm_probability=pfa,
                          pulses=pulses)
    assert radar.threshold == pytest.approx(special.gammainccinv(pulses, pfa), rel=1e-12)
    assert radar([1e12])[0] == pytest.approx(pfa, rel=1e-12)  # no signal: P_D = P_FA


def test_single_pulse_snr_for_p_d_09_is_the_textbooks():
    """P_FA 1e-6, one pulse, P_D 0.9 needs about 13.2 dB on a steady target, 21.1 dB on a
    Swerling 1 or 2 target and 17.3 dB on a Swerling 3 or 4 target (the radar textbooks'
    figures, e.g. Richards, Fundamentals of Radar Signal Processing, ch. 6)."""
    from scipy.optimize import brentq

    def needed(case):
        def miss(db):
            radar = RadarEquation(reference_snr=db, reference_range=1.0,
                                  false_alarm_probability=1e-6, swerling=case)
            return radar([1.0])[0] - 0.9
        return brentq(miss, -10, 40, xtol=1e-6)

    for case, published in [(0, 13.2), (1, 21.1), (2, 21.1), (3, 17.3), (4, 17.3)]:
        assert needed(case) == pytest.approx(published, abs=0.06), case


def test_p_d_falls_with_the_fourth_power_of_range():
    radar = RadarEquation(reference_snr=20.0, reference_range=2000.0, loss=3.0,
                          false_alarm_probability=1e-6, swerling=1)
    r = np.array([0.0, 500.0, 2000.0, 4000.0, 1e7])
    snr = radar.snr(r)
    assert snr[0] == np.inf and snr[2] == pytest.approx(10 ** 1.7, rel=1e-14)
    assert snr[3] == pytest.approx(10 ** 1.7 / 16, rel=1e-14)
    pd = radar(r)
    assert pd[0] == 1.0 and np.all(np.diff(pd) < 0)
    # Swerling 1, one pulse: P_FA^(1/(1+S)) exactly
    np.testing.assert_allclose(pd[1:], 1e-6 ** (1 / (1 + snr[1:])), rtol=1e-14)
    assert np.isnan(radar([np.nan])[0])


def test_the_factor_composes_with_every_other_factor():
    """P_D of a stack with the radar equation is the product of each factor's own value."""
    rng = np.random.default_rng(7)
    radar = RadarEquation(reference_snr=12.0, reference_range=800.0, false_alarm_probability=1e-5,
                          swerling=3, pulses=4)
    horizon = RadarHorizon(antenna_height=4.0, target_height=1.0)  # 11.5 km
    bands = RangeBands(edges=(50.0, 5000.0), values=(0.0, 0.97, 0.5), upper_owns=(False, True))
    blind = AngularSector(centre=math.pi, width=math.radians(65), inside=0.0, outside=1.0)
    island = LandMask(polygons=[{"shell": np.array([[3e3, -1e3], [5e3, -1e3], [5e3, 1e3], [3e3, 1e3]]),
                                 "holes": []}])
    model = DetectionProbabilityModel(factors=[0.9, bands, radar, blind, horizon, island])
    pose = Pose(120.0, -40.0, 0.3)
    states = rng.uniform(-14e3, 14e3, (5000, 4))
    got = model.evaluate(pose, states)
    dx, dy = states[:, 0] - pose.x, states[:, 2] - pose.y
    r = np.hypot(dx, dy)
    body = np.arctan2(dy, dx) - pose.heading
    inside = np.abs(np.angle(np.exp(1j * (body - math.pi)))) <= math.radians(65) / 2
    on_land = island.contains(np.column_stack([states[:, 0], states[:, 2]]))
    expected = 0.9 * bands(r) * radar(r) * np.where(inside, 0.0, 1.0) * horizon(r) * ~on_land
    np.testing.assert_allclose(got, expected, rtol=1e-12, atol=0)
    assert np.count_nonzero((got > 0) & (got < 0.9 * 0.97 - 1e-3)) > 1000  # the radar shapes it


@pytest.mark.parametrize("component", [
    RadarEquation(reference_snr=13.0, reference_range=1500.0, false_alarm_probability=1e-6,
                  swerling=2, pulses=8, loss=2.5),
    RadarHorizon(antenna_height=25.0, target_height=3.0, k=1.2),
])
def test_components_serialise_exactly(component):
    assert pickle.loads(pickle.dumps(component)) == component
    yaml = YAML(typ="safe")
    back = yaml.load(yaml.dumps(component))
    assert back == component
    r = np.linspace(0.0, 40e3, 101)
    np.testing.assert_array_equal(back(r), component(r))


def _direct_horizon(antenna, target, k, radius):
    """Over a sphere of radius kR, the arc along the surface from the antenna's foot to the
    target's foot at which the straight line between them grazes the sphere."""
    big = k * radius
    return big * (math.acos(big / (big + antenna)) + math.acos(big / (big + target)))


def test_the_horizon_is_the_spherical_earths_within_two_hundredths_of_a_percent():
    rng = np.random.default_rng(3)
    for antenna, target, k in zip(rng.uniform(0, 1000, 200), rng.uniform(0, 1000, 200),
                                  rng.uniform(0.5, 2.0, 200)):
        horizon = RadarHorizon(antenna_height=antenna, target_height=target, k=k)
        direct = _direct_horizon(antenna, target, k, ctxmodels.horizon.EARTH_RADIUS)
        assert horizon.range == pytest.approx(direct, rel=2e-4)
        assert horizon([0.998 * direct, 1.002 * direct]).tolist() == [1.0, 0.0]
    standard = RadarHorizon(antenna_height=20.0, target_height=5.0)  # 4/3 Earth
    assert standard.range == pytest.approx(18_433 + 9_217, abs=5)
    assert standard([standard.range])[0] == 1.0  # the edge is visible


@pytest.mark.parametrize("kwargs, argument, kind", [
    ({"reference_snr": float("nan")}, "reference_snr", ArgumentError),
    ({"reference_range": 0.0}, "reference_range", ArgumentError),
    ({"false_alarm_probability": 1.0}, "false_alarm_probability", ArgumentError),
    ({"false_alarm_probability": 0.6}, "false_alarm_probability", ArgumentError),
    ({"reference_range": 1e-200}, "reference_range", ArgumentError),
    ({"reference_snr": 10**400}, "reference_snr", ArgumentError),
    ({"false_alarm_probability": 0.0}, "false_alarm_probability", ArgumentError),
    ({"false_alarm_probability": -0.1}, "false_alarm_probability", ArgumentError),
    ({"swerling": 5}, "swerling", ArgumentError),
    ({"swerling": 1.5}, "swerling", ArgumentTypeError),
    ({"pulses": 0}, "pulses", ArgumentError),
    ({"pulses": 5000}, "pulses", ArgumentError),
    ({"loss": -1.0}, "loss", ArgumentError),
    ({"reference_snr": "13"}, "reference_snr", ArgumentTypeError),
])
def test_bad_radar_parameters_name_their_argument(kwargs, argument, kind):
    args = {"reference_snr": 13.0, "reference_range": 1000.0, "false_alarm_probability": 1e-6,
            **kwargs}
    with pytest.raises(kind) as info:
        RadarEquation(**args)
    assert info.value.argument == argument, str(info.value)


@pytest.mark.parametrize("kwargs, argument", [
    ({"antenna_height": -1.0}, "antenna_height"),
    ({"target_height": -0.5}, "target_height"),
    ({"antenna_height": float("nan")}, "antenna_height"),
    ({"k": 0.0}, "k"),
    ({"k": -4 / 3}, "k"),
    ({"earth_radius": 0.0}, "earth_radius"),
    ({"earth_radius": 1e308, "k": 1e10}, "earth_radius"),
    ({"antenna_height": 1.7e308}, "antenna_height"),
    ({"target_height": 1.7e308}, "target_height"),
    ({"k": 10**400}, "k"),
])
def test_bad_horizon_parameters_name_their_argument(kwargs, argument):
    with pytest.raises(ArgumentError) as info:
        RadarHorizon(**{"antenna_height": 10.0, **kwargs})
    assert info.value.argument == argument, str(info.value)


@pytest.mark.parametrize("ranges, kind", [
    ("1500", ArgumentTypeError), ([[1.0, 2.0], [3.0]], ArgumentTypeError), (None, ArgumentTypeError),
    (np.zeros((2, 2)), ArgumentError), ([-1.0], ArgumentError), (-np.inf, ArgumentError),
])
def test_bad_ranges_are_named(ranges, kind):
    radar = RadarEquation(reference_snr=13.0, reference_range=1000.0, false_alarm_probability=1e-6)
    horizon = RadarHorizon(antenna_height=10.0)
    for call in (radar, radar.snr, horizon):
        with pytest.raises(kind) as info:
            call(ranges)
        assert info.value.argument == "ranges", str(info.value)
