"""The declarative components as Stone Soup components: they print, compare by value, hash,
pickle, deep-copy and round-trip through Stone Soup's YAML to equal objects that evaluate
identically, and refuse mutation. Then DetectorContext / DetectionSet with real Stone Soup
states, hypotheses and detections, and the type stubs against the compiled module.
"""
import ast
import copy
import datetime
import math
import pathlib
import pickle

import numpy as np
import pytest
import shapely
from shapely.geometry import MultiPolygon, Polygon
from stonesoup.models.measurement.linear import LinearGaussian
from stonesoup.models.measurement.nonlinear import CartesianToBearingRange
from stonesoup.serialise import YAML
from stonesoup.types.array import StateVector, StateVectors
from stonesoup.types.detection import Detection
from stonesoup.types.hypothesis import SingleHypothesis
from stonesoup.types.prediction import GaussianStatePrediction
from stonesoup.types.state import GaussianState, ParticleState, State

import ctxmodels
from ctxmodels import (AngularSector, ClutterDensityModel, CoastalClutter, ConstantPose,
                       DetectionProbabilityModel, DetectionSet, DetectorContext, ElevationSector,
                       LandMask, LineOfSight, MetadataThreshold, Mounting, NavigationTrack, Pose,
                       RadarEquation, RadarHorizon, RangeBands, RangeRateNotch, SensorModel, Zone,
                       _core)

T0 = datetime.datetime(2024, 5, 1, 12, 0, 0)
RNG = np.random.default_rng(99)
STATES = np.column_stack([RNG.uniform(-2000, 2000, 4000), RNG.normal(0, 5, 4000),
                          RNG.uniform(-2000, 2000, 4000), RNG.normal(0, 5, 4000)])
STATES[:200, 0::2] = RNG.uniform(-100, 100, (200, 2))
COVARS = np.tile(np.diag([400.0, 4.0, 900.0, 4.0]), (4000, 1, 1))
AREAS = RNG.uniform(0, 20, (4000, 1))
# [x, vx, y, vy, z, vz]: the states with heights, for the factors that read them
STATES_3D = np.column_stack([STATES, RNG.uniform(-50, 800, 4000), RNG.normal(0, 1, 4000)])
COVARS_3D = np.tile(np.diag([400.0, 4.0, 900.0, 4.0, 2500.0, 1.0]), (4000, 1, 1))
ISLAND = np.array([[100.0, -50.0], [300.0, -50.0], [300.0, 150.0], [100.0, 150.0]])
LAKE = np.array([[150.0, 0.0], [250.0, 0.0], [200.0, 100.0]])


# --- one factory per component class (called twice to get equal, distinct objects) ----------
def radar_detection():
    return DetectionProbabilityModel(factors=[
        RangeBands(edges=(50, 1612), values=(0, 0.4, 0), upper_owns=(False, True)),
        AngularSector.blind(math.pi, math.radians(65))])


def land_mask():
    return LandMask(polygons=[(ISLAND, [LAKE]), ISLAND + [1000.0, 0.0]])


def radar_sensor():
    return SensorModel(detection=radar_detection(),
                       clutter=ClutterDensityModel(factors=[RangeBands(edges=(1000,), values=(1e-3, 1e-2))]),
                       mounting=Mounting(forward=4.0, left=-1.0, yaw=0.1),
                       pd_evaluation="gauss-hermite", pd_order=5, name="radar")


def lidar_sensor():
    return SensorModel(
        detection=DetectionProbabilityModel(factors=[RangeBands(edges=(50, 80), values=(0.95, 0.2, 0.0))]),
        clutter=ClutterDensityModel(factors=[
            MetadataThreshold(key="area", threshold=10, below=1e-1, at_or_above=1e-3)]),
        name="lidar")


def spatial_sensor():
    """A 3-D radar: slant range, an elevation beam and the horizon at each target's height."""
    return SensorModel(detection=spatial_detection(), clutter=ClutterDensityModel(factors=[1e-4]),
                       position_mapping=(0, 2, 4), mounting=Mounting(forward=1.0, up=12.0),
                       pd_evaluation="cubature", name="3-D radar")


