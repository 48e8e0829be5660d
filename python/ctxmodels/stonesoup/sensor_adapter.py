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
simulator or the platform has moved the sensor.

Coverage is planar: a 3-D sensor (``RadarElevationBearingRange``) is read on the x/y
plane of its ``position_mapping``, exact for targets at the sensor's height; roll or
pitch would tilt the coverage out of the plane and raise. The clutter density is the
caller's: Stone Soup's clutter models are generators, not densities in the detections'
measurement space.
"""
from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
from stonesoup.base import Property
from stonesoup.buffered_generator import BufferedGenerator
from stonesoup.feeder.base import DetectionFeeder

from ..clutter import ClutterDensityModel
from ..context import DetectionSet
from ..detection import DetectionProbabilityModel
from ..pose import Pose, PoseSource
from ..range_bands import RangeBands
from ..sector import AngularSector
from ..sensor import SensorModel

#: The Stone Soup sensor classes read here (by name, so the module imports without them).
SUPPORTED = ("RadarBearingRange", "RadarRotatingBearingRange", "RadarBearing",
             "RadarRotatingBearing", "RadarElevationBearingRange")


def _kind(sensor) -> str:
    """The sensor's class name, which must be one of :data:`SUPPORTED` exactly: a subclass
    (``RadarRotatingElevationBearingRange``, a range-rate radar, a user's own) may add
    coverage rules these models would silently drop."""
    cls = type(sensor)
    if cls.__name__ in SUPPORTED and cls.__module__.startswith("stonesoup."):
        if getattr(sensor, "obstacles", None):
            raise ValueError("sensor: has obstacles, whose occlusion is not read here; use a "
                             "ctxmodels LandMask/LineOfSight for what blocks the view")
        return cls.__name__
    raise TypeError(f"sensor: {cls.__name__} is not a Stone Soup sensor read here; "
                    f"supported: {', '.join(SUPPORTED)}")


#: The supported sensors whose field of view turns with the antenna's dwell centre.
ROTATING = ("RadarRotatingBearingRange", "RadarRotatingBearing")


def _planar_yaw(orientation, argument: str) -> float:
    roll, pitch, yaw = (float(v) for v in np.asarray(orientation, dtype=float).ravel()[:3])
    if roll != 0.0 or pitch != 0.0:
        raise ValueError(f"{argument}: roll {roll} and pitch {pitch} rad tilt the coverage "
                         f"out of the x/y plane; only a yaw is read")
    return yaw


def sensor_model_from_stonesoup(sensor, prob_detection: float, clutter_density: float,
                                *, name: str = "") -> SensorModel:
    """The :class:`~ctxmodels.SensorModel` of a Stone Soup radar: P_D ``prob_detection``
    within its ``max_range`` (and rotating field of view), 0 outside; λ the constant
    ``clutter_density``. Use it with :func:`sensor_pose` at each scan."""
    kind = _kind(sensor)
    p = float(prob_detection)
    if not 0.0 <= p <= 1.0:
        raise ValueError(f"prob_detection: must lie in [0, 1], got {prob_detection!r}")
    factors: list = [p]
    max_range = float(sensor.max_range)
    if math.isnan(max_range) or max_range < 0:
        raise ValueError(f"sensor: max_range must be >= 0, got {sensor.max_range!r}")
    if math.isfinite(max_range):
        # r <= max_range is detectable: the edge belongs to the band below.
        factors.append(RangeBands(edges=(max_range,), values=(1.0, 0.0), upper_owns=(False,)))
    if kind in ROTATING:
        fov = float(sensor.fov_angle)
        if not fov > 0:
            raise ValueError(f"sensor: fov_angle must be > 0, got {sensor.fov_angle!r}")
        if fov < 2 * math.pi:
            factors.append(AngularSector.field_of_view(0.0, fov))
    mapping = tuple(int(m) for m in sensor.position_mapping[:2])
    return SensorModel(detection=DetectionProbabilityModel(factors=factors),
                       clutter=ClutterDensityModel(factors=[float(clutter_density)]),
                       position_mapping=mapping, name=name)


def sensor_pose(sensor) -> Pose:
    """The pose of a Stone Soup sensor now: x/y of its position and the heading of its
    boresight (the antenna's, for a rotating radar), counter-clockwise from +x."""
    kind = _kind(sensor)
    if sensor.position is None or sensor.orientation is None:
        raise ValueError("sensor: has no position or orientation; mount it on a platform")
    position = np.asarray(sensor.position, dtype=float).ravel()
    heading = _planar_yaw(sensor.orientation, "sensor orientation")
    if kind in ROTATING:
        heading += float(np.asarray(sensor.dwell_centre, dtype=float).ravel()[0])
    return Pose(x=float(position[0]), y=float(position[1]), heading=heading)


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
        _kind(self.sensor)

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


class PlatformContextFeeder(DetectionFeeder):
    r"""The scans of Stone Soup's :class:`~stonesoup.simulator.platform.PlatformDetectionSimulator`
    (one per sensor per time step, platform by platform, sensor by sensor) as
    :class:`~ctxmodels.DetectionSet`\ s, each with the context of the sensor that made it:
    its ``sensor_models`` entry at the sensor's pose then (:func:`sensor_pose`)."""

    sensor_models: Sequence[SensorModel] = Property(
        doc="One model per sensor, in the simulator's order (its platforms, then each "
            "platform's sensors); e.g. ``SensorModel.from_stonesoup(sensor, p, λ)``.")

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        sensors = self._sensors()
        models = list(self.sensor_models)
        if len(models) != len(sensors) or not all(isinstance(m, SensorModel) for m in models):
            raise ValueError(f"sensor_models: expected {len(sensors)} SensorModels (one per "
                             f"sensor of the simulator's platforms), got {len(models)}")
        if any(m.mounting is not None for m in models):
            raise ValueError("sensor_models: the sensors' poses already hold their mounting "
                             "offsets; give models without a mounting")
        for sensor in sensors:
            _kind(sensor)

    def _sensors(self) -> list:
        platforms = getattr(self.reader, "platforms", None)
        if platforms is None:
            raise TypeError(f"reader: expected a Stone Soup PlatformDetectionSimulator, got "
                            f"{type(self.reader).__name__}")
        return [sensor for platform in platforms for sensor in platform.sensors]

    @BufferedGenerator.generator_method
    def data_gen(self):
        sensors, models = self._sensors(), list(self.sensor_models)
        for k, (time, detections) in enumerate(self.reader):
            sensor, model = sensors[k % len(sensors)], models[k % len(sensors)]
            yield time, DetectionSet(detections, model.context(sensor_pose(sensor), time))


__all__ = ["PlatformContextFeeder", "SUPPORTED", "SensorPose", "sensor_model_from_stonesoup",
           "sensor_pose"]
