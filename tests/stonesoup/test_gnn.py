"""Conformance of the batched GNN associator with stock Stone Soup 1.9.1.

:class:`FastGNNWith2DAssignment` is held against the stock
:class:`~stonesoup.dataassociator.neighbour.GNNWith2DAssignment` with its own (separate but
identical) hypothesiser: the same track → hypothesis mapping in the same order, hypotheses
equal object graph for object graph (types, predictions with their transition model and
prior, measurement predictions, distances to floating-point equality), the same sharing of
prediction and measurement-prediction objects within a track's hypotheses, the same
assignment under ties; and, as the ``MultiMeasurementInitiator``'s associator inside a
whole JPDA ``MultiTargetMixtureTracker`` run, the same holding and confirmed tracks, state
for state, after every scan.

Track sets hash by identity, so two runs visit them in different orders and JPDA sums its
joint probabilities in that order: two *stock* runs differ in the last bits. The run tests
therefore hand every associator its tracks sorted by birth (test-only subclasses below);
the associators themselves are untouched.
"""
import datetime
import math

import numpy as np
import pytest
from stonesoup.base import Base
from stonesoup.dataassociator.neighbour import GNNWith2DAssignment
from stonesoup.dataassociator.probability import JPDAwithEHM2
from stonesoup.deleter.time import UpdateTimeStepsDeleter
from stonesoup.hypothesiser.distance import DistanceHypothesiser
from stonesoup.hypothesiser.probability import PDAHypothesiser
from stonesoup.initiator.simple import MultiMeasurementInitiator
from stonesoup.measures import Euclidean, Mahalanobis, SquaredMahalanobis
from stonesoup.models.measurement.linear import LinearGaussian
from stonesoup.models.measurement.nonlinear import (
    CartesianToBearingRange,
    CartesianToElevationBearingRange,
)
from stonesoup.models.transition.linear import (
    CombinedLinearGaussianTransitionModel,
    ConstantVelocity,
)
from stonesoup.predictor.kalman import (
    ExtendedKalmanPredictor,
    KalmanPredictor,
    UnscentedKalmanPredictor,
)
from stonesoup.tracker.simple import MultiTargetMixtureTracker
from stonesoup.types.angle import Bearing
from stonesoup.types.array import StateVector
from stonesoup.types.detection import Clutter, Detection, TrueDetection
from stonesoup.types.hypothesis import SingleDistanceHypothesis, SingleHypothesis
from stonesoup.types.prediction import Prediction
from stonesoup.types.state import GaussianState, WeightedGaussianState
from stonesoup.types.track import Track
from stonesoup.types.update import GaussianStateUpdate
from stonesoup.updater.kalman import ExtendedKalmanUpdater, KalmanUpdater

from ctxmodels.stonesoup import ComponentPathWarning, gnn
from ctxmodels.stonesoup.gnn import FastGNNWith2DAssignment

T0 = datetime.datetime(2025, 3, 1, 9, 0, 0)
TRANSITION = CombinedLinearGaussianTransitionModel([ConstantVelocity(0.5), ConstantVelocity(0.5)])
LIDAR = LinearGaussian(4, (0, 2), np.diag([1.5, 1.5]))
INIT_COVAR = np.diag([10.0, 15.0, 10.0, 15.0]) ** 2


def at(seconds):
    return T0 + datetime.timedelta(seconds=seconds)


def radar(heading=0.3, offset=(5.0, -3.0)):
    return CartesianToBearingRange(4, (0, 2), np.diag([0.01 ** 2, 4.0]),
                                   translation_offset=StateVector(list(offset)),
                                   rotation_offset=StateVector([0.0, 0.0, heading]))


# --- deep comparison -------------------------------------------------------------------------

