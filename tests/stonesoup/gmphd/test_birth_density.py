"""A birth density: measurement-driven births weighted by a product of factors at each
detection (range bands from the scan's sensor, zones), held against NumPy and Shapely, and
the same on the component and the array GM-PHD."""
import pickle

import numpy as np
import pytest
import shapely
from stonesoup.serialise import YAML

from ctxmodels import (ClutterDensityModel, DetectionSet, LandMask, MetadataThreshold, RangeBands,
                       Zone, detection_positions)
from ctxmodels.errors import ArgumentError, ArgumentTypeError, ShapeError
from ctxmodels.stonesoup import (ArrayPointProcessTracker, CircularRegion, MeasurementDrivenBirth,
                                 PointProcessMultiTargetTracker)

from .setups import (RTOL, lockstep, radar_lidar_scenario, seeded_uuids, stock_components,
                     with_contexts)

pytestmark = pytest.mark.usefixtures("stock_in_stable_order")

HARBOUR = [(200.0, 100.0), (500.0, 100.0), (500.0, 350.0), (200.0, 350.0)]


def _density():
    return ClutterDensityModel(factors=[RangeBands(edges=(600.0,), values=(1.0, 4.0)),
                                        Zone(polygons=LandMask(polygons=[HARBOUR]), inside=10.0)])


def test_birth_weights_are_the_density_at_each_detection():
    scenario = radar_lidar_scenario(n_scans=12)
    birth = MeasurementDrivenBirth(birth_weight=1e-3, birth_density=_density())
    checked = 0
    for _, scan in with_contexts(scenario["scans"]):
        detections = list(scan)
        if not detections:
            continue
        pose = scan.detector_context.pose
        xy = detection_positions(detections, (0, 2))
        r = np.hypot(xy[:, 0] - pose.x, xy[:, 1] - pose.y)
        in_harbour = shapely.covers(shapely.Polygon(HARBOUR), shapely.points(xy))
        expected = 1e-3 * np.where(r < 600.0, 1.0, 4.0) * np.where(in_harbour, 10.0, 1.0)
        np.testing.assert_allclose(birth.weights(detections, xy, scan.detector_context), expected,
                                   rtol=1e-15)
        components = birth.components(scan, None)  # (the context read from the set)
        np.testing.assert_allclose([c.weight for c in components], expected, rtol=1e-15)
        checked += len(detections)
    assert checked > 20


def test_metadata_factors_read_the_detections_metadata():
    scenario = radar_lidar_scenario(n_scans=12)
    lidar_scans = [s for _, s in with_contexts(scenario["scans"])
                   if s and all("area" in d.metadata for d in s)]
    birth = MeasurementDrivenBirth(birth_weight=1.0, birth_density=ClutterDensityModel(factors=[
        MetadataThreshold(key="area", threshold=10.0, below=3.0, at_or_above=0.5)]))
    for scan in lidar_scans:
        detections = list(scan)
        weights = birth.weights(detections, None, scan.detector_context)
        areas = np.array([d.metadata["area"] for d in detections])
        assert weights.tolist() == np.where(areas < 10.0, 3.0, 0.5).tolist()


def test_without_a_density_every_birth_weighs_birth_weight():
    birth = MeasurementDrivenBirth(birth_weight=2e-4)
    scenario = radar_lidar_scenario(n_scans=3)
    scan = next(s for _, s in scenario["scans"] if s)
    assert birth.weights(list(scan)).tolist() == [2e-4] * len(scan)


def test_a_density_needs_the_scans_context():
    birth = MeasurementDrivenBirth(birth_density=_density())
    scenario = radar_lidar_scenario(n_scans=3)
    scan = next(s for _, s in scenario["scans"] if s)
    with pytest.raises(ArgumentError) as info:
        birth.components(DetectionSet(scan), None)
    assert info.value.argument == "birth_density"
    with pytest.raises(ArgumentTypeError) as info:
        MeasurementDrivenBirth(birth_density=RangeBands(edges=(1.0,), values=(1.0, 2.0)))
    assert info.value.argument == "birth_density"


def test_positions_must_match_the_detections_and_weights_stay_finite():
    scenario = radar_lidar_scenario(n_scans=6)
    _, scan = next((t, s) for t, s in with_contexts(scenario["scans"]) if len(s) >= 3)
    detections, context = list(scan), scan.detector_context
    birth = MeasurementDrivenBirth(birth_weight=1e-3, birth_density=_density())
    with pytest.raises(ShapeError) as info:
        birth.weights(detections, np.zeros((len(detections) - 1, 2)), context)
    assert info.value.argument == "positions"
    huge = MeasurementDrivenBirth(birth_weight=1e300,
                                  birth_density=ClutterDensityModel(factors=[1e300]))
    with pytest.raises(ArgumentError) as info:
        huge.weights(detections, None, context)
    assert info.value.argument == "birth_density"
    with pytest.raises(ArgumentError) as info:
        MeasurementDrivenBirth(birth_weight=10**400)
    assert info.value.argument == "birth_weight"


def test_birth_with_a_density_serialises():
    birth = MeasurementDrivenBirth(birth_weight=1e-3, birth_density=_density())
    back = pickle.loads(pickle.dumps(birth))
    assert back.birth_density == birth.birth_density
    yaml = YAML(typ="safe")
    again = yaml.load(yaml.dumps(birth))
    assert again.birth_density == birth.birth_density and again.birth_weight == 1e-3


def _pair(scans, scenario, density):
    def build(cls):
        return cls(detector=scans, **stock_components(scenario, context_updater=True),
                   birth=MeasurementDrivenBirth(birth_weight=1e-3, birth_density=density),
                   surveillance_region=CircularRegion(centre=(0.0, 0.0), radius=1200.0),
                   max_position_std=60.0, extraction_threshold=0.5)
    return build(PointProcessMultiTargetTracker), build(ArrayPointProcessTracker)


def test_both_gm_phd_paths_weight_births_by_the_density():
    scenario = radar_lidar_scenario(n_scans=60)
    scans = with_contexts(scenario["scans"])
    with seeded_uuids(3):
        reference, tracker = _pair(scans, scenario, _density())
        assert lockstep(reference, tracker) <= RTOL
    # births 4× beyond 600 m and 10× in the harbour: the mixture is not the one without
    with seeded_uuids(3):
        weighted, _ = _pair(scans, scenario, _density())
    with seeded_uuids(3):
        flat, _ = _pair(scans, scenario, None)
    gap = 0.0
    for _ in zip(weighted, flat):
        total = [sum(float(c.weight) for c in t.gaussian_mixture) for t in (weighted, flat)]
        gap = max(gap, total[0] - total[1])
    assert gap > 1e-2
