"""Hardening III (adapters): hostile inputs to land masks and GeoJSON, lon/lat mapping,
range bands' serialisation, the Stone Soup sensor and platform adapters, surveillance
regions, learners and ``paper_tracker``. Bad input raises ValueError/TypeError whose message
starts with the argument's name; wrong results are checked against the right ones."""
from __future__ import annotations

import datetime
import json
import math

import numpy as np
import pytest

from ctxmodels import LandMask, LineOfSight, NavigationTrack, RangeBands
from ctxmodels.geo import MAX_DISTANCE, lonlat_to_local, pyproj_available
from ctxmodels.stonesoup.gmphd.region import CircularRegion, PoseCentredRegion

T0 = datetime.datetime(2026, 1, 1)
NAN, INF = float("nan"), float("inf")
BACKENDS = ["numpy"] + (["pyproj"] if pyproj_available() else [])


def names_argument(call, exception, argument):
    with pytest.raises(exception) as info:
        call()
    assert str(info.value).startswith(f"{argument}:"), str(info.value)
    return str(info.value)


def _navigation():
    stamps = [T0 + datetime.timedelta(seconds=s) for s in range(3)]
    return NavigationTrack(timestamps=stamps, positions=[[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]],
                           headings=[0.0, 0.0, 0.0])


# --- regions ---------------------------------------------------------------------------------

BAD_RADII = [True, False, np.bool_(True), "1", "", None, NAN, INF, -INF, 0, 0.0, -1, -1e-300,
             np.float64(NAN), np.float32(-2), np.int64(0), [1.0], np.array([1.0]), np.array(1.0),
             1 + 0j, datetime.timedelta(seconds=1), object()]


@pytest.mark.parametrize("radius", BAD_RADII, ids=repr)
def test_pose_centred_region_refuses_a_radius_that_is_not_a_positive_number(radius):
    error = (ValueError, TypeError)
    names_argument(lambda: PoseCentredRegion(pose_source=_navigation(), radius=radius), error,
                   "radius")
    names_argument(lambda: CircularRegion(centre=(0.0, 0.0), radius=radius), error, "radius")


@pytest.mark.parametrize("radius", [1, 1.5, np.float32(2.0), np.int64(3), np.uint8(4), 1e300,
                                    5e-324], ids=repr)
def test_region_radius_of_any_real_number_type_is_kept_as_a_float(radius):
    region = PoseCentredRegion(pose_source=_navigation(), radius=radius)
    assert type(region.radius) is float and region.radius == float(radius)
    assert region.at(T0).radius == float(radius)


BAD_CENTRES = [None, 5, "12", (True, 0.0), ("1", "2"), (0.0,), (0.0, 1.0, 2.0), (NAN, 0.0),
               (0.0, INF), np.array([[1.0, 2.0], [3.0, 4.0]]), {"x": 0, "y": 0}, (None, 0.0),
               (1 + 1j, 0.0)]


@pytest.mark.parametrize("centre", BAD_CENTRES, ids=repr)
def test_circular_region_refuses_a_bad_centre(centre):
    names_argument(lambda: CircularRegion(centre=centre, radius=1.0), (ValueError, TypeError),
                   "centre")


BAD_POINTS = [np.zeros((4, 3)), np.zeros((1, 1)), np.zeros(4), np.zeros(3), np.zeros((2, 2, 2)),
              [[0.0, 0.0], [1.0]], [["a", "b"]], "0 0", {"x": 0}, np.array([[True, False]]),
              np.array([[1j, 0]]), [[None, None]]]


@pytest.mark.parametrize("points", BAD_POINTS, ids=lambda p: repr(p)[:40])
def test_circular_region_contains_names_points_of_the_wrong_shape(points):
    region = CircularRegion(centre=(0.0, 0.0), radius=2.0)
    names_argument(lambda: region.contains(points), (ValueError, TypeError), "points")


def test_circular_region_contains_reads_rows_and_one_pair():
    region = CircularRegion(centre=(1.0, 1.0), radius=2.0)
    np.testing.assert_array_equal(region.contains([[1.0, 3.0], [1.0, 3.0001], [NAN, 0.0]]),
                                  [True, False, False])
    np.testing.assert_array_equal(region.contains((1.0, 1.0)), [True])
    np.testing.assert_array_equal(region.contains(np.array([[3, 1]], dtype=np.int32)), [True])
    assert region.contains(np.empty((0, 2))).shape == (0,)
    assert region.contains([]).shape == (0,)


# --- range bands through Stone Soup's YAML ---------------------------------------------------

@pytest.mark.parametrize("flags", [np.bool_(True), np.bool_(False), (np.bool_(True),),
                                   [np.bool_(False)], np.array([True]), (True,), False,
                                   np.array(True)], ids=repr)
def test_range_bands_with_numpy_booleans_survive_stone_soups_yaml(flags):
    from stonesoup.serialise import YAML
    bands = RangeBands(edges=(50.0,), values=(1.0, 0.0), upper_owns=flags)
    owners = bands.upper_owns
    assert owners in (True, False) and type(owners) is bool or \
        type(owners) is tuple and all(type(f) is bool for f in owners)
    back = YAML().load(YAML().dumps(bands))
    assert back == bands
    assert back([50.0])[0] == bands([50.0])[0] == (0.0 if bool(np.ravel(flags)[0]) else 1.0)


@pytest.mark.parametrize("flags", [np.array([[True]]), np.array([1]), [np.int64(1)],
                                   np.array(["True"])], ids=repr)
def test_range_bands_refuse_non_boolean_flag_arrays(flags):
    names_argument(lambda: RangeBands(edges=(50.0,), values=(1.0, 0.0), upper_owns=flags),
                   TypeError, "upper_owns")


# --- GeoJSON ---------------------------------------------------------------------------------

SQUARE = [[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0], [0.0, 0.0]]


def _polygon(rings):
    return {"type": "Polygon", "coordinates": rings}


def _collection(*geometries):
    return {"type": "FeatureCollection",
            "features": [{"type": "Feature", "properties": {}, "geometry": g} for g in geometries]}


