"""Land: polygon land masks (P_D 0 on land) and line-of-sight occlusion (radar shadow)."""
from __future__ import annotations

import json
import os
import re
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from stonesoup.base import Property

from . import _core
from ._component import ModelComponent, as_float, as_rows, frozen_copy


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
        node, document = _read_geojson(source)
        return _land_from_document(cls, node, document, origin)

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
        return _land_from_document(cls, geometry.__geo_interface__, _Document("geometry"),
                                   origin)

    @property
    def vertex_count(self) -> int:
        return self._compiled().vertex_count

    def contains(self, points) -> np.ndarray:
        """Whether each (x, y) row of ``points`` is on land (boundary included). A NaN or
        infinite row raises :class:`ValueError`."""
        return self._compiled().contains(as_rows(points, "points", ncols=2))


#: Deepest nesting of GeometryCollections (and Features) read: deeper is refused, not a
#: RecursionError.
_MAX_NESTING = 32


class _Document:
    """Where a GeoJSON document came from, to say where in it something is wrong: every
    message starts with the argument's name (``source``, or ``geometry`` for shapely), then
    the file's path if it is a file, then the JSON path inside the document."""

    def __init__(self, name: str, path: str | None = None):
        self.name, self.path = name, path

    def at(self, where: str) -> str:
        file = f"{self.path!r}: " if self.path is not None else ""
        return f"{self.name}: {file}{where or 'top level'}"

    def error(self, where: str, message: str) -> ValueError:
        return ValueError(f"{self.at(where)}: {message}")


def _read_geojson(source) -> tuple[Any, _Document]:
    """The parsed document of ``source`` (a mapping, JSON text, or a file path) and where
    it came from. Unreadable files and invalid JSON raise naming ``source``, the file and
    the line and column."""
    if isinstance(source, Mapping):
        return source, _Document("source")
    if isinstance(source, str) and source.lstrip().startswith(("{", "[")):
        return _parse_json(source, _Document("source")), _Document("source")
    if isinstance(source, str) and not source.strip():
        raise ValueError("source: is an empty string; expected a GeoJSON path, JSON text or "
                         "a parsed mapping")
    if isinstance(source, (str, os.PathLike)):
        path = os.fspath(source)
        if not isinstance(path, str):
            raise TypeError(f"source: expected a GeoJSON path, string or mapping, got the "
                            f"bytes path {path!r}")
        document = _Document("source", path)
        try:
            with open(path, encoding="utf-8") as stream:
                text = stream.read()
        except FileNotFoundError:
            raise FileNotFoundError(f"source: no such GeoJSON file: {path!r}") from None
        except UnicodeDecodeError as err:
            raise ValueError(f"source: {path!r}: not UTF-8 text (GeoJSON is UTF-8, RFC 7946): "
                             f"byte {err.start}: {err.reason}") from None
        except OSError as err:
            raise type(err)(f"source: cannot read {path!r}: {err.strerror or err}") from None
        return _parse_json(text, document), document
    raise TypeError(f"source: expected a GeoJSON path, string or mapping, got "
                    f"{type(source).__name__}")


def _parse_json(text: str, document: _Document) -> Any:
    try:
        return json.loads(text)
    except json.JSONDecodeError as err:
        file = f"{document.path!r}: " if document.path is not None else ""
        raise ValueError(f"{document.name}: {file}not valid JSON at line {err.lineno}, column "
                         f"{err.colno} (character {err.pos}): {err.msg}") from None
    except RecursionError:
        raise document.error("", "the JSON is nested too deeply to read") from None


def _is_list(value) -> bool:
    """A JSON array (or a tuple or array of a ``__geo_interface__``), not text."""
    return isinstance(value, (Sequence, np.ndarray)) and not isinstance(value, (str, bytes))


def _kind_of(node, where: str, document: _Document) -> str:
    if not isinstance(node, Mapping):
        raise document.error(where, f"expected a GeoJSON object, got {type(node).__name__} "
                                    f"{_short(node)}")
    kind = node.get("type")
    if not isinstance(kind, str):
        raise document.error(where, f"has no 'type' string (got {_short(kind)})")
    return kind


