"""Statistics figures: per-tracker scores and paired differences with their 95 % intervals
(:func:`plot_summary`), and a paired difference over a grid of simulation settings
(:func:`plot_sensitivity`).
(Figures as :mod:`~ctxmodels.experiment.canvas` says.)
"""
from __future__ import annotations

import textwrap
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from .canvas import new_figure

#: How each verdict is drawn: colour-blind-safe colours and distinct markers, so the
#: verdict reads in grey-scale too.
VERDICT_STYLES = {
    "reproduced": dict(color="#1b9e77", marker="o"),
    "not reproduced": dict(color="#d95f02", marker="X"),
    "inconclusive": dict(color="0.45", marker="s"),
    "non-inferior": dict(color="#1b9e77", marker="^"),
    "inferior": dict(color="#d95f02", marker="v"),
}
#: The verdicts always in the legend; the others appear when drawn.
_LEGEND_VERDICTS = ("reproduced", "not reproduced", "inconclusive")
_OTHER_VERDICT = dict(color="#7570b3", marker="D")
SCORE_COLOUR = "#1f5fa8"
#: The paper's own effect beside a finding's simulated difference.
PAPER_STYLE = dict(marker="D", ms=7, mfc="none", mec="k", mew=1.3, ls="none")


def _intervals(values, rows: int, name: str) -> np.ndarray:
    array = np.asarray(values, dtype=float).reshape(-1, 3) if np.size(values) else \
        np.empty((0, 3))
    if array.shape != (rows, 3):
        raise ValueError(f"{name}: expected shape ({rows}, 3) of (mean, low, high), "
                         f"got {np.shape(values)}")
    return array


def _interval_rows(ax, labels, stats, styles, *, annotate=True):
    """One row per label, first at the top: a point at the mean with a bar to (low, high).
    Rows whose mean is NaN say "n/a"; a NaN bound leaves out the bar."""
    ax.set_yticks(range(len(labels)), labels=labels)
    ax.set_ylim(len(labels) - 0.5, -0.7)
    drawn = 0
    for row, ((mean, low, high), style) in enumerate(zip(stats, styles)):
        if not np.isfinite(mean):
            ax.text(0.02, row, "n/a (not applicable)", transform=ax.get_yaxis_transform(),
                    va="center", fontsize=8, color="0.4", style="italic")
            continue
        bounds = np.isfinite([low, high]).all()
        xerr = [[max(mean - low, 0.0)], [max(high - mean, 0.0)]] if bounds else None
        ax.errorbar([mean], [row], xerr=xerr, fmt=style["marker"], color=style["color"],
                    ms=7, capsize=4, elinewidth=1.6, zorder=3)
        drawn += 1
        if annotate:
            text = f"{mean:.3g}" + (f"  [{low:.3g}, {high:.3g}]" if bounds else "")
            ax.annotate(text, (mean, row), xytext=(0, 7), textcoords="offset points",
                        ha="center", fontsize=7.5, color="0.25")
    if not drawn:
        ax.text(0.5, 0.5, "no data", transform=ax.transAxes, ha="center", color="0.4")
    ax.grid(axis="x", alpha=0.3)
    ax.margins(x=0.12)
    return drawn


def _one_per_row(values, rows: int, name: str) -> np.ndarray:
    """One value per row (finding or tracker); None: all NaN."""
    array = np.full(rows, np.nan) if values is None else np.asarray(values, dtype=float)
    if array.shape != (rows,):
        raise ValueError(f"{name}: expected {rows} values, got {np.shape(values)}")
    return array


