"""End to end: the experiment runner, its outputs and the CLI, on short runs."""
import json
import math

import numpy as np
import pytest

from ctxmodels.cli import main
from ctxmodels.experiment.runner import ExperimentConfig, Job, run_experiment, run_job
from ctxmodels.experiment.scenarios import make_scenario
from ctxmodels.experiment.scoring import score_run
from ctxmodels.experiment.sensors import paper_sensor_models
from ctxmodels.experiment.trackers import applicable, build_tracker
from ctxmodels.trackers import TRACKERS
from ctxmodels.stonesoup.ordering import in_track_order


def test_every_tracker_builds_and_runs_a_few_scans():
    run = make_scenario("islands", 0, 3.0)
    for name, spec in TRACKERS.items():
        tracker = build_tracker(spec, run, fast=True)
        scans = sum(1 for _ in tracker)
        expected = len(run.radar_scans) + (0 if spec.primary_only else len(run.lidar_scans))
        assert scans == expected, name


@pytest.mark.parametrize("scenario", ["mixed-range", "formation", "islands"])
def test_simulation_and_scoring_make_no_reference_cycles(scenario):
    """run_job also simulates and scores with the collector paused."""
    import gc
    gc.collect()
    gc.disable()
    try:
        run = make_scenario(scenario, 2, 20.0)
        tracks = set()
        for _, scan_tracks in build_tracker(TRACKERS["gmphd-context"], run, fast=True):
            tracks |= scan_tracks
        gc.collect()  # (the tracker is checked below; here the scoring is)
        score = score_run(run, [t for t in in_track_order(tracks) if len(t)])
        assert len(run.radar_scans) and score.hota.hota >= 0.0
        del run, tracks, scan_tracks, score
        unreachable = gc.collect()
    finally:
        gc.enable()
    assert unreachable == 0


@pytest.mark.parametrize("scenario", ["mixed-range", "formation", "islands"])
def test_no_tracker_makes_reference_cycles(scenario):
    """run_job pauses the cyclic garbage collector while a tracker runs; that is only free
    of cost if tracking leaves nothing for it: after a run with the collector off, no
    unreachable object may remain, on either path."""
    import gc
    for name, spec in TRACKERS.items():
        if not applicable(name, scenario):
            continue
        for fast in (True, False):
            run = make_scenario(scenario, 1, 6.0)
            tracker = build_tracker(spec, run, fast=fast)
            gc.collect()
            gc.disable()
            try:
                tracks = set()
                for _, scan_tracks in tracker:
                    tracks |= scan_tracks
                del tracker, tracks, scan_tracks
                unreachable = gc.collect()
            finally:
                gc.enable()
            assert unreachable == 0, (name, fast, unreachable)


def test_line_of_sight_tracker_only_on_islands():
    assert applicable("gmphd-sight", "islands")
    assert not applicable("gmphd-sight", "mixed-range")
    jobs = ExperimentConfig(scenarios=("mixed-range",), seeds=(0,)).jobs()
    assert not any(job.tracker == "gmphd-sight" for job in jobs)


def test_context_models_follow_the_paper():
    models = paper_sensor_models()
    radar = models["radar"].context((0.0, 0.0, 0.0))
    lidar = models["lidar"].context((0.0, 0.0, 0.0))
    states = np.array([[30.0, 0, 0, 0], [60.0, 0, 0, 0], [500.0, 0, 0, 0], [-500.0, 0, 0, 0]])
    assert radar.prob_detection_array(states).tolist() == [0.0, 0.4, 0.4, 0.0]
    assert lidar.prob_detection_array(states).tolist() == [0.95, 0.2, 0.0, 0.0]


def test_job_is_deterministic_and_scores_are_sane():
    job = Job("mixed-range", 3, "gmphd-context", duration=20.0, digest=True)
    first, second = run_job(job), run_job(job)
    # bit for bit: nothing iterates a set of detections, tracks or tags in address order
    assert first.hota.hota == second.hota.hota and first.gospa.rms == second.gospa.rms
    assert first.track_count == second.track_count and first.digest == second.digest
    assert len(first.digest) == 64  # asked for, so computed
    assert run_job(Job("mixed-range", 3, "gmphd-context", duration=20.0)).digest == ""
    assert 0.0 <= first.hota.hota <= 1.0
    assert 0.0 <= first.gospa.rms <= 30.0 * math.sqrt(10)  # a few missed/false targets at most


