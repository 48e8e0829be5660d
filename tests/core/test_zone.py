"""Zone: a value inside a set of polygons, another outside, against Shapely's ``covers``
(a point on the boundary is inside), in a clutter model, and its errors."""
import numpy as np
import pytest
import shapely

from ctxmodels import ClutterDensityModel, LandMask, Zone
from ctxmodels.errors import ArgumentError, ArgumentTypeError

HARBOUR = [(200.0, 100.0), (500.0, 100.0), (500.0, 350.0), (200.0, 350.0)]


def test_zone_is_shapelys_cover():
    rng = np.random.default_rng(5)
    points = np.vstack([rng.uniform(0, 700, (2000, 2)), [[200.0, 200.0], [500.0, 350.0]]])
    zone = Zone(polygons=LandMask(polygons=[HARBOUR]), inside=10.0, outside=0.5)
    expected = np.where(shapely.covers(shapely.Polygon(HARBOUR), shapely.points(points)), 10.0, 0.5)
    np.testing.assert_array_equal(zone(points), expected)
    clutter = ClutterDensityModel(factors=[2.0, zone])
    np.testing.assert_array_equal(clutter.evaluate((0.0, 0.0, 0.0), points), 2.0 * expected)


@pytest.mark.parametrize("kwargs, argument, kind", [
    ({"inside": -1.0}, "inside", ArgumentError),
    ({"inside": float("nan")}, "inside", ArgumentError),
    ({"outside": float("inf")}, "outside", ArgumentError),
    ({"inside": "10"}, "inside", ArgumentTypeError),
    ({"polygons": HARBOUR}, "polygons", ArgumentTypeError),
])
def test_bad_zones_name_their_argument(kwargs, argument, kind):
    with pytest.raises(kind) as info:
        Zone(**{"polygons": LandMask(polygons=[HARBOUR]), "inside": 10.0, **kwargs})
    assert info.value.argument == argument, str(info.value)


def test_a_clutter_model_refuses_a_zone_of_zero_density():
    with pytest.raises(ArgumentError) as info:
        ClutterDensityModel(factors=[Zone(polygons=LandMask(polygons=[HARBOUR]), inside=0.0)])
    assert info.value.argument == "factors"
