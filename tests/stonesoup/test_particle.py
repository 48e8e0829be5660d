"""Context-aware Bernoulli particle and SMC-PHD updaters, held against the stock Stone Soup
1.9.1 updaters on seeded scenarios and against the filter equations."""
from __future__ import annotations


import numpy as np
import pytest
from scipy.special import logsumexp
from stonesoup.initiator.particle import SMCPHDInitiator
from stonesoup.types.array import StateVectors
from stonesoup.types.detection import Detection, MissedDetection
from stonesoup.types.hypothesis import SingleHypothesis
from stonesoup.types.multihypothesis import MultipleHypothesis
from stonesoup.types.prediction import BernoulliParticleStatePrediction, ParticleStatePrediction
from stonesoup.updater.particle import BernoulliParticleUpdater as StockBernoulli
from stonesoup.updater.particle import SMCPHDUpdater as StockSMCPHD

import ctxmodels
from ctxmodels import DetectionSet
from ctxmodels.stonesoup.particle import BernoulliParticleUpdater, SMCPHDUpdater

from .particle_setups import (CLUTTER, MEASUREMENT, ORIGIN, PROB_DETECTION, SECOND, T0,
                              banded_context, bernoulli_hypotheses, run_bernoulli, run_smcphd,
                              scenario, smcphd_filter, smcphd_prior)


def constant_context(prob_detection=PROB_DETECTION, clutter=CLUTTER):
    model = ctxmodels.SensorModel(
        detection=ctxmodels.DetectionProbabilityModel(factors=[prob_detection]),
        clutter=ctxmodels.ClutterDensityModel(factors=[clutter]))
    return model.context(ORIGIN)


# --- Bernoulli ------------------------------------------------------------------------------
@pytest.mark.parametrize("feed", ["no context", "constant context"])
@pytest.mark.parametrize("options", [{}, {"regularise": False, "constrain": True}],
                         ids=["regularised", "constrained"])
def test_bernoulli_reproduces_stock_bit_for_bit(feed, options):
    # With a context an empty scan is a missed detection (the stock skips it): scans with
    # detections for the constant-context comparison.
    scans = (scenario(never_empty=True) if feed == "constant context"
             else scenario(empty=(3, 6)))
    context = constant_context() if feed == "constant context" else None
    stock = run_bernoulli(StockBernoulli, scans, seed=7, **options)
    ours = run_bernoulli(BernoulliParticleUpdater, scans, seed=7, context=context, **options)
    assert ours == stock
    assert 0.9 < stock[-1][2] <= 1  # the scenario confirms the target


class CountingContext:
    def __init__(self, context):
        self.context = context
        self.calls = {"prob_detection_array": 0, "clutter_spatial_density_detections": 0}

    def prob_detection_array(self, means, covars=None, *, out=None):
        self.calls["prob_detection_array"] += 1
        assert covars is None
        return self.context.prob_detection_array(means)

    def clutter_spatial_density_detections(self, detections):
        self.calls["clutter_spatial_density_detections"] += 1
        return self.context.clutter_spatial_density_detections(detections)


def bernoulli_prediction(n=400, seed=2, existence=0.6):
    """Particles spread over 0–120 m in x, so P_D differs between them."""
    rng = np.random.default_rng(seed)
    particles = StateVectors(np.vstack([rng.uniform(0, 120, n), rng.normal(0, 1, n),
                                        rng.uniform(-5, 5, n), rng.normal(0, 1, n)]))
    log_weight = np.log(rng.uniform(0.5, 1.5, n))
    log_weight -= logsumexp(log_weight)
    return BernoulliParticleStatePrediction(state_vector=particles, log_weight=log_weight,
                                            existence_probability=existence,
                                            timestamp=T0 + SECOND)


def reference_pd(prediction):
    x = np.asarray(prediction.state_vector, float)
    r = np.hypot(x[0], x[2])
    return np.where(r < 50, 0.95, np.where(r < 80, 0.2, 0.0))


def reference_clutter(detection):
    return 1e-3 if np.hypot(*np.asarray(detection.state_vector, float).ravel()) < 30 else 1e-2


