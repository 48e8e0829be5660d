r"""Batched Gaussian maths behind the array paths' Stone Soup side: the fast GNN association
(:class:`~ctxmodels.stonesoup.FastGNNWith2DAssignment`) and the array JPDA initiator, and
the object factories the array trackers build their states with. For :math:`N` states
with means :math:`x_n` and covariances :math:`P_n`:

Prediction (Kalman predictor, linear Gaussian transition, linear control model, no control
input), per distinct time step :math:`\Delta t`:

.. math::
    x_{n|k-1} = F(\Delta t)\,x_n + B\,0, \qquad
    P_{n|k-1} = F(\Delta t)\,P_n\,F(\Delta t)^T + Q(\Delta t) + B\,\Gamma\,B^T

Measurement prediction for a measurement model :math:`h` with noise :math:`R`:

.. math::
    \hat z_n = h(x_{n|k-1}),\quad H_n = \partial h/\partial x\,|_{x_{n|k-1}},\quad
    \Upsilon_n = P_{n|k-1} H_n^T,\quad S_n = H_n \Upsilon_n + R

with :math:`H_n` the model matrix for a :class:`~stonesoup.models.measurement.linear.LinearGaussian`
model and, for :class:`~stonesoup.models.measurement.nonlinear.CartesianToBearingRange` under
an :class:`~stonesoup.updater.kalman.ExtendedKalmanUpdater`, Stone Soup's own forward
finite-difference Jacobian, reproduced operation for operation (step
:math:`\delta_i = \max(10^8\,\mathrm{spacing}(x_i), 10^{-8})`, bearing differences wrapped to
:math:`[-\pi, \pi)`): that Jacobian carries round-off up to :math:`10^{-4}` relative, so matching
the stock filter to better than that needs the same floating-point operations, not an
analytic Jacobian. For
:class:`~ctxmodels.stonesoup.models.AnalyticCartesianToBearingRange` it is that model's
closed-form Jacobian, computed for all components by the elementwise code the model runs for
one (so bit for bit its ``jacobian``). Other models fall back to the stock updater's
``predict_measurement`` per component (still one call per component, not per pair).

Stacked ``matmul`` calls run the same BLAS kernel per matrix as the stock single-matrix
products, so predicted means are bit-for-bit the stock ones.

Over 400 lines because the prediction, the measurement models' batches and the factories
that turn their rows into Stone Soup objects are read together by both array paths; each
piece is short.
"""
from __future__ import annotations

from collections.abc import Sequence
from typing import Any, NamedTuple

import numpy as np
from stonesoup.models.base import GaussianModel, LinearModel
from stonesoup.models.control.linear import LinearControlModel
from stonesoup.models.measurement.linear import LinearGaussian
from stonesoup.models.measurement.nonlinear import CartesianToBearingRange
from stonesoup.predictor.kalman import ExtendedKalmanPredictor, KalmanPredictor
from stonesoup.types.angle import Angle, Bearing
from stonesoup.types.array import CovarianceMatrix, StateVector
from stonesoup.types.prediction import GaussianMeasurementPrediction, GaussianStatePrediction
from stonesoup.types.track import Track
from stonesoup.updater.kalman import ExtendedKalmanUpdater, KalmanUpdater

from .._upstream import (TRACK_METADATAS, TRACK_STATES, check_measurement_model,
                         from_state_classes, has_setter, property_slot)
from .models import (
    AnalyticCartesianToBearingRange,
    bearing_range_jacobians,
    rotated_offsets,
)

_TWO_PI = 2.0 * np.pi

#: Updaters whose measurement prediction and Kalman update are reproduced here exactly.
KALMAN_UPDATERS = (KalmanUpdater, ExtendedKalmanUpdater)


def mod_bearing(x):
    r"""Wrap to :math:`[-\pi, \pi)` with the same floating-point operations as Stone Soup's
    ``mod_bearing`` (:math:`((x + \pi) \bmod 2\pi) - \pi`), elementwise."""
    return (x + np.pi) % _TWO_PI - np.pi


