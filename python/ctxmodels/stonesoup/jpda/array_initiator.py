r"""The M-of-N initiator with its holding tracks' scan in the Rust core.

:class:`ArrayMultiMeasurementInitiator` has the Properties of ctxmodels'
:class:`~ctxmodels.stonesoup.MultiMeasurementInitiator` (the readable reference) and
releases the same tracks. In a JPDA run most detections are clutter and each starts a
holding track that coasts, unassociated, until the deleter drops it 30 scans later: a
hundred holding tracks, most never released. Here the holding tracks' last states are
stacked arrays, and one core call per scan (:func:`ctxmodels._core.initiator_scan`, see
``rust/jpda/initiation.rs``) predicts them, gates every track × detection pair on the
Mahalanobis distance, solves the GNN 2-D assignment (the shortest augmenting path method
SciPy's ``linear_sum_assignment`` uses, ties broken the same way), runs the Kalman update of
the assigned pairs and advances the M-of-N counts. Stone Soup states are built only for the
tracks released (:mod:`~ctxmodels.stonesoup.jpda._initiator_history`).

**"The same tracks"** (tested in ``tests/stonesoup/jpda/test_array_initiator.py`` and, through
the JPDA, ``tests/stonesoup/jpda/test_array_tracker.py``): scan by scan the same tracks are released;
each has the same states in the same order, of the same types, at the same times, its
updates on the same detection objects (so the same gate and assignment decisions), and the
numbers (state vectors, covariances, distances, predictions, measurement predictions) agree
to rounding. Not bit for bit: the core inverts S its own way where Stone Soup calls
``pinv`` (distance) and ``inv`` (gain), and sums its products in its own order. Measured:
1e-12 relative at worst over 120 s of scenario 1 (603 tracks released; its radar's
finite-difference Jacobian, whose step follows the last bit of a state, included), ~1e-15
with linear models. A decision could differ only where two costs tie to within that
rounding; exact ties go as SciPy breaks them (tested). New tracks come from a second core
call (:func:`ctxmodels._core.initiator_births`, see
:mod:`~ctxmodels.stonesoup.jpda._initiator_births`): their means are the stock initiator's
bit for bit, so new tracks are ordered (:func:`~ctxmodels.stonesoup.in_track_order`, by
their first state's bytes) as the reference orders them; their covariances are the stock
ones to rounding (to ~1e-5 relative with the finite-difference Jacobian).

:attr:`holding_tracks` is the live set, as stock; reading it builds the holding tracks not
built yet and adds the states of the scans since their last materialisation, so the tracks
read are complete (the JPDA never reads it: a clutter detection's holding track is never
built).

Supported (anything else runs ctxmodels' :class:`MultiMeasurementInitiator` code, after
the pending states are added): a :class:`~stonesoup.dataassociator.neighbour.GNNWith2DAssignment`
or :class:`~ctxmodels.stonesoup.FastGNNWith2DAssignment` over a plain
:class:`~stonesoup.hypothesiser.distance.DistanceHypothesiser` (Mahalanobis or squared
Mahalanobis measure without mapping, no ``predict_with_measurements``), a Kalman / extended
Kalman predictor with a linear Gaussian transition model and no control input, Kalman /
extended Kalman updaters without covariance options (``force_symmetric_covariance`` is
applied), measurement models the core takes (``LinearGaussian``, 2-D
``CartesianToBearingRange`` or :class:`~ctxmodels.stonesoup.AnalyticCartesianToBearingRange`,
all of a scan's models measuring the same number of values), a stock or ctxmodels
``UpdateTimeStepsDeleter``, Stone Soup's ``UpdateTimeDeleter`` with a ``timedelta``
window, or an :class:`~ctxmodels.stonesoup.ExpectedMissesDeleter` without a hypothesiser
given each scan's context (``delete_last_pred`` off; the verdicts from per-row counts, see
:mod:`~ctxmodels.stonesoup.jpda._initiator_deletion`), Gaussian float64 states, and detections
stamped with the scan time.
"""
from __future__ import annotations

from itertools import compress
from operator import attrgetter