def assert_same(a, b, path="root", seen=None):
    """``a`` and ``b`` are equal object graphs: same types, equal numbers (arrays to
    floating-point equality, object arrays element type by element type), shared objects
    (detections, models) identical. ``seen`` memoises compared pairs (and keeps them alive,
    so ids are not reused)."""
    if a is b:
        return
    seen = {} if seen is None else seen
    key = (id(a), id(b))
    if key in seen:
        return
    seen[key] = (a, b)
    assert type(a) is type(b), f"{path}: {type(a).__name__} != {type(b).__name__}"
    if isinstance(a, np.ndarray):
        assert a.shape == b.shape and a.dtype == b.dtype, path
        if a.dtype == object:
            for x, y in zip(a.ravel(), b.ravel()):
                assert type(x) is type(y) and x == y, f"{path}: {x!r} != {y!r}"
        else:
            assert np.array_equal(a, b), f"{path}: {a!r} != {b!r}"
    elif isinstance(a, Track):
        assert_same(list(a.states), list(b.states), f"{path}.states", seen)
    elif isinstance(a, Base):
        if isinstance(a, Prediction):  # held strongly or (once superseded) by weak reference
            assert type(a._property_prior) is type(b._property_prior), f"{path}.prior"
        for name in type(a).properties:
            assert_same(getattr(a, name), getattr(b, name), f"{path}.{name}", seen)
    elif isinstance(a, (list, tuple)):
        assert len(a) == len(b), f"{path}: length {len(a)} != {len(b)}"
        for k, (x, y) in enumerate(zip(a, b)):
            assert_same(x, y, f"{path}[{k}]", seen)
    elif isinstance(a, dict):
        assert list(a) == list(b), path
        for k in a:
            assert_same(a[k], b[k], f"{path}[{k!r}]", seen)
    elif isinstance(a, float) and math.isnan(a):
        assert math.isnan(b), path
    else:
        assert a == b, f"{path}: {a!r} != {b!r}"


def sharing(multi):
    """Which hypotheses of one track share their prediction / measurement prediction."""
    preds = [h.prediction for h in multi]
    meas = [h.measurement_prediction for h in multi]
    return ([next(k for k, p in enumerate(preds) if p is q) for q in preds],
            [None if m is None else next(k for k, x in enumerate(meas) if x is m) for m in meas])


def assert_same_hypotheses(expected, got):
    """Same tracks (the same objects, or equal copies) in the same order, equal hypotheses
    sharing objects alike."""
    assert len(expected) == len(got)
    seen = {}
    for (ta, ha), (tb, hb) in zip(expected.items(), got.items()):
        assert_same(ta, tb, "track", seen)
        assert_same(ha, hb, "hypotheses", seen)
        assert sharing(ha) == sharing(hb)


def assert_same_associations(expected, got, tracks=None):
    """The same mapping; in the same order when both hold the same track objects, else
    (two copies of the tracks, ``tracks`` = (copy a, copy b)) matched by position."""
    if tracks is None:
        assert [id(t) for t in expected] == [id(t) for t in got]
        pairs = [(t, t) for t in expected]
    else:
        assert len(expected) == len(got) == len(tracks[0])
        pairs = list(zip(*tracks))
    seen = {}
    for ta, tb in pairs:
        assert_same(expected[ta], got[tb], "association", seen)


def assert_same_prior_references(tracks_a, tracks_b):
    """Predictions hold their prior strongly until the next prediction from that prior
    turns it into a weak reference (``Prediction.__init__``): the same pattern in both."""
    for ta, tb in zip(tracks_a, tracks_b):
        for sa, sb in zip(ta, tb):
            pa = getattr(getattr(sa, "hypothesis", None), "prediction", None)
            pb = getattr(getattr(sb, "hypothesis", None), "prediction", None)
            assert type(getattr(pa, "_property_prior", None)) is \
                type(getattr(pb, "_property_prior", None))


# --- unit-level: one scan ------------------------------------------------------------------

def associators(predictor_cls=KalmanPredictor, updater_cls=ExtendedKalmanUpdater,
                measure=None, **options):
    """A stock and a fast associator, each with its own (identical) components, so that no
    cache is shared between them."""
    pair = []
    for cls in (GNNWith2DAssignment, FastGNNWith2DAssignment):
        hypothesiser = DistanceHypothesiser(
            predictor_cls(TRANSITION), updater_cls(measurement_model=None),
            measure if measure is not None else Mahalanobis(),
            **{"missed_distance": 3, **options})
        pair.append(cls(hypothesiser))
    return pair


