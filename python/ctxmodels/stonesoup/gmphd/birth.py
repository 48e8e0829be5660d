r"""Measurement-driven (adaptive) birth for Gaussian-mixture point-process trackers.

Stone Soup's GM-PHD tracker adds one static birth component per scan. Over a km-scale
surveillance area that component is so wide that its likelihood per unit measurement
volume is tiny: a birth weight of 1e-4 spread over :math:`\sim 10^6\,\mathrm{m}^2` never
outweighs the clutter intensity, and no track starts. Measurement-driven birth (Ristic,
Clark, Vo & Vo 2012; Reuter et al. 2014) instead places a small birth component on every
detection.

The form used here is the standard adaptive one: the detections of scan :math:`k` define
the birth intensity of a *later* scan,

.. math::
    \gamma(x) = \sum_{z \in Z_k} w_b\, \mathcal{N}\bigl(x;\ m_b(z),\ P_b\bigr),

with :math:`m_b(z)` the detection's world position (through the measurement model's
inverse) and zero (or ``velocity_mean``) velocity, so a detection never both creates a
component and updates it. With asynchronous sensors "the next scan" is often another
sensor that cannot see the birth at all (a 10 Hz lidar between two 0.8 Hz radar scans):
a birth component that is not detected is discarded by the stock updater, so such births
would never survive. Hence a birth enters at the first later scan whose context gives it
:math:`P_D > 0` at its mean — for that scan's sensor, :math:`P_D = 0` makes the component
pass the update unchanged, so deferring it is the same as entering it earlier — or at the
next scan when there is no context (the stock, uniform-P_D case). Births still waiting
after ``max_delay`` are dropped.

With a ``birth_density`` the weights follow the context as λ does: detection :math:`z` of a
scan by a sensor in state :math:`S` gives a birth of weight
:math:`w_b(z) = w_b\, b(z; S)`, :math:`b` the product of the density model's factors at the
detection's world position — births likelier at a harbour mouth (a
:class:`~ctxmodels.Zone`), at the edge of the coverage where targets enter (range bands),
less likely on land (a ``Zone`` of the land with a small ``inside``).

The components carry ``tag='birth'``, like the stock birth component: the hypothesiser gives
a detected birth a fresh tag (a new potential track), the updater drops an undetected one,
and the tracker never turns a ``'birth'`` component into a track.
"""
from __future__ import annotations

import datetime
from collections.abc import Sequence

import numpy as np
from stonesoup.base import Base, Property
from stonesoup.types.array import CovarianceMatrix
from stonesoup.types.state import TaggedWeightedGaussianState

from ..._component import as_float
from ...clutter import ClutterDensityModel
from ...context import detection_positions
from ...errors import ArgumentError, ArgumentTypeError, ShapeError
from ...foreign import as_array_context

#: Table I of the paper: track initialisation covariance for [x, vx, y, vy].
TABLE_I_BIRTH_COVAR = np.diag([10.0, 15.0, 10.0, 15.0]) ** 2


def _indices(values, name: str) -> tuple[int, ...]:
    try:
        indices = tuple(values)
    except TypeError:
        raise TypeError(f"{name}: expected a sequence of state indices, got {values!r}") from None
    if not all(isinstance(i, (int, np.integer)) and not isinstance(i, bool) and i >= 0
               for i in indices):
        raise ValueError(f"{name}: indices must be ints >= 0, got {indices}")
    if len(set(indices)) != len(indices):
        raise ValueError(f"{name}: indices must be distinct, got {indices}")
    return tuple(int(i) for i in indices)


