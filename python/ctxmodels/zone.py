r"""Zones: a factor that takes one value inside a set of polygons and another outside."""
from __future__ import annotations

import numpy as np
from stonesoup.base import Property

from . import _core
from ._component import ModelComponent, as_float
from .errors import ArgumentTypeError
from .land import LandMask


class Zone(ModelComponent):
    r"""A factor that is ``inside`` within ``polygons`` and ``outside`` elsewhere,

    .. math::
        f(z) = \begin{cases} \text{inside} & z \in Z \\ \text{outside} & \text{otherwise,}
        \end{cases}

    with :math:`Z` the polygons of a :class:`~ctxmodels.LandMask` (a point on a boundary is
    inside; holes are outside) and :math:`z` a detection's world position. A factor of
    :class:`~ctxmodels.ClutterDensityModel` — and so of a birth density
    (:class:`~ctxmodels.stonesoup.MeasurementDrivenBirth`'s ``birth_density``): births 10×
    likelier in a harbour mouth, ``Zone(polygons=harbour_mouth, inside=10.0)``; 100× less
    likely on land, ``Zone(polygons=land, inside=0.01)``. λ and birth densities divide by
    nothing here, but a clutter model needs both values > 0.
    """

    polygons: LandMask = Property(doc="The zone's polygons.")
    inside: float = Property(doc="The factor inside the polygons (≥ 0; > 0 in a clutter model).")
    outside: float = Property(default=1.0, doc="The factor outside them (≥ 0; > 0 in a clutter model).")

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        if not isinstance(self.polygons, LandMask):
            raise ArgumentTypeError("polygons", f"expected a LandMask, got {type(self.polygons).__name__}")
        self._compiled()

    def _compiled(self) -> _core.Zone:
        return self._cached("core", lambda: _core.Zone(
            self.polygons._compiled(), as_float(self.inside, "inside", finite=False),
            as_float(self.outside, "outside", finite=False)))

    def __call__(self, positions) -> np.ndarray:
        """The factor at world ``positions`` (M, 2)."""
        inside = self.polygons.contains(positions)
        return np.where(inside, float(self.inside), float(self.outside))