def _figure_summary(tracker_labels, hota, gospa, finding_labels, hota_diff, gospa_diff,
                    verdicts, title="", gospa_verdicts=None, hota_paper=None,
                    gospa_paper=None, false_tracks=None, tracked=None):
    from matplotlib.lines import Line2D
    trackers, findings = list(tracker_labels), list(finding_labels)
    hota = _intervals(hota, len(trackers), "hota")
    gospa = _intervals(gospa, len(trackers), "gospa")
    hota_diff = _intervals(hota_diff, len(findings), "hota_diff")
    gospa_diff = _intervals(gospa_diff, len(findings), "gospa_diff")
    hota_paper = _one_per_row(hota_paper, len(findings), "hota_paper")
    gospa_paper = _one_per_row(gospa_paper, len(findings), "gospa_paper")
    verdicts = [str(v) for v in verdicts]
    gospa_verdicts = verdicts if gospa_verdicts is None else [str(v) for v in gospa_verdicts]
    for name, given in (("verdicts", verdicts), ("gospa_verdicts", gospa_verdicts)):
        if len(given) != len(findings):
            raise ValueError(f"{name}: expected {len(findings)}, got {len(given)}")
    # An unexpected verdict is drawn in a fallback style, not an error: a figure at the
    # end of a long run should not fail over a label.
    styles = {metric: [VERDICT_STYLES.get(v.lower(), _OTHER_VERDICT) for v in given]
              for metric, given in (("HOTA", verdicts), ("GOSPA", gospa_verdicts))}
    management = false_tracks is not None or tracked is not None
    false_tracks = _one_per_row(false_tracks, len(trackers), "false_tracks")
    tracked = _one_per_row(tracked, len(trackers), "tracked")
    # A scope without findings (scenario 2 alone) gets the score panels only, not two empty
    # difference panels.
    rows = max(len(trackers), 1) + 1.2
    heights = [rows] + ([rows] if management else []) + ([len(findings) + 1.2] if findings else [])
    fig = new_figure(figsize=(12.5, 1.6 + 0.42 * sum(heights)), dpi=100, layout="constrained")
    axes = fig.subplots(len(heights), 2, gridspec_kw={"height_ratios": heights}, squeeze=False)
    (ax_h, ax_g) = axes[0]
    tracker_style = [dict(color=SCORE_COLOUR, marker="o")] * len(trackers)
    _interval_rows(ax_h, trackers, hota, tracker_style)
    ax_h.set_title("HOTA per tracker\n(higher is better →)", fontsize=10)
    ax_h.set_xlabel("HOTA (%)")
    _interval_rows(ax_g, trackers, gospa, tracker_style)
    ax_g.set_title("GOSPA per tracker\n(← lower is better)", fontsize=10)
    ax_g.set_xlabel("GOSPA (m)")
    ax_g.tick_params(labelleft=False)
    if title:
        fig.suptitle(title)
    if management:
        ax_f, ax_t = axes[1]
        no_bar = np.full(len(trackers), np.nan)
        _interval_rows(ax_f, trackers, np.column_stack([false_tracks, no_bar, no_bar]),
                       tracker_style)
        ax_f.set_title("False tracks per radar scan, mean over seeds\n(← fewer is better)",
                       fontsize=10)
        ax_f.set_xlabel("false tracks (never matched to a vessel) per scan")
        _interval_rows(ax_t, trackers, np.column_stack([tracked, no_bar, no_bar]),
                       tracker_style)
        ax_t.set_title("Vessel time tracked, mean over seeds\n(more is better →)", fontsize=10)
        ax_t.set_xlabel("vessel time tracked (%)")
        ax_t.tick_params(labelleft=False)
    if not findings:
        return fig
    ax_dh, ax_dg = axes[-1]
    # Both difference panels are signed as the findings table: positive supports the
    # claim "A better than B" (HOTA as A − B, GOSPA — lower is better — as B − A).
    for ax, stats, paper, metric, unit, order in (
            (ax_dh, hota_diff, hota_paper, "HOTA", "percentage points", "A − B"),
            (ax_dg, gospa_diff, gospa_paper, "GOSPA", "m", "B − A")):
        ax.axvline(0.0, color="k", lw=1.0, zorder=1)
        _interval_rows(ax, findings, stats, styles[metric])
        rows = np.flatnonzero(np.isfinite(paper))
        if rows.size:
            ax.plot(paper[rows], rows, zorder=4, gid=f"paper-{metric}", **PAPER_STYLE)
        ax.set_title(f"Paired {metric} difference {order}\n(A better →)", fontsize=10)
        ax.set_xlabel(f"{order} ({unit}); 0 = no difference")
        lo, hi = ax.get_xlim()  # keep the zero line in view even when all are far from it
        ax.set_xlim(min(lo, -0.05 * (hi - lo)), max(hi, 0.05 * (hi - lo)))
    ax_dg.tick_params(labelleft=False)  # same findings as the panel to its left
    drawn = [v.lower() for v in verdicts + gospa_verdicts]
    seen = dict.fromkeys(list(_LEGEND_VERDICTS) + drawn)
    handles = [Line2D([], [], ls="none", ms=8, label=f"verdict: {v}",
                      **VERDICT_STYLES.get(v, _OTHER_VERDICT)) for v in seen]
    handles.append(Line2D([], [], color="0.3", lw=1.6, marker="|", ms=10,
                          label="bar: 95 % interval"))
    if np.isfinite(hota_paper).any() or np.isfinite(gospa_paper).any():
        handles.append(Line2D([], [], label="paper's effect (Table II)", **PAPER_STYLE))
    fig.legend(handles=handles, loc="outside lower center", ncols=min(len(handles), 5),
               fontsize=9, title="Each finding 'A − B' compares tracker A with tracker B; "
                                 "positive differences favour A on both metrics",
               title_fontsize=9)
    return fig


