"""Hardening III: ctxmodels' trackers fed hostile scans, the study's files, timing and
progress bar, and the test run's warning filters.

Trackers: the four ctxmodels trackers (component-path JPDA, ArrayJPDATracker, component-path
GM-PHD, ArrayPointProcessTracker) refuse the same bad scans with the same message, naming
the scan (its index in the run and its time) and the detection; the documented-equivalent
array and component paths agree. See ctxmodels.stonesoup.scan_checks.
"""
from __future__ import annotations

import contextlib
import datetime
import io
import json
import math
import pathlib
import subprocess
import sys
import textwrap
import warnings

import numpy as np
import pytest
from stonesoup.dataassociator.probability import JPDAwithEHM2
from stonesoup.deleter.time import UpdateTimeStepsDeleter
from stonesoup.initiator.simple import SimpleMeasurementInitiator
from stonesoup.predictor.kalman import KalmanPredictor
from stonesoup.types.detection import Detection
from stonesoup.types.state import GaussianState, State
from stonesoup.types.track import Track
from stonesoup.updater.kalman import KalmanUpdater

import ctxmodels
from ctxmodels import DetectionSet
from ctxmodels.stonesoup import (
    ArrayJPDATracker,
    ArrayPointProcessTracker,
    ComponentPathWarning,
    MultiTargetMixtureTracker,
    PDAHypothesiser,
    PointProcessMultiTargetTracker,
)

from gmphd_setups import birth_component, stock_components, tutorial_scenario
from test_stonesoup_array_jpda import run_side_by_side, tutorial_pair
from test_stonesoup_jpda import CLUTTER, MEASUREMENT, PD, T0, TRANSITION, track_at

UTC = datetime.timezone.utc


# --- the four trackers ------------------------------------------------------------------------
def _first_time(scans):
    try:
        time = scans[0][0]
    except (IndexError, TypeError, KeyError):
        return None
    return time if isinstance(time, datetime.datetime) else None


def _jpda(cls, scans, updater_model=MEASUREMENT, track_time=None):
    if track_time is None:  # the track on the first scan's clock (naive or aware)
        first = _first_time(scans)
        track_time = T0.replace(tzinfo=first.tzinfo if first is not None else None)
    predictor, updater = KalmanPredictor(TRANSITION), KalmanUpdater(updater_model)
    hypothesiser = PDAHypothesiser(predictor, updater, clutter_spatial_density=CLUTTER,
                                   prob_detect=PD)
    initiator = SimpleMeasurementInitiator(
        GaussianState(np.zeros((4, 1)), np.diag([1.5, 0.5, 1.5, 0.5])), MEASUREMENT)
    tracker = cls(initiator=initiator, deleter=UpdateTimeStepsDeleter(3), detector=scans,
                  data_associator=JPDAwithEHM2(hypothesiser), updater=updater)
    tracker._tracks.add(track_at(0.0, 0.0, t=track_time))  # a track: the hypothesiser runs
    return tracker


def _gmphd(cls, scans, **_):
    scenario = tutorial_scenario(n_scans=2)
    return cls(detector=scans, birth_component=birth_component(scenario),
               extraction_threshold=0.5, **stock_components(scenario, context_updater=True))


TRACKERS = {
    "jpda-component": lambda scans, **kw: _jpda(MultiTargetMixtureTracker, scans, **kw),
    "jpda-array": lambda scans, **kw: _jpda(ArrayJPDATracker, scans, **kw),
    "gmphd-component": lambda scans, **kw: _gmphd(PointProcessMultiTargetTracker, scans),
    "gmphd-array": lambda scans, **kw: _gmphd(ArrayPointProcessTracker, scans),
}


def at(seconds, tz=None):
    return (T0 + datetime.timedelta(seconds=seconds)).replace(tzinfo=tz)


def det(values, seconds=1.0, tz=None, model=MEASUREMENT):
    return Detection(np.array(values, dtype=float).reshape(-1, 1), timestamp=at(seconds, tz),
                     measurement_model=model)


def good(seconds, tz=None):
    return (at(seconds, tz), {det([1.0, 1.0], seconds, tz), det([3.0, -2.0], seconds, tz)})


def _falls_back(kind, reason):
    """An array tracker's scan that runs the component path (as intended): its one
    ComponentPathWarning, naming ``reason``; nothing for the component trackers."""
    if "array" not in kind:
        return contextlib.nullcontext()
    return pytest.warns(ComponentPathWarning, match=reason)


