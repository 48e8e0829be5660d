"""The command line under misuse and interruption: every user error is a one-line usage
error (exit 2) before any work starts; Ctrl-C stops a run within seconds (exit 130) and
leaves no worker processes and no partial outputs; a run replaces the previous run's
outputs in its folder and nothing else."""
import json
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from ctxmodels.cli import experiment as experiment_command
from ctxmodels.cli.output import OutputFolder
from ctxmodels.cli import main

from .setups import TINY, usage_error


@pytest.mark.parametrize("argv, option", [
    (["--seeds", "0"], "--seeds"),
    (["--seeds", "-3"], "--seeds"),
    (["--workers", "0"], "--workers"),
    (["--workers", "-4"], "--workers"),
    (["--seed-start", "-1"], "--seed-start"),
    (["--duration", "0"], "--duration"),
    (["--duration", "-5"], "--duration"),
    (["--duration", "nan"], "--duration"),
    (["--duration", "inf"], "--duration"),
    (["--duration", "1e9"], "--duration"),
    (["--duration", "480.5"], "--duration"),
    (["--duration", "1e-9"], "--duration"),  # rounds to no scan on the µs clock
    (["--trackers", "nope"], "--trackers"),
    (["--trackers", "gmphd-sight", "--scenarios", "mixed-range"], "--trackers"),
    (["--trackers", "gmphd-sight", "--scenarios", "mixed-range", "formation"], "--trackers"),
    (["--trackers", "jpda", "--scenarios", "islands"], "--trackers"),
    (["--scenarios", "atlantis"], "--scenarios"),
    (["--lidar-clutter", "1e7"], "--lidar-clutter"),
    (["--lidar-clutter", "100.5"], "--lidar-clutter"),
    (["--radar-clutter", "1e7", "5"], "--radar-clutter"),
    (["--radar-clutter", "600", "600"], "--radar-clutter"),  # the sum is bounded
    (["--radar-clutter", "5", "-1"], "--radar-clutter"),
    (["--radar-bearing-std", "46"], "--radar-bearing-std"),
    (["--radar-bearing-std", "0"], "--radar-bearing-std"),
])
def test_experiment_usage_errors_exit_2_before_any_work(argv, option, tmp_path, capsys, no_work):
    out = tmp_path / "out"
    line = usage_error(["experiment", *TINY, "--output", str(out), *argv], capsys)
    assert line.startswith(f"ctxmodels experiment: error: argument {option}:"), line
    assert not out.exists()  # refused before the output folder was made


def test_line_of_sight_refusal_names_the_pair(tmp_path, capsys, no_work):
    line = usage_error(["experiment", *TINY, "--trackers", "gmphd-sight", "--output",
                        str(tmp_path / "out")], capsys)
    assert "gmphd-sight" in line and "mixed-range" in line and "islands" in line


def test_output_naming_a_file_is_refused(tmp_path, capsys, no_work):
    existing = tmp_path / "results"
    existing.write_text("not a folder")
    line = usage_error(["experiment", *TINY, "--output", str(existing)], capsys)
    assert "argument --output" in line and "not a folder" in line
    assert existing.read_text() == "not a folder"
    line = usage_error(["experiment", *TINY, "--output", str(existing / "sub")], capsys)
    assert "argument --output" in line and "cannot create" in line


def test_unwritable_output_folder_is_refused(capsys, no_work):
    # /proc takes no new files, also for root (for whom chmod blocks nothing)
    folder = Path("/proc")
    with pytest.raises(OSError):
        (folder / ".ctxmodels-test").write_bytes(b"")
    line = usage_error(["experiment", *TINY, "--output", str(folder)], capsys)
    assert "argument --output" in line and "cannot write" in line


def _record_instead_of_running(monkeypatch) -> dict:
    """Replaces the experiment command by one that records its checked arguments."""
    seen = {}

    def record(args):
        seen["args"] = args
        return 0
    monkeypatch.setattr(experiment_command, "_experiment", record)
    return seen


@pytest.mark.parametrize("argv, accepted", [
    (["--lidar-clutter", "100"], "lidar_clutter"),
    (["--radar-clutter", "500", "500"], "radar_clutter"),
    (["--radar-bearing-std", "45"], "radar_bearing_std"),
    (["--duration", "480"], "duration"),
    (["--seed-start", "0", "--seeds", "10000"], "seeds"),
])
def test_bounds_themselves_are_accepted(argv, accepted, tmp_path, monkeypatch):
    seen = _record_instead_of_running(monkeypatch)
    assert main(["experiment", *TINY, "--output", str(tmp_path / "out"), *argv]) == 0
    assert getattr(seen["args"], accepted) is not None


