"""Bad input gets a clear Python exception of the right type whose message names the
argument; awkward-but-valid input (other dtypes, non-contiguous views, empty arrays) is
accepted and gives the right answer."""
import datetime
import math

import numpy as np
import pytest
from stonesoup.types.array import StateVector
from stonesoup.types.detection import Detection

from ctxmodels import (AngularSector, ClutterDensityModel, DetectionProbabilityModel, LandMask,
                       LineOfSight, MetadataThreshold, Mounting, NavigationTrack, Pose, RangeBands,
                       SensorModel, _core)

POSE = Pose(x=3.0, y=-4.0, heading=0.6)
RADAR = DetectionProbabilityModel(factors=[
    RangeBands(edges=(50, 1612), values=(0, 0.4, 0), upper_owns=(False, True)),
    AngularSector.blind(math.pi, math.radians(65))])
CLUTTER = ClutterDensityModel(factors=[
    RangeBands(edges=(1000,), values=(1e-3, 1e-2)),
    MetadataThreshold(key="area", threshold=10, below=1e-1, at_or_above=1e-3)])
SENSOR = SensorModel(detection=RADAR, clutter=CLUTTER)
SQUARE = np.array([[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]])
RNG = np.random.default_rng(17)
STATES = np.column_stack([RNG.uniform(-2000, 2000, 3000), RNG.normal(0, 5, 3000),
                          RNG.uniform(-2000, 2000, 3000), RNG.normal(0, 5, 3000)])
COVARS = np.tile(np.diag([900.0, 4.0, 400.0, 4.0]), (3000, 1, 1))


def raises(exception, argument, call, *args, **kwargs):
    """`call` raises `exception` and the message starts by naming `argument`."""
    with pytest.raises(exception) as info:
        call(*args, **kwargs)
    assert argument in str(info.value), str(info.value)
    return str(info.value)


# --- shapes -----------------------------------------------------------------------------------
@pytest.mark.parametrize("states", [np.zeros(4), np.zeros((2, 4, 1)), np.float64(3.0), [[1.0, 2.0], [3.0]]])
def test_states_of_the_wrong_shape(states):
    raises((ValueError, TypeError), "states", RADAR.evaluate, POSE, states)


def test_position_mapping_out_of_range_or_invalid():
    raises(ValueError, "position_mapping", RADAR.evaluate, POSE, np.zeros((2, 4)), (0, 4))
    raises(ValueError, "position_mapping", RADAR.evaluate, POSE, np.zeros((2, 2)), (0, 2))
    raises(ValueError, "position_mapping", RADAR.evaluate, POSE, np.zeros((2, 4)), (0, -1))
    raises(ValueError, "position_mapping", RADAR.evaluate, POSE, np.zeros((2, 4)), (1, 1))
    raises(ValueError, "position_mapping", RADAR.expected, POSE, np.zeros((2, 4)), np.zeros((2, 4, 4)),
           (5, 0))
    for mapping in [(0, 0), (0, -2), (0, 1, 1), (0, 1, 2, 3)]:
        raises(ValueError, "position_mapping", SensorModel, detection=RADAR, clutter=CLUTTER,
               position_mapping=mapping)
    context = SensorModel(detection=RADAR, clutter=CLUTTER, position_mapping=(0, 6)).context(POSE)
    message = raises(ValueError, "means", context.prob_detection_array, np.zeros((3, 4)))
    assert "(0, 6)" in message


@pytest.mark.parametrize("covars, argument", [
    (np.zeros((3, 3, 3)), "covars"), (np.zeros((2, 4, 4)), "covars"), (np.zeros((4, 4)), "covars"),
    (np.zeros((3, 4)), "covars")])
def test_covariances_of_the_wrong_shape(covars, argument):
    raises(ValueError, argument, RADAR.expected, POSE, np.zeros((3, 4)), covars)


