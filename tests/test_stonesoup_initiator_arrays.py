"""The array helpers of the M-of-N initiator (``ctxmodels.stonesoup.initiator_arrays``)
against their reference computations: the core's gate screen against the NumPy screen
(``fast_association.screen_pairs``) and the exact stock distances; its input errors."""
from __future__ import annotations

import datetime

import numpy as np
import pytest
from stonesoup.measures import Mahalanobis, SquaredMahalanobis
from stonesoup.models.measurement.linear import LinearGaussian
from stonesoup.models.measurement.nonlinear import CartesianToBearingRange
from stonesoup.types.detection import Detection
from stonesoup.types.array import CovarianceMatrix, StateVector
from stonesoup.types.angle import Bearing
from stonesoup.models.transition.linear import (CombinedLinearGaussianTransitionModel,
                                                ConstantVelocity)
from stonesoup.predictor.kalman import KalmanPredictor
from stonesoup.types.hypothesis import SingleHypothesis
from stonesoup.types.prediction import GaussianStatePrediction
from stonesoup.types.state import GaussianState
from stonesoup.updater.kalman import ExtendedKalmanUpdater

from ctxmodels import _core
from ctxmodels.stonesoup import initiator_arrays
from ctxmodels.stonesoup.fast import measurement_batch
from ctxmodels.stonesoup.fast_association import SCREEN_MARGIN, screen_pairs

START = datetime.datetime(2024, 1, 1)
LIDAR = LinearGaussian(ndim_state=4, mapping=(0, 2), noise_covar=np.diag([4.0, 9.0]))
RADAR = CartesianToBearingRange(ndim_state=4, mapping=(0, 2), noise_covar=np.diag([1e-3, 4.0]),
                                translation_offset=StateVector([10.0, -5.0]))


def _states(rng, count):
    means = rng.normal(0.0, 50.0, size=(count, 4, 1))
    a = rng.normal(size=(count, 4, 4)) * rng.lognormal(0.0, 1.5, size=(count, 1, 1))
    covars = a @ a.transpose(0, 2, 1) + np.eye(4)
    return means, covars


def _detections(rng, model, count):
    if model is RADAR:
        return [Detection(StateVector([Bearing(rng.uniform(-np.pi, np.pi)),
                                       rng.uniform(1.0, 120.0)]), measurement_model=model)
                for _ in range(count)]
    return [Detection(StateVector(rng.normal(0.0, 60.0, size=(2, 1))), measurement_model=model)
            for _ in range(count)]


@pytest.mark.parametrize("model", [LIDAR, RADAR])
@pytest.mark.parametrize("squared", [False, True])
def test_screen_equals_the_numpy_screen_and_keeps_every_passing_pair(model, squared):
    rng = np.random.default_rng(3)
    updater = ExtendedKalmanUpdater(None)
    for _ in range(20):
        means, covars = _states(rng, 30)
        batch = measurement_batch(updater, model, means, covars)
        dets = _detections(rng, model, 12)
        gate = float(rng.uniform(1.0, 40.0))
        ours = initiator_arrays.screen(batch, dets, gate, squared)
        numpy_screen = screen_pairs(batch, dets, gate, squared, invert=np.linalg.inv)
        assert np.array_equal(ours, numpy_screen)
        measure = SquaredMahalanobis() if squared else Mahalanobis()
        passing = 0
        for n in range(len(means)):
            mp = batch.measurement_prediction(n, None)
            for k, det in enumerate(dets):
                if measure(mp, det) < gate:  # the stock gate
                    assert ours[n, k]
                    passing += 1
        assert passing <= ours.sum()


def test_screen_corner_cases():
    rng = np.random.default_rng(4)
    means, covars = _states(rng, 3)
    batch = measurement_batch(ExtendedKalmanUpdater(None), LIDAR, means, covars)
    dets = _detections(rng, LIDAR, 4) + [Detection(StateVector([np.nan, 0.0]),
                                                   measurement_model=LIDAR)]
    screen = initiator_arrays.screen(batch, dets, 1e-3, False)
    assert screen[:, -1].all() and not screen[:, :-1].any()
    for gate in (0.0, -1.0, float("nan")):
        assert not initiator_arrays.screen(batch, dets, gate, False).any()
    assert initiator_arrays.screen(batch, dets, 1e12, True).all()
    assert initiator_arrays.screen(batch, [], 10.0, False).shape == (3, 0)


