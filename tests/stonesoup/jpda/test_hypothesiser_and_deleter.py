"""The context-aware PDAHypothesiser and ExpectedMissesDeleter, held against stock Stone Soup.

Conformance: with no context, or a context whose P_D and λ are the stock constants, the
drop-in gives the stock hypotheses bit for bit, and a whole MultiTargetMixtureTracker run
(JPDA, JPDA-EHM, JPDA-EHM2, JPDA-LBP, PDA) gives the stock tracks bit for bit. Behaviour:
P_D per track and λ per detection enter exactly where the stock constants do; P_D = 0
leaves a track untouched; the deleter keeps radar-only tracks through lidar scans that
cannot see them.
"""

import datetime
import math
import pickle

import numpy as np
import pytest
from stonesoup.dataassociator.neighbour import GNNWith2DAssignment
from stonesoup.dataassociator.probability import (
    JPDA,
    PDA,
    JPDAwithEHM,
    JPDAwithEHM2,
    JPDAwithLBP,
)
from stonesoup.deleter.time import UpdateTimeDeleter, UpdateTimeStepsDeleter
from stonesoup.hypothesiser.distance import DistanceHypothesiser
from stonesoup.hypothesiser.probability import PDAHypothesiser as StockPDAHypothesiser
from stonesoup.initiator.simple import MultiMeasurementInitiator
from stonesoup.measures import Mahalanobis
from stonesoup.models.measurement.linear import LinearGaussian
from stonesoup.models.transition.linear import (
    CombinedLinearGaussianTransitionModel,
    ConstantVelocity,
)
from stonesoup.predictor.kalman import KalmanPredictor
from stonesoup.tracker.simple import MultiTargetMixtureTracker
from stonesoup.types.detection import Detection, MissedDetection
from stonesoup.types.hypothesis import SingleHypothesis
from stonesoup.types.multihypothesis import MultipleHypothesis
from stonesoup.types.numeric import Probability
from stonesoup.types.prediction import GaussianStatePrediction
from stonesoup.types.state import GaussianState
from stonesoup.types.track import Track
from stonesoup.types.update import GaussianStateUpdate, Update
from stonesoup.updater.kalman import KalmanUpdater

from ctxmodels import (
    AngularSector,
    ClutterDensityModel,
    DetectionProbabilityModel,
    DetectionSet,
    DetectorContext,
    RangeBands,
    SensorModel,
)
from ctxmodels.stonesoup import (
    ContextFeeder,
    ExpectedMissesDeleter,
    MissesNotWeighedWarning,
    MultiSensorFeeder,
    PDAHypothesiser,
)
from ctxmodels.stonesoup import UpdateTimeStepsDeleter as FastUpdateTimeStepsDeleter

from .setups import (CLUTTER, MEASUREMENT, ORIGIN, PD, T0, TRANSITION, VARYING, _tracker,
                     constant_sensor, hypothesisers, track_at, tutorial_scans)


def at(seconds):
    return T0 + datetime.timedelta(seconds=seconds)


def assert_same_hypotheses(ours, stock):
    assert len(ours) == len(stock)
    for a, b in zip(ours, stock):
        assert type(a) is type(b)
        assert a.measurement is b.measurement or (
            isinstance(a.measurement, MissedDetection)
            and isinstance(b.measurement, MissedDetection)
            and a.measurement.timestamp == b.measurement.timestamp)
        assert type(a.probability) is type(b.probability)
        assert a.probability == b.probability  # Probability compares log values exactly
        assert np.array_equal(a.prediction.state_vector, b.prediction.state_vector)
        assert np.array_equal(a.prediction.covar, b.prediction.covar)
        if b.measurement_prediction is None:
            assert a.measurement_prediction is None
        else:
            assert np.array_equal(a.measurement_prediction.state_vector,
                                  b.measurement_prediction.state_vector)
            assert np.array_equal(a.measurement_prediction.covar, b.measurement_prediction.covar)


STOCK_CONFIGS = [
    dict(clutter_spatial_density=CLUTTER, prob_detect=PD),
    dict(clutter_spatial_density=CLUTTER, prob_detect=Probability(PD)),
    dict(clutter_spatial_density=CLUTTER, prob_detect=np.float64(0.7), prob_gate=0.99),
    dict(clutter_spatial_density=0.02, prob_detect=Probability(0.6), include_all=True),
    dict(clutter_spatial_density=CLUTTER, prob_detect=PD, normalise=False),
    dict(clutter_spatial_density=CLUTTER, prob_detect=1.0),
    # Values where float and Probability arithmetic round differently in 1 - P_D·P_G:
    # the drop-in must follow the stock types, not just the stock formula.
    dict(clutter_spatial_density=CLUTTER, prob_detect=0.65),
    dict(clutter_spatial_density=CLUTTER, prob_detect=0.75, prob_gate=0.99),
    dict(clutter_spatial_density=CLUTTER, prob_detect=Probability(0.8), prob_gate=0.99),
]


