"""A detector context evaluates one snapshot of its learned P_D factors on every path.

The first P_D call of a context, by whichever method, fixes its
:class:`~ctxmodels.DetectionEstimate` factors; every later call — any method, any input
layout, any dtype, with or without covariances — must give what a context of the same
sensor with those bands *fixed* gives, however the estimate is updated meanwhile. The
reference is a model with plain :class:`~ctxmodels.RangeBands` holding the values the
estimate had before the update, so a path that reads the live estimate fails here.
"""
import copy
import pickle

import numpy as np
import pytest
from stonesoup.types.array import StateVector, StateVectors
from stonesoup.types.hypothesis import SingleHypothesis
from stonesoup.types.prediction import GaussianStatePrediction
from stonesoup.types.state import GaussianState, ParticleState, State

from ctxmodels import (AngularSector, ClutterDensityModel, DetectionEstimate,
                       DetectionProbabilityModel, Pose, RangeBands, SensorModel)

POSE = Pose(x=3.0, y=-2.0, heading=0.4)
#: Targets at 2–9 m from the sensor: all in the estimate's band [0, 10), some in the sector.
POSITIONS = np.array([[5.0, -2.0], [3.0, 4.0], [-4.0, -2.5], [9.0, 1.0]])
STATES = np.array([[x, 1.0, y, -1.0] for x, y in POSITIONS])
COVAR = np.diag([4.0, 1.0, 9.0, 1.0])


def estimate():
    learned = DetectionEstimate(edges=[0.0, 10.0, 20.0], prior_probability=0.5, prior_trials=2.0)
    learned.update((0.0, 0.0, 0.0), [[5.0, 0.0]] * 3, [1, 1, 1])  # band 0 → 0.8
    return learned


def sensor(factor, evaluation="mean"):
    return SensorModel(
        detection=DetectionProbabilityModel(factors=[
            0.9, factor, AngularSector(centre=np.pi, width=np.radians(90), inside=0.0, outside=0.7)]),
        clutter=ClutterDensityModel(factors=[1e-3]), pd_evaluation=evaluation)


def paths():
    """Every way to ask a context for P_D: (name, call(context) -> array of the 4 targets)."""
    c_rows = np.ascontiguousarray(STATES)
    yield "array C float64", lambda ctx: ctx.prob_detection_array(c_rows)
    yield "array C float64, out", lambda ctx: ctx.prob_detection_array(c_rows, out=np.empty(4))
    yield "array list", lambda ctx: ctx.prob_detection_array(STATES.tolist())
    yield "array Fortran", lambda ctx: ctx.prob_detection_array(np.asfortranarray(STATES))
    yield "array float32", lambda ctx: ctx.prob_detection_array(STATES.astype(np.float32))
    yield "array int", lambda ctx: ctx.prob_detection_array(STATES.round().astype(np.int64))
    yield "array strided", lambda ctx: ctx.prob_detection_array(
        np.repeat(STATES, 2, axis=0)[::2])
    yield "array covars", lambda ctx: ctx.prob_detection_array(
        STATES, np.repeat(COVAR[np.newaxis], 4, axis=0))
    yield "particles", lambda ctx: ctx.prob_detection_particles(STATES.T.copy())
    yield "particles Fortran", lambda ctx: ctx.prob_detection_particles(
        np.asfortranarray(STATES.T))
    yield "particles log", lambda ctx: np.exp(ctx.prob_detection_particles(STATES.T, log=True))
    yield "particles missed", lambda ctx: 1 - ctx.prob_detection_particles(
        STATES.T, missed=True)[1]
    yield "states", lambda ctx: ctx.prob_detection_states(
        [GaussianState(StateVector(s), COVAR) for s in STATES])
    for name, make in [
            ("state vector", lambda s: StateVector(s)),
            ("flat vector", lambda s: np.array(s)),
            ("list vector", lambda s: s.tolist()),
            ("int vector", lambda s: StateVector(s.round().astype(np.int64))),
            ("State", lambda s: State(StateVector(s))),
            ("Gaussian", lambda s: GaussianState(StateVector(s), COVAR)),
            ("Gaussian float32", lambda s: GaussianState(StateVector(s.astype(np.float32)),
                                                         COVAR.astype(np.float32))),
            ("hypothesis", lambda s: SingleHypothesis(
                GaussianStatePrediction(StateVector(s), COVAR), None)),
            ("particle state", lambda s: ParticleState(
                StateVectors(np.repeat(s[:, np.newaxis], 3, axis=1)),
                weight=np.full(3, 1 / 3)))]:
        yield name, lambda ctx, make=make: np.array(
            [float(ctx.prob_detection(make(s))) for s in STATES])


PATHS = list(paths())


def rounded_where_needed(name):
    # the integer paths read positions rounded to whole metres; the reference reads the same
    return name in ("array int", "int vector")


