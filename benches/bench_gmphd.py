"""Per-scan time of the GM-PHD chain: stock Stone Soup 1.9.1 vs ctxmodels' scan core.

One scan = hypothesise (predict + gate) → PHD update → reduce (prune + merge), timed stage by
stage on the same synthetic scan for

* stock: ``GaussianMixtureHypothesiser(DistanceHypothesiser(KalmanPredictor,
  ExtendedKalmanUpdater, Mahalanobis))``, ``PHDUpdater``, ``GaussianMixtureReducer``;
* array: the same scan as :class:`~ctxmodels.stonesoup.ArrayPointProcessTracker` runs it
  (mixture as arrays; predict, update, reduce in the core; "hypothesise" = predict plus the
  detections' ordering and conversion),

at N components × M detections (default 50×20, 200×50, 1000×100) and for two sensors of the
paper's set-up: a lidar-like linear x/y sensor and a radar-like bearing–range sensor
(``CartesianToBearingRange``, extended Kalman). Components are spread over a 3 km square
around the sensor with random covariances and weights; half the detections come from
components, the rest are clutter. Every repeat builds fresh component objects, so Stone
Soup's prediction and measurement-prediction caches never hit across repeats. Medians of the
repeats are reported (the stock chain at the largest size gets fewer repeats).

Run ``python benches/bench_gmphd.py`` (``--help`` for options); prints a table and writes
JSON (``--output``).
"""
from __future__ import annotations

import argparse
import datetime
import json
import platform
import statistics
import sys
import time
from pathlib import Path

import numpy as np
from stonesoup.hypothesiser.distance import DistanceHypothesiser
from stonesoup.hypothesiser.gaussianmixture import GaussianMixtureHypothesiser
from stonesoup.measures import Mahalanobis
from stonesoup.mixturereducer.gaussianmixture import GaussianMixtureReducer
from stonesoup.models.measurement.linear import LinearGaussian
from stonesoup.models.measurement.nonlinear import CartesianToBearingRange
from stonesoup.models.transition.linear import (
    CombinedLinearGaussianTransitionModel,
    ConstantVelocity,
)
from stonesoup.predictor.kalman import KalmanPredictor
from stonesoup.types.angle import Bearing
from stonesoup.types.array import StateVector
from stonesoup.types.detection import Clutter, Detection
from stonesoup.types.state import TaggedWeightedGaussianState
from stonesoup.updater.kalman import ExtendedKalmanUpdater
from stonesoup.updater.pointprocess import PHDUpdater

from ctxmodels import _core
from ctxmodels.stonesoup import ArrayPointProcessTracker

START = datetime.datetime(2024, 1, 1)
SCAN_DT = 1.25  # the radar's period
SIZES = ((50, 20), (200, 50), (1000, 100))
STAGES = ("hypothesise", "update", "reduce", "total")


def _chain():
    transition = CombinedLinearGaussianTransitionModel([ConstantVelocity(0.05)] * 2)
    predictor = KalmanPredictor(transition)
    updater = ExtendedKalmanUpdater(measurement_model=None)
    inner = DistanceHypothesiser(predictor, updater, Mahalanobis(), missed_distance=3)
    return (GaussianMixtureHypothesiser(inner, order_by_detection=True),
            PHDUpdater(updater, clutter_spatial_density=1e-4, prob_detection=0.9,
                       prob_survival=0.99),
            GaussianMixtureReducer(prune_threshold=1e-8, merge_threshold=16))


