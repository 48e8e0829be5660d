"""What a Stone Soup radar covers, read off the sensor as ctxmodels factors (no model or
context is built here: :meth:`ctxmodels.SensorModel.from_stonesoup` builds the model,
:mod:`~ctxmodels.stonesoup.sensor_adapter` the pose and the scan's context; see its
docstring for the coverage's maths)."""
from __future__ import annotations

import math

import numpy as np

from .._component import as_float, as_position_mapping
from ..elevation import ElevationSector
from ..errors import ArgumentError, ArgumentTypeError
from ..range_bands import RangeBands
from ..sector import AngularSector

#: The Stone Soup sensor classes read here (by name, so the module imports without them).
SUPPORTED = ("RadarBearingRange", "RadarRotatingBearingRange", "RadarBearing",
             "RadarRotatingBearing", "RadarElevationBearingRange",
             "RadarRotatingElevationBearingRange", "RadarElevationBearingRangeRate")

#: The supported sensors that measure in 3-D: slant range from the sensor's height, and
#: (the rotating one) elevation; read with the state's (x, y, z).
SPATIAL = ("RadarElevationBearingRange", "RadarRotatingElevationBearingRange",
           "RadarElevationBearingRangeRate")


def sensor_kind(sensor) -> str:
    """The sensor's class name, which must be one of :data:`SUPPORTED` exactly: a subclass
    (a 2-D range-rate radar, a raster-scan one, a user's own) may add coverage rules these
    models would silently drop."""
    cls = type(sensor)
    if cls.__name__ in SUPPORTED and cls.__module__.startswith("stonesoup."):
        if getattr(sensor, "obstacles", None):
            raise ValueError("sensor: has obstacles, whose occlusion is not read here; use a "
                             "ctxmodels LandMask/LineOfSight for what blocks the view")
        return cls.__name__
    raise TypeError(f"sensor: {cls.__name__} is not a Stone Soup sensor read here; "
                    f"supported: {', '.join(SUPPORTED)}")


#: The supported sensors whose field of view turns with the antenna's dwell centre.
ROTATING = ("RadarRotatingBearingRange", "RadarRotatingBearing",
            "RadarRotatingElevationBearingRange")


def planar_yaw(orientation, argument: str) -> float:
    roll, pitch, yaw = (float(v) for v in np.asarray(orientation, dtype=float).ravel()[:3])
    if roll != 0.0 or pitch != 0.0:
        raise ValueError(f"{argument}: roll {roll} and pitch {pitch} rad tilt the coverage "
                         f"out of the x/y plane; only a yaw is read")
    return yaw


def coverage_factors(sensor) -> tuple[list, tuple[int, ...]]:
    """The P_D factors of the radar's coverage (its range limit, a rotating radar's field
    of view and a rotating 3-D radar's vertical extent; none for an unlimited one) and the
    state indices of its x and y (and z for a 3-D radar)."""
    kind = sensor_kind(sensor)
    factors: list = []
    max_range = sensor_number(sensor, "max_range")
    if math.isnan(max_range) or max_range < 0:
        raise ValueError(f"sensor: max_range must be >= 0, got {sensor.max_range!r}")
    if math.isfinite(max_range):
        # r <= max_range is detectable: the edge belongs to the band below.
        factors.append(RangeBands(edges=(max_range,), values=(1.0, 0.0), upper_owns=(False,)))
    if kind in ROTATING:
        fov = sensor_number(sensor, "fov_angle")
        if not fov > 0:
            raise ValueError(f"sensor: fov_angle must be > 0, got {sensor.fov_angle!r}")
        if fov < 2 * math.pi:
            factors.append(AngularSector.field_of_view(0.0, fov))
    if kind == "RadarRotatingElevationBearingRange":
        # (its tilt_centre is in the sensor's pose: the sector is the antenna's own)
        extent = sensor_number(sensor, "vertical_extent")
        if not extent > 0:
            raise ValueError(f"sensor: vertical_extent must be > 0, got {sensor.vertical_extent!r}")
        if extent < math.pi:
            factors.append(ElevationSector(lower=-extent / 2, upper=extent / 2))
    axes = 3 if kind in SPATIAL else 2
    try:
        mapping = as_position_mapping(tuple(sensor.position_mapping)[:axes], "sensor",
                                      heights=axes == 3)
    except (ArgumentError, ArgumentTypeError) as err:
        which = "x, y and z" if axes == 3 else "x and y"
        raise type(err)("sensor", f"position_mapping {sensor.position_mapping!r} is not "
                                  f"{axes} state indices of {which} ({err.detail})") from None
    return factors, mapping


def sensor_number(sensor, attribute: str) -> float:
    """A number the sensor holds (``max_range``, ``fov_angle``), named if it is none."""
    value = getattr(sensor, attribute, None)
    try:
        return as_float(value, "sensor", finite=False)
    except TypeError:
        raise TypeError(f"sensor: {attribute} must be a number, got {type(value).__name__} "
                        f"{value!r}") from None
