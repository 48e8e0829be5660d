"""Figures: the sensors' P_D coverage maps around a pose (``ctxmodels coverage`` and the
study's ``coverage_*.png``). Tracks are drawn by :mod:`~ctxmodels.experiment.track_plots`,
scores and differences by :mod:`~ctxmodels.experiment.summary_plots`; all build their figures
as :mod:`~ctxmodels.experiment.canvas` says."""
from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from .canvas import new_figure


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


HEADING_COLOUR = "#ff2a2a"


def _figure_coverage(sensor_models, pose, extents=(1800.0, 100.0), land=(), resolution=400,
                     title=""):
    from matplotlib.lines import Line2D
    names = list(sensor_models)
    panels = names + (["any sensor"] if len(names) > 1 else [])
    fig = new_figure(figsize=(3.6 * len(panels) + 1.1, 3.45 * len(extents) + 1.0), dpi=100,
                  layout="constrained")
    axes = fig.subplots(len(extents), len(panels), squeeze=False)
    px, py, heading = (pose.x, pose.y, pose.heading) if hasattr(pose, "x") else pose
    image = None
    for row, extent in enumerate(extents):
        xs, ys, grids = coverage_grid(sensor_models, pose, extent, resolution)
        if len(names) > 1:
            miss = np.ones_like(next(iter(grids.values())))
            for grid in grids.values():
                miss *= 1 - grid
            grids["any sensor"] = 1 - miss
        for col, name in enumerate(panels):
            ax = axes[row, col]
            image = ax.imshow(grids[name], origin="lower", extent=(xs[0], xs[-1], ys[0], ys[-1]),
                              vmin=0, vmax=1, cmap="viridis", interpolation="nearest")
            for polygon in land:
                ring = np.vstack([polygon, polygon[:1]])
                ax.plot(ring[:, 0], ring[:, 1], color="w", lw=0.9)
            length = 0.14 * extent
            ax.annotate("", xy=(px + length * math.cos(heading), py + length * math.sin(heading)),
                        xytext=(px, py), arrowprops=dict(arrowstyle="-|>", color=HEADING_COLOUR,
                                                         lw=1.6, mutation_scale=12))
            what = "any sensor detects" if name == "any sensor" else f"{name} P_D"
            ax.set_title(f"{what}, ±{extent:,.0f} m around the ego", fontsize=9)
            ax.set_xlim(xs[0], xs[-1])
            ax.set_ylim(ys[0], ys[-1])
            ax.set_xlabel("x (m)", fontsize=8)
            ax.set_ylabel("y (m)", fontsize=8)
            ax.tick_params(labelsize=7)
    colourbar = fig.colorbar(image, ax=axes, shrink=0.85, aspect=30)
    colourbar.set_label("P_D (detection probability)")
    handles = [Line2D([], [], color=HEADING_COLOUR, lw=1.6, marker=">", markevery=[1],
                      label=f"ego heading ({math.degrees(heading) % 360:.0f}° from +x, "
                            f"counter-clockwise); arrow starts at the ego ({px:g}, {py:g}) m")]
    if len(land):
        handles.append(Line2D([], [], color="w", lw=1.2, mec="0.5",
                              label="land outline (white)"))
    fig.legend(handles=handles, loc="outside lower center", ncols=len(handles), fontsize=8,
               facecolor="0.85")
    fig.suptitle(title or "Detection probability around the ego")
    return fig


def plot_coverage(path: str | Path, sensor_models: Mapping, pose, extents=(1800.0, 100.0),
                  land: Sequence[np.ndarray] = (), resolution: int = 400, title: str = ""):
    """Coverage maps: one row per extent (e.g. the radar's km scale and the lidar's 100 m),
    one column per sensor plus the probability that at least one sensor detects; one
    shared P_D colour bar, the ego's heading as a red arrow explained in a legend."""
    fig = _figure_coverage(sensor_models, pose, extents, land, resolution, title)
    fig.savefig(path)
