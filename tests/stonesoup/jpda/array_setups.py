"""The array JPDA path beside the component path: tracker pairs built from the same
components (the JPDA tutorial's, the experiment's, two sensors at two rates), run scan by
scan and compared state by state."""
import numpy as np
from stonesoup.dataassociator.neighbour import GNNWith2DAssignment
from stonesoup.dataassociator.probability import JPDAwithEHM2
from stonesoup.hypothesiser.distance import DistanceHypothesiser
from stonesoup.hypothesiser.probability import PDAHypothesiser as StockPDAHypothesiser
from stonesoup.measures import Mahalanobis
from stonesoup.models.measurement.linear import LinearGaussian
from stonesoup.models.measurement.nonlinear import CartesianToBearingRange
from stonesoup.predictor.kalman import KalmanPredictor
from stonesoup.types.multihypothesis import MultipleHypothesis
from stonesoup.types.numeric import Probability
from stonesoup.types.state import GaussianState
from stonesoup.types.update import Update
from stonesoup.updater.kalman import KalmanUpdater

from ctxmodels.stonesoup import (AnalyticCartesianToBearingRange, ArrayJPDATracker,
                                 ArrayMultiMeasurementInitiator, MultiMeasurementInitiator,
                                 MultiSensorFeeder, MultiTargetMixtureTracker,
                                 UpdateTimeStepsDeleter, in_track_order)

from .setups import CLUTTER, MEASUREMENT, PD, TRANSITION, _tracker, tutorial_scans

RTOL = 1e-9


def _relative(a, b) -> float:
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    scale = np.max(np.abs(b))
    return float(np.max(np.abs(a - b)) / scale) if scale > 0 else float(np.max(np.abs(a)))


def _compare_states(ours, theirs) -> float:
    worst = 0.0
    assert type(ours) is type(theirs) and ours.timestamp == theirs.timestamp
    worst = max(worst, _relative(ours.state_vector, theirs.state_vector),
                _relative(ours.covar, theirs.covar))
    if isinstance(theirs, Update) and isinstance(theirs.hypothesis, MultipleHypothesis):
        mine, stock = list(ours.hypothesis), list(theirs.hypothesis)
        assert len(mine) == len(stock)
        for a, b in zip(mine, stock):
            assert bool(a) == bool(b)
            if b:
                assert a.measurement is b.measurement
                worst = max(worst, _relative(a.measurement_prediction.state_vector,
                                             b.measurement_prediction.state_vector),
                            _relative(a.measurement_prediction.covar,
                                      b.measurement_prediction.covar))
            assert isinstance(a.probability, Probability)
            worst = max(worst, abs(float(a.probability) - float(b.probability)))
            worst = max(worst, _relative(a.prediction.state_vector, b.prediction.state_vector))
    return worst


def run_side_by_side(ours, reference):
    """Iterates both trackers scan by scan; the worst relative difference of any state."""
    worst, scans, most = 0.0, 0, 0
    for (t1, a), (t2, b) in zip(ours, reference):
        assert t1 == t2
        a, b = in_track_order(a), in_track_order(b)
        assert [len(t) for t in a] == [len(t) for t in b], f"tracks differ at {t1}"
        for x, y in zip(a, b):
            assert x.metadata == y.metadata
            worst = max(worst, _compare_states(x.state, y.state))
        scans += 1
        most = max(most, len(a))
    assert most >= 2  # something was tracked
    return worst, scans


def _array_initiator(initiator):
    return ArrayMultiMeasurementInitiator(
        prior_state=initiator.prior_state, deleter=initiator.deleter,
        data_associator=initiator.data_associator, updater=initiator.updater,
        measurement_model=initiator.measurement_model, min_points=initiator.min_points,
        updates_only=initiator.updates_only)


def _component(tracker):
    """The component-path tracker and initiator (the reference) with the components of an
    array ``tracker`` (the experiment builds the array ones)."""
    held = tracker.initiator
    initiator = MultiMeasurementInitiator(
        prior_state=held.prior_state, deleter=held.deleter, data_associator=held.data_associator,
        updater=held.updater, measurement_model=held.measurement_model,
        min_points=held.min_points, updates_only=held.updates_only)
    return MultiTargetMixtureTracker(initiator=initiator, deleter=tracker.deleter,
                                     detector=tracker.detector,
                                     data_associator=tracker.data_associator,
                                     updater=tracker.updater)


def tutorial_pair(associator=JPDAwithEHM2, hypothesiser_cls=StockPDAHypothesiser, scans=None,
                  deleter=lambda h: UpdateTimeStepsDeleter(3), **config):
    config = {"clutter_spatial_density": CLUTTER, "prob_detect": PD, **config}
    scans = tutorial_scans(seed=6, steps=20, clutter_max=5) if scans is None else scans
    trackers = []
    for cls, initiator_cls in ((ArrayJPDATracker, ArrayMultiMeasurementInitiator),
                               (MultiTargetMixtureTracker, MultiMeasurementInitiator)):
        hypothesiser = hypothesiser_cls(KalmanPredictor(TRANSITION), KalmanUpdater(MEASUREMENT),
                                        **config)
        trackers.append(_tracker(hypothesiser, deleter(hypothesiser), associator, detector=scans,
                                 tracker_cls=cls, initiator_cls=initiator_cls))
    return trackers


