"""Hostile inputs to the learners (``ClutterMapLearner``, ``DetectionLearner``) and
``LearningTracker``: a bad position mapping, gate radius, weighting, confirmation, tracker
or learners is refused at construction, and tracks of the wrong kind or dimension at learn
time, each naming the argument."""
from __future__ import annotations

import datetime

import numpy as np
import pytest
from ..hostile import names_argument

T0 = datetime.datetime(2026, 1, 1)
NAN, INF = float("nan"), float("inf")


def _learners():
    from ctxmodels.stonesoup import ClutterMapLearner, DetectionLearner
    return {"clutter": lambda **kw: ClutterMapLearner(gate_radius=30.0, **kw),
            "detection": lambda **kw: DetectionLearner(gate_radius=30.0, **kw)}


BAD_MAPPINGS = [(0, 0), (0,), (0, 1, 2), (-1, 2), (0, 2.0), (True, 2), "02", None, 5,
                {"x": 0, "y": 2}, (0, 2**40), (np.float64(0), 2)]


@pytest.mark.parametrize("kind", ["clutter", "detection"])
@pytest.mark.parametrize("mapping", BAD_MAPPINGS, ids=repr)
def test_learners_name_a_bad_position_mapping_at_construction(kind, mapping):
    names_argument(lambda: _learners()[kind](position_mapping=mapping), (ValueError, TypeError),
                   "position_mapping")


def _scan_with_estimates(kind):
    from stonesoup.models.measurement.linear import LinearGaussian
    from stonesoup.types.detection import Detection
    from ctxmodels import (ClutterDensityModel, ClutterMap, DetectionEstimate,
                           DetectionProbabilityModel, DetectionSet, Pose, SensorModel)
    measurement = LinearGaussian(ndim_state=4, mapping=(0, 2), noise_covar=np.eye(2))
    detection = (DetectionEstimate(edges=(0.0, 100.0, 200.0), prior_probability=0.5)
                 if kind == "detection" else 0.9)
    clutter = (ClutterMap(space="world-xy", edges=(np.linspace(-200, 200, 5),) * 2,
                          prior_intensity=1e-3)
               if kind == "clutter" else 1e-3)
    model = SensorModel(detection=DetectionProbabilityModel(factors=[detection]),
                        clutter=ClutterDensityModel(factors=[clutter]))
    context = model.context(Pose(x=0.0, y=0.0), T0)
    return DetectionSet({Detection([[10.0], [20.0]], timestamp=T0,
                                   measurement_model=measurement)}, context)


@pytest.mark.parametrize("kind", ["clutter", "detection"])
@pytest.mark.parametrize("mapping", [(0, 9), (4, 2), (2, 4)], ids=repr)
def test_learners_name_position_mapping_and_the_tracks_dimension_at_learn_time(kind, mapping):
    from stonesoup.types.state import State
    from stonesoup.types.track import Track
    learner = _learners()[kind](position_mapping=mapping)
    track = Track([State(np.array([[10.0], [0.0], [20.0], [0.0]]), timestamp=T0)])
    message = names_argument(lambda: learner.learn(T0, _scan_with_estimates(kind), {track}),
                             ValueError, "position_mapping")
    assert "4-D state" in message and str(T0) in message


@pytest.mark.parametrize("kind", ["clutter", "detection"])
@pytest.mark.parametrize("tracks", [None, 5, "tracks"], ids=repr)
def test_learners_name_tracks_that_are_not_tracks(kind, tracks):
    learner = _learners()[kind]()
    names_argument(lambda: learner.learn(T0, _scan_with_estimates(kind), tracks), TypeError,
                   "tracks")


@pytest.mark.parametrize("kind", ["clutter", "detection"])
@pytest.mark.parametrize("radius", [True, np.bool_(True), "30", None, NAN, INF, -1.0, [30.0],
                                    np.array([30.0]), 1j], ids=repr)
def test_learners_name_a_bad_gate_radius(kind, radius):
    from ctxmodels.stonesoup import ClutterMapLearner, DetectionLearner
    cls = ClutterMapLearner if kind == "clutter" else DetectionLearner
    names_argument(lambda: cls(gate_radius=radius), (ValueError, TypeError), "gate_radius")


@pytest.mark.parametrize("weighting", [None, 5, ["gates"], np.array(["gates"]), "GATES", ""],
                         ids=repr)
def test_clutter_learner_names_a_bad_weighting(weighting):
    from ctxmodels.stonesoup import ClutterMapLearner
    names_argument(lambda: ClutterMapLearner(gate_radius=30.0, weighting=weighting),
                   (ValueError, TypeError), "weighting")


@pytest.mark.parametrize("confirmation", [True, np.bool_(False), -1, 1.5, "3", None, NAN],
                         ids=repr)
def test_detection_learner_names_a_bad_confirmation(confirmation):
    from ctxmodels.stonesoup import DetectionLearner
    names_argument(lambda: DetectionLearner(gate_radius=30.0, confirmation=confirmation),
                   (ValueError, TypeError), "confirmation")


def _stone_soup_tracker():
    from stonesoup.tracker.simple import SingleTargetTracker
    return SingleTargetTracker(initiator=None, deleter=None, detector=[], data_associator=None,
                               updater=None)


@pytest.mark.parametrize("tracker", [None, 5, "tracker", [], object()], ids=repr)
def test_learning_tracker_names_a_tracker_that_is_not_one(tracker):
    from ctxmodels.stonesoup import LearningTracker
    names_argument(lambda: LearningTracker(tracker=tracker, learners=[]), TypeError, "tracker")


@pytest.mark.parametrize("learners", [5, None, "learners", {"a": 1}, "one", [None], [5],
                                      [object()]], ids=repr)
def test_learning_tracker_names_bad_learners(learners):
    from ctxmodels.stonesoup import LearningTracker
    given = _learners()["clutter"]() if learners == "one" else learners
    names_argument(lambda: LearningTracker(tracker=_stone_soup_tracker(), learners=given),
                   TypeError, "learners")
