"""The study's trackers on anyone's data (``paper_tracker``): plain ``(time, detections)``
streams under any sensor names, a SensorModel per sensor and a pose source give the
experiment runner's results bit for bit, and the surveillance region follows the platform
(asked for each scan's time only, never for a time ahead of the scans)."""
import dataclasses
import datetime
import math

import numpy as np
import pytest
from stonesoup.types.detection import Detection
from stonesoup.models.measurement.linear import LinearGaussian

from ctxmodels import (AngularSector, ClutterDensityModel, ClutterMap, ConstantPose,
                       DetectionEstimate, DetectionProbabilityModel, Mounting, NavigationTrack,
                       Pose, RangeBands, SensorModel)
from ctxmodels.experiment.runner import Job, run_job
from ctxmodels.experiment.scenarios import make_scenario
from ctxmodels.experiment.scoring import score_run, tracks_digest
from ctxmodels.experiment.sensors import paper_sensor_models
from ctxmodels.experiment.trackers import applicable
from ctxmodels.trackers import TRACKERS, PaperTracker, paper_tracker
from ctxmodels.trackers.models import learned_clutter_map
from ctxmodels.stonesoup import (ArrayPointProcessTracker, CircularRegion, ClutterMapLearner,
                                 DetectionLearner, PoseCentredRegion,
                                 PointProcessMultiTargetTracker, in_track_order)

DURATION, SEED = 40.0, 2


class RecordingPoses:
    """A pose source that remembers which times it was asked for."""

    def __init__(self, navigation):
        self.navigation, self.asked = navigation, []

    def pose_at(self, timestamp):
        self.asked.append(timestamp)
        return self.navigation.pose_at(timestamp)


def _renamed(model: SensorModel, name: str) -> SensorModel:
    properties = {key: getattr(model, key) for key in type(model).properties}
    return SensorModel(**{**properties, "name": name})


def _own_data_result(tracker: str, scenario: str, fast: bool = True, duration: float = DURATION):
    """The tracker built the way a user with their own data builds it: lists of
    (time, set of detections) named 'masthead' and 'bow', and a navigation log."""
    run = make_scenario(scenario, SEED, duration)
    streams = {"masthead": [(scan.timestamp, set(scan.detections)) for scan in run.radar_scans],
               "bow": [(scan.timestamp, set(scan.detections)) for scan in run.lidar_scans]}
    paper = paper_sensor_models(land=run.land if TRACKERS[tracker].line_of_sight else ())
    models = {"masthead": _renamed(paper["radar"], "masthead"),
              "bow": _renamed(paper["lidar"], "bow")}
    poses = RecordingPoses(NavigationTrack(timestamps=run.ego.timestamps,
                                           positions=run.ego.positions, headings=run.ego.headings))
    built = paper_tracker(tracker, streams, models, poses, primary="masthead", fast=fast)
    used = [streams["masthead"]] + ([] if TRACKERS[tracker].primary_only else [streams["bow"]])
    tracks, scans = set(), 0
    for time, current in built:
        tracks |= current
        scans += 1
        # Poses are asked for as the scans come (a merge looks one scan ahead per sensor),
        # never for a time further on: no trajectory is needed in advance.
        horizon = max(next((t for t, _ in stream if t > time), time) for stream in used)
        assert not poses.asked or max(poses.asked) <= horizon
    reported = [track for track in in_track_order(tracks) if len(track)]
    return run, scans, reported, poses


CASES = [(name, scenario) for name in TRACKERS for scenario in ("mixed-range", "islands")
         if applicable(name, scenario) and (scenario == "islands") == (name == "gmphd-sight")]


@pytest.mark.parametrize("tracker,scenario", CASES)
def test_every_tracker_on_own_streams_gives_the_runners_results(tracker, scenario):
    runner = run_job(Job(scenario, SEED, tracker, DURATION, digest=True))
    run, scans, reported, poses = _own_data_result(tracker, scenario)
    assert scans == runner.scans
    assert tracks_digest(reported) == runner.digest
    assert runner.track_count > 0  # the comparison compares something
    score = score_run(run, reported)
    for ours, theirs in ((score.hota, runner.hota), (score.gospa, runner.gospa)):
        for field in dataclasses.fields(theirs):
            np.testing.assert_array_equal(getattr(ours, field.name), getattr(theirs, field.name))
    if not TRACKERS[tracker].uses_context and TRACKERS[tracker].family == "jpda":
        assert poses.asked == []  # stock JPDA: no contexts, no region
    else:
        # contexts and the GM-PHD's region ask for the platform's pose at scan times only
        scan_times = {scan.timestamp for scan in run.radar_scans}
        if not TRACKERS[tracker].primary_only:
            scan_times |= {scan.timestamp for scan in run.lidar_scans}
        assert set(poses.asked) == scan_times


