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


def _radar_factors(model):
    """The model's radar-equation and radar-horizon factors."""
    from ..horizon import RadarHorizon
    from ..radar import RadarEquation
    factors = list(model.detection.factors)
    return ([f for f in factors if isinstance(f, RadarEquation)],
            [f for f in factors if isinstance(f, RadarHorizon)])


def _horizon_only(model):
    """``model`` with its radar horizons as its only P_D factors (None without one): the
    horizon drawn where the model puts it, mounting and heights included."""
    from ..detection import DetectionProbabilityModel
    from ..sensor import SensorModel
    horizons = _radar_factors(model)[1]
    if not horizons:
        return None
    return SensorModel(detection=DetectionProbabilityModel(factors=horizons),
                       clutter=model.clutter, position_mapping=model.position_mapping,
                       mounting=model.mounting)


def horizon_range(model, height: float = 0.0) -> float | None:
    """The nearest radar horizon of ``model``'s factors for targets ``height`` metres up (a
    horizon at each target's height reads it; one at a fixed height does not, and is a
    range — a slant range in a 3-D model), metres; None without a horizon."""
    from ..horizon import RadarHorizon
    ranges = [RadarHorizon(antenna_height=h.antenna_height, target_height=max(height, 0.0),
                           k=h.k, earth_radius=h.earth_radius).range
              if h.target_height is None else h.range for h in _radar_factors(model)[1]]
    return min(ranges) if ranges else None


def radar_curves(radar, ranges: np.ndarray) -> dict[int, np.ndarray]:
    """P_D against range of ``radar`` (a :class:`~ctxmodels.RadarEquation`) for each
    Swerling case 0–4 at its reference SNR, false-alarm probability, pulses and loss."""
    from ..radar import RadarEquation
    return {case: RadarEquation(reference_snr=radar.reference_snr,
                                reference_range=radar.reference_range,
                                false_alarm_probability=radar.false_alarm_probability,
                                swerling=case, pulses=radar.pulses, loss=radar.loss)(ranges)
            for case in range(5)}


SWERLING_COLOURS = ["#000000", "#1f77b4", "#ff7f0e", "#2ca02c", "#d62728"]


