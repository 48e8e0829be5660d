r"""The context of one scan of a Stone Soup radar: a :class:`~ctxmodels.DetectorContext`
that decides the radar's ``max_range`` edge as the radar's own ``is_detectable`` does.

Stone Soup's radar computes the range it compares with ``max_range`` in its body frame,
rotating the offset with a NumPy matrix product whose last bits depend on the BLAS kernel,
so within about :math:`10^{-15}\,r_{\max}` of the edge no other computation of the range
decides as it does (of targets placed exactly at ``max_range`` on 240 bearings, the world
range put 18 to 60 on the other side of the edge on the four radars of the tests; OpenBLAS,
x86-64). :class:`SensorContext` evaluates the plain context and re-decides only
the targets whose world range lies within :data:`EDGE_SLIVER` of ``max_range``, one state
at a time with the radar's measurement model; :func:`~ctxmodels.stonesoup.sensor_context`
makes one from a radar now.
"""
from __future__ import annotations

import math
from typing import Any

import numpy as np
from stonesoup.base import Property
from stonesoup.types.array import StateVector
from stonesoup.types.numeric import Probability
from stonesoup.types.state import State

from .. import _core
from .._component import as_columns, as_float, as_int, as_rows
from ..context import DetectorContext
from ..detection import DetectionProbabilityModel
from ..range_bands import RangeBands

#: How near its ``max_range`` (relative) the world range of a target must lie for a
#: :class:`SensorContext` to decide the range edge with the sensor's own range: a thousand
#: times the body-frame rotation's rounding (about :math:`10^{-15}`), far inside any
#: target's size.
EDGE_SLIVER = 1e-12

#: How far (relative) the edge at ``max_range`` is moved in the two copies of the detection
#: model that give P_D on either side of it for the targets in the sliver: far beyond the
#: sliver, far inside any other edge a range band could sensibly have there.
_EDGE_SHIFT = 1e-9