def _lengths(tracker):
    seen = set()
    for _, tracks in tracker:
        seen |= tracks
    return sorted(len(track) for track in seen)


def _with_radar_model(run, cls):
    """The run's radar detections measured by a ``cls`` bearing–range model (same
    Properties): the scenario's own closed-form one, or Stone Soup's finite difference."""
    models = {}
    for scan in run.radar_scans:
        for detection in scan.detections:
            model = detection.measurement_model
            if id(model) not in models:
                models[id(model)] = cls(ndim_state=model.ndim_state, mapping=model.mapping,
                                        noise_covar=model.noise_covar,
                                        translation_offset=model.translation_offset,
                                        rotation_offset=model.rotation_offset)
            detection.measurement_model = models[id(model)]


def _scenario_pair(tracker, duration, closed_form, scenario="mixed-range"):
    from ctxmodels.experiment import trackers
    from ctxmodels.experiment.scenarios import make_scenario
    run = make_scenario(scenario, 0, duration)
    _with_radar_model(run, AnalyticCartesianToBearingRange if closed_form
                      else CartesianToBearingRange)
    spec = trackers.TRACKERS[tracker]
    ours = trackers.build_tracker(spec, run).tracker
    assert type(ours) is ArrayJPDATracker
    return ours, _component(trackers.build_tracker(spec, run).tracker)


PRIOR = GaussianState(np.zeros((4, 1)), np.diag([0, 1, 0, 1]))


def two_rate_scans():
    """A 1 Hz sensor and a 2.5 Hz one (coinciding every 2 s) on the same two targets, merged
    in time order: the case where a window in time and one in scans differ."""
    coarse = LinearGaussian(4, (0, 2), np.eye(2) * 2.0)
    slow = tutorial_scans(seed=5, steps=12, model=coarse, period=1.0, clutter_max=4,
                          truth_seed=4)
    fast = tutorial_scans(seed=6, steps=28, model=MEASUREMENT, period=0.4, clutter_max=3,
                          truth_seed=4)
    return list(MultiSensorFeeder([slow, fast]))


def pair(deleter, holding_deleter, scans):
    """(array tracker, component tracker): JPDA-EHM2 with the stock PDA hypothesiser, the
    M-of-N initiator (GNN on Mahalanobis distance, two points) holding with
    ``holding_deleter()``, the tracker deleting with ``deleter()``."""
    trackers = []
    for cls, initiator_cls in ((ArrayJPDATracker, ArrayMultiMeasurementInitiator),
                               (MultiTargetMixtureTracker, MultiMeasurementInitiator)):
        predictor, updater = KalmanPredictor(TRANSITION), KalmanUpdater(MEASUREMENT)
        hypothesiser = StockPDAHypothesiser(predictor, updater, clutter_spatial_density=CLUTTER,
                                            prob_detect=PD)
        initiator = initiator_cls(
            prior_state=PRIOR, measurement_model=MEASUREMENT, deleter=holding_deleter(),
            data_associator=GNNWith2DAssignment(
                DistanceHypothesiser(predictor, updater, Mahalanobis(), missed_distance=3)),
            updater=updater, min_points=2)
        trackers.append(cls(initiator=initiator, deleter=deleter(), detector=scans,
                            data_associator=JPDAwithEHM2(hypothesiser), updater=updater))
    return trackers


def _close(a, b) -> bool:
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    if a.shape != b.shape:
        return False
    scale = np.max(np.abs(b)) if b.size else 0.0
    return bool(np.all(np.abs(a - b) <= RTOL * scale))


def assert_same_track(ours, reference):
    """The same states (see test_array_initiator.py's module docstring) of two tracks."""
    assert len(ours.states) == len(reference.states)
    for x, y in zip(ours.states, reference.states):
        assert type(x) is type(y) and x.timestamp == y.timestamp
        assert _close(x.state_vector, y.state_vector) and _close(x.covar, y.covar)
        hx, hy = getattr(x, "hypothesis", None), getattr(y, "hypothesis", None)
        assert (hx is None) == (hy is None)
        if hy is None:
            continue
        assert hx.measurement is hy.measurement
        if hy.prediction is None:  # a birth: the inner initiator's own state
            assert hx.prediction is None
            continue
        assert type(hx) is type(hy) and type(hx.prediction) is type(hy.prediction)
        assert _close(hx.distance, hy.distance)
        assert _close(hx.prediction.state_vector, hy.prediction.state_vector)
        assert _close(hx.prediction.covar, hy.prediction.covar)
        mx, my = hx.measurement_prediction, hy.measurement_prediction
        assert [type(v) for v in mx.state_vector.ravel()] == [type(v) for v in my.state_vector.ravel()]
        assert _close(mx.state_vector, my.state_vector) and _close(mx.covar, my.covar)
        assert _close(mx.cross_covar, my.cross_covar)


def assert_same_tracks(ours, reference):
    ours, reference = in_track_order(ours), in_track_order(reference)
    assert len(ours) == len(reference)
    for a, b in zip(ours, reference):
        assert_same_track(a, b)