def track_histories(rng, t, count=12):
    """Tracks ending in the state types a MultiMeasurementInitiator produces (an initiated
    update, updates from a distance hypothesis whose prediction has a prior, predictions
    after misses) and a plain Gaussian state, last updated at various times."""
    predictor = KalmanPredictor(TRANSITION)
    updater = KalmanUpdater(LIDAR)
    tracks = []
    for k in range(count):
        start = at(t - 3.0 + 0.25 * (k % 4))
        mean = np.array([rng.uniform(-300, 300), rng.normal(0, 5),
                         rng.uniform(-300, 300), rng.normal(0, 5)])
        first = Detection(StateVector(mean[[0, 2]]), timestamp=start, measurement_model=LIDAR)
        track = Track([GaussianStateUpdate(StateVector(mean), INIT_COVAR.copy(),
                                           SingleHypothesis(None, first), start)])
        kind = k % 4
        steps = {0: 0, 1: 2, 2: 3, 3: 1}[kind]
        when = start
        for step in range(steps):
            when += datetime.timedelta(seconds=0.5)
            prediction = predictor.predict(track, timestamp=when)
            if kind == 2 and step == steps - 1:
                track.append(prediction)  # a miss: the track ends on a prediction
                continue
            z = LIDAR.function(prediction, noise=False) + rng.normal(0, 1, (2, 1))
            det = Detection(StateVector(z), timestamp=when, measurement_model=LIDAR)
            measurement_prediction = updater.predict_measurement(prediction)
            track.append(updater.update(SingleDistanceHypothesis(
                prediction, det, 1.0, measurement_prediction)))
        if k == 7:
            track.append(GaussianState(track.state.state_vector.copy(),
                                       track.state.covar.copy(), timestamp=track.timestamp))
        tracks.append(track)
    return tracks


def scan(rng, tracks, t, model=None, clutter=12, det_time=None, near_fraction=0.7):
    """Detections at ``det_time`` (default ``t``): clutter plus one near most tracks'
    predicted measurement, under ``model`` (default: lidar)."""
    model = LIDAR if model is None else model
    when = at(t if det_time is None else det_time)
    predictor = KalmanPredictor(TRANSITION)
    detections = set()
    for track in tracks:
        if rng.random() > near_fraction:
            continue
        prediction = predictor.predict(track, timestamp=when)
        z = np.asarray(model.function(prediction, noise=False), dtype=float).ravel()
        z += rng.normal(0, 1.0, z.shape) * np.sqrt(np.diag(model.covar()))
        detections.add(TrueDetection(_vector(model, z), timestamp=when, measurement_model=model,
                                     groundtruth_path=None))
    for _ in range(clutter):
        if isinstance(model, CartesianToBearingRange):
            z = np.array([rng.uniform(-math.pi, math.pi), rng.uniform(5, 500)])
        else:
            z = rng.uniform(-320, 320, 2)
        detections.add(Clutter(_vector(model, z), timestamp=when, measurement_model=model))
    return detections


def _vector(model, z):
    if isinstance(model, CartesianToBearingRange):
        return StateVector([Bearing(z[0]), z[1]])
    return StateVector(z)


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("options", [
    {}, {"include_all": True}, {"measure": SquaredMahalanobis(), "missed_distance": 9},
    {"missed_distance": 25}, {"predictor_cls": ExtendedKalmanPredictor},
    {"updater_cls": KalmanUpdater}])
