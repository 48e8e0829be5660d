"""Real geography: longitude/latitude mapped to the trackers' local plane, the world's
shorelines as land, and real ship traffic.

- :mod:`ctxmodels.geo.plane`: longitude/latitude to east/north metres around an origin;
- :mod:`ctxmodels.geo.shorelines`: GSHHG shorelines for a box, as land polygons;
- :mod:`ctxmodels.geo.clip`: a polygon with holes clipped to a box;
- :mod:`ctxmodels.geo.ais`: AIS position reports read into per-vessel trajectories;
- :mod:`ctxmodels.geo.site`: a sensor at a real coastal site, with its land.
"""
from .plane import MAX_DISTANCE, WGS84_A, WGS84_F, lonlat_to_local, pyproj_available

__all__ = ["MAX_DISTANCE", "WGS84_A", "WGS84_F", "lonlat_to_local", "pyproj_available"]