def test_fast_and_stock_chains_give_the_same_scores(stock_in_stable_order):
    fast = run_job(Job("formation", 1, "gmphd-pd-aware", duration=12.0))
    stock = run_job(Job("formation", 1, "gmphd-pd-aware", duration=12.0, stock=True))
    assert fast.hota.hota == pytest.approx(stock.hota.hota, rel=1e-9, abs=1e-12)
    assert fast.gospa.rms == pytest.approx(stock.gospa.rms, rel=1e-9, abs=1e-12)
    assert fast.track_count == stock.track_count


def test_run_experiment_writes_table_and_files(tmp_path):
    config = ExperimentConfig(scenarios=("mixed-range", "formation"),
                              trackers=("gmphd-uniform", "gmphd-context"), seeds=(0, 1),
                              duration=10.0, workers=1)
    results = run_experiment(config, progress=False)
    assert len(results.results) == 2 * 2 * 2
    table = results.table_markdown()
    assert "GM-PHD (uniform)" in table and "GM-PHD (context-aware)" in table
    assert "Combined (S1+S2)" in table
    paths = results.save(tmp_path)
    summary = json.loads(paths["json"].read_text())
    assert {row["tracker"] for row in summary["scores"]} == {"gmphd-uniform", "gmphd-context"}
    for row in summary["scores"]:
        hota = row["combined"]["hota"]
        assert 0 <= hota["low"] <= hota["mean"] <= hota["high"] <= 100
    assert len(paths["csv"].read_text().splitlines()) == 1 + 8
    # the paper's Table II beside each row, per scope, in the table and the JSON
    from ctxmodels.experiment.paper import TABLE_II
    uniform = next(line for line in table.splitlines() if line.startswith("| GM-PHD (uniform)"))
    cells = [cell.strip() for cell in uniform.strip("|").split("|")][1:]
    expected = [TABLE_II["gmphd-uniform"][scope] for scope in ("combined", "mixed-range",
                                                               "formation")]
    for k, paper in enumerate(expected):
        assert cells[2 * k].endswith(f"({paper.hota:.1f})")
        assert cells[2 * k + 1].endswith(f"({paper.gospa:.1f})")
    by_tracker = {row["tracker"]: row for row in summary["scores"]}
    assert by_tracker["gmphd-context"]["paper"]["formation"] == {"hota": 73.5, "gospa": 31.0}
    assert "Calibrated:" in table and "Simulated truth: calibrated" in table
    _check_management_table(results, summary, paths)
    findings = json.loads(paths["findings_json"].read_text())
    # No finding has all its trackers among these two: each says so instead of a verdict.
    assert findings and {f["verdict"] for f in findings} == {"not run"}
    assert all(f["hota_difference"] is None for f in findings)


def _check_management_table(results, summary, paths):
    """The track-management table: every tracker on every scope, pooled per seed."""
    from ctxmodels.experiment import metrics
    from ctxmodels.experiment.report import MANAGEMENT_COLUMNS
    rows = {(row["tracker"], row["scope"]): row for row in summary["management"]}
    assert set(rows) == {(t, s) for t in ("gmphd-uniform", "gmphd-context")
                         for s in ("combined", "mixed-range", "formation")}
    markdown = paths["markdown"].read_text()
    assert "## Track management" in markdown
    assert all(header in markdown for _, header, _ in MANAGEMENT_COLUMNS)
    for tracker in ("gmphd-uniform", "gmphd-context"):
        combined, s1, s2 = (rows[(tracker, s)] for s in ("combined", "mixed-range", "formation"))
        assert combined["seeds"] == 2
        # counts of the combined scope are the scenarios' counts summed per seed
        for key in ("false_tracks", "id_switches", "fragmentations", "never_tracked"):
            assert combined[key] == pytest.approx(s1[key] + s2[key])
        assert all(0 <= row[k] <= 100 for row in (combined, s1, s2)
                   for k in ("deta", "assa", "loca", "tracked_percent"))
        # GOSPA's terms add up to the seeds' mean squared RMS GOSPA
        by_key = results.by_key()
        squares = [metrics.combine_gospa([by_key[(tracker, s, seed)].gospa
                                          for s in ("mixed-range", "formation")]).rms ** 2
                   for seed in (0, 1)]
        parts = combined["gospa_localisation"] + combined["gospa_missed"] + combined["gospa_false"]
        assert parts == pytest.approx(np.mean(squares), rel=1e-9)
    header = paths["csv"].read_text().splitlines()[0].split(",")
    assert header[:10] == ["tracker", "scenario", "seed", "hota_percent", "deta", "assa",
                           "gospa_rms", "tracks", "mean_tracks_per_scan", "scans"]
    assert {"id_switches", "fragmentations", "false_track_lifetime", "time_to_track",
            "gospa_missed"} <= set(header)
    assert all(r.management is not None and r.management.frames == len(r.tracks_per_time)
               for r in results.results)


