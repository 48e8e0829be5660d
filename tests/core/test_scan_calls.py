"""The detector context's thin P_D calls (ctxmodels.scan_calls): the common case goes
straight to the core, everything else through the general path, with the same bits and
the same errors; the per-scan state is rebuilt when a Property changes and never pickled."""
import copy
import math
import pickle

import numpy as np
import pytest
from stonesoup.types.array import StateVector, StateVectors
from stonesoup.types.hypothesis import SingleHypothesis
from stonesoup.types.numeric import Probability
from stonesoup.types.prediction import GaussianStatePrediction
from stonesoup.types.state import ParticleState

from ctxmodels import (AngularSector, ClutterDensityModel, DetectionProbabilityModel,
                       LandMask, Pose, RangeBands, SensorModel)

ISLAND = [[300.0, 300.0], [500.0, 300.0], [500.0, 500.0], [300.0, 500.0]]


def _sensor(pd_evaluation="mean"):
    detection = DetectionProbabilityModel(factors=[
        0.9, RangeBands(edges=(50, 400, 1612), values=(0, 0.8, 0.4, 0), upper_owns=(False, True, True)),
        AngularSector.blind(math.pi, math.radians(65)), LandMask(polygons=[ISLAND])])
    return SensorModel(detection=detection, clutter=ClutterDensityModel(factors=[1e-3]),
                       pd_evaluation=pd_evaluation)


