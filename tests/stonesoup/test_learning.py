"""Learning from a tracker's own output (``LearningTracker``, ``ClutterMapLearner``,
``DetectionLearner``): the hook sees each scan the tracker saw, with its tracks, and changes
nothing else; a GM-PHD that learns its radar's clutter map on a simulated scan stream
converges to the true clutter intensity without absorbing the target it tracks (the gate),
where a map fed every detection takes the target for clutter; one that learns its radar's
P_D converges to the target's; the P_D learner counts confirmed tracks only, weighted by
the sensor's other factors."""
import datetime
import math
import pickle

import numpy as np
import pytest
from stonesoup.hypothesiser.distance import DistanceHypothesiser
from stonesoup.hypothesiser.gaussianmixture import GaussianMixtureHypothesiser
from stonesoup.measures import Mahalanobis
from stonesoup.mixturereducer.gaussianmixture import GaussianMixtureReducer
from stonesoup.models.measurement.nonlinear import CartesianToBearingRange
from stonesoup.models.transition.linear import (CombinedLinearGaussianTransitionModel,
                                                ConstantVelocity)
from stonesoup.predictor.kalman import KalmanPredictor
from stonesoup.types.detection import Detection
from stonesoup.updater.kalman import ExtendedKalmanUpdater

from stonesoup.types.state import GaussianState
from stonesoup.types.track import Track

from ctxmodels import (AngularSector, ClutterDensityModel, ClutterMap, ConstantPose,
                       DetectionEstimate, DetectionProbabilityModel, DetectionSet, LandMask, Pose,
                       RangeBands, SensorModel)
from ctxmodels.stonesoup import (ArrayPointProcessTracker, CircularRegion, ClutterMapLearner,
                                 ContextFeeder, DetectionLearner, LearningTracker,
                                 MeasurementDrivenBirth, PHDUpdater, in_stable_order,
                                 in_track_order)

START = datetime.datetime(2026, 1, 1)
TARGET = np.array([600.0, 300.0])
BEARINGS, RANGES = np.linspace(-math.pi, math.pi, 13), np.linspace(0.0, 1500.0, 6)  # 30° × 300 m
TRUE_CLUTTER = 2e-3  # per rad·m: 2e-3 × 2π × 1500 ≈ 19 clutter points a scan


def _scans(n, seed):
    """A radar at the origin: a stationary target (P_D 0.9, σ 0.5°, 5 m) and uniform
    clutter in bearing–range."""
    rng = np.random.default_rng(seed)
    model = CartesianToBearingRange(ndim_state=4, mapping=(0, 2),
                                    noise_covar=np.diag([math.radians(0.5) ** 2, 25.0]))
    truth = (math.atan2(TARGET[1], TARGET[0]), float(np.hypot(*TARGET)))
    scans = []
    for k in range(n):
        time = START + datetime.timedelta(seconds=k)
        measured = []
        if rng.random() < 0.9:
            measured.append((truth[0] + rng.normal(0, math.radians(0.5)), truth[1] + rng.normal(0, 5)))
        for _ in range(rng.poisson(TRUE_CLUTTER * 2 * math.pi * 1500)):
            measured.append((rng.uniform(-math.pi, math.pi), rng.uniform(0, 1500)))
        scans.append((time, {Detection([[b], [r]], timestamp=time, measurement_model=model)
                             for b, r in measured}))
    return scans


def _learning_tracker(scans, learned, learners, detection=None):
    detection = detection or RangeBands(edges=(1500.0,), values=(0.9, 0.0))
    sensor = SensorModel(detection=DetectionProbabilityModel(factors=[detection]),
                         clutter=ClutterDensityModel(factors=[learned]))
    predictor = KalmanPredictor(CombinedLinearGaussianTransitionModel(
        [ConstantVelocity(0.05), ConstantVelocity(0.05)]))
    updater = ExtendedKalmanUpdater(measurement_model=None, force_symmetric_covariance=True)
    tracker = ArrayPointProcessTracker(
        detector=ContextFeeder(reader=scans, sensor_model=sensor,
                               pose_source=ConstantPose(pose=Pose(x=0.0, y=0.0))),
        hypothesiser=GaussianMixtureHypothesiser(DistanceHypothesiser(
            predictor, updater, Mahalanobis(), missed_distance=3), order_by_detection=True),
        updater=PHDUpdater(updater, clutter_spatial_density=1e-3, prob_detection=0.9),
        reducer=GaussianMixtureReducer(prune_threshold=1e-6, merge_threshold=16),
        extraction_threshold=0.85,
        birth=MeasurementDrivenBirth(birth_weight=1e-4, birth_covar=np.diag([10., 5., 10., 5.]) ** 2),
        surveillance_region=CircularRegion(centre=(0, 0), radius=2000), max_position_std=200.0)
    return LearningTracker(tracker=tracker, learners=learners)


