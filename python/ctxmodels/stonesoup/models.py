r"""Stone Soup's measurement and transition models as ctxmodels uses them: a bearing–range
measurement model with its exact Jacobian, the scan cores' form of a measurement model, a
transition model that computes F(Δt) and Q(Δt) once per interval, and a prediction's
control terms kept per interval.

**The exact Jacobian.** Stone Soup's
:class:`~stonesoup.models.measurement.nonlinear.CartesianToBearingRange` has no Jacobian of
its own: an extended Kalman filter gets one from a forward finite difference of the model
function, with a step of :math:`\max(10^8\,\mathrm{spacing}(x_i), 10^{-8})` per state
element. Such a derivative is only good to about :math:`10^{-8}` relative, and that error is
not smooth in the state: moving the state by one unit in the last place moves the difference
quotient by about :math:`10^{-8}` (far more on small entries). An EKF built on it therefore
returns posteriors that depend on the last bit of its inputs, so two correct implementations
of the same filter (NumPy with BLAS, or a compiled core) that round one operation differently
drift apart at the :math:`10^{-8}` level and cannot be compared to a tight tolerance. The
bearing–range Jacobian has a short closed form; :class:`AnalyticCartesianToBearingRange`
uses it, and is otherwise the stock model. :func:`core_measurement_model` gives the Rust
scan cores' form of a measurement model.

**The cached transition.** Stone Soup rebuilds the transition matrix and noise covariance of
a combined model (a ``scipy.linalg.block_diag`` per call) for every prediction of every track
and component. Asynchronous sensors produce only a handful of distinct scan intervals, so
caching per Δt removes that cost without changing a single number: the cached arrays are the
ones the stock model returns for that interval
(:class:`CachedCombinedLinearGaussianTransitionModel`). :class:`ControlTerms` does the same
for a Kalman prediction's control terms (the array JPDA and initiator ask it whether there
are any).
"""
from __future__ import annotations

import operator

import numpy as np
from stonesoup.models.control.linear import LinearControlModel
from stonesoup.models.measurement.linear import LinearGaussian
from stonesoup.models.measurement.nonlinear import CartesianToBearingRange
from stonesoup.models.transition.linear import CombinedLinearGaussianTransitionModel
from stonesoup.updater.kalman import ExtendedKalmanUpdater

from .. import _core
from ..model_key import compared_by_value


def _checked_mapping(mapping) -> None:
    """Raise :class:`ValueError` unless ``mapping`` is two integer state indices."""
    try:
        size = len(mapping)
    except TypeError:
        size = None
    if size != 2:
        raise ValueError(
            "mapping: AnalyticCartesianToBearingRange needs exactly two state indices "
            f"(the x and y position elements), got {mapping!r}")
    try:
        for index in mapping:
            operator.index(index)
    except TypeError:
        raise ValueError(
            f"mapping: the state indices must be integers, got {mapping!r}") from None


def rotated_offsets(rotation: np.ndarray, mapping, offset, vectors: np.ndarray) -> np.ndarray:
    r"""Sensor-frame coordinates :math:`r = R\,(x_{m_0} - t_0,\ x_{m_1} - t_1,\ 0)^T` of
    states ``vectors`` ``(N, D)``, as ``(N, 3)``.

    One :math:`3 \times 3` by :math:`3 \times 1` product per state, the product the stock
    model function forms for a single state, so :math:`r` carries the same rounding."""
    xyz = np.zeros((len(vectors), 3, 1))
    xyz[:, 0, 0] = vectors[:, mapping[0]] - offset[0, 0]
    xyz[:, 1, 0] = vectors[:, mapping[1]] - offset[1, 0]
    return (np.asarray(rotation, dtype=np.float64)[np.newaxis] @ xyz)[..., 0]


def bearing_range_jacobians(rotation: np.ndarray, mapping, rotated: np.ndarray,
                            ndim_state: int) -> tuple[np.ndarray, np.ndarray]:
    r"""Closed-form bearing–range Jacobians at sensor-frame points ``rotated`` (``(N, 2)``
    or ``(N, 3)``, from :func:`rotated_offsets`).

    Returns the Jacobians ``(N, 2, ndim_state)`` and a boolean mask ``(N,)`` of the points
    at the sensor (:math:`\rho = 0`), whose rows are not finite and must be replaced.
    Elementwise operations only, so a point's Jacobian does not depend on how many others
    are computed with it.
    """
    r0 = rotated[:, 0]
    r1 = rotated[:, 1]
    with np.errstate(divide="ignore", invalid="ignore"):
        rho = np.hypot(r0, r1)       # no overflow or underflow of r0² + r1²
        cos = r0 / rho               # unit line of sight in the sensor frame
        sin = r1 / rho
        jac = np.zeros((len(rotated), 2, ndim_state))
        for k, column in enumerate(mapping):
            along_x = rotation[0, k]     # ∂r0/∂x_{m_k}
            along_y = rotation[1, k]     # ∂r1/∂x_{m_k}
            # a repeated index (two names for one element) gets both contributions
            jac[:, 0, column] += (cos * along_y - sin * along_x) / rho
            jac[:, 1, column] += cos * along_x + sin * along_y
    return jac, rho == 0