def spatial_detection():
    return DetectionProbabilityModel(factors=[
        0.9, RangeBands(edges=(1500,), values=(1.0, 0.0)),
        ElevationSector(lower=math.radians(-5), upper=math.radians(25)),
        RadarHorizon(antenna_height=30.0, target_height=None, earth_radius=20_000.0)])


def navigation():
    times = [T0 + datetime.timedelta(seconds=s) for s in (0.0, 1.5, 4.0)]
    return NavigationTrack(timestamps=times, positions=[[0.0, 0.0], [10.0, 5.0], [12.0, 30.0]],
                           headings=[3.0, -3.0, -1.0])


FACTORIES = {
    "RangeBands": lambda: RangeBands(edges=(50, 80), values=(0.95, 0.2, 0.0)),
    "RangeBands-per-edge": lambda: RangeBands(edges=(50, 1612), values=(0, 0.4, 0), upper_owns=(False, True)),
    "AngularSector": lambda: AngularSector(centre=math.pi, width=math.radians(65), inside=0.1, outside=0.9),
    "LandMask": land_mask,
    "LandMask-shapely-Polygon": lambda: LandMask(polygons=Polygon(ISLAND, [LAKE])),
    "LandMask-shapely-MultiPolygon": lambda: LandMask(polygons=MultiPolygon(
        [Polygon(ISLAND, [LAKE]), Polygon(ISLAND + [1000.0, 0.0])])),
    "LineOfSight": lambda: LineOfSight(land=land_mask()),
    "LineOfSight-clearance": lambda: LineOfSight(land=land_mask(), clearance=250.0),
    "RadarEquation": lambda: RadarEquation(reference_snr=13.0, reference_range=1500.0,
                                           false_alarm_probability=1e-6, swerling=3, pulses=4,
                                           loss=1.5),
    "RadarHorizon": lambda: RadarHorizon(antenna_height=20.0, target_height=3.0),
    "RadarHorizon-target-height": lambda: RadarHorizon(antenna_height=20.0, target_height=None, k=1.2),
    "ElevationSector": lambda: ElevationSector(lower=-0.05, upper=0.4, inside=0.8, outside=0.1),
    "RangeRateNotch": lambda: RangeRateNotch(width=1.5, blind_speed=30.0, multiples=2, inside=0.1),
    "DetectionProbabilityModel": radar_detection,
    "DetectionProbabilityModel-3d": spatial_detection,
    "DetectionProbabilityModel-radar-equation": lambda: DetectionProbabilityModel(factors=[
        RadarEquation(reference_snr=10.0, reference_range=800.0, false_alarm_probability=1e-5),
        RadarHorizon(antenna_height=5.0)]),
    "DetectionProbabilityModel-land": lambda: DetectionProbabilityModel(
        factors=[0.9, land_mask(), LineOfSight(land=land_mask())]),
    "MetadataThreshold": lambda: MetadataThreshold(key="area", threshold=10, below=1e-1, at_or_above=1e-3),
    "MetadataThreshold-missing": lambda: MetadataThreshold(key="snr", threshold=3.5, below=2.0,
                                                           at_or_above=0.5, missing=1.0),
    "CoastalClutter": lambda: CoastalClutter(land=land_mask(), width=30.0, inside=20.0),
    "Zone": lambda: Zone(polygons=land_mask(), inside=10.0, outside=0.5),
    "ClutterDensityModel-zone": lambda: ClutterDensityModel(factors=[
        1e-3, Zone(polygons=land_mask(), inside=0.01)]),
    "ClutterDensityModel-coast": lambda: ClutterDensityModel(factors=[
        1e-3, CoastalClutter(land=land_mask(), width=15.0, inside=50.0, seen_only=False)]),
    "ClutterDensityModel": lambda: ClutterDensityModel(factors=[
        2.0, RangeBands(edges=(1000,), values=(1e-3, 1e-2)),
        MetadataThreshold(key="area", threshold=10, below=1e-1, at_or_above=1e-3)]),
    "Pose": lambda: Pose(x=10.0, y=-3.5, heading=2.5),
    "Pose-raised": lambda: Pose(x=10.0, y=-3.5, heading=2.5, z=40.0),
    "Pose-moving": lambda: Pose(x=10.0, y=-3.5, heading=2.5, z=40.0, vx=3.0, vy=-1.0, vz=0.5),
    "Mounting": lambda: Mounting(forward=4.0, left=-1.0, yaw=0.1),
    "Mounting-up": lambda: Mounting(forward=4.0, left=-1.0, yaw=0.1, up=6.5),
    "ConstantPose": lambda: ConstantPose(pose=Pose(x=1.0, y=2.0, heading=-0.5)),
    "NavigationTrack": navigation,
    "NavigationTrack-heights": lambda: NavigationTrack(
        timestamps=[T0 + datetime.timedelta(seconds=s) for s in (0.0, 1.5, 4.0)],
        positions=[[0.0, 0.0, 5.0], [10.0, 5.0, 7.5], [12.0, 30.0, 2.0]], headings=[3.0, -3.0, -1.0]),
    "SensorModel-radar": radar_sensor,
    "SensorModel-lidar": lidar_sensor,
    "SensorModel-3d": spatial_sensor,
}


