"""Runs the paper's comparison: scenarios × trackers × seeds, scored at radar timestamps.

One *job* is one tracker on one seeded scenario; jobs are independent and run on any
:class:`concurrent.futures.Executor` (a process pool by default). A Dask or Ray executor
works unchanged, because a job is a picklable dataclass handed to a top-level function::

    from dask.distributed import Client
    results = run_experiment(config, executor=Client().get_executor())

    from ray.util.multiprocessing import Pool      # or any Executor adapter
    ...

Monte Carlo: for each tracker the per-seed scores give a mean and a 95 % interval
(Student t over seeds). *Combined* scores aggregate the scenarios of one seed as the paper
does — HOTA with TrackEval's multi-sequence aggregation, GOSPA as the RMS over all
evaluation times of all scenarios — and are then averaged over seeds.

Reported tracks are Stone Soup's own: a track is present at a radar timestamp when it has a
state at exactly that time (see :mod:`ctxmodels.experiment.trackers`).

Ground truth is the moving vessels (the paper's RTK-logged targets). Static objects — sea
markers and islets, detected by both sensors — are *distractors*, handled as MOTChallenge
evaluations handle them (TrackEval removes tracker outputs matched to distractor ground
truth before scoring): at each evaluation time, track states are assigned jointly to vessels
and static objects (Hungarian, HOTA similarity), and states assigned to a static object with
similarity ≥ 0.5 are dropped. A track on a charted marker is then neither a hit nor a false
track; without this, the paper's scores (HOTA ≈ 90 % on Scenario 1 with several markers
and islets in view) would be impossible. ``ExperimentConfig.static_distractors=False`` turns it
off (static-object tracks then count as false tracks).
"""
from __future__ import annotations

import concurrent.futures
import csv
import gc
import hashlib
import io
import json
import math
import os
import time
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np
from stonesoup.types.track import Track

from . import metrics
from .executors import (InlineExecutor, sigint_blocked, stop_now, worker_ignores_sigint,
                        write_atomic)
from .scenarios import SCENARIOS, LidarConfig, RadarConfig, make_scenario

#: Scenario names in table order, and the short labels of the results table.
SCENARIO_LABELS = {"mixed-range": "Scenario 1", "formation": "Scenario 2", "islands": "Scenario 3"}


@dataclass(frozen=True)
class Job:
    scenario: str
    seed: int
    tracker: str
    duration: float | None = None
    stock: bool = False
    keep_tracks: bool = False
    static_distractors: bool = True
    #: Truth models of the simulated sensors (None: the scenario defaults). The trackers'
    #: models never change with these: they are the sensitivity knobs of the simulation.
    radar: RadarConfig | None = None
    lidar: LidarConfig | None = None


@dataclass
class JobResult:
    job: Job
    hota: metrics.HOTAResult
    gospa: metrics.GOSPAResult
    seconds: float
    scans: int
    track_count: int
    tracks: list = field(default_factory=list)  # [(times, xy)] when job.keep_tracks
    #: SHA-256 of every reported track state (time, mean, covariance), in track order: equal
    #: digests mean bit-identical tracks.
    digest: str = ""


def drop_distractor_states(tracks, run, times, mapping=(0, 2)) -> list:
    """Tracks without the states that lie on static objects (see the module docs)."""
    from scipy.optimize import linear_sum_assignment
    statics = run.static_positions
    if not len(statics):
        return list(tracks)
    wanted = set(times)
    vessels_at: dict = {}
    for truth in run.truth_by_id.values():  # by id, not set order
        for state in truth.states:
            if state.timestamp in wanted:
                vessels_at.setdefault(state.timestamp, []).append(
                    [float(state.state_vector[mapping[0]]), float(state.state_vector[mapping[1]])])
    by_time: dict = {}
    for k, track in enumerate(tracks):
        for state in track.states:
            if state.timestamp in wanted:
                by_time.setdefault(state.timestamp, []).append((k, state))
    dropped: set = set()
    for time_, entries in by_time.items():
        points = np.array([[float(s.state_vector[mapping[0]]), float(s.state_vector[mapping[1]])]
                           for _, s in entries])
        objects = np.vstack([np.array(vessels_at.get(time_, []), dtype=float).reshape(-1, 2),
                             statics])
        n_vessels = len(objects) - len(statics)
        similarity = metrics.position_similarity(objects, points)  # (objects, tracks)
        rows, cols = linear_sum_assignment(-similarity)
        for r, c in zip(rows, cols):
            if r >= n_vessels and similarity[r, c] >= 0.5:
                dropped.add(id(entries[c][1]))
    kept = []
    for track in tracks:
        states = [s for s in track.states if id(s) not in dropped]
        if states:
            kept.append(Track(states, id=track.id))
    return kept


