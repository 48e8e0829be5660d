"""Angular sectors in the sensor's body frame (blind sectors, fields of view)."""
from __future__ import annotations

import math

from stonesoup.base import Property

from . import _core
from ._component import ModelComponent, as_float


class AngularSector(ModelComponent):
    r"""A factor that takes one value inside a body-frame angular sector, another outside.

    Angles are radians in the sensor's body frame: 0 is the sensor's heading (boresight),
    positive counter-clockwise (Stone Soup's convention), so :math:`\pi` is astern. A point
    at body bearing :math:`\beta` is inside when the angle between :math:`\beta` and
    ``centre`` is at most ``width / 2`` (boundary inside), correct across the ±π wrap.

    The paper's radar blind sector, 65° centred astern:
    ``AngularSector(centre=math.pi, width=math.radians(65), inside=0.0, outside=1.0)``.
    """

    centre: float = Property(doc="Body-frame bearing of the sector's centre, radians.")
    width: float = Property(doc="Total angular width, radians in (0, 2π].")
    inside: float = Property(default=0.0, doc="Value inside the sector (default: blind).")
    outside: float = Property(default=1.0, doc="Value outside the sector.")

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._compiled()

    @classmethod
    def blind(cls, centre: float, width: float) -> AngularSector:
        """A blind sector: 0 inside, 1 outside."""
        return cls(centre=centre, width=width, inside=0.0, outside=1.0)

    @classmethod
    def field_of_view(cls, centre: float, width: float) -> AngularSector:
        """A field of view: 1 inside, 0 outside."""
        return cls(centre=centre, width=width, inside=1.0, outside=0.0)

    def _compiled(self) -> _core.AngularSector:
        width = as_float(self.width, "width")
        if width > 2 * math.pi:
            raise ValueError(
                f"width: must be in (0, 2π] radians, got {width} — "
                f"did you pass degrees? Use math.radians({width:g})")
        return self._cached("core", lambda: _core.AngularSector(
            as_float(self.centre, "centre"), width,
            as_float(self.inside, "inside"), as_float(self.outside, "outside")))
