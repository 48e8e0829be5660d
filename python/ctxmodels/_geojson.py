"""Reading GeoJSON into land polygons, for :meth:`ctxmodels.LandMask.from_geojson` and
:meth:`~ctxmodels.LandMask.from_shapely`: the document walked (FeatureCollection, Feature,
GeometryCollection, Polygon, MultiPolygon; nesting bounded), each ring checked and, with an
origin, projected to local metres, and every error naming where in the document it is (the
argument, the file, the JSON path).
"""
from __future__ import annotations

import json
import os
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from .errors import InvalidLandError

#: Deepest nesting of GeometryCollections (and Features) read: deeper is refused, not a
#: RecursionError.
_MAX_NESTING = 32


class Document:
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


def read_geojson(source) -> tuple[Any, Document]:
    """The parsed document of ``source`` (a mapping, JSON text, or a file path) and where
    it came from. Unreadable files and invalid JSON raise naming ``source``, the file and
    the line and column."""
    if isinstance(source, Mapping):
        return source, Document("source")
    if isinstance(source, str) and source.lstrip().startswith(("{", "[")):
        return _parse_json(source, Document("source")), Document("source")
    if isinstance(source, str) and not source.strip():
        raise ValueError("source: is an empty string; expected a GeoJSON path, JSON text or "
                         "a parsed mapping")
    if isinstance(source, (str, os.PathLike)):
        path = os.fspath(source)
        if not isinstance(path, str):
            raise TypeError(f"source: expected a GeoJSON path, string or mapping, got the "
                            f"bytes path {path!r}")
        document = Document("source", path)
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


def _parse_json(text: str, document: Document) -> Any:
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


def _kind_of(node, where: str, document: Document) -> str:
    if not isinstance(node, Mapping):
        raise document.error(where, f"expected a GeoJSON object, got {type(node).__name__} "
                                    f"{_short(node)}")
    kind = node.get("type")
    if not isinstance(kind, str):
        raise document.error(where, f"has no 'type' string (got {_short(kind)})")
    return kind


def _member(node: Mapping, key: str, where: str, document: Document, what: str):
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


def _geojson_polygons(node, document: Document, where: str = "",
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


def _geometry(node, document: Document, where: str, depth: int) -> list:
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


def _polygon(rings, document: Document, where: str) -> list:
    """One polygon's rings (RFC 7946: linear rings of >= 4 positions, closed, the first the
    shell): as one (where, rings) entry; an empty polygon is none (as RFC 7946 allows)."""
    if len(rings) == 0:
        return []
    return [(where, [_linear_ring(ring, document, f"{where}[{k}]")
                     for k, ring in enumerate(rings)])]


def _linear_ring(ring, document: Document, where: str) -> np.ndarray:
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


def land_from_document(cls, node, document: Document, origin) :
    """The mask of a GeoJSON document's polygons, projected around ``origin``: errors in a
    polygon (from the projection or the mask's validation) name where it is."""
    if origin is not None:
        from .geo.plane import _origin
        origin = _origin(origin)  # refused before the document is read, naming origin
    found = _geojson_polygons(node, document)
    if not found:
        raise document.error("", "holds no polygons (no land)")
    polygons = []
    for where, rings in found:
        if origin is not None:
            from .geo.plane import lonlat_to_local
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
    except InvalidLandError as err:
        # polygon 2's hole 0 -> "source: <where polygon 2 is>[1]: hole 0: ..."
        if err.polygon >= len(found):
            raise
        where = found[err.polygon][0]
        if err.ring is None:  # about the whole polygon
            raise document.error(where, err.detail) from None
        raise document.error(f"{where}[{err.ring}]", f"{err.ring_name}: {err.problem}") from None
