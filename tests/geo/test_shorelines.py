"""GSHHG shorelines read for a box (ctxmodels.geo.shorelines), on the real files (downloaded
from the package index at first use): the Isle of Wight's area and perimeter against
GSHHG's own figure and pyproj's geodesic computation, the clip against shapely, and known
places on land and at sea."""
import numpy as np
import pytest
import shapely
from pyproj import Geod

from ctxmodels import LandMask
from ctxmodels.geo.clip import clip_to_box, signed_area
from ctxmodels.geo.plane import lonlat_to_local
from ctxmodels.geo.shorelines import read_shorelines, shoreline_polygons

SOLENT = (-1.75, 50.55, -0.9, 50.95)
WIGHT_AREA_KM2 = 388.834757382  # GSHHG's area of the island (its full-resolution polygon)


def isle_of_wight(resolution):
    found = [s for s in read_shorelines((-1.6, 50.57, -1.05, 50.77), resolution)
             if abs(s.area_km2 - WIGHT_AREA_KM2) < 1e-6]
    assert len(found) == 1 and found[0].level == 1
    return found[0]


@pytest.mark.parametrize("resolution, vertices", [("i", 26), ("h", 85), ("f", 607)])
def test_isle_of_wight_area_and_perimeter(resolution, vertices):
    wight = isle_of_wight(resolution)
    assert len(wight.lonlat) == vertices
    plane = lonlat_to_local(wight.lonlat, wight.lonlat.mean(axis=0))
    area = abs(signed_area(plane)) / 1e6
    perimeter = np.sum(np.hypot(*(np.roll(plane, -1, axis=0) - plane).T)) / 1e3
    # pyproj's geodesic area and perimeter on the WGS 84 ellipsoid: independent of the plane
    lon, lat = wight.lonlat.T
    geodesic_area, geodesic_perimeter = Geod(ellps="WGS84").polygon_area_perimeter(lon, lat)
    assert abs(area - abs(geodesic_area) / 1e6) < 1e-4 * area
    assert abs(perimeter - geodesic_perimeter / 1e3) < 1e-4 * perimeter
    if resolution == "f":
        # the full-resolution polygon is the one GSHHG measured: its area to 1e-5
        assert abs(area - WIGHT_AREA_KM2) < 1e-5 * WIGHT_AREA_KM2
        assert 128.0 < perimeter < 129.2  # 128.6 km (the often quoted 92 km is a coarser scale's)
    else:
        assert abs(area - WIGHT_AREA_KM2) < 0.02 * WIGHT_AREA_KM2


def test_coarser_resolutions_have_shorter_coasts():
    lengths = []
    for resolution in "ihf":
        ring = isle_of_wight(resolution).lonlat
        lengths.append(Geod(ellps="WGS84").polygon_area_perimeter(*ring.T)[1])
    assert lengths[0] < lengths[1] < lengths[2]


@pytest.mark.parametrize("resolution", ["c", "l", "i", "h", "f"])
def test_clipped_land_matches_shapely(resolution):
    box = SOLENT
    lands = [s for s in read_shorelines(box, resolution) if s.level == 1]
    assert lands
    ours = []
    for land in lands:
        ours += [shapely.Polygon(s, h) for s, h in clip_to_box(land.lonlat, [], box)]
    theirs = shapely.union_all([shapely.Polygon(s.lonlat) for s in lands]).intersection(shapely.box(*box))
    ours = shapely.MultiPolygon(ours)
    assert ours.is_valid
    assert abs(ours.area - theirs.area) < 1e-9 * theirs.area
    assert ours.symmetric_difference(theirs).area < 1e-9 * theirs.area


# (longitude, latitude, on land)
PLACES = [(-1.2985, 50.7003, True),   # Newport, Isle of Wight
          (-1.4044, 50.9097, True),   # Southampton
          (-1.0910, 50.7989, True),   # Portsmouth
          (-1.3000, 50.7850, False),  # the Solent off Cowes
          (-1.1000, 50.7500, False),  # Spithead
          (-1.3700, 50.8500, False),  # Southampton Water
          (-1.0000, 50.6500, False)]  # the Channel south-east of the island


@pytest.mark.parametrize("resolution", ["h", "f"])
def test_known_places_on_land_and_at_sea(resolution):
    origin = (-1.3, 50.75)
    mask = LandMask(polygons=shoreline_polygons(SOLENT, origin, resolution))
    points = lonlat_to_local([(lon, lat) for lon, lat, _ in PLACES], origin)
    assert mask.contains(points).tolist() == [on for *_, on in PLACES]


def test_polygons_are_in_the_plane_around_the_origin():
    origin = (-1.3, 50.75)
    polygons = shoreline_polygons(SOLENT, origin, "i")
    # inside the plane's box around the box's mapped corners (meridians converge northwards)
    corners = lonlat_to_local([(SOLENT[i], SOLENT[j]) for i in (0, 2) for j in (1, 3)], origin)
    every = np.concatenate([p["shell"] for p in polygons])
    assert np.all(every >= corners.min(axis=0) - 1e-6) and np.all(every <= corners.max(axis=0) + 1e-6)
    # the default origin is the box's centre
    centred = shoreline_polygons(SOLENT, resolution="i")
    centre = ((SOLENT[0] + SOLENT[2]) / 2, (SOLENT[1] + SOLENT[3]) / 2)
    explicit = shoreline_polygons(SOLENT, centre, resolution="i")
    assert all(np.array_equal(a["shell"], b["shell"]) for a, b in zip(centred, explicit, strict=True))
    assert not np.allclose(centred[0]["shell"], polygons[0]["shell"])


def test_antarctica_is_land():
    polygons = shoreline_polygons((1.0, -80.0, 10.0, -70.0), resolution="c")
    assert polygons and LandMask(polygons=polygons).contains(
        lonlat_to_local([(5.0, -75.0)], (5.5, -75.0))).all()
    # across the meridian GSHHG cuts Antarctica along, its halves would touch: refused
    with pytest.raises(ValueError, match="box: holds both halves of GSHHG polygon 4"):
        shoreline_polygons((-5.0, -80.0, 5.0, -70.0), resolution="c")


def test_a_box_beyond_the_plane_around_its_origin_is_named():
    with pytest.raises(ValueError, match="box: reaches farther than 1000 km"):
        shoreline_polygons((-10.0, 40.0, 20.0, 60.0), resolution="c")
    with pytest.raises(ValueError, match="box: reaches farther"):
        shoreline_polygons(SOLENT, origin=(30.0, 30.0), resolution="c")


def test_a_box_of_open_sea_has_no_land():
    assert shoreline_polygons((-3.0, 49.6, -2.5, 49.8), resolution="i") == []


@pytest.mark.parametrize("box, message", [
    ((-1, 50, -2, 51), "box: longitudes"), ((-1, 51, 0, 50), "box: latitudes"),
    ((-1, 50, 0), "box: expected"), ("solent", "box: expected"),
    ((-1, 50, float("nan"), 51), "box"), ((170, 0, 190, 1), "box: longitudes"),
    (np.array(5.0), "box: expected")])
def test_bad_boxes_are_named(box, message):
    with pytest.raises((TypeError, ValueError), match=message):
        read_shorelines(box, "c")


def test_bad_resolution_is_named():
    for resolution in ("x", ["c"], None):
        with pytest.raises(ValueError, match="resolution: one of"):
            read_shorelines(SOLENT, resolution)
