r"""Whole-scan JPDA: the stock (J)PDA mixture tracker's numbers from one Rust call per scan.

:class:`ArrayJPDATracker` has the Properties of
:class:`~ctxmodels.stonesoup.MultiTargetMixtureTracker` (``initiator``, ``deleter``,
``detector``, ``data_associator``, ``updater``) and, scan for scan, gives the tracks that
tracker gives. The component path asks the hypothesiser for each track in turn (a
prediction, a measurement prediction, a likelihood and a hypothesis object per detection),
runs EHM over Python objects in ``Probability`` (log-space) arithmetic, updates every gated
pair through the updater and reduces each track's mixture with ``gm_reduce_single``. Here
the tracks' last states are stacked and one call into the Rust core
(:func:`ctxmodels._core.jpda_scan`) does the whole scan: prediction, measurement
prediction, the PDA weights, the χ² gate, the exact joint association marginals (EHM2 over
clusters of tracks sharing detections), every Kalman update and the mixture reduction; one
Stone Soup state per track is built from the result.

Supported (anything else runs the component path of
:class:`~ctxmodels.stonesoup.MultiTargetMixtureTracker`, scan by scan, counted in
``component_scans`` — ``array_scans`` counts the others — and the first such scan raises a
:class:`~ctxmodels.stonesoup.ComponentPathWarning` naming why):

* ``data_associator``: :class:`~stonesoup.dataassociator.probability.JPDAwithEHM2`,
  ``JPDAwithEHM`` or ``JPDA`` (all give the same exact marginals) over a stock or
  ctxmodels :class:`~stonesoup.hypothesiser.probability.PDAHypothesiser` with a
  ``clutter_spatial_density`` (or a ctxmodels context on the scan);
* a Kalman / extended Kalman predictor with a linear Gaussian transition model, and Kalman /
  extended Kalman updaters without covariance options;
* scans whose detections share one time (the scan's) and one measurement model *value*:
  ``LinearGaussian``, ``CartesianToBearingRange`` (2-D, extended Kalman updaters; Stone
  Soup's finite-difference Jacobian reproduced operation for operation) or
  :class:`~ctxmodels.stonesoup.AnalyticCartesianToBearingRange` (closed form). Models are
  compared by type and Properties, bit for bit
  (:func:`~ctxmodels.model_key.measurement_model_key`): a model object per detection is one
  model;
* scans with and without a ctxmodels detector context (P_D per track from the context's
  array form, λ per detection, as the ctxmodels hypothesiser computes them);
* tracks whose last state is a :class:`~stonesoup.types.state.GaussianState` (or a
  subclass whose Properties a prediction copies) with a float64 or integer state vector
  and covariance of the transition model's size, and a timestamp. Integer states (a track
  started at ``[[0], [1], [0], [1]]``) are converted to float64, as NumPy converts them in
  the stock predictor's product with the float64 transition matrix: the same numbers.
  Other element types (object arrays, float32, long double) run the component path.

Numbers: the same mathematics in other floating-point operations (f64 arithmetic where
Stone Soup uses ``Probability`` log-space arithmetic, Cholesky inverses, another summation
order), so states agree to ~1e-13 relative with linear and closed-form models (measured:
3e-15 on the JPDA tutorial set-up, 7e-14 on 10 s of the experiment's scenario 1). Stone
Soup's finite-difference Jacobian steps by max(1e8 ulp(x), 1e-8): at a negative coordinate
of a few hundred metres the step is 1e-8 while one ulp of the coordinate is ~1e-13, so a
last-bit difference in a predicted state moves the Jacobian by ~1e-5 relative, and the next
scans carry that on: with that model the agreement is measured (1.2e-5 on 10 s of scenario
1), not bit-level (see ``tests/stonesoup/jpda/test_array_tracker.py``).

Initiation: any initiator works; :class:`~ctxmodels.stonesoup.ArrayMultiMeasurementInitiator`
(the M-of-N initiator with its holding tracks as arrays) is the one that keeps a JPDA run
fast, and is handed each scan's free detections still in stable order.

States: an update when some detection's marginal exceeds the missed detection's (a
:class:`~stonesoup.types.update.GaussianStateUpdate` whose ``hypothesis`` is the JPDA
:class:`~stonesoup.types.multihypothesis.MultipleHypothesis`, built only when something
reads it), else a :class:`~stonesoup.types.prediction.GaussianStatePrediction`; track
metadata follow the stock rule (metadata of the hypotheses' detections, most likely last).

Deletion (:mod:`~ctxmodels.stonesoup.jpda._array_deletion`): with a ctxmodels or stock
:class:`~stonesoup.deleter.time.UpdateTimeStepsDeleter`, a ctxmodels
:class:`~ctxmodels.stonesoup.ExpectedMissesDeleter` or a stock
:class:`~stonesoup.deleter.time.UpdateTimeDeleter` (``delete_last_pred`` off), each track's
misses since its last detection-backed state (or that state's time) are counted as states
are appended instead of walking the track, and the verdicts are the deleter's own functions
of those counts (:mod:`~ctxmodels.stonesoup.jpda.deleter`). A
:class:`~stonesoup.deleter.error.CovarianceBasedDeleter` reads only the last state's
covariance: its verdicts (:func:`~ctxmodels.stonesoup.jpda.deleter.covariance_verdict`) are
taken on the scan's stacked posterior covariances; a
:class:`~ctxmodels.stonesoup.DuplicateTrackDeleter` reads the scan's stacked posterior means
and covariances. A :class:`~stonesoup.deleter.multi.CompositeDeleter` or ctxmodels'
:class:`~ctxmodels.stonesoup.CompositeDeleter` (``delete_last_pred`` off) whose members (a
list or tuple) are any of these is evaluated by the composite's rule
(:func:`~ctxmodels.stonesoup.jpda.composite_deleter.composite_verdicts`): delete when all
say so (``intersect``) or when any does. Any other deleter is called.

Determinism: detections in :func:`~ctxmodels.stonesoup.in_stable_order`, tracks in creation
order; the core runs on one thread in index order.

Why one long module: the scan's steps (the configuration check, the priors read off the
tracks, the core call, one Stone Soup state per track and its metadata) share the scan's
arrays and run in one pass per scan; split across modules they would pass those arrays
through several layers on the hot path.
"""
from __future__ import annotations

