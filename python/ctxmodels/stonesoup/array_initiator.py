r"""The M-of-N initiator with its holding tracks kept as arrays.

:class:`ArrayMultiMeasurementInitiator` has the Properties of ctxmodels'
:class:`~ctxmodels.stonesoup.MultiMeasurementInitiator` and releases the same tracks, with
the same states, scan for scan. In a JPDA run most detections are clutter and each starts a
holding track that coasts, unassociated, until the deleter drops it 30 scans later: a
hundred holding tracks, each predicted, hypothesised and given a prediction object every
scan, most never released. Here the holding tracks' means and covariances are stacked
arrays; a scan predicts them in one product, screens all track × detection pairs at once
(as :class:`~ctxmodels.stonesoup.FastGNNWith2DAssignment` does) and takes Stone Soup's own
distance, assignment and Kalman update for the few pairs that can pass the gate. A holding
track's coasting predictions are kept as array rows and turned into Stone Soup states only
when the track is updated or released; the deleter's verdict comes from a count kept per
track (the distinct times since its last detection, or that detection's time).

So a holding track (in :attr:`holding_tracks`, the live set, as stock) holds its states up
to its last update; the predictions since are added when it is updated or released, or
when a scan runs the component path. Released tracks are complete.

Supported (anything else runs ctxmodels' :class:`MultiMeasurementInitiator` code, after
the pending states are added): a :class:`~stonesoup.dataassociator.neighbour.GNNWith2DAssignment`
or :class:`~ctxmodels.stonesoup.FastGNNWith2DAssignment` over a plain
:class:`~stonesoup.hypothesiser.distance.DistanceHypothesiser` (Mahalanobis or squared
Mahalanobis measure without mapping, no ``predict_with_measurements``), a Kalman / extended
Kalman predictor with a linear Gaussian transition model, Kalman / extended Kalman updaters,
a stock or ctxmodels ``UpdateTimeStepsDeleter`` or Stone Soup's ``UpdateTimeDeleter`` with a
``timedelta`` window (``delete_last_pred`` off; the verdicts from per-row counts, see
:mod:`~ctxmodels.stonesoup.initiator_deletion`), Gaussian float64 states, and detections
stamped with the scan time.
"""
from __future__ import annotations

import numpy as np
from stonesoup.dataassociator import neighbour as _stock_neighbour
from stonesoup.dataassociator.neighbour import GNNWith2DAssignment
from stonesoup.hypothesiser.distance import DistanceHypothesiser
from stonesoup.measures import Mahalanobis, SquaredMahalanobis
from stonesoup.models.base import LinearModel, ReversibleModel
from stonesoup.types.angle import Bearing
from stonesoup.types.array import CovarianceMatrix, StateVector
from stonesoup.types.hypothesis import SingleDistanceHypothesis
from stonesoup.types.state import GaussianState

from ..model_key import measurement_model_key, scan_model_groups
from .fast import KALMAN_UPDATERS, ObjectFactory, measurement_batch, supports_predictor
from .fast_association import (
    FastGNNWith2DAssignment,
    _copied_properties,
    _measurement_prediction,
)
from . import initiator_deletion
from .initiator_births import UPDATE_STATE, Births
from .initiator_blocks import PRIOR_PREDICTION, Block, Holding, materialise
from .initiator_arrays import (ControlTerms, angle_wrap, kalman_updates, pair_distances,
                               predict_rows, screen, screen_states)
from .mixture_tracker import MultiMeasurementInitiator
from .ordering import OrderedDetections, in_stable_order, in_track_order

#: A hypothesis as the distance hypothesiser builds it.
_DISTANCE_HYPOTHESIS = ObjectFactory(SingleDistanceHypothesis, dict(
    prediction=None, measurement=None, distance=0.0, measurement_prediction=None))