def _refusal(tracker, exception):
    with pytest.raises(exception) as info:
        list(tracker)
    return str(info.value)


# (id, scans, exception, message prefix, texts the message must hold)
HOSTILE_SCANS = [
    ("detections-None", [(at(1), None)], TypeError, "detector:", ["scan 0", str(at(1)), "NoneType"]),
    ("detections-str", [(at(1), "detections")], TypeError, "detector:", ["scan 0", "str"]),
    ("detections-bytes", [(at(1), b"\x00")], TypeError, "detector:", ["scan 0", "bytes"]),
    ("detections-int", [(at(1), 5)], TypeError, "detector:", ["scan 0", "int"]),
    ("item-str", [(at(1), ["abc"])], TypeError, "detections:", ["item 0", "scan 0", "str"]),
    ("item-None", [(at(1), [det([1, 1]), None])], TypeError, "detections:", ["item 1", "NoneType"]),
    ("item-State", [(at(1), [State([[1.0], [1.0]], timestamp=at(1))])], TypeError,
     "detections:", ["item 0", "State"]),
    ("item-array", [(at(1), [np.array([[1.0], [1.0]])])], TypeError, "detections:",
     ["item 0", "ndarray"]),
    ("scan-not-a-pair", [{det([1, 1])}], TypeError, "detector:", ["scan 0", "pair"]),
    ("scan-three-items", [(at(1), set(), "x")], TypeError, "detector:", ["scan 0", "3 items"]),
    ("scan-None", [None], TypeError, "detector:", ["scan 0", "NoneType"]),
    ("time-None", [(None, {det([1, 1])})], TypeError, "detector:", ["scan 0", "datetime"]),
    ("time-str", [("2024-05-01 12:00:01", {det([1, 1])})], TypeError, "detector:",
     ["scan 0", "str"]),
    ("time-float", [(1.0, set())], TypeError, "detector:", ["scan 0", "float"]),
    ("time-date", [(datetime.date(2024, 5, 1), set())], TypeError, "detector:", ["scan 0", "date"]),
    ("nan-x", [good(1), (at(2), {det([math.nan, 5.0], 2), det([1.0, 1.0], 2)})], ValueError,
     "detections:", ["scan 1", str(at(2)), "not finite", "nan"]),
    ("nan-y", [(at(1), {det([5.0, math.nan])})], ValueError, "detections:",
     ["row 0", "scan 0", "not finite"]),
    ("plus-inf", [(at(1), {det([math.inf, 5.0])})], ValueError, "detections:", ["not finite", "inf"]),
    ("minus-inf", [(at(1), {det([1.0, -math.inf]), det([0.0, 0.0])})], ValueError,
     "detections:", ["not finite", "-inf"]),
    ("huge-overflowing", [(at(1), {Detection(np.array([[1e308 * 10], [0.0]]), timestamp=at(1),
                                             measurement_model=MEASUREMENT)})],
     ValueError, "detections:", ["not finite"]),
    ("three-elements", [(at(1), {det([1.0, 1.0, 3.0])})], ValueError, "detections:",
     ["row 0", "scan 0", "3 elements", "measures 2"]),
    ("one-element", [good(1), (at(2), {det([1.0], 2), det([1.0, 2.0], 2)})], ValueError,
     "detections:", ["scan 1", "1 elements", "measures 2"]),
    ("backwards", [good(2), good(1)], ValueError, "detector:",
     ["scan 1", str(at(1)), "earlier", str(at(2))]),
    ("backwards-later", [good(1), good(3), good(2)], ValueError, "detector:", ["scan 2"]),
    ("naive-then-aware", [good(1), good(2, UTC)], ValueError, "detector:",
     ["scan 1", "timezone-aware", str(at(1))]),
    ("aware-then-naive", [good(1, UTC), good(2)], ValueError, "detector:",
     ["scan 1", "timezone-naive"]),
    ("aware-detection-in-naive-scan", [(at(1), {det([1.0, 1.0], 1, UTC)})], ValueError,
     "detections:", ["scan 0", "timezone-aware", "[1.0, 1.0]"]),
    ("naive-detection-in-aware-scan",
     [(at(1, UTC), {det([1.0, 1.0], 1, UTC), det([2.0, 1.0], 1)})], ValueError,
     "detections:", ["scan 0", "timezone-naive", "[2.0, 1.0]"]),
]


