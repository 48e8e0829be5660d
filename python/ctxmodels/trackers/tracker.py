"""What :func:`~ctxmodels.trackers.paper_tracker` returns, whatever the tracker's family."""
from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from stonesoup.base import Property
from stonesoup.tracker.base import Tracker

from .specs import TrackerSpec


class PaperTracker(Tracker):
    """One of the study's trackers on the user's data: iterate it for ``(time, tracks)`` per
    scan, as any Stone Soup tracker.

    The same reading for every family: :attr:`tracks` are the current tracks,
    :attr:`gaussian_mixture` the GM-PHD's intensity (None for a JPDA, which has none), and
    :attr:`tracker` the Stone Soup tracker that runs the scans — a GM-PHD or a JPDA, with its
    detector, deleter, initiator and ``array_path``. The learned trackers' :attr:`learners`
    read its output after each scan (a :class:`~ctxmodels.stonesoup.LearningTracker` runs
    them)."""

    spec: TrackerSpec = Property(doc="The tracker's settings (:data:`~ctxmodels.trackers.TRACKERS`).")
    tracker: Tracker = Property(doc="The Stone Soup tracker that runs the scans.")
    learners: Sequence[Any] = Property(
        default=(), doc="What learns from the tracker's output after each scan (the learned "
                        "trackers' clutter map and P_D), in order; empty for the others.")

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        if not isinstance(self.spec, TrackerSpec):
            raise TypeError(f"spec: expected a TrackerSpec, got {type(self.spec).__name__}")
        if not callable(getattr(self.tracker, "__iter__", None)) \
                or not hasattr(type(self.tracker), "tracks"):
            raise TypeError(f"tracker: expected a Stone Soup tracker, got "
                            f"{type(self.tracker).__name__}")
        self.learners = list(self.learners)
        self._scans = None

    @property
    def tracks(self) -> set:
        return self.tracker.tracks

    @property
    def gaussian_mixture(self):
        """The GM-PHD's mixture (its intensity); None for a JPDA."""
        return getattr(self.tracker, "gaussian_mixture", None)

    def __iter__(self):
        if self._scans is None:
            runner = self.tracker
            if self.learners:
                from ..stonesoup.learning import LearningTracker
                runner = LearningTracker(tracker=self.tracker, learners=self.learners)
            self._scans = iter(runner)
        return self

    def __next__(self):
        if self._scans is None:
            iter(self)
        return next(self._scans)
