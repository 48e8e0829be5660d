"""The reference paper's four sensor equations, built the way docs/guide.md builds them, checked
case by case at their edges and against a literal transcription of the equations.

eq. pd-lidar      P_D = 0.95 (r < 50), 0.2 (50 ≤ r < 80), 0 (r ≥ 80)
eq. pd-radar      P_D = 0.4 for 50 < r < 1612 outside the 65° blind sector astern, else 0
eq. lambda-lidar  λ = 1e-1 (area < 10), 1e-3 otherwise
eq. lambda-radar  λ = 1e-3 (r < 1000), 1e-2 otherwise
"""
import datetime
import math

import numpy as np
import pytest
from stonesoup.models.measurement.linear import LinearGaussian
from stonesoup.models.measurement.nonlinear import CartesianToBearingRange
from stonesoup.types.array import StateVector
from stonesoup.types.detection import Detection
from stonesoup.types.prediction import GaussianStatePrediction

from ctxmodels import (AngularSector, ClutterDensityModel, DetectionProbabilityModel,
                       MetadataThreshold, Mounting, Pose, RangeBands, SensorModel)

T0 = datetime.datetime(2024, 5, 1, 12, 0, 0)
HALF_BLIND = math.radians(65) / 2
TINY = 1e-9  # radians: far above rounding (~1e-15 rad), far below anything physical


def lidar_model(**kwargs) -> SensorModel:
    return SensorModel(
        detection=DetectionProbabilityModel(factors=[RangeBands(edges=(50, 80), values=(0.95, 0.2, 0.0))]),
        clutter=ClutterDensityModel(factors=[
            MetadataThreshold(key="area", threshold=10, below=1e-1, at_or_above=1e-3)]),
        name="lidar", **kwargs)


def radar_model(**kwargs) -> SensorModel:
    return SensorModel(
        detection=DetectionProbabilityModel(factors=[
            RangeBands(edges=(50, 1612), values=(0, 0.4, 0), upper_owns=(False, True)),
            AngularSector.blind(math.pi, math.radians(65))]),
        clutter=ClutterDensityModel(factors=[RangeBands(edges=(1000,), values=(1e-3, 1e-2))]),
        name="radar", **kwargs)


# --- the equations, transcribed literally (the independent reference) ------------------------
def paper_pd_lidar(r):
    return 0.95 if r < 50 else 0.2 if r < 80 else 0.0


def paper_pd_radar(r, body_bearing):
    off_astern = abs(math.remainder(body_bearing - math.pi, 2 * math.pi))
    in_sector = off_astern > HALF_BLIND  # "in-sector": outside the blind sector
    return 0.4 if 50 < r < 1612 and in_sector else 0.0


def paper_lambda_lidar(area):
    return 1e-1 if area < 10 else 1e-3


def paper_lambda_radar(r):
    return 1e-3 if r < 1000 else 1e-2


def cv_rows(xy) -> np.ndarray:
    """[x, vx, y, vy] rows (Stone Soup's constant-velocity layout) at positions `xy`."""
    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    rows = np.zeros((len(xy), 4))
    rows[:, 0], rows[:, 2] = xy[:, 0], xy[:, 1]
    rows[:, 1], rows[:, 3] = 3.0, -1.0  # velocities must not matter
    return rows


# --- eq. pd-lidar ------------------------------------------------------------------------------
# Offsets whose length is exact in binary floating point (axis-aligned, or 3-4-5 triangles).
LIDAR_CASES = [
    ((0.0, 0.0), 0.95),
    ((49.999, 0.0), 0.95),
    ((30.0, -40.0), 0.2),      # r = 50 exactly: the upper band owns the edge
    ((0.0, -50.0), 0.2),
    ((-79.999, 0.0), 0.2),
    ((48.0, 64.0), 0.0),       # r = 80 exactly
    ((0.0, 80.0), 0.0),
    ((600.0, 800.0), 0.0),
]


