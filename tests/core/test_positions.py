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
from ctxmodels.context import ranges_for_bands

RADAR = SensorModel(
    detection=DetectionProbabilityModel(factors=[RangeBands(edges=(50, 1612),
                                                            values=(0, 0.4, 0))]),
    clutter=ClutterDensityModel(factors=[RangeBands(edges=(1000,), values=(1e-3, 1e-2))]))
CONTEXT = RADAR.context(Pose(x=0.0, y=0.0, heading=0.0), None)


def test_lambda_reads_positions_in_the_detection_models_state_space():
    # state [x, vx, ax, y, vy, ay]: y is index 3. Against the sensor's default (0, 2), index
    # 2 (ax) used to be read as y; now that is an error, and a sensor whose position_mapping
    # names the 6-D state's x/y reads the model's own x and y.
    model = LinearGaussian(ndim_state=6, mapping=(0, 3), noise_covar=np.eye(2))
    near = Detection(np.array([[10.0], [900.0]]), measurement_model=model)  # r ≈ 900 m
    far = Detection(np.array([[10.0], [1100.0]]), measurement_model=model)  # r ≈ 1100 m
    with pytest.raises(ValueError, match=r"^detections: detection 0's measurement model "
                                         r"LinearGaussian maps state indices \(0, 3\).*"
                                         r"position_mapping \(0, 2\)"):
        CONTEXT.clutter_spatial_density_detections([near, far])
    six_d = SensorModel(detection=RADAR.detection, clutter=RADAR.clutter,
                        position_mapping=(0, 3)).context(Pose(x=0.0, y=0.0, heading=0.0), None)
    np.testing.assert_array_equal(detection_positions([near, far], (0, 3)),
                                  [[10.0, 900.0], [10.0, 1100.0]])
    assert six_d.clutter_spatial_density_detections([near, far]).tolist() == [1e-3, 1e-2]
    # a model measuring more than position keeps the sensor's indices: x and y, not x and vx
    full = LinearGaussian(ndim_state=4, mapping=(0, 1, 2, 3), noise_covar=np.eye(4))
    det = Detection(np.array([[3.0], [-1.0], [1500.0], [2.0]]), measurement_model=full)
    np.testing.assert_array_equal(detection_positions([det]), [[3.0, 1500.0]])
    # a velocity-only model has no position: an error, not (vx, vy)
    velocity = LinearGaussian(ndim_state=4, mapping=(1, 3), noise_covar=np.eye(2))
    with pytest.raises(ValueError, match="maps state indices \\(1, 3\\)"):
        detection_positions([Detection(np.ones((2, 1)), measurement_model=velocity)])


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


def _radar_at_edge_pose():
    """The radar's context at a pose, and a bearing–range model measuring from it."""
    context = RADAR.context(Pose(x=12.3, y=-45.6, heading=0.3), None)
    model = CartesianToBearingRange(ndim_state=4, mapping=(0, 2), noise_covar=np.eye(2),
                                    translation_offset=np.array([[12.3], [-45.6]]))
    return context, model


def test_bearing_range_detection_on_a_band_edge_uses_its_measured_range():
    """Measured at exactly 1000 m (the radar's λ edge, owned by the far band): the polar →
    Cartesian → range round trip lands an ulp short for about a quarter of bearings."""
    context, model = _radar_at_edge_pose()
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


def test_measured_range_is_read_only_where_it_agrees_with_the_context_pose():
    """A bearing–range detection measured from another point (a lever arm the detection
    model has and the context's pose lacks) keeps the range from the context's pose, and a
    negative measured range (noise near the sensor) is never read as a range."""
    context = RADAR.context(Pose(x=0.0, y=0.0, heading=0.0), None)
    offset = CartesianToBearingRange(ndim_state=4, mapping=(0, 2), noise_covar=np.eye(2),
                                     translation_offset=np.array([[5.0], [0.0]]))
    # 999 m from (5, 0) along +x is 1004 m from the context's pose: the far band
    det = Detection(np.array([[0.0], [999.0]]), measurement_model=offset)
    assert context.clutter_spatial_density_detections([det]).tolist() == [1e-2]
    at_origin = CartesianToBearingRange(ndim_state=4, mapping=(0, 2), noise_covar=np.eye(2))
    negative = Detection(np.array([[0.0], [-3.0]]), measurement_model=at_origin)
    assert np.isnan(ranges_for_bands([negative], detection_positions([negative]),
                                     context.pose)[0])


@pytest.mark.parametrize("ranges, message", [([np.inf], "infinite"), ([1.0, 2.0], "1 entries")])
def test_bad_measured_ranges_raise_naming_ranges(ranges, message):
    with pytest.raises(ValueError, match=f"^ranges: .*{message}"):
        CONTEXT.clutter_spatial_density_array(np.zeros((1, 2)), [{}], ranges=np.array(ranges))


def test_pda_lambda_of_a_detection_does_not_depend_on_the_other_detections():
    """A detection without its own model (measured by the updater's model) used to send the
    whole scan through another position rule that ignored measured ranges."""
    from stonesoup.predictor.kalman import KalmanPredictor
    from stonesoup.models.transition.linear import (CombinedLinearGaussianTransitionModel,
                                                    ConstantVelocity)
    from stonesoup.updater.kalman import ExtendedKalmanUpdater
    from ctxmodels.stonesoup import PDAHypothesiser
    context, model = _radar_at_edge_pose()
    on_edge = [Detection(np.array([[b], [1000.0]]), measurement_model=model)
               for b in np.linspace(-3.1, 3.1, 100)]
    modelless = Detection(np.array([[0.5], [1000.0]]))  # the updater's model measures it
    hypothesiser = PDAHypothesiser(
        KalmanPredictor(CombinedLinearGaussianTransitionModel([ConstantVelocity(0.1)] * 2)),
        ExtendedKalmanUpdater(measurement_model=model), clutter_spatial_density=1e-3,
        prob_detect=0.9)
    alone = hypothesiser._evaluate_clutter(context, on_edge)
    mixed = hypothesiser._evaluate_clutter(context, on_edge + [modelless])
    assert np.asarray(alone).tolist() == [1e-2] * 100
    assert np.asarray(mixed).tolist() == [1e-2] * 101