def _member(node: Mapping, key: str, where: str, document: _Document, what: str):
    if key not in node:
        raise document.error(where, f"a {node['type']} needs a '{key}' member ({what})")
    value = node[key]
    if not _is_list(value):
        raise document.error(_join(where, key), f"expected {what}, got "
                                                f"{type(value).__name__} {_short(value)}")
    return value


def _join(where: str, key: str) -> str:
    return f"{where}.{key}" if where else key


def _short(value) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


_GEOMETRIES = ("Polygon", "MultiPolygon", "GeometryCollection")
_OTHER_GEOMETRIES = ("Point", "MultiPoint", "LineString", "MultiLineString")


def _geojson_polygons(node, document: _Document, where: str = "",
                      depth: int = 0) -> list[tuple[str, list[np.ndarray]]]:
    """Every polygon of a GeoJSON object as (where it is, its rings as (K, 2) x/y arrays,
    shell first), in document order; anything else raises naming where it is."""
    if depth > _MAX_NESTING:
        raise document.error(where, f"nested more than {_MAX_NESTING} levels deep")
    kind = _kind_of(node, where, document)
    if kind == "FeatureCollection":
        if depth:
            raise document.error(where, "a FeatureCollection cannot be nested in another "
                                        "object")
        features = _member(node, "features", where, document, "a list of Features")
        out = []
        for i, feature in enumerate(features):
            at = _join(where, f"features[{i}]")
            if _kind_of(feature, at, document) != "Feature":
                raise document.error(at, f"expected a Feature, got {feature['type']!r}")
            out += _geojson_polygons(feature, document, at, depth + 1)
        return out
    if kind == "Feature":
        if "geometry" not in node:
            raise document.error(where, "a Feature needs a 'geometry' member (null for none)")
        geometry = node["geometry"]
        if geometry is None:
            return []  # a feature without a location: no land
        return _geometry(geometry, document, _join(where, "geometry"), depth + 1)
    return _geometry(node, document, where, depth)


def _geometry(node, document: _Document, where: str, depth: int) -> list:
    if depth > _MAX_NESTING:
        raise document.error(where, f"nested more than {_MAX_NESTING} levels deep")
    kind = _kind_of(node, where, document)
    if kind == "GeometryCollection":
        geometries = _member(node, "geometries", where, document, "a list of geometries")
        out = []
        for i, geometry in enumerate(geometries):
            out += _geometry(geometry, document, _join(where, f"geometries[{i}]"), depth + 1)
        return out
    if kind == "Polygon":
        rings = _member(node, "coordinates", where, document, "a list of linear rings")
        return _polygon(rings, document, _join(where, "coordinates"))
    if kind == "MultiPolygon":
        polygons = _member(node, "coordinates", where, document, "a list of polygons")
        out = []
        for i, rings in enumerate(polygons):
            at = _join(where, f"coordinates[{i}]")
            if not _is_list(rings):
                raise document.error(at, f"expected a polygon (a list of linear rings), got "
                                         f"{type(rings).__name__} {_short(rings)}")
            out += _polygon(rings, document, at)
        return out
    if kind in _OTHER_GEOMETRIES:
        raise document.error(where, f"expected Polygon or MultiPolygon land (or a Feature, "
                                    f"FeatureCollection or GeometryCollection of them), got "
                                    f"{kind!r}, which has no area")
    if kind in ("Feature", "FeatureCollection"):
        raise document.error(where, f"expected a geometry here, got a {kind}")
    raise document.error(where, f"expected Polygon or MultiPolygon land (or a Feature, "
                                f"FeatureCollection or GeometryCollection of them), got "
                                f"{kind!r}")


