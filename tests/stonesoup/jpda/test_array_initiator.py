"""The array M-of-N initiator (its holding tracks' scan in the Rust core,
``ctxmodels._core.initiator_scan``) against ctxmodels' component ``MultiMeasurementInitiator``
(the readable reference, Stone Soup's own hypothesiser, GNN assignment and updater).

"The same tracks" means, scan by scan: the same number of released tracks, and in
:func:`~ctxmodels.stonesoup.in_track_order` each pair has the same states in the same order,
of the same types, at the same timestamps, each update on the same detection object (so
the same gate and assignment decisions), and numbers — state vectors, covariances, the
hypotheses' distances, their predictions and measurement predictions — equal to a relative
``RTOL`` (of each array's largest magnitude). Not bit for bit: the core inverts the
innovation covariance by LU where Stone Soup calls ``pinv`` (distance) and ``inv`` (gain),
and sums its products in its own order; measured worst differences are ~1e-12 (120 s of
scenario 1 with the finite-difference bearing–range Jacobian, 603 tracks released; 5e-13
on the 12 s run below; ~1e-15 with linear models). ``RTOL`` leaves three orders of
magnitude for other platforms' rounding; a different decision would fail the structural
checks, not the tolerance. The holding tracks are compared the same way once their
pending states are added.
"""
from __future__ import annotations

import datetime

import numpy as np
import pytest
from stonesoup.dataassociator.neighbour import GNNWith2DAssignment
from stonesoup.deleter.time import UpdateTimeDeleter
from stonesoup.deleter.time import UpdateTimeStepsDeleter as StockDeleter
from stonesoup.hypothesiser.distance import DistanceHypothesiser
from stonesoup.measures import Mahalanobis, SquaredMahalanobis
from stonesoup.predictor.kalman import KalmanPredictor
from stonesoup.types.state import GaussianState
from stonesoup.updater.kalman import KalmanUpdater

from ctxmodels import _core
from ctxmodels.stonesoup import (ArrayMultiMeasurementInitiator, FastGNNWith2DAssignment,
                                 MultiMeasurementInitiator, in_track_order)

from .array_setups import assert_same_tracks
from .setups import MEASUREMENT, TRANSITION, tutorial_scans


def _run(ours, reference, scans, remove_at=None):
    released = 0
    for k, (time, detections) in enumerate(scans):
        a, b = ours.initiate(set(detections), time), reference.initiate(set(detections), time)
        assert_same_tracks(a, b)
        assert len(ours.holding_tracks) == len(reference.holding_tracks)
        released += len(a)
        if k == remove_at:  # a holding track removed from outside is forgotten by both
            victim = in_track_order(reference.holding_tracks)[0]
            reference.holding_tracks.remove(victim)
            first = victim.states[0]
            mine, = [t for t in ours.holding_tracks if t.states[0].hypothesis.measurement
                     is first.hypothesis.measurement]
            ours.holding_tracks.remove(mine)
    assert ours.component_calls == 0 and ours.array_calls == len(scans)
    # (reading holding_tracks builds them, complete)
    assert_same_tracks(ours.holding_tracks, reference.holding_tracks)
    return released


def _tutorial_pair(measure=Mahalanobis(), deleter=StockDeleter(3), **options):
    predictor, updater = KalmanPredictor(TRANSITION), KalmanUpdater(MEASUREMENT)
    gate = options.pop("gate", 3)

    def build(cls, associator):
        return cls(prior_state=GaussianState(np.zeros((4, 1)), np.diag([0, 1, 0, 1])),
                   measurement_model=MEASUREMENT, deleter=deleter,
                   data_associator=associator(DistanceHypothesiser(
                       predictor, updater, measure, missed_distance=gate)),
                   updater=updater, **options)
    return (build(ArrayMultiMeasurementInitiator, FastGNNWith2DAssignment),
            build(MultiMeasurementInitiator, GNNWith2DAssignment))


@pytest.mark.parametrize("updates_only", [True, False])
def test_releases_the_references_tracks(updates_only):
    ours, reference = _tutorial_pair(min_points=3 if updates_only else 5,
                                     updates_only=updates_only)
    scans = tutorial_scans(seed=9, steps=24, clutter_max=6)
    assert _run(ours, reference, scans, remove_at=10) >= 2


