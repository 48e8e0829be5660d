"""The test run's warning filters (pyproject.toml's ``filterwarnings``): a warning from
ctxmodels' own code fails the run whatever its category, at run time or at compile time;
third-party code's warnings stay warnings; and the package's sources compile without any."""
from __future__ import annotations

import pathlib
import subprocess
import sys
import textwrap
import warnings

import pytest

import ctxmodels


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
    project = pathlib.Path(__file__).resolve().parents[1]
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