@compared_by_value
class AnalyticCartesianToBearingRange(CartesianToBearingRange):
    r""":class:`~stonesoup.models.measurement.nonlinear.CartesianToBearingRange` whose
    :meth:`jacobian` is exact instead of a finite difference.

    Same Properties, measurement function, inverse function and noise as the parent (so it
    serialises, pickles and converts detections exactly as the parent does). Only a 2-D
    ``mapping`` (the :math:`x` and :math:`y` state indices) is supported; anything else is
    rejected at construction with a :class:`ValueError`.

    With translation :math:`t` (``translation_offset``) and rotation matrix :math:`R`
    (``rotation_matrix``, built from ``rotation_offset``), the model sees the target at

    .. math::
        r = R \begin{bmatrix} x_{m_0} - t_0 \\ x_{m_1} - t_1 \\ 0 \end{bmatrix},
        \qquad
        \phi = \operatorname{atan2}(r_1, r_0), \quad
        \rho = \sqrt{r_0^2 + r_1^2}.

    :math:`r` is linear in the state, :math:`\partial r_i / \partial x_{m_k} = R_{ik}`,
    and differentiating the polar coordinates gives
    :math:`\partial\phi/\partial r_0 = -r_1/\rho^2`,
    :math:`\partial\phi/\partial r_1 = r_0/\rho^2`,
    :math:`\partial\rho/\partial r_i = r_i/\rho`. By the chain rule, for :math:`k = 0, 1`

    .. math::
        \frac{\partial\phi}{\partial x_{m_k}} = \frac{r_0 R_{1k} - r_1 R_{0k}}{\rho^2},
        \qquad
        \frac{\partial\rho}{\partial x_{m_k}} = \frac{r_0 R_{0k} + r_1 R_{1k}}{\rho},

    and every other column of the :math:`2 \times n` Jacobian is zero. It is evaluated as
    :math:`(\hat u_0 R_{1k} - \hat u_1 R_{0k})/\rho` and :math:`\hat u_0 R_{0k} + \hat u_1
    R_{1k}` with the unit line of sight :math:`\hat u = r/\rho` and
    :math:`\rho = \operatorname{hypot}(r_0, r_1)`, a few units in the last place from the
    exact value at any range.

    At :math:`\rho = 0` (target at the sensor) bearing has no derivative; there the
    parent's finite-difference Jacobian is returned, which is finite.

    Why: the parent's finite difference carries :math:`\sim 10^{-8}` relative error that
    jumps when the state changes in its last bit, which makes an extended Kalman filter's
    output sensitive to round-off and keeps independent implementations from agreeing
    beyond about eight digits. The closed form is smooth in the state and accurate to
    round-off, so a 1-ulp change of the input changes the posterior by round-off only.
    """

    def __init__(self, *args, **kwargs):
        names = list(type(self).properties)
        position = names.index("mapping")
        if "mapping" in kwargs:
            _checked_mapping(kwargs["mapping"])
        elif len(args) > position:
            _checked_mapping(args[position])
        super().__init__(*args, **kwargs)

    def jacobian(self, state, **kwargs) -> np.ndarray:
        r"""The exact Jacobian :math:`\partial h/\partial x` at ``state`` (class docstring).

        Parameters
        ----------
        state : :class:`~stonesoup.types.state.State`
            A state with an :math:`(n, 1)` state vector.

        Returns
        -------
        :class:`numpy.ndarray` of shape (2, :math:`n`), float64
            Rows: bearing, range. The parent's finite-difference Jacobian if the target is
            at the sensor (:math:`\rho = 0`).
        """
        vector = np.asarray(state.state_vector, dtype=np.float64)
        if vector.ndim != 2 or vector.shape[1] != 1:
            raise ValueError(f"state: expected an (n, 1) state vector, got shape "
                             f"{vector.shape}")
        rotation = self.rotation_matrix
        rotated = rotated_offsets(rotation, self.mapping, self.translation_offset, vector.T)
        jac, at_sensor = bearing_range_jacobians(rotation, self.mapping, rotated,
                                                 vector.shape[0])
        if at_sensor[0]:
            return np.asarray(super().jacobian(state, **kwargs), dtype=np.float64)
        return jac[0]