def test_scan_matches_stock(seed, options):
    """Mixed radar (bearing–range, Bearing-typed) and lidar (linear) detections in one scan,
    tracks with every kind of history: hypotheses and associations equal to stock, and the
    tracks (two identical copies, one per associator) left alike."""
    t = 10.0
    copies = []
    for _ in range(2):
        tracks = track_histories(np.random.default_rng(seed), t)
        tracks.append(Track([GaussianStateUpdate(StateVector([9e3, 0.0, 9e3, 0.0]), INIT_COVAR,
                                                 SingleHypothesis(None, None), at(t - 1))]))
        copies.append(tracks)
    rng = np.random.default_rng(100 + seed)
    near = copies[0][:-1]  # nothing near the last (far) track
    detections = scan(rng, near, t) | scan(rng, near, t, model=radar(), clutter=20)
    if options.get("updater_cls") is KalmanUpdater:  # a linear updater: lidar only
        detections = {d for d in detections if d.measurement_model is LIDAR}
    stock, fast = associators(**options)
    assert_same_hypotheses(stock.generate_hypotheses(copies[0], detections, at(t)),
                           fast.generate_hypotheses(copies[1], detections, at(t)))
    assert_same_prior_references(*copies)
    stock, fast = associators(**options)
    expected = stock.associate(copies[0], detections, at(t))
    got = fast.associate(copies[1], detections, at(t))
    assert_same_associations(expected, got, copies)
    # the scan exercised the gate: some tracks were assigned a detection, some missed
    assert 0 < sum(bool(h) for h in got.values()) < len(got)
    # and the associator's own set handling (undetected tracks first, in set order)
    stock, fast = associators(**options)
    track_set = set(copies[1])
    assert [id(t) for t in stock.associate(track_set, detections, at(t))] == \
        [id(t) for t in fast.associate(track_set, detections, at(t))]


def test_detections_stamped_after_the_scan_time():
    """Missed detections predicted to the scan time, detections to their own (later)
    times, as the stock predictor's per-timestamp cache shares them."""
    rng = np.random.default_rng(11)
    tracks = track_histories(rng, 5.0)
    detections = scan(rng, tracks, 5.0, det_time=5.25) | scan(rng, tracks, 5.0)
    for options in ({}, {"include_all": True}):
        stock, fast = associators(**options)
        assert_same_hypotheses(stock.generate_hypotheses(tracks, detections, at(5.0)),
                               fast.generate_hypotheses(tracks, detections, at(5.0)))


def test_bearings_across_the_pi_line():
    """Radar detections of targets straight behind the sensor (bearing ±π): the wrapped
    differences decide the gate as the stock Bearing arithmetic does."""
    model = radar(heading=0.0, offset=(0.0, 0.0))
    tracks, detections = [], set()
    rng = np.random.default_rng(3)
    for k in range(20):
        x, y = -200.0 - 10 * k, rng.normal(0, 2.0)
        tracks.append(Track([GaussianStateUpdate(StateVector([x, 0.0, y, 0.0]), INIT_COVAR,
                                                 SingleHypothesis(None, None), at(0))]))
        bearing = math.atan2(y, x) + rng.normal(0, 0.01)
        bearing = (bearing + math.pi) % (2 * math.pi) - math.pi
        detections.add(Detection(StateVector([Bearing(bearing), math.hypot(x, y)]),
                                 timestamp=at(0.5), measurement_model=model))
    stock, fast = associators()
    expected = stock.generate_hypotheses(tracks, detections, at(0.5))
    assert_same_hypotheses(expected, fast.generate_hypotheses(tracks, detections, at(0.5)))
    assert sum(len(h) - 1 for h in expected.values()) >= 15  # wrapped pairs did gate


@pytest.mark.parametrize("measure, gate", [(Mahalanobis(), 3.0), (SquaredMahalanobis(), 9.0)])
def test_pairs_on_the_gate_are_decided_as_stock(measure, gate):
    """Detections placed at the gate distance (to rounding) in many directions: the
    screening keeps every pair the stock gate could accept, and the exact distance decides."""
    rng = np.random.default_rng(5)
    predictor, updater = KalmanPredictor(TRANSITION), ExtendedKalmanUpdater(None)
    tracks = track_histories(rng, 2.0, count=8)
    detections = set()
    for track in tracks:
        mp = updater.predict_measurement(predictor.predict(track, timestamp=at(2.0)), LIDAR)
        root = np.linalg.cholesky(mp.covar)
        for angle in np.linspace(0, 2 * math.pi, 40, endpoint=False):
            direction = np.array([math.cos(angle), math.sin(angle)])
            z = mp.state_vector.ravel() + 3.0 * root @ direction
            detections.add(Detection(StateVector(z), timestamp=at(2.0), measurement_model=LIDAR))
    stock, fast = associators(measure=measure, missed_distance=gate)
    expected = stock.generate_hypotheses(tracks, detections, at(2.0))
    got = fast.generate_hypotheses(tracks, detections, at(2.0))
    assert_same_hypotheses(expected, got)
    inside = sum(len(h) - 1 for h in expected.values())
    assert 0 < inside < 40 * len(tracks)  # rounding put some pairs either side of the gate


