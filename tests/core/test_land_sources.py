"""Land from real data: ``LandMask.from_shapely`` and ``LandMask.from_geojson`` (files,
strings, mappings; Polygons, MultiPolygons with holes, features and collections), and
longitude/latitude mapped to a local east/north frame (ctxmodels.geo), each held against
an independent reference: shapely's containment on ≥ 10⁴ points, PROJ's pipeline and
geodesic distances."""
from __future__ import annotations

import json
import math
import pickle

import numpy as np
import pytest
import shapely
from pyproj import Geod
from shapely.geometry import MultiPolygon, Polygon, mapping

from ctxmodels import LandMask
from ctxmodels.geo import lonlat_to_local

RNG_SEED = 20261123


def _star(cx, cy, radius, n, rng, jitter=0.35):
    """A star-shaped ring around (cx, cy): valid (simple) for any radii > 0."""
    angles = np.sort(rng.uniform(0, 2 * math.pi, n))
    radii = radius * (1 - jitter + jitter * rng.random(n))
    return np.column_stack([cx + radii * np.cos(angles), cy + radii * np.sin(angles)])


def _islands(rng) -> MultiPolygon:
    """Three islands, two with holes (lagoons), and a small island inside one lagoon."""
    big = Polygon(_star(0, 0, 1000, 60, rng), [_star(0, 0, 300, 25, rng, 0.2),
                                               _star(550, 0, 120, 12, rng, 0.2)])
    other = Polygon(_star(2600, 900, 700, 40, rng), [_star(2600, 900, 250, 18, rng, 0.2)])
    plain = Polygon(_star(-2200, -1500, 500, 30, rng))
    inner = Polygon(_star(0, 0, 120, 10, rng, 0.2))  # inside big's first hole
    geometry = MultiPolygon([big, other, plain, inner])
    assert geometry.is_valid
    return geometry


def _query_points(geometry, n, rng):
    """n uniform points over the bounds, plus every vertex (boundary: land) and points one
    metre either side of edge midpoints."""
    x0, y0, x1, y1 = geometry.bounds
    points = [np.column_stack([rng.uniform(x0 - 100, x1 + 100, n),
                               rng.uniform(y0 - 100, y1 + 100, n)])]
    for polygon in geometry.geoms:
        for ring in [polygon.exterior, *polygon.interiors]:
            xy = np.asarray(ring.coords)
            points.append(xy)
            mid = (xy[:-1] + xy[1:]) / 2
            d = xy[1:] - xy[:-1]
            normal = np.column_stack([-d[:, 1], d[:, 0]]) / np.hypot(d[:, 0], d[:, 1])[:, None]
            points += [mid + normal, mid - normal]
    return np.vstack(points)


def _agree_with_shapely(mask, geometry, points):
    ours = mask.contains(points)
    theirs = shapely.intersects_xy(geometry, points[:, 0], points[:, 1])  # boundary = land
    assert np.array_equal(ours, theirs), f"{int((ours != theirs).sum())} disagree"
    assert 0.05 < ours.mean() < 0.95  # both land and sea were asked about


def test_from_shapely_multipolygon_with_holes_matches_shapely():
    rng = np.random.default_rng(RNG_SEED)
    geometry = _islands(rng)
    mask = LandMask.from_shapely(geometry)
    assert len(mask.polygons) == 4 and [len(p["holes"]) for p in mask.polygons] == [2, 1, 0, 0]
    points = _query_points(geometry, 20_000, rng)
    assert len(points) >= 10_000
    _agree_with_shapely(mask, geometry, points)
    # A single Polygon works too, and the mask is an ordinary component.
    single = LandMask.from_shapely(geometry.geoms[0])
    _agree_with_shapely(single, geometry.geoms[0], points)
    assert pickle.loads(pickle.dumps(mask)) == mask


def test_from_geojson_file_string_mapping_and_features_match_shapely(tmp_path):
    rng = np.random.default_rng(RNG_SEED + 1)
    geometry = _islands(rng)
    points = _query_points(geometry, 12_000, rng)
    as_mapping = mapping(geometry)
    path = tmp_path / "coast.geojson"
    features = {"type": "FeatureCollection", "features": [
        {"type": "Feature", "properties": {"name": "two"},
         "geometry": mapping(MultiPolygon(list(geometry.geoms)[:2]))},
        {"type": "Feature", "properties": {}, "geometry": None},
        {"type": "Feature", "properties": {"name": "rest"},
         "geometry": {"type": "GeometryCollection", "geometries": [
             mapping(g) for g in list(geometry.geoms)[2:]]}}]}
    path.write_text(json.dumps(features))
    sources = [as_mapping, json.dumps(as_mapping), path, str(path), features]
    masks = [LandMask.from_geojson(source) for source in sources]
    for mask in masks:
        _agree_with_shapely(mask, geometry, points)
    assert all(m == masks[0] for m in masks)  # same polygons, whatever the container