def behaviour(obj):
    """What the component computes, as arrays/tuples to compare bit for bit."""
    pose = Pose(x=15.0, y=-20.0, heading=2.2)
    raised = Pose(x=15.0, y=-20.0, heading=2.2, z=25.0)
    if isinstance(obj, Zone):
        return obj(STATES[:, 0::2] / 4)
    if isinstance(obj, (RangeBands, RadarHorizon)):
        return obj(np.linspace(0, 40_000, 4001))
    if isinstance(obj, RadarEquation):
        return obj(np.linspace(0, 4000, 4001)), obj.threshold
    if isinstance(obj, AngularSector):
        return DetectionProbabilityModel(factors=[obj]).evaluate(pose, STATES)
    if isinstance(obj, RangeRateNotch):
        moving = Pose(x=15.0, y=-20.0, heading=2.2, vx=2.0)
        return DetectionProbabilityModel(factors=[obj]).evaluate(moving, STATES, velocity_mapping=(1, 3))
    if isinstance(obj, ElevationSector):
        return DetectionProbabilityModel(factors=[obj]).evaluate(raised, STATES_3D, (0, 2, 4))
    if isinstance(obj, DetectionProbabilityModel) and any(
            isinstance(f, ElevationSector) for f in obj.factors):
        return (obj.evaluate(raised, STATES_3D, (0, 2, 4)),
                obj.expected(raised, STATES_3D, COVARS_3D, (0, 2, 4), "cubature"))
    if isinstance(obj, LandMask):
        return obj.contains(STATES[:, 0::2] / 4)
    if isinstance(obj, LineOfSight):
        return obj.visible((0.0, 0.0), STATES[:, 0::2] / 4)
    if isinstance(obj, DetectionProbabilityModel):
        return (obj.evaluate(pose, STATES / 4),
                obj.expected(pose, STATES / 4, COVARS, (0, 2), "cubature"))
    if isinstance(obj, MetadataThreshold):
        column = AREAS.copy()
        column[::7] = np.nan
        if obj.missing is None:
            column[::7] = 1.0
        return ClutterDensityModel(factors=[obj]).evaluate(pose, STATES[:, 0::2], column)
    if isinstance(obj, CoastalClutter):
        return obj.evaluate(pose, STATES[:, 0::2] / 4)
    if isinstance(obj, ClutterDensityModel):
        areas = AREAS if obj.metadata_keys else None
        return obj.evaluate(pose, STATES[:, 0::2], areas), obj.evaluate(pose, STATES[:, 0::2] / 4, areas)
    if isinstance(obj, Pose):
        return obj.as_tuple()
    if isinstance(obj, Mounting):
        return obj.apply(pose).as_tuple()
    if isinstance(obj, ConstantPose):
        return obj.pose_at(T0).as_tuple()
    if isinstance(obj, NavigationTrack):
        return [obj.pose_at(T0 + datetime.timedelta(seconds=s)).as_tuple() for s in np.linspace(0, 4, 17)]
    if isinstance(obj, SensorModel) and len(obj.position_mapping) == 3:
        context = obj.context(raised, T0)
        return (context.pose.as_tuple(), context.prob_detection_array(STATES_3D),
                context.prob_detection_array(STATES_3D, COVARS_3D),
                context.clutter_spatial_density_array(STATES_3D[:, 0::2][:, :2]))
    if isinstance(obj, SensorModel):
        context = obj.context(pose, T0)
        metadata = [{"area": a} for a in AREAS[:, 0]]
        return (context.pose.as_tuple(), context.prob_detection_array(STATES),
                context.prob_detection_array(STATES, COVARS),
                context.clutter_spatial_density_array(STATES[:, 0::2], metadata))
    raise AssertionError(f"no behaviour for {type(obj).__name__}")


