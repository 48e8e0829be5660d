"""Births of states with a height: MeasurementDrivenBirth with (x, y, z) position indices
puts each birth at its detection's 3-D position (through the detection's own measurement
model, here Stone Soup's elevation–bearing–range), and a birth density reads x and y."""
from __future__ import annotations

import datetime
import math

import numpy as np
import pytest
from stonesoup.models.measurement.nonlinear import CartesianToElevationBearingRange
from stonesoup.types.detection import Detection

from ctxmodels import (ClutterDensityModel, DetectionProbabilityModel, DetectionSet,
                       ElevationSector, RangeBands, SensorModel, detection_positions)
from ctxmodels.stonesoup import MeasurementDrivenBirth

T0 = datetime.datetime(2026, 1, 1)


def _detections():
    model = CartesianToElevationBearingRange(ndim_state=6, mapping=(0, 2, 4),
                                             noise_covar=np.eye(3),
                                             translation_offset=np.array([[10.0], [-5.0], [30.0]]))
    targets = [(1000.0, 200.0, 500.0), (-3000.0, 4000.0, 1200.0), (50.0, -60.0, 30.0)]
    detections = []
    for x, y, z in targets:
        dx, dy, dz = x - 10.0, y + 5.0, z - 30.0
        rho = math.sqrt(dx * dx + dy * dy + dz * dz)
        vector = np.array([[math.asin(dz / rho)], [math.atan2(dy, dx)], [rho]])
        detections.append(Detection(vector, timestamp=T0, measurement_model=model))
    return detections, np.array(targets)


def test_births_sit_at_each_detections_3d_position():
    detections, targets = _detections()
    np.testing.assert_allclose(detection_positions(detections, (0, 2, 4)), targets, atol=1e-6)
    birth = MeasurementDrivenBirth(birth_weight=0.01, position_mapping=(0, 2, 4),
                                   velocity_mapping=(1, 3, 5), birth_covar=np.eye(6) * 100.0)
    components = birth.components(detections)
    means = np.array([np.ravel(c.state_vector) for c in components])
    np.testing.assert_allclose(means[:, [0, 2, 4]], targets, atol=1e-6)
    assert np.all(means[:, [1, 3, 5]] == 0.0)


def test_a_birth_density_reads_the_plane_below_the_detection():
    detections, targets = _detections()
    density = ClutterDensityModel(factors=[RangeBands(edges=(2000.0,), values=(1.0, 0.1))])
    sensor = SensorModel(detection=DetectionProbabilityModel(factors=[
        ElevationSector(lower=-0.1, upper=1.2)]), clutter=ClutterDensityModel(factors=[1e-9]),
        position_mapping=(0, 2, 4))
    context = sensor.context((10.0, -5.0, 0.0, 30.0), T0)
    birth = MeasurementDrivenBirth(birth_weight=0.01, position_mapping=(0, 2, 4),
                                   velocity_mapping=(1, 3, 5), birth_covar=np.eye(6) * 100.0,
                                   birth_density=density)
    components = birth.components(DetectionSet(detections, context))  # (a set: any order)
    means = np.array([np.ravel(c.state_vector)[[0, 2, 4]] for c in components])
    plane = np.hypot(means[:, 0] - 10.0, means[:, 1] + 5.0)
    np.testing.assert_allclose([c.weight for c in components],
                               0.01 * np.where(plane < 2000.0, 1.0, 0.1))
    assert sorted(plane.round(3).tolist()) == sorted(
        np.hypot(targets[:, 0] - 10.0, targets[:, 1] + 5.0).round(3).tolist())
    with pytest.raises(ValueError, match="position_mapping: must hold the two indices"):
        MeasurementDrivenBirth(position_mapping=(0, 2, 4, 5), velocity_mapping=(),
                               birth_covar=np.eye(6))
