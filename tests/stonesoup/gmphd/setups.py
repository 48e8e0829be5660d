"""GM-PHD set-ups shared by the conformance tests: the Stone Soup GM-PHD tutorial (linear)
and an asynchronous radar (bearing–range, extended Kalman, one model per scan) + lidar
(linear) scenario, with or without per-scan contexts; and the comparison helpers."""
import datetime
import math
import random
import uuid
from contextlib import contextmanager

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
from stonesoup.updater.kalman import ExtendedKalmanUpdater, KalmanUpdater
from stonesoup.updater.pointprocess import PHDUpdater as StockPHDUpdater

from ctxmodels import (
    AngularSector,
    ClutterDensityModel,
    DetectionProbabilityModel,
    DetectionSet,
    MetadataThreshold,
    RangeBands,
    SensorModel,
)
from ctxmodels.stonesoup import AnalyticCartesianToBearingRange, PHDUpdater
from stonesoup.types.mixture import GaussianMixture
from stonesoup.types.detection import TrueDetection
import ctxmodels

START = datetime.datetime(2024, 1, 1)
RTOL = 1e-9


@contextmanager
def seeded_uuids(seed=0):
    """Deterministic uuid4 tags (Stone Soup calls ``uuid.uuid4`` at call time)."""
    rng = random.Random(seed)
    original = uuid.uuid4
    uuid.uuid4 = lambda: uuid.UUID(int=rng.getrandbits(128), version=4)
    try:
        yield
    finally:
        uuid.uuid4 = original


def relative_difference(a, b) -> float:
    """max |a − b| / (|b| + s), s the largest magnitude in the array: ``≤ 1e-9`` is
    ``numpy.allclose(a, b, rtol=1e-9, atol=1e-9·s)``. Entries far below the array's scale
    (a covariance's cross terms, which the Kalman update forms by cancellation) are
    compared on that scale."""
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    assert a.shape == b.shape, (a.shape, b.shape)
    scale = max(np.abs(a).max(initial=0.0), np.abs(b).max(initial=0.0))
    if scale == 0:
        return 0.0
    return float(np.max(np.abs(a - b) / (np.abs(b) + scale)))


def state_difference(a, b) -> float:
    """The largest relative difference of two states' weight, mean and covariance."""
    assert a.timestamp == b.timestamp, (a.timestamp, b.timestamp)
    return max(relative_difference(float(a.weight), float(b.weight)),
               relative_difference(a.state_vector, b.state_vector),
               relative_difference(a.covar, b.covar))


def tracks_difference(expected, got, where="") -> float:
    """Tracks in creation order, pairwise: same number, same lengths and timestamps; returns
    the largest relative difference of their states."""
    expected, got = list(expected), list(got)
    assert len(expected) == len(got), f"{where}: {len(expected)} vs {len(got)} tracks"
    worst = 0.0
    for a, b in zip(expected, got):
        assert len(a) == len(b), f"{where}: track lengths {len(a)} vs {len(b)}"
        for sa, sb in zip(a.states, b.states):
            worst = max(worst, state_difference(sa, sb))
    return worst


def lockstep(reference, tracker, compare_mixtures=False, explained=None):
    """Runs both trackers scan by scan; after each, the same tracks (creation order) to
    within the returned worst relative difference; with ``compare_mixtures`` also the same
    mixture (components in order, tags matched one to one). Where the reference reports
    its detections' clutter probabilities, the array tracker reports the same (to the
    worst difference); ``explained`` (a list) collects those below 1."""
    worst, scans = 0.0, 0
    tag_map: dict = {}
    # (a LearningTracker is iterated as itself, its learners run; its tracker is compared)
    inner = lambda t: getattr(t, "tracker", t)  # noqa: E731
    for (t1, _), (t2, _) in zip(reference, tracker):
        assert t1 == t2
        scans += 1
        worst = max(worst, tracks_difference(inner(reference).target_tracks.values(),
                                             inner(tracker).target_tracks.values(), f"scan {scans}"))
        expected = inner(reference).clutter_probabilities
        if expected is not None:
            got = inner(tracker).clutter_probabilities
            assert got[0] == expected[0] == t1 and got[1].keys() == expected[1].keys()
            a = np.array(list(expected[1].values()))
            b = np.array([got[1][d] for d in expected[1]])
            worst = max(worst, float(np.max(np.abs(a - b), initial=0.0)))
            if explained is not None:
                explained.extend(a[a < 1])
        if compare_mixtures:
            expected = reference.gaussian_mixture.components
            got = tracker.gaussian_mixture.components
            assert len(expected) == len(got), f"scan {scans}: mixture sizes"
            for a, b in zip(expected, got):
                assert tag_map.setdefault(a.tag, b.tag) == b.tag, f"scan {scans}: tags"
                worst = max(worst, state_difference(a, b))
    assert scans > 0
    assert sum(1 for _ in tracker) == 0, "the array tracker has scans left over"
    return worst


