"""The online detection-probability estimate (``DetectionEstimate``): the posterior mean of
each band against an independent NumPy computation of the discounted Beta posterior,
convergence to the true P_D per band, use as a P_D factor frozen per scan's context, named
errors, exact pickle/YAML round trips that continue identically."""
import pickle

import numpy as np
import pytest
from stonesoup.serialise import YAML

from ctxmodels import (AngularSector, ClutterDensityModel, DetectionEstimate,
                       DetectionProbabilityModel, Pose, SensorModel)

EDGES = (50.0, 400.0, 900.0, 1600.0)
ORIGIN = (0.0, 0.0, 0.0)


def _trials(rng, n, true=(0.8, 0.4, 0.1)):
    """n tracks at random ranges 0–1800 m and bearings, detected with each band's P_D."""
    ranges = rng.uniform(0, 1800, n)
    bearings = rng.uniform(-np.pi, np.pi, n)
    positions = np.column_stack([ranges * np.cos(bearings), ranges * np.sin(bearings)])
    band = np.searchsorted(EDGES, ranges, side="right") - 1
    inside = (band >= 0) & (band < len(true))
    p = np.where(inside, np.asarray(true)[np.clip(band, 0, len(true) - 1)], 0.0)
    return positions, rng.random(n) < p, rng.choice([0.0, 1.0, 0.5], n, p=[0.2, 0.6, 0.2])


def test_posterior_mean_is_the_discounted_beta_mean():
    rng = np.random.default_rng(3)
    estimate = DetectionEstimate(edges=EDGES, prior_probability=0.3, prior_trials=4.0,
                                 forgetting=0.9)
    scans = [_trials(rng, int(rng.integers(0, 12))) for _ in range(30)]
    for positions, detected, weights in scans:
        estimate.update(ORIGIN, positions, detected, weights)
    # independently: every trial discounted by 0.9 per later scan, summed per band
    hits, trials = np.zeros(3), np.zeros(3)
    for k, (positions, detected, weights) in enumerate(scans):
        band = np.searchsorted(EDGES, np.hypot(*positions.T), side="right") - 1
        for b, d, w in zip(band, detected, weights):
            if 0 <= b < 3 and w > 0:  # (a trial of weight 0 is no evidence, hit or miss)
                hits[b] += 0.9 ** (len(scans) - 1 - k) * d
                trials[b] += 0.9 ** (len(scans) - 1 - k) * w
    np.testing.assert_allclose(estimate.hits, hits, rtol=1e-12)
    np.testing.assert_allclose(estimate.trials, trials, rtol=1e-12)
    np.testing.assert_allclose(estimate.probabilities(),
                               np.clip((0.3 * 4 + hits) / (4 + trials), 0, 1), rtol=1e-12)


def test_converges_to_each_bands_true_detection_probability():
    rng = np.random.default_rng(5)
    estimate = DetectionEstimate(edges=EDGES, prior_probability=0.5, prior_trials=5.0,
                                 forgetting=0.99)
    for _ in range(1500):
        positions, detected, _ = _trials(rng, 20)
        estimate.update(ORIGIN, positions, detected)
    # ~20·(band width / 1800) trials a scan per band, a memory of ~199 scans: ≥ 780 trials
    # in the narrowest band, so σ ≤ √(0.24 / 780) ≈ 0.018; the prior's pull ≤ 5/785 · 0.4
    np.testing.assert_allclose(estimate.probabilities(), (0.8, 0.4, 0.1), atol=0.06)


def test_no_evidence_keeps_the_prior_and_weight_zero_is_no_evidence():
    estimate = DetectionEstimate(edges=EDGES, prior_probability=0.35)
    estimate.update(ORIGIN, [[100.0, 0.0], [0.0, 2000.0], [10.0, 0.0]], [False, True, True],
                    [0.0, 1.0, 1.0])  # a blind-sector miss; a hit beyond; a hit inside 50 m
    assert np.all(estimate.probabilities() == 0.35)
    estimate.update(ORIGIN, np.empty((0, 2)), [])  # an empty scan forgets, adds nothing
    assert np.all(estimate.probabilities() == 0.35)


