"""Per-scan cost of the context-aware Stone Soup drop-ins against the stock 1.9.1 components.

* **GM-PHD update**: ``ctxmodels.stonesoup.PHDUpdater`` with a ``DetectorContext`` (the
  paper's radar: range bands and the blind sector astern, plus range-banded clutter) against
  ``stonesoup.updater.pointprocess.PHDUpdater`` with the constant P_D and clutter density, on
  the same hypotheses (built once by ``GaussianMixtureHypothesiser``; updaters do not change
  them): N components × M detections, default 50 × 20.
* **Particle log P_D** over 10⁵ particles (Stone Soup's (D, N) ``StateVectors``; the same
  radar, optionally with a land mask and line of sight), measured in the same run, calls
  interleaved: the path the particle updaters took before
  (``np.log(context.prob_detection_array(particles.T))``: the transposed view copied to
  rows, NumPy's log in Python), the core call that replaced it
  (``context.prob_detection_particles(particles, log=True)``), the updater's
  ``get_log_detection_probability`` (which makes that call) and the stock updater's
  constant. The two paths' results are checked bit for bit. Particles as a prediction makes
  them (C-ordered) and as resampling leaves them (Fortran-ordered: there ``.T`` is already
  rows, no copy).

Times are medians of repeated scans, per scan. Run ``python benches/end_to_end.py``
(``--quick`` for a small run, ``--json PATH`` to write the results).
"""
from __future__ import annotations

import argparse
import datetime
import json
import math
import os
import statistics
import sys
import time

import numpy as np
from stonesoup.hypothesiser.distance import DistanceHypothesiser
from stonesoup.hypothesiser.gaussianmixture import GaussianMixtureHypothesiser
from stonesoup.measures import Mahalanobis
from stonesoup.models.measurement.linear import LinearGaussian
from stonesoup.models.transition.linear import CombinedLinearGaussianTransitionModel, ConstantVelocity
from stonesoup.predictor.kalman import KalmanPredictor
from stonesoup.types.array import StateVectors
from stonesoup.types.detection import Clutter, Detection
from stonesoup.types.mixture import GaussianMixture
from stonesoup.types.prediction import BernoulliParticleStatePrediction
from stonesoup.types.state import TaggedWeightedGaussianState
from stonesoup.updater.kalman import KalmanUpdater
from stonesoup.updater.particle import BernoulliParticleUpdater as StockBernoulli
from stonesoup.updater.pointprocess import PHDUpdater as StockPHD

import ctxmodels
from ctxmodels.stonesoup.particle import BernoulliParticleUpdater
from ctxmodels.stonesoup.gmphd import PHDUpdater

T0 = datetime.datetime(2024, 1, 1)
SCAN = datetime.timedelta(seconds=1.25)
SENSOR_POSE = (-1500.0, 250.0, 0.3)
MEASUREMENT = LinearGaussian(ndim_state=4, mapping=(0, 2), noise_covar=np.eye(2) * 25.0)
TRANSITION = CombinedLinearGaussianTransitionModel([ConstantVelocity(0.05)] * 2)


def radar_context(with_land: bool = False):
    factors = [
        ctxmodels.RangeBands(edges=(50.0, 1612.0), values=(0.0, 0.4, 0.0), upper_owns=(False, True)),
        ctxmodels.AngularSector(centre=math.pi, width=math.radians(65.0), inside=0.0, outside=1.0),
    ]
    if with_land:
        n = 10_000
        t = 2 * np.pi * np.arange(n) / n
        r = 300.0 * (1 + 0.3 * np.sin(3 * t))
        land = ctxmodels.LandMask(polygons=[np.column_stack([r * np.cos(t) - 600, r * np.sin(t) + 250])])
        factors += [land, ctxmodels.LineOfSight(land=land)]
    model = ctxmodels.SensorModel(
        detection=ctxmodels.DetectionProbabilityModel(factors=factors),
        clutter=ctxmodels.ClutterDensityModel(factors=[
            ctxmodels.RangeBands(edges=(1000.0,), values=(1e-7, 1e-6), upper_owns=(True,))]),
        position_mapping=(0, 2))
    return model.context(SENSOR_POSE, T0 + SCAN)


def median_time(fn, repeats: int) -> float:
    fn()
    samples = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        samples.append(time.perf_counter() - start)
    return statistics.median(samples)


def phd_scan(n_components: int, n_detections: int, seed: int = 3):
    """A prior mixture around the sensor and one scan of detections (half from components)."""
    rng = np.random.default_rng(seed)
    components = []
    for k in range(n_components):
        mean = [rng.uniform(-2500, 500), rng.normal(0, 3), rng.uniform(-1000, 1500), rng.normal(0, 3)]
        components.append(TaggedWeightedGaussianState(
            np.array(mean, float).reshape(-1, 1), np.diag([30.0, 2.0, 30.0, 2.0]) ** 2,
            weight=rng.uniform(0.1, 1.0), timestamp=T0, tag=str(k)))
    timestamp = T0 + SCAN
    detections = set()
    for j in range(n_detections):
        if j < n_detections // 2:
            c = components[j % n_components]
            z = np.array([c.state_vector[0, 0], c.state_vector[2, 0]]) + rng.normal(0, 5, 2)
            detections.add(Detection(z.reshape(-1, 1), timestamp=timestamp, measurement_model=MEASUREMENT))
        else:
            z = [rng.uniform(-2500, 500), rng.uniform(-1000, 1500)]
            detections.add(Clutter(np.array(z).reshape(-1, 1), timestamp=timestamp,
                                   measurement_model=MEASUREMENT))
    kalman = KalmanUpdater(MEASUREMENT)
    hypothesiser = GaussianMixtureHypothesiser(
        DistanceHypothesiser(KalmanPredictor(TRANSITION), kalman, Mahalanobis(), missed_distance=1e6),
        order_by_detection=True)
    hypotheses = hypothesiser.hypothesise(GaussianMixture(components), detections, timestamp)
    return kalman, hypotheses