# (document, where the message must say the problem is, after "source: ")
BAD_GEOJSON = [
    ({"type": "Polygon"}, "top level: a Polygon needs a 'coordinates'"),
    ({"coordinates": [SQUARE]}, "top level: has no 'type'"),
    ({"type": 5, "coordinates": [SQUARE]}, "top level: has no 'type'"),
    ({"type": "Polygonal", "coordinates": [SQUARE]}, "top level: expected Polygon"),
    ({"type": "FeatureCollection", "features": 5}, "features: expected a list"),
    ({"type": "FeatureCollection", "features": None}, "features: expected a list"),
    ({"type": "FeatureCollection", "features": "abc"}, "features: expected a list"),
    ({"type": "FeatureCollection"}, "top level: a FeatureCollection needs a 'features'"),
    ({"type": "FeatureCollection", "features": [5]}, "features[0]: expected a GeoJSON object"),
    ({"type": "FeatureCollection", "features": [_polygon([SQUARE])]},
     "features[0]: expected a Feature"),
    ({"type": "FeatureCollection", "features": [{"type": "Feature"}]},
     "features[0]: a Feature needs a 'geometry'"),
    (_collection(_polygon([SQUARE]), {"type": "Point", "coordinates": [0, 0]}),
     "features[1].geometry: expected Polygon"),
    (_collection(_polygon([SQUARE]), {"type": "LineString", "coordinates": [[0, 0], [1, 1]]}),
     "features[1].geometry: expected Polygon"),
    (_collection({"type": "Feature", "geometry": None}), "features[0].geometry: expected a "
                                                         "geometry"),
    (_collection(_polygon(None)), "features[0].geometry.coordinates: expected a list"),
    (_collection(_polygon(7)), "features[0].geometry.coordinates: expected a list"),
    (_collection(_polygon("abc")), "features[0].geometry.coordinates: expected a list"),
    (_collection(_polygon([5])), "features[0].geometry.coordinates[0]: expected a linear ring"),
    (_collection(_polygon(SQUARE)), "features[0].geometry.coordinates[0][0]: expected a position"),
    (_collection(_polygon([SQUARE[:3]])), "features[0].geometry.coordinates[0]: a linear ring "
                                          "needs at least 4"),
    (_collection(_polygon([[]])), "features[0].geometry.coordinates[0]: a linear ring needs"),
    (_collection(_polygon([SQUARE[:4]])), "features[0].geometry.coordinates[0]: a linear ring "
                                          "must be closed"),
    (_collection(_polygon([[[0, 0], [1, 0], ["0", 1], [0, 0]]])),
     "features[0].geometry.coordinates[0][2]: coordinates must be numbers"),
    (_collection(_polygon([[[0, 0], [1, 0], [True, 1], [0, 0]]])),
     "features[0].geometry.coordinates[0][2]: coordinates must be numbers"),
    (_collection(_polygon([[[0, 0], [1, 0], [None, 1], [0, 0]]])),
     "features[0].geometry.coordinates[0][2]: coordinates must be numbers"),
    (_collection(_polygon([[[0, 0], [1, 0], [NAN, 1], [0, 0]]])),
     "features[0].geometry.coordinates[0][2]: coordinates must be finite"),
    (_collection(_polygon([[[0, 0], [1, 0], [INF, 1], [0, 0]]])),
     "features[0].geometry.coordinates[0][2]: coordinates must be finite"),
    (_collection(_polygon([[[0, 0], [1, 0], [1], [0, 0]]])),
     "features[0].geometry.coordinates[0][2]: expected a position"),
    (_collection(_polygon([[[0, 0], [1, 0], [[0, 1]], [0, 0]]])),
     "features[0].geometry.coordinates[0][2]: expected a position"),
    (_collection(_polygon([[[0, 0], [1, 0], [[0, 1], [1, 1]], [0, 0]]])),
     "features[0].geometry.coordinates[0][2]: coordinates must be numbers"),
    (_collection(_polygon([SQUARE, [[1, 1], [2, 1], [1, 1]]])),
     "features[0].geometry.coordinates[1]: a linear ring needs at least 4"),
    (_collection(_polygon([[[0, 0], [1, 0], [2, 0], [0, 0]]])),
     "features[0].geometry.coordinates[0]: shell: has zero area"),
    (_collection(_polygon([SQUARE, [[20, 20], [21, 20], [20, 21], [20, 20]]])),
     "features[0].geometry.coordinates: polygon 0 hole 0 lies outside its shell"),
    ({"type": "MultiPolygon", "coordinates": [SQUARE]},
     "coordinates[0][0][0]: expected a position"),
    ({"type": "MultiPolygon", "coordinates": [5]}, "coordinates[0]: expected a polygon"),
    ({"type": "MultiPolygon", "coordinates": None}, "coordinates: expected a list"),
    ({"type": "MultiPolygon", "coordinates": []}, "top level: holds no polygons"),
    ({"type": "GeometryCollection"}, "top level: a GeometryCollection needs a 'geometries'"),
    ({"type": "GeometryCollection", "geometries": 3}, "geometries: expected a list"),
    ({"type": "GeometryCollection", "geometries": [{"type": "Point", "coordinates": [0, 0]}]},
     "geometries[0]: expected Polygon"),
    ({"type": "GeometryCollection", "geometries": [{"type": "Feature", "geometry": None}]},
     "geometries[0]: expected a geometry here"),
    ({"type": "GeometryCollection", "geometries": [None]}, "geometries[0]: expected a GeoJSON"),
    ({"type": "GeometryCollection", "geometries": []}, "top level: holds no polygons"),
    ({"type": "FeatureCollection", "features": []}, "top level: holds no polygons"),
    ({"type": "Feature", "geometry": None}, "top level: holds no polygons"),
    ({"type": "Feature", "geometry": {"type": "FeatureCollection", "features": []}},
     "geometry: expected a geometry here"),
    ({"type": "Feature", "geometry": 3}, "geometry: expected a GeoJSON object"),
]


@pytest.mark.parametrize("document, where", BAD_GEOJSON, ids=[w for _, w in BAD_GEOJSON])
def test_bad_geojson_names_source_and_where_in_the_document(document, where, tmp_path):
    message = names_argument(lambda: LandMask.from_geojson(document), ValueError, "source")
    assert message.startswith(f"source: {where}"), message
    # the same as JSON text, and as a file (named by its path)
    text = json.dumps(document)
    assert names_argument(lambda: LandMask.from_geojson(text), ValueError, "source") == message
    path = tmp_path / "land.geojson"
    path.write_text(text, encoding="utf-8")
    message = names_argument(lambda: LandMask.from_geojson(path), ValueError, "source")
    assert message.startswith(f"source: {str(path)!r}: {where}"), message


@pytest.mark.parametrize("text", ['{"type": "Polygon", "coordinates": [[[0, 0], [1, 0]',
                                  '{"type": "Polygon",\n "coordinates": [[[0, 0] [1, 0]]]}',
                                  '{', '{"type": }', "[1, 2", '{"a": 1} trailing'],
                         ids=["truncated", "missing-comma", "brace", "no-value", "array",
                              "trailing"])
def test_invalid_json_names_source_file_and_line_and_column(text, tmp_path):
    message = names_argument(lambda: LandMask.from_geojson(text), ValueError, "source")
    assert "not valid JSON at line" in message and "column" in message, message
    path = tmp_path / "broken.geojson"
    path.write_text(text, encoding="utf-8")
    message = names_argument(lambda: LandMask.from_geojson(str(path)), ValueError, "source")
    assert message.startswith(f"source: {str(path)!r}: not valid JSON at line"), message


def test_a_top_level_json_array_is_not_geojson():
    names_argument(lambda: LandMask.from_geojson("[1, 2]"), ValueError, "source")


@pytest.mark.parametrize("source", [42, None, 4.5, True, b'{"type": "Polygon"}', [SQUARE],
                                    object()], ids=repr)
def test_from_geojson_refuses_sources_of_other_types(source):
    names_argument(lambda: LandMask.from_geojson(source), TypeError, "source")


@pytest.mark.parametrize("source", ["", "   "], ids=repr)
def test_from_geojson_refuses_an_empty_string(source):
    names_argument(lambda: LandMask.from_geojson(source), ValueError, "source")


def test_missing_unreadable_and_non_utf8_files_name_source(tmp_path):
    names_argument(lambda: LandMask.from_geojson(tmp_path / "missing.geojson"),
                   FileNotFoundError, "source")
    names_argument(lambda: LandMask.from_geojson(tmp_path), OSError, "source")  # a directory
    latin = tmp_path / "latin.geojson"
    latin.write_bytes(b'{"type": "Polygon", "name": "\xe9"}')
    names_argument(lambda: LandMask.from_geojson(latin), ValueError, "source")


def test_good_geojson_in_every_form_gives_the_same_land(tmp_path):
    hole = [[2.0, 2.0], [4.0, 2.0], [4.0, 4.0], [2.0, 4.0], [2.0, 2.0]]
    far = [[20.0, 0.0], [30.0, 0.0], [30.0, 10.0, 5.0], [20.0, 0.0]]  # a 3-D position too
    expected = LandMask(polygons=[(SQUARE, [hole]), [p[:2] for p in far]])
    forms = [
        {"type": "MultiPolygon", "coordinates": [[SQUARE, hole], [far]]},
        _collection(_polygon([SQUARE, hole]), None, _polygon([far]), _polygon([])),
        {"type": "GeometryCollection", "geometries": [
            _polygon([SQUARE, hole]), {"type": "GeometryCollection",
                                       "geometries": [_polygon([far])]}]},
        {"type": "Feature", "geometry": {"type": "MultiPolygon",
                                         "coordinates": [[SQUARE, hole], [far]]}},
    ]
    for form in forms:
        assert LandMask.from_geojson(form) == expected
        assert LandMask.from_geojson(json.dumps(form, indent=2)) == expected
    path = tmp_path / "land.geojson"
    path.write_text(json.dumps(forms[0]), encoding="utf-8")
    assert LandMask.from_geojson(path) == LandMask.from_geojson(str(path)) == expected