def test_the_component_path_matches_too():
    # (12 s: the component path is the slow, readable reference)
    runner = run_job(Job("mixed-range", SEED, "gmphd-context", 12.0, stock=True, digest=True))
    _, _, reported, _ = _own_data_result("gmphd-context", "mixed-range", fast=False, duration=12.0)
    assert runner.track_count > 0
    assert tracks_digest(reported) == runner.digest


def test_what_each_tracker_reads():
    """Built from the same models, each tracker reads what its row of Table I says: the
    uniform ones plain scans (no contexts), P_D-aware the models' P_D with λ = 1e-3, the
    context-aware ones the models as given; radar-only the primary sensor's scans only."""
    from ctxmodels.experiment.sensors import uniform_clutter
    from ctxmodels.stonesoup import ContextFeeder
    pose = ConstantPose(pose=Pose(x=0.0, y=0.0))
    streams = {"a": [], "b": []}
    models = _models()
    for name, spec in TRACKERS.items():
        if spec.line_of_sight:
            continue
        built = paper_tracker(name, streams, models, pose, primary="b")
        learners = ([ClutterMapLearner] if spec.clutter == "learned" else []) \
            + ([DetectionLearner] if spec.pd == "learned" else [])
        assert isinstance(built, PaperTracker) and built.spec is spec
        assert [type(x) for x in built.learners] == learners
        built = built.tracker
        feeders = built.detector.feeders
        expected = ["b"] if spec.primary_only else ["a", "b"]
        if not spec.uses_context:
            assert len(feeders) == len(expected)
            assert all(f is streams[s] for f, s in zip(feeders, expected))
            continue
        assert all(isinstance(f, ContextFeeder) and f.pose_source is pose for f in feeders)
        for feeder, sensor in zip(feeders, expected, strict=True):
            if spec.pd == "learned" and sensor == "b":  # the primary's bands: a fresh estimate
                (estimate,) = feeder.sensor_model.detection.factors
                assert isinstance(estimate, DetectionEstimate) and estimate.trials.sum() == 0
                assert estimate.edges == (0.0, 80.0) and estimate.outside == 0  # the lidar's reach
            else:
                assert feeder.sensor_model.detection == models[sensor].detection
            if spec.clutter == "learned" and sensor == "b":  # the primary's λ: a fresh map
                (learned,) = feeder.sensor_model.clutter.factors
                assert isinstance(learned, ClutterMap) and learned.exposure == 0
                assert learned.edges[1][-1] >= 80.0 and learned.space == "bearing-range"  # the lidar's reach
                continue
            clutter = (uniform_clutter() if spec.clutter == "uniform" and spec.pd == "context"
                       else models[sensor].clutter)
            assert feeder.sensor_model.clutter == clutter
            assert feeder.sensor_model.name == models[sensor].name


def _scenario_streams(duration=20.0):
    run = make_scenario("mixed-range", SEED, duration)
    streams = {"radar": [(scan.timestamp, set(scan.detections)) for scan in run.radar_scans],
               "lidar": [(scan.timestamp, set(scan.detections)) for scan in run.lidar_scans]}
    navigation = NavigationTrack(timestamps=run.ego.timestamps, positions=run.ego.positions,
                                 headings=run.ego.headings)
    return streams, navigation


def _digest(built) -> str:
    tracks = set()
    for _, current in built:
        tracks |= current
    return tracks_digest([track for track in in_track_order(tracks) if len(track)])