def test_default_trackers_skip_line_of_sight_where_there_is_no_land(tmp_path, monkeypatch):
    seen = _record_instead_of_running(monkeypatch)
    # The default list holds gmphd-sight: it runs on islands only, without an error.
    assert main(["experiment", "--scenarios", "mixed-range", "--output",
                 str(tmp_path / "a")]) == 0
    assert seen.pop("args").trackers is None
    # Named with a scenario that has land, it runs there and is skipped elsewhere.
    assert main(["experiment", "--scenarios", "mixed-range", "islands", "--trackers",
                 "gmphd-context", "gmphd-sight", "--output", str(tmp_path / "b")]) == 0
    assert seen["args"].skipped == [("gmphd-sight", "mixed-range")]


@pytest.mark.parametrize("argv, option", [
    (["--resolution", "0"], "--resolution"),
    (["--resolution", "1"], "--resolution"),
    (["--pose", "nan", "0", "90"], "--pose"),
    (["--pose", "0", "0", "inf"], "--pose"),
    (["--extent", "0"], "--extent"),
    (["--extent", "-100"], "--extent"),
    (["--sensors", "sonar"], "--sensors"),
    (["--antenna-height", "20"], "--antenna-height"),
    (["--clearance", "100"], "--clearance"),
    (["--coastline", "f"], "--coastline"),
    (["--site", "-1.1", "50.8", "--coastline", "x"], "--coastline"),
    (["--site", "-1.1", "50.8", "--clearance", "-1"], "--clearance"),
    (["--site", "-1.1", "50.8", "--antenna-height", "0"], "--antenna-height"),
    (["--site", "200", "50"], "--site"),
    (["--site", "-1.1", "85"], "--site"),
    (["--site", "-1.1", "50.8", "--scenario", "islands"], "--site"),
    (["--site", "-1.1", "50.8", "--extent", "600000"], "--extent"),
    (["--site", "20", "80", "--extent", "500000"], "--extent"),
    (["--site", "179.99", "0", "--extent", "5000"], "--extent"),
])
def test_coverage_usage_errors(argv, option, tmp_path, capsys):
    png = tmp_path / "cov.png"
    line = usage_error(["coverage", "--output", str(png), *argv], capsys)
    assert line.startswith(f"ctxmodels coverage: error: argument {option}:"), line
    assert not png.exists()


def _model_files(tmp_path):
    from stonesoup.serialise import YAML
    from stonesoup.types.state import State
    files = {"missing": tmp_path / "missing.yaml", "text": tmp_path / "notes.txt",
             "binary": tmp_path / "image.png", "broken": tmp_path / "broken.yaml",
             "state": tmp_path / "state.yaml"}
    files["text"].write_text("just some words\n")  # YAML for the string itself
    files["binary"].write_bytes(b"\x89PNG\r\n\x1a\n\x00\xff\xfe")
    files["broken"].write_text("a: [1, 2\n")
    files["state"].write_text(YAML().dumps(State([1.0, 2.0])))
    return files


@pytest.mark.parametrize("kind, message", [
    ("missing", "cannot read"), ("text", "not a ctxmodels SensorModel"),
    ("binary", "not a text"), ("broken", "not Stone Soup YAML"),
    ("state", "holds a State, not a ctxmodels SensorModel")])
def test_coverage_model_that_is_not_a_sensor_model(kind, message, tmp_path, capsys):
    png = tmp_path / "cov.png"
    line = usage_error(["coverage", "--model", str(_model_files(tmp_path)[kind]),
                        "--output", str(png)], capsys)
    assert line.startswith("ctxmodels coverage: error: argument --model:"), line
    assert message in line
    assert not png.exists()


def test_coverage_output_checked_up_front(tmp_path, capsys):
    assert "is a folder" in usage_error(["coverage", "--output", str(tmp_path)], capsys)
    assert "does not exist" in usage_error(
        ["coverage", "--output", str(tmp_path / "no" / "cov.png")], capsys)
    assert "cannot write '.xyz'" in usage_error(
        ["coverage", "--output", str(tmp_path / "cov.xyz")], capsys)


def test_coverage_of_a_saved_sensor_model(tmp_path):
    from stonesoup.serialise import YAML

    from ctxmodels.experiment.sensors import paper_sensor_models
    model = tmp_path / "radar.yaml"
    model.write_text(YAML().dumps(paper_sensor_models()["radar"]))
    png = tmp_path / "cov.png"
    assert main(["coverage", "--model", str(model), "--resolution", "20", "--output",
                 str(png)]) == 0
    assert png.read_bytes()[:4] == b"\x89PNG"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cov.png", "radar.yaml"]