@pytest.mark.parametrize("kind", list(TRACKERS))
@pytest.mark.parametrize("name, scans, exception, prefix, texts", HOSTILE_SCANS,
                         ids=[case[0] for case in HOSTILE_SCANS])
def test_hostile_scans_are_refused_naming_the_scan(kind, name, scans, exception, prefix, texts):
    message = _refusal(TRACKERS[kind](scans), exception)
    assert message.startswith(prefix), message
    for text in texts:
        assert text in message, (text, message)


@pytest.mark.parametrize("name, scans, exception, prefix, texts", HOSTILE_SCANS,
                         ids=[case[0] for case in HOSTILE_SCANS])
def test_array_and_component_paths_refuse_with_the_same_message(name, scans, exception, prefix,
                                                                texts):
    """The documented-equivalent paths: one message, word for word (before, the component
    JPDA and GM-PHD silently dropped a NaN detection at constant λ)."""
    for component, array in (("jpda-component", "jpda-array"),
                             ("gmphd-component", "gmphd-array")):
        assert _refusal(TRACKERS[component](scans), exception) == \
            _refusal(TRACKERS[array](scans), exception)


@pytest.mark.parametrize("kind", list(TRACKERS))
def test_nan_detection_with_a_context_is_refused_the_same_way(kind):
    from test_stonesoup_jpda import ORIGIN, constant_sensor
    sensor = constant_sensor()
    scans = [(at(1), DetectionSet({det([math.nan, 5.0]), det([1.0, 1.0])},
                                  detector_context=sensor.context(ORIGIN.pose_at(at(1)))))]
    message = _refusal(TRACKERS[kind](scans), ValueError)
    assert message.startswith("detections: row 1 of scan 0 at ") and "not finite" in message


@pytest.mark.parametrize("kind", list(TRACKERS))
def test_detection_without_a_model_is_named_with_its_scan(kind):
    """No model on the detection and none on the updater: Stone Soup's bare "No
    measurement model specified", now with the scan and the detection."""
    scans = [good(1), (at(2), {det([1.0, 1.0], 2, model=None), det([0.5, 0.5], 2)})]
    with _falls_back(kind, "2 distinct measurement models"):
        message = _refusal(TRACKERS[kind](scans, updater_model=None), ValueError)
    assert message.startswith("detections: scan 1 at " + str(at(2))), message
    assert "row 0 ([0.5, 0.5])" not in message and "[1.0, 1.0]" in message
    assert "no measurement model" in message


@pytest.mark.parametrize("kind", ["jpda-component", "jpda-array"])
def test_aware_scan_against_a_naive_track_is_named(kind):
    message = _refusal(TRACKERS[kind]([good(1, UTC)], track_time=T0), ValueError)
    assert message.startswith(f"detector: scan 0 at {at(1, UTC)}:"), message
    assert "timezone-aware" in message


@pytest.mark.parametrize("kind", list(TRACKERS))
@pytest.mark.parametrize("name, scans", [
    ("empty-set", [(at(1), set())]),
    ("empty-list", [(at(1), [])]),
    ("empty-tuple", [(at(1), ())]),
    ("empty-detection-set", [(at(1), DetectionSet(set()))]),
    ("generator", [(at(1), (d for d in good(1)[1]))]),
    ("same-time-twice", [good(1), good(1), good(2)]),
    ("aware-throughout", "aware"),
    ("detection-time-not-the-scans", [(at(1), {det([1.0, 1.0], 3)})]),
])
def test_odd_but_valid_scans_run(kind, name, scans):
    if scans == "aware":
        scans = [good(1, UTC), good(2, UTC)]
    tracker = TRACKERS[kind](scans)
    with _falls_back(kind if name == "detection-time-not-the-scans" else "", "timestamps other"):
        out = list(tracker)
    assert [time for time, _ in out] == [time for time, _ in scans]


def test_refusal_happens_before_any_work():
    """A refused scan leaves the tracker as it was: the next good scan runs."""
    for kind in TRACKERS:
        tracker = TRACKERS[kind]([])
        tracker.update_tracker(*good(1))
        before = {id(t): len(t) for t in tracker.tracks}
        with pytest.raises(ValueError):
            tracker.update_tracker(at(2), {det([math.nan, 1.0], 2)})
        assert {id(t): len(t) for t in tracker.tracks} == before, kind
        tracker.update_tracker(*good(2))


