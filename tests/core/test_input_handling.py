"""Reliability defects found by an outside tester, kept as reproducers: each failed before its
fix (a Rust panic escaping as ``pyo3_runtime.PanicException``, a silent wrong answer, a
refused valid input or an error that did not name its argument).
"""
import datetime
import inspect
import math
import pickle
import threading

import numpy as np
import pytest

from ctxmodels import (ClutterDensityModel, DetectionProbabilityModel, LandMask, LineOfSight,
                       MetadataThreshold, NavigationTrack, Pose, RangeBands, SensorModel, _core)
from ..hostile import names

POSE = Pose(x=3.0, y=-4.0, heading=0.6)
SQUARE = [[100.0, -50.0], [300.0, -50.0], [300.0, 150.0], [100.0, 150.0]]
LAND = LandMask(polygons=[np.array(SQUARE)])
DETECTION = DetectionProbabilityModel(factors=[
    RangeBands(edges=(50, 1612), values=(0, 0.4, 0), upper_owns=(False, True)), LAND,
    LineOfSight(land=LAND)])
CLUTTER = ClutterDensityModel(factors=[
    RangeBands(edges=(1000,), values=(1e-3, 1e-2)),
    MetadataThreshold(key="area", threshold=10, below=1e-1, at_or_above=1e-3)])
SENSOR = SensorModel(detection=DETECTION, clutter=CLUTTER)
CUBATURE = SensorModel(detection=DETECTION, clutter=CLUTTER, pd_evaluation="cubature")
RNG = np.random.default_rng(5)
N = 64


def states(n=N):
    rng = np.random.default_rng(n)
    return np.column_stack([rng.uniform(-1500, 1500, n), rng.normal(0, 5, n),
                            rng.uniform(-1500, 1500, n), rng.normal(0, 5, n)])


# --- 1. out= buffers that overlap an input, or are shared by threads ----------------------------
def _overlap_cases():
    """(label, call(out-maker)) for every array entry point taking out=, with `out` carved
    from each of its inputs in turn. The raw _core methods are listed too: the test below
    checks that no _core method with an `out` parameter is missing."""
    cases = []
    for label, make_inputs, call in [
        ("DetectionModel.evaluate states", lambda: [states()],
         lambda a, out: DETECTION._compiled().evaluate(POSE.as_tuple(), a[0], (0, 2), out)),
        ("DetectionAtPose.evaluate states", lambda: [states()],
         lambda a, out: _core.DetectionAtPose(DETECTION._compiled(), POSE.as_tuple()).evaluate(a[0], out)),
        ("DetectionModel.expected means", lambda: [states(), np.tile(np.eye(4), (N, 1, 1))],
         lambda a, out: DETECTION._compiled().expected(POSE.as_tuple(), a[0], a[1], (0, 2), "cubature", 3,
                                                      out)),
        ("ClutterModel.evaluate positions", lambda: [states()[:, 0::2].copy(), RNG.uniform(0, 20, (N, 1))],
         lambda a, out: CLUTTER._compiled().evaluate(POSE.as_tuple(), a[0], a[1], out)),
        ("ClutterAtPose.evaluate positions", lambda: [states()[:, 0::2].copy(), RNG.uniform(0, 20, (N, 1))],
         lambda a, out: _core.ClutterAtPose(CLUTTER._compiled(), POSE.as_tuple()).evaluate(a[0], a[1], out)),
        ("DetectionProbabilityModel.evaluate", lambda: [states()],
         lambda a, out: DETECTION.evaluate(POSE, a[0], out=out)),
        ("DetectionProbabilityModel.expected", lambda: [states(), np.tile(np.eye(4), (N, 1, 1))],
         lambda a, out: DETECTION.expected(POSE, a[0], a[1], out=out)),
        ("ClutterDensityModel.evaluate", lambda: [states()[:, 0::2].copy(), RNG.uniform(0, 20, (N, 1))],
         lambda a, out: CLUTTER.evaluate(POSE, a[0], a[1], out=out)),
        ("DetectorContext.prob_detection_array", lambda: [states()],
         lambda a, out: SENSOR.context(POSE).prob_detection_array(a[0], out=out)),
        ("DetectorContext.prob_detection_array covars", lambda: [states(), np.tile(np.eye(4), (N, 1, 1))],
         lambda a, out: CUBATURE.context(POSE).prob_detection_array(a[0], a[1], out=out)),
        ("DetectorContext.clutter_spatial_density_array",
         lambda: [states()[:, 0::2].copy(), RNG.uniform(0, 20, (N, 1))],
         lambda a, out: SENSOR.context(POSE).clutter_spatial_density_array(a[0], a[1], out=out)),
    ]:
        for k in range(len(make_inputs())):
            cases.append(pytest.param(make_inputs, call, k, id=f"{label} out-overlaps-input{k}"))
    return cases