def _draw_radar_curves(ax, name: str, radars: list, reach: float, horizon: float | None) -> None:
    radar = radars[0]
    ranges = np.linspace(0.0, reach, 400)
    for case, pd in radar_curves(radar, ranges).items():
        own = case == radar.swerling
        ax.plot(ranges, pd, color=SWERLING_COLOURS[case], lw=2.6 if own else 1.1,
                ls="-" if case in (0, 1, 3) else "--",
                label=f"Swerling {case}" + (" (the model's)" if own else ""))
    if horizon is not None and horizon <= reach:
        ax.axvline(horizon, color="0.3", ls=":", lw=1.2, label="radar horizon")
    ax.set_xlim(0.0, reach)
    ax.set_ylim(0.0, 1.02)
    more = (f" (the first of its {len(radars)} radar equations: P_D is their product)"
            if len(radars) > 1 else "")
    ax.set_title(f"{name}: radar equation P_D per Swerling case{more}\n"
                 f"{radar.reference_snr:g} dB at {radar.reference_range:,.0f} m, "
                 f"P_FA {radar.false_alarm_probability:g}, {radar.pulses} pulse(s)", fontsize=9)
    ax.set_xlabel("range (m)", fontsize=8)
    ax.set_ylabel("P_D", fontsize=8)
    ax.tick_params(labelsize=7)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="upper right")


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
    radars = {name: _radar_factors(model)[0] for name, model in sensor_models.items()}
    curves = any(radars.values())
    rows = len(extents) + spatial + curves
    fig = new_figure(figsize=(3.6 * len(panels) + 1.5, 3.45 * rows + 1.0), dpi=100,
                  layout="constrained")
    axes = fig.subplots(rows, len(panels), squeeze=False)
    pose = _as_pose(pose)
    px, py, heading = pose.x, pose.y, pose.heading
    image = None
    horizons = {name: _horizon_only(model) for name, model in sensor_models.items()}
    horizons = {name: model for name, model in horizons.items() if model is not None}
    drawn: set = set()  # the models whose horizon is on a map
    for row, extent in enumerate(extents):
        xs, ys, grids = coverage_grid(sensor_models, pose, extent, resolution, height)
        rings = coverage_grid(horizons, pose, extent, resolution, height)[2] if horizons else {}
        if len(names) > 1:
            grids["any sensor"] = _any_sensor(grids)
        for col, name in enumerate(panels):
            ax = axes[row, col]
            image = ax.imshow(grids[name], origin="lower", extent=(xs[0], xs[-1], ys[0], ys[-1]),
                              vmin=0, vmax=1, cmap="viridis", interpolation="nearest")
            for polygon in land:
                ring = np.vstack([polygon, polygon[:1]])
                ax.plot(ring[:, 0], ring[:, 1], color="w", lw=0.9)
            if name in rings and rings[name].min() < 0.5 < rings[name].max():
                ax.contour(xs, ys, rings[name], levels=[0.5], colors="w", linestyles="--",
                           linewidths=1.0)
                drawn.add(name)
            length = 0.14 * extent
            ax.annotate("", xy=(px + length * math.cos(heading), py + length * math.sin(heading)),
                        xytext=(px, py), arrowprops=dict(arrowstyle="-|>", color=HEADING_COLOUR,
                                                         lw=1.6, mutation_scale=12))
            what = "any sensor detects" if name == "any sensor" else f"{name} P_D"
            at = f",\ntargets {height:g} m up" if spatial else ""
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
        rings = section_grid(horizons, pose, extent, top, resolution)[2] if horizons else {}
        if len(names) > 1:
            grids["any sensor"] = _any_sensor(grids)
        for col, name in enumerate(panels):
            ax = axes[len(extents), col]
            image = ax.imshow(grids[name], origin="lower", aspect="auto",
                              extent=(ranges[0], ranges[-1], heights[0], heights[-1]),
                              vmin=0, vmax=1, cmap="viridis", interpolation="nearest")
            what = "any sensor detects" if name == "any sensor" else f"{name} P_D"
            ax.set_title(f"{what}: section along the heading", fontsize=9)
            ax.set_xlabel("ground range along the ego's heading (m)", fontsize=8)
            ax.set_ylabel("height (m)", fontsize=8)
            ax.tick_params(labelsize=7)
            if name in rings and rings[name].min() < 0.5 < rings[name].max():
                ax.contour(ranges, heights, rings[name], levels=[0.5], colors="w",
                           linestyles="--", linewidths=1.0)
                drawn.add(name)
    if curves:
        for col, name in enumerate(panels):
            ax = axes[-1, col]
            if not radars.get(name):
                ax.remove()
                continue
            _draw_radar_curves(ax, name, radars[name], extents[0],
                               horizon_range(sensor_models[name], height))
    maps = [ax for ax in fig.axes if ax.images]
    colourbar = fig.colorbar(image, ax=maps, shrink=0.85, aspect=30)
    colourbar.set_label("P_D (detection probability)")
    handles = [Line2D([], [], color=HEADING_COLOUR, lw=1.6, marker=">", markevery=[1],
                      label=f"ego heading ({math.degrees(heading) % 360:.0f}° from +x, "
                            f"counter-clockwise); arrow starts at the ego ({px:g}, {py:g}) m")]
    if len(land):
        handles.append(Line2D([], [], color="w", lw=1.2, mec="0.5",
                              label="land outline (white)"))
    for name in horizons:
        where = "white dashed" if name in drawn else "not on these maps"
        handles.append(Line2D([], [], color="w", lw=1.0, ls="--",
                              label=f"{name}: radar horizon ({where}) at "
                                    f"{horizon_range(sensor_models[name], height) / 1000:,.1f} km"))
    # (in as many columns as the figure has panels: one panel's width holds one entry)
    fig.legend(handles=handles, loc="outside lower center", ncols=min(len(handles), len(panels)),
               fontsize=8, facecolor="0.85")
    fig.suptitle(title or "Detection probability around the ego")
    return fig


def plot_coverage(path: str | Path, sensor_models: Mapping, pose, extents=(1800.0, 100.0),
                  land: Sequence[np.ndarray] = (), resolution: int = 400, title: str = "",
                  height: float = 0.0, ceiling: float | None = None):
    """Coverage maps: one row per extent (e.g. the radar's km scale and the lidar's 100 m),
    one column per sensor plus the probability that at least one sensor detects; one
    shared P_D colour bar, the ego's heading as a red arrow explained in a legend. With a
    3-D model among them, the plan views are of targets ``height`` metres up and a further
    row is the vertical section along the heading: ground range up to the first extent by
    height up to ``ceiling`` (a tenth of that extent by default). A radar horizon is drawn
    as a white dashed line on its model's maps (named in the legend with its range for
    targets at ``height``); a model with a radar equation gets a last row of its P_D
    against range for each Swerling case, its own bold."""
    fig = _figure_coverage(sensor_models, pose, extents, land, resolution, title, height,
                           ceiling)
    fig.savefig(path)