def test_deep_nesting_is_refused_naming_source():
    node = _polygon([SQUARE])
    for _ in range(40):
        node = {"type": "GeometryCollection", "geometries": [node]}
    names_argument(lambda: LandMask.from_geojson(node), ValueError, "source")
    names_argument(lambda: LandMask.from_geojson("[" * 100_000), ValueError, "source")


def test_lonlat_errors_in_geojson_name_source_and_where():
    far = _polygon([[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 0.0]]])
    message = names_argument(lambda: LandMask.from_geojson(_collection(far), origin=(179.0, 0.0)),
                             ValueError, "source")
    assert message.startswith("source: features[0].geometry.coordinates[0]: lonlat:"), message
    names_argument(lambda: LandMask.from_geojson(_collection(far), origin=(0.0, 91.0)),
                   ValueError, "origin")
    names_argument(lambda: LandMask.from_geojson(_collection(far), origin="0,0"), TypeError,
                   "origin")


@pytest.mark.parametrize("scale", [1e160, 1e200, 1e300, 1e307])
def test_valid_polygons_with_huge_coordinates_are_accepted(scale):
    """Huge masks are validated and indexed in a frame scaled down by a power of two: the
    same answers as the mask at unit scale, and an invalid ring is still refused."""
    from ctxmodels import LineOfSight
    shell = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    hole = np.array([[0.4, 0.4], [0.6, 0.4], [0.6, 0.6], [0.4, 0.6]])
    points = np.array([[0.2, 0.2], [0.5, 0.5], [0.9, 0.95], [1.5, 0.5], [-0.1, 0.5]])
    unit = LandMask(polygons=[{"shell": shell, "holes": [hole]}])
    huge = LandMask(polygons=[{"shell": shell * scale, "holes": [hole * scale]}])
    np.testing.assert_array_equal(huge.contains(points * scale), unit.contains(points))
    assert unit.contains(points).tolist() == [True, False, True, False, False]
    sight = LineOfSight(land=huge)
    np.testing.assert_array_equal(sight.visible(np.array([-0.5, 0.5]) * scale, points * scale),
                                  LineOfSight(land=unit).visible(np.array([-0.5, 0.5]), points))
    bowtie = np.array([[0.0, 0.0], [1.0, 1.0], [1.0, 0.0], [0.0, 1.0]]) * scale
    names_argument(lambda: LandMask(polygons=[bowtie]), ValueError, "polygons")


# --- land masks and line of sight -----------------------------------------------------------

BAD_POLYGONS = [None, 5, "abc", [None], ["abc"], [{"holes": []}], [{"shell": SQUARE, "holes": None}],
                [{"shell": SQUARE, "holes": 5}], [np.zeros((4, 3))], [[[0, 0], [1]]],
                [np.array([[True, False], [False, True], [True, True]])],
                [[[0.0, 0.0], [1.0, 0.0], [NAN, 1.0]]], [[[0.0, 0.0], [1.0, 0.0], [INF, 1.0]]],
                [], [[[0, 0], [1, 1]]], [[[0, 0], [1, 1], [2, 2]]]]


@pytest.mark.parametrize("polygons", BAD_POLYGONS, ids=lambda p: repr(p)[:50])
def test_land_mask_refuses_bad_polygons_naming_polygons(polygons):
    names_argument(lambda: LandMask(polygons=polygons), (ValueError, TypeError), "polygons")


BAD_SENSORS = [None, "00", (True, 0.0), ("0", "1"), (0.0,), (0.0, 1.0, 2.0), (NAN, 0.0),
               (INF, 0.0), 5, {"x": 0}]


@pytest.mark.parametrize("sensor", BAD_SENSORS, ids=repr)
def test_line_of_sight_refuses_a_bad_sensor_position(sensor):
    sight = LineOfSight(land=LandMask(polygons=[SQUARE]))
    names_argument(lambda: sight.visible(sensor, [[20.0, 20.0]]), (ValueError, TypeError),
                   "sensor")


@pytest.mark.parametrize("land", [None, 5, "land", [SQUARE]], ids=repr)
def test_line_of_sight_needs_a_land_mask(land):
    names_argument(lambda: LineOfSight(land=land), TypeError, "land")


# --- longitude/latitude ----------------------------------------------------------------------

@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("lonlat, origin", [
    ([[180.0, 0.0]], (0.0, 0.0)),  # the antipode folded back onto the origin
    ([[0.0, 0.0]], (180.0, 0.0)),
    ([[10.0, 0.0]], (0.0, 0.0)),  # 1113 km
    ([[-170.0, 0.0]], (10.0, 0.0)),
    ([[0.0, -89.0]], (0.0, 89.0)),
    ([[10.7, 59.9], [100.0, 59.9]], (10.6, 59.85)),  # one far row among near ones
], ids=str)
def test_points_beyond_the_local_planes_reach_are_refused(lonlat, origin, backend):
    message = names_argument(lambda: lonlat_to_local(lonlat, origin, backend=backend),
                             ValueError, "lonlat")
    assert "MAX_DISTANCE" in message


@pytest.mark.parametrize("backend", BACKENDS)
def test_points_within_the_reach_are_mapped_and_agree_across_the_antimeridian(backend):
    # 999 km east along the equator: mapped, to R·sin θ of the sphere within 0.5 %
    east = math.degrees(0.999 * MAX_DISTANCE / 6378137.0)
    local = lonlat_to_local([[east, 0.0]], (0.0, 0.0), backend=backend)
    assert 0.99 * MAX_DISTANCE < local[0, 0] < MAX_DISTANCE and local[0, 1] == pytest.approx(0)
    across = lonlat_to_local([[-179.9, 0.0], [179.7, 0.0]], (179.9, 0.0), backend=backend)
    np.testing.assert_allclose(across[:, 0], [22_264, -22_264], rtol=1e-3)


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("lonlat", [
    [[0.0, 91.0]], [[0.0, -90.5]], [[181.0, 0.0]], [[-540.0, 0.0]], [[NAN, 0.0]], [[0.0, INF]],
    [[0.0]], [[0.0, 0.0, 0.0]], np.zeros(2), [["a", "b"]], "0 0", None, 5, {"lon": 0},
    np.array([[True, False]]), [[0.0, 0.0], [1.0]], np.array([[1j, 0]]),
    np.array([[0, 0]], dtype="timedelta64[s]"),
], ids=lambda v: repr(v)[:40])
def test_bad_lonlat_is_refused_naming_it(lonlat, backend):
    names_argument(lambda: lonlat_to_local(lonlat, (0.0, 0.0), backend=backend),
                   (ValueError, TypeError), "lonlat")


@pytest.mark.parametrize("origin", [
    (0.0, 90.0), (0.0, -90.0), (181.0, 0.0), (NAN, 0.0), (0.0, INF), (True, 0.0), ("0", "0"),
    "00", "0,0", 0.0, None, (0.0,), (0.0, 0.0, 0.0), {"lon": 0, "lat": 0}, (None, 0.0),
    np.array([[0.0, 0.0], [1.0, 1.0]]),
], ids=repr)
def test_bad_origins_are_refused_naming_origin(origin):
    names_argument(lambda: lonlat_to_local([[0.0, 0.0]], origin), (ValueError, TypeError),
                   "origin")