# --- gathering -----------------------------------------------------------------------------
def gaussian_arrays(states: Sequence) -> tuple[np.ndarray, np.ndarray]:
    """Means ``(N, D, 1)`` and covariances ``(N, D, D)`` (float64) of Gaussian states."""
    if not states:
        return np.empty((0, 0, 1)), np.empty((0, 0, 0))
    try:
        means = np.array([s.state_vector for s in states], dtype=np.float64)
        covars = np.array([s.covar for s in states], dtype=np.float64)
    except ValueError:
        raise ValueError("states: every state needs an (D, 1) state vector and a (D, D) "
                         "covariance of one common dimension D") from None
    if means.ndim != 3 or means.shape[2] != 1 or covars.shape != means.shape[:2] + means.shape[1:2]:
        raise ValueError("states: every state needs an (D, 1) state vector and a (D, D) "
                         "covariance of one common dimension D")
    return means, covars


def vector_views(means: np.ndarray) -> list:
    """One :class:`StateVector` view per row of ``(N, D, 1)`` means (no copies)."""
    return [row.view(StateVector) for row in means]


def covariance_views(covars: np.ndarray) -> list:
    """One :class:`CovarianceMatrix` view per ``(D, D)`` block of ``(N, D, D)`` covariances."""
    return [block.view(CovarianceMatrix) for block in covars]


# --- object construction ------------------------------------------------------------------------
class ObjectFactory:
    """Builds instances of a Stone Soup :class:`~stonesoup.base.Base` class as its
    constructor does, without its per-Property Python machinery.

    A scan creates thousands of predictions, hypotheses and components; Stone Soup's
    constructor costs several microseconds each, most of the fast path's time. A Base
    constructor stores each Property in the instance's ``_property_<name>`` slot, applying
    defaults and default factories; the factory does the same directly. That is only valid
    for classes whose ``__init__`` chain does nothing else for the argument types passed
    (states already holding a ``StateVector``/``CovarianceMatrix``, no ``prior``), so on
    first use it builds one object both ways from ``probe`` arguments and falls back to the
    real constructor for good if the two differ in any slot.
    """

    def __init__(self, cls: type, probe: dict):
        self.cls = cls
        self._slots = {}
        self._constants = {}
        self._factories = []
        usable = True
        for name, prop in cls.properties.items():
            if has_setter(prop) or prop.readonly:
                usable = False
            key = property_slot(name)
            self._slots[name] = key
            if prop.default_factory is not prop.empty:
                self._factories.append((key, prop.default, prop.default_factory))
            elif prop.default is not prop.empty:
                self._constants[key] = prop.default
        self.fast = usable and self._agrees(probe)

    def _build(self, kwargs):
        obj = object.__new__(self.cls)
        slots = dict(self._constants)
        names = self._slots
        for name, value in kwargs.items():
            slots[names[name]] = value
        for key, default, factory in self._factories:
            if slots.get(key, default) is default:
                slots[key] = factory()
        obj.__dict__ = slots
        return obj

    def _agrees(self, probe) -> bool:
        try:
            real = self.cls(**probe)
            built = self._build(probe)
        except Exception:  # noqa: BLE001 - any failure: use the real constructor
            return False
        if real.__dict__.keys() != built.__dict__.keys():
            return False
        for key, value in real.__dict__.items():
            other = built.__dict__[key]
            if value is other:
                continue
            if type(value) is not type(other) or not isinstance(value, (dict, list)) \
                    or value != other:
                return False
        return True

    def __call__(self, **kwargs):
        """An instance with these Properties (callers pass every required one)."""
        if self.fast:
            return self._build(kwargs)
        return self.cls(**kwargs)

    def maker(self, *names: str):
        """A function ``make(*values)`` building instances from positional values of the
        Properties ``names`` (every required one; the others at their defaults) — one dict
        per object, for loops that build thousands."""
        keys = [self._slots[name] for name in names]
        constants = {k: v for k, v in self._constants.items() if k not in keys}
        if not self.fast or any(key not in keys for key, _, _ in self._factories):
            return lambda *values: self(**dict(zip(names, values)))
        new, cls = object.__new__, self.cls
        if len(keys) == 3:  # (a prediction per track and scan: the slots set one by one)
            template = dict.fromkeys(keys)  # (as make orders them: these, then the defaults)
            template.update(constants)
            first, second, third = keys

            def make3(a, b, c):
                obj = new(cls)
                obj.__dict__ = slots = template.copy()
                slots[first], slots[second], slots[third] = a, b, c
                return obj
            return make3

        def make(*values):
            obj = new(cls)
            slots = dict(zip(keys, values))
            slots.update(constants)
            obj.__dict__ = slots
            return obj
        return make


