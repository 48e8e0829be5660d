"""Land: polygon land masks (P_D 0 on land) and line-of-sight occlusion (radar shadow)."""
from __future__ import annotations

import json
import os
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

    @classmethod
    def from_geojson(cls, source, origin=None) -> "LandMask":
        """Land from GeoJSON: a file path, a JSON string or a parsed mapping holding a
        FeatureCollection, Feature, GeometryCollection, Polygon or MultiPolygon (every
        polygon with its holes; other geometry types raise, naming where they are).

        GeoJSON positions are [longitude, latitude] degrees (RFC 7946): give ``origin``
        (longitude, latitude) and they are mapped to east/north metres around it
        (:func:`ctxmodels.geo.lonlat_to_local`). Without ``origin`` the positions are taken
        as x/y metres already (a projected file)."""
        return cls(polygons=_project(_geojson_polygons(_read_geojson(source)), origin))

    @classmethod
    def from_shapely(cls, geometry, origin=None) -> "LandMask":
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
        return cls(polygons=_project(_geojson_polygons(geometry.__geo_interface__), origin))

    @property
    def vertex_count(self) -> int:
        return self._compiled().vertex_count

    def contains(self, points) -> np.ndarray:
        """Whether each (x, y) row of ``points`` is on land (boundary included). A NaN or
        infinite row raises :class:`ValueError`."""
        return self._compiled().contains(as_rows(points, "points", ncols=2))


def _read_geojson(source) -> Mapping:
    if isinstance(source, Mapping):
        return source
    if isinstance(source, (str, os.PathLike)):
        text = str(source)
        if isinstance(source, str) and text.lstrip().startswith("{"):
            return json.loads(text)
        with open(source, encoding="utf-8") as stream:
            return json.load(stream)
    raise TypeError(f"source: expected a GeoJSON path, string or mapping, got "
                    f"{type(source).__name__}")


def _geojson_polygons(geojson: Mapping, where: str = "source") -> list[list]:
    """Every polygon of a GeoJSON object as a list of rings (shell first), in file order."""
    kind = geojson.get("type") if isinstance(geojson, Mapping) else None
    if kind == "FeatureCollection":
        return [p for i, feature in enumerate(geojson.get("features", []))
                for p in _geojson_polygons(feature, f"{where} feature {i}")]
    if kind == "Feature":
        geometry = geojson.get("geometry")
        return [] if geometry is None else _geojson_polygons(geometry, where)
    if kind == "GeometryCollection":
        return [p for i, g in enumerate(geojson.get("geometries", []))
                for p in _geojson_polygons(g, f"{where} geometry {i}")]
    if kind == "Polygon":
        return [geojson["coordinates"]]
    if kind == "MultiPolygon":
        return list(geojson["coordinates"])
    raise ValueError(f"{where}: expected Polygon or MultiPolygon land (or a Feature, "
                     f"FeatureCollection or GeometryCollection of them), got {kind!r}")


def _project(polygons: list[list], origin) -> list[dict]:
    """Rings as (K, 2) x/y arrays (the first two coordinates of each position), mapped
    from longitude/latitude around ``origin`` when one is given."""
    from .geo import lonlat_to_local

    out = []
    for i, rings in enumerate(polygons):
        if not rings:
            raise ValueError(f"polygons: polygon {i} has no rings")
        arrays = []
        for k, ring in enumerate(rings):
            try:
                xy = np.array([position[:2] for position in ring], dtype=np.float64)
            except (TypeError, ValueError, IndexError):
                raise ValueError(f"polygons: polygon {i} ring {k} is not a list of "
                                 f"[x, y] positions") from None
            if xy.ndim != 2 or xy.shape[1] != 2:
                raise ValueError(f"polygons: polygon {i} ring {k} is not a list of "
                                 f"[x, y] positions")
            arrays.append(xy if origin is None else lonlat_to_local(xy, origin))
        out.append({"shell": arrays[0], "holes": arrays[1:]})
    return out


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
