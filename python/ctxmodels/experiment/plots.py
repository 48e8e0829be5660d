"""Figures: tracking output like the paper's Fig. 4, and P_D coverage maps.

Statistics figures (per-tracker scores, paired differences, sensitivity grids) are in
:mod:`ctxmodels.experiment.summary_plots` and re-exported here.

Figures are built on :class:`matplotlib.figure.Figure` directly, not through pyplot: no
global figure registry, no backend switch for the caller, and headless machines work.
Each ``plot_*`` saves the figure that a ``_figure_*`` twin returns, so tests can inspect
legends and labels without reading pixels.
"""
from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from .summary_plots import plot_sensitivity, plot_summary  # noqa: F401 (re-exported)

#: A track is an *inlier* when at least half of its states lie within this distance (m) of
#: some ground-truth vessel at the same time; otherwise it is a clutter track.
INLIER_DISTANCE = 30.0

LAND_COLOUR = "#d9c8a0"
TRUTH_COLOUR = "0.2"
CLUTTER_COLOUR = "#e0301e"
STATIC_COLOUR = "0.1"
EGO_COLOUR = "#7b2fbe"  # purple: not confusable with the grey truth or the blue inliers


def _figure(**kwargs):
    from matplotlib.figure import Figure
    return Figure(**kwargs)


class Polyline:
    """A track or truth reduced to what a figure needs: times (s) and (x, y) rows."""

    def __init__(self, times, xy, label=""):
        self.times = np.asarray(times, dtype=float).reshape(-1)
        self.xy = np.asarray(xy, dtype=float).reshape(-1, 2)
        self.label = label

    @classmethod
    def from_states(cls, states, epoch, mapping=(0, 2), label=""):
        times = [(s.timestamp - epoch).total_seconds() for s in states]
        xy = [[float(s.state_vector[mapping[0]]), float(s.state_vector[mapping[1]])]
              for s in states]
        return cls(times, xy, label)


def inlier_mask(tracks: Sequence[Polyline], truths: Sequence[Polyline],
                distance: float = INLIER_DISTANCE) -> np.ndarray:
    """Boolean per track: is it an inlier? See :func:`classify_tracks` for the rule.

    Vectorised over all states at once: every track state is matched to the truth time
    table by binary search, then compared with each truth slot of that time in turn.
    """
    lengths = np.array([len(track.times) for track in tracks], dtype=int)
    if not len(tracks):
        return np.zeros(0, dtype=bool)
    near = np.zeros(int(lengths.sum()), dtype=bool)
    truth_times = [truth.times for truth in truths if len(truth.times)]
    if near.size and truth_times:
        times = np.round(np.concatenate([track.times for track in tracks]), 6)
        xy = np.concatenate([track.xy for track in tracks])
        truth_t = np.round(np.concatenate(truth_times), 6)
        truth_xy = np.concatenate([truth.xy for truth in truths if len(truth.times)])
        # A (time, slot, xy) table: the truth points present at each distinct time.
        keys, group, counts = np.unique(truth_t, return_inverse=True, return_counts=True)
        order = np.argsort(group, kind="stable")
        slot = np.empty(len(truth_t), dtype=int)
        slot[order] = np.arange(len(truth_t)) - np.repeat(np.cumsum(counts) - counts, counts)
        table = np.full((len(keys), int(counts.max()), 2), np.nan)
        table[group, slot] = truth_xy
        at = np.minimum(np.searchsorted(keys, times), len(keys) - 1)
        matched = keys[at] == times
        rows, points = at[matched], xy[matched]
        best = np.full(len(rows), np.inf)
        for k in range(table.shape[1]):  # few slots (vessels); memory stays O(states)
            best = np.fmin(best, np.hypot(*(table[rows, k] - points).T))
        near[matched] = best <= distance
    near_count = np.bincount(np.repeat(np.arange(len(tracks)), lengths), weights=near,
                             minlength=len(tracks))
    return near_count >= lengths / 2


def classify_tracks(tracks: Sequence[Polyline], truths: Sequence[Polyline],
                    distance: float = INLIER_DISTANCE):
    """Split tracks into ``(inliers, clutter)`` lists, each in the input order.

    A track state is *near* when some truth has a point at the same time (times compared
    after rounding to the microsecond) within ``distance`` metres of it; a state at a time
    where no truth has a point is not near, yet still counts. A track is an inlier when
    at least half of its states are near (so exactly half is an inlier; an empty track
    is an inlier too), otherwise clutter.
    """
    mask = inlier_mask(tracks, truths, distance)
    return ([t for t, keep in zip(tracks, mask) if keep],
            [t for t, keep in zip(tracks, mask) if not keep])