from operator import itemgetter

import numpy as np
from stonesoup.dataassociator.probability import JPDA, JPDAwithEHM, JPDAwithEHM2
from stonesoup.hypothesiser.probability import PDAHypothesiser as _StockPDAHypothesiser
from stonesoup.types.array import CovarianceMatrix, Matrix, StateVector
from stonesoup.types.detection import Detection, MissedDetection
from stonesoup.types.hypothesis import SingleHypothesis, SingleProbabilityHypothesis
from stonesoup.types.multihypothesis import MultipleHypothesis
from stonesoup.types.numeric import Probability
from stonesoup.types.prediction import GaussianMeasurementPrediction, GaussianStatePrediction
from stonesoup.types.state import GaussianState
from stonesoup.types.update import GaussianStateUpdate

from ... import _core
from ...errors import NotPositiveDefiniteError
from ..._upstream import live_tracks, plain_property, property_slot
from ...context import DetectorContext
from ...model_key import measurement_model_key, scan_model_groups
from ._array_deletion import ArrayDeletion
from .array_initiator import ArrayMultiMeasurementInitiator
from ._initiator_history import PRIOR_PREDICTION as _PRIOR_PREDICTION
from .._batch import KALMAN_UPDATERS, ObjectFactory, plain_track_lists, supports_predictor
from ..gnn import _copied_properties
from .hypothesiser import PDAHypothesiser, gate_threshold, is_detection_backed
from ..models import ControlTerms, core_measurement_model
from .tracker import MultiTargetMixtureTracker
from ..paths import PathCounts
from ..ordering import in_track_order, ordered_subset
from ..scan_context import context_kwargs, scan_context

