"""ctxmodels: context-aware sensor models for multi-target tracking.

Detection probability :math:`P_D(x; S)` and clutter density :math:`\\lambda(z; S)` that
depend on the predicted state, the measurement and the sensor's state at each scan (pose,
range bands, blind sectors, land, line of sight), evaluated over whole arrays in a Rust core
and handed to Stone Soup trackers as per-scan :class:`DetectorContext` objects.
"""
from ._core import rule_points
from .clutter import ClutterDensityModel, MetadataThreshold
from .clutter_map import ClutterMap
from .coast import CoastalClutter
from .context import DetectionSet, DetectorContext, detection_positions, measured_ranges
from .detection import DetectionProbabilityModel
from .detection_estimate import DetectionEstimate
from .errors import (ArgumentError, ArgumentTypeError, InfeasibleAssignmentError, InvalidLandError,
                     NonFiniteError, NotPositiveDefiniteError, ShapeError)
from .elevation import ElevationSector
from .horizon import RadarHorizon
from .land import LandMask, LineOfSight
from .pose import ConstantPose, Mounting, NavigationTrack, Pose, PoseSource
from .radar import RadarEquation
from .range_bands import RangeBands
from .range_rate import RangeRateNotch
from .sector import AngularSector
from .sensor import SensorModel
from .zone import Zone

__version__ = "0.1.0"

# SensorModel.from_stonesoup is the Stone Soup adapters' conversion (see ctxmodels.sensor)
from . import stonesoup  # noqa: E402, F401

__all__ = [
    "AngularSector",
    "ArgumentError",
    "ArgumentTypeError",
    "ClutterDensityModel",
    "ClutterMap",
    "CoastalClutter",
    "ConstantPose",
    "DetectionEstimate",
    "DetectionProbabilityModel",
    "DetectionSet",
    "DetectorContext",
    "ElevationSector",
    "LandMask",
    "LineOfSight",
    "MetadataThreshold",
    "Mounting",
    "NavigationTrack",
    "InfeasibleAssignmentError",
    "InvalidLandError",
    "NonFiniteError",
    "NotPositiveDefiniteError",
    "Pose",
    "PoseSource",
    "RadarEquation",
    "RadarHorizon",
    "RangeBands",
    "RangeRateNotch",
    "SensorModel",
    "ShapeError",
    "Zone",
    "detection_positions",
    "measured_ranges",
    "rule_points",
]
