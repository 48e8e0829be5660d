"""Detection probability models: P_D(x; S) as a product of coverage factors."""
from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from stonesoup.base import Property

from . import _core
from ._component import (ModelComponent, as_array, as_columns, as_float, as_int,
                         as_position_mapping, as_rows, as_sequence, check_out, velocity_indices)
from .detection_estimate import DetectionEstimate
from .elevation import ElevationSector
from .errors import ArgumentError, ShapeError
from .horizon import RadarHorizon
from .land import LandMask, LineOfSight
from .pose import Pose, pose_tuple
from .radar import RadarEquation
from .range_bands import RangeBands
from .range_rate import RangeRateNotch
from .sector import AngularSector

DetectionFactor = (float | RangeBands | AngularSector | RadarEquation | RadarHorizon
                   | ElevationSector | RangeRateNotch | LandMask | LineOfSight | DetectionEstimate)

#: Integration rules for the expected P_D of a Gaussian (see :class:`SensorModel`).
PD_RULES = ("mean", "cubature", "unscented", "gauss-hermite")
#: Largest Gauss–Hermite order (nodes per axis).
MAX_ORDER = 32


class DetectionProbabilityModel(ModelComponent):
    r"""Detection probability of a sensor as the product of its factors,

    .. math::
        P_D(x; S) = \prod_f f(x; S) \in [0, 1],

    where :math:`S` is the sensor pose at the scan. Factors: constants (floats), range
    bands (:class:`RangeBands`, over range from the sensor), body-frame sectors
    (:class:`AngularSector`), the radar equation (:class:`RadarEquation`) and horizon
    (:class:`RadarHorizon`), elevation sectors (:class:`ElevationSector`), range-rate blind
    zones (:class:`RangeRateNotch`, reading the state's velocity), land
    (:class:`LandMask`: 0 on land) and line of sight (:class:`LineOfSight`: 0 when shadowed
    by land) and range bands learned online (:class:`DetectionEstimate`: read as they stand
    when the model is put at a scan's pose). Every factor value must lie in [0, 1].

    States are read at ``position_mapping``: (x, y) puts every target at the sensor's
    height; (x, y, z) reads each one's height, and then ranges are slant ranges from the
    pose's height ``z``, elevations are angles above the sensor's horizontal plane, and
    bearings, land and line of sight are read on the plane below the target.

    The paper's radar (eq. pd-radar): ``DetectionProbabilityModel(factors=[
    RangeBands(edges=(50, 1612), values=(0, 0.4, 0), upper_owns=(False, True)),
    AngularSector.blind(math.pi, math.radians(65))])``.
    """

    factors: Sequence[DetectionFactor] = Property(doc="The factors whose product is P_D.")

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._replace("factors", as_sequence(self.factors, "factors", "factors"))
        self._compiled()

    def _compiled(self) -> _core.DetectionModel:
        def build():
            parts = []
            for i, factor in enumerate(self.factors):
                if isinstance(factor, (RangeBands, AngularSector, RadarEquation, RadarHorizon,
                                       ElevationSector, RangeRateNotch, LandMask, LineOfSight)):
                    parts.append(factor._compiled())
                elif isinstance(factor, DetectionEstimate):
                    parts.append(factor._core)  # shared: its updates reach this model
                elif isinstance(factor, (int, float, np.integer, np.floating)):
                    parts.append(as_float(factor, f"factors[{i}]"))
                else:
                    raise TypeError(f"factors[{i}]: expected a float, RangeBands, AngularSector, "
                                    "RadarEquation, RadarHorizon, ElevationSector, "
                                    "RangeRateNotch, LandMask, LineOfSight or DetectionEstimate, "
                                    "got "
                                    f"{type(factor).__name__}")
            return _core.DetectionModel(parts)
        return self._cached("core", build)

    def frozen(self) -> DetectionProbabilityModel:
        """This model with every :class:`DetectionEstimate` factor replaced by its
        :meth:`~DetectionEstimate.bands` as they stand now (itself when it has none): the
        snapshot a :class:`~ctxmodels.DetectorContext` evaluates for its whole scan, on
        every path, whatever updates the estimates get meanwhile."""
        # (asked every scan; which factors are estimates is fixed with the model)
        estimates = self._cached("estimates", lambda: tuple(
            i for i, factor in enumerate(self.factors) if isinstance(factor, DetectionEstimate)))
        if not estimates:
            return self
        factors = list(self.factors)
        for i in estimates:
            factors[i] = factors[i].bands()
        # The same bands (an estimate not updated since) give the same immutable snapshot:
        # the last one, already compiled, is kept.
        last = self.__dict__.get("_cached_frozen")
        if last is not None and all(a is b for a, b in zip(last.factors, factors, strict=True)):
            return last
        frozen = DetectionProbabilityModel(factors=factors)
        self.__dict__["_cached_frozen"] = frozen
        return frozen

    def evaluate(self, pose: Pose, states, position_mapping=(0, 2), *, out=None,
                 velocity_mapping=None) -> np.ndarray:
        """P_D at each row of ``states`` (N, D) for a sensor at ``pose``; the velocity at
        ``velocity_mapping`` (needed by a :class:`RangeRateNotch`)."""
        rows = as_rows(states, "states")
        mapping = _mapping_within(position_mapping, velocity_mapping, rows, "states")
        return self._compiled().evaluate(pose_tuple(pose), rows, mapping,
                                         check_out(out, rows.shape[0], states=rows))

    def evaluate_particles(self, pose: Pose, particles, position_mapping=(0, 2), *, log=False,
                           missed=False, velocity_mapping=None):
        """P_D at each column of ``particles`` (D, N), read in place; ``log``: log P_D;
        ``missed``: also 1 - P_D (or its log), as a pair. See
        :meth:`~ctxmodels.DetectorContext.prob_detection_particles`."""
        columns = as_columns(particles, "particles")
        mapping = _core_mapping(position_mapping, velocity_mapping)
        return self._compiled().evaluate_particles(pose_tuple(pose), columns, mapping,
                                                   bool(log), bool(missed))

    def expected(self, pose: Pose, means, covars, position_mapping=(0, 2), rule="cubature",
                 order=3, *, out=None, velocity_mapping=None) -> np.ndarray:
        """Expected P_D over Gaussians N(means[i], covars[i]) under an integration rule (over
        the position; a range-rate notch integrated over the velocity given the position,
        exactly: see :class:`RangeRateNotch`)."""
        if rule not in PD_RULES:
            raise ArgumentError("rule", f"must be one of {PD_RULES}, got {rule!r}")
        means = as_rows(means, "means")
        covars = as_array(covars, "covars", 3, "(N, D, D)")
        mapping = _mapping_within(position_mapping, velocity_mapping, means, "means")
        order = as_int(order, "order", low=1, high=MAX_ORDER)
        return self._compiled().expected(pose_tuple(pose), means, covars, mapping, rule, order,
                                         check_out(out, means.shape[0], means=means, covars=covars))


def _core_mapping(position_mapping, velocity_mapping) -> tuple[int, ...]:
    """The columns the core reads: the positions, then the velocity if given."""
    positions = as_position_mapping(position_mapping, heights=True)
    if velocity_mapping is None:
        return positions
    return positions + velocity_indices(velocity_mapping, positions)


def _mapping_within(position_mapping, velocity_mapping, rows: np.ndarray, name: str
                    ) -> tuple[int, ...]:
    mapping = _core_mapping(position_mapping, velocity_mapping)
    if max(mapping) >= rows.shape[1]:
        raise ShapeError(name, f"position_mapping / velocity_mapping {mapping} is out of "
                               f"range for rows of {rows.shape[1]} columns")
    return mapping