def _map():
    return ClutterMap(space="bearing-range", edges=(BEARINGS, RANGES), prior_intensity=1e-3,
                      prior_scans=10.0, forgetting=0.995)


class Recorder:
    def __init__(self):
        self.calls = []

    def learn(self, time, detections, tracks):
        self.calls.append((time, detections, frozenset(tracks)))


def test_learners_see_each_scan_and_change_nothing_else():
    scans = _scans(40, seed=1)
    recorder = Recorder()
    wrapped = _learning_tracker(scans, _map(), [recorder])
    plain = _learning_tracker(scans, _map(), []).tracker
    for (t1, tracks1), (t2, tracks2) in zip(wrapped, plain, strict=True):
        assert t1 == t2 and len(tracks1) == len(tracks2)
        assert [t.state_vector.tobytes() for t in in_track_order(tracks1)] == \
               [t.state_vector.tobytes() for t in in_track_order(tracks2)]
    assert [c[0] for c in recorder.calls] == [time for time, _ in scans]
    assert all(set(call[1]) == detections for call, (_, detections) in zip(recorder.calls, scans))
    assert all(call[1].detector_context is not None for call in recorder.calls)
    assert wrapped.tracks == wrapped.tracker.tracks


@pytest.mark.parametrize("learner", [ClutterMapLearner(gate_radius=30.0),
                                     ClutterMapLearner(weighting="posterior")],
                         ids=["gates", "posterior"])
def test_a_gmphd_learns_the_clutter_and_not_its_target(learner):
    scans = _scans(600, seed=2)
    learned = _map()
    tracker = _learning_tracker(scans, learned, [learner])
    everything = _map()  # fed every detection, no gates: the target is clutter to it
    held = 0
    for (_, tracks), (_, detections) in zip(tracker, scans):
        everything.update((0.0, 0.0, 0.0), [
            [d.state_vector[1, 0] * math.cos(d.state_vector[0, 0]),
             d.state_vector[1, 0] * math.sin(d.state_vector[0, 0])] for d in detections])
        near = [t for t in tracks if np.hypot(*(t.state_vector[[0, 2], 0] - TARGET)) < 30]
        held += bool(near)
    assert held >= 570  # the target is tracked nearly throughout

    grid = learned.intensity_grid()
    target_cell = (np.searchsorted(BEARINGS, math.atan2(*TARGET[::-1])) - 1,
                   np.searchsorted(RANGES, np.hypot(*TARGET)) - 1)
    others = np.ones(grid.shape, bool)
    others[target_cell] = False
    # elsewhere: the true intensity but for the prior's pull (S = Σ 0.995ʲ ≈ 190 scans of
    # evidence against the prior's 10); each cell expects ~60 clutter points in that memory
    # (±13 %), their mean over 59 cells ±2 %
    evidence = (1 - 0.995 ** 600) / 0.005
    expected = (TRUE_CLUTTER * evidence + 1e-3 * 10) / (evidence + 10)
    assert abs(grid[others].mean() / expected - 1) < 0.06
    # the target's cell: its detections were gated out (and the gate's area unexposed) or
    # had a clutter probability near 0, so λ there is the clutter's, within the cells'
    # spread; the ungated map adds the target's 0.9 detections a scan over the cell's
    # 157 rad·m, ≈ 3× the clutter
    spread = grid[others].std()
    assert spread < 0.2 * expected
    assert abs(grid[target_cell] - expected) < 3 * spread
    assert everything.intensity_grid()[target_cell] > 2.5 * expected


def test_a_gmphd_learns_its_targets_detection_probability():
    scans = _scans(600, seed=4)
    estimate = DetectionEstimate(edges=(0.0, 1500.0), prior_probability=0.5, prior_trials=5.0,
                                 forgetting=0.99)
    tracker = _learning_tracker(scans, 2e-3, [DetectionLearner(gate_radius=30.0)], estimate)
    seen = []
    for _ in tracker:
        seen.append(estimate.probabilities()[0])
    # the target's P_D is 0.9; a memory of ~100 scans of one track: σ ≈ √(0.09/100) = 0.03,
    # a clutter point in a 30 m gate at 670 m ≈ 0.008 a scan
    assert abs(np.mean(seen[300:]) - 0.9) < 0.04
    assert abs(seen[-1] - 0.9) < 0.1
    assert seen[0] == 0.5  # no confirmed track yet: the prior


