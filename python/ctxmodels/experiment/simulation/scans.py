"""What one simulated sensor scan is, and the pieces both sensors share to make one:
scan timing, the scene at a sensor's scan times, and how an object's detection is typed.

Scan times are integer microseconds after the epoch (``period`` and ``phase`` of the
sensor's config), so radar and lidar timestamps are exact and never coincide. A vessel's
detection is a ``TrueDetection`` linked to its ``GroundTruthPath``; static objects,
clutter and land returns are ``Clutter``. Every detection's ``metadata['source']`` is
``'target'`` (plus ``'truth_id'``), ``'static'`` (plus ``'static_id'``), ``'clutter'``
or ``'land'``.
"""

from __future__ import annotations

import datetime
from typing import NamedTuple

import numpy as np
from stonesoup.types.detection import Clutter, Detection, TrueDetection

__all__ = [
    "Scan",
    "SensorPose",
    "SensorScene",
    "object_detection",
    "object_metadata",
    "scan_offsets_us",
]


class SensorPose(NamedTuple):
    """Sensor position (m) and heading (rad, from +x counter-clockwise) at a scan."""

    x: float
    y: float
    heading: float

    @property
    def position(self) -> np.ndarray:
        return np.array([self.x, self.y])


class Scan(NamedTuple):
    """One sensor scan: ``(timestamp, detections, sensor_pose)``."""

    timestamp: datetime.datetime
    detections: set[Detection]
    sensor_pose: SensorPose


class SensorScene(NamedTuple):
    """Object kinematics at one sensor's scan times."""

    ego_positions: np.ndarray  # (K, 2)
    ego_headings: np.ndarray  # (K,)
    positions: np.ndarray  # (K, N, 2) vessels then static objects
    exists: np.ndarray  # (K, N)
    sources: list[tuple[str, str, str]]  # (source, id key, id) per object


def object_metadata(source) -> dict:
    kind, key, object_id = source
    return {"source": kind, key: object_id}


def object_detection(source, state_vector, timestamp, model, metadata, truth_paths):
    """A vessel's detection is a TrueDetection linked to its path; anything else is Clutter."""
    if source[0] == "target":
        return TrueDetection(state_vector, groundtruth_path=truth_paths[source[2]],
                             timestamp=timestamp, measurement_model=model, metadata=metadata)
    return Clutter(state_vector, timestamp=timestamp, measurement_model=model, metadata=metadata)


class ScanStream:
    """One sensor's scans as the (time, detections) stream a tracker reads (again on every
    iteration)."""

    def __init__(self, scans):
        self.scans = scans

    def __iter__(self):
        return ((scan.timestamp, set(scan.detections)) for scan in self.scans)


def scan_offsets_us(period: float, phase: float, duration: float) -> np.ndarray:
    """Scan times in integer microseconds after the epoch, in [0, duration)."""
    period_us, phase_us = round(period * 1e6), round(phase * 1e6)
    end_us = round(duration * 1e6)
    return np.arange(phase_us, end_us, period_us, dtype=np.int64)