def test_coverage_at_a_real_site(tmp_path, capsys):
    from stonesoup.serialise import YAML

    from ctxmodels.experiment.sensors import paper_sensor_models
    png = tmp_path / "site.png"
    # Southsea Castle, Portsmouth: a radar on the shore (the shorelines are downloaded once)
    assert main(["coverage", "--site", "-1.0889", "50.7780", "--extent", "8000", "--coastline", "h",
                 "--resolution", "40", "--output", str(png)]) == 0
    assert png.read_bytes()[:4] == b"\x89PNG"
    said = capsys.readouterr().err
    assert "on land" in said and "land within 500 m of the antenna blocks nothing" in said
    # a saved model at a site 3 km inland: told that it sees nothing
    model = tmp_path / "radar.yaml"
    model.write_text(YAML().dumps(paper_sensor_models()["radar"]))
    assert main(["coverage", "--site", "-1.29", "50.69", "--model", str(model), "--coastline", "i",
                 "--extent", "3000", "--resolution", "20", "--output", str(png)]) == 0
    assert "every ray meets land" in capsys.readouterr().err
    # open sea, no land within the maps: the radar alone
    assert main(["coverage", "--site", "-30", "-40", "--extent", "2000", "--coastline", "c",
                 "--resolution", "20", "--output", str(png)]) == 0
    assert "no land within the maps" in capsys.readouterr().err


def test_coverage_refuses_two_models_of_one_name_and_bad_mathtext(tmp_path, capsys):
    from stonesoup.serialise import YAML

    from ctxmodels.experiment.sensors import paper_sensor_models
    first, second = tmp_path / "a.yaml", tmp_path / "b.yaml"
    for path in (first, second):  # both hold the model named "radar"
        path.write_text(YAML().dumps(paper_sensor_models()["radar"]))
    png = tmp_path / "cov.png"
    line = usage_error(["coverage", "--model", str(first), str(second), "--output", str(png)],
                       capsys)
    assert "argument --model" in line and "second model named 'radar'" in line
    line = usage_error(["coverage", "--title", "$\\foo$", "--output", str(png)], capsys)
    assert "argument --title" in line and "mathtext" in line
    # a model's name is drawn in its titles: checked as the title is
    from ctxmodels import SensorModel
    radar = paper_sensor_models()["radar"]
    named = SensorModel(detection=radar.detection, clutter=radar.clutter, name="radar $\\frac{$ A")
    first.write_text(YAML().dumps(named))
    line = usage_error(["coverage", "--model", str(first), "--output", str(png)], capsys)
    assert "the model named" in line and "mathtext" in line
    assert not png.exists()


def test_an_early_interrupt_leaves_no_empty_output_folder(tmp_path, monkeypatch):
    """Ctrl-C before any run started (while the jobs are listed): the folder this run
    created is removed again."""
    from ctxmodels.experiment import runner

    def interrupted(self):
        raise KeyboardInterrupt
    monkeypatch.setattr(runner.ExperimentConfig, "jobs", interrupted)
    out = tmp_path / "fresh"
    assert main(["experiment", *TINY, "--output", str(out)]) == 130
    assert not out.exists()


def test_a_ctrl_c_held_back_under_the_default_action_still_ends_the_process():
    """sigint_deferred restores SIG_DFL and re-raises the held-back SIGINT: the process
    dies of SIGINT instead of carrying on."""
    code = ("import os, signal, time\n"
            "from ctxmodels.experiment.executors import sigint_deferred\n"
            "signal.signal(signal.SIGINT, signal.SIG_DFL)\n"
            "with sigint_deferred():\n"
            "    os.kill(os.getpid(), signal.SIGINT)\n"
            "    time.sleep(0.2)\n"
            "    print('held', flush=True)\n"
            "print('carried on', flush=True)\n")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                            timeout=60, preexec_fn=_default_sigint)
    assert result.stdout == "held\n" and result.returncode == -signal.SIGINT


