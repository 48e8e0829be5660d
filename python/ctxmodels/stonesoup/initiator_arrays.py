"""Array helpers of :class:`~ctxmodels.stonesoup.array_initiator.ArrayMultiMeasurementInitiator`:
whole-scan computations whose results equal (bit for bit, where they feed a state) the
Stone Soup computations they replace.
"""
from __future__ import annotations

import numpy as np
from stonesoup.types.angle import Bearing

from .. import _core
from .fast import detection_vectors, wrap_plan
from .fast_association import SCREEN_MARGIN, screen_pairs


def screen(batch, dets, missed_distance: float, squared: bool) -> np.ndarray:
    """:func:`~ctxmodels.stonesoup.fast_association.screen_pairs` (the ``(N, K)`` mask of the
    pairs that may pass the gate) in one core call (``_core.jpda_screen``: LU inverses of
    the innovation covariances, cheaper than the stock pseudo-inverses; the relative margin
    covers the difference many times over). Angle rows other than :class:`Bearing` run the
    NumPy screen."""
    n = len(batch.means)
    try:
        z, kinds = detection_vectors(dets)
        if z.ndim != 2 or z.shape[1] != batch.means.shape[1] or batch.covars.ndim != 3:
            return np.ones((n, len(dets)), dtype=bool)
        plan = wrap_plan(batch.angle_rows, kinds, z.shape[1])
    except (ValueError, TypeError):
        return np.ones((n, len(dets)), dtype=bool)
    if any(cls is not Bearing for _, cls, _ in plan) or batch.means.dtype != np.float64 \
            or batch.covars.dtype != np.float64:
        return screen_pairs(batch, dets, missed_distance, squared, invert=np.linalg.inv)
    if squared:
        threshold = missed_distance
    elif missed_distance > 0:
        threshold = missed_distance * missed_distance
    else:
        # a square root is never below a non-positive gate (NaN is not below anything)
        return np.zeros((n, len(dets)), dtype=bool)
    wrap = np.zeros(z.shape, dtype=bool)
    for row, _, mask in plan:
        wrap[mask, row] = True
    return _core.jpda_screen(np.ascontiguousarray(batch.means), np.ascontiguousarray(batch.covars),
                             np.ascontiguousarray(z), wrap, float(threshold), SCREEN_MARGIN)
