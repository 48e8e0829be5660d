r"""Elevation sectors: limits on a target's angle above the sensor's horizontal plane."""
from __future__ import annotations

import math

from stonesoup.base import Property

from . import _core
from ._component import ModelComponent, as_float
from .errors import ArgumentError


class ElevationSector(ModelComponent):
    r"""A factor that takes one value between two elevations, another outside them.

    A target at offset :math:`(\Delta x, \Delta y, \Delta z)` from the sensor has elevation
    :math:`\varepsilon = \operatorname{atan2}(\Delta z, \sqrt{\Delta x^2 + \Delta y^2})`,
    radians above the sensor's horizontal plane — for a pitched or rolled pose, of the
    offset in the sensor's own frame (:class:`~ctxmodels.Pose`).
    It is inside when ``lower`` :math:`\le \varepsilon \le` ``upper`` (boundaries inside),
    decided without an arctangent as :math:`r \sin(\text{lower}) \le \Delta z \le
    r \sin(\text{upper})`, :math:`r` the slant range; a limit at :math:`\pm\pi/2` bounds
    nothing, and the sensor's own position is inside. The target's height is read when the
    sensor model's ``position_mapping`` has three indices; with two, every target is at
    the sensor's height (elevation 0).

    A surveillance radar's beam from −2° to +30°:
    ``ElevationSector(lower=math.radians(-2), upper=math.radians(30))``.
    """

    lower: float = Property(doc="Lowest elevation inside, radians in [−π/2, π/2].")
    upper: float = Property(doc="Highest elevation inside, radians in [lower, π/2].")
    inside: float = Property(default=1.0, doc="Value inside (default: covered).")
    outside: float = Property(default=0.0, doc="Value outside.")

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._compiled()

    def _compiled(self) -> _core.ElevationSector:
        def build():
            lower, upper = as_float(self.lower, "lower"), as_float(self.upper, "upper")
            for name, value in (("lower", lower), ("upper", upper)):
                if abs(value) > math.pi / 2:
                    raise ArgumentError(name, f"must be an elevation in [−π/2, π/2] radians, got "
                                              f"{value} — did you pass degrees? Use "
                                              f"math.radians({value:g})")
            return _core.ElevationSector(lower, upper, as_float(self.inside, "inside"),
                                         as_float(self.outside, "outside"))
        return self._cached("core", build)
