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

Ground truth is the moving vessels; tracks on static objects (sea markers, islets) are
distractors, neither hits nor false tracks (see :mod:`ctxmodels.experiment.scoring`;
``ExperimentConfig.static_distractors=False`` counts them as false tracks).
"""
from __future__ import annotations

import concurrent.futures
import contextlib
import dataclasses
import functools
import gc
import os
import time
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from . import metrics
from .executors import InlineExecutor, sigint_blocked, stop_now, worker_ignores_sigint
from .extraction import extracted
from .report import ExperimentResults, simulation_changes  # noqa: F401 (re-exported)
from .scenarios import SCENARIOS, LidarConfig, RadarConfig, make_scenario
from .scoring import score_run, tracks_digest
from .track_management import TrackManagement


@dataclass(frozen=True)
class Job:
    scenario: str
    seed: int
    tracker: str
    duration: float | None = None
    stock: bool = False
    keep_tracks: bool = False
    #: Compute :attr:`JobResult.digest` (a pass over every track state: a sixth of a whole
    #: study's CPU time, so only the reproducibility checks ask for it).
    digest: bool = False
    static_distractors: bool = True
    #: Truth models of the simulated sensors (None: the scenario defaults). The trackers'
    #: models never change with these: they are the sensitivity knobs of the simulation.
    radar: RadarConfig | None = None
    lidar: LidarConfig | None = None
    #: Which states are scored (:mod:`~ctxmodels.experiment.extraction`).
    extract: str = "stone-soup"
    #: Changes to the tracker's :class:`~ctxmodels.trackers.TrackerSpec` as
    #: ``(field, value)`` pairs (a search over its settings, e.g. ``scripts/tune_jpda.py``).
    tracker_options: tuple = ()

    def __post_init__(self):
        # checked here, where the job is made, not in a worker after its simulation
        from .extraction import EXTRACTIONS
        from ..trackers import TRACKERS
        if self.extract not in EXTRACTIONS:
            raise ValueError(f"extract: unknown extraction rule {self.extract!r}; choose from "
                             f"{list(EXTRACTIONS)}")
        if self.tracker not in TRACKERS:
            raise ValueError(f"tracker: unknown tracker {self.tracker!r}; choose from "
                             f"{list(TRACKERS)}")
        if self.tracker_options:
            fields = {f.name for f in dataclasses.fields(TRACKERS[self.tracker])}
            unknown = [name for name, _ in self.tracker_options if name not in fields]
            if unknown:
                raise ValueError(f"tracker_options: {unknown} are not TrackerSpec fields")
            dataclasses.replace(TRACKERS[self.tracker], **dict(self.tracker_options))


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
    #: digests mean bit-identical tracks. Empty unless ``job.digest``.
    digest: str = ""
    #: Tracks and vessels present at each radar time (distractors dropped), for the
    #: track-count report.
    tracks_per_time: tuple = ()
    truths_per_time: tuple = ()
    #: CPU time of the job's process while its tracker ran (``seconds`` is the wall time:
    #: more than this when the job shared a busy core). Jobs run one at a time in a process
    #: of the default pool; an executor running jobs in threads of one process counts the
    #: other threads' CPU time too.
    cpu_seconds: float = 0.0
    #: False tracks, ID switches, fragmentations, time to track (None: not scored).
    management: TrackManagement | None = None


@contextlib.contextmanager
def collector_paused():
    """Pauses Python's cyclic garbage collector, the objects alive on entry frozen out of
    its sight (nests; restores the collector's state on exit).

    No tracker makes reference cycles (tests hold every tracker to that), so a collection
    while a job runs could free nothing, yet its full passes over the growing tracks cost a
    sixth of a P_D-aware run, and once the tracking is done, the first full pass over a
    JPDA run's half a million states took a second of each job's scoring. Reference
    counting frees everything as before."""
    collecting, outermost = gc.isenabled(), gc.get_freeze_count() == 0
    gc.freeze()
    gc.disable()
    try:
        yield
    finally:
        if outermost:
            gc.unfreeze()
        if collecting:
            gc.enable()


def track_scans(tracker) -> tuple[float, int, set]:
    """Runs ``tracker`` over all its scans as a job does: ``(seconds, scans, tracks)`` — the
    tracking time, the number of scans, and every track it reported on any scan. The
    collector is paused meanwhile (see :func:`collector_paused`)."""
    with collector_paused():
        started = time.perf_counter()
        all_tracks = set()
        scans = 0
        for _, tracks in tracker:
            all_tracks |= tracks
            scans += 1
        seconds = time.perf_counter() - started
    return seconds, scans, all_tracks


def run_job(job: Job) -> JobResult:
    """Simulates the scenario, runs the tracker over both sensors' scans, scores it."""
    from ..stonesoup.ordering import in_track_order
    from ..trackers import TRACKERS
    from .trackers import build_tracker

    spec = dataclasses.replace(TRACKERS[job.tracker], **dict(job.tracker_options))
    # simulation (its objects are acyclic too), tracking, scoring and the tracks' release
    with collector_paused():
        run = simulated_run(job.scenario, job.seed, job.duration, job.radar, job.lidar)
        tracker = build_tracker(spec, run, fast=not job.stock)
        cpu_started = time.process_time()
        seconds, scans, all_tracks = track_scans(tracker)
        cpu_seconds = time.process_time() - cpu_started
        # By content, not set (address) order: the metrics then see the same track order
        # in every process.
        reported = extracted([track for track in in_track_order(all_tracks) if len(track)],
                             job.extract)
        score = score_run(run, reported, job.static_distractors)
        kept = kept_paths(reported, run.radar_times[0]) if job.keep_tracks else []
        digest = tracks_digest(reported) if job.digest else ""
        del tracker, all_tracks, reported
    return JobResult(job, score.hota, score.gospa, seconds, scans, score.track_count, kept,
                     digest, score.tracks_per_time, score.truths_per_time,
                     cpu_seconds=cpu_seconds, management=score.management)


def kept_paths(tracks, epoch) -> list:
    """Each track's path for the figures: (seconds since ``epoch``, [[x, y], ...]) lists."""
    kept = []
    seconds: dict = {}  # the tracks share their scans' timestamps
    for track in tracks:
        states = track.states
        times = []
        for state in states:
            stamp = state.timestamp
            value = seconds.get(stamp)
            if value is None:
                value = seconds[stamp] = (stamp - epoch).total_seconds()
            times.append(value)
        vectors = np.array([state.state_vector for state in states], dtype=np.float64)
        kept.append((times, vectors[:, [0, 2], 0].tolist()))
    return kept


@functools.lru_cache(maxsize=2)
def simulated_run(scenario: str, seed: int, duration, radar, lidar):
    """The run of a job's scenario (simulated, or the Solent's). A worker runs every tracker
    of a (scenario, seed) in turn (see :func:`run_experiment`'s job order), so it simulates
    each once. Trackers only read the run (the results are the same with one worker or
    several: tested)."""
    return make_scenario(scenario, seed, duration, radar=radar, lidar=lidar)


#: The full study: every scenario for its whole length (480 s), on this many seeds.
FULL_SEEDS = 10
#: ``--quick``: a smoke run of the same study, for trying things.
QUICK_SEEDS, QUICK_DURATION = 3, 60.0


@dataclass
class ExperimentConfig:
    """The study to run. The defaults are the full study: every tracker (the paper's five,
    the context-aware JPDA, and line of sight on the islands), every scenario for its whole
    length, :data:`FULL_SEEDS` seeds."""
    scenarios: Sequence[str] = ("mixed-range", "formation", "islands")
    trackers: Sequence[str] | None = None  # None: trackers.DEFAULT_TRACKERS
    seeds: Sequence[int] = tuple(range(FULL_SEEDS))
    duration: float | None = None  # None: each scenario's full length
    stock: bool = False
    workers: int | None = None
    plot_seed: int | None = 0
    static_distractors: bool = True
    radar: RadarConfig | None = None  # simulated radar (None: RadarConfig(), calibrated)
    lidar: LidarConfig | None = None  # simulated lidar (None: LidarConfig(), calibrated)
    extract: str = "stone-soup"  # which states are scored (see .extraction)

    def jobs(self) -> list[Job]:
        from ..trackers import TRACKERS
        from .trackers import DEFAULT_TRACKERS, applicable
        trackers = list(self.trackers) if self.trackers else list(DEFAULT_TRACKERS)
        for name in trackers:
            if name not in TRACKERS:
                raise ValueError(f"trackers: unknown tracker {name!r}; choose from {list(TRACKERS)}")
        for name in self.scenarios:
            if name not in SCENARIOS:
                raise ValueError(f"scenarios: unknown scenario {name!r}; choose from {list(SCENARIOS)}")
        return [Job(s, seed, t, self.duration, self.stock, keep_tracks=(seed == self.plot_seed),
                    static_distractors=self.static_distractors, radar=self.radar,
                    lidar=self.lidar, extract=self.extract)
                for s in self.scenarios for t in trackers if applicable(t, s)
                for seed in self.seeds]


def job_cost(job: Job) -> float:
    """Rough CPU seconds of a job (tracker cost scaled by the simulated duration, plus
    simulation and scoring): orders the jobs and weights the progress estimate."""
    from ..trackers import TRACKERS
    duration = job.duration or _default_duration(job.scenario)
    return (TRACKERS[job.tracker].cost + 1.0) * duration / 480.0


@functools.cache
def _default_duration(scenario: str) -> float:
    return SCENARIOS[scenario].duration


def submission_order(jobs: list[Job]) -> list[Job]:
    """Jobs grouped by simulated run (scenario, seed, sensors), the costliest group first and
    within a group the costliest job first: a worker then simulates a run once for all its
    trackers (:func:`simulated_run` keeps the last two), and the pool ends on short jobs."""
    groups: dict = {}
    for job in jobs:
        groups.setdefault((job.scenario, job.seed, job.duration, job.radar, job.lidar), []).append(job)
    ordered = sorted(groups.values(), key=lambda g: -sum(job_cost(j) for j in g))
    return [job for group in ordered for job in sorted(group, key=lambda j: -job_cost(j))]


def run_experiment(config: ExperimentConfig,
                   executor: concurrent.futures.Executor | None = None,
                   progress: bool = True) -> ExperimentResults:
    """Runs every job of ``config`` on ``executor`` (default: a process pool with
    ``config.workers`` processes) and collects the results.

    On Ctrl-C (KeyboardInterrupt) or a failed job, the queued jobs are cancelled and, with
    the default pool, the worker processes are stopped at once; the exception propagates."""
    started = time.perf_counter()
    results = run_jobs(config.jobs(), config.workers, executor, progress)
    return ExperimentResults(config, results, time.perf_counter() - started)


def run_jobs(jobs: list[Job], workers: int | None = None,
             executor: concurrent.futures.Executor | None = None,
             progress: bool = True) -> list[JobResult]:
    """Runs ``jobs`` (see :func:`run_experiment`); results in completion order."""
    own = executor is None
    # (once here, not in every worker: the Solent's first use downloads its data)
    for name in sorted({job.scenario for job in jobs} & SCENARIOS.keys()):
        SCENARIOS[name].prepare()
    if own:
        # More processes than jobs would only sit idle.
        workers = min(workers or os.cpu_count() or 1, max(len(jobs), 1))
        executor = (concurrent.futures.ProcessPoolExecutor(max_workers=workers,
                                                           initializer=worker_ignores_sigint)
                    if workers > 1 else InlineExecutor())
    results = []
    futures = []
    bar = _Progress(jobs, progress)
    try:
        order = submission_order(jobs)
        # Workers are forked while submitting: SIGINT stays blocked until each has set
        # its own handler, so a Ctrl-C in that window cannot raise inside a new worker.
        with sigint_blocked(own and isinstance(executor, concurrent.futures.ProcessPoolExecutor)):
            futures = [executor.submit(run_job, job) for job in order]
        for future in concurrent.futures.as_completed(futures):
            results.append(future.result())
            bar.done(results[-1].job)
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
    return results


class _Progress:
    """A progress bar over the jobs' estimated cost (:func:`job_cost`), so its time estimate
    holds from the first finished job although a JPDA run costs twenty radar-only runs.

    The bar counts integer milli-units of estimated cost: the total is the sum of the very
    integers the finished jobs add, so the count ends exactly on the total. (Rounding the
    total and each job's cost separately let the count overshoot it: tqdm warned "clamping
    frac to range [0, 1]" and showed a negative time left.)"""

    def __init__(self, jobs: list[Job], enabled: bool):
        self._total, self._done = len(jobs), 0
        self._bar = None
        if not enabled:
            return
        try:
            from tqdm import tqdm
        except ImportError:  # (a base dependency; an install that lost it runs without a bar)
            return
        total = sum(_progress_weight(job) for job in jobs)
        # The mean rate since the start (smoothing 0), not a moving average: the jobs finish
        # in bursts (a group's short jobs together), which would make the estimate swing.
        # (the runs count as the description: tqdm puts a comma before a postfix)
        self._bar = tqdm(total=total, unit="est-ms", smoothing=0, desc=f"0/{self._total} runs",
                         bar_format="{desc} {percentage:3.0f}%|{bar}| [{elapsed}<{remaining}]")

    def done(self, job: Job) -> None:
        self._done += 1
        if self._bar is not None:
            self._bar.set_description_str(f"{self._done}/{self._total} runs", refresh=False)
            self._bar.update(_progress_weight(job))

    def close(self) -> None:
        if self._bar is not None:
            self._bar.close()


def _progress_weight(job: Job) -> int:
    """A job's share of the progress bar: its estimated cost in integer milli-units (at
    least 1, so every finished job moves the bar)."""
    return max(1, round(1000 * job_cost(job)))
