"""The new holding tracks of the array M-of-N initiator (``initiator_births``) against
Stone Soup's ``SimpleMeasurementInitiator`` and ``model.inverse_function``, bit for bit."""
from __future__ import annotations

import datetime

import numpy as np
import pytest
from stonesoup.initiator.simple import SimpleMeasurementInitiator
from stonesoup.models.measurement.linear import LinearGaussian
from stonesoup.models.measurement.nonlinear import CartesianToBearingRange
from stonesoup.types.angle import Bearing
from stonesoup.types.array import CovarianceMatrix, StateVector
from stonesoup.types.detection import Detection
from stonesoup.types.state import GaussianState
from stonesoup.types.track import Track

from ctxmodels.stonesoup.jpda import _initiator_births as initiator_births
from ctxmodels.stonesoup.measurement import AnalyticCartesianToBearingRange

START = datetime.datetime(2024, 1, 1)


def _radar(kind, rotation=0.7):
    return kind(ndim_state=4, mapping=(0, 2), noise_covar=np.diag([1e-3, 4.0]),
                translation_offset=StateVector([12.5, -7.25]),
                rotation_offset=StateVector([0.0, 0.0, rotation]))


def _typed(rng, model, count):
    return [Detection(StateVector([Bearing(rng.uniform(-np.pi, np.pi)),
                                   rng.uniform(0.0, 300.0) if k % 5 else 0.0]),
                      timestamp=START, measurement_model=model, metadata={"k": k})
            for k in range(count)]


@pytest.mark.parametrize("kind", [CartesianToBearingRange, AnalyticCartesianToBearingRange])
@pytest.mark.parametrize("rotation", [0.0, 0.7, -2.5])
def test_inverse_bearing_range_equals_the_model_bit_for_bit(kind, rotation):
    rng = np.random.default_rng(11)
    model = _radar(kind, rotation)
    dets = _typed(rng, model, 300)
    # float vectors and other element types take the stock steps one by one
    dets.append(Detection(StateVector([0.3, 40.0]), timestamp=START, measurement_model=model))
    dets.append(Detection(StateVector([Bearing(0.3), 40]), timestamp=START, measurement_model=model))
    ours = initiator_births.inverse_bearing_range(model, dets)
    for det, vector in zip(dets, ours):
        stock = model.inverse_function(det)
        assert type(vector) is StateVector and vector.dtype == stock.dtype
        assert vector.shape == stock.shape and vector.tobytes() == stock.tobytes()


@pytest.mark.parametrize("kind", [CartesianToBearingRange, AnalyticCartesianToBearingRange,
                                  LinearGaussian])
def test_births_equal_the_stock_initiator_bit_for_bit(kind):
    rng = np.random.default_rng(12)
    if kind is LinearGaussian:
        model = LinearGaussian(ndim_state=4, mapping=(0, 2), noise_covar=np.diag([4.0, 9.0]))
        dets = [Detection(StateVector(rng.normal(0.0, 50.0, (2, 1))), timestamp=START,
                          measurement_model=model, metadata={"k": k}) for k in range(40)]
    else:
        model = _radar(kind)
        dets = _typed(rng, model, 40)
    prior = GaussianState(StateVector([0.0, 0.0, 0.0, 0.0]),
                          CovarianceMatrix(np.diag([100.0, 25.0, 100.0, 25.0])))
    inner = SimpleMeasurementInitiator(prior_state=prior, measurement_model=None)
    births = initiator_births.Births()
    for _ in range(2):  # the second scan from the linear cache / the fast track factory
        ours = {t.state.hypothesis.measurement.metadata["k"]: t
                for t in births(inner, dets, START)}
        stock = {t.state.hypothesis.measurement.metadata["k"]: t
                 for t in inner.initiate(set(dets), START)}
        assert ours.keys() == stock.keys()
        for k, track in stock.items():
            mine = ours[k]
            assert type(mine) is Track and len(mine) == 1
            assert type(mine.state) is type(track.state)
            assert mine.state.hypothesis.measurement is track.state.hypothesis.measurement
            assert mine.state.hypothesis.prediction is None
            assert mine.state.timestamp == track.state.timestamp
            assert mine.state_vector.tobytes() == track.state_vector.tobytes()
            assert mine.covar.tobytes() == track.covar.tobytes()
            assert mine.metadata == track.metadata == {"k": k}
            assert mine.metadatas == track.metadatas and mine.init_metadata == {}
            assert isinstance(mine.id, str) and mine.id != track.id
    assert births._track.fast


def test_track_factory_falls_back_when_the_constructor_differs(monkeypatch):
    factory = initiator_births._TrackFactory()
    state = GaussianState(StateVector([1.0]), CovarianceMatrix([[1.0]]), timestamp=START)
    real_init = Track.__init__

    def init(self, *args, **kwargs):  # a constructor that does more than the factory
        real_init(self, *args, **kwargs)
        self.extra = 1

    monkeypatch.setattr(Track, "__init__", init)
    first = factory(state)
    assert factory.fast is False and first.extra == 1
    assert factory(state).extra == 1