def assert_same_behaviour(a, b):
    for x, y in zip(_flatten(behaviour(a)), _flatten(behaviour(b)), strict=True):
        np.testing.assert_array_equal(x, y)


def _flatten(value):
    if isinstance(value, tuple) and any(isinstance(v, np.ndarray) for v in value):
        return [np.asarray(v, dtype=float) for v in value]
    return [np.asarray(value, dtype=float)]


@pytest.fixture(params=sorted(FACTORIES))
def factory(request):
    return FACTORIES[request.param]


def test_every_public_component_class_is_covered():
    classes = {type(f()) for f in FACTORIES.values()}
    public = {getattr(ctxmodels, name) for name in ctxmodels.__all__}
    components = {c for c in public
                  if isinstance(c, type) and issubclass(c, ctxmodels._component.ModelComponent)}
    components -= {ctxmodels.PoseSource}  # abstract
    assert components <= classes


def test_repr_names_the_class_and_its_properties(factory):
    obj = factory()
    text = repr(obj)
    assert text.startswith(type(obj).__name__ + "(")
    for name in type(obj).properties:
        assert f"{name}=" in text
    assert str(obj)


def test_equal_values_are_equal_and_hash_alike(factory):
    a, b = factory(), factory()
    assert a is not b
    assert a == b and not (a != b)
    assert hash(a) == hash(b)
    assert len({a, b}) == 1
    assert a != object() and a != None  # noqa: E711


@pytest.mark.parametrize("make, other", [
    (FACTORIES["RangeBands"], lambda: RangeBands(edges=(50, 80), values=(0.95, 0.25, 0.0))),
    (FACTORIES["RangeBands"], lambda: RangeBands(edges=(50, 80), values=(0.95, 0.2, 0.0), upper_owns=False)),
    (FACTORIES["AngularSector"],
     lambda: AngularSector(centre=-math.pi, width=math.radians(65), inside=0.1, outside=0.9)),
    (FACTORIES["RadarEquation"], lambda: RadarEquation(
        reference_snr=13.0, reference_range=1500.0, false_alarm_probability=1e-6, swerling=4,
        pulses=4, loss=1.5)),
    (FACTORIES["RadarHorizon"], lambda: RadarHorizon(antenna_height=20.0, target_height=3.5)),
    (FACTORIES["RadarHorizon"], lambda: RadarHorizon(antenna_height=20.0, target_height=None)),
    (FACTORIES["ElevationSector"], lambda: ElevationSector(lower=-0.05, upper=0.41, inside=0.8,
                                                           outside=0.1)),
    (FACTORIES["Pose-raised"], lambda: Pose(x=10.0, y=-3.5, heading=2.5, z=40.5)),
    (FACTORIES["Pose-moving"], lambda: Pose(x=10.0, y=-3.5, heading=2.5, z=40.0, vx=3.5, vy=-1.0,
                                            vz=0.5)),
    (FACTORIES["RangeRateNotch"], lambda: RangeRateNotch(width=1.5, blind_speed=31.0, multiples=2,
                                                         inside=0.1)),
    (FACTORIES["Mounting-up"], lambda: Mounting(forward=4.0, left=-1.0, yaw=0.1, up=6.0)),
    (FACTORIES["Zone"], lambda: Zone(polygons=land_mask(), inside=10.0, outside=0.25)),
    (land_mask, lambda: LandMask(polygons=[ISLAND])),
    (FACTORIES["MetadataThreshold"], lambda: MetadataThreshold(key="area", threshold=10, below=1e-1,
                                                               at_or_above=1e-3, missing=1.0)),
    (radar_sensor, lidar_sensor),
    (FACTORIES["Pose"], lambda: Pose(x=10.0, y=-3.5, heading=2.5 + 1e-12)),
])
def test_different_values_are_unequal(make, other):
    assert make() != other()