@pytest.mark.parametrize("backend", ["proj4", None, "", 1, "NUMPY"], ids=repr)
def test_unknown_backend_is_refused_naming_it(backend):
    names_argument(lambda: lonlat_to_local([[0.0, 0.0]], (0.0, 0.0), backend=backend),
                   ValueError, "backend")


@pytest.mark.parametrize("backend", BACKENDS)
def test_empty_lonlat_and_numpy_origin_types_work(backend):
    assert lonlat_to_local([], (10.0, 59.0), backend=backend).shape == (0, 2)
    assert lonlat_to_local(np.empty((0, 2)), (10.0, 59.0), backend=backend).shape == (0, 2)
    origin = (np.float32(10.0), np.int64(59))
    np.testing.assert_allclose(lonlat_to_local([[10.0, 59.0]], origin, backend=backend),
                               [[0.0, 0.0]], atol=1e-6)
    np.testing.assert_allclose(lonlat_to_local([[10.0, 59.0]], np.array([10.0, 59.0]),
                                               backend=backend), [[0.0, 0.0]], atol=1e-6)


# --- Stone Soup sensor adapter ----------------------------------------------------------------

def _radar(kind="fixed", position=(100.0, -50.0), yaw=0.7, rotation=0.3, max_range=800.0,
           dwell=0.0, fov=2 * math.pi, with_platform=False):
    from stonesoup.platform.base import FixedPlatform
    from stonesoup.sensor.radar.radar import RadarBearingRange, RadarRotatingBearingRange
    from stonesoup.types.array import StateVector
    from stonesoup.types.state import State
    common = dict(ndim_state=4, position_mapping=(0, 2), noise_covar=np.eye(2),
                  max_range=max_range, rotation_offset=StateVector([0, 0, rotation]),
                  mounting_offset=StateVector([3.0, -1.0]))
    if kind == "rotating":
        sensor = RadarRotatingBearingRange(dwell_centre=StateVector([dwell]), rpm=10,
                                           fov_angle=fov, **common)
    else:
        sensor = RadarBearingRange(**common)
    platform = FixedPlatform(
        states=[State(StateVector([position[0], 0, position[1], 0]), timestamp=T0)],
        position_mapping=(0, 2), orientation=StateVector([0, 0, yaw]), sensors=[sensor])
    return (sensor, platform) if with_platform else sensor


EDGE_RADARS = [
    dict(kind="fixed", position=(100.0, -50.0), yaw=0.7, rotation=0.3, max_range=800.0),
    dict(kind="rotating", position=(12345.6, -777.0), yaw=2.1, rotation=-0.4, max_range=1612.0,
         dwell=0.3),
    dict(kind="fixed", position=(0.0, 0.0), yaw=-1.3, rotation=1.0, max_range=333.3),
    dict(kind="rotating", position=(-40.0, 7.5), yaw=0.0, rotation=0.0, max_range=50.0,
         dwell=1.1),
]


EDGE_IDS = [f"{r['kind']}-{r['max_range']}" for r in EDGE_RADARS]
#: A rotating radar whose field of view is narrower than a turn: its edge is the sector's.
NARROW = dict(kind="rotating", position=(-40.0, 7.5), yaw=0.4, rotation=0.2, max_range=50.0,
              dwell=1.1, fov=math.pi)


def _detectable(sensor, states) -> np.ndarray:
    """The radar's own ``is_detectable``, one state at a time."""
    from stonesoup.types.groundtruth import GroundTruthState
    return np.array([bool(np.all(sensor.is_detectable(
        GroundTruthState(s.reshape(-1, 1), timestamp=T0)))) for s in states])


def _ring(sensor, r, n=240) -> np.ndarray:
    """(n, 4) CV states at world range ``r`` from the sensor on n bearings."""
    centre = np.asarray(sensor.position, dtype=float).ravel()
    bearings = np.linspace(-math.pi, math.pi, n, endpoint=False)
    return np.column_stack([centre[0] + r * np.cos(bearings), np.zeros(n),
                            centre[1] + r * np.sin(bearings), np.zeros(n)])


def _pd_on_every_path(context, states) -> dict:
    """P_D of ``states`` (N, D) by every public path of the context."""
    from stonesoup.types.hypothesis import SingleHypothesis
    from stonesoup.types.prediction import GaussianStatePrediction
    from stonesoup.types.state import GaussianState, State
    vectors = [s.reshape(-1, 1) for s in states]
    covars = np.tile(np.eye(4), (len(states), 1, 1))
    log_pd, log_missed = context.prob_detection_particles(np.asfortranarray(states.T),
                                                          log=True, missed=True)
    pd_pair, missed = context.prob_detection_particles(states.T.copy(), missed=True)
    return {
        "array": context.prob_detection_array(states),
        "array-list": context.prob_detection_array(states.tolist()),
        "array-covars": context.prob_detection_array(states, covars),
        "states": context.prob_detection_states([GaussianState(v, np.eye(4)) for v in vectors]),
        "one-state": np.array([float(context.prob_detection(State(v))) for v in vectors]),
        "one-flat": np.array([float(context.prob_detection(s.copy())) for s in states]),
        "one-hypothesis": np.array([float(context.prob_detection(SingleHypothesis(
            GaussianStatePrediction(v, np.eye(4), timestamp=T0), None))) for v in vectors]),
        "one-list": np.array([float(context.prob_detection(s.tolist())) for s in states]),
        "particles": context.prob_detection_particles(states.T),
        "particles-log": np.exp(log_pd),
        "particles-missed": pd_pair,
        "particles-missed-complement": 1 - missed,
        "particles-log-missed": 1 - np.exp(log_missed),
    }


@pytest.mark.parametrize("radar", EDGE_RADARS + [NARROW], ids=EDGE_IDS + ["narrow-fov"])
@pytest.mark.parametrize("made_by", ["sensor_context", "PlatformContextFeeder"])
def test_pd_agrees_with_is_detectable_at_max_range_on_every_path(radar, made_by):
    """The issue's test, at ``max_range`` and one ulp either side on 240 bearings: P_D > 0
    exactly where the radar's own ``is_detectable`` says the target is detectable (no
    disagreement) on every P_D path of the context the radar's scan gets, and P_D there is
    the value inside the coverage (0.9), as bit for bit as the plain context gives it."""
    sensor, platform = _radar(**radar, with_platform=True)
    model = _edge_model(sensor)
    context = _edge_context(sensor, platform, model, made_by)
    plain = model.context(_sensor_pose(sensor), T0)
    inside = plain.prob_detection_array(_ring(sensor, sensor.max_range * 0.5))
    checked = 0
    for r in (np.nextafter(sensor.max_range, 0), sensor.max_range,
              np.nextafter(sensor.max_range, INF)):
        states = _ring(sensor, r)
        detectable = _detectable(sensor, states)
        for path, pd in _pd_on_every_path(context, states).items():
            disagreements = int(np.sum((pd > 0) != detectable))
            assert disagreements == 0, f"{path} at max_range{r - sensor.max_range:+g}"
            # inside: the plain context's value there (0.9, or 0 outside the field of view)
            expected = np.where(detectable, inside, 0.0)
            if path.startswith(("array", "states", "one", "particles-missed")) \
                    and path != "particles-missed-complement":
                np.testing.assert_array_equal(pd, expected, err_msg=path)
            else:  # through a log or a complement: to their rounding
                np.testing.assert_allclose(pd, expected, rtol=0, atol=1e-15, err_msg=path)
            checked += 1
        if radar is not NARROW:
            assert detectable.any() and (r <= sensor.max_range or not detectable.all())
    assert checked == 3 * 13


def _sensor_pose(sensor):
    from ctxmodels.stonesoup import sensor_pose
    return sensor_pose(sensor)