def test_a_detection_model_reads_the_estimate_frozen_per_context():
    estimate = DetectionEstimate(edges=EDGES, prior_probability=0.5, prior_trials=2.0)
    blind = AngularSector.blind(np.pi, np.radians(60))
    sensor = SensorModel(detection=DetectionProbabilityModel(factors=[estimate, blind]),
                         clutter=ClutterDensityModel(factors=[1e-3]))
    states = np.array([[200.0, 0, 0, 0], [-200.0, 0, 0, 0], [1000.0, 0, 0, 0],
                       [2000.0, 0, 0, 0], [0.0, 0, 30.0, 0]])
    before = sensor.context(Pose(x=0.0, y=0.0))
    np.testing.assert_array_equal(before.prob_detection_array(states), [0.5, 0, 0.5, 0, 0])
    estimate.update(ORIGIN, [[200.0, 0.0], [1000.0, 0.0], [1100.0, 0.0]], [True, False, False])
    after = sensor.context(Pose(x=0.0, y=0.0))
    # the scan's context keeps the estimate it started with; the next one reads the update
    np.testing.assert_array_equal(before.prob_detection_array(states), [0.5, 0, 0.5, 0, 0])
    p = estimate.probabilities()
    assert p[0] == (1 + 1) / 3 and p[2] == 1 / 4
    np.testing.assert_array_equal(after.prob_detection_array(states), [p[0], 0, p[2], 0, 0])


def _used_estimate():
    rng = np.random.default_rng(11)
    estimate = DetectionEstimate(edges=EDGES, prior_probability=0.5, forgetting=0.93)
    for _ in range(25):
        estimate.update(ORIGIN, *_trials(rng, 9))
    return estimate


@pytest.mark.parametrize("round_trip", ["pickle", "yaml"])
def test_state_round_trips_exactly_and_continues_identically(round_trip):
    estimate = _used_estimate()
    restored = (pickle.loads(pickle.dumps(estimate)) if round_trip == "pickle"
                else YAML().load(YAML().dumps(estimate)))
    assert type(restored) is DetectionEstimate and estimate.trials.sum() > 0
    assert restored.hits.tobytes() == estimate.hits.tobytes()
    assert restored.trials.tobytes() == estimate.trials.tobytes()
    scan = _trials(np.random.default_rng(12), 7)
    estimate.update(ORIGIN, *scan)
    restored.update(ORIGIN, *scan)
    assert restored.probabilities().tobytes() == estimate.probabilities().tobytes()


def test_reset_and_immutability_of_the_configuration():
    estimate = _used_estimate()
    estimate.reset()
    assert np.all(estimate.probabilities() == 0.5) and estimate.trials.sum() == 0
    with pytest.raises(AttributeError, match="^DetectionEstimate.forgetting: set at construction"):
        estimate.forgetting = 0.5


@pytest.mark.parametrize("kwargs,argument", [
    (dict(edges=()), "edges"),
    (dict(edges=(10.0,)), "edges"),
    (dict(edges=(10.0, 10.0)), "edges"),
    (dict(edges=(-1.0, 10.0)), "edges"),
    (dict(edges=(0.0, np.inf)), "edges"),
    (dict(prior_probability=0.0), "prior_probability"),
    (dict(prior_probability=1.0), "prior_probability"),
    (dict(prior_probability=float("nan")), "prior_probability"),
    (dict(prior_probability="high"), "prior_probability"),
    (dict(prior_trials=0.0), "prior_trials"),
    (dict(prior_trials=-2.0), "prior_trials"),
    (dict(forgetting=0.0), "forgetting"),
    (dict(forgetting=1.01), "forgetting"),
    (dict(outside=1.5), "outside"),
    (dict(hits=[1.0, 2.0]), "hits"),
    (dict(trials=[-1.0]), "trials"),
])
def test_bad_configuration_is_named(kwargs, argument):
    config = dict(edges=(0.0, 100.0), prior_probability=0.5)
    with pytest.raises((ValueError, TypeError), match=f"^{argument}: "):
        DetectionEstimate(**{**config, **kwargs})


def test_bad_updates_are_named_and_change_nothing():
    estimate = _used_estimate()
    before = estimate.hits.tobytes(), estimate.trials.tobytes()
    for args, argument in [(([[1.0, 2.0]], [0.5]), "detected"),
                           (([[1.0, 2.0]], [1.0], [1.5]), "weights"),
                           (([[np.nan, 2.0]], [1.0]), "positions"),
                           (([[1.0, 2.0]], [1.0, 0.0]), "detected"),
                           (([[1.0, 2.0, 3.0]], [1.0]), "positions")]:
        with pytest.raises(ValueError, match=f"^{argument}: "):
            estimate.update(ORIGIN, *args)
    assert (estimate.hits.tobytes(), estimate.trials.tobytes()) == before


def test_detection_model_names_what_it_accepts():
    with pytest.raises(TypeError, match="DetectionEstimate"):
        DetectionProbabilityModel(factors=[object()])
