"""How the simulated vessels (and the ego) move.

Truth trajectories are fixed per scenario: waypoints joined by constant-rate turns
(:mod:`.paths`) that the turn rate ramps into and out of (below), constant speed per
vessel, i.e. nearly-constant-velocity / coordinated-turn motion. Every motion maps a
batch of times (s after the epoch) to a :class:`MotionSample` in one vectorised call:

* :class:`PathMotion`: constant speed along a path;
* :class:`FormationMotion`: a rigid offset in a leader's body frame;
* :class:`WeaveMotion`: progress along a path while weaving sinusoidally across it;
* :class:`DriftMotion`: station keeping (slow drift, heading oscillating about a mean).

Turn rates ramp
---------------
A vessel cannot change its turn rate instantaneously. The rudder (or outboard) slews over
a second or two, and the hull's yaw rate then follows with a lag: in Nomoto's
first-order steering model the time constant T is of order 1–3 s for a small craft (tens
of seconds for a ship). A designed path of legs and circular arcs is only C¹: its
curvature κ, and so the turn rate ω = speed·κ, steps at every join. Sailing one exactly
keeps the vessel's own velocity continuous (constant speed along a continuous tangent),
but not anything derived from its turn: a formation partner rigidly offset by ``o`` moves
at v + ω·J·R(h)·o, and a vessel weaving at an offset d from a path progresses at
speed·(1 − d·κ). In the formation scenario their truth velocities jumped at the joins,
by up to 0.36 and 0.76 m/s between consecutive 10 Hz states.

So every path is sailed with its turn rate ramped linearly over
:data:`TURN_RATE_RAMP_TIME` = 4 s centred on each join. A linear ramp of duration τ lags
a step by τ/2, as a first-order response with T = τ/2 does: τ = 4 s is T = 2 s, mid-range
for small craft. The value is set from that physical argument alone, not from any
tracking result. In arc length the ramp is speed·τ long, a clothoid transition
(:meth:`~.paths.Path.with_turn_transitions`): the heading outside the ramps is exactly as
designed, and the routes move by less than a metre in the three scenarios (waypoints are
passed within that). Velocities are then continuous and accelerations bounded (they
still step where a ramp starts or ends). ``turn_rate_ramp=0`` sails the designed path
itself.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from typing import NamedTuple

import numpy as np

from .geometry import TWO_PI, wrap_angle
from .paths import Path

__all__ = [
    "TURN_RATE_RAMP_TIME",
    "DriftMotion",
    "FormationMotion",
    "MotionSample",
    "PathMotion",
    "WeaveMotion",
]

TURN_RATE_RAMP_TIME = 4.0
"""Seconds over which a vessel's turn rate ramps from one constant value to the next."""


class MotionSample(NamedTuple):
    """Kinematics at a batch of times; rows where ``exists`` is false are NaN."""

    positions: np.ndarray  # (T, 2)
    velocities: np.ndarray  # (T, 2)
    headings: np.ndarray  # (T,)
    exists: np.ndarray  # (T,) bool


@dataclass(frozen=True)
class PathMotion:
    """Constant speed along a :class:`Path`, starting at ``start_time`` (s after the
    epoch; negative = already under way); exists only while on the path. The turn rate
    ramps over ``turn_rate_ramp`` s at each join (:attr:`sailed_path`)."""

    path: Path
    speed: float
    start_time: float = 0.0
    turn_rate_ramp: float = TURN_RATE_RAMP_TIME

    @cached_property
    def sailed_path(self) -> Path:
        """:attr:`path` as sailed: with clothoid transitions ``speed · turn_rate_ramp``
        long."""
        return self.path.with_turn_transitions(self.speed * self.turn_rate_ramp)

    def sample(self, times) -> MotionSample:
        times = np.asarray(times, dtype=float)
        arc_length = self.speed * (times - self.start_time)
        exists = (arc_length >= 0.0) & (arc_length <= self.path.length)
        positions, tangents, _ = self.sailed_path.sample(arc_length)
        positions[~exists] = np.nan
        velocities = self.speed * tangents
        velocities[~exists] = np.nan
        headings = np.arctan2(tangents[:, 1], tangents[:, 0])
        headings[~exists] = np.nan
        return MotionSample(positions, velocities, headings, exists)

    def turn_rates(self, times) -> np.ndarray:
        times = np.asarray(times, dtype=float)
        _, _, curvatures = self.sailed_path.sample(self.speed * (times - self.start_time))
        return self.speed * curvatures


@dataclass(frozen=True)
class FormationMotion:
    """Rigid formation: a fixed offset in the leader's body frame (x ahead, y to port);
    heading equal to the leader's. Its velocity is continuous because the leader's turn
    rate is."""

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
    lateral offset ``amplitude · sin(2π (t − start_time) / period)`` (positive to port).
    The path's turn rate ramps over ``turn_rate_ramp`` s at each join, as
    :class:`PathMotion`'s does, so the progress speed ``speed · (1 − offset · κ)`` is
    continuous."""

    path: Path
    speed: float
    amplitude: float
    period: float
    start_time: float = 0.0
    turn_rate_ramp: float = TURN_RATE_RAMP_TIME

    @cached_property
    def sailed_path(self) -> Path:
        """:attr:`path` with clothoid transitions ``speed · turn_rate_ramp`` long."""
        return self.path.with_turn_transitions(self.speed * self.turn_rate_ramp)

    def sample(self, times) -> MotionSample:
        times = np.asarray(times, dtype=float)
        elapsed = times - self.start_time
        arc_length = self.speed * elapsed
        exists = (arc_length >= 0.0) & (arc_length <= self.path.length)
        centres, tangents, curvatures = self.sailed_path.sample(arc_length)
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
