"""
JPDA through a blind sector: counting misses the sensor could not have had
==========================================================================

A sensor blind in a 90° sector watches a target that crosses the sector for 12 scans.
Stone Soup's ``UpdateTimeStepsDeleter`` counts every scan without a detection as a miss
and deletes the track after a few; when the target comes out, a new track has to start
over. ctxmodels' :class:`~ctxmodels.stonesoup.ExpectedMissesDeleter` sums the detection
probability each scan had for the track instead — P_D = 0 in the blind sector accrues
nothing — so the track coasts through and keeps its identity.

Both trackers are the same JPDA (Stone Soup's ``JPDA`` over ctxmodels'
context-aware :class:`~ctxmodels.stonesoup.PDAHypothesiser`, each scan carrying its
context); only the deleter differs.
"""

# %%
# Scans of a target crossing the blind sector
# -------------------------------------------
import datetime
import math

import numpy as np
from stonesoup.dataassociator.neighbour import GNNWith2DAssignment
from stonesoup.dataassociator.probability import JPDA
from stonesoup.hypothesiser.distance import DistanceHypothesiser
from stonesoup.measures import Mahalanobis
from stonesoup.models.measurement.linear import LinearGaussian
from stonesoup.models.transition.linear import (CombinedLinearGaussianTransitionModel,
                                                ConstantVelocity)
from stonesoup.predictor.kalman import KalmanPredictor
from stonesoup.types.detection import Clutter, TrueDetection
from stonesoup.types.state import GaussianState
from stonesoup.updater.kalman import KalmanUpdater

from ctxmodels import (AngularSector, ClutterDensityModel, ConstantPose, DetectionProbabilityModel,
                       Pose, SensorModel)
from ctxmodels.stonesoup import (ContextFeeder, ExpectedMissesDeleter,
                                 MultiMeasurementInitiator, MultiTargetMixtureTracker,
                                 PDAHypothesiser, UpdateTimeStepsDeleter)

start = datetime.datetime(2026, 1, 1)
prob_detection, clutter_density = 0.9, 1e-5
# blind between bearings 45° and 135° (north), seen everywhere else
sensor = SensorModel(
    detection=DetectionProbabilityModel(factors=[
        prob_detection, AngularSector.blind(centre=math.pi / 2, width=math.pi / 2)]),
    clutter=ClutterDensityModel(factors=[clutter_density]))
measurement = LinearGaussian(ndim_state=4, mapping=(0, 2), noise_covar=np.eye(2) * 4.0)
transition = CombinedLinearGaussianTransitionModel([ConstantVelocity(0.01)] * 2)


def scans(steps=35, seed=11):
    """A target going east at 25 m/s, 150 m north of the sensor: blind while its bearing
    is between 45° and 135° (x from -150 to 150 m: 12 scans)."""
    rng = np.random.default_rng(seed)
    out = []
    for k in range(steps):
        time = start + datetime.timedelta(seconds=k)
        x, y = -400.0 + 25.0 * k, 150.0
        detections = set()
        seen = not (math.pi / 4 <= math.atan2(y, x) <= 3 * math.pi / 4)
        if seen and rng.random() < prob_detection:
            z = np.array([[x], [y]]) + rng.normal(0, 2.0, (2, 1))
            detections.add(TrueDetection(z, timestamp=time, measurement_model=measurement,
                                         groundtruth_path=None))
        for _ in range(rng.poisson(0.5)):  # sparse clutter around the target
            z = np.array([[x], [y]]) + rng.uniform(-60, 60, (2, 1))
            detections.add(Clutter(z, timestamp=time, measurement_model=measurement))
        out.append((time, detections))
    return out


# %%
# The two JPDA trackers
# ---------------------
def jpda(deleter_kind):
    predictor, updater = KalmanPredictor(transition), KalmanUpdater(measurement)
    hypothesiser = PDAHypothesiser(predictor, updater, clutter_spatial_density=clutter_density,
                                   prob_detect=prob_detection)
    deleter = (UpdateTimeStepsDeleter(time_steps_since_update=4) if deleter_kind == "stock"
               else ExpectedMissesDeleter(expected_misses=4, hypothesiser=hypothesiser))
    initiator = MultiMeasurementInitiator(
        prior_state=GaussianState(np.zeros((4, 1)), np.diag([0, 30, 0, 30]) ** 2),
        measurement_model=measurement, deleter=UpdateTimeStepsDeleter(2), updater=updater,
        data_associator=GNNWith2DAssignment(
            DistanceHypothesiser(predictor, updater, Mahalanobis(), missed_distance=3)),
        min_points=3)
    feeder = ContextFeeder(reader=scans(), sensor_model=sensor,
                           pose_source=ConstantPose(pose=Pose(x=0.0, y=0.0)))
    return MultiTargetMixtureTracker(initiator=initiator, deleter=deleter, detector=feeder,
                                     data_associator=JPDA(hypothesiser), updater=updater)


# %%
# One track, or two
# -----------------
# The stock deleter drops the track a few scans into the blind sector and the initiator
# starts a new one after it; the expected-misses deleter keeps the first one, which picks
# the target up again where it comes out.
for kind in ("stock", "expected misses"):
    tracker = jpda(kind)
    started = {}
    for time, tracks in tracker:
        for track in tracks:
            started.setdefault(track.id, time)
    final = next(iter(tracker.tracks))
    x, y = final.state_vector[0, 0], final.state_vector[2, 0]
    truth_x = -400.0 + 25.0 * 34
    print(f"{kind}: {len(started)} track(s) over the run, {len(tracker.tracks)} alive at "
          f"the end, started at {(started[final.id] - start).seconds} s, "
          f"{math.hypot(x - truth_x, y - 150.0):.0f} m from the target")