def plot_summary(path: str | Path, tracker_labels: Sequence[str], hota, gospa,
                 finding_labels: Sequence[str], hota_diff, gospa_diff,
                 verdicts: Sequence[str], title: str = "",
                 gospa_verdicts: Sequence[str] | None = None, hota_paper=None,
                 gospa_paper=None, false_tracks=None, tracked=None):
    """Four panels: HOTA (%) and GOSPA (m) per tracker as means with 95 % interval bars;
    below, per finding "A − B", the paired HOTA and GOSPA differences with their intervals
    around a zero line, signed as the findings table (positive favours A: HOTA A − B,
    GOSPA B − A) and marked by verdict ("reproduced", "not reproduced", "inconclusive",
    "non-inferior", "inferior"). ``verdicts`` mark the HOTA panel, and the GOSPA panel too
    unless ``gospa_verdicts`` gives that metric's own; ``hota_paper``/``gospa_paper``
    (one value per finding, NaN: none) add the paper's effect as a hollow diamond.
    ``hota``/``gospa``: (n_trackers, 3) and ``hota_diff``/``gospa_diff``: (n_findings, 3)
    rows of (mean, low, high); NaN rows read "n/a". With ``false_tracks`` / ``tracked``
    (one mean per tracker: false tracks per radar scan, % of vessel time tracked) a row of
    track-management panels follows the scores. With no findings the difference panels
    are left out."""
    _figure_summary(tracker_labels, hota, gospa, finding_labels, hota_diff, gospa_diff,
                    verdicts, title, gospa_verdicts, hota_paper, gospa_paper, false_tracks,
                    tracked).savefig(path)


def _tick(value) -> str:
    if isinstance(value, (int, float, np.integer, np.floating)):
        return f"{value:g}"
    return str(value)


def excludes_zero(low, high, better: str = "higher"):
    """(favours, against): boolean grids of cells whose 95 % interval excludes 0 on the
    side the finding predicts (``better`` = "higher": above 0; "lower": below 0) and on
    the other side. NaN bounds exclude nothing."""
    low, high = np.asarray(low, dtype=float), np.asarray(high, dtype=float)
    above, below = np.nan_to_num(low, nan=-np.inf) > 0, np.nan_to_num(high, nan=np.inf) < 0
    return (above, below) if better == "higher" else (below, above)


