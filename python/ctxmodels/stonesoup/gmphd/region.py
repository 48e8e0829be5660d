"""Surveillance regions for the point-process trackers: where the PHD is estimated.

A region answers ``contains(points)`` for (N, 2) world x/y positions (one (x, y) pair is one
point; other shapes raise, naming ``points``). A region that moves
with the platform also has ``at(timestamp)``, which gives the region of one scan; the
trackers ask for it once per scan (:class:`PoseCentredRegion`).
"""
from __future__ import annotations

import math
import numbers
from collections.abc import Mapping, Sequence

import numpy as np
from stonesoup.base import Base, Property

from ..._upstream import property_slot
from ...errors import argument_error
from ...pose import PoseSource

_CENTRE, _RADIUS = property_slot("centre"), property_slot("radius")


class CircularRegion(Base):
    """A disc of world x/y: the simplest surveillance region for
    :class:`~ctxmodels.stonesoup.PointProcessMultiTargetTracker`."""

    centre: Sequence[float] = Property(doc="Centre (x, y), metres.")
    radius: float = Property(doc="Radius, metres (> 0).")

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.centre, self.radius = _centre(self.centre), _radius(self.radius)

    def contains(self, points) -> np.ndarray:
        """Whether each (x, y) row of ``points`` lies in the disc (boundary included).

        ``points``: an (N, 2) array of world x/y rows (N may be 0), or one (x, y) pair. Any
        other shape — (N, 3) states, a flat list of several points — raises
        :class:`ValueError` naming ``points``, rather than being re-read as pairs. A NaN row
        is outside."""
        points = _points(points)
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
        try:
            pose = self.pose_source.pose_at(timestamp)
        except (TypeError, ValueError) as err:  # e.g. a navigation log that ends too early
            raise argument_error("pose_source", f"no platform pose for the scan at {timestamp} "
                                 f"(the surveillance region's centre): {err}", err) from err
        x, y, radius = pose.x, pose.y, self.radius
        if type(x) is float and type(y) is float and type(radius) is float \
                and math.isfinite(x + y + radius) and radius > 0:
            # what CircularRegion(...) builds from values its checks pass: every scan builds
            # one, and the checks cost more than the rest of the region's work
            region = object.__new__(CircularRegion)
            region.__dict__.update({_CENTRE: (x, y), _RADIUS: radius})
            return region
        return CircularRegion(centre=(x, y), radius=radius)


def _radius(value) -> float:
    """A finite radius > 0 in metres: a real number (Python or NumPy, not a bool — ``True``
    is not 1 m — nor a string or an array)."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(
            value, (numbers.Real, np.integer, np.floating)):
        raise TypeError(f"radius: expected a positive number of metres, got "
                        f"{type(value).__name__} {value!r}")
    radius = float(value)
    if not math.isfinite(radius) or radius <= 0:
        raise ValueError(f"radius: must be a finite number of metres > 0, got {value!r}")
    return radius


def _centre(value) -> tuple[float, float]:
    """A finite (x, y) pair of real numbers (not bools or strings)."""
    if isinstance(value, (str, bytes, Mapping)) or not isinstance(value, (Sequence, np.ndarray)):
        raise TypeError(f"centre: expected a finite (x, y) pair of numbers, got {value!r}")
    items = np.asarray(value, dtype=object).ravel() if isinstance(value, np.ndarray) \
        else list(value)
    if len(items) != 2:
        raise ValueError(f"centre: must be a finite (x, y) pair, got {len(items)} values: "
                         f"{value!r}")
    for item in items:
        if isinstance(item, (bool, np.bool_)) or not isinstance(
                item, (numbers.Real, np.integer, np.floating)):
            raise TypeError(f"centre: expected a finite (x, y) pair of numbers, got {value!r}")
    x, y = float(items[0]), float(items[1])
    if not (math.isfinite(x) and math.isfinite(y)):
        raise ValueError(f"centre: must be a finite (x, y) pair, got {value!r}")
    return x, y


def _points(points) -> np.ndarray:
    """``points`` as an (N, 2) float64 array: (N, 2) rows or one (x, y) pair."""
    if isinstance(points, (str, bytes, Mapping)):
        raise TypeError(f"points: expected (N, 2) x/y rows, got {type(points).__name__}")
    try:
        array = np.asarray(points)
    except (TypeError, ValueError) as err:  # ragged rows
        raise ValueError(f"points: expected (N, 2) x/y rows ({err})") from None
    if array.dtype == object or array.dtype == np.bool_ \
            or not np.issubdtype(array.dtype, np.number) or np.iscomplexobj(array):
        raise TypeError(f"points: expected (N, 2) real x/y rows, got dtype {array.dtype}")
    if array.ndim == 1 and array.shape[0] in (0, 2):
        array = array.reshape(-1, 2)  # no points, or one (x, y) pair
    if array.ndim != 2 or array.shape[1] != 2:
        raise ValueError(f"points: expected (N, 2) x/y rows (or one (x, y) pair), got shape "
                         f"{array.shape}")
    return array.astype(np.float64, copy=False)


def scan_region(region, timestamp):
    """The region that applies to the scan at ``timestamp`` (``region.at(timestamp)`` for a
    moving region, else ``region`` itself; None stays None)."""
    at = getattr(region, "at", None)
    return at(timestamp) if callable(at) else region


__all__ = ["CircularRegion", "PoseCentredRegion"]
