"""Detector contexts that are not ctxmodels' own (``ctxmodels.foreign``): anything with
``prob_detection(hypothesis)`` and ``clutter_spatial_density(detection)``, Stone Soup's
interface, works in the drop-ins and gives the numbers a ctxmodels context with the same
answers gives (one call per prediction and per detection instead of one array call)."""
import math

import numpy as np
import pytest
from stonesoup.types.detection import Detection, MissedDetection
from stonesoup.types.hypothesis import SingleHypothesis
from stonesoup.types.numeric import Probability
from stonesoup.types.prediction import GaussianStatePrediction
from stonesoup.types.state import GaussianState
from stonesoup.types.track import Track

from ctxmodels import DetectionSet
from ctxmodels.foreign import PerCallContext, as_array_context
from ctxmodels.stonesoup import (ArrayPointProcessTracker, CircularRegion,
                                 MeasurementDrivenBirth, PDAHypothesiser,
                                 PointProcessMultiTargetTracker)

from ..stonesoup.gmphd.setups import (RTOL, radar_lidar_scenario, seeded_uuids, stock_components,
                                      tracks_difference, with_contexts)

pytestmark = pytest.mark.usefixtures("stock_in_stable_order")


class Foreign:
    """A user's context: only the two per-call methods, answering what ``inner`` answers
    (a ctxmodels context), and counting the calls."""

    def __init__(self, inner):
        self.inner = inner
        self.calls = {"prob_detection": 0, "clutter_spatial_density": 0}

    def prob_detection(self, hypothesis):
        self.calls["prob_detection"] += 1
        assert isinstance(hypothesis, SingleHypothesis)  # the interface passes hypotheses
        return self.inner.prob_detection(hypothesis)

    def clutter_spatial_density(self, detection):
        self.calls["clutter_spatial_density"] += 1
        return self.inner.clutter_spatial_density(detection)


def foreign_scans(scans):
    """The same scans, each context hidden behind :class:`Foreign`."""
    return [(t, DetectionSet(d, detector_context=Foreign(d.detector_context))) for t, d in scans]


def run(cls, scans, scenario):
    tracker = cls(detector=scans, **stock_components(scenario, context_updater=True),
                  birth=MeasurementDrivenBirth(birth_weight=1e-2),
                  surveillance_region=CircularRegion(centre=(0.0, 0.0), radius=1200.0),
                  max_position_std=60.0, extraction_threshold=0.5)
    return tracker


@pytest.mark.parametrize("cls", [PointProcessMultiTargetTracker, ArrayPointProcessTracker])
def test_gm_phd_trackers_give_the_same_tracks_with_a_foreign_context(cls):
    """The radar–lidar GM-PHD set-up with ctxmodels contexts against the same contexts seen
    only through Stone Soup's interface, after every scan."""
    scenario = radar_lidar_scenario(n_scans=40)
    scans = with_contexts(scenario["scans"])
    foreign = foreign_scans(scans)
    with seeded_uuids(4):
        reference = run(PointProcessMultiTargetTracker, scans, scenario)
        tracker = run(cls, foreign, scenario)
        worst, steps = 0.0, 0
        for (t1, _), (t2, _) in zip(reference, tracker):
            assert t1 == t2
            steps += 1
            worst = max(worst, tracks_difference(reference.target_tracks.values(),
                                                 tracker.target_tracks.values(), f"scan {steps}"))
    assert steps == 40 and worst <= RTOL
    assert len(reference.target_tracks) >= 1
    calls = [d.detector_context.calls for _, d in foreign]
    assert sum(c["prob_detection"] for c in calls) > 0
    assert sum(c["clutter_spatial_density"] for c in calls) > 0


