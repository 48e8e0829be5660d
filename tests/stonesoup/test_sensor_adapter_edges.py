"""The Stone Soup sensor and platform adapters (ctxmodels.stonesoup.sensor_adapter) at their
edges: P_D > 0 exactly where the radar's own ``is_detectable`` says so at its maximum range
and on every bearing off the rounding sliver, on every path; the sensor context keeps its
radar as it was; and hostile inputs (settings, sensor models, readers, a sensor mounted
after the feeder was built) raise ValueError/TypeError whose message starts with the
argument's name."""
from __future__ import annotations

import datetime
import math

import numpy as np
import pytest
from ..hostile import names_argument

T0 = datetime.datetime(2026, 1, 1)
NAN, INF = float("nan"), float("inf")


# --- Stone Soup sensor adapter ----------------------------------------------------------------

def _radar(kind="fixed", position=(100.0, -50.0), yaw=0.7, rotation=0.3, max_range=800.0,
           dwell=0.0, fov=2 * math.pi, with_platform=False):
    from stonesoup.platform.base import FixedPlatform
    from stonesoup.sensor.radar.radar import RadarBearingRange, RadarRotatingBearingRange
    from stonesoup.types.array import StateVector
    from stonesoup.types.state import State
    common = dict(ndim_state=4, position_mapping=(0, 2), noise_covar=np.eye(2),
                  max_range=max_range, rotation_offset=StateVector([0, 0, rotation]),
                  mounting_offset=StateVector([3.0, -1.0]))
    if kind == "rotating":
        sensor = RadarRotatingBearingRange(dwell_centre=StateVector([dwell]), rpm=10,
                                           fov_angle=fov, **common)
    else:
        sensor = RadarBearingRange(**common)
    platform = FixedPlatform(
        states=[State(StateVector([position[0], 0, position[1], 0]), timestamp=T0)],
        position_mapping=(0, 2), orientation=StateVector([0, 0, yaw]), sensors=[sensor])
    return (sensor, platform) if with_platform else sensor


EDGE_RADARS = [
    dict(kind="fixed", position=(100.0, -50.0), yaw=0.7, rotation=0.3, max_range=800.0),
    dict(kind="rotating", position=(12345.6, -777.0), yaw=2.1, rotation=-0.4, max_range=1612.0,
         dwell=0.3),
    dict(kind="fixed", position=(0.0, 0.0), yaw=-1.3, rotation=1.0, max_range=333.3),
    dict(kind="rotating", position=(-40.0, 7.5), yaw=0.0, rotation=0.0, max_range=50.0,
         dwell=1.1),
]


EDGE_IDS = [f"{r['kind']}-{r['max_range']}" for r in EDGE_RADARS]
#: A rotating radar whose field of view is narrower than a turn: its edge is the sector's.
NARROW = dict(kind="rotating", position=(-40.0, 7.5), yaw=0.4, rotation=0.2, max_range=50.0,
              dwell=1.1, fov=math.pi)


def _detectable(sensor, states) -> np.ndarray:
    """The radar's own ``is_detectable``, one state at a time."""
    from stonesoup.types.groundtruth import GroundTruthState
    return np.array([bool(np.all(sensor.is_detectable(
        GroundTruthState(s.reshape(-1, 1), timestamp=T0)))) for s in states])


def _ring(sensor, r, n=240) -> np.ndarray:
    """(n, 4) CV states at world range ``r`` from the sensor on n bearings."""
    centre = np.asarray(sensor.position, dtype=float).ravel()
    bearings = np.linspace(-math.pi, math.pi, n, endpoint=False)
    return np.column_stack([centre[0] + r * np.cos(bearings), np.zeros(n),
                            centre[1] + r * np.sin(bearings), np.zeros(n)])


def _pd_on_every_path(context, states) -> dict:
    """P_D of ``states`` (N, D) by every public path of the context."""
    from stonesoup.types.hypothesis import SingleHypothesis
    from stonesoup.types.prediction import GaussianStatePrediction
    from stonesoup.types.state import GaussianState, State
    vectors = [s.reshape(-1, 1) for s in states]
    covars = np.tile(np.eye(4), (len(states), 1, 1))
    log_pd, log_missed = context.prob_detection_particles(np.asfortranarray(states.T),
                                                          log=True, missed=True)
    pd_pair, missed = context.prob_detection_particles(states.T.copy(), missed=True)
    return {
        "array": context.prob_detection_array(states),
        "array-list": context.prob_detection_array(states.tolist()),
        "array-covars": context.prob_detection_array(states, covars),
        "states": context.prob_detection_states([GaussianState(v, np.eye(4)) for v in vectors]),
        "one-state": np.array([float(context.prob_detection(State(v))) for v in vectors]),
        "one-flat": np.array([float(context.prob_detection(s.copy())) for s in states]),
        "one-hypothesis": np.array([float(context.prob_detection(SingleHypothesis(
            GaussianStatePrediction(v, np.eye(4), timestamp=T0), None))) for v in vectors]),
        "one-list": np.array([float(context.prob_detection(s.tolist())) for s in states]),
        "particles": context.prob_detection_particles(states.T),
        "particles-log": np.exp(log_pd),
        "particles-missed": pd_pair,
        "particles-missed-complement": 1 - missed,
        "particles-log-missed": 1 - np.exp(log_missed),
    }


