r"""A sensor at a real coastal site: its position in the local plane, the land around it from
the GSHHG shorelines, and the line of sight it has over that land.

A coastal radar stands on land — a mast on a fort, a cliff top — and looks out over the
sea. The shorelines have no heights, so the view over the land near the antenna is a
*clearance* (:class:`ctxmodels.LineOfSight`): land within it blocks nothing; the land
beyond (the rest of the island, the headlands along the coast) still casts its shadow.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._component import as_float
from ..errors import ArgumentError
from ..land import LandMask, LineOfSight
from .plane import _origin, lonlat_to_local
from .shorelines import shoreline_polygons

#: metres per degree of latitude (mean): for a box of the right size around a site
METRES_PER_DEGREE = 111_195.0


def box_around(lonlat, half_width: float) -> tuple[float, float, float, float]:
    """A (lon_min, lat_min, lon_max, lat_max) box that holds every point within
    ``half_width`` metres east or north of ``lonlat`` (with 2 % to spare). A box that would
    cross the antimeridian or come within a degree of a pole is refused, naming ``lonlat``."""
    lon, lat = _origin(lonlat)
    half_width = as_float(half_width, "half_width")
    if not half_width > 0:
        raise ArgumentError("half_width", f"must be a distance > 0 metres, got {half_width}")
    dlat = 1.02 * half_width / METRES_PER_DEGREE
    north = abs(lat) + dlat
    if north >= 89.0:
        raise ArgumentError("lonlat", f"{half_width:g} m around ({lon}, {lat}) comes within a "
                                      f"degree of a pole")
    dlon = 1.02 * half_width / (METRES_PER_DEGREE * np.cos(np.radians(north)))
    if lon - dlon < -180.0 or lon + dlon > 180.0:
        raise ArgumentError("lonlat", f"{half_width:g} m around ({lon}, {lat}) crosses the "
                                      f"antimeridian, which the shorelines' boxes do not")
    return lon - dlon, lat - dlat, lon + dlon, lat + dlat


def shore_distance(polygons, point) -> float:
    """Distance (m) from ``point`` (x, y) to the nearest edge of the polygons' rings."""
    best = np.inf
    p = np.asarray(point, dtype=np.float64)
    for polygon in polygons:
        for ring in [polygon["shell"], *polygon["holes"]]:
            a = np.asarray(ring, dtype=np.float64)
            b = np.roll(a, -1, axis=0)
            ab = b - a
            length2 = np.einsum("ij,ij->i", ab, ab)
            t = np.clip(np.einsum("ij,ij->i", p - a, ab) / np.where(length2 > 0, length2, 1.0), 0, 1)
            nearest = a + t[:, None] * ab
            best = min(best, float(np.min(np.hypot(*(nearest - p).T))))
    return best


@dataclass(frozen=True, eq=False)
class CoastalSite:
    """A site (longitude, latitude) in the plane of ``origin``: ``position`` (x, y) metres,
    the ``land`` of the shorelines around, whether the site stands on it (``on_land``) and
    how far it is from the nearest shore (``shore_distance``, m)."""

    lonlat: tuple[float, float]
    origin: tuple[float, float]
    position: tuple[float, float]
    land: LandMask | None  # None: no land around (open sea)
    on_land: bool
    shore_distance: float  # inf without land

    def line_of_sight(self, clearance: float) -> LineOfSight | None:
        """Line of sight over the site's land, land within ``clearance`` (m) of the antenna
        blocking nothing (None without land: nothing blocks)."""
        return None if self.land is None else LineOfSight(land=self.land, clearance=clearance)


def coastal_site(lonlat, half_width: float, origin=None, resolution: str = "f",
                 land: LandMask | None = None) -> CoastalSite:
    """The site at ``lonlat`` with the shorelines within ``half_width`` metres of it, in the
    plane of ``origin`` (the site itself by default). Several sites of one scene share one
    ``land`` (already in ``origin``'s plane): pass it and no shorelines are read."""
    lonlat = _origin(lonlat)
    origin = _origin(origin) if origin is not None else lonlat
    if land is None:
        polygons = shoreline_polygons(box_around(lonlat, half_width), origin, resolution)
        land = LandMask(polygons=polygons) if polygons else None
    position = lonlat_to_local([lonlat], origin)[0]
    on_land = land is not None and bool(land.contains(position[None, :])[0])
    distance = shore_distance(land.polygons, position) if land is not None else np.inf
    return CoastalSite(lonlat=lonlat, origin=origin, position=(float(position[0]), float(position[1])),
                       land=land, on_land=on_land, shore_distance=distance)


__all__ = ["METRES_PER_DEGREE", "CoastalSite", "box_around", "coastal_site", "shore_distance"]