_ASSOCIATORS = (JPDAwithEHM2, JPDAwithEHM, JPDA)
#: Prior state vector and covariance types the array path takes: float64 and the integer
#: types (a track started at ``[[0], [1], [0], [1]]``). The stock predictor multiplies an
#: integer array by the float64 transition matrix, and NumPy converts it to float64 first:
#: converted here once, the prediction is the same number.
_PRIOR_DTYPES = frozenset(np.dtype(kind) for kind in (
    np.float64, np.int8, np.int16, np.int32, np.int64, np.uint8, np.uint16, np.uint32,
    np.uint64))
_HYPOTHESISERS = (_StockPDAHypothesiser, PDAHypothesiser)


# --- Stone Soup objects, built as their constructors build them ---------------------------
_SINGLE_HYPOTHESES = property_slot("single_hypotheses")
_NORMALISE = property_slot("normalise")
_TOTAL_WEIGHT = property_slot("total_weight")
_UPDATE = ObjectFactory(GaussianStateUpdate, dict(
    state_vector=StateVector([0.0]), covar=CovarianceMatrix([[1.0]]),
    hypothesis=SingleHypothesis(None, Detection(StateVector([0.0]))), timestamp=None))
_PREDICTION = ObjectFactory(GaussianStatePrediction, dict(
    state_vector=StateVector([0.0]), covar=CovarianceMatrix([[1.0]]), timestamp=None))
_NEW_UPDATE = _UPDATE.maker("state_vector", "covar", "hypothesis", "timestamp")
_NEW_PREDICTION = _PREDICTION.maker("state_vector", "covar", "timestamp")
_MEASUREMENT_PREDICTION = ObjectFactory(GaussianMeasurementPrediction, dict(
    state_vector=StateVector([0.0]), covar=CovarianceMatrix([[1.0]]), timestamp=None,
    cross_covar=Matrix([[1.0]])))


class _ScanHypotheses(MultipleHypothesis):
    """The JPDA :class:`MultipleHypothesis` of one track and scan, built from the scan's
    arrays the first time ``single_hypotheses`` is read: the missed detection and each gated
    detection with its marginal probability, the track's prediction and measurement
    prediction, as the stock associator returns them. Pickles as a plain
    :class:`MultipleHypothesis`."""

    @property
    def single_hypotheses(self):
        hypotheses = self.__dict__.get(_SINGLE_HYPOTHESES)
        if hypotheses is None:
            hypotheses = self.__dict__[_SINGLE_HYPOTHESES] = self._build()
            del self.__dict__["_pending"]
        return hypotheses

    @single_hypotheses.setter
    def single_hypotheses(self, value):
        self.__dict__[_SINGLE_HYPOTHESES] = value
        self.__dict__.pop("_pending", None)

    def __bool__(self):  # (pending: the missed detection and the gated ones, never empty)
        return "_pending" in self.__dict__ or len(self) > 0

    def __len__(self):  # bool() of an update (deleters ask it) without building anything
        pending = self.__dict__.get("_pending")
        if pending is not None:
            scan, t, _ = pending
            return 1 + int(np.count_nonzero(scan.gated[t]))
        return len(self.single_hypotheses)

    def _build(self):
        scan, t, prior = self.__dict__["_pending"]
        prediction = _PRIOR_PREDICTION(
            state_vector=scan.pred_means[t].reshape(-1, 1).view(StateVector),
            covar=scan.pred_covars[t].view(CovarianceMatrix),
            timestamp=scan.time, transition_model=scan.transition_model, prior=prior,
            **{name: getattr(prior, name) for name in (_copied_properties(type(prior)) or ())})
        vector = scan.meas_means[t].reshape(-1, 1).copy()
        if scan.bearing_row is not None:
            vector = vector.astype(object)
            vector[scan.bearing_row, 0] = scan.bearing_type(float(vector[scan.bearing_row, 0]))
        measurement_prediction = _MEASUREMENT_PREDICTION(
            state_vector=vector.view(StateVector), covar=scan.meas_covars[t].view(CovarianceMatrix),
            timestamp=scan.time, cross_covar=scan.cross_covars[t].view(Matrix))
        marginals = scan.marginals[t]
        hypotheses = [SingleProbabilityHypothesis(
            prediction, MissedDetection(timestamp=scan.time), probability=Probability(marginals[0]))]
        for j in np.flatnonzero(scan.gated[t]).tolist():
            hypotheses.append(SingleProbabilityHypothesis(
                prediction, scan.detections[j], probability=Probability(marginals[1 + j]),
                measurement_prediction=measurement_prediction))
        return hypotheses

    def __reduce__(self):
        state = {key: value for key, value in self.__dict__.items() if key != "_pending"}
        state[_SINGLE_HYPOTHESES] = self.single_hypotheses
        return (_plain_multiple_hypothesis, (state,))


