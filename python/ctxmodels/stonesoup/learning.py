"""Learning observability from a tracker's own output, one scan at a time.

:class:`LearningTracker` wraps any Stone Soup tracker and, after each scan, hands the
scan's detections (with their context) and the tracker's tracks to its *learners*. The
trackers' update equations are untouched: what a learner changes — a
:class:`~ctxmodels.ClutterMap` in a sensor's clutter model — is read by the contexts of
the scans that follow. :class:`ClutterMapLearner` is the learner of clutter maps,
:class:`DetectionLearner` that of detection-probability estimates.
"""
from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

import numpy as np
from stonesoup.base import Base, Property
from stonesoup.tracker.base import Tracker

from .._component import as_position_mapping
from ..clutter_map import ClutterMap
from ..context import detection_positions, measured_ranges
from ..detection import DetectionProbabilityModel
from ..detection_estimate import DetectionEstimate
from ..sensor import SensorModel
from .ordering import in_stable_order, in_track_order


class _GatedLearner(Base):
    """What the gate-based learners share: a gate of ``gate_radius`` around each track's
    position at the scan, whose detections are the track's."""

    gate_radius: float = Property(doc="Radius (m) of the disc around each track's position "
                                      "at the scan whose detections are the track's.")
    position_mapping: Sequence[int] = Property(default=(0, 2),
                                               doc="Indices of x and y in the track states.")

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        # Checked now (any integer type, stored as a tuple of ints); whether the tracks'
        # states hold these indices is checked at each scan, naming the track.
        self.position_mapping = as_position_mapping(self.position_mapping)
        radius = self.gate_radius
        if radius is None and not self._gated:
            return
        if isinstance(radius, (bool, np.bool_)) or not isinstance(radius, (int, float, np.integer,
                                                               np.floating)) \
                or not (math.isfinite(radius) and radius >= 0):
            raise ValueError(f"gate_radius: must be a finite number of metres >= 0, got "
                             f"{radius!r}")

    @property
    def _gated(self) -> bool:
        """Whether this learner uses its gates (and so needs ``gate_radius``)."""
        return True

    def _tracked(self, time, tracks) -> tuple[list, np.ndarray]:
        """The tracks with a state at the scan (in track order) and their positions (T, 2)."""
        x, y = self.position_mapping
        if tracks is None or isinstance(tracks, (str, bytes)) or not isinstance(tracks, Iterable):
            raise TypeError(f"tracks: expected the tracker's tracks (a set of Tracks) at the "
                            f"scan at {time}, got {type(tracks).__name__}")
        # (filtered, then sorted: the same order, as sorting is stable; fewer keys built)
        tracked = in_track_order([t for t in tracks if len(t) and t.timestamp == time])
        rows = []
        for track in tracked:
            vector = np.asarray(track.state_vector)
            if vector.ndim != 2 or max(x, y) >= vector.shape[0]:
                raise ValueError(f"position_mapping: ({x}, {y}) is out of range for the "
                                 f"{vector.shape[0] if vector.ndim else 0}-D state of track "
                                 f"{getattr(track, 'id', '?')} at the scan at {time}")
            rows.append([float(vector[x, 0]), float(vector[y, 0])])
        states = np.array(rows, dtype=np.float64).reshape(-1, 2)
        return tracked, states


def _learned_factors(detections, part: str, kind: type):
    """The scan's context, its sensor model and the distinct ``kind`` factors of the model's
    ``part`` ("clutter" or "detection"; none without a context)."""
    context = getattr(detections, "detector_context", None)
    model = getattr(context, "sensor_model", None)
    if type(model) is SensorModel:
        # (asked every scan, of every sensor; a SensorModel and its parts are immutable, so
        # the answer per model object is kept with it)
        found = _LEARNED_FACTORS.get((id(model), part, kind))
        if found is not None and found[0] is model:
            return context, model, list(found[1])
    factors = getattr(getattr(model, part, None), "factors", ())
    learned = list({id(f): f for f in factors if isinstance(f, kind)}.values())
    if type(model) is SensorModel:
        if len(_LEARNED_FACTORS) >= 64:
            _LEARNED_FACTORS.clear()
        _LEARNED_FACTORS[(id(model), part, kind)] = (model, tuple(learned))
    return context, model, learned


#: (id(sensor model), part, kind) -> (the model, its learned factors of that kind).
_LEARNED_FACTORS: dict = {}


def _scan(detections, model) -> tuple[list, np.ndarray]:
    """A scan's detections in a reproducible order (whatever the set's) and their world
    positions (M, 2)."""
    ordered = in_stable_order(detections)
    if not ordered:
        return ordered, np.empty((0, 2))
    return ordered, detection_positions(ordered, model.plane_mapping)


_WEIGHTINGS = ("gates", "posterior")


