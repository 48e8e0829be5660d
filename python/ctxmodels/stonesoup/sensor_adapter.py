r"""Context models from Stone Soup's own sensors: coverage read off a radar, pose off its
platform.

A Stone Soup radar decides what it can detect with ``is_detectable(state)``: the target's
range from the sensor at most ``max_range`` and, for the rotating radars, its bearing from
the antenna within :math:`\pm` ``fov_angle``/2. :func:`sensor_model_from_stonesoup` turns
that into a :class:`~ctxmodels.SensorModel` — P_D :math:`= p` inside the coverage and 0
outside,

.. math::
    P_D(x; S) = p \cdot [\,r \le r_{\max}\,] \cdot
        [\,|\beta - \beta_{\text{antenna}}| \le \theta_{\text{fov}}/2\,],

with the range band owning its edge and the field of view its boundary, as
``is_detectable`` does — and :func:`sensor_pose` reads the sensor's pose :math:`S` now:
its position (platform position plus the rotated mounting offset) and heading (the
platform's yaw plus the sensor's rotation offset, plus the dwell centre for a rotating
radar, whose field of view turns with it). Ask for the pose at each scan, when the
simulator or the platform has moved the sensor; :func:`sensor_context` makes the scan's
context from the radar now, pose included.

Range at the edge: a context made by :func:`sensor_context` (as :class:`PlatformContextFeeder`
makes them) is a :class:`~ctxmodels.stonesoup.radar_context.SensorContext`, which decides
the sliver within :math:`10^{-12}\,r_{\max}` of ``max_range`` with the radar's own range, so
its P_D > 0 exactly where ``is_detectable`` is True (see
:mod:`~ctxmodels.stonesoup.radar_context`). A plain context,
``SensorModel.context(sensor_pose(sensor))`` (and a :class:`~ctxmodels.stonesoup.ContextFeeder`
with :class:`SensorPose`), decides on the world range, with the square root's rounding
decided exactly (:class:`~ctxmodels.RangeBands`): the same answer on every path, input
layout and SIMD backend, a target whose world range is exactly ``max_range`` inside, and
agreement with ``is_detectable`` everywhere outside the sliver.

A 3-D sensor (``RadarElevationBearingRange``, ``RadarRotatingElevationBearingRange``,
``RadarElevationBearingRangeRate``) is read in 3-D: the model's ``position_mapping`` is
the sensor's (x, y, z), the pose has the sensor's height, ``max_range`` bounds the slant
range and a rotating one's ``vertical_extent`` is an
:class:`~ctxmodels.ElevationSector` of :math:`\pm` ``vertical_extent``/2. Its pose
carries the sensor's roll and pitch (a rotating radar's ``tilt_centre`` added to the pitch,
as Stone Soup adds it), so bearings and elevations are read in the tilted antenna's frame
(:class:`~ctxmodels.Pose`). A 2-D radar's frame turns about the vertical only: a roll or
pitch of it raises. The clutter density is the caller's:
Stone Soup's clutter models are generators, not densities in the detections' measurement
space.
"""
from __future__ import annotations

import datetime
import math
import sys
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

import numpy as np
from stonesoup.base import Property
from stonesoup.buffered_generator import BufferedGenerator
from stonesoup.feeder.base import DetectionFeeder
from stonesoup.models.measurement.nonlinear import CartesianToBearingRange
from stonesoup.types.array import StateVector

from .._component import as_float
from ..clutter import ClutterDensityModel
from ..errors import argument_error
from ..context import DetectionSet
from ..detection import DetectionProbabilityModel
from ..pose import Pose, PoseSource
from ..sensor import SensorModel, provide
from .radar_context import SensorContext
from .sensor_coverage import (ROTATING, SPATIAL, SUPPORTED, coverage_factors, planar_yaw,
                              sensor_kind, sensor_number)