def test_bernoulli_state_dependent_update_matches_the_equations():
    prediction = bernoulli_prediction()
    detections = [Detection(np.array([[20.0], [1.0]]), timestamp=prediction.timestamp,
                            measurement_model=MEASUREMENT),
                  Detection(np.array([[65.0], [-2.0]]), timestamp=prediction.timestamp,
                            measurement_model=MEASUREMENT)]
    context = CountingContext(banded_context())
    updater = BernoulliParticleUpdater(measurement_model=None, clutter_rate=1,
                                       clutter_distribution=1, detection_probability=0.5)
    result = updater.update(bernoulli_hypotheses(prediction, detections, prediction.timestamp),
                            detector_context=context)
    assert context.calls == {"prob_detection_array": 1, "clutter_spatial_density_detections": 1}

    pd = reference_pd(prediction)
    w = np.exp(prediction.log_weight)
    likelihood = np.array([np.exp(MEASUREMENT.logpdf(d, prediction)) for d in detections])
    ratio = sum(g / reference_clutter(d) for g, d in zip(likelihood, detections))
    delta = np.sum(pd * w) - np.sum(pd * ratio * w)
    r = prediction.existence_probability
    assert result.existence_probability == pytest.approx((1 - delta) / (1 - r * delta) * r,
                                                         rel=1e-10)
    expected = (1 - pd + pd * ratio) * w
    np.testing.assert_allclose(np.exp(result.log_weight), expected / expected.sum(), rtol=1e-9)


def test_bernoulli_empty_scan_with_context_is_a_missed_detection():
    prediction = bernoulli_prediction()
    hypotheses = bernoulli_hypotheses(prediction, [], prediction.timestamp)
    updater = BernoulliParticleUpdater(measurement_model=None, clutter_rate=1,
                                       clutter_distribution=1, detection_probability=0.5)
    result = updater.update(hypotheses, detector_context=banded_context())
    pd, w, r = reference_pd(prediction), np.exp(prediction.log_weight), 0.6
    seen = np.sum(pd * w)
    assert 0 < seen < 1
    assert result.existence_probability == pytest.approx((1 - seen) * r / (1 - r * seen), rel=1e-12)
    expected = (1 - pd) * w
    np.testing.assert_allclose(np.exp(result.log_weight), expected / expected.sum(), rtol=1e-10)
    # Out of coverage (P_D 0 at every particle): nothing changes.
    blind = updater.update(hypotheses, detector_context=constant_context(0.0))
    assert blind.existence_probability == pytest.approx(0.6, rel=1e-15)
    np.testing.assert_allclose(blind.log_weight, prediction.log_weight, rtol=0, atol=1e-12)
    # Without a context the stock updater leaves an empty scan alone.
    plain = updater.update(hypotheses)
    assert plain.existence_probability == 0.6


def test_bernoulli_log_detection_probability_path():
    prediction = bernoulli_prediction(n=50)
    updater = BernoulliParticleUpdater(measurement_model=None, detection_probability=0.3)
    assert np.all(updater.get_log_detection_probability(prediction) == np.log(0.3))
    context = CountingContext(banded_context())
    with np.errstate(divide="raise"):  # log 0 must not warn
        log_pd = updater.get_log_detection_probability(prediction, context)
    np.testing.assert_array_equal(np.exp(log_pd), reference_pd(prediction))
    assert context.calls["prob_detection_array"] == 1


# --- SMC-PHD --------------------------------------------------------------------------------
@pytest.mark.parametrize("feed", ["no context", "constant context"])
def test_smcphd_reproduces_stock_bit_for_bit(feed):
    scans = scenario(empty=(3, 6))
    context = constant_context() if feed == "constant context" else None
    stock = run_smcphd(StockSMCPHD, scans, seed=9)
    ours = run_smcphd(SMCPHDUpdater, scans, seed=9, context=context)
    assert ours == stock
    final = np.frombuffer(stock[-1][1])
    assert 0.5 < np.exp(logsumexp(final)) < 3  # about one target's worth of intensity


def smcphd_hypotheses(prediction, detections):
    return MultipleHypothesis(
        [SingleHypothesis(prediction, MissedDetection(timestamp=prediction.timestamp))]
        + [SingleHypothesis(prediction, d) for d in detections])