@pytest.mark.parametrize("heading", [0.0, 1.1, -2.9])
@pytest.mark.parametrize("offset, expected", LIDAR_CASES)
def test_pd_lidar_edges(offset, expected, heading):
    sensor = (12.5, -7.25)
    target = (sensor[0] + offset[0], sensor[1] + offset[1])
    r = math.hypot(target[0] - sensor[0], target[1] - sensor[1])
    assert expected == paper_pd_lidar(r)  # the case list itself matches the paper
    context = lidar_model().context(Pose(x=sensor[0], y=sensor[1], heading=heading), T0)
    assert context.prob_detection_array(cv_rows(target))[0] == expected
    prediction = GaussianStatePrediction(StateVector(cv_rows(target)[0]), np.eye(4), timestamp=T0)
    assert float(context.prob_detection(prediction)) == expected


# --- eq. pd-radar ------------------------------------------------------------------------------
# Sensor facing +y (heading π/2), so world +x is the starboard beam (body bearing -π/2),
# clear of the blind sector: axis-aligned offsets by dyadic ranges are exact on the edges.
RADAR_RANGE_CASES = [
    (0.0, 0.0),
    (49.75, 0.0),
    (50.0, 0.0),              # 50 < r: the edge belongs to the band below
    (50 + 2**-20, 0.4),
    (800.0, 0.4),
    (1612 - 2**-20, 0.4),
    (1612.0, 0.0),            # r < 1612: the edge belongs to the band above
    (1612.25, 0.0),
    (5000.0, 0.0),
]


@pytest.mark.parametrize("r, expected", RADAR_RANGE_CASES)
def test_pd_radar_range_edges(r, expected):
    sensor = (100.0, -40.0)
    context = radar_model().context(Pose(x=sensor[0], y=sensor[1], heading=math.pi / 2), T0)
    target = (sensor[0] + r, sensor[1])
    assert math.hypot(target[0] - sensor[0], target[1] - sensor[1]) == r
    assert expected == paper_pd_radar(r, -math.pi / 2)
    assert context.prob_detection_array(cv_rows(target))[0] == expected


SECTOR_BEARINGS = [
    (math.pi, 0.0),                            # straight astern: blind
    (-math.pi, 0.0),
    (math.pi - HALF_BLIND + TINY, 0.0),        # just inside the blind sector, port side
    (-math.pi + HALF_BLIND - TINY, 0.0),       # just inside, starboard side (across ±π)
    (math.pi - HALF_BLIND - TINY, 0.4),        # just outside
    (-math.pi + HALF_BLIND + TINY, 0.4),
    (0.0, 0.4),                                # ahead
    (math.pi / 2, 0.4),                        # abeam
    (-math.pi / 2, 0.4),
]


@pytest.mark.parametrize("heading", [0.0, math.pi / 2, -2.5, 3.1, -math.pi, 7.0])
@pytest.mark.parametrize("bearing, expected", SECTOR_BEARINGS)
def test_pd_radar_blind_sector_edges(bearing, expected, heading):
    sensor = (-350.0, 220.0)
    r = 500.0
    target = (sensor[0] + r * math.cos(heading + bearing), sensor[1] + r * math.sin(heading + bearing))
    assert expected == paper_pd_radar(r, bearing)
    context = radar_model().context(Pose(x=sensor[0], y=sensor[1], heading=heading), T0)
    assert context.prob_detection_array(cv_rows(target))[0] == expected


def test_pd_radar_is_measured_from_the_mounted_sensor():
    """A lever arm moves the range origin and a yaw turns the blind sector with the sensor."""
    mounting = Mounting(forward=5.0, left=-1.5, yaw=math.pi / 2)
    platform = Pose(x=10.0, y=20.0, heading=0.0)
    context = radar_model(mounting=mounting).context(platform, T0)
    # Facing +x, forward 5 m and 1.5 m to the right: the sensor is at (15, 18.5), heading +y.
    assert (context.pose.x, context.pose.y) == (15.0, 18.5)
    assert context.pose.heading == pytest.approx(math.pi / 2, abs=1e-15)
    at_50 = (65.0, 18.5)                     # 50 m from the sensor (its beam), 55 m from the platform
    astern = (15.0, 18.5 - 500.0)            # the sensor's astern is the platform's right
    platform_astern = (10.0 - 500.0, 20.0)   # astern of the platform, abeam of the sensor
    targets = cv_rows([at_50, astern, platform_astern, (65.0 + 2**-20, 18.5)])
    np.testing.assert_array_equal(context.prob_detection_array(targets), [0.0, 0.0, 0.4, 0.4])
    unmounted = radar_model().context(platform, T0).prob_detection_array(targets)
    np.testing.assert_array_equal(unmounted, [0.4, 0.4, 0.0, 0.4])