def test_pickle_round_trip(factory):
    obj = factory()
    behaviour(obj)  # compiled Rust objects are cached by now and must not be pickled
    restored = pickle.loads(pickle.dumps(obj))
    assert restored == obj and hash(restored) == hash(obj)
    assert_same_behaviour(restored, obj)
    _assert_immutable(restored)


def test_deepcopy(factory):
    obj = factory()
    behaviour(obj)
    clone = copy.deepcopy(obj)
    assert clone == obj and clone is not obj
    assert_same_behaviour(clone, obj)
    _assert_immutable(clone)


def test_stone_soup_yaml_round_trip(factory):
    obj = factory()
    text = YAML().dumps(obj)
    assert f"!{type(obj).__module__}.{type(obj).__name__}" in text
    restored = YAML().load(text)
    assert type(restored) is type(obj)
    assert restored == obj and hash(restored) == hash(obj)
    assert_same_behaviour(restored, obj)
    _assert_immutable(restored)
    assert YAML().dumps(restored) == text


def test_yaml_of_several_components_in_one_document():
    radar, lidar = radar_sensor(), lidar_sensor()
    restored = YAML().load(YAML().dumps({"radar": radar, "lidar": lidar, "nav": navigation()}))
    assert restored["radar"] == radar and restored["lidar"] == lidar and restored["nav"] == navigation()


def test_yaml_tag_of_a_moved_module_loads_the_public_class():
    """A tag names the defining module; one whose module no longer holds the class (the
    layout moved it) loads the package's public class of that name. A name that is not
    public under the tag's package is still an error naming the tag."""
    from ruamel.yaml.constructor import ConstructorError
    from ctxmodels.stonesoup import CircularRegion, PHDUpdater
    text = YAML().dumps({"region": CircularRegion(centre=(1.0, 2.0), radius=3.0),
                         "bands": RangeBands(edges=[50.0], values=[0.9, 0.2])})
    moved = (text.replace(f"!{CircularRegion.__module__}.", "!ctxmodels.stonesoup.pointprocess.")
                 .replace(f"!{RangeBands.__module__}.", "!ctxmodels.bands."))
    assert "!ctxmodels.stonesoup.pointprocess.CircularRegion" in moved
    assert "!ctxmodels.bands.RangeBands" in moved
    restored = YAML().load(moved)
    assert restored["region"].radius == 3.0 and type(restored["region"]) is CircularRegion
    assert restored["bands"] == RangeBands(edges=[50.0], values=[0.9, 0.2])
    assert PHDUpdater.__module__ != "ctxmodels.stonesoup.pointprocess"
    with pytest.raises(ConstructorError, match="ctxmodels.stonesoup.pointprocess.NoSuchThing"):
        YAML().load(moved.replace("pointprocess.CircularRegion", "pointprocess.NoSuchThing"))
    with pytest.raises(ConstructorError, match="ctxmodels.bands.CircularRegion"):
        YAML().load(moved.replace("!ctxmodels.bands.RangeBands", "!ctxmodels.bands.CircularRegion"))


def _assert_immutable(obj):
    for name in type(obj).properties:
        with pytest.raises(AttributeError, match=name):
            setattr(obj, name, getattr(obj, name))


def test_components_are_immutable(factory):
    obj = factory()
    before = behaviour(obj)
    _assert_immutable(obj)
    if hasattr(obj, "factors"):  # the factor list cannot be edited in place behind the cache
        with pytest.raises((AttributeError, TypeError)):
            obj.factors.append(0.5)
        with pytest.raises(TypeError):
            obj.factors[0] = 0.5
    for x, y in zip(_flatten(before), _flatten(behaviour(obj))):
        np.testing.assert_array_equal(x, y)


def test_array_properties_neither_alias_the_input_nor_accept_edits():
    positions, headings, shell = np.array([[0.0, 0.0], [10.0, 0.0]]), np.array([0.0, 1.0]), ISLAND.copy()
    track = NavigationTrack(timestamps=[T0, T0 + datetime.timedelta(seconds=1)], positions=positions,
                            headings=headings)
    land = LandMask(polygons=[shell])
    before = (copy.deepcopy(track), copy.deepcopy(land))
    positions[1, 0], headings[1], shell[0, 0] = 99.0, 2.0, -500.0
    assert (track, land) == before
    for array in (track.positions, track.headings, land.polygons[0]["shell"]):
        with pytest.raises(ValueError):
            array[0] = 1.0