def _plain_multiple_hypothesis(state):
    hypothesis = object.__new__(MultipleHypothesis)
    hypothesis.__dict__.update(state)
    return hypothesis


class _Scan:
    """What one scan's lazily built hypotheses need from the scan."""

    __slots__ = ("time", "detections", "transition_model", "pred_means",
                 "pred_covars", "meas_means", "meas_covars", "cross_covars", "gated",
                 "marginals", "bearing_row", "bearing_type")


def _lazy_hypothesis(scan: _Scan, t: int, prior) -> _ScanHypotheses:
    hypothesis = object.__new__(_ScanHypotheses)
    hypothesis.__dict__.update({_NORMALISE: True, _TOTAL_WEIGHT: 1, "_pending": (scan, t, prior)})
    return hypothesis


# --- measurement models -----------------------------------------------------------------------
def _updater_supported(updater) -> bool:
    return (type(updater) in KALMAN_UPDATERS
            and not updater.force_positive_definite_covariance and not updater.use_joseph_cov)


# --- tracks -------------------------------------------------------------------------------
_GAUSSIAN_PRIOR_TYPES: dict = {}
_PRIOR_FIELDS = ("state_vector", "covar", "timestamp")
#: A plain prior's fields, read from its instance dictionary (``KeyError`` when one is unset).
_PRIOR_SLOTS = itemgetter(*(property_slot(name) for name in _PRIOR_FIELDS))


def _gaussian_prior_type(kind: type):
    """Whether the array path can take a last state of type ``kind`` as a prior (a
    :class:`GaussianState` whose Properties a prediction copies are known), per type: False,
    or how its fields are read — "plain" when ``state_vector``, ``covar`` and ``timestamp``
    are plain Stone Soup Properties (no getter, no attribute hook: the value is the
    instance's ``_property_<name>`` entry), else "attributes"."""
    known = _GAUSSIAN_PRIOR_TYPES.get(kind)
    if known is None:
        if not (issubclass(kind, GaussianState) and _copied_properties(kind) is not None):
            known = False
        else:
            plain = kind.__getattribute__ is object.__getattribute__ \
                and not hasattr(kind, "__getattr__")
            for name in _PRIOR_FIELDS:
                plain = plain and plain_property(kind, name)
            known = "plain" if plain else "attributes"
        _GAUSSIAN_PRIOR_TYPES[kind] = known
    return known


def _prior_fields(prior):
    """``(state_vector, covar, timestamp)`` of a track's last state (each None when
    missing), or None when its type is not one :func:`_gaussian_prior_type` takes. Read from
    the instance dictionary for plain Properties (the value their getter returns)."""
    kind = _GAUSSIAN_PRIOR_TYPES.get(type(prior))
    if kind is None:
        kind = _gaussian_prior_type(type(prior))
    if not kind:
        return None
    if kind == "plain":
        try:
            return _PRIOR_SLOTS(prior.__dict__)
        except KeyError:
            pass
    return (getattr(prior, "state_vector", None), getattr(prior, "covar", None),
            getattr(prior, "timestamp", None))


def _is_backed(state) -> bool:
    """:func:`is_detection_backed`, answered at once for the array path's predictions."""
    return type(state) is not GaussianStatePrediction and is_detection_backed(state)


