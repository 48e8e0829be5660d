"""The study's trackers on anyone's sensor data: :func:`paper_tracker` checks the user's
streams, sensor models and pose source, derives the sensor models the tracker reads
(:mod:`~ctxmodels.trackers.models`) and assembles its Stone Soup components
(:mod:`~ctxmodels.trackers.components`) into a :class:`~ctxmodels.trackers.PaperTracker`."""
from __future__ import annotations

import datetime
import itertools
import math
from collections.abc import Iterable, Iterator, Mapping

import numpy as np
from stonesoup.predictor.kalman import KalmanPredictor
from stonesoup.updater.kalman import ExtendedKalmanUpdater

from .. import SensorModel
from ..pose import NavigationTrack, PoseSource
from ..errors import argument_error
from ..stonesoup.gmphd.region import PoseCentredRegion
from .components import gmphd_tracker, jpda_tracker, motion_model
from .models import (sees_land, sensor_reach, with_coast, with_learned_clutter,
                     with_learned_detection, with_uniform_clutter)
from .specs import REGION_MARGIN, TRACKERS, UNIFORM_CLUTTER, TrackerSpec
from .tracker import PaperTracker


def paper_tracker(name: str | TrackerSpec, streams: Mapping[str, Iterable],
                  sensor_models: Mapping[str, SensorModel] | None,
                  pose_source: PoseSource, *, primary: str | None = None, fast: bool = True,
                  region_radius: float | None = None) -> PaperTracker:
    r"""One of the study's trackers (:data:`~ctxmodels.trackers.TRACKERS`, by name, or a
    :class:`~ctxmodels.trackers.TrackerSpec`) on anyone's sensor data, as a
    :class:`~ctxmodels.trackers.PaperTracker`: iterate it for ``(time, tracks)`` per scan, as
    any Stone Soup tracker; its ``tracks`` are the current tracks and its
    ``gaussian_mixture`` the GM-PHD's intensity (None for a JPDA).

    ``streams``: sensor name → an iterable of ``(time, detections)`` scans in time order
    (a Stone Soup detector or reader, or a list), empty scans included — an empty scan is
    what tells a context-aware tracker that the sensor looked and saw nothing. Each
    detection carries its own measurement model. Scans of different sensors are merged in
    time order; at equal times they go in the order of ``streams``. An iterator that yields
    no scan (a generator already read, say) is refused.

    ``sensor_models``: sensor name → its :class:`~ctxmodels.SensorModel`, needed only where
    read: the context-aware and learned trackers read P_D and λ of every stream (the
    ``pd-aware`` ones P_D, with λ = 1e-3); a GM-PHD without ``region_radius`` reads each
    sensor's P_D reach for its surveillance region; the literal and tuned JPDA read none
    (give None). For ``gmphd-sight`` give models with land and line of sight in P_D
    (:func:`~ctxmodels.experiment.sensors.radar_detection` with ``land``).

    ``pose_source``: the platform's pose at each scan's time (a
    :class:`~ctxmodels.NavigationTrack`, a :class:`~ctxmodels.stonesoup.SensorPose`, …).
    Every GM-PHD's surveillance region follows it (:class:`~ctxmodels.stonesoup.PoseCentredRegion`):
    a disc of ``region_radius`` around the platform at each scan, by default the farthest
    reach of any sensor's P_D (its outermost range band with P_D > 0, plus its mounting's
    lever arm) plus :data:`~ctxmodels.trackers.specs.REGION_MARGIN`.

    ``primary``: the sensor kept by the single-sensor tracker (``gmphd-radar-only``), and
    the one whose model is learned or given a coastal band.
    ``fast``: the trackers that compute each scan in the Rust core (False: the component
    path, the readable reference with the same results).

    The streams are read once, as the tracker runs: give lists or readers, not generators,
    to build several trackers from the same data. The pose source must cover every scan's
    time (contexts and the region ask it at each scan). One pose source serves all sensors:
    mounting offsets go in each ``SensorModel.mounting``.
    """
    spec = name if isinstance(name, TrackerSpec) else (
        TRACKERS.get(name) if isinstance(name, str) else None)
    if spec is None:
        raise ValueError(f"name: unknown tracker {name!r}; choose from {list(TRACKERS)}")
    if not isinstance(streams, Mapping):
        raise TypeError(f"streams: expected a mapping of sensor name -> (time, detections) "
                        f"scans, got {type(streams).__name__}")
    if sensor_models is None:
        sensor_models = {}
    if not isinstance(sensor_models, Mapping):
        raise TypeError(f"sensor_models: expected a mapping of sensor name -> SensorModel (or "
                        f"None where no model is read), got {type(sensor_models).__name__}")
    streams, sensor_models = dict(streams), dict(sensor_models)
    if not streams:
        raise ValueError("streams: no sensor streams given")
    for sensor, stream in streams.items():
        if not isinstance(sensor, str):
            raise TypeError(f"streams: sensor names must be strings, got {sensor!r}")
        if stream is None or isinstance(stream, (str, bytes, Mapping)) \
                or not isinstance(stream, Iterable):
            raise TypeError(f"streams: sensor {sensor!r}: expected an iterable of (time, "
                            f"detections) scans, got {type(stream).__name__}")
    wrong = [sensor for sensor, model in sensor_models.items() if not isinstance(model, SensorModel)]
    if wrong:
        raise TypeError(f"sensor_models: expected SensorModel values; not one for {wrong}")
    if not callable(getattr(pose_source, "pose_at", None)):
        raise TypeError("pose_source: expected an object with pose_at(timestamp), got "
                        f"{type(pose_source).__name__}")
    if primary is not None and not isinstance(primary, str):
        raise TypeError(f"primary: expected a sensor name (str) or None, got "
                        f"{type(primary).__name__} {primary!r}")
    if primary is not None and primary not in streams:
        raise ValueError(f"primary: {primary!r} is not a stream (one of {list(streams)})")
    if not isinstance(fast, (bool, np.bool_)):
        raise TypeError(f"fast: expected True or False, got {type(fast).__name__} {fast!r}")
    fast = bool(fast)
    if region_radius is not None:
        region_radius = _given_radius(region_radius)
    if spec.primary_only:
        if primary is None:
            raise ValueError(f"primary: {spec.name} keeps one sensor; name it (one of "
                             f"{list(streams)})")
        streams = {primary: streams[primary]}
    _check_models(spec, streams, sensor_models, region_radius)
    sensor_models = _models_read(spec, streams, sensor_models, primary)
    streams = {sensor: _not_exhausted(sensor, stream) for sensor, stream in streams.items()}
    for sensor, stream in streams.items():
        _check_stream(sensor, stream, sensor_models[sensor] if spec.uses_context else None,
                      pose_source if spec.uses_context or spec.family == "gmphd" else None)
    predictor = KalmanPredictor(motion_model())
    # Symmetrised posteriors: the standard-form update P − K S Kᵀ lets round-off asymmetry
    # grow about 40-fold per 200 updates of a long-tracked target (measured, stock and core
    # alike), until covariances turn indefinite (a 240 s run, scan ~1900).
    updater = ExtendedKalmanUpdater(measurement_model=None, force_symmetric_covariance=True)
    detector = _detector(spec, streams, sensor_models, pose_source)
    if spec.family == "jpda":
        return PaperTracker(spec=spec, tracker=jpda_tracker(spec, predictor, updater, detector, fast))
    radius = (region_radius if region_radius is not None
              else _region_radius([sensor_models[s] for s in streams]))
    region = PoseCentredRegion(pose_source=pose_source, radius=radius)
    tracker = gmphd_tracker(spec, region, predictor, updater, detector, fast)
    from ..stonesoup.learning import ClutterMapLearner, DetectionLearner
    from .models import LEARNING_GATE
    learners = []
    if spec.clutter == "learned":
        weighting = spec.clutter_map.weighting
        learners.append(ClutterMapLearner(
            weighting=weighting, gate_radius=LEARNING_GATE if weighting == "gates" else None))
    if spec.pd == "learned":
        learners.append(DetectionLearner(gate_radius=LEARNING_GATE))
    return PaperTracker(spec=spec, tracker=tracker, learners=learners)


