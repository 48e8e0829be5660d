"""pytest plugin: run Stone Soup's own test modules with ctxmodels' drop-ins substituted.

Loaded by ``scripts/upstream_tests.py`` as ``-p upstream_substitute`` (this directory on
``PYTHONPATH``), with ``--ctx-upstream-root`` pointing at a directory holding the upstream
test packages extracted from the Stone Soup sdist (``<root>/stonesoup/<sub>/tests/...``).

How the substitution works:

1. The extracted ``tests`` packages are made sub-packages of the *installed* Stone Soup
   (``<root>/stonesoup/<sub>`` is appended to ``stonesoup.<sub>.__path__``), so the upstream
   modules' relative imports (``from ..pointprocess import ...``) resolve to the installed
   library, exactly as in an upstream checkout.
2. Every Stone Soup module the upstream files import is imported first, unpatched.
3. While the upstream conftests and test modules are imported (from the initial conftests
   to the end of collection), each stock class of the profile's map is replaced by its
   ctxmodels drop-in *in the module that defines it*. The upstream ``from X import Name``
   statements, ``parametrize`` lists and fixture ``params`` therefore bind the ctxmodels
   classes. After collection the stock modules are restored, so Stone Soup's own code never
   sees a patched name; a module other than the upstream tests and ctxmodels that was first
   imported during that window and bound a ctxmodels class is an error (step 2 missed it).

And how it is proved, per test:

* before a test runs, neither its module's nor its conftests' globals, nor its parameters
  (and the Stone Soup objects they hold), may hold a substituted stock class or an instance
  of one (the test errors otherwise);
* while a test (setup, call and teardown) runs, creating an instance whose type *is* a
  substituted stock class fails the test (a name that leaked through unsubstituted);
* every construction of a ctxmodels substitute during a test, and every substitute
  instance in its parameters, is recorded; the JSON report (``--ctx-report``) lists, per
  test, its outcome, which substituted components it built and any leak, and the runner
  script requires each component to be built by at least one passing test;
* ``--ctx-control`` runs the same with nothing substituted: the checks must then fail every
  upstream test (``tests/upstream/test_substitution.py`` asserts they do).

The session also runs ``tests/upstream/test_internals.py`` (:data:`INTERNALS_CHECK`, added to
the command line's paths): the checks that the Stone Soup internals ctxmodels relies on
(``ctxmodels._upstream``) exist and behave as relied on, against the Stone Soup whose tests
run. They are not upstream tests: no substitution check applies to them (they build stock
classes on purpose), and the report lists them apart, under ``"internals"``; they pass or
fail alike with and without ``--ctx-control``.

The map, stock dotted name -> ctxmodels dotted name, is :data:`PROFILES`; nothing else
needs to change to substitute another class.
"""
from __future__ import annotations

import ast
import functools
import importlib
import json
import os
import sys
from pathlib import Path

import pytest

# --- The one place to configure what is substituted ------------------------------------
# Stock Stone Soup class (where it is defined) -> ctxmodels drop-in. Substituting another
# class, or another drop-in for one (e.g. ctxmodels.stonesoup.ArrayPointProcessTracker for
# PointProcessMultiTargetTracker), is one line here.
DEFAULT = {
    "stonesoup.tracker.pointprocess.PointProcessMultiTargetTracker":
        "ctxmodels.stonesoup.PointProcessMultiTargetTracker",
    "stonesoup.updater.pointprocess.PHDUpdater": "ctxmodels.stonesoup.PHDUpdater",
    "stonesoup.updater.pointprocess.LCCUpdater": "ctxmodels.stonesoup.LCCUpdater",
    "stonesoup.hypothesiser.probability.PDAHypothesiser": "ctxmodels.stonesoup.PDAHypothesiser",
    "stonesoup.tracker.simple.MultiTargetMixtureTracker":
        "ctxmodels.stonesoup.MultiTargetMixtureTracker",
    "stonesoup.initiator.simple.MultiMeasurementInitiator":
        "ctxmodels.stonesoup.MultiMeasurementInitiator",
    "stonesoup.deleter.time.UpdateTimeStepsDeleter": "ctxmodels.stonesoup.UpdateTimeStepsDeleter",
    "stonesoup.dataassociator.neighbour.GNNWith2DAssignment":
        "ctxmodels.stonesoup.FastGNNWith2DAssignment",
    "stonesoup.updater.particle.BernoulliParticleUpdater":
        "ctxmodels.stonesoup.BernoulliParticleUpdater",
    "stonesoup.updater.particle.SMCPHDUpdater": "ctxmodels.stonesoup.SMCPHDUpdater",
}