def test_clutter_positions_and_metadata_of_the_wrong_shape():
    raises(ValueError, "positions", CLUTTER.evaluate, POSE, np.zeros((3, 4)), np.zeros((3, 1)))
    # (3 columns: positions with heights, read as slant ranges)
    raises(ValueError, "positions", CLUTTER.evaluate, POSE, np.zeros(2), np.zeros((1, 1)))
    raises(ValueError, "metadata", CLUTTER.evaluate, POSE, np.zeros((3, 2)), np.zeros((3, 2)))
    raises(ValueError, "metadata", CLUTTER.evaluate, POSE, np.zeros((3, 2)), [{"area": 1.0}] * 2)
    raises(TypeError, "metadata", CLUTTER.evaluate, POSE, np.zeros((2, 2)), [{"area": 1.0}, {"area": "big"}])
    raises(ValueError, "points", LandMask(polygons=[SQUARE]).contains, np.zeros((3, 3)))
    visible = LineOfSight(land=LandMask(polygons=[SQUARE])).visible
    raises(ValueError, "targets", visible, (20.0, 20.0), np.zeros((3, 1)))
    raises(ValueError, "sensor", visible, (20.0, np.nan), np.zeros((3, 2)))
    raises(ValueError, "sensor", visible, (1.0, 2.0, 3.0), np.zeros((3, 2)))


# --- dtypes and memory layout -------------------------------------------------------------------
@pytest.mark.parametrize("dtype", [object, complex, np.complex64, "U3", "datetime64[s]"])
def test_non_numeric_or_complex_states_are_type_errors(dtype):
    states = np.zeros((2, 4)).astype(dtype)
    raises(TypeError, "states", RADAR.evaluate, POSE, states)
    raises(TypeError, "means", RADAR.expected, POSE, states, np.zeros((2, 4, 4)))
    raises(TypeError, "positions", CLUTTER.evaluate, POSE, states[:, :2], np.zeros((2, 1)))


@pytest.mark.parametrize("dtype", [np.float32, np.int64, np.int32, np.int16, np.uint16, np.float16])
def test_other_real_dtypes_are_converted(dtype):
    kind = np.dtype(dtype).kind
    values = np.abs(np.round(STATES[:500])) if kind == "u" else np.round(STATES[:500]) if kind == "i" \
        else STATES[:500]
    states = values.astype(dtype)
    expected = RADAR.evaluate(POSE, states.astype(np.float64))
    np.testing.assert_array_equal(RADAR.evaluate(POSE, states), expected)
    assert expected.dtype == np.float64


def test_non_contiguous_inputs_are_converted_and_evaluated_correctly():
    expected_pd = RADAR.evaluate(POSE, STATES)
    expected_e = RADAR.expected(POSE, STATES, COVARS, (0, 2), "cubature")
    fortran = np.asfortranarray(STATES)
    strided = np.zeros((3000, 8))
    strided[:, ::2] = STATES
    reversed_rows = STATES[::-1].copy()[::-1]
    for view in (fortran, strided[:, ::2], reversed_rows):
        assert not view.flags.c_contiguous
        np.testing.assert_array_equal(RADAR.evaluate(POSE, view), expected_pd)
        np.testing.assert_array_equal(RADAR.expected(POSE, view, COVARS, (0, 2), "cubature"), expected_e)
    transposed_covars = np.ascontiguousarray(COVARS.transpose(0, 2, 1)).transpose(0, 2, 1)
    assert not transposed_covars.flags.c_contiguous
    np.testing.assert_array_equal(RADAR.expected(POSE, STATES, transposed_covars, (0, 2), "cubature"),
                                  expected_e)
    positions, metadata = STATES[:, 0::2], np.asfortranarray(RNG.uniform(0, 20, (3000, 1)))
    np.testing.assert_array_equal(CLUTTER.evaluate(POSE, positions, metadata),
                                  CLUTTER.evaluate(POSE, positions.copy(), metadata.copy()))
    land = LandMask(polygons=[np.asfortranarray(SQUARE * 100)])
    np.testing.assert_array_equal(land.contains(positions), land.contains(positions.copy()))
    assert land.contains(positions).any()
    ranges = STATES[::3, 0]
    np.testing.assert_array_equal(RangeBands(edges=(50, 80), values=(0.95, 0.2, 0.0))(np.abs(ranges)),
                                  RangeBands(edges=(50, 80), values=(0.95, 0.2, 0.0))(np.abs(ranges).copy()))


