"""Hostile inputs to every public constructor, update and evaluation of the learned models
(:class:`~ctxmodels.ClutterMap`, :class:`~ctxmodels.DetectionEstimate`), the coastal
clutter factor and the detector contexts built on them.

Each case replaces one argument of a valid call by a value the documentation does not
accept. The call must raise ``TypeError`` or ``ValueError`` whose message starts with that
argument's name — never another exception, never a silent NaN, never a result. Accepted
extremes (the edges of every documented range) must give finite results and a finite
state after many updates, or be refused at construction naming the argument.
``test_the_count_of_hostile_inputs`` states how many cases the file tries.
"""
from __future__ import annotations

import datetime
import math

import numpy as np
import pytest

from ctxmodels import (ClutterDensityModel, ClutterMap, CoastalClutter, DetectionEstimate,
                       DetectionProbabilityModel, LandMask, Pose, SensorModel)

NAN, INF = math.nan, math.inf
POSE = Pose(x=1.0, y=-2.0, heading=0.3)
LAND = LandMask(polygons=[[(100.0, -50.0), (200.0, -50.0), (200.0, 50.0), (100.0, 50.0)]])

#: Values no number-typed argument accepts.
NOT_NUMBERS = [None, True, np.bool_(False), "1", b"1", [1.0], {}, object(), 1 + 1j,
               np.timedelta64(1, "s"), np.datetime64("2026-01-01"), datetime.timedelta(1)]
#: Values no (M, 2) positions argument accepts.
NOT_POSITIONS = [None, "ab", 5.0, [1.0, 2.0], [[1.0, 2.0, 3.0]], [[[1.0, 2.0]]],
                 [[1.0], [1.0, 2.0]], [[1.0, "a"]], [[NAN, 0.5], [1.0, 1.0]],
                 [[1.0, 1.0], [0.5, INF]], [[-INF, 0.0], [1.0, 1.0]],
                 np.array([[1, 2]], dtype="timedelta64[s]"), np.array([[1 + 1j, 2]]),
                 np.array([[1.0, 2.0]], dtype=object), np.zeros((2, 2, 1))]
#: Values no clutter evaluation accepts: (M, 3) positions are detections with heights there.
NOT_DETECTION_POSITIONS = ([v for v in NOT_POSITIONS if not isinstance(v, list)
                            or v != [[1.0, 2.0, 3.0]]]
                           + [[[1.0, 2.0, 3.0, 4.0]], [[1.0, 2.0, NAN]]])
#: Values no pose accepts.
NOT_POSES = [None, "abc", 5.0, (0.0, 0.0), (0.0, 0.0, 0.0, 0.0, 0.0), (0.0, NAN, 0.0),
             (0.0, 0.0, 0.0, NAN),
             (INF, 0.0, 0.0), (0.0, 0.0, "n"), (0.0, True, 0.0), {"x": 0}, object()]


def names(argument, call):
    with pytest.raises((TypeError, ValueError)) as info:
        call()
    message = str(info.value)
    assert message.startswith(f"{argument}:") or message.startswith(f"{argument}["), message


# --- constructors ---------------------------------------------------------------------------

def clutter_map(**changes):
    kwargs = dict(space="bearing-range", edges=([-1.0, 0.0, 1.0], [0.0, 100.0, 500.0]),
                  prior_intensity=1e-3, prior_scans=5.0, forgetting=0.9)
    kwargs.update(changes)
    return ClutterMap(**kwargs)


def detection_estimate(**changes):
    kwargs = dict(edges=[0.0, 100.0, 500.0], prior_probability=0.5, prior_trials=4.0,
                  forgetting=0.9)
    kwargs.update(changes)
    return DetectionEstimate(**kwargs)


def coastal(**changes):
    kwargs = dict(land=LAND, width=10.0, inside=5.0)
    kwargs.update(changes)
    return CoastalClutter(**kwargs)


