r"""A polygon with holes clipped to an axis-aligned box: the land of a map tile.

The rings are oriented so that land lies on their left (shell counter-clockwise, holes
clockwise). Walking each ring, the parts strictly inside the box are *fragments*: each
enters the box at a point of its boundary and leaves it at another (Liang–Barsky per edge;
the crossing points are put exactly on the box's side). The boundary of land ∩ box is then
the fragments joined by the box's own boundary, walked counter-clockwise from each
fragment's exit to the nearest entry (Weiler–Atherton with a convex clip window): land lies
on the left of an exit, so it continues along the box that way. Every ring it yields is a
shell, counter-clockwise.

Rings that never cross the box are whole: inside, they are kept (holes go to the shell
around them); outside, they are dropped, unless the box lies inside one — then the box is
land (inside a shell) or water (inside a hole). No vertex may lie on the box's boundary
(:func:`clip_to_box` moves a side that would by a nano-degree outwards first), so every
crossing is a proper one.
"""
from __future__ import annotations

import numpy as np

Ring = np.ndarray  # (K, 2), not closed (the last vertex is not the first repeated)


def signed_area(ring: Ring) -> float:
    """Shoelace area: positive for a counter-clockwise ring."""
    x, y = ring[:, 0], ring[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))


def contains(ring: Ring, point) -> bool:
    """Even–odd point in polygon (``point`` not on the ring)."""
    px, py = point
    x, y = ring[:, 0], ring[:, 1]
    x2, y2 = np.roll(x, -1), np.roll(y, -1)
    straddles = (y > py) != (y2 > py)
    with np.errstate(divide="ignore", invalid="ignore"):
        at = x + (py - y) * (x2 - x) / (y2 - y)
    return bool(np.count_nonzero(straddles & (px < at)) % 2)


def _oriented(ring: Ring, counter_clockwise: bool) -> Ring:
    return ring if (signed_area(ring) > 0) == counter_clockwise else ring[::-1]


def _perimeter_position(point, box) -> float:
    """Where a point on the box's boundary lies along it, counter-clockwise from
    (x0, y0): bottom [0, 1), right [1, 2), top [2, 3), left [3, 4)."""
    x0, y0, x1, y1 = box
    x, y = point
    if y == y0:
        return (x - x0) / (x1 - x0)
    if x == x1:
        return 1.0 + (y - y0) / (y1 - y0)
    if y == y1:
        return 2.0 + (x1 - x) / (x1 - x0)
    return 3.0 + (y1 - y) / (y1 - y0)


def _crossing(a, b, t: float, box):
    """The point a + t (b - a), put exactly on the box side it lies on."""
    x0, y0, x1, y1 = box
    x, y = a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])
    sides = [(abs(x - x0), 0, x0), (abs(x - x1), 0, x1), (abs(y - y0), 1, y0), (abs(y - y1), 1, y1)]
    _, axis, value = min(sides)
    point = [min(max(x, x0), x1), min(max(y, y0), y1)]
    point[axis] = value
    return tuple(point)


def _inside_span(a, b, box) -> tuple[float, float] | None:
    """Liang–Barsky: the parameters [t0, t1] of the segment a→b inside the closed box."""
    x0, y0, x1, y1 = box
    t0, t1 = 0.0, 1.0
    dx, dy = b[0] - a[0], b[1] - a[1]
    for p, q in ((-dx, a[0] - x0), (dx, x1 - a[0]), (-dy, a[1] - y0), (dy, y1 - a[1])):
        if p == 0.0:
            if q < 0.0:
                return None
            continue
        t = q / p
        if p < 0.0:
            t0 = max(t0, t)
        else:
            t1 = min(t1, t)
        if t0 > t1:
            return None
    return t0, t1


def _fragments(ring: Ring, box) -> list[list] | None:
    """The ring's runs strictly inside the box, each from its entry to its exit point;
    ``None`` when the ring has no vertex outside (it is wholly inside)."""
    x0, y0, x1, y1 = box
    inside = (ring[:, 0] > x0) & (ring[:, 0] < x1) & (ring[:, 1] > y0) & (ring[:, 1] < y1)
    if inside.all():
        return None
    start = int(np.argmin(inside))
    n = len(ring)
    x, y = ring[:, 0], ring[:, 1]
    x2, y2 = np.roll(x, -1), np.roll(y, -1)
    # an edge with both ends beyond one side of the box cannot meet it
    apart = (((x <= x0) & (x2 <= x0)) | ((x >= x1) & (x2 >= x1))
             | ((y <= y0) & (y2 <= y0)) | ((y >= y1) & (y2 >= y1)))
    fragments, current = [], None
    # in a fragment, the edge starts inside, so it is never apart: skipping every apart
    # edge skips no edge of a fragment
    walk = (start + np.arange(n)) % n
    for k in walk[~apart[walk]].tolist():
        a, b = ring[k], ring[(k + 1) % n]
        b_inside = bool(inside[(k + 1) % n])
        if current is None:
            span = _inside_span(a, b, box)
            if span is None or span[1] <= span[0]:
                continue
            current = [_crossing(a, b, span[0], box)]
        if b_inside:
            current.append((float(b[0]), float(b[1])))
        else:
            span = _inside_span(a, b, box)
            current.append(_crossing(a, b, span[1], box))
            fragments.append(current)
            current = None
    return fragments


