"""Whole trackers configured with ctxmodels components survive Stone Soup's YAML: the
configuration is written out and read back *before* running, and the loaded tracker, run
over the same files, gives the same tracks bit for bit.

Component-level round trips live in core/test_components.py, stonesoup/test_feeder.py,
stonesoup/gmphd/test_tracker.py and stonesoup/jpda/test_hypothesiser_and_deleter.py; this
module checks the assembly: GM-PHD (PointProcessMultiTargetTracker + PHDUpdater +
MeasurementDrivenBirth + CircularRegion + hypothesiser + reducer) and JPDA (PDAHypothesiser +
ExpectedMissesDeleter), both fed by a MultiSensorFeeder of ContextFeeders over stock
YAMLDetectionReaders of a radar and a lidar file.
"""
import datetime
import itertools
import math
import uuid

import numpy as np
import pytest
from stonesoup.dataassociator.neighbour import GNNWith2DAssignment
from stonesoup.dataassociator.probability import JPDA
from stonesoup.deleter.time import UpdateTimeStepsDeleter
from stonesoup.hypothesiser.distance import DistanceHypothesiser
from stonesoup.hypothesiser.gaussianmixture import GaussianMixtureHypothesiser
from stonesoup.initiator.simple import MultiMeasurementInitiator
from stonesoup.measures import Mahalanobis
from stonesoup.mixturereducer.gaussianmixture import GaussianMixtureReducer
from stonesoup.models.measurement.linear import LinearGaussian
from stonesoup.models.transition.linear import (CombinedLinearGaussianTransitionModel,
                                                ConstantVelocity)
from stonesoup.predictor.kalman import KalmanPredictor
from stonesoup.reader.yaml import YAMLDetectionReader
from stonesoup.serialise import YAML
from stonesoup.tracker.simple import MultiTargetMixtureTracker
from stonesoup.types.detection import Detection
from stonesoup.types.state import GaussianState
from stonesoup.updater.kalman import KalmanUpdater

from ctxmodels import (AngularSector, ClutterDensityModel, ConstantPose, DetectionProbabilityModel,
                       NavigationTrack, Pose, RangeBands, SensorModel)
from ctxmodels.stonesoup import (CircularRegion, ContextFeeder, ExpectedMissesDeleter,
                                 MeasurementDrivenBirth, MultiSensorFeeder, PDAHypothesiser,
                                 PHDUpdater, PointProcessMultiTargetTracker)

T0 = datetime.datetime(2024, 5, 1, 12, 0, 0)
MEASUREMENT = LinearGaussian(ndim_state=4, mapping=(0, 2), noise_covar=np.diag([4.0, 4.0]))
TRANSITION = CombinedLinearGaussianTransitionModel([ConstantVelocity(0.5), ConstantVelocity(0.5)])
RADAR = SensorModel(
    detection=DetectionProbabilityModel(factors=[
        RangeBands(edges=(50, 1612), values=(0, 0.4, 0), upper_owns=(False, True)),
        AngularSector.blind(math.pi, math.radians(65))]),
    clutter=ClutterDensityModel(factors=[RangeBands(edges=(1000,), values=(1e-4, 1e-3))]),
    pd_evaluation="cubature", name="radar")
LIDAR = SensorModel(
    detection=DetectionProbabilityModel(factors=[RangeBands(edges=(50, 80), values=(0.95, 0.2, 0.0))]),
    clutter=ClutterDensityModel(factors=[1e-3]), name="lidar")


@pytest.fixture
def counted_tags(monkeypatch):
    """Deterministic uuid4 (component tags, track ids), restarted before each run."""
    def restart():
        counter = itertools.count()
        monkeypatch.setattr(uuid, "uuid4", lambda: uuid.UUID(int=next(counter)))
    return restart


@pytest.fixture
def scan_files(tmp_path):
    """A radar file (1 Hz, two targets 60 m and 400 m out, some clutter) and a lidar file
    (4 Hz, the near target only, every third scan empty), written as stock Stone Soup YAML
    detection files (detections keep their measurement model, which CSV rows cannot)."""
    rng = np.random.default_rng(5)
    targets = [np.array([60.0, 1.0, -20.0, 0.5]), np.array([400.0, -2.0, 100.0, 1.0])]

    def detection(x, y, t):
        return Detection(np.array([[x + rng.normal(0, 2)], [y + rng.normal(0, 2)]]), timestamp=t,
                         measurement_model=MEASUREMENT)

    def position(target, s):
        return target[0] + target[1] * s, target[2] + target[3] * s

    radar, lidar = [], []
    for k in range(12):
        t = T0 + datetime.timedelta(seconds=k)
        scan = {detection(*position(target, k), t) for target in targets}
        if k % 4 == 1:
            scan.add(detection(rng.uniform(-900, 900), rng.uniform(-900, 900), t))
        radar.append({"time": t, "detections": scan})
    for k in range(44):
        t = T0 + datetime.timedelta(seconds=k / 4)
        scan = {detection(*position(targets[0], k / 4), t)} if k % 3 else set()
        lidar.append({"time": t, "detections": scan})
    paths = tmp_path / "radar.yaml", tmp_path / "lidar.yaml"
    for path, docs in zip(paths, (radar, lidar)):
        YAML().dump_all(docs, path)
    return paths


