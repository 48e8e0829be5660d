"""Land: polygon land masks (P_D 0 on land) and line-of-sight occlusion (radar shadow)."""
from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from stonesoup.base import Property

from . import _core
from ._component import ModelComponent, as_rows, frozen_copy


def _ring(ring: Any, where: str) -> np.ndarray:
    return frozen_copy(as_rows(ring, f"polygons: {where}", ncols=2))


def _normalise_polygon(polygon: Any, index: int) -> dict:
    """One polygon as ``{'shell': (K, 2) array, 'holes': [(K, 2) arrays]}``."""
    if hasattr(polygon, "exterior") and hasattr(polygon, "interiors"):  # shapely Polygon
        shell, holes = polygon.exterior.coords, [h.coords for h in polygon.interiors]
    elif isinstance(polygon, Mapping):
        if "shell" not in polygon:
            raise ValueError(f"polygons: polygon {index} is a mapping without a 'shell' key")
        shell, holes = polygon["shell"], polygon.get("holes", ())
    else:
        as_array = None
        try:
            as_array = np.asarray(polygon, dtype=np.float64)
        except (ValueError, TypeError):
            pass
        if as_array is not None and as_array.ndim == 2:
            shell, holes = polygon, ()
        elif isinstance(polygon, Sequence) and len(polygon) == 2:
            shell, holes = polygon
        else:
            raise ValueError(
                f"polygons: polygon {index} must be a (K, 2) vertex array, a (shell, holes) pair, "
                f"a {{'shell': ..., 'holes': [...]}} mapping or a shapely Polygon")
    return {
        "shell": _ring(shell, f"polygon {index} shell"),
        "holes": [_ring(h, f"polygon {index} hole {k}") for k, h in enumerate(holes)],
    }


def normalise_polygons(polygons: Any) -> list[dict]:
    """Polygons in every accepted form (also a shapely MultiPolygon) as plain mappings."""
    if hasattr(polygons, "geoms"):  # shapely MultiPolygon / GeometryCollection
        polygons = list(polygons.geoms)
    elif hasattr(polygons, "exterior"):
        polygons = [polygons]
    if isinstance(polygons, (str, bytes)) or not isinstance(polygons, Sequence):
        raise TypeError(f"polygons: expected a sequence of polygons, got {type(polygons).__name__}")
    return [_normalise_polygon(p, i) for i, p in enumerate(polygons)]


class LandMask(ModelComponent):
    r"""Land as polygons with holes: the factor is 0 on land (boundary included), 1 at sea.

    Rings may be in any orientation, closed or not; consecutive duplicate vertices are
    dropped. The mask is validated when built — rings with fewer than three distinct
    vertices, zero area, self-intersections, touching rings, holes outside their shell and
    overlapping polygons raise :class:`ValueError` naming the polygon and ring.

    Coordinates are world x/y metres, the same frame as the tracker's states.
    """

    polygons: Sequence[Mapping] = Property(
        doc="Land polygons: each a (K, 2) vertex array, a (shell, holes) pair, a "
            "``{'shell': ..., 'holes': [...]}`` mapping or a shapely Polygon (a MultiPolygon "
            "is accepted for the whole). Stored as a tuple of ``{'shell': array, 'holes': "
            "(arrays,)}`` with read-only float64 arrays.")

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._replace("polygons", normalise_polygons(self.polygons))
        self._compiled()

    def _compiled(self) -> _core.LandMask:
        return self._cached("core", lambda: _core.LandMask(
            [(p["shell"], list(p["holes"])) for p in self.polygons]))

    @property
    def vertex_count(self) -> int:
        return self._compiled().vertex_count

    def contains(self, points) -> np.ndarray:
        """Whether each (x, y) row of ``points`` is on land (boundary included). A NaN or
        infinite row raises :class:`ValueError`."""
        return self._compiled().contains(as_rows(points, "points", ncols=2))


class LineOfSight(ModelComponent):
    r"""Occlusion by land: the factor is 0 when the straight segment from the sensor to the
    target meets land (grazing a coastline counts), 1 otherwise — radar shadow behind
    islands. The sensor is assumed to be at sea.

    Each query is a ray cast through a bounding-volume hierarchy over the coastline edges
    (parry), :math:`O(\log E)` per target.
    """

    land: LandMask = Property(doc="The land that blocks the view.")

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        if not isinstance(self.land, LandMask):
            raise TypeError(f"land: expected a LandMask, got {type(self.land).__name__}")

    def _compiled(self) -> _core.LineOfSight:
        return self._cached("core", lambda: _core.LineOfSight(self.land._compiled()))

    def visible(self, sensor, targets) -> np.ndarray:
        """Whether each (x, y) row of ``targets`` is visible from ``sensor`` (x, y). A NaN
        or infinite row raises :class:`ValueError`."""
        sensor = np.asarray(sensor, dtype=np.float64).ravel()
        if sensor.shape != (2,) or not np.all(np.isfinite(sensor)):
            raise ValueError(f"sensor: must be a finite (x, y) position, got {sensor}")
        return self._compiled().visible((float(sensor[0]), float(sensor[1])),
                                        as_rows(targets, "targets", ncols=2))
