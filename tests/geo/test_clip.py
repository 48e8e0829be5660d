"""A polygon with holes clipped to a box (ctxmodels.geo.clip), held against shapely's
intersection on random star-shaped polygons with holes and random boxes."""
import numpy as np
import pytest
import shapely
from hypothesis import assume, given
from hypothesis import strategies as st

from ctxmodels import LandMask
from ctxmodels.geo.clip import clip_to_box, signed_area


def star(rng, centre, r_min, r_max, k):
    angles = np.sort(rng.uniform(0, 2 * np.pi, k))
    radii = rng.uniform(r_min, r_max, k)
    return np.column_stack([centre[0] + radii * np.cos(angles), centre[1] + radii * np.sin(angles)])


def ours_as_shapely(pieces):
    return shapely.MultiPolygon([shapely.Polygon(s, h) for s, h in pieces])


def check(shell, holes, box):
    pieces = clip_to_box(shell, holes, box)
    theirs = shapely.Polygon(shell, holes).intersection(shapely.box(*box))
    for ring, inner in pieces:
        assert signed_area(ring) > 0
        assert all(signed_area(h) < 0 for h in inner)
        assert shapely.Polygon(ring, inner).is_valid
    ours = ours_as_shapely(pieces)
    scale = max(theirs.area, 1e-12)
    assert abs(ours.area - theirs.area) <= 1e-9 * scale + 1e-12
    assert ours.symmetric_difference(theirs).area <= 1e-9 * scale + 1e-12
    if pieces:
        LandMask(polygons=[{"shell": s, "holes": h} for s, h in pieces])  # valid land
    return pieces


@given(seed=st.integers(0, 2**32 - 1), k=st.integers(3, 60), n_holes=st.integers(0, 3))
def test_random_star_polygons_with_holes_match_shapely(seed, k, n_holes):
    rng = np.random.default_rng(seed)
    shell = star(rng, (0.0, 0.0), 2.0, 10.0, k)
    holes = []
    for j in range(n_holes):  # small stars around points well inside the shell's inner disc
        angle = 2 * np.pi * j / max(n_holes, 1)
        centre = (0.9 * np.cos(angle), 0.9 * np.sin(angle))
        holes.append(star(rng, centre, 0.1, 0.4, int(rng.integers(3, 12))))
    assume(shapely.Polygon(shell, holes).is_valid)  # the holes inside the shell (a star's
    x = np.sort(rng.uniform(-12, 12, 2))             # edges can pass near its centre)
    y = np.sort(rng.uniform(-12, 12, 2))
    check(shell, holes, (x[0], y[0], x[1] + 1e-3, y[1] + 1e-3))


def test_whole_cases():
    square = np.array([[0.0, 0], [10, 0], [10, 10], [0, 10]])
    lake = np.array([[4.0, 4], [6, 4], [6, 6], [4, 6]])
    # box inside the land: the box itself
    (ring, holes), = check(square, [], (1, 1, 2, 2))
    assert abs(signed_area(ring) - 1.0) < 1e-12 and holes == []
    # box inside the lake: no land
    assert check(square, [lake], (4.5, 4.5, 5.5, 5.5)) == []
    # box around everything: the polygon, its lake kept as a hole
    (ring, holes), = check(square, [lake], (-1, -1, 11, 11))
    assert len(holes) == 1
    # box apart: nothing
    assert check(square, [lake], (20, 20, 30, 30)) == []
    # the box's centre in a lake wholly inside the box: the box is land with the lake
    (ring, holes), = check(square, [lake], (3, 3, 7, 7))
    assert len(holes) == 1 and abs(signed_area(ring) - 16) < 1e-12
    # a lake touching the box's side from inside
    check(square, [np.array([[3.0, 4], [6, 4], [6, 6], [3, 6]])], (3, 3, 7, 7))
    # a lake cut by the box's side becomes a bay of the shell
    (ring, holes), = check(square, [lake], (1, 1, 5, 9))
    assert holes == [] and abs(signed_area(ring) - (4 * 8 - 2)) < 1e-12


def test_vertices_on_the_box_side_are_proper_crossings():
    # a comb whose teeth touch y = 5 exactly, and vertices on x = 0
    comb = np.array([[0.0, 0], [6, 0], [6, 5], [5, 2], [4, 5], [3, 2], [2, 5], [1, 2], [0, 5]])
    pieces = check(comb, [], (0.0, 1.0, 6.0, 5.0))
    assert len(pieces) == 1
    pieces = check(comb, [], (-1.0, 3.0, 7.0, 6.0))  # cuts the teeth apart
    assert len(pieces) == 4  # teeth at x = 0, 2, 4, 6


@pytest.mark.parametrize("orientation", [1, -1])
def test_orientation_of_the_input_does_not_matter(orientation):
    rng = np.random.default_rng(4)
    shell = star(rng, (0.0, 0.0), 2.0, 10.0, 40)[::orientation]
    hole = star(rng, (0.5, 0.0), 0.2, 0.6, 7)[::-orientation]
    check(shell, [hole], (-3.0, -5.0, 6.0, 0.3))


@pytest.mark.parametrize("shell, box, message", [
    ([[0, 0], [1, 0], [0, 1]], (7, 7, 3, 3), "box: expected finite"),
    ([[0, 0], [1, 0], [0, 1]], (float("nan"), 0, 1, 1), "box: expected finite"),
    ([[0, 0], [1, 0], [0, 1]], (0, 0, 0, 1), "box: expected finite"),
    ([[0, 0], [1, 0], [0, 1]], "box", "box: expected"),
    ([[0, 0], [1, 0]], (0, 0, 1, 1), "shell: expected"),
    ([0, 1, 2], (0, 0, 1, 1), "shell: expected"),
    ([[0, 0], [1, float("nan")], [0, 1]], (0, 0, 1, 1), "shell: vertices must be finite"),
])
def test_bad_input_is_named(shell, box, message):
    with pytest.raises((TypeError, ValueError), match=message):
        clip_to_box(shell, [], box)


def test_a_ring_that_crosses_itself_is_refused_not_looped_on():
    bowtie = np.array([[0.0, 0], [4, 4], [4, 0], [0, 4]])
    with pytest.raises(ValueError, match="cross"):
        for box in [(1, -1, 3, 5), (-1, 1, 5, 3), (1, 1, 3, 3), (0.5, -1, 1.5, 5)]:
            clip_to_box(bowtie, [], box)