def track_scans(tracker) -> tuple[float, int, set]:
    """Runs ``tracker`` over all its scans as a job does: ``(seconds, scans, tracks)`` — the
    tracking time, the number of scans, and every track it reported on any scan.

    Whatever the tracker was built from (the simulated run: every scan's detections, the
    truths) stays alive and unchanged while it runs, so it is frozen out of the garbage
    collector's sight. And the collector is paused while it tracks: no tracker makes
    reference cycles (tests hold every tracker to that), so a collection could free
    nothing, yet its full passes over the growing tracks cost a sixth of a P_D-aware run.
    Reference counting frees everything as before."""
    gc.freeze()
    collecting = gc.isenabled()
    gc.disable()
    try:
        started = time.perf_counter()
        all_tracks = set()
        scans = 0
        for _, tracks in tracker:
            all_tracks |= tracks
            scans += 1
        seconds = time.perf_counter() - started
    finally:
        if collecting:
            gc.enable()
        gc.unfreeze()
    return seconds, scans, all_tracks


def run_job(job: Job) -> JobResult:
    """Simulates the scenario, runs the tracker over both sensors' scans, scores it."""
    from ..stonesoup.ordering import in_track_order
    from .trackers import TRACKERS, build_tracker

    spec = TRACKERS[job.tracker]
    run = make_scenario(job.scenario, job.seed, job.duration, radar=job.radar, lidar=job.lidar)
    tracker = build_tracker(spec, run, fast=not job.stock)
    seconds, scans, all_tracks = track_scans(tracker)
    times = run.radar_times
    # By content, not set (address) order: the metrics then see the same track order in
    # every process.
    reported = [track for track in in_track_order(all_tracks) if len(track)]
    if job.static_distractors:
        reported = drop_distractor_states(reported, run, times)
    truths = list(run.truth_by_id.values())  # by id, not set (address) order
    hota = metrics.hota(truths, reported, times)
    gospa = metrics.gospa(truths, reported, times)
    kept = []
    if job.keep_tracks:
        epoch = times[0]
        for track in reported:
            kept.append(([(s.timestamp - epoch).total_seconds() for s in track.states],
                         [[float(s.state_vector[0]), float(s.state_vector[2])]
                          for s in track.states]))
    return JobResult(job, hota, gospa, seconds, scans, len(reported), kept,
                     tracks_digest(reported))


def tracks_digest(tracks) -> str:
    """SHA-256 over the tracks' states (timestamp, state vector, covariance bytes) in the
    given order."""
    digest = hashlib.sha256()
    for track in tracks:
        digest.update(b"track")
        for state in track.states:
            digest.update(str(state.timestamp).encode())
            digest.update(np.ascontiguousarray(state.state_vector, dtype=np.float64).tobytes())
            covar = getattr(state, "covar", None)
            if covar is not None:
                digest.update(np.ascontiguousarray(covar, dtype=np.float64).tobytes())
    return digest.hexdigest()


@dataclass
class ExperimentConfig:
    scenarios: Sequence[str] = ("mixed-range", "formation", "islands")
    trackers: Sequence[str] | None = None  # None: trackers.DEFAULT_TRACKERS
    seeds: Sequence[int] = (0, 1)
    duration: float | None = 60.0
    stock: bool = False
    workers: int | None = None
    plot_seed: int | None = 0
    static_distractors: bool = True
    radar: RadarConfig | None = None  # simulated radar (None: RadarConfig())
    lidar: LidarConfig | None = None  # simulated lidar (None: LidarConfig())

    def jobs(self) -> list[Job]:
        from .trackers import DEFAULT_TRACKERS, TRACKERS, applicable
        trackers = list(self.trackers) if self.trackers else list(DEFAULT_TRACKERS)
        for name in trackers:
            if name not in TRACKERS:
                raise ValueError(f"trackers: unknown tracker {name!r}; choose from {list(TRACKERS)}")
        for name in self.scenarios:
            if name not in SCENARIOS:
                raise ValueError(f"scenarios: unknown scenario {name!r}; choose from {list(SCENARIOS)}")
        return [Job(s, seed, t, self.duration, self.stock, keep_tracks=(seed == self.plot_seed),
                    static_distractors=self.static_distractors, radar=self.radar,
                    lidar=self.lidar)
                for s in self.scenarios for t in trackers if applicable(t, s)
                for seed in self.seeds]