def bench_phd(n_components, n_detections, repeats):
    kalman, hypotheses = phd_scan(n_components, n_detections)
    context = radar_context()
    stock = StockPHD(kalman, clutter_spatial_density=1e-6, prob_detection=0.4, prob_survival=0.99)
    ours = PHDUpdater(kalman, clutter_spatial_density=1e-6, prob_detection=0.4, prob_survival=0.99)
    t_stock = median_time(lambda: stock.update(hypotheses), repeats)
    t_ours = median_time(lambda: ours.update(hypotheses, detector_context=context), repeats)
    t_ours_plain = median_time(lambda: ours.update(hypotheses), repeats)
    n_out = len(ours.update(hypotheses, detector_context=context))
    return {"benchmark": "gmphd_update", "components": n_components, "detections": n_detections,
            "ms_per_scan": {"stock": t_stock * 1e3, "ctxmodels_context": t_ours * 1e3,
                            "ctxmodels_no_context": t_ours_plain * 1e3},
            "ratio_context_over_stock": t_ours / t_stock, "updated_components": n_out}


def median_times(fns: dict, repeats: int) -> dict:
    """Median time of each callable, the callables interleaved in every repeat so load
    changes on a shared machine hit them alike."""
    for fn in fns.values():
        fn()
    samples = {name: [] for name in fns}
    for _ in range(repeats):
        for name, fn in fns.items():
            start = time.perf_counter()
            fn()
            samples[name].append(time.perf_counter() - start)
    return {name: statistics.median(s) for name, s in samples.items()}


def old_particle_log_pd(context, prediction):
    """The particle updaters' path before prob_detection_particles: rows for
    prob_detection_array (the transposed view, copied unless Fortran-ordered), NumPy's log."""
    particles = np.asarray(prediction.state_vector, dtype=np.float64)
    pd = np.asarray(context.prob_detection_array(particles.T), dtype=np.float64)
    with np.errstate(divide="ignore"):
        return np.log(pd)


def bench_particle_pd(n_particles, repeats, with_land, order="C"):
    rng = np.random.default_rng(4)
    states = np.vstack([rng.uniform(-3000, 1000, n_particles), rng.normal(0, 3, n_particles),
                        rng.uniform(-1500, 2000, n_particles), rng.normal(0, 3, n_particles)])
    particles = StateVectors(np.asarray(states, order=order))
    log_weight = np.full(n_particles, -np.log(n_particles))
    prediction = BernoulliParticleStatePrediction(state_vector=particles, log_weight=log_weight,
                                                  existence_probability=0.6, timestamp=T0 + SCAN)
    context = radar_context(with_land)
    stock = StockBernoulli(measurement_model=MEASUREMENT, detection_probability=0.4)
    ours = BernoulliParticleUpdater(measurement_model=MEASUREMENT, detection_probability=0.4)
    log_pd = ours.get_log_detection_probability(prediction, context)
    assert log_pd.shape == (n_particles,) and np.isfinite(log_pd).any() and np.isneginf(log_pd).any()
    assert log_pd.tobytes() == old_particle_log_pd(context, prediction).tobytes()
    assert log_pd.tobytes() == context.prob_detection_particles(particles, log=True).tobytes()
    times = median_times({
        "old_path": lambda: old_particle_log_pd(context, prediction),
        "new_call": lambda: context.prob_detection_particles(particles, log=True),
        "updater": lambda: ours.get_log_detection_probability(prediction, context),
        "stock": lambda: stock.get_log_detection_probability(prediction),
    }, repeats)
    name = "particle_log_pd" + ("_land_sight" if with_land else "") + ("_fortran" if order == "F" else "")
    return {"benchmark": name, "particles": n_particles, "order": order,
            "ms_per_scan": {k: v * 1e3 for k, v in times.items()},
            "ns_per_particle": {k: v / n_particles * 1e9 for k, v in times.items()},
            "ratio_old_over_new": times["old_path"] / times["new_call"]}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--json", metavar="PATH")
    parser.add_argument("--components", type=int, default=50)
    parser.add_argument("--detections", type=int, default=20)
    parser.add_argument("--particles", type=int, default=100_000)
    args = parser.parse_args(argv)
    repeats = 5 if args.quick else 21
    particles = 10_000 if args.quick else args.particles
    results = {"machine": {"cpu_count": os.cpu_count(), "python": sys.version.split()[0],
                           "numpy": np.__version__, "ctxmodels": ctxmodels.__version__,
                           "repeats": repeats, "quick": args.quick},
               "results": [bench_phd(args.components, args.detections, repeats),
                           bench_particle_pd(particles, repeats, with_land=False),
                           bench_particle_pd(particles, repeats, with_land=False, order="F"),
                           bench_particle_pd(particles, repeats, with_land=True)]}
    print(f"# {os.cpu_count()} cores · {repeats} repeats (median per scan)")
    for r in results["results"]:
        times = "  ".join(f"{k} {v:8.3f} ms" for k, v in r["ms_per_scan"].items())
        size = (f"{r['components']}×{r['detections']}" if "components" in r
                else f"{r['particles']} particles")
        ratio = f"  old/new {r['ratio_old_over_new']:.2f}×" if "ratio_old_over_new" in r else ""
        print(f"{r['benchmark']:34s} {size:>18s}  {times}{ratio}")
    if args.json:
        with open(args.json, "w") as f:
            json.dump(results, f, indent=2)
    return 0


if __name__ == "__main__":
    sys.exit(main())
