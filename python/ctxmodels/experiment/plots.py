"""Figures: tracking output like the paper's Fig. 4, and P_D coverage maps.

Matplotlib is imported lazily with the non-interactive Agg backend, so the experiment runs
on headless machines.
"""
from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

#: A track is an *inlier* when at least half of its states lie within this distance of some
#: ground-truth vessel at the same time; otherwise it is drawn as a clutter track.
INLIER_DISTANCE = 30.0


def _pyplot():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


class Polyline:
    """A track or truth reduced to what a figure needs: times (s) and (x, y) rows."""

    def __init__(self, times, xy, label=""):
        self.times = np.asarray(times, dtype=float)
        self.xy = np.asarray(xy, dtype=float).reshape(-1, 2)
        self.label = label

    @classmethod
    def from_states(cls, states, epoch, mapping=(0, 2), label=""):
        times = [(s.timestamp - epoch).total_seconds() for s in states]
        xy = [[float(s.state_vector[mapping[0]]), float(s.state_vector[mapping[1]])]
              for s in states]
        return cls(times, xy, label)


def classify_tracks(tracks: Sequence[Polyline], truths: Sequence[Polyline],
                    distance: float = INLIER_DISTANCE):
    """Split tracks into (inliers, clutter) by their distance to the truth (see
    :data:`INLIER_DISTANCE`)."""
    truth_at: dict[float, list] = {}
    for truth in truths:
        for t, p in zip(truth.times, truth.xy):
            truth_at.setdefault(round(float(t), 6), []).append(p)
    inliers, clutter = [], []
    for track in tracks:
        near = 0
        for t, p in zip(track.times, track.xy):
            points = truth_at.get(round(float(t), 6))
            if points:
                near += bool(np.min(np.hypot(*(np.asarray(points) - p).T)) <= distance)
        (inliers if near >= len(track.times) / 2 else clutter).append(track)
    return inliers, clutter


def plot_tracks(path: str | Path, title: str, tracks: Sequence[Polyline],
                truths: Sequence[Polyline], ego: Polyline, ego_heading: float,
                land: Sequence[np.ndarray] = (), static_positions: np.ndarray | None = None,
                extent: float | None = None):
    """Tracking output like the paper's Fig. 4: truth dashed grey, inlier tracks in blues,
    clutter tracks in red, the ego's path and final pose in black."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(7, 7), dpi=110)
    for polygon in land:
        ring = np.vstack([polygon, polygon[:1]])
        ax.fill(ring[:, 0], ring[:, 1], color="#d9c8a0", zorder=0)
    for truth in truths:
        ax.plot(truth.xy[:, 0], truth.xy[:, 1], "--", color="0.55", lw=1.2, zorder=1)
    if static_positions is not None and len(static_positions):
        ax.plot(static_positions[:, 0], static_positions[:, 1], "^", color="tab:red", ms=5,
                mfc="none", zorder=2)
    inliers, clutter = classify_tracks(tracks, truths)
    blues = plt.get_cmap("Blues")
    for k, track in enumerate(inliers):
        ax.plot(track.xy[:, 0], track.xy[:, 1], "-", color=blues(0.45 + 0.5 * ((k * 0.37) % 1)),
                lw=1.6, zorder=3)
    for track in clutter:
        ax.plot(track.xy[:, 0], track.xy[:, 1], "-", color="tab:red", lw=1.0, alpha=0.8,
                zorder=3)
    ex, ey = ego.xy[-1]
    ax.plot(ego.xy[:, 0], ego.xy[:, 1], "-", color="k", lw=0.8, zorder=4)
    ax.plot([ex], [ey], marker=(3, 0, math.degrees(ego_heading) - 90), color="k", ms=12,
            zorder=5)
    ax.set_title(f"{title}\n{len(inliers)} inlier tracks (blue), {len(clutter)} clutter "
                 f"tracks (red)", fontsize=10)
    ax.set_aspect("equal")
    if extent is not None:
        ax.set_xlim(ex - extent, ex + extent)
        ax.set_ylim(ey - extent, ey + extent)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def coverage_grid(sensor_models: Mapping, pose, extent: float, resolution: int = 400):
    """P_D of each sensor model on a square grid around ``pose``: (xs, ys, {name: P_D})."""
    from ..pose import Pose
    if not isinstance(pose, Pose):
        pose = Pose(x=pose[0], y=pose[1], heading=pose[2])
    xs = np.linspace(pose.x - extent, pose.x + extent, resolution)
    ys = np.linspace(pose.y - extent, pose.y + extent, resolution)
    gx, gy = np.meshgrid(xs, ys)
    grids = {}
    for name, model in sensor_models.items():
        mapping = tuple(model.position_mapping)
        states = np.zeros((gx.size, max(mapping) + 1))
        states[:, mapping[0]] = gx.ravel()
        states[:, mapping[1]] = gy.ravel()
        grids[name] = model.context(pose).prob_detection_array(states).reshape(gx.shape)
    return xs, ys, grids


def plot_coverage(path: str | Path, sensor_models: Mapping, pose, extents=(1800.0, 100.0),
                  land: Sequence[np.ndarray] = (), resolution: int = 400, title: str = ""):
    """Coverage maps: one row per extent (e.g. the radar's km scale and the lidar's 100 m),
    one column per sensor plus the probability that at least one sensor detects."""
    plt = _pyplot()
    names = list(sensor_models)
    ncols = len(names) + (1 if len(names) > 1 else 0)
    fig, axes = plt.subplots(len(extents), ncols, figsize=(4.2 * ncols, 4.0 * len(extents)),
                             dpi=100, squeeze=False)
    for row, extent in enumerate(extents):
        xs, ys, grids = coverage_grid(sensor_models, pose, extent, resolution)
        panels = [(name, grids[name]) for name in names]
        if len(names) > 1:
            miss = np.ones_like(next(iter(grids.values())))
            for grid in grids.values():
                miss *= 1 - grid
            panels.append(("any sensor", 1 - miss))
        for col, (name, grid) in enumerate(panels):
            ax = axes[row, col]
            image = ax.imshow(grid, origin="lower", extent=(xs[0], xs[-1], ys[0], ys[-1]),
                              vmin=0, vmax=1, cmap="viridis")
            for polygon in land:
                ring = np.vstack([polygon, polygon[:1]])
                ax.plot(ring[:, 0], ring[:, 1], color="w", lw=0.8)
            px, py, heading = (pose.x, pose.y, pose.heading) if hasattr(pose, "x") else pose
            ax.arrow(px, py, 0.08 * extent * math.cos(heading), 0.08 * extent * math.sin(heading),
                     color="r", width=0.006 * extent)
            ax.set_title(f"P_D {name} (±{extent:g} m)", fontsize=9)
            ax.set_xlim(xs[0], xs[-1])
            ax.set_ylim(ys[0], ys[-1])
            ax.tick_params(labelsize=7)
            fig.colorbar(image, ax=ax, fraction=0.046, pad=0.03)
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