def _edge_model(sensor):
    from ctxmodels import SensorModel
    return SensorModel.from_stonesoup(sensor, prob_detection=0.9, clutter_density=1e-4)


def _edge_context(sensor, platform, model, made_by):
    """The context of a scan of ``sensor`` now, from :func:`sensor_context` or as the
    :class:`PlatformContextFeeder` gives it (its first scan, at the platform's time)."""
    from ctxmodels.stonesoup import PlatformContextFeeder, sensor_context
    from ctxmodels.stonesoup import SensorContext
    if made_by == "sensor_context":
        context = sensor_context(sensor, model, T0)
    else:
        from stonesoup.simulator.platform import PlatformDetectionSimulator

        class Still:  # no targets: only the scans and their contexts are read
            def __iter__(self):
                yield T0, set()
        simulator = PlatformDetectionSimulator(groundtruth=Still(), platforms=[platform])
        [(time, scan)] = list(PlatformContextFeeder(reader=simulator, sensor_models=[model]))
        context = scan.detector_context
        assert time == T0 and context.timestamp == T0
    assert type(context) is SensorContext and context.sensor_model is model
    assert context.pose == _sensor_pose(sensor)
    return context


@pytest.mark.parametrize("radar", EDGE_RADARS + [NARROW], ids=EDGE_IDS + ["narrow-fov"])
@pytest.mark.parametrize("made_by", ["plain", "sensor_context"])
def test_pd_agrees_with_is_detectable_on_every_bearing_off_the_rounding_sliver(radar, made_by):
    """Either side of ``max_range`` by 1e-12 of it (far beyond the rotation's rounding, far
    inside any target's size), and well inside and outside, on 240 bearings: P_D > 0 exactly
    where Stone Soup's radar says the target is detectable, for the plain context (world
    range) and the sensor's (its own range in the sliver between); the two agree bit for
    bit there."""
    sensor, platform = _radar(**radar, with_platform=True)
    model = _edge_model(sensor)
    plain = model.context(_sensor_pose(sensor), T0)
    context = plain if made_by == "plain" else _edge_context(sensor, platform, model, made_by)
    for r in (sensor.max_range * (1 - 1e-12), sensor.max_range * (1 + 1e-12),
              sensor.max_range * 0.5, sensor.max_range * 2):
        states = _ring(sensor, r)
        pd = context.prob_detection_array(states)
        detectable = _detectable(sensor, states)
        np.testing.assert_array_equal(pd > 0, detectable, err_msg=f"range {r}")
        np.testing.assert_array_equal(pd, plain.prob_detection_array(states))
        assert detectable.any() == (r < sensor.max_range)  # (the test can fail both ways)


@pytest.mark.parametrize("radar", EDGE_RADARS, ids=EDGE_IDS)
def test_a_target_whose_world_range_is_exactly_max_range_is_inside(radar):
    """The plain context's edge (``SensorModel.context(sensor_pose(sensor))``): the
    world-frame range, ``<=`` as in ``is_detectable``; along the axes the range is exact, so
    the edge itself is tested, and one ulp beyond is outside."""
    from ctxmodels import SensorModel
    from ctxmodels.stonesoup import sensor_pose
    sensor = _radar(**radar)
    if radar["kind"] == "rotating":  # keep the antenna's field of view out of it
        sensor.fov_angle = 2 * math.pi
    model = SensorModel.from_stonesoup(sensor, prob_detection=0.9, clutter_density=1e-4)
    pose = sensor_pose(sensor)
    context = model.context(pose, T0)
    r = sensor.max_range
    for dx, dy in ((r, 0.0), (-r, 0.0), (0.0, r), (0.0, -r)):
        at = np.array([[pose.x + dx, 0.0, pose.y + dy, 0.0]])
        if math.hypot(at[0, 0] - pose.x, at[0, 2] - pose.y) != r:
            continue  # (the sum rounded: not exactly on the edge)
        assert context.prob_detection_array(at)[0] == 0.9
        # the next representable position whose offset from the sensor exceeds max_range
        beyond, axis, centre = at.copy(), 0 if dx else 2, pose.x if dx else pose.y
        while abs(beyond[0, axis] - centre) <= r:
            beyond[0, axis] = np.nextafter(beyond[0, axis], math.copysign(INF, dx or dy))
        assert context.prob_detection_array(beyond)[0] == 0.0


def test_sensor_context_keeps_the_radar_as_it_was_and_pickles_and_copies():
    """The context decides with the radar as it was when made (the radar moving or changing
    its max_range afterwards reaches it not), survives pickling and deep copies with the
    same P_D on every target, and hashes and compares by identity."""
    import copy
    import pickle
    from stonesoup.types.array import StateVector
    from ctxmodels.stonesoup import sensor_context
    sensor = _radar(**EDGE_RADARS[1])
    states = _ring(sensor, sensor.max_range)
    detectable = _detectable(sensor, states)
    context = sensor_context(sensor, _edge_model(sensor), T0)
    before = context.prob_detection_array(states)
    np.testing.assert_array_equal(before > 0, detectable)
    sensor.max_range = 1.0
    sensor.dwell_centre = StateVector([2.0])
    sensor.movement_controller.states[-1].state_vector[0, 0] += 5.0
    for other in (context, pickle.loads(pickle.dumps(context)), copy.deepcopy(context)):
        np.testing.assert_array_equal(other.prob_detection_array(states), before)
        np.testing.assert_array_equal(other.prob_detection_particles(states.T), before)
        assert other.max_range == EDGE_RADARS[1]["max_range"]
    copied = copy.deepcopy(context)
    assert copied != context and context == context and hash(context) == object.__hash__(context)
    assert {context: 1}[context] == 1


def test_sensor_context_with_the_expected_pd_under_a_rule_integrates_the_plain_model():
    """With covariances and a ``pd_evaluation`` other than 'mean' the expected P_D is the
    plain context's (documented); without covariances the mean decides, as the radar does."""
    from ctxmodels import SensorModel
    from ctxmodels.stonesoup import sensor_context
    sensor = _radar(**EDGE_RADARS[0])
    base = _edge_model(sensor)
    model = SensorModel(detection=base.detection, clutter=base.clutter,
                        position_mapping=base.position_mapping, pd_evaluation="cubature")
    context = sensor_context(sensor, model, T0)
    plain = model.context(_sensor_pose(sensor), T0)
    states = _ring(sensor, sensor.max_range)
    covars = np.tile(np.eye(4), (len(states), 1, 1))
    np.testing.assert_array_equal(context.prob_detection_array(states, covars),
                                  plain.prob_detection_array(states, covars))
    np.testing.assert_array_equal(context.prob_detection_array(states) > 0,
                                  _detectable(sensor, states))


@pytest.mark.parametrize("bad", ["sensor", "model", "mounted", "mapping"])
def test_sensor_context_names_what_it_cannot_use(bad):
    from ctxmodels import Mounting, SensorModel
    from ctxmodels.stonesoup import sensor_context
    sensor = _radar()
    model = _edge_model(sensor)
    if bad == "sensor":
        names_argument(lambda: sensor_context(object(), model), TypeError, "sensor")
    elif bad == "model":
        names_argument(lambda: sensor_context(sensor, model.detection), TypeError,
                       "sensor_model")
    else:
        other = SensorModel(detection=model.detection, clutter=model.clutter,
                            **({"mounting": Mounting(forward=1.0)} if bad == "mounted"
                               else {"position_mapping": (0, 1)}))
        names_argument(lambda: sensor_context(sensor, other), ValueError, "sensor_model")


