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

Points farther than :data:`MAX_DISTANCE` (1000 km, great-circle on the mean Earth sphere)
from the origin are refused (``ValueError`` naming ``lonlat``): there the plane's distances
fall short by more than 0.4 % (4 km), and beyond a quarter of the Earth the plane folds
back — a point on the far side of the Earth would land on the origin. Clip the data to the
scene, or take an origin nearer it.

With ``pyproj`` installed (``pip install "ctxmodels[geo]"``) PROJ computes it (its
``cart`` + ``topocentric`` pipeline); without, the same formulas in NumPy. The two agree
to well under a millimetre (tested).
"""
from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from .._component import as_float, as_rows

#: WGS 84: semi-major axis (m) and flattening.
WGS84_A = 6378137.0
WGS84_F = 1.0 / 298.257223563
_E2 = WGS84_F * (2.0 - WGS84_F)
#: The mean Earth radius (IUGG, m): the sphere :data:`MAX_DISTANCE` is measured on.
MEAN_RADIUS = 6371008.8
#: Farthest great-circle distance (m) from the origin that :func:`lonlat_to_local` maps: the
#: plane's distances from the origin are short by at most 0.41 % there (1 - sin θ / θ).
MAX_DISTANCE = 1_000_000.0


def _origin(origin) -> tuple[float, float]:
    if isinstance(origin, (str, bytes, Mapping)) or not isinstance(origin, (Sequence, np.ndarray)):
        raise TypeError(f"origin: expected (longitude, latitude) in degrees, got {origin!r}")
    values = list(np.ravel(origin)) if isinstance(origin, np.ndarray) else list(origin)
    if len(values) != 2:
        raise TypeError(f"origin: expected (longitude, latitude) in degrees, got {origin!r}")
    lon, lat = (as_float(v, "origin", finite=False) for v in values)
    if not (np.isfinite(lon) and np.isfinite(lat) and -180.0 <= lon <= 180.0
            and -90.0 < lat < 90.0):
        raise ValueError(f"origin: longitude must lie in [-180, 180] and latitude in "
                         f"(-90, 90) degrees (the poles have no east), got ({lon}, {lat})")
    return lon, lat


def _central_angle(lon, lat, lon0: float, lat0: float) -> np.ndarray:
    """Great-circle angles (rad) from (lon0, lat0) to each point (haversine: accurate at
    every distance, antipodes included)."""
    phi, phi0 = np.radians(lat), np.radians(lat0)
    half = (np.sin((phi - phi0) / 2) ** 2
            + np.cos(phi) * np.cos(phi0) * np.sin(np.radians(lon - lon0) / 2) ** 2)
    return 2 * np.arcsin(np.sqrt(np.clip(half, 0.0, 1.0)))


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

    ``backend``: ``'pyproj'``, ``'numpy'`` or ``'auto'`` (pyproj when installed).

    Raises :class:`ValueError` naming ``lonlat`` for a NaN or infinite coordinate, a
    longitude outside [-180, 180], a latitude outside [-90, 90] and a point farther than
    :data:`MAX_DISTANCE` from the origin (the plane is only a local map; see the module
    docstring), whichever backend."""
    if backend not in ("auto", "pyproj", "numpy"):
        raise ValueError(f"backend: must be 'auto', 'pyproj' or 'numpy', got {backend!r}")
    if backend == "pyproj" and not pyproj_available():
        raise ValueError("backend: 'pyproj' needs pyproj installed "
                         "(pip install \"ctxmodels[geo]\"); or use 'numpy'")
    lon0, lat0 = _origin(origin)
    if isinstance(lonlat, (str, bytes, Mapping)):
        raise TypeError(f"lonlat: expected (N, 2) [longitude, latitude] rows, got "
                        f"{type(lonlat).__name__}")
    try:
        given = np.asarray(lonlat)
    except (TypeError, ValueError):  # ragged rows: as_rows names them
        given = None
    if given is not None and given.dtype == np.bool_:
        raise TypeError("lonlat: expected (N, 2) [longitude, latitude] degrees, got booleans")
    if given is not None and given.ndim == 1 and given.size == 0:
        lonlat = np.empty((0, 2))  # no points (an empty list)
    points = as_rows(lonlat, "lonlat", ncols=2)
    finite = np.isfinite(points).all(axis=1)
    if not finite.all():
        row = int(np.argmin(finite))
        raise ValueError(f"lonlat: coordinates must be finite, got {points[row].tolist()} "
                         f"in row {row}")
    bad_lat = np.abs(points[:, 1]) > 90.0
    if np.any(bad_lat):
        raise ValueError(f"lonlat: latitudes must lie in [-90, 90] degrees (longitude "
                         f"first, as GeoJSON), got {points[bad_lat, 1][0]:g}")
    bad_lon = np.abs(points[:, 0]) > 180.0
    if np.any(bad_lon):
        raise ValueError(f"lonlat: longitudes must lie in [-180, 180] degrees, got "
                         f"{points[bad_lon, 0][0]:g}")
    distance = MEAN_RADIUS * _central_angle(points[:, 0], points[:, 1], lon0, lat0)
    far = distance > MAX_DISTANCE
    if np.any(far):
        row = int(np.argmax(far))
        raise ValueError(
            f"lonlat: {points[row].tolist()} (row {row}) is {distance[row] / 1000:.0f} km from "
            f"the origin ({lon0}, {lat0}); the local plane maps points within MAX_DISTANCE = "
            f"{MAX_DISTANCE / 1000:.0f} km only (farther, it distorts distances by more than "
            f"0.4 % and folds the far side of the Earth back onto the origin): clip the data "
            f"to the scene or choose an origin nearer it")
    if len(points) == 0:
        return np.empty((0, 2))
    if backend == "auto":
        backend = "pyproj" if pyproj_available() else "numpy"
    if backend == "pyproj":
        return _pyproj_local(points, lon0, lat0)
    return _numpy_local(points, lon0, lat0)


__all__ = ["MAX_DISTANCE", "WGS84_A", "WGS84_F", "lonlat_to_local", "pyproj_available"]