# --- ArrayJPDATracker: integer track states take the array path -------------------------------
def _integer_track():
    return Track([GaussianState(np.array([[0], [1], [0], [1]]), np.diag([2, 1, 2, 1]),
                                timestamp=T0 - datetime.timedelta(seconds=1))])


def test_integer_track_states_take_the_array_path_with_the_component_paths_numbers():
    ours, reference = tutorial_pair()
    start = _integer_track()
    assert start.state_vector.dtype.kind == "i" and start.covar.dtype.kind == "i"
    for tracker in (ours, reference):
        tracker._tracks.add(_integer_track())
    worst, scans = run_side_by_side(ours, reference)
    assert ours.array_scans == scans and ours.component_scans == 0
    assert worst <= 1e-9


def test_object_track_states_still_run_the_component_path():
    ours, reference = tutorial_pair()
    for tracker in (ours, reference):
        track = _integer_track()
        track.states[0].state_vector = track.states[0].state_vector.astype(object)
        tracker._tracks.add(track)
    with pytest.warns(ComponentPathWarning, match="last state"):
        worst, scans = run_side_by_side(ours, reference)
    assert ours.component_scans == 1 and ours.array_scans == scans - 1
    assert worst <= 1e-9


# --- warnings from ctxmodels' own code fail the test run ---------------------------------------
def test_package_sources_compile_without_warnings():
    """No invalid escape (or other compile-time warning) in any module of the package,
    whatever the byte-code cache holds."""
    root = pathlib.Path(ctxmodels.__file__).parent
    sources = sorted(root.rglob("*.py"))
    assert len(sources) > 40
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for path in sources:
            compile(path.read_text(encoding="utf-8"), str(path), "exec")


def _warn_from(module: str, category):
    exec(compile("import warnings\nwarnings.warn('probe', category)", f"<{module}>", "exec"),
         {"__name__": module, "category": category})


@pytest.mark.parametrize("category", [DeprecationWarning, RuntimeWarning, UserWarning,
                                      FutureWarning, SyntaxWarning])
def test_a_warning_from_a_ctxmodels_module_is_an_error(category):
    for module in ("ctxmodels", "ctxmodels.stonesoup.gmphd.tracker", "ctxmodels.experiment.runner"):
        with pytest.raises(category):
            _warn_from(module, category)


def test_numpy_warning_in_ctxmodels_code_is_an_error_and_third_party_ones_are_not():
    code = compile("import numpy\nnumpy.log(numpy.zeros(1))", "<probe>", "exec")
    with pytest.raises(RuntimeWarning):
        exec(code, {"__name__": "ctxmodels.probe"})
    for module in ("stonesoup.probe", "numpy.probe", "ctxmodelsx", "dask.probe"):
        with warnings.catch_warnings(record=True) as caught:  # (keeps the filters)
            exec(code, {"__name__": module})
            _warn_from(module, DeprecationWarning)
        assert len(caught) == 2, module


def test_compile_time_warnings_in_ctxmodels_sources_are_errors():
    source = "x = '\\k'\n"  # an invalid escape
    for path in ("/src/python/ctxmodels/probe.py", "/venv/site-packages/ctxmodels/a/b.py"):
        with pytest.raises(SyntaxError):
            compile(source, path, "exec")
    with warnings.catch_warnings(record=True) as caught:
        compile(source, "/venv/site-packages/stonesoup/probe.py", "exec")
    assert caught and issubclass(caught[0].category, (DeprecationWarning, SyntaxWarning))


def test_the_projects_pytest_configuration_fails_a_run_on_a_ctxmodels_warning(tmp_path):
    """The filters as pytest reads them from pyproject.toml, in a run of their own."""
    project = pathlib.Path(__file__).resolve().parents[2]
    (tmp_path / "test_probe.py").write_text(textwrap.dedent("""
        import warnings

        def _warn(module):
            exec("import warnings; warnings.warn('probe', DeprecationWarning)",
                 {"__name__": module})

        def test_ours():
            _warn("ctxmodels.stonesoup.probe")

        def test_theirs():
            _warn("stonesoup.probe")
    """))
    run = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider",
                          "-c", str(project / "pyproject.toml"), "--rootdir", str(tmp_path),
                          str(tmp_path / "test_probe.py")],
                         capture_output=True, text=True, timeout=120, cwd=tmp_path)
    assert run.returncode == 1, run.stdout + run.stderr
    assert "1 failed, 1 passed" in run.stdout and "test_ours" in run.stdout, run.stdout


