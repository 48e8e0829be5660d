"""
JPDA with a slow radar and a fast short-range sensor: starting tracks the radar alone sees
===========================================================================================

A radar scanning at 0.5 Hz (P_D 0.85 from 100 m to 2.5 km, blind 70° astern) and a 5 Hz
short-range sensor (P_D 0.9 out to 150 m) feed one JPDA. A target 1 km away is seen by
the radar only: between two radar scans come ten short-range scans that cannot see it.

The confirmed tracks' deleter is context-aware
(:class:`~ctxmodels.stonesoup.ExpectedMissesDeleter` over the context-aware
:class:`~ctxmodels.stonesoup.PDAHypothesiser`), but a track has to be confirmed first: the
M-of-N initiator's holding tracks are predicted by a distance hypothesiser that knows
nothing of P_D. With Stone Soup's ``UpdateTimeStepsDeleter(3)`` as the initiator's
deleter, every empty short-range scan counts as a miss of every holding track, so a
holding track the radar started is gone long before the radar's next scan: the far
target is never confirmed. An :class:`~ctxmodels.stonesoup.ExpectedMissesDeleter` as the
initiator's deleter weighs those misses by P_D in each scan's context — which ctxmodels'
:class:`~ctxmodels.stonesoup.MultiTargetMixtureTracker` hands to its
:class:`~ctxmodels.stonesoup.MultiMeasurementInitiator` — so the short-range scans cost a
holding track 1 km away nothing, and the radar's second and third detections confirm it.
"""

# %%
# Two sensors on one fixed platform, two targets
# ----------------------------------------------
import datetime
import math

import numpy as np
from stonesoup.dataassociator.neighbour import GNNWith2DAssignment
from stonesoup.dataassociator.probability import JPDA
from stonesoup.deleter.error import CovarianceBasedDeleter
from stonesoup.deleter.multi import CompositeDeleter
from stonesoup.hypothesiser.distance import DistanceHypothesiser
from stonesoup.measures import Mahalanobis
from stonesoup.models.measurement.linear import LinearGaussian
from stonesoup.models.measurement.nonlinear import CartesianToBearingRange
from stonesoup.models.transition.linear import (CombinedLinearGaussianTransitionModel,
                                                ConstantVelocity)
from stonesoup.predictor.kalman import KalmanPredictor
from stonesoup.types.detection import Clutter, TrueDetection
from stonesoup.types.state import GaussianState
from stonesoup.updater.kalman import ExtendedKalmanUpdater

from ctxmodels import (AngularSector, ClutterDensityModel, ConstantPose, DetectionProbabilityModel,
                       Pose, RangeBands, SensorModel)
from ctxmodels.stonesoup import (ArrayJPDATracker, ArrayMultiMeasurementInitiator,
                                 ContextFeeder, ExpectedMissesDeleter, FastGNNWith2DAssignment,
                                 MultiMeasurementInitiator, MultiSensorFeeder,
                                 MultiTargetMixtureTracker, PDAHypothesiser,
                                 UpdateTimeStepsDeleter)

start = datetime.datetime(2026, 1, 1)
DURATION = 120  # s
RADAR_PD, RADAR_CLUTTER = 0.85, 1e-4  # λ per rad·m
SHORT_PD, SHORT_REACH, SHORT_CLUTTER = 0.9, 150.0, 0.5 / (math.pi * 150.0 ** 2)  # λ per m²
radar = SensorModel(name="radar", detection=DetectionProbabilityModel(factors=[
    RangeBands(edges=(100.0, 2500.0), values=(0.0, RADAR_PD, 0.0)),
    AngularSector.blind(centre=math.pi, width=math.radians(70))]),
    clutter=ClutterDensityModel(factors=[RADAR_CLUTTER]))
short_range = SensorModel(name="short", detection=DetectionProbabilityModel(factors=[
    RangeBands(edges=(SHORT_REACH,), values=(SHORT_PD, 0.0))]),
    clutter=ClutterDensityModel(factors=[SHORT_CLUTTER]))
platform = ConstantPose(pose=Pose(x=0.0, y=0.0))
bearing_range = CartesianToBearingRange(ndim_state=4, mapping=(0, 2),
                                        noise_covar=np.diag([math.radians(0.5) ** 2, 5.0 ** 2]))
position = LinearGaussian(ndim_state=4, mapping=(0, 2), noise_covar=np.eye(2) * 0.5 ** 2)


def truth(name, t):
    """Where each target is ``t`` s after the start: 'far' 1 km ahead, 'near' 60 m off."""
    if name == "far":
        return np.array([900.0 - 2.0 * t, 300.0 + 3.0 * t])
    return np.array([60.0 + 0.5 * t, -40.0 + 0.3 * t])