def test_platform_feeder_names_a_model_reading_another_position_than_its_sensor():
    from ctxmodels import SensorModel
    from ctxmodels.stonesoup import PlatformContextFeeder
    simulator, sensors = _simulator()
    models = _models(sensors)
    models[1] = SensorModel(detection=models[1].detection, clutter=models[1].clutter,
                            position_mapping=(0, 1))
    message = names_argument(lambda: PlatformContextFeeder(reader=simulator,
                                                           sensor_models=models),
                             ValueError, "sensor_models")
    assert "item 1" in message and "platform 1 sensor 0" in message


BAD_PROBABILITIES = [None, "0.9", True, np.bool_(False), NAN, INF, -0.1, 1.0000001, 2, [0.9],
                     np.array([0.9]), 1j, object()]
BAD_DENSITIES = [None, "x", True, 0, 0.0, -1e-4, NAN, INF, [1e-4], np.array([1e-4]), 1j,
                 np.float64(0.0), 5e-324]


@pytest.mark.parametrize("prob_detection", BAD_PROBABILITIES, ids=repr)
def test_from_stonesoup_names_prob_detection(prob_detection):
    from ctxmodels import SensorModel
    names_argument(lambda: SensorModel.from_stonesoup(_radar(), prob_detection, 1e-4),
                   (ValueError, TypeError), "prob_detection")


@pytest.mark.parametrize("clutter_density", BAD_DENSITIES, ids=repr)
def test_from_stonesoup_names_clutter_density(clutter_density):
    from ctxmodels import SensorModel
    names_argument(lambda: SensorModel.from_stonesoup(_radar(), 0.9, clutter_density),
                   (ValueError, TypeError), "clutter_density")


@pytest.mark.parametrize("name", [None, 5, b"radar", ["radar"]], ids=repr)
def test_from_stonesoup_names_name(name):
    from ctxmodels import SensorModel
    names_argument(lambda: SensorModel.from_stonesoup(_radar(), 0.9, 1e-4, name=name),
                   TypeError, "name")


@pytest.mark.parametrize("sensor", [None, 5, "radar", object(), [1]], ids=repr)
def test_from_stonesoup_names_sensor(sensor):
    from ctxmodels import SensorModel
    names_argument(lambda: SensorModel.from_stonesoup(sensor, 0.9, 1e-4), TypeError, "sensor")


@pytest.mark.parametrize("attribute, value", [("max_range", NAN), ("max_range", -1.0),
                                              ("max_range", "800"), ("max_range", None),
                                              ("max_range", True), ("fov_angle", 0.0),
                                              ("fov_angle", NAN), ("fov_angle", "1"),
                                              ("fov_angle", -1.0)], ids=str)
def test_from_stonesoup_names_the_sensor_for_its_bad_settings(attribute, value):
    from ctxmodels import SensorModel
    sensor = _radar(kind="rotating", fov=1.0)
    setattr(sensor, attribute, value)
    names_argument(lambda: SensorModel.from_stonesoup(sensor, 0.9, 1e-4),
                   (ValueError, TypeError), "sensor")


@pytest.mark.parametrize("prob_detection, clutter_density", [
    (0, 1e-4), (1, 1e-4), (np.float32(0.5), np.float32(1e-3)), (np.int64(1), np.int64(2)),
    (0.5, 1e300), (0.5, 2.2250738585072014e-308)], ids=str)
def test_from_stonesoup_accepts_every_real_number_type(prob_detection, clutter_density):
    from ctxmodels import SensorModel
    model = SensorModel.from_stonesoup(_radar(), prob_detection, clutter_density, name="r")
    assert model.detection.factors[0] == float(prob_detection)
    assert model.clutter.factors[0] == float(clutter_density)


def _simulator(sensors_per_platform=(1, 1), steps=3):
    from stonesoup.models.transition.linear import (CombinedLinearGaussianTransitionModel,
                                                    ConstantVelocity)
    from stonesoup.simulator.platform import PlatformDetectionSimulator
    from stonesoup.simulator.simple import MultiTargetGroundTruthSimulator
    from stonesoup.types.state import GaussianState
    transition = CombinedLinearGaussianTransitionModel([ConstantVelocity(0.5)] * 2)
    truths = MultiTargetGroundTruthSimulator(
        transition_model=transition,
        initial_state=GaussianState([[0], [0], [0], [0]], np.diag([100.0, 1, 100, 1]) ** 2,
                                    timestamp=T0),
        timestep=datetime.timedelta(seconds=1), number_steps=steps, birth_rate=0.5,
        death_probability=0.0, seed=1)
    from stonesoup.platform.base import FixedPlatform
    sensors = [_radar(position=(10.0 * k, 0.0)) for k in range(sum(sensors_per_platform))]
    fixed = []
    k = 0
    for count in sensors_per_platform:
        platform = FixedPlatform(states=[sensors[k].movement_controller.states[-1]],
                                 position_mapping=(0, 2), sensors=[])
        for sensor in sensors[k:k + count]:
            platform.add_sensor(sensor)
        fixed.append(platform)
        k += count
    return PlatformDetectionSimulator(groundtruth=truths, platforms=fixed), sensors


def _models(sensors):
    from ctxmodels import SensorModel
    return [SensorModel.from_stonesoup(s, 0.8, 1e-5) for s in sensors]


@pytest.mark.parametrize("models", ["one", None, "models", 5, {"a": 1}, "strings", "short",
                                    "long", "mounted"], ids=str)
def test_platform_feeder_names_bad_sensor_models_at_construction(models):
    from ctxmodels import Mounting, SensorModel
    from ctxmodels.stonesoup import PlatformContextFeeder
    simulator, sensors = _simulator()
    good = _models(sensors)
    given = {"one": good[0], "strings": ["a", "b"], "short": good[:1], "long": good * 2,
             "mounted": [good[0], SensorModel(detection=good[1].detection,
                                              clutter=good[1].clutter,
                                              mounting=Mounting(forward=1.0))]}
    given = given[models] if isinstance(models, str) and models in given else models
    names_argument(lambda: PlatformContextFeeder(reader=simulator, sensor_models=given),
                   (ValueError, TypeError), "sensor_models")


@pytest.mark.parametrize("reader", [None, [], 5, "sim"], ids=repr)
def test_platform_feeder_names_a_reader_that_is_not_a_platform_simulator(reader):
    from ctxmodels.stonesoup import PlatformContextFeeder
    names_argument(lambda: PlatformContextFeeder(reader=reader, sensor_models=[]), TypeError,
                   "reader")


def test_platform_feeder_names_a_sensor_mounted_after_it_was_built():
    from ctxmodels.stonesoup import PlatformContextFeeder
    simulator, sensors = _simulator()
    feeder = PlatformContextFeeder(reader=simulator, sensor_models=_models(sensors))
    simulator.platforms[1].add_sensor(_radar(position=(5.0, 5.0)))
    message = names_argument(lambda: list(feeder), ValueError, "sensor_models")
    assert "platform 1 sensor 1 (RadarBearingRange)" in message and str(T0) in message


def test_platform_feeder_gives_each_scan_its_sensors_model():
    from ctxmodels.stonesoup import PlatformContextFeeder, sensor_pose
    simulator, sensors = _simulator(sensors_per_platform=(2, 1))
    models = _models(sensors)
    scans = list(PlatformContextFeeder(reader=simulator, sensor_models=models))
    assert len(scans) == 3 * 3  # 3 sensors, 3 times
    for k, (_, scan) in enumerate(scans):
        assert scan.detector_context.sensor_model is models[k % 3]
        assert scan.detector_context.pose == sensor_pose(sensors[k % 3])


# --- learners ---------------------------------------------------------------------------------

def _learners():
    from ctxmodels.stonesoup import ClutterMapLearner, DetectionLearner
    return {"clutter": lambda **kw: ClutterMapLearner(gate_radius=30.0, **kw),
            "detection": lambda **kw: DetectionLearner(gate_radius=30.0, **kw)}


