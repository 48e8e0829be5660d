r"""The tuned JPDA's search (``docs/jpda_baselines.md`` declares it; this module is that
search, nothing more).

Each setting :math:`(M, T_\mathrm{init}, T_\mathrm{del})` of :data:`GRID` runs the JPDA with
windows in time and duplicate merging (``TrackerSpec.confirm_window``, ``delete_window``,
``merge_duplicates``) on the paper's two scenarios, on the calibration seeds, at the
calibrated truth. Its objective is the tracker's own performance: the mean over the
scenarios of the mean HOTA over the seeds, higher better; ties within :data:`TIE` points go
to the smaller mean RMS GOSPA, then to the earlier setting in grid order. Only the JPDA
runs: no claimed row enters.
"""
from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .calibration import SEEDS
from .paper import PAPER_SCENARIOS

#: min. detections to confirm; holding-track window (s); track deletion window (s).
GRID = {"min_points": (3, 5), "confirm_window": (1.3, 2.6, 3.9),
        "delete_window": (5.0, 10.0, 20.0)}
#: HOTA points within which two settings tie.
TIE = 0.1


@dataclass(frozen=True)
class Setting:
    min_points: int
    confirm_window: float
    delete_window: float

    def options(self) -> tuple:
        """The ``Job.tracker_options`` that make ``jpda`` this setting."""
        return (("min_points", self.min_points), ("confirm_window", self.confirm_window),
                ("delete_window", self.delete_window), ("merge_duplicates", True))


@dataclass
class SettingResult:
    setting: Setting
    hota: float  # mean over scenarios of the seeds' mean HOTA (%)
    gospa: float  # mean over scenarios of the seeds' mean RMS GOSPA (m)
    per_scenario: dict  # scenario -> (HOTA, GOSPA)


def settings() -> list[Setting]:
    return [Setting(*values) for values in itertools.product(*GRID.values())]


def jobs(seeds: Sequence[int] = SEEDS) -> list:
    from .runner import Job
    return [Job(scenario, seed, "jpda", tracker_options=setting.options())
            for setting in settings() for scenario in PAPER_SCENARIOS for seed in seeds]


def summarise(results: Sequence) -> list[SettingResult]:
    """Each setting's objective from the job results, in grid order."""
    by_setting: dict = {}
    for result in results:
        by_setting.setdefault(result.job.tracker_options, {}).setdefault(
            result.job.scenario, []).append(result)
    out = []
    for setting in settings():
        runs = by_setting.get(setting.options(), {})
        if set(runs) != set(PAPER_SCENARIOS):
            raise ValueError(f"results: setting {setting} has no runs on "
                             f"{sorted(set(PAPER_SCENARIOS) - set(runs))}")
        per = {s: (float(np.mean([100 * r.hota.hota for r in runs[s]])),
                   float(np.mean([r.gospa.rms for r in runs[s]]))) for s in PAPER_SCENARIOS}
        out.append(SettingResult(setting, float(np.mean([h for h, _ in per.values()])),
                                 float(np.mean([g for _, g in per.values()])), per))
    return out


def choose(summary: Sequence[SettingResult]) -> SettingResult:
    """The declared choice: the highest HOTA; within :data:`TIE` of it, the smallest GOSPA,
    then the first in grid order."""
    if not summary:
        raise ValueError("summary: no settings to choose from")
    best = max(r.hota for r in summary)
    tied = [r for r in summary if r.hota >= best - TIE]
    return min(tied, key=lambda r: r.gospa)  # (min keeps the first of equal GOSPAs)


def search(workers: int | None = None, seeds: Sequence[int] = SEEDS,
           progress: bool = True) -> list[SettingResult]:
    from .runner import run_jobs
    return summarise(run_jobs(jobs(seeds), workers, progress=progress))


__all__ = ["GRID", "Setting", "SettingResult", "TIE", "choose", "jobs", "search", "settings",
           "summarise"]