def simulation_changes(radar: RadarConfig | None, lidar: LidarConfig | None) -> str:
    """The simulated-sensor settings that differ from the defaults, as ``name=value`` text
    (empty when none do), so a results table always says what it was simulated with."""
    parts = []
    for prefix, config, default in (("radar", radar, RadarConfig()), ("lidar", lidar, LidarConfig())):
        if config is None:
            continue
        for name, value in asdict(config).items():
            if value != getattr(default, name):
                parts.append(f"{prefix}.{name}={value:g}" if isinstance(value, float)
                             else f"{prefix}.{name}={value}")
    return ", ".join(parts)


def _interval(values: Sequence[float]) -> tuple[float, float]:
    """Mean and half-width of the 95 % Student-t interval over seeds."""
    values = np.asarray(values, dtype=float)
    mean = float(np.mean(values))
    if len(values) < 2:
        return mean, float("nan")
    from scipy.stats import t
    half = float(t.ppf(0.975, len(values) - 1) * np.std(values, ddof=1) / math.sqrt(len(values)))
    return mean, half


@dataclass
class ExperimentResults:
    config: ExperimentConfig
    results: list[JobResult]
    wall_seconds: float

    def scores(self) -> list[dict]:
        """One row per tracker: per scenario and combined, HOTA (%) and RMS GOSPA (m) as
        mean and 95 % half-width over seeds."""
        from .trackers import TRACKERS
        by_key: dict[tuple[str, str, int], JobResult] = {
            (r.job.tracker, r.job.scenario, r.job.seed): r for r in self.results}
        trackers = [t for t in (self.config.trackers or TRACKERS) if
                    any(r.job.tracker == t for r in self.results)]
        rows = []
        for tracker in trackers:
            row = {"tracker": tracker, "label": TRACKERS[tracker].label}
            seeds = sorted({r.job.seed for r in self.results if r.job.tracker == tracker})
            scenario_names = [s for s in self.config.scenarios
                              if any(r.job.tracker == tracker and r.job.scenario == s
                                     for r in self.results)]
            for scenario in scenario_names:
                per_seed = [by_key[(tracker, scenario, s)] for s in seeds
                            if (tracker, scenario, s) in by_key]
                row[scenario] = {
                    "hota": _interval([100 * r.hota.hota for r in per_seed]),
                    "gospa": _interval([r.gospa.rms for r in per_seed]),
                }
            combined_scenarios = [s for s in scenario_names if s in ("mixed-range", "formation")]
            combined_h, combined_g = [], []
            for seed in seeds:
                parts = [by_key[(tracker, s, seed)] for s in combined_scenarios
                         if (tracker, s, seed) in by_key]
                if parts:
                    combined_h.append(100 * metrics.combine_hota([p.hota for p in parts]).hota)
                    combined_g.append(metrics.combine_gospa([p.gospa for p in parts]).rms)
            if combined_h:
                row["combined"] = {"hota": _interval(combined_h), "gospa": _interval(combined_g)}
            row["seconds"] = float(np.mean([r.seconds for r in self.results if r.job.tracker == tracker]))
            rows.append(row)
        return rows

    def table_markdown(self) -> str:
        """The results table in the layout of the paper's Table II (plus Scenario 3)."""
        rows = self.scores()
        columns = ["combined"] + [s for s in self.config.scenarios]
        names = {"combined": "Combined (S1+S2)", **SCENARIO_LABELS}
        header = "| Method | " + " | ".join(
            f"{names.get(c, c)} HOTA (%) ↑ | {names.get(c, c)} GOSPA ↓" for c in columns) + " |"
        lines = [header, "|" + "---|" * (1 + 2 * len(columns))]

        def cell(row, column, metric):
            if column not in row:
                return "—"
            mean, half = row[column][metric]
            return f"{mean:.1f}" if math.isnan(half) else f"{mean:.1f} ± {half:.1f}"

        for row in rows:
            lines.append(f"| {row['label']} | " + " | ".join(
                f"{cell(row, c, 'hota')} | {cell(row, c, 'gospa')}" for c in columns) + " |")
        seeds = ", ".join(map(str, self.config.seeds))
        lines.append("")
        lines.append(f"Mean ± 95 % interval over seeds [{seeds}]; duration "
                     f"{self.config.duration or 'default'} s per scenario; "
                     f"{'component-path' if self.config.stock else 'array'} trackers; "
                     f"wall time {self.wall_seconds:.0f} s.")
        changed = simulation_changes(self.config.radar, self.config.lidar)
        if changed:
            lines.append(f"Simulated sensors changed from the defaults: {changed}.")
        return "\n".join(lines)

    def save(self, folder: str | Path) -> dict[str, Path]:
        """Writes results.md, .csv and .json to ``folder``; each file appears complete or
        not at all (written beside its final name, then renamed)."""
        folder = Path(folder)
        folder.mkdir(parents=True, exist_ok=True)
        paths = {"markdown": folder / "results.md", "csv": folder / "results.csv",
                 "json": folder / "results.json"}
        table = io.StringIO(newline="")
        writer = csv.writer(table)
        writer.writerow(["tracker", "scenario", "seed", "hota_percent", "deta", "assa",
                         "gospa_rms", "tracks", "scans", "seconds"])
        for r in sorted(self.results, key=lambda r: (r.job.tracker, r.job.scenario, r.job.seed)):
            writer.writerow([r.job.tracker, r.job.scenario, r.job.seed,
                             f"{100 * r.hota.hota:.4f}", f"{r.hota.deta:.6f}",
                             f"{r.hota.assa:.6f}", f"{r.gospa.rms:.4f}", r.track_count,
                             r.scans, f"{r.seconds:.3f}"])
        summary = {"config": {k: (list(v) if isinstance(v, (list, tuple)) else v)
                              for k, v in asdict(self.config).items()},
                   "wall_seconds": self.wall_seconds, "scores": self.scores()}
        write_atomic(paths["markdown"], self.table_markdown() + "\n")
        write_atomic(paths["csv"], table.getvalue())
        write_atomic(paths["json"], json.dumps(summary, indent=2, default=float))
        return paths