def test_usage_error_from_the_console_command(tmp_path):
    # End to end through a real process: exit status 2, one message, no traceback.
    done = subprocess.run([sys.executable, "-m", "ctxmodels.cli", "experiment", "--duration",
                           "nan", "--output", str(tmp_path / "out")],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 2
    assert "Traceback" not in done.stderr
    assert done.stderr.splitlines()[-1].startswith("ctxmodels experiment: error: argument "
                                                   "--duration")
    assert not (tmp_path / "out").exists()


# --- a second run into the same folder ------------------------------------------------


def test_second_run_replaces_the_previous_outputs_only(tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["experiment", *TINY, "--output", str(out)]) == 0  # with figures
    first = {p.name for p in out.iterdir()}
    assert {"results.md", "results.csv", "results.json", "coverage_mixed-range.png",
            "tracks_mixed-range_gmphd-context.png"} <= first
    (out / "notes.txt").write_text("mine")
    (out / "coverage_custom.png").write_bytes(b"mine")
    assert main(["experiment", *TINY, "--no-plots", "--output", str(out)]) == 0
    after = {p.name for p in out.iterdir()}
    # The first run's figures are gone; the user's files, even ctxmodels-like names, stay.
    assert after == {"results.md", "results.csv", "results.json", "findings.md",
                     "findings.json", "notes.txt", "coverage_custom.png",
                     OutputFolder.MANIFEST}
    assert (out / "notes.txt").read_text() == "mine"
    manifest = json.loads((out / OutputFolder.MANIFEST).read_text())
    assert manifest["files"] == ["findings.json", "findings.md", "results.csv", "results.json",
                                 "results.md"]
    capsys.readouterr()


def test_folder_from_before_manifests_and_a_hostile_manifest(tmp_path):
    folder = tmp_path / "old"
    folder.mkdir()
    for name in ("results.json", "tracks_formation_jpda.png", "coverage_islands.png",
                 "holiday.png"):
        (folder / name).write_text("x")
    assert OutputFolder(folder).previous() == {
        "results.json", "tracks_formation_jpda.png", "coverage_islands.png"}
    outside = tmp_path / "outside.txt"
    outside.write_text("keep")
    (folder / OutputFolder.MANIFEST).write_text(json.dumps(
        {"files": ["../outside.txt", str(outside), "holiday.png", "/etc/passwd", ".."]}))
    assert OutputFolder(folder).previous() == {"holiday.png"}
    (folder / OutputFolder.MANIFEST).write_text("{not json")
    assert OutputFolder(folder).previous() == set()


def _default_sigint():
    signal.signal(signal.SIGINT, signal.SIG_DFL)


@pytest.fixture
def sigint_raises():
    """SIGINT raises KeyboardInterrupt in this process for the test, as in a terminal, also
    when the suite was started with SIGINT ignored (a background job)."""
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, previous)


def test_ctrl_c_while_outputs_move_in_leaves_one_complete_run(tmp_path, monkeypatch,
                                                              sigint_raises):
    out = tmp_path / "out"
    out.mkdir()
    for name in ("results.md", "tracks_formation_jpda.png"):
        (out / name).write_text("old")
    (out / OutputFolder.MANIFEST).write_text(json.dumps(
        {"files": ["results.md", "tracks_formation_jpda.png"]}))
    folder = OutputFolder(out)
    real_replace = os.replace

    def replace_with_ctrl_c(source, target):
        os.kill(os.getpid(), signal.SIGINT)  # Ctrl-C at the first rename
        monkeypatch.setattr(os, "replace", real_replace)
        real_replace(source, target)
    with folder.staging() as stage:
        for name in ("results.md", "results.csv"):
            (stage / name).write_text("new")
        monkeypatch.setattr(os, "replace", replace_with_ctrl_c)
        with pytest.raises(KeyboardInterrupt):  # raised once the commit is complete
            folder.commit(stage)
    assert folder.committed
    assert {p.name for p in out.iterdir()} == {"results.md", "results.csv",
                                              OutputFolder.MANIFEST}
    assert (out / "results.md").read_text() == "new"
    assert json.loads((out / OutputFolder.MANIFEST).read_text())["files"] == [
        "results.csv", "results.md"]


# --- Ctrl-C ---------------------------------------------------------------------------


def test_inline_run_stops_at_the_first_interrupt(monkeypatch):
    from ctxmodels.experiment import runner
    calls = []

    def interrupted(job):
        calls.append(job)
        raise KeyboardInterrupt
    monkeypatch.setattr(runner, "run_job", interrupted)
    config = runner.ExperimentConfig(scenarios=("mixed-range",), trackers=("gmphd-context",),
                                     seeds=range(5), duration=5.0, workers=1)
    with pytest.raises(KeyboardInterrupt):
        runner.run_experiment(config, progress=False)
    assert len(calls) == 1  # not one failed job and four more runs


