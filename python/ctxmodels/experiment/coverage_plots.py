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


def _as_pose(pose):
    from ..pose import Pose, as_pose
    return pose if isinstance(pose, Pose) else as_pose(pose)


def _pd_at(model, pose, x: np.ndarray, y: np.ndarray, z: np.ndarray | float) -> np.ndarray:
    """P_D of ``model`` at ``pose`` at world points (x, y) and heights z (read only by a
    model with a height in its ``position_mapping``) of targets at rest, in the points'
    shape. The states hold only what the model reads, packed (whatever its indices)."""
    from ..sensor import SensorModel
    axes = len(model.position_mapping)
    velocity = None if model.velocity_mapping is None else tuple(range(axes, 2 * axes))
    packed = SensorModel(detection=model.detection, clutter=model.clutter,
                         position_mapping=tuple(range(axes)), velocity_mapping=velocity,
                         mounting=model.mounting)
    states = np.zeros((x.size, 2 * axes if velocity else axes))
    for index, values in zip(range(axes), (x, y, z)):
        states[:, index] = np.broadcast_to(values, x.shape).ravel()
    return packed.context(pose).prob_detection_array(states).reshape(x.shape)


def coverage_grid(sensor_models: Mapping, pose, extent: float, resolution: int = 400,
                  height: float = 0.0):
    """P_D of each sensor model on a square grid around ``pose``: (xs, ys, {name: P_D}); a
    3-D model's targets are at ``height`` (metres)."""
    pose = _as_pose(pose)
    xs = np.linspace(pose.x - extent, pose.x + extent, resolution)
    ys = np.linspace(pose.y - extent, pose.y + extent, resolution)
    gx, gy = np.meshgrid(xs, ys)
    return xs, ys, {name: _pd_at(model, pose, gx, gy, height)
                    for name, model in sensor_models.items()}


def section_grid(sensor_models: Mapping, pose, extent: float, ceiling: float,
                 resolution: int = 400):
    """P_D of each sensor model on a vertical section along the pose's heading (the
    platform's own, before any mounting): ground range 0…``extent`` by height
    0…``ceiling``, (ranges, heights, {name: P_D}); a planar model ignores the height."""
    pose = _as_pose(pose)
    ranges = np.linspace(0.0, extent, resolution)
    heights = np.linspace(0.0, ceiling, resolution)
    gr, gz = np.meshgrid(ranges, heights)
    gx, gy = pose.x + gr * math.cos(pose.heading), pose.y + gr * math.sin(pose.heading)
    return ranges, heights, {name: _pd_at(model, pose, gx, gy, gz)
                             for name, model in sensor_models.items()}


def _any_sensor(grids: dict) -> np.ndarray:
    miss = np.ones_like(next(iter(grids.values())))
    for grid in grids.values():
        miss *= 1 - grid
    return 1 - miss


HEADING_COLOUR = "#ff2a2a"


def _figure_coverage(sensor_models, pose, extents=(1800.0, 100.0), land=(), resolution=400,
                     title="", height=0.0, ceiling=None):
    from matplotlib.lines import Line2D
    names = list(sensor_models)
    panels = names + (["any sensor"] if len(names) > 1 else [])
    spatial = any(len(model.position_mapping) == 3 for model in sensor_models.values())
    rows = len(extents) + spatial
    fig = new_figure(figsize=(3.6 * len(panels) + 1.5, 3.45 * rows + 1.0), dpi=100,
                  layout="constrained")
    axes = fig.subplots(rows, len(panels), squeeze=False)
    pose = _as_pose(pose)
    px, py, heading = pose.x, pose.y, pose.heading
    image = None
    for row, extent in enumerate(extents):
        xs, ys, grids = coverage_grid(sensor_models, pose, extent, resolution, height)
        if len(names) > 1:
            grids["any sensor"] = _any_sensor(grids)
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
            at = f", targets {height:g} m up" if spatial else ""
            ax.set_title(f"{what}, ±{extent:,.0f} m around the ego{at}", fontsize=9)
            ax.set_xlim(xs[0], xs[-1])
            ax.set_ylim(ys[0], ys[-1])
            ax.set_xlabel("x (m)", fontsize=8)
            ax.set_ylabel("y (m)", fontsize=8)
            ax.tick_params(labelsize=7)
    if spatial:
        extent = extents[0]
        top = ceiling if ceiling is not None else extent / 10
        ranges, heights, grids = section_grid(sensor_models, pose, extent, top, resolution)
        if len(names) > 1:
            grids["any sensor"] = _any_sensor(grids)
        for col, name in enumerate(panels):
            ax = axes[-1, col]
            image = ax.imshow(grids[name], origin="lower", aspect="auto",
                              extent=(ranges[0], ranges[-1], heights[0], heights[-1]),
                              vmin=0, vmax=1, cmap="viridis", interpolation="nearest")
            what = "any sensor detects" if name == "any sensor" else f"{name} P_D"
            ax.set_title(f"{what}: section along the heading", fontsize=9)
            ax.set_xlabel("ground range along the ego's heading (m)", fontsize=8)
            ax.set_ylabel("height (m)", fontsize=8)
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
                  land: Sequence[np.ndarray] = (), resolution: int = 400, title: str = "",
                  height: float = 0.0, ceiling: float | None = None):
    """Coverage maps: one row per extent (e.g. the radar's km scale and the lidar's 100 m),
    one column per sensor plus the probability that at least one sensor detects; one
    shared P_D colour bar, the ego's heading as a red arrow explained in a legend. With a
    3-D model among them, the plan views are of targets ``height`` metres up and a last
    row is the vertical section along the heading: ground range up to the first extent by
    height up to ``ceiling`` (a tenth of that extent by default)."""
    fig = _figure_coverage(sensor_models, pose, extents, land, resolution, title, height,
                           ceiling)
    fig.savefig(path)