POSITIVE = NOT_NUMBERS + [NAN, INF, -INF, 0.0, -1.0, -1e-300]
CONSTRUCTOR_CASES = (
    [(clutter_map, "space", v) for v in [None, 5, "polar", "", b"world-xy", "WORLD-XY"]]
    + [(clutter_map, "edges", v) for v in [
        None, 5, "ab", [], [[0.0, 1.0]], [[0.0, 1.0]] * 3, [[1.0, 0.0], [0.0, 1.0]],
        [[0.0, 0.0], [0.0, 1.0]], [[0.0, NAN], [0.0, 1.0]], [[0.0, INF], [0.0, 1.0]],
        [[-4.0, 0.0], [0.0, 1.0]], [[0.0, 4.0], [0.0, 1.0]], [[-1.0, 0.0], [-5.0, 1.0]],
        [[0.0], [0.0, 1.0]], [["a", "b"], [0.0, 1.0]], [[[0.0, 1.0]], [0.0, 1.0]],
        [np.array([0, 1], dtype="timedelta64[s]"), [0.0, 1.0]]]]
    + [(clutter_map, "prior_intensity", v) for v in POSITIVE]
    + [(clutter_map, "prior_scans", v) for v in POSITIVE]
    + [(clutter_map, "forgetting", v) for v in NOT_NUMBERS + [NAN, INF, 0.0, -0.5, 1.0000001, 2.0]]
    + [(clutter_map, "pooling", v) for v in [None, 5, "ring", "", "RANGE"]]
    + [(lambda **k: clutter_map(pooling="range", **k), "pooling_scans", v)
       for v in [v for v in POSITIVE if v is not None]]
    + [(clutter_map, "counts", v) for v in [
        "ab", 5.0, [[1.0, 2.0]], np.zeros((2, 2, 1)), np.full((2, 2), NAN),
        np.full((2, 2), -1.0), np.full((2, 2), INF), np.zeros((3, 2))]]
    + [(clutter_map, "deficit", v) for v in [
        "ab", np.full((2, 2), NAN), np.full((2, 2), -1.0), np.zeros((2, 3))]]
    + [(clutter_map, "exposure", v) for v in NOT_NUMBERS[1:] + [NAN, INF, -1.0]]
    + [(clutter_map, "scale", v) for v in NOT_NUMBERS[1:] + [NAN, INF, 0.0, -1.0]]
    + [(detection_estimate, "edges", v) for v in [
        None, 5, "ab", [], [1.0], [1.0, 0.0], [0.0, 0.0], [-1.0, 1.0], [0.0, NAN],
        [0.0, INF], [[0.0, 1.0]], ["a", "b"], np.array([0, 1], dtype="timedelta64[s]")]]
    + [(detection_estimate, "prior_probability", v)
       for v in NOT_NUMBERS + [NAN, INF, 0.0, 1.0, -0.1, 1.5]]
    + [(detection_estimate, "prior_trials", v) for v in POSITIVE]
    + [(detection_estimate, "forgetting", v)
       for v in NOT_NUMBERS + [NAN, INF, 0.0, -0.5, 1.0000001]]
    + [(detection_estimate, "outside", v) for v in NOT_NUMBERS + [NAN, INF, -0.1, 1.1]]
    + [(detection_estimate, "hits", v) for v in [
        "ab", [1.0], [1.0, 2.0, 3.0], [NAN, 0.0], [-1.0, 0.0], [INF, 0.0], [[1.0, 1.0]]]]
    + [(detection_estimate, "trials", v) for v in [
        "ab", [1.0], [NAN, 0.0], [-1.0, 0.0], [INF, 0.0]]]
    + [(coastal, "land", v) for v in [None, 5, "land", [[(0, 0), (1, 0), (1, 1)]]]]
    + [(coastal, "width", v) for v in NOT_NUMBERS + [NAN, INF, -1.0]]
    + [(coastal, "inside", v) for v in NOT_NUMBERS + [NAN, INF, 0.0, -1.0]]
    + [(coastal, "seen_only", v) for v in [None, 1, "yes", 1.0]]
)


@pytest.mark.parametrize("build, argument, value", CONSTRUCTOR_CASES,
                         ids=[f"{b.__name__}-{a}-{i}" for i, (b, a, _) in enumerate(CONSTRUCTOR_CASES)])
def test_constructors_name_the_argument(build, argument, value):
    names(argument, lambda: build(**{argument: value}))


# --- updates and evaluations ----------------------------------------------------------------

