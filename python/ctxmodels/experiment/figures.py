"""The experiment's figures: every tracker's tracks on every scenario for the plot seed, the
context-aware models' coverage per scenario, and a summary per scope (scores with their
intervals, and the paired differences of the findings on that scope)."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from .findings import COMBINED

_SCOPE_TITLES = {COMBINED: "Scenarios 1 and 2 combined", "mixed-range": "Scenario 1 (mixed-range)",
                 "formation": "Scenario 2 (formation)", "islands": "Scenario 3 (islands)"}


def draw_experiment_figures(results, folder: Path) -> dict[str, Path]:
    """Writes the figures of ``results`` (an :class:`~.report.ExperimentResults`) to
    ``folder``; returns ``{name: path}``."""
    written = _draw_tracks_and_coverage(results, folder)
    written.update(_draw_summaries(results, folder))
    return written


def _draw_tracks_and_coverage(results, folder: Path) -> dict[str, Path]:
    from .plots import Polyline, plot_coverage, plot_tracks
    from .scenarios import make_scenario
    from .sensors import paper_sensor_models
    from .trackers import TRACKERS
    written = {}
    config = results.config
    for scenario in config.scenarios:
        run = make_scenario(scenario, config.plot_seed, config.duration)
        epoch = run.radar_times[0]
        truths = [Polyline.from_states(t.states, epoch, label=t.id)
                  for t in sorted(run.truths, key=lambda t: t.id)]
        ego = Polyline([(t - epoch).total_seconds() for t in run.ego.timestamps],
                       run.ego.positions)
        for result in sorted(results.results, key=lambda r: r.job.tracker):
            job = result.job
            if job.scenario != scenario or job.seed != config.plot_seed:
                continue
            tracks = [Polyline(times, xy) for times, xy in result.tracks]
            path = folder / f"tracks_{scenario}_{job.tracker}.png"
            plot_tracks(path, f"{scenario}: {TRACKERS[job.tracker].label} (seed {job.seed})",
                        tracks, truths, ego, float(run.ego.headings[-1]), land=run.land,
                        static_positions=run.static_positions)
            written[path.stem] = path
        pose = run.ego.pose_at(run.radar_times[0])
        path = folder / f"coverage_{scenario}.png"
        plot_coverage(path, paper_sensor_models(land=run.land), tuple(pose), land=run.land,
                      title=f"P_D of the context-aware models, {scenario}, first radar scan")
        written[path.stem] = path
    return written


def _draw_summaries(results, folder: Path) -> dict[str, Path]:
    from .summary_plots import plot_summary
    written = {}
    rows = results.scores()
    findings = [f for f in results.findings() if f.hota is not None]
    seeds = len(results.config.seeds)
    for scope in results.scopes():
        scored = [row for row in rows if scope in row]
        here = [f for f in findings if f.finding.scope == scope]
        path = folder / f"summary_{scope}.png"
        plot_summary(
            path, [row["label"] for row in scored],
            np.array([_triple(row[scope]["hota"]) for row in scored]).reshape(-1, 3),
            np.array([_triple(row[scope]["gospa"]) for row in scored]).reshape(-1, 3),
            [f.finding.short or f.finding.key for f in here],
            np.array([_triple(f.hota) for f in here]).reshape(-1, 3),
            # The figure shows GOSPA differences as A − B (negative: A better); the
            # findings sign them so that positive supports the claim.
            np.array([_triple(f.gospa, negate=True) for f in here]).reshape(-1, 3),
            [f.verdict for f in here],
            title=f"{_SCOPE_TITLES.get(scope, scope)}: mean and 95 % interval over {seeds} seeds")
        written[path.stem] = path
    return written


def _triple(interval, negate: bool = False) -> tuple[float, float, float]:
    if negate:
        return (-interval.mean, -interval.high, -interval.low)
    return (interval.mean, interval.low, interval.high)
