"""The experiment's results: score table, findings, track counts, and the files they go to.

Per tracker and scope the score is the mean over seeds with its percentile-bootstrap 95 %
interval (:func:`~.statistics.bootstrap_mean`); findings compare trackers paired by seed
(:mod:`~.findings`). Every number written depends only on the jobs' results, never on
their completion order: no timing goes into the files (two runs write identical files),
it is printed (:meth:`ExperimentResults.timing_line`).

Beside the scores, a track-management table (:meth:`ExperimentResults.management`) breaks
them down per tracker and scope: HOTA's DetA, AssA and LocA, GOSPA's localisation, missed
and false terms (:func:`~.metrics.gospa_split`), and the track-management metrics of
:mod:`~.track_management`. A scope's runs of one seed are pooled first (HOTA, GOSPA and
track management each by its own combine: ratios of sums), then the seeds are averaged.
"""
from __future__ import annotations

import csv
import io
import math
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from . import findings as findings_
from . import metrics
from . import track_management as management_
from .metrics import GOSPA_C
from .scenarios import SOLENT
from .solent.scene import DISTANCE_SCALE as SOLENT_SCALE
from .executors import write_atomic, write_json
from .findings import COMBINED, COMBINED_SCENARIOS, seed_scores
from .paper import paper_row
from .statistics import bootstrap_mean

#: Scenario names in table order, and the short labels of the results table.
SCENARIO_LABELS = {"mixed-range": "Scenario 1", "formation": "Scenario 2", "islands": "Scenario 3",
                   SOLENT: "Scenario 4 (Solent)"}

#: The track-management table's columns: key, markdown header, format.
MANAGEMENT_COLUMNS = (
    ("deta", "DetA (%)", ".1f"), ("assa", "AssA (%)", ".1f"), ("loca", "LocA (%)", ".1f"),
    ("gospa_localisation", "GOSPA² loc. (m²)", ".1f"),
    ("gospa_missed", "GOSPA² missed (m²)", ".1f"), ("gospa_false", "GOSPA² false (m²)", ".1f"),
    ("false_tracks_per_scan", "false tracks / scan", ".2f"),
    ("false_tracks", "false tracks", ".1f"),
    ("false_track_lifetime", "false-track life (s)", ".1f"),
    ("id_switches", "ID switches", ".1f"), ("fragmentations", "fragmentations", ".1f"),
    ("tracked_percent", "tracked (%)", ".1f"), ("time_to_track", "time to track (s)", ".1f"),
    ("never_tracked", "never tracked", ".1f"))


def _scope_runs(by_key: dict, tracker: str, scope: str) -> dict[int, list]:
    """``{seed: [JobResult, ...]}``: the runs of ``tracker`` that make up ``scope`` on each
    seed (seeds missing a scenario of the combined scope are left out, as in the scores)."""
    scenarios = COMBINED_SCENARIOS if scope == COMBINED else (scope,)
    seeds = sorted({seed for (t, _, seed) in by_key if t == tracker})
    runs = {seed: [by_key.get((tracker, s, seed)) for s in scenarios] for seed in seeds}
    return {seed: parts for seed, parts in runs.items()
            if all(p is not None and p.management is not None for p in parts)}


def management_values(parts: list) -> dict[str, float]:
    """The track-management table's values of runs pooled as one (one seed of a scope)."""
    hota = metrics.combine_hota([p.hota for p in parts])
    localisation, missed, false = metrics.gospa_split(
        metrics.combine_gospa([p.gospa for p in parts]))
    pooled = management_.combine([p.management for p in parts])
    return {"deta": 100 * hota.deta, "assa": 100 * hota.assa, "loca": 100 * hota.loca,
            "gospa_localisation": localisation, "gospa_missed": missed, "gospa_false": false,
            "false_tracks_per_scan": pooled.false_tracks_per_scan,
            "false_tracks": float(pooled.false_tracks),
            "false_track_lifetime": pooled.false_track_lifetime,
            "id_switches": float(pooled.id_switches),
            "fragmentations": float(pooled.fragmentations),
            "tracked_percent": 100 * pooled.tracked_fraction,
            "time_to_track": pooled.time_to_track,
            "never_tracked": float(pooled.never_tracked)}


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


#: The README's study table lies between these two lines (``scripts/readme_table.py``).
README_MARKERS = ("<!-- study-table: generated by scripts/readme_table.py; do not edit -->",
                  "<!-- study-table: end -->")