ASSOCIATORS = [JPDA, JPDAwithEHM, JPDAwithEHM2, JPDAwithLBP, PDA]


@pytest.fixture(scope="module")
def scans():
    return tutorial_scans(seed=6, clutter_max=4)


def _tracks():
    return [track_at(0, 0), track_at(0, 20, vy=-1), track_at(8, 10, vx=0.5, vy=0)]


# --- hypothesiser conformance ---------------------------------------------------------------

@pytest.mark.parametrize("config", STOCK_CONFIGS + [dict(prob_detect=Probability(0.85))])
def test_without_context_identical_to_stock(scans, config):
    stock, ours = hypothesisers(config)
    for track in _tracks():
        for time, detections in scans[:8]:
            assert_same_hypotheses(ours.hypothesise(track, detections, time),
                                   stock.hypothesise(track, detections, time))
            # A DetectionSet without a context is a plain scan too. (Same set object for
            # both: a copied set may iterate in another order, which changes the order of
            # the normalising sum in the last bit.)
            no_context = DetectionSet(detections)
            assert_same_hypotheses(ours.hypothesise(track, no_context, time),
                                   stock.hypothesise(track, no_context, time))


@pytest.mark.parametrize("config", STOCK_CONFIGS)
def test_constant_context_identical_to_stock(scans, config):
    stock, ours = hypothesisers(config)
    sensor = constant_sensor(float(config["prob_detect"]), config["clutter_spatial_density"])
    gated = 0
    for track in _tracks():
        for time, detections in scans[:8]:
            context = sensor.context(ORIGIN.pose_at(time), time)
            scan = DetectionSet(detections, context)
            reference = stock.hypothesise(track, scan, time)  # the stock one ignores the context
            gated += len(reference) - 1
            assert_same_hypotheses(ours.hypothesise(track, scan, time), reference)
            assert_same_hypotheses(
                ours.hypothesise(track, detections, time, detector_context=context),
                stock.hypothesise(track, detections, time))
    assert gated > 10  # the comparison covered real detection hypotheses


def test_context_keyword_takes_precedence_over_the_set(scans):
    _, ours = hypothesisers(dict(clutter_spatial_density=CLUTTER, prob_detect=PD))
    stock, _ = hypothesisers(dict(clutter_spatial_density=0.3, prob_detect=0.5))
    time, detections = scans[3]
    on_set = constant_sensor().context(ORIGIN.pose_at(time), time)
    explicit = constant_sensor(0.5, 0.3).context(ORIGIN.pose_at(time), time)
    track = _tracks()[0]
    scan = DetectionSet(detections, on_set)
    assert_same_hypotheses(ours.hypothesise(track, scan, time, detector_context=explicit),
                           stock.hypothesise(track, scan, time))


# --- P_D per track, λ per detection ----------------------------------------------------------

def _band(value_range, edges, values):
    return values[int(np.searchsorted(edges, value_range, side="right"))]


@pytest.mark.parametrize("include_all, as_type", [(False, Probability), (True, Probability),
                                                  (False, float)])
def test_varying_context_matches_stock_with_that_tracks_pd_and_that_detections_lambda(
        scans, include_all, as_type):
    """Each weight equals the stock weight of a hypothesiser built with this track's P_D and
    this detection's λ (computed here independently of the Rust core). P_D 0.35 is a value
    that does not survive float → Probability → float, so it must be passed on raw."""
    config = dict(clutter_spatial_density=1.0, prob_detect=as_type(0.5), normalise=False,
                  include_all=include_all, prob_gate=as_type(0.99))
    _, ours = hypothesisers(config)
    predictor, updater = ours.predictor, ours.updater
    checked = set()
    for track in _tracks():
        for time, detections in scans[:8]:
            context = VARYING.context(ORIGIN.pose_at(time), time)
            detections = DetectionSet(detections, context)
            hypotheses = ours.hypothesise(track, detections, time)
            prediction = predictor.predict(track, timestamp=time)
            pd = _band(math.hypot(prediction.state_vector[0, 0], prediction.state_vector[2, 0]),
                       (6.0, 14.0), (0.95, 0.35, 0.2))
            checked.add(pd)
            missed = StockPDAHypothesiser(predictor, updater, **{
                **config, "prob_detect": as_type(pd)}).hypothesise(track, set(), time)
            assert_same_hypotheses([hypotheses[0]], [missed[0]])
            stock_all = StockPDAHypothesiser(predictor, updater, **{
                **config, "prob_detect": as_type(pd)}).hypothesise(track, detections, time)
            assert {h.measurement for h in hypotheses if h} \
                == {h.measurement for h in stock_all if h}
            for hypothesis in list(hypotheses)[1:]:
                z = hypothesis.measurement.state_vector
                lam = _band(math.hypot(z[0, 0], z[1, 0]), (12.0,), (0.05, 0.4))
                stock = StockPDAHypothesiser(predictor, updater, **{
                    **config, "prob_detect": as_type(pd), "clutter_spatial_density": lam})
                reference = stock.hypothesise(track, detections, time)[hypothesis.measurement]
                assert_same_hypotheses([hypothesis], [reference])
    assert checked == {0.95, 0.35, 0.2}  # every P_D band was exercised