def _out_in(array):
    """An `out` of N float64 entries sharing memory with `array` (from its start)."""
    flat = array.reshape(-1)
    assert flat.size >= N and np.shares_memory(flat, array)
    return flat[:N]


@pytest.mark.parametrize("make_inputs, call, k", _overlap_cases())
def test_out_overlapping_any_input_is_a_value_error_naming_out(make_inputs, call, k):
    inputs = make_inputs()
    expected = call([a.copy() for a in inputs], None)
    names(lambda: call(inputs, _out_in(inputs[k])), ValueError, "out")
    # The refused call wrote nothing, and a separate buffer still works.
    out = np.empty(N)
    assert call(inputs, out) is out
    np.testing.assert_array_equal(out, expected)


def test_overlap_cases_cover_every_core_method_with_out():
    with_out = set()
    for name in _core.__all__:
        cls = getattr(_core, name)
        for attr, member in vars(cls).items() if isinstance(cls, type) else []:
            try:
                parameters = inspect.signature(member).parameters
            except (TypeError, ValueError):
                continue
            if "out" in parameters:
                with_out.add(f"{name}.{attr}")
    covered = {c.id.split(" ")[0] for c in _overlap_cases()}
    assert with_out and with_out <= covered, with_out - covered


def test_out_equal_to_a_one_column_input_is_refused():
    metadata = RNG.uniform(0, 20, (N, 1))
    names(lambda: CLUTTER.evaluate(POSE, np.zeros((N, 2)), metadata, out=metadata.reshape(-1)),
          ValueError, "out")


