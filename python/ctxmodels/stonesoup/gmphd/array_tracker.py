r"""The GM-PHD tracker with each scan computed in the Rust core.

:class:`ArrayPointProcessTracker` has the Properties of
:class:`~ctxmodels.stonesoup.PointProcessMultiTargetTracker` (the stock ones plus ``birth``,
``surveillance_region``, ``max_position_std``, ``position_mapping``) and returns the same
tracks. It keeps the mixture as arrays between scans and runs a scan — Kalman prediction,
gate, PHD update, region and uncertainty bounds, prune/merge/truncate — in a few calls into
:class:`ctxmodels._core.GaussianMixtureArrays`; P_D per component and λ per detection come
from the scan's :class:`~ctxmodels.DetectorContext` in one array call each. Stone Soup
objects are built only for what it hands out: track states, and the mixture when
:attr:`~ArrayPointProcessTracker.gaussian_mixture` is read.

**Supported configurations** (checked every scan; anything else runs the component path of
:class:`~ctxmodels.stonesoup.PointProcessMultiTargetTracker` for that scan, with the same
results, counted in ``component_scans`` — ``array_scans`` counts the others — and the first
such scan raises a :class:`~ctxmodels.stonesoup.ComponentPathWarning` naming why):

* ``hypothesiser``: Stone Soup's ``GaussianMixtureHypothesiser(order_by_detection=True)``
  over a ``DistanceHypothesiser`` with a ``Mahalanobis`` or ``SquaredMahalanobis`` measure
  (no mapping) and a Kalman or extended Kalman predictor whose transition model is linear
  Gaussian (no control input);
* ``updater``: a PHD updater (ctxmodels' context-aware one or the stock one) over a Kalman or
  extended Kalman updater (``force_symmetric_covariance`` supported; no Joseph form, no
  forced positive definiteness);
* ``reducer``: Stone Soup's ``GaussianMixtureReducer``; with ``kdtree_max_distance`` the
  candidates in the gate are visited in increasing weight (stock: in a set's address
  order, which changes from process to process);
* a scan whose detections share one measurement model *value* — ``LinearGaussian``, or
  (extended Kalman) ``CartesianToBearingRange`` (Stone Soup's finite-difference Jacobian,
  reproduced) or :class:`~ctxmodels.stonesoup.AnalyticCartesianToBearingRange` — and the
  scan's timestamp. Models are compared by type and Properties, bit for bit
  (:func:`~ctxmodels.model_key.measurement_model_key`), so a model object per detection
  (readers, Stone Soup's sensors measured target by target) is one model; detections from
  two sensor positions in one scan are two.

**Agreement with the component path.** The same formulae in the same order, so results
agree to rounding. Rounding differs (the core does not call BLAS/LAPACK): with linear models
and the closed-form bearing–range Jacobian the tracks agree with the stock pipeline to
rtol 1e-9 and better; with Stone Soup's finite-difference Jacobian, whose round-off follows
the last bit of the state (~1e-8 relative), to about that.

Track ids are the stock ones in kind (a fresh ``uuid4`` string per new tag); tags inside the
core are integers, named only when a track or the mixture needs them.

One module, though long: the tracker's state between scans (the mixture as arrays, its tag
names and times, the births waiting to enter) and the scan that reads and writes it are one
object's; what a scan may run on the core is in ``_plan``, births in ``birth``, regions in
``region``.
"""
from __future__ import annotations

import datetime
import uuid

import numpy as np
from stonesoup.models.measurement.linear import LinearGaussian
from stonesoup.types.array import CovarianceMatrix, StateVector
from stonesoup.types.mixture import GaussianMixture
from stonesoup.types.state import TaggedWeightedGaussianState
from stonesoup.types.track import Track