@pytest.mark.parametrize("evaluation", ["mean", "cubature"])
@pytest.mark.parametrize("first", [name for name, _ in PATHS])
def test_every_path_reads_the_snapshot_fixed_by_the_first_call(first, evaluation):
    learned = estimate()
    fixed = sensor(learned.bands(), evaluation)  # the estimate as it stood, as plain bands
    context = sensor(learned, evaluation).context(POSE)
    reference = fixed.context(POSE)
    calls = dict(PATHS)
    before = calls[first](context)
    for _ in range(20):  # drive band 0 towards 0: a live read would see ~0.1
        learned.update((0.0, 0.0, 0.0), [[5.0, 0.0]], [0])
    assert learned.probabilities()[0] < 0.2
    np.testing.assert_array_equal(before, calls[first](reference))
    for name, call in PATHS:
        assert np.array_equal(call(context), call(reference)), name
    # the snapshot survives pickles and copies
    for restored in (pickle.loads(pickle.dumps(context)), copy.deepcopy(context)):
        for name, call in PATHS:
            assert np.array_equal(call(restored), call(reference)), name


def test_each_context_takes_the_estimate_as_it_stands_at_its_first_call():
    learned = estimate()
    model = sensor(learned)
    early, late = model.context(POSE), model.context(POSE)
    at_first = early.prob_detection_array(STATES)
    learned.update((0.0, 0.0, 0.0), [[5.0, 0.0]] * 10, [0] * 10)
    updated = late.prob_detection_array(STATES)  # first call after the update: sees it
    np.testing.assert_array_equal(updated, sensor(learned.bands()).context(POSE)
                                  .prob_detection_array(STATES))
    assert np.all(updated[at_first > 0] < at_first[at_first > 0])
    np.testing.assert_array_equal(early.prob_detection_array(STATES), at_first)


def test_the_snapshot_is_the_estimate_bit_for_bit():
    """bands() and the core's own read of the estimate agree to the bit, at every range."""
    learned = estimate()
    ranges = np.concatenate([np.linspace(0, 25, 1001), [10.0, 20.0, np.nextafter(10.0, 0)]])
    states = np.column_stack([ranges, np.zeros_like(ranges), np.zeros_like(ranges),
                              np.zeros_like(ranges)])
    live = DetectionProbabilityModel(factors=[learned]).evaluate(Pose(x=0, y=0), states)
    fixed = DetectionProbabilityModel(factors=[learned.bands()]).evaluate(Pose(x=0, y=0), states)
    np.testing.assert_array_equal(live, fixed)
    assert DetectionProbabilityModel(factors=[learned]).frozen().factors[0] == learned.bands()
    plain = DetectionProbabilityModel(factors=[0.5, RangeBands(edges=[1.0], values=[1.0, 0.0])])
    assert plain.frozen() is plain


def test_every_clutter_path_reads_the_map_as_it_stands():
    """λ has one rule on every path: a ClutterMap is read as it stands at the call."""
    from stonesoup.models.measurement.linear import LinearGaussian
    from stonesoup.types.detection import Detection
    from ctxmodels import ClutterMap
    learned = ClutterMap(space="world-xy", edges=([0.0, 10.0, 20.0], [-10.0, 10.0]),
                         prior_intensity=1e-3, prior_scans=2.0, forgetting=1.0)
    sensor_model = SensorModel(detection=DetectionProbabilityModel(factors=[0.9]),
                               clutter=ClutterDensityModel(factors=[2.0, learned]))
    context = sensor_model.context(Pose(x=0.0, y=0.0))
    positions = np.array([[5.0, 0.0], [15.0, 1.0], [30.0, 0.0]])
    model = LinearGaussian(ndim_state=4, mapping=(0, 2), noise_covar=np.eye(2))
    detections = [Detection(StateVector(p), measurement_model=model) for p in positions]
    paths = {
        "array C float64": lambda: context.clutter_spatial_density_array(positions),
        "array list": lambda: context.clutter_spatial_density_array(positions.tolist()),
        "array Fortran": lambda: context.clutter_spatial_density_array(np.asfortranarray(positions)),
        "array ranges": lambda: context.clutter_spatial_density_array(
            positions, ranges=np.full(3, np.nan)),
        "detections": lambda: context.clutter_spatial_density_detections(detections),
        "one by one": lambda: np.array([context.clutter_spatial_density(d) for d in detections]),
    }
    for path in paths.values():
        path()  # every path has been called once before the update
    for _ in range(30):
        learned.update((0.0, 0.0, 0.0), [[5.0, 0.0]] * 4)
    expected = 2.0 * learned.intensity((0.0, 0.0, 0.0), positions)
    assert expected[0] > 10 * 2.0 * 1e-3  # the update moved the cell a lot
    for name, path in paths.items():
        np.testing.assert_array_equal(path(), expected, err_msg=name)
