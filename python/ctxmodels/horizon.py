r"""The radar horizon: no detection beyond the range at which the Earth's bulge hides the
target from the antenna."""
from __future__ import annotations

import math

import numpy as np
from stonesoup.base import Property

from . import _core
from ._component import ModelComponent, as_float
from .errors import ArgumentError
from .radar import _ranges

#: The Earth's mean radius, metres.
EARTH_RADIUS = 6_371_000.0


class RadarHorizon(ModelComponent):
    r"""1 within the radar horizon, 0 beyond it.

    Over a smooth sphere of effective radius :math:`kR` (refraction bends radar rays down;
    :math:`k = 4/3` is the standard atmosphere), an antenna at height :math:`h_a` sees a
    target at height :math:`h_t` up to the range

    .. math::
        d = \sqrt{2 k R h_a} + \sqrt{2 k R h_t},

    the sum of the two tangent distances to the horizon (to first order in :math:`h/kR`: the
    exact tangent lengths are :math:`\sqrt{2kRh + h^2}`, and arcs over the sphere are
    shorter by :math:`O(d^3/(kR)^2)`; together they differ from :math:`d` by less than
    0.02 % for heights below 1 km and :math:`k \ge 1/2`). A target at exactly :math:`d` is
    visible. With a fixed
    ``target_height`` the factor is a range band with its edge at :math:`d`: it composes
    with every other factor and costs what a range band costs (and, as every range band,
    reads the slant range in a model with heights). With ``target_height=None`` each
    target's own height :math:`h_t` is read from its state (a sensor model whose
    ``position_mapping`` has three indices; a target below the sea counts as at it), the
    edge moves out with it, and :math:`d` is compared with the plane distance.
    """

    antenna_height: float = Property(doc="Antenna height above the sea, metres (≥ 0).")
    target_height: float = Property(
        default=0.0, doc="Target height above the sea, metres (≥ 0); None: each target's own "
                         "height, read from its state.")
    k: float = Property(default=4 / 3, doc="Effective Earth radius factor (> 0; 4/3: standard refraction).")
    earth_radius: float = Property(default=EARTH_RADIUS, doc="The Earth's radius R, metres (> 0).")

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        heights = ("antenna_height",) if self.target_height is None else ("antenna_height",
                                                                            "target_height")
        for name in heights:
            if not as_float(getattr(self, name), name) >= 0:
                raise ArgumentError(name, f"must be a height ≥ 0 metres, got {getattr(self, name)}")
        for name in ("k", "earth_radius"):
            if not as_float(getattr(self, name), name) > 0:
                raise ArgumentError(name, f"must be > 0, got {getattr(self, name)}")
        reach = 2.0 * float(self.k) * float(self.earth_radius)
        if not math.isfinite(reach):
            raise ArgumentError("earth_radius", f"2 k R overflows: k {self.k}, R {self.earth_radius}")
        if not reach >= 1.0:
            raise ArgumentError("earth_radius", f"2 k R is below a metre: k {self.k}, "
                                                f"R {self.earth_radius}")
        for name in heights:
            if not math.isfinite(reach * float(getattr(self, name))):
                raise ArgumentError(name, f"2 k R h overflows: h {getattr(self, name)}")
        self._compiled()

    @property
    def range(self) -> float:
        """The horizon range :math:`d`, metres (of a target at the sea for
        ``target_height=None``)."""
        reach = 2.0 * float(self.k) * float(self.earth_radius)
        target = 0.0 if self.target_height is None else float(self.target_height)
        return math.sqrt(reach * float(self.antenna_height)) + math.sqrt(reach * target)

    def _compiled(self) -> _core.RangeBands | _core.Horizon:
        def build():
            if self.target_height is None:
                reach = 2.0 * float(self.k) * float(self.earth_radius)
                return _core.Horizon(math.sqrt(reach * float(self.antenna_height)), reach)
            # r ≤ d visible: the edge belongs to the band below
            return _core.RangeBands([self.range], [1.0, 0.0], [False])
        return self._cached("core", build)

    def __call__(self, ranges) -> np.ndarray:
        """1 at each range (metres, ≥ 0) within the horizon of a target at
        ``target_height`` (at the sea for ``None``), 0 beyond; NaN raises."""
        if self.target_height is None:
            return RadarHorizon(antenna_height=self.antenna_height, k=self.k,
                                earth_radius=self.earth_radius)(ranges)
        return self._compiled().at(_ranges(ranges))
