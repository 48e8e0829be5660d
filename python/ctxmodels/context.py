"""Per-scan detector contexts, and detection sets that carry them.

Interface compatible with the proposal in dstl/Stone-Soup#1291: a detector yields
``(time, DetectionSet)``; the set carries the :class:`DetectorContext` of its scan (also
when empty), and trackers ask the context for :math:`P_D(x; S)` per predicted state and
:math:`\\lambda(z; S)` per detection.
"""
from __future__ import annotations

import datetime
from collections.abc import Iterable, Sequence
from typing import Any

import numpy as np
from stonesoup.base import Base, Property
from stonesoup.models.measurement.linear import LinearGaussian
from stonesoup.models.measurement.nonlinear import CartesianToBearingRange
from stonesoup.types.numeric import Probability

from .model_key import scan_model_groups
from .pose import Pose
from .scan_calls import ScanCalls
from .sensor import SensorModel

# The upstream interface (dstl/Stone-Soup#1291) where this Stone Soup has it: an abstract
# class with ``prob_detection`` and ``clutter_spatial_density`` (not a Stone Soup ``Base``),
# and a ``set`` of detections carrying ``detector_context``. Ours are real subclasses of
# both, so ``isinstance`` checks in upstream code accept them; without them (Stone Soup
# 1.9.1) they are a ``Base`` component and a ``set``.
try:
    from stonesoup.types.detector_context import DetectorContext as _UpstreamContext  # type: ignore
except ImportError:  # stonesoup 1.9.x
    _UPSTREAM_CONTEXT: tuple = ()
else:
    _UPSTREAM_CONTEXT = () if issubclass(Base, _UpstreamContext) else (_UpstreamContext,)
try:
    from stonesoup.types.detection import DetectionSet as _UpstreamSet  # type: ignore
except ImportError:  # stonesoup 1.9.x
    _UpstreamSet = set


class DetectionSet(_UpstreamSet):
    """A scan's detections (a ``set``) with the :class:`DetectorContext` of that scan.

    An empty scan is an empty ``DetectionSet`` that still carries its context: that is what
    tells a tracker the sensor looked and saw nothing there.
    """

    def __init__(self, detections: Iterable = (), detector_context: "DetectorContext | None" = None):
        super().__init__(detections)
        self.detector_context = detector_context

    def copy(self) -> "DetectionSet":
        return DetectionSet(self, self.detector_context)

    def __repr__(self):
        return f"DetectionSet({set(self)!r}, detector_context={self.detector_context!r})"

    def __reduce__(self):
        return (type(self), (list(self), self.detector_context))


def _state_of(hypothesis_or_state: Any):
    """The predicted state of a hypothesis, or the state itself."""
    return getattr(hypothesis_or_state, "prediction", hypothesis_or_state)


def _position_indices(model, position_mapping, i) -> list[int]:
    """The x/y indices of ``model``'s state space: ``position_mapping``, which the model must
    map (measure) both of; anything else would read some other state entry as a position."""
    mapping = [int(m) for m in getattr(model, "mapping", ())]
    wanted = [int(m) for m in position_mapping]
    if all(m in mapping for m in wanted):
        return wanted
    raise ValueError(f"detections: detection {i}'s measurement model {type(model).__name__} "
                     f"maps state indices {tuple(mapping)}, which do not include the sensor's "
                     f"position_mapping {tuple(wanted)}; give the SensorModel the x/y indices "
                     "of the state its detections' models measure")