def _clutter_style(count: int) -> tuple[float, float]:
    """(line width, alpha) for ``count`` clutter tracks: faint when there are thousands, so
    that overlap shows density instead of a solid red blot."""
    alpha = float(np.clip(6.0 / math.sqrt(max(count, 1)), 0.12, 0.8))
    return (0.6 if count > 200 else 0.9), alpha


def _draw_polylines(ax, polylines, colours, lw, alpha, zorder):
    """All polylines as one LineCollection; single-state ones as dots (a one-point line is
    invisible)."""
    from matplotlib.collections import LineCollection
    long_ = [(p.xy, c) for p, c in zip(polylines, colours) if len(p.xy) > 1]
    dots = [(p.xy[0], c) for p, c in zip(polylines, colours) if len(p.xy) == 1]
    if long_:
        ax.add_collection(LineCollection([xy for xy, _ in long_], colors=[c for _, c in long_],
                                         linewidths=lw, alpha=alpha, zorder=zorder,
                                         capstyle="round"))
    if dots:
        pts = np.array([xy for xy, _ in dots])
        ax.scatter(pts[:, 0], pts[:, 1], s=max(2.0, 4 * lw), c=[c for _, c in dots],
                   alpha=alpha, linewidths=0, zorder=zorder)


def _pose_marker(heading: float):
    """A dart pointing along ``heading`` (radians from +x): unlike an equilateral triangle,
    which way it points is unambiguous."""
    from matplotlib.path import Path as MPath
    dart = np.array([[1.0, 0.0], [-0.7, 0.55], [-0.35, 0.0], [-0.7, -0.55], [1.0, 0.0]])
    c, s = math.cos(heading), math.sin(heading)
    return MPath(dart @ np.array([[c, s], [-s, c]]), closed=True)


def _view(truths, ego, static, extent, margin):
    """Square view limits ((x0, x1), (y0, y1)), or None to fit everything."""
    if extent is not None and len(ego.xy):
        (cx, cy), half = ego.xy[-1], float(extent)
    else:
        pts = [p.xy for p in truths if len(p.xy)] + [q for q in (ego.xy, static) if len(q)]
        if not pts:
            return None
        pts = np.concatenate(pts)
        lo, hi = np.nanmin(pts, axis=0), np.nanmax(pts, axis=0)
        (cx, cy), half = (lo + hi) / 2, float(np.max(hi - lo)) / 2
        half += max(0.08 * 2 * half, 50.0) if margin is None else float(margin)
    return (cx - half, cx + half), (cy - half, cy + half)


def _outside(polylines, view) -> int:
    """How many polylines have a point outside ``view``."""
    if view is None or not polylines:
        return 0
    (x0, x1), (y0, y1) = view
    lengths = np.array([len(p.xy) for p in polylines])
    xy = np.concatenate([p.xy for p in polylines])
    out = (xy[:, 0] < x0) | (xy[:, 0] > x1) | (xy[:, 1] < y0) | (xy[:, 1] > y1)
    return int(np.count_nonzero(np.bincount(np.repeat(np.arange(len(polylines)), lengths),
                                            weights=out, minlength=len(polylines))))


