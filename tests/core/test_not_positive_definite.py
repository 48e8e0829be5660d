"""A covariance that must be positive definite and is not raises
:class:`ctxmodels.NotPositiveDefiniteError` — a ``ValueError`` naming the argument, of its own
type so that callers (the array JPDA's fall-back to the component path) need not read the
message — from the GM-PHD update and the JPDA scan alike; it survives pickling (a worker's
error reaches the pool)."""
import pickle

import numpy as np
import pytest

import ctxmodels
from ctxmodels import _core


def test_it_is_a_value_error_of_the_package():
    assert issubclass(ctxmodels.NotPositiveDefiniteError, ValueError)
    assert ctxmodels.NotPositiveDefiniteError is ctxmodels.errors.NotPositiveDefiniteError
    error = pickle.loads(pickle.dumps(ctxmodels.NotPositiveDefiniteError("covars", "track 0")))
    assert type(error) is ctxmodels.NotPositiveDefiniteError and str(error) == "covars: track 0"
    assert (error.argument, error.detail) == ("covars", "track 0")


def _linear(noise):
    return np.array([[1.0, 0, 0, 0], [0, 0, 1.0, 0]]), np.eye(2) * noise


def test_jpda_scan_names_the_track_whose_innovation_covariance_is_not_positive_definite():
    model = _core.MeasurementModel.linear(*_linear(1.0))
    means = np.zeros((2, 4))
    covars = np.stack([np.eye(4), -10.0 * np.eye(4)])  # track 1: H P Hᵀ + R = -9 I
    z = np.array([[0.5, 0.5]])
    with pytest.raises(ctxmodels.NotPositiveDefiniteError,
                       match=r"^covars: track 1: the innovation covariance .* not positive definite"):
        _core.jpda_scan(model, means, covars, z, np.full(2, 0.9), np.full(1, 1e-3), 0.99, 9.21)
    # a positive definite one is no error
    _core.jpda_scan(model, means[:1], covars[:1], z, np.full(1, 0.9), np.full(1, 1e-3), 0.99, 9.21)


def test_gmphd_update_names_the_measurement_model():
    mixture = _core.GaussianMixtureArrays(4)
    mixture.extend(np.zeros((1, 4)), (-10.0 * np.eye(4))[np.newaxis], np.ones(1), [0], [0])
    model = _core.MeasurementModel.linear(*_linear(1.0))
    with pytest.raises(ctxmodels.NotPositiveDefiniteError,
                       match=r"^measurement_model: the innovation covariance of component 0"):
        mixture.update(model, np.array([[0.5, 0.5]]), np.full(1, 0.9), np.full(1, 1e-3),
                       prob_survival=1.0, missed_distance=1e9, squared=False,
                       include_all=True, normalise=True, skip_undetectable=True, time=0)