def detection_positions(detections: Sequence, position_mapping=(0, 2)) -> np.ndarray:
    """World (x, y) of each detection, (M, 2), from each detection's *own* measurement
    model: through its ``inverse_function`` (bearing–range and other non-linear models) or
    the pseudo-inverse of a linear model's matrix, read at the ``position_mapping`` indices
    of that model's state space. A model that does not map both of those indices (a 6-D
    model with ``mapping=(0, 3)`` against ``(0, 2)``, a 1-D model), or a detection whose
    vector does not have the model's ``ndim_meas`` rows, raises ValueError: the state space
    of the detections must be the one the sensor's ``position_mapping`` describes. Linear
    detections sharing a model are converted in one matrix product."""
    positions = np.empty((len(detections), 2))
    for model, indices, vectors in _model_groups(detections, "position (needed for λ)"):
        if isinstance(model, LinearGaussian):
            xy = _position_indices(model, position_mapping, indices[0])
            positions[indices] = (_pseudo_inverse(model.matrix()) @ vectors().T)[xy].T
        elif _batched_bearing_range(model):
            xy = _position_indices(model, position_mapping, indices[0])
            positions[indices] = _bearing_range_inverse(model, vectors())[:, xy]
        elif hasattr(model, "inverse_function"):
            for i in indices:
                state = np.asarray(model.inverse_function(detections[i]),
                                   dtype=np.float64).ravel()
                positions[i] = state[_position_indices(model, position_mapping, i)]
        else:
            raise ValueError(f"detections: detection {indices[0]}'s measurement model "
                             f"{type(model).__name__} has no inverse_function")
    return positions


def _model_groups(detections: Sequence, needed_for: str):
    """The detections grouped by measurement model *value*
    (:func:`~ctxmodels.model_key.measurement_model_key`: equal models in different objects
    form one group, its first model the representative), in first-appearance order: ``(model,
    indices, vectors)`` with ``vectors()`` their measurement vectors as float rows (checked
    against the model's ``ndim_meas``; taken from the collection's stacked ``vectors`` when
    it carries them, as :class:`~ctxmodels.stonesoup.ordering.OrderedDetections` does)."""
    n = len(detections)
    stacked = getattr(detections, "vectors", None)
    for model, indices in scan_model_groups(detections).values():
        if model is None:
            raise ValueError(f"detections: detection {indices[0]} has no measurement model, "
                             f"so its {needed_for} is unknown")
        ndim_meas = getattr(model, "ndim_meas", None)

        def vectors(indices=indices, ndim_meas=ndim_meas):
            if stacked is not None and stacked.shape == (n, ndim_meas):
                return stacked if len(indices) == n else stacked[indices]
            return _measurement_vectors(detections, indices, ndim_meas)
        yield model, indices, vectors


def _measurement_vectors(detections: Sequence, indices: list, ndim_meas) -> np.ndarray:
    """The measurement vectors of ``detections[indices]`` as float rows (K, m); ValueError
    naming the first detection whose vector is not ``ndim_meas`` long (if given)."""
    vectors = [detections[i].state_vector for i in indices]
    try:
        stacked = np.array(vectors, dtype=np.float64)
    except (TypeError, ValueError):
        stacked = None
    if stacked is not None and stacked.ndim == 3 and stacked.shape[2] == 1:
        stacked = stacked[..., 0]
    if stacked is not None and stacked.ndim == 2 \
            and (ndim_meas is None or stacked.shape[1] == ndim_meas):
        return stacked
    for i, vector in zip(indices, vectors):
        shape = np.shape(vector)
        if ndim_meas is not None and shape not in ((ndim_meas, 1), (ndim_meas,)):
            raise ValueError(f"detections: detection {i} has a state vector of shape {shape}, "
                             f"but its measurement model {type(detections[i].measurement_model).__name__} "
                             f"measures {ndim_meas} values")
    raise ValueError(f"detections: detections {indices} have state vectors of different "
                     "shapes or non-numeric values")


_PSEUDO_INVERSES: dict = {}


def _pseudo_inverse(matrix) -> np.ndarray:
    """``pinv`` of a linear model's matrix."""
    return _inverted_by_value(_PSEUDO_INVERSES, matrix, np.linalg.pinv)


