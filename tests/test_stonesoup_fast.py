"""Conformance of the fast GM-PHD drop-ins with stock Stone Soup 1.9.1.

Every fast component is held against the stock component it replaces: alone in an otherwise
stock chain, and as the whole fast chain, scan after scan (mixture: same components in the
same order, same tags, weights/means/covariances to rtol 1e-9; tracks: same ids and states),
on the Stone Soup GM-PHD tutorial set-up and on an asynchronous radar (bearing–range,
extended Kalman, per-scan models) + lidar (linear) scenario. With a detector context the
fast updaters are held against ``ctxmodels.stonesoup.pointprocess``.

Tags are uuid4 strings: the tests seed ``uuid.uuid4`` so two runs draw the same tags. That
is also what makes a stock chain reproducible at all: the stock reducer orders components
sharing a tag by iterating a ``set`` of tag strings, and the extended Kalman filter's
finite-difference Jacobian turns the resulting last-bit differences into 1e-8 ones.
"""
import datetime
import math
import random
import uuid
from contextlib import contextmanager

import numpy as np
import pytest
from scipy.stats import multivariate_normal
from stonesoup.hypothesiser.distance import DistanceHypothesiser
from stonesoup.hypothesiser.gaussianmixture import GaussianMixtureHypothesiser
from stonesoup.measures import Euclidean, Mahalanobis, SquaredMahalanobis
from stonesoup.mixturereducer.gaussianmixture import GaussianMixtureReducer
from stonesoup.models.measurement.linear import LinearGaussian
from stonesoup.models.measurement.nonlinear import CartesianToBearingRange
from stonesoup.models.transition.linear import (
    CombinedLinearGaussianTransitionModel,
    ConstantVelocity,
)
from stonesoup.predictor.kalman import KalmanPredictor, UnscentedKalmanPredictor
from stonesoup.tracker.pointprocess import PointProcessMultiTargetTracker
from stonesoup.types.angle import Bearing
from stonesoup.types.array import CovarianceMatrix, StateVector
from stonesoup.types.detection import Clutter, Detection, MissedDetection
from stonesoup.types.hypothesis import SingleDistanceHypothesis
from stonesoup.types.multihypothesis import MultipleHypothesis
from stonesoup.types.numeric import Probability
from stonesoup.types.prediction import (
    GaussianMeasurementPrediction,
    TaggedWeightedGaussianStatePrediction,
)
from stonesoup.types.state import TaggedWeightedGaussianState, WeightedGaussianState
from stonesoup.types.update import GaussianMixtureUpdate
from stonesoup.updater.kalman import ExtendedKalmanUpdater, KalmanUpdater, UnscentedKalmanUpdater
from stonesoup.updater.pointprocess import LCCUpdater, PHDUpdater

from ctxmodels import (
    AngularSector,
    ClutterDensityModel,
    DetectionProbabilityModel,
    DetectionSet,
    MetadataThreshold,
    RangeBands,
    SensorModel,
)
from ctxmodels.stonesoup import pointprocess
from ctxmodels.stonesoup.fast import (
    FastGaussianMixtureHypothesiser,
    FastGaussianMixtureReducer,
    FastLCCUpdater,
    FastPHDUpdater,
    ObjectFactory,
    gaussian_arrays,
    measurement_batch,
    stock_gaussian_pdf,
)

# Stock runs compared bit for bit with ctxmodels visit shared tags in first-appearance order.
pytestmark = pytest.mark.usefixtures("stock_in_stable_order")

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


def close(a, b):
    """Equal to RTOL, relative to the larger magnitude in the array (entries near zero in
    a covariance or a mean are compared on the array's scale)."""
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    if a.shape != b.shape:
        return False
    scale = max(np.abs(a).max(initial=0.0), np.abs(b).max(initial=0.0))
    return bool(np.allclose(a, b, rtol=RTOL, atol=RTOL * scale))


def assert_same_components(expected, got, where=""):
    assert len(expected) == len(got), f"{where}: {len(expected)} vs {len(got)} components"
    for i, (a, b) in enumerate(zip(expected, got)):
        assert type(a) is type(b), f"{where}[{i}] type"
        assert getattr(a, "tag", None) == getattr(b, "tag", None), f"{where}[{i}] tag"
        assert close(float(a.weight), float(b.weight)), \
            f"{where}[{i}] weight {float(a.weight)!r} vs {float(b.weight)!r}"
        assert close(a.state_vector, b.state_vector), f"{where}[{i}] mean"
        assert close(a.covar, b.covar), f"{where}[{i}] covar"
        assert a.timestamp == b.timestamp, f"{where}[{i}] timestamp"


