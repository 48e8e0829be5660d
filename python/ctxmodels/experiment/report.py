"""The experiment's results: score table, findings, track counts, and the files they go to.

Per tracker and scope the score is the mean over seeds with its percentile-bootstrap 95 %
interval (:func:`~.statistics.bootstrap_mean`); findings compare trackers paired by seed
(:mod:`~.findings`). Every number written depends only on the jobs' results, never on
their completion order: no timing goes into the files (two runs write identical files),
it is printed (:meth:`ExperimentResults.timing_line`).
"""
from __future__ import annotations

import csv
import io
import math
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from . import findings as findings_
from .executors import write_atomic, write_json
from .findings import COMBINED, seed_scores
from .statistics import bootstrap_mean

#: Scenario names in table order, and the short labels of the results table.
SCENARIO_LABELS = {"mixed-range": "Scenario 1", "formation": "Scenario 2", "islands": "Scenario 3"}


def simulation_changes(radar, lidar) -> str:
    """The simulated-sensor settings that differ from the defaults, as ``name=value`` text
    (empty when none do), so a results table always says what it was simulated with."""
    from .scenarios import LidarConfig, RadarConfig
    parts = []
    for prefix, config, default in (("radar", radar, RadarConfig()), ("lidar", lidar, LidarConfig())):
        if config is None:
            continue
        for name, value in asdict(config).items():
            if value != getattr(default, name):
                parts.append(f"{prefix}.{name}={value:g}" if isinstance(value, float)
                             else f"{prefix}.{name}={value}")
    return ", ".join(parts)


def truth_line(radar, lidar) -> str:
    """One sentence naming the simulated truth: a named truth
    (:data:`~ctxmodels.experiment.scenarios.TRUTHS`) or its changes from the calibrated
    defaults."""
    from .scenarios import TRUTHS, LidarConfig, RadarConfig
    radar, lidar = radar or RadarConfig(), lidar or LidarConfig()
    for truth in TRUTHS.values():
        if (truth.radar, truth.lidar) == (radar, lidar):
            return f"Simulated truth: {truth.name} ({truth.description})."
    return (f"Simulated truth: the calibrated one with {simulation_changes(radar, lidar)}.")