@pytest.mark.parametrize("measure, gate", [(SquaredMahalanobis(), 9.0), (Mahalanobis(), 3.0)])
def test_squared_measure_and_the_update_time_deleter(measure, gate):
    ours, reference = _tutorial_pair(measure, UpdateTimeDeleter(datetime.timedelta(seconds=3)),
                                     gate=gate, min_points=3)
    scans = tutorial_scans(seed=4, steps=24, clutter_max=8)
    assert _run(ours, reference, scans) >= 2


def test_the_scenarios_radar_and_lidar_scans():
    """The experiment's initiator (GNN on Mahalanobis distance, 3 points, 30 steps) on
    scenario 1's merged radar (bearing–range, finite-difference Jacobian) and lidar scans."""
    from ctxmodels.experiment import trackers
    from ctxmodels.experiment.scenarios import make_scenario
    from .array_setups import _array_initiator, _component
    run = make_scenario("mixed-range", 0, 12.0)
    reference = _component(trackers.build_tracker(trackers.TRACKERS["jpda"], run).tracker).initiator
    ours = _array_initiator(reference)
    scans = list(trackers.build_tracker(trackers.TRACKERS["jpda"], run).tracker.detector)
    assert _run(ours, reference, scans) >= 3


def test_expected_misses_weighed_in_each_scans_context():
    """An ExpectedMissesDeleter as the initiator's deleter (no hypothesiser: each miss weighed
    by P_D in the scan's context) on scenario 1's radar and lidar scans with their contexts:
    the same released and holding tracks as the component initiator, every scan on the
    array path; and the weighing matters (a count of 3 misses releases fewer tracks)."""
    from ctxmodels.experiment import trackers
    from ctxmodels.experiment.scenarios import make_scenario
    from ctxmodels.stonesoup import ExpectedMissesDeleter
    from .array_setups import _array_initiator, _component
    run = make_scenario("mixed-range", 0, 12.0)
    scans = list(trackers.build_tracker(trackers.TRACKERS["jpda-context"], run).tracker.detector)

    def pair(deleter):
        reference = _component(trackers.build_tracker(trackers.TRACKERS["jpda"], run).tracker).initiator
        reference.deleter = deleter()
        ours = _array_initiator(reference)
        ours.deleter = deleter()
        return ours, reference

    ours, reference = pair(lambda: ExpectedMissesDeleter(expected_misses=3))
    released = 0
    for time, detections in scans:
        context = detections.detector_context
        a = ours.initiate(set(detections), time, detector_context=context)
        b = reference.initiate(set(detections), time, detector_context=context)
        assert_same_tracks(a, b)
        assert len(ours.holding_tracks) == len(reference.holding_tracks)
        released += len(a)
    assert ours.component_calls == 0 and ours.array_calls == len(scans)
    assert_same_tracks(ours.holding_tracks, reference.holding_tracks)
    counted, _ = pair(lambda: StockDeleter(3))
    counted_released = sum(len(counted.initiate(set(d), t)) for t, d in scans)
    assert released > counted_released


def test_expected_misses_without_a_context_run_the_component_path():
    """A scan without a context cannot weigh the misses: it runs the component path, whose
    deleter counts them and says so once."""
    from ctxmodels.stonesoup import ExpectedMissesDeleter, MissesNotWeighedWarning
    ours, _ = _tutorial_pair(deleter=ExpectedMissesDeleter(expected_misses=3), min_points=3)
    scans = tutorial_scans(seed=9, steps=12, clutter_max=6)
    with pytest.warns(MissesNotWeighedWarning):
        for time, detections in scans:
            ours.initiate(set(detections), time)
    assert ours.array_calls == 0 and ours.component_calls == len(scans)


def test_only_released_tracks_are_built(monkeypatch):
    """On scenario 1's scans, with nothing reading :attr:`holding_tracks`, the only Stone
    Soup tracks the array initiator builds are the ones it releases: the holding tracks the
    deleter drops (clutter) never get a Track or a state."""
    from ctxmodels.experiment import trackers
    from ctxmodels.experiment.scenarios import make_scenario
    from ctxmodels.stonesoup.jpda._initiator_births import Births
    from .array_setups import _array_initiator, _component
    built = []
    real = Births.track
    monkeypatch.setattr(Births, "track", lambda self, *birth: built.append(1) or real(self, *birth))
    run = make_scenario("mixed-range", 0, 30.0)
    jpda = trackers.build_tracker(trackers.TRACKERS["jpda"], run).tracker
    ours = _array_initiator(_component(jpda).initiator)
    released = 0
    for time, detections in trackers.build_tracker(trackers.TRACKERS["jpda"], run).tracker.detector:
        released += len(ours.initiate(set(detections), time))
    born = ours._next_serial  # holding rows started
    assert ours.component_calls == 0 and released >= 10
    assert len(built) == released < born / 2  # most holding tracks were never built