def _figure_tracks(title, tracks, truths, ego, ego_heading, land=(), static_positions=None,
                   extent=None, *, zoom=True, margin=None, distance=INLIER_DISTANCE):
    import matplotlib
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch
    fig = _figure(figsize=(10.5, 7.6), dpi=110, layout="constrained")
    ax = fig.add_subplot()
    handles = []
    mask = inlier_mask(tracks, truths, distance)
    inliers = [t for t, keep in zip(tracks, mask) if keep]
    clutter = [t for t, keep in zip(tracks, mask) if not keep]
    if len(land):
        for polygon in land:
            ring = np.vstack([polygon, polygon[:1]])
            ax.fill(ring[:, 0], ring[:, 1], color=LAND_COLOUR, zorder=0)
        handles.append(Patch(color=LAND_COLOUR, label="land"))
    for truth in truths:
        ax.plot(truth.xy[:, 0], truth.xy[:, 1], "--", color=TRUTH_COLOUR, lw=1.1, zorder=5)
        if len(truth.xy):  # where a vessel starts tells which way it goes
            ax.plot(*truth.xy[0], "o", color=TRUTH_COLOUR, ms=4, zorder=5)
    handles.append(Line2D([], [], ls="--", color=TRUTH_COLOUR, lw=1.1, marker="o", ms=4,
                          markevery=[0], label=f"truth: vessels ({len(truths)}),\n● at start"))
    # Clutter beneath, inliers above it, truth dashed on top so both stay visible.
    lw, alpha = _clutter_style(len(clutter))
    _draw_polylines(ax, clutter, [CLUTTER_COLOUR] * len(clutter), lw, alpha, zorder=2)
    handles.append(Line2D([], [], color=CLUTTER_COLOUR, lw=1.5, alpha=max(alpha, 0.6),
                          label=f"clutter tracks ({len(clutter):,})"))
    blues = matplotlib.colormaps["Blues"]
    _draw_polylines(ax, inliers, [blues(0.55 + 0.4 * ((k * 0.37) % 1))
                                  for k in range(len(inliers))], 2.2, 0.95, zorder=4)
    handles.append(Line2D([], [], color=blues(0.75), lw=2.2,
                          label=f"inlier tracks ({len(inliers):,}):\n≥ half their states "
                                f"≤ {distance:g} m\nfrom a vessel"))
    static = np.asarray(static_positions if static_positions is not None else (),
                        dtype=float).reshape(-1, 2)
    view = _view(truths, ego, static, extent, margin) if zoom or extent is not None else None
    if len(static):
        ax.plot(static[:, 0], static[:, 1], "D", ls="none", mfc="none", mec=STATIC_COLOUR,
                mew=1.3, ms=7, zorder=3)
        hidden = _outside([Polyline(np.zeros(1), p) for p in static], view)
        handles.append(Line2D([], [], marker="D", ls="none", mfc="none", mec=STATIC_COLOUR,
                              mew=1.3, ms=7,
                              label=f"static objects: sea markers,\nislets ({len(static)}"
                                    + (f", {hidden} out of view)" if hidden else ")")))
    if len(ego.xy):
        ax.plot(ego.xy[:, 0], ego.xy[:, 1], "-", color=EGO_COLOUR, lw=1.4, zorder=6)
        ax.plot(*ego.xy[-1], marker=_pose_marker(ego_heading), ls="none", color=EGO_COLOUR,
                mec="k", mew=0.6, ms=15, zorder=7)
    handles.append(Line2D([], [], color=EGO_COLOUR, lw=1.4, label="ego path"))
    handles.append(Line2D([], [], marker=_pose_marker(0.0), ls="none", color=EGO_COLOUR,
                          mec="k", mew=0.6, ms=13, label="ego final pose\n(points along heading)"))
    beyond = _outside(tracks, view)
    note = f"{len(tracks):,} tracks: {len(inliers):,} inlier, {len(clutter):,} clutter"
    if beyond:
        note += f"; {beyond:,} extend beyond this view"
    ax.set_title(f"{title}\n{note}" if title else note, fontsize=10)
    ax.set_aspect("equal", adjustable="box")
    if view is not None:
        ax.set_xlim(*view[0])
        ax.set_ylim(*view[1])
    else:
        ax.autoscale_view()
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.grid(alpha=0.3)
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=8.5,
              borderaxespad=0.0, labelspacing=0.9, frameon=False)
    return fig


def plot_tracks(path: str | Path, title: str, tracks: Sequence[Polyline],
                truths: Sequence[Polyline], ego: Polyline, ego_heading: float,
                land: Sequence[np.ndarray] = (), static_positions: np.ndarray | None = None,
                extent: float | None = None, *, zoom: bool = True, margin: float | None = None,
                distance: float = INLIER_DISTANCE):
    """Tracking output like the paper's Fig. 4, with a legend: truth dashed dark grey,
    inlier tracks in blues above clutter tracks in faint red, static objects as open black
    diamonds, the ego's path and final pose in purple, land in sand.

    The view is a square around the truths, the ego's path and the static objects plus
    ``margin`` (default:
    8 % of the span, at least 50 m) when ``zoom``; around the ego's final position with
    half-width ``extent`` when that is given; else all data. How many tracks leave the
    view is said in the title. ``distance``: see :func:`classify_tracks`.
    """
    fig = _figure_tracks(title, tracks, truths, ego, ego_heading, land, static_positions,
                         extent, zoom=zoom, margin=margin, distance=distance)
    fig.savefig(path)


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
    fig = _figure(figsize=(3.6 * len(panels) + 1.1, 3.45 * len(extents) + 1.0), dpi=100,
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
