"""The study's files, timing and progress bar: strict JSON (null for every non-finite
number, the sweep's through the same writer), a timing line that sums CPU time and calls
wall time wall time, and a progress bar that ends exactly on its total."""
from __future__ import annotations

import io
import json
import math
import pathlib
import sys
import warnings

import numpy as np
import pytest


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