def test_threads_sharing_one_out_get_results_or_value_errors_never_panics():
    """Writers fill one shared ``out`` with one of two different answers, readers read it
    as their states: every call succeeds or is a ValueError, and a reader that succeeds
    read one writer's complete answer, never a mix of two."""
    n = 40_000
    inputs = [states(n), states(n) * 3.0]
    answers = [DETECTION.evaluate(POSE, x) for x in inputs]
    assert not np.array_equal(answers[0], answers[1])
    read_back = [DETECTION.evaluate(POSE, a.reshape(-1, 4)) for a in answers]
    shared = answers[0].copy()
    context = SENSOR.context(POSE)
    outcomes, lock = [], threading.Lock()

    def writer(k):
        for i in range(40):
            try:
                got = context.prob_detection_array(inputs[(i + k) % 2], out=shared)
                outcome = ("ok", got is shared)
            except BaseException as err:  # noqa: B036 — record panics instead of dying
                outcome = (type(err).__name__, str(err))
            with lock:
                outcomes.append(outcome)

    def reader(k):
        # Reads the buffer the writers fill, as the states of its own call.
        private = np.empty(n // 4)
        for _ in range(40):
            try:
                DETECTION.evaluate(POSE, shared.reshape(-1, 4), out=private)
                whole = any(np.array_equal(private, r) for r in read_back)
                outcome = ("ok", whole)
            except BaseException as err:  # noqa: B036
                outcome = (type(err).__name__, str(err))
            with lock:
                outcomes.append(outcome)

    threads = [threading.Thread(target=writer if k < 6 else reader, args=(k,)) for k in range(8)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len(outcomes) == 8 * 40
    # (a ValueError naming the argument: ctxmodels' ArgumentError)
    unexpected = [o for o in outcomes if o[0] not in ("ok", "ArgumentError")]
    assert not unexpected, unexpected[:3]
    assert all(o[1] is True for o in outcomes if o[0] == "ok"), "a torn read or a copy"
    for kind, message in outcomes:
        if kind == "ArgumentError":
            assert message.startswith(("out:", "states:")), message
    assert any(o[0] == "ok" for o in outcomes)
    # Whichever writer finished last left its whole answer.
    assert any(np.array_equal(shared, a) for a in answers)


# --- 3. NaN and infinite positions and ranges ------------------------------------------------------
@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_non_finite_points_are_refused_by_land_and_line_of_sight(bad):
    points = np.array([[0.0, 0.0], [bad, 10.0], [10.0, 0.0]])
    assert "row 1" in names(lambda: LAND.contains(points), ValueError, "points")
    assert "row 1" in names(lambda: LineOfSight(land=LAND).visible((0.0, 0.0), points), ValueError,
                            "targets")
    names(lambda: LAND._compiled().contains(points), ValueError, "points")
    names(lambda: LineOfSight(land=LAND)._compiled().visible((0.0, 0.0), points), ValueError, "targets")
    names(lambda: LineOfSight(land=LAND)._compiled().visible((bad, 0.0), np.zeros((1, 2))), ValueError,
          "sensor")


def test_nan_ranges_are_refused():
    bands = RangeBands(edges=[50.0, 80.0], values=[0.95, 0.2, 0.0])
    assert "row 1" in names(lambda: bands([0.0, math.nan]), ValueError, "ranges")
    names(lambda: bands._compiled().at(np.array([0.0, math.nan])), ValueError, "ranges")


def test_infinite_ranges_are_ordered_like_any_range():
    """A range gets the band above every edge it has passed (the documented e_k = ∞ and the
    edge-counting reference of test_properties): +inf the last, -inf the first."""
    bands = RangeBands(edges=[50.0, 80.0], values=[0.95, 0.2, 0.1])
    np.testing.assert_array_equal(bands([0.0, math.inf, -math.inf]), [0.95, 0.1, 0.95])


# --- 4. sequence Properties are copied into immutable values ---------------------------------------
def _mutable_components():
    """(build(lists), mutate(lists)) pairs: build a component from the lists, then edit them."""
    return {
        "RangeBands": (lambda: {"edges": [50.0, 80.0], "values": [0.95, 0.2, 0.0],
                                "upper_owns": [True, False]},
                       lambda kw: RangeBands(**kw),
                       lambda kw: (kw["edges"].__setitem__(0, 60.0), kw["values"].append(9.0),
                                   kw["upper_owns"].__setitem__(1, True))),
        "RangeBands-ndarray": (lambda: {"edges": np.array([50.0, 80.0]), "values": np.array([0.95, 0.2, 0.0]),
                                        "upper_owns": np.array([True, False])},
                               lambda kw: RangeBands(**kw),
                               lambda kw: (kw["edges"].__setitem__(0, 60.0), kw["values"].__setitem__(0, 0.1),
                                           kw["upper_owns"].__setitem__(1, True))),
        "LandMask": (lambda: {"polygons": [([[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]],
                                            [[[4.0, 4.0], [6.0, 4.0], [6.0, 6.0]]])]},
                     lambda kw: LandMask(**kw),
                     lambda kw: (kw["polygons"][0][0].__setitem__(0, [-5.0, -5.0]),
                                 kw["polygons"][0][1].clear(),
                                 kw["polygons"].append([[20.0, 20.0], [30.0, 20.0], [30.0, 30.0]]))),
        "DetectionProbabilityModel": (lambda: {"factors": [0.5, RangeBands(edges=[50.0], values=[1.0, 0.4])]},
                                      lambda kw: DetectionProbabilityModel(**kw),
                                      lambda kw: (kw["factors"].append(0.1),
                                                  kw["factors"].__setitem__(0, 0.9))),
        "ClutterDensityModel": (lambda: {"factors": [2e-3, MetadataThreshold(
                                    key="area", threshold=10, below=1e-1, at_or_above=1e-3)]},
                                lambda kw: ClutterDensityModel(**kw),
                                lambda kw: (kw["factors"].append(10.0), kw["factors"].__setitem__(0, 1.0))),
        "SensorModel": (lambda: {"position_mapping": [0, 2]},
                        lambda kw: SensorModel(detection=DetectionProbabilityModel(factors=[
                            RangeBands(edges=[50.0], values=[1.0, 0.4])]),
                            clutter=ClutterDensityModel(factors=[1e-3]), **kw),
                        lambda kw: kw["position_mapping"].__setitem__(1, 1)),
        "NavigationTrack": (lambda: {"timestamps": [datetime.datetime(2024, 1, 1, 0, 0, s) for s in (0, 10)],
                                     "positions": [[0.0, 0.0], [100.0, 0.0]], "headings": [0.0, 1.0]},
                            lambda kw: NavigationTrack(**kw),
                            lambda kw: (kw["timestamps"].__setitem__(
                                            1, datetime.datetime(2024, 1, 1, 0, 0, 20)),
                                        kw["positions"][1].__setitem__(0, 7.0), kw["headings"].append(3.0))),
    }


def _evaluation(obj):
    if isinstance(obj, RangeBands):
        return obj(np.linspace(0, 100, 201))
    if isinstance(obj, LandMask):
        return obj.contains(np.column_stack([np.linspace(-10, 40, 101), np.linspace(-10, 40, 101)]))
    if isinstance(obj, DetectionProbabilityModel):
        return obj.evaluate(POSE, states())
    if isinstance(obj, ClutterDensityModel):
        return obj.evaluate(POSE, states()[:, 0::2], np.random.default_rng(0).uniform(0, 20, (N, 1)))
    if isinstance(obj, SensorModel):
        return obj.context(POSE).prob_detection_array(states())
    if isinstance(obj, NavigationTrack):
        return np.array([obj.pose_at(datetime.datetime(2024, 1, 1, 0, 0, s)).as_tuple() for s in range(11)])
    raise AssertionError(type(obj))


def _assert_no_mutable_sequences(value, where):
    if isinstance(value, list):
        raise AssertionError(f"{where} is a list")
    if isinstance(value, np.ndarray):
        assert not value.flags.writeable, f"{where} is a writeable array"
    if isinstance(value, (tuple, list)):
        for i, v in enumerate(value):
            _assert_no_mutable_sequences(v, f"{where}[{i}]")
    if isinstance(value, dict):
        for k, v in value.items():
            _assert_no_mutable_sequences(v, f"{where}[{k!r}]")


@pytest.mark.parametrize("name", sorted(_mutable_components()))
def test_editing_the_lists_a_component_was_built_from_changes_nothing(name):
    make_kwargs, build, mutate = _mutable_components()[name]
    kwargs = make_kwargs()
    obj = build(kwargs)
    twin = build(make_kwargs())
    text, pickled = repr(obj), pickle.dumps(obj)
    before = _evaluation(obj)
    mutate(kwargs)
    for prop in type(obj).properties:
        _assert_no_mutable_sequences(getattr(obj, prop), f"{name}.{prop}")
    assert repr(obj) == text
    assert obj == twin and hash(obj) == hash(twin)
    assert pickle.dumps(obj) == pickled
    restored = pickle.loads(pickled)
    assert restored == obj
    np.testing.assert_array_equal(_evaluation(obj), before)
    np.testing.assert_array_equal(_evaluation(restored), before)


# --- 5. unaligned but C-contiguous arrays -----------------------------------------------------------
def unaligned(array):
    raw = np.frombuffer(bytearray(array.nbytes + 1), offset=1, dtype=np.float64, count=array.size)
    out = raw.reshape(array.shape)
    out[...] = array
    assert out.flags.c_contiguous and not out.flags.aligned
    return out


def test_unaligned_arrays_are_accepted_with_the_same_results():
    x = states(500)
    covars = np.tile(np.diag([400.0, 4.0, 900.0, 4.0]), (500, 1, 1))
    areas = RNG.uniform(0, 20, (500, 1))
    np.testing.assert_array_equal(DETECTION.evaluate(POSE, unaligned(x)), DETECTION.evaluate(POSE, x))
    np.testing.assert_array_equal(DETECTION.expected(POSE, unaligned(x), unaligned(covars)),
                                  DETECTION.expected(POSE, x, covars))
    np.testing.assert_array_equal(CLUTTER.evaluate(POSE, unaligned(x[:, 0::2].copy()), unaligned(areas)),
                                  CLUTTER.evaluate(POSE, x[:, 0::2], areas))
    np.testing.assert_array_equal(LAND.contains(unaligned(x[:, 0::2] / 8)), LAND.contains(x[:, 0::2] / 8))
    np.testing.assert_array_equal(RangeBands(edges=[50.0], values=[1.0, 0.0])(unaligned(np.abs(x[:, 0]))),
                                  RangeBands(edges=[50.0], values=[1.0, 0.0])(np.abs(x[:, 0])))
    core = DETECTION._compiled()
    np.testing.assert_array_equal(core.evaluate(POSE.as_tuple(), unaligned(x), (0, 2), None),
                                  core.evaluate(POSE.as_tuple(), x, (0, 2), None))
    np.testing.assert_array_equal(
        core.expected(POSE.as_tuple(), unaligned(x), unaligned(covars), (0, 2), "cubature", 3, None),
        core.expected(POSE.as_tuple(), x, covars, (0, 2), "cubature", 3, None))
    np.testing.assert_array_equal(LAND._compiled().contains(unaligned(x[:, 0::2] / 8)),
                                  LAND._compiled().contains(x[:, 0::2] / 8))
    out = unaligned(np.zeros(500))
    names(lambda: core.evaluate(POSE.as_tuple(), x, (0, 2), out), ValueError, "out")


# --- 6. position_mapping of any integer type --------------------------------------------------------
def test_numpy_integer_position_mapping_is_accepted():
    mapping = (np.int64(0), np.int32(2))
    sensor = SensorModel(detection=DETECTION, clutter=CLUTTER, position_mapping=mapping)
    assert sensor.position_mapping == (0, 2)
    assert all(type(i) is int for i in sensor.position_mapping)
    x = states()
    np.testing.assert_array_equal(sensor.context(POSE).prob_detection_array(x), DETECTION.evaluate(POSE, x))
    np.testing.assert_array_equal(DETECTION.evaluate(POSE, x, mapping), DETECTION.evaluate(POSE, x))
    np.testing.assert_array_equal(DETECTION.evaluate(POSE, x, np.array([0, 2])), DETECTION.evaluate(POSE, x))


@pytest.mark.parametrize("mapping, exception", [
    ((0, 2, 3, 4), ValueError), ((0, 2, 2), ValueError), ((0.0, 2.0), TypeError),
    ((0, 2.5), TypeError), ((False, True), TypeError),
    ((0, -1), ValueError), ((0, 2**70), ValueError), ((1, 1), ValueError), ("02", TypeError)])
def test_bad_position_mappings_name_position_mapping(mapping, exception):
    names(lambda: SensorModel(detection=DETECTION, clutter=CLUTTER, position_mapping=mapping), exception,
          "position_mapping")
    names(lambda: DETECTION.evaluate(POSE, states(), mapping), exception, "position_mapping")
    names(lambda: DETECTION.expected(POSE, states(), np.tile(np.eye(4), (N, 1, 1)), mapping), exception,
          "position_mapping")


def test_position_mapping_beyond_the_state_names_the_states_and_the_mapping():
    # (a ShapeError naming the array, as the core's own check on every layout does)
    message = names(lambda: DETECTION.evaluate(POSE, states(), (0, 4)), ValueError, "states")
    assert "position_mapping" in message and "(0, 4)" in message


# --- 7. metadata as rows ------------------------------------------------------------------------------
def test_metadata_as_a_list_of_rows_is_read_like_an_array():
    positions = states()[:3, 0::2]
    rows = [[5.0], [20.0], [10]]
    np.testing.assert_array_equal(CLUTTER.evaluate(POSE, positions, rows),
                                  CLUTTER.evaluate(POSE, positions, np.array(rows, dtype=float)))
    np.testing.assert_array_equal(CLUTTER.evaluate(POSE, positions, [(5.0,), (20.0,), (10,)]),
                                  CLUTTER.evaluate(POSE, positions, np.array(rows, dtype=float)))
    names(lambda: CLUTTER.evaluate(POSE, positions, [[5.0], [20.0]]), ValueError, "metadata")
    names(lambda: CLUTTER.evaluate(POSE, positions, [[5.0, 1.0], [20.0, 1.0], [1.0, 1.0]]), ValueError,
          "metadata")
    names(lambda: CLUTTER.evaluate(POSE, positions, [[5.0], {"area": 1.0}, [1.0]]), TypeError, "metadata")


# --- 8. tiny polygons -----------------------------------------------------------------------------------
@pytest.mark.parametrize("scale", [1e-200, 1e-300, 5e-320])
def test_tiny_valid_triangle_is_land(scale):
    mask = LandMask(polygons=[[(0.0, 0.0), (scale, 0.0), (0.0, scale)]])
    inside = np.array([[scale / 4, scale / 4], [0.0, 0.0], [scale / 2, scale / 2]])
    outside = np.array([[scale, scale], [-scale, 0.0], [0.75 * scale, 0.75 * scale], [1.0, 1.0]])
    np.testing.assert_array_equal(mask.contains(inside), [True, True, True])
    np.testing.assert_array_equal(mask.contains(outside), [False, False, False, False])


def test_collinear_rings_are_still_refused():
    for ring in ([(0.0, 0.0), (1e-200, 1e-200), (2e-200, 2e-200)], [(0.0, 0.0), (1.0, 0.0), (3.0, 0.0)]):
        assert "zero area" in names(lambda: LandMask(polygons=[ring]), ValueError, "polygons")


# --- 9. naive and timezone-aware datetimes ------------------------------------------------------------
NAIVE = datetime.datetime(2024, 1, 1, 12, 0, 0)
AWARE = datetime.datetime(2024, 1, 1, 12, 0, 0, tzinfo=datetime.timezone.utc)
SECOND = datetime.timedelta(seconds=1)


def test_navigation_track_mixing_naive_and_aware_timestamps_names_timestamps():
    message = names(lambda: NavigationTrack(timestamps=[NAIVE, AWARE + SECOND], positions=[[0, 0], [1, 1]],
                                            headings=[0, 0]), TypeError, "timestamps")
    assert "naive" in message and "aware" in message
    aware = NavigationTrack(timestamps=[AWARE, AWARE + 10 * SECOND], positions=[[0, 0], [10, 0]],
                            headings=[0, 0])
    assert aware.pose_at(AWARE + 5 * SECOND).x == 5.0
    assert "naive" in names(lambda: aware.pose_at(NAIVE), TypeError, "timestamp")


# --- 10. errors that must name their argument ----------------------------------------------------------
@pytest.mark.parametrize("order", [-1, 0, 33, 2**70])
def test_bad_order_names_order(order):
    names(lambda: DETECTION.expected(POSE, states(), np.tile(np.eye(4), (N, 1, 1)), order=order), ValueError,
          "order")
    names(lambda: DETECTION._compiled().expected(POSE.as_tuple(), states(), np.tile(np.eye(4), (N, 1, 1)),
                                                 (0, 2), "cubature", -1, None), ValueError, "order")


@pytest.mark.parametrize("order", [2.5, True, "3"])
def test_non_integer_order_names_order(order):
    names(lambda: DETECTION.expected(POSE, states(), np.tile(np.eye(4), (N, 1, 1)), order=order), TypeError,
          "order")


def test_ragged_covariances_name_covars():
    names(lambda: DETECTION.expected(POSE, states(2), [np.eye(4), np.eye(3)]), TypeError, "covars")
    names(lambda: DETECTION.expected(POSE, states(2), [np.eye(4), "x"]), TypeError, "covars")


@pytest.mark.parametrize("factors", [None, 3, "ab"])
def test_non_sequence_factors_name_factors(factors):
    names(lambda: DetectionProbabilityModel(factors=factors), TypeError, "factors")
    names(lambda: ClutterDensityModel(factors=factors), TypeError, "factors")


@pytest.mark.parametrize("value", [1e308 * 10, -math.inf, 10**400, -(10**400)],
                         ids=["inf", "-inf", "1e400", "-1e400"])
def test_huge_metadata_names_metadata(value):
    positions = np.zeros((2, 2))
    names(lambda: CLUTTER.evaluate(POSE, positions, [{"area": 1.0}, {"area": value}]), ValueError, "metadata")
    if isinstance(value, float):
        assert "row 1" in names(lambda: CLUTTER.evaluate(POSE, positions, np.array([[1.0], [value]])),
                                ValueError, "metadata")