def test_sensor_models_only_where_read():
    """The literal and tuned JPDA read no sensor model: None gives the same tracks as the
    paper's models. A GM-PHD reads the sensors' reach unless the region's radius is given;
    the context-aware trackers read P_D and λ. A missing model is named where it is read."""
    streams, navigation = _scenario_streams()
    models = paper_sensor_models()
    for name in ("jpda", "jpda-tuned"):
        given = _digest(paper_tracker(name, streams, models, navigation))
        assert _digest(paper_tracker(name, streams, None, navigation)) == given
        assert _digest(paper_tracker(name, streams, {"radar": models["radar"]}, navigation)) == given
    radius = 1612.0 + 500.0  # what the paper's models give
    assert _digest(paper_tracker("gmphd-uniform", streams, None, navigation, region_radius=radius)) \
        == _digest(paper_tracker("gmphd-uniform", streams, models, navigation))
    with pytest.raises(ValueError, match=r"^sensor_models: gmphd-uniform reads the sensors' P_D "
                                         r"reach .*region_radius.*\['radar', 'lidar'\]"):
        paper_tracker("gmphd-uniform", streams, None, navigation)
    for name in ("gmphd-context", "jpda-context", "gmphd-pd-aware"):
        with pytest.raises(ValueError, match=rf"^sensor_models: {name} reads P_D and λ.*\['lidar'\]"):
            paper_tracker(name, streams, {"radar": models["radar"]}, navigation, region_radius=radius)


def test_an_exhausted_iterator_is_refused_and_a_fresh_one_runs():
    """A generator already read would give a tracker no scans and an empty run without a
    word: refused, naming the sensor. A fresh generator runs as the list does."""
    streams, navigation = _scenario_streams()
    models = paper_sensor_models()
    spent = (scan for scan in streams["lidar"])
    list(spent)
    with pytest.raises(ValueError, match="^streams: sensor 'lidar' is an iterator with no scans left"):
        paper_tracker("gmphd-context", {**streams, "lidar": spent}, models, navigation)
    fresh = {sensor: (scan for scan in stream) for sensor, stream in streams.items()}
    assert _digest(paper_tracker("gmphd-context", fresh, models, navigation)) \
        == _digest(paper_tracker("gmphd-context", streams, models, navigation))


def test_one_return_type_with_tracks_and_mixture():
    """Every tracker comes back as a PaperTracker: its tracks are the running tracker's, its
    mixture the GM-PHD's (None for a JPDA); the learned ones carry their learners."""
    streams, navigation = _scenario_streams(8.0)
    models = paper_sensor_models()
    for name, spec in TRACKERS.items():
        if spec.line_of_sight:
            continue
        built = paper_tracker(name, streams, models, navigation, primary="radar")
        assert isinstance(built, PaperTracker) and built.spec is spec
        for _, tracks in built:
            assert tracks == built.tracks == built.tracker.tracks
        if spec.family == "jpda":
            assert built.gaussian_mixture is None
        else:
            assert built.gaussian_mixture is built.tracker.gaussian_mixture
            assert len(built.gaussian_mixture) > 0
        assert len(built.learners) == (spec.clutter == "learned") + (spec.pd == "learned")
    with pytest.raises(TypeError, match="^spec: "):
        PaperTracker(spec="gmphd-context", tracker=built.tracker)
    with pytest.raises(TypeError, match="^tracker: "):
        PaperTracker(spec=TRACKERS["jpda"], tracker=[])


def _models():
    paper = paper_sensor_models()
    return {"a": paper["radar"], "b": paper["lidar"]}


def test_clear_errors_naming_the_argument():
    pose = ConstantPose(pose=Pose(x=0.0, y=0.0))
    streams = {"a": [], "b": []}
    with pytest.raises(ValueError, match="^name: unknown tracker 'kalman'"):
        paper_tracker("kalman", streams, _models(), pose)
    with pytest.raises(ValueError, match="^streams: no sensor streams"):
        paper_tracker("gmphd-context", {}, _models(), pose)
    with pytest.raises(ValueError, match=r"^sensor_models: .*\['c'\]"):
        paper_tracker("gmphd-context", {"a": [], "c": []}, _models(), pose)
    with pytest.raises(TypeError, match="^pose_source: "):
        paper_tracker("gmphd-context", streams, _models(), object())
    with pytest.raises(ValueError, match="^primary: gmphd-radar-only keeps one sensor"):
        paper_tracker("gmphd-radar-only", streams, _models(), pose)
    with pytest.raises(ValueError, match="^primary: 'c' is not a stream"):
        paper_tracker("gmphd-context", streams, _models(), pose, primary="c")
    for radius in (-1.0, float("nan"), "far", True):
        with pytest.raises(ValueError, match="^region_radius: must be a finite number"):
            paper_tracker("gmphd-context", streams, _models(), pose, region_radius=radius)
    with pytest.raises(ValueError, match="^sensor_models: gmphd-sight needs land"):
        paper_tracker("gmphd-sight", streams, _models(), pose)
    unbounded = {"a": SensorModel(detection=DetectionProbabilityModel(factors=[0.9]),
                                  clutter=ClutterDensityModel(factors=[1e-4]))}
    with pytest.raises(ValueError, match="^region_radius: "):
        paper_tracker("gmphd-context", {"a": []}, unbounded, pose)
    # ... and with the radius given, it builds.
    paper_tracker("gmphd-context", {"a": []}, unbounded, pose, region_radius=3000.0)


