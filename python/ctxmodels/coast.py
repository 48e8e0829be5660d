r"""Coastal clutter: a clutter factor for the returns a radar gets from a shore.

A radar sees a shore as a line of returns, measured with its own noise, so they fall in a
band along the coastline. :class:`CoastalClutter` multiplies λ by ``inside`` there:

.. math::
    f(z; S) = \begin{cases} \text{inside} & d(z, \partial L) \le w
        \text{ and the nearest coastline point is seen from } S \\
        1 & \text{otherwise,} \end{cases}

with :math:`d(z, \partial L)` the distance from the detection's world position to the
nearest point of the :class:`~ctxmodels.LandMask`'s coastline (every ring: shores of
islands and of lakes), on either side, and :math:`w` the ``width``. "Seen" is the
simulation's and a radar's rule: the sight line from the sensor to that coastline point,
stopped 1 m short of it, crosses no land — the shore that faces the sensor, not the far
side of an island (``seen_only=False`` drops the condition).

A physical choice of the two numbers: ``width`` about two standard deviations of the
sensor's position error across the shore at the coast's range, and ``inside`` the ratio of
the shore returns' density in the band to the λ the other factors give there.
"""
from __future__ import annotations

import numpy as np
from stonesoup.base import Property

from . import _core
from ._component import ModelComponent, as_float, as_rows
from .land import LandMask
from .pose import Pose, pose_tuple


class CoastalClutter(ModelComponent):
    """λ × ``inside`` within ``width`` of a coastline the sensor sees (see the module
    docs); a factor of :class:`~ctxmodels.ClutterDensityModel`."""

    land: LandMask = Property(doc="The land whose coastline returns clutter.")
    width: float = Property(doc="Half-width (m, >= 0) of the band on each side of the coast.")
    inside: float = Property(doc="The factor in the band (> 0).")
    seen_only: bool = Property(default=True, doc="Only coast seen from the sensor (the sight "
                                                 "line to it crosses no land).")

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        if not isinstance(self.land, LandMask):
            raise TypeError(f"land: expected a LandMask, got {type(self.land).__name__}")
        if not isinstance(self.seen_only, (bool, np.bool_)):
            raise TypeError(f"seen_only: expected a bool, got {type(self.seen_only).__name__}")
        self._compiled()

    def _compiled(self) -> _core.CoastalBand:
        return self._cached("core", lambda: _core.CoastalBand(
            self.land._compiled(), as_float(self.width, "width", finite=False),
            as_float(self.inside, "inside", finite=False), bool(self.seen_only)))

    def evaluate(self, pose: Pose, positions) -> np.ndarray:
        """The factor at world ``positions`` (M, 2) for a sensor at ``pose``."""
        return self._compiled().evaluate(pose_tuple(pose), as_rows(positions, "positions", ncols=2))


__all__ = ["CoastalClutter"]
