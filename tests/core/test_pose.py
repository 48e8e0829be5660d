"""A pitched and rolled pose: its rotation is Stone Soup's ``build_rotation_matrix`` of
[roll, pitch, heading], and a model's sectors and elevation sectors read each target's
bearing and elevation in that frame — against NumPy's atan2 of M d, on random factor
stacks, with every other factor the world's; a mounting adds its angles to the
platform's, as Stone Soup adds a sensor's ``rotation_offset``; bad angles are named."""
from __future__ import annotations

import math

import numpy as np
import pytest
from stonesoup.functions import build_rotation_matrix

from ctxmodels import (AngularSector, DetectionProbabilityModel, ElevationSector, Mounting, Pose,
                       RadarHorizon, RangeBands)


def _stone_soup_frame(pose):
    return build_rotation_matrix(np.array([[pose.roll], [pose.pitch], [pose.heading]]))


@pytest.mark.parametrize("seed", range(6))
def test_tilted_sectors_are_numpys_bearings_and_elevations(seed):
    rng = np.random.default_rng(seed)
    pose = Pose(x=rng.uniform(-50, 50), y=rng.uniform(-50, 50), z=rng.uniform(0, 40),
                heading=rng.uniform(-math.pi, math.pi), pitch=rng.uniform(-0.6, 0.6),
                roll=rng.uniform(-0.6, 0.6))
    centre, width = rng.uniform(-math.pi, math.pi), rng.uniform(0.3, 5.5)
    low, high = np.sort(rng.uniform(-1.2, 1.2, 2))
    factors = [0.9, RangeBands(edges=(900.0,), values=(1.0, 0.4)),
               AngularSector(centre=centre, width=width, inside=1.0, outside=0.25),
               ElevationSector(lower=low, upper=high, inside=0.8, outside=0.1),
               RadarHorizon(antenna_height=30.0, target_height=None, earth_radius=2e4)]
    n = 20_000
    states = np.column_stack([rng.uniform(-1500, 1500, n), np.zeros(n),
                              rng.uniform(-1500, 1500, n), np.zeros(n),
                              rng.uniform(-300, 900, n), np.zeros(n)])
    got = DetectionProbabilityModel(factors=factors).evaluate(pose, states, (0, 2, 4))
    d = np.stack([states[:, 0] - pose.x, states[:, 2] - pose.y, states[:, 4] - pose.z])
    sx, sy, sz = _stone_soup_frame(pose) @ d
    bearing = np.arctan2(sy, sx)
    elevation = np.arctan2(sz, np.hypot(sx, sy))
    off = np.angle(np.exp(1j * (bearing - centre)))
    sector = np.where(np.abs(off) <= width / 2, 1.0, 0.25)
    beam = np.where((elevation >= low) & (elevation <= high), 0.8, 0.1)
    slant = np.linalg.norm(d, axis=0)
    bands = np.where(slant <= 900.0, 1.0, 0.4)
    reach = 2 * 4 / 3 * 2e4
    seen = np.hypot(d[0], d[1]) <= math.sqrt(reach * 30.0) + np.sqrt(reach * np.maximum(
        states[:, 4], 0.0))
    want = 0.9 * bands * sector * beam * seen
    clear = ((np.abs(np.abs(off) - width / 2) > 1e-9) & (np.abs(elevation - low) > 1e-9)
             & (np.abs(elevation - high) > 1e-9) & (np.abs(slant - 900.0) > 1e-6))
    assert clear.mean() > 0.999
    np.testing.assert_allclose(got[clear], want[clear], rtol=1e-13)
    # the tilt is read: level, the same targets differ
    level = Pose(x=pose.x, y=pose.y, z=pose.z, heading=pose.heading)
    flat = DetectionProbabilityModel(factors=factors).evaluate(level, states, (0, 2, 4))
    assert np.mean(flat != got) > 0.01


def test_a_pitched_boresight_looks_up():
    beam = DetectionProbabilityModel(factors=[ElevationSector(lower=-0.05, upper=0.05)])
    up = Pose(x=0.0, y=0.0, pitch=0.3)
    # 1 km ahead at 0.3 rad up: on the tilted boresight; at the sea: 0.3 rad below it
    targets = np.array([[1000.0, 0, 0, 0, 1000 * math.tan(0.3), 0], [1000.0, 0, 0, 0, 0.0, 0]])
    assert beam.evaluate(up, targets, (0, 2, 4)).tolist() == [1.0, 0.0]
    # rolled a quarter turn, a left-right fan beam becomes an up-down one
    fan = DetectionProbabilityModel(factors=[AngularSector(centre=0.0, width=0.1, inside=1.0,
                                                           outside=0.0)])
    rolled = Pose(x=0.0, y=0.0, roll=math.pi / 2)
    above = np.array([[1000.0, 0, 0, 0, 300.0, 0], [1000.0, 0, 300.0, 0, 0.0, 0]])
    assert fan.evaluate(rolled, above, (0, 2, 4)).tolist() == [0.0, 1.0]
    assert fan.evaluate(Pose(x=0.0, y=0.0), above, (0, 2, 4)).tolist() == [1.0, 0.0]


def test_a_mounting_adds_its_angles_to_the_platforms():
    platform = Pose(x=10.0, y=5.0, heading=0.5, pitch=0.1, roll=-0.2, vx=3.0)
    sensor = Mounting(forward=2.0, yaw=0.25, pitch=0.05, roll=0.3, up=4.0).apply(platform)
    assert (sensor.pitch, sensor.roll) == pytest.approx((0.15, 0.1))
    assert (sensor.heading, sensor.z, sensor.vx) == pytest.approx((0.75, 4.0, 3.0))
    assert Pose(x=0.0, y=0.0, pitch=0.2).as_tuple() == (0, 0, 0, 0, 0, 0, 0, 0.2, 0)


@pytest.mark.parametrize("make, argument", [
    (lambda: Pose(x=0.0, y=0.0, pitch=float("nan")), "pitch"),
    (lambda: Pose(x=0.0, y=0.0, roll=float("inf")), "roll"),
    (lambda: Mounting(pitch="up"), "pitch"),
    (lambda: Mounting(roll=float("nan")), "roll"),
    (lambda: Mounting(pitch=1e308).apply(Pose(x=0.0, y=0.0, pitch=1e308)), "mounting"),
])
def test_bad_angles_are_named(make, argument):
    with pytest.raises((TypeError, ValueError)) as info:
        make()
    assert str(info.value).startswith(argument), str(info.value)