def _inverted_by_value(cache: dict, matrix, invert, limit: int = 64) -> np.ndarray:
    """``invert(matrix)``, cached in ``cache`` by the matrix's value: scans often bring a new
    model object with the same matrix (a moving sensor's few recurring headings)."""
    matrix = np.ascontiguousarray(matrix, dtype=np.float64)
    key = (matrix.shape, matrix.tobytes())
    inverse = cache.get(key)
    if inverse is None:
        if len(cache) >= limit:
            cache.clear()
        inverse = cache[key] = invert(matrix)
    return inverse


def _batched_bearing_range(model) -> bool:
    """A 2-D bearing–range model whose inverse :func:`_bearing_range_inverse` computes."""
    return (isinstance(model, CartesianToBearingRange)
            and type(model).inverse_function is CartesianToBearingRange.inverse_function
            and len(model.mapping) == 2
            and model.rotation_offset[0] == 0 and model.rotation_offset[1] == 0)


def _bearing_range_inverse(model, polar: np.ndarray) -> np.ndarray:
    """``model.inverse_function`` of K (bearing, range) rows at once, (K, ndim_state): the
    polar-to-Cartesian point rotated back to the world and shifted by the offset."""
    bearing, rng = polar[:, 0], polar[:, 1]
    xyz = np.array([rng * np.cos(bearing), rng * np.sin(bearing), np.zeros(len(polar))])
    xy = (_inverse_rotation(model.rotation_matrix) @ xyz)[0:2]
    states = np.zeros((len(polar), model.ndim_state))
    offset = np.asarray(model.translation_offset, dtype=np.float64)[:2, 0]
    states[:, list(model.mapping[:2])] = (xy + offset[:, np.newaxis]).T
    return states


_INVERSE_ROTATIONS: dict = {}


def _inverse_rotation(rotation) -> np.ndarray:
    """``inv`` of a model's rotation matrix."""
    return _inverted_by_value(_INVERSE_ROTATIONS, rotation, np.linalg.inv, limit=256)


def measured_ranges(detections: Sequence) -> np.ndarray:
    """Each detection's measured range from its sensor, (M,): the range element of a 2-D
    bearing–range measurement (Stone Soup's :class:`CartesianToBearingRange`, measured from
    its ``translation_offset``), NaN for any other detection."""
    n = len(detections)
    groups = scan_model_groups(detections)
    stacked = getattr(detections, "vectors", None)
    if stacked is not None and stacked.shape == (n, 2) and len(groups) == 1 \
            and _measures_range(next(iter(groups.values()))[0]):
        return stacked[:, 1].copy()  # one bearing–range model (value) per scan: the usual case
    ranges = np.full(n, np.nan)
    for model, indices in groups.values():
        if _measures_range(model):
            for i in indices:
                ranges[i] = float(np.asarray(detections[i].state_vector,
                                             dtype=np.float64).ravel()[1])
    return ranges


def _measures_range(model) -> bool:
    return isinstance(model, CartesianToBearingRange) and len(model.mapping) == 2


#: How far (relative) a measured range may lie from the range of the detection's position
#: from the context's pose and still be read as the same range: far above the round trip's
#: ulps, far below any physical lever arm.
_RANGE_AGREEMENT = 1e-9


def ranges_for_bands(detections: Sequence, positions: np.ndarray, pose: Pose) -> np.ndarray:
    """The ranges λ's range bands read, (M,): a detection's measured range
    (:func:`measured_ranges`) where it agrees with the range of its position from ``pose``
    to within a relative :data:`_RANGE_AGREEMENT` and is ≥ 0, NaN (use the position)
    elsewhere. So a detection measured exactly on a band edge falls in the band that owns
    the edge, instead of wherever the polar → Cartesian → range round trip (an ulp either
    way) puts it; a detection measured from elsewhere (another lever arm) keeps the range
    from the context's pose."""
    measured = measured_ranges(detections)
    from_pose = np.hypot(positions[:, 0] - pose.x, positions[:, 1] - pose.y)
    with np.errstate(invalid="ignore"):
        agree = (measured >= 0) & (np.abs(measured - from_pose)
                                   <= _RANGE_AGREEMENT * np.maximum(1.0, from_pose))
    return np.where(agree, measured, np.nan)