def run_experiment(config: ExperimentConfig,
                   executor: concurrent.futures.Executor | None = None,
                   progress: bool = True) -> ExperimentResults:
    """Runs every job of ``config`` on ``executor`` (default: a process pool with
    ``config.workers`` processes) and collects the results.

    On Ctrl-C (KeyboardInterrupt) or a failed job, the queued jobs are cancelled and, with
    the default pool, the worker processes are stopped at once; the exception propagates."""
    jobs = config.jobs()
    started = time.perf_counter()
    own = executor is None
    if own:
        # More processes than jobs would only sit idle.
        workers = min(config.workers or os.cpu_count() or 1, max(len(jobs), 1))
        executor = (concurrent.futures.ProcessPoolExecutor(max_workers=workers,
                                                           initializer=worker_ignores_sigint)
                    if workers > 1 else InlineExecutor())
    results = []
    futures = []
    bar = _progress(len(jobs), progress)
    try:
        # Longest jobs first keeps the pool busy to the end.
        order = sorted(jobs, key=lambda j: (j.tracker.startswith("jpda"), j.duration or 0), reverse=True)
        # Workers are forked while submitting: SIGINT stays blocked until each has set
        # its own handler, so a Ctrl-C in that window cannot raise inside a new worker.
        with sigint_blocked(own and isinstance(executor, concurrent.futures.ProcessPoolExecutor)):
            futures = [executor.submit(run_job, job) for job in order]
        for future in concurrent.futures.as_completed(futures):
            results.append(future.result())
            bar.update(1)
    except BaseException:
        # Without this, shutdown() below would first run every queued job.
        if own:
            stop_now(executor)
        for future in futures:
            future.cancel()
        raise
    finally:
        bar.close()
        if own:
            executor.shutdown()
    return ExperimentResults(config, results, time.perf_counter() - started)


def _progress(total: int, enabled: bool):
    try:
        from tqdm import tqdm
        return tqdm(total=total, disable=not enabled, desc="runs", unit="run")
    except ImportError:  # tqdm is an optional extra
        class _Silent:
            def update(self, n):
                pass

            def close(self):
                pass
        return _Silent()