# --- the study: strict JSON, truthful timing, a progress bar that ends at 100 % ----------------
def _strict(text):
    def refuse(token):
        raise ValueError(f"not JSON: {token}")
    return json.loads(text, parse_constant=refuse)


def test_one_seed_study_writes_strict_json(tmp_path, capsys):
    from ctxmodels.cli import main
    out = tmp_path / "out"
    assert main(["experiment", "--scenarios", "mixed-range", "--trackers", "gmphd-context",
                 "gmphd-uniform", "--seeds", "1", "--duration", "5", "--workers", "1",
                 "--quiet", "--no-plots", "--output", str(out)]) == 0
    results = _strict((out / "results.json").read_text())
    findings = _strict((out / "findings.json").read_text())
    interval = results["scores"][0]["mixed-range"]["hota"]
    assert interval["low"] is None and interval["high"] is None  # one seed: no interval
    assert isinstance(interval["mean"], float)
    assert isinstance(findings, list)
    err = capsys.readouterr().err
    line = next(line for line in err.splitlines() if "runs; wall time" in line)
    assert "CPU-s in total" in line and "s of the runs' wall time" in line, line


def test_the_json_writer_writes_null_for_every_non_finite_number():
    from ctxmodels.experiment.executors import json_text
    text = json_text({"a": math.nan, "b": [np.float64(np.inf), -math.inf, np.float32(1.5)],
                      "c": np.int64(3), "d": np.array([1.0, np.nan]), "e": np.bool_(True),
                      "f": (1, "x", None)})
    assert _strict(text) == {"a": None, "b": [None, None, 1.5], "c": 3, "d": [1.0, None],
                             "e": True, "f": [1, "x", None]}


def test_sweep_json_goes_through_the_same_writer():
    from ctxmodels.experiment import executors, report, sweep
    assert sweep.write_json is executors.write_json is report.write_json


def test_timing_line_sums_cpu_time_and_calls_wall_time_wall_time():
    from ctxmodels.experiment.report import ExperimentResults
    from ctxmodels.experiment.runner import JobResult

    def result(wall, cpu):
        return JobResult(job=None, hota=None, gospa=None, seconds=wall, scans=1,
                         track_count=0, cpu_seconds=cpu)
    line = ExperimentResults(None, [result(900.0, 400.0), result(917.0, 412.0)],
                             1000.0).timing_line()
    assert line == ("2 runs; wall time 1000 s; tracking 812 CPU-s in total "
                    "(1817 s of the runs' wall time).")


def test_a_job_measures_its_tracking_cpu_time():
    from ctxmodels.experiment.runner import Job, run_job
    result = run_job(Job("mixed-range", 0, "gmphd-context", duration=5.0))
    assert result.cpu_seconds > 0.0  # (may exceed the wall time: the core has threads)


def test_progress_bar_ends_exactly_on_its_total_without_a_warning(monkeypatch):
    """The full study's jobs, finished in any order: the bar's count ends on its total (it
    overshot by 1e-12 and tqdm warned, clamping, with a negative ETA)."""
    from tqdm import TqdmWarning

    from ctxmodels.experiment import runner
    jobs = runner.ExperimentConfig().jobs()
    stream = io.StringIO()
    monkeypatch.setattr(sys, "stderr", stream)
    with warnings.catch_warnings():
        warnings.simplefilter("error", TqdmWarning)
        bar = runner._Progress(jobs, True)
        for job in reversed(runner.submission_order(jobs)):
            bar.done(job)
        assert bar._bar.n == bar._bar.total
        bar._bar.refresh()
        bar.close()
    assert "100%" in stream.getvalue() and "<-" not in stream.getvalue()
    assert len(jobs) > 200 and f"{len(jobs)}/{len(jobs)} runs" in stream.getvalue()


def test_progress_bar_off_builds_no_bar():
    from ctxmodels.experiment import runner
    bar = runner._Progress(runner.ExperimentConfig(seeds=[0]).jobs(), False)
    assert bar._bar is None
    bar.done(runner.ExperimentConfig(seeds=[0]).jobs()[0])
    bar.close()


def test_tqdm_is_a_base_dependency():
    """`ctxmodels experiment` is a base entry point: its progress bar's library comes with
    the base install (read from pyproject.toml: installed metadata lags until reinstall)."""
    tomllib = pytest.importorskip("tomllib")
    project = pathlib.Path(__file__).resolve().parents[2] / "pyproject.toml"
    base = tomllib.loads(project.read_text())["project"]["dependencies"]
    assert any(r.replace(" ", "").startswith("tqdm") for r in base), base


