"""The tuned JPDA's declared search (docs/jpda_baselines.md): its grid, its jobs and its
choice rule."""
from __future__ import annotations

from types import SimpleNamespace

import pytest

from ctxmodels.experiment import jpda_tuning
from ctxmodels.experiment.calibration import SEEDS
from ctxmodels.experiment.jpda_tuning import Setting, SettingResult, choose, summarise
from ctxmodels.experiment.paper import PAPER_SCENARIOS


def test_the_grid_is_the_declared_one():
    assert jpda_tuning.GRID == {"min_points": (3, 5), "confirm_window": (1.3, 2.6, 3.9),
                                "delete_window": (5.0, 10.0, 20.0)}
    assert len(jpda_tuning.settings()) == 18


def test_jobs_run_only_the_jpda_on_the_calibration_seeds_and_paper_scenarios():
    jobs = jpda_tuning.jobs()
    assert {job.tracker for job in jobs} == {"jpda"}
    assert {job.seed for job in jobs} == set(SEEDS)
    assert {job.scenario for job in jobs} == set(PAPER_SCENARIOS)
    assert len(jobs) == 18 * len(SEEDS) * len(PAPER_SCENARIOS)
    assert all(dict(job.tracker_options)["merge_duplicates"] for job in jobs)
    assert all(job.radar is None and job.lidar is None for job in jobs)  # the calibrated truth


def _result(setting, hota, gospa):
    return SettingResult(setting, hota, gospa, {})


def test_choice_is_highest_hota_then_smallest_gospa_within_a_tie_then_grid_order():
    a, b, c = Setting(3, 1.3, 5.0), Setting(3, 2.6, 5.0), Setting(5, 1.3, 5.0)
    assert choose([_result(a, 50.0, 30.0), _result(b, 60.0, 35.0)]).setting == b
    # within 0.1 point: the smaller GOSPA wins
    assert choose([_result(a, 60.0, 35.0), _result(b, 59.95, 30.0)]).setting == b
    # outside the tie: HOTA decides
    assert choose([_result(a, 60.0, 35.0), _result(b, 59.8, 30.0)]).setting == a
    # equal on both: the first in grid order
    assert choose([_result(a, 60.0, 30.0), _result(c, 60.0, 30.0)]).setting == a


def test_summary_averages_seeds_then_scenarios():
    setting = jpda_tuning.settings()[0]
    results = []
    for scenario, values in zip(PAPER_SCENARIOS, ([(0.5, 20.0), (0.7, 30.0)], [(0.2, 40.0)])):
        for hota, gospa in values:
            results.append(SimpleNamespace(
                job=SimpleNamespace(tracker_options=setting.options(), scenario=scenario),
                hota=SimpleNamespace(hota=hota), gospa=SimpleNamespace(rms=gospa)))
    # the other settings: one run each so the summary is complete
    for other in jpda_tuning.settings()[1:]:
        for scenario in PAPER_SCENARIOS:
            results.append(SimpleNamespace(
                job=SimpleNamespace(tracker_options=other.options(), scenario=scenario),
                hota=SimpleNamespace(hota=0.0), gospa=SimpleNamespace(rms=0.0)))
    first = summarise(results)[0]
    assert first.per_scenario[PAPER_SCENARIOS[0]] == pytest.approx((60.0, 25.0))
    assert first.hota == pytest.approx((60.0 + 20.0) / 2)
    assert first.gospa == pytest.approx((25.0 + 40.0) / 2)


def test_bad_search_input_is_refused_naming_the_argument():
    from ctxmodels.experiment.runner import Job
    with pytest.raises(ValueError, match="summary"):
        choose([])
    with pytest.raises(ValueError, match="results"):
        summarise([])
    with pytest.raises(ValueError, match="tracker_options"):
        Job("mixed-range", 0, "jpda", tracker_options=(("bogus", 1.0),))
    with pytest.raises(ValueError, match="delete_window"):
        Job("mixed-range", 0, "jpda", tracker_options=(("delete_window", -1.0),))
    with pytest.raises(ValueError, match="JPDA settings"):
        Job("mixed-range", 0, "gmphd-context", tracker_options=(("merge_duplicates", True),))
    with pytest.raises(ValueError, match="extract"):
        Job("mixed-range", 0, "jpda", extract="max")