def detector(radar_path, lidar_path):
    navigation = NavigationTrack(timestamps=[T0, T0 + datetime.timedelta(seconds=20)],
                                 positions=[[0.0, 0.0], [20.0, 5.0]], headings=[0.0, 0.3])
    return MultiSensorFeeder([
        ContextFeeder(YAMLDetectionReader(radar_path), sensor_model=RADAR, pose_source=navigation),
        ContextFeeder(YAMLDetectionReader(lidar_path), sensor_model=LIDAR,
                      pose_source=ConstantPose(Pose(x=0, y=0)))])


def phd_tracker(paths):
    updater = KalmanUpdater(MEASUREMENT)
    hypothesiser = GaussianMixtureHypothesiser(
        DistanceHypothesiser(KalmanPredictor(TRANSITION), updater, Mahalanobis(), missed_distance=3),
        order_by_detection=True)
    return PointProcessMultiTargetTracker(
        detector=detector(*paths), hypothesiser=hypothesiser,
        updater=PHDUpdater(updater, prob_survival=0.99),
        reducer=GaussianMixtureReducer(prune_threshold=1e-6, merge_threshold=5),
        extraction_threshold=0.5,
        birth=MeasurementDrivenBirth(birth_weight=1e-2),
        surveillance_region=CircularRegion(centre=(0.0, 0.0), radius=2000.0),
        max_position_std=500.0)


def jpda_tracker(paths):
    predictor, updater = KalmanPredictor(TRANSITION), KalmanUpdater(MEASUREMENT)
    hypothesiser = PDAHypothesiser(predictor, updater, clutter_spatial_density=1e-3, prob_detect=0.9)
    initiator = MultiMeasurementInitiator(
        prior_state=GaussianState(np.zeros((4, 1)), np.diag([0.0, 4.0, 0.0, 4.0])),
        measurement_model=MEASUREMENT, deleter=UpdateTimeStepsDeleter(2),
        data_associator=GNNWith2DAssignment(
            DistanceHypothesiser(predictor, updater, Mahalanobis(), missed_distance=3)),
        updater=updater, min_points=2)
    return MultiTargetMixtureTracker(
        initiator=initiator, deleter=ExpectedMissesDeleter(expected_misses=3, hypothesiser=hypothesiser),
        detector=detector(*paths), data_associator=JPDA(hypothesiser), updater=updater)


def run(tracker):
    """Per scan: time, and each track's latest state vector and covariance (exact bits)."""
    out = []
    for time, tracks in tracker:
        states = sorted((t.state_vector.ravel().tobytes(), t.covar.tobytes()) for t in tracks)
        out.append((time, states))
    return out


@pytest.mark.parametrize("make", [phd_tracker, jpda_tracker], ids=["gm-phd", "jpda"])
def test_tracker_round_trips_through_yaml_and_runs_identically(make, scan_files,
                                                                        counted_tags):
    original = make(scan_files)
    text = YAML().dumps(original)
    for name in ("PHDUpdater", "MeasurementDrivenBirth", "CircularRegion", "ContextFeeder",
                 "MultiSensorFeeder", "SensorModel", "NavigationTrack", "AngularSector"):
        assert name in text or make is jpda_tracker, name
    if make is phd_tracker:
        assert "max_position_std: 500.0" in text
    if make is jpda_tracker:
        assert "PDAHypothesiser" in text and "ExpectedMissesDeleter" in text
    loaded = YAML().load(text)
    assert YAML().dumps(loaded) == text  # a fixed point: nothing lost or added
    # The same configuration built afresh: the loaded copy must match it, not only the
    # original (guards against state shared between original and copy).
    fresh = make(scan_files)

    counted_tags()
    reference = run(original)
    for copy_ in (loaded, fresh):
        counted_tags()
        assert run(copy_) == reference
    # The run did something worth comparing: scans from both sensors, tracks confirmed.
    assert len(reference) == 12 + 44
    assert sum(len(states) for _, states in reference) > 20


def test_loaded_tracker_carries_equal_sensor_models(scan_files):
    loaded = YAML().load(YAML().dumps(phd_tracker(scan_files)))
    feeders = loaded.detector.feeders
    assert [f.sensor_model for f in feeders] == [RADAR, LIDAR]
    assert feeders[0].sensor_model is not RADAR  # really rebuilt, not shared
    pose = Pose(x=5.0, y=-3.0, heading=2.0)
    means = np.random.default_rng(2).uniform(-1700, 1700, (500, 4))
    covars = np.tile(np.eye(4) * 50.0, (500, 1, 1))
    np.testing.assert_array_equal(feeders[0].sensor_model.context(pose).prob_detection_array(means, covars),
                                  RADAR.context(pose).prob_detection_array(means, covars))