class SensorContext(DetectorContext):
    r"""The :class:`~ctxmodels.DetectorContext` of a scan of a Stone Soup radar, which
    decides the range edge as the radar does: built by :func:`sensor_context` (and by
    :class:`PlatformContextFeeder`), never by hand in the usual case.

    It holds, as well as the context's Properties, what the radar's ``is_detectable``
    computed the range with when the context was made: the measurement model
    (``range_model``), the row of its output that is the range (``range_row``) and
    ``max_range``. Every P_D path of the context
    (:meth:`~ctxmodels.DetectorContext.prob_detection`,
    :meth:`~ctxmodels.DetectorContext.prob_detection_states`,
    :meth:`~ctxmodels.DetectorContext.prob_detection_array`,
    :meth:`~ctxmodels.DetectorContext.prob_detection_particles`, with ``log`` and
    ``missed``) gives what the plain context gives, except for a target whose world range
    from the pose lies within a relative :data:`EDGE_SLIVER` of ``max_range``: there
    ``range_model.function(state, noise=False)[range_row, 0] <= max_range``, evaluated for
    that one state as ``is_detectable`` evaluates it, decides which side of the edge the
    target is on, and P_D is what the context gives on that side (the other factors'
    product times the range band's value there). The edges re-decided are those at exactly
    ``max_range`` that the band below owns (``r <= max_range``, as
    :func:`sensor_model_from_stonesoup` builds them, learned bands included); a model
    without one decides its coverage on the world range everywhere. The expected P_D of a
    Gaussian (a ``pd_evaluation`` other than ``'mean'``, given covariances) integrates the
    plain model: cubature points are not targets the radar would be asked about.
    """

    range_model: Any = Property(
        doc="The measurement model the radar's ``is_detectable`` computes the range with, "
            "as the radar built it when the context was made (its position and heading "
            "then).")
    range_row: int = Property(doc="The row of ``range_model``'s output that is the range.")
    max_range: float = Property(doc="The radar's ``max_range`` when the context was made.")

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        if not callable(getattr(self.range_model, "function", None)):
            raise TypeError(f"range_model: expected a Stone Soup measurement model, got "
                            f"{type(self.range_model).__name__}")
        as_int(self.range_row, "range_row")
        value = as_float(self.max_range, "max_range", finite=False)
        if math.isnan(value) or value < 0:
            raise ValueError(f"max_range: must be >= 0, got {self.max_range!r}")

    def __setattr__(self, name, value):
        super().__setattr__(name, value)
        self.__dict__.pop("_edge", None)

    def __getstate__(self):
        state = super().__getstate__()
        state.pop("_edge", None)
        return state

    def _calls(self):
        calls = super()._calls()
        # Built with the scan's calls and dropped with them: the same snapshot of the
        # detection model (learned bands fixed at the first P_D call).
        self.__dict__["_edge"] = _RangeEdge.of(self, calls.detection)
        return calls

    def prob_detection_array(self, means, covars=None, *, out=None) -> np.ndarray:
        pd = super().prob_detection_array(means, covars, out=out)
        edge = self.__dict__["_edge"]
        if edge is None or not (covars is None or self._scan_calls.mean_only):
            return pd
        rows = means
        near = edge.sliver.evaluate(rows, None)  # 1 in the sliver, 0 elsewhere
        if near is None:  # (not float64 C-contiguous rows: converted as the base class does)
            rows = as_rows(means, "means")
            near = edge.sliver.evaluate(rows, None)
        if near @ near:  # (cheaper than looking for the indices when there are none)
            edge.decide(np.flatnonzero(near), lambda k: rows[k], pd)
        return pd

    def prob_detection_particles(self, particles, *, log: bool = False, missed: bool = False):
        result = super().prob_detection_particles(particles, log=log, missed=missed)
        edge = self.__dict__["_edge"]
        if edge is not None:
            columns = as_columns(particles, "particles")
            near = edge.sliver_core.evaluate_particles(edge.pose, columns, edge.mapping, False,
                                                       False)
            if near @ near:
                edge.decide(np.flatnonzero(near), lambda k: columns[:, k].T, result, log=log,
                            missed=missed)
        return result

    def prob_detection(self, hypothesis_or_state) -> Probability:
        calls = self._scan_calls or self._calls()
        edge = self.__dict__["_edge"]
        if edge is not None and calls.mean_only:
            state = getattr(hypothesis_or_state, "prediction", hypothesis_or_state)
            vector = getattr(state, "state_vector", state)
            pd = calls.at_pose.at(vector)  # (the base class's thin path)
            if pd is not None:  # a float64 (D, 1) or (D,) array with a finite position
                if edge.sliver.at(vector):
                    pd = edge.at_rows(np.asarray(vector).reshape(1, -1))[0]
                return calls.probability(pd)
        # everything else reaches prob_detection_array, which decides the edge
        return super().prob_detection(hypothesis_or_state)


