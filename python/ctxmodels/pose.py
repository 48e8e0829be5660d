"""Sensor poses: where the sensor is and where it points at each scan.

Angle convention, once for the whole library: Stone Soup's. World coordinates are x/y
Cartesian metres; headings and bearings are radians counter-clockwise from +x (not compass
bearings). A sensor's body frame has x along its heading and y to its left, so a body
bearing of π is astern. Heights z are metres up. A level pose turns about the vertical
only (heading), so a sensor's elevations are measured from its horizontal plane; a pitched
or rolled one reads bearings and elevations in its own frame, by Stone Soup's rotation of
[roll, pitch, heading] (:class:`Pose`).
"""
from __future__ import annotations

import bisect
import datetime
import math
from collections.abc import Sequence

import numpy as np
from stonesoup.base import Property

from . import _core
from ._upstream import property_slot
from ._component import ModelComponent, as_float, as_rows, as_sequence, frozen_copy
from .errors import ArgumentError, ArgumentTypeError, ShapeError, argument_error


class Pose(ModelComponent):
    r"""Position (x, y, metres), heading (radians from +x, counter-clockwise), height (z,
    metres: where a sensor model with a height in its ``position_mapping`` measures slant
    ranges and elevations from), velocity (vx, vy, vz, m/s: what a range-rate notch
    measures radial speeds against) and pitch and roll (radians).

    A pitched or rolled sensor reads bearings and elevations in its own frame, as Stone Soup
    orients a sensor by [roll, pitch, yaw]: a world offset :math:`d` is
    :math:`M d` there, with

    .. math::
        M = R_x(-\text{roll})\, R_y(\text{pitch})\, R_z(-\text{heading}),

    so a positive pitch tilts the boresight up; :class:`AngularSector` and
    :class:`ElevationSector` read :math:`M d`, everything else (ranges, the horizon, land,
    radial speeds) is the world's."""

    x: float = Property(doc="World x, metres.")
    y: float = Property(doc="World y, metres.")
    heading: float = Property(default=0.0, doc="Heading, radians counter-clockwise from +x.")
    z: float = Property(default=0.0, doc="Height, metres (read only for states with a height).")
    vx: float = Property(default=0.0, doc="Velocity along x, m/s.")
    vy: float = Property(default=0.0, doc="Velocity along y, m/s.")
    vz: float = Property(default=0.0, doc="Vertical velocity, m/s.")
    pitch: float = Property(default=0.0, doc="Pitch, radians (positive: boresight up).")
    roll: float = Property(default=0.0, doc="Roll, radians (Stone Soup's sense).")

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        for name in _NAMES:
            as_float(getattr(self, name), name)

    def as_tuple(self) -> tuple[float, ...]:
        """(x, y, heading, z, vx, vy, vz, pitch, roll), the core's form."""
        return tuple(float(getattr(self, name)) for name in _NAMES)


def as_pose(pose, name: str = "pose") -> Pose:
    """``pose``, a :class:`Pose` or an (x, y, heading), (x, y, heading, z),
    (x, y, heading, z, vx, vy, vz) or (x, y, heading, z, vx, vy, vz, pitch, roll) sequence of
    finite numbers, as a :class:`Pose`; TypeError or ValueError naming ``name`` for anything
    else."""
    if isinstance(pose, Pose):
        return pose
    if isinstance(pose, (str, bytes)) or not isinstance(pose, (Sequence, np.ndarray)):
        raise ArgumentTypeError(name, f"expected a Pose or an (x, y, heading) sequence, got "
                                      f"{type(pose).__name__}")
    values = tuple(np.ravel(pose)) if isinstance(pose, np.ndarray) else tuple(pose)
    if len(values) not in (3, 4, 7, 9):
        raise ArgumentTypeError(name, f"expected a Pose or an (x, y, heading), "
                                      f"(x, y, heading, z), (x, y, heading, z, vx, vy, vz) or "
                                      f"(x, y, heading, z, vx, vy, vz, pitch, roll) sequence, "
                                      f"got {len(values)} values")
    try:
        x, y, heading, *rest = (as_float(v, axis) for v, axis in zip(values, _NAMES))
    except (TypeError, ValueError) as err:
        raise argument_error(name, str(err), err) from None
    return _computed_pose(x, y, heading, *rest[:1], *([tuple(rest[1:4])] if rest[1:] else []),
                          *([tuple(rest[4:])] if rest[4:] else []))


def pose_tuple(pose, name: str = "pose") -> tuple[float, ...]:
    """``pose`` (a :class:`Pose` or a sequence :func:`as_pose` reads) as the core's tuple."""
    return as_pose(pose, name).as_tuple()


_NAMES = ("x", "y", "heading", "z", "vx", "vy", "vz", "pitch", "roll")
_SLOTS = tuple(property_slot(name) for name in _NAMES)


