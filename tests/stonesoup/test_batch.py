"""The batched Gaussian maths and object factories in ``ctxmodels.stonesoup._batch`` (used by
the fast GNN association, the array JPDA initiator and the array trackers), held against
the stock Stone Soup calls they replace."""
import datetime

import numpy as np
import pytest
from stonesoup.models.measurement.nonlinear import CartesianToBearingRange
from stonesoup.types.angle import Bearing
from stonesoup.types.array import CovarianceMatrix, StateVector
from stonesoup.types.prediction import TaggedWeightedGaussianStatePrediction
from stonesoup.types.state import TaggedWeightedGaussianState
from stonesoup.updater.kalman import ExtendedKalmanUpdater

from ctxmodels.stonesoup._batch import ObjectFactory, gaussian_arrays, measurement_batch

from .gmphd.setups import seeded_uuids

START = datetime.datetime(2024, 1, 1)


def test_bearing_range_measurement_prediction_is_bitwise_stock():
    """Jacobians by Stone Soup's finite differences, reproduced operation for operation,
    including bearings across ±π and a rotated, offset sensor."""
    rng = np.random.default_rng(0)
    updater = ExtendedKalmanUpdater(measurement_model=None)
    model = CartesianToBearingRange(4, (0, 2), np.diag([1e-4, 4.0]),
                                    translation_offset=StateVector([12.0, -7.0]),
                                    rotation_offset=StateVector([0.0, 0.0, 2.9]))
    means = np.column_stack([rng.uniform(-2000, 2000, 300), rng.normal(0, 5, 300),
                             rng.uniform(-2000, 2000, 300), rng.normal(0, 5, 300)])
    means[:20, 2] = -7.0 + rng.normal(0, 1e-3, 20)  # on the ±π line behind the sensor
    means[:20, 0] = -abs(means[:20, 0])
    covars = np.array([np.diag(rng.uniform(1, 50, 4)) for _ in means])
    batch = measurement_batch(updater, model, means[..., np.newaxis], covars)
    for n, (m, c) in enumerate(zip(means, covars)):
        mp = updater.predict_measurement(
            TaggedWeightedGaussianStatePrediction(StateVector(m), CovarianceMatrix(c),
                                                  weight=1, tag="x"), model)
        assert np.array_equal(model.jacobian(TaggedWeightedGaussianState(StateVector(m), c)),
                              batch.matrices[n])
        assert np.array_equal(np.asarray(mp.covar), batch.covars[n])
        assert np.array_equal(np.asarray(mp.cross_covar), batch.cross_covars[n])
        assert float(mp.state_vector[0, 0]) == batch.means[n, 0]
        assert isinstance(batch.typed_vector(n)[0, 0], Bearing)


def test_object_factory_matches_constructor_and_falls_back():
    factory = ObjectFactory(TaggedWeightedGaussianState, dict(
        state_vector=StateVector([0.0]), covar=CovarianceMatrix([[1.0]]), timestamp=None,
        weight=0.5, tag="probe"))
    assert factory.fast
    sv, covar = StateVector([1.0, 2.0]), CovarianceMatrix(np.eye(2))
    built = factory(state_vector=sv, covar=covar, timestamp=START, weight=0.3, tag="x")
    real = TaggedWeightedGaussianState(state_vector=sv, covar=covar, timestamp=START,
                                       weight=0.3, tag="x")
    assert built.__dict__ == real.__dict__ and type(built) is type(real)
    with seeded_uuids(8):
        fresh = factory(state_vector=sv, covar=covar, timestamp=None, weight=0.3, tag=None)
    with seeded_uuids(8):
        assert fresh.tag == TaggedWeightedGaussianState(sv, covar, tag=None).tag
    # a probe the constructor treats differently (it converts a plain array): fall back
    slow = ObjectFactory(TaggedWeightedGaussianState, dict(
        state_vector=np.zeros((1, 1)), covar=np.eye(1), timestamp=None, weight=0.5, tag="p"))
    assert not slow.fast
    made = slow(state_vector=np.zeros((2, 1)), covar=np.eye(2), weight=1.0, tag="q")
    assert isinstance(made.state_vector, StateVector)
    assert isinstance(made.covar, CovarianceMatrix)


def test_gaussian_arrays_rejects_mixed_dimensions():
    states = [TaggedWeightedGaussianState(StateVector([0.0, 1.0]), np.eye(2)),
              TaggedWeightedGaussianState(StateVector([0.0, 1.0, 2.0]), np.eye(3))]
    with pytest.raises(ValueError, match="states"):
        gaussian_arrays(states)


def test_object_factory_maker_builds_what_the_constructor_builds():
    factory = ObjectFactory(TaggedWeightedGaussianState, dict(
        state_vector=StateVector([0.0]), covar=CovarianceMatrix([[1.0]]), timestamp=None,
        weight=0.5, tag="probe"))
    make = factory.maker("state_vector", "covar", "weight", "tag", "timestamp")
    sv, covar = StateVector([1.0, 2.0]), CovarianceMatrix(np.eye(2))
    built = make(sv, covar, 0.3, "x", START)
    real = TaggedWeightedGaussianState(state_vector=sv, covar=covar, timestamp=START,
                                       weight=0.3, tag="x")
    assert built.__dict__ == real.__dict__ and type(built) is type(real)
    # without the tag (a default factory: a fresh uuid) it falls back to the constructor
    with seeded_uuids(3):
        fresh = factory.maker("state_vector", "covar")(sv, covar)
    with seeded_uuids(3):
        assert fresh.tag == TaggedWeightedGaussianState(sv, covar).tag