def sensor_model_from_stonesoup(sensor, prob_detection: float, clutter_density: float,
                                *, name: str = "") -> SensorModel:
    """The :class:`~ctxmodels.SensorModel` of a Stone Soup radar: P_D ``prob_detection``
    within its ``max_range`` (and rotating field of view), 0 outside; λ the constant
    ``clutter_density``. Use it with :func:`sensor_pose` at each scan. (The same as
    :meth:`ctxmodels.SensorModel.from_stonesoup`.)"""
    return _model_of(SensorModel, sensor, prob_detection, clutter_density, name=name)


def _model_of(cls: type, sensor, prob_detection, clutter_density, *, name: str = ""):
    """:func:`sensor_model_from_stonesoup` as an instance of ``cls`` (a SensorModel class):
    what ``cls.from_stonesoup`` returns."""
    sensor_kind(sensor)  # (the sensor is named first, as before any number)
    p = as_float(prob_detection, "prob_detection", finite=False)
    if not 0.0 <= p <= 1.0:
        raise ValueError(f"prob_detection: must lie in [0, 1], got {prob_detection!r}")
    density = as_float(clutter_density, "clutter_density", finite=False)
    if not (math.isfinite(density) and density >= sys.float_info.min):
        raise ValueError(f"clutter_density: must be a finite density > 0, at least "
                         f"{sys.float_info.min} (per unit of the detections' measurement "
                         f"space; trackers divide by it), got {clutter_density!r}")
    if not isinstance(name, str):
        raise TypeError(f"name: expected a string label, got {type(name).__name__} {name!r}")
    factors, mapping = coverage_factors(sensor)
    return cls(detection=DetectionProbabilityModel(factors=[p, *factors]),
               clutter=ClutterDensityModel(factors=[density]), position_mapping=mapping,
               name=name)


# SensorModel.from_stonesoup converts with this
provide("from_stonesoup", _model_of)


def sensor_pose(sensor) -> Pose:
    """The pose of a Stone Soup sensor now: x/y of its position (and its height z for a 3-D
    radar), the heading of its boresight (the antenna's, for a rotating radar),
    counter-clockwise from +x, its platform's velocity, and for a 3-D radar its pitch
    (a rotating one's ``tilt_centre`` included) and roll."""
    kind = sensor_kind(sensor)
    if sensor.position is None or sensor.orientation is None:
        raise ValueError("sensor: has no position or orientation; mount it on a platform")
    position = np.asarray(sensor.position, dtype=float).ravel()
    if kind in SPATIAL:
        roll, pitch, heading = (float(v) for v in
                                np.asarray(sensor.orientation, dtype=float).ravel()[:3])
        if kind in ROTATING:
            pitch += float(np.asarray(sensor.tilt_centre, dtype=float).ravel()[0])
    else:
        roll, pitch, heading = 0.0, 0.0, planar_yaw(sensor.orientation, "sensor orientation")
    if kind in ROTATING:
        heading += float(np.asarray(sensor.dwell_centre, dtype=float).ravel()[0])
    z = float(position[2]) if kind in SPATIAL and position.size > 2 else 0.0
    velocity = getattr(sensor, "velocity", None)
    velocity = [0.0] * 3 if velocity is None else [float(v) for v in np.ravel(velocity)[:3]]
    vx, vy, vz = (velocity + [0.0, 0.0, 0.0])[:3]
    try:
        return Pose(x=float(position[0]), y=float(position[1]), heading=heading, z=z, vx=vx,
                    vy=vy, vz=vz if kind in SPATIAL else 0.0, pitch=pitch, roll=roll)
    except (TypeError, ValueError) as err:
        raise argument_error("sensor", f"its pose now is not finite ({err})", err) from None


class SensorPose(PoseSource):
    """The pose of a Stone Soup sensor at each scan, read off its platform as it moves: the
    pose source of a :class:`~ctxmodels.stonesoup.ContextFeeder` over a Stone Soup
    simulator, which moves the platform to a scan's time before it yields the scan. A scan
    at another time than the platform's latest state raises (the pose there is unknown).
    It is the *sensor's* pose, mounting included: pair it with a sensor model without a
    ``mounting``."""

    sensor: Any = Property(doc="A supported Stone Soup sensor, mounted on a platform.")

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        sensor_kind(self.sensor)

    def pose_at(self, timestamp=None) -> Pose:
        platform_time = _platform_time(self.sensor)
        if timestamp is not None and platform_time is not None and platform_time != timestamp:
            raise ValueError(f"timestamp: the sensor's platform is at {platform_time}, not at "
                             f"the scan time {timestamp}; read the pose when the simulator "
                             f"yields the scan")
        return sensor_pose(self.sensor)


