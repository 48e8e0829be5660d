"""The new holding tracks of the array M-of-N initiator (``_initiator_births``, the core's
``initiator_births``) against Stone Soup's ``SimpleMeasurementInitiator``: the same tracks,
means bit for bit, covariances to the stated tolerances."""
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
from ctxmodels.stonesoup.models import AnalyticCartesianToBearingRange

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


#: Covariances against the stock initiator's, relative to each matrix's largest element:
#: bit for bit with a linear model (the core is given NumPy's H⁺, and with a selection matrix
#: every product is exact); rounding with the closed-form Jacobian (the core's SVD
#: pseudo-inverse against LAPACK's; measured ≤ 2.3e-15); and the finite difference's own
#: noise with Stone Soup's Jacobian (NumPy's arctan2 and the C library's atan2 differ in the
#: last bit for a few per cent of arguments, and the bearing row divides such differences by
#: steps of 1e-8 to 1e-6; measured ≤ 4.9e-5).
COVAR_RTOL = {LinearGaussian: 0.0, AnalyticCartesianToBearingRange: 1e-12,
              CartesianToBearingRange: 1e-3}


def _relative(a, b) -> float:
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))


def _by_k(tracks) -> dict:
    return {t.state.hypothesis.measurement.metadata["k"]: t for t in tracks}


@pytest.mark.parametrize("kind", [CartesianToBearingRange, AnalyticCartesianToBearingRange,
                                  LinearGaussian])
@pytest.mark.parametrize("rotation", [0.0, 0.7, -2.5])
def test_births_equal_the_stock_initiator(kind, rotation):
    """Means bit for bit, covariances to ``COVAR_RTOL``; every other field as stock."""
    rng = np.random.default_rng(12)
    if kind is LinearGaussian:
        model = LinearGaussian(ndim_state=4, mapping=(0, 2), noise_covar=np.diag([4.0, 9.0]))
        dets = [Detection(StateVector(rng.normal(0.0, 50.0, (2, 1))), timestamp=START,
                          measurement_model=model, metadata={"k": k}) for k in range(200)]
    else:
        model = _radar(kind, rotation)
        dets = [d for d in _typed(rng, model, 250) if d.state_vector[1, 0] != 0.0]
    prior = GaussianState(StateVector([1.0, -2.0, 3.0, 0.5]),
                          CovarianceMatrix(np.diag([100.0, 25.0, 100.0, 25.0]) + 0.5))
    inner = SimpleMeasurementInitiator(prior_state=prior, measurement_model=None,
                                       diag_load=0.25)
    births = initiator_births.Births()
    worst = 0.0
    for _ in range(2):  # the second scan from the cached core model / the fast track factory
        ours, stock = _by_k(births(inner, dets, START)), _by_k(inner.initiate(set(dets), START))
        assert ours.keys() == stock.keys() and len(ours) == len(dets)
        for k, track in stock.items():
            mine = ours[k]
            assert type(mine) is Track and len(mine) == 1
            assert type(mine.state) is type(track.state)
            assert mine.state.hypothesis.measurement is track.state.hypothesis.measurement
            assert mine.state.hypothesis.prediction is None
            assert mine.state.timestamp == track.state.timestamp
            assert type(mine.state_vector) is StateVector and mine.state_vector.dtype == np.float64
            assert mine.state_vector.tobytes() == track.state_vector.tobytes()
            assert type(mine.covar) is CovarianceMatrix and mine.covar.shape == (4, 4)
            worst = max(worst, _relative(mine.covar, track.covar))
            assert mine.metadata == track.metadata == {"k": k}
            assert mine.metadatas == track.metadatas and mine.init_metadata == {}
            assert isinstance(mine.id, str) and mine.id != track.id
    assert worst <= COVAR_RTOL[kind]
    assert births._track.fast


