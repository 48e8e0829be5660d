"""λ of detections with a height (a 3-D radar's): range bands on the slant range from the
sensor's height, elevation sectors on the elevation above it, maps and zones on the plane
below — against a NumPy computation with atan2 elevations, and through Stone Soup's own
elevation–bearing–range detections (their measured slant range read by the bands); a
planar model of such a clutter model and (M, 2) positions are refused by name."""
from __future__ import annotations

import datetime
import math

import numpy as np
import pytest
from stonesoup.models.measurement.nonlinear import CartesianToElevationBearingRange
from stonesoup.types.detection import Detection
from stonesoup.types.state import State

from ctxmodels import (ArgumentError, ClutterDensityModel, DetectionProbabilityModel,
                       ElevationSector, LandMask, Pose, RangeBands, SensorModel, ShapeError, Zone)
from ctxmodels.stonesoup import MeasurementDrivenBirth

T0 = datetime.datetime(2026, 1, 1)
POSE = Pose(x=120.0, y=-80.0, heading=0.4, z=25.0)
LOW, HIGH = math.radians(-3.0), math.radians(1.5)


def _model():
    harbour = LandMask(polygons=[[(0, 0), (3000, 0), (3000, 3000), (0, 3000)]])
    return ClutterDensityModel(factors=[
        2e-7, RangeBands(edges=(2000.0, 6000.0), values=(3.0, 1.0, 0.2)),
        ElevationSector(lower=LOW, upper=HIGH, inside=40.0, outside=1.0),
        Zone(polygons=harbour, inside=5.0, outside=1.0)])


def _numpy_lambda(positions, pose, ranges=None):
    dx, dy, dz = (positions[:, 0] - pose.x, positions[:, 1] - pose.y, positions[:, 2] - pose.z)
    slant = np.sqrt(dx ** 2 + dy ** 2 + dz ** 2) if ranges is None else ranges
    bands = np.select([slant <= 2000.0, slant <= 6000.0], [3.0, 1.0], 0.2)
    elevation = np.arctan2(dz, np.hypot(dx, dy))
    sea = np.where((elevation >= LOW) & (elevation <= HIGH), 40.0, 1.0)
    harbour = np.where((positions[:, 0] >= 0) & (positions[:, 0] <= 3000)
                       & (positions[:, 1] >= 0) & (positions[:, 1] <= 3000), 5.0, 1.0)
    return 2e-7 * bands * sea * harbour, slant, elevation


def test_lambda_with_heights_is_numpys():
    rng = np.random.default_rng(3)
    n = 20_000
    positions = np.column_stack([rng.uniform(-8000, 8000, n), rng.uniform(-8000, 8000, n),
                                 rng.uniform(-50, 600, n)])
    got = _model().evaluate(POSE, positions)
    want, slant, elevation = _numpy_lambda(positions, POSE)
    # away from the band edges and the elevation limits (no decision is rounded there)
    clear = ((np.abs(slant - 2000) > 1e-6) & (np.abs(slant - 6000) > 1e-6)
             & (np.abs(elevation - LOW) > 1e-9) & (np.abs(elevation - HIGH) > 1e-9))
    assert clear.mean() > 0.999
    np.testing.assert_allclose(got[clear], want[clear], rtol=1e-14)
    assert len(np.unique(np.round(want / 2e-7, 6))) >= 10  # every factor is in play
    # the heights matter: the same detections read on the plane would differ
    planar = ClutterDensityModel(factors=[f for f in _model().factors
                                          if not isinstance(f, ElevationSector)])
    plane = planar.evaluate(POSE, positions[:, :2])
    raised = planar.evaluate(POSE, positions)
    assert np.mean(plane != raised) > 0.001  # slant against plane range at the band edges


def test_stone_soups_elevation_bearing_range_detections():
    """Detections of a 3-D radar (Stone Soup's measurement model, measured from the sensor's
    position): λ from their inverse positions, the bands reading the measured slant range."""
    rng = np.random.default_rng(8)
    model = CartesianToElevationBearingRange(
        ndim_state=6, mapping=(0, 2, 4), noise_covar=np.eye(3),
        translation_offset=np.array([[POSE.x], [POSE.y], [POSE.z]]))
    truths = np.column_stack([rng.uniform(-6000, 6000, 300), np.zeros(300),
                              rng.uniform(-6000, 6000, 300), np.zeros(300),
                              rng.uniform(0, 400, 300), np.zeros(300)])
    truths[:5, 4] = POSE.z  # at the sensor's height: elevation 0
    detections = [Detection(model.function(State(t.reshape(-1, 1))), timestamp=T0,
                            measurement_model=model) for t in truths]
    sensor = SensorModel(detection=DetectionProbabilityModel(factors=[0.9]), clutter=_model(),
                         position_mapping=(0, 2, 4))
    context = sensor.context(POSE, T0)
    got = context.clutter_spatial_density_detections(detections)
    measured = np.array([float(d.state_vector[2, 0]) for d in detections])
    want, _, _ = _numpy_lambda(truths[:, [0, 2, 4]], POSE, ranges=measured)
    np.testing.assert_allclose(got, want, rtol=1e-12)
    assert got[0] == context.clutter_spatial_density(detections[0])