# A profile is the default map with some stock names given a different substitute.
PROFILES = {
    "default": DEFAULT,
    # The trackers and initiator that compute whole scans in the Rust core.
    "array": {
        **DEFAULT,
        "stonesoup.tracker.pointprocess.PointProcessMultiTargetTracker":
            "ctxmodels.stonesoup.ArrayPointProcessTracker",
        "stonesoup.tracker.simple.MultiTargetMixtureTracker":
            "ctxmodels.stonesoup.ArrayJPDATracker",
        "stonesoup.initiator.simple.MultiMeasurementInitiator":
            "ctxmodels.stonesoup.ArrayMultiMeasurementInitiator",
    },
}
# -----------------------------------------------------------------------------------------


#: ctxmodels' checks of the Stone Soup internals it relies on, run in the same session.
INTERNALS_CHECK = Path(__file__).resolve().parent / "test_internals.py"


class SubstitutionLeak(AssertionError):
    """An upstream test reached a stock class that should have been substituted."""


def resolve(dotted: str):
    """The object named by ``package.module.Name``."""
    module_name, _, name = dotted.rpartition(".")
    return getattr(importlib.import_module(module_name), name)


def pytest_addoption(parser):
    group = parser.getgroup("ctxmodels-upstream")
    group.addoption("--ctx-upstream-root", help="directory holding the extracted stonesoup/ test tree")
    group.addoption("--ctx-profile", default="default", choices=sorted(PROFILES),
                    help="substitution profile (default: %(default)s)")
    group.addoption("--ctx-report", help="write a JSON report of outcomes and substitutes used here")
    group.addoption("--ctx-control", action="store_true",
                    help="negative control: check and report as usual but substitute nothing "
                         "(the checks must then fail every test that reaches a stock class)")