def test_land_mask_from_shapely_equals_arrays_in_behaviour():
    assert_same_behaviour(FACTORIES["LandMask-shapely-MultiPolygon"](), land_mask())
    assert_same_behaviour(FACTORIES["LandMask-shapely-Polygon"](), LandMask(polygons=[(ISLAND, [LAKE])]))


# --- DetectorContext and DetectionSet --------------------------------------------------------
@pytest.fixture
def radar_context():
    return radar_sensor().context(Pose(x=15.0, y=-20.0, heading=2.2), T0)


def test_context_carries_the_mounted_pose_and_timestamp(radar_context):
    sensor = radar_context.sensor_model
    assert radar_context.pose == sensor.mounting.apply(Pose(x=15.0, y=-20.0, heading=2.2))
    assert radar_context.timestamp == T0
    assert isinstance(radar_context, DetectorContext)
    assert "DetectorContext(" in repr(radar_context)
    same_pose = sensor.context((15.0, -20.0, 2.2), T0)  # a tuple pose works too
    assert same_pose.pose == radar_context.pose


def test_contexts_hash_and_compare_by_identity(radar_context):
    twin = radar_context.sensor_model.context(Pose(x=15.0, y=-20.0, heading=2.2), T0)
    assert twin != radar_context and radar_context == radar_context
    assert hash(twin) != hash(radar_context) or twin is radar_context
    assert len({radar_context, twin, radar_context}) == 2
    assert {radar_context: 1}[radar_context] == 1


def _cv(x, y):
    return StateVector([x, 1.0, y, -2.0])


def test_prob_detection_accepts_stone_soup_objects():
    context = lidar_sensor().context(Pose(x=0.0, y=0.0, heading=0.7), T0)  # 'mean' evaluation
    vector = _cv(30.0, 40.0)  # r = 50: the 0.2 band
    prediction = GaussianStatePrediction(vector, np.eye(4) * 100, timestamp=T0)
    model = LinearGaussian(ndim_state=4, mapping=(0, 2), noise_covar=np.eye(2))
    detection = Detection(StateVector([30.0, 40.0]), timestamp=T0, measurement_model=model)
    for item in [SingleHypothesis(prediction, detection), SingleHypothesis(prediction, None), prediction,
                 GaussianState(vector, np.eye(4)), State(vector), vector, np.array([30.0, 1.0, 40.0, -2.0]),
                 [30.0, 1.0, 40.0, -2.0]]:
        pd = context.prob_detection(item)
        assert float(pd) == 0.2, type(item).__name__
    assert type(context.prob_detection(prediction)).__name__ == "Probability"


def test_prob_detection_of_a_particle_state_is_the_weighted_mean():
    context = lidar_sensor().context(Pose(x=5.0, y=5.0, heading=0.0), T0)
    rng = np.random.default_rng(4)
    n = 5000
    particles = np.zeros((4, n))
    particles[0], particles[2] = 5 + rng.normal(0, 60, n), 5 + rng.normal(0, 60, n)
    weights = rng.random(n)
    state = ParticleState(StateVectors(particles), weight=weights / weights.sum(), timestamp=T0)
    pd_each = context.prob_detection_array(particles.T)
    expected = np.sum(weights * pd_each) / np.sum(weights)
    assert float(context.prob_detection(state)) == pytest.approx(expected, rel=1e-12)
    assert float(context.prob_detection(state)) != pytest.approx(pd_each.mean(), rel=1e-6)  # weights matter
    hypothesis = SingleHypothesis(state, None)
    assert float(context.prob_detection(hypothesis)) == pytest.approx(expected, rel=1e-12)