class Scan:
    """A reproducible scan: N prior components (+ birth) and M detections at one time."""

    def __init__(self, n_components: int, n_detections: int, sensor: str, seed: int):
        rng = np.random.default_rng(seed)
        self.time = START + datetime.timedelta(seconds=SCAN_DT)
        pos = rng.uniform(-1500, 1500, size=(n_components, 2))
        vel = rng.normal(0, 3, size=(n_components, 2))
        self.means = np.column_stack([pos[:, 0], vel[:, 0], pos[:, 1], vel[:, 1]])
        sd = np.column_stack([rng.uniform(3, 20, n_components), rng.uniform(0.5, 3, n_components),
                              rng.uniform(3, 20, n_components), rng.uniform(0.5, 3, n_components)])
        self.covars = np.array([np.diag(s ** 2) for s in sd])
        self.weights = rng.uniform(1e-6, 1.0, n_components)
        # half the detections from components, moved one scan on, the rest clutter
        n_true = min(n_detections // 2, n_components)
        sources = rng.choice(n_components, n_true, replace=False)
        truth = pos[sources] + vel[sources] * SCAN_DT + rng.normal(0, 3, size=(n_true, 2))
        clutter = rng.uniform(-1500, 1500, size=(n_detections - n_true, 2))
        if sensor == "linear":
            model = LinearGaussian(4, (0, 2), np.diag([9.0, 9.0]))
            vectors = [StateVector(p) for p in np.vstack([truth, clutter])]
        elif sensor == "bearing-range":
            model = CartesianToBearingRange(
                4, (0, 2), np.diag([np.radians(1.0) ** 2, 25.0]),
                translation_offset=StateVector([10.0, -20.0]),
                rotation_offset=StateVector([0.0, 0.0, 0.3]))
            rel = np.vstack([truth, clutter]) - np.array([10.0, -20.0])
            vectors = [StateVector([Bearing(np.arctan2(y, x) - 0.3), np.hypot(x, y)])
                       for x, y in rel]
        else:
            raise ValueError(f"sensor: expected 'linear' or 'bearing-range', got {sensor!r}")
        self.detections = {(Detection if i < n_true else Clutter)(
            v, timestamp=self.time, measurement_model=model) for i, v in enumerate(vectors)}

    def components(self):
        """Fresh component objects (no Stone Soup cache hits across repeats)."""
        comps = [TaggedWeightedGaussianState(m.reshape(-1, 1).copy(), c.copy(), weight=w,
                                             tag=f"c{i}", timestamp=START)
                 for i, (m, c, w) in enumerate(zip(self.means, self.covars, self.weights))]
        birth = TaggedWeightedGaussianState(StateVector([0.0, 0.0, 0.0, 0.0]),
                                            np.diag([1500.0, 5.0, 1500.0, 5.0]) ** 2,
                                            weight=0.1, tag="birth", timestamp=self.time)
        return comps + [birth]


def time_chain(chain, scan: Scan) -> dict:
    hypothesiser, updater, reducer = chain
    components = scan.components()
    t0 = time.perf_counter()
    hypotheses = hypothesiser.hypothesise(components, scan.detections, scan.time)
    t1 = time.perf_counter()
    update = updater.update(hypotheses)
    t2 = time.perf_counter()
    reduced = reducer.reduce(update.components)
    t3 = time.perf_counter()
    return {"hypothesise": t1 - t0, "update": t2 - t1, "reduce": t3 - t2, "total": t3 - t0,
            "pairs": sum(len(mh) for mh in hypotheses[:-1]),
            "components_out": len(reduced)}


def time_array(chain, scan: Scan) -> dict:
    """The same scan in the core, as :class:`ArrayPointProcessTracker` runs it: the mixture
    as arrays, F/Q per time step, the detections' vectors and model converted, then
    predict, update and reduce (hypothesise = predict + conversions)."""
    from ctxmodels.stonesoup.gmphd._plan import _Plan
    from ctxmodels.stonesoup.ordering import in_stable_order
    hypothesiser, updater, reducer = chain
    holder = type("Tracker", (), {})()
    holder.hypothesiser, holder.updater, holder.reducer = hypothesiser, updater, reducer
    components = scan.components()
    arrays = _core.GaussianMixtureArrays(4)
    first = arrays.reserve_tags(len(components))
    arrays.extend(np.array([c.state_vector.ravel() for c in components], dtype=float),
                  np.array([c.covar for c in components], dtype=float),
                  np.array([c.weight for c in components], dtype=float),
                  [0 if c.tag == "birth" else first + i for i, c in enumerate(components)],
                  [0 if c.tag != "birth" else int(SCAN_DT * 1e6) for c in components])
    now = int(SCAN_DT * 1e6)
    t0 = time.perf_counter()
    plan = _Plan.of(holder)
    detections = in_stable_order(scan.detections)
    model = detections[0].measurement_model
    scan_model = plan.scan_model(model, 4)
    z = detections.vectors
    times = arrays.distinct_times()
    # F(Δt), Q(Δt) from the tracker's per-step cache, as in a run (warm after one scan)
    matrices = [_TRANSITIONS._transition(plan.predictor, now - t) for t in times]
    arrays.predict(times, now, np.array([f for f, _ in matrices]),
                   np.array([q for _, q in matrices]))
    t1 = time.perf_counter()
    arrays.update(scan_model, z, np.full(len(arrays), plan.prob_detection),
                  np.full(len(z), plan.clutter), prob_survival=plan.prob_survival,
                  missed_distance=plan.missed_distance, squared=plan.squared,
                  include_all=plan.include_all, normalise=plan.normalise,
                  skip_undetectable=False, time=now)
    t2 = time.perf_counter()
    arrays.reduce(**plan.reduce)
    t3 = time.perf_counter()
    return {"hypothesise": t1 - t0, "update": t2 - t1, "reduce": t3 - t2, "total": t3 - t0,
            "pairs": -1, "components_out": len(arrays)}


_TRANSITIONS = ArrayPointProcessTracker(detector=None, hypothesiser=None, updater=None,
                                        reducer=None)

VARIANTS = {"stock": time_chain, "array": time_array}


def measure(n, m, sensor, repeats, repeats_stock, seed):
    scan = Scan(n, m, sensor, seed)
    result = {"components": n, "detections": m, "sensor": sensor}
    for label, timer in VARIANTS.items():
        chain = _chain()
        timer(_chain(), Scan(min(n, 20), min(m, 10), sensor, seed + 1))  # warm-up
        runs = [timer(chain, scan) for _ in range(repeats_stock if label == "stock" else repeats)]
        result[label] = {stage: statistics.median(r[stage] for r in runs) for stage in STAGES}
        result[label]["repeats"] = len(runs)
        result[label]["components_out"] = runs[0]["components_out"]
    result["pairs"] = time_chain(_chain(), scan)["pairs"]
    result["speedup"] = {stage: result["stock"][stage] / result["array"][stage]
                         for stage in STAGES}
    return result


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sizes", nargs="+", default=[f"{n}x{m}" for n, m in SIZES],
                        help="N×M sizes as NxM (default: 50x20 200x50 1000x100)")
    parser.add_argument("--sensors", nargs="+", default=["linear", "bearing-range"],
                        choices=["linear", "bearing-range"])
    parser.add_argument("--repeats", type=int, default=7, help="repeats per size (median)")
    parser.add_argument("--stock-repeats-large", type=int, default=2,
                        help="stock repeats for sizes with N×M ≥ 50000 (slow)")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--output", default="bench_gmphd.json", help="JSON file to write")
    args = parser.parse_args(argv)

    sizes = []
    for text in args.sizes:
        try:
            n, m = (int(v) for v in text.lower().split("x"))
        except ValueError:
            parser.error(f"--sizes: expected NxM, got {text!r}")
        if n < 1 or m < 0:
            parser.error(f"--sizes: need N ≥ 1 and M ≥ 0, got {text!r}")
        sizes.append((n, m))
    if args.repeats < 1 or args.stock_repeats_large < 1:
        parser.error("--repeats and --stock-repeats-large must be ≥ 1")

    results = []
    header = (f"{'sensor':<14}{'N×M':>10}{'pairs':>7}  " + "".join(
        f"{stage + ' ms stock/array (×)':>33}" for stage in STAGES))
    print(header)
    print("-" * len(header))
    for sensor in args.sensors:
        for n, m in sizes:
            stock_repeats = args.stock_repeats_large if n * m >= 50_000 else args.repeats
            r = measure(n, m, sensor, args.repeats, stock_repeats, args.seed)
            results.append(r)
            cells = "".join(
                f"{r['stock'][s] * 1e3:>12.2f} /{r['array'][s] * 1e3:>8.3f} ({r['speedup'][s]:>6.0f}×)"
                for s in STAGES)
            print(f"{sensor:<14}{f'{n}×{m}':>10}{r['pairs']:>7}  {cells}", flush=True)

    payload = {
        "benchmark": "GM-PHD per-scan time, stock Stone Soup vs the ctxmodels scan core",
        "python": sys.version.split()[0],
        "numpy": np.__version__,
        "machine": platform.machine(),
        "processor": platform.processor(),
        "repeats": args.repeats,
        "stock_repeats_large": args.stock_repeats_large,
        "results": results,
    }
    Path(args.output).write_text(json.dumps(payload, indent=2))
    print(f"\nwrote {args.output}")
    return payload


if __name__ == "__main__":
    main()