def _check_models(spec: TrackerSpec, streams, sensor_models, region_radius) -> None:
    """Every model the tracker reads is given (:func:`paper_tracker`'s ``sensor_models``)."""
    needed = spec.uses_context or spec.line_of_sight or spec.coastal or (
        spec.family == "gmphd" and region_radius is None)
    missing = [sensor for sensor in streams if sensor not in sensor_models]
    if needed and missing:
        reads = ("P_D and λ" if spec.uses_context else
                 "the sensors' P_D reach for its surveillance region (or give region_radius)")
        raise ValueError(f"sensor_models: {spec.name} reads {reads}: need a SensorModel for "
                         f"every stream; missing for {missing}")
    if spec.line_of_sight and not any(sees_land(sensor_models[s]) for s in streams):
        raise ValueError(f"sensor_models: {spec.name} needs land in some sensor's P_D "
                         "(LandMask / LineOfSight factors); none has any")


def _models_read(spec: TrackerSpec, streams, sensor_models, primary) -> dict:
    """The sensor models the tracker reads, derived from the user's for ``spec``."""
    models = {sensor: sensor_models[sensor] for sensor in streams if sensor in sensor_models}
    if spec.coastal:
        if primary is None:
            raise ValueError(f"primary: {spec.name} adds a coastal band to the primary sensor's "
                             f"λ; name it (one of {list(streams)})")
        models[primary] = with_coast(models[primary])
    if spec.pd == "context" and spec.clutter == "uniform":
        models = {s: with_uniform_clutter(m, UNIFORM_CLUTTER) for s, m in models.items()}
    if "learned" in (spec.pd, spec.clutter) and primary is None:
        raise ValueError(f"primary: {spec.name} learns the primary sensor's model; name it "
                         f"(one of {list(streams)})")
    if spec.clutter == "learned":
        models[primary] = with_learned_clutter(models[primary], spec.clutter_map)
    if spec.pd == "learned":
        models[primary] = with_learned_detection(models[primary], spec.detection_estimate)
    return models