class _Substitution:
    def __init__(self, root: Path, profile: str, control: bool = False):
        import stonesoup
        self.root = root.resolve()
        installed = Path(stonesoup.__file__).resolve()
        if self.root in installed.parents:
            raise pytest.UsageError(f"stonesoup imported from the extracted tree: {installed}")
        self.profile = profile
        self.control = control
        self.mapping = PROFILES[profile]
        self.stock = {}        # stock dotted name -> stock class
        self.substitute = {}   # stock dotted name -> ctxmodels class
        for stock_name, ours_name in self.mapping.items():
            try:
                ours = resolve(ours_name)
            except (ImportError, AttributeError) as error:
                raise pytest.UsageError(
                    f"profile {profile!r}: cannot import {ours_name} ({error})") from None
            self.stock[stock_name] = resolve(stock_name)
            self.substitute[stock_name] = ours
        self.stock_by_class = {cls: name for name, cls in self.stock.items()}
        self.current = None    # the nodeid of the running test
        self.leaks = {}        # nodeid -> [messages]
        self.used = {}         # nodeid -> {stock dotted names whose substitute was built}
        self.outcomes = {}     # nodeid -> outcome
        self.skip_reasons = {}  # nodeid -> why skipped
        # nodeid of each INTERNALS_CHECK item -> its name in the report (the file lies
        # outside the session's root, so its nodeids carry no path)
        self.internal_ids = {}
        self.internals = {}    # nodeid -> outcome, for those
        self._saved_modules = None

    # -- 1. upstream test packages become sub-packages of the installed stonesoup ---------
    def attach_test_packages(self) -> list[Path]:
        files = sorted((self.root / "stonesoup").rglob("*.py"))
        for tests_dir in sorted({f.parent for f in files if f.parent.name == "tests"}):
            parent = tests_dir.parent.relative_to(self.root)
            package = importlib.import_module(".".join(parent.parts))
            if str(tests_dir.parent) not in package.__path__:
                package.__path__.append(str(tests_dir.parent))
        return files

    # -- 2. import what the upstream files import, before anything is patched -------------
    def preimport(self, files: list[Path]) -> None:
        for path in files:
            relative = path.relative_to(self.root).with_suffix("")
            in_package = (path.parent / "__init__.py").exists()
            package = ".".join(relative.parts[:-1]) if in_package else ""
            for node in ast.walk(ast.parse(path.read_text(), str(path))):
                if isinstance(node, ast.Import):
                    targets = [alias.name for alias in node.names]
                elif isinstance(node, ast.ImportFrom):
                    base = node.module or ""
                    if node.level:
                        if not package:
                            continue
                        parts = package.split(".")
                        base = ".".join(parts[:len(parts) - node.level + 1] + ([base] if base else []))
                    targets = [base] + [f"{base}.{alias.name}" for alias in node.names]
                else:
                    continue
                for target in targets:
                    if not target.startswith("stonesoup") or ".tests" in target:
                        continue
                    try:
                        importlib.import_module(target)
                    except ImportError:
                        pass  # a name, not a submodule (or an optional dependency)

    # -- 3. the stock names bound to ctxmodels classes during collection -----------------
    def activate(self) -> None:
        self._saved_modules = set(sys.modules)
        for stock_name, ours in self.substitute.items():
            module_name, _, name = stock_name.rpartition(".")
            setattr(sys.modules[module_name], name, ours)

    def deactivate(self) -> None:
        if self._saved_modules is None:
            return  # never activated (--ctx-control)
        for stock_name, stock in self.stock.items():
            module_name, _, name = stock_name.rpartition(".")
            setattr(sys.modules[module_name], name, stock)
        ours = set(self.substitute.values())
        # A module imported while the patch was active, outside the upstream tests and
        # outside ctxmodels, may have bound a ctxmodels class thinking it stock.
        bad = []
        for module_name in sorted(set(sys.modules) - self._saved_modules):
            module = sys.modules[module_name]
            path = getattr(module, "__file__", None)
            if module_name.startswith("ctxmodels") or (path and self.root in Path(path).resolve().parents):
                continue
            if any(value in ours for value in list(vars(module).values()) if isinstance(value, type)):
                bad.append(module_name)
        if bad:
            raise pytest.UsageError(
                "imported while the substitution was active (pre-import them): " + ", ".join(bad))

    # -- proof --------------------------------------------------------------------------
    def instrument(self) -> None:
        """Record every construction of a substitute; a construction of exactly a stock
        class during a test is a leak."""
        for stock_name, stock in self.stock.items():
            stock.__init__ = self._wrap(stock.__init__, stock_name, stock, leak_check=True)
        for stock_name, ours in self.substitute.items():
            ours.__init__ = self._wrap(ours.__init__, stock_name, ours, leak_check=False)

    def _wrap(self, init, stock_name, cls, leak_check):
        state = self

        @functools.wraps(init)
        def __init__(self, *args, **kwargs):
            if state.current is not None:
                if leak_check and type(self) is cls:
                    message = (f"constructed stock {stock_name}, not its substitute "
                               f"{state.mapping[stock_name]}")
                    state.leaks.setdefault(state.current, []).append(message)
                    raise SubstitutionLeak(message)
                if not leak_check and isinstance(self, cls):
                    state.used.setdefault(state.current, set()).add(stock_name)
            init(self, *args, **kwargs)
        return __init__

    def static_leaks(self, item) -> list[str]:
        """Stock classes still bound where the test reads names: its module, its conftests,
        its parameters."""
        modules = [item.module] if getattr(item, "module", None) else []
        ancestors = Path(item.path).resolve().parents
        modules += [m for m in item.config.pluginmanager.get_plugins()
                    if getattr(m, "__file__", None)
                    and Path(m.__file__).name == "conftest.py"
                    and Path(m.__file__).resolve().parent in ancestors]
        found = []
        for module in modules:
            for name, value in vars(module).items():
                if isinstance(value, type) and value in self.stock_by_class:
                    found.append(f"{module.__name__}.{name} is stock {self.stock_by_class[value]}")
        callspec = getattr(item, "callspec", None)
        for name, value in (callspec.params.items() if callspec else ()):
            for obj in _reachable(value):
                if isinstance(obj, type):
                    if obj in self.stock_by_class:
                        found.append(f"parameter {name} is stock {self.stock_by_class[obj]}")
                    continue
                # Parameters built when the module was imported (e.g. an initiator in a
                # parametrize list): their components count as used by this test.
                if type(obj) in self.stock_by_class:
                    found.append(f"parameter {name} holds a stock {self.stock_by_class[type(obj)]}")
                for stock_name, ours in self.substitute.items():
                    if isinstance(obj, ours):
                        self.used.setdefault(item.nodeid, set()).add(stock_name)
        return found


