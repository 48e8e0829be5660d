"""Seeded scenarios and filters for the particle updaters: a Bernoulli particle filter and an
SMC-PHD filter run over the same scans, with a context or without."""
import datetime

import numpy as np
from stonesoup.hypothesiser.simple import SimpleHypothesiser
from stonesoup.models.measurement.linear import LinearGaussian
from stonesoup.models.transition.linear import (CombinedLinearGaussianTransitionModel,
                                                ConstantVelocity)
from stonesoup.predictor.particle import BernoulliParticlePredictor, SMCPHDPredictor
from stonesoup.regulariser.particle import MCMCRegulariser
from stonesoup.resampler.particle import SystematicResampler
from stonesoup.sampler.detection import GaussianDetectionParticleSampler, SwitchingDetectionSampler
from stonesoup.sampler.particle import ParticleSampler
from stonesoup.types.array import StateVectors
from stonesoup.types.detection import Clutter, Detection, MissedDetection
from stonesoup.types.hypothesis import SingleHypothesis
from stonesoup.types.multihypothesis import MultipleHypothesis
from stonesoup.types.state import BernoulliParticleState, ParticleState

import ctxmodels

T0 = datetime.datetime(2024, 1, 1)
SECOND = datetime.timedelta(seconds=1)
ORIGIN = (0.0, 0.0, 0.0)
TRANSITION = CombinedLinearGaussianTransitionModel([ConstantVelocity(0.5)] * 2)
MEASUREMENT = LinearGaussian(ndim_state=4, mapping=(0, 2), noise_covar=np.eye(2) * 4.0)
PROB_DETECTION = 0.9
CLUTTER_RATE = 2.0
CLUTTER_DISTRIBUTION = 1 / 200.0 ** 2
CLUTTER = CLUTTER_RATE * CLUTTER_DISTRIBUTION


def banded_context(edges=(50, 80), values=(0.95, 0.2, 0.0), clutter_edges=(30,),
                   clutter_values=(1e-3, 1e-2)):
    model = ctxmodels.SensorModel(
        detection=ctxmodels.DetectionProbabilityModel(
            factors=[ctxmodels.RangeBands(edges=edges, values=values)]),
        clutter=ctxmodels.ClutterDensityModel(
            factors=[ctxmodels.RangeBands(edges=clutter_edges, values=clutter_values)]))
    return model.context(ORIGIN)


def scenario(steps=8, seed=5, never_empty=False, empty=()):
    """One target from (-40, 10) at (4, 1) m/s, P_D 0.9, Poisson(2) clutter over
    [-100, 100]²; with ``never_empty`` every scan holds at least one clutter point; the
    scans numbered in ``empty`` hold nothing."""
    rng = np.random.default_rng(seed)
    scans = []
    for k in range(1, steps + 1):
        timestamp = T0 + k * SECOND
        detections = set()
        if rng.random() < PROB_DETECTION:
            z = np.array([-40 + 4 * k, 10 + k]) + rng.normal(0, 2, 2)
            detections.add(Detection(z.reshape(-1, 1), timestamp=timestamp,
                                     measurement_model=MEASUREMENT))
        for _ in range(max(rng.poisson(CLUTTER_RATE), 1 if never_empty else 0)):
            detections.add(Clutter(rng.uniform(-100, 100, (2, 1)), timestamp=timestamp,
                                   measurement_model=MEASUREMENT))
        scans.append((timestamp, set() if k in empty else detections))
    return scans


def bernoulli_prior(n=300, seed=1):
    rng = np.random.default_rng(seed)
    particles = StateVectors(rng.normal([[-40], [4], [10], [1]], [[15], [2], [15], [2]], (4, n)))
    return BernoulliParticleState(state_vector=particles, weight=np.full(n, 1 / n),
                                  existence_probability=0.5, timestamp=T0)


def bernoulli_filter(updater_cls, regularise=True, constrain=False):
    sampler = SwitchingDetectionSampler(
        detection_sampler=GaussianDetectionParticleSampler(nsamples=100),
        backup_sampler=ParticleSampler(
            distribution_func=np.random.multivariate_normal,
            params={"mean": np.zeros(4), "cov": np.diag([100.0, 4, 100, 4]) ** 2, "size": 100},
            ndim_state=4))
    predictor = BernoulliParticlePredictor(transition_model=TRANSITION, birth_sampler=sampler,
                                           birth_probability=0.05, survival_probability=0.98)
    updater = updater_cls(
        measurement_model=None, resampler=SystematicResampler(),
        regulariser=MCMCRegulariser(transition_model=TRANSITION) if regularise else None,
        constraint_func=(lambda state: state.state_vector[0, :] > 60) if constrain else None,
        clutter_rate=CLUTTER_RATE, clutter_distribution=CLUTTER_DISTRIBUTION,
        detection_probability=PROB_DETECTION, nsurv_particles=300)
    return predictor, updater


def bernoulli_hypotheses(prediction, detections, timestamp):
    if detections:
        return MultipleHypothesis([SingleHypothesis(prediction, d) for d in detections])
    return MultipleHypothesis([SingleHypothesis(prediction, MissedDetection(timestamp=timestamp))])


def run_bernoulli(updater_cls, scans, seed, context=None, **options):
    predictor, updater = bernoulli_filter(updater_cls, **options)
    np.random.seed(seed)
    state = bernoulli_prior()
    history = []
    for timestamp, detections in scans:
        prediction = predictor.predict(state, timestamp=timestamp)
        hypotheses = bernoulli_hypotheses(prediction, detections, timestamp)
        state = (updater.update(hypotheses) if context is None
                 else updater.update(hypotheses, detector_context=context))
        history.append((np.asarray(state.state_vector).tobytes(), state.log_weight.tobytes(),
                        float(state.existence_probability)))
    return history


def smcphd_filter(updater_cls, prob_detect=PROB_DETECTION, n=400):
    sampler = ParticleSampler(
        distribution_func=np.random.multivariate_normal,
        params={"mean": np.zeros(4), "cov": np.diag([60.0, 3, 60, 3]) ** 2, "size": n},
        ndim_state=4)
    predictor = SMCPHDPredictor(transition_model=TRANSITION, death_probability=0.01,
                                birth_probability=0.1, birth_rate=0.05, birth_sampler=sampler,
                                birth_func_num_samples_field="size")
    updater = updater_cls(measurement_model=None, prob_detect=prob_detect,
                          clutter_intensity=CLUTTER,
                          resampler=SystematicResampler(), num_samples=n)
    return predictor, updater


def smcphd_prior(n=400, seed=4):
    rng = np.random.default_rng(seed)
    particles = StateVectors(rng.normal([[-40], [4], [10], [1]], [[10], [2], [10], [2]], (4, n)))
    return ParticleState(state_vector=particles, weight=np.full(n, 1.0 / n), timestamp=T0)


def run_smcphd(updater_cls, scans, seed, context=None):
    predictor, updater = smcphd_filter(updater_cls)
    hypothesiser = SimpleHypothesiser(predictor, check_timestamp=False)
    np.random.seed(seed)
    state = smcphd_prior()
    history = []
    for timestamp, detections in scans:
        hypotheses = hypothesiser.hypothesise(state, detections, timestamp)
        state = (updater.update(hypotheses) if context is None
                 else updater.update(hypotheses, detector_context=context))
        history.append((np.asarray(state.state_vector).tobytes(), state.log_weight.tobytes()))
    return history