# --- tracks ---------------------------------------------------------------------------------
_object_attribute = object.__getattribute__


def plain_track_lists(track):
    """``(states, metadatas)`` of a plain :class:`~stonesoup.types.track.Track` (exactly that
    type), read from its ``__dict__``; None for any other track. Every attribute read on a
    track goes through Stone Soup's ``StateMutableSequence.__getattribute__`` (in Python:
    the track, then its last state), which costs more than the work around it in loops
    that touch every track every scan."""
    if type(track) is not Track:
        return None
    fields = _object_attribute(track, "__dict__")
    states, metadatas = fields.get(TRACK_STATES), fields.get(TRACK_METADATAS)
    if type(states) is not list or type(metadatas) is not list:
        return None
    return states, metadatas


# --- Stone Soup's from_state type selection, resolved once per type ---------------------------
_TARGET_CACHE: dict = {}


def from_state_target(base: type, state_type: type) -> type:
    """The class ``base.from_state(state)`` builds for a ``state`` of ``state_type`` (Stone
    Soup's :class:`~stonesoup.types.state.CreatableFromState` lookup along the MRO), cached
    per type pair."""
    key = (base, state_type)
    target = _TARGET_CACHE.get(key)
    if target is None:
        mapping = from_state_classes(base)
        try:
            target = mapping[next(t for t in state_type.mro() if t in mapping)]
        except StopIteration:
            raise TypeError(f"{base.__name__} type not defined for {state_type.__name__}") from None
        _TARGET_CACHE[key] = target
    return target


# --- prediction ------------------------------------------------------------------------------
def supports_predictor(predictor) -> bool:
    """Whether :func:`predict_batch` reproduces ``predictor.predict`` exactly."""
    model = getattr(predictor, "transition_model", None)
    if type(predictor) not in (KalmanPredictor, ExtendedKalmanPredictor):
        return False
    if not (isinstance(model, LinearModel) and isinstance(model, GaussianModel)):
        return False
    if type(predictor) is ExtendedKalmanPredictor and type(model).function is not LinearModel.function:
        return False  # the EKF predictor calls model.function, which a subclass may redefine
    return type(predictor.control_model) is LinearControlModel


def predict_batch(predictor, priors: Sequence, means: np.ndarray, covars: np.ndarray,
                  timestamp) -> tuple[np.ndarray, np.ndarray]:
    r"""Kalman prediction of all ``priors`` to ``timestamp``, grouped by time step.

    ``means``/``covars`` are the priors' stacked arrays (:func:`gaussian_arrays`). Calls the
    transition and control models exactly as :meth:`KalmanPredictor.predict` does (once per
    distinct :math:`\Delta t`), so errors for missing timestamps are the stock ones.
    """
    n = len(priors)
    pred_means = np.empty_like(means)
    pred_covars = np.empty_like(covars)
    groups: dict = {}
    for i, prior in enumerate(priors):
        if timestamp is None or prior.timestamp is None:
            interval = None
        else:
            interval = timestamp - prior.timestamp
        groups.setdefault(interval, []).append(i)
    model = predictor.transition_model
    control = predictor.control_model
    for interval, members in groups.items():
        idx = np.asarray(members) if len(members) < n else slice(None)
        prior = priors[members[0]]
        matrix = np.asarray(model.matrix(time_interval=interval), dtype=np.float64)
        offset = control.function(None, prior=prior, time_interval=interval)
        # (F x) + B 0, as the predictor adds them
        pred_means[idx] = (matrix[np.newaxis] @ means[idx]) + np.asarray(offset, dtype=np.float64)
        process = np.asarray(model.covar(time_interval=interval), dtype=np.float64)
        ctrl = control.matrix(control_input=None, prior=prior, time_interval=interval)
        ctrl_noise = ctrl @ control.control_noise @ ctrl.T
        pred_covars[idx] = ((matrix[np.newaxis] @ covars[idx]) @ matrix.T[np.newaxis]
                            + process) + ctrl_noise
    return pred_means, pred_covars


