"""Array helpers of :class:`~ctxmodels.stonesoup.array_initiator.ArrayMultiMeasurementInitiator`:
whole-scan computations whose results equal (bit for bit, where they feed a state) the
Stone Soup computations they replace.
"""
from __future__ import annotations

import numpy as np
from stonesoup.models.control.linear import LinearControlModel
from stonesoup.functions import mod_bearing
from stonesoup.types.angle import Bearing

from .. import _core
from .fast import detection_vectors, wrap_plan
from .fast_association import SCREEN_MARGIN, _measurement_prediction, screen_pairs


def screen(batch, dets, missed_distance: float, squared: bool) -> np.ndarray:
    """:func:`~ctxmodels.stonesoup.fast_association.screen_pairs` (the ``(N, K)`` mask of the
    pairs that may pass the gate) in one core call (``_core.jpda_screen``: LU inverses of
    the innovation covariances, cheaper than the stock pseudo-inverses; the relative margin
    covers the difference many times over). Angle rows other than :class:`Bearing` run the
    NumPy screen."""
    n = len(batch.means)
    args = _screen_args(batch.angle_rows, batch.means.shape[1], dets, missed_distance, squared)
    if args is not None and args[0] is None:  # the arrays cannot be formed
        return np.ones((n, len(dets)), dtype=bool)
    if args is None or batch.means.dtype != np.float64 or batch.covars.dtype != np.float64 \
            or batch.covars.ndim != 3:
        return screen_pairs(batch, dets, missed_distance, squared, invert=np.linalg.inv)
    if args[0] is False:
        return np.zeros((n, len(dets)), dtype=bool)
    z, wrap, threshold = args
    return _core.jpda_screen(np.ascontiguousarray(batch.means), np.ascontiguousarray(batch.covars),
                             z, wrap, threshold, SCREEN_MARGIN)


def screen_states(core, means, covars, dets, missed_distance: float, squared: bool):
    """:func:`screen` of the predicted states ``means`` (N, D, 1) / ``covars`` (N, D, D)
    themselves: the core forms their predicted measurements and innovation covariances
    (``_core.jpda_screen_states``; the rounding differs from the stock measurement
    prediction's far less than the margin, and a bearing at the wrap stays a candidate).
    ``core`` is (the core's model, its angle rows) or None; None when this cannot screen."""
    if core is None or means.dtype != np.float64 or covars.dtype != np.float64:
        return None
    model, angle_rows = core
    args = _screen_args(angle_rows, model.ndim_meas, dets, missed_distance, squared)
    if args is None or args[0] is None:
        return None
    if args[0] is False:
        return np.zeros((len(means), len(dets)), dtype=bool)
    z, wrap, threshold = args
    return _core.jpda_screen_states(model, np.ascontiguousarray(means[:, :, 0]),
                                    np.ascontiguousarray(covars), z, wrap, threshold,
                                    SCREEN_MARGIN)


def _screen_args(angle_rows: dict, ndim_meas: int, dets, missed_distance, squared):
    """(detections (K, m), wrap (K, m), threshold) for the core's screen; (False,) when no
    pair can pass; (None,) when the detections' arrays cannot be formed; None when an angle
    type other than :class:`Bearing` is involved."""
    try:
        z, kinds = detection_vectors(dets)
        if z.ndim != 2 or z.shape[1] != ndim_meas:
            return (None,)
        plan = wrap_plan(angle_rows, kinds, z.shape[1])
    except (ValueError, TypeError):
        return (None,)
    if any(cls is not Bearing for _, cls, _ in plan):
        return None
    if squared:
        threshold = missed_distance
    elif missed_distance > 0:
        threshold = missed_distance * missed_distance
    else:
        # a square root is never below a non-positive gate (NaN is not below anything)
        return (False,)
    wrap = np.zeros(z.shape, dtype=bool)
    for row, _, mask in plan:
        wrap[mask, row] = True
    return np.ascontiguousarray(z), wrap, float(threshold)


class ControlTerms:
    """The control model's contribution to a Kalman prediction (the offset
    ``control.function(None, …)`` and the noise ``B Q_u Bᵀ``), as the predictor computes
    them, memoised per time interval for the stock :class:`LinearControlModel` (whose
    matrix and noise do not depend on the prior; the models are immutable, as the cached
    transition model assumes); any other control model is called every time."""

    def __init__(self):
        self._cache: dict = {}

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