def _scan_args(rows=2, dets=3):
    model = _core.MeasurementModel.linear(np.array([[1.0, 0, 0, 0], [0, 0, 1.0, 0]]),
                                              np.eye(2))
    f = np.eye(4)[np.newaxis]
    return dict(
        models=[model], means=np.zeros((rows, 4)), covars=np.stack([np.eye(4)] * rows),
        transition_index=np.zeros(rows, dtype=np.int64), transition_matrices=f,
        transition_covars=np.zeros((1, 4, 4)), detections=np.zeros((dets, 2)),
        model_index=np.zeros(dets, dtype=np.int64), missed_distance=3.0,
        points=np.ones(rows, dtype=np.int64), since=np.ones(rows, dtype=np.int64),
        new_time=np.ones(rows, dtype=bool))


def test_core_scan_assigns_updates_and_counts():
    args = _scan_args(rows=2, dets=2)
    args["means"][1, [0, 2]] = 10.0
    args["detections"][:] = [[10.5, 10.0], [50.0, 50.0]]
    out = _core.initiator_scan(**args, min_points=2)
    assert out["assigned"].tolist() == [-1, 0]
    # S = H P Hᵀ + R = 2 I: d = √(0.5² / 2); K = ½ on the measured rows
    assert out["distances"].tolist() == [np.sqrt(0.125)]
    assert out["means"][1].tolist() == [10.25, 0.0, 10.0, 0.0]
    assert out["points"].tolist() == [2, 2] and out["since"].tolist() == [2, 1]
    assert out["released"].tolist() == [True, True]
    out = _core.initiator_scan(**args, updates_only=True, min_points=2)
    assert out["points"].tolist() == [1, 2] and out["released"].tolist() == [False, True]
    assert "expired" not in out  # deletion is the deleter's verdict, not the core's


def test_core_scan_errors_name_the_argument():
    for key, value, argument in [
        ("covars", np.zeros((2, 4, 3)), "covars"),
        ("detections", np.zeros((3, 3)), "detections"),
        ("model_index", np.array([0, 1, 0]), "model_index"),
        ("model_index", np.array([0, -1, 0]), "model_index"),
        ("transition_index", np.array([0, 5]), "transition_index"),
        ("since", np.ones(3, dtype=np.int64), "since"),
        ("means", np.full((2, 4), np.nan), "means"),
        ("missed_distance", float("nan"), "missed_distance"),
        ("transition_covars", np.zeros((2, 4, 4)), "transition_covars"),
    ]:
        args = _scan_args()
        args[key] = value
        with pytest.raises(ValueError, match=f"^{argument}"):
            _core.initiator_scan(**args)
    args = _scan_args()
    args["covars"] = np.zeros((2, 4, 4))  # S = R: fine; a singular S is an error
    _core.initiator_scan(**args)
    args["models"] = [_core.MeasurementModel.linear(np.array([[1.0, 0, 0, 0], [0, 0, 1.0, 0]]),
                                                        np.zeros((2, 2)))]
    with pytest.raises(ValueError, match="^covars"):
        _core.initiator_scan(**args)


