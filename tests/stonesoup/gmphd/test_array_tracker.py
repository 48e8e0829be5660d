"""The array GM-PHD tracker (each scan in the Rust core) against the stock pipeline.

The reference is ctxmodels' ``PointProcessMultiTargetTracker`` — the stock Stone Soup
hypothesiser, PHD updater and reducer, fed each scan's detections in the stable order (and,
with the ``stock_in_stable_order`` fixture, the stock reducer visiting shared tags in
first-appearance order). After every scan the two must hold the same tracks, state by
state, to rtol 1e-9 (:func:`setups.relative_difference`) with linear models and the
closed-form bearing–range Jacobian. With Stone Soup's finite-difference Jacobian the bound
is looser and measured (see ``test_finite_difference_jacobian_agrees_to_its_round_off``).
"""
import datetime
import math
import pickle

import numpy as np
import pytest
from stonesoup.mixturereducer.gaussianmixture import GaussianMixtureReducer
from stonesoup.measures import SquaredMahalanobis
from stonesoup.serialise import YAML
from stonesoup.types.array import StateVector
from stonesoup.types.detection import Detection
from stonesoup.types.state import TaggedWeightedGaussianState
from stonesoup.updater.pointprocess import LCCUpdater

from ctxmodels import DetectionSet, _core
from ctxmodels.experiment.scenarios import make_scenario
from ctxmodels.experiment.trackers import build_tracker
from ctxmodels.trackers import TRACKERS
from ctxmodels.stonesoup import (
    ArrayPointProcessTracker,
    CircularRegion,
    ComponentPathWarning,
    MeasurementDrivenBirth,
    PointProcessMultiTargetTracker,
)

from .setups import (RTOL, START, birth_component, lockstep, radar_lidar_scenario, relative_difference,
                     seeded_uuids, stock_components, tutorial_scenario, with_contexts)

pytestmark = pytest.mark.usefixtures("stock_in_stable_order")


def pair(scans, components, **tracker_options):
    """The reference and the array tracker on the same scans with equal components."""
    def build(cls):
        parts = components()
        return cls(detector=scans, **parts, **tracker_options)
    return build(PointProcessMultiTargetTracker), build(ArrayPointProcessTracker)


# --- conformance -------------------------------------------------------------------------------
def test_tutorial_matches_stock_after_every_scan():
    scenario = tutorial_scenario(n_scans=30)
    with seeded_uuids(1):
        reference, tracker = pair(scenario["scans"], lambda: stock_components(scenario),
                                  birth_component=birth_component(scenario),
                                  extraction_threshold=0.5)
        assert tracker.array_path
        worst = lockstep(reference, tracker, compare_mixtures=True)
    assert worst <= RTOL
    assert len(reference.target_tracks) >= 2


@pytest.mark.parametrize("pd_evaluation", ["mean", "cubature"])
def test_radar_lidar_with_contexts_matches_after_every_scan(pd_evaluation):
    """Contexts, measurement-driven birth, a surveillance region and the uncertainty bound:
    the experiment's configuration on a small scenario."""
    scenario = radar_lidar_scenario(n_scans=60)
    scans = with_contexts(scenario["scans"], pd_evaluation)
    options = dict(birth=MeasurementDrivenBirth(birth_weight=1e-2),
                   surveillance_region=CircularRegion(centre=(0.0, 0.0), radius=1200.0),
                   max_position_std=60.0, extraction_threshold=0.5)
    explained = []
    with seeded_uuids(2):
        reference, tracker = pair(
            scans, lambda: stock_components(scenario, context_updater=True), **options)
        worst = lockstep(reference, tracker, explained=explained)
    assert worst <= RTOL
    assert len(reference.target_tracks) >= 1
    # the tracked targets explain their detections: clutter probabilities near 0 as well as
    # between (a detection near a weak component)
    assert min(explained) < 0.01 and any(0.05 < p < 0.95 for p in explained)


