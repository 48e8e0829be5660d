"""What ctxmodels' trackers check of each scan a detector hands them, before any work.

Stone Soup's trackers take whatever the detector yields and fail deep inside a predictor or
updater (``'NoneType' object is not iterable``, ``No measurement model specified``, ``can't
subtract offset-naive and offset-aware datetimes``), or not at all: a detection at
``[[nan], [5]]`` is silently never associated by the component path, while the array path
refuses it. Every ctxmodels tracker (:class:`~ctxmodels.stonesoup.MultiTargetMixtureTracker`,
:class:`~ctxmodels.stonesoup.ArrayJPDATracker`,
:class:`~ctxmodels.stonesoup.PointProcessMultiTargetTracker`,
:class:`~ctxmodels.stonesoup.ArrayPointProcessTracker`) runs :func:`checked_scan` on each scan,
so the array and component paths refuse the same scans with the same message, and runs the
scan inside :func:`naming_scan_errors`. What is refused (``k`` is the scan's index in the
tracker's run, from 0):

* a scan that is not a ``(time, detections)`` pair, a time that is not a
  :class:`datetime.datetime`, detections that are not a collection (``None``, a string),
  an item that is not a detection (no ``state_vector``/``timestamp``) — ``TypeError``;
* a scan earlier than the previous one, or one whose time (or a detection's) is
  timezone-aware where the previous scan's was naive, or the other way round —
  ``ValueError``; scans at the *same* time (two sensors on one clock) are fine;
* a detection whose measurement vector holds NaN or infinity, or whose length is not the
  size of its own measurement model — ``ValueError``.

Detections are named by their index in :func:`~ctxmodels.stonesoup.in_stable_order` (the
order every ctxmodels tracker visits them, the same in every process) and their vector. The
checks cost one float conversion of the scan's vectors; the ordering is only computed to
report an error.
"""
from __future__ import annotations

import datetime
import re

import numpy as np

from .ordering import in_stable_order

#: What Stone Soup's updaters raise for a detection without a measurement model when the
#: updater has none either (``_check_measurement_model``).
_NO_MODEL = "No measurement model specified"
_MIXED_TZ = re.compile(r"can't (subtract|compare) offset-naive and offset-aware datetimes")


def _is_aware(stamp: datetime.datetime) -> bool:
    return stamp.tzinfo is not None and stamp.utcoffset() is not None


def _where(index: int, time) -> str:
    return f"scan {index} at {time}"


class _Where:
    """:func:`_where`, formatted only when a message is (the time's text costs more than
    the checks of a small scan)."""

    __slots__ = ("index", "time")

    def __init__(self, index: int, time):
        self.index, self.time = index, time

    def __str__(self) -> str:
        return _where(self.index, self.time)

    def __format__(self, spec: str) -> str:
        return format(str(self), spec)


def _vector_text(detection) -> str:
    try:
        return str(np.asarray(detection.state_vector, dtype=np.float64).ravel().tolist())
    except (TypeError, ValueError):
        return repr(detection.state_vector)


def _ordered_index(detections, detection) -> int:
    """The index of ``detection`` among ``detections`` in stable (value) order."""
    return next(i for i, d in enumerate(in_stable_order(detections)) if d is detection)


def checked_scan(tracker, scan):
    """``scan`` (one item of ``tracker``'s detector) as ``(time, detections)`` once checked
    (see the module docstring); raises TypeError/ValueError naming the scan (its index in
    the tracker's run and its time) and the detection. Remembers the scan's time on the
    tracker for the next check."""
    return checked_scan_rows(tracker, scan)[:2]


def checked_scan_rows(tracker, scan):
    """:func:`checked_scan`, and the detections' measurement vectors as the check converted
    them, in iteration order (``np.array`` of the vectors as float64; None when they do not
    convert to one array, or the detections are no plain set, list or tuple, whose second
    iteration could visit them in another order): ``(time, detections, rows)``."""
    index, previous = tracker.__dict__.get("_scan_checks", (0, None))
    if not (isinstance(scan, (tuple, list)) and len(scan) == 2):
        raise TypeError(f"detector: scan {index}: expected a (time, detections) pair, got "
                        f"{type(scan).__name__}"
                        + (f" of {len(scan)} items" if isinstance(scan, (tuple, list)) else ""))
    time, detections = scan
    if not isinstance(time, datetime.datetime):
        raise TypeError(f"detector: scan {index}: the time must be a datetime.datetime, got "
                        f"{type(time).__name__} {time!r}")
    where = _Where(index, time)
    if detections is None or isinstance(detections, (str, bytes)) \
            or not hasattr(detections, "__iter__"):
        raise TypeError(f"detector: {where}: expected a collection of detections, got "
                        f"{type(detections).__name__}")
    # a collection (sized) is iterated again by the tracker; anything else once, here
    items = detections if hasattr(detections, "__len__") else list(detections)
    aware = _is_aware(time)
    if previous is not None:
        if _is_aware(previous) != aware:
            raise ValueError(
                f"detector: {where} is timezone-{'aware' if aware else 'naive'} but the "
                f"previous scan's time {previous} is not: mix naive and aware times and "
                "Python cannot subtract them")
        if time < previous:
            raise ValueError(f"detector: {where} is earlier than the previous scan "
                             f"({previous}): scans must come in time order")
    vectors, models = [], []
    last_stamp = None  # (a scan's detections mostly share one timestamp object)
    for i, detection in enumerate(items):
        try:
            vector = detection.state_vector
            stamp = detection.timestamp
            model = detection.measurement_model
        except AttributeError:
            vector = None
        if vector is None:
            raise TypeError(f"detections: item {i} of {where} is a "
                            f"{type(detection).__name__}, not a detection (a state_vector, "
                            "a timestamp and a measurement_model)")
        if stamp is not last_stamp:
            if isinstance(stamp, datetime.datetime) and _is_aware(stamp) != aware:
                raise ValueError(
                    f"detections: the detection at {_vector_text(detection)} of {where} is "
                    f"timezone-{'aware' if not aware else 'naive'} ({stamp}) but the scan's "
                    "time is not: Python cannot subtract naive and aware times")
            last_stamp = stamp
        vectors.append(vector)
        models.append(model)
    rows = _check_vectors(items, vectors, models, where)
    tracker.__dict__["_scan_checks"] = (index + 1, time)
    if type(items).__iter__ not in _PLAIN_ITERATION:
        rows = None
    return time, items, rows


