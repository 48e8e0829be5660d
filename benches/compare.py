"""ctxmodels against the fastest NumPy formulation and Shapely 2, on the same models.

Each model is built three ways where that makes sense and timed in one process, on the same
inputs:

* **P_D of the paper's radar** — range bands edges (50, 1612) m, values (0, 0.4, 0), the 50 m
  edge owned by the band below, and a 65° blind sector astern (π ± 32.5°) — over 10³…10⁷
  states. NumPy: squared range against squared edges, the sector as a dot product against
  the sector's centre direction (squared, no square root, no ``atan2``), preallocated
  temporaries and in-place ufuncs.
* **Per-call cost** of a detector context: ``prob_detection_array(states, out=out)`` at
  N = 1, 10, 100 against the NumPy radar's call at the same N, and the scalar
  ``prob_detection(hypothesis)`` against a plain Python function of the same radar
  (``PythonRadar``), in ns per call.
* **Expected P_D** over Gaussians with the third-degree cubature rule (4 points), against P_D
  at the mean; NumPy evaluates the same 4 sigma points with the same Cholesky factor.
* **Clutter density** with the paper's lidar metadata rule (segment ``area < 10`` → 1e-1, else
  1e-3; missing → 1e-2) times a radar-like range rule; NumPy with ``np.where``.
* **Land containment** on deterministic island coastlines of 10²…10⁵ vertices, smooth and
  jagged (the same formula as ``benches/core.rs``): ``LandMask.contains`` against Shapely's
  prepared polygon with vectorised ``shapely.contains_xy``.
* **Line of sight** from one sensor position at sea to many targets: ``LineOfSight.visible``
  against ``shapely.intersects`` of ``shapely.linestrings`` sensor→target segments with the
  prepared land polygon (a segment touching land, or ending on it, is blocked in both).
* **P_D with land and line of sight**: the radar with a ``LandMask`` and a ``LineOfSight``
  factor (10⁴-vertex coastline) against NumPy radar × Shapely land × Shapely sight.
* **The radar equation** (``RadarEquation``): Swerling 1, one pulse, against NumPy's closed
  form ``exp(ln P_FA / (1 + S(r)))`` on preallocated buffers; Swerling 0, ten pulses,
  against SciPy's non-central χ² survival function (``scipy.stats.ncx2.sf``). **The radar
  horizon** (``RadarHorizon``) against NumPy's ``r² ≤ d²``. States spread to 3× the
  reference range, so that P_D takes every value from 1 to P_FA.
* **3-D coverage** on Stone Soup's 3-D constant-velocity rows [x, vx, y, vy, z, vz]: an
  ``ElevationSector`` alone, and a beam (slant-range band × elevation sector ×
  ``RadarHorizon`` at each target's height), against NumPy deciding the elevation as
  r sin(lower) ≤ Δz ≤ r sin(upper) (no arctangent) on preallocated buffers.
* **The range-rate notch** (``RangeRateNotch``) seen from a moving radar, against NumPy's
  radial speed on preallocated buffers (the notch squared; the blind speeds on |ṙ|).

Agreement is checked on every run: answers must be identical except for points within 1e-6 m
of a decision boundary (a range edge, the sector's cone, a coastline; for sight, segments
passing within 1e-6 m of the coast). Times are medians of repeated runs (each run repeats
the call until it takes a few milliseconds), ns per state / point / target; speed-ups are
ratios measured in the same run. ``os.cpu_count()`` is recorded: ctxmodels' P_D and clutter
use all cores for large arrays, ``LandMask.contains`` / ``LineOfSight.visible`` and Shapely
run on one.

Run ``python benches/compare.py`` (about 2 minutes on 2 cores), ``--quick`` for a small run
(seconds), ``--json PATH`` to write the results.
"""
from __future__ import annotations

import argparse
import datetime
import json
import math
import os
import platform
import statistics
import sys
import time

import numpy as np
import shapely

import ctxmodels
from ctxmodels import (
    AngularSector,
    RadarEquation,
    RadarHorizon,
    ClutterDensityModel,
    DetectionProbabilityModel,
    ElevationSector,
    RangeRateNotch,
    LandMask,
    LineOfSight,
    MetadataThreshold,
    RangeBands,
    SensorModel,
)

TOL = 1e-6  # metres: answers within this of a decision boundary may differ
COAST_RADIUS = 1000.0
QUERY_HALF_WIDTH = 1600.0
SENSOR = (-1500.0, 250.0)
HEADING = 0.3
EDGES = (50.0, 1612.0)
BLIND_WIDTH = math.radians(65.0)
GOLDEN = 0.6180339887498949


# --- inputs ---------------------------------------------------------------------------------
def coastline(n: int, jagged: bool) -> np.ndarray:
    """A star-shaped island of ``n`` vertices (always simple): a smooth lobed outline, or
    the same with quasi-random radial spikes of up to 10 % of the radius at every vertex."""
    k = np.arange(n, dtype=np.float64)
    t = 2.0 * np.pi * k / n
    r = COAST_RADIUS * (1.0 + 0.3 * np.sin(3.0 * t) + 0.1 * np.cos(7.0 * t + 0.5))
    if jagged:
        r = r * (1.0 - 0.1 * ((k * GOLDEN) % 1.0))
    return np.column_stack([r * np.cos(t), r * np.sin(t)])