class ArrayJPDATracker(PathCounts, ArrayDeletion, MultiTargetMixtureTracker):
    """:class:`~ctxmodels.stonesoup.MultiTargetMixtureTracker` computing each supported scan
    with one call into the Rust core (see the module docstring); the same Properties,
    tracks and states. :attr:`array_scans` and :attr:`component_scans` count the scans each
    path ran; the first component-path scan raises a
    :class:`~ctxmodels.stonesoup.ComponentPathWarning` naming why (once per tracker)."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._init_deletion()
        self._models: dict = {}
        self._control_terms = ControlTerms()
        self._count_paths()

    @property
    def array_path(self) -> bool:
        """Whether every scan so far ran in the core (``component_scans == 0``) and the
        current associator, hypothesiser, predictor and updaters are ones the core runs;
        before the first scan, only the latter. A scan the core cannot take (detections
        with different measurement models, …) makes it False for good."""
        return self.component_scans == 0 and self._hypothesiser() is not None

    # --- configuration --------------------------------------------------------------------
    def _hypothesiser(self):
        """The PDA hypothesiser when the associator/hypothesiser/predictor/updater
        configuration is one the core reproduces, else None."""
        hypothesiser = self._hypothesiser_or_refusal()
        return None if isinstance(hypothesiser, str) else hypothesiser

    def _hypothesiser_or_refusal(self):
        """The PDA hypothesiser, or why the configuration is not one the core runs."""
        associator = self.data_associator
        if type(associator) not in _ASSOCIATORS:
            return f"the data associator is a {type(associator).__name__}, not a JPDA"
        hypothesiser = associator.hypothesiser
        if type(hypothesiser) not in _HYPOTHESISERS:
            return f"the hypothesiser is a {type(hypothesiser).__name__}, not a PDAHypothesiser"
        if not supports_predictor(hypothesiser.predictor):
            return "the predictor is not a Kalman one with a linear Gaussian transition model"
        if not (_updater_supported(hypothesiser.updater) and _updater_supported(self.updater)):
            return ("the updaters are not plain (extended) Kalman updaters without Joseph "
                    "form or forced positive definiteness")
        return hypothesiser

    def _model_for(self, hypothesiser, detections):
        """The scan's one measurement model (detections' own, or the updaters'), its core
        model and bearing row; or why there is none (a string). Detections are grouped by
        their models' values (:func:`~ctxmodels.model_key.measurement_model_key`), so equal
        models in different objects are one model (the first detection's)."""
        groups = scan_model_groups(detections)
        if len(groups) != 1:
            return f"detections with {len(groups)} distinct measurement models"
        (key, (model, _)), = groups.items()
        if model is None:
            model = hypothesiser.updater.measurement_model
            if model is None or self.updater.measurement_model is not model:
                return ("detections without a measurement model, and the updaters do not "
                        "share one")
            key = measurement_model_key(model)
        if type(hypothesiser.updater) is not type(self.updater):
            return "the hypothesiser's and the tracker's updaters are of different types"
        # cached by value: equal models (a moving radar's recurring ones) share an entry
        cached = self._models.get(key)
        if cached is None:
            core, bearing_row = core_measurement_model(model, type(self.updater))
            cached = self._models[key] = (model, core, bearing_row)
            if len(self._models) > 64:  # per-scan models (a moving radar): keep a few
                self._models = {k: value for k, value in self._models.items()
                                if k == key or (type(k) is tuple and k[0] == "empty")}
        if cached[1] is None:
            return (f"a {type(model).__name__} measurement model (the core takes "
                    "LinearGaussian and, with extended Kalman updaters, 2-D bearing-range)")
        return cached

    # --- the scan (``__next__``: the parent's, which checks the scan first) --------------
    def _scan(self, time, detections):
        result = self._array_scan(time, detections)
        if isinstance(result, str):
            self._ran_component_scan(time, result)
            self._counters.clear()  # states appended by the component path: re-read
            return super()._scan(time, detections)
        self._ran_array_scan()
        return result

    def _array_scan(self, time, detections):
        """The scan in the core: ``(time, tracks)``, or why it cannot run there (a string;
        nothing has changed then)."""
        hypothesiser = self._hypothesiser_or_refusal()
        if isinstance(hypothesiser, str):
            return hypothesiser
        tracks = self.tracks_in_order
        if any(d.timestamp != time for d in detections):
            return "detections with timestamps other than the scan's"
        context = scan_context(detections, {}) if type(hypothesiser) is PDAHypothesiser else None
        if context is not None and not (
                isinstance(context, DetectorContext)
                and type(context).prob_detection_states is DetectorContext.prob_detection_states):
            return "a detector context that is not a ctxmodels DetectorContext"
        if detections:
            entry = self._model_for(hypothesiser, detections)
            if isinstance(entry, str):
                return entry
            _, core_model, bearing_row = entry
        else:  # no detection: only missed-detection hypotheses, no model is read
            core_model, bearing_row = self._empty_model(hypothesiser), None
        if context is None and hypothesiser.clutter_spatial_density is None:
            # the stock validation-region clutter estimate
            return "a PDA hypothesiser without clutter_spatial_density and no context"

        predictor = hypothesiser.predictor
        ndim = predictor.transition_model.ndim_state
        track_lists, priors, vectors, covars, stamps = [], [], [], [], []
        vector_shape, covar_shape = (ndim, 1), (ndim, ndim)
        for track in tracks:
            lists = plain_track_lists(track)
            prior = track.state if lists is None else lists[0][-1]
            fields = _prior_fields(prior)
            if fields is not None:
                vector, covar, stamp = fields
            if not (fields is not None
                    and isinstance(vector, np.ndarray) and vector.dtype in _PRIOR_DTYPES
                    and vector.shape == vector_shape and isinstance(covar, np.ndarray)
                    and covar.dtype in _PRIOR_DTYPES and covar.shape == covar_shape
                    and stamp is not None):
                return (f"a track whose last state (a {type(prior).__name__}) is not a "
                        "float64 or integer Gaussian state of the transition model's size "
                        "with a timestamp")
            track_lists.append(lists)
            priors.append(prior)
            vectors.append(vector)
            covars.append(covar)
            stamps.append(stamp)

        taken_mask = latest = None
        counted_now = frozenset()
        if tracks:
            scan = self._run_core(time, detections, tracks, priors, (vectors, covars, stamps),
                                  hypothesiser, context, core_model, bearing_row)
            if isinstance(scan, str):
                return scan
            scan_result, out, prob_detect = scan
            self._append_states(time, tracks, track_lists, priors, scan_result, out,
                                prob_detect, hypothesiser)
            taken_mask = out["taken"]
            latest = (tracks, out["means"], out["covars"], time)
            counted_now = set(tracks) if None not in track_lists else {
                track for track, lists in zip(tracks, track_lists) if lists is not None}
        # deletion, then the initiator on the detections no track took (as the stock loop),
        # each handed the scan's context as the component path hands it
        live = live_tracks(self)
        live -= self._delete(live, detections, latest, counted_now)
        free = None if taken_mask is None or not taken_mask.any() else ~taken_mask
        if isinstance(self.initiator, ArrayMultiMeasurementInitiator):
            # still in stable order: not sorted again; models grouped, vectors converted once
            unassociated = ordered_subset(detections, free)
        else:  # what the stock loop hands over
            unassociated = set(detections if free is None else
                               [d for d, kept in zip(detections, free.tolist()) if kept])
        new = self.initiator.initiate(unassociated, time,
                                      **context_kwargs(detections, self.initiator.initiate))
        if new:
            live |= new
            self._order.update(dict.fromkeys(in_track_order(new)))
        return time, self.tracks

    def _empty_model(self, hypothesiser):
        ndim = hypothesiser.predictor.transition_model.ndim_state
        cached = self._models.get(("empty", ndim))
        if cached is None:
            cached = self._models[("empty", ndim)] = _core.MeasurementModel.linear(
                np.eye(1, ndim), np.eye(1))
        return cached

    def _run_core(self, time, detections, tracks, priors, prior_arrays, hypothesiser, context,
                  core_model, bearing_row):
        """The scan through the core; ``prior_arrays``: the priors' state vectors,
        covariances and timestamps."""
        predictor = hypothesiser.predictor
        transition = predictor.transition_model
        control = predictor.control_model
        vectors, covars, stamps = prior_arrays
        means = np.array(vectors, dtype=np.float64)[:, :, 0]
        covars = np.array(covars, dtype=np.float64)
        intervals: dict = {}
        if stamps.count(stamps[0]) == len(stamps):  # (the usual scan: one previous time)
            intervals[time - stamps[0]] = 0
            index = [0] * len(stamps)
        else:
            index = []
            for stamp in stamps:
                interval = time - stamp
                k = intervals.get(interval)
                if k is None:
                    k = intervals[interval] = len(intervals)
                index.append(k)
        matrices, noises = [], []
        for interval in intervals:
            prior = priors[index.index(intervals[interval])]
            matrices.append(np.asarray(transition.matrix(time_interval=interval), dtype=np.float64))
            if self._control_terms.adds_input(control, prior, interval):
                return "a control input (the core predicts without one)"
            noises.append(np.asarray(transition.covar(time_interval=interval), dtype=np.float64))
        matrices = np.ascontiguousarray(
            matrices[0][np.newaxis] if len(matrices) == 1 else np.stack(matrices))
        noises = np.ascontiguousarray(
            noises[0][np.newaxis] if len(noises) == 1 else np.stack(noises))
        means, covars = np.ascontiguousarray(means), np.ascontiguousarray(covars)
        # λ per detection and P_D per track, as the (ctxmodels) hypothesiser takes them
        if not detections:
            clutter = np.empty(0)
            z = np.empty((0, core_model.ndim_meas))
        else:
            if context is None:
                clutter = _filled(len(detections), float(hypothesiser.clutter_spatial_density))
            else:
                clutter = np.asarray(hypothesiser.scan_clutter(context, context, detections),
                                     dtype=np.float64)
            rows = getattr(detections, "vectors", None)  # (an OrderedDetections' float rows)
            if not (isinstance(rows, np.ndarray) and rows.shape[0] == len(detections)):
                rows = np.array([d.state_vector for d in detections], dtype=np.float64)[:, :, 0]
            z = np.ascontiguousarray(rows)
        predict = dict(transition_index=index, transition_matrices=matrices,
                       transition_covars=noises)
        if context is None:
            prob_detect = _filled(len(tracks), float(hypothesiser.prob_detect))
        else:
            # a ctxmodels context reading P_D at the mean: its model at the pose, read in
            # the core at each predicted mean; any other: its array route on the prediction
            prob_detect = _core_detection(context)
            if prob_detect is None:
                means, covars = _core.jpda_predict(means, covars, **predict)
                predict = {}
                prob_detect = _context_prob_detection(context, means, covars, time)
        threshold = gate_threshold(hypothesiser.prob_gate, core_model.ndim_meas)
        try:
            out = _core.jpda_scan(core_model, means, covars, z, prob_detect, clutter,
                                  float(hypothesiser.prob_gate), threshold,
                                  bool(hypothesiser.include_all), **predict,
                                  force_symmetric=bool(self.updater.force_symmetric_covariance))
        except NotPositiveDefiniteError:
            # the stock code takes the nearest positive-definite matrix: the component path
            return ("an innovation covariance that is not positive definite (the stock "
                    "code takes the nearest positive-definite matrix)")
        pred_means, pred_covars = (out["pred_means"], out["pred_covars"]) if predict else (
            means, covars)
        scan = _Scan()
        scan.time = time
        scan.detections = detections
        scan.transition_model = transition
        scan.pred_means, scan.pred_covars = pred_means, pred_covars  # (viewed when read)
        scan.meas_means = out["meas_means"]
        scan.meas_covars = out["meas_covars"]
        scan.cross_covars = out["cross_covars"]
        scan.gated = out["gated"]
        scan.marginals = out["marginals"]
        scan.bearing_row = bearing_row
        if bearing_row is not None:
            from stonesoup.types.angle import Bearing
            scan.bearing_type = Bearing
        return scan, out, out["prob_detect"]

    def _append_states(self, time, tracks, track_lists, priors, scan, out, prob_detect,
                       hypothesiser):
        """Appends each track's state of the scan; ``track_lists``: each track's
        :func:`plain_track_lists`, read before the scan."""
        means = out["means"][:, :, np.newaxis]
        covars = out["covars"]
        updates = out["is_update"].tolist()
        records = type(hypothesiser) is PDAHypothesiser
        pd_list = prob_detect.tolist()
        plan = self._deletion_plan()
        counting = () if plan is None else self._counting(plan, hypothesiser)
        gated = out["gated"]
        marginals = out["marginals"]
        detections = scan.detections
        new_update, new_prediction = _NEW_UPDATE, _NEW_PREDICTION
        lengths = []  # each track's length before its state of this scan
        for t, track in enumerate(tracks):
            lists = track_lists[t]
            if records:
                if lists is None:
                    hypothesiser._record(track, time, pd_list[t])
                else:
                    states = lists[0]
                    hypothesiser._record_at(track, len(states),
                                            bool(states) and _is_backed(states[-1]), time,
                                            pd_list[t])
            mean = means[t].view(StateVector)
            covar = covars[t].view(CovarianceMatrix)
            if updates[t]:
                hypothesis = _lazy_hypothesis(scan, t, priors[t])
                state = new_update(mean, covar, hypothesis, time)
                columns = gated[t].nonzero()[0].tolist()
                metadata = self._update_metadata(track, lists, detections, columns,
                                                 marginals[t])
            else:
                state = new_prediction(mean, covar, time)
                metadata = None
            if lists is None:
                length = len(track)
                track.append(state)  # another track type: its own bookkeeping
            else:  # what Track.append does
                states, metadatas = lists
                if metadata is None:
                    metadata = (metadatas[-1] if metadatas else track.init_metadata).copy()
                metadatas.append(metadata)
                states.append(state)
                length = len(states) - 1
            lengths.append(length)
        if counting:  # an update here always has detection hypotheses: detection-backed
            self._count(tracks, lengths, updates, time, pd_list, counting)

    @staticmethod
    def _update_metadata(track, lists, detections, columns, marginals):
        """The metadata Stone Soup's ``Track.append`` derives from a JPDA update: the
        previous metadata (``lists``: the track's :func:`plain_track_lists`), updated with
        the metadata of each detection hypothesis in ascending probability (a stable sort:
        ties keep detection order), the most likely last."""
        if lists is None:
            metadata = track.metadata.copy()
        else:
            metadatas = lists[1]
            metadata = (metadatas[-1] if metadatas else track.init_metadata).copy()
        if len(columns) > 1:
            weights = marginals.tolist()
            columns = sorted(columns, key=lambda j: weights[1 + j])
        for j in columns:
            extra = detections[j].metadata
            if extra is not None:
                metadata.update(extra)
        return metadata



def _filled(n: int, value: float) -> np.ndarray:
    """``np.full(n, value)`` of a float, without its Python-level steps."""
    array = np.empty(n)
    array.fill(value)
    return array


def _core_detection(context):
    """A ctxmodels context's P_D model at the scan's pose (``DetectionAtPose``), which the
    core reads at each predicted mean: the bits of ``context.prob_detection_array`` of the
    predicted means. None for a sensor model reading P_D over the Gaussian, or a context
    whose array route is not ctxmodels' own (a subclass's, or one set on the object)."""
    route = getattr(context.prob_detection_array, "__func__", None)
    if route is not DetectorContext.prob_detection_array:
        return None
    return context._mean_detection()


def _context_prob_detection(context, pred_means, pred_covars, time):
    """P_D per track from the context's array route, checked to lie in [0, 1]."""
    covar_arg = None if context.sensor_model.pd_evaluation == "mean" else pred_covars
    prob_detect = np.ascontiguousarray(context.prob_detection_array(pred_means, covar_arg),
                                       dtype=np.float64)
    bad = np.flatnonzero(~((prob_detect >= 0.0) & (prob_detect <= 1.0)))
    if bad.size:
        raise ValueError(f"detector_context: P_D must lie in [0, 1], got "
                         f"{prob_detect[bad[0]]} for a track at {time}")
    return prob_detect


__all__ = ["ArrayJPDATracker"]
