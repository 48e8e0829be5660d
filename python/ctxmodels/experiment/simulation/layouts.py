"""The three scenarios (registry :data:`SCENARIOS`; :func:`make_scenario` also takes 1, 2, 3).

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
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .geometry import TWO_PI
from .lidar import LidarConfig
from .motion import DriftMotion, FormationMotion, PathMotion, WeaveMotion
from .paths import PathBuilder, tangent_point
from .radar import RadarConfig
from .run import ScenarioRun, simulate
from .scene import SceneLayout, StaticObject, TargetSpec

__all__ = ["SCENARIOS", "ScenarioSpec", "make_scenario"]


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
        .turn(loop_radius, TWO_PI)
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
    # the blind sector on straight legs. (The weave period was chosen to put zero lateral
    # offset near the route's curvature jumps, from before turn rates ramped; it stays
    # so the scenario stays the same.)
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
    angles = rotation + np.linspace(0.0, TWO_PI, radii.size, endpoint=False)
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

    @property
    def duration(self) -> float:
        """The scenario's length (s)."""
        return self.layout().default_duration

    def prepare(self) -> None:
        """What a study does once before its workers start: nothing (a simulated scene
        needs no data)."""


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