def test_raw_core_refuses_arrays_that_are_not_c_contiguous():
    core = RADAR._compiled()
    fortran = np.asfortranarray(STATES[:10])
    try:
        got = core.evaluate(POSE.as_tuple(), fortran, (0, 2), None)
    except ValueError as err:
        assert "states" in str(err)
    else:
        np.testing.assert_array_equal(got, core.evaluate(POSE.as_tuple(), STATES[:10], (0, 2), None))


# --- non-finite states ----------------------------------------------------------------------------
@pytest.mark.parametrize("n, bad_rows", [(10, [3, 7]), (5000, [4321]), (70_000, [50_001, 60_000, 65_000]),
                                         (70_000, [69_999])])
def test_non_finite_positions_name_states_and_the_first_bad_row(n, bad_rows):
    states = np.ones((n, 4))
    for k, row in enumerate(bad_rows):
        states[row, 2 if k % 2 else 0] = [np.nan, np.inf, -np.inf][k % 3]
    for _ in range(3):  # the parallel path must report the same row every time
        message = raises(ValueError, "states", RADAR.evaluate, POSE, states)
        assert f"row {bad_rows[0]}" in message
    message = raises(ValueError, "means", RADAR.expected, POSE, states, np.tile(np.eye(4), (n, 1, 1)))
    assert f"row {bad_rows[0]}" in message
    message = raises(ValueError, "means", SENSOR.context(POSE).prob_detection_array, states)
    assert f"row {bad_rows[0]}" in message


def test_non_finite_values_outside_the_position_columns_are_ignored():
    states = STATES.copy()
    states[:, 1] = np.nan
    states[:, 3] = np.inf
    np.testing.assert_array_equal(RADAR.evaluate(POSE, states), RADAR.evaluate(POSE, STATES))


def test_bad_covariances_name_covars_and_the_first_bad_row():
    n = 70_000
    means = np.ones((n, 4))
    asymmetric = np.eye(4)
    asymmetric[0, 2] = 5.0
    for bad in (-np.eye(4), np.full((4, 4), np.nan), asymmetric):
        covars = np.tile(np.eye(4), (n, 1, 1))
        covars[40_000] = bad
        covars[69_000] = -np.eye(4)
        assert "row 40000" in raises(ValueError, "covars", RADAR.expected, POSE, means, covars)


def test_non_finite_clutter_inputs_name_their_argument_and_row():
    n = 70_000
    positions, metadata = np.zeros((n, 2)), np.ones((n, 1))
    positions[40_000, 1] = np.nan
    assert "row 40000" in raises(ValueError, "positions", CLUTTER.evaluate, POSE, positions, metadata)
    metadata[33_000] = np.nan  # missing, and the rule has no `missing` value
    assert "row 33000" in raises(ValueError, "metadata", CLUTTER.evaluate, POSE, positions, metadata)
    # A missing key in a detection's metadata mapping: the same argument, the detection and
    # the key named.
    message = raises(ValueError, "metadata", CLUTTER.evaluate, POSE, np.zeros((2, 2)), [{"area": 1.0}, {}])
    assert "detection 1 has no 'area'" in message


def test_clutter_reports_the_first_bad_row_whatever_the_problem():
    positions, metadata = np.zeros((20, 2)), np.ones((20, 1))
    metadata[5] = np.nan
    positions[10, 0] = np.nan
    assert "row 5" in raises(ValueError, "metadata", CLUTTER.evaluate, POSE, positions, metadata)


def test_non_finite_poses_and_mountings():
    raises(ValueError, "x", Pose, x=np.nan, y=0.0)
    raises(ValueError, "heading", Pose, x=0.0, y=0.0, heading=np.inf)
    raises(TypeError, "y", Pose, x=0.0, y="north")
    raises(ValueError, "forward", Mounting, forward=np.nan)
    raises(ValueError, "yaw", Mounting, yaw=-np.inf)
    raises(TypeError, "pose", SENSOR.context, (1.0, 2.0))
    raises(ValueError, "pose", _core.mount, (0.0, np.nan, 0.0), 1.0, 0.0, 0.0)


