"""The Solent's figures: what each radar sees (the context-aware models' P_D over the real
coast) and each tracker's tracks over a map of it."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..canvas import new_figure
from . import scene

LAND, WATER = "#d9c8a0", "#eef4f8"
SITE_COLOURS = ("#7b2d8b", "#d95f02")
#: The view (km east and north of Southsea Castle).
VIEW_X, VIEW_Y = (-22.0, 24.0), (-31.0, 9.0)


def _draw_land(ax, filled: bool = True, outline: str = "0.45") -> None:
    for polygon in scene.land():
        for k, ring in enumerate([polygon["shell"], *polygon["holes"]]):
            closed = np.vstack([ring, ring[:1]]) / 1000.0
            if filled:
                ax.fill(closed[:, 0], closed[:, 1], color=LAND if k == 0 else WATER, lw=0, zorder=1)
            ax.plot(closed[:, 0], closed[:, 1], color=outline, lw=0.4 if filled else 0.5, zorder=2)


def _draw_sites(ax) -> None:
    for site, colour in zip(scene.SITES, SITE_COLOURS):
        x, y = np.asarray(site.position) / 1000.0
        ax.plot(x, y, marker="^", ms=9, color=colour, mec="k", zorder=6,
                label=f"{site.label}: {site.reach / 1000:g} km, {1 / site.period:g} Hz, "
                      f"antenna {site.height:g} m")


def _frame(ax, title: str) -> None:
    ax.set_facecolor(WATER)
    ax.set_aspect("equal")
    ax.set_xlim(*VIEW_X)
    ax.set_ylim(*VIEW_Y)
    ax.set_xlabel("east of Southsea Castle (km)", fontsize=8)
    ax.set_ylabel("north (km)", fontsize=8)
    ax.tick_params(labelsize=7)
    ax.set_title(title, fontsize=9)


def plot_solent_tracks(path: str | Path, title: str, tracks, truths) -> None:
    """``tracks`` and ``truths`` (:class:`~..track_plots.Polyline`) over the coast."""
    fig = new_figure(figsize=(8.0, 7.2), dpi=110, layout="constrained")
    ax = fig.subplots()
    _frame(ax, title)
    _draw_land(ax)
    for k, truth in enumerate(truths):
        ax.plot(*(truth.xy.T / 1000.0), color="0.25", lw=1.0, ls=(0, (3, 2)), zorder=3,
                label="AIS vessels (where scored)" if k == 0 else None)
    for k, track in enumerate(tracks):
        ax.plot(*(track.xy.T / 1000.0), color="#1f77b4", lw=1.3, alpha=0.85, zorder=4,
                label="tracks" if k == 0 else None)
    _draw_sites(ax)
    ax.legend(loc="lower left", fontsize=7, framealpha=0.9)
    fig.savefig(path)


def plot_solent_coverage(path: str | Path, resolution: int = 300) -> None:
    """Each radar's P_D under the line-of-sight model, and where at least one sees."""
    from ... import Pose
    from .trackers import site_models
    models = site_models("context")
    xs = np.linspace(VIEW_X[0] * 1e3, VIEW_X[1] * 1e3, resolution)
    ys = np.linspace(VIEW_Y[0] * 1e3, VIEW_Y[1] * 1e3, resolution)
    grid_x, grid_y = np.meshgrid(xs, ys)
    states = np.column_stack([grid_x.ravel(), np.zeros(grid_x.size), grid_y.ravel(),
                              np.zeros(grid_x.size)])
    platform = Pose(x=0.0, y=0.0, heading=0.0)
    fields = {name: model.detection.evaluate(model.sensor_pose(platform), states).reshape(grid_x.shape)
              for name, model in models.items()}
    fields["either radar"] = 1.0 - np.prod([1.0 - f for f in fields.values()], axis=0)
    fig = new_figure(figsize=(13.5, 4.8), dpi=110, layout="constrained")
    axes = fig.subplots(1, 3)
    labels = {site.name: site.label for site in scene.SITES}
    for ax, (name, field) in zip(axes, fields.items()):
        _frame(ax, f"P_D: {labels.get(name, name)}")
        image = ax.imshow(field, origin="lower", extent=(xs[0] / 1e3, xs[-1] / 1e3, ys[0] / 1e3,
                                                         ys[-1] / 1e3),
                          vmin=0, vmax=1, cmap="viridis", interpolation="nearest", zorder=0)
        _draw_land(ax, filled=False, outline="w")
        _draw_sites(ax)
    axes[0].legend(loc="lower left", fontsize=6.5, framealpha=0.9)
    fig.colorbar(image, ax=list(axes), shrink=0.8, label="P_D")
    fig.suptitle("The Solent: what each radar can see (range, horizon, land, line of sight "
                 f"with {scene.CLEARANCE:g} m clearance)", fontsize=10)
    fig.savefig(path)