from ... import _core
from ..._upstream import check_measurement_model
from ...context import DetectorContext, detection_positions
from ...model_key import scan_model_groups
from ...foreign import as_array_context
from ._plan import _Plan
from .._batch import ObjectFactory, plain_track_lists
from ..ordering import in_stable_order
from ..scan_context import declares_context
from ..paths import PathCounts
from .tracker import PointProcessMultiTargetTracker
from .region import CircularRegion, scan_region

_BIRTH_NAME = TaggedWeightedGaussianState.BIRTH
_BIRTH = 0  # the core's birth tag
_MICROSECOND = datetime.timedelta(microseconds=1)
_STATE = ObjectFactory(TaggedWeightedGaussianState, dict(
    state_vector=StateVector([0.0]), covar=CovarianceMatrix([[1.0]]), timestamp=None,
    weight=0.5, tag="probe")).maker("state_vector", "covar", "weight", "tag", "timestamp")


class ArrayPointProcessTracker(PathCounts, PointProcessMultiTargetTracker):
    r"""GM-PHD tracker computing each scan in the Rust core (see the module docstring).

    Same Properties, inputs and tracks as
    :class:`~ctxmodels.stonesoup.PointProcessMultiTargetTracker`; configurations and scans
    the core does not cover run that component path scan by scan. :attr:`array_scans` and
    :attr:`component_scans` count the scans each path ran; the first component-path scan
    raises a :class:`~ctxmodels.stonesoup.ComponentPathWarning` naming why (once per
    tracker).
    """

    def __init__(self, *args, **kwargs):
        self._count_paths()
        self._arrays = None          # _core.GaussianMixtureArrays, once the dimension is known
        self._mixture_object = None  # the mixture as Stone Soup objects, when authoritative
        super().__init__(*args, **kwargs)
        self._epoch = None
        self._tag_names: dict[int, str] = {}
        self._tag_ids: dict[str, int] = {}
        self._track_of_tag: dict[int, Track] = {}
        self._pending = None  # births waiting for a scan that can see them (core arrays)
        self._transitions: dict = {}
        self._scan_positions: dict = {}

    # --- the mixture, as arrays or as objects ----------------------------------------------
    @property
    def gaussian_mixture(self) -> GaussianMixture:
        """The mixture as Stone Soup components (built on demand; assigning one replaces
        the mixture)."""
        if self._mixture_object is None:
            self._mixture_object = GaussianMixture(self._components())
        return self._mixture_object

    @gaussian_mixture.setter
    def gaussian_mixture(self, value):
        self._mixture_object = value

    @property
    def array_path(self) -> bool:
        """Whether every scan so far ran in the core (``component_scans == 0``) and the
        current configuration is one the core runs; before the first scan, only the latter.
        A scan the core cannot take (detections with different measurement models, …) makes
        it False for good."""
        return self.component_scans == 0 and _Plan.refusal(self) is None

    def _tag_name(self, tag: int) -> str:
        name = self._tag_names.get(tag)
        if name is None:
            name = _BIRTH_NAME if tag == _BIRTH else str(uuid.uuid4())
            self._tag_names[tag] = name
            self._tag_ids[name] = tag
        return name

    def _tag_id(self, name, arrays=None) -> int:
        """The core's tag for a tag string, reserved in ``arrays`` (default the mixture's)
        if new."""
        if name == _BIRTH_NAME:
            return _BIRTH
        tag = self._tag_ids.get(name)
        if tag is None:
            if arrays is None:
                self._ensure_arrays(self._ndim())
                arrays = self._arrays
            tag = arrays.reserve_tags(1)
            self._tag_ids[name] = tag
            self._tag_names[tag] = name
        return tag

    def _time(self, timestamp: datetime.datetime) -> int:
        if self._epoch is None:
            self._epoch = timestamp
        return (timestamp - self._epoch) // _MICROSECOND

    def _timestamp(self, time: int) -> datetime.datetime:
        return self._epoch + datetime.timedelta(microseconds=int(time))

    def _components(self) -> list:
        return self._as_components(self._arrays)

    def _as_components(self, arrays) -> list:
        """Stone Soup components of core arrays (the mixture, or the waiting births)."""
        if arrays is None or len(arrays) == 0:
            return []
        means, covars = arrays.means(), arrays.covars()
        return [TaggedWeightedGaussianState(
                    state_vector=means[i].reshape(-1, 1), covar=covars[i], weight=float(w),
                    tag=self._tag_name(int(tag)), timestamp=self._timestamp(t))
                for i, (w, tag, t) in enumerate(zip(arrays.weights(), arrays.tags().tolist(),
                                                    arrays.times().tolist()))]

    def _ensure_arrays(self, ndim: int) -> None:
        if self._arrays is None:
            self._arrays = _core.GaussianMixtureArrays(ndim)

    def _as_arrays(self, components, next_tag: int = 1):
        """Core arrays of Stone Soup components (tags named as the tracker names them);
        ``next_tag`` carries the tag sequence over."""
        components = list(components)
        ndim = (len(components[0].state_vector) if components
                else self._arrays.ndim if self._arrays is not None else self._ndim())
        arrays = _core.GaussianMixtureArrays(ndim)
        arrays.reserve_tags(next_tag - 1)
        if not components:
            return arrays
        tags = [self._tag_id(getattr(c, "tag", None) or str(uuid.uuid4()), arrays)
                for c in components]
        arrays.extend(np.array([np.asarray(c.state_vector, dtype=np.float64).ravel()
                                for c in components]),
                      np.array([np.asarray(c.covar, dtype=np.float64) for c in components]),
                      np.array([float(c.weight) for c in components]), tags,
                      [self._time(c.timestamp) for c in components])
        return arrays

    def _load(self, components) -> None:
        """Replace the arrays by Stone Soup components (a mixture set by the user, or left by
        a component-path scan)."""
        next_tag = self._arrays.next_tag if self._arrays is not None else 1
        self._arrays = self._as_arrays(components, next_tag)

    # --- births -----------------------------------------------------------------------------
    def _queue_births(self, detections, time: int, context) -> None:
        """The scan's detections' births wait in ``_pending`` for a scan that can see them."""
        birth = self.birth
        positions = self._positions(detections, birth.position_mapping)
        means = birth.means(detections, positions)
        weights = np.ascontiguousarray(birth.weights(detections, positions, context), dtype=np.float64)
        n, ndim = means.shape
        covar = np.ascontiguousarray(birth.birth_covar, dtype=np.float64)
        if self._pending is None:
            self._pending = _core.GaussianMixtureArrays(ndim)
        # Only this scan's births meet this scan's region: the queued ones met their own
        # scan's (a region that moves may have left them behind since, as on the component path).
        region = self._region
        if region is None or type(region) is CircularRegion:  # (in one call into the core)
            circle = None if region is None else (
                tuple(map(int, self.position_mapping)), region.centre, region.radius)
            self._pending.extend_births(means, covar, weights, time, circle)
            return
        covars = np.empty((n,) + covar.shape)
        covars[...] = covar  # (one per birth)
        fresh = _core.GaussianMixtureArrays(ndim)
        fresh.extend(means, covars, weights, [_BIRTH] * n,
                     [time] * n)
        self._within_region(fresh)
        self._pending.take_from(fresh, [True] * len(fresh))

    def _enter_due_births(self, arrays, time: int, context) -> None:
        """Moves the queued births that enter this scan into the mixture (see
        ``MeasurementDrivenBirth.due``): those no older than ``max_delay``, and with a
        context those it gives P_D > 0."""
        pending = self._pending
        if pending is None or not len(pending):
            return
        birth = self.birth
        if birth.max_delay is not None:
            stale = time - pending.times() > birth.max_delay // _MICROSECOND
            if stale.any():
                pending.retain((~stale).tolist())
        if context is None:
            entering = [True] * len(pending)
        else:
            pd = _core_prob_detection(pending, context)
            if pd is None:  # (a foreign context, P_D over the Gaussian, or an error to name)
                entering = birth.visible(pending.means(), pending.covars(), context).tolist()
            else:
                entering = (pd > 0).tolist()  # (MeasurementDrivenBirth.visible's rule)
        arrays.take_from(pending, entering)

    def _within_region(self, arrays) -> None:
        """Drops the components outside the surveillance region (a CircularRegion in the
        core, any other region through its ``contains`` or call)."""
        region = self._region
        if region is None or not len(arrays):
            return
        mapping = tuple(map(int, self.position_mapping))
        if type(region) is CircularRegion:
            arrays.retain_inside_circle(mapping, region.centre, region.radius)
        else:
            arrays.retain(self._inside_mask(arrays.means()[:, list(mapping)]).tolist())

    # --- a scan -----------------------------------------------------------------------------
    def _scan(self, time, detections) -> tuple[datetime.datetime, set[Track]]:
        """One checked scan (the parent's ``__next__`` checks it and calls this)."""
        plan = _Plan.read(self)
        refusal = plan if isinstance(plan, str) else None
        if refusal is None:
            self._region = scan_region(self.surveillance_region, time)  # (the component
            scan = self._scan_inputs(plan, time, detections)           # path sets it itself)
            if isinstance(scan, str):
                refusal, scan = scan, None
        if refusal is not None:
            self._ran_component_scan(time, refusal)
            return self._component_scan(time, detections)
        self._ran_array_scan()
        if self._mixture_object is not None:
            self._load(self._mixture_object.components)
            self._mixture_object = None
        self._array_scan(plan, time, *scan)
        return time, self.tracks

    def _scan_inputs(self, plan: _Plan, time, detections):
        """The scan's ordered detections, context, measurement vectors and core model; or
        why the core cannot run this scan (a string). The detections are grouped by their
        measurement models' values (:func:`~ctxmodels.model_key.measurement_model_key`), so
        equal models in different objects (one per detection) are one model; the first
        detection's is the one used."""
        context = getattr(detections, "detector_context", None)
        ordered = in_stable_order(detections)
        if context is not None and not declares_context(self.updater.update):
            context = None
        if context is not None:
            context = as_array_context(context, "prob_detection_array",
                                       "clutter_spatial_density_detections")
        ndim = self._ndim()
        if ndim is None:
            return "the state dimension is not known (no mixture, birth_component or birth)"
        if not ordered:
            return ordered, context, np.empty((0, 1)), None
        groups = scan_model_groups(ordered)
        if len(groups) != 1:
            return f"detections with {len(groups)} distinct measurement models"
        if any(d.timestamp != time for d in ordered):
            return "detections with timestamps other than the scan's"
        (key, (detections_model, _)), = groups.items()
        model = check_measurement_model(plan.gate_updater, detections_model)
        if check_measurement_model(plan.measurement_updater, model) is not model:
            return "the hypothesiser's and the updater's measurement models differ"
        scan_model = plan.scan_model(model, ndim, key if model is detections_model else None)
        if scan_model is None:
            return (f"a {type(model).__name__} measurement model (the core takes "
                    "LinearGaussian and, with extended Kalman updaters, 2-D bearing-range)")
        if ordered.vectors is None or ordered.vectors.shape[1] != scan_model.ndim_meas:
            return "measurement vectors not of the model's ndim_meas rows"
        if type(model) is LinearGaussian and any(d.state_vector.dtype == object for d in ordered):
            # typed (angle) elements in a linear model: the component path
            return "typed (angle) measurement elements in a linear model"
        return ordered, context, ordered.vectors, scan_model

    def _ndim(self):
        if self._arrays is not None:
            return self._arrays.ndim
        if self._mixture_object is not None and len(self._mixture_object):
            return len(self._mixture_object.components[0].state_vector)
        if self.birth_component is not None:
            return len(self.birth_component.state_vector)
        if self.birth is not None:
            return self.birth.ndim_state
        return None

    def _array_scan(self, plan: _Plan, time, detections, context, z, scan_model) -> None:
        now = self._time(time)
        self._ensure_arrays(self._ndim())
        arrays = self._arrays
        if self.birth_component is not None:
            self.birth_component.timestamp = time
            b = self.birth_component
            arrays.extend(np.asarray(b.state_vector, dtype=np.float64).reshape(1, -1),
                          np.asarray(b.covar, dtype=np.float64)[np.newaxis],
                          np.array([float(b.weight)]), [self._tag_id(b.tag)], [now])
        if self.birth is not None:
            self._enter_due_births(arrays, now, context)

        self._predict(plan, arrays, now)
        n = len(arrays)
        if context is not None:
            prob_detection = _core_prob_detection(arrays, context)
            if prob_detection is None:
                # A foreign context (no sensor model) is asked about each Gaussian prediction.
                model = getattr(context, "sensor_model", None)
                gaussian = model is None or model.pd_evaluation != "mean"
                covars = arrays.covars() if gaussian else None
                prob_detection = np.asarray(
                    context.prob_detection_array(arrays.means(), covars), dtype=np.float64)
            model = getattr(context, "sensor_model", None)
            positions = None
            if detections and getattr(getattr(model, "clutter", None), "uses_position", False):
                positions = self._positions(detections, model.position_mapping)
            clutter = (np.asarray(context.clutter_spatial_density_detections(
                detections, positions=positions), dtype=np.float64)
                if detections else np.empty(0))
        else:
            prob_detection = np.full(n, plan.prob_detection)
            clutter = np.full(len(detections), plan.clutter)
        if scan_model is None:  # no detections: only the missed-detection terms
            scan_model = _NO_DETECTIONS[arrays.ndim]
            z = np.empty((0, scan_model.ndim_meas))
        clutter_probability = arrays.update(
            scan_model, np.ascontiguousarray(z), prob_detection, clutter,
            prob_survival=plan.prob_survival, missed_distance=plan.missed_distance,
            squared=plan.squared, include_all=plan.include_all, normalise=plan.normalise,
            skip_undetectable=context is not None, time=now,
            force_symmetric=plan.force_symmetric)
        self._clutter_probabilities = (time, detections, clutter_probability)
        self._within_region(arrays)
        if self.max_position_std is not None:
            x, y = self.position_mapping
            arrays.retain_position_std((int(x), int(y)), float(self.max_position_std))
        arrays.reduce(**plan.reduce)
        self._update_tracks_from_arrays(time)
        if self.birth is not None and detections:
            self._queue_births(detections, now, context)
        self._scan_positions = {}

    def _positions(self, detections, mapping) -> np.ndarray:
        """The scan's detection positions for one position mapping, computed once (λ and
        the births both need them)."""
        key = tuple(int(i) for i in mapping)
        positions = self._scan_positions.get(key)
        if positions is None:
            positions = self._scan_positions[key] = detection_positions(detections, key)
        return positions

    def _predict(self, plan: _Plan, arrays, now: int) -> None:
        if len(arrays) == 0:
            return
        times = arrays.distinct_times()
        matrices = [self._transition(plan.predictor, now - t) for t in times]
        arrays.predict(times, now, np.array([f for f, _ in matrices]),
                       np.array([q for _, q in matrices]))

    def _transition(self, predictor, step: int):
        """F(Δt) and Q(Δt) (plus the control model's noise, as the Kalman predictor adds
        it) for a time step in µs, cached per predictor and step: the models are immutable
        and a scan has a handful of distinct steps."""
        key = (id(predictor), id(predictor.transition_model), id(predictor.control_model), step)
        cache = self._transitions
        found = cache.get(key)
        if found is not None and found[0] is predictor:
            return found[1]
        interval = datetime.timedelta(microseconds=step)
        model, control = predictor.transition_model, predictor.control_model
        ctrl = control.matrix(control_input=None, prior=None, time_interval=interval)
        noise = (np.asarray(model.covar(time_interval=interval), dtype=np.float64)
                 + ctrl @ control.control_noise @ ctrl.T)
        matrices = (np.asarray(model.matrix(time_interval=interval), dtype=np.float64),
                    np.asarray(noise, dtype=np.float64))
        if len(cache) >= 256:
            cache.clear()
        cache[key] = (predictor, matrices)
        return matrices

    def _update_tracks_from_arrays(self, time) -> None:
        """The stock ``update_tracks`` and ``end_tracks`` on the arrays: a component whose tag
        has a track extends it; one above the extraction threshold starts one; tracks whose
        tag left the mixture end."""
        tracks = self._track_of_tag
        # (a Probability threshold compares as a float)
        tags, weights, means, covars, gone = self._arrays.track_states(
            list(tracks), float(self.extraction_threshold))
        # One block per scan; each state's vector and covariance are views of their own row
        # of it (the core's arrays are not shared, so nothing else keeps it alive).
        vectors, covariances = means.view(StateVector), covars.view(CovarianceMatrix)
        row, make, names = np.ndarray.__getitem__, _STATE, self._tag_names
        for j, tag in enumerate(tags):
            state = make(row(vectors, j), row(covariances, j), weights[j],
                         names.get(tag) or self._tag_name(tag), time)
            track = tracks.get(tag)
            if track is None:
                tracks[tag] = self.target_tracks[state.tag] = Track([state], id=state.tag)
            else:
                lists = plain_track_lists(track)
                (track.states if lists is None else lists[0]).append(state)
        for tag in gone:
            del self.target_tracks[names[tag]]
            del tracks[tag]
        if len(names) > len(tracks):
            # names given to untracked components (the mixture was read) live as long as
            # the component, so its tag stays the same string
            present = set(self._arrays.tags().tolist())
            for tag in [t for t in names if t not in present and t not in tracks]:
                del self._tag_ids[names.pop(tag)]

    def _component_scan(self, time, detections):
        """One scan through the component path (the parent tracker), arrays converted."""
        self._pending_births = self._as_components(self._pending)
        tracker_time, tracks = _ComponentScan(self, time, detections).run()
        self._pending = (self._as_arrays(self._pending_births) if self._pending_births
                         else None)
        # the parent keeps tracks by tag string; re-key them by the core's tags
        self._track_of_tag = {self._tag_id(name): track
                              for name, track in self.target_tracks.items()}
        return tracker_time, tracks