# --- configuration ------------------------------------------------------------------------------
@pytest.mark.parametrize("kwargs, exception, argument", [
    (dict(edges=(-1, 5), values=(1, 1, 1)), ValueError, "edges"),
    (dict(edges=(5, 1), values=(1, 1, 1)), ValueError, "edges"),
    (dict(edges=(5, 5), values=(1, 1, 1)), ValueError, "edges"),
    (dict(edges=(np.nan,), values=(1, 1)), ValueError, "edges"),
    (dict(edges=(np.inf,), values=(1, 1)), ValueError, "edges"),
    (dict(edges="50", values=(1, 1)), TypeError, "edges"),
    (dict(edges=(5,), values=(1, 1, 1)), ValueError, "values"),
    (dict(edges=(5,), values=(1,)), ValueError, "values"),
    (dict(edges=(5,), values=(1, np.nan)), ValueError, "values"),
    (dict(edges=(5,), values=(1, "x")), TypeError, "values"),
    (dict(edges=(5,), values=(1, 1), upper_owns=(True, False)), ValueError, "upper_owns"),
])
def test_bad_range_bands(kwargs, exception, argument):
    raises(exception, argument, RangeBands, **kwargs)


@pytest.mark.parametrize("factor", [
    RangeBands(edges=(5,), values=(1.2, 1)), RangeBands(edges=(5,), values=(0.5, -0.1)), -0.1, 1.0001,
    AngularSector(centre=0.0, width=1.0, inside=2.0), AngularSector(centre=0.0, width=1.0, outside=-1.0)])
def test_probabilities_outside_the_unit_interval(factor):
    raises(ValueError, "factors", DetectionProbabilityModel, factors=[0.5, factor])


@pytest.mark.parametrize("factor", [
    0.0, -1e-3, np.inf, RangeBands(edges=(5,), values=(1e-3, 0.0)), RangeBands(edges=(5,), values=(-1, 1)),
    MetadataThreshold(key="area", threshold=1, below=0.0, at_or_above=1),
    MetadataThreshold(key="area", threshold=1, below=1, at_or_above=-2),
    MetadataThreshold(key="area", threshold=1, below=1, at_or_above=1, missing=0.0)])
def test_zero_negative_or_infinite_clutter_densities(factor):
    raises(ValueError, "factors", ClutterDensityModel, factors=[1.0, factor])


def test_wrong_factor_types_name_factors():
    raises(TypeError, "factors", DetectionProbabilityModel,
           factors=[MetadataThreshold(key="area", threshold=1, below=1, at_or_above=1)])
    raises(TypeError, "factors", DetectionProbabilityModel, factors=["0.5"])
    raises(TypeError, "factors", ClutterDensityModel, factors=[AngularSector(centre=0.0, width=1.0)])
    raises(TypeError, "factors", ClutterDensityModel, factors=[LandMask(polygons=[SQUARE])])
    raises(TypeError, "key", MetadataThreshold, key=3, threshold=1, below=1, at_or_above=1)
    raises(ValueError, "threshold", ClutterDensityModel,
           factors=[MetadataThreshold(key="a", threshold=np.nan, below=1, at_or_above=1)])
    raises(TypeError, "land", LineOfSight, land=SQUARE)
    raises(TypeError, "detection", SensorModel, detection=CLUTTER, clutter=CLUTTER)
    raises(TypeError, "clutter", SensorModel, detection=RADAR, clutter=RADAR)
    raises(TypeError, "mounting", SensorModel, detection=RADAR, clutter=CLUTTER, mounting=(1.0, 0.0, 0.0))


@pytest.mark.parametrize("width", [65, 65.0, 180.0, 360.0, 7.0])
def test_degrees_passed_as_width(width):
    message = raises(ValueError, "width", AngularSector, centre=math.pi, width=width)
    assert "radians" in message and "degrees" in message


