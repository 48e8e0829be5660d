"""Land masks and line of sight held against shapely 2 (GEOS) as the independent reference.

Random star-shaped, jagged polygons with holes (and islands in those holes), several per
mask. Containment: ``shapely.intersects_xy`` on the union (boundary counts as land).
Line of sight: ``LineString([sensor, target]).intersects(land)``. Where a floating-point
answer may legitimately differ (a point or segment within 1e-6 m of the coastline) the
reference is taken only when land grown and shrunk by that margin agree; vertices and the
integer-coordinate cases are compared exactly, boundary included.
"""
import math

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st
from shapely.geometry import MultiPolygon, Polygon

from ctxmodels import (AngularSector, ClutterDensityModel, DetectionProbabilityModel, LandMask,
                       LineOfSight, Pose, RangeBands, SensorModel)


def examples(n: int) -> int:
    return max(1, n * settings().max_examples // 100)


EPS = 1e-6
seeds = st.integers(0, 2**32 - 1)


def star_ring(rng, cx, cy, rmin, rmax, n, jagged=False):
    """A star-shaped ring around (cx, cy): jittered angles, radii in [rmin, rmax] (spikes
    alternating with notches when jagged)."""
    t = (np.arange(n) + rng.uniform(0.05, 0.95, n)) * 2 * np.pi / n
    r = rng.uniform(rmin, rmax, n)
    if jagged:
        r = np.where(np.arange(n) % 2 == 0, rmax - 0.1 * (rmax - rmin) * rng.random(n), r)
    return np.column_stack([cx + r * np.cos(t), cy + r * np.sin(t)])


def random_land(rng, n_polygons, max_vertices, n_holes, island, jagged):
    """Up to nine non-overlapping polygons on a 300 m grid. A shell has ≥ 12 vertices at radii
    ≥ 60 m, so it contains the 52 m disc its holes (≤ 40 m out) live in."""
    polygons = []
    for k in range(n_polygons):
        cx, cy = 300.0 * (k % 3) + rng.uniform(-20, 20), 300.0 * (k // 3) + rng.uniform(-20, 20)
        shell = star_ring(rng, cx, cy, 60, 120, int(rng.integers(12, max_vertices + 1)), jagged)
        holes = []
        for h in range(n_holes):
            a = 2 * np.pi * h / 3
            hx, hy = cx + 28 * math.cos(a), cy + 28 * math.sin(a)
            holes.append(star_ring(rng, hx, hy, 8 if h == 0 else 4, 12, int(rng.integers(8, 40))))
            if h == 0 and island:
                polygons.append(Polygon(star_ring(rng, hx, hy, 2, 4, int(rng.integers(3, 12)))))
        polygons.append(Polygon(shell, holes))
    assert all(p.is_valid for p in polygons)
    return polygons


land_configs = st.fixed_dictionaries({
    "n_polygons": st.integers(1, 5), "max_vertices": st.sampled_from([12, 60, 600]),
    "n_holes": st.integers(0, 3), "island": st.booleans(), "jagged": st.booleans()})


def robust_points(geometry, points):
    """shapely's containment (boundary included), and which points are over EPS from the
    boundary so that any correct floating-point answer must agree."""
    boundary = geometry.boundary
    shapely.prepare(boundary)
    clear = ~shapely.dwithin(boundary, shapely.points(points), EPS)
    return shapely.intersects_xy(geometry, points[:, 0], points[:, 1]), clear


def robust_segments(geometry, lines):
    """Whether each segment meets land, and where that answer is the same for land grown
    and shrunk by EPS (mitred, so the buffers stay as small as the coastline)."""
    grown = geometry.buffer(EPS, quad_segs=1, join_style="mitre")
    shrunk = geometry.buffer(-EPS, quad_segs=1, join_style="mitre")
    shapely.prepare(grown)
    shapely.prepare(shrunk)
    wide = shapely.intersects(grown, lines)
    return wide, wide == shapely.intersects(shrunk, lines)


@settings(max_examples=examples(25))
@given(config=land_configs, seed=seeds)
def test_containment_matches_shapely(config, seed):
    rng = np.random.default_rng(seed)
    polygons = random_land(rng, **config)
    union = shapely.union_all(polygons)
    land = LandMask(polygons=polygons)
    vertices = np.concatenate([np.asarray(ring.coords) for p in polygons
                               for ring in [p.exterior, *p.interiors]])
    xmin, ymin, xmax, ymax = union.bounds
    points = np.concatenate([
        rng.uniform([xmin - 30, ymin - 30], [xmax + 30, ymax + 30], (10_000, 2)),
        vertices[rng.integers(0, len(vertices), 3000)] + rng.normal(0, 0.05, (3000, 2)),
        # x exactly on a vertex's x: the index's walk meets that vertex and falls back.
        np.column_stack([vertices[rng.integers(0, len(vertices), 2000), 0],
                         rng.uniform(ymin - 5, ymax + 5, 2000)]),
    ])
    got = land.contains(points)
    expected, robust = robust_points(union, points)
    assert robust.mean() > 0.99
    np.testing.assert_array_equal(got[robust], expected[robust])
    assert 0.02 < expected.mean() < 0.98
    assert land.contains(vertices).all()  # the boundary is land
    assert land.vertex_count == sum(len(ring.coords) - 1 for p in polygons
                                    for ring in [p.exterior, *p.interiors])


@settings(max_examples=examples(12))
@given(seed=seeds, n=st.integers(1, 3))
def test_integer_coordinates_match_shapely_exactly_on_the_boundary(seed, n):
    """Integer vertices queried on the integer lattice: many points lie exactly on edges
    and at vertex x's, where both sides are exact."""
    rng = np.random.default_rng(seed)
    polygons = []
    for k in range(n):
        ring = np.round(star_ring(rng, 60.0 * k, 0.0, 10, 28, int(rng.integers(3, 30))))
        ring = ring[np.any(ring != np.roll(ring, 1, axis=0), axis=1)]
        polygon = Polygon(ring)
        if polygon.is_valid and len(ring) >= 3 and polygon.area > 0:
            polygons.append(polygon)
    if not polygons:
        polygons = [Polygon([(0, 0), (10, 0), (10, 10)])]
    land = LandMask(polygons=polygons)
    xs, ys = np.meshgrid(np.arange(-35.0, 60.0 * n), np.arange(-35.0, 36.0))
    points = np.column_stack([xs.ravel(), ys.ravel()])
    halves = points + 0.5  # and the lattice of half-integers
    union = shapely.union_all(polygons)
    for query in (points, halves):
        np.testing.assert_array_equal(land.contains(query),
                                      shapely.intersects_xy(union, query[:, 0], query[:, 1]))
    on_boundary = shapely.intersects_xy(union.boundary, points[:, 0], points[:, 1])
    assert on_boundary.sum() >= len(polygons) * 3 and land.contains(points[on_boundary]).all()


@settings(max_examples=examples(15))
@given(config=land_configs, seed=seeds)
def test_line_of_sight_matches_shapely(config, seed):
    rng = np.random.default_rng(seed)
    polygons = random_land(rng, **config)
    union = shapely.union_all(polygons)
    xmin, ymin, xmax, ymax = union.bounds
    low, high = [xmin - 100, ymin - 100], [xmax + 100, ymax + 100]
    grown = union.buffer(EPS)
    sensor = rng.uniform(low, high)
    while shapely.intersects_xy(grown, *sensor):  # the sensor is at sea
        sensor = rng.uniform(low, high)
    targets = np.concatenate([rng.uniform(low, high, (10_000, 2)),
                              sensor + rng.normal(0, 30, (500, 2))])
    sight = LineOfSight(land=LandMask(polygons=polygons))
    got = sight.visible(sensor, targets)
    lines = shapely.linestrings(np.stack([np.broadcast_to(sensor, targets.shape), targets], axis=1))
    blocked, robust = robust_segments(union, lines)
    assert robust.mean() > 0.99
    np.testing.assert_array_equal(got[robust], ~blocked[robust])
    assert 0 < got.mean() < 1


@settings(max_examples=examples(12))
@given(config=land_configs, seed=seeds, clearance=st.sampled_from([0.0, 5.0, 40.0]))
def test_line_of_sight_with_clearance_matches_shapely(config, seed, clearance):
    """A sensor anywhere, on land too: the segment tested starts ``clearance`` along the way
    (shapely on that segment), a target nearer than that is blocked only on land; the
    single queries and a scan's index (through a DetectionModel) agree."""
    rng = np.random.default_rng(seed)
    polygons = random_land(rng, **config)
    union = shapely.union_all(polygons)
    xmin, ymin, xmax, ymax = union.bounds
    low, high = [xmin - 100, ymin - 100], [xmax + 100, ymax + 100]
    sensor = rng.uniform(low, high)
    targets = np.concatenate([rng.uniform(low, high, (5_000, 2)), sensor + rng.normal(0, 30, (500, 2))])
    land = LandMask(polygons=polygons)
    sight = LineOfSight(land=land, clearance=clearance)
    got = sight.visible(sensor, targets)
    offset = targets - sensor
    distance = np.hypot(offset[:, 0], offset[:, 1])
    far = distance > clearance
    starts = sensor + offset * (clearance / np.where(far, distance, 1.0))[:, None]
    lines = shapely.linestrings(np.stack([starts[far], targets[far]], axis=1))
    blocked, robust = robust_segments(union, lines)
    assert robust.mean() > 0.99
    np.testing.assert_array_equal(got[far][robust], ~blocked[robust])
    on_land, clear = robust_points(union, targets[~far])
    np.testing.assert_array_equal(got[~far][clear], ~on_land[clear])
    states = np.column_stack([targets[:, 0], np.zeros(len(targets)), targets[:, 1], np.zeros(len(targets))])
    scan = DetectionProbabilityModel(factors=[sight]).evaluate(Pose(x=sensor[0], y=sensor[1]), states)
    np.testing.assert_array_equal(scan, got.astype(float))


def test_clearance_lets_a_radar_on_land_see_over_its_own_coast():
    square = np.array([[0.0, 0], [100, 0], [100, 100], [0, 100]])
    far_island = np.array([[300.0, 40], [320, 40], [320, 60], [300, 60]])
    land = LandMask(polygons=[square, far_island])
    sensor, targets = (90.0, 50.0), np.array([[200.0, 50], [400.0, 50], [-50.0, 50], [95.0, 50]])
    assert not LineOfSight(land=land).visible(sensor, targets).any()  # at sea: all shadowed
    # 20 m of clearance clears its own coast 10 m away, not the far island nor its own land
    # 90 m behind it; the target 5 m away stands on land
    assert LineOfSight(land=land, clearance=20.0).visible(sensor, targets).tolist() == [
        True, False, False, False]


@pytest.mark.parametrize("clearance", [-1.0, float("nan"), float("inf"), "10"])
def test_bad_clearance_is_named(clearance):
    land = LandMask(polygons=[np.array([[0.0, 0], [1, 0], [0, 1]])])
    with pytest.raises((ValueError, TypeError), match="clearance"):
        LineOfSight(land=land, clearance=clearance)


@settings(max_examples=examples(10))
@given(seed=seeds, heading=st.floats(-7, 7))
def test_land_and_sight_factors_in_a_detection_model(seed, heading):
    """P_D = bands × sector × (not on land) × (not shadowed), from the sensor's pose."""
    rng = np.random.default_rng(seed)
    polygons = random_land(rng, 4, 80, 1, True, False)
    union = shapely.union_all(polygons)
    mask = LandMask(polygons=polygons)
    bands = RangeBands(edges=(50.0, 500.0), values=(0.0, 0.9, 0.3))
    sector = AngularSector.blind(math.pi, math.radians(65))
    model = DetectionProbabilityModel(factors=[bands, sector, mask, LineOfSight(land=mask)])
    sensor = np.array([150.0, 150.0]) + rng.normal(0, 10, 2)  # between the four islands
    assert not shapely.intersects_xy(union.buffer(1.0), *sensor)
    targets = rng.uniform(-200, 500, (10_000, 2))
    got = model.evaluate(Pose(x=sensor[0], y=sensor[1], heading=heading), targets, (0, 1))
    without_land = DetectionProbabilityModel(factors=[bands, sector]).evaluate(
        Pose(x=sensor[0], y=sensor[1], heading=heading), targets, (0, 1))
    lines = shapely.linestrings(np.stack([np.broadcast_to(sensor, targets.shape), targets], axis=1))
    blocked, robust = robust_segments(union, lines)
    np.testing.assert_array_equal(got[robust], np.where(blocked, 0.0, without_land)[robust])
    assert (got[robust] == 0).any() and (got[robust] > 0).any()


# --- explicit cases ----------------------------------------------------------------------------
SQUARE = np.array([[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]])
HOLE = np.array([[3.0, 3.0], [7.0, 3.0], [7.0, 7.0], [3.0, 7.0]])
ISLAND = np.array([[4.5, 4.5], [5.5, 4.5], [5.0, 5.5]])


def test_boundary_holes_and_islands():
    land = LandMask(polygons=[(SQUARE, [HOLE]), ISLAND])
    points = np.array([[1, 1], [5, 3.5], [5, 4.8], [0, 5], [10, 10], [3, 5], [5.0, 5.5],
                       [11, 5], [-1e-12, 5], [4.0, 6.5]])
    np.testing.assert_array_equal(land.contains(points),
                                  [True, False, True, True, True, True, True, False, False, False])


def test_orientation_closing_vertex_and_input_forms_do_not_matter():
    reference = LandMask(polygons=[(SQUARE, [HOLE])])
    points = np.random.default_rng(5).uniform(-2, 12, (10_000, 2))
    expected = reference.contains(points)
    closed_cw = np.vstack([SQUARE[::-1], SQUARE[-1:]])
    forms = [
        [(closed_cw, [HOLE[::-1]])],
        [{"shell": SQUARE.tolist(), "holes": [HOLE.tolist()]}],
        [Polygon(SQUARE, [HOLE])],
        Polygon(SQUARE, [HOLE]),
        MultiPolygon([Polygon(SQUARE, [HOLE])]),
    ]
    for form in forms:
        np.testing.assert_array_equal(LandMask(polygons=form).contains(points), expected)


def test_multipolygon_from_shapely_matches_the_polygons():
    rng = np.random.default_rng(8)
    polygons = random_land(rng, 3, 50, 2, True, True)
    points = rng.uniform(-150, 750, (10_000, 2))
    from_list = LandMask(polygons=polygons).contains(points)
    multi = shapely.union_all(polygons)
    assert isinstance(multi, MultiPolygon)
    np.testing.assert_array_equal(LandMask(polygons=multi).contains(points), from_list)


def test_line_of_sight_explicit_cases():
    sight = LineOfSight(land=LandMask(polygons=[np.array([[100.0, -10.0], [120.0, -10.0],
                                                         [120.0, 10.0], [100.0, 10.0]])]))
    sensor = (0.0, 0.0)
    targets = np.array([
        [200.0, 0.0],    # behind the island: shadowed
        [50.0, 0.0],     # in front: visible
        [200.0, 40.0],   # clear of it
        [110.0, 0.0],    # on land
        [100.0, 0.0],    # on the coast
        [200.0, 20.0],   # grazing the corner (100, 10) exactly: blocked
        [200.0, 20.5],   # passing just above it
        [0.0, 0.0],      # the sensor's own position (at sea)
        [130.0, 0.0],    # right behind the far coast
    ])
    np.testing.assert_array_equal(sight.visible(sensor, targets),
                                  [False, True, True, False, False, False, True, True, False])


def test_line_of_sight_inside_a_lake():
    """A sensor in a lake sees across the lake, not past its shore, and not the island."""
    sight = LineOfSight(land=LandMask(polygons=[(SQUARE * 10, [HOLE * 10]), ISLAND * 10]))
    sensor = (35.0, 35.0)
    targets = np.array([[65.0, 35.0], [35.0, 65.0], [65.0, 65.0], [50.0, 80.0], [150.0, 35.0]])
    np.testing.assert_array_equal(sight.visible(sensor, targets), [True, True, False, False, False])


def test_sensor_model_with_land_uses_the_mounted_sensor_position():
    """Line of sight is cast from the sensor's pose at the scan, not from the world origin."""
    land = LandMask(polygons=[np.array([[100.0, -10.0], [120.0, -10.0], [120.0, 10.0], [100.0, 10.0]])])
    model = SensorModel(detection=DetectionProbabilityModel(factors=[0.8, land, LineOfSight(land=land)]),
                        clutter=ClutterDensityModel(factors=[1e-3]))
    target = np.array([[200.0, 0.0, 0.0, 0.0]])
    assert model.context(Pose(x=0.0, y=0.0, heading=0.0)).prob_detection_array(target)[0] == 0.0
    assert model.context(Pose(x=0.0, y=100.0, heading=0.0)).prob_detection_array(target)[0] == 0.8
    assert model.context(Pose(x=300.0, y=0.0, heading=2.0)).prob_detection_array(target)[0] == 0.8


@pytest.mark.parametrize("n_vertices", [3, 1000, 10_000])
def test_large_coastline_matches_shapely(n_vertices):
    rng = np.random.default_rng(n_vertices)
    polygon = Polygon(star_ring(rng, 0.0, 0.0, 500.0, 1000.0, n_vertices, jagged=True))
    land = LandMask(polygons=[polygon])
    points = rng.uniform(-1100, 1100, (20_000, 2))
    expected, robust = robust_points(polygon, points)
    np.testing.assert_array_equal(land.contains(points)[robust], expected[robust])
    assert robust.mean() > 0.99