def core_measurement_model(model, updater_kind=ExtendedKalmanUpdater):
    """The scan cores' :class:`ctxmodels._core.MeasurementModel` for a Stone Soup measurement
    model and the row of its bearing (or None), or ``(None, None)`` where the core does not
    compute what ``updater_kind`` would: a ``LinearGaussian``, or a 2-D
    ``CartesianToBearingRange`` (finite-difference Jacobian) or
    :class:`AnalyticCartesianToBearingRange` under an ``ExtendedKalmanUpdater``. The core is
    given the inverse of the measurement as Stone Soup computes it (NumPy's ``pinv`` of the
    matrix, ``inv`` of the rotation), so new tracks' means are Stone Soup's to the bit."""
    kind = type(model)
    if kind is LinearGaussian:
        matrix = np.ascontiguousarray(model.matrix(), dtype=np.float64)
        return _core.MeasurementModel.linear(
            matrix, np.ascontiguousarray(model.covar(), dtype=np.float64),
            pseudo_inverse=np.ascontiguousarray(np.linalg.pinv(matrix))), None
    if updater_kind is not ExtendedKalmanUpdater or len(getattr(model, "mapping", ())) != 2:
        return None, None
    if kind is CartesianToBearingRange:
        jacobian = "finite-difference"
    elif kind is AnalyticCartesianToBearingRange:
        jacobian = "analytic"
    else:
        return None, None
    offset = np.asarray(model.translation_offset, dtype=np.float64).ravel()
    rotation = np.ascontiguousarray(model.rotation_matrix, dtype=np.float64)
    if offset.size < 2 or rotation.shape != (3, 3):
        return None, None
    try:
        inverse = np.ascontiguousarray(np.linalg.inv(rotation), dtype=np.float64)
    except np.linalg.LinAlgError:
        inverse = None
    core = _core.MeasurementModel.bearing_range(
        (int(model.mapping[0]), int(model.mapping[1])), (float(offset[0]), float(offset[1])),
        rotation, np.ascontiguousarray(model.covar(), dtype=np.float64), jacobian,
        inverse_rotation_matrix=inverse)
    return core, 0


class CachedCombinedLinearGaussianTransitionModel(CombinedLinearGaussianTransitionModel):
    """:class:`~stonesoup.models.transition.linear.CombinedLinearGaussianTransitionModel`
    with F and Q memoised per ``time_interval`` (returned read-only, so a caller that tried
    to modify a shared array would fail loudly instead of corrupting later predictions)."""

    #: Distinct intervals kept; asynchronous scans make a few, a long run a few hundred.
    max_cached = 4096

    def _memo(self, kind, compute, kwargs):
        # A linear Gaussian model's F and Q depend on Δt only; predictors also pass the
        # `prior`, which they do not use. Anything else: no caching.
        for name in kwargs:
            if name != "time_interval" and name != "prior":
                return compute(**kwargs)
        cache = self.__dict__.setdefault("_cached_arrays", {})
        key = (kind, kwargs.get("time_interval"))
        value = cache.get(key)
        if value is None:
            value = compute(**kwargs)
            value.flags.writeable = False
            if len(cache) >= self.max_cached:
                cache.clear()
            cache[key] = value
        return value

    def matrix(self, **kwargs):
        return self._memo("F", super().matrix, kwargs)

    def covar(self, **kwargs):
        return self._memo("Q", super().covar, kwargs)

    def __getstate__(self):
        state = dict(self.__dict__)
        state.pop("_cached_arrays", None)
        return state


class ControlTerms:
    """The control model's contribution to a Kalman prediction (the offset
    ``control.function(None, …)`` and the noise ``B Q_u Bᵀ``), as the predictor computes
    them, memoised per time interval for the stock :class:`LinearControlModel` (whose
    matrix and noise do not depend on the prior; the models are immutable, as the cached
    transition model assumes); any other control model is called every time."""

    def __init__(self):
        self._cache: dict = {}
        self._answers: dict = {}  # the same keys -> (control, adds_input's answer)

    def adds_input(self, control, prior, interval) -> bool:
        """Whether the terms over ``interval`` are not all zero (as float64 arrays), the
        answer kept with the terms (the stock model's). ``prior``: the prior state, or a
        function returning it, called only when the answer is not kept."""
        key = None
        if type(control) is LinearControlModel:
            key = (id(control), id(control.control_matrix), id(control.control_noise), interval)
            found = self._answers.get(key)
            if found is not None and found[0] is control:
                return found[1]
        offset, noise = self(control, prior() if callable(prior) else prior, interval)
        answer = bool(np.asarray(offset, dtype=np.float64).any()
                      or np.asarray(noise, dtype=np.float64).any())
        if key is not None:
            if len(self._answers) >= 256:
                self._answers.clear()
            self._answers[key] = (control, answer)
        return answer

    def __call__(self, control, prior, interval):
        cacheable = type(control) is LinearControlModel
        if cacheable:
            key = (id(control), id(control.control_matrix), id(control.control_noise), interval)
            found = self._cache.get(key)
            if found is not None and found[0] is control:
                return found[1], found[2]
        offset = control.function(None, prior=prior, time_interval=interval)
        ctrl = control.matrix(control_input=None, prior=prior, time_interval=interval)
        noise = ctrl @ control.control_noise @ ctrl.T
        if cacheable:
            if len(self._cache) >= 256:
                self._cache.clear()
            self._cache[key] = (control, offset, noise)
        return offset, noise