class ClutterMapLearner(_GatedLearner):
    r"""Updates the :class:`~ctxmodels.ClutterMap` factors of each scan's sensor with that
    scan. Which detections count as clutter, by ``weighting``:

    * ``"gates"`` (any tracker): a detection is clutter unless it lies in a *gate*, a disc
      of ``gate_radius`` around the position of a track at the scan; a gate's area is also
      left out of its cell's exposure for the scan (see :class:`~ctxmodels.ClutterMap`), so
      the tracks — including false ones — neither feed the map nor starve it. A target's
      detections before its track is extracted are counted as clutter.
    * ``"posterior"`` (a tracker that reports ``clutter_probabilities``, as the GM-PHD
      trackers of :mod:`ctxmodels.stonesoup` do): each detection counts as its posterior
      clutter probability :math:`\kappa(z) / (\kappa(z) + \sum_j p_S P_D^{(j)} w^{(j)}
      q^{(j)}(z))` in the tracker's update, the expected number of clutter points it is
      (an EM step), and the whole scan is exposure. A target's detections count as
      clutter in proportion to how little the filter already believes in it: fully at its
      first scan (its birth enters at the next), then less as its components, extracted
      or not, gain weight. The map then learns from what the filter believes, so its
      errors feed back: a λ too low lets clutter seed components that then explain (and
      hide) more clutter. Needs the tracker: :class:`LearningTracker` calls :meth:`bind`
      with the tracker it wraps (one learner serves one tracker; the binding is not
      pickled, and the next iteration binds again). A scan that the tracker's component
      path updates with a stock updater reports no probabilities and raises.

    ``gate_radius`` (``"gates"`` only) should hold a track's own detections: a few standard
    deviations of the measurement error in position (a radar with σ_bearing = 1° at
    1.6 km: 28 m).
    """

    gate_radius: float = Property(default=None, doc="Radius (m) of the disc around each "
                                                    "track's position at the scan whose "
                                                    "detections are the track's (needed "
                                                    "with ``weighting='gates'``).")
    weighting: str = Property(default="gates", doc="How detections count as clutter: "
                                                   "``gates`` or ``posterior``.")

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)  # (checks gate_radius where it is used)
        if not isinstance(self.weighting, str) or self.weighting not in _WEIGHTINGS:
            raise ValueError(f"weighting: must be one of {', '.join(_WEIGHTINGS)}, got "
                             f"{self.weighting!r}")
        if self.weighting == "posterior" and self.gate_radius is not None:
            raise ValueError("gate_radius: not used with weighting='posterior' (leave it "
                             "None)")
        self._tracker = None

    @property
    def _gated(self) -> bool:
        return self.weighting == "gates"

    def bind(self, tracker) -> None:
        """The tracker whose updates weight the detections (``weighting="posterior"``;
        with gates there is nothing to bind)."""
        if self.weighting != "posterior":
            return
        if not hasattr(tracker, "clutter_probabilities"):
            raise TypeError(f"tracker: weighting='posterior' needs a tracker that reports "
                            f"clutter_probabilities; {type(tracker).__name__} does not")
        self._tracker = tracker

    def __getstate__(self):
        # the bound tracker (with its detector's generators) is not the learner's state
        return {**vars(self), "_tracker": None}

    def learn(self, time, detections, tracks) -> None:
        """After the scan at ``time``: ``detections`` as the tracker received them (a
        :class:`~ctxmodels.DetectionSet` with its context; anything else is ignored) and
        the tracker's ``tracks``."""
        context, model, maps = _learned_factors(detections, "clutter", ClutterMap)
        if not maps:
            return
        ordered, positions = _scan(detections, model)
        ranges = measured_ranges(ordered) if ordered else None
        if self.weighting == "posterior":
            gates, weights = None, self._posterior(time, ordered)
        else:
            _, states = self._tracked(time, tracks)
            gates = np.column_stack([states, np.full(len(states), float(self.gate_radius))])
            weights = None
        for learned in maps:
            learned.update(context.pose, positions, ranges, gates, weights)

    def _posterior(self, time, ordered) -> np.ndarray:
        """The clutter probabilities the bound tracker gave ``ordered`` in its scan at
        ``time``."""
        if self._tracker is None:
            raise RuntimeError("weighting='posterior' needs the tracker: wrap it in a "
                               "LearningTracker, or call bind(tracker) first")
        reported = self._tracker.clutter_probabilities
        if reported is None or reported[0] != time:
            raise RuntimeError(f"the tracker reported no clutter probabilities for the scan "
                               f"at {time} (a stock updater does not)")
        try:
            return np.array([reported[1][detection] for detection in ordered], dtype=np.float64)
        except KeyError:
            raise RuntimeError(f"the tracker's clutter probabilities at {time} are for other "
                               "detections than the learner's") from None


