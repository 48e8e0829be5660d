"""Seeded simulator of the paper's radar–lidar USV experiment (the "truth" side).

The recorded dataset of the paper is not public, so the experiment runs on a faithful
simulation of its sensing geometry (paper Section IV-A, Fig. 2) and scenario
descriptions. This module is deliberately independent of the rest of ``ctxmodels``
(it never imports ``ctxmodels._core``): it is the ground truth the context-aware models
are judged against, so it must not share their code.

Conventions
-----------
Stone Soup's: world x/y Cartesian in metres; headings and bearings in radians,
measured from +x counter-clockwise. Target states are ``[x, vx, y, vy]``. A radar
bearing is relative to the ego's heading (0 = dead ahead, +π/2 = port); this is what
``CartesianToBearingRange(translation_offset=(x, y), rotation_offset=(0, 0, heading))``
produces (checked by experiment and by the tests). Both sensors are mounted at the ego's
navigation reference point (no lever arm), and the navigation track is exact (the
measurement noise stands for all error sources). Timestamps are naive
:class:`datetime.datetime` starting at :data:`EPOCH`.

Sensors (truth models; all values are fields of :class:`RadarConfig` /
:class:`LidarConfig` and can be overridden)
-------------------------------------------------------------------------------------
Radar, 0.8 Hz (period 1.25 s, first scan at the epoch):

* covers 50 m < r < 1612 m outside a 65° blind sector centred astern
  (bearing π relative to the heading, i.e. world heading + π);
* P_D 0.4 for every object (vessel or static) inside coverage and in line of sight,
  0 otherwise (paper eq. pd-radar);
* noise: bearing σ = 1°, range σ = 5 m (plausible for blob centroids of a small
  X-band open-array radar; at 1.5 km 1° is 26 m across the line of sight);
* clutter uniform in bearing–range over the covered arc (2π − 65° = 5.149 rad):
  Poisson(5) per scan in 50–1000 m and Poisson(32) per scan in 1000–1612 m, i.e.
  1.02e-3 and 1.02e-2 per rad·m — the paper's λ_radar (eq. lambda-radar) taken as a
  density in the radar's measurement space, so its context-aware clutter model is the
  true one, and "uniform λ = 1e-3" is misspecified beyond 1 km exactly as in the paper;
* land returns (scenario "islands" only): Poisson(0.01 per metre of coastline) points
  per scan drawn uniformly along all coastlines, kept where the radar sees that piece of
  coast (in coverage, not shadowed), then measured with the radar noise. The islands
  lie beyond lidar range, so the lidar has no land returns.

Lidar, 10 Hz (period 0.1 s, first scan 43 ms after the epoch, so the two sensors are
asynchronous and never share a timestamp):

* detections are segment centroids in world x/y (``LinearGaussian`` on state indices
  (0, 2)), noise σ = 0.5 m per axis; each carries ``metadata['area']`` (m²);
* P_D 0.95 for r < 50 m, 0.2 for 50 ≤ r < 80 m, 0 beyond (paper eq. pd-lidar),
  again subject to line of sight over land;
* vessel segments: area = the vessel's nominal area × lognormal(σ = 0.25), never
  below 10 m² (nominal 15–30 m²: small boats seen from ≤ 80 m);
* static markers: their own small nominal area (buoys ~2 m²) with the same jitter,
  so close markers look like clutter to an area rule — as in reality;
* clutter: Poisson(3) segments per scan uniform in area over 3 m < r < 80 m around the
  ego, i.e. 1.49e-4 per m²; areas lognormal with median 2.5 m² and σ = 0.8
  (≈ 96 % below 10 m²). The paper's λ_lidar (0.1 / 1e-3) is a tuning value, not a
  density (taken per m² it would mean ~2000 clutter points per scan).

Static objects (sea markers, islets) are detected like vessels by both sensors but are
not evaluated ground truth (the paper evaluates the RTK-logged moving vessels); they
are kept in :attr:`ScenarioRun.static_objects`. Land polygons occlude both sensors
(radar shadow); nothing occludes behind another vessel.

Scenarios (registry :data:`SCENARIOS`; ``make_scenario`` also takes 1, 2, 3)
---------------------------------------------------------------------------
``"mixed-range"`` (1)
    Ego holds station (0.03 m/s drift, heading north ±3°). Two vessels run between
    ≈1.5 km and ≈300 m; a third comes in from 1.1 km, loops once around the ego at a
    30 m radius and departs. Sea markers at 40 m and 68 m (lidar range) and further
    out; islets as point objects. Default 480 s (the interval of the paper's
    tracking-output figure).
``"formation"`` (2)
    Ego sails at 3 m/s (east, then a 90° port turn and a 60° starboard turn) with a
    cooperating USV in rigid formation 30 m off its starboard quarter (lidar only:
    inside the radar's 50 m minimum range). A vessel follows 170–300 m astern weaving
    across the ego's wake (in and out of the blind sector), one crosses astern and later
    drops into the blind sector again while the ego heads north, one manoeuvres at
    medium range. Default 480 s.
``"islands"`` (3, ours)
    Ego holds station (heading north, so the blind sector points south) among three
    islands (polygons, ≥ 300 m away); two vessels pass behind islands as seen from the
    ego (radar shadow), one emerges from behind an island, one stays in the open; a
    marker sits in an island's shadow. Default 480 s.

Truth trajectories are fixed per scenario (waypoints joined by constant-rate turns,
constant speed per vessel: nearly-constant-velocity / coordinated-turn motion); the
seed only drives detection, noise and clutter draws. ``duration`` cuts a window from
the start of that fixed timeline. Radar and lidar draws come from independent child
streams of ``numpy.random.default_rng(seed)``, so changing one sensor's settings never
changes the other sensor's detections.

Public API
----------
``make_scenario(name, seed, duration=None, *, radar=None, lidar=None) -> ScenarioRun``
    Generate one named scenario.
``simulate(layout, seed, duration=None, *, radar=None, lidar=None, name="custom")``
    Generate any :class:`SceneLayout` (build your own with :class:`PathBuilder`,
    :class:`PathMotion`, :class:`WeaveMotion`, :class:`FormationMotion`,
    :class:`DriftMotion`, :class:`TargetSpec`, :class:`StaticObject`).
``SCENARIOS``: ``{name: ScenarioSpec}``; ``ScenarioSpec.layout()`` builds its layout.
:class:`ScenarioRun` fields: ``name, seed, duration, truths`` (set of
``GroundTruthPath``, stable ``id``, a state at every radar and lidar timestamp while
the vessel exists), ``static_objects, land, ego`` (:class:`EgoNavigation` at every scan
time), ``radar_scans, lidar_scans`` (time-ordered :class:`Scan` =
``(timestamp, set_of_detections, SensorPose)``), ``radar_times, lidar_times, radar,
lidar``. Vessel detections are ``TrueDetection`` (``groundtruth_path`` set); clutter,
static and land returns are ``Clutter``. Every detection's ``metadata['source']`` is
``'target'`` (plus ``'truth_id'``), ``'static'`` (plus ``'static_id'``),
``'clutter'`` or ``'land'``; lidar detections also carry ``'area'``.
"""