def test_detections_without_a_measurement_model_use_the_updaters_for_lambda():
    with_model = tutorial_scans(seed=3, steps=4)
    without = tutorial_scans(seed=3, steps=4, with_model=False)
    _, ours = hypothesisers(dict(clutter_spatial_density=1.0, prob_detect=PD, normalise=False))
    for (time, a), (_, b) in zip(with_model, without):
        context = VARYING.context(ORIGIN.pose_at(time), time)
        track = _tracks()[2]
        ha = ours.hypothesise(track, DetectionSet(a, context), time)
        hb = ours.hypothesise(track, DetectionSet(b, context), time)
        key = lambda h: tuple(h.measurement.state_vector.ravel())  # noqa: E731
        assert sorted(float(h.probability) for h in ha) == sorted(float(h.probability) for h in hb)
        assert sorted(map(key, list(ha)[1:])) == sorted(map(key, list(hb)[1:]))


def test_lambda_once_per_scan_and_pd_once_per_track(scans, monkeypatch):
    calls = {"clutter": 0, "pd": 0}
    clutter_method = DetectorContext.clutter_spatial_density_detections
    pd_method = DetectorContext.prob_detection_states

    def counting_clutter(self, detections):
        calls["clutter"] += 1
        return clutter_method(self, detections)

    def counting_pd(self, states):
        calls["pd"] += 1
        return pd_method(self, states)

    monkeypatch.setattr(DetectorContext, "clutter_spatial_density_detections", counting_clutter)
    monkeypatch.setattr(DetectorContext, "prob_detection_states", counting_pd)
    _, ours = hypothesisers(dict(clutter_spatial_density=CLUTTER, prob_detect=PD))
    tracks = _tracks()
    for n, (time, detections) in enumerate(scans[:5], start=1):
        context = VARYING.context(ORIGIN.pose_at(time), time)
        JPDA(ours).associate(tracks, DetectionSet(detections, context), time)
        assert calls == {"clutter": n, "pd": n * len(tracks)}


def test_plain_upstream_style_context_is_accepted(scans):
    """A context with only the scalar interface (as in dstl/Stone-Soup#1291)."""
    class ScalarContext:
        def prob_detection(self, state):
            return Probability(PD)

        def clutter_spatial_density(self, detection):
            return CLUTTER

    stock, ours = hypothesisers(dict(clutter_spatial_density=CLUTTER, prob_detect=Probability(PD)))
    for time, detections in scans[:5]:
        track = _tracks()[0]
        assert_same_hypotheses(ours.hypothesise(track, detections, time,
                                                detector_context=ScalarContext()),
                               stock.hypothesise(track, detections, time))


def test_bad_context_values_raise_naming_the_context(scans):
    class Context:
        def __init__(self, pd, lam):
            self.pd, self.lam = pd, lam

        def prob_detection(self, state):
            return self.pd

        def clutter_spatial_density(self, detection):
            return self.lam

    _, ours = hypothesisers(dict(clutter_spatial_density=CLUTTER, prob_detect=PD))
    time, detections = scans[2]
    with pytest.raises(ValueError, match="detector_context.*P_D"):
        ours.hypothesise(_tracks()[0], detections, time, detector_context=Context(1.5, 0.1))
    with pytest.raises(ValueError, match="detector_context.*clutter"):
        ours.hypothesise(_tracks()[0], detections, time, detector_context=Context(0.5, 0.0))


# --- P_D = 0: the track is left alone ----------------------------------------------------------