def test_radar_lidar_without_contexts_matches_with_the_mixture_read_each_scan():
    """Reading ``gaussian_mixture`` builds Stone Soup objects and hands them back to the
    core at the next scan: nothing may change."""
    scenario = radar_lidar_scenario(n_scans=40)
    with seeded_uuids(3):
        reference, tracker = pair(scenario["scans"], lambda: stock_components(scenario),
                                  birth_component=birth_component(scenario),
                                  extraction_threshold=0.5)
        worst = lockstep(reference, tracker, compare_mixtures=True)
    assert worst <= RTOL


def test_finite_difference_jacobian_agrees_to_its_round_off():
    """Stone Soup's finite-difference bearing–range Jacobian (step 1e-8 for negative
    coordinates) has round-off up to ~1e-4 relative that follows the last bit of the state,
    so two correct filters differing in rounding agree only to about that. Measured on this
    set-up: 1.2e-4 elementwise (bound 1e-3); the same set-up with the closed-form Jacobian
    agrees to 1e-9 (the tests above)."""
    scenario = radar_lidar_scenario(n_scans=60, analytic=False)
    scans = with_contexts(scenario["scans"])
    with seeded_uuids(4):
        reference, tracker = pair(
            scans, lambda: stock_components(scenario, context_updater=True),
            birth=MeasurementDrivenBirth(birth_weight=1e-2), extraction_threshold=0.5)
        assert tracker.array_path
        worst = lockstep(reference, tracker)
    assert worst <= 1e-3


EXPERIMENT_CASES = [("mixed-range", name) for name in
                    ("gmphd-context", "gmphd-pd-aware", "gmphd-uniform", "gmphd-radar-only")] \
    + [("formation", "gmphd-context"), ("islands", "gmphd-sight"), ("islands", "gmphd-learned"),
       ("islands", "gmphd-learned-clutter"), ("islands", "gmphd-coastal")]


@pytest.mark.parametrize(("scenario", "name"), EXPERIMENT_CASES)
def test_experiment_trackers_match_the_component_path(scenario, name):
    run = make_scenario(scenario, 0, 12.0)
    spec = TRACKERS[name]
    reference, tracker = build_tracker(spec, run, fast=False), build_tracker(spec, run)
    assert lockstep(reference, tracker) <= RTOL
    reference, tracker = getattr(reference, "tracker", reference), getattr(tracker, "tracker", tracker)
    assert type(reference) is PointProcessMultiTargetTracker
    assert type(tracker) is ArrayPointProcessTracker and tracker.array_path


