"""Context-aware track initiation: an ExpectedMissesDeleter as the M-of-N initiator's
deleter weighs a holding track's misses by P_D in each scan's context (the context ctxmodels'
MultiTargetMixtureTracker hands its initiator), and says so once when it cannot."""
import datetime
import pickle
import warnings

import numpy as np
import pytest
from stonesoup.dataassociator.neighbour import GNNWith2DAssignment
from stonesoup.dataassociator.probability import JPDA
from stonesoup.hypothesiser.distance import DistanceHypothesiser
from stonesoup.measures import Mahalanobis
from stonesoup.models.measurement.linear import LinearGaussian
from stonesoup.models.transition.linear import (CombinedLinearGaussianTransitionModel,
                                                ConstantVelocity)
from stonesoup.predictor.kalman import KalmanPredictor
from stonesoup.tracker.simple import MultiTargetMixtureTracker as StockMixtureTracker
from stonesoup.types.detection import Detection
from stonesoup.types.state import GaussianState
from stonesoup.updater.kalman import KalmanUpdater

from ctxmodels import (ClutterDensityModel, ConstantPose, DetectionProbabilityModel, Pose,
                       RangeBands, SensorModel)
from ctxmodels.stonesoup import (ContextFeeder, ExpectedMissesDeleter, MissesNotWeighedWarning,
                                 MultiMeasurementInitiator, MultiTargetMixtureTracker,
                                 PDAHypothesiser)

START = datetime.datetime(2026, 1, 1)
MODEL = LinearGaussian(ndim_state=4, mapping=(0, 2), noise_covar=np.eye(2))


def _sensor(reach):
    """P_D 1 out to ``reach`` m, 0 beyond."""
    return SensorModel(detection=DetectionProbabilityModel(factors=[
        RangeBands(edges=(reach,), values=(1.0, 0.0))]),
        clutter=ClutterDensityModel(factors=[1e-6]))


def _scans(target, steps, detected_until):
    """A target standing at ``target``, detected on the first ``detected_until`` scans, 1 s
    apart; the rest are empty scans."""
    return [(START + datetime.timedelta(seconds=k),
             {Detection(np.array([[target[0]], [target[1]]]), timestamp=START
                        + datetime.timedelta(seconds=k), measurement_model=MODEL)}
             if k < detected_until else set()) for k in range(steps)]


def _initiator(deleter, min_points=5):
    transition = CombinedLinearGaussianTransitionModel([ConstantVelocity(0.01)] * 2)
    predictor, updater = KalmanPredictor(transition), KalmanUpdater(MODEL)
    return MultiMeasurementInitiator(
        prior_state=GaussianState(np.zeros((4, 1)), np.diag([1.0, 1.0, 1.0, 1.0])),
        measurement_model=MODEL, deleter=deleter, updater=updater, min_points=min_points,
        data_associator=GNNWith2DAssignment(
            DistanceHypothesiser(predictor, updater, Mahalanobis(), missed_distance=3)))


def _tracker(deleter, reach, scans, stock=False):
    transition = CombinedLinearGaussianTransitionModel([ConstantVelocity(0.01)] * 2)
    predictor, updater = KalmanPredictor(transition), KalmanUpdater(MODEL)
    hypothesiser = PDAHypothesiser(predictor, updater, clutter_spatial_density=1e-6,
                                   prob_detect=0.9)
    feeder = ContextFeeder(reader=scans, sensor_model=_sensor(reach),
                           pose_source=ConstantPose(pose=Pose(x=0.0, y=0.0)))
    tracker_class = StockMixtureTracker if stock else MultiTargetMixtureTracker
    return tracker_class(initiator=_initiator(deleter), detector=feeder,
                         deleter=ExpectedMissesDeleter(expected_misses=3,
                                                       hypothesiser=hypothesiser),
                         data_associator=JPDA(hypothesiser), updater=updater)


def _holding_after(tracker):
    for _ in tracker:
        pass
    return tracker.initiator.holding_tracks


@pytest.mark.parametrize("reach,kept", [(50.0, True), (500.0, False)])
def test_holding_track_misses_weigh_only_where_the_sensor_sees(reach, kept):
    """A holding track with 2 of its 5 points, then 6 empty scans: outside the sensor's reach
    (P_D 0) the misses accrue nothing and it is held; inside (P_D 1) it goes after 3."""
    holding = _holding_after(_tracker(ExpectedMissesDeleter(expected_misses=3), reach,
                                      _scans((100.0, 0.0), 8, detected_until=2)))
    assert (len(holding) == 1) is kept
    if kept:
        (track,) = holding
        assert len(track) == 8  # 2 updates, 6 predictions weighed 0


def test_the_expected_misses_are_the_context_p_d_summed():
    """P_D 1 inside 150 m: 2 detections, then 3 misses of P_D 1 each: deleted when 3 are
    allowed (the sum reaches the threshold), held when 3.5 are."""
    for allowed, survives in ((3.0, False), (3.5, True)):
        holding = _holding_after(_tracker(ExpectedMissesDeleter(expected_misses=allowed), 150.0,
                                          _scans((100.0, 0.0), 5, detected_until=2)))
        assert (len(holding) == 1) is survives


def test_without_a_context_it_warns_once_and_counts():
    """Stone Soup's own tracker hands its initiator no context: the misses are counted with
    default_prob_detect (1), and one MissesNotWeighedWarning says so."""
    tracker = _tracker(ExpectedMissesDeleter(expected_misses=3), 50.0,
                       _scans((100.0, 0.0), 8, detected_until=2), stock=True)
    with pytest.warns(MissesNotWeighedWarning, match="counted, not weighed") as caught:
        holding = _holding_after(tracker)
    assert len([w for w in caught if w.category is MissesNotWeighedWarning]) == 1
    assert not holding  # P_D 0 out there, yet deleted: counted as 1 each


def test_with_the_hypothesisers_record_no_warning():
    """The confirmed tracks' deleter reads its hypothesiser's record: never the fallback."""
    tracker = _tracker(ExpectedMissesDeleter(expected_misses=3), 500.0,
                       _scans((100.0, 0.0), 14, detected_until=6))
    with warnings.catch_warnings():
        warnings.simplefilter("error", MissesNotWeighedWarning)
        for _ in tracker:
            pass


def test_the_record_survives_pickling():
    deleter = ExpectedMissesDeleter(expected_misses=3)
    tracker = _tracker(deleter, 50.0, _scans((100.0, 0.0), 6, detected_until=2))
    holding = _holding_after(tracker)
    (track,) = holding
    copy_deleter, copy_track = pickle.loads(pickle.dumps((tracker.initiator.deleter, track)))
    assert copy_deleter.expected_misses_since_detection(copy_track) == 0.0
    assert tracker.initiator.deleter.expected_misses_since_detection(track) == 0.0


def test_a_bad_context_p_d_is_named():
    class Broken:
        def prob_detection_states(self, states):
            return np.full(len(states), 1.5)

        def clutter_spatial_density_detections(self, detections):
            return np.zeros(len(detections))

    deleter = ExpectedMissesDeleter(expected_misses=3)
    tracker = _tracker(deleter, 50.0, _scans((100.0, 0.0), 4, detected_until=2))
    holding = _holding_after(tracker)
    with pytest.raises(ValueError, match=r"^detector_context: P_D must lie in \[0, 1\]"):
        deleter.delete_tracks(holding, detector_context=Broken())
