"""Feeders that attach each scan's :class:`~ctxmodels.DetectorContext` to its detections,
and merge several sensors' scans into one time-ordered, asynchronous stream.

A Stone Soup tracker pulls ``(time, detections)`` pairs from its ``detector``. Wrapping a
sensor's reader in :class:`ContextFeeder` turns every scan — empty ones included — into a
:class:`~ctxmodels.DetectionSet` carrying the context of that sensor at that scan, which the
context-aware hypothesisers and updaters read. :class:`MultiSensorFeeder` then interleaves
the sensors by time without touching the scans: a 0.8 Hz radar and a 10 Hz lidar stay two
streams of separate scans, each processed by the tracker at its own timestamp.
"""
from __future__ import annotations

import datetime
import heapq
from collections.abc import Iterable, Iterator, Mapping, Sequence

import numpy as np

from stonesoup.base import Property
from stonesoup.buffered_generator import BufferedGenerator
from stonesoup.feeder.base import DetectionFeeder
from stonesoup.reader import Reader

from ..clutter import MetadataThreshold
from ..context import DetectionSet
from ..errors import argument_error
from ..pose import PoseSource, time_kind
from ..sensor import SensorModel


class _FirstTime:
    """The first scan time seen across the streams of one merge, and whose it was."""

    def __init__(self):
        self.kind: str | None = None
        self.where = ""


def _scans(source: Iterable, name: str, label: str = "",
           first: _FirstTime | None = None) -> Iterator[tuple[datetime.datetime, set]]:
    """``(time, detections)`` pairs of a reader, checked to be pairs, in time order, and all
    naive or all timezone-aware datetimes (also across the streams sharing `first`).
    `label` says whose stream it is in messages (e.g. the sensor's name)."""
    try:
        iterator = iter(source)
    except TypeError:
        raise TypeError(f"{name}: expected a detector/reader iterable as (time, detections) "
                        f"pairs, got {type(source).__name__}") from None
    first = first or _FirstTime()
    previous = None
    for item in iterator:
        try:
            time, detections = item
        except (TypeError, ValueError):
            raise TypeError(f"{name}: each item{label} must be a (time, detections) pair, "
                            f"got {_short(item)}") from None
        kind = time_kind(time)
        if kind is not None:
            if first.kind is None:
                first.kind, first.where = kind, f"{name}{label} at {time}"
            elif kind != first.kind:
                # Checked here: comparing the two kinds would raise a bare TypeError later.
                raise TypeError(f"{name}: the scan at {time}{label} is {kind}, but the scan of "
                                f"{first.where} is {first.kind}; use all naive or all "
                                f"timezone-aware datetimes")
        try:
            backwards = previous is not None and time < previous
        except TypeError:
            raise TypeError(f"{name}: the scan time {time!r}{label} cannot be compared with the "
                            f"previous one, {previous!r}") from None
        if backwards:
            raise ValueError(f"{name}: scans must come in time order, but a scan at {time} "
                             f"follows one at {previous}")
        previous = time
        _check_detections(time, detections, name, label)
        yield time, detections


def _check_detections(time, detections, name: str, label: str) -> None:
    """A scan's detections must be a collection of detections (objects with a
    ``state_vector``): None, text or a lone detection say so, naming the scan."""
    # (the usual collections are no Mapping and iterable: the abstract-class checks, twice
    # a scan, are left to the others)
    plain = type(detections) in _PLAIN_COLLECTIONS
    if hasattr(detections, "state_vector") or not plain and (
            detections is None or isinstance(detections, (str, bytes, Mapping))
            or not isinstance(detections, Iterable)):
        raise TypeError(f"{name}: the scan at {time}{label} holds "
                        f"{type(detections).__name__} {_short(detections)}, not a set of "
                        f"detections (give an empty set for a scan without any)")
    for detection in detections:
        if not hasattr(detection, "state_vector"):
            raise TypeError(f"{name}: the scan at {time}{label} holds "
                            f"{type(detection).__name__} {_short(detection)}, not a detection")


_PLAIN_COLLECTIONS = frozenset({set, frozenset, list, tuple, DetectionSet})


def _short(value) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def _required_metadata(model: SensorModel) -> tuple[str, ...]:
    """The metadata keys every detection of the sensor must carry: those of its clutter
    rules without a ``missing`` density."""
    return tuple(dict.fromkeys(f.key for f in model.clutter.factors
                               if isinstance(f, MetadataThreshold) and f.missing is None))


def _check_metadata(time, detections, keys, name: str, label: str) -> None:
    for detection in detections:
        metadata = getattr(detection, "metadata", None) or {}
        for key in keys:
            if key not in metadata:
                raise ValueError(f"{name}: a detection of the scan at {time}{label} has no "
                                 f"{key!r} in its metadata, which the sensor's clutter rule "
                                 f"on {key!r} reads (it has no `missing` density): "
                                 f"{_short(detection)}")
            value = metadata[key]
            if isinstance(value, (bool, np.bool_)) or not isinstance(
                    value, (int, float, np.integer, np.floating)):
                raise TypeError(f"{name}: a detection of the scan at {time}{label} has "
                                f"metadata {key!r} = {_short(value)}, not a number")


def _sensor_label(feeder) -> str:
    name = getattr(feeder, "sensor_name", None) or \
        getattr(getattr(feeder, "sensor_model", None), "name", "")
    return f" (sensor {name!r})" if name else ""