def test_infeasible_assignment_is_its_own_error_and_the_initiator_raises_the_stocks(
        monkeypatch):
    """With an infinite gate a holding row cannot stay unassigned: more rows than detections
    has no assignment. The core raises :class:`ctxmodels.InfeasibleAssignmentError` (a
    ValueError naming the argument, picklable); the array initiator turns it into the
    RuntimeError the stock initiator's associator raises, by type."""
    import pickle

    import ctxmodels
    assert issubclass(ctxmodels.InfeasibleAssignmentError, ValueError)
    assert ctxmodels.InfeasibleAssignmentError is ctxmodels.errors.InfeasibleAssignmentError
    error = pickle.loads(pickle.dumps(ctxmodels.InfeasibleAssignmentError("cost", "row 1")))
    assert type(error) is ctxmodels.InfeasibleAssignmentError and str(error) == "cost: row 1"
    assert (error.argument, error.detail) == ("cost", "row 1")
    args = {**_scan_args(rows=2, dets=1), "missed_distance": float("inf")}
    with pytest.raises(ctxmodels.InfeasibleAssignmentError, match="^missed_distance: .*not feasible"):
        _core.initiator_scan(**args, min_points=2)
    from ctxmodels.stonesoup.jpda import _initiator_scan
    raised, core_scan = [], _core.initiator_scan

    def spy(*a, **k):
        try:
            return core_scan(*a, **k)
        except ctxmodels.InfeasibleAssignmentError:
            raised.append(1)
            raise
    monkeypatch.setattr(_initiator_scan._core, "initiator_scan", spy)
    scans = tutorial_scans(seed=9, steps=6, clutter_max=1)
    outcomes = []
    for initiator in _tutorial_pair(gate=float("inf")):
        try:
            for time, detections in scans:
                initiator.initiate(set(list(detections)[:1]) if time > scans[2][0] else
                                   detections, time)
            outcomes.append(None)
        except RuntimeError as err:
            outcomes.append(str(err))
    assert outcomes == ["Assignment was not feasible"] * 2
    assert raised == [1]  # the array initiator's came from the core's error


@pytest.mark.parametrize("layout", [
    [(-1.0, 0.0), (1.0, 0.0)],  # two tracks, one detection midway: an exact tie
    [(-1.0, 0.0), (1.0, 0.0), (0.0, 1.0)],  # three equidistant tracks
    [(-2.0, 1.0), (2.0, 1.0), (0.0, -1.0), (0.0, 3.0)],  # four tracks, two pairs tie
])
@pytest.mark.parametrize("detections", [[(0.0, 0.0)], [(0.0, 0.0), (0.0, 0.0)]])
def test_assignment_ties_go_as_the_references(layout, detections):
    """Holding tracks placed symmetrically about the detections, so that their distances tie
    exactly in both paths: the core's assignment breaks the tie as SciPy's (which Stone
    Soup's GNN calls) does — the same track takes the same detection. (Tracks with equal
    states would be no test: their order is the set's, in the reference too, and which of
    two equal tracks takes a detection changes no number.)"""
    from stonesoup.types.detection import Detection
    from stonesoup.types.hypothesis import SingleHypothesis
    from stonesoup.types.track import Track
    from stonesoup.types.update import GaussianStateUpdate
    start = datetime.datetime(2024, 1, 1)
    later = start + datetime.timedelta(seconds=1)
    scan = [Detection(np.array([[x], [y]]), timestamp=later, measurement_model=MEASUREMENT,
                      metadata={"k": k}) for k, (x, y) in enumerate(detections)]
    made = []
    for cls, associator in ((ArrayMultiMeasurementInitiator, FastGNNWith2DAssignment),
                            (MultiMeasurementInitiator, GNNWith2DAssignment)):
        predictor, updater = KalmanPredictor(TRANSITION), KalmanUpdater(MEASUREMENT)
        initiator = cls(prior_state=GaussianState(np.zeros((4, 1)), np.diag([0, 1, 0, 1])),
                        measurement_model=MEASUREMENT, deleter=StockDeleter(3), updater=updater,
                        min_points=5, data_associator=associator(DistanceHypothesiser(
                            predictor, updater, Mahalanobis(), missed_distance=10)))
        for k, (x, y) in enumerate(layout):
            birth = Detection(np.array([[x], [y]]), timestamp=start, metadata={"row": k})
            initiator.holding_tracks.add(Track([GaussianStateUpdate(
                np.array([[x], [0.0], [y], [0.0]]), np.eye(4), SingleHypothesis(None, birth),
                timestamp=start)]))
        initiator.initiate(set(scan), later)
        made.append({t.states[0].hypothesis.measurement.metadata.get("row"):
                     getattr(getattr(t.states[-1], "hypothesis", None), "measurement", None)
                     for t in initiator.holding_tracks if len(t) > 1})
    ours, reference = made
    assert ours.keys() == reference.keys()
    assert {k: getattr(d, "metadata", None) for k, d in ours.items()} == \
        {k: getattr(d, "metadata", None) for k, d in reference.items()}
    assert any(d is not None for d in reference.values())  # something was assigned