@pytest.mark.parametrize("associator", ASSOCIATORS)
def test_pd_zero_at_a_track_leaves_it_on_its_prediction(associator):
    """A scan that cannot see the track, with a detection right on it: the missed detection
    gets all the mass, the track coasts on its prediction, the detection is left over. The
    reference is a stock tracker whose global P_D is switched to 0 for that scan."""
    stock_h, ours = hypothesisers(dict(clutter_spatial_density=CLUTTER, prob_detect=PD))
    trackers = {"ours": _tracker(ours, UpdateTimeStepsDeleter(5), associator),
                "stock": _tracker(stock_h, UpdateTimeStepsDeleter(5), associator)}
    sensor = constant_sensor()
    for k in range(4):  # one target on x = y, no clutter: confirmed after two scans
        z = Detection([[k], [k]], timestamp=at(k), measurement_model=MEASUREMENT)
        scan = DetectionSet({z}, sensor.context(ORIGIN.pose_at(at(k))))
        for tracker in trackers.values():
            tracker.update_tracker(at(k), scan)
    track, = trackers["ours"].tracks
    assert isinstance(track[-1], Update)

    # Blind within 100 m of the sensor: P_D = 0 at the track, yet a detection right on it.
    blind = SensorModel(detection=DetectionProbabilityModel(factors=[
        RangeBands(edges=(100.0,), values=(0.0, 0.9))]),
        clutter=ClutterDensityModel(factors=[CLUTTER]))
    time = at(4)
    prediction = ours.predictor.predict(track, timestamp=time)
    on_track = Detection(prediction.state_vector[[0, 2]], timestamp=time,
                         measurement_model=MEASUREMENT)
    scan = DetectionSet({on_track}, blind.context(ORIGIN.pose_at(time), time))

    hypotheses = ours.hypothesise(track, scan, time)
    assert [float(h.probability) for h in hypotheses] == [1.0, 0.0]
    n_states = len(track)
    trackers["ours"].update_tracker(time, scan)
    stock_h.prob_detect = 0.0
    trackers["stock"].update_tracker(time, scan)
    assert trackers["ours"].tracks == {track} and len(track) == n_states + 1
    # All mass on the missed detection: the track coasts on its prediction (up to the
    # exp/log rounding of Stone Soup's mixture reduction with Probability weights) ...
    assert not isinstance(track[-1], Update)
    np.testing.assert_allclose(track[-1].state_vector, prediction.state_vector, rtol=1e-13)
    np.testing.assert_allclose(track[-1].covar, prediction.covar, rtol=1e-13)
    # ... exactly as the stock tracker does with P_D = 0.
    stock_track, = trackers["stock"].tracks
    assert_same_tracks([track], [stock_track])
    assert ours.recorded_prob_detect(track) == 0.0
    # The detection stayed unassociated, so it went to the initiator.
    assert any(holding[0].hypothesis.measurement is on_track
               for holding in trackers["ours"].initiator.holding_tracks)


# --- whole-tracker conformance -------------------------------------------------------------------

def birth(track):
    """A reproducible sort key: when and where the track started."""
    return track[0].timestamp, tuple(track[0].state_vector.ravel())


class OrderedMixtureTracker(MultiTargetMixtureTracker):
    """The stock tracker with its tracks visited in a reproducible order.

    Track hashes by identity, so two runs visit their track sets in different orders, and
    JPDA sums joint-hypothesis probabilities in that order: two *stock* runs on the same
    detections then differ in the last bits (measured: most tracks, by ~1e-14). Sorting by
    birth makes bit-for-bit comparison of runs meaningful; the loop itself is untouched.
    """

    @property
    def tracks(self):
        return sorted(self._tracks, key=birth)


def _run(tracker):
    seen = {}
    for _, tracks in tracker:
        for track in tracks:
            seen[id(track)] = track
    return sorted(seen.values(), key=birth)


def assert_same_tracks(ours, stock):
    assert len(ours) == len(stock)
    for a, b in zip(ours, stock):
        assert len(a) == len(b)
        for sa, sb in zip(a, b):
            assert type(sa) is type(sb) and sa.timestamp == sb.timestamp
            assert np.array_equal(sa.state_vector, sb.state_vector)
            assert np.array_equal(sa.covar, sb.covar)


@pytest.mark.parametrize("associator", ASSOCIATORS)
def test_tutorial_tracker_run_identical_to_stock(scans, associator):
    # The same scan objects for both runs: the drop-in's carry the stock constants' context.
    fed = list(ContextFeeder(scans, sensor_model=constant_sensor(), pose_source=ORIGIN))
    runs = {}
    for name, cls in (("stock", StockPDAHypothesiser), ("ours", PDAHypothesiser)):
        predictor, updater = KalmanPredictor(TRANSITION), KalmanUpdater(MEASUREMENT)
        hypothesiser = cls(predictor, updater, clutter_spatial_density=CLUTTER, prob_detect=PD)
        runs[name] = _run(_tracker(hypothesiser, UpdateTimeStepsDeleter(3), associator,
                                   detector=fed, tracker_cls=OrderedMixtureTracker))
    assert_same_tracks(runs["ours"], runs["stock"])
    # The run exercised the association: a track followed a target through most of the
    # scans, and some scans had detections shared between the hypotheses of several tracks.
    assert max(len(t) for t in runs["ours"]) >= 12
    shared = 0
    for time, _ in scans:
        seen = [h.measurement for t in runs["ours"] for s in t
                if s.timestamp == time
                and isinstance(getattr(s, "hypothesis", None), MultipleHypothesis)
                for h in s.hypothesis if h]
        shared += len(seen) - len(set(seen))
    assert shared > 0