BAD_MAPPINGS = [(0, 0), (0,), (0, 1, 2), (-1, 2), (0, 2.0), (True, 2), "02", None, 5,
                {"x": 0, "y": 2}, (0, 2**40), (np.float64(0), 2)]


@pytest.mark.parametrize("kind", ["clutter", "detection"])
@pytest.mark.parametrize("mapping", BAD_MAPPINGS, ids=repr)
def test_learners_name_a_bad_position_mapping_at_construction(kind, mapping):
    names_argument(lambda: _learners()[kind](position_mapping=mapping), (ValueError, TypeError),
                   "position_mapping")


def _scan_with_estimates(kind):
    from stonesoup.models.measurement.linear import LinearGaussian
    from stonesoup.types.detection import Detection
    from ctxmodels import (ClutterDensityModel, ClutterMap, DetectionEstimate,
                           DetectionProbabilityModel, DetectionSet, Pose, SensorModel)
    measurement = LinearGaussian(ndim_state=4, mapping=(0, 2), noise_covar=np.eye(2))
    detection = (DetectionEstimate(edges=(0.0, 100.0, 200.0), prior_probability=0.5)
                 if kind == "detection" else 0.9)
    clutter = (ClutterMap(space="world-xy", edges=(np.linspace(-200, 200, 5),) * 2,
                          prior_intensity=1e-3)
               if kind == "clutter" else 1e-3)
    model = SensorModel(detection=DetectionProbabilityModel(factors=[detection]),
                        clutter=ClutterDensityModel(factors=[clutter]))
    context = model.context(Pose(x=0.0, y=0.0), T0)
    return DetectionSet({Detection([[10.0], [20.0]], timestamp=T0,
                                   measurement_model=measurement)}, context)


@pytest.mark.parametrize("kind", ["clutter", "detection"])
@pytest.mark.parametrize("mapping", [(0, 9), (4, 2), (2, 4)], ids=repr)
def test_learners_name_position_mapping_and_the_tracks_dimension_at_learn_time(kind, mapping):
    from stonesoup.types.state import State
    from stonesoup.types.track import Track
    learner = _learners()[kind](position_mapping=mapping)
    track = Track([State(np.array([[10.0], [0.0], [20.0], [0.0]]), timestamp=T0)])
    message = names_argument(lambda: learner.learn(T0, _scan_with_estimates(kind), {track}),
                             ValueError, "position_mapping")
    assert "4-D state" in message and str(T0) in message


@pytest.mark.parametrize("kind", ["clutter", "detection"])
@pytest.mark.parametrize("tracks", [None, 5, "tracks"], ids=repr)
def test_learners_name_tracks_that_are_not_tracks(kind, tracks):
    learner = _learners()[kind]()
    names_argument(lambda: learner.learn(T0, _scan_with_estimates(kind), tracks), TypeError,
                   "tracks")


@pytest.mark.parametrize("kind", ["clutter", "detection"])
@pytest.mark.parametrize("radius", [True, np.bool_(True), "30", None, NAN, INF, -1.0, [30.0],
                                    np.array([30.0]), 1j], ids=repr)
def test_learners_name_a_bad_gate_radius(kind, radius):
    from ctxmodels.stonesoup import ClutterMapLearner, DetectionLearner
    cls = ClutterMapLearner if kind == "clutter" else DetectionLearner
    names_argument(lambda: cls(gate_radius=radius), (ValueError, TypeError), "gate_radius")


@pytest.mark.parametrize("weighting", [None, 5, ["gates"], np.array(["gates"]), "GATES", ""],
                         ids=repr)
def test_clutter_learner_names_a_bad_weighting(weighting):
    from ctxmodels.stonesoup import ClutterMapLearner
    names_argument(lambda: ClutterMapLearner(gate_radius=30.0, weighting=weighting),
                   (ValueError, TypeError), "weighting")


@pytest.mark.parametrize("confirmation", [True, np.bool_(False), -1, 1.5, "3", None, NAN],
                         ids=repr)
def test_detection_learner_names_a_bad_confirmation(confirmation):
    from ctxmodels.stonesoup import DetectionLearner
    names_argument(lambda: DetectionLearner(gate_radius=30.0, confirmation=confirmation),
                   (ValueError, TypeError), "confirmation")


def _stone_soup_tracker():
    from stonesoup.tracker.simple import SingleTargetTracker
    return SingleTargetTracker(initiator=None, deleter=None, detector=[], data_associator=None,
                               updater=None)


@pytest.mark.parametrize("tracker", [None, 5, "tracker", [], object()], ids=repr)
def test_learning_tracker_names_a_tracker_that_is_not_one(tracker):
    from ctxmodels.stonesoup import LearningTracker
    names_argument(lambda: LearningTracker(tracker=tracker, learners=[]), TypeError, "tracker")


@pytest.mark.parametrize("learners", [5, None, "learners", {"a": 1}, "one", [None], [5],
                                      [object()]], ids=repr)
def test_learning_tracker_names_bad_learners(learners):
    from ctxmodels.stonesoup import LearningTracker
    given = _learners()["clutter"]() if learners == "one" else learners
    names_argument(lambda: LearningTracker(tracker=_stone_soup_tracker(), learners=given),
                   TypeError, "learners")


# --- feeders and paper_tracker ------------------------------------------------------------------

def _paper_models():
    from ctxmodels.experiment.sensors import paper_sensor_models
    paper = paper_sensor_models()
    return {"radar": paper["radar"], "lidar": paper["lidar"]}


def _lidar_detection(time, area=12.0):
    from stonesoup.models.measurement.linear import LinearGaussian
    from stonesoup.types.detection import Detection
    model = LinearGaussian(ndim_state=4, mapping=(0, 2), noise_covar=np.eye(2))
    return Detection([[10.0], [5.0]], timestamp=time, measurement_model=model,
                     metadata={} if area is None else {"area": area})


def _times(n):
    return [T0 + datetime.timedelta(seconds=k) for k in range(n)]


_DEFAULT = object()


def _paper(name="gmphd-context", streams=_DEFAULT, models=_DEFAULT, pose=_DEFAULT, **options):
    from ctxmodels.trackers import paper_tracker
    streams = {"radar": [(t, set()) for t in _times(3)],
               "lidar": [(t, {_lidar_detection(t)}) for t in _times(3)]} \
        if streams is _DEFAULT else streams
    return paper_tracker(name, streams, _paper_models() if models is _DEFAULT else models,
                         _navigation() if pose is _DEFAULT else pose, **options)


@pytest.mark.parametrize("streams", [[("radar", [])], [], None, "radar", 5,
                                     [(T0, set())]], ids=repr)
def test_paper_tracker_names_streams_that_are_not_a_mapping(streams):
    names_argument(lambda: _paper(streams=streams), TypeError, "streams")


@pytest.mark.parametrize("stream", [None, 5, "scans", {"t": 1}], ids=repr)
def test_paper_tracker_names_a_stream_that_is_not_scans(stream):
    message = names_argument(lambda: _paper(streams={"radar": stream}), TypeError, "streams")
    assert "'radar'" in message


@pytest.mark.parametrize("models", [[("radar", None)], "radar", 5], ids=repr)
def test_paper_tracker_names_sensor_models_that_are_not_a_mapping(models):
    names_argument(lambda: _paper(models=models), TypeError, "sensor_models")


def test_paper_tracker_names_sensor_models_missing_where_read():
    """None is accepted for trackers that read no model, and named where one is read."""
    names_argument(lambda: _paper(models=None), ValueError, "sensor_models")


@pytest.mark.parametrize("name", ["kalman", None, 5, "", "GMPHD-CONTEXT", ["gmphd-context"]],
                         ids=repr)
def test_paper_tracker_names_an_unknown_tracker(name):
    names_argument(lambda: _paper(name=name), ValueError, "name")