class _RangeEdge:
    """What a :class:`SensorContext` re-decides the range edge with, for one snapshot of its
    detection model: which targets are in the sliver around ``max_range`` (1 there, 0
    elsewhere, from the core at the context's pose), and the model with the edge moved just
    beyond the sliver either way (so its P_D on each side of the edge is the plain model's,
    bit for bit, for every target in the sliver)."""

    # (not the context itself: a context is freed as soon as its scan is done with it)
    __slots__ = ("sliver", "sliver_core", "pose", "mapping", "velocity", "_where", "_radar", "_factors",
                 "_models")

    @classmethod
    def of(cls, context: SensorContext, snapshot: DetectionProbabilityModel):
        """The edge of ``context``'s ``snapshot``; None when none of its factors has an
        edge at ``max_range`` owned by the band below."""
        limit = float(context.max_range)
        if not 0 < limit < math.inf:
            return None
        low, high = limit * (1 - _EDGE_SHIFT), limit * (1 + _EDGE_SHIFT)
        inside, outside = list(snapshot.factors), list(snapshot.factors)
        found = False
        for i, factor in enumerate(snapshot.factors):
            if not isinstance(factor, RangeBands):
                continue
            edges = [float(e) for e in factor.edges]
            owners = factor._owners()
            if limit not in edges:
                continue
            k = edges.index(limit)
            if owners[k] or (k > 0 and edges[k - 1] >= low) \
                    or (k + 1 < len(edges) and edges[k + 1] <= high):
                continue  # the band above owns it (not is_detectable's rule), or too close
            inside[i], outside[i] = (
                RangeBands(edges=edges[:k] + [moved] + edges[k + 1:], values=factor.values,
                           upper_owns=factor.upper_owns) for moved in (high, low))
            found = True
        if not found:
            return None
        edge = cls()
        edge.mapping = tuple(int(i) for i in context.sensor_model.position_mapping)
        edge.velocity = context.sensor_model.velocity_mapping
        edge.pose = context.pose.as_tuple()
        edge.sliver_core = _sliver_model(limit)._compiled()
        edge.sliver = _core.DetectionAtPose(edge.sliver_core, edge.pose, edge.mapping, "mean", 1)
        edge._where = context.pose
        edge._radar = (context.range_model, int(context.range_row), limit)
        edge._factors = (inside, outside)
        edge._models = None
        return edge

    def _sides(self) -> tuple[DetectionProbabilityModel, DetectionProbabilityModel]:
        """The snapshot with the edge moved beyond the sliver, then before it (built at the
        first target in the sliver)."""
        if self._models is None:
            self._models = tuple(DetectionProbabilityModel(factors=f) for f in self._factors)
        return self._models

    def detectable(self, row: np.ndarray) -> bool:
        """The radar's decision for one state: its range as ``is_detectable`` computes it,
        one state per call, ``<= max_range``."""
        range_model, range_row, max_range = self._radar
        vector = StateVector(np.array(row, dtype=np.float64).reshape(-1, 1))
        measured = range_model.function(State(vector), noise=False)
        return bool(measured[range_row, 0] <= max_range)

    def at_rows(self, rows: np.ndarray) -> np.ndarray:
        """P_D at ``rows`` (K, D), each on the side of the edge the radar puts it."""
        inside = np.array([self.detectable(row) for row in rows], dtype=bool)
        pd = np.empty(len(rows))
        for model, which in zip(self._sides(), (inside, ~inside)):
            if which.any():
                pd[which] = model.evaluate(self._where, rows[which], self.mapping,
                                           velocity_mapping=self.velocity)
        return pd

    def decide(self, near: np.ndarray, rows_at, result, *, log=False, missed=False) -> None:
        """Re-decides, in ``result`` (P_D per target, or the particles' pair), the targets
        ``near`` (indices) in the sliver; ``rows_at(near)`` their states as rows (K, D)."""
        if near.size == 0:
            return
        rows = np.asarray(rows_at(near), dtype=np.float64)
        if not (log or missed):
            result[near] = self.at_rows(rows)
            return
        inside = np.array([self.detectable(row) for row in rows], dtype=bool)
        for model, which in zip(self._sides(), (inside, ~inside)):
            if not which.any():
                continue
            values = model.evaluate_particles(self._where, np.ascontiguousarray(rows[which].T),
                                              self.mapping, log=log, missed=missed,
                                              velocity_mapping=self.velocity)
            if missed:
                result[0][near[which]], result[1][near[which]] = values
            else:
                result[near[which]] = values


_SLIVER_MODELS: dict[float, DetectionProbabilityModel] = {}


def _sliver_model(limit: float) -> DetectionProbabilityModel:
    """1 for a world range within :data:`EDGE_SLIVER` (relative, ends included) of
    ``limit``, 0 elsewhere; one per ``max_range`` (a radar keeps its own scan after scan)."""
    model = _SLIVER_MODELS.get(limit)
    if model is None:
        if len(_SLIVER_MODELS) >= 64:
            _SLIVER_MODELS.clear()
        width = limit * EDGE_SLIVER
        model = _SLIVER_MODELS[limit] = DetectionProbabilityModel(factors=[RangeBands(
            edges=(limit - width, limit + width), values=(0.0, 1.0, 0.0),
            upper_owns=(True, False))])
    return model


__all__ = ["EDGE_SLIVER", "SensorContext"]
