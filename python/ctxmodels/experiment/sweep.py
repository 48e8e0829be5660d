"""Sensitivity map: the study's findings over a grid of simulated-sensor settings.

The findings depend on how the simulated truth is set up (its sensors' clutter and
accuracy), never on the trackers, which keep their models in every cell. Two maps:

* radar: far clutter (returns per scan beyond 1000 m) × bearing noise σ, the lidar at its
  default. Far clutter 3.2 per scan makes the trackers' uniform λ = 1e-3 per rad·m true
  everywhere; 32 per scan is the paper's context λ = 1e-2 (the default simulation); 10 lies
  between. Bearing σ 1° is the default, 0.3° about what brings the absolute scores near the
  paper's.
* lidar: clutter segments per scan within 80 m, the radar at its default.

Every cell is the full study's set of jobs with its own simulated sensors; all cells' jobs
share one pool. Each finding is evaluated per cell exactly as in the main study
(:mod:`~ctxmodels.experiment.findings`): the declared one-sided tests with Holm's correction
over that cell's findings × metrics — each cell is the study at that setting, so the
family-wise error rate holds per cell, not over the whole map (a map of where a finding
holds is descriptive; its heatmaps draw the unadjusted 95 % intervals).
"""
from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from . import findings as findings_
from .executors import write_atomic, write_json
from .report import ExperimentResults
from .runner import ExperimentConfig, run_jobs
from .scenarios import LidarConfig, RadarConfig

DEFAULT_FAR_CLUTTER = (3.2, 10.0, 32.0)
DEFAULT_BEARING_STD_DEG = (0.3, 0.6, 1.0)
DEFAULT_LIDAR_CLUTTER = (0.0, 3.0, 10.0)
#: Seeds per cell by default: a full sweep is eleven studies.
SWEEP_SEEDS = 5


@dataclass(frozen=True)
class Cell:
    """One simulated-sensor setting of the sweep."""
    far_clutter: float
    bearing_std_deg: float
    lidar_clutter: float

    def sensors(self) -> tuple[RadarConfig, LidarConfig]:
        radar = dataclasses.replace(RadarConfig(), clutter_per_scan_far=self.far_clutter,
                                    bearing_std=math.radians(self.bearing_std_deg))
        lidar = dataclasses.replace(LidarConfig(), clutter_per_scan=self.lidar_clutter)
        return radar, lidar


@dataclass
class SweepConfig:
    base: ExperimentConfig  # trackers, scenarios, seeds, duration, workers
    far_clutter: Sequence[float] = DEFAULT_FAR_CLUTTER
    bearing_std_deg: Sequence[float] = DEFAULT_BEARING_STD_DEG
    lidar_clutter: Sequence[float] = DEFAULT_LIDAR_CLUTTER

    def cells(self) -> list[Cell]:
        """The radar grid at the default lidar, then the lidar line at the default radar
        (the default setting once)."""
        radar, lidar = RadarConfig(), LidarConfig()
        bearing = math.degrees(radar.bearing_std)
        cells = [Cell(c, b, lidar.clutter_per_scan) for b in self.bearing_std_deg
                 for c in self.far_clutter]
        cells += [Cell(radar.clutter_per_scan_far, bearing, n) for n in self.lidar_clutter]
        unique: dict = {}
        for cell in cells:  # one cell per distinct simulation
            unique.setdefault(cell.sensors(), cell)
        return list(unique.values())

    def experiment(self, cell: Cell) -> ExperimentConfig:
        radar, lidar = cell.sensors()
        return dataclasses.replace(self.base, radar=radar, lidar=lidar, plot_seed=None)