# --- the reducer alone ---------------------------------------------------------------------------
def random_mixture(n, seed, duplicate_tags=False):
    rng = np.random.default_rng(seed)
    centres = rng.uniform(-50, 50, size=(max(n // 4, 1), 4))
    components = []
    for i in range(n):
        a = rng.normal(size=(4, 4))
        components.append(TaggedWeightedGaussianState(
            StateVector(centres[rng.integers(len(centres))] + rng.normal(0, 2, 4)),
            a @ a.T + np.diag(rng.uniform(0.5, 8, 4)), weight=float(10 ** rng.uniform(-11, 0.2)),
            tag=f"t{i % (n // 3)}" if duplicate_tags else f"t{i}", timestamp=START))
    components[5].weight = components[4].weight  # a tie in weight
    return components


def core_reduce(components, **options):
    """The core's reduction of Stone Soup components, back as (tag or None for a fresh
    one, weight, mean, covariance) rows."""
    names = list(dict.fromkeys(c.tag for c in components))
    arrays = _core.GaussianMixtureArrays(4)
    first = arrays.reserve_tags(len(names))
    ids = {name: first + i for i, name in enumerate(names)}
    arrays.extend(np.array([c.state_vector.ravel() for c in components], dtype=float),
                  np.array([c.covar for c in components], dtype=float),
                  np.array([float(c.weight) for c in components]),
                  [ids[c.tag] for c in components], [0] * len(components))
    settings = dict(pruning=True, prune_threshold=1e-9, merging=True, merge_threshold=16.0,
                    truncating=True, max_components=2 ** 63, kdtree_max_distance=None)
    settings.update(options)
    arrays.reduce(**settings)
    back = {i: name for name, i in ids.items()}
    return [(back.get(tag), w, m, c) for tag, w, m, c in zip(
        arrays.tags().tolist(), arrays.weights(), arrays.means(), arrays.covars())]


def assert_same_reduction(expected, got, original_tags):
    assert len(expected) == len(got)
    for a, (tag, weight, mean, covar) in zip(expected, got):
        assert (a.tag if a.tag in original_tags else None) == tag
        assert relative_difference(float(a.weight), weight) <= RTOL
        assert relative_difference(a.state_vector.ravel(), mean) <= RTOL
        assert relative_difference(a.covar, covar) <= RTOL


@pytest.mark.parametrize("options", [
    {}, {"merge_threshold": 40}, {"max_number_components": 9},
    {"pruning": False, "merge_threshold": 5}, {"merging": False, "max_number_components": 20},
    {"prune_threshold": 1e-3}])
@pytest.mark.parametrize("duplicate_tags", [False, True])
def test_core_reducer_matches_stock(options, duplicate_tags):
    core_options = {{"max_number_components": "max_components"}.get(k, k): v
                    for k, v in options.items()}
    for seed in range(3):
        components = random_mixture(60, seed, duplicate_tags)
        tags = {c.tag for c in components}
        expected = GaussianMixtureReducer(**dict(dict(prune_threshold=1e-9), **options)).reduce(
            [TaggedWeightedGaussianState(**{n: getattr(c, n) for n in type(c).properties})
             for c in components])
        assert_same_reduction(expected, core_reduce(components, **core_options), tags)
        assert len(expected) < len(components)


def kdtree_gated_merge(components, merge_threshold, max_distance):
    """Reference for the k-d-tree gate in the stable order: the stock greedy merge restricted
    to the components within ``max_distance`` (Euclidean, whole state) of the heaviest's own
    mean, visited in increasing weight (stock visits them in a set's address order)."""
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


def test_core_reducer_kdtree_gate_merges_candidates_in_weight_order():
    for seed in range(3):
        components = random_mixture(60, seed)
        tags = {c.tag for c in components}
        expected = kdtree_gated_merge(components, 40, 5)
        got = core_reduce(components, pruning=False, merge_threshold=40.0,
                          kdtree_max_distance=5.0)
        assert_same_reduction(expected, got, tags)
        wide = core_reduce(components, pruning=False, merge_threshold=40.0)
        assert len(got) != len(wide)


def test_core_reducer_merges_near_the_threshold_exactly():
    """Pairs whose distance sits within rounding of the threshold: the bound that skips far
    pairs must not skip a pair the exact distance merges."""
    rng = np.random.default_rng(3)
    components = []
    for i in range(80):
        covar = np.diag(rng.uniform(1, 4, 4))
        components.append(TaggedWeightedGaussianState(
            StateVector(rng.normal(0, 1e3, 4)), covar, weight=rng.uniform(0.01, 0.2),
            tag=f"a{i}", timestamp=START))
        direction = rng.normal(size=4)
        direction *= math.sqrt(16.0 / (direction @ np.linalg.inv(covar) @ direction)) * (
            1 + rng.choice([-1e-12, 1e-12]))
        components.append(TaggedWeightedGaussianState(
            components[-1].state_vector + direction[:, np.newaxis], covar,
            weight=float(components[-1].weight) / 2, tag=f"b{i}", timestamp=START))
    expected = GaussianMixtureReducer(prune_threshold=1e-9, merge_threshold=16).reduce(
        list(components))
    got = core_reduce(components)
    assert_same_reduction(expected, got, {c.tag for c in components})
    assert 80 < len(got) < 160


# --- fallbacks, the mixture, errors --------------------------------------------------------------
def test_unsupported_configuration_runs_the_component_path():
    scenario = tutorial_scenario(n_scans=12)

    def lcc():
        parts = stock_components(scenario)
        parts["updater"] = LCCUpdater(parts["updater"].updater, clutter_spatial_density=1e-3,
                                      prob_detection=0.9, mean_number_of_false_alarms=3)
        return parts
    with seeded_uuids(5):
        reference, tracker = pair(scenario["scans"], lcc,
                                  birth_component=birth_component(scenario),
                                  extraction_threshold=0.5)
        assert not tracker.array_path
        with pytest.warns(ComponentPathWarning, match="LCCUpdater, not a PHD updater"):
            assert lockstep(reference, tracker, compare_mixtures=True) == 0.0
    assert tracker.array_scans == 0 and tracker.component_scans == 12


def test_a_scan_the_core_cannot_take_runs_the_component_path():
    """A scan mixing two measurement models (and one whose detections carry another
    timestamp) runs through the components; the scans around it in the core."""
    scenario = radar_lidar_scenario(n_scans=30)
    scans = list(scenario["scans"])
    (_, first), (t2, second) = scans[8], scans[9]
    merged = {Detection(d.state_vector, timestamp=t2, measurement_model=d.measurement_model)
              for d in first} | set(second)
    scans[9] = (t2, merged)
    with seeded_uuids(6):
        reference, tracker = pair(scans, lambda: stock_components(scenario),
                                  birth_component=birth_component(scenario),
                                  extraction_threshold=0.5)
        assert tracker.array_path  # (the configuration is the core's)
        with pytest.warns(ComponentPathWarning, match="2 distinct measurement models"):
            assert lockstep(reference, tracker) <= RTOL
    assert tracker.component_scans == 1 and tracker.array_scans == len(scans) - 1
    assert not tracker.array_path  # (what ran)


def test_an_assigned_mixture_is_the_one_the_next_scan_updates():
    scenario = tutorial_scenario(n_scans=10)
    scans = scenario["scans"]
    start = [TaggedWeightedGaussianState(StateVector([-30.0, 1.0, 10.0, -0.5]),
                                         np.diag([4.0, 1.0, 4.0, 1.0]), weight=0.9, tag="mine",
                                         timestamp=scans[0][0] - datetime.timedelta(seconds=1))]
    with seeded_uuids(7):
        reference, tracker = pair(scans, lambda: stock_components(scenario),
                                  extraction_threshold=0.5)
        for t in (reference, tracker):
            t.gaussian_mixture.components = [TaggedWeightedGaussianState(
                **{n: getattr(c, n) for n in type(c).properties}) for c in start]
        assert lockstep(reference, tracker, compare_mixtures=True) <= RTOL
    assert "mine" in tracker.target_tracks


def test_errors_name_the_argument():
    scenario = tutorial_scenario(n_scans=3)
    t, detections = scenario["scans"][1]
    bad = {Detection(StateVector([float("nan"), 1.0]), timestamp=t,
                     measurement_model=next(iter(detections)).measurement_model)}
    tracker = ArrayPointProcessTracker(detector=[(t, bad)], **stock_components(scenario),
                                       birth_component=birth_component(scenario))
    with pytest.raises(ValueError, match="detections"):
        next(iter(tracker))

    class Region:
        def contains(self, points):
            return np.ones(len(points) + 1, dtype=bool)
    tracker = ArrayPointProcessTracker(detector=scenario["scans"], **stock_components(scenario),
                                       birth_component=birth_component(scenario),
                                       surveillance_region=Region())
    with pytest.raises(ValueError, match="surveillance_region"):
        next(iter(tracker))

    class Overconfident:
        sensor_model = type("M", (), {"pd_evaluation": "mean"})()

        def prob_detection_array(self, means, covars=None):
            return np.full(len(means), 1.5)

        def clutter_spatial_density_detections(self, detections, positions=None):
            return np.full(len(detections), 1e-3)
    context_scans = [(t, DetectionSet(d, detector_context=Overconfident()))
                     for t, d in scenario["scans"]]
    tracker = ArrayPointProcessTracker(
        detector=context_scans, **stock_components(scenario, context_updater=True),
        birth_component=birth_component(scenario))
    with pytest.raises(ValueError, match="prob_detection"):
        next(iter(tracker))


def test_tracker_serialises_and_pickles_like_a_stone_soup_component():
    scenario = tutorial_scenario(n_scans=5)
    tracker = ArrayPointProcessTracker(detector=None, **stock_components(scenario),
                                       birth_component=birth_component(scenario),
                                       max_position_std=50.0)
    text = YAML().dumps(tracker)
    assert "ArrayPointProcessTracker" in text and "max_position_std: 50.0" in text
    loaded = YAML().load(text)
    assert type(loaded) is ArrayPointProcessTracker and loaded.max_position_std == 50.0
    copy = pickle.loads(pickle.dumps(tracker))
    assert copy.max_position_std == 50.0 and copy.array_path


def test_mixture_arrays_pickle_round_trip():
    arrays = _core.GaussianMixtureArrays(2)
    tag = arrays.reserve_tags(3)
    arrays.extend(np.array([[1.0, 2.0], [3.0, 4.0]]), np.array([np.eye(2), 2 * np.eye(2)]),
                  np.array([0.5, 0.25]), [tag, 0], [7, 8])
    copy = pickle.loads(pickle.dumps(arrays))
    assert len(copy) == 2 and copy.next_tag == arrays.next_tag
    for name in ("means", "covars", "weights", "tags", "times"):
        assert np.array_equal(getattr(copy, name)(), getattr(arrays, name)())
    with pytest.raises(ValueError, match="tags"):
        arrays.extend(np.zeros((1, 2)), np.eye(2)[np.newaxis], np.ones(1), [10 ** 6], [0])
    with pytest.raises(ValueError, match="covars"):
        arrays.extend(np.zeros((1, 2)), np.eye(3)[np.newaxis], np.ones(1), [0], [0])


def test_mixture_p_d_in_the_core_is_the_contexts_array_call():
    """P_D on the mixture's means in the core (the array tracker's route for a ctxmodels
    context reading P_D at the mean) gives the bits of the context's array call on the means
    copied out; a mapping beyond the state is None (the general route names the error)."""
    from ctxmodels import DetectionProbabilityModel, Pose, RangeBands, SensorModel, ClutterDensityModel
    model = SensorModel(detection=DetectionProbabilityModel(factors=[RangeBands(
        edges=(50.0, 400.0, 900.0), values=(0.0, 0.9, 0.5, 0.0))]),
        clutter=ClutterDensityModel(factors=[1e-3]))
    context = model.context(Pose(x=10.0, y=-5.0, heading=0.3))
    rng = np.random.default_rng(3)
    arrays = _core.GaussianMixtureArrays(4)
    means = rng.normal(0.0, 500.0, (40, 4))
    arrays.extend(means, np.broadcast_to(np.eye(4), (40, 4, 4)).copy(), np.full(40, 0.1),
                  [0] * 40, [0] * 40)
    pd = arrays.prob_detection(context._mean_detection())
    assert pd.tobytes() == context.prob_detection_array(arrays.means()).tobytes()
    far = SensorModel(detection=model.detection, clutter=model.clutter, position_mapping=(0, 7))
    assert arrays.prob_detection(far.context(Pose(x=0.0, y=0.0))._mean_detection()) is None
    cubature = SensorModel(detection=model.detection, clutter=model.clutter,
                           pd_evaluation="cubature")
    assert cubature.context(Pose(x=0.0, y=0.0))._mean_detection() is None


def test_births_queue_in_one_core_call_as_in_steps():
    """``extend_births`` keeps the births inside the circle and appends them, as extending a
    fresh mixture, keeping it inside the circle and taking it all does."""
    rng = np.random.default_rng(4)
    means, covar = rng.normal(0.0, 10.0, (12, 4)), np.diag([4.0, 1.0, 4.0, 1.0])
    for circle in (None, ((0, 2), (1.0, -2.0), 9.0)):
        one, steps = _core.GaussianMixtureArrays(4), _core.GaussianMixtureArrays(4)
        weights = rng.uniform(0.01, 0.2, 12)
        one.extend_births(means, covar, weights, 5, circle)
        fresh = _core.GaussianMixtureArrays(4)
        fresh.extend(means, np.broadcast_to(covar, (12, 4, 4)).copy(), weights,
                     [0] * 12, [5] * 12)
        if circle is not None:
            fresh.retain_inside_circle(*circle)
        steps.take_from(fresh, [True] * len(fresh))
        for name in ("means", "covars", "weights", "tags", "times"):
            assert getattr(one, name)().tobytes() == getattr(steps, name)().tobytes()
        assert 0 < len(one) <= 12
    with pytest.raises(ValueError, match="covar"):
        one.extend_births(means, np.eye(3), np.full(12, 0.1), 5)
    with pytest.raises(ValueError, match="^weights: must have 12 entries"):
        one.extend_births(means, covar, np.full(11, 0.1), 5)