def test_default_region_radius_is_the_farthest_reach_plus_the_margin():
    pose = ConstantPose(pose=Pose(x=0.0, y=0.0))
    tracker = paper_tracker("gmphd-context", {"a": [], "b": []}, _models(), pose).tracker
    assert tracker.surveillance_region.radius == 1612.0 + 500.0
    # the lever arm of a mounted sensor counts; the P_D-free uniform trackers get the same
    lidar = SensorModel(detection=DetectionProbabilityModel(factors=[RangeBands(
        edges=(3000.0,), values=(0.5, 0.0))]), clutter=ClutterDensityModel(factors=[1e-3]),
        mounting=Mounting(forward=3.0, left=4.0))
    for name in ("gmphd-context", "gmphd-uniform"):
        tracker = paper_tracker(name, {"a": [], "b": []}, {**_models(), "b": lidar}, pose).tracker
        assert tracker.surveillance_region.radius == 3000.0 + 5.0 + 500.0


# --- the region itself -------------------------------------------------------------------

def _navigation():
    start = datetime.datetime(2026, 1, 1)
    times = [start + datetime.timedelta(seconds=s) for s in (0.0, 10.0)]
    return NavigationTrack(timestamps=times, positions=[[0.0, 0.0], [100.0, 0.0]],
                           headings=[0.0, 0.0]), start


def test_pose_centred_region_is_a_disc_around_the_platform_at_the_scan():
    navigation, start = _navigation()
    region = PoseCentredRegion(pose_source=navigation, radius=30.0)
    at5 = region.at(start + datetime.timedelta(seconds=5))
    assert isinstance(at5, CircularRegion) and at5.centre == (50.0, 0.0) and at5.radius == 30.0
    assert at5.contains([[20.0, 0.0], [19.99, 0.0], [50.0, 30.0]]).tolist() == [True, False, True]
    with pytest.raises(ValueError, match="^radius: "):
        PoseCentredRegion(pose_source=navigation, radius=0.0)
    with pytest.raises(TypeError, match="^pose_source: "):
        PoseCentredRegion(pose_source=None, radius=1.0)


@pytest.mark.parametrize("tracker_class", [PointProcessMultiTargetTracker,
                                           ArrayPointProcessTracker])
def test_trackers_drop_what_the_moving_region_leaves_behind(tracker_class):
    """A target seen near the start, then no detections while the platform moves 100 m
    east: the disc of 30 m around the platform leaves the target's component behind after
    scan 5 (platform at 50 m), on the component and the array path alike."""
    from stonesoup.hypothesiser.distance import DistanceHypothesiser
    from stonesoup.hypothesiser.gaussianmixture import GaussianMixtureHypothesiser
    from stonesoup.measures import Mahalanobis
    from stonesoup.mixturereducer.gaussianmixture import GaussianMixtureReducer
    from stonesoup.models.transition.linear import (CombinedLinearGaussianTransitionModel,
                                                    ConstantVelocity)
    from stonesoup.predictor.kalman import KalmanPredictor
    from stonesoup.updater.kalman import KalmanUpdater
    from ctxmodels.stonesoup import MeasurementDrivenBirth, PHDUpdater

    navigation, start = _navigation()
    model = LinearGaussian(ndim_state=4, mapping=(0, 2), noise_covar=np.eye(2))
    scans = []
    for k in range(11):
        time = start + datetime.timedelta(seconds=k)
        seen = {Detection([[10.0], [0.0]], timestamp=time, measurement_model=model)} if k < 3 else set()
        scans.append((time, seen))
    predictor = KalmanPredictor(CombinedLinearGaussianTransitionModel(
        [ConstantVelocity(0.01), ConstantVelocity(0.01)]))
    updater = KalmanUpdater(measurement_model=None)
    tracker = tracker_class(
        detector=scans, hypothesiser=GaussianMixtureHypothesiser(DistanceHypothesiser(
            predictor, updater, Mahalanobis(), missed_distance=3), order_by_detection=True),
        updater=PHDUpdater(updater, clutter_spatial_density=1e-6, prob_detection=0.3),
        reducer=GaussianMixtureReducer(prune_threshold=1e-9, merge_threshold=16),
        extraction_threshold=0.5,
        birth=MeasurementDrivenBirth(birth_weight=0.5, birth_covar=np.diag([1.0, 1.0, 1.0, 1.0])),
        surveillance_region=PoseCentredRegion(pose_source=navigation, radius=30.0))
    alive = []
    for time, _ in tracker:
        means = [c.state_vector[0, 0] for c in tracker.gaussian_mixture.components]
        alive.append(len(means))
        centre = navigation.pose_at(time).x
        assert all(abs(x - centre) <= 30.0 for x in means)
    assert alive[3] > 0 and alive[-1] == 0


