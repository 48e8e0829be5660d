"""Cases found by the hardening fuzzers (tests/core/test_errors_random.py, rust/fuzz.rs), kept as
minimal reproducers. Each was a strict xfail asserting the *correct* behaviour until fixed:
it fails loudly (XPASS → error) once the bug is fixed, so the marker must then be removed.
"""
import datetime
import math

import numpy as np
import pytest

from ctxmodels import (ClutterDensityModel, DetectionProbabilityModel, NavigationTrack, Pose,
                       RangeBands, SensorModel)
from ..hostile import names_argument

POSE = Pose(x=0.0, y=0.0, heading=0.0)


def test_clutter_density_product_that_underflows_is_not_silently_zero():
    model = ClutterDensityModel(factors=[1e-200, 1e-200])
    try:
        lam = model.evaluate(POSE, np.zeros((2, 2)))
    except ValueError as err:
        assert str(err).startswith("factors:")
    else:
        assert np.all(lam > 0), lam


def test_clutter_density_product_that_overflows_names_factors():
    model = ClutterDensityModel(factors=[1e200, 1e200])
    names_argument(lambda: model.evaluate(POSE, np.zeros((2, 2))), ValueError, "factors")


@pytest.mark.parametrize("flags", [None, 3])
def test_range_bands_non_iterable_upper_owns_names_it(flags):
    names_argument(lambda: RangeBands(edges=[50.0], values=[1.0, 0.0], upper_owns=flags),
                   TypeError, "upper_owns")


@pytest.mark.parametrize("flags", [["False"], [None], [2.5]])
def test_range_bands_non_bool_upper_owns_are_refused(flags):
    names_argument(lambda: RangeBands(edges=[50.0], values=[1.0, 0.0], upper_owns=flags),
                   TypeError, "upper_owns")


def test_range_bands_bool_flags_control_the_edge():
    """The working counterpart of the xfail above: real bools decide who owns r = 50."""
    assert RangeBands(edges=[50.0], values=[1.0, 0.0], upper_owns=[True])([50.0])[0] == 0.0
    assert RangeBands(edges=[50.0], values=[1.0, 0.0], upper_owns=[False])([50.0])[0] == 1.0


@pytest.mark.parametrize("mapping", [None, 2])
def test_sensor_model_non_iterable_position_mapping_names_it(mapping):
    names_argument(lambda: SensorModel(detection=DetectionProbabilityModel(factors=[0.5]),
                                       clutter=ClutterDensityModel(factors=[1e-3]),
                                       position_mapping=mapping),
                   TypeError, "position_mapping")


@pytest.mark.parametrize("metadata", [0.0, 3])
def test_scalar_metadata_names_metadata(metadata):
    model = ClutterDensityModel(factors=[1e-3])
    names_argument(lambda: model.evaluate(POSE, np.zeros((1, 2)), metadata), TypeError, "metadata")


@pytest.mark.parametrize("headings", [[0j], np.array([1 + 2j])])
def test_complex_navigation_headings_name_headings(headings):
    stamps = [datetime.datetime(2024, 1, 1)]
    names_argument(lambda: NavigationTrack(timestamps=stamps, positions=[[0.0, 0.0]], headings=headings),
                   TypeError, "headings")


def test_tiny_but_representable_lambda_is_kept():
    """Guard for the fix of the underflow: one small factor must stay exact."""
    lam = ClutterDensityModel(factors=[1e-200]).evaluate(POSE, np.zeros((1, 2)))
    assert lam[0] == 1e-200 and math.isfinite(lam[0])


# --- range bands' flags through Stone Soup's YAML -----------------------------------------------
@pytest.mark.parametrize("flags", [np.bool_(True), np.bool_(False), (np.bool_(True),),
                                   [np.bool_(False)], np.array([True]), (True,), False,
                                   np.array(True)], ids=repr)
def test_range_bands_with_numpy_booleans_survive_stone_soups_yaml(flags):
    from stonesoup.serialise import YAML
    bands = RangeBands(edges=(50.0,), values=(1.0, 0.0), upper_owns=flags)
    owners = bands.upper_owns
    assert owners in (True, False) and type(owners) is bool or \
        type(owners) is tuple and all(type(f) is bool for f in owners)
    back = YAML().load(YAML().dumps(bands))
    assert back == bands
    assert back([50.0])[0] == bands([50.0])[0] == (0.0 if bool(np.ravel(flags)[0]) else 1.0)


@pytest.mark.parametrize("flags", [np.array([[True]]), np.array([1]), [np.int64(1)],
                                   np.array(["True"])], ids=repr)
def test_range_bands_refuse_non_boolean_flag_arrays(flags):
    names_argument(lambda: RangeBands(edges=(50.0,), values=(1.0, 0.0), upper_owns=flags),
                   TypeError, "upper_owns")