def test_smcphd_state_dependent_weights_match_the_equations():
    source = bernoulli_prediction(existence=1.0)
    prediction = ParticleStatePrediction(state_vector=source.state_vector,
                                         log_weight=source.log_weight + np.log(1.7),
                                         timestamp=source.timestamp)
    detections = [Detection(np.array([[20.0], [1.0]]), timestamp=prediction.timestamp,
                            measurement_model=MEASUREMENT),
                  Detection(np.array([[65.0], [-2.0]]), timestamp=prediction.timestamp,
                            measurement_model=MEASUREMENT),
                  Detection(np.array([[500.0], [0.0]]), timestamp=prediction.timestamp,
                            measurement_model=MEASUREMENT)]
    context = CountingContext(banded_context())
    updater = SMCPHDUpdater(measurement_model=None, prob_detect=0.5, clutter_intensity=1.0)
    np.random.seed(0)
    weights = updater.get_log_weights_per_hypothesis(smcphd_hypotheses(prediction, detections),
                                                     detector_context=context)
    assert context.calls == {"prob_detection_array": 1, "clutter_spatial_density_detections": 1}
    # The stock likelihood g(z|x) of the SMC-PHD adds measurement noise to the particles
    # (``logpdf(..., noise=True)``): draw the same noise for the reference.
    np.random.seed(0)
    likelihoods = np.exp(updater._get_measurement_loglikelihoods(prediction, detections))
    pd, w = reference_pd(prediction), np.exp(prediction.log_weight)
    with np.errstate(divide="ignore"):
        np.testing.assert_allclose(weights[:, 0], np.log((1 - pd) * w), rtol=1e-12)
    for j, d in enumerate(detections, start=1):
        term = pd * likelihoods[:, j - 1] * w
        np.testing.assert_allclose(np.exp(weights[:, j]),
                                   term / (reference_clutter(d) + term.sum()),
                                   rtol=1e-9, atol=1e-300)
    # The update goes through the same path: one P_D call and one λ call per update.
    context.calls = dict.fromkeys(context.calls, 0)
    updater.update(smcphd_hypotheses(prediction, detections), detector_context=context)
    assert context.calls == {"prob_detection_array": 1, "clutter_spatial_density_detections": 1}


def test_smcphd_initiator_gets_the_scan_context():
    """SMCPHDInitiator forwards no context: ``scan_context`` supplies it."""
    scans = scenario(steps=4, never_empty=True)

    def initiate(updater_cls, wrap):
        predictor, updater = smcphd_filter(updater_cls)
        initiator = SMCPHDInitiator(prior_state=smcphd_prior(), predictor=predictor,
                                    updater=updater, threshold=0.5)
        np.random.seed(3)
        out = []
        for timestamp, detections in scans:
            with wrap(updater):
                tracks = initiator.initiate(detections, timestamp)
            out.append((len(tracks), initiator._state.log_weight.tobytes()))
        return out, updater

    import contextlib
    stock, _ = initiate(StockSMCPHD, lambda u: contextlib.nullcontext())
    same, updater = initiate(SMCPHDUpdater, lambda u: u.scan_context(constant_context()))
    assert same == stock and any(n for n, _ in stock)
    assert updater._scan_context is None  # restored on exit
    blind, _ = initiate(SMCPHDUpdater, lambda u: u.scan_context(constant_context(0.0)))
    assert all(n == 0 for n, _ in blind)  # nothing can be confirmed where P_D = 0


@pytest.mark.parametrize("prob", [0.9, 0.917, 0.0, 1.0])
def test_constant_context_logs_are_the_stocks_bits(prob):
    """log P_D and log(1 - P_D) of a constant context are the stock updaters' NumPy logs
    of the constant, bit for bit (NumPy's AVX-512 log and libm's differ in the last bit at
    0.917 and at 1 - 0.917; whole filter runs round such a bit away)."""
    prediction = bernoulli_prediction(n=5000)
    context = constant_context(prob)
    stock = StockBernoulli(measurement_model=None, detection_probability=prob)
    ours = BernoulliParticleUpdater(measurement_model=None, detection_probability=0.5)
    with np.errstate(divide="ignore"):
        want = stock.get_log_detection_probability(prediction)
    assert ours.get_log_detection_probability(prediction, context).tobytes() == want.tobytes()
    detections = [Detection(np.array([[20.0], [1.0]]), timestamp=prediction.timestamp,
                            measurement_model=MEASUREMENT)]
    hypotheses = smcphd_hypotheses(prediction, detections)
    context = constant_context(prob, clutter=0.25)
    stock = StockSMCPHD(measurement_model=None, prob_detect=prob, clutter_intensity=0.25)
    ours = SMCPHDUpdater(measurement_model=None, prob_detect=0.5, clutter_intensity=1.0)
    np.random.seed(2)  # the likelihood draws noise
    with np.errstate(divide="ignore"):
        want = stock.get_log_weights_per_hypothesis(hypotheses)
    np.random.seed(2)
    assert ours.get_log_weights_per_hypothesis(hypotheses, context).tobytes() == want.tobytes()