def readme_table(summary: dict) -> str:
    """The README's study table from a saved ``results.json`` (``summary``): per tracker,
    combined and per-scenario HOTA and GOSPA (mean over seeds) with the paper's Table II
    value in parentheses, and the seeds it came from."""
    names = {COMBINED: "S1+S2", "mixed-range": "S1", "formation": "S2"}
    scopes = [scope for scope in names if any(scope in row for row in summary["scores"])]
    lines = ["| Method | " + " | ".join(f"{names[s]} HOTA (%) ↑ | {names[s]} GOSPA (m) ↓"
                                      for s in scopes) + " |",
             "|---|" + "---|" * (2 * len(scopes))]
    for row in summary["scores"]:
        if not any(scope in row for scope in scopes):
            continue
        cells = []
        for scope in scopes:
            for metric in ("hota", "gospa"):
                if scope not in row:
                    cells.append("—")
                    continue
                paper = row.get("paper", {}).get(scope)
                cells.append(f"{row[scope][metric]['mean']:.1f}"
                             + (f" ({paper[metric]:.1f})" if paper else ""))
        lines.append(f"| {row['label']} | " + " | ".join(cells) + " |")
    seeds = summary["config"]["seeds"]
    lines += ["", f"Mean over {len(seeds)} seeds ({seeds[0]}–{seeds[-1]}); in parentheses "
              "the paper's Table II (recorded data)."]
    return "\n".join([README_MARKERS[0], *lines, README_MARKERS[1]])