def cv_model(q):
    return CombinedLinearGaussianTransitionModel([ConstantVelocity(q), ConstantVelocity(q)])


def tutorial_scenario(n_scans=20, seed=3):
    """The Stone Soup GM-PHD tutorial set-up: CV targets, linear x/y measurements with
    P_D 0.9, uniform clutter, a Kalman updater."""
    rng = np.random.default_rng(seed)
    model = LinearGaussian(4, (0, 2), np.diag([0.75, 0.75]))
    truths = [np.array([-30.0, 1.0, 10.0, -0.5]), np.array([20.0, -0.8, -25.0, 1.0]),
              np.array([5.0, 0.2, 30.0, -1.2])]
    scans = []
    for k in range(n_scans):
        t = START + datetime.timedelta(seconds=k)
        detections = set()
        for x in truths:
            pos = np.array([x[0] + x[1] * k, x[2] + x[3] * k])
            if rng.random() < 0.9:
                detections.add(Detection(StateVector(pos + rng.normal(0, math.sqrt(0.75), 2)),
                                         timestamp=t, measurement_model=model))
        for _ in range(rng.poisson(3)):
            detections.add(Clutter(StateVector(rng.uniform(-60, 60, 2)), timestamp=t,
                                   measurement_model=model))
        scans.append((t, detections))
    return dict(name="tutorial", scans=scans, transition=cv_model(0.3), kalman=KalmanUpdater,
                birth=(np.zeros(4), np.diag([1000.0, 2.0, 1000.0, 2.0]), 0.25),
                missed_distance=3, merge_threshold=200, clutter=1e-3, pd=0.9)


def radar_lidar_scenario(n_scans=26, seed=1, analytic=True):
    """A 0.8 Hz bearing–range radar (a new model per scan: the platform moves and turns)
    and a linear x/y lidar every 0.9 s, asynchronous. One target sits almost astern, so
    bearings straddle ±π and the angle wrapping matters. ``analytic``: the radar model has
    the closed-form Jacobian, else Stone Soup's finite difference."""
    rng = np.random.default_rng(seed)
    radar_model = AnalyticCartesianToBearingRange if analytic else CartesianToBearingRange
    truths = [np.array([300.0, -2.0, 200.0, 1.0]), np.array([-400.0, 3.0, -100.0, 0.5]),
              np.array([30.0, 0.5, -20.0, -0.3]), np.array([-600.0, 0.0, -3.0, 0.0])]
    lidar = LinearGaussian(4, (0, 2), np.diag([0.25, 0.25]))
    times = sorted([(k * 1.25, "radar") for k in range(n_scans)]
                   + [(0.043 + k * 0.9, "lidar") for k in range(n_scans)])[:n_scans]
    scans = []
    for t, sensor in times:
        ts = START + datetime.timedelta(seconds=t)
        positions = [np.array([x[0] + x[1] * t, x[2] + x[3] * t]) for x in truths]
        detections = set()
        if sensor == "radar":
            ego, heading = np.array([5.0 + 0.1 * t, -3.0]), 0.02 + 0.01 * t
            model = radar_model(
                4, (0, 2), np.diag([math.radians(1.0) ** 2, 25.0]),
                translation_offset=StateVector(ego), rotation_offset=StateVector([0, 0, heading]))
            for p in positions:
                if rng.random() < 0.85:
                    d = p - ego
                    bearing = math.atan2(d[1], d[0]) - heading + rng.normal() * math.radians(1)
                    detections.add(Detection(
                        StateVector([Bearing(bearing), math.hypot(*d) + rng.normal() * 5]),
                        timestamp=ts, measurement_model=model))
            for _ in range(rng.poisson(5)):
                detections.add(Clutter(StateVector([Bearing(rng.uniform(-math.pi, math.pi)),
                                                    rng.uniform(50, 1500)]),
                                       timestamp=ts, measurement_model=model))
        else:
            for p in positions:
                if np.hypot(*p) < 80 and rng.random() < 0.9:
                    detections.add(Detection(StateVector(p + rng.normal(0, 0.5, 2)),
                                             timestamp=ts, measurement_model=lidar,
                                             metadata={"area": 20.0}))
            for _ in range(rng.poisson(3)):
                detections.add(Clutter(StateVector(rng.uniform(-80, 80, 2)), timestamp=ts,
                                       measurement_model=lidar,
                                       metadata={"area": float(rng.uniform(1, 12))}))
        scans.append((ts, detections))
    return dict(name="radar-lidar", scans=scans, transition=cv_model(0.05),
                kalman=ExtendedKalmanUpdater,
                birth=(np.zeros(4), np.diag([500.0, 5.0, 500.0, 5.0]) ** 2, 0.25),
                missed_distance=5, merge_threshold=50, clutter=1e-5, pd=0.6)