def test_pda_hypothesiser_asks_a_foreign_context_with_a_hypothesis():
    scenario = radar_lidar_scenario(n_scans=12)
    scans = with_contexts(scenario["scans"])
    parts = stock_components(scenario, context_updater=True)
    kalman = parts["updater"].updater
    predictor = parts["hypothesiser"].hypothesiser.predictor
    hypothesiser = PDAHypothesiser(predictor, kalman, clutter_spatial_density=1e-6,
                                   prob_detect=0.9)
    track = Track([GaussianState(np.array([[20.0], [1.0], [30.0], [0.5]]),
                                 np.diag([25.0, 1.0, 25.0, 1.0]), timestamp=scans[0][0])])
    checked = 0
    for t, detections in scans[1:]:
        ours = hypothesiser.hypothesise(track, detections, t)
        foreign = Foreign(detections.detector_context)
        theirs = hypothesiser.hypothesise(track, detections, t, detector_context=foreign)
        assert len(ours) == len(theirs)
        for a, b in zip(ours, theirs):
            missed = isinstance(a.measurement, MissedDetection)
            assert a.measurement is b.measurement or (
                missed and isinstance(b.measurement, MissedDetection))
            assert math.isclose(float(a.probability), float(b.probability), rel_tol=1e-12)
        assert foreign.calls["prob_detection"] == 1
        assert foreign.calls["clutter_spatial_density"] == len(detections)
        checked += len(detections)
    assert checked > 0


def test_per_call_context_checks_the_answers_and_names_the_argument():
    class Bad:
        def __init__(self, pd, clutter):
            self.pd, self.clutter = pd, clutter

        def prob_detection(self, hypothesis):
            return self.pd

        def clutter_spatial_density(self, detection):
            return self.clutter

    def wrap(context):
        return as_array_context(context, "prob_detection_states",
                                "clutter_spatial_density_detections")

    prediction = GaussianStatePrediction(np.zeros((4, 1)), np.eye(4))
    detection = Detection(np.zeros((2, 1)))
    assert wrap(Bad(0.3, 1e-4)).prob_detection_states([prediction]).tolist() == [0.3]
    assert isinstance(wrap(Bad(Probability(0.3), 1e-4)), PerCallContext)
    for pd in (1.5, -0.1, float("nan")):
        with pytest.raises(ValueError, match=r"detector_context: prob_detection \(P_D\) must lie in"):
            wrap(Bad(pd, 1e-4)).prob_detection_states([prediction])
    for clutter in (0.0, -1.0, float("inf"), float("nan")):
        with pytest.raises(ValueError, match="detector_context: clutter_spatial_density must"):
            wrap(Bad(0.3, clutter)).clutter_spatial_density_detections([detection])
    with pytest.raises(TypeError, match="detector_context: expected a detector context"):
        wrap(object())
    # P_D is asked about the prediction with a missed-detection hypothesis.
    seen = []

    class Recording(Bad):
        def prob_detection(self, hypothesis):
            seen.append(hypothesis)
            return 0.5

    wrap(Recording(0, 1)).prob_detection_states([prediction])
    assert seen[0].prediction is prediction and isinstance(seen[0].measurement, MissedDetection)


@pytest.mark.parametrize("filter_name", ["bernoulli", "smcphd"])
def test_particle_updaters_give_the_same_states_with_a_foreign_context(filter_name):
    """P_D per particle and λ per detection asked one at a time: the same particles,
    weights and existence as with the ctxmodels context (Stone Soup's ``Probability`` may
    move a P_D by an ulp on the way, so to rounding)."""
    from ctxmodels.stonesoup.particle import BernoulliParticleUpdater, SMCPHDUpdater

    from ..stonesoup.particle_setups import banded_context, run_bernoulli, run_smcphd, scenario
    scans = scenario(empty=(3,))
    context = banded_context()
    foreign = Foreign(context)
    if filter_name == "bernoulli":
        ours = run_bernoulli(BernoulliParticleUpdater, scans, seed=3, context=context)
        theirs = run_bernoulli(BernoulliParticleUpdater, scans, seed=3, context=foreign)
    else:
        ours = run_smcphd(SMCPHDUpdater, scans, seed=3, context=context)
        theirs = run_smcphd(SMCPHDUpdater, scans, seed=3, context=foreign)
    assert len(ours) == len(theirs) == len(scans)
    for a, b in zip(ours, theirs):
        for x, y in zip(a, b):
            if isinstance(x, bytes):
                x, y = np.frombuffer(x), np.frombuffer(y)
            np.testing.assert_allclose(y, x, rtol=1e-9, atol=1e-12)
    assert foreign.calls["prob_detection"] > 0 and foreign.calls["clutter_spatial_density"] > 0