def _figure_sensitivity(finding_label, x_name, x_values, y_name, y_values, diff, low, high,
                        metric_label, better="higher"):
    import matplotlib
    from matplotlib.patches import Patch, Rectangle
    if better not in ("higher", "lower"):
        raise ValueError(f"better: 'higher' or 'lower', got {better!r}")
    x_values, y_values = list(x_values), list(y_values)
    shape = (len(y_values), len(x_values))
    grids = []
    for name, values in (("diff", diff), ("low", low), ("high", high)):
        array = np.asarray(values, dtype=float)
        if array.size != shape[0] * shape[1]:
            raise ValueError(f"{name}: expected shape {shape}, got {array.shape}")
        grids.append(array.reshape(shape))  # a 1-D row is accepted for len(y_values) == 1
    diff, low, high = grids
    favours, against = excludes_zero(low, high, better)
    scale = float(np.nanmax(np.abs(diff))) if np.isfinite(diff).any() else 1.0
    scale = scale or 1.0
    # Blue always means "favours the finding": flip the map when lower is better.
    cmap = matplotlib.colormaps["RdBu" if better == "higher" else "RdBu_r"].with_extremes(
        bad="0.82")
    width = max(6.0, 1.35 * shape[1] + 3.2)
    fig = new_figure(figsize=(width, max(3.4, 1.0 * shape[0] + 2.6)), dpi=100,
                  layout="constrained")
    ax = fig.add_subplot()
    image = ax.imshow(np.ma.masked_invalid(diff), cmap=cmap, vmin=-scale, vmax=scale,
                      origin="lower", aspect="auto", interpolation="nearest")
    for i, j in np.ndindex(*shape):
        d = diff[i, j]
        marked = favours[i, j] or against[i, j]
        if not np.isfinite(d):
            ax.text(j, i, "n/a", ha="center", va="center", fontsize=9, color="0.25")
            continue
        text = f"{d:+.3g}"
        if np.isfinite(low[i, j]) and np.isfinite(high[i, j]):
            text += f"\n[{low[i, j]:+.3g}, {high[i, j]:+.3g}]"
        ax.text(j, i, text, ha="center", va="center", fontsize=8.5,
                fontweight="bold" if marked else "normal",
                color="w" if abs(d) > 0.6 * scale else "k")
        if marked:
            box = Rectangle((j - 0.45, i - 0.45), 0.9, 0.9, fill=False, ec="k", lw=2.2,
                            ls="-" if favours[i, j] else (0, (3, 2)), zorder=3)
            box.set_gid(f"excludes-zero:{i},{j}")
            ax.add_patch(box)
    ax.set_xticks(range(shape[1]), labels=[_tick(v) for v in x_values])
    ax.set_xlabel(x_name)
    if shape[0] == 1 and not y_name:
        ax.set_yticks([])
    else:
        ax.set_yticks(range(shape[0]), labels=[_tick(v) for v in y_values])
        ax.set_ylabel(y_name)
    colourbar = fig.colorbar(image, ax=ax, shrink=0.9)
    colourbar.set_label(f"{metric_label} difference")
    good, bad = (1.0, 0.0) if better == "higher" else (0.0, 1.0)
    for y, words in ((good, "favours\nfinding"), (bad, "against\nfinding")):
        colourbar.ax.text(0.5, y + (0.02 if y else -0.02), words, transform=colourbar.ax.transAxes,
                          ha="center", va="bottom" if y else "top", fontsize=7.5)
    # (long claims wrapped to the figure's width: the title is centred over the heatmap,
    # left of the colour bar, and must not run off the figure's left edge)
    ax.set_title("\n".join(textwrap.wrap(f"{finding_label}: {metric_label} difference",
                                         int(11 * width) - 10))
                 + "\nmean [95 % interval] per setting", fontsize=10)
    handles = [Patch(fill=False, ec="k", lw=2.2, label="bold, solid box: interval excludes 0,"
                                                       " favours the finding"),
               Patch(fill=False, ec="k", lw=2.2, ls=(0, (3, 2)),
                     label="bold, dashed box: interval excludes 0, against the finding"),
               Patch(fc="0.82", ec="0.6", label="n/a: not applicable")]
    fig.legend(handles=handles, loc="outside lower center", ncols=1 if shape[1] < 4 else 3,
               fontsize=8, title_fontsize=8.5,
               title=f"{better.capitalize()} {metric_label} is better: blue cells favour the "
                     f"finding, red cells go against it")
    return fig


def plot_sensitivity(path: str | Path, finding_label: str, x_name: str, x_values,
                     y_name: str, y_values, diff, low, high, metric_label: str,
                     better: str = "higher"):
    """Heatmap of a finding's paired difference (mean ``diff`` with 95 % interval
    ``low``..``high``, each of shape (len(y_values), len(x_values))) over two simulation
    settings; a single row when ``len(y_values) == 1``. Diverging colours centred at 0,
    blue where the difference favours the finding (``better``: "higher" or "lower");
    cells whose interval excludes 0 are bold and boxed (solid: favours, dashed: against);
    NaN cells are grey "n/a"."""
    _figure_sensitivity(finding_label, x_name, x_values, y_name, y_values, diff, low, high,
                        metric_label, better).savefig(path)