def _not_exhausted(sensor: str, stream: Iterable) -> Iterable:
    """``stream``, refused when it is an iterator that yields nothing (a generator already
    read gives a tracker no scan, and the run would end at once without a word); its first
    scan is put back in front."""
    if iter(stream) is not stream:
        return stream  # a list, tuple or reader: each iteration starts afresh
    try:
        first = next(stream)
    except StopIteration:
        raise ValueError(f"streams: sensor {sensor!r} is an iterator with no scans left (a "
                         "generator already read?); give a list or a reader, which can be "
                         "read again") from None
    return _Chained(first, stream)


class _Chained:
    """An iterator's first item put back in front of the rest (read once, like the iterator)."""

    def __init__(self, first, rest: Iterator):
        self._items = itertools.chain((first,), rest)

    def __iter__(self):
        return self._items


def _detector(spec: TrackerSpec, streams, sensor_models, pose_source):
    """The tracker's input: the sensors' scans in time order — with each scan's context
    for context-aware trackers, as plain sets for the uniform ones (stock behaviour)."""
    from ..stonesoup import ContextFeeder, MultiSensorFeeder
    if not spec.uses_context:
        return MultiSensorFeeder(feeders=list(streams.values()), sensor_names=list(streams))
    return MultiSensorFeeder(feeders=[
        ContextFeeder(reader=reader, sensor_model=sensor_models[sensor], pose_source=pose_source,
                      sensor_name=sensor)
        for sensor, reader in streams.items()], sensor_names=list(streams))


def _check_stream(sensor: str, stream, model: SensorModel | None, pose_source) -> None:
    """A stream given as a list (or tuple), checked before anything runs: each scan a
    (datetime, set of detections) pair in time order, each detection with the metadata the
    sensor's clutter rules read (``model``, for the context-aware trackers), each time within
    a :class:`~ctxmodels.NavigationTrack` pose source. Errors start ``streams:`` and name the
    sensor and the scan time. Readers and generators are checked as they are read (by the
    feeders, naming the sensor and scan the same way)."""
    from ..stonesoup.feeder import _check_metadata, _required_metadata, _scans
    if not isinstance(stream, (list, tuple)):
        return
    label = f" (sensor {sensor!r})"
    keys = _required_metadata(model) if model is not None else ()
    track = pose_source if isinstance(pose_source, NavigationTrack) else None
    for k, (time, detections) in enumerate(_scans(stream, "streams", label)):
        if not isinstance(time, datetime.datetime):
            raise TypeError(f"streams: scan {k} of sensor {sensor!r} has the time {time!r}; "
                            f"scan times must be datetimes")
        if keys:
            _check_metadata(time, detections, keys, "streams", label)
        if track is not None:
            try:
                track.pose_at(time)  # (a lookup: the log is in memory)
            except (TypeError, ValueError) as err:
                raise argument_error("pose_source", f"no pose for the scan at {time}{label}: {err}",
                                     err) from None


def _given_radius(value) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)) \
            or not (math.isfinite(value) and value > 0):
        raise ValueError(f"region_radius: must be a finite number of metres > 0, got {value!r}")
    return float(value)


def _region_radius(models) -> float:
    reach = max(sensor_reach(model) for model in models)
    if not math.isfinite(reach):
        raise ValueError("region_radius: a sensor's P_D has no outer range band with P_D = 0 "
                         "(a constant P_D, say), so its reach is unbounded; give the "
                         "surveillance region's radius (m)")
    return reach + REGION_MARGIN
