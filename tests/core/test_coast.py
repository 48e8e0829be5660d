"""The coastal clutter band (``CoastalClutter``) against shapely on random points around an
archipelago with a lake (an island with a hole): distance to the coastline, and which
shore the sensor sees (sight line to the nearest coast point, stopped 1 m short); its use
as a λ factor; named errors; printing, pickling and YAML."""
import pickle

import numpy as np
import pytest
from shapely.geometry import LineString, MultiPolygon, Point, Polygon
from shapely.ops import nearest_points
from stonesoup.serialise import YAML

from ctxmodels import ClutterDensityModel, CoastalClutter, LandMask, Pose, RangeBands

ISLANDS = MultiPolygon([
    Polygon([(400, 100), (560, 140), (600, 320), (450, 380), (380, 250)]),
    Polygon([(-700, -300), (-350, -330), (-300, -50), (-500, 80), (-720, -60)],
            holes=[[(-600, -200), (-420, -220), (-400, -80), (-560, -60)]]),
    Polygon([(100, -800), (260, -760), (220, -600), (80, -640)]),
])
WIDTH, INSIDE = 30.0, 50.0


def _reference(points, sensor, seen_only):
    """The band by shapely: distance to the boundary ≤ width and, with ``seen_only``, the
    sight line to the nearest boundary point (1 m short of it) crossing no land. Points
    within 1e-6 m of the band's edge are left out (None): a rounding apart."""
    boundary = ISLANDS.boundary
    expected = []
    for x, y in points:
        point = Point(x, y)
        distance = boundary.distance(point)
        if abs(distance - WIDTH) < 1e-6:
            expected.append(None)
            continue
        inside = distance <= WIDTH
        if inside and seen_only:
            q = np.asarray(nearest_points(boundary, point)[0].coords[0])
            away = np.asarray(sensor) - q
            short = q + away / np.hypot(*away) * 1.0
            inside = not LineString([sensor, short]).intersects(ISLANDS)
        expected.append(INSIDE if inside else 1.0)
    return expected


@pytest.mark.parametrize("seen_only", [False, True])
def test_band_matches_shapely_on_random_points(seen_only):
    rng = np.random.default_rng(21)
    # most points near the coasts, where the answer changes; the rest anywhere
    coast = np.array([ISLANDS.boundary.interpolate(d).coords[0]
                      for d in rng.uniform(0, ISLANDS.boundary.length, 8000)])
    points = np.vstack([coast + rng.normal(0, 25, coast.shape),
                        rng.uniform(-900, 700, (2000, 2))])
    sensor = (0.0, 0.0)
    band = CoastalClutter(land=LandMask(polygons=ISLANDS), width=WIDTH, inside=INSIDE,
                          seen_only=seen_only)
    got = band.evaluate(Pose(x=sensor[0], y=sensor[1]), points)
    expected = _reference(points, sensor, seen_only)
    compared = [(g, e) for g, e in zip(got, expected) if e is not None]
    assert len(compared) >= 9990
    mismatches = [(i, g, e) for i, (g, e) in enumerate(compared) if g != e]
    assert not mismatches, mismatches[:5]
    in_band = sum(g == INSIDE for g, _ in compared)
    # both answers well represented (seen from the origin, about a third of the shore)
    assert (1000 if seen_only else 3000) < in_band < 9000
    if seen_only:
        # the far shores (and the lake's, seen from outside the island) are not in the band
        unseen = band.evaluate(Pose(x=sensor[0], y=sensor[1]), [[610.0, 330.0], [-500.0, -140.0]])
        assert list(unseen) == [1.0, 1.0]


def test_a_clutter_factor_multiplies_the_other_factors():
    land = LandMask(polygons=ISLANDS)
    band = CoastalClutter(land=land, width=WIDTH, inside=INSIDE)
    model = ClutterDensityModel(factors=[RangeBands(edges=(500.0,), values=(1e-3, 1e-2)), band])
    rng = np.random.default_rng(2)
    points = rng.uniform(-900, 700, (1001, 2))  # not a multiple of 4: the kernel's last block
    pose = Pose(x=10.0, y=-20.0, heading=0.3)
    expected = np.where(np.hypot(points[:, 0] - 10, points[:, 1] + 20) < 500, 1e-3, 1e-2) \
        * band.evaluate(pose, points)
    assert model.evaluate(pose, points).tobytes() == expected.tobytes()
    assert (band.evaluate(pose, points) == INSIDE).sum() > 20


@pytest.mark.parametrize("kwargs,argument,error", [
    (dict(width=-1.0), "width", ValueError),
    (dict(width=float("nan")), "width", ValueError),
    (dict(inside=0.0), "inside", ValueError),
    (dict(inside=float("inf")), "inside", ValueError),
    (dict(land="islands"), "land", TypeError),
    (dict(seen_only="yes"), "seen_only", TypeError),
])
def test_bad_configuration_is_named(kwargs, argument, error):
    config = dict(land=LandMask(polygons=ISLANDS), width=WIDTH, inside=INSIDE)
    with pytest.raises(error, match=f"^{argument}: "):
        CoastalClutter(**{**config, **kwargs})


def test_prints_compares_pickles_and_serialises():
    band = CoastalClutter(land=LandMask(polygons=ISLANDS), width=WIDTH, inside=INSIDE)
    assert repr(band).startswith("CoastalClutter(") and "width=30.0" in repr(band)
    points = np.array([[395.0, 100.0], [0.0, 0.0], [90.0, -600.0]])
    for restored in (pickle.loads(pickle.dumps(band)), YAML().load(YAML().dumps(band))):
        assert type(restored) is CoastalClutter
        assert restored.evaluate(Pose(x=0.0, y=0.0), points).tobytes() == \
            band.evaluate(Pose(x=0.0, y=0.0), points).tobytes()
