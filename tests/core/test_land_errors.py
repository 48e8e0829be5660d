"""Hostile inputs to land: GeoJSON documents, strings and files (bad ones are refused naming
the source and where in the document), polygons, the line of sight's sensor position and
land, and lon/lat mapped to local metres (beyond the local plane's reach, bad origins,
unknown backends). Bad input raises ValueError/TypeError whose message starts with the
argument's name; valid extremes give the right land."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest

from ctxmodels import LandMask, LineOfSight
from ctxmodels.geo import MAX_DISTANCE, lonlat_to_local, pyproj_available
from ..hostile import names_argument

NAN, INF = float("nan"), float("inf")
BACKENDS = ["numpy"] + (["pyproj"] if pyproj_available() else [])


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
