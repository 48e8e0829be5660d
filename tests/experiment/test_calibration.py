"""The calibration of the simulated truth reads the paper's baseline rows only, and does what
docs/calibration.md declares."""
import dataclasses
import math

import pytest

from ctxmodels.experiment import calibration
from ctxmodels.experiment.calibration import (RADAR_GRID, RadarPoint, StageResult, best, loss,
                                              radar_points)
from ctxmodels.experiment.paper import BASELINES, CLAIMED, PAPER_SCENARIOS, TABLE_II, Score
from ctxmodels.experiment.scenarios import RadarConfig


def paper_scores(shift=0.0):
    return {(t, s): Score(TABLE_II[t][s].hota + shift, TABLE_II[t][s].gospa - shift)
            for t in TABLE_II for s in PAPER_SCENARIOS}


def test_the_loss_is_zero_on_the_paper_and_counts_declared_units():
    assert loss(paper_scores(), BASELINES) == 0.0
    scores = paper_scores()
    scores[("gmphd-radar-only", "mixed-range")] = Score(85.6 - 5.0, 24.2 + 2.5)
    assert loss(scores, ["gmphd-radar-only"]) == pytest.approx(2.0)
    assert loss(scores, ["gmphd-uniform", "jpda"]) == 0.0


def test_claimed_rows_change_nothing_and_cannot_be_asked_for():
    scores = paper_scores(shift=3.0)
    before = {stage: loss(scores, trackers)
              for stage, trackers in calibration.STAGE_TRACKERS.items()}
    for tracker in CLAIMED:
        for scenario in PAPER_SCENARIOS:
            scores[(tracker, scenario)] = Score(-1e6, 1e6)
    for stage, trackers in calibration.STAGE_TRACKERS.items():
        assert loss(scores, trackers) == before[stage]
        assert not set(trackers) & set(CLAIMED)
    for tracker in CLAIMED:
        with pytest.raises(ValueError, match="^trackers: "):
            loss(scores, [tracker])


def test_the_choice_ignores_claimed_rows_end_to_end():
    """best() over a stage whose points carry wildly different claimed scores picks by the
    baseline rows alone."""
    points = radar_points()[:4]
    stage = []
    for i, point in enumerate(points):
        scores = paper_scores(shift=[2.0, 0.5, 1.0, 3.0][i])
        for tracker in CLAIMED:  # the claimed rows favour the point the baselines reject
            for scenario in PAPER_SCENARIOS:
                scores[(tracker, scenario)] = TABLE_II[tracker][scenario] if i == 3 else Score(0, 99)
        stage.append(StageResult(point, scores, loss(scores, calibration.STAGE_TRACKERS[1])))
    assert best(stage, RadarPoint.order).point == points[1]


def test_grid_points_become_the_declared_truth():
    assert len(radar_points()) == math.prod(len(v) for v in RADAR_GRID.values()) == 150
    point = RadarPoint(0.9, 1e-4, 1e-3, 0.5)
    radar = point.config()
    assert radar.prob_detection == 0.9
    assert radar.clutter_density_near == pytest.approx(1e-4, rel=1e-12)
    assert radar.clutter_density_far == pytest.approx(1e-3, rel=1e-12)
    assert radar.bearing_std == pytest.approx(math.radians(0.5))
    untouched = {f.name for f in dataclasses.fields(RadarConfig)} - {
        "prob_detection", "clutter_per_scan_near", "clutter_per_scan_far", "bearing_std"}
    for name in untouched:
        assert getattr(radar, name) == getattr(RadarConfig(), name), name
    assert calibration.lidar_config(0.3).clutter_per_scan == 0.3
    assert not set(calibration.SEEDS) & set(range(20)) and max(calibration.SEEDS) < 1000


def test_ties_go_to_the_smaller_probability_then_the_smaller_clutter():
    low, high = RadarPoint(0.6, 1e-4, 1e-4, 1.0), RadarPoint(0.9, 1e-5, 1e-5, 0.5)
    quiet = RadarPoint(0.6, 1e-5, 1e-5, 1.0)
    stage = [StageResult(p, {}, 1.0) for p in (high, low, quiet)]
    assert best(stage, RadarPoint.order).point == quiet


def test_a_stage_runs_real_jobs_and_scores_them():
    """One short grid point through the real runner: the seed means are the jobs' scores."""
    from ctxmodels.experiment.runner import Job, run_job
    point = RadarPoint(0.9, 1e-4, 1e-4, 1.0)
    radar, lidar = point.config(), calibration.lidar_config(1.0)
    jobs = [Job(s, seed, "gmphd-radar-only", duration=20.0, radar=radar, lidar=lidar)
            for s in PAPER_SCENARIOS for seed in (100, 101)]
    results = [run_job(job) for job in jobs]
    means = calibration.seed_means(results)
    for scenario in PAPER_SCENARIOS:
        mine = [r for r in results if r.job.scenario == scenario]
        score = means[("gmphd-radar-only", scenario)]
        assert score.hota == pytest.approx(sum(100 * r.hota.hota for r in mine) / 2)
        assert score.gospa == pytest.approx(sum(r.gospa.rms for r in mine) / 2)
        assert 0 <= score.hota <= 100 and math.isfinite(score.gospa) and score.gospa >= 0


def test_the_default_truth_is_the_calibrations_choice():
    """The scenarios' default sensors are the values docs/calibration.md's run chose (its
    committed JSON), and the stress truth is the one the docs describe."""
    import json
    from pathlib import Path

    from ctxmodels.experiment.scenarios import TRUTHS, LidarConfig
    chosen = json.loads((Path(__file__).parents[2] / "docs" / "figures" /
                         "calibration.json").read_text())["chosen"]
    point = calibration.RadarPoint(**chosen["radar"])
    assert point.config() == RadarConfig()
    assert calibration.lidar_config(chosen["lidar_clutter_per_scan"]) == LidarConfig()
    assert TRUTHS["calibrated"].radar == RadarConfig() and TRUTHS["calibrated"].lidar == LidarConfig()
    stress = TRUTHS["stress"]
    assert stress.radar.prob_detection == 0.4
    assert math.isclose(stress.radar.clutter_density_far, 1.0e-2, rel_tol=0.05)
    assert math.isclose(math.degrees(stress.radar.bearing_std), 1.0)
    assert stress.lidar.clutter_per_scan == 3.0