class ArrayMultiMeasurementInitiator(MultiMeasurementInitiator):
    """ctxmodels' :class:`MultiMeasurementInitiator` with the holding tracks as arrays (see
    the module docstring): the same released tracks and states. :attr:`array_calls` and
    :attr:`component_calls` count the calls each path ran."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._records: list[Holding] = []
        self._serials: list = []  # the records' serials (ascending)
        self._next_serial = 0
        self._means = None  # (H, D, 1): each holding track's last state, aligned with _records
        self._covars = None  # (H, D, D)
        self._deletion = initiator_deletion.HoldingCounts()  # what the deleter reads, per row
        self._counted = np.empty(0, dtype=np.int64)  # points towards release
        self._last_times: list = []
        self._blocks: dict[int, Block] = {}
        self._next_block = 0
        self._births = Births()
        self._control_terms = ControlTerms()
        self._core_models: dict = {}
        self.array_calls = 0
        self.component_calls = 0

    # --- configuration ----------------------------------------------------------------------
    def _supported(self) -> bool:
        associator = self.data_associator
        if type(associator) not in (GNNWith2DAssignment, FastGNNWith2DAssignment):
            return False
        hypothesiser = associator.hypothesiser
        if type(hypothesiser) is not DistanceHypothesiser or hypothesiser.predict_with_measurements:
            return False
        measure = hypothesiser.measure
        if type(measure) not in (Mahalanobis, SquaredMahalanobis) or measure.mapping is not None:
            return False
        if not supports_predictor(hypothesiser.predictor):
            return False
        if type(hypothesiser.updater) not in KALMAN_UPDATERS or type(self.updater) not in KALMAN_UPDATERS:
            return False
        return initiator_deletion.supported(self.deleter)

    # --- pending states ------------------------------------------------------------------------
    def _materialise(self, record: Holding) -> None:
        """Append the states the component path would have appended since the record's last
        materialisation (see :func:`~ctxmodels.stonesoup.initiator_blocks.materialise`)."""
        materialise(record, self._blocks, self._next_block,
                    self.data_associator.hypothesiser.predictor.transition_model)

    def _materialise_all(self) -> None:
        for record in self._records:
            self._materialise(record)
        self._records = []
        self._serials = []
        self._means = self._covars = None
        self._deletion = initiator_deletion.HoldingCounts()
        self._counted = np.empty(0, dtype=np.int64)
        self._last_times = []
        self._blocks = {}
        self._points = {}  # the component path recounts from the (now complete) tracks

    def _prune_blocks(self) -> None:
        oldest = min((r.pending_from for r in self._records), default=self._next_block)
        for b in [b for b in self._blocks if b < oldest]:
            del self._blocks[b]

    def _read_track(self, track, ndim):
        """(last state, points, deletion counts (:func:`initiator_deletion.read`)) of a
        track joining the holding set, or None if its last state cannot be held as arrays."""
        states = track.states
        state = states[-1] if len(states) else None
        vector, covar = getattr(state, "state_vector", None), getattr(state, "covar", None)
        if not (isinstance(state, GaussianState) and _copied_properties(type(state)) is not None
                and isinstance(vector, np.ndarray) and vector.dtype == np.float64
                and vector.shape == (ndim, 1) and isinstance(covar, np.ndarray)
                and covar.dtype == np.float64 and covar.shape == (ndim, ndim)
                and state.timestamp is not None):
            return None
        if len(states) == 1:  # a new track: one state
            points = 1 if self._counts(state) else 0
        else:
            points = sum(1 for s in states if self._counts(s))
        return state, points, initiator_deletion.read(states)

    def _sync(self, ndim) -> bool:
        """Aligns the records with :attr:`holding_tracks` (tracks removed or added from
        outside, new tracks in :func:`track_key` order, as the drop-in orders them); False
        if a holding track cannot be held as arrays."""
        live = self.holding_tracks
        records = self._records
        if len(records) == len(live) and all(r.track in live for r in records):
            return True
        keep = [k for k, r in enumerate(records) if r.track in live]
        present = {id(records[k].track) for k in keep}
        added = in_track_order(t for t in live if id(t) not in present)
        if len(keep) < len(records):
            self._records = [records[k] for k in keep]
            self._serials = [self._serials[k] for k in keep]
            if self._means is not None:
                self._means, self._covars = self._means[keep], self._covars[keep]
            self._counted = self._counted[keep]
            self._deletion.take(keep)
            self._last_times = [self._last_times[k] for k in keep]
        return self._add(added, ndim)

    def _add(self, added, ndim) -> bool:
        """Appends records for the tracks ``added`` (in that order) to the holding rows."""
        if not added:
            return True
        read = [self._read_track(t, ndim) for t in added]
        if any(r is None for r in read):
            return False
        empty = self._means is None
        first = self._next_serial
        self._next_serial += len(added)
        self._records = self._records + [Holding(t, self._next_block, first + k)
                                         for k, t in enumerate(added)]
        self._serials = self._serials + list(range(first, first + len(added)))
        self._means = np.concatenate(
            [np.empty((0, ndim, 1)) if empty else self._means]
            + [state.state_vector[np.newaxis] for state, _, _ in read])
        self._covars = np.concatenate(
            [np.empty((0, ndim, ndim)) if empty else self._covars]
            + [state.covar[np.newaxis] for state, _, _ in read])
        self._counted = np.concatenate([self._counted, [p for _, p, _ in read]]).astype(np.int64)
        self._deletion.add([n for _, _, n in read])
        self._last_times = self._last_times + [state.timestamp for state, _, _ in read]
        return True

    def _core_model(self, updater, model):
        """(the core's model, its angle rows) for screening predicted states measured by
        ``model``, or None (then the measurement predictions of all rows screen)."""
        key = (measurement_model_key(model), type(updater))  # equal models share an entry
        cached = self._core_models.get(key)
        if cached is None:
            from .array_jpda import _core_model  # (that module builds on this one)
            core, bearing_row = _core_model(type(updater), model)
            entry = None if core is None else (core, {} if bearing_row is None
                                               else {bearing_row: Bearing})
            cached = self._core_models[key] = (model, type(updater), entry)
            if len(self._core_models) > 64:
                self._core_models = {key: cached}
        return cached[2]

    # --- a scan ---------------------------------------------------------------------------------
    def initiate(self, detections, timestamp, **kwargs):
        # The tracker's scan context: accepted, as by the component path (which, like the
        # stock initiator, does not pass it on: holding tracks are gated by distance).
        kwargs.pop("detector_context", None)
        if type(detections) is not OrderedDetections:  # (already in order: not sorted again)
            detections = in_stable_order(detections)
        if self.skip_non_reversible:
            detections = [d for d in detections
                          if isinstance(d.measurement_model, (ReversibleModel, LinearModel))]
        hypothesiser = getattr(self.data_associator, "hypothesiser", None)
        ndim = getattr(getattr(getattr(hypothesiser, "predictor", None), "transition_model", None),
                       "ndim_state", None)
        if kwargs or not self._supported() or any(d.timestamp != timestamp for d in detections) \
                or not self._sync(ndim):
            self._materialise_all()
            self.component_calls += 1
            return super().initiate(detections, timestamp, **kwargs)
        self.array_calls += 1

        sure_tracks = set()
        associated = set()
        if self._records:
            assigned = self._associate(detections, timestamp)
            self._advance(assigned, detections, timestamp, associated, sure_tracks)
        new = self._new_tracks([d for d in detections if id(d) not in associated], timestamp)
        self.holding_tracks |= new
        if not self._add(in_track_order(new), ndim):
            self._materialise_all()  # a new track the arrays cannot hold: re-read next scan
        return sure_tracks

    # --- new holding tracks ----------------------------------------------------------------------
    def _new_tracks(self, detections, timestamp):
        """What the inner initiator returns for ``detections`` (see
        :mod:`~ctxmodels.stonesoup.initiator_births`)."""
        return self._births(self.initiator, detections, timestamp)

    def _associate(self, detections, timestamp):
        """Per holding row: the assigned (detection index, distance, measurement prediction,
        predicted mean, predicted covariance), the string 'missed', or None (no state), as
        the GNN 2-D assignment decides; also predicts every row."""
        hypothesiser = self.data_associator.hypothesiser
        predictor, updater, measure = hypothesiser.predictor, hypothesiser.updater, hypothesiser.measure
        missed_distance = hypothesiser.missed_distance
        records = self._records
        n = len(records)
        pred_means, pred_covars = predict_rows(
            predictor, self._control_terms, lambda k: records[k].track.state, self._means,
            self._covars, self._last_times, timestamp)

        hypotheses: dict[int, list] = {}  # row -> [(column, distance, batch, batch row)]
        if detections:
            squared = type(measure) is SquaredMahalanobis
            # by model value: equal models in different objects are one group (its first)
            for raw_model, members in scan_model_groups(detections).values():
                resolved = updater._check_measurement_model(raw_model)
                group_dets = [detections[j] for j in members]
                candidates = None if hypothesiser.include_all else screen_states(
                    self._core_model(updater, resolved), pred_means, pred_covars, group_dets,
                    float(missed_distance), squared)
                if candidates is not None:
                    # only the rows that kept a pair: their measurement prediction (row by
                    # row the same numbers as in a batch of all rows)
                    index = np.flatnonzero(candidates.any(axis=1))
                    if not index.size:
                        continue
                    batch = measurement_batch(updater, resolved, pred_means[index],
                                              pred_covars[index])
                    candidates = candidates[index]
                else:
                    index = None
                    batch = measurement_batch(updater, resolved, pred_means, pred_covars)
                    candidates = np.ones((n, len(members)), dtype=bool) \
                        if hypothesiser.include_all \
                        else screen(batch, group_dets, float(missed_distance), squared)
                rows, cols = np.nonzero(candidates)  # batch rows
                if not rows.size:
                    continue
                distances = pair_distances(batch, rows.tolist(), cols.tolist(), group_dets,
                                           measure, squared, timestamp)
                holding = rows if index is None else index[rows]
                for row, brow, col, distance in zip(holding.tolist(), rows.tolist(),
                                                    cols.tolist(), distances):
                    if hypothesiser.include_all or distance < missed_distance:
                        hypotheses.setdefault(row, []).append(
                            (members[col], distance, batch, brow))

        assigned: list = ["missed"] * n
        detected = sorted(hypotheses)
        if detected:
            n_dets = len(detections)
            costs = np.full((len(detected), n_dets + len(detected)), np.inf)
            for i, k in enumerate(detected):
                costs[i, n_dets + i] = missed_distance
                for column, distance, _, _ in hypotheses[k]:
                    costs[i, column] = distance
            try:
                _, col4row = _stock_neighbour.linear_sum_assignment(costs, False)
            except ValueError:
                raise RuntimeError("Assignment was not feasible") from None
            for i, k in enumerate(detected):
                column = int(col4row[i])
                if column == n_dets + i:
                    continue
                chosen = next((h for h in hypotheses[k] if h[0] == column), None)
                if chosen is not None:
                    column, distance, batch, brow = chosen
                    chosen = (column, distance, _measurement_prediction(batch, brow, timestamp))
                assigned[k] = chosen
        self._pred = (pred_means, pred_covars)
        return assigned

    def _advance(self, assigned, detections, timestamp, associated, sure_tracks):
        """Appends this scan's state to every holding row (a pending prediction, or the stock
        update of its assigned detection), releases the rows with enough points and deletes
        those past the deleter's limit, as the drop-in does track by track."""
        hypothesiser = self.data_associator.hypothesiser
        pred_means, pred_covars = self._pred
        del self._pred
        records = self._records
        block = Block(pred_means, pred_covars, timestamp, self._serials)
        index = self._next_block
        self._blocks[index] = block
        self._next_block += 1
        means, covars = pred_means.copy(), pred_covars.copy()
        new_time = np.fromiter((t != timestamp for t in self._last_times), dtype=bool,
                               count=len(records))
        appended = np.ones(len(records), dtype=bool)
        updated = np.zeros(len(records), dtype=bool)
        updater = self.updater
        batched = (type(updater) in KALMAN_UPDATERS and not updater.use_joseph_cov
                   and not updater.force_positive_definite_covariance)
        pending = []  # float hypotheses, updated together below
        transition = hypothesiser.predictor.transition_model
        for k, choice in enumerate(assigned):
            if choice is None:  # no hypothesis from the assignment: stock appends nothing
                block.skipped.add(records[k].serial)
                means[k], covars[k] = self._means[k], self._covars[k]
                appended[k] = False
            elif choice != "missed":
                column, distance, mp = choice
                record = records[k]
                prediction = PRIOR_PREDICTION(
                    state_vector=pred_means[k].view(StateVector),
                    covar=pred_covars[k].view(CovarianceMatrix), timestamp=timestamp,
                    transition_model=transition, prior=None,
                    **{name: getattr(record.track.state, name)
                       for name in _copied_properties(type(record.track.state))})
                detection = detections[column]
                hypothesis = _DISTANCE_HYPOTHESIS(prediction=prediction, measurement=detection,
                                                  distance=distance, measurement_prediction=mp)
                associated.add(id(detection))
                updated[k] = True
                wrap = angle_wrap(detection.state_vector, mp.state_vector) if batched else None
                if wrap is not None:
                    pending.append((k, hypothesis, wrap))
                    continue
                state = updater.update(hypothesis)
                block.updates[record.serial] = state
                means[k] = np.asarray(state.state_vector, dtype=np.float64)
                covars[k] = np.asarray(state.covar, dtype=np.float64)
        if pending:
            hypotheses = [h for _, h, _ in pending]
            new_means, new_covars = kalman_updates(
                [h.prediction for h in hypotheses], [h.measurement_prediction for h in hypotheses],
                [h.measurement for h in hypotheses], [w for _, _, w in pending],
                bool(updater.force_symmetric_covariance))
            for (k, hypothesis, _), mean, covar in zip(pending, new_means, new_covars):
                block.updates[records[k].serial] = UPDATE_STATE(
                    state_vector=mean.view(StateVector), covar=covar.view(CovarianceMatrix),
                    hypothesis=hypothesis, timestamp=hypothesis.measurement.timestamp)
                means[k], covars[k] = mean, covar
        # points: updates (and predictions unless updates_only); the deleter's counts:
        # distinct times (reset by a detection, one more for each new time), detection time
        self._counted += updated if self.updates_only else appended
        self._deletion.advance(updated, appended & new_time, timestamp)
        self._last_times = [timestamp if a else t for a, t in zip(appended.tolist(),
                                                                  self._last_times)]
        keep = np.ones(len(records), dtype=bool)
        for k in np.flatnonzero(appended & (self._counted >= self.min_points)).tolist():
            record = records[k]
            self._materialise(record)
            sure_tracks.add(record.track)
            self.holding_tracks.discard(record.track)
            keep[k] = False
        for k in self._deletion.expired(self.deleter, np.flatnonzero(keep).tolist(),
                                        self._last_times):
            self.holding_tracks.discard(records[k].track)
            keep[k] = False
        if not keep.all():
            kept = keep.tolist()
            self._records = [r for r, k in zip(records, kept) if k]
            self._serials = [r for r, k in zip(self._serials, kept) if k]
            self._last_times = [t for t, k in zip(self._last_times, kept) if k]
            means, covars = means[keep], covars[keep]
            self._counted = self._counted[keep]
            self._deletion.take(keep)
        self._means, self._covars = means, covars
        if index % 32 == 0:
            self._prune_blocks()


__all__ = ["ArrayMultiMeasurementInitiator"]
