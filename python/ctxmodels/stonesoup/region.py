"""Surveillance regions for the point-process trackers: where the PHD is estimated.

A region answers ``contains(points)`` for (N, 2) world x/y positions. A region that moves
with the platform also has ``at(timestamp)``, which gives the region of one scan; the
trackers ask for it once per scan (:class:`PoseCentredRegion`).
"""
from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from stonesoup.base import Base, Property

from ..pose import PoseSource


class CircularRegion(Base):
    """A disc of world x/y: the simplest surveillance region for
    :class:`~ctxmodels.stonesoup.PointProcessMultiTargetTracker`."""

    centre: Sequence[float] = Property(doc="Centre (x, y), metres.")
    radius: float = Property(doc="Radius, metres (> 0).")

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        centre = np.asarray(self.centre, dtype=np.float64).ravel()
        if centre.shape != (2,) or not np.all(np.isfinite(centre)):
            raise ValueError(f"centre: must be a finite (x, y) pair, got {self.centre!r}")
        self.centre, self.radius = (float(centre[0]), float(centre[1])), _radius(self.radius)

    def contains(self, points) -> np.ndarray:
        """Whether each (x, y) row of ``points`` lies in the disc (boundary included)."""
        points = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        offsets = points - np.asarray(self.centre)
        return np.einsum("ij,ij->i", offsets, offsets) <= self.radius ** 2


class PoseCentredRegion(Base):
    r"""A disc that follows the platform: at a scan at time :math:`t`, the points within
    ``radius`` of the platform's position :math:`p(t)` from ``pose_source``.

    The natural region of a moving sensor platform: nothing outside every sensor's reach
    (plus a margin for targets about to enter it) is estimated, and no trajectory is needed
    in advance — the pose source is asked at each scan's time only."""

    pose_source: PoseSource = Property(
        doc="The platform's pose at each scan (e.g. a :class:`~ctxmodels.NavigationTrack`).")
    radius: float = Property(doc="Radius around the platform, metres (> 0).")

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        if not callable(getattr(self.pose_source, "pose_at", None)):
            raise TypeError("pose_source: expected an object with pose_at(timestamp), got "
                            f"{type(self.pose_source).__name__}")
        self.radius = _radius(self.radius)

    def at(self, timestamp) -> CircularRegion:
        """The region of the scan at ``timestamp``: a disc around the platform there."""
        pose = self.pose_source.pose_at(timestamp)
        return CircularRegion(centre=(pose.x, pose.y), radius=self.radius)


def _radius(value) -> float:
    try:
        radius = float(value)
    except (TypeError, ValueError):
        raise TypeError(f"radius: expected a number, got {value!r}") from None
    if not math.isfinite(radius) or radius <= 0:
        raise ValueError(f"radius: must be finite and > 0, got {value!r}")
    return radius


def scan_region(region, timestamp):
    """The region that applies to the scan at ``timestamp`` (``region.at(timestamp)`` for a
    moving region, else ``region`` itself; None stays None)."""
    at = getattr(region, "at", None)
    return at(timestamp) if callable(at) else region


__all__ = ["CircularRegion", "PoseCentredRegion"]