def test_two_sensor_asynchronous_run_identical_to_stock():
    """A 1 Hz 'radar' and a 2.5 Hz 'lidar' (coinciding every 2 s) merged by
    MultiSensorFeeder, observing the same two targets, each scan with its own sensor's
    context of the stock constants."""
    radar_model = LinearGaussian(4, (0, 2), np.eye(2) * 2.0)
    radar = tutorial_scans(seed=5, steps=10, model=radar_model, period=1.0, clutter_max=3,
                           truth_seed=4)
    lidar = tutorial_scans(seed=6, steps=25, model=MEASUREMENT, period=0.4, clutter_max=2,
                           truth_seed=4)
    feeder = MultiSensorFeeder([
        ContextFeeder(radar, sensor_model=constant_sensor(name="radar"), pose_source=ORIGIN),
        ContextFeeder(lidar, sensor_model=constant_sensor(name="lidar"), pose_source=ORIGIN)])

    predictor, updater = KalmanPredictor(TRANSITION), KalmanUpdater(MEASUREMENT)
    ours = _tracker(PDAHypothesiser(predictor, updater, clutter_spatial_density=CLUTTER,
                                    prob_detect=PD),
                    UpdateTimeStepsDeleter(4), detector=feeder, tracker_cls=OrderedMixtureTracker)
    fed, seen = [], {}
    for time, tracks in ours:
        fed.append(feeder.current)  # the scan the tracker just processed
        assert feeder.current[0] == time
        seen.update((id(t), t) for t in tracks)
    assert len(fed) == len(radar) + len(lidar)  # every scan separately, none merged
    names = [d.detector_context.sensor_model.name for _, d in fed]
    assert [n for (t, _), n in zip(fed, names) if t == at(2)] == ["radar", "lidar"]

    predictor, updater = KalmanPredictor(TRANSITION), KalmanUpdater(MEASUREMENT)
    stock = _tracker(StockPDAHypothesiser(predictor, updater, clutter_spatial_density=CLUTTER,
                                          prob_detect=PD),
                     UpdateTimeStepsDeleter(4), detector=fed, tracker_cls=OrderedMixtureTracker)
    ours_tracks = sorted(seen.values(), key=birth)
    assert len(ours_tracks) >= 2
    assert_same_tracks(ours_tracks, _run(stock))


# --- the P_D record and pickling ---------------------------------------------------------------

def test_record_follows_the_tracker_and_survives_pickling(scans):
    _, ours = hypothesisers(dict(clutter_spatial_density=CLUTTER, prob_detect=PD))
    tracker = _tracker(ours, UpdateTimeStepsDeleter(3))
    for time, detections in scans[:8]:
        context = VARYING.context(ORIGIN.pose_at(time), time)
        tracker.update_tracker(time, DetectionSet(detections, context))
    assert tracker.tracks
    before = set(tracker.tracks)
    time, detections = scans[8]
    context = VARYING.context(ORIGIN.pose_at(time), time)
    tracker.update_tracker(time, DetectionSet(detections, context))
    assert before & tracker.tracks
    for track in before & tracker.tracks:  # tracks the tracker (not the initiator) updated
        # The last state was appended after this scan's hypothesise call.
        prior = Track(track.states[:-1])
        prediction = ours.predictor.predict(prior, timestamp=track.timestamp)
        mean = prediction.state_vector
        expected = _band(math.hypot(mean[0, 0], mean[2, 0]), (6.0, 14.0), (0.95, 0.35, 0.2))
        assert ours.recorded_prob_detect(track) == expected
        assert ours.recorded_prob_detect(track, len(track) - 1) == expected
    # Without a context the stock P_D is recorded.
    before = set(tracker.tracks)
    time, detections = scans[9]
    tracker.update_tracker(time, detections)
    assert before & tracker.tracks
    assert all(ours.recorded_prob_detect(t) == PD for t in before & tracker.tracks)

    copy, tracks = pickle.loads(pickle.dumps((ours, list(tracker.tracks))))
    assert [copy.recorded_prob_detect(t) for t in tracks] \
        == [ours.recorded_prob_detect(t) for t in tracker.tracks]
    with pytest.raises(IndexError, match="index"):
        ours.recorded_prob_detect(tracks[0], 10_000)