@dataclass
class SweepResults:
    config: SweepConfig
    cells: dict  # Cell -> ExperimentResults
    wall_seconds: float

    def findings(self) -> dict:
        """``{finding key: {cell: FindingResult}}``."""
        table: dict = {f.key: {} for f in findings_.FINDINGS}
        for cell, results in self.cells.items():
            for result in results.findings():
                table[result.finding.key][cell] = result
        return table

    def grids(self, key: str, metric: str = "hota"):
        """The radar map of one finding: ``(far clutter values, bearing values, mean, low,
        high)`` with arrays of shape (bearings, clutters); NaN where not run."""
        return self._grid(key, metric, list(self.config.far_clutter),
                          list(self.config.bearing_std_deg),
                          lambda x, y: (x, y, LidarConfig().clutter_per_scan))

    def lidar_line(self, key: str, metric: str = "hota"):
        radar = RadarConfig()
        return self._grid(key, metric, list(self.config.lidar_clutter), [None],
                          lambda x, _: (radar.clutter_per_scan_far,
                                        math.degrees(radar.bearing_std), x))

    def _grid(self, key, metric, xs, ys, cell_at):
        by_cell = self.findings()[key]
        values = np.full((3, len(ys), len(xs)), math.nan)
        for i, y in enumerate(ys):
            for j, x in enumerate(xs):
                result = by_cell.get(Cell(*cell_at(x, y)))
                interval = getattr(result, metric, None) if result else None
                if interval is not None:
                    values[:, i, j] = (interval.mean, interval.low, interval.high)
        return xs, ys, values[0], values[1], values[2]

    def tracker_scores(self) -> list[dict]:
        """Per cell and tracker: HOTA, GOSPA (mean over seeds, combined scope where the
        tracker ran on Scenarios 1 and 2, else its scenario) and tracks per radar scan."""
        rows = []
        for cell, results in self.cells.items():
            counts = {}
            for row in results.track_counts():
                counts.setdefault(row["tracker"], []).append(row["mean"])
            for row in results.scores():
                scope = next(s for s in results.scopes() if s in row)
                rows.append({**dataclasses.asdict(cell), "tracker": row["tracker"], "scope": scope,
                             "hota": row[scope]["hota"].mean, "gospa": row[scope]["gospa"].mean,
                             "tracks_per_scan": float(np.mean(counts[row["tracker"]]))})
        return rows

    def markdown(self) -> str:
        lines = [f"Sensitivity sweep: {len(self.cells)} simulated-sensor settings × "
                 f"{len(self.config.base.seeds)} seeds; paired differences (positive supports "
                 "the finding) with 95 % paired-t intervals and verdicts. Each setting is "
                 "judged as the main study is (one-sided tests at 5 %, non-inferiority for "
                 "\"≥\" findings, Holm's correction over that setting's findings × metrics); "
                 "the family is the setting's, not the whole map's: read the map as where "
                 "each finding holds, not as one confirmatory test.", ""]
        lines.append("| Finding | far clutter /scan | bearing σ (°) | lidar clutter /scan | "
                     "ΔHOTA (pp) [95 % CI] | ΔGOSPA (m) [95 % CI] | verdict |")
        lines.append("|---|---|---|---|---|---|---|")
        for finding in findings_.FINDINGS:
            for cell, result in self.findings()[finding.key].items():
                if result.hota is None:
                    continue
                lines.append(
                    f"| {finding.short} | {cell.far_clutter:g} | {cell.bearing_std_deg:g} | "
                    f"{cell.lidar_clutter:g} | {_cell(result.hota)} | {_cell(result.gospa)} | "
                    f"{result.verdict} |")
        lines += ["", "Scores per setting (mean over seeds; S1+S2 combined where the tracker "
                  "ran there) and tracks per radar scan (mean over scenarios):", "",
                  "| far clutter /scan | bearing σ (°) | lidar clutter /scan | tracker | scope | "
                  "HOTA (%) | GOSPA (m) | tracks per scan |", "|---|---|---|---|---|---|---|---|"]
        for row in self.tracker_scores():
            lines.append(f"| {row['far_clutter']:g} | {row['bearing_std_deg']:g} | "
                         f"{row['lidar_clutter']:g} | {row['tracker']} | {row['scope']} | "
                         f"{row['hota']:.1f} | {row['gospa']:.1f} | {row['tracks_per_scan']:.1f} |")
        return "\n".join(lines)

    def save(self, folder: str | Path, plots: bool = True) -> dict[str, Path]:
        folder = Path(folder)
        folder.mkdir(parents=True, exist_ok=True)
        paths = {"markdown": folder / "sweep.md", "json": folder / "sweep.json"}
        rows = []
        for key, by_cell in self.findings().items():
            for cell, result in by_cell.items():
                rows.append({**dataclasses.asdict(cell), **result.as_dict()})
        write_atomic(paths["markdown"], self.markdown() + "\n")
        write_json(paths["json"], {"seeds": list(self.config.base.seeds),
                                   "duration": self.config.base.duration,
                                   "cells": rows, "scores": self.tracker_scores()})
        if plots:
            paths.update(self._plot(folder))
        return paths

    def _plot(self, folder: Path) -> dict[str, Path]:
        from .summary_plots import plot_sensitivity
        written = {}
        for finding in findings_.FINDINGS:
            xs, ys, mean, low, high = self.grids(finding.key)
            if np.all(np.isnan(mean)):
                continue
            path = folder / f"sweep_{finding.key}_radar.png"
            plot_sensitivity(path, f"{finding.short}: {finding.claim}",
                             "radar far clutter (returns per scan beyond 1 km)", xs,
                             "radar bearing σ (°)", ys, mean, low, high,
                             "ΔHOTA (pp)")
            written[path.stem] = path
            xs, _, mean, low, high = self.lidar_line(finding.key)
            path = folder / f"sweep_{finding.key}_lidar.png"
            plot_sensitivity(path, f"{finding.short}: {finding.claim}",
                             "lidar clutter (segments per scan within 80 m)", xs, "", [0.0],
                             mean, low, high, "ΔHOTA (pp)")
            written[path.stem] = path
        return written


def _cell(interval) -> str:
    if math.isnan(interval.low):
        return f"{interval.mean:+.1f}"
    return f"{interval.mean:+.1f} [{interval.low:+.1f}, {interval.high:+.1f}]"


def run_sweep(config: SweepConfig, executor=None, progress: bool = True) -> SweepResults:
    """Runs every cell's study in one pool (see :func:`~.runner.run_experiment`)."""
    started = time.perf_counter()
    experiments = {cell: config.experiment(cell) for cell in config.cells()}
    jobs = [job for experiment in experiments.values() for job in experiment.jobs()]
    results = run_jobs(jobs, config.base.workers, executor, progress)
    by_sensors: dict = {}
    for result in results:
        by_sensors.setdefault((result.job.radar, result.job.lidar), []).append(result)
    wall = time.perf_counter() - started
    cells = {cell: ExperimentResults(experiment, by_sensors.get((experiment.radar, experiment.lidar), []), wall)
             for cell, experiment in experiments.items()}
    return SweepResults(config, cells, wall)
