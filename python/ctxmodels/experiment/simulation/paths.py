"""Paths of the simulated vessels: straight legs joined by constant-radius turns, and
the same paths as a vessel sails them, with clothoid transitions into and out of turns.

A :class:`Path` is parameterised by arc length. :class:`PathBuilder` lays one out
turtle-style (``straight``, ``turn``, ``head_to`` a waypoint) and :func:`tangent_point`
finds where a leg meets a circle tangentially. Such a designed path is C¹ (position and
tangent continuous), but its curvature steps at every join of a leg and a turn.

:meth:`Path.with_turn_transitions` makes it C²: the curvature ramps linearly over a given
length centred on each join where it steps (an Euler spiral, or clothoid, the transition
curve of road and railway design). :mod:`.motion` sails every path that way and says why.
A transition is the box average of the designed curvature, so outside the transitions
the heading is exactly as designed; inside one the vessel starts turning half a
transition early and turns more gently, which moves the rest of the path sideways by
about Δκ·L²/24 (Δκ the curvature step, L the transition length) per join.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import NamedTuple

import numpy as np

from .geometry import TWO_PI, wrap_angle

__all__ = ["Path", "PathBuilder", "tangent_point"]

# Gauss–Legendre quadrature of a clothoid's position: with 16 nodes it is exact to
# rounding while the heading turns by less than about a radian over the piece, so
# longer transition pieces are split.
_NODES, _WEIGHTS = np.polynomial.legendre.leggauss(16)
_MAX_PIECE_TURN = 1.0


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


class _Clothoid(NamedTuple):
    start: np.ndarray
    heading: float  # at the start
    curvature: float  # signed, at the start
    curvature_rate: float  # d curvature / d arc length
    length: float


def _evaluate(segment, along: np.ndarray):
    """Positions (M, 2), unit tangents (M, 2) and signed curvatures (M,) at ``along``
    (M,) metres into one segment."""
    if isinstance(segment, _Line):
        positions = segment.start + along[:, None] * segment.direction
        tangents = np.broadcast_to(segment.direction, positions.shape)
        return positions, tangents, np.zeros(along.size)
    if isinstance(segment, _Arc):
        angle = segment.start_angle + segment.turn_sign * along / segment.radius
        cos, sin = np.cos(angle), np.sin(angle)
        positions = segment.centre + segment.radius * np.column_stack([cos, sin])
        tangents = segment.turn_sign * np.column_stack([-sin, cos])
        return positions, tangents, np.full(along.size, segment.turn_sign / segment.radius)

    def heading(u):  # quadratic in arc length
        return segment.heading + u * (segment.curvature + 0.5 * segment.curvature_rate * u)

    # Position = start + ∫ (cos, sin)(heading) du, by quadrature on [0, along].
    headings = heading(along[:, None] * (0.5 * (_NODES + 1.0)))
    tangent_sums = np.column_stack([np.cos(headings) @ _WEIGHTS, np.sin(headings) @ _WEIGHTS])
    positions = segment.start + (0.5 * along)[:, None] * tangent_sums
    end_heading = heading(along)
    tangents = np.column_stack([np.cos(end_heading), np.sin(end_heading)])
    return positions, tangents, segment.curvature + segment.curvature_rate * along


def _line_or_arc(start, heading: float, curvature: float, length: float):
    """The line (curvature 0) or arc starting at ``start`` with this heading."""
    direction = np.array([math.cos(heading), math.sin(heading)])
    if curvature == 0.0:
        return _Line(start, direction, length)
    sign = 1.0 if curvature > 0 else -1.0
    radius = 1.0 / abs(curvature)
    centre = start + sign * radius * np.array([-direction[1], direction[0]])
    return _Arc(centre, radius, math.atan2(*(start - centre)[::-1]), sign, length)


class Path:
    """A curve of straight legs, circular arcs and clothoids, parameterised by arc length."""

    def __init__(self, segments: Sequence[_Line | _Arc | _Clothoid]):
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
            if mask.any():
                positions[mask], tangents[mask], curvatures[mask] = _evaluate(
                    seg, s[mask] - self._starts[index]
                )
        return positions, tangents, curvatures

    def with_turn_transitions(self, length: float) -> Path:
        """This path with its curvature ramped linearly over ``length`` metres centred on
        each join where it steps (shorter where a join lies closer than ``length / 2`` to
        an end of the path, so the path still starts where and as it did). Overlapping
        ramps add up. ``length`` 0 returns the path itself."""
        if length < 0:
            raise ValueError("the transition length must be non-negative")
        if any(isinstance(seg, _Clothoid) for seg in self._segments):
            raise ValueError("the path already has transitions")
        curvatures = np.array(
            [0.0 if isinstance(seg, _Line) else seg.turn_sign / seg.radius
             for seg in self._segments]
        )
        joins, steps = self._starts[1:-1], np.diff(curvatures)
        joins, steps = joins[steps != 0.0], steps[steps != 0.0]
        if length == 0 or joins.size == 0:
            return self
        half = np.minimum(0.5 * length, np.minimum(joins, self.length - joins))
        bounds = np.unique(np.concatenate([[0.0, self.length], joins - half, joins + half]))

        def ramped_curvature(s):  # the box average of the designed curvature
            ramps = np.clip((s - joins + half) / (2 * half), 0.0, 1.0)
            return curvatures[0] + float(np.sum(steps * ramps))

        # (length, curvature at its start, curvature rate or None where as designed)
        pieces = []
        for lo, hi in zip(bounds[:-1], bounds[1:]):
            ramps = np.abs(0.5 * (lo + hi) - joins) < half
            if not ramps.any():
                index = int(np.searchsorted(self._starts, 0.5 * (lo + hi), side="right") - 1)
                pieces.append((hi - lo, float(curvatures[index]), None))
                continue
            rate = float(np.sum(steps[ramps] / (2 * half[ramps])))
            start = ramped_curvature(lo)
            turn = max(abs(start), abs(start + rate * (hi - lo))) * (hi - lo)
            count = max(1, math.ceil(turn / _MAX_PIECE_TURN))
            piece = (hi - lo) / count
            pieces += [(piece, start + rate * i * piece, rate) for i in range(count)]

        position, tangent, _ = _evaluate(self._segments[0], np.zeros(1))
        position, heading = position[0], math.atan2(tangent[0, 1], tangent[0, 0])
        segments = []
        for piece, curvature, rate in pieces:
            # Transition pieces stay clothoids even where overlapping ramps cancel: an
            # arc of rounding-error curvature would put its centre at 1e16 m.
            segment = (_line_or_arc(position, heading, curvature, piece) if rate is None
                       else _Clothoid(position, heading, curvature, rate, piece))
            segments.append(segment)
            position = _evaluate(segment, np.array([piece]))[0][0]
            heading += piece * (curvature + 0.5 * (rate or 0.0) * piece)
        return Path(segments)


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