def _particle_weights(weights, n: int) -> np.ndarray:
    """A particle state's weights as floats, checked: one finite, non-negative weight per
    particle, not all zero (the P_D average divides by their sum)."""
    try:
        w = np.asarray(weights, dtype=np.float64).ravel()
    except (TypeError, ValueError):
        raise TypeError("hypothesis_or_state: particle weights must be numbers, got "
                        f"{type(weights).__name__}") from None
    if w.size != n:
        raise ValueError(f"hypothesis_or_state: {w.size} particle weights for {n} particles")
    if not np.all(np.isfinite(w)) or np.any(w < 0):
        raise ValueError("hypothesis_or_state: particle weights must be finite and >= 0")
    if not np.sum(w) > 0:
        raise ValueError("hypothesis_or_state: particle weights sum to 0; P_D is their "
                         "weighted mean")
    return w


def _renamed(err: Exception, inner: str, outer: str) -> Exception:
    """``err`` with the argument name ``inner`` that starts its message (the model's) as the
    caller's ``outer``: the error names what the caller passed."""
    message = str(err)
    if message.startswith(f"{inner}:"):
        return type(err)(f"{outer}:{message[len(inner) + 1:]}")
    return err


class DetectorContext(Base, *_UPSTREAM_CONTEXT):
    r"""The observability of one sensor at one scan: :math:`P_D(x; S)` and
    :math:`\lambda(z; S)` for the sensor state :math:`S` (its pose at the scan).

    Built by :meth:`SensorModel.context`. Contexts hash and compare by identity, so Stone
    Soup can forward them into ``lru_cache``-d calls. The array forms evaluate a whole scan
    in one call into the Rust core (GIL released, rows split over cores). The first P_D
    call prepares the scan (:mod:`~ctxmodels.scan_calls`), so that a call per hypothesis,
    as Stone Soup's trackers make, costs a fraction of a microsecond.

    Learned P_D factors (:class:`~ctxmodels.DetectionEstimate`) are read once per context:
    the first P_D call, by whichever method, fixes them as they stand
    (:meth:`~ctxmodels.DetectionProbabilityModel.frozen`), and every later P_D call of the
    context, by any method and any input layout, evaluates that snapshot (it also goes into
    pickles and copies). λ reads a :class:`~ctxmodels.ClutterMap` as it stands at each
    call, on every method alike: update maps after a scan's tracking.
    """

    sensor_model: SensorModel = Property(doc="The sensor's model.")
    pose: Pose = Property(doc="The sensor's own pose at the scan (mounting applied).")
    timestamp: datetime.datetime | None = Property(default=None, doc="The scan time.")

    __hash__ = object.__hash__

    #: Built on the first P_D call (see :mod:`~ctxmodels.scan_calls`); dropped when a
    #: Property is set and left out of pickles and copies.
    _scan_calls: ScanCalls | None = None
    #: The detection model the context evaluates, fixed at its first P_D call; dropped when
    #: a Property is set, kept in pickles and copies.
    _snapshot = None

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        if not isinstance(self.sensor_model, SensorModel):
            raise TypeError(f"sensor_model: expected a SensorModel, got "
                            f"{type(self.sensor_model).__name__}")
        if not isinstance(self.pose, Pose):
            raise TypeError(f"pose: expected a Pose, got {type(self.pose).__name__}")
        if self.timestamp is not None and not isinstance(self.timestamp, datetime.datetime):
            raise TypeError(f"timestamp: expected a datetime.datetime or None, got "
                            f"{type(self.timestamp).__name__} {self.timestamp!r}")

    def __eq__(self, other):
        return self is other

    def __setattr__(self, name, value):
        super().__setattr__(name, value)
        self.__dict__.pop("_scan_calls", None)
        self.__dict__.pop("_snapshot", None)

    def __getstate__(self):
        state = dict(self.__dict__)
        state.pop("_scan_calls", None)
        return state

    def _calls(self) -> ScanCalls:
        snapshot = self._snapshot
        if snapshot is None:
            snapshot = self.__dict__["_snapshot"] = self.sensor_model.detection.frozen()
        calls = self.__dict__["_scan_calls"] = ScanCalls(self.sensor_model, snapshot, self.pose)
        return calls

    # --- detection probability -----------------------------------------------------------
    def prob_detection_array(self, means, covars=None, *, out=None) -> np.ndarray:
        """P_D for N states: ``means`` (N, D); with ``covars`` (N, D, D) and a sensor model
        whose ``pd_evaluation`` is not ``'mean'``, the expectation over each Gaussian."""
        calls = self._scan_calls or self._calls()
        model = self.sensor_model
        try:
            if covars is None or calls.mean_only:
                # the common case (float64 rows, usable out) in one call; else converted here
                pd = calls.at_pose.evaluate(means, out)
                if pd is not None:
                    return pd
                return calls.detection.evaluate(self.pose, means, tuple(model.position_mapping),
                                                out=out)
            return calls.detection.expected(self.pose, means, covars,
                                            tuple(model.position_mapping), model.pd_evaluation,
                                            model.pd_order, out=out)
        except (TypeError, ValueError) as err:
            raise _renamed(err, "states", "means") from None

    def prob_detection_particles(self, particles, *, log: bool = False, missed: bool = False
                                 ) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
        r"""P_D at every particle of a particle state, in one call into the core.

        For particles :math:`x^{(1)}, \dots, x^{(N)}`, the columns of ``particles``,

        .. math::
            p_i = P_D\bigl(x^{(i)}; S\bigr), \qquad
            \ell_i = \log p_i \quad (\log 0 = -\infty),

        P_D read at each particle's position (the sensor model's ``position_mapping`` rows)
        as :meth:`prob_detection_array` reads it at a mean: bit for bit
        ``prob_detection_array(particles.T)``, and with ``log`` bit for bit ``numpy.log`` of
        that. The array is read in place, C- or Fortran-ordered (other layouts and dtypes are
        copied first), so there is no transposed copy; the logs are looked up in the core per
        particle from a table of the scan's distinct P_D values (a handful: products of band,
        sector and land values) that NumPy's ``log`` fills, GIL released (past 256 distinct
        values NumPy takes the log of every value).

        Parameters
        ----------
        particles : array_like, shape (D, N)
            One column per particle: a particle state's ``state_vector``
            (:class:`~stonesoup.types.array.StateVectors`).
        log : bool
            Return :math:`\ell_i` instead of :math:`p_i`.
        missed : bool
            Also return :math:`1 - p_i` (:math:`\log(1 - p_i)` with ``log``), the
            missed-detection factor, from the same evaluation.

        Returns
        -------
        : :class:`numpy.ndarray` of shape (N,)
            :math:`p_i` or :math:`\ell_i`; with ``missed`` a pair ``(detected, missed)``.

        Raises
        ------
        ValueError
            ``particles`` is not 2-D, has fewer rows than ``position_mapping`` reads, or a
            particle's position is NaN or infinite (naming the first such particle).
        """
        calls = self._scan_calls or self._calls()
        return calls.detection.evaluate_particles(self.pose, particles,
                                                  tuple(self.sensor_model.position_mapping),
                                                  log=log, missed=missed)

    def prob_detection_states(self, states: Sequence) -> np.ndarray:
        """P_D of Stone Soup states, predictions or hypotheses, in one array call."""
        states = [_state_of(s) for s in states]
        if not states:
            return np.empty(0)
        means = np.stack([np.asarray(s.state_vector, dtype=np.float64).ravel() for s in states])
        covars = None
        if self.sensor_model.pd_evaluation != "mean" and all(
                getattr(s, "covar", None) is not None for s in states):
            covars = np.stack([np.asarray(s.covar, dtype=np.float64) for s in states])
        return self.prob_detection_array(means, covars)

    def prob_detection(self, hypothesis_or_state) -> Probability:
        """P_D of one hypothesis' prediction, a state, or a plain state vector. A particle
        state gets the weighted mean of its particles' P_D."""
        state = _state_of(hypothesis_or_state)
        vector = getattr(state, "state_vector", state)
        calls = self._scan_calls or self._calls()
        # one float64 vector (and covariance) with a finite position: straight to the core
        pd = calls.at_pose.at(vector) if calls.mean_only else calls.at_pose.expected_at(vector, state)
        if pd is not None:
            return calls.probability(pd)
        try:
            vector = np.asarray(vector)
            if vector.dtype.kind in "mMUSV":  # (NumPy would read timedelta64 as integers)
                raise TypeError
            vector = vector.astype(np.float64, copy=False)  # object: Stone Soup's angles
        except (TypeError, ValueError):
            raise TypeError(f"hypothesis_or_state: cannot read a numeric state vector from "
                            f"{type(hypothesis_or_state).__name__}") from None
        if vector.ndim == 2 and vector.shape[1] > 1:  # particles: (D, N)
            pd = self.prob_detection_array(vector.T)
            weights = getattr(state, "weight", None)
            w = (np.full(pd.shape, 1 / pd.size) if weights is None
                 else _particle_weights(weights, pd.size))
            return Probability(float(np.sum(w * pd) / np.sum(w)))
        mean = vector.reshape(1, -1)
        covar = getattr(state, "covar", None)
        covars = None if covar is None else np.asarray(covar, dtype=np.float64)[np.newaxis]
        try:
            return Probability(float(self.prob_detection_array(mean, covars)[0]))
        except (TypeError, ValueError) as err:
            raise _renamed(err, "means", "hypothesis_or_state") from None

    # --- clutter ---------------------------------------------------------------------------
    def clutter_spatial_density_array(self, positions, metadata=None, *, ranges=None,
                                      out=None) -> np.ndarray:
        """λ for M detections at world ``positions`` (M, 2); ``metadata`` an (M, K) array in
        the clutter model's ``metadata_keys`` order or a sequence of metadata mappings;
        ``ranges`` (M,) measured ranges that range bands read instead (NaN: none)."""
        if ranges is None:
            # the common case (float64 arrays, usable out) in one call; else converted here
            calls = self._scan_calls or self._calls()
            lam = calls.clutter_at_pose.evaluate(positions, metadata, out)
            if lam is not None:
                return lam
        return self.sensor_model.clutter.evaluate(self.pose, positions, metadata, ranges=ranges,
                                                  out=out)

    def clutter_spatial_density_detections(self, detections: Sequence,
                                           positions=None) -> np.ndarray:
        """λ of Stone Soup detections, in one array call. ``positions``: their (M, 2) world
        positions if already computed (:func:`detection_positions` with the sensor model's
        ``position_mapping``)."""
        if not isinstance(detections, Sequence):
            detections = list(detections)
        clutter = self.sensor_model.clutter
        ranges = None
        if clutter.uses_position:
            if positions is None:
                positions = detection_positions(detections, self.sensor_model.position_mapping)
            ranges = ranges_for_bands(detections, positions, self.pose)
        else:
            positions = np.zeros((len(detections), 2))
        metadata = [d.metadata for d in detections] if clutter.metadata_keys else None
        return clutter.evaluate(self.pose, positions, metadata, ranges=ranges)

    def clutter_spatial_density(self, detection) -> float:
        """λ of one detection (position from its measurement model, metadata from
        ``detection.metadata``)."""
        return float(self.clutter_spatial_density_detections([detection])[0])


__all__ = ["DetectionSet", "DetectorContext", "detection_positions", "measured_ranges"]