from __future__ import annotations

import datetime
import heapq
import math
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np
from stonesoup.models.measurement.linear import LinearGaussian
from stonesoup.models.measurement.nonlinear import CartesianToBearingRange
from stonesoup.types.angle import Bearing
from stonesoup.types.array import CovarianceMatrix, StateVector
from stonesoup.types.detection import Clutter, Detection, TrueDetection
from stonesoup.types.groundtruth import GroundTruthPath, GroundTruthState

# (a Stone Soup model with its exact Jacobian: no ctxmodels core, no context models)
from ..stonesoup.measurement import AnalyticCartesianToBearingRange

__all__ = [
    "EPOCH",
    "SCENARIOS",
    "DriftMotion",
    "EgoNavigation",
    "FormationMotion",
    "LidarConfig",
    "MotionSample",
    "Path",
    "PathBuilder",
    "PathMotion",
    "RadarConfig",
    "ScenarioRun",
    "ScenarioSpec",
    "Scan",
    "SceneLayout",
    "SensorPose",
    "StaticObject",
    "TargetSpec",
    "WeaveMotion",
    "make_scenario",
    "simulate",
    "tangent_point",
]

EPOCH = datetime.datetime(2024, 6, 1, 12, 0, 0)
"""Time of the first radar scan of every run."""

_TWO_PI = 2.0 * math.pi


def _wrap_angle(angle):
    """Wrap to [-π, π)."""
    return (np.asarray(angle) + math.pi) % _TWO_PI - math.pi


# --------------------------------------------------------------------------------------
# Sensor configuration
# --------------------------------------------------------------------------------------


@dataclass(frozen=True)
class RadarConfig:
    """Truth model of the radar. Angles in radians, distances in metres, times in s."""

    period: float = 1.25
    phase: float = 0.0
    min_range: float = 50.0
    max_range: float = 1612.0
    blind_sector_width: float = math.radians(65.0)
    prob_detection: float = 0.4
    bearing_std: float = math.radians(1.0)
    range_std: float = 5.0
    clutter_boundary_range: float = 1000.0
    clutter_per_scan_near: float = 5.0
    clutter_per_scan_far: float = 32.0
    land_returns_per_metre: float = 0.01

    @property
    def covered_bearing_extent(self) -> float:
        """Width of the bearing interval outside the blind sector (rad)."""
        return _TWO_PI - self.blind_sector_width

    @property
    def clutter_density_near(self) -> float:
        """Clutter density below the boundary range, per rad·m of measurement space."""
        volume = self.covered_bearing_extent * (self.clutter_boundary_range - self.min_range)
        return self.clutter_per_scan_near / volume

    @property
    def clutter_density_far(self) -> float:
        """Clutter density beyond the boundary range, per rad·m of measurement space."""
        volume = self.covered_bearing_extent * (self.max_range - self.clutter_boundary_range)
        return self.clutter_per_scan_far / volume

    @property
    def noise_covar(self) -> CovarianceMatrix:
        return CovarianceMatrix(np.diag([self.bearing_std**2, self.range_std**2]))

    def in_coverage(self, ranges, relative_bearings):
        """Whether points at these ranges and body-frame bearings are in coverage."""
        ranges = np.asarray(ranges)
        outside_blind = (
            np.abs(_wrap_angle(relative_bearings)) < math.pi - self.blind_sector_width / 2
        )
        return (ranges > self.min_range) & (ranges < self.max_range) & outside_blind

    def measurement_model(self, pose: SensorPose) -> CartesianToBearingRange:
        """Bearing–range model of one scan taken from ``pose``: Stone Soup's
        ``CartesianToBearingRange`` with the closed-form Jacobian
        (:class:`~ctxmodels.stonesoup.AnalyticCartesianToBearingRange`). The simulation never
        linearises; the trackers do, and the exact Jacobian keeps their results from
        depending on the last bit of a state (the stock finite difference does)."""
        return AnalyticCartesianToBearingRange(
            ndim_state=4,
            mapping=(0, 2),
            noise_covar=self.noise_covar,
            translation_offset=StateVector([pose.x, pose.y]),
            rotation_offset=StateVector([0.0, 0.0, pose.heading]),
        )


