r"""Longitude/latitude to a local east–north frame in metres, for land data in WGS 84.

ctxmodels works in a flat x/y frame in metres (x east, y north, as the tracker's states).
Coastlines come in longitude/latitude (GeoJSON is WGS 84 by definition, RFC 7946).
:func:`lonlat_to_local` maps them to the *local tangent plane* at an origin: each point's
geodetic position (on the WGS 84 ellipsoid, height 0) to Earth-centred Cartesian
coordinates :math:`\mathbf{p}`, then

.. math::
    e = -\sin\lambda_0\,\Delta X + \cos\lambda_0\,\Delta Y, \qquad
    n = -\sin\varphi_0\cos\lambda_0\,\Delta X - \sin\varphi_0\sin\lambda_0\,\Delta Y
        + \cos\varphi_0\,\Delta Z,

with :math:`\Delta\mathbf{p} = \mathbf{p} - \mathbf{p}_0` and :math:`(\lambda_0, \varphi_0)`
the origin's longitude and latitude: east and north along the ellipsoid's tangent plane
(the "topocentric" frame; the up component is dropped). It has no seam at the
antimeridian. Distances from the origin along the plane fall short of the geodesic ones
by about :math:`d^2 / (6 R^2)` relative (4 mm at 10 km, 0.5 m at 50 km), so take an
origin near the scene.

With ``pyproj`` installed (``pip install "ctxmodels[geo]"``) PROJ computes it (its
``cart`` + ``topocentric`` pipeline); without, the same formulas in NumPy. The two agree
to well under a millimetre (tested).
"""
from __future__ import annotations

import numpy as np

from ._component import as_rows

#: WGS 84: semi-major axis (m) and flattening.
WGS84_A = 6378137.0
WGS84_F = 1.0 / 298.257223563
_E2 = WGS84_F * (2.0 - WGS84_F)


def _origin(origin) -> tuple[float, float]:
    try:
        lon, lat = (float(v) for v in origin)
    except (TypeError, ValueError):
        raise TypeError(f"origin: expected (longitude, latitude) in degrees, got {origin!r}") \
            from None
    if not (np.isfinite(lon) and np.isfinite(lat) and -180.0 <= lon <= 180.0
            and -90.0 < lat < 90.0):
        raise ValueError(f"origin: longitude must lie in [-180, 180] and latitude in "
                         f"(-90, 90) degrees, got ({lon}, {lat})")
    return lon, lat


def _cartesian(lon_deg, lat_deg) -> np.ndarray:
    """Earth-centred Cartesian coordinates (m) of points on the WGS 84 ellipsoid."""
    lon, lat = np.radians(lon_deg), np.radians(lat_deg)
    sin_lat = np.sin(lat)
    n = WGS84_A / np.sqrt(1.0 - _E2 * sin_lat * sin_lat)  # prime-vertical radius
    return np.stack([n * np.cos(lat) * np.cos(lon), n * np.cos(lat) * np.sin(lon),
                     n * (1.0 - _E2) * sin_lat], axis=-1)


def _numpy_local(lonlat: np.ndarray, lon0: float, lat0: float) -> np.ndarray:
    delta = _cartesian(lonlat[:, 0], lonlat[:, 1]) - _cartesian(lon0, lat0)
    sin_lon, cos_lon = np.sin(np.radians(lon0)), np.cos(np.radians(lon0))
    sin_lat, cos_lat = np.sin(np.radians(lat0)), np.cos(np.radians(lat0))
    east = -sin_lon * delta[:, 0] + cos_lon * delta[:, 1]
    north = (-sin_lat * cos_lon * delta[:, 0] - sin_lat * sin_lon * delta[:, 1]
             + cos_lat * delta[:, 2])
    return np.column_stack([east, north])


def _pyproj_local(lonlat: np.ndarray, lon0: float, lat0: float) -> np.ndarray:
    from pyproj import Transformer
    transformer = Transformer.from_pipeline(
        f"+proj=pipeline +step +proj=cart +ellps=WGS84 "
        f"+step +proj=topocentric +ellps=WGS84 +lon_0={lon0!r} +lat_0={lat0!r} +h_0=0")
    east, north, _ = transformer.transform(lonlat[:, 0], lonlat[:, 1], np.zeros(len(lonlat)))
    return np.column_stack([east, north])


def pyproj_available() -> bool:
    try:
        import pyproj  # noqa: F401
    except ImportError:
        return False
    return True


def lonlat_to_local(lonlat, origin, *, backend: str = "auto") -> np.ndarray:
    """(N, 2) east/north metres of ``lonlat`` (N, 2) [longitude, latitude] degrees on the
    local tangent plane at ``origin`` (longitude, latitude) — see the module docstring.

    ``backend``: ``'pyproj'``, ``'numpy'`` or ``'auto'`` (pyproj when installed)."""
    lon0, lat0 = _origin(origin)
    points = as_rows(lonlat, "lonlat", ncols=2)
    if not np.all(np.isfinite(points)):
        raise ValueError("lonlat: coordinates must be finite")
    outside = np.abs(points[:, 1]) > 90.0
    if np.any(outside):
        raise ValueError(f"lonlat: latitudes must lie in [-90, 90] degrees (longitude "
                         f"first, as GeoJSON), got {points[outside, 1][0]:g}")
    if backend == "auto":
        backend = "pyproj" if pyproj_available() else "numpy"
    if backend == "pyproj":
        return _pyproj_local(points, lon0, lat0)
    if backend == "numpy":
        return _numpy_local(points, lon0, lat0)
    raise ValueError(f"backend: must be 'auto', 'pyproj' or 'numpy', got {backend!r}")


__all__ = ["WGS84_A", "WGS84_F", "lonlat_to_local", "pyproj_available"]
