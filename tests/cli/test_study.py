"""The main job end to end: ``ctxmodels experiment --quick``, identical files from two runs,
and ``ctxmodels sweep``."""
import json

import pytest

from ctxmodels.cli import main
from ctxmodels.experiment.findings import FINDINGS
from ctxmodels.experiment.runner import ExperimentConfig, submission_order
from ctxmodels.experiment.sweep import SweepConfig, run_sweep
from ctxmodels.experiment.trackers import DEFAULT_TRACKERS, applicable


def test_quick_run_end_to_end(tmp_path, capsys):
    out = tmp_path / "quick"
    assert main(["experiment", "--quick", "--workers", "2", "--quiet", "--output", str(out)]) == 0
    printed = capsys.readouterr().out
    for heading in ("## Scores", "## Findings", "## Track management", "## Tracks per radar scan"):
        assert heading in printed
    findings = json.loads((out / "findings.json").read_text())
    assert [f["key"] for f in findings] == [f.key for f in FINDINGS]
    # the Solent is not a default scenario (it downloads its data): its findings do not run
    run = [f for f in findings if f["scope"] != "solent"]
    assert {f["verdict"] for f in findings if f["scope"] == "solent"} == {"not run"}
    assert {f["verdict"] for f in run} <= {"reproduced", "not reproduced", "inconclusive",
                                           "non-inferior", "inferior"}
    assert all(f["hota_test"]["p_holm"] is not None for f in run)
    assert all(len(f["seeds"]) == 3 for f in run)
    summary = json.loads((out / "results.json").read_text())
    assert {row["tracker"] for row in summary["scores"]} == set(DEFAULT_TRACKERS)
    # One track plot per tracker and scenario, a coverage map per scenario, summaries.
    for scenario in ("mixed-range", "formation", "islands"):
        for tracker in DEFAULT_TRACKERS:
            if applicable(tracker, scenario):
                assert (out / f"tracks_{scenario}_{tracker}.png").stat().st_size > 0
        assert (out / f"coverage_{scenario}.png").stat().st_size > 0
    assert (out / "summary_combined.png").stat().st_size > 0


def test_two_runs_write_identical_files(tmp_path, capsys):
    argv = ["experiment", "--scenarios", "mixed-range", "formation", "--trackers", "gmphd-context",
            "jpda-context", "--seeds", "2", "--duration", "8", "--no-plots", "--quiet"]
    assert main([*argv, "--workers", "2", "--output", str(tmp_path / "a")]) == 0
    assert main([*argv, "--workers", "1", "--output", str(tmp_path / "b")]) == 0
    capsys.readouterr()
    names = sorted(p.name for p in (tmp_path / "a").iterdir())
    assert "findings.json" in names and "results.csv" in names
    for name in names:
        assert (tmp_path / "a" / name).read_bytes() == (tmp_path / "b" / name).read_bytes(), name


def test_jobs_are_grouped_by_simulated_run_costliest_first():
    jobs = ExperimentConfig(seeds=(0, 1), duration=30.0).jobs()
    order = submission_order(jobs)
    assert sorted(order, key=repr) == sorted(jobs, key=repr)
    groups = [(j.scenario, j.seed) for j in order]
    # Each (scenario, seed) appears as one contiguous block.
    blocks = [g for k, g in enumerate(groups) if k == 0 or groups[k - 1] != g]
    assert len(blocks) == len(set(groups)) == 6
    assert order[0].tracker == "jpda-context"  # the costliest job of the costliest group