def test_jpda_screen_input_errors():
    means, covars = np.zeros((2, 2)), np.stack([np.eye(2)] * 2)
    z, wrap = np.zeros((3, 2)), np.zeros((3, 2), dtype=bool)
    assert _core.jpda_screen(means, covars, z, wrap, 1.0, SCREEN_MARGIN).all()
    for args, argument in [
        ((means, np.zeros((2, 2, 3)), z, wrap, 1.0, 0.0), "covars"),
        ((means, covars, np.zeros((3, 3)), wrap, 1.0, 0.0), "detections"),
        ((means, covars, z, np.zeros((2, 2), dtype=bool), 1.0, 0.0), "wrap"),
        ((means, covars, z, wrap, 1.0, -1.0), "margin"),
        ((means, covars, z, wrap, 1.0, float("nan")), "margin"),
        ((np.asfortranarray(np.zeros((2, 3)))[:, :2], covars, z, wrap, 1.0, 0.0), "means"),
    ]:
        with pytest.raises(ValueError, match=f"^{argument}"):
            _core.jpda_screen(*args)
    with pytest.raises(TypeError):
        _core.jpda_screen(means, covars, z, wrap.astype(np.int64), 1.0, 0.0)
    # a singular innovation covariance keeps its row; NaN stays a candidate
    singular = np.stack([np.ones((2, 2)), np.eye(2)])
    far = np.full((1, 2), 1e6)
    out = _core.jpda_screen(np.array([[0.0, 0.0], [np.nan, 0.0]]), singular, far,
                            np.zeros((1, 2), dtype=bool), 1.0, SCREEN_MARGIN)
    assert out.tolist() == [[True], [True]]


def _prior(rng, seconds):
    means, covars = _states(rng, 1)
    return GaussianState(StateVector(means[0]), CovarianceMatrix(covars[0]),
                         timestamp=START + datetime.timedelta(seconds=seconds))


def test_predict_rows_equals_the_stock_predictor_bit_for_bit():
    rng = np.random.default_rng(5)
    model = CombinedLinearGaussianTransitionModel([ConstantVelocity(0.5), ConstantVelocity(0.5)])
    predictor = KalmanPredictor(model)
    terms = initiator_arrays.ControlTerms()
    now = START + datetime.timedelta(seconds=3)
    for times in ([1.0] * 6, [1.0, 2.5, 1.0, 0.5, 2.5, 2.9]):
        priors = [_prior(rng, t) for t in times]
        means = np.array([p.state_vector for p in priors])
        covars = np.array([p.covar for p in priors])
        for _ in range(2):  # the second time from the control terms' cache
            pred_means, pred_covars = initiator_arrays.predict_rows(
                predictor, terms, priors.__getitem__, means, covars,
                [p.timestamp for p in priors], now)
            for prior, mean, covar in zip(priors, pred_means, pred_covars):
                stock = predictor.predict(prior, timestamp=now)
                assert np.asarray(stock.state_vector).tobytes() == mean.tobytes()
                assert np.asarray(stock.covar).tobytes() == covar.tobytes()


@pytest.mark.parametrize("symmetric", [False, True])
def test_kalman_updates_equal_the_stock_updater_bit_for_bit(symmetric):
    rng = np.random.default_rng(6)
    updater = ExtendedKalmanUpdater(LIDAR, force_symmetric_covariance=symmetric)
    hypotheses = []
    for _ in range(9):
        prior = _prior(rng, 0.0)
        prediction = GaussianStatePrediction(prior.state_vector, prior.covar,
                                             timestamp=prior.timestamp)
        mp = updater.predict_measurement(prediction, LIDAR)
        detection, = _detections(rng, LIDAR, 1)
        hypotheses.append(SingleHypothesis(prediction, detection, mp))
    means, covars = initiator_arrays.kalman_updates(
        [h.prediction for h in hypotheses], [h.measurement_prediction for h in hypotheses],
        [h.measurement for h in hypotheses], [(False, False)] * len(hypotheses), symmetric)
    for hypothesis, mean, covar in zip(hypotheses, means, covars):
        stock = updater.update(hypothesis)
        assert np.asarray(stock.state_vector).tobytes() == mean.tobytes()
        assert np.asarray(stock.covar).tobytes() == covar.tobytes()


