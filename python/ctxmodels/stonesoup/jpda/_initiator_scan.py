"""The core call of a scan of :class:`~ctxmodels.stonesoup.ArrayMultiMeasurementInitiator`:
what :func:`ctxmodels._core.initiator_scan` takes, read from the initiator's components and
the scan's detections — the core's measurement models (one per model *value*, see
:func:`~ctxmodels.model_key.scan_model_groups`), the detections' values, each holding row's
transition ``F(Δt)``, ``Q(Δt)`` — or that the core cannot take the scan (then it runs the
component path).
"""
from __future__ import annotations

from typing import NamedTuple
from collections.abc import Callable

import numpy as np
from stonesoup.measures import SquaredMahalanobis
from stonesoup.types.angle import Bearing

from ... import _core
from ...errors import InfeasibleAssignmentError
from ..._upstream import check_measurement_model
from ...model_key import measurement_model_key, scan_model_groups
from ..models import ControlTerms, core_measurement_model


class Rows(NamedTuple):
    """The holding rows as the core takes them: last means (H, D) and covariances
    (H, D, D), points, distinct times since the last detection, last times, and ``prior(k)``,
    row k's last state as a Stone Soup state (asked of the control model)."""
    means: np.ndarray
    covars: np.ndarray
    counted: np.ndarray
    since: np.ndarray
    last_times: list
    prior: Callable


class ScanCore:
    """Runs a scan's holding rows through the core (:meth:`__call__`), keeping the core's
    models per model value and the control model's answer per interval."""

    def __init__(self):
        self._control_terms = ControlTerms()
        self._core_models: dict = {}

    def __call__(self, initiator, rows, detections, timestamp):
        """The core's results for the holding ``rows`` (:class:`Rows`) and this scan's
        ``detections`` (a dict of arrays, with the models' bearing flags under ``"bearing"``
        and the model index under ``"model_index"``), or None when the scan must run the
        component path."""
        hypothesiser = initiator.data_associator.hypothesiser
        predictor = hypothesiser.predictor
        transition = predictor.transition_model
        found = self._scan_models(hypothesiser.updater, detections)
        if found is None:
            return None
        models, model_index, z, bearing = found
        last_times = rows.last_times
        # (the usual scan: every row last seen at one time, often the same object)
        uniform = bool(last_times) and last_times.count(last_times[0]) == len(last_times)
        distinct = dict.fromkeys(last_times[:1] if uniform else last_times)
        matrices, noises = [], []
        for k, last in enumerate(distinct):
            interval = timestamp - last
            distinct[last] = k
            row = last_times.index(last)
            if self._control_terms.adds_input(predictor.control_model,
                                              lambda row=row: rows.prior(row), interval):
                return None  # (the core predicts without a control input)
            matrices.append(np.asarray(transition.matrix(time_interval=interval), dtype=np.float64))
            noises.append(np.asarray(transition.covar(time_interval=interval), dtype=np.float64))
        n = len(last_times)
        if len(distinct) == 1:
            index = np.zeros(n, dtype=np.int64)
            new_time = np.empty(n, dtype=bool)
            new_time.fill(last_times[0] != timestamp)
        else:
            index = np.array([distinct[t] for t in last_times], dtype=np.int64)
            new_time = np.array([t != timestamp for t in last_times])
        try:
            out = _core.initiator_scan(
                models, rows.means, rows.covars, index,
                matrices[0][np.newaxis] if len(matrices) == 1 else np.stack(matrices),
                noises[0][np.newaxis] if len(noises) == 1 else np.stack(noises),
                z, model_index, float(hypothesiser.missed_distance), rows.counted,
                rows.since, new_time,
                squared=type(hypothesiser.measure) is SquaredMahalanobis,
                include_all=bool(hypothesiser.include_all),
                force_symmetric=bool(initiator.updater.force_symmetric_covariance),
                updates_only=bool(initiator.updates_only), min_points=int(initiator.min_points))
        except InfeasibleAssignmentError:
            raise RuntimeError("Assignment was not feasible") from None  # (the stock error)
        except ValueError:
            return None  # (a singular innovation covariance: the component path decides)
        out["bearing"] = bearing
        out["model_index"] = model_index
        return out

    def _scan_models(self, updater, detections):
        """(the core's models, each detection's model index, the detections' values (M, m),
        per model whether it measures a bearing first), or None when the core cannot take
        the scan's detections."""
        models, bearing, index = [], [], np.empty(len(detections), dtype=np.int64)
        if not detections:  # (the usual initiator scan: no detection left free)
            return models, index, np.empty((0, 0)), bearing
        # by model value: equal models in different objects are one group (its first)
        for key, (raw_model, members) in scan_model_groups(detections).items():
            model = check_measurement_model(updater, raw_model)
            core = self._core_model(updater, model, key if model is raw_model else None)
            if core is None:
                return None
            index[members] = len(models)
            models.append(core[0])
            bearing.append(core[1])
        if len({model.ndim_meas for model in models}) > 1:
            return None
        m = models[0].ndim_meas if models else 0
        vectors = [d.state_vector for d in detections]
        z = getattr(detections, "vectors", None)  # (an OrderedDetections' float rows)
        if isinstance(z, np.ndarray) and z.dtype == np.float64 \
                and z.shape == (len(detections), m):
            z = np.ascontiguousarray(z)
        else:
            try:
                z = np.array(vectors, dtype=np.float64).reshape(len(detections), m)
            except (TypeError, ValueError):
                return None
        for vector, g in zip(vectors, index.tolist()):
            # the stock z − ẑ wraps the model's bearing (a Bearing or float detection);
            # another angle type in a detection would wrap its own way
            if vector.dtype != np.float64 and not _typed_as(vector, bearing[g]):
                return None
        return models, index, z, bearing

    def _core_model(self, updater, model, key=None):
        """(the core's model, whether it measures a bearing first) for detections measured by
        ``model`` (the updater's resolution of a detection's model; ``key`` its
        :func:`~ctxmodels.model_key.measurement_model_key` when known), or None."""
        if key is None:
            key = measurement_model_key(model)
        key = (key, type(updater))  # equal models share an entry
        cached = self._core_models.get(key)
        if cached is None:
            core, bearing_row = core_measurement_model(model, type(updater))
            cached = self._core_models[key] = (model, None if core is None
                                               else (core, bearing_row is not None))
            if len(self._core_models) > 64:
                self._core_models = {key: cached}
        return cached[1]



def _typed_as(vector, bearing: bool) -> bool:
    """Whether an object-typed detection vector holds floats, and a :class:`Bearing` first
    if ``bearing`` (the rows the core wraps)."""
    values = np.ndarray.ravel(vector).tolist()  # (the elements, without a subclass's ravel)
    for row, value in enumerate(values):
        if row == 0 and bearing and type(value) is Bearing:
            continue
        if type(value) not in (float, np.float64):
            return False
    return True


__all__ = ["Rows", "ScanCore"]