def _track(*states):
    return Track([GaussianState([[x], [0.0], [y], [0.0]], np.eye(4), timestamp=START
                                + datetime.timedelta(seconds=k)) for k, (x, y) in states])


def test_detection_learner_counts_confirmed_tracks_weighted_by_the_other_factors():
    estimate = DetectionEstimate(edges=(50.0, 400.0, 900.0, 1600.0), prior_probability=0.5,
                                 forgetting=1.0)
    sensor = SensorModel(detection=DetectionProbabilityModel(factors=[
        estimate, AngularSector.blind(math.pi, math.radians(60))]),
        clutter=ClutterDensityModel(factors=[1e-3]))
    model = CartesianToBearingRange(ndim_state=4, mapping=(0, 2), noise_covar=np.eye(2))

    def scan(k, *points):
        time = START + datetime.timedelta(seconds=k)
        detections = {Detection([[math.atan2(y, x)], [math.hypot(x, y)]], timestamp=time,
                                measurement_model=model) for x, y in points}
        return time, DetectionSet(detections, sensor.context(Pose(x=0.0, y=0.0), time))

    a, b, c = _track((1, (300.0, 0.0))), _track((1, (0.0, 600.0))), _track((1, (-300.0, 0.0)))
    learner = DetectionLearner(gate_radius=20.0, confirmation=1)
    learner.learn(*scan(1, (305.0, 0.0), (0.0, 590.0)), {a, b, c})
    assert estimate.trials.sum() == 0  # nobody confirmed yet
    # a: in coverage, detected again; b: detected, then missed; c: astern, in the blind
    # sector; d: new at the second scan, detected there
    for track in (a, b, c):
        track.append(_track((2, tuple(track.state_vector[[0, 2], 0]))).state)
    d = _track((2, (0.0, -1000.0)))
    learner.learn(*scan(2, (300.0, 4.0), (0.0, -1000.0)), {a, b, c, d})
    # a: a hit in band 0; b: a miss in band 1; c unconfirmed; d: no earlier detection
    assert list(estimate.hits) == [1.0, 0.0, 0.0] and list(estimate.trials) == [1.0, 1.0, 0.0]
    everyone = DetectionLearner(gate_radius=20.0, confirmation=0)
    fresh = DetectionEstimate(edges=(50.0, 400.0, 900.0, 1600.0), prior_probability=0.5,
                              forgetting=1.0)
    time, detections = scan(2, (300.0, 4.0), (0.0, -1000.0))
    detections.detector_context = SensorModel(detection=DetectionProbabilityModel(factors=[
        fresh, AngularSector.blind(math.pi, math.radians(60))]),
        clutter=ClutterDensityModel(factors=[1e-3])).context(Pose(x=0.0, y=0.0), time)
    everyone.learn(time, detections, {a, b, c, d})
    # with no confirmation every track counts, but c's weight is 0: the blind sector
    assert list(fresh.hits) == [1.0, 0.0, 1.0] and list(fresh.trials) == [1.0, 1.0, 1.0]


def test_a_track_on_land_with_a_land_return_in_its_gate_is_no_evidence():
    """The land factor gives the track weight 0: ten scans of a land return in its gate
    leave its band at the prior (a weight-0 hit counted as a full hit drove it to 1.0),
    while a track on water, detected as often, moves its band."""
    estimate = DetectionEstimate(edges=(50.0, 400.0, 900.0), prior_probability=0.5,
                                 forgetting=1.0)
    island = LandMask(polygons=[[(600.0, -50.0), (700.0, -50.0), (700.0, 50.0), (600.0, 50.0)]])
    sensor = SensorModel(detection=DetectionProbabilityModel(factors=[estimate, island]),
                         clutter=ClutterDensityModel(factors=[1e-3]))
    model = CartesianToBearingRange(ndim_state=4, mapping=(0, 2), noise_covar=np.eye(2))
    on_land, on_water = (650.0, 0.0), (200.0, 100.0)
    tracks = [_track((0, on_land)), _track((0, on_water))]
    learner = DetectionLearner(gate_radius=20.0, confirmation=0)
    for k in range(1, 11):
        time = START + datetime.timedelta(seconds=k)
        for track, (x, y) in zip(tracks, (on_land, on_water)):
            track.append(_track((k, (x, y))).state)
        detections = {Detection([[math.atan2(y, x)], [math.hypot(x, y)]], timestamp=time,
                                measurement_model=model) for x, y in (on_land, on_water)}
        learner.learn(time, DetectionSet(detections, sensor.context(Pose(x=0.0, y=0.0), time)),
                      set(tracks))
    assert estimate.probabilities()[1] == 0.5 and estimate.trials[1] == 0.0
    assert estimate.trials[0] == 10.0 and estimate.probabilities()[0] == pytest.approx(12.5 / 15)