@pytest.mark.parametrize("kwargs, argument", [
    (dict(centre=math.pi, width=0.0), "width"), (dict(centre=math.pi, width=-0.5), "width"),
    (dict(centre=math.pi, width=np.nan), "width"), (dict(centre=180.0, width=1.0), "centre"),
    (dict(centre=np.nan, width=1.0), "centre"), (dict(centre=0.0, width=1.0, inside=np.nan), "inside")])
def test_bad_sectors(kwargs, argument):
    raises(ValueError, argument, AngularSector, **kwargs)


@pytest.mark.parametrize("polygons, fragment", [
    ([np.array([[0.0, 0.0], [1.0, 1.0]])], "3 distinct"),
    ([np.array([[0.0, 0.0], [1.0, 1.0], [0.0, 0.0]])], "3 distinct"),
    ([np.array([[0.0, 0.0], [1.0, 1.0], [1.0, 1.0], [0.0, 0.0]])], "3 distinct"),
    ([np.array([[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]])], "zero area"),
    ([np.array([[0.0, 0.0], [10.0, 10.0], [10.0, 0.0], [0.0, 6.0]])], "cross"),       # self-intersecting
    ([np.array([[0.0, 0.0], [4.0, 0.0], [4.0, 4.0], [2.0, 0.0], [0.0, 4.0]])], "cross"),  # touches itself
    ([(SQUARE, [np.array([[0.0, 4.0], [2.0, 4.0], [2.0, 6.0], [0.0, 6.0]])])], "cross"),  # hole on the shell
    ([(SQUARE, [np.array([[0.0, 5.0], [2.0, 4.0], [2.0, 6.0]])])], "cross"),          # hole's vertex on it
    ([(SQUARE, [np.array([[2.0, 2.0], [4.0, 2.0], [4.0, 4.0]]),
                np.array([[4.0, 4.0], [6.0, 4.0], [6.0, 6.0]])])], "cross"),          # holes touch each other
    ([(SQUARE, [np.array([[20.0, 4.0], [22.0, 4.0], [22.0, 6.0]])])], "outside its shell"),
    ([SQUARE, SQUARE + 2.0], "cross"),                                               # overlapping polygons
    ([SQUARE, np.array([[2.0, 2.0], [3.0, 2.0], [3.0, 3.0]])], "lies on the land"),    # one inside another
    ([np.array([[0.0, 0.0], [1.0, np.nan], [1.0, 1.0]])], "not finite"),
    ([np.zeros((4, 3))], "2 columns"),
    ([], "at least one polygon"),
    ([{"holes": []}], "shell"),
])
def test_invalid_polygons(polygons, fragment):
    message = raises(ValueError, "polygons", LandMask, polygons=polygons)
    assert fragment in message


def test_polygons_that_are_not_sequences():
    raises(TypeError, "polygons", LandMask, polygons="coast")
    raises(TypeError, "polygons", LandMask, polygons=7)


def test_bad_rules_and_orders():
    raises(ValueError, "rule", RADAR.expected, POSE, np.zeros((1, 4)), np.zeros((1, 4, 4)), rule="simpson")
    raises(ValueError, "order", RADAR.expected, POSE, np.zeros((1, 4)), np.zeros((1, 4, 4)),
           rule="gauss-hermite", order=0)
    raises(ValueError, "order", RADAR.expected, POSE, np.zeros((1, 4)), np.zeros((1, 4, 4)),
           rule="gauss-hermite", order=33)
    raises(ValueError, "rule", _core.rule_points, "trapezoid")
    raises(ValueError, "pd_evaluation", SensorModel, detection=RADAR, clutter=CLUTTER, pd_evaluation="gh")
    raises(ValueError, "pd_order", SensorModel, detection=RADAR, clutter=CLUTTER, pd_order=0)
    raises(ValueError, "pd_order", SensorModel, detection=RADAR, clutter=CLUTTER, pd_order=2.5)