def _computed_pose(x: float, y: float, heading: float, z: float = 0.0,
                   velocity: tuple = (0.0, 0.0, 0.0), tilt: tuple = (0.0, 0.0)) -> Pose:
    """The :class:`Pose` ``Pose(x=x, y=y, heading=heading, z=z, vx=..., vy=..., vz=...,
    pitch=..., roll=...)`` builds, for floats computed from already validated ones
    (interpolated, mounted): without the per-Property checks, which cost more than the rest
    of a scan's context."""
    pose = object.__new__(Pose)
    pose.__dict__["_initialised"] = True
    pose.__dict__.update(zip(_SLOTS, (x, y, heading, z, *velocity, *tilt)))
    return pose


class Mounting(ModelComponent):
    """Where a sensor sits on its platform: lever arm in the platform's body frame (and
    height above it) and the yaw, pitch and roll of the sensor relative to the platform.
    The sensor's angles are the platform's plus these, as Stone Soup adds a sensor's
    ``rotation_offset`` to its platform's orientation; the lever arm turns with the
    platform's heading only."""

    forward: float = Property(default=0.0, doc="Lever arm along the platform heading, metres.")
    left: float = Property(default=0.0, doc="Lever arm to the platform's left, metres.")
    yaw: float = Property(default=0.0, doc="Boresight yaw relative to the platform, radians.")
    up: float = Property(default=0.0, doc="Height of the sensor above the platform's z, metres.")
    pitch: float = Property(default=0.0, doc="Pitch relative to the platform, radians (up > 0).")
    roll: float = Property(default=0.0, doc="Roll relative to the platform, radians.")

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        for name in ("forward", "left", "yaw", "up", "pitch", "roll"):
            as_float(getattr(self, name), name)

    def apply(self, platform: Pose) -> Pose:
        """The sensor's pose on a platform at ``platform``, moving with it (the lever arm's
        own speed while the platform turns is left out)."""
        x, y, heading, z = _core.mount(platform.as_tuple(), float(self.forward), float(self.left),
                                       float(self.yaw), float(self.up))
        pitch, roll = (float(platform.pitch) + float(self.pitch),
                       float(platform.roll) + float(self.roll))
        if not (math.isfinite(pitch) and math.isfinite(roll)):
            raise ArgumentError("mounting", f"the mounted sensor's pitch {pitch} or roll {roll} "
                                            "is not finite")
        return _computed_pose(x, y, heading, z, platform.as_tuple()[4:7], (pitch, roll))


class PoseSource(ModelComponent):
    """Gives the platform pose at a scan's timestamp."""

    def pose_at(self, timestamp: datetime.datetime | None) -> Pose:
        raise NotImplementedError


class ConstantPose(PoseSource):
    """A platform that does not move (a coastal radar, a moored buoy)."""

    pose: Pose = Property(doc="The platform's pose at every scan.")

    def pose_at(self, timestamp=None) -> Pose:
        return self.pose


def _seconds(timestamps: Sequence[datetime.datetime], epoch: datetime.datetime) -> np.ndarray:
    return np.array([(t - epoch).total_seconds() for t in timestamps], dtype=np.float64)


def time_kind(time) -> str | None:
    """'naive' or 'timezone-aware' for a datetime (the two cannot be compared), else None."""
    if isinstance(time, datetime.datetime):
        return "timezone-aware" if time.utcoffset() is not None else "naive"
    return None