def test_paper_pd_over_random_positions_matches_the_equations():
    """10⁴ random positions per sensor, plus headings and sensor positions, against the
    literal equations (ranges and bearings from hypot/atan2; points within 1e-9 of an
    edge, where the two formulations may round differently, are left out)."""
    rng = np.random.default_rng(20240501)
    for model, equation, extent in [(radar_model(), paper_pd_radar, 2000.0),
                                    (lidar_model(), lambda r, b: paper_pd_lidar(r), 100.0)]:
        for _ in range(3):
            sx, sy, heading = rng.uniform(-1e3, 1e3), rng.uniform(-1e3, 1e3), rng.uniform(-7, 7)
            xy = np.column_stack([sx + rng.uniform(-extent, extent, 10_000),
                                  sy + rng.uniform(-extent, extent, 10_000)])
            got = model.context(Pose(x=sx, y=sy, heading=heading)).prob_detection_array(cv_rows(xy))
            r = np.hypot(xy[:, 0] - sx, xy[:, 1] - sy)
            bearing = np.arctan2(xy[:, 1] - sy, xy[:, 0] - sx) - heading
            expected = np.array([equation(ri, bi) for ri, bi in zip(r, bearing)])
            off_astern = np.abs(np.remainder(bearing, 2 * np.pi) - np.pi)
            clear = (np.min(np.abs(r[:, None] - np.array([50, 80, 1612])), axis=1) > 1e-9) \
                & (np.abs(off_astern - HALF_BLIND) > 1e-9)
            assert clear.sum() > 9_900
            np.testing.assert_array_equal(got[clear], expected[clear])
            assert len(set(expected[clear])) >= 2


# --- eq. lambda-lidar --------------------------------------------------------------------------
@pytest.mark.parametrize("area, expected", [(0.0, 1e-1), (9.999, 1e-1), (10, 1e-3), (10.0, 1e-3),
                                            (10.001, 1e-3), (250.0, 1e-3)])
def test_lambda_lidar_area_rule(area, expected):
    assert expected == paper_lambda_lidar(area)
    context = lidar_model().context(Pose(x=3.0, y=4.0, heading=0.3), T0)
    model = LinearGaussian(ndim_state=4, mapping=(0, 2), noise_covar=np.eye(2) * 0.1)
    detection = Detection(StateVector([30.0, -2.0]), timestamp=T0, measurement_model=model,
                          metadata={"area": area, "label": "car"})
    assert context.clutter_spatial_density(detection) == expected
    many = context.clutter_spatial_density_detections([detection] * 3)
    np.testing.assert_array_equal(many, [expected] * 3)


def test_lambda_lidar_without_area_is_an_error():
    context = lidar_model().context(Pose(x=0.0, y=0.0), T0)
    model = LinearGaussian(ndim_state=4, mapping=(0, 2), noise_covar=np.eye(2))
    detection = Detection(StateVector([1.0, 2.0]), timestamp=T0, measurement_model=model, metadata={})
    with pytest.raises(ValueError, match="metadata: detection 0 has no 'area'"):
        context.clutter_spatial_density(detection)


