"""Drop-in components for released Stone Soup (1.9.1) that read per-scan detector contexts.

* Feeding: :class:`ContextFeeder` attaches one sensor's :class:`~ctxmodels.DetectorContext`
  to each of its scans; :class:`MultiSensorFeeder` interleaves several sensors' scans in
  time order; :class:`PlatformContextFeeder` gives each scan of Stone Soup's platform
  simulator the context of the radar that made it (:func:`sensor_context`, which decides
  the range edge as the radar does). Either is the ``detector`` of a stock tracker.
* PDA/JPDA (:mod:`~ctxmodels.stonesoup.jpda`): :class:`PDAHypothesiser`, the stock
  hypothesiser with :math:`P_D` per track and :math:`\\lambda` per detection taken from the
  scan's context (stock behaviour without one).
* Track management: :class:`ExpectedMissesDeleter` deletes JPDA tracks on the expected, not
  the counted, number of missed detections; :class:`UpdateTimeStepsDeleter` is the stock
  miss-counting deleter reading only a track's trailing states;
  :class:`DuplicateTrackDeleter` deletes one of two tracks on one target (the
  track-to-track χ² test), in a :class:`CompositeDeleter` (Stone Soup's, which also takes
  members that compare tracks with each other) beside per-track deleters.
* GM-PHD / LCC (:mod:`~ctxmodels.stonesoup.gmphd`): :class:`PHDUpdater`, :class:`LCCUpdater`
  (P_D per component, λ per detection, one array call each per scan) and
  :class:`PointProcessMultiTargetTracker`, which passes each scan's context to the updater
  and adds measurement-driven birth (:class:`MeasurementDrivenBirth`) and a surveillance
  region (:class:`CircularRegion`, or :class:`PoseCentredRegion` following the platform).
* Particle filters: :class:`BernoulliParticleUpdater`, :class:`SMCPHDUpdater` (P_D over all
  particles in one array call).
* Whole scans in the Rust core: :class:`ArrayPointProcessTracker` (GM-PHD) and
  :class:`ArrayJPDATracker` with :class:`ArrayMultiMeasurementInitiator` (JPDA) — the same
  Properties and tracks as the component-path trackers above, which stay as the readable
  reference (each counts the scans it ran on either path, ``array_scans`` and
  ``component_scans``, and raises one :class:`ComponentPathWarning` when a scan falls back);
  :class:`FastGNNWith2DAssignment`, the stock GNN association with all
  track × detection distances of a scan computed at once.
* Reproducibility: :class:`MultiTargetMixtureTracker` and :class:`MultiMeasurementInitiator`
  (the stock JPDA tracker and M-of-N initiator in a stable order); every ctxmodels tracker
  puts a scan's detections in value order (:func:`in_stable_order`) and never lets set
  iteration (memory addresses) decide a result; :func:`in_track_order` sorts tracks by
  content.
* Learning: :class:`LearningTracker` calls learners after each scan of any tracker;
  :class:`ClutterMapLearner` feeds a sensor's :class:`~ctxmodels.ClutterMap` with the
  detections no track explains, :class:`DetectionLearner` its
  :class:`~ctxmodels.DetectionEstimate` with whether its tracks were detected.
* :class:`CachedCombinedLinearGaussianTransitionModel`: F(Δt), Q(Δt) computed once per
  scan interval.
* :class:`AnalyticCartesianToBearingRange`: the stock bearing–range measurement model with
  its exact Jacobian instead of a finite difference, so an extended Kalman filter's output
  does not depend on the last bit of its inputs.
"""
from .feeder import ContextFeeder, MultiSensorFeeder
from .gmphd import (ArrayPointProcessTracker, CircularRegion, LCCUpdater, MeasurementDrivenBirth,
                    PHDUpdater, PointProcessMultiTargetTracker, PoseCentredRegion)
from .gnn import FastGNNWith2DAssignment
from .jpda import (ArrayJPDATracker, ArrayMultiMeasurementInitiator, CompositeDeleter,
                   DuplicateTrackDeleter, ExpectedMissesDeleter, MissesNotWeighedWarning,
                   MultiMeasurementInitiator, MultiTargetMixtureTracker, PDAHypothesiser,
                   UpdateTimeStepsDeleter)
from .learning import ClutterMapLearner, DetectionLearner, LearningTracker
from .models import AnalyticCartesianToBearingRange, CachedCombinedLinearGaussianTransitionModel
from .ordering import in_stable_order, in_track_order
from .particle import BernoulliParticleUpdater, SMCPHDUpdater
from .paths import ComponentPathWarning
from .sensor_adapter import (PlatformContextFeeder, SensorContext, SensorPose, sensor_context,
                             sensor_model_from_stonesoup, sensor_pose)

__all__ = [
    "ArrayPointProcessTracker",
    "AnalyticCartesianToBearingRange",
    "ArrayJPDATracker",
    "ArrayMultiMeasurementInitiator",
    "BernoulliParticleUpdater",
    "CachedCombinedLinearGaussianTransitionModel",
    "CircularRegion",
    "ClutterMapLearner",
    "ComponentPathWarning",
    "CompositeDeleter",
    "DetectionLearner",
    "DuplicateTrackDeleter",
    "LCCUpdater",
    "MeasurementDrivenBirth",
    "PHDUpdater",
    "PointProcessMultiTargetTracker",
    "PoseCentredRegion",
    "SMCPHDUpdater",
    "ContextFeeder",
    "FastGNNWith2DAssignment",
    "ExpectedMissesDeleter",
    "MissesNotWeighedWarning",
    "MultiMeasurementInitiator",
    "MultiSensorFeeder",
    "MultiTargetMixtureTracker",
    "LearningTracker",
    "PDAHypothesiser",
    "UpdateTimeStepsDeleter",
    "in_stable_order",
    "in_track_order",
    "PlatformContextFeeder",
    "SensorContext",
    "SensorPose",
    "sensor_context",
    "sensor_model_from_stonesoup",
    "sensor_pose",
]
