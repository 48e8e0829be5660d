"""A sensor with every kind of factor and seeded inputs large enough for the core's own
threads, evaluated on every path: shared by the concurrency tests and their child processes."""
import hashlib
import math

import numpy as np

from ctxmodels import (AngularSector, ClutterDensityModel, DetectionProbabilityModel, LandMask,
                       LineOfSight, MetadataThreshold, RangeBands, SensorModel)

N = 40_000  # above the core's parallel threshold (32768 rows): Rayon threads are used too
ISLAND = np.array([[100.0, -50.0], [300.0, -50.0], [300.0, 150.0], [100.0, 150.0]])
LAND = LandMask(polygons=[ISLAND, ISLAND + [-900.0, 400.0]])


def sensor(pd_evaluation="mean"):
    return SensorModel(
        detection=DetectionProbabilityModel(factors=[
            RangeBands(edges=(50, 1612), values=(0, 0.4, 0), upper_owns=(False, True)),
            AngularSector.blind(math.pi, math.radians(65)), LAND, LineOfSight(land=LAND)]),
        clutter=ClutterDensityModel(factors=[
            RangeBands(edges=(1000,), values=(1e-3, 1e-2)),
            MetadataThreshold(key="area", threshold=10, below=1e-1, at_or_above=1e-3)]),
        pd_evaluation=pd_evaluation, pd_order=4)


def inputs(seed, n=N):
    rng = np.random.default_rng(seed)
    means = np.column_stack([rng.uniform(-1800, 1800, n), rng.normal(0, 5, n),
                             rng.uniform(-1800, 1800, n), rng.normal(0, 5, n)])
    covars = np.tile(np.diag([400.0, 4.0, 900.0, 4.0]), (n, 1, 1))
    areas = rng.uniform(0, 20, (n, 1))
    return means, covars, areas


def evaluate_all(context, means, covars, areas):
    # The particle form reads the same states as (D, N) columns; log and log(1 - P_D).
    return (context.prob_detection_array(means),
            context.prob_detection_array(means, covars),
            context.clutter_spatial_density_array(means[:, 0::2], areas),
            *context.prob_detection_particles(np.ascontiguousarray(means.T), log=True,
                                              missed=True))


def digest(results):
    h = hashlib.sha256()
    for r in results:
        h.update(np.ascontiguousarray(r).tobytes())
    return h.hexdigest()