# --- measurement prediction ---------------------------------------------------------------------
class MeasurementBatch(NamedTuple):
    r"""Measurement prediction of :math:`N` predicted states under one measurement model."""

    model: Any
    #: predicted measurements ``(N, m)`` (angles as their wrapped float values)
    means: np.ndarray
    #: innovation covariances :math:`S_n`, ``(N, m, m)``
    covars: np.ndarray
    #: cross covariances :math:`P H^T`, ``(N, D, m)``
    cross_covars: np.ndarray
    #: measurement matrices / Jacobians :math:`H_n`, ``(N, m, D)``; ``None`` when unknown
    matrices: np.ndarray | None
    #: ``{row: Angle subclass}`` for rows whose stock predicted measurement holds angles
    angle_rows: dict
    #: stock measurement-prediction objects when they were computed by the stock updater
    objects: list | None

    def typed_vector(self, n: int) -> StateVector:
        """The stock-typed predicted measurement vector of state ``n`` (angles as
        :class:`~stonesoup.types.angle.Angle` objects, as the stock model returns them)."""
        if not self.angle_rows:
            return self.means[n].reshape(-1, 1).view(StateVector)
        column = np.empty((self.means.shape[1], 1), dtype=object)
        for row, value in enumerate(self.means[n].tolist()):
            angle = self.angle_rows.get(row)
            column[row, 0] = value if angle is None else angle(value)
        return column.view(StateVector)

    def measurement_prediction(self, n: int, timestamp, typed_vector=None):
        """The :class:`GaussianMeasurementPrediction` the stock updater returns for state
        ``n`` (its own object when the stock updater computed it)."""
        if self.objects is not None:
            return self.objects[n]
        vector = self.typed_vector(n) if typed_vector is None else typed_vector
        return _MEASUREMENT_PREDICTION(
            state_vector=vector, covar=self.covars[n].view(CovarianceMatrix),
            timestamp=timestamp, cross_covar=self.cross_covars[n].view(CovarianceMatrix))


_MEASUREMENT_PREDICTION = ObjectFactory(GaussianMeasurementPrediction, dict(
    state_vector=StateVector([0.0]), covar=CovarianceMatrix([[1.0]]), timestamp=None,
    cross_covar=CovarianceMatrix([[1.0]])))


def _linear_batch(model, means, covars):
    matrix = np.asarray(model.matrix(), dtype=np.float64)
    pred = (matrix[np.newaxis] @ means)[..., 0]           # H x, as LinearModel.function
    cross = covars @ matrix.T[np.newaxis]                  # P H^T
    innov = (matrix[np.newaxis] @ cross) + np.asarray(model.covar(), dtype=np.float64)
    return pred, innov, cross, np.broadcast_to(matrix, (len(means),) + matrix.shape)