def sensor_models(pd_evaluation="mean"):
    radar = SensorModel(
        detection=DetectionProbabilityModel(factors=[
            RangeBands(edges=(50.0, 1612.0), values=(0.0, 0.4, 0.0), upper_owns=(False, True)),
            AngularSector.blind(math.pi, math.radians(65.0))]),
        clutter=ClutterDensityModel(factors=[RangeBands(edges=(1000.0,), values=(1e-3, 1e-2))]),
        pd_evaluation=pd_evaluation)
    lidar = SensorModel(
        detection=DetectionProbabilityModel(factors=[
            RangeBands(edges=(50.0, 80.0), values=(0.95, 0.2, 0.0))]),
        clutter=ClutterDensityModel(factors=[MetadataThreshold(
            key="area", threshold=10.0, below=1e-1, at_or_above=1e-3, missing=1e-3)]),
        pd_evaluation=pd_evaluation)
    return radar, lidar


def with_contexts(scans, pd_evaluation="mean"):
    """Each scan as a DetectionSet carrying its sensor's context (pose from the radar
    model's offsets; the lidar at the origin)."""
    radar, lidar = sensor_models(pd_evaluation)
    out = []
    for t, detections in scans:
        models = {d.measurement_model for d in detections}
        model = next(iter(models)) if models else None
        if isinstance(model, CartesianToBearingRange):
            pose = (float(model.translation_offset[0, 0]), float(model.translation_offset[1, 0]),
                    float(model.rotation_offset[2, 0]))
            context = radar.context(pose, t)
        else:
            context = lidar.context((0.0, 0.0, 0.0), t)
        out.append((t, DetectionSet(detections, detector_context=context)))
    return out


def stock_components(scenario, context_updater=False, **reducer_options):
    """The stock GM-PHD components of a set-up (the PHD updater: stock, or ctxmodels' with
    contexts)."""
    kalman = scenario["kalman"](measurement_model=None)
    predictor = KalmanPredictor(scenario["transition"])
    hypothesiser = GaussianMixtureHypothesiser(
        DistanceHypothesiser(predictor, kalman, Mahalanobis(),
                             missed_distance=scenario["missed_distance"]),
        order_by_detection=True)
    updater = (PHDUpdater if context_updater else StockPHDUpdater)(
        kalman, clutter_spatial_density=scenario["clutter"], prob_detection=scenario["pd"],
        prob_survival=0.99)
    reducer = GaussianMixtureReducer(
        **dict(dict(prune_threshold=1e-8, merge_threshold=scenario["merge_threshold"]),
               **reducer_options))
    return dict(hypothesiser=hypothesiser, updater=updater, reducer=reducer)