def test_ties_are_broken_as_stock():
    """Identical tracks competing for the same detections: equal costs, so the assignment
    depends on the row order, which must be the stock one."""
    state = GaussianStateUpdate(StateVector([10.0, 1.0, -5.0, 0.5]), INIT_COVAR,
                                SingleHypothesis(None, None), at(0))
    for order in range(3):
        tracks = [Track([GaussianStateUpdate(state.state_vector.copy(), state.covar.copy(),
                                             SingleHypothesis(None, None), at(0))])
                  for _ in range(4)]
        tracks = tracks[order:] + tracks[:order]
        detections = {Detection(StateVector([10.0 + dx, -5.0 + dy]), timestamp=at(1),
                                measurement_model=LIDAR)
                      for dx, dy in ((1.0, 0.0), (-1.0, 0.0), (0.0, 1.0))}
        stock, fast = associators()
        expected = stock.associate(tracks, detections, at(1))
        got = fast.associate(tracks, detections, at(1))
        assert_same_associations(expected, got)
        assert sorted(bool(h) for h in got.values()) == [False, True, True, True]
        assert [id(h.measurement) for h in got.values() if h] == \
            [id(h.measurement) for h in expected.values() if h]


def test_empty_inputs_and_missed_only_scans():
    rng = np.random.default_rng(2)
    tracks = track_histories(rng, 4.0)
    far = {Detection(StateVector([5000.0, 5000.0]), timestamp=at(4.0), measurement_model=LIDAR)}
    for trks, dets in ((tracks, set()), ([], far), ([], set()), (tracks, far)):
        stock, fast = associators()
        assert_same_hypotheses(stock.generate_hypotheses(trks, dets, at(4.0)),
                               fast.generate_hypotheses(trks, dets, at(4.0)))
        stock, fast = associators()
        assert_same_associations(stock.associate(set(trks), dets, at(4.0)),
                                 fast.associate(set(trks), dets, at(4.0)))


def test_infinite_gate_is_infeasible_as_stock():
    """With the default missed distance (infinity) a track cannot stay unassigned: more
    tracks than detections is infeasible, for both."""
    rng = np.random.default_rng(4)
    tracks = track_histories(rng, 3.0, count=4)
    one = {Detection(StateVector([0.0, 0.0]), timestamp=at(3.0), measurement_model=LIDAR)}
    stock, fast = associators(missed_distance=float("inf"))
    with pytest.raises(RuntimeError, match="not feasible"):
        stock.associate(set(tracks), one, at(3.0))
    with pytest.raises(RuntimeError, match="not feasible"):
        fast.associate(set(tracks), one, at(3.0))