def test_sweep_grid_and_maps(tmp_path):
    from ctxmodels.experiment.scenarios import TRUTHS, LidarConfig, RadarConfig
    from ctxmodels.experiment.sweep import Cell, calibrated_cell
    config = SweepConfig(ExperimentConfig(scenarios=("mixed-range",),
                                          trackers=("gmphd-uniform", "gmphd-radar-only"),
                                          seeds=(0, 1), duration=6.0, workers=1),
                         prob_detection=(0.4, 0.7), far_clutter=(1e-3, 3e-3),
                         bearing_std_deg=(0.5, 1.0), lidar_clutter=(0.3, 3.0))
    cells = config.cells()
    # 2 × 2 radar cells (one is the calibrated truth), bearing 1°, lidar 3, the stress truth
    assert len(cells) == 7 and len({c.sensors() for c in cells}) == 7
    assert calibrated_cell() in cells
    assert calibrated_cell().sensors() == (RadarConfig(), LidarConfig())
    assert Cell.of_truth("stress").sensors() == (TRUTHS["stress"].radar, TRUTHS["stress"].lidar)
    assert Cell.of_truth("stress") in cells
    assert len(SweepConfig(ExperimentConfig()).cells()) == 13
    assert len(SweepConfig(ExperimentConfig(), stress=False).cells()) == 12
    results = run_sweep(config, progress=False)
    xs, ys, mean, low, high = results.grids("uniform-loses-radar-only-tracks")
    assert xs == [1e-3, 3e-3] and ys == [0.4, 0.7] and mean.shape == (2, 2)
    assert (low <= mean).all() and (mean <= high).all()
    xs, _, line, _, _ = results.lidar_line("uniform-loses-radar-only-tracks")
    assert xs == [0.3, 3.0] and line.shape == (1, 2) and not any(map(lambda v: v != v, line[0]))
    xs, _, line, _, _ = results.bearing_line("uniform-loses-radar-only-tracks")
    assert xs == [0.5, 1.0] and not any(map(lambda v: v != v, line[0]))
    # Findings whose trackers did not run have no map.
    assert (results.grids("context-beats-jpda")[2] != results.grids("context-beats-jpda")[2]).all()
    paths = results.save(tmp_path)
    for name in ("radar", "bearing", "lidar"):
        assert (tmp_path / f"sweep_uniform-loses-radar-only-tracks_{name}.png").stat().st_size > 0
    assert not (tmp_path / "sweep_context-beats-jpda_radar.png").exists()
    rows = json.loads(paths["json"].read_text())["cells"]
    assert {(r["truth"], r["prob_detection"], r["lidar_clutter"]) for r in rows if r["key"] ==
            "uniform-loses-radar-only-tracks"} == {("calibrated", 0.4, 0.3),
                                                   ("calibrated", 0.7, 0.3),
                                                   ("calibrated", 0.7, 3.0), ("stress", 0.4, 3.0)}
    assert "| stress | 0.4 |" in paths["markdown"].read_text()


@pytest.mark.parametrize("change, argument", [
    (dict(prob_detection=1.5), "prob_detection"), (dict(prob_detection=0.0), "prob_detection"),
    (dict(far_clutter=-1e-3), "far_clutter"), (dict(lidar_clutter=float("nan")), "lidar_clutter"),
    (dict(bearing_std_deg=0.0), "bearing_std_deg"), (dict(truth="calm"), "truth")])
def test_sweep_cells_refuse_bad_settings_naming_them(change, argument):
    from ctxmodels.experiment.sweep import Cell
    values = dict(prob_detection=0.7, far_clutter=3e-3, bearing_std_deg=0.5, lidar_clutter=0.3)
    with pytest.raises(ValueError, match=argument):
        Cell(**{**values, **change})


@pytest.mark.parametrize("argv, option", [
    (["--radar-bearing-std", "0"], "--radar-bearing-std"),
    (["--radar-far-clutter", "-1"], "--radar-far-clutter"),
    (["--radar-far-clutter", "1"], "--radar-far-clutter"),
    (["--radar-pd", "0"], "--radar-pd"),
    (["--radar-pd", "1.5"], "--radar-pd"),
    (["--lidar-clutter", "1e9"], "--lidar-clutter"),
    (["--seeds", "0"], "--seeds"),
    (["--duration", "1e6"], "--duration"),
])
def test_sweep_usage_errors_exit_2_before_any_work(argv, option, tmp_path, capsys, monkeypatch):
    import ctxmodels.experiment.sweep as sweep
    monkeypatch.setattr(sweep, "run_jobs", lambda *a, **k: pytest.fail("work started"))
    with pytest.raises(SystemExit) as exit_:
        main(["sweep", *argv, "--output", str(tmp_path / "out")])
    assert exit_.value.code == 2
    err = capsys.readouterr().err
    assert option in err and len(err.strip().splitlines()[-1]) > 0
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("command", ["experiment", "sweep"])
def test_help_prints_its_text_as_written(command, capsys):
    # argparse formats only argument help with %: a "%%" in a description prints as is
    with pytest.raises(SystemExit) as exit_:
        main([command, "--help"])
    assert exit_.value.code == 0
    out = " ".join(capsys.readouterr().out.split())
    assert "95 % " in out and "%%" not in out