def predict_rows(predictor, control_terms, priors, means, covars, last_times, timestamp):
    """Kalman prediction of the rows ``means`` (H, D, 1) / ``covars`` (H, D, D), last
    updated at ``last_times``, to ``timestamp``: per distinct interval, the predictor's
    ``(F x) + B u`` and ``((F P) Fᵀ + Q) + B Q_u Bᵀ`` (row by row the stock products).
    ``priors(k)`` is row k's last state (the control model's ``prior``)."""
    n = len(last_times)
    pred_means = np.empty_like(means)
    pred_covars = np.empty_like(covars)
    if n and last_times.count(last_times[0]) == n:  # one interval (the usual case)
        groups = {timestamp - last_times[0]: None}
    else:
        groups = {}
        for k, last in enumerate(last_times):
            groups.setdefault(timestamp - last, []).append(k)
    model = predictor.transition_model
    control = predictor.control_model
    for interval, members in groups.items():
        if members is None or len(members) == n:
            idx, first = slice(None), 0
        else:
            idx, first = np.asarray(members), members[0]
        matrix = np.asarray(model.matrix(time_interval=interval), dtype=np.float64)
        offset, ctrl_noise = control_terms(control, priors(first), interval)
        pred_means[idx] = (matrix[np.newaxis] @ means[idx]) + np.asarray(offset, dtype=np.float64)
        process = np.asarray(model.covar(time_interval=interval), dtype=np.float64)
        pred_covars[idx] = ((matrix[np.newaxis] @ covars[idx]) @ matrix.T[np.newaxis]
                            + process) + ctrl_noise
    return pred_means, pred_covars


def angle_wrap(measurement_vector, predicted_vector):
    """How the stock ``z − ẑ`` of two measurement vectors computes each row, as a tuple of
    bools (True: a :class:`Bearing` difference, wrapped by ``mod_bearing``; False: a float
    difference), or None when the typed arithmetic is anything else (the stock code then
    runs)."""
    if measurement_vector.dtype == np.float64 and predicted_vector.dtype == np.float64:
        if measurement_vector.shape != predicted_vector.shape:
            return None
        return (False,) * len(measurement_vector)
    if predicted_vector.ndim != 2 or predicted_vector.shape[1] != 1:
        return None
    return wrap_rows(measurement_vector, tuple(map(type, predicted_vector[:, 0].tolist())))


def wrap_rows(measurement_vector, predicted_kinds: tuple):
    """:func:`angle_wrap` against a predicted vector whose rows have the types
    ``predicted_kinds``."""
    if measurement_vector.ndim != 2 or measurement_vector.shape != (len(predicted_kinds), 1):
        return None
    wrap = []
    for z, kind in zip(measurement_vector[:, 0].tolist(), predicted_kinds):
        if type(z) is Bearing and kind is Bearing:
            wrap.append(True)
        elif type(z) in _FLOATS and kind in _FLOATS:
            wrap.append(False)
        else:
            return None
    return tuple(wrap)


def pair_distances(batch, rows: list, cols: list, dets, measure, squared: bool,
                   timestamp) -> list:
    """The stock ``measure`` (a Mahalanobis or squared Mahalanobis measure without mapping)
    between predicted measurement ``rows[p]`` of ``batch`` and detection ``dets[cols[p]]``,
    for each pair p: float vectors with the measure's own arithmetic (``pinv`` of each S in
    one stacked call, then its ``einsum`` per pair), Bearing-typed pairs in stacked arrays
    (:func:`typed_distances`), anything else by the measure itself."""
    columns = set(cols)
    if not batch.angle_rows and all(dets[c].state_vector.dtype == np.float64 for c in columns):
        unique = sorted(set(rows))
        inverses = dict(zip(unique, np.linalg.pinv(batch.covars[unique])))
        out = []
        for row, col in zip(rows, cols):
            delta = -(dets[col].state_vector.T - batch.means[row])
            distance = np.einsum('ij,jk,ik->i', delta, inverses[row], delta).squeeze()[()]
            out.append(distance if squared else np.sqrt(distance))
        return out
    typed: dict = {}
    if not squared and batch.objects is None and batch.angle_rows \
            and all(cls is Bearing for cls in batch.angle_rows.values()):
        kinds = tuple(batch.angle_rows.get(i, float) for i in range(batch.means.shape[1]))
        wraps = {c: wrap_rows(dets[c].state_vector, kinds) for c in columns}
        pairs = [(r, c) for r, c in zip(rows, cols) if wraps[c] is not None]
        if pairs:
            typed = dict(zip(pairs, typed_distances(
                batch, [r for r, _ in pairs], [dets[c] for _, c in pairs],
                [wraps[c] for _, c in pairs])))
    out = []
    cache: dict = {}
    for row, col in zip(rows, cols):
        distance = typed.get((row, col))
        if distance is None:
            mp = cache.get(row)
            if mp is None:
                mp = cache[row] = _measurement_prediction(batch, row, timestamp)
            distance = measure(mp, dets[col])
        out.append(distance)
    return out