def _platform_time(sensor):
    states = getattr(getattr(sensor, "movement_controller", None), "states", None)
    return states[-1].timestamp if states else None


def _range_model(sensor, kind: str):
    """The measurement model the radar's ``is_detectable`` computes the range with now, and
    the row of its output that is the range. The bearing-only radars measure range with a
    bearing–range model at the same position and heading (the rotating one's antenna
    heading included)."""
    if kind in ("RadarBearing", "RadarRotatingBearing"):
        orientation = np.asarray(sensor.orientation, dtype=float).reshape(-1, 1).copy()
        if kind == "RadarRotatingBearing":
            orientation[2, 0] += float(np.asarray(sensor.dwell_centre, dtype=float).ravel()[0])
        model = CartesianToBearingRange(
            ndim_state=sensor.ndim_state, mapping=sensor.position_mapping,
            noise_covar=sensor.noise_covar, translation_offset=sensor.position,
            rotation_offset=StateVector(orientation))
        return model, 1
    return sensor.measurement_model, 2 if kind in SPATIAL else 1


def sensor_context(sensor, sensor_model: SensorModel,
                   timestamp: datetime.datetime | None = None) -> SensorContext:
    """The context of a scan of the Stone Soup radar ``sensor`` taken now: ``sensor_model``
    (e.g. ``SensorModel.from_stonesoup(sensor, p, λ)``, without a ``mounting``) at the
    sensor's pose now (:func:`sensor_pose`), deciding the range edge as the radar's
    ``is_detectable`` does (:class:`SensorContext`). ``timestamp`` labels the scan."""
    kind = sensor_kind(sensor)
    if not isinstance(sensor_model, SensorModel):
        raise TypeError(f"sensor_model: expected a SensorModel, got "
                        f"{type(sensor_model).__name__}")
    if sensor_model.mounting is not None:
        raise ValueError("sensor_model: has a mounting, but the sensor's pose already holds "
                         "its mounting offset; give a model without one")
    _check_mapping(sensor, sensor_model, "sensor_model")
    return _sensor_context(sensor, sensor_model, timestamp, kind)


def _check_mapping(sensor, sensor_model: SensorModel, argument: str) -> None:
    """The model must read the target's position where the radar measures it: x and y, and
    z for a 3-D radar (whose range is the slant range)."""
    read = tuple(int(i) for i in sensor_model.position_mapping)
    measured = tuple(int(i) for i in tuple(sensor.position_mapping)[:3 if sensor_kind(sensor)
                                                                    in SPATIAL else 2])
    if read != measured:
        raise ValueError(f"{argument}: position_mapping {read} is not the sensor's "
                         f"{measured}; the model would read another state entry as the "
                         f"target's position than the radar measures")


def _sensor_context(sensor, sensor_model: SensorModel, timestamp, kind: str | None = None
                    ) -> SensorContext:
    kind = kind or sensor_kind(sensor)
    range_model, range_row = _range_model(sensor, kind)
    return SensorContext(sensor_model=sensor_model, pose=sensor_pose(sensor),
                         timestamp=timestamp, range_model=range_model, range_row=range_row,
                         max_range=sensor_number(sensor, "max_range"))