class ContextFeeder(DetectionFeeder):
    r"""Attaches the detector context of one sensor to each of its scans.

    For every ``(t, detections)`` of :attr:`reader` it yields

    .. math::
        \bigl(t,\ \mathrm{DetectionSet}(\text{detections},\
        S_t = \text{sensor\_model.context}(\text{pose\_source.pose\_at}(t), t))\bigr),

    empty scans included: an empty scan with its context is how a tracker learns the sensor
    looked and saw nothing *there* (and nothing about targets it cannot see). The reader
    must be one sensor's: a Stone Soup detector, reader or simulator, or any iterable of
    ``(time, set_of_detections)`` pairs in time order. A context already on an incoming set
    is replaced. Use it as the ``detector`` of a Stone Soup tracker, or merge several with
    :class:`MultiSensorFeeder`.
    """

    sensor_model: SensorModel = Property(doc="The sensor's observability model.")
    pose_source: PoseSource = Property(
        doc="The platform's pose at each scan time (mounting is applied by the sensor model).")
    sensor_name: str = Property(
        default="", doc="The sensor's name in messages about its scans (default: the sensor "
                        "model's ``name``).")

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        if not isinstance(self.sensor_name, str):
            raise TypeError(f"sensor_name: expected a str, got {type(self.sensor_name).__name__}")
        if not isinstance(self.sensor_model, SensorModel):
            raise TypeError(f"sensor_model: expected a ctxmodels SensorModel, "
                            f"got {type(self.sensor_model).__name__}")
        if not callable(getattr(self.pose_source, "pose_at", None)):
            raise TypeError(f"pose_source: expected a PoseSource (with pose_at(timestamp)), "
                            f"got {type(self.pose_source).__name__}")
        if self.reader is None:
            raise TypeError("reader: a ContextFeeder needs the reader of its sensor")

    @BufferedGenerator.generator_method
    def data_gen(self):
        label = _sensor_label(self)
        required = _required_metadata(self.sensor_model)
        for time, detections in _scans(self.reader, "reader", label):
            if required:
                _check_metadata(time, detections, required, "reader", label)
            try:
                pose = self.pose_source.pose_at(time)
            except (TypeError, ValueError) as err:
                # e.g. naive scan times against an aware navigation log, or a scan after the
                # log ends: name the scan and the sensor
                raise argument_error("pose_source", f"no pose for the scan at {time}{label}: {err}",
                                     err) from err
            context = self.sensor_model.context(pose, time)
            yield time, DetectionSet(detections, context)


class MultiSensorFeeder(DetectionFeeder):
    """Interleaves several sensors' scan streams into one time-ordered asynchronous stream.

    Each scan stays one batch at its own timestamp, with its own detector context: nothing is
    resampled, and scans of different sensors that share a timestamp are *not* merged (they
    have different contexts); they are emitted one after the other, in the order of
    :attr:`feeders` (stable). Each feeder must itself yield in time order; a feeder that
    goes back in time raises :class:`ValueError` naming it.

    Unlike Stone Soup's :class:`~stonesoup.feeder.multi.MultiDataFeeder`, ties never fall
    back on comparing the detection sets themselves.
    """

    reader = None  # Several sources, not one: drop Feeder's ``reader`` Property.
    feeders: Sequence[Reader] = Property(
        doc="One feeder per sensor (typically :class:`ContextFeeder`), or any iterables of "
            "(time, detections) pairs in time order.")
    sensor_names: Sequence[str] = Property(
        default=None, doc="The sensors' names, one per feeder, for messages about their scans "
                          "(default: a feeder's sensor model's name, if it has one).")

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        if isinstance(self.feeders, Reader) or hasattr(self.feeders, "data_gen"):
            raise TypeError(f"feeders: expected a list of feeders, got one "
                            f"{type(self.feeders).__name__}; wrap it in a list")
        if isinstance(self.feeders, (str, bytes, Mapping)) or not isinstance(self.feeders, Iterable):
            raise TypeError(f"feeders: expected a sequence of feeders, "
                            f"got {type(self.feeders).__name__}")
        self.feeders = list(self.feeders)
        if not self.feeders:
            raise ValueError("feeders: need at least one feeder")
        names = self.sensor_names
        if names is not None:
            if isinstance(names, (str, bytes, Mapping)) or not isinstance(names, Sequence) \
                    or len(names) != len(self.feeders) \
                    or not all(isinstance(n, str) for n in names):
                raise TypeError(f"sensor_names: expected one name (str) per feeder "
                                f"({len(self.feeders)}), got {names!r}")
            self.sensor_names = list(names)

    @BufferedGenerator.generator_method
    def data_gen(self):
        first = _FirstTime()
        names = self.sensor_names
        labels = [f" (sensor {names[i]!r})" if names and names[i] else _sensor_label(feeder)
                  for i, feeder in enumerate(self.feeders)]
        streams = [_scans(feeder, f"feeders[{i}]", labels[i], first)
                   for i, feeder in enumerate(self.feeders)]
        # heapq.merge breaks equal keys by stream position: stable, and never compares sets.
        yield from heapq.merge(*streams, key=lambda scan: scan[0])


__all__ = ["ContextFeeder", "MultiSensorFeeder"]