def test_both_paths_agree_when_births_wait_while_the_region_moves():
    """A birth queued inside the region at t = 0 waits for a scan that can see it; at
    t = 0.5 the platform has moved 5 m away (the birth now 62 m off, outside the 60 m disc),
    and it is back at t = 1. The birth met its own scan's region, so it still enters at
    t = 1 on both paths (the array path used to drop it when filtering the queue again)."""
    from stonesoup.hypothesiser.distance import DistanceHypothesiser
    from stonesoup.hypothesiser.gaussianmixture import GaussianMixtureHypothesiser
    from stonesoup.measures import Mahalanobis
    from stonesoup.mixturereducer.gaussianmixture import GaussianMixtureReducer
    from stonesoup.models.transition.linear import (CombinedLinearGaussianTransitionModel,
                                                    ConstantVelocity)
    from stonesoup.predictor.kalman import KalmanPredictor
    from stonesoup.updater.kalman import KalmanUpdater
    from ctxmodels.stonesoup import (ContextFeeder, MeasurementDrivenBirth, MultiSensorFeeder,
                                     PHDUpdater)

    start = datetime.datetime(2026, 1, 1)

    def at(s):
        return start + datetime.timedelta(seconds=s)
    navigation = NavigationTrack(timestamps=[at(0), at(0.5), at(1), at(2)],
                                 positions=[[0, 0], [5, 0], [0, 0], [0, 0]], headings=[0] * 4)
    model = LinearGaussian(ndim_state=4, mapping=(0, 2), noise_covar=np.eye(2))

    def seen(x, s):
        return {Detection([[x], [0.0]], timestamp=at(s), measurement_model=model)}

    far_scans = [(at(0), seen(-57.0, 0)), (at(1), seen(-57.0, 1)), (at(2), seen(-57.0, 2))]
    near_scans = [(at(0.5), seen(6.0, 0.5)), (at(1.5), set())]

    def sensor(reach):
        return SensorModel(detection=DetectionProbabilityModel(factors=[RangeBands(
            edges=(reach,), values=(0.9, 0.0))]), clutter=ClutterDensityModel(factors=[1e-4]))

    def run(tracker_class):
        predictor = KalmanPredictor(CombinedLinearGaussianTransitionModel(
            [ConstantVelocity(0.01), ConstantVelocity(0.01)]))
        updater = KalmanUpdater(measurement_model=None)
        tracker = tracker_class(
            detector=MultiSensorFeeder(feeders=[
                ContextFeeder(reader=far_scans, sensor_model=sensor(100.0), pose_source=navigation),
                ContextFeeder(reader=near_scans, sensor_model=sensor(5.0), pose_source=navigation)]),
            hypothesiser=GaussianMixtureHypothesiser(DistanceHypothesiser(
                predictor, updater, Mahalanobis(), missed_distance=3), order_by_detection=True),
            updater=PHDUpdater(updater, clutter_spatial_density=1e-4, prob_detection=0.9),
            reducer=GaussianMixtureReducer(prune_threshold=1e-9, merge_threshold=16),
            extraction_threshold=0.5,
            birth=MeasurementDrivenBirth(birth_weight=0.5, birth_covar=np.eye(4)),
            surveillance_region=PoseCentredRegion(pose_source=navigation, radius=60.0))
        mixtures = [[(c.state_vector.ravel().tolist(), float(c.weight))
                     for c in tracker.gaussian_mixture.components] for _ in tracker]
        return tracker, mixtures

    component, reference = run(PointProcessMultiTargetTracker)
    array, ours = run(ArrayPointProcessTracker)
    assert array.array_path
    assert [len(m) for m in ours] == [len(m) for m in reference] == [0, 0, 1, 1, 1]
    for a, b in zip(ours, reference):
        for (mean_a, weight_a), (mean_b, weight_b) in zip(a, b):
            np.testing.assert_allclose(mean_a, mean_b, rtol=1e-9, atol=1e-9)
            assert weight_a == pytest.approx(weight_b, rel=1e-9)


