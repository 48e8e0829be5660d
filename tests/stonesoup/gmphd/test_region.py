"""Surveillance regions (``CircularRegion``, ``PoseCentredRegion``) refuse a radius that is not a
positive number, a bad centre and points of the wrong shape, naming the argument; a radius
of any real number type is kept as a float."""
from __future__ import annotations

import datetime

import numpy as np
import pytest

from ctxmodels.stonesoup.gmphd.region import CircularRegion, PoseCentredRegion
from ...hostile import _navigation, names_argument, T0

NAN, INF = float("nan"), float("inf")


BAD_RADII = [True, False, np.bool_(True), "1", "", None, NAN, INF, -INF, 0, 0.0, -1, -1e-300,
             np.float64(NAN), np.float32(-2), np.int64(0), [1.0], np.array([1.0]), np.array(1.0),
             1 + 0j, datetime.timedelta(seconds=1), object()]


@pytest.mark.parametrize("radius", BAD_RADII, ids=repr)
def test_pose_centred_region_refuses_a_radius_that_is_not_a_positive_number(radius):
    error = (ValueError, TypeError)
    names_argument(lambda: PoseCentredRegion(pose_source=_navigation(), radius=radius), error,
                   "radius")
    names_argument(lambda: CircularRegion(centre=(0.0, 0.0), radius=radius), error, "radius")


@pytest.mark.parametrize("radius", [1, 1.5, np.float32(2.0), np.int64(3), np.uint8(4), 1e300,
                                    5e-324], ids=repr)
def test_region_radius_of_any_real_number_type_is_kept_as_a_float(radius):
    region = PoseCentredRegion(pose_source=_navigation(), radius=radius)
    assert type(region.radius) is float and region.radius == float(radius)
    assert region.at(T0).radius == float(radius)


BAD_CENTRES = [None, 5, "12", (True, 0.0), ("1", "2"), (0.0,), (0.0, 1.0, 2.0), (NAN, 0.0),
               (0.0, INF), np.array([[1.0, 2.0], [3.0, 4.0]]), {"x": 0, "y": 0}, (None, 0.0),
               (1 + 1j, 0.0)]


@pytest.mark.parametrize("centre", BAD_CENTRES, ids=repr)
def test_circular_region_refuses_a_bad_centre(centre):
    names_argument(lambda: CircularRegion(centre=centre, radius=1.0), (ValueError, TypeError),
                   "centre")


BAD_POINTS = [np.zeros((4, 3)), np.zeros((1, 1)), np.zeros(4), np.zeros(3), np.zeros((2, 2, 2)),
              [[0.0, 0.0], [1.0]], [["a", "b"]], "0 0", {"x": 0}, np.array([[True, False]]),
              np.array([[1j, 0]]), [[None, None]]]


@pytest.mark.parametrize("points", BAD_POINTS, ids=lambda p: repr(p)[:40])
def test_circular_region_contains_names_points_of_the_wrong_shape(points):
    region = CircularRegion(centre=(0.0, 0.0), radius=2.0)
    names_argument(lambda: region.contains(points), (ValueError, TypeError), "points")


def test_circular_region_contains_reads_rows_and_one_pair():
    region = CircularRegion(centre=(1.0, 1.0), radius=2.0)
    np.testing.assert_array_equal(region.contains([[1.0, 3.0], [1.0, 3.0001], [NAN, 0.0]]),
                                  [True, False, False])
    np.testing.assert_array_equal(region.contains((1.0, 1.0)), [True])
    np.testing.assert_array_equal(region.contains(np.array([[3, 1]], dtype=np.int32)), [True])
    assert region.contains(np.empty((0, 2))).shape == (0,)
    assert region.contains([]).shape == (0,)