@pytest.mark.parametrize("radar", EDGE_RADARS + [NARROW], ids=EDGE_IDS + ["narrow-fov"])
@pytest.mark.parametrize("made_by", ["sensor_context", "PlatformContextFeeder"])
def test_pd_agrees_with_is_detectable_at_max_range_on_every_path(radar, made_by):
    """The issue's test, at ``max_range`` and one ulp either side on 240 bearings: P_D > 0
    exactly where the radar's own ``is_detectable`` says the target is detectable (no
    disagreement) on every P_D path of the context the radar's scan gets, and P_D there is
    the value inside the coverage (0.9), as bit for bit as the plain context gives it."""
    sensor, platform = _radar(**radar, with_platform=True)
    model = _edge_model(sensor)
    context = _edge_context(sensor, platform, model, made_by)
    plain = model.context(_sensor_pose(sensor), T0)
    inside = plain.prob_detection_array(_ring(sensor, sensor.max_range * 0.5))
    checked = 0
    for r in (np.nextafter(sensor.max_range, 0), sensor.max_range,
              np.nextafter(sensor.max_range, INF)):
        states = _ring(sensor, r)
        detectable = _detectable(sensor, states)
        for path, pd in _pd_on_every_path(context, states).items():
            disagreements = int(np.sum((pd > 0) != detectable))
            assert disagreements == 0, f"{path} at max_range{r - sensor.max_range:+g}"
            # inside: the plain context's value there (0.9, or 0 outside the field of view)
            expected = np.where(detectable, inside, 0.0)
            if path.startswith(("array", "states", "one", "particles-missed")) \
                    and path != "particles-missed-complement":
                np.testing.assert_array_equal(pd, expected, err_msg=path)
            else:  # through a log or a complement: to their rounding
                np.testing.assert_allclose(pd, expected, rtol=0, atol=1e-15, err_msg=path)
            checked += 1
        if radar is not NARROW:
            assert detectable.any() and (r <= sensor.max_range or not detectable.all())
    assert checked == 3 * 13


def _sensor_pose(sensor):
    from ctxmodels.stonesoup import sensor_pose
    return sensor_pose(sensor)


def _edge_model(sensor):
    from ctxmodels import SensorModel
    return SensorModel.from_stonesoup(sensor, prob_detection=0.9, clutter_density=1e-4)


def _edge_context(sensor, platform, model, made_by):
    """The context of a scan of ``sensor`` now, from :func:`sensor_context` or as the
    :class:`PlatformContextFeeder` gives it (its first scan, at the platform's time)."""
    from ctxmodels.stonesoup import PlatformContextFeeder, sensor_context
    from ctxmodels.stonesoup import SensorContext
    if made_by == "sensor_context":
        context = sensor_context(sensor, model, T0)
    else:
        from stonesoup.simulator.platform import PlatformDetectionSimulator

        class Still:  # no targets: only the scans and their contexts are read
            def __iter__(self):
                yield T0, set()
        simulator = PlatformDetectionSimulator(groundtruth=Still(), platforms=[platform])
        [(time, scan)] = list(PlatformContextFeeder(reader=simulator, sensor_models=[model]))
        context = scan.detector_context
        assert time == T0 and context.timestamp == T0
    assert type(context) is SensorContext and context.sensor_model is model
    assert context.pose == _sensor_pose(sensor)
    return context


