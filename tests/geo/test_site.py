"""A sensor at a real coastal site (ctxmodels.geo.site): the box around it, its distance to
the shore against shapely, and what a radar on Southsea's shore sees over the real
shorelines."""
import numpy as np
import pytest
import shapely

from ctxmodels.geo.plane import lonlat_to_local
from ctxmodels.geo.site import box_around, coastal_site, shore_distance

SOUTHSEA = (-1.0889, 50.7780)  # Southsea Castle, Portsmouth


@pytest.mark.parametrize("lonlat, half_width", [(SOUTHSEA, 15000.0), ((20.0, -60.0), 80000.0),
                                                ((-179.9, 10.0), 5000.0)])
def test_box_around_holds_the_half_width(lonlat, half_width):
    box = box_around(lonlat, half_width)
    corners = lonlat_to_local([(box[0], box[1]), (box[2], box[3]), (box[0], box[3]), (box[2], box[1])],
                              lonlat)
    west_east = lonlat_to_local([(box[0], lonlat[1]), (box[2], lonlat[1])], lonlat)[:, 0]
    south_north = lonlat_to_local([(lonlat[0], box[1]), (lonlat[0], box[3])], lonlat)[:, 1]
    assert west_east[0] <= -half_width
    assert west_east[1] >= half_width
    assert south_north[0] <= -half_width and south_north[1] >= half_width
    assert np.all(np.abs(corners) < 3 * half_width)


def test_shore_distance_matches_shapely():
    rng = np.random.default_rng(5)
    polygons = [{"shell": np.array([[0.0, 0], [10, 0], [10, 10], [0, 10]]),
                 "holes": [np.array([[4.0, 4], [6, 4], [6, 6], [4, 6]])]},
                {"shell": np.array([[20.0, 0], [30, 5], [20, 10]]), "holes": []}]
    boundary = shapely.MultiLineString([np.vstack([r, r[:1]]) for p in polygons
                                        for r in [p["shell"], *p["holes"]]])
    for point in rng.uniform(-5, 35, (200, 2)):
        assert shore_distance(polygons, point) == pytest.approx(
            boundary.distance(shapely.Point(point)), abs=1e-12)


def test_southsea_castle_over_the_real_shorelines():
    site = coastal_site(SOUTHSEA, 15000.0)
    assert site.on_land and 150.0 < site.shore_distance < 250.0  # GSHHG puts the shore ~200 m off
    assert site.position == (0.0, 0.0) and site.origin == SOUTHSEA
    places = {"Spithead": (-1.10, 50.75), "the Nab": (-0.95, 50.67),
              "off Cowes, behind Gilkicker Point": (-1.30, 50.785),
              "Portsmouth Harbour, behind Gosport": (-1.12, 50.81),
              "the Channel, behind the Isle of Wight": (-1.25, 50.55)}
    points = lonlat_to_local(list(places.values()), site.origin)
    seen = dict(zip(places, site.line_of_sight(500.0).visible(site.position, points).tolist()))
    assert seen == {"Spithead": True, "the Nab": True, "off Cowes, behind Gilkicker Point": False,
                    "Portsmouth Harbour, behind Gosport": False,
                    "the Channel, behind the Isle of Wight": False}
    # without clearance the radar, on land, sees nothing
    assert not site.line_of_sight(0.0).visible(site.position, points).any()


def test_sites_of_one_scene_share_its_land():
    first = coastal_site(SOUTHSEA, 20000.0, origin=(-1.15, 50.75), resolution="i")
    second = coastal_site((-1.07, 50.68), 20000.0, origin=(-1.15, 50.75), land=first.land)
    assert second.land is first.land
    assert np.allclose(second.position, lonlat_to_local([(-1.07, 50.68)], (-1.15, 50.75))[0])


@pytest.mark.parametrize("lonlat, half_width, message", [
    (SOUTHSEA, 0.0, "half_width: must be a distance > 0"),
    (SOUTHSEA, -5.0, "half_width: must be a distance > 0"),
    (SOUTHSEA, float("nan"), "half_width: must be finite"),
    (SOUTHSEA, "10", "half_width: expected a number"),
    ((179.99, 65.5), 20000.0, "lonlat: .* crosses the antimeridian"),
    ((0.0, 88.9), 20000.0, "lonlat: .* within a degree of a pole"),
])
def test_bad_boxes_around_a_site_are_named(lonlat, half_width, message):
    with pytest.raises((TypeError, ValueError), match=message):
        box_around(lonlat, half_width)


def test_a_site_at_open_sea_has_no_land():
    site = coastal_site((-30.0, -40.0), 5000.0, resolution="c")
    assert site.land is None and not site.on_land and site.shore_distance == np.inf
    assert site.line_of_sight(500.0) is None