class PlatformContextFeeder(DetectionFeeder):
    r"""The scans of Stone Soup's :class:`~stonesoup.simulator.platform.PlatformDetectionSimulator`
    (one per sensor per time step, platform by platform, sensor by sensor) as
    :class:`~ctxmodels.DetectionSet`\ s, each with the context of the sensor that made it:
    its ``sensor_models`` entry at the sensor's pose then, deciding the range edge as the
    sensor does (:func:`sensor_context`)."""

    sensor_models: Sequence[SensorModel] = Property(
        doc="One model per sensor, in the simulator's order (its platforms, then each "
            "platform's sensors); e.g. ``SensorModel.from_stonesoup(sensor, p, λ)``.")

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        sensors = self._sensors()
        models = self.sensor_models
        if isinstance(models, SensorModel):
            raise TypeError("sensor_models: expected a list of SensorModels, one per sensor of "
                            "the simulator's platforms, got one SensorModel; wrap it in a list")
        if isinstance(models, (str, bytes, Mapping)) or not isinstance(models, (Sequence,
                                                                             np.ndarray)):
            raise TypeError(f"sensor_models: expected a list of SensorModels, one per sensor "
                            f"of the simulator's platforms, got {type(models).__name__}")
        models = list(models)
        for i, model in enumerate(models):
            if not isinstance(model, SensorModel):
                raise TypeError(f"sensor_models: item {i} is a {type(model).__name__}, not a "
                                f"SensorModel")
        if len(models) != len(sensors):
            raise ValueError(f"sensor_models: expected {len(sensors)} SensorModels (one per "
                             f"sensor of the simulator's platforms), got {len(models)}")
        if any(m.mounting is not None for m in models):
            raise ValueError("sensor_models: the sensors' poses already hold their mounting "
                             "offsets; give models without a mounting")
        for (where, sensor) in zip(self._places(), sensors):
            try:
                sensor_kind(sensor)
            except (TypeError, ValueError) as err:
                raise argument_error("reader", f"{where}: {err}", err) from None
        for i, (where, sensor, model) in enumerate(zip(self._places(), sensors, models)):
            try:
                _check_mapping(sensor, model, f"sensor_models: item {i}")
            except ValueError as err:
                raise ValueError(f"{err} ({where})") from None
        # The sensors as built: each scan's model is looked up by its sensor, so a sensor
        # mounted later is named, not silently given another sensor's model.
        self._models = {id(sensor): (sensor, model) for sensor, model in zip(sensors, models)}

    def _platforms(self) -> list:
        platforms = getattr(self.reader, "platforms", None)
        if platforms is None or isinstance(platforms, (str, bytes)) \
                or not isinstance(platforms, Iterable):
            raise TypeError(f"reader: expected a Stone Soup PlatformDetectionSimulator, got "
                            f"{type(self.reader).__name__}")
        platforms = list(platforms)
        for i, platform in enumerate(platforms):
            sensors = getattr(platform, "sensors", None)
            if sensors is None or not isinstance(sensors, Iterable):
                raise TypeError(f"reader: platform {i} ({type(platform).__name__}) has no "
                                f"sensors list")
        return platforms

    def _sensors(self) -> list:
        return [sensor for platform in self._platforms() for sensor in platform.sensors]

    def _places(self) -> list[str]:
        return [f"platform {i} sensor {j} ({type(sensor).__name__})"
                for i, platform in enumerate(self._platforms())
                for j, sensor in enumerate(platform.sensors)]

    @BufferedGenerator.generator_method
    def data_gen(self):
        # The simulator yields, at each time, one scan per sensor of its platforms in order
        # (read again at each scan: platforms may gain or lose sensors as it runs).
        previous, step = None, 0
        for time, detections in self.reader:
            step = step + 1 if time == previous else 0
            previous = time
            sensors = self._sensors()
            if not sensors:
                raise ValueError(f"reader: a scan at {time}, but the simulator's platforms "
                                 f"have no sensors now")
            index = step % len(sensors)
            sensor = sensors[index]
            known = self._models.get(id(sensor))
            if known is None or known[0] is not sensor:
                where = self._places()[index]
                raise ValueError(
                    f"sensor_models: no model for {where}, which made the scan at {time}: it "
                    f"was mounted after the PlatformContextFeeder was built (the models are "
                    f"one per sensor then); build the feeder once every sensor is mounted")
            yield time, DetectionSet(detections, _sensor_context(sensor, known[1], time))


__all__ = ["PlatformContextFeeder", "SUPPORTED", "SensorPose", "sensor_context",
           "sensor_model_from_stonesoup", "sensor_pose"]