def test_any_executor_works(tmp_path):
    from concurrent.futures import ThreadPoolExecutor
    config = ExperimentConfig(scenarios=("mixed-range",), trackers=("gmphd-radar-only",),
                              seeds=(0, 1), duration=8.0)
    with ThreadPoolExecutor(2) as pool:
        threaded = run_experiment(config, executor=pool, progress=False)
    inline = run_experiment(ExperimentConfig(**{**config.__dict__, "workers": 1}), progress=False)
    key = lambda r: (r.job.seed, r.hota.hota, r.gospa.rms)  # noqa: E731
    assert sorted(map(key, threaded.results)) == sorted(map(key, inline.results))


def test_each_scenario_is_prepared_once_before_any_job_runs(monkeypatch):
    # (the Solent's preparation downloads its data: once, not in every worker at a time)
    from ctxmodels.experiment import runner
    from ctxmodels.experiment.simulation.layouts import ScenarioSpec
    events = []
    monkeypatch.setattr(ScenarioSpec, "prepare", lambda spec: events.append(spec.name))
    real = runner.run_job
    monkeypatch.setattr(runner, "run_job", lambda job: events.append("job") or real(job))
    jobs = [Job(name, seed, "gmphd-radar-only", duration=4.0)
            for name, seed in [("mixed-range", 0), ("formation", 0), ("mixed-range", 1)]]
    assert len(runner.run_jobs(jobs, workers=1, progress=False)) == 3
    assert events == ["formation", "mixed-range", "job", "job", "job"]


def test_cli_experiment_and_coverage(tmp_path, capsys):
    out = tmp_path / "run"
    code = main(["experiment", "--scenarios", "islands", "--trackers", "gmphd-context",
                 "gmphd-sight", "--seeds", "1", "--duration", "8", "--workers", "1",
                 "--output", str(out), "--quiet"])
    assert code == 0
    printed = capsys.readouterr().out
    assert "GM-PHD (line-of-sight)" in printed
    for name in ("results.md", "results.csv", "results.json", "coverage_islands.png",
                 "tracks_islands_gmphd-sight.png"):
        assert (out / name).stat().st_size > 0, name
    png = tmp_path / "cov.png"
    assert main(["coverage", "--scenario", "islands", "--output", str(png),
                 "--resolution", "60"]) == 0
    assert png.read_bytes()[:4] == b"\x89PNG"


def test_cli_rejects_unknown_tracker(capsys):
    with pytest.raises(SystemExit) as exit_:
        main(["experiment", "--trackers", "nope", "--seeds", "1", "--duration", "1",
              "--no-plots", "--quiet", "--workers", "1"])
    assert exit_.value.code == 2 and "--trackers" in capsys.readouterr().err
    with pytest.raises(ValueError, match="trackers"):  # the library-level check
        ExperimentConfig(trackers=["nope"]).jobs()