def test_experiment_lidar_needs_area_unless_told_what_to_do_without_it():
    """The experiment's lidar clutter model has no silent default for a detection without
    ``area`` (it would quietly turn the context-aware tracker into the P_D-aware one): an
    error naming the key, unless ``lidar_missing_area`` gives its λ."""
    from ctxmodels.experiment.sensors import paper_sensor_models
    model = LinearGaussian(ndim_state=4, mapping=(0, 2), noise_covar=np.eye(2))
    with_area = Detection(StateVector([1.0, 2.0]), timestamp=T0, measurement_model=model,
                          metadata={"area": 3.0})
    without = Detection(StateVector([1.0, 2.0]), timestamp=T0, measurement_model=model,
                        metadata={"label": "car"})
    strict = paper_sensor_models()["lidar"].context(Pose(x=0.0, y=0.0), T0)
    assert strict.clutter_spatial_density(with_area) == 1e-1
    with pytest.raises(ValueError, match="detection 1 has no 'area'.*set the rule's `missing`"):
        strict.clutter_spatial_density_detections([with_area, without])
    told = paper_sensor_models(lidar_missing_area=2e-3)["lidar"].context(Pose(x=0.0, y=0.0), T0)
    np.testing.assert_array_equal(told.clutter_spatial_density_detections([with_area, without]),
                                  [1e-1, 2e-3])
    # The uniform model reads no metadata at all.
    uniform = paper_sensor_models(clutter="uniform")["lidar"].context(Pose(x=0.0, y=0.0), T0)
    assert uniform.clutter_spatial_density(without) == 1e-3


# --- eq. lambda-radar --------------------------------------------------------------------------
@pytest.mark.parametrize("true_range, expected", [(10.0, 1e-3), (999.0, 1e-3), (999.999, 1e-3),
                                                  (1000.001, 1e-2), (1500.0, 1e-2), (3000.0, 1e-2)])
@pytest.mark.parametrize("bearing", [0.0, 2.0, -3.0])
def test_lambda_radar_from_bearing_range_detections(true_range, expected, bearing):
    """The detection's position comes from the measurement model's inverse, and λ's range
    band must match the true range from the (mounted) sensor."""
    platform = Pose(x=-120.0, y=75.0, heading=0.8)
    radar = radar_model(mounting=Mounting(forward=4.0, left=1.0, yaw=0.0))
    context = radar.context(platform, T0)
    sensor = context.pose
    model = CartesianToBearingRange(
        ndim_state=4, mapping=(0, 2), noise_covar=np.diag([1e-4, 1.0]),
        translation_offset=StateVector([sensor.x, sensor.y]),
        rotation_offset=StateVector([0.0, 0.0, sensor.heading]))
    detection = Detection(StateVector([bearing, true_range]), timestamp=T0, measurement_model=model)
    assert expected == paper_lambda_radar(true_range)
    assert context.clutter_spatial_density(detection) == expected


def test_lambda_radar_edge_at_exactly_1000():
    context = radar_model().context(Pose(x=5.0, y=-5.0, heading=-1.0), T0)
    positions = np.array([[5.0 + 1000.0, -5.0], [5.0, -5.0 - 1000.0], [5.0 + 600.0, -5.0 + 800.0],
                          [5.0 + 999.9999, -5.0], [5.0, -5.0]])
    r = np.hypot(positions[:, 0] - 5.0, positions[:, 1] + 5.0)
    expected = [paper_lambda_radar(x) for x in r]
    assert expected == [1e-2, 1e-2, 1e-2, 1e-3, 1e-3]
    np.testing.assert_array_equal(context.clutter_spatial_density_array(positions), expected)


def test_fused_scan_contexts_answer_per_sensor():
    """The paper's point: at the same instant a target 1 km away is unseen by the lidar but
    visible to the radar, so only the radar scan should count a miss."""
    platform = Pose(x=0.0, y=0.0, heading=0.0)
    far, near = cv_rows([(1000.0, 0.0)]), cv_rows([(30.0, 0.0)])
    lidar, radar = lidar_model().context(platform, T0), radar_model().context(platform, T0)
    assert lidar.prob_detection_array(far)[0] == 0.0
    assert radar.prob_detection_array(far)[0] == 0.4
    assert lidar.prob_detection_array(near)[0] == 0.95
    assert radar.prob_detection_array(near)[0] == 0.0