@pytest.mark.parametrize("radar", EDGE_RADARS + [NARROW], ids=EDGE_IDS + ["narrow-fov"])
@pytest.mark.parametrize("made_by", ["plain", "sensor_context"])
def test_pd_agrees_with_is_detectable_on_every_bearing_off_the_rounding_sliver(radar, made_by):
    """Either side of ``max_range`` by 1e-12 of it (far beyond the rotation's rounding, far
    inside any target's size), and well inside and outside, on 240 bearings: P_D > 0 exactly
    where Stone Soup's radar says the target is detectable, for the plain context (world
    range) and the sensor's (its own range in the sliver between); the two agree bit for
    bit there."""
    sensor, platform = _radar(**radar, with_platform=True)
    model = _edge_model(sensor)
    plain = model.context(_sensor_pose(sensor), T0)
    context = plain if made_by == "plain" else _edge_context(sensor, platform, model, made_by)
    for r in (sensor.max_range * (1 - 1e-12), sensor.max_range * (1 + 1e-12),
              sensor.max_range * 0.5, sensor.max_range * 2):
        states = _ring(sensor, r)
        pd = context.prob_detection_array(states)
        detectable = _detectable(sensor, states)
        np.testing.assert_array_equal(pd > 0, detectable, err_msg=f"range {r}")
        np.testing.assert_array_equal(pd, plain.prob_detection_array(states))
        assert detectable.any() == (r < sensor.max_range)  # (the test can fail both ways)


@pytest.mark.parametrize("radar", EDGE_RADARS, ids=EDGE_IDS)
def test_a_target_whose_world_range_is_exactly_max_range_is_inside(radar):
    """The plain context's edge (``SensorModel.context(sensor_pose(sensor))``): the
    world-frame range, ``<=`` as in ``is_detectable``; along the axes the range is exact, so
    the edge itself is tested, and one ulp beyond is outside."""
    from ctxmodels import SensorModel
    from ctxmodels.stonesoup import sensor_pose
    sensor = _radar(**radar)
    if radar["kind"] == "rotating":  # keep the antenna's field of view out of it
        sensor.fov_angle = 2 * math.pi
    model = SensorModel.from_stonesoup(sensor, prob_detection=0.9, clutter_density=1e-4)
    pose = sensor_pose(sensor)
    context = model.context(pose, T0)
    r = sensor.max_range
    for dx, dy in ((r, 0.0), (-r, 0.0), (0.0, r), (0.0, -r)):
        at = np.array([[pose.x + dx, 0.0, pose.y + dy, 0.0]])
        if math.hypot(at[0, 0] - pose.x, at[0, 2] - pose.y) != r:
            continue  # (the sum rounded: not exactly on the edge)
        assert context.prob_detection_array(at)[0] == 0.9
        # the next representable position whose offset from the sensor exceeds max_range
        beyond, axis, centre = at.copy(), 0 if dx else 2, pose.x if dx else pose.y
        while abs(beyond[0, axis] - centre) <= r:
            beyond[0, axis] = np.nextafter(beyond[0, axis], math.copysign(INF, dx or dy))
        assert context.prob_detection_array(beyond)[0] == 0.0


def test_sensor_context_keeps_the_radar_as_it_was_and_pickles_and_copies():
    """The context decides with the radar as it was when made (the radar moving or changing
    its max_range afterwards reaches it not), survives pickling and deep copies with the
    same P_D on every target, and hashes and compares by identity."""
    import copy
    import pickle
    from stonesoup.types.array import StateVector
    from ctxmodels.stonesoup import sensor_context
    sensor = _radar(**EDGE_RADARS[1])
    states = _ring(sensor, sensor.max_range)
    detectable = _detectable(sensor, states)
    context = sensor_context(sensor, _edge_model(sensor), T0)
    before = context.prob_detection_array(states)
    np.testing.assert_array_equal(before > 0, detectable)
    sensor.max_range = 1.0
    sensor.dwell_centre = StateVector([2.0])
    sensor.movement_controller.states[-1].state_vector[0, 0] += 5.0
    for other in (context, pickle.loads(pickle.dumps(context)), copy.deepcopy(context)):
        np.testing.assert_array_equal(other.prob_detection_array(states), before)
        np.testing.assert_array_equal(other.prob_detection_particles(states.T), before)
        assert other.max_range == EDGE_RADARS[1]["max_range"]
    copied = copy.deepcopy(context)
    assert copied != context and context == context and hash(context) == object.__hash__(context)
    assert {context: 1}[context] == 1


