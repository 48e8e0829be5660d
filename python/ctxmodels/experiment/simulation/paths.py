"""Paths of the simulated vessels: straight legs joined by constant-radius turns.

A :class:`Path` is a C¹ curve (position and tangent continuous) parameterised by arc
length; :class:`PathBuilder` lays one out turtle-style (``straight``, ``turn``,
``head_to`` a waypoint) and :func:`tangent_point` finds where a leg meets a circle
tangentially. How a vessel moves along a path is :mod:`.motion`'s business.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import NamedTuple

import numpy as np

from .geometry import TWO_PI, wrap_angle

__all__ = ["Path", "PathBuilder", "tangent_point"]


class _Line(NamedTuple):
    start: np.ndarray
    direction: np.ndarray
    length: float


class _Arc(NamedTuple):
    centre: np.ndarray
    radius: float
    start_angle: float  # angle of the start point seen from the centre
    turn_sign: float  # +1 counter-clockwise (port turn), -1 clockwise
    length: float


class Path:
    """A C¹ curve of straight legs and circular arcs, parameterised by arc length."""

    def __init__(self, segments: Sequence[_Line | _Arc]):
        if not segments:
            raise ValueError("a path needs at least one segment")
        self._segments = tuple(segments)
        self._starts = np.concatenate([[0.0], np.cumsum([seg.length for seg in segments])])

    @property
    def length(self) -> float:
        return float(self._starts[-1])

    def sample(self, arc_length) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Positions (N, 2), unit tangents (N, 2) and signed curvatures (N,) at
        ``arc_length`` (clamped to the path)."""
        s = np.clip(np.atleast_1d(np.asarray(arc_length, dtype=float)), 0.0, self.length)
        positions = np.empty((s.size, 2))
        tangents = np.empty((s.size, 2))
        curvatures = np.zeros(s.size)
        segment_index = np.clip(
            np.searchsorted(self._starts, s, side="right") - 1, 0, len(self._segments) - 1
        )
        for index, seg in enumerate(self._segments):
            mask = segment_index == index
            if not mask.any():
                continue
            along = s[mask] - self._starts[index]
            if isinstance(seg, _Line):
                positions[mask] = seg.start + along[:, None] * seg.direction
                tangents[mask] = seg.direction
            else:
                angle = seg.start_angle + seg.turn_sign * along / seg.radius
                cos, sin = np.cos(angle), np.sin(angle)
                positions[mask] = seg.centre + seg.radius * np.column_stack([cos, sin])
                tangents[mask] = seg.turn_sign * np.column_stack([-sin, cos])
                curvatures[mask] = seg.turn_sign / seg.radius
        return positions, tangents, curvatures


class PathBuilder:
    """Turtle-style construction of a :class:`Path`.

    >>> path = PathBuilder((0, 0), heading=0).straight(100).turn(50, math.pi / 2).build()
    """

    def __init__(self, start, heading: float):
        self._position = np.asarray(start, dtype=float).reshape(2)
        self._heading = float(heading)
        self._segments: list[_Line | _Arc] = []

    @property
    def position(self) -> np.ndarray:
        return self._position.copy()

    @property
    def heading(self) -> float:
        return self._heading

    def straight(self, length: float) -> PathBuilder:
        if length < 0:
            raise ValueError("length must be non-negative")
        if length > 0:
            direction = np.array([math.cos(self._heading), math.sin(self._heading)])
            self._segments.append(_Line(self._position.copy(), direction, float(length)))
            self._position = self._position + length * direction
        return self

    def turn(self, radius: float, angle: float) -> PathBuilder:
        """Constant-radius turn by ``angle`` (rad; positive = to port/counter-clockwise)."""
        if radius <= 0:
            raise ValueError("radius must be positive")
        if angle == 0:
            return self
        sign = 1.0 if angle > 0 else -1.0
        left_normal = np.array([-math.sin(self._heading), math.cos(self._heading)])
        centre = self._position + sign * radius * left_normal
        start_angle = math.atan2(*(self._position - centre)[::-1])
        self._segments.append(_Arc(centre, float(radius), start_angle, sign, radius * abs(angle)))
        end_angle = start_angle + angle
        self._position = centre + radius * np.array([math.cos(end_angle), math.sin(end_angle)])
        self._heading = float(wrap_angle(self._heading + angle))
        return self

    def head_to(self, point, turn_radius: float) -> PathBuilder:
        """Turn towards ``point`` at ``turn_radius`` (shorter side first), then run
        straight to it."""
        target = np.asarray(point, dtype=float).reshape(2)
        offset = target - self._position
        direction = np.array([math.cos(self._heading), math.sin(self._heading)])
        cross = direction[0] * offset[1] - direction[1] * offset[0]
        if abs(cross) < 1e-9 * max(1.0, float(np.hypot(*offset))) and offset @ direction > 0:
            return self.straight(float(np.hypot(*offset)))
        preferred = 1.0 if cross >= 0 else -1.0
        for sign in (preferred, -preferred):
            sweep = self._turn_sweep_towards(target, turn_radius, sign)
            if sweep is not None:
                self.turn(turn_radius, sign * sweep)
                return self.straight(float(np.hypot(*(target - self._position))))
        raise ValueError(f"{point} is inside both turning circles of radius {turn_radius}")

    def _turn_sweep_towards(self, target, radius, sign):
        left_normal = np.array([-math.sin(self._heading), math.cos(self._heading)])
        centre = self._position + sign * radius * left_normal
        to_target = target - centre
        distance = float(np.hypot(*to_target))
        if distance <= radius:
            return None
        # Leaving the circle along its tangent towards the target: the tangent point's
        # radius makes an angle acos(R/d) with the centre→target direction, on the side
        # opposite to the direction of travel.
        tangent_angle = math.atan2(to_target[1], to_target[0]) - sign * math.acos(radius / distance)
        start_angle = math.atan2(*(self._position - centre)[::-1])
        return float((sign * (tangent_angle - start_angle)) % TWO_PI)

    def build(self) -> Path:
        return Path(self._segments)


def tangent_point(start, centre, radius: float, counter_clockwise: bool = True) -> np.ndarray:
    """Point where a straight leg from ``start`` meets the circle (``centre``,
    ``radius``) tangentially, to continue around it in the given direction."""
    start = np.asarray(start, dtype=float)
    centre = np.asarray(centre, dtype=float)
    offset = start - centre
    distance = float(np.hypot(*offset))
    if distance <= radius:
        raise ValueError("start must lie outside the circle")
    sign = 1.0 if counter_clockwise else -1.0
    angle = math.atan2(offset[1], offset[0]) + sign * math.acos(radius / distance)
    return centre + radius * np.array([math.cos(angle), math.sin(angle)])
