"""Learned observability blocks, per scan: the clutter map's update plus λ for the scan's
detections (issue target: ≤ 20 µs at 40 detections on a 100 × 64 grid), against the same
estimator in NumPy (running scale, ``np.add.at``; the best a user could write per scan).

    python benches/learned.py [--detections 40] [--repeats 7] [--pooling none|range|estimated]

(``estimated``: range rings with the pool weight estimated from each ring's spread, cells
its level cannot explain set apart, as the study's map; NumPy recomputes the rings' cells
apart, levels and spreads once per scan, before reading λ.)

Both sides do one scan's work as a tracker would: λ of the scan's detections from the map
as it stands (through a detector context on our side), then the map's update with them.
"""
from __future__ import annotations

import argparse
import math
import time

import numpy as np

from ctxmodels import (ClutterDensityModel, ClutterMap, DetectionProbabilityModel, Pose,
                       SensorModel)

BEARINGS, RANGES = np.linspace(-math.pi, math.pi, 101), np.linspace(0.0, 1612.0, 65)
PRIOR, PRIOR_SCANS, FORGETTING, POOLING_SCANS = 1e-3, 10.0, 0.99, 10.0


class NumpyMap:
    """The map in NumPy; with ``pooled``, range rings (their counts kept as a running sum,
    the cheapest way in NumPy), with ``estimated`` their weights from their spreads."""

    def __init__(self, pooled=False, estimated=False):
        self.volumes = np.outer(np.diff(BEARINGS), np.diff(RANGES))
        self.counts = np.zeros(self.volumes.shape)
        self.exposure, self.scale = 0.0, 1.0
        self.pooled, self.estimated = pooled or estimated, estimated
        self.ring_volumes = self.volumes.sum(axis=0)
        self.ring_counts = np.zeros(self.volumes.shape[1])

    def cells(self, pose, positions):
        d = positions - pose[:2]
        bearing = np.arctan2(d[:, 1], d[:, 0]) - pose[2]
        bearing = (bearing + math.pi) % (2 * math.pi) - math.pi
        rng = np.hypot(d[:, 0], d[:, 1])
        i = np.searchsorted(BEARINGS, bearing, side="right") - 1
        j = np.searchsorted(RANGES, rng, side="right") - 1
        inside = (i >= 0) & (i < len(BEARINGS) - 1) & (j >= 0) & (j < len(RANGES) - 1)
        return i, j, inside

    def scan(self, pose, positions, out):
        i, j, inside = self.cells(pose, positions)
        n = self.counts[i[inside], j[inside]] / self.scale
        s = self.exposure / self.scale
        out.fill(PRIOR)
        if self.estimated:
            v = self.ring_volumes
            rings = (PRIOR * PRIOR_SCANS * v + self.ring_counts / self.scale) / (PRIOR_SCANS * v + v * s)
            exposed = self.volumes * s
            x = max(0.0, 1.0 - s * (1.0 - FORGETTING))
            per_scan = (1.0 - x * x) / (1.0 - FORGETTING ** 2) / s if s > 0 else 0.0
            counts = self.counts / self.scale
            # cells apart: Poisson deviance (effective counts) beyond ln(cells / 1 %)
            effective = 1.0 / per_scan if per_scan > 0 else 0.0
            k, mu = counts * effective, rings * exposed * effective
            with np.errstate(divide="ignore", invalid="ignore"):
                divergence = np.where(k > 0, k * np.log(k / mu) - k + mu, mu)
            apart = (mu > 0) & (divergence > math.log(self.volumes.shape[0] / 0.01))
            keep = ~apart
            rings = (PRIOR * PRIOR_SCANS * v + (keep * counts).sum(axis=0)) / \
                (PRIOR_SCANS * v + (keep * exposed).sum(axis=0))
            excess = (keep * ((counts - rings * exposed) ** 2 - rings * exposed * per_scan)).sum(axis=0)
            weight = (keep * exposed ** 2).sum(axis=0)
            spread = np.where(weight > 0, np.maximum(excess, 0.0) / np.where(weight > 0, weight, 1.0), 0.0)
            ring, tau = rings[j[inside]], spread[j[inside]]
            volume = self.volumes[i[inside], j[inside]]
            with np.errstate(divide="ignore", invalid="ignore"):
                sp = ring / (tau * volume)
                pooled = np.where(tau > 0, (ring * sp + n / volume) / (sp + s), ring)
            alone = (PRIOR * PRIOR_SCANS + n / volume) / (PRIOR_SCANS + s)
            out[inside] = np.where(apart[i[inside], j[inside]], alone, pooled)
        elif self.pooled:
            v = self.ring_volumes[j[inside]]
            ring = (PRIOR * PRIOR_SCANS * v + self.ring_counts[j[inside]] / self.scale) / \
                (PRIOR_SCANS * v + v * s)
            out[inside] = (ring * POOLING_SCANS + n / self.volumes[i[inside], j[inside]]) / \
                (POOLING_SCANS + s)
        else:
            out[inside] = (PRIOR * PRIOR_SCANS + n / self.volumes[i[inside], j[inside]]) / \
                (PRIOR_SCANS + s)
        self.scale /= FORGETTING
        np.add.at(self.counts, (i[inside], j[inside]), self.scale)
        if self.pooled:
            np.add.at(self.ring_counts, j[inside], self.scale)
        self.exposure += self.scale
        return out