_PLAIN_ITERATION = (set.__iter__, frozenset.__iter__, list.__iter__, tuple.__iter__)


def _length(vector) -> int:
    shape = np.shape(vector)
    return shape[0] if shape else 1


def _check_vectors(items, vectors, models, where):
    """Every measurement vector finite, and as long as its own measurement model measures;
    returns the vectors as one float64 array (None if they do not make one)."""
    rows = None
    if not vectors:
        return rows
    try:
        rows = np.array(vectors, dtype=np.float64)
        finite = np.isfinite(rows)
        # (per vector only when some value is not finite: the rare case)
        finite = None if finite.all() else finite.reshape(len(vectors), -1).all(axis=1)
        length = rows.shape[1] if rows.ndim >= 2 else None  # shared by every vector
    except (TypeError, ValueError):  # vectors of different lengths (several sensors), or odd
        finite = []
        for vector in vectors:
            try:
                finite.append(bool(np.all(np.isfinite(np.asarray(vector, dtype=np.float64)))))
            except (TypeError, ValueError):
                finite.append(False)
        finite = np.array(finite)
        length = rows = None
    if finite is not None and not finite.all():
        bad = [d for d, ok in zip(items, finite.tolist()) if not ok]
        row = min(_ordered_index(items, d) for d in bad)
        detection = in_stable_order(items)[row]
        raise ValueError(f"detections: row {row} of {where} is not finite "
                         f"({_vector_text(detection)}): a measurement holds NaN or infinity "
                         "(or something that is not a number)")
    distinct = {id(model): model for model in models if model is not None}
    sizes = {key: getattr(model, "ndim_meas", None) for key, model in distinct.items()}
    if length is not None and all(size in (None, length) for size in sizes.values()):
        return rows  # one length, which every model measures
    for detection, vector, model in zip(items, vectors, models):
        size = None if model is None else sizes[id(model)]
        if size is not None and _length(vector) != size:
            row = _ordered_index(items, detection)
            raise ValueError(f"detections: row {row} of {where} has {_length(vector)} "
                             f"elements ({_vector_text(detection)}) but its measurement model "
                             f"measures {size}")


class naming_scan_errors:
    """Re-raises Stone Soup's anonymous errors of a scan with the scan and detection named:
    ``No measurement model specified`` (a detection without a model, and an updater with
    none to fall back on) and the naive/aware datetime mix (a scan against the tracks'
    states). A context manager (a class: it wraps every scan, and a generator-based one
    costs more)."""

    __slots__ = ("time", "detections", "index")

    def __init__(self, tracker, time, detections):
        self.index = tracker.__dict__.get("_scan_checks", (1, None))[0] - 1
        self.time, self.detections = time, detections

    def __enter__(self) -> None:
        return None

    def __exit__(self, kind, error, traceback) -> bool:
        if kind is None:
            return False
        if issubclass(kind, ValueError):
            self._named_model_error(error)
        elif issubclass(kind, TypeError) and _MIXED_TZ.fullmatch(str(error)):
            time = self.time
            raise ValueError(
                f"detector: {_where(self.index, time)}: the scan's time is timezone-"
                f"{'aware' if _is_aware(time) else 'naive'} but a track's or component's "
                f"state is not: naive and aware times cannot be subtracted") from error
        return False

    def _named_model_error(self, error) -> None:
        if str(error) != _NO_MODEL:
            return
        where = _where(self.index, self.time)
        ordered = in_stable_order(self.detections)
        missing = [row for row, d in enumerate(ordered) if d.measurement_model is None]
        if not missing:  # (raised for something other than the scan's detections)
            raise ValueError(f"detections: {where}: {error}") from error
        rows = ", ".join(map(str, missing[:5])) + (", ..." if len(missing) > 5 else "")
        first = _vector_text(ordered[missing[0]])
        if len(missing) == 1:
            named = f"row {rows} ({first}) has"
        else:
            named = f"rows {rows} (the first at {first}) have"
        raise ValueError(
            f"detections: {where}: {named} no measurement model, and the tracker's updater "
            "has none to use instead: give each detection its measurement_model, or the "
            "updater one") from error


__all__ = ["checked_scan", "checked_scan_rows", "naming_scan_errors"]