def assert_same_tracks(expected, got, where=""):
    expected = sorted(expected, key=lambda t: t.id)
    got = sorted(got, key=lambda t: t.id)
    assert [t.id for t in expected] == [t.id for t in got], f"{where}: track ids"
    for a, b in zip(expected, got):
        assert_same_components(list(a.states), list(b.states), f"{where} track {a.id}")


# --- scenarios -----------------------------------------------------------------------------
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


def radar_lidar_scenario(n_scans=26, seed=1):
    """A 0.8 Hz bearing–range radar (a new CartesianToBearingRange per scan: the platform
    moves and turns) and a linear x/y lidar every 0.9 s, asynchronous. One target sits
    almost astern, so bearings straddle ±π and the angle wrapping matters."""
    rng = np.random.default_rng(seed)
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
            model = CartesianToBearingRange(
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


SCENARIOS = {"tutorial": tutorial_scenario(), "radar-lidar": radar_lidar_scenario()}


def build_chain(scenario, fast=(False, False, False), lcc=False, context_updaters=False,
                **updater_kwargs):
    kalman = scenario["kalman"](measurement_model=None,
                                **updater_kwargs.pop("kalman_kwargs", {}))
    predictor = KalmanPredictor(scenario["transition"])
    inner = DistanceHypothesiser(predictor, kalman, Mahalanobis(),
                                 missed_distance=scenario["missed_distance"])
    hypothesiser = (FastGaussianMixtureHypothesiser if fast[0]
                    else GaussianMixtureHypothesiser)(inner, order_by_detection=True)
    kwargs = dict(clutter_spatial_density=scenario["clutter"], prob_detection=scenario["pd"],
                  prob_survival=0.99, **updater_kwargs)
    if lcc:
        stock = pointprocess.LCCUpdater if context_updaters else LCCUpdater
        cls = FastLCCUpdater if fast[1] else stock
        updater = cls(kalman, mean_number_of_false_alarms=5, variance_of_false_alarms=30,
                      **kwargs)
    else:
        stock = pointprocess.PHDUpdater if context_updaters else PHDUpdater
        updater = (FastPHDUpdater if fast[1] else stock)(kalman, **kwargs)
    reducer = (FastGaussianMixtureReducer if fast[2] else GaussianMixtureReducer)(
        prune_threshold=1e-8, merge_threshold=scenario["merge_threshold"])
    return hypothesiser, updater, reducer


def birth_component(scenario):
    mean, covar, weight = scenario["birth"]
    return TaggedWeightedGaussianState(StateVector(mean), covar, weight=weight, tag="birth",
                                       timestamp=START)


def run_tracker(scenario, fast=(False, False, False), lcc=False):
    """(mixture, tracks) after every scan of the stock tracker with these components."""
    hypothesiser, updater, reducer = build_chain(scenario, fast, lcc)
    history = []
    with seeded_uuids(11):
        tracker = PointProcessMultiTargetTracker(
            detector=scenario["scans"], hypothesiser=hypothesiser, updater=updater,
            reducer=reducer, birth_component=birth_component(scenario),
            extraction_threshold=0.5)
        for _, tracks in tracker:
            history.append((list(tracker.gaussian_mixture.components), set(tracks)))
    return history


_REFERENCES = {}


def reference(name, lcc=False):
    key = (name, lcc)
    if key not in _REFERENCES:
        _REFERENCES[key] = run_tracker(SCENARIOS[name], lcc=lcc)
    return _REFERENCES[key]


VARIANTS = {"hypothesiser": (True, False, False), "updater": (False, True, False),
            "reducer": (False, False, True), "chain": (True, True, True)}


# --- whole-pipeline conformance --------------------------------------------------------------
@pytest.mark.parametrize("variant", list(VARIANTS))
@pytest.mark.parametrize("name", list(SCENARIOS))
def test_phd_tracker_matches_stock_after_every_scan(name, variant):
    expected = reference(name)
    got = run_tracker(SCENARIOS[name], VARIANTS[variant])
    assert len(got) == len(expected) == len(SCENARIOS[name]["scans"])
    n_tracks = 0
    for k, ((mix_a, tracks_a), (mix_b, tracks_b)) in enumerate(zip(expected, got)):
        assert_same_components(mix_a, mix_b, f"scan {k}")
        assert_same_tracks(tracks_a, tracks_b, f"scan {k}")
        n_tracks = max(n_tracks, len(tracks_a))
    assert n_tracks >= 2  # the scenario does produce tracks to compare
    assert max(len(m) for m, _ in expected) >= 10


@pytest.mark.parametrize("variant", ["updater", "chain"])
def test_lcc_tracker_matches_stock_after_every_scan(variant):
    expected = reference("radar-lidar", lcc=True)
    got = run_tracker(SCENARIOS["radar-lidar"], VARIANTS[variant], lcc=True)
    for k, ((mix_a, tracks_a), (mix_b, tracks_b)) in enumerate(zip(expected, got)):
        assert_same_components(mix_a, mix_b, f"scan {k}")
        assert_same_tracks(tracks_a, tracks_b, f"scan {k}")


# --- with a detector context: against ctxmodels.stonesoup.pointprocess ------------------------
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


def run_context_tracker(scans, fast, lcc):
    scenario = SCENARIOS["radar-lidar"]
    hypothesiser, updater, reducer = build_chain(scenario, fast, lcc, context_updaters=True)
    history = []
    with seeded_uuids(5):
        tracker = pointprocess.PointProcessMultiTargetTracker(
            detector=scans, hypothesiser=hypothesiser, updater=updater, reducer=reducer,
            birth_component=birth_component(scenario), extraction_threshold=0.5)
        for _, tracks in tracker:
            history.append((list(tracker.gaussian_mixture.components), set(tracks)))
    return history


@pytest.mark.parametrize(("pd_evaluation", "lcc"), [("mean", False), ("mean", True),
                                                    ("cubature", False)],
                         ids=["phd", "lcc", "phd-cubature"])
def test_context_updaters_match_pointprocess(pd_evaluation, lcc):
    scans = with_contexts(SCENARIOS["radar-lidar"]["scans"][:20], pd_evaluation)
    expected = run_context_tracker(scans, (False, False, False), lcc)
    for variant in ("updater", "chain"):
        got = run_context_tracker(scans, VARIANTS[variant], lcc)
        for k, ((mix_a, tracks_a), (mix_b, tracks_b)) in enumerate(zip(expected, got)):
            assert_same_components(mix_a, mix_b, f"{variant} scan {k}")
            assert_same_tracks(tracks_a, tracks_b, f"{variant} scan {k}")
    # the context does change the result (P_D 0 beyond the lidar's 80 m, ...)
    without = reference("radar-lidar", lcc=lcc)
    assert any(len(a) != len(b) for (a, _), (b, _) in zip(expected, without))


def test_context_updater_calls_the_context_once_per_scan():
    scenario = SCENARIOS["radar-lidar"]
    scans = with_contexts(scenario["scans"][:8])
    hypothesiser, updater, reducer = build_chain(scenario, (True, True, True))

    class Counting:
        def __init__(self, context):
            self.context, self.calls = context, {"pd": 0, "clutter": 0}

        def prob_detection_array(self, means, covars=None):
            self.calls["pd"] += 1
            return self.context.prob_detection_array(means, covars)

        def clutter_spatial_density_detections(self, detections):
            self.calls["clutter"] += 1
            return self.context.clutter_spatial_density_detections(detections)

    mixture = []
    with seeded_uuids(2):
        birth = birth_component(scenario)
        for t, detections in scans:
            birth.timestamp = t
            hypotheses = hypothesiser.hypothesise(mixture + [birth], detections, t)
            counting = Counting(detections.detector_context)
            update = updater.update(hypotheses, detector_context=counting)
            gating = any(len(mh) for mh in hypotheses[:-1])
            assert counting.calls == {"pd": 1, "clutter": int(gating)}
            mixture = reducer.reduce(update.components)


def test_context_with_zero_pd_drops_pairs_and_keeps_missed_weight():
    """P_D = 0 everywhere: no detection term survives, missed weights are w·p_S."""
    scenario = SCENARIOS["tutorial"]
    blind = SensorModel(detection=DetectionProbabilityModel(factors=[0.0]),
                        clutter=ClutterDensityModel(factors=[1e-3]))
    hypothesiser, updater, _ = build_chain(scenario, (True, True, True))
    t, detections = scenario["scans"][3]
    prior = [TaggedWeightedGaussianState(StateVector([-27.0, 1.0, 8.5, -0.5]),
                                         np.diag([4.0, 1.0, 4.0, 1.0]), weight=0.8, tag="a",
                                         timestamp=t - datetime.timedelta(seconds=1))]
    hypotheses = hypothesiser.hypothesise(prior, detections, t)
    assert sum(len(mh) for mh in hypotheses[:-1]) >= 1
    update = updater.update(hypotheses, detector_context=blind.context((0.0, 0.0, 0.0), t))
    assert [c.tag for c in update.components] == ["a"]
    assert float(update.components[0].weight) == pytest.approx(0.8 * 0.99, rel=1e-12)


def test_context_errors_name_the_argument():
    scenario = SCENARIOS["tutorial"]
    hypothesiser, updater, _ = build_chain(scenario, (True, True, True))
    t, detections = scenario["scans"][0]
    hypotheses = hypothesiser.hypothesise([birth_component(scenario)], detections, t)
    with pytest.raises(TypeError, match="detector_context"):
        updater.update(hypotheses, detector_context=object())
    context = sensor_models()[1].context((0.0, 0.0, 0.0), t)
    with pytest.raises(ValueError, match="hypotheses"):
        updater.update([], detector_context=context)


# --- the hypothesiser's output, object by object ----------------------------------------------
def prior_mixture(t0, n=12, seed=4):
    rng = np.random.default_rng(seed)
    comps = [TaggedWeightedGaussianState(
        StateVector([rng.uniform(-40, 40), rng.normal(), rng.uniform(-40, 40), rng.normal()]),
        np.diag([rng.uniform(1, 9), 0.5, rng.uniform(1, 9), 0.5]), weight=rng.uniform(0.1, 1),
        tag=f"c{i}", timestamp=t0) for i in range(n)]
    birth = TaggedWeightedGaussianState(StateVector([0.0, 0.0, 0.0, 0.0]),
                                        np.diag([900.0, 4.0, 900.0, 4.0]), weight=0.2,
                                        tag="birth", timestamp=t0 + datetime.timedelta(seconds=1))
    return comps + [birth]


def hypothesisers(measure=None, include_all=False, order_by_detection=True, kalman=None,
                  missed_distance=4, predictor=None):
    predictor = predictor or KalmanPredictor(cv_model(0.3))
    kalman = kalman or ExtendedKalmanUpdater(measurement_model=None)
    inner = DistanceHypothesiser(predictor, kalman, measure or Mahalanobis(),
                                 missed_distance=missed_distance, include_all=include_all)
    return (GaussianMixtureHypothesiser(inner, order_by_detection=order_by_detection),
            FastGaussianMixtureHypothesiser(inner, order_by_detection=order_by_detection))


def assert_same_hypotheses(expected, got):
    assert type(got) is list and len(got) == len(expected)
    for mh_a, mh_b in zip(expected, got):
        assert type(mh_b) is MultipleHypothesis and len(mh_a) == len(mh_b)
        assert type(mh_a.single_hypotheses) is type(mh_b.single_hypotheses)
        for a, b in zip(mh_a, mh_b):
            assert type(a) is type(b) is SingleDistanceHypothesis
            assert type(a.prediction) is type(b.prediction)
            assert a.prediction.tag == b.prediction.tag
            assert a.prediction.weight == b.prediction.weight
            assert a.prediction.timestamp == b.prediction.timestamp
            assert np.array_equal(a.prediction.state_vector, b.prediction.state_vector)
            assert np.array_equal(a.prediction.covar, b.prediction.covar)
            assert a.measurement is b.measurement or (
                type(a.measurement) is type(b.measurement) is MissedDetection
                and a.measurement.timestamp == b.measurement.timestamp)
            assert close(a.distance, b.distance)
            if a.measurement_prediction is None:
                assert b.measurement_prediction is None
            else:
                mp_a, mp_b = a.measurement_prediction, b.measurement_prediction
                assert type(mp_a) is type(mp_b) is GaussianMeasurementPrediction
                assert [type(v) for v in mp_a.state_vector.ravel()] == \
                    [type(v) for v in mp_b.state_vector.ravel()]
                assert close(mp_a.state_vector.astype(float), mp_b.state_vector.astype(float))
                assert np.array_equal(mp_a.covar, mp_b.covar)
                assert np.array_equal(mp_a.cross_covar, mp_b.cross_covar)
                assert mp_a.timestamp == mp_b.timestamp


def scan_detections(t, kind="radar", n=8, seed=5, heading=0.4):
    rng = np.random.default_rng(seed)
    if kind == "lidar":
        model = LinearGaussian(4, (0, 2), np.diag([1.0, 1.0]))
        return {Detection(StateVector(rng.uniform(-40, 40, 2)), timestamp=t,
                          measurement_model=model) for _ in range(n)}
    model = CartesianToBearingRange(4, (0, 2), np.diag([0.02 ** 2, 4.0]),
                                    translation_offset=StateVector([3.0, -2.0]),
                                    rotation_offset=StateVector([0.0, 0.0, heading]))
    return {Detection(StateVector([Bearing(rng.uniform(-math.pi, math.pi)), rng.uniform(5, 60)]),
                      timestamp=t, measurement_model=model) for _ in range(n)}


@pytest.mark.parametrize("kind", ["radar", "lidar"])
@pytest.mark.parametrize("options", [
    {}, {"order_by_detection": False}, {"include_all": True}, {"measure": SquaredMahalanobis()},
    {"missed_distance": 40}])
def test_hypothesiser_objects_match_stock(kind, options):
    t0 = START
    t = t0 + datetime.timedelta(seconds=1)
    components = prior_mixture(t0)
    components.insert(3, components[1])  # a repeated object counts once, as in stock
    detections = scan_detections(t, kind, seed=7)
    # targets near components so that pairs gate
    model = next(iter(detections)).measurement_model
    for c in components[:6]:
        state = c.state_vector + np.array([[c.state_vector[1]], [0], [c.state_vector[3]], [0]])
        z = model.function(TaggedWeightedGaussianState(state, c.covar), noise=False)
        detections.add(Detection(StateVector(z), timestamp=t, measurement_model=model))
    stock, fast = hypothesisers(**options)
    with seeded_uuids(1):
        expected = stock.hypothesise(components, detections, t)
    with seeded_uuids(1):
        got = fast.hypothesise(components, detections, t)
    assert_same_hypotheses(expected, got)
    if not options.get("include_all"):
        assert sum(len(mh) for mh in got[:-1]) >= 6


def test_hypothesiser_edge_cases_match_stock():
    t0 = START
    t = t0 + datetime.timedelta(seconds=1)
    stock, fast = hypothesisers()
    components = prior_mixture(t0)
    for comps, dets in [(components, set()), ([], scan_detections(t)), ([], set())]:
        with seeded_uuids(1):
            expected = stock.hypothesise(comps, dets, t)
        with seeded_uuids(1):
            got = fast.hypothesise(comps, dets, t)
        assert_same_hypotheses(expected, got)
    # detections stamped later than the scan time: predicted to their own time
    later = scan_detections(t + datetime.timedelta(seconds=0.5))
    with seeded_uuids(1):
        expected = stock.hypothesise(components, later, t)
    with seeded_uuids(1):
        got = fast.hypothesise(components, later, t)
    assert_same_hypotheses(expected, got)
    mixed = scan_detections(t) | scan_detections(t + datetime.timedelta(seconds=1))
    with pytest.raises(ValueError, match="same timestamp"):
        fast.hypothesise(components, mixed, t)


@pytest.mark.parametrize("setup", ["euclidean", "unscented-predictor", "unscented-updater",
                                   "kwargs"])
def test_hypothesiser_unsupported_configurations_match_stock(setup):
    """Configurations the batched path does not reproduce run (or partly run) the stock
    code and give the stock result."""
    t = START + datetime.timedelta(seconds=1)
    options, kwargs = {}, {}
    if setup == "euclidean":
        options["measure"] = Euclidean(mapping=(0, 1))
    elif setup == "unscented-predictor":
        options["predictor"] = UnscentedKalmanPredictor(cv_model(0.3))
    elif setup == "unscented-updater":
        options["kalman"] = UnscentedKalmanUpdater(measurement_model=None)
    else:
        kwargs["unused_keyword"] = 1
    stock, fast = hypothesisers(missed_distance=30 if setup == "euclidean" else 4, **options)
    components = prior_mixture(START)
    detections = scan_detections(t, "radar")
    with seeded_uuids(1):
        expected = stock.hypothesise(components, detections, t, **kwargs)
    with seeded_uuids(1):
        got = fast.hypothesise(components, detections, t, **kwargs)
    assert_same_hypotheses(expected, got)


def test_bearing_range_measurement_prediction_is_bitwise_stock():
    """Jacobians by Stone Soup's finite differences, reproduced operation for operation,
    including bearings across ±π and a rotated, offset sensor."""
    rng = np.random.default_rng(0)
    updater = ExtendedKalmanUpdater(measurement_model=None)
    model = CartesianToBearingRange(4, (0, 2), np.diag([1e-4, 4.0]),
                                    translation_offset=StateVector([12.0, -7.0]),
                                    rotation_offset=StateVector([0.0, 0.0, 2.9]))
    means = np.column_stack([rng.uniform(-2000, 2000, 300), rng.normal(0, 5, 300),
                             rng.uniform(-2000, 2000, 300), rng.normal(0, 5, 300)])
    means[:20, 2] = -7.0 + rng.normal(0, 1e-3, 20)  # on the ±π line behind the sensor
    means[:20, 0] = -abs(means[:20, 0])
    covars = np.array([np.diag(rng.uniform(1, 50, 4)) for _ in means])
    batch = measurement_batch(updater, model, means[..., np.newaxis], covars)
    for n, (m, c) in enumerate(zip(means, covars)):
        mp = updater.predict_measurement(
            TaggedWeightedGaussianStatePrediction(StateVector(m), CovarianceMatrix(c),
                                                  weight=1, tag="x"), model)
        assert np.array_equal(model.jacobian(TaggedWeightedGaussianState(StateVector(m), c)),
                              batch.matrices[n])
        assert np.array_equal(np.asarray(mp.covar), batch.covars[n])
        assert np.array_equal(np.asarray(mp.cross_covar), batch.cross_covars[n])
        assert float(mp.state_vector[0, 0]) == batch.means[n, 0]
        assert isinstance(batch.typed_vector(n)[0, 0], Bearing)


def test_gaussian_pdf_is_bitwise_scipy():
    rng = np.random.default_rng(9)
    count = 600
    a = rng.normal(size=(count, 2, 2))
    scales = np.array([np.diag([10 ** rng.uniform(-2, 0), 10 ** rng.uniform(0, 2)])
                       for _ in range(count)])
    covars = scales @ (a @ a.transpose(0, 2, 1) + np.eye(2)) @ scales
    covars[:, 0, 1] += rng.normal(size=count) * 1e-17  # as computed covariances are
    x = rng.normal(size=(count, 2)) * 3
    mu = rng.normal(size=(count, 2))
    keys = [k // 3 for k in range(count)]
    covars[1::3] = covars[0::3]  # rows sharing a key share a covariance
    covars[2::3] = covars[0::3]
    for given_keys in (None, keys):
        got = stock_gaussian_pdf(x, mu, covars, given_keys)
        expected = [multivariate_normal.pdf(x[k], mean=mu[k], cov=covars[k]) for k in range(count)]
        assert got.tolist() == expected
    with pytest.raises(np.linalg.LinAlgError):
        stock_gaussian_pdf(x[:1], mu[:1], np.zeros((1, 2, 2)) + np.eye(2) * [1.0, 0.0])


# --- the updater's options -------------------------------------------------------------------
@pytest.mark.parametrize("kalman_kwargs", [
    {}, {"use_joseph_cov": True}, {"force_symmetric_covariance": True}])
@pytest.mark.parametrize("name", list(SCENARIOS))
def test_updater_options_match_stock(name, kalman_kwargs):
    scenario = SCENARIOS[name]
    for normalisation in (True, False):
        stock = build_chain(scenario, kalman_kwargs=dict(kalman_kwargs),
                            normalisation=normalisation)
        fast = build_chain(scenario, (False, True, False), kalman_kwargs=dict(kalman_kwargs),
                           normalisation=normalisation)
        mixture = []
        with seeded_uuids(4):
            birth = birth_component(scenario)
            for k, (t, detections) in enumerate(scenario["scans"][:10]):
                birth.timestamp = t
                hypotheses = stock[0].hypothesise(mixture + [birth], detections, t)
                a = stock[1].update(hypotheses)
                b = fast[1].update(hypotheses)
                assert type(b) is GaussianMixtureUpdate and b.hypothesis is hypotheses
                assert_same_components(a.components, b.components, f"scan {k}")
                mixture = stock[2].reduce(a.components)


def test_updater_with_another_kalman_updater_matches_stock():
    """An unscented single-target updater: called pair by pair, weights still batched."""
    scenario = SCENARIOS["radar-lidar"]
    kalman = UnscentedKalmanUpdater(measurement_model=None)
    hypothesiser, _, reducer = build_chain(scenario, (True, False, True))
    stock = PHDUpdater(kalman, clutter_spatial_density=1e-5, prob_detection=0.8)
    fast = FastPHDUpdater(kalman, clutter_spatial_density=1e-5, prob_detection=0.8)
    mixture = []
    with seeded_uuids(4):
        birth = birth_component(scenario)
        for k, (t, detections) in enumerate(scenario["scans"][:8]):
            birth.timestamp = t
            hypotheses = hypothesiser.hypothesise(mixture + [birth], detections, t)
            a, b = stock.update(hypotheses), fast.update(hypotheses)
            assert_same_components(a.components, b.components, f"scan {k}")
            mixture = reducer.reduce(a.components)


def test_updater_without_hypotheses_fails_as_stock():
    updater = FastPHDUpdater(KalmanUpdater(measurement_model=None))
    with pytest.raises(IndexError):
        PHDUpdater(KalmanUpdater(measurement_model=None)).update([])
    with pytest.raises(IndexError):
        updater.update([])


# --- the reducer -----------------------------------------------------------------------------
def random_mixture(n, seed, tagged=True, probability_weights=False, duplicate_tags=False):
    rng = np.random.default_rng(seed)
    centres = rng.uniform(-50, 50, size=(max(n // 4, 1), 4))
    comps = []
    for i in range(n):
        mean = centres[rng.integers(len(centres))] + rng.normal(0, 2, 4)
        a = rng.normal(size=(4, 4))
        covar = a @ a.T + np.diag(rng.uniform(0.5, 8, 4))
        weight = float(10 ** rng.uniform(-11, 0.2))
        if probability_weights:
            weight = Probability(weight)
        if tagged:
            tag = f"t{i % (n // 3)}" if duplicate_tags else f"t{i}"
            comps.append(TaggedWeightedGaussianState(StateVector(mean), covar, weight=weight,
                                                     tag=tag, timestamp=START))
        else:
            comps.append(WeightedGaussianState(StateVector(mean), covar, weight=weight,
                                               timestamp=START))
    comps[5].weight = comps[4].weight  # a tie in weight
    return comps


def copies(components):
    return [type(c)(**{name: getattr(c, name) for name in type(c).properties})
            for c in components]


@pytest.mark.parametrize("options", [
    {}, {"merge_threshold": 40}, {"max_number_components": 9},
    {"pruning": False, "merge_threshold": 5}, {"merging": False, "max_number_components": 20},
    {"prune_threshold": 1e-3}])
@pytest.mark.parametrize("kind", ["tagged", "duplicate-tags", "untagged", "probability"])
def test_reducer_matches_stock(kind, options):
    for seed in range(3):
        components = random_mixture(
            60, seed, tagged=kind != "untagged", probability_weights=kind == "probability",
            duplicate_tags=kind == "duplicate-tags")
        a_in, b_in = copies(components), copies(components)
        with seeded_uuids(seed):
            expected = GaussianMixtureReducer(**options).reduce(a_in)
        with seeded_uuids(seed):
            got = FastGaussianMixtureReducer(**options).reduce(b_in)
        assert_same_components(expected, got, f"seed {seed}")
        # components the reducer kept unmerged are the input objects, weights updated in place
        kept_a = [i for i, c in enumerate(a_in) if any(c is e for e in expected)]
        kept_b = [i for i, c in enumerate(b_in) if any(c is g for g in got)]
        assert kept_a == kept_b
        assert [float(c.weight) for c in a_in] == pytest.approx(
            [float(c.weight) for c in b_in], rel=RTOL)
    assert len(expected) < len(components) or not options.get("merging", True)


def kdtree_gated_merge(components, merge_threshold, max_distance):
    """Reference for the k-d-tree gate, in the stable order: the stock greedy merge (heaviest
    first, the rest visited in increasing weight, ties in input order) restricted to the
    components within ``max_distance`` (Euclidean, full state) of the heaviest's *initial*
    mean, as the stock's ball query finds them. Stock visits those candidates in the order
    of a ``set`` of components (memory addresses), which no two processes share."""
    stock = GaussianMixtureReducer(merge_threshold=merge_threshold)
    measure = SquaredMahalanobis(state_covar_inv_cache_size=None)
    remaining = sorted(components, key=lambda c: c.weight)
    merged = []
    while remaining:
        best = remaining.pop()
        centre = best.state_vector.ravel().copy()
        for component in list(remaining):
            if np.linalg.norm(component.state_vector.ravel() - centre) > max_distance:
                continue
            if measure(state1=component, state2=best) < merge_threshold:
                remaining.remove(component)
                best = stock.merge_components(best, component)
        merged.append(best)
    return merged


@pytest.mark.parametrize("kind", ["tagged", "untagged", "probability"])
def test_reducer_kdtree_gate_merges_candidates_in_weight_order(kind):
    for seed in range(3):
        components = random_mixture(60, seed, tagged=kind != "untagged",
                                    probability_weights=kind == "probability")
        # a gate that excludes no one: exactly the stock reducer without a gate
        wide = FastGaussianMixtureReducer(kdtree_max_distance=1e9, merge_threshold=40,
                                          pruning=False).reduce(list(components))
        assert_same_components(GaussianMixtureReducer(merge_threshold=40, pruning=False)
                               .reduce(list(components)), wide, f"seed {seed}, wide gate")
        # a gate that does exclude: the reference above
        got = FastGaussianMixtureReducer(kdtree_max_distance=5, merge_threshold=40,
                                         pruning=False).reduce(list(components))
        assert_same_components(kdtree_gated_merge(components, 40, 5), got, f"seed {seed}")
        assert len(got) < len(components) and len(got) != len(wide)


def test_reducer_merges_near_the_threshold_exactly():
    """Pairs whose distance sits within rounding of the threshold: the prefilter must not
    drop any pair the exact distance merges."""
    rng = np.random.default_rng(3)
    components = []
    for i in range(80):
        covar = np.diag(rng.uniform(1, 4, 4))
        components.append(TaggedWeightedGaussianState(
            StateVector(rng.normal(0, 1e3, 4)), covar, weight=rng.uniform(0.01, 0.2),
            tag=f"a{i}", timestamp=START))
        # a lighter twin at squared Mahalanobis distance 16·(1 ± 1e-12) from it
        direction = rng.normal(size=4)
        inverse = np.linalg.pinv(covar)
        direction *= math.sqrt(16.0 / (direction @ inverse @ direction)) * (1 + rng.choice(
            [-1e-12, 1e-12]))
        components.append(TaggedWeightedGaussianState(
            components[-1].state_vector + direction[:, np.newaxis], covar,
            weight=float(components[-1].weight) / 2, tag=f"b{i}", timestamp=START))
    expected = GaussianMixtureReducer(merge_threshold=16).reduce(copies(components))
    got = FastGaussianMixtureReducer(merge_threshold=16).reduce(copies(components))
    assert_same_components(expected, got)
    assert 80 < len(got) < 160


# --- plumbing ------------------------------------------------------------------------------------
def test_object_factory_matches_constructor_and_falls_back():
    factory = ObjectFactory(TaggedWeightedGaussianState, dict(
        state_vector=StateVector([0.0]), covar=CovarianceMatrix([[1.0]]), timestamp=None,
        weight=0.5, tag="probe"))
    assert factory.fast
    sv, covar = StateVector([1.0, 2.0]), CovarianceMatrix(np.eye(2))
    built = factory(state_vector=sv, covar=covar, timestamp=START, weight=0.3, tag="x")
    real = TaggedWeightedGaussianState(state_vector=sv, covar=covar, timestamp=START,
                                       weight=0.3, tag="x")
    assert built.__dict__ == real.__dict__ and type(built) is type(real)
    with seeded_uuids(8):
        fresh = factory(state_vector=sv, covar=covar, timestamp=None, weight=0.3, tag=None)
    with seeded_uuids(8):
        assert fresh.tag == TaggedWeightedGaussianState(sv, covar, tag=None).tag
    # a probe the constructor treats differently (it converts a plain array): fall back
    slow = ObjectFactory(TaggedWeightedGaussianState, dict(
        state_vector=np.zeros((1, 1)), covar=np.eye(1), timestamp=None, weight=0.5, tag="p"))
    assert not slow.fast
    made = slow(state_vector=np.zeros((2, 1)), covar=np.eye(2), weight=1.0, tag="q")
    assert isinstance(made.state_vector, StateVector)
    assert isinstance(made.covar, CovarianceMatrix)


def test_gaussian_arrays_rejects_mixed_dimensions():
    states = [TaggedWeightedGaussianState(StateVector([0.0, 1.0]), np.eye(2)),
              TaggedWeightedGaussianState(StateVector([0.0, 1.0, 2.0]), np.eye(3))]
    with pytest.raises(ValueError, match="states"):
        gaussian_arrays(states)
