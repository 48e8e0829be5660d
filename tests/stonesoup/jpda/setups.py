"""Stone Soup's JPDA tutorial, rebuilt (seeded): its targets, scans, models and tracker, and
sensor models whose contexts hold the tutorial's constant P_D and λ."""
import datetime

import numpy as np
from stonesoup.dataassociator.neighbour import GNNWith2DAssignment
from stonesoup.dataassociator.probability import JPDA
from stonesoup.deleter.time import UpdateTimeStepsDeleter
from stonesoup.hypothesiser.distance import DistanceHypothesiser
from stonesoup.hypothesiser.probability import PDAHypothesiser as StockPDAHypothesiser
from stonesoup.initiator.simple import MultiMeasurementInitiator
from stonesoup.measures import Mahalanobis
from stonesoup.models.measurement.linear import LinearGaussian
from stonesoup.models.transition.linear import (CombinedLinearGaussianTransitionModel,
                                                ConstantVelocity)
from stonesoup.predictor.kalman import KalmanPredictor
from stonesoup.tracker.simple import MultiTargetMixtureTracker
from stonesoup.types.detection import Clutter, TrueDetection
from stonesoup.types.state import GaussianState
from stonesoup.types.track import Track
from stonesoup.updater.kalman import KalmanUpdater

from ctxmodels import (ClutterDensityModel, ConstantPose, DetectionProbabilityModel, Pose,
                       RangeBands, SensorModel)
from ctxmodels.stonesoup import PDAHypothesiser

T0 = datetime.datetime(2024, 5, 1, 12, 0, 0)
ORIGIN = ConstantPose(Pose(x=0.0, y=0.0, heading=0.0))
# Stone Soup's JPDA tutorial: P_D 0.9, clutter spatial density 0.125.
PD, CLUTTER = 0.9, 0.125


def constant_sensor(pd=PD, clutter=CLUTTER, name=""):
    """A sensor model whose context is the stock component's constants."""
    return SensorModel(detection=DetectionProbabilityModel(factors=[pd]),
                       clutter=ClutterDensityModel(factors=[clutter]), name=name)


TRANSITION = CombinedLinearGaussianTransitionModel([ConstantVelocity(0.005)] * 2)
MEASUREMENT = LinearGaussian(ndim_state=4, mapping=(0, 2), noise_covar=np.eye(2) * 0.75)


TRUTH_STEP = 0.2  # seconds: the targets' trajectories are drawn on this grid


def tutorial_truths(seed, duration):
    """Stone Soup's JPDA tutorial targets: two 2-D CV targets crossing half-way, as states
    every TRUTH_STEP seconds."""
    rng = np.random.default_rng(seed)
    dt = datetime.timedelta(seconds=TRUTH_STEP)
    paths = []
    for start in ([0, 1, 0, 1], [0, 1, 20, -1]):
        x = np.array(start, dtype=float).reshape(-1, 1)
        path = [x]
        for _ in range(round(duration / TRUTH_STEP)):
            noise = rng.multivariate_normal(np.zeros(4), TRANSITION.covar(time_interval=dt))
            x = TRANSITION.function(GaussianState(x, np.eye(4)), noise=noise.reshape(-1, 1),
                                    time_interval=dt)
            path.append(x)
        paths.append(path)
    return paths


def tutorial_scans(seed=1991, steps=16, model=MEASUREMENT, with_model=True, period=1.0,
                   clutter_max=5, truth_seed=None):
    """Scans of the tutorial's targets every ``period`` seconds (a multiple of TRUTH_STEP):
    P_D 0.9, and 0..clutter_max-1 clutter points uniform in a 20 m box around each target.
    Sensors given the same ``truth_seed`` observe the same trajectories."""
    paths = tutorial_truths(seed if truth_seed is None else truth_seed, (steps - 1) * period)
    stride = round(period / TRUTH_STEP)
    rng = np.random.default_rng(seed)
    kwargs = {"measurement_model": model} if with_model else {}
    scans = []
    for k in range(steps):
        t = T0 + k * datetime.timedelta(seconds=period)
        detections = set()
        for path in paths:
            x = path[k * stride]
            if rng.random() <= PD:
                z = model.matrix() @ x + rng.multivariate_normal(
                    [0, 0], model.covar()).reshape(-1, 1)
                detections.add(TrueDetection(z, timestamp=t, groundtruth_path=None, **kwargs))
            cx, cy = x[0, 0], x[2, 0]
            for _ in range(rng.integers(clutter_max)):
                z = np.array([[rng.uniform(cx - 10, cx + 10)], [rng.uniform(cy - 10, cy + 10)]])
                detections.add(Clutter(z, timestamp=t, **kwargs))
        scans.append((t, detections))
    return scans


def track_at(x, y, vx=1.0, vy=1.0, t=T0):
    return Track([GaussianState([[x], [vx], [y], [vy]], np.diag([1.5, 0.5, 1.5, 0.5]),
                                timestamp=t)])


def hypothesisers(cls_kwargs):
    predictor, updater = KalmanPredictor(TRANSITION), KalmanUpdater(MEASUREMENT)
    return (StockPDAHypothesiser(predictor, updater, **cls_kwargs),
            PDAHypothesiser(predictor, updater, **cls_kwargs))


# P_D by the range of the predicted position, λ by the range of the detection.
VARYING = SensorModel(
    detection=DetectionProbabilityModel(factors=[RangeBands(edges=(6.0, 14.0),
                                                            values=(0.95, 0.35, 0.2))]),
    clutter=ClutterDensityModel(factors=[RangeBands(edges=(12.0,), values=(0.05, 0.4))]))


def _tracker(hypothesiser, deleter, associator=JPDA, detector=None, tracker_cls=None,
             initiator_cls=MultiMeasurementInitiator):
    """The tutorial's tracker: JPDA-type association, tracks started by a
    MultiMeasurementInitiator (GNN on Mahalanobis distance, two points)."""
    predictor, updater = hypothesiser.predictor, hypothesiser.updater
    initiator = initiator_cls(
        prior_state=GaussianState(np.zeros((4, 1)), np.diag([0, 1, 0, 1])),
        measurement_model=MEASUREMENT,
        deleter=UpdateTimeStepsDeleter(2),
        data_associator=GNNWith2DAssignment(
            DistanceHypothesiser(predictor, updater, Mahalanobis(), missed_distance=3)),
        updater=updater, min_points=2)
    return (tracker_cls or MultiTargetMixtureTracker)(
        initiator=initiator, deleter=deleter, detector=detector,
        data_associator=associator(hypothesiser), updater=updater)