def test_tracks_on_static_objects_are_distractors():
    from stonesoup.types.state import State
    from stonesoup.types.track import Track

    from ctxmodels.experiment import metrics
    from ctxmodels.experiment.scoring import drop_distractors, score_run
    run = make_scenario("mixed-range", 0, 5.0)
    times = run.radar_times
    marker = run.static_positions[0]
    vessel = run.truth_by_id[sorted(run.truth_by_id)[0]]
    vessel_at = {s.timestamp: s for s in vessel.states}
    on_marker = Track([State([[marker[0] + 2], [0], [marker[1]], [0]], timestamp=t) for t in times])
    on_vessel = Track([State(vessel_at[t].state_vector.copy(), timestamp=t) for t in times])
    far_away = Track([State([[5000.0], [0], [5000.0], [0]], timestamp=t) for t in times])
    tracks = [on_marker, on_vessel, far_away]
    frames = metrics.frames_from_stonesoup(list(run.truth_by_id.values()), tracks, times)
    kept, dropped = drop_distractors(frames, run.static_positions)
    assert dropped.tolist() == [0] * len(times)  # every position of the marker track, only
    assert all(frame.track_ids.tolist() == [1, 2] for frame in kept)
    # Scored against vessels only, the marker track no longer costs anything, and it is gone.
    scored, plain = score_run(run, tracks[:2]), score_run(run, tracks[:2], static_distractors=False)
    assert (scored.track_count, plain.track_count) == (1, 2)
    assert scored.gospa.rms < plain.gospa.rms
    assert scored.tracks_per_time == (1,) * len(times) and plain.tracks_per_time == (2,) * len(times)
    # Track management sees the same frames: the marker track is a false track (alive for
    # the whole run, in seconds) only when static objects are not distractors.
    assert (scored.management.false_tracks, plain.management.false_tracks) == (0, 1)
    assert plain.management.false_track_lifetime == (times[-1] - times[0]).total_seconds()
    for score in (scored, plain):
        assert score.management.unmatched_track_frames == int(score.gospa.num_false.sum())
        assert score.management.frames == len(times) and score.management.id_switches == 0


def test_cli_sensitivity_options_change_the_simulated_sensors_only(tmp_path, capsys):
    out = tmp_path / "light"
    code = main(["experiment", "--scenarios", "mixed-range", "--trackers", "gmphd-radar-only",
                 "--seeds", "1", "--duration", "6", "--workers", "1", "--output", str(out),
                 "--quiet", "--no-plots", "--radar-clutter", "5", "3.2", "--lidar-clutter",
                 "0.5", "--radar-bearing-std", "0.8"])
    assert code == 0
    printed = capsys.readouterr().out
    assert "radar.clutter_per_scan_far=3.2" in printed
    assert "lidar.clutter_per_scan=0.5" in printed
    assert f"radar.bearing_std={math.radians(0.8):g}" in printed
    config = json.loads((out / "results.json").read_text())["config"]
    assert config["radar"]["clutter_per_scan_far"] == 3.2
    assert config["radar"]["clutter_per_scan_near"] == 5.0
    assert config["lidar"]["clutter_per_scan"] == 0.5


def test_default_table_names_no_simulation_changes():
    from ctxmodels.experiment.runner import simulation_changes
    from ctxmodels.experiment.scenarios import LidarConfig, RadarConfig
    assert simulation_changes(None, None) == ""
    assert simulation_changes(RadarConfig(), LidarConfig()) == ""


def test_job_passes_the_simulated_radar_to_the_scenario():
    import dataclasses

    from ctxmodels.experiment.scenarios import RadarConfig
    quiet = dataclasses.replace(RadarConfig(), clutter_per_scan_near=0.0, clutter_per_scan_far=0.0)
    default = run_job(Job("formation", 2, "gmphd-radar-only", duration=15.0))
    no_clutter = run_job(Job("formation", 2, "gmphd-radar-only", duration=15.0, radar=quiet))
    # Same seed, same vessels: without radar clutter the radar-only tracker can only have
    # fewer tracks, and the run must differ from the default one.
    assert no_clutter.track_count <= default.track_count
    assert (no_clutter.gospa.rms, no_clutter.track_count) != (default.gospa.rms, default.track_count)
    run = make_scenario("formation", 2, 15.0, radar=quiet)
    sources = {d.metadata["source"] for scan in run.radar_scans for d in scan.detections}
    assert "clutter" not in sources


@pytest.mark.parametrize("option, values", [
    ("--radar-clutter", ["5", "-1"]), ("--lidar-clutter", ["nan"]),
    ("--radar-bearing-std", ["0"])])
def test_cli_rejects_bad_sensitivity_values(option, values, capsys):
    with pytest.raises(SystemExit):
        main(["experiment", option, *values, "--seeds", "1", "--duration", "1", "--quiet"])
    assert option in capsys.readouterr().err