def _polygon(rings, document: _Document, where: str) -> list:
    """One polygon's rings (RFC 7946: linear rings of >= 4 positions, closed, the first the
    shell): as one (where, rings) entry; an empty polygon is none (as RFC 7946 allows)."""
    if len(rings) == 0:
        return []
    return [(where, [_linear_ring(ring, document, f"{where}[{k}]")
                     for k, ring in enumerate(rings)])]


def _linear_ring(ring, document: _Document, where: str) -> np.ndarray:
    if not _is_list(ring):
        raise document.error(where, f"expected a linear ring (a list of [x, y] positions), "
                                    f"got {type(ring).__name__} {_short(ring)}")
    xy = np.empty((len(ring), 2))
    for j, position in enumerate(ring):
        at = f"{where}[{j}]"
        if not _is_list(position) or len(position) < 2:
            raise document.error(at, f"expected a position [x, y] (or [x, y, z]), got "
                                     f"{_short(position)}; is the nesting right (a Polygon's "
                                     f"coordinates are a list of rings of positions)?")
        for c in (0, 1):
            value = position[c]
            if isinstance(value, (bool, np.bool_)) or not isinstance(
                    value, (int, float, np.integer, np.floating)):
                raise document.error(at, f"coordinates must be numbers, got {_short(value)}")
            xy[j, c] = float(value)
        if not (np.isfinite(xy[j, 0]) and np.isfinite(xy[j, 1])):
            raise document.error(at, f"coordinates must be finite, got {xy[j].tolist()}")
    if len(xy) < 4:
        raise document.error(where, f"a linear ring needs at least 4 positions (3 corners and "
                                    f"the first again), got {len(xy)}")
    if not np.array_equal(xy[0], xy[-1]):
        raise document.error(where, f"a linear ring must be closed (its last position equal "
                                    f"to its first, RFC 7946), got {xy[0].tolist()} ... "
                                    f"{xy[-1].tolist()}")
    return xy


def _land_from_document(cls, node, document: _Document, origin) -> LandMask:
    """The mask of a GeoJSON document's polygons, projected around ``origin``: errors in a
    polygon (from the projection or the mask's validation) name where it is."""
    if origin is not None:
        from .geo import _origin
        origin = _origin(origin)  # refused before the document is read, naming origin
    found = _geojson_polygons(node, document)
    if not found:
        raise document.error("", "holds no polygons (no land)")
    polygons = []
    for where, rings in found:
        if origin is not None:
            from .geo import lonlat_to_local
            projected = []
            for k, ring in enumerate(rings):
                try:
                    projected.append(lonlat_to_local(ring, origin))
                except ValueError as err:
                    raise document.error(f"{where}[{k}]", str(err)) from None
            rings = projected
        polygons.append({"shell": rings[0], "holes": rings[1:]})
    try:
        return cls(polygons=polygons)
    except ValueError as err:
        # "polygons: polygon 2 hole 0: ..." -> "source: <where polygon 2 is>[1]: ..."
        text = str(err)
        named = re.match(r"polygons: polygon (\d+)(?: (shell|hole (\d+))(?=:))?", text)
        if named is None or int(named.group(1)) >= len(found):
            raise
        where = found[int(named.group(1))][0]
        if named.group(2) is None:  # about the whole polygon
            raise document.error(where, text[len("polygons: "):]) from None
        ring = 0 if named.group(3) is None else int(named.group(3)) + 1
        raise document.error(f"{where}[{ring}]",
                             f"{named.group(2)}{text[named.end():]}") from None


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
        if isinstance(sensor, (str, bytes, Mapping)) or not isinstance(sensor, (Sequence, np.ndarray)):
            raise TypeError(f"sensor: expected a finite (x, y) position, got {sensor!r}")
        values = list(np.ravel(sensor)) if isinstance(sensor, np.ndarray) else list(sensor)
        if len(values) != 2:
            raise ValueError(f"sensor: must be a finite (x, y) position, got {sensor!r}")
        x, y = (as_float(v, "sensor") for v in values)
        return self._compiled().visible((x, y),
                                        as_rows(targets, "targets", ncols=2))
