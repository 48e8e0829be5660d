"""ctxmodels' trackers hand each scan's detector context to every component that
declares a ``detector_context`` parameter on ``hypothesise``, ``associate``, ``initiate``
or ``delete_tracks`` (as the upstream DetectorContext proposal's trackers hand it on):
recording components see each scan's context, in scan order, and nothing on a scan
without one. Stock components, which take only ``**kwargs``, are called as stock (their
chains below were not written for it: 1.9.1's CompositeHypothesiser takes no ``**kwargs``).
The numbers do not change (the stock-equivalence tests of each tracker run with contexts);
the array paths stay array paths."""
from __future__ import annotations

import contextlib
import inspect

import pytest
from stonesoup.dataassociator.probability import JPDA, JPDAwithEHM2
from stonesoup.deleter.base import Deleter
from stonesoup.hypothesiser.gaussianmixture import GaussianMixtureHypothesiser
from stonesoup.hypothesiser.probability import PDAHypothesiser as StockPDAHypothesiser

from ctxmodels import DetectionSet
from ctxmodels.stonesoup import (ArrayJPDATracker, ArrayMultiMeasurementInitiator,
                                 ArrayPointProcessTracker, ComponentPathWarning,
                                 MultiMeasurementInitiator,
                                 MultiTargetMixtureTracker, PHDUpdater,
                                 PointProcessMultiTargetTracker, UpdateTimeStepsDeleter)
from .gmphd.setups import (CLUTTER_DENSITY, constant_context, tutorial_scans as phd_scans,
                           tutorial_tracker)
from .jpda.setups import (CLUTTER, PD, T0, _tracker, constant_sensor, hypothesisers, track_at,
                          tutorial_scans as jpda_scans)

NONE = "no detector_context keyword"


def _recording(base, method):
    """A subclass of ``base`` whose ``method`` declares ``detector_context`` (so a tracker
    hands it over) and notes what it was given (NONE without it) in ``seen``."""
    def recorded(self, *args, detector_context=NONE, **kwargs):
        self.__dict__.setdefault("seen", []).append(detector_context)
        if detector_context is not NONE:
            kwargs["detector_context"] = detector_context
        return getattr(super(cls, self), method)(*args, **kwargs)
    # the base method's signature plus the keyword, for trackers that inspect it
    signature = inspect.signature(getattr(base, method))
    if "detector_context" not in signature.parameters:
        parameters = [p for p in signature.parameters.values() if p.kind != p.VAR_KEYWORD]
        parameters.append(inspect.Parameter("detector_context", inspect.Parameter.KEYWORD_ONLY,
                                            default=None))
        parameters += [p for p in signature.parameters.values() if p.kind == p.VAR_KEYWORD]
        signature = signature.replace(parameters=parameters)
    recorded.__signature__ = signature
    cls = type(f"Recording{base.__name__}", (base,), {method: recorded})
    return cls


def _with_contexts(scans, make_context, plain=(2,)):
    """Each scan as a DetectionSet with its own context object, except the scans at
    ``plain`` (plain sets); the contexts in scan order (None for a plain scan)."""
    fed, contexts = [], []
    for k, (time, detections) in enumerate(scans):
        if k in plain:
            fed.append((time, set(detections)))
            contexts.append(None)
        else:
            context = make_context(time)
            fed.append((time, DetectionSet(detections, detector_context=context)))
            contexts.append(context)
    return fed, contexts


def _expected(contexts):
    return [NONE if c is None else c for c in contexts]


@pytest.mark.parametrize("tracker_cls", [PointProcessMultiTargetTracker, ArrayPointProcessTracker])
def test_point_process_trackers_hand_the_context_to_hypothesiser_and_updater(tracker_cls):
    starts, scans = phd_scans(steps=6)
    tracker = tutorial_tracker(tracker_cls, PHDUpdater, starts)
    hypothesiser = tracker.hypothesiser
    tracker.hypothesiser = _recording(GaussianMixtureHypothesiser, "hypothesise")(
        hypothesiser.hypothesiser, order_by_detection=True)
    tracker.updater = _recording(PHDUpdater, "update")(
        tracker.updater.updater, clutter_spatial_density=CLUTTER_DENSITY,
        prob_detection=0.9, prob_survival=1 - 0.005)
    fed, contexts = _with_contexts(scans, lambda t: constant_context(0.9, CLUTTER_DENSITY, t))
    # (recording subclasses are not the core's configuration: the array tracker's component
    # path runs, as intended here, and says so once)
    with (pytest.warns(ComponentPathWarning, match="hypothesiser is not")
          if tracker_cls is ArrayPointProcessTracker else contextlib.nullcontext()):
        for time, detections in fed:
            tracker.update_tracker(time, detections)
    assert tracker.hypothesiser.seen == _expected(contexts)
    assert tracker.updater.seen == _expected(contexts)
    assert len(tracker.tracks) > 0  # it tracked