def test_lonlat_coastline_is_mapped_around_the_origin():
    """An antimeridian-free coast near Oslo given in longitude/latitude: the mask built with
    an origin holds exactly what shapely holds for the same polygon mapped the same way,
    and the mapping keeps geodesic distances to the origin (PROJ's Geod) within 1 mm."""
    rng = np.random.default_rng(RNG_SEED + 2)
    origin = (10.6, 59.85)
    metres = _islands(rng)  # the same shapes, drawn in metres, then made lon/lat
    scale = np.array([1 / (111_320 * math.cos(math.radians(origin[1]))), 1 / 111_000])

    def to_lonlat(xy):
        return np.asarray(xy) * scale + origin

    lonlat = MultiPolygon([Polygon(to_lonlat(p.exterior.coords),
                                   [to_lonlat(h.coords) for h in p.interiors])
                           for p in metres.geoms])
    assert lonlat.is_valid
    mask = LandMask.from_geojson(mapping(lonlat), origin=origin)
    local = MultiPolygon([Polygon(lonlat_to_local(np.asarray(p.exterior.coords), origin),
                                  [lonlat_to_local(np.asarray(h.coords), origin)
                                   for h in p.interiors]) for p in lonlat.geoms])
    query = lonlat_to_local(to_lonlat(_query_points(metres, 15_000, rng)), origin)
    _agree_with_shapely(mask, local, query)
    assert LandMask.from_shapely(lonlat, origin=origin) == mask
    # distances from the origin: planar against geodesic
    sample = to_lonlat(_query_points(metres, 200, rng))
    _, _, geodesic = Geod(ellps="WGS84").inv(np.full(len(sample), origin[0]),
                                             np.full(len(sample), origin[1]),
                                             sample[:, 0], sample[:, 1])
    planar = np.hypot(*lonlat_to_local(sample, origin).T)
    assert geodesic.max() > 2000
    np.testing.assert_allclose(planar, geodesic, rtol=0, atol=1e-3)


@pytest.mark.parametrize("origin", [(10.6, 59.85), (-179.95, -16.9), (45.0, 78.0), (0.0, 0.0)])
def test_numpy_and_proj_give_the_same_local_frame(origin):
    """The documented fallback equals PROJ's cart + topocentric pipeline, also across the
    antimeridian (no seam) and at high latitude."""
    rng = np.random.default_rng(RNG_SEED + 3)
    lon = (origin[0] + rng.uniform(-0.3, 0.3, 10_000) + 180.0) % 360.0 - 180.0
    lat = origin[1] + rng.uniform(-0.2, 0.2, 10_000)
    points = np.column_stack([lon, lat])
    ours = lonlat_to_local(points, origin, backend="numpy")
    proj = lonlat_to_local(points, origin, backend="pyproj")
    np.testing.assert_allclose(ours, proj, rtol=0, atol=1e-6)
    assert np.abs(ours).max() > 5_000
    np.testing.assert_array_equal(lonlat_to_local([origin], origin, backend="numpy"), [[0, 0]])


def test_bad_land_sources_raise_naming_what_is_wrong(tmp_path):
    bow_tie = Polygon([(0, 0), (10, 10), (10, 0), (0, 10)])
    with pytest.raises(ValueError, match="geometry: invalid .*[Ss]elf-intersection"):
        LandMask.from_shapely(bow_tie)
    with pytest.raises(TypeError, match="geometry: expected a shapely geometry"):
        LandMask.from_shapely([[0, 0], [1, 0], [0, 1]])
    collection = {"type": "FeatureCollection", "features": [
        {"type": "Feature", "geometry": mapping(Polygon([(0, 0), (1, 0), (0, 1)]))},
        {"type": "Feature", "geometry": {"type": "Point", "coordinates": [0, 0]}}]}
    with pytest.raises(ValueError, match=r"^source: features\[1\]\.geometry: .*got 'Point'"):
        LandMask.from_geojson(collection)
    with pytest.raises(ValueError, match=r"^source: coordinates\[0\]\[0\]: expected a position"):
        LandMask.from_geojson({"type": "Polygon", "coordinates": [[[0], [1], [2]]]})
    with pytest.raises(TypeError, match="source: expected a GeoJSON path"):
        LandMask.from_geojson(42)
    with pytest.raises(FileNotFoundError):
        LandMask.from_geojson(tmp_path / "missing.geojson")
    square = {"type": "Polygon", "coordinates": [[[10, 59], [10.1, 59], [10.1, 59.1], [10, 59]]]}
    with pytest.raises(ValueError, match="origin: longitude must lie"):
        LandMask.from_geojson(square, origin=(200.0, 59.0))
    with pytest.raises(TypeError, match="origin: expected"):
        LandMask.from_geojson(square, origin=10.0)
    swapped = {"type": "Polygon", "coordinates": [[[59, 10], [59, 100.1], [59.1, 100], [59, 10]]]}
    with pytest.raises(ValueError, match="lonlat: latitudes must lie in"):
        LandMask.from_geojson(swapped, origin=(10.0, 59.0))
    with pytest.raises(ValueError, match="backend: must be"):
        lonlat_to_local([[10.0, 59.0]], (10.0, 59.0), backend="proj4")
