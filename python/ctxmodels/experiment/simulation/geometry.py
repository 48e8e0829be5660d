"""Plane geometry of the simulated sensing: angles, polar coordinates seen from the ego,
land polygons and line of sight over land.

Land polygons occlude both sensors (radar shadow): an object is seen only if the segment
from the ego to it crosses no coastline edge. Nothing occludes behind another vessel.
Land polygons are ``(V, 2)`` arrays of vertices in order, implicitly closed.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

__all__ = [
    "TWO_PI",
    "coastline_sampler",
    "land_edges",
    "on_land",
    "polar",
    "sight_blocked",
    "visible",
    "wrap_angle",
]


TWO_PI = 2.0 * math.pi


def wrap_angle(angle):
    """Wrap to [-π, π)."""
    return (np.asarray(angle) + math.pi) % TWO_PI - math.pi


def polar(positions: np.ndarray, ego_positions: np.ndarray, ego_headings: np.ndarray):
    """Ranges and body-frame bearings of positions (K, N, 2) seen from egos (K, 2)."""
    relative = positions - ego_positions[:, None, :]
    ranges = np.hypot(relative[..., 0], relative[..., 1])
    bearings = wrap_angle(np.arctan2(relative[..., 1], relative[..., 0]) - ego_headings[:, None])
    return ranges, bearings


def land_edges(land: Sequence[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """All polygon edges as start points (E, 2) and end points (E, 2)."""
    if not land:
        return np.empty((0, 2)), np.empty((0, 2))
    starts = np.concatenate([np.asarray(poly, dtype=float) for poly in land])
    ends = np.concatenate([np.roll(np.asarray(poly, dtype=float), -1, axis=0) for poly in land])
    return starts, ends


def sight_blocked(
    origins: np.ndarray,
    targets: np.ndarray,
    edge_starts: np.ndarray,
    edge_ends: np.ndarray,
    chunk: int = 4096,
) -> np.ndarray:
    """Whether each segment origin→target (M, 2 each) crosses any land edge."""
    blocked = np.zeros(len(origins), dtype=bool)
    if len(edge_starts) == 0 or len(origins) == 0:
        return blocked
    edge = edge_ends - edge_starts  # (E, 2)
    for lo in range(0, len(origins), chunk):
        p = origins[lo : lo + chunk, None, :]
        ray = targets[lo : lo + chunk, None, :] - p  # (M, 1, 2)
        to_edge = edge_starts[None] - p  # (M, E, 2)
        denominator = ray[..., 0] * edge[None, :, 1] - ray[..., 1] * edge[None, :, 0]
        with np.errstate(divide="ignore", invalid="ignore"):
            along_ray = (
                to_edge[..., 0] * edge[None, :, 1] - to_edge[..., 1] * edge[None, :, 0]
            ) / denominator
            along_edge = (
                to_edge[..., 0] * ray[..., 1] - to_edge[..., 1] * ray[..., 0]
            ) / denominator
        hits = (along_ray >= 0) & (along_ray <= 1) & (along_edge >= 0) & (along_edge <= 1)
        blocked[lo : lo + chunk] = hits.any(axis=1)
    return blocked


def on_land(points: np.ndarray, land: Sequence[np.ndarray]) -> np.ndarray:
    """Even–odd point-in-polygon test for points (N, 2)."""
    inside = np.zeros(len(points), dtype=bool)
    for poly in land:
        poly = np.asarray(poly, dtype=float)
        a, b = poly, np.roll(poly, -1, axis=0)
        x, y = points[:, None, 0], points[:, None, 1]
        straddles = (a[None, :, 1] > y) != (b[None, :, 1] > y)
        with np.errstate(divide="ignore", invalid="ignore"):
            crossing_x = a[None, :, 0] + (y - a[None, :, 1]) * (b[None, :, 0] - a[None, :, 0]) / (
                b[None, :, 1] - a[None, :, 1]
            )
        inside ^= (np.count_nonzero(straddles & (x < crossing_x), axis=1) % 2).astype(bool)
    return inside


def coastline_sampler(land: Sequence[np.ndarray]):
    """Function mapping uniform [0, 1) draws to points spread evenly along all coasts."""
    starts, ends = land_edges(land)
    lengths = np.hypot(*(ends - starts).T)
    cumulative = np.concatenate([[0.0], np.cumsum(lengths)])

    def points(uniform: np.ndarray) -> np.ndarray:
        s = uniform * cumulative[-1]
        index = np.clip(np.searchsorted(cumulative, s, side="right") - 1, 0, len(lengths) - 1)
        fraction = (s - cumulative[index]) / lengths[index]
        return starts[index] + fraction[:, None] * (ends[index] - starts[index])

    return points, float(cumulative[-1])


def visible(candidates, positions, ego_positions, edges):
    """Line-of-sight mask over land for the candidate (K, N) pairs."""
    in_sight = candidates.copy()
    if len(edges[0]) == 0:
        return in_sight
    scan_index, object_index = np.nonzero(candidates)
    blocked = sight_blocked(ego_positions[scan_index], positions[scan_index, object_index], *edges)
    in_sight[scan_index[blocked], object_index[blocked]] = False
    return in_sight
