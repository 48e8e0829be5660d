"""The experiment's figures: every tracker's tracks on every scenario for the plot seed, the
context-aware models' coverage per scenario, and a summary per scope (scores with their
intervals, and the paired differences of the findings on that scope)."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from .findings import COMBINED, paper_effect
from .scenarios import SOLENT

_SCOPE_TITLES = {COMBINED: "Scenarios 1 and 2 combined", "mixed-range": "Scenario 1 (mixed-range)",
                 "formation": "Scenario 2 (formation)", "islands": "Scenario 3 (islands)",
                "solent": "Scenario 4 (Solent)"}


def draw_experiment_figures(results, folder: Path) -> dict[str, Path]:
    """Writes the figures of ``results`` (an :class:`~.report.ExperimentResults`) to
    ``folder``; returns ``{name: path}``.

    Drawn in this process, one after the other: a forked pool would inherit the Rust core's
    thread pool without its threads, and the coverage grids are large enough to use it."""
    config = results.config
    written = {}
    for scenario in config.scenarios:
        plotted = [(r.job.tracker, r.tracks) for r in sorted(results.results, key=lambda r: r.job.tracker)
                   if r.job.scenario == scenario and r.job.seed == config.plot_seed]
        if scenario == SOLENT:
            written.update(_draw_solent(folder, config.plot_seed, config.duration, plotted))
            continue
        written.update(_draw_scenario(folder, scenario, config.plot_seed, config.duration,
                                      plotted, config.radar, config.lidar))
        if scenario == "mixed-range":
            written.update(_draw_paper_figures(folder, config.plot_seed, config.duration,
                                               dict(plotted), config.radar, config.lidar))
    for scope, fields in _summaries(results):
        written.update(_draw_summary(folder, scope, fields))
    return written


def _draw_scenario(folder: Path, scenario: str, seed: int, duration, plotted, radar=None,
                   lidar=None) -> dict[str, Path]:
    """Every plotted tracker's tracks on ``scenario`` (``plotted``: (tracker, kept track
    paths) pairs), and the context-aware models' coverage there."""
    from .coverage_plots import plot_coverage
    from .track_plots import Polyline, plot_tracks
    from .runner import simulated_run
    from .sensors import paper_sensor_models
    from ..trackers import TRACKERS
    written = {}
    # (the runs' own simulation: cached, so scenario 1's serves the paper figures too)
    run = simulated_run(scenario, seed, duration, radar, lidar)
    epoch = run.radar_times[0]
    truths = [Polyline.from_states(t.states, epoch, label=t.id)
              for t in sorted(run.truths, key=lambda t: t.id)]
    ego = Polyline([(t - epoch).total_seconds() for t in run.ego.timestamps], run.ego.positions)
    for tracker, paths in plotted:
        tracks = [Polyline(times, xy) for times, xy in paths]
        path = folder / f"tracks_{scenario}_{tracker}.png"
        plot_tracks(path, f"{scenario}: {TRACKERS[tracker].label} (seed {seed})",
                    tracks, truths, ego, float(run.ego.headings[-1]), land=run.land,
                    static_positions=run.static_positions)
        written[path.stem] = path
    pose = run.ego.pose_at(run.radar_times[0])
    path = folder / f"coverage_{scenario}.png"
    plot_coverage(path, paper_sensor_models(land=run.land), tuple(pose), land=run.land,
                  title=f"P_D of the context-aware models, {scenario}, first radar scan")
    written[path.stem] = path
    return written


def _draw_solent(folder: Path, seed: int, duration, plotted) -> dict[str, Path]:
    """The Solent's tracks per tracker over the coast, and its radars' coverage."""
    from .runner import simulated_run
    from .solent.figures import plot_solent_coverage, plot_solent_tracks
    from .track_plots import Polyline
    from ..trackers import TRACKERS
    written = {}
    run = simulated_run(SOLENT, seed, duration, None, None)
    epoch = run.radar_times[0]
    truths = [Polyline.from_states(t.states, epoch, label=t.id)
              for t in sorted(run.truths, key=lambda t: t.id)]
    for tracker, paths in plotted:
        path = folder / f"tracks_{SOLENT}_{tracker}.png"
        plot_solent_tracks(path, f"Solent: {TRACKERS[tracker].label} (seed {seed})",
                           [Polyline(times, xy) for times, xy in paths], truths)
        written[path.stem] = path
    path = folder / f"coverage_{SOLENT}.png"
    plot_solent_coverage(path)
    written[path.stem] = path
    return written


#: The paper's Fig. 4 panels on scenario 1: the better JPDA baseline, uniform, context-aware.
FIG4_TRACKERS = (("jpda-tuned", "jpda"), ("gmphd-uniform",), ("gmphd-context",))
#: The mechanism figure's trackers: the weight a far vessel keeps under each.
MECHANISM_TRACKERS = ("gmphd-uniform", "gmphd-pd-aware", "gmphd-context")