def test_births_read_the_heights_as_lambda_does():
    model = CartesianToElevationBearingRange(
        ndim_state=6, mapping=(0, 2, 4), noise_covar=np.eye(3),
        translation_offset=np.array([[POSE.x], [POSE.y], [POSE.z]]))
    density = ClutterDensityModel(factors=[ElevationSector(lower=LOW, upper=HIGH, inside=0.1,
                                                           outside=1.0)])
    birth = MeasurementDrivenBirth(birth_weight=0.5, birth_covar=np.eye(6),
                                   position_mapping=(0, 2, 4), birth_density=density)
    # a boat at the sea (inside: weight 0.05) and an aircraft 2 km up (outside: 0.5)
    truths = [[4000.0, 0, 1000.0, 0, 0.0, 0], [4000.0, 0, 1000.0, 0, 2000.0, 0]]
    detections = [Detection(model.function(State(np.reshape(t, (-1, 1)))), timestamp=T0,
                            measurement_model=model) for t in truths]
    sensor = SensorModel(detection=DetectionProbabilityModel(factors=[0.9]), clutter=density,
                         position_mapping=(0, 2, 4))
    weights = birth.weights(detections, detector_context=sensor.context(POSE, T0))
    np.testing.assert_allclose(weights, [0.05, 0.5], rtol=1e-12)


def test_heights_missing_where_a_model_reads_them_are_named():
    with pytest.raises(ShapeError) as info:
        _model().evaluate(POSE, np.zeros((3, 2)))
    assert info.value.argument == "positions" and "(M, 3)" in str(info.value)
    with pytest.raises(ArgumentError) as info:
        SensorModel(detection=DetectionProbabilityModel(factors=[0.9]), clutter=_model())
    assert info.value.argument == "position_mapping"
    with pytest.raises(ShapeError) as info:
        _model().evaluate(POSE, np.zeros((3, 4)))
    assert info.value.argument == "positions"
    bad = np.array([[100.0, 0.0, 0.0], [200.0, 0.0, np.nan]])
    with pytest.raises(ValueError, match="positions: row 1"):
        _model().evaluate(POSE, bad)
    with pytest.raises(ValueError, match="factors"):
        ClutterDensityModel(factors=[ElevationSector(lower=LOW, upper=HIGH, outside=0.0)])


def test_a_map_in_a_3d_model_reads_the_plane_on_every_path():
    """A bearing–range map of a 3-D radar reads the detection's plane range, whether λ
    comes from the detection (whose measured range is a slant one) or from its (x, y, z)."""
    from ctxmodels import ClutterMap, Mounting
    learned = ClutterMap(space="bearing-range",
                         edges=(np.linspace(-math.pi, math.pi, 9), np.array([0., 5000, 10000, 20000])),
                         prior_intensity=1e-3, prior_scans=10, forgetting=0.99)
    rng = np.random.default_rng(0)
    for _ in range(50):  # clutter learned in the 5–10 km ring only
        r, b = rng.uniform(5000, 10000, 40), rng.uniform(-math.pi, math.pi, 40)
        learned.update(Pose(x=0, y=0, z=25), np.column_stack([r * np.cos(b), r * np.sin(b)]))
    sensor = SensorModel(detection=DetectionProbabilityModel(factors=[0.9]),
                         clutter=ClutterDensityModel(factors=[learned]),
                         position_mapping=(0, 2, 4), mounting=Mounting(up=25))
    context = sensor.context(Pose(x=0, y=0), T0)
    model = CartesianToElevationBearingRange(
        ndim_state=6, mapping=(0, 2, 4), noise_covar=np.eye(3),
        translation_offset=np.array([[0.0], [0.0], [25.0]]))
    truth = np.array([4000.0, 0, 100, 0, 4000, 0])  # plane range 4.0 km, slant range 5.6 km
    detection = Detection(model.function(State(truth.reshape(-1, 1))), timestamp=T0,
                          measurement_model=model)
    from_detection = context.clutter_spatial_density_detections([detection])
    from_position = context.clutter_spatial_density_array(truth[[0, 2, 4]][None])
    plane = ClutterDensityModel(factors=[learned]).evaluate(context.pose, truth[[0, 2]][None])
    np.testing.assert_allclose(from_detection, plane, rtol=1e-12)
    np.testing.assert_allclose(from_position, plane, rtol=1e-12)


def test_out_may_not_overlap_positions_with_heights():
    positions = np.asfortranarray(np.column_stack([np.full(4, 1000.0), np.zeros(4), np.zeros(4)]))
    with pytest.raises(ArgumentError, match="out: overlaps positions"):
        _model().evaluate(POSE, positions, out=positions[:, 2])
    assert np.all(positions[:, 2] == 0.0)


def test_a_planar_birth_with_an_elevation_density_is_refused_when_built():
    density = ClutterDensityModel(factors=[ElevationSector(lower=LOW, upper=HIGH, inside=0.1,
                                                           outside=1.0)])
    with pytest.raises(ArgumentError) as info:
        MeasurementDrivenBirth(birth_weight=0.5, birth_covar=np.eye(4), birth_density=density)
    assert info.value.argument == "birth_density"