@pytest.mark.parametrize("kind", [CartesianToBearingRange, AnalyticCartesianToBearingRange])
def test_a_detection_at_the_sensor(kind):
    """ρ = 0: bearing has no derivative, both Jacobians fall back to the finite difference,
    which there differences atan2 of rounding noise: the stock covariance is that noise too.
    The mean is the stock one to the bit, the covariance finite, symmetric (to rounding,
    as the stock one) and positive semi-definite."""
    model = _radar(kind, 0.7)
    det = Detection(StateVector([Bearing(0.4), 0.0]), timestamp=START, measurement_model=model)
    prior = GaussianState(StateVector([0.0] * 4), CovarianceMatrix(np.diag([1.0, 4.0, 1.0, 4.0])))
    inner = SimpleMeasurementInitiator(prior_state=prior, measurement_model=None)
    (mine,), (stock,) = initiator_births.Births()(inner, [det], START), inner.initiate({det}, START)
    assert mine.state_vector.tobytes() == stock.state_vector.tobytes()
    covar = np.asarray(mine.covar)
    assert np.all(np.isfinite(covar)) and _relative(covar, covar.T) <= 1e-12
    assert np.linalg.eigvalsh(covar).min() >= -1e-9 * np.abs(covar).max()


def test_mixed_scan_runs_the_core_where_it_can_and_the_stock_code_elsewhere(monkeypatch):
    """Two bearing–range models (equal values in different objects are one), a linear model
    of the same measurement size, detections the core cannot read (an int range), a
    model the core does not take, and a non-finite detection (the core refuses it, the
    stock code decides): the same tracks as the stock initiator, and one core call."""
    from stonesoup.models.measurement.nonlinear import CartesianToElevationBearingRange
    rng = np.random.default_rng(5)
    radar, twin, other = (_radar(AnalyticCartesianToBearingRange, 0.7),
                          _radar(AnalyticCartesianToBearingRange, 0.7),
                          _radar(AnalyticCartesianToBearingRange, -1.2))
    linear = LinearGaussian(ndim_state=4, mapping=(0, 2), noise_covar=np.diag([4.0, 9.0]))
    dets = _typed(rng, radar, 6) + _typed(rng, twin, 4) + _typed(rng, other, 3)
    dets += [Detection(StateVector(rng.normal(0.0, 50.0, (2, 1))), timestamp=START,
                       measurement_model=linear) for _ in range(3)]
    dets.append(Detection(StateVector([Bearing(0.3), 40]), timestamp=START, measurement_model=radar))
    elevation = CartesianToElevationBearingRange(ndim_state=6, mapping=(0, 2, 4),
                                                 noise_covar=np.eye(3))
    for k, det in enumerate(dets):
        det.metadata = {"k": k}
    calls = []
    real = initiator_births._core.initiator_births
    monkeypatch.setattr(initiator_births._core, "initiator_births",
                        lambda *a, **kw: calls.append(len(a[1])) or real(*a, **kw))
    prior = GaussianState(StateVector([0.0] * 4), CovarianceMatrix(np.diag([9.0, 4.0, 9.0, 4.0])))
    inner = SimpleMeasurementInitiator(prior_state=prior, measurement_model=None)
    ours, stock = (_by_k(initiator_births.Births()(inner, dets, START)),
                   _by_k(inner.initiate(set(dets), START)))
    assert ours.keys() == stock.keys() == set(range(len(dets)))
    for k in stock:
        assert ours[k].state_vector.tobytes() == stock[k].state_vector.tobytes()
        assert _relative(ours[k].covar, stock[k].covar) <= 1e-12
    assert calls == [len(dets) - 1]  # the int range ran the stock code
    # a model the core does not take: the stock code, the same numbers
    det6 = Detection(StateVector([0.1, 0.2, 30.0]), timestamp=START, measurement_model=elevation)
    prior6 = GaussianState(StateVector([0.0] * 6), CovarianceMatrix(np.eye(6)))
    inner6 = SimpleMeasurementInitiator(prior_state=prior6, measurement_model=None)
    (mine,), (theirs,) = initiator_births.Births()(inner6, [det6], START), inner6.initiate({det6}, START)
    assert mine.state_vector.tobytes() == theirs.state_vector.tobytes()
    assert mine.covar.tobytes() == theirs.covar.tobytes() and len(calls) == 1
    # a non-finite detection: the core refuses the call, the stock initiator runs (and fails)
    bad = Detection(StateVector([Bearing(0.3), np.inf]), timestamp=START, measurement_model=radar)
    for initiate in (initiator_births.Births(), lambda i, d, t: i.initiate(set(d), t)):
        with np.errstate(all="ignore"), pytest.raises(np.linalg.LinAlgError):
            initiate(inner, [bad], START)