@dataclass(frozen=True)
class LidarConfig:
    """Truth model of the lidar. Distances in metres, areas in m², times in s.

    ``range_bands`` holds ``(upper_range, prob_detection)`` pairs in increasing range;
    beyond the last upper range the lidar sees nothing.
    """

    period: float = 0.1
    phase: float = 0.043
    range_bands: tuple[tuple[float, float], ...] = ((50.0, 0.95), (80.0, 0.2))
    position_std: float = 0.5
    clutter_per_scan: float = 3.0
    clutter_min_range: float = 3.0
    clutter_area_median: float = 2.5
    clutter_area_log_std: float = 0.8
    area_log_std: float = 0.25
    min_vessel_area: float = 10.0

    @property
    def max_range(self) -> float:
        return self.range_bands[-1][0]

    @property
    def clutter_density(self) -> float:
        """Clutter density per m² of the x/y measurement space."""
        area = math.pi * (self.max_range**2 - self.clutter_min_range**2)
        return self.clutter_per_scan / area

    def prob_detection(self, ranges):
        """Truth P_D at these ranges (array)."""
        ranges = np.asarray(ranges, dtype=float)
        prob = np.zeros_like(ranges)
        lower = 0.0
        for upper, band_prob in self.range_bands:
            prob[(ranges >= lower) & (ranges < upper)] = band_prob
            lower = upper
        return prob

    def measurement_model(self) -> LinearGaussian:
        return LinearGaussian(
            ndim_state=4,
            mapping=(0, 2),
            noise_covar=CovarianceMatrix(np.eye(2) * self.position_std**2),
        )


# --------------------------------------------------------------------------------------
# Motion: paths of straight legs and constant-radius turns
# --------------------------------------------------------------------------------------


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
        self._heading = float(_wrap_angle(self._heading + angle))
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
        return float((sign * (tangent_angle - start_angle)) % _TWO_PI)

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
        phase = _TWO_PI * elapsed / self.period
        offset = self.amplitude * np.sin(phase)
        offset_rate = self.amplitude * _TWO_PI / self.period * np.cos(phase)
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
        headings = _wrap_angle(
            self.mean_heading
            + self.heading_amplitude * np.sin(_TWO_PI * times / self.heading_period)
        )
        return MotionSample(positions, velocities, headings, np.ones(times.size, dtype=bool))


# --------------------------------------------------------------------------------------
# Scene description
# --------------------------------------------------------------------------------------


@dataclass(frozen=True)
class TargetSpec:
    """An evaluated (RTK-logged) moving vessel."""

    id: str
    motion: PathMotion | FormationMotion | WeaveMotion
    lidar_area: float = 20.0


@dataclass(frozen=True)
class StaticObject:
    """A sea marker or islet: detected by the sensors, not evaluated ground truth."""

    id: str
    position: tuple[float, float]
    kind: str = "marker"
    lidar_area: float = 2.0


@dataclass(frozen=True)
class SceneLayout:
    """Everything fixed about a scenario; :func:`simulate` adds the random draws."""

    ego: DriftMotion | PathMotion
    targets: tuple[TargetSpec, ...]
    static_objects: tuple[StaticObject, ...] = ()
    land: tuple[np.ndarray, ...] = ()
    default_duration: float = 480.0
    description: str = ""


# --------------------------------------------------------------------------------------
# Output
# --------------------------------------------------------------------------------------


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


@dataclass(eq=False)
class EgoNavigation:
    """The ego's navigation track at every scan time of both sensors."""

    timestamps: list[datetime.datetime]
    positions: np.ndarray  # (T, 2)
    velocities: np.ndarray  # (T, 2)
    headings: np.ndarray  # (T,)
    _index: dict = field(init=False, repr=False)
    _seconds: np.ndarray = field(init=False, repr=False)

    def __post_init__(self):
        self._index = {timestamp: i for i, timestamp in enumerate(self.timestamps)}
        self._seconds = np.array(
            [(t - self.timestamps[0]).total_seconds() for t in self.timestamps]
        )

    def pose_at(self, timestamp: datetime.datetime) -> SensorPose:
        """Pose at a scan time (exact), or interpolated linearly between scan times."""
        index = self._index.get(timestamp)
        if index is not None:
            return SensorPose(*map(float, self.positions[index]), float(self.headings[index]))
        seconds = (timestamp - self.timestamps[0]).total_seconds()
        x = np.interp(seconds, self._seconds, self.positions[:, 0])
        y = np.interp(seconds, self._seconds, self.positions[:, 1])
        heading = np.interp(seconds, self._seconds, np.unwrap(self.headings))
        return SensorPose(float(x), float(y), float(_wrap_angle(heading)))


@dataclass(eq=False)
class ScenarioRun:
    """One generated run: ground truth, scene, navigation and both sensors' scans."""

    name: str
    seed: int
    duration: float
    truths: set[GroundTruthPath]
    static_objects: tuple[StaticObject, ...]
    land: list[np.ndarray]
    ego: EgoNavigation
    radar_scans: list[Scan]
    lidar_scans: list[Scan]
    radar: RadarConfig
    lidar: LidarConfig
    description: str = ""

    @property
    def radar_times(self) -> list[datetime.datetime]:
        """The evaluation timestamps (the paper scores at radar times only)."""
        return [scan.timestamp for scan in self.radar_scans]

    @property
    def lidar_times(self) -> list[datetime.datetime]:
        return [scan.timestamp for scan in self.lidar_scans]

    @property
    def truth_by_id(self) -> dict[str, GroundTruthPath]:
        return {truth.id: truth for truth in sorted(self.truths, key=lambda path: path.id)}

    @property
    def static_positions(self) -> np.ndarray:
        return np.array([obj.position for obj in self.static_objects], dtype=float).reshape(-1, 2)

    def scans(self) -> Iterator[tuple[str, Scan]]:
        """Both sensors' scans merged in time order, as ``(sensor_name, scan)``."""
        radar = (("radar", scan) for scan in self.radar_scans)
        lidar = (("lidar", scan) for scan in self.lidar_scans)
        return heapq.merge(radar, lidar, key=lambda item: item[1].timestamp)