def _corners_between(s_from: float, s_to: float, box) -> list:
    """The box's corners passed walking counter-clockwise from s_from to s_to."""
    x0, y0, x1, y1 = box
    corners = [(1.0, (x1, y0)), (2.0, (x1, y1)), (3.0, (x0, y1)), (4.0, (x0, y0))]
    span = (s_to - s_from) % 4.0
    passed = []
    for s, corner in corners + [(s + 4.0, c) for s, c in corners]:
        if 0.0 < s - s_from < span:
            passed.append(corner)
    return passed


def _join(fragments: list[list], box) -> list[Ring]:
    entries = [_perimeter_position(f[0], box) for f in fragments]
    exits = [_perimeter_position(f[-1], box) for f in fragments]
    unused = set(range(len(fragments)))
    rings = []
    while unused:
        first = min(unused)
        points, k = [], first
        while True:
            unused.discard(k)
            points.extend(fragments[k])
            following = min(range(len(fragments)),
                            key=lambda j: ((entries[j] - exits[k]) % 4.0, j))
            points.extend(_corners_between(exits[k], entries[following], box))
            if following == first:
                break
            if following not in unused:  # only rings that cross themselves lead back here
                raise ValueError("shell: the rings cross one another or themselves (not a "
                                 "simple polygon with holes inside it)")
            k = following
        rings.append(np.array(points, dtype=np.float64))
    return rings


def _nudged(box, rings: list[Ring]):
    """The box with any side that passes through a vertex moved outwards by a
    nano-degree (so that every crossing is proper)."""
    x0, y0, x1, y1 = box
    points = np.concatenate(rings)
    while np.any(points[:, 0] == x0):
        x0 = np.nextafter(x0 - 1e-9, -np.inf)
    while np.any(points[:, 0] == x1):
        x1 = np.nextafter(x1 + 1e-9, np.inf)
    while np.any(points[:, 1] == y0):
        y0 = np.nextafter(y0 - 1e-9, -np.inf)
    while np.any(points[:, 1] == y1):
        y1 = np.nextafter(y1 + 1e-9, np.inf)
    return float(x0), float(y0), float(x1), float(y1)


def _ring(ring, name: str) -> np.ndarray:
    try:
        ring = np.asarray(ring, dtype=np.float64)
    except (TypeError, ValueError):
        raise TypeError(f"{name}: expected (K, 2) vertices") from None
    if ring.ndim != 2 or ring.shape[1] != 2 or len(ring) < 3:
        raise ValueError(f"{name}: expected (K, 2) vertices, K >= 3, got shape {ring.shape}")
    if not np.isfinite(ring).all():
        raise ValueError(f"{name}: vertices must be finite")
    return ring


def clip_to_box(shell: Ring, holes: list[Ring], box) -> list[tuple[Ring, list[Ring]]]:
    """``shell`` minus ``holes``, intersected with ``box`` = (x0, y0, x1, y1): a list of
    (shell, holes) polygons, shells counter-clockwise and holes clockwise. Exact but for
    the nudge of a box side that passes through a vertex (module docs): a polygon that
    touches the box from outside leaves a sliver a nano-degree wide."""
    try:
        x0, y0, x1, y1 = (float(v) for v in box)
    except (TypeError, ValueError):
        raise TypeError(f"box: expected (x0, y0, x1, y1), got {box!r}") from None
    if not (np.isfinite([x0, y0, x1, y1]).all() and x0 < x1 and y0 < y1):
        raise ValueError(f"box: expected finite x0 < x1 and y0 < y1, got {box!r}")
    shell = _oriented(_ring(shell, "shell"), True)
    holes = [_oriented(_ring(h, f"holes[{k}]"), False) for k, h in enumerate(holes)]
    box = _nudged((x0, y0, x1, y1), [shell, *holes])
    x0, y0, x1, y1 = box
    whole_holes, fragments = [], []
    shell_pieces = _fragments(shell, box)
    whole_shell = shell_pieces is None
    fragments += shell_pieces or []
    for hole in holes:
        pieces = _fragments(hole, box)
        if pieces is None:
            whole_holes.append(hole)
        else:
            fragments += pieces
    if whole_shell:
        shells = [shell]
    elif fragments:
        shells = _join(fragments, box)
    else:
        # no ring crosses the box's boundary: the boundary is all land or all water, as its
        # corner is (the box's centre could lie in a hole wholly inside the box)
        corner = (x0, y0)
        box_is_land = contains(shell, corner) and not any(contains(h, corner) for h in holes)
        shells = [np.array([(x0, y0), (x1, y0), (x1, y1), (x0, y1)])] if box_is_land else []
    polygons = []
    for ring in shells:
        inner = [h for h in whole_holes if contains(ring, h[0])]
        polygons.append((ring, inner))
    return polygons