class ParticleCountingContext(CountingContext):
    """A ctxmodels context's particle call, counted: the updaters' core path."""

    def __init__(self, context):
        super().__init__(context)
        self.calls["prob_detection_particles"] = 0

    def prob_detection_particles(self, particles, *, log=False, missed=False):
        self.calls["prob_detection_particles"] += 1
        return self.context.prob_detection_particles(particles, log=log, missed=missed)


@pytest.mark.parametrize("make", [banded_context, lambda: constant_context(0.917)],
                         ids=["banded", "constant 0.917"])
def test_core_path_gives_the_row_path_bits(make):
    """One ``prob_detection_particles`` call (columns read in place, logs in the core) and
    no ``prob_detection_array``; the numbers bit for bit those of a context that only has
    ``prob_detection_array`` (transposed particles, NumPy's log in Python)."""
    prediction = bernoulli_prediction(n=5000)
    detections = [Detection(np.array([[20.0], [1.0]]), timestamp=prediction.timestamp,
                            measurement_model=MEASUREMENT)]
    core, rows = ParticleCountingContext(make()), CountingContext(make())
    bernoulli = BernoulliParticleUpdater(measurement_model=None, clutter_rate=1,
                                         clutter_distribution=1, detection_probability=0.5)
    log_pd = bernoulli.get_log_detection_probability(prediction, core)
    assert log_pd.tobytes() == bernoulli.get_log_detection_probability(prediction, rows).tobytes()
    if make is banded_context:
        assert np.isneginf(log_pd).any() and np.isfinite(log_pd).any()
    hypotheses = bernoulli_hypotheses(prediction, detections, prediction.timestamp)
    a = bernoulli.update(hypotheses, detector_context=core)
    b = bernoulli.update(hypotheses, detector_context=rows)
    assert a.log_weight.tobytes() == b.log_weight.tobytes()
    assert a.existence_probability == b.existence_probability

    smcphd = SMCPHDUpdater(measurement_model=None, prob_detect=0.5, clutter_intensity=1.0)
    hypotheses = smcphd_hypotheses(prediction, detections)
    np.random.seed(1)  # the stock likelihood draws noise
    weights = smcphd.get_log_weights_per_hypothesis(hypotheses, detector_context=core)
    np.random.seed(1)
    assert weights.tobytes() == smcphd.get_log_weights_per_hypothesis(
        hypotheses, detector_context=rows).tobytes()
    # log P_D, the Bernoulli update, the SMC-PHD weights: one P_D call each.
    assert core.calls == {"prob_detection_array": 0, "prob_detection_particles": 3,
                          "clutter_spatial_density_detections": 2}
    assert rows.calls["prob_detection_array"] == 3


def test_context_must_be_a_context():
    updater = SMCPHDUpdater(measurement_model=None, prob_detect=0.5, clutter_intensity=1.0)
    prediction = bernoulli_prediction(n=10)
    with pytest.raises(TypeError, match="detector_context"):
        updater.update(smcphd_hypotheses(prediction, []), detector_context=0.9)
    with pytest.raises(TypeError, match="detector_context"):
        with updater.scan_context("radar"):
            pass
    bernoulli = BernoulliParticleUpdater(measurement_model=None, detection_probability=0.5,
                                         clutter_rate=1,
                                         clutter_distribution=1)
    with pytest.raises(ValueError, match="hypotheses"):
        bernoulli.update(MultipleHypothesis([]), detector_context=constant_context())
    # A DetectionSet carries the context the caller passes on.
    detections = DetectionSet((), constant_context())
    assert detections.detector_context is not None
