"""The Solent's two radars as simulated truth, independent of the context models (NumPy
geometry of :mod:`ctxmodels.experiment.simulation.geometry`, never the core).

A vessel is *covered* by a radar at a scan when it is known there (AIS), on water, between
50 m and the radar's reach, above its horizon (antenna and :data:`~.scene.VESSEL_HEIGHT`,
k = 4/3) and in its line of sight: the segment from :data:`~.scene.CLEARANCE` out along
the way to the vessel meets no land. A covered vessel is detected with the calibrated P_D
0.7, measured in bearing and range with the calibrated σ 0.5° and 5 m
(:class:`~ctxmodels.experiment.scenarios.RadarConfig`'s defaults). Clutter: as many false
alarms a scan as the calibrated radar has (Poisson, mean 14.3: its near and far means, a
CFAR detector's false alarms per scan), uniform in bearing and range over 50 m to the
reach; no land returns (the radar's processor masks land). Each radar draws from its own
stream of the seed.
"""
from __future__ import annotations

import datetime

import numpy as np
from stonesoup.types.angle import Bearing
from stonesoup.types.array import StateVector
from stonesoup.types.detection import Clutter, TrueDetection

from ..simulation.geometry import on_land, sight_blocked, wrap_angle
from ..simulation.radar import RadarConfig
from ..simulation.scans import Scan, SensorPose, scan_offsets_us
from . import scene

#: The calibrated radar (docs/calibration.md): P_D, noise and false alarms per scan.
CALIBRATED = RadarConfig()
MIN_RANGE = CALIBRATED.min_range
CLUTTER_PER_SCAN = CALIBRATED.clutter_per_scan_near + CALIBRATED.clutter_per_scan_far


def rings(polygons) -> list[np.ndarray]:
    """Every ring (shells and holes) of the land polygons: the coastline."""
    return [np.asarray(r) for p in polygons for r in [p["shell"], *p["holes"]]]


def on_water(positions: np.ndarray, polygons) -> np.ndarray:
    """Positions (N, 2) off the land (even–odd over all rings: holes are water; each ring
    tests only the points inside its bounding box)."""
    inside = np.zeros(len(positions), dtype=bool)
    for ring in rings(polygons):
        low, high = ring.min(axis=0), ring.max(axis=0)
        near = np.flatnonzero(np.all((positions >= low) & (positions <= high), axis=1))
        if near.size:
            inside[near] ^= on_land(positions[near], [ring])
    return ~inside


def within_reach(site: scene.Site, positions: np.ndarray) -> np.ndarray:
    """Whether each (N, 2) position lies between 50 m and the radar's reach, above its
    horizon (line of sight aside)."""
    offset = positions - np.asarray(site.position)
    ranges = np.hypot(offset[:, 0], offset[:, 1])
    return (ranges > MIN_RANGE) & (ranges < min(site.reach, scene.horizon_range(site.height)))


def covered(site: scene.Site, positions: np.ndarray, polygons) -> np.ndarray:
    """Whether the radar at ``site`` covers each (N, 2) position on water (module docs)."""
    offset = positions - np.asarray(site.position)
    ranges = np.hypot(offset[:, 0], offset[:, 1])
    reach = min(site.reach, scene.horizon_range(site.height))
    inside = within_reach(site, positions)
    starts_at = np.asarray(site.position) + offset * (scene.CLEARANCE / np.maximum(ranges, 1e-9))[:, None]
    edges = _edges_that_can_block(site, polygons, reach)
    result = inside.copy()
    candidates = np.flatnonzero(inside & (ranges > scene.CLEARANCE))
    result[candidates] = ~sight_blocked(starts_at[candidates], positions[candidates], *edges)
    return result


def _edges_that_can_block(site: scene.Site, polygons, reach: float):
    """The coastline edges (starts, ends) that can meet a sight line of the site's: the
    tested segments run from the clearance to the target, within ``reach`` of the site, so
    an edge wholly nearer than the clearance or wholly beyond the reach meets none."""
    coast = rings(polygons)
    starts = np.concatenate(coast)
    ends = np.concatenate([np.roll(r, -1, axis=0) for r in coast])
    a, b = starts - np.asarray(site.position), ends - np.asarray(site.position)
    ab = b - a
    t = np.clip(-np.einsum("ij,ij->i", a, ab) / np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-300), 0, 1)
    nearest = np.hypot(*(a + t[:, None] * ab).T)
    farthest = np.maximum(np.hypot(*a.T), np.hypot(*b.T))
    keep = (nearest <= reach) & (farthest >= scene.CLEARANCE)
    return starts[keep], ends[keep]


def scan_times(site: scene.Site, epoch: datetime.datetime, duration: float) -> list[datetime.datetime]:
    """The radar's scans in [epoch, epoch + duration), whole microseconds."""
    return [epoch + datetime.timedelta(microseconds=int(us))
            for us in scan_offsets_us(site.period, site.phase, duration)]


def measurement_model(site: scene.Site):
    return CALIBRATED.measurement_model(SensorPose(*site.position, 0.0))


def generate_scans(site: scene.Site, times, positions: np.ndarray, seen: np.ndarray,
                   paths: np.ndarray, rng: np.random.Generator) -> list[Scan]:
    """The radar's scans at ``times`` of the vessels at ``positions`` (T, N, 2), those
    ``seen`` (T, N: known, on water and :func:`covered`) being detected; ``paths`` (T, N)
    the truth path each vessel is on at each scan (a detection's ``groundtruth_path``)."""
    count, vessels = seen.shape
    # every draw up front, independent of coverage: the stream does not depend on it
    detect_draws = rng.random((count, vessels))
    noise = rng.standard_normal((count, vessels, 2))
    clutter_counts = rng.poisson(CLUTTER_PER_SCAN, count)
    clutter = np.column_stack([rng.uniform(-np.pi, np.pi, clutter_counts.sum()),
                               rng.uniform(MIN_RANGE, site.reach, clutter_counts.sum())])
    clutter_split = np.split(clutter, np.cumsum(clutter_counts)[:-1])
    detected = seen & (detect_draws < CALIBRATED.prob_detection)
    x0, y0 = site.position
    pose = SensorPose(x0, y0, 0.0)
    model = measurement_model(site)
    scans = []
    for k, time in enumerate(times):
        detections = set()
        for j in np.flatnonzero(detected[k]):
            dx, dy = positions[k, j, 0] - x0, positions[k, j, 1] - y0
            bearing = np.arctan2(dy, dx) + CALIBRATED.bearing_std * noise[k, j, 0]
            range_ = np.hypot(dx, dy) + CALIBRATED.range_std * noise[k, j, 1]
            detections.add(TrueDetection(
                StateVector([Bearing(float(wrap_angle(bearing))), range_]), timestamp=time,
                measurement_model=model, groundtruth_path=paths[k, j],
                metadata={"source": "target", "truth_id": paths[k, j].id}))
        for bearing, range_ in clutter_split[k]:
            detections.add(Clutter(StateVector([Bearing(bearing), range_]), timestamp=time,
                                   measurement_model=model, metadata={"source": "clutter"}))
        scans.append(Scan(time, detections, pose))
    return scans


__all__ = ["CLUTTER_PER_SCAN", "covered", "generate_scans", "on_water", "scan_times", "within_reach"]