def test_core_births_errors_name_the_argument():
    from ctxmodels import _core
    model = _core.MeasurementModel.linear(np.eye(2, 4), np.eye(2))
    z, index = np.zeros((2, 2)), np.zeros(2, dtype=np.int64)
    mean, covar = np.zeros(4), np.eye(4)
    cases = [
        (([model], np.zeros((2, 3)), index, mean, covar), "detections"),
        (([model], z, np.zeros(3, dtype=np.int64), mean, covar), "model_index"),
        (([model], z, np.array([0, 1]), mean, covar), "model_index"),
        (([model], z, np.array([0, -1]), mean, covar), "model_index"),
        (([model], z, index, mean, np.eye(3)), "prior_covar"),
        (([model], z, index, np.full(4, np.nan), covar), "prior_mean"),
        (([model], np.full((2, 2), np.inf), index, mean, covar), "detections"),
        (([], z, index, mean, covar), "models"),
        (([_core.MeasurementModel.linear(np.eye(2, 3), np.eye(2))], z, index, mean, covar),
         "model"),
    ]
    for args, argument in cases:
        with pytest.raises(ValueError, match=argument):
            _core.initiator_births(*args)
    with pytest.raises(ValueError, match="diag_load"):
        _core.initiator_births([model], z, index, mean, covar, float("nan"))
    with pytest.raises(ValueError, match="pseudo_inverse"):
        _core.MeasurementModel.linear(np.eye(2, 4), np.eye(2), pseudo_inverse=np.eye(2))
    with pytest.raises(ValueError, match="inverse_rotation_matrix"):
        _core.MeasurementModel.bearing_range((0, 2), (0.0, 0.0), np.eye(3), np.eye(2),
                                                 inverse_rotation_matrix=np.full((3, 3), np.nan))
    singular = _core.MeasurementModel.bearing_range((0, 2), (0.0, 0.0), np.zeros((3, 3)),
                                                        np.eye(2))
    with pytest.raises(ValueError, match="rotation_matrix"):
        _core.initiator_births([singular], np.array([[0.1, 5.0]]), np.zeros(1, dtype=np.int64),
                               mean, covar)
    # empty scans are fine
    means, covars = _core.initiator_births([model], np.zeros((0, 2)), np.zeros(0, dtype=np.int64),
                                           mean, covar)
    assert means.shape == (0, 4) and covars.shape == (0, 4, 4)


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


def test_a_rotation_out_of_the_plane_raises_the_stock_error():
    """A bearing–range model rolled or pitched has no inverse function in Stone Soup: the
    births run the stock code, which raises its RuntimeError."""
    model = _radar(CartesianToBearingRange)
    model.rotation_offset = StateVector([0.1, 0.0, 0.7])
    det = Detection(StateVector([Bearing(0.3), 40.0]), timestamp=START, measurement_model=model)
    prior = GaussianState(StateVector([0.0] * 4), CovarianceMatrix(np.eye(4)))
    inner = SimpleMeasurementInitiator(prior_state=prior, measurement_model=None)
    for initiate in (initiator_births.Births(), lambda i, d, t: i.initiate(set(d), t)):
        with pytest.raises(RuntimeError, match="2D"):
            initiate(inner, [det], START)