def test_unbatched_models_and_states_use_the_stock_code(monkeypatch):
    """A measurement model without a batched form uses the stock measurement prediction on
    the batched predictions; a track whose state is not a plain Gaussian goes to the stock
    hypothesiser; the results stay stock."""
    rng = np.random.default_rng(9)
    tracks = track_histories(rng, 6.0)
    weighted = tracks[3].state
    tracks[3].append(WeightedGaussianState(weighted.state_vector, weighted.covar, weight=0.5,
                                           timestamp=weighted.timestamp))
    three_d = CartesianToElevationBearingRange(4, (0, 2, 1), np.diag([1e-4, 1e-4, 4.0]))
    detections = scan(rng, tracks, 6.0) | scan(rng, tracks, 6.0, model=three_d, clutter=0,
                                                 near_fraction=0.5)
    calls = []
    stock_hypothesise = DistanceHypothesiser.hypothesise
    monkeypatch.setattr(DistanceHypothesiser, "hypothesise",
                        lambda self, track, *a, **k: calls.append(track)
                        or stock_hypothesise(self, track, *a, **k))
    stock, fast = associators()
    expected = stock.generate_hypotheses(tracks, detections, at(6.0))
    calls.clear()
    got = fast.generate_hypotheses(tracks, detections, at(6.0))
    assert calls == [tracks[3]]
    assert_same_hypotheses(expected, got)


@pytest.mark.parametrize("setup", ["euclidean", "mapping", "unscented", "kwargs",
                                   "with-measurements"])
def test_unsupported_configurations_run_stock(setup, monkeypatch):
    rng = np.random.default_rng(6)
    tracks = track_histories(rng, 6.0)
    detections = scan(rng, tracks, 6.0)
    options, kwargs = {}, {}
    if setup == "euclidean":
        options = {"measure": Euclidean(mapping=(0, 1)), "missed_distance": 20}
    elif setup == "mapping":
        options = {"measure": Mahalanobis(mapping=(0, 1))}
    elif setup == "unscented":
        options = {"predictor_cls": UnscentedKalmanPredictor}
    elif setup == "with-measurements":
        options = {"predict_with_measurements": True}
    else:
        kwargs = {"unused": 1}
    batched = []
    monkeypatch.setattr(FastGNNWith2DAssignment, "_hypothesise_batch",
                        lambda self, *a: batched.append(a) or {})
    stock, fast = associators(**options)
    expected = stock.associate(set(tracks), detections, at(6.0), **kwargs)
    got = fast.associate(set(tracks), detections, at(6.0), **kwargs)
    assert not batched
    assert_same_associations(expected, got)


def test_value_equal_detections_run_stock(monkeypatch):
    """Detections comparing by value would change which column ``list.index`` finds."""
    class ValueDetection(Detection):
        def __eq__(self, other):
            return isinstance(other, Detection) and np.array_equal(self.state_vector,
                                                                   other.state_vector)
        __hash__ = Detection.__hash__

    rng = np.random.default_rng(8)
    tracks = track_histories(rng, 6.0)
    detections = {ValueDetection(d.state_vector, timestamp=d.timestamp,
                                 measurement_model=d.measurement_model)
                  for d in scan(rng, tracks, 6.0)}
    stock_associate = GNNWith2DAssignment.associate
    calls = []
    monkeypatch.setattr(GNNWith2DAssignment, "associate",
                        lambda self, *a, **k: calls.append(1) or stock_associate(self, *a, **k))
    fast = associators()[1]
    fast.associate(set(tracks), detections, at(6.0))
    assert calls == [1]


def test_screen_keeps_nan_and_drops_non_positive_gates():
    """The screening rule's corner cases: a NaN distance stays a candidate (the stock
    measure and gate decide); no square root is below a non-positive or NaN gate."""
    from ctxmodels.stonesoup._batch import measurement_batch
    rng = np.random.default_rng(1)
    tracks = track_histories(rng, 1.0, count=3)
    detections = list(scan(rng, tracks, 1.0, clutter=2))
    detections.append(Detection(StateVector([np.nan, 0.0]), timestamp=at(1.0),
                                measurement_model=LIDAR))
    priors = [t.state for t in tracks]
    means = np.array([p.state_vector for p in priors])
    covars = np.array([p.covar for p in priors])
    batch = measurement_batch(ExtendedKalmanUpdater(None), LIDAR, means, covars)
    screen = associators(missed_distance=1e-3)[1]._screen(batch, detections)
    assert screen[:, -1].all() and not screen[:, :-1].any()
    for gate in (0.0, -1.0, float("nan")):
        assert not associators(missed_distance=gate)[1]._screen(batch, detections).any()
    squared = associators(measure=SquaredMahalanobis(), missed_distance=1e12)[1]
    assert squared._screen(batch, detections).all()
    assert gnn.SCREEN_MARGIN < 1e-3
    # and the whole scan with the NaN detection is still the stock one (with include_all,
    # NaN distances and all, sorted as the stock comparisons sort them)
    for options in ({}, {"include_all": True}):
        stock, fast = associators(**options)
        assert_same_hypotheses(stock.generate_hypotheses(tracks, set(detections), at(1.0)),
                               fast.generate_hypotheses(tracks, set(detections), at(1.0)))