def _reachable(value, limit=10_000):
    """``value`` and the objects reachable from it through Stone Soup properties and
    containers (a breadth-first walk, each object once)."""
    from stonesoup.base import Base
    seen, queue, out = set(), [value], []
    while queue and len(out) < limit:
        obj = queue.pop(0)
        if id(obj) in seen:
            continue
        seen.add(id(obj))
        out.append(obj)
        if isinstance(obj, Base):
            queue.extend(getattr(obj, name, None) for name in type(obj).properties)
        elif isinstance(obj, (list, tuple, set, frozenset)):
            queue.extend(obj)
        elif isinstance(obj, dict):
            queue.extend(obj.values())
    return out


_STATE: _Substitution | None = None


@pytest.hookimpl(tryfirst=True)
def pytest_load_initial_conftests(early_config, parser, args):
    global _STATE
    root = early_config.known_args_namespace.ctx_upstream_root
    if not root:
        raise pytest.UsageError("upstream_substitute needs --ctx-upstream-root")
    options = early_config.known_args_namespace
    _STATE = _Substitution(Path(root), options.ctx_profile, control=options.ctx_control)
    files = _STATE.attach_test_packages()
    _STATE.preimport(files)
    _STATE.instrument()
    if not _STATE.control:
        _STATE.activate()
    if str(INTERNALS_CHECK) not in args:
        args.append(str(INTERNALS_CHECK))


@pytest.hookimpl(trylast=True)
def pytest_collection_finish(session):
    _STATE.deactivate()
    _STATE.internal_ids = {item.nodeid: f"{INTERNALS_CHECK.name}::{item.name}"
                           for item in session.items
                           if Path(item.path).resolve() == INTERNALS_CHECK}


@pytest.hookimpl(wrapper=True)
def pytest_runtest_protocol(item, nextitem):
    # (the internals checks are not upstream tests: nothing is recorded against them)
    _STATE.current = None if item.nodeid in _STATE.internal_ids else item.nodeid
    try:
        return (yield)
    finally:
        _STATE.current = None


@pytest.hookimpl(tryfirst=True)
def pytest_runtest_setup(item):
    if item.nodeid in _STATE.internal_ids:
        return
    found = _STATE.static_leaks(item)
    if found:
        _STATE.leaks.setdefault(item.nodeid, []).extend(found)
        if not _STATE.control:
            raise SubstitutionLeak("; ".join(found))
        # The negative control lets the test run, so that the construction check shows too.


@pytest.hookimpl(wrapper=True)
def pytest_runtest_makereport(item, call):
    report = yield
    # A leak fails the test even if the test swallowed the SubstitutionLeak.
    leaks = _STATE.leaks.get(item.nodeid)
    if leaks and report.when == "call" and report.passed:
        report.outcome = "failed"
        report.longrepr = "SubstitutionLeak: " + "; ".join(leaks)
    return report


def pytest_runtest_logreport(report):
    if report.nodeid in _STATE.internal_ids:
        if report.failed or (report.skipped and report.nodeid not in _STATE.internals):
            _STATE.internals[report.nodeid] = "failed" if report.failed else "skipped"
        elif report.when == "call" and report.passed:
            _STATE.internals.setdefault(report.nodeid, "passed")
        return
    outcome = _STATE.outcomes.get(report.nodeid)
    if report.failed:
        _STATE.outcomes[report.nodeid] = "error" if report.when != "call" else "failed"
    elif report.skipped and outcome is None:
        _STATE.outcomes[report.nodeid] = "skipped"
        _STATE.skip_reasons[report.nodeid] = (report.longrepr[2] if isinstance(report.longrepr, tuple)
                                              else str(report.longrepr))
    elif report.when == "call" and report.passed and outcome is None:
        _STATE.outcomes[report.nodeid] = "passed"


def pytest_sessionfinish(session, exitstatus):
    path = session.config.getoption("ctx_report")
    if not path or _STATE is None:
        return
    tests = [{"nodeid": nodeid,
              "outcome": outcome,
              "substituted": sorted(_STATE.used.get(nodeid, ())),
              "leaks": _STATE.leaks.get(nodeid, []),
              **({"skip_reason": _STATE.skip_reasons[nodeid]} if nodeid in _STATE.skip_reasons else {})}
             for nodeid, outcome in _STATE.outcomes.items()]
    report = {"profile": _STATE.profile,
              "control": _STATE.control,
              "map": _STATE.mapping,
              "python": sys.version.split()[0],
              "pid": os.getpid(),
              "tests": tests,
              "internals": [{"nodeid": _STATE.internal_ids[nodeid], "outcome": outcome}
                            for nodeid, outcome in _STATE.internals.items()]}
    Path(path).write_text(json.dumps(report, indent=1))