def test_prob_detection_with_expected_pd_uses_the_covariance(radar_context):
    sensor = radar_context.pose
    edge = sensor.heading + math.pi - math.radians(32.5)  # on the blind sector's edge
    mean = _cv(sensor.x + 500 * math.cos(edge), sensor.y + 500 * math.sin(edge))
    prediction = GaussianStatePrediction(mean, np.diag([900.0, 1.0, 400.0, 1.0]), timestamp=T0)
    model = radar_context.sensor_model
    expected = model.detection.expected(radar_context.pose, np.asarray(prediction.state_vector).T,
                                        np.asarray(prediction.covar)[None], (0, 2), "gauss-hermite", 5)
    assert float(radar_context.prob_detection(prediction)) == pytest.approx(expected[0], rel=1e-14)
    assert 0 < expected[0] < 0.4
    at_mean = model.detection.evaluate(radar_context.pose, np.asarray(prediction.state_vector).T)[0]
    at_mean_pd = radar_context.prob_detection(State(prediction.state_vector))
    assert float(at_mean_pd) == pytest.approx(at_mean, rel=1e-14)


def test_prob_detection_states_is_one_call_for_a_list(radar_context):
    rng = np.random.default_rng(6)
    predictions = [GaussianStatePrediction(_cv(*rng.uniform(-1500, 1500, 2)), np.diag([100.0, 1, 100.0, 1]),
                                           timestamp=T0) for _ in range(50)]
    hypotheses = [SingleHypothesis(p, None) for p in predictions]
    batch = radar_context.prob_detection_states(hypotheses)
    # Probability keeps its value as a logarithm, so one-by-one values may differ by an ulp.
    one_by_one = [float(radar_context.prob_detection(h)) for h in hypotheses]
    np.testing.assert_allclose(batch, one_by_one, rtol=1e-14)
    assert len(set(batch)) > 3
    np.testing.assert_array_equal(radar_context.prob_detection_states(predictions), batch)
    assert radar_context.prob_detection_states([]).shape == (0,)


def test_clutter_density_of_a_linear_gaussian_detection():
    lidar = lidar_sensor().context(Pose(x=0.0, y=0.0), T0)
    model = LinearGaussian(ndim_state=4, mapping=(0, 2), noise_covar=np.eye(2))
    small = Detection(StateVector([3.0, 4.0]), timestamp=T0, measurement_model=model, metadata={"area": 2.5})
    large = Detection(StateVector([3.0, 4.0]), timestamp=T0, measurement_model=model, metadata={"area": 12})
    assert lidar.clutter_spatial_density(small) == 1e-1
    assert lidar.clutter_spatial_density(large) == 1e-3
    np.testing.assert_array_equal(lidar.clutter_spatial_density_detections([small, large, small]),
                                  [1e-1, 1e-3, 1e-1])
    # Position-dependent λ reads the position through the model's (pseudo-)inverse.
    radar = radar_sensor().context(Pose(x=0.0, y=0.0, heading=0.0), T0)
    sensor = radar.pose
    near = Detection(StateVector([sensor.x + 600.0, sensor.y + 799.0]), measurement_model=model)
    far = Detection(StateVector([sensor.x + 600.0, sensor.y + 801.0]), measurement_model=model)
    np.testing.assert_array_equal(radar.clutter_spatial_density_detections([near, far]), [1e-3, 1e-2])


@pytest.mark.parametrize("true_range", [20.0, 999.5, 1000.5, 1611.0, 2500.0])
@pytest.mark.parametrize("bearing", [-3.0, -0.5, 0.0, 1.0, 3.1])
def test_clutter_density_of_a_bearing_range_detection(true_range, bearing):
    """The radar's λ band follows the detection's true range from the sensor."""
    context = radar_sensor().context(Pose(x=-40.0, y=25.0, heading=1.3), T0)
    sensor = context.pose
    model = CartesianToBearingRange(ndim_state=4, mapping=(0, 2), noise_covar=np.diag([1e-4, 1.0]),
                                    translation_offset=StateVector([sensor.x, sensor.y]),
                                    rotation_offset=StateVector([0.0, 0.0, sensor.heading]))
    detection = Detection(StateVector([bearing, true_range]), timestamp=T0, measurement_model=model)
    assert context.clutter_spatial_density(detection) == (1e-3 if true_range < 1000 else 1e-2)


