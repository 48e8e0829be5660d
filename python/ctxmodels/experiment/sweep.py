"""Sensitivity map: the study's findings over a grid of simulated-sensor settings.

The findings depend on how the simulated truth is set up, never on the trackers, which
keep their models in every cell. Around the calibrated truth (``docs/calibration.md``):

* radar map: the radar's true P_D × its far clutter density (per rad·m beyond 1000 m). P_D
  is the value the calibration could not identify (0.6–0.95 fitted the baseline rows
  equally); far clutter 1e-3 makes the trackers' uniform λ true everywhere, 3e-3 is the
  calibrated value, 1e-2 the paper's context λ;
* bearing line: the radar's bearing σ (0.5° calibrated, 1° the stress truth's);
* lidar line: lidar clutter points per scan within 80 m (0.3 calibrated);
* the ``stress`` truth (:data:`~ctxmodels.experiment.scenarios.TRUTHS`) as one more cell:
  the trackers' P_D 0.4 and far λ 1e-2 copied into the truth, bearing σ 1°, 3 lidar
  clutter points a scan.

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
from .scenarios import TRUTHS, LidarConfig, RadarConfig
from .simulation.radar import CALIBRATED_CLUTTER_DENSITY

DEFAULT_RADAR_PD = (0.4, 0.7, 0.9)
DEFAULT_FAR_CLUTTER = (1e-3, 3e-3, 1e-2)  # per rad·m beyond 1000 m
DEFAULT_BEARING_STD_DEG = (0.5, 1.0)
DEFAULT_LIDAR_CLUTTER = (0.3, 3.0, 10.0)
#: Seeds per cell by default.
SWEEP_SEEDS = 5


@dataclass(frozen=True)
class Cell:
    """One simulated-sensor setting of the sweep: the calibrated truth with these values,
    or (``truth="stress"``) the named stress truth as it is, described by its values."""
    prob_detection: float
    far_clutter: float  # per rad·m beyond 1000 m
    bearing_std_deg: float
    lidar_clutter: float
    truth: str = "calibrated"

    def __post_init__(self):
        if self.truth not in TRUTHS:
            raise ValueError(f"truth: unknown truth {self.truth!r}; choose from {list(TRUTHS)}")
        if not (0.0 < self.prob_detection <= 1.0):
            raise ValueError(f"prob_detection: the radar's P_D must be in (0, 1], got "
                             f"{self.prob_detection!r}")
        for name in ("far_clutter", "lidar_clutter"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0.0):
                raise ValueError(f"{name}: must be finite and ≥ 0, got {value!r}")
        if not (math.isfinite(self.bearing_std_deg) and self.bearing_std_deg > 0.0):
            raise ValueError(f"bearing_std_deg: must be finite and > 0, got "
                             f"{self.bearing_std_deg!r}")

    @classmethod
    def of_truth(cls, name: str) -> Cell:
        radar, lidar = TRUTHS[name].radar, TRUTHS[name].lidar
        # (the calibrated density exactly, so that its cell is the default study's truth)
        far = (CALIBRATED_CLUTTER_DENSITY[1] if name == "calibrated"
               else radar.clutter_density_far)
        return cls(radar.prob_detection, far, math.degrees(radar.bearing_std),
                   lidar.clutter_per_scan, name)

    def sensors(self) -> tuple[RadarConfig, LidarConfig]:
        truth = TRUTHS[self.truth]
        if self.truth != "calibrated":
            return truth.radar, truth.lidar
        base = truth.radar
        # (the product in RadarConfig's order, so the calibrated cell is bit-identical)
        far = self.far_clutter * base.covered_bearing_extent * (
            base.max_range - base.clutter_boundary_range)
        radar = dataclasses.replace(base, prob_detection=self.prob_detection,
                                    clutter_per_scan_far=far,
                                    bearing_std=math.radians(self.bearing_std_deg))
        lidar = dataclasses.replace(truth.lidar, clutter_per_scan=self.lidar_clutter)
        return radar, lidar


def calibrated_cell() -> Cell:
    return Cell.of_truth("calibrated")


@dataclass
class SweepConfig:
    base: ExperimentConfig  # trackers, scenarios, seeds, duration, workers
    prob_detection: Sequence[float] = DEFAULT_RADAR_PD
    far_clutter: Sequence[float] = DEFAULT_FAR_CLUTTER
    bearing_std_deg: Sequence[float] = DEFAULT_BEARING_STD_DEG
    lidar_clutter: Sequence[float] = DEFAULT_LIDAR_CLUTTER
    stress: bool = True  # the stress truth as one more cell

    def cells(self) -> list[Cell]:
        """The radar map, then the bearing and lidar lines at the calibrated radar (the
        calibrated setting once), then the stress truth."""
        home = calibrated_cell()
        cells = [dataclasses.replace(home, prob_detection=pd, far_clutter=far)
                 for pd in self.prob_detection for far in self.far_clutter]
        cells += [dataclasses.replace(home, bearing_std_deg=b) for b in self.bearing_std_deg]
        cells += [dataclasses.replace(home, lidar_clutter=n) for n in self.lidar_clutter]
        if self.stress:
            cells.append(Cell.of_truth("stress"))
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
        """The radar map of one finding: ``(far clutter values, P_D values, mean, low,
        high)`` with arrays of shape (P_Ds, clutters); NaN where not run."""
        home = calibrated_cell()
        return self._grid(key, metric, list(self.config.far_clutter),
                          list(self.config.prob_detection),
                          lambda x, y: dataclasses.replace(home, prob_detection=y, far_clutter=x))

    def bearing_line(self, key: str, metric: str = "hota"):
        home = calibrated_cell()
        return self._grid(key, metric, list(self.config.bearing_std_deg), [None],
                          lambda x, _: dataclasses.replace(home, bearing_std_deg=x))

    def lidar_line(self, key: str, metric: str = "hota"):
        home = calibrated_cell()
        return self._grid(key, metric, list(self.config.lidar_clutter), [None],
                          lambda x, _: dataclasses.replace(home, lidar_clutter=x))

    def _grid(self, key, metric, xs, ys, cell_at):
        by_cell = self.findings()[key]
        values = np.full((3, len(ys), len(xs)), math.nan)
        for i, y in enumerate(ys):
            for j, x in enumerate(xs):
                result = by_cell.get(cell_at(x, y))
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
        lines.append("| Finding | truth | radar P_D | far clutter (/rad·m) | bearing σ (°) | "
                     "lidar clutter /scan | ΔHOTA (pp) [95 % CI] | ΔGOSPA (m) [95 % CI] | "
                     "verdict |")
        lines.append("|---|---|---|---|---|---|---|---|---|")
        for finding in findings_.FINDINGS:
            for cell, result in self.findings()[finding.key].items():
                if result.hota is None:
                    continue
                lines.append(
                    f"| {finding.short} | {_setting(cell)} | {_cell(result.hota)} | "
                    f"{_cell(result.gospa)} | {result.verdict} |")
        lines += ["", "Scores per setting (mean over seeds; S1+S2 combined where the tracker "
                  "ran there) and tracks per radar scan (mean over scenarios):", "",
                  "| truth | radar P_D | far clutter (/rad·m) | bearing σ (°) | lidar clutter /scan "
                  "| tracker | scope | HOTA (%) | GOSPA (m) | tracks per scan |",
                  "|---|---|---|---|---|---|---|---|---|---|"]
        for row in self.tracker_scores():
            cell = Cell(*(row[f.name] for f in dataclasses.fields(Cell)))
            lines.append(f"| {_setting(cell)} | {row['tracker']} | {row['scope']} | "
                         f"{row['hota']:.1f} | {row['gospa']:.1f} | {row['tracks_per_scan']:.1f} |")
        return "\n".join(lines)

    def save(self, folder: str | Path, plots: bool = True) -> dict[str, Path]:
        folder = Path(folder)
        folder.mkdir(parents=True, exist_ok=True)
        paths = {"markdown": folder / "sweep.md", "json": folder / "sweep.json"}
        rows = []
        for by_cell in self.findings().values():
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
                             "radar far clutter (per rad·m beyond 1 km)", xs,
                             "radar P_D (truth)", ys, mean, low, high, "ΔHOTA (pp)")
            written[path.stem] = path
            for name, axis, line in (
                    ("bearing", "radar bearing σ (°)", self.bearing_line(finding.key)),
                    ("lidar", "lidar clutter (points per scan within 80 m)",
                     self.lidar_line(finding.key))):
                path = folder / f"sweep_{finding.key}_{name}.png"
                plot_sensitivity(path, f"{finding.short}: {finding.claim}", axis, line[0], "",
                                 [0.0], line[2], line[3], line[4], "ΔHOTA (pp)")
                written[path.stem] = path
        return written


def _setting(cell: Cell) -> str:
    """A cell's truth columns: name, radar P_D, far clutter, bearing σ, lidar clutter."""
    return (f"{cell.truth} | {cell.prob_detection:g} | {cell.far_clutter:.3g} | "
            f"{cell.bearing_std_deg:g} | {cell.lidar_clutter:g}")


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
    cells = {cell: ExperimentResults(
                 experiment, by_sensors.get((experiment.radar, experiment.lidar), []), wall)
             for cell, experiment in experiments.items()}
    return SweepResults(config, cells, wall)