def radar_scans(seed=3):
    rng = np.random.default_rng(seed)
    out = []
    for t in np.arange(0.0, DURATION, 2.0):
        time = start + datetime.timedelta(seconds=float(t))
        detections = set()
        for name in ("far", "near"):
            x, y = truth(name, t)
            if radar.detection.evaluate(Pose(x=0.0, y=0.0), np.array([[x, 0.0, y, 0.0]]))[0] \
                    > rng.random():
                z = np.array([[math.atan2(y, x)], [math.hypot(x, y)]]) \
                    + rng.normal(0.0, [[math.radians(0.5)], [5.0]])
                detections.add(TrueDetection(z, timestamp=time, measurement_model=bearing_range,
                                             groundtruth_path=None))
        # clutter: uniform over the seen bearings (290°) and 100 m–2.5 km
        for _ in range(rng.poisson(RADAR_CLUTTER * math.radians(290) * 2400.0)):
            bearing = math.remainder(rng.uniform(math.radians(-145), math.radians(145)), math.tau)
            z = np.array([[bearing], [rng.uniform(100.0, 2500.0)]])
            detections.add(Clutter(z, timestamp=time, measurement_model=bearing_range))
        out.append((time, detections))
    return out


def short_range_scans(seed=4):
    rng = np.random.default_rng(seed)
    out = []
    for t in np.arange(0.0, DURATION, 0.2):
        time = start + datetime.timedelta(seconds=float(t))
        detections = set()
        for name in ("far", "near"):
            x, y = truth(name, t)
            if math.hypot(x, y) < SHORT_REACH and rng.random() < SHORT_PD:
                z = np.array([[x], [y]]) + rng.normal(0.0, 0.5, (2, 1))
                detections.add(TrueDetection(z, timestamp=time, measurement_model=position,
                                             groundtruth_path=None))
        for _ in range(rng.poisson(0.5)):  # 0.5 clutter points a scan over the 150 m disc
            r, a = SHORT_REACH * math.sqrt(rng.random()), rng.uniform(-math.pi, math.pi)
            detections.add(Clutter(np.array([[r * math.cos(a)], [r * math.sin(a)]]),
                                   timestamp=time, measurement_model=position))
        out.append((time, detections))
    return out


# %%
# One JPDA, two initiator deleters
# --------------------------------
# Everything but the initiator's deleter is the README's context-aware JPDA: the
# context-aware hypothesiser, expected misses (3) or an uncertain position (σ > 200 m)
# to delete a confirmed track.
def jpda(initiator_deleter, array=False):
    """The JPDA; ``array``: the same components' array drop-ins (whole scans in the Rust
    core, the same tracks to rounding)."""
    transition = CombinedLinearGaussianTransitionModel([ConstantVelocity(0.05)] * 2)
    predictor, updater = KalmanPredictor(transition), ExtendedKalmanUpdater(measurement_model=None)
    hypothesiser = PDAHypothesiser(predictor, updater, clutter_spatial_density=RADAR_CLUTTER,
                                   prob_detect=RADAR_PD, prob_gate=0.99)
    deleter = CompositeDeleter(intersect=False, deleters=[
        ExpectedMissesDeleter(expected_misses=3, hypothesiser=hypothesiser),
        CovarianceBasedDeleter(covar_trace_thresh=2 * 200.0 ** 2, mapping=[0, 2])])
    initiator = (ArrayMultiMeasurementInitiator if array else MultiMeasurementInitiator)(
        prior_state=GaussianState(np.zeros((4, 1)), np.diag([10.0, 15.0, 10.0, 15.0]) ** 2),
        deleter=initiator_deleter, updater=updater, min_points=3,
        data_associator=(FastGNNWith2DAssignment if array else GNNWith2DAssignment)(
            DistanceHypothesiser(predictor, updater, Mahalanobis(), missed_distance=3)))
    feeder = MultiSensorFeeder(feeders=[
        ContextFeeder(reader=radar_scans(), sensor_model=radar, pose_source=platform),
        ContextFeeder(reader=short_range_scans(), sensor_model=short_range, pose_source=platform)])
    return (ArrayJPDATracker if array else MultiTargetMixtureTracker)(
        initiator=initiator, deleter=deleter, detector=feeder,
        data_associator=JPDA(hypothesiser), updater=updater)


def held(tracker, name, within=50.0):
    """The share of radar scans after which some confirmed track is within ``within`` m
    of target ``name``."""
    radar_times = {time for time, _ in radar_scans()}
    hits = []
    for time, tracks in tracker:
        if time in radar_times:
            where = truth(name, (time - start).total_seconds())
            hits.append(any(np.hypot(*(track.state_vector[[0, 2], 0] - where)) <= within
                            for track in tracks))
    return float(np.mean(hits))


# %%
# The far target: never confirmed, or held
# ----------------------------------------
# The near target, seen by both sensors, is held either way.
for label, initiator_deleter in (
        ("UpdateTimeStepsDeleter(3)", UpdateTimeStepsDeleter(time_steps_since_update=3)),
        ("ExpectedMissesDeleter(3)", ExpectedMissesDeleter(expected_misses=3))):
    far, near = held(jpda(initiator_deleter), "far"), held(jpda(initiator_deleter), "near")
    print(f"initiator deleter {label}: far target held on {far:.0%} of radar scans, "
          f"near target on {near:.0%}")

# %%
# The array drop-ins
# ------------------
# ``ArrayJPDATracker`` with ``ArrayMultiMeasurementInitiator`` runs each scan in the Rust
# core and hands the initiator each scan's context too: the same tracks, to rounding.
tracker = jpda(ExpectedMissesDeleter(expected_misses=3), array=True)
print(f"array drop-ins, initiator deleter ExpectedMissesDeleter(3): far target held on "
      f"{held(tracker, 'far'):.0%} of radar scans, every initiator scan in the core: "
      f"{tracker.initiator.component_calls == 0}")