# --- the deleter ------------------------------------------------------------------------------

def _random_track(rng, n, first_is_update):
    """States at distinct times: detection-backed updates, predictions, and updates whose
    hypothesis is a missed detection (which count as misses for stock deleters too)."""
    states = []
    for k in range(n):
        t, mean = at(k), np.zeros((4, 1))
        kind = "update" if (k == 0 and first_is_update) else rng.choice(
            ["update", "prediction", "missed"], p=[0.3, 0.55, 0.15]) if k else "prior"
        if kind == "prior":
            states.append(GaussianState(mean, np.eye(4), timestamp=t))
            continue
        prediction = GaussianStatePrediction(mean, np.eye(4), timestamp=t)
        if kind == "prediction":
            states.append(prediction)
        else:
            measurement = Detection([[0], [0]], timestamp=t) if kind == "update" \
                else MissedDetection(timestamp=t)
            hypothesis = SingleHypothesis(prediction, measurement)
            states.append(GaussianStateUpdate(mean, np.eye(4), hypothesis, timestamp=t))
    return Track(states)


def test_deleter_with_pd_one_is_the_stock_update_time_steps_deleter():
    rng = np.random.default_rng(7)
    tracks = [_random_track(rng, int(rng.integers(1, 14)), bool(rng.integers(2)))
              for _ in range(300)]
    # (no hypothesiser, no context: each deleter says once that it counts, not weighs)
    for n in range(1, 7):
        stock = UpdateTimeStepsDeleter(time_steps_since_update=n)
        ours = ExpectedMissesDeleter(expected_misses=n)
        decisions = [stock.check_for_deletion(t) for t in tracks]
        with pytest.warns(MissesNotWeighedWarning) as caught:
            assert [ours.check_for_deletion(t) for t in tracks] == decisions
        assert len(caught) == 1
        assert 0 < sum(decisions) < len(tracks)
    # A constant P_D = p deletes after ceil(N / p) misses.
    ours = ExpectedMissesDeleter(expected_misses=2.0, default_prob_detect=0.5)
    stock = UpdateTimeStepsDeleter(time_steps_since_update=4)
    with pytest.warns(MissesNotWeighedWarning):
        assert [ours.check_for_deletion(t) for t in tracks] \
            == [stock.check_for_deletion(t) for t in tracks]


def test_deleter_sums_the_recorded_pd_since_the_last_detection(scans):
    _, ours = hypothesisers(dict(clutter_spatial_density=CLUTTER, prob_detect=PD))
    track = track_at(0, 0)
    hit = SingleHypothesis(None, Detection([[0], [0]], timestamp=at(0.5)))
    track.append(GaussianStateUpdate(track[0].state_vector, track[0].covar, hit,
                                     timestamp=at(0.5)))
    deleter = ExpectedMissesDeleter(expected_misses=1.0, hypothesiser=ours,
                                    default_prob_detect=0.25)
    sensors = [constant_sensor(0.3), constant_sensor(0.0), constant_sensor(0.6)]
    for k, sensor in enumerate(sensors, start=1):
        time = at(k)
        context = sensor.context(ORIGIN.pose_at(time), time)
        hypotheses = ours.hypothesise(track, DetectionSet(set(), context), time)
        track.append(hypotheses[0].prediction)
    assert deleter.expected_misses_since_detection(track) == pytest.approx(0.9)
    assert not deleter.check_for_deletion(track)
    # A state appended by someone else accrues the default, and the deleter says so.
    track.append(GaussianStatePrediction(track[-1].state_vector, track[-1].covar, timestamp=at(9)))
    with pytest.warns(MissesNotWeighedWarning, match="default_prob_detect=0.25"):
        assert deleter.expected_misses_since_detection(track) == pytest.approx(1.15)
    assert deleter.check_for_deletion(track)
    # A record whose time does not match the state is not used.
    time = at(10)
    ours.hypothesise(track, DetectionSet(set(), sensors[2].context(ORIGIN.pose_at(time))), time)
    track.append(GaussianStatePrediction(track[-1].state_vector, track[-1].covar,
                                         timestamp=at(11)))
    assert ours.recorded_prob_detect(track) is None