@pytest.mark.parametrize("analytic", [False, True])
def test_bearing_range_updates_equal_the_stock_updater_bit_for_bit(analytic):
    """Typed (Bearing) detections and predicted measurements: the wrapped innovation, as
    the stock ``z − ẑ`` computes it, near and across ±π."""
    from ctxmodels.stonesoup.fast import measurement_batch
    from ctxmodels.stonesoup.measurement import AnalyticCartesianToBearingRange
    model = RADAR if not analytic else AnalyticCartesianToBearingRange(
        ndim_state=4, mapping=(0, 2), noise_covar=np.diag([1e-3, 4.0]),
        translation_offset=StateVector([10.0, -5.0]))
    rng = np.random.default_rng(7)
    updater = ExtendedKalmanUpdater(None, force_symmetric_covariance=True)
    means, covars = _states(rng, 40)
    means[:20, 0, 0] = -rng.uniform(1.0, 50.0, 20)  # behind the sensor: bearings near ±π
    means[:20, 2, 0] = -5.0 + rng.normal(0.0, 1e-3, 20)
    batch = measurement_batch(updater, model, means, covars)
    hypotheses, wraps = [], []
    for n in range(len(means)):
        prediction = GaussianStatePrediction(StateVector(means[n]), CovarianceMatrix(covars[n]),
                                             timestamp=START)
        mp = batch.measurement_prediction(n, START)
        bearing = float(mp.state_vector[0, 0]) + rng.normal(0.0, 0.05)
        detection = Detection(StateVector([Bearing(bearing), float(mp.state_vector[1, 0]) + 1.0]),
                              timestamp=START, measurement_model=model)
        wrap = initiator_arrays.angle_wrap(detection.state_vector, mp.state_vector)
        assert wrap == (True, False)
        hypotheses.append(SingleHypothesis(prediction, detection, mp))
        wraps.append(wrap)
    means, covars = initiator_arrays.kalman_updates(
        [h.prediction for h in hypotheses], [h.measurement_prediction for h in hypotheses],
        [h.measurement for h in hypotheses], wraps, True)
    for hypothesis, mean, covar in zip(hypotheses, means, covars):
        stock = updater.update(hypothesis)
        assert np.asarray(stock.state_vector, dtype=np.float64).tobytes() == mean.tobytes()
        assert np.asarray(stock.covar).tobytes() == covar.tobytes()


def test_angle_wrap_declines_other_typed_arithmetic():
    from stonesoup.types.angle import Elevation
    floats = StateVector([1.0, 2.0])
    assert initiator_arrays.angle_wrap(floats, floats) == (False, False)
    typed = StateVector([Bearing(1.0), 2.0])
    assert initiator_arrays.angle_wrap(typed, typed) == (True, False)
    assert initiator_arrays.angle_wrap(floats, typed) is None  # float − Bearing: __rsub__
    assert initiator_arrays.angle_wrap(StateVector([Elevation(0.1), 2.0]), typed) is None
    assert initiator_arrays.angle_wrap(typed, StateVector([Bearing(1.0), 2.0, 3.0])) is None


