"""Each kind of core error arrives as its own class of :mod:`ctxmodels.errors`, with the
argument (and where it applies, the row, polygon and ring) as attributes, so that callers
react to the error without reading its text; the classes pickle with their attributes."""
import datetime
import pickle

import numpy as np
import pytest

import ctxmodels
from ctxmodels import _core, errors
from ctxmodels.errors import (ArgumentError, ArgumentTypeError, InfeasibleAssignmentError,
                              InvalidLandError, NonFiniteError, NotPositiveDefiniteError,
                              ShapeError)

SQUARE = np.array([[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]])


def _raised(call):
    with pytest.raises(ArgumentError) as info:
        call()
    return info.value


def test_the_classes_are_value_errors_exported_at_the_top():
    for cls in (ArgumentError, ShapeError, NonFiniteError, InvalidLandError,
                NotPositiveDefiniteError, InfeasibleAssignmentError):
        assert issubclass(cls, ValueError)
        assert getattr(ctxmodels, cls.__name__) is cls
    assert issubclass(ArgumentTypeError, TypeError) and not issubclass(ArgumentTypeError, ValueError)
    assert set(errors.__all__) - {"argument_error"} <= set(ctxmodels.__all__)


def test_a_core_value_error_names_its_argument_as_an_attribute():
    err = _raised(lambda: _core.RangeBands([2.0, 1.0], [0.1, 0.2, 0.3], [False, False]))
    assert type(err) is ArgumentError and err.argument == "edges"
    assert str(err) == f"edges: {err.detail}"


def test_a_core_shape_error_is_a_shape_error():
    err = _raised(lambda: _core.MeasurementModel.linear(np.eye(2, 4), np.eye(3)))
    assert type(err) is ShapeError and err.argument == "noise_covar"
    assert "(2, 2)" in err.detail


def test_a_non_finite_row_is_named_by_index():
    bands = _core.RangeBands([1.0], [0.9, 0.1], [False])
    err = _raised(lambda: bands.at(np.array([0.5, 2.0, np.nan, np.nan])))
    assert type(err) is NonFiniteError and (err.argument, err.row) == ("ranges", 2)
    assert str(err).startswith("ranges: row 2 is not finite")


def test_a_ring_fault_says_which_polygon_and_ring_and_what_is_wrong_without_where():
    bad = SQUARE.copy()
    bad[2, 0] = np.nan
    hole = np.array([[2.0, 2.0], [4.0, 2.0], [4.0, 4.0], [2.0, 4.0]])
    polygons = [{"shell": SQUARE + 100.0, "holes": []},
                {"shell": SQUARE * 3, "holes": [hole, bad]}]
    err = _raised(lambda: ctxmodels.LandMask(polygons=polygons))
    assert type(err) is InvalidLandError and err.argument == "polygons"
    assert (err.polygon, err.ring, err.ring_name) == (1, 2, "hole 1")
    assert err.problem.startswith("vertex 2 is not finite")
    assert str(err) == f"polygons: polygon 1 hole 1: {err.problem}"


def test_a_polygon_fault_has_no_ring_and_its_detail_names_the_rings():
    outside = np.array([[20.0, 20.0], [21.0, 20.0], [21.0, 21.0]])
    err = _raised(lambda: ctxmodels.LandMask(polygons=[{"shell": SQUARE, "holes": [outside]}]))
    assert type(err) is InvalidLandError
    assert (err.polygon, err.ring, err.ring_name) == (0, None, None)
    assert err.detail == "polygon 0 hole 0 lies outside its shell"


def test_the_python_layer_raises_the_same_classes():
    detection = ctxmodels.DetectionProbabilityModel(factors=(ctxmodels.RangeBands(edges=(5.0,),
                                                                                  values=(0.9, 0.1)),))
    pose = ctxmodels.Pose(0.0, 0.0, 0.0)
    err = _raised(lambda: detection.evaluate(pose, np.zeros((3, 4)), out=np.empty(2)))
    assert type(err) is ShapeError and err.argument == "out"
    with pytest.raises(ArgumentTypeError) as info:
        detection.evaluate(pose, "not states")
    assert info.value.argument == "states"


def test_a_context_names_the_callers_argument_by_the_attribute():
    sensor = ctxmodels.SensorModel(
        detection=ctxmodels.DetectionProbabilityModel(factors=()),
        clutter=ctxmodels.ClutterDensityModel(factors=[ctxmodels.RangeBands(edges=(1.0,),
                                                                            values=(1e-6, 1e-6))]))
    context = sensor.context(ctxmodels.Pose(0.0, 0.0, 0.0), datetime.datetime(2026, 1, 1))
    with pytest.raises(ArgumentError) as info:
        context.prob_detection_array(np.zeros((2, 1)))  # the model reads x, y at (0, 2)
    assert info.value.argument == "means", str(info.value)


@pytest.mark.parametrize("error", [
    ArgumentError("a", "is wrong"),
    ArgumentTypeError("a", "is no number"),
    ShapeError("a", "has 3 columns"),
    NonFiniteError("a", "row 4 is not finite (NaN)", 4),
    InvalidLandError("polygons", "polygon 1 shell: too small", 1, 0, "too small"),
    NotPositiveDefiniteError("covars", "track 0"),
    InfeasibleAssignmentError("cost", "row 1"),
])
def test_errors_pickle_with_their_attributes_and_can_be_renamed(error):
    back = pickle.loads(pickle.dumps(error))
    assert type(back) is type(error) and str(back) == str(error)
    assert vars(back) == vars(error)
    renamed = error.renamed("outer")
    assert type(renamed) is type(error) and renamed.argument == "outer"
    assert str(renamed) == "outer: " + error.detail
    assert renamed.args[1:] == error.args[1:]


def test_argument_error_keeps_the_kind_of_its_cause():
    assert type(errors.argument_error("x", "bad", TypeError("t"))) is ArgumentTypeError
    assert type(errors.argument_error("x", "bad", KeyError("k"))) is ArgumentError