def learned_calls():
    """(name, call(argument, value)) for every update and evaluation, with their valid
    arguments, and which arguments to attack with which values."""
    def map_update(**changes):
        kwargs = dict(pose=POSE, positions=[[50.0, 0.0], [400.0, 10.0]], ranges=None,
                      gates=[[50.0, 0.0, 5.0]], weights=[0.5, 1.0])
        kwargs.update(changes)
        return clutter_map().update(**kwargs)

    def map_intensity(**changes):
        kwargs = dict(pose=POSE, positions=[[50.0, 0.0], [400.0, 10.0]], ranges=None)
        kwargs.update(changes)
        return clutter_map().intensity(**kwargs)

    def estimate_update(**changes):
        kwargs = dict(pose=POSE, positions=[[50.0, 0.0], [400.0, 10.0]], detected=[1, 0],
                      weights=[1.0, 0.5])
        kwargs.update(changes)
        return detection_estimate().update(**kwargs)

    def coast_evaluate(**changes):
        kwargs = dict(pose=POSE, positions=[[95.0, 0.0], [0.0, 0.0]])
        kwargs.update(changes)
        return coastal().evaluate(**kwargs)

    def clutter_model(**changes):
        kwargs = dict(pose=POSE, positions=[[50.0, 0.0], [400.0, 10.0]])
        kwargs.update(changes)
        model = ClutterDensityModel(factors=[clutter_map(), coastal()])
        return model.evaluate(**kwargs)

    def detection_model(**changes):
        kwargs = dict(pose=POSE, states=[[50.0, 0.0, 0.0, 0.0], [400.0, 0.0, 10.0, 0.0]])
        kwargs.update(changes)
        return DetectionProbabilityModel(factors=[detection_estimate()]).evaluate(**kwargs)

    def context(**changes):
        kwargs = dict(pose=POSE, timestamp=datetime.datetime(2026, 1, 1))
        kwargs.update(changes)
        sensor = SensorModel(detection=DetectionProbabilityModel(factors=[detection_estimate()]),
                             clutter=ClutterDensityModel(factors=[clutter_map()]))
        return sensor.context(**kwargs)

    ctx = context()

    def pd_array(**changes):
        kwargs = dict(means=[[50.0, 0.0, 0.0, 0.0]])
        kwargs.update(changes)
        return ctx.prob_detection_array(**kwargs)

    def pd_particles(**changes):
        kwargs = dict(particles=np.array([[50.0], [0.0], [0.0], [0.0]]))
        kwargs.update(changes)
        return ctx.prob_detection_particles(**kwargs)

    def lam_array(**changes):
        kwargs = dict(positions=[[50.0, 0.0], [400.0, 10.0]], ranges=None)
        kwargs.update(changes)
        return ctx.clutter_spatial_density_array(**kwargs)

    def pd_one(hypothesis_or_state):
        return ctx.prob_detection(hypothesis_or_state)

    ranges = [None] if False else [[NAN, "a"], "ab", [[1.0, 2.0]], [1.0], [-1.0, 5.0],
                                   [INF, 5.0], np.array([1, 2], dtype="timedelta64[s]")]
    weights = ["ab", [0.5], [[0.5, 0.5]], [NAN, 1.0], [-0.1, 1.0], [1.5, 1.0], [INF, 1.0]]
    yield map_update, "pose", NOT_POSES
    yield map_update, "positions", NOT_POSITIONS
    yield map_update, "ranges", ranges
    yield map_update, "gates", [
        "ab", [[1.0, 2.0]], [1.0, 2.0, 3.0], [[NAN, 0.0, 1.0]], [[0.0, 0.0, -1.0]],
        [[0.0, 0.0, INF]], [[0.0, INF, 1.0]], np.array([[1, 2, 3]], dtype="timedelta64[s]")]
    yield map_update, "weights", weights
    yield map_intensity, "pose", NOT_POSES
    yield map_intensity, "positions", NOT_POSITIONS
    yield map_intensity, "ranges", ranges
    yield estimate_update, "pose", NOT_POSES
    yield estimate_update, "positions", NOT_POSITIONS
    yield estimate_update, "detected", [
        None, "ab", [1], [[1, 0]], [2, 0], [0.5, 0], [-1, 0], [NAN, 0],
        np.array([1, 0], dtype="timedelta64[s]")]
    yield estimate_update, "weights", weights
    yield coast_evaluate, "pose", NOT_POSES
    yield coast_evaluate, "positions", NOT_POSITIONS
    yield clutter_model, "pose", NOT_POSES
    yield clutter_model, "positions", NOT_DETECTION_POSITIONS
    yield detection_model, "pose", NOT_POSES
    yield detection_model, "states", [
        None, "ab", [[[50.0, 0.0, 0.0, 0.0]]], [[NAN, 0.0, 0.0, 0.0]],
        [[50.0, 0.0, INF, 0.0]], np.array([[1, 2, 3, 4]], dtype="timedelta64[s]"),
        [["a", 0.0, 0.0, 0.0]]]
    yield context, "pose", NOT_POSES
    yield context, "timestamp", ["now", 5.0, np.datetime64("2026-01-01"), datetime.date(2026, 1, 1),
                                 datetime.timedelta(1)]
    yield pd_array, "means", [
        None, "ab", [[NAN, 0.0, 0.0, 0.0]], [[50.0, 0.0, -INF, 0.0]],
        np.array([[1, 2, 3, 4]], dtype="timedelta64[s]"), np.array([[1j, 0, 0, 0]])]
    yield pd_particles, "particles", [
        None, "ab", np.array([[50.0]]), np.array([[NAN], [0.0], [0.0], [0.0]]),
        np.array([[1], [2], [3], [4]], dtype="timedelta64[s]")]
    yield lam_array, "positions", NOT_DETECTION_POSITIONS
    yield lam_array, "ranges", ranges
    yield pd_one, "hypothesis_or_state", [
        None, "abcd", np.array([1, 2, 3, 4], dtype="timedelta64[s]"), [NAN, 0.0, 0.0, 0.0],
        np.array([50.0, 0.0]), object()]