def _draw_paper_figures(folder: Path, seed: int, duration, plotted: dict, radar=None,
                        lidar=None) -> dict[str, Path]:
    """Scenario 1 as the paper shows it: trackers side by side (its Fig. 4), and the
    mechanism — the far vessel's GM-PHD weight over time under each tracker."""
    from .runner import simulated_run
    from .track_plots import Polyline, plot_mechanism, plot_track_panels
    from ..trackers import TRACKERS
    written = {}
    run = simulated_run("mixed-range", seed, duration, radar, lidar)
    epoch = run.radar_times[0]
    truths = [Polyline.from_states(t.states, epoch, label=t.id)
              for t in sorted(run.truths, key=lambda t: t.id)]
    ego = Polyline([(t - epoch).total_seconds() for t in run.ego.timestamps], run.ego.positions)
    panels = []
    for choices in FIG4_TRACKERS:
        name = next((n for n in choices if n in plotted), None)
        if name is not None:
            panels.append((TRACKERS[name].label,
                           [Polyline(times, xy) for times, xy in plotted[name]]))
    if len(panels) == len(FIG4_TRACKERS):
        path = folder / "tracks_mixed-range_fig4.png"
        plot_track_panels(path, f"Scenario 1 (seed {seed}), as the paper's Fig. 4", panels,
                          truths, ego, float(run.ego.headings[-1]),
                          static_positions=run.static_positions)
        written[path.stem] = path
    present = [name for name in MECHANISM_TRACKERS if name in plotted]
    if len(present) >= 2:
        ego_xy = np.asarray(run.ego.positions)
        far = max(truths, key=lambda t: float(np.median(np.hypot(*(t.xy - ego_xy[-1]).T))))
        seconds = [(t - epoch).total_seconds() for t in run.radar_times]
        window = (0.0, min(MECHANISM_WINDOW, seconds[-1]))
        series = [(TRACKERS[name].label, *mass_on_vessel(name, run, far.label, window[1]))
                  for name in present]
        lidar_seconds = [(t - epoch).total_seconds() for t in run.lidar_times]
        path = folder / "mechanism_mixed-range.png"
        plot_mechanism(path, f"Scenario 1 (seed {seed}): the PHD mass on {far.label}, the "
                       "vessel farthest from the ego, beyond the lidar's 80 m",
                       series, seconds, lidar_seconds, window=window)
        written[path.stem] = path
    return written


#: Seconds of scenario 1 the mechanism figure shows.
MECHANISM_WINDOW = 40.0


def mass_on_vessel(tracker: str, run, vessel: str, until: float,
                   distance: float = 30.0) -> tuple[list, list]:
    """Runs ``tracker`` (a GM-PHD) on ``run`` for its first ``until`` seconds and returns
    (times since the first radar scan, PHD mass) after each scan: the summed weight of the
    mixture's components within ``distance`` m of ``vessel`` at that time."""
    from ..trackers import TRACKERS
    from .trackers import build_tracker
    if TRACKERS[tracker].family != "gmphd":
        raise ValueError(f"tracker: {tracker} has no PHD mixture (a GM-PHD is needed)")
    if vessel not in run.truth_by_id:
        raise ValueError(f"vessel: {vessel!r} is not one of {list(run.truth_by_id)}")
    epoch = run.radar_times[0]
    truth = {state.timestamp: state for state in run.truth_by_id[vessel]}
    times, masses = [], []
    built = build_tracker(TRACKERS[tracker], run)
    for time, _ in built:
        seconds = (time - epoch).total_seconds()
        if seconds > until:
            break
        state = truth.get(time)
        mass = 0.0
        if state is not None:
            xy = np.array([float(state.state_vector[0]), float(state.state_vector[2])])
            for component in built.gaussian_mixture:
                mean = np.asarray(component.state_vector, dtype=float).ravel()
                if math.hypot(mean[0] - xy[0], mean[2] - xy[1]) <= distance:
                    mass += float(component.weight)
        times.append(seconds)
        masses.append(mass)
    return times, masses


def _summaries(results) -> list[tuple[str, dict]]:
    """Per scope, the scope and the keyword arguments of
    :func:`~.summary_plots.plot_summary`. The findings' differences are drawn exactly as
    the findings table gives them (positive supports the claim, GOSPA too) and each
    panel's markers are that metric's verdict, not the finding's overall one."""
    rows = results.scores()
    managed = {(row["tracker"], row["scope"]): row for row in results.management()}
    findings = [f for f in results.findings() if f.hota is not None]
    seeds = len(results.config.seeds)
    out = []
    for scope in results.scopes():
        scored = [row for row in rows if scope in row]
        here = [f for f in findings if f.finding.scope == scope]
        paper = [paper_effect(f.finding) or (np.nan, np.nan) for f in here]
        out.append((scope, dict(
            tracker_labels=[row["label"] for row in scored],
            hota=np.array([_triple(row[scope]["hota"]) for row in scored]).reshape(-1, 3),
            gospa=np.array([_triple(row[scope]["gospa"]) for row in scored]).reshape(-1, 3),
            finding_labels=[f.finding.short or f.finding.key for f in here],
            hota_diff=np.array([_triple(f.hota) for f in here]).reshape(-1, 3),
            gospa_diff=np.array([_triple(f.gospa) for f in here]).reshape(-1, 3),
            verdicts=[f.hota_verdict for f in here],
            gospa_verdicts=[f.gospa_verdict for f in here],
            hota_paper=np.array([p[0] for p in paper], dtype=float),
            gospa_paper=np.array([p[1] for p in paper], dtype=float),
            false_tracks=np.array([managed.get((row["tracker"], scope), {}).get(
                "false_tracks_per_scan", np.nan) for row in scored], dtype=float),
            tracked=np.array([managed.get((row["tracker"], scope), {}).get(
                "tracked_percent", np.nan) for row in scored], dtype=float),
            title=f"{_SCOPE_TITLES.get(scope, scope)}: mean and 95 % interval over {seeds} "
                  f"seeds")))
    return out


def _draw_summary(folder: Path, scope: str, fields: dict) -> dict[str, Path]:
    from .summary_plots import plot_summary
    path = folder / f"summary_{scope}.png"
    plot_summary(path, **fields)
    return {path.stem: path}


def _triple(interval) -> tuple[float, float, float]:
    return (interval.mean, interval.low, interval.high)