def test_detection_set_carries_its_context(radar_context):
    model = LinearGaussian(ndim_state=4, mapping=(0, 2), noise_covar=np.eye(2))
    detections = {Detection(StateVector([float(i), 2.0]), timestamp=T0, measurement_model=model)
                  for i in range(3)}
    scan = DetectionSet(detections, radar_context)
    assert isinstance(scan, set) and set(scan) == detections
    assert scan.detector_context is radar_context
    assert scan.copy().detector_context is radar_context and scan.copy() == scan
    empty = DetectionSet(detector_context=radar_context)
    assert len(empty) == 0 and empty.detector_context is radar_context
    assert DetectionSet().detector_context is None

    restored = pickle.loads(pickle.dumps(scan))
    assert isinstance(restored, DetectionSet) and len(restored) == 3
    context = restored.detector_context
    assert isinstance(context, DetectorContext) and context is not radar_context  # identity is per object
    assert (context.sensor_model, context.pose, context.timestamp) == \
        (radar_context.sensor_model, radar_context.pose, radar_context.timestamp)
    np.testing.assert_array_equal(context.prob_detection_array(STATES),
                                  radar_context.prob_detection_array(STATES))
    empty_restored = pickle.loads(pickle.dumps(empty))
    assert len(empty_restored) == 0 and empty_restored.detector_context.pose == radar_context.pose


def test_default_position_mapping_is_stone_soups_cv_layout():
    """The core's `position_mapping` default (0, 2) — shown as `...` in its signature."""
    core = radar_detection()._compiled()
    pose = (15.0, -20.0, 2.2)
    np.testing.assert_array_equal(core.evaluate(pose, STATES), core.evaluate(pose, STATES, (0, 2)))
    np.testing.assert_array_equal(core.expected(pose, STATES, COVARS),
                                  core.expected(pose, STATES, COVARS, (0, 2), "cubature", 3))


# --- the type stubs ----------------------------------------------------------------------------
def test_stub_declares_exactly_what_the_core_exports():
    """A quick guard; ``python -m mypy.stubtest ctxmodels._core`` (scripts/test.sh) does
    the full signature check."""
    stub = pathlib.Path(_core.__file__).with_name("_core.pyi")
    tree = ast.parse(stub.read_text())
    declared = {node.name for node in tree.body if isinstance(node, (ast.ClassDef, ast.FunctionDef))}
    assert declared == set(_core.__all__)
    assert (stub.parent / "py.typed").exists()
    for node in tree.body:
        if isinstance(node, ast.ClassDef):
            runtime = {n for n in vars(getattr(_core, node.name)) if not n.startswith("_")}
            stubbed = {n.name for n in node.body
                       if isinstance(n, ast.FunctionDef) and not n.name.startswith("_")}
            assert stubbed == runtime, node.name


def test_shapely_union_is_the_reference_for_the_masks_used_here():
    """The masks above are valid shapely geometry (so the round-trips test real land)."""
    union = shapely.union_all([Polygon(ISLAND, [LAKE]), Polygon(ISLAND + [1000.0, 0.0])])
    points = STATES[:, 0::2] / 4
    np.testing.assert_array_equal(land_mask().contains(points),
                                  shapely.intersects_xy(union, points[:, 0], points[:, 1]))


def test_poses_a_navigation_track_and_a_mounting_compute_are_ordinary_poses():
    """pose_at and Mounting.apply build their Poses without the Property checks: each must
    be the Pose the constructor builds from the same floats, in every respect."""
    import pickle
    track = navigation()
    mounting = Mounting(forward=3.0, left=-1.0, yaw=0.25)
    for seconds in (0.0, 0.37, 1.5, 2.0, 4.0):  # (4.0: the last sample)
        pose = track.pose_at(T0 + datetime.timedelta(seconds=seconds))
        for made in (pose, mounting.apply(pose)):
            built = Pose(**{name: getattr(made, name)
                            for name in ("x", "y", "heading", "z", "vx", "vy", "vz")})
            assert type(made) is Pose
            assert made.__dict__ == built.__dict__ and list(made.__dict__) == list(built.__dict__)
            assert made == built and hash(made) == hash(built) and repr(made) == repr(built)
            assert pickle.loads(pickle.dumps(made)) == built
            with pytest.raises(AttributeError, match="immutable"):
                made.x = 1.0