def test_bad_out_buffers():
    states = np.zeros((3, 4))
    readonly = np.zeros(3)
    readonly.flags.writeable = False
    raises(ValueError, "out", RADAR.evaluate, POSE, states, out=np.zeros(2))
    raises(ValueError, "out", RADAR.evaluate, POSE, states, out=np.zeros((3, 1)))
    raises(TypeError, "out", RADAR.evaluate, POSE, states, out=np.zeros(3, dtype=np.float32))
    raises(TypeError, "out", RADAR.evaluate, POSE, states, out=[0.0, 0.0, 0.0])
    raises(ValueError, "out", RADAR.evaluate, POSE, states, out=np.zeros(6)[::2])
    raises(ValueError, "out", RADAR.evaluate, POSE, states, out=readonly)
    raises(ValueError, "out", RADAR.expected, POSE, states, np.zeros((3, 4, 4)), out=np.zeros(4))
    raises(ValueError, "out", CLUTTER.evaluate, POSE, np.zeros((3, 2)), np.ones((3, 1)), out=np.zeros(1))
    raises(ValueError, "out", SENSOR.context(POSE).prob_detection_array, states, out=np.zeros(1))


def test_navigation_track_errors():
    t0 = datetime.datetime(2024, 1, 1)
    later = t0 + datetime.timedelta(seconds=1)
    def track(timestamps, positions, headings):
        return NavigationTrack(timestamps=timestamps, positions=positions, headings=headings)

    raises(ValueError, "timestamps", track, [later, t0], np.zeros((2, 2)), [0, 0])
    raises(ValueError, "timestamps", track, [t0, t0], np.zeros((2, 2)), [0, 0])
    raises(ValueError, "timestamps", track, [], np.zeros((0, 2)), [])
    raises(TypeError, "timestamps", track, [0.0], np.zeros((1, 2)), [0])
    raises(ValueError, "positions", track, [t0], np.zeros((2, 2)), [0])
    raises(ValueError, "positions", track, [t0], np.zeros((1, 4)), [0])  # (x, y, z) at most
    raises(ValueError, "headings", track, [t0], np.zeros((1, 2)), [np.nan])
    two = track([t0, later], np.zeros((2, 2)), [0, 1])
    raises(ValueError, "timestamp", two.pose_at, later + datetime.timedelta(seconds=1))
    raises(TypeError, "timestamp", two.pose_at, 0.5)


def test_detections_without_a_usable_measurement_model():
    context = SENSOR.context(POSE)
    raises(ValueError, "detections", context.clutter_spatial_density,
           Detection(StateVector([1.0, 2.0]), metadata={"area": 3.0}))
    raises(TypeError, "hypothesis_or_state", context.prob_detection, object())


# --- empty input --------------------------------------------------------------------------------
def test_zero_rows_return_empty_arrays():
    context = SENSOR.context(POSE)
    results = [
        RADAR.evaluate(POSE, np.zeros((0, 4))),
        RADAR.evaluate(POSE, np.zeros((0, 4)), out=np.zeros(0)),
        RADAR.expected(POSE, np.zeros((0, 4)), np.zeros((0, 4, 4))),
        CLUTTER.evaluate(POSE, np.zeros((0, 2)), np.zeros((0, 1))),
        CLUTTER.evaluate(POSE, np.zeros((0, 2)), []),
        context.prob_detection_array(np.zeros((0, 4))),
        context.prob_detection_array(np.zeros((0, 4)), np.zeros((0, 4, 4))),
        context.prob_detection_states([]),
        context.clutter_spatial_density_array(np.zeros((0, 2))),
        context.clutter_spatial_density_detections([]),
        RangeBands(edges=(1,), values=(1, 2))([]),
    ]
    for result in results:
        assert isinstance(result, np.ndarray) and result.shape == (0,) and result.dtype == np.float64
    land = LandMask(polygons=[SQUARE])
    empty = np.zeros((0, 2))
    for result in (land.contains(empty), LineOfSight(land=land).visible((20.0, 20.0), empty)):
        assert result.shape == (0,) and result.dtype == np.bool_
