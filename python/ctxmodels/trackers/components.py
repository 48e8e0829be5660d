"""The Stone Soup components of the study's two tracker families, from a
:class:`~ctxmodels.trackers.TrackerSpec` (settings in :mod:`ctxmodels.trackers.specs`)."""
from __future__ import annotations

import datetime

import numpy as np
from stonesoup.dataassociator.neighbour import GNNWith2DAssignment
from stonesoup.dataassociator.probability import JPDAwithEHM2
from stonesoup.hypothesiser.distance import DistanceHypothesiser
from stonesoup.hypothesiser.gaussianmixture import GaussianMixtureHypothesiser
from stonesoup.hypothesiser.probability import PDAHypothesiser as StockPDAHypothesiser
from stonesoup.measures import Mahalanobis
from stonesoup.mixturereducer.gaussianmixture import GaussianMixtureReducer
from stonesoup.models.transition.linear import ConstantVelocity
from stonesoup.types.state import GaussianState
from stonesoup.updater.pointprocess import PHDUpdater as StockPHDUpdater

from .specs import (BIRTH_WEIGHT, DUPLICATE_THRESHOLD, GATE_MAHALANOBIS, INIT_STD,
                    JPDA_DELETE_AFTER, JPDA_EXPECTED_MISSES, JPDA_PROB_GATE, MAX_POSITION_STD,
                    MERGE_MAHALANOBIS, POSITION_MAPPING, PRUNE_THRESHOLD, SIGMA_ACC,
                    UNIFORM_CLUTTER, UNIFORM_PD)


def motion_model():
    """Constant velocity per axis; F and Q cached per scan interval (same numbers as the
    stock combined model, without rebuilding them for every prediction)."""
    from ..stonesoup.models import CachedCombinedLinearGaussianTransitionModel
    q = SIGMA_ACC ** 2
    return CachedCombinedLinearGaussianTransitionModel([ConstantVelocity(q), ConstantVelocity(q)])


def position_std_deleter():
    r"""Stone Soup's ``CovarianceBasedDeleter`` deleting a track whose RMS x/y position σ
    exceeds :data:`~ctxmodels.trackers.specs.MAX_POSITION_STD`: the GM-PHD's bound
    (``retain_position_std`` keeps a component while
    :math:`P_{xx} + P_{yy} \le 2\sigma_{\max}^2`). Stone Soup 1.9.1 deletes when the sum of
    the ``mapping``'s diagonal entries of the last state's covariance is strictly greater
    than ``covar_trace_thresh`` (``mapping`` None or empty: the whole trace), so
    with the threshold :math:`2\sigma_{\max}^2` (80000 m², exact in floating point) it deletes
    exactly the tracks the GM-PHD bound would drop."""
    from stonesoup.deleter.error import CovarianceBasedDeleter
    return CovarianceBasedDeleter(covar_trace_thresh=2.0 * MAX_POSITION_STD ** 2,
                                  mapping=list(POSITION_MAPPING))


def jpda_tracker(spec, predictor, updater, detector, fast):
    from stonesoup.deleter.multi import CompositeDeleter
    from stonesoup.deleter.time import UpdateTimeDeleter

    from ..stonesoup import CompositeDeleter as PairwiseCompositeDeleter
    from ..stonesoup import (ArrayJPDATracker, ArrayMultiMeasurementInitiator,
                             DuplicateTrackDeleter, ExpectedMissesDeleter, FastGNNWith2DAssignment,
                             MultiMeasurementInitiator, MultiTargetMixtureTracker,
                             PDAHypothesiser, UpdateTimeStepsDeleter)
    hypothesiser_class = PDAHypothesiser if spec.uses_context else StockPDAHypothesiser
    hypothesiser = hypothesiser_class(predictor, updater, clutter_spatial_density=UNIFORM_CLUTTER,
                                      prob_detect=UNIFORM_PD, prob_gate=JPDA_PROB_GATE)
    if spec.uses_context:
        deleter = CompositeDeleter(intersect=False, deleters=[
            ExpectedMissesDeleter(expected_misses=JPDA_EXPECTED_MISSES, hypothesiser=hypothesiser),
            position_std_deleter()])
    elif spec.delete_window is not None:
        deleter = UpdateTimeDeleter(time_since_update=datetime.timedelta(seconds=spec.delete_window))
    else:
        deleter = UpdateTimeStepsDeleter(time_steps_since_update=spec.delete_after)
    if spec.merge_duplicates:  # (ctxmodels' composite: Stone Soup's asks track by track)
        deleter = PairwiseCompositeDeleter(intersect=False, deleters=[
            deleter, DuplicateTrackDeleter(threshold=DUPLICATE_THRESHOLD, mapping=POSITION_MAPPING)])
    holding = (UpdateTimeStepsDeleter(time_steps_since_update=JPDA_DELETE_AFTER)
               if spec.confirm_window is None else
               UpdateTimeDeleter(time_since_update=datetime.timedelta(seconds=spec.confirm_window)))
    prior = GaussianState(np.zeros((4, 1)), np.diag(INIT_STD ** 2))
    # The array tracker and initiator compute each scan in the Rust core; the component
    # path is the readable reference with the same results.
    initiator = (ArrayMultiMeasurementInitiator if fast else MultiMeasurementInitiator)(
        prior_state=prior, deleter=holding,
        data_associator=(FastGNNWith2DAssignment if fast else GNNWith2DAssignment)(DistanceHypothesiser(
            predictor, updater, Mahalanobis(), missed_distance=GATE_MAHALANOBIS)),
        updater=updater, min_points=spec.min_points)
    return (ArrayJPDATracker if fast else MultiTargetMixtureTracker)(
        initiator=initiator, deleter=deleter, detector=detector,
        data_associator=JPDAwithEHM2(hypothesiser), updater=updater)


def gmphd_tracker(spec, region, predictor, updater, detector, fast):
    from ..stonesoup.gmphd.birth import MeasurementDrivenBirth
    from ..stonesoup.gmphd.array_tracker import ArrayPointProcessTracker
    from ..stonesoup.gmphd import PHDUpdater, PointProcessMultiTargetTracker
    hypothesiser = GaussianMixtureHypothesiser(DistanceHypothesiser(
        predictor, updater, Mahalanobis(), missed_distance=GATE_MAHALANOBIS),
        order_by_detection=True)
    phd_class = PHDUpdater if spec.uses_context else StockPHDUpdater
    phd = phd_class(updater, clutter_spatial_density=UNIFORM_CLUTTER, prob_detection=UNIFORM_PD)
    # (Uniform trackers get plain sets, so even the context-capable fast updater runs stock.)
    reducer = GaussianMixtureReducer(prune_threshold=PRUNE_THRESHOLD,
                                     merge_threshold=MERGE_MAHALANOBIS ** 2)
    birth = MeasurementDrivenBirth(birth_weight=BIRTH_WEIGHT, birth_covar=np.diag(INIT_STD ** 2))
    # The array tracker computes each scan in the Rust core; the component path is the
    # readable reference with the same results.
    tracker_class = ArrayPointProcessTracker if fast else PointProcessMultiTargetTracker
    return tracker_class(
        detector=detector, hypothesiser=hypothesiser, updater=phd, reducer=reducer,
        extraction_threshold=spec.extraction_threshold, birth=birth,
        surveillance_region=region, max_position_std=MAX_POSITION_STD)
