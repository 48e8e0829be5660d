"""Learning observability from a tracker's own output, one scan at a time.

:class:`LearningTracker` wraps any Stone Soup tracker and, after each scan, hands the
scan's detections (with their context) and the tracker's tracks to its *learners*. The
trackers' update equations are untouched: what a learner changes — a
:class:`~ctxmodels.ClutterMap` in a sensor's clutter model — is read by the contexts of
the scans that follow. :class:`ClutterMapLearner` is the learner of clutter maps.
"""
from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
from stonesoup.base import Base, Property
from stonesoup.tracker.base import Tracker

from ..clutter_map import ClutterMap
from ..context import detection_positions, measured_ranges
from .ordering import in_stable_order, in_track_order


class ClutterMapLearner(Base):
    r"""Updates the :class:`~ctxmodels.ClutterMap` factors of each scan's sensor with that
    scan: its detections are clutter unless they lie in a *gate*, a disc of
    ``gate_radius`` around the position of a track at the scan; a gate's area is also left
    out of its cell's exposure for the scan (see :class:`~ctxmodels.ClutterMap`), so the
    tracks — including false ones — neither feed the map nor starve it.

    ``gate_radius`` should hold a track's own detections: a few standard deviations of the
    measurement error in position (a radar with σ_bearing = 1° at 1.6 km: 28 m).
    """

    gate_radius: float = Property(doc="Radius (m) of the disc around each track's position "
                                      "at the scan whose detections are the track's.")
    position_mapping: Sequence[int] = Property(default=(0, 2),
                                               doc="Indices of x and y in the track states.")

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        radius = self.gate_radius
        if isinstance(radius, bool) or not isinstance(radius, (int, float, np.integer, np.floating)) \
                or not (math.isfinite(radius) and radius >= 0):
            raise ValueError(f"gate_radius: must be a finite number of metres >= 0, got {radius!r}")

    def learn(self, time, detections, tracks) -> None:
        """After the scan at ``time``: ``detections`` as the tracker received them (a
        :class:`~ctxmodels.DetectionSet` with its context; anything else is ignored) and
        the tracker's ``tracks``."""
        context = getattr(detections, "detector_context", None)
        model = getattr(context, "sensor_model", None)
        clutter = getattr(model, "clutter", None)
        maps = list({id(f): f for f in getattr(clutter, "factors", ())
                     if isinstance(f, ClutterMap)}.values())
        if not maps:
            return
        ordered = in_stable_order(detections)  # a reproducible order, whatever the set's
        if ordered:
            positions = detection_positions(ordered, model.position_mapping)
            ranges = measured_ranges(ordered)
        else:
            positions, ranges = np.empty((0, 2)), None
        x, y = self.position_mapping
        gates = np.array([[float(t.state_vector[x, 0]), float(t.state_vector[y, 0]),
                           float(self.gate_radius)]
                          for t in in_track_order(tracks) if len(t) and t.timestamp == time],
                         dtype=np.float64).reshape(-1, 3)
        for learned in maps:
            learned.update(context.pose, positions, ranges, gates)


class LearningTracker(Tracker):
    """Any Stone Soup tracker, with ``learners`` called after each of its scans as
    ``learner.learn(time, detections, tracks)`` — the detections the tracker received for
    that scan and the tracks it returned. Iterate it as the tracker it wraps; its
    ``tracks`` are that tracker's."""

    tracker: Tracker = Property(doc="The tracker whose output the learners read.")
    learners: Sequence[Any] = Property(doc="Objects with ``learn(time, detections, tracks)``, "
                                           "called in order after each scan.")

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        for i, learner in enumerate(self.learners):
            if not callable(getattr(learner, "learn", None)):
                raise TypeError(f"learners: learner {i} ({type(learner).__name__}) has no "
                                "learn(time, detections, tracks)")
        self._scans = None

    @property
    def tracks(self):
        return self.tracker.tracks

    def __iter__(self):
        if self._scans is None:
            # Between the tracker and its detector: the scan the tracker is working on.
            self._scans = _LastScan(self.tracker.detector)
            self.tracker.detector = self._scans
        self._inner = iter(self.tracker)
        return self

    def __next__(self):
        time, tracks = next(self._inner)
        detections = self._scans.last[1]
        for learner in self.learners:
            learner.learn(time, detections, tracks)
        return time, tracks


class _LastScan:
    """A detector that passes scans through and remembers the last one it gave."""

    def __init__(self, detector):
        self.detector, self.last = detector, (None, set())

    def __iter__(self):
        for scan in self.detector:
            self.last = scan
            yield scan


__all__ = ["ClutterMapLearner", "LearningTracker"]
