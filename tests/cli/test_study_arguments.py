"""The study's commands refuse bad arguments before any work starts (exit 2, one usage
line naming the option), and without matplotlib say what to install unless told to draw
nothing."""
from __future__ import annotations

import pytest

from .setups import TINY, usage_error as _usage_error


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
