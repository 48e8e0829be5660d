"""Land: polygon land masks (P_D 0 on land) and line-of-sight occlusion (radar shadow)."""
from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from stonesoup.base import Property

from . import _core
from ._component import ModelComponent, as_float, as_rows, frozen_copy
from ._geojson import Document, land_from_document, read_geojson
from .errors import ArgumentError


def _ring(ring: Any, where: str) -> np.ndarray:
    if isinstance(ring, (str, bytes, Mapping)):
        raise TypeError(f"polygons: {where}: expected (K, 2) vertices, got {type(ring).__name__}")
    try:
        is_bool = np.asarray(ring).dtype == np.bool_
    except (TypeError, ValueError):  # ragged: as_rows names it
        is_bool = False
    if is_bool:
        raise TypeError(f"polygons: {where}: expected (K, 2) vertices in metres, got booleans")
    return frozen_copy(as_rows(ring, f"polygons: {where}", ncols=2))


def _normalise_polygon(polygon: Any, index: int) -> dict:
    """One polygon as ``{'shell': (K, 2) array, 'holes': [(K, 2) arrays]}``."""
    if hasattr(polygon, "exterior") and hasattr(polygon, "interiors"):  # shapely Polygon
        shell, holes = polygon.exterior.coords, [h.coords for h in polygon.interiors]
    elif isinstance(polygon, Mapping):
        if "shell" not in polygon:
            raise ValueError(f"polygons: polygon {index} is a mapping without a 'shell' key")
        shell, holes = polygon["shell"], polygon.get("holes", ())
    elif isinstance(polygon, (str, bytes)) or polygon is None:
        raise TypeError(f"polygons: polygon {index} must be a (K, 2) vertex array, a (shell, "
                        f"holes) pair, a {{'shell': ..., 'holes': [...]}} mapping or a shapely "
                        f"Polygon, got {type(polygon).__name__}")
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
    if isinstance(holes, (str, bytes, Mapping)) or not isinstance(holes, (Sequence, np.ndarray)):
        raise TypeError(f"polygons: polygon {index} holes: expected a sequence of (K, 2) rings, "
                        f"got {type(holes).__name__}")
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

    @classmethod
    def from_geojson(cls, source, origin=None) -> LandMask:
        """Land from GeoJSON: a file path, a JSON string or a parsed mapping holding a
        FeatureCollection, Feature, GeometryCollection, Polygon or MultiPolygon (every
        polygon with its holes; other geometry types raise, naming where they are).

        GeoJSON positions are [longitude, latitude] degrees (RFC 7946): give ``origin``
        (longitude, latitude) and they are mapped to east/north metres around it
        (:func:`ctxmodels.geo.lonlat_to_local`). Without ``origin`` the positions are taken
        as x/y metres already (a projected file).

        The whole document is checked as RFC 7946 has it: each linear ring a list of at least
        four [x, y] (or [x, y, z]) positions of finite numbers, closed (the last position
        repeats the first); a Feature's ``geometry`` null is no land; an empty
        ``coordinates`` array is an empty geometry. Anything else — a missing member, a
        wrong type or nesting, a non-land geometry, invalid JSON — raises
        :class:`ValueError` whose message starts ``source:``, then the file's path (for a
        file), then where in the document, e.g.
        ``source: features[3].geometry.coordinates[0][2]: coordinates must be finite`` (for
        invalid JSON, the line and column). A missing file raises
        :class:`FileNotFoundError`."""
        node, document = read_geojson(source)
        return land_from_document(cls, node, document, origin)

    @classmethod
    def from_shapely(cls, geometry, origin=None) -> LandMask:
        """Land from a shapely Polygon, MultiPolygon or GeometryCollection of polygons, with
        holes. An invalid geometry raises :class:`ValueError` with shapely's reason. With
        ``origin`` (longitude, latitude) the coordinates are longitude/latitude degrees,
        mapped to east/north metres as in :meth:`from_geojson`."""
        try:
            import shapely
        except ImportError:  # pragma: no cover - shapely is what the caller passes
            raise TypeError("geometry: from_shapely needs shapely installed") from None
        if not isinstance(geometry, shapely.Geometry):
            raise TypeError(f"geometry: expected a shapely geometry, got "
                            f"{type(geometry).__name__}")
        if not geometry.is_valid:
            from shapely.validation import explain_validity
            raise ValueError(f"geometry: invalid ({explain_validity(geometry)})")
        return land_from_document(cls, geometry.__geo_interface__, Document("geometry"),
                                   origin)

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
    islands.

    With ``clearance`` :math:`c = 0` the sensor is taken to be at sea (from a sensor on land
    every target is shadowed). A coastal radar stands on land, on a mast or a cliff top
    that looks over the land around it: with :math:`c > 0` the segment tested starts at
    :math:`s + c\,(t - s)/\lVert t - s\rVert` instead of at the sensor :math:`s`, so land
    within :math:`c` of the sensor blocks nothing and the land beyond it (the rest of its
    own island, the headlands along the coast) still does. A target within :math:`c` is
    shadowed only by standing on land. Without heights in the land data this is a 2-D
    stand-in for the antenna's view down over the coast, to choose per site.

    Each query is a ray cast through a bounding-volume hierarchy over the coastline edges
    (parry), :math:`O(\log E)` per target.
    """

    land: LandMask = Property(doc="The land that blocks the view.")
    clearance: float = Property(
        default=0.0,
        doc="Land within this distance (metres) of the sensor blocks nothing (≥ 0; 0: the "
            "sensor is at sea).")

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        if not isinstance(self.land, LandMask):
            raise TypeError(f"land: expected a LandMask, got {type(self.land).__name__}")
        clearance = as_float(self.clearance, "clearance")
        if not clearance >= 0.0:
            raise ArgumentError("clearance", f"must be a distance >= 0 metres, got {clearance}")
        self._replace("clearance", clearance)

    def _compiled(self) -> _core.LineOfSight:
        return self._cached("core", lambda: _core.LineOfSight(self.land._compiled(), self.clearance))

    def visible(self, sensor, targets) -> np.ndarray:
        """Whether each (x, y) row of ``targets`` is visible from ``sensor`` (x, y). A NaN
        or infinite row raises :class:`ValueError`."""
        if isinstance(sensor, (str, bytes, Mapping)) or not isinstance(sensor, (Sequence, np.ndarray)):
            raise TypeError(f"sensor: expected a finite (x, y) position, got {sensor!r}")
        values = list(np.ravel(sensor)) if isinstance(sensor, np.ndarray) else list(sensor)
        if len(values) != 2:
            raise ValueError(f"sensor: must be a finite (x, y) position, got {sensor!r}")
        x, y = (as_float(v, "sensor") for v in values)
        return self._compiled().visible((x, y),
                                        as_rows(targets, "targets", ncols=2))
