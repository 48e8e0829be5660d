"""The stable order (ctxmodels.stonesoup.ordering): a scan's detections and a run's tracks
are ordered by their values and content only, never by object identity, set order or the
process's hash seed."""
import datetime
import random

import numpy as np
from stonesoup.dataassociator.probability import JPDAwithEHM2
from stonesoup.deleter.time import UpdateTimeStepsDeleter
from stonesoup.hypothesiser.probability import PDAHypothesiser
from stonesoup.predictor.kalman import KalmanPredictor
from stonesoup.types.detection import Detection
from stonesoup.updater.kalman import KalmanUpdater

from ctxmodels import DetectionSet
from ctxmodels.stonesoup import (MultiMeasurementInitiator, MultiTargetMixtureTracker,
                                 in_stable_order, in_track_order)
from ctxmodels.stonesoup.ordering import track_key

from .jpda.setups import MEASUREMENT, TRANSITION, _tracker as tutorial_tracker, tutorial_scans


def _detections(n, seed, context=None):
    rng = np.random.default_rng(seed)
    detections = [Detection(rng.normal(size=(2, 1)), measurement_model=MEASUREMENT,
                            metadata={"area": float(rng.integers(3))}) for _ in range(n)]
    # exact twins of a detection (same vector, metadata and model) and a vector twin with
    # other metadata
    detections.append(Detection(detections[0].state_vector.copy(), measurement_model=MEASUREMENT,
                                metadata=dict(detections[0].metadata)))
    detections.append(Detection(detections[0].state_vector.copy(), measurement_model=MEASUREMENT,
                                metadata={"area": 99.0}))
    return detections


def test_stable_order_depends_on_values_only():
    detections = _detections(30, 1)
    reference = [(d.state_vector.tobytes(), repr(d.metadata)) for d in in_stable_order(detections)]
    for seed in range(5):
        shuffled = list(detections)
        random.Random(seed).shuffle(shuffled)
        # rebuilt objects (other addresses), fed as a set
        rebuilt = {Detection(d.state_vector.copy(), measurement_model=MEASUREMENT,
                             metadata=dict(d.metadata)) for d in shuffled}
        for given in (shuffled, rebuilt):
            order = [(d.state_vector.tobytes(), repr(d.metadata)) for d in in_stable_order(given)]
            assert order == reference
    # the scan's context travels with the ordered detections
    context = object()
    assert in_stable_order(DetectionSet(detections, context)).detector_context is context
    assert in_stable_order(set(detections)).detector_context is None


def test_stable_order_of_converted_rows_is_the_same():
    """The vectors the scan check converted (in the collection's order) give the same order,
    detections and float rows as converting them again; rows of another shape are not used."""
    from ctxmodels.stonesoup.scan_checks import checked_scan_rows

    class Tracker:
        pass
    detections = _detections(30, 2)
    for given in (set(detections), list(detections), detections[:1]):
        _, items, rows = checked_scan_rows(Tracker(), (datetime.datetime(2024, 1, 1), given))
        assert rows is not None
        got, expected = in_stable_order(items, rows), in_stable_order(items)
        assert list(got) == list(expected)
        assert np.array_equal(got.vectors, expected.vectors)
    wrong = np.zeros((len(detections) + 1, 2, 1))
    assert np.array_equal(in_stable_order(detections, wrong).vectors,
                          in_stable_order(detections).vectors)


def _tracker(tracker_cls, initiator_cls, scans):
    predictor, updater = KalmanPredictor(TRANSITION), KalmanUpdater(MEASUREMENT)
    hypothesiser = PDAHypothesiser(predictor, updater, clutter_spatial_density=0.125,
                                   prob_detect=0.9)
    return tutorial_tracker(hypothesiser, UpdateTimeStepsDeleter(3), JPDAwithEHM2,
                            detector=scans, tracker_cls=tracker_cls,
                            initiator_cls=initiator_cls)


def test_track_order_depends_on_content_only():
    scans = tutorial_scans(seed=3, steps=8, clutter_max=3)
    tracker = _tracker(MultiTargetMixtureTracker, MultiMeasurementInitiator, scans)
    seen = {}
    for _, tracks in tracker:
        seen.update((id(t), t) for t in tracks)
    tracks = list(seen.values())
    assert len(tracks) >= 2
    keys = [track_key(t) for t in in_track_order(tracks)]
    for seed in range(3):
        random.Random(seed).shuffle(tracks)
        assert [track_key(t) for t in in_track_order(tracks)] == keys
