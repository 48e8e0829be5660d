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
from stonesoup.types.numeric import Probability

from ._upstream import property_slot
from .errors import ArgumentError, ArgumentTypeError
from .pose import Pose
# (the detections' positions and ranges lived here: still importable from here)
from .positions import detection_positions, measured_ranges, ranges_for_bands  # noqa: F401
from .scan_calls import ScanCalls
from .sensor import SensorModel, provide

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

_SENSOR_MODEL, _POSE, _TIMESTAMP = (property_slot(name)
                                    for name in ("sensor_model", "pose", "timestamp"))


class DetectionSet(_UpstreamSet):
    """A scan's detections (a ``set``) with the :class:`DetectorContext` of that scan.

    An empty scan is an empty ``DetectionSet`` that still carries its context: that is what
    tells a tracker the sensor looked and saw nothing there.
    """

    def __init__(self, detections: Iterable = (), detector_context: DetectorContext | None = None):
        super().__init__(detections)
        self.detector_context = detector_context

    def copy(self) -> DetectionSet:
        return DetectionSet(self, self.detector_context)

    def __repr__(self):
        return f"DetectionSet({set(self)!r}, detector_context={self.detector_context!r})"

    def __reduce__(self):
        return (type(self), (list(self), self.detector_context))


def _state_of(hypothesis_or_state: Any):
    """The predicted state of a hypothesis, or the state itself."""
    return getattr(hypothesis_or_state, "prediction", hypothesis_or_state)


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
    """``err`` about the argument ``inner`` (as the model names it) as an error about the
    caller's ``outer``: the error names what the caller passed."""
    if isinstance(err, (ArgumentError, ArgumentTypeError)) and err.argument == inner:
        return err.renamed(outer)
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

    @classmethod
    def _of(cls, sensor_model: SensorModel, pose: Pose, timestamp=None) -> DetectorContext:
        """``DetectorContext(sensor_model=..., pose=..., timestamp=...)``; when the values
        pass its checks as they stand (a feeder's every scan), the same object without
        Stone Soup's per-Property setting, which costs more than the scan's P_D calls."""
        if cls is DetectorContext and isinstance(sensor_model, SensorModel) \
                and isinstance(pose, Pose) \
                and (timestamp is None or isinstance(timestamp, datetime.datetime)):
            context = object.__new__(cls)
            context.__dict__.update({_SENSOR_MODEL: sensor_model, _POSE: pose,
                                     _TIMESTAMP: timestamp})
            return context
        return cls(sensor_model=sensor_model, pose=pose, timestamp=timestamp)

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

    def _mean_detection(self):
        """The scan's P_D at a state's mean in the core (``DetectionAtPose``) when the sensor
        model reads P_D at the mean, else None: what the array trackers evaluate on memory
        the core holds (``GaussianMixtureArrays.prob_detection``), the same bits as
        :meth:`prob_detection_array` of those means. Counts as a P_D call (it fixes the
        snapshot)."""
        calls = self._scan_calls or self._calls()
        return calls.at_pose if calls.mean_only else None

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
                return calls.detection.evaluate(self.pose, means, model.position_mapping,
                                                out=out, velocity_mapping=model.velocity_mapping)
            return calls.detection.expected(self.pose, means, covars,
                                            model.position_mapping, model.pd_evaluation,
                                            model.pd_order, out=out,
                                            velocity_mapping=model.velocity_mapping)
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
        model = self.sensor_model
        return calls.detection.evaluate_particles(self.pose, particles, model.position_mapping,
                                                  log=log, missed=missed,
                                                  velocity_mapping=model.velocity_mapping)

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
        """λ for M detections at world ``positions`` (M, 2) — (M, 3) with heights, read as
        slant ranges and elevations from the sensor's height; ``metadata`` an (M, K) array in
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
        positions — (M, 3) for a model with heights — if already computed
        (:func:`detection_positions` with the sensor model's ``position_mapping``)."""
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
        if ranges is None and metadata is None:  # (the scan's prepared call: the same bits)
            return self.clutter_spatial_density_array(positions)
        return clutter.evaluate(self.pose, positions, metadata, ranges=ranges)

    def clutter_spatial_density(self, detection) -> float:
        """λ of one detection (position from its measurement model, metadata from
        ``detection.metadata``)."""
        return float(self.clutter_spatial_density_detections([detection])[0])


# SensorModel.context builds its contexts with this
provide("context", DetectorContext._of)

__all__ = ["DetectionSet", "DetectorContext", "detection_positions", "measured_ranges"]