def typed_distances(batch, rows, dets, wraps) -> list:
    """The stock Mahalanobis distance of predicted measurement ``rows[p]`` of
    ``batch`` (its typed vector: :class:`Bearing` rows where ``batch.angle_rows`` says, all
    of them Bearing) and detection ``dets[p]``, whose rows are typed as ``wraps[p]`` says
    (:func:`wrap_rows`). The stock measure computes ``δ = −(z − ẑ)`` on the typed values
    (a Bearing wraps after the difference and after the negation), ``pinv(S)``, and sums
    ``(δ_j S⁻¹_jk) δ_k`` in an object ``einsum``: Python floats, j then k, in order. The
    same operations on float arrays give the same bits, and the square root makes them the
    NumPy float the stock measure returns. (The squared measure returns the object sum
    itself, a Python or NumPy float depending on its operands: not computed here.)"""
    rows = np.asarray(rows)
    unique, index = np.unique(rows, return_inverse=True)
    inverses = np.linalg.pinv(batch.covars[unique])[index]
    zhat = batch.means[rows]
    for row in batch.angle_rows:  # the typed vector: Bearing(value)
        zhat[:, row] = mod_bearing(zhat[:, row])
    z = np.array([d.state_vector for d in dets], dtype=np.float64)[:, :, 0]
    wrap = np.array(wraps, dtype=bool).reshape(z.shape)
    delta = z - zhat
    delta[wrap] = mod_bearing(delta[wrap])
    delta = -delta
    delta[wrap] = mod_bearing(delta[wrap])
    total = np.zeros(len(rows))
    m = z.shape[1]
    for j in range(m):
        for k in range(m):
            total = ((delta[:, j] * inverses[:, j, k]) * delta[:, k]) + total
    return list(np.sqrt(total))


_FLOATS = (float, np.float64)


def kalman_updates(predictions, measurement_predictions, measurements, wraps, symmetric: bool):
    """The Kalman updater's posterior ``(means (U, D, 1), covars (U, D, D))`` of U
    hypotheses at once: row by row the stock expressions ``K = C S⁻¹``,
    ``P − (K S) Kᵀ`` (then ``(P + Pᵀ)/2`` if ``symmetric``) and ``x + K (z − ẑ)`` (stacked
    products and inverses compute each matrix as the single ones do), where the rows of
    ``z − ẑ`` marked in ``wraps`` (U tuples from :func:`angle_wrap`) are the wrapped
    difference of two :class:`Bearing` values, ``mod_bearing(z − ẑ)``, which the stock
    product then casts to float."""
    cross = np.array([mp.cross_covar for mp in measurement_predictions], dtype=np.float64)
    innov = np.array([mp.covar for mp in measurement_predictions], dtype=np.float64)
    zhat = np.array([mp.state_vector for mp in measurement_predictions], dtype=np.float64)
    z = np.array([m.state_vector for m in measurements], dtype=np.float64)
    prior_covars = np.array([p.covar for p in predictions], dtype=np.float64)
    prior_means = np.array([p.state_vector for p in predictions], dtype=np.float64)
    gain = cross @ np.linalg.inv(innov)
    covars = prior_covars - (gain @ innov) @ gain.transpose(0, 2, 1)
    if symmetric:
        covars = (covars + covars.transpose(0, 2, 1)) / 2
    innovation = z - zhat
    wrap = np.array(wraps, dtype=bool).reshape(innovation.shape)
    if wrap.any():
        innovation[wrap] = mod_bearing(innovation[wrap])
    means = prior_means + gain @ innovation
    return means, covars