def query_points(n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return rng.uniform(-QUERY_HALF_WIDTH, QUERY_HALF_WIDTH, (n, 2))


def cv_states(n: int, seed: int, half_width: float = 2000.0) -> np.ndarray:
    """(n, 4) constant-velocity states [x, vx, y, vy] around the origin."""
    rng = np.random.default_rng(seed)
    s = np.empty((n, 4))
    s[:, 0] = rng.uniform(-half_width, half_width, n)
    s[:, 2] = rng.uniform(-half_width, half_width, n)
    s[:, 1] = rng.uniform(-10, 10, n)
    s[:, 3] = rng.uniform(-10, 10, n)
    return s


def position_covariances(n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    sx, sy, rho = rng.uniform(5, 60, n), rng.uniform(5, 60, n), rng.uniform(-0.8, 0.8, n)
    c = np.zeros((n, 4, 4))
    c[:, 0, 0] = sx * sx
    c[:, 2, 2] = sy * sy
    c[:, 0, 2] = c[:, 2, 0] = rho * sx * sy
    c[:, 1, 1] = c[:, 3, 3] = 1.0
    return c


# --- timing ---------------------------------------------------------------------------------
def median_time(fn, repeats: int, min_sample: float) -> float:
    """Median seconds per call over ``repeats`` samples; each sample repeats the call until
    it has run for ``min_sample`` seconds."""
    fn()  # warm up (first-call caches, page faults)
    start = time.perf_counter()
    fn()
    once = time.perf_counter() - start
    inner = max(1, int(min_sample / max(once, 1e-9)))
    samples = []
    for _ in range(repeats):
        start = time.perf_counter()
        for _ in range(inner):
            fn()
        samples.append((time.perf_counter() - start) / inner)
    return statistics.median(samples)


# --- the radar three ways -------------------------------------------------------------------
def radar_model(extra_factors=()) -> SensorModel:
    detection = DetectionProbabilityModel(factors=[
        RangeBands(edges=EDGES, values=(0.0, 0.4, 0.0), upper_owns=(False, True)),
        AngularSector(centre=math.pi, width=BLIND_WIDTH, inside=0.0, outside=1.0),
        *extra_factors,
    ])
    return SensorModel(detection=detection, clutter=ClutterDensityModel(factors=[1e-4]),
                       position_mapping=(0, 2))


class NumpyRadar:
    """The radar's P_D with preallocated temporaries: r² against squared edges and the blind
    sector as inside ⇔ d·c ≥ |d| cos(w/2) ⇔ d·c ≥ 0 and (d·c)² ≥ r² cos²(w/2) (cos(w/2) > 0
    for w < π), so neither a square root nor an angle is computed."""

    def __init__(self, n: int, sensor=SENSOR, heading=HEADING):
        self.sx, self.sy = sensor
        bearing = heading + math.pi  # the sector's centre, world frame
        self.cx, self.cy = math.cos(bearing), math.sin(bearing)
        self.cos2 = math.cos(BLIND_WIDTH / 2) ** 2
        self.e0, self.e1 = EDGES[0] ** 2, EDGES[1] ** 2
        self.dx, self.dy, self.r2, self.along, self.tmp = (np.empty(n) for _ in range(5))
        self.m1, self.m2, self.m3 = np.empty(n, bool), np.empty(n, bool), np.empty(n, bool)
        self.out = np.empty(n)

    def __call__(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        dx, dy, r2, along, tmp = self.dx, self.dy, self.r2, self.along, self.tmp
        m1, m2, m3, out = self.m1, self.m2, self.m3, self.out
        np.subtract(x, self.sx, out=dx)
        np.subtract(y, self.sy, out=dy)
        np.multiply(dx, dx, out=r2)
        np.multiply(dy, dy, out=tmp)
        np.add(r2, tmp, out=r2)
        # 0.4 for 50 < r < 1612 (the 50 m edge belongs to the band below, 1612 m above).
        np.greater(r2, self.e0, out=m1)
        np.less(r2, self.e1, out=m2)
        np.logical_and(m1, m2, out=m1)
        # Blind (inside the sector) when along ≥ 0 and along² ≥ r² cos²(w/2).
        np.multiply(dx, self.cx, out=along)
        np.multiply(dy, self.cy, out=tmp)
        np.add(along, tmp, out=along)
        np.greater_equal(along, 0.0, out=m2)
        np.multiply(along, along, out=tmp)
        np.multiply(r2, self.cos2, out=dx)  # dx is free now
        np.greater_equal(tmp, dx, out=m3)
        np.logical_and(m2, m3, out=m2)
        np.logical_not(m2, out=m2)
        np.logical_and(m1, m2, out=m1)
        np.multiply(m1, 0.4, out=out)
        return out

    def near_boundary(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Points within TOL of a range edge or of the sector's cone."""
        dx, dy = x - self.sx, y - self.sy
        r = np.hypot(dx, dy)
        near = (np.abs(r - EDGES[0]) < TOL) | (np.abs(r - EDGES[1]) < TOL)
        # Distance to the cone's boundary rays, for points on the sector's side.
        along = dx * self.cx + dy * self.cy
        across = np.abs(dx * self.cy - dy * self.cx)
        half = BLIND_WIDTH / 2
        dist_to_ray = np.abs(across * math.cos(half) - along * math.sin(half))
        return near | ((along > -TOL) & (dist_to_ray < TOL)) | (r < TOL)


def agreement(a: np.ndarray, b: np.ndarray, near: np.ndarray, atol: float = 0.0) -> dict:
    differ = np.abs(a.astype(float) - b.astype(float)) > atol
    return {"n": int(a.size), "differ": int(differ.sum()), "differ_far_from_boundary":
            int((differ & ~near).sum()), "near_boundary": int(near.sum())}


# --- benchmarks -----------------------------------------------------------------------------
def bench_pd(sizes, repeats, min_sample):
    model = radar_model()
    context = model.context((*SENSOR, HEADING))
    rows = []
    for n in sizes:
        states = cv_states(n, seed=n)
        x, y = np.ascontiguousarray(states[:, 0]), np.ascontiguousarray(states[:, 2])
        numpy_radar = NumpyRadar(n)
        out = np.empty(n)
        ours = context.prob_detection_array(states, out=out).copy()
        ref = numpy_radar(x, y).copy()
        check = agreement(ours, ref, numpy_radar.near_boundary(x, y))
        t_ctx = median_time(lambda: context.prob_detection_array(states, out=out), repeats, min_sample)
        t_np = median_time(lambda: numpy_radar(x, y), repeats, min_sample)
        rows.append(row("pd_radar", n, n, {"ctxmodels": t_ctx, "numpy": t_np}, check))
    return rows


class PythonRadar:
    """The radar's P_D of one hypothesis as a plain Python function, what a user would pass
    where Stone Soup takes a callable: the same r² edges and dot-product sector as
    :class:`NumpyRadar`, on the two floats of the prediction's position."""

    def __init__(self, sensor=SENSOR, heading=HEADING):
        self.sx, self.sy = sensor
        bearing = heading + math.pi
        self.cx, self.cy = math.cos(bearing), math.sin(bearing)
        self.cos2 = math.cos(BLIND_WIDTH / 2) ** 2
        self.e0, self.e1 = EDGES[0] ** 2, EDGES[1] ** 2

    def __call__(self, hypothesis) -> float:
        vector = hypothesis.prediction.state_vector
        dx, dy = vector[0, 0] - self.sx, vector[2, 0] - self.sy
        r2 = dx * dx + dy * dy
        if not self.e0 < r2 < self.e1:
            return 0.0
        along = dx * self.cx + dy * self.cy
        return 0.0 if along >= 0 and along * along >= r2 * self.cos2 else 0.4


def bench_calls(sizes, repeats, min_sample):
    """Per-call cost: ``prob_detection_array`` with ``out=`` at small N against the NumPy
    radar's call at the same N, and the scalar ``prob_detection(hypothesis)`` (a Stone Soup
    ``Probability``) against :class:`PythonRadar` (a float), ns per call."""
    from stonesoup.types.hypothesis import SingleHypothesis
    from stonesoup.types.prediction import GaussianStatePrediction
    context = radar_model().context((*SENSOR, HEADING))
    rows = []
    for n in sizes:
        states = cv_states(n, seed=100 + n)
        x, y = np.ascontiguousarray(states[:, 0]), np.ascontiguousarray(states[:, 2])
        numpy_radar = NumpyRadar(n)
        out = np.empty(n)
        check = agreement(context.prob_detection_array(states, out=out).copy(),
                          numpy_radar(x, y).copy(), numpy_radar.near_boundary(x, y))
        times = {"ctxmodels": median_time(lambda: context.prob_detection_array(states, out=out),
                                          repeats, min_sample),
                 "numpy": median_time(lambda: numpy_radar(x, y), repeats, min_sample)}
        rows.append(row("pd_call_array (per call)", n, 1, times, check))
    states = cv_states(1000, seed=7)
    hypotheses = [SingleHypothesis(GaussianStatePrediction(s.reshape(-1, 1), np.eye(4)), None)
                  for s in states]
    python_radar, numpy_radar = PythonRadar(), NumpyRadar(len(states))
    ours = np.array([float(context.prob_detection(h)) for h in hypotheses])
    theirs = np.array([python_radar(h) for h in hypotheses])
    check = agreement(ours, theirs, numpy_radar.near_boundary(states[:, 0], states[:, 2]))
    one = hypotheses[len(hypotheses) // 2]
    times = {"ctxmodels": median_time(lambda: context.prob_detection(one), repeats, min_sample),
             "python": median_time(lambda: python_radar(one), repeats, min_sample)}
    rows.append(row("pd_call_scalar (per call)", 1, 1, times, check))
    return rows


def bench_expected_pd(sizes, repeats, min_sample):
    return [r for n in sizes for r in _bench_expected_pd(n, repeats, min_sample)]


def _bench_expected_pd(n, repeats, min_sample):
    means = cv_states(n, seed=11)
    covars = position_covariances(n, seed=12)
    at_mean = radar_model().context((*SENSOR, HEADING))
    cubature_model = radar_model()
    cubature_model = SensorModel(detection=cubature_model.detection, clutter=cubature_model.clutter,
                                 position_mapping=(0, 2), pd_evaluation="cubature")
    cubature = cubature_model.context((*SENSOR, HEADING))
    # NumPy: the same Cholesky factor of the position block and the 4 points ±√2 on the axes.
    a, b, c = covars[:, 0, 0], covars[:, 0, 2], covars[:, 2, 2]
    l11 = np.sqrt(a)
    l21 = b / l11
    l22 = np.sqrt(c - l21 * l21)
    s = math.sqrt(2.0)
    offsets = [(l11 * u0, l21 * u0 + l22 * u1) for u0, u1 in ((s, 0.0), (-s, 0.0), (0.0, s), (0.0, -s))]
    mx, my = means[:, 0].copy(), means[:, 2].copy()
    radar4 = NumpyRadar(4 * n)
    xs = np.concatenate([mx + ox for ox, _ in offsets])
    ys = np.concatenate([my + oy for _, oy in offsets])
    xs_buf, ys_buf = np.empty(4 * n), np.empty(4 * n)

    def numpy_cubature():
        for k, (ox, oy) in enumerate(offsets):
            np.add(mx, ox, out=xs_buf[k * n:(k + 1) * n])
            np.add(my, oy, out=ys_buf[k * n:(k + 1) * n])
        return radar4(xs_buf, ys_buf).reshape(4, n).mean(axis=0)

    ours = cubature.prob_detection_array(means, covars).copy()
    ref = numpy_cubature()
    near = radar4.near_boundary(xs, ys).reshape(4, n).any(axis=0)
    # Weighted sums of the same values in a different order: equal to rounding.
    check = agreement(ours, ref, near, atol=1e-12)
    out = np.empty(n)
    times = {
        "ctxmodels": median_time(lambda: cubature.prob_detection_array(means, covars, out=out),
                                 repeats, min_sample),
        "ctxmodels_at_mean": median_time(lambda: at_mean.prob_detection_array(means, out=out),
                                         repeats, min_sample),
        "numpy": median_time(numpy_cubature, repeats, min_sample),
    }
    return [row("expected_pd_cubature", n, n, times, check)]


def bench_clutter(sizes, repeats, min_sample):
    return [r for n in sizes for r in _bench_clutter(n, repeats, min_sample)]


def _bench_clutter(n, repeats, min_sample):
    clutter = ClutterDensityModel(factors=[
        RangeBands(edges=(1000.0,), values=(1e-3, 1e-2), upper_owns=(True,)),
        MetadataThreshold(key="area", threshold=10.0, below=1e-1, at_or_above=1e-3, missing=1e-2),
    ])
    model = SensorModel(detection=DetectionProbabilityModel(factors=[0.9]), clutter=clutter,
                        position_mapping=(0, 2))
    context = model.context((*SENSOR, HEADING))
    rng = np.random.default_rng(5)
    positions = rng.uniform(-2500, 2500, (n, 2))
    area = rng.uniform(0, 40, n)
    area[rng.random(n) < 0.1] = np.nan
    metadata = area.reshape(-1, 1).copy()
    r2, tmp = np.empty(n), np.empty(n)
    out = np.empty(n)

    def numpy_clutter():
        np.subtract(positions[:, 0], SENSOR[0], out=r2)
        np.multiply(r2, r2, out=r2)
        np.subtract(positions[:, 1], SENSOR[1], out=tmp)
        np.multiply(tmp, tmp, out=tmp)
        np.add(r2, tmp, out=r2)
        lam = np.where(r2 >= 1000.0 ** 2, 1e-2, 1e-3)
        rule = np.where(np.isnan(area), 1e-2, np.where(area < 10.0, 1e-1, 1e-3))
        return np.multiply(lam, rule, out=out)

    ours = context.clutter_spatial_density_array(positions, metadata).copy()
    ref = numpy_clutter().copy()
    r = np.hypot(positions[:, 0] - SENSOR[0], positions[:, 1] - SENSOR[1])
    check = agreement(ours, ref, np.abs(r - 1000.0) < TOL)
    ours_out = np.empty(n)
    times = {
        "ctxmodels": median_time(
            lambda: context.clutter_spatial_density_array(positions, metadata, out=ours_out),
            repeats, min_sample),
        "numpy": median_time(numpy_clutter, repeats, min_sample),
    }
    return [row("clutter_metadata", n, n, times, check)]


def slant_offsets(x, y, z, height, dz, h2, r2, tmp):
    """NumPy's offsets from a sensor at the origin and ``height``, into the buffers: the
    height above it ``dz``, the squared plane range ``h2`` and the squared slant range ``r2``
    (``h2`` and ``r2`` may be one buffer)."""
    np.subtract(z, height, out=dz)
    np.multiply(x, x, out=h2)
    np.multiply(y, y, out=tmp)
    np.add(h2, tmp, out=h2)
    np.multiply(dz, dz, out=tmp)
    np.add(h2, tmp, out=r2)


def bench_clutter_heights(sizes, repeats, min_sample):
    """λ of a 3-D radar's detections, (M, 3) positions: range bands on the slant range from
    the sensor's height × sea clutter below +0.5° of elevation (an elevation sector)."""
    rows = []
    lower, upper = math.radians(-90), math.radians(0.5)
    clutter = ClutterDensityModel(factors=[
        RangeBands(edges=(20_000.0,), values=(1e-9, 2e-10)),
        ElevationSector(lower=lower, upper=upper, inside=50.0, outside=1.0)])
    model = SensorModel(detection=DetectionProbabilityModel(factors=[0.9]), clutter=clutter,
                        position_mapping=(0, 2, 4))
    context = model.context((0.0, 0.0, 0.0, 25.0))
    for n in sizes:
        rng = np.random.default_rng(n + 3)
        positions = np.column_stack([rng.uniform(-40e3, 40e3, n), rng.uniform(-40e3, 40e3, n),
                                     rng.uniform(0, 3000, n)])
        x, y, z = (np.ascontiguousarray(positions[:, c]) for c in range(3))
        out = np.empty(n)
        dz, r2, r, tmp = (np.empty(n) for _ in range(4))
        sea = np.empty(n, bool)

        def numpy_clutter():
            # slant r², the band, then r sin(lower) ≤ dz ≤ r sin(upper) without an arctangent
            slant_offsets(x, y, z, 25.0, dz, r2, r2, tmp)
            np.sqrt(r2, out=r)
            np.multiply(r, math.sin(upper), out=tmp)
            np.less_equal(dz, tmp, out=sea)
            np.multiply(sea, 49.0, out=tmp)
            np.add(tmp, 1.0, out=tmp)
            np.copyto(out, np.where(r <= 20_000.0, 1e-9, 2e-10))
            return np.multiply(out, tmp, out=out)

        ours = context.clutter_spatial_density_array(positions).copy()
        ref = np.array(numpy_clutter(), copy=True)
        elevation = np.arctan2(z - 25.0, np.hypot(x, y))
        slant = np.sqrt(x ** 2 + y ** 2 + (z - 25.0) ** 2)
        near = (np.abs(elevation - upper) < 1e-9) | (np.abs(slant - 20_000.0) < TOL)
        check = agreement(ours, ref, near)
        ours_out = np.empty(n)
        times = {
            "ctxmodels": median_time(
                lambda: context.clutter_spatial_density_array(positions, out=ours_out),
                repeats, min_sample),
            "numpy": median_time(numpy_clutter, repeats, min_sample),
        }
        rows.append(row("clutter_elevation_slant", n, n, times, check))
    return rows


def land_models(n_vertices: int, jagged: bool):
    ring = coastline(n_vertices, jagged)
    polygon = shapely.Polygon(ring)
    assert polygon.is_valid
    shapely.prepare(polygon)
    return LandMask(polygons=[ring]), polygon


def bench_land(vertex_counts, n_points, repeats, min_sample):
    points = query_points(n_points, seed=4)
    px, py = points[:, 0].copy(), points[:, 1].copy()
    rows = []
    for jagged in (False, True):
        for nv in vertex_counts:
            land, polygon = land_models(nv, jagged)
            ours = land.contains(points)
            ref = shapely.contains_xy(polygon, px, py)
            # shapely.contains_xy is False on the boundary; ctxmodels counts it as land.
            differ = ours != ref
            near = np.zeros(n_points, bool)
            if differ.any():
                near[differ] = shapely.distance(polygon.boundary, shapely.points(points[differ])) < TOL
            check = {"n": n_points, "differ": int(differ.sum()),
                     "differ_far_from_boundary": int((differ & ~near).sum()),
                     "near_boundary": int(near.sum())}
            times = {
                "ctxmodels": median_time(lambda: land.contains(points), repeats, min_sample),
                "shapely": median_time(lambda: shapely.contains_xy(polygon, px, py), repeats, min_sample),
            }
            rows.append(row(f"land_contains_{'jagged' if jagged else 'smooth'}", nv, n_points, times, check))
    return rows


def sight_segments(targets: np.ndarray) -> np.ndarray:
    coords = np.empty((len(targets), 2, 2))
    coords[:, 0] = SENSOR
    coords[:, 1] = targets
    return shapely.linestrings(coords)


def shapely_visible(polygon, targets: np.ndarray) -> np.ndarray:
    return ~shapely.intersects(polygon, sight_segments(targets))


def sight_check(ours, ref, polygon, targets) -> dict:
    differ = ours != ref
    near = np.zeros(len(targets), bool)
    if differ.any():
        near[differ] = shapely.distance(polygon.boundary, sight_segments(targets[differ])) < TOL
    return {"n": int(len(targets)), "differ": int(differ.sum()),
            "differ_far_from_boundary": int((differ & ~near).sum()), "near_boundary": int(near.sum())}


def bench_sight(vertex_counts, n_targets, shapely_budget, repeats, min_sample):
    targets = query_points(n_targets, seed=5)
    rows = []
    for jagged in (False, True):
        for nv in vertex_counts:
            land, polygon = land_models(nv, jagged)
            sight = LineOfSight(land=land)
            # Shapely costs ~2 µs per coastline vertex per 1000 targets: time it on a subset
            # of the same targets when the full set would take too long.
            n_shapely = int(min(n_targets, max(1000, shapely_budget // nv)))
            sub = targets[:n_shapely]
            ours = sight.visible(SENSOR, targets)
            ref = shapely_visible(polygon, sub)
            check = sight_check(ours[:n_shapely], ref, polygon, sub)
            t_ctx = median_time(lambda: sight.visible(SENSOR, targets), repeats, min_sample) / n_targets
            t_shp = median_time(lambda: shapely_visible(polygon, sub), max(1, repeats // 2 + 1),
                                min_sample) / n_shapely
            r = row(f"line_of_sight_{'jagged' if jagged else 'smooth'}", nv, 1,
                    {"ctxmodels": t_ctx, "shapely": t_shp}, check)
            r["targets"] = {"ctxmodels": n_targets, "shapely": n_shapely}
            rows.append(r)
    return rows


def bench_pd_land_sight(n_states, n_vertices, repeats, min_sample):
    """The whole radar P_D with land and sight, against NumPy radar × Shapely land × Shapely
    sight (each only where the radar's P_D is not already 0)."""
    land, polygon = land_models(n_vertices, jagged=False)
    model = radar_model([land, LineOfSight(land=land)])
    context = model.context((*SENSOR, HEADING))
    states = cv_states(n_states, seed=9, half_width=QUERY_HALF_WIDTH)
    x, y = states[:, 0].copy(), states[:, 2].copy()
    numpy_radar = NumpyRadar(n_states)

    def reference():
        pd = numpy_radar(x, y).copy()
        live = np.flatnonzero(pd)
        pts = np.column_stack([x[live], y[live]])
        on_land = shapely.contains_xy(polygon, pts[:, 0], pts[:, 1])
        seen = shapely_visible(polygon, pts)
        pd[live[on_land | ~seen]] = 0.0
        return pd

    ours = context.prob_detection_array(states).copy()
    ref = reference()
    differ = ours != ref
    near = numpy_radar.near_boundary(x, y)
    if (differ & ~near).any():
        idx = np.flatnonzero(differ & ~near)
        pts = np.column_stack([x[idx], y[idx]])
        near[idx] = ((shapely.distance(polygon.boundary, shapely.points(pts)) < TOL)
                     | (shapely.distance(polygon.boundary, sight_segments(pts)) < TOL))
    check = {"n": n_states, "differ": int(differ.sum()),
             "differ_far_from_boundary": int((differ & ~near).sum()), "near_boundary": int(near.sum())}
    out = np.empty(n_states)
    times = {
        "ctxmodels": median_time(lambda: context.prob_detection_array(states, out=out), repeats, min_sample),
        "numpy+shapely": median_time(reference, max(1, repeats // 2 + 1), min_sample),
    }
    r = row("pd_radar_land_sight", n_vertices, n_states, times, check)
    r["states"] = n_states
    return [r]


def bench_radar(sizes, repeats, min_sample):
    from scipy import stats
    rows = []
    pose = (0.0, 0.0, 0.0)
    sw1 = RadarEquation(reference_snr=13.0, reference_range=1500.0, false_alarm_probability=1e-6,
                        swerling=1)
    sw0 = RadarEquation(reference_snr=5.0, reference_range=1500.0, false_alarm_probability=1e-6,
                        swerling=0, pulses=10)
    horizon = RadarHorizon(antenna_height=20.0, target_height=2.0)
    for n in sizes:
        states = cv_states(n, seed=n + 1, half_width=4500.0)
        x, y = np.ascontiguousarray(states[:, 0]), np.ascontiguousarray(states[:, 2])
        out, r2, tmp = np.empty(n), np.empty(n), np.empty(n)

        def squared_range():
            np.multiply(x, x, out=r2)
            np.multiply(y, y, out=tmp)
            np.add(r2, tmp, out=r2)
            return r2

        def numpy_sw1(ln_pfa=math.log(1e-6), s0=10 ** 1.3, r0_2=1500.0 ** 2):
            np.divide(r0_2, squared_range(), out=tmp)
            np.multiply(tmp, tmp, out=tmp)
            np.multiply(tmp, s0, out=tmp)
            np.add(tmp, 1.0, out=tmp)
            np.divide(ln_pfa, tmp, out=tmp)
            return np.exp(tmp, out=out)

        threshold = sw0.threshold

        def scipy_sw0():
            snr = 10 ** 0.5 * (1500.0 ** 2 / squared_range()) ** 2
            return stats.ncx2.sf(2 * threshold, 20, 20 * snr)

        d2 = horizon.range ** 2

        def numpy_horizon():
            return np.less_equal(squared_range(), d2).astype(np.float64)

        for name, factor, reference, label, atol in [
                ("pd_radar_equation_swerling1", sw1, numpy_sw1, "numpy", 1e-13),
                ("pd_radar_equation_swerling0_10", sw0, scipy_sw0, "scipy", 1e-9),
                ("pd_radar_horizon", horizon, numpy_horizon, "numpy", 0.0)]:
            context = SensorModel(detection=DetectionProbabilityModel(factors=[factor]),
                                  clutter=ClutterDensityModel(factors=[1e-4]),
                                  position_mapping=(0, 2)).context(pose)
            ours = context.prob_detection_array(states, out=out).copy()
            ref = np.array(reference(), copy=True)
            near = np.abs(np.sqrt(squared_range()) - horizon.range) < TOL if atol == 0 else np.zeros(n, bool)
            check = agreement(ours, ref, near, atol=atol)
            t_ctx = median_time(lambda: context.prob_detection_array(states, out=out), repeats, min_sample)
            t_ref = median_time(reference, repeats, min_sample)
            rows.append(row(name, n, n, {"ctxmodels": t_ctx, label: t_ref}, check))
    return rows


def bench_heights(sizes, repeats, min_sample):
    """3-D coverage on (N, 6) states [x, vx, y, vy, z, vz]: an elevation sector alone, and a
    beam (slant-range band × elevation sector × the horizon at each target's height)."""
    rows = []
    pose = (0.0, 0.0, 0.0, 25.0)
    lower, upper = math.radians(-2), math.radians(30)
    sector = ElevationSector(lower=lower, upper=upper)
    horizon = RadarHorizon(antenna_height=25.0, target_height=None)
    band = RangeBands(edges=(30_000.0,), values=(0.9, 0.0))
    scale = 2 * horizon.k * horizon.earth_radius
    reach = math.sqrt(scale * 25.0)
    for n in sizes:
        rng = np.random.default_rng(n + 2)
        states = np.column_stack([rng.uniform(-40e3, 40e3, n), np.zeros(n), rng.uniform(-40e3, 40e3, n),
                                  np.zeros(n), rng.uniform(-100, 6000, n), np.zeros(n)])
        x, y, z = (np.ascontiguousarray(states[:, c]) for c in (0, 2, 4))
        out = np.empty(n)
        dz, h2, r2, r, tmp, edge = (np.empty(n) for _ in range(6))
        m1, m2 = np.empty(n, bool), np.empty(n, bool)

        def offsets():
            slant_offsets(x, y, z, 25.0, dz, h2, r2, tmp)

        def beam_mask():
            # r sin(lower) ≤ dz ≤ r sin(upper): no arctangent
            np.sqrt(r2, out=r)
            np.multiply(r, math.sin(lower), out=tmp)
            np.greater_equal(dz, tmp, out=m1)
            np.multiply(r, math.sin(upper), out=tmp)
            np.less_equal(dz, tmp, out=m2)
            np.logical_and(m1, m2, out=m1)
            return m1

        def numpy_sector():
            offsets()
            return np.multiply(beam_mask(), 1.0, out=out)

        def numpy_beam():
            offsets()
            beam_mask()
            np.less(r2, 30_000.0 ** 2, out=m2)
            np.logical_and(m1, m2, out=m1)
            # the horizon: h² ≤ (√(2kR h_a) + √(2kR max(z, 0)))²
            np.maximum(z, 0.0, out=edge)
            np.multiply(edge, scale, out=edge)
            np.sqrt(edge, out=edge)
            np.add(edge, reach, out=edge)
            np.multiply(edge, edge, out=edge)
            np.less_equal(h2, edge, out=m2)
            np.logical_and(m1, m2, out=m1)
            return np.multiply(m1, 0.9, out=out)

        for name, factors, reference in [("pd_elevation_sector", [sector], numpy_sector),
                                         ("pd_3d_beam_horizon", [band, sector, horizon], numpy_beam)]:
            context = SensorModel(detection=DetectionProbabilityModel(factors=factors),
                                  clutter=ClutterDensityModel(factors=[1e-4]),
                                  position_mapping=(0, 2, 4)).context(pose)
            ours = context.prob_detection_array(states, out=out).copy()
            ref = np.array(reference(), copy=True)
            elevation = np.arctan2(z - 25.0, np.hypot(x, y))
            near = (np.abs(elevation - lower) < 1e-9) | (np.abs(elevation - upper) < 1e-9)
            check = agreement(ours, ref, near)
            t_ctx = median_time(lambda: context.prob_detection_array(states, out=out), repeats, min_sample)
            t_ref = median_time(reference, repeats, min_sample)
            rows.append(row(name, n, n, {"ctxmodels": t_ctx, "numpy": t_ref}, check))
    return rows


def bench_range_rate(sizes, repeats, min_sample):
    """The MTI notch on (N, 4) states [x, vx, y, vy] seen from a moving radar: |ṙ| ≤ w, and
    the first three blind speeds."""
    rows = []
    notch = RangeRateNotch(width=1.5, blind_speed=32.0, multiples=3)
    pose = ctxmodels.Pose(x=0.0, y=0.0, vx=4.0, vy=-2.0)
    for n in sizes:
        rng = np.random.default_rng(n + 3)
        states = np.column_stack([rng.uniform(-8e3, 8e3, n), rng.uniform(-40, 40, n),
                                  rng.uniform(-8e3, 8e3, n), rng.uniform(-40, 40, n)])
        x, vx, y, vy = (np.ascontiguousarray(states[:, c]) for c in range(4))
        out = np.empty(n)
        r2, dot, tmp, speed = (np.empty(n) for _ in range(4))
        notched, m = np.empty(n, bool), np.empty(n, bool)

        def numpy_notch():
            np.multiply(x, x, out=r2)
            np.multiply(y, y, out=tmp)
            np.add(r2, tmp, out=r2)
            np.subtract(vx, 4.0, out=tmp)
            np.multiply(x, tmp, out=dot)
            np.add(vy, 2.0, out=tmp)
            np.multiply(y, tmp, out=tmp)
            np.add(dot, tmp, out=dot)
            np.multiply(dot, dot, out=tmp)
            np.multiply(r2, 1.5 * 1.5, out=speed)
            np.less_equal(tmp, speed, out=notched)
            np.sqrt(r2, out=speed)
            np.abs(dot, out=tmp)
            np.divide(tmp, speed, out=speed)
            for k in (1, 2, 3):
                np.subtract(speed, 32.0 * k, out=tmp)
                np.abs(tmp, out=tmp)
                np.less_equal(tmp, 1.5, out=m)
                np.logical_or(notched, m, out=notched)
            np.logical_not(notched, out=notched)
            return np.multiply(notched, 1.0, out=out)

        context = SensorModel(detection=DetectionProbabilityModel(factors=[notch]),
                              clutter=ClutterDensityModel(factors=[1e-4]),
                              velocity_mapping=(1, 3)).context(pose)
        ours = context.prob_detection_array(states, out=out).copy()
        ref = np.array(numpy_notch(), copy=True)
        radial = np.abs((x * (vx - 4.0) + y * (vy + 2.0)) / np.hypot(x, y))
        near = np.zeros(n, bool)
        for edge in (1.5, 30.5, 33.5, 62.5, 65.5, 94.5, 97.5):
            near |= np.abs(radial - edge) < 1e-9
        check = agreement(ours, ref, near)
        t_ctx = median_time(lambda: context.prob_detection_array(states, out=out), repeats, min_sample)
        t_ref = median_time(numpy_notch, repeats, min_sample)
        rows.append(row("pd_range_rate_notch", n, n, {"ctxmodels": t_ctx, "numpy": t_ref}, check))
    return rows


def row(name, size, per, times, check):
    """`per`: how many states / points / targets one call handles (1 if already per item)."""
    ns = {k: v / per * 1e9 for k, v in times.items()}
    ours = ns["ctxmodels"]
    speedup = {k: v / ours for k, v in ns.items() if k != "ctxmodels"}
    return {"benchmark": name, "size": size, "ns_per_item": ns, "speedup": speedup, "agreement": check}


def print_table(results: dict) -> None:
    m = results["machine"]
    print(f"# ctxmodels {m['ctxmodels']} · numpy {m['numpy']} · shapely {m['shapely']} · "
          f"{m['cpu_count']} cores · {m['repeats']} repeats (median)")
    header = (f"{'benchmark':28s} {'size':>8s} {'ctxmodels':>10s} {'reference':>24s} "
              f"{'speed-up':>9s} {'agree':>12s}")
    print(header)
    print("-" * len(header))
    for r in results["results"]:
        ours = r["ns_per_item"]["ctxmodels"]
        refs = [(k, v) for k, v in r["ns_per_item"].items() if k != "ctxmodels"]
        a = r["agreement"]
        agree = "ok" if a["differ_far_from_boundary"] == 0 else f"{a['differ_far_from_boundary']} BAD"
        if a["differ"]:
            agree += f" ({a['differ']}≈)"
        for i, (k, v) in enumerate(refs):
            label = f"{v:10.1f} ns {k}"
            print(f"{r['benchmark'] if i == 0 else '':28s} {r['size'] if i == 0 else '':>8} "
                  f"{(f'{ours:8.1f} ns') if i == 0 else '':>10s} {label:>24s} "
                  f"{r['speedup'][k]:8.1f}× {agree if i == 0 else '':>12s}")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="small sizes and few repeats (seconds)")
    parser.add_argument("--json", metavar="PATH", help="write the results as JSON")
    parser.add_argument("--repeats", type=int, default=None, help="samples per timing (median)")
    args = parser.parse_args(argv)
    quick = args.quick
    repeats = args.repeats or (3 if quick else 7)
    min_sample = 0.002 if quick else 0.02
    radar_sizes = (10_000,) if quick else (10_000, 1_000_000)
    if quick:
        pd_sizes, vertex_counts = (1000, 10_000), (100, 1000)
        n_points, n_targets, shapely_budget = 10_000, 5_000, 5e6
        cub_n, clutter_n, combo = (10_000,), (10_000,), (5_000, 1000)
    else:
        pd_sizes, vertex_counts, n_points, n_targets, shapely_budget = (
            (1000, 10_000, 100_000, 1_000_000, 10_000_000), (100, 1000, 10_000, 100_000), 100_000,
            100_000, 1e9)
        cub_n, clutter_n, combo = (10_000, 100_000), (10_000, 100_000, 1_000_000), (100_000, 10_000)

    results = {
        "machine": {
            "cpu_count": os.cpu_count(), "platform": platform.platform(), "processor": platform.processor(),
            "python": sys.version.split()[0], "numpy": np.__version__, "shapely": shapely.__version__,
            "ctxmodels": ctxmodels.__version__, "date": datetime.datetime.now().isoformat(timespec="seconds"),
            "quick": quick, "repeats": repeats,
        },
        "results": [],
    }
    out = results["results"]
    out += bench_pd(pd_sizes, repeats, min_sample)
    out += bench_calls((1, 10, 100), repeats, min_sample)
    out += bench_expected_pd(cub_n, repeats, min_sample)
    out += bench_clutter(clutter_n, repeats, min_sample)
    out += bench_land(vertex_counts, n_points, repeats, min_sample)
    out += bench_sight(vertex_counts, n_targets, shapely_budget, repeats, min_sample)
    out += bench_pd_land_sight(*combo, repeats, min_sample)
    out += bench_radar(radar_sizes, repeats, min_sample)
    out += bench_heights(radar_sizes, repeats, min_sample)
    out += bench_range_rate(radar_sizes, repeats, min_sample)
    out += bench_clutter_heights(radar_sizes, repeats, min_sample)
    print_table(results)
    bad = [r["benchmark"] for r in out if r["agreement"]["differ_far_from_boundary"]]
    results["agree"] = not bad
    if args.json:
        with open(args.json, "w") as f:
            json.dump(results, f, indent=2)
    if bad:
        print(f"DISAGREEMENT away from boundaries in: {', '.join(bad)}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
