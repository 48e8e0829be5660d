"""Regressions (reliability pass 2): λ reads each detection's position through its own
measurement model and mapping, and a bearing–range detection's range band from its measured
range; bad particle weights and mismatched detections raise, naming the argument."""
import math

import numpy as np
import pytest
from stonesoup.models.measurement.linear import LinearGaussian
from stonesoup.models.measurement.nonlinear import CartesianToBearingRange
from stonesoup.types.array import StateVectors
from stonesoup.types.detection import Detection
from stonesoup.types.state import ParticleState

from ctxmodels import (ClutterDensityModel, DetectionProbabilityModel, Pose, RangeBands,
                       SensorModel, detection_positions, measured_ranges)

RADAR = SensorModel(
    detection=DetectionProbabilityModel(factors=[RangeBands(edges=(50, 1612),
                                                            values=(0, 0.4, 0))]),
    clutter=ClutterDensityModel(factors=[RangeBands(edges=(1000,), values=(1e-3, 1e-2))]))
CONTEXT = RADAR.context(Pose(x=0.0, y=0.0, heading=0.0), None)


def test_lambda_reads_a_six_dimensional_models_own_mapping():
    # state [x, vx, ax, y, vy, ay]: y is index 3, which the sensor's (0, 2) does not name
    model = LinearGaussian(ndim_state=6, mapping=(0, 3), noise_covar=np.eye(2))
    near = Detection(np.array([[10.0], [900.0]]), measurement_model=model)  # r ≈ 900 m
    far = Detection(np.array([[10.0], [1100.0]]), measurement_model=model)  # r ≈ 1100 m
    np.testing.assert_array_equal(detection_positions([near, far]),
                                  [[10.0, 900.0], [10.0, 1100.0]])
    assert CONTEXT.clutter_spatial_density_detections([near, far]).tolist() == [1e-3, 1e-2]
    # a 4-D model that maps the sensor's indices keeps them, whatever else it maps
    full = LinearGaussian(ndim_state=4, mapping=(0, 1, 2, 3), noise_covar=np.eye(4))
    det = Detection(np.array([[3.0], [-1.0], [1500.0], [2.0]]), measurement_model=full)
    np.testing.assert_array_equal(detection_positions([det]), [[3.0, 1500.0]])


def test_lambda_of_a_one_dimensional_model_raises_naming_detections():
    model = LinearGaussian(ndim_state=4, mapping=(0,), noise_covar=np.eye(1))
    det = Detection(np.array([[1500.0]]), measurement_model=model)
    with pytest.raises(ValueError, match=r"^detections: detection 0.*maps state indices \(0,\)"):
        CONTEXT.clutter_spatial_density_detections([det])


def test_detection_whose_vector_does_not_fit_its_model_raises_naming_detections():
    model = LinearGaussian(ndim_state=4, mapping=(0, 2), noise_covar=np.eye(2))
    det = Detection(np.array([[1.0], [2.0], [3.0]]), measurement_model=model)
    with pytest.raises(ValueError, match=r"^detections: detection 0 has a state vector of "
                                         r"shape \(3, 1\).*measures 2 values"):
        CONTEXT.clutter_spatial_density_detections([det])


PARTICLES = StateVectors(np.array([[100.0, 0, 0, 0], [200, 0, 0, 0], [3000, 0, 0, 0]]).T)


@pytest.mark.filterwarnings("ignore::RuntimeWarning")  # Stone Soup's own log(0) of weights
@pytest.mark.parametrize("weights, message", [
    ([0.0, 0.0, 0.0], "sum to 0"),
    ([math.nan, 1.0, 1.0], "finite and >= 0"),
    ([1.0, -1.0, 1.0], "finite and >= 0"),
    ([1.0, 1.0], "2 particle weights for 3 particles"),
])
def test_bad_particle_weights_raise_naming_the_state(weights, message):
    state = ParticleState(PARTICLES, weight=np.array(weights))
    with pytest.raises(ValueError, match=f"^hypothesis_or_state: .*{message}"):
        CONTEXT.prob_detection(state)


def test_good_particle_weights_give_the_weighted_mean():
    state = ParticleState(PARTICLES, weight=np.array([1.0, 2.0, 3.0]))
    # P_D 0.4 at 100 m and 200 m, 0 at 3 km: (0.4 + 0.8) / 6
    assert float(CONTEXT.prob_detection(state)) == pytest.approx(1.2 / 6, rel=1e-15)


def test_bearing_range_detection_on_a_band_edge_uses_its_measured_range():
    """Measured at exactly 1000 m (the radar's λ edge, owned by the far band): the polar →
    Cartesian → range round trip lands an ulp short for about a quarter of bearings."""
    pose = Pose(x=12.3, y=-45.6, heading=0.3)
    context = RADAR.context(pose, None)
    model = CartesianToBearingRange(ndim_state=4, mapping=(0, 2), noise_covar=np.eye(2),
                                    translation_offset=np.array([[12.3], [-45.6]]))
    detections = [Detection(np.array([[bearing], [1000.0]]), measurement_model=model)
                  for bearing in np.linspace(-3.1, 3.1, 400)]
    assert context.clutter_spatial_density_detections(detections).tolist() == [1e-2] * 400
    np.testing.assert_array_equal(measured_ranges(detections), np.full(400, 1000.0))
    # the position path really does lose the edge for some bearings: the case is exercised
    positions = detection_positions(detections)
    by_position = context.clutter_spatial_density_array(positions, [{}] * 400)
    assert 0 < np.count_nonzero(by_position == 1e-3) < 400
    # other detections (here a linear one) keep reading the range of their position
    linear = Detection(np.array([[12.3], [954.4]]), measurement_model=LinearGaussian(
        ndim_state=4, mapping=(0, 2), noise_covar=np.eye(2)))
    assert np.isnan(measured_ranges([linear])[0])
    assert context.clutter_spatial_density_detections([linear]).tolist() == [1e-2]


@pytest.mark.parametrize("ranges, message", [([np.inf], "infinite"), ([1.0, 2.0], "1 entries")])
def test_bad_measured_ranges_raise_naming_ranges(ranges, message):
    with pytest.raises(ValueError, match=f"^ranges: .*{message}"):
        CONTEXT.clutter_spatial_density_array(np.zeros((1, 2)), [{}], ranges=np.array(ranges))
