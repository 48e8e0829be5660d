"""Running a scene: :func:`simulate` turns a :class:`~.scene.SceneLayout` and a seed into
a :class:`ScenarioRun` (ground truth, navigation and both sensors' scans).

The truth is fixed by the layout; the seed only drives detection, noise and clutter
draws. ``duration`` cuts a window from the start of the layout's fixed timeline. Radar
and lidar draws come from independent child streams of ``numpy.random.default_rng(seed)``,
so changing one sensor's settings never changes the other sensor's detections.

Truth states are ``GroundTruthState`` ``[x, vx, y, vy]`` at every radar and lidar
timestamp while the vessel exists; the ego's navigation track (:class:`EgoNavigation`)
is exact at every scan time (the measurement noise stands for all error sources).
Timestamps are naive :class:`datetime.datetime` starting at :data:`EPOCH`.
"""

from __future__ import annotations

import datetime
import heapq
from collections.abc import Iterator
from dataclasses import dataclass, field

import numpy as np
from stonesoup.types.array import StateVector
from stonesoup.types.groundtruth import GroundTruthPath, GroundTruthState

from .geometry import on_land, wrap_angle
from .lidar import LidarConfig, generate_lidar_scans
from .radar import RadarConfig, generate_radar_scans
from .scans import Scan, SensorPose, SensorScene, scan_offsets_us
from .scene import SceneLayout, StaticObject

__all__ = ["EPOCH", "EgoNavigation", "ScenarioRun", "simulate"]

EPOCH = datetime.datetime(2024, 6, 1, 12, 0, 0)
"""Time of the first radar scan of every run."""


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
        return SensorPose(float(x), float(y), float(wrap_angle(heading)))


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

    radar_us = scan_offsets_us(radar.period, radar.phase, duration)
    lidar_us = scan_offsets_us(lidar.period, lidar.phase, duration)
    all_us = np.union1d(radar_us, lidar_us)
    seconds = all_us / 1e6
    timestamps = [EPOCH + datetime.timedelta(microseconds=int(us)) for us in all_us]

    ego = layout.ego.sample(seconds)
    if not ego.exists.all():
        raise ValueError("the ego must exist for the whole run")
    land = [np.asarray(poly, dtype=float) for poly in layout.land]
    if land and on_land(ego.positions, land).any():
        raise ValueError("the ego's track crosses land")

    truth_paths: dict[str, GroundTruthPath] = {}
    target_samples = []
    for target in layout.targets:
        sample = target.motion.sample(seconds)
        if land and on_land(sample.positions[sample.exists], land).any():
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
        return rows, SensorScene(
            ego.positions[rows], ego.headings[rows], positions[rows], exists[rows], sources
        )

    # Independent child streams (Generator.spawn needs numpy ≥ 1.25; this is the same).
    radar_rng, lidar_rng = map(np.random.default_rng, np.random.SeedSequence(seed).spawn(2))
    radar_rows, radar_scene = scene_at(radar_us)
    lidar_rows, lidar_scene = scene_at(lidar_us)
    radar_scans = generate_radar_scans(
        radar, radar_scene, [timestamps[i] for i in radar_rows], truth_paths, land, radar_rng
    )
    lidar_scans = generate_lidar_scans(
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