def test_the_learned_map_spans_the_bearings_the_radar_sees():
    """``gmphd-learned``'s clutter map leaves the radar's blind sector astern (65°) out of
    its grid — a pooled ring would otherwise learn the sector's missing clutter as a lower
    level — in 59 cells of 5°; a blind sector that does not hold bearing π would split the
    seen interval, so the grid keeps the full circle then."""
    learned = learned_clutter_map(paper_sensor_models()["radar"])
    bearings = np.asarray(learned.edges[0])
    assert len(bearings) == 60 and learned.pooling == "range"
    np.testing.assert_allclose(bearings[[0, -1]], np.radians([-147.5, 147.5]), rtol=1e-12)
    np.testing.assert_allclose(np.diff(bearings), math.radians(5.0), rtol=1e-9)
    for centre in (-math.pi, 3 * math.pi):  # the same sector, other turns
        radar = paper_sensor_models()["radar"]
        factors = [AngularSector.blind(centre, math.radians(65.0)) if isinstance(f, AngularSector)
                   else f for f in radar.detection.factors]
        moved = SensorModel(detection=DetectionProbabilityModel(factors=factors),
                            clutter=radar.clutter, name="radar")
        np.testing.assert_allclose(np.asarray(learned_clutter_map(moved).edges[0]), bearings)
    ahead = [AngularSector.blind(0.0, math.radians(65.0)) if isinstance(f, AngularSector) else f
             for f in paper_sensor_models()["radar"].detection.factors]
    split = SensorModel(detection=DetectionProbabilityModel(factors=ahead),
                        clutter=paper_sensor_models()["radar"].clutter, name="radar")
    np.testing.assert_allclose(np.asarray(learned_clutter_map(split).edges[0])[[0, -1]],
                               [-math.pi, math.pi])


def test_learned_settings_ride_on_the_spec():
    """A variant of a learned tracker is a spec with replaced settings; building it leaves
    the registry's spec, and what it builds, as they were (no module state)."""
    from ctxmodels.trackers.models import ClutterMapSettings, DetectionEstimateSettings
    pose = ConstantPose(pose=Pose(x=0.0, y=0.0))
    spec = TRACKERS["gmphd-learned"]
    variant = dataclasses.replace(
        spec, clutter_map=dataclasses.replace(spec.clutter_map, pooling_scans=10.0,
                                              full_circle=True, weighting="gates"),
        detection_estimate=dataclasses.replace(spec.detection_estimate, band=400.0))

    def primary(built):
        feeder = built.tracker.detector.feeders[0]  # the radar's: the primary
        (learned_map,) = feeder.sensor_model.clutter.factors
        estimate = next(f for f in feeder.sensor_model.detection.factors
                        if isinstance(f, DetectionEstimate))
        return learned_map, estimate, built.learners[0]

    models = paper_sensor_models()
    learned, estimate, learner = primary(paper_tracker(variant, {"radar": [], "lidar": []},
                                                       models, pose, primary="radar"))
    assert learned.pooling_scans == 10.0 and learner.weighting == "gates"
    np.testing.assert_allclose(np.asarray(learned.edges[0])[[0, -1]], [-math.pi, math.pi])
    assert len(estimate.edges) - 1 == round((1612.0 - 50.0) / 400.0)
    learned, estimate, learner = primary(paper_tracker("gmphd-learned", {"radar": [], "lidar": []},
                                                       models, pose, primary="radar"))
    assert spec.clutter_map == ClutterMapSettings()
    assert spec.detection_estimate == DetectionEstimateSettings()
    assert learned.pooling_scans is None and learner.weighting == "posterior"
    assert np.asarray(learned.edges[0])[0] > -math.pi  # the blind sector left out
    assert len(estimate.edges) - 1 == round((1612.0 - 50.0) / 200.0)
