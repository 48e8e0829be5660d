"""Soak: stream many cheap scans through a context-aware GM-PHD tracker and check that
memory does not grow per scan after warm-up.

Per scan: a ContextFeeder builds the scan's DetectorContext from a NavigationTrack pose
(mounted sensor), the tracker (the component path, PointProcessMultiTargetTracker, and the
array path, ArrayPointProcessTracker) predicts its mixture and evaluates P_D over it
through the Rust core, and the scan's λ is evaluated for a few
positions. The mixture is held at a fixed size (components in the radar's blind sector:
P_D 0, weights kept, survival 1; none above the extraction threshold, so no track history
accumulates), so any steady growth of the process's memory is a leak.

Memory is the resident set size from /proc/self/status (it sees the Rust allocator too,
which tracemalloc does not), sampled every `every` scans; the assertion is on the
least-squares slope in bytes per scan after warm-up. Short version in the default run; the
≥ 10⁵-scan soak is ``python -m pytest -m slow tests/stonesoup/gmphd/test_memory.py -s``.
"""
import datetime
import gc
import math

import numpy as np
import pytest
from stonesoup.hypothesiser.distance import DistanceHypothesiser
from stonesoup.hypothesiser.gaussianmixture import GaussianMixtureHypothesiser
from stonesoup.measures import Mahalanobis
from stonesoup.mixturereducer.gaussianmixture import GaussianMixtureReducer
from stonesoup.models.measurement.linear import LinearGaussian
from stonesoup.models.transition.linear import (CombinedLinearGaussianTransitionModel,
                                                ConstantVelocity)
from stonesoup.predictor.kalman import KalmanPredictor
from stonesoup.types.mixture import GaussianMixture
from stonesoup.types.state import TaggedWeightedGaussianState
from stonesoup.updater.kalman import KalmanUpdater

from ctxmodels import (AngularSector, ClutterDensityModel, DetectionProbabilityModel, Mounting,
                       NavigationTrack, RangeBands, SensorModel)
from ctxmodels.stonesoup import (ArrayPointProcessTracker, ContextFeeder, PHDUpdater,
                                 PointProcessMultiTargetTracker)

TRACKERS = [PointProcessMultiTargetTracker, ArrayPointProcessTracker]

T0 = datetime.datetime(2024, 5, 1, 12, 0, 0)
PERIOD = datetime.timedelta(seconds=0.1)
MEASUREMENT = LinearGaussian(ndim_state=4, mapping=(0, 2), noise_covar=np.diag([4.0, 4.0]))
# Zero process noise: the parked components stay exactly where they are.
TRANSITION = CombinedLinearGaussianTransitionModel([ConstantVelocity(0.0), ConstantVelocity(0.0)])
RADAR = SensorModel(
    detection=DetectionProbabilityModel(factors=[
        RangeBands(edges=(50, 1612), values=(0, 0.4, 0), upper_owns=(False, True)),
        AngularSector.blind(math.pi, math.radians(65))]),
    clutter=ClutterDensityModel(factors=[RangeBands(edges=(1000,), values=(1e-4, 1e-3))]),
    mounting=Mounting(forward=2.0, left=0.0, yaw=0.0), pd_evaluation="cubature")
POSITIONS = np.array([[100.0, 0.0], [-500.0, 20.0], [1500.0, -3.0]])


def rss_bytes() -> int:
    with open("/proc/self/status") as status:
        for line in status:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) * 1024
    raise RuntimeError("no VmRSS in /proc/self/status")


def empty_scans(n):
    for k in range(n):
        yield T0 + k * PERIOD, set()


def soak(scans, every, tracker_class):
    """Runs the tracker over `scans` empty scans; returns (scan index, RSS) samples."""
    navigation = NavigationTrack(timestamps=[T0, T0 + scans * PERIOD],
                                 positions=[[0.0, 0.0], [0.0, 0.0]], headings=[0.0, 0.0])
    updater = KalmanUpdater(MEASUREMENT)
    tracker = tracker_class(
        detector=ContextFeeder(empty_scans(scans), sensor_model=RADAR, pose_source=navigation),
        hypothesiser=GaussianMixtureHypothesiser(
            DistanceHypothesiser(KalmanPredictor(TRANSITION), updater, Mahalanobis(),
                                 missed_distance=3), order_by_detection=True),
        updater=PHDUpdater(updater, prob_survival=1.0),
        reducer=GaussianMixtureReducer(prune_threshold=1e-9, merging=False),
        extraction_threshold=0.9)
    # Astern of the sensor (heading 0), inside the 65° blind sector: P_D 0 (also under the
    # cubature rule: no velocity variance, so the position spread stays 10 m²), weights kept.
    tracker.gaussian_mixture = GaussianMixture([TaggedWeightedGaussianState(
        np.array([[-300.0 - 40 * i], [0.0], [5.0 * i - 10], [0.0]]), np.diag([10.0, 0.0, 10.0, 0.0]),
        weight=0.5, timestamp=T0, tag=f"c{i}") for i in range(5)])
    samples = []
    lam_total = 0.0
    # The feeder drives update_tracker directly (iterating the tracker would restart its
    # mixture); this is the stock tracker's loop body.
    for k, (time, detections) in enumerate(tracker.detector):
        tracker.update_tracker(time, detections)
        assert not tracker.tracks
        context = detections.detector_context
        lam_total += float(context.clutter_spatial_density_array(POSITIONS).sum())
        if k % every == 0:
            gc.collect()
            samples.append((k, rss_bytes()))
    assert k == scans - 1
    assert len(tracker.gaussian_mixture) == 5
    assert all(float(c.weight) == 0.5 for c in tracker.gaussian_mixture)
    assert lam_total == pytest.approx(scans * (1e-4 + 1e-4 + 1e-3))
    return samples


def growth_per_scan(samples, warm_up):
    """Least-squares slope of RSS (bytes) against scan index, after `warm_up` scans."""
    k, rss = np.array([s for s in samples if s[0] >= warm_up], dtype=float).T
    return float(np.polyfit(k, rss, 1)[0])


@pytest.mark.parametrize("tracker_class", TRACKERS, ids=lambda c: c.__name__)
def test_short_soak_memory_is_flat(tracker_class):
    samples = soak(scans=1500, every=50, tracker_class=tracker_class)
    slope = growth_per_scan(samples, warm_up=500)
    # A leak of one small object per scan (a context, a 5-row array) is ≥ 100 B/scan.
    assert slope < 50.0, (slope, samples)


@pytest.mark.slow
@pytest.mark.parametrize("tracker_class", TRACKERS, ids=lambda c: c.__name__)
def test_long_soak_memory_is_flat(tracker_class):
    scans = 100_000
    samples = soak(scans=scans, every=2000, tracker_class=tracker_class)
    slope = growth_per_scan(samples, warm_up=10_000)
    print(f"\nsoak ({tracker_class.__name__}): {scans} scans, RSS {samples[0][1] / 2**20:.1f} MiB at scan 0, "
          f"{samples[-1][1] / 2**20:.1f} MiB at scan {samples[-1][0]}, "
          f"slope after warm-up {slope:.3f} B/scan")
    assert slope < 5.0, (slope, samples)