def _process_group(pgid: int) -> list[int]:
    """Live processes in the process group (Linux /proc), zombies excluded."""
    pids = []
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            stat = Path(f"/proc/{entry}/stat").read_text()
        except OSError:
            continue
        fields = stat.rsplit(")", 1)[1].split()  # state, ppid, pgrp, ...
        if int(fields[2]) == pgid and fields[0] != "Z":
            pids.append(int(entry))
    return pids


def _wait_for(condition, timeout: float, what: str):
    deadline = time.monotonic() + timeout
    while not condition():
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out waiting for {what}")
        time.sleep(0.05)


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs Linux /proc")
@pytest.mark.parametrize("target, workers, previous", [
    ("group", "2", False),  # what a terminal does: SIGINT to every process of the job
    ("parent", "2", True),  # `kill -INT <pid>`: the workers see nothing
    ("parent", "1", False),  # no pool: the run happens in the CLI's own process
])
def test_ctrl_c_stops_the_run(target, workers, previous, tmp_path):
    out = tmp_path / "out"
    if previous:  # a previous run's results must survive an interrupted run
        out.mkdir()
        (out / "results.md").write_text("previous")
        (out / OutputFolder.MANIFEST).write_text(json.dumps({"files": ["results.md"]}))
    # Eight 120 s runs: about a minute of work on two cores, one run alone takes seconds.
    argv = [sys.executable, "-m", "ctxmodels.cli", "experiment", "--scenarios", "mixed-range",
            "--trackers", "gmphd-context", "--seeds", "8", "--duration", "120", "--workers",
            workers, "--no-plots", "--quiet", "--output", str(out)]
    # Its own process group, as in a shell; SIGINT at its default disposition, as in a
    # terminal (a job started in the background, as CI may start this suite, inherits
    # SIGINT ignored, and Python then never raises KeyboardInterrupt).
    process = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                               start_new_session=True, preexec_fn=_default_sigint)
    stderr: list[str] = []
    reader = threading.Thread(target=lambda: stderr.extend(process.stderr), daemon=True)
    reader.start()
    try:
        _wait_for(lambda: any(line.startswith("ctxmodels experiment: ") for line in stderr)
                  or process.poll() is not None, 120, "the banner")
        assert process.poll() is None, "".join(stderr)
        if workers != "1":
            _wait_for(lambda: len(_process_group(process.pid)) >= 1 + int(workers), 60,
                      "the worker processes")
        time.sleep(1.0)  # let the workers pick up their first jobs
        sent = time.monotonic()
        (os.killpg if target == "group" else os.kill)(process.pid, signal.SIGINT)
        code = process.wait(timeout=60)
        seconds = time.monotonic() - sent
        reader.join(timeout=10)
        stdout = process.stdout.read()
    finally:
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGKILL)
            process.wait()
    err = "".join(stderr)
    assert code == 130, err
    assert seconds < 10, f"took {seconds:.1f} s to stop"
    assert "Traceback" not in err and "KeyboardInterrupt" not in err, err
    assert err.rstrip("\n").splitlines()[-1].startswith("ctxmodels experiment: interrupted"), err
    assert "| Method" not in stdout  # the queued runs did not go on to make a table
    _wait_for(lambda: not _process_group(process.pid), 5, "no processes left in the group")
    if previous:
        assert {p.name for p in out.iterdir()} == {"results.md", OutputFolder.MANIFEST}
        assert (out / "results.md").read_text() == "previous"
    else:
        assert not out.exists()  # made for this run, left empty, so removed


def _sleep(seconds):
    time.sleep(seconds)


def test_stopping_the_pool_leaves_nothing_for_the_exit_hook():
    """The pool's manager thread has ended (its wake-up pipe closed) when ``stop_now``
    returns: CPython's exit hook writes to every live pool's pipe, and if the manager thread
    is closing that pipe at the same moment the write fails with EBADF and prints a
    traceback after the CLI's last line (seen in CI, about one run in fifty)."""
    import concurrent.futures

    from ctxmodels.experiment.executors import stop_now, worker_ignores_sigint
    executor = concurrent.futures.ProcessPoolExecutor(2, initializer=worker_ignores_sigint)
    futures = [executor.submit(_sleep, 30) for _ in range(6)]
    _wait_for(lambda: sum(f.running() for f in futures) >= 2, 30, "two running jobs")
    manager = executor._executor_manager_thread
    processes = list(executor._processes.values())
    stop_now(executor)
    assert not manager.is_alive()
    assert not any(process.is_alive() for process in processes)
    assert all(f.cancelled() for f in futures if not f.running() and not f.done())