def test_sensor_context_with_the_expected_pd_under_a_rule_integrates_the_plain_model():
    """With covariances and a ``pd_evaluation`` other than 'mean' the expected P_D is the
    plain context's (documented); without covariances the mean decides, as the radar does."""
    from ctxmodels import SensorModel
    from ctxmodels.stonesoup import sensor_context
    sensor = _radar(**EDGE_RADARS[0])
    base = _edge_model(sensor)
    model = SensorModel(detection=base.detection, clutter=base.clutter,
                        position_mapping=base.position_mapping, pd_evaluation="cubature")
    context = sensor_context(sensor, model, T0)
    plain = model.context(_sensor_pose(sensor), T0)
    states = _ring(sensor, sensor.max_range)
    covars = np.tile(np.eye(4), (len(states), 1, 1))
    np.testing.assert_array_equal(context.prob_detection_array(states, covars),
                                  plain.prob_detection_array(states, covars))
    np.testing.assert_array_equal(context.prob_detection_array(states) > 0,
                                  _detectable(sensor, states))


@pytest.mark.parametrize("bad", ["sensor", "model", "mounted", "mapping"])
def test_sensor_context_names_what_it_cannot_use(bad):
    from ctxmodels import Mounting, SensorModel
    from ctxmodels.stonesoup import sensor_context
    sensor = _radar()
    model = _edge_model(sensor)
    if bad == "sensor":
        names_argument(lambda: sensor_context(object(), model), TypeError, "sensor")
    elif bad == "model":
        names_argument(lambda: sensor_context(sensor, model.detection), TypeError,
                       "sensor_model")
    else:
        other = SensorModel(detection=model.detection, clutter=model.clutter,
                            **({"mounting": Mounting(forward=1.0)} if bad == "mounted"
                               else {"position_mapping": (0, 1)}))
        names_argument(lambda: sensor_context(sensor, other), ValueError, "sensor_model")


def test_platform_feeder_names_a_model_reading_another_position_than_its_sensor():
    from ctxmodels import SensorModel
    from ctxmodels.stonesoup import PlatformContextFeeder
    simulator, sensors = _simulator()
    models = _models(sensors)
    models[1] = SensorModel(detection=models[1].detection, clutter=models[1].clutter,
                            position_mapping=(0, 1))
    message = names_argument(lambda: PlatformContextFeeder(reader=simulator,
                                                           sensor_models=models),
                             ValueError, "sensor_models")
    assert "item 1" in message and "platform 1 sensor 0" in message


BAD_PROBABILITIES = [None, "0.9", True, np.bool_(False), NAN, INF, -0.1, 1.0000001, 2, [0.9],
                     np.array([0.9]), 1j, object()]
BAD_DENSITIES = [None, "x", True, 0, 0.0, -1e-4, NAN, INF, [1e-4], np.array([1e-4]), 1j,
                 np.float64(0.0), 5e-324]


@pytest.mark.parametrize("prob_detection", BAD_PROBABILITIES, ids=repr)
def test_from_stonesoup_names_prob_detection(prob_detection):
    from ctxmodels import SensorModel
    names_argument(lambda: SensorModel.from_stonesoup(_radar(), prob_detection, 1e-4),
                   (ValueError, TypeError), "prob_detection")


@pytest.mark.parametrize("clutter_density", BAD_DENSITIES, ids=repr)
def test_from_stonesoup_names_clutter_density(clutter_density):
    from ctxmodels import SensorModel
    names_argument(lambda: SensorModel.from_stonesoup(_radar(), 0.9, clutter_density),
                   (ValueError, TypeError), "clutter_density")


@pytest.mark.parametrize("name", [None, 5, b"radar", ["radar"]], ids=repr)
def test_from_stonesoup_names_name(name):
    from ctxmodels import SensorModel
    names_argument(lambda: SensorModel.from_stonesoup(_radar(), 0.9, 1e-4, name=name),
                   TypeError, "name")


@pytest.mark.parametrize("sensor", [None, 5, "radar", object(), [1]], ids=repr)
def test_from_stonesoup_names_sensor(sensor):
    from ctxmodels import SensorModel
    names_argument(lambda: SensorModel.from_stonesoup(sensor, 0.9, 1e-4), TypeError, "sensor")


@pytest.mark.parametrize("attribute, value", [("max_range", NAN), ("max_range", -1.0),
                                              ("max_range", "800"), ("max_range", None),
                                              ("max_range", True), ("fov_angle", 0.0),
                                              ("fov_angle", NAN), ("fov_angle", "1"),
                                              ("fov_angle", -1.0)], ids=str)
def test_from_stonesoup_names_the_sensor_for_its_bad_settings(attribute, value):
    from ctxmodels import SensorModel
    sensor = _radar(kind="rotating", fov=1.0)
    setattr(sensor, attribute, value)
    names_argument(lambda: SensorModel.from_stonesoup(sensor, 0.9, 1e-4),
                   (ValueError, TypeError), "sensor")