# --- the study's command line -------------------------------------------------------------------
from test_cli_reliability import TINY  # noqa: E402
from test_cli_reliability import usage_error as _usage_error  # noqa: E402


@pytest.fixture
def without_matplotlib(monkeypatch):
    import importlib.util
    find_spec = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec",
                        lambda name, *a: None if name == "matplotlib" else find_spec(name, *a))


@pytest.mark.parametrize("command", ["experiment", "sweep"])
def test_study_without_matplotlib_exits_2_naming_what_to_install(command, tmp_path, capsys,
                                                                 no_work, without_matplotlib):
    out = tmp_path / "out"
    line = _usage_error([command, *TINY, "--output", str(out)], capsys)
    assert line.startswith(f"ctxmodels {command}: error: argument --no-plots:"), line
    assert 'pip install "ctxmodels[experiment]"' in line and "matplotlib" in line
    assert not out.exists()


def test_study_without_matplotlib_runs_with_no_plots(tmp_path, monkeypatch, without_matplotlib):
    from ctxmodels import cli
    from ctxmodels.cli import experiment as experiment_command
    seen = {}
    monkeypatch.setattr(experiment_command, "_experiment",
                        lambda args: seen.setdefault("args", args) and 0)
    assert cli.main(["experiment", *TINY, "--no-plots", "--output", str(tmp_path / "o")]) == 0
    assert seen["args"].no_plots


def test_coverage_without_matplotlib_exits_2(tmp_path, capsys, without_matplotlib):
    line = _usage_error(["coverage", "--output", str(tmp_path / "c.png")], capsys)
    assert line.startswith("ctxmodels coverage: error: argument --output:") and "matplotlib" in line


STUDY_ARGUMENTS = [
    (["--seeds", "1.5"], "--seeds"),
    (["--seeds", "ten"], "--seeds"),
    (["--seeds", ""], "--seeds"),
    (["--seeds", "10001"], "--seeds"),
    (["--workers", "2.0"], "--workers"),
    (["--workers", "abc"], "--workers"),
    (["--seed-start", "0x10"], "--seed-start"),
    (["--seed-start", "1e3"], "--seed-start"),
    (["--duration", "abc"], "--duration"),
    (["--duration", ""], "--duration"),
    (["--duration", "-inf"], "--duration"),
    (["--scenarios", ""], "--scenarios"),
    (["--trackers", ""], "--trackers"),
    (["--trackers", "JPDA"], "--trackers"),
]


@pytest.mark.parametrize("command", ["experiment", "sweep"])
@pytest.mark.parametrize("argv, option", STUDY_ARGUMENTS,
                         ids=[" ".join(a) or "empty" for a, _ in STUDY_ARGUMENTS])
def test_study_argument_errors_exit_2_before_any_work(command, argv, option, tmp_path, capsys,
                                                      no_work):
    out = tmp_path / "out"
    line = _usage_error([command, *TINY, "--output", str(out), *argv], capsys)
    assert line.startswith(f"ctxmodels {command}: error: argument {option}:"), line
    assert not out.exists()


SWEEP_ARGUMENTS = [
    (["--radar-far-clutter", "nan"], "--radar-far-clutter"),
    (["--radar-far-clutter", "-1"], "--radar-far-clutter"),
    (["--radar-far-clutter", "996"], "--radar-far-clutter"),  # near 5 + far > 1000
    (["--radar-bearing-std", "0"], "--radar-bearing-std"),
    (["--radar-bearing-std", "inf"], "--radar-bearing-std"),
    (["--lidar-clutter", "101"], "--lidar-clutter"),
    (["--lidar-clutter", "x"], "--lidar-clutter"),
]


@pytest.mark.parametrize("argv, option", SWEEP_ARGUMENTS,
                         ids=[" ".join(a) for a, _ in SWEEP_ARGUMENTS])
def test_sweep_grid_errors_exit_2_before_any_work(argv, option, tmp_path, capsys, no_work):
    out = tmp_path / "out"
    line = _usage_error(["sweep", *TINY, "--output", str(out), *argv], capsys)
    assert line.startswith(f"ctxmodels sweep: error: argument {option}:"), line
    assert not out.exists()