def test_deleter_and_hypothesiser_round_trip_through_yaml():
    from stonesoup.serialise import YAML
    _, ours = hypothesisers(dict(clutter_spatial_density=CLUTTER, prob_detect=Probability(PD),
                                 prob_gate=0.99))
    deleter = ExpectedMissesDeleter(expected_misses=2.5, hypothesiser=ours,
                                    default_prob_detect=0.5)
    loaded = YAML().load(YAML().dumps(deleter))
    assert type(loaded) is ExpectedMissesDeleter and type(loaded.hypothesiser) is PDAHypothesiser
    assert (loaded.expected_misses, loaded.default_prob_detect) == (2.5, 0.5)
    for name in ("clutter_spatial_density", "prob_detect", "prob_gate", "include_all",
                 "normalise"):
        assert getattr(loaded.hypothesiser, name) == getattr(ours, name)


def test_deleter_errors_name_the_argument():
    with pytest.raises(ValueError, match="expected_misses"):
        ExpectedMissesDeleter(expected_misses=0)
    with pytest.raises(TypeError, match="expected_misses"):
        ExpectedMissesDeleter(expected_misses="many")
    with pytest.raises(ValueError, match="default_prob_detect"):
        ExpectedMissesDeleter(expected_misses=2, default_prob_detect=1.5)
    stock, _ = hypothesisers(dict(clutter_spatial_density=CLUTTER))
    with pytest.raises(TypeError, match="hypothesiser"):
        ExpectedMissesDeleter(expected_misses=2, hypothesiser=stock)


# --- the paper's failure in miniature: 0.8 Hz radar + 10 Hz lidar ------------------------------

RADAR = SensorModel(
    detection=DetectionProbabilityModel(factors=[
        RangeBands(edges=(50.0, 1612.0), values=(0.0, 0.4, 0.0), upper_owns=(False, True)),
        AngularSector.blind(math.pi, math.radians(65))]),
    clutter=ClutterDensityModel(factors=[1e-6]), name="radar")
LIDAR = SensorModel(
    detection=DetectionProbabilityModel(factors=[RangeBands(edges=(50.0, 80.0),
                                                            values=(0.95, 0.2, 0.0))]),
    clutter=ClutterDensityModel(factors=[1e-3]), name="lidar")
RADAR_MODEL = LinearGaussian(4, (0, 2), np.eye(2) * 25.0)
LIDAR_MODEL = LinearGaussian(4, (0, 2), np.eye(2) * 0.1)
RADAR_PERIOD, LAST_RADAR_HIT, END = 1.25, 10.0, 15.0
BLIP_TIMES = (3.0, 3.1, 3.2)  # a lidar false target 20 m away, seen three scans then gone


def _radar_lidar_scans():
    rng = np.random.default_rng(12)
    radar = []
    for k in range(int(END / RADAR_PERIOD) + 1):
        t = k * RADAR_PERIOD
        detections = set()
        if t <= LAST_RADAR_HIT:  # a vessel 400 m out, then gone
            truth = np.array([[400.0 - 3.0 * t], [100.0 + 1.0 * t]])
            detections.add(Detection(truth + rng.normal(0, 3, (2, 1)), timestamp=at(t),
                                     measurement_model=RADAR_MODEL))
        radar.append((at(t), detections))
    lidar = []
    for k in range(int(END * 10) + 1):
        t = round(k * 0.1, 1)
        detections = set()
        if t in BLIP_TIMES:
            detections.add(Detection([[20.0], [5.0]], timestamp=at(t),
                                     measurement_model=LIDAR_MODEL))
        lidar.append((at(t), detections))
    return MultiSensorFeeder([ContextFeeder(radar, sensor_model=RADAR, pose_source=ORIGIN),
                              ContextFeeder(lidar, sensor_model=LIDAR, pose_source=ORIGIN)])


def _radar_lidar_run(make_deleter):
    transition = CombinedLinearGaussianTransitionModel([ConstantVelocity(0.05)] * 2)
    predictor = KalmanPredictor(transition)
    updater = KalmanUpdater(RADAR_MODEL)
    hypothesiser = PDAHypothesiser(predictor, updater, clutter_spatial_density=1e-3,
                                   prob_detect=0.9)
    initiator = MultiMeasurementInitiator(
        prior_state=GaussianState(np.zeros((4, 1)), np.diag([0, 9, 0, 9])),
        deleter=UpdateTimeDeleter(datetime.timedelta(seconds=3)),
        data_associator=GNNWith2DAssignment(
            DistanceHypothesiser(predictor, updater, Mahalanobis(), missed_distance=3)),
        updater=updater, min_points=2)
    tracker = MultiTargetMixtureTracker(
        initiator=initiator, deleter=make_deleter(hypothesiser), detector=_radar_lidar_scans(),
        data_associator=JPDA(hypothesiser), updater=updater)
    alive = {}  # track -> times it was in the tracker's output
    for time, tracks in tracker:
        for track in tracks:
            alive.setdefault(track, []).append(time)
    radar = [t for t in alive if t[0].state_vector[0, 0] > 300]
    blip = [t for t in alive if t[0].state_vector[0, 0] < 50]
    return alive, radar, blip


