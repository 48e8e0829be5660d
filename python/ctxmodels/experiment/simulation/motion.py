"""How the simulated vessels (and the ego) move.

Truth trajectories are fixed per scenario: waypoints joined by constant-rate turns
(:mod:`.paths`), constant speed per vessel, i.e. nearly-constant-velocity /
coordinated-turn motion. Every motion maps a batch of times (s after the epoch) to a
:class:`MotionSample` in one vectorised call:

* :class:`PathMotion`: constant speed along a path;
* :class:`FormationMotion`: a rigid offset in a leader's body frame;
* :class:`WeaveMotion`: progress along a path while weaving sinusoidally across it;
* :class:`DriftMotion`: station keeping (slow drift, heading oscillating about a mean).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from .geometry import TWO_PI, wrap_angle
from .paths import Path

__all__ = ["DriftMotion", "FormationMotion", "MotionSample", "PathMotion", "WeaveMotion"]


class MotionSample(NamedTuple):
    """Kinematics at a batch of times; rows where ``exists`` is false are NaN."""

    positions: np.ndarray  # (T, 2)
    velocities: np.ndarray  # (T, 2)
    headings: np.ndarray  # (T,)
    exists: np.ndarray  # (T,) bool


@dataclass(frozen=True)
class PathMotion:
    """Constant speed along a :class:`Path`, starting at ``start_time`` (s after the
    epoch; negative = already under way); exists only while on the path."""

    path: Path
    speed: float
    start_time: float = 0.0

    def sample(self, times) -> MotionSample:
        times = np.asarray(times, dtype=float)
        arc_length = self.speed * (times - self.start_time)
        exists = (arc_length >= 0.0) & (arc_length <= self.path.length)
        positions, tangents, _ = self.path.sample(arc_length)
        positions[~exists] = np.nan
        velocities = self.speed * tangents
        velocities[~exists] = np.nan
        headings = np.arctan2(tangents[:, 1], tangents[:, 0])
        headings[~exists] = np.nan
        return MotionSample(positions, velocities, headings, exists)

    def turn_rates(self, times) -> np.ndarray:
        times = np.asarray(times, dtype=float)
        _, _, curvatures = self.path.sample(self.speed * (times - self.start_time))
        return self.speed * curvatures


@dataclass(frozen=True)
class FormationMotion:
    """Rigid formation: a fixed offset in the leader's body frame (x ahead, y to port);
    heading equal to the leader's."""

    leader: PathMotion
    body_offset: tuple[float, float]

    def sample(self, times) -> MotionSample:
        lead = self.leader.sample(times)
        cos, sin = np.cos(lead.headings), np.sin(lead.headings)
        ahead, port = self.body_offset
        world_offset = np.column_stack([cos * ahead - sin * port, sin * ahead + cos * port])
        turn_rate = self.leader.turn_rates(times)
        # d/dt R(h)·o = ω J R(h)·o with J the 90° rotation.
        rotation_velocity = turn_rate[:, None] * np.column_stack(
            [-world_offset[:, 1], world_offset[:, 0]]
        )
        return MotionSample(
            lead.positions + world_offset,
            lead.velocities + rotation_velocity,
            lead.headings.copy(),
            lead.exists.copy(),
        )


@dataclass(frozen=True)
class WeaveMotion:
    """Constant progress along a :class:`Path` while weaving sinusoidally across it:
    lateral offset ``amplitude · sin(2π (t − start_time) / period)`` (positive to port)."""

    path: Path
    speed: float
    amplitude: float
    period: float
    start_time: float = 0.0

    def sample(self, times) -> MotionSample:
        times = np.asarray(times, dtype=float)
        elapsed = times - self.start_time
        arc_length = self.speed * elapsed
        exists = (arc_length >= 0.0) & (arc_length <= self.path.length)
        centres, tangents, curvatures = self.path.sample(arc_length)
        normals = np.column_stack([-tangents[:, 1], tangents[:, 0]])
        phase = TWO_PI * elapsed / self.period
        offset = self.amplitude * np.sin(phase)
        offset_rate = self.amplitude * TWO_PI / self.period * np.cos(phase)
        positions = centres + offset[:, None] * normals
        # The normal turns with the path: dn/ds = −κ t.
        velocities = (self.speed * (1.0 - offset * curvatures))[:, None] * tangents + offset_rate[
            :, None
        ] * normals
        headings = np.arctan2(velocities[:, 1], velocities[:, 0])
        positions[~exists] = np.nan
        velocities[~exists] = np.nan
        headings[~exists] = np.nan
        return MotionSample(positions, velocities, headings, exists)


@dataclass(frozen=True)
class DriftMotion:
    """Station keeping: slow constant drift, heading oscillating about a mean."""

    origin: tuple[float, float]
    drift_velocity: tuple[float, float] = (0.0, 0.0)
    mean_heading: float = math.pi / 2
    heading_amplitude: float = 0.0
    heading_period: float = 240.0

    def sample(self, times) -> MotionSample:
        times = np.asarray(times, dtype=float)
        velocity = np.asarray(self.drift_velocity, dtype=float)
        positions = np.asarray(self.origin, dtype=float) + times[:, None] * velocity
        velocities = np.broadcast_to(velocity, positions.shape).copy()
        headings = wrap_angle(
            self.mean_heading
            + self.heading_amplitude * np.sin(TWO_PI * times / self.heading_period)
        )
        return MotionSample(positions, velocities, headings, np.ones(times.size, dtype=bool))
