r"""The simulated truth calibrated against the paper's baseline rows (``docs/calibration.md``
states the procedure; this module is that procedure, nothing more).

For a grid point :math:`\theta` of truth parameters, each baseline tracker :math:`b` runs on
the paper's two scenarios :math:`s` on the calibration seeds; :math:`\bar H_{b,s}` and
:math:`\bar G_{b,s}` are its mean HOTA (%) and RMS GOSPA (m) over the seeds, and

.. math::
    L(\theta) = \sum_b \sum_s \Bigl(\frac{\bar H_{b,s}(\theta) - H^*_{b,s}}{5}\Bigr)^2
              + \Bigl(\frac{\bar G_{b,s}(\theta) - G^*_{b,s}}{2.5}\Bigr)^2

against Table II's :math:`H^*, G^*` (:data:`~ctxmodels.experiment.paper.TABLE_II`). Stage 1
fixes the radar's truth on the radar-only GM-PHD's rows, stage 2 the lidar's clutter rate on
the uniform GM-PHD's and the JPDA's, with the radar at stage 1's choice. :func:`loss` reads
the baseline rows only and refuses any other.
"""
from __future__ import annotations

import dataclasses
import itertools
import math
from collections.abc import Iterable, Mapping, Sequence

import numpy as np

from .paper import BASELINES, PAPER_SCENARIOS, TABLE_II, Score
from .scenarios import LidarConfig, RadarConfig

#: Stage 1's grid: radar P_D of every object; clutter per rad·m below and beyond 1000 m;
#: bearing σ in degrees.
RADAR_GRID = {
    "prob_detection": (0.6, 0.7, 0.8, 0.9, 0.95),
    "clutter_near": (1e-5, 1e-4, 1e-3),
    "clutter_far": (1e-5, 1e-4, 3e-4, 1e-3, 3e-3),
    "bearing_std_deg": (0.5, 1.0),
}
#: Stage 2's grid: lidar clutter points per scan.
LIDAR_GRID = (0.1, 0.3, 1.0, 3.0, 10.0)
#: The calibration seeds (never used by the study's development, nor by its reported runs).
SEEDS = (100, 101, 102)
#: A misfit of this much HOTA (points) or GOSPA (m) counts one unit of loss.
HOTA_SCALE, GOSPA_SCALE = 5.0, 2.5
#: The baseline trackers whose rows each stage reads.
STAGE_TRACKERS = {1: ("gmphd-radar-only",), 2: ("gmphd-uniform", "jpda")}


@dataclasses.dataclass(frozen=True)
class RadarPoint:
    """A point of stage 1's grid (see :data:`RADAR_GRID`)."""

    prob_detection: float
    clutter_near: float
    clutter_far: float
    bearing_std_deg: float

    def config(self, base: RadarConfig = RadarConfig()) -> RadarConfig:
        """The simulated radar with these values: densities per rad·m become Poisson means
        per scan over the covered arc of each range band."""
        arc = base.covered_bearing_extent
        near = self.clutter_near * arc * (base.clutter_boundary_range - base.min_range)
        far = self.clutter_far * arc * (base.max_range - base.clutter_boundary_range)
        return dataclasses.replace(base, prob_detection=self.prob_detection,
                                   clutter_per_scan_near=near, clutter_per_scan_far=far,
                                   bearing_std=math.radians(self.bearing_std_deg))

    def order(self) -> tuple:
        """The declared tie-break: the smaller P_D, then the smaller clutter."""
        return (self.prob_detection, self.clutter_near + self.clutter_far, self.clutter_far,
                self.bearing_std_deg)


def radar_points() -> list[RadarPoint]:
    return [RadarPoint(*values) for values in itertools.product(*RADAR_GRID.values())]


def lidar_config(clutter_per_scan: float, base: LidarConfig = LidarConfig()) -> LidarConfig:
    return dataclasses.replace(base, clutter_per_scan=clutter_per_scan)


def loss(scores: Mapping[tuple[str, str], Score], trackers: Sequence[str]) -> float:
    r""":math:`L` over ``trackers`` (baseline rows only) and the paper's two scenarios, from
    ``scores[(tracker, scenario)]`` (mean HOTA %, mean RMS GOSPA m). Nothing else in
    ``scores`` is read."""
    total = 0.0
    for tracker in trackers:
        if tracker not in BASELINES:
            raise ValueError(f"trackers: {tracker!r} is not a baseline row of Table II; the "
                             f"calibration reads only {BASELINES}")
        for scenario in PAPER_SCENARIOS:
            score, paper = scores[(tracker, scenario)], TABLE_II[tracker][scenario]
            total += ((score.hota - paper.hota) / HOTA_SCALE) ** 2 \
                + ((score.gospa - paper.gospa) / GOSPA_SCALE) ** 2
    return total