def test_typed_distances_equal_the_stock_measure_bit_for_bit():
    """Bearing-typed pairs, bearings near and across ±π: the value and the type the stock
    Mahalanobis measure returns."""
    rng = np.random.default_rng(9)
    means, covars = _states(rng, 25)
    means[:12, 0, 0] = -rng.uniform(1.0, 50.0, 12)  # behind the sensor: bearings near ±π
    means[:12, 2, 0] = -5.0 + rng.normal(0.0, 1e-3, 12)
    batch = measurement_batch(ExtendedKalmanUpdater(None), RADAR, means, covars)
    kinds = (Bearing, float)
    rows, dets, wraps = [], [], []
    for n in range(len(means)):
        for det in _detections(rng, RADAR, 3) + [Detection(StateVector(
                [Bearing(batch.means[n, 0] + rng.normal(0.0, 0.1)), batch.means[n, 1]]),
                measurement_model=RADAR)]:
            rows.append(n)
            dets.append(det)
            wraps.append(initiator_arrays.wrap_rows(det.state_vector, kinds))
    assert all(w == (True, False) for w in wraps)
    ours = initiator_arrays.typed_distances(batch, rows, dets, wraps)
    measure = Mahalanobis()
    for n, det, distance in zip(rows, dets, ours):
        stock = measure(batch.measurement_prediction(n, None), det)
        assert type(stock) is type(distance)
        assert np.float64(stock).tobytes() == np.float64(distance).tobytes()


@pytest.mark.parametrize("model", [LIDAR, RADAR])
def test_screen_states_keeps_every_passing_pair(model):
    """Screening the predicted states (the core forms ẑ and S) keeps every pair the stock
    gate passes, and agrees with the screen of the stock measurement predictions."""
    from ctxmodels.stonesoup.array_jpda import _core_model
    core, bearing_row = _core_model(ExtendedKalmanUpdater, model)
    angle_rows = {} if bearing_row is None else {bearing_row: Bearing}
    rng = np.random.default_rng(13)
    updater = ExtendedKalmanUpdater(None)
    measure = Mahalanobis()
    passing = 0
    for _ in range(10):
        means, covars = _states(rng, 30)
        dets = _detections(rng, model, 12)
        gate = float(rng.uniform(1.0, 40.0))
        ours = initiator_arrays.screen_states((core, angle_rows), means, covars, dets, gate, False)
        batch = measurement_batch(updater, model, means, covars)
        assert np.array_equal(ours, initiator_arrays.screen(batch, dets, gate, False))
        distances = initiator_arrays.pair_distances(
            batch, [n for n in range(30) for _ in dets], [k for _ in range(30) for k in range(12)],
            dets, measure, False, None)
        for p, distance in enumerate(distances):
            n, k = divmod(p, 12)
            stock = measure(batch.measurement_prediction(n, None), dets[k])
            assert np.float64(stock).tobytes() == np.float64(distance).tobytes()
            if stock < gate:
                assert ours[n, k]
                passing += 1
    assert passing > 0
    for gate in (0.0, -1.0, float("nan")):
        assert not initiator_arrays.screen_states((core, angle_rows), means, covars, dets, gate,
                                                  False).any()
    assert initiator_arrays.screen_states(None, means, covars, dets, 1.0, False) is None


def test_jpda_screen_states_input_errors():
    model = _core.JPDAMeasurementModel.linear(np.array([[1.0, 0, 0, 0], [0, 0, 1.0, 0]]),
                                              np.eye(2))
    means, covars = np.zeros((3, 4)), np.stack([np.eye(4)] * 3)
    z, wrap = np.zeros((2, 2)), np.zeros((2, 2), dtype=bool)
    assert _core.jpda_screen_states(model, means, covars, z, wrap, 1.0, SCREEN_MARGIN).all()
    for args, argument in [
        ((model, means, np.zeros((3, 4, 3)), z, wrap, 1.0, 0.0), "covars"),
        ((model, means, covars, np.zeros((2, 3)), wrap, 1.0, 0.0), "detections"),
        ((model, means, covars, z, np.zeros((1, 2), dtype=bool), 1.0, 0.0), "wrap"),
        ((model, means, covars, z, wrap, 1.0, -1.0), "margin"),
        ((model, np.zeros((3, 3)), np.stack([np.eye(3)] * 3), z, wrap, 1.0, 0.0), "model"),
    ]:
        with pytest.raises(ValueError, match=f"^{argument}"):
            _core.jpda_screen_states(*args)
    # a state with NaN keeps its pairs
    means[1, 0] = np.nan
    far = np.full((2, 2), 1e6)
    assert _core.jpda_screen_states(model, means, covars, far, wrap, 1.0,
                                    SCREEN_MARGIN).tolist() == [[False, False], [True, True],
                                                                [False, False]]