def _core_prob_detection(arrays, context):
    """P_D at each component's mean of ``arrays``, computed in the core from a ctxmodels
    context's model at the scan's pose (no means copied out and back): the bits of
    ``context.prob_detection_array(arrays.means())``. None for a context or sensor model
    the core route does not cover, or means it cannot evaluate (the general route then
    names why)."""
    if type(context) is not DetectorContext:
        return None
    at_pose = context._mean_detection()
    return None if at_pose is None else arrays.prob_detection(at_pose)


class _ComponentScan:
    """Runs the parent's scan (the component path) on an already-fetched, checked scan."""

    def __init__(self, tracker, time, detections):
        self.tracker, self.scan = tracker, (time, detections)

    def run(self):
        tracker = self.tracker
        mixture = tracker.gaussian_mixture  # objects become authoritative
        tracker.gaussian_mixture = mixture
        return PointProcessMultiTargetTracker._scan(tracker, *self.scan)


class _NoDetections(dict):
    """A linear model of the right state dimension for scans without detections (only the
    missed-detection terms are computed; the model is never evaluated)."""

    def __missing__(self, ndim):
        model = _core.MeasurementModel.linear(np.zeros((1, ndim)), np.ones((1, 1)))
        self[ndim] = model
        return model


_NO_DETECTIONS = _NoDetections()

__all__ = ["ArrayPointProcessTracker"]