CALL_CASES = [(call, argument, value) for call, argument, values in learned_calls()
              for value in values]


@pytest.mark.parametrize("call, argument, value", CALL_CASES,
                         ids=[f"{c.__name__}-{a}-{i}" for i, (c, a, _) in enumerate(CALL_CASES)])
def test_updates_and_evaluations_name_the_argument(call, argument, value):
    names(argument, lambda: call(**{argument: value}))


# --- accepted extremes stay finite ---------------------------------------------------------

MAP_EXTREMES = [dict(forgetting=f) for f in (1e-300, 1e-150, 1e-9, 0.5, 1.0)] + [
    dict(prior_intensity=p, prior_scans=s) for p in (1e-300, 1e300) for s in (1e-300, 1e10, 1e308)
] + [dict(pooling=pool, pooling_scans=ps, prior_scans=s)
     for pool in ("range", "grid") for ps in (None, 1e-300, 1e308) for s in (1e-300, 1e308)]


@pytest.mark.parametrize("extreme", MAP_EXTREMES, ids=[str(e) for e in MAP_EXTREMES])
def test_accepted_clutter_map_extremes_stay_finite(extreme):
    try:
        learned = clutter_map(**extreme)
    except ValueError as err:  # refusing a combination is allowed, naming an argument
        assert str(err).split(":")[0] in extreme, err
        return
    detections = [[50.0, 0.0], [400.0, 10.0], [420.0, -5.0]]
    for scan in range(40):
        learned.update(POSE, detections if scan % 3 else [],
                       gates=[[50.0, 0.0, 5.0]] if scan % 2 else None)
        lam = learned.intensity(POSE, detections)
        assert np.all(np.isfinite(lam)) and np.all(lam >= np.finfo(float).tiny), (scan, lam)
    grid = learned.intensity_grid()
    assert np.all(np.isfinite(grid)) and np.all(grid >= np.finfo(float).tiny), grid
    for state in (learned.counts, learned.deficit, learned.exposure, learned.scale):
        assert np.all(np.isfinite(state)), state


ESTIMATE_EXTREMES = [dict(forgetting=f) for f in (1e-300, 1e-150, 0.5, 1.0)] + [
    dict(prior_trials=s) for s in (1e-300, 1e308)] + [
    dict(prior_probability=p) for p in (1e-300, 1 - 1e-16)]


@pytest.mark.parametrize("extreme", ESTIMATE_EXTREMES, ids=[str(e) for e in ESTIMATE_EXTREMES])
def test_accepted_detection_estimate_extremes_stay_finite(extreme):
    try:
        learned = detection_estimate(**extreme)
    except ValueError as err:
        assert str(err).split(":")[0] in extreme, err
        return
    for scan in range(40):
        learned.update(POSE, [[50.0, 0.0], [400.0, 10.0]], [scan % 2, 1], [1.0, 1e-300])
        p = learned.probabilities()
        assert np.all(np.isfinite(p)) and np.all((p >= 0) & (p <= 1)), (scan, p)
    assert np.all(np.isfinite(learned.hits)) and np.all(np.isfinite(learned.trials))


def test_the_count_of_hostile_inputs():
    """The number this file tries (reported in the hardening notes); it must not shrink."""
    total = len(CONSTRUCTOR_CASES) + len(CALL_CASES) + len(MAP_EXTREMES) + len(ESTIMATE_EXTREMES)
    assert total >= 400, total