@dataclass
class ExperimentResults:
    config: object  # ExperimentConfig
    results: list  # [JobResult]
    wall_seconds: float

    def by_key(self) -> dict:
        return {(r.job.tracker, r.job.scenario, r.job.seed): r for r in self.results}

    def trackers(self) -> list[str]:
        from ..trackers import TRACKERS
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
        from ..trackers import TRACKERS
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
            paper = paper_row(tracker)
            row["paper"] = {scope: paper[scope]._asdict() for scope in self.scopes()
                            if scope in paper}
            row["seconds"] = float(np.mean([r.seconds for r in self.results if r.job.tracker == tracker]))
            rows.append(row)
        return rows

    def findings(self) -> list:
        return findings_.evaluate_all(self.by_key())

    def management(self) -> list[dict]:
        """Per tracker and scope (as in the scores): each track-management column
        (:data:`MANAGEMENT_COLUMNS`) as the mean over seeds of the seed's pooled runs, and
        the number of seeds."""
        from ..trackers import TRACKERS
        by_key = self.by_key()
        rows = []
        for tracker in self.trackers():
            for scope in self.scopes():
                per_seed = [management_values(parts)
                            for parts in _scope_runs(by_key, tracker, scope).values()]
                if not per_seed:
                    continue
                means = {key: float(np.mean([values[key] for values in per_seed]))
                         for key, _, _ in MANAGEMENT_COLUMNS}
                rows.append({"tracker": tracker, "label": TRACKERS[tracker].label,
                             "scope": scope, "seeds": len(per_seed), **means})
        return rows

    def management_markdown(self) -> str:
        names = {COMBINED: "Combined (S1+S2)", **SCENARIO_LABELS}
        lines = ["| Method | Scope | " + " | ".join(h for _, h, _ in MANAGEMENT_COLUMNS) + " |",
                 "|---|---|" + "---|" * len(MANAGEMENT_COLUMNS)]
        for row in self.management():
            lines.append(f"| {row['label']} | {names.get(row['scope'], row['scope'])} | "
                         + " | ".join(format(row[key], spec)
                                      for key, _, spec in MANAGEMENT_COLUMNS) + " |")
        lines += ["", "Mean over seeds; a scope's runs of one seed are pooled first (counts summed over its "
                  "scenarios, rates as ratios of sums). Truths and tracks are matched by GOSPA's assignment"
                  f" (c = {GOSPA_C:g} m; {GOSPA_C * SOLENT_SCALE:g} m on the Solent) at each radar time, "
                  "static-object tracks dropped. "
                  "GOSPA's terms are the means over radar times of the parts of the squared GOSPA: they add"
                  " up to the mean over seeds of RMS GOSPA². False tracks are never matched; their life "
                  "runs from first to last radar time; time to track runs from a vessel's first radar time "
                  "to its first match (never-tracked vessels count their whole presence)."]
        return "\n".join(lines)

    def track_counts(self) -> list[dict]:
        """Per tracker and scenario: tracks reported per radar scan (mean over scans and
        seeds, and the largest), beside the vessels present per scan."""
        from ..trackers import TRACKERS
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
            f"{names.get(c, c)} HOTA (%) ↑ (paper) | {names.get(c, c)} GOSPA (m) ↓ (paper)"
            for c in columns) + " |"
        lines = [header, "|" + "---|" * (1 + 2 * len(columns))]

        def cell(row, column, metric):
            if column not in row:
                return "—"
            value = row[column][metric]
            paper = row["paper"].get(column)
            text = (f"{value.mean:.1f}" if math.isnan(value.low)
                    else f"{value.mean:.1f} [{value.low:.1f}, {value.high:.1f}]")
            return text + (f" ({paper[metric]:.1f})" if paper else "")

        for row in rows:
            lines.append(f"| {row['label']} | " + " | ".join(
                f"{cell(row, c, 'hota')} | {cell(row, c, 'gospa')}" for c in columns) + " |")
        seeds = self.config.seeds
        lines.append("")
        lines.append(f"Mean [95 % percentile-bootstrap interval] over {len(seeds)} seeds "
                     f"({seeds[0]}–{seeds[-1]}); "
                     f"{f'{self.config.duration:g} s' if self.config.duration else 'the whole'} "
                     f"of each scenario; "
                     f"{'component-path' if self.config.stock else 'array'} trackers. "
                     "In parentheses: the paper's Table II on its recorded data.")
        if any(s != SOLENT for s in self.config.scenarios):
            lines.append("Simulated: the sensors, clutter and scenes (hand-built after the "
                         "paper's descriptions; its paths are not public). Calibrated: the "
                         "radar's P_D, clutter and bearing σ and the lidar's clutter rate, on "
                         "the paper's baseline rows only (docs/calibration.md). Not reproduced "
                         "by any calibrated setting: the baselines' absolute scores "
                         "(docs/calibration.md says why), so compare differences, not levels.")
        if SOLENT in self.config.scenarios:
            lines.append("Scenario 4 (Solent): real coast (GSHHG) and real vessels (AIS, 12 "
                         "January 2016) with two simulated radars at real sites, the "
                         "calibrated radar's P_D, noise and false alarms a scan "
                         f"(ctxmodels.experiment.solent); distances in its scores × "
                         f"{SOLENT_SCALE:g} (c = {GOSPA_C * SOLENT_SCALE:g} m). The paper has no "
                         f"such scene: its rows are its own scenarios'.")
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
            "## Track management", self.management_markdown(),
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
        # (new columns go last: readers by position keep working)
        writer.writerow(["tracker", "scenario", "seed", "hota_percent", "deta", "assa",
                         "gospa_rms", "tracks", "mean_tracks_per_scan", "scans", *_CSV_EXTRA])
        for r in sorted(self.results, key=lambda r: (r.job.tracker, r.job.scenario, r.job.seed)):
            writer.writerow([r.job.tracker, r.job.scenario, r.job.seed,
                             f"{100 * r.hota.hota:.4f}", f"{r.hota.deta:.6f}",
                             f"{r.hota.assa:.6f}", f"{r.gospa.rms:.4f}", r.track_count,
                             f"{np.mean(r.tracks_per_time):.3f}" if r.tracks_per_time else "",
                             r.scans, *_csv_extra(r)])
        scores = [{k: ({m: i.as_dict() for m, i in v.items()}
                       if isinstance(v, dict) and k != "paper" else v)
                   for k, v in row.items() if k != "seconds"} for row in self.scores()]
        config = {k: (list(v) if isinstance(v, (list, tuple)) else v)
                  for k, v in asdict(self.config).items() if k != "workers"}
        findings = [f.as_dict() for f in self.findings()]
        summary = {"config": config, "scores": scores, "findings": findings,
                   "management": self.management(), "track_counts": self.track_counts()}
        write_atomic(paths["markdown"], self.markdown() + "\n")
        write_atomic(paths["csv"], table.getvalue())
        write_json(paths["json"], summary)  # (NaN, e.g. the interval of one seed: null)
        write_atomic(paths["findings"], findings_.findings_markdown(self.findings()) + "\n")
        write_json(paths["findings_json"], findings)
        return paths


#: results.csv's per-run track-management columns.
_CSV_EXTRA = ("loca", "gospa_localisation", "gospa_missed", "gospa_false",
              "false_tracks_per_scan", "false_tracks", "false_track_lifetime", "id_switches",
              "fragmentations", "tracked_fraction", "time_to_track", "never_tracked")


def _csv_extra(result) -> list[str]:
    """A run's :data:`_CSV_EXTRA` cells (empty when it has no track-management metrics)."""
    if result.management is None:
        return [""] * len(_CSV_EXTRA)
    localisation, missed, false = metrics.gospa_split(result.gospa)
    m = result.management
    return [f"{result.hota.loca:.6f}", f"{localisation:.4f}", f"{missed:.4f}", f"{false:.4f}",
            f"{m.false_tracks_per_scan:.4f}", str(m.false_tracks),
            f"{m.false_track_lifetime:.4f}", str(m.id_switches), str(m.fragmentations),
            f"{m.tracked_fraction:.6f}", f"{m.time_to_track:.4f}", str(m.never_tracked)]