def test_drop_in_properties_and_round_trips():
    """Same Properties as the stock associator; survives pickling and Stone Soup's YAML,
    and the copies still give the stock result."""
    import pickle

    from stonesoup.serialise import YAML
    assert issubclass(FastGNNWith2DAssignment, GNNWith2DAssignment)
    assert list(FastGNNWith2DAssignment.properties) == list(GNNWith2DAssignment.properties)
    rng = np.random.default_rng(12)
    tracks = track_histories(rng, 6.0)
    detections = scan(rng, tracks, 6.0) | scan(rng, tracks, 6.0, model=radar())
    stock, fast = associators()
    # (YAML-loaded components hold ruamel's number and list types: compare like with like)
    for load in (lambda x: pickle.loads(pickle.dumps(x)), lambda x: YAML().load(YAML().dumps(x))):
        stock_copy, fast_copy = load(stock), load(fast)
        assert type(fast_copy) is FastGNNWith2DAssignment
        assert_same_associations(stock_copy.associate(tracks, detections, at(6.0)),
                                 fast_copy.associate(tracks, detections, at(6.0)))


# --- whole tracker runs ---------------------------------------------------------------------

def birth(track):
    """Reproducible track order: when and where the track started."""
    return track[0].timestamp, tuple(np.asarray(track[0].state_vector, dtype=float).ravel())


class _Sorted:
    """Test-only: hands the associator its tracks in birth order (see module docstring)."""

    def associate(self, tracks, detections, timestamp, **kwargs):
        return super().associate(sorted(tracks, key=birth), detections, timestamp, **kwargs)


class SortedGNN(_Sorted, GNNWith2DAssignment):
    pass


class SortedFastGNN(_Sorted, FastGNNWith2DAssignment):
    pass


class SortedJPDA(_Sorted, JPDAwithEHM2):
    pass


def _sorted_jpda_runs_the_component_path():
    """The sorted associator is not the array JPDA's: its scans run the component path (as
    intended: the initiators are compared), which the array tracker says once."""
    return pytest.warns(ComponentPathWarning, match="SortedJPDA, not a JPDA")


def sorted_tracker(tracker, fast):
    """The tracker with sorted associators; the initiator's GNN stock or fast."""
    initiator = tracker.initiator
    gnn = SortedFastGNN if fast else SortedGNN
    initiator.data_associator = gnn(initiator.data_associator.hypothesiser)
    tracker.data_associator = SortedJPDA(tracker.data_associator.hypothesiser)
    return tracker


def run_lockstep(stock, fast, max_scans=None):
    """Both trackers scan by scan: same times, same holding and confirmed tracks (by birth),
    equal object graphs. Returns (scans, max holding tracks, confirmed tracks seen)."""
    seen = {}
    scans = most_holding = 0
    confirmed = set()
    for (time_s, tracks_s), (time_f, tracks_f) in zip(stock, fast):
        assert time_s == time_f
        for which, a, b in (("confirmed", tracks_s, tracks_f),
                            ("holding", stock.initiator.holding_tracks,
                             fast.initiator.holding_tracks)):
            a, b = sorted(a, key=birth), sorted(b, key=birth)
            assert [birth(t) for t in a] == [birth(t) for t in b], f"{which} at {time_s}"
            for ta, tb in zip(a, b):
                assert_same(ta, tb, f"{which} track at {time_s}", seen)
            assert_same_prior_references(a, b)
        scans += 1
        most_holding = max(most_holding, len(fast.initiator.holding_tracks))
        confirmed.update(birth(t) for t in tracks_f)
        if max_scans is not None and scans >= max_scans:
            break
    return scans, most_holding, len(confirmed)


