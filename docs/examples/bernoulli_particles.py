"""
A Bernoulli particle filter with P_D per particle
=================================================

A short-range sensor (P_D 0.95 within 50 m, nothing beyond) follows a target that drives
out of its range and stays out. ctxmodels' :class:`~ctxmodels.stonesoup.BernoulliParticleUpdater`
takes each scan's context and evaluates P_D at every particle (one call into the core per
scan). With a context that knows the coverage, an empty scan says "not within 50 m": the
particles that were in range lose weight, the others keep it, and the existence
probability barely moves. With a context that says P_D = 0.95 everywhere, every empty scan
is evidence that the target is gone, and the existence probability collapses.

(Stone Soup 1.9.1's own Bernoulli updater skips a scan without detections altogether: it
takes neither kind of evidence from it.)
"""

# %%
# The sensor and the scans
# ------------------------
import datetime

import numpy as np
from stonesoup.models.measurement.linear import LinearGaussian
from stonesoup.models.transition.linear import (CombinedLinearGaussianTransitionModel,
                                                ConstantVelocity)
from stonesoup.predictor.particle import BernoulliParticlePredictor
from stonesoup.resampler.particle import SystematicResampler
from stonesoup.sampler.detection import (GaussianDetectionParticleSampler,
                                         SwitchingDetectionSampler)
from stonesoup.sampler.particle import ParticleSampler
from stonesoup.types.array import StateVectors
from stonesoup.types.detection import MissedDetection, TrueDetection
from stonesoup.types.hypothesis import SingleHypothesis
from stonesoup.types.multihypothesis import MultipleHypothesis
from stonesoup.types.state import BernoulliParticleState

from ctxmodels import (ClutterDensityModel, DetectionProbabilityModel, RangeBands,
                       SensorModel)
from ctxmodels.stonesoup import BernoulliParticleUpdater

start = datetime.datetime(2026, 1, 1)
prob_detection, clutter_rate, clutter_area = 0.95, 0.5, 200.0 * 200.0
clutter = ClutterDensityModel(factors=[clutter_rate / clutter_area])
coverage = SensorModel(detection=DetectionProbabilityModel(factors=[
    RangeBands(edges=(50.0,), values=(prob_detection, 0.0))]), clutter=clutter)
everywhere = SensorModel(detection=DetectionProbabilityModel(factors=[prob_detection]),
                         clutter=clutter)
transition = CombinedLinearGaussianTransitionModel([ConstantVelocity(0.2)] * 2)
measurement = LinearGaussian(ndim_state=4, mapping=(0, 2), noise_covar=np.eye(2) * 2.0)


def scans(steps=36, seed=3):
    """The target: from (-30, 5) east at 3 m/s, out of range after about 26 s."""
    rng = np.random.default_rng(seed)
    out = []
    for k in range(steps):
        time = start + datetime.timedelta(seconds=k)
        x, y = -30.0 + 3.0 * k, 5.0
        detections = set()
        if np.hypot(x, y) < 50.0 and rng.random() < prob_detection:
            z = np.array([[x], [y]]) + rng.normal(0, np.sqrt(2.0), (2, 1))
            detections.add(TrueDetection(z, timestamp=time, measurement_model=measurement,
                                         groundtruth_path=None))
        out.append((time, detections, (x, y)))
    return out


# %%
# The same filter, fed the two contexts
# -------------------------------------
def run(sensor, seed=5):
    np.random.seed(seed)  # Stone Soup's samplers and resampler draw from NumPy's global RNG
    birth = SwitchingDetectionSampler(
        detection_sampler=GaussianDetectionParticleSampler(nsamples=100),
        backup_sampler=ParticleSampler(
            distribution_func=np.random.multivariate_normal,
            params={"mean": np.zeros(4), "cov": np.diag([30.0, 3, 30, 3]) ** 2, "size": 100},
            ndim_state=4))
    predictor = BernoulliParticlePredictor(transition_model=transition, birth_sampler=birth,
                                           birth_probability=0.01, survival_probability=0.999)
    updater = BernoulliParticleUpdater(measurement_model=None, resampler=SystematicResampler(),
                          clutter_rate=clutter_rate, clutter_distribution=1 / clutter_area,
                          detection_probability=prob_detection, nsurv_particles=500)
    rng = np.random.default_rng(1)
    particles = StateVectors(rng.normal([[-30], [3], [5], [0]], [[5], [1], [5], [1]], (4, 500)))
    state = BernoulliParticleState(state_vector=particles, weight=np.full(500, 1 / 500),
                                   existence_probability=0.9, timestamp=start)
    existence = []
    for time, detections, _ in scans():
        prediction = predictor.predict(state, timestamp=time)
        hypotheses = MultipleHypothesis(
            [SingleHypothesis(prediction, d) for d in detections] or
            [SingleHypothesis(prediction, MissedDetection(timestamp=time))])
        state = updater.update(hypotheses, detector_context=sensor.context((0.0, 0.0, 0.0), time))
        existence.append(float(state.existence_probability))
    return np.array(existence), state


uniform, _ = run(everywhere)
context, last = run(coverage)
mean = np.average(last.state_vector, axis=1, weights=np.exp(last.log_weight))
truth = scans()[-1][2]
print(f"existence probability 9 s after leaving coverage: P_D 0.95 everywhere "
      f"{uniform[-1]:.3f}, with the coverage {context[-1]:.3f}")
print(f"context-aware estimate {np.hypot(mean[0] - truth[0], mean[2] - truth[1]):.0f} m "
      f"from the target, {np.hypot(mean[0], mean[2]):.0f} m from the sensor")