def _mixture_tracker(tracker_cls, initiator_cls, associator):
    _, ours = hypothesisers(dict(clutter_spatial_density=CLUTTER, prob_detect=PD))
    deleter = _recording(_NeverDeleter, "delete_tracks")()
    tracker = _tracker(ours, deleter, associator=associator, tracker_cls=tracker_cls,
                       initiator_cls=_recording(initiator_cls, "initiate"))
    return tracker


class _NeverDeleter(Deleter):
    """A deleter no plan of the array tracker knows: it is called as a component."""

    def check_for_deletion(self, track, **kwargs):
        return False


def _run_jpda(tracker):
    sensor = constant_sensor()
    fed, contexts = _with_contexts(jpda_scans(steps=8),
                                   lambda t: sensor.context((0.0, 0.0, 0.0), t))
    for time, detections in fed:
        tracker.update_tracker(time, detections)
    return contexts


def test_mixture_tracker_hands_the_context_to_associator_deleter_and_initiator():
    tracker = _mixture_tracker(MultiTargetMixtureTracker, MultiMeasurementInitiator,
                               _recording(JPDA, "associate"))
    contexts = _run_jpda(tracker)
    expected = _expected(contexts)
    assert tracker.data_associator.seen == expected
    assert tracker.deleter.seen == expected
    assert tracker.initiator.seen == expected
    assert len(tracker.tracks) > 0


def test_array_jpda_tracker_hands_the_context_on_and_stays_on_its_array_paths():
    tracker = _mixture_tracker(ArrayJPDATracker, ArrayMultiMeasurementInitiator, JPDAwithEHM2)
    contexts = _run_jpda(tracker)
    expected = _expected(contexts)
    assert tracker.deleter.seen == expected
    assert tracker.initiator.seen == expected
    # The context reached them on the array paths (one core call per scan), not by
    # sending the scans to the component path.
    assert tracker.array_scans == len(contexts) and tracker.component_scans == 0
    assert tracker.initiator.array_calls == len(contexts)
    assert tracker.initiator.component_calls == 0
    assert len(tracker.tracks) > 0


def test_stock_components_below_an_associator_take_the_keyword_unchanged():
    """Forwarded into a stock JPDA over Stone Soup's own PDAHypothesiser, the keyword goes
    down its predictor and updater calls (all ``**kwargs``) and changes nothing.
    (ctxmodels' PDAHypothesiser reading it in preference to the detections' own context is
    tested in jpda/test_hypothesiser_and_deleter.py.)"""
    stock_h, _ = hypothesisers(dict(clutter_spatial_density=CLUTTER, prob_detect=PD))
    time, detections = jpda_scans(steps=2)[1]
    tracks = [track_at(1.0, 1.0), track_at(2.0, 19.0)]
    context = constant_sensor(pd=0.3).context((0.0, 0.0, 0.0), time)
    forwarded = JPDA(stock_h).associate(tracks, set(detections), time, detector_context=context)
    plain = JPDA(stock_h).associate(tracks, set(detections), time)
    def key(hypotheses):
        return [(h.measurement if h else "missed", float(h.probability)) for h in hypotheses]
    for track in tracks:
        assert key(forwarded[track]) == key(plain[track])
        assert len(forwarded[track]) > 1  # a detection was in the gate


class _NoKeywordsHypothesiser(StockPDAHypothesiser):
    """Stone Soup's PDA hypothesiser with the signature of 1.9.1's CompositeHypothesiser:
    no ``**kwargs``, so a keyword handed down through the associator would raise."""

    def hypothesise(self, track, detections, timestamp):
        return super().hypothesise(track, detections, timestamp)


def test_stock_components_are_called_as_stock():
    """A stock associator over a hypothesiser without ``**kwargs`` (as 1.9.1's
    CompositeHypothesiser), a stock deleter: the tracker hands them nothing, so scans with
    contexts run as they did before forwarding; the opted-in initiator still gets them."""
    stock_h, _ = hypothesisers(dict(clutter_spatial_density=CLUTTER, prob_detect=PD))
    strict = _NoKeywordsHypothesiser(stock_h.predictor, stock_h.updater,
                                     clutter_spatial_density=CLUTTER, prob_detect=PD)
    with pytest.raises(TypeError, match="detector_context"):  # what forwarding would do
        JPDA(strict).associate([track_at(1.0, 1.0)], set(), T0, detector_context=object())
    tracker = _mixture_tracker(MultiTargetMixtureTracker, MultiMeasurementInitiator, JPDA)
    tracker.data_associator = JPDA(strict)
    tracker.deleter = UpdateTimeStepsDeleter(3)
    contexts = _run_jpda(tracker)
    assert any(c is not None for c in contexts)
    assert tracker.initiator.seen == _expected(contexts)
    assert len(tracker.tracks) > 0