def test_posterior_weights_are_the_trackers_clutter_probabilities():
    """The map of a posterior learner is the map updated with each detection weighted by
    the probability the tracker reported for it, in the scan's stable order."""
    scans = _scans(30, seed=6)
    learned, by_hand = _map(), _map()
    tracker = _learning_tracker(scans, learned, [ClutterMapLearner(weighting="posterior")])
    weights_seen = []
    for (time, _), (_, detections) in zip(tracker, scans):
        reported_time, reported = tracker.tracker.clutter_probabilities
        assert reported_time == time and reported.keys() == detections
        ordered = in_stable_order(detections)
        weights = np.array([reported[d] for d in ordered])
        positions = [[d.state_vector[1, 0] * math.cos(d.state_vector[0, 0]),
                      d.state_vector[1, 0] * math.sin(d.state_vector[0, 0])] for d in ordered]
        by_hand.update((0.0, 0.0, 0.0), positions, [d.state_vector[1, 0] for d in ordered],
                       weights=weights)
        weights_seen.extend(weights)
    assert learned.intensity_grid().tobytes() == by_hand.intensity_grid().tobytes()
    assert min(weights_seen) < 0.01 and max(weights_seen) == 1.0  # the target, and clutter


def test_a_posterior_learner_needs_a_tracker_that_reports():
    learner = ClutterMapLearner(weighting="posterior")
    scans = _scans(2, seed=7)
    context_scans = list(_learning_tracker(scans, _map(), []).tracker.detector)
    with pytest.raises(RuntimeError, match="needs the tracker"):
        learner.learn(context_scans[0][0], context_scans[0][1], set())
    with pytest.raises(TypeError, match="^tracker: weighting='posterior'"):
        learner.bind(object())
    tracker = _learning_tracker(scans, _map(), []).tracker
    learner.bind(tracker)  # bound, but the tracker has not run this scan
    with pytest.raises(RuntimeError, match="no clutter probabilities"):
        learner.learn(context_scans[0][0], context_scans[0][1], set())


def test_bad_learners_are_named():
    with pytest.raises(ValueError, match="^gate_radius: "):
        ClutterMapLearner(gate_radius=-1.0)
    with pytest.raises(ValueError, match="^gate_radius: "):
        ClutterMapLearner()  # gates need a radius
    with pytest.raises(ValueError, match="^weighting: "):
        ClutterMapLearner(gate_radius=1.0, weighting="soft")
    with pytest.raises(ValueError, match="^gate_radius: not used"):
        ClutterMapLearner(gate_radius=30.0, weighting="posterior")


@pytest.mark.parametrize("weighting", ["gates", "posterior"])
def test_a_learner_pickles_after_a_run_without_its_tracker(weighting):
    """The bound tracker is not the learner's state: a learner pickles after a run (its
    tracker's detector holds generators), and a LearningTracker binds it again."""
    learner = ClutterMapLearner(weighting=weighting,
                                gate_radius=30.0 if weighting == "gates" else None)
    scans = _scans(5, seed=8)
    wrapped = _learning_tracker(scans, _map(), [learner])
    for _ in wrapped:
        pass
    restored = pickle.loads(pickle.dumps(learner))
    assert repr(restored) == repr(learner) and restored._tracker is None
    again = _learning_tracker(scans, _map(), [restored])
    assert sum(1 for _ in again) == len(scans)  # bound again by the new LearningTracker
    with pytest.raises(ValueError, match="^gate_radius: "):
        DetectionLearner(gate_radius=float("nan"))
    with pytest.raises(ValueError, match="^confirmation: "):
        DetectionLearner(gate_radius=1.0, confirmation=-1)
    with pytest.raises(TypeError, match="^learners: learner 0"):
        LearningTracker(tracker=_learning_tracker([], _map(), []).tracker, learners=[object()])
