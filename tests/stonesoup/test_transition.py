"""The cached transition model gives the stock model's numbers, and its cache is safe."""
import datetime
import pickle

import numpy as np
import pytest
from stonesoup.models.transition.linear import (CombinedLinearGaussianTransitionModel,
                                                ConstantVelocity)
from stonesoup.predictor.kalman import KalmanPredictor
from stonesoup.types.state import GaussianState

from ctxmodels.stonesoup import CachedCombinedLinearGaussianTransitionModel


def models():
    parts = [ConstantVelocity(0.64), ConstantVelocity(0.3)]
    return CombinedLinearGaussianTransitionModel(parts), \
        CachedCombinedLinearGaussianTransitionModel(parts)


@pytest.mark.parametrize("seconds", [0.1, 1.25, 0.043, 7.0, 0.0])
def test_matrices_equal_stock(seconds):
    stock, cached = models()
    dt = datetime.timedelta(seconds=seconds)
    for _ in range(2):  # second call comes from the cache
        assert np.array_equal(cached.matrix(time_interval=dt), stock.matrix(time_interval=dt))
        assert np.array_equal(cached.covar(time_interval=dt), stock.covar(time_interval=dt))


def test_predictions_equal_stock_and_cache_is_read_only():
    stock, cached = models()
    t0 = datetime.datetime(2024, 1, 1)
    prior = GaussianState(np.array([[1.0], [2.0], [3.0], [-1.0]]), np.diag([4.0, 1, 9, 2]),
                          timestamp=t0)
    for seconds in (0.1, 1.25, 0.1):
        t = t0 + datetime.timedelta(seconds=seconds)
        a = KalmanPredictor(stock).predict(prior, timestamp=t)
        b = KalmanPredictor(cached).predict(prior, timestamp=t)
        assert np.array_equal(a.state_vector, b.state_vector)
        assert np.array_equal(a.covar, b.covar)
    matrix = cached.matrix(time_interval=datetime.timedelta(seconds=0.1))
    with pytest.raises(ValueError):
        matrix[0, 0] = 5.0


def test_pickles_without_cache():
    _, cached = models()
    cached.matrix(time_interval=datetime.timedelta(seconds=1))
    clone = pickle.loads(pickle.dumps(cached))
    assert "_cached_arrays" not in clone.__dict__
    assert np.array_equal(clone.matrix(time_interval=datetime.timedelta(seconds=1)),
                          cached.matrix(time_interval=datetime.timedelta(seconds=1)))