def _bearing_range_function(model, states):
    """``CartesianToBearingRange._function`` on ``(D, K)`` float states: (bearing, range)."""
    mapping = model.mapping
    offset = model.translation_offset
    xyz = np.array([states[mapping[0], :] - offset[0, 0],
                    states[mapping[1], :] - offset[1, 0],
                    np.zeros(states.shape[1])])
    rotated = model.rotation_matrix @ xyz
    rho = np.sqrt(rotated[0, :] ** 2 + rotated[1, :] ** 2)
    phi = np.arctan2(rotated[1, :], rotated[0, :])
    return mod_bearing(0.0 + phi), 0.0 + rho


def _bearing_range_batch(model, means, covars):
    n, ndim, _ = means.shape
    x = means[..., 0]
    # Stone Soup's finite-difference step, per state and dimension
    delta = 1e8 * np.spacing(x)
    delta[delta < 1e-8] = 1e-8
    # columns 0..D-1: x + delta_i e_i; column D: x (the same tile + eye product as stock)
    perturbed = (np.repeat(x[:, :, np.newaxis], ndim + 1, axis=2)
                 + np.eye(ndim, ndim + 1)[np.newaxis] * delta[:, :, np.newaxis])
    flat = perturbed.transpose(1, 0, 2).reshape(ndim, n * (ndim + 1))
    bearing, rng = _bearing_range_function(model, flat)
    bearing = bearing.reshape(n, ndim + 1)
    rng = rng.reshape(n, ndim + 1)
    jac = np.empty((n, 2, ndim))
    jac[:, 0, :] = mod_bearing(bearing[:, :ndim] - bearing[:, ndim:]) / delta
    jac[:, 1, :] = (rng[:, :ndim] - rng[:, ndim:]) / delta
    # the predicted measurement rotates one column per state, as model.function(state)
    # does: a (3, 3) @ (3, 1) product, whose kernel may round unlike the wide one above
    mapping, offset = model.mapping, model.translation_offset
    xyz = np.zeros((n, 3, 1))
    xyz[:, 0, 0] = x[:, mapping[0]] - offset[0, 0]
    xyz[:, 1, 0] = x[:, mapping[1]] - offset[1, 0]
    rotated = (np.asarray(model.rotation_matrix)[np.newaxis] @ xyz)[..., 0]
    pred = np.stack([mod_bearing(0.0 + np.arctan2(rotated[:, 1], rotated[:, 0])),
                     0.0 + np.sqrt(rotated[:, 0] ** 2 + rotated[:, 1] ** 2)], axis=1)
    cross = covars @ jac.transpose(0, 2, 1)
    innov = (jac @ cross) + np.asarray(model.covar(), dtype=np.float64)
    return pred, innov, cross, jac


def _bearing_range_prediction(rotated):
    """(bearing, range) ``(N, 2)`` from sensor-frame points, with the stock function's
    operations (``cart2pol``, then the wrap of the typed ``Bearing`` sum)."""
    return np.stack([mod_bearing(0.0 + np.arctan2(rotated[:, 1], rotated[:, 0])),
                     0.0 + np.sqrt(rotated[:, 0] ** 2 + rotated[:, 1] ** 2)], axis=1)


def _analytic_bearing_range_batch(model, means, covars, timestamp):
    """:class:`AnalyticCartesianToBearingRange`: the model's closed-form Jacobian for all
    states at once (the same elementwise code its ``jacobian`` runs for one state); a state
    at the sensor (ρ = 0) takes the model's own finite-difference fallback."""
    ndim = means.shape[1]
    x = means[..., 0]
    rotation = model.rotation_matrix
    if len(x):
        rotated = rotated_offsets(rotation, model.mapping, model.translation_offset, x)
    else:
        rotated = np.empty((0, 3))
    jac, at_sensor = bearing_range_jacobians(rotation, model.mapping, rotated, ndim)
    for i in np.flatnonzero(at_sensor):
        state = GaussianStatePrediction(means[i].view(StateVector),
                                        covars[i].view(CovarianceMatrix), timestamp=timestamp)
        jac[i] = model.jacobian(state)
    pred = _bearing_range_prediction(rotated)
    cross = covars @ jac.transpose(0, 2, 1)
    innov = (jac @ cross) + np.asarray(model.covar(), dtype=np.float64)
    return pred, innov, cross, jac