class MeasurementDrivenBirth(Base):
    r"""One birth component per detection (see the module docstring for the scheme).

    Each component has weight ``birth_weight`` (the paper's Table I: 1e-4), mean at the
    detection's world position (``position_mapping`` indices) with velocity
    ``velocity_mean`` (``velocity_mapping`` indices; other indices 0), covariance
    ``birth_covar`` (Table I: :math:`\mathrm{diag}([10, 15, 10, 15])^2`), the scan's
    timestamp and ``tag='birth'``.
    """

    birth_weight: float = Property(
        default=1e-4, doc="Weight of each birth component: expected births per detection.")
    birth_covar: CovarianceMatrix = Property(
        default=None, doc="Covariance of each birth component; default Table I, "
                          "diag([10, 15, 10, 15])² for [x, vx, y, vy].")
    position_mapping: Sequence[int] = Property(
        default=(0, 2), doc="Indices of x and y in the state (and of z, for states with a "
                            "height).")
    velocity_mapping: Sequence[int] = Property(
        default=(1, 3), doc="Indices of the velocity components in the state.")
    velocity_mean: Sequence[float] = Property(
        default=None, doc="Prior mean velocity, one value per velocity index; default 0.")
    max_delay: datetime.timedelta = Property(
        default=None, doc="Births no scan could see within this long after their detection "
                          "are dropped; None: no limit.")
    birth_density: ClutterDensityModel = Property(
        default=None, doc="Relative birth density b(z; S): each birth's weight is "
                          "``birth_weight`` × b at its detection, for the pose of the scan's "
                          "sensor (needs each scan's detector context). None: b = 1.")

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        weight = as_float(self.birth_weight, "birth_weight", finite=False)
        if not np.isfinite(weight) or weight <= 0:
            raise ValueError(f"birth_weight: must be finite and > 0, got {weight}")
        if self.birth_covar is None:
            self.birth_covar = CovarianceMatrix(TABLE_I_BIRTH_COVAR)
        covar = np.asarray(self.birth_covar, dtype=np.float64)
        if covar.ndim != 2 or covar.shape[0] != covar.shape[1] or not np.all(np.isfinite(covar)):
            raise ValueError(f"birth_covar: must be a finite square matrix, "
                             f"got shape {covar.shape}")
        if not np.allclose(covar, covar.T):
            raise ValueError("birth_covar: must be symmetric")
        self.birth_covar = CovarianceMatrix(covar)
        ndim = covar.shape[0]
        position = _indices(self.position_mapping, "position_mapping")
        if len(position) not in (2, 3):
            raise ValueError(f"position_mapping: must hold the two indices of x and y (or "
                             f"three, with z), got {position}")
        velocity = _indices(self.velocity_mapping or (), "velocity_mapping")
        if set(position) & set(velocity):
            raise ValueError("velocity_mapping: must not share indices with position_mapping")
        if max(position + velocity) >= ndim:
            raise ValueError(f"position_mapping / velocity_mapping: index out of range for a "
                             f"{ndim}-dimensional birth_covar")
        if self.velocity_mean is None:
            self.velocity_mean = (0.0,) * len(velocity)
        mean = np.asarray(self.velocity_mean, dtype=np.float64).ravel()
        if mean.shape != (len(velocity),) or not np.all(np.isfinite(mean)):
            raise ValueError(f"velocity_mean: needs one finite value per velocity index "
                             f"({len(velocity)}), got {self.velocity_mean!r}")
        if self.birth_density is not None and not isinstance(self.birth_density, ClutterDensityModel):
            raise ArgumentTypeError("birth_density", f"expected a ClutterDensityModel, got "
                                                     f"{type(self.birth_density).__name__}")
        if self.birth_density is not None and self.birth_density.uses_height \
                and len(position) != 3:
            raise ArgumentError("birth_density", "its ElevationSector reads each detection's "
                                                 "height, but position_mapping gives no height; "
                                                 "give the (x, y, z) indices")
        if self.max_delay is not None and not isinstance(self.max_delay, datetime.timedelta):
            raise TypeError(f"max_delay: expected a datetime.timedelta, "
                            f"got {type(self.max_delay).__name__}")
        # Canonical forms, so a YAML round trip (lists for tuples) gives the same component.
        self.position_mapping, self.velocity_mapping = position, velocity
        self.velocity_mean = tuple(float(v) for v in mean)
        self._position = list(position)
        self._velocity = list(velocity)
        self._velocity_mean = mean

    @property
    def ndim_state(self) -> int:
        return self.birth_covar.shape[0]

    def components(self, detections, timestamp: datetime.datetime | None = None,
                   detector_context=None) -> list[TaggedWeightedGaussianState]:
        """A birth component at each detection of one scan (world position through each
        detection's measurement model: linear models by pseudo-inverse, non-linear ones by
        their ``inverse_function``). ``timestamp`` defaults to each detection's own; the
        ``detector_context`` (default: the detection set's) gives the pose that a
        ``birth_density`` is evaluated for."""
        if detector_context is None:
            detector_context = getattr(detections, "detector_context", None)
        detections = list(detections)
        if not detections:
            return []
        positions = detection_positions(detections, self._position)
        means = self.means(detections, positions)
        weights = self.weights(detections, positions, detector_context)
        return [TaggedWeightedGaussianState(
                    state_vector=mean.reshape(-1, 1),
                    covar=self.birth_covar.copy(),
                    weight=weight,
                    tag=TaggedWeightedGaussianState.BIRTH,
                    timestamp=timestamp if timestamp is not None else detection.timestamp)
                for mean, weight, detection in zip(means, weights, detections)]

    def weights(self, detections: Sequence, positions=None, detector_context=None) -> np.ndarray:
        """The (N,) birth weights of ``detections``: ``birth_weight`` each, times the
        ``birth_density`` at each detection's world position (``positions``, (N, 2) or
        (N, 3) as this birth's ``position_mapping``, if already computed; with heights the
        density reads them as λ does: slant ranges, elevations) for the pose of
        ``detector_context``'s sensor, in one call."""
        n = len(detections)
        if self.birth_density is None:
            return np.full(n, float(self.birth_weight))
        pose = getattr(detector_context, "pose", None)
        if pose is None:
            raise ArgumentError("birth_density", "needs each scan's detector context with its "
                                "sensor's pose (feed the tracker through a ContextFeeder)")
        if positions is None:
            positions = detection_positions(detections, self._position)
        elif np.shape(positions) != (n, len(self._position)):
            raise ShapeError("positions", f"must be ({n}, {len(self._position)}), one row per "
                                          f"detection, got shape {np.shape(positions)}")
        metadata = ([d.metadata for d in detections] if self.birth_density.metadata_keys
                    else None)
        density = self.birth_density.evaluate(pose, np.ascontiguousarray(positions), metadata)
        with np.errstate(over="ignore", under="ignore"):  # (refused below, by name)
            weights = float(self.birth_weight) * density
        if not np.all(np.isfinite(weights) & (weights > 0)):
            raise ArgumentError("birth_density", f"birth_weight {self.birth_weight} times the "
                                "density overflows or underflows at a detection")
        return weights

    def means(self, detections: Sequence, positions=None) -> np.ndarray:
        """The (N, D) birth means of ``detections`` (see :meth:`components`); ``positions``:
        their (N, 2) or (N, 3) world positions if already computed (:func:`detection_positions` with
        this birth's ``position_mapping``)."""
        if positions is None:
            positions = detection_positions(detections, self._position)
        means = np.zeros((len(detections), self.ndim_state))
        means[:, self._position] = positions
        means[:, self._velocity] = self._velocity_mean
        return means

    @staticmethod
    def visible(means: np.ndarray, covars: np.ndarray | None, detector_context) -> np.ndarray:
        """Whether the context gives P_D > 0 at each birth: ``means`` (N, D), ``covars``
        (N, D, D) or None (used when the sensor model takes P_D's expectation over a
        Gaussian); one array call (a call per birth for a context with only Stone Soup's
        per-call interface)."""
        context = as_array_context(detector_context, "prob_detection_array")
        return context.prob_detection_array(means, covars) > 0

    def due(self, births: Sequence[TaggedWeightedGaussianState], timestamp: datetime.datetime,
            detector_context=None) -> tuple[list, list]:
        """Split queued ``births`` into those that enter the scan at ``timestamp`` and those
        that keep waiting: with a ``detector_context``, a birth enters when P_D > 0 at its
        mean (one array call for all of them); without one, every birth enters. Births older
        than ``max_delay`` are dropped."""
        births = list(births)
        if self.max_delay is not None:
            births = [b for b in births
                      if b.timestamp is None or timestamp - b.timestamp <= self.max_delay]
        if detector_context is None or not births:
            return births, []
        means = np.array([np.asarray(b.state_vector, dtype=np.float64).ravel() for b in births])
        covars = np.array([np.asarray(b.covar, dtype=np.float64) for b in births])
        visible = self.visible(means, covars, detector_context)
        entering = [b for b, v in zip(births, visible) if v]
        waiting = [b for b, v in zip(births, visible) if not v]
        return entering, waiting


__all__ = ["MeasurementDrivenBirth", "TABLE_I_BIRTH_COVAR"]
