"""Tracking output like the paper's Fig. 4: tracks over the scene, each classed as an
inlier (on a vessel), a distractor (on a static object: scoring drops it) or clutter,
one tracker per figure or several side by side.
(Figures as :mod:`~ctxmodels.experiment.canvas` says.)
"""
from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from .canvas import new_figure

#: A track is an *inlier* when at least half of its states lie within this distance (m) of
#: some ground-truth vessel at the same time (a *distractor* when of a static object).
INLIER_DISTANCE = 30.0

LAND_COLOUR = "#d9c8a0"
TRUTH_COLOUR = "0.2"
CLUTTER_COLOUR = "#e0301e"
DISTRACTOR_COLOUR = "#f39c12"  # orange: apart from clutter red and inlier blue
STATIC_COLOUR = "0.1"
EGO_COLOUR = "#7b2fbe"  # purple: not confusable with the grey truth or the blue inliers


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


def distractor_mask(tracks: Sequence[Polyline], static_positions,
                    distance: float = INLIER_DISTANCE) -> np.ndarray:
    """Boolean per track: do at least half of its states lie within ``distance`` of some
    static object (a sea marker or islet, which does not move)?"""
    static = np.asarray(static_positions, dtype=float).reshape(-1, 2)
    if not len(tracks) or not len(static):
        return np.zeros(len(tracks), dtype=bool)
    out = np.zeros(len(tracks), dtype=bool)
    for k, track in enumerate(tracks):
        if len(track.xy):
            gaps = np.hypot(*(track.xy[:, None, :] - static[None, :, :]).transpose(2, 0, 1))
            out[k] = np.count_nonzero(gaps.min(axis=1) <= distance) >= len(track.xy) / 2
    return out


def classify_tracks(tracks: Sequence[Polyline], truths: Sequence[Polyline],
                    distance: float = INLIER_DISTANCE, static_positions=None):
    """Split tracks into ``(inliers, clutter)`` lists — or, with ``static_positions``,
    ``(inliers, distractors, clutter)`` — each in the input order.

    A track state is *near* when some truth has a point at the same time (times compared
    after rounding to the microsecond) within ``distance`` metres of it; a state at a time
    where no truth has a point is not near, yet still counts. A track is an inlier when
    at least half of its states are near (so exactly half is an inlier; an empty track
    is an inlier too). Of the others, a track with at least half its states within
    ``distance`` of a static object is a *distractor* (scoring drops it, as it drops any
    track position on a static object); the rest are clutter.
    """
    mask = inlier_mask(tracks, truths, distance)
    inliers = [t for t, keep in zip(tracks, mask) if keep]
    others = [t for t, keep in zip(tracks, mask) if not keep]
    if static_positions is None:
        return inliers, others
    on_static = distractor_mask(others, static_positions, distance)
    return (inliers, [t for t, s in zip(others, on_static) if s],
            [t for t, s in zip(others, on_static) if not s])


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


def _draw_tracks(ax, tracks, truths, ego, ego_heading, land, static_positions, extent, zoom,
                 margin, distance):
    """One panel of tracking output on ``ax``: returns (legend handles, title note)."""
    import matplotlib
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch
    handles = []
    static = np.asarray(static_positions if static_positions is not None else (),
                        dtype=float).reshape(-1, 2)
    inliers, distractors, clutter = classify_tracks(tracks, truths, distance, static)
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
    _draw_polylines(ax, distractors, [DISTRACTOR_COLOUR] * len(distractors), 1.6, 0.9, zorder=3)
    handles.append(Line2D([], [], color=DISTRACTOR_COLOUR, lw=1.6,
                          label=f"distractor tracks ({len(distractors):,}):\non static objects, "
                                "not scored"))
    blues = matplotlib.colormaps["Blues"]
    _draw_polylines(ax, inliers, [blues(0.55 + 0.4 * ((k * 0.37) % 1))
                                  for k in range(len(inliers))], 2.2, 0.95, zorder=4)
    handles.append(Line2D([], [], color=blues(0.75), lw=2.2,
                          label=f"inlier tracks ({len(inliers):,}):\n≥ half their states "
                                f"≤ {distance:g} m\nfrom a vessel"))
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
    note = (f"{len(tracks):,} tracks: {len(inliers):,} inlier, {len(distractors):,} "
            f"distractor, {len(clutter):,} clutter")
    if beyond:
        note += f"; {beyond:,} extend beyond this view"
    ax.set_aspect("equal", adjustable="box")
    if view is not None:
        ax.set_xlim(*view[0])
        ax.set_ylim(*view[1])
    else:
        ax.autoscale_view()
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.grid(alpha=0.3)
    return handles, note


def _figure_tracks(title, tracks, truths, ego, ego_heading, land=(), static_positions=None,
                   extent=None, *, zoom=True, margin=None, distance=INLIER_DISTANCE):
    fig = new_figure(figsize=(10.5, 7.6), dpi=110, layout="constrained")
    ax = fig.add_subplot()
    handles, note = _draw_tracks(ax, tracks, truths, ego, ego_heading, land, static_positions,
                                 extent, zoom, margin, distance)
    ax.set_title(f"{title}\n{note}" if title else note, fontsize=10)
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=8.5,
              borderaxespad=0.0, labelspacing=0.9, frameon=False)
    return fig