def test_expected_misses_deleter_keeps_the_radar_track_through_blind_lidar_scans():
    alive, radar, blip = _radar_lidar_run(
        lambda h: ExpectedMissesDeleter(expected_misses=1.0, hypothesiser=h))
    # One radar track, confirmed at the second radar scan, never dropped while the radar sees
    # the target (12 lidar scans between radar scans accrue P_D = 0 each) ...
    track, = radar
    times = alive[track]
    assert times[0] == at(RADAR_PERIOD)
    assert at(LAST_RADAR_HIT) in times
    gaps = [(b - a).total_seconds() for a, b in zip(times, times[1:])]
    assert max(gaps) < 0.11  # present at every scan of its life
    # ... and deleted by the radar scans that then miss it: 2 × 0.4 < 1 ≤ 3 × 0.4, so it
    # is gone at the third (13.75 s), last seen at the lidar scan before (13.7 s).
    assert times[-1] == at(13.7)
    # The lidar false target, where the lidar surely sees it (P_D 0.95), is deleted at its
    # second missed lidar scan (3.4 s): 0.95 < 1 ≤ 1.9.
    blip_track, = blip
    assert alive[blip_track][-1] == at(3.3)


def test_update_time_steps_deleter_faces_the_papers_trade_off():
    # Small N: the radar track dies between radar scans, and is re-initiated over and over.
    alive, radar, _ = _radar_lidar_run(lambda h: UpdateTimeStepsDeleter(time_steps_since_update=5))
    assert len(radar) > 1
    assert all(alive[t][-1] < at(LAST_RADAR_HIT + 0.01) for t in radar)
    first = min(radar, key=lambda t: alive[t][0])
    assert alive[first][-1] < at(2 * RADAR_PERIOD)  # gone before the next radar scan
    # N large enough to bridge radar scans keeps the lidar false track alive for N lidar scans.
    alive, radar, blip = _radar_lidar_run(
        lambda h: UpdateTimeStepsDeleter(time_steps_since_update=30))
    assert len(radar) == 1
    blip_track, = blip
    assert alive[blip_track][-1] >= at(BLIP_TIMES[-1] + 2.5)


def test_trailing_states_deleter_equals_the_stock_deleter():
    """Random tracks of predictions, detection-backed updates, updates without a detection
    and repeated timestamps (two sensors at one instant): the same verdict as stock."""
    rng = np.random.default_rng(12)
    prediction = GaussianStatePrediction(np.zeros((4, 1)), np.eye(4), timestamp=T0)
    for steps in (1, 2, 3, 5):
        ours, stock = FastUpdateTimeStepsDeleter(steps), UpdateTimeStepsDeleter(steps)
        verdicts = []
        for _ in range(300):
            states, t = [], 0
            for _ in range(int(rng.integers(1, 12))):
                t += int(rng.integers(0, 2))  # 0: another look at the same instant
                kind = rng.integers(3)
                hypothesis = SingleHypothesis(prediction, Detection(
                    np.zeros((2, 1)), timestamp=at(t))) if kind == 0 else SingleHypothesis(
                    prediction, MissedDetection(timestamp=at(t)))
                states.append(GaussianStatePrediction(np.zeros((4, 1)), np.eye(4), at(t))
                              if kind == 2 else
                              GaussianStateUpdate(np.zeros((4, 1)), np.eye(4), hypothesis, at(t)))
            track = Track(states)
            verdict = stock.check_for_deletion(track)
            assert ours.check_for_deletion(track) == verdict
            verdicts.append(verdict)
        assert 0 < sum(verdicts) < len(verdicts)  # both answers occur


@pytest.mark.parametrize("prob_gate", [0.5, 0.9, 0.95, 0.99, 0.9999, Probability(0.95)])
@pytest.mark.parametrize("ndim", [1, 2, 3, 4])
def test_gate_threshold_is_stone_soups(prob_gate, ndim):
    """The JPDA's gate (ctxmodels' hypothesiser and the array JPDA read our
    gate_threshold) is exactly the value Stone Soup's PDA hypothesiser compares with (its
    private _gate_threshold: pinned here, so a change upstream fails this test)."""
    from stonesoup.hypothesiser.probability import PDAHypothesiser as StockPDAHypothesiser
    from ctxmodels.stonesoup.jpda.hypothesiser import gate_threshold
    assert gate_threshold(prob_gate, ndim) == StockPDAHypothesiser._gate_threshold(prob_gate, ndim)
