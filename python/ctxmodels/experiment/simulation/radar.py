"""The simulated radar (a truth model; every value is a field of :class:`RadarConfig`
and can be overridden).

Radar, 0.8 Hz (period 1.25 s, first scan at the epoch):

* covers 50 m < r < 1612 m outside a 65° blind sector centred astern
  (bearing π relative to the heading, i.e. world heading + π);
* P_D 0.7 for every object (vessel or static) inside coverage and in line of sight,
  0 otherwise (the shape of paper eq. pd-radar; the value is calibrated);
* noise: bearing σ = 0.5° (calibrated), range σ = 5 m;
* clutter uniform in bearing–range over the covered arc (2π − 65° = 5.149 rad):
  1e-3 per rad·m in 50–1000 m and 3e-3 per rad·m in 1000–1612 m (calibrated), i.e.
  Poisson(4.89) and Poisson(9.45) per scan;
* land returns (scenario "islands" only): Poisson(0.01 per metre of coastline) points
  per scan drawn uniformly along all coastlines, kept where the radar sees that piece of
  coast (in coverage, not shadowed), then measured with the radar noise. The islands
  lie beyond lidar range, so the lidar has no land returns.

The calibrated values (P_D, clutter densities, bearing σ) were chosen from the paper's
baseline rows of Table II by the procedure in ``docs/calibration.md``
(:mod:`ctxmodels.experiment.calibration`); :data:`~.truths.TRUTHS` also names the stress
setting that copies the trackers' P_D 0.4 and far λ 1e-2 into the truth.

A radar bearing is relative to the ego's heading (0 = dead ahead, +π/2 = port); this is
what ``CartesianToBearingRange(translation_offset=(x, y), rotation_offset=(0, 0,
heading))`` produces. Every random draw of a run is taken up front from the radar's own
stream, independent of coverage, so the stream is stable.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from stonesoup.models.measurement.nonlinear import CartesianToBearingRange
from stonesoup.types.angle import Bearing
from stonesoup.types.array import CovarianceMatrix, StateVector
from stonesoup.types.detection import Clutter, Detection

# (a Stone Soup model with its exact Jacobian: no ctxmodels core, no context models)
from ...stonesoup.models import AnalyticCartesianToBearingRange
from .geometry import (
    TWO_PI,
    coastline_sampler,
    land_edges,
    polar,
    sight_blocked,
    visible,
    wrap_angle,
)
from .scans import Scan, SensorPose, SensorScene, object_detection, object_metadata

__all__ = ["CALIBRATED_CLUTTER_DENSITY", "RadarConfig", "generate_radar_scans"]


#: The calibrated clutter densities per rad·m below and beyond 1000 m (docs/calibration.md).
CALIBRATED_CLUTTER_DENSITY = (1e-3, 3e-3)
#: The covered arc of the default geometry (rad): the calibrated densities per rad·m become
#: Poisson means per scan over it.
_ARC = TWO_PI - math.radians(65.0)


@dataclass(frozen=True)
class RadarConfig:
    """Truth model of the radar. Angles in radians, distances in metres, times in s."""

    period: float = 1.25
    phase: float = 0.0
    min_range: float = 50.0
    max_range: float = 1612.0
    blind_sector_width: float = math.radians(65.0)
    prob_detection: float = 0.7
    bearing_std: float = math.radians(0.5)
    range_std: float = 5.0
    clutter_boundary_range: float = 1000.0
    # 1e-3 and 3e-3 per rad·m over 50–1000 m and 1000–1612 m of the covered arc
    clutter_per_scan_near: float = CALIBRATED_CLUTTER_DENSITY[0] * _ARC * (1000.0 - 50.0)
    clutter_per_scan_far: float = CALIBRATED_CLUTTER_DENSITY[1] * _ARC * (1612.0 - 1000.0)
    land_returns_per_metre: float = 0.01

    @property
    def covered_bearing_extent(self) -> float:
        """Width of the bearing interval outside the blind sector (rad)."""
        return TWO_PI - self.blind_sector_width

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
            np.abs(wrap_angle(relative_bearings)) < math.pi - self.blind_sector_width / 2
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


def generate_radar_scans(
    config: RadarConfig, scene: SensorScene, timestamps, truth_paths, land, rng
) -> list[Scan]:
    scan_count, object_count = scene.exists.shape
    ranges, bearings = polar(scene.positions, scene.ego_positions, scene.ego_headings)
    with np.errstate(invalid="ignore"):
        covered = scene.exists & config.in_coverage(ranges, bearings)
    edges = land_edges(land)
    covered = visible(covered, scene.positions, scene.ego_positions, edges)

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
            state_vector = StateVector([Bearing(wrap_angle(bearing)), range_])
            metadata = object_metadata(scene.sources[j])
            detections.add(object_detection(scene.sources[j], state_vector, timestamp, model,
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


def _land_returns(config: RadarConfig, scene: SensorScene, land, edges, rng) -> list[np.ndarray]:
    """Measured (bearing, range) land returns per scan from the radar-visible coast."""
    coast_points, coast_length = coastline_sampler(land)
    scan_count = len(scene.ego_headings)
    counts = rng.poisson(config.land_returns_per_metre * coast_length, scan_count)
    points = coast_points(rng.random(counts.sum()))
    noise = rng.standard_normal((counts.sum(), 2))
    scan_index = np.repeat(np.arange(scan_count), counts)
    ego = scene.ego_positions[scan_index]
    relative = points - ego
    ranges = np.hypot(relative[:, 0], relative[:, 1])
    bearings = wrap_angle(
        np.arctan2(relative[:, 1], relative[:, 0]) - scene.ego_headings[scan_index]
    )
    keep = config.in_coverage(ranges, bearings)
    # Stop the sight line 1 m short: the point itself lies on the coast.
    short_of_coast = points - relative / np.maximum(ranges, 1e-9)[:, None]
    keep[keep] &= ~sight_blocked(ego[keep], short_of_coast[keep], *edges)
    measured = np.column_stack(
        [
            wrap_angle(bearings + config.bearing_std * noise[:, 0]),
            ranges + config.range_std * noise[:, 1],
        ]
    )
    return [measured[(scan_index == k) & keep] for k in range(scan_count)]