def _figure_track_panels(title, panels, truths, ego, ego_heading, land=(),
                         static_positions=None, extent=None, *, zoom=True, margin=None,
                         distance=INLIER_DISTANCE):
    """Several trackers' output side by side (``panels``: (panel title, tracks) pairs) on
    one scene and view, as the paper's Fig. 4; each panel's legend counts its own tracks."""
    fig = new_figure(figsize=(5.2 * len(panels), 7.4), dpi=110, layout="constrained")
    axes = fig.subplots(1, len(panels), squeeze=False, sharex=True, sharey=True)[0]
    for ax, (name, tracks) in zip(axes, panels):
        handles, note = _draw_tracks(ax, tracks, truths, ego, ego_heading, land,
                                     static_positions, extent, zoom, margin, distance)
        ax.set_title(name + "\n" + note.replace(": ", ":\n", 1), fontsize=9)
        ax.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, -0.1),
                  fontsize=7.5, ncol=2, frameon=False)
    if title:
        fig.suptitle(title, fontsize=11)
    return fig


def _save_whole(fig, path) -> None:
    """Saves with the bounding box grown to every artist: the panels' legends sit below
    their axes, outside the layout's own box."""
    fig.savefig(path, bbox_inches="tight", pad_inches=0.15)


def plot_tracks(path: str | Path, title: str, tracks: Sequence[Polyline],
                truths: Sequence[Polyline], ego: Polyline, ego_heading: float,
                land: Sequence[np.ndarray] = (), static_positions: np.ndarray | None = None,
                extent: float | None = None, *, zoom: bool = True, margin: float | None = None,
                distance: float = INLIER_DISTANCE):
    """Tracking output like the paper's Fig. 4, with a legend: truth dashed dark grey,
    inlier tracks in blues above clutter tracks in faint red, tracks on static objects
    (distractors) in orange, static objects as open black diamonds, the ego's path and
    final pose in purple, land in sand.

    The view is a square around the truths, the ego's path and the static objects plus
    ``margin`` (default:
    8 % of the span, at least 50 m) when ``zoom``; around the ego's final position with
    half-width ``extent`` when that is given; else all data. How many tracks leave the
    view is said in the title. ``distance``: see :func:`classify_tracks`.
    """
    fig = _figure_tracks(title, tracks, truths, ego, ego_heading, land, static_positions,
                         extent, zoom=zoom, margin=margin, distance=distance)
    fig.savefig(path)




def plot_track_panels(path: str | Path, title: str, panels, truths: Sequence[Polyline],
                      ego: Polyline, ego_heading: float, land: Sequence[np.ndarray] = (),
                      static_positions: np.ndarray | None = None, extent: float | None = None,
                      *, zoom: bool = True, margin: float | None = None,
                      distance: float = INLIER_DISTANCE):
    """Several trackers' output side by side on one scene, as the paper's Fig. 4
    (``panels``: (panel title, tracks) pairs; styles as :func:`plot_tracks`)."""
    _save_whole(_figure_track_panels(title, panels, truths, ego, ego_heading, land,
                                     static_positions, extent, zoom=zoom, margin=margin,
                                     distance=distance), path)


#: The mechanism figure's lowest PHD mass drawn (log scale; no component at all draws here).
MASS_FLOOR = 1e-6


def _figure_mechanism(title, series, radar_times, lidar_times, window):
    """The PHD mass on one vessel over time for several trackers (``series``:
    (label, times, masses)), radar scans as vertical lines, lidar scans as a rug."""
    from matplotlib.lines import Line2D
    fig = new_figure(figsize=(11.0, 4.6), dpi=110, layout="constrained")
    ax = fig.add_subplot()
    lo, hi = window
    for t in (t for t in radar_times if lo <= t <= hi):
        ax.axvline(t, color="0.75", lw=0.8, zorder=0)
    rug = [t for t in lidar_times if lo <= t <= hi]
    ax.plot(rug, np.full(len(rug), 2 * MASS_FLOOR), "|", color="0.45", ms=6, zorder=1)
    colours = ["#e0301e", "#1f5fa8", "#f39c12", "#7b2fbe"]
    handles = []
    for (label, times, weights), colour in zip(series, colours):
        keep = (np.asarray(times) >= lo) & (np.asarray(times) <= hi)
        ax.step(np.asarray(times)[keep], np.maximum(np.asarray(weights)[keep], MASS_FLOOR),
                where="post", color=colour, lw=1.6, zorder=3)
        none = not np.any(np.asarray(weights)[keep] > 0)
        handles.append(Line2D([], [], color=colour, lw=1.6,
                              label=label + ("\n(no mass at any scan shown)" if none else "")))
    handles.append(Line2D([], [], color="0.75", lw=0.8, label="radar scan"))
    handles.append(Line2D([], [], color="0.45", ls="none", marker="|", ms=8,
                          label="lidar scan (the vessel beyond its reach)"))
    ax.set_xlim(lo, hi)
    top = max([1.0] + [float(np.max(m)) for _, _, m in series if len(m)])
    # log scale: the uniform tracker's mass lives orders of magnitude below 1
    ax.set_yscale("log")
    ax.set_ylim(MASS_FLOOR, 2 * top)
    ax.set_xlabel("time (s)")
    ax.set_ylabel(f"PHD mass within 30 m of the vessel\n(log; {MASS_FLOOR:g} where none)")
    ax.set_title(title, fontsize=10)
    ax.grid(alpha=0.3, axis="y")
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8.5,
              frameon=False)
    return fig


def plot_mechanism(path: str | Path, title: str, series, radar_times, lidar_times,
                   window=(0.0, 60.0)):
    """The mechanism of the paper's finding: the PHD mass on one vessel (the summed weight
    of the mixture's components near it: how many targets the filter believes are there)
    over ``window`` (s) after each scan, for each tracker in ``series`` ((label, times,
    masses) triples), with the radar scans and the lidar scans marked."""
    _figure_mechanism(title, series, radar_times, lidar_times, window).savefig(path)