def per_scan(fn, scans: int, repeats: int) -> float:
    best = []
    for _ in range(repeats):
        started = time.perf_counter()
        for k in range(scans):
            fn(k)
        best.append((time.perf_counter() - started) / scans)
    return float(np.median(best))


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--detections", type=int, default=40)
    parser.add_argument("--scans", type=int, default=2000)
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--pooling", choices=("none", "range", "estimated"), default="none")
    args = parser.parse_args(argv)
    estimated = args.pooling == "estimated"
    config = dict(space="bearing-range", edges=(BEARINGS, RANGES), prior_intensity=PRIOR,
                  prior_scans=PRIOR_SCANS, forgetting=FORGETTING,
                  pooling="range" if estimated else args.pooling,
                  pooling_scans=None if estimated else POOLING_SCANS)
    pooled = args.pooling == "range"
    rng = np.random.default_rng(1)
    pose = Pose(x=50.0, y=-20.0, heading=0.4)
    polar = rng.uniform([-math.pi, 0.0], [math.pi, 1700.0], (args.scans, args.detections, 2))
    scans = np.ascontiguousarray(np.stack([polar[..., 1] * np.cos(polar[..., 0]) + pose.x,
                                           polar[..., 1] * np.sin(polar[..., 0]) + pose.y], -1))

    learned = ClutterMap(**config)
    sensor = SensorModel(detection=DetectionProbabilityModel(factors=[0.9]),
                         clutter=ClutterDensityModel(factors=[learned]))
    out = np.empty(args.detections)

    def ours(k):
        positions = scans[k]
        context = sensor.context(pose)  # a scan's context, as a feeder makes it
        context.clutter_spatial_density_array(positions, out=out)
        learned.update(pose, positions)

    reference = NumpyMap(pooled, estimated)
    ref_out = np.empty(args.detections)
    pose_array = np.array(pose.as_tuple())

    def numpy_scan(k):
        reference.scan(pose_array, scans[k], ref_out)

    # the same numbers first: a fresh pair over the first 200 scans
    check_map, check_ref = ClutterMap(**config), NumpyMap(pooled, estimated)
    worst = 0.0
    for k in range(200):
        a = check_map.intensity(pose, scans[k])
        check_map.update(pose, scans[k])
        b = check_ref.scan(pose_array, scans[k], np.empty(args.detections)).copy()
        worst = max(worst, float(np.max(np.abs(a / b - 1))))
    t_ours = per_scan(ours, args.scans, args.repeats)
    t_numpy = per_scan(numpy_scan, args.scans, args.repeats)
    print(f"clutter map ({args.pooling} pooling), {args.detections} detections, "
          f"{len(BEARINGS) - 1}×{len(RANGES) - 1} grid: "
          f"{t_ours * 1e6:.2f} µs per scan (context + λ + update) vs NumPy {t_numpy * 1e6:.2f} µs "
          f"({t_numpy / t_ours:.1f}×); agreement over 200 scans: max relative difference {worst:.1e}")
    return 0 if worst < 1e-12 else 1


if __name__ == "__main__":
    raise SystemExit(main())