# --------------------------------------------------------------------------------------
# Geometry: land
# --------------------------------------------------------------------------------------


def _object_detection(source, state_vector, timestamp, model, metadata, truth_paths):
    """A vessel's detection is a TrueDetection linked to its path; anything else is Clutter."""
    if source[0] == "target":
        return TrueDetection(state_vector, groundtruth_path=truth_paths[source[2]],
                             timestamp=timestamp, measurement_model=model, metadata=metadata)
    return Clutter(state_vector, timestamp=timestamp, measurement_model=model, metadata=metadata)


def _land_edges(land: Sequence[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """All polygon edges as start points (E, 2) and end points (E, 2)."""
    if not land:
        return np.empty((0, 2)), np.empty((0, 2))
    starts = np.concatenate([np.asarray(poly, dtype=float) for poly in land])
    ends = np.concatenate([np.roll(np.asarray(poly, dtype=float), -1, axis=0) for poly in land])
    return starts, ends


def _sight_blocked(
    origins: np.ndarray,
    targets: np.ndarray,
    edge_starts: np.ndarray,
    edge_ends: np.ndarray,
    chunk: int = 4096,
) -> np.ndarray:
    """Whether each segment origin→target (M, 2 each) crosses any land edge."""
    blocked = np.zeros(len(origins), dtype=bool)
    if len(edge_starts) == 0 or len(origins) == 0:
        return blocked
    edge = edge_ends - edge_starts  # (E, 2)
    for lo in range(0, len(origins), chunk):
        p = origins[lo : lo + chunk, None, :]
        ray = targets[lo : lo + chunk, None, :] - p  # (M, 1, 2)
        to_edge = edge_starts[None] - p  # (M, E, 2)
        denominator = ray[..., 0] * edge[None, :, 1] - ray[..., 1] * edge[None, :, 0]
        with np.errstate(divide="ignore", invalid="ignore"):
            along_ray = (
                to_edge[..., 0] * edge[None, :, 1] - to_edge[..., 1] * edge[None, :, 0]
            ) / denominator
            along_edge = (
                to_edge[..., 0] * ray[..., 1] - to_edge[..., 1] * ray[..., 0]
            ) / denominator
        hits = (along_ray >= 0) & (along_ray <= 1) & (along_edge >= 0) & (along_edge <= 1)
        blocked[lo : lo + chunk] = hits.any(axis=1)
    return blocked


def _on_land(points: np.ndarray, land: Sequence[np.ndarray]) -> np.ndarray:
    """Even–odd point-in-polygon test for points (N, 2)."""
    inside = np.zeros(len(points), dtype=bool)
    for poly in land:
        poly = np.asarray(poly, dtype=float)
        a, b = poly, np.roll(poly, -1, axis=0)
        x, y = points[:, None, 0], points[:, None, 1]
        straddles = (a[None, :, 1] > y) != (b[None, :, 1] > y)
        with np.errstate(divide="ignore", invalid="ignore"):
            crossing_x = a[None, :, 0] + (y - a[None, :, 1]) * (b[None, :, 0] - a[None, :, 0]) / (
                b[None, :, 1] - a[None, :, 1]
            )
        inside ^= (np.count_nonzero(straddles & (x < crossing_x), axis=1) % 2).astype(bool)
    return inside


def _coastline_sampler(land: Sequence[np.ndarray]):
    """Function mapping uniform [0, 1) draws to points spread evenly along all coasts."""
    starts, ends = _land_edges(land)
    lengths = np.hypot(*(ends - starts).T)
    cumulative = np.concatenate([[0.0], np.cumsum(lengths)])

    def points(uniform: np.ndarray) -> np.ndarray:
        s = uniform * cumulative[-1]
        index = np.clip(np.searchsorted(cumulative, s, side="right") - 1, 0, len(lengths) - 1)
        fraction = (s - cumulative[index]) / lengths[index]
        return starts[index] + fraction[:, None] * (ends[index] - starts[index])

    return points, float(cumulative[-1])


# --------------------------------------------------------------------------------------
# Simulation
# --------------------------------------------------------------------------------------


def _scan_offsets_us(period: float, phase: float, duration: float) -> np.ndarray:
    """Scan times in integer microseconds after the epoch, in [0, duration)."""
    period_us, phase_us = round(period * 1e6), round(phase * 1e6)
    end_us = round(duration * 1e6)
    return np.arange(phase_us, end_us, period_us, dtype=np.int64)


def _polar(positions: np.ndarray, ego_positions: np.ndarray, ego_headings: np.ndarray):
    """Ranges and body-frame bearings of positions (K, N, 2) seen from egos (K, 2)."""
    relative = positions - ego_positions[:, None, :]
    ranges = np.hypot(relative[..., 0], relative[..., 1])
    bearings = _wrap_angle(np.arctan2(relative[..., 1], relative[..., 0]) - ego_headings[:, None])
    return ranges, bearings


def _visible(candidates, positions, ego_positions, edges):
    """Line-of-sight mask over land for the candidate (K, N) pairs."""
    visible = candidates.copy()
    if len(edges[0]) == 0:
        return visible
    scan_index, object_index = np.nonzero(candidates)
    blocked = _sight_blocked(ego_positions[scan_index], positions[scan_index, object_index], *edges)
    visible[scan_index[blocked], object_index[blocked]] = False
    return visible


class _Scene(NamedTuple):
    """Object kinematics at one sensor's scan times."""

    ego_positions: np.ndarray  # (K, 2)
    ego_headings: np.ndarray  # (K,)
    positions: np.ndarray  # (K, N, 2) vessels then static objects
    exists: np.ndarray  # (K, N)
    sources: list[tuple[str, str, str]]  # (source, id key, id) per object


def _object_metadata(source) -> dict:
    kind, key, object_id = source
    return {"source": kind, key: object_id}


def _radar_scans(
    config: RadarConfig, scene: _Scene, timestamps, truth_paths, land, rng
) -> list[Scan]:
    scan_count, object_count = scene.exists.shape
    ranges, bearings = _polar(scene.positions, scene.ego_positions, scene.ego_headings)
    with np.errstate(invalid="ignore"):
        covered = scene.exists & config.in_coverage(ranges, bearings)
    edges = _land_edges(land)
    covered = _visible(covered, scene.positions, scene.ego_positions, edges)

    # Draw everything up front, independent of coverage, so the stream is stable.
    detect_draws = rng.random((scan_count, object_count))
    object_noise = rng.standard_normal((scan_count, object_count, 2))
    detected = covered & (detect_draws < config.prob_detection)

    half_arc = config.covered_bearing_extent / 2
    near_counts = rng.poisson(config.clutter_per_scan_near, scan_count)
    far_counts = rng.poisson(config.clutter_per_scan_far, scan_count)
    # Bearings uniform over the covered arc, centred on dead ahead.
    near_clutter = np.column_stack(
        [
            rng.uniform(-half_arc, half_arc, near_counts.sum()),
            rng.uniform(config.min_range, config.clutter_boundary_range, near_counts.sum()),
        ]
    )
    far_clutter = np.column_stack(
        [
            rng.uniform(-half_arc, half_arc, far_counts.sum()),
            rng.uniform(config.clutter_boundary_range, config.max_range, far_counts.sum()),
        ]
    )
    near_split = np.split(near_clutter, np.cumsum(near_counts)[:-1])
    far_split = np.split(far_clutter, np.cumsum(far_counts)[:-1])

    land_split = [np.empty((0, 2))] * scan_count
    if land and config.land_returns_per_metre > 0:
        land_split = _land_returns(config, scene, land, edges, rng)

    scans = []
    for k, timestamp in enumerate(timestamps):
        pose = SensorPose(
            float(scene.ego_positions[k, 0]),
            float(scene.ego_positions[k, 1]),
            float(scene.ego_headings[k]),
        )
        model = config.measurement_model(pose)
        detections: set[Detection] = set()
        for j in np.flatnonzero(detected[k]):
            bearing = bearings[k, j] + config.bearing_std * object_noise[k, j, 0]
            range_ = ranges[k, j] + config.range_std * object_noise[k, j, 1]
            state_vector = StateVector([Bearing(_wrap_angle(bearing)), range_])
            metadata = _object_metadata(scene.sources[j])
            detections.add(_object_detection(scene.sources[j], state_vector, timestamp, model,
                                             metadata, truth_paths))
        for measured, source in (
            (near_split[k], "clutter"),
            (far_split[k], "clutter"),
            (land_split[k], "land"),
        ):
            for bearing, range_ in measured:
                detections.add(
                    Clutter(
                        StateVector([Bearing(bearing), range_]),
                        timestamp=timestamp,
                        measurement_model=model,
                        metadata={"source": source},
                    )
                )
        scans.append(Scan(timestamp, detections, pose))
    return scans


def _land_returns(config: RadarConfig, scene: _Scene, land, edges, rng) -> list[np.ndarray]:
    """Measured (bearing, range) land returns per scan from the radar-visible coast."""
    coast_points, coast_length = _coastline_sampler(land)
    scan_count = len(scene.ego_headings)
    counts = rng.poisson(config.land_returns_per_metre * coast_length, scan_count)
    points = coast_points(rng.random(counts.sum()))
    noise = rng.standard_normal((counts.sum(), 2))
    scan_index = np.repeat(np.arange(scan_count), counts)
    ego = scene.ego_positions[scan_index]
    relative = points - ego
    ranges = np.hypot(relative[:, 0], relative[:, 1])
    bearings = _wrap_angle(
        np.arctan2(relative[:, 1], relative[:, 0]) - scene.ego_headings[scan_index]
    )
    keep = config.in_coverage(ranges, bearings)
    # Stop the sight line 1 m short: the point itself lies on the coast.
    short_of_coast = points - relative / np.maximum(ranges, 1e-9)[:, None]
    keep[keep] &= ~_sight_blocked(ego[keep], short_of_coast[keep], *edges)
    measured = np.column_stack(
        [
            _wrap_angle(bearings + config.bearing_std * noise[:, 0]),
            ranges + config.range_std * noise[:, 1],
        ]
    )
    return [measured[(scan_index == k) & keep] for k in range(scan_count)]


def _lidar_scans(
    config: LidarConfig, scene: _Scene, timestamps, truth_paths, areas, land, rng
) -> list[Scan]:
    scan_count, object_count = scene.exists.shape
    ranges, _ = _polar(scene.positions, scene.ego_positions, scene.ego_headings)
    with np.errstate(invalid="ignore"):
        prob = np.where(scene.exists, config.prob_detection(np.nan_to_num(ranges, nan=np.inf)), 0.0)
    covered = _visible(prob > 0, scene.positions, scene.ego_positions, _land_edges(land))

    detect_draws = rng.random((scan_count, object_count))
    object_noise = rng.standard_normal((scan_count, object_count, 2))
    area_jitter = rng.standard_normal((scan_count, object_count))
    detected = covered & (detect_draws < prob)
    measured = scene.positions + config.position_std * object_noise
    object_areas = np.asarray(areas)[None, :] * np.exp(config.area_log_std * area_jitter)
    is_vessel = np.array([source[0] == "target" for source in scene.sources])
    object_areas[:, is_vessel] = np.maximum(object_areas[:, is_vessel], config.min_vessel_area)

    counts = rng.poisson(config.clutter_per_scan, scan_count)
    total = counts.sum()
    # Uniform in area over the annulus: r² uniform.
    clutter_range = np.sqrt(rng.uniform(config.clutter_min_range**2, config.max_range**2, total))
    clutter_angle = rng.uniform(-math.pi, math.pi, total)
    clutter_area = config.clutter_area_median * np.exp(
        config.clutter_area_log_std * rng.standard_normal(total)
    )
    scan_index = np.repeat(np.arange(scan_count), counts)
    clutter_xy = scene.ego_positions[scan_index] + clutter_range[:, None] * np.column_stack(
        [np.cos(clutter_angle), np.sin(clutter_angle)]
    )
    bounds = np.concatenate([[0], np.cumsum(counts)])

    model = config.measurement_model()
    scans = []
    for k, timestamp in enumerate(timestamps):
        pose = SensorPose(
            float(scene.ego_positions[k, 0]),
            float(scene.ego_positions[k, 1]),
            float(scene.ego_headings[k]),
        )
        detections: set[Detection] = set()
        for j in np.flatnonzero(detected[k]):
            state_vector = StateVector(measured[k, j])
            metadata = _object_metadata(scene.sources[j]) | {"area": float(object_areas[k, j])}
            detections.add(_object_detection(scene.sources[j], state_vector, timestamp, model,
                                             metadata, truth_paths))
        for i in range(bounds[k], bounds[k + 1]):
            detections.add(
                Clutter(
                    StateVector(clutter_xy[i]),
                    timestamp=timestamp,
                    measurement_model=model,
                    metadata={"source": "clutter", "area": float(clutter_area[i])},
                )
            )
        scans.append(Scan(timestamp, detections, pose))
    return scans


def simulate(
    layout: SceneLayout,
    seed: int,
    duration: float | None = None,
    *,
    radar: RadarConfig | None = None,
    lidar: LidarConfig | None = None,
    name: str = "custom",
) -> ScenarioRun:
    """Generate one run of ``layout``: same arguments, same run (bit for bit)."""
    radar = radar or RadarConfig()
    lidar = lidar or LidarConfig()
    duration = layout.default_duration if duration is None else float(duration)
    if duration <= 0:
        raise ValueError("duration must be positive")

    radar_us = _scan_offsets_us(radar.period, radar.phase, duration)
    lidar_us = _scan_offsets_us(lidar.period, lidar.phase, duration)
    all_us = np.union1d(radar_us, lidar_us)
    seconds = all_us / 1e6
    timestamps = [EPOCH + datetime.timedelta(microseconds=int(us)) for us in all_us]

    ego = layout.ego.sample(seconds)
    if not ego.exists.all():
        raise ValueError("the ego must exist for the whole run")
    land = [np.asarray(poly, dtype=float) for poly in layout.land]
    if land and _on_land(ego.positions, land).any():
        raise ValueError("the ego's track crosses land")

    truth_paths: dict[str, GroundTruthPath] = {}
    target_samples = []
    for target in layout.targets:
        sample = target.motion.sample(seconds)
        if land and _on_land(sample.positions[sample.exists], land).any():
            raise ValueError(f"target {target.id!r} sails on land")
        states = np.column_stack(
            [
                sample.positions[:, 0],
                sample.velocities[:, 0],
                sample.positions[:, 1],
                sample.velocities[:, 1],
            ]
        )
        truth_paths[target.id] = GroundTruthPath(
            [
                GroundTruthState(StateVector(states[i]), timestamp=timestamps[i])
                for i in np.flatnonzero(sample.exists)
            ],
            id=target.id,
        )
        target_samples.append(sample)

    time_count = len(seconds)
    static_positions = np.array(
        [obj.position for obj in layout.static_objects], dtype=float
    ).reshape(1, -1, 2)
    positions = np.concatenate(
        [sample.positions[:, None, :] for sample in target_samples]
        + [np.broadcast_to(static_positions, (time_count, len(layout.static_objects), 2))],
        axis=1,
    )
    exists = np.concatenate(
        [sample.exists[:, None] for sample in target_samples]
        + [np.ones((time_count, len(layout.static_objects)), dtype=bool)],
        axis=1,
    )
    sources = [("target", "truth_id", target.id) for target in layout.targets] + [
        ("static", "static_id", obj.id) for obj in layout.static_objects
    ]
    areas = [target.lidar_area for target in layout.targets] + [
        obj.lidar_area for obj in layout.static_objects
    ]

    def scene_at(sensor_us):
        rows = np.searchsorted(all_us, sensor_us)
        return rows, _Scene(
            ego.positions[rows], ego.headings[rows], positions[rows], exists[rows], sources
        )

    # Independent child streams (Generator.spawn needs numpy ≥ 1.25; this is the same).
    radar_rng, lidar_rng = map(np.random.default_rng, np.random.SeedSequence(seed).spawn(2))
    radar_rows, radar_scene = scene_at(radar_us)
    lidar_rows, lidar_scene = scene_at(lidar_us)
    radar_scans = _radar_scans(
        radar, radar_scene, [timestamps[i] for i in radar_rows], truth_paths, land, radar_rng
    )
    lidar_scans = _lidar_scans(
        lidar, lidar_scene, [timestamps[i] for i in lidar_rows], truth_paths, areas, land, lidar_rng
    )

    return ScenarioRun(
        name=name,
        seed=seed,
        duration=duration,
        truths=set(truth_paths.values()),
        static_objects=tuple(layout.static_objects),
        land=land,
        ego=EgoNavigation(timestamps, ego.positions, ego.velocities, ego.headings),
        radar_scans=radar_scans,
        lidar_scans=lidar_scans,
        radar=radar,
        lidar=lidar,
        description=layout.description,
    )


# --------------------------------------------------------------------------------------
# The three scenarios
# --------------------------------------------------------------------------------------


def _heading_towards(start, point) -> float:
    offset = np.asarray(point, dtype=float) - np.asarray(start, dtype=float)
    return math.atan2(offset[1], offset[0])


def _mixed_range_layout() -> SceneLayout:
    ego = DriftMotion(
        origin=(0.0, 0.0),
        drift_velocity=(0.025, 0.015),
        mean_heading=math.pi / 2,
        heading_amplitude=math.radians(3.0),
        heading_period=240.0,
    )

    def medium_range_vessel(start, waypoints, speed, turn_radius=80.0):
        builder = PathBuilder(start, _heading_towards(start, waypoints[0]))
        for waypoint in waypoints:
            builder.head_to(waypoint, turn_radius)
        return PathMotion(builder.build(), speed)

    # Inbound from 1.5 km north-east, past the ego ~300 m to the east, out south-east.
    vessel_a = medium_range_vessel(
        (900.0, 1200.0), [(310.0, 200.0), (290.0, -200.0), (1150.0, -950.0)], 5.5
    )
    # Inbound from 1.5 km west, ~300 m west of the ego, out north-west.
    vessel_b = medium_range_vessel(
        (-1450.0, -320.0), [(-330.0, 40.0), (-290.0, 550.0), (-950.0, 1150.0)], 5.0
    )

    # Loop vessel: straight at the tangent of a 30 m circle around the ego where the ego
    # will be when it gets there, one full counter-clockwise loop, then away north-west.
    loop_start, loop_speed, loop_radius = np.array([700.0, -820.0]), 5.0, 30.0
    arrival = float(np.hypot(*loop_start)) / loop_speed
    loop_time = arrival + math.pi * loop_radius / loop_speed  # half-way round
    centre = ego.sample([loop_time]).positions[0]
    entry = tangent_point(loop_start, centre, loop_radius, counter_clockwise=True)
    loop_path = (
        PathBuilder(loop_start, _heading_towards(loop_start, entry))
        .straight(float(np.hypot(*(entry - loop_start))))
        .turn(loop_radius, _TWO_PI)
        .head_to((-1000.0, 650.0), 40.0)
        .build()
    )
    loop_vessel = PathMotion(loop_path, loop_speed)

    statics = (
        StaticObject("marker-near", (28.0, -29.0), "marker", 2.0),  # 40 m: reliable lidar
        StaticObject("marker-68m", (-55.0, 40.0), "marker", 2.0),  # degraded lidar band
        StaticObject("marker-east", (450.0, -250.0), "marker", 2.0),
        StaticObject("marker-north", (-380.0, 420.0), "marker", 2.0),
        StaticObject("islet-south", (-250.0, -650.0), "islet", 150.0),
        StaticObject("islet-east", (1200.0, 300.0), "islet", 150.0),
        StaticObject("islet-far", (-700.0, -1100.0), "islet", 150.0),
    )
    return SceneLayout(
        ego=ego,
        targets=(
            TargetSpec("vessel-a", vessel_a, 25.0),
            TargetSpec("vessel-b", vessel_b, 30.0),
            TargetSpec("loop-vessel", loop_vessel, 15.0),
        ),
        static_objects=statics,
        default_duration=480.0,
        description=(
            "Scenario 1: mixed-range traffic around a station-keeping ego; one vessel "
            "loops around the ego at 30 m."
        ),
    )


def _formation_layout() -> SceneLayout:
    # The ego's route starts 600 m west of the origin so a follower can use the same route.
    route = (
        PathBuilder((-600.0, 0.0), heading=0.0)
        .straight(1050.0)
        .turn(250.0, math.pi / 2)
        .straight(300.0)
        .turn(250.0, -math.pi / 3)
        .straight(900.0)
        .build()
    )
    ego = PathMotion(route, speed=3.0, start_time=-200.0)  # at the origin at t = 0
    cooperating = FormationMotion(ego, body_offset=(-6.0, -29.4))  # 30 m, starboard quarter

    # Follows the ego's route 250–300 m behind, weaving ±170 m across it: in and out of
    # the blind sector on straight legs. The weave period puts zero lateral offset near
    # the route's curvature jumps, where WeaveMotion's speed would otherwise jump.
    follower = WeaveMotion(route, speed=3.1, amplitude=170.0, period=226.0, start_time=-120.0)

    # Crosses astern of the ego from north to south, then runs east and north: in the
    # blind sector while astern, and again while the ego heads north.
    crossing_path = (
        PathBuilder((-250.0, 750.0), heading=-math.pi / 2)
        .head_to((-150.0, -200.0), 80.0)
        .head_to((250.0, -700.0), 80.0)
        .head_to((1400.0, -450.0), 80.0)
        .head_to((1700.0, 400.0), 80.0)
        .build()
    )
    crosser = PathMotion(crossing_path, speed=4.5)

    # Manoeuvres at medium range north-east: westbound, a loop, then north.
    manoeuvre_path = (
        PathBuilder((1300.0, 800.0), heading=math.pi)
        .straight(500.0)
        .turn(120.0, -3 * math.pi / 2)
        .head_to((700.0, 1400.0), 100.0)
        .head_to((100.0, 1300.0), 100.0)
        .head_to((-300.0, 700.0), 100.0)
        .build()
    )
    manoeuvrer = PathMotion(manoeuvre_path, speed=4.0)

    statics = (
        StaticObject("marker-route", (200.0, 70.0), "marker", 2.0),  # passed at ~70 m
        StaticObject("marker-bend", (700.0, 420.0), "marker", 2.0),
        StaticObject("islet-north", (150.0, 650.0), "islet", 150.0),
        StaticObject("islet-south", (-500.0, -600.0), "islet", 150.0),
    )
    return SceneLayout(
        ego=ego,
        targets=(
            TargetSpec("cooperating-usv", cooperating, 20.0),
            TargetSpec("follower", follower, 25.0),
            TargetSpec("crosser", crosser, 30.0),
            TargetSpec("manoeuvrer", manoeuvrer, 20.0),
        ),
        static_objects=statics,
        default_duration=480.0,
        description=(
            "Scenario 2: ego in close formation with a cooperating USV at 30 m; vessels "
            "manoeuvre at medium range and cross the radar's rear blind sector."
        ),
    )


def _island(centre, radii, rotation=0.0) -> np.ndarray:
    """Star-shaped polygon: one vertex per radius, evenly spread in angle."""
    radii = np.asarray(radii, dtype=float)
    angles = rotation + np.linspace(0.0, _TWO_PI, radii.size, endpoint=False)
    return np.asarray(centre, dtype=float) + radii[:, None] * np.column_stack(
        [np.cos(angles), np.sin(angles)]
    )


def _islands_layout() -> SceneLayout:
    # Heading north: the blind sector points south, clear of the islands' shadows.
    ego = DriftMotion(
        origin=(0.0, 0.0),
        drift_velocity=(0.02, -0.01),
        mean_heading=math.pi / 2,
        heading_amplitude=math.radians(2.0),
        heading_period=300.0,
    )
    north_east = _island((380.0, 260.0), [120, 95, 130, 110, 90, 125, 105, 115, 100, 120, 95, 110])
    north_west = _island(
        (-480.0, 520.0), [150, 175, 140, 160, 185, 150, 165, 140, 170, 155], rotation=0.2
    )
    south_east_long = _island(
        (600.0, -480.0), [240, 90, 80, 70, 95, 230, 85, 75, 70, 90], rotation=2.2
    )
    land = (north_east, north_west, south_east_long)

    def vessel(start, waypoints, speed, turn_radius=80.0):
        builder = PathBuilder(start, _heading_towards(start, waypoints[0]))
        for waypoint in waypoints:
            builder.head_to(waypoint, turn_radius)
        return PathMotion(builder.build(), speed)

    # East→west north of the ego: behind the NE island, in sight, behind the NW island.
    northern = vessel((1300.0, 480.0), [(200.0, 520.0), (-500.0, 850.0), (-1300.0, 950.0)], 5.0)
    # South-west behind the SE island and back north-east behind it again.
    south_eastern = vessel(
        (1450.0, -100.0),
        [(1150.0, -950.0), (800.0, -1150.0), (1350.0, -650.0), (1250.0, 100.0)],
        5.0,
    )
    # Weaves in open water to the west, always in sight (the control target).
    open_water = vessel(
        (-1200.0, -150.0),
        [(-700.0, -350.0), (-1000.0, -600.0), (-500.0, -550.0), (-900.0, -150.0), (-500.0, 50.0)],
        4.0,
        turn_radius=60.0,
    )
    # Comes out of the NW island's shadow towards the ego, turns away west.
    emerging = vessel(
        (-850.0, 1050.0),
        [(-900.0, 250.0), (-300.0, 200.0), (-1200.0, 150.0)],
        4.0,
        turn_radius=60.0,
    )

    statics = (
        StaticObject("marker-open", (120.0, -150.0), "marker", 2.0),
        StaticObject("marker-shadowed", (700.0, 480.0), "marker", 2.0),  # behind the NE island
        StaticObject("marker-channel", (-250.0, 250.0), "marker", 2.0),
    )
    return SceneLayout(
        ego=ego,
        targets=(
            TargetSpec("northern", northern, 25.0),
            TargetSpec("south-eastern", south_eastern, 25.0),
            TargetSpec("open-water", open_water, 20.0),
            TargetSpec("emerging", emerging, 20.0),
        ),
        static_objects=statics,
        land=land,
        default_duration=480.0,
        description=(
            "Scenario 3 (ours): islands as land polygons; vessels pass into the radar "
            "shadow of the islands as seen from the ego."
        ),
    )


@dataclass(frozen=True)
class ScenarioSpec:
    """A registered scenario: its number, a one-line title and how to lay it out."""

    name: str
    number: int
    title: str
    layout: Callable[[], SceneLayout]


SCENARIOS: dict[str, ScenarioSpec] = {
    "mixed-range": ScenarioSpec("mixed-range", 1, "Mixed-range traffic", _mixed_range_layout),
    "formation": ScenarioSpec(
        "formation", 2, "Close-range formation with occlusion", _formation_layout
    ),
    "islands": ScenarioSpec("islands", 3, "Islands and radar shadow", _islands_layout),
}
"""The paper's two scenarios and our islands scenario, by name."""


def make_scenario(
    name: str | int,
    seed: int,
    duration: float | None = None,
    *,
    radar: RadarConfig | None = None,
    lidar: LidarConfig | None = None,
) -> ScenarioRun:
    """Generate a named scenario (a key of :data:`SCENARIOS` or its number 1–3).

    ``duration`` (s) defaults to the scenario's own (480 s); shorter durations cut a
    window from the start of the same fixed truth timeline.
    """
    if isinstance(name, int):
        matches = [spec for spec in SCENARIOS.values() if spec.number == name]
        if not matches:
            raise KeyError(f"no scenario number {name}; choose from 1–{len(SCENARIOS)}")
        spec = matches[0]
    else:
        try:
            spec = SCENARIOS[name]
        except KeyError:
            raise KeyError(f"unknown scenario {name!r}; choose from {sorted(SCENARIOS)}") from None
    return simulate(spec.layout(), seed, duration, radar=radar, lidar=lidar, name=spec.name)