def _states(n, seed=0):
    rng = np.random.default_rng(seed)
    states = rng.uniform(-1800, 1800, size=(n, 4))
    states[: n // 10, [0, 2]] = rng.uniform(250, 550, size=(n // 10, 2))  # around the island
    return states


def _general(context, states):
    """The general path: the detection model's own evaluation at the context's pose."""
    model = context.sensor_model
    return model.detection.evaluate(context.pose, states, tuple(model.position_mapping))


@pytest.mark.parametrize("n", [0, 1, 7, 5000])  # 5000: past the rows that keep the GIL
def test_array_call_has_the_general_paths_bits(n):
    context = _sensor().context((10.0, -20.0, 0.3))
    states = _states(n)
    expected = _general(context, states)
    assert np.array_equal(context.prob_detection_array(states), expected)
    out = np.full(n, np.nan)
    assert context.prob_detection_array(states, out=out) is out
    assert np.array_equal(out, expected)
    if n >= 1000:
        assert set(expected.tolist()) >= {0.0, 0.9 * 0.8, 0.9 * 0.4}  # both bands took part
        inside = np.all((states[:, [0, 2]] > 300) & (states[:, [0, 2]] < 500), axis=1)
        assert inside.sum() > 10 and np.all(expected[inside] == 0)  # and the land


def test_array_call_converts_what_the_core_does_not_take():
    context = _sensor().context((10.0, -20.0, 0.3))
    states = _states(200)
    expected = _general(context, states)
    for given in (states.tolist(), np.asfortranarray(states), states.astype(np.float32),
                  np.repeat(states, 2, axis=0)[::2]):
        assert np.array_equal(context.prob_detection_array(given),
                              _general(context, np.asarray(given, dtype=np.float64)))
    assert np.array_equal(context.prob_detection_array(states), expected)


@pytest.mark.parametrize("out, error, text", [
    (np.empty(3, dtype=np.float32), TypeError, "out: must have dtype float64"),
    (np.empty(4), ValueError, "out: must have shape (3,)"),
    (np.empty(6)[::2], ValueError, "out: must be C-contiguous"),
    ([0.0, 0.0, 0.0], TypeError, "out: must be a numpy.ndarray"),
])
def test_a_bad_out_gets_the_general_paths_error(out, error, text):
    context = _sensor().context((0.0, 0.0, 0.0))
    with pytest.raises(error, match=text.replace("(", r"\(").replace(")", r"\)")):
        context.prob_detection_array(_states(3), out=out)


def test_a_read_only_or_overlapping_out_is_refused():
    context = _sensor().context((0.0, 0.0, 0.0))
    states = _states(4)
    frozen = np.empty(4)
    frozen.setflags(write=False)
    with pytest.raises(ValueError, match="out: must be writeable"):
        context.prob_detection_array(states, out=frozen)
    with pytest.raises(ValueError, match="out: .*overlap"):
        context.prob_detection_array(states, out=states.reshape(-1)[:4])


def test_non_finite_or_unmappable_rows_raise_naming_the_argument():
    context = _sensor().context((0.0, 0.0, 0.0))
    states = _states(5)
    states[3, 2] = np.nan
    with pytest.raises(ValueError, match="^means: row 3"):
        context.prob_detection_array(states)
    with pytest.raises(ValueError, match="position_mapping"):
        context.prob_detection_array(np.zeros((2, 2)))


def test_scalar_call_equals_the_array_row_for_every_kind_of_state():
    context = _sensor().context((10.0, -20.0, 0.3))
    states = _states(300, seed=1)
    expected = _general(context, states)
    for row, pd in zip(states, expected):
        prediction = GaussianStatePrediction(StateVector(row), np.eye(4))
        for given in (SingleHypothesis(prediction, None), prediction, StateVector(row), row,
                      row.reshape(-1, 1).copy(), row.tolist()):
            value = context.prob_detection(given)
            assert type(value) is Probability and value.log_value == Probability(pd).log_value
        assert context._scan_calls.at_pose.at(prediction.state_vector) == pd  # the thin path ran


def test_scalar_call_falls_back_where_the_core_does_not_read():
    context = _sensor().context((10.0, -20.0, 0.3))
    row = np.array([200.0, 1.0, -150.0, 0.5])
    (expected,) = _general(context, row[np.newaxis])
    object_vector = StateVector([200, 1, -150, 0.5]).astype(object)  # typed elements
    assert float(context.prob_detection(object_vector)) == expected
    particles = ParticleState(StateVectors(np.tile(row[:, np.newaxis], 5)),
                              weight=np.full(5, 0.2))
    assert float(context.prob_detection(particles)) == pytest.approx(expected, rel=1e-15)
    with pytest.raises(ValueError):
        context.prob_detection(StateVector([np.nan, 0, 1, 0]))
    with pytest.raises(TypeError, match="hypothesis_or_state"):
        context.prob_detection(object())


def test_expected_pd_contexts_still_integrate_over_the_covariance():
    context = _sensor("cubature").context((0.0, 0.0, 0.0))
    # on a band edge: the expectation differs from the value at the mean
    prediction = GaussianStatePrediction(StateVector([400.0, 0, 1.0, 0]), np.diag([900.0, 1, 900, 1]))
    at_mean = float(_general(context, prediction.state_vector.reshape(1, -1))[0])
    expected = context.sensor_model.detection.expected(
        context.pose, prediction.state_vector.reshape(1, -1), prediction.covar[np.newaxis],
        rule="cubature")[0]
    value = context.prob_detection(SingleHypothesis(prediction, None))
    assert value.log_value == Probability(expected).log_value and expected != at_mean
    # a bare vector has no covariance: read at the point
    assert float(context.prob_detection(prediction.state_vector)) == at_mean


def test_setting_a_property_rebuilds_the_scan_state():
    sensor = _sensor()
    context = sensor.context((0.0, 0.0, 0.0))
    row = np.array([[100.0, 0, 0.0, 0]])
    assert context.prob_detection_array(row)[0] > 0
    context.pose = Pose(x=0.0, y=0.0, heading=math.pi)  # now the target is in the blind sector
    assert context.prob_detection_array(row)[0] == 0
    assert float(context.prob_detection(row[0])) == 0


def test_contexts_pickle_and_copy_after_use():
    context = _sensor().context((10.0, -20.0, 0.3))
    states = _states(50)
    expected = context.prob_detection_array(states)
    float(context.prob_detection(states[0]))
    for other in (pickle.loads(pickle.dumps(context)), copy.copy(context), copy.deepcopy(context)):
        assert np.array_equal(other.prob_detection_array(states), expected)
        assert other.sensor_model == context.sensor_model and other.pose == context.pose


@pytest.mark.parametrize("rule", ["cubature", "unscented", "gauss-hermite"])
def test_scalar_expected_pd_has_the_general_paths_bits(rule):
    context = _sensor(rule).context((10.0, -20.0, 0.3))
    rng = np.random.default_rng(5)
    means = _states(200, seed=2)
    scales = rng.uniform(1, 60, size=(200, 2))
    covars = np.zeros((200, 4, 4))
    for k, (sx, sy) in enumerate(scales):
        rho = rng.uniform(-0.9, 0.9) * sx * sy
        covars[k] = np.diag([sx * sx, 1.0, sy * sy, 1.0])
        covars[k, 0, 2] = covars[k, 2, 0] = rho
    model = context.sensor_model
    expected = model.detection.expected(context.pose, means, covars, rule=rule,
                                        order=model.pd_order)
    # smeared over band edges, sector and land: values no single point has
    assert len(set(expected.tolist()) - {0.0, 0.9 * 0.8, 0.9 * 0.4}) >= 3
    for mean, covar, pd in zip(means, covars, expected):
        prediction = GaussianStatePrediction(StateVector(mean), covar)
        value = context.prob_detection(SingleHypothesis(prediction, None))
        # (a Probability keeps log(p): float() of it need not give p back)
        assert type(value) is Probability and value.log_value == Probability(pd).log_value
        # ... and it came from the thin entry point, not the general path
        assert context._scan_calls.at_pose.expected_at(prediction.state_vector, prediction) == pd


def test_scalar_expected_pd_refuses_what_the_general_path_refuses():
    context = _sensor("cubature").context((0.0, 0.0, 0.0))
    bad = np.diag([-4.0, 1.0, 9.0, 1.0])  # not positive semi-definite
    with pytest.raises(ValueError, match="covars"):
        context.prob_detection(GaussianStatePrediction(StateVector([100.0, 0, 0, 0]), bad))
    with pytest.raises(ValueError, match="^hypothesis_or_state: row 0"):
        context.prob_detection(GaussianStatePrediction(StateVector([np.inf, 0, 0, 0]), np.eye(4)))