@pytest.mark.parametrize("primary", [5, ["radar"], True, "sonar", ""], ids=repr)
def test_paper_tracker_names_a_bad_primary(primary):
    names_argument(lambda: _paper(primary=primary), (ValueError, TypeError), "primary")


@pytest.mark.parametrize("fast", [None, 1, "yes", 0.0], ids=repr)
def test_paper_tracker_names_a_bad_fast(fast):
    names_argument(lambda: _paper(fast=fast), TypeError, "fast")


@pytest.mark.parametrize("radius", [True, "far", NAN, INF, -1.0, 0, [3000.0]], ids=repr)
def test_paper_tracker_names_a_bad_region_radius(radius):
    names_argument(lambda: _paper(region_radius=radius), ValueError, "region_radius")


@pytest.mark.parametrize("pose", [None, 5, "nav", object()], ids=repr)
def test_paper_tracker_names_a_bad_pose_source(pose):
    from ctxmodels.trackers import paper_tracker
    names_argument(lambda: paper_tracker("gmphd-context", {"radar": []}, _paper_models(), pose),
                   TypeError, "pose_source")


BAD_SCANS = {
    "none": lambda t: (t, None),
    "string-set": lambda t: (t, {"detection"}),
    "string": lambda t: (t, "detections"),
    "int": lambda t: (t, 5),
    "lone-detection": lambda t: (t, _lidar_detection(t)),
    "list-of-none": lambda t: (t, [None]),
    "triple": lambda t: (t, set(), 1),
    "none-item": lambda t: None,
    "float-time": lambda t: (1.5, set()),
}


@pytest.mark.parametrize("tracker", ["gmphd-context", "gmphd-uniform", "jpda"])
@pytest.mark.parametrize("bad", list(BAD_SCANS))
def test_paper_tracker_names_the_sensor_and_scan_of_a_bad_scan_at_construction(bad, tracker):
    times = _times(3)
    lidar = [(t, {_lidar_detection(t)}) for t in times]
    lidar[1] = BAD_SCANS[bad](times[1])
    streams = {"radar": [(t, set()) for t in times], "lidar": lidar}
    message = names_argument(lambda: _paper(name=tracker, streams=streams), TypeError, "streams")
    assert "'lidar'" in message
    if bad not in ("triple", "none-item", "float-time"):
        assert str(times[1]) in message


@pytest.mark.parametrize("tracker", ["gmphd-context", "gmphd-uniform"])
@pytest.mark.parametrize("bad", ["none", "string-set", "string", "lone-detection"])
def test_paper_tracker_names_the_sensor_and_scan_of_a_bad_scan_read_from_a_reader(bad, tracker):
    """Readers (not lists) are read as the tracker runs: the feeders name the scan."""
    times = _times(3)

    class Reader:
        def __iter__(self):
            yield times[0], {_lidar_detection(times[0])}
            yield BAD_SCANS[bad](times[1])

    tracker = _paper(name=tracker, streams={"radar": [(t, set()) for t in times],
                                            "lidar": Reader()})
    with pytest.raises(TypeError) as info:
        list(tracker)
    assert "(sensor 'lidar')" in str(info.value) and str(times[1]) in str(info.value)


@pytest.mark.parametrize("area", [None, "12", True, [12.0]], ids=repr)
def test_a_missing_or_bad_lidar_area_names_the_sensor_and_scan(area):
    times = _times(3)
    lidar = [(t, {_lidar_detection(t)}) for t in times]
    lidar[2] = (times[2], {_lidar_detection(times[2], area=area)})
    message = names_argument(lambda: _paper(streams={"radar": [], "lidar": lidar}),
                             (ValueError, TypeError), "streams")
    assert "'lidar'" in message and str(times[2]) in message and "'area'" in message


def test_a_missing_lidar_area_in_a_reader_names_the_sensor_and_scan_as_it_runs():
    times = _times(3)
    tracker = _paper(streams={"lidar": iter([(times[0], {_lidar_detection(times[0], None)})])})
    with pytest.raises(ValueError) as info:
        list(tracker)
    message = str(info.value)
    assert message.startswith("reader:") and "(sensor 'lidar')" in message \
        and str(times[0]) in message and "'area'" in message


@pytest.mark.parametrize("tracker", ["gmphd-context", "gmphd-uniform", "gmphd-pd-aware"])
def test_a_navigation_log_that_ends_too_early_names_the_sensor_and_scan(tracker):
    times = _times(5)  # the log covers 0..2 s
    streams = {"radar": [(t, set()) for t in times[:2]],
               "lidar": [(t, {_lidar_detection(t)}) for t in times]}
    message = names_argument(lambda: _paper(name=tracker, streams=streams), ValueError,
                             "pose_source")
    assert "'lidar'" in message and str(times[3]) in message


def test_a_pose_source_that_ends_too_early_names_the_sensor_and_scan_as_it_runs():
    navigation = _navigation()

    class Poses:  # not a NavigationTrack: asked as the scans come
        def pose_at(self, timestamp):
            return navigation.pose_at(timestamp)

    times = _times(5)
    tracker = _paper(streams={"lidar": [(t, {_lidar_detection(t)}) for t in times]},
                     pose=Poses())
    with pytest.raises(ValueError) as info:
        list(tracker)
    assert str(info.value).startswith("pose_source:") and "(sensor 'lidar')" in str(info.value) \
        and str(times[3]) in str(info.value)


def test_good_streams_still_track():
    tracker = _paper()
    assert [time for time, _ in tracker] == [t for t in _times(3) for _ in range(2)]


@pytest.mark.parametrize("feeders", ["one", None, 5, "abc", {"a": 1}], ids=repr)
def test_multi_sensor_feeder_names_bad_feeders(feeders):
    from ctxmodels import ConstantPose, Pose
    from ctxmodels.stonesoup import ContextFeeder, MultiSensorFeeder
    one = ContextFeeder(reader=[], sensor_model=_paper_models()["radar"],
                        pose_source=ConstantPose(pose=Pose(x=0.0, y=0.0)))
    given = one if feeders == "one" else feeders
    names_argument(lambda: MultiSensorFeeder(feeders=given), TypeError, "feeders")


@pytest.mark.parametrize("names", ["ab", ["a"], [1, 2], 5], ids=repr)
def test_multi_sensor_feeder_names_bad_sensor_names(names):
    from ctxmodels.stonesoup import MultiSensorFeeder
    names_argument(lambda: MultiSensorFeeder(feeders=[[], []], sensor_names=names), TypeError,
                   "sensor_names")


@pytest.mark.parametrize("name", [None, 5, ["radar"]], ids=repr)
def test_context_feeder_names_a_bad_sensor_name(name):
    from ctxmodels import ConstantPose, Pose
    from ctxmodels.stonesoup import ContextFeeder
    names_argument(lambda: ContextFeeder(reader=[], sensor_model=_paper_models()["radar"],
                                         pose_source=ConstantPose(pose=Pose(x=0.0, y=0.0)),
                                         sensor_name=name), TypeError, "sensor_name")


@pytest.mark.parametrize("times", ["timedelta64", "float", "mixed-kinds"])
def test_context_feeder_names_scan_times_it_cannot_use(times):
    from ctxmodels.stonesoup import ContextFeeder
    aware = datetime.datetime(2026, 1, 1, tzinfo=datetime.timezone.utc)
    scans = {"timedelta64": [(np.timedelta64(1, "s"), set())],
             "float": [(1.0, set()), (0.5, set())],
             "mixed-kinds": [(T0, set()), (aware, set())]}[times]
    feeder = ContextFeeder(reader=scans, sensor_model=_paper_models()["radar"],
                           pose_source=_navigation(), sensor_name="radar")
    with pytest.raises((TypeError, ValueError)) as info:
        list(feeder)
    assert str(info.value).split(":")[0] in ("reader", "pose_source"), str(info.value)
