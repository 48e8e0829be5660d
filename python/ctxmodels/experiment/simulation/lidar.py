"""The simulated lidar (a truth model; every value is a field of :class:`LidarConfig`
and can be overridden).

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
* clutter: Poisson(0.3) segments per scan (calibrated, ``docs/calibration.md``), i.i.d.
  from scan to scan, uniform in area over 3 m < r < 80 m around the ego, i.e. 1.49e-5
  per m²; areas lognormal with median 2.5 m² and σ = 0.8
  (≈ 96 % below 10 m²). The paper's λ_lidar (0.1 / 1e-3) is a tuning value, not a
  density (taken per m² it would mean ~2000 clutter points per scan).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from stonesoup.models.measurement.linear import LinearGaussian
from stonesoup.types.array import CovarianceMatrix, StateVector
from stonesoup.types.detection import Clutter, Detection

from .geometry import land_edges, polar, visible
from .scans import Scan, SensorPose, SensorScene, object_detection, object_metadata

__all__ = ["LidarConfig", "generate_lidar_scans"]


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
    clutter_per_scan: float = 0.3
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


def generate_lidar_scans(
    config: LidarConfig, scene: SensorScene, timestamps, truth_paths, areas, land, rng
) -> list[Scan]:
    scan_count, object_count = scene.exists.shape
    ranges, _ = polar(scene.positions, scene.ego_positions, scene.ego_headings)
    with np.errstate(invalid="ignore"):
        prob = np.where(scene.exists, config.prob_detection(np.nan_to_num(ranges, nan=np.inf)), 0.0)
    covered = visible(prob > 0, scene.positions, scene.ego_positions, land_edges(land))

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
            metadata = object_metadata(scene.sources[j]) | {"area": float(object_areas[k, j])}
            detections.add(object_detection(scene.sources[j], state_vector, timestamp, model,
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