class DetectionLearner(_GatedLearner):
    r"""Updates the :class:`~ctxmodels.DetectionEstimate` factors of each scan's sensor with
    that scan. A track is *detected* at a scan when a detection of the scan lies within
    ``gate_radius`` of its position at the scan (the association, read from the output of
    any tracker, including the array trackers that keep no hypotheses). Every *confirmed*
    track with a state at the scan is a trial there: a hit if detected, weighted by the
    product of the sensor's other P_D factors at its position (0 in a blind sector or
    behind land: no evidence). Confirmed: detected by this sensor on at least
    ``confirmation`` earlier scans — the M-of-N rule of track confirmation. It keeps out
    false tracks, which would otherwise count their misses against the sensor and pull the
    estimate down (and a lower P_D keeps false tracks alive longer: a feedback loop). It
    conditions on earlier scans only, so for a real target this scan's trial is unbiased.

    Known biases, both small when the gate holds a track's detections and little clutter:
    a clutter point inside a missed track's gate counts as a hit (up to λ × the gate's
    area), and the miss after which a tracker deletes a track is not seen (the track has no
    state at that scan).
    """

    confirmation: int = Property(default=3, doc="Detections by the sensor a track needs "
                                                "on earlier scans to count as a trial.")

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        if isinstance(self.confirmation, (bool, np.bool_)) \
                or not isinstance(self.confirmation, (int, np.integer)) or self.confirmation < 0:
            raise ValueError(f"confirmation: must be an integer >= 0, got {self.confirmation!r}")
        self._detections = {}  # track id -> detections by the sensor so far
        self._others = {}  # id(model) -> (model, {id(estimate): its other factors' model})

    def learn(self, time, detections, tracks) -> None:
        """After the scan at ``time``: ``detections`` as the tracker received them (a
        :class:`~ctxmodels.DetectionSet` with its context; anything else is ignored) and
        the tracker's ``tracks``."""
        context, model, estimates = _learned_factors(detections, "detection", DetectionEstimate)
        if not estimates:
            return
        tracked, states = self._tracked(time, tracks)
        _, found = _scan(detections, model)
        if len(states) and len(found):
            gaps = np.hypot(states[:, None, 0] - found[None, :, 0],
                            states[:, None, 1] - found[None, :, 1])
            detected = (gaps <= self.gate_radius).any(axis=1)
        else:
            detected = np.zeros(len(states), dtype=bool)
        earlier = np.array([self._detections.get(t.id, 0) for t in tracked], dtype=np.int64)
        trial = earlier >= self.confirmation
        for estimate in estimates:
            weights = self._other_factors(model, estimate).evaluate(
                context.pose, states[trial], position_mapping=(0, 1))
            estimate.update(context.pose, states[trial], detected[trial], weights)
        # (tracks without a state at the scan have ended)
        self._detections = {t.id: int(n) for t, n in zip(tracked, earlier + detected)}

    def _other_factors(self, model, estimate) -> DetectionProbabilityModel:
        """``model``'s P_D without ``estimate`` (built once per model and estimate)."""
        kept, others = self._others.setdefault(id(model), (model, {}))
        if id(estimate) not in others:
            others[id(estimate)] = DetectionProbabilityModel(
                factors=[f for f in model.detection.factors if f is not estimate] or [1.0])
        return others[id(estimate)]


class LearningTracker(Tracker):
    """Any Stone Soup tracker, with ``learners`` called after each of its scans as
    ``learner.learn(time, detections, tracks)`` — the detections the tracker received for
    that scan and the tracks it returned. A learner that reads more of the tracker (its
    update's clutter probabilities) is handed it first, as ``learner.bind(tracker)``.
    Iterate it as the tracker it wraps; its ``tracks`` are that tracker's."""

    tracker: Tracker = Property(doc="The tracker whose output the learners read.")
    learners: Sequence[Any] = Property(doc="Objects with ``learn(time, detections, tracks)``, "
                                           "called in order after each scan.")

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        tracker = self.tracker
        if tracker is None or not hasattr(tracker, "detector") \
                or not callable(getattr(tracker, "__iter__", None)):
            raise TypeError(f"tracker: expected a Stone Soup tracker (iterable, with a "
                            f"detector), got {type(tracker).__name__}")
        learners = self.learners
        if callable(getattr(learners, "learn", None)):
            raise TypeError(f"learners: expected a list of learners, got one "
                            f"{type(learners).__name__}; wrap it in a list")
        if isinstance(learners, (str, bytes, Mapping)) or not isinstance(learners, Sequence):
            raise TypeError(f"learners: expected a list of objects with learn(time, "
                            f"detections, tracks), got {type(learners).__name__}")
        for i, learner in enumerate(learners):
            if not callable(getattr(learner, "learn", None)):
                raise TypeError(f"learners: learner {i} ({type(learner).__name__}) has no "
                                "learn(time, detections, tracks)")
        self._scans = None

    @property
    def tracks(self):
        return self.tracker.tracks

    def __iter__(self):
        for learner in self.learners:
            if callable(getattr(learner, "bind", None)):
                learner.bind(self.tracker)
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


__all__ = ["ClutterMapLearner", "DetectionLearner", "LearningTracker"]