import numpy as np
from stonesoup.dataassociator.neighbour import GNNWith2DAssignment
from stonesoup.hypothesiser.distance import DistanceHypothesiser
from stonesoup.measures import Mahalanobis, SquaredMahalanobis
from stonesoup.models.base import LinearModel, ReversibleModel
from stonesoup.types.state import GaussianState

from ...foreign import as_array_context
from .deleter import ExpectedMissesDeleter
from .._batch import KALMAN_UPDATERS, supports_predictor
from ..gnn import FastGNNWith2DAssignment, _copied_properties
from . import _initiator_deletion as initiator_deletion
from ._initiator_births import Births
from ._initiator_history import Block, Holding, Update, materialise
from ._initiator_scan import Rows, ScanCore
from .tracker import MultiMeasurementInitiator
from ..ordering import OrderedDetections, in_stable_order, in_track_order, ordered_subset


class ArrayMultiMeasurementInitiator(MultiMeasurementInitiator):
    """ctxmodels' :class:`MultiMeasurementInitiator` with the holding tracks' scan in the
    Rust core (see the module docstring): the same released tracks, their numbers to
    rounding. :attr:`array_calls` and :attr:`component_calls` count the calls each path
    ran."""

    def __init__(self, *args, **kwargs):
        self._records: list[Holding] = []
        self._holding: set = set()
        super().__init__(*args, **kwargs)
        self._serials: list = []  # the records' serials (ascending)
        self._next_serial = 0
        self._means = None  # (H, D): each holding track's last state, aligned with _records
        self._covars = None  # (H, D, D)
        self._deletion = initiator_deletion.HoldingCounts()  # what the deleter reads, per row
        self._counted = np.empty(0, dtype=np.int64)  # points towards release
        self._last_times: list = []
        self._blocks: dict[int, Block] = {}
        self._next_block = 0
        self._births = Births()
        self._scan_core = ScanCore()
        self._context = None  # the scan's, while an ExpectedMissesDeleter weighs its misses
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
        for updater in (hypothesiser.updater, self.updater):
            if type(updater) not in KALMAN_UPDATERS or updater.use_joseph_cov \
                    or updater.force_positive_definite_covariance:
                return False
        if type(hypothesiser.updater) is not type(self.updater):
            return False
        return initiator_deletion.supported(self.deleter)

    # --- the holding tracks ---------------------------------------------------------------------
    @property
    def holding_tracks(self) -> set:
        """The live set of holding tracks, as stock; reading it builds the tracks not built
        yet and adds their pending states, so the tracks read are complete."""
        for k, record in enumerate(self._records):
            self._materialise(record)
            self._record_misses(k, record)
        return self._holding

    @holding_tracks.setter
    def holding_tracks(self, tracks: set) -> None:
        self._holding = tracks

    # --- pending states ------------------------------------------------------------------------
    def _materialise(self, record: Holding) -> None:
        """Build the record's track if it is not built yet and append the states the
        component path would have appended since its last materialisation (see
        :func:`~ctxmodels.stonesoup.jpda._initiator_history.materialise`)."""
        if record.track is None:
            record.track = self._births.track(*record.birth)
            record.birth = None
            self._holding.add(record.track)
        materialise(record, self._blocks, self._next_block,
                    self.data_associator.hypothesiser.predictor.transition_model)

    def _record_misses(self, row: int, record: Holding) -> None:
        """Hands an ExpectedMissesDeleter the P_D of the misses since the row's last
        detection, for the states the track now holds (its component path reads them)."""
        misses = self._deletion.misses[row]
        if misses and type(self.deleter) is ExpectedMissesDeleter:
            track, n = record.track, len(record.track)
            for i, pd in enumerate(misses):
                self.deleter.record_prob_detect(track, n - len(misses) + i, pd)

    def _materialise_all(self) -> None:
        for k, record in enumerate(self._records):
            self._materialise(record)
            self._record_misses(k, record)
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
        live = self._holding
        records = self._records
        tracks = list(map(attrgetter("track"), records))  # (most rows are unbuilt: None)
        if len(tracks) - tracks.count(None) == len(live) \
                and (not live or all(t in live for t in tracks if t is not None)):
            return True
        keep = [k for k, r in enumerate(records) if r.track is None or r.track in live]
        present = {id(records[k].track) for k in keep if records[k].track is not None}
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
            [np.empty((0, ndim)) if empty else self._means]
            + [state.state_vector.reshape(1, ndim) for state, _, _ in read])
        self._covars = np.concatenate(
            [np.empty((0, ndim, ndim)) if empty else self._covars]
            + [state.covar[np.newaxis] for state, _, _ in read])
        self._counted = np.concatenate([self._counted, [p for _, p, _ in read]]).astype(np.int64)
        misses = ([self.deleter.prob_detect_since_detection(t) for t in added]
                  if type(self.deleter) is ExpectedMissesDeleter else None)
        self._deletion.add([n for _, _, n in read], misses)
        self._last_times = self._last_times + [state.timestamp for state, _, _ in read]
        return True

    # --- a scan ---------------------------------------------------------------------------------
    def initiate(self, detections, timestamp, detector_context=None, **kwargs):
        """The holding tracks confirmed by this scan's ``detections``; the scan's
        ``detector_context`` weighs the misses of an ExpectedMissesDeleter (a scan without
        one runs the component path, whose deleter then warns that it counts)."""
        weighs = type(self.deleter) is ExpectedMissesDeleter
        self._context = detector_context if weighs else None
        if type(detections) is not OrderedDetections:  # (already in order: not sorted again)
            detections = in_stable_order(detections)
        if self.skip_non_reversible:
            detections = [d for d in detections
                          if isinstance(d.measurement_model, (ReversibleModel, LinearModel))]
        hypothesiser = getattr(self.data_associator, "hypothesiser", None)
        ndim = getattr(getattr(getattr(hypothesiser, "predictor", None), "transition_model", None),
                       "ndim_state", None)
        scan = None
        if not kwargs and self._supported() and all(d.timestamp == timestamp for d in detections) \
                and (detector_context is not None or not weighs) and self._sync(ndim):
            scan = self._scan_core(self, self._rows(), detections, timestamp) \
                if self._records else ()
        if scan is None:
            self._materialise_all()
            self.component_calls += 1
            return super().initiate(detections, timestamp, detector_context=detector_context,
                                    **kwargs)
        self.array_calls += 1

        sure_tracks = set()
        associated = set()
        if scan:
            self._advance(scan, detections, timestamp, associated, sure_tracks)
        free = detections if not associated else ordered_subset(  # (grouped, converted once)
            detections, [id(d) not in associated for d in detections])
        new, births = self._births.arrays(self.initiator, free, timestamp)
        if new or not self._add_births(births, ndim, timestamp):
            new.update(self._births.track(*birth) for birth in births)
            self._holding |= new
            if not self._add(in_track_order(new), ndim):
                self._materialise_all()  # a new track the arrays cannot hold: re-read next scan
        return sure_tracks

    def _add_births(self, births, ndim, timestamp) -> bool:
        """Appends rows for ``births`` (see :meth:`Births.arrays`), their tracks not built,
        in the order :func:`in_track_order` gives their tracks (time, then the state
        vector's bytes); False (nothing added) if a birth cannot be held as arrays."""
        if not births:
            return True
        for det, mean, covar, prior in births:
            if not (isinstance(mean, np.ndarray) and mean.dtype == np.float64
                    and mean.shape == (ndim, 1) and isinstance(covar, np.ndarray)
                    and covar.dtype == np.float64 and covar.shape == (ndim, ndim)
                    and det.timestamp == timestamp and type(prior) is GaussianState):
                return False
        # (sorted() is stable: equal keys are equal states, whose order changes no number)
        births = sorted(births, key=lambda b: np.ascontiguousarray(b[1]).tobytes())
        n = len(births)
        first = self._next_serial
        self._next_serial += n
        self._records = self._records + [Holding(None, self._next_block, first + k, birth)
                                         for k, birth in enumerate(births)]
        self._serials = self._serials + list(range(first, first + n))
        means = np.ascontiguousarray(np.array([b[1] for b in births])[:, :, 0])
        covars = np.array([b[2] for b in births])
        self._means = means if self._means is None else np.concatenate([self._means, means])
        self._covars = covars if self._covars is None else np.concatenate([self._covars, covars])
        self._counted = np.concatenate([self._counted, np.ones(n, dtype=np.int64)])
        # one state, an update (counted with updates_only too), detection-backed
        self._deletion.add([(1, timestamp)] * n)
        self._last_times = self._last_times + [timestamp] * n
        return True

    def _missed_prob_detect(self, out, missed) -> np.ndarray:
        """P_D of the rows ``missed`` at their predictions, in the scan's context (as the
        deleter evaluates it at the prediction the component path appends)."""
        if not len(missed):
            return np.empty(0)
        context = as_array_context(self._context, "prob_detection_array",
                                   "clutter_spatial_density_detections")
        model = getattr(context, "sensor_model", None)
        gaussian = model is None or model.pd_evaluation != "mean"
        means = np.ascontiguousarray(out["pred_means"][missed])
        covars = np.ascontiguousarray(out["pred_covars"][missed]) if gaussian else None
        values = np.asarray(context.prob_detection_array(means, covars), dtype=np.float64)
        bad = np.flatnonzero(~((values >= 0.0) & (values <= 1.0)))
        if len(bad):
            raise ValueError(f"detector_context: P_D must lie in [0, 1], got "
                             f"{values[bad[0]]} for a holding track")
        return values

    def _rows(self) -> Rows:
        return Rows(self._means, self._covars, self._counted, self._deletion.since,
                    self._last_times, self._row_prior)

    def _row_prior(self, row: int):
        """Row ``row``'s last state as a Stone Soup state."""
        record = self._records[row]
        if record.track is not None:
            return record.track.state
        return GaussianState(self._means[row][:, np.newaxis], self._covars[row],
                             timestamp=self._last_times[row])

    def _advance(self, out, detections, timestamp, associated, sure_tracks):
        """Records this scan's block (predictions, updates), releases the rows with enough
        points and deletes those past the deleter's limit, as the drop-in does track by
        track."""
        records = self._records
        pred_means = out["pred_means"]
        block = Block(pred_means[:, :, np.newaxis], out["pred_covars"], timestamp, self._serials)
        self._blocks[self._next_block] = block
        self._next_block += 1
        assigned = out["assigned"]
        rows = (assigned >= 0).nonzero()[0]
        columns = assigned[rows].tolist()
        bearing, model_index = out["bearing"], out["model_index"]
        post_means = out["means"][:, :, np.newaxis]
        for u, (k, j) in enumerate(zip(rows.tolist(), columns)):
            detection = detections[j]
            associated.add(id(detection))
            block.updates[records[k].serial] = Update(
                post_means[k], out["covars"][k], detection, out["distances"][u],
                out["meas_means"][u], out["meas_covars"][u], out["cross_covars"][u],
                bearing[model_index[j]])
        self._counted = out["points"]
        missed = prob_detect = None
        if self._context is not None:
            missed = np.flatnonzero(assigned < 0)
            prob_detect = self._missed_prob_detect(out, missed)
        self._deletion.advance(out["since"], rows, timestamp, missed, prob_detect)
        self._last_times = [timestamp] * len(records)
        released = out["released"]
        for k in released.nonzero()[0].tolist():
            record = records[k]
            self._materialise(record)
            sure_tracks.add(record.track)
            self._holding.discard(record.track)
        # the deleter's verdicts from the rows' counts (a released row is not held either way)
        keep = ~(released | self._deletion.expired(self.deleter, self._last_times))
        self._means, self._covars = out["means"], out["covars"]
        if not keep.all():
            for k in (~keep & ~released).nonzero()[0].tolist():
                if records[k].track is not None:
                    self._holding.discard(records[k].track)
            kept = keep.tolist()
            self._records = list(compress(records, kept))
            self._serials = list(compress(self._serials, kept))
            self._last_times = [timestamp] * len(self._records)
            self._means, self._covars = self._means[keep], self._covars[keep]
            self._counted = self._counted[keep]
            self._deletion.take(keep)
        if self._next_block % 32 == 1:
            self._prune_blocks()


__all__ = ["ArrayMultiMeasurementInitiator"]