@pytest.mark.parametrize("prob_detection, clutter_density", [
    (0, 1e-4), (1, 1e-4), (np.float32(0.5), np.float32(1e-3)), (np.int64(1), np.int64(2)),
    (0.5, 1e300), (0.5, 2.2250738585072014e-308)], ids=str)
def test_from_stonesoup_accepts_every_real_number_type(prob_detection, clutter_density):
    from ctxmodels import SensorModel
    model = SensorModel.from_stonesoup(_radar(), prob_detection, clutter_density, name="r")
    assert model.detection.factors[0] == float(prob_detection)
    assert model.clutter.factors[0] == float(clutter_density)


def _simulator(sensors_per_platform=(1, 1), steps=3):
    from stonesoup.models.transition.linear import (CombinedLinearGaussianTransitionModel,
                                                    ConstantVelocity)
    from stonesoup.simulator.platform import PlatformDetectionSimulator
    from stonesoup.simulator.simple import MultiTargetGroundTruthSimulator
    from stonesoup.types.state import GaussianState
    transition = CombinedLinearGaussianTransitionModel([ConstantVelocity(0.5)] * 2)
    truths = MultiTargetGroundTruthSimulator(
        transition_model=transition,
        initial_state=GaussianState([[0], [0], [0], [0]], np.diag([100.0, 1, 100, 1]) ** 2,
                                    timestamp=T0),
        timestep=datetime.timedelta(seconds=1), number_steps=steps, birth_rate=0.5,
        death_probability=0.0, seed=1)
    from stonesoup.platform.base import FixedPlatform
    sensors = [_radar(position=(10.0 * k, 0.0)) for k in range(sum(sensors_per_platform))]
    fixed = []
    k = 0
    for count in sensors_per_platform:
        platform = FixedPlatform(states=[sensors[k].movement_controller.states[-1]],
                                 position_mapping=(0, 2), sensors=[])
        for sensor in sensors[k:k + count]:
            platform.add_sensor(sensor)
        fixed.append(platform)
        k += count
    return PlatformDetectionSimulator(groundtruth=truths, platforms=fixed), sensors


def _models(sensors):
    from ctxmodels import SensorModel
    return [SensorModel.from_stonesoup(s, 0.8, 1e-5) for s in sensors]


@pytest.mark.parametrize("models", ["one", None, "models", 5, {"a": 1}, "strings", "short",
                                    "long", "mounted"], ids=str)
def test_platform_feeder_names_bad_sensor_models_at_construction(models):
    from ctxmodels import Mounting, SensorModel
    from ctxmodels.stonesoup import PlatformContextFeeder
    simulator, sensors = _simulator()
    good = _models(sensors)
    given = {"one": good[0], "strings": ["a", "b"], "short": good[:1], "long": good * 2,
             "mounted": [good[0], SensorModel(detection=good[1].detection,
                                              clutter=good[1].clutter,
                                              mounting=Mounting(forward=1.0))]}
    given = given[models] if isinstance(models, str) and models in given else models
    names_argument(lambda: PlatformContextFeeder(reader=simulator, sensor_models=given),
                   (ValueError, TypeError), "sensor_models")


@pytest.mark.parametrize("reader", [None, [], 5, "sim"], ids=repr)
def test_platform_feeder_names_a_reader_that_is_not_a_platform_simulator(reader):
    from ctxmodels.stonesoup import PlatformContextFeeder
    names_argument(lambda: PlatformContextFeeder(reader=reader, sensor_models=[]), TypeError,
                   "reader")


def test_platform_feeder_names_a_sensor_mounted_after_it_was_built():
    from ctxmodels.stonesoup import PlatformContextFeeder
    simulator, sensors = _simulator()
    feeder = PlatformContextFeeder(reader=simulator, sensor_models=_models(sensors))
    simulator.platforms[1].add_sensor(_radar(position=(5.0, 5.0)))
    message = names_argument(lambda: list(feeder), ValueError, "sensor_models")
    assert "platform 1 sensor 1 (RadarBearingRange)" in message and str(T0) in message


def test_platform_feeder_gives_each_scan_its_sensors_model():
    from ctxmodels.stonesoup import PlatformContextFeeder, sensor_pose
    simulator, sensors = _simulator(sensors_per_platform=(2, 1))
    models = _models(sensors)
    scans = list(PlatformContextFeeder(reader=simulator, sensor_models=models))
    assert len(scans) == 3 * 3  # 3 sensors, 3 times
    for k, (_, scan) in enumerate(scans):
        assert scan.detector_context.sensor_model is models[k % 3]
        assert scan.detector_context.pose == sensor_pose(sensors[k % 3])