@dataclass
class ExperimentResults:
    config: object  # ExperimentConfig
    results: list  # [JobResult]
    wall_seconds: float

    def by_key(self) -> dict:
        return {(r.job.tracker, r.job.scenario, r.job.seed): r for r in self.results}

    def trackers(self) -> list[str]:
        from .trackers import TRACKERS
        ran = {r.job.tracker for r in self.results}
        return [t for t in (self.config.trackers or TRACKERS) if t in ran]

    def scopes(self) -> list[str]:
        scenarios = [s for s in self.config.scenarios if any(r.job.scenario == s for r in self.results)]
        combined = all(s in scenarios for s in findings_.COMBINED_SCENARIOS)
        return ([COMBINED] if combined else []) + scenarios

    def scores(self) -> list[dict]:
        """One row per tracker: per scope (``"combined"`` and each scenario) HOTA (%) and RMS
        GOSPA (m) as :class:`~.statistics.Interval` s over seeds, and the mean tracking
        seconds per run."""
        from .trackers import TRACKERS
        by_key = self.by_key()
        rows = []
        for tracker in self.trackers():
            row = {"tracker": tracker, "label": TRACKERS[tracker].label}
            for scope in self.scopes():
                per_seed = seed_scores(by_key, tracker, scope)
                if per_seed:
                    values = np.array(list(per_seed.values()))
                    row[scope] = {"hota": bootstrap_mean(values[:, 0]),
                                  "gospa": bootstrap_mean(values[:, 1])}
            row["seconds"] = float(np.mean([r.seconds for r in self.results if r.job.tracker == tracker]))
            rows.append(row)
        return rows

    def findings(self) -> list:
        return findings_.evaluate_all(self.by_key())

    def track_counts(self) -> list[dict]:
        """Per tracker and scenario: tracks reported per radar scan (mean over scans and
        seeds, and the largest), beside the vessels present per scan."""
        from .trackers import TRACKERS
        rows = []
        for tracker in self.trackers():
            for scenario in self.config.scenarios:
                runs = [r for r in self.results if r.job.tracker == tracker and r.job.scenario == scenario]
                if not runs:
                    continue
                counts = np.concatenate([np.asarray(r.tracks_per_time, dtype=float) for r in runs])
                vessels = np.concatenate([np.asarray(r.truths_per_time, dtype=float) for r in runs])
                rows.append({"tracker": tracker, "label": TRACKERS[tracker].label,
                             "scenario": scenario, "mean": float(counts.mean()),
                             "max": int(counts.max()), "vessels": float(vessels.mean()),
                             "tracks_started": float(np.mean([r.track_count for r in runs]))})
        return rows

    def table_markdown(self) -> str:
        """The results table in the layout of the paper's Table II (plus Scenario 3)."""
        rows = self.scores()
        columns = self.scopes()
        names = {COMBINED: "Combined (S1+S2)", **SCENARIO_LABELS}
        header = "| Method | " + " | ".join(
            f"{names.get(c, c)} HOTA (%) ↑ | {names.get(c, c)} GOSPA (m) ↓" for c in columns) + " |"
        lines = [header, "|" + "---|" * (1 + 2 * len(columns))]

        def cell(row, column, metric):
            if column not in row:
                return "—"
            value = row[column][metric]
            if math.isnan(value.low):
                return f"{value.mean:.1f}"
            return f"{value.mean:.1f} [{value.low:.1f}, {value.high:.1f}]"

        for row in rows:
            lines.append(f"| {row['label']} | " + " | ".join(
                f"{cell(row, c, 'hota')} | {cell(row, c, 'gospa')}" for c in columns) + " |")
        seeds = self.config.seeds
        lines.append("")
        lines.append(f"Mean [95 % percentile-bootstrap interval] over {len(seeds)} seeds "
                     f"({seeds[0]}–{seeds[-1]}); "
                     f"{f'{self.config.duration:g} s' if self.config.duration else 'the whole'} "
                     f"of each scenario; "
                     f"{'component-path' if self.config.stock else 'array'} trackers.")
        lines.append(truth_line(self.config.radar, self.config.lidar))
        extract = getattr(self.config, "extract", "stone-soup")
        lines.append("Scored states: " + ("every state of every reported track (Stone Soup's "
                                          "extraction)." if extract == "stone-soup" else
                                          "GM-PHD states of weight ≥ 0.5 only."))
        return "\n".join(lines)

    def track_counts_markdown(self) -> str:
        lines = ["| Method | Scenario | tracks per radar scan (mean) | max | vessels per scan | "
                 "tracks per run |", "|---|---|---|---|---|---|"]
        for row in self.track_counts():
            lines.append(f"| {row['label']} | {SCENARIO_LABELS.get(row['scenario'], row['scenario'])} | "
                         f"{row['mean']:.1f} | {row['max']} | {row['vessels']:.1f} | "
                         f"{row['tracks_started']:.0f} |")
        lines += ["", "Tracks reported at each radar timestamp (static-object tracks dropped "
                  "as distractors), over all scans and seeds; tracks per run counts every "
                  "track the tracker reported at some time."]
        return "\n".join(lines)

    def timing_line(self) -> str:
        """Wall time of the study; the runs' tracking as CPU time (each run's process CPU
        time while its tracker ran, summed) and as wall time (each run's tracking wall
        time, summed: more than the CPU time when runs share a busy core)."""
        cpu = sum(r.cpu_seconds for r in self.results)
        busy = sum(r.seconds for r in self.results)
        return (f"{len(self.results)} runs; wall time {self.wall_seconds:.0f} s; tracking "
                f"{cpu:.0f} CPU-s in total ({busy:.0f} s of the runs' wall time).")

    def markdown(self) -> str:
        return "\n\n".join([
            "## Scores", self.table_markdown(),
            "## Findings", findings_.findings_markdown(self.findings()),
            "## Tracks per radar scan", self.track_counts_markdown()])

    def save(self, folder: str | Path) -> dict[str, Path]:
        """Writes results.md/.csv/.json and findings.md/.json to ``folder``; each file appears
        complete or not at all (written beside its final name, then renamed)."""
        folder = Path(folder)
        folder.mkdir(parents=True, exist_ok=True)
        paths = {"markdown": folder / "results.md", "csv": folder / "results.csv",
                 "json": folder / "results.json", "findings": folder / "findings.md",
                 "findings_json": folder / "findings.json"}
        table = io.StringIO(newline="")
        writer = csv.writer(table)
        writer.writerow(["tracker", "scenario", "seed", "hota_percent", "deta", "assa",
                         "gospa_rms", "tracks", "mean_tracks_per_scan", "scans"])
        for r in sorted(self.results, key=lambda r: (r.job.tracker, r.job.scenario, r.job.seed)):
            writer.writerow([r.job.tracker, r.job.scenario, r.job.seed,
                             f"{100 * r.hota.hota:.4f}", f"{r.hota.deta:.6f}",
                             f"{r.hota.assa:.6f}", f"{r.gospa.rms:.4f}", r.track_count,
                             f"{np.mean(r.tracks_per_time):.3f}" if r.tracks_per_time else "",
                             r.scans])
        scores = [{k: ({m: i.as_dict() for m, i in v.items()} if isinstance(v, dict) else v)
                   for k, v in row.items() if k != "seconds"} for row in self.scores()]
        config = {k: (list(v) if isinstance(v, (list, tuple)) else v)
                  for k, v in asdict(self.config).items() if k != "workers"}
        findings = [f.as_dict() for f in self.findings()]
        summary = {"config": config, "scores": scores, "findings": findings,
                   "track_counts": self.track_counts()}
        write_atomic(paths["markdown"], self.markdown() + "\n")
        write_atomic(paths["csv"], table.getvalue())
        write_json(paths["json"], summary)  # (NaN, e.g. the interval of one seed: null)
        write_atomic(paths["findings"], findings_.findings_markdown(self.findings()) + "\n")
        write_json(paths["findings_json"], findings)
        return paths