def linear_scans(seed=0, steps=40, period=0.5):
    """Three constant-velocity targets seen by a linear sensor (P_D 0.9) with clutter."""
    rng = np.random.default_rng(seed)
    truths = np.array([[0.0, 2.0, 0.0, 1.0], [50.0, -1.0, 20.0, 0.5], [-40.0, 0.5, 60.0, -2.0]])
    model = LinearGaussian(4, (0, 2), np.diag([0.75, 0.75]))
    scans = []
    for k in range(steps):
        t = at(k * period)
        truths[:, 0] += truths[:, 1] * period
        truths[:, 2] += truths[:, 3] * period
        detections = set()
        for x in truths:
            if rng.random() < 0.9:
                z = x[[0, 2]] + rng.normal(0, math.sqrt(0.75), 2)
                detections.add(TrueDetection(StateVector(z), timestamp=t, measurement_model=model,
                                             groundtruth_path=None))
        for _ in range(rng.poisson(6)):
            detections.add(Clutter(StateVector(rng.uniform(-100, 150, 2)), timestamp=t,
                                   measurement_model=model))
        scans.append((t, detections))
    return scans


class _Replay:
    def __init__(self, scans):
        self.scans = scans

    def __iter__(self):
        return ((t, set(d)) for t, d in self.scans)


def linear_tracker(scans, fast):
    predictor, updater = KalmanPredictor(TRANSITION), KalmanUpdater(measurement_model=None)
    initiator = MultiMeasurementInitiator(
        prior_state=GaussianState(np.zeros((4, 1)), INIT_COVAR),
        deleter=UpdateTimeStepsDeleter(4),
        data_associator=GNNWith2DAssignment(DistanceHypothesiser(predictor, updater,
                                                                 Mahalanobis(), missed_distance=3)),
        updater=updater, min_points=3)
    hypothesiser = PDAHypothesiser(predictor, updater, clutter_spatial_density=1e-4,
                                   prob_detect=0.9, prob_gate=0.95)
    tracker = MultiTargetMixtureTracker(initiator=initiator, deleter=UpdateTimeStepsDeleter(4),
                                        detector=_Replay(scans),
                                        data_associator=JPDAwithEHM2(hypothesiser),
                                        updater=updater)
    return sorted_tracker(tracker, fast)


def test_linear_jpda_run_matches_stock():
    scans = linear_scans()
    n, most_holding, confirmed = run_lockstep(linear_tracker(scans, False),
                                              linear_tracker(scans, True))
    assert n == len(scans)
    assert most_holding >= 10 and confirmed >= 3


def experiment_trackers(seed, duration):
    from ctxmodels.experiment.scenarios import make_scenario
    from ctxmodels.experiment.trackers import build_tracker
    from ctxmodels.trackers import TRACKERS
    run = make_scenario("mixed-range", seed, duration)
    return (sorted_tracker(build_tracker(TRACKERS["jpda"], run).tracker, False),
            sorted_tracker(build_tracker(TRACKERS["jpda"], run).tracker, True))


def test_paper_jpda_run_matches_stock_first_scans():
    """The paper's JPDA (radar bearing–range + lidar, ~100 holding tracks): the first 30
    scans of mixed-range, seed 0 (the whole run is the slow test below)."""
    stock, fast = experiment_trackers(0, 15.0)
    with _sorted_jpda_runs_the_component_path():
        n, most_holding, _ = run_lockstep(stock, fast, max_scans=30)
    assert n == 30 and most_holding >= 40


@pytest.mark.slow
@pytest.mark.parametrize("seed", [0, 1])
def test_paper_jpda_run_matches_stock(seed):
    stock, fast = experiment_trackers(seed, 15.0)
    with _sorted_jpda_runs_the_component_path():
        n, most_holding, confirmed = run_lockstep(stock, fast)
    assert n > 150 and most_holding >= 80 and confirmed >= 3