def seed_means(results: Iterable) -> dict[tuple[str, str], Score]:
    """Mean HOTA (%) and RMS GOSPA (m) over the seeds, per (tracker, scenario), of job
    results (:class:`~ctxmodels.experiment.runner.JobResult`)."""
    groups: dict[tuple[str, str], list] = {}
    for result in results:
        groups.setdefault((result.job.tracker, result.job.scenario), []).append(result)
    return {key: Score(float(np.mean([100 * r.hota.hota for r in group])),
                       float(np.mean([r.gospa.rms for r in group])))
            for key, group in sorted(groups.items())}


def stage_jobs(trackers: Sequence[str], radar: RadarConfig, lidar: LidarConfig,
               seeds: Sequence[int] = SEEDS) -> list:
    from .runner import Job
    return [Job(scenario, seed, tracker, radar=radar, lidar=lidar)
            for tracker in trackers for scenario in PAPER_SCENARIOS for seed in seeds]


@dataclasses.dataclass
class StageResult:
    """One grid point: its parameters, its baseline rows' seed means and its loss."""

    point: object
    scores: dict
    loss: float


def run_stage(points: Sequence, configs, trackers: Sequence[str], workers: int | None = None,
              seeds: Sequence[int] = SEEDS, progress: bool = True) -> list[StageResult]:
    """Runs ``trackers`` at every grid point (``configs(point)`` gives its (radar, lidar))
    in one pool; the points' results in grid order."""
    from .runner import run_jobs
    jobs = {point: stage_jobs(trackers, *configs(point), seeds) for point in points}
    results = run_jobs([job for batch in jobs.values() for job in batch], workers,
                       progress=progress)
    by_truth: dict = {}
    for result in results:
        by_truth.setdefault((result.job.radar, result.job.lidar), []).append(result)
    stage = []
    for point in points:
        scores = seed_means(by_truth[configs(point)])
        stage.append(StageResult(point, scores, loss(scores, trackers)))
    return stage


def best(stage: Sequence[StageResult], order=lambda point: point) -> StageResult:
    """The grid point of least loss (ties by ``order``, the declared tie-break)."""
    return min(stage, key=lambda r: (r.loss, order(r.point)))


@dataclasses.dataclass
class Calibration:
    radar_stage: list[StageResult]
    radar: RadarPoint
    lidar_stage: list[StageResult]
    lidar_clutter: float
    seeds: tuple

    def truth(self) -> tuple[RadarConfig, LidarConfig]:
        return self.radar.config(), lidar_config(self.lidar_clutter)


def calibrate(workers: int | None = None, seeds: Sequence[int] = SEEDS,
              progress: bool = True) -> Calibration:
    """Both stages, as ``docs/calibration.md`` declares them."""
    lidar = LidarConfig()
    radar_stage = run_stage(radar_points(), lambda p: (p.config(), lidar), STAGE_TRACKERS[1],
                            workers, seeds, progress)
    radar = best(radar_stage, RadarPoint.order).point
    lidar_stage = run_stage(list(LIDAR_GRID), lambda n: (radar.config(), lidar_config(n)),
                            STAGE_TRACKERS[2], workers, seeds, progress)
    return Calibration(radar_stage, radar, lidar_stage, best(lidar_stage).point, tuple(seeds))


def near_best(stage: Sequence[StageResult], margin: float = 2.0) -> list[StageResult]:
    """The grid points within ``margin`` units of the least loss, best first."""
    least = min(r.loss for r in stage)
    return sorted((r for r in stage if r.loss <= least + margin), key=lambda r: r.loss)


def as_json(calibration: Calibration) -> dict:
    """What ``scripts/calibrate.py`` writes: the choice, every grid point's rows and loss."""
    def rows(stage):
        return [{"point": dataclasses.asdict(r.point) if dataclasses.is_dataclass(r.point)
                 else {"lidar_clutter_per_scan": r.point},
                 "loss": r.loss,
                 "scores": {f"{t}/{s}": score._asdict() for (t, s), score in r.scores.items()}}
                for r in stage]
    radar, lidar = calibration.truth()
    return {"seeds": list(calibration.seeds),
            "chosen": {"radar": dataclasses.asdict(calibration.radar),
                       "lidar_clutter_per_scan": calibration.lidar_clutter,
                       "radar_clutter_per_scan": [radar.clutter_per_scan_near,
                                                  radar.clutter_per_scan_far]},
            "paper": {t: {s: TABLE_II[t][s]._asdict() for s in PAPER_SCENARIOS}
                      for t in BASELINES},
            "stage1": rows(calibration.radar_stage), "stage2": rows(calibration.lidar_stage)}


__all__ = ["Calibration", "LIDAR_GRID", "RADAR_GRID", "RadarPoint", "SEEDS", "StageResult",
           "as_json", "best", "calibrate", "lidar_config", "loss", "near_best", "radar_points",
           "run_stage", "seed_means"]
