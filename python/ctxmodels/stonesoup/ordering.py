"""A stable order for the sets Stone Soup hands around, so that results do not depend on
memory addresses.

Stone Soup keeps a scan's detections and a tracker's tracks in ``set`` objects. Detections
and tracks hash by identity, so a set of them iterates in *address* order, which changes
from process to process. Whatever a tracker computes in that order — hypotheses, merge
order among equal weights, sums of joint-association probabilities, which of two equal
candidates a solver picks — then changes in the last bits, and sometimes more (a tie
broken the other way starts or ends another track).

ctxmodels' trackers never let that order decide a result: each scan's detections are put
in the order of :func:`detection_key` (their values, never their identity) before anything
iterates them, and tracks are kept in the order they were created. :func:`track_key` sorts
any collection of tracks by content, for reporting.

Detections with equal keys have the same measurement vector, metadata and measurement
model, so they are interchangeable: which comes first changes no number.
"""
from __future__ import annotations

from collections.abc import Iterable

import numpy as np


class OrderedDetections(list):
    """One scan's detections as a list in :func:`detection_key` order, carrying the scan's
    ``detector_context`` (``None`` for a plain set) as a
    :class:`~ctxmodels.DetectionSet` does."""

    def __init__(self, detections: Iterable = (), detector_context=None):
        super().__init__(detections)
        self.detector_context = detector_context

    def __reduce__(self):
        return (type(self), (list(self), self.detector_context))


def _vector_bytes(state) -> bytes:
    # Bytes order every float, NaN and signed zero included: a total, reproducible order.
    return np.ascontiguousarray(np.asarray(state.state_vector, dtype=np.float64)).tobytes()


def _metadata_key(metadata) -> str:
    if not metadata:
        return ""
    return repr(sorted((repr(k), repr(v)) for k, v in metadata.items()))


def detection_key(detection, _model_keys: dict | None = None) -> tuple:
    """A sort key from a detection's values: time, type, measurement vector, metadata,
    measurement model (type and Properties). Never its identity or memory address."""
    model = getattr(detection, "measurement_model", None)
    if _model_keys is None:
        model_key = "" if model is None else f"{type(model).__qualname__}{model!r}"
    else:
        model_key = _model_keys.get(id(model))
        if model_key is None:
            model_key = _model_keys[id(model)] = \
                "" if model is None else f"{type(model).__qualname__}{model!r}"
    timestamp = getattr(detection, "timestamp", None)
    return ("" if timestamp is None else str(timestamp), type(detection).__qualname__,
            _vector_bytes(detection), _metadata_key(getattr(detection, "metadata", None)),
            model_key)


def in_stable_order(detections) -> OrderedDetections:
    """The detections of one scan in :func:`detection_key` order, keeping the scan's
    ``detector_context`` (if the collection carries one)."""
    model_keys: dict = {}  # one repr per measurement model, not per detection
    ordered = sorted(detections, key=lambda d: detection_key(d, model_keys))
    return OrderedDetections(ordered, getattr(detections, "detector_context", None))


class _TrackKey:
    """Orders tracks by when and where they started, then length and last state, and only
    on a tie there by every state's time and vector (rarely needed, so computed lazily)."""

    __slots__ = ("track", "head")

    def __init__(self, track):
        self.track = track
        if len(track) == 0:
            self.head = (0,)
        else:
            first, last = track.states[0], track.states[-1]
            self.head = (1, first.timestamp, _vector_bytes(first), len(track),
                         last.timestamp, _vector_bytes(last))

    def _all(self) -> list:
        return [(str(s.timestamp), _vector_bytes(s)) for s in self.track.states]

    def __lt__(self, other: "_TrackKey") -> bool:
        if self.head != other.head:
            return self.head < other.head
        return self._all() < other._all()

    def __eq__(self, other) -> bool:
        return self.head == other.head and self._all() == other._all()


def track_key(track) -> _TrackKey:
    """A sort key from a track's content (never its identity or random ``id``): tracks with
    equal keys hold the same states, so which comes first changes no number."""
    return _TrackKey(track)


def in_track_order(tracks: Iterable) -> list:
    """Tracks sorted by :func:`track_key`: a reproducible order for any set of tracks."""
    return sorted(tracks, key=track_key)


__all__ = ["OrderedDetections", "detection_key", "in_stable_order", "in_track_order",
           "track_key"]
