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

from ..model_key import carry_model_groups


class OrderedDetections(list):
    """One scan's detections as a list in :func:`detection_key` order, carrying the scan's
    ``detector_context`` (``None`` for a plain set) as a
    :class:`~ctxmodels.DetectionSet` does, and ``vectors``: the measurement vectors as
    float rows (M, m) in the same order, when they share a shape (else ``None``)."""

    def __init__(self, detections: Iterable = (), detector_context=None, vectors=None):
        super().__init__(detections)
        self.detector_context = detector_context
        self.vectors = vectors

    def __reduce__(self):
        return (type(self), (list(self), self.detector_context, self.vectors))


def _vector_bytes(state) -> bytes:
    # Bytes order every float, NaN and signed zero included: a total, reproducible order.
    return np.ascontiguousarray(np.asarray(state.state_vector, dtype=np.float64)).tobytes()


def _metadata_key(metadata) -> str:
    if not metadata:
        return ""
    return repr(sorted((repr(k), repr(v)) for k, v in metadata.items()))


def _model_key(model) -> str:
    return "" if model is None else f"{type(model).__qualname__}{model!r}"


class _DetectionKey:
    """Orders detections by time, type and measurement vector, and only on a tie there by
    metadata and measurement model (a model's ``repr`` prints its arrays: slow, so computed
    lazily, once per model)."""

    __slots__ = ("detection", "head", "_model_keys")

    def __init__(self, detection, head: tuple, model_keys: dict):
        self.detection = detection
        self.head = head
        self._model_keys = model_keys

    def tail(self) -> tuple:
        model = getattr(self.detection, "measurement_model", None)
        model_key = self._model_keys.get(id(model))
        if model_key is None:
            model_key = self._model_keys[id(model)] = _model_key(model)
        return _metadata_key(getattr(self.detection, "metadata", None)), model_key

    def key(self) -> tuple:
        return self.head + self.tail()

    def __lt__(self, other: _DetectionKey) -> bool:
        if self.head != other.head:
            return self.head < other.head
        return self.tail() < other.tail()

    def __eq__(self, other) -> bool:
        return self.head == other.head and self.tail() == other.tail()


def _time_key(detection) -> str:
    timestamp = getattr(detection, "timestamp", None)
    return "" if timestamp is None else str(timestamp)


def detection_key(detection) -> tuple:
    """A sort key from a detection's values: time, type, measurement vector, metadata,
    measurement model (type and Properties). Never its identity or memory address."""
    head = (_time_key(detection), type(detection).__qualname__, _vector_bytes(detection))
    return _DetectionKey(detection, head, {}).key()


def _float_vectors(detections: list, converted=None):
    """The detections' measurement vectors as float rows (M, m), or None when they do not
    share one shape; ``converted``: their ``np.array`` as float64, if already made."""
    vectors = converted
    if vectors is None or vectors.ndim != 3 or vectors.shape[0] != len(detections):
        try:
            vectors = np.array([d.state_vector for d in detections], dtype=np.float64)
        except (TypeError, ValueError):
            return None
    if vectors.ndim != 3 or vectors.shape[2] != 1:
        return None
    return vectors[..., 0]


def in_stable_order(detections, rows=None) -> OrderedDetections:
    """The detections of one scan in :func:`detection_key` order, keeping the scan's
    ``detector_context`` (if the collection carries one). ``rows``: the detections'
    measurement vectors as one float64 array in the collection's iteration order
    (``np.array`` of them), when the caller has made it
    (:func:`~ctxmodels.stonesoup.scan_checks.checked_scan_rows`)."""
    context = getattr(detections, "detector_context", None)
    detections = list(detections)
    if not detections:
        return OrderedDetections((), context, None)
    vectors = _float_vectors(detections, rows)
    if len(detections) == 1:  # (most of a 10 Hz sensor's scans: nothing to sort)
        return OrderedDetections(detections, context, vectors)
    times: dict = {}  # str() once per timestamp
    heads = []
    # each row's bytes cut from the rows' (C-ordered) bytes: the row's own tobytes()
    raw = vectors.tobytes() if vectors is not None else b""
    width = len(raw) // len(detections)
    for i, detection in enumerate(detections):
        timestamp = getattr(detection, "timestamp", None)
        time_key = times.get(timestamp)
        if time_key is None:
            time_key = times[timestamp] = _time_key(detection)
        vector = raw[i * width:(i + 1) * width] if vectors is not None \
            else _vector_bytes(detection)
        heads.append((time_key, type(detection).__qualname__, vector))
    order = sorted(range(len(detections)), key=heads.__getitem__)
    if len(set(heads)) == len(heads):  # no ties: the usual case
        return OrderedDetections([detections[i] for i in order], context,
                                 None if vectors is None else vectors[order])
    # equal heads (equal time, type and vector; rare): metadata and model decide
    model_keys: dict = {}  # (models, whose repr is slow, keyed once per scan)
    start = 0
    for end in range(1, len(order) + 1):
        if end < len(order) and heads[order[end]] == heads[order[start]]:
            continue
        if end - start > 1:
            order[start:end] = sorted(order[start:end], key=lambda i: _DetectionKey(
                detections[i], heads[i], model_keys))
        start = end
    return OrderedDetections([detections[i] for i in order], context,
                             None if vectors is None else vectors[order])


def ordered_subset(detections, keep=None) -> OrderedDetections:
    """The detections of a scan in stable order (a list) whose entry of ``keep`` (booleans
    aligned with them; None: all) is true, in that order, as an :class:`OrderedDetections`
    without a context. Their float rows and the scan's measurement-model groups
    (:func:`~ctxmodels.model_key.carry_model_groups`) come along when ``detections`` holds
    them, so nothing is converted or keyed again."""
    rows = getattr(detections, "vectors", None)
    if not (isinstance(rows, np.ndarray) and rows.shape[0] == len(detections)):
        rows = None
    if keep is None:
        kept = range(len(detections))
        subset = OrderedDetections(detections, None, rows)
    else:
        mask = np.asarray(keep, dtype=bool)
        kept = mask.nonzero()[0].tolist()
        subset = OrderedDetections([detections[k] for k in kept], None,
                                   None if rows is None else rows[mask])
    carry_model_groups(detections, subset, kept)
    return subset


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

    def __lt__(self, other: _TrackKey) -> bool:
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
           "ordered_subset", "track_key"]
