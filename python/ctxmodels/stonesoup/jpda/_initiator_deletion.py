"""The holding tracks' deletion in :class:`~ctxmodels.stonesoup.ArrayMultiMeasurementInitiator`:
per holding row, what its deleter reads, kept as the rows advance instead of walking the
tracks (whose coasting predictions are not even appended yet). The verdicts are the
deleter's own (:mod:`~ctxmodels.stonesoup.jpda.deleter`), from these counts:

* ``UpdateTimeStepsDeleter`` (stock or ctxmodels): the number of distinct timestamps since
  the row's last detection-backed state (advanced by the core's scan),
  :func:`~ctxmodels.stonesoup.jpda.deleter.time_steps_verdict`;
* Stone Soup's ``UpdateTimeDeleter``: the latest timestamp of a detection-backed state,
  :func:`~ctxmodels.stonesoup.jpda.deleter.update_time_verdict` with the row's last time;
* :class:`~ctxmodels.stonesoup.ExpectedMissesDeleter` without a hypothesiser (an initiator's:
  each miss weighed by the P_D of the row's prediction in the scan's context): the P_D of
  each miss since the row's last detection,
  :meth:`~ctxmodels.stonesoup.ExpectedMissesDeleter.deletes_after`.
"""
from __future__ import annotations

import datetime
from itertools import compress

import numpy as np
from stonesoup.deleter.time import UpdateTimeDeleter
from stonesoup.deleter.time import UpdateTimeStepsDeleter as _StockUpdateTimeStepsDeleter

from .deleter import (ExpectedMissesDeleter, UpdateTimeStepsDeleter, latest_detection_time,
                      time_steps_verdict, times_since_detection, update_time_verdict)


def supported(deleter) -> bool:
    """Whether the rows can reach ``deleter``'s verdicts (``delete_last_pred`` off)."""
    if getattr(deleter, "delete_last_pred", True):
        return False
    kind = type(deleter)
    if kind in (UpdateTimeStepsDeleter, _StockUpdateTimeStepsDeleter):
        return True
    if kind is ExpectedMissesDeleter:
        return deleter.hypothesiser is None  # (P_D from each scan's context)
    return kind is UpdateTimeDeleter and type(deleter.time_since_update) is datetime.timedelta


def read(states) -> tuple:
    """(distinct times since the last detection-backed state, latest detection-backed
    time or None) of a track's ``states``."""
    return len(times_since_detection(states)), latest_detection_time(states)


class HoldingCounts:
    """The counts of the holding rows (aligned with the initiator's records): ``since``
    (distinct times since the last detection) and ``backed`` (latest detection-backed
    time)."""

    def __init__(self):
        self.since = np.empty(0, dtype=np.int64)
        self.backed: list = []
        #: Per row, the P_D of each miss since its last detection, oldest first (kept for an
        #: ExpectedMissesDeleter only; empty lists otherwise).
        self.misses: list[list[float]] = []

    def add(self, counts, misses=None) -> None:
        """Appends rows with ``counts`` (pairs from :func:`read`) and, for an
        ExpectedMissesDeleter, the P_D of their misses since their last detection."""
        self.since = np.concatenate([self.since, [n for n, _ in counts]]).astype(np.int64)
        self.backed = self.backed + [b for _, b in counts]
        self.misses = self.misses + (list(misses) if misses is not None
                                     else [[] for _ in counts])

    def take(self, keep) -> None:
        """Keeps the rows ``keep`` (indices, or a boolean mask), in that order."""
        self.since = self.since[keep]
        if isinstance(keep, np.ndarray) and keep.dtype == bool:
            mask = keep.tolist()
            self.backed = list(compress(self.backed, mask))
            self.misses = list(compress(self.misses, mask))
            return
        self.backed = [self.backed[k] for k in keep]
        self.misses = [self.misses[k] for k in keep]

    def advance(self, since, updated, timestamp, missed=None, prob_detect=None) -> None:
        """A scan at ``timestamp``: ``since`` from the core (see
        :func:`ctxmodels._core.initiator_scan`); the rows ``updated`` (indices) got a
        detection; for an ExpectedMissesDeleter the rows ``missed`` (indices) missed with
        P_D ``prob_detect`` (aligned)."""
        self.since = since
        for k in updated.tolist():
            if self.backed[k] is None or timestamp > self.backed[k]:
                self.backed[k] = timestamp
            self.misses[k] = []
        if missed is not None:
            for k, pd in zip(missed.tolist(), prob_detect.tolist()):
                self.misses[k].append(pd)

    def expired(self, deleter, last_times) -> np.ndarray:
        """Per row, whether ``deleter`` deletes it (a boolean array); ``last_times``: each
        row's last state's time."""
        if type(deleter) is UpdateTimeDeleter:
            return np.array([update_time_verdict(deleter, backed, last)
                             for backed, last in zip(self.backed, last_times)], dtype=bool)
        if type(deleter) is ExpectedMissesDeleter:
            return np.array([deleter.deletes_after(reversed(misses)) for misses in self.misses],
                            dtype=bool)
        return np.asarray(time_steps_verdict(deleter, self.since), dtype=bool)


__all__ = ["HoldingCounts", "read", "supported"]