class NavigationTrack(PoseSource):
    r"""Platform poses interpolated from a navigation log.

    Positions are interpolated linearly in time; headings along the shorter arc of the
    circle (so 179° → -179° passes through 180°, not 0°); the velocity is that of the
    interpolation, the log's segment (the next one at a logged time, the last one at the
    end; 0 for a one-entry log). A timestamp outside the log raises :class:`ValueError`
    rather than extrapolating.
    """

    timestamps: Sequence[datetime.datetime] = Property(
        doc="Strictly increasing log times, all naive or all timezone-aware (stored as a tuple).")
    positions: np.ndarray = Property(doc="(T, 2) world x/y positions, or (T, 3) x/y/z with the "
                                         "platform's height, metres.")
    headings: np.ndarray = Property(doc="(T,) headings, radians counter-clockwise from +x.")

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        object.__setattr__(self, "_initialised", False)
        self.timestamps = as_sequence(self.timestamps, "timestamps", "datetimes")
        positions = as_rows(self.positions, "positions")
        if positions.shape[1] not in (2, 3):
            raise ShapeError("positions", f"must have 2 columns (x, y) or 3 (x, y, z), got shape "
                                          f"{positions.shape}")
        self.positions = frozen_copy(positions)
        headings = np.asarray(self.headings)
        if headings.dtype == object or not (np.issubdtype(headings.dtype, np.integer)
                                            or np.issubdtype(headings.dtype, np.floating)):
            raise TypeError(f"headings: must be real numbers (radians), got dtype {headings.dtype}")
        self.headings = frozen_copy(headings.ravel())
        object.__setattr__(self, "_initialised", True)
        n = len(self.timestamps)
        if n == 0:
            raise ValueError("timestamps: a navigation track needs at least one entry")
        if not all(isinstance(t, datetime.datetime) for t in self.timestamps):
            raise TypeError("timestamps: must be datetime.datetime objects")
        kinds = [time_kind(t) for t in self.timestamps]
        if any(kind != kinds[0] for kind in kinds):
            k = next(i for i, kind in enumerate(kinds) if kind != kinds[0])
            raise TypeError(f"timestamps: mixes naive and timezone-aware datetimes (entry 0 is "
                            f"{kinds[0]}, entry {k} is {kinds[k]})")
        if self.positions.shape[0] != n or self.headings.shape[0] != n:
            raise ValueError(
                f"positions/headings: need one row per timestamp ({n}), got "
                f"{self.positions.shape[0]} positions and {self.headings.shape[0]} headings")
        if not (np.all(np.isfinite(self.positions)) and np.all(np.isfinite(self.headings))):
            raise ValueError("positions/headings: must be finite")
        seconds = _seconds(self.timestamps, self.timestamps[0])
        if np.any(np.diff(seconds) <= 0):
            raise ValueError("timestamps: must be strictly increasing")

    def pose_at(self, timestamp: datetime.datetime) -> Pose:
        if not isinstance(timestamp, datetime.datetime):
            raise TypeError(f"timestamp: expected a datetime, got {type(timestamp).__name__}")
        log = self._cached("log", self._log)
        last = log.last
        # A scan asks twice (its context, the tracker's region); the track is immutable, so
        # an equal plain datetime (same offset from the first entry) has the same pose.
        if last is not None and type(timestamp) is datetime.datetime and timestamp == last[0]:
            return last[1]
        if time_kind(timestamp) != log.kind:
            raise TypeError(f"timestamp: {timestamp} is {time_kind(timestamp)} but the "
                            f"navigation track's timestamps are {log.kind}")
        seconds = log.seconds
        t = (timestamp - self.timestamps[0]).total_seconds()
        if t < 0 or t > seconds[-1]:
            raise ValueError(
                f"timestamp: {timestamp} is outside the navigation track "
                f"[{self.timestamps[0]}, {self.timestamps[-1]}]")
        k = bisect.bisect_right(seconds, t) - 1
        if k >= len(seconds) - 1:
            pose = _computed_pose(*log.positions[-1][:2], log.headings[-1],
                                  *(log.positions[-1][2:] or [0.0]), log.velocity(len(seconds) - 2))
        else:
            # Python floats: the same IEEE operations, one rounding each, as on the arrays
            f = (t - seconds[k]) / (seconds[k + 1] - seconds[k])
            # (x, y, and z when the log has heights)
            p0, p1 = log.positions[k], log.positions[k + 1]
            h0, h1 = log.headings[k], log.headings[k + 1]
            turn = math.remainder(h1 - h0, 2 * math.pi)
            heading = math.remainder(h0 + f * turn, 2 * math.pi)
            x, y, *z = ((1 - f) * a + f * b for a, b in zip(p0, p1))
            pose = _computed_pose(x, y, heading, *(z or [0.0]), log.velocity(k))
        if type(timestamp) is datetime.datetime:
            log.last = (timestamp, pose)
        return pose

    def _log(self) -> _NavigationLog:
        return _NavigationLog(_seconds(self.timestamps, self.timestamps[0]).tolist(),
                              self.positions.tolist(), self.headings.tolist(),
                              time_kind(self.timestamps[0]))


class _NavigationLog:
    """A navigation track's log as Python floats (a pose costs a few float operations, not
    a dozen NumPy calls), and the last pose asked for."""

    __slots__ = ("seconds", "positions", "headings", "kind", "last")

    def __init__(self, seconds: list, positions: list, headings: list, kind):
        self.seconds, self.positions, self.headings, self.kind = seconds, positions, headings, kind
        self.last = None

    def velocity(self, k: int) -> tuple[float, float, float]:
        """The velocity along segment ``k`` (entries k to k + 1); 0 without one."""
        if not 0 <= k < len(self.seconds) - 1:
            return (0.0, 0.0, 0.0)
        dt = self.seconds[k + 1] - self.seconds[k]
        v = [(b - a) / dt for a, b in zip(self.positions[k], self.positions[k + 1])]
        return (v[0], v[1], v[2] if len(v) > 2 else 0.0)