def birth_component(scenario):
    mean, covar, weight = scenario["birth"]
    return TaggedWeightedGaussianState(StateVector(mean), covar, weight=weight, tag="birth",
                                       timestamp=START)


T0 = datetime.datetime(2024, 1, 1)
SECOND = datetime.timedelta(seconds=1)
ORIGIN = (0.0, 0.0, 0.0)


def constant_context(prob_detection, clutter, timestamp=None):
    """A context whose P_D and λ are the constants of a stock component."""
    model = ctxmodels.SensorModel(
        detection=ctxmodels.DetectionProbabilityModel(factors=[prob_detection]),
        clutter=ctxmodels.ClutterDensityModel(factors=[clutter]))
    return model.context(ORIGIN, timestamp)


PROB_DETECTION = 0.9
CLUTTER_RATE = 3.0
CLUTTER_DENSITY = CLUTTER_RATE / 400.0 ** 2
MEASUREMENT_MODEL = LinearGaussian(ndim_state=4, mapping=(0, 2), noise_covar=np.eye(2) * 0.75)
TRANSITION_MODEL = CombinedLinearGaussianTransitionModel([ConstantVelocity(0.3)] * 2)


def tutorial_scans(steps=12, seed=11):
    rng = np.random.default_rng(seed)
    starts = [np.array([x, vx, y, vy]) for x, y, vx, vy in
              zip(rng.uniform(-30, 30, 3), rng.uniform(-30, 30, 3),
                  rng.uniform(-1, 1, 3), rng.uniform(-1, 1, 3))]
    states = [s.copy() for s in starts]
    scans = []
    for k in range(steps):
        timestamp = T0 + k * SECOND
        detections = set()
        for i, state in enumerate(states):
            if k:
                states[i] = TRANSITION_MODEL.function(
                    _state(state), noise=rng.normal(size=(4, 1)) * 0.3, time_interval=SECOND
                ).ravel()
            if rng.random() < PROB_DETECTION:
                z = MEASUREMENT_MODEL.matrix() @ states[i] + rng.normal(0, np.sqrt(0.75), 2)
                detections.add(TrueDetection(z.reshape(-1, 1), timestamp=timestamp,
                                             measurement_model=MEASUREMENT_MODEL,
                                             groundtruth_path=None))
        for _ in range(rng.poisson(CLUTTER_RATE)):
            detections.add(Clutter(rng.uniform(-200, 200, (2, 1)), timestamp=timestamp,
                                   measurement_model=MEASUREMENT_MODEL))
        scans.append((timestamp, detections))
    return starts, scans


def _state(vector):
    from stonesoup.types.state import State
    return State(np.asarray(vector, dtype=float).reshape(-1, 1))


def tutorial_tracker(tracker_cls, updater_cls, starts, **extra):
    kalman_updater = KalmanUpdater(MEASUREMENT_MODEL)
    hypothesiser = GaussianMixtureHypothesiser(
        DistanceHypothesiser(KalmanPredictor(TRANSITION_MODEL), kalman_updater, Mahalanobis(),
                             missed_distance=3),
        order_by_detection=True)
    updater = updater_cls(kalman_updater, clutter_spatial_density=CLUTTER_DENSITY,
                          prob_detection=PROB_DETECTION, prob_survival=1 - 0.005)
    birth = TaggedWeightedGaussianState(
        state_vector=[0, 0, 0, 0], covar=np.diag([1000, 2, 1000, 2]) ** 2, weight=0.25,
        tag=TaggedWeightedGaussianState.BIRTH, timestamp=T0)
    reducer = GaussianMixtureReducer(prune_threshold=1e-8, merge_threshold=5)
    tracker = tracker_cls(detector=None, hypothesiser=hypothesiser, updater=updater,
                          reducer=reducer, birth_component=birth, extraction_threshold=0.25,
                          **extra)
    tracker.gaussian_mixture = GaussianMixture([
        TaggedWeightedGaussianState(start.reshape(-1, 1), np.diag([10, 5, 10, 5]) ** 2,
                                    weight=0.25, timestamp=T0) for start in starts])
    return tracker