def _angle_rows_of(vector) -> dict:
    rows = {}
    for row, value in enumerate(np.asarray(vector, dtype=object).ravel()):
        if isinstance(value, Angle):
            rows[row] = type(value)
    return rows


def measurement_batch(updater, model, means: np.ndarray, covars: np.ndarray,
                      timestamp=None) -> MeasurementBatch:
    r"""Measurement prediction of all predicted states under ``model`` (``None``: the
    updater's own model), equal to ``updater.predict_measurement`` state by state.

    Linear Gaussian models and the bearing–range model are computed in stacked arrays for
    Kalman/extended Kalman updaters; any other updater or model calls the stock
    ``predict_measurement`` once per state.
    """
    model = check_measurement_model(updater, model)
    kind = type(updater)
    if kind in KALMAN_UPDATERS and type(model) is LinearGaussian:
        pred, innov, cross, jac = _linear_batch(model, means, covars)
        return MeasurementBatch(model, pred, innov, cross, jac, {}, None)
    if kind is ExtendedKalmanUpdater and type(model) is CartesianToBearingRange \
            and len(model.mapping) == 2:
        pred, innov, cross, jac = _bearing_range_batch(model, means, covars)
        return MeasurementBatch(model, pred, innov, cross, jac, {0: Bearing}, None)
    if kind is ExtendedKalmanUpdater and type(model) is AnalyticCartesianToBearingRange:
        pred, innov, cross, jac = _analytic_bearing_range_batch(model, means, covars, timestamp)
        return MeasurementBatch(model, pred, innov, cross, jac, {0: Bearing}, None)
    objects = [updater.predict_measurement(
        GaussianStatePrediction(m.view(StateVector), c.view(CovarianceMatrix), timestamp=timestamp),
        model) for m, c in zip(means, covars)]
    if not objects:
        empty = np.empty((0, 0))
        return MeasurementBatch(model, empty, empty[..., None], empty[..., None], None, {}, [])
    pred = np.array([np.asarray(o.state_vector, dtype=np.float64).ravel() for o in objects])
    innov = np.array([o.covar for o in objects], dtype=np.float64)
    cross = np.array([o.cross_covar for o in objects], dtype=np.float64)
    return MeasurementBatch(model, pred, innov, cross, None,
                            _angle_rows_of(objects[0].state_vector), objects)


# --- angle-aware differences ------------------------------------------------------------------
def detection_vectors(detections: Sequence) -> tuple[np.ndarray, list]:
    """Measurement vectors ``(M, m)`` (float) and, per detection, ``{row: Angle subclass}``
    of its angle-typed elements."""
    if not detections:
        return np.empty((0, 0)), []
    vectors = [d.state_vector for d in detections]
    values = np.array(vectors, dtype=np.float64)[..., 0]
    kinds = [_angle_rows_of(v) if v.dtype == object else {} for v in vectors]
    return values, kinds


def wrap_plan(angle_rows: dict, kinds: list, ndim_meas: int) -> list:
    """For ``z − ẑ`` as Stone Soup computes it on typed vectors: per measurement row, the
    Angle class that wraps it and a mask of the detections it applies to. The detection's
    own angle type takes precedence (its ``__sub__`` runs first), else the prediction's."""
    plan = []
    for row in range(ndim_meas):
        classes = [kind.get(row, angle_rows.get(row)) for kind in kinds]
        for cls in {c for c in classes if c is not None}:
            mask = np.array([c is cls for c in classes])
            plan.append((row, cls, mask))
    return plan


def apply_wrap(diff: np.ndarray, plan: list) -> np.ndarray:
    """Wrap the angle rows of ``diff`` (``(..., M, m)``, detections on the second-last
    axis) in place, per :func:`wrap_plan`."""
    for row, cls, mask in plan:
        diff[..., mask, row] = cls.mod_angle(diff[..., mask, row])
    return diff
